/*
 * test_image_io.c — round trips and failure modes of src/io (contract in src/io/image_io.h).
 *
 * The main fixture is stb's asymmetric test image (stb tests/image_write_test.c): a 6x5 "F" in red on blue,
 * with a different colour in every corner, so a vertical or horizontal flip, a transpose or an R/B swap all
 * change some pixel. Every case works in a private directory from mkdtemp(), removed at exit.
 * Independent cross-checks: EXR written by OpenEXR Core (ours) is read back through OpenImageIO (the OpenEXR
 * C++ library), and files written by oiiotool (OpenImageIO + OpenEXR C++ / libpng) are read by mr_img_read.
 * Reading from memory (mr_img_read_memory) gives what reading the same bytes from a file gives, bit for bit.
 */
#include <dirent.h>
#include <errno.h>
#include <float.h>
#include <math.h>
#include <png.h>
#include <setjmp.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "../src/io/image_io.h"
#include "../src/io/io_internal.h"
#include "harness.h"

/* ---- fixtures and helpers ------------------------------------------------------------------------- */

/* Number of entries in the test directory whose name contains ".tmp". */
static int count_temporaries(void) {
    DIR *d = opendir(mr_test_scratch_dir());
    if (d == NULL) return -1;
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d)) != NULL)
        if (strstr(e->d_name, ".tmp") != NULL) n++;
    closedir(d);
    return n;
}

static int file_exists(const char *path) {
    struct stat st;
    return stat(path, &st) == 0;
}

static long read_file(const char *path, unsigned char *buf, long cap) {
    FILE *f = fopen(path, "rb");
    if (f == NULL) return -1;
    long n = (long)fread(buf, 1, (size_t)cap, f);
    fclose(f);
    return n;
}

/* Run a shell command quietly; returns its exit status (or -1). */
static int run_quiet(const char *cmd) {
    char full[4096];
    if (snprintf(full, sizeof full, "%s >/dev/null 2>&1", cmd) >= (int)sizeof full) return -1;
    int rc = system(full);
    return rc == -1 ? -1 : (WIFEXITED(rc) ? WEXITSTATUS(rc) : -1);
}

#define F_W 6
#define F_H 5
static const char f_shape[F_H][F_W + 1] = {
    ".XXXX.",
    ".X....",
    ".XXX..",
    ".X....",
    ".X....",
};

/* The F in red (1,0,0) on blue (0,0,1), corners (0,0) (5,0) (0,4) (5,4) distinct. `scale` multiplies every
 * value (HDR/EXR cases use values above 1). channels 1: grey levels instead of colours; 4: alpha varies. */
static mr_image *make_f(int channels, float scale) {
    mr_image *img = NULL;
    if (mr_image_create(F_W, F_H, channels, &img) != MR_OK) return NULL;
    static const float corners[4][4] = {
        {0.25f, 0.5f, 0.75f, 0.5f}, /* top-left */
        {0.75f, 0.125f, 0.5f, 0.0f}, /* top-right: alpha 0 with colour, catches premultiplication */
        {0.0625f, 0.875f, 0.25f, 0.25f}, /* bottom-left */
        {0.5f, 0.375f, 0.0f, 1.0f}, /* bottom-right */
    };
    for (int y = 0; y < F_H; y++)
        for (int x = 0; x < F_W; x++) {
            float *p = mr_image_at(img, x, y);
            float rgba[4];
            int corner = -1;
            if (x == 0 && y == 0) corner = 0;
            if (x == F_W - 1 && y == 0) corner = 1;
            if (x == 0 && y == F_H - 1) corner = 2;
            if (x == F_W - 1 && y == F_H - 1) corner = 3;
            if (corner >= 0) {
                memcpy(rgba, corners[corner], sizeof rgba);
            } else if (f_shape[y][x] == 'X') {
                rgba[0] = 1.0f, rgba[1] = 0.0f, rgba[2] = 0.0f, rgba[3] = 1.0f;
            } else {
                rgba[0] = 0.0f, rgba[1] = 0.0f, rgba[2] = 1.0f, rgba[3] = 0.75f;
            }
            if (channels == 1) {
                /* grey: F = 1, background 0.125, corners their first value */
                p[0] = scale * (corner >= 0 ? rgba[0] : (f_shape[y][x] == 'X' ? 1.0f : 0.125f));
            } else {
                for (int c = 0; c < 3; c++) p[c] = scale * rgba[c];
                if (channels == 4) p[3] = rgba[3];
            }
        }
    return img;
}

/* A width x height RGB image of pseudo-random values in [0,1] from `seed` (incompressible: a truncated file of it
 * loses pixel data, not padding). NULL on allocation failure. */
static mr_image *make_noise(int width, int height, unsigned seed) {
    mr_image *noise = NULL;
    if (mr_image_create(width, height, 3, &noise) != MR_OK) return NULL;
    for (size_t i = 0; i < mr_image_value_count(noise); i++) {
        seed = seed * 1103515245u + 12345u;
        noise->pixels[i] = (float)((seed >> 8) & 0xffff) / 65535.0f;
    }
    return noise;
}

/* What an integer file of `bits` stores for linear v and what reading it back must give. */
static float expected_integer(float v, int bits, int srgb) {
    double scale = bits == 16 ? 65535.0 : 255.0;
    double x = v < 0.0f ? 0.0 : (v > 1.0f ? 1.0 : v);
    if (srgb) x = mr_linear_to_srgb((float)x);
    double code = floor(x * scale + 0.5);
    float stored = (float)(code / scale);
    return srgb ? mr_srgb_to_linear(stored) : stored;
}

/* Compare b to the expected integer-file decode of a: returns the largest deviation. */
static double max_integer_error(const mr_image *a, const mr_image *b, int bits, int srgb) {
    double worst = 0.0;
    size_t n = mr_image_value_count(a);
    for (size_t i = 0; i < n; i++) {
        int alpha = a->channels == 4 && i % 4 == 3;
        double e = fabs((double)b->pixels[i] - (double)expected_integer(a->pixels[i], bits, srgb && !alpha));
        if (e > worst || isnan(e)) worst = isnan(e) ? INFINITY : e;
    }
    return worst;
}

static int same_shape(const mr_image *a, const mr_image *b) {
    return a != NULL && b != NULL && a->width == b->width && a->height == b->height && a->channels == b->channels;
}

/* Write `img` to `name` and read it back with default options; NULL on failure (checks recorded). */
static mr_image *round_trip(const char *name, const mr_image *img, const mr_img_write_options *wo,
                            const mr_img_read_options *ro) {
    const char *path = mr_test_tmp_path(name);
    MR_CHECK_OK(mr_img_write(path, img, wo));
    mr_image *back = NULL;
    MR_CHECK_OK(mr_img_read(path, ro, &back));
    MR_CHECK_MSG(same_shape(img, back), "%s: shape %dx%dx%d -> %dx%dx%d", name, img->width, img->height,
                 img->channels, back ? back->width : 0, back ? back->height : 0, back ? back->channels : 0);
    if (!same_shape(img, back)) {
        mr_image_free(back);
        return NULL;
    }
    return back;
}

/* ---- sRGB --------------------------------------------------------------------------------------------- */

/* First, before any other thread exists: a file only the OpenImageIO module writes and reads (TIFF) loads the
 * module. Besides checking that it loads, this keeps `make asan` working: GCC 12's LeakSanitizer crashes at exit
 * ("Tracer caught signal 11", in its scan of dynamic TLS) when the module's libraries were dlopen'ed after the
 * process had started threads, which happened once PNG stopped going through the module (png_io.c). */
MR_TEST(openimageio_module_loads_first) {
    mr_image *img = make_f(3, 0.5f), *back = NULL;
    const char *path = mr_test_tmp_path("module.tif");
    MR_CHECK_OK(mr_img_write(path, img, NULL));
    MR_CHECK_OK(mr_img_read(path, NULL, &back));
    MR_CHECK(back != NULL && back->width == img->width && back->height == img->height);
    mr_image_free(back);
    mr_image_free(img);
}

MR_TEST(srgb_transfer_functions) {
    MR_CHECK(mr_srgb_to_linear(0.0f) == 0.0f);
    MR_CHECK(mr_srgb_to_linear(1.0f) == 1.0f);
    MR_CHECK(mr_linear_to_srgb(0.0f) == 0.0f);
    MR_CHECK_NEAR(mr_linear_to_srgb(1.0f), 1.0, 1e-7);
    /* IEC 61966-2-1 values: 0.5 encoded is 0.21404114 linear; the linear segment below 0.04045. */
    MR_CHECK_NEAR(mr_srgb_to_linear(0.5f), 0.214041140482232, 1e-7);
    MR_CHECK_NEAR(mr_srgb_to_linear(0.04f), 0.04 / 12.92, 1e-9);
    MR_CHECK_NEAR(mr_linear_to_srgb(0.002f), 0.002 * 12.92, 1e-8);
    MR_CHECK_NEAR(mr_linear_to_srgb(0.214041140482232f), 0.5, 1e-7);
    /* The two segments meet (continuity at the breakpoints to the precision of the published constants). */
    MR_CHECK_NEAR(mr_srgb_to_linear(0.04045f), 0.0031308, 1e-7);
    MR_CHECK_NEAR(mr_linear_to_srgb(0.0031308f), 0.04045, 1e-6);
    /* Every 8-bit and 16-bit code survives decode + encode, and decoding is strictly increasing. */
    int bad = 0;
    float prev = -1.0f;
    for (int q = 0; q <= 65535; q++) {
        float v = (float)(q / 65535.0);
        float lin = mr_srgb_to_linear(v);
        if (!(lin > prev)) bad++;
        prev = lin;
        if ((int)floor(mr_linear_to_srgb(lin) * 65535.0 + 0.5) != q) bad++;
    }
    MR_CHECK_MSG(bad == 0, "%d 16-bit codes failed", bad);
    /* Negative values are mirrored, not NaN. */
    MR_CHECK_NEAR(mr_linear_to_srgb(-0.25f), -mr_linear_to_srgb(0.25f), 0.0);
    MR_CHECK(isnan(mr_linear_to_srgb(NAN)));
}

/* ---- round trips -------------------------------------------------------------------------------------- */

MR_TEST(png8_rgb_round_trip) {
    mr_image *f = make_f(3, 1.0f);
    mr_image *back = round_trip("f8.png", f, NULL, NULL);
    if (back) {
        MR_CHECK_NEAR(max_integer_error(f, back, 8, 1), 0.0, 1e-6);
        /* and the decode really is sRGB: 0.25 linear is not stored as 64/255 */
        MR_CHECK_NEAR(mr_image_at(back, 0, 0)[0], 0.25, 0.003);
        MR_CHECK(mr_image_at(back, 1, 0)[0] == 1.0f && mr_image_at(back, 1, 0)[2] == 0.0f);
    }
    /* Read as data: the raw stored codes, code = round(encode(v) * 255). */
    mr_img_read_options ro = {MR_IMG_DATA, 0, 0};
    mr_image *raw = NULL;
    MR_CHECK_OK(mr_img_read(mr_test_tmp_path("f8.png"), &ro, &raw));
    if (raw) MR_CHECK_NEAR(raw->pixels[0] * 255.0, floor(mr_linear_to_srgb(0.25f) * 255.0 + 0.5), 1e-4);
    mr_image_free(raw);
    mr_image_free(back);
    mr_image_free(f);
}

MR_TEST(png16_rgb_round_trip) {
    mr_image *f = make_f(3, 1.0f);
    mr_img_write_options wo = {MR_IMG_COLOR, 16, 0};
    mr_image *back = round_trip("f16.png", f, &wo, NULL);
    if (back) MR_CHECK_NEAR(max_integer_error(f, back, 16, 1), 0.0, 1e-6);
    mr_image_free(back);
    mr_image_free(f);
}

