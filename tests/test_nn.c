/*
 * test_nn.c — the hand-written MLP (nn/mlp.h): the backward pass against central differences, inference against
 * a scalar reference, thread-count independence, NaN propagation, exact weight-file round trips, rejected
 * files, learning a smooth function, determinism, early stopping and bad arguments.
 *
 * Training cases use small networks and datasets (a second or so each, also under AddressSanitizer); every
 * random draw is seeded, so every case is deterministic. The throughput check runs only when asked:
 *   MR_NN_TIMING=1 OMP_NUM_THREADS=2 build/tests/test_nn inference_throughput
 */
#include <errno.h>
#include <math.h>
#include <omp.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "../nn/mlp_internal.h"
#include "mr_core.h" /* mr_rng_*: the seeded inputs */
#include "harness.h"
#include "text_lines.h"

/* ---- helpers ---------------------------------------------------------------------------------------------- */

static double uniform(uint64_t *rng, double lo, double hi) { return lo + (hi - lo) * mr_rng_unit(rng); }

/* A network with random weights and normalisation (the values need not make sense, only be varied). */
static mr_mlp *random_net(int n_in, int n_hidden, int n_out, uint64_t seed) {
    mr_mlp *net = NULL;
    MR_CHECK_OK(mr_mlp_create(n_in, n_hidden, n_out, &net));
    if (net == NULL) return NULL;
    uint64_t rng = mr_rng_stream(seed, 99);
    size_t params = mr_mlp_param_count(net);
    for (size_t q = 0; q < params; q++) net->data[q] = (float)uniform(&rng, -1.0, 1.0);
    for (int i = 0; i < n_in; i++) {
        net->in_mean[i] = (float)uniform(&rng, -0.5, 0.5);
        net->in_std[i] = (float)uniform(&rng, 0.1, 2.0);
    }
    for (int k = 0; k < n_out; k++) {
        net->out_mean[k] = (float)uniform(&rng, -0.5, 0.5);
        net->out_std[k] = (float)uniform(&rng, 0.1, 2.0);
    }
    return net;
}

static float *random_rows(size_t n, int cols, uint64_t seed) {
    float *a = malloc(n * (size_t)cols * sizeof(float));
    uint64_t rng = mr_rng_stream(seed, 7);
    for (size_t q = 0; q < n * (size_t)cols; q++) a[q] = (float)uniform(&rng, 0.0, 1.0);
    return a;
}

/* The network of mlp.h evaluated one row at a time in plain scalar float, in the order the header documents. */
static void reference_predict(const mr_mlp *net, const float *x, float *y) {
    const int I = net->n_in, H = net->n_hidden, O = net->n_out;
    float u[64];
    for (int i = 0; i < I; i++) u[i] = (x[i] - net->in_mean[i]) / net->in_std[i];
    for (int k = 0; k < O; k++) y[k] = net->b2[k];
    for (int j = 0; j < H; j++) {
        float h = net->b1[j];
        for (int i = 0; i < I; i++) h += net->w1[i * H + j] * u[i];
        h = h < 0.0f ? 0.0f : h;
        for (int k = 0; k < O; k++) y[k] += net->w2[k * H + j] * h;
    }
    for (int k = 0; k < O; k++) y[k] = net->out_mean[k] + net->out_std[k] * y[k];
}

/* The same network and order with every product added by a fused multiply-add (fmaf: one rounding), as the
 * AVX2 and AVX-512 kernels compute it (mlp.h). */
static void reference_predict_fused(const mr_mlp *net, const float *x, float *y) {
    const int I = net->n_in, H = net->n_hidden, O = net->n_out;
    float u[64];
    for (int i = 0; i < I; i++) u[i] = (x[i] - net->in_mean[i]) / net->in_std[i];
    for (int k = 0; k < O; k++) y[k] = net->b2[k];
    for (int j = 0; j < H; j++) {
        float h = net->b1[j];
        for (int i = 0; i < I; i++) h = fmaf(net->w1[i * H + j], u[i], h);
        h = h < 0.0f ? 0.0f : h;
        for (int k = 0; k < O; k++) y[k] = fmaf(net->w2[k * H + j], h, y[k]);
    }
    for (int k = 0; k < O; k++) y[k] = net->out_mean[k] + net->out_std[k] * y[k];
}

/* How far a fused and an unfused evaluation of a row's output k may be apart: each is within gamma_m S of the exact
 * value (Higham, "Accuracy and Stability of Numerical Algorithms", 2nd ed., section 3.1: a sum of m products
 * evaluated in any order, fused or not, with unit roundoff u = 2^-24, gamma_m = m u / (1 - m u)), where
 * S = |out_mean| + out_std (|b2| + sum_j |w2_kj| (|b1_j| + sum_i |w1_ij u_i|)) bounds the terms' magnitudes and
 * m = n_in + n_hidden + 4 counts the roundings along the longest path (layer 1, layer 2, the two of the output's
 * scale and shift, and the normalisation's). So the two are within 2 gamma_m S. */
static double fused_tolerance(const mr_mlp *net, const float *x, int k) {
    const int I = net->n_in, H = net->n_hidden;
    double u[64], s = fabs((double)net->b2[k]);
    for (int i = 0; i < I; i++) u[i] = ((double)x[i] - net->in_mean[i]) / net->in_std[i];
    for (int j = 0; j < H; j++) {
        double a = fabs((double)net->b1[j]);
        for (int i = 0; i < I; i++) a += fabs((double)net->w1[i * H + j] * u[i]);
        s += fabs((double)net->w2[k * H + j]) * a;
    }
    s = fabs((double)net->out_mean[k]) + (double)net->out_std[k] * s;
    const double m = I + H + 4, unit = 0x1p-24;
    return 2.0 * (m * unit / (1.0 - m * unit)) * s;
}

/* A scratch directory for files, removed at exit (each case removes the files it writes). */
static char scratch_dir[256];

static void remove_scratch_dir(void) { rmdir(scratch_dir); }

static const char *scratch_path(const char *name) {
    static char path[512];
    if (scratch_dir[0] == '\0') {
        snprintf(scratch_dir, sizeof scratch_dir, "/tmp/mr_test_nn.%ld", (long)getpid());
        MR_CHECK(mkdir(scratch_dir, 0700) == 0 || errno == EEXIST);
        atexit(remove_scratch_dir);
    }
    snprintf(path, sizeof path, "%s/%s", scratch_dir, name);
    return path;
}

