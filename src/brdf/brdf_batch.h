/*
 * brdf_batch.h — what the batched kernels of src/brdf share (the eval_batch contract is in brdf.h); internal.
 *
 * A kernel is a plain loop over the batch's structure-of-arrays, marked `#pragma omp simd`, whose body is the
 * model's eval written without branches (selects instead) and without libm's exp/pow (mr_batch_exp, mr_batch_pow
 * below). MR_BATCH_KERNEL compiles the same loop twice: once for AVX2 + FMA (4 doubles a vector) and once for the
 * baseline instruction set (SSE2 on x86-64: 2 doubles where GCC vectorises the loop for it, which it does not do for
 * every kernel), and picks one at run time. The Makefile builds src/brdf with -fno-math-errno (sqrt is an
 * instruction, not a call that may set errno) and -fno-trapping-math (a branch on a comparison may become a select);
 * neither changes any value.
 *
 * Precision: double throughout, as eval. The geometry (mr_batch_geom) repeats mr_brdf_geom_init's operations in
 * the same order, and kernels reuse brdf_internal.h's branch-free helpers (G1, Fresnel), so a kernel differs from
 * eval only through mr_batch_exp / mr_batch_pow (and, in the AVX2 variant, their fused multiply-adds) and GGX's
 * D G written with one division (mr_batch_ggx_dg, mr_batch_ggx_dv_correlated).
 * docs/performance.md ("Vectorised lobes", "Double, not float") says why double and not float: the float kernels at
 * the end of this file (brdf_float.h) exist to measure that choice and are used only where a plan asks for them.
 */
#ifndef MR_BRDF_BATCH_H
#define MR_BRDF_BATCH_H

#include <stdint.h>
#include <string.h>

#include "brdf_internal.h"

#define MR_BATCH_INLINE static inline __attribute__((always_inline))

#if defined(__x86_64__) || defined(__i386__)
#define MR_BATCH_X86 1
#else
#define MR_BATCH_X86 0
#endif

/* a * b + c, fused (one rounding) in the AVX2/FMA variant, two roundings in the portable one. `fused` is a
 * constant in each variant, so the choice is made at compile time. */
MR_BATCH_INLINE double mr_batch_madd(double a, double b, double c, const int fused) {
    return fused ? fma(a, b, c) : a * b + c;
}

MR_BATCH_INLINE uint64_t mr_batch_bits(double x) {
    uint64_t u;
    memcpy(&u, &x, sizeof u);
    return u;
}

MR_BATCH_INLINE double mr_batch_double(uint64_t u) {
    double x;
    memcpy(&x, &u, sizeof x);
    return x;
}

/* exp(x) without libm, in operations a vector unit has: x = k ln2 + r with k = round(x / ln2) (the 1.5 * 2^52
 * rounding trick: the sum's low bits are k) and |r| <= ln2/2, ln2 split in fdlibm's hi/lo pair (k ln2_hi is exact);
 * exp(r) by its Taylor polynomial to degree 13 (remainder below 0.35^14/14! = 5e-18, under 0.03 ulp), Horner;
 * 2^k added to the result's exponent bits. Accuracy: within 2 ulp of the true value (tests/test_batch.c measures
 * the largest difference from libm's exp over [-708, 709]). x < -708 gives 0 (the true value is below 3.3e-308,
 * where the result would be subnormal), x > 709 gives +inf (the true value exceeds 8.2e307), NaN gives NaN. */
