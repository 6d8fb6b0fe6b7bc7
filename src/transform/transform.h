/*
 * transform.h — per-texel transforms from one BRDF model's parameters to another's, as const descriptors (design
 * principle 1, like src/brdf): the workflow converters of paper section 8 (Eq. 2; Eq. 3 with the mean and the
 * albedo-weighted metallic; the Khronos converter), the learned spec -> metal network, and the lossless route of
 * KHR_materials_specular + KHR_materials_ior. docs/architecture.md shows where they sit in a conversion.
 *
 * Main calls:
 *   const mr_transform_kind *kind = mr_transform_find("gltf-specgloss", "gltf", "weighted");
 *   mr_transform *t;  mr_transform_create(kind, NULL, &t);           // NULL: documented defaults
 *   mr_transform_batch b = {0};
 *   b.n = texels;  b.in[0] = diffuse;  b.in[1] = specular;  b.in[2] = glossiness;    // kind->inputs[] order
 *   b.out[0] = base_color;  b.out[1] = metallic;  b.out[2] = roughness;               // kind->outputs[] order
 *   mr_transform_apply(t, &b);
 *   mr_transform_free(t);
 * Texture sets: mr_transform_convert_maps (images and constants in, one image per output slot and per-texel flags
 * out); mr_transform_convert_texture_set (spec2metal's and metal2spec's pipeline: files read and checked, converted,
 * packed into output layouts with mr_image_pack / mr_image_with_alpha), written all or none with its flag picture
 * (mr_texture_set_write: files named by mr_texture_output_path) and summed up (mr_texture_set_stats); the rules
 * around it (mr_texture_constant_parse, mr_texture_default_format, mr_texture_check_bits);
 * mr_transform_convert_material (convert's: a material's maps and values). Flags: mr_flags_count (by reason) and
 * mr_flag_picture (a colour code as data: mr_workflow_flag_code here, mr_learned_flag_code in learned.h).
 *
 * Planes. A transform reads and writes planes of floats, one per slot: a slot is one parameter of the source
 * (inputs) or target (outputs) model of src/brdf, named as the model names it, with its channel count; a 3-channel
 * plane is RGB interleaved (3n floats). An optional input slot may be NULL: the model's default value is used. An
 * output plane may be NULL when the caller does not want it. Every kind clamps inputs outside a slot's domain
 * [min, max] and reads NaN and infinities as the slot's `nonfinite` value, flagging both. Input and output planes may
 * be the same arrays (in-place conversion is allowed when the channel counts match).
 *
 * Flags: mr_wf_flag bits per texel (workflow.h: CLAMPED_INPUT, NONFINITE_INPUT, OFF_MANIFOLD, METHOD_FAILED).
 *
 * Repeated values. Real 8-bit texture sets hold few distinct texels (~5 % of a 2048^2 set). For a kind flagged
 * MR_TRANSFORM_PER_TEXEL (every output a function of the same texel's inputs and nothing else), apply evaluates
 * each distinct input value of a block once and copies its answer (bit-identical to evaluating every texel).
 *
 * Nothing outside src/transform switches on a transform's name: callers find kinds by (source, target, name) and
 * read what they need from the descriptor. Threads: a created transform is immutable; apply may be called from
 * several threads at once. Ownership: one owner, one free (mr_transform_free, NULL-safe). Nothing is printed.
 */
#ifndef MR_TRANSFORM_H
#define MR_TRANSFORM_H

#include <stddef.h>
#include <stdint.h>

#include "../mr_image.h"
#include "../brdf/brdf.h"
#include "../io/image_io.h"
#include "../mr_status.h"
#include "../workflow/workflow.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Parameters a kind reads or writes at most: 16 holds the layered models (standard-surface has 14, openpbr 13,
 * blender-principled 11), so texture sets convert into them, by --direct or a learned transform. */
#define MR_TRANSFORM_MAX_SLOTS 16

/* Bit flags of mr_transform_slot.flags. */
enum {
    MR_SLOT_OPTIONAL = 1, /* input: may be NULL (the model's default is used) */
    MR_SLOT_CONSTANT = 2  /* output: the same value for every texel (`value`), whatever the inputs */
};

