/*
 * usd_preview.c — `usd-preview`: OpenUSD's UsdPreviewSurface, specification version 2.5 (docs/
 * spec_usdpreviewsurface.rst, "Preview Surface"), both workflows; isotropic, opaque.
 *
 *   alpha = roughness^2, alpha_c = clearcoat_roughness^2  ("usually squared before use with a GGX ... lobe")
 *   S(a) = D V: GGX D, height-correlated Smith V = G2/(4 n.l n.v) (the microfacet lobe of MaterialX's
 *          generalized_schlick_bsdf; the same D V as gltf)
 *   w = (1 - wi.h)^5, Schlick:  F_c = F0_c + (F90_c - F0_c) w
 *   R2 = ((1 - ior)/(1 + ior))^2
 *   metallic workflow (use_specular_workflow = 0; spec, input metallic):
 *     k_c   = mix(1, diffuse_c, metallic)                 (F90: white at metallic 0, the albedo at metallic 1)
 *     F0_c  = mix(R2 k_c, k_c, metallic) = k_c ((1 - metallic) R2 + metallic),   F90_c = k_c
 *     W     = 1 - metallic                                ("pure metals have no diffuse")
 *   specular workflow (use_specular_workflow = 1; spec, input specularColor):
 *     F0_c  = specular_color_c,  F90_c = 1,  W = 1        (metallic is ignored)
 *   diffuse_c  = W (1 - F_c) diffuse_c / pi               (Lambert, dimmed by the primary lobe's Fresnel)
 *   specular_c = F_c S(alpha) + clearcoat (R2 + (1 - R2) w) S(alpha_c)
 *
 * The clearcoat is white (spec, input clearcoat: "The color is white") with F0 from the ior input, not a fixed
 * 1.5: spec input ior, "including the clearcoat if clearcoat > 0" (anchor updateior, a clarification of version
 * 2.4 kept in 2.5); MaterialX's graph feeds the same R2 to its coat (coat_F0).
 *
 * Where the two reference implementations differ, this file follows the specification's words and Pixar's own
 * (pxr/usdImaging/plugin/usdShaders/shaders/previewSurface.glslfx, Storm), and MaterialX 1.39's graph
 * (libraries/bxdf/usd_preview_surface.mtlx, ND_UsdPreviewSurface_surfaceshader) is read for the structure both
 * share: alpha = roughness^2, generalized Schlick Fresnel with the F0/F90 above (its nodes specular_color_metallic
 * and F0 are the same mix; note that F0 is NOT the plain mix(R2, diffuse, metallic): k_c scales both ends), a
 * white coat with F0 = R2. The choices, with what MaterialX does instead:
 *   - Diffuse weight W (1 - F_c(wi.h)) per channel (Storm). MaterialX layers the Schlick lobe over the diffuse with
 *     its `layer` node, which scales the diffuse by 1 - E(n.v), the lobe's directional albedo at the view direction
 *     only (averaged over channels): not reciprocal, and it needs an albedo table. Its metallic workflow also
 *     weights the diffuse by (1 - metallic) twice (diffuse_bsdf_weight, then the metallic mix), (1 - metallic)^2.
 *   - The metal: one Schlick lobe with F0 = F90 = k (the specification's "both F0 and edge F90 reflectivity will
 *     simply be the Albedo"). MaterialX mixes, by metallic, a conductor_bsdf whose complex IOR comes from
 *     artistic_ior(diffuseColor, diffuseColor) (exact Fresnel, F(0) = diffuseColor, tending to 1 at grazing) with
 *     the Schlick lobe; the two agree at normal incidence and differ towards grazing.
 *   - The clearcoat is added on top of the base (Storm); MaterialX layers it (the base times 1 - clearcoat E_coat).
 *   - No multiple-scattering compensation: MaterialX's generalized_schlick_bsdf (pbrlib/genglsl) multiplies its
 *     lobe by mx_ggx_energy_compensation(n.v, alpha); Storm has none.
 *   - G: height-correlated Smith (MaterialX's mx_ggx_smith_G2); Storm uses the separable Schlick-GGX k = alpha/2
 *     and adds 0.001 to D's numerator and to 4 n.l n.v, shading hacks left out here.
 *
 * Parameters (the specification's inputs and fallbacks; the CLI spells them in lowercase with underscores):
 *   diffuse_color          RGB [0, 1]     default 0.18  diffuseColor (the albedo in the metallic workflow).
 *                                                       NONLINEAR: in the metallic workflow F_c is affine in it
 *                                                       (through k_c) and the diffuse multiplies F_c by it, so f is
 *                                                       quadratic in it for 0 < metallic < 1. In the specular
 *                                                       workflow it would be LINEAR; the role must hold in both.
 *   use_specular_workflow  SWITCH 0/1     default 0     useSpecularWorkflow (an int input): 1 = specular workflow.
 *   specular_color         RGB [0, 1]     default 0     specularColor (specular workflow only). AFFINE in both
 *                                                       workflows: F_c and the diffuse are affine in it there,
 *                                                       and f does not depend on it in the metallic workflow.
 *   metallic                   [0, 1]     default 0     metallic (metallic workflow only)
 *   roughness                  [0.01, 1]  default 0.5   roughness, log scale. The specification allows 0 (a mirror);
 *                                                       0.01 (alpha = 1e-4, as gltf) keeps the lobe finite.
 *   clearcoat                  [0, 1]     default 0     clearcoat: the coat lobe's weight. AFFINE: f = base +
 *                                                       clearcoat coat, the base independent of it.
 *   clearcoat_roughness        [0.01, 1]  default 0.01  clearcoatRoughness, log scale (same floor).
 *                                                       Fits hold both at their given values (MR_PARAM_FIT_FIXED,
 *                                                       default: no coat), as gltf holds its extensions: a remap
 *                                                       from a coatless source should not invent a coat to mimic
 *                                                       a Fresnel edge; give clearcoat=... to keep a coat.
 *   ior                        [1, 3]     default 1.5   ior: R2 for the metallic workflow's F0 and for the coat.
 *                                                       [1, 3] is MaterialX's soft range (uisoftmin/uisoftmax);
 *                                                       fits hold it fixed (MR_PARAM_FIT_FIXED), as gltf's.
 * 8/16-bit maps of diffuse_color and specular_color are sRGB-encoded (the specification's UsdUVTexture
 * sourceColorSpace "auto" treats 8-bit colour textures as sRGB); every other map is linear.
 *
 * Special cases (tests/test_brdf.c known_usd_preview):
 *   - metallic workflow, metallic 0, clearcoat 0 = gltf with metallic 0 and the same ior (F0 = R2, F90 = 1, diffuse
 *     (1 - F)/pi times the colour; gltf's 1 - max_c F_c equals 1 - F_c for a grey F), bit for bit.
 *   - the core glTF material (base b, metallic m, no extensions) = the specular workflow with specular_color =
 *     mix(0.04, b, m) and diffuse_color = (1 - m) 0.96 b/(1 - specular_color) (<= 1), exactly: glTF's mix of a
 *     dielectric and a white-edged metal is one Schlick lobe with F90 = 1.
 *   - not the metallic workflow at metallic > 0: there the metal's edge is the albedo (F90 = k), glTF's white.
 *   - no setting is Lambert: with F0 = 0 (ior 1, or specular_color 0) Schlick still gives F = w, so the diffuse is
 *     (1 - w) diffuse/pi (diffuse/pi exactly only on retro-reflection, wi = wo) and the specular w D V.
 *
 * Out of scope (a fit scene cannot see them; USD files carry them): emissiveColor, opacity, opacityThreshold,
 * opacityMode (MaterialX), normal, displacement, occlusion, and the transmission lobe of translucent surfaces.
 * Energy: flagged MR_BRDF_NOT_ENERGY_CONSERVING. The diffuse weight 1 - F(wi.h) double counts towards grazing
 * incidence as gltf's does (white diffuse, metallic 0, ior 1.5: albedo 0.997 at normal incidence at roughness 0.5,
 * 1.35 at 80 degrees at roughness 0.01), and the clearcoat is added without taking energy from the base (white
 * diffuse, clearcoat 1: 1.037 at normal incidence). The worst the white-furnace test finds is 2.65 at 88 degrees
 * (white, ior 1, both lobes smooth, clearcoat 1: three mirror-like terms of F = w each). These are the reference
 * shading's (Storm's), not defects here; the specular lobe alone (F = 1) stays below 1 (0.89 at 40 degrees,
 * roughness 0.5: single-scattering GGX loses energy).
 * Derivatives: analytic, by hand (usd_eval_grad below: the model is a few affine and product terms), every slot;
 * the switch's 0. At clearcoat 0 the one-sided derivative in clearcoat is the coat lobe. Cost
 * (tests/bench_brdf_grad.c): about 50 ns per eval_grad, 3 to 4 times an eval with a prepared state, 1.3 to 1.5 times
 * a prepare + eval.
 */
