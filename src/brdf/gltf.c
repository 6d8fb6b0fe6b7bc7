/*
 * gltf.c — `gltf`: the glTF 2.0 metallic-roughness material (Specification Appendix B) with the
 * KHR_materials_specular and KHR_materials_ior extensions; isotropic.
 *
 *   alpha = roughness^2,  S = D V  (the "specular_brdf"),  w = (1 - |wi.h|)^5
 *   D = alpha^2 / (pi ((n.h)^2 (alpha^2 - 1) + 1)^2)                                               (GGX)
 *   V = 1 / (2 (n.v sqrt(alpha^2 + (1 - alpha^2)(n.l)^2) + n.l sqrt(alpha^2 + (1 - alpha^2)(n.v)^2)))
 *       (height-correlated Smith, G / (4 n.l n.v))
 *   dielectric:  f0_c = min(((ior - 1)/(ior + 1))^2 specular_color_c, 1) specular,  f90 = specular
 *                F_c = f0_c + (f90 - f0_c) w
 *                f = F_c S + (1 - max_c F_c) base_c / pi
 *   metal:       f = (base_c + (1 - base_c) w) S
 *   material  = (1 - metallic) dielectric + metallic metal
 *
 * Split: diffuse part = (1 - metallic)(1 - max_c F_c) base_c/pi; specular part = the rest. Without the extensions
 * (specular = 1, specular_color = 1, ior = 1.5, so a grey f0 = 0.04) this is the core specification's normative
 * material = mix(dielectric_brdf, metal_brdf, metallic). Its "optimized" form f = (1 - F) c_diff/pi + F D V with
 * f0 = mix(0.04, base, metallic) agrees at metallic 0 and 1; in between it dims the diffuse lobe by the
 * metal-mixed F instead of the dielectric one (a difference of order metallic (1 - metallic) (F_metal - F_diel)).
 *
 * Parameters (defaults are the specification's):
 *   base_color      RGB  [0, 1]     default 1     baseColorFactor (linear). AFFINE: the diffuse part is linear in
 *                                                 it and the metal's specular part affine, per channel.
 *   metallic             [0, 1]     default 1     metallicFactor. f is affine in metallic alone, but bilinear with
 *                                                 base_color, so it is NONLINEAR (searched, not solved).
 *   roughness            [0.01, 1]  default 1     roughnessFactor, log scale; alpha = roughness^2. alpha = 0 is
 *                                                 singular (the specification says to clamp it): 0.01, i.e.
 *                                                 alpha >= 1e-4 as Mitsuba's floor, is the minimum.
 *   specular             [0, 1]     default 1     KHR_materials_specular specularFactor
 *   specular_color  RGB  [0, 25]    default 1     KHR_materials_specular specularColorFactor. The extension allows
 *                                                 values above 1; 25 = 1/0.04 reaches f0 = 1 at the default ior.
 *   ior                  [1, 5]     default 1.5   KHR_materials_ior. Its special value 0 (spec-gloss compatibility,
 *                                                 infinite index, F = 1) is not supported here: use
 *                                                 `gltf-specgloss` for such materials.
 *
 * Source: KhronosGroup/glTF specification/2.0/Specification.adoc Appendix B, extensions/2.0/Khronos/
 * KHR_materials_specular and KHR_materials_ior (brdf-reference 5.1, 5.3).
 * Limitations: no clearcoat, sheen, transmission, volume, iridescence or anisotropy extensions; textures are
 * handled outside the model (these are the per-texel factors).
 * Energy: flagged MR_BRDF_NOT_ENERGY_CONSERVING. The specification's fresnel_mix weights the diffuse lobe by
 * 1 - F(v.h) per pair of directions; near grazing incidence the mirror-like specular lobe takes F(v.h) close to 1
 * while the diffuse lobe, spread over directions whose v.h is large, keeps nearly 1 - F0. The two then count the
 * same energy twice: a smooth white dielectric (roughness 0.01, metallic 0, base 1) has albedo 1.00 at normal
 * incidence but 1.35 at 80 degrees and 1.78 at 88 degrees (1.10 at 88 degrees for roughness 0.6). Single-scattering
 * GGX also loses energy at high roughness. Both are the specification's BRDF, not defects here.
 * Gradient: analytic for every parameter (one-sided where specular_color x f0 reaches 1 or two channels tie for
 * max F).
 */
#include "brdf_batch.h"
#include "brdf_float.h"

/* Slots of the packed value vector. */
enum { GLTF_BASE = 0, GLTF_METALLIC = 3, GLTF_ROUGHNESS = 4, GLTF_SPECULAR = 5, GLTF_SPECULAR_COLOR = 6,
       GLTF_IOR = 9 };

