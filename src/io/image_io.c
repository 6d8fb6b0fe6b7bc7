/*
 * image_io.c — mr_img_read / mr_img_write (contract in image_io.h; internal layout in io_internal.h).
 *
 * Reading: check the path (missing, a directory, unreadable: MR_ERR_IO naming it) and, for PNG, the chunk
 * structure; decode a PNG through png_io.c (libdeflate, libpng) and anything else through the OpenImageIO shim,
 * then convert the channel layout and sRGB-decode integer-stored colour (IEC 61966-2-1). Bytes in memory
 * (mr_img_read_memory) take the same path from the chunk check on: fmemopen gives the check and the decoder the
 * same stdio stream a file gives them, and OpenImageIO reads them through an IOMemReader.
 * Writing: check every option before touching the disk, convert to the file's sample type (sRGB-encode after
 * clamping to [0,1], then round to nearest), and write through the atomic temp-file protocol of
 * atomic_file.c: OpenEXR Core writes .exr into the temporary file, png_io.c encodes PNG, OpenImageIO every other
 * format (io_internal.h says how each reaches the disk).
 */
#include <ctype.h>
#include <errno.h>
#include <float.h>
#include <libdeflate.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../mr_internal.h"
#include "image_io.h"
#include "io_internal.h"

#define DEFAULT_MAX_DIMENSION MR_IO_MAX_DIMENSION_DEFAULT
#define DEFAULT_JPEG_QUALITY 95

typedef enum file_format { FORMAT_EXR, FORMAT_HDR, FORMAT_PNG, FORMAT_JPEG, FORMAT_TIFF, FORMAT_UNKNOWN } file_format;

static const char *const format_names[] = {"EXR", "Radiance HDR", "PNG", "JPEG", "TIFF", "?"};

/* The format named by the extension of `path` (case-insensitive). */
static file_format format_of(const char *path) {
    const char *slash = strrchr(path, '/');
    const char *dot = strrchr(path, '.');
    if (dot == NULL || (slash != NULL && dot < slash)) return FORMAT_UNKNOWN;
    char ext[8];
    size_t n = strlen(dot + 1);
    if (n == 0 || n >= sizeof ext) return FORMAT_UNKNOWN;
    for (size_t i = 0; i <= n; i++) ext[i] = (char)tolower((unsigned char)dot[1 + i]);
    if (strcmp(ext, "exr") == 0) return FORMAT_EXR;
    if (strcmp(ext, "hdr") == 0) return FORMAT_HDR;
    if (strcmp(ext, "png") == 0) return FORMAT_PNG;
    if (strcmp(ext, "jpg") == 0 || strcmp(ext, "jpeg") == 0) return FORMAT_JPEG;
    if (strcmp(ext, "tif") == 0 || strcmp(ext, "tiff") == 0) return FORMAT_TIFF;
    return FORMAT_UNKNOWN;
}

/* ---- reading ---------------------------------------------------------------------------------------- */

static uint32_t be32(const unsigned char *p) {
    return ((uint32_t)p[0] << 24) | ((uint32_t)p[1] << 16) | ((uint32_t)p[2] << 8) | (uint32_t)p[3];
}

/* The most deflate expands: 258 bytes from one 2-bit code (1032 times), as png_deflate.c counts it. */
#define DEFLATE_MAX_RATIO 1032

/* If the open stream `f` is a PNG (by its signature, whatever the extension: *is_png says), walk its chunk
 * structure (ISO/IEC 15948 section 5: length, type, data, CRC) up to IEND: IHDR first, every length inside the
 * file, every CRC right. Why here and not in the decoder: libpng's messages (png_io.c decodes with it what
 * png_deflate.c does not take, and png_deflate.c leaves it every malformed file) do not say where a file went wrong
 * (and OpenImageIO's PNG reader, which a PNG no longer reaches, printed them on stderr). This catches truncation
 * and any corruption that a CRC detects (all but deliberately crafted files) with a message saying where, before
 * any decoder sees the file. It also holds the sizes IHDR claims against what the file can hold, before a decoder
 * allocates for them: each side at most max_dimension, and the IDAT chunks together at least 1/1032 of the image's
 * samples (deflate's largest expansion), so a file of a few bytes claiming 16384 x 16384 is refused as truncated
 * instead of making libpng allocate a gigabyte of rows it will never fill. */
