/*
 * doc.h — material documents: MaterialX 1.39 (.mtlx) and USD (.usda, UsdPreviewSurface) written from a small model.
 *
 *   mr_doc *doc = mr_doc_create();
 *   mr_doc_material *m = NULL;
 *   mr_doc_add_material(doc, "Metal", mr_brdf_find("openpbr"), &m);       // every parameter unset: node defaults
 *   mr_doc_set_constant(m, "base_color", (double[3]){0.9, 0.6, 0.2});
 *   mr_doc_set_texture(m, "specular_roughness", "metal_mr.png", 1, 0, NULL);  // G channel of a map, UV set 0
 *   mr_doc_write(doc, "out.mtlx");                                        // the format by the extension
 *   mr_doc_free(doc);
 *
 *   mr_gltf *asset; mr_gltf_load("a.gltf", &asset);                        // a glTF asset converted (gltf/)
 *   mr_doc_gltf_options o = {0};  o.target = mr_brdf_find("usd-preview"); o.image_prefix = "out";
 *   mr_doc_gltf_result *r;  mr_doc_from_gltf(asset, &o, &r);               // remaps, maps carried or converted
 *   ... check r->images[i].path, r->maps[i].path against the inputs ... mr_doc_gltf_write(asset, r, "out.usda");
 *   mr_doc_gltf_result_free(r);
 *
 * A material is a name, a target BRDF model from the registry (openpbr, standard-surface, gltf: MaterialX;
 * usd-preview: USD) and, per parameter of the model, nothing (the node's own default), a constant (linear values) or
 * a texture: a file (as written into the document, relative to it), a channel (-1: the map's RGB for a colour
 * parameter, or its first channel for a scalar; 0..3 = R, G, B, A), a UV set and a scale (glTF's factor times the
 * texel; 1: none).
 *
 * What is written (docs/documents.md): only inputs that the node definitions declare (mr_doc_node_inputs, a table of
 * facts read from MaterialX's libraries and the UsdPreviewSurface specification; tests/test_doc.c checks every
 * written input against it). A texture's colour space follows the one rule of parameter maps (io/image_io.h,
 * mr_brdf_param_map_encoding): a parameter flagged MR_PARAM_SRGB_MAP in an 8/16-bit file is sRGB ("srgb_texture" in
 * MaterialX, sourceColorSpace "sRGB" in USD), anything else is data (no colorspace in MaterialX: the document's
 * lin_rec709 working space, no conversion; "raw" in USD); float files (.exr, .hdr) are linear either way.
 *
 * Errors follow mr_status.h. The document owns its strings (copied on set). Not thread-safe per document.
 */
#ifndef MR_DOC_H
#define MR_DOC_H

#include "../brdf/brdf.h"
#include "../mr_image.h"
#include "../mr_status.h"
#include "../remap/direct.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum mr_doc_format {
    MR_DOC_FORMAT_UNKNOWN = 0,
    MR_DOC_FORMAT_MTLX, /* MaterialX 1.39 */
    MR_DOC_FORMAT_USDA  /* USD ASCII, UsdPreviewSurface */
} mr_doc_format;

typedef enum mr_doc_value_kind {
    MR_DOC_UNSET = 0, /* not written: the node's default */
    MR_DOC_CONSTANT,
    MR_DOC_TEXTURE
} mr_doc_value_kind;

/* How a map repeats outside [0, 1] along u (s) or v (t). */
typedef enum mr_doc_wrap {
    MR_DOC_WRAP_UNSET = 0, /* not written: the node's default (MaterialX: periodic; USD: useMetadata) */
    MR_DOC_WRAP_REPEAT,    /* MaterialX "periodic", USD "repeat" */
    MR_DOC_WRAP_CLAMP,     /* "clamp" in both */
    MR_DOC_WRAP_MIRROR     /* "mirror" in both */
} mr_doc_wrap;

typedef struct mr_doc_value {
    mr_doc_value_kind kind;
    double constant[3]; /* MR_DOC_CONSTANT: linear values, channels of the parameter */
    char *file;         /* MR_DOC_TEXTURE: as written into the document (owned) */
    int channel;        /* -1: RGB (colour parameter) or first channel (scalar); 0..3: R, G, B, A */
    int uv_set;         /* 0: the first UV set ("st" in USD, texcoord 0 in MaterialX) */
    double scale[3];    /* multiply the texel's channels (after decoding to linear): 1 = none; a scalar's in [0] */
    mr_doc_wrap wrap_s, wrap_t; /* UNSET unless mr_doc_set_texture_wrap */
} mr_doc_value;

