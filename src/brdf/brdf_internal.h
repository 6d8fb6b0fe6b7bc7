/*
 * brdf_internal.h — math shared by the model files of src/brdf; internal, not installed.
 *
 * Everything is static inline, so each model file takes only what it uses. Formulas cite sections of
 * docs/brdf-reference.md (in ../shared) and the renderer file they were read from. The helpers that return a
 * derivative take a pointer for it, which may be NULL when only the value is wanted (eval's hot path).
 *
 * Conventions: directions are unit vectors in the local frame, n = (0,0,1) (brdf.h). The helpers assume the
 * caller already returned 0 below the horizon (mr_brdf_geom_init does both at once).
 */
#ifndef MR_BRDF_INTERNAL_H
#define MR_BRDF_INTERNAL_H

#include <math.h>
#include <string.h>

#include "../mr_internal.h"
#include "brdf.h"

/* Cosines of directions above the horizon are raised to at least this before any formula sees them.
 * brdf.h promises finite values for every pair with z > 0, and z may be as small as a denormal: then
 * 1/(cos_i cos_o) (ward-duer), H_z^4 (ward-balanced) or |wi + wo|^2 would overflow or underflow to 0.
 * 1e-12 rad above the horizon changes nothing a renderer can resolve, and keeps every intermediate product
 * inside double range (the smallest is H_z^4 >= 1.6e-47). */
#define MR_BRDF_COS_MIN 1e-12

/* Geometry of one (wi, wo) pair, computed once per eval. Every field is symmetric in (wi, wo), so models
 * built from these fields are reciprocal by construction. */
typedef struct mr_brdf_geom {
    double cos_i, cos_o;   /* wi.z and wo.z, raised to MR_BRDF_COS_MIN */
    double sin2_i, sin2_o; /* x^2 + y^2 of wi and wo: sin^2(theta) without the cancellation of 1 - z^2 */
    double hx, hy, hz;     /* H = wi + wo, not normalised (Ward uses it as is, brdf-reference 2.1) */
    double h_len2;         /* H.H */
    double cos_h;          /* n.h for h = H/|H| */
    double sin2_h;         /* 1 - cos_h^2, computed as (H_x^2 + H_y^2)/H.H */
    double tan2_h;         /* tan^2(theta_h) = (H_x^2 + H_y^2)/H_z^2 */
    double dot_h;          /* wi.h = wo.h = |H|/2 for unit vectors (one value, so F(wi.h) is reciprocal) */
} mr_brdf_geom;

/* Fills *g and returns 1 if both directions are strictly above the horizon; returns 0 otherwise (the caller
 * then outputs 0, brdf.h). NaN cosines count as below the horizon. */
static inline int mr_brdf_geom_init(const double wi[3], const double wo[3], mr_brdf_geom *g) {
    if (!(wi[2] > 0.0 && wo[2] > 0.0)) return 0;
    g->cos_i = wi[2] > MR_BRDF_COS_MIN ? wi[2] : MR_BRDF_COS_MIN;
    g->cos_o = wo[2] > MR_BRDF_COS_MIN ? wo[2] : MR_BRDF_COS_MIN;
    g->sin2_i = wi[0] * wi[0] + wi[1] * wi[1];
    g->sin2_o = wo[0] * wo[0] + wo[1] * wo[1];
    g->hx = wi[0] + wo[0];
    g->hy = wi[1] + wo[1];
    g->hz = g->cos_i + g->cos_o;
    double hxy2 = g->hx * g->hx + g->hy * g->hy;
    g->h_len2 = hxy2 + g->hz * g->hz; /* >= hz^2 >= 4e-24: no underflow */
    g->cos_h = g->hz / sqrt(g->h_len2);
    g->sin2_h = hxy2 / g->h_len2;
    g->tan2_h = hxy2 / (g->hz * g->hz);
    g->dot_h = MR_MIN(0.5 * sqrt(g->h_len2), 1.0);
    return 1;
}

/* Writes 0 to both outputs (either may be NULL): below the horizon. */
static inline void mr_brdf_zero(double diffuse[3], double specular[3]) {
    for (int c = 0; c < 3; c++) {
        if (diffuse) diffuse[c] = 0.0;
        if (specular) specular[c] = 0.0;
    }
}

/* Copies values[] into out[] (MR_BRDF_MAX_VALUES doubles), each slot clamped into its parameter's
 * [min, max] with NaN going to min: the clamping brdf.h asks of prepare(). */
static inline void mr_brdf_clamp_values(const mr_brdf_model *model, const double *values, double *out) {
    int slot = 0;
    for (int i = 0; i < model->param_count; i++) {
        const mr_brdf_param *p = &model->params[i];
        for (int c = 0; c < p->channels; c++, slot++) out[slot] = mr_clampd(values[slot], p->min_value, p->max_value);
    }
}

/* The common start of every eval_grad: zeroes both gradient arrays (value_count * 3 doubles each) and returns 0
 * below the horizon, where the gradient is 0; otherwise fills *g and the clamped values v[MR_BRDF_MAX_VALUES] and
 * returns 1. */