/* alpha = roughness^2 >= 1e-4: the parameter's minimum 0.01, squared. */
#define GLTF_ROUGHNESS_MIN 0.01

static const mr_brdf_param gltf_params[] = {
    {"base_color", 3, 1.0, 0.0, 1.0, MR_PARAM_AFFINE, MR_LOBE_BOTH, MR_PARAM_SRGB_MAP,
     "baseColorFactor, linear RGB", NULL},
    {"metallic", 1, 1.0, 0.0, 1.0, MR_PARAM_NONLINEAR, MR_LOBE_BOTH, 0,
     "metallicFactor (f is affine in it alone, bilinear with base_color)", NULL},
    {"roughness", 1, 1.0, GLTF_ROUGHNESS_MIN, 1.0, MR_PARAM_NONLINEAR, MR_LOBE_SPECULAR, MR_PARAM_LOG_SCALE,
     "roughnessFactor; GGX alpha = roughness^2", NULL},
    {"specular", 1, 1.0, 0.0, 1.0, MR_PARAM_NONLINEAR, MR_LOBE_BOTH, MR_PARAM_FIT_FIXED,
     "KHR_materials_specular specularFactor (dielectric f0 and f90 scale)", NULL},
    {"specular_color", 3, 1.0, 0.0, 25.0, MR_PARAM_NONLINEAR, MR_LOBE_BOTH, MR_PARAM_FIT_FIXED | MR_PARAM_SRGB_MAP,
     "KHR_materials_specular specularColorFactor, linear RGB (dielectric f0 tint)", NULL},
    {"ior", 1, 1.5, 1.0, 5.0, MR_PARAM_NONLINEAR, MR_LOBE_BOTH, MR_PARAM_FIT_FIXED,
     "KHR_materials_ior index of refraction (dielectric f0 = ((ior-1)/(ior+1))^2); 0 is not supported", NULL},
};

typedef struct gltf_state {
    double alpha;
    double metallic;
    double specular;
    double base[3];
    double f0[3]; /* dielectric f0_c = min(f0_ior specular_color_c, 1) specular */
} gltf_state;

_Static_assert(sizeof(gltf_state) <= MR_BRDF_STATE_BYTES, "gltf_state must fit in MR_BRDF_STATE_BYTES");

static void gltf_prepare(const mr_brdf_model *model, const double *values, void *state_bytes) {
    gltf_state *state = state_bytes;
    double v[MR_BRDF_MAX_VALUES];
    mr_brdf_clamp_values(model, values, v);
    double r = (v[GLTF_IOR] - 1.0) / (v[GLTF_IOR] + 1.0);
    state->alpha = v[GLTF_ROUGHNESS] * v[GLTF_ROUGHNESS];
    state->metallic = v[GLTF_METALLIC];
    state->specular = v[GLTF_SPECULAR];
    for (int c = 0; c < 3; c++) {
        state->base[c] = v[GLTF_BASE + c];
        state->f0[c] = MR_MIN(r * r * v[GLTF_SPECULAR_COLOR + c], 1.0) * v[GLTF_SPECULAR];
    }
}

static void gltf_eval(const void *state_bytes, const double wi[3], const double wo[3], double diffuse[3],
                      double specular[3]) {
    const gltf_state *state = state_bytes;
    mr_brdf_geom g;
    if (!mr_brdf_geom_init(wi, wo, &g)) {
        mr_brdf_zero(diffuse, specular);
        return;
    }
    double w = mr_schlick_weight(g.dot_h);
    double F[3], Fmax = 0.0;
    for (int c = 0; c < 3; c++) {
        F[c] = state->f0[c] + (state->specular - state->f0[c]) * w;
        Fmax = MR_MAX(Fmax, F[c]);
    }
    double m = state->metallic;
    if (diffuse)
        for (int c = 0; c < 3; c++) diffuse[c] = (1.0 - m) * (1.0 - Fmax) * state->base[c] * MR_INV_PI;
    if (specular) {
        double S = mr_ggx_dv_correlated(state->alpha, &g, NULL);
        for (int c = 0; c < 3; c++)
            specular[c] = ((1.0 - m) * F[c] + m * (state->base[c] + (1.0 - state->base[c]) * w)) * S;
    }
}

