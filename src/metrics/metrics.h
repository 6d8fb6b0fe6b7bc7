/*
 * metrics.h — image differences: RMSE on linear images (what the optimiser minimises) and SSIM on
 * display-referred images (what reports show).
 *
 * SSIM convention (fixed, documented once here and in docs/metrics.md):
 *   1. display mapping: each linear channel is multiplied by `exposure` (default 1), clamped to [0,1] (a
 *      negative value counts as 0, a product beyond a float's range as 1) and sRGB-encoded (no other tone
 *      curve: the fit scene is lit so that diffuse albedos stay below 1);
 *   2. luma: Y' = 0.299 R' + 0.587 G' + 0.114 B' (ITU-R BT.601 on the encoded values, as MATLAB's rgb2gray,
 *      kept in double, not rounded to 8-bit levels); single-channel images are used as they are (mapped as
 *      in step 1); alpha is ignored;
 *   3. SSIM of Wang et al. 2004 on Y' with dynamic range L = 1: Gaussian window 11x11, sigma 1.5, normalised;
 *      K1 = 0.01, K2 = 0.03; population (co)variances; 'valid' filtering, so the map is (w-10)x(h-10);
 *      MSSIM = mean of the map. No automatic downsampling unless opts.downsample asks for MATLAB's rule.
 * Sums are accumulated in double, in a fixed order, so results do not depend on the thread count.
 * Cross-checked against ssim.js 3.5.0 ('original' mode) to a few 1e-9 (tests/ssim_crosscheck.sh).
 *
 * Values: every function here refuses a NaN or an infinity in the compared channels of either image
 * (MR_ERR_INVALID_ARG naming "image a" or "image b", the pixel and the channel): they have no difference and no
 * display value, so a figure computed over them would hide bad data. Negative values are compared as they are
 * (RMSE) or clamped (SSIM's display mapping). Images that are measurements (renders to fit or to judge) should
 * also hold no negative radiance: mr_image_check_radiance (mr_image.h) checks that, naming the file; `matremap
 * ssim` and `matremap remap` call it on every image they read.
 *
 * Object masks (what a viewer looks at: a rendered object, not the background around it). A mask is a
 * 1-channel image of the images' size holding, per pixel, the fraction the object covers, in [0, 1] (a render
 * plan's coverage, mr_render_plan_coverage_mask in render.h); a pixel with a value > 0 belongs to the object.
 *   - SSIM over a mask (mr_ssim_options.mask) is the mean of the same SSIM map over the map pixels whose 11x11
 *     window holds at least one object pixel: the mask dilated by the window's radius, 5 pixels, in the
 *     Chebyshev (square) sense. Map pixel (x, y) is centred on image pixel (x + 5, y + 5) and its window spans
 *     image columns x .. x + 10 and rows y .. y + 10, so it counts when any of those is an object pixel. Why
 *     that set: the window is every pixel a map value depends on, so these are exactly the values the object
 *     influences, including the windows that straddle its silhouette (where its outline stands against the
 *     background); every other window sees background only, identical in renders of one scene (SSIM exactly
 *     1), which would only dilute the figure in proportion to the frame's emptiness. Each counted value has
 *     weight 1 (not the coverage).
 *   - RMSE over a mask (mr_rmse_masked) is over the object pixels (value > 0), each counted once, and the
 *     reference's mean over the same pixels and channels is its natural denominator (relative RMSE).
 * A mask of all ones gives the whole-frame figures bit for bit.
 */
#ifndef MR_METRICS_H
#define MR_METRICS_H

#include "../mr_image.h"
#include "../mr_status.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct mr_ssim_options {
    double exposure;      /* linear scale before clamping; 0 = 1.0; otherwise positive and finite */
    int downsample;       /* 0 = none; 1 = Wang's MATLAB rule f = max(1, round(min(w,h)/256)), box filter +
                             decimate; not with a mask */
    const mr_image *mask; /* NULL = the whole frame (every map pixel); otherwise the object's coverage (see the
                             header comment): 1 channel, the images' size, values in [0, 1]; the mean is taken
                             over the map pixels whose window holds an object pixel (> 0). Borrowed. */
    int threads;          /* OpenMP threads: 0 (default) = automatic, a team of omp_get_max_threads() only for
                             images of at least 65536 pixels, one thread below; n in 1 .. MR_METRICS_MAX_THREADS:
                             n threads. The figures do not depend on it */
} mr_ssim_options;

#define MR_METRICS_MAX_THREADS 1024

/* Root-mean-square difference over all pixels and the first min(3, channels) channels of two linear images
 * (alpha is not compared; no clamping). Sizes and channel counts must match (MR_ERR_INVALID_ARG, naming both
 * sizes). A NaN or infinite value is MR_ERR_INVALID_ARG naming the image and the first such pixel (header
 * comment, "Values"). *out_rmse is untouched on failure. */
mr_status mr_rmse(const mr_image *a, const mr_image *b, double *out_rmse);

/* Like mr_rmse, over the pixels where mask > 0 only (mask NULL: every pixel, exactly mr_rmse), each counted
 * once, on `threads` threads (as mr_ssim_options.threads: 0 = automatic, mr_rmse's choice), and, if out_mean_a
 * is not NULL, the mean of a's values over the same pixels and channels: with the reference as a, rmse / mean
 * is the RMSE relative to the reference's mean radiance on the object. The mask is as for SSIM (header
 * comment). Errors as mr_rmse, and MR_ERR_INVALID_ARG for a mask of the wrong size or channels, a value outside
 * [0, 1] (naming the pixel), a mask that covers no pixel, or threads outside 0 .. MR_METRICS_MAX_THREADS. The
 * outputs are untouched on failure. */
mr_status mr_rmse_masked(const mr_image *a, const mr_image *b, const mr_image *mask, int threads,
                         double *out_rmse, double *out_mean_a);

/* Mean SSIM of a and b (same size and channels; at least 11x11 after downsampling). opts may be NULL.
 * With opts->mask, the mean over the map pixels whose window touches the object (header comment).
 * If map_out is not NULL, *map_out receives the 1-channel SSIM map ((w-10)x(h-10) of the possibly downsampled
 * images, values in [-1,1]; the whole map, with or without a mask), owned by the caller. Errors:
 * MR_ERR_INVALID_ARG (sizes, options; a NaN or infinite value, header comment "Values"; a mask of the wrong size
 * or channels, with a value outside [0, 1], with downsampling, or whose dilation reaches no map pixel),
 * MR_ERR_NOMEM; the outputs are untouched on failure.
 * A 512x512 RGB pair takes a few milliseconds. */
mr_status mr_ssim(const mr_image *a, const mr_image *b, const mr_ssim_options *opts, double *out_ssim,
                  mr_image **map_out);

/* A false-colour RGB picture of an SSIM map for people to look at: 1 (identical) is black, lower values
 * rise through a colour ramp to white at `floor` and below (floor 0 = 0.5; otherwise in [-1, 1)); NaN shows
 * as white. The ramp is MATLAB's "hot" (black -> red -> yellow -> white) over t = (1 - ssim) / (1 - floor),
 * defined in display (sRGB) values snapped to 8-bit codes; the returned image holds their linear
 * equivalents, so writing it with mr_img_write as MR_IMG_COLOR reproduces the ramp exactly. The map must have
 * 1 channel (MR_ERR_INVALID_ARG). *out_rgb is owned by the caller. */
mr_status mr_ssim_map_visualise(const mr_image *map, double floor, mr_image **out_rgb);

#ifdef __cplusplus
}
#endif

#endif /* MR_METRICS_H */
