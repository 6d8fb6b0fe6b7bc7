/*
 * phong.c — `phong`: the modified (energy-normalised) Phong BRDF of Lafortune & Willems 1994 plus a Lambert
 * base, as Mitsuba 0.6 implements it; isotropic.
 *
 *   f_r = rho_s (n + 2)/(2 pi) max(0, wo.r)^n + rho_d / pi,    r = (-wi_x, -wi_y, wi_z) (mirror of wi)
 *
 * wo.r = wi_z wo_z - wi_x wo_x - wi_y wo_y is symmetric in (wi, wo), so f_r is reciprocal. Zero unless both
 * cosines are > 0.
 *
 * Parameters:
 *   diffuse   RGB  [0, 1]      default 0.5   rho_d (Mitsuba diffuseReflectance)
 *   specular  RGB  [0, 10]     default 0.2   rho_s (Mitsuba specularReflectance); values above 1 are legal in
 *                                            Mitsuba and trimmed (below); 10 bounds the search
 *   exponent       [1, 10000]  default 30    Phong exponent n (Mitsuba exponent), log scale. Mitsuba accepts
 *                                            any n >= 0; 1 keeps the log scale defined, 10000 is a near-mirror.
 *   trim      switch {0, 1}    default 1     Mitsuba's ensureEnergyConservation, as in ward.c: if
 *                                            m = max over channels of (rho_d + rho_s) > 1, both are scaled by
 *                                            0.99/m. The LINEAR roles and the lobes are exact for trim = 0 or
 *                                            m <= 1 only.
 *
 * Source: Mitsuba 0.6 src/bsdfs/phong.cpp and src/librender/bsdf.cpp (brdf-reference 2.2).
 * Limitations: the lobe is centred on the mirror direction, not on the normal, so it is not a microfacet model;
 * it has no Fresnel term.
 * Energy: the (n+2)/(2 pi) normalisation makes the specular albedo exactly rho_s at normal incidence and less
 * elsewhere (the lobe is clipped by the horizon); with trimming the total stays below 1.
 * Gradient: analytic for every parameter, including through trimming (one-sided where m = 1 or where two
 * channels tie for m).
 */
#include "brdf_batch.h"

/* Slots of the packed value vector. */
enum { PHONG_DIFFUSE = 0, PHONG_SPECULAR = 3, PHONG_EXPONENT = 6, PHONG_TRIM = 7 };

static const mr_brdf_param phong_params[] = {
    {"diffuse", 3, 0.5, 0.0, 1.0, MR_PARAM_LINEAR, MR_LOBE_DIFFUSE, MR_PARAM_SRGB_MAP,
     "diffuse reflectance rho_d, linear RGB (Mitsuba diffuseReflectance); linear only while not trimmed", NULL},
    {"specular", 3, 0.2, 0.0, 10.0, MR_PARAM_LINEAR, MR_LOBE_SPECULAR, MR_PARAM_SRGB_MAP,
     "specular reflectance rho_s, linear RGB (Mitsuba specularReflectance); linear only while not trimmed", NULL},
    {"exponent", 1, 30.0, 1.0, 10000.0, MR_PARAM_NONLINEAR, MR_LOBE_SPECULAR, MR_PARAM_LOG_SCALE,
     "Phong exponent n of max(0, wo.r)^n, with (n+2)/(2 pi) normalisation", NULL},
    {"trim", 1, 1.0, 0.0, 1.0, MR_PARAM_SWITCH, MR_LOBE_BOTH, 0,
     "1: Mitsuba's energy trimming, rho_d and rho_s scaled by 0.99/max(rho_d + rho_s) when that exceeds 1", NULL},
};

typedef struct phong_state {
    double exponent;
    double diffuse_over_pi[3]; /* trimmed rho_d / pi */
    double specular[3];        /* trimmed rho_s */
} phong_state;

_Static_assert(sizeof(phong_state) <= MR_BRDF_STATE_BYTES, "phong_state must fit in MR_BRDF_STATE_BYTES");

/* The specular factor S = (n+2)/(2 pi) max(0, wo.r)^n (f_s = rho_s S), with dS/dn. */
static double phong_lobe(double n, const double wi[3], const double wo[3], const mr_brdf_geom *g,
                         double *d_dn) {
    double cos_r = g->cos_i * g->cos_o - wi[0] * wo[0] - wi[1] * wo[1];
    if (!(cos_r > 0.0)) {
        if (d_dn) *d_dn = 0.0;
        return 0.0;
    }
    double p = pow(MR_MIN(cos_r, 1.0), n);
    double S = (n + 2.0) * (0.5 * MR_INV_PI) * p;
    if (d_dn) *d_dn = p * (0.5 * MR_INV_PI) + S * log(MR_MIN(cos_r, 1.0));
    return S;
}

