/*
 * metrics.c — RMSE and SSIM (contracts and the SSIM convention in metrics.h; rationale in docs/metrics.md).
 *
 * SSIM: Z. Wang, A. C. Bovik, H. R. Sheikh, E. P. Simoncelli, "Image quality assessment: from error visibility
 * to structural similarity", IEEE Trans. Image Processing 13(4), 600-612, 2004, eq. (13) with the parameters
 * of its reference MATLAB code ssim.m (Z. Wang, 2009, "SSIM index with automatic downsampling"):
 *   window  fspecial('gaussian', 11, 1.5), normalised to sum 1;  filter2(..., 'valid');
 *   C1 = (K1 L)^2, C2 = (K2 L)^2 with K1 = 0.01, K2 = 0.03, L = 1 (our luma is in [0,1]);
 *   sigma_x^2 = E[x^2] - mu_x^2 (population moments, as filter2 with a unit-sum window gives);
 *   SSIM = (2 mu_x mu_y + C1)(2 sigma_xy + C2) / ((mu_x^2 + mu_y^2 + C1)(sigma_x^2 + sigma_y^2 + C2));
 *   MSSIM = mean of the map.
 * Optional downsampling (opts.downsample = 1) is ssim.m's rule: f = max(1, round(min(M,N)/256)); if f > 1,
 * imfilter(img, ones(f)/f^2, 'symmetric', 'same') then img(1:f:end, 1:f:end). imfilter anchors a kernel at
 * floor((f+1)/2) (MATLAB documentation, "imfilter"), so for even f each output averages the f x f block
 * starting at the kept pixel; the 'symmetric' border mirrors including the edge pixel.
 *
 * Implementation:
 *   1. display mapping per pixel (metrics.h): x = clamp(v * exposure, 0, 1) (NaN -> 0), sRGB-encoded per
 *      IEC 61966-2-1, luma Y' = 0.299 R' + 0.587 G' + 0.114 B' (ITU-R BT.601), all in double;
 *   2. the 11x11 Gaussian is separable (w_ij = g_i g_j exactly), so the five moments x, y, x^2, y^2, xy are
 *      filtered horizontally row by row into a ring of the last 11 rows, then vertically while the map is
 *      evaluated (ssim_stream: rows stream through a small per-thread buffer, no whole-image temporaries);
 *   3. OpenMP splits rows among threads, but every value is computed by the same operations in the same order
 *      whichever thread runs it, and the mean sums per-row sums sequentially: the result is bit-identical
 *      for any thread count (a plain OpenMP reduction would not be; ../shared/docs/toolchain.md).
 * Speed (docs/metrics.md): the sRGB encoding is the hot spot (pow() costs ~25 ns here; a 512^2 RGB image
 * needs 786k of them), so step 1 evaluates x^(1/2.4) as t0^(1/2.4) (1 + u)^(1/2.4): t0 is x with all but 7
 * mantissa bits cleared (its power comes from a 1076-entry table computed with pow() on every call: no global
 * state), u = x/t0 - 1 is in [0, 2^-7), and (1 + u)^(1/2.4) is its binomial series to u^6 (truncation below
 * 1e-16 relative), so the encoding agrees with pow() to ~1e-15. The hot loops are branch-free and
 * vectorise; they also get an AVX2 clone (MR_SIMD_CLONES), bit-identical to the baseline one.
 */
#include "metrics.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "../mr_internal.h"

/* Images smaller than this are measured on one thread: a team costs more than it saves (a remap measures its
 * 64^2 fit once per run; many run side by side). Results do not depend on the thread count. */
#define METRICS_PARALLEL_PIXELS 65536

/* requested: the caller's thread count (mr_ssim_options.threads; 0 = automatic). */
static int metrics_threads(int requested, long pixels) {
    return mr_auto_threads(requested, pixels, METRICS_PARALLEL_PIXELS);
}

#define SSIM_WIN 11
#define SSIM_RADIUS 5
#define SSIM_SIGMA 1.5
#define SSIM_K1 0.01
#define SSIM_K2 0.03
#define SSIM_L 1.0

/* ---- sRGB encoding in double (IEC 61966-2-1) ---------------------------------------------------------- */

#define ENC_SHIFT 45 /* keep the exponent and the top 52 - 45 = 7 mantissa bits */

