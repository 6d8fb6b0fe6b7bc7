/*
 * svr.c — epsilon-SVR with RBF kernels: training through libsvm with a grid then a compass search of the
 * hyper-parameters, and our own prediction (contract in svr.h).
 */
#include "learn/svr.h"

#include <libsvm/svm.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "mr_internal.h"
#include "nn/mlp_internal.h" /* the splitmix64 streams of the split (mr_mlp_rng_*) */

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

/* One row: x raw in, y raw out, u scratch of n_in doubles. The order of operations is libsvm's (svr.h). */
static void predict_row(const mr_svr *m, const double *restrict x, double *restrict u, double *restrict y) {
    const int n_in = m->n_in;
    int nan = 0;
    for (int i = 0; i < n_in; i++) {
        u[i] = (x[i] - m->in_mean[i]) / m->in_std[i];
        nan |= isnan(u[i]);
    }
    for (int k = 0; k < m->n_out; k++) {
        const mr_svr_output *o = &m->outputs[k];
        const double *restrict sv = o->sv;
        const double neg_gamma = -o->gamma;
        double sum = 0.0;
        for (int s = 0; s < o->sv_count; s++, sv += n_in) {
            double d2 = 0.0;
            for (int i = 0; i < n_in; i++) {
                const double t = u[i] - sv[i];
                d2 += t * t;
            }
            sum += o->coef[s] * exp(neg_gamma * d2);
        }
        y[k] = nan ? NAN : m->out_mean[k] + m->out_std[k] * (sum - o->rho);
    }
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
    int threads = max_team > 0 ? max_team : omp_get_max_threads();
#else
    int threads = 1;
    (void)max_team;
#endif
    // A thread per MR_SVR_PREDICT_ROWS rows at most: for fewer, starting a team costs more than it saves.
    if ((size_t)threads > count / MR_SVR_PREDICT_ROWS) threads = (int)(count / MR_SVR_PREDICT_ROWS);
    if (threads < 1) threads = 1;
    double *ws = malloc((size_t)threads * (size_t)m->n_in * sizeof(double));
    if (ws == NULL) return mr_fail(MR_ERR_NOMEM, "svr predict: out of memory for the workspace");
    const size_t n_in = (size_t)m->n_in, n_out = (size_t)m->n_out;
    const long rows = (long)count;
#pragma omp parallel num_threads(threads) if (threads > 1)
    {
#ifdef _OPENMP
        double *u = ws + (size_t)omp_get_thread_num() * n_in;
#else
        double *u = ws;
#endif
#pragma omp for schedule(static)
        for (long r = 0; r < rows; r++) predict_row(m, in + (size_t)r * n_in, u, out + (size_t)r * n_out);
    }
    free(ws);
    return MR_OK;
}

/* ---- training: data ----------------------------------------------------------------------------------------- */

enum { AXIS_C, AXIS_GAMMA, AXIS_EPSILON, AXES };

/* The search space per axis, in log units of `base` (svr.h): the grid lo, lo + spacing, ..., hi; the local
 * search's first step (half the spacing) and its box (the grid widened by one spacing). */
static const struct axis {
    const char *name;
    double base, lo, hi, spacing;
} axes[AXES] = {
    {"C", 2.0, -2.0, 12.0, 2.0},
    {"gamma", 2.0, -6.0, 4.0, 2.0},
    {"epsilon", 10.0, -4.0, -1.0, 1.0},
};

#define LIBSVM_TOLERANCE 1e-3 /* libsvm's stopping tolerance (its -e), its default */
#define FINAL_SCALE 0.125     /* the local search stops when its step falls below this share of the first */

typedef struct trainer {
    int n_in, n_out, threads;
    size_t n, n_val, n_train;
    size_t *order;             /* [n]: the validation rows, then the training rows */
    struct svm_node *nodes;    /* [n][n_in + 1]: row r's normalised inputs, indices 1..n_in, then index -1 */
    struct svm_node **x_train; /* [n_train] rows of the training split */
    struct svm_node **x_all;   /* [n] every row in its order */
    double *v;                 /* [n][n_out] normalised outputs */
    double *y_train;           /* [n_out][n_train] */
    double *y_all;             /* [n_out][n] */
    double *in_mean, *in_std, *out_mean, *out_std;
    int fixed[AXES];           /* 1: the axis is the option's value, not searched */
    double fixed_value[AXES];
    const mr_svr_train_options *opt;
    double start;              /* mr_now_seconds() at the call */
} trainer;