static inline int mr_brdf_grad_begin(const mr_brdf_model *model, const double *values, const double wi[3],
                                     const double wo[3], double *d_diffuse, double *d_specular, mr_brdf_geom *g,
                                     double *v) {
    int count = mr_brdf_value_count(model);
    for (int j = 0; j < count * 3; j++) d_diffuse[j] = d_specular[j] = 0.0;
    if (!mr_brdf_geom_init(wi, wo, g)) return 0;
    mr_brdf_clamp_values(model, values, v);
    return 1;
}

/* ---- prepared derivatives of the hand-written models (brdf.h, grad_ops) ---- */

/* Their prepared state: the values as given and clamped, the slots asked for, and whether that is the lobe's shape
 * parameter alone (`shape_slot`), which the fits' projection asks for at every step and a model's grad_ops eval
 * computes by itself; any other set of slots is taken from eval_grad (mr_brdf_grad_slots_eval), so the numbers are
 * eval_grad's either way (tests/test_brdf.c checks them equal). */
typedef struct mr_brdf_grad_slots {
    const mr_brdf_model *model;
    double values[MR_BRDF_MAX_VALUES]; /* as given */
    double v[MR_BRDF_MAX_VALUES];      /* clamped, as eval_grad clamps them */
    int slots[MR_BRDF_MAX_VALUES];
    int count;
    int shape_only;                    /* count == 1 and slots[0] == the shape slot */
    double scale;                      /* a model's own prepared factor (Ward: Mitsuba's trimming scale) */
} mr_brdf_grad_slots;

static inline void mr_brdf_grad_slots_prepare(const mr_brdf_model *model, const double *values, const int *slots,
                                              int count, int shape_slot, mr_brdf_grad_slots *state) {
    const int n = mr_brdf_value_count(model);
    state->model = model;
    memcpy(state->values, values, (size_t)n * sizeof *values);
    mr_brdf_clamp_values(model, values, state->v);
    memcpy(state->slots, slots, (size_t)count * sizeof *slots);
    state->count = count;
    state->shape_only = count == 1 && slots[0] == shape_slot;
    state->scale = 1.0;
}

/* grad_ops batchable (brdf.h) for these states: the shape slot alone, whose derivative leaves the diffuse part
 * unchanged; a model with a batched shape derivative points its grad_ops at this. */
static inline int mr_brdf_grad_slots_batchable(const void *state) {
    return ((const mr_brdf_grad_slots *)state)->shape_only;
}

/* Any set of slots: eval_grad's numbers, copied out for the slots asked for. */
static inline void mr_brdf_grad_slots_eval(const mr_brdf_grad_slots *state, const double wi[3], const double wo[3],
                                           double *d_diffuse, double *d_specular) {
    double all_d[MR_BRDF_MAX_VALUES * 3], all_s[MR_BRDF_MAX_VALUES * 3];
    state->model->eval_grad(state->model, state->values, wi, wo, all_d, all_s);
    for (int k = 0; k < state->count; k++)
        for (int c = 0; c < 3; c++) {
            d_diffuse[k * 3 + c] = all_d[state->slots[k] * 3 + c];
            d_specular[k * 3 + c] = all_s[state->slots[k] * 3 + c];
        }
}

/* ---- Mitsuba 0.6 energy trimming (src/librender/bsdf.cpp ensureEnergyConservation; brdf-reference 2.1) ---- */

/* If enabled and m = max over channels of (diffuse + specular) exceeds 1, Mitsuba scales BOTH reflectances by
 * 0.99/m. For constant textures the per-texture maxima are the values themselves. */
typedef struct mr_brdf_trim {
    int active;    /* 1 if the scaling applies */
    int argmax;    /* channel attaining m (the first one on ties) */
    double max;    /* m */
    double scale;  /* 0.99/m if active, else 1 */
} mr_brdf_trim;

static inline mr_brdf_trim mr_brdf_trim_compute(const double diffuse[3], const double specular[3], int enabled) {
    mr_brdf_trim t = {0, 0, diffuse[0] + specular[0], 1.0};
    for (int c = 1; c < 3; c++)
        if (diffuse[c] + specular[c] > t.max) {
            t.max = diffuse[c] + specular[c];
            t.argmax = c;
        }
    if (enabled && t.max > 1.0) {
        t.active = 1;
        t.scale = 0.99 / t.max;
    }
    return t;
}

/* Whether Mitsuba trims at these packed values (the `rescales` hook of brdf.h): the model's values clamped, its
 * diffuse and specular RGB at slots `diffuse` and `specular`, its trim switch at slot `trim`. */
static inline int mr_brdf_trim_engaged(const mr_brdf_model *model, const double *values, int diffuse, int specular,
                                       int trim) {
    double v[MR_BRDF_MAX_VALUES];
    mr_brdf_clamp_values(model, values, v);
    return mr_brdf_trim_compute(v + diffuse, v + specular, v[trim] >= 0.5).active;
}