/* eval over a batch (brdf.h eval_batch): gltf_eval's operations. */
MR_BATCH_INLINE void gltf_batch_body(const void *state_bytes, const mr_brdf_batch *batch, const int fused) {
    (void)fused; // no exp or pow here
    const gltf_state *state = state_bytes;
    const double alpha = state->alpha, m = state->metallic, spec = state->specular;
    const double b0 = state->base[0], b1 = state->base[1], b2 = state->base[2];
    const double f0 = state->f0[0], f1 = state->f0[1], f2 = state->f0[2];
    MR_BATCH_ARRAYS(batch);
#pragma omp simd
    for (int i = 0; i < n_; i++) {
        mr_brdf_geom g;
        const int lit = mr_batch_geom(ix_[i], iy_[i], iz_[i], ox_[i], oy_[i], oz_[i], &g);
        const double w = mr_schlick_weight(g.dot_h);
        const double F0 = f0 + (spec - f0) * w, F1 = f1 + (spec - f1) * w, F2 = f2 + (spec - f2) * w;
        double Fmax = 0.0;
        Fmax = MR_MAX(Fmax, F0);
        Fmax = MR_MAX(Fmax, F1);
        Fmax = MR_MAX(Fmax, F2);
        const double S = lit ? mr_batch_ggx_dv_correlated(alpha, &g) : 0.0;
        d0_[i] = lit ? (1.0 - m) * (1.0 - Fmax) * b0 * MR_INV_PI : 0.0;
        d1_[i] = lit ? (1.0 - m) * (1.0 - Fmax) * b1 * MR_INV_PI : 0.0;
        d2_[i] = lit ? (1.0 - m) * (1.0 - Fmax) * b2 * MR_INV_PI : 0.0;
        s0_[i] = ((1.0 - m) * F0 + m * (b0 + (1.0 - b0) * w)) * S;
        s1_[i] = ((1.0 - m) * F1 + m * (b1 + (1.0 - b1) * w)) * S;
        s2_[i] = ((1.0 - m) * F2 + m * (b2 + (1.0 - b2) * w)) * S;
    }
}

MR_BATCH_KERNEL(gltf_eval_batch, gltf_batch_body)

/* gltf_batch_body in float (brdf_float.h): D V as mr_batch_ggx_dv_correlated's, D written as a^2 (|H|^2/root)^2/pi
 * to stay in float's range (brdf_batch.h, "single precision"). */
MR_BATCH_INLINE void gltf_batchf_body(const void *state_bytes, const mr_brdf_batch *batch, const int fused) {
    (void)fused; // no exp or pow here
    const gltf_state *state = state_bytes;
    const float alpha = (float)state->alpha, m = (float)state->metallic, spec = (float)state->specular;
    const float a2 = alpha * alpha, inv_pi = (float)MR_INV_PI;
    const float b0 = (float)state->base[0], b1 = (float)state->base[1], b2 = (float)state->base[2];
    const float f0 = (float)state->f0[0], f1 = (float)state->f0[1], f2 = (float)state->f0[2];
    MR_BATCH_ARRAYS(batch);
#pragma omp simd
    for (int i = 0; i < n_; i++) {
        mr_batchf_geom_t g;
        const int lit = mr_batchf_geom(ix_[i], iy_[i], iz_[i], ox_[i], oy_[i], oz_[i], &g);
        const float w = mr_batchf_schlick_weight(g.dot_h);
        const float F0 = f0 + (spec - f0) * w, F1 = f1 + (spec - f1) * w, F2 = f2 + (spec - f2) * w;
        const float Fmax = MR_MAX(MR_MAX(MR_MAX(0.0f, F0), F1), F2);
        const float nl = g.cos_i, nv = g.cos_o;
        const float root_l = sqrtf(a2 * (1.0f - nl * nl) + nl * nl);
        const float root_v = sqrtf(a2 * (1.0f - nv * nv) + nv * nv);
        const float t = g.h_len2 / (a2 * (g.hz * g.hz) + g.hxy2);
        const float S = lit ? 0.5f * (a2 * t * t * inv_pi) / (nv * root_l + nl * root_v) : 0.0f;
        const float diffuse = (1.0f - m) * (1.0f - Fmax) * inv_pi;
        d0_[i] = lit ? diffuse * b0 : 0.0f;
        d1_[i] = lit ? diffuse * b1 : 0.0f;
        d2_[i] = lit ? diffuse * b2 : 0.0f;
        s0_[i] = ((1.0f - m) * F0 + m * (b0 + (1.0f - b0) * w)) * S;
        s1_[i] = ((1.0f - m) * F1 + m * (b1 + (1.0f - b1) * w)) * S;
        s2_[i] = ((1.0f - m) * F2 + m * (b2 + (1.0f - b2) * w)) * S;
    }
}

MR_BATCH_KERNEL(gltf_eval_batch_float, gltf_batchf_body)

mr_brdf_batch_fn mr_gltf_float_kernel(const mr_brdf_model *model) {
    return model->eval == gltf_eval ? gltf_eval_batch_float : NULL;
}

