/*
 * bench_envlight.c — environment lights: error against the pattern size N, and what N costs (make bench).
 *
 * Prints Markdown tables on stdout; asserts nothing. docs/rendering.md shows them (scripts/bench.sh rewrites its
 * bench:envlight section).
 *   1. Accuracy: the fit scene's camera and sphere lit by each real HDR map (normalised to a mean radiance of 1
 *      over the sphere of directions, so SSIM's display mapping sees the sphere's own range), 128^2, for Lambert
 *      and for a specular-only GGX at three roughnesses. Each render at N directions is compared with the render
 *      at N = 65536 (the reference; its own error is about a quarter of N = 16384's): relative RMSE
 *      (RMSE / RMS of the reference, linear RGB) and SSIM (docs/metrics.md).
 *   2. Cost: plan creation (pattern + per-hit direction indices) and median render time with the plan prepared,
 *      256^2, 1 and 2 OpenMP threads, plan memory; the point-light fit scene for scale.
 * Usage: bench_envlight HDRI_DIR [--quick]   (HDRI_DIR holds studio_small_03_1k.hdr and tabac_plant_vogl.hdr)
 */
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench_util.h"
#include "matremap.h"
#include "render/render_internal.h"

#define REFERENCE_N 65536
#define ACCURACY_SIZE 128
#define COST_SIZE 256

typedef struct material {
    const char *label;
    const char *model;
    double values[7];
} material;

/* Lambert, and GGX metal-like (f0 0.9, no diffuse) so that the specular lobe alone is measured. */
static const material materials[] = {
    {"lambert albedo 0.8", "lambert", {0.8, 0.8, 0.8}},
    {"ggx alpha 0.5", "ggx", {0.5, 0.9, 0.9, 0.9, 0.0, 0.0, 0.0}},
    {"ggx alpha 0.2", "ggx", {0.2, 0.9, 0.9, 0.9, 0.0, 0.0, 0.0}},
    {"ggx alpha 0.05", "ggx", {0.05, 0.9, 0.9, 0.9, 0.0, 0.0, 0.0}},
};
#define MATERIAL_COUNT ((int)(sizeof materials / sizeof materials[0]))

static const int accuracy_ns[] = {16, 64, 256, 1024, 4096, 16384};
#define ACCURACY_N_COUNT ((int)(sizeof accuracy_ns / sizeof accuracy_ns[0]))

static void die(const char *what) {
    fprintf(stderr, "bench_envlight: %s: %s\n", what, mr_last_error());
    exit(3);
}

/* 1 / (mean luminance over the sphere of directions): the scale that gives the map a mean radiance of 1. */
static double normalising_scale(const mr_image *map) {
    double sum = 0.0, weight = 0.0;
    for (int j = 0; j < map->height; j++) {
        double s = sin(3.14159265358979323846 * (j + 0.5) / map->height);
        for (int i = 0; i < map->width; i++) {
            const float *px = mr_image_at(map, i, j);
            sum += s * (0.2126 * px[0] + 0.7152 * px[1] + 0.0722 * px[2]);
        }
        weight += s * map->width;
    }
    return weight / sum;
}

static mr_render_plan *make_plan(int size, const mr_image *map, double scale, int samples, double *ms) {
    mr_scene scene = mr_scene_fit(&(mr_fit_scene_options){size, MR_FIT_LIGHT_45, 0});
    scene.lights[0] = mr_light_environment(map, scale, 0.0, samples);
    mr_render_plan *plan = NULL;
    double t0 = bench_now();
    if (mr_render_plan_create(&scene, &plan) != MR_OK) die("plan");
    if (ms != NULL) *ms = 1e3 * (bench_now() - t0);
    return plan;
}

static mr_image *render(const mr_render_plan *plan, const material *m) {
    mr_image *img = NULL;
    if (mr_render(plan, mr_brdf_find(m->model), m->values, MR_COMPONENT_FULL, &img) != MR_OK) die("render");
    return img;
}

/* RMSE(a, ref) / RMS(ref) over linear RGB. */
static double relative_rmse(const mr_image *a, const mr_image *ref) {
    double rmse = 0.0, rms = 0.0;
    if (mr_rmse(a, ref, &rmse) != MR_OK) die("rmse");
    for (size_t i = 0; i < mr_image_value_count(ref); i++) rms += (double)ref->pixels[i] * ref->pixels[i];
    rms = sqrt(rms / (double)mr_image_value_count(ref));
    return rmse / rms;
}