/* Gradient of f = trim(rho_d)/pi (diffuse part) + trim(rho_s) * lobe (specular part) with respect to the raw
 * rho_d (slots slot_d..+2) and rho_s (slots slot_s..+2), written into the [slot*3 + channel] arrays.
 * With trimming active, x' = 0.99 x/m and dm/dx_c' = [c' == argmax] for both x = rho_d and x = rho_s, so
 *   d x'_c / d x_c'  = 0.99 ([c == c']/m - [c' == argmax] x_c/m^2)
 *   d x'_c / d y_c'  = -0.99 [c' == argmax] x_c/m^2          (y the other reflectance)
 * The derivative is one-sided at the trimming boundary m = 1 and where two channels tie for the maximum. */
static inline void mr_brdf_trim_grad(const mr_brdf_trim *t, const double rho_d[3], const double rho_s[3],
                                     double lobe, int slot_d, int slot_s, double *d_diffuse, double *d_specular) {
    for (int cp = 0; cp < 3; cp++)
        for (int c = 0; c < 3; c++) {
            double own = c == cp ? 1.0 : 0.0;
            double dd_dd = own, ds_ds = own, dd_ds = 0.0, ds_dd = 0.0; /* d(trimmed x)/d(raw y) */
            if (t->active) {
                double on_max = cp == t->argmax ? 1.0 : 0.0;
                double m2 = t->max * t->max;
                dd_dd = 0.99 * (own / t->max - on_max * rho_d[c] / m2);
                ds_ds = 0.99 * (own / t->max - on_max * rho_s[c] / m2);
                ds_dd = -0.99 * on_max * rho_s[c] / m2;
                dd_ds = -0.99 * on_max * rho_d[c] / m2;
            }
            d_diffuse[(slot_d + cp) * 3 + c] = dd_dd * MR_INV_PI;
            d_specular[(slot_d + cp) * 3 + c] = ds_dd * lobe;
            d_diffuse[(slot_s + cp) * 3 + c] = dd_ds * MR_INV_PI;
            d_specular[(slot_s + cp) * 3 + c] = ds_ds * lobe;
        }
}

/* ---- microfacet distributions (Mitsuba 0.6 src/bsdfs/microfacet.h; brdf-reference 2.3, 4.1) ---- */

typedef enum mr_mf_dist {
    MR_MF_BECKMANN = 0,
    MR_MF_GGX,
    MR_MF_EPHONG, /* Mitsuba 0.5.1+ "phong" == "as": Phong/Ashikhmin-Shirley distribution, Walter exponent */
    MR_MF_DIST_COUNT
} mr_mf_dist;

/* Isotropic D(h) for roughness alpha > 0 at cos_h > 0, tan2_h = tan^2(theta_h), sin2_h = sin^2(theta_h).
 * Writes dD/dalpha to *d_dalpha if non-NULL. No cut-off here: Mitsuba's (D cos_h < 1e-20 -> 0) is applied by
 * the Mitsuba models, glTF and Cycles have none.
 *   Beckmann: exp(-tan^2/a^2) / (pi a^2 cos^4)
 *   GGX:      a^2 / (pi (a^2 cos^2 + sin^2)^2)  (== 1/(pi a^2 cos^4 (1 + tan^2/a^2)^2), Mitsuba; == glTF 5.1 D;
 *             == Cycles' alpha2/(pi cos^4 (alpha2 + tan^2)^2) with alpha2 = a^2)
 *   EPhong:   (n+2)/(2 pi) cos^n,  n = max(2/a^2 - 2, 0)  (Walter et al. 2007) */
static inline double mr_mf_D(mr_mf_dist dist, double alpha, double cos_h, double tan2_h, double sin2_h,
                             double *d_dalpha) {
    double a2 = alpha * alpha, c2 = cos_h * cos_h, D, dD;
    switch (dist) {
    case MR_MF_BECKMANN:
        D = exp(-tan2_h / a2) / (MR_PI * a2 * c2 * c2);
        dD = D * (2.0 * tan2_h / (a2 * alpha) - 2.0 / alpha);
        break;
    case MR_MF_GGX: {
        /* a^2 cos^2 + sin^2 >= a^2 min(1, ...) > 0; written without 1 - cos^2 to avoid cancellation */
        double root = a2 * c2 + sin2_h;
        D = a2 / (MR_PI * root * root);
        dD = D * (2.0 / alpha - 4.0 * alpha * c2 / root);
        break;
    }
    default: {
        double n = 2.0 / a2 - 2.0;
        double p = n > 0.0 ? pow(cos_h, n) : 1.0;
        D = (MR_MAX(n, 0.0) + 2.0) * (0.5 * MR_INV_PI) * p;
        /* dD/dn = cos^n/(2 pi) + D ln(cos_h); dn/dalpha = -4/alpha^3 (0 where n is clamped at 0, alpha = 1) */
        dD = n > 0.0 ? (p * (0.5 * MR_INV_PI) + D * log(cos_h)) * (-4.0 / (a2 * alpha)) : 0.0;
        break;
    }
    }
    if (d_dalpha) *d_dalpha = dD;
    return D;
}

