/*
 * blender_principled.c — `blender-principled`: Blender 4.x Cycles' Principled BSDF (the 4.0 rewrite), its opaque,
 * isotropic reflection: a coat over a metal / dielectric-specular / Lambert stack, layered by albedo.
 *
 * Read in the Cycles sources of Blender 4.2 (intern/cycles/kernel/svm/closure.h CLOSURE_BSDF_PRINCIPLED_ID, as
 * stored at commit 02e6985c: thin film present, the diffuse a plain Lambert closure, no Diffuse Roughness input;
 * kernel/closure/bsdf_microfacet.h microfacet_fresnel, microfacet_ggx_preserve_energy,
 * bsdf_microfacet_estimate_albedo, bsdf_microfacet_setup_fresnel_*; bsdf_util.h closure_layering_weight,
 * fresnel_f82tint_B, fresnel_f82, fresnel_f82_Fss, F0_from_ior, ior_from_F0). Cycles' eval returns f cos(wo); ours
 * does not (brdf.h). The first argument of eval is the view direction (Cycles' sd->wi; render.c calls
 * eval(view, light)), at which every albedo estimate below is taken: the model is not reciprocal
 * (MR_BRDF_NON_RECIPROCAL), as Cycles' layering is not.
 *
 *   Lobes: GGX, alpha = roughness^2, Smith G2 = 1/(1 + Lambda_i + Lambda_o), DV = D G2/(4 cos_i cos_o)
 *     (mr_ggx_dv_correlated). With multiscatter on (the node's default "Multiscatter GGX"; the coat always), a
 *     lobe is scaled by 1 + F_ms (1 - E)/E, F_ms = F_ss E_avg/(1 - F_ss (1 - E_avg)) (microfacet_ggx_preserve_energy:
 *     the energy scale 1/E times its Fresnel darkening), E = E(mu_v, r) the lobe's F = 1 albedo, E_avg its average,
 *     F_ss the lobe's average Fresnel.
 *   w = 1 (the weight left for lower layers, RGB).
 *   Layering (closure_layering_weight, bsdf_albedo): a layer's albedo estimate is its closure weight times
 *     mix(F0, F90, s(mu_v, r, eta)); with multiscatter the weight carries the darkening E + F_ms (1 - E), so the
 *     estimate does too (dk below; 1 without multiscatter). Lower layers keep w (1 - max_c estimate_c).
 *   Coat (coat_weight C > 0): f += C F(v.h, coat_ior) DV_c ms_c, F the exact dielectric Fresnel,
 *     alpha_c = coat_roughness^2, F_ss = F_avg(coat_ior); ms_c and dk_c whatever multiscatter says (Cycles'
 *     bsdf_microfacet_setup_fresnel_dielectric always preserves energy). Then
 *     w *= 1 - C dk_c mix(F0_c, 1, s(mu_v, r_c, coat_ior)) and w *= mix(1, coat_tint^(1/cos_t), C),
 *     cos_t = sqrt(1 - (1 - mu_v^2)/coat_ior^2) (the view ray refracted into the coat, one pass).
 *   Metal: f += metallic w F82(v.h) DV ms, F82 = saturate(F_Schlick(base_color) - b mu (1 - mu)^6),
 *     b = (1 - specular_tint) F_Schlick(1/7)/((1/7)(6/7)^6) (brdf_internal.h mr_f82_*), F_ss = mix(F0, 1, 1/21)
 *     - b/126 (the exact average of that curve). Then w *= 1 - metallic.
 *   Dielectric specular: f0 = F0(ior) 2 specular_ior_level, eta = (1 + sqrt(f0))/(1 - sqrt(f0)) (f0 <= 0.99);
 *     F = mix(f0 specular_tint, 1, saturate((F(v.h, eta) - f0)/(1 - f0))) per channel (the generalized Schlick
 *     with a negative exponent: the real Fresnel curve remapped), f += w F DV ms, F_ss = mix(f0 tint, 1,
 *     (F_avg(eta) - f0)/(1 - f0)). Then w *= 1 - max_c dk_c mix(f0 tint_c, 1, s(mu_v, r, eta)).
 *   Diffuse: f += w base_color/pi (Lambert).
 *   Albedo estimate s(mu, r, eta) (Cycles' ggx_gen_schlick_ior_s): the lobe-weighted mean of the remap weight,
 *     (E_F(mu) - F0 E(mu))/((1 - F0) E(mu)), E_F the albedo with the real Fresnel (layering.c tables).
 *
 * Substitutions, with their size: Cycles' lookup tables (ggx_E, ggx_Eavg, ggx_gen_schlick_ior_s) are replaced by
 * this library's one GGX albedo table (layering.c, ggx_albedo_tables.h, shared with openpbr and standard-surface;
 * the same integrals, computed here, differently gridded; its interpolation error, stated in layering.c, is at
 * most 0.00095 up to 80 degrees for ior 1.05-3, 0.00034 for the F = 1 table), and the fitted fresnel_dielectric_Fss by
 * the exact average F_avg. Cycles works in float and drops closures below CLOSURE_WEIGHT_CUTOFF (1e-5); this model
 * is double and continuous.
 *
 * Parameters (the node's inputs, lowercase; defaults the node's):
 *   base_color         RGB [0, 1]      default 0.8
 *   metallic               [0, 1]      default 0
 *   roughness              [0.01, 1]   default 0.5   log scale; alpha = roughness^2, floor 0.01 (alpha 1e-4)
 *   ior                    [1, 3]      default 1.5   (the node allows below 1: not supported here). Fits hold it.
 *   specular_ior_level     [0, 1]      default 0.5   0.5 leaves F0(ior); 0 removes the specular layer. Fits hold it.
 *   specular_tint      RGB [0, 1]      default 1     dielectric F0 tint (F90 stays 1); the metal's F82 tint. Fixed.
 *   coat_weight            [0, 1]      default 0     fits hold the coat parameters
 *   coat_roughness         [0, 1]      default 0.03  computed with a floor of 0.01
 *   coat_ior               [1, 3]      default 1.5
 *   coat_tint          RGB [0, 1]      default 1
 *   multiscatter           {0, 1}      default 1     1 "Multiscatter GGX", 0 "GGX" (metal, specular; not coat)
 * Default holds (what a fit holds unless given other values with --to or --hold NAME=VALUE; every fit prints them):
 *   ior=1.5, specular_ior_level=0.5, specular_tint=1 and the coat (coat_weight=0 ...); a fit solves base_color,
 *   metallic and roughness. The fit scene cannot tell metallic from specular_ior_level (both raise F0 while they
 *   lower the diffuse). Measured on six Ward materials (fit scene 32^2): with the level fitted, 1 of 6 remaps
 *   converged (3 at-bound, 1 local minimum) in 2502-3750 renders; with it held, 4 of 6 converged (the others: one
 *   under-resolved lobe, one Ward highlight no model here reaches) in 1544-2920 renders, SSIM within 0.002.
 * All NONLINEAR (albedo-scaled layers), multiscatter a SWITCH. metallic alone is in fact affine (f = metallic w_c
 * metal + (1 - metallic) (what lies below), and nothing below or above depends on it); its role stays NONLINEAR, as
 * the fit's answers were measured with it.
 * Split: diffuse part = the Lambert lobe with its weight w; specular part = coat, metal and dielectric lobes.
 * Out of scope: Diffuse Roughness (4.3+ sources, not the ones read), subsurface, transmission, sheen, emission, thin
 * film, anisotropy, alpha, normals.
 * Energy: the albedo-scaled stack conserves energy up to the estimate's approximations; the white furnace of
 * tests/test_brdf.c bounds it (known_blender_principled reports the figures).
 * Derivatives: analytic, every slot but the switch (bp_eval_grad): bp_prepare and bp_eval transcribed in forward-mode
 *   dual numbers (dual.h), through the tables' interpolation (layering.c) and the Simpson sums of E_avg and F_avg
 *   differentiated term by term. One-sided at corners: a table node (ior 1.5 at specular_ior_level 0.5 is the node
 *   eta = 1.5), the clamps of s and of the layer weights, and the max over channels of the specular estimate, where
 *   tied channels (a grey specular_tint, 1 by default, the top of its range) take the derivative from below. The coat
 *   and the metal are evaluated at coat_weight 0 and metallic 0 too (their terms are 0 there), so that the
 *   derivatives there are the ones from inside the range. Cost (tests/bench_brdf_grad.c, one thread): about 7.7 us
 *   per eval_grad, twice a prepare + eval (3.4 us, most of it the four 65-point averages, which eval_grad needs with
 *   their derivatives) and 50 times an eval with a prepared state (150 ns). Prepared derivatives (bp_grad_ops,
 *   brdf.h grad_ops: bp_prepare's half, with those averages, once per parameter set, for the slots a caller asks
 *   for only; the coat and the metal skipped where their weight is a constant 0 outside those slots): for the 5
 *   slots a fit solves, 0.40-0.47 us per evaluation, 1.9-3.9 us to prepare, the same numbers as eval_grad's
 *   (tests/test_brdf.c, prepared_gradient_equals_eval_grad_for_any_slots).
 */
