/*
 * mlp.c — the network object, batched float inference and the double forward/backward pass used by training
 * (contracts in mlp.h and mlp_internal.h).
 *
 * Inference puts rows in the vector lanes. A block of `lanes` rows is transposed into xt[n_in][lanes] and
 * normalised there (a vector subtract and divide per input); then for each hidden unit j the pre-activations of the
 * block's rows are summed over the inputs with w1[i][j] broadcast (a vector multiply-add per input), passed through
 * the ReLU and at once added, times w2[k][j], into the accumulators of each output k. Every inner loop runs over
 * the rows of a block, a compile-time constant, so GCC vectorises it completely (no reduction, no remainder) and
 * each row's arithmetic is the scalar order of mlp.h, the same bits in any lane, block or thread. For the design
 * card's 6 x H x 4 the input and output loops are unrolled with the sizes as constants, so the six inputs and four
 * accumulators stay in registers and the hidden loop does only broadcasts and 10 multiply-adds per vector of rows.
 *
 * The kernels (mr_mlp_kernel, mlp.h). The library is compiled for baseline x86-64 (SSE2); on x86-64 Linux with GCC
 * the block loop also exists compiled for x86-64-v3 (AVX2 + FMA: 16 registers of 8 floats) and x86-64-v4 (AVX-512:
 * 32 registers of 16 floats), chosen at run time with __builtin_cpu_supports, or forced by MR_MLP_KERNEL.
 *   - AVX512 and AVX2, the defaults where the CPU has them, fuse each product into its sum (fmaf, which GCC turns
 *     into vfmadd231ps with the weight broadcast from memory) and read the weights from the network's packed copy
 *     (struct mr_mlp_packed below: per hidden unit its n_in input weights, bias and n_out output weights, one
 *     stream; made once when the network is read or trained, checked against the values at each call). A fused
 *     multiply-add rounds once where the unfused loop rounds twice, so the outputs differ from the unfused ones by
 *     rounding: for the shipped spec2metal network on 4 M random texels by at most ~1e-6 (bench_workflow
 *     prints the largest difference); tests/test_nn.c checks every row against Higham's bound (2 gamma_m S, its
 *     fused_tolerance) and each kernel bit for bit against its scalar reference, so AVX512 and AVX2 agree bit for
 *     bit.
 *   - SSE2 (the baseline build; CPUs without FMA) and EXACT (the same unfused loop at the CPU's widest vectors) keep
 *     the rounding of earlier versions: every product and sum rounded (ISO C mode: -ffp-contract=off), identical
 *     bits on every CPU.
 * Block sizes keep a variant's inputs, accumulators and hidden values in registers. Unfused, measured for
 * 6 x 300 x 4 on one core of a Xeon with AVX-512, best of runs on a shared machine: SSE2 8 rows 3.0 M rows/s, 16 rows
 * 1.4 M, 4 rows 2.6 M; AVX2 8 rows 6.2 M, 16 rows 5.3 M; AVX-512 32 rows 9.3 M, 16 rows 7.9 M; on AMD Zen 3 (AVX2,
 * no AVX-512) 16 rows win instead (one core, quiet: 8.0-9.2 M rows/s against 6.4-7.2 M for 8 rows), so AMD CPUs get
 * an unfused AVX2 variant of their own. Fused, on AMD Zen 5 (EPYC, 2 FMA units of 16 floats at ~4.1 GHz: a peak of
 * ~131 G FMA/s or ~44 M rows/s per core), per CPU-second of one core on a busy machine: AVX-512 32 rows 33.5 M rows/s
 * (EXACT 27.1 M), AVX2 16 rows 17.7 M, 8 rows 16.9 M.
 *
 * Training's pass (mr_mlp_sse_grad) keeps the hidden dimension contiguous instead: w1 is [n_in][n_hidden], so
 * the forward sum, the backward products and the weight-gradient updates are all unit-stride loops over j.
 * The output sums use eight fixed partial sums (a fixed order, so still deterministic) to break the dependency
 * chain of one long double-precision sum.
 */
#include "mlp_internal.h"

#include <limits.h>
#include <math.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#ifdef _OPENMP
#include <omp.h>
#endif

#include "../src/mr_internal.h"

