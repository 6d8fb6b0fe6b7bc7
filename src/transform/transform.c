/*
 * transform.c — the transform registry, instances, and batched application with repeated values evaluated once
 * (contract in transform.h). The kinds live in their own files (workflow_kinds.c).
 */
#include "transform/transform.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "brdf/brdf.h"
#include "mr_internal.h"
#include "nn/mlp.h"

extern const mr_transform_kind mr_transform_spec2metal_weighted, mr_transform_spec2metal_mean,
    mr_transform_spec2metal_khronos, mr_transform_spec2metal_mlp, mr_transform_spec2metal_extension,
    mr_transform_metal2spec_eq2, mr_transform_metal2spec_khronos, mr_transform_paper_spec2metal_weighted,
    mr_transform_paper_spec2metal_mean, mr_transform_paper_spec2metal_mlp, mr_transform_paper_metal2spec_eq2;

/* A pair's first kind is its default. */
static const mr_transform_kind *const registry[] = {
    &mr_transform_spec2metal_weighted,
    &mr_transform_spec2metal_mlp,
    &mr_transform_spec2metal_mean,
    &mr_transform_spec2metal_khronos,
    &mr_transform_spec2metal_extension,
    &mr_transform_metal2spec_eq2,
    &mr_transform_metal2spec_khronos,
    &mr_transform_paper_spec2metal_weighted,
    &mr_transform_paper_spec2metal_mlp,
    &mr_transform_paper_spec2metal_mean,
    &mr_transform_paper_metal2spec_eq2,
    NULL,
};

const mr_transform_kind *const *mr_transforms(void) { return registry; }

const mr_transform_kind *mr_transform_find(const char *source, const char *target, const char *name) {
    if (source == NULL || target == NULL) {
        mr_fail(MR_ERR_INVALID_ARG, "transform: NULL source or target model");
        return NULL;
    }
    char list[512] = "";
    for (const mr_transform_kind *const *k = registry; *k != NULL; k++) {
        if (strcmp((*k)->source, source) != 0 || strcmp((*k)->target, target) != 0) continue;
        if (name == NULL || strcmp((*k)->name, name) == 0) return *k;
        snprintf(list + strlen(list), sizeof list - strlen(list), "%s%s", list[0] ? ", " : "", (*k)->name);
    }
    if (list[0] != '\0') {
        mr_fail(MR_ERR_INVALID_ARG, "transform '%s' from %s to %s: unknown (valid: %s)", name, source, target, list);
        return NULL;
    }
    for (const mr_transform_kind *const *k = registry; *k != NULL; k++) {
        char pair[128];
        snprintf(pair, sizeof pair, "%s -> %s", (*k)->source, (*k)->target);
        if (strstr(list, pair) == NULL)
            snprintf(list + strlen(list), sizeof list - strlen(list), "%s%s", list[0] ? ", " : "", pair);
    }
    mr_fail(MR_ERR_INVALID_ARG, "no transform from %s to %s (pairs with transforms: %s)", source, target, list);
    return NULL;
}

static int slot_index(const mr_transform_slot *slots, int count, const char *name) {
    for (int i = 0; name != NULL && i < count; i++)
        if (strcmp(slots[i].name, name) == 0) return i;
    return -1;
}

int mr_transform_input_index(const mr_transform_kind *kind, const char *name) {
    return kind ? slot_index(kind->inputs, kind->input_count, name) : -1;
}

int mr_transform_output_index(const mr_transform_kind *kind, const char *name) {
    return kind ? slot_index(kind->outputs, kind->output_count, name) : -1;
}

/* One slot per parameter of `model`, in table order; 0 if it has more than a kind may have. */
static int model_slots(const mr_brdf_model *model, mr_transform_slot *slots) {
    if (model->param_count > MR_TRANSFORM_MAX_SLOTS) return 0;
    for (int p = 0; p < model->param_count; p++) {
        const mr_brdf_param *q = &model->params[p];
        slots[p] = (mr_transform_slot){q->name, q->channels, q->min_value, q->max_value, q->min_value,
                                       MR_SLOT_OPTIONAL, 0.0, -1};
    }
    return 1;
}