MR_TEST(large_integer_round_trips) {
    /* Large enough that reading tabulates the decode of every code (8 and 16 bit), noisy so every code
     * region is hit; the result must be exactly the per-value decode. */
    mr_image *noise = NULL, *grey = NULL;
    MR_CHECK_OK(mr_image_create(160, 160, 3, &noise));
    MR_CHECK_OK(mr_image_create(160, 160, 1, &grey));
    unsigned s = 4242;
    for (size_t i = 0; i < mr_image_value_count(noise); i++) {
        s = s * 1103515245u + 12345u;
        noise->pixels[i] = (float)((s >> 8) & 0xffff) / 60000.0f - 0.02f; /* a little below 0 and above 1 */
    }
    for (size_t i = 0; i < mr_image_value_count(grey); i++) grey->pixels[i] = noise->pixels[3 * i];
    for (int bits = 8; bits <= 16; bits += 8) {
        mr_img_write_options wo = {MR_IMG_COLOR, bits, 0};
        mr_image *back = round_trip(bits == 8 ? "big8.png" : "big16.png", noise, &wo, NULL);
        if (back) MR_CHECK_NEAR(max_integer_error(noise, back, bits, 1), 0.0, 0.0);
        mr_image_free(back);
        back = round_trip(bits == 8 ? "bigg8.png" : "bigg16.tif", grey, &wo, NULL);
        if (back) MR_CHECK_NEAR(max_integer_error(grey, back, bits, 1), 0.0, 0.0);
        mr_image_free(back);
    }
    mr_image_free(grey);
    mr_image_free(noise);
}

MR_TEST(png_data_encoding_is_linear) {
    mr_image *f = make_f(3, 1.0f);
    mr_img_write_options wo = {MR_IMG_DATA, 8, 0};
    mr_img_read_options ro = {MR_IMG_DATA, 0, 0};
    mr_image *back = round_trip("data.png", f, &wo, &ro);
    if (back) {
        MR_CHECK_NEAR(max_integer_error(f, back, 8, 0), 0.0, 1e-6);
        MR_CHECK_NEAR(mr_image_at(back, 0, 0)[0], 64.0 / 255.0, 1e-7); /* 0.25 -> code 64 */
    }
    mr_image_free(back);
    mr_image_free(f);
}

MR_TEST(tiff_round_trips) {
    mr_image *f = make_f(3, 1.0f);
    for (int bits = 8; bits <= 16; bits += 8) {
        mr_img_write_options wo = {MR_IMG_COLOR, bits, 0};
        mr_image *back = round_trip(bits == 8 ? "f8.tif" : "f16.tiff", f, &wo, NULL);
        if (back) MR_CHECK_NEAR(max_integer_error(f, back, bits, 1), 0.0, 1e-6);
        mr_image_free(back);
    }
    mr_image_free(f);
}

MR_TEST(jpeg_round_trip) {
    /* JPEG is lossy and subsamples chroma: the F scaled 8x (one 8x8 block per cell) and compared at the
     * cell centres with a loose tolerance that still tells red from blue and every corner colour apart. */
    const int s = 8;
    mr_image *f = make_f(3, 1.0f), *big = NULL;
    MR_CHECK_OK(mr_image_create(F_W * s, F_H * s, 3, &big));
    for (int y = 0; y < F_H * s; y++)
        for (int x = 0; x < F_W * s; x++)
            memcpy(mr_image_at(big, x, y), mr_image_at(f, x / s, y / s), 3 * sizeof(float));
    mr_img_write_options wo = {MR_IMG_COLOR, 0, 95};
    mr_image *back = round_trip("f.jpg", big, &wo, NULL);
    if (back) {
        double worst = 0.0;
        for (int cy = 0; cy < F_H; cy++)
            for (int cx = 0; cx < F_W; cx++)
                for (int c = 0; c < 3; c++) {
                    double want = mr_linear_to_srgb(mr_image_at(f, cx, cy)[c]);
                    double got = mr_linear_to_srgb(mr_image_at(back, cx * s + s / 2, cy * s + s / 2)[c]);
                    worst = fmax(worst, fabs(want - got));
                }
        MR_CHECK_MSG(worst < 0.06, "largest display-value error %.4f", worst);
    }
    /* quality is honoured: quality 10 gives a smaller file than 95 */
    mr_img_write_options low = {MR_IMG_COLOR, 0, 10};
    MR_CHECK_OK(mr_img_write(mr_test_tmp_path("low.jpg"), big, &low));
    struct stat hi_st, lo_st;
    MR_CHECK(stat(mr_test_tmp_path("f.jpg"), &hi_st) == 0 && stat(mr_test_tmp_path("low.jpg"), &lo_st) == 0 &&
             lo_st.st_size < hi_st.st_size);
    mr_image_free(back);
    mr_image_free(big);
    mr_image_free(f);
}

MR_TEST(exr_float_round_trip_is_exact) {
    mr_image *f = make_f(3, 4.0f);
    /* values an integer format could not hold: negative, tiny, huge, subnormal, non-finite */
    float *p = mr_image_at(f, 2, 3);
    p[0] = -0.5f, p[1] = 1e-30f, p[2] = 3.0e38f;
    p = mr_image_at(f, 3, 3);
    p[0] = FLT_MIN / 4.0f, p[1] = 123.456f, p[2] = INFINITY;
    mr_image *back = round_trip("f32.exr", f, NULL, NULL);
    if (back) MR_CHECK(memcmp(back->pixels, f->pixels, mr_image_value_count(f) * sizeof(float)) == 0);
    /* NaN survives as NaN */
    mr_image_at(f, 4, 4)[1] = NAN;
    mr_image_free(back);
    back = round_trip("nan.exr", f, NULL, NULL);
    if (back) MR_CHECK(isnan(mr_image_at(back, 4, 4)[1]));
    mr_image_free(back);
    mr_image_free(f);
}

MR_TEST(exr_half_round_trip) {
    mr_image *f = make_f(4, 2.0f);
    mr_image_at(f, 2, 2)[0] = 0.1f;    /* not representable in half */
    mr_image_at(f, 2, 2)[1] = 1000.3f; /* half spacing at 1000 is 0.5 */
    mr_img_write_options wo = {MR_IMG_COLOR, 16, 0};
    mr_image *back = round_trip("f16.exr", f, &wo, NULL);
    if (back) {
        int bad = 0;
        for (size_t i = 0; i < mr_image_value_count(f); i++) {
            double v = f->pixels[i], got = back->pixels[i];
            /* round to nearest half: relative error at most 2^-11 */
            if (fabs(got - v) > fabs(v) * (1.0 / 2048.0)) bad++;
        }
        MR_CHECK_MSG(bad == 0, "%d values off by more than half precision", bad);
        MR_CHECK(mr_image_at(back, 0, 0)[0] == 0.5f && mr_image_at(back, 1, 0)[0] == 2.0f); /* exact in half */
        MR_CHECK(mr_image_at(back, 2, 2)[0] != 0.1f && fabs(mr_image_at(back, 2, 2)[0] - 0.1) < 0.1 / 2048.0);
        MR_CHECK(mr_image_at(back, 5, 0)[3] == 0.0f && mr_image_at(back, 5, 0)[0] == 1.5f); /* alpha 0 keeps colour */
    }
    mr_image_free(back);
    mr_image_free(f);
}

MR_TEST(hdr_round_trip) {
    mr_image *f = make_f(3, 5.0f);
    mr_image_at(f, 3, 2)[0] = 0.1f, mr_image_at(f, 3, 2)[1] = 0.1f, mr_image_at(f, 3, 2)[2] = 0.1f;
    mr_image *back = round_trip("f.hdr", f, NULL, NULL);
    if (back) {
        /* RGBE: 8-bit mantissas under a shared exponent, so the error is ~1% of the pixel's largest channel */
        double worst = 0.0;
        for (int y = 0; y < F_H; y++)
            for (int x = 0; x < F_W; x++) {
                const float *a = mr_image_at(f, x, y), *b = mr_image_at(back, x, y);
                double m = fmax(a[0], fmax(a[1], a[2]));
                for (int c = 0; c < 3; c++) worst = fmax(worst, fabs(a[c] - b[c]) / m);
            }
        MR_CHECK_MSG(worst <= 0.01, "largest relative RGBE error %.4f", worst);
        MR_CHECK(mr_image_at(back, 1, 0)[0] == 5.0f && mr_image_at(back, 1, 0)[2] == 0.0f);
    }
    mr_image_free(back);
    /* 1-channel images are stored as grey RGB; alpha cannot be stored */
    mr_image *g = make_f(1, 2.0f);
    MR_CHECK_OK(mr_img_write(mr_test_tmp_path("g.hdr"), g, NULL));
    mr_image *gb = NULL;
    MR_CHECK_OK(mr_img_read(mr_test_tmp_path("g.hdr"), NULL, &gb));
    if (gb) {
        MR_CHECK(gb->channels == 3);
        MR_CHECK(mr_image_at(gb, 1, 0)[0] == 2.0f && mr_image_at(gb, 1, 0)[2] == 2.0f);
        MR_CHECK_NEAR(mr_image_at(gb, 2, 1)[1], 0.25, 0.0025);
    }
    mr_image *rgba = make_f(4, 1.0f);
    MR_CHECK(mr_img_write(mr_test_tmp_path("a.hdr"), rgba, NULL) == MR_ERR_UNSUPPORTED);
    MR_CHECK(strstr(mr_last_error(), "alpha") != NULL);
    mr_image_free(rgba);
    mr_image_free(gb);
    mr_image_free(g);
    mr_image_free(f);
}

MR_TEST(one_channel_round_trips) {
    mr_image *g = make_f(1, 1.0f);
    mr_image *back = round_trip("g.png", g, NULL, NULL);
    if (back) MR_CHECK_NEAR(max_integer_error(g, back, 8, 1), 0.0, 1e-6);
    mr_image_free(back);
    mr_img_write_options w16 = {MR_IMG_DATA, 16, 0};
    mr_img_read_options rdata = {MR_IMG_DATA, 0, 0};
    back = round_trip("g16.tif", g, &w16, &rdata);
    if (back) MR_CHECK_NEAR(max_integer_error(g, back, 16, 0), 0.0, 1e-7);
    mr_image_free(back);
    back = round_trip("g.exr", g, NULL, NULL);
    if (back) MR_CHECK(memcmp(back->pixels, g->pixels, mr_image_value_count(g) * sizeof(float)) == 0);
    mr_image_free(back);
    /* the EXR channel is called Y (oiiotool reads our file independently of mr_img_read) */
    char cmd[700];
    snprintf(cmd, sizeof cmd, "iinfo -v '%s' | grep -q 'channel list: Y'", mr_test_tmp_path("g.exr"));
    MR_CHECK(run_quiet(cmd) == 0);
    back = round_trip("g.jpg", g, NULL, NULL);
    if (back) MR_CHECK_NEAR(mr_linear_to_srgb(mr_image_at(back, 1, 0)[0]), 1.0, 0.05);
    mr_image_free(back);
    mr_image_free(g);
}

MR_TEST(rgba_alpha_is_not_premultiplied) {
    mr_image *f = make_f(4, 1.0f);
    for (int bits = 8; bits <= 16; bits += 8) {
        mr_img_write_options wo = {MR_IMG_COLOR, bits, 0};
        mr_image *back = round_trip(bits == 8 ? "a8.png" : "a16.png", f, &wo, NULL);
        if (back) {
            MR_CHECK_NEAR(max_integer_error(f, back, bits, 1), 0.0, 1e-6);
            /* top-right has alpha 0 and colour (0.75, 0.125, 0.5): premultiplication would make it black */
            MR_CHECK_NEAR(mr_image_at(back, 5, 0)[0], 0.75, 0.005);
            MR_CHECK(mr_image_at(back, 5, 0)[3] == 0.0f);
            /* alpha is stored linearly (not sRGB-encoded): 0.5 -> code 128 (8-bit) */
            MR_CHECK_NEAR(mr_image_at(back, 0, 0)[3], bits == 8 ? 128.0 / 255.0 : 32768.0 / 65535.0, 1e-7);
        }
        mr_image_free(back);
    }
    mr_image *back = round_trip("a.tif", f, NULL, NULL);
    if (back) MR_CHECK_NEAR(max_integer_error(f, back, 8, 1), 0.0, 1e-6);
    mr_image_free(back);
    back = round_trip("a.exr", f, NULL, NULL);
    if (back) MR_CHECK(memcmp(back->pixels, f->pixels, mr_image_value_count(f) * sizeof(float)) == 0);
    mr_image_free(back);
    /* JPEG has no alpha */
    MR_CHECK(mr_img_write(mr_test_tmp_path("a.jpg"), f, NULL) == MR_ERR_UNSUPPORTED);
    mr_image_free(f);
}