#include "brdf_internal.h"
#include "dual.h"

/* Slots of the packed value vector. */
enum {
    BP_BASE = 0, BP_METALLIC = 3, BP_ROUGHNESS = 4, BP_IOR = 5, BP_LEVEL = 6, BP_TINT = 7, BP_COAT_WEIGHT = 10,
    BP_COAT_ROUGHNESS = 11, BP_COAT_IOR = 12, BP_COAT_TINT = 13, BP_MULTISCATTER = 16
};

#define BP_ROUGHNESS_MIN 0.01

static const mr_brdf_param bp_params[] = {
    {"base_color", 3, 0.8, 0.0, 1.0, MR_PARAM_NONLINEAR, MR_LOBE_BOTH, MR_PARAM_SRGB_MAP,
     "Base Color, linear RGB: Lambert albedo and metal F0", NULL},
    {"metallic", 1, 0.0, 0.0, 1.0, MR_PARAM_NONLINEAR, MR_LOBE_BOTH, 0, "Metallic", NULL},
    {"roughness", 1, 0.5, BP_ROUGHNESS_MIN, 1.0, MR_PARAM_NONLINEAR, MR_LOBE_BOTH, MR_PARAM_LOG_SCALE,
     "Roughness; GGX alpha = roughness^2 (metal and specular)", NULL},
    {"ior", 1, 1.5, 1.0, 3.0, MR_PARAM_NONLINEAR, MR_LOBE_BOTH, MR_PARAM_FIT_FIXED, "IOR of the dielectric", NULL},
    {"specular_ior_level", 1, 0.5, 0.0, 1.0, MR_PARAM_NONLINEAR, MR_LOBE_BOTH, MR_PARAM_FIT_FIXED,
     "Specular IOR Level: F0 = F0(ior) 2 level (0.5 keeps the ior)", NULL},
    {"specular_tint", 3, 1.0, 0.0, 1.0, MR_PARAM_NONLINEAR, MR_LOBE_BOTH, MR_PARAM_FIT_FIXED | MR_PARAM_SRGB_MAP,
     "Specular Tint: dielectric F0 tint (F90 = 1); the metal's F82 tint", NULL},
    {"coat_weight", 1, 0.0, 0.0, 1.0, MR_PARAM_NONLINEAR, MR_LOBE_BOTH, MR_PARAM_FIT_FIXED, "Coat Weight", NULL},
    {"coat_roughness", 1, 0.03, 0.0, 1.0, MR_PARAM_NONLINEAR, MR_LOBE_BOTH, MR_PARAM_FIT_FIXED,
     "Coat Roughness; alpha = max(r, 0.01)^2", NULL},
    {"coat_ior", 1, 1.5, 1.0, 3.0, MR_PARAM_NONLINEAR, MR_LOBE_BOTH, MR_PARAM_FIT_FIXED, "Coat IOR", NULL},
    {"coat_tint", 3, 1.0, 0.0, 1.0, MR_PARAM_NONLINEAR, MR_LOBE_BOTH, MR_PARAM_FIT_FIXED | MR_PARAM_SRGB_MAP,
     "Coat Tint: transmittance at normal incidence, one pass along the view ray", NULL},
    {"multiscatter", 1, 1.0, 0.0, 1.0, MR_PARAM_SWITCH, MR_LOBE_BOTH, MR_PARAM_FIT_FIXED,
     "1: Multiscatter GGX (the node's default), 0: GGX", NULL},
};