static mr_status config_is_state(const mr_transform_kind *kind, const mr_transform_options *opts, void **state) {
    (void)opts;
    *state = (void *)kind->config;
    return MR_OK;
}

mr_status mr_transform_model_kind_init(mr_transform_model_kind *mk, const mr_brdf_model *source,
                                       const mr_brdf_model *target, const char *name, const char *summary,
                                       unsigned flags, const void *config,
                                       mr_status (*apply)(const mr_transform *t, const mr_transform_batch *b)) {
    if (mk == NULL || source == NULL || target == NULL || apply == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "transform kind: NULL argument");
    if (!model_slots(source, mk->inputs) || !model_slots(target, mk->outputs))
        return mr_fail(MR_ERR_INVALID_ARG, "transform %s: %s or %s has more than %d parameters", name, source->name,
                       target->name, MR_TRANSFORM_MAX_SLOTS);
    mr_transform_kind *k = &mk->kind;
    *k = (mr_transform_kind){0};
    k->name = name;
    k->summary = summary;
    k->source = source->name;
    k->target = target->name;
    k->input_count = source->param_count;
    k->inputs = mk->inputs;
    k->output_count = target->param_count;
    k->outputs = mk->outputs;
    k->flags = flags;
    k->config = config;
    k->create = config_is_state;
    k->apply = apply;
    return MR_OK;
}

/* ---- instances ---------------------------------------------------------------------------------------------- */

#define NETWORK_FILE "spec2metal.mlp"

struct mr_transform {
    const mr_transform_kind *kind;
    mr_transform_options opts;
    mr_mlp *owned_network;       /* the installed network, when opts.network was NULL */
    char network_path[4096 + 64];
    void *state;
};

mr_status mr_transform_create(const mr_transform_kind *kind, const mr_transform_options *opts, mr_transform **out) {
    if (kind == NULL || out == NULL) return mr_fail(MR_ERR_INVALID_ARG, "transform: NULL kind or output");
    *out = NULL;
    mr_transform_options o = opts ? *opts : (mr_transform_options){0};
    const char *name = kind->name;
    if (o.dielectric_f0 == 0.0) o.dielectric_f0 = MR_WF_F0_GLTF;
    if (o.eps == 0.0) o.eps = MR_WF_DEFAULT_EPS;
    if (!(o.dielectric_f0 > 0.0 && o.dielectric_f0 < 1.0))
        return mr_fail(MR_ERR_INVALID_ARG, "transform %s: dielectric_f0 %g: expected a value in (0, 1)", name,
                       o.dielectric_f0);
    if (!(o.eps > 0.0 && o.eps < 1.0))
        return mr_fail(MR_ERR_INVALID_ARG, "transform %s: eps %g: expected a value in (0, 1)", name, o.eps);
    if (o.threads < 0 || o.threads > 1024)
        return mr_fail(MR_ERR_INVALID_ARG, "transform %s: threads %d: expected 0 (automatic) .. 1024", name,
                       o.threads);
    if (!(kind->flags & MR_TRANSFORM_USES_F0) && opts != NULL && opts->dielectric_f0 != 0.0)
        return mr_fail(MR_ERR_INVALID_ARG, "transform %s: takes no dielectric F0 (%g given)", name,
                       opts->dielectric_f0);
    if (!(kind->flags & MR_TRANSFORM_NEEDS_NETWORK) && o.network != NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "transform %s: takes no network", name);
    mr_transform *t = calloc(1, sizeof *t);
    if (t == NULL) return mr_fail(MR_ERR_NOMEM, "transform %s: out of memory", name);
    t->kind = kind;
    mr_status status = MR_OK;
    if ((kind->flags & MR_TRANSFORM_NEEDS_NETWORK) && o.network == NULL) {
        // $MATREMAP_WEIGHTS, else the installed network.
        const char *env = getenv("MATREMAP_WEIGHTS");
        if (env != NULL && env[0] != '\0') {
            snprintf(t->network_path, sizeof t->network_path, "%s", env);
            status = mr_mlp_read(t->network_path, &t->owned_network);
            if (status != MR_OK) mr_fail_context(status, "transform %s: the network given by MATREMAP_WEIGHTS", name);
        } else {
            status = mr_data_path(NETWORK_FILE, t->network_path, sizeof t->network_path);
            if (status != MR_OK) mr_fail_context(status, "transform %s: no network", name);
            if (status == MR_OK) status = mr_mlp_read(t->network_path, &t->owned_network); // its errors name the file
        }
        o.network = t->owned_network;
    }
    t->opts = o;
    if (status == MR_OK && kind->create != NULL) status = kind->create(kind, &t->opts, &t->state);
    if (status != MR_OK) {
        mr_transform_free(t);
        return status;
    }
    *out = t;
    return MR_OK;
}

