/*
 * bench_remap.c — what a uniform remap's accuracy costs in time (make bench; docs/performance.md, "Uniform remaps").
 *
 * For seeded random source materials per model pair, remaps at fit-scene sizes 32..512 (AUTO) and with each
 * strategy at 64, on one thread, and reports time per remap and the fit's quality. A fit made at a small size is
 * judged where it is used: the fitted target and the source are both re-rendered at 512^2 and compared there
 * (SSIM and relative RMSE at 512^2), and the mean |SSIM_512(fit at size r) - SSIM_512(fit at 512)| says what
 * the smaller fit scene gives away. Prints Markdown on stdout (progress on stderr); asserts nothing.
 * Usage: bench_remap [--quick]; with BENCH_REMAP_DETAIL set in the environment, every AUTO fit is also listed on
 * stderr (source values, size, SSIM at 512^2, outcome), to see which materials a small fit scene gets wrong.
 */
#include <math.h>
#include <omp.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench_util.h"
#include "matremap.h"
#include "remap/remap.h"

#define SIZE_COUNT 5
#define MAX_MATERIALS 50
static const int sizes[SIZE_COUNT] = {32, 64, 128, 256, 512};
#define STRATEGY_SIZE 64 /* sizes[1] */
#define BUDGET_MS 50.0
#define SSIM_TOLERANCE 0.001

/* A source model, the sub-ranges its random materials are drawn from, and a target. */
typedef struct pair {
    const char *source, *target;
    const char *ranges; /* for the table header */
    int materials[SIZE_COUNT];
    int strategy_materials;
    int glossy;         /* narrow lobes (issue 13): alpha 1e-4 .. 0.03, little diffuse */
} pair;

/* Materials per size: all 50 where a remap takes milliseconds; fewer at 256^2 and 512^2, and fewer for Cycles'
 * Principled BSDF, whose remap searches three nonlinear parameters from 8 starts (seconds per remap at 256^2). */
static pair pairs[] = {
    {"ward", "ggx", "diffuse 0.05-0.6, specular 0.02-0.35 (per channel), alpha 0.03-0.5 (log)",
     {50, 50, 50, 20, 20}, 50, 0},
    {"ggx", "ward", "diffuse 0.05-0.6, F0 0.02-0.3 (per channel), alpha 0.03-0.5 (log)", {50, 50, 50, 20, 20}, 50, 0},
    {"as", "ward", "diffuse 0.05-0.6, F0 0.02-0.3 (per channel), alpha 0.03-0.5 (log)", {50, 50, 50, 20, 20}, 50, 0},
    {"gltf", "cycles-principled", "base colour 0.05-0.95 (per channel), metallic 0-1, roughness 0.15-0.9",
     {50, 50, 15, 4, 2}, 16, 0},
    {"ggx", "ward", "glossy: diffuse 0-0.1, F0 0.02-0.3 (per channel), alpha 1e-4-0.03 (log)", {30, 30, 30, 12, 12},
     12, 1},
};
#define PAIR_COUNT ((int)(sizeof pairs / sizeof pairs[0]))

/* " (glossy)" for the glossy pair's rows, "" for the others. */
static const char *tag(const pair *p) { return p->glossy ? " (glossy)" : ""; }

/* One random material of the pair's source model, within the ranges its `ranges` line states. */
static void random_material(const pair *p, const mr_brdf_model *m, unsigned long long *state, double *values) {
    const char *draw = p->glossy                           ? "glossy"
                       : strcmp(p->source, "ward") == 0 ? "ward"
                       : strcmp(p->source, "gltf") == 0 ? "gltf"
                                                        : "microfacet";
    bench_random_material(draw, m, state, values);
}

static mr_render_plan *plan_of(int size, double *ms) {
    mr_scene scene = mr_scene_fit(&(mr_fit_scene_options){size, MR_FIT_LIGHT_45, 0});
    mr_render_plan *plan = NULL;
    double t0 = bench_now();
    if (mr_render_plan_create(&scene, &plan) != MR_OK) {
        fprintf(stderr, "bench_remap: %s\n", mr_last_error());
        exit(3);
    }
    if (ms) *ms = 1e3 * (bench_now() - t0);
    return plan;
}

