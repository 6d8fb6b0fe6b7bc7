/*
 * levenberg.c — bounded Levenberg–Marquardt (contract and references in levenberg.h).
 */
#include "levenberg.h"

#include <math.h>
#include <string.h>

/* lambda scales the diagonal of M (Marquardt's scaling: invariant to each coordinate's units). It starts small, as
 * the fits start near a minimum (a grid point's basin, a warm start), shrinks by LAMBDA_DOWN after a kept step and
 * grows by LAMBDA_UP after a refused one; past LAMBDA_MAX the steps are far below any tolerance. */
#define LAMBDA_START 1e-3
#define LAMBDA_DOWN 0.25
#define LAMBDA_UP 8.0
#define LAMBDA_MIN 1e-12
#define LAMBDA_MAX 1e10
/* A diagonal entry below this fraction of the largest still gets this much damping, so that a coordinate the
 * images barely see cannot take an unbounded step. */
#define DIAGONAL_FLOOR 1e-12
/* The longest step, in normalised units: a quarter of a parameter's range, about two cells of AUTO's 2-D grid. */
#define MAX_STEP 0.25

int mr_lm_spd_solve(int m, double *A, int r, double *B) {
    for (int j = 0; j < m; j++) { // A = L L^T, L in A's lower triangle
        double d = A[j * m + j];
        for (int k = 0; k < j; k++) d -= A[j * m + k] * A[j * m + k];
        if (!(d > 0.0)) return 0;
        A[j * m + j] = d = sqrt(d);
        for (int i = j + 1; i < m; i++) {
            double v = A[i * m + j];
            for (int k = 0; k < j; k++) v -= A[i * m + k] * A[j * m + k];
            A[i * m + j] = v / d;
        }
    }
    for (int c = 0; c < r; c++) {
        for (int i = 0; i < m; i++) { // L y = b
            double v = B[i * r + c];
            for (int k = 0; k < i; k++) v -= A[i * m + k] * B[k * r + c];
            B[i * r + c] = v / A[i * m + i];
        }
        for (int i = m - 1; i >= 0; i--) { // L^T x = y
            double v = B[i * r + c];
            for (int k = i + 1; k < m; k++) v -= A[k * m + i] * B[k * r + c];
            B[i * r + c] = v / A[i * m + i];
        }
    }
    return 1;
}

/* The symmetric rank-one update of S after a kept step s (Dennis, Gay and Welsch's structured secant idea, NL2SOL,
 * ACM TOMS 7(3), 1981, with SR1 in place of their update): the new model's curvature M + S must turn s into the
 * change of the half-gradient y = (g_new - g_old) / 2, which is what F's true Hessian did along s. Skipped where the
 * correction is nearly orthogonal to s (SR1's safeguard, Nocedal and Wright 6.2). In one dimension this is the
 * secant method on F' = 0 (superlinear), where Gauss-Newton alone converges only linearly when the residual is
 * large (a Ward lobe fitted to a GGX lobe). */
static void secant_update(int n, const double *M, double *S, const double *s, const double *g_old,
                          const double *g_new) {
    double v[MR_LM_MAX_DIMENSION], vs = 0.0, vv = 0.0, ss = 0.0;
    for (int i = 0; i < n; i++) {
        v[i] = 0.5 * (g_new[i] - g_old[i]);
        for (int j = 0; j < n; j++) v[i] -= (M[i * n + j] + S[i * n + j]) * s[j];
        vs += v[i] * s[i];
        vv += v[i] * v[i];
        ss += s[i] * s[i];
    }
    if (!(fabs(vs) > 1e-8 * sqrt(vv * ss))) return;
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++) S[i * n + j] += v[i] * v[j] / vs;
}

/* Drop the secant term; 0 when it was zero already. */
static int secant_reset(int n, double *S) {
    int had = 0;
    for (int i = 0; i < n * n; i++) {
        had |= S[i] != 0.0;
        S[i] = 0.0;
    }
    return had;
}

static double clamp_unit(double x) { return x > 0.0 ? (x < 1.0 ? x : 1.0) : 0.0; } // NaN -> 0

/* The decrease the quadratic model F + g.d + d^T B d promises for the step d = trial - u, B = M + S. */
static double promised_decrease(int n, const double *M, const double *S, const double *g, const double *u,
                                const double *trial) {
    double promised = 0.0;
    for (int i = 0; i < n; i++) {
        double curvature = 0.0;
        for (int j = 0; j < n; j++) curvature += (M[i * n + j] + S[i * n + j]) * (trial[j] - u[j]);
        promised -= (g[i] + curvature) * (trial[i] - u[i]);
    }
    return promised;
}