static void gltf_eval_grad(const mr_brdf_model *model, const double *values, const double wi[3],
                           const double wo[3], double *d_diffuse, double *d_specular) {
    mr_brdf_geom g;
    double v[MR_BRDF_MAX_VALUES];
    if (!mr_brdf_grad_begin(model, values, wi, wo, d_diffuse, d_specular, &g, v)) return;
    const double *base = v + GLTF_BASE, *color = v + GLTF_SPECULAR_COLOR;
    double m = v[GLTF_METALLIC], rough = v[GLTF_ROUGHNESS], spec = v[GLTF_SPECULAR], ior = v[GLTF_IOR];
    double r = (ior - 1.0) / (ior + 1.0), f0_ior = r * r;
    double df0_ior = 4.0 * (ior - 1.0) / ((ior + 1.0) * (ior + 1.0) * (ior + 1.0));
    double w = mr_schlick_weight(g.dot_h);
    double dS_dalpha;
    double S = mr_ggx_dv_correlated(rough * rough, &g, &dS_dalpha);

    /* q_c = min(f0_ior color_c, 1); F_c = spec (q_c (1 - w) + w); Fmax = F at the channel of the largest q */
    double q[3], F[3];
    int cmax = 0;
    for (int c = 0; c < 3; c++) {
        q[c] = MR_MIN(f0_ior * color[c], 1.0);
        F[c] = spec * (q[c] * (1.0 - w) + w);
        if (q[c] > q[cmax]) cmax = c;
    }
    double Fmax = F[cmax];
    int q_free = f0_ior * color[cmax] < 1.0; /* the min() is not saturated at the max channel */

    for (int c = 0; c < 3; c++) {
        double metal_c = base[c] + (1.0 - base[c]) * w;
        /* base_color */
        d_diffuse[(GLTF_BASE + c) * 3 + c] = (1.0 - m) * (1.0 - Fmax) * MR_INV_PI;
        d_specular[(GLTF_BASE + c) * 3 + c] = m * (1.0 - w) * S;
        /* metallic */
        d_diffuse[GLTF_METALLIC * 3 + c] = -(1.0 - Fmax) * base[c] * MR_INV_PI;
        d_specular[GLTF_METALLIC * 3 + c] = (metal_c - F[c]) * S;
        /* roughness: alpha = roughness^2 */
        d_specular[GLTF_ROUGHNESS * 3 + c] = ((1.0 - m) * F[c] + m * metal_c) * dS_dalpha * 2.0 * rough;
        /* specular: F_c and Fmax are linear in it */
        d_diffuse[GLTF_SPECULAR * 3 + c] = -(1.0 - m) * (q[cmax] * (1.0 - w) + w) * base[c] * MR_INV_PI;
        d_specular[GLTF_SPECULAR * 3 + c] = (1.0 - m) * (q[c] * (1.0 - w) + w) * S;
        /* specular_color: F_c through q_c, Fmax through q_cmax */
        for (int cp = 0; cp < 3; cp++) {
            double dq_own = (cp == c && f0_ior * color[c] < 1.0) ? f0_ior : 0.0;
            double dq_max = (cp == cmax && q_free) ? f0_ior : 0.0;
            d_specular[(GLTF_SPECULAR_COLOR + cp) * 3 + c] = (1.0 - m) * spec * (1.0 - w) * dq_own * S;
            d_diffuse[(GLTF_SPECULAR_COLOR + cp) * 3 + c] =
                -(1.0 - m) * spec * (1.0 - w) * dq_max * base[c] * MR_INV_PI;
        }
        /* ior: through f0_ior in every unsaturated q */
        double dq_c = f0_ior * color[c] < 1.0 ? color[c] * df0_ior : 0.0;
        double dq_max = q_free ? color[cmax] * df0_ior : 0.0;
        d_specular[GLTF_IOR * 3 + c] = (1.0 - m) * spec * (1.0 - w) * dq_c * S;
        d_diffuse[GLTF_IOR * 3 + c] = -(1.0 - m) * spec * (1.0 - w) * dq_max * base[c] * MR_INV_PI;
    }
}

const mr_brdf_model mr_brdf_gltf = {
    .name = "gltf",
    .summary = "glTF 2.0 metallic-roughness + KHR_materials_specular/ior (GGX, height-correlated Smith)",
    .source = "glTF 2.0 Specification.adoc Appendix B; KHR_materials_specular, KHR_materials_ior",
    .param_count = (int)(sizeof gltf_params / sizeof gltf_params[0]),
    .params = gltf_params,
    .flags = MR_BRDF_NOT_ENERGY_CONSERVING,
    .config = NULL,
    .prepare = gltf_prepare,
    .eval = gltf_eval,
    .eval_batch = gltf_eval_batch,
    .eval_grad = gltf_eval_grad,
};