static void write_text(const char *path, const char *text, size_t size) {
    FILE *f = fopen(path, "wb");
    MR_CHECK(f != NULL);
    if (f == NULL) return;
    MR_CHECK(fwrite(text, 1, size, f) == size);
    fclose(f);
}

/* Two networks with the same shape and the same bits everywhere. */
static int same_net(const mr_mlp *a, const mr_mlp *b) {
    return a != NULL && b != NULL && a->n_in == b->n_in && a->n_hidden == b->n_hidden && a->n_out == b->n_out &&
           a->data_count == b->data_count && memcmp(a->data, b->data, a->data_count * sizeof(float)) == 0;
}

/* ---- gradient and inference ------------------------------------------------------------------------------- */

/* The backward pass against central differences, in double, on a 3 x 5 x 2 network, for every parameter.
 * With h = 1e-6 the difference quotient is accurate to ~1e-9 relative (truncation h^2, rounding 1e-16 / h), so
 * 1e-6 catches a wrong sign, index or factor of 2 anywhere. The data are chosen so that no pre-activation is
 * within 1e-3 of the ReLU's kink (checked), where the derivative jumps. */
MR_TEST(gradient_matches_central_differences) {
    const mr_mlp_dims d = {3, 5, 2};
    enum { N = 4 };
    const size_t P = mr_mlp_dims_params(&d);
    double params[64], grad[64], x[N * 3], t[N * 2], work[32];
    MR_CHECK(P == 32 && mr_mlp_work_doubles(&d) <= 32);
    uint64_t rng = mr_rng_stream(5, 0);
    for (size_t q = 0; q < P; q++) params[q] = uniform(&rng, -1.0, 1.0);
    for (int q = 0; q < N * 3; q++) x[q] = uniform(&rng, -1.5, 1.5);
    for (int q = 0; q < N * 2; q++) t[q] = uniform(&rng, -1.0, 1.0);
    // Away from the kink: every hidden pre-activation of every row.
    double closest = INFINITY;
    for (int s = 0; s < N; s++)
        for (int j = 0; j < 5; j++) {
            double z = params[mr_mlp_off_b1(&d) + (size_t)j];
            for (int i = 0; i < 3; i++) z += params[i * 5 + j] * x[s * 3 + i];
            closest = fmin(closest, fabs(z));
        }
    MR_CHECK_MSG(closest > 1e-3, "a pre-activation is %g from the kink: pick other data", closest);

    memset(grad, 0, sizeof grad);
    double e = mr_mlp_sse_grad(&d, params, x, t, N, grad, work);
    MR_CHECK(e > 0.0);
    MR_CHECK(mr_mlp_sse_grad(&d, params, x, t, N, NULL, work) == e); // loss only: the same forward pass
    const double h = 1e-6;
    double worst = 0.0;
    for (size_t q = 0; q < P; q++) {
        double saved = params[q];
        params[q] = saved + h;
        double ep = mr_mlp_sse_grad(&d, params, x, t, N, NULL, work);
        params[q] = saved - h;
        double em = mr_mlp_sse_grad(&d, params, x, t, N, NULL, work);
        params[q] = saved;
        double fd = (ep - em) / (2.0 * h);
        double rel = fabs(grad[q] - fd) / fmax(fabs(grad[q]) + fabs(fd), 1e-6);
        worst = fmax(worst, rel);
        MR_CHECK_MSG(rel < 1e-6, "parameter %zu: backward %.12g, central difference %.12g", q, grad[q], fd);
    }
    // The gradient is added, not stored: a second call doubles it.
    double again[64];
    memcpy(again, grad, sizeof again);
    mr_mlp_sse_grad(&d, params, x, t, N, again, work);
    for (size_t q = 0; q < P; q++) MR_CHECK_NEAR(again[q], 2.0 * grad[q], 1e-12 * fmax(1.0, fabs(grad[q])));
}

/* Every kernel this CPU runs gives exactly its scalar reference's bits (SSE2 and EXACT the unfused order of mlp.h,
 * AVX2 and AVX-512 the fused one), for a block size that does not divide the row count, a hidden width that is not
 * a multiple of any vector width, and the design card's 6 x H x 4 (the specialised path) as well as another shape
 * (the general one); so the fused kernels agree with each other bit for bit, and with the unfused ones within
 * fused_tolerance. Inputs include values far outside the training range (+-1e3, 0, subnormal). */
MR_TEST(predict_matches_scalar_reference) {
    const int shapes[3][3] = {{6, 37, 4}, {6, 300, 4}, {5, 23, 3}};
    for (int s = 0; s < 3; s++) {
        const int I = shapes[s][0], H = shapes[s][1], O = shapes[s][2];
        mr_mlp *net = random_net(I, H, O, 11 + (uint64_t)s);
        if (s == 1) MR_CHECK_OK(mr_mlp_pack(net)); // one shape from packed weights, the others packed per call
        const size_t n = 37;
        float *x = random_rows(n, I, 3);
        const float extremes[4] = {1e3f, -1e3f, 0.0f, 0x1p-140f};
        for (int q = 0; q < 4; q++) x[(size_t)(30 + q) * (size_t)I + (size_t)(q % I)] = extremes[q];
        float *y = malloc(n * (size_t)O * sizeof(float));
        double worst = 0.0; // the largest fused - unfused difference, in units of its tolerance
        for (int kernel = MR_MLP_KERNEL_SSE2; kernel < MR_MLP_KERNEL_COUNT; kernel++) {
            if (!mr_mlp_kernel_available((mr_mlp_kernel)kernel)) continue;
            const int fused = kernel == MR_MLP_KERNEL_AVX2 || kernel == MR_MLP_KERNEL_AVX512;
            MR_CHECK_OK(mr_mlp_predict_kernel(net, x, n, y, 0, (mr_mlp_kernel)kernel));
            int mismatches = 0;
            for (size_t r = 0; r < n; r++) {
                float ref[8], other[8];
                (fused ? reference_predict_fused : reference_predict)(net, x + r * (size_t)I, ref);
                if (memcmp(ref, y + r * (size_t)O, (size_t)O * sizeof(float)) != 0) mismatches++;
                (fused ? reference_predict : reference_predict_fused)(net, x + r * (size_t)I, other);
                for (int k = 0; k < O; k++) {
                    double tol = fused_tolerance(net, x + r * (size_t)I, k);
                    double diff = fabs((double)ref[k] - (double)other[k]);
                    MR_CHECK_MSG(diff <= tol, "%dx%dx%d row %zu output %d: fused and unfused differ by %g (bound %g)",
                                 I, H, O, r, k, diff, tol);
                    worst = fmax(worst, diff / tol);
                }
            }
            MR_CHECK_MSG(mismatches == 0, "%dx%dx%d, %s kernel: %d of %zu rows differ from the reference", I, H, O,
                         mr_mlp_kernel_name((mr_mlp_kernel)kernel), mismatches, n);
            // One row alone gives the same bits as inside a batch.
            float one[8];
            MR_CHECK_OK(mr_mlp_predict_kernel(net, x + 20 * (size_t)I, 1, one, 0, (mr_mlp_kernel)kernel));
            MR_CHECK(memcmp(one, y + 20 * (size_t)O, (size_t)O * sizeof(float)) == 0);
        }
        MR_CHECK(worst > 0.0 && worst < 0.05); // they do differ, by far less than the bound
        free(x);
        free(y);
        mr_mlp_free(net);
    }
}

