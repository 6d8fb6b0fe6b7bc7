/*
 * test_metrics.c — RMSE and SSIM (contracts in src/metrics/metrics.h; convention in docs/metrics.md).
 *
 * The reference for SSIM here is a deliberately naive implementation written from the definition (Wang et
 * al. 2004, eq. 13, with ssim.m's parameters): its own sRGB formula (IEC 61966-2-1) and BT.601 luma, the
 * full 2-D 11x11 Gaussian (not the separable form the library uses), one window at a time, all in double.
 * The library must match it to 1e-12. tests/ssim_crosscheck.sh adds an independent implementation (ssim.js).
 */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "../src/io/image_io.h"
#include "../src/metrics/metrics.h"
#include "harness.h"

/* ---- fixtures ------------------------------------------------------------------------------------------ */

static uint64_t rng_state = 0x9E3779B97F4A7C15ull;

static double rng_uniform(void) { /* xorshift64*: deterministic, platform-independent */
    rng_state ^= rng_state >> 12;
    rng_state ^= rng_state << 25;
    rng_state ^= rng_state >> 27;
    return (double)((rng_state * 0x2545F4914F6CDD1Dull) >> 11) * (1.0 / 9007199254740992.0);
}

/* A lit-sphere-like image: a shaded disc with a highlight on a dark background, values partly above 1 (so
 * the display clamp matters), times `channels` tints, plus uniform noise of amplitude `noise`. */
static mr_image *make_scene(int w, int h, int channels, double noise, uint64_t seed) {
    mr_image *img = NULL;
    if (mr_image_create(w, h, channels, &img) != MR_OK) return NULL;
    rng_state = seed;
    const double tint[4] = {1.0, 0.8, 0.55, 1.0};
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            double u = (x + 0.5) / w * 2.0 - 1.0, v = (y + 0.5) / h * 2.0 - 1.0;
            double r2 = u * u + v * v;
            double base = 0.02 + 0.05 * (u + 1.0);
            if (r2 < 0.8) {
                double nz = sqrt(1.0 - r2 / 0.8);
                double diffuse = 0.7 * fmax(0.0, 0.3 * u - 0.5 * v + 0.8 * nz);
                double hx = u + 0.3, hy = v + 0.35;
                base = diffuse + 1.6 * exp(-(hx * hx + hy * hy) / 0.01);
            }
            float *p = mr_image_at(img, x, y);
            for (int c = 0; c < channels; c++) {
                double value = c == 3 ? 1.0 : base * tint[c] + noise * (rng_uniform() - 0.5);
                p[c] = (float)value;
            }
        }
    return img;
}

static mr_image *with_noise(const mr_image *src, double amplitude, uint64_t seed) {
    mr_image *out = NULL;
    if (mr_image_clone(src, &out) != MR_OK) return NULL;
    rng_state = seed;
    for (size_t i = 0; i < mr_image_value_count(out); i++) out->pixels[i] += (float)(amplitude * (rng_uniform() - 0.5));
    return out;
}

/* ---- the naive reference ------------------------------------------------------------------------------- */

static double ref_srgb_encode(double linear) { /* IEC 61966-2-1 */
    double x = linear >= 0.0 ? (linear <= 1.0 ? linear : 1.0) : 0.0; /* clamp; NaN -> 0 */
    return x <= 0.0031308 ? 12.92 * x : 1.055 * pow(x, 1.0 / 2.4) - 0.055;
}

/* Display luma (metrics.h steps 1-2), w*h doubles. */
static double *ref_luma(const mr_image *img, double exposure) {
    double *y = malloc((size_t)img->width * (size_t)img->height * sizeof(double));
    for (int j = 0; j < img->height; j++)
        for (int i = 0; i < img->width; i++) {
            const float *p = mr_image_at(img, i, j);
            double v;
            if (img->channels == 1)
                v = ref_srgb_encode(p[0] * exposure);
            else
                v = 0.299 * ref_srgb_encode(p[0] * exposure) + 0.587 * ref_srgb_encode(p[1] * exposure) +
                    0.114 * ref_srgb_encode(p[2] * exposure);
            y[(size_t)j * (size_t)img->width + (size_t)i] = v;
        }
    return y;
}

/* MSSIM of two w x h planes, brute force: every 11x11 window with the 2-D Gaussian. map optional. */
static double ref_ssim_planes(const double *x, const double *y, int w, int h, double *map) {
    double win[11][11], total = 0.0;
    for (int a = 0; a < 11; a++)
        for (int b = 0; b < 11; b++) {
            win[a][b] = exp(-((a - 5) * (a - 5) + (b - 5) * (b - 5)) / (2.0 * 1.5 * 1.5));
            total += win[a][b];
        }
    for (int a = 0; a < 11; a++)
        for (int b = 0; b < 11; b++) win[a][b] /= total;
    const double c1 = 0.01 * 0.01, c2 = 0.03 * 0.03;
    double sum = 0.0;
    for (int j = 0; j + 11 <= h; j++)
        for (int i = 0; i + 11 <= w; i++) {
            double mx = 0, my = 0, xx = 0, yy = 0, xy = 0;
            for (int a = 0; a < 11; a++)
                for (int b = 0; b < 11; b++) {
                    double wv = win[a][b];
                    double px = x[(size_t)(j + a) * (size_t)w + (size_t)(i + b)];
                    double py = y[(size_t)(j + a) * (size_t)w + (size_t)(i + b)];
                    mx += wv * px;
                    my += wv * py;
                    xx += wv * px * px;
                    yy += wv * py * py;
                    xy += wv * px * py;
                }
            double vx = xx - mx * mx, vy = yy - my * my, cxy = xy - mx * my;
            double s = (2 * mx * my + c1) * (2 * cxy + c2) / ((mx * mx + my * my + c1) * (vx + vy + c2));
            if (map) map[(size_t)j * (size_t)(w - 10) + (size_t)i] = s;
            sum += s;
        }
    return sum / ((double)(w - 10) * (double)(h - 10));
}

/* MATLAB's imfilter(ones(f)/f^2, 'symmetric', 'same') + img(1:f:end, 1:f:end), written from the MATLAB
 * documentation: the kernel's origin is element floor((f+1)/2), 'symmetric' mirrors including the edge. */
