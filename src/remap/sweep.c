/*
 * sweep.c — parameter sweeps through mr_remap, streamed to a crash-safe, resumable CSV file (contract in
 * sweep.h).
 *
 * Why the file protocol is what it is (the line-by-line part, shared with direct.c's caches, is remap_file.c's):
 *   - O_APPEND + one write() per complete line (remap_file.h): rows of different threads never interleave, and a
 *     process killed at any instant leaves whole rows plus at most one torn last line, which resume removes.
 *   - Rows are written in completion order (threads finish out of order) and sorted once, at the end, by
 *     writing a temporary file and renaming it over the original (src/io/atomic_file.c), so a crash during the
 *     rewrite leaves the complete unsorted file, and the next resume sorts it.
 *   - Numbers use the C numeric locale through uselocale(), which is per thread: a host program that called
 *     setlocale() with a decimal comma neither breaks our files nor sees its locale changed.
 */
#include "sweep.h"

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>
#ifdef _OPENMP
#include <omp.h>
#endif

#include "../c_locale.h"
#include "../io/io_internal.h"
#include "../matremap.h"
#include "../mr_internal.h"
#include "remap_file.h"

#define COMMAND_PREFIX "# command: "
#define WHAT "sweep file" /* what messages call the file */
#define ROW_TAIL_COLUMNS 6 /* rmse, relative_rmse, ssim, outcome, renders, seconds */

/* ---- samples --------------------------------------------------------------------------------------------- */

/* splitmix64 (Steele, Lea, Flood, "Fast splittable pseudorandom number generators", OOPSLA 2014): a bijective
 * mixer, so distinct (seed, index) start states never coincide for one seed. */
