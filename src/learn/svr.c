/*
 * svr.c — epsilon-SVR with RBF kernels: training through libsvm with a grid then a compass search of the
 * hyper-parameters, and our own prediction (contract in svr.h).
 */
#include "learn/svr.h"

#include <libsvm/svm.h>
#include <limits.h>
#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "cxx_module.h"
#include "mr_internal.h"

#ifdef _OPENMP
#include <omp.h>
#endif

/* ---- the model ---------------------------------------------------------------------------------------------- */

static size_t round_up(size_t bytes) {
    const size_t a = _Alignof(max_align_t);
    return (bytes + a - 1) / a * a;
}

mr_status mr_svr_alloc(int n_in, int n_out, const int *sv_counts, mr_svr **out) {
    if (out == NULL || sv_counts == NULL) return mr_fail(MR_ERR_INVALID_ARG, "svr alloc: NULL argument");
    if (n_in < 1 || n_in > MR_SVR_MAX_IO || n_out < 1 || n_out > MR_SVR_MAX_IO)
        return mr_fail(MR_ERR_INVALID_ARG, "svr alloc: %d inputs, %d outputs (expected 1 to %d each)", n_in, n_out,
                       MR_SVR_MAX_IO);
    size_t doubles = 2 * (size_t)n_in + 2 * (size_t)n_out;
    for (int k = 0; k < n_out; k++) {
        if (sv_counts[k] < 0 || sv_counts[k] > MR_SVR_MAX_ROWS)
            return mr_fail(MR_ERR_INVALID_ARG, "svr alloc: output %d: %d support vectors (expected 0 to %d)", k,
                           sv_counts[k], MR_SVR_MAX_ROWS);
        doubles += (size_t)sv_counts[k] * ((size_t)n_in + 1); // below 2^20 * 1025 * 1024 doubles: no overflow
    }
    const size_t head = round_up(sizeof(mr_svr)), table = round_up((size_t)n_out * sizeof(mr_svr_output));
    if (doubles > (SIZE_MAX - head - table) / sizeof(double))
        return mr_fail(MR_ERR_NOMEM, "svr alloc: %zu doubles do not fit in memory", doubles);
    unsigned char *block = malloc(head + table + doubles * sizeof(double));
    if (block == NULL) return mr_fail(MR_ERR_NOMEM, "svr alloc: out of memory for %zu doubles", doubles);
    mr_svr *m = (mr_svr *)block;
    m->n_in = n_in;
    m->n_out = n_out;
    m->outputs = (mr_svr_output *)(block + head);
    double *d = (double *)(block + head + table);
    memset(d, 0, doubles * sizeof(double));
    m->in_mean = d;
    m->in_std = d + n_in;
    m->out_mean = d + 2 * n_in;
    m->out_std = d + 2 * n_in + n_out;
    for (int i = 0; i < n_in; i++) m->in_std[i] = 1.0;
    for (int k = 0; k < n_out; k++) m->out_std[k] = 1.0;
    d += 2 * (size_t)n_in + 2 * (size_t)n_out;
    for (int k = 0; k < n_out; k++) {
        mr_svr_output *o = &m->outputs[k];
        memset(o, 0, sizeof *o);
        o->sv_count = sv_counts[k];
        o->sv = d;
        d += (size_t)sv_counts[k] * (size_t)n_in;
        o->coef = d;
        d += sv_counts[k];
        o->gamma = 1.0;
    }
    *out = m;
    return MR_OK;
}

void mr_svr_free(mr_svr *m) { free(m); }

/* The shape: sizes in range and no NULL array. */
static mr_status check_shape(const char *what, const mr_svr *m) {
    if (m == NULL) return mr_fail(MR_ERR_INVALID_ARG, "%s: NULL model", what);
    if (m->n_in < 1 || m->n_in > MR_SVR_MAX_IO || m->n_out < 1 || m->n_out > MR_SVR_MAX_IO)
        return mr_fail(MR_ERR_INVALID_ARG, "%s: %d inputs, %d outputs (expected 1 to %d each)", what, m->n_in,
                       m->n_out, MR_SVR_MAX_IO);
    if (m->in_mean == NULL || m->in_std == NULL || m->out_mean == NULL || m->out_std == NULL || m->outputs == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "%s: model with a NULL array", what);
    for (int k = 0; k < m->n_out; k++) {
        const mr_svr_output *o = &m->outputs[k];
        if (o->sv_count < 0 || o->sv_count > MR_SVR_MAX_ROWS)
            return mr_fail(MR_ERR_INVALID_ARG, "%s: output %d: %d support vectors (expected 0 to %d)", what, k,
                           o->sv_count, MR_SVR_MAX_ROWS);
        if (o->sv_count > 0 && (o->sv == NULL || o->coef == NULL))
            return mr_fail(MR_ERR_INVALID_ARG, "%s: output %d: NULL support vectors or coefficients", what, k);
    }
    return MR_OK;
}

/* MR_ERR_INVALID_ARG naming the first non-finite value of v[0 .. count - 1] (or one not above 0 if positive). */
static mr_status check_values(const char *field, int k, const double *v, size_t count, int positive) {
    for (size_t i = 0; i < count; i++) {
        if (!isfinite(v[i]) || (positive && !(v[i] > 0.0))) {
            if (k >= 0)
                return mr_fail(MR_ERR_INVALID_ARG, "svr: output %d: %s[%zu] = %g (expected %s)", k, field, i, v[i],
                               positive ? "finite and > 0" : "finite");
            return mr_fail(MR_ERR_INVALID_ARG, "svr: %s[%zu] = %g (expected %s)", field, i, v[i],
                           positive ? "finite and > 0" : "finite");
        }
    }
    return MR_OK;
}

mr_status mr_svr_check(const mr_svr *m) {
    mr_status s = check_shape("svr", m);
    if (s == MR_OK) s = check_values("in_mean", -1, m->in_mean, (size_t)m->n_in, 0);
    if (s == MR_OK) s = check_values("in_std", -1, m->in_std, (size_t)m->n_in, 1);
    if (s == MR_OK) s = check_values("out_mean", -1, m->out_mean, (size_t)m->n_out, 0);
    if (s == MR_OK) s = check_values("out_std", -1, m->out_std, (size_t)m->n_out, 1);
    for (int k = 0; s == MR_OK && k < m->n_out; k++) {
        const mr_svr_output *o = &m->outputs[k];
        const double record[5] = {o->rho, o->C, o->epsilon, o->validation_rmse, o->grid_rmse};
        s = check_values("sv", k, o->sv, (size_t)o->sv_count * (size_t)m->n_in, 0);
        if (s == MR_OK) s = check_values("coef", k, o->coef, (size_t)o->sv_count, 0);
        if (s == MR_OK) s = check_values("gamma", k, &o->gamma, 1, 1);
        if (s == MR_OK) s = check_values("rho, C, epsilon, validation_rmse, grid_rmse", k, record, 5, 0);
    }
    return s;
}

