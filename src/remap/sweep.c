/*
 * sweep.c — parameter sweeps through mr_remap, streamed to a crash-safe, resumable CSV file (contract in
 * sweep.h): the samples, the spec's checks, the file opened, resumed and sorted, and the run (threads, and ranks
 * under MPI). The file's format (header, rows, their checks) is sweep_file.c's; merging shards, sweep_merge.c's.
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
#include "../mr_internal.h"
#include "remap_file.h"
#include "sweep_file.h"
#include "sweep_internal.h"

#define WHAT "sweep file" /* what messages call the file */

/* ---- samples --------------------------------------------------------------------------------------------- */

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
            double u = mr_rng_unit(state);
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
    // mr_rng_mix is a bijection (mr_core.h), so distinct (seed, index) start states never coincide for one seed.
    uint64_t state = mr_rng_mix(mr_rng_mix((uint64_t)spec->seed) + (uint64_t)index);
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
    if (status == MR_OK && spec->renderers.source[0]) status = mr_renderer_check(spec->renderers.source, m);
    if (status == MR_OK && spec->renderers.target[0])
        status = mr_renderer_check(spec->renderers.target, spec->target);
    if (status == MR_OK && spec->renderers.samples < 0)
        status = mr_fail(MR_ERR_INVALID_ARG, "sweep: renderer samples %d: expected 0 (default) or more",
                         spec->renderers.samples);
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

long mr_sweep_total_unchecked(const mr_sweep_spec *spec) { return sample_count_unchecked(spec); }

int mr_sweep_draws_param(const mr_sweep_spec *spec, int p) { return random_eligible(spec, p); }


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

long mr_sweep_shard_size(long total, long shard, long shards) {
    return total > shard ? (total - shard - 1) / shards + 1 : 0;
}

mr_status mr_sweep_check_line(const mr_sweep_spec *spec, long total, long shard, long shards, const char *line,
                              size_t length, mr_sweep_row *row) {
    mr_status status = mr_sweep_file_parse_row(spec, total, line, length, row);
    if (status == MR_OK)
        status = mr_sweep_file_check_row(spec, row);
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
                                       header->length, MR_SWEEP_COMMAND_PREFIX, &rows_at, &line_number);
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
        status = mr_sweep_check_line(spec, f->total, f->shard, f->shards, pos, (size_t)(nl - pos) + 1, &row);
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
    mr_renderer *renderers[2]; /* the sources' and the targets' renderers: NULL = built-in */
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
        status = mr_sweep_check_line(st->spec, f->total, f->shard, f->shards, line, length, &row);
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
    o.source_renderer = st->renderers[0];
    o.target_renderer = st->renderers[1];
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
        status = mr_sweep_file_format_row(spec, &row, line, sizeof line, &length);
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
    f.expected = mr_sweep_shard_size(total, f.shard, f.shards);
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
        status = mr_sweep_file_header(spec, opts->command_line, opts->shard_index, opts->shard_count, &header);
    if (status == MR_OK)
        status = mr_sweep_file_header(spec, NULL, opts->shard_index, opts->shard_count, &bare);
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
        // External renderers: one process per worker thread, started by the first render that needs it.
        const char *names[2] = {spec->renderers.source, spec->renderers.target};
        for (int k = 0; k < 2 && status == MR_OK && share > 0; k++) {
            if (names[k][0] == '\0' || strcmp(names[k], "builtin") == 0) continue;
            mr_renderer_options ro = {0};
            ro.samples = spec->renderers.samples;
            ro.processes = threads;
            status = mr_renderer_open(names[k], &ro, &st->renderers[k]);
            if (status == MR_OK) status = mr_renderer_start(st->renderers[k], NULL, 0);
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
    long renderer_renders = 0, renderer_starts = 0;
    for (int k = 0; k < 2; k++) {
        renderer_renders += mr_renderer_render_count(st->renderers[k]);
        renderer_starts += mr_renderer_process_starts(st->renderers[k]);
        mr_renderer_free(st->renderers[k]);
    }
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
        out->renderer_renders = renderer_renders;
        out->renderer_starts = renderer_starts;
    }
    free(st);
    return status;
}