static uint64_t mix64(uint64_t z) {
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

static uint64_t next64(uint64_t *state) {
    *state += 0x9e3779b97f4a7c15ULL;
    return mix64(*state);
}

/* Uniform in [0, 1): the top 53 bits. */
static double next_unit(uint64_t *state) { return (double)(next64(state) >> 11) * 0x1p-53; }

static int random_eligible(const mr_sweep_spec *spec, int p) {
    const mr_brdf_param *param = &spec->source->params[p];
    return !(spec->held & (1u << p)) && param->role != MR_PARAM_SWITCH && !(param->flags & MR_PARAM_FIT_FIXED) &&
           param->max_value > param->min_value;
}

/* Value k of an axis; the endpoints are returned exactly (no lo + 1.0 * (hi - lo) rounding). */
static double axis_value(const mr_sweep_axis *axis, long k) {
    if (axis->count <= 1 || k <= 0) return axis->lo;
    if (k >= axis->count - 1) return axis->hi;
    double t = (double)k / (double)(axis->count - 1);
    double v = axis->log_scale ? exp(log(axis->lo) + t * (log(axis->hi) - log(axis->lo)))
                               : axis->lo + t * (axis->hi - axis->lo);
    return mr_clampd(v, axis->lo, axis->hi);
}

static long sample_count_unchecked(const mr_sweep_spec *spec) {
    if (spec->sampling == MR_SWEEP_RANDOM) return spec->random_count;
    long total = 1;
    for (int a = 0; a < spec->axis_count; a++) {
        if (spec->axes[a].count < 1 || total > MR_SWEEP_MAX_SAMPLES / spec->axes[a].count)
            return MR_SWEEP_MAX_SAMPLES + 1;
        total *= spec->axes[a].count;
    }
    return total;
}

static void sample_unchecked(const mr_sweep_spec *spec, long index, double *values) {
    const mr_brdf_model *m = spec->source;
    memcpy(values, spec->source_values, (size_t)mr_brdf_value_count(m) * sizeof(double));
    if (spec->sampling == MR_SWEEP_GRID) {
        long rest = index;
        for (int a = spec->axis_count - 1; a >= 0; a--) { /* the last axis is the fastest digit */
            const mr_sweep_axis *axis = &spec->axes[a];
            double v = axis_value(axis, rest % axis->count);
            rest /= axis->count;
            int offset = mr_brdf_param_offset(m, axis->param);
            for (int c = 0; c < m->params[axis->param].channels; c++) values[offset + c] = v;
        }
        return;
    }
    uint64_t state = mix64(mix64((uint64_t)spec->seed) + (uint64_t)index);
    for (int p = 0; p < m->param_count; p++) {
        if (!random_eligible(spec, p)) continue;
        const mr_brdf_param *param = &m->params[p];
        int offset = mr_brdf_param_offset(m, p);
        int log_scale = (param->flags & MR_PARAM_LOG_SCALE) && param->min_value > 0.0;
        for (int c = 0; c < param->channels; c++) {
            double u = next_unit(&state);
            double v = log_scale ? exp(log(param->min_value) + u * (log(param->max_value) - log(param->min_value)))
                                 : param->min_value + u * (param->max_value - param->min_value);
            values[offset + c] = mr_clampd(v, param->min_value, param->max_value);
        }
    }
}

/* ---- spec ------------------------------------------------------------------------------------------------ */

void mr_sweep_spec_init(mr_sweep_spec *spec, const mr_brdf_model *source, const mr_brdf_model *target) {
    memset(spec, 0, sizeof *spec);
    spec->source = source;
    spec->target = target;
    if (source != NULL) mr_brdf_default_values(source, spec->source_values);
    if (target != NULL) mr_brdf_default_values(target, spec->target_values);
    spec->remap = mr_remap_options_default();
    spec->remap.target_values = NULL;
    spec->sampling = MR_SWEEP_GRID;
    spec->seed = 1;
}

static void list_params(const mr_brdf_model *m, char *list, size_t size) {
    size_t used = 0;
    list[0] = '\0';
    for (int i = 0; i < m->param_count && used + 1 < size; i++) {
        int n = snprintf(list + used, size - used, "%s%s", i ? ", " : "", m->params[i].name);
        if (n < 0) break;
        used += (size_t)n;
    }
}

/* Range and integrality checks of one axis; `what` names it in messages. */
static mr_status check_axis(const mr_brdf_model *m, const mr_sweep_axis *axis, const char *what) {
    if (axis->param < 0 || axis->param >= m->param_count)
        return mr_fail(MR_ERR_INVALID_ARG, "grid %s: parameter index %d is not one of model '%s'", what,
                       axis->param, m->name);
    const mr_brdf_param *p = &m->params[axis->param];
    if (axis->count < 1)
        return mr_fail(MR_ERR_INVALID_ARG, "grid '%s': n = %ld, expected at least 1", what, axis->count);
    if (!isfinite(axis->lo) || !isfinite(axis->hi))
        return mr_fail(MR_ERR_INVALID_ARG, "grid '%s': bounds must be finite numbers", what);
    if (axis->lo > axis->hi)
        return mr_fail(MR_ERR_INVALID_ARG, "grid '%s': lo %g is greater than hi %g", what, axis->lo, axis->hi);
    if (axis->lo < p->min_value || axis->hi > p->max_value)
        return mr_fail(MR_ERR_INVALID_ARG, "grid '%s': %g is outside %s's range [%g, %g] (model '%s')", what,
                       axis->lo < p->min_value ? axis->lo : axis->hi, p->name, p->min_value, p->max_value, m->name);
    if (axis->log_scale && !(axis->lo > 0.0))
        return mr_fail(MR_ERR_INVALID_ARG, "grid '%s': log spacing needs lo > 0, got %g", what, axis->lo);
    if (p->role == MR_PARAM_SWITCH) {
        int integral = axis->lo == floor(axis->lo) && axis->hi == floor(axis->hi) && !axis->log_scale;
        if (integral && axis->count > 1) integral = fmod(axis->hi - axis->lo, (double)(axis->count - 1)) == 0.0;
        if (!integral)
            return mr_fail(MR_ERR_INVALID_ARG,
                           "grid '%s': %s is a switch, so every grid value must be an integer (e.g. %s=%g:%g:%g, "
                           "linear)",
                           what, p->name, p->name, floor(axis->lo), floor(axis->hi),
                           floor(axis->hi) - floor(axis->lo) + 1.0);
    }
    return MR_OK;
}

mr_status mr_sweep_parse_axis(const mr_brdf_model *source, const char *text, mr_sweep_axis *out) {
    if (source == NULL || text == NULL || out == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "grid: NULL model, text or output");
    const char *equals = strchr(text, '=');
    if (equals == NULL || equals == text)
        return mr_fail(MR_ERR_INVALID_ARG, "grid '%s': expected name=lo:hi:n or name=lo:hi:n:log", text);
    size_t name_len = (size_t)(equals - text);
    mr_sweep_axis axis;
    memset(&axis, 0, sizeof axis);
    axis.param = -1;
    for (int i = 0; i < source->param_count; i++)
        if (strlen(source->params[i].name) == name_len && strncmp(source->params[i].name, text, name_len) == 0)
            axis.param = i;
    if (axis.param < 0) {
        char list[512];
        list_params(source, list, sizeof list);
        return mr_fail(MR_ERR_INVALID_ARG, "grid '%s': source model '%s' has no parameter '%.*s' (valid: %s)", text,
                       source->name, (int)name_len, text, list);
    }

    mr_c_numeric cn;
    mr_status status = mr_c_numeric_enter(&cn, "sweep");
    if (status != MR_OK) return status;
    const char *cursor = equals + 1;
    char *end = NULL;
    errno = 0;
    axis.lo = strtod(cursor, &end);
    int ok = end != cursor && *end == ':' && errno != ERANGE;
    if (ok) {
        cursor = end + 1;
        errno = 0;
        axis.hi = strtod(cursor, &end);
        ok = end != cursor && *end == ':' && errno != ERANGE;
    }
    if (ok) {
        cursor = end + 1;
        errno = 0;
        axis.count = strtol(cursor, &end, 10);
        ok = end != cursor && (*end == '\0' || *end == ':') && errno != ERANGE;
    }
    mr_c_numeric_leave(&cn);
    if (!ok)
        return mr_fail(MR_ERR_INVALID_ARG,
                       "grid '%s': expected name=lo:hi:n or name=lo:hi:n:log with numbers lo, hi and an integer n",
                       text);
    if (*end == ':') {
        if (strcmp(end + 1, "log") != 0)
            return mr_fail(MR_ERR_INVALID_ARG, "grid '%s': unknown spacing '%s' (valid: log; linear is the default)",
                           text, end + 1);
        axis.log_scale = 1;
    }
    status = check_axis(source, &axis, text);
    if (status != MR_OK) return status;
    *out = axis;
    return MR_OK;
}

mr_status mr_sweep_check(const mr_sweep_spec *spec) {
    if (spec == NULL || spec->source == NULL || spec->target == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "sweep: NULL spec, source model or target model");
    const mr_brdf_model *m = spec->source;
    if (mr_brdf_value_count(m) > MR_BRDF_MAX_VALUES || mr_brdf_value_count(spec->target) > MR_BRDF_MAX_VALUES ||
        m->param_count > (int)(sizeof spec->held * CHAR_BIT))
        return mr_fail(MR_ERR_INVALID_ARG, "sweep: a model has more values than a sweep can hold");
    mr_status status = mr_remap_file_check_values(m, spec->source_values, "source");
    if (status == MR_OK) status = mr_remap_file_check_values(spec->target, spec->target_values, "target");
    if (status != MR_OK) return status;
    if (m->param_count < (int)(sizeof spec->held * CHAR_BIT) && (spec->held >> m->param_count) != 0)
        return mr_fail(MR_ERR_INVALID_ARG, "sweep: held marks parameters that model '%s' does not have", m->name);
    status = mr_remap_file_check_options("sweep", &spec->remap, &spec->scene);
    if (status != MR_OK) return status;
    if (spec->remap.initial_values != NULL) // every sample would start there, and the header would not say so
        return mr_fail(MR_ERR_INVALID_ARG, "sweep: remap.initial_values must be NULL (a sweep starts no fit warm)");

    if (spec->sampling == MR_SWEEP_GRID) {
        if (spec->axis_count < 1 || spec->axis_count > MR_SWEEP_MAX_AXES)
            return mr_fail(MR_ERR_INVALID_ARG, "sweep: a grid needs 1 to %d axes, got %d", MR_SWEEP_MAX_AXES,
                           spec->axis_count);
        for (int a = 0; a < spec->axis_count; a++) {
            char what[64];
            int p = spec->axes[a].param;
            snprintf(what, sizeof what, "%s", p >= 0 && p < m->param_count ? m->params[p].name : "?");
            status = check_axis(m, &spec->axes[a], what);
            if (status != MR_OK) return status;
            for (int b = 0; b < a; b++)
                if (spec->axes[b].param == p)
                    return mr_fail(MR_ERR_INVALID_ARG, "sweep: parameter '%s' has two grid axes", what);
        }
    } else if (spec->sampling == MR_SWEEP_RANDOM) {
        if (spec->random_count < 1 || spec->random_count > MR_SWEEP_MAX_SAMPLES)
            return mr_fail(MR_ERR_INVALID_ARG, "sweep: random sample count %ld: expected 1 to %ld",
                           spec->random_count, MR_SWEEP_MAX_SAMPLES);
        int eligible = 0;
        for (int p = 0; p < m->param_count; p++) eligible += random_eligible(spec, p);
        if (eligible == 0)
            return mr_fail(MR_ERR_INVALID_ARG,
                           "sweep: model '%s' has no parameter left to randomise (switches, fixed extension factors "
                           "and the values given are held)",
                           m->name);
    } else {
        return mr_fail(MR_ERR_INVALID_ARG, "sweep: sampling %d is neither grid nor random", (int)spec->sampling);
    }
    if (sample_count_unchecked(spec) > MR_SWEEP_MAX_SAMPLES)
        return mr_fail(MR_ERR_INVALID_ARG, "sweep: the grid has more than %ld samples", MR_SWEEP_MAX_SAMPLES);
    return MR_OK;
}

long mr_sweep_sample_count(const mr_sweep_spec *spec) {
    mr_status status = mr_sweep_check(spec);
    return status == MR_OK ? sample_count_unchecked(spec) : 0;
}

mr_status mr_sweep_sample(const mr_sweep_spec *spec, long index, double *values) {
    mr_status status = mr_sweep_check(spec);
    if (status != MR_OK) return status;
    long total = sample_count_unchecked(spec);
    if (index < 0 || index >= total || values == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "sweep: sample %ld: expected 0 to %ld", index, total - 1);
    sample_unchecked(spec, index, values);
    return MR_OK;
}

/* ---- header, columns, rows ---------------------------------------------------------------------------------- */

/* The header for this run (every line '\n'-terminated, the column line last), in the C numeric locale. */
static mr_status build_header(const mr_sweep_spec *spec, const char *command_line, mr_strbuf *sb) {
    mr_strbuf_printf(sb, "# matremap %s sweep\n", mr_version());
    mr_strbuf_printf(sb, "# from: %s", spec->source->name);
    mr_strbuf_values(sb, spec->source, spec->source_values);
    mr_strbuf_printf(sb, "\n# to: %s", spec->target->name);
    mr_strbuf_values(sb, spec->target, spec->target_values);
    mr_strbuf_printf(sb, "\n");
    mr_strbuf_remap_lines(sb, spec->target, &spec->remap, &spec->scene);
    if (spec->sampling == MR_SWEEP_GRID) {
        mr_strbuf_printf(sb, "# sampling: grid");
        for (int a = 0; a < spec->axis_count; a++) {
            const mr_sweep_axis *axis = &spec->axes[a];
            mr_strbuf_printf(sb, " %s=%.17g:%.17g:%ld%s", spec->source->params[axis->param].name, axis->lo, axis->hi,
                      axis->count, axis->log_scale ? ":log" : "");
        }
    } else {
        mr_strbuf_printf(sb, "# sampling: random=%ld seed=%llu over", spec->random_count, spec->seed);
        int first = 1;
        for (int p = 0; p < spec->source->param_count; p++)
            if (random_eligible(spec, p)) {
                mr_strbuf_printf(sb, "%s%s", first ? " " : ",", spec->source->params[p].name);
                first = 0;
            }
    }
    mr_strbuf_printf(sb, "\n# samples: %ld\n" COMMAND_PREFIX, sample_count_unchecked(spec));
    // The command line is informational; a line break in an argument must not start a line of its own.
    for (const char *c = command_line ? command_line : ""; *c; c++)
        mr_strbuf_printf(sb, "%c", *c == '\n' || *c == '\r' ? ' ' : *c);
    mr_strbuf_printf(sb, "\nindex");
    mr_strbuf_columns(sb, spec->source, "");
    mr_strbuf_columns(sb, spec->target, "to_");
    mr_strbuf_printf(sb, ",rmse,relative_rmse,ssim,outcome,renders,seconds\n");
    return sb->failed ? mr_fail(MR_ERR_NOMEM, "sweep: out of memory building the header") : MR_OK;
}

/* Row formatting in the current (C) numeric locale. */
static mr_status format_row(const mr_sweep_spec *spec, const mr_sweep_row *row, char *buf, size_t size,
                            size_t *length) {
    const char *outcome = mr_fit_outcome_name(row->outcome);
    if (outcome == NULL) return mr_fail(MR_ERR_INVALID_ARG, "sweep row %ld: outcome %d out of range", row->index,
                                        (int)row->outcome);
    size_t used = 0;
    int n = snprintf(buf, size, "%ld", row->index);
    int ns = mr_brdf_value_count(spec->source), nt = mr_brdf_value_count(spec->target);
    for (int k = 0; n >= 0 && k < ns + nt; k++) {
        used += (size_t)n;
        double v = k < ns ? row->source[k] : row->target[k - ns];
        n = snprintf(buf + MR_MIN(used, size), used < size ? size - used : 0, ",%.17g", v);
    }
    if (n >= 0) {
        used += (size_t)n;
        n = snprintf(buf + MR_MIN(used, size), used < size ? size - used : 0, ",%.17g,%.17g,%.17g,%s,%ld,%.17g\n",
                     row->rmse, row->relative_rmse, row->ssim, outcome, row->renders, row->seconds);
    }
    if (n < 0 || used + (size_t)n >= size)
        return mr_fail(MR_ERR_INVALID_ARG, "sweep row %ld: does not fit in a buffer of %zu bytes", row->index, size);
    if (length != NULL) *length = used + (size_t)n;
    return MR_OK;
}

mr_status mr_sweep_format_row(const mr_sweep_spec *spec, const mr_sweep_row *row, char *buf, size_t size,
                              size_t *length) {
    if (spec == NULL || spec->source == NULL || spec->target == NULL || row == NULL || buf == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "sweep: NULL spec, row or buffer");
    mr_c_numeric cn;
    mr_status status = mr_c_numeric_enter(&cn, "sweep");
    if (status != MR_OK) return status;
    status = format_row(spec, row, buf, size, length);
    mr_c_numeric_leave(&cn);
    return status;
}

/* Row parsing in the current (C) numeric locale; `total` bounds the index. */
static mr_status parse_row(const mr_sweep_spec *spec, long total, const char *line, size_t length,
                           mr_sweep_row *out) {
    if (length > 0 && line[length - 1] == '\n') length--;
    size_t at = 0;
    const int ns = mr_brdf_value_count(spec->source), nt = mr_brdf_value_count(spec->target);
    const int columns = 1 + ns + nt + ROW_TAIL_COLUMNS;
    mr_sweep_row row;
    memset(&row, 0, sizeof row);
    const char *field = NULL;
    size_t len = 0;
    for (int k = 0; k < columns; k++) {
        if (!mr_csv_next_field(line, length, &at, &field, &len))
            return mr_fail(MR_ERR_FORMAT, "row has %d columns, expected %d", k, columns);
        int ok;
        if (k == 0) {
            ok = mr_csv_parse_long(field, len, &row.index) && row.index < total;
            if (!ok)
                return mr_fail(MR_ERR_FORMAT, "index '%.*s' is not a sample number in [0, %ld]",
                               (int)MR_MIN(len, 40), field, total - 1);
            continue;
        }
        int c = k - 1;
        if (c < ns) {
            ok = mr_csv_parse_double(field, len, &row.source[c]);
        } else if (c < ns + nt) {
            ok = mr_csv_parse_double(field, len, &row.target[c - ns]);
        } else {
            switch (c - ns - nt) {
            case 0: ok = mr_csv_parse_double(field, len, &row.rmse); break;
            case 1: ok = mr_csv_parse_double(field, len, &row.relative_rmse); break;
            case 2: ok = mr_csv_parse_double(field, len, &row.ssim); break;
            case 3:
                ok = 0;
                for (int o = 0; o < MR_FIT_OUTCOME_COUNT; o++) {
                    const char *name = mr_fit_outcome_name((mr_fit_outcome)o);
                    if (strlen(name) == len && memcmp(name, field, len) == 0) {
                        row.outcome = (mr_fit_outcome)o;
                        ok = 1;
                    }
                }
                break;
            case 4: ok = mr_csv_parse_long(field, len, &row.renders); break;
            default: ok = mr_csv_parse_double(field, len, &row.seconds); break;
            }
        }
        if (!ok)
            return mr_fail(MR_ERR_FORMAT, "column %d: '%.*s' is not a valid value", k + 1, (int)MR_MIN(len, 40),
                           field);
    }
    if (at != SIZE_MAX) return mr_fail(MR_ERR_FORMAT, "row has more than %d columns", columns);
    *out = row;
    return MR_OK;
}

mr_status mr_sweep_parse_row(const mr_sweep_spec *spec, const char *line, size_t length, mr_sweep_row *out) {
    mr_status status = mr_sweep_check(spec);
    if (status != MR_OK) return status;
    if (line == NULL || out == NULL) return mr_fail(MR_ERR_INVALID_ARG, "sweep: NULL line or output");
    mr_c_numeric cn;
    status = mr_c_numeric_enter(&cn, "sweep");
    if (status != MR_OK) return status;
    status = parse_row(spec, sample_count_unchecked(spec), line, length, out);
    mr_c_numeric_leave(&cn);
    return status;
}

/* ---- the file ------------------------------------------------------------------------------------------------ */

typedef struct sweep_file {
    const char *path;
    int fd;
    off_t size;
    long total;
    unsigned char *done; /* per sample: already in the file */
    long done_count;
    long truncated;
} sweep_file;

/* Check an existing file against this run's header, collect the samples it holds, and cut off a torn last line
 * (only after everything else checked out, so a refused file is left exactly as it was). */
static mr_status adopt_file(const mr_sweep_spec *spec, const mr_strbuf *header, sweep_file *f) {
    char *data = NULL;
    size_t size = 0;
    mr_status status = mr_text_file_read_all(f->fd, f->path, WHAT, &data, &size);
    if (status != MR_OK) return status;
    if (size == 0) { /* created but killed before its header went out: start it */
        free(data);
        return mr_text_file_append(f->fd, f->path, WHAT, header->text, header->length, &f->size);
    }
    size_t rows_at = 0;
    long line_number = 0;
    status = mr_text_file_match_header(f->path, WHAT, "was made by another sweep",
                                       "use another output file, or remove it", data, size, header->text,
                                       header->length, COMMAND_PREFIX, &rows_at, &line_number);
    if (status != MR_OK) {
        free(data);
        return status;
    }
    const char *pos = data + rows_at, *end = data + size;
    double source[MR_BRDF_MAX_VALUES];
    const int ns = mr_brdf_value_count(spec->source);
    while (pos < end) { /* rows */
        const char *nl = memchr(pos, '\n', (size_t)(end - pos));
        line_number++;
        if (nl == NULL) { /* torn last line: a write cut short; everything before it is whole */
            f->truncated = (long)(end - pos);
            break;
        }
        mr_sweep_row row;
        status = parse_row(spec, f->total, pos, (size_t)(nl - pos) + 1, &row);
        if (status != MR_OK) {
            free(data);
            return mr_fail_context(status, "sweep file '%s': line %ld", f->path, line_number);
        }
        if (f->done[row.index]) {
            free(data);
            return mr_fail(MR_ERR_FORMAT, "sweep file '%s': line %ld: sample %ld appears a second time", f->path,
                           line_number, row.index);
        }
        sample_unchecked(spec, row.index, source);
        if (memcmp(source, row.source, (size_t)ns * sizeof(double)) != 0) {
            free(data);
            return mr_fail(MR_ERR_FORMAT,
                           "sweep file '%s': line %ld: the source values of sample %ld are not this sweep's (was the "
                           "file edited?)",
                           f->path, line_number, row.index);
        }
        f->done[row.index] = 1;
        f->done_count++;
        pos = nl + 1;
    }
    free(data);
    if (f->truncated > 0) {
        off_t keep = (off_t)(size - (size_t)f->truncated);
        if (ftruncate(f->fd, keep) != 0) {
            int err = errno;
            return mr_fail(MR_ERR_IO, "sweep file '%s': cannot remove its torn last line: %s", f->path, strerror(err));
        }
        f->size = keep;
    }
    return MR_OK;
}

/* Open (and lock) the file, fresh or resumed. */
static mr_status open_file(const mr_sweep_spec *spec, const mr_strbuf *header, int resume, sweep_file *f) {
    int flags = O_RDWR | O_APPEND | O_CREAT | O_CLOEXEC | (resume ? 0 : O_EXCL);
    f->fd = open(f->path, flags, 0666);
    if (f->fd < 0) {
        int err = errno;
        if (err == EEXIST)
            return mr_fail(MR_ERR_INVALID_ARG, "sweep file '%s' already exists; not overwriting it (resume it, or "
                           "remove it)", f->path);
        return mr_fail(MR_ERR_IO, "sweep file '%s': cannot open: %s", f->path, strerror(err));
    }
    struct stat st;
    if (fstat(f->fd, &st) != 0 || !S_ISREG(st.st_mode))
        return mr_fail(MR_ERR_INVALID_ARG, "sweep file '%s' is not a regular file", f->path);
    mr_status status = mr_text_file_lock(f->fd, f->path, WHAT);
    if (status != MR_OK) return status;
    f->size = st.st_size;
    if (resume)
        return adopt_file(spec, header, f);
    status = mr_text_file_append(f->fd, f->path, WHAT, header->text, header->length, &f->size);
    if (status != MR_OK)
        unlink(f->path); // made here (O_EXCL), locked, holding no row: an empty file would refuse a rerun
    return status;
}

/* Every sample is in the file: rewrite it in index order unless it already is (atomic: temporary + rename). */
static mr_status sort_file(sweep_file *f, long header_lines, int *sorted) {
    *sorted = 0;
    char *data = NULL;
    size_t size = 0;
    mr_status status = mr_text_file_read_all(f->fd, f->path, WHAT, &data, &size);
    if (status != MR_OK) return status;
    const char **lines = calloc((size_t)f->total, sizeof *lines);
    if (lines == NULL) {
        free(data);
        return mr_fail(MR_ERR_NOMEM, "sweep file '%s': out of memory sorting %ld rows", f->path, f->total);
    }
    // The file's own header (its command line may differ from this run's) is kept byte for byte.
    const char *rows = data;
    for (long h = 0; h < header_lines && rows < data + size; h++) {
        const char *nl = memchr(rows, '\n', (size_t)(data + size - rows));
        rows = nl ? nl + 1 : data + size;
    }
    const size_t header_length = (size_t)(rows - data);
    int in_order = 1;
    long k = 0;
    // Rows were all validated (or written by us); the index is the text before the first comma. The strtol
    // cannot run past the buffer: mr_text_file_read_all NUL-terminates it.
    for (const char *pos = rows; pos < data + size && k < f->total; k++) {
        long index = strtol(pos, NULL, 10);
        if (index < 0 || index >= f->total) index = 0; /* cannot happen; keeps the array in bounds */
        lines[index] = pos;
        in_order &= index == k;
        const char *nl = memchr(pos, '\n', (size_t)(data + size - pos));
        pos = nl ? nl + 1 : data + size;
    }
    in_order &= k == f->total;
    for (long i = 0; i < f->total; i++)
        if (lines[i] == NULL) { /* cannot happen: every sample was checked in; refuse rather than drop rows */
            free(lines);
            free(data);
            return mr_fail(MR_ERR_FORMAT, "sweep file '%s': sample %ld is missing at the end of the run", f->path, i);
        }
    if (in_order) {
        free(lines);
        free(data);
        if (fsync(f->fd) != 0) {
            int err = errno;
            return mr_fail(MR_ERR_IO, "sweep file '%s': cannot flush: %s", f->path, strerror(err));
        }
        return MR_OK;
    }
    mr_atomic_file tmp;
    status = mr_atomic_begin(f->path, &tmp);
    FILE *out = status == MR_OK ? fopen(tmp.tmp_path, "w") : NULL;
    if (status == MR_OK && out == NULL) {
        int err = errno;
        status = mr_fail(MR_ERR_IO, "sweep file '%s': cannot open temporary file '%s': %s", f->path, tmp.tmp_path,
                         strerror(err));
    }
    if (status == MR_OK) {
        int ok = fwrite(data, 1, header_length, out) == header_length;
        for (long i = 0; ok && i < f->total; i++) {
            const char *nl = strchr(lines[i], '\n');
            size_t len = (size_t)(nl - lines[i]) + 1;
            ok = fwrite(lines[i], 1, len, out) == len;
        }
        ok = (fflush(out) == 0) & ok;
        int err = errno;
        ok = (fclose(out) == 0) & ok;
        if (!ok)
            status = mr_fail(MR_ERR_IO, "sweep file '%s': cannot write the sorted copy '%s': %s", f->path,
                             tmp.tmp_path, strerror(err ? err : errno));
    }
    if (status == MR_OK) status = mr_atomic_commit(&tmp);
    if (status != MR_OK && tmp.active) mr_atomic_abort(&tmp);
    if (status == MR_OK) *sorted = 1;
    free(lines);
    free(data);
    return status;
}

/* ---- the run ------------------------------------------------------------------------------------------------- */

typedef struct run_state {
    const mr_sweep_spec *spec;
    const mr_sweep_options *opts;
    sweep_file *file;
    const mr_render_plan *plan;
    long run_total, run_done;
    long outcomes[MR_FIT_OUTCOME_COUNT];
    const long *pending;       /* the samples this run computes */
    int stop;                  /* set (under the file lock) when the file fails: no new samples start */
    long failed;               /* samples whose remap failed (the others go on: their rows are worth having) */
    mr_status failure;         /* the failure to report: a file error, else the lowest failed sample's */
    long failure_index;
    int file_failed;
    char failure_message[1024];
} run_state;

/* Called under the file lock, on the thread that failed (mr_last_error() is per thread). A file error stops the
 * run; a failed remap is counted and the sweep goes on. The reported failure does not depend on thread timing
 * unless the file fails: it is the lowest failed index. */
static void record_failure(run_state *st, mr_status status, long index, int file_error) {
    if (file_error) {
#pragma omp atomic write
        st->stop = 1;
    } else {
        st->failed++;
    }
    if (st->file_failed || (!file_error && st->failure != MR_OK && st->failure_index < index)) return;
    st->failure = status;
    st->failure_index = index;
    st->file_failed = file_error;
    snprintf(st->failure_message, sizeof st->failure_message, "%s", mr_last_error());
}

/* Remap sample `index` and append its row. Runs on a worker thread, in the C numeric locale. */
static void run_sample(run_state *st, long index) {
    const mr_sweep_spec *spec = st->spec;
    mr_sweep_row row;
    memset(&row, 0, sizeof row);
    row.index = index;
    sample_unchecked(spec, index, row.source);
    mr_remap_options o = spec->remap;
    o.target_values = spec->target_values;
    mr_remap_result r;
    mr_status status = mr_remap(st->plan, spec->source, row.source, spec->target, &o, &r);
    char line[MR_SWEEP_MAX_LINE];
    size_t length = 0;
    if (status == MR_OK) {
        memcpy(row.target, r.values, (size_t)mr_brdf_value_count(spec->target) * sizeof(double));
        row.rmse = r.rmse;
        row.relative_rmse = r.relative_rmse;
        row.ssim = r.ssim;
        row.outcome = r.outcome;
        row.renders = r.renders;
        row.seconds = r.seconds;
        status = format_row(spec, &row, line, sizeof line, &length);
    }
#pragma omp critical(mr_sweep_file)
    {
        if (status != MR_OK) {
            record_failure(st, status, index, 0);
        } else if (!st->stop) {
            status = mr_text_file_append(st->file->fd, st->file->path, WHAT, line, length, &st->file->size);
            if (status != MR_OK) {
                record_failure(st, status, index, 1);
            } else {
                st->file->done_count++;
                st->run_done++;
                st->outcomes[row.outcome]++;
                if (st->opts->progress != NULL) {
                    mr_sweep_progress p = {st->file->done_count, st->file->total, st->run_done, st->run_total, &row};
                    st->opts->progress(&p, st->opts->progress_user);
                }
            }
        }
    }
}

static void run_item(void *ctx, long k) {
    run_state *st = ctx;
    run_sample(st, st->pending[k]);
}

static mr_status run_pending(run_state *st, const long *pending, long count, int threads) {
    st->pending = pending;
    mr_status status = mr_remap_run_parallel(threads, count, &st->stop, run_item, st, "sweep");
    if (status != MR_OK) return status;
    if (st->file_failed) return mr_fail(st->failure, "%s", st->failure_message);
    if (st->failed > 0)
        return mr_fail(st->failure,
                       "sweep: %ld of %ld samples failed (the other rows are in '%s'; a resume retries the failed "
                       "ones); sample %ld: %s",
                       st->failed, count, st->file->path, st->failure_index, st->failure_message);
    return MR_OK;
}

mr_status mr_sweep_run(const mr_sweep_spec *spec, const char *path, const mr_sweep_options *opts,
                       mr_sweep_summary *out) {
    double start = mr_now_seconds();
    mr_sweep_options defaults;
    memset(&defaults, 0, sizeof defaults);
    if (opts == NULL) opts = &defaults;
    mr_status status = mr_sweep_check(spec);
    if (status != MR_OK) return status;
    if (path == NULL || path[0] == '\0') return mr_fail(MR_ERR_INVALID_ARG, "sweep: empty output path");
    if (opts->threads < 0) return mr_fail(MR_ERR_INVALID_ARG, "sweep: threads %d: expected >= 0", opts->threads);
    int threads = opts->threads;
#ifdef _OPENMP
    if (threads == 0) threads = omp_get_max_threads();
#else
    threads = 1;
#endif

    mr_strbuf header = {0};
    mr_c_numeric cn;
    status = mr_c_numeric_enter(&cn, "sweep");
    if (status != MR_OK) return status;
    sweep_file f;
    memset(&f, 0, sizeof f);
    f.path = path;
    f.fd = -1;
    f.total = sample_count_unchecked(spec);
    f.done = calloc((size_t)f.total, 1);
    mr_render_plan *plan = NULL;
    long *pending = NULL;
    run_state st;
    memset(&st, 0, sizeof st);
    if (f.done == NULL) status = mr_fail(MR_ERR_NOMEM, "sweep: out of memory for %ld samples", f.total);
    if (status == MR_OK) status = build_header(spec, opts->command_line, &header);
    if (status == MR_OK) status = open_file(spec, &header, opts->resume, &f);
    mr_c_numeric_leave(&cn);
    long already = f.done_count;

    long pending_count = 0;
    if (status == MR_OK && f.done_count < f.total) {
        pending = malloc((size_t)(f.total - f.done_count) * sizeof *pending);
        if (pending == NULL) status = mr_fail(MR_ERR_NOMEM, "sweep: out of memory for %ld samples", f.total);
        for (long i = 0; status == MR_OK && i < f.total; i++)
            if (!f.done[i]) pending[pending_count++] = i;
        if (status == MR_OK) {
            mr_scene scene = mr_remap_file_scene(&spec->scene);
            status = mr_render_plan_create(&scene, &plan);
        }
        if (status == MR_OK) {
            st.spec = spec;
            st.opts = opts;
            st.file = &f;
            st.plan = plan;
            st.run_total = pending_count;
            st.failure = MR_OK;
            status = run_pending(&st, pending, pending_count, threads);
        }
    }
    int sorted = 0;
    long header_lines = 0;
    for (size_t i = 0; i < header.length; i++) header_lines += header.text[i] == '\n';
    if (status == MR_OK) status = sort_file(&f, header_lines, &sorted);
    if (f.fd >= 0) close(f.fd); /* releases the lock, after the rename */
    mr_render_plan_free(plan);
    free(pending);
    free(f.done);
    free(header.text);
    if (status != MR_OK) return status;
    if (out != NULL) {
        memset(out, 0, sizeof *out);
        out->total = f.total;
        out->already_done = already;
        out->computed = st.run_done;
        memcpy(out->outcomes, st.outcomes, sizeof out->outcomes);
        out->truncated_bytes = f.truncated;
        out->sorted = sorted;
        out->threads = threads;
        out->seconds = mr_now_seconds() - start;
    }
    return MR_OK;
}