void mr_transform_free(mr_transform *t) {
    if (t == NULL) return;
    if (t->kind->destroy != NULL) t->kind->destroy(t->state);
    mr_mlp_free(t->owned_network);
    free(t);
}

const mr_transform_kind *mr_transform_kind_of(const mr_transform *t) { return t ? t->kind : NULL; }
const mr_transform_options *mr_transform_options_of(const mr_transform *t) { return t ? &t->opts : NULL; }
const char *mr_transform_network_path(const mr_transform *t) {
    return t && t->owned_network ? t->network_path : "";
}
void *mr_transform_state(const mr_transform *t) { return t ? t->state : NULL; }

/* ---- application -------------------------------------------------------------------------------------------- */

/* Texels a PER_TEXEL kind deduplicates together: the hash table and compact planes of one block fit in L2. */
#define BLOCK 65536
/* The first PROBE texels of a block decide: mostly distinct (noise, float data) -> no hashing for that block. */
#define PROBE 4096
#define MAX_KEY (3 * MR_TRANSFORM_MAX_SLOTS)

/* The bits of texel i's input values, slot after slot (constant-size copies: this runs once per texel). */
static inline int texel_key(const mr_transform_kind *kind, const mr_transform_batch *b, size_t i, uint32_t *key) {
    int length = 0;
    for (int s = 0; s < kind->input_count; s++) {
        if (kind->inputs[s].channels == 3) {
            memcpy(key + length, b->in[s] + 3 * i, 3 * sizeof *key);
            length += 3;
        } else {
            memcpy(key + length, b->in[s] + i, sizeof *key);
            length += 1;
        }
    }
    return length;
}

static inline int same_key(const uint32_t *a, const uint32_t *b, int length) {
    uint32_t differ = 0;
    for (int k = 0; k < length; k++) differ |= a[k] ^ b[k];
    return differ == 0;
}

/* The sub-batch of texels [start, start + count) of b. */
static mr_transform_batch sub_batch(const mr_transform_kind *kind, const mr_transform_batch *b, size_t start,
                                    size_t count) {
    mr_transform_batch s = *b;
    s.n = count;
    for (int i = 0; i < kind->input_count; i++) s.in[i] = b->in[i] + (size_t)kind->inputs[i].channels * start;
    for (int j = 0; j < kind->output_count; j++) s.out[j] = b->out[j] + (size_t)kind->outputs[j].channels * start;
    s.flags = b->flags + start;
    return s;
}

typedef struct dedupe_work {
    uint32_t *table;   /* 2 * BLOCK slots: 1 + row, 0 = empty */
    uint32_t *first;   /* row -> block texel of its first occurrence */
    uint32_t *row_of;  /* block texel -> row */
    float *planes;     /* compact inputs then outputs, per slot, BLOCK * channels each */
    uint8_t *flags;
} dedupe_work;

static size_t total_channels(const mr_transform_slot *slots, int count) {
    size_t c = 0;
    for (int i = 0; i < count; i++) c += (size_t)slots[i].channels;
    return c;
}

static int dedupe_work_alloc(const mr_transform_kind *kind, dedupe_work *w) {
    size_t channels = total_channels(kind->inputs, kind->input_count) +
                      total_channels(kind->outputs, kind->output_count);
    w->table = malloc(2 * BLOCK * sizeof *w->table);
    w->first = malloc(BLOCK * sizeof *w->first);
    w->row_of = malloc(BLOCK * sizeof *w->row_of);
    w->planes = malloc(BLOCK * channels * sizeof *w->planes);
    w->flags = malloc(BLOCK);
    return w->table && w->first && w->row_of && w->planes && w->flags;
}

