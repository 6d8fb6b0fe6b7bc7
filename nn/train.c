/*
 * train.c — mr_mlp_train: split, normalisation, He initialisation, Adam on shuffled minibatches, early stopping
 * (contract and references in mlp.h).
 *
 * Deterministic for any thread count: a minibatch is cut into chunks of `chunk_rows` rows, a number that depends
 * on batch_size only; each chunk's gradient goes into its own buffer, and the Adam step adds the chunk buffers
 * in chunk order for each parameter. Loss passes (epoch 0, validation) likewise sum fixed chunks of
 * EVAL_CHUNK rows in order. Threads only decide who computes which chunk. The loss of each minibatch is the
 * forward pass of its own gradient computation (before the step), so an epoch costs one forward and one
 * backward pass over the training split plus one forward pass over the validation split.
 *
 * Training uses the float-rounded means and standard deviations that the returned network stores, so the
 * network trained and the network returned normalise identically.
 */
#include "mlp_internal.h"

#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#ifdef _OPENMP
#include <omp.h>
#endif

#include "../src/mr_internal.h"

/* Rows per chunk of a loss pass. */
#define EVAL_CHUNK 256
/* Smallest number of rows per gradient chunk; a minibatch has at most MAX_CHUNKS chunks. */
#define MIN_CHUNK_ROWS 16
#define MAX_CHUNKS 32

static const char *const stop_names[MR_MLP_STOP_COUNT] = {"max-epochs", "patience", "callback", "diverged"};

const char *mr_mlp_stop_str(mr_mlp_stop stop) {
    if ((int)stop < 0 || stop >= MR_MLP_STOP_COUNT) return "unknown";
    return stop_names[stop];
}

static int thread_id(void) {
#ifdef _OPENMP
    return omp_get_thread_num();
#else
    return 0;
#endif
}

/* ---- options ---------------------------------------------------------------------------------------------- */

typedef struct resolved {
    int n_hidden, batch, max_epochs, patience, threads;
    double val_fraction, lr, beta1, beta2, eps;
    uint64_t seed;
} resolved;

/* The automatic thread rule's threshold (mr_mlp_train_options.threads = 0, mr_auto_threads): any training set. A
 * team gains as soon as a minibatch or a loss pass has two chunks, and each parallel loop forks only then. */
#define PARALLEL_ROWS 2

