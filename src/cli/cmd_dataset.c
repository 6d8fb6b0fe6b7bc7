/*
 * cmd_dataset.c — `matremap dataset`: training pairs for the learned spec -> metal converter, labelled by the
 * image objective of src/workflow/labels.h (docs/training.md), and `matremap dataset --compare`: how well each
 * objective's labels, and each converter, keep the look under other lights (object SSIM of spheres).
 *
 * Inputs are spec-gloss texels as 8-bit textures store them (sRGB codes decoded to linear), drawn from a
 * mixture that covers real textures (draw_texel says which and why), plus texels of glTF assets given with
 * --asset. Each sample is a pure function of (seed, index), so files do not depend on the thread count.
 */
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <omp.h>
#include <unistd.h>

#include "cli.h"
#include "gltf/mr_gltf.h"
#include "workflow/labels.h"

#define MAX_ASSETS 16
#define MAX_ENVS 4
#define MAX_WEIGHTS 4
#define ASSET_TEXELS 4096 /* texels sampled from each asset's spec-gloss maps */

static void print_help(void) {
    printf("Usage: matremap dataset -o PAIRS.csv [options]\n"
           "       matremap dataset --compare --env MAP.hdr [--env MAP.hdr ...] [options]\n"
           "\n"
           "Makes training pairs for the specular -> metallic network: spec-gloss texels (diffuse, specular) and\n"
           "the glTF metal-rough material (base colour, metallic) that renders most like each one, on a sphere\n"
           "under two synthetic grey environments (a studio and a sky, none of the maps evaluations use) at four\n"
           "glossinesses (0.3, 0.6, 0.8, 0.95), by an image objective (docs/training.md). Texels are drawn as\n"
           "8-bit textures store them: uniform codes, the dielectric F0 band (specular 40-70/255) with dark and\n"
           "saturated diffuse, grey inputs, metals, partly metallic texels of Eq. 2, and texels of --asset files.\n"
           "The file loads in 'matremap train' (its diffuse columns hold the diffuse lobe d (1 - max specular)).\n"
           "A pair's outcome is converged when the label renders like the texel within one 8-bit code (rms),\n"
           "else unreachable (no metal-rough material matches it; the label is the closest one).\n"
           "\n"
           "With --compare, fits the labels of every objective for a set of texels (the named hard cases, texels\n"
           "of --asset files and drawn ones), and prints a table of how close each objective's labels, each\n"
           "analytic inverse and each --weights network render to the original under the --env maps: SSIM over\n"
           "the sphere's inner square (the object's pixels), mean and worst over texels.\n"
           "\n"
           "Options:\n"
           "  -o, --output FILE     the pairs (CSV, written atomically); with --compare, the table (markdown)\n"
           "  --samples N           drawn texels (default 16000; --compare: 400)\n"
           "  --seed S              seed of the draws (default 1); sample i depends only on (S, i)\n"
           "  --objective O         luma (default), exposed, display, log or linear (labels.h)\n"
           "  --asset FILE.gltf     spec-gloss assets whose texels join the mixture (repeatable; 30 %% of the\n"
           "                        samples, shared equally)\n"
           "  --size N              label sphere side in pixels (default 32)\n"
           "  --label-env FILE      an environment the labels are made under, instead of the built-in synthetic\n"
           "                        studio and sky (repeatable, at most %d)\n"
           "  --chroma-weight W     luma objective: weight of the per-channel colour term (default 0.1)\n"
           "  --regularisation L    pull towards the analytic answer (default 1e-4, labels.h)\n"
           "  --threads T           OpenMP threads (default 0: automatic, all cores); results do not depend on it\n"
           "  --compare             the objective comparison (needs --env)\n"
           "  --env FILE            an environment map for --compare (repeatable, at most %d)\n"
           "  --weights FILE        a network to compare too (repeatable, at most %d)\n"
           "  --json                a summary as one JSON object on stdout: the output, pair count, outcomes\n"
           "                        (converged, unreachable), categories, seconds; with --compare (which then\n"
           "                        needs -o for the table) each column's mean and worst SSIM\n"
           "  --help                this text\n"
           "\n"
           "Exit codes: 0 done, 1 usage error, 2 bad input (an asset or map that cannot be read, an asset without\n"
           "spec-gloss materials, an output that cannot be written), 3 internal failure.\n"
           "\n"
           "Examples:\n"
           "  matremap dataset -o pairs.csv --samples 2000 --asset Duck.gltf --asset Avocado.gltf\n"
           "  matremap dataset --compare --env studio.hdr --env tabac.hdr --weights data/spec2metal.mlp\n",
           MAX_ENVS, MAX_ENVS, MAX_WEIGHTS);
}

