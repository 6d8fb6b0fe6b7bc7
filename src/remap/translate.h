/*
 * translate.h — MaterialX's closed-form translation graphs as a baseline beside the image-fitted remap (remap.h):
 * a material's parameters carried into another model by the formulas of MaterialX's own translation nodegraphs,
 * with no rendering (docs/remap.md, "MaterialX's translation graphs"; the table against the remap:
 * docs/evaluation-translations.md).
 *
 *   const mr_translation *t;  mr_translate_find(from, to, &t);           // is there a graph for this pair?
 *   double out[MR_BRDF_MAX_VALUES];  mr_translate(from, values, to, out); // the graph's values
 *   mr_translate_result r;  mr_translate_compare(plan, from, values, to, &r);  // values + SSIM in the fit scene
 *
 * The graphs (MaterialX 1.39.5, libraries/bxdf/translation/; written here from the .mtlx files, no code copied):
 *   standard-surface -> gltf         NG_standard_surface_to_gltf_pbr
 *   standard-surface -> usd-preview  NG_standard_surface_to_UsdPreviewSurface
 *   openpbr -> standard-surface      NG_open_pbr_surface_to_standard_surface
 * MaterialX has no graph from glTF or UsdPreviewSurface, and none from Standard Surface into OpenPBR's parameters
 * that this project's models could use beside these three; every other pair is MR_ERR_UNSUPPORTED.
 *
 * Values: the source's packed values (brdf.h) as given; the output is the target's packed vector: every
 * parameter the graph drives, the target's defaults for the ones it does not (usd-preview's
 * use_specular_workflow = 0 and specular_color, standard-surface's coat_affect_color), each clamped into the
 * target's [min, max] (a graph's roughness 0 becomes the models' floor 0.01), so that the result can be given
 * back to any command. What a target model here cannot hold (gltf's clearcoat: no KHR_materials_clearcoat in the
 * `gltf` descriptor) is lost and named in mr_translation.dropped.
 * Pure functions of their inputs; thread-safe.
 */
#ifndef MR_TRANSLATE_H
#define MR_TRANSLATE_H

#include "../brdf/brdf.h"
#include "../mr_status.h"
#include "../render/render.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct mr_translation {
    const char *from;    /* source model name: "standard-surface" */
    const char *to;      /* target model name: "gltf" */
    const char *graph;   /* MaterialX nodegraph: "NG_standard_surface_to_gltf_pbr" */
    const char *file;    /* its file in MaterialX: "libraries/bxdf/translation/standard_surface_to_gltf_pbr.mtlx" */
    const char *dropped; /* one line: the source parameters the graph (or the target model here) does not carry */
} mr_translation;

/* The MaterialX version the graphs were read from ("1.39.5", commit in docs/remap.md). */
#define MR_TRANSLATE_MATERIALX_VERSION "1.39.5"

/* The translations, NULL-terminated, in the order of the header comment. */
const mr_translation *const *mr_translations(void);

/* The translation from `from` to `to` into *out. MR_ERR_INVALID_ARG for a NULL model; MR_ERR_UNSUPPORTED when
 * MaterialX has no graph for the pair: "no MaterialX translation graph from 'FROM' to 'TO' (graphs:
 * standard-surface -> gltf, standard-surface -> usd-preview, openpbr -> standard-surface)". *out untouched on
 * failure. */
mr_status mr_translate_find(const mr_brdf_model *from, const mr_brdf_model *to, const mr_translation **out);

/* The graph's translation of `values` (from's packed vector) into out (to's packed vector, mr_brdf_value_count(to)
 * doubles). mr_translate_find's errors, and MR_ERR_INVALID_ARG naming the parameter for a value that is not
 * finite; out is untouched on failure. */
mr_status mr_translate(const mr_brdf_model *from, const double *values, const mr_brdf_model *to, double *out);

/* A translation and how its render compares with the source's in a scene, measured as mr_remap measures a fit
 * (remap.h, mr_remap_result): whole-image RMSE of the linear renders, RMSE over the pixels the object covers
 * relative to the source's RMS radiance there, whole-frame display-referred SSIM (metrics.h). */
typedef struct mr_translate_result {
    double values[MR_BRDF_MAX_VALUES]; /* the target's packed values (mr_translate) */
    double rmse;
    double relative_rmse;
    double ssim;
    double seconds; /* wall time: the translation and both renders */
} mr_translate_result;

/* mr_translate, then the source and the translation rendered with `plan` and compared. mr_translate's,
 * mr_render's and the metrics' errors; *out is written only on success. */
mr_status mr_translate_compare(const mr_render_plan *plan, const mr_brdf_model *from, const double *values,
                               const mr_brdf_model *to, mr_translate_result *out);

#ifdef __cplusplus
}
#endif

#endif /* MR_TRANSLATE_H */