double mr_svr_far_field(const mr_svr *m, int k) { return m->out_mean[k] - m->out_std[k] * m->outputs[k].rho; }

/* ---- prediction --------------------------------------------------------------------------------------------- */

/* Rows go in vector lanes, as in nn/mlp.c: a block of LANES rows is normalised and transposed into u[n_in][LANES],
 * then for each support vector the squared distances of the block's rows are summed over the inputs (the support
 * vector's value broadcast) and each kernel term is added into the rows' sums. Every inner loop runs over the
 * block's rows, a compile-time constant, so GCC vectorises it, and each row's arithmetic is the order of svr.h, the
 * same bits in any lane, block or thread. glibc's exp() is a scalar call that would take most of the time (about
 * 25 ns a term where the whole vectorised term costs a few), so the kernel uses exp_nonpositive below: plain
 * arithmetic that vectorises, within 1 ulp of exp. On x86-64 Linux with GCC the block loop is also compiled for
 * x86-64-v3 (AVX2) and chosen at run time (target_clones); no variant fuses a multiply and an add (ISO C mode:
 * -ffp-contract=off), so all give the same bits. */
#define LANES 8

#if defined(__GNUC__) && !defined(__clang__) && __GNUC__ >= 12 && defined(__x86_64__) && defined(__linux__)
#define SVR_CLONES __attribute__((target_clones("arch=x86-64-v3", "default")))
#else
#define SVR_CLONES
#endif

/* e^x[l] for each lane, x[l] <= 0, into e[l]: 0 from -708 down (where e^x < 2^-1021 and every kernel term is
 * negligible) and for NaN (a NaN row is flagged apart). Cody and Waite's reduction x = n ln2 + r, |r| <= ln2 / 2,
 * with ln2 split in a high part exact in n ln2 (fdlibm's) and a low part; e^r by its Taylor series to degree 13
 * (the next term is below 5e-18 of it); 2^n built in the exponent bits. Measured against glibc over (-708, 0]:
 * within 1 ulp. Three loops without branches, as GCC vectorises them at -O2 (one loop with the selects is not). */
static MR_ALWAYS_INLINE void exp_lanes(const double *restrict x, double *restrict e) {
    const double lo = -708.0, shifter = 0x1.8p52; /* t = x log2(e) + 1.5 2^52 holds round(x log2 e) in its bits */
    double xc[LANES];
    for (int l = 0; l < LANES; l++) xc[l] = x[l] > lo ? x[l] : lo;
    for (int l = 0; l < LANES; l++) {
        const double t = xc[l] * 0x1.71547652b82fep0 + shifter;
        const double n = t - shifter;
        const double r = (xc[l] - n * 0x1.62e42feep-1) - n * 0x1.a39ef35793c76p-33;
        double p = 1.0 / 6227020800.0; // 1/13!
        p = p * r + 1.0 / 479001600.0;
        p = p * r + 1.0 / 39916800.0;
        p = p * r + 1.0 / 3628800.0;
        p = p * r + 1.0 / 362880.0;
        p = p * r + 1.0 / 40320.0;
        p = p * r + 1.0 / 5040.0;
        p = p * r + 1.0 / 720.0;
        p = p * r + 1.0 / 120.0;
        p = p * r + 1.0 / 24.0;
        p = p * r + 1.0 / 6.0;
        p = p * r + 0.5;
        p = p * r + 1.0;
        p = p * r + 1.0;
        uint64_t bits;
        memcpy(&bits, &t, sizeof bits);
        bits = (bits + 1023) << 52; // n + 1023 in the exponent field (n >= -1022 here)
        double scale;
        memcpy(&scale, &bits, sizeof scale);
        e[l] = p * scale;
    }
    for (int l = 0; l < LANES; l++) e[l] = xc[l] > lo ? e[l] : 0.0;
}

/* One block: u[n_in][LANES] normalised inputs in, acc[n_out][LANES] normalised outputs out. */
SVR_CLONES
static void predict_block(const mr_svr *m, const double *restrict u, double *restrict acc) {
    const int n_in = m->n_in;
    for (int k = 0; k < m->n_out; k++) {
        const mr_svr_output *o = &m->outputs[k];
        const double neg_gamma = -o->gamma;
        const double *restrict sv = o->sv;
        double sum[LANES] = {0.0};
        for (int s = 0; s < o->sv_count; s++, sv += n_in) {
            double d2[LANES] = {0.0}, x[LANES], e[LANES];
            for (int i = 0; i < n_in; i++) {
                const double c = sv[i];
                for (int l = 0; l < LANES; l++) {
                    const double d = u[i * LANES + l] - c;
                    d2[l] += d * d;
                }
            }
            for (int l = 0; l < LANES; l++) x[l] = neg_gamma * d2[l];
            exp_lanes(x, e);
            const double coef = o->coef[s];
            for (int l = 0; l < LANES; l++) sum[l] += coef * e[l];
        }
        for (int l = 0; l < LANES; l++) acc[k * LANES + l] = sum[l] - o->rho;
    }
}

/* Rows [first, first + count) of `in` (count <= LANES) to `out`; ws holds (n_in + n_out) LANES doubles. A partial
 * block repeats its last row in the spare lanes. */
static void predict_rows(const mr_svr *m, const double *in, size_t first, int count, double *out, double *ws) {
    const size_t n_in = (size_t)m->n_in, n_out = (size_t)m->n_out;
    double *u = ws, *acc = ws + n_in * LANES;
    int nan[LANES];
    for (int l = 0; l < LANES; l++) {
        const double *x = in + (first + (size_t)(l < count ? l : count - 1)) * n_in;
        nan[l] = 0;
        for (size_t i = 0; i < n_in; i++) {
            u[i * LANES + (size_t)l] = (x[i] - m->in_mean[i]) / m->in_std[i];
            nan[l] |= isnan(u[i * LANES + (size_t)l]);
        }
    }
    predict_block(m, u, acc);
    for (int l = 0; l < count; l++)
        for (size_t k = 0; k < n_out; k++)
            out[(first + (size_t)l) * n_out + k] =
                nan[l] ? NAN : m->out_mean[k] + m->out_std[k] * acc[k * LANES + (size_t)l];
}