/* A constant input of the material's surface node that is no parameter of its model (a lobe matremap's models do
 * not have: transmission, subsurface, emission, sheen, thin film, opacity, ...), as read from a MaterialX document:
 * written back unchanged by the writers when the node is the same, reported as not carried otherwise. */
typedef struct mr_doc_extra {
    char *name;       /* the node's input name (owned) */
    char type[16];    /* its MaterialX type: "float", "color3", "vector3", "integer", "boolean" */
    double value[3];  /* the channels of the type (boolean, integer: value[0] = 0/1, the integer) */
} mr_doc_extra;

typedef struct mr_doc_material {
    char *name;                 /* as given (owned); written as an identifier (mr_doc_identifier) */
    const mr_brdf_model *model; /* openpbr, standard-surface, gltf, usd-preview */
    mr_doc_value values[MR_BRDF_MAX_VALUES]; /* by parameter index of the model */
    int extra_count;
    mr_doc_extra *extras;       /* (owned) mr_doc_add_extra */
} mr_doc_material;

typedef struct mr_doc mr_doc;

/* An empty document; NULL when out of memory. */
mr_doc *mr_doc_create(void);
void mr_doc_free(mr_doc *doc);
int mr_doc_material_count(const mr_doc *doc);
/* The k-th material (NULL outside [0, count)); the pointer stays valid until the next add or the free. */
mr_doc_material *mr_doc_material_at(mr_doc *doc, int k);
const mr_doc_material *mr_doc_material_get(const mr_doc *doc, int k);
/* Appends a material of `model` (every parameter unset). MR_ERR_INVALID_ARG when no format can write the model
 * (the message lists those that can), MR_ERR_NOMEM. *out (may be NULL) receives it. */
mr_status mr_doc_add_material(mr_doc *doc, const char *name, const mr_brdf_model *model, mr_doc_material **out);
/* The parameter called `param` of the material's model set to constant values (the parameter's channel count
 * read from `values`). MR_ERR_INVALID_ARG naming an unknown parameter or a non-finite value. */
mr_status mr_doc_set_constant(mr_doc_material *m, const char *param, const double *values);
/* The parameter set to a texture (see the header comment); scale: the parameter's channel count of factors, NULL =
 * 1. MR_ERR_INVALID_ARG: unknown parameter, a switch parameter, an empty file or one holding '@', '"' or a control
 * character, a channel outside -1..3, a single channel for a colour parameter, a negative UV set, a non-finite
 * scale. */
mr_status mr_doc_set_texture(mr_doc_material *m, const char *param, const char *file, int channel, int uv_set,
                             const double *scale);

/* The wraps of a parameter set to a texture. MR_ERR_INVALID_ARG: unknown parameter, no texture, a wrap outside the
 * enum. */
mr_status mr_doc_set_texture_wrap(mr_doc_material *m, const char *param, mr_doc_wrap wrap_s, mr_doc_wrap wrap_t);

/* An extra constant input (mr_doc_extra) of the material's surface node: `input` must be declared by the node that
 * writes the model (mr_doc_node_inputs, in MaterialX for openpbr, standard-surface, gltf and usd-preview's
 * UsdPreviewSurface) with type `type`, and not carry a parameter of the model. MR_ERR_INVALID_ARG naming the input
 * otherwise, or a non-finite value; a repeated input replaces the earlier one. */
mr_status mr_doc_add_extra(mr_doc_material *m, const char *input, const char *type, const double *value);

/* The format of a path by its extension (".mtlx", ".usda", case-insensitive); UNKNOWN otherwise. */
mr_doc_format mr_doc_format_from_path(const char *path);
/* "mtlx", "usda"; NULL for UNKNOWN. */
const char *mr_doc_format_name(mr_doc_format format);
/* The surface shader node that writes `model` in `format` ("open_pbr_surface", "standard_surface", "gltf_pbr",
 * "UsdPreviewSurface"), or NULL when the format cannot write it. */
const char *mr_doc_surface_node(const mr_brdf_model *model, mr_doc_format format);
/* The node input that carries parameter `param` of `model` in `format` ("base_color" -> "base_color",
 * usd-preview's "diffuse_color" -> "diffuseColor", standard-surface's "specular_ior" -> "specular_IOR"); NULL when
 * the format cannot write the model or the index is out of range. */
