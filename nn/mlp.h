/*
 * mlp.h — a hand-written one-hidden-layer ReLU perceptron: training (Adam, minibatches, early stopping),
 * batched inference and exact weight files. The user's design card asks for 6 x 300 x 4: diffuse RGB and
 * specular RGB of a specular-workflow material in, albedo RGB and metallic out. Every size is a parameter.
 *
 * Main calls:
 *   mr_mlp_train_options o = {0};                 // zero = defaults (each field says what 0 means)
 *   o.n_hidden = 64;  o.seed = 7;  o.epoch_fn = draw_progress;  o.epoch_user = &bar;
 *   mr_mlp *net = NULL;  mr_mlp_train_report r;
 *   mr_mlp_train(x, y, n, 6, 4, &o, &net, &r);    // x: n x 6, y: n x 4, raw (unnormalised) floats
 *   mr_mlp_write(net, "spec2metal.mlp");           // atomic; reads back bit for bit
 *   mr_mlp_predict(net, in, count, out);           // in: count x 6 raw values, out: count x 4 raw values
 *   mr_mlp_free(net);
 *   mr_mlp_read("spec2metal.mlp", &net);
 *
 * The network. For one row x (n_in raw values), in float:
 *   u_i = (x_i - in_mean[i]) / in_std[i]                                  normalised input
 *   h_j = max(0, b1[j] + w1[0][j] u_0 + w1[1][j] u_1 + ...)            j < n_hidden, the ReLU layer
 *   v_k = b2[k] + w2[k][0] h_0 + w2[k][1] h_1 + ...                      k < n_out, linear
 *   y_k = out_mean[k] + out_std[k] v_k                                   raw output
 * The sums run in the index order shown. How each product is added depends on the inference kernel
 * (mr_mlp_kernel, chosen at run time): the AVX-512 and AVX2 kernels fuse every product into its sum (one rounding
 * per multiply-add, FMA), the SSE2 and EXACT kernels round each product and each sum (the library is built in ISO
 * C mode, so nothing else fuses). For a given kernel a row's outputs are the same bits whatever the other rows or
 * the thread count; the fused and unfused kernels differ by rounding only (nn/mlp.c, "Fused multiply-adds": the
 * bound tests/test_nn.c checks). Outputs are raw: nothing is clamped (a metallic of 1.02 stays 1.02; the caller
 * clamps).
 * Training minimises the mean squared error of v against the normalised targets (y - out_mean) / out_std, so
 * all outputs weigh the same whatever their units.
 *
 * Shapes and layout. mr_mlp is plain data: the fields below point into one block, `data`, of `data_count`
 * floats holding w1, b1, w2, b2, in_mean, in_std, out_mean, out_std in that order. w1 is [n_in][n_hidden]
 * (w1[i * n_hidden + j]: input i to hidden unit j) and w2 is [n_out][n_hidden] (w2[k * n_hidden + j]), so the
 * hidden dimension is contiguous. Row-major batches: row r of `in` is in[r * n_in .. r * n_in + n_in - 1].
 * Sizes: 1 <= n_in, n_out <= MR_MLP_MAX_IO, 1 <= n_hidden <= MR_MLP_MAX_HIDDEN, and at most MR_MLP_MAX_PARAMS
 * weights and biases in all (a bound on what a weight file can make the reader allocate).
 *
 * Normalisation. mr_mlp_train computes each input and output feature's mean and (population) standard
 * deviation over the training split only, in double, and stores them with the weights; inference applies
 * them, so callers always pass and receive raw values. A feature whose standard deviation is not above
 * 1e-12 * max(1, |mean|) (constant, as a switch held fixed in a dataset) gets std 1: it normalises to ~0 and
 * yields no NaN.
 *
 * NaN. A row with a NaN among its inputs gets NaN in all of its outputs (NaN propagates through the ReLU:
 * max(0, NaN) is NaN here), and an infinite input gives non-finite outputs; other rows are unaffected.
 * mr_mlp_predict does not flag such rows: callers with untrusted inputs check isnan() on the outputs.
 * Training data must be finite (MR_ERR_INVALID_ARG naming the first bad row and column otherwise).
 *
 * Training (mr_mlp_train). References: He, Zhang, Ren, Sun, "Delving deep into rectifiers", ICCV 2015 (the
 * initialisation); Kingma, Ba, "Adam: a method for stochastic optimization", ICLR 2015 (the optimiser, with
 * its bias correction, as in Algorithm 1); Prechelt, "Early stopping — but when?", 1998 (patience).
 *   - Split: a seeded shuffle of the rows; the first round(validation_fraction * n) (at least 1, at most n - 1)
 *     are the validation split, the rest the training split.
 *   - Initialisation: w1 ~ N(0, 2 / n_in) (He, for the ReLU layer), w2 ~ N(0, 1 / n_hidden) (LeCun, for the
 *     linear layer), biases 0.
 *   - Each epoch shuffles the training split (seeded) and takes minibatches of batch_size rows (the last one
 *     may be smaller); each minibatch is one Adam step on its mean loss. The master weights, gradients, Adam
 *     moments and losses are double; the returned network is their rounding to float.
 *   - After each epoch the validation loss is measured. The weights of the epoch with the lowest validation
 *     loss so far (strictly lower; epoch 0 is the initialisation) are kept; training stops after `patience`
 *     epochs without a new best, after max_epochs, when the callback asks, or when a loss turns non-finite,
 *     and the best weights are returned.
 *   - Loss: the mean over rows and outputs of the squared error in normalised output units. An epoch's train
 *     loss is the mean of the minibatch losses of that epoch weighted by their rows, measured before each
 *     step (as Keras reports it); epoch 0's is a full pass over the training split.
 *
 * Determinism. Everything random comes from splitmix64 streams derived from opts->seed (mr_rng_stream of
 * mr_core.h: split, initial weights, epoch shuffles). A minibatch's gradient is summed over fixed chunks of rows
 * (the chunking depends only on batch_size) and the chunk sums are added in chunk order, so training gives
 * bit-identical weights for a seed whatever the thread count and whichever of the per-CPU variants of the gradient
 * pass runs (they differ only in vector width); across machines only libm can differ (the initialisation uses log
 * and cos).
 *
 * Threads. mr_mlp_train runs the chunks of a minibatch and of the loss passes on opts->threads OpenMP
 * threads; mr_mlp_predict splits rows in blocks over omp_get_max_threads() threads, one per 256 rows at most (a
 * team costs more than fewer rows save); mr_mlp_evaluate likewise.
 * All functions are reentrant and a network may be shared by threads for reading (predict, evaluate, write).
 *
 * Ownership. One owner, one free: a network returned through `mr_mlp **out` belongs to the caller and is
 * released, with everything it points to, by mr_mlp_free() (NULL-safe). Its values may be changed in place;
 * its pointers and sizes may not. The library keeps no pointer to caller arrays after a call returns.
 * The network also owns its weights in the layout the inference kernels read (`packed`), made when it is read or
 * trained; a prediction checks that they still match the values (a 15 KB comparison for 6 x 300 x 4) and, after
 * the values were changed in place, packs them for that call instead (mr_mlp_pack makes them current again).
 *
 * The weight file (mr_mlp_write / mr_mlp_read), versions 1 and 2. Text, '\n' line ends, ASCII, one key per line
 * followed by its values separated by single spaces, every number a C99 hexadecimal float ("%a" of the float:
 * -0x1.8p+3, 0x0p+0), which reads back bit for bit (and is independent of the process locale: the library
 * switches its own thread to the C numeric locale while reading or writing):
 *   matremap-mlp 1                  magic and version (2 for a network with a kind)
 *   n_in 6
 *   n_hidden 300
 *   n_out 4
 *   activation relu linear          hidden and output activations (the only pair this version knows)
 *   kind WORD                       version 2 only: mr_mlp.kind (a network with an empty kind is written as
 *                                   version 1, without this line, so plain networks keep their files)
 *   in_mean m_0 ... m_{n_in-1}
 *   in_std s_0 ... s_{n_in-1}       each > 0
 *   out_mean ...                    n_out values
 *   out_std ...                     n_out values, each > 0
 *   w1 w1[i][0] ... w1[i][n_hidden-1]      n_in such lines, i = 0, 1, ...
 *   b1 b1[0] ... b1[n_hidden-1]
 *   w2 w2[k][0] ... w2[k][n_hidden-1]      n_out such lines, k = 0, 1, ...
 *   b2 b2[0] ... b2[n_out-1]
 *   end
 * Keys come in exactly this order and counts; values must be finite floats. The reader accepts any decimal or
 * hexadecimal number strtod() reads, rounded to float (what the writer writes is exact), and several spaces
 * between fields; nothing else. A wrong magic or version, an unknown or misplaced key, a wrong value count, a
 * bad number, a missing "end" or a last line without '\n' (a truncated file), or anything after "end" is
 * MR_ERR_FORMAT with a message naming the file and the line. Writes go to a temporary file in the same
 * directory that is renamed over the target once complete (an existing file is never partly overwritten).
 */
