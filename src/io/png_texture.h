/*
 * png_texture.h — PNG textures at the level of their stored codes and palettes: what glTF's texture conversion
 * (gltf/convert.c) reads and writes without decoding to floats. The image I/O module's interface to the rest of the
 * library: not installed and not public (image_io.h is). src/io's own files get it through io_internal.h, whose other
 * declarations stay private to src/io.
 * C and C++ both include it, so it uses no C-only syntax.
 */
#ifndef MR_IO_PNG_TEXTURE_H
#define MR_IO_PNG_TEXTURE_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "../mr_status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The largest width or height an image read accepts unless told otherwise (mr_img_read_options.max_dimension 0;
 * the PNG readers of glTF conversions): 16384, a 4 GiB RGBA float image. */
#define MR_IO_MAX_DIMENSION_DEFAULT 16384

/* ---- 8-bit sRGB codes (srgb.c) --------------------------------------------------------------------------- */

/* The 8-bit sRGB code the image writer stores for a linear value (clamped to [0, 1], NaN -> 0): exactly
 * floor(clamp(mr_linear_to_srgb(v)) * 255 + 0.5), by table (srgb.c). Call mr_srgb8_init() once before (thread-safe,
 * idempotent). */
void mr_srgb8_init(void);
unsigned char mr_srgb8_encode(float linear);

/* ---- PNG codes in and out (png_deflate.c) ---------------------------------------------------------------- */

/* An 8-bit image's stored samples, undecoded: what a texture conversion reads (a quarter of the floats' memory). */
typedef struct mr_io_codes {
    int width, height;
    int channels;   /* the stored layout: 1 grey, 2 grey + alpha, 3 RGB, 4 RGBA */
    uint8_t *codes; /* width * height * channels, top-left first; malloc'ed, the caller frees it */
} mr_io_codes;

/* png_deflate.c's decoder (io_internal.h, mr_io_png_deflate_read) giving the codes of an 8-bit non-palette PNG
 * without a tRNS key, from `file` open at its first byte (*handled = 1, or a status of its own); *handled = 0 for
 * any other PNG (then decode it to floats). mr_io_decode_code gives a code's value as the readers decode it. */
mr_status mr_io_png_deflate_read_codes(FILE *file, const char *label, int max_dimension, mr_io_codes *codes,
                                       int *handled);

/* How the PNG writer compresses. `filters` is a set of PNG filter types (§9 of the PNG spec; the bits of libpng's
 * PNG_FILTER_*): one type filters every row; several choose per row the one whose bytes, read as signed, have
 * the smallest sum of absolute values (libpng's heuristic; MR_IO_PNG_ALL_FILTERS: all five). With libpng = 0
 * the writer is png_deflate.c's, `level` libdeflate's 0-12 (1 fastest, 6 its default, 12 smallest); with
 * libpng = 1 it is libpng + zlib (png_io.c, the writer before libdeflate, kept for comparisons), level zlib's 0-9.
 * MR_IO_PNG_DEFAULT is the default of mr_img_write and of glTF conversions (docs/performance.md, "PNG read and
 * write": the fastest setting whose files are at most 15 % larger than OpenImageIO's, zlib level 6). */
typedef struct mr_io_png_settings {
    int level;
    int filters;
    int libpng;
} mr_io_png_settings;
#define MR_IO_PNG_FILTER_NONE 0x08  /* PNG_FILTER_NONE of png.h (this header does not include it) */
#define MR_IO_PNG_FILTER_SUB 0x10
#define MR_IO_PNG_FILTER_UP 0x20
#define MR_IO_PNG_FILTER_AVG 0x40
#define MR_IO_PNG_FILTER_PAETH 0x80
#define MR_IO_PNG_ALL_FILTERS 0xf8
#define MR_IO_PNG_DEFAULT {1, MR_IO_PNG_ALL_FILTERS, 0}

/* Encode `data` (width*height*channels unsigned samples of `bits` 8 or 16, host order, top-left first; channels
 * 1 grey, 2 grey + alpha, 3 RGB, 4 RGBA) as a PNG in memory: *bytes (malloc'ed, the caller frees it) and *size;
 * srgb_tag adds the sRGB, gAMA and cHRM chunks; `name` names the image in errors. */
mr_status mr_io_png_encode(const char *name, int width, int height, int channels, int bits, const void *data,
                           int srgb_tag, const mr_io_png_settings *settings, unsigned char **bytes, size_t *size);

/* ---- Paletted PNG (png_palette.c) --------------------------------------------------------------------- */

/* A non-interlaced paletted PNG taken apart: its header, palette, index stream and index histogram. */
typedef struct mr_io_png_palette {
    int width, height, bit_depth;  /* bit depth 1, 2, 4 or 8 */
    unsigned char ihdr[13];        /* the IHDR data, copied into the rewritten file */
    int entries;                   /* PLTE entries, 1 .. 2^bit_depth */
    unsigned char rgb[256][3];     /* PLTE */
    unsigned char alpha[256];      /* tRNS, 255 past it or without one */
    int has_alpha;                 /* a tRNS chunk was present */
    size_t counts[256];            /* texels per entry */
    unsigned char *idat;           /* the IDAT data, concatenated (owned: mr_io_png_palette_free) */
    size_t idat_size;
} mr_io_png_palette;

/* 1 when `bytes` start as a non-interlaced paletted PNG (signature and IHDR only: a sniff, not a check). */
int mr_io_png_is_paletted(const unsigned char *bytes, size_t size);

/* Take the PNG in bytes[size] apart: every chunk's length and CRC checked, the index stream inflated once for the
 * histogram. MR_ERR_FORMAT naming `label` for anything else or anything broken; MR_ERR_NOMEM. */
mr_status mr_io_png_palette_read(const unsigned char *bytes, size_t size, const char *label, mr_io_png_palette *out);
void mr_io_png_palette_free(mr_io_png_palette *p);

/* The PNG of p's header and index stream under the palette rgb[p->entries] and alpha (NULL: opaque; tRNS written up
 * to the last entry that is not 255), with the sRGB chunks the writer adds when srgb_tag is set; *bytes is malloc'ed
 * (the caller frees it). */
mr_status mr_io_png_palette_write(const mr_io_png_palette *p, const unsigned char rgb[][3],
                                  const unsigned char *alpha, int srgb_tag, unsigned char **bytes, size_t *size);

/* The value the image reader gives a stored integer code of `bits` (8 or 16) bits: sRGB-decoded for colour (srgb 1)
 * or code / (2^bits - 1) as data, exactly as mr_img_read_stored computes it. */
float mr_io_decode_code(unsigned code, int bits, int srgb);

#ifdef __cplusplus
}
#endif

#endif /* MR_IO_PNG_TEXTURE_H */