/* Median wall time of one render in ms: at least `min_reps` renders and at least `min_seconds` in all. */
static double time_render(const mr_render_plan *plan, const material *m, mr_image *image, int min_reps,
                          double min_seconds) {
    double samples[64];
    int count = 0;
    const mr_brdf_model *model = mr_brdf_find(m->model);
    // the threads the caller set (omp_set_num_threads), not the automatic rule's choice for this plan
    const int threads = omp_get_max_threads();
    mr_render_into_threads(plan, threads, model, m->values, MR_COMPONENT_FULL, image); // warm caches and threads
    double start = bench_now();
    while (count < 64 && (count < min_reps || bench_now() - start < min_seconds)) {
        double t0 = bench_now();
        mr_render_into_threads(plan, threads, model, m->values, MR_COMPONENT_FULL, image);
        samples[count++] = 1e3 * (bench_now() - t0);
    }
    return bench_median(samples, count);
}

int main(int argc, char **argv) {
    if (argc < 2) {
        fprintf(stderr, "usage: bench_envlight HDRI_DIR [--quick]\n");
        return 1;
    }
    int quick = argc > 2 && strcmp(argv[2], "--quick") == 0;
    const char *names[2] = {"studio_small_03_1k.hdr", "tabac_plant_vogl.hdr"};
    mr_image *maps[2] = {NULL, NULL};
    double scales[2];
    for (int k = 0; k < 2; k++) {
        char path[4096];
        snprintf(path, sizeof path, "%s/%s", argv[1], names[k]);
        if (mr_img_read(path, NULL, &maps[k]) != MR_OK) {
            printf("(environment maps not found in %s: %s)\n", argv[1], mr_last_error());
            return 0;
        }
        scales[k] = normalising_scale(maps[k]);
    }

    // 1. Accuracy against the N = 65536 reference.
    double rel[2][MATERIAL_COUNT][ACCURACY_N_COUNT], ssim[2][MATERIAL_COUNT][ACCURACY_N_COUNT];
    const int n_count = quick ? ACCURACY_N_COUNT - 1 : ACCURACY_N_COUNT;
    for (int k = 0; k < 2; k++) {
        mr_render_plan *ref_plan = make_plan(ACCURACY_SIZE, maps[k], scales[k], quick ? 16384 : REFERENCE_N, NULL);
        mr_image *refs[MATERIAL_COUNT];
        for (int m = 0; m < MATERIAL_COUNT; m++) refs[m] = render(ref_plan, &materials[m]);
        mr_render_plan_free(ref_plan);
        for (int i = 0; i < n_count; i++) {
            mr_render_plan *plan = make_plan(ACCURACY_SIZE, maps[k], scales[k], accuracy_ns[i], NULL);
            for (int m = 0; m < MATERIAL_COUNT; m++) {
                mr_image *img = render(plan, &materials[m]);
                rel[k][m][i] = relative_rmse(img, refs[m]);
                if (mr_ssim(img, refs[m], NULL, &ssim[k][m][i], NULL) != MR_OK) die("ssim");
                mr_image_free(img);
            }
            mr_render_plan_free(plan);
        }
        for (int m = 0; m < MATERIAL_COUNT; m++) mr_image_free(refs[m]);
    }
    printf("Fit-scene camera and unit sphere, %d², lit only by the map, normalised to mean radiance 1 (scale %.4g "
           "for\n%s, %.4g for %s), no rotation; ggx is specular only (f0 0.9, diffuse 0).\nEach image is "
           "compared with the render at N = %d.\n\n", ACCURACY_SIZE, scales[0], names[0], scales[1], names[1],
           quick ? 16384 : REFERENCE_N);
    for (int table = 0; table < 2; table++) {
        printf("%s\n\n| map | material |", table == 0
                   ? "Relative RMSE (RMSE / RMS of the reference, linear RGB):"
                   : "SSIM against the reference (display-referred, docs/metrics.md):");
        for (int i = 0; i < n_count; i++) printf(" N %d |", accuracy_ns[i]);
        printf("\n|---|---|");
        for (int i = 0; i < n_count; i++) printf("---:|");
        printf("\n");
        for (int k = 0; k < 2; k++)
            for (int m = 0; m < MATERIAL_COUNT; m++) {
                printf("| %s | %s |", k == 0 ? "studio_small_03" : "tabac_plant", materials[m].label);
                for (int i = 0; i < n_count; i++)
                    printf(table == 0 ? " %.2e |" : " %.4f |", table == 0 ? rel[k][m][i] : ssim[k][m][i]);
                printf("\n");
            }
        printf("\n");
        fflush(stdout);
    }

    // 2. Cost against N (studio map; the tabac map's plan costs the same per direction).
    const int cost_ns[] = {16, 64, 256, 1024, 4096, 16384};
    const int cost_count = quick ? 4 : 6;
    mr_image *image = NULL;
    if (mr_image_create(COST_SIZE, COST_SIZE, 3, &image) != MR_OK) die("image");
    mr_scene point_scene = mr_scene_fit(&(mr_fit_scene_options){COST_SIZE, MR_FIT_LIGHT_45, 0});
    mr_render_plan *point_plan = NULL;
    double t0 = bench_now();
    if (mr_render_plan_create(&point_scene, &point_plan) != MR_OK) die("plan");
    double point_plan_ms = 1e3 * (bench_now() - t0);
    double point_ms[2][2];
    for (int t = 0; t < 2; t++) {
        omp_set_num_threads(t + 1);
        point_ms[t][0] = time_render(point_plan, &materials[0], image, 7, 0.3);
        point_ms[t][1] = time_render(point_plan, &materials[2], image, 7, 0.3);
    }
    printf("Cost, %d², studio map: plan = pattern + per-hit direction indices (built once per scene, 2 threads);\n"
           "render = median ms of one render with the plan prepared (what an optimiser pays per iteration), 1 and 2\n"
           "OpenMP threads; Mevals/s = BRDF evaluations per second, ggx, 1 thread.\n"
           "Point-light fit scene for scale: plan %.1f ms, %.2f MB; render lambert %.2f / %.2f ms, ggx %.2f / %.2f ms "
           "(1 / 2 threads).\n\n", COST_SIZE, point_plan_ms, (double)mr_render_plan_bytes(point_plan) / 1e6,
           point_ms[0][0], point_ms[1][0], point_ms[0][1], point_ms[1][1]);
    mr_render_plan_free(point_plan);
    printf("| N | plan ms | plan MB | env samples | per lit pixel | lambert 1 thr | lambert 2 thr | ggx 1 thr "
           "| ggx 2 thr | ggx Mevals/s |\n|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n");
    for (int i = 0; i < cost_count; i++) {
        double plan_ms[3];
        mr_render_plan *plan = NULL;
        int plan_reps = cost_ns[i] >= 4096 ? 1 : 3;
        omp_set_num_threads(2);
        for (int r = 0; r < plan_reps; r++) {
            mr_render_plan_free(plan);
            plan = make_plan(COST_SIZE, maps[0], scales[0], cost_ns[i], &plan_ms[r]);
        }
        double p_ms = bench_median(plan_ms, plan_reps);
        int reps = cost_ns[i] >= 4096 ? 3 : 7;
        double min_seconds = cost_ns[i] >= 4096 ? 0.0 : 0.3;
        double ms[2][2];
        for (int t = 0; t < 2; t++) {
            omp_set_num_threads(t + 1);
            ms[t][0] = time_render(plan, &materials[0], image, reps, min_seconds);
            ms[t][1] = time_render(plan, &materials[2], image, reps, min_seconds);
        }
        long env = mr_render_plan_env_sample_count(plan);
        printf("| %d | %.1f | %.1f | %ld | %.0f | %.2f | %.2f | %.2f | %.2f | %.1f |\n", cost_ns[i], p_ms,
               (double)mr_render_plan_bytes(plan) / 1e6, env, (double)env / mr_render_plan_lit_pixel_count(plan),
               ms[0][0], ms[1][0], ms[0][1], ms[1][1], (double)env / (ms[0][1] * 1e-3) / 1e6);
        fflush(stdout);
        mr_render_plan_free(plan);
    }
    mr_image_free(image);
    mr_image_free(maps[0]);
    mr_image_free(maps[1]);
    return 0;
}