static double *ref_downsample(const double *src, int w, int h, int f, int *dw, int *dh) {
    *dw = (w + f - 1) / f;
    *dh = (h + f - 1) / f;
    double *out = malloc((size_t)*dw * (size_t)*dh * sizeof(double));
    int origin = (f + 1) / 2; /* 1-based */
    for (int j = 0; j < *dh; j++)
        for (int i = 0; i < *dw; i++) {
            double s = 0.0;
            for (int a = 1; a <= f; a++)
                for (int b = 1; b <= f; b++) {
                    int r = j * f + (a - origin), c = i * f + (b - origin);
                    if (r < 0) r = -r - 1;
                    if (r >= h) r = 2 * h - r - 1;
                    if (c < 0) c = -c - 1;
                    if (c >= w) c = 2 * w - c - 1;
                    s += src[(size_t)r * (size_t)w + (size_t)c] / (f * f);
                }
            out[(size_t)j * (size_t)*dw + (size_t)i] = s;
        }
    return out;
}

static double ref_ssim(const mr_image *a, const mr_image *b, double exposure, int downsample, double *map) {
    double *x = ref_luma(a, exposure), *y = ref_luma(b, exposure);
    int w = a->width, h = a->height;
    if (downsample) {
        int m = w < h ? w : h;
        int f = (int)floor(m / 256.0 + 0.5);
        if (f > 1) {
            int dw, dh;
            double *xs = ref_downsample(x, w, h, f, &dw, &dh), *ys = ref_downsample(y, w, h, f, &dw, &dh);
            free(x);
            free(y);
            x = xs;
            y = ys;
            w = dw;
            h = dh;
        }
    }
    double s = ref_ssim_planes(x, y, w, h, map);
    free(x);
    free(y);
    return s;
}

/* ---- SSIM properties ----------------------------------------------------------------------------------- */

MR_TEST(ssim_of_an_image_with_itself_is_exactly_one) {
    mr_image *a = make_scene(64, 48, 3, 0.1, 1);
    double s = 0.0;
    mr_image *map = NULL;
    MR_CHECK_OK(mr_ssim(a, a, NULL, &s, &map));
    MR_CHECK(s == 1.0);
    int not_one = 0;
    if (map)
        for (size_t i = 0; i < mr_image_value_count(map); i++) not_one += map->pixels[i] != 1.0f;
    MR_CHECK(not_one == 0);
    mr_image_free(map);
    mr_image_free(a);
}

MR_TEST(ssim_is_symmetric) {
    mr_image *a = make_scene(70, 50, 3, 0.05, 2), *b = make_scene(70, 50, 3, 0.2, 3);
    double ab = 0.0, ba = 0.0;
    MR_CHECK_OK(mr_ssim(a, b, NULL, &ab, NULL));
    MR_CHECK_OK(mr_ssim(b, a, NULL, &ba, NULL));
    MR_CHECK_MSG(ab == ba, "%.17g vs %.17g", ab, ba);
    MR_CHECK(ab < 1.0 && ab > 0.0);
    mr_image_free(a);
    mr_image_free(b);
}

MR_TEST(ssim_decreases_with_noise) {
    mr_image *a = make_scene(96, 96, 3, 0.0, 4);
    const double levels[5] = {0.005, 0.02, 0.05, 0.1, 0.3};
    double prev = 1.0;
    for (int k = 0; k < 5; k++) {
        mr_image *b = with_noise(a, levels[k], 100 + (uint64_t)k);
        double s = 0.0;
        MR_CHECK_OK(mr_ssim(a, b, NULL, &s, NULL));
        MR_CHECK_MSG(s < prev, "noise %.3f: SSIM %.6f, previous %.6f", levels[k], s, prev);
        prev = s;
        mr_image_free(b);
    }
    MR_CHECK(prev < 0.5);
    mr_image_free(a);
}

MR_TEST(constant_images_known_answer) {
    /* For constant images every variance and the covariance vanish, so SSIM = (2 mx my + C1)/(mx^2 + my^2 + C1)
     * with mx, my the display values (here 1-channel: the sRGB encodings of the linear values). */
    const double pairs[4][2] = {{0.2, 0.5}, {0.0, 1.0}, {0.001, 0.002}, {0.7, 0.7}};
    for (int k = 0; k < 4; k++) {
        mr_image *a = NULL, *b = NULL;
        MR_CHECK_OK(mr_image_create(20, 15, 1, &a));
        MR_CHECK_OK(mr_image_create(20, 15, 1, &b));
        for (int i = 0; i < 20 * 15; i++) {
            a->pixels[i] = (float)pairs[k][0];
            b->pixels[i] = (float)pairs[k][1];
        }
        double mx = ref_srgb_encode((float)pairs[k][0]), my = ref_srgb_encode((float)pairs[k][1]);
        double c1 = 1e-4;
        double expected = (2 * mx * my + c1) / (mx * mx + my * my + c1);
        double s = 0.0;
        MR_CHECK_OK(mr_ssim(a, b, NULL, &s, NULL));
        MR_CHECK_NEAR(s, expected, 1e-12);
        mr_image_free(a);
        mr_image_free(b);
    }
}

MR_TEST(ssim_matches_brute_force_reference) {
    /* tiny fixtures, RGB and grey, with and without exposure (which also exercises the clamp) */
    struct {
        int w, h, channels;
        double exposure;
    } cases[4] = {{16, 13, 3, 1.0}, {11, 11, 3, 1.0}, {23, 17, 1, 2.5}, {19, 12, 4, 0.3}};
    for (int k = 0; k < 4; k++) {
        mr_image *a = make_scene(cases[k].w, cases[k].h, cases[k].channels, 0.3, 10 + (uint64_t)k);
        mr_image *b = with_noise(a, 0.4, 20 + (uint64_t)k);
        mr_ssim_options o = {cases[k].exposure, 0, NULL, 0};
        double s = 0.0;
        mr_image *map = NULL;
        MR_CHECK_OK(mr_ssim(a, b, &o, &s, &map));
        double *ref_map = malloc((size_t)(cases[k].w - 10) * (size_t)(cases[k].h - 10) * sizeof(double));
        double expected = ref_ssim(a, b, cases[k].exposure, 0, ref_map);
        MR_CHECK_NEAR(s, expected, 1e-12);
        MR_CHECK(s < 0.99);
        if (map) {
            double worst = 0.0;
            for (size_t i = 0; i < mr_image_value_count(map); i++)
                worst = fmax(worst, fabs(map->pixels[i] - ref_map[i]));
            MR_CHECK_NEAR(worst, 0.0, 1e-7); /* the map is stored as float */
        }
        free(ref_map);
        mr_image_free(map);
        mr_image_free(a);
        mr_image_free(b);
    }
    /* a golden value, so a change in either implementation is noticed */
    mr_image *a = make_scene(16, 13, 3, 0.3, 10), *b = with_noise(a, 0.4, 20);
    double s = 0.0;
    MR_CHECK_OK(mr_ssim(a, b, NULL, &s, NULL));
    MR_CHECK_NEAR(s, 0.81946624810015933, 1e-12); /* recorded when both implementations first agreed */
    mr_image_free(a);
    mr_image_free(b);
}