/* One parameter a transform reads or writes. */
typedef struct mr_transform_slot {
    const char *name;  /* the model's parameter name: "diffuse", "glossiness", "base_color" */
    int channels;      /* 1 or 3 */
    double min, max;   /* domain: inputs are clamped into it (flagged) */
    double nonfinite;  /* inputs: the value NaN and infinities are read as (flagged); outputs: unused */
    unsigned flags;    /* MR_SLOT_* */
    double value;      /* MR_SLOT_CONSTANT outputs: the value */
    int copy_of;       /* outputs: the input slot this output repeats unchanged (after sanitising), or -1. A caller
                          converting textures may reuse the input's texture instead (the extension route does) */
} mr_transform_slot;

/* Bit flags of mr_transform_kind.flags. */
enum {
    MR_TRANSFORM_PER_TEXEL = 1,     /* outputs depend on the same texel's inputs only (repeats evaluated once) */
    MR_TRANSFORM_NEEDS_NETWORK = 2, /* create needs mr_transform_options.network (or the installed default) */
    MR_TRANSFORM_TOLERANCES = 4,    /* OFF_MANIFOLD is computed, with mr_transform_batch.stored tolerances */
    MR_TRANSFORM_USES_F0 = 8,       /* mr_transform_options.dielectric_f0 applies */
    MR_TRANSFORM_CONVENTION = 16    /* mr_transform_options.plain_diffuse applies (how a spec-gloss diffuse is read) */
};

typedef struct mr_transform mr_transform;
typedef struct mr_transform_kind mr_transform_kind;
struct mr_mlp;

/* Options of mr_transform_create; a zeroed struct (or NULL) is the documented defaults. */
typedef struct mr_transform_options {
    double dielectric_f0;           /* MR_TRANSFORM_USES_F0 kinds: F0d of Eq. 2 and 3, in (0, 1); 0 = the kind's
                                       default (MR_WF_F0_GLTF; the Khronos kinds accept only it) */
    double eps;                     /* absolute tolerance (workflow.h, mr_wf_options.eps); 0 = MR_WF_DEFAULT_EPS */
    const struct mr_mlp *network;   /* NEEDS_NETWORK kinds: borrowed, must outlive the transform; NULL = the
                                       installed network (mr_wf_network_path) loaded and owned by the transform */
    int threads;                    /* 0 = automatic (a team only for large batches); n >= 1: n. Results do not
                                       depend on it */
    int plain_diffuse;              /* glTF-pair workflow kinds but Khronos: read the spec-gloss diffuse as the
                                       Lambert lobe itself, Eq. 2 as printed (MR_WF_DIFFUSE_PLAIN), not as glTF's
                                       d (1 - max s); default 0 */
} mr_transform_options;

/* One call's planes. in[i] / out[j] follow kind->inputs[] / kind->outputs[]. */
typedef struct mr_transform_batch {
    size_t n;                                          /* texels */
    const float *in[MR_TRANSFORM_MAX_SLOTS];
    float *out[MR_TRANSFORM_MAX_SLOTS];
    mr_wf_quantisation stored[MR_TRANSFORM_MAX_SLOTS]; /* how each input plane was stored (TOLERANCES kinds: the
                                                          off-manifold tolerance, workflow.h); zeroed: exact */
    uint8_t *flags;                                    /* n mr_wf_flag bytes, or NULL */
    int threads;                                       /* 0: the transform's option; n >= 1: n for this call */
} mr_transform_batch;

struct mr_transform_kind {
    const char *name;    /* unique for its (source, target) pair: "weighted", "mlp", "extension", "eq2" */
    const char *summary; /* one line: what it does and where it comes from */
    const char *source;  /* source model (src/brdf registry name): "gltf-specgloss" */
    const char *target;  /* target model: "gltf" */
    int input_count;
    const mr_transform_slot *inputs;
    int output_count;
    const mr_transform_slot *outputs;
    unsigned flags;      /* MR_TRANSFORM_* */
    const void *config;  /* member configuration of a family sharing one file's code */

    /* Build the state (*state may stay NULL); options already defaulted and checked against the kind's flags. */
    mr_status (*create)(const mr_transform_kind *kind, const mr_transform_options *opts, void **state);
    void (*destroy)(void *state); /* NULL-safe; may be NULL when create keeps no state */
    /* Convert b->n texels: every output plane non-NULL (apply supplies scratch for the ones the caller dropped),
     * optional inputs non-NULL (apply fills the default), flags non-NULL. */
    mr_status (*apply)(const mr_transform *t, const mr_transform_batch *b);
};

/* ---- registry (transform.c) ---- */

