/*
 * mr_gltf.h — glTF 2.0 assets in and out: PBR materials, textures, samplers and images (C API over tinygltf).
 *
 * Usage:
 *     mr_gltf *asset = NULL;
 *     if (mr_gltf_load("in.gltf", &asset) != MR_OK) { fprintf(stderr, "%s\n", mr_last_error()); ... }
 *     mr_gltf_material m;
 *     mr_gltf_get_material(asset, 0, &m);          // every field, glTF defaults where the file has none
 *     m.has_spec_gloss = 0;                         // drop KHR_materials_pbrSpecularGlossiness
 *     m.metallic_factor = 0.0;
 *     mr_gltf_set_material(asset, 0, &m);
 *     mr_gltf_save(asset, "out/out.gltf");          // or .glb; buffers and images written beside it
 *     mr_gltf_free(asset);
 *
 * Ownership: mr_gltf_load creates the asset, mr_gltf_free (NULL-safe) releases it and everything reachable from
 * it. Strings and byte pointers handed out (material names, image bytes, mime types, paths) belong to the asset
 * and stay valid until the asset is modified or freed. The exception is geometry: mr_gltf_get_triangles returns a
 * copy the caller owns and releases with mr_gltf_triangles_free (see "Geometry" below).
 *
 * Images are never decoded on load or save: the encoded bytes (PNG, JPEG, ...) of every image are kept as read and
 * written back unchanged. A caller that needs pixels decodes them with mr_gltf_image_read / mr_gltf_texture_read
 * (external images from their file, embedded ones from memory), or takes the bytes (mr_gltf_get_image, written to
 * a file by mr_gltf_image_write_file) to a decoder of its own.
 *
 * Saving (mr_gltf_save) picks the container from the extension (.gltf or .glb). A .gltf is written with its
 * resources beside it: external buffers and images under their original relative URIs (or a fresh name when
 * the URI is absolute or leaves the output directory), data-URI buffers and images kept as data URIs, images
 * stored in buffer views kept there; a .glb's binary chunk becomes "<name>.bin" beside a .gltf output. A .glb
 * output is self-contained: every buffer is packed into its binary chunk (views moved accordingly; one buffer
 * is left, with the first one's name and extras) and every image gets a buffer view there, its bytes
 * unchanged (an asset using EXT_meshopt_compression, which points into buffers by index, is not packed and
 * keeps external files like a .gltf). Every file is written to a temporary name and renamed when
 * complete; on failure the files this call created are removed. The output and its resources are never
 * written over a file the asset was read from, even one an edit has since removed from the asset (a new image
 * named like a pruned image's file gets a fresh name; an unchanged resource that would land on its own source is
 * left in place). extensionsUsed/extensionsRequired are brought up to date first (mr_gltf_sync_extensions).
 * mr_gltf_save_with can name the side files after the output (out/floppy.gltf: floppy.bin, floppy_NAME.png) and
 * refuses to replace an existing file that is not a side file of the output it replaces (mr_gltf_save_options).
 *
 * Everything this API does not touch (meshes, nodes, animations, skins, cameras, scenes, extras, other
 * extensions, properties outside the schema) is written back: what tinygltf 2.7 parses but does not write
 * (asset.minVersion, skins' extras, unknown properties, default values) is restored from the file's own JSON,
 * except inside what this API edits (see gltf/README.md).
 *
 * Threading: an asset may be used by one thread at a time; distinct assets are independent. Errors follow
 * mr_status.h: a status, and a one-line message naming the file and the value in mr_last_error().
 */
#ifndef MR_GLTF_H
#define MR_GLTF_H

#include <stddef.h>
#include <stdint.h>

#include "io/image_io.h"
#include "mr_status.h"
#include "render/render.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct mr_gltf mr_gltf;

/* A texture reference (glTF textureInfo) with its KHR_texture_transform. index -1 = no texture. */
typedef struct mr_gltf_texture_ref {
    int index;               /* textures[] index, -1 = none */
    int tex_coord;           /* TEXCOORD_n set, default 0 */
    double value;            /* normalTexture.scale / occlusionTexture.strength (default 1); unused elsewhere */
    int has_transform;       /* KHR_texture_transform present */
    double offset[2];        /* default 0,0 */
    double rotation;         /* radians, default 0 */
    double scale[2];         /* default 1,1 */
    int transform_tex_coord; /* the transform's texCoord override, -1 = none */
} mr_gltf_texture_ref;