mr_lm_result mr_lm_minimise(const mr_lm_problem *problem, double xtol, int max_values, double *u) {
    mr_lm_result result = {NAN, 0, 0, 0};
    const int n = problem->n;
    const double noise = problem->noise > 0.0 ? problem->noise : 1e-15;
    if (n < 1 || n > MR_LM_MAX_DIMENSION) return result;
    for (int i = 0; i < n; i++) u[i] = clamp_unit(u[i]);
    double F = problem->value(problem->data, u);
    result.values = 1;
    result.at_last_value = 1;
    if (isnan(F)) return result;
    if (max_values <= 1) { // one evaluation allowed: no step can be tried, so no linearisation is needed
        result.minimum = F;
        return result;
    }
    double gradient[MR_LM_MAX_DIMENSION], M[MR_LM_MAX_DIMENSION * MR_LM_MAX_DIMENSION];
    if (!problem->linearise(problem->data, u, gradient, M)) return result;
    result.linearisations = 1;
    double lambda = LAMBDA_START;
    // S: the secant estimate of the residual's own curvature, which Gauss-Newton leaves out (levenberg.h).
    double S[MR_LM_MAX_DIMENSION * MR_LM_MAX_DIMENSION] = {0};
    while (result.values < max_values) {
        // The free coordinates: not on a bound that the gradient pushes against, and seen by the images.
        int free_index[MR_LM_MAX_DIMENSION], m = 0;
        double largest = 0.0;
        for (int i = 0; i < n; i++) {
            if ((u[i] <= 0.0 && gradient[i] > 0.0) || (u[i] >= 1.0 && gradient[i] < 0.0)) continue;
            if (!(M[i * n + i] > 0.0)) continue; // no curvature means J's column is 0, and so is the gradient
            free_index[m++] = i;
            largest = fmax(largest, M[i * n + i]);
        }
        if (m == 0) break; // every coordinate on a bound it is pushed against: a minimum in the box
        double A[MR_LM_MAX_DIMENSION * MR_LM_MAX_DIMENSION], step[MR_LM_MAX_DIMENSION];
        for (int a = 0; a < m; a++) {
            for (int b = 0; b < m; b++) {
                const int at = free_index[a] * n + free_index[b];
                A[a * m + b] = M[at] + S[at];
            }
            A[a * m + a] += lambda * fmax(M[free_index[a] * n + free_index[a]], DIAGONAL_FLOOR * largest);
            step[a] = -0.5 * gradient[free_index[a]];
        }
        if (!mr_lm_spd_solve(m, A, 1, step)) { // indefinite: without the secant term first, then damped more
            if (secant_reset(n, S)) continue;
            if ((lambda *= LAMBDA_UP) > LAMBDA_MAX) break;
            continue;
        }
        // A step longer than MAX_STEP is shortened along its direction: where a coordinate's curvature is
        // nearly 0 (a parameter the images barely see here), M alone would send it across the whole range.
        double longest = 0.0;
        for (int a = 0; a < m; a++) longest = fmax(longest, fabs(step[a]));
        const double shorten = longest > MAX_STEP ? MAX_STEP / longest : 1.0;
        double trial[MR_LM_MAX_DIMENSION], moved = 0.0;
        memcpy(trial, u, (size_t)n * sizeof *u);
        for (int a = 0; a < m; a++) {
            const int i = free_index[a];
            trial[i] = clamp_unit(u[i] + shorten * step[a]);
            moved = fmax(moved, fabs(trial[i] - u[i]));
        }
        if (moved <= xtol) break; // converged: no coordinate would move by more than the tolerance
        const double promised = promised_decrease(n, M, S, gradient, u, trial);
        if (!(promised > 0.0)) {
            // The model promises no decrease for its own step: the secant term made it indefinite (it is then
            // dropped: plain Gauss-Newton again), or the box's clamp turned the step; damp more.
            if (!secant_reset(n, S) && (lambda *= LAMBDA_UP) > LAMBDA_MAX) break;
            continue;
        }
        if (promised <= noise * F) break; // what it could still gain is rounding
        double F_trial = problem->value(problem->data, trial);
        result.values++;
        if (!(F_trial < F) && !isnan(F_trial) && result.values < max_values) {
            // Refused: F along the step is nearly a parabola through F, its slope g.d and F_trial; one try at its
            // minimum (within [0.1, 0.5] of the step) before more damping saves the renders of several raises of
            // lambda when a long step overshoots (Nocedal and Wright 3.5, interpolation).
            double slope = 0.0;
            for (int i = 0; i < n; i++) slope += gradient[i] * (trial[i] - u[i]);
            const double curvature = F_trial - F - slope;
            const double t = curvature > 0.0 ? fmin(fmax(-slope / (2.0 * curvature), 0.1), 0.5) : 0.5;
            for (int i = 0; i < n; i++) trial[i] = clamp_unit(u[i] + t * (trial[i] - u[i]));
            F_trial = problem->value(problem->data, trial);
            result.values++;
        }
        if (isnan(F_trial)) {
            result.minimum = NAN;
            result.at_last_value = 0;
            return result;
        }
        if (!(F_trial < F)) {
            result.at_last_value = 0;
            if ((lambda *= LAMBDA_UP) > LAMBDA_MAX) break;
            continue;
        }
        const double gain = F - F_trial;
        double previous_gradient[MR_LM_MAX_DIMENSION], step_taken[MR_LM_MAX_DIMENSION];
        for (int i = 0; i < n; i++) step_taken[i] = trial[i] - u[i];
        memcpy(u, trial, (size_t)n * sizeof *u);
        F = F_trial;
        result.at_last_value = 1;
        lambda = fmax(lambda * LAMBDA_DOWN, LAMBDA_MIN);
        if (gain <= noise * F) break; // the decrease is rounding: F is at its minimum
        memcpy(previous_gradient, gradient, (size_t)n * sizeof *gradient);
        if (!problem->linearise(problem->data, u, gradient, M)) {
            result.minimum = NAN;
            return result;
        }
        result.linearisations++;
        secant_update(n, M, S, step_taken, previous_gradient, gradient);
    }
    result.minimum = F;
    return result;
}
