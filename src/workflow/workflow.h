/*
 * workflow.h — analytic conversions between the metallic and the specular workflow (Sztrajman et al. 2019,
 * section 8, Eq. 2 and Eq. 3; the Khronos glTF converter as a third baseline). docs/workflow.md has the
 * derivations and the hard-case table.
 *
 * Main calls:
 *   mr_wf_options o = mr_wf_options_default();          // F0d 0.04 (glTF), WEIGHTED, eps 1e-6
 *   o.dielectric_f0 = MR_WF_F0_PAPER;                    // ... or the paper's 0.03
 *   o.diffuse_quantisation = (mr_wf_quantisation){8, 1, {1, 1, 1}};  // from an 8-bit sRGB texture: the
 *   o.specular_quantisation = o.diffuse_quantisation;                // flags allow half a code ("Tolerances")
 *   mr_wf_spec s;  unsigned flags;
 *   mr_wf_metal_to_spec(&(mr_wf_metal){{0.9, 0.5, 0.2}, 0.7, 0.3}, &o, &s, &flags);   // one texel
 *   mr_wf_spec_to_metal_batch(&spec_maps, n, &o, &metal_maps, flags8);                  // n texels
 *
 * The two workflows (values are linear reflectances in [0, 1]; RGB in the order R, G, B):
 *   metallic: albedo A (RGB), metallic m (scalar), roughness;
 *   specular: diffuse d (RGB), specular F0 s (RGB), roughness.
 * They describe the same BRDF (the `ggx` / `ggx-metallic` pair of src/brdf, glTF's metal-rough and spec-gloss),
 * so they share the roughness parameterisation: roughness passes through unchanged (clamped to [0, 1] like every
 * input). A spec-gloss target stores glossiness = 1 - roughness; that is the caller's business.
 *
 * Methods (mr_wf_method), spec -> metal; metal -> spec is Eq. 2 for all of them except KHRONOS:
 *   - Eq. 2 (metal -> spec):  d_c = A_c (1 - m),  s_c = F0d (1 - m) + m A_c.
 *   - Per channel, Eq. 3 generalised to any F0d: A_c is the root of A^2 - (s_c + d_c) A + F0d d_c = 0,
 *       A_c = ((s_c + d_c) + sqrt(max((s_c + d_c)^2 - 4 F0d d_c, 0))) / 2,   m_c = 1 - d_c / A_c,
 *     which is the paper's (s+d)/2 (1 + sqrt(1 - 4 F0d d/(s+d)^2)) and (s - F0d)/(A - F0d) without their divisions
 *     by s + d and A - F0d. A negative discriminant (no exact solution: s + d < 2 sqrt(F0d d)) is clamped to 0.
 *     Where that root is A_c <= F0d + t_s (t_s: the specular value's tolerance, eps by default), the channel is
 *     ambiguous: it has two exact readings, (A_c, m_c) and the less metallic (F0d d_c / A_c, 1 - A_c / F0d) (the
 *     roots multiply to F0d d_c; also, as the nearest readings, when the discriminant was clamped). The less
 *     metallic one is m_c = 0 for every dark dielectric (albedo <= F0d, m = 0, which the larger root would read as
 *     m = 1 - d/F0d), and albedo 0 with metallic 1 for black (d = s = 0): the only metallic material that renders
 *     black (a dielectric reflects F0d). If moreover |s_c - F0d| <= t_s, the less metallic reading is the
 *     dielectric (A_c = d_c, m_c = 0), which reproduces the channel within its tolerance: near the double root the
 *     second root is ill-conditioned (dm/ds is infinite there), and an 8-bit dielectric specular (0.0395 for
 *     0.04) beside a diffuse of 0.035 would read as m = 0.068. m_c is clamped to [0, 1] (it is negative only off
 *     the manifold, where d_c > A_c).
 *   - MEAN:     m = (m_r + m_g + m_b) / 3                                    (the paper's strategy 1)
 *   - WEIGHTED: m = sum_c A_c m_c / sum_c A_c, or MEAN when sum_c A_c <= eps (the paper's strategy 2). On the
 *     manifold A_c m_c = A_c - d_c, so m = 1 - sum d / sum A: the metallic that keeps the channel-summed diffuse
 *     exact; dark channels, whose m_c is ill-conditioned (dm = -dd / A) or ambiguous, count little.
 *   - then, for the one chosen m, each channel's albedo is the least-squares fit of Eq. 2 to (d_c, s_c),
 *       A_c = clamp(((1 - m) d_c + m (s_c - F0d (1 - m))) / ((1 - m)^2 + m^2), 0, 1),
 *     which returns the exact albedo whenever (d_c, s_c) is reachable with this m.
 *   - ambiguous channels: each combination of their readings (at most 8) gives an m and a fit; the least metallic
 *     combination whose fit reproduces the texel within its tolerance T_c (below) is taken, else the one that
 *     misses by least. So a channel darker than F0d in a brighter metal takes the reading the other channels
 *     agree with (the texel stays exact), and a texel ambiguous in every channel keeps its less metallic readings
 *     where they agree (dark dielectrics; a dark grey metal reads as its twin, which renders alike).
 *   - KHRONOS: the glTF project's converter (KHR_materials_pbrSpecularGlossiness, convert-between-workflows,
 *     three.pbrUtilities.js) in both directions, operation for operation in double precision: perceived
 *     brightness instead of channels, diffuse renormalised by (1 - max_c s_c) / (1 - 0.04), its own epsilon 1e-6.
 *     Its F0d is the constant 0.04: opts->dielectric_f0 must be 0.04 (MR_ERR_INVALID_ARG otherwise).
 *   - CUSTOM: opts->custom converts one texel (the slot for a learned converter such as nn/'s MLP; see
 *     mr_wf_custom_fn). Its outputs are sanitised like inputs (non-finite -> 0, clamped to [0, 1]).
 *
 * Hard cases (never an error, never NaN: every output is finite and in [0, 1]; metal -> spec results are clamped
 * to it, which only removes rounding excess, e.g. Khronos's diffuse for an albedo channel of 1 can come out
 * ~1e-12 above 1); per-texel flags (mr_wf_flag):
 *   - an input outside [0, 1] is clamped to it (MR_WF_CLAMPED_INPUT);
 *   - a NaN or infinite input is read as 0, a roughness as 1 (below) (MR_WF_NONFINITE_INPUT);
 *   - MR_WF_OFF_MANIFOLD (spec -> metal): the result, put through the method's forward conversion (Eq. 2;
 *     Khronos's own for KHRONOS), misses the sanitised input by more than its tolerance T_c ("Tolerances" below:
 *     2 eps by default) in some value. That is: the input is not reachable with one metallic (a coloured
 *     dielectric F0, specular above what the albedo allows or below F0d, a negative discriminant), or the
 *     single-metallic choice missed one (MEAN averaging a dark channel's noisy m_c in; KHRONOS's own losses).
 *   - MR_WF_METHOD_FAILED: the CUSTOM callback returned non-zero (the texel is then albedo 0, metallic 0) or a
 *     value outside [0, 1] or non-finite (sanitised).
 * metal -> spec is a closed formula (Eq. 2 is exact) and sets OFF_MANIFOLD only under MR_WF_DIFFUSE_SPECGLOSS, for
 * a texel whose spec-gloss diffuse would have to exceed 1.
 * Roughness (either direction) is the exception to "non-finite is read as 0": a NaN or infinite roughness is read
 * as 1, fully rough (flagged MR_WF_NONFINITE_INPUT), so a broken texel never becomes a mirror. A caller turning
 * glossiness into roughness = 1 - glossiness keeps NaN and infinities non-finite, and gets the same texel as a
 * non-finite glossiness read as 0.
 *
 * Tolerances. OFF_MANIFOLD asks whether the input could be a metallic material's, up to how precisely the input
 * is known. By default every value is taken as exact to opts->eps (1e-6: float rounding). A value decoded from an
 * 8-bit texture is only known to half a code value (up to 0.0045 in linear units), and at 1e-6 the flag marks most
 * texels of a clean metal-rough export. opts->diffuse_quantisation and opts->specular_quantisation say how each
 * input map was stored (mr_wf_quantisation: bits, sRGB or linear codes, the factor applied after decoding); the
 * tolerance of a value v of that map, channel c, is then
 *     t = max(eps, scale[c] * mr_img_half_step(v / scale[c], bits, sRGB or linear))
 * (image_io.h: half a code value at the code nearest to v / scale[c]), so it varies per texel and per value; with
 * bits 0 (the default) t = eps. With t_d (the diffuse value's) and t_s (the specular's), per channel c:
 *   - the compared diffuse is the lobe d (1 - max s) under MR_WF_DIFFUSE_SPECGLOSS, so its own tolerance is
 *     t_d[c] (1 - max s) + d[c] t_s[k], k the channel of max s (first-order propagation); plain: t_d[c];
 *   - both forward-converted values of channel c, diffuse and specular, may miss their inputs by
 *     T_c = t_d'[c] + t_s[c] (t_d' the diffuse's own, as above): the result depends on both inputs, and a fit
 *     spreads an error in either over both (on channel c's manifold line, an input error (e_d, e_s) leaves the
 *     residual (m e_d - (1 - m) e_s) (m, -(1 - m)) / (m^2 + (1 - m)^2), each component at most |e_d| + |e_s| / 2;
 *     the single metallic's own error adds to it). With the default eps this is 2 eps (plain convention). The
 *     choice among ambiguous channels' readings (above) asks the same question of each combination;
 *   - the Eq. 3 ambiguity test is A_c <= F0d + t_s[c], and the dielectric reading |s_c - F0d| <= t_s[c]: the
 *     root moves with the specular by dA/ds = A/sqrt(disc), about 1 for a dark channel (d << F0d), and hardly
 *     with the diffuse there, so a dark dielectric whose quantised specular lands a code above or below F0d still
 *     reads as m = 0 rather than as a half metal or m = 0.068.
 * The WEIGHTED "black texel" test (sum of albedos <= eps) always uses eps: it guards a division, not a precision.
 * mr_wf_spec_to_metal_mlp_batch computes no OFF_MANIFOLD and ignores the quantisations. The batch tabulates sRGB
 * quantisations (8 bits: 11 KB; 16 bits: 1 MB, allocated per call: MR_ERR_NOMEM) and answers exactly what the
 * per-texel functions, which call mr_img_half_step, answer. Near-black partial metals (every channel <= ~0.05)
 * can still be flagged: one code of diffuse moves their metallic by hundredths (docs/workflow.md has figures).
 *
 * Batched layout (mr_wf_*_maps): planar, one array per texture map, n texels each; an RGB map holds 3n floats,
 * channels interleaved per texel (texel i at [3i, 3i + 3), the pixel buffer of a 3-channel mr_image); a scalar map
 * holds n floats. Roughness maps are optional: both NULL, or both given (copied, clamped). Inputs are only read.
 * An output map may be the very same array as an input map of the same size (in place: each texel reads all its
 * inputs before writing); any other overlap is undefined. Values are computed in double and rounded to float.
 *
 * Arguments: opts may be NULL (the defaults). Invalid arguments (NULL pointers, dielectric_f0 outside [0, 1) or
 * not finite, eps outside [0, 1), an unknown method, CUSTOM without a callback, KHRONOS with F0d != 0.04, n too
 * large, a quantisation with bits other than 0, 8 or 16 or a negative or non-finite scale) return
 * MR_ERR_INVALID_ARG with mr_last_error() naming the value; outputs are then untouched.
 * Threads: the batch functions run an OpenMP parallel for over texels; every texel is a pure function of its own
 * inputs, so results are bit-identical for any thread count and equal to the per-texel functions' (rounded to
 * float). All functions are reentrant. Ownership: the caller owns every array; the only allocations are the
 * spec -> metal batch's tolerance tables (freed before it returns) and the network's blocks.
 * The library never prints, exits or aborts.
 */