MR_TEST(read_channel_conversions) {
    mr_image *g = make_f(1, 1.0f), *rgb = make_f(3, 1.0f), *rgba = make_f(4, 1.0f);
    MR_CHECK_OK(mr_img_write(mr_test_tmp_path("cg.png"), g, NULL));
    MR_CHECK_OK(mr_img_write(mr_test_tmp_path("crgb.png"), rgb, NULL));
    MR_CHECK_OK(mr_img_write(mr_test_tmp_path("crgba.exr"), rgba, NULL));
    mr_image *img = NULL;
    mr_img_read_options ro = {MR_IMG_COLOR, 3, 0};
    MR_CHECK_OK(mr_img_read(mr_test_tmp_path("cg.png"), &ro, &img)); /* grey -> RGB broadcast */
    if (img) {
        MR_CHECK(img->channels == 3);
        const float *p = mr_image_at(img, 5, 4);
        MR_CHECK(p[0] == p[1] && p[1] == p[2] && fabs(p[0] - 0.5) < 0.005);
    }
    mr_image_free(img);
    img = NULL;
    ro.channels = 4; /* grey -> RGBA, alpha 1 */
    MR_CHECK_OK(mr_img_read(mr_test_tmp_path("cg.png"), &ro, &img));
    if (img) MR_CHECK(img->channels == 4 && mr_image_at(img, 2, 2)[3] == 1.0f);
    mr_image_free(img);
    img = NULL;
    ro.channels = 3; /* RGBA -> RGB drops alpha */
    MR_CHECK_OK(mr_img_read(mr_test_tmp_path("crgba.exr"), &ro, &img));
    if (img) MR_CHECK(img->channels == 3 && mr_image_at(img, 5, 0)[0] == 0.75f);
    mr_image_free(img);
    static mr_image sentinel_image; /* *out must be left untouched on failure */
    mr_image *const sentinel = &sentinel_image;
    img = sentinel;
    ro.channels = 1; /* RGB -> luminance is refused */
    MR_CHECK(mr_img_read(mr_test_tmp_path("crgb.png"), &ro, &img) == MR_ERR_FORMAT);
    MR_CHECK(img == sentinel);
    MR_CHECK(strstr(mr_last_error(), "crgb.png") != NULL);
    ro.channels = 2;
    MR_CHECK(mr_img_read(mr_test_tmp_path("crgb.png"), &ro, &img) == MR_ERR_INVALID_ARG);
    MR_CHECK(img == sentinel);
    /* A grey+alpha PNG written by oiiotool (libpng) reads as RGBA, or grey with channels = 1. */
    char cmd[700];
    /* (--attrib keeps oiiotool from un-premultiplying on write: the file holds codes 128 and 64) */
    snprintf(cmd, sizeof cmd,
             "oiiotool --create 4x3 2 --fill:color=0.5,0.25 4x3+0+0 --attrib oiio:UnassociatedAlpha 1 -d uint8 "
             "-o '%s'",
             mr_test_tmp_path("ga.png"));
    MR_CHECK(run_quiet(cmd) == 0);
    img = NULL;
    mr_img_read_options data = {MR_IMG_DATA, 0, 0};
    MR_CHECK_OK(mr_img_read(mr_test_tmp_path("ga.png"), &data, &img));
    if (img) {
        const float *p = mr_image_at(img, 3, 2);
        MR_CHECK(img->channels == 4);
        MR_CHECK_NEAR(p[0], 128.0 / 255.0, 1e-7);
        MR_CHECK(p[0] == p[1] && p[1] == p[2]);
        MR_CHECK_NEAR(p[3], 64.0 / 255.0, 1e-7); /* unassociated: grey is not multiplied by alpha */
    }
    mr_image_free(img);
    img = NULL;
    data.channels = 1;
    MR_CHECK_OK(mr_img_read(mr_test_tmp_path("ga.png"), &data, &img));
    if (img) MR_CHECK(img->channels == 1 && fabs(img->pixels[0] - 128.0 / 255.0) < 1e-7);
    mr_image_free(img);
    mr_image_free(g);
    mr_image_free(rgb);
    mr_image_free(rgba);
}

/* The PNG reader (libpng, png_io.c) returns what the OpenImageIO reader returns for the same file, bit for bit:
 * layouts written by oiiotool (grey, grey + alpha, RGB, RGBA at 8 and 16 bits), an Adam7-interlaced RGBA file
 * written here with libpng, and real textures of ../shared/assets (RGB and palette PNGs up to 2048^2). */
static void same_raw(const char *path) {
    mr_io_raw a = {0, 0, 0, 0, 0, NULL}, b = {0, 0, 0, 0, 0, NULL};
    MR_CHECK_OK(mr_io_png_read(path, 16384, &a));
    MR_CHECK_OK(mr_io_oiio_read(path, 16384, &b));
    if (a.pixels != NULL && b.pixels != NULL) {
        MR_CHECK_MSG(a.width == b.width && a.height == b.height && a.channels == b.channels && a.bits == b.bits &&
                         a.encoded == b.encoded,
                     "%s: libpng %dx%dx%d %d bits, OpenImageIO %dx%dx%d %d bits", path, a.width, a.height,
                     a.channels, a.bits, b.width, b.height, b.channels, b.bits);
        size_t n = (size_t)a.width * (size_t)a.height * (size_t)a.channels, differ = 0;
        if (a.width == b.width && a.height == b.height && a.channels == b.channels)
            for (size_t i = 0; i < n; i++) differ += memcmp(&a.pixels[i], &b.pixels[i], sizeof(float)) != 0;
        MR_CHECK_MSG(differ == 0, "%s: %zu of %zu values differ", path, differ, n);
    }
    free(a.pixels);
    free(b.pixels);
}

MR_TEST(png_reader_matches_openimageio) {
    static const char *const layouts[][2] = {
        {"grey8.png", "--ch R -d uint8"},         {"ga8.png", "--ch R,A -d uint8"},
        {"rgb8.png", "--ch R,G,B -d uint8"},      {"rgba8.png", "-d uint8"},
        {"grey16.png", "--ch R -d uint16"},       {"rgba16.png", "-d uint16"},
    };
    for (size_t k = 0; k < sizeof layouts / sizeof layouts[0]; k++) {
        char cmd[1024];
        snprintf(cmd, sizeof cmd, "oiiotool --pattern fill:topleft=0.1,0.9,0.3,1:topright=0.8,0.2,0.6,0.5:"
                 "bottomleft=0,0.5,1,0.25:bottomright=1,1,0,0 37x23 4 --attrib oiio:UnassociatedAlpha 1 %s -o '%s'",
                 layouts[k][1], mr_test_tmp_path(layouts[k][0]));
        MR_CHECK_MSG(run_quiet(cmd) == 0, "%s", cmd);
        same_raw(mr_test_tmp_path(layouts[k][0]));
    }
    // Adam7 (oiiotool cannot write it): 16-bit RGBA rows of a ramp, interlaced by libpng itself.
    FILE *f = fopen(mr_test_tmp_path("adam7.png"), "wb");
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, NULL, NULL, NULL);
    png_infop info = png ? png_create_info_struct(png) : NULL;
    MR_CHECK(f != NULL && png != NULL && info != NULL);
    if (f != NULL && png != NULL && info != NULL && setjmp(png_jmpbuf(png)) == 0) {
        enum { W = 29, H = 19 };
        static unsigned char rows[H][W * 8];
        png_bytep pointers[H];
        for (int y = 0; y < H; y++) {
            for (int b = 0; b < W * 8; b++) rows[y][b] = (unsigned char)(y * 37 + b * 11);
            pointers[y] = rows[y];
        }
        png_init_io(png, f);
        png_set_IHDR(png, info, W, H, 16, PNG_COLOR_TYPE_RGB_ALPHA, PNG_INTERLACE_ADAM7, PNG_COMPRESSION_TYPE_DEFAULT,
                     PNG_FILTER_TYPE_DEFAULT);
        png_write_info(png, info);
        png_set_interlace_handling(png);
        png_write_image(png, pointers);
        png_write_end(png, NULL);
    }
    png_destroy_write_struct(png ? &png : NULL, info ? &info : NULL);
    if (f != NULL) fclose(f);
    same_raw(mr_test_tmp_path("adam7.png"));

    const char *shared = getenv("MR_SHARED");
    char root[1024];
    snprintf(root, sizeof root, "%s/assets", shared ? shared : "../shared");
    static const char *const assets[] = {
        "specgloss/Duck-pbrSpecularGlossiness/glTF-pbrSpecularGlossiness/DuckCM.png", // palette
        "specgloss/CesiumMilkTruck-pbrSpecularGlossiness/glTF-pbrSpecularGlossiness/CesiumMilkTruck.png",
        "metalrough/TextureSettingsTest/glTF/CheckAndX.png",
    };
    for (size_t k = 0; k < sizeof assets / sizeof assets[0]; k++) {
        char path[1400];
        snprintf(path, sizeof path, "%s/%s", root, assets[k]);
        same_raw(path);
    }
}

/* ---- reading from memory ------------------------------------------------------------------------------ */

/* The image mr_img_read_memory decodes from the bytes of `path` equals what mr_img_read_stored reads from the file
 * itself, bit for bit (size, channels, every value, the stored description), under the options `ro`. */
static void same_as_file(const char *path, const mr_img_read_options *ro) {
    size_t size = 0;
    char *bytes = mr_test_read_file(path, &size);
    MR_CHECK_MSG(bytes != NULL && size > 0, "%s: cannot read it", path);
    if (bytes == NULL) return;
    mr_image *from_file = NULL, *from_memory = NULL;
    mr_img_stored a = {-1, MR_IMG_COLOR}, b = {-2, MR_IMG_DATA};
    MR_CHECK_OK(mr_img_read_stored(path, ro, &from_file, &a));
    MR_CHECK_OK(mr_img_read_memory(bytes, size, "test bytes", ro, &from_memory, &b));
    MR_CHECK_MSG(same_shape(from_file, from_memory), "%s: file %dx%dx%d, memory %dx%dx%d", path,
                 from_file ? from_file->width : 0, from_file ? from_file->height : 0,
                 from_file ? from_file->channels : 0, from_memory ? from_memory->width : 0,
                 from_memory ? from_memory->height : 0, from_memory ? from_memory->channels : 0);
    if (same_shape(from_file, from_memory))
        MR_CHECK_MSG(memcmp(from_file->pixels, from_memory->pixels, mr_image_value_count(from_file) * sizeof(float)) ==
                         0, "%s: the values differ", path);
    MR_CHECK_MSG(a.bits == b.bits && a.encoding == b.encoding, "%s: stored %d bits/%d vs %d bits/%d", path, a.bits,
                 (int)a.encoding, b.bits, (int)b.encoding);
    mr_image_free(from_file);
    mr_image_free(from_memory);
    free(bytes);
}

MR_TEST(read_memory_matches_the_file) {
    mr_image *rgb = make_f(3, 1.0f), *rgba = make_f(4, 1.0f), *grey = make_f(1, 1.0f), *bright = make_f(3, 4.0f);
    struct {
        const char *name;
        const mr_image *image;
        int bits;
    } files[] = {
        {"mem8.png", rgb, 8},   {"mem16.png", rgb, 16},  {"mem16a.png", rgba, 16}, {"memg8.png", grey, 8},
        {"mem.jpg", rgb, 8},    {"memg.jpg", grey, 8},   {"mem16.tif", rgba, 16},  {"mem.exr", bright, 32},
        {"memh.exr", rgba, 16}, {"mem.hdr", bright, 0},
    };
    const mr_img_read_options as_data = {MR_IMG_DATA, 4, 0}, as_rgb = {MR_IMG_COLOR, 3, 0};
    for (size_t k = 0; k < sizeof files / sizeof files[0]; k++) {
        mr_img_write_options wo = {MR_IMG_COLOR, files[k].bits, 0};
        const char *path = mr_test_tmp_path(files[k].name);
        MR_CHECK_OK(mr_img_write(path, files[k].image, &wo));
        same_as_file(path, NULL);
        same_as_file(path, &as_data);
        same_as_file(path, &as_rgb);
        // The same bytes under another format's extension: read by their signature's reader all the same.
        size_t size = 0;
        char *bytes = mr_test_read_file(path, &size);
        const char *misnamed = mr_test_tmp_path(strstr(files[k].name, ".png") ? "misnamed.exr" : "misnamed.png");
        MR_CHECK(bytes != NULL && mr_test_write_file(misnamed, bytes, size));
        same_as_file(misnamed, NULL);
        free(bytes);
    }
    /* Real textures: palette and RGB PNGs of ../shared/assets (the Duck's is 512^2, CheckAndX has an sRGB chunk). */
    const char *shared = getenv("MR_SHARED");
    char path[1400];
    snprintf(path, sizeof path, "%s/assets/specgloss/Duck-pbrSpecularGlossiness/glTF-pbrSpecularGlossiness/DuckCM.png",
             shared ? shared : "../shared");
    same_as_file(path, NULL);
    snprintf(path, sizeof path, "%s/assets/metalrough/TextureSettingsTest/glTF/CheckAndX.png",
             shared ? shared : "../shared");
    same_as_file(path, NULL);
    mr_image_free(rgb);
    mr_image_free(rgba);
    mr_image_free(grey);
    mr_image_free(bright);
}