/* The packed weights follow the values: a network changed in place after mr_mlp_pack predicts with its new values,
 * and mr_mlp_pack makes the packed copy current again (same bits either way). */
MR_TEST(predict_follows_values_changed_in_place) {
    mr_mlp *net = random_net(6, 64, 4, 17);
    MR_CHECK_OK(mr_mlp_pack(net));
    const size_t n = 50;
    float *x = random_rows(n, 6, 18), *y = malloc(n * 4 * sizeof(float)), *z = malloc(n * 4 * sizeof(float));
    net->w2[3 * 64 + 5] += 0.5f;
    net->in_std[2] *= 2.0f;
    MR_CHECK_OK(mr_mlp_predict(net, x, n, y));
    MR_CHECK_OK(mr_mlp_pack(net));
    MR_CHECK_OK(mr_mlp_predict(net, x, n, z));
    MR_CHECK(memcmp(y, z, n * 4 * sizeof(float)) == 0);
    mr_mlp_kernel kernel = MR_MLP_KERNEL_AUTO;
    MR_CHECK_OK(mr_mlp_kernel_auto(&kernel));
    const int fused = kernel == MR_MLP_KERNEL_AVX2 || kernel == MR_MLP_KERNEL_AVX512;
    for (size_t r = 0; r < n; r++) {
        float ref[4];
        (fused ? reference_predict_fused : reference_predict)(net, x + r * 6, ref);
        MR_CHECK(memcmp(ref, y + r * 4, sizeof ref) == 0);
    }
    // The kernel names and the override (MR_MLP_KERNEL, read once per process).
    const char *forced = getenv("MR_MLP_KERNEL");
    if (forced != NULL && forced[0] != '\0') MR_CHECK(strcmp(mr_mlp_kernel_name(kernel), forced) == 0);
    MR_CHECK(mr_mlp_kernel_name(MR_MLP_KERNEL_COUNT) == NULL && strcmp(mr_mlp_kernel_name(0), "auto") == 0);
    MR_CHECK(mr_mlp_predict_kernel(net, x, n, y, 0, MR_MLP_KERNEL_COUNT) == MR_ERR_INVALID_ARG);
    free(x);
    free(y);
    free(z);
    mr_mlp_free(net);
}

MR_TEST(predict_is_identical_for_1_and_2_threads) {
    mr_mlp *net = random_net(6, 300, 4, 21);
    const size_t n = 1013;
    float *x = random_rows(n, 6, 4);
    float *y1 = malloc(n * 4 * sizeof(float)), *y2 = malloc(n * 4 * sizeof(float));
    int saved = omp_get_max_threads();
    for (int kernel = MR_MLP_KERNEL_AUTO; kernel < MR_MLP_KERNEL_COUNT; kernel++) {
        if (!mr_mlp_kernel_available((mr_mlp_kernel)kernel)) continue;
        MR_CHECK_OK(mr_mlp_predict_kernel(net, x, n, y1, 1, (mr_mlp_kernel)kernel));
        MR_CHECK_OK(mr_mlp_predict_kernel(net, x, n, y2, 2, (mr_mlp_kernel)kernel));
        MR_CHECK_MSG(memcmp(y1, y2, n * 4 * sizeof(float)) == 0, "%s kernel",
                     mr_mlp_kernel_name((mr_mlp_kernel)kernel));
    }
    omp_set_num_threads(1);
    MR_CHECK_OK(mr_mlp_predict(net, x, n, y1));
    omp_set_num_threads(2);
    MR_CHECK_OK(mr_mlp_predict(net, x, n, y2));
    omp_set_num_threads(saved);
    MR_CHECK(memcmp(y1, y2, n * 4 * sizeof(float)) == 0);
    double e1 = 0, e2 = 0;
    omp_set_num_threads(1);
    MR_CHECK_OK(mr_mlp_evaluate(net, x, y1, n, &e1));
    omp_set_num_threads(2);
    MR_CHECK_OK(mr_mlp_evaluate(net, x, y1, n, &e2));
    omp_set_num_threads(saved);
    MR_CHECK(e1 == 0.0 && e2 == 0.0); // the network's own predictions as targets
    free(x);
    free(y1);
    free(y2);
    mr_mlp_free(net);
}

/* mlp.h: a NaN input gives NaN in every output of its row and leaves the other rows alone, in every kernel. */
MR_TEST(nan_input_propagates_to_its_row_only) {
    mr_mlp *net = random_net(6, 40, 4, 31);
    const size_t n = 20;
    float *x = random_rows(n, 6, 5);
    float *clean = malloc(n * 4 * sizeof(float)), *y = malloc(n * 4 * sizeof(float));
    float *dirty = malloc(n * 6 * sizeof(float));
    memcpy(dirty, x, n * 6 * sizeof(float));
    dirty[7 * 6 + 2] = NAN;
    dirty[13 * 6 + 5] = INFINITY;
    for (int kernel = MR_MLP_KERNEL_AUTO; kernel < MR_MLP_KERNEL_COUNT; kernel++) {
        if (!mr_mlp_kernel_available((mr_mlp_kernel)kernel)) continue;
        MR_CHECK_OK(mr_mlp_predict_kernel(net, x, n, clean, 0, (mr_mlp_kernel)kernel));
        MR_CHECK_OK(mr_mlp_predict_kernel(net, dirty, n, y, 0, (mr_mlp_kernel)kernel));
        for (size_t r = 0; r < n; r++)
            for (int k = 0; k < 4; k++) {
                float v = y[r * 4 + (size_t)k];
                if (r == 7)
                    MR_CHECK_MSG(isnan(v), "%s: row 7 output %d is %g", mr_mlp_kernel_name((mr_mlp_kernel)kernel), k,
                                 (double)v);
                else if (r == 13)
                    MR_CHECK_MSG(!isfinite(v), "%s: row 13 output %d is %g",
                                 mr_mlp_kernel_name((mr_mlp_kernel)kernel), k, (double)v);
                else
                    MR_CHECK(memcmp(&v, &clean[r * 4 + (size_t)k], sizeof v) == 0);
            }
    }
    free(x);
    free(dirty);
    free(clean);
    free(y);
    mr_mlp_free(net);
}

