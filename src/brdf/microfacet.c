/*
 * microfacet.c — the Mitsuba 0.5.1+/0.6 microfacet family, isotropic: three distributions x four Fresnel
 * modes, twelve descriptors sharing this file's code through `config`:
 *
 *   beckmann            ggx            as              Schlick F with F0 given (the paper's "pbr" plugin)
 *   beckmann-nofresnel  ggx-nofresnel  as-nofresnel    F = 1
 *   beckmann-conductor  ggx-conductor  as-conductor    exact conductor F (Mitsuba roughconductor)
 *   beckmann-plastic    ggx-plastic    as-plastic      dielectric F over a Lambert base (after roughplastic)
 *
 *   f_s = rho_s F(wi.h) D(h) G1(wi) G1(wo) / (4 cos_i cos_o),   h = normalize(wi + wo)
 *
 * D (brdf-reference 2.3; Mitsuba sets D = 0 where D cos_h < 1e-20, and so do we):
 *   beckmann  exp(-tan^2(theta_h)/alpha^2) / (pi alpha^2 cos^4(theta_h))
 *   ggx       1 / (pi alpha^2 cos^4(theta_h) (1 + tan^2(theta_h)/alpha^2)^2)
 *   as        (n+2)/(2 pi) cos^n(theta_h), n = 2/alpha^2 - 2 (Walter et al. 2007). Mitsuba 0.5.1+ has no separate
 *             Ashikhmin-Shirley model: "as" and "phong" both name this EPhong distribution (the anisotropic
 *             Ashikhmin-Shirley extension of Phong, isotropic here). The authors' "Mitsuba-Pbr-AS" is this.
 * G1, separable (uncorrelated) Smith, a = 1/(alpha tan(theta_v)):
 *   beckmann, as  1 if a >= 1.6, else (3.535 a + 2.181 a^2)/(1 + 2.276 a + 2.577 a^2) (rational fit, < 0.35%)
 *   ggx           2 / (1 + sqrt(1 + alpha^2 tan^2(theta_v)))
 * F and the extra terms per mode:
 *   (Schlick)   F = F0 + (1 - F0)(1 - wi.h)^5, rho_s = 1; plus an optional Lambert lobe rho_d/pi
 *   -nofresnel  F = 1; plus an optional Lambert lobe rho_d/pi
 *   -conductor  F = exact conductor Fresnel (Mitsuba fresnelConductorExact) per channel, of (eta, k)
 *   -plastic    F = exact dielectric Fresnel of ior (Mitsuba fresnelDielectricExt), plus
 *               f_d = rho_d/pi (1 - F(cos_i)) (1 - F(cos_o))
 *
 * Parameters (alpha first in every member; RGB parameters take 3 slots):
 *   alpha     [1e-4, 1]  default 0.1   roughness, log scale; 1e-4 is Mitsuba's own floor
 *   (Schlick)    f0       RGB [0, 1] default 0.04  Schlick F0 (AFFINE); 0.04 = dielectric of ior 1.5 (the
 *                                                  authors' plugin takes F0 directly; its default is not stated)
 *                diffuse  RGB [0, 1] default 0     optional Lambert lobe, off by default = the paper's plugin
 *   -nofresnel   specular RGB [0, 1] default 1     rho_s;  diffuse RGB [0, 1] default 0 as above
 *   -conductor   eta      RGB [0, 10] default Cu (0.200438, 0.924033, 1.10221)  real part of the relative index
 *                k        RGB [0, 10] default Cu (3.91295, 2.45285, 2.14219)    extinction coefficient
 *                specular RGB [0, 1] default 1     rho_s (Mitsuba specularReflectance)
 *                The Cu triples are a commonly used RGB reduction of copper's spectral eta and k (they appear as
 *                Cu_eta/Cu_k in public renderer code); we did not derive them from Mitsuba's Cu.eta.spd/Cu.k.spd.
 *                Mitsuba 0.6 renders Cu spectrally and divides eta and k by extEta = 1.000277 (air), so its
 *                colours differ slightly. eta = 0, k = 1 is Mitsuba's material "none" (F = 1).
 *   -plastic     ior      [1, 3] default 1.49  relative index int/ext. Mitsuba's defaults (polypropylene 1.49 in air
 *                                              1.000277) give 1.4896; 1.49 is the interior index alone.
 *                specular RGB [0, 1] default 1     rho_s (Mitsuba specularReflectance)
 *                diffuse  RGB [0, 1] default 0.5   rho_d (Mitsuba diffuseReflectance)
 *
 * -plastic simplifies Mitsuba's roughplastic on purpose. Mitsuba's diffuse term is
 * rho_d'/pi T(cos_i) T(cos_o) / eta^2 with rough-transmittance tables T and rho_d' = rho_d/(1 - F_dr) (internal
 * scattering). Here the smooth-interface transmittances 1 - F(cos) replace T, and the 1/eta^2 and 1/(1 - F_dr)
 * factors are dropped. This keeps f_d linear in rho_d (the optimiser's linear solve), reciprocal, energy-bounded
 * (f_d <= rho_d/pi), finite as ior -> 1 (where roughplastic's renormalisation is undefined and Mitsuba rejects
 * int == ext), and needs no 3-D data tables. It is darker than roughplastic (which adds back the light that
 * scatters inside the coat) and ignores how roughness changes the transmittance.
 *
 * Mitsuba trims single textures (roughconductor: rho_s scaled by 0.99/max if max(rho_s) > 1); with rho_s <= 1 as
 * bounded here that never happens, so there is no trim switch.
 *
 * Energy. The Schlick and -nofresnel members are flagged MR_BRDF_INDEPENDENT_LOBES: their optional diffuse lobe is
 * simply added, so diffuse + specular may exceed 1 if the caller asks for it; each lobe alone is checked.
 * Beckmann and GGX (single scattering, separable Smith) stay below 1 at every angle and alpha we measured (up to
 * 89.9 degrees; the F = 1 albedo at normal incidence is 1.00 / 0.99 for alpha = 0.1 and 0.46 / 0.31 for alpha = 1).
 * The `as` members that can reach F = 1 (`as`, `as-nofresnel`, `as-conductor` with eta = 0, k = 1) are flagged
 * MR_BRDF_NOT_ENERGY_CONSERVING: Mitsuba gives the Phong distribution the Beckmann rational G1, which was fitted to
 * the Beckmann distribution and overestimates G for wide Phong lobes, so the F = 1 albedo exceeds 1 at grazing
 * incidence: 1.02 at 80 degrees and 1.27 at 88 degrees for alpha = 1, 1.05 at 88 degrees for alpha = 0.5. That is
 * Mitsuba's model. `as-plastic` stays below 1 (F <= 0.25 at normal incidence, and its diffuse lobe loses energy at
 * the interface).
 *
 * Source: Mitsuba 0.6 src/bsdfs/microfacet.h, roughconductor.cpp, roughplastic.cpp, src/libcore/util.cpp
 * (brdf-reference 2.3-2.5); the authors' pbr.cpp plugin (brdf-reference 1). Mitsuba's eval() includes
 * cos(theta_o); ours does not (brdf.h).
 * Limitations: isotropic only; Mitsuba 0.5.0's older "as" (V-groove G, exponent floor 0.1) is not modelled;
 * single scattering only (energy is lost at high alpha, as in Mitsuba).
 * Gradient: analytic for every parameter (alpha through D and both G1; eta and k through the exact Fresnel
 * derivatives; ior through the dielectric Fresnel at wi.h, cos_i and cos_o). One-sided at the G1 switch a = 1.6
 * and at Mitsuba's D cut-off; where the conductor Fresnel has a square-root branch point (k = 0 and
 * eta <= sin(theta)) the infinite derivative is reported as 0.
 */
