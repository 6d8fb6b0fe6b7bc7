/*
 * ggx_metallic.c — `ggx-metallic`: the paper's metallic workflow over the `ggx` model (Sztrajman et al. 2019,
 * section 8, Eq. 2): a GGX microfacet lobe with Mitsuba's separable Smith G and a Schlick Fresnel, plus a
 * Lambert base, parameterised by albedo and metallic instead of diffuse and specular colours. Isotropic.
 *
 *   diffuse colour  d_c = albedo_c (1 - metallic)
 *   specular (F0)   s_c = f0_dielectric (1 - metallic) + metallic albedo_c          (paper Eq. 2)
 *   f = d_c / pi  +  (s_c + (1 - s_c)(1 - wi.h)^5) D G1(wi) G1(wo) / (4 cos_i cos_o)
 *
 * It is `ggx` (diffuse = d, f0 = s) exactly, so remapping ggx-metallic -> ggx recovers Eq. 2 and the reverse
 * remap, ggx -> ggx-metallic, is the inverse workflow conversion the paper trains its regressor on; materials
 * off the metallic manifold (a coloured dielectric F0, say) get the visually closest metallic approximation.
 *
 * Parameters:
 *   albedo          RGB [0, 1]       default 0.8   base colour, linear RGB. AFFINE: d is linear and s affine
 *                                                  in it for a fixed metallic.
 *   metallic             [0, 1]      default 0     metalness; bilinear with albedo, so NONLINEAR (searched).
 *   alpha                [1e-4, 1]   default 0.1   GGX roughness (Mitsuba's alpha, floored at 1e-4), log scale.
 *   dielectric_f0        [0, 0.2]    default 0.04  the non-metal F0 of Eq. 2: 0.04 is glTF's (ior 1.5), 0.03
 *                                                  the paper's. Held fixed by fits (a convention, not a look).
 *
 * Source: the paper's Eq. 2; GGX D and Smith G1 of Mitsuba 0.6 microfacet.h (brdf-reference 2.3), Schlick
 * Fresnel with F0 as in the authors' "pbr" plugin (brdf-reference 1).
 * Energy: each lobe conserves energy as `ggx`'s do; their sum can exceed 1 for a white albedo (the Lambert base
 * is not dimmed by the Fresnel term), so the model carries MR_BRDF_INDEPENDENT_LOBES like `ggx`.
 * Gradient: analytic for every parameter.
 */
#include "brdf_batch.h"

enum { GM_ALBEDO = 0, GM_METALLIC = 3, GM_ALPHA = 4, GM_F0D = 5 };

static const mr_brdf_param ggx_metallic_params[] = {
    {"albedo", 3, 0.8, 0.0, 1.0, MR_PARAM_AFFINE, MR_LOBE_BOTH, MR_PARAM_SRGB_MAP,
     "base colour, linear RGB: diffuse = albedo (1 - metallic), F0 = f0d (1 - metallic) + metallic albedo", NULL},
    {"metallic", 1, 0.0, 0.0, 1.0, MR_PARAM_NONLINEAR, MR_LOBE_BOTH, 0, "metalness (paper Eq. 2)", NULL},
    {"alpha", 1, 0.1, 1e-4, 1.0, MR_PARAM_NONLINEAR, MR_LOBE_SPECULAR, MR_PARAM_LOG_SCALE,
     "GGX roughness alpha (Mitsuba's, isotropic); floored at 1e-4", NULL},
    {"dielectric_f0", 1, 0.04, 0.0, 0.2, MR_PARAM_AFFINE, MR_LOBE_SPECULAR, MR_PARAM_FIT_FIXED,
     "F0 of non-metals in Eq. 2: 0.04 (glTF) or 0.03 (the paper); held fixed by fits", NULL},
};

typedef struct gm_state {
    double alpha;
    double diffuse_over_pi[3];
    double f0[3];
} gm_state;

_Static_assert(sizeof(gm_state) <= MR_BRDF_STATE_BYTES, "gm_state must fit in MR_BRDF_STATE_BYTES");

static void gm_prepare(const mr_brdf_model *model, const double *values, void *state_bytes) {
    gm_state *state = state_bytes;
    double v[MR_BRDF_MAX_VALUES];
    mr_brdf_clamp_values(model, values, v);
    double m = v[GM_METALLIC];
    state->alpha = v[GM_ALPHA];
    for (int c = 0; c < 3; c++) {
        state->diffuse_over_pi[c] = v[GM_ALBEDO + c] * (1.0 - m) * MR_INV_PI;
        state->f0[c] = v[GM_F0D] * (1.0 - m) + m * v[GM_ALBEDO + c];
    }
}

