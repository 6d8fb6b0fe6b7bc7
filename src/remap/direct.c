/*
 * direct.c — the direct remap of texels through mr_remap: quantisation, deduplication, warm-started chains and the
 * answer cache (contract in direct.h).
 *
 * Why the pieces are what they are:
 *   - Real texture sets hold far fewer distinct values than texels, and a remap costs milliseconds, so each
 *     distinct quantised value is remapped once (a hash table keyed by the bits of the quantised vector).
 *   - A local refinement from a neighbour's answer costs about half a full remap (no global grid: docs/
 *     performance.md, "Direct remaps"), so the unique values are ordered so that most have a solved neighbour:
 *     a Morton (Z-order) curve through their quantised coordinates keeps nearby values together, cut into fixed
 *     chains. The chains depend on the input alone, and each runs on one thread from its first value to its last,
 *     so the answers do not depend on the thread count.
 *   - The cache file follows the sweep file's protocol (remap_file.h): one write() per complete line, O_APPEND, a
 *     lock, a header that must match.
 */
#include "direct.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#ifdef _OPENMP
#include <omp.h>
#endif

#include "../c_locale.h"
#include "../io/image_io.h"
#include "../mr_internal.h"
#include "remap_file.h"

#define WHAT "direct cache" /* what messages call the cache file */
#define MAX_TOLERANCE 1.0
#define MIN_TOLERANCE MR_DIRECT_MIN_TOLERANCE /* direct.h; keeps the quantised coordinates far inside int64 */

/* ---- quantisation ---------------------------------------------------------------------------------------- */

typedef enum slot_scale { SCALE_LINEAR, SCALE_LOG, SCALE_SRGB, SCALE_EXACT } slot_scale;

/* How a parameter is quantised (direct.h): switches exactly, roughness-like ones in log space, colours (RGB
 * parameters) in sRGB-encoded units, the rest linearly. */
static slot_scale scale_of(const mr_brdf_param *p) {
    if (p->role == MR_PARAM_SWITCH) return SCALE_EXACT;
    if ((p->flags & MR_PARAM_LOG_SCALE) && p->min_value > 0.0) return SCALE_LOG;
    if (p->channels == 3) return SCALE_SRGB;
    return SCALE_LINEAR;
}

/* Quantise one vector (direct.h): q[] the quantised values, k[] (may be NULL) their integer coordinates (steps of
 * t, of t_log for log-scale slots), *clamped (may be NULL) set to 1 if a value was outside its range. Returns the
 * packed slot of the first value that is not finite, or -1. */
static int quantise_vector(const mr_brdf_model *m, double t_all, double t_log, const double *in, double *q, int64_t *k,
                           int *clamped) {
    int slot = 0;
    for (int i = 0; i < m->param_count; i++) {
        const mr_brdf_param *p = &m->params[i];
        const slot_scale scale = scale_of(p);
        const double t = scale == SCALE_LOG ? t_log : t_all;
        for (int c = 0; c < p->channels; c++, slot++) {
            const double raw = in[slot];
            if (!isfinite(raw)) return slot;
            const double v = mr_clampd(raw, p->min_value, p->max_value);
            if (clamped != NULL && v != raw) *clamped = 1;
            double key, value;
            if (scale == SCALE_LOG) {
                key = nearbyint(log(v) / t);
                value = exp(key * t);
            } else if (scale == SCALE_SRGB) {
                key = nearbyint(mr_srgb_encode_double(v) / t);
                value = mr_srgb_decode_double(key * t);
            } else if (scale == SCALE_LINEAR) {
                key = nearbyint(v / t);
                value = key * t;
            } else {
                key = nearbyint(v);
                value = v;
            }
            // + 0.0 turns a -0 into +0: equal values must have equal bits (the hash keys on them).
            q[slot] = mr_clampd(value, p->min_value, p->max_value) + 0.0;
            if (k != NULL) k[slot] = (int64_t)key;
        }
    }
    return -1;
}

/* The name of the parameter owning packed slot `slot` of m, with its channel ("diffuse[1]"), into buf. */
static const char *slot_name(const mr_brdf_model *m, int slot, char *buf, size_t size) {
    for (int i = 0, offset = 0; i < m->param_count; offset += m->params[i].channels, i++)
        if (slot < offset + m->params[i].channels) {
            if (m->params[i].channels == 1)
                snprintf(buf, size, "%s", m->params[i].name);
            else
                snprintf(buf, size, "%s[%d]", m->params[i].name, slot - offset);
            return buf;
        }
    snprintf(buf, size, "slot %d", slot);
    return buf;
}

static mr_status check_tolerance(double *t) {
    if (*t == 0.0) *t = MR_DIRECT_DEFAULT_TOLERANCE;
    if (!(*t >= MIN_TOLERANCE && *t <= MAX_TOLERANCE))
        return mr_fail(MR_ERR_INVALID_ARG, "direct remap: tolerance %g: expected a step in [%g, %g] (0: default %g)",
                       *t, MIN_TOLERANCE, MAX_TOLERANCE, MR_DIRECT_DEFAULT_TOLERANCE);
    return MR_OK;
}

/* The roughness step (direct.h, mr_direct_options.roughness_tolerance): 0 = the step t itself. */
static mr_status check_roughness_tolerance(double t, double *t_log) {
    if (*t_log == 0.0) *t_log = t;
    if (!(*t_log >= MIN_TOLERANCE && *t_log <= MAX_TOLERANCE))
        return mr_fail(MR_ERR_INVALID_ARG, "direct remap: roughness tolerance %g: expected a step in [%g, %g] (0: the "
                       "tolerance)", *t_log, MIN_TOLERANCE, MAX_TOLERANCE);
    return MR_OK;
}

mr_status mr_direct_quantise(const mr_brdf_model *source, double tolerance, const double *in, double *q) {
    return mr_direct_quantise_steps(source, tolerance, 0.0, in, q);
}