/* The options in force for n rows: zero fields read as their defaults (mlp.h). */
static mr_status resolve_options(const mr_mlp_train_options *o, size_t n, resolved *r) {
    mr_mlp_train_options zero;
    memset(&zero, 0, sizeof zero);
    if (o == NULL) o = &zero;
    if (o->n_hidden < 0 || o->batch_size < 0 || o->max_epochs < 0 || o->patience < 0 || o->threads < 0)
        return mr_fail(MR_ERR_INVALID_ARG,
                       "mlp train: negative option (n_hidden %d, batch_size %d, max_epochs %d, patience %d, "
                       "threads %d)", o->n_hidden, o->batch_size, o->max_epochs, o->patience, o->threads);
    if (!(o->validation_fraction >= 0.0 && o->validation_fraction < 1.0))
        return mr_fail(MR_ERR_INVALID_ARG, "mlp train: validation_fraction %g (expected 0 <= f < 1; 0 = 0.1)",
                       o->validation_fraction);
    if (!(o->learning_rate >= 0.0 && isfinite(o->learning_rate)))
        return mr_fail(MR_ERR_INVALID_ARG, "mlp train: learning_rate %g (expected a finite value > 0; 0 = 1e-3)",
                       o->learning_rate);
    if (!(o->beta1 >= 0.0 && o->beta1 < 1.0) || !(o->beta2 >= 0.0 && o->beta2 < 1.0))
        return mr_fail(MR_ERR_INVALID_ARG, "mlp train: beta1 %g, beta2 %g (expected 0 <= beta < 1; 0 = default)",
                       o->beta1, o->beta2);
    if (!(o->epsilon >= 0.0 && isfinite(o->epsilon)))
        return mr_fail(MR_ERR_INVALID_ARG, "mlp train: epsilon %g (expected a finite value > 0; 0 = 1e-8)",
                       o->epsilon);
    r->n_hidden = o->n_hidden ? o->n_hidden : MR_MLP_DEFAULT_HIDDEN;
    r->batch = o->batch_size ? o->batch_size : MR_MLP_DEFAULT_BATCH;
    r->max_epochs = o->max_epochs ? o->max_epochs : MR_MLP_DEFAULT_MAX_EPOCHS;
    r->patience = o->patience ? o->patience : MR_MLP_DEFAULT_PATIENCE;
#ifdef _OPENMP
    r->threads = mr_auto_threads(o->threads, (long)MR_MIN(n, (size_t)LONG_MAX), PARALLEL_ROWS);
#else
    (void)n;
    r->threads = 1;
#endif
    r->val_fraction = o->validation_fraction > 0.0 ? o->validation_fraction : MR_MLP_DEFAULT_VALIDATION;
    r->lr = o->learning_rate > 0.0 ? o->learning_rate : MR_MLP_DEFAULT_LEARNING_RATE;
    r->beta1 = o->beta1 > 0.0 ? o->beta1 : MR_MLP_DEFAULT_BETA1;
    r->beta2 = o->beta2 > 0.0 ? o->beta2 : MR_MLP_DEFAULT_BETA2;
    r->eps = o->epsilon > 0.0 ? o->epsilon : MR_MLP_DEFAULT_EPSILON;
    r->seed = (uint64_t)o->seed;
    return MR_OK;
}

/* ---- the run's state -------------------------------------------------------------------------------------- */

typedef struct trainer {
    mr_mlp_dims d;
    resolved opt;
    const float *x, *y;
    size_t P;                      /* parameters */
    float *in_mean, *in_std;       /* the normalisation the network stores (float), one block from in_mean: */
    float *out_mean, *out_std;     /* in_mean [n_in], in_std [n_in], out_mean [n_out], out_std [n_out] */
    size_t *order;                 /* n: the split permutation; [0, n_val) validation, [n_val, n) training */
    size_t n_val, n_train;
    double *params, *best, *m, *v; /* one block of 4 x P: weights, best weights, Adam's moments */
    double *grads;                 /* one gradient per chunk of a minibatch (at most MAX_CHUNKS) x P */
    double *chunk_sse;             /* per chunk of a minibatch or a loss pass */
    size_t chunk_sse_count;
    size_t chunk_rows;             /* rows per gradient chunk */
    size_t scratch_rows;           /* rows a thread's scratch holds */
    double *scratch;               /* threads x scratch_stride */
    size_t scratch_stride;
} trainer;

static void trainer_free(trainer *t) {
    free(t->in_mean);
    free(t->order);
    free(t->params);
    free(t->grads);
    free(t->chunk_sse);
    free(t->scratch);
}

/* Normalised rows order[0 .. count-1] into xb (count x n_in) and tb (count x n_out). */
static void load_rows(const trainer *t, const size_t *order, size_t count, double *xb, double *tb) {
    const size_t I = (size_t)t->d.n_in, O = (size_t)t->d.n_out;
    for (size_t r = 0; r < count; r++) {
        const float *xs = t->x + order[r] * I, *ys = t->y + order[r] * O;
        for (size_t i = 0; i < I; i++) xb[r * I + i] = ((double)xs[i] - t->in_mean[i]) / t->in_std[i];
        for (size_t k = 0; k < O; k++) tb[r * O + k] = ((double)ys[k] - t->out_mean[k]) / t->out_std[k];
    }
}