typedef struct bp_state {
    double r, alpha;            /* base lobes */
    double rho[3];              /* base_color */
    double metallic;
    double f0m[3], b[3];        /* metal F0 and F82 coefficient */
    double fss_m[3];            /* metal average Fresnel */
    double eta, f0;             /* dielectric specular: eta from ior and level, its F0 */
    double f0s[3];              /* saturate(f0 specular_tint) */
    double fss_s[3];            /* specular average Fresnel (tinted) */
    int spec;                   /* eta != 1 */
    double E_avg;               /* base lobes' E_avg(r) */
    int coat;
    double C, r_c, alpha_c, eta_c, f0_c, fss_c, E_avg_c, inv_eta_c2;
    double log_tint[3];
    int tint_black[3];
    int multiscatter;
} bp_state;

_Static_assert(sizeof(bp_state) <= MR_BRDF_STATE_BYTES, "bp_state must fit in MR_BRDF_STATE_BYTES");

static double bp_lerp(double a, double b, double t) { return a + (b - a) * t; }

/* microfacet_ggx_preserve_energy's darkening E + F_ms (1 - E), F_ms = F_ss E_avg/(1 - F_ss (1 - E_avg)): the
 * closure weight's factor. The lobe's scale is this times the energy scale 1/E: 1 + F_ms (1 - E)/E. */
