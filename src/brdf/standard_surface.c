/*
 * standard_surface.c — `standard-surface`: Autodesk Standard Surface 1.0.1, its opaque reflection layers (coat over
 * metal/specular over diffuse); isotropic. Section names below are those of the specification (Autodesk/
 * standard-surface, index.html); the reference graph is reference/standard_surface.mtlx (MaterialX nodegraph
 * NG_standard_surface_surfaceshader_100, which 1.0.1 reuses with new defaults).
 *
 *   Closures ("Closures"; each a GGX lobe with alpha = roughness^2 and the height-correlated Smith V):
 *     coat_brdf     = F_d(wi.h; coat_ior) D V(alpha_c),     alpha_c = coat_roughness^2            ("Coating")
 *     specular_brdf = F_d(wi.h; specular_ior) D V(alpha_s)                                ("Specular reflection")
 *     metal_brdf    = F_c(wi.h; n, k) D V(alpha_s)                                              ("Metal")
 *     diffuse_brdf  = (A + B max(0, cos(phi_i - phi_o)) sin(a) tan(b))/pi      ("Diffuse reflection": Oren-Nayar)
 *   F_d is the exact dielectric Fresnel, F_c the exact conductor Fresnel (brdf_internal.h), D the GGX distribution,
 *   V = G2/(4 cos_i cos_o) Smith's height-correlated masking-shadowing, as the reference graph's dielectric_bsdf and
 *   conductor_bsdf (MaterialX pbrlib) use.
 *   Metal ("Metal"): n + ik from Gulbrandsen's artistic IOR (mr_artistic_ior, brdf_internal.h), reflectivity
 *     r = base base_color, edge tint g = specular specular_color; so F_c at normal incidence is base base_color.
 *   Oren-Nayar: the qualitative model of Oren & Nayar 1994 (their eq. 30), sigma = diffuse_roughness in radians as
 *     the reference graph passes it: A = 1 - 0.5 s/(s + 0.33), B = 0.45 s/(s + 0.09), s = sigma^2, a = max(theta_i,
 *     theta_o), b = min; written as B (wi.wo - cos_i cos_o)/max(cos_i, cos_o) where that is positive. sigma = 0
 *     gives Lambert exactly (A = 1, B = 0).
 *   Layering, the spec's closure weights with E(x) = reflectance(x), the directional albedo at the VIEW direction
 *   (wi; render.c evaluates f(view, light)):
 *     specular_reflection_layer = s sc specular_brdf + (1 - s sc E_s(wi)) base bc' diffuse_brdf
 *                                                    ("Specular reflection"; transmission, sheen, subsurface = 0)
 *     specular_mixture = metalness metal_brdf + (1 - metalness) specular_reflection_layer               ("Metal")
 *     coat_layer = coat coat_brdf + ((1 - coat) + coat coat_color (1 - E_c(wi))) specular_mixture       ("Coating")
 *   with s = specular, sc = specular_color, bc' = base_color^(1 + coat coat_affect_color) (coat_affect_color) and
 *   alpha_s = lerp(specular_roughness, 1, coat coat_affect_roughness coat_roughness)^2 (coat_affect_roughness),
 *   both from "Coating". The reference graph writes the coat tint as mix(1, coat_color, coat) (1 - coat E_c): the
 *   same at coat_color = 1 or coat in {0, 1}; this model follows the specification's formula.
 *   Split: diffuse part = the diffuse_brdf term with all its weights; specular part = the rest.
 *
 * Directional albedos E_s, E_c: the specification assumes a reflectance() function and leaves its computation
 *   open. Here E(mu; r, eta) of the F_d D V lobe is the library's one GGX albedo table, shared with openpbr and
 *   blender-principled (layering.c, ggx_albedo_tables.h, written by scripts/gen-ggx-albedo.c with a half-vector
 *   quadrature of this lobe), interpolated linearly in sqrt(mu), sqrt((r - 0.01)/0.99) and sqrt((eta - 1)/2).
 *   prepare() finds the (r, eta) cells and fractions once per lobe (mr_ggx_albedo_slice_init); eval() finishes the
 *   trilinear lookup at sqrt(cos_i), in double, the value mr_ggx_albedo_dielectric gives bit for bit. (Until
 *   issue 31 prepare stored a 41-node float curve per lobe; its float rounding, ~1e-7 of E, made f a staircase at
 *   the scale central differences of the derivative test resolve, 4e-4 relative errors in d f/d specular_ior.)
 *   Accuracy, seen as |albedo - 1| of a dielectric over a
 *   white Lambert base (which is exactly 1 with exact albedos; white furnace of tests/test_brdf.c, whose own
 *   quadrature error is ~1e-3 towards grazing): <= 0.0057 over ior 1.05-3, roughness 0.01-1 and 0-88 degrees;
 *   <= 0.0008 up to 80 degrees (E changes fastest near grazing, most for ior near 1, where Fresnel has its sharp
 *   knee). The table is const data: thread-safe, nothing computed at run time.
 *
 * Parameters (the specification's names, lowercased: the command line's identifiers are lowercase (brdf.h), so
 * specular_IOR is `specular_ior` and coat_IOR is `coat_ior`; defaults of version 1.0.1; ranges the soft ranges):
 *   base                 [0, 1]     default 1    weight of the diffuse lobe and factor of the metal's reflectivity.
 *                                                Fits hold it (only base base_color is visible).
 *   base_color      RGB  [0, 1]     default 0.8  diffuse colour and metal reflectivity (sRGB maps). NONLINEAR: the
 *                                                metal's Fresnel depends on it through n, k.
 *   diffuse_roughness    [0, 1]     default 0    Oren-Nayar sigma (radians); 0 = Lambert. Fits hold it (default hold,
 *                                                below).
 *   metalness            [0, 1]     default 0    AFFINE: the specification's statistical mix.
 *   specular             [0, 1]     default 1    dielectric specular weight and metal edge-tint factor. Fits hold it.
 *   specular_color  RGB  [0, 1]     default 1    dielectric tint and metal edge tint (sRGB maps). Fits hold it.
 *   specular_roughness   [0.01, 1]  default 0.2  alpha = r^2; 0.01 (alpha = 1e-4) is the floor, as other models here.
 *   specular_ior         [1, 3]     default 1.5  dielectric F0 = ((ior - 1)/(ior + 1))^2 s sc. Fits hold it.
 *   coat                 [0, 1]     default 0    coat weight. Fits hold it (a remap should not invent a coat).
 *   coat_color      RGB  [0, 1]     default 1    tint of everything below the coat (sRGB maps). Fits hold it.
 *   coat_roughness       [0.01, 1]  default 0.1  alpha_c = r^2. Fits hold it.
 *   coat_ior             [1, 3]     default 1.5  the coat's index. Fits hold it.
 *   coat_affect_color    [0, 1]     default 0    in the model because f_r changes with it where coat > 0; fits hold
 *   coat_affect_roughness[0, 1]     default 0    both, since a fit cannot tell them from base_color and
 *                                                specular_roughness.
 *   Every colour enters nonlinearly somewhere (the metal's n, k; the albedo-weighted layering), so only metalness
 *   is AFFINE; coat_color would be affine as well, but not jointly with metalness (their product appears).
 *
 * Default holds (what a fit holds unless given other values with --to or --hold NAME=VALUE; every fit prints them):
 *   base=1, diffuse_roughness=0, specular=1, specular_color=1, specular_ior=1.5 and the coat (coat=0 ...); a fit
 *   solves base_color, metalness and specular_roughness. A fit scene cannot tell base from base_color, specular
 *   from specular_ior, nor a little Oren-Nayar from a darker Lambert with a broader specular. Measured on six Ward
 *   materials (fit scene 32^2): holding diffuse_roughness too turned 1 at-bound fit into a converged one (4 of 6
 *   converged instead of 3; the others: one under-resolved lobe, one Ward highlight no model here reaches), SSIM
 *   within 0.001 of the free fit, in half the renders (1246-2950 against 1938-5070).
 *
 * Out of scope (not parameters; documents carry them): opacity/transparency, emission, transmission (and its
 * colour, depth, scatter, dispersion, extra roughness), subsurface (all its parameters), sheen, thin film,
 * anisotropy and rotation (specular and coat), normal and coat_normal, tangent, thin_walled.
 * Reciprocity: flagged MR_BRDF_NON_RECIPROCAL. The specification's weights 1 - E(wi) depend on the incoming (view)
 * direction only; its section "Reciprocity" says so and accepts it. f(wi, wo) = f(wo, wi) holds when specular = 0
 * and coat = 0.
 * Energy: conserving by the specification's construction (white furnace at the view direction: coat E_c +
 * (1 - coat E_c) (...) <= 1 for any lower layer of albedo <= 1), up to the table's error above. Single-scattering
 * GGX loses energy at high roughness, as in the reference graph without its energy compensation.
 * Derivatives: analytic, every slot (ss_eval_grad): prepare and eval transcribed in forward-mode dual numbers (dual.h),
 * through Gulbrandsen's n, k and the exact conductor Fresnel's derivatives, and the albedo table's interpolation
 * differentiated cell by cell (layering.c; one-sided at cell boundaries: specular_ior 1.5 is the node eta = 1.5). At
 * coat 0, metalness 0 and coat_affect_color 0 (defaults) the derivatives are the one-sided ones from inside the range.
 * Cost (tests/bench_brdf_grad.c, one thread): about 2.1 us per eval_grad, 30 times an eval with a prepared state
 * (70 ns) and 14 times a prepare + eval (155 ns). Prepared derivatives (ss_grad_ops, brdf.h grad_ops: ss_prepare's
 * half once per parameter set, for the slots a caller asks for only; the coat and the metal skipped where their
 * weight is a constant 0 outside those slots): for the 5 slots a fit solves, 0.24-0.28 us per evaluation, 0.25 us
 * to prepare, the same numbers as eval_grad's (tests/test_brdf.c, prepared_gradient_equals_eval_grad_for_any_slots).
 */
