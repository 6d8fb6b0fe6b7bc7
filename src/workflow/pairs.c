/*
 * pairs.c — training pairs: texels drawn, labelled, written; the objectives compared. Contract in pairs.h.
 */
#include "pairs.h"

#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../c_locale.h"
#include "../mr_internal.h"
#include "nn/mlp.h"
#include "workflow.h"

/* The draws' random numbers: a stream of the core RNG (mr_core.h, splitmix64), bit for bit the one `matremap
 * dataset` always used (the files depend on it). */
typedef struct rng {
    uint64_t state;
} rng;

static inline double uniform(rng *r) { return mr_rng_unit(&r->state); }

static int code_between(rng *r, int lo, int hi) {
    int v = lo + (int)(uniform(r) * (hi - lo + 1));
    return v > hi ? hi : v;
}

/* An 8-bit sRGB code's linear value (glTF colour textures: diffuse, specular). */
static double srgb_code(int code) {
    double v = code / 255.0;
    return v <= 0.04045 ? v / 12.92 : pow((v + 0.055) / 1.055, 2.4);
}

static int srgb_encode_code(double linear) {
    double v = linear <= 0.0031308 ? 12.92 * linear : 1.055 * pow(linear, 1.0 / 2.4) - 0.055;
    int code = (int)lround(v * 255.0);
    return code < 0 ? 0 : code > 255 ? 255 : code;
}

static const char *const category_names[MR_WF_PAIR_CATEGORY_COUNT] = {"uniform", "dielectric", "grey",
                                                                     "metal",   "mixed",      "asset"};

const char *mr_wf_pair_category_name(mr_wf_pair_category category) {
    return (int)category >= 0 && category < MR_WF_PAIR_CATEGORY_COUNT ? category_names[category] : NULL;
}

/* ---- drawing texels ------------------------------------------------------------------------------------------ */

/* A colour of 8-bit codes: dark (codes 0-40), saturated (one or two channels high, the others low), or uniform. */
static void diffuse_colour(rng *r, double d[3]) {
    double kind = uniform(r);
    if (kind < 0.3) {
        for (int c = 0; c < 3; c++) d[c] = srgb_code(code_between(r, 0, 40));
    } else if (kind < 0.65) {
        int high = code_between(r, 0, 2), second = uniform(r) < 0.4 ? (high + 1 + code_between(r, 0, 1)) % 3 : -1;
        for (int c = 0; c < 3; c++)
            d[c] = srgb_code(c == high || c == second ? code_between(r, 120, 255) : code_between(r, 0, 50));
    } else {
        for (int c = 0; c < 3; c++) d[c] = srgb_code(code_between(r, 0, 255));
    }
}