MR_BATCH_INLINE double mr_batch_exp(double x, const int fused) {
    const double magic = 0x1.8p52, log2e = 1.4426950408889634074;
    const double ln2_hi = 6.93147180369123816490e-01, ln2_lo = 1.90821492927058770002e-10;
    const double xc = x < -708.0 ? -708.0 : (x > 709.0 ? 709.0 : x);
    const double t = mr_batch_madd(xc, log2e, magic, fused);
    const double k = t - magic;
    double r = mr_batch_madd(-k, ln2_hi, xc, fused);
    r = mr_batch_madd(-k, ln2_lo, r, fused);
    double p = 1.0 / 6227020800.0; /* 1/13! */
    p = mr_batch_madd(p, r, 1.0 / 479001600.0, fused);
    p = mr_batch_madd(p, r, 1.0 / 39916800.0, fused);
    p = mr_batch_madd(p, r, 1.0 / 3628800.0, fused);
    p = mr_batch_madd(p, r, 1.0 / 362880.0, fused);
    p = mr_batch_madd(p, r, 1.0 / 40320.0, fused);
    p = mr_batch_madd(p, r, 1.0 / 5040.0, fused);
    p = mr_batch_madd(p, r, 1.0 / 720.0, fused);
    p = mr_batch_madd(p, r, 1.0 / 120.0, fused);
    p = mr_batch_madd(p, r, 1.0 / 24.0, fused);
    p = mr_batch_madd(p, r, 1.0 / 6.0, fused);
    p = mr_batch_madd(p, r, 0.5, fused);
    p = mr_batch_madd(p, r, 1.0, fused);
    p = mr_batch_madd(p, r, 1.0, fused);
    // p is in [0.70, 1.42] and k in [-1021, 1023]: the sum of exponents stays a normal number.
    const double scaled = mr_batch_double(mr_batch_bits(p) + ((mr_batch_bits(t) - mr_batch_bits(magic)) << 52));
    const double bounded = x < -708.0 ? 0.0 : (x > 709.0 ? (double)INFINITY : scaled);
    return x == x ? bounded : x;
}

/* log(x) for a normal x > 0 (the kernels take logarithms of cosines floored at MR_BRDF_COS_MIN): x = 2^e m with
 * m in [sqrt(1/2), sqrt(2)) from the bits, log m = 2 atanh(f), f = (m - 1)/(m + 1), |f| <= 0.172, by its odd
 * series to f^21 (the next term is below 2^-60 of the sum); e ln2 with fdlibm's hi/lo split. Within 2 ulp of the
 * true value (tests/test_batch.c). */
MR_BATCH_INLINE double mr_batch_log(double x, const int fused) {
    const double ln2_hi = 6.93147180369123816490e-01, ln2_lo = 1.90821492927058770002e-10;
    const uint64_t xb = mr_batch_bits(x);
    // The biased exponent as a double without an integer conversion: 2^52 + field, minus 2^52 + 1023.
    double e = mr_batch_double(0x4330000000000000ULL | (xb >> 52)) - (0x1p52 + 1023.0);
    double m = mr_batch_double((xb & 0x000fffffffffffffULL) | 0x3ff0000000000000ULL);
    const int big = m > 1.41421356237309504880;
    m = big ? 0.5 * m : m;
    e = big ? e + 1.0 : e;
    const double f = (m - 1.0) / (m + 1.0), s = f * f;
    double q = 1.0 / 21.0;
    q = mr_batch_madd(q, s, 1.0 / 19.0, fused);
    q = mr_batch_madd(q, s, 1.0 / 17.0, fused);
    q = mr_batch_madd(q, s, 1.0 / 15.0, fused);
    q = mr_batch_madd(q, s, 1.0 / 13.0, fused);
    q = mr_batch_madd(q, s, 1.0 / 11.0, fused);
    q = mr_batch_madd(q, s, 1.0 / 9.0, fused);
    q = mr_batch_madd(q, s, 1.0 / 7.0, fused);
    q = mr_batch_madd(q, s, 1.0 / 5.0, fused);
    q = mr_batch_madd(q, s, 1.0 / 3.0, fused);
    const double two_f = 2.0 * f;
    const double log_m = mr_batch_madd(two_f * s, q, two_f, fused);
    return mr_batch_madd(e, ln2_hi, mr_batch_madd(e, ln2_lo, log_m, fused), fused);
}

/* x^y = exp(y log x) for a normal x > 0 (cosines) and finite y. The error of y log x (log's 2 ulp and the product's
 * rounding, relative to |y ln x|) becomes a relative error of the result: within (2 + 6 |y ln x|) ulp, below 1e-12
 * wherever the result exceeds e^-708. x = 1 gives exactly 1. */
MR_BATCH_INLINE double mr_batch_pow(double x, double y, const int fused) {
    return mr_batch_exp(y * mr_batch_log(x, fused), fused);
}

/* mr_brdf_geom_init for pair i of a batch, without its branch: the fields are computed for every pair (the
 * cosines' floor keeps them finite below the horizon too) and the return value says whether both directions are
 * above the horizon (the kernel then selects 0). Same operations in the same order: the same bits. */
