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
#define SHARD_PREFIX "# shard: "
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

/* One draw of every eligible parameter into values, from the stream at *state; grey: one number for an RGB
 * parameter's three channels (the TEXTURE region). */
static void draw_once(const mr_sweep_spec *spec, uint64_t *state, int grey, double *values) {
    const mr_brdf_model *m = spec->source;
    for (int p = 0; p < m->param_count; p++) {
        if (!random_eligible(spec, p)) continue;
        const mr_brdf_param *param = &m->params[p];
        int offset = mr_brdf_param_offset(m, p);
        int log_scale = (param->flags & MR_PARAM_LOG_SCALE) && param->min_value > 0.0;
        for (int c = 0; c < param->channels; c++) {
            if (grey && c > 0) {
                values[offset + c] = values[offset];
                continue;
            }
            double u = next_unit(state);
            double v = log_scale ? exp(log(param->min_value) + u * (log(param->max_value) - log(param->min_value)))
                                 : param->min_value + u * (param->max_value - param->min_value);
            values[offset + c] = mr_clampd(v, param->min_value, param->max_value);
        }
    }
}

/* The drawn LINEAR parameters at their range's minimum (the TEXTURE region's last resort). */
static void linear_at_minimum(const mr_sweep_spec *spec, double *values) {
    const mr_brdf_model *m = spec->source;
    for (int p = 0; p < m->param_count; p++) {
        if (!random_eligible(spec, p) || m->params[p].role != MR_PARAM_LINEAR) continue;
        int offset = mr_brdf_param_offset(m, p);
        for (int c = 0; c < m->params[p].channels; c++) values[offset + c] = m->params[p].min_value;
    }
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
    const int texture = spec->region == MR_SWEEP_REGION_TEXTURE;
    for (long draw = 0;; draw++) {
        draw_once(spec, &state, texture, values);
        if (!texture || m->rescales == NULL || !m->rescales(m, values)) return;
        if (draw + 1 >= MR_SWEEP_MAX_DRAWS) break;
    }
    // Nothing linear in MR_SWEEP_MAX_DRAWS draws: the drawn reflectances at their minimum, which
    // mr_sweep_check has made sure the source does not rescale.
    linear_at_minimum(spec, values);
}

static const char *const region_names[MR_SWEEP_REGION_COUNT] = {"texture", "range"};

const char *mr_sweep_region_name(mr_sweep_region region) {
    return (unsigned)region < MR_SWEEP_REGION_COUNT ? region_names[region] : NULL;
}

