/*
 * bench_fit.c — the fit engine's speed and its answers, pair by pair (make bench; docs/performance.md, "The fit
 * engine").
 *
 * For seeded random source materials per model pair, remaps each at the default 64^2 fit scene (AUTO, defaults,
 * one thread, the plan built once and reused, as a sweep runs them) and prints per pair the median and p90 time of
 * the whole mr_remap call, the median renders and the outcomes. With --save FILE it writes every remap's answer
 * (outcome, relative RMSE, renders, ms, fitted values); with --against FILE it compares this build's answers with
 * such a file, material by material: the largest |Δ relative RMSE|, the outcomes that changed, and the median
 * ratios of renders and time. That is how a change of the engine shows "the same answers in fewer renders".
 * Asserts nothing (the timed figures live here, not in tests).
 *
 * Usage: bench_fit [--quick] [--pairs a,b,...] [--local auto|gradient|bobyqa] [--material N] [--table] [--save FILE]
 *                  [--against FILE] [--precision double|float]
 *   --quick   8 materials per pair (4 for the slow ones)
 *   --pairs   only these pair names (as printed: "ward>ggx", "ggx>ward", ...)
 *   --local   the fits' local method (mr_remap_options.local_method; default auto)
 *   --material N  only material N of each pair (to look at one fit; its source values go to stderr)
 *   --table   instead: what accuracy costs in time, per pair, fit size (32, 64, 128) and local method (gradient,
 *             bobyqa): median renders and ms, the floor (renders x the measured time of one render of the target at
 *             that size), and the fits judged at 512^2 (mean |ΔSSIM| against the gradient fit at 128^2); with a
 *             precision axis for pairs whose target has a float kernel (src/brdf/brdf_float.h): every fit again
 *             with the plan's renders in float (render_internal.h, mr_render_plan_set_float_kernels; the 512^2
 *             judge stays double), and a second table of what float changed against double, fit by fit: the
 *             largest |Δ relative RMSE|, outcomes changed, the time ratio, and one render of the target in each
 *             precision
 *   --precision float   the remaps' plan renders with the float kernels (models without one stay double): with
 *             --against, how far a float engine's answers move from the reference
 *   --kernels instead: ns per direction pair of the batch kernels alone, double against float, portable and
 *             AVX2/FMA, for the models with a float kernel (batches of 256 fit-scene-like pairs, best of 31 runs),
 *             and the median ms of one 64^2 fit-scene render (defaults, the AUTO path) in each precision
 */
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench_util.h"
#include "brdf/brdf_float.h"
#include "matremap.h"
#include "remap/remap.h"
#include "render/render_internal.h"

#define MAX_MATERIALS 50
#define FIT_SIZE 64

/* A source model, how its random materials are drawn, a target, and how many materials. */
typedef struct pair {
    const char *name;     /* "source>target", with a suffix for a variant */
    const char *source, *target;
    const char *draw;     /* ward | microfacet | glossy | gltf */
    int materials;
} pair;

static const pair pairs[] = {
    {"ward>ggx", "ward", "ggx", "ward", 50},
    {"ggx>ward", "ggx", "ward", "microfacet", 50},
    {"as>ward", "as", "ward", "microfacet", 50},
    {"ggx>ward(glossy)", "ggx", "ward", "glossy", 30},
    {"ward>gltf", "ward", "gltf", "ward", 50},
    {"gltf>ward", "gltf", "ward", "gltf", 50},
    {"ggx>ggx-metallic", "ggx", "ggx-metallic", "microfacet", 30},
    {"ward>blender-ward", "ward", "blender-ward", "ward", 30},
    {"gltf>cycles-principled", "gltf", "cycles-principled", "gltf", 16},
    {"gltf>usd-preview", "gltf", "usd-preview", "gltf", 16},
    {"gltf>standard-surface", "gltf", "standard-surface", "gltf", 8},
    {"gltf>openpbr", "gltf", "openpbr", "gltf", 8},
    {"gltf>blender-principled", "gltf", "blender-principled", "gltf", 8},
};
#define PAIR_COUNT ((int)(sizeof pairs / sizeof pairs[0]))

/* One remap's answer. */
typedef struct answer {
    double ms, rel, values[MR_BRDF_MAX_VALUES];
    long renders;
    int outcome, value_count;
} answer;

static double quantile(double *v, int n, double q) {
    qsort(v, (size_t)n, sizeof v[0], bench_compare_doubles);
    int rank = (int)ceil(q * n) - 1;
    return v[rank < 0 ? 0 : rank >= n ? n - 1 : rank];
}