#ifndef MR_WORKFLOW_H
#define MR_WORKFLOW_H

#include <stddef.h>
#include <stdint.h>

#include "../mr_status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Dielectric F0 conventions: glTF's (ior 1.5; the default) and the paper's. */
#define MR_WF_F0_GLTF 0.04
#define MR_WF_F0_PAPER 0.03
/* The default absolute reflectance tolerance (mr_wf_options.eps): about 16 float ulps at 1, far below an 8-bit
 * step (1/255), so a float round trip is exact within it. */
#define MR_WF_DEFAULT_EPS 1e-6

/* Spec -> metal methods. The default is 0 (so a zeroed mr_wf_options means it); values are append-only from here
 * (WEIGHTED and MEAN swapped places in 0.1.0 for that). */
typedef enum mr_wf_method {
    MR_WF_WEIGHTED = 0, /* Eq. 3 per channel, albedo-weighted mean metallic (the default) */
    MR_WF_MEAN,         /* Eq. 3 per channel, mean metallic */
    MR_WF_KHRONOS,  /* the Khronos glTF converter, both directions */
    MR_WF_CUSTOM,   /* opts->custom (spec -> metal); Eq. 2 for metal -> spec */
    MR_WF_METHOD_COUNT
} mr_wf_method;

/* What the specular workflow's diffuse map means. The two workflows share one BRDF only when the specular
 * material's diffuse lobe is read the same way on both sides of the conversion. Values are append-only. */