typedef enum mr_gltf_alpha_mode {
    MR_GLTF_ALPHA_OPAQUE = 0,
    MR_GLTF_ALPHA_MASK,
    MR_GLTF_ALPHA_BLEND
} mr_gltf_alpha_mode;

/* Every material field this API reads and writes. mr_gltf_material_defaults() gives glTF's defaults. */
typedef struct mr_gltf_material {
    const char *name; /* "" if none; owned by the asset on get, copied on set (NULL = "") */

    /* core pbrMetallicRoughness */
    double base_color_factor[4];                    /* default 1,1,1,1 */
    double metallic_factor;                         /* default 1 */
    double roughness_factor;                        /* default 1 */
    mr_gltf_texture_ref base_color_texture;
    mr_gltf_texture_ref metallic_roughness_texture; /* G = roughness, B = metallic */

    mr_gltf_texture_ref normal_texture;    /* value = scale */
    mr_gltf_texture_ref occlusion_texture; /* value = strength, R channel */
    mr_gltf_texture_ref emissive_texture;
    double emissive_factor[3]; /* default 0,0,0 */
    mr_gltf_alpha_mode alpha_mode;
    double alpha_cutoff; /* default 0.5 */
    int double_sided;

    /* KHR_materials_pbrSpecularGlossiness (has_spec_gloss = 0: absent; set removes it) */
    int has_spec_gloss;
    double diffuse_factor[4];  /* default 1,1,1,1 */
    double specular_factor[3]; /* default 1,1,1 */
    double glossiness_factor;  /* default 1 */
    mr_gltf_texture_ref diffuse_texture;
    mr_gltf_texture_ref specular_glossiness_texture; /* RGB = specular, A = glossiness */

    /* KHR_materials_specular */
    int has_specular;
    double specular_strength;        /* the extension's specularFactor, default 1 */
    double specular_color_factor[3]; /* default 1,1,1 */
    mr_gltf_texture_ref specular_texture;       /* A = strength */
    mr_gltf_texture_ref specular_color_texture; /* RGB */

    /* KHR_materials_ior */
    int has_ior;
    double ior; /* default 1.5 */
} mr_gltf_material;

/* A sampler's filters (glTF's GL numbers only in the file: 9728 NEAREST, 9729 LINEAR, 9984-9987 the mipmap modes). */
typedef enum mr_gltf_filter {
    MR_GLTF_FILTER_UNSET = 0,           /* absent: the viewer chooses */
    MR_GLTF_FILTER_NEAREST,             /* 9728 */
    MR_GLTF_FILTER_LINEAR,              /* 9729 */
    MR_GLTF_FILTER_NEAREST_MIPMAP_NEAREST, /* 9984 */
    MR_GLTF_FILTER_LINEAR_MIPMAP_NEAREST,  /* 9985 */
    MR_GLTF_FILTER_NEAREST_MIPMAP_LINEAR,  /* 9986 */
    MR_GLTF_FILTER_LINEAR_MIPMAP_LINEAR,   /* 9987 */
    MR_GLTF_FILTER_COUNT
} mr_gltf_filter;

/* A texture's sampler, in the renderer's terms (render/render.h): wraps are mr_wrap (MR_WRAP_REPEAT is glTF's
 * default 10497, MR_WRAP_CLAMP 33071 CLAMP_TO_EDGE, MR_WRAP_MIRROR 33648 MIRRORED_REPEAT; MR_WRAP_DEFAULT, a zeroed
 * sampler's, is written as REPEAT). A value the file holds that glTF does not define reads as UNSET / REPEAT. */
typedef struct mr_gltf_sampler {
    mr_gltf_filter mag_filter;
    mr_gltf_filter min_filter;
    mr_wrap wrap_s;
    mr_wrap wrap_t;
} mr_gltf_sampler;

/* What a texture points at. */
typedef struct mr_gltf_texture {
    int image;               /* images[] index, -1 if the texture has no source */
    int sampler;             /* samplers[] index, -1 = default sampler */
    mr_gltf_sampler params;  /* the sampler's values (defaults when sampler is -1) */
} mr_gltf_texture;