#include "brdf_batch.h"
#include "brdf_float.h"

typedef enum mf_fresnel { MF_SCHLICK = 0, MF_NONE, MF_CONDUCTOR, MF_PLASTIC } mf_fresnel;

typedef struct mf_config {
    mr_mf_dist dist;
    mf_fresnel fresnel;
} mf_config;

/* Slots of the packed value vector, per Fresnel mode. */
enum { MF_ALPHA = 0 };
enum { MF_SCHLICK_F0 = 1, MF_SCHLICK_DIFFUSE = 4 };
enum { MF_NONE_SPECULAR = 1, MF_NONE_DIFFUSE = 4 };
enum { MF_COND_ETA = 1, MF_COND_K = 4, MF_COND_SPECULAR = 7 };
enum { MF_PLASTIC_IOR = 1, MF_PLASTIC_SPECULAR = 2, MF_PLASTIC_DIFFUSE = 5 };

#define MF_ALPHA_PARAM                                                                                 \
    {"alpha", 1, 0.1, 1e-4, 1.0, MR_PARAM_NONLINEAR, MR_LOBE_SPECULAR, MR_PARAM_LOG_SCALE,            \
     "microfacet roughness alpha (Mitsuba alpha, isotropic); floored at 1e-4 as Mitsuba", NULL}
#define MF_DIFFUSE_PARAM(def)                                                                          \
    {"diffuse", 3, def, 0.0, 1.0, MR_PARAM_LINEAR, MR_LOBE_DIFFUSE, MR_PARAM_SRGB_MAP,                 \
     "Lambert reflectance rho_d, linear RGB, added to the specular lobe", NULL}
#define MF_SPECULAR_PARAM                                                                              \
    {"specular", 3, 1.0, 0.0, 1.0, MR_PARAM_LINEAR, MR_LOBE_SPECULAR, MR_PARAM_SRGB_MAP,               \
     "specular scale rho_s, linear RGB (Mitsuba specularReflectance)", NULL}

static const mr_brdf_param mf_schlick_params[] = {
    MF_ALPHA_PARAM,
    {"f0", 3, 0.04, 0.0, 1.0, MR_PARAM_AFFINE, MR_LOBE_SPECULAR, MR_PARAM_SRGB_MAP,
     "Schlick reflectance at normal incidence F0, linear RGB (the authors' pbr plugin)", NULL},
    MF_DIFFUSE_PARAM(0.0),
};

static const mr_brdf_param mf_none_params[] = {
    MF_ALPHA_PARAM,
    MF_SPECULAR_PARAM,
    MF_DIFFUSE_PARAM(0.0),
};

static const double cu_eta[3] = {0.200438, 0.924033, 1.10221};
static const double cu_k[3] = {3.91295, 2.45285, 2.14219};

