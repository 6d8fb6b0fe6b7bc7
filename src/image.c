/* image.c — mr_image allocation (contract in mr_image.h). */
#include "mr_image.h"

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

void mr_image_free(mr_image *image) {
    if (image == NULL) return;
    free(image->pixels);
    free(image);
}
