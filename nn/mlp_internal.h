/*
 * mlp_internal.h — pieces of nn/ shared between its C files and tests/test_nn.c; not installed, not public.
 *
 * Division of labour (the public contract is mlp.h):
 *   mlp.c      the float network: create/free, batched inference (mr_mlp_predict), evaluation; and the double
 *              forward/backward pass that training uses (mr_mlp_sse_grad);
 *   train.c    data checks, split, normalisation, initialisation, Adam, minibatches, early stopping;
 *   weights.c  the weight file: formatting, parsing, atomic writes.
 *
 * Training works on a flat double parameter vector with the same layout as mr_mlp's first four arrays:
 * w1 [n_in][n_hidden], b1 [n_hidden], w2 [n_out][n_hidden], b2 [n_out].
 */
#ifndef MR_MLP_INTERNAL_H
#define MR_MLP_INTERNAL_H

#include <stddef.h>
#include <stdint.h>

#include "mlp.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct mr_mlp_dims {
    int n_in, n_hidden, n_out;
} mr_mlp_dims;

/* Offsets into the parameter vector, and its length. */
static inline size_t mr_mlp_off_b1(const mr_mlp_dims *d) { return (size_t)d->n_in * (size_t)d->n_hidden; }
static inline size_t mr_mlp_off_w2(const mr_mlp_dims *d) { return mr_mlp_off_b1(d) + (size_t)d->n_hidden; }
static inline size_t mr_mlp_off_b2(const mr_mlp_dims *d) {
    return mr_mlp_off_w2(d) + (size_t)d->n_out * (size_t)d->n_hidden;
}
static inline size_t mr_mlp_dims_params(const mr_mlp_dims *d) { return mr_mlp_off_b2(d) + (size_t)d->n_out; }

/* MR_OK if 1 <= n_in, n_out <= MR_MLP_MAX_IO and 1 <= n_hidden <= MR_MLP_MAX_HIDDEN; else MR_ERR_INVALID_ARG
 * naming `what` and the bad size. */
mr_status mr_mlp_check_dims(const char *what, int n_in, int n_hidden, int n_out);

/* Doubles of scratch mr_mlp_sse_grad needs. */
static inline size_t mr_mlp_work_doubles(const mr_mlp_dims *d) { return 3 * (size_t)d->n_hidden + (size_t)d->n_out; }

/* The sum of squared errors E = sum over the n rows and the n_out outputs of (v - t)^2, for normalised inputs
 * x (n x n_in) and normalised targets t (n x n_out, row-major doubles), of the network with parameters
 * `params` (layout above), computed in double; rows are taken in order. If grad is not NULL, dE/dparams is
 * ADDED to grad[0 .. mr_mlp_dims_params(d) - 1]. The ReLU's derivative at 0 is taken as 0. work holds
 * mr_mlp_work_doubles(d) doubles. */
double mr_mlp_sse_grad(const mr_mlp_dims *d, const double *params, const double *x, const double *t, size_t n,
                       double *grad, double *work);

#ifdef __cplusplus
}
#endif

#endif /* MR_MLP_INTERNAL_H */