static int wanted(const char *list, const char *name) {
    if (list == NULL) return 1;
    size_t n = strlen(name);
    for (const char *at = list; (at = strstr(at, name)) != NULL; at += n)
        if ((at == list || at[-1] == ',') && (at[n] == ',' || at[n] == '\0')) return 1;
    return 0;
}

/* Read a --save file into reference[pair][material]; returns 0 on a malformed file. */
static int read_reference(const char *path, answer reference[PAIR_COUNT][MAX_MATERIALS],
                          int have[PAIR_COUNT][MAX_MATERIALS]) {
    FILE *f = fopen(path, "r");
    if (f == NULL) return 0;
    char name[64];
    int material;
    answer a;
    while (fscanf(f, "%63s %d %d %lf %ld %lf %d", name, &material, &a.outcome, &a.rel, &a.renders, &a.ms,
                  &a.value_count) == 7) {
        if (a.value_count > MR_BRDF_MAX_VALUES || material < 0 || material >= MAX_MATERIALS) break;
        for (int v = 0; v < a.value_count; v++)
            if (fscanf(f, "%lf", &a.values[v]) != 1) return fclose(f), 0;
        for (int p = 0; p < PAIR_COUNT; p++)
            if (strcmp(pairs[p].name, name) == 0) {
                reference[p][material] = a;
                have[p][material] = 1;
            }
    }
    fclose(f);
    return 1;
}

/* ---- --table: fit size x local method ---------------------------------------------------------------------- */

#define TABLE_SIZES 3
#define TABLE_METHODS 2
static const int table_sizes[TABLE_SIZES] = {32, 64, 128};
static const mr_local_method table_methods[TABLE_METHODS] = {MR_LOCAL_GRADIENT, MR_LOCAL_BOBYQA};

static mr_render_plan *plan_of_size(int size) {
    mr_scene scene = mr_scene_fit(&(mr_fit_scene_options){size, MR_FIT_LIGHT_45, 0});
    mr_render_plan *plan = NULL;
    if (mr_render_plan_create(&scene, &plan) != MR_OK) {
        fprintf(stderr, "bench_fit: %s\n", mr_last_error());
        exit(3);
    }
    return plan;
}

/* Median ms of one full render of `model` at its defaults (the floor's unit). */
static double render_ms(const mr_render_plan *plan, const mr_brdf_model *model, mr_image *scratch) {
    double values[MR_BRDF_MAX_VALUES], t[15];
    mr_brdf_default_values(model, values);
    for (int k = 0; k < 15; k++) {
        double t0 = bench_now();
        if (mr_render_into(plan, model, values, MR_COMPONENT_FULL, scratch) != MR_OK) exit(3);
        t[k] = 1e3 * (bench_now() - t0);
    }
    return quantile(t, 15, 0.5);
}

/* SSIM at 512^2 of the target's values against the source's 512^2 render. */
static double ssim_512(const mr_render_plan *plan512, const mr_brdf_model *target, const double *values,
                       const mr_image *source512, mr_image *scratch512) {
    double ssim;
    if (mr_render_into(plan512, target, values, MR_COMPONENT_FULL, scratch512) != MR_OK ||
        mr_ssim(scratch512, source512, NULL, &ssim, NULL) != MR_OK) {
        fprintf(stderr, "bench_fit: %s\n", mr_last_error());
        exit(3);
    }
    return ssim;
}

#define TABLE_PRECISIONS 2 /* double, float */
static const char *const precision_names[TABLE_PRECISIONS] = {"double", "float"};

