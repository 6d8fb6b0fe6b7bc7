/*
 * image_io.h — reading and writing images (EXR, Radiance HDR, PNG, JPEG, TIFF).
 *
 * Main calls: mr_img_read(path, &opts, &image) ... mr_img_write(path, image, &opts). Free with mr_image_free.
 * mr_img_read_memory decodes an encoded image already in memory (e.g. embedded in a glTF asset) the same way.
 * Maps named in text ("orm.png:g:linear"): mr_map_ref_split, mr_map_ref_check, mr_map_ref_read.
 * Sets of files: mr_img_read_param_maps / mr_img_read_texture_set read the maps of a texture set side by side (the
 * latter checks them: grey data maps, packed channels, one size); mr_img_write_set writes several images all or
 * none (each to a temporary beside it, all renamed into place once every one is written).
 *
 * Colour convention (the only place it is applied): images in memory are linear (mr_image.h).
 *   - EXR and HDR hold linear floats and are read and written as they are.
 *   - 8/16-bit files (PNG, JPEG, TIFF) holding colour (MR_IMG_COLOR, the default) are sRGB-decoded on read and
 *     sRGB-encoded (after clamping to [0,1], NaN -> 0) on write, then rounded to the nearest code. Data maps
 *     (MR_IMG_DATA: roughness, metallic, normals) are read and written as plain [0,1] values. Alpha is always
 *     linear and never premultiplied (PNG/TIFF store unassociated alpha; EXR alpha is kept as stored).
 *     On read, the rule follows the stored sample type: integer samples are display-encoded, floating-point
 *     samples (EXR, HDR, float TIFF) are linear.
 *   - A map of a BRDF parameter is read by the one rule of mr_img_read_param_map (below): sRGB for colour
 *     parameters (MR_PARAM_SRGB_MAP), linear for the rest, unless the map overrides it.
 * Backends: PNG is read and written without OpenImageIO (png_deflate.c: libdeflate inflates and deflates its
 * image data; png_io.c: libpng decodes what png_deflate.c leaves, e.g. Adam7); anything else goes through
 * OpenImageIO (C++ shim, image_io_oiio.cpp, built as the module libmatremap-oiio.so and loaded on first use, see
 * oiio_module.c; MR_OIIO_MODULE overrides where it is looked for, and a missing module is MR_ERR_EXTERNAL), which
 * decodes every EXR compression (OpenEXR Core 3.1.5 cannot decode DWAA/DWAB, see ../shared/docs/toolchain.md).
 * EXR writing uses the OpenEXR Core C API directly (exr_write.c: scanline, ZIP, FLOAT or HALF channels R,G,B(,A)
 * or Y). Other formats are written by OpenImageIO (JPEG and HDR encoded in memory first: io_internal.h says why).
 * Format limits: JPEG and Radiance HDR cannot store alpha (4-channel images are MR_ERR_UNSUPPORTED, not
 * silently flattened); JPEG sides are at most 65500 pixels; HDR stores RGB (a 1-channel image is written as
 * grey RGB) and has no sign, so negative and NaN values are written as 0.
 * Robustness: only a regular file is read (a folder, a FIFO, a device such as /dev/zero is MR_ERR_IO naming it,
 * before a byte is read). Reads reject images larger than opts.max_dimension on either side before decoding pixels,
 * check a PNG's chunk structure (truncation, CRC) and hold the size its IHDR claims against what its IDAT chunks
 * can inflate to (at most 1032 bytes per compressed byte) before any decoder allocates for it, and fail on any
 * error a decoder reports, even one it treats as a warning (a truncated JPEG). Through OpenImageIO, the spec is
 * checked before pixels (size, at most 1024 channels, a data window within +-2^30, tiles no larger than
 * max_dimension; deep, volume and multi-part EXR images refused) and the pixels are read a band of rows at a time,
 * so that a header claiming more rows than the file holds fails at its first missing band instead of costing the
 * whole image's memory and time. Only the first subimage's data window is read (and only the first mipmap level).
 * What libpng, libjpeg, OpenEXR and OpenImageIO say is folded into the one message; none of it is printed.
 * Writes go to a temporary file "<path>.tmp.<pid>.<n>" beside the target and are renamed over it only when
 * every write, flush and fsync succeeded; on failure no partial output is left behind and an existing target
 * is untouched. New files get mode 0666 minus the umask, like any other output.
 * Nothing is printed: every failure is a status plus a message naming the file (mr_last_error()).
 * Thread safety: calls on different images may run concurrently.
 */