mr_status mr_svr_predict(const mr_svr *m, const double *in, size_t count, double *out) {
    return mr_svr_predict_threads(m, in, count, out, 0);
}

mr_status mr_svr_predict_threads(const mr_svr *m, const double *in, size_t count, double *out, int max_team) {
    mr_status status = check_shape("svr predict", m);
    if (status != MR_OK) return status;
    if (count == 0) return MR_OK;
    if (in == NULL || out == NULL) return mr_fail(MR_ERR_INVALID_ARG, "svr predict: NULL input or output array");
    if (count > SIZE_MAX / sizeof(double) / (size_t)MR_MAX(m->n_in, m->n_out))
        return mr_fail(MR_ERR_INVALID_ARG, "svr predict: %zu rows overflow size_t", count);
#ifdef _OPENMP
    // The automatic rule (mr_auto_threads): a team from two blocks of rows on, capped below.
    int threads = mr_auto_threads(max_team, (long)MR_MIN(count, (size_t)LONG_MAX), 2 * MR_SVR_PREDICT_ROWS);
#else
    int threads = 1;
    (void)max_team;
#endif
    // A thread per MR_SVR_PREDICT_ROWS rows at most: for fewer, starting a team costs more than it saves.
    if ((size_t)threads > count / MR_SVR_PREDICT_ROWS) threads = (int)(count / MR_SVR_PREDICT_ROWS);
    if (threads < 1) threads = 1;
    const size_t per_thread = ((size_t)m->n_in + (size_t)m->n_out) * LANES;
    double *ws = malloc((size_t)threads * per_thread * sizeof(double));
    if (ws == NULL) return mr_fail(MR_ERR_NOMEM, "svr predict: out of memory for the workspace");
    const long blocks = (long)((count + LANES - 1) / LANES);
#pragma omp parallel num_threads(threads) if (threads > 1)
    {
#ifdef _OPENMP
        double *mine = ws + (size_t)omp_get_thread_num() * per_thread;
#else
        double *mine = ws;
#endif
#pragma omp for schedule(static)
        for (long b = 0; b < blocks; b++) {
            const size_t first = (size_t)b * LANES;
            predict_rows(m, in, first, (int)MR_MIN((size_t)LANES, count - first), out, mine);
        }
    }
    free(ws);
    return MR_OK;
}

/* ---- training: data ----------------------------------------------------------------------------------------- */

enum { AXIS_C, AXIS_GAMMA, AXIS_EPSILON, AXES };

/* The search space per axis, in log units of `base` (svr.h): the grid lo, lo + spacing, ..., hi; the local
 * search's first step is half the spacing and its box the grid widened by one spacing. */
static const struct axis {
    const char *name;
    double base, lo, hi, spacing;
} axes[AXES] = {
    {"C", 2.0, -2.0, 12.0, 2.0},
    {"gamma", 2.0, -8.0, 4.0, 2.0},
    {"epsilon", 10.0, -4.0, -1.0, 1.0},
};

/* Grid cells are numbered with C varying fastest, then epsilon, then gamma: a run of C values is a line. */
static const int cell_axes[AXES] = {AXIS_GAMMA, AXIS_EPSILON, AXIS_C}; /* slowest first */

#define LIBSVM_TOLERANCE 1e-3 /* libsvm's stopping tolerance (its -e), its default */
#define FINAL_SCALE 0.25      /* the local search stops when its step falls below this share of the first */
#define LINE_GROWTH 4         /* iterations grow about as C when coefficients sit at the bound: 4x a grid step */

enum { ROWS_SEARCH, ROWS_TRAIN, ROWS_ALL }; /* which rows a fit uses */

typedef struct trainer {
    int n_in, n_out, threads;
    size_t n, n_val, n_train, n_search;
    long cap;                  /* iterations above which a search fit is too costly (svr.h) */
    size_t *order;             /* [n]: the validation rows, then the training rows */
    struct svm_node *nodes;    /* [n][n_in + 1]: row r's normalised inputs, indices 1..n_in, then index -1 */
    struct svm_node **x_train; /* [n_train] rows of the training split (the search's are the first n_search) */
    struct svm_node **x_all;   /* [n] every row in its order */
    double *v;                 /* [n][n_out] normalised outputs */
    double *y_train;           /* [n_out][n_train] */
    double *y_all;             /* [n_out][n] */
    double *in_mean, *in_std, *out_mean, *out_std;
    int fixed[AXES];           /* 1: the axis is the option's value, not searched */
    double fixed_value[AXES];
    const mr_svr_train_options *opt;
    const mr_cxx_table *svm;   /* libsvm's functions (cxx_module.h: in the C++ module, loaded on first use) */
    double start;              /* mr_now_seconds() at the call */
} trainer;

enum { JOB_FITTED, JOB_COPIED, JOB_SKIPPED }; /* how a job got its score */

/* One candidate of one output: log coordinates t (unused on fixed axes) and its validation score. */
typedef struct job {
    int output;
    double t[AXES];
    double rmse;         /* normalised units; +inf for a failed or too costly fit */
    long iterations;     /* libsvm's iterations for the fit */
    int at_bound;        /* some coefficient reached C */
    int how;             /* JOB_* */
    const char *refused; /* svm_check_parameter's message, or NULL */
} job;

/* libsvm reports through its print function only; the iteration count comes at the end of each fit as
 * "optimization finished, #iter = N". Fits run whole on one thread, so a thread-local count is the fit's. */
static _Thread_local long fit_iterations;

static void libsvm_print(const char *s) {
    const char *p = strstr(s, "#iter = ");
    if (p != NULL) fit_iterations = strtol(p + 8, NULL, 10);
}

/* libsvm's print function is one process-wide pointer: set once, before any of our fits. */
static pthread_once_t libsvm_print_once = PTHREAD_ONCE_INIT;

static void set_libsvm_print(void) {
    const mr_cxx_table *svm;
    if (mr_cxx_svm("svr train", &svm) == MR_OK) svm->svm_set_print_string_function(libsvm_print);
}

/* Mean and population deviation of column `col` of the `stride`-wide rows rows[0 .. count - 1], in row order;
 * deviation 1 for a (near) constant column (svr.h). */
