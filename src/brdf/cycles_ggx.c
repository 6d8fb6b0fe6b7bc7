/*
 * cycles_ggx.c — `cycles-ggx`: the paper's "Cycles GGX" (Sztrajman et al. 2019, Figs. 1, 16-18 and its
 * Appendix): Blender Cycles' Glossy BSDF with the GGX distribution, its colour a Schlick Fresnel of F0, plus an
 * optional Lambert (Diffuse BSDF, roughness 0) added to it; isotropic.
 *
 *   alpha = roughness^2                                 (the Glossy node squares its Roughness input)
 *   D     = alpha^2 / (pi (1 + (alpha^2 - 1) cos^2(theta_h))^2)              (Cycles' GGX D, alpha2 = alpha^2)
 *   G     correlated = 0: G1(wi) G1(wo), G1 = 2/(1 + sqrt(1 + alpha^2 tan^2))   (separable: Cycles <= 3.4)
 *         correlated = 1: 1/(1 + L(wi) + L(wo)), L = (sqrt(1 + alpha^2 tan^2) - 1)/2  (height-correlated: 3.5+)
 *   F     = F0 + (1 - F0)(1 - wi.h)^5                   (Schlick, F0 given directly)
 *   f     = diffuse/pi  +  F D G / (4 cos_i cos_o)
 *
 * Why this form. The paper names a Fresnel coefficient F0 for Cycles GGX (Figs. 16 and 17: "remapping of
 * Fresnel coefficient F0") but does not say how the Glossy BSDF, which has a colour and no Fresnel of its own
 * (brdf-reference 4.1, 4.4), was given one. The authors' own Mitsuba side is their "pbr" plugin, D G times a
 * Schlick Fresnel of F0 with no diffuse (brdf-reference 1), and their Appendix fit Mitsuba GGX -> Cycles GGX is
 * close to the identity in both parameters (alpha_C = 0.98 alpha_M + ..., s_C = s_M [1.05 - ...]), which is
 * what the same lobe with the same Fresnel gives. So Cycles GGX here is that lobe: the pbr plugin's D G with
 * Cycles' alpha = roughness^2. Caveat: a node graph cannot evaluate a Fresnel at wi.h (a closure's colour is
 * computed before the light direction is known), so a literal Blender set-up had either colour = F0 (no
 * Fresnel: `ggx-nofresnel`, specular = F0, alpha = roughness^2) or a Schlick of the view angle n.wi (not
 * reciprocal). Those differ from this model only where (1 - cos)^5 matters, at grazing angles. Not in the
 * paper's fit scene: its 45-degree light puts every wi.h near cos 22.5 degrees, where (1 - wi.h)^5 = 2.5e-6, so a
 * remap of `ggx` (f0 0.5, alpha 0.01-0.6) to `ggx-nofresnel` returns specular 0.50003. The paper's F0 slope of
 * 0.90-1.05 between Mitsuba GGX and Cycles GGX therefore cannot come from the Fresnel form; renderer differences
 * (light, irradiance matching) remain its explanation, as the paper suggests.
 *
 * Exactness: with correlated = 0 this is `ggx` (the Mitsuba pbr model) at alpha = roughness^2 and the same f0
 * and diffuse, to the last bit (the same D and G1 code), except where Mitsuba's cut-off D cos_h < 1e-20 zeroes
 * `ggx` (far tails of grazing half vectors; Cycles has no cut-off). The separable G1 is also Mitsuba's GGX G1
 * (brdf-reference 2.3). With correlated = 1, G D/(4 cos_i cos_o) is glTF's height-correlated visibility V D
 * (brdf-reference 5.1) with the same alpha, which is Cycles 3.5+'s G2 written without the Lambdas.
 *
 * Parameters:
 *   roughness   [0.01, 1]  default 0.5  the Glossy node's Roughness (its 3.4 default), log scale;
 *                                       alpha = roughness^2.
 *                                       Cycles accepts 0 (a mirror); 0.01 gives alpha = 1e-4, Mitsuba's floor.
 *                                       The paper's alpha_C behaves as the GGX alpha (its Mitsuba GGX -> Cycles
 *                                       GGX fit is near the identity): compare roughness^2 with it.
 *   f0          RGB [0, 1] default 0.04 Schlick F0, linear RGB (AFFINE); 0.04 = dielectric of ior 1.5
 *   diffuse     RGB [0, 1] default 0    Lambert reflectance added to the glossy lobe; 0 = the pbr plugin
 *   correlated  switch     default 0    0: separable Smith G (Cycles <= 3.4, Blender 2.7x-3.4: the paper's and
 *                                       Debian 12's Blender 3.4.1); 1: height-correlated G (Cycles 3.5+)
 *
 * Not simulated: Multiscatter GGX (another distribution of the Glossy node), which adds back the energy single
 * scattering loses at high roughness; anisotropy; Cycles' 1e-5 closure-weight cut-off.
 * Checked against Blender 3.4.1 (scripts/cycles_fit_scene.py --material glossy: Glossy BSDF, GGX, colour 1, which
 * is f0 = 1 here; fit scene, 256^2, specular component; docs/cycles-peer.md): mean radiance within 0.005 % at
 * roughness 0.2, 0.5 and 0.8 (0.2 rendered at 1024^2 and box-filtered to 256^2, as Cycles' pixels are), object
 * SSIM 0.9998-1.0000; correlated = 1 is 1.4 % brighter than Blender 3.4 at roughness 0.8 (3.4's G is separable).
 * Source: Blender 3.4 intern/cycles/kernel/closure/bsdf_microfacet.h (GGX D, separable G1), svm/closure.h
 * (roughness squared); 3.5+ bsdf_microfacet.h (height-correlated G2) (brdf-reference 4.1, 4.2); Schlick F0 as
 * the authors' pbr.cpp (brdf-reference 1). Cycles' eval returns f_r cos(wo); ours does not (brdf.h).
 * Energy: flagged MR_BRDF_INDEPENDENT_LOBES as `ggx`: each lobe conserves energy, their sum only while the
 * albedos add up to at most 1 (the diffuse is not dimmed by the Fresnel term).
 * Gradient: analytic for every parameter (roughness through alpha = roughness^2, D and G).
 */