mr_status mr_direct_quantise_steps(const mr_brdf_model *source, double tolerance, double roughness_tolerance,
                                   const double *in, double *q) {
    if (source == NULL || in == NULL || q == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "direct remap: NULL model, values or output");
    mr_status status = check_tolerance(&tolerance);
    if (status == MR_OK) status = check_roughness_tolerance(tolerance, &roughness_tolerance);
    if (status != MR_OK) return status;
    double out[MR_BRDF_MAX_VALUES];
    const int bad = quantise_vector(source, tolerance, roughness_tolerance, in, out, NULL, NULL);
    if (bad >= 0) {
        char name[64];
        return mr_fail(MR_ERR_INVALID_ARG, "direct remap: %s = %g: expected a finite value",
                       slot_name(source, bad, name, sizeof name), in[bad]);
    }
    memcpy(q, out, (size_t)mr_brdf_value_count(source) * sizeof *q);
    return MR_OK;
}

/* ---- a table of vectors, keyed by their bits --------------------------------------------------------------- */

/* Open addressing over indices into a growing array of `width`-double keys; slots hold index + 1 (0: empty). */
typedef struct vector_table {
    int width;
    double *keys;       /* count * width */
    size_t count, key_capacity;
    uint32_t *slots;
    size_t slot_capacity; /* a power of 2, at least twice count */
} vector_table;

static uint32_t hash_vector(const double *v, int width) {
    uint32_t words[2 * MR_BRDF_MAX_VALUES];
    memcpy(words, v, (size_t)width * sizeof *v);
    return mr_hash_words(words, 2 * width);
}

static void table_free(vector_table *t) {
    free(t->keys);
    free(t->slots);
}

static int table_rehash(vector_table *t, size_t capacity) {
    uint32_t *slots = calloc(capacity, sizeof *slots);
    if (slots == NULL) return 0;
    for (size_t i = 0; i < t->count; i++) {
        size_t at = hash_vector(t->keys + i * (size_t)t->width, t->width) & (capacity - 1);
        while (slots[at] != 0) at = (at + 1) & (capacity - 1);
        slots[at] = (uint32_t)(i + 1);
    }
    free(t->slots);
    t->slots = slots;
    t->slot_capacity = capacity;
    return 1;
}

/* The index of `key` in the table, adding it (at the end) if `insert` and it is new; SIZE_MAX if it is absent
 * (insert = 0) or memory ran out (insert = 1: *failed set). */
static size_t table_find(vector_table *t, const double *key, int insert, int *failed) {
    const size_t bytes = (size_t)t->width * sizeof *key;
    if (t->slot_capacity > 0) {
        size_t at = hash_vector(key, t->width) & (t->slot_capacity - 1);
        for (; t->slots[at] != 0; at = (at + 1) & (t->slot_capacity - 1)) {
            const size_t index = t->slots[at] - 1;
            if (memcmp(t->keys + index * (size_t)t->width, key, bytes) == 0) return index;
        }
    }
    if (!insert) return SIZE_MAX;
    if (t->count >= UINT32_MAX - 1) {
        *failed = 1;
        return SIZE_MAX;
    }
    if (2 * (t->count + 1) > t->slot_capacity && !table_rehash(t, t->slot_capacity ? 2 * t->slot_capacity : 1024)) {
        *failed = 1;
        return SIZE_MAX;
    }
    if (t->count == t->key_capacity) {
        size_t capacity = t->key_capacity ? 2 * t->key_capacity : 1024;
        double *keys = realloc(t->keys, capacity * bytes);
        if (keys == NULL) {
            *failed = 1;
            return SIZE_MAX;
        }
        t->keys = keys;
        t->key_capacity = capacity;
    }
    memcpy(t->keys + t->count * (size_t)t->width, key, bytes);
    size_t at = hash_vector(key, t->width) & (t->slot_capacity - 1);
    while (t->slots[at] != 0) at = (at + 1) & (t->slot_capacity - 1);
    t->slots[at] = (uint32_t)(t->count + 1);
    return t->count++;
}

/* ---- the answers -------------------------------------------------------------------------------------------- */

typedef enum answer_how { HOW_NONE = 0, HOW_FULL, HOW_WARM, HOW_CACHE } answer_how;
static const char *const how_names[] = {"none", "full", "warm", "cache"};

/* One answer: the target vector and what the seed guard and the summary need. */
typedef struct answer {
    double values[MR_BRDF_MAX_VALUES];
    double relative_rmse;
    mr_fit_outcome outcome;
    answer_how how; /* HOW_CACHE for a value found in the cache (whatever found it first) */
} answer;

/* ---- the cache file ------------------------------------------------------------------------------------------ */

typedef struct cache_file {
    const char *path;
    int fd;
    off_t size;
    long truncated;      /* bytes of a torn last line removed */
    vector_table table;  /* the cached source vectors */
    answer *answers;     /* table.count of them */
    size_t answer_capacity;
    long appended;
} cache_file;

typedef struct run_config {
    const mr_brdf_model *source, *target;
    int ns, nt;
    double tolerance, roughness_tolerance;
    mr_remap_options remap;                   /* defaulted; target_values points at target_values below */
    double target_values[MR_BRDF_MAX_VALUES];
    mr_fit_scene_options scene;
    int chain_length;
    int cold;
    int fit_every_shape;
    int share_shapes;                         /* shared shapes apply (direct.h; shapes_shareable) */
    unsigned char shape_slot[MR_BRDF_MAX_VALUES]; /* source slots that may shape the specular lobe */
} run_config;