#include "brdf_internal.h"
#include "dual.h"

/* Slots of the packed value vector. */
enum {
    SS_BASE = 0, SS_BASE_COLOR = 1, SS_DIFFUSE_ROUGHNESS = 4, SS_METALNESS = 5, SS_SPECULAR = 6,
    SS_SPECULAR_COLOR = 7, SS_SPECULAR_ROUGHNESS = 10, SS_SPECULAR_IOR = 11, SS_COAT = 12, SS_COAT_COLOR = 13,
    SS_COAT_ROUGHNESS = 16, SS_COAT_IOR = 17, SS_COAT_AFFECT_COLOR = 18, SS_COAT_AFFECT_ROUGHNESS = 19
};

#define SS_HELD MR_PARAM_FIT_FIXED

static const mr_brdf_param ss_params[] = {
    {"base", 1, 1.0, 0.0, 1.0, MR_PARAM_NONLINEAR, MR_LOBE_BOTH, SS_HELD,
     "base: weight of the diffuse lobe, factor of the metal reflectivity", NULL},
    {"base_color", 3, 0.8, 0.0, 1.0, MR_PARAM_NONLINEAR, MR_LOBE_BOTH, MR_PARAM_SRGB_MAP,
     "base_color, linear RGB: diffuse colour; metal reflectivity = base base_color (Gulbrandsen)", NULL},
    {"diffuse_roughness", 1, 0.0, 0.0, 1.0, MR_PARAM_NONLINEAR, MR_LOBE_DIFFUSE, SS_HELD,
     "diffuse_roughness: Oren-Nayar sigma in radians; 0 = Lambert", NULL},
    {"metalness", 1, 0.0, 0.0, 1.0, MR_PARAM_AFFINE, MR_LOBE_BOTH, 0,
     "metalness: mix of metal_brdf and the dielectric specular/diffuse layers", NULL},
    {"specular", 1, 1.0, 0.0, 1.0, MR_PARAM_NONLINEAR, MR_LOBE_BOTH, SS_HELD,
     "specular: dielectric specular weight; metal edge tint = specular specular_color", NULL},
    {"specular_color", 3, 1.0, 0.0, 1.0, MR_PARAM_NONLINEAR, MR_LOBE_BOTH, SS_HELD | MR_PARAM_SRGB_MAP,
     "specular_color, linear RGB: dielectric specular tint and metal edge tint", NULL},
    {"specular_roughness", 1, 0.2, 0.01, 1.0, MR_PARAM_NONLINEAR, MR_LOBE_BOTH, MR_PARAM_LOG_SCALE,
     "specular_roughness: GGX alpha = roughness^2 (metal and dielectric specular)", NULL},
    {"specular_ior", 1, 1.5, 1.0, 3.0, MR_PARAM_NONLINEAR, MR_LOBE_BOTH, SS_HELD,
     "specular_IOR: dielectric specular index (F0 = ((ior-1)/(ior+1))^2)", NULL},
    {"coat", 1, 0.0, 0.0, 1.0, MR_PARAM_NONLINEAR, MR_LOBE_BOTH, SS_HELD, "coat: weight of the clear coat", NULL},
    {"coat_color", 3, 1.0, 0.0, 1.0, MR_PARAM_NONLINEAR, MR_LOBE_BOTH, SS_HELD | MR_PARAM_SRGB_MAP,
     "coat_color, linear RGB: tint of the layers below the coat", NULL},
    {"coat_roughness", 1, 0.1, 0.01, 1.0, MR_PARAM_NONLINEAR, MR_LOBE_BOTH,
     SS_HELD | MR_PARAM_LOG_SCALE, "coat_roughness: coat GGX alpha = roughness^2", NULL},
    {"coat_ior", 1, 1.5, 1.0, 3.0, MR_PARAM_NONLINEAR, MR_LOBE_BOTH, SS_HELD, "coat_IOR: the coat's index", NULL},
    {"coat_affect_color", 1, 0.0, 0.0, 1.0, MR_PARAM_NONLINEAR, MR_LOBE_DIFFUSE, SS_HELD,
     "coat_affect_color: diffuse colour = base_color^(1 + coat coat_affect_color)", NULL},
    {"coat_affect_roughness", 1, 0.0, 0.0, 1.0, MR_PARAM_NONLINEAR, MR_LOBE_BOTH, SS_HELD,
     "coat_affect_roughness: specular roughness -> lerp(r, 1, coat coat_affect_roughness coat_roughness)", NULL},
};