static mr_status check_png_structure(const char *label, FILE *f, int max_dimension, int *is_png) {
    static const unsigned char signature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    static const int samples_of[7] = {1, 0, 3, 1, 2, 0, 4}; // per colour type (IHDR, §11.2.2); 0: invalid
    unsigned char head[8];
    *is_png = fread(head, 1, 8, f) == 8 && memcmp(head, signature, 8) == 0;
    if (!*is_png) return MR_OK;
    unsigned char buf[16384];
    long offset = 8;
    uint64_t width = 0, height = 0, sample_bits = 0, idat_bytes = 0;
    for (int chunk = 0;; chunk++) {
        size_t got = fread(head, 1, 8, f);
        if (got != 8)
            return mr_fail(MR_ERR_FORMAT, "%s: truncated PNG: the file ends at byte %ld, before the IEND chunk",
                           label, offset + (long)got);
        const uint32_t length = be32(head);
        char type[5] = {(char)head[4], (char)head[5], (char)head[6], (char)head[7], '\0'};
        for (int i = 0; i < 4; i++)
            if (!isalpha((unsigned char)type[i]))
                return mr_fail(MR_ERR_FORMAT, "%s: corrupt PNG: invalid chunk type at byte %ld", label, offset);
        if (length > 0x7fffffffu)
            return mr_fail(MR_ERR_FORMAT, "%s: corrupt PNG: chunk '%s' at byte %ld claims %lu bytes", label,
                           type, offset, (unsigned long)length);
        if (chunk == 0 && strcmp(type, "IHDR") != 0)
            return mr_fail(MR_ERR_FORMAT, "%s: corrupt PNG: the first chunk is '%s', not IHDR", label, type);
        if (chunk == 0 && length != 13)
            return mr_fail(MR_ERR_FORMAT, "%s: corrupt PNG: IHDR holds %lu bytes, not 13", label,
                           (unsigned long)length);
        uint32_t crc = libdeflate_crc32(0, head + 4, 4); // CRC-32 of ISO/IEC 15948:2003, Annex D
        for (uint32_t left = length; left > 0;) {
            size_t want = left < sizeof buf ? left : sizeof buf;
            size_t n = fread(buf, 1, want, f);
            if (n == 0) {
                if (ferror(f))
                    return mr_fail(MR_ERR_IO, "%s: read error at byte %ld", label,
                                   offset + 8 + (long)(length - left));
                return mr_fail(MR_ERR_FORMAT,
                               "%s: truncated PNG: chunk '%s' at byte %ld needs %lu data bytes, the file ends "
                               "after %lu",
                               label, type, offset, (unsigned long)length, (unsigned long)(length - left));
            }
            crc = libdeflate_crc32(crc, buf, n);
            left -= (uint32_t)n;
        }
        unsigned char stored[4];
        if (fread(stored, 1, 4, f) != 4)
            return mr_fail(MR_ERR_FORMAT, "%s: truncated PNG: chunk '%s' at byte %ld lacks its CRC", label, type,
                           offset);
        if (crc != be32(stored))
            return mr_fail(MR_ERR_FORMAT, "%s: corrupt PNG: CRC mismatch in chunk '%s' at byte %ld", label, type,
                           offset);
        if (chunk == 0) { // buf holds the 13 bytes of IHDR: width, height, bit depth, colour type, ...
            width = be32(buf);
            height = be32(buf + 4);
            const unsigned depth = buf[8], colour = buf[9];
            if (width == 0 || height == 0 || width > 0x7fffffffu || height > 0x7fffffffu)
                return mr_fail(MR_ERR_FORMAT, "%s: corrupt PNG: IHDR gives %llux%llu pixels", label,
                               (unsigned long long)width, (unsigned long long)height);
            if (width > (uint64_t)max_dimension || height > (uint64_t)max_dimension)
                return mr_fail(MR_ERR_FORMAT, "%s: %llux%llu pixels exceeds the maximum dimension %d", label,
                               (unsigned long long)width, (unsigned long long)height, max_dimension);
            if (colour > 6 || samples_of[colour] == 0 || depth == 0 || depth > 16)
                return mr_fail(MR_ERR_FORMAT, "%s: corrupt PNG: IHDR gives colour type %u at %u bits", label, colour,
                               depth);
            sample_bits = width * height * (uint64_t)samples_of[colour] * depth; // < 2^62: both sides <= 2^31
        }
        if (strcmp(type, "IDAT") == 0)
            idat_bytes += length;
        offset += 12 + (long)length;
        if (strcmp(type, "IEND") == 0)
            break;
    }
    // The image data is at least sample_bits / 8 bytes (more with filter bytes and Adam7 passes), of which deflate
    // makes at most DEFLATE_MAX_RATIO from each compressed byte (plus the zlib header and checksum, 6 bytes).
    if (idat_bytes < 6 || (idat_bytes - 6) * DEFLATE_MAX_RATIO < sample_bits / 8)
        return mr_fail(MR_ERR_FORMAT,
                       "%s: truncated PNG: IHDR claims %llux%llu pixels (at least %llu bytes of image data), but its "
                       "IDAT chunks hold %llu compressed bytes, which inflate to at most %llu",
                       label, (unsigned long long)width, (unsigned long long)height,
                       (unsigned long long)(sample_bits / 8), (unsigned long long)idat_bytes,
                       (unsigned long long)(idat_bytes < 6 ? 0 : (idat_bytes - 6) * DEFLATE_MAX_RATIO));
    return MR_OK;
}