/* An image's encoded bytes and where they came from. Pointers belong to the asset. */
typedef struct mr_gltf_image {
    const unsigned char *bytes; /* encoded (PNG/JPEG/...) bytes, NULL if none could be read */
    size_t size;
    const char *mime_type; /* "image/png", "image/jpeg", ... ("" if unknown) */
    const char *uri;       /* the URI as in the file ("" for buffer views and data URIs) */
    const char *path;      /* the resolved file of an external image, "" otherwise */
    int buffer_view;       /* bufferViews[] index, -1 if none */
} mr_gltf_image;

/* Counts of the asset's top-level arrays. */
typedef struct mr_gltf_counts {
    int materials, textures, images, samplers;
    int meshes, nodes, scenes, accessors, buffer_views, buffers;
    int animations, skins, cameras;
} mr_gltf_counts;

/* Reads a .gltf or .glb (by content: a binary glTF starts with "glTF") with its buffers and images: external
 * files relative to the asset (beside it only: not looked for in the working directory), data URIs and GLB chunks.
 * Missing or unreadable buffers and images, malformed JSON and truncated containers fail with MR_ERR_IO /
 * MR_ERR_FORMAT and a message naming the file (and the buffer or image by index and URI).
 *
 * Nothing in the file is trusted (see "Limits" below for the numbers): the JSON's nesting is bounded before any
 * parser sees it; the asset and every file a URI names must be a regular file (a folder, a FIFO, a device such as
 * /dev/zero is refused by name: "glTF 'a.gltf': image 3 ('textures/'): is a directory"); an image in a buffer view
 * must lie within its buffer; and the materials are held against the parts of the glTF schema this API reads,
 * which tinygltf 2.7 does not check (it drops an extension that is not a JSON object, and defaults a factor of the
 * wrong type): every material and extension an object; the factors of the core material and of
 * KHR_materials_pbrSpecularGlossiness, _specular and _ior numbers of the right count, finite and within the
 * schema's ranges; every textureInfo's index a texture of the asset, its texCoord a non-negative integer, its
 * KHR_texture_transform well formed; alphaMode OPAQUE, MASK or BLEND; every texture's source and sampler in range.
 * A failure there is MR_ERR_FORMAT naming the material (index and name), the field and the value ("material 2
 * ('Glass'): extensions.KHR_materials_pbrSpecularGlossiness is a number, not a JSON object"). Accessors are
 * checked when geometry is read (mr_gltf_get_triangles).
 *
 * Limits (MR_ERR_FORMAT past them, each far above what real assets use):
 *   - JSON nesting: 128 levels of arrays and objects (a real asset nests about 10; tinygltf and nlohmann/json
 *     recurse per level, and tens of thousands of levels overflowed the stack);
 *   - the asset and each external buffer or image: 2^31 - 1 bytes (tinygltf 2.7 passes sizes as int);
 *   - geometry (mr_gltf_get_triangles): a scene of at most 2^24 vertices and 2^24 triangles after instancing,
 *     and an accessor without a buffer view (zeros) of at most 2^20 elements; every other count is bounded by
 *     the bytes that hold it. */
mr_status mr_gltf_load(const char *path, mr_gltf **out);

void mr_gltf_free(mr_gltf *asset);

/* The file the asset was read from. */
const char *mr_gltf_path(const mr_gltf *asset);

/* The k-th file the asset was read from: k = 0 the .gltf or .glb itself (mr_gltf_path), then each external buffer
 * and image file as opened (relative to the asset's folder; a file two of them share comes once per reference), as
 * loaded: edits that remove images (mr_gltf_prune_unused) do not remove them here. NULL for k past the last (or a
 * NULL asset). What a writer must never replace: mr_gltf_save and mr_gltf_image_write_file refuse or avoid them,
 * and matremap's commands check their outputs against them. */
const char *mr_gltf_source_file(const mr_gltf *asset, int k);

void mr_gltf_get_counts(const mr_gltf *asset, mr_gltf_counts *out);

/* glTF's default material (no name, no textures, no extensions). */
void mr_gltf_material_defaults(mr_gltf_material *out);