/* Rows per inference block of each variant (see the top of the file); MAX_LANES bounds them all. */
#define LANES_BASE 8
#define LANES_V3 8
#define LANES_V3_ZEN 16
#define LANES_V4 32
#define LANES_FUSED_V3 16
#define LANES_FUSED_V4 32
#define MAX_LANES 32
/* Rows a thread must have to be started (~256 x 120 ns of 6 x 300 x 4 work, many times a team's start-up). */
#define PREDICT_ROWS_PER_THREAD 256
/* Rows per predict call inside mr_mlp_evaluate. */
#define EVAL_ROWS 4096

#if defined(__GNUC__) && !defined(__clang__)
#define MR_ALWAYS_INLINE inline __attribute__((always_inline))
#define MR_UNROLL _Pragma("GCC unroll 8")
#else
#define MR_ALWAYS_INLINE inline
#define MR_UNROLL
#endif

/* Per-CPU variants (see the top of the file): explicit ones for inference, GCC target_clones for the training
 * pass. MR_MLP_NO_CLONES turns both off. */
#if defined(__GNUC__) && !defined(__clang__) && __GNUC__ >= 12 && defined(__x86_64__) && defined(__linux__) && \
    !defined(MR_MLP_NO_CLONES)
#define MR_MLP_MULTIVERSION 1
#define MR_MLP_TARGET(arch) __attribute__((target(arch)))
#define MR_MLP_CLONES __attribute__((target_clones("arch=x86-64-v4", "arch=x86-64-v3", "default")))
#else
#define MR_MLP_MULTIVERSION 0
#define MR_MLP_CLONES
#endif

static int thread_id(void) {
#ifdef _OPENMP
    return omp_get_thread_num();
#else
    return 0;
#endif
}

/* ---- the object ------------------------------------------------------------------------------------------- */

mr_status mr_mlp_check_dims(const char *what, int n_in, int n_hidden, int n_out) {
    if (n_in < 1 || n_in > MR_MLP_MAX_IO)
        return mr_fail(MR_ERR_INVALID_ARG, "%s: %d inputs (expected 1 to %d)", what, n_in, MR_MLP_MAX_IO);
    if (n_hidden < 1 || n_hidden > MR_MLP_MAX_HIDDEN)
        return mr_fail(MR_ERR_INVALID_ARG, "%s: %d hidden units (expected 1 to %d)", what, n_hidden,
                       MR_MLP_MAX_HIDDEN);
    if (n_out < 1 || n_out > MR_MLP_MAX_IO)
        return mr_fail(MR_ERR_INVALID_ARG, "%s: %d outputs (expected 1 to %d)", what, n_out, MR_MLP_MAX_IO);
    mr_mlp_dims d = {n_in, n_hidden, n_out};
    if (mr_mlp_dims_params(&d) > (size_t)MR_MLP_MAX_PARAMS)
        return mr_fail(MR_ERR_INVALID_ARG, "%s: %dx%dx%d has %zu parameters (at most %ld)", what, n_in, n_hidden,
                       n_out, mr_mlp_dims_params(&d), MR_MLP_MAX_PARAMS);
    return MR_OK;
}

mr_status mr_mlp_create(int n_in, int n_hidden, int n_out, mr_mlp **out) {
    if (out == NULL) return mr_fail(MR_ERR_INVALID_ARG, "mlp create: NULL output pointer");
    mr_status status = mr_mlp_check_dims("mlp create", n_in, n_hidden, n_out);
    if (status != MR_OK) return status;
    mr_mlp_dims d = {n_in, n_hidden, n_out};
    size_t params = mr_mlp_dims_params(&d);
    size_t count = params + 2 * (size_t)n_in + 2 * (size_t)n_out;
    mr_mlp *net = calloc(1, sizeof *net);
    if (net == NULL) return mr_fail(MR_ERR_NOMEM, "mlp create: out of memory");
    net->data = calloc(count, sizeof(float));
    if (net->data == NULL) {
        free(net);
        return mr_fail(MR_ERR_NOMEM, "mlp create: out of memory for %zu floats", count);
    }
    net->n_in = n_in;
    net->n_hidden = n_hidden;
    net->n_out = n_out;
    net->data_count = count;
    net->w1 = net->data;
    net->b1 = net->data + mr_mlp_off_b1(&d);
    net->w2 = net->data + mr_mlp_off_w2(&d);
    net->b2 = net->data + mr_mlp_off_b2(&d);
    net->in_mean = net->data + params;
    net->in_std = net->in_mean + n_in;
    net->out_mean = net->in_std + n_in;
    net->out_std = net->out_mean + n_out;
    for (int i = 0; i < n_in; i++) net->in_std[i] = 1.0f;
    for (int k = 0; k < n_out; k++) net->out_std[k] = 1.0f;
    *out = net;
    return MR_OK;
}