/* Binomial coefficients of (1 + u)^a, a = 1/2.4, as constant expressions (folded at compile time). */
#define ENC_A (1.0 / 2.4)
#define ENC_C1 ENC_A
#define ENC_C2 (ENC_C1 * (ENC_A - 1.0) / 2.0)
#define ENC_C3 (ENC_C2 * (ENC_A - 2.0) / 3.0)
#define ENC_C4 (ENC_C3 * (ENC_A - 3.0) / 4.0)
#define ENC_C5 (ENC_C4 * (ENC_A - 4.0) / 5.0)
#define ENC_C6 (ENC_C5 * (ENC_A - 5.0) / 6.0)

typedef struct srgb_encoder {
    uint64_t first; /* table index of the smallest key above the linear segment */
    size_t count;
    double *base; /* t0^(1/2.4) */
    double *inv;  /* 1 / t0 */
} srgb_encoder;

static uint64_t double_bits(double x) {
    uint64_t bits;
    memcpy(&bits, &x, sizeof bits);
    return bits;
}

static double bits_double(uint64_t bits) {
    double x;
    memcpy(&x, &bits, sizeof x);
    return x;
}

static int encoder_init(srgb_encoder *enc) {
    enc->first = double_bits(0.0031308) >> ENC_SHIFT;
    uint64_t last = double_bits(1.0) >> ENC_SHIFT;
    enc->count = (size_t)(last - enc->first + 1);
    enc->base = malloc(2 * enc->count * sizeof(double));
    if (enc->base == NULL) return 0;
    enc->inv = enc->base + enc->count;
    for (size_t i = 0; i < enc->count; i++) {
        double t0 = bits_double((enc->first + i) << ENC_SHIFT);
        enc->base[i] = pow(t0, ENC_A);
        enc->inv[i] = 1.0 / t0;
    }
    return 1;
}

static void encoder_free(srgb_encoder *enc) { free(enc->base); }

/* clamp(x, 0, 1) then sRGB-encode; NaN maps to 0. Series truncated after u^6: the next term is below
 * 0.02 * 2^-49 relative. Written without branches (both segments are evaluated, the table index is kept in
 * range for the linear one) so that loops over it vectorize with gathers where the CPU has them. */
static inline double bit_select(uint64_t mask, double a, double b) { /* mask ? a : b, bitwise */
    return bits_double((double_bits(a) & mask) | (double_bits(b) & ~mask));
}

static inline double display_encode(const double *base, const double *inv, int64_t first, double x) {
    /* clamp to [0,1] as masks (a ?: would become a branch the vectoriser cannot speculate); NaN and -0.0
     * become +0.0, so the sign bit is clear and the table index below stays in range */
    x = bit_select((uint64_t)0 - (uint64_t)(x > 0.0), x, 0.0);
    x = bit_select((uint64_t)0 - (uint64_t)(x <= 1.0), x, 1.0);
    int64_t key = (int64_t)(double_bits(x) >> ENC_SHIFT);
    key = key > first ? key : first;
    const int64_t i = key - first;
    const double u = (x - bits_double((uint64_t)key << ENC_SHIFT)) * inv[i];
    const double p = 1.0 + u * (ENC_C1 + u * (ENC_C2 + u * (ENC_C3 + u * (ENC_C4 + u * (ENC_C5 + u * ENC_C6)))));
    const double curve = 1.055 * (base[i] * p) - 0.055;
    return bit_select((uint64_t)0 - (uint64_t)(x > 0.0031308), curve, 12.92 * x);
}

/* Hot loops get an AVX2 clone beside the baseline one (GCC function multiversioning, chosen once per process
 * from the CPU). Without FMA contraction (ISO C mode implies -ffp-contract=off) every operation rounds as in
 * the baseline, so both clones give bit-identical results. */
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && defined(__linux__)
#define MR_SIMD_CLONES __attribute__((target_clones("avx2", "default")))
#else
#define MR_SIMD_CLONES
#endif

/* One row of display luma (metrics.h steps 1-2): ch 1 is used as grey; ch 3 or 4 gives BT.601 luma. The RGB
 * and RGBA loops are written out separately so that each has a compile-time stride and vectorises. */
MR_SIMD_CLONES
static void luma_row(const float *src, int w, int ch, double exposure, const double *base, const double *inv,
                     int64_t first, double *dst) {
    if (ch == 1) {
#pragma omp simd
        for (int x = 0; x < w; x++) dst[x] = display_encode(base, inv, first, (double)src[x] * exposure);
    } else if (ch == 3) {
#pragma omp simd
        for (int x = 0; x < w; x++) {
            const float *p = src + 3 * (size_t)x;
            const double r = display_encode(base, inv, first, (double)p[0] * exposure);
            const double g = display_encode(base, inv, first, (double)p[1] * exposure);
            const double b = display_encode(base, inv, first, (double)p[2] * exposure);
            dst[x] = 0.299 * r + 0.587 * g + 0.114 * b;
        }
    } else {
#pragma omp simd
        for (int x = 0; x < w; x++) {
            const float *p = src + 4 * (size_t)x;
            const double r = display_encode(base, inv, first, (double)p[0] * exposure);
            const double g = display_encode(base, inv, first, (double)p[1] * exposure);
            const double b = display_encode(base, inv, first, (double)p[2] * exposure);
            dst[x] = 0.299 * r + 0.587 * g + 0.114 * b;
        }
    }
}

