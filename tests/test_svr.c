/*
 * test_svr.c — epsilon-SVR transforms (src/learn/svr.h): smooth functions recovered on held-out points, the same
 * model bits for any thread count, our prediction against libsvm's svm_predict, the local search never worse than
 * the grid, fixed hyper-parameters, the far field outside the data (the paper's Fig. 19), plain-data models, and
 * bad arguments refused with the value named.
 *
 * Training cases use a few hundred rows (a second or two each on 2 cores). The measurements of a realistic case run
 * only when asked:
 *   MR_SVR_TIMING=1 OMP_NUM_THREADS=2 build/tests/test_svr timing
 */
#include <libsvm/svm.h>
#include <math.h>
#include <omp.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "harness.h"
#include "learn/svr.h"
#include "mr_internal.h"

/* ---- helpers ---------------------------------------------------------------------------------------------- */

static double uniform(uint64_t *s, double lo, double hi) {
    *s = *s * 6364136223846793005ull + 1442695040888963407ull;
    return lo + (hi - lo) * (double)(*s >> 11) * (1.0 / 9007199254740992.0);
}

/* A remap-like transform: Ward alpha and specular RGB in, GGX alpha and F0 RGB out (the shape of the paper's
 * appendix fits: a roughness polynomial, one slope k(alpha) for the three channels). */
static void brdf_like(const double *x, double *y) {
    const double a = x[0];
    const double k = 1.05 - 0.187 * exp(-23.45 * a) + 0.036 * exp(-116.4 * a * a);
    y[0] = 0.02 + 1.01 * a - 0.13 * a * a - 0.41 * a * a * a + 0.24 * a * a * a * a;
    for (int c = 0; c < 3; c++) y[1 + c] = k * x[1 + c];
}

static void brdf_like_rows(size_t n, uint64_t seed, double noise, double *x, double *y) {
    for (size_t r = 0; r < n; r++) {
        x[4 * r] = uniform(&seed, 0.01, 1.0);
        for (int c = 1; c < 4; c++) x[4 * r + c] = uniform(&seed, 0.0, 1.0);
        brdf_like(x + 4 * r, y + 4 * r);
        for (int k = 0; k < 4; k++) y[4 * r + k] += noise * uniform(&seed, -1.0, 1.0);
    }
}

/* Whether two models are the same bits, field by field. */
static int same_model(const mr_svr *a, const mr_svr *b) {
    if (a->n_in != b->n_in || a->n_out != b->n_out) return 0;
    if (memcmp(a->in_mean, b->in_mean, (size_t)a->n_in * sizeof(double)) != 0 ||
        memcmp(a->in_std, b->in_std, (size_t)a->n_in * sizeof(double)) != 0 ||
        memcmp(a->out_mean, b->out_mean, (size_t)a->n_out * sizeof(double)) != 0 ||
        memcmp(a->out_std, b->out_std, (size_t)a->n_out * sizeof(double)) != 0)
        return 0;
    for (int k = 0; k < a->n_out; k++) {
        const mr_svr_output *p = &a->outputs[k], *q = &b->outputs[k];
        if (p->sv_count != q->sv_count) return 0;
        const double pv[6] = {p->rho, p->gamma, p->C, p->epsilon, p->validation_rmse, p->grid_rmse};
        const double qv[6] = {q->rho, q->gamma, q->C, q->epsilon, q->validation_rmse, q->grid_rmse};
        if (memcmp(pv, qv, sizeof pv) != 0) return 0;
        if (memcmp(p->sv, q->sv, (size_t)p->sv_count * (size_t)a->n_in * sizeof(double)) != 0 ||
            memcmp(p->coef, q->coef, (size_t)p->sv_count * sizeof(double)) != 0)
            return 0;
    }
    return 1;
}