void mr_mlp_free(mr_mlp *net) {
    if (net == NULL) return;
    free(net->packed);
    free(net->data);
    free(net);
}

size_t mr_mlp_param_count(const mr_mlp *net) {
    if (net == NULL) return 0;
    mr_mlp_dims d = {net->n_in, net->n_hidden, net->n_out};
    return mr_mlp_dims_params(&d);
}

/* A network whose sizes and pointers are consistent (values are not checked). */
static mr_status check_net(const char *what, const mr_mlp *net) {
    if (net == NULL) return mr_fail(MR_ERR_INVALID_ARG, "%s: NULL network", what);
    mr_status status = mr_mlp_check_dims(what, net->n_in, net->n_hidden, net->n_out);
    if (status != MR_OK) return status;
    if (net->w1 == NULL || net->b1 == NULL || net->w2 == NULL || net->b2 == NULL || net->in_mean == NULL ||
        net->in_std == NULL || net->out_mean == NULL || net->out_std == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "%s: network with a NULL array", what);
    return MR_OK;
}

/* ---- packed weights ----------------------------------------------------------------------------------------- */

/* The fused kernels read, per hidden unit j, its n_in input weights, its bias and its n_out output weights, in
 * that order: units[j * stride .. j * stride + stride) with stride = n_in + 1 + n_out, one stream the hidden loop
 * walks front to back (the plain layout has them in n_in + n_out + 1 arrays H floats apart). `source` is the copy
 * of net->data they were made from: a prediction compares it with the network's values and packs afresh for the
 * call when they differ, so a network changed in place never predicts with stale weights. */
struct mr_mlp_packed {
    size_t source_count; /* floats in source: net->data_count */
    int stride;
    float *source;
    float *units;        /* n_hidden x stride */
    float *b2;           /* n_out */
};

static size_t packed_floats(const mr_mlp *net) {
    return net->data_count + (size_t)net->n_hidden * (size_t)(net->n_in + 1 + net->n_out) + (size_t)net->n_out;
}

/* Lay net's weights out in `units` and `b2` (floats for the stride-major hidden units, then the output biases). */
static void pack_units(const mr_mlp *net, float *units, float *b2) {
    const size_t H = (size_t)net->n_hidden, stride = (size_t)(net->n_in + 1 + net->n_out);
    for (size_t j = 0; j < H; j++) {
        float *u = units + j * stride;
        for (int i = 0; i < net->n_in; i++) u[i] = net->w1[(size_t)i * H + j];
        u[net->n_in] = net->b1[j];
        for (int k = 0; k < net->n_out; k++) u[net->n_in + 1 + k] = net->w2[(size_t)k * H + j];
    }
    memcpy(b2, net->b2, (size_t)net->n_out * sizeof *b2);
}

/* Are net's packed weights made from its current values? */
static int packed_current(const mr_mlp *net) {
    const struct mr_mlp_packed *p = net->packed;
    return p != NULL && p->source_count == net->data_count &&
           memcmp(p->source, net->data, net->data_count * sizeof(float)) == 0;
}

mr_status mr_mlp_pack(mr_mlp *net) {
    mr_status status = check_net("mlp pack", net);
    if (status != MR_OK) return status;
    if (net->data == NULL || net->data_count == 0) return mr_fail(MR_ERR_INVALID_ARG, "mlp pack: network without data");
    size_t floats = packed_floats(net);
    struct mr_mlp_packed *p = malloc(sizeof *p + floats * sizeof(float));
    if (p == NULL) return mr_fail(MR_ERR_NOMEM, "mlp pack: out of memory for %zu floats", floats);
    p->source_count = net->data_count;
    p->stride = net->n_in + 1 + net->n_out;
    p->source = (float *)(p + 1);
    p->units = p->source + net->data_count;
    p->b2 = p->units + (size_t)net->n_hidden * (size_t)p->stride;
    memcpy(p->source, net->data, net->data_count * sizeof(float));
    pack_units(net, p->units, p->b2);
    free(net->packed);
    net->packed = p;
    return MR_OK;
}

/* ---- inference -------------------------------------------------------------------------------------------- */