#include "brdf_batch.h"

/* Slots of the packed value vector. */
enum { CG_ROUGHNESS = 0, CG_F0 = 1, CG_DIFFUSE = 4, CG_CORRELATED = 7 };

static const mr_brdf_param cg_params[] = {
    {"roughness", 1, 0.5, 0.01, 1.0, MR_PARAM_NONLINEAR, MR_LOBE_SPECULAR, MR_PARAM_LOG_SCALE,
     "Glossy BSDF Roughness (Cycles' slider); GGX alpha = roughness^2", NULL},
    {"f0", 3, 0.04, 0.0, 1.0, MR_PARAM_AFFINE, MR_LOBE_SPECULAR, MR_PARAM_SRGB_MAP,
     "Schlick reflectance at normal incidence F0 of wi.h, linear RGB (as the authors' pbr plugin)", NULL},
    {"diffuse", 3, 0.0, 0.0, 1.0, MR_PARAM_LINEAR, MR_LOBE_DIFFUSE, MR_PARAM_SRGB_MAP,
     "Lambert reflectance rho_d, linear RGB, added to the glossy lobe (a Diffuse BSDF, roughness 0)", NULL},
    {"correlated", 1, 0.0, 0.0, 1.0, MR_PARAM_SWITCH, MR_LOBE_SPECULAR, 0,
     "Smith G: 0 separable G1(wi) G1(wo) (Cycles <= 3.4), 1 height-correlated (Cycles 3.5+)", NULL},
};

typedef struct cg_state {
    double alpha;
    int correlated;
    double f0[3];
    double diffuse_over_pi[3];
} cg_state;

_Static_assert(sizeof(cg_state) <= MR_BRDF_STATE_BYTES, "cg_state must fit in MR_BRDF_STATE_BYTES");

static void cg_prepare(const mr_brdf_model *model, const double *values, void *state_bytes) {
    cg_state *state = state_bytes;
    double v[MR_BRDF_MAX_VALUES];
    mr_brdf_clamp_values(model, values, v);
    state->alpha = v[CG_ROUGHNESS] * v[CG_ROUGHNESS];
    state->correlated = v[CG_CORRELATED] >= 0.5;
    for (int c = 0; c < 3; c++) {
        state->f0[c] = v[CG_F0 + c];
        state->diffuse_over_pi[c] = v[CG_DIFFUSE + c] * MR_INV_PI;
    }
}

/* D G/(4 cos_i cos_o) with either G, and its alpha derivative if d_dalpha. */
static double cg_dg(double alpha, int correlated, const mr_brdf_geom *g, double *d_dalpha) {
    return correlated ? mr_ggx_dv_correlated(alpha, g, d_dalpha) : mr_mf_dg(MR_MF_GGX, alpha, g, 0, d_dalpha);
}

