/*
 * mr_gltf_convert.h — a glTF asset's materials converted between the PBR workflows through a transform
 * (src/transform/transform.h): metal-rough from KHR_materials_pbrSpecularGlossiness (gltf-specgloss -> gltf), or
 * spec-gloss beside metal-rough (gltf -> gltf-specgloss). What `matremap gltf` does; docs/architecture.md draws it.
 *
 *   mr_gltf *asset;  mr_gltf_load("in.gltf", &asset);
 *   mr_transform *t;  mr_transform_create(mr_transform_find("gltf-specgloss", "gltf", "weighted"), NULL, &t);
 *   mr_gltf_convert_options o = {0};  o.transform = t;
 *   mr_gltf_convert(asset, &o, NULL);
 *   mr_gltf_prune_unused(asset, NULL);  mr_gltf_save(asset, "out/out.gltf");
 * or all of it, load to save, in one call: mr_gltf_convert_file("in.gltf", "out/out.gltf", &o, &result)
 * (docs/examples/convert_asset.c), summed up by mr_gltf_convert_totals_of(&result, &totals).
 *
 * Per material: the source workflow's factors times its textures, in linear values (colour textures sRGB-decoded,
 * glossiness and alpha linear), on the grid of the larger source texture (the smaller resampled bilinearly, texel
 * centres aligned), through the transform; the target's textures are new PNG (or EXR) images packed as glTF packs
 * them (metal-rough: base colour RGB + the diffuse's alpha, metallicRoughness G = roughness, B = metallic, R = 0;
 * spec-gloss: diffuse RGB + the base colour's alpha, specularGlossiness RGB = specular, A = glossiness), with the
 * sampler and texture transform of the first source texture and factors 1. A material without textures gets
 * factors only. An output the transform repeats unchanged (mr_transform_slot.copy_of) reuses the source texture and
 * factor instead of a new image, and a constant output becomes a factor (the extension route: KHR_materials_specular
 * and KHR_materials_ior, no texel converted but glossiness). Materials whose sources are the same images with the
 * same factors share one conversion and its textures.
 *
 * Which materials: gltf-specgloss -> gltf converts every material carrying the spec-gloss extension, except (unless
 * `overwrite`) those with metal-rough values of their own (textures or factors other than glTF's defaults: the
 * artist's fallback is kept); the extension is then removed unless `keep_source`. gltf -> gltf-specgloss converts
 * every material without the extension and keeps the metal-rough core as the fallback.
 *
 * Threads: the transform's option. Memory: the decoded source textures, the 8-bit target textures, and planes of one
 * band of rows. Errors name the asset, the material and the texture; on failure the asset may hold some converted
 * materials (load it again to retry). Nothing is printed.
 */
#ifndef MR_GLTF_CONVERT_H
#define MR_GLTF_CONVERT_H

#include <stddef.h>

#include "gltf/mr_gltf.h"
#include "transform/transform.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct mr_gltf_convert_options {
    const mr_transform *transform; /* required: gltf-specgloss -> gltf, or gltf -> gltf-specgloss */
    const char *image_format;      /* "png" (default) or "exr" for the new images */
    const char *image_prefix;      /* new images are PREFIX_mK_NAME.EXT beside the output; NULL = "converted", or
                                      for mr_gltf_convert_file the output's name without its extension */
    int overwrite;                 /* 1: convert spec-gloss materials that have metal-rough values of their own */
    int keep_source;               /* 1: keep the spec-gloss extension on converted materials */
    int exact_inputs;              /* 1: inputs exact to the transform's eps; 0 (default): each value known to half a
                                      code of its texture, times its factor (workflow.h, "Tolerances") */
    int keep_unused;               /* mr_gltf_convert_file: 1 keeps textures, images and samplers nothing refers to
                                      any more; 0 (default) prunes them (mr_gltf_prune_unused) */
    void (*progress)(void *user, int material, int material_count); /* after each material; may be NULL */
    void *progress_user;
    int replace_files;             /* mr_gltf_convert_file: 1 lets a side file of the output replace an existing
                                      file that is not the earlier output's own (mr_gltf_save_options) */
    const char *replace_hint;      /* mr_gltf_convert_file: what allows it, named in the refusal (NULL: the field) */
    int core_only;                 /* gltf-specgloss -> gltf but the extension route: 1 writes the core metal-rough
                                      values alone; 0 (default) adds KHR_materials_specular values solved per texel
                                      over them (mr_gltf_specular_color_solve), to kept materials too, so that
                                      engines reading the extension see the spec-gloss F0 ("both readings"); not
                                      with image_format "exr" or keep_source (the report's extension_note says) */
    double extension_ior;          /* the ior those values are solved for: 0 = 1.5, glTF's default (no
                                      KHR_materials_ior written); any other value in (1, 1e4] is written there */
} mr_gltf_convert_options;

