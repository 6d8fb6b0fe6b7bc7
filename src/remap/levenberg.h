/*
 * levenberg.h — bounded Levenberg–Marquardt minimisation of a sum of squares, the local stage of the image fits
 * (remap.c) when the target model has analytic derivatives (brdf.h, eval_grad).
 *
 * The problem is F(u) = |r(u)|^2 over the box [0,1]^n (the fit's normalised coordinates). The caller gives F and, at
 * a point F was just evaluated at, the gradient g = 2 J^T r and a Gauss-Newton matrix M ~ J^T J (for a variable
 * projection, Kaufman's: J projected off the solved linear columns; Kaufman, BIT 15, 1975). A step solves
 * (M + lambda diag(M)) d = -g/2 over the coordinates that are free (not on a bound the gradient pushes against:
 * the projected Gauss-Newton step of Bertsekas, SIAM J. Control 20(2), 1982), clamps u + d into the box, and is
 * kept if F decreases (then lambda shrinks, and the next step is nearly Gauss-Newton: quadratic convergence for
 * small residuals) or refused (lambda grows: a shorter step towards steepest descent). Moré's safeguards in short
 * (Moré, "The Levenberg-Marquardt algorithm: implementation and theory", 1978), with three additions the image fits
 * need: a symmetric rank-one secant estimate of the residual's own curvature added to M (large residuals, where
 * Gauss-Newton alone converges linearly: a Ward lobe fitted to a GGX one), steps of at most a quarter of the box,
 * and one retry of a refused step at the minimum of the parabola along it.
 *
 * It stops when a step would move no coordinate by more than xtol (the same normalised tolerance the derivative-free
 * BOBYQA stage uses), when a step promises or gains no more than F's rounding (`noise`), when lambda grows past any
 * useful step, or after max_values evaluations of F. Deterministic: the same calls in the same order for the same
 * inputs.
 */
#ifndef MR_LEVENBERG_H
#define MR_LEVENBERG_H

#define MR_LM_MAX_DIMENSION 24

typedef struct mr_lm_problem {
    int n;      /* 1 .. MR_LM_MAX_DIMENSION coordinates, each in [0, 1] */
    void *data; /* passed to the callbacks */
    /* F at u, >= 0; NAN stops the minimisation (a failed render: the caller records why). */
    double (*value)(void *data, const double *u);
    /* Called only directly after value() at this same u (so it may reuse what value computed): the gradient of F
     * (n doubles) and the Gauss-Newton matrix (n x n, row-major, symmetric positive semi-definite). 0 stops the
     * minimisation (a failure the caller records). */
    int (*linearise)(void *data, const double *u, double *gradient, double *gauss_newton);
    double noise; /* F's relative rounding: a step that promises or gains less than noise * F ends the search
                     (F summed from float images: ~1e-7); 0: 1e-15 (F in double throughout) */
} mr_lm_problem;

typedef struct mr_lm_result {
    double minimum;   /* F at the returned u (NAN after a failure) */
    int values;       /* evaluations of F made */
    int linearisations;
    int at_last_value; /* 1 when the last value() call was at the returned u (the caller's state matches it) */
} mr_lm_result;

/* Solve A X = B for a symmetric positive definite m x m matrix A (row-major; overwritten by its Cholesky factor) and
 * r right-hand sides B (m x r, row-major; overwritten by X); 0, with A and B garbage, when A is not numerically
 * positive definite. */
int mr_lm_spd_solve(int m, double *A, int r, double *B);

/* Minimise from u (in/out, clamped into [0,1] first). xtol > 0; max_values >= 1. */
mr_lm_result mr_lm_minimise(const mr_lm_problem *problem, double xtol, int max_values, double *u);

#endif /* MR_LEVENBERG_H */