static double bp_darkening(double E, double E_avg, double fss) {
    double fms = fss * E_avg / (1.0 - fss * (1.0 - E_avg));
    return E + fms * (1.0 - E);
}

/* Cycles' estimate s of the remap weight: (E_F - F0 E)/((1 - F0) E), clamped into [0, 1]. */
static double bp_estimate_s(double mu, double r, double eps, double f0) {
    double E = MR_MAX(mr_ggx_albedo_one(mu, r), 1e-6);
    return mr_clampd((mr_ggx_albedo_dielectric(mu, r, eps) - f0 * E) / ((1.0 - f0) * E), 0.0, 1.0);
}

static void bp_prepare(const mr_brdf_model *model, const double *values, void *state_bytes) {
    bp_state *st = state_bytes;
    double v[MR_BRDF_MAX_VALUES];
    mr_brdf_clamp_values(model, values, v);
    st->r = MR_MAX(v[BP_ROUGHNESS], BP_ROUGHNESS_MIN);
    st->alpha = st->r * st->r;
    st->metallic = v[BP_METALLIC];
    st->multiscatter = v[BP_MULTISCATTER] >= 0.5;
    st->E_avg = mr_ggx_albedo_one_avg(st->r);

    double ior = v[BP_IOR], f0_ior = (ior - 1.0) / (ior + 1.0);
    double f0 = MR_MIN(f0_ior * f0_ior * 2.0 * v[BP_LEVEL], 0.99); /* ior_from_F0 clamps F0 to 0.99 */
    st->f0 = f0;
    st->eta = (1.0 + sqrt(f0)) / (1.0 - sqrt(f0));
    st->spec = f0 > 0.0;
    double s_avg = st->spec ? mr_clampd((mr_fresnel_dielectric_avg(st->eta) - f0) / (1.0 - f0), 0.0, 1.0) : 0.0;
    for (int c = 0; c < 3; c++) {
        st->rho[c] = v[BP_BASE + c];
        st->f0m[c] = v[BP_BASE + c];
        st->b[c] = mr_f82_coeff(st->f0m[c], v[BP_TINT + c]);
        st->fss_m[c] = bp_lerp(st->f0m[c], 1.0, 1.0 / 21.0) - st->b[c] / 126.0;
        st->f0s[c] = mr_clampd(f0 * v[BP_TINT + c], 0.0, 1.0);
        st->fss_s[c] = bp_lerp(st->f0s[c], 1.0, s_avg);
    }

    st->C = v[BP_COAT_WEIGHT];
    st->coat = st->C > 0.0;
    st->r_c = MR_MAX(v[BP_COAT_ROUGHNESS], BP_ROUGHNESS_MIN);
    st->alpha_c = st->r_c * st->r_c;
    st->eta_c = v[BP_COAT_IOR];
    double q = (st->eta_c - 1.0) / (st->eta_c + 1.0);
    st->f0_c = q * q;
    st->fss_c = st->eta_c > 1.0 ? mr_fresnel_dielectric_avg(st->eta_c) : 0.0;
    st->E_avg_c = mr_ggx_albedo_one_avg(st->r_c);
    st->inv_eta_c2 = 1.0 / (st->eta_c * st->eta_c);
    for (int c = 0; c < 3; c++) {
        double t = v[BP_COAT_TINT + c];
        st->tint_black[c] = !(t > 0.0);
        st->log_tint[c] = t > 0.0 ? log(t) : 0.0;
    }
}