/* The display-referred luma plane of `image` (w*h doubles, row-major). */
static void luma_plane(const mr_image *image, double exposure, const srgb_encoder *enc, int requested, double *out) {
    const int w = image->width, h = image->height, ch = image->channels;
    const int threads = metrics_threads(requested, (long)w * h);
#pragma omp parallel for schedule(static) num_threads(threads) if (threads > 1)
    for (int y = 0; y < h; y++)
        luma_row(image->pixels + (size_t)y * (size_t)w * (size_t)ch, w, ch, exposure, enc->base, enc->inv,
                 (int64_t)enc->first, out + (size_t)y * (size_t)w);
}

/* ---- MATLAB downsampling --------------------------------------------------------------------------- */

static int mirror_index(int i, int n) {
    if (i < 0) return -i - 1;      /* 'symmetric': ... x1 x0 | x0 x1 ... */
    if (i >= n) return 2 * n - i - 1;
    return i;
}

/* ssim.m's imfilter(ones(f)/f^2, 'symmetric', 'same') + (1:f:end, 1:f:end): src w x h -> dst dw x dh. */
static void downsample_plane(const double *src, int w, int h, int f, int requested, double *dst, int dw, int dh) {
    const int before = (f + 1) / 2 - 1; /* MATLAB's kernel origin is floor((f+1)/2) (1-based) */
    const double area = (double)f * (double)f;
    const int threads = metrics_threads(requested, (long)w * h);
#pragma omp parallel for schedule(static) num_threads(threads) if (threads > 1)
    for (int i = 0; i < dh; i++) {
        for (int j = 0; j < dw; j++) {
            double sum = 0.0;
            for (int r = 0; r < f; r++) {
                const double *row = src + (size_t)mirror_index(i * f - before + r, h) * (size_t)w;
                for (int c = 0; c < f; c++) sum += row[mirror_index(j * f - before + c, w)];
            }
            dst[(size_t)i * (size_t)dw + (size_t)j] = sum / area;
        }
    }
}

/* MATLAB's round() (half away from zero) of min(w,h)/256, at least 1. */
static int downsample_factor(int w, int h) {
    double f = floor((double)MR_MIN(w, h) / 256.0 + 0.5);
    return f < 1.0 ? 1 : (int)f;
}

/* ---- SSIM core -------------------------------------------------------------------------------------- */

static void gaussian_taps(double g[SSIM_WIN]) {
    double sum = 0.0;
    for (int k = 0; k < SSIM_WIN; k++) {
        double d = (double)(k - SSIM_RADIUS);
        g[k] = exp(-d * d / (2.0 * SSIM_SIGMA * SSIM_SIGMA));
        sum += g[k];
    }
    for (int k = 0; k < SSIM_WIN; k++) g[k] /= sum;
}

/* Horizontal pass for one row: the five moments x, y, x^2, y^2, xy correlated with the 11 taps (n inputs ->
 * n - 10 outputs). Taps k and 10-k are equal and paired; products are formed on the fly. With x == y the
 * x^2 and xy sums are the same operations on the same values, so SSIM(x, x) comes out exactly 1. */
MR_SIMD_CLONES
static void filter_row(const double *x, const double *y, int n_out, const double g[SSIM_WIN], double *hx,
                       double *hy, double *hxx, double *hyy, double *hxy) {
#pragma omp simd
    for (int j = 0; j < n_out; j++) {
        const double cx = x[j + SSIM_RADIUS], cy = y[j + SSIM_RADIUS], gc = g[SSIM_RADIUS];
        double sx = gc * cx, sy = gc * cy, sxx = gc * (cx * cx), syy = gc * (cy * cy), sxy = gc * (cx * cy);
        for (int k = 0; k < SSIM_RADIUS; k++) {
            const double a = x[j + k], b = x[j + SSIM_WIN - 1 - k];
            const double c = y[j + k], d = y[j + SSIM_WIN - 1 - k];
            const double gk = g[k];
            sx += gk * (a + b);
            sy += gk * (c + d);
            sxx += gk * (a * a + b * b);
            syy += gk * (c * c + d * d);
            sxy += gk * (a * c + b * d);
        }
        hx[j] = sx;
        hy[j] = sy;
        hxx[j] = sxx;
        hyy[j] = syy;
        hxy[j] = sxy;
    }
}

