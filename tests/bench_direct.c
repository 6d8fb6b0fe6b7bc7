/*
 * bench_direct.c — what the direct remap (src/remap/direct.h) costs on real texture sets, and how far its answers
 * stay from single remaps of the same texels (make bench; docs/performance.md, "Direct remaps").
 *
 * The sets: the shared spec-gloss texture sets (Avocado, FloppyDisk; 2048^2 PNGs) box-filtered to 1024^2 in their
 * stored 8-bit values and rounded to 8 bits again, as a 1024^2 PNG of the set would store them (the glTF files'
 * factors are not applied), then read as Ward SVBRDFs through a documented mapping, not a conversion: Ward's
 * diffuse = the diffuse texel, Ward's specular = the specular texel (both sRGB-decoded, by the library's rule for maps
 * of colour parameters), Ward's alpha = (1 - glossiness)^2 (glossiness linear, as the rule reads gltf-specgloss's;
 * floored at 1e-4 as the models floor it), Mitsuba's energy trimming on.
 * They are remapped into GGX (the paper's Mitsuba Ward -> Mitsuba GGX), AUTO, the default fit scene (64^2, light
 * at 45 degrees).
 *
 * Prints Markdown on stdout (progress on stderr); asserts nothing:
 *   1. distinct values per set and quantisation step t, for the Ward reading (alpha quantised in log space) and
 *      for the same texels as glTF spec-gloss (glossiness quantised linearly);
 *   2. the direct remap of each whole set at the default step on 2 threads: unique values, full / warm /
 *      fallback / shared-shape counts, wall time and CPU time (the machine may be shared: CPU time / 2 is what 2
 *      idle cores would take), outcomes; and the same with every shape fitted (fit_every_shape: no shared
 *      shapes), the answers' largest difference from the default run's;
 *   3. accuracy on seeded random texels of each set: the direct answer d against the full remap e of the exact
 *      (unquantised) texel and the full remap c of its quantised value: d - c is what the warm start adds,
 *      c - e what quantisation adds. Each as the largest parameter difference (reflectances absolute, alpha
 *      relative) and as the render difference (relative RMSE of the two answers' renders in the fit scene);
 *   4. the quantisation error c - e and the projected time against the step t, and for colours at 1/255 with
 *      roughness at 4/255 (roughness_tolerance).
 * Usage: bench_direct SPECGLOSS_DIR [--quick] (--quick: a 256^2 centre crop of each set, fewer samples).
 */
#include <math.h>
#include <omp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bench_util.h"
#include "io/io_internal.h"
#include "matremap.h"

#define STEP_COUNT 7
/* t = steps[i] / 255, roughness at roughness_steps[i] / 255 */
static const int steps[STEP_COUNT] = {1, 1, 2, 3, 4, 6, 8}, roughness_steps[STEP_COUNT] = {1, 4, 2, 3, 4, 6, 8};
#define MAX_SAMPLES 200

typedef struct texture_set {
    const char *name;
    const char *diffuse, *specgloss; /* under SPECGLOSS_DIR */
} texture_set;

static const texture_set sets[] = {
    {"Avocado", "Avocado-pbrSpecularGlossiness/glTF-pbrSpecularGlossiness/Avocado_diffuse.png",
     "Avocado-pbrSpecularGlossiness/glTF-pbrSpecularGlossiness/Avocado_specularGlossiness.png"},
    {"FloppyDisk", "FloppyDisk-sketchfab/textures/material_0_diffuse.png",
     "FloppyDisk-sketchfab/textures/material_0_specularGlossiness.png"},
};
#define SET_COUNT ((int)(sizeof sets / sizeof sets[0]))

static double cpu_now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void fail(const char *what) {
    fprintf(stderr, "bench_direct: %s: %s\n", what, mr_last_error());
    exit(3);
}

/* The set's texels as 8-bit codes (diffuse RGB, specular RGB, glossiness), `side`^2 of them: the 2048^2 files box
 * filtered by `factor` in their stored values and rounded, cropped to the centre when `side` is smaller. */