/* The registered kinds, NULL-terminated. */
const mr_transform_kind *const *mr_transforms(void);

/* The kind converting `source` to `target` called `name` (NULL: the pair's default, its first registered kind), or
 * NULL with a message in mr_last_error() naming the pair's kinds (or the pairs that have some). */
const mr_transform_kind *mr_transform_find(const char *source, const char *target, const char *name);

/* Index of slot `name` in the kind's inputs (outputs), or -1. */
int mr_transform_input_index(const mr_transform_kind *kind, const char *name);
int mr_transform_output_index(const mr_transform_kind *kind, const char *name);

/* A kind that reads every parameter of `source` and writes every parameter of `target` (learned.h, direct.h): its
 * slot tables (one slot per parameter in table order: name, channels, range as domain, the minimum for non-finite
 * inputs, optional) and the kind pointing at them. Embed it first in the block that owns the kind. */
typedef struct mr_transform_model_kind {
    mr_transform_kind kind; /* first: a pointer to the kind is one to the block */
    mr_transform_slot inputs[MR_TRANSFORM_MAX_SLOTS], outputs[MR_TRANSFORM_MAX_SLOTS];
} mr_transform_model_kind;

/* Fill *mk: the slot tables, and the kind with `name`, `summary` (both borrowed), `flags`, `config` and `apply`; its
 * create hands `config` to apply as the state (mr_transform_state), its destroy is NULL. MR_ERR_INVALID_ARG naming
 * the models when one has more parameters than MR_TRANSFORM_MAX_SLOTS. */
mr_status mr_transform_model_kind_init(mr_transform_model_kind *mk, const mr_brdf_model *source,
                                       const mr_brdf_model *target, const char *name, const char *summary,
                                       unsigned flags, const void *config,
                                       mr_status (*apply)(const mr_transform *t, const mr_transform_batch *b));

/* ---- instances ---- */

/* MR_ERR_INVALID_ARG naming the field for options outside their ranges or not applying to the kind (a network for
 * an analytic kind, an F0 other than 0.04 for a Khronos kind); the network's errors (MR_ERR_IO, MR_ERR_FORMAT
 * naming the file); MR_ERR_NOMEM. */
mr_status mr_transform_create(const mr_transform_kind *kind, const mr_transform_options *opts, mr_transform **out);
void mr_transform_free(mr_transform *t);

const mr_transform_kind *mr_transform_kind_of(const mr_transform *t);
/* The options in force (defaults filled in); for a network kind, the network used. */
const mr_transform_options *mr_transform_options_of(const mr_transform *t);
/* A network kind's weights file when the transform loaded the installed one, else "" (a borrowed network). */
const char *mr_transform_network_path(const mr_transform *t);

/* Convert b->n texels (n = 0 is a no-op). MR_ERR_INVALID_ARG for a NULL required input plane. Deterministic for
 * any thread count. */
mr_status mr_transform_apply(const mr_transform *t, const mr_transform_batch *b);

/* ---- texture sets ---- */

/* One input map of a texture-set conversion: an image or a constant. */
typedef struct mr_transform_map {
    const mr_image *image;     /* NULL: `value` everywhere. Images of one conversion share one size */
    int channel;               /* 1-channel slots: the image channel read (0 for a grey image); RGB slots read
                                  channels 0-2 (a grey image's one channel broadcast) */
    int complement;            /* 1: 1 - value (a roughness map for a glossiness slot); NaN stays NaN */
    double value[3];           /* the constant (RGB slots: R, G, B) */
    mr_wf_quantisation stored; /* how the image stored its values (TOLERANCES kinds); zeroed: exact */
} mr_transform_map;

/* Texture-set conversion: in[i] (one per kind->inputs[i]; an optional slot may be a constant of its default) through
 * t, texel by texel, into out[j] (one new image per kind->outputs[j], 1 or 3 channels, the maps' size, 1 x 1 when
 * every map is a constant: the caller frees them) and *flags (width x height mr_wf_flag bytes, malloc'ed; flags may
 * be NULL). MR_ERR_INVALID_ARG naming the slots for maps of different sizes or a channel the image lacks;
 * MR_ERR_NOMEM. On failure nothing is returned. */
mr_status mr_transform_convert_maps(const mr_transform *t, const mr_transform_map *in, mr_image **out,
                                    uint8_t **flags);