/* ---- drawing texels ------------------------------------------------------------------------------------------ */

/* A stream of the core RNG (mr_core.h: splitmix64). */
typedef struct rng {
    uint64_t state;
} rng;

static double uniform(rng *r) { return mr_rng_unit(&r->state); }

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

typedef enum category {
    CAT_UNIFORM = 0, /* every code equally likely, channels independent (coloured specular too) */
    CAT_DIELECTRIC,  /* specular in the 8-bit dielectric band 40-70 (grey, sometimes a code or two apart) */
    CAT_GREY,        /* grey diffuse and grey specular */
    CAT_METAL,       /* dark diffuse, bright (tinted) specular */
    CAT_MIXED,       /* Eq. 2 of a partly metallic texel, stored in 8 bits */
    CAT_ASSET,       /* a texel of an --asset */
    CAT_COUNT
} category;

static const char *const category_names[CAT_COUNT] = {"uniform", "dielectric", "grey", "metal", "mixed", "asset"};

typedef struct texel_pool {
    float *texels; /* count x 6: diffuse RGB, specular RGB (linear spec-gloss values) */
    size_t count;
    int assets;
} texel_pool;

/* Sample i: its category by a fixed mixture (asset texels 30 % when there are any), then its values. */
static category draw_texel(uint64_t seed, size_t i, const texel_pool *pool, mr_wf_spec *t) {
    rng r = {mr_rng_mix(seed * 0x9e3779b97f4a7c15ULL + 0x632be59bd9b4e019ULL) ^ mr_rng_mix((uint64_t)i + 1)};
    double u = uniform(&r);
    category cat;
    if (pool->count > 0 && u < 0.3)
        cat = CAT_ASSET;
    else {
        double v = pool->count > 0 ? (u - 0.3) / 0.7 : u;
        cat = v < 0.25 ? CAT_UNIFORM : v < 0.55 ? CAT_DIELECTRIC : v < 0.67 ? CAT_GREY : v < 0.82 ? CAT_METAL
                                                                                          : CAT_MIXED;
    }
    memset(t, 0, sizeof *t);
    switch (cat) {
    case CAT_UNIFORM:
        for (int c = 0; c < 3; c++) {
            t->diffuse[c] = srgb_code(code_between(&r, 0, 255));
            t->specular[c] = srgb_code(code_between(&r, 0, 255));
        }
        break;
    case CAT_DIELECTRIC: {
        int code = code_between(&r, 40, 70);
        int jitter = uniform(&r) < 0.3;
        diffuse_colour(&r, t->diffuse);
        for (int c = 0; c < 3; c++) t->specular[c] = srgb_code(code + (jitter ? code_between(&r, -3, 3) : 0));
        break;
    }
    case CAT_GREY: {
        int dc = code_between(&r, 0, 255), sc = code_between(&r, 0, 255);
        for (int c = 0; c < 3; c++) {
            t->diffuse[c] = srgb_code(dc);
            t->specular[c] = srgb_code(sc);
        }
        break;
    }
    case CAT_METAL: {
        int base = code_between(&r, 120, 255);
        for (int c = 0; c < 3; c++) {
            t->diffuse[c] = srgb_code(code_between(&r, 0, 12));
            int code = base - code_between(&r, 0, 80);
            t->specular[c] = srgb_code(code < 60 ? 60 : code);
        }
        break;
    }
    case CAT_MIXED: {
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
        size_t k = (size_t)(uniform(&r) * (double)pool->count);
        if (k >= pool->count) k = pool->count - 1;
        for (int c = 0; c < 3; c++) {
            t->diffuse[c] = pool->texels[6 * k + c];
            t->specular[c] = pool->texels[6 * k + 3 + c];
        }
        break;
    }
    }
    return cat;
}

/* ---- texels of glTF assets ----------------------------------------------------------------------------------- */

/* Value of channel c of `image` at the relative position (u, v) (nearest texel), or 1 without an image. */
static double texel_at(const mr_image *image, double u, double v, int c) {
    if (image == NULL) return 1.0;
    int x = (int)(u * image->width), y = (int)(v * image->height);
    if (x >= image->width) x = image->width - 1;
    if (y >= image->height) y = image->height - 1;
    int ch = c < image->channels ? c : 0;
    return image->pixels[((size_t)y * image->width + x) * image->channels + ch];
}

