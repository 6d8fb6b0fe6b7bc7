/*
 * png_deflate.c — PNG encoding and decoding around libdeflate (io_internal.h, "PNG").
 *
 * Why not libpng alone: libpng drives zlib through its streaming interface, a few kilobytes at a time, and zlib's
 * deflate and inflate are what a texture-set conversion spent most of its PNG time in (docs/performance.md, "PNG
 * read and write"). libdeflate compresses and decompresses whole buffers, faster than zlib for files of the same
 * size (several times so when compressing: the measurements are there), but it knows nothing of PNG. This file
 * does the PNG around it (ISO/IEC 15948:2003, the W3C PNG Specification, second edition: "§" below):
 *
 *   - the datastream layout of §5: the 8-byte signature, then chunks of length, type, data and CRC-32 (Annex D,
 *     computed with libdeflate_crc32);
 *   - the five filter types of §9 and, for the encoder, libpng's adaptive choice per row;
 *   - the encoder writes IHDR (§11.2.2), the sRGB, gAMA and cHRM chunks byte for byte as libpng's
 *     png_set_sRGB_gAMA_and_cHRM wrote them (§11.3.3), one zlib stream (§10) split into IDAT chunks, and IEND;
 *   - the decoder takes the non-interlaced PNGs of every colour type and bit depth (§11.2.2), with PLTE and tRNS,
 *     and gives what png_io.c's libpng reader gives (tests/test_image_io.c proves it bit for bit). Anything it
 *     does not take, or that is not a well-formed file (a CRC mismatch, a chunk out of place, zlib data that does
 *     not inflate to exactly the image, an unknown critical chunk, Adam7), it hands back untouched (*handled = 0)
 *     and png_io.c decodes it with libpng, as before: so every file gives the values, warnings and errors it
 *     gave, and this decoder never has to mimic libpng's handling of broken files.
 *
 * One thread: filtering, vectorised, is about a sixth of the encoding, and sharing it out gained nothing; the
 * deflate stream itself cannot be split with libdeflate (the last block of each piece is marked as the stream's
 * last), and the conversions already encode and decode their textures side by side (docs/performance.md, "PNG
 * read and write"). Nothing here prints, and libdeflate does not either.
 */
#include <libdeflate.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "../mr_internal.h"
#include "io_internal.h"

static const unsigned char signature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};