static mr_status build_header(const run_config *cfg, mr_strbuf *sb) {
    mr_strbuf_printf(sb, "# matremap %s direct-cache\n# from: %s\n# to: %s", mr_version(), cfg->source->name,
                     cfg->target->name);
    mr_strbuf_values(sb, cfg->target, cfg->target_values);
    mr_strbuf_printf(sb, "\n");
    mr_strbuf_remap_lines(sb, cfg->source, cfg->target, &cfg->remap, &cfg->scene, NULL);
    mr_strbuf_printf(sb, "# direct: tolerance=%.17g", cfg->tolerance);
    // Written only when it differs, so that caches made before the option existed still match.
    if (cfg->roughness_tolerance != cfg->tolerance)
        mr_strbuf_printf(sb, " roughness_tolerance=%.17g", cfg->roughness_tolerance);
    mr_strbuf_printf(sb, " start=%s\n", cfg->cold ? "cold" : "warm");
    // The columns: a source column list without its leading comma.
    mr_strbuf columns = {0};
    mr_strbuf_columns(&columns, cfg->source, "");
    mr_strbuf_columns(&columns, cfg->target, "to_");
    if (!columns.failed && columns.text != NULL)
        mr_strbuf_printf(sb, "%s,relative_rmse,outcome,how\n", columns.text + 1);
    sb->failed |= columns.failed;
    free(columns.text);
    return sb->failed ? mr_fail(MR_ERR_NOMEM, "direct remap: out of memory building the cache header") : MR_OK;
}

/* One cache line for the answer `a` of quantised source vector q, into buf (C numeric locale). */
static mr_status format_line(const run_config *cfg, const double *q, const answer *a, char *buf, size_t size,
                             size_t *length) {
    size_t used = 0;
    for (int j = 0; j < cfg->ns + cfg->nt; j++) {
        int n = snprintf(buf + used, size - used, "%.17g,", j < cfg->ns ? q[j] : a->values[j - cfg->ns]);
        if (n < 0 || (size_t)n >= size - used) return mr_fail(MR_ERR_INVALID_ARG, "direct remap: cache line too long");
        used += (size_t)n;
    }
    int n = snprintf(buf + used, size - used, "%.17g,%s,%s\n", a->relative_rmse, mr_fit_outcome_name(a->outcome),
                     how_names[a->how]);
    if (n < 0 || (size_t)n >= size - used) return mr_fail(MR_ERR_INVALID_ARG, "direct remap: cache line too long");
    *length = used + (size_t)n;
    return MR_OK;
}

/* Parse one cache line (without its '\n') into q and *a; MR_ERR_FORMAT naming what is wrong. */
static mr_status parse_line(const run_config *cfg, const char *line, size_t length, double *q, answer *a) {
    size_t at = 0, len = 0;
    const char *field = NULL;
    const int columns = cfg->ns + cfg->nt + 3;
    memset(a, 0, sizeof *a);
    for (int k = 0; k < columns; k++) {
        if (!mr_csv_next_field(line, length, &at, &field, &len))
            return mr_fail(MR_ERR_FORMAT, "the line has %d columns, expected %d", k, columns);
        int ok = 0;
        if (k < cfg->ns)
            ok = mr_csv_parse_double(field, len, &q[k]) && isfinite(q[k]);
        else if (k < cfg->ns + cfg->nt)
            ok = mr_csv_parse_double(field, len, &a->values[k - cfg->ns]) && isfinite(a->values[k - cfg->ns]);
        else if (k == cfg->ns + cfg->nt)
            ok = mr_csv_parse_double(field, len, &a->relative_rmse) && a->relative_rmse >= 0.0;
        else if (k == cfg->ns + cfg->nt + 1) {
            for (int o = 0; o < MR_FIT_OUTCOME_COUNT; o++) {
                const char *name = mr_fit_outcome_name((mr_fit_outcome)o);
                if (strlen(name) == len && memcmp(name, field, len) == 0) {
                    a->outcome = (mr_fit_outcome)o;
                    ok = 1;
                }
            }
        } else {
            ok = (len == 4 && (memcmp(field, "full", 4) == 0 || memcmp(field, "warm", 4) == 0));
        }
        if (!ok)
            return mr_fail(MR_ERR_FORMAT, "column %d: '%.*s' is not a valid value", k + 1, (int)MR_MIN(len, 40),
                           field);
    }
    if (at != SIZE_MAX) return mr_fail(MR_ERR_FORMAT, "the line has more than %d columns", columns);
    double again[MR_BRDF_MAX_VALUES];
    quantise_vector(cfg->source, cfg->tolerance, cfg->roughness_tolerance, q, again, NULL, NULL);
    if (memcmp(again, q, (size_t)cfg->ns * sizeof *q) != 0)
        return mr_fail(MR_ERR_FORMAT, "its source values are not a quantised value of tolerance %.17g (was the file "
                       "edited?)", cfg->tolerance);
    // Its message stands ("its target value alpha = 3 of model 'ggx' is outside [...]"); the caller adds the line.
    if (mr_remap_file_check_values(cfg->target, a->values, "its target") != MR_OK) return MR_ERR_FORMAT;
    a->how = HOW_CACHE;
    return MR_OK;
}

static int cache_add(cache_file *c, const double *q, const answer *a, int *failed) {
    const size_t before = c->table.count;
    const size_t index = table_find(&c->table, q, 1, failed);
    if (index == SIZE_MAX) return 0;
    if (index < before) return 1; // a second line for a value: the first one stands
    if (index >= c->answer_capacity) {
        size_t capacity = c->answer_capacity ? 2 * c->answer_capacity : 1024;
        answer *grown = realloc(c->answers, capacity * sizeof *grown);
        if (grown == NULL) {
            *failed = 1;
            return 0;
        }
        c->answers = grown;
        c->answer_capacity = capacity;
    }
    c->answers[index] = *a;
    return 1;
}

/* Read an existing cache (header checked, lines parsed, a torn last line cut off only once all else checked out,
 * so a refused file is left exactly as it was), or write the header of a new one. C numeric locale. */
