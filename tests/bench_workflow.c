/*
 * bench_workflow.c — what the specular -> metallic conversion's accuracy costs in time (make bench;
 * docs/performance.md, "Workflow conversion").
 *
 * 1. Throughput: every method converts the same texels on 1 and 2 threads; texels/s, best of 3, and the ratio to
 *    WEIGHTED (the analytic peer) measured in the same run. Inputs: 2048^2 seeded random specular texels (diffuse
 *    and F0 uniform in [0, 1] per channel: every texel distinct and off the manifold, the network's worst case),
 *    and each --texture's real spec-gloss maps (read as glTF spec-gloss: the diffuse dimmed by 1 - max specular),
 *    which repeat their values as real textures do. --peer: a second network (the first one shipped) measured
 *    beside the default on the same texels. Under the random texels: the network's prediction alone, each of its
 *    kernels on 2 threads (EXACT, the unfused kernel of earlier versions, is the peer of the fused ones), their
 *    largest difference, and the floor: its FMAs per texel at this machine's FMA peak, measured by independent FMA
 *    chains on 1 and 2 cores (per second of CPU time: a core's peak whatever else the machine runs).
 * 2. Accuracy: on the held-out pairs of `make dataset` (test-pairs.csv) every method's answer and the labels
 *    themselves, rendered on a sphere under both shared HDR maps (held out of training) at glossiness 0.3, 0.6
 *    and 0.9: object SSIM against the spec-gloss texel (mr_wf_label_ssim), mean and worst, and the RMSE of
 *    metallic against the labels.
 * 3. MLP width: networks of 16, 32, 64, 128 and 300 hidden units trained as `make train` trains the default one
 *    (residual form, seed 1, same data), with their training time, accuracy as in 2 and inference throughput on
 *    2 threads.
 * Usage: bench_workflow WEIGHTS DATASET_DIR HDR HDR [--quick] [--peer NAME WEIGHTS]
 *                       [--texture NAME DIFFUSE SPECULAR_GLOSSINESS]...
 * Without the dataset or the HDR maps, 2 and 3 are skipped.
 * Prints Markdown on stdout, progress on stderr; asserts nothing.
 */
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bench_util.h"
#include "matremap.h"

#define SIDE 2048
#define ALPHA 0.2
#define FIT_SIZE 64

typedef struct method {
    const char *name;
    mr_wf_method method; /* MR_WF_CUSTOM: the network */
} method;

static const method methods[] = {
    {"mlp (6x300x4)", MR_WF_CUSTOM}, {"weighted", MR_WF_WEIGHTED}, {"mean", MR_WF_MEAN}, {"khronos", MR_WF_KHRONOS}};
#define METHOD_COUNT ((int)(sizeof methods / sizeof methods[0]))
#define MAX_TEXTURES 4

/* One set of texels to convert. */
typedef struct texel_set {
    char name[128];
    float *diffuse, *specular;
    size_t n;
    mr_wf_diffuse spec_diffuse; /* how the diffuse is read */
} texel_set;