static void gm_eval(const void *state_bytes, const double wi[3], const double wo[3], double diffuse[3],
                    double specular[3]) {
    const gm_state *state = state_bytes;
    mr_brdf_geom g;
    if (!mr_brdf_geom_init(wi, wo, &g)) {
        mr_brdf_zero(diffuse, specular);
        return;
    }
    if (diffuse)
        for (int c = 0; c < 3; c++) diffuse[c] = state->diffuse_over_pi[c];
    if (specular) {
        double dg = mr_mf_dg(MR_MF_GGX, state->alpha, &g, 1, NULL);
        double w = mr_schlick_weight(g.dot_h);
        for (int c = 0; c < 3; c++) specular[c] = (state->f0[c] + (1.0 - state->f0[c]) * w) * dg;
    }
}

/* eval over a batch (brdf.h eval_batch): gm_eval's operations. */
MR_BATCH_INLINE void gm_batch_body(const void *state_bytes, const mr_brdf_batch *batch, const int fused) {
    const gm_state *state = state_bytes;
    const double alpha = state->alpha;
    const double d0 = state->diffuse_over_pi[0], d1 = state->diffuse_over_pi[1], d2 = state->diffuse_over_pi[2];
    const double f0 = state->f0[0], f1 = state->f0[1], f2 = state->f0[2];
    MR_BATCH_ARRAYS(batch);
#pragma omp simd
    for (int i = 0; i < n_; i++) {
        mr_brdf_geom g;
        const int lit = mr_batch_geom(ix_[i], iy_[i], iz_[i], ox_[i], oy_[i], oz_[i], &g);
        const double dg = lit ? mr_batch_mf_dg(MR_MF_GGX, alpha, &g, 1, fused) : 0.0;
        const double w = mr_schlick_weight(g.dot_h);
        d0_[i] = lit ? d0 : 0.0;
        d1_[i] = lit ? d1 : 0.0;
        d2_[i] = lit ? d2 : 0.0;
        s0_[i] = (f0 + (1.0 - f0) * w) * dg;
        s1_[i] = (f1 + (1.0 - f1) * w) * dg;
        s2_[i] = (f2 + (1.0 - f2) * w) * dg;
    }
}

MR_BATCH_KERNEL(gm_eval_batch, gm_batch_body)

static void gm_eval_grad(const mr_brdf_model *model, const double *values, const double wi[3], const double wo[3],
                         double *d_diffuse, double *d_specular) {
    mr_brdf_geom g;
    double v[MR_BRDF_MAX_VALUES];
    if (!mr_brdf_grad_begin(model, values, wi, wo, d_diffuse, d_specular, &g, v)) return;
    double m = v[GM_METALLIC], f0d = v[GM_F0D], d_dg;
    double dg = mr_mf_dg(MR_MF_GGX, v[GM_ALPHA], &g, 1, &d_dg);
    double w = mr_schlick_weight(g.dot_h);
    for (int c = 0; c < 3; c++) {
        double albedo = v[GM_ALBEDO + c];
        double f0 = f0d * (1.0 - m) + m * albedo;
        /* specular_c = (f0 + (1 - f0) w) dg, so d/df0 = (1 - w) dg */
        double d_f0 = (1.0 - w) * dg;
        d_diffuse[(GM_ALBEDO + c) * 3 + c] = (1.0 - m) * MR_INV_PI;
        d_specular[(GM_ALBEDO + c) * 3 + c] = m * d_f0;
        d_diffuse[GM_METALLIC * 3 + c] = -albedo * MR_INV_PI;
        d_specular[GM_METALLIC * 3 + c] = (albedo - f0d) * d_f0;
        d_specular[GM_ALPHA * 3 + c] = (f0 + (1.0 - f0) * w) * d_dg;
        d_specular[GM_F0D * 3 + c] = (1.0 - m) * d_f0;
    }
}

const mr_brdf_model mr_brdf_ggx_metallic = {
    .name = "ggx-metallic",
    .summary = "GGX + Lambert in the metallic workflow (paper Eq. 2): albedo, metallic, alpha",
    .source = "Sztrajman et al. 2019 Eq. 2 over Mitsuba 0.6 microfacet.h GGX + Schlick F0",
    .param_count = (int)(sizeof ggx_metallic_params / sizeof ggx_metallic_params[0]),
    .params = ggx_metallic_params,
    .flags = MR_BRDF_INDEPENDENT_LOBES,
    .config = NULL,
    .prepare = gm_prepare,
    .eval = gm_eval,
    .eval_batch = gm_eval_batch,
    .eval_grad = gm_eval_grad,
};