/* A texture reference with no texture (index -1) and identity transform. */
void mr_gltf_texture_ref_none(mr_gltf_texture_ref *out);

mr_status mr_gltf_get_material(const mr_gltf *asset, int material, mr_gltf_material *out);

/* Writes every field of *in into the material. Extensions whose has_* flag is 0 are removed (their fields in *in
 * are ignored, and read back as defaults); present ones are updated in place (keys this API does not know, e.g.
 * extras, are kept; a value equal to what the file means already is left as written). Texture indices must
 * exist and factors be finite (MR_ERR_INVALID_ARG, nothing changed). */
mr_status mr_gltf_set_material(mr_gltf *asset, int material, const mr_gltf_material *in);

/* Removes extension `name` (any extension) from a material; MR_OK (and *removed = 0) if it was absent.
 * removed may be NULL. */
mr_status mr_gltf_remove_material_extension(mr_gltf *asset, int material, const char *name, int *removed);

/* An empty asset: asset.version "2.0", generator "matremap", nothing else (no scene, mesh, material or buffer), for
 * materials added with mr_gltf_add_material and images with mr_gltf_add_image_file (matremap export of a MaterialX
 * document to .gltf/.glb); `label` names it in messages (mr_gltf_path) and is never read. MR_ERR_NOMEM. */
mr_status mr_gltf_create(const char *label, mr_gltf **out);

/* Appends a material with mr_gltf_set_material's fields; *out_material (may be NULL) receives its index. On failure
 * the asset is as it was. */
mr_status mr_gltf_add_material(mr_gltf *asset, const mr_gltf_material *in, int *out_material);

/* Whether a material carries extension `name` (0 or 1; 0 for a bad index). */
int mr_gltf_material_has_extension(const mr_gltf *asset, int material, const char *name);

mr_status mr_gltf_get_texture(const mr_gltf *asset, int texture, mr_gltf_texture *out);

mr_status mr_gltf_get_image(const mr_gltf *asset, int image, mr_gltf_image *out);

/* Writes an image's encoded bytes to `path` (atomically; never over the asset's input files). */
mr_status mr_gltf_image_write_file(const mr_gltf *asset, int image, const char *path);

/* Adds an image read from `file` (PNG, JPEG or EXR by content), saved beside the output under the relative
 * `uri` (no "..", not absolute). *out_image receives its index. */
mr_status mr_gltf_add_image_file(mr_gltf *asset, const char *file, const char *uri, int *out_image);

/* Adds an image from its encoded bytes (PNG, JPEG or EXR by content; copied), saved beside the output under the
 * relative `uri` (no "..", not absolute). *out_image receives its index. */
mr_status mr_gltf_add_image_bytes(mr_gltf *asset, const void *bytes, size_t size, const char *uri, int *out_image);

/* Decodes image `image` (mr_img_read_stored's conventions: opts may be NULL, *stored may be NULL): an external image
 * from its file, an embedded one (data URI, buffer view) from the asset's bytes in memory (mr_img_read_memory;
 * nothing is written to disk). Errors name the asset and the image index ("glTF 'a.gltf': image 3: truncated PNG:
 * ..."; an external image's also name its file). */
mr_status mr_gltf_image_read(const mr_gltf *asset, int image, const mr_img_read_options *opts, mr_image **out,
                             mr_img_stored *stored);

/* The same for the image of texture `texture`; a texture without an image is MR_ERR_FORMAT naming it. */
mr_status mr_gltf_texture_read(const mr_gltf *asset, int texture, const mr_img_read_options *opts, mr_image **out,
                               mr_img_stored *stored);

struct mr_wf_texel_pool;
/* Texels of the asset's spec-gloss materials (KHR_materials_pbrSpecularGlossiness) for `matremap dataset`'s draws
 * (src/workflow/pairs.h): one source of the pool, MR_WF_POOL_SOURCE_TEXELS texels shared equally among those
 * materials, each the diffuse and specular-glossiness textures (decoded as colour textures: sRGB to linear) times
 * their factors at one random position, from the stream of (seed, the pool's source count). *materials gets how
 * many materials were sampled: 0 (an asset without spec-gloss materials) adds nothing and is left to the caller to
 * judge. A texture that cannot be decoded fails with its error (the texels added before it stay). */