typedef enum mr_wf_diffuse {
    MR_WF_DIFFUSE_PLAIN = 0, /* the diffuse lobe is d itself: Lambert + GGX, the paper's `ggx` / `ggx-metallic`
                                pair and Eq. 2 as printed (the default) */
    MR_WF_DIFFUSE_SPECGLOSS, /* glTF KHR_materials_pbrSpecularGlossiness: the lobe is d (1 - max_c s_c), and glTF
                                metal-rough's is A (1 - m). Spec -> metal converts d (1 - max_c s_c); metal -> spec
                                divides Eq. 2's diffuse by (1 - max_c s_c) (where that exceeds 1, e.g. a white
                                dielectric, it is clamped to 1 and the texel flagged MR_WF_OFF_MANIFOLD) */
    MR_WF_DIFFUSE_COUNT
} mr_wf_diffuse;

/* "paper" (PLAIN), "gltf" (SPECGLOSS): the names of `--convention`; NULL outside the enum. */
const char *mr_wf_diffuse_name(mr_wf_diffuse diffuse);
/* Parse one of the names above into *out; MR_ERR_INVALID_ARG saying what each means otherwise (*out untouched). */
mr_status mr_wf_diffuse_from_name(const char *name, mr_wf_diffuse *out);

/* "mean", "weighted", "khronos", "custom"; NULL outside the enum. */
const char *mr_wf_method_name(mr_wf_method method);
/* Parse one of the names above into *out; MR_ERR_INVALID_ARG listing them otherwise (*out untouched). */
mr_status mr_wf_method_from_name(const char *name, mr_wf_method *out);