#ifndef MR_IMAGE_IO_H
#define MR_IMAGE_IO_H

#include "../brdf/brdf.h"
#include "../mr_image.h"
#include "../mr_status.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum mr_img_encoding {
    MR_IMG_COLOR = 0, /* sRGB-encoded in 8/16-bit files (the default) */
    MR_IMG_DATA       /* linear values in every format */
} mr_img_encoding;

typedef struct mr_img_read_options {
    mr_img_encoding encoding; /* how to interpret 8/16-bit files; 0 = MR_IMG_COLOR */
    int channels;             /* 0 = as stored (1 stays 1, 2 -> 4 as grey+alpha, >= 3 -> 3 or 4); 1, 3 or 4 to
                                 convert (grey broadcast to RGB, RGB -> luminance is an error, alpha dropped or
                                 added as 1) */
    int max_dimension;        /* largest accepted width or height; 0 = 16384 */
} mr_img_read_options;

typedef struct mr_img_write_options {
    mr_img_encoding encoding; /* 0 = MR_IMG_COLOR: sRGB-encode for 8/16-bit formats */
    int bits;                 /* 8/16 for PNG and TIFF, 8 for JPEG, 16 (half) or 32 for EXR; 0 = the format's
                                 default: 8 for PNG/JPEG/TIFF, 32 for EXR, HDR is always RGBE */
    int jpeg_quality;         /* 1..100; 0 = 95 */
} mr_img_write_options;

/* Read `path` into a new image (*out, owned by the caller; untouched on failure). opts may be NULL for the
 * defaults. Errors name the file: MR_ERR_IO (missing, a directory or another non-regular file, unreadable),
 * MR_ERR_FORMAT (not an image, truncated or corrupt, a header claiming more than the file holds, larger than
 * max_dimension, RGB data when 1 channel was requested, volume or deep images), MR_ERR_UNSUPPORTED (a multi-part
 * EXR), MR_ERR_INVALID_ARG (bad options), MR_ERR_NOMEM. */
mr_status mr_img_read(const char *path, const mr_img_read_options *opts, mr_image **out);

/* How a file stored the samples mr_img_read_stored decoded: what limits the precision of its values. */
typedef struct mr_img_stored {
    int bits;                 /* 8 or 16 for unsigned-integer samples (PNG, JPEG, TIFF: value = code / (2^bits -
                                 1)); 0 for floating-point samples (EXR, HDR, float TIFF) and other integer widths */
    mr_img_encoding encoding; /* how the colour channels were decoded: MR_IMG_COLOR when they were sRGB-decoded
                                 (integer samples read as colour), MR_IMG_DATA when taken as they are (alpha is
                                 always linear) */
} mr_img_stored;

/* mr_img_read, and *stored (may be NULL; written on success only) says how the file stored its samples, for
 * mr_img_half_step. */
mr_status mr_img_read_stored(const char *path, const mr_img_read_options *opts, mr_image **out,
                             mr_img_stored *stored);

/* mr_img_read_stored for an encoded image in memory: `size` bytes at `bytes` (e.g. an image embedded in a glTF
 * asset, as a data URI or in a buffer view), with the same options, conventions, checks and results as reading
 * the same bytes from a file, bit for bit; nothing touches the disk. The format is recognised by the first bytes:
 * PNG (as for a file), JPEG, EXR, Radiance HDR, TIFF, WebP, GIF and BMP (OpenImageIO). Messages call the
 * data `name` (e.g. "glTF 'x.gltf': image 3"; NULL or "" = "image in memory"). *out is owned by the caller and
 * untouched on failure; *stored (may be NULL) as for mr_img_read_stored. Errors: MR_ERR_FORMAT (no bytes, another
 * format, truncated or corrupt, larger than max_dimension, RGB data when 1 channel was requested),
 * MR_ERR_INVALID_ARG (out NULL, bytes NULL with a size, bad options), MR_ERR_NOMEM, MR_ERR_EXTERNAL (the
 * OpenImageIO module cannot be loaded). The bytes are only read, and may be freed once the call returns. */
mr_status mr_img_read_memory(const void *bytes, size_t size, const char *name, const mr_img_read_options *opts,
                             mr_image **out, mr_img_stored *stored);