static void column_stats(const double *data, size_t stride, size_t col, const size_t *rows, size_t count,
                         double *mean_out, double *std_out) {
    double sum = 0.0;
    for (size_t i = 0; i < count; i++) sum += data[rows[i] * stride + col];
    const double mean = sum / (double)count;
    double ss = 0.0;
    for (size_t i = 0; i < count; i++) {
        const double d = data[rows[i] * stride + col] - mean;
        ss += d * d;
    }
    const double sd = sqrt(ss / (double)count);
    *mean_out = mean;
    *std_out = sd > 1e-12 * MR_MAX(1.0, fabs(mean)) ? sd : 1.0;
}

static mr_status check_options(const mr_svr_train_options *o) {
    if (!(o->validation_fraction >= 0.0 && o->validation_fraction < 1.0))
        return mr_fail(MR_ERR_INVALID_ARG, "svr train: validation_fraction %g (expected 0 <= f < 1; 0 = %g)",
                       o->validation_fraction, MR_SVR_DEFAULT_VALIDATION);
    if (o->threads < 0) return mr_fail(MR_ERR_INVALID_ARG, "svr train: %d threads (expected >= 0)", o->threads);
    if (o->search_rows < 0)
        return mr_fail(MR_ERR_INVALID_ARG, "svr train: search_rows %d (expected >= 0; 0 = %d)", o->search_rows,
                       MR_SVR_SEARCH_ROWS);
    const double fixed[AXES] = {o->C, o->gamma, o->epsilon};
    for (int a = 0; a < AXES; a++)
        if (!(fixed[a] >= 0.0 && isfinite(fixed[a])))
            return mr_fail(MR_ERR_INVALID_ARG, "svr train: %s %g (expected finite and > 0, or 0 = search)",
                           axes[a].name, fixed[a]);
    return MR_OK;
}

static mr_status check_data(const double *x, const double *y, size_t n, int n_in, int n_out) {
    for (size_t r = 0; r < n; r++) {
        for (int i = 0; i < n_in; i++)
            if (!isfinite(x[r * (size_t)n_in + (size_t)i]))
                return mr_fail(MR_ERR_INVALID_ARG, "svr train: input row %zu column %d is %g (expected finite)", r,
                               i, x[r * (size_t)n_in + (size_t)i]);
        for (int k = 0; k < n_out; k++)
            if (!isfinite(y[r * (size_t)n_out + (size_t)k]))
                return mr_fail(MR_ERR_INVALID_ARG, "svr train: output row %zu column %d is %g (expected finite)", r,
                               k, y[r * (size_t)n_out + (size_t)k]);
    }
    return MR_OK;
}

static void trainer_free(trainer *t) {
    free(t->order);
    free(t->nodes);
    free(t->x_train);
    free(t->x_all);
    free(t->v);
    free(t->y_train);
    free(t->y_all);
    free(t->in_mean);
}

/* Split, normalise, and lay the rows out for libsvm. */
static mr_status trainer_init(trainer *t, const double *x, const double *y) {
    const size_t n = t->n, I = (size_t)t->n_in, O = (size_t)t->n_out;
    t->order = malloc(n * sizeof *t->order);
    t->nodes = malloc(n * (I + 1) * sizeof *t->nodes);
    t->x_train = malloc(n * sizeof *t->x_train);
    t->x_all = malloc(n * sizeof *t->x_all);
    t->v = malloc(n * O * sizeof *t->v);
    t->y_train = malloc(n * O * sizeof *t->y_train);
    t->y_all = malloc(n * O * sizeof *t->y_all);
    t->in_mean = malloc(2 * (I + O) * sizeof *t->in_mean);
    if (t->order == NULL || t->nodes == NULL || t->x_train == NULL || t->x_all == NULL || t->v == NULL ||
        t->y_train == NULL || t->y_all == NULL || t->in_mean == NULL)
        return mr_fail(MR_ERR_NOMEM, "svr train: out of memory (%zu rows)", n);
    t->in_std = t->in_mean + I;
    t->out_mean = t->in_std + I;
    t->out_std = t->out_mean + O;

    // Split: a Fisher-Yates shuffle (the modulo's bias, below n / 2^64, is immaterial).
    for (size_t r = 0; r < n; r++) t->order[r] = r;
    uint64_t rng = mr_rng_stream(t->opt->seed, 1);
    for (size_t i = n; i > 1; i--) {
        const size_t j = (size_t)(mr_rng_next(&rng) % (uint64_t)i), tmp = t->order[i - 1];
        t->order[i - 1] = t->order[j];
        t->order[j] = tmp;
    }
    const double fraction = t->opt->validation_fraction > 0.0 ? t->opt->validation_fraction : MR_SVR_DEFAULT_VALIDATION;
    const double wanted = floor(fraction * (double)n + 0.5);
    t->n_val = wanted < 1.0 ? 1 : wanted > (double)(n - 1) ? n - 1 : (size_t)wanted;
    t->n_train = n - t->n_val;
    const size_t search_rows = t->opt->search_rows > 0 ? (size_t)t->opt->search_rows : MR_SVR_SEARCH_ROWS;
    t->n_search = MR_MIN(t->n_train, search_rows);
    t->cap = MR_SVR_ITERATIONS_PER_ROW * (long)t->n_search + MR_SVR_ITERATIONS_MIN;
    if (t->fixed[AXIS_C] && t->fixed[AXIS_GAMMA] && t->fixed[AXIS_EPSILON]) t->cap = LONG_MAX; // nothing to choose

    // Normalisation from the training split, then the normalised rows.
    const size_t *train = t->order + t->n_val;
    for (size_t i = 0; i < I; i++) column_stats(x, I, i, train, t->n_train, &t->in_mean[i], &t->in_std[i]);
    for (size_t k = 0; k < O; k++) column_stats(y, O, k, train, t->n_train, &t->out_mean[k], &t->out_std[k]);
    for (size_t r = 0; r < n; r++) {
        struct svm_node *node = t->nodes + r * (I + 1);
        for (size_t i = 0; i < I; i++) {
            node[i].index = (int)i + 1;
            node[i].value = (x[r * I + i] - t->in_mean[i]) / t->in_std[i];
        }
        node[I].index = -1;
        node[I].value = 0.0;
        t->x_all[r] = node;
        for (size_t k = 0; k < O; k++) {
            t->v[r * O + k] = (y[r * O + k] - t->out_mean[k]) / t->out_std[k];
            t->y_all[k * n + r] = t->v[r * O + k];
        }
    }
    for (size_t i = 0; i < t->n_train; i++) {
        t->x_train[i] = t->x_all[train[i]];
        for (size_t k = 0; k < O; k++) t->y_train[k * t->n_train + i] = t->v[train[i] * O + k];
    }
    return MR_OK;
}