typedef struct ss_state {
    double alpha_s, alpha_c;   /* specular/metal and coat GGX alpha */
    double eta_s, eta_c;       /* specular_ior, coat_ior */
    double metalness, coat;
    double spec_w[3];          /* specular specular_color */
    double coat_tint[3];       /* coat coat_color */
    double diffuse_over_pi[3]; /* base bc' / pi */
    double on_a, on_b;         /* Oren-Nayar A, B */
    double metal_n[3], metal_k[3];
    mr_ggx_albedo_slice e_s, e_c; /* the albedo table's (roughness, ior) cells of E_s and E_c */
} ss_state;

_Static_assert(sizeof(ss_state) <= MR_BRDF_STATE_BYTES, "ss_state must fit in MR_BRDF_STATE_BYTES");

static void ss_prepare(const mr_brdf_model *model, const double *values, void *state_bytes) {
    ss_state *st = state_bytes;
    double v[MR_BRDF_MAX_VALUES];
    mr_brdf_clamp_values(model, values, v);
    double coat = v[SS_COAT];
    double rough_s = v[SS_SPECULAR_ROUGHNESS], rough_c = v[SS_COAT_ROUGHNESS];
    double affect = coat * v[SS_COAT_AFFECT_ROUGHNESS] * rough_c;
    rough_s = rough_s + (1.0 - rough_s) * affect; /* lerp(roughness, 1, ...), "Coating" */
    st->alpha_s = rough_s * rough_s;
    st->alpha_c = rough_c * rough_c;
    st->eta_s = v[SS_SPECULAR_IOR];
    st->eta_c = v[SS_COAT_IOR];
    st->metalness = v[SS_METALNESS];
    st->coat = coat;
    double gamma = 1.0 + coat * v[SS_COAT_AFFECT_COLOR];
    double sigma2 = v[SS_DIFFUSE_ROUGHNESS] * v[SS_DIFFUSE_ROUGHNESS];
    st->on_a = 1.0 - 0.5 * sigma2 / (sigma2 + 0.33);
    st->on_b = 0.45 * sigma2 / (sigma2 + 0.09);
    for (int c = 0; c < 3; c++) {
        double bc = v[SS_BASE_COLOR + c];
        double bc_diffuse = gamma == 1.0 ? bc : pow(bc, gamma);
        st->diffuse_over_pi[c] = v[SS_BASE] * bc_diffuse * MR_INV_PI;
        st->spec_w[c] = v[SS_SPECULAR] * v[SS_SPECULAR_COLOR + c];
        st->coat_tint[c] = coat * v[SS_COAT_COLOR + c];
        mr_artistic_ior(v[SS_BASE] * bc, st->spec_w[c], &st->metal_n[c], &st->metal_k[c]);
    }
    mr_ggx_albedo_slice_init(rough_s, (st->eta_s - 1.0) / (st->eta_s + 1.0), &st->e_s);
    mr_ggx_albedo_slice_init(rough_c, (st->eta_c - 1.0) / (st->eta_c + 1.0), &st->e_c);
}