#include "brdf_internal.h"

/* Slots of the packed value vector. */
enum { USD_DIFFUSE = 0, USD_SPEC_WORKFLOW = 3, USD_SPECULAR_COLOR = 4, USD_METALLIC = 7, USD_ROUGHNESS = 8,
       USD_CLEARCOAT = 9, USD_CLEARCOAT_ROUGHNESS = 10, USD_IOR = 11 };

/* alpha = roughness^2 >= 1e-4, as gltf's floor. */
#define USD_ROUGHNESS_MIN 0.01

static const mr_brdf_param usd_params[] = {
    {"diffuse_color", 3, 0.18, 0.0, 1.0, MR_PARAM_NONLINEAR, MR_LOBE_BOTH, MR_PARAM_SRGB_MAP,
     "diffuseColor, linear RGB (the albedo, and the metal's F0/F90, in the metallic workflow)", NULL},
    {"use_specular_workflow", 1, 0.0, 0.0, 1.0, MR_PARAM_SWITCH, MR_LOBE_BOTH, 0,
     "useSpecularWorkflow: 0 = metallic workflow (metallic, ior), 1 = specular workflow (specular_color)", NULL},
    {"specular_color", 3, 0.0, 0.0, 1.0, MR_PARAM_AFFINE, MR_LOBE_BOTH, MR_PARAM_SRGB_MAP,
     "specularColor, linear RGB: F0 of the specular workflow (F90 white); unused in the metallic one", NULL},
    {"metallic", 1, 0.0, 0.0, 1.0, MR_PARAM_NONLINEAR, MR_LOBE_BOTH, 0,
     "metallic (metallic workflow): F0 = mix(R2 k, k, metallic), F90 = k = mix(1, diffuse_color, metallic)", NULL},
    {"roughness", 1, 0.5, USD_ROUGHNESS_MIN, 1.0, MR_PARAM_NONLINEAR, MR_LOBE_SPECULAR, MR_PARAM_LOG_SCALE,
     "roughness; GGX alpha = roughness^2", NULL},
    {"clearcoat", 1, 0.0, 0.0, 1.0, MR_PARAM_AFFINE, MR_LOBE_SPECULAR, MR_PARAM_FIT_FIXED,
     "clearcoat: weight of the white second GGX lobe (F0 = R2, F90 = 1), added to the base", NULL},
    {"clearcoat_roughness", 1, 0.01, USD_ROUGHNESS_MIN, 1.0, MR_PARAM_NONLINEAR, MR_LOBE_SPECULAR,
     MR_PARAM_LOG_SCALE | MR_PARAM_FIT_FIXED, "clearcoatRoughness; the coat's GGX alpha = clearcoat_roughness^2", NULL},
    {"ior", 1, 1.5, 1.0, 3.0, MR_PARAM_NONLINEAR, MR_LOBE_BOTH, MR_PARAM_FIT_FIXED,
     "ior: R2 = ((1-ior)/(1+ior))^2, the metallic workflow's dielectric F0 and the clearcoat's F0", NULL},
};