/* A failed read from memory: `want`, a message naming `name` and containing `words` (if not NULL), no image. */
static void memory_fails(const void *bytes, size_t size, const char *name, const mr_img_read_options *ro,
                         mr_status want, const char *words) {
    mr_image *img = NULL;
    mr_status got = mr_img_read_memory(bytes, size, name, ro, &img, NULL);
    MR_CHECK_MSG(got == want, "%s: %s, expected %s (%s)", name, mr_status_str(got), mr_status_str(want),
                 mr_last_error());
    MR_CHECK_MSG(strstr(mr_last_error(), name) != NULL, "%s: message '%s'", name, mr_last_error());
    if (words != NULL) MR_CHECK_MSG(strstr(mr_last_error(), words) != NULL, "%s: message '%s'", name, mr_last_error());
    MR_CHECK(img == NULL);
    mr_image_free(img);
}

MR_TEST(read_memory_bad_bytes_fail_clearly) {
    mr_image *noise = make_noise(64, 64, 777);
    MR_CHECK(noise != NULL);
    static unsigned char bytes[1 << 16];
    /* garbage: text, random bytes, an empty buffer */
    const char text[] = "this is not an image at all\n";
    memory_fails(text, sizeof text - 1, "glTF 'x.gltf': image 3", NULL, MR_ERR_FORMAT, "not an image");
    unsigned s = 4711;
    for (size_t i = 0; i < 3000; i++) {
        s = s * 1103515245u + 12345u;
        bytes[i] = (unsigned char)(s >> 16);
    }
    memory_fails(bytes, 3000, "random bytes", NULL, MR_ERR_FORMAT, NULL);
    memory_fails(text, 0, "no bytes", NULL, MR_ERR_FORMAT, NULL);
    /* truncated: every format cut in half, and a PNG with a flipped bit (its CRC no longer matches) */
    const char *formats[] = {"png", "jpg", "exr", "hdr", "tif"};
    for (int f = 0; f < 5; f++) {
        char name[64];
        snprintf(name, sizeof name, "memcut.%s", formats[f]);
        MR_CHECK_OK(mr_img_write(mr_test_tmp_path(name), noise, NULL));
        long n = read_file(mr_test_tmp_path(name), bytes, sizeof bytes);
        MR_CHECK(n > 1000 && n < (long)sizeof bytes);
        snprintf(name, sizeof name, "half a %s", formats[f]);
        memory_fails(bytes, (size_t)n / 2, name, NULL, MR_ERR_FORMAT, f == 0 ? "truncated PNG" : NULL);
        if (f == 0) {
            bytes[n / 2] ^= 0x10;
            memory_fails(bytes, (size_t)n, "a flipped PNG", NULL, MR_ERR_FORMAT, "CRC");
            bytes[n / 2] ^= 0x10;
            /* the checks of mr_img_read_stored: size, channels, options */
            mr_img_read_options small = {MR_IMG_COLOR, 0, 32}, grey = {MR_IMG_COLOR, 1, 0}, bad = {MR_IMG_COLOR, 2, 0};
            memory_fails(bytes, (size_t)n, "a large PNG", &small, MR_ERR_FORMAT, "64x64");
            memory_fails(bytes, (size_t)n, "an RGB PNG", &grey, MR_ERR_FORMAT, "1 channel");
            memory_fails(bytes, (size_t)n, "two channels", &bad, MR_ERR_INVALID_ARG, NULL);
        }
    }
    /* arguments */
    mr_image *img = NULL;
    MR_CHECK(mr_img_read_memory(NULL, 10, "x", NULL, &img, NULL) == MR_ERR_INVALID_ARG && img == NULL);
    MR_CHECK(mr_img_read_memory(text, 4, "x", NULL, NULL, NULL) == MR_ERR_INVALID_ARG);
    MR_CHECK(mr_img_read_memory(text, 4, NULL, NULL, &img, NULL) == MR_ERR_FORMAT && img == NULL);
    MR_CHECK(strstr(mr_last_error(), "image in memory") != NULL);
    MR_CHECK(count_temporaries() == 0);
    mr_image_free(noise);
}

/* ---- independent cross-checks with oiiotool ----------------------------------------------------------- */

/* oiiotool arguments drawing make_f(3, scale) with --fill. */
static void f_fill_args(char *out, size_t cap, float scale) {
    snprintf(out, cap,
             "--create %dx%d 3 --fill:color=0,0,%g %dx%d+0+0 "
             "--fill:color=%g,0,0 1x5+1+0 --fill:color=%g,0,0 3x1+2+0 --fill:color=%g,0,0 2x1+2+2 "
             "--fill:color=%g,%g,%g 1x1+0+0 --fill:color=%g,%g,%g 1x1+5+0 "
             "--fill:color=%g,%g,%g 1x1+0+4 --fill:color=%g,%g,%g 1x1+5+4",
             F_W, F_H, scale, F_W, F_H, scale, scale, scale, 0.25 * scale, 0.5 * scale, 0.75 * scale,
             0.75 * scale, 0.125 * scale, 0.5 * scale, 0.0625 * scale, 0.875 * scale, 0.25 * scale, 0.5 * scale,
             0.375 * scale, 0.0 * scale);
}

MR_TEST(reads_files_written_by_oiiotool) {
    mr_image *f = make_f(3, 2.0f);
    char args[1024], cmd[2048];
    f_fill_args(args, sizeof args, 2.0f);
    /* EXR written by OpenImageIO through the OpenEXR C++ library (not by our Core writer) */
    const char *types[2] = {"float", "half"};
    const char *names[2] = {"oiio32.exr", "oiio16.exr"};
    for (int k = 0; k < 2; k++) {
        snprintf(cmd, sizeof cmd, "oiiotool %s -d %s -o '%s'", args, types[k], mr_test_tmp_path(names[k]));
        MR_CHECK_MSG(run_quiet(cmd) == 0, "%s", cmd);
        mr_image *img = NULL;
        MR_CHECK_OK(mr_img_read(mr_test_tmp_path(names[k]), NULL, &img));
        if (img) MR_CHECK_MSG(same_shape(f, img) && memcmp(img->pixels, f->pixels, 6 * 5 * 3 * sizeof(float)) == 0,
                              "%s differs from the in-memory F", names[k]);
        mr_image_free(img);
    }
    mr_image_free(f);
    /* PNG written by oiiotool (libpng): codes round(v * 255), decoded from sRGB by default */
    f = make_f(3, 1.0f);
    f_fill_args(args, sizeof args, 1.0f);
    snprintf(cmd, sizeof cmd, "oiiotool %s -d uint8 -o '%s'", args, mr_test_tmp_path("oiio.png"));
    MR_CHECK(run_quiet(cmd) == 0);
    mr_image *img = NULL;
    MR_CHECK_OK(mr_img_read(mr_test_tmp_path("oiio.png"), NULL, &img));
    if (img && same_shape(f, img)) {
        double worst = 0.0;
        for (size_t i = 0; i < mr_image_value_count(f); i++) {
            double code = floor(f->pixels[i] * 255.0 + 0.5); /* oiiotool quantised the values as given */
            worst = fmax(worst, fabs(img->pixels[i] - mr_srgb_to_linear((float)(code / 255.0))));
        }
        MR_CHECK_NEAR(worst, 0.0, 1e-7);
    }
    mr_image_free(img);
    mr_image_free(f);
}

MR_TEST(oiiotool_reads_our_exr) {
    /* Our Core-written EXR dumped by oiiotool: the exact values, in the right place. */
    mr_image *f = make_f(4, 3.0f);
    MR_CHECK_OK(mr_img_write(mr_test_tmp_path("dump.exr"), f, NULL));
    char cmd[700];
    snprintf(cmd, sizeof cmd, "oiiotool --dumpdata '%s' 2>&1", mr_test_tmp_path("dump.exr"));
    FILE *p = popen(cmd, "r");
    MR_CHECK(p != NULL);
    int seen = 0, bad = 0;
    char line[512];
    while (p != NULL && fgets(line, sizeof line, p) != NULL) {
        int x, y;
        float v[4];
        if (sscanf(line, " Pixel (%d, %d): %f %f %f %f", &x, &y, &v[0], &v[1], &v[2], &v[3]) != 6) continue;
        seen++;
        if (x < 0 || x >= F_W || y < 0 || y >= F_H) {
            bad++;
            continue;
        }
        const float *want = mr_image_at(f, x, y);
        for (int c = 0; c < 4; c++)
            if (fabs(v[c] - want[c]) > 1e-6) bad++;
    }
    if (p != NULL) MR_CHECK(pclose(p) == 0);
    MR_CHECK_MSG(seen == F_W * F_H && bad == 0, "%d pixels parsed, %d mismatches", seen, bad);
    mr_image_free(f);
}

/* ---- atomicity ---------------------------------------------------------------------------------------- */

MR_TEST(write_into_missing_directory_fails_cleanly) {
    mr_image *f = make_f(3, 1.0f);
    const char *exts[3] = {"png", "exr", "hdr"};
    for (int k = 0; k < 3; k++) {
        char path[600];
        snprintf(path, sizeof path, "%s/f.%s", mr_test_tmp_path("no/such/dir"), exts[k]);
        MR_CHECK(mr_img_write(path, f, NULL) == MR_ERR_IO);
        MR_CHECK_MSG(strstr(mr_last_error(), path) != NULL, "message '%s' does not name the file", mr_last_error());
        MR_CHECK(!file_exists(mr_test_tmp_path("no")));
    }
    MR_CHECK(count_temporaries() == 0);
    mr_image_free(f);
}

MR_TEST(failed_write_leaves_target_untouched) {
    mr_image *f = make_f(3, 1.0f);
    unsigned char before[65536], after[65536];
    char target[600];
    snprintf(target, sizeof target, "%s", mr_test_tmp_path("keep.jpg"));
    MR_CHECK_OK(mr_img_write(target, f, NULL));
    long n_before = read_file(target, before, sizeof before);
    MR_CHECK(n_before > 0);

    /* 1. rejected before anything is written */
    mr_img_write_options bad_bits = {MR_IMG_COLOR, 16, 0};
    MR_CHECK(mr_img_write(target, f, &bad_bits) == MR_ERR_INVALID_ARG);
    /* 2. a size the format cannot hold is refused up front (libjpeg would otherwise exit() the process) */
    mr_image *wide = NULL;
    MR_CHECK_OK(mr_image_create(70000, 1, 3, &wide));
    MR_CHECK(mr_img_write(target, wide, NULL) == MR_ERR_UNSUPPORTED);
    MR_CHECK(strstr(mr_last_error(), "keep.jpg") != NULL);
    long n_after = read_file(target, after, sizeof after);
    MR_CHECK(n_after == n_before && memcmp(before, after, (size_t)n_before) == 0);
    MR_CHECK(count_temporaries() == 0);

    /* 3. the rename fails after a complete temporary file: the target is a directory */
    const char *dirs[3] = {"isdir.png", "isdir.exr", "isdir.tif"};
    for (int k = 0; k < 3; k++) {
        MR_CHECK(mkdir(mr_test_tmp_path(dirs[k]), 0755) == 0);
        MR_CHECK(mr_img_write(mr_test_tmp_path(dirs[k]), f, NULL) == MR_ERR_IO);
        MR_CHECK(strstr(mr_last_error(), dirs[k]) != NULL);
        struct stat st;
        MR_CHECK(stat(mr_test_tmp_path(dirs[k]), &st) == 0 && S_ISDIR(st.st_mode));
    }
    MR_CHECK(count_temporaries() == 0);

    /* 4. a successful write replaces the old content */
    mr_image *g = make_f(3, 0.5f);
    MR_CHECK_OK(mr_img_write(target, g, NULL));
    n_after = read_file(target, after, sizeof after);
    MR_CHECK(n_after > 0 && (n_after != n_before || memcmp(before, after, (size_t)n_before) != 0));
    MR_CHECK(count_temporaries() == 0);
    mr_image_free(g);
    mr_image_free(wide);
    mr_image_free(f);
}