static void bp_eval(const void *state_bytes, const double wi[3], const double wo[3], double diffuse[3],
                    double specular[3]) {
    const bp_state *st = state_bytes;
    mr_brdf_geom g;
    if (!mr_brdf_geom_init(wi, wo, &g)) {
        mr_brdf_zero(diffuse, specular);
        return;
    }
    double mu_v = MR_MIN(g.cos_i, 1.0);
    double w[3] = {1.0, 1.0, 1.0}, spec[3] = {0.0, 0.0, 0.0};

    if (st->coat) {
        double E_c = MR_MAX(mr_ggx_albedo_one(mu_v, st->r_c), 1e-6);
        /* bsdf_microfacet_setup_fresnel_dielectric preserves the coat's energy whatever the node's distribution */
        double dark = bp_darkening(E_c, st->E_avg_c, st->fss_c), scale = dark / E_c;
        double F = st->eta_c > 1.0 ? mr_fresnel_dielectric(g.dot_h, st->eta_c, NULL) : 0.0;
        double lobe = st->C * F * mr_ggx_dv_correlated(st->alpha_c, &g, NULL) * scale;
        double est = st->eta_c > 1.0 ? bp_lerp(st->f0_c, 1.0, bp_estimate_s(mu_v, st->r_c, sqrt(st->f0_c), st->f0_c))
                                     : 0.0;
        /* bsdf_albedo is the closure weight (darkened) times the estimate */
        double keep = mr_clampd(1.0 - st->C * dark * est, 0.0, 1.0);
        /* the view ray refracted into the coat; coat_ior >= 1, so cos_t >= mu_v > 0 */
        double cos_t = sqrt(MR_MAX(1.0 - g.sin2_i * st->inv_eta_c2, 0.0));
        double depth = 1.0 / MR_MAX(cos_t, MR_BRDF_COS_MIN);
        for (int c = 0; c < 3; c++) {
            spec[c] = lobe;
            double T = st->tint_black[c] ? 0.0 : exp(st->log_tint[c] * depth);
            w[c] = keep * bp_lerp(1.0, T, st->C);
        }
    }

    double DV = mr_ggx_dv_correlated(st->alpha, &g, NULL);
    double E = MR_MAX(mr_ggx_albedo_one(mu_v, st->r), 1e-6);
    if (st->metallic > 0.0) {
        for (int c = 0; c < 3; c++) {
            double scale = st->multiscatter ? bp_darkening(E, st->E_avg, st->fss_m[c]) / E : 1.0;
            spec[c] += st->metallic * w[c] * mr_f82_tint(g.dot_h, st->f0m[c], st->b[c]) * DV * scale;
            w[c] *= 1.0 - st->metallic;
        }
    }
    if (st->spec) {
        double sF = mr_clampd((mr_fresnel_dielectric(g.dot_h, st->eta, NULL) - st->f0) / (1.0 - st->f0), 0.0, 1.0);
        double s_est = bp_estimate_s(mu_v, st->r, sqrt(st->f0), st->f0), est_max = 0.0;
        for (int c = 0; c < 3; c++) {
            double dark = st->multiscatter ? bp_darkening(E, st->E_avg, st->fss_s[c]) : 1.0;
            double scale = st->multiscatter ? dark / E : 1.0;
            spec[c] += w[c] * bp_lerp(st->f0s[c], 1.0, sF) * DV * scale;
            est_max = MR_MAX(est_max, dark * bp_lerp(st->f0s[c], 1.0, s_est));
        }
        double keep = mr_clampd(1.0 - est_max, 0.0, 1.0);
        for (int c = 0; c < 3; c++) w[c] *= keep;
    }
    for (int c = 0; c < 3; c++) {
        if (diffuse) diffuse[c] = w[c] * st->rho[c] * MR_INV_PI;
        if (specular) specular[c] = spec[c];
    }
}

/* bp_darkening and bp_estimate_s in dual numbers */
static mr_dual bp_dual_darkening(mr_dual_tape *tp, mr_dual E, mr_dual E_avg, mr_dual fss) {
    mr_dual fms = mr_dual_div(tp, mr_dual_mul(tp, fss, E_avg),
                              mr_dual_rsubc(tp, 1.0, mr_dual_mul(tp, fss, mr_dual_rsubc(tp, 1.0, E_avg))));
    return mr_dual_add(tp, E, mr_dual_mul(tp, fms, mr_dual_rsubc(tp, 1.0, E)));
}

static mr_dual bp_dual_estimate_s(mr_dual_tape *tp, double mu, mr_dual r, mr_dual eps, mr_dual f0) {
    mr_dual E = mr_dual_maxc(mr_dual_albedo_one(tp, mu, r), 1e-6);
    mr_dual num = mr_dual_sub(tp, mr_dual_albedo_dielectric(tp, mu, r, eps), mr_dual_mul(tp, f0, E));
    return mr_dual_clampc(mr_dual_div(tp, num, mr_dual_mul(tp, mr_dual_rsubc(tp, 1.0, f0), E)), 0.0, 1.0);
}

/* d f_r / d values[j]: bp_prepare and bp_eval transcribed in dual numbers (dual.h), operation for operation, so the
 * value part is eval's to rounding. Differences from eval's branches, all where eval's value is unchanged: the coat
 * is evaluated at coat_weight 0 and the metal at metallic 0 (their terms are then 0 or 1, and their derivatives give
 * the one-sided derivatives a fit starting there needs). The multiscatter switch's derivative is 0.
 * Two halves: bp_grad_prepare_duals (bp_prepare's part, no direction) and bp_grad_eval_duals (bp_eval's), so that a
 * prepared derivative state (bp_grad_ops, brdf.h) does the first once per parameter set; eval_grad runs both. */