typedef struct usd_state {
    double alpha, alpha_coat;
    double weight;   /* W: 1 - metallic (metallic workflow) or 1 (specular workflow) */
    double coat;     /* clearcoat */
    double coat_f0;  /* R2 */
    double f0[3], f90[3];
    double diffuse[3];
} usd_state;

_Static_assert(sizeof(usd_state) <= MR_BRDF_STATE_BYTES, "usd_state must fit in MR_BRDF_STATE_BYTES");

static void usd_prepare(const mr_brdf_model *model, const double *values, void *state_bytes) {
    usd_state *state = state_bytes;
    double v[MR_BRDF_MAX_VALUES];
    mr_brdf_clamp_values(model, values, v);
    double r = (1.0 - v[USD_IOR]) / (1.0 + v[USD_IOR]), r2 = r * r;
    double m = v[USD_METALLIC];
    int specular_workflow = v[USD_SPEC_WORKFLOW] >= 0.5;
    state->alpha = v[USD_ROUGHNESS] * v[USD_ROUGHNESS];
    state->alpha_coat = v[USD_CLEARCOAT_ROUGHNESS] * v[USD_CLEARCOAT_ROUGHNESS];
    state->coat = v[USD_CLEARCOAT];
    state->coat_f0 = r2;
    state->weight = specular_workflow ? 1.0 : 1.0 - m;
    for (int c = 0; c < 3; c++) {
        double d = v[USD_DIFFUSE + c];
        state->diffuse[c] = d;
        if (specular_workflow) {
            state->f0[c] = v[USD_SPECULAR_COLOR + c];
            state->f90[c] = 1.0;
        } else {
            double k = (1.0 - m) + m * d; /* mix(1, diffuse, metallic) */
            state->f0[c] = (1.0 - m) * r2 * k + m * k;
            state->f90[c] = k;
        }
    }
}