static void dedupe_work_free(dedupe_work *w) {
    free(w->table);
    free(w->first);
    free(w->row_of);
    free(w->planes);
    free(w->flags);
}

/* One block of a PER_TEXEL kind: its distinct input values gathered, converted once, answers copied back. A block
 * that is mostly distinct is converted as it is. */
static mr_status dedupe_block(const mr_transform *t, const mr_transform_batch *block, dedupe_work *w) {
    const mr_transform_kind *kind = t->kind;
    const size_t n = block->n, mask = 2 * BLOCK - 1;
    memset(w->table, 0, 2 * BLOCK * sizeof *w->table);
    size_t rows = 0;
    uint32_t key[MAX_KEY], other[MAX_KEY];
    for (size_t i = 0; i < n; i++) {
        if (i == PROBE && 4 * rows > 3 * PROBE) return kind->apply(t, block);
        int length = texel_key(kind, block, i, key);
        size_t h = mr_hash_words(key, length) & mask;
        for (; w->table[h] != 0; h = (h + 1) & mask) {
            texel_key(kind, block, w->first[w->table[h] - 1], other);
            if (same_key(key, other, length)) break;
        }
        if (w->table[h] == 0) {
            w->table[h] = (uint32_t)(rows + 1);
            w->first[rows++] = (uint32_t)i;
        }
        w->row_of[i] = w->table[h] - 1;
    }
    // Compact planes: the distinct rows' inputs, and room for their outputs.
    mr_transform_batch c = *block;
    c.n = rows;
    c.flags = w->flags;
    float *p = w->planes;
    for (int s = 0; s < kind->input_count; s++) {
        const size_t ch = (size_t)kind->inputs[s].channels;
        if (ch == 1)
            for (size_t r = 0; r < rows; r++) p[r] = block->in[s][w->first[r]];
        else
            for (size_t r = 0; r < rows; r++) memcpy(p + 3 * r, block->in[s] + 3 * (size_t)w->first[r], 3 * sizeof *p);
        c.in[s] = p;
        p += ch * BLOCK;
    }
    for (int s = 0; s < kind->output_count; s++) {
        c.out[s] = p;
        p += (size_t)kind->outputs[s].channels * BLOCK;
    }
    mr_status status = kind->apply(t, &c);
    if (status != MR_OK) return status;
    for (int s = 0; s < kind->output_count; s++) {
        const size_t ch = (size_t)kind->outputs[s].channels;
        float *dst = block->out[s];
        const float *src = c.out[s];
        if (ch == 1)
            for (size_t i = 0; i < n; i++) dst[i] = src[w->row_of[i]];
        else
            for (size_t i = 0; i < n; i++) memcpy(dst + 3 * i, src + 3 * (size_t)w->row_of[i], 3 * sizeof *dst);
    }
    for (size_t i = 0; i < n; i++) block->flags[i] = w->flags[w->row_of[i]];
    return MR_OK;
}

static mr_status apply_deduplicated(const mr_transform *t, const mr_transform_batch *b) {
    const size_t blocks = (b->n + BLOCK - 1) / BLOCK;
    const int threads = mr_auto_threads(b->threads > 0 ? b->threads : t->opts.threads, (long)MR_MIN(b->n, 1u << 30),
                                        MR_WF_PARALLEL_TEXELS);
    const int team = (size_t)threads < blocks ? threads : (int)blocks;
    mr_status status = MR_OK;
    char message[1024] = "";
#pragma omp parallel num_threads(team) if (team > 1)
    {
        dedupe_work w;
        mr_status mine = dedupe_work_alloc(t->kind, &w) ? MR_OK : MR_ERR_NOMEM;
#pragma omp for schedule(dynamic, 1)
        for (long k = 0; k < (long)blocks; k++) {
            if (mine != MR_OK) continue;
            size_t start = (size_t)k * BLOCK;
            mr_transform_batch block = sub_batch(t->kind, b, start, MR_MIN(BLOCK, b->n - start));
            block.threads = 1;
            mine = dedupe_block(t, &block, &w);
        }
        dedupe_work_free(&w);
        if (mine != MR_OK) {
#pragma omp critical(mr_transform_failure)
            if (status == MR_OK) {
                status = mine;
                snprintf(message, sizeof message, "%s", mine == MR_ERR_NOMEM ? "out of memory" : mr_last_error());
            }
        }
    }
    return status == MR_OK ? MR_OK : mr_fail(status, "transform %s: %s", t->kind->name, message);
}

