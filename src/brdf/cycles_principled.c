/*
 * cycles_principled.c — `cycles-principled`: the diffuse and specular layers of Blender Cycles' Principled BSDF
 * v1 as of Blender 3.4 (the version Debian 12 ships, 3.4.1); isotropic, opaque.
 *
 *   Specular layer, single-scatter GGX with the "PRINCIPLED_V1" Fresnel blend:
 *     alpha = roughness^2,  ior = 2/(1 - sqrt(0.08 specular)) - 1   (so F_dielectric(1, ior) = 0.08 specular)
 *     lum = 0.3 R + 0.6 G + 0.1 B of base_color;  tint = base/lum, or (1,1,1) if lum = 0
 *     cspec0 = saturate(0.08 specular mix(1, tint, specular_tint) (1 - metallic) + base metallic)
 *     FH = (F_dielectric(wi.h, ior) - F0) / (1 - F0),  F0 = F_dielectric(1, ior)
 *     F = cspec0 (1 - FH) + FH
 *     f_s = F D G1(wi) G1(wo) / (4 cos_i cos_o)
 *       D = GGX = alpha^2 / (pi cos^4(theta_h) (alpha^2 + tan^2(theta_h))^2),  G1 = 2/(1 + sqrt(1 + alpha^2 tan^2))
 *   Diffuse layer, Burley 2012 ("PRINCIPLED_DIFFUSE_FULL"), weight (1 - metallic):
 *     F_L = (1 - cos_i)^5, F_V = (1 - cos_o)^5, RR = roughness (1 + wi.wo)  (= 2 roughness (wi.h)^2)
 *     f_d = base (1 - metallic)/pi ((1 - F_V/2)(1 - F_L/2) + RR (F_L + F_V + F_L F_V (RR - 1)))
 *         = base (1 - metallic)/pi (1 + (F_d90 - 1) F_L)(1 + (F_d90 - 1) F_V),  F_d90 = 0.5 + RR
 *
 * Version choices, with the evidence:
 *   - G is the separable Smith G1(wi) G1(wo) of Cycles <= 3.4 (3.5 moved to the height-correlated form).
 *   - The tint luminance is 0.3 R + 0.6 G + 0.1 B, the "luminance approx." line of the specular code in
 *     intern/cycles/kernel/svm/closure.h. Read in a 3.0-3.4 copy of the file (float3 closure weights,
 *     PRINCIPLED_DIFFUSE_FULL) and in a 3.5/3.6 one (Spectrum weights, FresnelPrincipledV1); only the sheen tint
 *     uses linear_rgb_to_gray (the scene-linear, Rec.709 luminance) there. The request for this model named
 *     Rec.709 for the specular tint as well; the source says otherwise, and the source wins here.
 *   - cspec0 is saturated as bsdf_microfacet_ggx_fresnel_setup() does; FH is clamped to [0, 1], which changes
 *     nothing mathematically (F_dielectric >= F0 for cos <= 1) but keeps rounding from making F negative.
 *   - Cycles drops closures whose weight is below 1e-5 (CLOSURE_WEIGHT_CUTOFF); we keep them, so f stays smooth
 *     in its parameters. The difference is below 1e-5 of the lobe.
 *
 * Parameters (defaults are the node's):
 *   base_color     RGB [0, 1]     default 0.8  Base Color, linear RGB. NONLINEAR: the specular tint divides by its
 *                                              luminance and cspec0 is saturated (with specular_tint = 0 and no
 *                                              saturation it would be AFFINE).
 *   metallic           [0, 1]     default 0    Metallic
 *   specular           [0, 1]     default 0.5  Specular (0.5 = F0 0.04, ior 1.5); specular = 0 gives ior = 1, F0 = 0
 *   specular_tint      [0, 1]     default 0    Specular Tint
 *   roughness          [0.01, 1]  default 0.5  Roughness, log scale; alpha = roughness^2. Cycles accepts 0 (a mirror);
 *                                              0.01 (alpha = 1e-4, Mitsuba's floor) keeps the GGX lobe finite.
 *
 * Not simulated: Cycles' default distribution is Multiscatter GGX, used for roughness > 0.075; its random walk
 * adds back the energy single scattering loses at high roughness. That loss is large: with F = 1 the single-scatter
 * albedo at normal incidence is 0.88 at roughness 0.55 (alpha 0.3) and 0.31 at roughness 1 (ggx-nofresnel,
 * measured by the white-furnace quadrature of tests/test_brdf.c). This model is the single-scatter lobe at every
 * roughness, which is what "GGX" in the node gives; rough Multiscatter renders are brighter. Also omitted: sheen,
 * clearcoat, transmission, subsurface, anisotropy, emission, alpha, normal maps.
 *
 * Source: Blender 3.4 intern/cycles/kernel/svm/closure.h (CLOSURE_BSDF_PRINCIPLED_ID), kernel/closure/
 * bsdf_microfacet.h, bsdf_util.h (interpolate_fresnel_color, fresnel_dielectric_cos), bsdf_principled_diffuse.h
 * (brdf-reference 4.1-4.3). Cycles' eval returns f_r cos(wo); ours does not (brdf.h).
 * Energy: flagged MR_BRDF_NOT_ENERGY_CONSERVING. Burley's diffuse has a retro-reflective term (F_d90 up to 2.5)
 * whose albedo exceeds 1 for rough surfaces (white base, roughness 1: 1.04 at normal incidence, 1.28 at 80 degrees,
 * 1.49 at 88), and Principled v1 adds the specular layer on top of the diffuse one without taking its energy
 * away (white base, specular 1, roughness 0.3: total 1.07 at normal incidence, 1.23 at 80 degrees). That is
 * Cycles' model, not a bug here.
 * Gradient: analytic for every parameter (one-sided where cspec0 saturates, where FH clamps, and at lum = 0).
 */