const char *mr_doc_input_name(const mr_brdf_model *model, int param, mr_doc_format format);
/* Whether texels of parameter `param` in `file` are sRGB-encoded (the one rule, header comment): 1 or 0. */
int mr_doc_texture_is_srgb(const mr_brdf_param *param, const char *file);
/* `name` made an identifier both formats accept (letters, digits, '_'; not starting with a digit: "M_" prefixed),
 * into out (size bytes, truncated to fit). */
void mr_doc_identifier(const char *name, char *out, size_t size);

/* A node input as its definition declares it. */
typedef struct mr_doc_node_input {
    const char *name;
    const char *type; /* MaterialX: "float", "color3", "vector2", "integer", "boolean", "filename", "string", ...;
                         USD: "color3f", "float", "int", "normal3f", "token", "asset", "float2", "float4" */
} mr_doc_node_input;
/* The declared inputs (and outputs: mr_doc_node_outputs) of a node this module writes, facts read from
 * MaterialX 1.39's libraries (bxdf/open_pbr_surface.mtlx, standard_surface.mtlx, gltf_pbr.mtlx; stdlib's image,
 * extract, multiply, texcoord; pbrlib's surfacematerial) and the UsdPreviewSurface specification (UsdPreviewSurface,
 * UsdUVTexture, UsdPrimvarReader_float2). `node` is the node's name with its output type for the MaterialX nodes
 * that have several ("image_color3", "extract_color4", "multiply_float"), its name otherwise. NULL (and *count 0)
 * for a node not in the table. */
const mr_doc_node_input *mr_doc_node_inputs(mr_doc_format format, const char *node, int *count);
const mr_doc_node_input *mr_doc_node_outputs(mr_doc_format format, const char *node, int *count);

/* The document's text in `format` into *out (NUL-terminated, caller frees with free()). MR_ERR_INVALID_ARG when a
 * material's model is not written by the format (naming the material and the format's models); MR_ERR_NOMEM. */
mr_status mr_doc_to_text(const mr_doc *doc, mr_doc_format format, char **out);
/* mr_doc_to_text in the format of the path's extension, written atomically (mr_core.h). MR_ERR_INVALID_ARG for
 * another extension; MR_ERR_IO. */
mr_status mr_doc_write(const mr_doc *doc, const char *path);

/* ---- from a glTF asset (gltf_export.c) ---------------------------------------------------------------------- */

struct mr_gltf;
struct mr_learned_set;

/* How a material was converted. */
typedef enum mr_doc_route {
    MR_DOC_ROUTE_COPY = 0, /* glTF to gltf_pbr: the same parameters, exact */
    MR_DOC_ROUTE_REMAP,    /* uniform factors fitted by mr_remap in the fit scene (remap/remap.h) */
    MR_DOC_ROUTE_MAPS,     /* textures carried over unchanged (gltf -> usd-preview's metallic workflow, gltf) */
    MR_DOC_ROUTE_DIRECT,   /* textures converted by the direct remap of every distinct texel (`convert --direct`:
                              mr_learned_convert_material with hops 0), written as new maps */
    MR_DOC_ROUTE_LEARNED   /* textures converted through a chain of learned transforms (`convert --transforms`) */
} mr_doc_route;

/* THE route decision of the document exports (from a glTF asset here, from a MaterialX document too): a material of
 * model `source` into `target`, `textured` when maps feed it, `have_transforms` when learned transforms were given:
 *   uniform:  source == target -> COPY, else REMAP;
 *   textured: source == target, or gltf <-> usd-preview (the same quantities: docs/documents.md) -> MAPS (from
 *             usd-preview: its metallic workflow without clearcoat, which mr_doc_convert checks);
 *             any other pair -> LEARNED with transforms, else DIRECT (mr_doc_from_gltf, mr_doc_convert).
 * MR_ERR_INVALID_ARG for a NULL model or out. */
mr_status mr_doc_choose_route(const mr_brdf_model *source, const mr_brdf_model *target, int textured,
                              int have_transforms, mr_doc_route *out);

/* Progress of a material's DIRECT conversion: the material's index and the direct remap's progress. */
typedef void (*mr_doc_progress_fn)(int material, const mr_direct_progress *progress, void *user);

