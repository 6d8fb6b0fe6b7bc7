/*
 * test_png.c — the libdeflate PNG reader and writer (src/io/png_deflate.c): decoding bit for bit as libpng does on
 * every colour type, depth, filter and corner case, encoding that libpng, this reader and OpenImageIO read back
 * exactly, and corrupt streams that fail as libpng alone would. (Split from test_image_io.c.)
 */
#include <dirent.h>
#include <libdeflate.h>
#include <png.h>
#include <setjmp.h>
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "../src/io/image_io.h"
#include "../src/io/io_internal.h"
#include "harness.h"

/* ---- the libdeflate PNG reader and writer (png_deflate.c) --------------------------------------------------- */

/* Two decodes are the same: status, layout, and every float bit for bit. */
static void same_decode(const char *what, mr_status sa, const mr_io_raw *a, mr_status sb, const mr_io_raw *b) {
    MR_CHECK_MSG(sa == sb, "%s: %s against %s (%s)", what, mr_status_str(sa), mr_status_str(sb), mr_last_error());
    if (sa != MR_OK || sb != MR_OK) return;
    MR_CHECK_MSG(a->width == b->width && a->height == b->height && a->channels == b->channels && a->bits == b->bits &&
                     a->encoded == b->encoded,
                 "%s: %dx%dx%d %d bits against %dx%dx%d %d bits", what, a->width, a->height, a->channels, a->bits,
                 b->width, b->height, b->channels, b->bits);
    if (a->width != b->width || a->height != b->height || a->channels != b->channels) return;
    const size_t n = (size_t)a->width * (size_t)a->height * (size_t)a->channels;
    MR_CHECK_MSG(memcmp(a->pixels, b->pixels, n * sizeof(float)) == 0, "%s: the values differ", what);
}

/* `path` decoded by png_deflate.c (which must take it when must_take), by mr_io_png_read (which takes it or
 * leaves it to libpng) and by libpng alone: the same status and floats; a failure names the file. */
static void same_as_libpng(const char *path, int must_take) {
    mr_io_raw fast = {0, 0, 0, 0, 0, NULL}, either = {0, 0, 0, 0, 0, NULL}, ref = {0, 0, 0, 0, 0, NULL};
    int handled = 0;
    mr_status s_fast = MR_ERR_IO, s_ref = MR_ERR_IO;
    FILE *f = fopen(path, "rb");
    if (f != NULL) s_fast = mr_io_png_deflate_read(f, path, 16384, &fast, &handled);
    if (f != NULL) fclose(f);
    MR_CHECK_MSG(handled || !must_take, "%s: png_deflate.c left it to libpng", path);
    f = fopen(path, "rb");
    if (f != NULL) s_ref = mr_io_png_read_stream_libpng(f, path, 16384, &ref);
    if (f != NULL) fclose(f);
    const mr_status s_either = mr_io_png_read(path, 16384, &either);
    if (s_either != MR_OK) MR_CHECK_MSG(strstr(mr_last_error(), path) != NULL, "message '%s'", mr_last_error());
    same_decode(path, s_either, &either, s_ref, &ref);
    if (handled) same_decode(path, s_fast, &fast, s_ref, &ref);
    free(fast.pixels);
    free(either.pixels);
    free(ref.pixels);
}

/* A PNG written by libpng: w x h, `depth` bits, colour type `colour`, libpng's filter set `filters`, rows of
 * pseudo-random bytes from `seed` (bytes from {0, 255} only when `sparse`: tRNS keys then occur), optionally
 * interlaced, a palette of npal entries and |ntrans| tRNS alphas (all 255 when ntrans < 0: libpng still adds an
 * alpha channel), or a tRNS key (grey, RGB: the value of pixel (0, 0)),
 * a tEXt and a gAMA chunk, and small IDAT chunks (many of them). Returns 1 when written. */
