/*
 * bench_workflow.c — what the specular -> metallic conversion's accuracy costs in time (make bench;
 * docs/performance.md, "Workflow conversion").
 *
 * 1. Throughput: every method converts the same 2048^2 texture of seeded random specular texels (diffuse and F0
 *    uniform in [0, 1] per channel) on 1 and 2 threads; texels/s, best of 3, and the ratio to WEIGHTED (the
 *    analytic peer) measured in the same run.
 * 2. Accuracy: on the held-out pairs of `make dataset` (test-pairs.csv) every method's answer and the labels
 *    themselves, rendered on a sphere under both shared HDR maps (held out of training) at glossiness 0.3, 0.6
 *    and 0.9: object SSIM against the spec-gloss texel (mr_wf_label_ssim), mean and worst, and the RMSE of
 *    metallic against the labels.
 * 3. MLP width: networks of 16, 32, 64, 128 and 300 hidden units trained as `make train` trains the default one
 *    (residual form, seed 1, same data), with their training time, accuracy as in 2 and inference throughput on
 *    2 threads.
 * Usage: bench_workflow WEIGHTS DATASET_DIR HDR HDR [--quick]. Without the dataset, 2 and 3 are skipped.
 * Prints Markdown on stdout, progress on stderr; asserts nothing.
 */
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

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

static double uniform(unsigned long long *state) {
    unsigned long long z = (*state += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    z ^= z >> 31;
    return (double)(z >> 11) * (1.0 / 9007199254740992.0);
}

static mr_status convert(const mr_mlp *net, mr_wf_method m, const float *diffuse, const float *specular, size_t n,
                         float *albedo, float *metallic) {
    mr_wf_spec_maps in = {(float *)diffuse, (float *)specular, NULL};
    mr_wf_metal_maps out = {albedo, metallic, NULL};
    mr_wf_options o = mr_wf_options_default();
    o.method = m == MR_WF_CUSTOM ? MR_WF_WEIGHTED : m;
    return m == MR_WF_CUSTOM ? mr_wf_spec_to_metal_mlp_batch(net, &in, n, &o, &out, NULL)
                             : mr_wf_spec_to_metal_batch(&in, n, &o, &out, NULL);
}

/* Best-of-3 texels per second. */
static double throughput(const mr_mlp *net, mr_wf_method m, const float *diffuse, const float *specular, size_t n,
                         float *albedo, float *metallic, int threads) {
    omp_set_num_threads(threads);
    double best = HUGE_VAL;
    for (int run = 0; run < 3; run++) {
        double t0 = bench_now();
        if (convert(net, m, diffuse, specular, n, albedo, metallic) != MR_OK) return NAN;
        best = fmin(best, bench_now() - t0);
    }
    return (double)n / best;
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

int main(int argc, char **argv) {
    if (argc < 3) {
        fprintf(stderr, "usage: bench_workflow WEIGHTS DATASET_DIR HDR HDR [--quick]\n");
        return 1;
    }
    int quick = argc > 5 && strcmp(argv[5], "--quick") == 0;
    mr_mlp *net = NULL;
    if (mr_mlp_read(argv[1], &net) != MR_OK) {
        fprintf(stderr, "bench_workflow: %s\n", mr_last_error());
        return 1;
    }
    size_t n = quick ? (size_t)512 * 512 : (size_t)SIDE * SIDE;
    float *diffuse = malloc(n * 3 * sizeof *diffuse), *specular = malloc(n * 3 * sizeof *specular);
    float *albedo = malloc(n * 3 * sizeof *albedo), *metallic = malloc(n * sizeof *metallic);
    if (!diffuse || !specular || !albedo || !metallic) return 1;
    unsigned long long state = 42;
    for (size_t i = 0; i < 3 * n; i++) {
        diffuse[i] = (float)uniform(&state);
        specular[i] = (float)uniform(&state);
    }

    printf("### Throughput (%zu texels, random specular texels)\n\n", n);
    printf("| method | 1 thread (M texels/s) | 2 threads (M texels/s) | 2048² texture, 2 threads (ms) | "
           "time vs weighted (2 threads) |\n|---|---|---|---|---|\n");
    double rate[METHOD_COUNT][2];
    for (int m = 0; m < METHOD_COUNT; m++) {
        fprintf(stderr, "throughput: %s\n", methods[m].name);
        for (int t = 0; t < 2; t++)
            rate[m][t] = throughput(net, methods[m].method, diffuse, specular, n, albedo, metallic, t + 1);
    }
    for (int m = 0; m < METHOD_COUNT; m++)
        printf("| %s | %.1f | %.1f | %.0f | %.2f× |\n", methods[m].name, rate[m][0] / 1e6, rate[m][1] / 1e6,
               1e3 * (double)SIDE * SIDE / rate[m][1], rate[1][1] / rate[m][1]);

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
        printf("\n(accuracy and width tables skipped: %s; run make dataset)\n", mr_last_error());
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

    printf("\n### Accuracy on held-out texels (object SSIM under the shared HDR maps)\n\n");
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