MR_TEST(full_disk_fails_cleanly) {
    /* A file-size limit makes every write past 4 KiB fail with EFBIG, as a full disk would (SIGXFSZ ignored).
     * Each format must report MR_ERR_IO naming the file, remove its temporary, and keep the old target. */
    mr_image *noise = make_noise(128, 128, 777);
    MR_CHECK(noise != NULL);
    mr_image *f = make_f(3, 1.0f);
    const char *names[5] = {"full.png", "full.tif", "full.jpg", "full.hdr", "full.exr"};
    unsigned char before[8192], after[8192];
    long sizes[5];
    for (int k = 0; k < 5; k++) {
        MR_CHECK_OK(mr_img_write(mr_test_tmp_path(names[k]), f, NULL)); /* small: the old content */
        sizes[k] = read_file(mr_test_tmp_path(names[k]), before, sizeof before);
        MR_CHECK(sizes[k] > 0 && sizes[k] < 4096);
    }
    void (*old_handler)(int) = signal(SIGXFSZ, SIG_IGN);
    struct rlimit old_limit, limit;
    MR_CHECK(getrlimit(RLIMIT_FSIZE, &old_limit) == 0);
    limit = old_limit;
    limit.rlim_cur = 4096;
    MR_CHECK(setrlimit(RLIMIT_FSIZE, &limit) == 0);
    mr_status results[5];
    char messages[5][256];
    for (int k = 0; k < 5; k++) {
        results[k] = mr_img_write(mr_test_tmp_path(names[k]), noise, NULL);
        snprintf(messages[k], sizeof messages[k], "%s", mr_last_error());
    }
    MR_CHECK(setrlimit(RLIMIT_FSIZE, &old_limit) == 0);
    signal(SIGXFSZ, old_handler);
    for (int k = 0; k < 5; k++) {
        MR_CHECK_MSG(results[k] == MR_ERR_IO, "%s: %s", names[k], mr_status_str(results[k]));
        MR_CHECK_MSG(strstr(messages[k], names[k]) != NULL, "message '%s'", messages[k]);
        /* the old file is intact (same size, and still decodes to the F) */
        MR_CHECK(read_file(mr_test_tmp_path(names[k]), after, sizeof after) == sizes[k]);
        mr_image *back = NULL;
        MR_CHECK_OK(mr_img_read(mr_test_tmp_path(names[k]), NULL, &back));
        MR_CHECK(back != NULL && back->width == F_W && back->height == F_H);
        mr_image_free(back);
    }
    MR_CHECK(count_temporaries() == 0);
    mr_image_free(f);
    mr_image_free(noise);
}

MR_TEST(written_files_have_ordinary_permissions) {
    /* The temporary file is created 0666 & ~umask like any output, not 0600 as mkstemp would. */
    mode_t mask = umask(022);
    umask(mask);
    mr_image *f = make_f(3, 1.0f);
    const char *names[2] = {"mode.png", "mode.exr"};
    for (int k = 0; k < 2; k++) {
        MR_CHECK_OK(mr_img_write(mr_test_tmp_path(names[k]), f, NULL));
        struct stat st;
        MR_CHECK(stat(mr_test_tmp_path(names[k]), &st) == 0 && (st.st_mode & 0777) == (0666 & ~mask));
    }
    mr_image_free(f);
}

MR_TEST(concurrent_writes_and_reads) {
    /* Different files from several threads at once: temporary names must not collide. */
    mr_image *f = make_f(4, 1.0f);
    int failures = 0;
#pragma omp parallel for reduction(+ : failures)
    for (int i = 0; i < 16; i++) {
        char name[32];
        snprintf(name, sizeof name, "par%d.%s", i, i % 2 ? "exr" : "png");
        char path[600];
        snprintf(path, sizeof path, "%s/%s", mr_test_scratch_dir(), name);
        mr_image *back = NULL;
        if (mr_img_write(path, f, NULL) != MR_OK || mr_img_read(path, NULL, &back) != MR_OK || back->channels != 4)
            failures++;
        mr_image_free(back);
    }
    MR_CHECK(failures == 0);
    MR_CHECK(count_temporaries() == 0);
    mr_image_free(f);
}

/* ---- bad inputs --------------------------------------------------------------------------------------- */

MR_TEST(bad_inputs_give_clear_errors) {
    mr_image *img = NULL;
    /* missing file */
    const char *missing = mr_test_tmp_path("missing.png");
    MR_CHECK(mr_img_read(missing, NULL, &img) == MR_ERR_IO);
    MR_CHECK(strstr(mr_last_error(), missing) != NULL && strstr(mr_last_error(), "No such file") != NULL);
    MR_CHECK(img == NULL);
    /* a directory */
    MR_CHECK(mr_img_read(mr_test_scratch_dir(), NULL, &img) == MR_ERR_IO);
    /* a text file named .png */
    const char *text = mr_test_tmp_path("text.png");
    const char words[] = "this is not an image\n";
    MR_CHECK(mr_test_write_file(text, words, sizeof words - 1));
    MR_CHECK(mr_img_read(text, NULL, &img) == MR_ERR_FORMAT);
    MR_CHECK(strstr(mr_last_error(), text) != NULL);
    MR_CHECK(img == NULL);
    /* an empty file */
    MR_CHECK(mr_test_write_file(mr_test_tmp_path("empty.exr"), "", 0));
    MR_CHECK(mr_img_read(mr_test_tmp_path("empty.exr"), NULL, &img) == MR_ERR_FORMAT);
    /* a truncated PNG: a noisy 64x64 image cut in half */
    mr_image *noise = make_noise(64, 64, 12345);
    MR_CHECK(noise != NULL);
    char full[600], cut[600];
    snprintf(full, sizeof full, "%s", mr_test_tmp_path("whole.png"));
    snprintf(cut, sizeof cut, "%s", mr_test_tmp_path("cut.png"));
    MR_CHECK_OK(mr_img_write(full, noise, NULL));
    static unsigned char bytes[1 << 16];
    long n = read_file(full, bytes, sizeof bytes);
    MR_CHECK(n > 1000 && n < (long)sizeof bytes);
    MR_CHECK(mr_test_write_file(cut, bytes, (size_t)n / 2));
    MR_CHECK(mr_img_read(cut, NULL, &img) == MR_ERR_FORMAT);
    MR_CHECK_MSG(strstr(mr_last_error(), cut) != NULL && strstr(mr_last_error(), "truncated") != NULL, "%s",
                 mr_last_error());
    MR_CHECK(img == NULL);
    /* a PNG with one flipped bit inside its image data: the chunk CRC no longer matches */
    bytes[n / 2] ^= 0x10;
    MR_CHECK(mr_test_write_file(mr_test_tmp_path("flipped.png"), bytes, (size_t)n));
    bytes[n / 2] ^= 0x10;
    MR_CHECK(mr_img_read(mr_test_tmp_path("flipped.png"), NULL, &img) == MR_ERR_FORMAT);
    MR_CHECK_MSG(strstr(mr_last_error(), "flipped.png") != NULL && strstr(mr_last_error(), "CRC") != NULL, "%s",
                 mr_last_error());
    /* a PNG whose image data is not zlib data but carries a correct CRC (so only the decoder, libpng through
     * png_io.c, can tell): a clear error naming the file, no image */
    long idat = -1;
    for (long i = 8; i + 8 <= n; i++)
        if (memcmp(bytes + i, "IDAT", 4) == 0) {
            idat = i;
            break;
        }
    MR_CHECK(idat > 0);
    if (idat > 0) {
        const uint32_t length = (uint32_t)bytes[idat - 4] << 24 | (uint32_t)bytes[idat - 3] << 16 |
                                (uint32_t)bytes[idat - 2] << 8 | bytes[idat - 1];
        memset(bytes + idat + 4, 0xff, length); // 0xff 0xff is no zlib header
        uint32_t crc = 0xffffffffu; // CRC-32 of the type and data (ISO/IEC 15948, Annex D), bit by bit
        for (uint32_t k = 0; k < length + 4; k++) {
            crc ^= bytes[idat + k];
            for (int b = 0; b < 8; b++) crc = crc & 1 ? (crc >> 1) ^ 0xedb88320u : crc >> 1;
        }
        crc ^= 0xffffffffu;
        for (int b = 0; b < 4; b++) bytes[idat + 4 + length + b] = (unsigned char)(crc >> (24 - 8 * b));
        MR_CHECK(mr_test_write_file(mr_test_tmp_path("undecodable.png"), bytes, (size_t)n));
        img = NULL;
        MR_CHECK(mr_img_read(mr_test_tmp_path("undecodable.png"), NULL, &img) == MR_ERR_FORMAT);
        MR_CHECK_MSG(strstr(mr_last_error(), "undecodable.png") != NULL &&
                         strstr(mr_last_error(), "cannot decode PNG") != NULL,
                     "%s", mr_last_error());
        MR_CHECK(img == NULL);
    }
    /* a truncated JPEG: libjpeg only warns ("Premature end of JPEG file") and fills the rest with grey */
    MR_CHECK_OK(mr_img_write(mr_test_tmp_path("whole.jpg"), noise, NULL));
    n = read_file(mr_test_tmp_path("whole.jpg"), bytes, sizeof bytes);
    MR_CHECK(n > 1000 && n < (long)sizeof bytes);
    MR_CHECK(mr_test_write_file(mr_test_tmp_path("cut.jpg"), bytes, (size_t)n / 2));
    MR_CHECK(mr_img_read(mr_test_tmp_path("cut.jpg"), NULL, &img) == MR_ERR_FORMAT);
    MR_CHECK_MSG(strstr(mr_last_error(), "cut.jpg") != NULL, "%s", mr_last_error());
    /* truncated EXR and HDR */
    const char *others[2] = {"whole.exr", "whole.hdr"};
    for (int k = 0; k < 2; k++) {
        MR_CHECK_OK(mr_img_write(mr_test_tmp_path(others[k]), noise, NULL));
        n = read_file(mr_test_tmp_path(others[k]), bytes, sizeof bytes);
        MR_CHECK(n > 1000 && n < (long)sizeof bytes);
        char name[32];
        snprintf(name, sizeof name, "cut_%s", others[k] + 6);
        MR_CHECK(mr_test_write_file(mr_test_tmp_path(name), bytes, (size_t)n / 2));
        MR_CHECK(mr_img_read(mr_test_tmp_path(name), NULL, &img) == MR_ERR_FORMAT);
        MR_CHECK_MSG(strstr(mr_last_error(), name) != NULL, "%s", mr_last_error());
    }
    MR_CHECK(img == NULL);
    /* too large: checked from the header, before decoding */
    mr_img_read_options small = {MR_IMG_COLOR, 0, 32};
    MR_CHECK(mr_img_read(full, &small, &img) == MR_ERR_FORMAT);
    MR_CHECK(strstr(mr_last_error(), full) != NULL && strstr(mr_last_error(), "64x64") != NULL &&
             strstr(mr_last_error(), "32") != NULL);
    MR_CHECK(img == NULL);
    small.max_dimension = 64; /* the limit itself is accepted */
    MR_CHECK_OK(mr_img_read(full, &small, &img));
    mr_image_free(img);
    img = NULL;
    small.max_dimension = -1;
    MR_CHECK(mr_img_read(full, &small, &img) == MR_ERR_INVALID_ARG);
    /* writing: unknown extension, bad options */
    MR_CHECK(mr_img_write(mr_test_tmp_path("f.bmpx"), noise, NULL) == MR_ERR_INVALID_ARG);
    MR_CHECK(strstr(mr_last_error(), ".bmpx") != NULL);
    MR_CHECK(mr_img_write(mr_test_tmp_path("noext"), noise, NULL) == MR_ERR_INVALID_ARG);
    mr_img_write_options wo = {MR_IMG_COLOR, 12, 0};
    MR_CHECK(mr_img_write(mr_test_tmp_path("bad.png"), noise, &wo) == MR_ERR_INVALID_ARG);
    wo.bits = 8;
    MR_CHECK(mr_img_write(mr_test_tmp_path("bad.exr"), noise, &wo) == MR_ERR_INVALID_ARG);
    wo.bits = 0;
    wo.jpeg_quality = 101;
    MR_CHECK(mr_img_write(mr_test_tmp_path("bad.jpg"), noise, &wo) == MR_ERR_INVALID_ARG);
    wo.jpeg_quality = 0;
    wo.encoding = (mr_img_encoding)7;
    MR_CHECK(mr_img_write(mr_test_tmp_path("bad.tif"), noise, &wo) == MR_ERR_INVALID_ARG);
    MR_CHECK(!file_exists(mr_test_tmp_path("bad.png")) && !file_exists(mr_test_tmp_path("bad.exr")) &&
             !file_exists(mr_test_tmp_path("bad.jpg")) && !file_exists(mr_test_tmp_path("bad.tif")));
    /* upper-case extensions are fine */
    MR_CHECK_OK(mr_img_write(mr_test_tmp_path("UPPER.PNG"), noise, NULL));
    MR_CHECK(count_temporaries() == 0);
    mr_image_free(noise);
}