static mr_status adopt_cache(const run_config *cfg, const mr_strbuf *header, cache_file *c) {
    char *data = NULL;
    size_t size = 0;
    mr_status status = mr_text_file_read_all(c->fd, c->path, WHAT, &data, &size);
    if (status != MR_OK) return status;
    if (size == 0) { // new, or killed before its header went out
        free(data);
        return mr_text_file_append(c->fd, c->path, WHAT, header->text, header->length, &c->size);
    }
    size_t rows = 0;
    long line_number = 0;
    status = mr_text_file_match_header(c->path, WHAT, "belongs to another remap",
                                       "use another cache file for this configuration, or remove it", data, size,
                                       header->text, header->length, NULL, &rows, &line_number);
    const char *pos = data + rows, *end = data + size;
    while (status == MR_OK && pos < end) {
        const char *nl = memchr(pos, '\n', (size_t)(end - pos));
        line_number++;
        if (nl == NULL) { // a torn last line: a write cut short; everything before it is whole
            c->truncated = (long)(end - pos);
            break;
        }
        double q[MR_BRDF_MAX_VALUES];
        answer a;
        int failed = 0;
        status = parse_line(cfg, pos, (size_t)(nl - pos), q, &a);
        if (status != MR_OK)
            status = mr_fail_context(status, WHAT " '%s': line %ld", c->path, line_number);
        else if (!cache_add(c, q, &a, &failed))
            status = mr_fail(MR_ERR_NOMEM, WHAT " '%s': out of memory at line %ld", c->path, line_number);
        pos = nl + 1;
    }
    free(data);
    if (status == MR_OK && c->truncated > 0) {
        const off_t keep = (off_t)(size - (size_t)c->truncated);
        if (ftruncate(c->fd, keep) != 0) {
            int err = errno;
            return mr_fail(MR_ERR_IO, WHAT " '%s': cannot remove its torn last line: %s", c->path, strerror(err));
        }
        c->size = keep;
    }
    return status;
}

static mr_status open_cache(const run_config *cfg, cache_file *c) {
    mr_strbuf header = {0};
    mr_status status = build_header(cfg, &header);
    if (status == MR_OK) {
        c->fd = open(c->path, O_RDWR | O_APPEND | O_CREAT | O_CLOEXEC, 0666);
        if (c->fd < 0) {
            int err = errno;
            status = mr_fail(MR_ERR_IO, WHAT " '%s': cannot open: %s", c->path, strerror(err));
        }
    }
    struct stat st;
    if (status == MR_OK && (fstat(c->fd, &st) != 0 || !S_ISREG(st.st_mode)))
        status = mr_fail(MR_ERR_INVALID_ARG, WHAT " '%s' is not a regular file", c->path);
    if (status == MR_OK) status = mr_text_file_lock(c->fd, c->path, WHAT);
    if (status == MR_OK) {
        c->size = st.st_size;
        status = adopt_cache(cfg, &header, c);
    }
    free(header.text);
    return status;
}

/* ---- the order: Morton codes, chains ---------------------------------------------------------------------- */

typedef struct ordered {
    uint64_t code[2]; /* Morton codes: of the first slot group, then of the second */
    size_t unique;
} ordered;

static int compare_ordered(const void *a, const void *b) {
    const ordered *x = a, *y = b;
    for (int g = 0; g < 2; g++)
        if (x->code[g] != y->code[g]) return x->code[g] < y->code[g] ? -1 : 1;
    return (x->unique > y->unique) - (x->unique < y->unique);
}

/* Sort the unique values along a Morton curve through their integer coordinates k (count x width): each slot that
 * varies is scaled to `bits` bits over its range and the bits interleaved, most significant first. With `first`
 * (may be NULL: one group), the slots it flags are ordered first and the others only among values equal in those
 * (shared shapes, direct.h: a shape's siblings side by side). Ties (equal codes) keep the order of first
 * appearance. */
static ordered *morton_order(const int64_t *k, size_t count, int width, const unsigned char *first) {
    ordered *order = malloc((count ? count : 1) * sizeof *order);
    if (order == NULL) return NULL;
    int64_t lo[MR_BRDF_MAX_VALUES], hi[MR_BRDF_MAX_VALUES];
    int active[2][MR_BRDF_MAX_VALUES], active_count[2] = {0, 0};
    for (int j = 0; j < width; j++) {
        lo[j] = hi[j] = count ? k[j] : 0;
        for (size_t i = 1; i < count; i++) {
            lo[j] = MR_MIN(lo[j], k[i * (size_t)width + j]);
            hi[j] = MR_MAX(hi[j], k[i * (size_t)width + j]);
        }
        const int g = first != NULL && !first[j];
        if (hi[j] > lo[j]) active[g][active_count[g]++] = j;
    }
    for (size_t i = 0; i < count; i++) {
        for (int g = 0; g < 2; g++) {
            const int bits = active_count[g] ? MR_MIN(21, 63 / active_count[g]) : 0;
            const double top = (double)((1ULL << bits) - 1);
            uint64_t c[MR_BRDF_MAX_VALUES], code = 0;
            for (int a = 0; a < active_count[g]; a++) {
                const int j = active[g][a];
                c[a] = (uint64_t)llround(top * (double)(k[i * (size_t)width + j] - lo[j]) / (double)(hi[j] - lo[j]));
            }
            for (int b = bits - 1; b >= 0; b--)
                for (int a = 0; a < active_count[g]; a++) code = (code << 1) | ((c[a] >> b) & 1u);
            order[i].code[g] = code;
        }
        order[i].unique = i;
    }
    qsort(order, count, sizeof *order, compare_ordered);
    return order;
}

/* ---- the run ---------------------------------------------------------------------------------------------------- */