/* One block, unfused (the EXACT and SSE2 kernels): xt[n_in][lanes] normalised inputs in, acc[n_out][lanes]
 * normalised outputs out. Inlined with constant sizes (see predict_block). */
static MR_ALWAYS_INLINE void block_kernel(int n_in, int n_hidden, int n_out, const int lanes,
                                          const float *restrict w1, const float *restrict b1,
                                          const float *restrict w2, const float *restrict b2,
                                          const float *restrict xt, float *restrict acc) {
    const size_t H = (size_t)n_hidden;
    MR_UNROLL
    for (int k = 0; k < n_out; k++)
        for (int r = 0; r < lanes; r++) acc[k * lanes + r] = b2[k];
    for (size_t j = 0; j < H; j++) {
        float h[MAX_LANES];
        for (int r = 0; r < lanes; r++) h[r] = b1[j];
        MR_UNROLL
        for (int i = 0; i < n_in; i++) {
            const float w = w1[(size_t)i * H + j];
            for (int r = 0; r < lanes; r++) h[r] += w * xt[i * lanes + r];
        }
        // `h < 0 ? 0 : h` keeps a NaN (mlp.h: NaN propagates); fmaxf would turn it into 0.
        for (int r = 0; r < lanes; r++) h[r] = h[r] < 0.0f ? 0.0f : h[r];
        MR_UNROLL
        for (int k = 0; k < n_out; k++) {
            const float w = w2[(size_t)k * H + j];
            for (int r = 0; r < lanes; r++) acc[k * lanes + r] += w * h[r];
        }
    }
}

/* One block, fused (the AVX2 and AVX-512 kernels): the same sums in the same order, each product added by a
 * fused multiply-add, the weights read from the packed stream. Compiled only for targets with FMA, where GCC
 * turns fmaf over the lanes into vfmadd231ps with the weight broadcast: the hidden unit's bias starts its sum,
 * the ReLU is one compare and masked move on the registers, and the output sums stay in registers. */
static MR_ALWAYS_INLINE void fused_kernel(int n_in, int n_hidden, int n_out, const int lanes,
                                          const float *restrict units, const float *restrict b2,
                                          const float *restrict xt, float *restrict acc) {
    const int stride = n_in + 1 + n_out;
    MR_UNROLL
    for (int k = 0; k < n_out; k++)
        for (int r = 0; r < lanes; r++) acc[k * lanes + r] = b2[k];
    for (int j = 0; j < n_hidden; j++) {
        const float *restrict u = units + (size_t)j * (size_t)stride;
        float h[MAX_LANES];
        for (int r = 0; r < lanes; r++) h[r] = u[n_in];
        MR_UNROLL
        for (int i = 0; i < n_in; i++) {
            const float w = u[i];
            for (int r = 0; r < lanes; r++) h[r] = fmaf(w, xt[i * lanes + r], h[r]);
        }
        for (int r = 0; r < lanes; r++) h[r] = h[r] < 0.0f ? 0.0f : h[r];
        MR_UNROLL
        for (int k = 0; k < n_out; k++) {
            const float w = u[n_in + 1 + k];
            for (int r = 0; r < lanes; r++) acc[k * lanes + r] = fmaf(w, h[r], acc[k * lanes + r]);
        }
    }
}

/* What the inference variants share. */
typedef struct predict_job {
    const mr_mlp *net;
    const float *in;
    size_t n;
    float *out;
    float *ws;           /* per thread (n_in + n_out) * MAX_LANES floats */
    const float *units;  /* the packed weights (fused kernels) */
    const float *b2;
    int threads;
} predict_job;

/* Rows [b * lanes, b * lanes + lanes) (clipped to n): transpose and normalise, run the kernel, denormalise. The
 * transposition is a plain copy and the normalisation then runs over whole lanes (a vector subtract and divide
 * per input: the same correctly rounded (x - mean) / std as one row at a time). */