/* ---- output images: channels packed from converted maps (pack.c) ------------------------------------------
 * The images a texture-set conversion writes are packed from the converted maps channel by channel: glTF's
 * metallicRoughness (R 0, G roughness, B metallic), KHR_materials_pbrSpecularGlossiness' RGB specular and A
 * glossiness, and the first input map's alpha carried into an RGB output (spec2metal, metal2spec, convert). */

/* Where one channel of a packed image comes from: channel `channel` of `image`, or the fill value (image NULL). */
typedef struct mr_image_channel {
    const mr_image *image;
    int channel;
} mr_image_channel;

/* A new width x height image (*out, the caller frees it) of `channels` channels (1, 3 or 4), channel c copied from
 * sources[c] (values unchanged), `fill` where sources[c].image is NULL. MR_ERR_INVALID_ARG for a source of another
 * size or lacking the channel; MR_ERR_NOMEM. */
mr_status mr_image_pack(int width, int height, int channels, const mr_image_channel *sources, float fill,
                        mr_image **out);

/* `rgb` with the alpha of `alpha_source` appended, when rgb has 3 channels and alpha_source (may be NULL) has 4:
 * a new image in *out (the caller frees it); otherwise *out is rgb itself (not a copy: free it only once). Errors as
 * mr_image_pack's. */
mr_status mr_image_with_alpha(mr_image *rgb, const mr_image *alpha_source, mr_image **out);

/* ---- texture-set conversions: files in, packed images out (texture_set.c) ----------------------------------
 * The pipeline of spec2metal and metal2spec as one call: read and check the maps (mr_img_read_texture_set), feed
 * the transform's input slots from them (a map's colour channels or one channel, complemented when asked),
 * convert (mr_transform_convert_maps), and pack the converted slots into the output images a layout describes
 * (mr_image_pack; glTF's channel packing), the first map's alpha carried where a layout asks for it. The caller
 * writes the images (mr_img_write_set) and the flag picture (mr_flag_picture) and reports the flags
 * (mr_flags_count). */

/* Where a transform input slot's values come from: map `map` of the set, its colour channels (channel -1) or one
 * channel; complement: 1 - value (a roughness map for a glossiness slot; NaN stays NaN). */
typedef struct mr_texture_source {
    int map, channel, complement;
} mr_texture_source;

/* Channel sources of a layout besides the transform's output slots. */
enum {
    MR_LAYOUT_ZERO = -1, /* 0 */
    MR_LAYOUT_ALPHA = -2 /* the first map's alpha; a last channel that exists only when that map has one */
};

/* One output image: its name (for the caller's file names), how its file is encoded, and per channel the output
 * slot (and that slot's channel) written there, or MR_LAYOUT_ZERO / MR_LAYOUT_ALPHA. */
typedef struct mr_texture_layout {
    const char *name;
    mr_img_encoding encoding;
    int channels;
    int slot[4], channel[4];
} mr_texture_layout;

#define MR_TEXTURE_MAX_OUTPUTS 4

/* What to convert. maps[k] as mr_img_read_texture_set takes them (its images are the call's: read and freed by
 * it), constants[k] the value of a map without a path (R, G, B; a one-value map's in all three). */
typedef struct mr_texture_set {
    mr_img_param_map *maps;
    const double (*constants)[3];
    int map_count;
    const mr_texture_source *inputs;    /* one per kind->inputs[] */
    int exact;                          /* 0: each input known to half a code of its file (workflow.h,
                                           "Tolerances"); 1: every input exact (the transform's eps alone) */
    const mr_texture_layout *layouts;   /* the output images; layout_count 0: none (only the converted slots) */
    int layout_count;                   /* at most MR_TEXTURE_MAX_OUTPUTS */
    int threads;                        /* file decoding: 0 = automatic (mr_auto_threads), n >= 1: at most n. The
                                           conversion takes the transform's own option */
} mr_texture_set;

/* What came out; every pointer owned, released by mr_texture_result_free. */
typedef struct mr_texture_result {
    int width, height;                              /* the maps' size; 1 x 1 when every map is a constant */
    mr_image *converted[MR_TRANSFORM_MAX_SLOTS];    /* one per kind->outputs[] (as mr_transform_convert_maps) */
    mr_image *outputs[MR_TEXTURE_MAX_OUTPUTS];      /* one per layout */
    uint8_t *flags;                                 /* width x height mr_wf_flag bytes */
    double seconds[3];                              /* read, convert, pack */
    int failed_map;                                 /* on failure: the map refused (else -1), */
    int failed_reading;                             /* and whether its read failed (1) or a check refused it (0) */
} mr_texture_result;