/* Sample i: its category by a fixed mixture (pool texels 30 % when there are any), then its values. */
static mr_wf_pair_category draw_texel(uint64_t seed, size_t i, const mr_wf_texel_pool *pool, mr_wf_spec *t) {
    rng r = {mr_rng_mix(seed * 0x9e3779b97f4a7c15ULL + 0x632be59bd9b4e019ULL) ^ mr_rng_mix((uint64_t)i + 1)};
    const size_t pool_count = pool ? pool->count : 0;
    double u = uniform(&r);
    mr_wf_pair_category cat;
    if (pool_count > 0 && u < 0.3)
        cat = MR_WF_PAIR_ASSET;
    else {
        double v = pool_count > 0 ? (u - 0.3) / 0.7 : u;
        cat = v < 0.25   ? MR_WF_PAIR_UNIFORM
            : v < 0.55   ? MR_WF_PAIR_DIELECTRIC
            : v < 0.67   ? MR_WF_PAIR_GREY
            : v < 0.82   ? MR_WF_PAIR_METAL
                         : MR_WF_PAIR_MIXED;
    }
    memset(t, 0, sizeof *t);
    switch (cat) {
    case MR_WF_PAIR_UNIFORM:
        for (int c = 0; c < 3; c++) {
            t->diffuse[c] = srgb_code(code_between(&r, 0, 255));
            t->specular[c] = srgb_code(code_between(&r, 0, 255));
        }
        break;
    case MR_WF_PAIR_DIELECTRIC: {
        int code = code_between(&r, 40, 70);
        int jitter = uniform(&r) < 0.3;
        diffuse_colour(&r, t->diffuse);
        for (int c = 0; c < 3; c++) t->specular[c] = srgb_code(code + (jitter ? code_between(&r, -3, 3) : 0));
        break;
    }
    case MR_WF_PAIR_GREY: {
        int dc = code_between(&r, 0, 255), sc = code_between(&r, 0, 255);
        for (int c = 0; c < 3; c++) {
            t->diffuse[c] = srgb_code(dc);
            t->specular[c] = srgb_code(sc);
        }
        break;
    }
    case MR_WF_PAIR_METAL: {
        int base = code_between(&r, 120, 255);
        for (int c = 0; c < 3; c++) {
            t->diffuse[c] = srgb_code(code_between(&r, 0, 12));
            int code = base - code_between(&r, 0, 80);
            t->specular[c] = srgb_code(code < 60 ? 60 : code);
        }
        break;
    }
    case MR_WF_PAIR_MIXED: {
        mr_wf_metal m = {{0, 0, 0}, uniform(&r), 0};
        double a[3];
        diffuse_colour(&r, a);
        for (int c = 0; c < 3; c++) m.albedo[c] = a[c];
        mr_wf_options o = mr_wf_options_default();
        o.spec_diffuse = MR_WF_DIFFUSE_SPECGLOSS;
        mr_wf_spec s;
        if (mr_wf_metal_to_spec(&m, &o, &s, NULL) == MR_OK)
            for (int c = 0; c < 3; c++) {
                t->diffuse[c] = srgb_code(srgb_encode_code(s.diffuse[c]));
                t->specular[c] = srgb_code(srgb_encode_code(s.specular[c]));
            }
        break;
    }
    default: {
        size_t k = (size_t)(uniform(&r) * (double)pool_count);
        if (k >= pool_count) k = pool_count - 1;
        for (int c = 0; c < 3; c++) {
            t->diffuse[c] = pool->texels[6 * k + c];
            t->specular[c] = pool->texels[6 * k + 3 + c];
        }
        break;
    }
    }
    return cat;
}

/* ---- the pool of textured texels ----------------------------------------------------------------------------- */

void mr_wf_texel_pool_begin_source(mr_wf_texel_pool *pool, uint64_t seed) {
    pool->draw_state = mr_rng_mix(seed ^ 0xa5a5a5a5ULL) ^ mr_rng_mix((uint64_t)pool->sources + 77);
}

void mr_wf_texel_pool_end_source(mr_wf_texel_pool *pool) {
    pool->sources++;
}

/* Value of channel c of `image` at the relative position (u, v) (nearest texel), or 1 without an image. */
static double texel_at(const mr_image *image, double u, double v, int c) {
    if (image == NULL) return 1.0;
    int x = (int)(u * image->width), y = (int)(v * image->height);
    if (x >= image->width) x = image->width - 1;
    if (y >= image->height) y = image->height - 1;
    int ch = c < image->channels ? c : 0;
    return image->pixels[((size_t)y * image->width + x) * image->channels + ch];
}

mr_status mr_wf_texel_pool_add_maps(mr_wf_texel_pool *pool, const mr_image *diffuse, const mr_image *specgloss,
                                    const double diffuse_factor[3], const double specular_factor[3], size_t count) {
    if (pool == NULL || diffuse_factor == NULL || specular_factor == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "texel pool: NULL pool or factors");
    if (pool->count + count > pool->capacity) {
        float *grown = realloc(pool->texels, (pool->count + count) * 6 * sizeof *grown);
        if (grown == NULL)
            return mr_fail(MR_ERR_NOMEM, "texel pool: out of memory for %zu texels", pool->count + count);
        pool->texels = grown;
        pool->capacity = pool->count + count;
    }
    rng r = {pool->draw_state};
    for (size_t j = 0; j < count; j++) {
        double u = uniform(&r), v = uniform(&r);
        float *t = pool->texels + 6 * pool->count++;
        for (int c = 0; c < 3; c++) {
            t[c] = (float)fmin(1.0, fmax(0.0, texel_at(diffuse, u, v, c) * diffuse_factor[c]));
            t[3 + c] = (float)fmin(1.0, fmax(0.0, texel_at(specgloss, u, v, c) * specular_factor[c]));
        }
    }
    pool->draw_state = r.state;
    return MR_OK;
}