typedef enum mr_gltf_convert_outcome {
    MR_GLTF_SKIPPED = 0, /* nothing to convert (no spec-gloss extension; or gltf -> gltf-specgloss: it has one) */
    MR_GLTF_CONVERTED,
    MR_GLTF_KEPT,        /* its own metal-rough values kept (overwrite converts them) */
    MR_GLTF_SHARED       /* converted, sharing the conversion of an earlier material with the same sources */
} mr_gltf_convert_outcome;

/* What happened to one material. */
typedef struct mr_gltf_material_report {
    char name[128];    /* the material's name ("" if none; truncated) */
    mr_gltf_convert_outcome outcome;
    char reason[256];  /* why kept or skipped; "" otherwise */
    int width, height; /* texture grid, 0 when factors only */
    size_t flagged;    /* texels with any mr_wf_flag */
    size_t off_manifold, nonfinite, clamped, failed; /* texels with each flag */
    double seconds;
    /* KHR_materials_specular over the core values (both readings; mr_gltf_convert_options.core_only = 0) */
    int extension;            /* 1: specular values written */
    char extension_note[160]; /* why not, when the material qualified but got none ("" otherwise) */
    size_t texels;            /* texels the solve saw (its grid), 1 for factors only */
    size_t f0_unmet;          /* texels whose spec-gloss F0 the extension cannot give (MR_GLTF_F0_* flags) */
    size_t diffuse_off;       /* texels whose core diffuse base (1 - metallic) differs from the spec-gloss diffuse
                                 (as the convention reads it) by more than MR_GLTF_HYBRID_TOLERANCE in a channel:
                                 the base colour both readings share cannot be right for both there */
    double f0_max_error;      /* largest |F0 - specular| left, any channel */
    double diffuse_mean_error, diffuse_max_error; /* |base (1 - metallic) - diffuse|: mean over texels and
                                                     channels, largest */
} mr_gltf_material_report;

/* ---- both readings: KHR_materials_specular over a core metal-rough texel ----
 * An engine that reads KHR_materials_specular (and KHR_materials_ior) sees, per the extension's README
 * ("Implementation") and three.js's MeshPhysicalMaterial alike:
 * F0 = mix(min(F0(ior) specularColor, 1) specular, base, metallic), F90 = mix(specular, 1, metallic),
 * diffuse colour base (1 - metallic), F0(ior) = ((ior - 1) / (ior + 1))^2. With the
 * core base and metallic fixed, specular 1 (F90 = 1, as spec-gloss has it) and a specular colour per channel
 * (target - metallic base) / ((1 - metallic) F0(ior)) give F0 = target exactly, where that lies in
 * [0, 1 / F0(ior)]. Outside it the colour is clamped and the texel flagged: */
enum {
    MR_GLTF_F0_BELOW = 1, /* the metal part alone (metallic x base) reflects more than the target in some channel */
    MR_GLTF_F0_ABOVE = 2, /* the dielectric part cannot add enough: min(F0(ior) specularColor, 1) caps it */
    MR_GLTF_F0_METAL = 4  /* metallic 1: F0 is the base colour, which is not the target (no dielectric to set) */
};
/* Flags are raised when the F0 left differs from the target by more than this (linear, any channel); the same
 * bound decides diffuse_off. One 8-bit linear code. */