/* ---- weight files ----------------------------------------------------------------------------------------- */

MR_TEST(weight_file_round_trips_bit_exactly) {
    mr_mlp *net = random_net(6, 300, 4, 41);
    // Values that a decimal format with too few digits, or a careless parser, would change.
    net->w1[0] = -0.0f;
    net->w1[1] = 0x1p-149f;            // the smallest subnormal
    net->w1[2] = 0x1.fffffep+127f;     // FLT_MAX
    net->w1[3] = -0x1.fffffep-1f;      // just below -1
    net->w2[5] = 0.1f;
    net->b2[3] = 1e-30f;
    const char *path = scratch_path("round.mlp");
    MR_CHECK_OK(mr_mlp_write(net, path));
    mr_mlp *back = NULL;
    MR_CHECK_OK(mr_mlp_read(path, &back));
    MR_CHECK(same_net(net, back));
    if (back != NULL) MR_CHECK(signbit(back->w1[0]) && back->w1[0] == 0.0f);
    const size_t n = 50;
    float *x = random_rows(n, 6, 6);
    float *y1 = malloc(n * 4 * sizeof(float)), *y2 = malloc(n * 4 * sizeof(float));
    MR_CHECK_OK(mr_mlp_predict(net, x, n, y1));
    MR_CHECK_OK(mr_mlp_predict(back, x, n, y2));
    MR_CHECK(memcmp(y1, y2, n * 4 * sizeof(float)) == 0);
    // Writing what was read gives the same bytes; the file starts with the magic line.
    size_t size1 = 0, size2 = 0;
    char *text1 = mr_test_read_file(path, &size1);
    MR_CHECK_OK(mr_mlp_write(back, path));
    char *text2 = mr_test_read_file(path, &size2);
    MR_CHECK(text1 != NULL && text2 != NULL && size1 == size2 && memcmp(text1, text2, size1) == 0);
    if (text1 != NULL) MR_CHECK(strncmp(text1, "matremap-mlp 1\nn_in 6\nn_hidden 300\nn_out 4\n", 43) == 0);
    // mr_mlp_parse on the bytes is mr_mlp_read.
    mr_mlp *parsed = NULL;
    if (text1 != NULL) MR_CHECK_OK(mr_mlp_parse(text1, size1, "x", &parsed));
    MR_CHECK(same_net(net, parsed));
    free(text1);
    free(text2);
    free(x);
    free(y1);
    free(y2);
    mr_mlp_free(parsed);
    mr_mlp_free(back);
    mr_mlp_free(net);
    unlink(path);
}

/* Parse `text` (NUL-terminated); expect MR_ERR_FORMAT with a message naming the file, the line and `needle`. */
static void expect_rejected(const char *text, const char *needle, int line) {
    mr_mlp *net = NULL;
    mr_status s = mr_mlp_parse(text, strlen(text), "bad.mlp", &net);
    char where[64];
    snprintf(where, sizeof where, "'bad.mlp': line %d:", line);
    MR_CHECK_MSG(s == MR_ERR_FORMAT, "got %s for a file that should fail with '%s'", mr_status_str(s), needle);
    MR_CHECK_MSG(strstr(mr_last_error(), where) != NULL && strstr(mr_last_error(), needle) != NULL,
                 "message '%s' lacks '%s' or '%s'", mr_last_error(), where, needle);
    MR_CHECK(net == NULL);
    mr_mlp_free(net);
}

/* A valid 2 x 3 x 1 file with one line replaced (line numbers from 1; 0 = none) or text appended. */
static void small_file(char *buf, size_t size, int replace_line, const char *replacement, const char *tail) {
    const char *lines[] = {"matremap-mlp 1", "n_in 2", "n_hidden 3", "n_out 1", "activation relu linear",
                           "in_mean 0x1p-1 -0x1.8p+0", "in_std 0x1p+0 0x1.4p+1", "out_mean 0x0p+0",
                           "out_std 0x1p-2", "w1 0x1p+0 -0x1p+0 0x1p-3", "w1 0x1.8p+0 0x0p+0 -0x1p-4",
                           "b1 0x0p+0 0x1p-5 -0x1p-5", "w2 0x1p+0 0x1p+1 -0x1p+2", "b2 0x1p-6", "end"};
    size_t used = 0;
    buf[0] = '\0';
    for (int l = 0; l < (int)(sizeof lines / sizeof lines[0]); l++) {
        const char *text = l + 1 == replace_line ? replacement : lines[l];
        if (text == NULL) continue; // line removed
        used += (size_t)snprintf(buf + used, size - used, "%s\n", text);
    }
    if (tail != NULL) snprintf(buf + used, size - used, "%s", tail);
}