MR_TEST(map_has_valid_size_and_mean) {
    mr_image *a = make_scene(41, 30, 3, 0.1, 5), *b = with_noise(a, 0.2, 6);
    double s = 0.0;
    mr_image *map = NULL;
    MR_CHECK_OK(mr_ssim(a, b, NULL, &s, &map));
    MR_CHECK(map != NULL && map->width == 31 && map->height == 20 && map->channels == 1);
    if (map) {
        double sum = 0.0, lo = 1.0, hi = -1.0;
        for (size_t i = 0; i < mr_image_value_count(map); i++) {
            sum += map->pixels[i];
            lo = fmin(lo, map->pixels[i]);
            hi = fmax(hi, map->pixels[i]);
        }
        MR_CHECK_NEAR(sum / (31.0 * 20.0), s, 1e-6);
        MR_CHECK(lo >= -1.0 && hi <= 1.0 && lo < hi);
    }
    mr_image_free(map);
    mr_image_free(a);
    mr_image_free(b);
}

MR_TEST(exposure_and_alpha) {
    /* exposure 2 equals doubling the pixels first (exact in float, so the results are bit-identical) */
    mr_image *a = make_scene(40, 32, 4, 0.1, 7), *b = with_noise(a, 0.1, 8);
    mr_image *a2 = NULL, *b2 = NULL;
    MR_CHECK_OK(mr_image_clone(a, &a2));
    MR_CHECK_OK(mr_image_clone(b, &b2));
    for (size_t i = 0; i < mr_image_value_count(a); i++) {
        a2->pixels[i] *= 2.0f;
        b2->pixels[i] *= 2.0f;
    }
    double s_exp = 0.0, s_pre = 0.0, s_default = 0.0, s_one = 0.0;
    mr_ssim_options two = {2.0, 0, NULL, 0}, one = {1.0, 0, NULL, 0}, zero = {0.0, 0, NULL, 0};
    MR_CHECK_OK(mr_ssim(a, b, &two, &s_exp, NULL));
    MR_CHECK_OK(mr_ssim(a2, b2, NULL, &s_pre, NULL));
    MR_CHECK(s_exp == s_pre);
    MR_CHECK_OK(mr_ssim(a, b, &zero, &s_default, NULL));
    MR_CHECK_OK(mr_ssim(a, b, &one, &s_one, NULL));
    MR_CHECK(s_default == s_one && s_one != s_exp);
    /* alpha is ignored: change it wildly, nothing moves */
    for (int i = 0; i < 40 * 32; i++) b->pixels[i * 4 + 3] = (float)(i % 7) / 7.0f;
    double s_alpha = 0.0;
    MR_CHECK_OK(mr_ssim(a, b, &one, &s_alpha, NULL));
    MR_CHECK(s_alpha == s_one);
    /* invalid options */
    mr_ssim_options bad = {-1.0, 0, NULL, 0};
    double untouched = 42.0;
    MR_CHECK(mr_ssim(a, b, &bad, &untouched, NULL) == MR_ERR_INVALID_ARG);
    bad.exposure = NAN;
    MR_CHECK(mr_ssim(a, b, &bad, &untouched, NULL) == MR_ERR_INVALID_ARG);
    bad.exposure = 1.0;
    bad.downsample = 2;
    MR_CHECK(mr_ssim(a, b, &bad, &untouched, NULL) == MR_ERR_INVALID_ARG);
    bad.downsample = 0;
    bad.threads = -1;
    MR_CHECK(mr_ssim(a, b, &bad, &untouched, NULL) == MR_ERR_INVALID_ARG);
    bad.threads = MR_METRICS_MAX_THREADS + 1;
    MR_CHECK(mr_ssim(a, b, &bad, &untouched, NULL) == MR_ERR_INVALID_ARG);
    MR_CHECK(mr_rmse_masked(a, b, NULL, -1, &untouched, NULL) == MR_ERR_INVALID_ARG);
    MR_CHECK(mr_rmse_masked(a, b, NULL, MR_METRICS_MAX_THREADS + 1, &untouched, NULL) == MR_ERR_INVALID_ARG);
    MR_CHECK(untouched == 42.0);
    mr_image_free(a);
    mr_image_free(b);
    mr_image_free(a2);
    mr_image_free(b2);
}

MR_TEST(non_finite_pixels) {
    /* NaN and infinities have no difference and no display value: refused by both metrics, naming the image, the
     * pixel and the channel, the outputs untouched. Negative values (and -0) are compared: SSIM clamps them. */
    mr_image *a = make_scene(20, 20, 3, 0.1, 9), *b = with_noise(a, 0.1, 10);
    mr_image_at(a, 3, 3)[0] = -0.0f; /* negative zero must map like +0 */
    mr_image_at(a, 4, 3)[0] = -1e-30f;
    double s = 0.0, r = -1.0;
    MR_CHECK_OK(mr_ssim(a, b, NULL, &s, NULL));
    MR_CHECK_NEAR(s, ref_ssim(a, b, 1.0, 0, NULL), 1e-12);
    MR_CHECK_OK(mr_rmse(a, b, &r));
    const float poison[3] = {NAN, INFINITY, -INFINITY};
    for (int k = 0; k < 3; k++) {
        mr_image *bad = NULL;
        MR_CHECK_OK(mr_image_clone(b, &bad));
        mr_image_at(bad, 7, 5)[1] = poison[k];
        mr_image *map = (mr_image *)&s;
        s = 42.0;
        r = 42.0;
        MR_CHECK(mr_ssim(a, bad, NULL, &s, &map) == MR_ERR_INVALID_ARG);
        MR_CHECK_MSG(strstr(mr_last_error(), "ssim: image b: pixel (7, 5), channel 1 holds") != NULL, "%s",
                     mr_last_error());
        MR_CHECK(s == 42.0 && map == (mr_image *)&s);
        MR_CHECK(mr_rmse(bad, a, &r) == MR_ERR_INVALID_ARG);
        MR_CHECK_MSG(strstr(mr_last_error(), "rmse: image a: pixel (7, 5), channel 1") != NULL, "%s", mr_last_error());
        MR_CHECK(mr_rmse_masked(a, bad, NULL, 0, &r, NULL) == MR_ERR_INVALID_ARG && r == 42.0);
        mr_image_free(bad);
    }
    /* Alpha is not compared, so a NaN there is no error. */
    mr_image *a4 = make_scene(20, 20, 4, 0.0, 9), *b4 = make_scene(20, 20, 4, 0.0, 9);
    mr_image_at(b4, 2, 2)[3] = NAN;
    MR_CHECK_OK(mr_ssim(a4, b4, NULL, &s, NULL));
    MR_CHECK(s == 1.0);
    MR_CHECK_OK(mr_rmse(a4, b4, &r));
    MR_CHECK(r == 0.0);
    mr_image_free(a4);
    mr_image_free(b4);
    mr_image_free(a);
    mr_image_free(b);
}