static int run_table(int quick, const char *only) {
    mr_render_plan *plans[TABLE_PRECISIONS][TABLE_SIZES], *plan512 = plan_of_size(512);
    mr_image *scratch[TABLE_SIZES], *source512 = NULL, *scratch512 = NULL;
    for (int z = 0; z < TABLE_SIZES; z++) {
        for (int q = 0; q < TABLE_PRECISIONS; q++) {
            plans[q][z] = plan_of_size(table_sizes[z]);
            mr_render_plan_set_float_kernels(plans[q][z], q);
        }
        if (mr_image_create(table_sizes[z], table_sizes[z], 3, &scratch[z]) != MR_OK) return 3;
    }
    if (mr_image_create(512, 512, 3, &source512) != MR_OK || mr_image_create(512, 512, 3, &scratch512) != MR_OK)
        return 3;
    // Float against double, fit by fit, printed after the main table.
    static char compare[PAIR_COUNT * TABLE_SIZES * TABLE_METHODS][200];
    int compare_rows = 0;
    printf("| pair | size | local | precision | materials | median renders | median ms | floor ms | "
           "mean ΔSSIM@512 (max) | outcomes |\n|---|---:|---|---|---:|---:|---:|---:|---:|---|\n");
    for (int p = 0; p < PAIR_COUNT; p++) {
        if (!wanted(only, pairs[p].name)) continue;
        const mr_brdf_model *source = mr_brdf_find(pairs[p].source), *target = mr_brdf_find(pairs[p].target);
        if (source == NULL || target == NULL) return 3;
        const int precisions = mr_brdf_float_kernel(target) != NULL ? TABLE_PRECISIONS : 1;
        const int n = quick ? 2 : (pairs[p].materials >= 16 ? 8 : 4);
        static double ms[TABLE_PRECISIONS][TABLE_SIZES][TABLE_METHODS][MAX_MATERIALS];
        static double renders[TABLE_PRECISIONS][TABLE_SIZES][TABLE_METHODS][MAX_MATERIALS];
        static double ssim[TABLE_PRECISIONS][TABLE_SIZES][TABLE_METHODS][MAX_MATERIALS];
        static double rel[TABLE_PRECISIONS][TABLE_SIZES][TABLE_METHODS][MAX_MATERIALS];
        static int outcome[TABLE_PRECISIONS][TABLE_SIZES][TABLE_METHODS][MAX_MATERIALS];
        unsigned long long state = 0x31ULL + (unsigned long long)p; // the same materials as the pair's first ones
        for (int i = 0; i < n; i++) {
            double values[MR_BRDF_MAX_VALUES];
            bench_random_material(pairs[p].draw, source, &state, values);
            if (mr_render_into(plan512, source, values, MR_COMPONENT_FULL, source512) != MR_OK) return 3;
            for (int q = 0; q < precisions; q++)
                for (int z = 0; z < TABLE_SIZES; z++)
                    for (int k = 0; k < TABLE_METHODS; k++) {
                        mr_remap_options o = mr_remap_options_default();
                        o.local_method = table_methods[k];
                        mr_remap_result r;
                        double t0 = bench_now();
                        if (mr_remap(plans[q][z], source, values, target, &o, &r) != MR_OK) {
                            fprintf(stderr, "bench_fit: %s #%d: %s\n", pairs[p].name, i, mr_last_error());
                            return 3;
                        }
                        ms[q][z][k][i] = 1e3 * (bench_now() - t0);
                        renders[q][z][k][i] = (double)r.renders;
                        rel[q][z][k][i] = r.relative_rmse;
                        outcome[q][z][k][i] = (int)r.outcome;
                        ssim[q][z][k][i] = ssim_512(plan512, target, r.values, source512, scratch512);
                    }
        }
        for (int z = 0; z < TABLE_SIZES; z++) {
            double one_render[TABLE_PRECISIONS] = {0.0, 0.0};
            for (int q = 0; q < precisions; q++) one_render[q] = render_ms(plans[q][z], target, scratch[z]);
            for (int q = 0; q < precisions; q++)
                for (int k = 0; k < TABLE_METHODS; k++) {
                    double mean = 0.0, worst = 0.0, r[MAX_MATERIALS], t[MAX_MATERIALS];
                    int c[MR_FIT_OUTCOME_COUNT] = {0};
                    for (int i = 0; i < n; i++) {
                        double d = fabs(ssim[q][z][k][i] - ssim[0][TABLE_SIZES - 1][0][i]);
                        mean += d / n;
                        worst = fmax(worst, d);
                        r[i] = renders[q][z][k][i];
                        t[i] = ms[q][z][k][i];
                        c[outcome[q][z][k][i]]++;
                    }
                    const double median_renders = quantile(r, n, 0.5);
                    printf("| %s | %d² | %s | %s | %d | %.0f | %.2f | %.2f | %.5f (%.5f) | %d / %d / %d / %d / %d |\n",
                           pairs[p].name, table_sizes[z], mr_local_method_name(table_methods[k]), precision_names[q],
                           n, median_renders, quantile(t, n, 0.5), median_renders * one_render[q], mean, worst,
                           c[MR_FIT_CONVERGED], c[MR_FIT_AT_BOUND], c[MR_FIT_UNREACHABLE], c[MR_FIT_LOCAL_MINIMUM],
                           c[MR_FIT_UNDER_RESOLVED]);
                }
            for (int k = 0; precisions == TABLE_PRECISIONS && k < TABLE_METHODS; k++) {
                double worst_rel = 0.0, worst_ssim = 0.0, ratio[MAX_MATERIALS];
                int changed = 0;
                for (int i = 0; i < n; i++) {
                    worst_rel = fmax(worst_rel, fabs(rel[1][z][k][i] - rel[0][z][k][i]));
                    worst_ssim = fmax(worst_ssim, fabs(ssim[1][z][k][i] - ssim[0][z][k][i]));
                    changed += outcome[1][z][k][i] != outcome[0][z][k][i];
                    ratio[i] = ms[1][z][k][i] / ms[0][z][k][i];
                }
                snprintf(compare[compare_rows++], sizeof compare[0],
                         "| %s | %d² | %s | %d | %.2g | %d | %.2g | %.2f | %.4f | %.4f | %.2f |", pairs[p].name,
                         table_sizes[z], mr_local_method_name(table_methods[k]), n, worst_rel, changed, worst_ssim,
                         quantile(ratio, n, 0.5), one_render[0], one_render[1], one_render[1] / one_render[0]);
            }
        }
        fflush(stdout);
    }
    if (compare_rows > 0) {
        printf("\nFloat against double, the same materials: largest |Δ relative RMSE| of the fits (the answers' "
               "tolerance is 1e-4), outcomes changed, largest |Δ SSIM@512|, median time ratio float/double of the "
               "remaps, and the median ms of one render of the target (defaults) at that size in each precision.\n\n"
               "| pair | size | local | materials | max abs Δ rel. RMSE | outcomes changed | max abs Δ SSIM@512 | "
               "time ratio | 1 render double ms | 1 render float ms | render ratio |\n"
               "|---|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|\n");
        for (int row = 0; row < compare_rows; row++) printf("%s\n", compare[row]);
    }
    for (int z = 0; z < TABLE_SIZES; z++) {
        for (int q = 0; q < TABLE_PRECISIONS; q++) mr_render_plan_free(plans[q][z]);
        mr_image_free(scratch[z]);
    }
    mr_render_plan_free(plan512);
    mr_image_free(source512);
    mr_image_free(scratch512);
    return 0;
}

