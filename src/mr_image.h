/*
 * mr_image.h — the in-memory image every module exchanges.
 *
 * Layout (the whole contract): `pixels` holds width*height*channels floats, channels interleaved, the top-left
 * pixel first, rows top to bottom, no row padding. Channel order is R,G,B (channels = 3), R,G,B,A (4), or a
 * single value (1). Values are linear: colour data is sRGB-decoded at the I/O boundary (src/io) and nowhere
 * else. An mr_image owns its pixel buffer; mr_image_free() releases both.
 */
#ifndef MR_IMAGE_H
#define MR_IMAGE_H

#include <stddef.h>

#include "mr_status.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct mr_image {
    int width;
    int height;
    int channels; /* 1, 3 or 4 */
    float *pixels;
} mr_image;

/* Allocate a zero-filled image. width, height >= 1, channels in {1, 3, 4}, width*height*channels must fit
 * in memory (MR_ERR_NOMEM otherwise). On success *out is owned by the caller (mr_image_free). */
mr_status mr_image_create(int width, int height, int channels, mr_image **out);

/* A deep copy of `src` in *out (caller owns it). */
mr_status mr_image_clone(const mr_image *src, mr_image **out);

/* Release the image and its pixels. NULL is allowed. */
void mr_image_free(mr_image *image);

/* Radiance a measurement can hold (an image to fit or to compare: remap's source renders, the images `matremap ssim`
 * compares): every value of the colour channels, the first min(3, channels) (alpha is not radiance), finite and
 * >= 0 (-0 included). MR_OK, or MR_ERR_INVALID_ARG naming the first other value in row order: "<label>: pixel
 * (x, y), channel c holds nan: expected finite radiance >= 0" (label NULL = "image"; a reader's label,
 * "image 'x.exr'", names the file). */
mr_status mr_image_check_radiance(const mr_image *image, const char *label);

/* Every value of the image (alpha included) times `factor`, in place, each rounded to float once: (float)(v *
 * factor) (an exposure, an irradiance scale). NULL is allowed (nothing done). */
void mr_image_scale(mr_image *image, double factor);

/* Number of floats in the pixel buffer. */
static inline size_t mr_image_value_count(const mr_image *image) {
    return (size_t)image->width * (size_t)image->height * (size_t)image->channels;
}

/* Pointer to pixel (x, y)'s first channel; no bounds check. */
static inline float *mr_image_at(const mr_image *image, int x, int y) {
    return image->pixels + ((size_t)y * (size_t)image->width + (size_t)x) * (size_t)image->channels;
}

#ifdef __cplusplus
}
#endif

#endif /* MR_IMAGE_H */
