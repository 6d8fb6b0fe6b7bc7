/*
 * matremap.h — libmatremap, the public API in one include.
 *
 * matremap translates material appearance between BRDF models, renderers and workflows by comparing rendered
 * images (Sztrajman, Krivanek, Wilkie, Weyrich, "Image-based Remapping of Spatially Varying Material
 * Appearance", JCGT 8(4), 2019).
 *
 * Typical use (tests/install_cli.sh compiles and runs exactly these lines, in main(), against an installed tree):
 *   const mr_brdf_model *ward = mr_brdf_find("ward"), *ggx = mr_brdf_find("ggx"); // brdf/brdf.h: descriptors
 *   double v[MR_BRDF_MAX_VALUES];
 *   mr_brdf_default_values(ward, v);
 *   if (mr_brdf_parse_assignment(ward, "alpha=0.2", v) != MR_OK) return 1;
 *   mr_scene scene = mr_scene_fit(&(mr_fit_scene_options){MR_REMAP_DEFAULT_SIZE, MR_FIT_LIGHT_45, 0});
 *   mr_render_plan *plan = NULL;                                   // render/render.h: geometry once per scene
 *   if (mr_render_plan_create(&scene, &plan) != MR_OK) return 1;
 *   mr_remap_result r;                                              // remap/remap.h: Ward's look in GGX
 *   mr_status s = mr_remap(plan, ward, v, ggx, NULL, &r);
 *   mr_image *img = NULL;                                          // the GGX fit, rendered
 *   if (s == MR_OK) s = mr_render(plan, ggx, r.values, MR_COMPONENT_FULL, &img);
 *   if (s == MR_OK) s = mr_img_write("ggx.exr", img, NULL);       // io/image_io.h
 *   if (s == MR_OK) printf("%s, SSIM %.4f\n", mr_fit_outcome_name(r.outcome), r.ssim);
 *   else fprintf(stderr, "%s\n", mr_last_error());
 *   mr_image_free(img);
 *   mr_render_plan_free(plan);
 *   return s == MR_OK ? 0 : 1;
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

#include "mr_core.h" /* the version (MR_VERSION_*, mr_version), mr_data_path, the RNG, atomic files, threads */
#include "mr_status.h"
#include "mr_image.h"
#include "brdf/brdf.h"
#include "render/render.h"
#include "render/renderer.h"
#include "io/image_io.h"
#include "io/output_plan.h"
#include "io/obj_load.h"
#include "metrics/metrics.h"
#include "remap/remap.h"
#include "remap/direct.h"
#include "remap/sweep.h"
#include "report/report.h"
#include "workflow/workflow.h"
#include "workflow/dataset.h"
#include "workflow/labels.h"
#include "workflow/pairs.h"
#include "transform/transform.h"
#include "learn/parametric.h"
#include "learn/svr.h"
#include "learn/sweep_table.h"
#include "learn/learned.h"
#include "learn/learned_plots.h"
#include "nn/mlp.h"
#include "gltf/mr_gltf.h"
#include "gltf/mr_gltf_convert.h"
#include "gltf/mr_gltf_scene.h"
#include "gltf/mr_gltf_library.h"
#include "doc/doc.h"
#include "remap/translate.h"
#include "api/api.h"

#endif /* MATREMAP_H */
