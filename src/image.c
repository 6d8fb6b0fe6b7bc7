/* image.c — mr_image allocation (contract in mr_image.h). */
#include "mr_image.h"

#include <float.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "mr_internal.h"

mr_status mr_image_create(int width, int height, int channels, mr_image **out) {
    if (width < 1 || height < 1)
        return mr_fail(MR_ERR_INVALID_ARG, "image: size %dx%d: both sides must be >= 1", width, height);
    if (channels != 1 && channels != 3 && channels != 4)
        return mr_fail(MR_ERR_INVALID_ARG, "image: %d channels: expected 1, 3 or 4", channels);
    size_t count = (size_t)width * (size_t)height;
    if (count > SIZE_MAX / sizeof(float) / (size_t)channels)
        return mr_fail(MR_ERR_NOMEM, "image: %dx%dx%d floats do not fit in memory", width, height, channels);
    mr_image *image = malloc(sizeof *image);
    float *pixels = calloc(count * (size_t)channels, sizeof(float));
    if (image == NULL || pixels == NULL) {
        free(image);
        free(pixels);
        return mr_fail(MR_ERR_NOMEM, "image: out of memory for %dx%dx%d floats", width, height, channels);
    }
    image->width = width;
    image->height = height;
    image->channels = channels;
    image->pixels = pixels;
    *out = image;
    return MR_OK;
}

mr_status mr_image_clone(const mr_image *src, mr_image **out) {
    mr_image *copy = NULL;
    mr_status status = mr_image_create(src->width, src->height, src->channels, &copy);
    if (status != MR_OK) return status;
    memcpy(copy->pixels, src->pixels, mr_image_value_count(src) * sizeof(float));
    *out = copy;
    return MR_OK;
}

mr_status mr_image_check_values(const mr_image *image, const char *label, int allow_negative) {
    if (label == NULL) label = "image";
    if (image == NULL || image->pixels == NULL) return mr_fail(MR_ERR_INVALID_ARG, "%s: NULL image", label);
    const int channels = image->channels, used = MR_MIN(3, channels);
    const size_t n = (size_t)image->width * (size_t)image->height;
    for (size_t i = 0; i < n; i++)
        for (int c = 0; c < used; c++) {
            const float v = image->pixels[i * (size_t)channels + (size_t)c];
            // NaN fails both comparisons; -0 passes (it is >= 0).
            if (allow_negative ? (v >= -FLT_MAX && v <= FLT_MAX) : (v >= 0.0f && v <= FLT_MAX)) continue;
            return mr_fail(MR_ERR_INVALID_ARG, "%s: pixel (%d, %d), channel %d holds %g: expected %s", label,
                           (int)(i % (size_t)image->width), (int)(i / (size_t)image->width), c, (double)v,
                           allow_negative ? "finite values" : "finite radiance >= 0");
        }
    return MR_OK;
}

mr_status mr_image_check_radiance(const mr_image *image, const char *label) {
    return mr_image_check_values(image, label, 0);
}

void mr_image_free(mr_image *image) {
    if (image == NULL) return;
    free(image->pixels);
    free(image);
}

void mr_image_scale(mr_image *image, double factor) {
    if (image == NULL) return;
    const size_t n = mr_image_value_count(image);
    for (size_t p = 0; p < n; p++) image->pixels[p] = (float)(image->pixels[p] * factor);
}
