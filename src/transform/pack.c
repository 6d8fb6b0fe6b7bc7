/*
 * pack.c — output images packed channel by channel from converted maps (contract in transform.h, "output
 * images").
 */
#include "mr_internal.h"
#include "transform.h"

mr_status mr_image_pack(int width, int height, int channels, const mr_image_channel *sources, float fill,
                        mr_image **out) {
    for (int c = 0; c < channels; c++) {
        const mr_image *im = sources[c].image;
        if (im != NULL && (im->width != width || im->height != height || sources[c].channel < 0 ||
                           sources[c].channel >= im->channels))
            return mr_fail(MR_ERR_INVALID_ARG, "mr_image_pack: channel %d: a %dx%d image of %d channels has no "
                           "channel %d of a %dx%d one", c, im->width, im->height, im->channels, sources[c].channel,
                           width, height);
    }
    mr_image *packed = NULL;
    mr_status status = mr_image_create(width, height, channels, &packed);
    if (status != MR_OK) return status;
    const size_t n = (size_t)width * (size_t)height;
    float *dst = packed->pixels;
    for (int c = 0; c < channels; c++) {
        const mr_image *im = sources[c].image;
        const size_t stride = im ? (size_t)im->channels : 0, offset = (size_t)sources[c].channel;
        for (size_t i = 0; i < n; i++)
            dst[i * (size_t)channels + (size_t)c] = im ? im->pixels[i * stride + offset] : fill;
    }
    *out = packed;
    return MR_OK;
}

mr_status mr_image_with_alpha(mr_image *rgb, const mr_image *alpha_source, mr_image **out) {
    if (alpha_source == NULL || alpha_source->channels != 4 || rgb->channels != 3) {
        *out = rgb; // the contract: the same image, not a copy
        return MR_OK;
    }
    const mr_image_channel sources[4] = {{rgb, 0}, {rgb, 1}, {rgb, 2}, {alpha_source, 3}};
    return mr_image_pack(rgb->width, rgb->height, 4, sources, 0.0f, out);
}