static const mr_brdf_param mf_conductor_params[] = {
    MF_ALPHA_PARAM,
    {"eta", 3, 0.924033, 0.0, 10.0, MR_PARAM_NONLINEAR, MR_LOBE_SPECULAR, 0,
     "conductor index (real part), RGB; default Cu (0.200438, 0.924033, 1.10221)", cu_eta},
    {"k", 3, 2.45285, 0.0, 10.0, MR_PARAM_NONLINEAR, MR_LOBE_SPECULAR, 0,
     "conductor extinction coefficient, RGB; default Cu (3.91295, 2.45285, 2.14219)", cu_k},
    MF_SPECULAR_PARAM,
};

static const mr_brdf_param mf_plastic_params[] = {
    MF_ALPHA_PARAM,
    {"ior", 1, 1.49, 1.0, 3.0, MR_PARAM_NONLINEAR, MR_LOBE_BOTH, 0,
     "relative index of refraction of the coating (Mitsuba intIOR/extIOR)", NULL},
    MF_SPECULAR_PARAM,
    MF_DIFFUSE_PARAM(0.5),
};

typedef struct mf_state {
    mr_mf_dist dist;
    mf_fresnel fresnel;
    double alpha;
    double ior;                /* -plastic */
    double spec[3];            /* F0 (Schlick) or rho_s */
    double eta[3], k[3];       /* -conductor */
    double diffuse_over_pi[3]; /* rho_d/pi; 0 for -conductor */
} mf_state;

_Static_assert(sizeof(mf_state) <= MR_BRDF_STATE_BYTES, "mf_state must fit in MR_BRDF_STATE_BYTES");

/* The slot of the specular reflectance (F0 or rho_s) and of rho_d (-1: none) for a Fresnel mode. */
static int mf_spec_slot(mf_fresnel fresnel) {
    switch (fresnel) {
    case MF_SCHLICK: return MF_SCHLICK_F0;
    case MF_NONE: return MF_NONE_SPECULAR;
    case MF_CONDUCTOR: return MF_COND_SPECULAR;
    default: return MF_PLASTIC_SPECULAR;
    }
}

static int mf_diffuse_slot(mf_fresnel fresnel) {
    switch (fresnel) {
    case MF_SCHLICK: return MF_SCHLICK_DIFFUSE;
    case MF_NONE: return MF_NONE_DIFFUSE;
    case MF_CONDUCTOR: return -1;
    default: return MF_PLASTIC_DIFFUSE;
    }
}

static void mf_prepare(const mr_brdf_model *model, const double *values, void *state_bytes) {
    const mf_config *config = model->config;
    mf_state *state = state_bytes;
    double v[MR_BRDF_MAX_VALUES];
    mr_brdf_clamp_values(model, values, v);
    state->dist = config->dist;
    state->fresnel = config->fresnel;
    state->alpha = v[MF_ALPHA];
    state->ior = config->fresnel == MF_PLASTIC ? v[MF_PLASTIC_IOR] : 1.0;
    int spec = mf_spec_slot(config->fresnel), diffuse = mf_diffuse_slot(config->fresnel);
    for (int c = 0; c < 3; c++) {
        state->spec[c] = v[spec + c];
        state->diffuse_over_pi[c] = diffuse >= 0 ? v[diffuse + c] * MR_INV_PI : 0.0;
        state->eta[c] = config->fresnel == MF_CONDUCTOR ? v[MF_COND_ETA + c] : 1.0;
        state->k[c] = config->fresnel == MF_CONDUCTOR ? v[MF_COND_K + c] : 0.0;
    }
}

/* mr_mf_dg with a constant distribution in each branch, so that each copy is specialised for it (the render
 * loop's hot path; a call with the distribution as a variable was not inlined). */
static double mf_dg(mr_mf_dist dist, double alpha, const mr_brdf_geom *g) {
    switch (dist) {
    case MR_MF_GGX: return mr_mf_dg(MR_MF_GGX, alpha, g, 1, NULL);
    case MR_MF_BECKMANN: return mr_mf_dg(MR_MF_BECKMANN, alpha, g, 1, NULL);
    default: return mr_mf_dg(MR_MF_EPHONG, alpha, g, 1, NULL);
    }
}

static void mf_eval(const void *state_bytes, const double wi[3], const double wo[3], double diffuse[3],
                    double specular[3]) {
    const mf_state *state = state_bytes;
    mr_brdf_geom g;
    if (!mr_brdf_geom_init(wi, wo, &g)) {
        mr_brdf_zero(diffuse, specular);
        return;
    }
    if (diffuse) {
        double transmit = 1.0; /* -plastic: through the smooth interface, in and out */
        if (state->fresnel == MF_PLASTIC)
            transmit = (1.0 - mr_fresnel_dielectric(g.cos_i, state->ior, NULL)) *
                       (1.0 - mr_fresnel_dielectric(g.cos_o, state->ior, NULL));
        for (int c = 0; c < 3; c++) diffuse[c] = state->diffuse_over_pi[c] * transmit;
    }
    if (specular) {
        double dg = mf_dg(state->dist, state->alpha, &g);
        switch (state->fresnel) {
        case MF_SCHLICK: {
            double w = mr_schlick_weight(g.dot_h);
            for (int c = 0; c < 3; c++) specular[c] = (state->spec[c] + (1.0 - state->spec[c]) * w) * dg;
            break;
        }
        case MF_NONE:
            for (int c = 0; c < 3; c++) specular[c] = state->spec[c] * dg;
            break;
        case MF_CONDUCTOR:
            for (int c = 0; c < 3; c++)
                specular[c] = dg > 0.0 ? state->spec[c] *
                                             mr_fresnel_conductor(g.dot_h, state->eta[c], state->k[c], NULL, NULL) * dg
                                       : 0.0;
            break;
        default: {
            double F = mr_fresnel_dielectric(g.dot_h, state->ior, NULL);
            for (int c = 0; c < 3; c++) specular[c] = state->spec[c] * F * dg;
            break;
        }
        }
    }
}