/* Smith G1 of Mitsuba 0.6 microfacet.h smithG1() for the isotropic case and m = h (so (v.m)(v.n) > 0 holds
 * whenever both directions are above the horizon), at cos_v > 0 with sin2_v = sin^2(theta_v):
 *   tan = 0:          1
 *   Beckmann, EPhong: a = 1/(alpha tan); 1 if a >= 1.6, else (3.535 a + 2.181 a^2)/(1 + 2.276 a + 2.577 a^2)
 *   GGX:              2/(1 + sqrt(1 + alpha^2 tan^2))   (also Cycles <= 3.4's separable G1, brdf-reference 4.1)
 * Writes dG1/dalpha to *d_dalpha if non-NULL (0 on the flat a >= 1.6 branch; one-sided at a = 1.6). */
static inline double mr_mf_G1(mr_mf_dist dist, double alpha, double cos_v, double sin2_v, double *d_dalpha) {
    double G = 1.0, dG = 0.0;
    if (sin2_v > 0.0) {
        if (dist == MR_MF_GGX) { /* in tan^2, one square root fewer: the render loop's costliest operations */
            double tan2_v = sin2_v / (cos_v * cos_v), s = sqrt(1.0 + alpha * alpha * tan2_v);
            G = 2.0 / (1.0 + s);
            dG = -2.0 / ((1.0 + s) * (1.0 + s)) * (alpha * tan2_v / s);
        } else {
            double a = cos_v / (alpha * sqrt(sin2_v));
            if (a < 1.6) {
                double num = 3.535 * a + 2.181 * a * a, den = 1.0 + 2.276 * a + 2.577 * a * a;
                G = num / den;
                double dG_da = ((3.535 + 4.362 * a) * den - num * (2.276 + 5.154 * a)) / (den * den);
                dG = dG_da * (-a / alpha);
            }
        }
    }
    if (d_dalpha) *d_dalpha = dG;
    return G;
}

/* D G1(wi) G1(wo) / (4 cos_i cos_o), the microfacet lobe without Fresnel, with its alpha derivative if d_dalpha.
 * mitsuba_cutoff applies Mitsuba's D = 0 where D cos_h < 1e-20 (microfacet.h eval(): "prevent potential numerical
 * issues"); Cycles has no such cut-off. */
static inline double mr_mf_dg(mr_mf_dist dist, double alpha, const mr_brdf_geom *g, int mitsuba_cutoff,
                              double *d_dalpha) {
    double dD, dGi, dGo;
    double D = mr_mf_D(dist, alpha, g->cos_h, g->tan2_h, g->sin2_h, d_dalpha ? &dD : NULL);
    if (mitsuba_cutoff && !(D * g->cos_h >= 1e-20)) {
        if (d_dalpha) *d_dalpha = 0.0;
        return 0.0;
    }
    double Gi = mr_mf_G1(dist, alpha, g->cos_i, g->sin2_i, d_dalpha ? &dGi : NULL);
    double Go = mr_mf_G1(dist, alpha, g->cos_o, g->sin2_o, d_dalpha ? &dGo : NULL);
    double inv = 1.0 / (4.0 * g->cos_i * g->cos_o);
    if (d_dalpha) *d_dalpha = (dD * Gi * Go + D * dGi * Go + D * Gi * dGo) * inv;
    return D * Gi * Go * inv;
}

/* ---- Fresnel ---- */

/* (1 - c)^5, the Schlick weight; c in [0, 1]. */
static inline double mr_schlick_weight(double c) {
    double m = 1.0 - c;
    double m2 = m * m;
    return m2 * m2 * m;
}

/* Exact unpolarised dielectric Fresnel for light arriving from the outside (cos_i in (0, 1]) of a medium of
 * relative index eta >= 1: Mitsuba 0.6 fresnelDielectricExt (src/libcore/util.cpp, brdf-reference 2.5); Cycles'
 * fresnel_dielectric_cos (bsdf_util.h) is the same function written without the transmitted angle.
 *   cos_t = sqrt(1 - sin_i^2/eta^2); R_s = (c_i - eta c_t)/(c_i + eta c_t); R_p = (eta c_i - c_t)/(eta c_i + c_t)
 *   F = (R_s^2 + R_p^2)/2
 * Writes dF/deta to *dF_deta if non-NULL. Denominators are >= c_i > 0 and cos_t >= c_i (eta >= 1). */
static inline double mr_fresnel_dielectric(double cos_i, double eta, double *dF_deta) {
    double sin2 = MR_MAX(1.0 - cos_i * cos_i, 0.0);
    double cos_t = sqrt(MR_MAX(1.0 - sin2 / (eta * eta), 0.0));
    double u = eta * cos_t;
    double rs = (cos_i - u) / (cos_i + u);
    double den_p = eta * cos_i + cos_t;
    double rp = (eta * cos_i - cos_t) / den_p;
    if (dF_deta) {
        double dcos_t = cos_t > 0.0 ? sin2 / (eta * eta * eta * cos_t) : 0.0;
        double drs = -2.0 * cos_i * (cos_t + eta * dcos_t) / ((cos_i + u) * (cos_i + u));
        double drp = 2.0 * cos_i * (cos_t - eta * dcos_t) / (den_p * den_p);
        *dF_deta = rs * drs + rp * drp;
    }
    return mr_clampd(0.5 * (rs * rs + rp * rp), 0.0, 1.0);
}