/* How far from `value` (a decoded value: linear for MR_IMG_COLOR, as stored for MR_IMG_DATA) the value an
 * integer file of `bits` bits stored as it may have been: half a code value, in decoded units. bits 8 or 16,
 * max = 2^bits - 1. MR_IMG_COLOR (sRGB): q is the code whose decode interval [lin((q - 1/2) / max), lin((q +
 * 1/2) / max)) holds the value (the code the writer stores), and the answer is the larger distance from lin(q /
 * max) to either end of that interval, its ends clamped to [0, 1] (lin(1/510) = 1.5e-4 at code 0, 0.0045 at 255
 * for 8 bits; in between, half the interval within 1 %: about 0.00068 at 56, where a dielectric's 0.04 is stored).
 * MR_IMG_DATA: 0.5 / max. 0 for other bits (floating-point storage, exact to its own rounding) and for a
 * non-finite value. JPEG's compression error is not part of it. */
double mr_img_half_step(double value, int bits, mr_img_encoding encoding);

/* Write `image` to `path`; the format follows the extension (.exr .hdr .png .jpg/.jpeg .tif/.tiff, case-
 * insensitive; anything else is MR_ERR_INVALID_ARG). opts may be NULL. Atomic: see the header comment.
 * Errors name the file: MR_ERR_INVALID_ARG (extension, bits, quality, encoding, invalid image; checked before
 * anything touches the disk), MR_ERR_UNSUPPORTED (a format limit above), MR_ERR_IO (the directory is missing
 * or unwritable, a write or the rename failed: the system's reason is given), MR_ERR_EXTERNAL (an encoder
 * failed), MR_ERR_NOMEM. */
mr_status mr_img_write(const char *path, const mr_image *image, const mr_img_write_options *opts);

/* ---- output sets: several images written all or none (image_set.c) ----------------------------------------
 * A command that writes a set of images which belong together (the maps of one converted texture set and its flag
 * picture) writes them with mr_img_write_set: each image goes to a hidden temporary file beside its target,
 * "DIR/.matremap-<pid>-NAME" (the extension kept, so the format is the target's), and only when every one is
 * written are they renamed into place, in order. A failure before the renames removes the temporaries and leaves
 * every target as it was (an earlier run's set stays whole); a target that is a folder, or named twice, is refused
 * before anything is written, so the renames (each within its folder) fail only on an I/O error, and then the
 * targets already renamed are removed too: none of the set rather than a mixed one. The folders must exist. */

typedef struct mr_img_set_item {
    const char *path;             /* the target */
    const char *label;            /* how the user named it, for messages ("-o out/ggx_"); NULL: none */
    const mr_image *image;        /* borrowed */
    mr_img_write_options options; /* as for mr_img_write */
} mr_img_set_item;

typedef struct mr_img_set_options {
    int threads; /* images encoded side by side: 0 = automatic (mr_auto_threads: a team, no larger than the set,
                    for two images or more), n >= 1: at most n. The files do not depend on it */
} mr_img_set_options;

/* Write items[0..count) all or none, as above; opts may be NULL (zeroed: the defaults). On failure *failed (may be
 * NULL) is the index of the item that failed (the first in order, when several did), else -1. Errors, each naming the
 * target: MR_ERR_INVALID_ARG "output 'P' (LABEL) is a folder" or "named twice" (nothing written); a write's own
 * status as "writing 'P': <its message>"; MR_ERR_IO "cannot rename 'TMP' to 'P': <reason>[ (the outputs renamed
 * before it removed)]"; MR_ERR_NOMEM. count 0 is a no-op. */
mr_status mr_img_write_set(const mr_img_set_item *items, int count, const mr_img_set_options *opts, int *failed);

/* The one rule for the names of a set's files made from a prefix (-o PREFIX of convert, spec2metal, metal2spec;
 * remap --images): a PREFIX ending in '/', '_', '-' or '.' (or empty) is followed by the name directly, any other
 * gets '_' in between:
 *   "out/ggx_" + "alpha.exr" -> "out/ggx_alpha.exr"    "pfx/ggx" + "alpha.exr" -> "pfx/ggx_alpha.exr"
 *   "out/"     + "alpha.exr" -> "out/alpha.exr"        "avocado" + "basecolor.png" -> "avocado_basecolor.png"
 * Writes the name into out (size bytes). MR_ERR_INVALID_ARG naming the prefix when it does not fit (out then holds
 * a truncated name, never used). */
mr_status mr_img_prefixed_name(char *out, size_t size, const char *prefix, const char *name);