MR_TEST(bad_weight_files_are_rejected) {
    char text[2048];
    mr_mlp *net = NULL;
    small_file(text, sizeof text, 0, NULL, NULL);
    MR_CHECK_OK(mr_mlp_parse(text, strlen(text), "good.mlp", &net));
    if (net != NULL) MR_CHECK(net->n_in == 2 && net->n_hidden == 3 && net->n_out == 1 && net->w1[3] == 1.5f);
    mr_mlp_free(net);

    small_file(text, sizeof text, 1, "matremap-nn 1", NULL);
    expect_rejected(text, "not an MLP weight file", 1);
    small_file(text, sizeof text, 1, "matremap-mlp 3", NULL);
    expect_rejected(text, "unsupported version '3'", 1);
    /* version 2 must say its kind on the line after the activations */
    small_file(text, sizeof text, 1, "matremap-mlp 2", NULL);
    expect_rejected(text, "expected 'kind WORD'", 6);
    small_file(text, sizeof text, 1, "matremap-mlp", NULL);
    expect_rejected(text, "no version", 1);
    small_file(text, sizeof text, 3, "n_hidden 0", NULL);
    expect_rejected(text, "n_hidden 0", 3);
    small_file(text, sizeof text, 3, "n_hidden 99999999999", NULL);
    expect_rejected(text, "not a size", 3);
    small_file(text, sizeof text, 3, "n_hidden 4", NULL); // the w1 lines then hold 3 values, not 4
    expect_rejected(text, "3 values after 'w1' (expected 4)", 10);
    small_file(text, sizeof text, 2, "n_inputs 2", NULL);
    expect_rejected(text, "expected 'n_in N'", 2);
    small_file(text, sizeof text, 5, "activation tanh linear", NULL);
    expect_rejected(text, "unsupported activations", 5);
    small_file(text, sizeof text, 7, "in_std 0x1p+0 0x0p+0", NULL);
    expect_rejected(text, "expected a value > 0", 7);
    small_file(text, sizeof text, 10, "w1 0x1p+0 nan 0x1p-3", NULL);
    expect_rejected(text, "expected a finite float", 10);
    small_file(text, sizeof text, 10, "w1 0x1p+0 1e39 0x1p-3", NULL);
    expect_rejected(text, "expected a finite float", 10);
    small_file(text, sizeof text, 10, "w1 0x1p+0 0x1p+0x 0x1p-3", NULL);
    expect_rejected(text, "not a number: '0x1p+0x'", 10);
    small_file(text, sizeof text, 10, "w1 0x1p+0 0x1p+0 0x1p-3 0x1p-3", NULL);
    expect_rejected(text, "more than 3 values", 10);
    small_file(text, sizeof text, 12, "b2 0x1p-6", NULL);
    expect_rejected(text, "expected 'b1'", 12);
    small_file(text, sizeof text, 11, NULL, NULL); // a w1 line missing
    expect_rejected(text, "expected 'w1'", 11);
    small_file(text, sizeof text, 15, "ending", NULL);
    expect_rejected(text, "expected 'end'", 15);
    small_file(text, sizeof text, 0, NULL, "w1 0x1p+0\n");
    expect_rejected(text, "unexpected content after 'end'", 16);
    small_file(text, sizeof text, 10, "w1 0x1p+0\t-0x1p+0 0x1p-3", NULL);
    expect_rejected(text, "not a number", 10);
    small_file(text, sizeof text, 10, "w1  0x1p+0  -0x1p+0   0x1p-3", NULL); // extra spaces are fine
    MR_CHECK_OK(mr_mlp_parse(text, strlen(text), "spaces.mlp", &net));
    mr_mlp_free(net);
    net = NULL;

    // Every proper prefix of a valid file (a truncated file) is rejected, naming the line it stops in.
    small_file(text, sizeof text, 0, NULL, NULL);
    size_t size = strlen(text);
    int accepted = 0, unnamed = 0;
    for (size_t cut = 0; cut < size; cut++) {
        mr_mlp *t = NULL;
        mr_status s = mr_mlp_parse(text, cut, "cut.mlp", &t);
        if (s != MR_ERR_FORMAT) accepted++;
        if (strstr(mr_last_error(), "'cut.mlp': line ") == NULL) unnamed++;
        mr_mlp_free(t);
    }
    MR_CHECK_MSG(accepted == 0, "%d truncations accepted", accepted);
    MR_CHECK_MSG(unnamed == 0, "%d messages without the file and line", unnamed);
    expect_rejected("", "unexpected end of file", 1);

    // Through files: a truncated file, a missing file.
    const char *path = scratch_path("cut.mlp");
    write_text(path, text, size - 7);
    MR_CHECK(mr_mlp_read(path, &net) == MR_ERR_FORMAT);
    MR_CHECK(strstr(mr_last_error(), path) != NULL && strstr(mr_last_error(), "line 14") != NULL);
    unlink(path);
    MR_CHECK(mr_mlp_read(path, &net) == MR_ERR_IO);
    MR_CHECK(strstr(mr_last_error(), path) != NULL);
    MR_CHECK(net == NULL);
}

/* A network that cannot be read back is not written; a failed write leaves no file and the old one intact. */
MR_TEST(bad_writes_leave_files_alone) {
    mr_mlp *net = random_net(2, 3, 1, 51);
    const char *path = scratch_path("keep.mlp");
    MR_CHECK_OK(mr_mlp_write(net, path));
    size_t size_before = 0;
    char *before = mr_test_read_file(path, &size_before);
    net->b1[2] = NAN;
    MR_CHECK(mr_mlp_write(net, path) == MR_ERR_INVALID_ARG);
    MR_CHECK(strstr(mr_last_error(), "b1[2]") != NULL);
    net->b1[2] = 0.0f;
    net->out_std[0] = 0.0f;
    MR_CHECK(mr_mlp_write(net, path) == MR_ERR_INVALID_ARG);
    MR_CHECK(strstr(mr_last_error(), "out_std[0]") != NULL);
    size_t size_after = 0;
    char *after = mr_test_read_file(path, &size_after);
    MR_CHECK(before != NULL && after != NULL && size_before == size_after && memcmp(before, after, size_after) == 0);
    net->out_std[0] = 1.0f;
    MR_CHECK(mr_mlp_write(net, scratch_path("no/such/dir.mlp")) == MR_ERR_IO);
    free(before);
    free(after);
    mr_mlp_free(net);
    unlink(path);
}

/* ---- training --------------------------------------------------------------------------------------------- */

/* Four smooth functions of six inputs in [0, 1] (something like the workflow's: products, a sine, a square). */
static void smooth_targets(const float *x, size_t n, float *y) {
    for (size_t r = 0; r < n; r++) {
        const float *a = x + r * 6;
        float *b = y + r * 4;
        b[0] = (float)(a[0] * a[3] + 0.5 * a[1]);
        b[1] = (float)(sin(2.0 * a[2]) + a[4] * a[4]);
        b[2] = (float)(a[5] - a[0] + 0.3 * a[1] * a[2]);
        b[3] = (float)(0.25 * (a[1] + a[2] + a[3]) + 2.0); // an offset the output normalisation removes
    }
}

typedef struct curve {
    int calls, last_epoch, ordered, finite, stop_at;
    double losses[512];
} curve;

static int record_epoch(const mr_mlp_epoch *e, void *user) {
    curve *c = user;
    if (e->epoch != c->calls) c->ordered = 0;
    if (!isfinite(e->train_loss) || !isfinite(e->validation_loss)) c->finite = 0;
    if (e->epoch < 512) c->losses[e->epoch] = e->validation_loss;
    c->calls++;
    c->last_epoch = e->epoch;
    return c->stop_at > 0 && e->epoch >= c->stop_at;
}