/* One remap's figures. */
typedef struct sample {
    double ms, renders, rel_fit, rel_512, ssim_512;
    mr_fit_outcome outcome;
} sample;

/* Remap the material at `plan` and judge the fit against the source's 512^2 render. */
static sample measure(const mr_render_plan *plan, const mr_render_plan *plan512, const mr_brdf_model *source,
                      const double *values, const mr_brdf_model *target, const mr_remap_options *o,
                      const mr_image *source512, mr_image *scratch512) {
    mr_remap_result r;
    double t0 = bench_now();
    if (mr_remap(plan, source, values, target, o, &r) != MR_OK) {
        fprintf(stderr, "bench_remap: %s\n", mr_last_error());
        exit(3);
    }
    sample s;
    s.ms = 1e3 * (bench_now() - t0);
    s.renders = (double)r.renders;
    s.rel_fit = r.relative_rmse;
    s.outcome = r.outcome;
    if (mr_render_into(plan512, target, r.values, MR_COMPONENT_FULL, scratch512) != MR_OK ||
        mr_ssim(scratch512, source512, NULL, &s.ssim_512, NULL) != MR_OK) {
        fprintf(stderr, "bench_remap: %s\n", mr_last_error());
        exit(3);
    }
    s.rel_512 = bench_relative_rmse(plan512, scratch512, source512);
    return s;
}

/* The q-quantile (nearest rank) of one field over samples[0..n-1]. */
static double quantile(const sample *samples, int n, size_t field, double q) {
    double v[MAX_MATERIALS];
    for (int i = 0; i < n; i++) v[i] = *(const double *)((const char *)&samples[i] + field);
    qsort(v, (size_t)n, sizeof v[0], bench_compare_doubles);
    int rank = (int)ceil(q * n) - 1;
    return v[rank < 0 ? 0 : rank >= n ? n - 1 : rank];
}

static void outcome_counts(const sample *samples, int n, char *out, size_t size) {
    int counts[MR_FIT_OUTCOME_COUNT] = {0};
    for (int i = 0; i < n; i++) counts[samples[i].outcome]++;
    snprintf(out, size, "%d / %d / %d / %d / %d", counts[MR_FIT_CONVERGED], counts[MR_FIT_AT_BOUND],
             counts[MR_FIT_UNREACHABLE], counts[MR_FIT_LOCAL_MINIMUM], counts[MR_FIT_UNDER_RESOLVED]);
}