/* What bp_grad_eval_duals takes from bp_grad_prepare_duals: the clamped values, their duals and bp_prepare's. */
typedef struct bp_grad_prep {
    double v[MR_BRDF_MAX_VALUES];
    mr_dual x[MR_DUAL_N];
    int multiscatter, spec_on;
    mr_dual r, alpha, metallic, E_avg, f0, sqrt_f0, eta, C, r_c, alpha_c, eta_c, f0_c, fss_c, E_avg_c, inv_eta_c2;
    mr_dual rho[3], b[3], fss_m[3], f0s[3], fss_s[3];
} bp_grad_prep;

_Static_assert(sizeof(bp_grad_prep) <= MR_DUAL_PREP_BYTES, "bp_grad_prep must fit in a mr_dual_grad_state");

/* bp_prepare in duals: p->v and p->x given (x[BP_MULTISCATTER] a constant) */
static void bp_grad_prepare_duals(mr_dual_tape *tp, bp_grad_prep *p) {
    const double *v = p->v;
    const mr_dual *x = p->x;
    const mr_dual one = mr_dual_const(1.0);
    mr_dual r = mr_dual_maxc(x[BP_ROUGHNESS], BP_ROUGHNESS_MIN), alpha = mr_dual_sq(tp, r), metallic = x[BP_METALLIC];
    int multiscatter = v[BP_MULTISCATTER] >= 0.5;
    mr_dual E_avg = mr_dual_albedo_one_avg(tp, r);
    mr_dual ior = x[BP_IOR], f0_ior = mr_dual_div(tp, mr_dual_addc(tp, ior, -1.0), mr_dual_addc(tp, ior, 1.0));
    mr_dual f0 = mr_dual_minc(mr_dual_mul(tp, mr_dual_scale(tp, mr_dual_sq(tp, f0_ior), 2.0), x[BP_LEVEL]), 0.99);
    mr_dual sqrt_f0 = mr_dual_sqrt(tp, f0);
    mr_dual eta = mr_dual_div(tp, mr_dual_addc(tp, sqrt_f0, 1.0), mr_dual_rsubc(tp, 1.0, sqrt_f0));
    int spec_on = f0.v > 0.0;
    mr_dual s_avg = spec_on
                        ? mr_dual_clampc(mr_dual_div(tp, mr_dual_sub(tp, mr_dual_fresnel_dielectric_avg(tp, eta), f0),
                                                     mr_dual_rsubc(tp, 1.0, f0)),
                                         0.0, 1.0)
                        : mr_dual_const(0.0);
    mr_dual rho[3], b[3], fss_m[3], f0s[3], fss_s[3];
    for (int c = 0; c < 3; c++) {
        rho[c] = x[BP_BASE + c];
        b[c] = mr_dual_f82_coeff(tp, rho[c], x[BP_TINT + c]);
        fss_m[c] = mr_dual_sub(tp, mr_dual_lerp(tp, rho[c], one, mr_dual_const(1.0 / 21.0)),
                               mr_dual_scale(tp, b[c], 1.0 / 126.0));
        f0s[c] = mr_dual_clampc(mr_dual_mul(tp, f0, x[BP_TINT + c]), 0.0, 1.0);
        fss_s[c] = mr_dual_lerp(tp, f0s[c], one, s_avg);
    }
    mr_dual C = x[BP_COAT_WEIGHT];
    mr_dual r_c = mr_dual_maxc(x[BP_COAT_ROUGHNESS], BP_ROUGHNESS_MIN), alpha_c = mr_dual_sq(tp, r_c);
    mr_dual eta_c = x[BP_COAT_IOR];
    mr_dual f0_c = mr_dual_sq(tp, mr_dual_div(tp, mr_dual_addc(tp, eta_c, -1.0), mr_dual_addc(tp, eta_c, 1.0)));
    mr_dual fss_c = eta_c.v > 1.0 ? mr_dual_fresnel_dielectric_avg(tp, eta_c) : mr_dual_const(0.0);
    mr_dual E_avg_c = mr_dual_albedo_one_avg(tp, r_c);
    mr_dual inv_eta_c2 = mr_dual_recip(tp, mr_dual_sq(tp, eta_c));

    p->multiscatter = multiscatter, p->spec_on = spec_on;
    p->r = r, p->alpha = alpha, p->metallic = metallic, p->E_avg = E_avg, p->f0 = f0, p->sqrt_f0 = sqrt_f0;
    p->eta = eta, p->C = C, p->r_c = r_c, p->alpha_c = alpha_c, p->eta_c = eta_c, p->f0_c = f0_c, p->fss_c = fss_c;
    p->E_avg_c = E_avg_c, p->inv_eta_c2 = inv_eta_c2;
    for (int c = 0; c < 3; c++)
        p->rho[c] = rho[c], p->b[c] = b[c], p->fss_m[c] = fss_m[c], p->f0s[c] = f0s[c], p->fss_s[c] = fss_s[c];
}