/* Exact conductor Fresnel, Mitsuba 0.6 fresnelConductorExact (src/libcore/util.cpp, after Moeller's "Optics";
 * brdf-reference 2.4), for c = cos_i in (0, 1], relative index eta >= 0 and extinction k >= 0:
 *   t = eta^2 - k^2 - s^2, A = sqrt(t^2 + 4 eta^2 k^2), a = sqrt((A + t)/2)
 *   R_s = (A + c^2 - 2ac)/(A + c^2 + 2ac)
 *   R_p = R_s (A c^2 + s^4 - 2ac s^2)/(A c^2 + s^4 + 2ac s^2),  F = (R_s + R_p)/2
 * eta = 1, k = 0 gives 0; eta = 0, k = 1 (Mitsuba's material "none") gives 1.
 * Writes dF/deta and dF/dk if the pointers are non-NULL. Where A or a vanish (k = 0 with eta <= sin_i, a
 * square-root branch point) the derivative is infinite; there the chain term is dropped (set to 0) so the
 * result stays finite. The R_p ratio is 0/0 only for eta = k = 0 at normal incidence, where R_p = R_s. */
static inline double mr_fresnel_conductor(double c, double eta, double k, double *dF_deta, double *dF_dk) {
    double c2 = c * c, s2 = MR_MAX(1.0 - c2, 0.0), s4 = s2 * s2;
    double t = eta * eta - k * k - s2;
    double A = sqrt(t * t + 4.0 * eta * eta * k * k);
    double a = sqrt(MR_MAX(0.5 * (A + t), 0.0));
    double P = A + c2, Q = 2.0 * a * c;
    double rs = (P - Q) / (P + Q); /* P + Q >= c^2 > 0 */
    double U = A * c2 + s4, W = Q * s2;
    double ratio = U + W > 1e-300 ? (U - W) / (U + W) : 1.0;
    double rp = rs * ratio;
    if (dF_deta || dF_dk) {
        /* d/dx for x = eta (index 0) and x = k (index 1) */
        double dt[2] = {2.0 * eta, -2.0 * k};
        double dA2[2] = {2.0 * t * dt[0] + 8.0 * eta * k * k, 2.0 * t * dt[1] + 8.0 * eta * eta * k}; /* d(A^2) */
        double out[2];
        for (int x = 0; x < 2; x++) {
            double dA = A > 1e-150 ? dA2[x] / (2.0 * A) : 0.0;
            double da = a > 1e-150 ? (dA + dt[x]) / (4.0 * a) : 0.0;
            double dP = dA, dQ = 2.0 * c * da;
            double drs = 2.0 * (Q * dP - P * dQ) / ((P + Q) * (P + Q));
            double dU = c2 * dA, dW = s2 * dQ;
            double dratio = U + W > 1e-300 ? 2.0 * (W * dU - U * dW) / ((U + W) * (U + W)) : 0.0;
            double drp = drs * ratio + rs * dratio;
            out[x] = 0.5 * (drs + drp);
        }
        if (dF_deta) *dF_deta = out[0];
        if (dF_dk) *dF_dk = out[1];
    }
    return mr_clampd(0.5 * (rs + rp), 0.0, 1.0);
}

/* ---- artistic complex IOR (Gulbrandsen 2014, "Artist Friendly Metallic Fresnel", JCGT 3(4)) ---- */

/* The largest reflectivity r the mapping below accepts: at r = 1 its n_max = (1 + sqrt r)/(1 - sqrt r) is
 * infinite. Clamping r to 1 - 1e-9 moves the normal-incidence reflectance by at most 1e-9, and keeps n and k below
 * about 4e9, where mr_fresnel_conductor's squares (1.6e19) are still far inside double range. Through
 * mr_fresnel_conductor the round trip r -> (n, k) -> F(1) holds to 1e-9 up to r = 1 - 1e-6; beyond, with g near 1
 * (n ~ (1 - r)/2 next to k ~ 1), its a = sqrt((A + t)/2) cancels and F(1) is off by up to 1e-8. */
#define MR_ARTISTIC_R_MAX (1.0 - 1e-9)

/* Gulbrandsen's map from artist colours (per channel) to a conductor's complex index n + ik:
 *   r = reflectivity (normal-incidence reflectance) in [0, 1], clamped to [0, MR_ARTISTIC_R_MAX]
 *   g = edge tint in [0, 1] (clamped)
 *   n_min = (1 - r)/(1 + r),  n_max = (1 + sqrt r)/(1 - sqrt r),  n = g n_min + (1 - g) n_max
 *   k^2 = ((n + 1)^2 r - (n - 1)^2)/(1 - r)     (clamped at 0 against rounding)
 * so that the exact conductor Fresnel at normal incidence, ((n - 1)^2 + k^2)/((n + 1)^2 + k^2), is r again: the
 * numerator is 4 n r/(1 - r) and the denominator 4 n/(1 - r). Use it with mr_fresnel_conductor. r = 0 gives
 * n = 1, k = 0 (no reflection); g moves the reflectance towards grazing incidence. */
