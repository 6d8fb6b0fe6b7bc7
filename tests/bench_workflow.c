/*
 * bench_workflow.c — what the specular -> metallic conversion's accuracy costs in time (make bench;
 * docs/performance.md, "Workflow conversion").
 *
 * 1. Throughput: every method converts the same 2048^2 texture of seeded random specular texels (diffuse and F0
 *    uniform in [0, 1] per channel) on 1 and 2 threads; texels/s, best of 3, and the ratio to WEIGHTED (the
 *    analytic peer) measured in the same run.
 * 2. Accuracy: on the held-out sweep files of `make dataset` (test-on-manifold.csv, test-off-manifold.csv) every
 *    method's metallic parameters are rendered with `ggx-metallic` in the fit scene (64^2, alpha 0.2, the
 *    dataset's) against the source specular material rendered with `ggx`: mean SSIM and mean relative RMSE, and
 *    the RMSE of metallic against the optimiser's labels.
 * 3. MLP width: networks of 16, 32, 64, 128 and 300 hidden units trained as `make train` trains the default one
 *    (seed 1, same data), with their training time, accuracy as in 2 and inference throughput on 2 threads.
 * Usage: bench_workflow WEIGHTS DATASET_DIR [--quick]. Without the dataset, 2 and 3 are skipped (said so).
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
    double ssim, relative_rmse, metallic_rmse;
} accuracy;

/* Render every test pair's source (ggx) and the method's conversion (ggx-metallic) in the fit scene. */
static accuracy judge(const mr_render_plan *plan, const mr_mlp *net, mr_wf_method m, const mr_wf_dataset *test) {
    accuracy a = {0, 0, 0};
    size_t n = test->n;
    float *diffuse = malloc(n * 3 * sizeof *diffuse), *specular = malloc(n * 3 * sizeof *specular);
    float *albedo = malloc(n * 3 * sizeof *albedo), *metallic = malloc(n * sizeof *metallic);
    for (size_t i = 0; i < n; i++)
        for (int c = 0; c < 3; c++) {
            diffuse[3 * i + c] = test->x[6 * i + c];
            specular[3 * i + c] = test->x[6 * i + 3 + c];
        }
    omp_set_num_threads(2);
    if (convert(net, m, diffuse, specular, n, albedo, metallic) != MR_OK) {
        a.ssim = NAN;
        return a;
    }
    const mr_brdf_model *ggx = mr_brdf_find("ggx"), *metal = mr_brdf_find("ggx-metallic");
    double source[MR_BRDF_MAX_VALUES], target[MR_BRDF_MAX_VALUES];
    mr_brdf_default_values(ggx, source);
    mr_brdf_default_values(metal, target);
    int s_alpha = mr_brdf_param_offset(ggx, mr_brdf_param_index(ggx, "alpha"));
    int s_f0 = mr_brdf_param_offset(ggx, mr_brdf_param_index(ggx, "f0"));
    int s_diffuse = mr_brdf_param_offset(ggx, mr_brdf_param_index(ggx, "diffuse"));
    int t_albedo = mr_brdf_param_offset(metal, mr_brdf_param_index(metal, "albedo"));
    int t_metallic = mr_brdf_param_offset(metal, mr_brdf_param_index(metal, "metallic"));
    int t_alpha = mr_brdf_param_offset(metal, mr_brdf_param_index(metal, "alpha"));
    source[s_alpha] = target[t_alpha] = ALPHA;
    double ssim_sum = 0.0, rel_sum = 0.0, metal_sq = 0.0;
#pragma omp parallel for reduction(+ : ssim_sum, rel_sum, metal_sq) schedule(dynamic) firstprivate(source, target)
    for (size_t i = 0; i < n; i++) {
        for (int c = 0; c < 3; c++) {
            source[s_f0 + c] = specular[3 * i + c];
            source[s_diffuse + c] = diffuse[3 * i + c];
            target[t_albedo + c] = albedo[3 * i + c];
        }
        target[t_metallic] = metallic[i];
        mr_image *a_img = NULL, *b_img = NULL, *black = NULL;
        double ssim = 0.0, rmse = 0.0, rms = 0.0;
        if (mr_render(plan, ggx, source, MR_COMPONENT_FULL, &a_img) == MR_OK &&
            mr_render(plan, metal, target, MR_COMPONENT_FULL, &b_img) == MR_OK &&
            mr_image_create(FIT_SIZE, FIT_SIZE, 3, &black) == MR_OK &&
            mr_ssim(a_img, b_img, NULL, &ssim, NULL) == MR_OK && mr_rmse(a_img, b_img, &rmse) == MR_OK &&
            mr_rmse(a_img, black, &rms) == MR_OK) {
            ssim_sum += ssim;
            rel_sum += rmse / fmax(rms, 1e-4);
        }
        double d = metallic[i] - test->y[4 * i + 3];
        metal_sq += d * d;
        mr_image_free(a_img);
        mr_image_free(b_img);
        mr_image_free(black);
    }
    a.ssim = ssim_sum / (double)n;
    a.relative_rmse = rel_sum / (double)n;
    a.metallic_rmse = sqrt(metal_sq / (double)n);
    free(diffuse);
    free(specular);
    free(albedo);
    free(metallic);
    return a;
}