MR_BATCH_INLINE int mr_batch_geom(double ix, double iy, double iz, double ox, double oy, double oz, mr_brdf_geom *g) {
    const int lit = (iz > 0.0) & (oz > 0.0);
    g->cos_i = iz > MR_BRDF_COS_MIN ? iz : MR_BRDF_COS_MIN;
    g->cos_o = oz > MR_BRDF_COS_MIN ? oz : MR_BRDF_COS_MIN;
    g->sin2_i = ix * ix + iy * iy;
    g->sin2_o = ox * ox + oy * oy;
    g->hx = ix + ox;
    g->hy = iy + oy;
    g->hz = g->cos_i + g->cos_o;
    const double hxy2 = g->hx * g->hx + g->hy * g->hy;
    g->h_len2 = hxy2 + g->hz * g->hz;
    g->cos_h = g->hz / sqrt(g->h_len2);
    g->sin2_h = hxy2 / g->h_len2;
    g->tan2_h = hxy2 / (g->hz * g->hz);
    g->dot_h = MR_MIN(0.5 * sqrt(g->h_len2), 1.0);
    return lit;
}

/* mr_fresnel_conductor's value (same operations), always inlined: GCC keeps the derivative-carrying original out of
 * line, and a call stops the loop's vectorisation. */
MR_BATCH_INLINE double mr_batch_fresnel_conductor(double c, double eta, double k) {
    const double c2 = c * c, s2 = MR_MAX(1.0 - c2, 0.0), s4 = s2 * s2;
    const double t = eta * eta - k * k - s2;
    const double A = sqrt(t * t + 4.0 * eta * eta * k * k);
    const double a = sqrt(MR_MAX(0.5 * (A + t), 0.0));
    const double P = A + c2, Q = 2.0 * a * c;
    const double rs = (P - Q) / (P + Q);
    const double U = A * c2 + s4, W = Q * s2;
    const double ratio = U + W > 1e-300 ? (U - W) / (U + W) : 1.0;
    const double rp = rs * ratio;
    return mr_clampd(0.5 * (rs + rp), 0.0, 1.0);
}

/* mr_mf_D's value for a constant distribution, with mr_batch_exp / mr_batch_pow for libm's exp / pow. */
MR_BATCH_INLINE double mr_batch_mf_D(const mr_mf_dist dist, double alpha, const mr_brdf_geom *g, const int fused) {
    const double a2 = alpha * alpha, c2 = g->cos_h * g->cos_h;
    if (dist == MR_MF_BECKMANN) return mr_batch_exp(-g->tan2_h / a2, fused) / (MR_PI * a2 * c2 * c2);
    if (dist == MR_MF_GGX) {
        const double root = a2 * c2 + g->sin2_h;
        return a2 / (MR_PI * root * root);
    }
    const double n = 2.0 / a2 - 2.0;
    const double p = n > 0.0 ? mr_batch_pow(g->cos_h, n, fused) : 1.0;
    return (MR_MAX(n, 0.0) + 2.0) * (0.5 * MR_INV_PI) * p;
}

/* GGX's D G1(wi) G1(wo) / (4 cos_i cos_o), separable Smith (mr_mf_dg's value), in one division instead of seven
 * (the render loop's costliest operations): with cos_h^2 = H_z^2/|H|^2 and sin_h^2 = (H_x^2 + H_y^2)/|H|^2,
 *   D = a^2 |H|^4 / (pi (a^2 H_z^2 + H_x^2 + H_y^2)^2),   G1(v) = 2 c/(c + sqrt(c^2 + a^2 s^2))  (c = cos, s^2 = sin^2)
 * so that D G1 G1 / (4 cos_i cos_o) = D / ((c_i + q_i)(c_o + q_o)), q = sqrt(c^2 + a^2 s^2). The same function as
 * eval's, rounded differently (a few ulp; MR_BRDF_BATCH_RTOL). Mitsuba's cut-off D cos_h < 1e-20, cos_h = H_z/|H|,
 * is tested without dividing. Every intermediate stays inside double range: a^2 >= 1e-8, H_z >= 2e-12. */