/* ASSET_TEXELS texels of every spec-gloss material of `path`, shared equally among its materials: diffuse and
 * specular maps (sRGB-decoded) times their factors, at the same relative position in both; the files the asset was
 * read from are added to io's inputs. Returns an exit code. */
static int add_asset_texels(const char *path, uint64_t seed, texel_pool *pool, cli_io *io) {
    mr_gltf *asset = NULL;
    mr_status status = mr_gltf_load(path, &asset);
    if (status != MR_OK) return cli_fail("dataset", status);
    char label[4096 + 16];
    snprintf(label, sizeof label, "--asset %s", path);
    cli_io_gltf(io, asset, label); // its buffers and images are inputs too
    mr_gltf_counts counts;
    mr_gltf_get_counts(asset, &counts);
    int sg_materials = 0;
    for (int k = 0; k < counts.materials; k++) {
        mr_gltf_material m;
        if (mr_gltf_get_material(asset, k, &m) == MR_OK && m.has_spec_gloss) sg_materials++;
    }
    if (sg_materials == 0) {
        mr_gltf_free(asset);
        fprintf(stderr,
                "matremap dataset: error: --asset %s: no material carries KHR_materials_pbrSpecularGlossiness\n",
                path);
        return CLI_EXIT_BAD_INPUT;
    }
    size_t per = ASSET_TEXELS / (size_t)sg_materials;
    float *grown = realloc(pool->texels, (pool->count + per * (size_t)sg_materials) * 6 * sizeof *grown);
    if (grown == NULL) {
        mr_gltf_free(asset);
        fprintf(stderr, "matremap dataset: error: out of memory\n");
        return CLI_EXIT_INTERNAL;
    }
    pool->texels = grown;
    int code = CLI_EXIT_OK;
    rng r = {mr_rng_mix(seed ^ 0xa5a5a5a5ULL) ^ mr_rng_mix((uint64_t)pool->assets + 77)};
    for (int k = 0; code == CLI_EXIT_OK && k < counts.materials; k++) {
        mr_gltf_material m;
        if (mr_gltf_get_material(asset, k, &m) != MR_OK || !m.has_spec_gloss) continue;
        mr_image *diffuse = NULL, *sg = NULL;
        mr_status status = MR_OK; // colour textures: the reader's default
        if (m.diffuse_texture.index >= 0)
            status = mr_gltf_texture_read(asset, m.diffuse_texture.index, NULL, &diffuse, NULL);
        if (status == MR_OK && m.specular_glossiness_texture.index >= 0)
            status = mr_gltf_texture_read(asset, m.specular_glossiness_texture.index, NULL, &sg, NULL);
        if (status != MR_OK) code = cli_fail("dataset", status);
        for (size_t j = 0; code == CLI_EXIT_OK && j < per; j++) {
            double u = uniform(&r), v = uniform(&r);
            float *t = pool->texels + 6 * pool->count++;
            for (int c = 0; c < 3; c++) {
                t[c] = (float)fmin(1.0, fmax(0.0, texel_at(diffuse, u, v, c) * m.diffuse_factor[c]));
                t[3 + c] = (float)fmin(1.0, fmax(0.0, texel_at(sg, u, v, c) * m.specular_factor[c]));
            }
        }
        mr_image_free(diffuse);
        mr_image_free(sg);
    }
    pool->assets++;
    mr_gltf_free(asset);
    return code;
}

/* ---- the pairs ----------------------------------------------------------------------------------------------- */

typedef struct pair {
    mr_wf_spec in;
    mr_wf_metal label;
    mr_wf_label_result result;
    category cat;
} pair;

static void progress(const char *what, size_t done, size_t total, double started) {
    fprintf(stderr, "\rmatremap dataset: %s %zu/%zu  %.0f s ", what, done, total, cli_now() - started);
}