/* --kernels: the kernels alone, ns per pair, best of 31 runs of 200 batches of 256 random pairs above the horizon
 * (cosines 0.2 to 1), the model's default values. */
static int run_kernels(void) {
    enum { PAIRS_PER_BATCH = 256, BATCHES = 200, RUNS = 31 };
    omp_set_num_threads(1); // the renders on one thread, as the table's
    static double in[6][PAIRS_PER_BATCH], out[6][PAIRS_PER_BATCH];
    unsigned long long state = 0x6b65726eULL;
    for (int i = 0; i < PAIRS_PER_BATCH; i++)
        for (int k = 0; k < 2; k++) {
            const double z = bench_uniform(&state, 0.2, 1.0), r = sqrt(1.0 - z * z);
            const double phi = bench_uniform(&state, 0.0, 6.28318530717958648);
            in[3 * k][i] = r * cos(phi);
            in[3 * k + 1][i] = r * sin(phi);
            in[3 * k + 2][i] = z;
        }
    const mr_brdf_batch batch = {PAIRS_PER_BATCH, {in[0], in[1], in[2]}, {in[3], in[4], in[5]},
                                 {out[0], out[1], out[2]}, {out[3], out[4], out[5]}};
    mr_render_plan *plans[2] = {plan_of_size(FIT_SIZE), plan_of_size(FIT_SIZE)};
    mr_render_plan_set_float_kernels(plans[1], 1);
    mr_image *scratch = NULL;
    if (mr_image_create(FIT_SIZE, FIT_SIZE, 3, &scratch) != MR_OK) return 3;
    printf("| model | portable double ns | portable float ns | ratio | AVX2 double ns | AVX2 float ns | ratio | "
           "64² render double ms | 64² render float ms | ratio |\n"
           "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
    const mr_brdf_model *const *models = mr_brdf_models();
    for (int m = 0; models[m] != NULL; m++) {
        const mr_brdf_model *model = models[m];
        const mr_brdf_batch_fn kernels[2] = {model->eval_batch, mr_brdf_float_kernel(model)};
        if (kernels[0] == NULL || kernels[1] == NULL) continue;
        double values[MR_BRDF_MAX_VALUES];
        mr_brdf_default_values(model, values);
        mr_brdf_state st;
        model->prepare(model, values, st.bytes);
        double ns[2][2]; // [vector][precision]
        for (int vector = 0; vector < 2; vector++)
            for (int q = 0; q < 2; q++) {
                double best = INFINITY;
                for (int run = 0; run < RUNS; run++) {
                    const double t0 = bench_now();
                    for (int b = 0; b < BATCHES; b++) kernels[q](st.bytes, &batch, vector);
                    best = fmin(best, bench_now() - t0);
                }
                ns[vector][q] = 1e9 * best / (BATCHES * PAIRS_PER_BATCH);
            }
        double render[2];
        for (int q = 0; q < 2; q++) {
            double t[51];
            for (int k = 0; k < 51; k++) {
                const double t0 = bench_now();
                if (mr_render_into(plans[q], model, values, MR_COMPONENT_FULL, scratch) != MR_OK) return 3;
                t[k] = 1e3 * (bench_now() - t0);
            }
            render[q] = quantile(t, 51, 0.5);
        }
        printf("| %s | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f | %.4f | %.4f | %.2f |\n", model->name, ns[0][0],
               ns[0][1], ns[0][1] / ns[0][0], ns[1][0], ns[1][1], ns[1][1] / ns[1][0], render[0], render[1],
               render[1] / render[0]);
        fflush(stdout);
    }
    mr_render_plan_free(plans[0]);
    mr_render_plan_free(plans[1]);
    mr_image_free(scratch);
    return 0;
}

int main(int argc, char **argv) {
    int quick = 0;
    const char *save = NULL, *against = NULL, *only = NULL;
    mr_local_method local = MR_LOCAL_AUTO;
    int material = -1, table = 0, use_float = 0;
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--quick") == 0) quick = 1;
        else if (strcmp(argv[i], "--table") == 0) table = 1;
        else if (strcmp(argv[i], "--kernels") == 0) return run_kernels();
        else if (strcmp(argv[i], "--save") == 0 && i + 1 < argc) save = argv[++i];
        else if (strcmp(argv[i], "--against") == 0 && i + 1 < argc) against = argv[++i];
        else if (strcmp(argv[i], "--pairs") == 0 && i + 1 < argc) only = argv[++i];
        else if (strcmp(argv[i], "--material") == 0 && i + 1 < argc) material = atoi(argv[++i]);
        else if (strcmp(argv[i], "--precision") == 0 && i + 1 < argc && strcmp(argv[i + 1], "double") == 0) i++;
        else if (strcmp(argv[i], "--precision") == 0 && i + 1 < argc && strcmp(argv[i + 1], "float") == 0)
            use_float = 1, i++;
        else if (strcmp(argv[i], "--local") == 0 && i + 1 < argc) {
            if (mr_local_method_from_name(argv[++i], &local) != MR_OK) {
                fprintf(stderr, "bench_fit: %s\n", mr_last_error());
                return 1;
            }
        }
        else {
            fprintf(stderr, "usage: bench_fit [--quick] [--pairs a,b,...] [--local auto|gradient|bobyqa] "
                            "[--material N] [--table] [--kernels] [--save FILE] [--against FILE] "
                            "[--precision double|float]\n");
            return 1;
        }
    }
    if (table) {
        omp_set_num_threads(1);
        return run_table(quick, only);
    }
    static answer reference[PAIR_COUNT][MAX_MATERIALS];
    static int have[PAIR_COUNT][MAX_MATERIALS];
    if (against && !read_reference(against, reference, have)) {
        fprintf(stderr, "bench_fit: cannot read the reference answers %s\n", against);
        return 3;
    }
    FILE *out = NULL;
    if (save && (out = fopen(save, "w")) == NULL) {
        fprintf(stderr, "bench_fit: cannot write %s\n", save);
        return 3;
    }
    omp_set_num_threads(1); // one core per remap, as a sweep runs them
    mr_scene scene = mr_scene_fit(&(mr_fit_scene_options){FIT_SIZE, MR_FIT_LIGHT_45, 0});
    mr_render_plan *plan = NULL;
    if (mr_render_plan_create(&scene, &plan) != MR_OK) {
        fprintf(stderr, "bench_fit: %s\n", mr_last_error());
        return 3;
    }
    mr_render_plan_set_float_kernels(plan, use_float);
    printf("| pair | materials | median ms | p90 ms | median renders | outcomes |%s\n",
           against ? " vs reference: max abs Δ rel. RMSE | outcomes changed | renders ratio | time ratio |" : "");
    printf("|---|---:|---:|---:|---:|---|%s\n", against ? "---:|---:|---:|---:|" : "");
    for (int p = 0; p < PAIR_COUNT; p++) {
        if (!wanted(only, pairs[p].name)) continue;
        const mr_brdf_model *source = mr_brdf_find(pairs[p].source), *target = mr_brdf_find(pairs[p].target);
        if (source == NULL || target == NULL) {
            fprintf(stderr, "bench_fit: %s\n", mr_last_error());
            return 3;
        }
        int n = pairs[p].materials;
        if (quick) n = n >= 16 ? 8 : 4;
        unsigned long long state = 0x31ULL + (unsigned long long)p;
        double ms[MAX_MATERIALS], renders[MAX_MATERIALS], render_ratio[MAX_MATERIALS], time_ratio[MAX_MATERIALS];
        int counts[MR_FIT_OUTCOME_COUNT] = {0}, changed = 0, compared = 0;
        double worst = 0.0;
        for (int i = 0; i < n; i++) {
            double values[MR_BRDF_MAX_VALUES];
            bench_random_material(pairs[p].draw, source, &state, values);
            if (material >= 0 && i != material) {
                ms[i] = renders[i] = 0.0;
                continue;
            }
            if (material >= 0) {
                fprintf(stderr, "bench_fit: %s #%d source", pairs[p].name, i);
                for (int v = 0; v < mr_brdf_value_count(source); v++) fprintf(stderr, " %.9g", values[v]);
                fprintf(stderr, "\n");
            }
            mr_remap_options o = mr_remap_options_default();
            o.local_method = local;
            mr_remap_result r;
            double t0 = bench_now();
            if (mr_remap(plan, source, values, target, &o, &r) != MR_OK) {
                fprintf(stderr, "bench_fit: %s #%d: %s\n", pairs[p].name, i, mr_last_error());
                return 3;
            }
            ms[i] = 1e3 * (bench_now() - t0);
            renders[i] = (double)r.renders;
            counts[r.outcome]++;
            if (out) {
                int k = mr_brdf_value_count(target);
                fprintf(out, "%s %d %d %.17g %ld %.6g %d", pairs[p].name, i, (int)r.outcome, r.relative_rmse,
                        r.renders, ms[i], k);
                for (int v = 0; v < k; v++) fprintf(out, " %.17g", r.values[v]);
                fprintf(out, "\n");
            }
            if (against && have[p][i]) {
                const answer *a = &reference[p][i];
                worst = fmax(worst, fabs(a->rel - r.relative_rmse));
                changed += a->outcome != (int)r.outcome;
                if (a->outcome != (int)r.outcome || fabs(a->rel - r.relative_rmse) > 1e-4)
                    fprintf(stderr, "bench_fit: %s #%d: %s rel %.6f (reference %s rel %.6f), renders %ld (%ld)\n",
                            pairs[p].name, i, mr_fit_outcome_name(r.outcome), r.relative_rmse,
                            mr_fit_outcome_name((mr_fit_outcome)a->outcome), a->rel, r.renders, a->renders);
                render_ratio[compared] = a->renders > 0 ? (double)r.renders / (double)a->renders : 1.0;
                time_ratio[compared] = a->ms > 0 ? ms[i] / a->ms : 1.0;
                compared++;
            }
        }
        if (material >= 0) { // one material: its own figures
            n = 1;
            ms[0] = ms[material < pairs[p].materials ? material : 0];
            renders[0] = renders[material < pairs[p].materials ? material : 0];
        }
        double median_renders = quantile(renders, n, 0.5);
        printf("| %s | %d | %.2f | %.2f | %.0f | %d / %d / %d / %d / %d |", pairs[p].name, n, quantile(ms, n, 0.5),
               quantile(ms, n, 0.9), median_renders, counts[MR_FIT_CONVERGED], counts[MR_FIT_AT_BOUND],
               counts[MR_FIT_UNREACHABLE], counts[MR_FIT_LOCAL_MINIMUM], counts[MR_FIT_UNDER_RESOLVED]);
        if (against && compared > 0)
            printf(" %.2g | %d | %.2f | %.2f |", worst, changed, quantile(render_ratio, compared, 0.5),
                   quantile(time_ratio, compared, 0.5));
        else if (against)
            printf(" - | - | - | - |");
        printf("\n");
        fflush(stdout);
    }
    if (out) fclose(out);
    mr_render_plan_free(plan);
    return 0;
}
