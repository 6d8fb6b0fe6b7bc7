/*
 * parametric.c — least-squares fits of the paper's parametric remapping (contract in parametric.h).
 */
#include "learn/parametric.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "mr_internal.h"

#define MAX_COLUMNS 6
/* How independent a design column must be of the earlier ones (its norm after their reflections, relative to its
 * own): a polynomial's powers are legitimately close on a short interval; the slope's exponential columns are not
 * allowed to nearly repeat the constant (e^(-0.01 a^2) ~ 1 - 0.01 a^2 makes -36 + 36 e^(...) cancellations). */
#define POLY_INDEPENDENCE 1e-9
#define SLOPE_INDEPENDENCE 1e-2
#define GRID 25 /* exponent values per axis, log-spaced over [MR_SLOPE_RATE_MIN, MR_SLOPE_RATE_MAX] */

/* min |A x - b| for A (n x m, row-major, n >= m, m <= MAX_COLUMNS) by Householder QR in place: a and b are
 * overwritten (callers pass copies; no allocation here, so a failure can only mean dependence). Returns 0 when
 * a column is (nearly) a combination of the earlier ones: its norm after their reflections is below `independence`
 * of its own, and the solution would rest on a cancellation. *rss gets the residual sum of squares. */
static int least_squares(double *a, double *b, size_t n, int m, double independence, double *x, double *rss) {
    int ok = 1;
    for (int k = 0; k < m && ok; k++) {
        double full = 0.0, norm = 0.0;
        for (size_t i = 0; i < n; i++) full += a[i * m + k] * a[i * m + k];
        for (size_t i = (size_t)k; i < n; i++) norm += a[i * m + k] * a[i * m + k];
        norm = sqrt(norm);
        if (!(norm > independence * sqrt(full)) || norm == 0.0) {
            ok = 0;
            break;
        }
        // v = a_k[k..] + sign(a_kk) |a_k[k..]| e_k; reflect the remaining columns and b.
        const double alpha = a[k * m + k] >= 0.0 ? -norm : norm;
        a[k * m + k] -= alpha;
        double vv = 0.0;
        for (size_t i = (size_t)k; i < n; i++) vv += a[i * m + k] * a[i * m + k];
        for (int j = k + 1; j <= m; j++) {
            double dot = 0.0;
            for (size_t i = (size_t)k; i < n; i++) dot += a[i * m + k] * (j < m ? a[i * m + j] : b[i]);
            const double f = 2.0 * dot / vv;
            for (size_t i = (size_t)k; i < n; i++) {
                if (j < m)
                    a[i * m + j] -= f * a[i * m + k];
                else
                    b[i] -= f * a[i * m + k];
            }
        }
        a[k * m + k] = alpha; // R's diagonal
    }
    if (ok) {
        for (int k = m - 1; k >= 0; k--) { // R x = Q^T b
            double s = b[k];
            for (int j = k + 1; j < m; j++) s -= a[k * m + j] * x[j];
            x[k] = s / a[k * m + k];
        }
        double r = 0.0;
        for (size_t i = (size_t)m; i < n; i++) r += b[i] * b[i];
        *rss = r;
    }
    return ok;
}

static mr_status check_finite(const double *v, size_t n, const char *what) {
    for (size_t i = 0; i < n; i++)
        if (!isfinite(v[i])) return mr_fail(MR_ERR_INVALID_ARG, "parametric fit: %s[%zu] = %g is not finite", what, i,
                                            v[i]);
    return MR_OK;
}

mr_status mr_fit_polynomial(const double *x, const double *y, size_t n, int degree, double *c, double *rms) {
    return mr_fit_polynomial_ex(x, y, n, degree, 0, c, rms);
}