static int write_with_libpng(const char *path, int w, int h, int depth, int colour, int filters, unsigned seed,
                             int sparse, int interlace, int npal, int ntrans, int key) {
    FILE *f = fopen(path, "wb");
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, NULL, NULL, NULL);
    png_infop info = png ? png_create_info_struct(png) : NULL;
    const int samples[7] = {1, 0, 3, 1, 2, 0, 4};
    const size_t row_bytes = ((size_t)w * (size_t)samples[colour] * (size_t)depth + 7) / 8;
    unsigned char *bytes = malloc(row_bytes * (size_t)h);
    png_bytep *rows = malloc((size_t)h * sizeof *rows);
    int ok = f != NULL && png != NULL && info != NULL && bytes != NULL && rows != NULL;
    for (size_t i = 0; ok && i < row_bytes * (size_t)h; i++) {
        seed = seed * 1103515245u + 12345u;
        bytes[i] = sparse ? ((seed >> 16) & 1 ? 255 : 0) : (unsigned char)(seed >> 16);
    }
    for (int y = 0; ok && y < h; y++) rows[y] = bytes + (size_t)y * row_bytes;
    if (ok && setjmp(png_jmpbuf(png)) == 0) {
        png_init_io(png, f);
        png_set_IHDR(png, info, (png_uint_32)w, (png_uint_32)h, depth, colour,
                     interlace ? PNG_INTERLACE_ADAM7 : PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT,
                     PNG_FILTER_TYPE_DEFAULT);
        png_color palette[256];
        png_byte alphas[256];
        for (int i = 0; i < 256; i++) {
            palette[i].red = (png_byte)(i * 7), palette[i].green = (png_byte)(255 - i);
            palette[i].blue = (png_byte)(i ^ 0x5a);
            alphas[i] = ntrans < 0 ? 255 : (png_byte)(i * 37);
        }
        if (npal > 0) png_set_PLTE(png, info, palette, npal);
        if (ntrans != 0) png_set_tRNS(png, info, alphas, abs(ntrans), NULL);
        if (key) { // pixel (0, 0) becomes transparent, and every pixel equal to it
            png_color_16 c = {0, 0, 0, 0, 0};
            const unsigned short v0 =
                depth == 16 ? (unsigned short)(bytes[0] << 8 | bytes[1]) : (unsigned short)(bytes[0] >> (8 - depth));
            if (colour == PNG_COLOR_TYPE_GRAY) {
                c.gray = v0;
            } else {
                c.red = v0;
                c.green = depth == 16 ? (unsigned short)(bytes[2] << 8 | bytes[3]) : bytes[1];
                c.blue = depth == 16 ? (unsigned short)(bytes[4] << 8 | bytes[5]) : bytes[2];
            }
            png_set_tRNS(png, info, NULL, 0, &c);
        }
        png_text text = {PNG_TEXT_COMPRESSION_NONE, "Comment", "a test", 6, 0, NULL, NULL};
        png_set_text(png, info, &text, 1);
        png_set_gAMA(png, info, 1 / 2.2);
        png_set_filter(png, PNG_FILTER_TYPE_BASE, filters);
        png_set_compression_buffer_size(png, 64);
        png_set_check_for_invalid_index(png, 0); // indices beyond a short palette, on purpose
        png_write_info(png, info);
        if (interlace) png_set_interlace_handling(png);
        png_write_image(png, rows);
        png_write_end(png, NULL);
    } else {
        ok = 0;
    }
    png_destroy_write_struct(png ? &png : NULL, info ? &info : NULL);
    if (f != NULL) ok = fclose(f) == 0 && ok;
    free(bytes);
    free(rows);
    return ok;
}

/* png_deflate.c decodes every non-interlaced layout as libpng does, bit for bit: every colour type at every bit
 * depth, each filter type alone and libpng's adaptive choice, tRNS keys and palette alphas (fewer than the
 * palette's entries, and all opaque), palettes shorter than the indices used (libpng reads those as black),
 * 1x1, 1xN and Nx1 images, ancillary chunks and many IDAT chunks; and every PNG of ../shared/assets. Adam7 it
 * leaves to libpng, which decodes it as before. */
