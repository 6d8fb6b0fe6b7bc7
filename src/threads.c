/*
 * threads.c — the automatic thread rule shared by renders, plans, metrics and texture batches (mr_internal.h).
 */
#include "mr_internal.h"

#ifdef _OPENMP
#include <omp.h>
#endif

int mr_auto_threads(int requested, long work, long threshold) {
    if (requested > 0) return requested;
#ifdef _OPENMP
    return work >= threshold ? omp_get_max_threads() : 1;
#else
    (void)work;
    (void)threshold;
    return 1;
#endif
}