/* sRGB-decode one stored value. For 8/16-bit storage (max_code 255 or 65535) the integer code is recovered
 * first, so the result is exactly the decode of code / max_code whichever way OIIO scaled it to float; `lut`
 * (or NULL) holds the decodes of every code. */
static float decode_value(float v, const float *lut, int bits, double max_code) {
    if (bits != 8 && bits != 16) return mr_srgb_to_linear(v);
    const int code = (int)(mr_clampd(v, 0.0, 1.0) * max_code + 0.5);
    return lut != NULL ? lut[code] : mr_io_decode_code((unsigned)code, bits, 1);
}

float mr_io_decode_code(unsigned code, int bits, int srgb) {
    const double max_code = bits == 16 ? 65535.0 : 255.0;
    // Data: the decoders' own scaling (png_io.c and png_deflate.c multiply by 1 / max_code computed in float).
    if (!srgb) return (float)code * (bits == 16 ? 1.0f / 65535.0f : 1.0f / 255.0f);
    return mr_srgb_to_linear((float)((double)code / max_code));
}

/* Fill `image` (already created with its channel count) from the raw layout (grey, grey+alpha, RGB, RGBA); `image`
 * may be the raw buffer itself when the channel counts match (each pixel is read before it is written).
 * Returns 0 on allocation failure. For 8/16-bit files with more values than codes, the decodes of all codes
 * are tabulated once (pow() per value would dominate reading a large PNG). */
static int convert_channels(const mr_io_raw *raw, mr_image *image, int decode_srgb) {
    const size_t count = (size_t)raw->width * (size_t)raw->height;
    const int in_ch = raw->channels, out_ch = image->channels;
    const int in_alpha = in_ch == 2 || in_ch == 4; /* alpha is the last stored channel */
    const int in_colour = in_alpha ? in_ch - 1 : in_ch; /* 1 (grey) or 3 (RGB) */
    float *lut = NULL;
    const double max_code = raw->bits == 8 ? 255.0 : 65535.0;
    if (decode_srgb && (raw->bits == 8 || raw->bits == 16) && count * (size_t)in_colour > ((size_t)1 << raw->bits)) {
        const size_t codes = (size_t)1 << raw->bits;
        lut = malloc(codes * sizeof(float));
        if (lut == NULL) return 0;
        for (size_t q = 0; q < codes; q++) lut[q] = mr_io_decode_code((unsigned)q, raw->bits, 1);
    }
    for (size_t p = 0; p < count; p++) {
        const float *src = raw->pixels + p * (size_t)in_ch;
        float *dst = image->pixels + p * (size_t)out_ch;
        float colour[3];
        if (in_colour == 1) {
            colour[0] = decode_srgb ? decode_value(src[0], lut, raw->bits, max_code) : src[0];
            colour[1] = colour[2] = colour[0];
        } else {
            for (int c = 0; c < 3; c++)
                colour[c] = decode_srgb ? decode_value(src[c], lut, raw->bits, max_code) : src[c];
        }
        float alpha = in_alpha ? src[in_ch - 1] : 1.0f;
        if (out_ch == 1) {
            dst[0] = colour[0];
        } else {
            dst[0] = colour[0];
            dst[1] = colour[1];
            dst[2] = colour[2];
            if (out_ch == 4) dst[3] = alpha;
        }
    }
    free(lut);
    return 1;
}

