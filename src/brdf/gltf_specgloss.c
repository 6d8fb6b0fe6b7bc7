/*
 * gltf_specgloss.c — `gltf-specgloss`: glTF 2.0's KHR_materials_pbrSpecularGlossiness material (archived,
 * superseded by KHR_materials_specular); isotropic.
 *
 *   c_diff = diffuse (1 - max_c specular_c),  F0 = specular,  alpha = (1 - glossiness)^2
 *   F_c = F0_c + (1 - F0_c)(1 - |wi.h|)^5                                                       (Schlick)
 *   f_c = (1 - F_c) c_diff_c / pi + F_c D V
 * with the same GGX D and height-correlated Smith V as the core metallic-roughness material (see gltf.c).
 * Split: diffuse part = (1 - F_c) c_diff_c / pi; specular part = F_c D V.
 *
 * Parameters (defaults are the extension's):
 *   diffuse     RGB  [0, 1]  default 1   diffuseFactor (RGB of the RGBA factor; alpha is coverage, not BRDF)
 *   specular    RGB  [0, 1]  default 1   specularFactor: F0. NONLINEAR: it scales the diffuse lobe by
 *                                        (1 - max specular)(1 - F), a product of two terms in it.
 *   glossiness       [0, 1]  default 1   glossinessFactor; alpha = (1 - glossiness)^2, floored at 1e-4 (Mitsuba's
 *                                        floor; the glossy end glossiness > 0.99 is therefore flat). Not log
 *                                        scale: the sensitive end is glossiness -> 1.
 *
 * Source: KhronosGroup/glTF extensions/2.0/Archived/KHR_materials_pbrSpecularGlossiness/README.md, with the
 * BRDF of Specification.adoc Appendix B (brdf-reference 5.1, 5.2).
 * Limitations: textures are handled outside the model (these are the per-texel factors).
 * Energy: flagged MR_BRDF_NOT_ENERGY_CONSERVING, for the reason given in gltf.c: (1 - F(v.h)) per pair of directions
 * lets a smooth surface with a weak F0 reflect more than it receives near grazing incidence (specular 0,
 * glossiness 1, diffuse 1: albedo 1.00 at normal incidence, 1.37 at 80 degrees, 1.81 at 88 degrees).
 * Gradient: analytic for every parameter (one-sided where two specular channels tie for the maximum, and 0 in
 * the flat glossiness > 0.99 band).
 */
#include "brdf_batch.h"

/* Slots of the packed value vector. */
enum { SG_DIFFUSE = 0, SG_SPECULAR = 3, SG_GLOSSINESS = 6 };

/* alpha floor (Mitsuba's 1e-4): glossiness above 1 - sqrt(1e-4) = 0.99 gives this alpha. */
#define SG_ALPHA_MIN 1e-4

static const mr_brdf_param specgloss_params[] = {
    {"diffuse", 3, 1.0, 0.0, 1.0, MR_PARAM_LINEAR, MR_LOBE_DIFFUSE, MR_PARAM_SRGB_MAP,
     "diffuseFactor, linear RGB", NULL},
    {"specular", 3, 1.0, 0.0, 1.0, MR_PARAM_NONLINEAR, MR_LOBE_BOTH, MR_PARAM_SRGB_MAP,
     "specularFactor = Schlick F0, linear RGB; also dims diffuse by (1 - max specular)", NULL},
    {"glossiness", 1, 1.0, 0.0, 1.0, MR_PARAM_NONLINEAR, MR_LOBE_SPECULAR, 0,
     "glossinessFactor; GGX alpha = (1 - glossiness)^2, floored at 1e-4", NULL},
};

typedef struct specgloss_state {
    double alpha;
    double c_diff_over_pi[3]; /* diffuse (1 - max specular) / pi */
    double f0[3];
} specgloss_state;

_Static_assert(sizeof(specgloss_state) <= MR_BRDF_STATE_BYTES, "specgloss_state must fit");

static int specgloss_argmax(const double *x) {
    int best = 0;
    for (int c = 1; c < 3; c++)
        if (x[c] > x[best]) best = c;
    return best;
}

static void specgloss_prepare(const mr_brdf_model *model, const double *values, void *state_bytes) {
    specgloss_state *state = state_bytes;
    double v[MR_BRDF_MAX_VALUES];
    mr_brdf_clamp_values(model, values, v);
    double rough = 1.0 - v[SG_GLOSSINESS];
    double smax = v[SG_SPECULAR + specgloss_argmax(v + SG_SPECULAR)];
    state->alpha = MR_MAX(rough * rough, SG_ALPHA_MIN);
    for (int c = 0; c < 3; c++) {
        state->c_diff_over_pi[c] = v[SG_DIFFUSE + c] * (1.0 - smax) * MR_INV_PI;
        state->f0[c] = v[SG_SPECULAR + c];
    }
}