static void ss_eval(const void *state_bytes, const double wi[3], const double wo[3], double diffuse[3],
                    double specular[3]) {
    const ss_state *st = state_bytes;
    mr_brdf_geom g;
    if (!mr_brdf_geom_init(wi, wo, &g)) {
        mr_brdf_zero(diffuse, specular);
        return;
    }
    double e_c = st->coat > 0.0 ? mr_ggx_albedo_slice_at(&st->e_c, g.cos_i) : 0.0;
    double below[3]; /* the coat layer's weight of everything under it, at the view direction */
    for (int c = 0; c < 3; c++) below[c] = (1.0 - st->coat) + st->coat_tint[c] * (1.0 - e_c);
    if (diffuse) {
        double e_s = mr_ggx_albedo_slice_at(&st->e_s, g.cos_i);
        double on = st->on_a;
        if (st->on_b > 0.0) {
            double s = wi[0] * wo[0] + wi[1] * wo[1] + wi[2] * wo[2] - g.cos_i * g.cos_o;
            if (s > 0.0) on += st->on_b * s / MR_MAX(g.cos_i, g.cos_o);
        }
        for (int c = 0; c < 3; c++)
            diffuse[c] = below[c] * (1.0 - st->metalness) * (1.0 - st->spec_w[c] * e_s) * st->diffuse_over_pi[c] * on;
    }
    if (specular) {
        double dv = mr_ggx_dv_correlated(st->alpha_s, &g, NULL);
        double f_d = mr_fresnel_dielectric(g.dot_h, st->eta_s, NULL);
        double coat = st->coat > 0.0
                          ? st->coat * mr_fresnel_dielectric(g.dot_h, st->eta_c, NULL) *
                                mr_ggx_dv_correlated(st->alpha_c, &g, NULL)
                          : 0.0;
        for (int c = 0; c < 3; c++) {
            double metal = st->metalness > 0.0
                               ? st->metalness * mr_fresnel_conductor(g.dot_h, st->metal_n[c], st->metal_k[c], NULL,
                                                                      NULL)
                               : 0.0;
            specular[c] = coat + below[c] * (metal + (1.0 - st->metalness) * st->spec_w[c] * f_d) * dv;
        }
    }
}

