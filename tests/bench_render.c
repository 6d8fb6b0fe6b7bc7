/*
 * bench_render.c — milliseconds per fit-scene render, per model, size and thread count (make bench).
 *
 * Prints a Markdown table on stdout; asserts nothing. Each figure is the median of repeated renders with a
 * prepared plan (geometry traced once, as the optimiser uses it); the plan's own cost is listed per size, so the
 * saving of "geometry once per scene" can be read off. A second table compares, per model on one thread, the
 * per-sample render loop with the batched one (portable and AVX2/FMA kernels). Usage: bench_render [--quick]
 */
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench_util.h"
#include "matremap.h"
#include "render/render_internal.h"

/* Median wall time of one render in ms: at least `min_reps` renders and at least `min_seconds` in all. */
/* Median ms of a render on `threads` threads (given, not the automatic rule's choice) along `path`
 * (render_internal.h: AUTO as every public call; or forced per-sample, batched portable, batched AVX2/FMA). */
static double time_render_path(const mr_render_plan *plan, int threads, const mr_brdf_model *model,
                               const double *values, mr_image *image, int min_reps, double min_seconds,
                               mr_render_path path, double (*clock)(void)) {
    double samples[256];
    int count = 0;
    double start = bench_now();
    mr_render_into_path(plan, threads, model, values, MR_COMPONENT_FULL, image, path); // warm caches and threads
    while (count < 256 && (count < min_reps || bench_now() - start < min_seconds)) {
        double t0 = clock();
        mr_render_into_path(plan, threads, model, values, MR_COMPONENT_FULL, image, path);
        samples[count++] = 1e3 * (clock() - t0);
    }
    return bench_median(samples, count);
}

/* CPU seconds of the calling thread: a one-thread render runs on it alone, and unlike wall time this does not count
 * the time other processes of a shared machine take the core away. */
static double thread_cpu_now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static double time_render(const mr_render_plan *plan, int threads, const mr_brdf_model *model,
                          const double *values, mr_image *image, int min_reps, double min_seconds) {
    return time_render_path(plan, threads, model, values, image, min_reps, min_seconds, MR_RENDER_PATH_AUTO, bench_now);
}

/* The batched lobes (docs/performance.md, "Vectorised lobes"): per model, ms per render on one thread at 64^2 (the
 * fit scene) and 512^2, along the per-sample loop (one eval call per sample, as before batches), the batched loop
 * with the portable kernels (what MATREMAP_SIMD=scalar or a CPU without AVX2 gets) and with the AVX2/FMA ones. CPU
 * time of the one thread, so that a busy machine's other processes do not enter the comparison. */
static int env_batch_table(int min_reps, double min_seconds);

static int batch_table(int min_reps, double min_seconds) {
    const int sizes[] = {64, 512};
    mr_render_plan *plans[2] = {NULL, NULL};
    for (int s = 0; s < 2; s++) {
        mr_scene scene = mr_scene_fit(&(mr_fit_scene_options){sizes[s], MR_FIT_LIGHT_45, 0});
        if (mr_render_plan_create(&scene, &plans[s]) != MR_OK) {
            fprintf(stderr, "bench_render: %s\n", mr_last_error());
            return 3;
        }
    }
    printf("\nBatched lobes, one thread, median CPU ms per render: the per-sample loop, the batched loop with the\n"
           "portable kernels (MATREMAP_SIMD=scalar) and with the AVX2/FMA ones%s; speed-up = per-sample / AVX2.\n\n",
           mr_brdf_batch_cpu_vector() ? "" : " (this CPU has no AVX2/FMA: portable again)");
    printf("| model | 64² per-sample | 64² portable | 64² AVX2 | speed-up 64² | 512² per-sample | 512² portable "
           "| 512² AVX2 | speed-up 512² |\n");
    printf("|---|---:|---:|---:|---:|---:|---:|---:|---:|\n");
    const mr_render_path paths[3] = {MR_RENDER_PATH_PER_SAMPLE, MR_RENDER_PATH_BATCH_PORTABLE,
                                     MR_RENDER_PATH_BATCH_VECTOR};
    const mr_brdf_model *const *models = mr_brdf_models();
    for (int m = 0; models[m] != NULL; m++) {
        double values[MR_BRDF_MAX_VALUES];
        mr_brdf_default_values(models[m], values);
        double ms[2][3];
        for (int s = 0; s < 2; s++) {
            mr_image *image = NULL;
            if (mr_image_create(sizes[s], sizes[s], 3, &image) != MR_OK) return 3;
            for (int p = 0; p < 3; p++)
                ms[s][p] = time_render_path(plans[s], 1, models[m], values, image, min_reps, min_seconds, paths[p],
                                            thread_cpu_now);
            mr_image_free(image);
        }
        printf("| %s | %.3f | %.3f | %.3f | %.2f | %.2f | %.2f | %.2f | %.2f |\n", models[m]->name, ms[0][0],
               ms[0][1], ms[0][2], ms[0][0] / ms[0][2], ms[1][0], ms[1][1], ms[1][2], ms[1][0] / ms[1][2]);
        fflush(stdout);
    }
    mr_render_plan_free(plans[0]);
    mr_render_plan_free(plans[1]);
    return env_batch_table(min_reps, min_seconds);
}

/* The same comparison under environment light (batches gathered from the hits, render.c render_gathered): the fit
 * scene's sphere at 128^2 lit by a synthetic 64x32 map with the default sampling, a few models. */