MR_BATCH_INLINE double mr_batch_ggx_dg(double alpha, const mr_brdf_geom *g, const int mitsuba_cutoff) {
    const double a2 = alpha * alpha, hxy2 = g->hx * g->hx + g->hy * g->hy;
    const double root = a2 * g->hz * g->hz + hxy2;
    const double qi = sqrt(g->cos_i * g->cos_i + a2 * g->sin2_i), qo = sqrt(g->cos_o * g->cos_o + a2 * g->sin2_o);
    const double shadow = (g->cos_i + qi) * (g->cos_o + qo); /* 4 cos_i cos_o / (G1(wi) G1(wo)) */
    const double num = a2 * g->h_len2 * g->h_len2;
    const double dg = num / (MR_PI * root * root * shadow);
    if (!mitsuba_cutoff) return dg;
    return dg * shadow * g->hz >= 1e-20 * sqrt(g->h_len2) ? dg : 0.0; /* D cos_h >= 1e-20, D = dg shadow */
}

/* mr_mf_dg's value (D G1(wi) G1(wo) / (4 cos_i cos_o), Mitsuba's cut-off if mitsuba_cutoff) with mr_batch_mf_D;
 * GGX by mr_batch_ggx_dg. */
MR_BATCH_INLINE double mr_batch_mf_dg(const mr_mf_dist dist, double alpha, const mr_brdf_geom *g,
                                      const int mitsuba_cutoff, const int fused) {
    if (dist == MR_MF_GGX) return mr_batch_ggx_dg(alpha, g, mitsuba_cutoff);
    const double D = mr_batch_mf_D(dist, alpha, g, fused);
    const double Gi = mr_mf_G1(dist, alpha, g->cos_i, g->sin2_i, NULL);
    const double Go = mr_mf_G1(dist, alpha, g->cos_o, g->sin2_o, NULL);
    const double inv = 1.0 / (4.0 * g->cos_i * g->cos_o);
    const double dg = D * Gi * Go * inv;
    return (mitsuba_cutoff && !(D * g->cos_h >= 1e-20)) ? 0.0 : dg;
}

/* mr_ggx_dv_correlated's value, D times glTF's height-correlated V = 1/(2 (nv root_l + nl root_v)) with
 * mr_gltf_visibility's roots, in one division (D as in mr_batch_ggx_dg). */
MR_BATCH_INLINE double mr_batch_ggx_dv_correlated(double alpha, const mr_brdf_geom *g) {
    const double a2 = alpha * alpha, nl = g->cos_i, nv = g->cos_o;
    const double root_l = sqrt(a2 * (1.0 - nl * nl) + nl * nl);
    const double root_v = sqrt(a2 * (1.0 - nv * nv) + nv * nv);
    const double sum = nv * root_l + nl * root_v;
    const double root = a2 * g->hz * g->hz + (g->hx * g->hx + g->hy * g->hy);
    return 0.5 * a2 * g->h_len2 * g->h_len2 / (MR_PI * root * root * sum);
}

/* The kernel's arrays as restrict-qualified locals (a kernel body starts with it). */
#define MR_BATCH_ARRAYS(batch)                                                                                   \
    const int n_ = (batch)->n;                                                                                   \
    const double *restrict ix_ = (batch)->wi[0], *restrict iy_ = (batch)->wi[1], *restrict iz_ = (batch)->wi[2]; \
    const double *restrict ox_ = (batch)->wo[0], *restrict oy_ = (batch)->wo[1], *restrict oz_ = (batch)->wo[2]; \
    double *restrict d0_ = (batch)->diffuse[0], *restrict d1_ = (batch)->diffuse[1];                             \
    double *restrict d2_ = (batch)->diffuse[2], *restrict s0_ = (batch)->specular[0];                            \
    double *restrict s1_ = (batch)->specular[1], *restrict s2_ = (batch)->specular[2]

/* Defines `static void name(const void *state, const mr_brdf_batch *batch, int vector)`, the eval_batch of a model,
 * from `body(state, batch, fused)`, an MR_BATCH_INLINE function holding the simd loop: an AVX2/FMA copy (fused = 1)
 * used when `vector` is set and the CPU has both (mr_brdf_batch_cpu_vector), else the baseline copy (fused = 0). */
#if MR_BATCH_X86
#define MR_BATCH_KERNEL(name, body)                                                                              \
    __attribute__((target("avx2,fma"))) static void name##_avx2(const void *state, const mr_brdf_batch *batch) { \
        body(state, batch, 1);                                                                                   \
    }                                                                                                            \
    static void name##_portable(const void *state, const mr_brdf_batch *batch) { body(state, batch, 0); }       \
    static void name(const void *state, const mr_brdf_batch *batch, int vector) {                                \
        if (vector && mr_brdf_batch_cpu_vector())                                                                \
            name##_avx2(state, batch);                                                                           \
        else                                                                                                     \
            name##_portable(state, batch);                                                                       \
    }
