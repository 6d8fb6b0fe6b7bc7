/*
 * brdf_batch.c — evaluation over batches of direction pairs: the fallback for models without a kernel, and the
 * run-time choice of the kernels' instruction set (contracts in brdf.h; kernels share brdf_batch.h).
 */
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#include "brdf_batch.h"
#include "brdf_float.h"

void mr_brdf_eval_batch(const mr_brdf_model *model, const void *state, const mr_brdf_batch *batch, int vector) {
    if (model->eval_batch != NULL) {
        model->eval_batch(state, batch, vector);
        return;
    }
    for (int i = 0; i < batch->n; i++) {
        const double wi[3] = {batch->wi[0][i], batch->wi[1][i], batch->wi[2][i]};
        const double wo[3] = {batch->wo[0][i], batch->wo[1][i], batch->wo[2][i]};
        double fd[3], fs[3];
        model->eval(state, wi, wo, fd, fs);
        for (int c = 0; c < 3; c++) {
            batch->diffuse[c][i] = fd[c];
            batch->specular[c][i] = fs[c];
        }
    }
}

/* -1: not yet known; else the answer. Computed by whichever thread asks first; every thread computes the same
 * value, so a race only repeats the work. */
static atomic_int cpu_vector = -1;
static atomic_int vector_default = -1;

int mr_brdf_batch_cpu_vector(void) {
    int known = atomic_load_explicit(&cpu_vector, memory_order_relaxed);
    if (known >= 0) return known;
#if MR_BATCH_X86
    __builtin_cpu_init(); // idempotent; needed if we run before libgcc's constructor
    known = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
#else
    known = 0;
#endif
    atomic_store_explicit(&cpu_vector, known, memory_order_relaxed);
    return known;
}

int mr_brdf_batch_vector_default(void) {
    int known = atomic_load_explicit(&vector_default, memory_order_relaxed);
    if (known >= 0) return known;
    const char *simd = getenv("MATREMAP_SIMD");
    known = (simd != NULL && strcmp(simd, "scalar") == 0) ? 0 : mr_brdf_batch_cpu_vector();
    atomic_store_explicit(&vector_default, known, memory_order_relaxed);
    return known;
}

mr_brdf_batch_fn mr_brdf_float_kernel(const mr_brdf_model *model) {
    mr_brdf_batch_fn kernel = mr_ward_float_kernel(model);
    if (kernel == NULL) kernel = mr_mf_float_kernel(model);
    if (kernel == NULL) kernel = mr_gltf_float_kernel(model);
    return kernel;
}

void mr_brdf_eval_batch_float(const mr_brdf_model *model, const void *state, const mr_brdf_batch *batch, int vector) {
    const mr_brdf_batch_fn kernel = mr_brdf_float_kernel(model);
    if (kernel != NULL)
        kernel(state, batch, vector);
    else
        mr_brdf_eval_batch(model, state, batch, vector);
}