/* Vertical 11-tap correlation at offset o of the ring rows s[0..10] (s[k] holds horizontal row r+k), paired
 * like filter_row. Written out tap by tap so the loop around it vectorises. */
static inline double vertical_taps(const double *const s[SSIM_WIN], size_t o, const double g[SSIM_WIN]) {
    double v = g[5] * s[5][o];
    v += g[0] * (s[0][o] + s[10][o]);
    v += g[1] * (s[1][o] + s[9][o]);
    v += g[2] * (s[2][o] + s[8][o]);
    v += g[3] * (s[3][o] + s[7][o]);
    v += g[4] * (s[4][o] + s[6][o]);
    return v;
}

/* One row of the SSIM map from the 11 horizontal rows s[k] (each holding the five moment rows x, y, x^2, y^2,
 * xy of ow values one after another): vertical taps accumulated in registers, then Wang et al.'s formula. */
MR_SIMD_CLONES
static void ssim_row(const double *const rows[SSIM_WIN], int ow, const double g[SSIM_WIN], double c1, double c2,
                     double *srow) {
    const double *s[SSIM_WIN];
    for (int k = 0; k < SSIM_WIN; k++) s[k] = rows[k];
    const size_t n = (size_t)ow;
#pragma omp simd
    for (int j = 0; j < ow; j++) {
        const size_t o = (size_t)j;
        const double mux = vertical_taps(s, o, g), muy = vertical_taps(s, n + o, g);
        const double exx = vertical_taps(s, 2 * n + o, g), eyy = vertical_taps(s, 3 * n + o, g);
        const double exy = vertical_taps(s, 4 * n + o, g);
        const double mux2 = mux * mux, muy2 = muy * muy, muxy = mux * muy;
        const double vx = exx - mux2, vy = eyy - muy2, cxy = exy - muxy;
        srow[j] = ((2.0 * muxy + c1) * (2.0 * cxy + c2)) / ((mux2 + muy2 + c1) * (vx + vy + c2));
    }
}

/* Where the luma rows come from: computed on the fly from the images (the usual case), or read from
 * precomputed planes (after downsampling). */
typedef struct luma_source {
    const mr_image *a, *b; /* on the fly when a != NULL */
    double exposure;
    const srgb_encoder *enc;
    const double *x, *y; /* planes, w values per row */
    int w;
} luma_source;

/* Horizontal moments of row r into `slot` (5 x ow values); xbuf/ybuf are w-value scratch rows. */
static void horizontal_row(const luma_source *src, int r, int ow, const double g[SSIM_WIN], double *xbuf,
                           double *ybuf, double *slot) {
    const double *x, *y;
    if (src->a != NULL) {
        const mr_image *a = src->a, *b = src->b;
        const size_t off = (size_t)r * (size_t)a->width * (size_t)a->channels;
        const srgb_encoder *e = src->enc;
        luma_row(a->pixels + off, a->width, a->channels, src->exposure, e->base, e->inv, (int64_t)e->first, xbuf);
        luma_row(b->pixels + off, b->width, b->channels, src->exposure, e->base, e->inv, (int64_t)e->first, ybuf);
        x = xbuf;
        y = ybuf;
    } else {
        x = src->x + (size_t)r * (size_t)src->w;
        y = src->y + (size_t)r * (size_t)src->w;
    }
    const size_t n = (size_t)ow;
    filter_row(x, y, ow, g, slot, slot + n, slot + 2 * n, slot + 3 * n, slot + 4 * n);
}

/* SSIM of two w x h luma sources. map (optional) receives (w-10)x(h-10) floats. counted (optional, (w-10) x
 * (h-10) flags) restricts the mean to the map pixels flagged non-zero (there must be at least one); NULL = all.
 * Returns 0 on OOM.
 * The output rows are cut into one contiguous band per thread; each band streams through its rows keeping the
 * last 11 horizontal rows in a ring, so memory is ~57 rows of doubles per thread instead of whole planes
 * (no page faults for megabytes of temporaries, and the working set stays in cache). A band recomputes the 10
 * horizontal rows it shares with its neighbour, by the same code on the same inputs, so every value, and the
 * result, is the same for any number of threads or bands. */