/* ---- training: fits ------------------------------------------------------------------------------------------ */

static void hyper_parameters(const trainer *t, const double lt[AXES], double hp[AXES]) {
    for (int a = 0; a < AXES; a++) hp[a] = t->fixed[a] ? t->fixed_value[a] : pow(axes[a].base, lt[a]);
}

/* libsvm's fit of output k with hyper-parameters hp (C, gamma, epsilon) on the rows `rows` (ROWS_*); NULL with
 * *refused set if svm_check_parameter refuses them. fit_iterations gets libsvm's iteration count. */
static struct svm_model *fit(const trainer *t, int k, const double hp[AXES], int rows, const char **refused) {
    struct svm_problem prob;
    prob.l = (int)(rows == ROWS_ALL ? t->n : rows == ROWS_TRAIN ? t->n_train : t->n_search);
    prob.y = rows == ROWS_ALL ? t->y_all + (size_t)k * t->n : t->y_train + (size_t)k * t->n_train;
    prob.x = rows == ROWS_ALL ? t->x_all : t->x_train;
    struct svm_parameter p;
    memset(&p, 0, sizeof p);
    p.svm_type = EPSILON_SVR;
    p.kernel_type = RBF;
    p.gamma = hp[AXIS_GAMMA];
    p.C = hp[AXIS_C];
    p.p = hp[AXIS_EPSILON];
    p.eps = LIBSVM_TOLERANCE;
    // Enough kernel cache for the whole l x l matrix of floats (libsvm's Qfloat), up to MR_SVR_CACHE_MB.
    const double mb = (double)prob.l * (double)prob.l * 4.0 / 1048576.0 + 1.0;
    p.cache_size = mb < MR_SVR_CACHE_MB ? mb : MR_SVR_CACHE_MB;
    p.shrinking = 1;
    p.probability = 0;
    fit_iterations = 0;
    *refused = t->svm->svm_check_parameter(&prob, &p);
    return *refused != NULL ? NULL : t->svm->svm_train(&prob, &p);
}

/* Score a job: fit on `rows`, root mean square error on the validation split (+inf if not finite). */
static void score(const trainer *t, job *j, int rows) {
    double hp[AXES];
    hyper_parameters(t, j->t, hp);
    struct svm_model *model = fit(t, j->output, hp, rows, &j->refused);
    j->how = JOB_FITTED;
    j->rmse = INFINITY;
    j->iterations = fit_iterations;
    j->at_bound = 0;
    if (model == NULL) return;
    for (int s = 0; s < model->l; s++) j->at_bound |= fabs(model->sv_coef[0][s]) >= hp[AXIS_C] * (1.0 - 1e-12);
    double sse = 0.0;
    for (size_t i = 0; i < t->n_val; i++) {
        const size_t r = t->order[i];
        const double d = t->svm->svm_predict(model, t->x_all[r]) - t->v[r * (size_t)t->n_out + (size_t)j->output];
        sse += d * d;
    }
    t->svm->svm_free_and_destroy_model(&model);
    const double rmse = sqrt(sse / (double)t->n_val);
    if (rmse < INFINITY) j->rmse = rmse; // NaN stays +inf: the worst score
}

/* Score one line of `len` search jobs, in order (the grid's C values, or one local-search poll): a fit above the
 * iteration cap scores +inf; after a fit with no coefficient at the bound C, every larger C has the same solution
 * and takes its score; after one above cap / LINE_GROWTH iterations the larger C values would cost more than the
 * cap and score +inf unfitted. */
static void score_line(const trainer *t, job *line, long len) {
    for (long i = 0; i < len; i++) {
        job *j = &line[i], *prev = i > 0 ? &line[i - 1] : NULL;
        j->refused = NULL;
        j->iterations = 0;
        j->at_bound = 0;
        if (prev != NULL && prev->how != JOB_SKIPPED && prev->rmse < INFINITY && !prev->at_bound) {
            j->how = JOB_COPIED;
            j->rmse = prev->rmse;
            j->iterations = prev->iterations; // the same solution, about the same cost
        } else if (prev != NULL && (prev->how == JOB_SKIPPED || prev->iterations > t->cap / LINE_GROWTH)) {
            j->how = JOB_SKIPPED;
            j->rmse = INFINITY;
        } else {
            score(t, j, ROWS_SEARCH);
            if (j->iterations > t->cap) j->rmse = INFINITY;
            if (j->refused != NULL) return;
        }
    }
}

/* Score `units` lines of `len` consecutive jobs on the trainer's threads, in batches between calls of the progress
 * callback (one batch without one). *done counts the phase's candidates; rep the fits made, their iterations and
 * those above the cap. MR_ERR_CANCELLED if the callback asks; MR_ERR_INVALID_ARG if libsvm refused a job's
 * hyper-parameters (a line stops at such a job, so the refusal is met before its unscored successors). */
static mr_status run_lines(const trainer *t, job *jobs, long units, long len, mr_svr_phase phase, long *done,
                           long planned, mr_svr_train_report *rep) {
    const long batch = t->opt->progress == NULL ? units : MR_MAX(8L, 4L * t->threads);
    for (long first = 0; first < units; first += batch) {
        const long last = MR_MIN(units, first + batch);
#pragma omp parallel for num_threads(t->threads) schedule(dynamic, 1) if (t->threads > 1)
        for (long u = first; u < last; u++) score_line(t, jobs + u * len, len);
        for (long i = first * len; i < last * len; i++) {
            if (jobs[i].refused != NULL) {
                double hp[AXES];
                hyper_parameters(t, jobs[i].t, hp);
                return mr_fail(MR_ERR_INVALID_ARG, "svr train: libsvm refuses C %g, gamma %g, epsilon %g: %s", hp[0],
                               hp[1], hp[2], jobs[i].refused);
            }
            if (jobs[i].how == JOB_FITTED) {
                long *fits = phase == MR_SVR_PHASE_GRID ? &rep->grid_fits : &rep->local_fits;
                (*fits)++;
                rep->iterations += jobs[i].iterations;
                rep->costly_fits += jobs[i].iterations > t->cap;
            }
        }
        *done += (last - first) * len;
        if (t->opt->progress != NULL) {
            const mr_svr_progress p = {phase, *done, planned, mr_now_seconds() - t->start};
            if (t->opt->progress(&p, t->opt->progress_user) != 0)
                return mr_fail(MR_ERR_CANCELLED, "svr train: cancelled by the progress callback");
        }
    }
    return MR_OK;
}