MR_TEST(measurements_must_be_finite_radiance) {
    /* mr_image_check_radiance: finite and >= 0 in the colour channels, naming the first other value in row order
     * with the caller's label. */
    mr_image *rgb = make_scene(16, 12, 3, 0.0, 3), *grey = make_scene(16, 12, 1, 0.0, 3);
    mr_image *rgba = make_scene(16, 12, 4, 0.0, 3);
    MR_CHECK_OK(mr_image_check_radiance(rgb, "image 'x.exr'"));
    MR_CHECK_OK(mr_image_check_radiance(grey, NULL));
    mr_image_at(rgb, 0, 0)[2] = -0.0f; /* -0 is 0 */
    mr_image_at(rgba, 1, 1)[3] = NAN;  /* alpha is not radiance */
    mr_image_at(rgba, 2, 1)[3] = -1.0f;
    MR_CHECK_OK(mr_image_check_radiance(rgb, "image 'x.exr'"));
    MR_CHECK_OK(mr_image_check_radiance(rgba, "image 'x.exr'"));
    const struct {
        int x, y, c;
        float v;
        const char *text;
    } cases[4] = {{9, 4, 1, NAN, "holds nan"},
                  {15, 11, 2, INFINITY, "holds inf"},
                  {0, 3, 0, -INFINITY, "holds -inf"},
                  {3, 0, 2, -1e-6f, "holds -1e-06"}};
    for (int k = 0; k < 4; k++) {
        mr_image *bad = NULL;
        MR_CHECK_OK(mr_image_clone(rgb, &bad));
        mr_image_at(bad, cases[k].x, cases[k].y)[cases[k].c] = cases[k].v;
        mr_image_at(bad, 15, 11)[0] = -2.0f; /* later in row order: not the one named (except case 1, before it) */
        char expected[128];
        snprintf(expected, sizeof expected, "image 'x.exr': pixel (%d, %d), channel %d %s: expected finite radiance",
                 cases[k].x, cases[k].y, k == 1 ? 0 : cases[k].c, k == 1 ? "holds -2" : cases[k].text);
        MR_CHECK(mr_image_check_radiance(bad, "image 'x.exr'") == MR_ERR_INVALID_ARG);
        MR_CHECK_MSG(strstr(mr_last_error(), expected) != NULL, "%s (expected %s)", mr_last_error(), expected);
        mr_image_free(bad);
    }
    mr_image_at(grey, 5, 6)[0] = NAN;
    MR_CHECK(mr_image_check_radiance(grey, NULL) == MR_ERR_INVALID_ARG);
    MR_CHECK_MSG(strstr(mr_last_error(), "image: pixel (5, 6), channel 0 holds nan") != NULL, "%s", mr_last_error());
    MR_CHECK(mr_image_check_radiance(NULL, "x") == MR_ERR_INVALID_ARG);
    mr_image_free(rgb);
    mr_image_free(grey);
    mr_image_free(rgba);
}

MR_TEST(size_errors) {
    mr_image *a = make_scene(20, 20, 3, 0.1, 11), *b = make_scene(20, 21, 3, 0.1, 11);
    mr_image *g = make_scene(20, 20, 1, 0.1, 11), *small = make_scene(10, 40, 3, 0.1, 11);
    double s = 42.0, r = 42.0;
    static mr_image sentinel_image; /* *map_out must stay untouched on failure */
    mr_image *const sentinel = &sentinel_image;
    mr_image *map = sentinel;
    MR_CHECK(mr_ssim(a, b, NULL, &s, &map) == MR_ERR_INVALID_ARG);
    MR_CHECK(strstr(mr_last_error(), "20x20x3") != NULL && strstr(mr_last_error(), "20x21x3") != NULL);
    MR_CHECK(mr_ssim(a, g, NULL, &s, &map) == MR_ERR_INVALID_ARG);
    MR_CHECK(mr_rmse(a, b, &r) == MR_ERR_INVALID_ARG);
    MR_CHECK(mr_rmse(a, g, &r) == MR_ERR_INVALID_ARG);
    MR_CHECK(mr_ssim(small, small, NULL, &s, &map) == MR_ERR_INVALID_ARG);
    MR_CHECK(strstr(mr_last_error(), "10x40") != NULL && strstr(mr_last_error(), "11x11") != NULL);
    MR_CHECK(mr_ssim(NULL, a, NULL, &s, NULL) == MR_ERR_INVALID_ARG);
    MR_CHECK(mr_ssim(a, a, NULL, NULL, NULL) == MR_ERR_INVALID_ARG);
    MR_CHECK(s == 42.0 && r == 42.0 && map == sentinel);
    /* the smallest valid size: one window, a 1x1 map */
    mr_image *eleven = make_scene(11, 11, 3, 0.2, 12);
    map = NULL;
    MR_CHECK_OK(mr_ssim(eleven, eleven, NULL, &s, &map));
    MR_CHECK(s == 1.0 && map != NULL && map->width == 1 && map->height == 1);
    mr_image_free(map);
    mr_image_free(eleven);
    mr_image_free(a);
    mr_image_free(b);
    mr_image_free(g);
    mr_image_free(small);
}