static int ssim_stream(const luma_source *src, int w, int h, const unsigned char *counted, int requested, float *map,
                       double *out) {
    const int ow = w - (SSIM_WIN - 1), oh = h - (SSIM_WIN - 1);
    double g[SSIM_WIN];
    gaussian_taps(g);
    const double c1 = (SSIM_K1 * SSIM_L) * (SSIM_K1 * SSIM_L);
    const double c2 = (SSIM_K2 * SSIM_L) * (SSIM_K2 * SSIM_L);

    const int threads = metrics_threads(requested, (long)w * h);
    const int bands = MR_MIN(threads, oh);
    const size_t slot_size = 5 * (size_t)ow;
    const size_t per_thread = 2 * (size_t)w + SSIM_WIN * slot_size + (size_t)ow;
    double *scratch = malloc((size_t)threads * per_thread * sizeof(double));
    double *row_sums = malloc((size_t)oh * sizeof(double));
    size_t *row_counts = malloc((size_t)oh * sizeof(size_t));
    if (scratch == NULL || row_sums == NULL || row_counts == NULL) {
        free(scratch);
        free(row_sums);
        free(row_counts);
        return 0;
    }

#pragma omp parallel num_threads(threads)
    {
        int t = 0;
#ifdef _OPENMP
        t = omp_get_thread_num();
#endif
        double *xbuf = scratch + (size_t)t * per_thread, *ybuf = xbuf + w;
        double *ring = ybuf + w, *srow = ring + SSIM_WIN * slot_size;

#pragma omp for schedule(static)
        for (int band = 0; band < bands; band++) {
            const int r0 = (int)((long long)oh * band / bands), r1 = (int)((long long)oh * (band + 1) / bands);
            for (int hr = r0; hr < r0 + SSIM_WIN - 1; hr++)
                horizontal_row(src, hr, ow, g, xbuf, ybuf, ring + (size_t)(hr % SSIM_WIN) * slot_size);
            for (int r = r0; r < r1; r++) {
                const int hr = r + SSIM_WIN - 1;
                horizontal_row(src, hr, ow, g, xbuf, ybuf, ring + (size_t)(hr % SSIM_WIN) * slot_size);
                const double *rows[SSIM_WIN];
                for (int k = 0; k < SSIM_WIN; k++) rows[k] = ring + (size_t)((r + k) % SSIM_WIN) * slot_size;
                ssim_row(rows, ow, g, c1, c2, srow);
                double sum = 0.0; /* in index order, whatever the thread */
                size_t n = (size_t)ow;
                if (counted == NULL) {
                    for (int j = 0; j < ow; j++) sum += srow[j];
                } else { /* the same additions, in the same order, over the flagged values only */
                    const unsigned char *flags = counted + (size_t)r * (size_t)ow;
                    n = 0;
                    for (int j = 0; j < ow; j++)
                        if (flags[j]) {
                            sum += srow[j];
                            n++;
                        }
                }
                row_sums[r] = sum;
                row_counts[r] = n;
                if (map != NULL) {
                    float *map_row = map + (size_t)r * (size_t)ow;
                    for (int j = 0; j < ow; j++) map_row[j] = (float)srow[j];
                }
            }
        }
    }

    double total = 0.0;
    size_t count = 0;
    for (int r = 0; r < oh; r++) {
        total += row_sums[r];
        count += row_counts[r];
    }
    /* count is ow * oh without flags, so the whole-frame mean is the division it always was */
    *out = counted == NULL ? total / ((double)ow * (double)oh) : total / (double)count;
    free(scratch);
    free(row_sums);
    free(row_counts);
    return 1;
}

/* ---- object masks (metrics.h) ------------------------------------------------------------------------ */

/* A mask for images of w x h: 1 channel, that size, every value finite and in [0, 1]. */
static mr_status check_mask(const char *what, const mr_image *mask, int w, int h) {
    if (mask->pixels == NULL || mask->channels != 1 || mask->width != w || mask->height != h)
        return mr_fail(MR_ERR_INVALID_ARG, "%s: the mask is %dx%dx%d; expected %dx%dx1 (the images' size, one "
                       "channel)", what, mask->width, mask->height, mask->channels, w, h);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            const float v = mask->pixels[(size_t)y * (size_t)w + (size_t)x];
            if (!(v >= 0.0f && v <= 1.0f))
                return mr_fail(MR_ERR_INVALID_ARG, "%s: mask value %g at pixel (%d, %d) is outside [0, 1]", what,
                               (double)v, x, y);
        }
    return MR_OK;
}

/* The map pixels whose 11 x 11 window holds an object pixel (mask > 0): the mask dilated by SSIM_RADIUS in
 * both directions, at the 'valid' centres. Separable: a horizontal "any" over 11 columns, then a vertical one
 * over 11 rows. Returns a new (w-10) x (h-10) flag array and the number of flags set, or NULL on OOM. */