mr_status mr_fit_polynomial_ex(const double *x, const double *y, size_t n, int degree, int through_origin, double *c,
                               double *rms) {
    if (x == NULL || y == NULL || c == NULL) return mr_fail(MR_ERR_INVALID_ARG, "polynomial fit: NULL argument");
    if (degree < 0 || degree > MR_POLY_MAX_DEGREE)
        return mr_fail(MR_ERR_INVALID_ARG, "polynomial fit: degree %d: expected 0 .. %d", degree, MR_POLY_MAX_DEGREE);
    if (through_origin && degree < 1)
        return mr_fail(MR_ERR_INVALID_ARG, "polynomial fit: degree %d through the origin: expected 1 .. %d", degree,
                       MR_POLY_MAX_DEGREE);
    const int m = degree + 1 - (through_origin != 0); // coefficients fitted
    if (n < (size_t)m)
        return mr_fail(MR_ERR_INVALID_ARG, "polynomial fit: %zu pairs for degree %d (at least %d)", n, degree, m);
    mr_status status = check_finite(x, n, "x");
    if (status == MR_OK) status = check_finite(y, n, "y");
    if (status != MR_OK) return status;
    double *a = malloc((n * (size_t)m + n) * sizeof *a), rss = 0.0; // the design, then a copy of y
    if (a == NULL) return mr_fail(MR_ERR_NOMEM, "polynomial fit: out of memory for %zu pairs", n);
    double *b = a + n * (size_t)m;
    memcpy(b, y, n * sizeof *b);
    for (size_t i = 0; i < n; i++) // column k holds x^(k + through_origin)
        for (int k = 0; k < m; k++)
            a[i * (size_t)m + (size_t)k] = k > 0 ? a[i * m + k - 1] * x[i] : through_origin ? x[i] : 1.0;
    c[0] = 0.0;
    const int ok = least_squares(a, b, n, m, POLY_INDEPENDENCE, c + (through_origin != 0), &rss);
    free(a);
    if (!ok)
        return mr_fail(MR_ERR_INVALID_ARG, "polynomial fit: the %zu x values do not determine a degree-%d polynomial "
                       "(too few distinct values)", n, degree);
    if (rms != NULL) *rms = sqrt(rss / (double)n);
    return MR_OK;
}

double mr_polynomial_eval(const double *c, int degree, double x) {
    double v = 0.0;
    for (int k = degree; k >= 0; k--) v = v * x + c[k]; // Horner
    return v;
}

double mr_specular_slope_eval(const mr_specular_slope *k, double alpha) {
    const double *c = k->c;
    return c[0] + c[1] * exp(-c[2] * alpha) + c[3] * exp(-c[4] * alpha * alpha) +
           (k->with_inverse ? c[5] / alpha : 0.0);
}

/* The slope fit's data and scratch. */
typedef struct slope_data {
    const double *alpha, *s_src, *s_tgt;
    size_t n;
    int with_inverse;
    double *design; /* 3n x columns; least_squares overwrites it, solve_linear refills it */
    double *rhs;    /* 3n: s_tgt copied for least_squares to overwrite (in the design's allocation) */
} slope_data;

/* For exponents (c2, c4): the linear coefficients (written into k->c) and the residual sum of squares; +inf when
 * the columns are nearly dependent. */
static double solve_linear(const slope_data *d, double c2, double c4, mr_specular_slope *k) {
    const int m = d->with_inverse ? 4 : 3;
    for (size_t i = 0; i < d->n; i++) {
        const double e2 = exp(-c2 * d->alpha[i]), e4 = exp(-c4 * d->alpha[i] * d->alpha[i]);
        for (int c = 0; c < 3; c++) {
            const double s = d->s_src[3 * i + (size_t)c];
            double *row = d->design + (3 * i + (size_t)c) * (size_t)m;
            row[0] = s;
            row[1] = e2 * s;
            row[2] = e4 * s;
            if (m == 4) row[3] = s / d->alpha[i];
        }
    }
    double x[4] = {0, 0, 0, 0}, rss = 0.0;
    memcpy(d->rhs, d->s_tgt, 3 * d->n * sizeof *d->rhs);
    if (!least_squares(d->design, d->rhs, 3 * d->n, m, SLOPE_INDEPENDENCE, x, &rss))
        return INFINITY;
    k->c[0] = x[0];
    k->c[1] = x[1];
    k->c[2] = c2;
    k->c[3] = x[2];
    k->c[4] = c4;
    k->c[5] = m == 4 ? x[3] : 0.0;
    return rss;
}

/* Golden-section search of log(rate) in [lo, hi] for exponent `which` (2 or 4), the other held at k's; k keeps the
 * best found (k already holds a candidate and its rss in *best). */