#include "brdf_batch.h"

/* Slots of the packed value vector. */
enum { CP_BASE = 0, CP_METALLIC = 3, CP_SPECULAR = 4, CP_SPECULAR_TINT = 5, CP_ROUGHNESS = 6 };

/* Luminance weights of the specular tint (closure.h, 3.x: "luminance approx."). */
static const double cp_lum_weight[3] = {0.3, 0.6, 0.1};

static const mr_brdf_param cp_params[] = {
    {"base_color", 3, 0.8, 0.0, 1.0, MR_PARAM_NONLINEAR, MR_LOBE_BOTH, MR_PARAM_SRGB_MAP,
     "Base Color, linear RGB: diffuse albedo, metal F0 and specular tint", NULL},
    {"metallic", 1, 0.0, 0.0, 1.0, MR_PARAM_NONLINEAR, MR_LOBE_BOTH, 0, "Metallic", NULL},
    {"specular", 1, 0.5, 0.0, 1.0, MR_PARAM_NONLINEAR, MR_LOBE_SPECULAR, 0,
     "Specular: dielectric F0 = 0.08 specular, ior = 2/(1 - sqrt(0.08 specular)) - 1", NULL},
    {"specular_tint", 1, 0.0, 0.0, 1.0, MR_PARAM_NONLINEAR, MR_LOBE_SPECULAR, MR_PARAM_FIT_FIXED,
     "Specular Tint: mixes the dielectric F0 towards base_color / luminance(base_color)", NULL},
    {"roughness", 1, 0.5, 0.01, 1.0, MR_PARAM_NONLINEAR, MR_LOBE_BOTH, MR_PARAM_LOG_SCALE,
     "Roughness; GGX alpha = roughness^2, Burley retro-reflection uses roughness itself", NULL},
};

typedef struct cp_state {
    double alpha;
    double roughness;
    double ior;
    double F0;                    /* F_dielectric(1, ior) */
    double cspec0[3];
    double diffuse_over_pi[3];    /* base (1 - metallic)/pi */
} cp_state;