MR_TEST(training_learns_a_smooth_function) {
    const size_t n = 2000, n_test = 500;
    float *x = random_rows(n, 6, 61), *y = malloc(n * 4 * sizeof(float));
    float *xt = random_rows(n_test, 6, 62), *yt = malloc(n_test * 4 * sizeof(float));
    smooth_targets(x, n, y);
    smooth_targets(xt, n_test, yt);
    mr_mlp_train_options o = {0};
    o.n_hidden = 32;
    o.batch_size = 32;
    o.max_epochs = 60;
    o.learning_rate = 3e-3;
    o.seed = 1;
    curve c = {0, -1, 1, 1, 0, {0}};
    o.epoch_fn = record_epoch;
    o.epoch_user = &c;
    mr_mlp *net = NULL;
    mr_mlp_train_report r;
    MR_CHECK_OK(mr_mlp_train(x, y, n, 6, 4, &o, &net, &r));
    MR_CHECK(net != NULL && net->n_hidden == 32);
    MR_CHECK(r.n_validation == 200 && r.n_train == 1800);
    MR_CHECK(c.ordered && c.finite && c.calls == r.epochs + 1 && c.last_epoch == r.epochs);
    MR_CHECK(r.stop == MR_MLP_STOP_MAX_EPOCHS || r.stop == MR_MLP_STOP_PATIENCE);
    MR_CHECK(r.best_validation_loss == c.losses[r.best_epoch]);
    MR_CHECK_MSG(r.best_validation_loss < 0.01 * r.initial_validation_loss,
                 "validation loss %g from %g after %d epochs", r.best_validation_loss, r.initial_validation_loss,
                 r.epochs);
    // Fresh data through the float network: normalised MSE far below the 1 a constant prediction scores.
    double mse = 1.0;
    MR_CHECK_OK(mr_mlp_evaluate(net, xt, yt, n_test, &mse));
    MR_CHECK_MSG(mse < 0.01, "test MSE %g (best validation %g)", mse, r.best_validation_loss);
    // The stored normalisation is the training split's: output 3's mean is close to 2.375.
    if (net != NULL) MR_CHECK_NEAR(net->out_mean[3], 2.375, 0.02);
    free(x);
    free(y);
    free(xt);
    free(yt);
    mr_mlp_free(net);
}

MR_TEST(training_is_deterministic_for_a_seed_and_any_thread_count) {
    const size_t n = 600;
    float *x = random_rows(n, 6, 71), *y = malloc(n * 4 * sizeof(float));
    smooth_targets(x, n, y);
    mr_mlp_train_options o = {0};
    o.n_hidden = 24;
    o.batch_size = 50; // chunks of 16, 16, 16 and 2 rows
    o.max_epochs = 8;
    o.seed = 1234;
    mr_mlp *a = NULL, *b = NULL, *c = NULL;
    mr_mlp_train_report ra, rb, rc;
    o.threads = 1;
    MR_CHECK_OK(mr_mlp_train(x, y, n, 6, 4, &o, &a, &ra));
    o.threads = 2;
    MR_CHECK_OK(mr_mlp_train(x, y, n, 6, 4, &o, &b, &rb));
    MR_CHECK(same_net(a, b));
    MR_CHECK(ra.epochs == rb.epochs && ra.best_epoch == rb.best_epoch && ra.stop == rb.stop);
    MR_CHECK(ra.best_validation_loss == rb.best_validation_loss && ra.final_train_loss == rb.final_train_loss);
    o.seed = 1235;
    MR_CHECK_OK(mr_mlp_train(x, y, n, 6, 4, &o, &c, &rc));
    MR_CHECK(c != NULL && a != NULL && memcmp(a->w1, c->w1, 24 * 6 * sizeof(float)) != 0);
    free(x);
    free(y);
    mr_mlp_free(a);
    mr_mlp_free(b);
    mr_mlp_free(c);
}

/* A constant input column and a constant output column: std 1, no NaN anywhere, and the network predicts the
 * constant output. */
MR_TEST(constant_features_normalise_without_nan) {
    const size_t n = 300;
    float *x = random_rows(n, 6, 81), *y = malloc(n * 4 * sizeof(float));
    smooth_targets(x, n, y);
    for (size_t r = 0; r < n; r++) {
        x[r * 6 + 2] = 0.5f;
        y[r * 4 + 1] = -3.0f;
    }
    mr_mlp_train_options o = {0};
    o.n_hidden = 16;
    o.max_epochs = 60;
    o.learning_rate = 1e-2;
    mr_mlp *net = NULL;
    mr_mlp_train_report r;
    MR_CHECK_OK(mr_mlp_train(x, y, n, 6, 4, &o, &net, &r));
    if (net == NULL) return;
    MR_CHECK(net->in_std[2] == 1.0f && net->in_mean[2] == 0.5f);
    MR_CHECK(net->out_std[1] == 1.0f && net->out_mean[1] == -3.0f);
    int finite = 1;
    for (size_t q = 0; q < net->data_count; q++) finite &= isfinite(net->data[q]) != 0;
    MR_CHECK(finite && isfinite(r.best_validation_loss));
    float out[4];
    MR_CHECK_OK(mr_mlp_predict(net, x, 1, out));
    MR_CHECK(isfinite(out[0]) && isfinite(out[2]) && isfinite(out[3]));
    MR_CHECK_NEAR(out[1], -3.0, 0.1); // learnt: the constant output's normalised target is 0
    free(x);
    free(y);
    mr_mlp_free(net);
}

/* Targets that are pure noise: the validation loss soon rises, patience stops the run, and the returned weights
 * are those of the best epoch — the same bits as a run that stops at that epoch. */