/* Train on n rows of f (n_in inputs drawn uniformly in [0, 1], n_out outputs) with the given options. */
static mr_svr *train_function(void (*f)(const double *, double *), size_t n, int n_in, int n_out, uint64_t seed,
                              const mr_svr_train_options *o, mr_svr_train_report *r) {
    double *x = malloc(n * (size_t)n_in * sizeof *x), *y = malloc(n * (size_t)n_out * sizeof *y);
    for (size_t i = 0; i < n; i++) {
        for (int c = 0; c < n_in; c++) x[i * (size_t)n_in + (size_t)c] = uniform(&seed, 0.0, 1.0);
        f(x + i * (size_t)n_in, y + i * (size_t)n_out);
    }
    mr_svr *m = NULL;
    MR_CHECK_OK(mr_svr_train(x, y, n, n_in, n_out, o, &m, r));
    free(x);
    free(y);
    return m;
}

static void sine(const double *x, double *y) { y[0] = sin(2.0 * MR_PI * x[0]); }

static void surface(const double *x, double *y) { y[0] = sin(3.0 * x[0]) * cos(2.0 * x[1]) + 0.5 * x[0]; }

static void two_outputs(const double *x, double *y) {
    y[0] = exp(-2.0 * x[0]) + 0.3 * x[1];
    y[1] = 0.2 + 0.5 * x[0] * x[1];
}

static void line(const double *x, double *y) { y[0] = 2.0 * x[0] + 1.0; }

/* The largest and root mean square error of m against f on `count` held-out points in [lo, hi]^n_in. */
static void held_out_error(const mr_svr *m, void (*f)(const double *, double *), int count, double lo, double hi,
                           double *max_err, double *rms) {
    double x[8], want[8], got[8], ss = 0.0;
    uint64_t seed = 4242;
    *max_err = 0.0;
    for (int i = 0; i < count; i++) {
        for (int c = 0; c < m->n_in; c++) x[c] = uniform(&seed, lo, hi);
        f(x, want);
        MR_CHECK_OK(mr_svr_predict(m, x, 1, got));
        for (int k = 0; k < m->n_out; k++) {
            const double e = fabs(got[k] - want[k]);
            *max_err = e > *max_err ? e : *max_err;
            ss += e * e;
        }
    }
    *rms = sqrt(ss / (count * m->n_out));
}

/* ---- cases ------------------------------------------------------------------------------------------------ */

/* y = sin(2 pi x) from 150 noise-free rows: recovered on held-out points inside the data (within 0.002 of a unit
 * amplitude, 0.001 root mean square); the search's choice is never worse than the grid's best. */
MR_TEST(sine_recovered) {
    mr_svr_train_options o = {0};
    o.seed = 3;
    mr_svr_train_report r;
    mr_svr *m = train_function(sine, 150, 1, 1, 11, &o, &r);
    if (m == NULL) return;
    double max_err, rms;
    held_out_error(m, sine, 400, 0.02, 0.98, &max_err, &rms);
    MR_CHECK_MSG(max_err < 0.002 && rms < 0.001, "max %g rms %g", max_err, rms);
    MR_CHECK(r.n_validation == 30 && r.n_train == 120 && r.n_search == 120);
    MR_CHECK(r.grid_fits > 0 && r.local_fits > 0 && r.local_rounds > 0);
    MR_CHECK(r.iterations >= r.grid_fits + r.local_fits); // libsvm's counts reach us (the cost cap relies on them)
    MR_CHECK_MSG(m->outputs[0].validation_rmse <= m->outputs[0].grid_rmse, "%g > %g", m->outputs[0].validation_rmse,
                 m->outputs[0].grid_rmse);
    MR_CHECK_OK(mr_svr_check(m));
    mr_svr_free(m);
}

/* A smooth function of two inputs from 300 rows: held-out error within 0.004 root mean square, 0.02 at worst. */
MR_TEST(two_inputs_recovered) {
    mr_svr_train_options o = {0};
    o.seed = 5;
    mr_svr_train_report r;
    mr_svr *m = train_function(surface, 300, 2, 1, 13, &o, &r);
    if (m == NULL) return;
    double max_err, rms;
    held_out_error(m, surface, 400, 0.02, 0.98, &max_err, &rms);
    MR_CHECK_MSG(max_err < 0.02 && rms < 0.004, "max %g rms %g", max_err, rms);
    MR_CHECK(m->outputs[0].validation_rmse <= m->outputs[0].grid_rmse);
    mr_svr_free(m);
}