static unsigned char *load_codes(const char *dir, const texture_set *set, int side) {
    char path[2][1024];
    snprintf(path[0], sizeof path[0], "%s/%s", dir, set->diffuse);
    snprintf(path[1], sizeof path[1], "%s/%s", dir, set->specgloss);
    mr_image *img[2];
    for (int f = 0; f < 2; f++) {
        mr_img_read_options o = {MR_IMG_DATA, 0, 0}; // the stored values: codes / 255
        if (mr_img_read(path[f], &o, &img[f]) != MR_OK) fail(path[f]);
    }
    const int w = img[0]->width, factor = w / 1024 > 0 ? w / 1024 : 1, full = w / factor;
    const int x0 = (full - side) / 2, y0 = (full - side) / 2;
    unsigned char *codes = malloc((size_t)side * side * 7);
    for (int y = 0; y < side; y++)
        for (int x = 0; x < side; x++) {
            double sum[7] = {0};
            for (int dy = 0; dy < factor; dy++)
                for (int dx = 0; dx < factor; dx++) {
                    const size_t at = (size_t)((y0 + y) * factor + dy) * (size_t)w + (size_t)((x0 + x) * factor + dx);
                    for (int c = 0; c < 3; c++) {
                        sum[c] += img[0]->pixels[at * (size_t)img[0]->channels + (size_t)c];
                        sum[3 + c] += img[1]->pixels[at * (size_t)img[1]->channels + (size_t)c];
                    }
                    sum[6] += img[1]->pixels[at * (size_t)img[1]->channels + 3];
                }
            for (int c = 0; c < 7; c++)
                codes[((size_t)y * side + x) * 7 + c] = (unsigned char)lround(255.0 * sum[c] / (factor * factor));
        }
    mr_image_free(img[0]);
    mr_image_free(img[1]);
    return codes;
}

/* The value an 8-bit map of parameter `index` of `model` holds at `code`, by the library's one rule for maps
 * (mr_brdf_param_map_encoding: sRGB-decoded for colour parameters, linear for the rest), as mr_img_read_param_map
 * would read it. */
static double map_value(const mr_brdf_model *model, int index, unsigned char code) {
    const double stored = code / 255.0;
    return mr_brdf_param_map_encoding(&model->params[index], MR_MAP_AS_PARAMETER) == MR_IMG_COLOR
               ? mr_srgb_decode_double(stored)
               : stored;
}

/* The Ward reading of the codes (the header comment), packed for model "ward": diffuse and specular as maps of
 * Ward's parameters, glossiness as a map of glTF spec-gloss's. */
static double *ward_texels(const mr_brdf_model *ward, const mr_brdf_model *sg, const unsigned char *codes, size_t n) {
    const int nv = mr_brdf_value_count(ward);
    const int di = mr_brdf_param_index(ward, "diffuse"), si = mr_brdf_param_index(ward, "specular");
    const int d = mr_brdf_param_offset(ward, di), s = mr_brdf_param_offset(ward, si);
    const int a = mr_brdf_param_offset(ward, mr_brdf_param_index(ward, "alpha"));
    const int gi = mr_brdf_param_index(sg, "glossiness");
    double *v = malloc(n * (size_t)nv * sizeof *v);
    for (size_t i = 0; i < n; i++) {
        double *t = v + i * (size_t)nv;
        mr_brdf_default_values(ward, t); // trim = 1
        for (int c = 0; c < 3; c++) {
            t[d + c] = map_value(ward, di, codes[i * 7 + (size_t)c]);
            t[s + c] = map_value(ward, si, codes[i * 7 + 3 + (size_t)c]);
        }
        const double r = 1.0 - map_value(sg, gi, codes[i * 7 + 6]);
        t[a] = fmax(r * r, 1e-4);
    }
    return v;
}

/* The same texels as glTF spec-gloss values (diffuse, specular, glossiness: the model's parameters in table order,
 * each read as a map of it). */
static double *specgloss_texels(const mr_brdf_model *sg, const unsigned char *codes, size_t n) {
    const int nv = mr_brdf_value_count(sg);
    double *v = malloc(n * (size_t)nv * sizeof *v);
    for (size_t i = 0; i < n; i++)
        for (int c = 0; c < 7; c++)
            v[i * (size_t)nv + (size_t)c] = map_value(sg, c < 3 ? 0 : c < 6 ? 1 : 2, codes[i * 7 + (size_t)c]);
    return v;
}