static MR_ALWAYS_INLINE void predict_block(const predict_job *job, size_t b, const int lanes, const int fused) {
    const mr_mlp *net = job->net;
    const int n_in = net->n_in, n_out = net->n_out;
    float *xt = job->ws + (size_t)thread_id() * (size_t)(n_in + n_out) * MAX_LANES;
    float *acc = xt + (size_t)n_in * (size_t)lanes;
    const size_t row0 = b * (size_t)lanes;
    const int rows = job->n - row0 < (size_t)lanes ? (int)(job->n - row0) : lanes;
    const float *x = job->in + row0 * (size_t)n_in;
    for (int r = 0; r < rows; r++)
        for (int i = 0; i < n_in; i++) xt[i * lanes + r] = x[(size_t)r * (size_t)n_in + (size_t)i];
    for (int i = 0; i < n_in; i++) {
        for (int r = rows; r < lanes; r++) xt[i * lanes + r] = 0.0f;
        const float mean = net->in_mean[i], std = net->in_std[i];
        for (int r = 0; r < lanes; r++) xt[i * lanes + r] = (xt[i * lanes + r] - mean) / std;
    }
    if (fused) {
        if (n_in == 6 && n_out == 4)
            fused_kernel(6, net->n_hidden, 4, lanes, job->units, job->b2, xt, acc);
        else
            fused_kernel(n_in, net->n_hidden, n_out, lanes, job->units, job->b2, xt, acc);
    } else {
        if (n_in == 6 && n_out == 4)
            block_kernel(6, net->n_hidden, 4, lanes, net->w1, net->b1, net->w2, net->b2, xt, acc);
        else
            block_kernel(n_in, net->n_hidden, n_out, lanes, net->w1, net->b1, net->w2, net->b2, xt, acc);
    }
    for (int r = 0; r < rows; r++) {
        float *o = job->out + (row0 + (size_t)r) * (size_t)n_out;
        for (int k = 0; k < n_out; k++) o[k] = net->out_mean[k] + net->out_std[k] * acc[k * lanes + r];
    }
}

/* The variants: the same loop, compiled for different CPUs with their block sizes. Blocks go to threads in
 * contiguous ranges (schedule(static)); which thread computes a row never changes its bits. */
static void predict_base(const predict_job *job) {
    const size_t blocks = (job->n + LANES_BASE - 1) / LANES_BASE;
#pragma omp parallel for num_threads(job->threads) schedule(static) if (job->threads > 1)
    for (size_t b = 0; b < blocks; b++) predict_block(job, b, LANES_BASE, 0);
}

#if MR_MLP_MULTIVERSION
MR_MLP_TARGET("arch=x86-64-v3")
static void predict_v3(const predict_job *job) {
    const size_t blocks = (job->n + LANES_V3 - 1) / LANES_V3;
#pragma omp parallel for num_threads(job->threads) schedule(static) if (job->threads > 1)
    for (size_t b = 0; b < blocks; b++) predict_block(job, b, LANES_V3, 0);
}

/* AMD Zen's vbroadcastss from memory takes a vector pipe, which Intel's load ports do for free: 16 rows per block
 * share each broadcast weight between two vectors of rows and win there, though the rows' inputs then spill. */
MR_MLP_TARGET("arch=x86-64-v3")
static void predict_v3_zen(const predict_job *job) {
    const size_t blocks = (job->n + LANES_V3_ZEN - 1) / LANES_V3_ZEN;
#pragma omp parallel for num_threads(job->threads) schedule(static) if (job->threads > 1)
    for (size_t b = 0; b < blocks; b++) predict_block(job, b, LANES_V3_ZEN, 0);
}

MR_MLP_TARGET("arch=x86-64-v4")
static void predict_v4(const predict_job *job) {
    const size_t blocks = (job->n + LANES_V4 - 1) / LANES_V4;
#pragma omp parallel for num_threads(job->threads) schedule(static) if (job->threads > 1)
    for (size_t b = 0; b < blocks; b++) predict_block(job, b, LANES_V4, 0);
}

MR_MLP_TARGET("arch=x86-64-v3")
static void predict_fused_v3(const predict_job *job) {
    const size_t blocks = (job->n + LANES_FUSED_V3 - 1) / LANES_FUSED_V3;
#pragma omp parallel for num_threads(job->threads) schedule(static) if (job->threads > 1)
    for (size_t b = 0; b < blocks; b++) predict_block(job, b, LANES_FUSED_V3, 1);
}

MR_MLP_TARGET("arch=x86-64-v4")
static void predict_fused_v4(const predict_job *job) {
    const size_t blocks = (job->n + LANES_FUSED_V4 - 1) / LANES_FUSED_V4;
#pragma omp parallel for num_threads(job->threads) schedule(static) if (job->threads > 1)
    for (size_t b = 0; b < blocks; b++) predict_block(job, b, LANES_FUSED_V4, 1);
}
#endif

