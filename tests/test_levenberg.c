/*
 * test_levenberg.c — the bounded Levenberg-Marquardt of the fits' local stage (src/remap/levenberg.h): known minima,
 * bounds, large residuals, failures, and the small SPD solver it shares with the projection.
 */
#include <math.h>
#include <string.h>

#include "harness.h"
#include "remap/levenberg.h"

/* A problem given by its residuals r(u) (count m) and their Jacobian (m x n): F = |r|^2, g = 2 J^T r, M = J^T J. */
typedef struct residuals {
    int n, m;
    void (*eval)(const double *u, double *r, double *J); /* J may be NULL */
    int values, fail_after;
    double last_u[MR_LM_MAX_DIMENSION];
} residuals;

static double value(void *data, const double *u) {
    residuals *p = data;
    if (p->fail_after > 0 && p->values >= p->fail_after) return NAN;
    p->values++;
    memcpy(p->last_u, u, (size_t)p->n * sizeof *u);
    double r[64], F = 0.0;
    p->eval(u, r, NULL);
    for (int i = 0; i < p->m; i++) F += r[i] * r[i];
    return F;
}

static int linearise(void *data, const double *u, double *g, double *M) {
    residuals *p = data;
    for (int i = 0; i < p->n; i++) MR_CHECK(u[i] == p->last_u[i]); // the contract: right after value() at u
    double r[64], J[64 * MR_LM_MAX_DIMENSION];
    p->eval(u, r, J);
    for (int a = 0; a < p->n; a++) {
        g[a] = 0.0;
        for (int i = 0; i < p->m; i++) g[a] += 2.0 * J[i * p->n + a] * r[i];
        for (int b = 0; b < p->n; b++) {
            M[a * p->n + b] = 0.0;
            for (int i = 0; i < p->m; i++) M[a * p->n + b] += J[i * p->n + a] * J[i * p->n + b];
        }
    }
    return 1;
}

static mr_lm_result minimise(residuals *p, double *u, int max_values) {
    mr_lm_problem problem = {p->n, p, value, linearise, 0.0};
    return mr_lm_minimise(&problem, 1e-9, max_values, u);
}

/* r = A u - y, A 3 x 2: a linear least-squares problem with its minimum inside the box. */
static void linear_eval(const double *u, double *r, double *J) {
    static const double A[3][2] = {{1.0, 0.5}, {0.2, 2.0}, {-0.3, 0.7}};
    static const double y[3] = {0.6, 1.1, 0.2};
    for (int i = 0; i < 3; i++) {
        r[i] = A[i][0] * u[0] + A[i][1] * u[1] - y[i];
        if (J) {
            J[i * 2] = A[i][0];
            J[i * 2 + 1] = A[i][1];
        }
    }
}

MR_TEST(a_linear_problem_is_solved_in_a_few_steps) {
    // Normal equations by hand: (A^T A) u = A^T y.
    double ata[4] = {1.0 + 0.04 + 0.09, 0.5 + 0.4 - 0.21, 0.5 + 0.4 - 0.21, 0.25 + 4.0 + 0.49};
    double aty[2] = {0.6 + 0.22 - 0.06, 0.3 + 2.2 + 0.14};
    MR_CHECK(mr_lm_spd_solve(2, ata, 1, aty));
    residuals p = {2, 3, linear_eval, 0, 0, {0}};
    double u[2] = {0.9, 0.1};
    mr_lm_result r = minimise(&p, u, 50);
    MR_CHECK_NEAR(u[0], aty[0], 1e-6);
    MR_CHECK_NEAR(u[1], aty[1], 1e-6);
    MR_CHECK_MSG(r.values <= 6, "%d evaluations for a linear problem", r.values);
    MR_CHECK(r.at_last_value);
}

/* A minimum outside the box: r = (u0 - 1.5, u1 + 0.25): the answer is the corner (1, 0). */
static void outside_eval(const double *u, double *r, double *J) {
    r[0] = u[0] - 1.5;
    r[1] = u[1] + 0.25;
    if (J) {
        J[0] = 1.0, J[1] = 0.0;
        J[2] = 0.0, J[3] = 1.0;
    }
}

MR_TEST(a_minimum_outside_the_box_ends_on_its_bounds) {
    residuals p = {2, 2, outside_eval, 0, 0, {0}};
    double u[2] = {0.3, 0.6};
    mr_lm_result r = minimise(&p, u, 50);
    MR_CHECK(u[0] == 1.0 && u[1] == 0.0);
    MR_CHECK_NEAR(r.minimum, 0.25 + 0.0625, 1e-12);
}

/* Rosenbrock as residuals, (10 (u1 - u0^2), 1 - u0): minimum 0 at (1, 1), a corner of the box, along a curved
 * valley. */
static void rosenbrock_eval(const double *u, double *r, double *J) {
    r[0] = 10.0 * (u[1] - u[0] * u[0]);
    r[1] = 1.0 - u[0];
    if (J) {
        J[0] = -20.0 * u[0], J[1] = 10.0;
        J[2] = -1.0, J[3] = 0.0;
    }
}