/* Per-texel flag bits (a texel's flags are their OR; 0 = clean). */
typedef enum mr_wf_flag {
    MR_WF_CLAMPED_INPUT = 1u << 0,   /* an input was outside [0, 1] and was clamped */
    MR_WF_NONFINITE_INPUT = 1u << 1, /* an input was NaN or infinite and was read as 0 (a roughness: as 1) */
    MR_WF_OFF_MANIFOLD = 1u << 2,    /* spec -> metal result misses the input by more than its tolerance */
    MR_WF_METHOD_FAILED = 1u << 3    /* the CUSTOM callback failed or returned values outside [0, 1] */
} mr_wf_flag;

/* One texel of each workflow. */
typedef struct mr_wf_metal {
    double albedo[3]; /* base colour, linear RGB */
    double metallic;
    double roughness; /* passes through */
} mr_wf_metal;

typedef struct mr_wf_spec {
    double diffuse[3];  /* linear RGB */
    double specular[3]; /* F0, linear RGB */
    double roughness;   /* passes through */
} mr_wf_spec;

/* How an input map of spec -> metal was stored, which bounds how precisely its values are known (see
 * "Tolerances" above). mr_wf_options_default() gives bits 0 and scale 1, 1, 1. */
typedef struct mr_wf_quantisation {
    int bits;        /* 0: exact to opts->eps (float maps, constants; the default); 8 or 16: each value was decoded
                        from an unsigned integer code of that many bits, then multiplied by scale[c] */
    int srgb;        /* with bits 8/16: 1 = sRGB-encoded codes (colour textures), 0 = linear codes */
    double scale[3]; /* with bits 8/16: the factor (finite, >= 0) that multiplied each channel's decoded value
                        (glTF's factors), default 1; a value of channel c is known to scale[c] times half a code */
} mr_wf_quantisation;

struct mr_img_stored;
/* How a map was stored as mr_img_read_stored says (*stored; NULL: a constant, exact), times scale[c] (glTF's factors;
 * NULL: 1, 1, 1): the 8/16-bit codes of a file (sRGB or linear), or exact (bits 0) for float files and constants. */
mr_wf_quantisation mr_wf_quantisation_of(const struct mr_img_stored *stored, const double *scale);

struct mr_wf_options;