_Static_assert(sizeof(cp_state) <= MR_BRDF_STATE_BYTES, "cp_state must fit in MR_BRDF_STATE_BYTES");

static double cp_ior(double specular) { return 2.0 / (1.0 - sqrt(0.08 * specular)) - 1.0; }

/* The raw (unsaturated) cspec0, and the tint colour mix(1, base/lum, specular_tint). */
static void cp_cspec0_raw(const double *v, double raw[3]) {
    double lum = 0.0;
    for (int c = 0; c < 3; c++) lum += cp_lum_weight[c] * v[CP_BASE + c];
    double m = v[CP_METALLIC], s = v[CP_SPECULAR], t = v[CP_SPECULAR_TINT];
    for (int c = 0; c < 3; c++) {
        double tint = lum > 0.0 ? v[CP_BASE + c] / lum : 1.0;
        raw[c] = 0.08 * s * ((1.0 - t) + tint * t) * (1.0 - m) + v[CP_BASE + c] * m;
    }
}

/* Burley's factor B (f_d = base (1 - metallic)/pi B), in Cycles' Lambert + retro-reflection split, with
 * dB/droughness. */
static double cp_burley(const mr_brdf_geom *g, double roughness, double *dB_droughness) {
    double FL = mr_schlick_weight(MR_MIN(g->cos_i, 1.0)), FV = mr_schlick_weight(MR_MIN(g->cos_o, 1.0));
    double LH2 = 0.5 * g->h_len2; /* dot(L, V) + 1 */
    double RR = roughness * LH2;
    if (dB_droughness) *dB_droughness = (FL + FV + FL * FV * (2.0 * RR - 1.0)) * LH2;
    return (1.0 - 0.5 * FV) * (1.0 - 0.5 * FL) + RR * (FL + FV + FL * FV * (RR - 1.0));
}

/* FH = clamp((F_dielectric(wi.h, ior) - F0)/(1 - F0), 0, 1). 1 - F0 = 1 - 0.08 specular >= 0.92: no guard needed
 * beyond the parameter bound. */
static double cp_fh(double dot_h, double ior, double F0) {
    double Fr = mr_fresnel_dielectric(dot_h, ior, NULL);
    return mr_clampd((Fr - F0) / (1.0 - F0), 0.0, 1.0);
}

static void cp_prepare(const mr_brdf_model *model, const double *values, void *state_bytes) {
    cp_state *state = state_bytes;
    double v[MR_BRDF_MAX_VALUES], raw[3];
    mr_brdf_clamp_values(model, values, v);
    cp_cspec0_raw(v, raw);
    state->roughness = v[CP_ROUGHNESS];
    state->alpha = v[CP_ROUGHNESS] * v[CP_ROUGHNESS];
    state->ior = cp_ior(v[CP_SPECULAR]);
    state->F0 = mr_fresnel_dielectric(1.0, state->ior, NULL);
    for (int c = 0; c < 3; c++) {
        state->cspec0[c] = mr_clampd(raw[c], 0.0, 1.0);
        state->diffuse_over_pi[c] = v[CP_BASE + c] * (1.0 - v[CP_METALLIC]) * MR_INV_PI;
    }
}

static void cp_eval(const void *state_bytes, const double wi[3], const double wo[3], double diffuse[3],
                    double specular[3]) {
    const cp_state *state = state_bytes;
    mr_brdf_geom g;
    if (!mr_brdf_geom_init(wi, wo, &g)) {
        mr_brdf_zero(diffuse, specular);
        return;
    }
    if (diffuse) {
        double B = cp_burley(&g, state->roughness, NULL);
        for (int c = 0; c < 3; c++) diffuse[c] = state->diffuse_over_pi[c] * B;
    }
    if (specular) {
        double dg = mr_mf_dg(MR_MF_GGX, state->alpha, &g, 0, NULL);
        double FH = cp_fh(g.dot_h, state->ior, state->F0);
        for (int c = 0; c < 3; c++) specular[c] = (state->cspec0[c] * (1.0 - FH) + FH) * dg;
    }
}