/* eval over a batch for one distribution and Fresnel mode (constants in each call below, so each of the twelve
 * loops is specialised): mf_eval's operations, mr_batch_mf_dg for mr_mf_dg. */
MR_BATCH_INLINE void mf_batch_loop(const mf_state *state, const mr_brdf_batch *batch, const mr_mf_dist dist,
                                   const mf_fresnel fresnel, const int fused) {
    const double alpha = state->alpha, ior = state->ior;
    const double d0 = state->diffuse_over_pi[0], d1 = state->diffuse_over_pi[1], d2 = state->diffuse_over_pi[2];
    const double r0 = state->spec[0], r1 = state->spec[1], r2 = state->spec[2];
    const double e0 = state->eta[0], e1 = state->eta[1], e2 = state->eta[2];
    const double k0 = state->k[0], k1 = state->k[1], k2 = state->k[2];
    MR_BATCH_ARRAYS(batch);
#pragma omp simd
    for (int i = 0; i < n_; i++) {
        mr_brdf_geom g;
        const int lit = mr_batch_geom(ix_[i], iy_[i], iz_[i], ox_[i], oy_[i], oz_[i], &g);
        double transmit = 1.0;
        if (fresnel == MF_PLASTIC)
            transmit = (1.0 - mr_fresnel_dielectric(g.cos_i, ior, NULL)) *
                       (1.0 - mr_fresnel_dielectric(g.cos_o, ior, NULL));
        const double dg = lit ? mr_batch_mf_dg(dist, alpha, &g, 1, fused) : 0.0;
        double f0 = r0, f1 = r1, f2 = r2; /* per channel: the factor of dg */
        if (fresnel == MF_SCHLICK) {
            const double w = mr_schlick_weight(g.dot_h);
            f0 = r0 + (1.0 - r0) * w;
            f1 = r1 + (1.0 - r1) * w;
            f2 = r2 + (1.0 - r2) * w;
        } else if (fresnel == MF_CONDUCTOR) {
            f0 = r0 * mr_batch_fresnel_conductor(g.dot_h, e0, k0);
            f1 = r1 * mr_batch_fresnel_conductor(g.dot_h, e1, k1);
            f2 = r2 * mr_batch_fresnel_conductor(g.dot_h, e2, k2);
        } else if (fresnel == MF_PLASTIC) {
            const double F = mr_fresnel_dielectric(g.dot_h, ior, NULL);
            f0 = r0 * F;
            f1 = r1 * F;
            f2 = r2 * F;
        }
        // mf_eval: (F0 + (1 - F0) w) dg, rho_s dg, rho_s F_cond dg (0 where dg is), rho_s F dg.
        s0_[i] = f0 * dg;
        s1_[i] = f1 * dg;
        s2_[i] = f2 * dg;
        d0_[i] = lit ? d0 * transmit : 0.0;
        d1_[i] = lit ? d1 * transmit : 0.0;
        d2_[i] = lit ? d2 * transmit : 0.0;
    }
}

#define MF_BATCH_CASES(dist)                                                                                     \
    switch (state->fresnel) {                                                                                    \
    case MF_SCHLICK: mf_batch_loop(state, batch, dist, MF_SCHLICK, fused); break;                                \
    case MF_NONE: mf_batch_loop(state, batch, dist, MF_NONE, fused); break;                                      \
    case MF_CONDUCTOR: mf_batch_loop(state, batch, dist, MF_CONDUCTOR, fused); break;                            \
    default: mf_batch_loop(state, batch, dist, MF_PLASTIC, fused); break;                                        \
    }

MR_BATCH_INLINE void mf_batch_body(const void *state_bytes, const mr_brdf_batch *batch, const int fused) {
    const mf_state *state = state_bytes;
    switch (state->dist) {
    case MR_MF_GGX: MF_BATCH_CASES(MR_MF_GGX) break;
    case MR_MF_BECKMANN: MF_BATCH_CASES(MR_MF_BECKMANN) break;
    default: MF_BATCH_CASES(MR_MF_EPHONG) break;
    }
}

MR_BATCH_KERNEL(mf_eval_batch, mf_batch_body)

/* mr_mf_G1's value in float (Beckmann's rational fit for Beckmann and EPhong, GGX's closed form). */
MR_BATCH_INLINE float mf_batchf_G1(const mr_mf_dist dist, float alpha, float cos_v, float sin2_v) {
    if (dist == MR_MF_GGX) {
        const float s = sqrtf(1.0f + alpha * alpha * (sin2_v / (cos_v * cos_v)));
        return 2.0f / (1.0f + s);
    }
    const float a = cos_v / (alpha * sqrtf(MR_MAX(sin2_v, 1e-30f)));
    const float G = (3.535f * a + 2.181f * a * a) / (1.0f + 2.276f * a + 2.577f * a * a);
    return (sin2_v > 0.0f) & (a < 1.6f) ? G : 1.0f;
}