static void usd_eval(const void *state_bytes, const double wi[3], const double wo[3], double diffuse[3],
                     double specular[3]) {
    const usd_state *state = state_bytes;
    mr_brdf_geom g;
    if (!mr_brdf_geom_init(wi, wo, &g)) {
        mr_brdf_zero(diffuse, specular);
        return;
    }
    double w = mr_schlick_weight(g.dot_h);
    double F[3];
    for (int c = 0; c < 3; c++) F[c] = state->f0[c] + (state->f90[c] - state->f0[c]) * w;
    if (diffuse)
        for (int c = 0; c < 3; c++) diffuse[c] = state->weight * (1.0 - F[c]) * state->diffuse[c] * MR_INV_PI;
    if (specular) {
        double S = mr_ggx_dv_correlated(state->alpha, &g, NULL);
        double coat = 0.0;
        if (state->coat > 0.0)
            coat = state->coat * (state->coat_f0 + (1.0 - state->coat_f0) * w) *
                   mr_ggx_dv_correlated(state->alpha_coat, &g, NULL);
        for (int c = 0; c < 3; c++) specular[c] = F[c] * S + coat;
    }
}

/* d f_r / d values[j], by hand: with w the Schlick weight, S = D V(alpha), S_c = D V(alpha_c), R2 the ior's F0,
 *   metallic workflow:  F_c = k_c P,  k_c = 1 - m + m d_c,  P = ((1 - m) R2 + m)(1 - w) + w,  W = 1 - m
 *   specular workflow:  F_c = s_c (1 - w) + w,  W = 1
 *   diffuse_c = W (1 - F_c) d_c/pi,  specular_c = F_c S + cc (R2 (1 - w) + w) S_c
 * so, e.g., dF_c/dm = (d_c - 1) P + k_c (1 - R2)(1 - w) and dR2/dior = 2 R (-2/(1 + ior)^2), R = (1 - ior)/(1 + ior).
 * The coat's terms are taken at clearcoat 0 too (its value there is 0; d/dclearcoat is the coat lobe). */