MR_TEST(png_deflate_reader_matches_libpng) {
    static const struct {
        int colour, depth;
    } layouts[] = {{0, 1}, {0, 2}, {0, 4}, {0, 8}, {0, 16}, {2, 8}, {2, 16}, {3, 1},
                   {3, 2}, {3, 4}, {3, 8}, {4, 8}, {4, 16}, {6, 8}, {6, 16}};
    static const int filters[6] = {PNG_FILTER_NONE, PNG_FILTER_SUB, PNG_FILTER_UP, PNG_FILTER_AVG, PNG_FILTER_PAETH,
                                   PNG_ALL_FILTERS};
    static const int sizes[4][2] = {{37, 23}, {1, 1}, {1, 29}, {29, 1}};
    int files = 0;
    for (size_t l = 0; l < sizeof layouts / sizeof layouts[0]; l++) {
        const int colour = layouts[l].colour, depth = layouts[l].depth, palette = colour == 3;
        const int variants = palette ? 4 : (colour == 0 || colour == 2) ? 2 : 1;
        for (int v = 0; v < variants; v++)
            for (int k = 0; k < 6 + 3 + 1; k++) { // each filter at 37x23, the adaptive one at the other sizes, Adam7
                const int size = k < 6 ? 0 : k < 9 ? k - 5 : 0, interlace = k == 9;
                const int filter = k < 6 ? filters[k] : PNG_ALL_FILTERS;
                // palette variants: full, with some alphas, all opaque alphas, short (indices beyond it)
                const int full = 1 << (depth < 8 ? depth : 8);
                const int npal = !palette ? 0 : v == 3 ? (full > 2 ? full / 2 + 1 : 1) : full;
                const int ntrans = !palette ? 0 : v == 1 ? (npal + 1) / 2 : v == 2 ? -npal : 0; // < 0: opaque
                char name[64];
                snprintf(name, sizeof name, "synth_%d_%d_%d_%d.png", colour, depth, v, k);
                const char *path = mr_test_tmp_path(name);
                int ok = write_with_libpng(path, sizes[size][0], sizes[size][1], depth, colour, filter,
                                           (unsigned)(l * 131 + (size_t)v * 17 + (size_t)k), !palette && v == 1,
                                           interlace, npal, ntrans, !palette && v == 1);
                MR_CHECK_MSG(ok, "%s: libpng could not write it", path);
                if (ok) same_as_libpng(path, !interlace);
                files++;
            }
    }
    MR_CHECK(files > 150);
    // Every PNG of the shared assets (RGB, RGBA, palette, 512^2 to 2048^2).
    char cmd[1200], line[1400];
    snprintf(cmd, sizeof cmd, "find '%s' -name '*.png' | sort", mr_test_asset_path(""));
    FILE *list = popen(cmd, "r");
    int assets = 0;
    while (list != NULL && fgets(line, sizeof line, list) != NULL) {
        line[strcspn(line, "\n")] = '\0';
        same_as_libpng(line, 1);
        assets++;
    }
    if (list != NULL) pclose(list);
    MR_CHECK_MSG(assets >= 15, "%d PNGs in %s", assets, mr_test_asset_path(""));
}

/* w x h x channels samples of `bits` (host order), pseudo-random from `seed` over smooth ramps, so that the
 * filters differ from row to row; malloc'ed. */
static void *make_samples(int w, int h, int channels, int bits, unsigned seed) {
    const size_t n = (size_t)w * (size_t)h * (size_t)channels;
    unsigned char *b8 = bits == 8 ? malloc(n) : NULL;
    uint16_t *b16 = bits == 16 ? malloc(n * 2) : NULL;
    for (size_t i = 0; i < n && (b8 != NULL || b16 != NULL); i++) {
        seed = seed * 1103515245u + 12345u;
        const size_t x = i / (size_t)channels % (size_t)w, y = i / (size_t)channels / (size_t)w;
        const unsigned v = (unsigned)(x * 3 + y * 5 + (i % (size_t)channels) * 40) + ((seed >> 16) & 7);
        if (b8 != NULL) b8[i] = (unsigned char)v;
        if (b16 != NULL) b16[i] = (uint16_t)(v * 257 + (seed >> 20));
    }
    return b8 != NULL ? (void *)b8 : (void *)b16;
}