/* mr_batch_mf_dg in float with Mitsuba's cut-off (D cos_h < 1e-20 gives 0), written for float's range (brdf_batch.h,
 * "single precision"): GGX D = a^2 (|H|^2/root)^2/pi (root = a^2 H_z^2 + H_x^2 + H_y^2 >= 4e-32) and, as in
 * mr_batch_ggx_dg, G1 G1/(4 cos_i cos_o) = 1/((c_i + q_i)(c_o + q_o)); Beckmann 1/cos^4(theta_h) = (1 + tan^2)^2;
 * EPhong cos_h^n = exp(-n/2 log1p(tan^2)). Below an exp argument of -80 both have D cos_h < 6e-28 for every alpha
 * (Beckmann: e^-80 (1 + 80 a^2)^1.5/(pi a^2) at most 6e-28 at alpha = 1e-4; EPhong: (n + 2)/(2 pi) e^-80 <= 6e-28),
 * so Mitsuba's cut-off zeroes them anyway. */
MR_BATCH_INLINE float mf_batchf_dg(const mr_mf_dist dist, float alpha, const mr_batchf_geom_t *g, const int fused) {
    const float a2 = alpha * alpha, pi = (float)MR_PI;
    float D;
    if (dist == MR_MF_GGX) {
        const float t = g->h_len2 / (a2 * (g->hz * g->hz) + g->hxy2);
        D = a2 * t * t / pi;
        const float qi = sqrtf(g->cos_i * g->cos_i + a2 * g->sin2_i);
        const float qo = sqrtf(g->cos_o * g->cos_o + a2 * g->sin2_o);
        const float dg = D / ((g->cos_i + qi) * (g->cos_o + qo));
        return D * g->cos_h >= 1e-20f ? dg : 0.0f;
    }
    float x; /* exp's argument: where it is below -80, D cos_h < 6e-28 (cut off); it is clamped there, so that D
              * stays a normal float (a subnormal result costs ~100 cycles) */
    if (dist == MR_MF_BECKMANN) {
        x = -g->tan2_h / a2;
        const float sec2 = 1.0f + g->tan2_h;
        D = mr_batchf_exp(MR_MAX(x, -80.0f), fused) * ((sec2 * sec2) / (pi * a2));
    } else {
        const float n = MR_MAX(2.0f / a2 - 2.0f, 0.0f);
        x = -0.5f * n * mr_batchf_log1p(g->tan2_h, fused);
        D = (n + 2.0f) * (0.5f / pi) * mr_batchf_exp(MR_MAX(x, -80.0f), fused);
    }
    const float Gi = mf_batchf_G1(dist, alpha, g->cos_i, g->sin2_i);
    const float Go = mf_batchf_G1(dist, alpha, g->cos_o, g->sin2_o);
    const float dg = D * (Gi * Go * (1.0f / (4.0f * g->cos_i * g->cos_o)));
    return (x >= -80.0f) & (D * g->cos_h >= 1e-20f) ? dg : 0.0f;
}

/* mf_batch_loop in float (brdf_float.h). */
MR_BATCH_INLINE void mf_batchf_loop(const mf_state *state, const mr_brdf_batch *batch, const mr_mf_dist dist,
                                    const mf_fresnel fresnel, const int fused) {
    const float alpha = (float)state->alpha, ior = (float)state->ior;
    const float ior2_minus_1 = (float)(state->ior * state->ior - 1.0);
    const float d0 = (float)state->diffuse_over_pi[0], d1 = (float)state->diffuse_over_pi[1];
    const float d2 = (float)state->diffuse_over_pi[2];
    const float r0 = (float)state->spec[0], r1 = (float)state->spec[1], r2 = (float)state->spec[2];
    const float e0 = (float)state->eta[0], e1 = (float)state->eta[1], e2 = (float)state->eta[2];
    const float k0 = (float)state->k[0], k1 = (float)state->k[1], k2 = (float)state->k[2];
    MR_BATCH_ARRAYS(batch);
#pragma omp simd
    for (int i = 0; i < n_; i++) {
        mr_batchf_geom_t g;
        const int lit = mr_batchf_geom(ix_[i], iy_[i], iz_[i], ox_[i], oy_[i], oz_[i], &g);
        float transmit = 1.0f;
        if (fresnel == MF_PLASTIC)
            transmit = mr_batchf_dielectric_transmit(g.cos_i, ior, ior2_minus_1) *
                       mr_batchf_dielectric_transmit(g.cos_o, ior, ior2_minus_1);
        const float dg = lit ? mf_batchf_dg(dist, alpha, &g, fused) : 0.0f;
        float f0 = r0, f1 = r1, f2 = r2;
        if (fresnel == MF_SCHLICK) {
            const float w = mr_batchf_schlick_weight(g.dot_h);
            f0 = r0 + (1.0f - r0) * w;
            f1 = r1 + (1.0f - r1) * w;
            f2 = r2 + (1.0f - r2) * w;
        } else if (fresnel == MF_CONDUCTOR) {
            f0 = r0 * mr_batchf_fresnel_conductor(g.dot_h, e0, k0);
            f1 = r1 * mr_batchf_fresnel_conductor(g.dot_h, e1, k1);
            f2 = r2 * mr_batchf_fresnel_conductor(g.dot_h, e2, k2);
        } else if (fresnel == MF_PLASTIC) {
            const float F = mr_batchf_fresnel_dielectric(g.dot_h, ior, ior2_minus_1);
            f0 = r0 * F;
            f1 = r1 * F;
            f2 = r2 * F;
        }
        s0_[i] = f0 * dg;
        s1_[i] = f1 * dg;
        s2_[i] = f2 * dg;
        d0_[i] = lit ? d0 * transmit : 0.0f;
        d1_[i] = lit ? d1 * transmit : 0.0f;
        d2_[i] = lit ? d2 * transmit : 0.0f;
    }
}