static inline void mr_artistic_ior(double r, double g, double *n, double *k) {
    r = mr_clampd(r, 0.0, MR_ARTISTIC_R_MAX);
    g = mr_clampd(g, 0.0, 1.0);
    double sr = sqrt(r);
    double n_min = (1.0 - r) / (1.0 + r), n_max = (1.0 + sr) / (1.0 - sr);
    double eta = g * n_min + (1.0 - g) * n_max;
    double k2 = ((eta + 1.0) * (eta + 1.0) * r - (eta - 1.0) * (eta - 1.0)) / (1.0 - r);
    *n = eta;
    *k = sqrt(MR_MAX(k2, 0.0));
}

/* ---- glTF 2.0 height-correlated Smith visibility (Specification.adoc Appendix B; brdf-reference 5.1) ---- */

/* V = G/(4 |n.l| |n.v|) = 1 / (2 (nv sqrt(a^2 + (1-a^2) nl^2) + nl sqrt(a^2 + (1-a^2) nv^2))), with the chi+
 * factors 1 above the horizon. a^2 + (1-a^2) x^2 is written as a^2 (1 - x^2) + x^2 (no cancellation, > 0).
 * The denominator is >= 4 alpha cos_i cos_o > 0 with the cosine floor. Writes dV/dalpha if non-NULL. */
static inline double mr_gltf_visibility(double alpha, double nl, double nv, double *d_dalpha) {
    double a2 = alpha * alpha;
    double root_l = sqrt(a2 * (1.0 - nl * nl) + nl * nl);
    double root_v = sqrt(a2 * (1.0 - nv * nv) + nv * nv);
    double sum = nv * root_l + nl * root_v;
    double V = 0.5 / sum;
    if (d_dalpha) {
        double dsum = nv * alpha * (1.0 - nl * nl) / root_l + nl * alpha * (1.0 - nv * nv) / root_v;
        *d_dalpha = -V * dsum / sum;
    }
    return V;
}

/* D V of GGX with the height-correlated V above: glTF's specular BRDF without F (brdf-reference 5.1), and Cycles
 * 3.5+'s GGX G2 D/(4 cos_i cos_o) (4.1), at alpha, with its alpha derivative if d_dalpha. */
static inline double mr_ggx_dv_correlated(double alpha, const mr_brdf_geom *g, double *d_dalpha) {
    double dD, dV;
    double D = mr_mf_D(MR_MF_GGX, alpha, g->cos_h, g->tan2_h, g->sin2_h, d_dalpha ? &dD : NULL);
    double V = mr_gltf_visibility(alpha, g->cos_i, g->cos_o, d_dalpha ? &dV : NULL);
    if (d_dalpha) *d_dalpha = dD * V + D * dV;
    return D * V;
}

/* ---- F82-tint metal Fresnel (Kutz et al. 2021, as OpenPBR 1.1 "Metal" writes it) ---- */

/* mu_bar = 1/7, the cosine of about 82 degrees where the tint is pinned. */
#define MR_F82_MU_BAR (1.0 / 7.0)

/* Schlick's curve F0 + (1 - F0)(1 - mu)^5, mu in [0, 1]. */
static inline double mr_schlick(double mu, double f0) { return f0 + (1.0 - f0) * mr_schlick_weight(mu); }

/* The F82-tint correction's coefficient b for one channel, so that mr_f82_tint(mu, f0, b) hits
 * tint * F_Schlick(mu_bar) at mu = mu_bar:  b = (1 - tint) F_Schlick(mu_bar) / (mu_bar (1 - mu_bar)^6). Computed
 * once per parameter set (prepare). */
static inline double mr_f82_coeff(double f0, double tint) {
    double m = 1.0 - MR_F82_MU_BAR, m2 = m * m, m6 = m2 * m2 * m2;
    return (1.0 - tint) * mr_schlick(MR_F82_MU_BAR, f0) / (MR_F82_MU_BAR * m6);
}

/* F82(mu) = F_Schlick(mu) - b mu (1 - mu)^6, clamped into [0, 1] (for black f0 and tint the curve dips a little
 * below 0 beside mu_bar; a reflectance cannot). */
static inline double mr_f82_tint(double mu, double f0, double b) {
    double m = 1.0 - mu, m2 = m * m;
    return mr_clampd(mr_schlick(mu, f0) - b * mu * m2 * m2 * m2, 0.0, 1.0);
}

/* ---- EON: energy-preserving Oren-Nayar (Portsmouth et al. 2024; OpenPBR 1.1 "Glossy-diffuse") ---- */