/* One candidate of one output: log coordinates t (unused on fixed axes) and its validation score. */
typedef struct job {
    int output;
    double t[AXES];
    double rmse;         /* normalised units; +inf for a failed fit */
    const char *refused; /* svm_check_parameter's message, or NULL */
} job;

static void print_nothing(const char *s) { (void)s; }

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
    uint64_t rng = mr_mlp_rng_stream(t->opt->seed, 1);
    for (size_t i = n; i > 1; i--) {
        const size_t j = (size_t)(mr_mlp_rng_next(&rng) % (uint64_t)i), tmp = t->order[i - 1];
        t->order[i - 1] = t->order[j];
        t->order[j] = tmp;
    }
    const double fraction = t->opt->validation_fraction > 0.0 ? t->opt->validation_fraction : MR_SVR_DEFAULT_VALIDATION;
    const double wanted = floor(fraction * (double)n + 0.5);
    t->n_val = wanted < 1.0 ? 1 : wanted > (double)(n - 1) ? n - 1 : (size_t)wanted;
    t->n_train = n - t->n_val;

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

/* libsvm's fit of output k with hyper-parameters hp (C, gamma, epsilon) on the training split or all rows; NULL
 * with *refused set if svm_check_parameter refuses them. */
static struct svm_model *fit(const trainer *t, int k, const double hp[AXES], int all_rows, const char **refused) {
    struct svm_problem prob;
    prob.l = (int)(all_rows ? t->n : t->n_train);
    prob.y = all_rows ? t->y_all + (size_t)k * t->n : t->y_train + (size_t)k * t->n_train;
    prob.x = all_rows ? t->x_all : t->x_train;
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
    *refused = svm_check_parameter(&prob, &p);
    return *refused != NULL ? NULL : svm_train(&prob, &p);
}

/* Score a job: fit on the training split, root mean square error on the validation split. */
static void score(const trainer *t, job *j) {
    double hp[AXES];
    hyper_parameters(t, j->t, hp);
    struct svm_model *model = fit(t, j->output, hp, 0, &j->refused);
    j->rmse = INFINITY;
    if (model == NULL) return;
    double sse = 0.0;
    for (size_t i = 0; i < t->n_val; i++) {
        const size_t r = t->order[i];
        const double d = svm_predict(model, t->x_all[r]) - t->v[r * (size_t)t->n_out + (size_t)j->output];
        sse += d * d;
    }
    svm_free_and_destroy_model(&model);
    const double rmse = sqrt(sse / (double)t->n_val);
    if (rmse < INFINITY) j->rmse = rmse; // NaN stays +inf: the worst score
}

/* Score jobs[0 .. count - 1] on the trainer's threads, in batches between calls of the progress callback (one
 * batch without one). *done counts the phase's fits. MR_ERR_CANCELLED if the callback asks; MR_ERR_INVALID_ARG if
 * libsvm refused a job's hyper-parameters. */