/* Thread `id`'s scratch: rows of inputs, rows of targets, the pass's work. */
static void scratch_of(const trainer *t, int id, double **xb, double **tb, double **work) {
    double *base = t->scratch + (size_t)id * t->scratch_stride;
    *xb = base;
    *tb = base + t->scratch_rows * (size_t)t->d.n_in;
    *work = *tb + t->scratch_rows * (size_t)t->d.n_out;
}

/* Mean loss of the rows order[0 .. count-1] with t->params, summed over fixed chunks in order. */
static double loss_pass(trainer *t, const size_t *order, size_t count) {
    const size_t chunks = (count + EVAL_CHUNK - 1) / EVAL_CHUNK;
#pragma omp parallel for num_threads(t->opt.threads) schedule(static) if (t->opt.threads > 1 && chunks > 1)
    for (size_t c = 0; c < chunks; c++) {
        double *xb, *tb, *work;
        scratch_of(t, thread_id(), &xb, &tb, &work);
        size_t first = c * EVAL_CHUNK, rows = MR_MIN((size_t)EVAL_CHUNK, count - first);
        load_rows(t, order + first, rows, xb, tb);
        t->chunk_sse[c] = mr_mlp_sse_grad(&t->d, t->params, xb, tb, rows, NULL, work);
    }
    double sum = 0.0;
    for (size_t c = 0; c < chunks; c++) sum += t->chunk_sse[c];
    return sum / ((double)count * (double)t->d.n_out);
}

/* One Adam step on the rows order[0 .. count-1], with beta1_t = beta1^step and beta2_t = beta2^step for the
 * step's number (from 1); returns the rows' sum of squared errors before the step. */
static double adam_step(trainer *t, const size_t *order, size_t count, double beta1_t, double beta2_t) {
    const size_t P = t->P;
    const size_t chunks = (count + t->chunk_rows - 1) / t->chunk_rows;
#pragma omp parallel for num_threads(t->opt.threads) schedule(static) if (t->opt.threads > 1 && chunks > 1)
    for (size_t c = 0; c < chunks; c++) {
        double *xb, *tb, *work;
        scratch_of(t, thread_id(), &xb, &tb, &work);
        size_t first = c * t->chunk_rows, rows = MR_MIN(t->chunk_rows, count - first);
        double *g = t->grads + c * P;
        memset(g, 0, P * sizeof *g);
        load_rows(t, order + first, rows, xb, tb);
        t->chunk_sse[c] = mr_mlp_sse_grad(&t->d, t->params, xb, tb, rows, g, work);
    }
    double sse = 0.0;
    for (size_t c = 0; c < chunks; c++) sse += t->chunk_sse[c];
    // Kingma & Ba, Algorithm 1, on the mean loss of the minibatch (gradient scaled by 1 / (rows * n_out)).
    const double scale = 1.0 / ((double)count * (double)t->d.n_out);
    const double b1 = t->opt.beta1, b2 = t->opt.beta2, lr = t->opt.lr, eps = t->opt.eps;
    const double c1 = 1.0 / (1.0 - beta1_t), c2 = 1.0 / (1.0 - beta2_t);
    double *restrict p = t->params, *restrict m = t->m, *restrict v = t->v;
    const double *restrict grads = t->grads;
#pragma omp parallel for num_threads(t->opt.threads) schedule(static) if (t->opt.threads > 1 && P >= 65536)
    for (size_t q = 0; q < P; q++) {
        double g = grads[q];
        for (size_t c = 1; c < chunks; c++) g += grads[c * P + q];
        g *= scale;
        m[q] = b1 * m[q] + (1.0 - b1) * g;
        v[q] = b2 * v[q] + (1.0 - b2) * g * g;
        p[q] -= lr * (m[q] * c1) / (sqrt(v[q] * c2) + eps);
    }
    return sse;
}