/* Fujii's Oren-Nayar f_ON = rho/pi (A + B s/t) with A = 1/(1 + c1 sigma), B = sigma A, c1 = 1/2 - 2/(3 pi),
 * s = wi.wo - cos_i cos_o, 1/t = 1 for s <= 0 and 1/max(cos_i, cos_o) for s > 0. Its rho-free directional
 * albedo is E(mu) = A + B g(mu) with (integrating s/t over the hemisphere in closed form)
 *   pi g = sin(th)(th - sin(th) cos(th)) + 2/3 tan(th)(1 - sin^3(th)) - 2/3 sin(th),  mu = cos(th),
 * and its cosine-weighted average is <E> = A + B <g>, <g> = 2/3 - 28/(15 pi). So that nothing cancels as
 * sigma -> 0, the code keeps 1 - E(mu) = sigma A (c1 - g(mu)) and 1 - <E> = sigma A (c1 - <g>). */
#define MR_EON_C1 (0.5 - 2.0 / (3.0 * MR_PI))
#define MR_EON_G_AVG (2.0 / 3.0 - 28.0 / (15.0 * MR_PI))

/* g(mu) above for mu in (0, 1]; 1 - sin^3 = (1 - sin)(1 + sin + sin^2) and 1 - sin = cos^2/(1 + sin) keep the
 * tan(th) term finite at grazing angles. */
static inline double mr_eon_g(double mu, double sin2) {
    double s = sqrt(sin2), th = atan2(s, mu);
    double t = s * (th - s * mu) + (2.0 / 3.0) * s * mu * (1.0 + s + sin2) / (1.0 + s) - (2.0 / 3.0) * s;
    return t * MR_INV_PI;
}

/* The per-parameter-set part of EON for one colour channel rho in [0, 1] and sigma in [0, 1]. */
typedef struct mr_eon {
    double A, B;          /* Fujii's coefficients */
    double sigma_A;       /* sigma A: 1 - E(mu) = sigma_A (c1 - g(mu)) */
    double comp[3];       /* rho_ms / (pi (c1 - <g>)) per channel: the multiple-scattering lobe's scale */
} mr_eon;

/* rho_ms = rho^2 <E> / (1 - rho (1 - <E>)) (the multiple-scattering albedo of the Oren-Nayar microfacets), and
 * f_comp = rho_ms / pi (1 - E(mu_i))(1 - E(mu_o)) / (1 - <E>), so that rho = 1 gives a total albedo of exactly 1
 * at every angle. comp[] folds 1/pi, rho_ms and 1/(1 - <E>) (its sigma A factor cancels one of the two in the
 * numerator, which the eval supplies). sigma = 0 leaves comp at 0 (Lambert). */
static inline void mr_eon_prepare(double sigma, const double rho[3], mr_eon *e) {
    e->A = 1.0 / (1.0 + MR_EON_C1 * sigma);
    e->B = sigma * e->A;
    e->sigma_A = sigma * e->A;
    double e_avg = e->A + e->B * MR_EON_G_AVG;
    for (int c = 0; c < 3; c++) {
        double one_minus_avg = e->sigma_A * (MR_EON_C1 - MR_EON_G_AVG);
        double rho_ms = rho[c] * rho[c] * e_avg / (1.0 - rho[c] * one_minus_avg);
        e->comp[c] = sigma > 0.0 ? MR_INV_PI * rho_ms / (MR_EON_C1 - MR_EON_G_AVG) : 0.0;
    }
}

/* EON's f_r: out[c] = rho_c/pi (A + B s/t) + f_comp_c, for the geometry g and the dot product
 * wi.wo (= cos_i cos_o + s). Symmetric in (wi, wo). */
static inline void mr_eon_eval(const mr_eon *e, const double rho[3], const mr_brdf_geom *g, double wi_dot_wo,
                               double out[3]) {
    double s = wi_dot_wo - g->cos_i * g->cos_o;
    double s_over_t = s > 0.0 ? s / MR_MAX(g->cos_i, g->cos_o) : s;
    double on = MR_INV_PI * (e->A + e->B * s_over_t);
    double ms = 0.0;
    if (e->sigma_A > 0.0)
        ms = e->sigma_A * (MR_EON_C1 - mr_eon_g(g->cos_i, g->sin2_i)) * (MR_EON_C1 - mr_eon_g(g->cos_o, g->sin2_o));
    for (int c = 0; c < 3; c++) out[c] = rho[c] * on + e->comp[c] * ms;
}

/* The rho-free Oren-Nayar albedo E(mu) = A + B g(mu) (the furnace tests' reference). */
static inline double mr_eon_albedo_on(const mr_eon *e, double mu, double sin2) {
    return e->A + e->B * mr_eon_g(mu, sin2);
}

/* ---- tabulated directional albedos of single-scattering GGX (layering.c; tables by scripts/gen-ggx-albedo.c) ---- */

/* E(mu) = integral over the hemisphere of D V F cos(theta_o) d omega_o for GGX with alpha = r^2, the
 * height-correlated V of mr_ggx_dv_correlated and F = mr_fresnel_dielectric(wo.h, eta), eta = (1 + eps)/(1 - eps),
 * eps = sqrt(F0) = (eta - 1)/(eta + 1) in [0, 0.5] (eta in [1, 3]); mu = cos(theta_i) in [0, 1], r in [0.01, 1]
 * (all clamped). Trilinear in (sqrt(mu), sqrt((r - 0.01)/0.99), sqrt((eta - 1)/2)) on the generated table
 * (ggx_albedo_tables.h, whose header states the interpolation error). The one table of all layered models. */