/* The same seed gives the same model bits on 1, 2 and 3 threads; predictions are the same bits on any team. */
MR_TEST(threads_bit_identical) {
    mr_svr *m[3] = {NULL, NULL, NULL};
    for (int t = 0; t < 3; t++) {
        mr_svr_train_options o = {0};
        o.seed = 9;
        o.threads = t + 1;
        m[t] = train_function(two_outputs, 120, 2, 2, 17, &o, NULL);
    }
    if (m[0] == NULL || m[1] == NULL || m[2] == NULL) goto done;
    MR_CHECK(same_model(m[0], m[1]));
    MR_CHECK(same_model(m[0], m[2]));
    enum { ROWS = 1500 };
    double *in = malloc(ROWS * 2 * sizeof *in), *a = malloc(ROWS * 2 * sizeof *a), *b = malloc(ROWS * 2 * sizeof *b);
    uint64_t seed = 1;
    for (int i = 0; i < 2 * ROWS; i++) in[i] = uniform(&seed, -0.5, 1.5);
    MR_CHECK_OK(mr_svr_predict_threads(m[0], in, ROWS, a, 1));
    MR_CHECK_OK(mr_svr_predict_threads(m[0], in, ROWS, b, 3));
    MR_CHECK(memcmp(a, b, ROWS * 2 * sizeof *a) == 0);
    for (int i = 0; i < ROWS; i += 97) { // a row alone is the same bits as in a batch
        double one[2];
        MR_CHECK_OK(mr_svr_predict(m[0], in + 2 * i, 1, one));
        MR_CHECK(memcmp(one, a + 2 * i, sizeof one) == 0);
    }
    free(in);
    free(a);
    free(b);
done:
    for (int t = 0; t < 3; t++) mr_svr_free(m[t]);
}

/* Our prediction against libsvm's svm_predict on the same model (rebuilt as an svm_model from the plain fields), at
 * points inside and far outside the data: equal within 1e-12 relative to the larger of the prediction and the
 * size of the terms it sums, out_std sum |coef| (our exp is within 1 ulp of glibc's; the sum cancels). */
MR_TEST(predict_matches_libsvm) {
    mr_svr_train_options o = {0};
    o.seed = 2;
    mr_svr *m = train_function(two_outputs, 160, 2, 2, 23, &o, NULL);
    if (m == NULL) return;
    const int n_in = m->n_in;
    int identical = 0, total = 0;
    double worst = 0.0;
    for (int k = 0; k < m->n_out; k++) {
        const mr_svr_output *q = &m->outputs[k];
        struct svm_node *nodes = malloc((size_t)q->sv_count * (size_t)(n_in + 1) * sizeof *nodes);
        struct svm_node **sv = malloc((size_t)q->sv_count * sizeof *sv);
        for (int s = 0; s < q->sv_count; s++) {
            sv[s] = nodes + s * (n_in + 1);
            for (int i = 0; i < n_in; i++) sv[s][i] = (struct svm_node){i + 1, q->sv[s * n_in + i]};
            sv[s][n_in] = (struct svm_node){-1, 0.0};
        }
        double *coef = q->coef, rho = q->rho, terms = 0.0;
        for (int s = 0; s < q->sv_count; s++) terms += fabs(q->coef[s]);
        terms *= m->out_std[k];
        struct svm_model sm;
        memset(&sm, 0, sizeof sm);
        sm.param.svm_type = EPSILON_SVR;
        sm.param.kernel_type = RBF;
        sm.param.gamma = q->gamma;
        sm.nr_class = 2;
        sm.l = q->sv_count;
        sm.SV = sv;
        sm.sv_coef = &coef;
        sm.rho = &rho;
        uint64_t seed = 77;
        for (int i = 0; i < 300; i++) {
            double x[2], u[3 * 2], ours[2];
            struct svm_node node[3];
            for (int c = 0; c < 2; c++) {
                x[c] = i < 250 ? uniform(&seed, 0.0, 1.0) : uniform(&seed, -3.0, 4.0);
                u[c] = (x[c] - m->in_mean[c]) / m->in_std[c];
                node[c] = (struct svm_node){c + 1, u[c]};
            }
            node[2] = (struct svm_node){-1, 0.0};
            MR_CHECK_OK(mr_svr_predict(m, x, 1, ours));
            const double theirs = m->out_mean[k] + m->out_std[k] * svm_predict(&sm, node);
            MR_CHECK_MSG(fabs(ours[k] - theirs) <= 1e-12 * fmax(terms, fabs(theirs)),
                         "output %d: %.17g vs libsvm %.17g (terms %g)", k, ours[k], theirs, terms);
            identical += ours[k] == theirs;
            worst = fmax(worst, fabs(ours[k] - theirs) / fmax(terms, fabs(theirs)));
            total++;
        }
        free(nodes);
        free(sv);
    }
    printf("    %d of %d predictions the same bits as libsvm's, the others within %.2g relative to the terms\n",
           identical, total, worst);
    mr_svr_free(m);
}