mr_status mr_transform_apply(const mr_transform *t, const mr_transform_batch *b) {
    if (t == NULL || b == NULL) return mr_fail(MR_ERR_INVALID_ARG, "transform: NULL transform or batch");
    if (b->n == 0) return MR_OK;
    const mr_transform_kind *kind = t->kind;
    for (int i = 0; i < kind->input_count; i++)
        if (b->in[i] == NULL && !(kind->inputs[i].flags & MR_SLOT_OPTIONAL))
            return mr_fail(MR_ERR_INVALID_ARG, "transform %s: input plane '%s' is NULL", kind->name,
                           kind->inputs[i].name);
    // Scratch for the planes the caller left out: defaults for optional inputs, room for unwanted outputs.
    mr_transform_batch full = *b;
    float *scratch[2 * MR_TRANSFORM_MAX_SLOTS] = {NULL};
    uint8_t *flags = NULL;
    int count = 0;
    mr_status status = MR_OK;
    for (int i = 0; i < kind->input_count && status == MR_OK; i++) {
        if (b->in[i] != NULL) continue;
        const mr_transform_slot *slot = &kind->inputs[i];
        const mr_brdf_model *model = mr_brdf_find(kind->source);
        int param = model ? mr_brdf_param_index(model, slot->name) : -1;
        double value = param >= 0 ? model->params[param].default_value : slot->min;
        size_t size = b->n * (size_t)slot->channels;
        float *plane = scratch[count++] = malloc(size * sizeof *plane);
        if (plane == NULL) status = MR_ERR_NOMEM;
        for (size_t k = 0; plane != NULL && k < size; k++) plane[k] = (float)value;
        full.in[i] = plane;
    }
    for (int j = 0; j < kind->output_count && status == MR_OK; j++) {
        if (b->out[j] != NULL) continue;
        float *plane = scratch[count++] = malloc(b->n * (size_t)kind->outputs[j].channels * sizeof *plane);
        if (plane == NULL) status = MR_ERR_NOMEM;
        full.out[j] = plane;
    }
    if (status == MR_OK && b->flags == NULL) {
        flags = malloc(b->n);
        if (flags == NULL) status = MR_ERR_NOMEM;
        full.flags = flags;
    }
    if (status != MR_OK)
        status = mr_fail(status, "transform %s: out of memory for %zu texels", kind->name, b->n);
    else if (kind->flags & MR_TRANSFORM_PER_TEXEL)
        status = apply_deduplicated(t, &full);
    else
        status = kind->apply(t, &full);
    for (int k = 0; k < count; k++) free(scratch[k]);
    free(flags);
    return status;
}

