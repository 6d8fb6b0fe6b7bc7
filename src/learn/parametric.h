/*
 * parametric.h — the paper's parametric remapping (Sztrajman et al. 2019, section 7), the fitting half: from
 * pairs of remapped uniform materials (sweeps), the target roughness as a polynomial of the source roughness, and
 * the target specular as the source specular times one slope k(alpha) for all three channels (chromaticity kept),
 *     k(alpha) = c0 + c1 e^(-c2 alpha) + c3 e^(-c4 alpha^2) [+ c5 / alpha].
 * Used by `matremap learn --method parametric` (learned.h).
 *
 * Conditioning. Fitted freely, that form is ill-conditioned: for a small c2, c1 e^(-c2 alpha) ~ c1 - c1 c2 alpha
 * trades off against c0, and unbounded fits drift to c0 ~ -600, c1 ~ +600 (the paper's appendix prints such
 * pairs: -944 + 944.82 e^(-0.00046 alpha)). Here the two exponents are searched on a bounded log-spaced grid
 * (c2 in [MR_SLOPE_RATE_MIN, MR_SLOPE_RATE_MAX], c4 likewise) and, for each pair, the linear coefficients (c0, c1,
 * c3 [, c5]) are the least-squares solution (Householder QR, no normal equations); a pair whose design columns are
 * nearly dependent (a column's residual norm below 1 % of its norm after the earlier ones are removed) is skipped
 * rather than solved, so the answer never rests on a cancellation. The four best grid pairs are each refined by
 * golden-section searches in each exponent in turn (log scale, two grid steps about the current value, 24 rounds),
 * and the best result kept.
 *
 * Nothing is printed; errors are MR_ERR_INVALID_ARG naming the value (non-finite data, alpha <= 0, too few pairs).
 */
#ifndef MR_LEARN_PARAMETRIC_H
#define MR_LEARN_PARAMETRIC_H

#include <stddef.h>

#include "../mr_status.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MR_POLY_MAX_DEGREE 4
#define MR_SLOPE_RATE_MIN 0.01   /* the exponents' search range (c2, c4), both ends included */
#define MR_SLOPE_RATE_MAX 1000.0

/* y ~ c[0] + c[1] x + ... + c[degree] x^degree by least squares (QR); *rms (may be NULL) the residual's root
 * mean square. MR_ERR_INVALID_ARG for degree outside 0..MR_POLY_MAX_DEGREE, fewer than degree + 1 pairs, or a
 * non-finite value (naming its index). */
mr_status mr_fit_polynomial(const double *x, const double *y, size_t n, int degree, double *c, double *rms);

/* The same with c[0] = 0 when through_origin (a mirror stays a mirror; the authors' roughness fit has no constant
 * term): x^1 .. x^degree fitted, degree >= 1. */
mr_status mr_fit_polynomial_ex(const double *x, const double *y, size_t n, int degree, int through_origin, double *c,
                               double *rms);

/* c[0] + c[1] x + ... */
double mr_polynomial_eval(const double *c, int degree, double x);

/* k(alpha) as above. */
typedef struct mr_specular_slope {
    double c[6];      /* c0 .. c4, and c5 (the 1/alpha term; 0 unless with_inverse) */
    int with_inverse; /* 1: the c5 / alpha term was fitted (the authors' code has it) */
    double rms;       /* root mean square of the specular residual over every channel of every pair */
} mr_specular_slope;

double mr_specular_slope_eval(const mr_specular_slope *k, double alpha);

/* Fit k from n pairs: alpha[i] the source roughness (> 0), s_src[3i..3i+2] and s_tgt[3i..3i+2] the source's and the
 * target's specular RGB; minimises sum over i, c of (s_tgt - k(alpha_i) s_src)^2. with_inverse adds c5 / alpha. */
mr_status mr_fit_specular_slope(const double *alpha, const double *s_src, const double *s_tgt, size_t n,
                                int with_inverse, mr_specular_slope *out);

#ifdef __cplusplus
}
#endif

#endif /* MR_LEARN_PARAMETRIC_H */