/* The read options with their defaults filled in (max_dimension 0 -> the default); messages name `label`. */
static mr_status read_options(const char *label, const mr_img_read_options *opts, mr_img_read_options *o) {
    const mr_img_read_options defaults = {MR_IMG_COLOR, 0, 0};
    *o = opts != NULL ? *opts : defaults;
    if (o->encoding != MR_IMG_COLOR && o->encoding != MR_IMG_DATA)
        return mr_fail(MR_ERR_INVALID_ARG, "%s: unknown encoding %d (valid: MR_IMG_COLOR, MR_IMG_DATA)", label,
                       (int)o->encoding);
    if (o->channels != 0 && o->channels != 1 && o->channels != 3 && o->channels != 4)
        return mr_fail(MR_ERR_INVALID_ARG, "%s: %d channels requested (valid: 0 = as stored, 1, 3, 4)", label,
                       o->channels);
    if (o->max_dimension < 0)
        return mr_fail(MR_ERR_INVALID_ARG, "%s: max_dimension %d must be >= 0 (0 = %d)", label, o->max_dimension,
                       DEFAULT_MAX_DIMENSION);
    if (o->max_dimension == 0) o->max_dimension = DEFAULT_MAX_DIMENSION;
    return MR_OK;
}

/* OpenImageIO's reader for encoded bytes, by their signature ("" if none matches). A file needs none of this:
 * OpenImageIO recognises it by its extension and, failing that, by trying every reader, which bytes in memory
 * cannot afford (some readers print when they fail). */
static const char *oiio_format_of(const unsigned char *bytes, size_t size) {
    static const struct {
        const char *magic;
        size_t length, offset;
        const char *format;
    } signatures[] = {
        {"\xff\xd8\xff", 3, 0, "jpeg"}, {"\x76\x2f\x31\x01", 4, 0, "openexr"}, {"#?", 2, 0, "hdr"},
        {"II*\0", 4, 0, "tiff"}, {"MM\0*", 4, 0, "tiff"}, {"WEBP", 4, 8, "webp"} /* after "RIFF" and a size */,
        {"GIF8", 4, 0, "gif"}, {"BM", 2, 0, "bmp"},
    };
    for (size_t i = 0; i < sizeof signatures / sizeof signatures[0]; i++)
        if (size >= signatures[i].offset + signatures[i].length &&
            memcmp(bytes + signatures[i].offset, signatures[i].magic, signatures[i].length) == 0)
            return signatures[i].format;
    return "";
}

/* The most bytes a JPEG file may have: it is read whole to have its header cleaned (jpeg_check.c). A JPEG of
 * 16384 x 16384 pixels (the default max_dimension) at quality 100 is about 200 MB. */
#define MAX_JPEG_FILE_BYTES (1L << 30)

/* The whole of `stream` (a file's, at most `limit` bytes) into *out (malloc'ed, the caller's) and *out_size. */
static mr_status read_whole_stream(FILE *stream, const char *label, long limit, unsigned char **out,
                                   size_t *out_size) {
    long length;
    if (fseek(stream, 0, SEEK_END) != 0 || (length = ftell(stream)) < 0 || fseek(stream, 0, SEEK_SET) != 0)
        return mr_fail(MR_ERR_IO, "%s: cannot seek in the file", label);
    if (length > limit)
        return mr_fail(MR_ERR_FORMAT, "%s: %ld bytes, more than the %ld a JPEG file may have (it is read whole)", label,
                       length, limit);
    unsigned char *whole = malloc(length ? (size_t)length : 1);
    if (whole == NULL) return mr_fail(MR_ERR_NOMEM, "%s: out of memory for %ld bytes", label, length);
    if (fread(whole, 1, (size_t)length, stream) != (size_t)length) {
        free(whole);
        return mr_fail(MR_ERR_IO, "%s: read error", label);
    }
    *out = whole;
    *out_size = (size_t)length;
    return MR_OK;
}

/* The read itself, shared by a file (path) and bytes in memory (path NULL, bytes and size): `stream` is open at
 * the start of either and is closed here; `label` is what messages call the image; *o has its defaults. */
