/* bench_util.h — timing helpers and seeded random materials shared by the benchmarks (tests/bench_*.c). */
#ifndef MR_BENCH_UTIL_H
#define MR_BENCH_UTIL_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "matremap.h"

/* Monotonic wall-clock seconds. */
static inline double bench_now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int bench_compare_doubles(const void *a, const void *b) {
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* The median of samples[0..count-1] (sorts them in place). */
static inline double bench_median(double *samples, int count) {
    qsort(samples, (size_t)count, sizeof samples[0], bench_compare_doubles);
    return samples[count / 2];
}

/* The relative RMSE of `fit` against `source` over the pixels the plan's object covers, as
 * mr_remap_result.relative_rmse defines it (relative to the source's RMS radiance there; 0 for a black source). */
static inline double bench_relative_rmse(const mr_render_plan *plan, const mr_image *fit, const mr_image *source) {
    const mr_scene *scene = mr_render_plan_scene(plan);
    const float *coverage = mr_render_plan_coverage(plan);
    double diff = 0.0, energy = 0.0;
    for (int p = 0; p < scene->width * scene->height; p++) {
        if (!(coverage[p] > 0.0f)) continue;
        for (int c = 0; c < 3; c++) {
            double a = fit->pixels[(size_t)p * 3 + c], b = source->pixels[(size_t)p * 3 + c];
            diff += (a - b) * (a - b);
            energy += b * b;
        }
    }
    return energy > 0.0 ? sqrt(diff / energy) : 0.0;
}

/* splitmix64: a uniform number in [lo, hi) (the same sequence for a seed in every run and build). */
static inline double bench_uniform(unsigned long long *state, double lo, double hi) {
    unsigned long long z = (*state += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    z ^= z >> 31;
    return lo + (hi - lo) * (double)(z >> 11) * (1.0 / 9007199254740992.0);
}

static inline double bench_log_uniform(unsigned long long *state, double lo, double hi) {
    return exp(bench_uniform(state, log(lo), log(hi)));
}

/* values[] of `m` at parameter `name`, channel `channel` = v; exits (3) when the model has no such parameter. */
static inline void bench_set(const mr_brdf_model *m, double *values, const char *name, int channel, double v) {
    int index = mr_brdf_param_index(m, name);
    if (index < 0) {
        fprintf(stderr, "bench: %s has no parameter %s\n", m->name, name);
        exit(3);
    }
    values[mr_brdf_param_offset(m, index) + channel] = v;
}

/* A random material of the benches' uniform remaps (docs/performance.md, "Uniform remaps"), by `draw`:
 *   ward:       diffuse 0.05-0.6, specular 0.02-0.35 (per channel), alpha 0.03-0.5 (log);
 *   gltf:       base colour 0.05-0.95 (per channel), metallic 0-1, roughness 0.15-0.9;
 *   glossy:     diffuse 0-0.1, F0 0.02-0.3 (per channel), alpha 1e-4-0.03 (log): lobes narrower than a 64^2 pixel;
 *   microfacet: diffuse 0.05-0.6, F0 0.02-0.3 (per channel), alpha 0.03-0.5 (log) (Schlick microfacet + Lambert). */
static inline void bench_random_material(const char *draw, const mr_brdf_model *m, unsigned long long *state,
                                         double *values) {
    mr_brdf_default_values(m, values);
    if (strcmp(draw, "ward") == 0) {
        for (int c = 0; c < 3; c++) bench_set(m, values, "diffuse", c, bench_uniform(state, 0.05, 0.6));
        for (int c = 0; c < 3; c++) bench_set(m, values, "specular", c, bench_uniform(state, 0.02, 0.35));
        bench_set(m, values, "alpha", 0, bench_log_uniform(state, 0.03, 0.5));
    } else if (strcmp(draw, "gltf") == 0) {
        for (int c = 0; c < 3; c++) bench_set(m, values, "base_color", c, bench_uniform(state, 0.05, 0.95));
        bench_set(m, values, "metallic", 0, bench_uniform(state, 0.0, 1.0));
        bench_set(m, values, "roughness", 0, bench_uniform(state, 0.15, 0.9));
    } else if (strcmp(draw, "glossy") == 0) {
        for (int c = 0; c < 3; c++) bench_set(m, values, "diffuse", c, bench_uniform(state, 0.0, 0.1));
        for (int c = 0; c < 3; c++) bench_set(m, values, "f0", c, bench_uniform(state, 0.02, 0.3));
        bench_set(m, values, "alpha", 0, bench_log_uniform(state, 1e-4, 0.03));
    } else {
        for (int c = 0; c < 3; c++) bench_set(m, values, "diffuse", c, bench_uniform(state, 0.05, 0.6));
        for (int c = 0; c < 3; c++) bench_set(m, values, "f0", c, bench_uniform(state, 0.02, 0.3));
        bench_set(m, values, "alpha", 0, bench_log_uniform(state, 0.03, 0.5));
    }
}

#endif /* MR_BENCH_UTIL_H */