static mr_status run_jobs(const trainer *t, job *jobs, long count, mr_svr_phase phase, long *done, long planned) {
    const long batch = t->opt->progress == NULL ? count : MR_MAX(32L, 16L * t->threads);
    for (long first = 0; first < count; first += batch) {
        const long last = MR_MIN(count, first + batch);
#pragma omp parallel for num_threads(t->threads) schedule(dynamic, 1) if (t->threads > 1)
        for (long i = first; i < last; i++) score(t, &jobs[i]);
        for (long i = first; i < last; i++)
            if (jobs[i].refused != NULL) {
                double hp[AXES];
                hyper_parameters(t, jobs[i].t, hp);
                return mr_fail(MR_ERR_INVALID_ARG, "svr train: libsvm refuses C %g, gamma %g, epsilon %g: %s", hp[0],
                               hp[1], hp[2], jobs[i].refused);
            }
        *done += last - first;
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
    long count, capacity;
} scored;

static int scored_add(scored *s, const double lt[AXES], double rmse) {
    if (s->count == s->capacity) {
        const long cap = s->capacity > 0 ? 2 * s->capacity : 256;
        double(*nt)[AXES] = realloc(s->t, (size_t)cap * sizeof *nt);
        if (nt == NULL) return 0;
        s->t = nt;
        double *nr = realloc(s->rmse, (size_t)cap * sizeof *nr);
        if (nr == NULL) return 0;
        s->rmse = nr;
        s->capacity = cap;
    }
    memcpy(s->t[s->count], lt, sizeof s->t[0]);
    s->rmse[s->count++] = rmse;
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
    int polls;
    double poll_t[2 * AXES][AXES];
    double poll_rmse[2 * AXES]; /* known already, or NAN until its job has run */
    long poll_job[2 * AXES];    /* the job scoring it this round, or -1 */
} search;

/* Grid sizes per axis (1 on a fixed axis) and the cell's log coordinates. */
static int grid_size(const trainer *t, int a) {
    return t->fixed[a] ? 1 : (int)((axes[a].hi - axes[a].lo) / axes[a].spacing) + 1;
}

static void cell_point(const trainer *t, long cell, double lt[AXES]) {
    for (int a = AXES - 1; a >= 0; a--) {
        const int size = grid_size(t, a);
        lt[a] = t->fixed[a] ? 0.0 : axes[a].lo + axes[a].spacing * (double)(cell % size);
        cell /= size;
    }
}

/* Whether grid cell `cell` of an output (scores rmse[0 .. cells - 1]) is below its axial neighbours, ties broken
 * by the cell's index. */
static int grid_local_min(const trainer *t, const double *rmse, long cell) {
    long stride = 1;
    for (int a = AXES - 1; a >= 0; a--) {
        const int size = grid_size(t, a);
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

/* Poll every active search's neighbours; new points become jobs (one per distinct point and output). */
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
                const int q = s->polls++;
                memcpy(s->poll_t[q], p, sizeof p);
                s->poll_job[q] = -1;
                s->poll_rmse[q] = NAN;
                const long known = scored_find(&done[s->output], p);
                if (known >= 0) {
                    s->poll_rmse[q] = done[s->output].rmse[known];
                    continue;
                }
                for (long j = 0; j < n_jobs && s->poll_job[q] < 0; j++)
                    if (jobs[j].output == s->output && same_point(jobs[j].t, p)) s->poll_job[q] = j;
                if (s->poll_job[q] >= 0) continue;
                jobs[n_jobs] = (job){s->output, {p[0], p[1], p[2]}, INFINITY, NULL};
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
            if (s->poll_job[q] >= 0) s->poll_rmse[q] = jobs[s->poll_job[q]].rmse;
            if (best < 0 || s->poll_rmse[q] < s->poll_rmse[best]) best = q;
        }
        if (best >= 0 && s->poll_rmse[best] < s->rmse) {
            memcpy(s->center, s->poll_t[best], sizeof s->center);
            s->rmse = s->poll_rmse[best];
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

/* The grid, then the local search, for every output; best[k] gets the chosen point's index in done[k]. */
static mr_status run_search(const trainer *t, scored *done, long *best, long *grid_best, mr_svr_train_report *rep) {
    const int O = t->n_out;
    long cells = 1;
    for (int a = 0; a < AXES; a++) cells *= grid_size(t, a);
    const long grid_jobs = cells * O;
    long capacity = MR_MAX(grid_jobs, (long)O * MR_SVR_STARTS * 2 * AXES);
    job *jobs = malloc((size_t)capacity * sizeof *jobs);
    search *searches = malloc((size_t)O * MR_SVR_STARTS * sizeof *searches);
    if (jobs == NULL || searches == NULL) {
        free(jobs);
        free(searches);
        return mr_fail(MR_ERR_NOMEM, "svr train: out of memory for the search");
    }
    mr_status status = MR_OK;
    for (long j = 0; j < grid_jobs; j++) {
        jobs[j].output = (int)(j / cells);
        cell_point(t, j % cells, jobs[j].t);
        jobs[j].rmse = INFINITY;
        jobs[j].refused = NULL;
    }
    long fits = 0;
    status = run_jobs(t, jobs, grid_jobs, MR_SVR_PHASE_GRID, &fits, grid_jobs);
    rep->grid_fits = fits;
    int n_search = 0;
    for (int k = 0; k < O && status == MR_OK; k++) {
        const job *g = jobs + (long)k * cells;
        double *rmse = malloc((size_t)cells * sizeof *rmse);
        if (rmse == NULL) {
            status = mr_fail(MR_ERR_NOMEM, "svr train: out of memory for the search");
            break;
        }
        for (long c = 0; c < cells; c++) {
            rmse[c] = g[c].rmse;
            if (!scored_add(&done[k], g[c].t, g[c].rmse)) status = mr_fail(MR_ERR_NOMEM, "svr train: out of memory");
        }
        // Starts: the cells below their neighbours, best first (the grid's best is one of them).
        grid_best[k] = 0;
        for (long c = 1; c < cells; c++)
            if (rmse[c] < rmse[grid_best[k]]) grid_best[k] = c;
        int starts = 0;
        long chosen[MR_SVR_STARTS];
        while (starts < MR_SVR_STARTS) {
            long pick = -1;
            for (long c = 0; c < cells; c++) {
                int taken = 0;
                for (int s = 0; s < starts; s++) taken |= chosen[s] == c;
                if (!taken && (pick < 0 || rmse[c] < rmse[pick]) && rmse[c] < INFINITY && grid_local_min(t, rmse, c))
                    pick = c;
            }
            if (pick < 0) break;
            chosen[starts++] = pick;
        }
        for (int s = 0; s < starts && cells > 1; s++) {
            search *se = &searches[n_search++];
            memset(se, 0, sizeof *se);
            se->output = k;
            se->active = 1;
            memcpy(se->center, g[chosen[s]].t, sizeof se->center);
            se->rmse = g[chosen[s]].rmse;
            se->scale = 1.0;
        }
        free(rmse);
    }

    // The local search, in rounds: every active search's polls are scored together.
    fits = 0;
    rep->local_rounds = 0;
    for (int round = 0; round < MR_SVR_MAX_ROUNDS && status == MR_OK; round++) {
        int active = 0;
        for (int s = 0; s < n_search; s++) active |= searches[s].active;
        if (!active) break;
        const long n_jobs = plan_round(t, searches, n_search, done, jobs);
        status = run_jobs(t, jobs, n_jobs, MR_SVR_PHASE_LOCAL, &fits, fits + n_jobs);
        for (long j = 0; j < n_jobs && status == MR_OK; j++)
            if (!scored_add(&done[jobs[j].output], jobs[j].t, jobs[j].rmse))
                status = mr_fail(MR_ERR_NOMEM, "svr train: out of memory");
        finish_round(searches, n_search, jobs);
        rep->local_rounds = round + 1;
    }
    rep->local_fits = fits;
    for (int k = 0; k < O && status == MR_OK; k++) {
        best[k] = 0;
        for (long i = 1; i < done[k].count; i++)
            if (done[k].rmse[i] < done[k].rmse[best[k]]) best[k] = i;
    }
    free(jobs);
    free(searches);
    return status;
}

/* ---- training: the entry point --------------------------------------------------------------------------------- */

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
    t.n_in = n_in;
    t.n_out = n_out;
    t.n = n;
    t.opt = o;
    t.start = mr_now_seconds();
#ifdef _OPENMP
    t.threads = o->threads > 0 ? o->threads : omp_get_max_threads();
#else
    t.threads = 1;
#endif
    const double fixed[AXES] = {o->C, o->gamma, o->epsilon};
    for (int a = 0; a < AXES; a++) {
        t.fixed[a] = fixed[a] > 0.0;
        t.fixed_value[a] = fixed[a];
    }
    svm_set_print_string_function(print_nothing); // libsvm's solver reports on stdout otherwise

    mr_svr_train_report rep;
    memset(&rep, 0, sizeof rep);
    scored *done = calloc((size_t)n_out, sizeof *done);
    long *best = malloc(2 * (size_t)n_out * sizeof *best);
    struct svm_model **models = calloc((size_t)n_out, sizeof *models);
    job *refits = malloc((size_t)n_out * sizeof *refits);
    int *sv_counts = malloc((size_t)n_out * sizeof *sv_counts);
    if (done == NULL || best == NULL || models == NULL || refits == NULL || sv_counts == NULL)
        status = mr_fail(MR_ERR_NOMEM, "svr train: out of memory");
    if (status == MR_OK) status = trainer_init(&t, x, y);
    long *grid_best = best + n_out;
    if (status == MR_OK) status = run_search(&t, done, best, grid_best, &rep);

    // Refit every output with its choice on all rows.
    if (status == MR_OK) {
        for (int k = 0; k < n_out; k++) {
            refits[k].output = k;
            memcpy(refits[k].t, done[k].t[best[k]], sizeof refits[k].t);
            refits[k].refused = NULL;
        }
        if (o->progress != NULL) {
            const mr_svr_progress p = {MR_SVR_PHASE_REFIT, 0, n_out, mr_now_seconds() - t.start};
            if (o->progress(&p, o->progress_user) != 0)
                status = mr_fail(MR_ERR_CANCELLED, "svr train: cancelled by the progress callback");
        }
    }
    if (status == MR_OK) {
#pragma omp parallel for num_threads(t.threads) schedule(dynamic, 1) if (t.threads > 1)
        for (int k = 0; k < n_out; k++) {
            double hp[AXES];
            hyper_parameters(&t, refits[k].t, hp);
            models[k] = fit(&t, k, hp, 1, &refits[k].refused);
        }
        for (int k = 0; k < n_out && status == MR_OK; k++) {
            if (models[k] == NULL)
                status = mr_fail(MR_ERR_INVALID_ARG, "svr train: libsvm refuses output %d's refit: %s", k,
                                 refits[k].refused != NULL ? refits[k].refused : "no model");
            else
                sv_counts[k] = models[k]->l;
        }
    }
    mr_svr *m = NULL;
    if (status == MR_OK) status = mr_svr_alloc(n_in, n_out, sv_counts, &m);
    if (status == MR_OK) {
        memcpy(m->in_mean, t.in_mean, (size_t)n_in * sizeof(double));
        memcpy(m->in_std, t.in_std, (size_t)n_in * sizeof(double));
        memcpy(m->out_mean, t.out_mean, (size_t)n_out * sizeof(double));
        memcpy(m->out_std, t.out_std, (size_t)n_out * sizeof(double));
        for (int k = 0; k < n_out; k++) {
            mr_svr_output *mo = &m->outputs[k];
            const struct svm_model *sm = models[k];
            double hp[AXES];
            hyper_parameters(&t, refits[k].t, hp);
            for (int s = 0; s < sm->l; s++) {
                for (const struct svm_node *node = sm->SV[s]; node->index != -1; node++)
                    if (node->index >= 1 && node->index <= n_in)
                        mo->sv[(size_t)s * (size_t)n_in + (size_t)(node->index - 1)] = node->value;
                mo->coef[s] = sm->sv_coef[0][s];
            }
            mo->rho = sm->rho[0];
            mo->gamma = hp[AXIS_GAMMA];
            mo->C = hp[AXIS_C];
            mo->epsilon = hp[AXIS_EPSILON];
            mo->validation_rmse = t.out_std[k] * done[k].rmse[best[k]];
            mo->grid_rmse = t.out_std[k] * done[k].rmse[grid_best[k]];
        }
    }
    if (models != NULL)
        for (int k = 0; k < n_out; k++)
            if (models[k] != NULL) svm_free_and_destroy_model(&models[k]);
    if (done != NULL)
        for (int k = 0; k < n_out; k++) {
            free(done[k].t);
            free(done[k].rmse);
        }
    free(done);
    free(best);
    free(models);
    free(refits);
    free(sv_counts);
    trainer_free(&t);
    if (status != MR_OK) {
        mr_svr_free(m);
        return status;
    }
    rep.n_train = t.n_train;
    rep.n_validation = t.n_val;
    rep.seconds = mr_now_seconds() - t.start;
    *out = m;
    if (report != NULL) *report = rep;
    return MR_OK;
}
