/*
 * matremap.h — libmatremap, the public API in one include.
 *
 * matremap translates material appearance between BRDF models, renderers and workflows by comparing rendered
 * images (Sztrajman, Krivanek, Wilkie, Weyrich, "Image-based Remapping of Spatially Varying Material
 * Appearance", JCGT 8(4), 2019).
 *
 * Typical use:
 *   const mr_brdf_model *m = mr_brdf_find("ggx");            // src/brdf/brdf.h: models as descriptors
 *   double v[MR_BRDF_MAX_VALUES]; mr_brdf_default_values(m, v);
 *   mr_brdf_parse_assignment(m, "alpha=0.2", v);
 *   mr_scene scene = mr_scene_fit_default();                   // src/render/render.h: the paper's fit scene
 *   mr_render_plan *plan; mr_render_plan_create(&scene, &plan);  // geometry once per scene
 *   mr_image *img; mr_render(plan, m, v, MR_COMPONENT_FULL, &img);  // BRDF evaluations only
 *   mr_img_write("sphere.exr", img, NULL);                    // src/io/image_io.h
 *   double s; mr_ssim(img, other, NULL, &s, NULL);            // src/metrics/metrics.h
 *   mr_image_free(img); mr_render_plan_free(plan);
 *
 * Errors: every fallible call returns mr_status (mr_status.h); mr_last_error() says what went wrong. The library
 * never prints, exits or aborts on bad input.
 * Ownership: whatever comes back through a `**out` parameter belongs to the caller and is released by the
 * matching *_free(), which accepts NULL.
 * Threads: the library uses OpenMP inside rendering and metrics; results are identical for any thread count.
 * Functions are reentrant; objects may be shared between threads for reading.
 */
#ifndef MATREMAP_H
#define MATREMAP_H

#define MR_VERSION_MAJOR 0
#define MR_VERSION_MINOR 1
#define MR_VERSION_PATCH 0
#define MR_VERSION_STRING "0.1.0"

#include "mr_status.h"
#include "mr_image.h"
#include "brdf/brdf.h"
#include "render/render.h"
#include "io/image_io.h"
#include "metrics/metrics.h"
#include "remap/remap.h"
#include "workflow/workflow.h"
#include "workflow/dataset.h"
#include "workflow/labels.h"
#include "nn/mlp.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The library's version string, MR_VERSION_STRING of the build it was compiled from. */
const char *mr_version(void);

#ifdef __cplusplus
}
#endif

#endif /* MATREMAP_H */
