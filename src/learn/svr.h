/*
 * svr.h — epsilon-SVR with RBF kernels, one model per output, for learned transforms between BRDF models (paper
 * section 5.1; issue 15, `matremap learn --method svr`). Training goes through libsvm (Chang and Lin, "LIBSVM: a
 * library for support vector machines", ACM TIST 2011); prediction is our own. Internal for now (not installed).
 *
 * Main calls:
 *   mr_svr_train_options o = {0};                   // zero = defaults (each field says what 0 means)
 *   o.seed = 7;  o.progress = draw_bar;  o.progress_user = &bar;
 *   mr_svr *m = NULL;  mr_svr_train_report r;
 *   mr_svr_train(x, y, n, 4, 4, &o, &m, &r);        // x: n x 4 source parameters, y: n x 4 target ones, raw
 *   mr_svr_predict(m, in, count, out);               // in: count x n_in raw values, out: count x n_out raw values
 *   mr_svr_free(m);
 *
 * The model. For one row x (n_in raw values):
 *   u_i = (x_i - in_mean[i]) / in_std[i]                                    normalised input
 *   v_k = sum over s < sv_count of coef[s] exp(-gamma |sv_s - u|^2) - rho   output k's SVR (fields of outputs[k])
 *   y_k = out_mean[k] + out_std[k] v_k                                      raw output
 * with |sv_s - u|^2 = sum over i in index order of (u_i - sv[s * n_in + i])^2, the kernel terms added in SV order,
 * one rounding per operation (ISO C mode, no fused multiply-add): the order of libsvm's svm_predict on the same
 * model. The exponential is our own, within 1 ulp of glibc's exp (it vectorises; exp() calls took most of the
 * time), so a prediction equals svm_predict's to about 1e-16 of out_std sum |coef| (tests/test_svr.c: 1e-12 is
 * asserted; most predictions are the same bits). Every output has its own support vectors, coefficients and
 * hyper-parameters. Outputs are not clamped.
 *
 * Plain data. mr_svr and everything it points to is one allocation (the struct, the outputs array, then the
 * doubles: in_mean, in_std, out_mean, out_std, then each output's sv and coef in output order), so a reader builds
 * one with mr_svr_alloc, fills the fields and checks it with mr_svr_check, and a writer walks the fields. Values may
 * be changed in place; pointers and sizes may not. Nothing refers to libsvm: a file of these fields (hexadecimal
 * floats) reproduces the model's predictions bit for bit.
 *
 * Extrapolation. Every kernel term vanishes far from the support vectors, so far outside the training data
 * v_k -> -rho and y_k -> out_mean[k] - out_std[k] rho (mr_svr_far_field): the SVR falls back to a constant near
 * the mean of the training outputs instead of continuing the trend. This is the paper's Fig. 19 failure (a specular
 * colour beyond the training range loses its chromaticity), kept on purpose and tested: the transform layer flags
 * texels outside the training domain. An infinite input gives exactly the far field (so does any input whose terms
 * all fall below e^-708); a NaN input gives NaN in every output of its row.
 *
 * Normalisation. mr_svr_train computes each input and output column's mean and population standard deviation over
 * the training split (below), in double in row order. A column whose deviation is not above 1e-12 max(1, |mean|)
 * (constant, as a parameter held fixed in a sweep) gets std 1. libsvm then fits the normalised rows, so C, gamma and
 * epsilon are in normalised units: gamma per squared standard deviation of the inputs, epsilon in standard
 * deviations of the output.
 *
 * Training (mr_svr_train).
 *   - Split: a seeded shuffle of the rows (splitmix64); the first round(validation_fraction n) (at least 1, at most
 *     n - 1) are the validation split, the rest the training split. The split also fixes the normalisation.
 *   - A candidate (C, gamma, epsilon) of an output is scored by one libsvm EPSILON_SVR fit (RBF kernel, shrinking,
 *     stopping tolerance 1e-3, libsvm's default; a kernel cache of the whole l x l matrix up to MR_SVR_CACHE_MB) on
 *     the search rows: the first search_rows (default MR_SVR_SEARCH_ROWS) of the shuffled training split; the score
 *     is the root mean square error on the validation split, in normalised units.
 *   - Cost. libsvm's SMO solver slows down sharply where the fit nears an interpolation (large C, small epsilon,
 *     wide kernels: noise-free sweeps invite it). For 720 rows of a smooth 4 x 4 remap (gamma 1/4, epsilon 1e-3)
 *     a fit took 44 thousand iterations (0.5 s) at C = 4, 0.7 million (10 s) at C = 64 and 7.9 million (57 s, and a
 *     worse validation error) at C = 1024; at 10^7 libsvm stops and prints a warning to stderr that no callback
 *     silences. The search bounds this by libsvm's own iteration count (from its report of each fit, so
 *     deterministic): a fit of more than MR_SVR_ITERATIONS_PER_ROW iterations per search row plus
 *     MR_SVR_ITERATIONS_MIN is too costly and scores +inf (report->costly_fits), and the search avoids the fits that
 *     would be, as below. Where the validation error still falls beyond that boundary, the choice is the best
 *     affordable one.
 *   - Grid: log2 C in -2, 0, ..., 12; log2 gamma in -8, -6, ..., 4; log10 epsilon in -4, -3, -2, -1 (224 cells per
 *     output). Why these ranges: outputs have unit deviation, so C = 2^-2 already lets a coefficient reach a quarter
 *     of it (heavily regularised) and 2^12 makes the fit an interpolation of noise-free sweeps; inputs have unit
 *     deviation, so with n_in = 1..6 a squared distance across the data is ~2 n_in and gamma = 2^-8 is a kernel much
 *     wider than the data (nearly polynomial: best where an output depends on one input of several, as the target
 *     roughness on the source roughness alone), 2^4 one a quarter of a deviation wide (finer than the spacing of a
 *     few thousand rows in four dimensions); epsilon = 1e-4 of a deviation is below the noise of optimiser-made
 *     sweeps, 1e-1 a coarse tube for noisy ones. For each (gamma, epsilon) the C values are fitted in increasing
 *     order: after a fit with no coefficient at the bound C, larger C values have the same solution and take its
 *     score unfitted; after a fit of more than a quarter of the cap (iterations grow about as C there, and the grid
 *     steps C by 4), the larger ones would exceed the cap and score +inf unfitted.
 *   - Local search: from the best grid cell and up to MR_SVR_STARTS - 1 further cells that are better than their
 *     grid neighbours (in order of validation error), a compass search in (log2 C, log2 gamma, log10 epsilon):
 *     poll the two neighbours at +-step on each axis, move to the best poll if it lowers the validation error,
 *     else halve the step; steps start at half the grid spacing (1, 1, 0.5) and the search ends after failing at a
 *     quarter of that, or after MR_SVR_MAX_ROUNDS rounds. It may leave the grid by one spacing on every side (C
 *     2^-4..2^14, gamma 2^-10..2^6, epsilon 1e-5..1). Neighbours in a costlier direction (larger C or gamma, smaller
 *     epsilon) of a centre whose fit took over half the cap are not polled. Candidates already scored are not
 *     fitted again. The chosen point is the lowest score of all candidates of the output (the first scored among
 *     ties, so the smaller C on a grid line), never worse than the grid's best: outputs[k].grid_rmse against
 *     outputs[k].validation_rmse says what the local search gained. (The paper tuned the three by "simple gradient
 *     descent"; the validation error of an SVR is piecewise smooth and full of plateaus in these parameters, where
 *     a grid then a derivative-free local search is the usual remedy: Hsu, Chang, Lin, "A practical guide to
 *     support vector classification", 2003.)
 *   - Fixed hyper-parameters: a C, gamma or epsilon set in the options is used for every output and not searched
 *     (the grid and the search run over the others; with all three fixed, one fit per output is scored, uncapped).
 *   - Validation error reported: when the search rows are the whole training split, the chosen candidate's score;
 *     otherwise the chosen hyper-parameters are fitted once more on the whole training split and scored (honest for
 *     the final model's size; grid_rmse is then from the search rows and may exceed or undercut it).
 *   - Refit: each output is finally fitted with its chosen hyper-parameters on all n rows (training and validation
 *     splits, still normalised with the training split's statistics): the validation rows are sweep data too, and a
 *     transform wants every sample. These fits are not capped; their hyper-parameters cost at most the cap on the
 *     search rows, far below libsvm's own limit of 10^7 iterations, so its warning is not reached in practice.
 *
 * Determinism. The split is the only random draw (from opts->seed). Every fit is a libsvm call on the same data in
 * the same order, which is deterministic, and so are its iteration counts; scores are stored by candidate and
 * compared in a fixed order, so the same seed gives the same model bits whatever the thread count (tests/test_svr.c
 * checks 1, 2 and 3 threads). Prediction: each row's outputs are the same bits whatever the other rows, the thread
 * count and the CPU (on x86-64 Linux an AVX2 variant is chosen at run time; it rounds exactly as the SSE2 one).
 *
 * Threads. Candidates are independent: the grid lines of all outputs, each round of the local search (the polls of
 * every start of every output) and the final fits run on opts->threads OpenMP threads (0 = automatic, all of them),
 * one libsvm fit per thread at a time, each with its own kernel cache. mr_svr_predict splits blocks of rows over
 * omp_get_max_threads() threads, one per MR_SVR_PREDICT_ROWS rows at most (a team costs more than fewer rows save).
 * All functions are reentrant and a model may be shared by threads for reading. libsvm prints through one
 * process-wide function pointer: the first mr_svr_train points it, once, at a function that prints nothing (it
 * reads the iteration counts the cost cap needs) and leaves it so; other libsvm users in the process are silenced
 * too, and must not replace it (the cap would go blind: report->iterations would stay 0).
 *
 * Ownership. A model returned through `mr_svr **out` belongs to the caller and is released, with everything it
 * points to, by mr_svr_free() (NULL-safe). The library keeps no pointer to caller arrays after a call returns, and
 * no libsvm model outlives the call that trained it (support vectors and coefficients are copied out).
 *
 * Errors. MR_ERR_INVALID_ARG with the value named (NULL arrays, sizes out of range, options out of range, a
 * non-finite training value by row and column, a hyper-parameter libsvm's svm_check_parameter refuses, a model that
 * fails mr_svr_check); MR_ERR_NUMERIC (no candidate of an output gives a finite validation error); MR_ERR_NOMEM;
 * MR_ERR_CANCELLED when the progress callback asks to stop. Nothing is printed. Out-pointers are untouched on
 * failure.
 */