typedef struct mr_doc_gltf_options {
    const mr_brdf_model *target; /* NULL: openpbr */
    const char *image_prefix;    /* the images the document refers to are written as mr_img_prefixed_name(prefix,
                                    "image<K>.<ext>") (io/image_io.h), referred to by their names relative to
                                    the prefix's folder: give the output's path without its extension. Required
                                    when a material is textured */
    int threads;                 /* of the remaps: 0 = automatic (render.h) */
    int size;                    /* the remaps' fit scene side: 0 = MR_REMAP_DEFAULT_SIZE, as remap, sweep and
                                    convert --direct fit (remap/remap.h) */
    const double *target_values; /* REMAP and DIRECT: the target's values held parameters keep (NULL: the
                                    target's defaults), as mr_remap_options.target_values */
    unsigned held;               /* REMAP and DIRECT: parameters held beside the target's default holds (bit p:
                                    parameter p; mr_brdf_parse_holds), as mr_remap_options.held */
    const mr_brdf_ties *ties;    /* REMAP and DIRECT: target parameters held at the source's values (brdf.h); NULL:
                                    the pair's defaults, mr_brdf_default_ties (openpbr: base_metalness=metallic) */
    double tolerance;            /* DIRECT: the quantisation step (remap/direct.h); 0 = MR_DOC_DEFAULT_TOLERANCE */
    const char *cache_path;      /* DIRECT: the direct remap's cache file (direct.h); NULL = none */
    const struct mr_learned_set *transforms; /* textured materials go LEARNED through the chain from the source
                                    model to the target found among them (mr_learned_find_chain); NULL: DIRECT */
    mr_doc_progress_fn progress; /* DIRECT: optional, as mr_direct_options.progress */
    void *progress_user;
    const char *document_path;   /* mr_doc_convert: the document read, against whose folder its relative map files
                                    are read (DIRECT, LEARNED) and the converted maps named; NULL: the current
                                    folder */
} mr_doc_gltf_options;

/* The direct route's default quantisation step in export: convert's, MR_DIRECT_DEFAULT_TOLERANCE = 6/255 (colours in
 * sRGB-encoded units, 43 levels per channel; roughness in ln units, a relative step of 2.4 %; metallic and other
 * scalars 0.024 absolute). Measured on the shared WaterBottle (2048^2, 4,712 distinct values into openpbr, metalness
 * tied): 47 s of CPU, 93 s wall on a loaded 2-core machine; sphere SSIM 0.996 to the source (12/255: 1,421 values,
 * 19 s of CPU, SSIM 0.990-0.992; docs/documents.md). */
#define MR_DOC_DEFAULT_TOLERANCE MR_DIRECT_DEFAULT_TOLERANCE

typedef struct mr_doc_gltf_material {
    char name[128];      /* the glTF material's name ("" if none) */
    mr_doc_route route;
    int outcome;         /* ROUTE_REMAP: the mr_fit_outcome; -1 otherwise */
    double ssim;         /* ROUTE_REMAP: the fit's SSIM; 1 otherwise */
    double relative_rmse;
    char detail[192];    /* ROUTE_REMAP: the fit's detail line */
    /* ROUTE_DIRECT and ROUTE_LEARNED: the conversion's figures (mr_learned_conversion) */
    int width, height;
    size_t texels;
    size_t unique;          /* DIRECT: distinct quantised values remapped */
    size_t unconverged;     /* DIRECT: texels whose fit did not converge; LEARNED: extrapolated texels */
    size_t failed_check;    /* LEARNED: texels converted by a transform that failed its check */
    size_t clamped;         /* clamped outputs or inputs */
    size_t flagged;         /* any flag (red, green or blue in the flag picture) */
    size_t outcomes[MR_FIT_OUTCOME_COUNT]; /* DIRECT: distinct values by fit outcome (mr_fit_outcome order) */
    int hops;               /* LEARNED: transforms in the chain */
    double tolerance;       /* DIRECT: the quantisation step used */
    double seconds;         /* the conversion's wall time */
    char not_carried[1024]; /* mr_doc_convert: the source's authored extra inputs (mr_doc_extra) the output does
                               not carry, comma-separated ("" none; cut with "..." when longer) */
} mr_doc_gltf_material;

/* A converted map the document refers to (DIRECT, LEARNED): written by mr_doc_gltf_write by the one rule of
 * parameter maps (8-bit PNG; sRGB for MR_PARAM_SRGB_MAP parameters, linear otherwise), or the flag picture. */