static void phong_prepare(const mr_brdf_model *model, const double *values, void *state_bytes) {
    phong_state *state = state_bytes;
    double v[MR_BRDF_MAX_VALUES];
    mr_brdf_clamp_values(model, values, v);
    mr_brdf_trim trim = mr_brdf_trim_compute(v + PHONG_DIFFUSE, v + PHONG_SPECULAR, v[PHONG_TRIM] >= 0.5);
    state->exponent = v[PHONG_EXPONENT];
    for (int c = 0; c < 3; c++) {
        state->diffuse_over_pi[c] = trim.scale * v[PHONG_DIFFUSE + c] * MR_INV_PI;
        state->specular[c] = trim.scale * v[PHONG_SPECULAR + c];
    }
}

static void phong_eval(const void *state_bytes, const double wi[3], const double wo[3], double diffuse[3],
                       double specular[3]) {
    const phong_state *state = state_bytes;
    mr_brdf_geom g;
    if (!mr_brdf_geom_init(wi, wo, &g)) {
        mr_brdf_zero(diffuse, specular);
        return;
    }
    double S = specular ? phong_lobe(state->exponent, wi, wo, &g, NULL) : 0.0;
    for (int c = 0; c < 3; c++) {
        if (diffuse) diffuse[c] = state->diffuse_over_pi[c];
        if (specular) specular[c] = state->specular[c] * S;
    }
}

/* eval over a batch (brdf.h eval_batch): phong_lobe's operations with mr_batch_pow for pow. The base of the power
 * is kept at least 1e-300 (mr_batch_log takes normal numbers); below it pow's value is 0 or, for n = 0, 1 either
 * way. */
MR_BATCH_INLINE void phong_batch_body(const void *state_bytes, const mr_brdf_batch *batch, const int fused) {
    const phong_state *state = state_bytes;
    const double n = state->exponent;
    const double d0 = state->diffuse_over_pi[0], d1 = state->diffuse_over_pi[1], d2 = state->diffuse_over_pi[2];
    const double r0 = state->specular[0], r1 = state->specular[1], r2 = state->specular[2];
    MR_BATCH_ARRAYS(batch);
#pragma omp simd
    for (int i = 0; i < n_; i++) {
        mr_brdf_geom g;
        const int lit = mr_batch_geom(ix_[i], iy_[i], iz_[i], ox_[i], oy_[i], oz_[i], &g);
        const double cos_r = g.cos_i * g.cos_o - ix_[i] * ox_[i] - iy_[i] * oy_[i];
        const double base = cos_r > 1e-300 ? MR_MIN(cos_r, 1.0) : 1e-300;
        const double lobe = (n + 2.0) * (0.5 * MR_INV_PI) * mr_batch_pow(base, n, fused);
        const double S = (lit & (cos_r > 0.0)) ? lobe : 0.0;
        d0_[i] = lit ? d0 : 0.0;
        d1_[i] = lit ? d1 : 0.0;
        d2_[i] = lit ? d2 : 0.0;
        s0_[i] = r0 * S;
        s1_[i] = r1 * S;
        s2_[i] = r2 * S;
    }
}

MR_BATCH_KERNEL(phong_eval_batch, phong_batch_body)

static void phong_eval_grad(const mr_brdf_model *model, const double *values, const double wi[3],
                            const double wo[3], double *d_diffuse, double *d_specular) {
    mr_brdf_geom g;
    double v[MR_BRDF_MAX_VALUES];
    if (!mr_brdf_grad_begin(model, values, wi, wo, d_diffuse, d_specular, &g, v)) return;
    const double *rho_d = v + PHONG_DIFFUSE, *rho_s = v + PHONG_SPECULAR;
    mr_brdf_trim trim = mr_brdf_trim_compute(rho_d, rho_s, v[PHONG_TRIM] >= 0.5);
    double dS;
    double S = phong_lobe(v[PHONG_EXPONENT], wi, wo, &g, &dS);
    mr_brdf_trim_grad(&trim, rho_d, rho_s, S, PHONG_DIFFUSE, PHONG_SPECULAR, d_diffuse, d_specular);
    for (int c = 0; c < 3; c++) d_specular[PHONG_EXPONENT * 3 + c] = trim.scale * rho_s[c] * dS;
}

/* Mitsuba trims at these values (brdf.h, rescales). */
static int phong_rescales(const mr_brdf_model *model, const double *values) {
    return mr_brdf_trim_engaged(model, values, PHONG_DIFFUSE, PHONG_SPECULAR, PHONG_TRIM);
}

const mr_brdf_model mr_brdf_phong = {
    .name = "phong",
    .summary = "modified Phong (Lafortune) + Lambert, Mitsuba's energy trimming",
    .source = "Mitsuba 0.6 phong.cpp + bsdf.cpp ensureEnergyConservation",
    .param_count = (int)(sizeof phong_params / sizeof phong_params[0]),
    .params = phong_params,
    .flags = 0,
    .config = NULL,
    .prepare = phong_prepare,
    .eval = phong_eval,
    .eval_batch = phong_eval_batch,
    .eval_grad = phong_eval_grad,
    .rescales = phong_rescales,
};