/* ---- training: the search ------------------------------------------------------------------------------------ */

/* Every candidate scored for one output, in the order scored (the grid first). */
typedef struct scored {
    double (*t)[AXES];
    double *rmse;
    long *iterations;
    long count, capacity;
} scored;

static int scored_add(scored *s, const job *j) {
    if (s->count == s->capacity) {
        const long cap = s->capacity > 0 ? 2 * s->capacity : 256;
        double(*nt)[AXES] = realloc(s->t, (size_t)cap * sizeof *nt);
        if (nt == NULL) return 0;
        s->t = nt;
        double *nr = realloc(s->rmse, (size_t)cap * sizeof *nr);
        if (nr == NULL) return 0;
        s->rmse = nr;
        long *ni = realloc(s->iterations, (size_t)cap * sizeof *ni);
        if (ni == NULL) return 0;
        s->iterations = ni;
        s->capacity = cap;
    }
    memcpy(s->t[s->count], j->t, sizeof s->t[0]);
    s->rmse[s->count] = j->rmse;
    s->iterations[s->count++] = j->iterations;
    return 1;
}

static int same_point(const double a[AXES], const double b[AXES]) {
    return a[0] == b[0] && a[1] == b[1] && a[2] == b[2]; // dyadic steps from integers: exact
}

/* The index of lt among s's candidates, or -1. */
static long scored_find(const scored *s, const double lt[AXES]) {
    for (long i = 0; i < s->count; i++)
        if (same_point(s->t[i], lt)) return i;
    return -1;
}

/* One compass search (svr.h). */
typedef struct search {
    int output, active;
    double center[AXES], rmse, scale;
    long iterations; /* the centre's fit's */
    int polls;
    double poll_t[2 * AXES][AXES];
    double poll_rmse[2 * AXES]; /* known already, or NAN until its job has run */
    long poll_iterations[2 * AXES];
    long poll_job[2 * AXES];    /* the job scoring it this round, or -1 */
} search;

/* Grid values on axis a (1 on a fixed axis). */
static int grid_size(const trainer *t, int a) {
    return t->fixed[a] ? 1 : (int)((axes[a].hi - axes[a].lo) / axes[a].spacing) + 1;
}

/* A grid cell's log coordinates. */
static void cell_point(const trainer *t, long cell, double lt[AXES]) {
    for (int c = AXES - 1; c >= 0; c--) {
        const int a = cell_axes[c], size = grid_size(t, a);
        lt[a] = t->fixed[a] ? 0.0 : axes[a].lo + axes[a].spacing * (double)(cell % size);
        cell /= size;
    }
}

/* Whether grid cell `cell` of an output (scores rmse[0 .. cells - 1]) is below its axial neighbours, ties broken
 * by the cell's index. */
static int grid_local_min(const trainer *t, const double *rmse, long cell) {
    long stride = 1;
    for (int c = AXES - 1; c >= 0; c--) {
        const int size = grid_size(t, cell_axes[c]);
        const long pos = cell / stride % size;
        for (int dir = -1; dir <= 1; dir += 2) {
            if (pos + dir < 0 || pos + dir >= size) continue;
            const long other = cell + dir * stride;
            if (rmse[other] < rmse[cell] || (rmse[other] == rmse[cell] && other < cell)) return 0;
        }
        stride *= size;
    }
    return 1;
}

/* Up to MR_SVR_STARTS searches from the grid cells of output k (scores rmse[0 .. cells - 1]) that are below their
 * neighbours, best first (the grid's best is one of them). Returns how many were added at searches[0 ..]. */
static int plan_starts(const trainer *t, int k, const double *rmse, const job *cells_jobs, long cells,
                       search *searches) {
    long chosen[MR_SVR_STARTS];
    int starts = 0;
    while (starts < MR_SVR_STARTS && cells > 1) {
        long pick = -1;
        for (long c = 0; c < cells; c++) {
            int taken = 0;
            for (int s = 0; s < starts; s++) taken |= chosen[s] == c;
            if (!taken && rmse[c] < INFINITY && (pick < 0 || rmse[c] < rmse[pick]) && grid_local_min(t, rmse, c))
                pick = c;
        }
        if (pick < 0) break;
        search *se = &searches[starts];
        memset(se, 0, sizeof *se);
        se->output = k;
        se->active = 1;
        memcpy(se->center, cells_jobs[pick].t, sizeof se->center);
        se->rmse = rmse[pick];
        se->iterations = cells_jobs[pick].iterations;
        se->scale = 1.0;
        chosen[starts++] = pick;
    }
    return starts;
}

/* Poll every active search's neighbours; new points become jobs (one per distinct point and output). A neighbour
 * in a costlier direction (a larger C or gamma, a smaller epsilon: libsvm needs more iterations there) of a centre
 * whose fit took over half the cap is not polled: it would most likely cost more than the cap and score +inf. */
static long plan_round(const trainer *t, search *searches, int count, const scored *done, job *jobs) {
    long n_jobs = 0;
    for (int si = 0; si < count; si++) {
        search *s = &searches[si];
        s->polls = 0;
        if (!s->active) continue;
        for (int a = 0; a < AXES; a++) {
            if (t->fixed[a]) continue;
            for (int dir = -1; dir <= 1; dir += 2) {
                double p[AXES];
                memcpy(p, s->center, sizeof p);
                p[a] += dir * 0.5 * axes[a].spacing * s->scale;
                if (p[a] < axes[a].lo - axes[a].spacing || p[a] > axes[a].hi + axes[a].spacing) continue;
                const int costlier = a == AXIS_EPSILON ? dir < 0 : dir > 0;
                if (costlier && s->iterations > t->cap / 2) continue;
                const int q = s->polls++;
                memcpy(s->poll_t[q], p, sizeof p);
                s->poll_job[q] = -1;
                s->poll_rmse[q] = NAN;
                const long known = scored_find(&done[s->output], p);
                if (known >= 0) {
                    s->poll_rmse[q] = done[s->output].rmse[known];
                    s->poll_iterations[q] = done[s->output].iterations[known];
                    continue;
                }
                for (long j = 0; j < n_jobs && s->poll_job[q] < 0; j++)
                    if (jobs[j].output == s->output && same_point(jobs[j].t, p)) s->poll_job[q] = j;
                if (s->poll_job[q] >= 0) continue;
                memset(&jobs[n_jobs], 0, sizeof jobs[n_jobs]);
                jobs[n_jobs].output = s->output;
                memcpy(jobs[n_jobs].t, p, sizeof p);
                s->poll_job[q] = n_jobs++;
            }
        }
    }
    return n_jobs;
}

