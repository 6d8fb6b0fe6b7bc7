/*
 * io_internal.h — pieces of src/io shared between its C files and the C++ OpenImageIO shim; not installed.
 *
 * Division of labour (the public contract is image_io.h):
 *   image_io.c          argument checks, extension and signature dispatch, channel conversion, sRGB coding,
 *                       quantisation, the PNG structure check before decoding;
 *   png_io.c            PNG decoding and encoding through libpng, and the choice between it and png_deflate.c;
 *   png_deflate.c       PNG decoding and encoding around libdeflate (the default for both);
 *   image_io_oiio.cpp   the only C++: decodes any format into floats, from a file (mr_io_oiio_read) or from
 *                       memory (mr_io_oiio_read_memory), and encodes already quantised 8/16-bit or float buffers
 *                       (mr_io_oiio_write); built as the module libmatremap-oiio.so, which oiio_module.c loads on
 *                       first use and forwards these calls to (OpenImageIO's dependencies cost ~0.4 s of
 *                       start-up, see oiio_module.c);
 *   exr_write.c         EXR encoding through the OpenEXR Core C API (mr_io_exr_write);
 *   atomic_file.c       the temp-file + rename protocol that every write goes through (mr_core.h);
 *   input_file.c        opening a file a user names as an input (mr_core.h);
 *   srgb.c              the IEC 61966-2-1 transfer functions.
 * C and C++ both include this header, so it uses no C-only syntax.
 */
#ifndef MR_IO_INTERNAL_H
#define MR_IO_INTERNAL_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "../mr_core.h"
#include "../mr_status.h"
#include "png_texture.h" /* the part of src/io that gltf/convert.c uses */