/* raw holds exactly `samples`: code / (2^bits - 1) in float, as every reader here scales. */
static int raw_holds(const mr_io_raw *raw, int w, int h, int channels, int bits, const void *samples) {
    if (raw->pixels == NULL || raw->width != w || raw->height != h || raw->channels != channels || raw->bits != bits)
        return 0;
    const float scale = bits == 8 ? 1.0f / 255.0f : 1.0f / 65535.0f;
    for (size_t i = 0; i < (size_t)w * (size_t)h * (size_t)channels; i++) {
        const float code =
            bits == 8 ? (float)((const unsigned char *)samples)[i] : (float)((const uint16_t *)samples)[i];
        if (memcmp(&raw->pixels[i], &(float){code * scale}, sizeof(float)) != 0) return 0;
    }
    return 1;
}

/* Write samples with `settings`, read the file back with libpng, with png_deflate.c (which must take it) and with
 * OpenImageIO: all three give the samples exactly. */
static void writes_and_reads_back(const char *what, int w, int h, int channels, int bits, int srgb,
                                  const mr_io_png_settings *settings) {
    void *samples = make_samples(w, h, channels, bits, (unsigned)(w * 7 + h * 3 + channels + bits));
    const char *path = mr_test_tmp_path("writer.png");
    MR_CHECK(samples != NULL);
    if (samples == NULL) return;
    MR_CHECK_OK(mr_io_png_write(path, w, h, channels, bits, samples, srgb, settings));
    mr_io_raw a = {0, 0, 0, 0, 0, NULL}, b = {0, 0, 0, 0, 0, NULL}, c = {0, 0, 0, 0, 0, NULL};
    FILE *f = fopen(path, "rb");
    MR_CHECK_OK(f != NULL ? mr_io_png_read_stream_libpng(f, path, 16384, &a) : MR_ERR_IO);
    if (f != NULL) fclose(f);
    int handled = 0;
    f = fopen(path, "rb");
    MR_CHECK_OK(f != NULL ? mr_io_png_deflate_read(f, path, 16384, &b, &handled) : MR_ERR_IO);
    if (f != NULL) fclose(f);
    MR_CHECK_OK(mr_io_oiio_read(path, 16384, &c));
    MR_CHECK_MSG(raw_holds(&a, w, h, channels, bits, samples) && handled &&
                     raw_holds(&b, w, h, channels, bits, samples) && raw_holds(&c, w, h, channels, bits, samples),
                 "%s: %dx%dx%d, %d bits, level %d, filters 0x%x, %s: libpng %d, libdeflate %d (taken %d), "
                 "OpenImageIO %d", what, w, h, channels, bits, settings->level, (unsigned)settings->filters,
                 settings->libpng ? "libpng" : "libdeflate", raw_holds(&a, w, h, channels, bits, samples),
                 raw_holds(&b, w, h, channels, bits, samples), handled, raw_holds(&c, w, h, channels, bits, samples));
    free(a.pixels);
    free(b.pixels);
    free(c.pixels);
    free(samples);
}

/* The libdeflate writer at every level with every filter alone and the adaptive choice, and the default (and
 * the libpng writer) for every layout, both bit depths, 1x1, 1xN and Nx1: what libpng, png_deflate.c and
 * OpenImageIO read back is what was written. Its IHDR and colour chunks are byte for byte libpng's. */
