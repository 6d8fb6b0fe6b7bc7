/*
 * object_metrics — how a viewer's render of a converted asset compares with its reference render, on the
 * object's pixels only (make evaluation-viewers; docs/evaluation.md, "What viewers show").
 *
 *   object_metrics REF.exr TEST.exr [--exposure E]
 *
 * Both images are linear RGBA renders of the same view with a transparent background (alpha = the object's
 * coverage). Prints one JSON line:
 *   ssim_object      SSIM (matremap's convention, docs/metrics.md: display-referred luma at exposure E) averaged
 *                    over the SSIM map's pixels whose window centre lies within 5 pixels (the window's half
 *                    width) of a pixel either image covers (alpha > 0): the object and the windows that touch it;
 *   ssim_frame       the same map averaged over the whole frame (what `matremap ssim` prints);
 *   luminance_ratio  mean linear luminance (Rec. 709) of TEST over mean of REF, on the pixels both cover fully
 *                    (alpha >= 0.999);
 *   ref_luminance    REF's mean luminance there; exposure: E, by default 0.18 / ref_luminance (REF's object at
 *                    mid-grey, as make evaluation-gltf exposes its SSIM);
 *   mask_iou         covered pixels of both over covered pixels of either (1 = the same silhouette).
 * Exit codes: 0 ok, 1 usage, 2 bad input (unreadable image, no alpha, different sizes, nothing covered).
 * The SSIM map comes from mr_ssim itself, so the figures are matremap's SSIM restricted to the object, not a
 * second implementation of it.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "src/io/image_io.h"
#include "src/metrics/metrics.h"

#define WINDOW_HALF 5 /* the SSIM window is 11x11 */

static double luminance(const float *p) {
    return 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
}

static int fail(const char *what, const char *path) {
    fprintf(stderr, "object_metrics: %s: %s\n", path, what);
    return 2;
}

int main(int argc, char **argv) {
    double exposure = 0.0;
    if (argc == 5 && strcmp(argv[3], "--exposure") == 0) {
        char *end = NULL;
        exposure = strtod(argv[4], &end);
        if (*end != '\0' || !(exposure > 0.0) || !isfinite(exposure)) {
            fprintf(stderr, "object_metrics: --exposure '%s': expected a positive number\n", argv[4]);
            return 1;
        }
    } else if (argc != 3) {
        fprintf(stderr, "usage: object_metrics REF.exr TEST.exr [--exposure E]\n");
        return 1;
    }
    mr_image *img[2] = {NULL, NULL};
    unsigned char *covered = NULL, *near = NULL;
    mr_image *map = NULL;
    int code = 2;
    for (int k = 0; k < 2; k++) {
        if (mr_img_read(argv[1 + k], NULL, &img[k]) != MR_OK) {
            code = fail(mr_last_error(), argv[1 + k]);
            goto done;
        }
        if (img[k]->channels != 4) {
            code = fail("needs an alpha channel (the object's coverage)", argv[1 + k]);
            goto done;
        }
    }
    const int w = img[0]->width, h = img[0]->height;
    if (img[1]->width != w || img[1]->height != h) {
        code = fail("not the size of the reference", argv[2]);
        goto done;
    }
    covered = calloc((size_t)w * h, 1);
    near = calloc((size_t)w * h, 1);
    if (!covered || !near) {
        code = fail("out of memory", argv[2]);
        goto done;
    }
    double sum_ref = 0.0, sum_test = 0.0;
    long full = 0, either = 0, both = 0;
    for (int y = 0; y < h; y++) {
        for (int x = 0; x < w; x++) {
            const float *a = mr_image_at(img[0], x, y), *b = mr_image_at(img[1], x, y);
            if (a[3] > 0.0f || b[3] > 0.0f) {
                covered[(size_t)y * w + x] = 1;
                either++;
            }
            if (a[3] > 0.0f && b[3] > 0.0f) both++;
            if (a[3] >= 0.999f && b[3] >= 0.999f) {
                sum_ref += luminance(a);
                sum_test += luminance(b);
                full++;
            }
        }
    }
    if (full == 0 || !(sum_ref > 0.0)) {
        code = fail("no pixel both images cover fully, or a black reference", argv[1]);
        goto done;
    }
    const double ref_lum = sum_ref / (double)full;
    if (exposure == 0.0) exposure = 0.18 / ref_lum;
    // Dilate the coverage by the window's half width (a square, as the window is).
    for (int y = 0; y < h; y++) {
        for (int x = 0; x < w; x++) {
            if (!covered[(size_t)y * w + x]) continue;
            for (int yy = y - WINDOW_HALF; yy <= y + WINDOW_HALF; yy++) {
                if (yy < 0 || yy >= h) continue;
                for (int xx = x - WINDOW_HALF; xx <= x + WINDOW_HALF; xx++) {
                    if (xx >= 0 && xx < w) near[(size_t)yy * w + xx] = 1;
                }
            }
        }
    }
    mr_ssim_options opts = {.exposure = exposure, .downsample = 0};
    double ssim_frame = 0.0;
    if (mr_ssim(img[0], img[1], &opts, &ssim_frame, &map) != MR_OK) {
        code = fail(mr_last_error(), argv[2]);
        goto done;
    }
    double sum = 0.0;
    long n = 0;
    for (int y = 0; y < map->height; y++) {
        for (int x = 0; x < map->width; x++) {
            if (near[(size_t)(y + WINDOW_HALF) * w + x + WINDOW_HALF]) {
                sum += *mr_image_at(map, x, y);
                n++;
            }
        }
    }
    printf("{\"ssim_object\": %.6f, \"ssim_frame\": %.6f, \"luminance_ratio\": %.6f, \"ref_luminance\": %.9g, "
           "\"exposure\": %.9g, \"object_pixels\": %ld, \"ssim_pixels\": %ld, \"mask_iou\": %.6f}\n",
           n ? sum / (double)n : 1.0, ssim_frame, sum_test / sum_ref, ref_lum, exposure, full, n,
           (double)both / (double)either);
    code = 0;
done:
    mr_image_free(img[0]);
    mr_image_free(img[1]);
    mr_image_free(map);
    free(covered);
    free(near);
    return code;
}