static size_t row_bytes; /* count_unique's comparator: the width of a row */

static int compare_rows(const void *a, const void *b) { return memcmp(a, b, row_bytes); }

/* Distinct quantised vectors among n texels of m at step t (what mr_direct_remap's summary calls `unique`). */
static size_t count_unique(const mr_brdf_model *m, const double *v, size_t n, double t, double t_r) {
    const int nv = mr_brdf_value_count(m);
    double *q = malloc(n * (size_t)nv * sizeof *q);
    for (size_t i = 0; i < n; i++)
        if (mr_direct_quantise_steps(m, t, t_r, v + i * (size_t)nv, q + i * (size_t)nv) != MR_OK) fail("quantise");
    row_bytes = (size_t)nv * sizeof *q;
    qsort(q, n, row_bytes, compare_rows);
    size_t unique = n > 0;
    for (size_t i = 1; i < n; i++) unique += memcmp(q + i * (size_t)nv, q + (i - 1) * (size_t)nv, row_bytes) != 0;
    free(q);
    return unique;
}

/* How far answer a is from the reference b (target vectors): *params the largest parameter difference (a
 * log-scale parameter relative, the others absolute), *image the relative RMSE of a's render against b's in the
 * fit scene (over the pixels the sphere covers, relative to b's RMS radiance). */
static void difference(const mr_render_plan *plan, const mr_brdf_model *m, const double *a, const double *b,
                       double *params, double *image) {
    *params = 0.0;
    for (int i = 0, slot = 0; i < m->param_count; slot += m->params[i].channels, i++) {
        const mr_brdf_param *p = &m->params[i];
        if (p->role == MR_PARAM_SWITCH) continue;
        for (int c = 0; c < p->channels; c++) {
            const double x = a[slot + c], y = b[slot + c];
            const double d = (p->flags & MR_PARAM_LOG_SCALE) ? fabs(x - y) / y : fabs(x - y);
            *params = fmax(*params, d);
        }
    }
    *image = 0.0;
    if (plan == NULL) return; // parameters only
    mr_image *ra = NULL, *rb = NULL;
    if (mr_render(plan, m, a, MR_COMPONENT_FULL, &ra) != MR_OK) fail("render");
    if (mr_render(plan, m, b, MR_COMPONENT_FULL, &rb) != MR_OK) fail("render");
    *image = bench_relative_rmse(plan, ra, rb);
    mr_image_free(ra);
    mr_image_free(rb);
}

static double quantile(double *v, int n, double q) {
    qsort(v, (size_t)n, sizeof v[0], bench_compare_doubles);
    int rank = (int)ceil(q * n) - 1;
    return v[rank < 0 ? 0 : rank >= n ? n - 1 : rank];
}

static void remap_or_fail(const mr_render_plan *plan, const mr_brdf_model *s, const double *v,
                          const mr_brdf_model *t, double *out) {
    mr_remap_options o = mr_remap_options_default();
    mr_remap_result r;
    if (mr_remap(plan, s, v, t, &o, &r) != MR_OK) fail("remap");
    memcpy(out, r.values, (size_t)mr_brdf_value_count(t) * sizeof *out);
}

static double progress_start;

static void progress(const mr_direct_progress *p, void *user) {
    (void)user;
    if (p->done % 500 == 0 || p->done == p->total)
        fprintf(stderr, "\r  %zu / %zu unique values, %.0f s", p->done, p->total, bench_now() - progress_start);
    if (p->done == p->total) fputc('\n', stderr);
}