static void refine(const slope_data *d, int which, double lo, double hi, mr_specular_slope *k, double *best) {
    const double g = 0.5 * (sqrt(5.0) - 1.0);
    double a = log(lo), b = log(hi);
    for (int it = 0; it < 40; it++) {
        const double x1 = b - g * (b - a), x2 = a + g * (b - a);
        mr_specular_slope k1 = *k, k2 = *k;
        const double r1 = solve_linear(d, which == 2 ? exp(x1) : k->c[2], which == 4 ? exp(x1) : k->c[4], &k1);
        const double r2 = solve_linear(d, which == 2 ? exp(x2) : k->c[2], which == 4 ? exp(x2) : k->c[4], &k2);
        if (r1 < *best) {
            *best = r1;
            *k = k1;
        }
        if (r2 < *best) {
            *best = r2;
            *k = k2;
        }
        if (r1 <= r2)
            b = x2;
        else
            a = x1;
    }
}

mr_status mr_fit_specular_slope(const double *alpha, const double *s_src, const double *s_tgt, size_t n,
                                int with_inverse, mr_specular_slope *out) {
    if (alpha == NULL || s_src == NULL || s_tgt == NULL || out == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "specular slope fit: NULL argument");
    const int m = with_inverse ? 4 : 3;
    if (3 * n < (size_t)m + 1)
        return mr_fail(MR_ERR_INVALID_ARG, "specular slope fit: %zu pairs are too few", n);
    mr_status status = check_finite(alpha, n, "alpha");
    if (status == MR_OK) status = check_finite(s_src, 3 * n, "s_src");
    if (status == MR_OK) status = check_finite(s_tgt, 3 * n, "s_tgt");
    for (size_t i = 0; status == MR_OK && i < n; i++)
        if (!(alpha[i] > 0.0)) status = mr_fail(MR_ERR_INVALID_ARG, "specular slope fit: alpha[%zu] = %g <= 0", i,
                                                alpha[i]);
    if (status != MR_OK) return status;
    slope_data d = {alpha, s_src, s_tgt, n, with_inverse, malloc(3 * n * ((size_t)m + 1) * sizeof(double)), NULL};
    if (d.design == NULL) return mr_fail(MR_ERR_NOMEM, "specular slope fit: out of memory for %zu pairs", n);
    d.rhs = d.design + 3 * n * (size_t)m;
    // The grid, then the best cell refined in each exponent within its grid neighbours.
    double rates[GRID];
    for (int g = 0; g < GRID; g++)
        rates[g] = MR_SLOPE_RATE_MIN * pow(MR_SLOPE_RATE_MAX / MR_SLOPE_RATE_MIN, (double)g / (GRID - 1));
    // Every grid cell solved; the STARTS best cells (distinct) refined by coordinate search in each exponent
    // (golden section in log scale over a bracket of two grid steps about the current value), ROUNDS times.
    enum { STARTS = 4, ROUNDS = 24 };
    mr_specular_slope starts[STARTS], k = {{0}, with_inverse, 0.0};
    double start_rss[STARTS];
    for (int s = 0; s < STARTS; s++) start_rss[s] = INFINITY;
    for (int i = 0; i < GRID; i++)
        for (int j = 0; j < GRID; j++) {
            const double rss = solve_linear(&d, rates[i], rates[j], &k);
            int worst = 0;
            for (int s = 1; s < STARTS; s++)
                if (start_rss[s] > start_rss[worst]) worst = s;
            if (rss < start_rss[worst]) {
                start_rss[worst] = rss;
                starts[worst] = k;
            }
        }
    mr_specular_slope best = k;
    double best_rss = INFINITY;
    const double step = pow(MR_SLOPE_RATE_MAX / MR_SLOPE_RATE_MIN, 2.0 / (GRID - 1)); // two grid steps
    for (int s = 0; s < STARTS; s++) {
        if (!isfinite(start_rss[s])) continue;
        for (int round = 0; round < ROUNDS; round++)
            for (int which = 2; which <= 4; which += 2) {
                const double at = starts[s].c[which];
                refine(&d, which, fmax(MR_SLOPE_RATE_MIN, at / step), fmin(MR_SLOPE_RATE_MAX, at * step), &starts[s],
                       &start_rss[s]);
            }
        if (start_rss[s] < best_rss) {
            best_rss = start_rss[s];
            best = starts[s];
        }
    }
    if (!isfinite(best_rss)) {
        free(d.design);
        return mr_fail(MR_ERR_INVALID_ARG, "specular slope fit: the %zu pairs do not determine k (every exponent pair "
                       "leaves its terms dependent: too few distinct roughness values)", n);
    }
    free(d.design);
    best.rms = sqrt(best_rss / (3.0 * (double)n));
    *out = best;
    return MR_OK;
}