static void cg_eval(const void *state_bytes, const double wi[3], const double wo[3], double diffuse[3],
                    double specular[3]) {
    const cg_state *state = state_bytes;
    mr_brdf_geom g;
    if (!mr_brdf_geom_init(wi, wo, &g)) {
        mr_brdf_zero(diffuse, specular);
        return;
    }
    if (diffuse)
        for (int c = 0; c < 3; c++) diffuse[c] = state->diffuse_over_pi[c];
    if (specular) {
        double dg = cg_dg(state->alpha, state->correlated, &g, NULL);
        double w = mr_schlick_weight(g.dot_h);
        for (int c = 0; c < 3; c++) specular[c] = (state->f0[c] + (1.0 - state->f0[c]) * w) * dg;
    }
}

/* eval over a batch for either G (a constant in each call below): cg_eval's operations. */
MR_BATCH_INLINE void cg_batch_loop(const cg_state *state, const mr_brdf_batch *batch, const int correlated,
                                   const int fused) {
    const double alpha = state->alpha;
    const double d0 = state->diffuse_over_pi[0], d1 = state->diffuse_over_pi[1], d2 = state->diffuse_over_pi[2];
    const double f0 = state->f0[0], f1 = state->f0[1], f2 = state->f0[2];
    MR_BATCH_ARRAYS(batch);
#pragma omp simd
    for (int i = 0; i < n_; i++) {
        mr_brdf_geom g;
        const int lit = mr_batch_geom(ix_[i], iy_[i], iz_[i], ox_[i], oy_[i], oz_[i], &g);
        const double lobe = correlated ? mr_batch_ggx_dv_correlated(alpha, &g)
                                       : mr_batch_mf_dg(MR_MF_GGX, alpha, &g, 0, fused);
        const double dg = lit ? lobe : 0.0;
        const double w = mr_schlick_weight(g.dot_h);
        d0_[i] = lit ? d0 : 0.0;
        d1_[i] = lit ? d1 : 0.0;
        d2_[i] = lit ? d2 : 0.0;
        s0_[i] = (f0 + (1.0 - f0) * w) * dg;
        s1_[i] = (f1 + (1.0 - f1) * w) * dg;
        s2_[i] = (f2 + (1.0 - f2) * w) * dg;
    }
}

MR_BATCH_INLINE void cg_batch_body(const void *state_bytes, const mr_brdf_batch *batch, const int fused) {
    const cg_state *state = state_bytes;
    if (state->correlated)
        cg_batch_loop(state, batch, 1, fused);
    else
        cg_batch_loop(state, batch, 0, fused);
}

MR_BATCH_KERNEL(cg_eval_batch, cg_batch_body)

static void cg_eval_grad(const mr_brdf_model *model, const double *values, const double wi[3],
                         const double wo[3], double *d_diffuse, double *d_specular) {
    mr_brdf_geom g;
    double v[MR_BRDF_MAX_VALUES];
    if (!mr_brdf_grad_begin(model, values, wi, wo, d_diffuse, d_specular, &g, v)) return;
    double rough = v[CG_ROUGHNESS], d_dg;
    double dg = cg_dg(rough * rough, v[CG_CORRELATED] >= 0.5, &g, &d_dg);
    double w = mr_schlick_weight(g.dot_h);
    for (int c = 0; c < 3; c++) {
        double F = v[CG_F0 + c] + (1.0 - v[CG_F0 + c]) * w;
        d_specular[CG_ROUGHNESS * 3 + c] = F * d_dg * 2.0 * rough; /* d alpha/d roughness = 2 roughness */
        d_specular[(CG_F0 + c) * 3 + c] = (1.0 - w) * dg;
        d_diffuse[(CG_DIFFUSE + c) * 3 + c] = MR_INV_PI;
    }
}

const mr_brdf_model mr_brdf_cycles_ggx = {
    .name = "cycles-ggx",
    .summary = "Cycles Glossy BSDF, GGX, alpha = roughness^2, Schlick F0 colour + Lambert (paper's Cycles GGX)",
    .source = "Blender 3.4 intern/cycles/kernel/closure/bsdf_microfacet.h, svm/closure.h; Schlick F0 as the "
              "authors' pbr.cpp",
    .param_count = (int)(sizeof cg_params / sizeof cg_params[0]),
    .params = cg_params,
    .flags = MR_BRDF_INDEPENDENT_LOBES,
    .config = NULL,
    .prepare = cg_prepare,
    .eval = cg_eval,
    .eval_batch = cg_eval_batch,
    .eval_grad = cg_eval_grad,
};