static double uniform(unsigned long long *state) {
    unsigned long long z = (*state += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    z ^= z >> 31;
    return (double)(z >> 11) * (1.0 / 9007199254740992.0);
}

static mr_status convert_as(const mr_mlp *net, mr_wf_method m, mr_wf_diffuse spec_diffuse, const float *diffuse,
                            const float *specular, size_t n, float *albedo, float *metallic) {
    mr_wf_spec_input in = {(float *)diffuse, (float *)specular, NULL};
    mr_wf_metal_maps out = {albedo, metallic, NULL};
    mr_wf_options o = mr_wf_options_default();
    o.method = m == MR_WF_CUSTOM ? MR_WF_WEIGHTED : m;
    o.spec_diffuse = spec_diffuse;
    return m == MR_WF_CUSTOM ? mr_wf_spec_to_metal_mlp_batch(net, &in, n, &o, &out, NULL)
                             : mr_wf_spec_to_metal_batch(&in, n, &o, &out, NULL);
}

static mr_status convert(const mr_mlp *net, mr_wf_method m, const float *diffuse, const float *specular, size_t n,
                         float *albedo, float *metallic) {
    return convert_as(net, m, MR_WF_DIFFUSE_PLAIN, diffuse, specular, n, albedo, metallic);
}

/* Best-of-3 texels per second. */
static double throughput_of(const mr_mlp *net, mr_wf_method m, const texel_set *t, float *albedo, float *metallic,
                            int threads) {
    omp_set_num_threads(threads);
    double best = HUGE_VAL;
    for (int run = 0; run < 3; run++) {
        double t0 = bench_now();
        if (convert_as(net, m, t->spec_diffuse, t->diffuse, t->specular, t->n, albedo, metallic) != MR_OK) return NAN;
        best = fmin(best, bench_now() - t0);
    }
    return (double)t->n / best;
}

static double throughput(const mr_mlp *net, mr_wf_method m, const float *diffuse, const float *specular, size_t n,
                         float *albedo, float *metallic, int threads) {
    texel_set t = {"", (float *)diffuse, (float *)specular, n, MR_WF_DIFFUSE_PLAIN};
    return throughput_of(net, m, &t, albedo, metallic, threads);
}

static int compare_texel(const void *a, const void *b) { return memcmp(a, b, 6 * sizeof(float)); }

/* What makes a texel set easy or hard for the network: the share of distinct (diffuse, specular) values and, of
 * the texels, the share whose residual gate is open (those the network is asked about). */
static void texel_stats(const texel_set *t, double *distinct, double *gated) {
    float *rows = malloc(t->n * 6 * sizeof *rows);
    size_t open = 0;
    for (size_t i = 0; i < t->n; i++) {
        double lobe[3], spec[3], smax = 0.0;
        for (int c = 0; c < 3; c++) {
            rows[6 * i + c] = t->diffuse[3 * i + c];
            rows[6 * i + 3 + c] = t->specular[3 * i + c];
            spec[c] = fmin(1.0, fmax(0.0, t->specular[3 * i + c]));
            smax = fmax(smax, spec[c]);
        }
        for (int c = 0; c < 3; c++) {
            lobe[c] = fmin(1.0, fmax(0.0, t->diffuse[3 * i + c]));
            if (t->spec_diffuse == MR_WF_DIFFUSE_SPECGLOSS) lobe[c] *= 1.0 - smax;
        }
        mr_wf_residual_anchor a;
        mr_wf_residual_anchor_of(lobe, spec, &a);
        open += a.gate > 0.0;
    }
    qsort(rows, t->n, 6 * sizeof *rows, compare_texel);
    size_t unique = t->n > 0;
    for (size_t i = 1; i < t->n; i++) unique += memcmp(rows + 6 * i, rows + 6 * (i - 1), 6 * sizeof *rows) != 0;
    free(rows);
    *distinct = (double)unique / (double)t->n;
    *gated = (double)open / (double)t->n;
}

/* A texture's spec-gloss maps as a texel set: the diffuse map's RGB and the specular-glossiness map's RGB. */
static int load_texture(const char *name, const char *diffuse_path, const char *specular_path, texel_set *t) {
    mr_img_read_options ro = {MR_IMG_COLOR, 3, 0};
    mr_image *d = NULL, *s = NULL;
    if (mr_img_read(diffuse_path, &ro, &d) != MR_OK || mr_img_read(specular_path, &ro, &s) != MR_OK) {
        fprintf(stderr, "bench_workflow: %s\n", mr_last_error());
        mr_image_free(d);
        return -1;
    }
    if (d->width != s->width || d->height != s->height) {
        fprintf(stderr, "bench_workflow: %s: the maps differ in size\n", name);
        mr_image_free(d);
        mr_image_free(s);
        return -1;
    }
    snprintf(t->name, sizeof t->name, "%s %dx%d", name, d->width, d->height);
    t->n = (size_t)d->width * (size_t)d->height;
    t->diffuse = d->pixels;
    t->specular = s->pixels;
    t->spec_diffuse = MR_WF_DIFFUSE_SPECGLOSS;
    d->pixels = s->pixels = NULL;
    mr_image_free(d);
    mr_image_free(s);
    return 0;
}

typedef struct accuracy {
    double ssim, worst, metallic_rmse;
} accuracy;

/* The spec-gloss texel of a pair: the dataset holds the diffuse lobe d (1 - max s); d is recovered from it. */
static mr_wf_spec pair_texel(const mr_wf_dataset *d, size_t i) {
    mr_wf_spec t = {{0, 0, 0}, {0, 0, 0}, 0};
    double smax = fmax(d->x[6 * i + 3], fmax(d->x[6 * i + 4], d->x[6 * i + 5]));
    for (int c = 0; c < 3; c++) {
        t.specular[c] = d->x[6 * i + 3 + c];
        t.diffuse[c] = smax < 1.0 ? fmin(1.0, d->x[6 * i + c] / (1.0 - smax)) : 0.0;
    }
    return t;
}

/* Every test pair converted by the method (net == NULL and m == MR_WF_METHOD_COUNT: the labels), judged by object
 * SSIM under the evaluation scene. */
static accuracy judge(const mr_wf_label_scene *eval, const mr_mlp *net, mr_wf_method m, const mr_wf_dataset *test) {
    accuracy a = {0, 1, 0};
    size_t n = test->n;
    float *diffuse = malloc(n * 3 * sizeof *diffuse), *specular = malloc(n * 3 * sizeof *specular);
    float *albedo = malloc(n * 3 * sizeof *albedo), *metallic = malloc(n * sizeof *metallic);
    for (size_t i = 0; i < n; i++) {
        for (int c = 0; c < 3; c++) {
            diffuse[3 * i + c] = test->x[6 * i + c];
            specular[3 * i + c] = test->x[6 * i + 3 + c];
            albedo[3 * i + c] = test->y[4 * i + c];
        }
        metallic[i] = test->y[4 * i + 3];
    }
    omp_set_num_threads(2);
    if (m != MR_WF_METHOD_COUNT && convert(net, m, diffuse, specular, n, albedo, metallic) != MR_OK) {
        a.ssim = NAN;
        return a;
    }
    double ssim_sum = 0.0, worst = 1.0, metal_sq = 0.0;
#pragma omp parallel for reduction(+ : ssim_sum, metal_sq) reduction(min : worst) schedule(dynamic)
    for (size_t i = 0; i < n; i++) {
        mr_wf_spec t = pair_texel(test, i);
        mr_wf_metal answer = {{albedo[3 * i], albedo[3 * i + 1], albedo[3 * i + 2]}, metallic[i], 0};
        double ssim = 0.0;
        if (mr_wf_label_ssim(eval, &t, &answer, &ssim) == MR_OK) {
            ssim_sum += ssim;
            worst = fmin(worst, ssim);
        }
        double d = metallic[i] - test->y[4 * i + 3];
        metal_sq += d * d;
    }
    a.ssim = ssim_sum / (double)n;
    a.worst = worst;
    a.metallic_rmse = sqrt(metal_sq / (double)n);
    free(diffuse);
    free(specular);
    free(albedo);
    free(metallic);
    return a;
}

/* This machine's fused multiply-adds per second on `threads` threads, measured: 16 independent chains of vector FMAs
 * per thread, unrolled so that they stay in registers (enough to cover the latency of every FMA unit), best of 5.
 * *lanes gets the floats per vector. */
#if defined(__GNUC__) && defined(__x86_64__)
#include <immintrin.h>
#define PEAK_ITERATIONS 20000000L
__attribute__((target("avx512f"))) static double fma_chains_avx512(void) {
    __m512 acc[16], a = _mm512_set1_ps(0.999999f), b = _mm512_set1_ps(1e-7f);
    for (int q = 0; q < 16; q++) acc[q] = _mm512_set1_ps((float)q);
    for (long it = 0; it < PEAK_ITERATIONS; it++)
        _Pragma("GCC unroll 16") for (int q = 0; q < 16; q++) acc[q] = _mm512_fmadd_ps(acc[q], a, b);
    float sum = 0.0f, lane[16];
    for (int q = 0; q < 16; q++) {
        _mm512_storeu_ps(lane, acc[q]);
        sum += lane[0];
    }
    return sum; // keeps the chains alive
}

__attribute__((target("avx2,fma"))) static double fma_chains_avx2(void) {
    __m256 acc[16], a = _mm256_set1_ps(0.999999f), b = _mm256_set1_ps(1e-7f);
    for (int q = 0; q < 16; q++) acc[q] = _mm256_set1_ps((float)q);
    for (long it = 0; it < PEAK_ITERATIONS; it++)
        _Pragma("GCC unroll 16") for (int q = 0; q < 16; q++) acc[q] = _mm256_fmadd_ps(acc[q], a, b);
    float sum = 0.0f, lane[8];
    for (int q = 0; q < 16; q++) {
        _mm256_storeu_ps(lane, acc[q]);
        sum += lane[0];
    }
    return sum;
}

/* Each thread's chains timed by its own CPU clock: the rate of a core while it runs them, whatever else the machine
 * runs (a shared machine's wall clock would measure its other jobs); the cores' rates added. */
static double peak_fmas(int threads, int *lanes) {
    __builtin_cpu_init();
    int wide = __builtin_cpu_supports("avx512f");
    if (!wide && !__builtin_cpu_supports("fma")) return NAN;
    *lanes = wide ? 16 : 8;
    double best = 0.0, sink = 0.0;
    for (int run = 0; run < 5; run++) {
        double total = 0.0;
#pragma omp parallel num_threads(threads) reduction(+ : sink, total)
        {
            struct timespec t0, t1;
            clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t0);
            sink += wide ? fma_chains_avx512() : fma_chains_avx2();
            clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t1);
            double seconds = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
            total += 16.0 * *lanes * PEAK_ITERATIONS / seconds;
        }
        best = fmax(best, total);
    }
    if (sink == 12345.0) fprintf(stderr, "(sink)\n");
    return best;
}
#else
static double peak_fmas(int threads, int *lanes) {
    (void)threads;
    *lanes = 0;
    return NAN;
}
#endif