mr_status mr_sweep_region_from_name(const char *name, mr_sweep_region *out) {
    for (int r = 0; r < MR_SWEEP_REGION_COUNT; r++)
        if (name != NULL && strcmp(name, region_names[r]) == 0) {
            *out = (mr_sweep_region)r;
            return MR_OK;
        }
    return mr_fail(MR_ERR_INVALID_ARG, "region '%s': expected texture (the values texture maps hold) or range "
                   "(every parameter over its whole range)", name ? name : "(null)");
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
        if ((unsigned)spec->region >= MR_SWEEP_REGION_COUNT)
            return mr_fail(MR_ERR_INVALID_ARG, "sweep: region %d is neither texture nor range", (int)spec->region);
        if (spec->region == MR_SWEEP_REGION_TEXTURE && m->rescales != NULL) {
            double lowest[MR_BRDF_MAX_VALUES];
            memcpy(lowest, spec->source_values, (size_t)mr_brdf_value_count(m) * sizeof(double));
            linear_at_minimum(spec, lowest);
            if (m->rescales(m, lowest))
                return mr_fail(MR_ERR_INVALID_ARG,
                               "sweep: the values held put model '%s' where it rescales its reflectances (energy "
                               "trimming) whatever is drawn, so no sample lies where texture maps do: hold smaller "
                               "reflectances, or sample --region range",
                               m->name);
        }
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

/* The header for this run (every line '\n'-terminated, the column line last), in the C numeric locale; a shard
 * (shard_count > 0) adds "# shard: K/N" before the command line. */
static mr_status build_header(const mr_sweep_spec *spec, const char *command_line, long shard_index, long shard_count,
                              mr_strbuf *sb) {
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
        mr_strbuf_printf(sb, "# sampling: random=%ld seed=%llu", spec->random_count, spec->seed);
        // Files from before regions have no region word, and are RANGE (parse_sampling_line).
        if (spec->region != MR_SWEEP_REGION_RANGE)
            mr_strbuf_printf(sb, " region=%s", mr_sweep_region_name(spec->region));
        mr_strbuf_printf(sb, " over");
        int first = 1;
        for (int p = 0; p < spec->source->param_count; p++)
            if (random_eligible(spec, p)) {
                mr_strbuf_printf(sb, "%s%s", first ? " " : ",", spec->source->params[p].name);
                first = 0;
            }
    }
    mr_strbuf_printf(sb, "\n# samples: %ld\n", sample_count_unchecked(spec));
    if (shard_count > 0)
        mr_strbuf_printf(sb, SHARD_PREFIX "%ld/%ld\n", shard_index, shard_count);
    mr_strbuf_printf(sb, COMMAND_PREFIX);
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

/* The name of field k of a row (0: "index"), as in the column line. */
static void column_name(const mr_sweep_spec *spec, int k, char *buf, size_t size) {
    static const char *const tail[ROW_TAIL_COLUMNS] = {"rmse",    "relative_rmse", "ssim",
                                                       "outcome", "renders",       "seconds"};
    static const char *const suffix[3] = {"_r", "_g", "_b"};
    if (k == 0) {
        snprintf(buf, size, "index");
        return;
    }
    int c = k - 1;
    for (int side = 0; side < 2; side++) {
        const mr_brdf_model *m = side ? spec->target : spec->source;
        for (int p = 0; p < m->param_count; p++) {
            int offset = mr_brdf_param_offset(m, p), channels = m->params[p].channels;
            if (c >= offset && c < offset + channels) {
                snprintf(buf, size, "%s%s%s", side ? "to_" : "", m->params[p].name,
                         channels == 3 ? suffix[c - offset] : "");
                return;
            }
        }
        c -= mr_brdf_value_count(m);
    }
    snprintf(buf, size, "%s", c >= 0 && c < ROW_TAIL_COLUMNS ? tail[c] : "?");
}

/* Range checks of a row's values (contract in sweep.h). The fitted values may lie outside a parameter's range by
 * rounding (mr_remap maps a log-scaled range's endpoints through exp(log(x)): Phong's exponent can come back as
 * 10000.000000000009), hence the band of 1e-9 of the range's width; 1e300 or a negative reflectance never fit. */
static mr_status check_row(const mr_sweep_spec *spec, const mr_sweep_row *row) {
    char name[64];
    int column = 1;
    for (int side = 0; side < 2; side++) {
        const mr_brdf_model *m = side ? spec->target : spec->source;
        const double *v = side ? row->target : row->source;
        for (int p = 0; p < m->param_count; p++) {
            const mr_brdf_param *param = &m->params[p];
            const double band = 1e-9 * (param->max_value - param->min_value);
            for (int c = 0; c < param->channels; c++, column++) {
                const double x = v[mr_brdf_param_offset(m, p) + c];
                if (isfinite(x) && x >= param->min_value - band && x <= param->max_value + band &&
                    (param->role != MR_PARAM_SWITCH || x == floor(x)))
                    continue;
                column_name(spec, column, name, sizeof name);
                if (!isfinite(x))
                    return mr_fail(MR_ERR_FORMAT, "column %d (%s): %g is not a finite number", column + 1, name, x);
                if (x < param->min_value - band || x > param->max_value + band)
                    return mr_fail(MR_ERR_FORMAT, "column %d (%s): %.17g is outside %s's range [%g, %g] (model '%s')",
                                   column + 1, name, x, param->name, param->min_value, param->max_value, m->name);
                return mr_fail(MR_ERR_FORMAT, "column %d (%s): %.17g is not an integer (%s is a switch of model '%s')",
                               column + 1, name, x, param->name, m->name);
            }
        }
    }
    // column is now the first tail column's field index (rmse).
    const struct {
        double value;
        int ok;
        const char *expected;
    } tail[] = {
        {row->rmse, isfinite(row->rmse) && row->rmse >= 0.0, "a finite number >= 0"},
        {row->relative_rmse, row->relative_rmse >= 0.0, "a number >= 0 (or inf)"},
        {row->ssim, isfinite(row->ssim) && fabs(row->ssim) <= 1.0 + 1e-9, "a number in [-1, 1]"},
    };
    for (int t = 0; t < 3; t++)
        if (!tail[t].ok) {
            column_name(spec, column + t, name, sizeof name);
            return mr_fail(MR_ERR_FORMAT, "column %d (%s): %g is not %s", column + t + 1, name, tail[t].value,
                           tail[t].expected);
        }
    if ((int)row->outcome < 0 || row->outcome >= MR_FIT_OUTCOME_COUNT)
        return mr_fail(MR_ERR_FORMAT, "column %d (outcome): %d is not an outcome", column + 4, (int)row->outcome);
    if (row->renders < 0)
        return mr_fail(MR_ERR_FORMAT, "column %d (renders): %ld is negative", column + 5, row->renders);
    if (!(isfinite(row->seconds) && row->seconds >= 0.0))
        return mr_fail(MR_ERR_FORMAT, "column %d (seconds): %g is not a finite number >= 0", column + 6, row->seconds);
    return MR_OK;
}

mr_status mr_sweep_check_row(const mr_sweep_spec *spec, const mr_sweep_row *row) {
    mr_status status = mr_sweep_check(spec);
    if (status != MR_OK)
        return status;
    if (row == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "sweep: NULL row");
    return check_row(spec, row);
}

/* ---- the file ------------------------------------------------------------------------------------------------ */

/* What a sample is to a file (sweep_file.state). */
enum { SAMPLE_TODO = 0, SAMPLE_IN_FILE = 1, SAMPLE_NOT_OURS = 2 };

typedef struct sweep_file {
    const char *path;
    int fd;
    off_t size;
    long total;           /* samples in the sweep */
    long shard, shards;   /* the file holds the samples with index % shards == shard (shards 1: all of them) */
    long expected;        /* how many samples that is */
    unsigned char *state; /* per sample: SAMPLE_TODO, _IN_FILE or _NOT_OURS */
    long done_count;      /* samples in the file */
    long truncated;
} sweep_file;

/* Samples with index % shards == shard among [0, total). */
static long shard_size(long total, long shard, long shards) {
    return total > shard ? (total - shard - 1) / shards + 1 : 0;
}

/* Parse and check one complete row line (`length` bytes, its '\n' included) of a file that holds shard
 * `shard` of `shards` of the sweep `spec`: the syntax, the values (check_row), a sample of this file, and that
 * sample's source values. The message says what is wrong, not where: callers add the file and line. */
static mr_status check_line(const mr_sweep_spec *spec, long total, long shard, long shards, const char *line,
                            size_t length, mr_sweep_row *row) {
    mr_status status = parse_row(spec, total, line, length, row);
    if (status == MR_OK)
        status = check_row(spec, row);
    if (status != MR_OK)
        return status;
    if (row->index % shards != shard)
        return mr_fail(MR_ERR_FORMAT, "sample %ld belongs to shard %ld/%ld, not to this file's %ld/%ld", row->index,
                       row->index % shards, shards, shard, shards);
    double source[MR_BRDF_MAX_VALUES];
    sample_unchecked(spec, row->index, source);
    if (memcmp(source, row->source, (size_t)mr_brdf_value_count(spec->source) * sizeof(double)) != 0)
        return mr_fail(MR_ERR_FORMAT, "the source values of sample %ld are not this sweep's (was the file edited?)",
                       row->index);
    return MR_OK;
}

/* Check an existing file against this run's header, collect the samples it holds, and cut off a torn last line
 * (only after everything else checked out, so a refused file is left exactly as it was). A torn line is never
 * counted, even when only its '\n' is missing: its write did not complete. */
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
    while (pos < end) { /* rows */
        const char *nl = memchr(pos, '\n', (size_t)(end - pos));
        line_number++;
        if (nl == NULL) { /* torn last line: a write cut short; everything before it is whole */
            f->truncated = (long)(end - pos);
            break;
        }
        mr_sweep_row row;
        status = check_line(spec, f->total, f->shard, f->shards, pos, (size_t)(nl - pos) + 1, &row);
        if (status == MR_OK && f->state[row.index] == SAMPLE_IN_FILE)
            status = mr_fail(MR_ERR_FORMAT, "sample %ld appears a second time", row.index);
        if (status != MR_OK) {
            free(data);
            return mr_fail_context(status, "sweep file '%s': line %ld", f->path, line_number);
        }
        f->state[row.index] = SAMPLE_IN_FILE;
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

/* Every sample of the file is in it: rewrite it in index order unless it already is (atomic: temporary +
 * rename). */
static mr_status sort_file(sweep_file *f, long header_lines, int *sorted) {
    *sorted = 0;
    char *data = NULL;
    size_t size = 0;
    mr_status status = mr_text_file_read_all(f->fd, f->path, WHAT, &data, &size);
    if (status != MR_OK) return status;
    const char **lines = calloc((size_t)MR_MAX(f->expected, 1), sizeof *lines);
    if (lines == NULL) {
        free(data);
        return mr_fail(MR_ERR_NOMEM, "sweep file '%s': out of memory sorting %ld rows", f->path, f->expected);
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
    // Rows were all validated (or written by us); the index is the text before the first comma, and row k of
    // the sorted file is sample shard + k * shards. The strtol cannot run past the buffer: mr_text_file_read_all
    // NUL-terminates it.
    for (const char *pos = rows; pos < data + size && k < f->expected; k++) {
        long index = strtol(pos, NULL, 10);
        if (index < 0 || index >= f->total || index % f->shards != f->shard)
            index = f->shard; /* cannot happen */
        lines[index / f->shards] = pos;
        in_order &= index == f->shard + k * f->shards;
        const char *nl = memchr(pos, '\n', (size_t)(data + size - pos));
        pos = nl ? nl + 1 : data + size;
    }
    in_order &= k == f->expected;
    for (long i = 0; i < f->expected; i++)
        if (lines[i] == NULL) { /* cannot happen: every sample was checked in; refuse rather than drop rows */
            free(lines);
            free(data);
            return mr_fail(MR_ERR_FORMAT, "sweep file '%s': sample %ld is missing at the end of the run", f->path,
                           f->shard + i * f->shards);
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
        for (long i = 0; ok && i < f->expected; i++) {
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

/* The messages between ranks (mr_sweep_comm). Per pair of ranks they arrive in order, so a worker's HELLO comes
 * before its rows, its rows before its DONE, and rank 0's STOP before its FINAL. Numbers travel in the machine's
 * byte order: the ranks of one run are copies of one build on machines of one architecture (the HELLO's header
 * hash would differ between builds that write other files).
 *   worker -> 0: HELLO   u64 header hash, i64 samples, i32 threads, i32 status, message (a setup failure)
 *   0 -> all:    (broadcast) GO i32 status, i32 0, i64 samples to run; then, if the status is MR_OK, the
 *                (samples + 7) / 8 bytes of the to-do bitmap (bit i % 8 of byte i / 8: sample i runs)
 *   worker -> 0: ROW     one row line, '\n' included
 *   worker -> 0: FAIL    i64 sample, i32 status, message: the sample's remap failed
 *   worker -> 0: DONE    i64 rows sent, i32 status, message (a failure of the rank that ended its share early)
 *   0 -> worker: STOP    (no content) the run failed: start no more samples
 *   0 -> worker: FINAL   i32 status: the run's end, after the file was finished */
enum { TAG_HELLO = 1, TAG_ROW, TAG_FAIL, TAG_DONE, TAG_STOP, TAG_FINAL };

static void put_u64(unsigned char *at, uint64_t v) { memcpy(at, &v, sizeof v); }
static void put_i32(unsigned char *at, int32_t v) { memcpy(at, &v, sizeof v); }
static uint64_t get_u64(const unsigned char *at) {
    uint64_t v;
    memcpy(&v, at, sizeof v);
    return v;
}
static int32_t get_i32(const unsigned char *at) {
    int32_t v;
    memcpy(&v, at, sizeof v);
    return v;
}

/* A fixed part of `fixed` bytes, then a NUL-terminated message: the message of a received buffer (terminated
 * here whatever the sender did; buf has MR_SWEEP_MESSAGE_MAX + 1 bytes). */
static const char *message_text(unsigned char *buf, size_t bytes, size_t fixed) {
    if (bytes < fixed)
        return "";
    buf[MR_MIN(bytes, (size_t)MR_SWEEP_MESSAGE_MAX)] = '\0';
    return (const char *)buf + fixed;
}

/* A status and message into buf (fixed part already there); the message is cut to fit. Returns the size. */
static size_t put_message(unsigned char *buf, size_t fixed, const char *message) {
    size_t len = strnlen(message, MR_SWEEP_MESSAGE_MAX - fixed - 1);
    memcpy(buf + fixed, message, len);
    buf[fixed + len] = '\0';
    return fixed + len + 1;
}

/* FNV-1a: equal headers give equal hashes; a header that differs (another version, other arguments) almost
 * surely does not. */
static uint64_t hash_text(const char *text, size_t length) {
    uint64_t h = 0xcbf29ce484222325ULL;
    for (size_t i = 0; i < length; i++)
        h = (h ^ (unsigned char)text[i]) * 0x100000001b3ULL;
    return h;
}

typedef struct run_state {
    const mr_sweep_spec *spec;
    const mr_sweep_options *opts;
    const mr_sweep_comm *comm; /* NULL: alone */
    int rank, size;
    sweep_file *file; /* rank 0 */
    const mr_render_plan *plan;
    long run_total, run_done; /* rank 0: the whole run's rows (every rank's); other ranks: their own */
    long outcomes[MR_FIT_OUTCOME_COUNT];
    const long *pending;       /* the samples this rank computes */
    int stop;                  /* set (under the file lock) when the run fails: no new samples start */
    long failed;               /* samples whose remap failed (the others go on: their rows are worth having) */
    mr_status failure;         /* the failure to report: a run failure, else the lowest failed sample's */
    long failure_index;
    int run_failed; /* the failure is the run's (file, communication, a rank), not a sample's */
    char failure_message[1024];
    int comm_failed;    /* a comm call failed: this rank stops talking */
    int workers_done;   /* rank 0: DONE messages received */
    int stop_sent;      /* rank 0: STOP sent to the other ranks */
    long threads_total; /* rank 0: threads of every rank */
    unsigned char message[MR_SWEEP_MESSAGE_MAX + 1];
} run_state;

/* Called under the file lock (or with no worker thread running), on the thread that failed (mr_last_error() is
 * per thread; `message` NULL means mr_last_error()). A run failure (the file, communication, a rank) stops the
 * run; a failed remap is counted and the sweep goes on. The reported failure does not depend on thread timing
 * unless the run fails: it is the lowest failed index. */
static void record_failure(run_state *st, mr_status status, long index, int run_failure, const char *message) {
    if (run_failure) {
#pragma omp atomic write
        st->stop = 1;
    } else {
        st->failed++;
    }
    if (st->run_failed || (!run_failure && st->failure != MR_OK && st->failure_index < index))
        return;
    st->failure = status;
    st->failure_index = index;
    st->run_failed = run_failure;
    snprintf(st->failure_message, sizeof st->failure_message, "%s", message ? message : mr_last_error());
}

/* A comm call, its failure recorded as the run's (and this rank stops talking: the peers learn of it from MPI,
 * which ends the job, or from the missing messages). */
static int comm_ok(run_state *st, mr_status status, const char *what) {
    if (status == MR_OK)
        return 1;
    mr_fail_context(status, "sweep: rank %d of %d: %s", st->rank, st->size, what);
    st->comm_failed = 1;
    record_failure(st, status, -1, 1, NULL);
    return 0;
}

static void send_to(run_state *st, int to, int tag, const void *buf, size_t bytes, const char *what) {
    if (!st->comm_failed)
        comm_ok(st, st->comm->send(st->comm->user, to, tag, buf, bytes), what);
}

/* Rank 0, after a run failure: tell the others to start no more samples (once). */
static void stop_others(run_state *st) {
    if (st->rank != 0 || st->size < 2 || st->stop_sent || !st->stop)
        return;
    st->stop_sent = 1;
    unsigned char none = 0;
    for (int r = 1; r < st->size; r++)
        send_to(st, r, TAG_STOP, &none, 1, "telling the ranks to stop");
}

/* Rank 0: append a line, count it and report progress (under the file lock). */
static void append_row(run_state *st, const mr_sweep_row *row, const char *line, size_t length) {
    sweep_file *f = st->file;
    mr_status status = mr_text_file_append(f->fd, f->path, WHAT, line, length, &f->size);
    if (status != MR_OK) {
        record_failure(st, status, row->index, 1, NULL);
        return;
    }
    f->state[row->index] = SAMPLE_IN_FILE;
    f->done_count++;
    st->run_done++;
    st->outcomes[row->outcome]++;
    if (st->opts->progress != NULL) {
        mr_sweep_progress p = {f->done_count, f->total, st->run_done, st->run_total, row};
        st->opts->progress(&p, st->opts->progress_user);
    }
}

/* Rank 0: a row from another rank. It must be one whole line of a sample this run is waiting for; a rank that
 * sends anything else is broken (another build?), and the run stops rather than write a doubtful row. After a
 * run failure rows are dropped (a resume computes them again). */
static void accept_remote_row(run_state *st, int from, const char *line, size_t length) {
    if (st->stop)
        return;
    sweep_file *f = st->file;
    mr_sweep_row row;
    mr_status status = MR_OK;
    if (length == 0 || line[length - 1] != '\n' || memchr(line, '\n', length - 1) != NULL ||
        memchr(line, '\0', length) != NULL)
        status = mr_fail(MR_ERR_FORMAT, "not one line");
    if (status == MR_OK)
        status = check_line(st->spec, f->total, f->shard, f->shards, line, length, &row);
    if (status == MR_OK && f->state[row.index] != SAMPLE_TODO)
        status = mr_fail(MR_ERR_FORMAT, "sample %ld is not one this run is waiting for", row.index);
    if (status != MR_OK) {
        mr_fail_context(status, "sweep: rank %d sent a row that rank 0 cannot accept", from);
        record_failure(st, status, -1, 1, NULL);
        return;
    }
    append_row(st, &row, line, length);
}

/* Rank 0: one message from another rank (under the file lock, or with no worker thread running). */
static void handle_message(run_state *st, int from, int tag, size_t bytes) {
    unsigned char *buf = st->message;
    if (tag == TAG_ROW) {
        accept_remote_row(st, from, (const char *)buf, bytes);
    } else if (tag == TAG_FAIL && bytes >= 12) {
        long index = (long)get_u64(buf);
        mr_status status = (mr_status)get_i32(buf + 8);
        char message[1024];
        snprintf(message, sizeof message, "(on rank %d) %s", from, message_text(buf, bytes, 12));
        record_failure(st, status == MR_OK ? MR_ERR_EXTERNAL : status, index, 0, message);
    } else if (tag == TAG_DONE && bytes >= 12) {
        st->workers_done++;
        mr_status status = (mr_status)get_i32(buf + 8);
        if (status != MR_OK) {
            char message[1024];
            snprintf(message, sizeof message, "sweep: rank %d stopped: %s", from, message_text(buf, bytes, 12));
            record_failure(st, status, -1, 1, message);
        }
    } else {
        mr_fail(MR_ERR_EXTERNAL, "sweep: rank %d sent an unexpected message (tag %d, %zu bytes)", from, tag, bytes);
        record_failure(st, MR_ERR_EXTERNAL, -1, 1, NULL);
    }
    stop_others(st);
}

/* Rank 0: handle the messages that have arrived (wait 0), or wait for one (wait 1). */
static void receive_messages(run_state *st, int wait) {
    for (;;) {
        if (st->comm_failed)
            return;
        int from = -1, tag = 0, got = 0;
        size_t bytes = 0;
        if (!comm_ok(st, st->comm->receive(st->comm->user, wait, &from, &tag, st->message, &bytes, &got), "receiving"))
            return;
        if (!got)
            return;
        handle_message(st, from, tag, MR_MIN(bytes, (size_t)MR_SWEEP_MESSAGE_MAX));
        if (wait)
            return;
    }
}

/* Another rank: any STOP from rank 0 that has arrived (under the file lock). */
static void poll_stop(run_state *st) {
    for (;;) {
        if (st->comm_failed)
            return;
        int from = -1, tag = 0, got = 0;
        size_t bytes = 0;
        if (!comm_ok(st, st->comm->receive(st->comm->user, 0, &from, &tag, st->message, &bytes, &got), "receiving"))
            return;
        if (!got)
            return;
        if (tag != TAG_STOP) {
            mr_fail(MR_ERR_EXTERNAL, "sweep: rank %d: unexpected message (tag %d) from rank %d during the run",
                    st->rank, tag, from);
            st->comm_failed = 1;
            record_failure(st, MR_ERR_EXTERNAL, -1, 1, NULL);
            return;
        }
#pragma omp atomic write
        st->stop = 1;
    }
}

/* Remap sample `index` and hand its row on: rank 0 appends it, the others send it to rank 0. Runs on a worker
 * thread, in the C numeric locale. */
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
        if (st->rank == 0) {
            if (status != MR_OK)
                record_failure(st, status, index, 0, NULL);
            else if (!st->stop)
                append_row(st, &row, line, length);
            if (st->size > 1) {
                receive_messages(st, 0);
                stop_others(st);
            }
        } else if (!st->comm_failed) {
            if (status != MR_OK) {
                st->failed++;
                put_u64(st->message, (uint64_t)index);
                put_i32(st->message + 8, (int32_t)status);
                size_t bytes = put_message(st->message, 12, mr_last_error());
                send_to(st, 0, TAG_FAIL, st->message, bytes, "sending a failure to rank 0");
            } else {
                send_to(st, 0, TAG_ROW, line, length, "sending a row to rank 0");
                st->run_done++;
                st->outcomes[row.outcome]++;
            }
            poll_stop(st);
        }
    }
}

static void run_item(void *ctx, long k) {
    run_state *st = ctx;
    run_sample(st, st->pending[k]);
}

/* The status a finished run reports (rank 0, or this rank alone). */
static mr_status run_status(run_state *st) {
    if (st->run_failed)
        return mr_fail(st->failure, "%s", st->failure_message);
    if (st->failed > 0)
        return mr_fail(st->failure,
                       "sweep: %ld of %ld samples failed (the other rows are in '%s'; a resume retries the failed "
                       "ones); sample %ld: %s",
                       st->failed, st->run_total, st->file->path, st->failure_index, st->failure_message);
    return MR_OK;
}

/* Rank 0 with other ranks: wait for every rank's DONE, handling their rows meanwhile, in the C numeric locale. */
static void gather_others(run_state *st) {
    mr_c_numeric cn;
    mr_status status = mr_c_numeric_enter(&cn, "sweep");
    if (status != MR_OK) {
        record_failure(st, status, -1, 1, NULL);
        stop_others(st);
    }
    while (st->workers_done < st->size - 1 && !st->comm_failed)
        receive_messages(st, 1);
    if (status == MR_OK)
        mr_c_numeric_leave(&cn);
}

/* Another rank, after its share: DONE (with a failure of its own, if any), then wait for rank 0's FINAL. */
static mr_status finish_other(run_state *st, mr_status own) {
    if (st->comm_failed)
        return mr_fail(st->failure, "%s", st->failure_message);
    put_u64(st->message, (uint64_t)st->run_done);
    put_i32(st->message + 8, (int32_t)own);
    size_t bytes = put_message(st->message, 12, own == MR_OK ? "" : mr_last_error());
    send_to(st, 0, TAG_DONE, st->message, bytes, "reporting to rank 0");
    while (!st->comm_failed) {
        int from = -1, tag = 0, got = 0;
        size_t n = 0;
        if (!comm_ok(st, st->comm->receive(st->comm->user, 1, &from, &tag, st->message, &n, &got), "receiving"))
            break;
        if (got && tag == TAG_FINAL && n >= 4) {
            mr_status final = (mr_status)get_i32(st->message);
            if (!comm_ok(st, st->comm->flush(st->comm->user), "flushing its messages"))
                break;
            if (final == MR_OK)
                return MR_OK;
            return mr_fail(final, "sweep: the run failed (rank 0 reports why; this is rank %d)", st->rank);
        }
        // STOP after this rank's last sample: nothing to stop any more.
    }
    return mr_fail(st->failure, "%s", st->failure_message);
}

/* Rank 0 with other ranks, at the end: everyone gets the run's status, and rank 0's messages are delivered. */
static void send_final(run_state *st, mr_status status) {
    unsigned char buf[4];
    put_i32(buf, (int32_t)status);
    for (int r = 1; r < st->size; r++)
        send_to(st, r, TAG_FINAL, buf, sizeof buf, "sending the end to the ranks");
    if (!st->comm_failed)
        comm_ok(st, st->comm->flush(st->comm->user), "flushing its messages");
}

/* Rank 0 with other ranks, before the file is opened: every rank's HELLO; a rank whose header differs from rank
 * 0's runs another sweep (another version, other arguments) and the run is refused. */
static mr_status gather_hellos(run_state *st, uint64_t hash, long total) {
    mr_status result = MR_OK;
    for (int hellos = 0; hellos < st->size - 1;) {
        int from = -1, tag = 0, got = 0;
        size_t bytes = 0;
        mr_status status = st->comm->receive(st->comm->user, 1, &from, &tag, st->message, &bytes, &got);
        if (status != MR_OK)
            return mr_fail_context(status, "sweep: rank 0: waiting for the other ranks");
        if (!got)
            continue;
        if (tag != TAG_HELLO || bytes < 24) {
            if (result == MR_OK)
                result =
                    mr_fail(MR_ERR_EXTERNAL, "sweep: rank %d sent an unexpected first message (tag %d)", from, tag);
            hellos++;
            continue;
        }
        hellos++;
        st->threads_total += get_i32(st->message + 16);
        mr_status theirs = (mr_status)get_i32(st->message + 20);
        if (result != MR_OK)
            continue;
        if (theirs != MR_OK)
            result = mr_fail(theirs, "sweep: rank %d could not start: %s", from, message_text(st->message, bytes, 24));
        else if (get_u64(st->message) != hash || (long)get_u64(st->message + 8) != total)
            result = mr_fail(MR_ERR_INVALID_ARG,
                             "sweep: rank %d runs another sweep than rank 0 (its file header would differ: another "
                             "matremap version, or other arguments?); nothing was written",
                             from);
    }
    return result;
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
    const long total = sample_count_unchecked(spec);
    if (opts->shard_count < 0 ||
        (opts->shard_count > 0 && (opts->shard_index < 0 || opts->shard_index >= opts->shard_count)))
        return mr_fail(MR_ERR_INVALID_ARG, "sweep: shard %ld/%ld: expected K/N with 0 <= K < N", opts->shard_index,
                       opts->shard_count);
    if (opts->shard_count > total)
        return mr_fail(MR_ERR_INVALID_ARG, "sweep: %ld shards for %ld samples: some shards would be empty",
                       opts->shard_count, total);
    const mr_sweep_comm *comm = opts->comm;
    if (comm != NULL && (comm->size < 1 || comm->rank < 0 || comm->rank >= comm->size || comm->broadcast == NULL ||
                         comm->send == NULL || comm->receive == NULL || comm->flush == NULL))
        return mr_fail(MR_ERR_INVALID_ARG, "sweep: comm: rank %d of %d, or a missing function", comm->rank, comm->size);
    const int size = comm ? comm->size : 1, rank = comm ? comm->rank : 0;
    if (size == 1)
        comm = NULL;
#ifdef _OPENMP
    int threads = mr_auto_threads(opts->threads, total, MR_SWEEP_PARALLEL_SAMPLES);
#else
    int threads = 1;
#endif

    run_state *st = calloc(1, sizeof *st);
    if (st == NULL)
        return mr_fail(MR_ERR_NOMEM, "sweep: out of memory");
    st->spec = spec;
    st->opts = opts;
    st->comm = comm;
    st->rank = rank;
    st->size = size;
    st->failure = MR_OK;
    st->threads_total = threads;
    mr_strbuf header = {0}, bare = {0};
    sweep_file f;
    memset(&f, 0, sizeof f);
    f.path = path;
    f.fd = -1;
    f.total = total;
    f.shard = opts->shard_count > 0 ? opts->shard_index : 0;
    f.shards = opts->shard_count > 0 ? opts->shard_count : 1;
    f.expected = shard_size(total, f.shard, f.shards);
    st->file = &f;
    unsigned char *todo = NULL; /* the to-do bitmap, as broadcast */
    const size_t todo_bytes = ((size_t)total + 7) / 8;
    mr_render_plan *plan = NULL;
    long *pending = NULL;

    mr_c_numeric cn;
    status = mr_c_numeric_enter(&cn, "sweep");
    if (status != MR_OK) {
        free(st);
        return status;
    }
    f.state = rank == 0 ? calloc((size_t)total, 1) : NULL; /* only rank 0 keeps the file's books */
    todo = calloc(todo_bytes, 1);
    if ((rank == 0 && f.state == NULL) || todo == NULL)
        status = mr_fail(MR_ERR_NOMEM, "sweep: out of memory for %ld samples", total);
    if (status == MR_OK)
        status = build_header(spec, opts->command_line, opts->shard_index, opts->shard_count, &header);
    if (status == MR_OK)
        status = build_header(spec, NULL, opts->shard_index, opts->shard_count, &bare);
    const uint64_t hash = status == MR_OK ? hash_text(bare.text, bare.length) : 0;

    // Setup: rank 0 hears from every rank, opens the file and tells everyone what to run.
    long todo_count = 0;
    if (rank == 0) {
        if (comm != NULL) {
            mr_status others = gather_hellos(st, hash, total);
            if (status == MR_OK)
                status = others;
        }
        if (status == MR_OK) {
            for (long i = 0; i < total; i++)
                if (i % f.shards != f.shard)
                    f.state[i] = SAMPLE_NOT_OURS;
            status = open_file(spec, &header, opts->resume, &f);
        }
        for (long i = 0; status == MR_OK && i < total; i++)
            if (f.state[i] == SAMPLE_TODO) {
                todo[i / 8] |= (unsigned char)(1u << (i % 8));
                todo_count++;
            }
        if (comm != NULL) {
            unsigned char go[16] = {0};
            put_i32(go, (int32_t)status);
            put_u64(go + 8, (uint64_t)todo_count);
            mr_status sent = comm->broadcast(comm->user, go, sizeof go);
            if (sent == MR_OK && status == MR_OK)
                sent = comm->broadcast(comm->user, todo, todo_bytes);
            if (sent != MR_OK && status == MR_OK) {
                status = mr_fail_context(sent, "sweep: rank 0: telling the ranks what to run");
                st->comm_failed = 1;
            }
        }
    } else {
        put_u64(st->message, hash);
        put_u64(st->message + 8, (uint64_t)total);
        put_i32(st->message + 16, threads);
        put_i32(st->message + 20, (int32_t)status);
        size_t bytes = put_message(st->message, 24, status == MR_OK ? "" : mr_last_error());
        mr_status sent = comm->send(comm->user, 0, TAG_HELLO, st->message, bytes);
        unsigned char go[16] = {0};
        if (sent == MR_OK)
            sent = comm->broadcast(comm->user, go, sizeof go);
        mr_status theirs = (mr_status)get_i32(go);
        if (sent == MR_OK && theirs == MR_OK)
            sent = comm->broadcast(comm->user, todo, todo_bytes);
        if (sent != MR_OK)
            status = mr_fail_context(sent, "sweep: rank %d: hearing from rank 0", rank);
        else if (theirs != MR_OK)
            status = mr_fail(theirs, "sweep: rank 0 did not start the run (it reports why; this is rank %d)", rank);
        for (long i = 0; status == MR_OK && i < total; i++)
            todo_count += (todo[i / 8] >> (i % 8)) & 1;
    }
    mr_c_numeric_leave(&cn);
    const long already = f.done_count;
    // From here on, once the setup succeeded, every rank goes through to the end of the protocol.
    const int started = status == MR_OK;

    // This rank's share: the k-th sample to run goes to rank k % size.
    long share = 0;
    if (status == MR_OK && todo_count > 0) {
        pending = malloc((size_t)(todo_count / size + 1) * sizeof *pending);
        if (pending == NULL)
            status = mr_fail(MR_ERR_NOMEM, "sweep: out of memory for %ld samples", todo_count);
        for (long i = 0, k = 0; status == MR_OK && i < total; i++)
            if ((todo[i / 8] >> (i % 8)) & 1) {
                if (k % size == rank)
                    pending[share++] = i;
                k++;
            }
        if (status == MR_OK && share > 0) {
            mr_scene scene = mr_remap_file_scene(&spec->scene);
            status = mr_render_plan_create(&scene, &plan);
        }
    }
    st->plan = plan;
    st->run_total = rank == 0 ? todo_count : share;
    if (status == MR_OK && share > 0) {
        st->pending = pending;
        mr_status ran = mr_remap_run_parallel(threads, share, &st->stop, run_item, st, "sweep");
        if (ran != MR_OK) {
            if (rank == 0) {
#pragma omp critical(mr_sweep_file)
                record_failure(st, ran, -1, 1, NULL);
            } else {
                status = ran;
            }
        }
    } else if (status != MR_OK && started && rank == 0) {
        record_failure(st, status, -1, 1, NULL); /* rank 0 could not compute its share: the run failed */
        status = MR_OK;
    }

    int sorted = 0;
    if (started && rank == 0) {
        if (comm != NULL) {
            stop_others(st);
            gather_others(st);
        }
        status = run_status(st);
        long header_lines = 0;
        for (size_t i = 0; i < header.length; i++)
            header_lines += header.text[i] == '\n';
        if (status == MR_OK)
            status = sort_file(&f, header_lines, &sorted);
        if (comm != NULL) {
            char message[1024]; /* mr_last_error()'s capacity (status.c) */
            snprintf(message, sizeof message, "%s", mr_last_error());
            send_final(st, status);
            if (status != MR_OK)
                mr_fail(status, "%s", message); /* the run's message, not a later one */
        }
    } else if (started) {
        status = finish_other(st, status);
    }
    if (f.fd >= 0) close(f.fd); /* releases the lock, after the rename */
    mr_render_plan_free(plan);
    free(pending);
    free(todo);
    free(f.state);
    free(header.text);
    free(bare.text);
    if (status == MR_OK && out != NULL) {
        memset(out, 0, sizeof *out);
        out->total = total;
        out->file_total = f.expected;
        out->already_done = already;
        out->computed = st->run_done;
        memcpy(out->outcomes, st->outcomes, sizeof out->outcomes);
        out->truncated_bytes = f.truncated;
        out->sorted = sorted;
        out->threads = threads;
        out->processes = size;
        out->threads_total = rank == 0 ? st->threads_total : threads;
        out->seconds = mr_now_seconds() - start;
    }
    free(st);
    return status;
}

/* ---- merging shards ------------------------------------------------------------------------------------------ */

/* Longest line merge reads (a header's command line can be long; a row is at most MR_SWEEP_MAX_LINE): a file
 * that is one endless line is refused, not swallowed. */
#define MERGE_MAX_LINE (1L << 20)

/* The next line of fp into *buf (grown as needed, NUL-terminated, '\n' kept) and *len; 0 at the end of the file,
 * -1 for a line longer than MERGE_MAX_LINE (MR_ERR_FORMAT) or out of memory (MR_ERR_NOMEM) in *failure, the
 * message naming `path` and the line. */
static int read_line(FILE *fp, const char *path, long line_number, char **buf, size_t *cap, size_t *len,
                     mr_status *failure) {
    *len = 0;
    for (;;) {
        if (*cap - *len < 2) {
            size_t grown = *cap ? 2 * *cap : 4096;
            char *p = realloc(*buf, grown);
            if (p == NULL) {
                *failure = mr_fail(MR_ERR_NOMEM, "shard file '%s': out of memory reading line %ld", path, line_number);
                return -1;
            }
            *buf = p;
            *cap = grown;
        }
        if (fgets(*buf + *len, (int)MR_MIN(*cap - *len, (size_t)INT_MAX), fp) == NULL)
            return *len > 0;
        *len += strlen(*buf + *len);
        if (*len > 0 && (*buf)[*len - 1] == '\n')
            return 1;
        if (*len > (size_t)MERGE_MAX_LINE) {
            *failure = mr_fail(MR_ERR_FORMAT, "shard file '%s': line %ld is longer than %ld bytes", path, line_number,
                               MERGE_MAX_LINE);
            return -1;
        }
    }
}

/* The text after `prefix` of the header line that starts with it, or NULL. */
static const char *header_field(char *const *lines, int count, const char *prefix) {
    size_t n = strlen(prefix);
    for (int i = 0; i < count; i++)
        if (strncmp(lines[i], prefix, n) == 0)
            return lines[i] + n;
    return NULL;
}

/* Split text (a copy) at spaces into at most `max` tokens; returns the count, -1 if there are more. */
static int split_words(char *text, char **words, int max) {
    int n = 0;
    char *save = NULL;
    for (char *w = strtok_r(text, " ", &save); w != NULL; w = strtok_r(NULL, " ", &save)) {
        if (n == max)
            return -1;
        words[n++] = w;
    }
    return n;
}

static int parse_whole_long(const char *text, long *out) { return mr_csv_parse_long(text, strlen(text), out); }

/* "MODEL name=v ..." (the "# from:" / "# to:" lines) into a model and its packed values. */
static mr_status parse_model_values(const char *text, const mr_brdf_model **model, double *values) {
    char copy[MR_SWEEP_MAX_LINE];
    if (strlen(text) >= sizeof copy)
        return mr_fail(MR_ERR_FORMAT, "the line is too long");
    strcpy(copy, text);
    char *words[2 * MR_BRDF_MAX_VALUES + 2];
    int n = split_words(copy, words, (int)(sizeof words / sizeof words[0]));
    if (n < 1)
        return mr_fail(MR_ERR_FORMAT, "no model named");
    *model = mr_brdf_find(words[0]);
    if (*model == NULL)
        return MR_ERR_FORMAT; /* mr_brdf_find's message lists the models */
    mr_brdf_default_values(*model, values);
    for (int k = 1; k < n; k++) {
        mr_status status = mr_brdf_parse_assignment(*model, words[k], values);
        if (status != MR_OK)
            return MR_ERR_FORMAT;
    }
    return MR_OK;
}

/* "strategy=S max_evaluations=N xtol=X grid_points=G starts=S seed=S[ held=a,b]" into spec->remap. */
static mr_status parse_remap_line(const char *text, mr_sweep_spec *spec) {
    char copy[MR_SWEEP_MAX_LINE];
    if (strlen(text) >= sizeof copy)
        return mr_fail(MR_ERR_FORMAT, "the line is too long");
    strcpy(copy, text);
    char *words[16];
    int n = split_words(copy, words, 16);
    for (int k = 0; k < n; k++) {
        char *eq = strchr(words[k], '=');
        if (eq == NULL)
            return mr_fail(MR_ERR_FORMAT, "'%s' is not name=value", words[k]);
        *eq = '\0';
        const char *key = words[k], *value = eq + 1;
        long v = 0;
        int ok = 1;
        if (strcmp(key, "strategy") == 0) {
            ok = mr_remap_strategy_from_name(value, &spec->remap.strategy) == MR_OK;
        } else if (strcmp(key, "xtol") == 0) {
            ok = mr_csv_parse_double(value, strlen(value), &spec->remap.xtol);
        } else if (strcmp(key, "held") == 0) {
            char *save = NULL;
            for (char *name = strtok_r(eq + 1, ",", &save); ok && name != NULL; name = strtok_r(NULL, ",", &save)) {
                int p = mr_brdf_param_index(spec->target, name);
                ok = p >= 0 && p < 32;
                if (ok)
                    spec->remap.held |= 1u << p;
            }
        } else if ((ok = parse_whole_long(value, &v) && v <= INT_MAX)) {
            if (strcmp(key, "max_evaluations") == 0)
                spec->remap.max_evaluations = (int)v;
            else if (strcmp(key, "grid_points") == 0)
                spec->remap.grid_points = (int)v;
            else if (strcmp(key, "starts") == 0)
                spec->remap.starts = (int)v;
            else if (strcmp(key, "seed") == 0)
                spec->remap.seed = (unsigned long)v;
            else
                ok = 0;
        }
        if (!ok)
            return mr_fail(MR_ERR_FORMAT, "'%s=%s' is not a remap option this version knows", key, value);
    }
    return MR_OK;
}

/* "fit size=N light=L intensity=I ..." into spec->scene (the other fields are fixed by the version: the rebuilt
 * header shows whether they match). */
static mr_status parse_scene_line(const char *text, mr_sweep_spec *spec) {
    char copy[MR_SWEEP_MAX_LINE];
    if (strlen(text) >= sizeof copy)
        return mr_fail(MR_ERR_FORMAT, "the line is too long");
    strcpy(copy, text);
    char *words[16];
    int n = split_words(copy, words, 16);
    if (n < 1 || strcmp(words[0], "fit") != 0)
        return mr_fail(MR_ERR_FORMAT, "not a fit scene");
    for (int k = 1; k < n; k++) {
        char *eq = strchr(words[k], '=');
        if (eq == NULL)
            return mr_fail(MR_ERR_FORMAT, "'%s' is not name=value", words[k]);
        *eq = '\0';
        long v = 0;
        int ok = 1;
        if (strcmp(words[k], "size") == 0)
            ok = parse_whole_long(eq + 1, &v) && v <= MR_RENDER_MAX_SIZE && (spec->scene.size = (int)v, 1);
        else if (strcmp(words[k], "light") == 0)
            ok = mr_fit_light_from_name(eq + 1, &spec->scene.light) == MR_OK;
        else if (strcmp(words[k], "intensity") == 0)
            ok = mr_csv_parse_double(eq + 1, strlen(eq + 1), &spec->scene.intensity);
        if (!ok)
            return mr_fail(MR_ERR_FORMAT, "'%s=%s' is not a scene setting this version knows", words[k], eq + 1);
    }
    return MR_OK;
}

mr_status mr_sweep_scene_parse(const char *text, mr_fit_scene_options *out) {
    mr_sweep_spec spec;
    memset(&spec, 0, sizeof spec);
    mr_status status = text != NULL && out != NULL ? parse_scene_line(text, &spec)
                                                    : mr_fail(MR_ERR_INVALID_ARG, "sweep scene: NULL argument");
    if (status == MR_OK) *out = spec.scene;
    return status;
}

/* "grid AXIS ..." or "random=N seed=S over p,q,..." into the spec's sampling. */
static mr_status parse_sampling_line(const char *text, mr_sweep_spec *spec) {
    char copy[MR_SWEEP_MAX_LINE];
    if (strlen(text) >= sizeof copy)
        return mr_fail(MR_ERR_FORMAT, "the line is too long");
    strcpy(copy, text);
    char *words[MR_SWEEP_MAX_AXES + 1];
    int n = split_words(copy, words, MR_SWEEP_MAX_AXES + 1);
    if (n >= 2 && strcmp(words[0], "grid") == 0) {
        spec->sampling = MR_SWEEP_GRID;
        for (int k = 1; k < n; k++) {
            mr_status status = mr_sweep_parse_axis(spec->source, words[k], &spec->axes[k - 1]);
            if (status != MR_OK)
                return MR_ERR_FORMAT;
        }
        spec->axis_count = n - 1;
        return MR_OK;
    }
    spec->region = MR_SWEEP_REGION_RANGE; // a header without a region word
    if (n == 5 && strncmp(words[2], "region=", 7) == 0) {
        if (mr_sweep_region_from_name(words[2] + 7, &spec->region) != MR_OK)
            return mr_fail(MR_ERR_FORMAT, "'%s': expected region=texture or region=range", words[2]);
        words[2] = words[3];
        words[3] = words[4];
        n = 4;
    }
    if (n == 4 && strncmp(words[0], "random=", 7) == 0 && strncmp(words[1], "seed=", 5) == 0 &&
        strcmp(words[2], "over") == 0) {
        spec->sampling = MR_SWEEP_RANDOM;
        char *end = NULL;
        errno = 0;
        unsigned long long seed = strtoull(words[1] + 5, &end, 10);
        if (!parse_whole_long(words[0] + 7, &spec->random_count) || words[1][5] < '0' || words[1][5] > '9' ||
            *end != '\0' || errno == ERANGE)
            return mr_fail(MR_ERR_FORMAT, "'%s %s': expected random=N seed=S", words[0], words[1]);
        spec->seed = seed;
        // Every parameter not drawn is held (switches and fixed factors are never drawn anyway).
        spec->held = spec->source->param_count >= 32 ? ~0u : (1u << spec->source->param_count) - 1;
        char *save = NULL;
        for (char *name = strtok_r(words[3], ",", &save); name != NULL; name = strtok_r(NULL, ",", &save)) {
            int p = mr_brdf_param_index(spec->source, name);
            if (p < 0 || p >= 32)
                return mr_fail(MR_ERR_FORMAT, "model '%s' has no parameter '%s'", spec->source->name, name);
            spec->held &= ~(1u << p);
        }
        return MR_OK;
    }
    return mr_fail(MR_ERR_FORMAT, "expected 'grid AXIS ...' or 'random=N seed=S [region=R] over PARAMETERS'");
}

/* One shard file being merged. */
typedef struct merge_shard {
    const char *path;
    FILE *fp;
    mr_sweep_spec spec;
    long k, n;
    char *bare;       /* the header without its "# shard:" and "# command:" lines: equal for shards of one sweep */
    long line_number; /* of the last line read */
    dev_t dev;
    ino_t ino;
} merge_shard;

/* Read and check a shard's header: parsed back into a sweep, which must rebuild the header byte for byte. */
static mr_status read_shard_header(merge_shard *s) {
    enum { MAX_HEADER_LINES = 32 };
    char *lines[MAX_HEADER_LINES] = {0};
    int count = 0;
    char *buf = NULL;
    size_t cap = 0, len = 0;
    mr_status status = MR_OK;
    mr_strbuf file_header = {0}, rebuilt = {0}, bare = {0};
    for (;;) { /* the '#' lines and the column line */
        int got = read_line(s->fp, s->path, s->line_number + 1, &buf, &cap, &len, &status);
        if (got < 0)
            break;
        if (got == 0 || buf[len - 1] != '\n') {
            status = mr_fail(MR_ERR_FORMAT, "shard file '%s': the header ends early, at line %ld (%s)", s->path,
                             s->line_number + 1, got ? "a torn line" : "the end of the file");
            break;
        }
        s->line_number++;
        if (count == MAX_HEADER_LINES) {
            status = mr_fail(MR_ERR_FORMAT, "shard file '%s': no column line after %d header lines", s->path, count);
            break;
        }
        mr_strbuf_printf(&file_header, "%s", buf);
        buf[len - 1] = '\0';
        lines[count] = strdup(buf);
        if (lines[count++] == NULL) {
            status = mr_fail(MR_ERR_NOMEM, "shard file '%s': out of memory", s->path);
            break;
        }
        if (buf[0] != '#')
            break; /* the column line ends the header */
    }
    free(buf);
    const char *from = NULL, *to = NULL, *remap = NULL, *scene = NULL, *sampling = NULL, *shard = NULL;
    const char *command = NULL;
    if (status == MR_OK) {
        from = header_field(lines, count, "# from: ");
        to = header_field(lines, count, "# to: ");
        remap = header_field(lines, count, "# remap: ");
        scene = header_field(lines, count, "# scene: ");
        sampling = header_field(lines, count, "# sampling: ");
        shard = header_field(lines, count, SHARD_PREFIX);
        command = header_field(lines, count, COMMAND_PREFIX);
        if (strncmp(lines[0], "# matremap ", 11) != 0 || from == NULL || to == NULL || remap == NULL || scene == NULL ||
            sampling == NULL || command == NULL)
            status = mr_fail(MR_ERR_FORMAT,
                             "shard file '%s' is not a sweep file (its header lacks a '# from:', "
                             "'# to:', '# remap:', '# scene:', '# sampling:' or '# command:' line)",
                             s->path);
        else if (shard == NULL)
            status = mr_fail(MR_ERR_FORMAT,
                             "'%s' is a whole sweep, not a shard (its header has no '# shard: K/N' "
                             "line): merge takes the files of 'matremap sweep ... --shard K/N' runs",
                             s->path);
    }
    if (status == MR_OK) {
        const char *slash = strchr(shard, '/');
        char kbuf[32];
        size_t klen = slash ? (size_t)(slash - shard) : 0;
        if (klen > 0 && klen < sizeof kbuf) {
            memcpy(kbuf, shard, klen);
            kbuf[klen] = '\0';
        }
        if (slash == NULL || klen == 0 || klen >= sizeof kbuf || !parse_whole_long(kbuf, &s->k) ||
            !parse_whole_long(slash + 1, &s->n) || s->n < 1 || s->k >= s->n)
            status =
                mr_fail(MR_ERR_FORMAT, "shard file '%s': '# shard: %s' is not K/N with 0 <= K < N", s->path, shard);
    }
    // The sweep, read back. A line this version would write otherwise shows in the comparison below.
    const char *step = "# from:";
    if (status == MR_OK) {
        const mr_brdf_model *source = NULL, *target = NULL;
        double sv[MR_BRDF_MAX_VALUES], tv[MR_BRDF_MAX_VALUES];
        status = parse_model_values(from, &source, sv);
        if (status == MR_OK) {
            step = "# to:";
            status = parse_model_values(to, &target, tv);
        }
        if (status == MR_OK) {
            mr_sweep_spec_init(&s->spec, source, target);
            memcpy(s->spec.source_values, sv, sizeof sv);
            memcpy(s->spec.target_values, tv, sizeof tv);
            step = "# remap:";
            status = parse_remap_line(remap, &s->spec);
        }
        if (status == MR_OK) {
            step = "# scene:";
            status = parse_scene_line(scene, &s->spec);
        }
        if (status == MR_OK) {
            step = "# sampling:";
            status = parse_sampling_line(sampling, &s->spec);
        }
        if (status == MR_OK) {
            step = "the header";
            status = mr_sweep_check(&s->spec);
        }
        if (status != MR_OK)
            mr_fail_context(MR_ERR_FORMAT, "shard file '%s': %s line", s->path, step);
        if (status != MR_OK)
            status = MR_ERR_FORMAT;
    }
    if (status == MR_OK) {
        status = build_header(&s->spec, command, s->k, s->n, &rebuilt);
        if (status == MR_OK && (file_header.failed || rebuilt.length != file_header.length ||
                                memcmp(rebuilt.text, file_header.text, rebuilt.length) != 0)) {
            // Name the first line that differs.
            const char *a = file_header.text ? file_header.text : "", *b = rebuilt.text;
            long line = 1;
            while (*a && *a == *b) {
                if (*a == '\n')
                    line++;
                a++;
                b++;
            }
            while (a > file_header.text && a[-1] != '\n')
                a--, b--;
            status =
                mr_fail(MR_ERR_FORMAT,
                        "shard file '%s': line %ld is '%.*s', but the sweep its header describes would have "
                        "'%.*s' (written by another matremap version, or edited?)",
                        s->path, line, (int)MR_MIN(strcspn(a, "\n"), 200), a, (int)MR_MIN(strcspn(b, "\n"), 200), b);
        }
    }
    if (status == MR_OK) {
        for (int i = 0; i < count; i++)
            if (strncmp(lines[i], SHARD_PREFIX, strlen(SHARD_PREFIX)) != 0 &&
                strncmp(lines[i], COMMAND_PREFIX, strlen(COMMAND_PREFIX)) != 0)
                mr_strbuf_printf(&bare, "%s\n", lines[i]);
        if (bare.failed)
            status = mr_fail(MR_ERR_NOMEM, "shard file '%s': out of memory", s->path);
        s->bare = bare.text;
        bare.text = NULL;
    }
    for (int i = 0; i < count; i++)
        free(lines[i]);
    free(file_header.text);
    free(rebuilt.text);
    free(bare.text);
    return status;
}

/* The first line where two shards' headers (shard and command lines left out) differ, for the message. */
static mr_status shards_differ(const merge_shard *a, const merge_shard *b) {
    const char *x = a->bare, *y = b->bare;
    long line = 1;
    while (*x && *x == *y) {
        if (*x == '\n')
            line++;
        x++;
        y++;
    }
    while (x > a->bare && x[-1] != '\n')
        x--, y--;
    return mr_fail(MR_ERR_INVALID_ARG,
                   "shard files '%s' and '%s' are from different sweeps: '%.*s' in the first, '%.*s' in the second",
                   a->path, b->path, (int)MR_MIN(strcspn(x, "\n"), 200), x, (int)MR_MIN(strcspn(y, "\n"), 200), y);
}

/* Open a shard and read its header. */
static mr_status open_shard(merge_shard *s) {
    // Regular files only, opened without blocking (fopen blocked on a FIFO named as a shard).
    char label[MR_IO_LABEL_SIZE + 16];
    snprintf(label, sizeof label, "shard file '%s'", s->path);
    mr_status opened = mr_io_open_input(s->path, label, 0, &s->fp, NULL);
    if (opened != MR_OK) return opened == MR_ERR_IO && errno == ENOENT ? MR_ERR_INVALID_ARG : opened;
    struct stat st;
    if (fstat(fileno(s->fp), &st) != 0 || !S_ISREG(st.st_mode))
        return mr_fail(MR_ERR_INVALID_ARG, "shard file '%s' is not a regular file", s->path);
    s->dev = st.st_dev;
    s->ino = st.st_ino;
    // A sweep still writing the shard holds its write lock (mr_text_file_lock): its rows are not all there yet.
    struct flock lock;
    memset(&lock, 0, sizeof lock);
    lock.l_type = F_WRLCK;
    lock.l_whence = SEEK_SET;
    if (fcntl(fileno(s->fp), F_GETLK, &lock) == 0 && lock.l_type != F_UNLCK)
        return mr_fail(MR_ERR_INVALID_ARG,
                       "shard file '%s' is being written by another process (pid %ld): merge it when its sweep has "
                       "finished",
                       s->path, (long)lock.l_pid);
    return read_shard_header(s);
}

/* Copy the rows of the shards, in index order (sample i is row i / N of shard i % N), into out, checking each. */
static mr_status merge_rows(merge_shard *const *by_k, long n, const mr_sweep_spec *spec, long total, FILE *out) {
    char *buf = NULL;
    size_t cap = 0, len = 0;
    mr_status status = MR_OK;
    for (long i = 0; status == MR_OK && i < total; i++) {
        merge_shard *s = by_k[i % n];
        const long want = shard_size(total, s->k, s->n);
        int got = read_line(s->fp, s->path, s->line_number + 1, &buf, &cap, &len, &status);
        if (got < 0)
            break;
        if (got == 0) {
            status = mr_fail(MR_ERR_INVALID_ARG,
                             "shard file '%s' (shard %ld/%ld) ends after %ld of its %ld rows, at sample %ld: finish "
                             "it first (run its sweep again with --resume)",
                             s->path, s->k, s->n, i / n, want, i);
            break;
        }
        s->line_number++;
        if (buf[len - 1] != '\n') {
            status = mr_fail(MR_ERR_INVALID_ARG,
                             "shard file '%s': line %ld is torn (no line end): the shard was interrupted; finish it "
                             "first (run its sweep again with --resume)",
                             s->path, s->line_number);
            break;
        }
        mr_sweep_row row;
        status = check_line(spec, total, s->k, s->n, buf, len, &row);
        if (status == MR_OK && row.index != i)
            status = mr_fail(row.index < i ? MR_ERR_FORMAT : MR_ERR_INVALID_ARG,
                             "sample %ld where sample %ld belongs (%s)", row.index, i,
                             row.index < i ? "a sample twice, or rows out of order: an unfinished shard? run its "
                                             "sweep again with --resume"
                                           : "samples are missing: finish the shard first (run its sweep again "
                                             "with --resume)");
        if (status != MR_OK) {
            mr_fail_context(status, "shard file '%s': line %ld", s->path, s->line_number);
            break;
        }
        if (fwrite(buf, 1, len, out) != len) {
            int err = errno;
            status = mr_fail(MR_ERR_IO, "sweep merge: cannot write: %s", strerror(err));
        }
    }
    for (long k = 0; status == MR_OK && k < n; k++) { /* nothing may follow a shard's last sample */
        merge_shard *s = by_k[k];
        int got = read_line(s->fp, s->path, s->line_number + 1, &buf, &cap, &len, &status);
        if (got > 0)
            status = mr_fail(MR_ERR_FORMAT,
                             "shard file '%s': line %ld follows the shard's last sample (%ld rows): an "
                             "edited file?",
                             s->path, s->line_number + 1, shard_size(total, s->k, s->n));
    }
    free(buf);
    return status;
}

mr_status mr_sweep_merge(const char *const *paths, int count, const char *output, const char *command_line,
                         mr_sweep_merge_summary *out) {
    if (paths == NULL || count < 1)
        return mr_fail(MR_ERR_INVALID_ARG, "sweep merge: no shard files given");
    if (output == NULL || output[0] == '\0')
        return mr_fail(MR_ERR_INVALID_ARG, "sweep merge: empty output path");
    struct stat ost;
    if (lstat(output, &ost) == 0)
        return mr_fail(MR_ERR_INVALID_ARG,
                       "sweep merge: '%s' already exists; not overwriting it (remove it, or "
                       "choose another -o)",
                       output);
    merge_shard *shards = calloc((size_t)count, sizeof *shards);
    merge_shard **by_k = calloc((size_t)count, sizeof *by_k);
    mr_c_numeric cn;
    mr_status status = mr_c_numeric_enter(&cn, "sweep merge");
    if (status != MR_OK) {
        free(shards);
        free(by_k);
        return status;
    }
    if (shards == NULL || by_k == NULL)
        status = mr_fail(MR_ERR_NOMEM, "sweep merge: out of memory");
    for (int i = 0; status == MR_OK && i < count; i++) {
        shards[i].path = paths[i];
        status = open_shard(&shards[i]);
        for (int j = 0; status == MR_OK && j < i; j++)
            if (shards[j].dev == shards[i].dev && shards[j].ino == shards[i].ino)
                status = mr_fail(MR_ERR_INVALID_ARG, "sweep merge: '%s' and '%s' are the same file", shards[j].path,
                                 shards[i].path);
    }
    // They must be the N shards of one sweep, each once.
    const long n = status == MR_OK ? shards[0].n : 0;
    for (int i = 0; status == MR_OK && i < count; i++) {
        merge_shard *s = &shards[i];
        if (s->n != n)
            status = mr_fail(MR_ERR_INVALID_ARG,
                             "shard files '%s' and '%s' split the sweep differently: shard %ld/%ld and %ld/%ld (all "
                             "shards must come from runs with the same N)",
                             shards[0].path, s->path, shards[0].k, shards[0].n, s->k, s->n);
        else if (strcmp(s->bare, shards[0].bare) != 0)
            status = shards_differ(&shards[0], s);
        for (int j = 0; status == MR_OK && j < i; j++)
            if (shards[j].k == s->k)
                status = mr_fail(MR_ERR_INVALID_ARG, "shard files '%s' and '%s' are both shard %ld/%ld", shards[j].path,
                                 s->path, s->k, n);
    }
    if (status == MR_OK && count != n) {
        char missing[512] = "";
        size_t used = 0;
        for (long k = 0, listed = 0; k < n && used + 32 < sizeof missing; k++) {
            int given = 0;
            for (int i = 0; i < count; i++)
                given |= shards[i].k == k;
            if (given)
                continue;
            used += (size_t)snprintf(missing + used, sizeof missing - used, "%s%ld/%ld", listed++ ? ", " : "", k, n);
        }
        status = mr_fail(MR_ERR_INVALID_ARG,
                         "sweep merge: %d shard files given, the sweep has %ld shards; missing: "
                         "%s",
                         count, n, missing);
    }
    for (int i = 0; status == MR_OK && i < count; i++)
        by_k[shards[i].k] = &shards[i]; /* K < N = count */
    mr_atomic_file tmp;
    memset(&tmp, 0, sizeof tmp);
    FILE *fp = NULL;
    long total = 0;
    if (status == MR_OK) {
        total = sample_count_unchecked(&shards[0].spec);
        status = mr_atomic_begin(output, &tmp);
    }
    if (status == MR_OK && (fp = fopen(tmp.tmp_path, "w")) == NULL) {
        int err = errno;
        status =
            mr_fail(MR_ERR_IO, "sweep merge: cannot open the temporary file '%s': %s", tmp.tmp_path, strerror(err));
    }
    if (status == MR_OK) {
        mr_strbuf header = {0};
        status = build_header(&shards[0].spec, command_line, 0, 0, &header);
        if (status == MR_OK && fwrite(header.text, 1, header.length, fp) != header.length) {
            int err = errno;
            status = mr_fail(MR_ERR_IO, "sweep merge: cannot write '%s': %s", tmp.tmp_path, strerror(err));
        }
        free(header.text);
    }
    if (status == MR_OK)
        status = merge_rows(by_k, n, &shards[0].spec, total, fp);
    if (fp != NULL) {
        int err = 0;
        if (fflush(fp) != 0)
            err = errno;
        if (fclose(fp) != 0 && err == 0)
            err = errno;
        if (err != 0 && status == MR_OK)
            status = mr_fail(MR_ERR_IO, "sweep merge: cannot write '%s': %s", tmp.tmp_path, strerror(err));
    }
    // Checked again just before the rename: the output may have appeared meanwhile (it is never replaced).
    if (status == MR_OK && lstat(output, &ost) == 0)
        status = mr_fail(MR_ERR_INVALID_ARG, "sweep merge: '%s' appeared while merging; not overwriting it", output);
    if (status == MR_OK)
        status = mr_atomic_commit(&tmp);
    if (status != MR_OK && tmp.active)
        mr_atomic_abort(&tmp);
    mr_c_numeric_leave(&cn);
    for (int i = 0; shards != NULL && i < count; i++) {
        if (shards[i].fp != NULL)
            fclose(shards[i].fp);
        free(shards[i].bare);
    }
    free(shards);
    free(by_k);
    if (status == MR_OK && out != NULL) {
        out->total = total;
        out->shards = n;
    }
    return status;
}