/* mr_artistic_ior (brdf_internal.h, Gulbrandsen 2014) in dual numbers: n and k of reflectivity r and edge tint g. */
static void ss_dual_artistic_ior(mr_dual_tape *tp, mr_dual r, mr_dual g, mr_dual *n, mr_dual *k) {
    r = mr_dual_clampc(r, 0.0, MR_ARTISTIC_R_MAX);
    g = mr_dual_clampc(g, 0.0, 1.0);
    mr_dual sr = mr_dual_sqrt(tp, r);
    mr_dual n_min = mr_dual_div(tp, mr_dual_rsubc(tp, 1.0, r), mr_dual_addc(tp, r, 1.0));
    mr_dual n_max = mr_dual_div(tp, mr_dual_addc(tp, sr, 1.0), mr_dual_rsubc(tp, 1.0, sr));
    mr_dual eta = mr_dual_add(tp, mr_dual_mul(tp, g, n_min), mr_dual_mul(tp, mr_dual_rsubc(tp, 1.0, g), n_max));
    mr_dual k2 = mr_dual_div(tp,
                             mr_dual_sub(tp, mr_dual_mul(tp, mr_dual_sq(tp, mr_dual_addc(tp, eta, 1.0)), r),
                                         mr_dual_sq(tp, mr_dual_addc(tp, eta, -1.0))),
                             mr_dual_rsubc(tp, 1.0, r));
    *n = eta;
    *k = mr_dual_sqrt(tp, mr_dual_maxc(k2, 0.0));
}