void mr_wf_texel_pool_free(mr_wf_texel_pool *pool) {
    if (pool == NULL) return;
    free(pool->texels);
    memset(pool, 0, sizeof *pool);
}

/* ---- labelling ----------------------------------------------------------------------------------------------- */

typedef struct pair {
    mr_wf_spec in;
    mr_wf_metal label;
    mr_wf_label_result result;
    mr_wf_pair_category cat;
} pair;

/* How often the progress callback hears of a stage (pairs between calls). */
#define PROGRESS_EVERY 256

/* Label every pair (an OpenMP team over pairs, dynamic: texels differ in cost). */
static mr_status label_pairs(const mr_wf_label_scene *scene, pair *pairs, size_t n, const char *stage,
                             const mr_wf_pairs_options *opts) {
    mr_status status = MR_OK;
    const int threads = mr_auto_threads(opts->threads, n > (size_t)LONG_MAX ? LONG_MAX : (long)n, 2);
    size_t done = 0;
#pragma omp parallel for schedule(dynamic, 16) num_threads(threads)
    for (size_t i = 0; i < n; i++) {
        mr_status s = mr_wf_label_fit(scene, &pairs[i].in, &pairs[i].label, &pairs[i].result);
        size_t now;
#pragma omp atomic capture
        now = ++done;
        if (s != MR_OK) {
#pragma omp critical(mr_wf_pairs_status)
            status = s;
        }
        if (opts->progress != NULL && now % PROGRESS_EVERY == 0 && now != n) {
#pragma omp critical(mr_wf_pairs_progress)
            opts->progress(stage, now, n, opts->progress_user);
        }
    }
    if (opts->progress != NULL) opts->progress(stage, n, n, opts->progress_user);
    return status;
}

/* The label options in force: the caller's, or the defaults; their scenes render with the pairs' threads unless
 * they name their own. */
static mr_wf_label_options label_options_of(const mr_wf_pairs_options *opts) {
    mr_wf_label_options o = opts->labels ? *opts->labels : mr_wf_label_options_default();
    if (o.threads == 0) o.threads = opts->threads;
    return o;
}

/* Drawn texels first come after `first` fixed ones; sample i of the draw is pairs[first + i]. */
static void draw_pairs(const mr_wf_pairs_options *opts, pair *pairs, size_t first, size_t samples) {
    for (size_t i = 0; i < samples; i++)
        pairs[first + i].cat = draw_texel(opts->seed, i, opts->pool, &pairs[first + i].in);
}

/* ---- the pairs file ------------------------------------------------------------------------------------------ */

/* The diffuse lobe the network reads (glTF's reading of a spec-gloss diffuse: d (1 - max s)). */
static void lobe(const mr_wf_spec *in, double d[3]) {
    double smax = fmax(in->specular[0], fmax(in->specular[1], in->specular[2]));
    for (int c = 0; c < 3; c++) d[c] = in->diffuse[c] * (1.0 - smax);
}

static mr_status write_pairs(const char *path, const pair *pairs, size_t n, const char *objective, uint64_t seed) {
    mr_atomic_file file;
    FILE *f = NULL;
    mr_status status = mr_atomic_open_text(path, &file, &f);
    if (status != MR_OK) return status;
    fprintf(f, "# matremap dataset: objective %s, seed %llu, %zu pairs (docs/training.md)\n", objective,
            (unsigned long long)seed, n);
    fprintf(f, "index,category,sg_diffuse_r,sg_diffuse_g,sg_diffuse_b,diffuse_r,diffuse_g,diffuse_b,f0_r,f0_g,f0_b,"
               "to_albedo_r,to_albedo_g,to_albedo_b,to_metallic,loss,analytic_loss,kept_analytic,outcome\n");
    for (size_t i = 0; i < n; i++) {
        const pair *p = &pairs[i];
        double d[3];
        lobe(&p->in, d);
        fprintf(f, "%zu,%s,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.6g,%.6g,%d,%s\n",
                i, category_names[p->cat], p->in.diffuse[0], p->in.diffuse[1], p->in.diffuse[2], d[0], d[1], d[2],
                p->in.specular[0], p->in.specular[1], p->in.specular[2], p->label.albedo[0], p->label.albedo[1],
                p->label.albedo[2], p->label.metallic, p->result.loss, p->result.analytic_loss,
                p->result.kept_analytic, p->result.loss <= MR_WF_PAIRS_CONVERGED_LOSS ? "converged" : "unreachable");
    }
    status = mr_atomic_close_text(f, &file);
    if (status != MR_OK) return status;
    return mr_atomic_commit(&file);
}