#else
#define MR_BATCH_KERNEL(name, body)                                                                              \
    static void name(const void *state, const mr_brdf_batch *batch, int vector) {                                \
        (void)vector;                                                                                            \
        body(state, batch, 0);                                                                                   \
    }
#endif


/* ---- single precision (the float kernels; brdf_float.h says how a render chooses them) ----
 *
 * A float kernel reads the batch's doubles, computes in float (8 lanes an AVX2 vector instead of 4) and writes f_r
 * back as doubles, so that it plugs into the same batch and render loop. Every conversion between the widths is an
 * instruction of its own: Ward converts its one lobe factor and multiplies by the per-channel constants in double;
 * the microfacet and gltf kernels multiply in float and convert the channels (done the Ward way they measured 15 %
 * slower for ggx and gltf, faster for ggx-nofresnel only: bench_fit --kernels). One part stays in double: the sums
 * H_x = wi_x + wo_x and H_y, which cancel where the lobe peaks (wi ~ mirror of wo); in float their error would be
 * 2^-24 of |wi_x| instead of 2^-24 of |H_x|, and a narrow lobe's exponent -tan^2(theta_h)/alpha^2 would lose every
 * digit at alpha = 1e-4. Every other intermediate is float and every formula is rewritten to stay inside float's
 * range (1.2e-38 .. 3.4e38) wherever the double one stays finite (the cosines floored at MR_BRDF_COS_MIN = 1e-12):
 * 1/cos^4(theta_h) as (1 + tan^2)^2, GGX's |H|^4/root^2 as (|H|^2/root)^2, pow(cos_h, n) as
 * exp(-n/2 log1p(tan^2)) (cos_h's own rounding, 2^-24, times n = 2e8 at alpha = 1e-4 would be all the answer). */

/* a * b + c in float, fused in the AVX2/FMA variant (mr_batch_madd's contract). */
MR_BATCH_INLINE float mr_batchf_madd(float a, float b, float c, const int fused) {
    return fused ? fmaf(a, b, c) : a * b + c;
}

MR_BATCH_INLINE uint32_t mr_batchf_bits(float x) {
    uint32_t u;
    memcpy(&u, &x, sizeof u);
    return u;
}

MR_BATCH_INLINE float mr_batchf_float(uint32_t u) {
    float x;
    memcpy(&x, &u, sizeof x);
    return x;
}

/* expf without libm: x = k ln2 + r, k = round(x / ln2) by the 1.5 * 2^23 trick, |r| <= ln2/2, ln2 in Cephes'
 * two-part split (0.693359375 has 9 bits, so k * 0.693359375 is exact); exp(r) = 1 + r + r^2 P(r), P Cephes expf's
 * degree-5 minimax polynomial (Cephes 2.8 expf.c, relative error 1.7e-7 over |r| <= ln2/2); 2^k added to the
 * exponent bits. Within 2 ulp of the true value (tests/test_batch.c measures the largest difference from libm's expf
 * over [-87, 88]). x < -87 gives 0 (the true value is below 1.7e-38, float's normal range ends at 1.2e-38),
 * x > 88 gives +inf (the true value exceeds 1.6e38), NaN gives NaN. */
MR_BATCH_INLINE float mr_batchf_exp(float x, const int fused) {
    const float magic = 0x1.8p23f, log2e = 1.44269504088896341f;
    const float c1 = 0.693359375f, c2 = -2.12194440e-4f;
    const float xc = x < -87.0f ? -87.0f : (x > 88.0f ? 88.0f : x);
    const float t = mr_batchf_madd(xc, log2e, magic, fused);
    const float k = t - magic;
    float r = mr_batchf_madd(-k, c1, xc, fused);
    r = mr_batchf_madd(-k, c2, r, fused);
    float p = 1.9875691500e-4f;
    p = mr_batchf_madd(p, r, 1.3981999507e-3f, fused);
    p = mr_batchf_madd(p, r, 8.3334519073e-3f, fused);
    p = mr_batchf_madd(p, r, 4.1665795894e-2f, fused);
    p = mr_batchf_madd(p, r, 1.6666665459e-1f, fused);
    p = mr_batchf_madd(p, r, 5.0000001201e-1f, fused);
    const float e = mr_batchf_madd(p * r, r, r, fused) + 1.0f;
    // e is in [0.70, 1.42] and k in [-126, 127]: the sum of exponents stays a normal number.
    const float scaled = mr_batchf_float(mr_batchf_bits(e) + ((mr_batchf_bits(t) - mr_batchf_bits(magic)) << 23));
    const float bounded = x < -87.0f ? 0.0f : (x > 88.0f ? (float)INFINITY : scaled);
    return x == x ? bounded : x;
}