/* The network's kernels on the same rows (2 threads), the previous one (EXACT: unfused, the kernel before the fused
 * ones) as the peer, and the physical floor: the network's FMAs per row at this machine's measured peak. */
static void network_floor(const mr_mlp *net, const float *rows, size_t n, float *y, double batch_rate) {
    double rate[MR_MLP_KERNEL_COUNT] = {0};
    mr_mlp_kernel chosen = MR_MLP_KERNEL_AUTO;
    if (mr_mlp_kernel_auto(&chosen) != MR_OK) return;
    printf("\nThe network's kernels alone (mr_mlp_predict_kernel, 2 threads, M rows/s, best of 3; the batch uses %s):",
           mr_mlp_kernel_name(chosen));
    for (int k = MR_MLP_KERNEL_SSE2; k < MR_MLP_KERNEL_COUNT; k++) {
        if (!mr_mlp_kernel_available((mr_mlp_kernel)k)) continue;
        double best = HUGE_VAL;
        for (int run = 0; run < 3; run++) {
            double t0 = bench_now();
            if (mr_mlp_predict_kernel(net, rows, n, y, 2, (mr_mlp_kernel)k) != MR_OK) break;
            best = fmin(best, bench_now() - t0);
        }
        rate[k] = (double)n / best;
        printf(" %s %.1f%s", mr_mlp_kernel_name((mr_mlp_kernel)k), rate[k] / 1e6,
               k == MR_MLP_KERNEL_EXACT ? " (the previous kernel)" : "");
    }
    printf("; %s over exact: %.2f×.", mr_mlp_kernel_name(chosen), rate[chosen] / rate[MR_MLP_KERNEL_EXACT]);
    float *other = malloc(n * (size_t)net->n_out * sizeof *other);
    if (other != NULL && mr_mlp_predict_kernel(net, rows, n, y, 2, chosen) == MR_OK &&
        mr_mlp_predict_kernel(net, rows, n, other, 2, MR_MLP_KERNEL_EXACT) == MR_OK) {
        double worst = 0.0;
        for (size_t q = 0; q < n * (size_t)net->n_out; q++) worst = fmax(worst, fabs((double)y[q] - other[q]));
        printf(" Largest |%s - exact| over the %zu x %d outputs: %.2g.", mr_mlp_kernel_name(chosen), n, net->n_out,
               worst);
    }
    free(other);
    printf("\n");
    int lanes = 0;
    double one = peak_fmas(1, &lanes), two = peak_fmas(2, &lanes);
    double fmas = (double)net->n_hidden * (net->n_in + net->n_out);
    if (isnan(one)) return;
    printf("\nThe floor: %.0f FMAs per texel (%d x %d + %d x %d). This machine's measured peak (16 independent %d-lane "
           "FMA chains per thread, per second of the thread's CPU time): %.1f G FMA/s on 1 core (lanes x FMA units x "
           "GHz), %.1f on 2, so at most %.1f M texels/s on 2 cores. The network alone reaches %.0f %% of it, the "
           "whole batch %.0f %% (wall clock: less on a machine shared with other jobs).\n",
           fmas, net->n_in, net->n_hidden, net->n_hidden, net->n_out, lanes, one / 1e9, two / 1e9,
           two / fmas / 1e6, 100.0 * rate[chosen] * fmas / two, 100.0 * batch_rate * fmas / two);
}