static int env_batch_table(int min_reps, double min_seconds) {
    mr_image *map = NULL;
    if (mr_image_create(64, 32, 3, &map) != MR_OK) return 3;
    for (size_t i = 0; i < (size_t)64 * 32 * 3; i++) map->pixels[i] = (float)(0.2 + (double)(i % 7) * 0.1);
    mr_scene scene = mr_scene_fit(&(mr_fit_scene_options){128, MR_FIT_LIGHT_45, 0});
    scene.lights[0] = mr_light_environment(map, 1.0, 0.0, 0);
    mr_render_plan *plan = NULL;
    if (mr_render_plan_create(&scene, &plan) != MR_OK) {
        fprintf(stderr, "bench_render: %s\n", mr_last_error());
        mr_image_free(map);
        return 3;
    }
    mr_image *image = NULL;
    if (mr_image_create(128, 128, 3, &image) != MR_OK) return 3;
    printf("\nThe same under environment light (128², a 64x32 map, default sampling: %ld samples), median CPU ms per\n"
           "render, one thread.\n\n| model | per-sample | portable | AVX2 | speed-up |\n|---|---:|---:|---:|---:|\n",
           mr_render_plan_sample_count(plan));
    const char *names[] = {"ward", "ggx", "gltf", "cycles-principled"};
    const mr_render_path paths[3] = {MR_RENDER_PATH_PER_SAMPLE, MR_RENDER_PATH_BATCH_PORTABLE,
                                     MR_RENDER_PATH_BATCH_VECTOR};
    for (size_t m = 0; m < sizeof names / sizeof names[0]; m++) {
        const mr_brdf_model *model = mr_brdf_find(names[m]);
        double values[MR_BRDF_MAX_VALUES], ms[3];
        mr_brdf_default_values(model, values);
        for (int p = 0; p < 3; p++)
            ms[p] = time_render_path(plan, 1, model, values, image, min_reps, min_seconds, paths[p], thread_cpu_now);
        printf("| %s | %.2f | %.2f | %.2f | %.2f |\n", names[m], ms[0], ms[1], ms[2], ms[0] / ms[2]);
        fflush(stdout);
    }
    mr_image_free(image);
    mr_render_plan_free(plan);
    mr_image_free(map);
    return 0;
}

int main(int argc, char **argv) {
    int quick = argc > 1 && strcmp(argv[1], "--quick") == 0;
    const int sizes[] = {256, 512};
    const int threads[] = {1, 2};
    int min_reps = quick ? 3 : 7;
    double min_seconds = quick ? 0.05 : 0.3;

    mr_render_plan *plans[2] = {NULL, NULL};
    double plan_ms[2];
    for (int s = 0; s < 2; s++) {
        mr_scene scene = mr_scene_fit(&(mr_fit_scene_options){sizes[s], MR_FIT_LIGHT_45, 0});
        double t0 = bench_now();
        if (mr_render_plan_create(&scene, &plans[s]) != MR_OK) {
            fprintf(stderr, "bench_render: %s\n", mr_last_error());
            return 3;
        }
        plan_ms[s] = 1e3 * (bench_now() - t0);
    }
    // What box-filtering the silhouette costs: the same scene with pixel-centre sampling only.
    mr_scene centres_scene = mr_scene_fit(&(mr_fit_scene_options){512, MR_FIT_LIGHT_45, 0});
    centres_scene.edge_samples = 1;
    mr_render_plan *centres = NULL;
    if (mr_render_plan_create(&centres_scene, &centres) != MR_OK) return 3;
    long filtered_samples = mr_render_plan_sample_count(plans[1]);
    long centre_samples = mr_render_plan_sample_count(centres);
    mr_render_plan_free(centres);
    printf("Fit scene, 45-degree light, default parameters of each model; median ms per render with the\n"
           "geometry plan prepared once (plan: %.1f ms at 256^2, %ld shading samples; %.1f ms at 512^2, %ld\n"
           "samples, of which %ld (%.1f %%) are the 4x4 sub-pixel samples of box-filtered silhouette pixels).\n"
           "OpenMP threads 1 and 2; speed-up = 1 thread / 2 threads; Meval/s = BRDF evaluations per second.\n\n",
           plan_ms[0], mr_render_plan_sample_count(plans[0]), plan_ms[1], filtered_samples,
           filtered_samples - centre_samples, 100.0 * (double)(filtered_samples - centre_samples) / centre_samples);
    printf("| model | 256² 1 thr | 256² 2 thr | 512² 1 thr | 512² 2 thr | speed-up 512² "
           "| Mevals/s 512² 2 thr |\n");
    printf("|---|---:|---:|---:|---:|---:|---:|\n");
    const mr_brdf_model *const *models = mr_brdf_models();
    for (int m = 0; models[m] != NULL; m++) {
        double values[MR_BRDF_MAX_VALUES];
        mr_brdf_default_values(models[m], values);
        double ms[2][2];
        for (int s = 0; s < 2; s++) {
            mr_image *image = NULL;
            if (mr_image_create(sizes[s], sizes[s], 3, &image) != MR_OK) return 3;
            for (int t = 0; t < 2; t++) {
                ms[s][t] = time_render(plans[s], threads[t], models[m], values, image, min_reps, min_seconds);
            }
            mr_image_free(image);
        }
        double mevals = (double)mr_render_plan_sample_count(plans[1]) / (ms[1][1] * 1e-3) / 1e6;
        printf("| %s | %.2f | %.2f | %.2f | %.2f | %.2f | %.1f |\n", models[m]->name, ms[0][0], ms[0][1], ms[1][0],
               ms[1][1], ms[1][0] / ms[1][1], mevals);
        fflush(stdout);
    }
    mr_render_plan_free(plans[0]);
    mr_render_plan_free(plans[1]);
    return batch_table(min_reps, min_seconds);
}