/* logf for a normal x > 0: x = 2^e m, m in [sqrt(1/2), sqrt(2)) from the bits, log m = 2 atanh(f),
 * f = (m - 1)/(m + 1), |f| <= 0.172, by its odd series to f^11 (the next term is below 2^-27 of the sum); e ln2 with
 * Cephes' split. Within 2 ulp of the true value where |log x| >= 0.1 and within 2^-24 absolute below
 * (tests/test_batch.c). */
MR_BATCH_INLINE float mr_batchf_log(float x, const int fused) {
    const float c1 = 0.693359375f, c2 = -2.12194440e-4f;
    const uint32_t xb = mr_batchf_bits(x);
    float e = (float)((int32_t)(xb >> 23) - 127);
    float m = mr_batchf_float((xb & 0x007fffffu) | 0x3f800000u);
    const int big = m > 1.41421356f;
    m = big ? 0.5f * m : m;
    e = big ? e + 1.0f : e;
    const float f = (m - 1.0f) / (m + 1.0f), s = f * f;
    float q = 1.0f / 11.0f;
    q = mr_batchf_madd(q, s, 1.0f / 9.0f, fused);
    q = mr_batchf_madd(q, s, 1.0f / 7.0f, fused);
    q = mr_batchf_madd(q, s, 1.0f / 5.0f, fused);
    q = mr_batchf_madd(q, s, 1.0f / 3.0f, fused);
    const float two_f = 2.0f * f;
    const float log_m = mr_batchf_madd(two_f * s, q, two_f, fused);
    return mr_batchf_madd(e, c1, mr_batchf_madd(e, c2, log_m, fused), fused);
}

/* log1p(x) for x >= 0 (tan^2 of an angle): log(u), u = 1 + x rounded, plus the first-order correction for that
 * rounding, (x - (u - 1))/u (Goldberg 1991, "What every computer scientist should know...", theorem 4's idea). */
MR_BATCH_INLINE float mr_batchf_log1p(float x, const int fused) {
    const float u = 1.0f + x;
    return mr_batchf_log(u, fused) + (x - (u - 1.0f)) / u;
}

/* The float geometry of a pair (mr_brdf_geom's fields that the float kernels use, hxy2 = H_x^2 + H_y^2 instead of
 * H_x and H_y). */
typedef struct mr_batchf_geom_t {
    float cos_i, cos_o, sin2_i, sin2_o, hz, hxy2, h_len2, cos_h, tan2_h, dot_h;
} mr_batchf_geom_t;

/* mr_batch_geom in float, H_x and H_y summed in double (see above); the squares of the x, y parts are summed in
 * double too and converted once (no accuracy reason: each conversion of a double vector to float costs as much as
 * a float operation on 8 lanes, and a kernel here is short). Returns whether both directions are above the
 * horizon. */
MR_BATCH_INLINE int mr_batchf_geom(double ix, double iy, double iz, double ox, double oy, double oz,
                                   mr_batchf_geom_t *g) {
    const int lit = (iz > 0.0) & (oz > 0.0);
    g->cos_i = (float)(iz > MR_BRDF_COS_MIN ? iz : MR_BRDF_COS_MIN);
    g->cos_o = (float)(oz > MR_BRDF_COS_MIN ? oz : MR_BRDF_COS_MIN);
    g->sin2_i = (float)(ix * ix + iy * iy);
    g->sin2_o = (float)(ox * ox + oy * oy);
    const double hx = ix + ox, hy = iy + oy;
    g->hz = g->cos_i + g->cos_o;
    g->hxy2 = (float)(hx * hx + hy * hy);
    g->h_len2 = g->hxy2 + g->hz * g->hz;
    g->cos_h = g->hz / sqrtf(g->h_len2);
    g->tan2_h = g->hxy2 / (g->hz * g->hz);
    g->dot_h = MR_MIN(0.5f * sqrtf(g->h_len2), 1.0f);
    return lit;
}