MR_TEST(png_deflate_writer_round_trips) {
    static const int filters[6] = {MR_IO_PNG_FILTER_NONE, MR_IO_PNG_FILTER_SUB, MR_IO_PNG_FILTER_UP,
                                   MR_IO_PNG_FILTER_AVG, MR_IO_PNG_FILTER_PAETH, MR_IO_PNG_ALL_FILTERS};
    for (int level = 0; level <= 12; level++)
        for (int k = 0; k < 6; k++) {
            const mr_io_png_settings settings = {level, filters[k], 0};
            writes_and_reads_back("levels", 37, 23, 4, 8, 1, &settings);
            writes_and_reads_back("levels", 23, 37, 3, 16, 0, &settings);
        }
    static const int sizes[4][2] = {{1, 1}, {1, 17}, {17, 1}, {37, 23}};
    const mr_io_png_settings both[2] = {MR_IO_PNG_DEFAULT, {3, MR_IO_PNG_ALL_FILTERS, 1}};
    for (int s = 0; s < 2; s++)
        for (int channels = 1; channels <= 4; channels++)
            for (int bits = 8; bits <= 16; bits += 8)
                for (int z = 0; z < 4; z++)
                    writes_and_reads_back("layouts", sizes[z][0], sizes[z][1], channels, bits, z % 2, &both[s]);
    // The header and colour chunks (IHDR, gAMA, sRGB, cHRM: 8 + 25 + 16 + 13 + 44 bytes) are libpng's.
    void *samples = make_samples(9, 7, 3, 8, 5);
    unsigned char *ours = NULL, *theirs = NULL;
    size_t ours_size = 0, theirs_size = 0;
    MR_CHECK_OK(mr_io_png_encode("x", 9, 7, 3, 8, samples, 1, &both[0], &ours, &ours_size));
    MR_CHECK_OK(mr_io_png_encode("x", 9, 7, 3, 8, samples, 1, &both[1], &theirs, &theirs_size));
    MR_CHECK(ours_size > 106 && theirs_size > 106 && ours != NULL && theirs != NULL && memcmp(ours, theirs, 106) == 0);
    free(ours);
    free(theirs);
    // Settings outside the ranges: refused, naming the image.
    const mr_io_png_settings bad[4] = {{13, MR_IO_PNG_ALL_FILTERS, 0}, {10, MR_IO_PNG_ALL_FILTERS, 1},
                                       {3, 0, 0}, {3, 0x101, 0}};
    for (int k = 0; k < 4; k++) {
        ours = NULL;
        MR_CHECK(mr_io_png_encode("bad settings", 9, 7, 3, 8, samples, 0, &bad[k], &ours, &ours_size) ==
                 MR_ERR_INVALID_ARG);
        MR_CHECK(ours == NULL && strstr(mr_last_error(), "bad settings") != NULL);
    }
    free(samples);
}

/* An 8-bit RGB PNG built chunk by chunk: IHDR (w x h, colour type `colour`), the zlib stream z in IDAT chunks of
 * `split` bytes (0: one), a tEXt chunk between the first two when `gap`, IEND. Returns its size. */
static size_t build_png(unsigned char *out, int w, int h, int colour, const unsigned char *z, size_t zn,
                        size_t split, int gap) {
    static const unsigned char signature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    unsigned char *at = out;
    memcpy(at, signature, 8);
    at += 8;
    const unsigned char ihdr[13] = {0, 0, (unsigned char)(w >> 8), (unsigned char)w, 0, 0, (unsigned char)(h >> 8),
                                    (unsigned char)h, 8, (unsigned char)colour, 0, 0, 0};
    typedef struct {
        const char *type;
        const unsigned char *data;
        size_t length;
    } chunk;
    chunk chunks[64];
    int count = 0;
    chunks[count++] = (chunk){"IHDR", ihdr, 13};
    const size_t piece = split > 0 ? split : zn;
    for (size_t done = 0; done < zn && count < 60; done += piece) {
        chunks[count++] = (chunk){"IDAT", z + done, zn - done < piece ? zn - done : piece};
        if (gap && done == 0) chunks[count++] = (chunk){"tEXt", (const unsigned char *)"a\0b", 3};
    }
    chunks[count++] = (chunk){"IEND", NULL, 0};
    for (int k = 0; k < count; k++) {
        const uint32_t n = (uint32_t)chunks[k].length;
        at[0] = (unsigned char)(n >> 24), at[1] = (unsigned char)(n >> 16), at[2] = (unsigned char)(n >> 8);
        at[3] = (unsigned char)n;
        memcpy(at + 4, chunks[k].type, 4);
        if (n > 0) memcpy(at + 8, chunks[k].data, n);
        const uint32_t crc = libdeflate_crc32(0, at + 4, 4 + (size_t)n);
        at[8 + n] = (unsigned char)(crc >> 24), at[9 + n] = (unsigned char)(crc >> 16);
        at[10 + n] = (unsigned char)(crc >> 8), at[11 + n] = (unsigned char)crc;
        at += 12 + n;
    }
    return (size_t)(at - out);
}

