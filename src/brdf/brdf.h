/*
 * brdf.h — BRDF models as const descriptors (design principle 1: models are data).
 *
 * Each model lives in one file of src/brdf/ and is described by one `const mr_brdf_model`; registry.c lists
 * them. Renderer, optimiser, CLI and exporters reach models only through these descriptors: nothing outside
 * src/brdf switches on a model's name. A family of closely related models (Ward's three normalisations, the
 * Mitsuba microfacet distributions x Fresnel modes) shares one file and its code, with one descriptor per
 * member and the member's configuration in `config`.
 *
 * Contracts common to every model:
 *   - Frame: directions are unit vectors in the local shading frame, normal n = (0,0,1), cos(theta) = z.
 *   - `eval` returns f_r itself, WITHOUT the cosine foreshortening term (unlike Mitsuba's eval(), which
 *     includes cos(theta_o)). Radiance from a point light is L = f_r * I * cos(theta_light) / d^2.
 *   - f_r is split into a diffuse and a specular part; full = diffuse + specular, always.
 *   - Below the horizon (wi.z <= 0 or wo.z <= 0) both parts are 0, unless a model documents a renderer's
 *     clamping convention (blender-ward clamps cosines as Blender Internal does, but still returns 0 there).
 *   - Colour: linear RGB; reflectance-like parameters are in [0,1] unless the table says otherwise.
 *   - Robustness: `prepare` clamps every value into [min, max] (NaN goes to min) and roughness to a documented
 *     floor, so eval never returns NaN or Inf for any input vector, at any pair of directions with z > 0.
 *   - Thread safety: descriptors are immutable; prepared state is plain data owned by the caller, so any
 *     number of threads may evaluate one prepared state at once.
 *
 * Parameter vectors: a model's parameters are packed in table order into one `double values[]`, a parameter
 * with 3 channels taking 3 consecutive slots (R,G,B). mr_brdf_value_count() gives the length and
 * mr_brdf_param_offset() the slot of a parameter's first channel.
 */
#ifndef MR_BRDF_H
#define MR_BRDF_H

#include <stddef.h>

#include "../mr_status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Upper bound on a model's packed value count and on its prepared-state size; descriptors must fit. */
#define MR_BRDF_MAX_VALUES 24
#define MR_BRDF_STATE_BYTES 512

/* How f_r depends on a parameter, with all other parameters fixed. The optimiser uses this structure:
 * for LINEAR/AFFINE parameters the best values for given nonlinear ones are a small linear least-squares
 * solve (design principle 3). */
typedef enum mr_param_role {
    MR_PARAM_LINEAR = 0,  /* f_r (per channel) is proportional to the value: albedo, specular scale */
    MR_PARAM_AFFINE,      /* f_r (per channel) is affine in the value: Schlick F0, glTF base colour */
    MR_PARAM_NONLINEAR,   /* roughness, exponent, IOR, metallic ... */
    MR_PARAM_SWITCH,      /* an integer option (0/1 ...), never optimised: e.g. Mitsuba's energy trimming */
    MR_PARAM_ROLE_COUNT
} mr_param_role;

/* Which part of f_r a parameter influences; two-stage fits use it to split the parameters. */
typedef enum mr_param_lobe {
    MR_LOBE_DIFFUSE = 1,
    MR_LOBE_SPECULAR = 2,
    MR_LOBE_BOTH = 3
} mr_param_lobe;

/* Bit flags of mr_brdf_param.flags. */
enum {
    MR_PARAM_LOG_SCALE = 1, /* the optimiser should search this parameter on a log scale (roughness) */
    MR_PARAM_FIT_FIXED = 2, /* fits hold it at its given value (default: the table's) instead of fitting it:
                               extension factors such as glTF's KHR_materials_specular, which a remap into the
                               core material should not invent */
    MR_PARAM_SRGB_MAP = 4   /* a colour (a reflectance or albedo given as an RGB colour: diffuse, specular, f0,
                               base colour, specular colour): 8/16-bit texture maps of it hold sRGB-encoded
                               values. Without the flag (roughness, alpha, metallic, ior, eta, scalars, switches)
                               they hold linear values. Float files (EXR, HDR, float TIFF) are linear either way.
                               The one rule every reader of maps applies: mr_brdf_param_map_encoding and
                               mr_img_read_param_map (io/image_io.h) */
};