mr_status mr_gltf_add_specgloss_texels(const mr_gltf *asset, uint64_t seed, struct mr_wf_texel_pool *pool,
                                       int *materials);

/* The asset at `path` read (mr_gltf_load) and its spec-gloss texels added to the pool (mr_gltf_add_specgloss_texels)
 * in one call, for `matremap dataset --asset PATH`. An asset without spec-gloss materials is MR_ERR_INVALID_ARG
 * "LABEL: no material carries KHR_materials_pbrSpecularGlossiness" (label: how the caller names the asset, "--asset
 * x.gltf"; NULL: "'PATH'"). On success *asset (may be NULL: the asset is freed) gets the asset, the caller's to free
 * (mr_gltf_free), e.g. to list the files it was read from (mr_gltf_source_file); on failure it is NULL. Errors:
 * mr_gltf_load's and mr_gltf_add_specgloss_texels'. */
mr_status mr_gltf_add_specgloss_texels_from_file(const char *path, const char *label, uint64_t seed,
                                                 struct mr_wf_texel_pool *pool, mr_gltf **asset);

/* Adds a texture of `image` with `sampler` (NULL = no sampler, i.e. glTF's defaults); an identical sampler
 * already in the asset is reused. *out_texture receives its index. */
mr_status mr_gltf_add_texture(mr_gltf *asset, int image, const mr_gltf_sampler *sampler, int *out_texture);

/* Brings extensionsUsed up to date for the extensions this API manages (KHR_materials_pbrSpecularGlossiness,
 * KHR_materials_specular, KHR_materials_ior, KHR_texture_transform): adds those in use, drops those no longer
 * used from extensionsUsed and extensionsRequired. Other extensions are left alone. */
void mr_gltf_sync_extensions(mr_gltf *asset);

/* Adds `name` to extensionsRequired (and extensionsUsed) when required is non-zero, removes it from
 * extensionsRequired otherwise (e.g. a spec-gloss material that gained a metallic-roughness fallback). The sync
 * on save still drops a managed extension no material uses. */
mr_status mr_gltf_set_extension_required(mr_gltf *asset, const char *name, int required);

/* extensionsUsed / extensionsRequired membership (0 or 1). */
int mr_gltf_extension_used(const mr_gltf *asset, const char *name);
int mr_gltf_extension_required(const mr_gltf *asset, const char *name);

/* ---- Pruning -------------------------------------------------------------------------------------------
 * mr_gltf_prune_unused removes the textures no material or other object refers to any more, then the images
 * no remaining texture refers to, then the samplers no remaining texture uses, and renumbers every reference
 * to those that stay. Removed images are not written by mr_gltf_save. It is meant for after an edit (e.g.
 * replacing spec-gloss materials by metal-rough ones leaves diffuseTexture and specularGlossinessTexture
 * unreferenced) but removes every unused texture, image and sampler, whether the edit or the file left it so.
 *
 * It is conservative: a texture is referenced by any material textureInfo (core, normal, occlusion,
 * emissive, any extension) and by any textureInfo-like object anywhere in the asset's extensions and extras,
 * including extensions this API does not know and properties outside the schema. In those JSON trees:
 *   - known references are kept and renumbered: an object with an integer "index" under a key ending in
 *     "Texture" or "Textures" (how every Khronos and vendor material extension names its textureInfos), a
 *     "source" inside a texture's extensions (KHR_texture_basisu, EXT_texture_webp, EXT_texture_avif,
 *     MSFT_texture_dds), and a "pointer" string "/textures/N...", "/images/N..." or "/samplers/N..."
 *     (KHR_animation_pointer);
 *   - anything else that may be an index (an "index" under another key; an integer under a key naming an
 *     image, texture, sampler, or "source"; a pointer-like string under another key; e.g.
 *     EXT_lights_image_based's specularImages) is uncertain: nothing at or below the largest such value is
 *     removed, so it never needs renumbering and stays right whatever it means.
 * A removed texture's own references do not keep an image or sampler. An image stored in a buffer view
 * leaves that view (and its bytes) in the buffer: buffer views are not renumbered. extensionsUsed is not
 * changed for extensions only the removed objects used (mr_gltf_sync_extensions handles the four it manages).
 *
 * Texture, image and sampler indices and pointers obtained before (mr_gltf_image's bytes, uri, path) are
 * stale afterwards; read them again. *stats (may be NULL) receives the counts removed and how many objects stay
 * only because of an uncertain reference. A NULL asset is MR_ERR_INVALID_ARG; on failure (also MR_ERR_NOMEM)
 * the asset is unchanged and *stats is zero. */