MR_TEST(deterministic_across_thread_counts) {
#ifdef _OPENMP
    mr_image *a = make_scene(517, 389, 3, 0.05, 13), *b = with_noise(a, 0.1, 14);
    int saved = omp_get_max_threads();
    double s[3], r[3], s_given[3], r_given[3];
    mr_image *maps[3] = {NULL, NULL, NULL};
    const int counts[3] = {1, 2, 3};
    for (int k = 0; k < 3; k++) {
        omp_set_num_threads(counts[k]); // the automatic team's size
        MR_CHECK_OK(mr_ssim(a, b, NULL, &s[k], &maps[k]));
        MR_CHECK_OK(mr_rmse(a, b, &r[k]));
    }
    omp_set_num_threads(saved);
    for (int k = 0; k < 3; k++) { // the caller's count (mr_ssim_options.threads)
        mr_ssim_options given = {1.0, 0, NULL, counts[k]};
        MR_CHECK_OK(mr_ssim(a, b, &given, &s_given[k], NULL));
        MR_CHECK_OK(mr_rmse_masked(a, b, NULL, counts[k], &r_given[k], NULL));
        MR_CHECK(s_given[k] == s[0] && r_given[k] == r[0]);
    }
    for (int k = 1; k < 3; k++) {
        MR_CHECK_MSG(s[k] == s[0], "%d threads: %.17g vs %.17g", counts[k], s[k], s[0]);
        MR_CHECK(r[k] == r[0]);
        MR_CHECK(maps[k] && maps[0] &&
                 memcmp(maps[k]->pixels, maps[0]->pixels, mr_image_value_count(maps[0]) * sizeof(float)) == 0);
    }
    for (int k = 0; k < 3; k++) mr_image_free(maps[k]);
    mr_image_free(a);
    mr_image_free(b);
#else
    MR_CHECK_MSG(0, "built without OpenMP");
#endif
}

MR_TEST(matlab_downsampling) {
    /* f = max(1, round(min(w,h)/256)): 520 -> 2 (even f: forward-looking blocks), 780 -> 3 (centred,
     * mirrored at the border), 383 -> 1 (no downsampling), 384 -> 2 (MATLAB rounds halves away from 0). */
    const int sizes[4][2] = {{600, 520}, {781, 800}, {400, 383}, {384, 390}};
    for (int k = 0; k < 4; k++) {
        mr_image *a = make_scene(sizes[k][0], sizes[k][1], 3, 0.2, 30 + (uint64_t)k);
        mr_image *b = with_noise(a, 0.3, 40 + (uint64_t)k);
        mr_ssim_options o = {1.0, 1, NULL, 0}, plain = {1.0, 0, NULL, 0};
        double s = 0.0, s_plain = 0.0;
        mr_image *map = NULL;
        MR_CHECK_OK(mr_ssim(a, b, &o, &s, &map));
        MR_CHECK_OK(mr_ssim(a, b, &plain, &s_plain, NULL));
        MR_CHECK_NEAR(s, ref_ssim(a, b, 1.0, 1, NULL), 1e-12);
        int m = sizes[k][0] < sizes[k][1] ? sizes[k][0] : sizes[k][1];
        int f = m >= 384 ? (m >= 640 ? 3 : 2) : 1;
        int dw = (sizes[k][0] + f - 1) / f, dh = (sizes[k][1] + f - 1) / f;
        MR_CHECK_MSG(map && map->width == dw - 10 && map->height == dh - 10, "case %d: map %dx%d, f %d", k,
                     map ? map->width : 0, map ? map->height : 0, f);
        if (f == 1)
            MR_CHECK(s == s_plain);
        else
            MR_CHECK(s > s_plain); /* averaging removes noise: the downsampled pair is more similar */
        mr_image_free(map);
        mr_image_free(a);
        mr_image_free(b);
    }
    /* a long thin image: f follows the shorter side (20 -> f = 1; 520 -> f = 2 for a 5000-pixel width) */
    const int thin_sizes[2][2] = {{1000, 20}, {5000, 520}};
    for (int k = 0; k < 2; k++) {
        mr_image *thin = make_scene(thin_sizes[k][0], thin_sizes[k][1], 1, 0.1, 50);
        mr_ssim_options o = {1.0, 1, NULL, 0};
        double s = 0.0;
        mr_image *map = NULL;
        MR_CHECK_OK(mr_ssim(thin, thin, &o, &s, &map));
        MR_CHECK(s == 1.0 && map && map->height == (k == 0 ? 10 : 250));
        mr_image_free(map);
        mr_image_free(thin);
    }
}

/* ---- RMSE ---------------------------------------------------------------------------------------------- */

MR_TEST(rmse_known_answers) {
    mr_image *a = NULL, *b = NULL;
    MR_CHECK_OK(mr_image_create(2, 1, 1, &a));
    MR_CHECK_OK(mr_image_create(2, 1, 1, &b));
    b->pixels[0] = 3.0f;
    b->pixels[1] = 4.0f;
    double r = 0.0;
    MR_CHECK_OK(mr_rmse(a, b, &r));
    MR_CHECK_NEAR(r, sqrt(12.5), 1e-15);
    MR_CHECK_OK(mr_rmse(b, a, &r));
    MR_CHECK_NEAR(r, sqrt(12.5), 1e-15);
    mr_image_free(a);
    mr_image_free(b);
    /* RGBA: alpha is not part of the error; linear values, no clamping (values above 1 count) */
    MR_CHECK_OK(mr_image_create(3, 2, 4, &a));
    MR_CHECK_OK(mr_image_create(3, 2, 4, &b));
    for (int i = 0; i < 6; i++) {
        float *p = b->pixels + i * 4;
        p[0] = 0.5f, p[1] = 1.5f, p[2] = -0.5f, p[3] = 0.9f;
    }
    MR_CHECK_OK(mr_rmse(a, b, &r));
    MR_CHECK_NEAR(r, sqrt((0.25 + 2.25 + 0.25) / 3.0), 1e-15);
    MR_CHECK_OK(mr_rmse(a, a, &r));
    MR_CHECK(r == 0.0);
    MR_CHECK(mr_rmse(a, b, NULL) == MR_ERR_INVALID_ARG);
    mr_image_free(a);
    mr_image_free(b);
}

/* ---- SSIM and RMSE over an object mask ------------------------------------------------------------------ */

/* A disc of radius r (pixels) centred at (cx, cy) as a coverage mask: 1 inside, 0 outside, the fraction of a
 * 4x4 sub-pixel grid on the edge (a render plan's convention). */