#ifndef MR_LEARN_SVR_H
#define MR_LEARN_SVR_H

#include <stddef.h>

#include "../mr_status.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MR_SVR_MAX_IO 1024          /* largest n_in or n_out */
#define MR_SVR_MAX_ROWS 1000000     /* most training rows (libsvm counts in int; the fit is O(rows^2) anyway) */
#define MR_SVR_DEFAULT_VALIDATION 0.2
#define MR_SVR_STARTS 2             /* local searches per output */
#define MR_SVR_MAX_ROUNDS 40        /* rounds of the local search */
#define MR_SVR_CACHE_MB 128         /* largest libsvm kernel cache per fit */
#define MR_SVR_PREDICT_ROWS 256     /* rows a prediction thread must have */
#define MR_SVR_SEARCH_ROWS 1000     /* training rows the search fits on, by default */
#define MR_SVR_ITERATIONS_PER_ROW 50 /* the cap: a search fit of more libsvm iterations than this per search */
#define MR_SVR_ITERATIONS_MIN 10000  /* row plus this is too costly and scores +inf (header comment) */

/* One output's epsilon-SVR (header comment). */
typedef struct mr_svr_output {
    int sv_count;           /* support vectors, >= 0 (0: the output is the constant -rho) */
    double *sv;             /* [sv_count][n_in] normalised inputs */
    double *coef;           /* [sv_count] dual coefficients alpha_s - alpha_s*, each in [-C, C] when trained */
    double rho;             /* v = sum coef_s K(sv_s, u) - rho, in normalised output units */
    double gamma;           /* the RBF kernel's exp(-gamma |sv - u|^2), > 0 */
    double C, epsilon;      /* training record: the penalty and tube half-width chosen (normalised units) */
    double validation_rmse; /* training record: root mean square validation error of the choice, raw units */
    double grid_rmse;       /* training record: the same for the grid's best cell, before the local search */
} mr_svr_output;