static mr_status check_pairs_options(const mr_wf_pairs_options *opts, const char *what) {
    if (opts == NULL) return mr_fail(MR_ERR_INVALID_ARG, "%s: NULL options", what);
    if (opts->samples < 0) return mr_fail(MR_ERR_INVALID_ARG, "%s: samples %d: expected >= 0", what, opts->samples);
    if (opts->threads < 0 || opts->threads > 1024)
        return mr_fail(MR_ERR_INVALID_ARG, "%s: threads %d: expected 0 (automatic) .. 1024", what, opts->threads);
    if (opts->pool != NULL && opts->pool->count > 0 && opts->pool->texels == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "%s: a pool of %zu texels without texels", what, opts->pool->count);
    return MR_OK;
}

static mr_status pairs_make(const mr_wf_pairs_options *opts, const char *path, mr_wf_pairs_summary *summary) {
    mr_status status = check_pairs_options(opts, "pairs");
    if (status != MR_OK) return status;
    if (path == NULL) return mr_fail(MR_ERR_INVALID_ARG, "pairs: NULL output path");
    const size_t n = opts->samples > 0 ? (size_t)opts->samples : 16000;
    pair *pairs = calloc(n, sizeof *pairs);
    if (pairs == NULL) return mr_fail(MR_ERR_NOMEM, "pairs: out of memory for %zu pairs", n);
    draw_pairs(opts, pairs, 0, n);
    const mr_wf_label_options lo = label_options_of(opts);
    mr_wf_label_scene *scene = NULL;
    status = mr_wf_label_scene_create(&lo, &scene);
    if (status == MR_OK) status = label_pairs(scene, pairs, n, "labels", opts);
    mr_wf_label_scene_free(scene);
    if (status == MR_OK) status = write_pairs(path, pairs, n, mr_wf_objective_name(lo.objective), opts->seed);
    if (status == MR_OK && summary != NULL) {
        memset(summary, 0, sizeof *summary);
        summary->pairs = n;
        for (size_t i = 0; i < n; i++) {
            summary->converged += pairs[i].result.loss <= MR_WF_PAIRS_CONVERGED_LOSS;
            summary->categories[pairs[i].cat]++;
        }
        summary->unreachable = n - summary->converged;
    }
    free(pairs);
    return status;
}

/* The file holds C-locale numbers whatever the host's locale (c_locale.h), as its reader expects. */
mr_status mr_wf_pairs_make(const mr_wf_pairs_options *opts, const char *path, mr_wf_pairs_summary *summary) {
    mr_c_numeric locale;
    mr_status status = mr_c_numeric_enter(&locale, "pairs");
    if (status != MR_OK) return status;
    status = pairs_make(opts, path, summary);
    mr_c_numeric_leave(&locale);
    return status;
}

/* ---- the comparison ------------------------------------------------------------------------------------------ */