/* The seconds since `start`. */
static double seconds_since(const struct timespec *start) {
    struct timespec now;
    clock_gettime(CLOCK_MONOTONIC, &now);
    return (double)(now.tv_sec - start->tv_sec) + 1e-9 * (double)(now.tv_nsec - start->tv_nsec);
}

/* Files that lie (issue 16). What is not a regular file is refused by name before a byte is read (a FIFO would
 * block, /dev/zero never end, a folder's size is 2^63 - 1). A JPEG or HDR header claiming 16000 x 16000 over a few
 * bytes fails at the first band of rows it cannot decode (it took 10-16 s and 3 GB, decoding grey rows, before).
 * A multi-part EXR is refused, and tiled files, read by rows of tiles, read as their scanline twins do. */
MR_TEST(untrusted_files_are_checked_before_they_are_read) {
    mr_image *img = NULL;
    const char *fifo = mr_test_tmp_path("pipe.exr");
    MR_CHECK(mkfifo(fifo, 0666) == 0);
    const struct {
        const char *path, *needle;
    } special[] = {{fifo, "is not a regular file (a FIFO)"},
                   {"/dev/zero", "is not a regular file (a character device)"},
                   {mr_test_scratch_dir(), "is a directory"}};
    for (size_t k = 0; k < sizeof special / sizeof special[0]; k++) {
        MR_CHECK(mr_img_read(special[k].path, NULL, &img) == MR_ERR_IO && img == NULL);
        char want[700];
        snprintf(want, sizeof want, "image '%s': %s", special[k].path, special[k].needle);
        MR_CHECK_MSG(strcmp(mr_last_error(), want) == 0, "'%s', expected '%s'", mr_last_error(), want);
    }
    // The opening itself: a size limit, and the reason alone without a label.
    FILE *f = NULL;
    uint64_t size = 0;
    const char *ten = mr_test_tmp_path("ten.bin");
    MR_CHECK(mr_test_write_file(ten, "0123456789", 10));
    MR_CHECK(mr_io_open_input(ten, "file 'ten.bin'", 9, &f, &size) == MR_ERR_FORMAT && f == NULL);
    MR_CHECK_MSG(strcmp(mr_last_error(), "file 'ten.bin': 10 bytes, more than the limit of 9") == 0, "%s",
                 mr_last_error());
    MR_CHECK(mr_io_open_input(fifo, NULL, 0, &f, NULL) == MR_ERR_IO && f == NULL);
    MR_CHECK_MSG(strcmp(mr_last_error(), "is not a regular file (a FIFO)") == 0, "%s", mr_last_error());
    MR_CHECK_OK(mr_io_open_input(ten, "ten", 10, &f, &size));
    MR_CHECK(f != NULL && size == 10 && fgetc(f) == '0');
    if (f != NULL)
        fclose(f);

    // Headers claiming 16000 x 16000: refused within seconds, naming the file, from a file and from memory.
    mr_image *noise = make_noise(64, 64, 777);
    static unsigned char bytes[1 << 16];
    const char *jpeg = mr_test_tmp_path("claims.jpg"), *hdr = mr_test_tmp_path("claims.hdr");
    MR_CHECK_OK(mr_img_write(jpeg, noise, NULL));
    long n = read_file(jpeg, bytes, sizeof bytes);
    long sof = -1;
    for (long i = 2; i + 9 < n && sof < 0; i++)
        if (bytes[i] == 0xff && bytes[i + 1] == 0xc0)
            sof = i;
    MR_CHECK(sof > 0);
    if (sof > 0) {
        bytes[sof + 5] = bytes[sof + 7] = 16000 >> 8; // height, width (big-endian)
        bytes[sof + 6] = bytes[sof + 8] = 16000 & 255;
        MR_CHECK(mr_test_write_file(jpeg, bytes, (size_t)n / 2)); // and most of the scan gone
        struct timespec start;
        clock_gettime(CLOCK_MONOTONIC, &start);
        MR_CHECK(mr_img_read(jpeg, NULL, &img) == MR_ERR_FORMAT && img == NULL);
        MR_CHECK_MSG(strstr(mr_last_error(), jpeg) != NULL && strstr(mr_last_error(), "corrupt or truncated") != NULL,
                     "%s", mr_last_error());
        MR_CHECK(mr_img_read_memory(bytes, (size_t)n / 2, "claims in memory", NULL, &img, NULL) == MR_ERR_FORMAT);
        MR_CHECK_MSG(strstr(mr_last_error(), "claims in memory") != NULL, "%s", mr_last_error());
        const double took = seconds_since(&start);
        // Over 30 s before; well under 1 s now (10 s under ASan, which maps the 3 GB buffer's shadow).
        MR_CHECK_MSG(took < 20.0, "%.1f s for two reads", took);
    }
    const char head[] = "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 16000 +X 16000\n";
    unsigned char lie[sizeof head - 1 + 64]; // the header, then 16 flat pixels
    memcpy(lie, head, sizeof head - 1);
    memset(lie + sizeof head - 1, 0x80, 64);
    MR_CHECK(mr_test_write_file(hdr, lie, sizeof lie));
    MR_CHECK(mr_img_read(hdr, NULL, &img) == MR_ERR_FORMAT && img == NULL);
    MR_CHECK_MSG(strstr(mr_last_error(), hdr) != NULL && strstr(mr_last_error(), "scanline 0") != NULL, "%s",
                 mr_last_error());

    // oiiotool's multi-part EXR is refused; its tiled files (odd sizes, mipmapped) read as the scanline one does.
    char cmd[2048];
    const char *scan = mr_test_tmp_path("scan.exr"), *tiled = mr_test_tmp_path("tiled.exr");
    const char *mip = mr_test_tmp_path("mip.exr"), *parts = mr_test_tmp_path("parts.exr");
    snprintf(cmd, sizeof cmd,
             "oiiotool --pattern checker:width=3:height=5 37x23 3 -d half -o '%s' --tile 8 8 -o '%s' "
             "--tile 16 16 -otex '%s' --dup --siappend --scanline -o '%s'",
             scan, tiled, mip, parts);
    MR_CHECK_MSG(run_quiet(cmd) == 0, "%s", cmd);
    mr_image *want = NULL;
    MR_CHECK_OK(mr_img_read(scan, NULL, &want));
    const char *twins[2] = {tiled, mip};
    for (int k = 0; k < 2 && want != NULL; k++) {
        MR_CHECK_OK(mr_img_read(twins[k], NULL, &img));
        MR_CHECK_MSG(img != NULL && img->width == 37 && img->height == 23 &&
                         memcmp(img->pixels, want->pixels, mr_image_value_count(want) * sizeof(float)) == 0,
                     "%s differs from %s", twins[k], scan);
        mr_image_free(img);
        img = NULL;
    }
    mr_image_free(want);
    MR_CHECK(mr_img_read(parts, NULL, &img) == MR_ERR_UNSUPPORTED && img == NULL);
    MR_CHECK_MSG(strstr(mr_last_error(), parts) != NULL && strstr(mr_last_error(), "multi-part EXR (2 parts)") != NULL,
                 "%s", mr_last_error());
    mr_image_free(noise);
}

MR_TEST(library_prints_nothing) {
    /* Library code never prints (mr_status.h): run the failure paths with stderr and stdout captured. */
    fflush(stdout);
    fflush(stderr);
    char capture[600];
    snprintf(capture, sizeof capture, "%s", mr_test_tmp_path("captured.txt"));
    int saved_out = dup(1), saved_err = dup(2);
    FILE *sink = fopen(capture, "w");
    MR_CHECK(sink != NULL && saved_out >= 0 && saved_err >= 0);
    if (sink == NULL || saved_out < 0 || saved_err < 0) return;
    dup2(fileno(sink), 1);
    dup2(fileno(sink), 2);

    mr_image *img = NULL, *noise = NULL;
    mr_status statuses[24];
    int k = 0;
    mr_image_create(40, 30, 3, &noise);
    for (size_t i = 0; i < mr_image_value_count(noise); i++) noise->pixels[i] = (float)((i * 7919) % 1000) / 1000.0f;
    static unsigned char bytes[1 << 16];
    const char *formats[4] = {"png", "jpg", "exr", "tif"};
    for (int f = 0; f < 4; f++) {
        char whole[64], cut[64];
        snprintf(whole, sizeof whole, "quiet.%s", formats[f]);
        snprintf(cut, sizeof cut, "quiet_cut.%s", formats[f]);
        mr_img_write(mr_test_tmp_path(whole), noise, NULL);
        long n = read_file(mr_test_tmp_path(whole), bytes, sizeof bytes);
        mr_test_write_file(mr_test_tmp_path(cut), bytes, n > 0 ? (size_t)n / 2 : 0);
        statuses[k++] = mr_img_read(mr_test_tmp_path(cut), NULL, &img);
        statuses[k++] = mr_img_read_memory(bytes, n > 0 ? (size_t)n / 2 : 0, cut, NULL, &img, NULL);
    }
    statuses[k++] = mr_img_read_memory("not an image", 12, "quiet text", NULL, &img, NULL);
    // Deflate data libdeflate refuses and libpng then fails on (its default handler printed "libpng error: ...").
    static const unsigned char signature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    static const unsigned char ihdr[13] = {0, 0, 0, 4, 0, 0, 0, 4, 8, 2, 0, 0, 0};
    static const unsigned char idat[16] = {0x78, 0x9c, 0xff, 0xff, 0xff, 0xff, 0, 1, 2, 3, 4, 5, 6, 7, 8, 9};
    unsigned char png[8 + 25 + 28 + 12], *at = png + 8;
    memcpy(png, signature, 8);
    at = mr_io_png_put_chunk(at, "IHDR", ihdr, sizeof ihdr);
    at = mr_io_png_put_chunk(at, "IDAT", idat, sizeof idat);
    at = mr_io_png_put_chunk(at, "IEND", NULL, 0);
    statuses[k++] = mr_img_read_memory(png, (size_t)(at - png), "quiet libpng", NULL, &img, NULL);
    mr_test_write_file(mr_test_tmp_path("quiet_libpng.png"), png, (size_t)(at - png));
    statuses[k++] = mr_img_read(mr_test_tmp_path("quiet_libpng.png"), NULL, &img);
    mkfifo(mr_test_tmp_path("quiet_fifo.exr"), 0666);
    statuses[k++] = mr_img_read(mr_test_tmp_path("quiet_fifo.exr"), NULL, &img);
    mr_test_write_file(mr_test_tmp_path("quiet_text.png"), "not a png", 9);
    statuses[k++] = mr_img_read(mr_test_tmp_path("quiet_text.png"), NULL, &img);
    statuses[k++] = mr_img_read(mr_test_tmp_path("quiet_missing.exr"), NULL, &img);
    mr_image *wide = NULL;
    mr_image_create(70000, 1, 1, &wide);
    statuses[k++] = mr_img_write(mr_test_tmp_path("quiet_wide.jpg"), wide, NULL);
    mr_image_free(wide);
    mr_image_free(noise);

    fflush(stdout);
    fflush(stderr);
    dup2(saved_out, 1);
    dup2(saved_err, 2);
    close(saved_out);
    close(saved_err);
    fclose(sink);
    for (int i = 0; i < k; i++) MR_CHECK_MSG(statuses[i] != MR_OK, "failure case %d succeeded", i);
    MR_CHECK(img == NULL);
    unsigned char text[512];
    long printed = read_file(capture, text, sizeof text - 1);
    if (printed > 0) text[printed] = '\0';
    MR_CHECK_MSG(printed == 0, "the library printed: %s", printed > 0 ? (const char *)text : "");
}

/* ---- what a file stored, and how precisely ------------------------------------------------------------- */

/* The sRGB decode of an 8/16-bit code, in double, written out independently of srgb.c. */
static double decode(double code, double max) {
    double v = code / max;
    return v <= 0.04045 ? v / 12.92 : pow((v + 0.055) / 1.055, 2.4);
}