/* ---- maps of BRDF parameters: the one rule (param_map.c) ----------------------------------------------------
 * A texture map of a BRDF parameter holds the parameter's own values. 8/16-bit files hold a colour parameter
 * (flagged MR_PARAM_SRGB_MAP in its descriptor, brdf.h: diffuse, specular, f0, base colour, ...) sRGB-encoded and
 * every other parameter (roughness, alpha, metallic, ior, scalars, switches) linear, whatever its range; float
 * files (EXR, HDR, float TIFF) are linear. A map may override the rule (the command line's FILE:linear and
 * FILE:srgb): MR_MAP_LINEAR takes the stored values of an 8/16-bit file as they are, MR_MAP_SRGB decodes them;
 * sRGB decoding applies to integer files only, so MR_MAP_SRGB on a float file is an error. Alpha is always
 * linear. Every command that reads parameter maps (render, report, convert, spec2metal, metal2spec) reads them
 * through mr_img_read_param_map; glTF's textures follow the glTF specification, which agrees with the flags of
 * the gltf and gltf-specgloss models (tests/test_brdf.c checks it). */
typedef enum mr_map_encoding {
    MR_MAP_AS_PARAMETER = 0, /* the rule: sRGB for a parameter flagged MR_PARAM_SRGB_MAP, else linear */
    MR_MAP_SRGB,             /* override: sRGB-decode 8/16-bit files (":srgb") */
    MR_MAP_LINEAR,           /* override: linear in every format (":linear") */
    MR_MAP_ENCODING_COUNT
} mr_map_encoding;

/* How 8/16-bit maps of `param` are decoded: MR_IMG_COLOR (sRGB) or MR_IMG_DATA (linear). `how` is the map's
 * override, MR_MAP_AS_PARAMETER for none: then MR_IMG_COLOR exactly when param->flags has MR_PARAM_SRGB_MAP.
 * A NULL param (a map that feeds no parameter) reads as MR_IMG_DATA unless overridden. */
mr_img_encoding mr_brdf_param_map_encoding(const mr_brdf_param *param, mr_map_encoding how);

/* The name of an encoding for displays and command lines: "sRGB" for MR_IMG_COLOR, "linear" for MR_IMG_DATA. */
const char *mr_img_encoding_name(mr_img_encoding encoding);

/* Read a map of `param` (may be NULL, as above) from `path` by the rule: mr_img_read_stored with the encoding
 * mr_brdf_param_map_encoding(param, how); opts (may be NULL) gives channels and max_dimension, its encoding is
 * ignored. *out and *stored (may be NULL) as for mr_img_read_stored. Errors: those of mr_img_read_stored, and
 * MR_ERR_INVALID_ARG naming the file when `how` is MR_MAP_SRGB and the file stores floating-point samples (they are
 * linear; sRGB decoding applies to 8/16-bit files), or when `how` is out of range. */
mr_status mr_img_read_param_map(const char *path, const mr_brdf_param *param, mr_map_encoding how,
                                const mr_img_read_options *opts, mr_image **out, mr_img_stored *stored);

/* ---- maps named in text: FILE[:r|g|b|a][:linear|srgb] (param_map.c) --------------------------------------------
 * How the command line (and any caller taking maps as text) names a map: the file, then optional selectors at its
 * end, in this order: a channel (:r, :g, :b or :a, where the caller picks channels: a one-channel parameter), then an
 * encoding (:linear or :srgb) overriding the parameter's own rule above (:srgb on a float file is an error). E.g.
 * "orm.png:g:linear". Selectors are always taken from the end: a file whose own name ends in one is given with an
 * explicit encoding after it ("odd:linear:srgb" reads the file "odd:linear" as sRGB). */

/* Split `text` into its file and selectors: *path_length is the length of FILE at the start of text, *channel the
 * channel (0-3 for r, g, b, a; -1 when none is given or `channels` is 0: the caller picks none, and ":g" stays part
 * of the file name), *encoding the override (MR_MAP_AS_PARAMETER when none is given). Never fails. */
void mr_map_ref_split(const char *text, int channels, size_t *path_length, int *channel, mr_map_encoding *encoding);

/* Check the text as mr_map_ref_split splits it: MR_OK, or MR_ERR_INVALID_ARG (a fault of the text itself, which a
 * command line reports as a usage error) naming `label` (how the user gave the map: "specular=@s.png:linear",
 * "--specular s.png"; NULL: the text): "'LABEL': no file name (expected FILE[:r|g|b|a][:linear|srgb])" (or
 * "FILE[:linear|srgb]" when channels is 0), "'LABEL': the channel comes before the encoding: x.png:g:linear" (for
 * "x.png:linear:g", unless a file "x.png:linear" exists). MR_ERR_NOMEM. */