/* Broken streams that get past the chunk checks (right CRCs) end as they did with libpng alone: zlib data
 * short or long by a row, a filter type of 5, a wrong Adler-32 (libpng takes it: it checks that only after the
 * last row), IDAT chunks with another chunk between them, a palette without PLTE, a CRC mismatch and a truncated
 * file read without image_io.c's chunk check, and random corruptions of the zlib stream; every failure is
 * MR_ERR_FORMAT naming the file, and nothing crashes (make asan). */
MR_TEST(png_deflate_corrupt_streams_fail_cleanly) {
    enum { W = 23, H = 11, ROW = 1 + 3 * W };
    static unsigned char filtered[(H + 1) * ROW], z[4096], file[8192], mutated[4096];
    unsigned seed = 99;
    for (int i = 0; i < (H + 1) * ROW; i++) {
        seed = seed * 1103515245u + 12345u;
        filtered[i] = i % ROW == 0 ? (unsigned char)(i / ROW % 5) : (unsigned char)(seed >> 16);
    }
    struct libdeflate_compressor *c = libdeflate_alloc_compressor(6);
    MR_CHECK(c != NULL);
    if (c == NULL) return;
    const char *path = mr_test_tmp_path("crafted.png");
    const size_t zn = libdeflate_zlib_compress(c, filtered, H * ROW, z, sizeof z);
    size_t n = build_png(file, W, H, 2, z, zn, 0, 0); // well formed: png_deflate.c takes it
    MR_CHECK(zn > 0 && mr_test_write_file(path, file, n));
    same_as_libpng(path, 1);
    n = build_png(file, W, H, 2, z, zn, zn / 3 + 1, 0); // in three IDAT chunks
    MR_CHECK(mr_test_write_file(path, file, n));
    same_as_libpng(path, 1);
    mr_io_raw raw = {0, 0, 0, 0, 0, NULL};
    int handled = 0;
    FILE *f = fopen(path, "rb");
    MR_CHECK(f != NULL && mr_io_png_deflate_read(f, path, 16, &raw, &handled) == MR_ERR_FORMAT && handled);
    MR_CHECK(raw.pixels == NULL && strstr(mr_last_error(), "exceeds the maximum dimension 16") != NULL);
    if (f != NULL) fclose(f);
    n = build_png(file, W, H, 2, z, zn, zn / 2, 1); // a tEXt between IDATs
    MR_CHECK(mr_test_write_file(path, file, n));
    same_as_libpng(path, 0);
    n = build_png(file, W, H, 3, z, zn, 0, 0); // colour type 3 without PLTE
    MR_CHECK(mr_test_write_file(path, file, n));
    same_as_libpng(path, 0);
    MR_CHECK(mr_io_png_read(path, 16384, &raw) == MR_ERR_FORMAT && strstr(mr_last_error(), path) != NULL);
    const size_t rows[2] = {H - 1, H + 1};
    for (int k = 0; k < 2; k++) { // a row short, a row long
        const size_t m = libdeflate_zlib_compress(c, filtered, rows[k] * ROW, mutated, sizeof mutated);
        n = build_png(file, W, H, 2, mutated, m, 0, 0);
        MR_CHECK(m > 0 && mr_test_write_file(path, file, n));
        same_as_libpng(path, 0);
    }
    MR_CHECK(mr_io_png_read(path, 16384, &raw) == MR_OK); // a row long: libpng warns and takes it
    free(raw.pixels);
    filtered[3 * ROW] = 5; // no such filter type
    size_t m = libdeflate_zlib_compress(c, filtered, H * ROW, mutated, sizeof mutated);
    filtered[3 * ROW] = 3;
    n = build_png(file, W, H, 2, mutated, m, 0, 0);
    MR_CHECK(mr_test_write_file(path, file, n));
    same_as_libpng(path, 0);
    raw.pixels = NULL;
    MR_CHECK(mr_img_read(path, NULL, &(mr_image *){NULL}) == MR_ERR_FORMAT);
    MR_CHECK_MSG(strstr(mr_last_error(), path) != NULL && strstr(mr_last_error(), "cannot decode PNG") != NULL, "%s",
                 mr_last_error());
    memcpy(mutated, z, zn);
    mutated[zn - 1] ^= 1; // the Adler-32
    n = build_png(file, W, H, 2, mutated, zn, 0, 0);
    MR_CHECK(mr_test_write_file(path, file, n));
    same_as_libpng(path, 0);
    n = build_png(file, W, H, 2, z, zn, 0, 0);
    file[8 + 25 + 8 + zn / 2] ^= 0x40; // inside the IDAT data: its CRC no longer matches
    MR_CHECK(mr_test_write_file(path, file, n));
    same_as_libpng(path, 0);
    MR_CHECK_MSG(mr_io_png_read(path, 16384, &raw) == MR_ERR_FORMAT && strstr(mr_last_error(), path) != NULL, "%s",
                 mr_last_error()); // libpng inflates a chunk's data before it reads the CRC: its message says which
    file[8 + 25 + 8 + zn / 2] ^= 0x40;
    MR_CHECK(mr_test_write_file(path, file, n - 30)); // cut inside the IDAT data
    same_as_libpng(path, 0);
    MR_CHECK(mr_io_png_read(path, 16384, &raw) == MR_ERR_FORMAT && strstr(mr_last_error(), path) != NULL);
    int failed = 0;
    for (int trial = 0; trial < 300; trial++) { // random corruptions, the CRCs made right again
        memcpy(mutated, z, zn);
        for (int k = 0; k <= trial % 3; k++) {
            seed = seed * 1103515245u + 12345u;
            mutated[(seed >> 8) % zn] = (unsigned char)(seed >> 20);
        }
        n = build_png(file, W, H, 2, mutated, zn, trial % 2 ? 0 : 97, 0);
        MR_CHECK(mr_test_write_file(path, file, n));
        same_as_libpng(path, 0);
        failed += mr_io_png_read(path, 16384, &raw) != MR_OK;
        free(raw.pixels);
        raw.pixels = NULL;
    }
    MR_CHECK_MSG(failed > 100, "only %d of 300 corruptions failed", failed);
    // The chunk structure itself: a byte of IHDR's data changed (its CRC made right), or any byte of the file.
    const size_t good = build_png(file, W, H, 2, z, zn, 97, 1);
    for (int trial = 0; trial < 400; trial++) {
        seed = seed * 1103515245u + 12345u;
        const size_t at = trial < 200 ? 16 + (seed >> 8) % 13 : (seed >> 8) % good;
        unsigned char copy[sizeof file];
        memcpy(copy, file, good);
        copy[at] = (unsigned char)(seed >> 20);
        if (trial < 200) {
            const uint32_t crc = libdeflate_crc32(0, copy + 12, 17);
            for (int b = 0; b < 4; b++) copy[29 + b] = (unsigned char)(crc >> (24 - 8 * b));
        }
        MR_CHECK(mr_test_write_file(path, copy, good));
        same_as_libpng(path, 0);
    }
    libdeflate_free_compressor(c);
}