/* Move or shrink every active search after its polls are scored; retire searches that end or that another one
 * of the same output (earlier in the list) has joined. */
static void finish_round(search *searches, int count, const job *jobs) {
    for (int si = 0; si < count; si++) {
        search *s = &searches[si];
        if (!s->active) continue;
        int best = -1;
        for (int q = 0; q < s->polls; q++) {
            if (s->poll_job[q] >= 0) {
                s->poll_rmse[q] = jobs[s->poll_job[q]].rmse;
                s->poll_iterations[q] = jobs[s->poll_job[q]].iterations;
            }
            if (best < 0 || s->poll_rmse[q] < s->poll_rmse[best]) best = q;
        }
        if (best >= 0 && s->poll_rmse[best] < s->rmse) {
            memcpy(s->center, s->poll_t[best], sizeof s->center);
            s->rmse = s->poll_rmse[best];
            s->iterations = s->poll_iterations[best];
        } else {
            s->scale *= 0.5;
            if (s->scale < FINAL_SCALE) s->active = 0;
        }
        for (int other = 0; other < si && s->active; other++) {
            const search *o = &searches[other];
            if (o->active && o->output == s->output && o->scale == s->scale && same_point(o->center, s->center))
                s->active = 0;
        }
    }
}

/* The grid, then the local search, for every output; best[k] gets the chosen point's index in done[k], grid_best[k]
 * the grid's best cell's. */
static mr_status run_search(const trainer *t, scored *done, long *best, long *grid_best, mr_svr_train_report *rep) {
    const int O = t->n_out;
    long cells = 1;
    for (int a = 0; a < AXES; a++) cells *= grid_size(t, a);
    const long line = grid_size(t, AXIS_C), grid_jobs = cells * O;
    const long capacity = MR_MAX(grid_jobs, (long)O * MR_SVR_STARTS * 2 * AXES);
    job *jobs = calloc((size_t)capacity, sizeof *jobs);
    search *searches = malloc((size_t)O * MR_SVR_STARTS * sizeof *searches);
    double *rmse = malloc((size_t)cells * sizeof *rmse);
    mr_status status = MR_OK;
    if (jobs == NULL || searches == NULL || rmse == NULL)
        status = mr_fail(MR_ERR_NOMEM, "svr train: out of memory for the search");
    for (long j = 0; j < grid_jobs && status == MR_OK; j++) {
        jobs[j].output = (int)(j / cells);
        cell_point(t, j % cells, jobs[j].t);
    }
    long candidates = 0;
    if (status == MR_OK)
        status = run_lines(t, jobs, grid_jobs / line, line, MR_SVR_PHASE_GRID, &candidates, grid_jobs, rep);
    int n_search = 0;
    for (int k = 0; k < O && status == MR_OK; k++) {
        const job *g = jobs + (long)k * cells;
        grid_best[k] = 0;
        for (long c = 0; c < cells; c++) {
            rmse[c] = g[c].rmse;
            if (rmse[c] < rmse[grid_best[k]]) grid_best[k] = c;
            if (!scored_add(&done[k], &g[c])) status = mr_fail(MR_ERR_NOMEM, "svr train: out of memory");
        }
        n_search += plan_starts(t, k, rmse, g, cells, searches + n_search);
    }

    // The local search, in rounds: the polls of every active search are scored together.
    candidates = 0;
    for (int round = 0; round < MR_SVR_MAX_ROUNDS && status == MR_OK; round++) {
        int active = 0;
        for (int s = 0; s < n_search; s++) active |= searches[s].active;
        if (!active) break;
        const long n_jobs = plan_round(t, searches, n_search, done, jobs);
        status = run_lines(t, jobs, n_jobs, 1, MR_SVR_PHASE_LOCAL, &candidates, candidates + n_jobs, rep);
        for (long j = 0; j < n_jobs && status == MR_OK; j++)
            if (!scored_add(&done[jobs[j].output], &jobs[j]))
                status = mr_fail(MR_ERR_NOMEM, "svr train: out of memory");
        finish_round(searches, n_search, jobs);
        rep->local_rounds = round + 1;
    }
    for (int k = 0; k < O && status == MR_OK; k++) {
        best[k] = 0;
        for (long i = 1; i < done[k].count; i++)
            if (done[k].rmse[i] < done[k].rmse[best[k]]) best[k] = i;
        if (!(done[k].rmse[best[k]] < INFINITY))
            status = mr_fail(MR_ERR_NUMERIC, "svr train: output %d: no candidate gives a finite validation error", k);
    }
    free(jobs);
    free(searches);
    free(rmse);
    return status;
}

/* ---- training: the entry point --------------------------------------------------------------------------------- */

/* After the search: output k's validation score on the whole training split (when the search used part of it),
 * then its fit on all rows. */
static void final_fit(const trainer *t, job *j, struct svm_model **model) {
    if (t->n_search < t->n_train) {
        score(t, j, ROWS_TRAIN);
        if (j->refused != NULL) return;
    }
    double hp[AXES];
    hyper_parameters(t, j->t, hp);
    *model = fit(t, j->output, hp, ROWS_ALL, &j->refused);
}