MR_TEST(read_stored_says_how_the_file_stored_its_samples) {
    mr_image *f = make_f(3, 1.0f);
    struct {
        const char *name;
        int bits;
        mr_img_encoding write, read;
        int want_bits;
        mr_img_encoding want_encoding;
    } cases[] = {
        {"s8.png", 8, MR_IMG_COLOR, MR_IMG_COLOR, 8, MR_IMG_COLOR},
        {"s8d.png", 8, MR_IMG_DATA, MR_IMG_DATA, 8, MR_IMG_DATA},
        {"s16.png", 16, MR_IMG_COLOR, MR_IMG_COLOR, 16, MR_IMG_COLOR},
        {"s16.tif", 16, MR_IMG_COLOR, MR_IMG_DATA, 16, MR_IMG_DATA},
        {"s32.exr", 32, MR_IMG_COLOR, MR_IMG_COLOR, 0, MR_IMG_DATA}, /* floats: never decoded */
        {"s16.exr", 16, MR_IMG_COLOR, MR_IMG_COLOR, 0, MR_IMG_DATA},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        mr_img_write_options wo = {cases[k].write, cases[k].bits, 0};
        mr_img_read_options ro = {cases[k].read, 0, 0};
        const char *path = mr_test_tmp_path(cases[k].name);
        MR_CHECK_OK(mr_img_write(path, f, &wo));
        mr_image *back = NULL;
        mr_img_stored stored = {-1, (mr_img_encoding)-1};
        MR_CHECK_OK(mr_img_read_stored(path, &ro, &back, &stored));
        MR_CHECK_MSG(stored.bits == cases[k].want_bits && stored.encoding == cases[k].want_encoding,
                     "%s: bits %d encoding %d", cases[k].name, stored.bits, (int)stored.encoding);
        mr_image_free(back);
    }
    /* A failed read leaves *stored untouched. */
    mr_image *none = NULL;
    mr_img_stored untouched = {77, MR_IMG_COLOR};
    MR_CHECK(mr_img_read_stored(mr_test_tmp_path("nothere.png"), NULL, &none, &untouched) == MR_ERR_IO);
    MR_CHECK(untouched.bits == 77 && none == NULL);
    mr_image_free(f);
}

/* The larger distance from the decode of code q to the decodes of q +- 1/2 (clamped to [0, max]). */
static double half_step(double q, double max) {
    return fmax(decode(fmin(q + 0.5, max), max) - decode(q, max), decode(q, max) - decode(fmax(q - 0.5, 0.0), max));
}

MR_TEST(half_step_is_half_a_code_value) {
    /* sRGB, 8 bits: at the code of the value. */
    const int codes[] = {0, 1, 10, 56, 128, 200, 254, 255};
    for (size_t k = 0; k < sizeof codes / sizeof codes[0]; k++) {
        double q = codes[k];
        double want = half_step(q, 255.0);
        /* in the interior, that is half the code's interval within 1 % */
        if (q > 0 && q < 255) MR_CHECK(fabs(want / (0.5 * (decode(q + 0.5, 255) - decode(q - 0.5, 255))) - 1) < 0.01);
        double at = mr_img_half_step(decode(q, 255.0), 8, MR_IMG_COLOR);
        MR_CHECK_MSG(fabs(at - want) <= 1e-9, "code %d: %.9g, expected %.9g", codes[k], at, want);
        /* Any value that stores as this code has the same step: a third of the way to either neighbour. */
        if (q > 0 && q < 255) {
            double lo = decode(q - 1.0 / 3.0, 255.0), hi = decode(q + 1.0 / 3.0, 255.0);
            MR_CHECK(fabs(mr_img_half_step(lo, 8, MR_IMG_COLOR) - want) <= 1e-9);
            MR_CHECK(fabs(mr_img_half_step(hi, 8, MR_IMG_COLOR) - want) <= 1e-9);
        }
    }
    /* Known magnitudes: the whole first half code at the bottom (0.5 / 255 / 12.92: only values above 0 store as
     * 0), likewise 0.0045 at the top, 0.00068 at code 56 (0.0396: the 8-bit store of a dielectric's 0.04). */
    MR_CHECK_NEAR(mr_img_half_step(0.0, 8, MR_IMG_COLOR), 0.5 / 255.0 / 12.92, 1e-12);
    MR_CHECK(mr_img_half_step(1.0, 8, MR_IMG_COLOR) > 0.0044 && mr_img_half_step(1.0, 8, MR_IMG_COLOR) < 0.0045);
    MR_CHECK(mr_img_half_step(0.04, 8, MR_IMG_COLOR) > 0.00066 && mr_img_half_step(0.04, 8, MR_IMG_COLOR) < 0.0007);
    /* 16 bits: the same formula on 65535 codes. */
    MR_CHECK_NEAR(mr_img_half_step(decode(30000.0, 65535.0), 16, MR_IMG_COLOR), half_step(30000.0, 65535.0), 1e-12);
    MR_CHECK_NEAR(mr_img_half_step(decode(3.0, 65535.0), 16, MR_IMG_COLOR), 0.5 / 65535.0 / 12.92, 1e-15);
    /* Linear codes: half a code everywhere. */
    MR_CHECK(mr_img_half_step(0.3, 8, MR_IMG_DATA) == 0.5 / 255.0);
    MR_CHECK(mr_img_half_step(0.0, 16, MR_IMG_DATA) == 0.5 / 65535.0);
    /* Floats and nonsense: 0. Out-of-range values are the end codes'. */
    MR_CHECK(mr_img_half_step(0.3, 0, MR_IMG_COLOR) == 0.0 && mr_img_half_step(0.3, 32, MR_IMG_COLOR) == 0.0);
    MR_CHECK(mr_img_half_step(NAN, 8, MR_IMG_COLOR) == 0.0 && mr_img_half_step(INFINITY, 8, MR_IMG_DATA) == 0.0);
    MR_CHECK(mr_img_half_step(1.5, 8, MR_IMG_COLOR) == mr_img_half_step(1.0, 8, MR_IMG_COLOR));
    MR_CHECK(mr_img_half_step(-0.5, 8, MR_IMG_COLOR) == mr_img_half_step(0.0, 8, MR_IMG_COLOR));
}

MR_TEST(parameter_maps_follow_one_rule) {
    /* An 8-bit grey PNG of code 64 (0.25 stored linearly): a map of Ward's specular (a colour, range up to 10) is
     * sRGB-decoded to 0.0513, of its alpha taken as stored; :linear and :srgb override; a float file is linear,
     * and :srgb on it is an error naming the file. */
    const mr_brdf_model *ward = mr_brdf_find("ward");
    MR_CHECK(ward != NULL);
    if (ward == NULL) return;
    const mr_brdf_param *specular = &ward->params[mr_brdf_param_index(ward, "specular")];
    const mr_brdf_param *alpha = &ward->params[mr_brdf_param_index(ward, "alpha")];
    MR_CHECK(mr_brdf_param_map_encoding(specular, MR_MAP_AS_PARAMETER) == MR_IMG_COLOR);
    MR_CHECK(mr_brdf_param_map_encoding(alpha, MR_MAP_AS_PARAMETER) == MR_IMG_DATA);
    MR_CHECK(mr_brdf_param_map_encoding(specular, MR_MAP_LINEAR) == MR_IMG_DATA);
    MR_CHECK(mr_brdf_param_map_encoding(alpha, MR_MAP_SRGB) == MR_IMG_COLOR);
    MR_CHECK(mr_brdf_param_map_encoding(NULL, MR_MAP_AS_PARAMETER) == MR_IMG_DATA);
    MR_CHECK(strcmp(mr_img_encoding_name(MR_IMG_COLOR), "sRGB") == 0);
    MR_CHECK(strcmp(mr_img_encoding_name(MR_IMG_DATA), "linear") == 0);
    mr_image *grey = NULL;
    MR_CHECK_OK(mr_image_create(4, 2, 3, &grey));
    if (grey == NULL) return;
    for (size_t i = 0; i < mr_image_value_count(grey); i++) grey->pixels[i] = 0.25f;
    const mr_img_write_options as_stored = {MR_IMG_DATA, 8, 0};
    const char *png = mr_test_tmp_path("code64.png"), *exr = mr_test_tmp_path("quarter.exr");
    MR_CHECK_OK(mr_img_write(png, grey, &as_stored));
    MR_CHECK_OK(mr_img_write(exr, grey, NULL));
    const double decoded = mr_srgb_decode_double(64.0 / 255.0); /* 0.05127 */
    const struct {
        const char *path;
        const mr_brdf_param *param;
        mr_map_encoding how;
        double expected;
        mr_img_encoding stored;
    } cases[] = {
        {png, specular, MR_MAP_AS_PARAMETER, decoded, MR_IMG_COLOR},
        {png, specular, MR_MAP_LINEAR, 64.0 / 255.0, MR_IMG_DATA},
        {png, alpha, MR_MAP_AS_PARAMETER, 64.0 / 255.0, MR_IMG_DATA},
        {png, alpha, MR_MAP_SRGB, decoded, MR_IMG_COLOR},
        {exr, specular, MR_MAP_AS_PARAMETER, 0.25, MR_IMG_DATA},
        {exr, specular, MR_MAP_LINEAR, 0.25, MR_IMG_DATA},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        mr_image *map = NULL;
        mr_img_stored stored = {-1, MR_IMG_COLOR};
        MR_CHECK_OK(mr_img_read_param_map(cases[k].path, cases[k].param, cases[k].how, NULL, &map, &stored));
        if (map == NULL) continue;
        MR_CHECK_NEAR(map->pixels[0], cases[k].expected, 1e-6);
        MR_CHECK_MSG(stored.encoding == cases[k].stored, "case %zu", k);
        mr_image_free(map);
    }
    mr_image *untouched = NULL;
    MR_CHECK(mr_img_read_param_map(exr, specular, MR_MAP_SRGB, NULL, &untouched, NULL) == MR_ERR_INVALID_ARG);
    MR_CHECK(untouched == NULL);
    MR_CHECK(strstr(mr_last_error(), "quarter.exr") != NULL && strstr(mr_last_error(), "floating-point") != NULL);
    MR_CHECK(mr_img_read_param_map(png, specular, (mr_map_encoding)7, NULL, &untouched, NULL) == MR_ERR_INVALID_ARG);
    mr_image_free(grey);
}

/* Entries of the test directory whose name starts with ".matremap-" (mr_img_write_set's temporaries). */
static int count_set_temporaries(void) {
    DIR *d = opendir(mr_test_scratch_dir());
    if (d == NULL) return -1;
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d)) != NULL) n += strncmp(e->d_name, ".matremap-", 10) == 0;
    closedir(d);
    return n;
}

/* mr_img_write_set: every image written (bytes as mr_img_write's), whatever the threads; a folder in one target's way
 * refuses the set before anything is written; a failing write leaves the earlier set whole and no temporary. */
