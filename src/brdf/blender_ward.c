/*
 * blender_ward.c — `blender-ward`: Blender Internal 2.7x's "WardIso" specular shader plus its Lambert diffuse
 * shader, as f_r; isotropic.
 *
 *   f_s = specular exp(-tan^2(acos(n.h)) / alpha^2) / (4 pi alpha^2 sqrt(n.v n.l)),   alpha = max(rms, 0.001)
 *   f_d = diffuse                                                     (no 1/pi: Blender Internal has none)
 *
 * BI's WardIso_Spec() returns n.l / (4 pi alpha^2) exp(...) / sqrt(n.v n.l), i.e. the value already includes
 * the n.l cosine, and the pixel adds `spec * specfac * lamp` to it; as an f_r (brdf.h: radiance =
 * f_r I cos(theta_l)/d^2) that is WardIso/n.l. Its Lambert shader adds (n.l) refl * colour * lamp, so f_d is
 * refl * colour, pi times brighter than a physical Lambert of the same albedo. This is Ward's 1992 form with a
 * normalised h (tan^2 does not depend on the scale of H) and without Mitsuba's 1e-10 cut-off.
 *
 * Parameters:
 *   diffuse   RGB  [0, 1]        default 0.64  material colour x diffuse intensity `refl` (BI defaults 0.8 x 0.8)
 *   specular  RGB  [0, 1]        default 0.5   specular colour x specular intensity `spec` (BI: (1,1,1) x 0.5)
 *   rms            [0.001, 0.4]  default 0.1   BI's "slope" (RNA specular_slope, UI range [0, 0.4]); BI floors it
 *                                              at 0.001 itself, which is the minimum here. Log scale.
 *
 * Cosine clamps: WardIso_Spec() replaces n.h, n.v, n.l <= 0 by 0.001, so by itself it returns a value below the
 * horizon too; we return 0 there as brdf.h requires. Above the horizon n.h > 0 always, so BI's n.h clamp only
 * guards the tan(acos(n.h)) division, as here.
 * Lamp falloff: BI's default point-lamp falloff is D/(D + d^2) (D = lamp distance 25), not 1/d^2. That is a lamp
 * property, not part of the BRDF: a remap matches it by irradiance matching (the ratio of diffuse-only renders),
 * as the paper does.
 *
 * Source: Blender 2.7x source/blender/render/intern/source/shadeoutput.c, WardIso_Spec() and shade_one_light()
 * (brdf-reference 3). BI evaluates in float; we use double.
 * Limitations: BI's tangent-shading mode (dot products replaced by sqrt(1 - x^2)) is not modelled.
 * Energy: flagged MR_BRDF_NOT_ENERGY_CONSERVING. The diffuse albedo is pi * diffuse (up to pi), and the Ward 1992
 * normalisation 1/sqrt(n.v n.l) diverges at the horizon (see ward.c: above 1 within a few tenths of a degree of
 * grazing for rms >= 0.4).
 * Gradient: analytic for every parameter.
 */
#include "brdf_batch.h"

/* Slots of the packed value vector. */
enum { BW_DIFFUSE = 0, BW_SPECULAR = 3, BW_RMS = 6 };

/* BI's floor of alpha (WardIso_Spec: alpha = MAX2(rms, 0.001f)); also the parameter's minimum. */
#define BW_ALPHA_MIN 0.001

static const mr_brdf_param blender_ward_params[] = {
    {"diffuse", 3, 0.64, 0.0, 1.0, MR_PARAM_LINEAR, MR_LOBE_DIFFUSE, MR_PARAM_SRGB_MAP,
     "BI material colour x diffuse intensity, linear RGB; f_d = diffuse (BI has no 1/pi)", NULL},
    {"specular", 3, 0.5, 0.0, 1.0, MR_PARAM_LINEAR, MR_LOBE_SPECULAR, MR_PARAM_SRGB_MAP,
     "BI specular colour x specular intensity, linear RGB", NULL},
    {"rms", 1, 0.1, BW_ALPHA_MIN, 0.4, MR_PARAM_NONLINEAR, MR_LOBE_SPECULAR, MR_PARAM_LOG_SCALE,
     "BI WardIso slope (RNA specular_slope), the Ward alpha", NULL},
};

typedef struct blender_ward_state {
    double alpha;
    double diffuse[3];
    double specular[3];
} blender_ward_state;

_Static_assert(sizeof(blender_ward_state) <= MR_BRDF_STATE_BYTES, "blender_ward_state must fit");

/* WardIso_Spec / n.l (the f_s of specular = 1), with its alpha derivative if d_dalpha. */
static double blender_ward_lobe(double alpha, const mr_brdf_geom *g, double *d_dalpha) {
    double nh = g->cos_h > 0.0 ? g->cos_h : 0.001; /* BI's clamp, see the header */
    double tan2 = MR_MAX(1.0 - nh * nh, 0.0) / (nh * nh);
    double a2 = alpha * alpha;
    double S = exp(-tan2 / a2) / (4.0 * MR_PI * a2 * sqrt(g->cos_o * g->cos_i));
    if (d_dalpha) *d_dalpha = S * (2.0 * tan2 / (a2 * alpha) - 2.0 / alpha);
    return S;
}

static void blender_ward_prepare(const mr_brdf_model *model, const double *values, void *state_bytes) {
    blender_ward_state *state = state_bytes;
    double v[MR_BRDF_MAX_VALUES];
    mr_brdf_clamp_values(model, values, v);
    state->alpha = MR_MAX(v[BW_RMS], BW_ALPHA_MIN);
    for (int c = 0; c < 3; c++) {
        state->diffuse[c] = v[BW_DIFFUSE + c];
        state->specular[c] = v[BW_SPECULAR + c];
    }
}