static mr_status read_stream(const char *path, const unsigned char *bytes, size_t size, FILE *stream,
                             const char *label, const mr_img_read_options *o, mr_image **out, mr_img_stored *stored) {
    int is_png = 0;
    mr_io_raw raw = {0, 0, 0, 0, 0, NULL};
    unsigned char *whole = NULL, *clean = NULL; /* a file's bytes; a JPEG's with its header cleaned */
    size_t whole_size = 0, clean_size = 0;
    const char *format = "";
    mr_status status = check_png_structure(label, stream, o->max_dimension, &is_png);
    // PNG (by its signature: nearly every glTF texture) through png_io.c; the rest through the OpenImageIO module,
    // loaded on first use, by the reader their signature names (a file named for another format is still read),
    // and by that reader alone: OpenImageIO never tries its other readers on a file the named one refuses (on a
    // corrupt .hdr it tried them all, camera raw included: 3 ms each). A file is read as the reader goes, except a
    // JPEG, whose header is rewritten in memory first.
    if (status == MR_OK && is_png) {
        rewind(stream);
        status = mr_io_png_read_stream(stream, label, o->max_dimension, &raw);
    } else if (status == MR_OK) {
        unsigned char head[32];
        rewind(stream);
        const size_t head_size = fread(head, 1, sizeof head, stream);
        format = oiio_format_of(head, head_size);
        // EXR: the header's sizes checked before OpenEXR trusts them (exr_check.c says why); GIF, BMP and WebP:
        // the picture's declared size, which their readers allocate when they open it (canvas_check.c).
        if (strcmp(format, "openexr") == 0)
            status = mr_io_exr_check(stream, label, o->max_dimension);
        else
            status = mr_io_canvas_check(head, head_size, format, label, o->max_dimension);
        // JPEG: its header rewritten without the metadata OpenImageIO would parse (jpeg_check.c says why).
        if (status == MR_OK && strcmp(format, "jpeg") == 0) {
            if (path != NULL) status = read_whole_stream(stream, label, MAX_JPEG_FILE_BYTES, &whole, &whole_size);
            if (whole != NULL) bytes = whole, size = whole_size;
            if (status == MR_OK) status = mr_io_jpeg_clean(bytes, size, label, &clean, &clean_size);
            if (status == MR_OK) bytes = clean, size = clean_size;
        }
    }
    fclose(stream);
    if (status == MR_OK && !is_png) {
        if (format[0] == '\0' && path != NULL) {
            status = mr_io_oiio_read(path, o->max_dimension, &raw);
        } else if (format[0] == '\0') {
            status = mr_fail(MR_ERR_FORMAT, "%s: not an image this reader knows from memory (by its first bytes: PNG, "
                             "JPEG, EXR, Radiance HDR, TIFF, WebP, GIF or BMP)", label);
        } else if (path != NULL && bytes == NULL) {
            status = mr_io_oiio_read_as(path, format, o->max_dimension, &raw);
        } else {
            status = mr_io_oiio_read_memory(bytes, size, format, label, o->max_dimension, &raw);
            // A reader that cannot read from memory reads the file.
            if (status == MR_ERR_UNSUPPORTED && path != NULL)
                status = mr_io_oiio_read_as(path, format, o->max_dimension, &raw);
        }
    }
    free(whole);
    free(clean);
    if (status != MR_OK) return status;

    int out_ch = o->channels;
    if (out_ch == 0) out_ch = raw.channels == 1 ? 1 : (raw.channels == 3 ? 3 : 4);
    if (out_ch == 1 && raw.channels >= 3) {
        free(raw.pixels);
        return mr_fail(MR_ERR_FORMAT, "%s: holds RGB%s colour but 1 channel was requested (convert to grey explicitly)",
                       label, raw.channels == 4 ? "A" : "");
    }
    mr_image *image = NULL;
    if (out_ch == raw.channels) {
        // The same layout: converted in place and the decoder's buffer adopted (one copy of a 2048² texture, not
        // two, at the peak; convert_channels reads each pixel before writing it).
        image = malloc(sizeof *image);
        if (image != NULL) *image = (mr_image){raw.width, raw.height, out_ch, raw.pixels};
        status = image != NULL ? MR_OK : mr_fail(MR_ERR_NOMEM, "out of memory");
    } else {
        status = mr_image_create(raw.width, raw.height, out_ch, &image);
    }
    if (status != MR_OK) {
        free(raw.pixels);
        return mr_fail_context(status, "%s", label);
    }
    const int decode_srgb = raw.encoded && o->encoding == MR_IMG_COLOR;
    int converted = convert_channels(&raw, image, decode_srgb);
    if (image->pixels != raw.pixels) free(raw.pixels);
    if (!converted) {
        mr_image_free(image);
        return mr_fail(MR_ERR_NOMEM, "%s: out of memory for the sRGB table", label);
    }
    *out = image;
    if (stored != NULL) {
        stored->bits = raw.bits == 8 || raw.bits == 16 ? raw.bits : 0;
        stored->encoding = decode_srgb ? MR_IMG_COLOR : MR_IMG_DATA;
    }
    return MR_OK;
}