/* Copy libsvm's fits (models[k] for output k) into a new plain model. */
static mr_status copy_models(const trainer *t, const job *chosen, const double *grid_rmse,
                             struct svm_model *const *models, mr_svr **out) {
    const int n_in = t->n_in, n_out = t->n_out;
    int *sv_counts = malloc((size_t)n_out * sizeof *sv_counts);
    if (sv_counts == NULL) return mr_fail(MR_ERR_NOMEM, "svr train: out of memory");
    for (int k = 0; k < n_out; k++) sv_counts[k] = models[k]->l;
    mr_svr *m = NULL;
    mr_status status = mr_svr_alloc(n_in, n_out, sv_counts, &m);
    free(sv_counts);
    if (status != MR_OK) return status;
    memcpy(m->in_mean, t->in_mean, (size_t)n_in * sizeof(double));
    memcpy(m->in_std, t->in_std, (size_t)n_in * sizeof(double));
    memcpy(m->out_mean, t->out_mean, (size_t)n_out * sizeof(double));
    memcpy(m->out_std, t->out_std, (size_t)n_out * sizeof(double));
    for (int k = 0; k < n_out; k++) {
        mr_svr_output *mo = &m->outputs[k];
        const struct svm_model *sm = models[k];
        for (int s = 0; s < sm->l; s++) {
            for (const struct svm_node *node = sm->SV[s]; node->index != -1; node++)
                if (node->index >= 1 && node->index <= n_in)
                    mo->sv[(size_t)s * (size_t)n_in + (size_t)(node->index - 1)] = node->value;
            mo->coef[s] = sm->sv_coef[0][s];
        }
        double hp[AXES];
        hyper_parameters(t, chosen[k].t, hp);
        mo->rho = sm->rho[0];
        mo->gamma = hp[AXIS_GAMMA];
        mo->C = hp[AXIS_C];
        mo->epsilon = hp[AXIS_EPSILON];
        mo->validation_rmse = t->out_std[k] * chosen[k].rmse;
        mo->grid_rmse = t->out_std[k] * grid_rmse[k];
    }
    *out = m;
    return MR_OK;
}

mr_status mr_svr_train(const double *x, const double *y, size_t n, int n_in, int n_out,
                       const mr_svr_train_options *opts, mr_svr **out, mr_svr_train_report *report) {
    const mr_svr_train_options defaults = {0};
    const mr_svr_train_options *o = opts != NULL ? opts : &defaults;
    if (x == NULL || y == NULL || out == NULL) return mr_fail(MR_ERR_INVALID_ARG, "svr train: NULL argument");
    if (n_in < 1 || n_in > MR_SVR_MAX_IO || n_out < 1 || n_out > MR_SVR_MAX_IO)
        return mr_fail(MR_ERR_INVALID_ARG, "svr train: %d inputs, %d outputs (expected 1 to %d each)", n_in, n_out,
                       MR_SVR_MAX_IO);
    if (n < 2 || n > MR_SVR_MAX_ROWS)
        return mr_fail(MR_ERR_INVALID_ARG, "svr train: %zu rows (expected 2 to %d)", n, MR_SVR_MAX_ROWS);
    mr_status status = check_options(o);
    if (status == MR_OK) status = check_data(x, y, n, n_in, n_out);
    if (status != MR_OK) return status;

    trainer t;
    memset(&t, 0, sizeof t);
    status = mr_cxx_svm("svr train", &t.svm);
    if (status != MR_OK) return status;
    t.n_in = n_in;
    t.n_out = n_out;
    t.n = n;
    t.opt = o;
    t.start = mr_now_seconds();
    // The automatic thread rule (mr_auto_threads) over the rows; any training set reaches the threshold: the
    // search fits up to ~200 candidates per output, which a team shares.
#ifdef _OPENMP
    t.threads = mr_auto_threads(o->threads, (long)n, 2);
#else
    t.threads = 1;
#endif
    const double fixed[AXES] = {o->C, o->gamma, o->epsilon};
    for (int a = 0; a < AXES; a++) {
        t.fixed[a] = fixed[a] > 0.0;
        t.fixed_value[a] = fixed[a];
    }
    pthread_once(&libsvm_print_once, set_libsvm_print); // libsvm's solver reports on stdout otherwise

    mr_svr_train_report rep;
    memset(&rep, 0, sizeof rep);
    scored *done = calloc((size_t)n_out, sizeof *done);
    long *best = malloc(2 * (size_t)n_out * sizeof *best);
    double *grid_rmse = malloc((size_t)n_out * sizeof *grid_rmse);
    struct svm_model **models = calloc((size_t)n_out, sizeof *models);
    job *chosen = calloc((size_t)n_out, sizeof *chosen);
    if (done == NULL || best == NULL || grid_rmse == NULL || models == NULL || chosen == NULL)
        status = mr_fail(MR_ERR_NOMEM, "svr train: out of memory");
    if (status == MR_OK) status = trainer_init(&t, x, y);
    if (status == MR_OK) status = run_search(&t, done, best, best + n_out, &rep);
    if (status == MR_OK) {
        for (int k = 0; k < n_out; k++) {
            chosen[k].output = k;
            memcpy(chosen[k].t, done[k].t[best[k]], sizeof chosen[k].t);
            chosen[k].rmse = done[k].rmse[best[k]];
            grid_rmse[k] = done[k].rmse[best[n_out + k]];
        }
        if (o->progress != NULL) {
            const mr_svr_progress p = {MR_SVR_PHASE_REFIT, 0, n_out, mr_now_seconds() - t.start};
            if (o->progress(&p, o->progress_user) != 0)
                status = mr_fail(MR_ERR_CANCELLED, "svr train: cancelled by the progress callback");
        }
    }
    if (status == MR_OK) {
#pragma omp parallel for num_threads(t.threads) schedule(dynamic, 1) if (t.threads > 1)
        for (int k = 0; k < n_out; k++) final_fit(&t, &chosen[k], &models[k]);
        for (int k = 0; k < n_out && status == MR_OK; k++)
            if (models[k] == NULL)
                status = mr_fail(MR_ERR_INVALID_ARG, "svr train: libsvm refuses output %d's final fit: %s", k,
                                 chosen[k].refused != NULL ? chosen[k].refused : "no model");
    }
    mr_svr *m = NULL;
    if (status == MR_OK) status = copy_models(&t, chosen, grid_rmse, models, &m);
    if (models != NULL)
        for (int k = 0; k < n_out; k++)
            if (models[k] != NULL) t.svm->svm_free_and_destroy_model(&models[k]);
    if (done != NULL)
        for (int k = 0; k < n_out; k++) {
            free(done[k].t);
            free(done[k].rmse);
            free(done[k].iterations);
        }
    free(done);
    free(best);
    free(grid_rmse);
    free(models);
    free(chosen);
    trainer_free(&t);
    if (status != MR_OK) return status;
    rep.n_train = t.n_train;
    rep.n_validation = t.n_val;
    rep.n_search = t.n_search;
    rep.seconds = mr_now_seconds() - t.start;
    *out = m;
    if (report != NULL) *report = rep;
    return MR_OK;
}