static void blender_ward_eval(const void *state_bytes, const double wi[3], const double wo[3], double diffuse[3],
                              double specular[3]) {
    const blender_ward_state *state = state_bytes;
    mr_brdf_geom g;
    if (!mr_brdf_geom_init(wi, wo, &g)) {
        mr_brdf_zero(diffuse, specular);
        return;
    }
    double S = specular ? blender_ward_lobe(state->alpha, &g, NULL) : 0.0;
    for (int c = 0; c < 3; c++) {
        if (diffuse) diffuse[c] = state->diffuse[c];
        if (specular) specular[c] = state->specular[c] * S;
    }
}

/* eval over a batch (brdf.h eval_batch): blender_ward_lobe's operations with mr_batch_exp for exp. */
MR_BATCH_INLINE void blender_ward_batch_body(const void *state_bytes, const mr_brdf_batch *batch, const int fused) {
    const blender_ward_state *state = state_bytes;
    const double alpha = state->alpha, a2 = alpha * alpha;
    const double d0 = state->diffuse[0], d1 = state->diffuse[1], d2 = state->diffuse[2];
    const double r0 = state->specular[0], r1 = state->specular[1], r2 = state->specular[2];
    MR_BATCH_ARRAYS(batch);
#pragma omp simd
    for (int i = 0; i < n_; i++) {
        mr_brdf_geom g;
        const int lit = mr_batch_geom(ix_[i], iy_[i], iz_[i], ox_[i], oy_[i], oz_[i], &g);
        const double nh = g.cos_h > 0.0 ? g.cos_h : 0.001;
        const double tan2 = MR_MAX(1.0 - nh * nh, 0.0) / (nh * nh);
        const double lobe = mr_batch_exp(-tan2 / a2, fused) / (4.0 * MR_PI * a2 * sqrt(g.cos_o * g.cos_i));
        const double S = lit ? lobe : 0.0;
        d0_[i] = lit ? d0 : 0.0;
        d1_[i] = lit ? d1 : 0.0;
        d2_[i] = lit ? d2 : 0.0;
        s0_[i] = r0 * S;
        s1_[i] = r1 * S;
        s2_[i] = r2 * S;
    }
}

MR_BATCH_KERNEL(blender_ward_eval_batch, blender_ward_batch_body)

static void blender_ward_eval_grad(const mr_brdf_model *model, const double *values, const double wi[3],
                                   const double wo[3], double *d_diffuse, double *d_specular) {
    mr_brdf_geom g;
    double v[MR_BRDF_MAX_VALUES];
    if (!mr_brdf_grad_begin(model, values, wi, wo, d_diffuse, d_specular, &g, v)) return;
    double dS;
    double S = blender_ward_lobe(MR_MAX(v[BW_RMS], BW_ALPHA_MIN), &g, &dS);
    for (int c = 0; c < 3; c++) {
        d_diffuse[(BW_DIFFUSE + c) * 3 + c] = 1.0;
        d_specular[(BW_SPECULAR + c) * 3 + c] = S;
        d_specular[BW_RMS * 3 + c] = v[BW_SPECULAR + c] * dS;
    }
}

/* Prepared derivatives (brdf.h, grad_ops): the rms slope alone, which the fits' projection asks for, as
 * blender_ward_eval_grad computes it; any other slots by blender_ward_eval_grad itself. */
static void blender_ward_grad_prepare(const mr_brdf_model *model, const double *values, const int *slots, int count,
                                      void *state) {
    mr_brdf_grad_slots_prepare(model, values, slots, count, BW_RMS, state);
}

static void blender_ward_grad_eval(const void *state, const double wi[3], const double wo[3], double *d_diffuse,
                                   double *d_specular) {
    const mr_brdf_grad_slots *st = state;
    if (!st->shape_only) {
        mr_brdf_grad_slots_eval(st, wi, wo, d_diffuse, d_specular);
        return;
    }
    mr_brdf_geom g;
    double dS = 0.0;
    if (mr_brdf_geom_init(wi, wo, &g)) blender_ward_lobe(MR_MAX(st->v[BW_RMS], BW_ALPHA_MIN), &g, &dS);
    for (int c = 0; c < 3; c++) {
        d_diffuse[c] = 0.0;
        d_specular[c] = st->v[BW_SPECULAR + c] * dS;
    }
}

static const mr_brdf_grad_ops blender_ward_grad_ops = {sizeof(mr_brdf_grad_slots), blender_ward_grad_prepare,
                                                       blender_ward_grad_eval, NULL, NULL};

const mr_brdf_model mr_brdf_blender_ward = {
    .name = "blender-ward",
    .summary = "Blender Internal 2.7x WardIso specular + Lambert diffuse (no 1/pi)",
    .source = "Blender 2.7x render/intern/source/shadeoutput.c WardIso_Spec, shade_one_light",
    .param_count = (int)(sizeof blender_ward_params / sizeof blender_ward_params[0]),
    .params = blender_ward_params,
    .flags = MR_BRDF_NOT_ENERGY_CONSERVING,
    .config = NULL,
    .prepare = blender_ward_prepare,
    .eval = blender_ward_eval,
    .eval_batch = blender_ward_eval_batch,
    .eval_grad = blender_ward_eval_grad,
    .grad_ops = &blender_ward_grad_ops,
};