/* With every hyper-parameter fixed at the search's choice, one fit per output reproduces the searched model bit
 * for bit (the same split, the same fits), validation error included; with only gamma fixed, every output has it. */
MR_TEST(fixed_hyper_parameters) {
    mr_svr_train_options o = {0};
    o.seed = 4;
    mr_svr *searched = train_function(surface, 200, 2, 1, 31, &o, NULL);
    if (searched == NULL) return;
    o.C = searched->outputs[0].C;
    o.gamma = searched->outputs[0].gamma;
    o.epsilon = searched->outputs[0].epsilon;
    mr_svr_train_report r;
    mr_svr *fixed = train_function(surface, 200, 2, 1, 31, &o, &r);
    if (fixed != NULL) {
        MR_CHECK(r.grid_fits == 1 && r.local_fits == 0);
        MR_CHECK(fixed->outputs[0].validation_rmse == searched->outputs[0].validation_rmse);
        MR_CHECK(fixed->outputs[0].grid_rmse == fixed->outputs[0].validation_rmse);
        MR_CHECK(fixed->outputs[0].sv_count == searched->outputs[0].sv_count);
        MR_CHECK(fixed->outputs[0].sv_count > 0 &&
                 memcmp(fixed->outputs[0].coef, searched->outputs[0].coef,
                        (size_t)fixed->outputs[0].sv_count * sizeof(double)) == 0);
        MR_CHECK(fixed->outputs[0].rho == searched->outputs[0].rho);
    }
    mr_svr_free(fixed);
    mr_svr_train_options g = {0};
    g.gamma = 0.75;
    mr_svr *partial = train_function(two_outputs, 120, 2, 2, 37, &g, &r);
    if (partial != NULL) {
        MR_CHECK(partial->outputs[0].gamma == 0.75 && partial->outputs[1].gamma == 0.75);
        MR_CHECK(r.grid_fits > 2 && r.grid_fits <= 2 * 8 * 4);
        for (int k = 0; k < 2; k++) MR_CHECK(partial->outputs[k].validation_rmse <= partial->outputs[k].grid_rmse);
    }
    mr_svr_free(partial);
    mr_svr_free(searched);
}

/* Extrapolation (svr.h; the paper's Fig. 19): trained on y = 2x + 1 over [0, 1], the SVR does not continue the
 * line. Far from the data every kernel term vanishes and the prediction is the far field out_mean - out_std rho,
 * exactly, a value inside the training outputs' range, near their mean; already 2 units beyond the data it has
 * fallen back below the last training output, where the line would give 7. */