typedef struct mr_gltf_prune_stats {
    int textures;  /* textures removed */
    int images;    /* images removed */
    int samplers;  /* samplers removed */
    int uncertain; /* textures, images and samplers kept without a known reference to them */
} mr_gltf_prune_stats;

mr_status mr_gltf_prune_unused(mr_gltf *asset, mr_gltf_prune_stats *stats);

/* ---- Geometry ------------------------------------------------------------------------------------------
 * mr_gltf_get_triangles gives the world-space triangles of a scene, grouped by material, in arrays an mr_mesh
 * (src/render/render.h) takes as they are: positions/normals/tangents/uv0 -> mr_mesh positions/normals/
 * tangents/uvs, indices and counts alike, has_transform = 0 (the vertices are already in world space).
 *
 * Every mesh primitive reachable from the scene's root nodes is included once per node instancing its mesh,
 * under the node's world matrix (matrix, or T * R * S, composed from the root down). Modes TRIANGLES (4, the
 * default), TRIANGLE_STRIP (5) and TRIANGLE_FAN (6) become triangle lists (a strip's odd triangles reordered to
 * keep the winding); POINTS and LINES* are skipped and counted. Attributes: POSITION (required, float VEC3)
 * transformed by the matrix; NORMAL by its inverse transpose, renormalised; TANGENT xyz by the matrix,
 * renormalised, w kept as +-1 except under a mirroring transform (negative determinant), where w is negated so
 * that the world bitangent w * cross(n, t) is still the transformed bitangent; TEXCOORD_0/1 as floats or
 * normalized unsigned bytes/shorts. Any component type, byteStride, byteOffset and sparse accessors are read;
 * min/max are ignored. Indices are u8/u16/u32 accessors or, without one, 0, 1, 2, ...
 *
 * Winding: triangles always come out counter-clockwise seen from their front in world space: under a
 * negative-determinant transform (which glTF says turns a primitive's winding clockwise) each triangle's last
 * two indices are swapped (counted in flipped_primitives).
 *
 * A group holds the primitives with one material and the same set of attributes (a material whose primitives
 * differ, some with normals and some without, say, gets one group per set), vertices concatenated. An absent
 * attribute is a NULL array with its has_* flag 0: a renderer generates normals (and tangents from UVs).
 * Integer positions, normals and tangents (KHR_mesh_quantization) are read as their (normalized) values.
 * Strips and fans keep their degenerate triangles. A normal or tangent set with a non-finite or zero vector, or
 * a UV set with a non-finite value, is dropped for that primitive (has_* 0: generated). An instance under a
 * zero-determinant transform (a zero scale hides it) and a primitive without POSITION are skipped and counted.
 *
 * Not applied: morph targets (weights ignored) and skins (the bind pose as stored, under the node's own
 * transform); KHR_texture_transform belongs to the material. Draco (KHR_draco_mesh_compression) is
 * MR_ERR_UNSUPPORTED, a meshopt-compressed buffer view (EXT_meshopt_compression) MR_ERR_FORMAT. Errors are
 * MR_ERR_FORMAT naming the file, mesh and primitive: accessors or buffer views out of range or of the wrong
 * type, indices past the vertex count, non-finite positions, attributes of different counts; a scene or node
 * naming a node or mesh that does not exist, and a node cycle, name the scene or node. A bad scene index is
 * MR_ERR_INVALID_ARG. Every count, byteOffset, byteStride and byteLength is held against the bytes that hold it
 * before anything is allocated for it (a view within its buffer; an accessor's stride * (count - 1) + element size
 * within its view, without overflow; sparse indices and values likewise), and the scene against the limits of
 * mr_gltf_load's "Limits": "accessor 0: count 1073741824 (12-byte elements, byteStride 12) at byteOffset 0 runs
 * past the end of buffer view 0 (byteLength 36)". */