/* Label every pair (OpenMP over pairs, dynamic: texels differ in cost). */
static mr_status label_pairs(const mr_wf_label_scene *scene, pair *pairs, size_t n, const char *what) {
    mr_status status = MR_OK;
    int draw = isatty(STDERR_FILENO);
    double started = cli_now();
    size_t done = 0;
#pragma omp parallel for schedule(dynamic, 16)
    for (size_t i = 0; i < n; i++) {
        mr_status s = mr_wf_label_fit(scene, &pairs[i].in, &pairs[i].label, &pairs[i].result);
        size_t now;
#pragma omp atomic capture
        now = ++done;
        if (s != MR_OK) {
#pragma omp critical(dataset_status)
            status = s;
        }
        if (draw && (now % 256 == 0 || now == n)) {
#pragma omp critical(dataset_progress)
            progress(what, now, n, started);
        }
    }
    if (draw) fputc('\n', stderr);
    return status;
}

/* The diffuse lobe the network reads (glTF's reading of a spec-gloss diffuse: d (1 - max s)). */
static void lobe(const mr_wf_spec *in, double d[3]) {
    double smax = fmax(in->specular[0], fmax(in->specular[1], in->specular[2]));
    for (int c = 0; c < 3; c++) d[c] = in->diffuse[c] * (1.0 - smax);
}

/* The library's atomic-file protocol (io_internal.h): the output is written to a temporary file beside `path`,
 * renamed over it only when complete. NULL (with the message printed) when the temporary file cannot be made. */
static FILE *begin_output(const char *path, mr_atomic_file *file) {
    mr_status status = mr_atomic_begin(path, file);
    FILE *f = status == MR_OK ? fopen(file->tmp_path, "w") : NULL;
    if (status != MR_OK)
        cli_fail("dataset", status);
    else if (f == NULL) {
        fprintf(stderr, "matremap dataset: error: cannot write '%s': %s\n", path, strerror(errno));
        mr_atomic_abort(file);
    }
    return f;
}

/* Close and commit what begin_output opened (abort on any write error). Returns an exit code. */
static int finish_output(FILE *f, mr_atomic_file *file) {
    int bad = ferror(f);
    if (fclose(f) != 0 || bad) {
        fprintf(stderr, "matremap dataset: error: cannot write '%s': %s\n", file->target, strerror(errno));
        mr_atomic_abort(file);
        return CLI_EXIT_BAD_INPUT;
    }
    mr_status status = mr_atomic_commit(file);
    return status == MR_OK ? CLI_EXIT_OK : cli_fail("dataset", status);
}

/* A label "converged" when its render matches the texel's within one 8-bit code (root mean square, in the
 * objective's display units); else "unreachable": the best metal-rough answer, which no metal-rough material
 * matches (e.g. a specular below the 0.04 every glTF dielectric reflects). `matremap train` keeps both. */
#define CONVERGED_LOSS (1.0 / (255.0 * 255.0))

static int write_pairs(const char *path, const pair *pairs, size_t n, const char *objective, uint64_t seed) {
    mr_atomic_file file;
    FILE *f = begin_output(path, &file);
    if (f == NULL) return CLI_EXIT_BAD_INPUT;
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
                p->result.kept_analytic, p->result.loss <= CONVERGED_LOSS ? "converged" : "unreachable");
    }
    return finish_output(f, &file);
}

/* ---- --compare ------------------------------------------------------------------------------------------------ */

/* The named hard cases (spec-gloss values; specular codes of the 8-bit dielectric band). */
typedef struct named_texel {
    const char *name;
    int diffuse[3], specular[3]; /* sRGB codes */
} named_texel;