/* The unfused loop at the CPU's widest vectors (EXACT). */
static void predict_exact(const predict_job *job) {
#if MR_MLP_MULTIVERSION
    __builtin_cpu_init(); // idempotent; needed if we run before libgcc's constructor
    if (__builtin_cpu_supports("x86-64-v4")) {
        predict_v4(job);
        return;
    }
    if (__builtin_cpu_supports("x86-64-v3")) {
        if (__builtin_cpu_is("amd"))
            predict_v3_zen(job);
        else
            predict_v3(job);
        return;
    }
#endif
    predict_base(job);
}

static const char *const kernel_names[MR_MLP_KERNEL_COUNT] = {"auto", "sse2", "exact", "avx2", "avx512"};

const char *mr_mlp_kernel_name(mr_mlp_kernel kernel) {
    return (unsigned)kernel < MR_MLP_KERNEL_COUNT ? kernel_names[kernel] : NULL;
}

int mr_mlp_kernel_available(mr_mlp_kernel kernel) {
    switch (kernel) {
    case MR_MLP_KERNEL_AUTO:
    case MR_MLP_KERNEL_SSE2:
    case MR_MLP_KERNEL_EXACT:
        return 1;
#if MR_MLP_MULTIVERSION
    case MR_MLP_KERNEL_AVX2:
        __builtin_cpu_init();
        return __builtin_cpu_supports("x86-64-v3") > 0; // AVX2, FMA, ...
    case MR_MLP_KERNEL_AVX512:
        __builtin_cpu_init();
        return __builtin_cpu_supports("x86-64-v4") > 0; // AVX-512F, BW, DQ, VL
#endif
    default:
        return 0;
    }
}

/* What AUTO resolves to, computed once per process (the environment and the CPU do not change under it): the
 * kernel + 1, or -1 - the offending kernel for an MR_MLP_KERNEL naming one this CPU lacks, or INT_MIN for an
 * unknown name. Racing first calls compute the same value. */
static _Atomic int auto_choice;

static int resolve_auto(void) {
    const char *forced = getenv("MR_MLP_KERNEL");
    if (forced != NULL && forced[0] != '\0') {
        for (int k = MR_MLP_KERNEL_SSE2; k < MR_MLP_KERNEL_COUNT; k++)
            if (strcmp(forced, kernel_names[k]) == 0)
                return mr_mlp_kernel_available((mr_mlp_kernel)k) ? k + 1 : -1 - k;
        return INT_MIN;
    }
    if (mr_mlp_kernel_available(MR_MLP_KERNEL_AVX512)) return MR_MLP_KERNEL_AVX512 + 1;
    if (mr_mlp_kernel_available(MR_MLP_KERNEL_AVX2)) return MR_MLP_KERNEL_AVX2 + 1;
    return MR_MLP_KERNEL_SSE2 + 1;
}

mr_status mr_mlp_kernel_auto(mr_mlp_kernel *out) {
    if (out == NULL) return mr_fail(MR_ERR_INVALID_ARG, "mlp kernel: NULL output");
    int choice = atomic_load(&auto_choice);
    if (choice == 0) {
        choice = resolve_auto();
        atomic_store(&auto_choice, choice);
    }
    if (choice == INT_MIN)
        return mr_fail(MR_ERR_INVALID_ARG, "MR_MLP_KERNEL '%s': not a kernel (sse2, exact, avx2, avx512)",
                       getenv("MR_MLP_KERNEL") ? getenv("MR_MLP_KERNEL") : "");
    if (choice < 0)
        return mr_fail(MR_ERR_INVALID_ARG, "MR_MLP_KERNEL '%s': this CPU cannot run that kernel",
                       kernel_names[-1 - choice]);
    *out = (mr_mlp_kernel)(choice - 1);
    return MR_OK;
}

mr_status mr_mlp_predict(const mr_mlp *net, const float *in, size_t n, float *out) {
    return mr_mlp_predict_kernel(net, in, n, out, 0, MR_MLP_KERNEL_AUTO);
}

mr_status mr_mlp_predict_threads(const mr_mlp *net, const float *in, size_t n, float *out, int max_team) {
    return mr_mlp_predict_kernel(net, in, n, out, max_team, MR_MLP_KERNEL_AUTO);
}