static unsigned char *window_support(const mr_image *mask, size_t *out_count) {
    const int w = mask->width, h = mask->height, ow = w - (SSIM_WIN - 1), oh = h - (SSIM_WIN - 1);
    unsigned char *across = malloc((size_t)ow * (size_t)h);
    unsigned char *flags = malloc((size_t)ow * (size_t)oh);
    if (across == NULL || flags == NULL) {
        free(across);
        free(flags);
        return NULL;
    }
    for (int y = 0; y < h; y++) {
        const float *row = mask->pixels + (size_t)y * (size_t)w;
        // Distance-based running "any": last = the latest object column seen so far.
        int last = -SSIM_WIN;
        for (int x = 0; x < w; x++) {
            if (row[x] > 0.0f) last = x;
            if (x >= SSIM_WIN - 1) across[(size_t)y * (size_t)ow + (size_t)(x - (SSIM_WIN - 1))] =
                (unsigned char)(x - last < SSIM_WIN);
        }
    }
    size_t count = 0;
    for (int x = 0; x < ow; x++) {
        int last = -SSIM_WIN;
        for (int y = 0; y < h; y++) {
            if (across[(size_t)y * (size_t)ow + (size_t)x]) last = y;
            if (y >= SSIM_WIN - 1) {
                const unsigned char f = (unsigned char)(y - last < SSIM_WIN);
                flags[(size_t)(y - (SSIM_WIN - 1)) * (size_t)ow + (size_t)x] = f;
                count += f;
            }
        }
    }
    free(across);
    *out_count = count;
    return flags;
}

static mr_status check_pair(const char *what, const mr_image *a, const mr_image *b) {
    if (a == NULL || b == NULL || a->pixels == NULL || b->pixels == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "%s: images must not be NULL", what);
    if (a->channels != 1 && a->channels != 3 && a->channels != 4)
        return mr_fail(MR_ERR_INVALID_ARG, "%s: first image has %d channels (valid: 1, 3, 4)", what, a->channels);
    if (a->width < 1 || a->height < 1)
        return mr_fail(MR_ERR_INVALID_ARG, "%s: first image has size %dx%d", what, a->width, a->height);
    if (a->width != b->width || a->height != b->height || a->channels != b->channels)
        return mr_fail(MR_ERR_INVALID_ARG,
                       "%s: images differ in size: %dx%dx%d vs %dx%dx%d (width x height x channels)", what, a->width,
                       a->height, a->channels, b->width, b->height, b->channels);
    // A NaN or an infinity has no difference and no display value: the caller's data is wrong (the labels say
    // which image; a caller with files checks them first, naming the file: mr_image_check_radiance).
    char label[64];
    snprintf(label, sizeof label, "%s: image a", what);
    mr_status status = mr_image_check_values(a, label, 1);
    snprintf(label, sizeof label, "%s: image b", what);
    if (status == MR_OK) status = mr_image_check_values(b, label, 1);
    return status;
}

