/* bench_util.h — timing helpers shared by the benchmarks (tests/bench_*.c). */
#ifndef MR_BENCH_UTIL_H
#define MR_BENCH_UTIL_H

#include <math.h>
#include <stdlib.h>
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

#endif /* MR_BENCH_UTIL_H */