typedef struct mr_doc_gltf_map {
    int material;       /* its material's index */
    int param;          /* the target parameter's index; -1: the flag picture (mr_learned_flag_code, linear) */
    char stem[160];     /* the material's part of the name: its identifier, "_<index>" added when taken */
    char path[1024];    /* where it is written: mr_img_prefixed_name(prefix, "<stem>_<param>.png") */
    char file[1024];    /* as the document refers to it */
    mr_image *image;    /* owned */
} mr_doc_gltf_map;

typedef struct mr_doc_gltf_image {
    int image;       /* the asset's image index */
    char path[1024]; /* where it is written */
    char file[1024]; /* as the document refers to it */
} mr_doc_gltf_image;

typedef struct mr_doc_gltf_result {
    mr_doc *doc;
    int material_count;
    mr_doc_gltf_material *materials;
    int image_count;
    mr_doc_gltf_image *images;
    int map_count;
    mr_doc_gltf_map *maps; /* converted maps, written beside the images */
} mr_doc_gltf_result;

/* Every material of `asset` converted to the target model into a document (nothing is written yet), by the route
 * mr_doc_choose_route gives. Uniform materials (no base colour nor metallic-roughness texture): gltf -> COPY, any
 * other target -> REMAP from the gltf model's values (base colour, metallic, roughness; KHR_materials_specular and
 * _ior when present). Textured materials: gltf and usd-preview (metallic workflow) -> MAPS (base colour map ->
 * base_color / diffuse_color, sRGB; metallic-roughness B -> metallic, G -> roughness; factors as scales); openpbr
 * and standard-surface -> DIRECT (or LEARNED with opts->transforms): the material as mr_gltf_material_brdf reads it
 * (factors folded into the decoded maps) converted by mr_learned_convert_material (hops 0: the direct remap with
 * opts' tolerance, holds, scene size and cache; or the chain gltf -> target found among opts->transforms), every
 * target parameter whose converted map holds one value set as that constant, every other as a new map
 * (result->maps, written by mr_doc_gltf_write) read through the textures' UV set and wraps, with the flag picture.
 * Refused (MR_ERR_UNSUPPORTED, naming the material): KHR_materials_pbrSpecularGlossiness-only materials,
 * KHR_texture_transform, a texture whose image is missing, and for DIRECT/LEARNED maps on different UV sets or wrap
 * modes (a converted map holds every parameter of a texel); maps of different sizes are the conversion's
 * MR_ERR_INVALID_ARG; no chain: mr_learned_find_chain's MR_ERR_INVALID_ARG. An asset without materials:
 * MR_ERR_INVALID_ARG. */
mr_status mr_doc_from_gltf(const struct mr_gltf *asset, const mr_doc_gltf_options *opts, mr_doc_gltf_result **out);
/* The result's images written (mr_gltf_image_write_file: atomic, never over an input; `asset` may be NULL when the
 * result has no images, as mr_doc_convert's), then its converted maps
 * (mr_img_write_set, all or none: 8-bit PNG, sRGB for MR_PARAM_SRGB_MAP parameters, linear otherwise, the flag
 * picture linear), then the document (mr_doc_write). On failure the images and maps already written are removed. */
mr_status mr_doc_gltf_write(const struct mr_gltf *asset, const mr_doc_gltf_result *result, const char *path);
void mr_doc_gltf_result_free(mr_doc_gltf_result *result);
/* "copy", "remap", "maps", "direct", "learned". */
const char *mr_doc_route_name(mr_doc_route route);

/* ---- from a MaterialX document (mtlx_read.c, doc_convert.c) --------------------------------------------------- */

/* The materials of a MaterialX 1.38/1.39 document (docs/documents.md, "Reading MaterialX"): each top-level
 * surfacematerial's surfaceshader, a node of open_pbr_surface (model openpbr), standard_surface
 * (standard-surface), gltf_pbr (gltf) or UsdPreviewSurface (usd-preview); its inputs constants, or maps through
 * image|tiledimage (+ texcoord) (+ extract) (+ multiply) in a nodegraph (nodegraph=, output=) or at the top level
 * (nodename=), with their wraps, UV sets, scales and colour spaces; a map's file as it is relative to the document
 * (fileprefix applied; mr_doc_rebase for another folder). Constant inputs the node declares that are no parameter
 * of the model become extras (mr_doc_extra). MR_ERR_UNSUPPORTED, naming the file, the line, the material and what
 * it cannot follow: any other node, interfacename, nodegraphs with interfaces or node definitions, other node
 * definition versions, a connected input that is no model parameter, a map whose colour space differs from the
 * one rule (doc.h header), tiling or offsets, another working colour space, looks, xi:include, a DOCTYPE.
 * MR_ERR_FORMAT: not well-formed XML, an input not in the node's definition or of another type (naming both), a
 * missing node, a malformed value, no surfacematerial. MR_ERR_IO: the file cannot be read. */