#define MR_GLTF_HYBRID_TOLERANCE (1.0 / 255.0)

/* The specular colour (linear, before any factor) that makes F0 = target at a texel of core base colour `base` and
 * metallic `metallic` for an engine reading the extensions with specular 1 and `ior` (> 1); returns MR_GLTF_F0_*
 * flags (0: exact). Inputs outside [0, 1] are clamped first; at metallic 1 (no dielectric part) the colour is
 * the one a dielectric texel would take, target / F0(ior) clamped, so that a filtered texture stays smooth. */
unsigned mr_gltf_specular_color_solve(const float base[3], float metallic, const float target[3], double ior,
                                      float color[3]);

/* Convert the asset's materials in place. reports: NULL or one per material (mr_gltf_get_counts). MR_ERR_INVALID_ARG
 * for a missing transform or one between other models, an unknown image format; the texture readers' errors
 * (naming asset and image); MR_ERR_FORMAT for a material whose two source textures map onto the surface
 * differently (texture coordinates or transform); MR_ERR_NOMEM. */
mr_status mr_gltf_convert(mr_gltf *asset, const mr_gltf_convert_options *opts, mr_gltf_material_report *reports);

/* What mr_gltf_convert_file did. */
typedef struct mr_gltf_convert_result {
    int material_count;
    mr_gltf_material_report *materials; /* [material_count]; owned, released by mr_gltf_convert_result_free */
    mr_gltf_prune_stats pruned;          /* what pruning removed (zeros with keep_unused) */
} mr_gltf_convert_result;

/* The whole job in one call: load `input`, convert (mr_gltf_convert), prune what nothing refers to any more (unless
 * keep_unused), and save `output` (.gltf with its files beside it, or .glb; never over an input file) through
 * mr_gltf_save_with, its side files named after the output (out/floppy.gltf: floppy.bin, floppy_m0_basecolor.png,
 * floppy_NAME for a copied image) and never replacing an existing file that is not a side file of the earlier output
 * at `output` (unless replace_files: MR_ERR_INVALID_ARG, nothing written). A spec-gloss
 * extension kept beside the new core material (keep_source, or gltf -> gltf-specgloss) is made optional, so engines
 * without it read the core material. *result (may be NULL) is filled on success and zeroed on failure. Errors are
 * mr_gltf_load's, mr_gltf_convert's and mr_gltf_save's. */
mr_status mr_gltf_convert_file(const char *input, const char *output, const mr_gltf_convert_options *opts,
                               mr_gltf_convert_result *result);

/* Releases result->materials and zeroes *result; NULL-safe. */
void mr_gltf_convert_result_free(mr_gltf_convert_result *result);

/* A conversion's totals over its materials. */
typedef struct mr_gltf_convert_totals {
    int converted;                 /* materials converted (MR_GLTF_CONVERTED, and MR_GLTF_SHARED reusing one) */
    int kept;                      /* materials kept with metal-rough values of their own (MR_GLTF_KEPT) */
    size_t texels;                 /* texels converted: each conversion once (MR_GLTF_CONVERTED only: materials
                                      sharing its sources wrote no textures of their own), 1 for factors only */
    mr_gltf_material_report total; /* flagged, off_manifold, nonfinite, clamped, failed, and the extension's
                                      texels, f0_unmet, diffuse_off summed (f0_max_error, diffuse_max_error the
                                      largest; diffuse_mean_error over those texels) over the same conversions and
                                      every kept material that got extension values; the other fields zero */
    int extensions;                /* materials given KHR_materials_specular values over their core ones */
} mr_gltf_convert_totals;

/* The totals of `result` (NULL: all zero) into *out. */
void mr_gltf_convert_totals_of(const mr_gltf_convert_result *result, mr_gltf_convert_totals *out);

#ifdef __cplusplus
}
#endif

#endif /* MR_GLTF_CONVERT_H */