mr_status mr_mlp_predict_kernel(const mr_mlp *net, const float *in, size_t n, float *out, int max_team,
                                mr_mlp_kernel kernel) {
    mr_status status = check_net("mlp predict", net);
    if (status != MR_OK) return status;
    if ((unsigned)kernel >= MR_MLP_KERNEL_COUNT)
        return mr_fail(MR_ERR_INVALID_ARG, "mlp predict: kernel %d: unknown (0 to %d)", (int)kernel,
                       MR_MLP_KERNEL_COUNT - 1);
    if (n == 0) return MR_OK;
    if (kernel == MR_MLP_KERNEL_AUTO && (status = mr_mlp_kernel_auto(&kernel)) != MR_OK) return status;
    if (!mr_mlp_kernel_available(kernel))
        return mr_fail(MR_ERR_UNSUPPORTED, "mlp predict: this CPU cannot run the %s kernel", kernel_names[kernel]);
    if (in == NULL || out == NULL) return mr_fail(MR_ERR_INVALID_ARG, "mlp predict: NULL input or output array");
    size_t widest = (size_t)MR_MAX(net->n_in, net->n_out);
    if (n > SIZE_MAX / widest) return mr_fail(MR_ERR_INVALID_ARG, "mlp predict: %zu rows overflow size_t", n);
    // The automatic rule (mr_auto_threads) with a team from two blocks of rows on, then a thread per
    // PREDICT_ROWS_PER_THREAD rows at most: for fewer, starting a team costs more than it saves.
    int threads = mr_auto_threads(max_team, (long)MR_MIN(n, (size_t)LONG_MAX), 2 * PREDICT_ROWS_PER_THREAD);
    if ((size_t)threads > n / PREDICT_ROWS_PER_THREAD) threads = (int)(n / PREDICT_ROWS_PER_THREAD);
    if (threads < 1) threads = 1;
    const int fused = kernel == MR_MLP_KERNEL_AVX2 || kernel == MR_MLP_KERNEL_AVX512;
    // A network changed in place since it was packed (or never packed) gets its weights packed for this call.
    const int pack_here = fused && !packed_current(net);
    size_t ws_floats = (size_t)threads * (size_t)(net->n_in + net->n_out) * MAX_LANES;
    size_t pack_floats = pack_here ? (size_t)net->n_hidden * (size_t)(net->n_in + 1 + net->n_out) + net->n_out : 0;
    float *ws = malloc((ws_floats + pack_floats) * sizeof(float));
    if (ws == NULL) return mr_fail(MR_ERR_NOMEM, "mlp predict: out of memory for the workspace");
    predict_job job = {net, in, n, out, ws, NULL, NULL, threads};
    if (pack_here) {
        float *units = ws + ws_floats;
        pack_units(net, units, units + (pack_floats - (size_t)net->n_out));
        job.units = units;
        job.b2 = units + (pack_floats - (size_t)net->n_out);
    } else if (fused) {
        job.units = net->packed->units;
        job.b2 = net->packed->b2;
    }
    switch (kernel) {
#if MR_MLP_MULTIVERSION
    case MR_MLP_KERNEL_AVX2:
        predict_fused_v3(&job);
        break;
    case MR_MLP_KERNEL_AVX512:
        predict_fused_v4(&job);
        break;
#endif
    case MR_MLP_KERNEL_EXACT:
        predict_exact(&job);
        break;
    default:
        predict_base(&job);
        break;
    }
    free(ws);
    return MR_OK;
}

mr_status mr_mlp_evaluate(const mr_mlp *net, const float *x, const float *y, size_t n, double *mse) {
    mr_status status = check_net("mlp evaluate", net);
    if (status != MR_OK) return status;
    if (n == 0) return mr_fail(MR_ERR_INVALID_ARG, "mlp evaluate: no rows");
    if (x == NULL || y == NULL || mse == NULL) return mr_fail(MR_ERR_INVALID_ARG, "mlp evaluate: NULL argument");
    const size_t n_in = (size_t)net->n_in, n_out = (size_t)net->n_out;
    if (n > SIZE_MAX / MR_MAX(n_in, n_out)) return mr_fail(MR_ERR_INVALID_ARG, "mlp evaluate: too many rows");
    size_t chunk = MR_MIN(n, (size_t)EVAL_ROWS);
    float *pred = malloc(chunk * n_out * sizeof(float));
    if (pred == NULL) return mr_fail(MR_ERR_NOMEM, "mlp evaluate: out of memory");
    double sum = 0.0;
    for (size_t row0 = 0; row0 < n; row0 += chunk) {
        size_t rows = MR_MIN(chunk, n - row0);
        status = mr_mlp_predict(net, x + row0 * n_in, rows, pred);
        if (status != MR_OK) {
            free(pred);
            return status;
        }
        for (size_t r = 0; r < rows; r++)
            for (size_t k = 0; k < n_out; k++) {
                double e = ((double)pred[r * n_out + k] - (double)y[(row0 + r) * n_out + k]) / (double)net->out_std[k];
                sum += e * e;
            }
    }
    free(pred);
    *mse = sum / ((double)n * (double)n_out);
    return MR_OK;
}

