/*
 * threads.c — the one automatic thread rule (mr_internal.h), for every options struct's `threads` field and every
 * command's `--threads`:
 *
 *   threads = n >= 1   n OpenMP threads;
 *   threads = 0        automatic: a team of omp_get_max_threads() threads (all cores, or OMP_NUM_THREADS) when the
 *                      work reaches the size at which a second thread gains, one thread below it.
 *
 * Each caller names its work and that threshold, measured where it is not obvious (docs/performance.md):
 * renders and plans (render.h, MR_RENDER_PARALLEL_SAMPLES / _PIXELS), meshes (mesh.h, MR_MESH_PARALLEL_FACES),
 * texel batches (workflow.h and transform.h, MR_WF_PARALLEL_TEXELS), metrics (metrics.c), sweeps (sweep.h,
 * MR_SWEEP_PARALLEL_SAMPLES: two samples), direct remaps (direct.c: two chains with work), SVR and MLP training
 * (svr.c, nn/train.c: any training set). Work too small to gain stays on one thread, so many copies of a
 * command can run side by side. No result depends on the thread count: each caller splits its work in a way
 * fixed by the input alone (the callers' headers say how).
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