typedef struct run_state {
    const run_config *cfg;
    const mr_render_plan *plan;
    const mr_direct_options *opts;
    const double *q;          /* unique values, quantised: count x ns */
    const int64_t *k;         /* their integer coordinates */
    size_t count;
    const ordered *order;
    const size_t *chains;     /* the chains with a value to remap (indices: chain c is order[c * length ...]) */
    answer *answers;          /* count; how == HOW_NONE until answered */
    uint64_t *shape_hash;     /* count (with share_shapes): hash of the source's specular render, 0 = not yet */
    cache_file *cache;        /* NULL: none */
    size_t done, hits, full, warm, fallbacks, shared;
    long renders;
    int stop;
    mr_status failure;
    size_t failure_position;  /* the lowest failed position in the order */
    char failure_message[1024];
} run_state;

static double distance2(const int64_t *a, const int64_t *b, int width) {
    double sum = 0.0;
    for (int j = 0; j < width; j++) {
        const double d = (double)(a[j] - b[j]);
        sum += d * d;
    }
    return sum;
}

/* Whether an answer may seed a warm start (direct.h): a converged fit, or an under-resolved one, whose refinement
 * from a neighbour finds the full remap's minimum as well (the lobe is narrower than the pixels, but its error
 * still has a minimum; tests/test_direct.c). */
static int seedable(mr_fit_outcome outcome) {
    return outcome == MR_FIT_CONVERGED || outcome == MR_FIT_UNDER_RESOLVED;
}

/* Whether the guard keeps a warm answer's outcome (direct.h): CONVERGED, or UNDER_RESOLVED from an under-resolved
 * seed. Turning under-resolved from a converged seed is the edge of a glossy region, where the verdict sits on its
 * threshold: that value gets its full remap's verdict, as before. */
static int outcome_kept(mr_fit_outcome outcome, const answer *seed) {
    return outcome == MR_FIT_CONVERGED || (outcome == MR_FIT_UNDER_RESOLVED && seed->outcome == outcome);
}

/* Remap unique value u: in full (seed NULL), warm-started from seed, or (shared) from a shape sibling's answer
 * with its shape as found (direct.h, "Shared shapes": one evaluation of the local refinement). */
static mr_status remap_one(run_state *st, size_t u, const answer *seed, int shared, answer *out, long *renders) {
    const run_config *cfg = st->cfg;
    mr_remap_options o = cfg->remap;
    o.initial_values = seed ? seed->values : NULL;
    if (seed != NULL) o.xtol = fmax(o.xtol, MR_DIRECT_WARM_XTOL);
    if (seed != NULL && shared) o.max_evaluations = 1;
    mr_remap_result r;
    mr_status status = mr_remap(st->plan, cfg->source, st->q + u * (size_t)cfg->ns, cfg->target, &o, &r);
    if (status != MR_OK) return status;
    memcpy(out->values, r.values, sizeof out->values);
    out->relative_rmse = r.relative_rmse;
    out->outcome = r.outcome;
    out->how = seed ? HOW_WARM : HOW_FULL;
    *renders += r.renders;
    return MR_OK;
}

/* Stop the run for a failure at `position` of the order (the lowest position's message is kept). Inside the
 * critical section mr_direct_state. */
static void record_failure(run_state *st, size_t position, mr_status status) {
#pragma omp atomic write
    st->stop = 1;
    if (st->failure == MR_OK || position < st->failure_position) {
        st->failure = status;
        st->failure_position = position;
        snprintf(st->failure_message, sizeof st->failure_message, "%s", mr_last_error());
    }
}

/* Answer unique value `u` (at `position` of the order) from `seed` (NULL: a full remap), append it to the cache and
 * report progress. Runs on a worker thread, in the C numeric locale. */
static void answer_value(run_state *st, size_t position, size_t u, const answer *seed, int shared) {
    const run_config *cfg = st->cfg;
    answer a;
    long renders = 0;
    int fallback = 0;
    mr_status status = remap_one(st, u, seed, shared, &a, &renders);
    if (status == MR_OK && seed != NULL &&
        !(outcome_kept(a.outcome, seed) &&
          a.relative_rmse <= MR_DIRECT_GUARD_GAIN * seed->relative_rmse + MR_DIRECT_GUARD_FLOOR)) {
        fallback = 1; // the guard (direct.h): redo it in full
        shared = 0;
        status = remap_one(st, u, NULL, 0, &a, &renders);
    }
    char line[MR_BRDF_MAX_VALUES * 2 * 32 + 128];
    size_t length = 0;
    if (status == MR_OK && st->cache != NULL)
        status = format_line(cfg, st->q + u * (size_t)cfg->ns, &a, line, sizeof line, &length);
#pragma omp critical(mr_direct_state)
    {
        if (status == MR_OK && st->cache != NULL)
            status = mr_text_file_append(st->cache->fd, st->cache->path, WHAT, line, length, &st->cache->size);
        if (status == MR_OK) {
            st->answers[u] = a;
            st->done++;
            st->renders += renders;
            st->fallbacks += (size_t)fallback;
            st->shared += (size_t)shared;
            if (a.how == HOW_WARM)
                st->warm++;
            else
                st->full++;
            if (st->cache != NULL) st->cache->appended++;
            if (st->opts->progress != NULL) {
                mr_direct_progress p = {st->done, st->count, st->hits};
                st->opts->progress(&p, st->opts->progress_user);
            }
        } else {
            record_failure(st, position, status);
        }
    }
}

/* fail_run outside the critical section. */
static void fail_run(run_state *st, size_t position, mr_status status) {
#pragma omp critical(mr_direct_state)
    record_failure(st, position, status);
}

/* The hash of unique value u's source render of the specular lobe alone (its bits, FNV-1a 64, never 0), computed
 * once: shape siblings (direct.h) must have bit-identical ones. 0 if the render failed (*status says why). */