/* A caller-supplied spec -> metal converter for MR_WF_CUSTOM (the slot for nn/'s MLP). It gets the sanitised
 * texel (values in [0, 1]) and the options (dielectric_f0, custom_data), writes albedo[3] and *metallic, and
 * returns 0 on success. The batch functions call it from several OpenMP threads at once: it must be reentrant,
 * and deterministic if the results are to be. It must not call back into the batch functions. */
typedef int (*mr_wf_custom_fn)(const struct mr_wf_options *opts, const double diffuse[3], const double specular[3],
                               double albedo[3], double *metallic);

typedef struct mr_wf_options {
    double dielectric_f0;   /* F0d of Eq. 2 and 3, in (0, 1); 0 = the default MR_WF_F0_GLTF (0.04); paper: 0.03 */
    mr_wf_method method;    /* default MR_WF_WEIGHTED */
    double eps;             /* absolute reflectance tolerance in (0, 1); 0 = the default MR_WF_DEFAULT_EPS: an Eq. 3
                               root within eps of F0d counts as ambiguous, albedos summing to <= eps fall back to
                               MEAN, a residual above 2 eps sets MR_WF_OFF_MANIFOLD (eps on each input). DBL_MIN
                               makes the flag see rounding. The quantisations below raise it per value
                               ("Tolerances") */
    mr_wf_custom_fn custom; /* MR_WF_CUSTOM only; default NULL */
    void *custom_data;      /* passed through to custom (via opts); default NULL */
    mr_wf_diffuse spec_diffuse; /* how the specular side's diffuse is read; default MR_WF_DIFFUSE_PLAIN. KHRONOS
                                   always reads it as spec-gloss (its own renormalisation) and ignores this */
    mr_wf_quantisation diffuse_quantisation;  /* spec -> metal: how the diffuse input was stored; default exact
                                                 (bits 0: tolerance eps). See "Tolerances" above */
    mr_wf_quantisation specular_quantisation; /* the same for the specular input */
    int threads;            /* the batches' OpenMP threads: 0 (default) = automatic, a team only for at least
                               MR_WF_PARALLEL_TEXELS texels (a 2048^2 map; not one texel or a dataset's few);
                               n >= 1: n (<= 1024). Results do not depend on it */
} mr_wf_options;

/* The automatic thread rule's threshold (mr_wf_options.threads = 0): below it a team costs more than it saves. */
#define MR_WF_PARALLEL_TEXELS 16384

/* The defaults listed above; a zero-initialised struct means the same (its zero F0d and eps read as the defaults). */
mr_wf_options mr_wf_options_default(void);

/* MR_OK, or MR_ERR_INVALID_ARG with the message every conversion would give for these options (CUSTOM needs its
 * callback in both directions, although metal -> spec does not call it). NULL is the defaults (MR_OK). */
mr_status mr_wf_options_check(const mr_wf_options *opts);

/* Metallic -> specular for one texel: Eq. 2 (KHRONOS: Khronos's converter). *out and *flags (which may be NULL)
 * are written on success. */
mr_status mr_wf_metal_to_spec(const mr_wf_metal *in, const mr_wf_options *opts, mr_wf_spec *out, unsigned *flags);

/* Specular -> metallic for one texel by opts->method. *out and *flags (may be NULL) are written on success. */
mr_status mr_wf_spec_to_metal(const mr_wf_spec *in, const mr_wf_options *opts, mr_wf_metal *out, unsigned *flags);

/* Planar texture maps of n texels (see "Batched layout" above). */
typedef struct mr_wf_metal_maps {
    float *albedo;    /* 3n: RGB interleaved */
    float *metallic;  /* n */
    float *roughness; /* n, or NULL */
} mr_wf_metal_maps;

typedef struct mr_wf_spec_maps {
    float *diffuse;   /* 3n: RGB interleaved */
    float *specular;  /* 3n: RGB interleaved */
    float *roughness; /* n, or NULL */
} mr_wf_spec_maps;

/* The same maps as a batch's input, read only (they may be an output's arrays: conversion in place is allowed). */
typedef struct mr_wf_metal_input {
    const float *albedo, *metallic, *roughness;
} mr_wf_metal_input;

typedef struct mr_wf_spec_input {
    const float *diffuse, *specular, *roughness;
} mr_wf_spec_input;

/* Convert n texels; flags (n bytes, may be NULL) receives each texel's mr_wf_flag bits. n = 0 is a no-op (map
 * pointers may then be NULL). Every required map must be non-NULL, and out->roughness non-NULL exactly when
 * in->roughness is. */