MR_TEST(image_sets_are_written_all_or_none) {
    mr_image *colour = make_f(3, 1.0f), *grey = make_f(1, 0.5f);
    char paths[3][600], single[600];
    const char *names[3] = {"set_a.png", "set_b.exr", "set_c.png"};
    for (int k = 0; k < 3; k++) snprintf(paths[k], sizeof paths[k], "%s", mr_test_tmp_path(names[k]));
    mr_img_set_item items[3] = {{paths[0], "-o set_", colour, {MR_IMG_COLOR, 16, 0}},
                                {paths[1], "-o set_", grey, {MR_IMG_DATA, 0, 0}},
                                {paths[2], "--flags", grey, {MR_IMG_DATA, 0, 0}}};
    unsigned char expected[65536], got[65536];
    for (int threads = 1; threads <= 3; threads += 2) {
        mr_img_set_options options = {threads};
        int failed = 7;
        MR_CHECK_OK(mr_img_write_set(items, 3, &options, &failed));
        MR_CHECK(failed == -1);
        for (int k = 0; k < 3; k++) { // the bytes of a single mr_img_write
            snprintf(single, sizeof single, "%s", mr_test_tmp_path(k == 1 ? "single.exr" : "single.png"));
            MR_CHECK_OK(mr_img_write(single, items[k].image, &items[k].options));
            long a = read_file(single, expected, sizeof expected), b = read_file(paths[k], got, sizeof got);
            MR_CHECK_MSG(a > 0 && a == b && memcmp(expected, got, (size_t)a) == 0, "%s, %d threads", names[k],
                         threads);
        }
    }
    MR_CHECK(count_set_temporaries() == 0);
    long before = read_file(paths[0], expected, sizeof expected);

    // A folder in the last target's way: refused, naming it and its label, before anything is written.
    char folder[600];
    snprintf(folder, sizeof folder, "%s", mr_test_tmp_path("set_dir.png"));
    MR_CHECK(mkdir(folder, 0755) == 0);
    mr_img_set_item blocked[2] = {{paths[0], "-o set_", grey, {MR_IMG_DATA, 0, 0}},
                                  {folder, "--flags", grey, {MR_IMG_DATA, 0, 0}}};
    int failed = -1;
    MR_CHECK(mr_img_write_set(blocked, 2, NULL, &failed) == MR_ERR_INVALID_ARG && failed == 1);
    MR_CHECK_MSG(strstr(mr_last_error(), "set_dir.png' (--flags) is a folder") != NULL, "%s", mr_last_error());
    MR_CHECK(read_file(paths[0], got, sizeof got) == before && memcmp(expected, got, (size_t)before) == 0);
    // The same target twice: refused.
    mr_img_set_item twice[2] = {items[0], items[0]};
    MR_CHECK(mr_img_write_set(twice, 2, NULL, &failed) == MR_ERR_INVALID_ARG && failed == 1);

    // A write that fails (a 4-channel JPEG) after others succeeded: the set is lost, the earlier one stays whole.
    mr_image *rgba = make_f(4, 1.0f);
    char jpeg[600];
    snprintf(jpeg, sizeof jpeg, "%s", mr_test_tmp_path("set_d.jpg"));
    mr_img_set_item bad[2] = {{paths[0], NULL, grey, {MR_IMG_DATA, 0, 0}}, {jpeg, NULL, rgba, {MR_IMG_COLOR, 0, 0}}};
    for (int threads = 1; threads <= 2; threads++) {
        mr_img_set_options options = {threads};
        MR_CHECK(mr_img_write_set(bad, 2, &options, &failed) == MR_ERR_UNSUPPORTED && failed == 1);
        MR_CHECK_MSG(strncmp(mr_last_error(), "writing '", 9) == 0 && strstr(mr_last_error(), "set_d.jpg") != NULL,
                     "%s", mr_last_error());
        MR_CHECK(read_file(paths[0], got, sizeof got) == before && memcmp(expected, got, (size_t)before) == 0);
        MR_CHECK(!file_exists(jpeg));
        MR_CHECK(count_set_temporaries() == 0 && count_temporaries() == 0);
    }
    MR_CHECK_OK(mr_img_write_set(NULL, 0, NULL, NULL)); // an empty set: nothing to do
    mr_image_free(colour);
    mr_image_free(grey);
    mr_image_free(rgba);
}

/* mr_img_read_param_maps: each map as mr_img_read_param_map reads it, constants skipped, whatever the threads; the
 * first failure in order reported, with the maps read left to the caller. */
MR_TEST(parameter_maps_read_side_by_side) {
    const mr_brdf_model *gltf = mr_brdf_find("gltf");
    const mr_brdf_param *colour = &gltf->params[mr_brdf_param_index(gltf, "base_color")];
    const mr_brdf_param *rough = &gltf->params[mr_brdf_param_index(gltf, "roughness")];
    mr_image *f = make_f(3, 1.0f);
    char a[600], b[600];
    snprintf(a, sizeof a, "%s", mr_test_tmp_path("maps_a.png"));
    snprintf(b, sizeof b, "%s", mr_test_tmp_path("maps_b.png"));
    MR_CHECK_OK(mr_img_write(a, f, NULL));
    MR_CHECK_OK(mr_img_write(b, f, &(mr_img_write_options){MR_IMG_DATA, 16, 0}));
    for (int threads = 0; threads <= 2; threads++) {
        mr_img_param_map maps[3] = {{.path = a, .param = colour, .how = MR_MAP_AS_PARAMETER},
                                    {.path = NULL, .param = rough, .how = MR_MAP_AS_PARAMETER},
                                    {.path = b, .param = rough, .how = MR_MAP_AS_PARAMETER}};
        int failed = 7;
        MR_CHECK_OK(mr_img_read_param_maps(maps, 3, NULL, threads, &failed));
        MR_CHECK(failed == -1 && maps[1].image == NULL);
        for (int k = 0; k < 3; k += 2) {
            mr_image *one = NULL;
            mr_img_stored stored;
            MR_CHECK_OK(mr_img_read_param_map(maps[k].path, maps[k].param, maps[k].how, NULL, &one, &stored));
            MR_CHECK(maps[k].image != NULL && one != NULL && maps[k].stored.bits == stored.bits &&
                     memcmp(maps[k].image->pixels, one->pixels,
                            (size_t)F_W * F_H * (size_t)one->channels * sizeof(float)) == 0);
            mr_image_free(one);
        }
        MR_CHECK(maps[0].stored.bits == 8 && maps[2].stored.bits == 16);
        for (int k = 0; k < 3; k++) mr_image_free(maps[k].image);
    }
    // A missing file and an unknown encoding: the first in order is reported; the others are read.
    mr_img_param_map bad[3] = {{.path = a, .param = colour, .how = MR_MAP_AS_PARAMETER},
                               {.path = mr_test_tmp_path("maps_missing.png"), .param = rough},
                               {.path = b, .param = rough, .how = MR_MAP_ENCODING_COUNT}};
    int failed = -1;
    MR_CHECK(mr_img_read_param_maps(bad, 3, NULL, 2, &failed) == MR_ERR_IO && failed == 1);
    MR_CHECK_MSG(strstr(mr_last_error(), "maps_missing.png") != NULL, "%s", mr_last_error());
    MR_CHECK(bad[0].image != NULL && bad[1].image == NULL && bad[2].image == NULL);
    for (int k = 0; k < 3; k++) mr_image_free(bad[k].image);
    mr_image_free(f);
}

/* mr_img_read_texture_set: one size (constants broadcast), a grey map's file grey, a packed map's channels; the first
 * problem in order refused, naming the map by its label. */
MR_TEST(texture_sets_are_read_and_checked) {
    const mr_brdf_model *gltf = mr_brdf_find("gltf");
    const mr_brdf_param *colour = &gltf->params[mr_brdf_param_index(gltf, "base_color")];
    const mr_brdf_param *rough = &gltf->params[mr_brdf_param_index(gltf, "roughness")];
    mr_image *rgb = make_f(3, 1.0f), *grey1 = make_f(1, 0.5f), *small = NULL;
    MR_CHECK_OK(mr_image_create(2, 2, 1, &small));
    char c[600], g[600], s[600];
    snprintf(c, sizeof c, "%s", mr_test_tmp_path("set_colour.png"));
    snprintf(g, sizeof g, "%s", mr_test_tmp_path("set_grey.png"));
    snprintf(s, sizeof s, "%s", mr_test_tmp_path("set_small.png"));
    MR_CHECK_OK(mr_img_write(c, rgb, NULL));
    MR_CHECK_OK(mr_img_write(g, grey1, &(mr_img_write_options){MR_IMG_DATA, 0, 0}));
    MR_CHECK_OK(mr_img_write(s, small, &(mr_img_write_options){MR_IMG_DATA, 0, 0}));
    // A colour map, a constant and a grey map: read, the set's size is the files'.
    mr_img_param_map ok[3] = {{c, colour, MR_MAP_AS_PARAMETER, NULL, {0}, "--basecolor c", 0, NULL, 0, NULL},
                              {NULL, rough, MR_MAP_AS_PARAMETER, NULL, {0}, "--metallic 0.5", 0, NULL, 1, NULL},
                              {g, rough, MR_MAP_AS_PARAMETER, NULL, {0}, "--roughness g", 0, NULL, 1, NULL}};
    int width = 0, height = 0, failed = 7;
    MR_CHECK_OK(mr_img_read_texture_set(ok, 3, NULL, 0, &width, &height, &failed));
    MR_CHECK(width == F_W && height == F_H && failed == -1 && ok[0].image && !ok[1].image && ok[2].image);
    for (int k = 0; k < 3; k++) mr_image_free(ok[k].image);
    // Constants only: one texel.
    mr_img_param_map constant = {NULL, rough, MR_MAP_AS_PARAMETER, NULL, {0}, NULL, 0, NULL, 0, NULL};
    MR_CHECK_OK(mr_img_read_texture_set(&constant, 1, NULL, 0, &width, &height, NULL));
    MR_CHECK(width == 1 && height == 1);
    // A colour file where a grey one is expected, the hint appended.
    mr_img_param_map colour_grey[2] = {{c, colour, MR_MAP_AS_PARAMETER, NULL, {0}, "--diffuse c", 0, NULL, 0, NULL},
                                       {c, rough, MR_MAP_AS_PARAMETER, NULL, {0}, "--glossiness c", 0, NULL, 1,
                                        " (a hint)"}};
    MR_CHECK(mr_img_read_texture_set(colour_grey, 2, NULL, 2, NULL, NULL, &failed) == MR_ERR_INVALID_ARG);
    MR_CHECK(failed == 1 && colour_grey[1].image != NULL);
    MR_CHECK_MSG(strstr(mr_last_error(), "--glossiness c is a colour image (pixel 0, 0 is") != NULL &&
                     strstr(mr_last_error(), "expected one channel, or grey (a hint)") != NULL,
                 "%s", mr_last_error());
    for (int k = 0; k < 2; k++) mr_image_free(colour_grey[k].image);
    // A packed map lacking its channels; two sizes.
    mr_img_param_map packed = {g, rough, MR_MAP_AS_PARAMETER, NULL, {0}, "--mr g", 3, "RGB: G, B", 0, NULL};
    MR_CHECK(mr_img_read_texture_set(&packed, 1, NULL, 0, NULL, NULL, &failed) == MR_ERR_INVALID_ARG && failed == 0);
    MR_CHECK_MSG(strcmp(mr_last_error(), "--mr g has one channel; expected RGB: G, B") == 0, "%s", mr_last_error());
    mr_image_free(packed.image);
    mr_img_param_map sizes[2] = {{g, rough, MR_MAP_AS_PARAMETER, NULL, {0}, "--a g", 0, NULL, 1, NULL},
                                 {s, rough, MR_MAP_AS_PARAMETER, NULL, {0}, NULL, 0, NULL, 1, NULL}};
    MR_CHECK(mr_img_read_texture_set(sizes, 2, NULL, 0, NULL, NULL, &failed) == MR_ERR_INVALID_ARG && failed == 1);
    MR_CHECK_MSG(strstr(mr_last_error(), "set_small.png' is 2x2 but --a g is 6x5: maps must have the same size") !=
                     NULL, "%s", mr_last_error());
    for (int k = 0; k < 2; k++) mr_image_free(sizes[k].image);
    mr_image_free(rgb);
    mr_image_free(grey1);
    mr_image_free(small);
}

MR_TEST_MAIN(MR_TEST_ENTRY(openimageio_module_loads_first), MR_TEST_ENTRY(srgb_transfer_functions),
             MR_TEST_ENTRY(png8_rgb_round_trip), MR_TEST_ENTRY(png16_rgb_round_trip),
             MR_TEST_ENTRY(large_integer_round_trips), MR_TEST_ENTRY(png_data_encoding_is_linear),
             MR_TEST_ENTRY(tiff_round_trips), MR_TEST_ENTRY(jpeg_round_trip),
             MR_TEST_ENTRY(exr_float_round_trip_is_exact), MR_TEST_ENTRY(exr_half_round_trip),
             MR_TEST_ENTRY(hdr_round_trip), MR_TEST_ENTRY(one_channel_round_trips),
             MR_TEST_ENTRY(rgba_alpha_is_not_premultiplied), MR_TEST_ENTRY(read_channel_conversions),
             MR_TEST_ENTRY(reads_files_written_by_oiiotool), MR_TEST_ENTRY(png_reader_matches_openimageio),
             MR_TEST_ENTRY(read_memory_matches_the_file), MR_TEST_ENTRY(read_memory_bad_bytes_fail_clearly),
             MR_TEST_ENTRY(oiiotool_reads_our_exr), MR_TEST_ENTRY(untrusted_files_are_checked_before_they_are_read),
             MR_TEST_ENTRY(write_into_missing_directory_fails_cleanly),
             MR_TEST_ENTRY(failed_write_leaves_target_untouched), MR_TEST_ENTRY(full_disk_fails_cleanly),
             MR_TEST_ENTRY(written_files_have_ordinary_permissions), MR_TEST_ENTRY(concurrent_writes_and_reads),
             MR_TEST_ENTRY(bad_inputs_give_clear_errors), MR_TEST_ENTRY(library_prints_nothing),
             MR_TEST_ENTRY(read_stored_says_how_the_file_stored_its_samples),
             MR_TEST_ENTRY(half_step_is_half_a_code_value), MR_TEST_ENTRY(parameter_maps_follow_one_rule),
             MR_TEST_ENTRY(image_sets_are_written_all_or_none), MR_TEST_ENTRY(parameter_maps_read_side_by_side),
             MR_TEST_ENTRY(texture_sets_are_read_and_checked))