static uint64_t shape_hash(run_state *st, size_t u, mr_image *images[2], mr_status *status) {
    if (st->shape_hash[u] != 0) return st->shape_hash[u];
    const run_config *cfg = st->cfg;
    const mr_scene *scene = mr_render_plan_scene(st->plan);
    for (int i = 0; i < 2 && *status == MR_OK; i++)
        if (images[i] == NULL) *status = mr_image_create(scene->width, scene->height, 3, &images[i]);
    if (*status == MR_OK)
        *status = mr_render_components_into_threads(st->plan, 0, cfg->source, st->q + u * (size_t)cfg->ns, images[0],
                                                    images[1]);
    if (*status != MR_OK) return 0;
    uint64_t h = 0xcbf29ce484222325ULL;
    const unsigned char *bytes = (const unsigned char *)images[1]->pixels;
    const size_t size = (size_t)scene->width * (size_t)scene->height * 3 * sizeof(float);
    for (size_t i = 0; i < size; i++) h = (h ^ bytes[i]) * 0x100000001b3ULL;
    st->shape_hash[u] = h | 1u;
    return st->shape_hash[u];
}

/* Unique value u's shape sibling at position p of the chain [begin, end) (direct.h, "Shared shapes"): the
 * earliest answered value of the chain with a seedable outcome, the same source values in every slot that may
 * shape the specular lobe and a bit-identical specular render; NULL if none. */
static const answer *shape_sibling(run_state *st, size_t begin, size_t end, size_t p, mr_image *images[2],
                                   mr_status *status) {
    const run_config *cfg = st->cfg;
    const int ns = cfg->ns;
    const size_t u = st->order[p].unique;
    const double *qu = st->q + u * (size_t)ns;
    for (size_t s = begin; s < end && *status == MR_OK; s++) {
        const size_t v = st->order[s].unique;
        if (s == p || st->answers[v].how == HOW_NONE || !seedable(st->answers[v].outcome)) continue;
        const double *qv = st->q + v * (size_t)ns;
        int same = 1;
        for (int j = 0; j < ns && same; j++) same = !cfg->shape_slot[j] || memcmp(&qu[j], &qv[j], sizeof *qu) == 0;
        if (!same) continue;
        const uint64_t hu = shape_hash(st, u, images, status), hv = shape_hash(st, v, images, status);
        if (*status == MR_OK && hu == hv) return &st->answers[v];
    }
    return NULL;
}

/* One chain: positions [begin, end) of the order, in order (direct.h). */
static void run_chain(run_state *st, size_t begin, size_t end) {
    const int ns = st->cfg->ns;
    mr_image *images[2] = {NULL, NULL}; /* shape_hash's renders */
    for (size_t p = begin; p < end; p++) {
        int stopping;
#pragma omp atomic read
        stopping = st->stop;
        if (stopping) return;
        const size_t u = st->order[p].unique;
        if (st->answers[u].how != HOW_NONE) continue; // a cache hit
        // A shape sibling, else the nearest value of the chain already answered with a seedable outcome (a warm
        // start from an unreachable or at-bound fit would only fall back).
        mr_status status = MR_OK;
        const answer *seed = st->cfg->share_shapes ? shape_sibling(st, begin, end, p, images, &status) : NULL;
        const int shared = seed != NULL;
        if (status != MR_OK) {
            fail_run(st, p, status);
            break;
        }
        double best = HUGE_VAL;
        for (size_t s = begin; s < end && !st->cfg->cold && !shared; s++) {
            const size_t v = st->order[s].unique;
            if (s == p || st->answers[v].how == HOW_NONE || !seedable(st->answers[v].outcome)) continue;
            const double d = distance2(st->k + u * (size_t)ns, st->k + v * (size_t)ns, ns);
            if (d < best) {
                best = d;
                seed = &st->answers[v];
            }
        }
        answer_value(st, p, u, seed, shared);
    }
    mr_image_free(images[0]);
    mr_image_free(images[1]);
}

/* Chain `item` of st->chains (a worker thread of mr_remap_run_parallel). */
static void run_item(void *ctx, long item) {
    run_state *st = ctx;
    const size_t length = (size_t)st->cfg->chain_length, chain = st->chains[item];
    run_chain(st, chain * length, MR_MIN((chain + 1) * length, st->count));
}

/* ---- the call ------------------------------------------------------------------------------------------------ */

/* Whether shapes may be shared (direct.h, "Shared shapes"): an AUTO fit by the built-in renderers, warm starts on,
 * whose fitted nonlinear target parameters (declared NONLINEAR, not held, not fixed by the model unless freed) all
 * shape the specular lobe, so that AUTO fits them, lobe by lobe, against the source's specular render alone. */
static int shapes_shareable(const run_config *cfg) {
    const mr_remap_options *r = &cfg->remap;
    if (cfg->cold || cfg->fit_every_shape || r->strategy != MR_REMAP_AUTO ||
        !mr_renderer_is_builtin(r->target_renderer) || !mr_renderer_is_builtin(r->source_renderer))
        return 0;
    int fitted = 0;
    for (int i = 0; i < cfg->target->param_count; i++) {
        const mr_brdf_param *p = &cfg->target->params[i];
        const unsigned bit = i < 32 ? 1u << i : 0u;
        const int held = (r->held & bit) || ((p->flags & MR_PARAM_FIT_FIXED) && !(r->freed & bit));
        if (p->role != MR_PARAM_NONLINEAR || held) continue;
        if (p->lobe != MR_LOBE_SPECULAR) return 0;
        fitted++;
    }
    return fitted > 0;
}