typedef struct mr_brdf_param {
    const char *name;     /* lowercase identifier used on the command line: "alpha", "specular" */
    int channels;         /* 1 or 3 */
    double default_value; /* the renderer's own default (per channel for RGB parameters) */
    double min_value;     /* inclusive bounds; prepare() clamps into them */
    double max_value;
    mr_param_role role;
    mr_param_lobe lobe;
    unsigned flags;
    const char *meaning;  /* one line: what it is, its parameterisation and the source convention */
    const double *default_rgb; /* optional per-channel defaults of an RGB parameter (a coloured default such
                                  as Mitsuba's Cu eta and k); NULL: default_value in every channel. When set,
                                  default_value holds the G channel, for one-number displays. */
} mr_brdf_param;

/* Bit flags of mr_brdf_model.flags. */
enum {
    /* The model legitimately reflects more than it receives for some valid parameters (e.g. Blender
     * Internal's diffuse has no 1/pi). The white-furnace test skips the energy bound for these and
     * `models` says so. */
    MR_BRDF_NOT_ENERGY_CONSERVING = 1,
    /* f_r = diffuse lobe + specular lobe with independent scales that nothing (Fresnel, trimming) couples, as
     * in a Mitsuba microfacet plugin with an optional Lambert base added. Each lobe alone conserves energy;
     * their sum only while the lobe albedos sum to at most 1, which is the caller's choice of parameters.
     * The white-furnace test checks these models lobe by lobe (unless they are also flagged
     * MR_BRDF_NOT_ENERGY_CONSERVING); a fit may want to constrain the sum. */
    MR_BRDF_INDEPENDENT_LOBES = 2,
    /* f_r(wi, wo) != f_r(wo, wi) for some valid parameters, by the model's own definition: it scales lower layers by
     * 1 - E(wi), the directional albedo of the layer above at the FIRST direction (OpenPBR's and Standard Surface's
     * albedo scaling, with the renderer's view direction first: render.c calls eval(view, light)). The reciprocity
     * test skips these models, the white-furnace test integrates over wo at a fixed wi, and `models` says so. */
    MR_BRDF_NON_RECIPROCAL = 4
};

/* A batch of direction pairs for eval_batch, in structure-of-arrays layout: pair i is
 * wi = (wi[0][i], wi[1][i], wi[2][i]) and wo likewise, unit vectors in the local frame (the render passes its view
 * direction as wi, as eval(view, light)). The kernel writes f_r's parts per channel into diffuse[c][i] and
 * specular[c][i], c = 0, 1, 2: all six arrays must be given (n doubles each; a caller that needs one part passes
 * scratch for the other). Outputs must not overlap the inputs. */
typedef struct mr_brdf_batch {
    int n;               /* pairs, >= 0 */
    const double *wi[3]; /* x, y, z arrays of the first directions */
    const double *wo[3]; /* x, y, z arrays of the second directions */
    double *diffuse[3];  /* R, G, B arrays of the diffuse part (out) */
    double *specular[3]; /* R, G, B arrays of the specular part (out) */
} mr_brdf_batch;

typedef struct mr_brdf_model mr_brdf_model;

/* Prepared derivatives (mr_brdf_model.grad_ops; optional): eval_grad split for a caller that needs d f_r at many
 * direction pairs for one parameter vector and only some slots (a derivative render, render.h; the fits' local stage
 * asks for its 2-5 fitted slots of up to 20). `prepare` does the value-only part of eval_grad (the model's prepare,
 * in derivative form) once, for the slots asked for only; `eval` the direction-dependent rest per pair, carrying
 * those slots' derivatives alone. Models without it (NULL) are differentiated by eval_grad per pair. */
typedef struct mr_brdf_grad_ops {
    size_t state_bytes; /* bytes of a prepared derivative state, allocated by the caller (aligned as malloc's) */
    /* Prepare `state` for values[] (as eval_grad takes them) and `count` DISTINCT packed slots slots[0..count),
     * 1 <= count <= the value count. The state may point into itself: use it where it was prepared, never a copy.
     * Never fails. */
    void (*prepare)(const mr_brdf_model *model, const double *values, const int *slots, int count, void *state);
    /* d f_r / d values[slots[k]] at (wi, wo) into d_diffuse[k*3 + c] and d_specular[k*3 + c], k < count: the same
     * numbers as eval_grad's [slots[k]*3 + c] (tests/test_brdf.c checks them equal as doubles). Reads the state
     * only: any number of threads may evaluate one prepared state at once. */
    void (*eval)(const void *state, const double wi[3], const double wo[3], double *d_diffuse, double *d_specular);
    /* Optional (NULL: none): nonzero when the prepared state has a batched form, eval_batch below: one slot that
     * leaves the diffuse part unchanged (the lobe's shape, which the fits' projection asks for at every step). */
    int (*batchable)(const void *state);
    /* Optional, with batchable: eval over a batch (eval_batch's contract and arrays) for a state batchable accepts,
     * d f_r / d values[slot] into batch->specular (batch->diffuse: zeros); the same numbers as eval within
     * eval_batch's tolerance (MR_BRDF_BATCH_RTOL, _ATOL; tests/test_batch.c). */
    void (*eval_batch)(const void *state, const mr_brdf_batch *batch, int vector);
} mr_brdf_grad_ops;