/* The named hard cases (spec-gloss values; specular codes of the 8-bit dielectric band). */
static const mr_wf_named_texel hard_cases[] = {
    {"black plastic", {12, 12, 12}, {56, 56, 56}},     {"dark grey plastic", {40, 40, 40}, {56, 56, 56}},
    {"mid grey plastic", {128, 128, 128}, {56, 56, 56}}, {"white plastic", {250, 250, 250}, {56, 56, 56}},
    {"dark dielectric F0 40", {20, 20, 20}, {40, 40, 40}}, {"bright dielectric F0 70", {220, 220, 220}, {70, 70, 70}},
    {"red cap", {200, 20, 15}, {56, 56, 56}},           {"green paint", {20, 160, 30}, {56, 56, 56}},
    {"blue paint", {15, 30, 190}, {56, 56, 56}},        {"yellow plastic", {230, 200, 10}, {56, 56, 56}},
    {"grey in (1, 0)", {255, 255, 255}, {0, 0, 0}},      {"grey half/half", {128, 128, 128}, {128, 128, 128}},
    {"gold", {0, 0, 0}, {255, 220, 130}},               {"copper", {0, 0, 0}, {250, 208, 192}},
    {"silver", {0, 0, 0}, {252, 250, 245}},             {"iron", {0, 0, 0}, {196, 199, 199}},
    {"half metal red", {100, 10, 8}, {170, 90, 80}},    {"coloured spec on grey", {128, 128, 128}, {230, 120, 120}},
    {"dark spec 20", {128, 128, 128}, {20, 20, 20}},
    {"bright diffuse + bright spec", {230, 230, 230}, {200, 200, 200}},
};
#define HARD_CASES ((int)(sizeof hard_cases / sizeof hard_cases[0]))

void mr_wf_compare_table_free(mr_wf_compare_table *table) {
    if (table == NULL) return;
    for (int k = 0; k < table->column_count; k++) free(table->columns[k].ssim);
    free(table->categories);
    free(table);
}

/* Column k's answers for every texel: an objective's labels (k < MR_WF_COMPARE_OBJECTIVES), an analytic inverse
 * (glTF reading of the diffuse), or a network; the column's name is set first. dif/spe hold the texels as planes,
 * alb/met are scratch planes of the batches. */
static mr_status column_answers(const mr_wf_compare_options *opts, int k, pair *texels, size_t n, const float *dif,
                                const float *spe, float *alb, float *met, mr_wf_metal *answers,
                                mr_wf_compare_column *col) {
    mr_status status;
    if (k < MR_WF_COMPARE_OBJECTIVES) {
        mr_wf_label_options lo = label_options_of(&opts->pairs);
        lo.objective = (mr_wf_objective)(MR_WF_OBJECTIVE_LINEAR + k);
        mr_wf_label_scene *scene = NULL;
        snprintf(col->name, sizeof col->name, "labels: %s", mr_wf_objective_name(lo.objective));
        status = mr_wf_label_scene_create(&lo, &scene);
        if (status == MR_OK) status = label_pairs(scene, texels, n, col->name, &opts->pairs);
        for (size_t i = 0; i < n; i++) answers[i] = texels[i].label;
        mr_wf_label_scene_free(scene);
        return status;
    }
    mr_wf_spec_input in = {dif, spe, NULL};
    mr_wf_metal_maps out = {alb, met, NULL};
    mr_wf_options o = mr_wf_options_default();
    o.spec_diffuse = MR_WF_DIFFUSE_SPECGLOSS;
    o.threads = opts->pairs.threads;
    int a = k - MR_WF_COMPARE_OBJECTIVES;
    if (a < 3) {
        static const mr_wf_method methods[3] = {MR_WF_WEIGHTED, MR_WF_MEAN, MR_WF_KHRONOS};
        o.method = methods[a];
        snprintf(col->name, sizeof col->name, "%s", mr_wf_method_name(o.method));
        status = mr_wf_spec_to_metal_batch(&in, n, &o, &out, NULL);
    } else {
        mr_mlp *net = NULL;
        const char *w = opts->weights[a - 3];
        status = mr_mlp_read(w, &net);
        snprintf(col->name, sizeof col->name, "mlp %s", strrchr(w, '/') ? strrchr(w, '/') + 1 : w);
        if (status == MR_OK) status = mr_wf_spec_to_metal_mlp_batch(net, &in, n, &o, &out, NULL);
        mr_mlp_free(net);
    }
    for (size_t i = 0; status == MR_OK && i < n; i++) {
        for (int c = 0; c < 3; c++) answers[i].albedo[c] = alb[3 * i + c];
        answers[i].metallic = met[i];
    }
    return status;
}