MR_TEST(early_stopping_restores_the_best_weights) {
    const size_t n = 240;
    float *x = random_rows(n, 6, 91), *y = random_rows(n, 4, 92);
    mr_mlp_train_options o = {0};
    o.n_hidden = 64;
    o.batch_size = 16;
    o.max_epochs = 300;
    o.patience = 5;
    o.learning_rate = 1e-2;
    o.validation_fraction = 0.25;
    o.seed = 3;
    curve c = {0, -1, 1, 1, 0, {0}};
    o.epoch_fn = record_epoch;
    o.epoch_user = &c;
    mr_mlp *net = NULL, *again = NULL;
    mr_mlp_train_report r, r2;
    MR_CHECK_OK(mr_mlp_train(x, y, n, 6, 4, &o, &net, &r));
    MR_CHECK_MSG(r.stop == MR_MLP_STOP_PATIENCE, "stopped by %s after %d epochs", mr_mlp_stop_str(r.stop), r.epochs);
    MR_CHECK(r.epochs == r.best_epoch + 5 && r.epochs < 300);
    double lowest = INFINITY;
    for (int e = 0; e <= r.epochs && e < 512; e++) lowest = fmin(lowest, c.losses[e]);
    MR_CHECK(r.best_validation_loss == lowest && c.losses[r.best_epoch] == lowest);
    if (r.best_epoch > 0) {
        o.max_epochs = r.best_epoch;
        o.patience = 1000;
        o.epoch_fn = NULL;
        MR_CHECK_OK(mr_mlp_train(x, y, n, 6, 4, &o, &again, &r2));
        MR_CHECK(r2.stop == MR_MLP_STOP_MAX_EPOCHS && r2.best_epoch == r.best_epoch);
        MR_CHECK(same_net(net, again));
    } else {
        MR_CHECK_MSG(0, "the initial weights were the best: the case does not test restoring");
    }
    free(x);
    free(y);
    mr_mlp_free(net);
    mr_mlp_free(again);
}

MR_TEST(callback_stops_training_and_defaults_apply) {
    const size_t n = 100;
    float *x = random_rows(n, 6, 101), *y = malloc(n * 4 * sizeof(float));
    smooth_targets(x, n, y);
    curve c = {0, -1, 1, 1, 3, {0}};
    mr_mlp_train_options o = {0}; // defaults: 300 hidden units
    o.epoch_fn = record_epoch;
    o.epoch_user = &c;
    mr_mlp *net = NULL;
    mr_mlp_train_report r;
    MR_CHECK_OK(mr_mlp_train(x, y, n, 6, 4, &o, &net, &r));
    MR_CHECK(r.stop == MR_MLP_STOP_CALLBACK && r.epochs == 3 && c.calls == 4);
    MR_CHECK(strcmp(mr_mlp_stop_str(r.stop), "callback") == 0);
    MR_CHECK(strcmp(mr_mlp_stop_str(MR_MLP_STOP_COUNT), "unknown") == 0);
    MR_CHECK(net != NULL && net->n_hidden == MR_MLP_DEFAULT_HIDDEN && r.n_validation == 10);
    MR_CHECK(net != NULL && mr_mlp_param_count(net) == 300 * 7 + 4 * 301);
    free(x);
    free(y);
    mr_mlp_free(net);
}

MR_TEST(bad_arguments_are_refused) {
    float x[6 * 4], y[4 * 4];
    for (int q = 0; q < 24; q++) x[q] = (float)q;
    for (int q = 0; q < 16; q++) y[q] = (float)q;
    mr_mlp *net = NULL;
    mr_mlp_train_options o = {0};
    o.n_hidden = 4;
    o.max_epochs = 1;
    MR_CHECK(mr_mlp_train(x, y, 1, 6, 4, &o, &net, NULL) == MR_ERR_INVALID_ARG);
    MR_CHECK(mr_mlp_train(NULL, y, 4, 6, 4, &o, &net, NULL) == MR_ERR_INVALID_ARG);
    MR_CHECK(mr_mlp_train(x, y, 4, 0, 4, &o, &net, NULL) == MR_ERR_INVALID_ARG);
    MR_CHECK(mr_mlp_train(x, y, 4, 6, MR_MLP_MAX_IO + 1, &o, &net, NULL) == MR_ERR_INVALID_ARG);
    x[2 * 6 + 3] = NAN;
    MR_CHECK(mr_mlp_train(x, y, 4, 6, 4, &o, &net, NULL) == MR_ERR_INVALID_ARG);
    MR_CHECK_MSG(strstr(mr_last_error(), "input row 2, column 3") != NULL, "%s", mr_last_error());
    x[2 * 6 + 3] = 0.0f;
    y[3 * 4 + 1] = -INFINITY;
    MR_CHECK(mr_mlp_train(x, y, 4, 6, 4, &o, &net, NULL) == MR_ERR_INVALID_ARG);
    MR_CHECK(strstr(mr_last_error(), "target row 3, column 1") != NULL);
    y[3 * 4 + 1] = 0.0f;
    mr_mlp_train_options bad = o;
    bad.validation_fraction = 1.0;
    MR_CHECK(mr_mlp_train(x, y, 4, 6, 4, &bad, &net, NULL) == MR_ERR_INVALID_ARG);
    bad = o;
    bad.learning_rate = -1e-3;
    MR_CHECK(mr_mlp_train(x, y, 4, 6, 4, &bad, &net, NULL) == MR_ERR_INVALID_ARG);
    bad = o;
    bad.beta2 = 1.0;
    MR_CHECK(mr_mlp_train(x, y, 4, 6, 4, &bad, &net, NULL) == MR_ERR_INVALID_ARG);
    bad = o;
    bad.n_hidden = MR_MLP_MAX_HIDDEN + 1;
    MR_CHECK(mr_mlp_train(x, y, 4, 6, 4, &bad, &net, NULL) == MR_ERR_INVALID_ARG);
    MR_CHECK(net == NULL);
    MR_CHECK_OK(mr_mlp_train(x, y, 4, 6, 4, NULL, &net, NULL)); // NULL options: defaults
    MR_CHECK(mr_mlp_predict(net, NULL, 3, y) == MR_ERR_INVALID_ARG);
    MR_CHECK(mr_mlp_predict(NULL, x, 3, y) == MR_ERR_INVALID_ARG);
    MR_CHECK_OK(mr_mlp_predict(net, NULL, 0, NULL));
    double mse = -1;
    MR_CHECK(mr_mlp_evaluate(net, x, y, 0, &mse) == MR_ERR_INVALID_ARG && mse == -1);
    mr_mlp *made = NULL;
    MR_CHECK(mr_mlp_create(6, 0, 4, &made) == MR_ERR_INVALID_ARG && made == NULL);
    MR_CHECK(mr_mlp_create(4096, 65536, 1, &made) == MR_ERR_INVALID_ARG && made == NULL); // > MR_MLP_MAX_PARAMS
    MR_CHECK(strstr(mr_last_error(), "parameters") != NULL);
    mr_mlp_free(NULL);
    mr_mlp_free(net);
}