double mr_ggx_albedo_dielectric(double mu, double r, double eps);
/* The same lookup split for a model that precomputes in prepare: the (r, eps) cell and fractions once per parameter
 * set (slice_init, which keeps pointers to the four table rows around them), the mu coordinate per eval (slice_at,
 * inline: 8 loads and 7 lerps). slice_at(slice_init(r, eps), mu) is mr_ggx_albedo_dielectric(mu, r, eps) bit for bit
 * (it is how that function computes). Against the 41-node float curve it replaces in standard-surface (2 loads, 1
 * lerp), one eval costs 43 -> 51 ns without a coat and 56 -> 69 with one (one thread, 4096 direction pairs, best of
 * 15 runs); the curve's float rounding made f a staircase in roughness and ior (layering.c). */
#define MR_GGX_ALBEDO_SLICE_N_MU 41
typedef struct mr_ggx_albedo_slice {
    const float *row[4]; /* E at the mu nodes: (eta cell, r cell), (eta, r + 1), (eta + 1, r), (eta + 1, r + 1) */
    double b, c;         /* fractions in the r and eta cells */
} mr_ggx_albedo_slice;
void mr_ggx_albedo_slice_init(double r, double eps, mr_ggx_albedo_slice *slice);
static inline double mr_ggx_albedo_slice_at(const mr_ggx_albedo_slice *slice, double mu) {
    /* layering.c's alb_cell on the mu axis, and its lerps in the same order */
    double t = sqrt(mr_clampd(mu, 0.0, 1.0)), x = t > 0.0 ? MR_MIN(t, 1.0) * (MR_GGX_ALBEDO_SLICE_N_MU - 1) : 0.0;
    int i = (int)x;
    if (i > MR_GGX_ALBEDO_SLICE_N_MU - 2) i = MR_GGX_ALBEDO_SLICE_N_MU - 2;
    double a = x - i, b = slice->b, v[2];
    for (int e = 0; e < 2; e++) {
        const float *lo = slice->row[2 * e], *hi = slice->row[2 * e + 1];
        double l = lo[i] + (lo[i + 1] - lo[i]) * a, h = hi[i] + (hi[i + 1] - hi[i]) * a;
        v[e] = l + (h - l) * b;
    }
    return v[0] + (v[1] - v[0]) * slice->c;
}
/* The same with F = 1: the lobe's own single-scattering albedo (bilinear in (sqrt(mu), sqrt((r - 0.01)/0.99))). */
double mr_ggx_albedo_one(double mu, double r);
/* Its cosine-weighted hemispherical average E_avg(r) = 2 integral_0^1 E(mu) mu dmu (Simpson's rule, 64 intervals, on
 * the interpolated table): per parameter set, not per eval. */
double mr_ggx_albedo_one_avg(double r);

/* The same three with their derivatives (eval_grad of the layered models): the derivative of the interpolation in r
 * and eps (mu is geometry), one-sided at cell boundaries, 0 where a coordinate is clamped or at r = 0.01, eps = 0
 * (layering.c says why). The values equal the functions' above bit for bit. */
double mr_ggx_albedo_dielectric_grad(double mu, double r, double eps, double *dE_dr, double *dE_deps);
double mr_ggx_albedo_one_grad(double mu, double r, double *dE_dr);
double mr_ggx_albedo_one_avg_grad(double r, double *dE_dr);

/* The hemispherical average of the exact dielectric Fresnel, F_avg(eta) = 2 integral_0^1 F(mu, eta) mu dmu, eta >= 1
 * (Simpson's rule, 64 intervals; F is smooth on [0, 1] for eta >= 1, the error is below 1e-7). Per parameter set. */
static inline double mr_fresnel_dielectric_avg(double eta) {
    double sum = 0.0;
    for (int i = 0; i <= 64; i++) {
        double mu = i / 64.0, w = (i == 0 || i == 64) ? 1.0 : (i % 2 ? 4.0 : 2.0);
        sum += w * 2.0 * mu * mr_fresnel_dielectric(MR_MAX(mu, 1e-9), eta, NULL);
    }
    return sum / (3.0 * 64.0);
}

/* mr_fresnel_dielectric_avg with its derivative d F_avg/d eta (the same Simpson sum of dF/deta), the same value. */
static inline double mr_fresnel_dielectric_avg_grad(double eta, double *dF_deta) {
    double sum = 0.0, dsum = 0.0;
    for (int i = 0; i <= 64; i++) {
        double mu = i / 64.0, w = (i == 0 || i == 64) ? 1.0 : (i % 2 ? 4.0 : 2.0), d;
        sum += w * 2.0 * mu * mr_fresnel_dielectric(MR_MAX(mu, 1e-9), eta, &d);
        dsum += w * 2.0 * mu * d;
    }
    *dF_deta = dsum / (3.0 * 64.0);
    return sum / (3.0 * 64.0);
}

#endif /* MR_BRDF_INTERNAL_H */