int main(int argc, char **argv) {
    if (argc < 3) {
        fprintf(stderr, "usage: bench_workflow WEIGHTS DATASET_DIR HDR HDR [--quick] [--peer NAME WEIGHTS] "
                        "[--texture NAME DIFFUSE SPECULAR_GLOSSINESS]...\n");
        return 1;
    }
    int quick = 0;
    const char *peer_name = NULL, *peer_path = NULL;
    texel_set sets[1 + MAX_TEXTURES];
    int set_count = 1;
    for (int i = 5; i < argc; i++) {
        if (strcmp(argv[i], "--quick") == 0) {
            quick = 1;
        } else if (strcmp(argv[i], "--peer") == 0 && i + 2 < argc) {
            peer_name = argv[i + 1];
            peer_path = argv[i + 2];
            i += 2;
        } else if (strcmp(argv[i], "--texture") == 0 && i + 3 < argc && set_count <= MAX_TEXTURES) {
            if (load_texture(argv[i + 1], argv[i + 2], argv[i + 3], &sets[set_count]) != 0) return 1;
            set_count++;
            i += 3;
        } else {
            fprintf(stderr, "bench_workflow: unknown or incomplete option '%s'\n", argv[i]);
            return 1;
        }
    }
    mr_mlp *net = NULL, *peer = NULL;
    if (mr_mlp_read(argv[1], &net) != MR_OK || (peer_path && mr_mlp_read(peer_path, &peer) != MR_OK)) {
        fprintf(stderr, "bench_workflow: %s\n", mr_last_error());
        return 1;
    }
    size_t n = quick ? (size_t)512 * 512 : (size_t)SIDE * SIDE, most = n;
    for (int t = 1; t < set_count; t++) most = sets[t].n > most ? sets[t].n : most;
    float *diffuse = malloc(n * 3 * sizeof *diffuse), *specular = malloc(n * 3 * sizeof *specular);
    float *albedo = malloc(most * 3 * sizeof *albedo), *metallic = malloc(most * sizeof *metallic);
    if (!diffuse || !specular || !albedo || !metallic) return 1;
    unsigned long long state = 42;
    for (size_t i = 0; i < 3 * n; i++) {
        diffuse[i] = (float)uniform(&state);
        specular[i] = (float)uniform(&state);
    }
    sets[0] = (texel_set){"", diffuse, specular, n, MR_WF_DIFFUSE_PLAIN};
    snprintf(sets[0].name, sizeof sets[0].name, "random texels %zu", n);

    printf("### Throughput\n\n");
    printf("M texels/s, best of 3; every method on the same texels. Random texels: diffuse and F0 uniform in [0, 1] "
           "per channel, every texel distinct and off the Eq. 2 manifold (the network's worst case: it runs on "
           "every one). Textures: real 8-bit spec-gloss maps read as glTF spec-gloss, which repeat their values "
           "(the network runs once per distinct value whose gate is open).%s\n\n",
           peer ? " The peer network is measured on the same texels in the same run." : "");
    for (int t = 0; t < set_count; t++) {
        double distinct, gated;
        texel_stats(&sets[t], &distinct, &gated);
        printf("**%s** (%.1f %% distinct values, gate open on %.1f %% of texels)\n\n", sets[t].name,
               100.0 * distinct, 100.0 * gated);
        printf("| method | 1 thread | 2 threads | 2048² texture, 2 threads (ms) | time vs weighted (2 threads) |\n"
               "|---|---|---|---|---|\n");
        double rate[METHOD_COUNT + 1][2];
        for (int m = 0; m <= METHOD_COUNT; m++) {
            if (m == METHOD_COUNT && !peer) break;
            fprintf(stderr, "throughput: %s, %s\n", sets[t].name, m < METHOD_COUNT ? methods[m].name : peer_name);
            for (int k = 0; k < 2; k++)
                rate[m][k] = throughput_of(m < METHOD_COUNT ? net : peer, m < METHOD_COUNT ? methods[m].method
                                           : MR_WF_CUSTOM, &sets[t], albedo, metallic, k + 1);
        }
        for (int m = 0; m <= METHOD_COUNT; m++) {
            if (m == METHOD_COUNT && !peer) break;
            printf("| %s | %.1f | %.1f | %.0f | %.2f× |\n", m < METHOD_COUNT ? methods[m].name : peer_name,
                   rate[m][0] / 1e6, rate[m][1] / 1e6, 1e3 * (double)SIDE * SIDE / rate[m][1], rate[1][1] / rate[m][1]);
        }
        if (t == 0) { // the network's own arithmetic on these rows: the ceiling of any texel-by-texel path
            float *rows = malloc(sets[0].n * 6 * sizeof *rows), *y = malloc(sets[0].n * 4 * sizeof *y);
            double best[2] = {HUGE_VAL, HUGE_VAL};
            for (size_t i = 0; rows && i < sets[0].n; i++)
                for (int c = 0; c < 3; c++) {
                    rows[6 * i + c] = sets[0].diffuse[3 * i + c];
                    rows[6 * i + 3 + c] = sets[0].specular[3 * i + c];
                }
            for (int k = 0; rows && y && k < 2; k++) {
                omp_set_num_threads(k + 1);
                for (int run = 0; run < 3; run++) {
                    double t0 = bench_now();
                    if (mr_mlp_predict(net, rows, sets[0].n, y) != MR_OK) break;
                    best[k] = fmin(best[k], bench_now() - t0);
                }
            }
            printf("\nThe 6x300x4 network's prediction alone (mr_mlp_predict) on the same rows: %.1f M rows/s on 1 "
                   "thread, %.1f on 2: no texel-by-texel path through it can be faster here.\n",
                   (double)sets[0].n / best[0] / 1e6, (double)sets[0].n / best[1] / 1e6);
            if (rows && y) network_floor(net, rows, sets[0].n, y, rate[0][1]);
            free(rows);
            free(y);
        }
        printf("\n");
    }
    for (int t = 1; t < set_count; t++) {
        free(sets[t].diffuse);
        free(sets[t].specular);
    }
    mr_mlp_free(peer);

    char test_path[4096], train_path[4096];
    snprintf(test_path, sizeof test_path, "%s/test-pairs.csv", argv[2]);
    snprintf(train_path, sizeof train_path, "%s/pairs.csv", argv[2]);
    const char *test_files[1] = {test_path}, *train_files[1] = {train_path};
    mr_wf_dataset test, train;
    mr_img_read_options ro = {MR_IMG_DATA, 3, 0};
    mr_image *envs[2] = {NULL, NULL};
    if (mr_wf_dataset_load(test_files, 1, NULL, &test) != MR_OK ||
        mr_wf_dataset_load(train_files, 1, NULL, &train) != MR_OK || argc < 5 ||
        mr_img_read(argv[3], &ro, &envs[0]) != MR_OK || mr_img_read(argv[4], &ro, &envs[1]) != MR_OK) {
        printf("(accuracy and width tables skipped: %s; run make dataset)\n", mr_last_error());
        mr_mlp_free(net);
        return 0;
    }
    if (quick) test.n = test.n < 200 ? test.n : 200;
    mr_wf_label_options eo = mr_wf_label_options_default();
    eo.size = 64;
    eo.env_count = 2;
    eo.envs[0] = envs[0];
    eo.envs[1] = envs[1];
    eo.glossiness_count = 3;
    eo.glossiness[0] = 0.3;
    eo.glossiness[1] = 0.6;
    eo.glossiness[2] = 0.9;
    mr_wf_label_scene *eval = NULL;
    if (mr_wf_label_scene_create(&eo, &eval) != MR_OK) return 1;

    printf("### Accuracy on held-out texels (object SSIM under the shared HDR maps)\n\n");
    printf("%zu held-out pairs of `make dataset` (test-pairs.csv, seed 2). Each answer rendered on a 64² sphere under "
           "both shared HDR maps (held out of training) at glossiness 0.3, 0.6, 0.9: SSIM over the sphere's inner "
           "square against the spec-gloss texel, mean and worst; metallic RMSE against the labels.\n\n", test.n);
    printf("| method | object SSIM (mean) | object SSIM (worst) | metallic RMSE vs labels |\n|---|---|---|---|\n");
    accuracy lab = judge(eval, NULL, MR_WF_METHOD_COUNT, &test);
    printf("| labels (the optimum the network learns) | %.5f | %.4f | 0 |\n", lab.ssim, lab.worst);
    for (int m = 0; m < METHOD_COUNT; m++) {
        fprintf(stderr, "accuracy: %s\n", methods[m].name);
        accuracy a = judge(eval, net, methods[m].method, &test);
        printf("| %s | %.5f | %.4f | %.4f |\n", methods[m].name, a.ssim, a.worst, a.metallic_rmse);
    }
    static const int widths[] = {16, 32, 64, 128, 300};
    int width_count = quick ? 2 : 5;
    printf("\n### MLP width (trained like `make train`: seed 1, %zu pairs)\n\n", train.n);
    printf("| hidden units | training (s) | epochs | object SSIM (mean) | object SSIM (worst) | metallic RMSE | "
           "inference, 2 threads (M texels/s) |\n|---|---|---|---|---|---|---|\n");
    mr_wf_residual_targets(train.x, train.y, train.n);
    for (int w = 0; w < width_count; w++) {
        fprintf(stderr, "width %d\n", widths[w]);
        mr_mlp_train_options o;
        memset(&o, 0, sizeof o);
        o.n_hidden = widths[w];
        o.seed = 1;
        mr_mlp *trained = NULL;
        mr_mlp_train_report r;
        double t0 = bench_now();
        if (mr_mlp_train(train.x, train.y, train.n, 6, 4, &o, &trained, &r) != MR_OK) return 1;
        snprintf(trained->kind, sizeof trained->kind, "%s", MR_WF_MLP_RESIDUAL_KIND);
        double seconds = bench_now() - t0;
        accuracy a = judge(eval, trained, MR_WF_CUSTOM, &test);
        double speed = throughput(trained, MR_WF_CUSTOM, diffuse, specular, n, albedo, metallic, 2);
        printf("| %d | %.1f | %d | %.5f | %.4f | %.4f | %.1f |\n", widths[w], seconds, r.epochs, a.ssim, a.worst,
               a.metallic_rmse, speed / 1e6);
        mr_mlp_free(trained);
    }
    mr_wf_label_scene_free(eval);
    mr_image_free(envs[0]);
    mr_image_free(envs[1]);
    mr_wf_dataset_free(&test);
    mr_wf_dataset_free(&train);
    mr_mlp_free(net);
    free(diffuse);
    free(specular);
    free(albedo);
    free(metallic);
    return 0;
}