#ifdef __cplusplus
extern "C" {
#endif

/* Atomic output files (atomic_file.c) and input files (input_file.c) are core: mr_core.h declares them. */
/* Plots drawn by gnuplot (gnuplot.c): io/gnuplot.h. */

/* ---- what messages call an image ---------------------------------------------------------------------- */

/* A read's messages name what it reads: "image '<path>'" for a file, the caller's name for bytes in memory
 * (mr_img_read_memory). mr_io_file_label: "image '<path>'" into label[MR_IO_LABEL_SIZE] (mr_core.h); returns
 * label. Inline: the OpenImageIO module needs it too. */
static inline const char *mr_io_file_label(char *label, const char *path) {
    snprintf(label, MR_IO_LABEL_SIZE, "image '%s'", path);
    return label;
}

/* ---- sRGB (srgb.c) ------------------------------------------------------------------------------------ */

/* mr_srgb_decode_double and mr_srgb_encode_double are public (image_io.h); mr_srgb8_encode is in png_texture.h. */


/* ---- decoding through OpenImageIO (image_io_oiio.cpp) ----------------------------------------------- */

/* What the shim hands back: the first subimage's data window as interleaved floats with the stored
 * channels reduced to one of four layouts, in this order: grey (1), grey+alpha (2), RGB (3), RGBA (4).
 * `encoded` is 1 when the file stores integers (8/16-bit PNG, JPEG, TIFF, ...), whose values are
 * display-encoded unless the caller says they are data; 0 for floating-point storage (EXR, HDR, float TIFF),
 * which is linear by convention. Alpha is unassociated (oiio:UnassociatedAlpha=1: PNG/TIFF alpha is not
 * premultiplied on read). `pixels` is malloc'ed; free() it. */
typedef struct mr_io_raw {
    int width;
    int height;
    int channels; /* 1..4 as above */
    int encoded;
    int bits;     /* 8 or 16 for 8/16-bit unsigned integer storage (value = code / (2^bits - 1)); else 0 */
    float *pixels;
} mr_io_raw;

/* Decode `path` (which the caller has checked exists and is a readable regular file). Rejects images with a
 * side larger than max_dimension (MR_ERR_FORMAT) before any pixel is decoded. Errors: MR_ERR_FORMAT (not an
 * image, corrupt or truncated, unsupported layout), MR_ERR_NOMEM, MR_ERR_EXTERNAL (anything else OIIO or
 * the C++ runtime threw). Messages name the file. */
mr_status mr_io_oiio_read(const char *path, int max_dimension, mr_io_raw *raw);

/* mr_io_oiio_read by OpenImageIO's reader `format` alone ("openexr", "hdr", "tiff", ...: the caller recognised
 * the file by its signature), which reads the file as it goes: whatever its name, and without trying the other
 * readers when this one refuses it. Same errors. */
mr_status mr_io_oiio_read_as(const char *path, const char *format, int max_dimension, mr_io_raw *raw);

/* mr_io_oiio_read for `size` encoded bytes at `bytes` (an OpenImageIO IOMemReader: nothing touches the disk),
 * decoded by OpenImageIO's reader `format` ("jpeg", "openexr", "hdr", "tiff", ...: the caller recognised it by
 * the bytes' signature; OpenImageIO recognises a file by its extension, which bytes lack). Messages call the
 * image `label`. Same errors; MR_ERR_UNSUPPORTED if that reader cannot read from memory. */
mr_status mr_io_oiio_read_memory(const void *bytes, size_t size, const char *format, const char *label,
                                 int max_dimension, mr_io_raw *raw);

/* An EXR file's structure checked before OpenImageIO opens it (exr_check.c): version 2, not deep; every header
 * attribute's size within the file; channel list, compression and data window present and valid; width and height
 * at most max_dimension; the offset table inside the file and every chunk offset after it. `stream` is the whole
 * file (or the bytes, through fmemopen), at any position; it is left at an unspecified one. MR_ERR_FORMAT naming
 * `label`, the field and the value; MR_ERR_UNSUPPORTED for deep data; MR_ERR_IO if it cannot seek. */
mr_status mr_io_exr_check(FILE *stream, const char *label, int max_dimension);

/* The picture size a GIF, BMP or WebP header declares (`format` as oiio_format_of names it: "gif", "bmp",
 * "webp"; any other passes), from the first `size` bytes at `head` (30 are enough), held against max_dimension
 * before OpenImageIO's reader allocates it at open (canvas_check.c says why). MR_ERR_FORMAT naming `label`, the
 * size and the limit. */
mr_status mr_io_canvas_check(const unsigned char *head, size_t size, const char *format, const char *label,
                             int max_dimension);

/* A JPEG's bytes with their header's marker segments checked (each length within the bytes) and its metadata
 * segments (APP1-APP13, APP15, comments: Exif, ICC, XMP, IPTC) left out, into *out (malloc'ed, the caller's; at
 * most `size` bytes) and *out_size; the scans are copied as they are (jpeg_check.c says why). MR_ERR_FORMAT naming
 * `label` and the byte; MR_ERR_NOMEM. */
mr_status mr_io_jpeg_clean(const unsigned char *bytes, size_t size, const char *label, unsigned char **out,
                           size_t *out_size);

/* Sample types for mr_io_oiio_write. */
typedef enum mr_io_sample {
    MR_IO_U8 = 0,
    MR_IO_U16,
    MR_IO_F32
} mr_io_sample;

/* Encode the interleaved buffer `data` (width*height*channels samples of `sample`, top-left first) with the
 * OpenImageIO writer chosen by the extension of `path`, and write it to `path` atomically. PNG, JPEG and HDR
 * are encoded in memory (an IOVecOutput) and written by mr_atomic_write_bytes, because OpenImageIO 2.4.7's
 * PNG writer turns a failed write (full disk) into a truncated file and success, and its JPEG writer keeps
 * libjpeg's default error handler, which exit()s the process on a write error (both seen with a file-size
 * limit); HDR takes the same path so that only libtiff is trusted with the disk. TIFF is written straight
 * into the temporary file: libtiff reports failed writes, and OIIO 2.4.7's TIFF writer produces an
 * unreadable file through an IOVecOutput set after create(). srgb_tag marks the file as sRGB-encoded (PNG
 * sRGB chunk and the like); jpeg_quality 1..100 is used by JPEG only. Errors name `path`. */
mr_status mr_io_oiio_write(const char *path, int width, int height, int channels, mr_io_sample sample,
                           const void *data, int srgb_tag, int jpeg_quality);

/* ---- PNG (png_io.c: libpng; png_deflate.c: libdeflate) ------------------------------------------------ */

/* mr_io_oiio_read for a PNG, without OpenImageIO: the same layouts and values (png_io.c). */
mr_status mr_io_png_read(const char *path, int max_dimension, mr_io_raw *raw);

/* The same from `file`, open at the PNG's first byte (a file, or bytes in memory through fmemopen) and left open;
 * messages call it `label`. Non-interlaced files decode through libdeflate (png_deflate.c); whatever that decoder
 * does not take (Adam7, anything malformed) through libpng, from the same start (the stream must be seekable). */
mr_status mr_io_png_read_stream(FILE *file, const char *label, int max_dimension, mr_io_raw *raw);

/* The reference decoder: mr_io_png_read_stream through libpng alone (the libdeflate decoder gives the same bit
 * for bit: tests/test_image_io.c compares them). */
mr_status mr_io_png_read_stream_libpng(FILE *file, const char *label, int max_dimension, mr_io_raw *raw);

/* png_deflate.c's decoder: *handled = 1 when it decoded the file into *raw or failed with a status of its own
 * (max_dimension, memory); *handled = 0 (status MR_OK, *raw untouched) when the file is one it leaves to libpng,
 * the stream then somewhere after its start. */
mr_status mr_io_png_deflate_read(FILE *file, const char *label, int max_dimension, mr_io_raw *raw, int *handled);

/* mr_io_png_encode (png_texture.h) written to `path` atomically. Errors name `path`. */
mr_status mr_io_png_write(const char *path, int width, int height, int channels, int bits, const void *data,
                          int srgb_tag, const mr_io_png_settings *settings);

/* png_deflate.c's encoder behind mr_io_png_encode (which checks the arguments first). */
mr_status mr_io_png_deflate_encode(const char *name, int width, int height, int channels, int bits, const void *data,
                                   int srgb_tag, const mr_io_png_settings *settings, unsigned char **bytes,
                                   size_t *size);

/* A big-endian 32-bit value (PNG's byte order, §7.1). */
uint32_t mr_io_be32(const unsigned char *p);

/* Undo filter `type` (§9: 0-4) of one scanline x[n] in place, `prev` the unfiltered line above (zeros above the
 * first), bpp its bytes per pixel (at least 1); 0 for an unknown type (png_deflate.c). */
int mr_io_png_unfilter_row(int type, uint8_t *x, const uint8_t *prev, size_t n, size_t bpp);

/* Write a PNG chunk (§5.3: length, type, data, CRC of type and data) at `at`, which has 12 + length bytes; returns
 * the byte after it (png_deflate.c). */
unsigned char *mr_io_png_put_chunk(unsigned char *at, const char *type, const void *data, size_t length);

/* Paletted PNGs (png_palette.c) and mr_io_decode_code: png_texture.h. */

/* ---- EXR through OpenEXR Core (exr_write.c) ---------------------------------------------------------- */

/* Write interleaved linear floats (channels 1, 3 or 4; named Y or R,G,B(,A)) as a single-part scanline EXR
 * with ZIP compression, FLOAT (half = 0) or HALF (half = 1) channels, into `file_path`. Errors name
 * `name_for_errors` (the target, not the temporary file). */
mr_status mr_io_exr_write(const char *name_for_errors, const char *file_path, int width, int height,
                          int channels, const float *pixels, int half);

#ifdef __cplusplus
}
#endif

#endif /* MR_IO_INTERNAL_H */