/* ---- the training pass (double) --------------------------------------------------------------------------- */

/* The loops over the hidden dimension go in blocks of 8 with a scalar remainder: at -O2 GCC only vectorises
 * loops whose trip count is a multiple of the vector length, and a block of 8 is one for every vector width. */

/* y[j] += a * x[j] */
static MR_ALWAYS_INLINE void axpy(double *restrict y, double a, const double *restrict x, size_t n) {
    size_t j = 0;
    for (; j + 8 <= n; j += 8)
        for (int l = 0; l < 8; l++) y[j + (size_t)l] += a * x[j + (size_t)l];
    for (; j < n; j++) y[j] += a * x[j];
}

/* sum of a[j] * b[j] in eight fixed partial sums, combined pairwise, then the remainder in order */
static MR_ALWAYS_INLINE double dot(const double *restrict a, const double *restrict b, size_t n) {
    double p[8] = {0, 0, 0, 0, 0, 0, 0, 0};
    size_t j = 0;
    for (; j + 8 <= n; j += 8)
        for (int l = 0; l < 8; l++) p[l] += a[j + (size_t)l] * b[j + (size_t)l];
    double s = ((p[0] + p[1]) + (p[2] + p[3])) + ((p[4] + p[5]) + (p[6] + p[7]));
    for (; j < n; j++) s += a[j] * b[j];
    return s;
}

/* Cloned for x86-64-v3 and v4 (GCC target_clones, chosen when the library loads); every clone computes the
 * same bits (the same operations in the same order, without fused multiply-adds), so training is as
 * deterministic across CPUs as across thread counts. */
MR_MLP_CLONES
double mr_mlp_sse_grad(const mr_mlp_dims *d, const double *params, const double *x, const double *t, size_t n,
                       double *grad, double *work) {
    const size_t I = (size_t)d->n_in, H = (size_t)d->n_hidden, O = (size_t)d->n_out;
    const double *restrict w1 = params;
    const double *restrict b1 = params + mr_mlp_off_b1(d);
    const double *restrict w2 = params + mr_mlp_off_w2(d);
    const double *restrict b2 = params + mr_mlp_off_b2(d);
    double *restrict z = work;          // pre-activations
    double *restrict a = work + H;      // activations
    double *restrict dz = work + 2 * H; // dE/dz
    double *restrict dv = work + 3 * H; // dE/dv
    double sse = 0.0;
    for (size_t s = 0; s < n; s++) {
        const double *xs = x + s * I, *ts = t + s * O;
        memcpy(z, b1, H * sizeof *z);
        for (size_t i = 0; i < I; i++) axpy(z, xs[i], w1 + i * H, H);
        for (size_t j = 0; j < H; j++) a[j] = z[j] > 0.0 ? z[j] : 0.0;
        for (size_t k = 0; k < O; k++) {
            double r = b2[k] + dot(w2 + k * H, a, H) - ts[k];
            sse += r * r;
            dv[k] = 2.0 * r;
        }
        if (grad == NULL) continue;
        double *restrict gw1 = grad;
        double *restrict gb1 = grad + mr_mlp_off_b1(d);
        double *restrict gw2 = grad + mr_mlp_off_w2(d);
        double *restrict gb2 = grad + mr_mlp_off_b2(d);
        memset(dz, 0, H * sizeof *dz);
        for (size_t k = 0; k < O; k++) {
            gb2[k] += dv[k];
            axpy(gw2 + k * H, dv[k], a, H);
            axpy(dz, dv[k], w2 + k * H, H);
        }
        for (size_t j = 0; j < H; j++) {
            dz[j] = z[j] > 0.0 ? dz[j] : 0.0;
            gb1[j] += dz[j];
        }
        for (size_t i = 0; i < I; i++) axpy(gw1 + i * H, xs[i], dz, H);
    }
    return sse;
}