/* splitmix64: the sampled texels, the same in every run. */
static uint64_t next_random(uint64_t *state) {
    uint64_t z = (*state += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

typedef struct set_result {
    size_t texels, unique[STEP_COUNT], unique_specgloss[STEP_COUNT];
    mr_direct_summary run, own;
    double wall, cpu, own_wall, own_cpu;
    double own_difference[2]; /* largest parameter difference over texels converged in both runs, and the rest */
    /* per sample: d-c, c-e, d-e as (params, image) */
    double warm_params[MAX_SAMPLES], warm_image[MAX_SAMPLES], quant_params[MAX_SAMPLES], quant_image[MAX_SAMPLES];
    double total_params[MAX_SAMPLES], total_image[MAX_SAMPLES];
    double step_image[STEP_COUNT][MAX_SAMPLES], step_params[STEP_COUNT][MAX_SAMPLES];
    int samples, step_samples;
} set_result;

int main(int argc, char **argv) {
    if (argc < 2) {
        fprintf(stderr, "usage: bench_direct SPECGLOSS_DIR [--quick]\n");
        return 1;
    }
    const int quick = argc > 2 && strcmp(argv[2], "--quick") == 0;
    const int side = quick ? 256 : 1024, samples = quick ? 40 : MAX_SAMPLES, step_samples = quick ? 20 : 120;
    const mr_brdf_model *ward = mr_brdf_find("ward"), *ggx = mr_brdf_find("ggx");
    const mr_brdf_model *sg = mr_brdf_find("gltf-specgloss");
    if (ward == NULL || ggx == NULL || sg == NULL) return 3;
    const int nw = mr_brdf_value_count(ward), ng = mr_brdf_value_count(ggx);
    mr_scene scene = mr_scene_fit(&(mr_fit_scene_options){MR_REMAP_DEFAULT_SIZE, MR_FIT_LIGHT_45, 0});
    mr_render_plan *plan = NULL;
    if (mr_render_plan_create(&scene, &plan) != MR_OK) fail("plan");
    static set_result results[SET_COUNT];
    for (int s = 0; s < SET_COUNT; s++) {
        set_result *r = &results[s];
        fprintf(stderr, "%s: loading\n", sets[s].name);
        unsigned char *codes = load_codes(argv[1], &sets[s], side);
        const size_t n = (size_t)side * side;
        r->texels = n;
        double *texels = ward_texels(ward, sg, codes, n), *as_sg = specgloss_texels(sg, codes, n);
        for (int k = 0; k < STEP_COUNT; k++) {
            r->unique[k] = count_unique(ward, texels, n, steps[k] / 255.0, roughness_steps[k] / 255.0);
            r->unique_specgloss[k] = count_unique(sg, as_sg, n, steps[k] / 255.0, roughness_steps[k] / 255.0);
        }
        // The whole set, default options, 2 threads.
        double *out = malloc(n * (size_t)ng * sizeof *out);
        mr_direct_options o;
        memset(&o, 0, sizeof o);
        o.threads = 2;
        o.progress = progress;
        progress_start = bench_now();
        const double wall0 = bench_now(), cpu0 = cpu_now();
        mr_fit_outcome *outcomes = malloc(n * sizeof *outcomes), *own_outcomes = malloc(n * sizeof *own_outcomes);
        if (mr_direct_remap(ward, ggx, texels, n, &o, out, outcomes, &r->run) != MR_OK) fail("direct remap");
        r->wall = bench_now() - wall0;
        r->cpu = cpu_now() - cpu0;
        // Every shape fitted (no shared shapes): what sharing saves, and how far its answers move.
        double *own = malloc(n * (size_t)ng * sizeof *own);
        o.fit_every_shape = 1;
        progress_start = bench_now();
        const double own_wall0 = bench_now(), own_cpu0 = cpu_now();
        if (mr_direct_remap(ward, ggx, texels, n, &o, own, own_outcomes, &r->own) != MR_OK) fail("direct remap");
        r->own_wall = bench_now() - own_wall0;
        r->own_cpu = cpu_now() - own_cpu0;
        r->own_difference[0] = r->own_difference[1] = 0.0;
        for (size_t i = 0; i < n; i++) {
            double params, image;
            difference(NULL, ggx, out + i * (size_t)ng, own + i * (size_t)ng, &params, &image);
            const int converged = outcomes[i] == MR_FIT_CONVERGED && own_outcomes[i] == MR_FIT_CONVERGED;
            r->own_difference[!converged] = fmax(r->own_difference[!converged], params);
        }
        free(own);
        free(outcomes);
        free(own_outcomes);
        // Accuracy on seeded random texels; their remaps on 2 threads, one each.
        uint64_t state = 0xd1ec7ULL + (uint64_t)s;
        size_t picked[MAX_SAMPLES];
        for (int i = 0; i < samples; i++) picked[i] = (size_t)(next_random(&state) % n);
        r->samples = samples;
        r->step_samples = step_samples;
        fprintf(stderr, "%s: %d single remaps of sampled texels\n", sets[s].name,
                samples * 2 + step_samples * STEP_COUNT * 2);
#pragma omp parallel for schedule(dynamic) num_threads(2)
        for (int i = 0; i < samples; i++) {
            const double *x = texels + picked[i] * (size_t)nw, *d = out + picked[i] * (size_t)ng;
            double q[MR_BRDF_MAX_VALUES], c[MR_BRDF_MAX_VALUES], e[MR_BRDF_MAX_VALUES];
            if (mr_direct_quantise(ward, 0.0, x, q) != MR_OK) fail("quantise");
            remap_or_fail(plan, ward, q, ggx, c);
            remap_or_fail(plan, ward, x, ggx, e);
            difference(plan, ggx, d, c, &r->warm_params[i], &r->warm_image[i]);
            difference(plan, ggx, c, e, &r->quant_params[i], &r->quant_image[i]);
            difference(plan, ggx, d, e, &r->total_params[i], &r->total_image[i]);
        }
#pragma omp parallel for schedule(dynamic) num_threads(2) collapse(2)
        for (int k = 0; k < STEP_COUNT; k++)
            for (int i = 0; i < step_samples; i++) {
                const double *x = texels + picked[i] * (size_t)nw;
                double q[MR_BRDF_MAX_VALUES], c[MR_BRDF_MAX_VALUES], e[MR_BRDF_MAX_VALUES];
                if (mr_direct_quantise_steps(ward, steps[k] / 255.0, roughness_steps[k] / 255.0, x, q) != MR_OK)
                    fail("quantise");
                remap_or_fail(plan, ward, q, ggx, c);
                remap_or_fail(plan, ward, x, ggx, e);
                difference(plan, ggx, c, e, &r->step_params[k][i], &r->step_image[k][i]);
            }
        free(out);
        free(texels);
        free(as_sg);
        free(codes);
    }
    mr_render_plan_free(plan);

    printf("Texture sets: the shared spec-gloss sets box-filtered to %d^2 8-bit texels%s, read as Mitsuba Ward "
           "SVBRDFs (diffuse and specular = the sRGB-decoded texels, alpha = (1 - glossiness)^2, trimming on) and "
           "remapped into GGX (AUTO, %d^2 fit scene, light at 45 degrees). Step t: colours quantised in steps of t "
           "in sRGB-encoded units, alpha in steps of t in ln alpha (src/remap/direct.h).\n\n",
           side, quick ? " (a centre crop: --quick)" : "", MR_REMAP_DEFAULT_SIZE);
    printf("**Distinct values against the step t** (the Ward reading; in brackets the same texels read as glTF "
           "spec-gloss, whose glossiness is quantised linearly)\n\n| set | texels |");
    for (int k = 0; k < STEP_COUNT; k++)
        if (steps[k] == roughness_steps[k])
            printf(" t = %d/255 |", steps[k]);
        else
            printf(" t = %d/255, roughness %d/255 |", steps[k], roughness_steps[k]);
    printf("\n|---|---:|");
    for (int k = 0; k < STEP_COUNT; k++) printf("---:|");
    printf("\n");
    for (int s = 0; s < SET_COUNT; s++) {
        printf("| %s | %zu |", sets[s].name, results[s].texels);
        for (int k = 0; k < STEP_COUNT; k++)
            printf(" %zu (%zu) |", results[s].unique[k], results[s].unique_specgloss[k]);
        printf("\n");
    }
    printf("\n**The direct remap of each set** (default step t = %.4g = %.0f/255, chains of %d, 2 threads). CPU s / 2 "
           "is the time on 2 idle cores (this machine may be shared); outcomes of the unique values: converged / "
           "at-bound / unreachable / local-minimum / under-resolved.\n\n",
           MR_DIRECT_DEFAULT_TOLERANCE, MR_DIRECT_DEFAULT_TOLERANCE * 255.0, MR_DIRECT_DEFAULT_CHAIN);
    printf("| set | shapes | texels | unique | full | warm | fallbacks | shared shapes | renders / remap | wall s | "
           "CPU s | CPU s / 2 | ms CPU / unique | outcomes |\n"
           "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|\n");
    for (int s = 0; s < SET_COUNT; s++)
        for (int own = 0; own < 2; own++) {
            const set_result *r = &results[s];
            const mr_direct_summary *m = own ? &r->own : &r->run;
            const double cpu = own ? r->own_cpu : r->cpu, wall = own ? r->own_wall : r->wall;
            printf("| %s | %s | %zu | %zu | %zu | %zu | %zu | %zu | %.1f | %.1f | %.1f | %.1f | %.2f | "
                   "%zu / %zu / %zu / %zu / %zu |\n",
                   sets[s].name, own ? "each fitted" : "shared", m->texels, m->unique, m->full, m->warm,
                   m->fallbacks, m->shared_shapes, m->remaps ? (double)m->renders / (double)m->remaps : 0.0, wall,
                   cpu, cpu / 2.0, m->unique ? 1e3 * cpu / (double)m->unique : 0.0, m->outcomes[0], m->outcomes[1],
                   m->outcomes[2], m->outcomes[3], m->outcomes[4]);
        }
    printf("\nShared shapes against every shape fitted: the answers' largest parameter difference (F0 and diffuse "
           "absolute, alpha relative) over the texels converged in both runs, and over the others (under-resolved: "
           "a lobe narrower than the pixels, whose alpha the image barely fixes):");
    for (int s = 0; s < SET_COUNT; s++)
        printf(" %s %.2g, %.2g%s", sets[s].name, results[s].own_difference[0], results[s].own_difference[1],
               s + 1 < SET_COUNT ? ";" : ".\n");
    printf("\n**Accuracy on sampled texels** (%d seeded random texels per set): d the direct answer, c the full remap "
           "of the texel's quantised value, e the full remap of the exact texel. *params*: the largest parameter "
           "difference (F0 and diffuse absolute, alpha relative); *image*: the relative RMSE of the two answers' "
           "renders in the fit scene. Median / 90th percentile / max.\n\n",
           samples);
    printf("| set | warm start d - c: params | d - c: image | quantisation c - e: params | c - e: image | "
           "together d - e: params | d - e: image |\n|---|---|---|---|---|---|---|\n");
    for (int s = 0; s < SET_COUNT; s++) {
        set_result *r = &results[s];
        double *columns[6] = {r->warm_params, r->warm_image, r->quant_params, r->quant_image, r->total_params,
                              r->total_image};
        printf("| %s |", sets[s].name);
        for (int c = 0; c < 6; c++)
            printf(" %.2g / %.2g / %.2g |", quantile(columns[c], r->samples, 0.5),
                   quantile(columns[c], r->samples, 0.9), quantile(columns[c], r->samples, 1.0));
        printf("\n");
    }
    printf("\n**The step t: quantisation error and projected time** (quantisation error c - e over %d sampled texels "
           "per set, image relative RMSE median / 90th percentile / max; time projected from the measured CPU ms per "
           "unique value at the default step, on 2 cores)\n\n| t |",
           step_samples);
    for (int s = 0; s < SET_COUNT; s++) printf(" %s: c - e image | params | projected s |", sets[s].name);
    printf("\n|---|");
    for (int s = 0; s < SET_COUNT; s++) printf("---|---|---:|");
    printf("\n");
    for (int k = 0; k < STEP_COUNT; k++) {
        if (steps[k] == roughness_steps[k])
            printf("| %d/255 |", steps[k]);
        else
            printf("| %d/255, roughness %d/255 |", steps[k], roughness_steps[k]);
        for (int s = 0; s < SET_COUNT; s++) {
            set_result *r = &results[s];
            const double per_unique = r->run.unique ? r->cpu / (double)r->run.unique : 0.0;
            printf(" %.2g / %.2g / %.2g | %.2g / %.2g | %.0f |", quantile(r->step_image[k], r->step_samples, 0.5),
                   quantile(r->step_image[k], r->step_samples, 0.9), quantile(r->step_image[k], r->step_samples, 1.0),
                   quantile(r->step_params[k], r->step_samples, 0.5),
                   quantile(r->step_params[k], r->step_samples, 1.0), per_unique * (double)r->unique[k] / 2.0);
        }
        printf("\n");
    }
    return 0;
}