static mr_status configure(const mr_brdf_model *source, const mr_brdf_model *target, const mr_direct_options *opts,
                           run_config *cfg) {
    memset(cfg, 0, sizeof *cfg);
    cfg->source = source;
    cfg->target = target;
    cfg->ns = mr_brdf_value_count(source);
    cfg->nt = mr_brdf_value_count(target);
    if (cfg->ns > MR_BRDF_MAX_VALUES || cfg->nt > MR_BRDF_MAX_VALUES)
        return mr_fail(MR_ERR_INVALID_ARG, "direct remap: a model has more than %d values", MR_BRDF_MAX_VALUES);
    cfg->tolerance = opts->tolerance;
    cfg->roughness_tolerance = opts->roughness_tolerance;
    mr_status status = check_tolerance(&cfg->tolerance);
    if (status == MR_OK) status = check_roughness_tolerance(cfg->tolerance, &cfg->roughness_tolerance);
    if (status != MR_OK) return status;
    if (opts->threads < 0 || opts->chain_length < 0)
        return mr_fail(MR_ERR_INVALID_ARG, "direct remap: threads %d and chain_length %d: expected >= 0 (0: default)",
                       opts->threads, opts->chain_length);
    cfg->chain_length = opts->chain_length ? opts->chain_length : MR_DIRECT_DEFAULT_CHAIN;
    cfg->cold = opts->cold != 0;
    cfg->fit_every_shape = opts->fit_every_shape != 0;
    // The remap options as mr_remap reads them, zeros as its defaults, so that {0} and the defaults are one
    // configuration (and one cache header).
    const mr_remap_options d = mr_remap_options_default();
    mr_remap_options r = opts->remap;
    if (r.initial_values != NULL || r.threads != 0)
        return mr_fail(MR_ERR_INVALID_ARG, "direct remap: remap.initial_values and remap.threads are set by the "
                       "direct remap: leave them NULL and 0");
    if (r.max_evaluations <= 0) r.max_evaluations = d.max_evaluations;
    if (!(r.xtol > 0.0)) r.xtol = d.xtol;
    if (r.starts <= 0) r.starts = d.starts;
    if (r.seed == 0) r.seed = d.seed;
    status = mr_remap_file_check_options("direct remap", &r, &opts->scene);
    if (status != MR_OK) return status;
    if (r.target_values != NULL)
        memcpy(cfg->target_values, r.target_values, (size_t)cfg->nt * sizeof(double));
    else
        mr_brdf_default_values(target, cfg->target_values);
    status = mr_remap_file_check_values(target, cfg->target_values, "direct remap: target");
    if (status != MR_OK) return status;
    r.target_values = cfg->target_values;
    cfg->remap = r;
    cfg->scene = opts->scene;
    cfg->share_shapes = shapes_shareable(cfg);
    for (int i = 0, slot = 0; i < source->param_count; slot += source->params[i].channels, i++)
        for (int c = 0; c < source->params[i].channels; c++)
            cfg->shape_slot[slot + c] = source->params[i].lobe != MR_LOBE_DIFFUSE;
    return MR_OK;
}

/* The distinct quantised values of the texels: q and k (count x ns, first appearance first) and each texel's
 * index into them. */
typedef struct unique_set {
    vector_table table; /* its keys are the quantised values */
    int64_t *k;
    size_t k_capacity;
    uint32_t *of_texel;
    size_t clamped;
} unique_set;

static mr_status deduplicate(const run_config *cfg, const double *in, size_t n, unique_set *u) {
    const int ns = cfg->ns;
    u->table.width = ns;
    u->of_texel = malloc(n * sizeof *u->of_texel);
    if (u->of_texel == NULL) return mr_fail(MR_ERR_NOMEM, "direct remap: out of memory for %zu texels", n);
    for (size_t i = 0; i < n; i++) {
        double q[MR_BRDF_MAX_VALUES];
        int64_t k[MR_BRDF_MAX_VALUES];
        int clamped = 0, failed = 0;
        const int bad =
            quantise_vector(cfg->source, cfg->tolerance, cfg->roughness_tolerance, in + i * (size_t)ns, q, k, &clamped);
        if (bad >= 0) {
            char name[64];
            return mr_fail(MR_ERR_INVALID_ARG, "direct remap: texel %zu: %s = %g: expected a finite value", i,
                           slot_name(cfg->source, bad, name, sizeof name), in[i * (size_t)ns + (size_t)bad]);
        }
        u->clamped += (size_t)clamped;
        const size_t before = u->table.count;
        const size_t index = table_find(&u->table, q, 1, &failed);
        if (failed) return mr_fail(MR_ERR_NOMEM, "direct remap: out of memory for %zu unique values", before);
        if (index == before) { // new: keep its coordinates
            if (u->table.count > u->k_capacity) {
                size_t capacity = u->k_capacity ? 2 * u->k_capacity : 1024;
                int64_t *grown = realloc(u->k, capacity * (size_t)ns * sizeof *grown);
                if (grown == NULL) return mr_fail(MR_ERR_NOMEM, "direct remap: out of memory for unique values");
                u->k = grown;
                u->k_capacity = capacity;
            }
            memcpy(u->k + index * (size_t)ns, k, (size_t)ns * sizeof *k);
        }
        u->of_texel[i] = (uint32_t)index;
    }
    return MR_OK;
}