#define MF_BATCHF_CASES(dist)                                                                                    \
    switch (state->fresnel) {                                                                                    \
    case MF_SCHLICK: mf_batchf_loop(state, batch, dist, MF_SCHLICK, fused); break;                               \
    case MF_NONE: mf_batchf_loop(state, batch, dist, MF_NONE, fused); break;                                     \
    case MF_CONDUCTOR: mf_batchf_loop(state, batch, dist, MF_CONDUCTOR, fused); break;                           \
    default: mf_batchf_loop(state, batch, dist, MF_PLASTIC, fused); break;                                       \
    }

MR_BATCH_INLINE void mf_batchf_body(const void *state_bytes, const mr_brdf_batch *batch, const int fused) {
    const mf_state *state = state_bytes;
    switch (state->dist) {
    case MR_MF_GGX: MF_BATCHF_CASES(MR_MF_GGX) break;
    case MR_MF_BECKMANN: MF_BATCHF_CASES(MR_MF_BECKMANN) break;
    default: MF_BATCHF_CASES(MR_MF_EPHONG) break;
    }
}

MR_BATCH_KERNEL(mf_eval_batch_float, mf_batchf_body)

mr_brdf_batch_fn mr_mf_float_kernel(const mr_brdf_model *model) {
    return model->eval == mf_eval ? mf_eval_batch_float : NULL;
}

static void mf_eval_grad(const mr_brdf_model *model, const double *values, const double wi[3],
                         const double wo[3], double *d_diffuse, double *d_specular) {
    const mf_config *config = model->config;
    mr_brdf_geom g;
    double v[MR_BRDF_MAX_VALUES];
    if (!mr_brdf_grad_begin(model, values, wi, wo, d_diffuse, d_specular, &g, v)) return;
    int spec = mf_spec_slot(config->fresnel), diffuse = mf_diffuse_slot(config->fresnel);
    double d_dg;
    double dg = mr_mf_dg(config->dist, v[MF_ALPHA], &g, 1, &d_dg);

    /* specular_c = rho_s F dg; Schlick has no rho_s (1) and its F0 inside F */
    for (int c = 0; c < 3; c++) {
        double rho = v[spec + c], F = 1.0;
        switch (config->fresnel) {
        case MF_SCHLICK: {
            double w = mr_schlick_weight(g.dot_h);
            F = rho + (1.0 - rho) * w;
            rho = 1.0;
            d_specular[(spec + c) * 3 + c] = (1.0 - w) * dg; /* dF/dF0 dg */
            break;
        }
        case MF_NONE:
            d_specular[(spec + c) * 3 + c] = dg;
            break;
        case MF_CONDUCTOR: {
            double dF_deta, dF_dk;
            F = mr_fresnel_conductor(g.dot_h, v[MF_COND_ETA + c], v[MF_COND_K + c], &dF_deta, &dF_dk);
            d_specular[(spec + c) * 3 + c] = F * dg;
            d_specular[(MF_COND_ETA + c) * 3 + c] = rho * dF_deta * dg;
            d_specular[(MF_COND_K + c) * 3 + c] = rho * dF_dk * dg;
            break;
        }
        default: {
            double dF_dior;
            F = mr_fresnel_dielectric(g.dot_h, v[MF_PLASTIC_IOR], &dF_dior);
            d_specular[(spec + c) * 3 + c] = F * dg;
            d_specular[MF_PLASTIC_IOR * 3 + c] = rho * dF_dior * dg;
            break;
        }
        }
        d_specular[MF_ALPHA * 3 + c] = rho * F * d_dg;
    }

    if (diffuse < 0) return;
    double transmit = 1.0, d_transmit = 0.0;
    if (config->fresnel == MF_PLASTIC) {
        double dFi, dFo;
        double Fi = mr_fresnel_dielectric(g.cos_i, v[MF_PLASTIC_IOR], &dFi);
        double Fo = mr_fresnel_dielectric(g.cos_o, v[MF_PLASTIC_IOR], &dFo);
        transmit = (1.0 - Fi) * (1.0 - Fo);
        d_transmit = -dFi * (1.0 - Fo) - (1.0 - Fi) * dFo;
    }
    for (int c = 0; c < 3; c++) {
        d_diffuse[(diffuse + c) * 3 + c] = transmit * MR_INV_PI;
        if (config->fresnel == MF_PLASTIC) d_diffuse[MF_PLASTIC_IOR * 3 + c] = v[diffuse + c] * MR_INV_PI * d_transmit;
    }
}

/* d f_r / d alpha at a lit pair's geometry into d[3], as mf_eval_grad computes it: rho F d_dg per channel (the
 * diffuse lobe does not depend on alpha; Schlick's rho is inside its F). Shared by grad_ops eval and eval_batch. */