/* (1 - c)^5 in float. */
MR_BATCH_INLINE float mr_batchf_schlick_weight(float c) {
    const float m = 1.0f - c, m2 = m * m;
    return m2 * m2 * m;
}

/* mr_fresnel_dielectric's value in float, written without its cancellations (u = eta cos_t, u^2 = eta^2 - 1 + c^2):
 * c - u = -(eta^2 - 1)/(c + u) and eta^2 c^2 - cos_t^2 = (eta^2 - 1)((eta^2 + 1) c^2 - 1)/eta^2, so
 *   R_s = -(eta^2 - 1)/(c + u)^2,   R_p = (eta^2 - 1)((eta^2 + 1) c^2 - 1)/(eta^2 (eta c + cos_t)^2).
 * The same numbers; float's c - u would keep no digit for eta near 1 (F ~ ((eta - 1)/2)^2 tiny, multiplied by a
 * narrow lobe's large D G), nor float's 1 - (1 - c^2) near grazing incidence. eta^2 - 1 is given as in
 * mr_batchf_dielectric_transmit. */
MR_BATCH_INLINE float mr_batchf_fresnel_dielectric(float c, float eta, float eta2_minus_1) {
    const float eta2 = eta * eta, cos_t = sqrtf(MR_MAX((eta2_minus_1 + c * c) / eta2, 0.0f));
    const float s = c + eta * cos_t, p = eta * c + cos_t;
    const float rs = -eta2_minus_1 / (s * s);
    const float rp = eta2_minus_1 * ((eta2 + 1.0f) * (c * c) - 1.0f) / (eta2 * (p * p));
    const float F = 0.5f * (rs * rs + rp * rp);
    return F < 0.0f ? 0.0f : (F > 1.0f ? 1.0f : F);
}

/* 1 - mr_fresnel_dielectric(cos_i, eta) in float, written without the cancellation of 1 - F (F -> 1 at grazing
 * incidence, where float's 1 - F would keep no digit): with u = eta cos_t, 1 - R_s^2 = 4 c u/(c + u)^2 and
 * 1 - R_p^2 = 4 eta c cos_t/(eta c + cos_t)^2, so 1 - F = 2 c (u/(c + u)^2 + eta cos_t/(eta c + cos_t)^2);
 * cos_t^2 = (eta^2 - 1 + c^2)/eta^2 (no cancellation for eta >= 1; eta^2 - 1 is given, rounded from double, as
 * float's own would lose its digits for eta near 1). */
MR_BATCH_INLINE float mr_batchf_dielectric_transmit(float c, float eta, float eta2_minus_1) {
    const float cos_t = sqrtf(MR_MAX((eta2_minus_1 + c * c) / (eta * eta), 0.0f));
    const float u = eta * cos_t, s = c + u, p = eta * c + cos_t;
    const float T = 2.0f * c * (u / (s * s) + u / (p * p));
    return T < 0.0f ? 0.0f : (T > 1.0f ? 1.0f : T);
}

/* mr_batch_fresnel_conductor in float (same formula; the 0/0 guard of the R_p ratio at float's scale). */
MR_BATCH_INLINE float mr_batchf_fresnel_conductor(float c, float eta, float k) {
    const float c2 = c * c, s2 = MR_MAX(1.0f - c2, 0.0f), s4 = s2 * s2;
    const float t = eta * eta - k * k - s2;
    const float A = sqrtf(t * t + 4.0f * eta * eta * k * k);
    const float a = sqrtf(MR_MAX(0.5f * (A + t), 0.0f));
    const float P = A + c2, Q = 2.0f * a * c;
    const float rs = (P - Q) / (P + Q);
    const float U = A * c2 + s4, W = Q * s2;
    const float ratio = U + W > 1e-30f ? (U - W) / (U + W) : 1.0f;
    const float F = 0.5f * (rs + rs * ratio);
    return F < 0.0f ? 0.0f : (F > 1.0f ? 1.0f : F);
}

/* The kernel's arrays and the float geometry's loop head are the double kernels' (MR_BATCH_ARRAYS); a float
 * kernel is defined by MR_BATCH_KERNEL like a double one. */

#endif /* MR_BRDF_BATCH_H */