static void specgloss_eval(const void *state_bytes, const double wi[3], const double wo[3], double diffuse[3],
                           double specular[3]) {
    const specgloss_state *state = state_bytes;
    mr_brdf_geom g;
    if (!mr_brdf_geom_init(wi, wo, &g)) {
        mr_brdf_zero(diffuse, specular);
        return;
    }
    double w = mr_schlick_weight(g.dot_h);
    double S = 0.0;
    if (specular)
        S = mr_ggx_dv_correlated(state->alpha, &g, NULL);
    for (int c = 0; c < 3; c++) {
        double F = state->f0[c] + (1.0 - state->f0[c]) * w;
        if (diffuse) diffuse[c] = (1.0 - F) * state->c_diff_over_pi[c];
        if (specular) specular[c] = F * S;
    }
}

/* eval over a batch (brdf.h eval_batch): specgloss_eval's operations. */
MR_BATCH_INLINE void specgloss_batch_body(const void *state_bytes, const mr_brdf_batch *batch, const int fused) {
    (void)fused; // no exp or pow here
    const specgloss_state *state = state_bytes;
    const double alpha = state->alpha;
    const double c0 = state->c_diff_over_pi[0], c1 = state->c_diff_over_pi[1], c2 = state->c_diff_over_pi[2];
    const double f0 = state->f0[0], f1 = state->f0[1], f2 = state->f0[2];
    MR_BATCH_ARRAYS(batch);
#pragma omp simd
    for (int i = 0; i < n_; i++) {
        mr_brdf_geom g;
        const int lit = mr_batch_geom(ix_[i], iy_[i], iz_[i], ox_[i], oy_[i], oz_[i], &g);
        const double w = mr_schlick_weight(g.dot_h);
        const double S = lit ? mr_batch_ggx_dv_correlated(alpha, &g) : 0.0;
        const double F0 = f0 + (1.0 - f0) * w, F1 = f1 + (1.0 - f1) * w, F2 = f2 + (1.0 - f2) * w;
        d0_[i] = lit ? (1.0 - F0) * c0 : 0.0;
        d1_[i] = lit ? (1.0 - F1) * c1 : 0.0;
        d2_[i] = lit ? (1.0 - F2) * c2 : 0.0;
        s0_[i] = F0 * S;
        s1_[i] = F1 * S;
        s2_[i] = F2 * S;
    }
}

MR_BATCH_KERNEL(specgloss_eval_batch, specgloss_batch_body)

static void specgloss_eval_grad(const mr_brdf_model *model, const double *values, const double wi[3],
                                const double wo[3], double *d_diffuse, double *d_specular) {
    mr_brdf_geom g;
    double v[MR_BRDF_MAX_VALUES];
    if (!mr_brdf_grad_begin(model, values, wi, wo, d_diffuse, d_specular, &g, v)) return;
    const double *dif = v + SG_DIFFUSE, *f0 = v + SG_SPECULAR;
    double rough = 1.0 - v[SG_GLOSSINESS];
    int floored = rough * rough <= SG_ALPHA_MIN;
    double alpha = floored ? SG_ALPHA_MIN : rough * rough;
    double dS_dalpha;
    double S = mr_ggx_dv_correlated(alpha, &g, &dS_dalpha);
    /* dalpha/dglossiness = -2 (1 - glossiness), 0 on the floor */
    double dS_dgloss = floored ? 0.0 : dS_dalpha * -2.0 * rough;
    double w = mr_schlick_weight(g.dot_h);
    int cmax = specgloss_argmax(f0);
    double smax = f0[cmax];
    for (int c = 0; c < 3; c++) {
        double F = f0[c] + (1.0 - f0[c]) * w;
        d_diffuse[(SG_DIFFUSE + c) * 3 + c] = (1.0 - F) * (1.0 - smax) * MR_INV_PI;
        /* diffuse_c = (1 - F_c) dif_c (1 - smax)/pi: F_c through specular_c, smax through specular_cmax */
        d_diffuse[(SG_SPECULAR + c) * 3 + c] += -(1.0 - w) * dif[c] * (1.0 - smax) * MR_INV_PI;
        d_diffuse[(SG_SPECULAR + cmax) * 3 + c] += -(1.0 - F) * dif[c] * MR_INV_PI;
        d_specular[(SG_SPECULAR + c) * 3 + c] = (1.0 - w) * S;
        d_specular[SG_GLOSSINESS * 3 + c] = F * dS_dgloss;
    }
}

const mr_brdf_model mr_brdf_gltf_specgloss = {
    .name = "gltf-specgloss",
    .summary = "glTF KHR_materials_pbrSpecularGlossiness (Schlick F0 = specular, GGX, height-correlated Smith)",
    .source = "glTF KHR_materials_pbrSpecularGlossiness README + Specification.adoc Appendix B",
    .param_count = (int)(sizeof specgloss_params / sizeof specgloss_params[0]),
    .params = specgloss_params,
    .flags = MR_BRDF_NOT_ENERGY_CONSERVING,
    .config = NULL,
    .prepare = specgloss_prepare,
    .eval = specgloss_eval,
    .eval_batch = specgloss_eval_batch,
    .eval_grad = specgloss_eval_grad,
};