int main(int argc, char **argv) {
    if (argc < 3) {
        fprintf(stderr, "usage: bench_workflow WEIGHTS DATASET_DIR [--quick]\n");
        return 1;
    }
    int quick = argc > 3 && strcmp(argv[3], "--quick") == 0;
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

    char on_path[4096], off_path[4096], train_paths[2][4096];
    snprintf(on_path, sizeof on_path, "%s/test-on-manifold.csv", argv[2]);
    snprintf(off_path, sizeof off_path, "%s/test-off-manifold.csv", argv[2]);
    snprintf(train_paths[0], sizeof train_paths[0], "%s/on-manifold.csv", argv[2]);
    snprintf(train_paths[1], sizeof train_paths[1], "%s/off-manifold.csv", argv[2]);
    const char *on_files[1] = {on_path}, *off_files[1] = {off_path}, *train_files[2] = {train_paths[0], train_paths[1]};
    mr_wf_dataset on, off, train;
    if (mr_wf_dataset_load(on_files, 1, NULL, &on) != MR_OK ||
        mr_wf_dataset_load(off_files, 1, NULL, &off) != MR_OK ||
        mr_wf_dataset_load(train_files, 2, NULL, &train) != MR_OK) {
        printf("\n(accuracy and width tables skipped: %s; run make dataset)\n", mr_last_error());
        mr_mlp_free(net);
        return 0;
    }
    mr_fit_scene_options so = {FIT_SIZE, MR_FIT_LIGHT_45, 0};
    mr_scene scene = mr_scene_fit(&so);
    mr_render_plan *plan = NULL;
    if (mr_render_plan_create(&scene, &plan) != MR_OK) return 1;

    printf("\n### Accuracy on held-out materials (fit scene %d², GGX alpha %.1f, light 45°)\n\n", FIT_SIZE, ALPHA);
    printf("%zu materials on the Eq. 2 manifold and %zu off it (`make dataset`, test files). SSIM and relative RMSE: "
           "the converted metallic material's render against the specular source's; metallic RMSE: against the "
           "image-based optimiser's metallic.\n\n", on.n, off.n);
    printf("| method | on: SSIM | on: rel. RMSE | on: metallic RMSE | off: SSIM | off: rel. RMSE "
           "| off: metallic RMSE |\n|---|---|---|---|---|---|---|\n");
    for (int m = 0; m < METHOD_COUNT; m++) {
        fprintf(stderr, "accuracy: %s\n", methods[m].name);
        accuracy a = judge(plan, net, methods[m].method, &on), b = judge(plan, net, methods[m].method, &off);
        printf("| %s | %.5f | %.4f | %.4f | %.5f | %.4f | %.4f |\n", methods[m].name, a.ssim, a.relative_rmse,
               a.metallic_rmse, b.ssim, b.relative_rmse, b.metallic_rmse);
    }

    static const int widths[] = {16, 32, 64, 128, 300};
    int width_count = quick ? 2 : 5;
    printf("\n### MLP width (trained like `make train`: seed 1, %zu pairs)\n\n", train.n);
    printf("| hidden units | training (s) | epochs | off: SSIM | off: metallic RMSE | on: SSIM | inference, 2 threads "
           "(M texels/s) |\n|---|---|---|---|---|---|---|\n");
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
        double seconds = bench_now() - t0;
        accuracy a = judge(plan, trained, MR_WF_CUSTOM, &on), b = judge(plan, trained, MR_WF_CUSTOM, &off);
        double speed = throughput(trained, MR_WF_CUSTOM, diffuse, specular, n, albedo, metallic, 2);
        printf("| %d | %.1f | %d | %.5f | %.4f | %.5f | %.1f |\n", widths[w], seconds, r.epochs, b.ssim,
               b.metallic_rmse, a.ssim, speed / 1e6);
        mr_mlp_free(trained);
    }
    mr_render_plan_free(plan);
    mr_wf_dataset_free(&on);
    mr_wf_dataset_free(&off);
    mr_wf_dataset_free(&train);
    mr_mlp_free(net);
    free(diffuse);
    free(specular);
    free(albedo);
    free(metallic);
    return 0;
}
