/*
 * render_internal.h — what render.c shares with the render module's tests only (internal: not installed). The
 * calls other modules use (renders with a thread count of the caller's, the plan zoomed on the highlight) are
 * public, in render.h.
 */
#ifndef MR_RENDER_INTERNAL_H
#define MR_RENDER_INTERNAL_H

#include "render.h"

/* A scene that looks at the first point light's highlight on the sphere (render.c, sphere_highlight) `zoom`
 * times closer: the same camera position, turned towards the highlight, its field of view `zoom` times
 * narrower, the same image size. Returns 0 (out untouched) when the scene is not a sphere or no point light's
 * highlight is seen (mr_render_plan_zoomed builds its plan from this scene). */
int mr_scene_zoom_on_highlight(const mr_scene *scene, double zoom, mr_scene *out);

/* How a render evaluates its material (render.c, render_core). AUTO, what every public call uses: batched where
 * the render allows it (one material without maps, point samples only: the fit scene), with the AVX2/FMA kernels
 * unless the CPU lacks them or MATREMAP_SIMD=scalar (mr_brdf_batch_vector_default); otherwise one eval per sample.
 * The others force a path, for tests and benchmarks: PER_SAMPLE the per-sample loop (as before batches), the
 * BATCH_ ones the batched loop with the portable or the AVX2/FMA kernels (the latter only where the CPU has them;
 * renders the batched loop cannot do take the per-sample one). */
typedef enum mr_render_path {
    MR_RENDER_PATH_AUTO = 0,
    MR_RENDER_PATH_PER_SAMPLE,
    MR_RENDER_PATH_BATCH_PORTABLE,
    MR_RENDER_PATH_BATCH_VECTOR
} mr_render_path;

/* mr_render_into_threads (render.h) along the given path. */
mr_status mr_render_into_path(const mr_render_plan *plan, int threads, const mr_brdf_model *model,
                              const double *values, mr_component component, mr_image *image, mr_render_path path);

/* How a plan traces its primary rays (render.c, trace_rays). AUTO, what mr_render_plan_create does: a sphere's
 * four at a time with AVX2 unless the CPU lacks it or MATREMAP_SIMD=scalar (mr_brdf_batch_vector_default), a
 * mesh's one at a time. SCALAR forces one at a time, VECTOR four at a time on a sphere wherever the CPU allows it;
 * for tests and benchmarks: the plan is the same, bit for bit, either way. */
typedef enum mr_plan_rays { MR_PLAN_RAYS_AUTO = 0, MR_PLAN_RAYS_SCALAR, MR_PLAN_RAYS_VECTOR } mr_plan_rays;

/* mr_render_plan_create (render.h) with the given rays. */
mr_status mr_render_plan_create_rays(const mr_scene *scene, mr_plan_rays rays, mr_render_plan **out);

/* The precision of the batched renders on `plan` (and its closer look, mr_render_plan_zoomed, now or when it is
 * built): on nonzero, models with a float kernel (brdf/brdf_float.h: the Ward and microfacet families, gltf) are
 * evaluated in float, the others in double as always; 0, the default of every plan, double everywhere. For
 * benchmarks and tests measuring what float would change (tests/bench_fit.c --table, docs/performance.md "Double,
 * not float"); not public API. Renders along the per-sample path and derivative renders stay double. Set it before
 * rendering, never while another thread renders with the plan. */
void mr_render_plan_set_float_kernels(mr_render_plan *plan, int on);

#endif /* MR_RENDER_INTERNAL_H */