/* Not a check: prints the inference throughput of a 6 x 300 x 4 network when MR_NN_TIMING is set. */
MR_TEST(inference_throughput) {
    if (getenv("MR_NN_TIMING") == NULL) return;
    mr_mlp *net = random_net(6, 300, 4, 111);
    const size_t n = (size_t)1 << 20;
    float *x = random_rows(n, 6, 112), *y = malloc(n * 4 * sizeof(float));
    MR_CHECK_OK(mr_mlp_predict(net, x, n, y)); // warm-up
    double best = INFINITY, total = 0;
    int reps = 10;
    for (int k = 0; k < reps; k++) {
        double t0 = omp_get_wtime();
        MR_CHECK_OK(mr_mlp_predict(net, x, n, y));
        double t = omp_get_wtime() - t0;
        best = fmin(best, t);
        total += t;
    }
    printf("    6x300x4 inference, %zu rows, %d threads: best %.2f M texels/s, mean %.2f M texels/s\n", n,
           omp_get_max_threads(), (double)n / best / 1e6, (double)n * reps / total / 1e6);
    free(x);
    free(y);
    mr_mlp_free(net);
}

/* The line tokenizer the .mlp and .mrt readers share (src/text_lines.h): lines counted from 1, tokens split at
 * runs of spaces, a last line without its '\n' told apart from the end of the text. */
MR_TEST(text_lines_count_lines_and_split_tokens) {
    const char text[] = "w1  1 -2\n\nend";
    mr_text_lines t;
    mr_text_lines_init(&t, text, sizeof text - 1);
    const char *tok = NULL;
    size_t len = 0;
    MR_CHECK(mr_text_lines_next(&t) == MR_TEXT_LINE && t.line == 1 && t.line_start == text);
    MR_CHECK(mr_text_lines_token(&t, &tok, &len) && mr_text_token_is(tok, len, "w1"));
    MR_CHECK(mr_text_lines_token(&t, &tok, &len) && mr_text_token_is(tok, len, "1"));
    MR_CHECK(mr_text_lines_token(&t, &tok, &len) && mr_text_token_is(tok, len, "-2"));
    MR_CHECK(!mr_text_lines_token(&t, &tok, &len));
    MR_CHECK(mr_text_lines_next(&t) == MR_TEXT_LINE && t.line == 2 && !mr_text_lines_token(&t, &tok, &len));
    MR_CHECK(mr_text_lines_next(&t) == MR_TEXT_NO_LINE_END && t.line == 2); /* "end" has no '\n' */
    mr_text_lines_init(&t, "x\n", 2);
    MR_CHECK(mr_text_lines_next(&t) == MR_TEXT_LINE && mr_text_lines_next(&t) == MR_TEXT_END && t.line == 1);
    mr_text_lines_init(&t, NULL, 0);
    MR_CHECK(mr_text_lines_next(&t) == MR_TEXT_END);
    MR_CHECK(!mr_text_token_is("end", 3, "en") && !mr_text_token_is("en", 2, "end"));
}

/* mr_mlp_write_with_curve: the network and its loss curve as one set; a curve that cannot be written leaves no
 * network either. */
MR_TEST(network_written_with_its_loss_curve) {
    mr_mlp *net = random_net(3, 4, 2, 11);
    if (net == NULL) return;
    const mr_mlp_epoch epochs[3] = {{0, 2, 1.0, 0.9, 0, 0.9}, {1, 2, 0.5, 0.6, 1, 0.6}, {2, 2, 0.25, 0.7, 1, 0.6}};
    const char *path = mr_test_tmp_path("curved.mlp"), *prefix = mr_test_tmp_path("curved_loss");
    int drawn = -1;
    MR_CHECK_OK(mr_mlp_write_with_curve(net, path, epochs, 3, prefix, "--loss-curve", "a title", &drawn));
    MR_CHECK(drawn == 0 || drawn == 1);
    mr_mlp *back = NULL;
    MR_CHECK_OK(mr_mlp_read(path, &back));
    mr_mlp_free(back);
    char csv[1024], svg[1024];
    snprintf(csv, sizeof csv, "%s.csv", prefix);
    snprintf(svg, sizeof svg, "%s.svg", prefix);
    char *text = mr_test_read_file(csv, NULL);
    MR_CHECK(text != NULL && strcmp(text, "epoch,train_loss,validation_loss,best_epoch\n0,1,0.9,0\n1,0.5,0.6,1\n"
                                          "2,0.25,0.7,1\n") == 0);
    free(text);
    MR_CHECK((access(svg, F_OK) == 0) == (drawn == 1));
    // A prefix under a plain file: nothing is written, not even the network.
    const char *plain = mr_test_tmp_path("curve_plain"), *none = mr_test_tmp_path("not_written.mlp");
    MR_CHECK(mr_test_write_file(plain, "x", 1));
    char bad[1024];
    snprintf(bad, sizeof bad, "%s/sub/loss", plain);
    MR_CHECK(mr_mlp_write_with_curve(net, none, epochs, 3, bad, NULL, NULL, &drawn) != MR_OK);
    MR_CHECK(access(none, F_OK) != 0 && drawn == 0);
    MR_CHECK(mr_mlp_write_with_curve(NULL, none, epochs, 3, prefix, NULL, NULL, NULL) == MR_ERR_INVALID_ARG);
    mr_mlp_free(net);
}

MR_TEST_MAIN(MR_TEST_ENTRY(gradient_matches_central_differences), MR_TEST_ENTRY(predict_matches_scalar_reference),
             MR_TEST_ENTRY(predict_follows_values_changed_in_place),
             MR_TEST_ENTRY(predict_is_identical_for_1_and_2_threads),
             MR_TEST_ENTRY(nan_input_propagates_to_its_row_only),
             MR_TEST_ENTRY(weight_file_round_trips_bit_exactly), MR_TEST_ENTRY(bad_weight_files_are_rejected),
             MR_TEST_ENTRY(bad_writes_leave_files_alone), MR_TEST_ENTRY(training_learns_a_smooth_function),
             MR_TEST_ENTRY(training_is_deterministic_for_a_seed_and_any_thread_count),
             MR_TEST_ENTRY(constant_features_normalise_without_nan),
             MR_TEST_ENTRY(early_stopping_restores_the_best_weights),
             MR_TEST_ENTRY(callback_stops_training_and_defaults_apply), MR_TEST_ENTRY(bad_arguments_are_refused),
             MR_TEST_ENTRY(inference_throughput), MR_TEST_ENTRY(text_lines_count_lines_and_split_tokens),
             MR_TEST_ENTRY(network_written_with_its_loss_curve))