MR_TEST(extrapolation_falls_back_to_the_mean) {
    mr_svr_train_options o = {0};
    o.seed = 8;
    mr_svr *m = train_function(line, 120, 1, 1, 41, &o, NULL);
    if (m == NULL) return;
    const double far = mr_svr_far_field(m, 0);
    const double xs[4] = {1e6, -1e6, INFINITY, -INFINITY};
    for (int i = 0; i < 4; i++) {
        double y;
        MR_CHECK_OK(mr_svr_predict(m, &xs[i], 1, &y));
        MR_CHECK_MSG(y == far, "x %g: %.17g, far field %.17g", xs[i], y, far);
    }
    MR_CHECK_MSG(far > 1.0 && far < 3.0 && fabs(far - m->out_mean[0]) < m->out_std[0], "far field %g (mean %g, std %g)",
                 far, m->out_mean[0], m->out_std[0]);
    double inside, beyond, x_in = 0.5, x_out = 3.0;
    MR_CHECK_OK(mr_svr_predict(m, &x_in, 1, &inside));
    MR_CHECK_OK(mr_svr_predict(m, &x_out, 1, &beyond));
    MR_CHECK_NEAR(inside, 2.0, 0.01);
    MR_CHECK_MSG(beyond < 3.0, "y(3) = %g (the line: 7)", beyond);
    mr_svr_free(m);
}

/* A NaN input gives NaN in every output of its row, and nothing in the others. */
MR_TEST(nan_input) {
    mr_svr_train_options o = {0};
    o.C = 4.0;
    o.gamma = 1.0;
    o.epsilon = 0.01;
    mr_svr *m = train_function(two_outputs, 60, 2, 2, 43, &o, NULL);
    if (m == NULL) return;
    const double in[6] = {0.2, 0.3, NAN, 0.5, 0.7, 0.1};
    double out[6], alone[2];
    MR_CHECK_OK(mr_svr_predict(m, in, 3, out));
    MR_CHECK(isnan(out[2]) && isnan(out[3]));
    MR_CHECK(isfinite(out[0]) && isfinite(out[1]) && isfinite(out[4]) && isfinite(out[5]));
    MR_CHECK_OK(mr_svr_predict(m, in + 4, 1, alone));
    MR_CHECK(memcmp(alone, out + 4, sizeof alone) == 0);
    mr_svr_free(m);
}

/* mr_svr_alloc's model (for a file reader): its layout, zero predictions, and mr_svr_check naming bad fields. */
MR_TEST(alloc_and_check) {
    const int counts[2] = {3, 0};
    mr_svr *m = NULL;
    MR_CHECK_OK(mr_svr_alloc(4, 2, counts, &m));
    if (m == NULL) return;
    MR_CHECK(m->n_in == 4 && m->n_out == 2 && m->outputs[0].sv_count == 3 && m->outputs[1].sv_count == 0);
    MR_CHECK(m->in_std[3] == 1.0 && m->out_std[1] == 1.0 && m->outputs[0].gamma == 1.0);
    MR_CHECK(m->outputs[0].coef == m->outputs[0].sv + 12); // one block, in the documented order
    MR_CHECK_OK(mr_svr_check(m));
    const double in[4] = {0.1, 0.2, 0.3, 0.4};
    double out[2] = {1.0, 1.0};
    MR_CHECK_OK(mr_svr_predict(m, in, 1, out));
    MR_CHECK(out[0] == 0.0 && out[1] == 0.0);
    m->outputs[1].rho = -0.5;
    m->out_mean[1] = 2.0;
    MR_CHECK_OK(mr_svr_predict(m, in, 1, out));
    MR_CHECK(out[1] == 2.5 && mr_svr_far_field(m, 1) == 2.5); // no support vectors: the constant -rho
    m->outputs[0].gamma = -1.0;
    MR_CHECK(mr_svr_check(m) == MR_ERR_INVALID_ARG && strstr(mr_last_error(), "output 0: gamma") != NULL);
    m->outputs[0].gamma = 2.0;
    m->in_std[2] = 0.0;
    MR_CHECK(mr_svr_check(m) == MR_ERR_INVALID_ARG && strstr(mr_last_error(), "in_std[2]") != NULL);
    m->in_std[2] = 1.0;
    m->outputs[0].sv[5] = NAN;
    MR_CHECK(mr_svr_check(m) == MR_ERR_INVALID_ARG && strstr(mr_last_error(), "sv[5]") != NULL);
    m->outputs[0].sv[5] = 0.0;
    MR_CHECK_OK(mr_svr_check(m));
    mr_svr_free(m);
    mr_svr_free(NULL);
    mr_svr *untouched = (mr_svr *)&counts;
    const int negative[1] = {-1};
    MR_CHECK(mr_svr_alloc(0, 1, counts, &untouched) == MR_ERR_INVALID_ARG);
    MR_CHECK(mr_svr_alloc(1, 1, negative, &untouched) == MR_ERR_INVALID_ARG);
    MR_CHECK(strstr(mr_last_error(), "-1 support vectors") != NULL);
    MR_CHECK(untouched == (mr_svr *)&counts);
    MR_CHECK(mr_svr_predict(NULL, in, 1, out) == MR_ERR_INVALID_ARG);
}