mr_status mr_ssim(const mr_image *a, const mr_image *b, const mr_ssim_options *opts, double *out_ssim,
                  mr_image **map_out) {
    mr_status status = check_pair("ssim", a, b);
    if (status != MR_OK) return status;
    if (out_ssim == NULL) return mr_fail(MR_ERR_INVALID_ARG, "ssim: out_ssim must not be NULL");
    mr_ssim_options o = {0.0, 0, NULL, 0};
    if (opts != NULL) o = *opts;
    const double exposure = o.exposure == 0.0 ? 1.0 : o.exposure;
    if (!(exposure > 0.0) || !isfinite(exposure))
        return mr_fail(MR_ERR_INVALID_ARG, "ssim: exposure %g must be positive and finite (0 = 1)", o.exposure);
    if (o.downsample != 0 && o.downsample != 1)
        return mr_fail(MR_ERR_INVALID_ARG, "ssim: downsample %d (valid: 0 = none, 1 = MATLAB rule)", o.downsample);
    if (o.threads < 0 || o.threads > MR_METRICS_MAX_THREADS)
        return mr_fail(MR_ERR_INVALID_ARG, "ssim: threads %d (valid: 0 = automatic, 1 .. %d)", o.threads,
                       MR_METRICS_MAX_THREADS);

    const int w = a->width, h = a->height;
    if (o.mask != NULL) {
        if (o.downsample)
            return mr_fail(MR_ERR_INVALID_ARG, "ssim: a mask and downsampling cannot be combined (the mask is at "
                           "full resolution)");
        status = check_mask("ssim", o.mask, w, h);
        if (status != MR_OK) return status;
    }
    const int f = o.downsample ? downsample_factor(w, h) : 1;
    const int dw = (w + f - 1) / f, dh = (h + f - 1) / f;
    /* (Downsampling keeps at least ~171 pixels per side, since f = round(min(w,h)/256), so only the input
     * size can be too small.) */
    if (dw < SSIM_WIN || dh < SSIM_WIN)
        return mr_fail(MR_ERR_INVALID_ARG, "ssim: images of %dx%d are smaller than the %dx%d SSIM window", w, h,
                       SSIM_WIN, SSIM_WIN);

    unsigned char *counted = NULL;
    if (o.mask != NULL) {
        size_t count = 0;
        counted = window_support(o.mask, &count);
        if (counted == NULL) return mr_fail(MR_ERR_NOMEM, "ssim: out of memory for a %dx%d mask", w, h);
        if (count == 0) {
            free(counted);
            return mr_fail(MR_ERR_INVALID_ARG, "ssim: the mask has no object pixel within the SSIM windows of "
                           "the %dx%d images", w, h);
        }
    }
    mr_image *map = NULL;
    if (map_out != NULL) {
        status = mr_image_create(dw - (SSIM_WIN - 1), dh - (SSIM_WIN - 1), 1, &map);
        if (status != MR_OK) {
            free(counted);
            return mr_fail_context(status, "ssim map");
        }
    }
    srgb_encoder enc;
    if (!encoder_init(&enc)) {
        free(counted);
        mr_image_free(map);
        return mr_fail(MR_ERR_NOMEM, "ssim: out of memory");
    }
    luma_source src = {a, b, exposure, &enc, NULL, NULL, w};
    double *planes = NULL;
    if (f > 1) {
        /* Downsampling needs whole luma planes: full resolution, then the decimated ones. */
        const size_t full = (size_t)w * (size_t)h, small = (size_t)dw * (size_t)dh;
        planes = malloc((2 * full + 2 * small) * sizeof(double));
        if (planes == NULL) {
            encoder_free(&enc);
            mr_image_free(map);
            return mr_fail(MR_ERR_NOMEM, "ssim: out of memory for %dx%d images", w, h);
        }
        double *x = planes, *y = planes + full, *xs = y + full, *ys = xs + small;
        luma_plane(a, exposure, &enc, o.threads, x);
        luma_plane(b, exposure, &enc, o.threads, y);
        downsample_plane(x, w, h, f, o.threads, xs, dw, dh);
        downsample_plane(y, w, h, f, o.threads, ys, dw, dh);
        src.a = src.b = NULL;
        src.x = xs;
        src.y = ys;
        src.w = dw;
    }
    double value = 0.0;
    int ok = ssim_stream(&src, dw, dh, counted, o.threads, map != NULL ? map->pixels : NULL, &value);
    free(counted);
    free(planes);
    encoder_free(&enc);
    if (!ok) {
        mr_image_free(map);
        return mr_fail(MR_ERR_NOMEM, "ssim: out of memory for %dx%d images", w, h);
    }
    *out_ssim = value;
    if (map_out != NULL) *map_out = map;
    return MR_OK;
}

/* ---- RMSE ------------------------------------------------------------------------------------------- */

mr_status mr_rmse(const mr_image *a, const mr_image *b, double *out_rmse) {
    return mr_rmse_masked(a, b, NULL, 0, out_rmse, NULL);
}