/* Every column's SSIM of every texel under the evaluation scene (a team over texels, dynamic). */
static mr_status judge_column(const mr_wf_label_scene *eval, const pair *texels, const mr_wf_metal *answers, size_t n,
                              int requested_threads, double *ssim) {
    mr_status status = MR_OK;
    const int threads = mr_auto_threads(requested_threads, n > (size_t)LONG_MAX ? LONG_MAX : (long)n, 2);
#pragma omp parallel for schedule(dynamic, 8) num_threads(threads)
    for (size_t i = 0; i < n; i++) {
        mr_status s = mr_wf_label_ssim(eval, &texels[i].in, &answers[i], &ssim[i]);
        if (s != MR_OK) {
#pragma omp critical(mr_wf_pairs_status)
            status = s;
        }
    }
    return status;
}

static mr_status compare(const mr_wf_compare_options *opts, pair *texels, size_t n, mr_wf_compare_table *table) {
    mr_wf_label_options eo = mr_wf_label_options_default();
    eo.size = 96;
    eo.env_count = opts->env_count;
    for (int e = 0; e < opts->env_count; e++) eo.envs[e] = opts->envs[e];
    eo.glossiness_count = 3;
    eo.glossiness[0] = 0.3;
    eo.glossiness[1] = 0.6;
    eo.glossiness[2] = 0.9;
    eo.threads = opts->pairs.threads;
    mr_wf_label_scene *eval = NULL;
    mr_status status = mr_wf_label_scene_create(&eo, &eval);
    if (status != MR_OK) return status;
    mr_wf_metal *answers = malloc(n * sizeof *answers);
    float *dif = malloc(n * 3 * sizeof *dif), *spe = malloc(n * 3 * sizeof *spe);
    float *alb = malloc(n * 3 * sizeof *alb), *met = malloc(n * sizeof *met);
    if (answers == NULL || dif == NULL || spe == NULL || alb == NULL || met == NULL)
        status = mr_fail(MR_ERR_NOMEM, "compare: out of memory for %zu texels", n);
    for (size_t i = 0; status == MR_OK && i < n; i++)
        for (int c = 0; c < 3; c++) {
            dif[3 * i + c] = (float)texels[i].in.diffuse[c];
            spe[3 * i + c] = (float)texels[i].in.specular[c];
        }
    const int total = MR_WF_COMPARE_OBJECTIVES + 3 + opts->weight_count;
    for (int k = 0; status == MR_OK && k < total; k++) {
        mr_wf_compare_column *col = &table->columns[table->column_count];
        col->ssim = malloc(n * sizeof *col->ssim);
        if (col->ssim == NULL) {
            status = mr_fail(MR_ERR_NOMEM, "compare: out of memory for %zu texels", n);
            break;
        }
        table->column_count++;
        status = column_answers(opts, k, texels, n, dif, spe, alb, met, answers, col);
        if (status == MR_OK) status = judge_column(eval, texels, answers, n, opts->pairs.threads, col->ssim);
    }
    free(answers);
    free(dif);
    free(spe);
    free(alb);
    free(met);
    mr_wf_label_scene_free(eval);
    return status;
}

mr_status mr_wf_pairs_compare(const mr_wf_compare_options *opts, mr_wf_compare_table **out) {
    if (out == NULL) return mr_fail(MR_ERR_INVALID_ARG, "compare: NULL output");
    *out = NULL;
    mr_status status = check_pairs_options(opts ? &opts->pairs : NULL, "compare");
    if (status != MR_OK) return status;
    if (opts->env_count < 1 || opts->env_count > MR_WF_LABEL_MAX_ENVS || opts->envs == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "compare: %d environments: expected 1 .. %d", opts->env_count,
                       MR_WF_LABEL_MAX_ENVS);
    if (opts->weight_count < 0 || opts->weight_count > MR_WF_COMPARE_MAX_WEIGHTS ||
        (opts->weight_count > 0 && opts->weights == NULL))
        return mr_fail(MR_ERR_INVALID_ARG, "compare: %d networks: expected 0 .. %d", opts->weight_count,
                       MR_WF_COMPARE_MAX_WEIGHTS);
    const size_t samples = opts->pairs.samples > 0 ? (size_t)opts->pairs.samples : 400;
    const size_t n = (size_t)HARD_CASES + samples;
    mr_wf_compare_table *table = calloc(1, sizeof *table);
    pair *texels = calloc(n, sizeof *texels);
    if (table != NULL) table->categories = malloc(n * sizeof *table->categories);
    if (table == NULL || texels == NULL || table->categories == NULL) {
        mr_wf_compare_table_free(table);
        free(texels);
        return mr_fail(MR_ERR_NOMEM, "compare: out of memory for %zu texels", n);
    }
    table->texel_count = n;
    table->hard_case_count = HARD_CASES;
    table->hard_cases = hard_cases;
    for (int i = 0; i < HARD_CASES; i++) {
        for (int c = 0; c < 3; c++) {
            texels[i].in.diffuse[c] = srgb_code(hard_cases[i].diffuse[c]);
            texels[i].in.specular[c] = srgb_code(hard_cases[i].specular[c]);
        }
        texels[i].cat = MR_WF_PAIR_UNIFORM;
    }
    draw_pairs(&opts->pairs, texels, (size_t)HARD_CASES, samples);
    for (size_t i = 0; i < n; i++) table->categories[i] = texels[i].cat;
    status = compare(opts, texels, n, table);
    free(texels);
    if (status != MR_OK) {
        mr_wf_compare_table_free(table);
        return status;
    }
    *out = table;
    return MR_OK;
}