typedef struct mr_gltf_triangle_group {
    int material;       /* materials[] index, -1 = glTF's default material */
    int vertex_count;
    int triangle_count;
    float *positions;   /* [vertex_count * 3], world space, finite */
    float *normals;     /* [vertex_count * 3], world space, unit; NULL when has_normals is 0 */
    float *tangents;    /* [vertex_count * 4], world xyz unit, w = +-1; NULL when has_tangents is 0 */
    float *uv0;         /* [vertex_count * 2], TEXCOORD_0 (glTF's u right, v down); NULL when has_uv0 is 0 */
    float *uv1;         /* [vertex_count * 2], TEXCOORD_1; NULL when has_uv1 is 0 */
    uint32_t *indices;  /* [triangle_count * 3] into this group's vertices, counter-clockwise from the front */
    int has_normals, has_tangents, has_uv0, has_uv1;
    int primitive_count; /* primitive instances merged into the group */
} mr_gltf_triangle_group;

typedef struct mr_gltf_triangles {
    int group_count;
    mr_gltf_triangle_group *groups;
    int scene;              /* the scene read, -1 if the asset has none (then nothing is read) */
    int vertex_count;       /* over all groups */
    int triangle_count;     /* over all groups */
    int primitive_count;    /* triangle primitive instances read */
    int skipped_primitives; /* point and line primitive instances */
    int flipped_primitives; /* instances under a negative-determinant transform (winding reversed) */
    double bbox_min[3], bbox_max[3]; /* world box of every vertex; 0 when there are none */
} mr_gltf_triangles;

/* World-space triangles of scene `scene` (-1: the asset's default scene, or scene 0 if none) into *out
 * (caller-owned: mr_gltf_triangles_free). An asset without scenes gives an empty set. On error *out is NULL. */
mr_status mr_gltf_get_triangles(const mr_gltf *asset, int scene, mr_gltf_triangles **out);

/* NULL-safe. */
void mr_gltf_triangles_free(mr_gltf_triangles *triangles);

/* The world-space bounding box of the scene's triangle vertices (as mr_gltf_get_triangles, whose errors it
 * returns), e.g. to frame a camera. *count receives the vertex count (0: empty scene, box 0); count may be NULL. */
mr_status mr_gltf_get_bounds(const mr_gltf *asset, int scene, double lo[3], double hi[3], int *count);

/* Writes the asset to `path` (.gltf or .glb, see the top of this header): side files under their own URIs, and an
 * existing file in their way replaced (unless it is an input). mr_gltf_save_with(asset, path, &{0, 1, NULL}). */
mr_status mr_gltf_save(mr_gltf *asset, const char *path);

/* How mr_gltf_save_with names the side files of a .gltf output (external buffers and images; a .glb has none) and
 * which existing files it may replace. A zeroed struct (or NULL): names as read, no existing file replaced but
 * the output's own. */
typedef struct mr_gltf_save_options {
    int name_after_output; /* 1: side files named after the output's stem STEM (its file name without the
                              extension), in the folder their URI has: buffer 0 STEM.bin, buffer k STEM_k.bin, an
                              image STEM_NAME (NAME its file name; kept as it is when it starts with "STEM_"
                              already, as new images named PREFIX_mK_... by mr_gltf_convert_file do), so outputs of
                              different names in one folder do not share side files; 0: the URIs as read */
    int replace_files;     /* 1: an existing file where a side file goes is replaced (inputs never are); 0: refused
                              (MR_ERR_INVALID_ARG, nothing written) unless the existing file at `path` is a glTF
                              (or .glb) that refers to it by URI, i.e. it is a side file of the output being
                              replaced (the same save run again) */
    const char *replace_hint; /* how the caller's user allows replacing, named in the refusal ("--replace-files");
                                 NULL: "replace_files" */
} mr_gltf_save_options;

/* mr_gltf_save with options (NULL: a zeroed struct). Besides mr_gltf_save's errors: MR_ERR_INVALID_ARG naming the
 * side file (buffer or image index and path) that would replace an existing file it may not; nothing is written
 * then. The output file itself, named by the caller, is replaced as by mr_gltf_save. */
mr_status mr_gltf_save_with(mr_gltf *asset, const char *path, const mr_gltf_save_options *opts);

#ifdef __cplusplus
}
#endif

#endif /* MR_GLTF_H */