/* Convert `set` through t into *out (zeroed first). On failure nothing is returned but out->failed_map and
 * out->failed_reading, and every image is freed. Errors: those of mr_img_read_texture_set (the map named by its
 * label), mr_transform_convert_maps and mr_image_pack; MR_ERR_INVALID_ARG for a source or layout naming a map,
 * slot or channel that is not there. */
mr_status mr_transform_convert_texture_set(const mr_transform *t, const mr_texture_set *set, mr_texture_result *out);
/* Free what a result holds and zero it (NULL-safe). */
void mr_texture_result_free(mr_texture_result *r);

/* ---- a texture set's maps as text, its files and its figures (texture_set.c) --------------------------------
 * What spec2metal and metal2spec decide from their options, and what they do with a result: a map given as a
 * constant, the output format, the output files' names, the files written all or none with the flag picture, and
 * each converted quantity's minimum, mean and maximum (the JSON summary's). */

/* 1 if `text` is written as a constant: not empty and made only of number characters ("0123456789.,+-eE"); any
 * other text names a file (a file named like a number is written "./0.5"). */
int mr_texture_constant_like(const char *text);

/* Parse a map's constant: one number (out[0..2] all of it: grey) or, when `colour`, R,G,B; every number finite and
 * in [0, 1]. MR_ERR_INVALID_ARG "V is outside [0, 1]" (V as %g) for the first number outside it, met left to
 * right; MR_ERR_FORMAT for text that is not such a constant (three numbers for a map that is not a colour, a
 * malformed or extra number). out is written only on success. */
mr_status mr_texture_constant_parse(const char *text, int colour, double out[3]);

/* "png", "exr" or "tif" for a format name or a file extension (case-insensitive; "tiff" too), NULL for others. */
const char *mr_texture_format_from_name(const char *text);

/* The output format a texture set takes by default: that of the first of paths[0..count) not NULL (a NULL path is a
 * constant map) when its extension is png, exr or tif (or tiff); "png" otherwise and when every path is NULL. */
const char *mr_texture_default_format(const char *const *paths, int count);

/* MR_OK when files of `format` ("png", "exr", "tif") take `bits` per sample: 0 (the format's default), 8 or 16 for
 * png and tif, 16 (half) or 32 (float) for exr; else MR_ERR_INVALID_ARG "FORMAT files take 8 or 16" (or "16 (half)
 * or 32 (float)"). */
mr_status mr_texture_check_bits(const char *format, int bits);

/* The file of `layout` under `prefix`: PREFIX_<layout name>.<format>, by mr_img_prefixed_name's rule (io/image_io.h;
 * "out/" + basecolor -> "out/basecolor.png"), into out (size bytes). MR_ERR_INVALID_ARG when it does not fit. */
mr_status mr_texture_output_path(const char *prefix, const mr_texture_layout *layout, const char *format, char *out,
                                 size_t size);

/* Where and how mr_texture_set_write writes a result. Zeroed: the defaults noted. */
struct mr_flag_code;
typedef struct mr_texture_write_options {
    const char *prefix;       /* required: the outputs are mr_texture_output_path(prefix, layouts[k], format) */
    const char *prefix_label; /* how messages name the outputs ("-o out"); NULL: by their paths alone */
    const char *format;       /* "png", "exr" or "tif"; NULL: "png" */
    int bits;                 /* per sample, as mr_texture_check_bits takes; 0: the format's default */
    const char *flags_path;   /* the flag picture's file; NULL: none */
    const char *flags_label;  /* how messages name it ("--flags"); NULL: by its path */
    const struct mr_flag_code *flag_code; /* the picture's colours (below); NULL: mr_workflow_flag_code */
    int threads;              /* files encoded side by side (mr_img_set_options.threads): 0 automatic */
} mr_texture_write_options;

/* Write result->outputs[0..count) (packed by layouts[0..count), each file encoded as its layout's encoding says)
 * and, when opts->flags_path is set, the picture of result->flags (mr_flag_picture, written linear: the code's
 * exact colours), all or none (mr_img_write_set). Errors: MR_ERR_INVALID_ARG for a NULL argument, an output missing
 * from the result, bits the format does not take or a name that does not fit; mr_flag_picture's and
 * mr_img_write_set's (naming the file). */