mr_status mr_doc_read_mtlx(const char *path, mr_doc **out);

/* The relative map files of `doc` (relative to the folder of document `from`) rewritten relative to the folder of
 * document `to` (absolute ones stay). MR_ERR_INVALID_ARG for a file that cannot be named (too long). */
mr_status mr_doc_rebase(mr_doc *doc, const char *from, const char *to);

/* Every material of `in` converted to opts->target (NULL: openpbr) into a new document, by mr_doc_choose_route:
 * the same model -> MR_DOC_ROUTE_COPY (every value, map and extra); a uniform material of another model ->
 * MR_DOC_ROUTE_REMAP (its values, unset ones the model's defaults, fitted by mr_remap as mr_doc_from_gltf does, with
 * opts' holds and ties); a textured one -> MR_DOC_ROUTE_MAPS where the parameters are the same quantities (gltf <->
 * usd-preview's metallic workflow: base colour, metallic, roughness, constant ior), otherwise DIRECT (or LEARNED with
 * opts->transforms) as mr_doc_from_gltf converts a glTF material: the source material built from the document's map
 * files (relative ones read against opts->document_path's folder, by the one rule of parameter maps, each map's
 * channel, its scale folded into the texels) and constants, its maps on one UV set with one pair of wraps
 * (otherwise MR_ERR_UNSUPPORTED) and of one size; the converted maps in result->maps (opts->image_prefix required),
 * referred to relative to the input document's folder (mr_doc_rebase then names them for the output), written by
 * mr_doc_gltf_write(NULL, ...). Errors name `label` (how the caller names the input, e.g. "MaterialX 'in.mtlx'"),
 * the material and the route. Extras the target does not carry are listed per material (not_carried). The result
 * has no images (the carried maps keep their files). */
mr_status mr_doc_convert(const mr_doc *in, const char *label, const mr_doc_gltf_options *opts,
                         mr_doc_gltf_result **out);

/* A document whose materials are all of the gltf model (e.g. mr_doc_convert's result with target gltf) as a new
 * glTF asset (gltf/mr_gltf.h: mr_gltf_create; no scene or mesh), for mr_gltf_save_with: pbrMetallicRoughness's
 * factors from the constants (KHR_materials_specular when specular or specular_color is a map or differs from the
 * extension's default 1, KHR_materials_ior when ior differs from 1.5), and maps as textures whose images are the
 * document's files (relative to document `doc_path`'s folder), read with mr_gltf_add_image_file under their file
 * names (name_after_output prefixes them on save), with a sampler of their wraps; a map's scale is the factor.
 * MR_ERR_UNSUPPORTED naming `label`, the material and the map where glTF cannot hold it: metallic not from B or
 * roughness not from G (metallicRoughnessTexture) or the two from different files, UV sets or wraps, specular not
 * from A, an ior map, a file that is not PNG or JPEG. The caller frees the asset (mr_gltf_free). */
mr_status mr_doc_to_gltf(const mr_doc *doc, const char *doc_path, const char *label, struct mr_gltf **out);

/* ---- one asset exported to one file (export.c) -------------------------------------------------------------- */

/* What `matremap export IN -o OUT` does, in one call (zeroed = the defaults said per field). */
typedef struct mr_doc_export_options {
    const mr_brdf_model *target; /* NULL: OUT's default, mr_doc_export_default_target */
    const double *target_values; /* as mr_doc_gltf_options (NULL: the target's defaults) */
    unsigned held;               /* as mr_doc_gltf_options */
    const mr_brdf_ties *ties;    /* NULL: each source model's default ties less `held`; given: these (a glTF input:
                                    gltf's ties, e.g. mr_brdf_parse_ties; a .mtlx: applied to every model, so only
                                    "none", a zeroed struct, is meaningful) */
    int threads, size;           /* as mr_doc_gltf_options */
    double tolerance;            /* DIRECT: 0 = MR_DOC_DEFAULT_TOLERANCE */
    const char *cache_path;      /* DIRECT: NULL = none */
    const struct mr_learned_set *transforms; /* NULL: DIRECT for textured materials of another model */
    mr_doc_progress_fn progress; /* DIRECT: optional */
    void *progress_user;
} mr_doc_export_options;