mr_status mr_img_read(const char *path, const mr_img_read_options *opts, mr_image **out) {
    return mr_img_read_stored(path, opts, out, NULL);
}

mr_status mr_img_read_stored(const char *path, const mr_img_read_options *opts, mr_image **out,
                             mr_img_stored *stored) {
    if (path == NULL || out == NULL) return mr_fail(MR_ERR_INVALID_ARG, "mr_img_read: path and out must not be NULL");
    char label[MR_IO_LABEL_SIZE];
    mr_io_file_label(label, path);
    mr_img_read_options o;
    mr_status status = read_options(label, opts, &o);
    if (status != MR_OK) return status;

    /* File-system problems are MR_ERR_IO with the system's reason (OIIO would call them "not an image"); only a
     * regular file is read: a folder, a FIFO or a device is refused by name (mr_io_open_input). */
    FILE *file = NULL;
    status = mr_io_open_input(path, label, 0, &file, NULL);
    if (status != MR_OK)
        return status;
    return read_stream(path, NULL, 0, file, label, &o, out, stored);
}

mr_status mr_img_read_memory(const void *bytes, size_t size, const char *name, const mr_img_read_options *opts,
                             mr_image **out, mr_img_stored *stored) {
    if (out == NULL || (bytes == NULL && size > 0))
        return mr_fail(MR_ERR_INVALID_ARG, "mr_img_read_memory: out must not be NULL, nor bytes with a size");
    const char *label = name != NULL && name[0] != '\0' ? name : "image in memory";
    mr_img_read_options o;
    mr_status status = read_options(label, opts, &o);
    if (status != MR_OK) return status;
    if (size == 0) return mr_fail(MR_ERR_FORMAT, "%s: no bytes (an empty image)", label);
    /* Mode "r": fmemopen only reads the buffer, so casting away its const is safe. */
    FILE *stream = fmemopen((void *)bytes, size, "r");
    if (stream == NULL) {
        int err = errno;
        return mr_fail(MR_ERR_NOMEM, "%s: cannot open the bytes as a stream: %s", label, strerror(err));
    }
    return read_stream(NULL, bytes, size, stream, label, &o, out, stored);
}

/* The decode of the point `code` (a half-integer at an interval's edge), clamped to [0, max_code]: rounded to
 * float like every decoded value, so that it decides which side of an edge a decoded value lies on exactly. */
static double decode_edge(double code, int max_code) {
    return mr_srgb_to_linear((float)(mr_clampd(code, 0.0, max_code) / max_code));
}

double mr_img_half_step(double value, int bits, mr_img_encoding encoding) {
    if ((bits != 8 && bits != 16) || !isfinite(value)) return 0.0;
    const int max_code = bits == 8 ? 255 : 65535;
    if (encoding != MR_IMG_COLOR) return 0.5 / max_code;
    const double v = mr_clampd(value, 0.0, 1.0);
    // The code whose decode interval [lin((q - 1/2) / max), lin((q + 1/2) / max)) holds v: the writer's rounding
    // (quantise()) first, then settled against the interval's edges, which decide a value at a midpoint.
    int q = (int)floor(mr_clampd(mr_linear_to_srgb((float)v), 0.0, 1.0) * max_code + 0.5);
    while ((q > 0 && v < decode_edge(q - 0.5, max_code)) || (q < max_code && v >= decode_edge(q + 0.5, max_code)))
        q += v < decode_edge(q - 0.5, max_code) ? -1 : 1;
    // The farther edge from the code's own decode, in double (differences of floats would lose digits at 16 bits).
    const double centre = mr_srgb_decode_double((double)q / max_code);
    const double lo = mr_srgb_decode_double(mr_clampd(q - 0.5, 0.0, max_code) / max_code);
    const double hi = mr_srgb_decode_double(mr_clampd(q + 0.5, 0.0, max_code) / max_code);
    return fmax(hi - centre, centre - lo);
}