static const named_texel hard_cases[] = {
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

typedef struct column {
    char name[96];
    double *ssim; /* per texel */
} column;

/* Converters in columns: label objectives (fitted under the synthetic lights), the analytic inverses (glTF
 * reading of the diffuse), networks. */
static int compare(pair *texels, size_t n, const char **names, const mr_image *const *envs, int env_count,
                   const char *const *weights, int weight_count, const mr_wf_label_options *label_opts,
                   const char *output, int json) {
    mr_wf_label_options eo = mr_wf_label_options_default();
    eo.size = 96;
    eo.env_count = env_count;
    for (int e = 0; e < env_count; e++) eo.envs[e] = envs[e];
    eo.glossiness_count = 3;
    eo.glossiness[0] = 0.3;
    eo.glossiness[1] = 0.6;
    eo.glossiness[2] = 0.9;
    mr_wf_label_scene *eval = NULL;
    mr_status status = mr_wf_label_scene_create(&eo, &eval);
    if (status != MR_OK) return cli_fail("dataset", status);
    column cols[MR_WF_OBJECTIVE_COUNT + 3 + MAX_WEIGHTS];
    int ncol = 0;
    mr_wf_metal *answers = malloc(n * sizeof *answers);
    float *dif = malloc(n * 3 * sizeof *dif), *spe = malloc(n * 3 * sizeof *spe);
    float *alb = malloc(n * 3 * sizeof *alb), *met = malloc(n * sizeof *met);
    if (answers == NULL || dif == NULL || spe == NULL || alb == NULL || met == NULL) {
        mr_clear_error(); // cli_fail then says "out of memory"
        status = MR_ERR_NOMEM;
    }
    for (size_t i = 0; status == MR_OK && i < n; i++)
        for (int c = 0; c < 3; c++) {
            dif[3 * i + c] = (float)texels[i].in.diffuse[c];
            spe[3 * i + c] = (float)texels[i].in.specular[c];
        }
    int total = MR_WF_OBJECTIVE_COUNT + 3 + weight_count;
    for (int k = MR_WF_OBJECTIVE_LINEAR; status == MR_OK && k < total; k++) { // every objective, then the rest
        column *col = &cols[ncol];
        col->ssim = malloc(n * sizeof *col->ssim);
        if (col->ssim == NULL) {
            mr_clear_error();
            status = MR_ERR_NOMEM;
            break;
        }
        ncol++;
        if (k < MR_WF_OBJECTIVE_COUNT) {
            mr_wf_label_options lo = *label_opts;
            lo.objective = (mr_wf_objective)k;
            mr_wf_label_scene *scene = NULL;
            snprintf(col->name, sizeof col->name, "labels: %s", mr_wf_objective_name(lo.objective));
            status = mr_wf_label_scene_create(&lo, &scene);
            if (status == MR_OK) status = label_pairs(scene, texels, n, col->name);
            for (size_t i = 0; i < n; i++) answers[i] = texels[i].label;
            mr_wf_label_scene_free(scene);
        } else {
            mr_wf_spec_input in = {dif, spe, NULL};
            mr_wf_metal_maps out = {alb, met, NULL};
            mr_wf_options o = mr_wf_options_default();
            o.spec_diffuse = MR_WF_DIFFUSE_SPECGLOSS;
            int a = k - MR_WF_OBJECTIVE_COUNT;
            if (a < 3) {
                static const mr_wf_method methods[3] = {MR_WF_WEIGHTED, MR_WF_MEAN, MR_WF_KHRONOS};
                o.method = methods[a];
                snprintf(col->name, sizeof col->name, "%s", mr_wf_method_name(o.method));
                status = mr_wf_spec_to_metal_batch(&in, n, &o, &out, NULL);
            } else {
                mr_mlp *net = NULL;
                const char *w = weights[a - 3];
                status = mr_mlp_read(w, &net);
                snprintf(col->name, sizeof col->name, "mlp %s", strrchr(w, '/') ? strrchr(w, '/') + 1 : w);
                if (status == MR_OK) status = mr_wf_spec_to_metal_mlp_batch(net, &in, n, &o, &out, NULL);
                mr_mlp_free(net);
            }
            for (size_t i = 0; status == MR_OK && i < n; i++) {
                for (int c = 0; c < 3; c++) answers[i].albedo[c] = alb[3 * i + c];
                answers[i].metallic = met[i];
            }
        }
#pragma omp parallel for schedule(dynamic, 8)
        for (size_t i = 0; i < n; i++) {
            if (status != MR_OK) continue;
            mr_status s = mr_wf_label_ssim(eval, &texels[i].in, &answers[i], &col->ssim[i]);
            if (s != MR_OK) {
#pragma omp critical(dataset_status)
                status = s;
            }
        }
    }
    mr_atomic_file file;
    FILE *f = status == MR_OK ? (output ? begin_output(output, &file) : stdout) : NULL;
    int code = status == MR_OK ? (f ? CLI_EXIT_OK : CLI_EXIT_BAD_INPUT) : cli_fail("dataset", status);
    if (f != NULL) {
        fprintf(f, "| texel | diffuse codes | specular codes |");
        for (int k = 0; k < ncol; k++) fprintf(f, " %s |", cols[k].name);
        fprintf(f, "\n|---|---|---|");
        for (int k = 0; k < ncol; k++) fprintf(f, "---:|");
        fprintf(f, "\n");
        for (size_t i = 0; i < (size_t)HARD_CASES && i < n; i++) {
            const named_texel *h = &hard_cases[i];
            fprintf(f, "| %s | %d,%d,%d | %d,%d,%d |", names[i], h->diffuse[0], h->diffuse[1], h->diffuse[2],
                    h->specular[0], h->specular[1], h->specular[2]);
            for (int k = 0; k < ncol; k++) fprintf(f, " %.4f |", cols[k].ssim[i]);
            fprintf(f, "\n");
        }
        for (int cat = 0; cat < CAT_COUNT; cat++) { /* the drawn texels by category */
            size_t count = 0;
            for (size_t i = (size_t)HARD_CASES; i < n; i++) count += texels[i].cat == (category)cat;
            if (count == 0) continue;
            fprintf(f, "| *drawn: %s, mean* (%zu) | | |", category_names[cat], count);
            for (int k = 0; k < ncol; k++) {
                double sum = 0.0;
                for (size_t i = (size_t)HARD_CASES; i < n; i++)
                    if (texels[i].cat == (category)cat) sum += cols[k].ssim[i];
                fprintf(f, " %.4f |", sum / (double)count);
            }
            fprintf(f, "\n");
        }
        const char *groups[3] = {"hard cases: mean", "all texels: mean", "all texels: worst"};
        for (int g = 0; g < 3; g++) {
            fprintf(f, "| **%s** (%zu) | | |", groups[g], g == 0 ? (size_t)HARD_CASES : n);
            for (int k = 0; k < ncol; k++) {
                double sum = 0.0, worst = 1.0;
                size_t count = g == 0 ? (size_t)HARD_CASES : n;
                for (size_t i = 0; i < count; i++) {
                    sum += cols[k].ssim[i];
                    worst = fmin(worst, cols[k].ssim[i]);
                }
                fprintf(f, " %.4f |", g == 2 ? worst : sum / (double)count);
            }
            fprintf(f, "\n");
        }
        if (output) code = finish_output(f, &file);
    }
    if (code == CLI_EXIT_OK && json) { // the columns' means and worsts over every texel, as the table's last rows
        printf("{\"command\": \"dataset --compare\", \"output\": ");
        cli_json_string(stdout, output);
        printf(", \"texels\": %zu, \"hard_cases\": %d, \"envs\": %d, \"columns\": [", n, HARD_CASES, env_count);
        for (int k = 0; k < ncol; k++) {
            double sum = 0.0, worst = 1.0;
            for (size_t i = 0; i < n; i++) {
                sum += cols[k].ssim[i];
                worst = fmin(worst, cols[k].ssim[i]);
            }
            printf("%s{\"name\": ", k ? ", " : "");
            cli_json_string(stdout, cols[k].name);
            printf(", \"mean_ssim\": %.6f, \"worst_ssim\": %.6f}", sum / (double)n, worst);
        }
        printf("]}\n");
    }
    for (int k = 0; k < ncol; k++) free(cols[k].ssim);
    free(answers);
    free(dif);
    free(spe);
    free(alb);
    free(met);
    mr_wf_label_scene_free(eval);
    return code;
}

int cmd_dataset(int argc, char **argv) {
    const char *output = NULL, *assets[MAX_ASSETS], *env_paths[MAX_ENVS], *weights[MAX_WEIGHTS];
    const char *label_env_paths[MAX_ENVS];
    int asset_count = 0, env_count = 0, label_env_count = 0, weight_count = 0;
    int samples = -1, seed = 1, threads = 0, do_compare = 0, json = 0;
    const double started = cli_now();
    mr_wf_label_options lo = mr_wf_label_options_default();
    for (int i = 1; i < argc; i++) {
        const char *value = NULL;
        int taken;
        if (cli_is_help(argv[i])) {
            print_help();
            return CLI_EXIT_OK;
        }
        if ((taken = cli_take_option("dataset", argc, argv, &i, "--output", &value)) ||
            (taken = cli_take_option("dataset", argc, argv, &i, "-o", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            output = value;
        } else if ((taken = cli_take_option("dataset", argc, argv, &i, "--samples", &value))) {
            if (taken < 0 || !cli_parse_int("dataset", "--samples", value, 1, 10000000, &samples))
                return CLI_EXIT_USAGE;
        } else if ((taken = cli_take_option("dataset", argc, argv, &i, "--seed", &value))) {
            if (taken < 0 || !cli_parse_int("dataset", "--seed", value, 0, 2147483647, &seed)) return CLI_EXIT_USAGE;
        } else if ((taken = cli_take_option("dataset", argc, argv, &i, "--objective", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            if (mr_wf_objective_from_name(value, &lo.objective) != MR_OK)
                return cli_usage_error("dataset", "--objective '%s': expected luma, exposed, display, log or linear",
                                       value);
        } else if ((taken = cli_take_option("dataset", argc, argv, &i, "--asset", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            if (asset_count == MAX_ASSETS) return cli_usage_error("dataset", "more than %d --asset files", MAX_ASSETS);
            assets[asset_count++] = value;
        } else if ((taken = cli_take_option("dataset", argc, argv, &i, "--env", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            if (env_count == MAX_ENVS) return cli_usage_error("dataset", "more than %d --env maps", MAX_ENVS);
            env_paths[env_count++] = value;
        } else if ((taken = cli_take_option("dataset", argc, argv, &i, "--label-env", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            if (label_env_count == MAX_ENVS)
                return cli_usage_error("dataset", "more than %d --label-env maps", MAX_ENVS);
            label_env_paths[label_env_count++] = value;
        } else if ((taken = cli_take_option("dataset", argc, argv, &i, "--weights", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            if (weight_count == MAX_WEIGHTS) return cli_usage_error("dataset", "more than %d --weights", MAX_WEIGHTS);
            weights[weight_count++] = value;
        } else if ((taken = cli_take_option("dataset", argc, argv, &i, "--size", &value))) {
            if (taken < 0 || !cli_parse_int("dataset", "--size", value, 16, 1024, &lo.size)) return CLI_EXIT_USAGE;
        } else if ((taken = cli_take_option("dataset", argc, argv, &i, "--regularisation", &value))) {
            if (taken < 0 || !cli_parse_double("dataset", "--regularisation", value, 0.0, 1.0, &lo.regularisation))
                return CLI_EXIT_USAGE;
            if (lo.regularisation == 0.0) lo.regularisation = MR_WF_LABEL_OFF; // 0 in the options: the default
        } else if ((taken = cli_take_option("dataset", argc, argv, &i, "--chroma-weight", &value))) {
            if (taken < 0 || !cli_parse_double("dataset", "--chroma-weight", value, 0.0, 100.0, &lo.chroma_weight))
                return CLI_EXIT_USAGE;
            if (lo.chroma_weight == 0.0) lo.chroma_weight = MR_WF_LABEL_OFF;
        } else if ((taken = cli_take_option("dataset", argc, argv, &i, "--threads", &value))) {
            if (taken < 0 || !cli_parse_int("dataset", "--threads", value, 0, 1024, &threads)) return CLI_EXIT_USAGE;
        } else if (strcmp(argv[i], "--compare") == 0) {
            do_compare = 1;
        } else if (strcmp(argv[i], "--json") == 0) {
            json = 1;
        } else {
            return cli_usage_error("dataset", "%s '%s'", argv[i][0] == '-' ? "unknown option" : "unexpected argument",
                                   argv[i]);
        }
    }
    if (!do_compare && output == NULL) return cli_usage_error("dataset", "missing -o PAIRS.csv");
    if (do_compare && env_count == 0) return cli_usage_error("dataset", "--compare needs at least one --env map");
    if (!do_compare && (env_count || weight_count))
        return cli_usage_error("dataset", "--env and --weights go with --compare");
    if (do_compare && json && output == NULL)
        return cli_usage_error("dataset", "--compare --json needs -o TABLE.md (the table; the JSON has its summary)");
    if (samples < 0) samples = do_compare ? 400 : 16000;
    if (threads > 0) omp_set_num_threads(threads);

    // Nothing written over a file read: -o against the maps, the networks and the assets with their files.
    cli_io io;
    cli_io_init(&io, "dataset");
    for (int e = 0; e < env_count; e++) cli_io_input(&io, env_paths[e], "--env %s", env_paths[e]);
    for (int e = 0; e < label_env_count; e++)
        cli_io_input(&io, label_env_paths[e], "--label-env %s", label_env_paths[e]);
    for (int w = 0; w < weight_count; w++) cli_io_input(&io, weights[w], "--weights %s", weights[w]);
    for (int a = 0; a < asset_count; a++) cli_io_input(&io, assets[a], "--asset %s", assets[a]);
    if (output != NULL) cli_io_output(&io, output, NULL);
    texel_pool pool = {NULL, 0, 0};
    int code = cli_io_check(&io);
    for (int a = 0; code == CLI_EXIT_OK && a < asset_count; a++)
        code = add_asset_texels(assets[a], (uint64_t)seed, &pool, &io);
    if (code == CLI_EXIT_OK) code = cli_io_check(&io); // with the assets' files
    cli_io_free(&io);
    size_t extra = do_compare ? (size_t)HARD_CASES : 0, n = extra + (size_t)samples;
    pair *pairs = code == CLI_EXIT_OK ? calloc(n, sizeof *pairs) : NULL;
    const char **names = code == CLI_EXIT_OK ? calloc(n, sizeof *names) : NULL;
    if (code == CLI_EXIT_OK && (pairs == NULL || names == NULL)) {
        fprintf(stderr, "matremap dataset: error: out of memory for %zu pairs\n", n);
        code = CLI_EXIT_INTERNAL;
    }
    for (size_t i = 0; code == CLI_EXIT_OK && i < n; i++) {
        if (i < extra) {
            for (int c = 0; c < 3; c++) {
                pairs[i].in.diffuse[c] = srgb_code(hard_cases[i].diffuse[c]);
                pairs[i].in.specular[c] = srgb_code(hard_cases[i].specular[c]);
            }
            names[i] = hard_cases[i].name;
            pairs[i].cat = CAT_UNIFORM;
        } else {
            pairs[i].cat = draw_texel((uint64_t)seed, i - extra, &pool, &pairs[i].in);
            names[i] = category_names[pairs[i].cat];
        }
    }
    free(pool.texels);
    mr_image *label_envs[MAX_ENVS] = {NULL};
    for (int e = 0; code == CLI_EXIT_OK && e < label_env_count; e++) {
        mr_img_read_options ro = {MR_IMG_DATA, 3, 0};
        mr_status status = mr_img_read(label_env_paths[e], &ro, &label_envs[e]);
        if (status == MR_OK) status = cli_check_radiance(label_envs[e], label_env_paths[e]);
        if (status != MR_OK) code = cli_fail("dataset", status);
        lo.envs[e] = label_envs[e];
        lo.env_count = e + 1;
    }
    if (code == CLI_EXIT_OK && do_compare) {
        mr_image *envs[MAX_ENVS] = {NULL};
        for (int e = 0; code == CLI_EXIT_OK && e < env_count; e++) {
            mr_img_read_options ro = {MR_IMG_DATA, 3, 0};
            mr_status status = mr_img_read(env_paths[e], &ro, &envs[e]);
            if (status == MR_OK) status = cli_check_radiance(envs[e], env_paths[e]);
            if (status != MR_OK) code = cli_fail("dataset", status);
        }
        if (code == CLI_EXIT_OK)
            code = compare(pairs, n, names, (const mr_image *const *)envs, env_count, weights, weight_count, &lo,
                           output, json);
        for (int e = 0; e < env_count; e++) mr_image_free(envs[e]);
    } else if (code == CLI_EXIT_OK) {
        mr_wf_label_scene *scene = NULL;
        mr_status status = mr_wf_label_scene_create(&lo, &scene);
        if (status == MR_OK) status = label_pairs(scene, pairs, n, "labels");
        mr_wf_label_scene_free(scene);
        code = status == MR_OK ? write_pairs(output, pairs, n, mr_wf_objective_name(lo.objective), (uint64_t)seed)
                               : cli_fail("dataset", status);
        if (code == CLI_EXIT_OK && json) {
            size_t converged = 0, per_category[CAT_COUNT] = {0};
            for (size_t i = 0; i < n; i++) {
                converged += pairs[i].result.loss <= CONVERGED_LOSS;
                per_category[pairs[i].cat]++;
            }
            printf("{\"command\": \"dataset\", \"output\": ");
            cli_json_string(stdout, output);
            printf(", \"pairs\": %zu, \"objective\": \"%s\", \"seed\": %d, \"assets\": %d, \"outcomes\": "
                   "{\"converged\": %zu, \"unreachable\": %zu}, \"categories\": {", n,
                   mr_wf_objective_name(lo.objective), seed, asset_count, converged, n - converged);
            for (int c = 0; c < CAT_COUNT; c++)
                printf("%s\"%s\": %zu", c ? ", " : "", category_names[c], per_category[c]);
            printf("}, \"seconds\": %.6f}\n", cli_now() - started);
        }
    }
    for (int e = 0; e < label_env_count; e++) mr_image_free(label_envs[e]);
    free(pairs);
    free(names);
    return code;
}