MR_BATCH_INLINE void mf_shape_derivative(const mr_mf_dist dist, const mf_fresnel fresnel, const double *v,
                                         const mr_brdf_geom *g, double d[3]) {
    const int spec = mf_spec_slot(fresnel);
    double d_dg;
    mr_mf_dg(dist, v[MF_ALPHA], g, 1, &d_dg);
    for (int c = 0; c < 3; c++) {
        double rho = v[spec + c], F = 1.0, unused, unused2;
        if (fresnel == MF_SCHLICK) {
            F = rho + (1.0 - rho) * mr_schlick_weight(g->dot_h);
            rho = 1.0;
        } else if (fresnel == MF_CONDUCTOR) {
            F = mr_fresnel_conductor(g->dot_h, v[MF_COND_ETA + c], v[MF_COND_K + c], &unused, &unused2);
        } else if (fresnel == MF_PLASTIC) {
            F = mr_fresnel_dielectric(g->dot_h, v[MF_PLASTIC_IOR], &unused);
        }
        d[c] = rho * F * d_dg;
    }
}

/* Prepared derivatives (brdf.h, grad_ops): alpha alone, which the fits' projection asks for, computed here with
 * mf_eval_grad's own calls and expressions (rho F d_dg; the diffuse lobe does not depend on alpha); any other slots
 * by mf_eval_grad itself. */
static void mf_grad_prepare(const mr_brdf_model *model, const double *values, const int *slots, int count,
                            void *state) {
    mr_brdf_grad_slots_prepare(model, values, slots, count, MF_ALPHA, state);
}

static void mf_grad_eval(const void *state, const double wi[3], const double wo[3], double *d_diffuse,
                         double *d_specular) {
    const mr_brdf_grad_slots *st = state;
    if (!st->shape_only) {
        mr_brdf_grad_slots_eval(st, wi, wo, d_diffuse, d_specular);
        return;
    }
    const mf_config *config = st->model->config;
    for (int c = 0; c < 3; c++) d_diffuse[c] = d_specular[c] = 0.0;
    mr_brdf_geom g;
    if (mr_brdf_geom_init(wi, wo, &g)) mf_shape_derivative(config->dist, config->fresnel, st->v, &g, d_specular);
}

/* mf_grad_eval's alpha derivative over a batch (grad_ops eval_batch): mf_shape_derivative lane by lane, so the same
 * numbers (zeros where the pair is not lit). */
MR_BATCH_INLINE void mf_grad_batch_loop(const mr_brdf_grad_slots *st, const mr_brdf_batch *batch,
                                        const mr_mf_dist dist, const mf_fresnel fresnel) {
    MR_BATCH_ARRAYS(batch);
#pragma omp simd
    for (int i = 0; i < n_; i++) {
        mr_brdf_geom g;
        double d[3] = {0.0, 0.0, 0.0};
        if (mr_batch_geom(ix_[i], iy_[i], iz_[i], ox_[i], oy_[i], oz_[i], &g))
            mf_shape_derivative(dist, fresnel, st->v, &g, d);
        d0_[i] = d1_[i] = d2_[i] = 0.0;
        s0_[i] = d[0];
        s1_[i] = d[1];
        s2_[i] = d[2];
    }
}

#define MF_GRAD_BATCH_CASES(dist)                                                                                \
    switch (config->fresnel) {                                                                                   \
    case MF_SCHLICK: mf_grad_batch_loop(st, batch, dist, MF_SCHLICK); break;                                     \
    case MF_NONE: mf_grad_batch_loop(st, batch, dist, MF_NONE); break;                                           \
    case MF_CONDUCTOR: mf_grad_batch_loop(st, batch, dist, MF_CONDUCTOR); break;                                 \
    default: mf_grad_batch_loop(st, batch, dist, MF_PLASTIC); break;                                             \
    }

MR_BATCH_INLINE void mf_grad_batch_body(const void *state, const mr_brdf_batch *batch, const int fused) {
    (void)fused; // mr_mf_dg's own operations, unfused, in both variants
    const mr_brdf_grad_slots *st = state;
    const mf_config *config = st->model->config;
    switch (config->dist) {
    case MR_MF_GGX: MF_GRAD_BATCH_CASES(MR_MF_GGX) break;
    case MR_MF_BECKMANN: MF_GRAD_BATCH_CASES(MR_MF_BECKMANN) break;
    default: MF_GRAD_BATCH_CASES(MR_MF_EPHONG) break;
    }
}

MR_BATCH_KERNEL(mf_grad_eval_batch, mf_grad_batch_body)

static const mr_brdf_grad_ops mf_grad_ops = {sizeof(mr_brdf_grad_slots), mf_grad_prepare, mf_grad_eval,
                                             mr_brdf_grad_slots_batchable, mf_grad_eval_batch};

static const mf_config mf_configs[MR_MF_DIST_COUNT][4] = {
    {{MR_MF_BECKMANN, MF_SCHLICK}, {MR_MF_BECKMANN, MF_NONE}, {MR_MF_BECKMANN, MF_CONDUCTOR},
     {MR_MF_BECKMANN, MF_PLASTIC}},
    {{MR_MF_GGX, MF_SCHLICK}, {MR_MF_GGX, MF_NONE}, {MR_MF_GGX, MF_CONDUCTOR}, {MR_MF_GGX, MF_PLASTIC}},
    {{MR_MF_EPHONG, MF_SCHLICK}, {MR_MF_EPHONG, MF_NONE}, {MR_MF_EPHONG, MF_CONDUCTOR}, {MR_MF_EPHONG, MF_PLASTIC}},
};