static mr_image *disc_mask(int w, int h, double cx, double cy, double r) {
    mr_image *m = NULL;
    if (mr_image_create(w, h, 1, &m) != MR_OK) return NULL;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            int inside = 0;
            for (int j = 0; j < 4; j++)
                for (int i = 0; i < 4; i++) {
                    double u = x + (i + 0.5) / 4 - cx, v = y + (j + 0.5) / 4 - cy;
                    inside += u * u + v * v < r * r;
                }
            m->pixels[(size_t)y * (size_t)w + (size_t)x] = (float)(inside / 16.0);
        }
    return m;
}

/* The masked mean of a reference map, from the definition in metrics.h: map pixel (x, y) counts when any
 * mask pixel of columns x..x+10, rows y..y+10 is > 0. *counted receives how many do. */
static double ref_masked_mean(const double *map, const mr_image *mask, long *counted) {
    const int w = mask->width, ow = w - 10, oh = mask->height - 10;
    double sum = 0.0;
    long n = 0;
    for (int y = 0; y < oh; y++)
        for (int x = 0; x < ow; x++) {
            int touches = 0;
            for (int j = 0; j < 11 && !touches; j++)
                for (int i = 0; i < 11 && !touches; i++)
                    touches = mask->pixels[(size_t)(y + j) * (size_t)w + (size_t)(x + i)] > 0.0f;
            if (!touches) continue;
            sum += map[(size_t)y * (size_t)ow + (size_t)x];
            n++;
        }
    *counted = n;
    return sum / (double)n;
}

MR_TEST(masked_ssim_matches_definition) {
    /* a disc inside the frame, one touching the border, and a single pixel */
    const double discs[3][3] = {{30.5, 26.0, 11.3}, {4.0, 44.0, 9.0}, {40.5, 10.5, 0.3}};
    mr_image *a = make_scene(64, 52, 3, 0.1, 60), *b = with_noise(a, 0.2, 61);
    double *map = malloc(54 * 42 * sizeof(double));
    ref_ssim(a, b, 1.0, 0, map);
    for (int k = 0; k < 3; k++) {
        mr_image *mask = disc_mask(64, 52, discs[k][0], discs[k][1], discs[k][2]);
        long counted = 0;
        double expected = ref_masked_mean(map, mask, &counted);
        mr_ssim_options o = {1.0, 0, mask, 0};
        double s = 0.0;
        MR_CHECK_OK(mr_ssim(a, b, &o, &s, NULL));
        MR_CHECK_NEAR(s, expected, 1e-12);
        MR_CHECK_MSG(counted > 0 && counted < 54 * 42, "disc %d: %ld map pixels counted", k, counted);
        if (k == 2) MR_CHECK_MSG(counted == 121, "a single pixel touches 11 x 11 windows, not %ld", counted);
        mr_image_free(mask);
    }
    free(map);
    mr_image_free(a);
    mr_image_free(b);
}

MR_TEST(mask_of_ones_is_the_whole_frame) {
    mr_image *a = make_scene(71, 53, 3, 0.1, 62), *b = with_noise(a, 0.3, 63), *ones = NULL;
    MR_CHECK_OK(mr_image_create(71, 53, 1, &ones));
    for (size_t i = 0; i < mr_image_value_count(ones); i++) ones->pixels[i] = 1.0f;
    mr_ssim_options whole = {1.5, 0, NULL, 0}, masked = {1.5, 0, ones, 0};
    double s_whole = 0.0, s_masked = 0.0, r_whole = 0.0, r_masked = 0.0, r_null = 0.0, mean = 0.0;
    MR_CHECK_OK(mr_ssim(a, b, &whole, &s_whole, NULL));
    MR_CHECK_OK(mr_ssim(a, b, &masked, &s_masked, NULL));
    MR_CHECK_MSG(s_whole == s_masked, "%.17g vs %.17g", s_whole, s_masked);
    MR_CHECK_OK(mr_rmse(a, b, &r_whole));
    MR_CHECK_OK(mr_rmse_masked(a, b, ones, 0, &r_masked, &mean));
    MR_CHECK_OK(mr_rmse_masked(a, b, NULL, 0, &r_null, NULL));
    MR_CHECK(r_whole == r_masked && r_whole == r_null);
    double sum = 0.0;
    for (size_t i = 0; i < mr_image_value_count(a); i++) sum += a->pixels[i];
    MR_CHECK_NEAR(mean, sum / (double)mr_image_value_count(a), 1e-12);
    mr_image_free(a);
    mr_image_free(b);
    mr_image_free(ones);
}

/* A copy of src with uniform noise of amplitude `amplitude` on the pixels that are the object's (mask > 0, far 0)
 * or that lie `far` or more pixels (Chebyshev distance) from every object pixel (far > 0). */
static mr_image *with_noise_where(const mr_image *src, const mr_image *mask, int far, double amplitude,
                                  uint64_t seed) {
    mr_image *out = NULL;
    if (mr_image_clone(src, &out) != MR_OK) return NULL;
    rng_state = seed;
    const int w = src->width, h = src->height;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            int near = 0;
            for (int j = y - (far - 1); far > 0 && j <= y + far - 1 && !near; j++)
                for (int i = x - (far - 1); i <= x + far - 1 && !near; i++)
                    near = i >= 0 && j >= 0 && i < w && j < h && mask->pixels[(size_t)j * (size_t)w + (size_t)i] > 0;
            if (far > 0 ? near : !(mask->pixels[(size_t)y * (size_t)w + (size_t)x] > 0.0f)) continue;
            for (int c = 0; c < src->channels; c++)
                mr_image_at(out, x, y)[c] += (float)(amplitude * (rng_uniform() - 0.5));
        }
    return out;
}

MR_TEST(background_difference_leaves_object_figures) {
    /* b differs from a only 11 or more pixels away from the object: no window that touches the object sees it */
    const int w = 80, h = 60;
    mr_image *a = make_scene(w, h, 3, 0.05, 64), *mask = disc_mask(w, h, 40.0, 30.0, 12.0);
    mr_image *b = with_noise_where(a, mask, 11, 0.6, 65);
    mr_ssim_options whole = {1.0, 0, NULL, 0}, object = {1.0, 0, mask, 0};
    double s_whole = 0.0, s_object = 0.0, r_whole = 0.0, r_object = -1.0;
    MR_CHECK_OK(mr_ssim(a, b, &whole, &s_whole, NULL));
    MR_CHECK_OK(mr_ssim(a, b, &object, &s_object, NULL));
    MR_CHECK_OK(mr_rmse(a, b, &r_whole));
    MR_CHECK_OK(mr_rmse_masked(a, b, mask, 0, &r_object, NULL));
    MR_CHECK_MSG(s_whole < 0.99 && s_object == 1.0, "whole frame %.6f, object %.17g", s_whole, s_object);
    MR_CHECK_MSG(r_whole > 0.01 && r_object == 0.0, "whole frame %g, object %g", r_whole, r_object);
    /* one pixel nearer (10 from the object) is inside a counted window: the object's SSIM sees it */
    mr_image *nearer = with_noise_where(a, mask, 10, 0.6, 65);
    MR_CHECK_OK(mr_ssim(a, nearer, &object, &s_object, NULL));
    MR_CHECK_MSG(s_object < 1.0, "object %.17g", s_object);
    mr_image_free(a);
    mr_image_free(b);
    mr_image_free(nearer);
    mr_image_free(mask);
}