mr_status mr_direct_remap(const mr_brdf_model *source, const mr_brdf_model *target, const double *in, size_t n,
                          const mr_direct_options *opts, double *out, mr_fit_outcome *outcomes,
                          mr_direct_summary *summary) {
    const double start = mr_now_seconds();
    mr_direct_options defaults;
    memset(&defaults, 0, sizeof defaults);
    if (opts == NULL) opts = &defaults;
    if (source == NULL || target == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "direct remap: NULL source or target model");
    if (n > 0 && (in == NULL || out == NULL))
        return mr_fail(MR_ERR_INVALID_ARG, "direct remap: NULL input or output values for %zu texels", n);
    if (n > (size_t)UINT32_MAX - 1)
        return mr_fail(MR_ERR_INVALID_ARG, "direct remap: %zu texels: at most %u at once", n, UINT32_MAX - 1);
    run_config cfg;
    mr_status status = configure(source, target, opts, &cfg);
    if (status != MR_OK) return status;
    if (summary != NULL) memset(summary, 0, sizeof *summary);
    if (n == 0) return MR_OK;

    unique_set uniques;
    memset(&uniques, 0, sizeof uniques);
    cache_file cache;
    memset(&cache, 0, sizeof cache);
    cache.fd = -1;
    cache.path = opts->cache_path;
    cache.table.width = cfg.ns;
    run_state st;
    memset(&st, 0, sizeof st);
    ordered *order = NULL;
    size_t *chains = NULL;
    mr_render_plan *plan = NULL;
    int threads = 1;

    status = deduplicate(&cfg, in, n, &uniques);
    const size_t count = uniques.table.count;
    if (status == MR_OK) {
        st.answers = calloc(count, sizeof *st.answers);
        st.shape_hash = cfg.share_shapes ? calloc(count, sizeof *st.shape_hash) : NULL;
        order = morton_order(uniques.k, count, cfg.ns, cfg.share_shapes ? cfg.shape_slot : NULL);
        if (st.answers == NULL || order == NULL || (cfg.share_shapes && st.shape_hash == NULL))
            status = mr_fail(MR_ERR_NOMEM, "direct remap: out of memory");
    }
    if (status == MR_OK && cache.path != NULL) {
        mr_c_numeric cn;
        status = mr_c_numeric_enter(&cn, "direct remap");
        if (status == MR_OK) {
            status = open_cache(&cfg, &cache);
            mr_c_numeric_leave(&cn);
        }
        for (size_t u = 0; status == MR_OK && u < count; u++) {
            const size_t hit = table_find(&cache.table, uniques.table.keys + u * (size_t)cfg.ns, 0, NULL);
            if (hit == SIZE_MAX) continue;
            st.answers[u] = cache.answers[hit];
            st.hits++;
        }
    }
    size_t chain_count = 0;
    if (status == MR_OK) {
        // Only chains with a value to remap run; never more threads than those.
        const size_t length = (size_t)cfg.chain_length, total = (count + length - 1) / length;
        chains = malloc((total ? total : 1) * sizeof *chains);
        if (chains == NULL) status = mr_fail(MR_ERR_NOMEM, "direct remap: out of memory");
        for (size_t c = 0; status == MR_OK && c < total; c++)
            for (size_t p = c * length; p < MR_MIN((c + 1) * length, count); p++)
                if (st.answers[order[p].unique].how == HOW_NONE) {
                    chains[chain_count++] = c;
                    break;
                }
#ifdef _OPENMP
        threads = mr_auto_threads(opts->threads, (long)chain_count, 2); // a team from two chains with work on
#endif
        threads = (int)MR_MAX(1, MR_MIN((size_t)threads, chain_count));
    }
    if (status == MR_OK && chain_count > 0) {
        const mr_scene scene = mr_remap_file_scene(&cfg.scene);
        status = mr_render_plan_create(&scene, &plan);
    }
    if (status == MR_OK) {
        st.cfg = &cfg;
        st.plan = plan;
        st.opts = opts;
        st.q = uniques.table.keys;
        st.k = uniques.k;
        st.count = count;
        st.order = order;
        st.cache = cache.path != NULL ? &cache : NULL;
        st.done = st.hits;
        st.failure = MR_OK;
        if (st.hits > 0 && opts->progress != NULL) {
            mr_direct_progress p = {st.done, st.count, st.hits};
            opts->progress(&p, opts->progress_user);
        }
        st.chains = chains;
        if (chain_count > 0)
            status = mr_remap_run_parallel(threads, (long)chain_count, &st.stop, run_item, &st, "direct remap");
        if (status == MR_OK && st.failure != MR_OK) status = mr_fail(st.failure, "%s", st.failure_message);
    }
    if (status == MR_OK && cache.fd >= 0 && cache.appended > 0 && fsync(cache.fd) != 0) {
        int err = errno;
        status = mr_fail(MR_ERR_IO, WHAT " '%s': cannot flush: %s", cache.path, strerror(err));
    }
    if (status == MR_OK) {
        for (size_t i = 0; i < n; i++) {
            const answer *a = &st.answers[uniques.of_texel[i]];
            memcpy(out + i * (size_t)cfg.nt, a->values, (size_t)cfg.nt * sizeof *out);
            // A tied parameter takes the texel's own source value, not its quantised one: the grid of the
            // tolerance need not hold the source's values (at 6/255 an IOR of 1.5 becomes 1.5059,
            // a metallic of 1 rounds to 0.988), and a tie promises the source's value (brdf.h).
            unsigned caller_held = cfg.remap.held;
            mr_brdf_apply_ties(source, in + i * (size_t)cfg.ns, target, &cfg.remap.ties, out + i * (size_t)cfg.nt,
                               &caller_held);
            if (outcomes != NULL) outcomes[i] = a->outcome;
        }
        if (summary != NULL) {
            summary->texels = n;
            summary->clamped = uniques.clamped;
            summary->unique = count;
            summary->cache_hits = st.hits;
            summary->full = st.full;
            summary->warm = st.warm;
            summary->fallbacks = st.fallbacks;
            summary->shared_shapes = st.shared;
            summary->remaps = st.full + st.warm + st.fallbacks;
            for (size_t u = 0; u < count; u++) summary->outcomes[st.answers[u].outcome]++;
            summary->renders = st.renders;
            summary->threads = chain_count > 0 ? threads : 0;
            summary->seconds = mr_now_seconds() - start;
        }
    }
    if (cache.fd >= 0) close(cache.fd); // releases the lock
    mr_render_plan_free(plan);
    table_free(&cache.table);
    free(cache.answers);
    table_free(&uniques.table);
    free(uniques.k);
    free(uniques.of_texel);
    free(st.answers);
    free(st.shape_hash);
    free(order);
    free(chains);
    return status;
}
