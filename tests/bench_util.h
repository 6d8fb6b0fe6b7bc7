/* bench_util.h — timing helpers shared by the benchmarks (tests/bench_*.c). */
#ifndef MR_BENCH_UTIL_H
#define MR_BENCH_UTIL_H

#include <stdlib.h>
#include <time.h>

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

#endif /* MR_BENCH_UTIL_H */