MR_TEST(object_difference_weighs_more_on_the_object) {
    /* b differs from a only on the object. Every window that does not touch the object compares identical
     * pixels (SSIM exactly 1), so 1 - whole = (1 - object) x counted / all, exactly up to rounding. */
    const int w = 90, h = 70;
    mr_image *a = make_scene(w, h, 3, 0.05, 66), *mask = disc_mask(w, h, 45.0, 35.0, 10.0);
    mr_image *b = with_noise_where(a, mask, 0, 0.3, 67);
    double *map = malloc((size_t)(w - 10) * (size_t)(h - 10) * sizeof(double));
    ref_ssim(a, b, 1.0, 0, map);
    long counted = 0;
    ref_masked_mean(map, mask, &counted);
    free(map);
    mr_ssim_options whole = {1.0, 0, NULL, 0}, object = {1.0, 0, mask, 0};
    double s_whole = 0.0, s_object = 0.0;
    MR_CHECK_OK(mr_ssim(a, b, &whole, &s_whole, NULL));
    MR_CHECK_OK(mr_ssim(a, b, &object, &s_object, NULL));
    MR_CHECK_MSG(s_object < s_whole && s_whole < 1.0, "object %.6f, whole frame %.6f", s_object, s_whole);
    MR_CHECK_NEAR(1.0 - s_whole, (1.0 - s_object) * (double)counted / ((w - 10.0) * (h - 10.0)), 1e-12);
    /* RMSE: the same squared error over fewer pixels; relative to a's mean over the object */
    double r_whole = 0.0, r_object = 0.0, mean = 0.0, sum = 0.0, sum_a = 0.0;
    long pixels = 0;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            if (!(mask->pixels[(size_t)y * (size_t)w + (size_t)x] > 0.0f)) continue;
            pixels++;
            for (int c = 0; c < 3; c++) {
                double d = (double)mr_image_at(a, x, y)[c] - mr_image_at(b, x, y)[c];
                sum += d * d;
                sum_a += mr_image_at(a, x, y)[c];
            }
        }
    MR_CHECK_OK(mr_rmse(a, b, &r_whole));
    MR_CHECK_OK(mr_rmse_masked(a, b, mask, 0, &r_object, &mean));
    MR_CHECK_NEAR(r_object, sqrt(sum / (3.0 * pixels)), 1e-12);
    MR_CHECK_NEAR(mean, sum_a / (3.0 * pixels), 1e-12);
    MR_CHECK_NEAR(r_whole * r_whole * w * h, r_object * r_object * pixels, 1e-9);
#ifdef _OPENMP
    /* bit-identical for any thread count, like the whole-frame figures */
    int saved = omp_get_max_threads();
    for (int threads = 1; threads <= 3; threads += 2) {
        omp_set_num_threads(threads);
        double s = 0.0, r = 0.0;
        MR_CHECK_OK(mr_ssim(a, b, &object, &s, NULL));
        MR_CHECK_OK(mr_rmse_masked(a, b, mask, 0, &r, NULL));
        MR_CHECK_MSG(s == s_object && r == r_object, "%d threads", threads);
    }
    omp_set_num_threads(saved);
#endif
    mr_image_free(a);
    mr_image_free(b);
    mr_image_free(mask);
}

MR_TEST(mask_errors) {
    mr_image *a = make_scene(30, 20, 3, 0.1, 68), *b = with_noise(a, 0.1, 69);
    mr_image *small = NULL, *rgb = NULL, *mask = NULL, *empty = NULL;
    MR_CHECK_OK(mr_image_create(30, 19, 1, &small));
    MR_CHECK_OK(mr_image_create(30, 20, 3, &rgb));
    MR_CHECK_OK(mr_image_create(30, 20, 1, &empty));
    mask = disc_mask(30, 20, 15.0, 10.0, 5.0);
    double s = 42.0, r = 42.0, mean = 42.0;
    static mr_image sentinel_image;
    mr_image *const sentinel = &sentinel_image;
    mr_image *map = sentinel;
    mr_ssim_options o = {1.0, 0, small, 0};
    MR_CHECK(mr_ssim(a, b, &o, &s, &map) == MR_ERR_INVALID_ARG);
    MR_CHECK_MSG(strstr(mr_last_error(), "30x19x1") != NULL, "%s", mr_last_error());
    MR_CHECK(mr_rmse_masked(a, b, small, 0, &r, &mean) == MR_ERR_INVALID_ARG);
    o.mask = rgb;
    MR_CHECK(mr_ssim(a, b, &o, &s, &map) == MR_ERR_INVALID_ARG);
    MR_CHECK(mr_rmse_masked(a, b, rgb, 0, &r, &mean) == MR_ERR_INVALID_ARG);
    o.mask = empty; /* no object pixel: no figure to give */
    MR_CHECK(mr_ssim(a, b, &o, &s, &map) == MR_ERR_INVALID_ARG);
    MR_CHECK(mr_rmse_masked(a, b, empty, 0, &r, &mean) == MR_ERR_INVALID_ARG);
    MR_CHECK_MSG(strstr(mr_last_error(), "covers no pixel") != NULL, "%s", mr_last_error());
    mask->pixels[3 * 30 + 7] = 1.5f;
    o.mask = mask;
    MR_CHECK(mr_ssim(a, b, &o, &s, &map) == MR_ERR_INVALID_ARG);
    MR_CHECK_MSG(strstr(mr_last_error(), "(7, 3)") != NULL, "%s", mr_last_error());
    mask->pixels[3 * 30 + 7] = NAN;
    MR_CHECK(mr_rmse_masked(a, b, mask, 0, &r, &mean) == MR_ERR_INVALID_ARG);
    mask->pixels[3 * 30 + 7] = 0.0f;
    o.downsample = 1; /* a mask is at full resolution */
    MR_CHECK(mr_ssim(a, b, &o, &s, &map) == MR_ERR_INVALID_ARG);
    MR_CHECK(s == 42.0 && r == 42.0 && mean == 42.0 && map == sentinel);
    /* the map is the whole map with a mask too */
    o.downsample = 0;
    map = NULL;
    MR_CHECK_OK(mr_ssim(a, b, &o, &s, &map));
    MR_CHECK(map != NULL && map->width == 20 && map->height == 10);
    mr_image_free(map);
    /* an object pixel outside the valid map still counts through the windows that reach it */
    for (size_t i = 0; i < mr_image_value_count(empty); i++) empty->pixels[i] = 0.0f;
    empty->pixels[0] = 0.25f; /* pixel (0, 0): only map pixel (0, 0)'s window holds it */
    o.mask = empty;
    map = NULL;
    MR_CHECK_OK(mr_ssim(a, b, &o, &s, &map));
    MR_CHECK(map != NULL);
    if (map != NULL) MR_CHECK_NEAR(s, map->pixels[0], 1e-7); /* the map holds floats */
    mr_image_free(map);
    mr_image_free(a);
    mr_image_free(b);
    mr_image_free(small);
    mr_image_free(rgb);
    mr_image_free(mask);
    mr_image_free(empty);
}