/* eval over a batch (brdf.h eval_batch): cp_eval's operations (cp_burley and cp_fh are small enough to inline). */
MR_BATCH_INLINE void cp_batch_body(const void *state_bytes, const mr_brdf_batch *batch, const int fused) {
    const cp_state *state = state_bytes;
    const double alpha = state->alpha, roughness = state->roughness, ior = state->ior, F0 = state->F0;
    const double d0 = state->diffuse_over_pi[0], d1 = state->diffuse_over_pi[1], d2 = state->diffuse_over_pi[2];
    const double c0 = state->cspec0[0], c1 = state->cspec0[1], c2 = state->cspec0[2];
    MR_BATCH_ARRAYS(batch);
#pragma omp simd
    for (int i = 0; i < n_; i++) {
        mr_brdf_geom g;
        const int lit = mr_batch_geom(ix_[i], iy_[i], iz_[i], ox_[i], oy_[i], oz_[i], &g);
        // cp_burley
        const double FL = mr_schlick_weight(MR_MIN(g.cos_i, 1.0)), FV = mr_schlick_weight(MR_MIN(g.cos_o, 1.0));
        const double LH2 = 0.5 * g.h_len2, RR = roughness * LH2;
        const double B = (1.0 - 0.5 * FV) * (1.0 - 0.5 * FL) + RR * (FL + FV + FL * FV * (RR - 1.0));
        const double dg = lit ? mr_batch_mf_dg(MR_MF_GGX, alpha, &g, 0, fused) : 0.0;
        // cp_fh
        const double Fr = mr_fresnel_dielectric(g.dot_h, ior, NULL);
        const double FH = mr_clampd((Fr - F0) / (1.0 - F0), 0.0, 1.0);
        d0_[i] = lit ? d0 * B : 0.0;
        d1_[i] = lit ? d1 * B : 0.0;
        d2_[i] = lit ? d2 * B : 0.0;
        s0_[i] = (c0 * (1.0 - FH) + FH) * dg;
        s1_[i] = (c1 * (1.0 - FH) + FH) * dg;
        s2_[i] = (c2 * (1.0 - FH) + FH) * dg;
    }
}

MR_BATCH_KERNEL(cp_eval_batch, cp_batch_body)