mr_status mr_rmse_masked(const mr_image *a, const mr_image *b, const mr_image *mask, int threads_requested,
                         double *out_rmse, double *out_mean_a) {
    mr_status status = check_pair("rmse", a, b);
    if (status != MR_OK) return status;
    if (out_rmse == NULL) return mr_fail(MR_ERR_INVALID_ARG, "rmse: out_rmse must not be NULL");
    const int w = a->width, h = a->height, ch = a->channels, used = MR_MIN(3, ch);
    if (mask != NULL && (status = check_mask("rmse", mask, w, h)) != MR_OK) return status;
    if (threads_requested < 0 || threads_requested > MR_METRICS_MAX_THREADS)
        return mr_fail(MR_ERR_INVALID_ARG, "rmse: threads %d (valid: 0 = automatic, 1 .. %d)", threads_requested,
                       MR_METRICS_MAX_THREADS);
    double *row_sums = malloc(3 * (size_t)h * sizeof(double)); /* squared differences, a's values, pixels */
    if (row_sums == NULL) return mr_fail(MR_ERR_NOMEM, "rmse: out of memory");
    double *row_a = row_sums + h, *row_pixels = row_a + h;
    const int threads = metrics_threads(threads_requested, (long)w * h);
#pragma omp parallel for schedule(static) num_threads(threads) if (threads > 1)
    for (int y = 0; y < h; y++) {
        const float *pa = a->pixels + (size_t)y * (size_t)w * (size_t)ch;
        const float *pb = b->pixels + (size_t)y * (size_t)w * (size_t)ch;
        const float *pm = mask != NULL ? mask->pixels + (size_t)y * (size_t)w : NULL;
        double sum = 0.0, sum_a = 0.0, pixels = 0.0;
        for (int x = 0; x < w; x++) {
            if (pm != NULL && !(pm[x] > 0.0f)) continue;
            pixels += 1.0;
            for (int c = 0; c < used; c++) {
                const size_t i = (size_t)x * (size_t)ch + (size_t)c;
                const double d = (double)pa[i] - (double)pb[i];
                sum += d * d;
                sum_a += (double)pa[i];
            }
        }
        row_sums[y] = sum;
        row_a[y] = sum_a;
        row_pixels[y] = pixels;
    }
    double total = 0.0, total_a = 0.0, pixels = 0.0;
    for (int y = 0; y < h; y++) {
        total += row_sums[y];
        total_a += row_a[y];
        pixels += row_pixels[y];
    }
    free(row_sums);
    // The values are finite floats (check_pair), whose squares a double holds; kept as a guard.
    if (!isfinite(total) || !isfinite(total_a))
        return mr_fail(MR_ERR_NUMERIC, "rmse: the squared differences overflow a double");
    if (pixels == 0.0) return mr_fail(MR_ERR_INVALID_ARG, "rmse: the mask covers no pixel of the %dx%d images", w, h);
    /* without a mask, pixels = w * h exactly (a sum of ones below 2^53) */
    *out_rmse = sqrt(total / (pixels * (double)used));
    if (out_mean_a != NULL) *out_mean_a = total_a / (pixels * (double)used);
    return MR_OK;
}

/* ---- SSIM map picture ------------------------------------------------------------------------------- */

/* MATLAB's "hot" colour map (black -> red -> yellow -> white) as a function of t in [0,1], in display (sRGB)
 * values: red rises over [0, 3/8], green over [3/8, 6/8], blue over [6/8, 1]. */
static void hot_ramp(double t, double rgb[3]) {
    rgb[0] = mr_clampd(t / 0.375, 0.0, 1.0);
    rgb[1] = mr_clampd((t - 0.375) / 0.375, 0.0, 1.0);
    rgb[2] = mr_clampd((t - 0.75) / 0.25, 0.0, 1.0);
}

/* sRGB decode in double (IEC 61966-2-1) of a display value in [0,1]. */
static double srgb_decode(double v) { return v <= 0.04045 ? v / 12.92 : pow((v + 0.055) / 1.055, 2.4); }

mr_status mr_ssim_map_visualise(const mr_image *map, double floor_value, mr_image **out_rgb) {
    if (map == NULL || map->pixels == NULL || out_rgb == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "ssim map picture: map and out_rgb must not be NULL");
    if (map->channels != 1)
        return mr_fail(MR_ERR_INVALID_ARG, "ssim map picture: the map has %d channels (expected 1)", map->channels);
    const double lo = floor_value == 0.0 ? 0.5 : floor_value;
    if (!(lo >= -1.0 && lo < 1.0))
        return mr_fail(MR_ERR_INVALID_ARG, "ssim map picture: floor %g must be in [-1, 1) (0 = 0.5)", floor_value);
    mr_image *rgb = NULL;
    mr_status status = mr_image_create(map->width, map->height, 3, &rgb);
    if (status != MR_OK) return mr_fail_context(status, "ssim map picture");
    /* Display values are snapped to 8-bit codes, so an 8-bit sRGB write reproduces them exactly: the linear
     * values stored here are their exact decodes, far (> 1e-4 code) from any rounding boundary. */
    double code_to_linear[256];
    for (int q = 0; q < 256; q++) code_to_linear[q] = srgb_decode(q / 255.0);
    const size_t count = (size_t)map->width * (size_t)map->height;
    for (size_t i = 0; i < count; i++) {
        double s = map->pixels[i];
        double t = isnan(s) ? 1.0 : mr_clampd((1.0 - s) / (1.0 - lo), 0.0, 1.0); /* NaN shows as worst */
        double display[3];
        hot_ramp(t, display);
        for (int c = 0; c < 3; c++) {
            int q = (int)floor(display[c] * 255.0 + 0.5);
            rgb->pixels[i * 3 + (size_t)c] = (float)code_to_linear[q];
        }
    }
    *out_rgb = rgb;
    return MR_OK;
}