mr_status mr_wf_metal_to_spec_batch(const mr_wf_metal_input *in, size_t n, const mr_wf_options *opts,
                                    const mr_wf_spec_maps *out, uint8_t *flags);
mr_status mr_wf_spec_to_metal_batch(const mr_wf_spec_input *in, size_t n, const mr_wf_options *opts,
                                    const mr_wf_metal_maps *out, uint8_t *flags);

struct mr_mlp;

/* The residual form of a spec -> metal network (mr_mlp.kind == MR_WF_MLP_RESIDUAL_KIND; docs/training.md). Its four
 * outputs are a correction delta to the albedo-weighted inverse W (Eq. 3, F0d 0.04, of the diffuse lobe), applied as
 *     albedo_c = W_c + gate (mean(delta_rgb) + chroma (delta_c - mean(delta_rgb))),   metallic = W_m + gate delta_m
 * (clamped to [0, 1]), where
 *   gate   = min(1, r / MR_WF_RESIDUAL_GATE), r = the largest |Eq. 2 of W - input| over the six values: 0 where
 *            Eq. 2 is exactly invertible, so texels on the manifold (any metal-rough texel converted by Eq. 2)
 *            come out exactly as the analytic inverse;
 *   chroma = min(1, c / MR_WF_RESIDUAL_CHROMA), c = max_ch |lobe_ch - mean lobe| + max_ch |s_ch - mean s|: a grey
 *            input (c = 0) gets the same correction in every channel, so grey in is grey out (W is grey there).
 * Training targets are the label minus W (matremap train --form residual). */
#define MR_WF_MLP_RESIDUAL_KIND "spec2metal-residual"
#define MR_WF_RESIDUAL_GATE 0.01
#define MR_WF_RESIDUAL_CHROMA 0.02

typedef struct mr_wf_residual_anchor {
    double albedo[3], metallic; /* W */
    double gate, chroma;        /* as above, in [0, 1] */
} mr_wf_residual_anchor;

/* The anchor of one texel: `lobe` the diffuse lobe (the network's input, d (1 - max s) for glTF spec-gloss) and
 * `specular`, both already in [0, 1]. Pure and reentrant. */
void mr_wf_residual_anchor_of(const double lobe[3], const double specular[3], mr_wf_residual_anchor *out);

/* Training pairs (x: n x 6 lobe RGB + specular RGB, y: n x 4 albedo RGB + metallic, as mr_wf_dataset holds them)
 * turned into the residual form's targets in place: y minus the anchor W of each row's x (clamped to [0, 1]). */
void mr_wf_residual_targets(const float *x, float *y, size_t n);

/* Specular -> metallic by a trained network (nn/mlp.h: 6 inputs diffuse RGB + specular RGB, 4 outputs albedo RGB
 * + metallic, e.g. data/spec2metal.mlp; read as the residual form above when its kind says so), batched: inputs
 * are sanitised like the other methods' (clamped to [0, 1], non-finite read as 0, flagged), the network runs in
 * chunks of texels (in the residual form only on texels whose gate is open), outputs are clamped to
 * [0, 1] (a non-finite output becomes 0 and sets MR_WF_METHOD_FAILED). OFF_MANIFOLD is not computed (a
 * regressor never reproduces its input exactly). opts: only eps and the roughness pairing matter; may be NULL.
 * Each distinct input value (the bits of its six floats) of a chunk of 32768 texels is converted once and its
 * answer copied to the texels that repeat it (real 8-bit texture sets hold ~5 % distinct values); the answers are
 * the bits of converting every texel alone. Threads: the automatic rule (opts->threads, MR_WF_PARALLEL_TEXELS), at
 * most one per chunk; each thread converts whole chunks (one team per call, no barrier inside it).
 * MR_ERR_INVALID_ARG for a network of another shape or a bad MR_MLP_KERNEL (nn/mlp.h); MR_ERR_NOMEM.
 * Deterministic for any thread count. */
mr_status mr_wf_spec_to_metal_mlp_batch(const struct mr_mlp *net, const mr_wf_spec_input *in, size_t n,
                                        const mr_wf_options *opts, const mr_wf_metal_maps *out, uint8_t *flags);

#ifdef __cplusplus
}
#endif

#endif /* MR_WORKFLOW_H */