/* ---- writing ---------------------------------------------------------------------------------------- */

/* Display-encode one value for an integer file: clamp to [0,1] (NaN -> 0), sRGB-encode colour, scale to the
 * integer range and round to nearest. `scale` is 255 or 65535. */
static unsigned quantise(float v, int srgb, double scale) {
    double x = mr_clampd(v, 0.0, 1.0);
    if (srgb) x = mr_linear_to_srgb((float)x);
    return (unsigned)floor(mr_clampd(x, 0.0, 1.0) * scale + 0.5);
}

/* A buffer for an 8/16-bit file. Returns NULL on allocation failure. */
static void *quantised_copy(const mr_image *image, int bits, int srgb) {
    const size_t n = mr_image_value_count(image);
    const int ch = image->channels;
    const int has_alpha = ch == 4;
    const double scale = bits == 16 ? 65535.0 : 255.0;
    void *buffer = malloc(n * (bits == 16 ? 2u : 1u));
    if (buffer == NULL) return NULL;
    if (bits == 8 && srgb) { // the common case (colour textures) by table: no pow per value
        mr_srgb8_init();
        uint8_t *out = buffer;
        for (size_t i = 0; i < n; i++) {
            int is_alpha = has_alpha && (int)(i % (size_t)ch) == 3;
            out[i] = is_alpha ? (uint8_t)quantise(image->pixels[i], 0, scale) : mr_srgb8_encode(image->pixels[i]);
        }
        return buffer;
    }
    for (size_t i = 0; i < n; i++) {
        int is_alpha = has_alpha && (int)(i % (size_t)ch) == 3;
        unsigned q = quantise(image->pixels[i], srgb && !is_alpha, scale);
        if (bits == 16)
            ((uint16_t *)buffer)[i] = (uint16_t)q;
        else
            ((uint8_t *)buffer)[i] = (uint8_t)q;
    }
    return buffer;
}

/* RGB floats for Radiance HDR: grey broadcast; RGBE has no sign, so negatives and NaN become 0 and +inf the
 * largest float. Returns NULL on allocation failure. */
static float *hdr_copy(const mr_image *image) {
    const size_t count = (size_t)image->width * (size_t)image->height;
    float *rgb = malloc(count * 3 * sizeof(float));
    if (rgb == NULL) return NULL;
    for (size_t p = 0; p < count; p++)
        for (int c = 0; c < 3; c++) {
            float v = image->pixels[p * (size_t)image->channels + (size_t)(image->channels == 1 ? 0 : c)];
            rgb[p * 3 + (size_t)c] = (float)mr_clampd(v, 0.0, FLT_MAX);
        }
    return rgb;
}

static mr_status check_write_options(const char *path, file_format format, const mr_image *image,
                                     const mr_img_write_options *o, int *bits, int *quality) {
    if (o->encoding != MR_IMG_COLOR && o->encoding != MR_IMG_DATA)
        return mr_fail(MR_ERR_INVALID_ARG, "image '%s': unknown encoding %d (valid: MR_IMG_COLOR, MR_IMG_DATA)", path,
                       (int)o->encoding);
    *bits = o->bits;
    switch (format) {
    case FORMAT_PNG:
    case FORMAT_TIFF:
        if (*bits == 0) *bits = 8;
        if (*bits != 8 && *bits != 16)
            return mr_fail(MR_ERR_INVALID_ARG, "image '%s': %d bits per sample (valid for %s: 8, 16)", path, o->bits,
                           format_names[format]);
        break;
    case FORMAT_JPEG:
        if (*bits == 0) *bits = 8;
        if (*bits != 8)
            return mr_fail(MR_ERR_INVALID_ARG, "image '%s': %d bits per sample (valid for JPEG: 8)", path, o->bits);
        break;
    case FORMAT_EXR:
        if (*bits == 0) *bits = 32;
        if (*bits != 16 && *bits != 32)
            return mr_fail(MR_ERR_INVALID_ARG, "image '%s': %d bits per sample (valid for EXR: 16 = half, 32 = float)",
                           path, o->bits);
        break;
    case FORMAT_HDR:
        if (*bits != 0 && *bits != 32)
            return mr_fail(MR_ERR_INVALID_ARG,
                           "image '%s': %d bits per sample (Radiance HDR is always RGBE; valid: 0 or 32)", path,
                           o->bits);
        *bits = 32;
        break;
    default: break;
    }
    *quality = o->jpeg_quality == 0 ? DEFAULT_JPEG_QUALITY : o->jpeg_quality;
    if (*quality < 1 || *quality > 100)
        return mr_fail(MR_ERR_INVALID_ARG, "image '%s': JPEG quality %d (valid: 1..100, 0 = %d)", path,
                       o->jpeg_quality, DEFAULT_JPEG_QUALITY);
    /* libjpeg's limit (JPEG_MAX_DIMENSION); OpenImageIO 2.4 leaves libjpeg's exit()ing error handler in place,
     * so this must be refused here, not discovered by the encoder. */
    if (format == FORMAT_JPEG && (image->width > 65500 || image->height > 65500))
        return mr_fail(MR_ERR_UNSUPPORTED, "image '%s': %dx%d exceeds JPEG's limit of 65500 pixels per side", path,
                       image->width, image->height);
    if (image->channels == 4 && (format == FORMAT_JPEG || format == FORMAT_HDR))
        return mr_fail(MR_ERR_UNSUPPORTED,
                       "image '%s': %s cannot store an alpha channel (drop it, or write PNG, TIFF or EXR)", path,
                       format_names[format]);
    return MR_OK;
}