/* The sizes IHDR claims, held against what the file holds before any decoder allocates (issue 16): a file of a
 * few bytes claiming 16000 x 16000 pixels made libpng allocate 768 MB of rows it never filled. Its IDAT chunks must
 * hold at least 1/1032 of the image's samples (deflate's largest expansion); the most compressible image there is,
 * all zeros at libdeflate's and zlib's best, still passes, and decodes. */
MR_TEST(png_sizes_are_held_against_the_file) {
    static unsigned char zeros[2048 * 2049], z[1 << 16], file[1 << 17];
    struct libdeflate_compressor *c = libdeflate_alloc_compressor(12);
    MR_CHECK(c != NULL);
    if (c == NULL)
        return;
    // 16000 x 16000 RGB over 64 bytes of zeros, non-interlaced and interlaced, from a file and from memory.
    const size_t zn = libdeflate_zlib_compress(c, zeros, 64, z, sizeof z);
    size_t n = build_png(file, 16000, 16000, 2, z, zn, 0, 0);
    const char *path = mr_test_tmp_path("claims.png");
    for (int interlaced = 0; interlaced < 2; interlaced++) {
        file[28] = (unsigned char)interlaced; // IHDR's interlace byte, and its CRC again
        const uint32_t crc = libdeflate_crc32(0, file + 12, 17);
        for (int b = 0; b < 4; b++)
            file[29 + b] = (unsigned char)(crc >> (24 - 8 * b));
        MR_CHECK(mr_test_write_file(path, file, n));
        mr_image *img = NULL;
        MR_CHECK(mr_img_read(path, NULL, &img) == MR_ERR_FORMAT && img == NULL);
        MR_CHECK_MSG(strstr(mr_last_error(), path) != NULL &&
                         strstr(mr_last_error(), "truncated PNG: IHDR claims 16000x16000 pixels") != NULL,
                     "%s", mr_last_error());
        MR_CHECK(mr_img_read_memory(file, n, "claims", NULL, &img, NULL) == MR_ERR_FORMAT && img == NULL);
        MR_CHECK_MSG(strstr(mr_last_error(), "claims: truncated PNG: IHDR claims 16000x16000") != NULL, "%s",
                     mr_last_error());
    }
    // Past the maximum dimension: said so, whatever IDAT holds.
    mr_img_read_options small = {MR_IMG_COLOR, 0, 15999};
    mr_image *img = NULL;
    MR_CHECK(mr_img_read(path, &small, &img) == MR_ERR_FORMAT);
    MR_CHECK_MSG(strstr(mr_last_error(), "16000x16000 pixels exceeds the maximum dimension 15999") != NULL, "%s",
                 mr_last_error());
    // The most compressible image: 2048 x 2048 grey zeros (filter bytes included) at libdeflate's level 12.
    const size_t best = libdeflate_zlib_compress(c, zeros, 2048 * 2049, z, sizeof z);
    n = build_png(file, 2048, 2048, 0, z, best, 0, 0);
    MR_CHECK(best > 0 && mr_test_write_file(path, file, n));
    MR_CHECK_MSG((best - 6) * 1032 >= 2048 * 2048, "%zu bytes", best);
    MR_CHECK_OK(mr_img_read(path, NULL, &img));
    MR_CHECK(img != NULL && img->width == 2048 && img->pixels[2048 * 2048 - 1] == 0.0f);
    mr_image_free(img);
    // The same claim with one compressed byte fewer than deflate needs for it is refused.
    const size_t need = 2048 * 2048 / 1032 + 6;
    if (best > need) {
        n = build_png(file, 2048, 2048, 0, z, need - 1, 0, 0);
        MR_CHECK(mr_test_write_file(path, file, n));
        img = NULL;
        MR_CHECK(mr_img_read(path, NULL, &img) == MR_ERR_FORMAT && img == NULL);
        MR_CHECK_MSG(strstr(mr_last_error(), "truncated PNG: IHDR claims 2048x2048") != NULL, "%s", mr_last_error());
    }
    libdeflate_free_compressor(c);
}

MR_TEST_MAIN(MR_TEST_ENTRY(png_deflate_reader_matches_libpng), MR_TEST_ENTRY(png_deflate_writer_round_trips),
             MR_TEST_ENTRY(png_deflate_corrupt_streams_fail_cleanly),
             MR_TEST_ENTRY(png_sizes_are_held_against_the_file))