struct mr_brdf_model {
    const char *name;    /* unique, lowercase: "ggx", "ward-duer" */
    const char *summary; /* one line for `matremap models` */
    const char *source;  /* where the formula comes from (renderer, file, version) */
    int param_count;
    const mr_brdf_param *params;
    unsigned flags;
    const void *config;  /* member configuration for families sharing one file; NULL otherwise */

    /* Turn a packed value vector (mr_brdf_value_count doubles) into prepared state: clamp, precompute.
     * `state` points to MR_BRDF_STATE_BYTES bytes, suitably aligned for double. Never fails. */
    void (*prepare)(const mr_brdf_model *model, const double *values, void *state);

    /* f_r(wi, wo) for the prepared state, split in diffuse[3] and specular[3] (RGB). Either output may be
     * NULL when the caller does not need it. Directions are unit vectors in the local frame. */
    void (*eval)(const void *state, const double wi[3], const double wo[3], double diffuse[3],
                 double specular[3]);

    /* Optional (NULL if absent): d f_r / d values[j] for every packed slot j, at the given (unclamped but
     * in-bounds) values. d_diffuse and d_specular each hold value_count*3 doubles, laid out
     * [j*3 + channel]. Switch parameters have derivative 0. */
    void (*eval_grad)(const mr_brdf_model *model, const double *values, const double wi[3],
                      const double wo[3], double *d_diffuse, double *d_specular);

    /* Optional (NULL if absent; only with eval_grad): eval_grad prepared once per parameter set, for chosen slots. */
    const mr_brdf_grad_ops *grad_ops;

    /* Optional (NULL: never): nonzero when the model rescales its LINEAR parameters at these packed values, so
     * that f_r is not linear in them there (Mitsuba's energy trimming, brdf_internal.h: diffuse + specular > 1
     * in some channel with trim on). Texture maps hold values where it does not: random sweeps draw there
     * (remap/sweep.h, the TEXTURE region) and learned transforms leave such rows out (learn/sweep_table.h). */
    int (*rescales)(const mr_brdf_model *model, const double *values);
    /* Optional (NULL: mr_brdf_eval_batch loops over eval): eval over a batch of direction pairs at once, for the
     * render loop (render.c evaluates a material without maps over its samples in batches). Contract: each output
     * equals what eval writes for that pair within MR_BRDF_BATCH_RTOL relative to the pair's largest value (both
     * parts, all channels) or MR_BRDF_BATCH_ATOL absolute (tests/test_batch.c checks it for every model and both
     * instruction sets); the result of a pair depends on that pair and `vector` alone, never on n or its position
     * in the batch (so renders stay the same for any thread count and chunking). `vector` nonzero asks for the
     * AVX2/FMA kernel, which is used only where the CPU has both (mr_brdf_batch_cpu_vector); zero asks for the
     * portable one. Kernels use brdf_batch.h's exp/log/pow, not libm's (a call would stop the vectorisation). */
    void (*eval_batch)(const void *state, const mr_brdf_batch *batch, int vector);
};

/* A prepared state on the stack: `mr_brdf_state st; model->prepare(model, values, st.bytes);` */
typedef union mr_brdf_state {
    double align_double;
    unsigned char bytes[MR_BRDF_STATE_BYTES];
} mr_brdf_state;

/* ---- registry (registry.c) ---- */

/* The registered models, in display order, NULL-terminated. */
const mr_brdf_model *const *mr_brdf_models(void);

/* Number of registered models. */
int mr_brdf_model_count(void);

/* The model called `name`, or NULL with a message listing the valid names in mr_last_error(). */
const mr_brdf_model *mr_brdf_find(const char *name);