/* bp_eval in duals at the geometry g of (wi, wo) */
static void bp_grad_eval_duals(const bp_grad_prep *p, mr_dual_tape *tp, const mr_brdf_geom *gp, mr_dual diffuse[3],
                               mr_dual spec[3]) {
    const mr_brdf_geom g = *gp;
    const double *v = p->v;
    const mr_dual *x = p->x;
    const mr_dual one = mr_dual_const(1.0);
    int multiscatter = p->multiscatter, spec_on = p->spec_on;
    mr_dual r = p->r, alpha = p->alpha, metallic = p->metallic, E_avg = p->E_avg, f0 = p->f0, sqrt_f0 = p->sqrt_f0;
    mr_dual eta = p->eta, C = p->C, r_c = p->r_c, alpha_c = p->alpha_c, eta_c = p->eta_c, f0_c = p->f0_c;
    mr_dual fss_c = p->fss_c, E_avg_c = p->E_avg_c, inv_eta_c2 = p->inv_eta_c2;
    const mr_dual *rho = p->rho, *b = p->b, *fss_m = p->fss_m, *f0s = p->f0s, *fss_s = p->fss_s;
    /* bp_eval: the coat, at coat_weight 0 too (see above) */
    double mu_v = MR_MIN(g.cos_i, 1.0);
    mr_dual w[3];
    if (mr_dual_is_const_zero(C)) { /* a prepared state holding coat_weight at 0: no coat (mr_dual_is_const_zero) */
        for (int c = 0; c < 3; c++) w[c] = one, spec[c] = mr_dual_const(0.0);
    } else {
        mr_dual E_c = mr_dual_maxc(mr_dual_albedo_one(tp, mu_v, r_c), 1e-6);
        mr_dual dark = bp_dual_darkening(tp, E_c, E_avg_c, fss_c), scale = mr_dual_div(tp, dark, E_c);
        mr_dual F = eta_c.v > 1.0 ? mr_dual_fresnel_dielectric(tp, g.dot_h, eta_c) : mr_dual_const(0.0);
        mr_dual lobe = mr_dual_mul(tp, mr_dual_mul(tp, mr_dual_mul(tp, C, F), mr_dual_ggx_dv(tp, alpha_c, &g)), scale);
        mr_dual est = eta_c.v > 1.0
                          ? mr_dual_lerp(tp, f0_c, one, bp_dual_estimate_s(tp, mu_v, r_c, mr_dual_sqrt(tp, f0_c), f0_c))
                          : mr_dual_const(0.0);
        mr_dual keep = mr_dual_clampc(mr_dual_rsubc(tp, 1.0, mr_dual_mul(tp, mr_dual_mul(tp, C, dark), est)), 0.0, 1.0);
        mr_dual cos_t =
            mr_dual_sqrt(tp, mr_dual_maxc(mr_dual_rsubc(tp, 1.0, mr_dual_scale(tp, inv_eta_c2, g.sin2_i)), 0.0));
        mr_dual depth = mr_dual_recip(tp, mr_dual_maxc(cos_t, MR_BRDF_COS_MIN));
        for (int c = 0; c < 3; c++) {
            spec[c] = lobe;
            mr_dual T = v[BP_COAT_TINT + c] > 0.0
                            ? mr_dual_exp(tp, mr_dual_mul(tp, mr_dual_log(tp, x[BP_COAT_TINT + c]), depth))
                            : mr_dual_const(0.0);
            w[c] = mr_dual_mul(tp, keep, mr_dual_lerp(tp, one, T, C));
        }
    }

    mr_dual DV = mr_dual_ggx_dv(tp, alpha, &g);
    mr_dual E = mr_dual_maxc(mr_dual_albedo_one(tp, mu_v, r), 1e-6);
    /* the metal, at metallic 0 too, unless a prepared state holds it at a constant 0 */
    for (int c = 0; c < 3 && !mr_dual_is_const_zero(metallic); c++) {
        mr_dual scale = multiscatter ? mr_dual_div(tp, bp_dual_darkening(tp, E, E_avg, fss_m[c]), E) : one;
        mr_dual metal = mr_dual_mul(tp, mr_dual_mul(tp, mr_dual_f82_tint(tp, g.dot_h, rho[c], b[c]), DV), scale);
        spec[c] = mr_dual_add(tp, spec[c], mr_dual_mul(tp, mr_dual_mul(tp, metallic, w[c]), metal));
        w[c] = mr_dual_mul(tp, w[c], mr_dual_rsubc(tp, 1.0, metallic));
    }
    if (spec_on) {
        mr_dual F = mr_dual_fresnel_dielectric(tp, g.dot_h, eta);
        mr_dual sF = mr_dual_clampc(mr_dual_div(tp, mr_dual_sub(tp, F, f0), mr_dual_rsubc(tp, 1.0, f0)), 0.0, 1.0);
        mr_dual s_est = bp_dual_estimate_s(tp, mu_v, r, sqrt_f0, f0), est_max = mr_dual_const(0.0);
        for (int c = 0; c < 3; c++) {
            mr_dual dark = multiscatter ? bp_dual_darkening(tp, E, E_avg, fss_s[c]) : one;
            mr_dual scale = multiscatter ? mr_dual_div(tp, dark, E) : one;
            mr_dual lobe = mr_dual_mul(tp, mr_dual_mul(tp, mr_dual_lerp(tp, f0s[c], one, sF), DV), scale);
            spec[c] = mr_dual_add(tp, spec[c], mr_dual_mul(tp, w[c], lobe));
            est_max = mr_dual_max(tp, est_max, mr_dual_mul(tp, dark, mr_dual_lerp(tp, f0s[c], one, s_est)));
        }
        mr_dual keep = mr_dual_clampc(mr_dual_rsubc(tp, 1.0, est_max), 0.0, 1.0);
        for (int c = 0; c < 3; c++) w[c] = mr_dual_mul(tp, w[c], keep);
    }
    for (int c = 0; c < 3; c++) diffuse[c] = mr_dual_scale(tp, mr_dual_mul(tp, w[c], rho[c]), MR_INV_PI);
}

