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
 *   atomic_file.c       the temp-file + rename protocol that every write goes through;
 *   srgb.c              the IEC 61966-2-1 transfer functions.
 * C and C++ both include this header, so it uses no C-only syntax.
 */
#ifndef MR_IO_INTERNAL_H
#define MR_IO_INTERNAL_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "../mr_status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- atomic output files (atomic_file.c) -------------------------------------------------------------
 * Protocol (after redis' rdbSave): mr_atomic_begin() creates an empty, exclusive temporary file beside the
 * target, named "<target>.tmp.<pid>.<n>" (same directory, so rename(2) cannot cross file systems); the writer
 * fills tmp_path; mr_atomic_commit() fsyncs it and renames it over the target; on any failure the caller
 * calls mr_atomic_abort(), which unlinks the temporary file. A target that existed before is never opened
 * for writing, so a failed write leaves it untouched. */
typedef struct mr_atomic_file {
    char tmp_path[4096]; /* the temporary file to write */
    const char *target;  /* borrowed: the final path */
    int active;          /* 1 between a successful begin and commit/abort */
} mr_atomic_file;

/* Create the temporary file for `target`. MR_ERR_IO (naming the target and the reason, e.g. a missing or
 * unwritable directory) or MR_ERR_INVALID_ARG (path too long). On failure nothing is left on disk. */
mr_status mr_atomic_begin(const char *target, mr_atomic_file *file);

/* fsync the finished temporary file and rename it to the target. On failure the temporary file is removed
 * (the caller need not call mr_atomic_abort, though doing so is harmless). */
mr_status mr_atomic_commit(mr_atomic_file *file);

/* The whole protocol for a file already encoded in memory: begin, fwrite + fflush + fclose (every result
 * checked), commit; abort on any failure. Errors (MR_ERR_IO) name the target and the system's reason. */
mr_status mr_atomic_write_bytes(const char *target, const void *bytes, size_t size);

/* Remove the temporary file (if still there). Safe to call twice, and after a successful commit (no-op).
 * Preserves errno and the recorded last-error message. */
void mr_atomic_abort(mr_atomic_file *file);

/* A text file written through stdio under the protocol: mr_atomic_open_text begins and opens the temporary file
 * for writing (*out; on failure NULL and nothing left: mr_atomic_begin's errors, or MR_ERR_IO "cannot write
 * 'TARGET': REASON"); mr_atomic_close_text closes it and checks every write (the stream's error indicator, the
 * last flush): MR_OK with the file still to commit (or abort), or MR_ERR_IO "cannot write 'TARGET': REASON" with
 * the temporary file removed. Messages as the command line's outputs have always said them. */
mr_status mr_atomic_open_text(const char *target, mr_atomic_file *file, FILE **out);
mr_status mr_atomic_close_text(FILE *f, mr_atomic_file *file);

/* Commit a set of prepared files all or none: every active file of files[0..n) in order; when one fails, the files
 * of the set committed before it are removed, and so are written[0..n_written) (outputs the caller committed just
 * before, e.g. the file the set goes with), the rest aborted, and MR_ERR_IO is returned with the commit's message
 * followed by " (the outputs written before it removed)". Inactive files (aborted, or never begun) are skipped. */
mr_status mr_atomic_commit_set(mr_atomic_file *files, int n, const char *const *written, int n_written);

/* ---- plots drawn by gnuplot (gnuplot.c) -------------------------------------------------------------------
 * A plot is a convenience beside the data it draws: the script (printf-style) is piped to "gnuplot" (popen, its
 * stderr discarded), which draws into the files the script names (the callers' temporary files). *drawn is 1 when
 * gnuplot ran and succeeded, 0 when it is missing or failed (the caller then aborts the pictures and keeps the
 * data). MR_ERR_IO "cannot write the plot script to gnuplot: REASON" only when writing to a gnuplot that started
 * failed. */
#if defined(__GNUC__)
__attribute__((format(printf, 2, 3)))
#endif
mr_status mr_gnuplot_draw(int *drawn, const char *script, ...);

/* ---- input files (input_file.c) ---------------------------------------------------------------------------
 * Every file a reader of src/io or gltf/ opens because a user (or a file the user gave) named it goes through
 * mr_io_open_input: only a regular file is read. A folder, a FIFO, a device (/dev/zero) or a socket is refused
 * by name before a byte is read, where fopen would open a folder (whose size, asked by seeking, is 2^63 - 1),
 * block on a FIFO or read a device without end. */

/* Open `path` for reading as a stdio stream (*out; the caller fcloses it) if it is a regular file of at most
 * max_bytes bytes (0: any size); *size (may be NULL) receives its size. Failures, with messages "<label>: <why>"
 * (just "<why>" when label is NULL): MR_ERR_IO "cannot open: <system reason>", "is a directory", "is not a
 * regular file (a FIFO)" (or a character device, a block device, a socket); MR_ERR_FORMAT "<n> bytes, more than
 * the limit of <max_bytes>". Never blocks: the file is opened with O_NONBLOCK and checked on its descriptor. */
mr_status mr_io_open_input(const char *path, const char *label, uint64_t max_bytes, FILE **out, uint64_t *size);

/* The largest width or height an image read accepts unless told otherwise (mr_img_read_options.max_dimension 0;
 * the PNG readers of glTF conversions): 16384, a 4 GiB RGBA float image. */
#define MR_IO_MAX_DIMENSION_DEFAULT 16384

/* ---- what messages call an image ---------------------------------------------------------------------- */

/* A read's messages name what it reads: "image '<path>'" for a file, the caller's name for bytes in memory
 * (mr_img_read_memory). Longer labels are cut to the size of mr_last_error's buffer, which would cut them anyway. */
#define MR_IO_LABEL_SIZE 1024

/* "image '<path>'" into label[MR_IO_LABEL_SIZE]; returns label. Inline: the OpenImageIO module needs it too. */
static inline const char *mr_io_file_label(char *label, const char *path) {
    snprintf(label, MR_IO_LABEL_SIZE, "image '%s'", path);
    return label;
}

/* ---- sRGB (srgb.c) ------------------------------------------------------------------------------------ */

/* mr_srgb_to_linear in double, not rounded to float (mr_img_half_step's differences of decodes need it). */
double mr_srgb_decode_double(double encoded);
/* mr_linear_to_srgb in double (the direct remap quantises colours in sRGB-encoded units, src/remap/direct.h). */
double mr_srgb_encode_double(double linear);

/* The 8-bit sRGB code the image writer stores for a linear value (clamped to [0, 1], NaN -> 0): exactly
 * floor(clamp(mr_linear_to_srgb(v)) * 255 + 0.5), by table (srgb.c). Call mr_srgb8_init() once before (thread-safe,
 * idempotent). */
void mr_srgb8_init(void);
unsigned char mr_srgb8_encode(float linear);

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

/* An 8-bit image's stored samples, undecoded: what a texture conversion reads (a quarter of the floats' memory). */
typedef struct mr_io_codes {
    int width, height;
    int channels;   /* the stored layout: 1 grey, 2 grey + alpha, 3 RGB, 4 RGBA */
    uint8_t *codes; /* width * height * channels, top-left first; malloc'ed, the caller frees it */
} mr_io_codes;

/* The same decoder, giving the codes of an 8-bit non-palette PNG without a tRNS key (*handled = 1, or a status of
 * its own); *handled = 0 for any other PNG (then decode it to floats). mr_io_decode_code gives a code's value as
 * the readers decode it. */
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
 * 1 grey, 2 grey + alpha, 3 RGB, 4 RGBA) as a PNG in memory and write it to `path` atomically; srgb_tag adds the
 * sRGB, gAMA and cHRM chunks. Errors name `path`. */
mr_status mr_io_png_write(const char *path, int width, int height, int channels, int bits, const void *data,
                          int srgb_tag, const mr_io_png_settings *settings);

/* The same encoding into memory: *bytes (malloc'ed, the caller frees it) and *size; `name` names the image in
 * errors. */
mr_status mr_io_png_encode(const char *name, int width, int height, int channels, int bits, const void *data,
                           int srgb_tag, const mr_io_png_settings *settings, unsigned char **bytes, size_t *size);

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