/* Fisher-Yates shuffle of a[0 .. n-1] (the modulo's bias, below n / 2^64, is immaterial). */
static void shuffle(size_t *a, size_t n, uint64_t *rng) {
    for (size_t i = n; i > 1; i--) {
        size_t j = (size_t)(mr_rng_next(rng) % (uint64_t)i);
        size_t tmp = a[i - 1];
        a[i - 1] = a[j];
        a[j] = tmp;
    }
}

/* Standard normal by Box-Muller (one of the pair). */
static double normal(uint64_t *rng) {
    double u1 = 1.0 - mr_rng_unit(rng); // (0, 1]
    double u2 = mr_rng_unit(rng);
    return sqrt(-2.0 * log(u1)) * cos(2.0 * MR_PI * u2);
}

/* Mean and population standard deviation of column `col` of the `stride`-wide rows order[0 .. count-1],
 * rounded to float; std 1 for a (near) constant column. */
static void column_stats(const float *data, size_t stride, size_t col, const size_t *order, size_t count,
                         float *mean_out, float *std_out) {
    double mean = 0.0;
    for (size_t r = 0; r < count; r++) mean += data[order[r] * stride + col];
    mean /= (double)count;
    double var = 0.0;
    for (size_t r = 0; r < count; r++) {
        double e = data[order[r] * stride + col] - mean;
        var += e * e;
    }
    double std = sqrt(var / (double)count);
    if (!(std > 1e-12 * MR_MAX(1.0, fabs(mean)))) std = 1.0;
    if (std > FLT_MAX) std = FLT_MAX; // data near +-FLT_MAX; keeps the conversion defined
    *mean_out = (float)mean;
    *std_out = (float)std;
}

/* The first non-finite value of a rows x cols array, as an error naming `what`, its row and column. */
static mr_status check_finite(const char *what, const float *a, size_t rows, size_t cols) {
    for (size_t r = 0; r < rows; r++)
        for (size_t c = 0; c < cols; c++)
            if (!isfinite(a[r * cols + c]))
                return mr_fail(MR_ERR_INVALID_ARG, "mlp train: %s row %zu, column %zu is %g (expected finite values)",
                               what, r, c, (double)a[r * cols + c]);
    return MR_OK;
}

static mr_status setup(trainer *t, size_t n) {
    const size_t I = (size_t)t->d.n_in, O = (size_t)t->d.n_out, P = t->P;
    t->in_mean = malloc(2 * (I + O) * sizeof(float));
    t->order = malloc(n * sizeof(size_t));
    t->params = malloc(4 * P * sizeof(double));
    t->chunk_rows = MR_MAX((size_t)MIN_CHUNK_ROWS, ((size_t)t->opt.batch + MAX_CHUNKS - 1) / MAX_CHUNKS);
    size_t grad_chunks = MR_MIN((size_t)MAX_CHUNKS, ((size_t)t->opt.batch + t->chunk_rows - 1) / t->chunk_rows);
    t->grads = malloc(grad_chunks * P * sizeof(double));
    t->chunk_sse_count = MR_MAX(grad_chunks, (n + EVAL_CHUNK - 1) / EVAL_CHUNK);
    t->chunk_sse = malloc(t->chunk_sse_count * sizeof(double));
    t->scratch_rows = MR_MAX(t->chunk_rows, (size_t)EVAL_CHUNK);
    t->scratch_stride = t->scratch_rows * (I + O) + mr_mlp_work_doubles(&t->d);
    t->scratch = malloc((size_t)t->opt.threads * t->scratch_stride * sizeof(double));
    if (t->in_mean == NULL || t->order == NULL || t->params == NULL || t->grads == NULL || t->chunk_sse == NULL ||
        t->scratch == NULL)
        return mr_fail(MR_ERR_NOMEM, "mlp train: out of memory (%zu rows, %zu parameters)", n, P);
    t->in_std = t->in_mean + I;
    t->out_mean = t->in_std + I;
    t->out_std = t->out_mean + O;
    t->best = t->params + P;
    t->m = t->best + P;
    t->v = t->m + P;

    // Split.
    for (size_t r = 0; r < n; r++) t->order[r] = r;
    uint64_t rng = mr_rng_stream(t->opt.seed, 1);
    shuffle(t->order, n, &rng);
    double wanted = floor(t->opt.val_fraction * (double)n + 0.5);
    t->n_val = wanted < 1.0 ? 1 : wanted > (double)(n - 1) ? n - 1 : (size_t)wanted;
    t->n_train = n - t->n_val;

    // Normalisation from the training split.
    const size_t *train = t->order + t->n_val;
    for (size_t i = 0; i < I; i++) column_stats(t->x, I, i, train, t->n_train, &t->in_mean[i], &t->in_std[i]);
    for (size_t k = 0; k < O; k++) column_stats(t->y, O, k, train, t->n_train, &t->out_mean[k], &t->out_std[k]);

    // Initialisation: He for the ReLU layer, LeCun for the linear one, zero biases.
    rng = mr_rng_stream(t->opt.seed, 2);
    memset(t->params, 0, P * sizeof(double));
    const double s1 = sqrt(2.0 / (double)I), s2 = sqrt(1.0 / (double)t->d.n_hidden);
    for (size_t q = 0; q < mr_mlp_off_b1(&t->d); q++) t->params[q] = s1 * normal(&rng);
    for (size_t q = mr_mlp_off_w2(&t->d); q < mr_mlp_off_b2(&t->d); q++) t->params[q] = s2 * normal(&rng);
    memcpy(t->best, t->params, P * sizeof(double));
    memset(t->m, 0, 2 * P * sizeof(double));
    return MR_OK;
}