/* d f_r / d values[j]: ss_prepare and ss_eval transcribed in dual numbers (dual.h), operation for operation, so the
 * value part is eval's to rounding. Differences from eval's branches, all where eval's value is unchanged: the coat
 * and the metal are evaluated at coat 0 and metalness 0 too, and base_color^(1 + coat coat_affect_color) at exponent
 * 1 as a power (their derivatives give the one-sided derivatives a fit starting there needs). Two halves:
 * ss_grad_prepare_duals (ss_prepare's part, no direction) and ss_grad_eval_duals (ss_eval's), so that a prepared
 * derivative state (ss_grad_ops, brdf.h) does the first once per parameter set; eval_grad runs both. */

/* What ss_grad_eval_duals takes from ss_grad_prepare_duals: the clamped values' duals and ss_prepare's. */
typedef struct ss_grad_prep {
    double v[MR_BRDF_MAX_VALUES];
    mr_dual x[MR_DUAL_N];
    mr_dual coat, metalness, rough_s, rough_c, alpha_s, alpha_c, eta_s, eta_c, on_a, on_b, eps_s, eps_c;
    mr_dual diffuse_over_pi[3], spec_w[3], coat_tint[3], metal_n[3], metal_k[3];
} ss_grad_prep;

_Static_assert(sizeof(ss_grad_prep) <= MR_DUAL_PREP_BYTES, "ss_grad_prep must fit in a mr_dual_grad_state");

/* ss_prepare in duals: p->v and p->x given */
static void ss_grad_prepare_duals(mr_dual_tape *tp, ss_grad_prep *p) {
    const mr_dual *x = p->x;
    mr_dual coat = x[SS_COAT], rough_c = x[SS_COAT_ROUGHNESS], metalness = x[SS_METALNESS];
    mr_dual affect = mr_dual_mul(tp, mr_dual_mul(tp, coat, x[SS_COAT_AFFECT_ROUGHNESS]), rough_c);
    mr_dual rough_s = x[SS_SPECULAR_ROUGHNESS];
    rough_s = mr_dual_add(tp, rough_s, mr_dual_mul(tp, mr_dual_rsubc(tp, 1.0, rough_s), affect));
    mr_dual alpha_s = mr_dual_sq(tp, rough_s), alpha_c = mr_dual_sq(tp, rough_c);
    mr_dual eta_s = x[SS_SPECULAR_IOR], eta_c = x[SS_COAT_IOR];
    mr_dual gamma = mr_dual_addc(tp, mr_dual_mul(tp, coat, x[SS_COAT_AFFECT_COLOR]), 1.0);
    mr_dual sigma2 = mr_dual_sq(tp, x[SS_DIFFUSE_ROUGHNESS]);
    mr_dual on_a =
        mr_dual_rsubc(tp, 1.0, mr_dual_scale(tp, mr_dual_div(tp, sigma2, mr_dual_addc(tp, sigma2, 0.33)), 0.5));
    mr_dual on_b = mr_dual_scale(tp, mr_dual_div(tp, sigma2, mr_dual_addc(tp, sigma2, 0.09)), 0.45);
    mr_dual diffuse_over_pi[3], spec_w[3], coat_tint[3], metal_n[3], metal_k[3];
    for (int c = 0; c < 3; c++) {
        mr_dual bc = x[SS_BASE_COLOR + c];
        /* bc^gamma: d/dbc = gamma bc^(gamma - 1), d/dgamma = bc^gamma ln(bc); at bc = 0, 1 for gamma = 1, else 0 */
        double p = gamma.v == 1.0 ? bc.v : pow(bc.v, gamma.v);
        double dp_dbc = bc.v > 0.0 ? gamma.v * pow(bc.v, gamma.v - 1.0) : (gamma.v == 1.0 ? 1.0 : 0.0);
        mr_dual bc_diffuse = mr_dual_chain2(tp, p, dp_dbc, bc, bc.v > 0.0 ? p * log(bc.v) : 0.0, gamma);
        diffuse_over_pi[c] = mr_dual_scale(tp, mr_dual_mul(tp, x[SS_BASE], bc_diffuse), MR_INV_PI);
        spec_w[c] = mr_dual_mul(tp, x[SS_SPECULAR], x[SS_SPECULAR_COLOR + c]);
        coat_tint[c] = mr_dual_mul(tp, coat, x[SS_COAT_COLOR + c]);
        ss_dual_artistic_ior(tp, mr_dual_mul(tp, x[SS_BASE], bc), spec_w[c], &metal_n[c], &metal_k[c]);
    }
    mr_dual eps_s = mr_dual_div(tp, mr_dual_addc(tp, eta_s, -1.0), mr_dual_addc(tp, eta_s, 1.0));
    mr_dual eps_c = mr_dual_div(tp, mr_dual_addc(tp, eta_c, -1.0), mr_dual_addc(tp, eta_c, 1.0));

    p->coat = coat, p->metalness = metalness, p->rough_s = rough_s, p->rough_c = rough_c, p->alpha_s = alpha_s;
    p->alpha_c = alpha_c, p->eta_s = eta_s, p->eta_c = eta_c, p->on_a = on_a, p->on_b = on_b, p->eps_s = eps_s;
    p->eps_c = eps_c;
    for (int c = 0; c < 3; c++) {
        p->diffuse_over_pi[c] = diffuse_over_pi[c], p->spec_w[c] = spec_w[c], p->coat_tint[c] = coat_tint[c];
        p->metal_n[c] = metal_n[c], p->metal_k[c] = metal_k[c];
    }
}