uint32_t mr_io_be32(const unsigned char *p) {
    return (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | (uint32_t)p[3];
}

static void put32(unsigned char *p, uint32_t v) {
    p[0] = (unsigned char)(v >> 24);
    p[1] = (unsigned char)(v >> 16);
    p[2] = (unsigned char)(v >> 8);
    p[3] = (unsigned char)v;
}

/* ---- filters (§9) ------------------------------------------------------------------------------------------
 * Each filtered byte predicts from a (the byte bpp to the left, 0 left of the row), b (the byte above, 0 in the
 * first row) and c (above-left): type 0 None, 1 Sub (a), 2 Up (b), 3 Average (floor((a + b) / 2)), 4 Paeth
 * (§9.4: whichever of a, b, c is nearest a + b - c, ties in that order). Encoding works on the original bytes, so
 * its loops carry no dependency from one byte to the next and vectorise; decoding needs the decoded a and c. */

static inline unsigned paeth(unsigned a, unsigned b, unsigned c) {
    const int p = (int)a + (int)b - (int)c;
    const int pa = abs(p - (int)a), pb = abs(p - (int)b), pc = abs(p - (int)c);
    return pa <= pb && pa <= pc ? a : (pb <= pc ? b : c);
}

/* Filter `n` bytes of `cur` (above it `prev`) with `type` into `out`; bpp >= 1 bytes per pixel. `omp simd`: GCC's
 * -O2 does not vectorise loops of unknown length, and filtering every row five ways for the adaptive choice cost
 * more than the compression itself before it did. */
static void filter_row(int type, const uint8_t *restrict cur, const uint8_t *restrict prev, size_t n, size_t bpp,
                       uint8_t *restrict out) {
    const size_t lead = bpp < n ? bpp : n;
    switch (type) {
    case 0:
        memcpy(out, cur, n);
        break;
    case 1:
        memcpy(out, cur, lead);
#pragma omp simd
        for (size_t i = bpp; i < n; i++) out[i] = (uint8_t)(cur[i] - cur[i - bpp]);
        break;
    case 2:
#pragma omp simd
        for (size_t i = 0; i < n; i++) out[i] = (uint8_t)(cur[i] - prev[i]);
        break;
    case 3:
        for (size_t i = 0; i < lead; i++) out[i] = (uint8_t)(cur[i] - (prev[i] >> 1));
#pragma omp simd
        for (size_t i = bpp; i < n; i++) out[i] = (uint8_t)(cur[i] - ((cur[i - bpp] + prev[i]) >> 1));
        break;
    default:
        for (size_t i = 0; i < lead; i++) out[i] = (uint8_t)(cur[i] - prev[i]); // Paeth(0, b, 0) = b
#pragma omp simd
        for (size_t i = bpp; i < n; i++) {
            const int16_t a = cur[i - bpp], b = prev[i], c = prev[i - bpp];
            const int16_t pa = (int16_t)abs(b - c), pb = (int16_t)abs(a - c), pc = (int16_t)abs(a + b - 2 * c);
            out[i] = (uint8_t)(cur[i] - (pa <= pb && pa <= pc ? a : pb <= pc ? b : c));
        }
        break;
    }
}

/* libpng's adaptive heuristic (png_write_find_filter): the filtered bytes read as signed, their absolute values
 * summed; the smallest sum wins. Summed in 32 bits per 2^23 bytes (at most 128 each), vectorised. */
static uint64_t filter_cost(const uint8_t *f, size_t n) {
    uint64_t sum = 0;
    for (size_t start = 0; start < n; start += (size_t)1 << 23) {
        const size_t end = n - start > ((size_t)1 << 23) ? start + ((size_t)1 << 23) : n;
        uint32_t part = 0;
#pragma omp simd reduction(+ : part)
        for (size_t i = start; i < end; i++) part += (uint32_t)abs((int8_t)f[i]);
        sum += part;
    }
    return sum;
}

/* Undo filter `type` on row `x` in place (above it `prev`, already decoded); 0 for a type outside 0-4. */
int mr_io_png_unfilter_row(int type, uint8_t *restrict x, const uint8_t *restrict prev, size_t n, size_t bpp) {
    const size_t lead = bpp < n ? bpp : n;
    switch (type) {
    case 0:
        return 1;
    case 1:
        for (size_t i = bpp; i < n; i++) x[i] = (uint8_t)(x[i] + x[i - bpp]);
        return 1;
    case 2:
#pragma omp simd
        for (size_t i = 0; i < n; i++) x[i] = (uint8_t)(x[i] + prev[i]);
        return 1;
    case 3:
        for (size_t i = 0; i < lead; i++) x[i] = (uint8_t)(x[i] + (prev[i] >> 1));
        for (size_t i = bpp; i < n; i++) x[i] = (uint8_t)(x[i] + ((x[i - bpp] + prev[i]) >> 1));
        return 1;
    case 4:
        for (size_t i = 0; i < lead; i++) x[i] = (uint8_t)(x[i] + prev[i]);
        for (size_t i = bpp; i < n; i++) x[i] = (uint8_t)(x[i] + paeth(x[i - bpp], prev[i], prev[i - bpp]));
        return 1;
    default:
        return 0;
    }
}

/* ---- encoding ---------------------------------------------------------------------------------------------- */

/* Rows per IDAT chunk do not matter to decoders; chunks of at most 1 MiB keep every chunk small for readers that
 * hold a chunk whole, at 12 bytes per MiB. */
#define IDAT_MAX ((size_t)1 << 20)

unsigned char *mr_io_png_put_chunk(unsigned char *at, const char *type, const void *data, size_t length) {
    put32(at, (uint32_t)length);
    memcpy(at + 4, type, 4);
    if (length > 0) memcpy(at + 8, data, length);
    put32(at + 8 + length, libdeflate_crc32(0, at + 4, 4 + length));
    return at + 12 + length;
}

/* Filter row y of the image into out (its filter byte, then row_bytes bytes): the filters of the set `filters`
 * (MR_IO_PNG_FILTER_* bits), the cheapest by filter_cost when several. For 16-bit samples the row and the one
 * above are put in the file's big-endian order first (be holds 2 * row_bytes bytes); cand holds 5 rows. */
static void encode_row(const unsigned char *image, int y, size_t row_bytes, size_t bpp, int bits, int filters,
                       uint8_t *be, uint8_t *cand, uint8_t *out) {
    const uint8_t *cur = image + (size_t)y * row_bytes, *prev = y > 0 ? cur - row_bytes : NULL;
    if (bits == 16) {
        uint8_t *c = be, *p = be + row_bytes;
        for (size_t i = 0; i < row_bytes; i += 2) {
            uint16_t v, w = 0;
            memcpy(&v, cur + i, 2);
            if (prev != NULL) memcpy(&w, prev + i, 2);
            c[i] = (uint8_t)(v >> 8), c[i + 1] = (uint8_t)v;
            p[i] = (uint8_t)(w >> 8), p[i + 1] = (uint8_t)w;
        }
        cur = c;
        prev = p;
    } else if (prev == NULL) {
        memset(be, 0, row_bytes);
        prev = be;
    }
    int best = -1;
    uint64_t best_cost = UINT64_MAX;
    for (int type = 0; type < 5; type++) {
        if (!(filters & (MR_IO_PNG_FILTER_NONE << type))) continue;
        uint8_t *f = cand + (size_t)type * row_bytes;
        filter_row(type, cur, prev, row_bytes, bpp, f);
        if ((filters & (filters - 1)) == 0) { // one filter: no choice to make
            best = type;
            break;
        }
        const uint64_t cost = filter_cost(f, row_bytes);
        if (cost < best_cost) best = type, best_cost = cost;
    }
    out[0] = (uint8_t)best;
    memcpy(out + 1, cand + (size_t)best * row_bytes, row_bytes);
}

mr_status mr_io_png_deflate_encode(const char *name, int width, int height, int channels, int bits, const void *data,
                                   int srgb_tag, const mr_io_png_settings *settings, unsigned char **bytes,
                                   size_t *size) {
    static const uint8_t colour_types[5] = {0, 0, 4, 2, 6}; // §11.2.2: grey, grey + alpha, RGB, RGBA
    const size_t bpp = (size_t)channels * (size_t)(bits / 8), row_bytes = (size_t)width * bpp;
    const size_t filtered_size = (size_t)height * (row_bytes + 1);
    if (row_bytes / bpp != (size_t)width || filtered_size / (row_bytes + 1) != (size_t)height)
        return mr_fail(MR_ERR_NOMEM, "image '%s': %dx%d pixels do not fit in memory", name, width, height);
    uint8_t *filtered = malloc(filtered_size), *scratch = malloc(7 * row_bytes); // 5 candidate rows, 2 big-endian
    struct libdeflate_compressor *compressor = libdeflate_alloc_compressor(settings->level);
    if (filtered == NULL || scratch == NULL || compressor == NULL) {
        free(filtered);
        free(scratch);
        libdeflate_free_compressor(compressor);
        return mr_fail(MR_ERR_NOMEM, "image '%s': out of memory for the PNG encoder", name);
    }
    for (int y = 0; y < height; y++)
        encode_row(data, y, row_bytes, bpp, bits, settings->filters, scratch + 5 * row_bytes, scratch,
                   filtered + (size_t)y * (row_bytes + 1));
    free(scratch);
    const size_t bound = libdeflate_zlib_compress_bound(compressor, filtered_size);
    unsigned char *z = malloc(bound);
    const size_t z_size = z != NULL ? libdeflate_zlib_compress(compressor, filtered, filtered_size, z, bound) : 0;
    libdeflate_free_compressor(compressor);
    free(filtered);
    if (z == NULL) return mr_fail(MR_ERR_NOMEM, "image '%s': out of memory for the PNG encoder", name);
    if (z_size == 0) {
        free(z);
        return mr_fail(MR_ERR_EXTERNAL, "image '%s': PNG encoding failed: libdeflate found no room for %zu bytes",
                       name, filtered_size);
    }
    const size_t idat_chunks = (z_size + IDAT_MAX - 1) / IDAT_MAX;
    const size_t total = 8 + 25 + (srgb_tag ? 16 + 13 + 44 : 0) + 12 * idat_chunks + z_size + 12;
    unsigned char *file = malloc(total);
    if (file == NULL) {
        free(z);
        return mr_fail(MR_ERR_NOMEM, "image '%s': out of memory for the PNG encoder", name);
    }
    unsigned char ihdr[13], *at = file;
    put32(ihdr, (uint32_t)width);
    put32(ihdr + 4, (uint32_t)height);
    ihdr[8] = (uint8_t)bits;
    ihdr[9] = colour_types[channels];
    ihdr[10] = ihdr[11] = ihdr[12] = 0; // deflate, adaptive filtering (method 0), no interlace
    memcpy(at, signature, 8);
    at = mr_io_png_put_chunk(at + 8, "IHDR", ihdr, 13);
    if (srgb_tag) {
        // libpng's png_set_sRGB_gAMA_and_cHRM(PNG_sRGB_INTENT_PERCEPTUAL), in its order: gAMA 1/2.2 (45455 in
        // units of 1e-5), sRGB rendering intent 0, cHRM with the sRGB white point and primaries (§11.3.3).
        static const unsigned char gama[4] = {0, 0, 0xb1, 0x8f}, srgb[1] = {0};
        static const uint32_t chrm_values[8] = {31270, 32900, 64000, 33000, 30000, 60000, 15000, 6000};
        unsigned char chrm[32];
        for (int i = 0; i < 8; i++) put32(chrm + 4 * i, chrm_values[i]);
        at = mr_io_png_put_chunk(at, "gAMA", gama, 4);
        at = mr_io_png_put_chunk(at, "sRGB", srgb, 1);
        at = mr_io_png_put_chunk(at, "cHRM", chrm, 32);
    }
    for (size_t done = 0; done < z_size; done += IDAT_MAX)
        at = mr_io_png_put_chunk(at, "IDAT", z + done, z_size - done < IDAT_MAX ? z_size - done : IDAT_MAX);
    at = mr_io_png_put_chunk(at, "IEND", NULL, 0);
    free(z);
    *bytes = file;
    *size = (size_t)(at - file);
    return MR_OK;
}

/* ---- decoding ---------------------------------------------------------------------------------------------- */

/* What the chunks before the image data say. */
typedef struct png_info {
    uint32_t width, height;
    int depth, colour;      /* IHDR */
    int samples;            /* per pixel in the file: 1 grey or palette index, 2 grey + alpha, 3 RGB, 4 RGBA */
    size_t row_bytes, bpp;  /* a row without its filter byte; bytes per pixel, at least 1 (§9.2) */
    int palette_size;       /* PLTE entries, 0 without PLTE */
    unsigned char palette[256][3];
    int trns;               /* tRNS seen: entries for a palette, 1 for grey or RGB */
    unsigned char trns_alpha[256];
    uint16_t trns_key[3];   /* the transparent grey (in [0]) or RGB, for colour types 0 and 2 */
} png_info;

/* IHDR (§11.2.2) as this decoder takes it: a valid combination of colour type and bit depth, compression and
 * filter method 0, no interlace. 0 for anything else (libpng decides). */
static int parse_ihdr(const unsigned char *d, png_info *info) {
    static const int samples[7] = {1, 0, 3, 1, 2, 0, 4};
    info->width = mr_io_be32(d);
    info->height = mr_io_be32(d + 4);
    info->depth = d[8];
    info->colour = d[9];
    if (info->width == 0 || info->height == 0 || info->width > 0x7fffffffu || info->height > 0x7fffffffu) return 0;
    if (info->colour > 6 || samples[info->colour] == 0 || d[10] != 0 || d[11] != 0 || d[12] != 0) return 0;
    const int depth = info->depth;
    const int depth_ok = info->colour == 0   ? (depth == 1 || depth == 2 || depth == 4 || depth == 8 || depth == 16)
                         : info->colour == 3 ? (depth == 1 || depth == 2 || depth == 4 || depth == 8)
                                             : (depth == 8 || depth == 16);
    if (!depth_ok) return 0;
    info->samples = samples[info->colour];
    const size_t bits = (size_t)info->width * (size_t)info->samples * (size_t)depth;
    info->row_bytes = (bits + 7) / 8;
    info->bpp = (size_t)info->samples * (size_t)depth >= 8 ? (size_t)info->samples * (size_t)depth / 8 : 1;
    return 1;
}

/* tRNS (§11.3.2.1) as libpng keeps it: after PLTE for a palette, with 1 to palette-size entries; one 16-bit grey
 * or three RGB values within the bit depth otherwise; none for colour types with alpha. 0 for anything else. */
static int parse_trns(const unsigned char *d, uint32_t length, png_info *info) {
    if (info->trns) return 0;
    if (info->colour == 3) {
        if (info->palette_size == 0 || length == 0 || length > (uint32_t)info->palette_size) return 0;
        memcpy(info->trns_alpha, d, length);
        info->trns = (int)length;
        return 1;
    }
    const uint32_t want = info->colour == 0 ? 2 : info->colour == 2 ? 6 : 0;
    if (want == 0 || length != want) return 0;
    for (uint32_t k = 0; k < length / 2; k++) {
        info->trns_key[k] = (uint16_t)(d[2 * k] << 8 | d[2 * k + 1]);
        if (info->trns_key[k] > (1u << info->depth) - 1) return 0; // libpng masks these: let it
    }
    info->trns = 1;
    return 1;
}

static int read_exact(FILE *file, void *into, size_t n) { return n == 0 || fread(into, 1, n, file) == n; }

/* Sample x of a row of `depth`-bit samples, big-endian within bytes and 16-bit samples (§7.2). */
static inline unsigned sample_at(const uint8_t *row, size_t x, int depth) {
    if (depth == 8) return row[x];
    if (depth == 16) return (unsigned)row[2 * x] << 8 | row[2 * x + 1];
    const size_t bit = x * (size_t)depth;
    return (unsigned)(row[bit / 8] >> (8 - depth - (int)(bit % 8))) & ((1u << depth) - 1);
}

/* Convert a decoded row to what png_io.c's libpng reader returns (png_set_expand: palette to RGB(A), grey below
 * 8 bits scaled to 8 by multiplying with 255 / (2^depth - 1), a tRNS key or palette alpha to an alpha channel;
 * then code * (1 / (2^bits - 1)) in float). lut8 holds the 256 8-bit values; pal the palette's, 4 per entry. */
static void row_to_floats(const png_info *info, const uint8_t *row, const float *lut8, const float *pal,
                          float *out) {
    const size_t w = info->width;
    if (info->colour == 3) {
        const int c = info->trns ? 4 : 3;
        for (size_t x = 0; x < w; x++, out += c)
            memcpy(out, pal + 4 * sample_at(row, x, info->depth), (size_t)c * sizeof *out);
        return;
    }
    const size_t n = w * (size_t)info->samples;
    if (!info->trns && info->depth == 8) {
        const float scale = 1.0f / 255.0f; // lut8's values, computed the same way: vectorised
#pragma omp simd
        for (size_t i = 0; i < n; i++) out[i] = (float)row[i] * scale;
    } else if (!info->trns && info->depth == 16) {
        const float scale = 1.0f / 65535.0f;
#pragma omp simd
        for (size_t i = 0; i < n; i++) out[i] = (float)(row[2 * i] << 8 | row[2 * i + 1]) * scale;
    } else {
        // Grey below 8 bits, or grey / RGB with a tRNS key: sample by sample, the alpha after each pixel.
        const int s = info->samples, depth = info->depth;
        const unsigned scale8 = depth < 8 ? 255u / ((1u << depth) - 1) : 1; // 255, 85, 17: bit replication
        const float scale16 = 1.0f / 65535.0f;
        for (size_t x = 0; x < w; x++) {
            int transparent = info->trns;
            for (int k = 0; k < s; k++) {
                const unsigned v = sample_at(row, x * (size_t)s + (size_t)k, depth);
                transparent &= v == info->trns_key[k];
                *out++ = depth == 16 ? (float)v * scale16 : lut8[v * scale8];
            }
            if (info->trns) *out++ = transparent ? 0.0f : (depth == 16 ? 65535.0f * scale16 : lut8[255]);
        }
    }
}

/* The chunks after the signature up to IEND: IHDR, PLTE and tRNS into *info, the IDAT data concatenated into
 * *idat. Returns 1 when the file is one this decoder takes (every CRC right, every chunk where it belongs), 0
 * otherwise; *status is set (and 1 returned with it) for our own failures: max_dimension, memory. */
static int read_chunks(FILE *file, const char *label, int max_dimension, png_info *info, unsigned char **idat,
                       size_t *idat_size, mr_status *status) {
    unsigned char head[8], scratch[4096];
    size_t capacity = 0, limit = 0;
    int seen_idat = 0, after_idat = 0;
    for (int chunk = 0;; chunk++) {
        if (!read_exact(file, head, 8)) return 0;
        const uint32_t length = mr_io_be32(head);
        const unsigned char *type = head + 4;
        if (length > 0x7fffffffu) return 0;
        for (int i = 0; i < 4; i++)
            if (!((type[i] >= 'A' && type[i] <= 'Z') || (type[i] >= 'a' && type[i] <= 'z'))) return 0;
        if ((chunk == 0) != (memcmp(type, "IHDR", 4) == 0)) return 0;
        uint32_t crc = libdeflate_crc32(0, type, 4);
        const int is_idat = memcmp(type, "IDAT", 4) == 0;
        if (seen_idat && !is_idat) after_idat = 1;
        if (is_idat) {
            if (after_idat) return 0; // IDAT chunks must be consecutive (§5.6)
            if (!seen_idat) {
                seen_idat = 1;
                if (info->colour == 3 && info->palette_size == 0) return 0;
                // The checks png_io.c makes once libpng has read the chunks before the image data, with its messages.
                if ((long)info->width > max_dimension || (long)info->height > max_dimension) {
                    *status = mr_fail(MR_ERR_FORMAT, "%s: %lux%lu pixels exceeds the maximum dimension %d", label,
                                      (unsigned long)info->width, (unsigned long)info->height, max_dimension);
                    return 1;
                }
                const int channels = info->colour == 3 ? (info->trns ? 4 : 3) : info->samples + (info->trns != 0);
                const size_t count = (size_t)info->width * info->height;
                if (count > SIZE_MAX / sizeof(float) / (size_t)channels ||
                    info->row_bytes + 1 > SIZE_MAX / 2 / info->height) {
                    *status = mr_fail(MR_ERR_NOMEM, "%s: %lux%lu pixels do not fit in memory", label,
                                      (unsigned long)info->width, (unsigned long)info->height);
                    return 1;
                }
                // Compressed data beyond twice the image (plus 1 MB) is no zlib stream an encoder makes:
                // libpng, which streams, takes such files.
                const size_t inflated = (info->row_bytes + 1) * info->height;
                limit = inflated < ((size_t)1 << 30) ? 2 * inflated + ((size_t)1 << 20) : inflated + (inflated >> 3);
                struct stat st;
                const int fd = fileno(file);
                capacity = fd >= 0 && fstat(fd, &st) == 0 && st.st_size > 0 ? (size_t)st.st_size : (size_t)1 << 20;
                capacity = capacity < limit ? capacity : limit;
                *idat = malloc(capacity);
                if (*idat == NULL) {
                    *status = mr_fail(MR_ERR_NOMEM, "%s: out of memory for %lux%lu pixels", label,
                                      (unsigned long)info->width, (unsigned long)info->height);
                    return 1;
                }
            }
            if (length > limit - *idat_size) return 0;
            if (*idat_size + length > capacity) {
                size_t grown = capacity;
                while (grown < *idat_size + length) grown = grown < limit / 2 ? 2 * grown : limit;
                unsigned char *bigger = realloc(*idat, grown);
                if (bigger == NULL) {
                    *status = mr_fail(MR_ERR_NOMEM, "%s: out of memory for %lux%lu pixels", label,
                                      (unsigned long)info->width, (unsigned long)info->height);
                    return 1;
                }
                *idat = bigger;
                capacity = grown;
            }
            if (!read_exact(file, *idat + *idat_size, length)) return 0;
            crc = libdeflate_crc32(crc, *idat + *idat_size, length);
            *idat_size += length;
        } else if (chunk == 0 || memcmp(type, "PLTE", 4) == 0 || memcmp(type, "tRNS", 4) == 0) {
            // Small chunks whose contents matter: IHDR 13 bytes, PLTE at most 256 entries (§11.2.3), tRNS at
            // most 256 (§11.3.2.1).
            if (length > 768 || after_idat || !read_exact(file, scratch, length)) return 0;
            crc = libdeflate_crc32(crc, scratch, length);
            if (chunk == 0) {
                if (length != 13 || !parse_ihdr(scratch, info)) return 0;
            } else if (type[0] == 'P') {
                const uint32_t most = info->colour == 3 ? 1u << info->depth : 256;
                if (info->palette_size != 0 || info->trns || info->colour == 0 || info->colour == 4 ||
                    length == 0 || length % 3 != 0 || length / 3 > most)
                    return 0;
                info->palette_size = (int)(length / 3);
                memcpy(info->palette, scratch, length);
            } else if (!parse_trns(scratch, length, info)) {
                return 0;
            }
        } else if (memcmp(type, "IEND", 4) == 0) {
            if (length != 0 || !seen_idat) return 0;
        } else if (!(type[0] & 0x20)) {
            return 0; // critical chunks (an upper-case first letter, §5.4) other than those above
        } else if (length > 8000000u) {
            return 0; // libpng's limit on ancillary chunks (PNG_USER_CHUNK_MALLOC_MAX): let it say what it does
        } else {
            for (uint32_t left = length; left > 0;) {
                const size_t n = left < sizeof scratch ? left : sizeof scratch;
                if (!read_exact(file, scratch, n)) return 0;
                crc = libdeflate_crc32(crc, scratch, n);
                left -= (uint32_t)n;
            }
        }
        unsigned char stored[4];
        if (!read_exact(file, stored, 4) || mr_io_be32(stored) != crc) return 0;
        if (memcmp(type, "IEND", 4) == 0) return 1;
    }
}

/* The decoder's common part: the chunks, the inflated and unfiltered rows (*rows: row y's samples at
 * *rows + y * (row_bytes + 1), without its filter byte at the start of each stride; freed by the caller) and *info.
 * Returns 1 when it decoded them or failed with a status of its own (*status), 0 when the file is one it leaves to
 * libpng. */
static int decode_rows(FILE *file, const char *label, int max_dimension, png_info **info_out, uint8_t **rows_out,
                       mr_status *status) {
    *status = MR_OK;
    *rows_out = NULL;
    *info_out = NULL;
    unsigned char head[8];
    if (!read_exact(file, head, 8) || memcmp(head, signature, 8) != 0) return 0;
    png_info *info = calloc(1, sizeof *info);
    if (info == NULL) return 0; // libpng will say it has no memory either
    unsigned char *idat = NULL;
    size_t idat_size = 0;
    if (!read_chunks(file, label, max_dimension, info, &idat, &idat_size, status) || *status != MR_OK) {
        free(idat);
        free(info);
        return *status != MR_OK;
    }
    const size_t stride = info->row_bytes + 1, inflated = stride * info->height;
    if (inflated / 1032 > idat_size) { // deflate expands at most 1032-fold (258 bytes for 2 bits): libpng says why
        free(idat);
        free(info);
        return 0;
    }
    uint8_t *rows = malloc(inflated + info->row_bytes); // and a row of zeros above the first (§9.2)
    struct libdeflate_decompressor *inflater = rows != NULL ? libdeflate_alloc_decompressor() : NULL;
    if (inflater == NULL) {
        *status = mr_fail(MR_ERR_NOMEM, "%s: out of memory for %lux%lu pixels", label, (unsigned long)info->width,
                          (unsigned long)info->height);
        free(rows);
        free(idat);
        free(info);
        return 1;
    }
    // Exactly the image's bytes, or libpng decides (it takes, with a warning, a stream holding more than the image,
    // and one whose Adler-32 is wrong: it reads that only after the last row).
    const enum libdeflate_result result =
        libdeflate_zlib_decompress(inflater, idat, idat_size, rows + info->row_bytes, inflated, NULL);
    libdeflate_free_decompressor(inflater);
    free(idat);
    int ok = result == LIBDEFLATE_SUCCESS;
    memset(rows, 0, info->row_bytes);
    for (uint32_t y = 0; y < info->height && ok; y++) {
        uint8_t *row = rows + info->row_bytes + (size_t)y * stride;
        const uint8_t *prev = y > 0 ? row - stride + 1 : rows;
        ok = mr_io_png_unfilter_row(row[0], row + 1, prev, info->row_bytes, info->bpp); // in place
    }
    if (!ok) { // not zlib data of exactly the image's size, or a filter type outside 0-4: libpng decides
        free(rows);
        free(info);
        return 0;
    }
    *rows_out = rows;
    *info_out = info;
    return 1;
}

mr_status mr_io_png_deflate_read(FILE *file, const char *label, int max_dimension, mr_io_raw *raw, int *handled) {
    png_info *info = NULL;
    uint8_t *rows = NULL;
    mr_status status = MR_OK;
    *handled = decode_rows(file, label, max_dimension, &info, &rows, &status);
    if (!*handled || status != MR_OK) return status;
    const int channels = info->colour == 3 ? (info->trns ? 4 : 3) : info->samples + (info->trns != 0);
    const size_t values = (size_t)info->width * info->height * (size_t)channels;
    float *pixels = malloc(values * sizeof *pixels);
    if (pixels == NULL) {
        status = mr_fail(MR_ERR_NOMEM, "%s: out of memory for %lux%lu pixels", label, (unsigned long)info->width,
                         (unsigned long)info->height);
        free(rows);
        free(info);
        return status;
    }
    float lut8[256], pal[256 * 4];
    for (int i = 0; i < 256; i++) lut8[i] = (float)i * (1.0f / 255.0f); // as png_io.c scales
    // libpng keeps 256 palette entries, zero beyond PLTE's, and alpha 255 beyond tRNS's.
    for (int i = 0; i < 256; i++) {
        for (int k = 0; k < 3; k++) pal[4 * i + k] = i < info->palette_size ? lut8[info->palette[i][k]] : 0.0f;
        pal[4 * i + 3] = lut8[i < info->trns ? info->trns_alpha[i] : 255];
    }
    const size_t stride = info->row_bytes + 1, out_row = (size_t)info->width * (size_t)channels;
    for (uint32_t y = 0; y < info->height; y++)
        row_to_floats(info, rows + info->row_bytes + (size_t)y * stride + 1, lut8, pal, pixels + (size_t)y * out_row);
    free(rows);
    raw->width = (int)info->width;
    raw->height = (int)info->height;
    raw->channels = channels;
    raw->encoded = 1;
    raw->bits = info->depth == 16 ? 16 : 8;
    raw->pixels = pixels;
    free(info);
    return MR_OK;
}

mr_status mr_io_png_deflate_read_codes(FILE *file, const char *label, int max_dimension, mr_io_codes *codes,
                                       int *handled) {
    png_info *info = NULL;
    uint8_t *rows = NULL;
    mr_status status = MR_OK;
    *handled = decode_rows(file, label, max_dimension, &info, &rows, &status);
    if (!*handled || status != MR_OK) return status;
    // 8-bit grey, grey + alpha, RGB or RGBA without a tRNS key: the samples are the codes. Others are left to
    // mr_io_png_deflate_read (*handled = 0).
    if (info->depth != 8 || info->colour == 3 || info->trns) {
        *handled = 0;
        free(rows);
        free(info);
        return MR_OK;
    }
    const size_t stride = info->row_bytes + 1;
    for (uint32_t y = 0; y < info->height; y++) // the rows packed together, over the filter bytes
        memmove(rows + (size_t)y * info->row_bytes, rows + info->row_bytes + (size_t)y * stride + 1, info->row_bytes);
    codes->width = (int)info->width;
    codes->height = (int)info->height;
    codes->channels = info->samples;
    codes->codes = rows;
    free(info);
    return MR_OK;
}