/* A trained model: plain data in one block (header comment). */
typedef struct mr_svr {
    int n_in, n_out;
    double *in_mean, *in_std;   /* [n_in]; u = (x - in_mean) / in_std, in_std > 0 */
    double *out_mean, *out_std; /* [n_out]; y = out_mean + out_std v, out_std > 0 */
    mr_svr_output *outputs;     /* [n_out] */
} mr_svr;

/* A model of the given sizes (sv_counts[k] support vectors for output k) in one block: means 0, deviations 1,
 * support vectors, coefficients and rho 0, gamma 1, the training record 0 (it predicts zeros). For a reader of
 * model files. MR_ERR_INVALID_ARG (sizes out of range: 1..MR_SVR_MAX_IO, 0..MR_SVR_MAX_ROWS support vectors),
 * MR_ERR_NOMEM. On success *out is the caller's (mr_svr_free); on failure it is untouched. */
mr_status mr_svr_alloc(int n_in, int n_out, const int *sv_counts, mr_svr **out);

/* Release a model and everything it points to. NULL is fine. */
void mr_svr_free(mr_svr *m);

/* Whether `m` is a usable model: sizes in range, no NULL array, every value finite, deviations and gammas > 0
 * (C, epsilon and the training record may be anything finite). MR_ERR_INVALID_ARG names the first bad field
 * ("svr: output 2: gamma -1 (expected > 0)"). */