/* Bad training data and options: MR_ERR_INVALID_ARG naming the value, *out and *report untouched. */
MR_TEST(invalid_training_input) {
    double x[2 * 10], y[10];
    for (int i = 0; i < 10; i++) {
        x[2 * i] = i / 10.0;
        x[2 * i + 1] = 1.0 - i / 10.0;
        y[i] = x[2 * i] * x[2 * i];
    }
    mr_svr *m = (mr_svr *)x;
    mr_svr_train_report r;
    memset(&r, 0xab, sizeof r);
    const mr_svr_train_report before = r;
    x[7] = NAN; // row 3, column 1
    MR_CHECK(mr_svr_train(x, y, 10, 2, 1, NULL, &m, &r) == MR_ERR_INVALID_ARG);
    MR_CHECK_MSG(strstr(mr_last_error(), "input row 3 column 1") != NULL, "%s", mr_last_error());
    x[7] = 0.5;
    y[6] = INFINITY;
    MR_CHECK(mr_svr_train(x, y, 10, 2, 1, NULL, &m, &r) == MR_ERR_INVALID_ARG);
    MR_CHECK_MSG(strstr(mr_last_error(), "output row 6 column 0") != NULL, "%s", mr_last_error());
    y[6] = 0.0;
    MR_CHECK(mr_svr_train(x, y, 1, 2, 1, NULL, &m, &r) == MR_ERR_INVALID_ARG);
    MR_CHECK(mr_svr_train(x, y, 10, 0, 1, NULL, &m, &r) == MR_ERR_INVALID_ARG);
    MR_CHECK(mr_svr_train(x, y, 10, 2, MR_SVR_MAX_IO + 1, NULL, &m, &r) == MR_ERR_INVALID_ARG);
    MR_CHECK(mr_svr_train(NULL, y, 10, 2, 1, NULL, &m, &r) == MR_ERR_INVALID_ARG);
    MR_CHECK(mr_svr_train(x, y, 10, 2, 1, NULL, NULL, &r) == MR_ERR_INVALID_ARG);
    mr_svr_train_options o = {0};
    o.validation_fraction = 1.0;
    MR_CHECK(mr_svr_train(x, y, 10, 2, 1, &o, &m, &r) == MR_ERR_INVALID_ARG);
    MR_CHECK(strstr(mr_last_error(), "validation_fraction 1") != NULL);
    o.validation_fraction = 0.0;
    o.threads = -1;
    MR_CHECK(mr_svr_train(x, y, 10, 2, 1, &o, &m, &r) == MR_ERR_INVALID_ARG);
    o.threads = 0;
    o.C = -1.0;
    MR_CHECK(mr_svr_train(x, y, 10, 2, 1, &o, &m, &r) == MR_ERR_INVALID_ARG);
    MR_CHECK(strstr(mr_last_error(), "C -1") != NULL);
    o.C = 0.0;
    o.gamma = NAN;
    MR_CHECK(mr_svr_train(x, y, 10, 2, 1, &o, &m, &r) == MR_ERR_INVALID_ARG);
    MR_CHECK(strstr(mr_last_error(), "gamma") != NULL);
    o.gamma = 0.0;
    o.epsilon = INFINITY;
    MR_CHECK(mr_svr_train(x, y, 10, 2, 1, &o, &m, &r) == MR_ERR_INVALID_ARG);
    MR_CHECK(strstr(mr_last_error(), "epsilon") != NULL);
    o.epsilon = 0.0;
    o.search_rows = -5;
    MR_CHECK(mr_svr_train(x, y, 10, 2, 1, &o, &m, &r) == MR_ERR_INVALID_ARG);
    MR_CHECK(strstr(mr_last_error(), "search_rows -5") != NULL);
    MR_CHECK(m == (mr_svr *)x && memcmp(&r, &before, sizeof r) == 0);
}