/* ss_eval in duals at the geometry g of (wi, wo) */
static void ss_grad_eval_duals(const ss_grad_prep *p, mr_dual_tape *tp, const mr_brdf_geom *gp, const double wi[3],
                               const double wo[3], mr_dual diffuse[3], mr_dual specular[3]) {
    const mr_brdf_geom g = *gp;
    mr_dual coat = p->coat, metalness = p->metalness, rough_s = p->rough_s, rough_c = p->rough_c;
    mr_dual alpha_s = p->alpha_s, alpha_c = p->alpha_c, eta_s = p->eta_s, eta_c = p->eta_c, on_a = p->on_a;
    mr_dual on_b = p->on_b, eps_s = p->eps_s, eps_c = p->eps_c;
    const mr_dual *diffuse_over_pi = p->diffuse_over_pi, *spec_w = p->spec_w, *coat_tint = p->coat_tint;
    const mr_dual *metal_n = p->metal_n, *metal_k = p->metal_k;
    /* a prepared state holding coat or metalness at a constant 0 skips that lobe (mr_dual_is_const_zero) */
    const int coat_on = !mr_dual_is_const_zero(coat), metal_on = !mr_dual_is_const_zero(metalness);
    mr_dual e_c = coat_on ? mr_dual_albedo_dielectric(tp, g.cos_i, rough_c, eps_c) : mr_dual_const(0.0);
    mr_dual e_s = mr_dual_albedo_dielectric(tp, g.cos_i, rough_s, eps_s);
    double s = wi[0] * wo[0] + wi[1] * wo[1] + wi[2] * wo[2] - g.cos_i * g.cos_o;
    mr_dual on = mr_dual_add(tp, on_a, mr_dual_scale(tp, on_b, s > 0.0 ? s / MR_MAX(g.cos_i, g.cos_o) : 0.0));
    mr_dual dv = mr_dual_ggx_dv(tp, alpha_s, &g);
    mr_dual f_d = mr_dual_fresnel_dielectric(tp, g.dot_h, eta_s);
    mr_dual coat_lobe = coat_on ? mr_dual_mul(tp, mr_dual_mul(tp, coat, mr_dual_fresnel_dielectric(tp, g.dot_h, eta_c)),
                                              mr_dual_ggx_dv(tp, alpha_c, &g))
                                : mr_dual_const(0.0);
    for (int c = 0; c < 3; c++) {
        mr_dual below = coat_on ? mr_dual_add(tp, mr_dual_rsubc(tp, 1.0, coat),
                                              mr_dual_mul(tp, coat_tint[c], mr_dual_rsubc(tp, 1.0, e_c)))
                                : mr_dual_const(1.0);
        mr_dual weight = mr_dual_mul(tp, mr_dual_mul(tp, below, mr_dual_rsubc(tp, 1.0, metalness)),
                                     mr_dual_rsubc(tp, 1.0, mr_dual_mul(tp, spec_w[c], e_s)));
        diffuse[c] = mr_dual_mul(tp, mr_dual_mul(tp, weight, diffuse_over_pi[c]), on);
        mr_dual dielectric = mr_dual_mul(tp, mr_dual_mul(tp, mr_dual_rsubc(tp, 1.0, metalness), spec_w[c]), f_d);
        mr_dual base = dielectric;
        if (metal_on) {
            double dn, dk;
            double F_c = mr_fresnel_conductor(g.dot_h, metal_n[c].v, metal_k[c].v, &dn, &dk);
            mr_dual metal = mr_dual_mul(tp, metalness, mr_dual_chain2(tp, F_c, dn, metal_n[c], dk, metal_k[c]));
            base = mr_dual_add(tp, metal, dielectric);
        }
        specular[c] = mr_dual_add(tp, coat_lobe, mr_dual_mul(tp, mr_dual_mul(tp, below, base), dv));
    }
}

