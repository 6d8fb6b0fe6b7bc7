/*
 * brdf_float.h — the single-precision batch kernels (internal: not installed, not public API). A render chooses
 * them per plan (render_internal.h, mr_render_plan_set_float_kernels; default off: double). They exist to measure
 * what float would change (docs/performance.md, "Double, not float"): same batch and contract shape as eval_batch
 * (brdf.h; doubles in and out), float arithmetic inside (brdf_batch.h, "single precision").
 *
 * Models with a float kernel: ward, ward-duer, ward-balanced (ward.c), the twelve microfacet members (microfacet.c)
 * and gltf (gltf.c). Every other model's float request takes its double kernel.
 */
#ifndef MR_BRDF_FLOAT_H
#define MR_BRDF_FLOAT_H

#include "brdf.h"

/* A batch kernel: eval_batch's signature. */
typedef void (*mr_brdf_batch_fn)(const void *state, const mr_brdf_batch *batch, int vector);

/* Contract of a float kernel, tests/test_batch.c: each output within MR_BRDF_FLOAT_RTOL relative to the pair's
 * largest value (both parts, all channels) of what eval writes, or MR_BRDF_FLOAT_ATOL absolute (Mitsuba's cut-offs,
 * D cos_h < 1e-20 and Ward's S <= 1e-10, which float's rounding moves across more often than double's); finite
 * wherever eval is; a pair's result depends on the pair and `vector` only (thread counts keep bits). */
#define MR_BRDF_FLOAT_RTOL 5e-5
#define MR_BRDF_FLOAT_ATOL 1e-8

/* The float kernel of `model`, or NULL when it has none. */
mr_brdf_batch_fn mr_brdf_float_kernel(const mr_brdf_model *model);

/* Per family (brdf_batch.c asks each): the kernel when `model` belongs to the family, else NULL. */
mr_brdf_batch_fn mr_ward_float_kernel(const mr_brdf_model *model);
mr_brdf_batch_fn mr_mf_float_kernel(const mr_brdf_model *model);
mr_brdf_batch_fn mr_gltf_float_kernel(const mr_brdf_model *model);

/* f_r over a batch in float where the model has a float kernel, else mr_brdf_eval_batch (double). */
void mr_brdf_eval_batch_float(const mr_brdf_model *model, const void *state, const mr_brdf_batch *batch, int vector);

#endif /* MR_BRDF_FLOAT_H */