typedef struct progress_log {
    int calls, stop_at, phases[MR_SVR_PHASE_COUNT], order_ok, counts_ok;
    mr_svr_phase last;
} progress_log;

static int log_progress(const mr_svr_progress *p, void *user) {
    progress_log *l = user;
    l->calls++;
    if (p->phase < l->last) l->order_ok = 0;
    if (p->done < 0 || p->done > p->planned) l->counts_ok = 0;
    l->last = p->phase;
    l->phases[p->phase]++;
    return l->stop_at > 0 && l->calls >= l->stop_at;
}

/* The progress callback sees the phases in order with sensible counts; asking to stop cancels the run cleanly. */
MR_TEST(progress_and_cancel) {
    progress_log l = {0, 0, {0, 0, 0}, 1, 1, MR_SVR_PHASE_GRID};
    mr_svr_train_options o = {0};
    o.progress = log_progress;
    o.progress_user = &l;
    mr_svr *m = train_function(sine, 60, 1, 1, 47, &o, NULL);
    MR_CHECK(m != NULL && l.order_ok && l.counts_ok);
    MR_CHECK(l.phases[MR_SVR_PHASE_GRID] > 0 && l.phases[MR_SVR_PHASE_LOCAL] > 0 && l.phases[MR_SVR_PHASE_REFIT] == 1);
    mr_svr_free(m);
    double x[60], y[60];
    uint64_t seed = 3;
    for (int i = 0; i < 60; i++) {
        x[i] = uniform(&seed, 0.0, 1.0);
        sine(&x[i], &y[i]);
    }
    for (int stop = 1; stop <= 3; stop += 2) { // during the grid, then later
        progress_log c = {0, stop, {0, 0, 0}, 1, 1, MR_SVR_PHASE_GRID};
        o.progress_user = &c;
        m = (mr_svr *)x;
        MR_CHECK(mr_svr_train(x, y, 60, 1, 1, &o, &m, NULL) == MR_ERR_CANCELLED);
        MR_CHECK(m == (mr_svr *)x && c.calls == stop);
    }
}

/* With more training rows than search_rows, the search fits on the first search_rows of the training split and
 * the reported validation error is the chosen fit's on the whole training split. */
MR_TEST(search_on_a_subsample) {
    mr_svr_train_options o = {0};
    o.seed = 6;
    o.search_rows = 60;
    mr_svr_train_report r;
    mr_svr *m = train_function(surface, 250, 2, 1, 53, &o, &r);
    if (m == NULL) return;
    MR_CHECK(r.n_search == 60 && r.n_train == 200);
    double max_err, rms;
    held_out_error(m, surface, 400, 0.02, 0.98, &max_err, &rms);
    MR_CHECK_MSG(rms < 0.01, "rms %g", rms);
    MR_CHECK(m->outputs[0].validation_rmse > 0.0 && m->outputs[0].validation_rmse < 0.01);
    mr_svr_free(m);
}

/* ---- timing (asked for) ------------------------------------------------------------------------------------ */

static int print_progress(const mr_svr_progress *p, void *user) {
    (void)user;
    static const char *names[] = {"grid", "local", "refit"};
    fprintf(stderr, "    %-5s %5ld / %5ld cand.  %6.2f s\n", names[p->phase], p->done, p->planned,
            p->seconds);
    return 0;
}

/* A realistic case: 4 inputs, 4 outputs, 900 rows of a remap-like function with optimiser-like noise; training time,
 * validation error, and prediction throughput on omp_get_max_threads() threads. */