MR_TEST(rosenbrock_valley_to_its_corner) {
    residuals p = {2, 2, rosenbrock_eval, 0, 0, {0}};
    double u[2] = {0.1, 0.9};
    mr_lm_result r = minimise(&p, u, 100);
    MR_CHECK_NEAR(u[0], 1.0, 1e-5);
    MR_CHECK_NEAR(u[1], 1.0, 1e-5);
    MR_CHECK(r.minimum < 1e-9);
}

/* A large residual in one dimension: a lobe of another shape fitted to samples, r_i = exp(-k_i u) - y_i with data
 * no u matches. Gauss-Newton alone converges linearly here; the secant term must make it converge fast. */
static const double large_k[6] = {0.5, 1.0, 2.0, 3.0, 5.0, 8.0};
static const double large_y[6] = {0.9, 0.5, 0.6, 0.1, 0.3, 0.0};
static void large_eval(const double *u, double *r, double *J) {
    for (int i = 0; i < 6; i++) {
        double e = exp(-large_k[i] * 3.0 * u[0]);
        r[i] = e - large_y[i];
        if (J) J[i] = -3.0 * large_k[i] * e;
    }
}

MR_TEST(large_residuals_converge_superlinearly) {
    // The minimum by a dense scan refined with golden sections.
    residuals scan = {1, 6, large_eval, 0, 0, {0}};
    double a = 0.0, b = 1.0, best = 0.0, best_F = HUGE_VAL;
    for (int i = 0; i <= 1000; i++) {
        double u = i / 1000.0, F = value(&scan, &u);
        if (F < best_F) best_F = F, best = u;
    }
    a = fmax(0.0, best - 0.002), b = fmin(1.0, best + 0.002);
    const double phi = 0.5 * (sqrt(5.0) - 1.0);
    for (int i = 0; i < 80; i++) {
        double c = b - phi * (b - a), d = a + phi * (b - a);
        if (value(&scan, &c) < value(&scan, &d)) b = d;
        else a = c;
    }
    const double expected = 0.5 * (a + b);
    MR_CHECK(expected > 0.05 && expected < 0.95);
    residuals p = {1, 6, large_eval, 0, 0, {0}};
    double u[1] = {0.9};
    mr_lm_result r = minimise(&p, u, 100);
    MR_CHECK_NEAR(u[0], expected, 1e-6);
    // Three steps of MAX_STEP (a quarter of the range) walk from 0.9 to the basin; the rest converge superlinearly
    // to F's double rounding (Gauss-Newton alone, without the secant term, took 18 here).
    MR_CHECK_MSG(r.values <= 10, "%d evaluations", r.values);
}

MR_TEST(a_failed_evaluation_ends_with_nan) {
    residuals p = {2, 2, rosenbrock_eval, 0, 3, {0}};
    double u[2] = {0.1, 0.9};
    mr_lm_result r = minimise(&p, u, 100);
    MR_CHECK(isnan(r.minimum));
    MR_CHECK(r.values == 4); // three good, the fourth failed
}

MR_TEST(bounded_work_and_clamped_starts) {
    residuals p = {2, 2, rosenbrock_eval, 0, 0, {0}};
    double u[2] = {-3.0, NAN};
    mr_lm_result r = minimise(&p, u, 3);
    MR_CHECK(r.values <= 3);
    MR_CHECK(u[0] >= 0.0 && u[0] <= 1.0 && u[1] >= 0.0 && u[1] <= 1.0);
    MR_CHECK(isfinite(r.minimum));
    mr_lm_problem bad = {0, &p, value, linearise, 0.0};
    MR_CHECK(isnan(mr_lm_minimise(&bad, 1e-9, 10, u).minimum));
}

MR_TEST(spd_solver_solves_and_refuses) {
    double A[9] = {4, 2, 0.4, 2, 5, 1, 0.4, 1, 3}, B[6] = {1, 0, 2, 1, -1, 3};
    const double A0[9] = {4, 2, 0.4, 2, 5, 1, 0.4, 1, 3}, B0[6] = {1, 0, 2, 1, -1, 3};
    MR_CHECK(mr_lm_spd_solve(3, A, 2, B));
    for (int i = 0; i < 3; i++)
        for (int c = 0; c < 2; c++) {
            double back = 0.0;
            for (int k = 0; k < 3; k++) back += A0[i * 3 + k] * B[k * 2 + c];
            MR_CHECK_NEAR(back, B0[i * 2 + c], 1e-12);
        }
    double singular[4] = {1, 1, 1, 1}, rhs[2] = {1, 2};
    MR_CHECK(!mr_lm_spd_solve(2, singular, 1, rhs));
    double indefinite[4] = {1, 2, 2, 1}, rhs2[2] = {1, 2};
    MR_CHECK(!mr_lm_spd_solve(2, indefinite, 1, rhs2));
}

MR_TEST_MAIN(MR_TEST_ENTRY(a_linear_problem_is_solved_in_a_few_steps),
             MR_TEST_ENTRY(a_minimum_outside_the_box_ends_on_its_bounds),
             MR_TEST_ENTRY(rosenbrock_valley_to_its_corner),
             MR_TEST_ENTRY(large_residuals_converge_superlinearly), MR_TEST_ENTRY(a_failed_evaluation_ends_with_nan),
             MR_TEST_ENTRY(bounded_work_and_clamped_starts), MR_TEST_ENTRY(spd_solver_solves_and_refuses))