#ifndef MR_MLP_H
#define MR_MLP_H

#include <stddef.h>

#include "mr_status.h" /* src/ in the tree (-Isrc), include/matremap/ once installed */

#ifdef __cplusplus
extern "C" {
#endif

#define MR_MLP_FILE_MAGIC "matremap-mlp"
#define MR_MLP_FILE_VERSION 2 /* the newest version written; version 1 files (no kind) are read too */
#define MR_MLP_KIND_MAX 32     /* bytes of mr_mlp.kind, its terminating zero included */

#define MR_MLP_MAX_IO 4096           /* largest n_in or n_out */
#define MR_MLP_MAX_HIDDEN 65536      /* largest n_hidden */
#define MR_MLP_MAX_PARAMS (1L << 26) /* most trainable parameters (mr_mlp_param_count) */

/* Defaults that 0 stands for in mr_mlp_train_options. */
#define MR_MLP_DEFAULT_HIDDEN 300
#define MR_MLP_DEFAULT_BATCH 64
#define MR_MLP_DEFAULT_MAX_EPOCHS 200
#define MR_MLP_DEFAULT_PATIENCE 20
#define MR_MLP_DEFAULT_VALIDATION 0.1
#define MR_MLP_DEFAULT_LEARNING_RATE 1e-3
#define MR_MLP_DEFAULT_BETA1 0.9
#define MR_MLP_DEFAULT_BETA2 0.999
#define MR_MLP_DEFAULT_EPSILON 1e-8

/* A network (plain data; layout in the header comment). */
typedef struct mr_mlp {
    int n_in, n_hidden, n_out;
    float *w1;        /* [n_in][n_hidden] */
    float *b1;        /* [n_hidden] */
    float *w2;        /* [n_out][n_hidden] */
    float *b2;        /* [n_out] */
    float *in_mean;   /* [n_in] */
    float *in_std;    /* [n_in], > 0 */
    float *out_mean;  /* [n_out] */
    float *out_std;   /* [n_out], > 0 */
    float *data;      /* all of the above, in this order */
    size_t data_count;
    char kind[MR_MLP_KIND_MAX]; /* "" (plain) or a word naming how the application reads the outputs (e.g.
                                   "spec2metal-residual", src/workflow/workflow.h): letters, digits, '.', '_',
                                   '-'; saved in the file (version 2). The network itself ignores it */
    struct mr_mlp_packed *packed; /* the kernels' copy of the weights (header comment, "Ownership"); NULL = none */
} mr_mlp;

/* The inference kernels (nn/mlp.c). AUTO: the environment variable MR_MLP_KERNEL if set (one of the names
 * below; meant for tests and benchmarks), else the fastest this CPU runs: AVX512 on x86-64-v4, AVX2 on x86-64-v3,
 * SSE2 otherwise. AVX512 and AVX2 fuse multiply-adds; SSE2 is the portable unfused loop; EXACT is the unfused
 * loop at this CPU's widest vectors (the kernel of earlier versions: SSE2's bits, faster). */
typedef enum mr_mlp_kernel {
    MR_MLP_KERNEL_AUTO = 0,
    MR_MLP_KERNEL_SSE2,   /* "sse2" */
    MR_MLP_KERNEL_EXACT,  /* "exact" */
    MR_MLP_KERNEL_AVX2,   /* "avx2": AVX2 + FMA */
    MR_MLP_KERNEL_AVX512, /* "avx512": AVX-512F */
    MR_MLP_KERNEL_COUNT
} mr_mlp_kernel;

/* "auto", "sse2", "exact", "avx2", "avx512"; NULL outside the enum. */
const char *mr_mlp_kernel_name(mr_mlp_kernel kernel);

/* The kernel AUTO stands for in this process (MR_MLP_KERNEL, else the CPU's; computed once). MR_ERR_INVALID_ARG
 * naming the variable's value when it is not a kernel name or names one this CPU cannot run. */
mr_status mr_mlp_kernel_auto(mr_mlp_kernel *out);

/* 1 when this build and CPU run `kernel` (AUTO, SSE2 and EXACT always), else 0. */
int mr_mlp_kernel_available(mr_mlp_kernel kernel);

/* (Re)make the network's packed weights from its current values (after changing them in place; reading and
 * training do it). Not while other threads predict with the network. MR_ERR_INVALID_ARG for a bad network,
 * MR_ERR_NOMEM (the network is unchanged). */
mr_status mr_mlp_pack(mr_mlp *net);

/* A network of the given sizes with zero weights and biases, means 0 and standard deviations 1 (it predicts
 * zeros). MR_ERR_INVALID_ARG for sizes outside the limits, MR_ERR_NOMEM. On success *out is the caller's
 * (mr_mlp_free); on failure *out is untouched. */
mr_status mr_mlp_create(int n_in, int n_hidden, int n_out, mr_mlp **out);

/* Release a network and everything it points to. NULL is fine. */
void mr_mlp_free(mr_mlp *net);

/* Number of trainable parameters: n_hidden * (n_in + 1) + n_out * (n_hidden + 1). */
size_t mr_mlp_param_count(const mr_mlp *net);

/* Run n rows through the network: in is n x n_in raw inputs, out receives n x n_out raw outputs (row-major;
 * the arrays must not overlap). n = 0 does nothing (in and out may then be NULL). Results are bit-identical
 * for any thread count (header comment); NaN inputs give NaN outputs for their row. Errors:
 * MR_ERR_INVALID_ARG (NULL or inconsistent network, NULL arrays, n x n_in overflowing size_t), MR_ERR_NOMEM
 * (a small per-thread workspace); out is untouched on failure. */
mr_status mr_mlp_predict(const mr_mlp *net, const float *in, size_t n, float *out);

/* mr_mlp_predict on at most max_team threads (0 = automatic, mr_auto_threads: omp_get_max_threads()), still one
 * per 256 rows at most. */
mr_status mr_mlp_predict_threads(const mr_mlp *net, const float *in, size_t n, float *out, int max_team);

/* mr_mlp_predict_threads with a given kernel (AUTO: as mr_mlp_predict). MR_ERR_UNSUPPORTED for a kernel this CPU
 * cannot run (mr_mlp_kernel_available), MR_ERR_INVALID_ARG outside the enum; mr_mlp_kernel_auto's error for AUTO
 * (n = 0 still does nothing and succeeds). */
mr_status mr_mlp_predict_kernel(const mr_mlp *net, const float *in, size_t n, float *out, int max_team,
                                mr_mlp_kernel kernel);

/* The loss of `net` on n rows (x: n x n_in raw inputs, y: n x n_out raw targets): the mean over rows and
 * outputs of ((prediction - y) / out_std)^2, accumulated in double in row order (the same for any thread
 * count). This is the training loss measured on the float network. Rows with NaN make it NaN. Errors as for
 * mr_mlp_predict, plus MR_ERR_INVALID_ARG for n = 0; *mse is written only on success. */
mr_status mr_mlp_evaluate(const mr_mlp *net, const float *x, const float *y, size_t n, double *mse);

/* ---- training ------------------------------------------------------------------------------------------ */

/* Why training stopped. */
typedef enum mr_mlp_stop {
    MR_MLP_STOP_MAX_EPOCHS = 0, /* max_epochs done */
    MR_MLP_STOP_PATIENCE,       /* `patience` epochs without a new best validation loss */
    MR_MLP_STOP_CALLBACK,       /* the epoch callback returned non-zero */
    MR_MLP_STOP_DIVERGED,       /* a loss became NaN or infinite (learning rate too high?) */
    MR_MLP_STOP_COUNT
} mr_mlp_stop;

/* "max-epochs", "patience", "callback", "diverged"; "unknown" outside the enum. */
const char *mr_mlp_stop_str(mr_mlp_stop stop);

/* What the epoch callback sees. Losses are in normalised output units (header comment). */
typedef struct mr_mlp_epoch {
    int epoch;                   /* 0: the initial weights, before any step; then 1, 2, ... */
    int max_epochs;              /* the resolved limit, for progress bars */
    double train_loss;           /* this epoch's training loss */
    double validation_loss;      /* validation loss after this epoch */
    int best_epoch;              /* the epoch with the lowest validation loss so far (may be this one) */
    double best_validation_loss;
} mr_mlp_epoch;

/* Called after epoch 0 and after every epoch, on the calling thread, outside any parallel region. Return 0 to
 * go on, non-zero to stop (the best weights so far are returned, with MR_MLP_STOP_CALLBACK). */
typedef int (*mr_mlp_epoch_fn)(const mr_mlp_epoch *epoch, void *user);

/* Zero-initialised = defaults. Negative or non-finite values are MR_ERR_INVALID_ARG. */
typedef struct mr_mlp_train_options {
    int n_hidden;                /* hidden units, <= MR_MLP_MAX_HIDDEN; 0 = 300 */
    int batch_size;              /* rows per Adam step; 0 = 64 */
    int max_epochs;              /* 0 = 200 */
    int patience;                /* epochs without a new best validation loss before stopping; 0 = 20 */
    double validation_fraction;  /* share of rows held out, < 1; 0 = 0.1 */
    double learning_rate;        /* Adam's alpha; 0 = 1e-3 */
    double beta1;                /* first-moment decay, < 1; 0 = 0.9 */
    double beta2;                /* second-moment decay, < 1; 0 = 0.999 */
    double epsilon;              /* added to sqrt(v_hat); 0 = 1e-8 */
    unsigned long long seed;     /* split, initialisation and shuffles; every value (0 included) is a seed */
    int threads;                 /* OpenMP threads; 0 = automatic (mr_auto_threads: a team of omp_get_max_threads()
                                    for any training set; each loop forks only for two chunks or more); results
                                    do not depend on it */
    mr_mlp_epoch_fn epoch_fn;    /* optional progress / loss-curve callback */
    void *epoch_user;            /* passed to epoch_fn */
} mr_mlp_train_options;

/* How a training run went. */
typedef struct mr_mlp_train_report {
    size_t n_train, n_validation;    /* rows in each split */
    int epochs;                      /* epochs completed */
    int best_epoch;                  /* the epoch whose weights were returned (0: the initial ones) */
    double initial_train_loss;       /* epoch 0 */
    double initial_validation_loss;  /* epoch 0 */
    double final_train_loss;         /* the last completed epoch's (epoch 0's if none) */
    double best_validation_loss;     /* of the returned weights, in double before the rounding to float */
    mr_mlp_stop stop;
} mr_mlp_train_report;

/* Train a network of n_in inputs, opts->n_hidden ReLU units and n_out outputs on n rows (x: n x n_in raw
 * inputs, y: n x n_out raw targets, row-major floats), as described in the header comment. opts may be NULL
 * (defaults). On MR_OK *out receives the network with the best validation loss (the caller's: mr_mlp_free)
 * and *report (may be NULL) how it went; the callback stopping the run, or a diverging loss, is still MR_OK
 * (see report->stop). Errors: MR_ERR_INVALID_ARG (NULL arrays, n < 2, sizes or options out of range, a
 * non-finite value in x or y — the message names its row and column), MR_ERR_NOMEM; *out and *report are
 * untouched on failure. */
mr_status mr_mlp_train(const float *x, const float *y, size_t n, int n_in, int n_out,
                       const mr_mlp_train_options *opts, mr_mlp **out, mr_mlp_train_report *report);

/* ---- weight files -------------------------------------------------------------------------------------- */

/* Write `net` to `path` in the format of the header comment, atomically (temporary file + rename).
 * MR_ERR_INVALID_ARG for a bad network (sizes, a non-finite value or a std <= 0: the message names it),
 * MR_ERR_IO naming the path and the system's reason, MR_ERR_NOMEM. On failure no file is created and an
 * existing one is left as it was. */
mr_status mr_mlp_write(const mr_mlp *net, const char *path);

/* The network at `path` (mr_mlp_write) with its training's loss curve, all or none: PREFIX.csv (a header
 * "epoch,train_loss,validation_loss,best_epoch", then one line per epochs[0..count), %.9g in the C locale) and
 * PREFIX.svg (train and validation loss against the epoch, log scale, titled `title`, drawn by gnuplot when it runs:
 * *drawn = 1; else 0 and only the CSV). The curve is prepared as temporary files, the network written, then the
 * curve renamed into place; a failure at any step leaves none of the three (a network already renamed is removed).
 * prefix_hint names the prefix in messages ("HINT 'PREFIX': the name is too long"; NULL: "loss curve"). drawn may be
 * NULL. MR_ERR_INVALID_ARG for NULL net, path, prefix or epochs (with count > 0); MR_ERR_IO naming a file that
 * cannot be written; mr_mlp_write's errors. */
mr_status mr_mlp_write_with_curve(const mr_mlp *net, const char *path, const mr_mlp_epoch *epochs, int count,
                                  const char *prefix, const char *prefix_hint, const char *title, int *drawn);

/* The weight file's text in memory (*text malloc'ed, NUL-terminated, the caller frees it; *length may be NULL):
 * exactly the bytes mr_mlp_write writes, for formats that embed a network (src/learn/learned.h). `name` labels
 * errors (NULL = "<memory>"). Errors as mr_mlp_write's, without MR_ERR_IO. */
mr_status mr_mlp_format(const mr_mlp *net, const char *name, char **text, size_t *length);

/* Read a weight file. MR_ERR_IO (cannot open or read, naming the path), MR_ERR_FORMAT (naming the path and
 * line: see the header comment), MR_ERR_NOMEM. On success *out is the caller's (mr_mlp_free); on failure it
 * is untouched. */
mr_status mr_mlp_read(const char *path, mr_mlp **out);

/* Parse `size` bytes of weight-file text (as mr_mlp_read does after reading the file; `name` stands for the
 * file in messages, NULL = "<memory>"). Same errors and ownership as mr_mlp_read, without MR_ERR_IO. */
mr_status mr_mlp_parse(const char *text, size_t size, const char *name, mr_mlp **out);

#ifdef __cplusplus
}
#endif

#endif /* MR_MLP_H */