#define MR_DOC_EXPORT_MAX_SOURCES 16

/* What an export did, for the caller to say: per material its route and figures, the images and maps written
 * (result), the format written, the target, and the ties the fits took per source model. */
typedef struct mr_doc_export_report {
    mr_doc_gltf_result *result;  /* owned (its doc the converted document); NULL when the export failed */
    const mr_brdf_model *target;
    char format[8];              /* "mtlx", "usda", "gltf" or "glb" */
    int source_count;            /* source models the ties are said for (a glTF input: 1, gltf; a .mtlx: each
                                    model with a REMAP material) */
    const mr_brdf_model *sources[MR_DOC_EXPORT_MAX_SOURCES];
    mr_brdf_ties ties[MR_DOC_EXPORT_MAX_SOURCES];
} mr_doc_export_report;

/* `input` (a glTF asset .gltf/.glb, or a MaterialX document .mtlx) exported to `output`, whose extension chooses
 * the format: .mtlx or .usda (mr_doc_from_gltf or mr_doc_read_mtlx + mr_doc_convert, then mr_doc_gltf_write: the
 * images beside OUT named OUT_image<K>, converted maps OUT_<material>_<param>.png; a .mtlx's maps rebased), .gltf or
 * .glb (a glTF input: the asset itself saved with side files named after OUT; a .mtlx: mr_doc_to_gltf; DIRECT or
 * LEARNED materials refused, MR_ERR_UNSUPPORTED, before any work). Nothing is written over a file read
 * (io/output_plan.h: OUT, the images, maps and the cache against the input's files, the maps a document names and
 * the transforms), checked before the work and again once the outputs are named; folders made for OUT are removed
 * again on failure. MR_ERR_INVALID_ARG: an input or output extension not listed, a target OUT's format does not
 * write. Otherwise the errors of the calls named, with their messages. *report is zeroed first and filled on
 * success (mr_doc_export_report_free). Nothing is printed. */
mr_status mr_doc_export_file(const char *input, const char *output, const mr_doc_export_options *opts,
                             mr_doc_export_report *report);
void mr_doc_export_report_free(mr_doc_export_report *report);
/* OUT's default model: .mtlx openpbr, .usda usd-preview, .gltf/.glb gltf; NULL for another extension. */
const mr_brdf_model *mr_doc_export_default_target(const char *output);
/* 1 when `path`'s extension is one export writes (.mtlx, .usda, .gltf, .glb). */
int mr_doc_export_output_ok(const char *path);

/* ---- many assets exported in one call (export_library.c) ------------------------------------------------------ */

struct mr_gltf_library_options;
struct mr_gltf_library_result;

/* The assets inputs[input_count] (gltf/mr_gltf_library.h's listing: files, folders walked for .gltf/.glb, globs)
 * each exported by mr_doc_export_file with `each` (its threads and progress set by the loop) to OUT_DIR/<its path
 * below the common root> with the extension replaced by `extension` (".mtlx", ".usda", ".gltf" or ".glb"), by
 * mr_gltf_convert_library's loop with `library`'s threads, progress, cancel, resume (library->settings: what the
 * export was told), shards and thumbnails (its convert and job unused; with each->cache_path the assets run one at
 * a time, `serial`: the cache takes one user at a time): summary.json (per asset the format, target,
 * materials with their routes and figures, images and maps) and index.html. The after-render (thumbnails, object
 * SSIM) is of a glTF output only (.gltf/.glb: the exported asset against the input); a .mtlx or .usda output holds
 * no geometry and is not rendered (null). A failed asset is recorded and the others go on (result->failed).
 * MR_ERR_INVALID_ARG: another extension; otherwise mr_gltf_convert_library's errors. */
mr_status mr_doc_export_library(const char *const *inputs, int input_count, const char *out_dir,
                                const mr_doc_export_options *each, const char *extension,
                                const struct mr_gltf_library_options *library, struct mr_gltf_library_result *result);

#ifdef __cplusplus
}
#endif

#endif /* MR_DOC_H */