/* The float network of t->best and the normalisation. */
static mr_status make_network(const trainer *t, mr_mlp **out) {
    mr_mlp *net = NULL;
    mr_status status = mr_mlp_create(t->d.n_in, t->d.n_hidden, t->d.n_out, &net);
    if (status != MR_OK) return status;
    for (size_t q = 0; q < t->P; q++) {
        if (!(fabs(t->best[q]) <= FLT_MAX)) { // also keeps the conversion below defined
            mr_mlp_free(net);
            return mr_fail(MR_ERR_NUMERIC, "mlp train: parameter %zu (%g) does not fit a float", q, t->best[q]);
        }
        net->data[q] = (float)t->best[q];
    }
    memcpy(net->in_mean, t->in_mean, 2 * ((size_t)t->d.n_in + (size_t)t->d.n_out) * sizeof(float));
    status = mr_mlp_pack(net); // the inference kernels' layout, once (mlp.h, "Ownership")
    if (status != MR_OK) {
        mr_mlp_free(net);
        return status;
    }
    *out = net;
    return MR_OK;
}

mr_status mr_mlp_train(const float *x, const float *y, size_t n, int n_in, int n_out,
                       const mr_mlp_train_options *opts, mr_mlp **out, mr_mlp_train_report *report) {
    trainer t;
    memset(&t, 0, sizeof t);
    if (out == NULL) return mr_fail(MR_ERR_INVALID_ARG, "mlp train: NULL output pointer");
    if (x == NULL || y == NULL) return mr_fail(MR_ERR_INVALID_ARG, "mlp train: NULL data array");
    if (n < 2) return mr_fail(MR_ERR_INVALID_ARG, "mlp train: %zu rows (need at least 2: one to train, one to "
                              "validate)", n);
    mr_status status = resolve_options(opts, n, &t.opt);
    if (status != MR_OK) return status;
    status = mr_mlp_check_dims("mlp train", n_in, t.opt.n_hidden, n_out);
    if (status != MR_OK) return status;
    if (n > SIZE_MAX / sizeof(size_t) / (size_t)MR_MAX(n_in, n_out))
        return mr_fail(MR_ERR_INVALID_ARG, "mlp train: %zu rows overflow size_t", n);
    status = check_finite("input", x, n, (size_t)n_in);
    if (status == MR_OK) status = check_finite("target", y, n, (size_t)n_out);
    if (status != MR_OK) return status;

    t.d.n_in = n_in;
    t.d.n_hidden = t.opt.n_hidden;
    t.d.n_out = n_out;
    t.x = x;
    t.y = y;
    t.P = mr_mlp_dims_params(&t.d);
    status = setup(&t, n);
    if (status != MR_OK) {
        trainer_free(&t);
        return status;
    }
    const size_t *val = t.order, *train = t.order + t.n_val;

    mr_mlp_train_report rep;
    memset(&rep, 0, sizeof rep);
    rep.n_train = t.n_train;
    rep.n_validation = t.n_val;
    rep.initial_train_loss = loss_pass(&t, train, t.n_train);
    rep.initial_validation_loss = loss_pass(&t, val, t.n_val);
    rep.final_train_loss = rep.initial_train_loss;
    rep.best_validation_loss = rep.initial_validation_loss;
    rep.best_epoch = 0;
    rep.stop = MR_MLP_STOP_MAX_EPOCHS;

    mr_mlp_epoch e = {0, t.opt.max_epochs, rep.initial_train_loss, rep.initial_validation_loss, 0,
                      rep.initial_validation_loss};
    int stop = 0;
    if (!isfinite(rep.initial_train_loss) || !isfinite(rep.initial_validation_loss)) {
        rep.stop = MR_MLP_STOP_DIVERGED;
        stop = 1;
    }
    if (opts != NULL && opts->epoch_fn != NULL && opts->epoch_fn(&e, opts->epoch_user) != 0 && !stop) {
        rep.stop = MR_MLP_STOP_CALLBACK;
        stop = 1;
    }

    size_t *train_order = t.order + t.n_val; // reshuffled in place every epoch
    uint64_t rng = mr_rng_stream(t.opt.seed, 3);
    double beta1_t = 1.0, beta2_t = 1.0;
    for (int epoch = 1; !stop && epoch <= t.opt.max_epochs; epoch++) {
        shuffle(train_order, t.n_train, &rng);
        double sse = 0.0;
        for (size_t first = 0; first < t.n_train; first += (size_t)t.opt.batch) {
            size_t rows = MR_MIN((size_t)t.opt.batch, t.n_train - first);
            beta1_t *= t.opt.beta1;
            beta2_t *= t.opt.beta2;
            sse += adam_step(&t, train_order + first, rows, beta1_t, beta2_t);
        }
        double train_loss = sse / ((double)t.n_train * (double)n_out);
        double val_loss = loss_pass(&t, val, t.n_val);
        rep.epochs = epoch;
        rep.final_train_loss = train_loss;
        int diverged = !isfinite(train_loss) || !isfinite(val_loss);
        if (!diverged && val_loss < rep.best_validation_loss) {
            rep.best_validation_loss = val_loss;
            rep.best_epoch = epoch;
            memcpy(t.best, t.params, t.P * sizeof(double));
        }
        e.epoch = epoch;
        e.train_loss = train_loss;
        e.validation_loss = val_loss;
        e.best_epoch = rep.best_epoch;
        e.best_validation_loss = rep.best_validation_loss;
        int asked = opts != NULL && opts->epoch_fn != NULL && opts->epoch_fn(&e, opts->epoch_user) != 0;
        if (diverged) {
            rep.stop = MR_MLP_STOP_DIVERGED;
            stop = 1;
        } else if (asked) {
            rep.stop = MR_MLP_STOP_CALLBACK;
            stop = 1;
        } else if (epoch - rep.best_epoch >= t.opt.patience) {
            rep.stop = MR_MLP_STOP_PATIENCE;
            stop = 1;
        }
    }

    mr_mlp *net = NULL;
    status = make_network(&t, &net);
    trainer_free(&t);
    if (status != MR_OK) return status;
    *out = net;
    if (report != NULL) *report = rep;
    return MR_OK;
}