mr_status mr_texture_set_write(const mr_texture_result *result, const mr_texture_layout *layouts, int count,
                               const mr_texture_write_options *opts);

/* One converted quantity's figures per channel, as converted (before the files' quantisation). */
typedef struct mr_texture_stats {
    int channels;                /* 1 or 3 (the slot's) */
    double min[3], mean[3], max[3];
} mr_texture_stats;

/* The figures of result->converted[slot] over its width x height texels (the mean is the sum in texel order, in
 * double, over the texel count). MR_ERR_INVALID_ARG for a NULL argument or a slot the result does not hold. */
mr_status mr_texture_set_stats(const mr_texture_result *result, int slot, mr_texture_stats *out);

/* The pipeline of convert as one call: a material of the kind's source model (struct mr_material, render.h: its
 * values and the maps bound to its parameters) converted texel by texel through t; each input slot reads the
 * parameter of its name, its map (the one bound) or its value. out[j] is one new image per kind->outputs[j] (the
 * caller frees them), an RGB one carrying the alpha of the first 4-channel map in parameter order; *flags as
 * mr_transform_convert_maps. MR_ERR_INVALID_ARG for a material of another model; the errors of
 * mr_transform_convert_maps and mr_image_with_alpha. On failure nothing is returned. */
struct mr_material;
mr_status mr_transform_convert_material(const mr_transform *t, const struct mr_material *material, mr_image **out,
                                        uint8_t **flags);

/* ---- flags: counted by reason, drawn as a picture (flags.c) ------------------------------------------------
 * Every conversion flags its texels with mr_wf_flag bits (workflow.h: CLAMPED_INPUT, NONFINITE_INPUT, OFF_MANIFOLD,
 * METHOD_FAILED; learned.h: EXTRAPOLATED, CLAMPED_OUTPUT, UNCHECKED; direct.h: UNCONVERGED). A command reports them
 * counted by reason (mr_flags_count) and draws them as a picture (mr_flag_picture) whose colour code is data, an
 * mr_flag_code table kept beside the transforms that set its flags:
 *   mr_workflow_flag_code (here; spec2metal, metal2spec --flags): the colour of a texel's most severe flag, first
 *     match wins: red method failed, magenta non-finite input, blue (0, 0.5, 1) clamped input, orange (1, 0.5, 0)
 *     off-manifold;
 *   mr_learned_flag_code (learned.h; convert's PREFIX_flags.png): one channel per kind of reason, each set when the
 *     texel has one: red extrapolated, unconverged or by a transform that failed its check, green clamped output,
 *     blue clamped or non-finite input.
 * A clean texel is black. The picture is written linear (MR_IMG_DATA), so its files hold the table's values. */

/* One colour of a code: a texel having any bit of `flags` takes (or adds) `rgb`. */
typedef struct mr_flag_colour {
    unsigned flags;
    float rgb[3];
} mr_flag_colour;

typedef enum mr_flag_paint {
    MR_FLAG_PAINT_FIRST = 0, /* the first colour (in table order: most severe first) whose flags the texel has */
    MR_FLAG_PAINT_EACH       /* every colour whose flags the texel has, channel by channel the largest value */
} mr_flag_paint;

typedef struct mr_flag_code {
    mr_flag_paint paint;
    int count;
    const mr_flag_colour *colours;
} mr_flag_code;

extern const mr_flag_code mr_workflow_flag_code;

/* counts[r] = how many of the n texels have any bit of reasons[r] (r < reason_count; 0xFF counts every flagged
 * texel). A NULL flags counts nothing (every count 0). */
void mr_flags_count(const uint8_t *flags, size_t n, const unsigned *reasons, int reason_count, size_t *counts);

/* The flag picture of width x height flags in `code`'s colours: a new RGB image (*out, the caller frees it; black
 * where a texel is clean). MR_ERR_INVALID_ARG for a NULL argument or a bad size, MR_ERR_NOMEM. */
mr_status mr_flag_picture(const uint8_t *flags, int width, int height, const mr_flag_code *code, mr_image **out);

/* One texel through doubles (constants, scripts): in[] / out[] packed in slot order (channels consecutive). */
mr_status mr_transform_apply_values(const mr_transform *t, const double *in, double *out, unsigned *flags);

/* For the kinds' own files (transform_internal.h would hold only this): the state create made. */
void *mr_transform_state(const mr_transform *t);

#ifdef __cplusplus
}
#endif

#endif /* MR_TRANSFORM_H */
