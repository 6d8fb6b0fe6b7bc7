/*
 * models.h — declarations of every model descriptor, and the registration order (internal to src/brdf and
 * the tests; callers use mr_brdf_find / mr_brdf_models).
 */
#ifndef MR_BRDF_MODELS_H
#define MR_BRDF_MODELS_H

#include "brdf.h"

extern const mr_brdf_model mr_brdf_lambert;
/* ward.c */
extern const mr_brdf_model mr_brdf_ward;
extern const mr_brdf_model mr_brdf_ward_duer;
extern const mr_brdf_model mr_brdf_ward_balanced;
/* phong.c */
extern const mr_brdf_model mr_brdf_phong;
/* microfacet.c */
extern const mr_brdf_model mr_brdf_beckmann;
extern const mr_brdf_model mr_brdf_ggx;
extern const mr_brdf_model mr_brdf_as;
extern const mr_brdf_model mr_brdf_beckmann_nofresnel;
extern const mr_brdf_model mr_brdf_ggx_nofresnel;
extern const mr_brdf_model mr_brdf_as_nofresnel;
extern const mr_brdf_model mr_brdf_beckmann_conductor;
extern const mr_brdf_model mr_brdf_ggx_conductor;
extern const mr_brdf_model mr_brdf_as_conductor;
extern const mr_brdf_model mr_brdf_beckmann_plastic;
extern const mr_brdf_model mr_brdf_ggx_plastic;
extern const mr_brdf_model mr_brdf_as_plastic;
/* ggx_metallic.c */
extern const mr_brdf_model mr_brdf_ggx_metallic;
/* blender_ward.c */
extern const mr_brdf_model mr_brdf_blender_ward;
/* gltf.c, gltf_specgloss.c */
extern const mr_brdf_model mr_brdf_gltf;
extern const mr_brdf_model mr_brdf_gltf_specgloss;
/* cycles_principled.c, cycles_ggx.c */
extern const mr_brdf_model mr_brdf_cycles_principled;
extern const mr_brdf_model mr_brdf_cycles_ggx;
/* usd_preview.c */
extern const mr_brdf_model mr_brdf_usd_preview;
/* openpbr.c, blender_principled.c */
extern const mr_brdf_model mr_brdf_openpbr;
extern const mr_brdf_model mr_brdf_blender_principled;
/* standard_surface.c */
extern const mr_brdf_model mr_brdf_standard_surface;

/* Display order of `matremap models`; registry.c expands it into its table. */
#define MR_BRDF_REGISTERED_MODELS                                                                           \
    &mr_brdf_lambert, &mr_brdf_ward, &mr_brdf_ward_duer, &mr_brdf_ward_balanced, &mr_brdf_phong,             \
        &mr_brdf_beckmann, &mr_brdf_ggx, &mr_brdf_as, &mr_brdf_beckmann_nofresnel, &mr_brdf_ggx_nofresnel,   \
        &mr_brdf_as_nofresnel, &mr_brdf_beckmann_conductor, &mr_brdf_ggx_conductor, &mr_brdf_as_conductor,   \
        &mr_brdf_beckmann_plastic, &mr_brdf_ggx_plastic, &mr_brdf_as_plastic, &mr_brdf_ggx_metallic,         \
        &mr_brdf_blender_ward,                                                                               \
        &mr_brdf_gltf, &mr_brdf_gltf_specgloss, &mr_brdf_cycles_principled, &mr_brdf_cycles_ggx,             \
        &mr_brdf_openpbr, &mr_brdf_blender_principled, &mr_brdf_usd_preview, &mr_brdf_standard_surface,

#endif /* MR_BRDF_MODELS_H */