mr_status mr_svr_check(const mr_svr *m);

/* Run count rows through the model: in is count x n_in raw inputs, out receives count x n_out raw outputs
 * (row-major, not overlapping). count = 0 does nothing (in and out may then be NULL). Each row's outputs are the
 * same bits whatever the other rows and the thread count. Checks the model's shape, not its values (mr_svr_check
 * does). MR_ERR_INVALID_ARG (NULL or inconsistent model, NULL arrays, count x n_in overflowing size_t),
 * MR_ERR_NOMEM; out is untouched on failure. */
mr_status mr_svr_predict(const mr_svr *m, const double *in, size_t count, double *out);

/* mr_svr_predict on at most max_team threads (0 = automatic, mr_auto_threads: omp_get_max_threads()), still one
 * per MR_SVR_PREDICT_ROWS rows at most. */
mr_status mr_svr_predict_threads(const mr_svr *m, const double *in, size_t count, double *out, int max_team);

/* Output k's value far from every support vector (an infinite input): out_mean[k] - out_std[k] rho. */
double mr_svr_far_field(const mr_svr *m, int k);

/* ---- training ------------------------------------------------------------------------------------------ */

typedef enum mr_svr_phase {
    MR_SVR_PHASE_GRID = 0, /* scoring the grid's cells */
    MR_SVR_PHASE_LOCAL,    /* the local search's rounds */
    MR_SVR_PHASE_REFIT,    /* fitting every output on all rows */
    MR_SVR_PHASE_COUNT
} mr_svr_phase;

/* What the progress callback sees. */
typedef struct mr_svr_progress {
    mr_svr_phase phase;
    long done;         /* candidates of this phase scored so far (fitted, or scored without a fit) */
    long planned;      /* the phase's candidates as known now (the local search learns its own as it goes) */
    double seconds;    /* since mr_svr_train began */
} mr_svr_progress;

/* Called on the calling thread, outside any parallel region, after each batch of fits. Return 0 to go on,
 * non-zero to stop (mr_svr_train then returns MR_ERR_CANCELLED). */
typedef int (*mr_svr_progress_fn)(const mr_svr_progress *progress, void *user);

/* Zero-initialised = defaults. Negative or non-finite values are MR_ERR_INVALID_ARG. */
typedef struct mr_svr_train_options {
    double validation_fraction; /* share of rows held out, < 1; 0 = 0.2 */
    unsigned long long seed;    /* the split; every value (0 included) is a seed */
    int threads;                /* OpenMP threads; 0 = automatic (mr_auto_threads: a team of omp_get_max_threads()
                                   for any training set, the search's candidates shared); results do not depend
                                   on it */
    double C;                   /* > 0: this penalty for every output, not searched; 0 = search */
    double gamma;               /* > 0: this kernel width (normalised units), not searched; 0 = search */
    double epsilon;             /* > 0: this tube half-width (normalised units), not searched; 0 = search */
    int search_rows;            /* training rows the search fits on; 0 = MR_SVR_SEARCH_ROWS */
    mr_svr_progress_fn progress;
    void *progress_user;
} mr_svr_train_options;

/* How a training run went (per output, the model's training record). */
typedef struct mr_svr_train_report {
    size_t n_train, n_validation; /* rows in each split */
    size_t n_search;              /* training rows the search fitted on */
    long grid_fits;               /* libsvm fits made for the grid (all outputs) */
    long local_fits;              /* and for the local search */
    long costly_fits;             /* of those, fits above the iteration cap (scored +inf) */
    long long iterations;         /* libsvm's iterations over the search's fits */
    int local_rounds;             /* rounds of the local search */
    double seconds;               /* wall time of the whole call */
} mr_svr_train_report;

/* Train one epsilon-SVR per output on n rows (x: n x n_in raw inputs, y: n x n_out raw targets, row-major) as in
 * the header comment. opts may be NULL (defaults). On MR_OK *out receives the model (the caller's: mr_svr_free) and
 * *report (may be NULL) how it went. Errors: MR_ERR_INVALID_ARG (NULL arrays, n < 2 or above MR_SVR_MAX_ROWS, sizes
 * or options out of range, a non-finite value in x or y — the message names its row and column), MR_ERR_NOMEM,
 * MR_ERR_CANCELLED; *out and *report are untouched on failure. */
mr_status mr_svr_train(const double *x, const double *y, size_t n, int n_in, int n_out,
                       const mr_svr_train_options *opts, mr_svr **out, mr_svr_train_report *report);

#ifdef __cplusplus
}
#endif

#endif /* MR_LEARN_SVR_H */