#define MF_DESCRIPTOR(cname, mname, msummary, msource, table, mflags, dist, fresnel)                     \
    const mr_brdf_model cname = {                                                                        \
        .name = mname,                                                                                   \
        .summary = msummary,                                                                             \
        .source = msource,                                                                               \
        .param_count = (int)(sizeof table / sizeof table[0]),                                            \
        .params = table,                                                                                 \
        .flags = mflags,                                                                                 \
        .config = &mf_configs[dist][fresnel],                                                            \
        .prepare = mf_prepare,                                                                           \
        .eval = mf_eval,                                                                                 \
        .eval_batch = mf_eval_batch,                                                                     \
        .eval_grad = mf_eval_grad,                                                                       \
        .grad_ops = &mf_grad_ops,                                                                        \
    }

#define MF_SRC_PBR "Mitsuba 0.6 microfacet.h + the authors' pbr.cpp (Schlick F0)"
#define MF_SRC_NONE "Mitsuba 0.6 microfacet.h (F = 1)"
#define MF_SRC_COND "Mitsuba 0.6 roughconductor.cpp + microfacet.h"
#define MF_SRC_PLASTIC "Mitsuba 0.6 microfacet.h + roughplastic.cpp (simplified diffuse)"

MF_DESCRIPTOR(mr_brdf_beckmann, "beckmann", "Beckmann microfacet, Smith G, Schlick F0 (paper's Mitsuba-Pbr-Beckmann)",
              MF_SRC_PBR, mf_schlick_params, MR_BRDF_INDEPENDENT_LOBES, MR_MF_BECKMANN, MF_SCHLICK);
MF_DESCRIPTOR(mr_brdf_ggx, "ggx", "GGX microfacet, separable Smith G, Schlick F0 (Mitsuba pbr plugin)", MF_SRC_PBR,
              mf_schlick_params, MR_BRDF_INDEPENDENT_LOBES, MR_MF_GGX, MF_SCHLICK);
MF_DESCRIPTOR(mr_brdf_as, "as", "Mitsuba 0.5.1+ EPhong/Ashikhmin-Shirley microfacet, Schlick F0 (Mitsuba-Pbr-AS)",
              MF_SRC_PBR, mf_schlick_params, MR_BRDF_INDEPENDENT_LOBES | MR_BRDF_NOT_ENERGY_CONSERVING, MR_MF_EPHONG,
              MF_SCHLICK);
MF_DESCRIPTOR(mr_brdf_beckmann_nofresnel, "beckmann-nofresnel", "Beckmann microfacet D G, F = 1, specular scale",
              MF_SRC_NONE, mf_none_params, MR_BRDF_INDEPENDENT_LOBES, MR_MF_BECKMANN, MF_NONE);
MF_DESCRIPTOR(mr_brdf_ggx_nofresnel, "ggx-nofresnel", "GGX microfacet D G, F = 1, specular scale", MF_SRC_NONE,
              mf_none_params, MR_BRDF_INDEPENDENT_LOBES, MR_MF_GGX, MF_NONE);
MF_DESCRIPTOR(mr_brdf_as_nofresnel, "as-nofresnel", "EPhong/AS microfacet D G, F = 1, specular scale", MF_SRC_NONE,
              mf_none_params, MR_BRDF_INDEPENDENT_LOBES | MR_BRDF_NOT_ENERGY_CONSERVING, MR_MF_EPHONG, MF_NONE);
MF_DESCRIPTOR(mr_brdf_beckmann_conductor, "beckmann-conductor",
              "Mitsuba roughconductor, Beckmann, exact Fresnel (eta, k)", MF_SRC_COND, mf_conductor_params, 0,
              MR_MF_BECKMANN, MF_CONDUCTOR);
MF_DESCRIPTOR(mr_brdf_ggx_conductor, "ggx-conductor", "Mitsuba roughconductor, GGX, exact Fresnel (eta, k)",
              MF_SRC_COND, mf_conductor_params, 0, MR_MF_GGX, MF_CONDUCTOR);
MF_DESCRIPTOR(mr_brdf_as_conductor, "as-conductor", "Mitsuba roughconductor, EPhong/AS, exact Fresnel (eta, k)",
              MF_SRC_COND, mf_conductor_params, MR_BRDF_NOT_ENERGY_CONSERVING, MR_MF_EPHONG, MF_CONDUCTOR);
MF_DESCRIPTOR(mr_brdf_beckmann_plastic, "beckmann-plastic", "rough plastic, Beckmann: dielectric Fresnel over Lambert",
              MF_SRC_PLASTIC, mf_plastic_params, 0, MR_MF_BECKMANN, MF_PLASTIC);
MF_DESCRIPTOR(mr_brdf_ggx_plastic, "ggx-plastic", "rough plastic, GGX: dielectric Fresnel over Lambert",
              MF_SRC_PLASTIC, mf_plastic_params, 0, MR_MF_GGX, MF_PLASTIC);
MF_DESCRIPTOR(mr_brdf_as_plastic, "as-plastic", "rough plastic, EPhong/AS: dielectric Fresnel over Lambert",
              MF_SRC_PLASTIC, mf_plastic_params, 0, MR_MF_EPHONG, MF_PLASTIC);