mr_status mr_transform_convert_maps(const mr_transform *t, const mr_transform_map *in, mr_image **out,
                                    uint8_t **flags_out) {
    if (t == NULL || in == NULL || out == NULL) return mr_fail(MR_ERR_INVALID_ARG, "transform: NULL argument");
    const mr_transform_kind *kind = t->kind;
    // The grid: the images' one size (1 x 1 for constants alone).
    int width = 1, height = 1, sized = -1;
    for (int i = 0; i < kind->input_count; i++) {
        const mr_image *im = in[i].image;
        if (im == NULL) continue;
        if (sized >= 0 && (im->width != width || im->height != height))
            return mr_fail(MR_ERR_INVALID_ARG, "transform %s: map '%s' is %dx%d but map '%s' is %dx%d", kind->name,
                           kind->inputs[i].name, im->width, im->height, kind->inputs[sized].name, width, height);
        const int channel = kind->inputs[i].channels == 3 ? (im->channels == 1 ? 0 : 2) : in[i].channel;
        if (channel < 0 || channel >= im->channels)
            return mr_fail(MR_ERR_INVALID_ARG, "transform %s: map '%s' has %d channel%s; channel %d was asked for",
                           kind->name, kind->inputs[i].name, im->channels, im->channels == 1 ? "" : "s", channel);
        width = im->width;
        height = im->height;
        sized = i;
    }
    const size_t n = (size_t)width * (size_t)height;
    float *planes[MR_TRANSFORM_MAX_SLOTS] = {NULL};
    uint8_t *flags = malloc(n);
    mr_status status = flags != NULL ? MR_OK : MR_ERR_NOMEM;
    for (int j = 0; j < kind->output_count; j++) out[j] = NULL;
    for (int j = 0; j < kind->output_count && status == MR_OK; j++)
        status = mr_image_create(width, height, kind->outputs[j].channels, &out[j]);
    mr_transform_batch b = {0};
    for (int i = 0; i < kind->input_count && status == MR_OK; i++) {
        const int ch = kind->inputs[i].channels;
        float *p = planes[i] = malloc(n * (size_t)ch * sizeof *p);
        if (p == NULL) {
            status = MR_ERR_NOMEM;
            break;
        }
        const mr_image *im = in[i].image;
        int from[3]; // per slot channel, the image channel read
        float value[3];
        for (int c = 0; c < ch; c++) {
            from[c] = ch == 3 ? (im && im->channels == 1 ? 0 : c) : in[i].channel;
            value[c] = in[i].complement ? 1.0f - (float)in[i].value[c] : (float)in[i].value[c];
        }
        const size_t stride = im ? (size_t)im->channels : 0;
        const int complement = in[i].complement;
        const int threads = mr_auto_threads(t->opts.threads, (long)MR_MIN(n, 1u << 30), MR_WF_PARALLEL_TEXELS);
#pragma omp parallel for schedule(static) num_threads(threads) if (threads > 1)
        for (long k = 0; k < (long)n; k++)
            for (int c = 0; c < ch; c++) {
                float v = value[c];
                if (im != NULL) {
                    v = im->pixels[(size_t)k * stride + (size_t)from[c]];
                    if (complement) v = 1.0f - v;
                }
                p[(size_t)k * (size_t)ch + (size_t)c] = v;
            }
        b.in[i] = p;
        b.stored[i] = in[i].stored;
    }
    if (status == MR_OK) {
        b.n = n;
        b.flags = flags;
        for (int j = 0; j < kind->output_count; j++) b.out[j] = out[j]->pixels;
        status = mr_transform_apply(t, &b);
    } else {
        status = mr_fail(status, "transform %s: out of memory for %dx%d texels", kind->name, width, height);
    }
    for (int i = 0; i < kind->input_count; i++) free(planes[i]);
    if (status != MR_OK) {
        for (int j = 0; j < kind->output_count; j++) {
            mr_image_free(out[j]);
            out[j] = NULL;
        }
        free(flags);
        return status;
    }
    if (flags_out != NULL)
        *flags_out = flags;
    else
        free(flags);
    return MR_OK;
}

mr_status mr_transform_apply_values(const mr_transform *t, const double *in, double *out, unsigned *flags) {
    if (t == NULL || in == NULL || out == NULL) return mr_fail(MR_ERR_INVALID_ARG, "transform: NULL argument");
    const mr_transform_kind *kind = t->kind;
    float in_values[MAX_KEY], out_values[MAX_KEY];
    mr_transform_batch b = {0};
    b.n = 1;
    b.threads = 1;
    uint8_t f = 0;
    b.flags = &f;
    size_t k = 0;
    for (int i = 0; i < kind->input_count; i++) {
        b.in[i] = in_values + k;
        for (int c = 0; c < kind->inputs[i].channels; c++, k++) in_values[k] = (float)in[k];
    }
    k = 0;
    for (int j = 0; j < kind->output_count; j++) {
        b.out[j] = out_values + k;
        k += (size_t)kind->outputs[j].channels;
    }
    mr_status status = kind->apply(t, &b);
    if (status != MR_OK) return status;
    for (size_t m = 0; m < k; m++) out[m] = out_values[m];
    if (flags != NULL) *flags = f;
    return MR_OK;
}