/* ---- parameter-vector helpers (registry.c) ---- */

/* Total number of packed doubles (sum of channels over the table). */
int mr_brdf_value_count(const mr_brdf_model *model);

/* Slot of the first channel of parameter `index`; -1 if index is out of range. */
int mr_brdf_param_offset(const mr_brdf_model *model, int index);

/* Index of the parameter called `name`, or -1. */
int mr_brdf_param_index(const mr_brdf_model *model, const char *name);

/* Fill values[] with the table defaults. */
void mr_brdf_default_values(const mr_brdf_model *model, double *values);

/* Channel `channel` of a parameter's default: default_rgb[channel] when the parameter has coloured defaults, else
 * default_value (what mr_brdf_default_values writes). */
double mr_brdf_param_default(const mr_brdf_param *param, int channel);

/* "linear", "affine", "nonlinear", "switch"; NULL outside the enum (`matremap models` prints them). */
const char *mr_param_role_name(mr_param_role role);
/* "diffuse", "specular", "both" (MR_LOBE_BOTH and any other value). */
const char *mr_param_lobe_name(mr_param_lobe lobe);

/* Parse one "name=value" or "name=r,g,b" assignment into values[]. A single number given to an RGB parameter
 * sets all three channels. Unknown names (the message lists the valid ones), malformed numbers, wrong channel
 * counts and values outside [min, max] are MR_ERR_INVALID_ARG. */
mr_status mr_brdf_parse_assignment(const mr_brdf_model *model, const char *assignment, double *values);

/* Parse a hold list, "NAME[=VALUE][,NAME[=VALUE]...]" (the --hold of remap, sweep and convert --direct): each NAME is
 * a parameter of `model` to hold instead of fit (bit p of *held is set; *held keeps the bits it had); NAME=VALUE also
 * sets it in values[] by mr_brdf_parse_assignment's rules (an RGB parameter takes one value or r,g,b: the commas
 * after the first number continue that value while they are followed by a number), a bare NAME keeps the value
 * values[] already holds (given or default). MR_ERR_INVALID_ARG, naming the parameter and the text, for an unknown
 * name (the message lists the valid ones), an empty item, a malformed or out-of-range value, or a parameter beyond
 * the 32 a mask holds; values[] and *held are written only on success. */
mr_status mr_brdf_parse_holds(const mr_brdf_model *model, const char *text, double *values, unsigned *held);

/* Why a fit of `model` does not fit parameter p when the caller holds the mask `held` (bit p: the caller's hold):
 * MR_HOLD_FITTED (it is fitted), MR_HOLD_SWITCH (a switch: an option, never fitted), MR_HOLD_CALLER (bit p of
 * `held` is set, whatever the descriptor says) or MR_HOLD_MODEL (the descriptor's default hold, MR_PARAM_FIT_FIXED:
 * the model's documented choice of what a fit scene cannot separate). The one rule the remap applies (remap.h). */
typedef enum mr_hold_reason { MR_HOLD_FITTED = 0, MR_HOLD_MODEL, MR_HOLD_CALLER, MR_HOLD_SWITCH } mr_hold_reason;
mr_hold_reason mr_brdf_hold_reason(const mr_brdf_model *model, unsigned held, int p);

/* The holds of a fit as one line into buf (capacity size, always terminated; cut short, never overrun): the
 * caller's holds, then the model's default ones, each group in table order and labelled once,
 * "a=1, b=0.9,1,1 (held_label); c=1.5, d=0 (default for MODEL)", values from values[] (%g; an RGB parameter "r,g,b"
 * unless its channels agree); switches are left out. held_label names the caller's holds ("--hold"; NULL: "held").
 * "" when nothing is held. Returns the length the whole line needs (as snprintf). */
size_t mr_brdf_format_holds(const mr_brdf_model *model, const double *values, unsigned held, const char *held_label,
                            char *buf, size_t size);
/* The same, leaving out the parameters of `tied` (a fit's ties, mr_brdf_ties.tied: a tie of a default-held
 * parameter changes the value it is held at, which the "tied:" line says instead). */
size_t mr_brdf_format_holds_tied(const mr_brdf_model *model, const double *values, unsigned held, unsigned tied,
                                 const char *held_label, char *buf, size_t size);

