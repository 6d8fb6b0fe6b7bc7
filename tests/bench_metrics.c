/*
 * bench_metrics.c — milliseconds per SSIM and RMSE of two fit-scene renders (make bench). Prints a Markdown
 * table; asserts nothing. The images are real renders (ggx against beckmann at the same alpha), the kind of
 * pair a remap or a report compares.
 */
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>

#include "bench_util.h"
#include "matremap.h"

static mr_image *render(int size, const char *model_name) {
    const mr_brdf_model *model = mr_brdf_find(model_name);
    double values[MR_BRDF_MAX_VALUES];
    mr_brdf_default_values(model, values);
    mr_scene scene = mr_scene_fit(&(mr_fit_scene_options){size, MR_FIT_LIGHT_45, 0});
    mr_render_plan *plan = NULL;
    mr_image *image = NULL;
    if (mr_render_plan_create(&scene, &plan) != MR_OK ||
        mr_render(plan, model, values, MR_COMPONENT_FULL, &image) != MR_OK) {
        fprintf(stderr, "bench_metrics: %s\n", mr_last_error());
        exit(3);
    }
    mr_render_plan_free(plan);
    return image;
}

/* Median ms of `reps` calls: which = 0 SSIM, 1 SSIM with map, 2 RMSE. */
static double time_metric(const mr_image *a, const mr_image *b, int which, int reps) {
    double samples[64];
    for (int r = 0; r < reps; r++) {
        double value = 0.0, t0 = bench_now();
        mr_image *map = NULL;
        if (which == 2)
            mr_rmse(a, b, &value);
        else
            mr_ssim(a, b, NULL, &value, which == 1 ? &map : NULL);
        samples[r] = 1e3 * (bench_now() - t0);
        mr_image_free(map);
    }
    return bench_median(samples, reps);
}

int main(void) {
    const int sizes[] = {256, 512, 1024};
    printf("SSIM (11x11 Gaussian, display-referred luma) and RMSE (linear RGB) of two fit-scene renders;\n"
           "median ms of 15 calls.\n\n");
    printf("| size | SSIM 1 thr | SSIM 2 thr | SSIM + map 2 thr | RMSE 1 thr | Mpixel/s SSIM 2 thr |\n");
    printf("|---:|---:|---:|---:|---:|---:|\n");
    for (int s = 0; s < 3; s++) {
        mr_image *a = render(sizes[s], "ggx"), *b = render(sizes[s], "beckmann");
        omp_set_num_threads(1);
        double ssim1 = time_metric(a, b, 0, 15), rmse1 = time_metric(a, b, 2, 15);
        omp_set_num_threads(2);
        double ssim2 = time_metric(a, b, 0, 15), map2 = time_metric(a, b, 1, 15);
        printf("| %d² | %.2f | %.2f | %.2f | %.2f | %.0f |\n", sizes[s], ssim1, ssim2, map2, rmse1,
               (double)sizes[s] * sizes[s] / (ssim2 * 1e-3) / 1e6);
        mr_image_free(a);
        mr_image_free(b);
    }
    return 0;
}