int main(int argc, char **argv) {
    int quick = argc > 1 && strcmp(argv[1], "--quick") == 0;
    if (quick)
        for (int p = 0; p < PAIR_COUNT; p++) {
            for (int s = 0; s < SIZE_COUNT; s++) pairs[p].materials[s] = pairs[p].materials[s] > 4 ? 4 : 1;
            pairs[p].strategy_materials = 2;
        }
    omp_set_num_threads(1); // one core per remap, as sweeps run them (and the 512^2 judging renders alike)
    double plan_ms[SIZE_COUNT];
    mr_render_plan *plans[SIZE_COUNT];
    for (int s = 0; s < SIZE_COUNT; s++) plans[s] = plan_of(sizes[s], &plan_ms[s]);
    mr_render_plan *plan512 = plans[SIZE_COUNT - 1];
    mr_image *source512 = NULL, *scratch512 = NULL;
    if (mr_image_create(512, 512, 3, &source512) != MR_OK || mr_image_create(512, 512, 3, &scratch512) != MR_OK)
        return 3;

    static sample by_size[PAIR_COUNT][SIZE_COUNT][MAX_MATERIALS];
    static sample by_strategy[PAIR_COUNT][MR_REMAP_STRATEGY_COUNT][MAX_MATERIALS];
    double total_start = bench_now();
    for (int p = 0; p < PAIR_COUNT; p++) {
        const mr_brdf_model *source = mr_brdf_find(pairs[p].source), *target = mr_brdf_find(pairs[p].target);
        if (source == NULL || target == NULL) return 3;
        unsigned long long state = 0x2019ULL + (unsigned long long)p;
        int most = pairs[p].strategy_materials;
        for (int s = 0; s < SIZE_COUNT; s++)
            if (pairs[p].materials[s] > most) most = pairs[p].materials[s];
        double pair_start = bench_now();
        for (int i = 0; i < most; i++) {
            double values[MR_BRDF_MAX_VALUES];
            random_material(&pairs[p], source, &state, values);
            if (mr_render_into(plan512, source, values, MR_COMPONENT_FULL, source512) != MR_OK) return 3;
            mr_remap_options o = mr_remap_options_default();
            for (int s = 0; s < SIZE_COUNT; s++)
                if (i < pairs[p].materials[s]) {
                    sample *x = &by_size[p][s][i];
                    *x = measure(plans[s], plan512, source, values, target, &o, source512, scratch512);
                    if (getenv("BENCH_REMAP_DETAIL")) {
                        fprintf(stderr, "%s -> %s #%d", pairs[p].source, pairs[p].target, i);
                        for (int v = 0; v < mr_brdf_value_count(source); v++) fprintf(stderr, " %.3g", values[v]);
                        fprintf(stderr, " | %d: SSIM@512 %.5f rel %.4f %s\n", sizes[s], x->ssim_512, x->rel_fit,
                                mr_fit_outcome_name(x->outcome));
                    }
                }
            for (int st = 0; st < MR_REMAP_STRATEGY_COUNT && i < pairs[p].strategy_materials; st++) {
                o.strategy = (mr_remap_strategy)st;
                o.skip_global_check = 1; // the strategy's own cost; the default check would add an AUTO run
                by_strategy[p][st][i] = st == MR_REMAP_AUTO && i < pairs[p].materials[1]
                                            ? by_size[p][1][i]
                                            : measure(plans[1], plan512, source, values, target, &o, source512,
                                                      scratch512);
            }
        }
        fprintf(stderr, "bench_remap: %s -> %s: %.0f s\n", pairs[p].source, pairs[p].target,
                bench_now() - pair_start);
    }

    printf("Random source materials per pair (seeded; the same materials at every size and for every strategy),\n"
           "remapped on one thread (OpenMP 1). Time is the whole `mr_remap` call: the source's three renders, the\n"
           "fit, the verdict render and its SSIM; the plan is built once per size and reused (%.0f, %.0f, %.0f,\n"
           "%.0f and %.0f ms at 32², 64², 128², 256² and 512²). Quality is judged at 512²: the fitted target\n"
           "and the source re-rendered there. ΔSSIM is the mean (and max) |SSIM₅₁₂(fit at this size) −\n"
           "SSIM₅₁₂(fit at 512²)| per material. Outcomes: converged / at-bound / unreachable /\n"
           "local-minimum / under-resolved. The last pair (glossy) has lobes down to alpha 1e-4, far below a\n"
           "pixel at 64², which the fit scene integrates about the highlight (docs/rendering.md).\n\n",
           plan_ms[0], plan_ms[1], plan_ms[2], plan_ms[3], plan_ms[4]);
    printf("Source ranges: ");
    for (int p = 0; p < PAIR_COUNT; p++)
        printf("%s%s%s: %s", p ? "; " : "", pairs[p].source, tag(&pairs[p]), pairs[p].ranges);
    printf(".\n\n");

    printf("**AUTO against fit-scene size.** Time, renders and outcomes over the row's materials; the quality\n"
           "columns after *n* over the first *n* of them, those that also have a 512² fit, so that they compare\n"
           "the same materials from row to row.\n\n");
    printf("| pair | size | materials | median ms | p90 ms | median renders | outcomes | n "
           "| median rel. RMSE (fit) | median rel. RMSE @512² | median SSIM @512² "
           "| ΔSSIM vs 512² fit: mean (max) |\n");
    printf("|---|---:|---:|---:|---:|---:|---|---:|---:|---:|---:|---:|\n");
    double mean_delta[PAIR_COUNT][SIZE_COUNT], median_ms[PAIR_COUNT][SIZE_COUNT];
    for (int p = 0; p < PAIR_COUNT; p++)
        for (int s = 0; s < SIZE_COUNT; s++) {
            const sample *x = by_size[p][s];
            int n = pairs[p].materials[s], n512 = pairs[p].materials[SIZE_COUNT - 1];
            int shared = n < n512 ? n : n512;
            double sum = 0.0, worst = 0.0;
            for (int i = 0; i < shared; i++) {
                double d = fabs(x[i].ssim_512 - by_size[p][SIZE_COUNT - 1][i].ssim_512);
                sum += d;
                worst = fmax(worst, d);
            }
            mean_delta[p][s] = shared > 0 ? sum / shared : NAN;
            median_ms[p][s] = quantile(x, n, offsetof(sample, ms), 0.5);
            char outcomes[64];
            outcome_counts(x, n, outcomes, sizeof outcomes);
            printf("| %s → %s%s | %d² | %d | %.1f | %.1f | %.0f | %s | %d | %.4f | %.4f | %.5f | %.5f (%.5f) |\n",
                   pairs[p].source, pairs[p].target, tag(&pairs[p]), sizes[s], n, median_ms[p][s],
                   quantile(x, n, offsetof(sample, ms), 0.9), quantile(x, n, offsetof(sample, renders), 0.5),
                   outcomes, shared, quantile(x, shared, offsetof(sample, rel_fit), 0.5),
                   quantile(x, shared, offsetof(sample, rel_512), 0.5),
                   quantile(x, shared, offsetof(sample, ssim_512), 0.5), mean_delta[p][s], worst);
        }
    printf("\n**Strategies at %d²** (local strategies without their global local-minimum check, "
           "`skip_global_check`)\n\n", STRATEGY_SIZE);
    printf("| pair | strategy | materials | median ms | p90 ms | median renders | median rel. RMSE (fit) "
           "| median SSIM @512² | outcomes |\n");
    printf("|---|---|---:|---:|---:|---:|---:|---:|---|\n");
    for (int p = 0; p < PAIR_COUNT; p++)
        for (int st = 0; st < MR_REMAP_STRATEGY_COUNT; st++) {
            const sample *x = by_strategy[p][st];
            int n = pairs[p].strategy_materials;
            char outcomes[64];
            outcome_counts(x, n, outcomes, sizeof outcomes);
            printf("| %s → %s%s | %s | %d | %.1f | %.1f | %.0f | %.4f | %.5f | %s |\n", pairs[p].source,
                   pairs[p].target, tag(&pairs[p]), mr_remap_strategy_name((mr_remap_strategy)st), n,
                   quantile(x, n, offsetof(sample, ms), 0.5), quantile(x, n, offsetof(sample, ms), 0.9),
                   quantile(x, n, offsetof(sample, renders), 0.5), quantile(x, n, offsetof(sample, rel_fit), 0.5),
                   quantile(x, n, offsetof(sample, ssim_512), 0.5), outcomes);
        }

    printf("\n**Smallest size with median ≤ %.0f ms on one core and mean ΔSSIM ≤ %g** (this run):\n\n", BUDGET_MS,
           SSIM_TOLERANCE);
    for (int p = 0; p < PAIR_COUNT; p++) {
        int chosen = -1, accurate = -1;
        for (int s = SIZE_COUNT - 1; s >= 0; s--) {
            if (mean_delta[p][s] <= SSIM_TOLERANCE) accurate = s;
            else break;
        }
        for (int s = 0; s < SIZE_COUNT; s++)
            if (s >= accurate && accurate >= 0 && median_ms[p][s] <= BUDGET_MS) {
                chosen = s;
                break;
            }
        if (chosen >= 0)
            printf("- %s → %s%s: %d² (median %.1f ms, mean ΔSSIM %.5f)\n", pairs[p].source, pairs[p].target,
                   tag(&pairs[p]), sizes[chosen], median_ms[p][chosen], mean_delta[p][chosen]);
        else
            printf("- %s → %s%s: none; ΔSSIM ≤ %g from %d² on (median %.1f ms there); the fastest size takes "
                   "%.1f ms\n",
                   pairs[p].source, pairs[p].target, tag(&pairs[p]), SSIM_TOLERANCE,
                   accurate >= 0 ? sizes[accurate] : 512,
                   accurate >= 0 ? median_ms[p][accurate] : NAN, median_ms[p][0]);
    }
    fprintf(stderr, "bench_remap: %.0f s in all\n", bench_now() - total_start);
    mr_image_free(source512);
    mr_image_free(scratch512);
    for (int s = 0; s < SIZE_COUNT; s++) mr_render_plan_free(plans[s]);
    return 0;
}