static void cp_eval_grad(const mr_brdf_model *model, const double *values, const double wi[3],
                         const double wo[3], double *d_diffuse, double *d_specular) {
    mr_brdf_geom g;
    double v[MR_BRDF_MAX_VALUES], raw[3];
    if (!mr_brdf_grad_begin(model, values, wi, wo, d_diffuse, d_specular, &g, v)) return;
    const double *base = v + CP_BASE;
    double m = v[CP_METALLIC], s = v[CP_SPECULAR], t = v[CP_SPECULAR_TINT], rough = v[CP_ROUGHNESS];
    cp_cspec0_raw(v, raw);

    /* diffuse: base (1 - m)/pi B(roughness) */
    double dB;
    double B = cp_burley(&g, rough, &dB);
    for (int c = 0; c < 3; c++) {
        d_diffuse[(CP_BASE + c) * 3 + c] = (1.0 - m) * MR_INV_PI * B;
        d_diffuse[CP_METALLIC * 3 + c] = -base[c] * MR_INV_PI * B;
        d_diffuse[CP_ROUGHNESS * 3 + c] = base[c] * (1.0 - m) * MR_INV_PI * dB;
    }

    /* specular: F_c dg, F_c = cspec0_c (1 - FH) + FH */
    double d_dg;
    double dg = mr_mf_dg(MR_MF_GGX, rough * rough, &g, 0, &d_dg);
    double ior = cp_ior(s), F0 = mr_fresnel_dielectric(1.0, ior, NULL);
    double Fr = mr_fresnel_dielectric(g.dot_h, ior, NULL);
    double FH_raw = (Fr - F0) / (1.0 - F0);
    double FH = mr_clampd(FH_raw, 0.0, 1.0);
    /* dFH/dspecular = (dFr/dspecular - (1 - FH) dF0/dspecular)/(1 - F0), F0 = 0.08 specular exactly. The chain
     * dFr/dior dior/dspecular is 0 * inf at specular = 0 (its limit is finite): evaluate it at specular >= 1e-12. */
    double s_eff = MR_MAX(s, 1e-12), x = sqrt(0.08 * s_eff);
    double dior_ds = 2.0 / ((1.0 - x) * (1.0 - x)) * (0.04 / x);
    double dFr_ds;
    mr_fresnel_dielectric(g.dot_h, cp_ior(s_eff), &dFr_ds);
    dFr_ds *= dior_ds;
    // At a clamp's edge the derivative is the one-sided one into the range the parameters reach: FH_raw >= 0 and
    // raw >= 0 always, so at 0 (a dielectric with specular 0, a black base at metallic 0) the slope is the side
    // above it, which a fit stepping away from its bound needs (a slope of 0 there would pin it to the bound).
    double dFH_ds = (FH_raw >= 0.0 && FH_raw < 1.0) ? (dFr_ds - (1.0 - FH) * 0.08) / (1.0 - F0) : 0.0;

    double lum = 0.0;
    for (int c = 0; c < 3; c++) lum += cp_lum_weight[c] * base[c];
    for (int c = 0; c < 3; c++) {
        double cspec0 = mr_clampd(raw[c], 0.0, 1.0);
        double F = cspec0 * (1.0 - FH) + FH;
        int unsaturated = raw[c] >= 0.0 && raw[c] < 1.0; /* saturate() passes the derivative (above) */
        double k = unsaturated ? (1.0 - FH) * dg : 0.0;  /* d specular_c / d raw_c */
        double tint = lum > 0.0 ? base[c] / lum : 1.0;
        /* raw_c = 0.08 s ((1 - t) + tint_c t)(1 - m) + base_c m */
        for (int cp = 0; cp < 3; cp++) {
            double dtint = lum > 0.0 ? ((cp == c ? 1.0 : 0.0) / lum - base[c] * cp_lum_weight[cp] / (lum * lum)) : 0.0;
            double draw = 0.08 * s * t * dtint * (1.0 - m) + (cp == c ? m : 0.0);
            d_specular[(CP_BASE + cp) * 3 + c] = k * draw;
        }
        d_specular[CP_METALLIC * 3 + c] = k * (base[c] - 0.08 * s * ((1.0 - t) + tint * t));
        d_specular[CP_SPECULAR * 3 + c] = k * 0.08 * ((1.0 - t) + tint * t) * (1.0 - m) + (1.0 - cspec0) * dFH_ds * dg;
        d_specular[CP_SPECULAR_TINT * 3 + c] = k * 0.08 * s * (tint - 1.0) * (1.0 - m);
        d_specular[CP_ROUGHNESS * 3 + c] = F * d_dg * 2.0 * rough;
    }
}

const mr_brdf_model mr_brdf_cycles_principled = {
    .name = "cycles-principled",
    .summary = "Blender 3.4 Cycles Principled BSDF v1: single-scatter GGX + PRINCIPLED_V1 Fresnel + Burley diffuse",
    .source = "Blender 3.4 intern/cycles/kernel/svm/closure.h, closure/bsdf_microfacet.h, bsdf_principled_diffuse.h",
    .param_count = (int)(sizeof cp_params / sizeof cp_params[0]),
    .params = cp_params,
    .flags = MR_BRDF_NOT_ENERGY_CONSERVING,
    .config = NULL,
    .prepare = cp_prepare,
    .eval = cp_eval,
    .eval_batch = cp_eval_batch,
    .eval_grad = cp_eval_grad,
};