/* Ties: target parameters held at the value of a source parameter (per material, row or texel) instead of fitted,
 * where a fit scene cannot separate what the source states (a metalness against the base colour at high roughness:
 * gltf -> openpbr at roughness 0.9, metallic 1, base colour 0.9 remaps to metalness 0.48, base colour 0.48 with SSIM
 * 0.996; docs/remap.md, "Ties"). Bit p of `tied`: target parameter p takes source parameter source[p] (the same
 * channel count). Zeroed = no ties. */
typedef struct mr_brdf_ties {
    unsigned tied;
    signed char source[32];
} mr_brdf_ties;

/* The documented default ties of a pair: what the source states and the target has under another name or the same
 * (registry.c's table). A target metalness (metallic, metalness, base_metalness) takes the source's, fitted or not
 * (gltf -> openpbr: base_metalness=metallic; -> standard-surface: metalness=metallic; -> blender-principled,
 * usd-preview, cycles-principled: metallic=metallic). A target parameter the target holds by default
 * (MR_PARAM_FIT_FIXED) takes the source's value of the same quantity instead of the held one: the dielectric IOR
 * (ior, specular_ior), the coat's weight (coat, coat_weight, clearcoat), roughness (coat_roughness,
 * clearcoat_roughness), IOR (coat_ior) and tint (coat_color, coat_tint), and the specular tint (specular_color,
 * specular_tint: F0's, and a metal's edge in the layered models). Held at their defaults instead, a jade (IOR
 * 2.418) or a ketchup (1.3) had no dielectric F0 to match and the fit bent other parameters, and a coated source
 * lost its coat (docs/evaluation-translations.md). None for a source stating none of these (Ward, GGX, Phong ...).
 * Same channel counts only. */
mr_brdf_ties mr_brdf_default_ties(const mr_brdf_model *source, const mr_brdf_model *target);

/* Parse a tie list "TARGET=SOURCE[,TARGET=SOURCE...]" (a target parameter, a source parameter of the same channel
 * count; switches refused) or "none" into *out (replacing it). MR_ERR_INVALID_ARG naming the item: an unknown name
 * (the valid ones listed), a channel mismatch, an empty item, a parameter beyond the 32 a mask holds. */
mr_status mr_brdf_parse_ties(const mr_brdf_model *source, const mr_brdf_model *target, const char *text,
                             mr_brdf_ties *out);

/* The ties as "a=b, c=d" into buf (always terminated; as snprintf: returns the length needed); "" for none. */
size_t mr_brdf_format_ties(const mr_brdf_model *source, const mr_brdf_model *target, const mr_brdf_ties *ties,
                           char *buf, size_t size);

/* Apply ties: target_values[tied parameter] = source_values[its source parameter] (clamped into the target
 * parameter's range), and the tied bits or'ed into *held (may be NULL). A parameter *held already holds (the
 * caller's hold) keeps its value: a hold wins over a tie. */
void mr_brdf_apply_ties(const mr_brdf_model *source, const double *source_values, const mr_brdf_model *target,
                        const mr_brdf_ties *ties, double *target_values, unsigned *held);

/* ---- batches (brdf_batch.c; the eval_batch contract above) ---- */

/* Tolerances of eval_batch against eval: relative to the pair's largest output, or absolute (the absolute bound
 * covers Mitsuba's cut-offs, D cos_h < 1e-20 and Ward's S <= 1e-10, which a last-bit difference can move across). */
#define MR_BRDF_BATCH_RTOL 1e-12
#define MR_BRDF_BATCH_ATOL 1e-9

/* f_r over a batch: model->eval_batch(state, batch, vector), or a loop over model->eval when the model has none. */
void mr_brdf_eval_batch(const mr_brdf_model *model, const void *state, const mr_brdf_batch *batch, int vector);

/* Whether this CPU runs the AVX2/FMA kernels (checked once, thread-safely; 0 off x86). */
int mr_brdf_batch_cpu_vector(void);

/* The `vector` a render passes by default: mr_brdf_batch_cpu_vector(), unless the environment variable
 * MATREMAP_SIMD is "scalar" (then 0: the portable kernels, for tests and comparisons; docs/performance.md). Read
 * once per process, thread-safely. */
int mr_brdf_batch_vector_default(void);

/* Convenience: prepare + eval of the full f_r (diffuse + specular) into rgb[3]. */
void mr_brdf_eval_full(const mr_brdf_model *model, const double *values, const double wi[3],
                       const double wo[3], double rgb[3]);

#ifdef __cplusplus
}
#endif

#endif /* MR_BRDF_H */