static void ss_grad_prepare(const mr_brdf_model *model, const double *values, const int *slots, int count,
                            void *state) {
    mr_dual_grad_state *st = state;
    ss_grad_prep *p = (ss_grad_prep *)st->prep.bytes;
    mr_dual_grad_state_begin(model, values, slots, count, st, p->v, p->x);
    ss_grad_prepare_duals(&st->tape, p);
}

static void ss_grad_eval(const void *state, const double wi[3], const double wo[3], double *d_diffuse,
                         double *d_specular) {
    const mr_dual_grad_state *st = state;
    mr_brdf_geom g;
    if (!mr_dual_grad_eval_begin(st, wi, wo, d_diffuse, d_specular, &g)) return;
    double scratch[MR_DUAL_SCRATCH];
    mr_dual_tape tape;
    mr_dual_tape_init(&tape, scratch, MR_DUAL_SCRATCH, st->count);
    mr_dual diffuse[3], specular[3];
    ss_grad_eval_duals((const ss_grad_prep *)st->prep.bytes, &tape, &g, wi, wo, diffuse, specular);
    mr_dual_store_grad(diffuse, specular, st->count, d_diffuse, d_specular);
}

static const mr_brdf_grad_ops ss_grad_ops = {sizeof(mr_dual_grad_state), ss_grad_prepare, ss_grad_eval, NULL, NULL};

/* eval_grad: every slot, through the prepared path (dual.h, mr_dual_eval_grad). */
static void ss_eval_grad(const mr_brdf_model *model, const double *values, const double wi[3], const double wo[3],
                         double *d_diffuse, double *d_specular) {
    mr_dual_eval_grad(&ss_grad_ops, model, values, wi, wo, d_diffuse, d_specular);
}

_Static_assert(20 <= MR_DUAL_N, "standard-surface's 20 packed values need as many dual slots");

const mr_brdf_model mr_brdf_standard_surface = {
    .name = "standard-surface",
    .summary = "Autodesk Standard Surface 1.0.1: coat over metal/dielectric GGX over Oren-Nayar, albedo-weighted",
    .source = "Autodesk/standard-surface index.html (1.0.1) + reference/standard_surface.mtlx; Gulbrandsen 2014",
    .param_count = (int)(sizeof ss_params / sizeof ss_params[0]),
    .params = ss_params,
    .flags = MR_BRDF_NON_RECIPROCAL,
    .config = NULL,
    .prepare = ss_prepare,
    .eval = ss_eval,
    .eval_grad = ss_eval_grad,
    .grad_ops = &ss_grad_ops,
};