/* ---- converters against labels ------------------------------------------------------------------------------- */

mr_status mr_wf_pairs_evaluate(const struct mr_mlp *net, const mr_wf_dataset *pairs, int threads,
                               mr_wf_method_error errors[MR_WF_EVALUATED_METHODS]) {
    if (net == NULL || pairs == NULL || errors == NULL || (pairs->n > 0 && (pairs->x == NULL || pairs->y == NULL)))
        return mr_fail(MR_ERR_INVALID_ARG, "evaluate: NULL network, pairs or errors");
    const size_t n = pairs->n;
    float *diffuse = malloc(n * 3 * sizeof *diffuse), *specular = malloc(n * 3 * sizeof *specular);
    float *albedo = malloc(n * 3 * sizeof *albedo), *metallic = malloc(n * sizeof *metallic);
    mr_status status = MR_OK;
    if (!(diffuse && specular && albedo && metallic))
        status = mr_fail(MR_ERR_NOMEM, "evaluate: out of memory for %zu pairs", n);
    for (size_t i = 0; status == MR_OK && i < n; i++)
        for (int c = 0; c < 3; c++) {
            diffuse[3 * i + c] = pairs->x[MR_WF_DATASET_INPUTS * i + c];
            specular[3 * i + c] = pairs->x[MR_WF_DATASET_INPUTS * i + 3 + c];
        }
    static const char *const names[MR_WF_EVALUATED_METHODS] = {"mlp", "weighted", "mean", "khronos"};
    static const mr_wf_method methods[MR_WF_EVALUATED_METHODS] = {MR_WF_CUSTOM, MR_WF_WEIGHTED, MR_WF_MEAN,
                                                                  MR_WF_KHRONOS};
    for (int m = 0; status == MR_OK && m < MR_WF_EVALUATED_METHODS; m++) {
        mr_wf_spec_input in = {diffuse, specular, NULL};
        mr_wf_metal_maps out = {albedo, metallic, NULL};
        mr_wf_options o = mr_wf_options_default();
        o.method = methods[m];
        o.threads = threads;
        status = m == 0 ? mr_wf_spec_to_metal_mlp_batch(net, &in, n, &o, &out, NULL)
                        : mr_wf_spec_to_metal_batch(&in, n, &o, &out, NULL);
        double sa = 0.0, sm = 0.0, worst = 0.0;
        for (size_t i = 0; status == MR_OK && i < n; i++) {
            for (int c = 0; c < 3; c++) {
                double d = albedo[3 * i + c] - pairs->y[MR_WF_DATASET_OUTPUTS * i + c];
                sa += d * d;
            }
            double d = metallic[i] - pairs->y[MR_WF_DATASET_OUTPUTS * i + 3];
            sm += d * d;
            worst = fmax(worst, fabs(d));
        }
        errors[m].name = names[m];
        errors[m].albedo_rmse = n ? sqrt(sa / (3.0 * (double)n)) : 0.0;
        errors[m].metallic_rmse = n ? sqrt(sm / (double)n) : 0.0;
        errors[m].metallic_max = worst;
    }
    free(diffuse);
    free(specular);
    free(albedo);
    free(metallic);
    return status;
}
