/*
 * bench_render.c — milliseconds per fit-scene render, per model, size and thread count (make bench).
 *
 * Prints a Markdown table on stdout; asserts nothing. Each figure is the median of repeated renders with a
 * prepared plan (geometry traced once, as the optimiser uses it); the plan's own cost is listed per size, so the
 * saving of "geometry once per scene" can be read off. Usage: bench_render [--quick]
 */
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench_util.h"
#include "matremap.h"
#include "render/render_internal.h"

/* Median wall time of one render in ms: at least `min_reps` renders and at least `min_seconds` in all. */
/* Median ms of a render on `threads` threads (given, not the automatic rule's choice). */
static double time_render(const mr_render_plan *plan, int threads, const mr_brdf_model *model,
                          const double *values, mr_image *image, int min_reps, double min_seconds) {
    double samples[256];
    int count = 0;
    double start = bench_now();
    mr_render_into_threads(plan, threads, model, values, MR_COMPONENT_FULL, image); // warm caches and threads
    while (count < 256 && (count < min_reps || bench_now() - start < min_seconds)) {
        double t0 = bench_now();
        mr_render_into_threads(plan, threads, model, values, MR_COMPONENT_FULL, image);
        samples[count++] = 1e3 * (bench_now() - t0);
    }
    return bench_median(samples, count);
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
    return 0;
}