mr_status mr_map_ref_check(const char *label, const char *text, int channels);

/* Read the map named by `text` (checked by mr_map_ref_check first; the channel selector is the caller's to apply) for
 * `param` (may be NULL: linear unless overridden) with mr_img_read_param_map (opts, *out and *stored as there).
 * *usage (may be NULL) is 1 when the request is at fault rather than the file: the text is malformed, or :srgb was
 * asked of a float file ("'LABEL': <mr_img_read_param_map's message>"); else 0. Errors: mr_map_ref_check's, those
 * of mr_img_read_param_map, MR_ERR_NOMEM ("out of memory for 'LABEL'"). */
mr_status mr_map_ref_read(const char *label, const char *text, int channels, const mr_brdf_param *param,
                          const mr_img_read_options *opts, mr_image **out, mr_img_stored *stored, int *usage);

/* One map of a texture set for mr_img_read_param_maps: what to read (path, param, how as for mr_img_read_param_map)
 * and, once read, the image and how its file stored it. */
typedef struct mr_img_param_map {
    const char *path;           /* NULL: nothing to read (a constant: image stays NULL) */
    const mr_brdf_param *param; /* may be NULL (linear unless overridden) */
    mr_map_encoding how;        /* the map's override, MR_MAP_AS_PARAMETER for none */
    mr_image *image;            /* out: the map, owned by the caller (NULL until read) */
    mr_img_stored stored;       /* out: how the file stored its samples */
    /* What mr_img_read_texture_set checks (zeroed: nothing): */
    const char *label;          /* names the map in messages, as the user gave it ("--glossiness 'g.png'"); NULL:
                                   "map 'PATH'" */
    int min_channels;           /* the channels the file must have (a packed map: 3 or 4); 0: any */
    const char *layout;         /* with min_channels: what those channels hold ("RGB: G roughness, B metallic") */
    int grey;                   /* 1: a one-value map: a file of 3 or more channels must be grey (R = G = B) */
    const char *hint;           /* appended to the message refusing a colour file for a grey map; may be NULL */
} mr_img_param_map;

/* Read every map of maps[0..count) with a path by mr_img_read_param_map (opts as there, may be NULL), the files
 * decoded side by side: `threads` 0 = automatic (mr_auto_threads: a team, no larger than the maps, for two maps or
 * more), n >= 1: at most n; the images do not depend on it. Each map's image is set once it is read, also when
 * another map failed: the caller frees every maps[k].image (NULL-safe) in either case. On failure the first map in
 * order that failed is the one reported (its status, its message in mr_last_error()) and *failed (may be NULL) is its
 * index, else -1. Errors: those of mr_img_read_param_map; MR_ERR_NOMEM. */
mr_status mr_img_read_param_maps(mr_img_param_map *maps, int count, const mr_img_read_options *opts, int threads,
                                 int *failed);

/* The maps of one texture set: mr_img_read_param_maps, then, map by map in order (the first problem is the one
 * reported), its read's failure or the checks its fields ask for, and one size for every file: *width x *height
 * is it (1 x 1 when every map is a constant; both may be NULL). Ownership as for mr_img_read_param_maps (the caller
 * frees every maps[k].image in either case). *failed (may be NULL) is the index of the map refused, else -1; its
 * image is NULL when its read failed, set when a check refused it. Errors: those of the reads; MR_ERR_INVALID_ARG,
 * naming the map by its label: "LABEL has one channel; expected LAYOUT" (or "no alpha channel"), "LABEL is a colour
 * image (pixel X, Y is R, G, B); expected one channel, or grey<HINT>", "LABEL is WxH but LABEL0 is WxH: maps must
 * have the same size (constants broadcast)". */
mr_status mr_img_read_texture_set(mr_img_param_map *maps, int count, const mr_img_read_options *opts, int threads,
                                  int *width, int *height, int *failed);

/* sRGB transfer functions (IEC 61966-2-1), exact piecewise form evaluated in double. Values outside [0,1]
 * are mirrored through 0 (odd extension, no clamping); NaN stays NaN. */
float mr_srgb_to_linear(float encoded);
float mr_linear_to_srgb(float linear);
/* The same in double, not rounded to float: mr_img_half_step's differences of decodes, and the direct remap, which
 * quantises colours in sRGB-encoded units (remap/direct.h), need it. */
double mr_srgb_decode_double(double encoded);
double mr_srgb_encode_double(double linear);

#ifdef __cplusplus
}
#endif

#endif /* MR_IMAGE_IO_H */