MR_TEST(timing) {
    const char *env = getenv("MR_SVR_TIMING");
    if (env == NULL || env[0] == '\0' || env[0] == '0') return;
    const size_t n = env[0] >= '2' && env[0] <= '9' ? (size_t)(env[0] - '0') * 1000 : 900;
    double *x = malloc(n * 4 * sizeof *x), *y = malloc(n * 4 * sizeof *y);
    brdf_like_rows(n, 5, 0.002, x, y);
    mr_svr_train_options o = {0};
    o.seed = 1;
    o.progress = getenv("MR_SVR_PROGRESS") != NULL ? print_progress : NULL;
    mr_svr *m = NULL;
    mr_svr_train_report r;
    MR_CHECK_OK(mr_svr_train(x, y, n, 4, 4, &o, &m, &r));
    if (m == NULL) return;
    printf("    %zu rows (%zu train, %zu validation, search on %zu), %d threads: %.2f s\n", n, r.n_train,
           r.n_validation, r.n_search, omp_get_max_threads(), r.seconds);
    printf("    %ld grid fits, %ld local fits in %d rounds, %ld above the iteration cap; %lld libsvm iterations\n",
           r.grid_fits, r.local_fits, r.local_rounds, r.costly_fits, r.iterations);
    for (int k = 0; k < 4; k++) {
        const mr_svr_output *q = &m->outputs[k];
        printf("    output %d: C %.4g gamma %.4g epsilon %.3g; %d SVs; validation RMSE %.3e (grid's best %.3e)\n", k,
               q->C, q->gamma, q->epsilon, q->sv_count, q->validation_rmse, q->grid_rmse);
    }
    // Held-out error against the noise-free function.
    enum { TEST = 2000 };
    double *tx = malloc(TEST * 4 * sizeof *tx), *ty = malloc(TEST * 4 * sizeof *ty), *p = malloc(TEST * 4 * sizeof *p);
    brdf_like_rows(TEST, 99, 0.0, tx, ty);
    MR_CHECK_OK(mr_svr_predict(m, tx, TEST, p));
    for (int k = 0; k < 4; k++) {
        double ss = 0.0;
        for (int i = 0; i < TEST; i++) ss += (p[4 * i + k] - ty[4 * i + k]) * (p[4 * i + k] - ty[4 * i + k]);
        printf("    output %d: held-out RMSE against the noise-free function %.3e\n", k, sqrt(ss / TEST));
    }
    // Throughput: the best of three runs on 1 thread and on omp_get_max_threads().
    const size_t rows = 200000;
    double *in = malloc(rows * 4 * sizeof *in), *out = malloc(rows * 4 * sizeof *out);
    brdf_like_rows(rows, 7, 0.0, in, out);
    int svs = 0;
    for (int k = 0; k < 4; k++) svs += m->outputs[k].sv_count;
    const int most = omp_get_max_threads();
    for (int team = 1; team <= most; team += most > 1 ? most - 1 : 1) {
        double best = INFINITY;
        for (int rep = 0; rep < 3; rep++) {
            const double t0 = mr_now_seconds();
            MR_CHECK_OK(mr_svr_predict_threads(m, in, rows, out, team));
            best = fmin(best, mr_now_seconds() - t0);
        }
        printf("    prediction: %.3f M rows/s on %d thread(s) (%d SVs in all; %.2f ns per kernel term and thread)\n",
               rows / best / 1e6, team, svs, best * 1e9 * team / ((double)rows * svs));
    }
    free(in);
    free(out);
    free(tx);
    free(ty);
    free(p);
    mr_svr_free(m);
    free(x);
    free(y);
}

MR_TEST_MAIN(MR_TEST_ENTRY(sine_recovered), MR_TEST_ENTRY(two_inputs_recovered), MR_TEST_ENTRY(threads_bit_identical),
             MR_TEST_ENTRY(predict_matches_libsvm), MR_TEST_ENTRY(fixed_hyper_parameters),
             MR_TEST_ENTRY(extrapolation_falls_back_to_the_mean), MR_TEST_ENTRY(nan_input),
             MR_TEST_ENTRY(alloc_and_check), MR_TEST_ENTRY(invalid_training_input), MR_TEST_ENTRY(progress_and_cancel),
             MR_TEST_ENTRY(search_on_a_subsample), MR_TEST_ENTRY(timing))