mr_status mr_img_write(const char *path, const mr_image *image, const mr_img_write_options *opts) {
    if (path == NULL || image == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "mr_img_write: path and image must not be NULL");
    if (image->width < 1 || image->height < 1 || image->pixels == NULL ||
        (image->channels != 1 && image->channels != 3 && image->channels != 4))
        return mr_fail(MR_ERR_INVALID_ARG, "image '%s': invalid image %dx%d with %d channels", path, image->width,
                       image->height, image->channels);
    const file_format format = format_of(path);
    if (format == FORMAT_UNKNOWN) {
        const char *dot = strrchr(path, '.');
        const char *slash = strrchr(path, '/');
        const char *ext = dot != NULL && (slash == NULL || dot > slash) ? dot : "(none)";
        return mr_fail(MR_ERR_INVALID_ARG,
                       "image '%s': unknown extension '%s' (valid: .exr .hdr .png .jpg .jpeg .tif .tiff)", path, ext);
    }
    mr_img_write_options o = {MR_IMG_COLOR, 0, 0};
    if (opts != NULL) o = *opts;
    int bits = 0, quality = 0;
    mr_status status = check_write_options(path, format, image, &o, &bits, &quality);
    if (status != MR_OK) return status;

    if (format == FORMAT_EXR) {
        /* OpenEXR Core writes the temporary file itself and reports every failed write (EXR_ERR_WRITE_IO). */
        mr_atomic_file file;
        status = mr_atomic_begin(path, &file);
        if (status != MR_OK) return status;
        status = mr_io_exr_write(path, file.tmp_path, image->width, image->height, image->channels, image->pixels,
                                 bits == 16);
        if (status != MR_OK) {
            mr_atomic_abort(&file);
            return status;
        }
        return mr_atomic_commit(&file);
    }

    /* Everything else: convert to the file's samples and let OpenImageIO encode them (atomically). */
    const int srgb = o.encoding == MR_IMG_COLOR;
    void *buffer = NULL;
    int out_channels = image->channels;
    mr_io_sample sample = MR_IO_F32;
    if (format == FORMAT_HDR) {
        buffer = hdr_copy(image);
        out_channels = 3;
    } else {
        buffer = quantised_copy(image, bits, srgb);
        sample = bits == 16 ? MR_IO_U16 : MR_IO_U8;
    }
    if (buffer == NULL)
        return mr_fail(MR_ERR_NOMEM, "image '%s': out of memory for %dx%d pixels", path, image->width, image->height);
    if (format == FORMAT_PNG) {
        const mr_io_png_settings settings = MR_IO_PNG_DEFAULT;
        status = mr_io_png_write(path, image->width, image->height, out_channels, bits, buffer, srgb, &settings);
    } else {
        status = mr_io_oiio_write(path, image->width, image->height, out_channels, sample, buffer,
                                  srgb && format != FORMAT_HDR, quality);
    }
    free(buffer);
    return status;
}