static void bp_grad_prepare(const mr_brdf_model *model, const double *values, const int *slots, int count,
                            void *state) {
    mr_dual_grad_state *st = state;
    bp_grad_prep *p = (bp_grad_prep *)st->prep.bytes;
    mr_dual_grad_state_begin(model, values, slots, count, st, p->v, p->x);
    p->x[BP_MULTISCATTER] = mr_dual_const(p->v[BP_MULTISCATTER]);
    bp_grad_prepare_duals(&st->tape, p);
}

static void bp_grad_eval(const void *state, const double wi[3], const double wo[3], double *d_diffuse,
                         double *d_specular) {
    const mr_dual_grad_state *st = state;
    mr_brdf_geom g;
    if (!mr_dual_grad_eval_begin(st, wi, wo, d_diffuse, d_specular, &g)) return;
    double scratch[MR_DUAL_SCRATCH];
    mr_dual_tape tape;
    mr_dual_tape_init(&tape, scratch, MR_DUAL_SCRATCH, st->count);
    mr_dual diffuse[3], spec[3];
    bp_grad_eval_duals((const bp_grad_prep *)st->prep.bytes, &tape, &g, diffuse, spec);
    mr_dual_store_grad(diffuse, spec, st->count, d_diffuse, d_specular);
}

static const mr_brdf_grad_ops bp_grad_ops = {sizeof(mr_dual_grad_state), bp_grad_prepare, bp_grad_eval, NULL, NULL};

/* eval_grad: every slot, through the prepared path (dual.h, mr_dual_eval_grad). */
static void bp_eval_grad(const mr_brdf_model *model, const double *values, const double wi[3], const double wo[3],
                         double *d_diffuse, double *d_specular) {
    mr_dual_eval_grad(&bp_grad_ops, model, values, wi, wo, d_diffuse, d_specular);
}

_Static_assert(17 <= MR_DUAL_N, "blender-principled's 17 packed values need as many dual slots");

const mr_brdf_model mr_brdf_blender_principled = {
    .name = "blender-principled",
    .summary = "Blender 4.2 Cycles Principled BSDF: coat, F82-tint metal, GGX specular over Lambert, albedo-layered",
    .source = "Blender 4.2 intern/cycles/kernel/svm/closure.h, closure/bsdf_microfacet.h, closure/bsdf_util.h",
    .param_count = (int)(sizeof bp_params / sizeof bp_params[0]),
    .params = bp_params,
    .flags = MR_BRDF_NON_RECIPROCAL,
    .config = NULL,
    .prepare = bp_prepare,
    .eval = bp_eval,
    .eval_grad = bp_eval_grad,
    .grad_ops = &bp_grad_ops,
};