/* ---- the SSIM map picture ------------------------------------------------------------------------------ */

MR_TEST(map_visualisation) {
    mr_image *map = NULL;
    MR_CHECK_OK(mr_image_create(6, 1, 1, &map));
    const float values[6] = {1.0f, 0.875f, 0.75f, 0.5f, -0.2f, NAN};
    memcpy(map->pixels, values, sizeof values);
    mr_image *rgb = NULL;
    MR_CHECK_OK(mr_ssim_map_visualise(map, 0.0, &rgb)); /* floor 0 means 0.5 */
    if (rgb) {
        MR_CHECK(rgb->width == 6 && rgb->height == 1 && rgb->channels == 3);
        const float *p = rgb->pixels;
        MR_CHECK(p[0] == 0.0f && p[1] == 0.0f && p[2] == 0.0f);                           /* identical: black */
        MR_CHECK(p[9] == 1.0f && p[10] == 1.0f && p[11] == 1.0f);                         /* at the floor: white */
        MR_CHECK(p[12] == 1.0f && p[13] == 1.0f && p[14] == 1.0f);                        /* below: white */
        MR_CHECK(p[15] == 1.0f && p[16] == 1.0f && p[17] == 1.0f);                        /* NaN: worst */
        MR_CHECK(p[3] > 0.0f && p[4] == 0.0f && p[5] == 0.0f);                            /* t = 1/4: red only */
        MR_CHECK(p[6] == 1.0f && p[7] > 0.0f && p[7] < 1.0f && p[8] == 0.0f);             /* t = 1/2: orange */
        /* the ramp is defined in display values snapped to 8-bit codes: an sRGB PNG reproduces them */
        char dir[] = "/tmp/mr_test_metrics.XXXXXX";
        if (mkdtemp(dir) != NULL) {
            char path[64];
            snprintf(path, sizeof path, "%s/map.png", dir);
            MR_CHECK_OK(mr_img_write(path, rgb, NULL));
            mr_img_read_options raw = {MR_IMG_DATA, 0, 0};
            mr_image *back = NULL;
            MR_CHECK_OK(mr_img_read(path, &raw, &back));
            if (back) {
                /* t = 1/4 -> red = (1/4)/(3/8) = 2/3 -> code round(170) */
                MR_CHECK_NEAR(back->pixels[3] * 255.0, 170.0, 1e-4);
                MR_CHECK_NEAR(back->pixels[7] * 255.0, floor((0.5 - 0.375) / 0.375 * 255.0 + 0.5), 1e-4);
                int mismatch = 0;
                for (int i = 0; i < 18; i++) {
                    double code = back->pixels[i] * 255.0;
                    double want = floor(mr_linear_to_srgb(rgb->pixels[i]) * 255.0 + 0.5);
                    double exact = mr_linear_to_srgb(rgb->pixels[i]) * 255.0; /* far from a rounding boundary */
                    mismatch += fabs(code - want) > 1e-4 || fabs(exact - want) > 1e-3;
                }
                MR_CHECK(mismatch == 0);
            }
            mr_image_free(back);
            remove(path);
            remove(dir);
        }
    }
    mr_image_free(rgb);
    rgb = NULL;
    MR_CHECK(mr_ssim_map_visualise(map, 1.0, &rgb) == MR_ERR_INVALID_ARG);
    MR_CHECK(mr_ssim_map_visualise(map, -1.5, &rgb) == MR_ERR_INVALID_ARG);
    mr_image *three = NULL;
    MR_CHECK_OK(mr_image_create(2, 2, 3, &three));
    MR_CHECK(mr_ssim_map_visualise(three, 0.0, &rgb) == MR_ERR_INVALID_ARG);
    MR_CHECK(rgb == NULL);
    mr_image_free(three);
    mr_image_free(map);
}

MR_TEST_MAIN(MR_TEST_ENTRY(ssim_of_an_image_with_itself_is_exactly_one), MR_TEST_ENTRY(ssim_is_symmetric),
             MR_TEST_ENTRY(ssim_decreases_with_noise), MR_TEST_ENTRY(constant_images_known_answer),
             MR_TEST_ENTRY(ssim_matches_brute_force_reference), MR_TEST_ENTRY(map_has_valid_size_and_mean),
             MR_TEST_ENTRY(exposure_and_alpha), MR_TEST_ENTRY(non_finite_pixels),
             MR_TEST_ENTRY(measurements_must_be_finite_radiance), MR_TEST_ENTRY(size_errors),
             MR_TEST_ENTRY(deterministic_across_thread_counts), MR_TEST_ENTRY(matlab_downsampling),
             MR_TEST_ENTRY(rmse_known_answers), MR_TEST_ENTRY(masked_ssim_matches_definition),
             MR_TEST_ENTRY(mask_of_ones_is_the_whole_frame),
             MR_TEST_ENTRY(background_difference_leaves_object_figures),
             MR_TEST_ENTRY(object_difference_weighs_more_on_the_object), MR_TEST_ENTRY(mask_errors),
             MR_TEST_ENTRY(map_visualisation))