static void usd_eval_grad(const mr_brdf_model *model, const double *values, const double wi[3], const double wo[3],
                          double *d_diffuse, double *d_specular) {
    mr_brdf_geom g;
    double v[MR_BRDF_MAX_VALUES];
    if (!mr_brdf_grad_begin(model, values, wi, wo, d_diffuse, d_specular, &g, v)) return;
    double ior = v[USD_IOR], r = (1.0 - ior) / (1.0 + ior), r2 = r * r;
    double dr2 = 2.0 * r * (-2.0 / ((1.0 + ior) * (1.0 + ior)));
    double m = v[USD_METALLIC], rough = v[USD_ROUGHNESS], coat_rough = v[USD_CLEARCOAT_ROUGHNESS];
    double coat = v[USD_CLEARCOAT];
    int specular_workflow = v[USD_SPEC_WORKFLOW] >= 0.5;
    double w = mr_schlick_weight(g.dot_h);
    double dS, dS_c;
    double S = mr_ggx_dv_correlated(rough * rough, &g, &dS);
    double S_c = mr_ggx_dv_correlated(coat_rough * coat_rough, &g, &dS_c);
    double coat_F = r2 + (1.0 - r2) * w;
    for (int c = 0; c < 3; c++) {
        double d = v[USD_DIFFUSE + c], F, dF_dd, dF_dm = 0.0, dF_dior = 0.0, W = 1.0;
        if (specular_workflow) {
            double sc = v[USD_SPECULAR_COLOR + c];
            F = sc + (1.0 - sc) * w;
            dF_dd = 0.0;
            d_diffuse[(USD_SPECULAR_COLOR + c) * 3 + c] = -(1.0 - w) * d * MR_INV_PI;
            d_specular[(USD_SPECULAR_COLOR + c) * 3 + c] = (1.0 - w) * S;
        } else {
            double k = (1.0 - m) + m * d, P = ((1.0 - m) * r2 + m) * (1.0 - w) + w;
            F = k * P;
            dF_dd = m * P;
            dF_dm = (d - 1.0) * P + k * (1.0 - r2) * (1.0 - w);
            dF_dior = k * (1.0 - m) * (1.0 - w) * dr2;
            W = 1.0 - m;
            /* W = 1 - m: the diffuse's own metallic term */
            d_diffuse[USD_METALLIC * 3 + c] = (-(1.0 - F) * d - W * dF_dm * d) * MR_INV_PI;
            d_specular[USD_METALLIC * 3 + c] = dF_dm * S;
        }
        d_diffuse[(USD_DIFFUSE + c) * 3 + c] = W * ((1.0 - F) - dF_dd * d) * MR_INV_PI;
        d_specular[(USD_DIFFUSE + c) * 3 + c] = dF_dd * S;
        d_specular[USD_ROUGHNESS * 3 + c] = F * dS * 2.0 * rough;
        d_specular[USD_CLEARCOAT * 3 + c] = coat_F * S_c;
        d_specular[USD_CLEARCOAT_ROUGHNESS * 3 + c] = coat * coat_F * dS_c * 2.0 * coat_rough;
        d_diffuse[USD_IOR * 3 + c] = -W * dF_dior * d * MR_INV_PI;
        d_specular[USD_IOR * 3 + c] = dF_dior * S + coat * (1.0 - w) * dr2 * S_c;
    }
}

const mr_brdf_model mr_brdf_usd_preview = {
    .name = "usd-preview",
    .summary = "OpenUSD UsdPreviewSurface 2.5, metallic and specular workflows + clearcoat (GGX, Schlick)",
    .source = "OpenUSD docs/spec_usdpreviewsurface.rst 2.5; hdSt previewSurface.glslfx; MaterialX "
              "usd_preview_surface.mtlx",
    .param_count = (int)(sizeof usd_params / sizeof usd_params[0]),
    .params = usd_params,
    .flags = MR_BRDF_NOT_ENERGY_CONSERVING,
    .config = NULL,
    .prepare = usd_prepare,
    .eval = usd_eval,
    .eval_grad = usd_eval_grad,
};
