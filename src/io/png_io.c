/*
 * png_io.c — PNG read and write without OpenImageIO (io_internal.h, "PNG"): the choice between libdeflate
 * (png_deflate.c, the default both ways) and libpng, and the libpng paths themselves.
 *
 * PNG is the format of nearly every glTF texture, and a texture-set conversion reads and writes several 2048^2
 * maps: going through OpenImageIO cost the loading of its ~250 libraries (the module, io/oiio_module.c) and its
 * default deflate level. This reader returns what mr_io_oiio_read returns for a PNG (the same channel layout: grey,
 * grey + alpha, RGB, RGBA; palettes, low bit depths and tRNS expanded; 8 or 16 bits; values code / (2^bits - 1);
 * display-encoded), and the writer encodes in memory and writes atomically as the OpenImageIO path does. The reader
 * takes any seekable stdio stream: a file, or an image in memory that image_io.c opens with fmemopen
 * (mr_img_read_memory), so both go through the same calls and give the same values. png_deflate.c decodes what it
 * takes (non-interlaced, well-formed files: nearly all) and hands the rest back; libpng then decodes it from the
 * start, so those files give the values and errors they always gave. libpng's reader is the reference that
 * png_deflate.c's output is tested against, bit for bit; its writer (libpng + zlib) stays for comparisons
 * (tests/bench_png.c) behind mr_io_png_settings.libpng.
 *
 * libpng reports errors by longjmp out of its calls: what the callbacks change and the code after a jump reads
 * (the message, the growing output) lives on the heap behind a `volatile` pointer, as C requires of objects
 * changed between setjmp and longjmp. Messages are recorded, never printed (libpng's default prints "libpng
 * error: ..." on stderr).
 */
#include <png.h>
#include <setjmp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../mr_internal.h"
#include "io_internal.h"

/* One read or write: the first error and the first warning the callbacks record (a PNG that decodes despite a
 * warning is taken, as OpenImageIO takes it; when the decode then fails, the warning goes into the message, as it
 * may say more than the error) and, when writing, the encoded file grown in memory (written at the end in one
 * checked atomic write, so that a full disk fails cleanly). */
typedef struct png_session {
    char error[256];
    char warning[256];
    unsigned char *data;
    size_t size, capacity;
    int out_of_memory;
} png_session;

static void on_error(png_structp png, png_const_charp message) {
    png_session *m = png_get_error_ptr(png);
    if (m != NULL && m->error[0] == '\0') snprintf(m->error, sizeof m->error, "%s", message ? message : "");
    png_longjmp(png, 1);
}

static void on_warning(png_structp png, png_const_charp message) {
    png_session *m = png_get_error_ptr(png);
    if (m != NULL && m->warning[0] == '\0')
        snprintf(m->warning, sizeof m->warning, "%s", message ? message : "");
}

/* PNG stores 16-bit samples big-endian; png_set_swap makes them little-endian: host order on such hosts only. */
static int host_is_little_endian(void) {
    const uint16_t probe = 1;
    return *(const unsigned char *)&probe == 1;
}

mr_status mr_io_png_read(const char *path, int max_dimension, mr_io_raw *raw) {
    char label[MR_IO_LABEL_SIZE];
    mr_io_file_label(label, path);
    FILE *file = NULL;
    mr_status status = mr_io_open_input(path, label, 0, &file, NULL);
    if (status != MR_OK)
        return status;
    status = mr_io_png_read_stream(file, label, max_dimension, raw);
    fclose(file);
    return status;
}

mr_status mr_io_png_read_stream(FILE *file, const char *label, int max_dimension, mr_io_raw *raw) {
    const long start = ftell(file);
    if (start >= 0) { // else (a pipe) libpng alone, which does not need to go back
        int handled = 0;
        mr_status status = mr_io_png_deflate_read(file, label, max_dimension, raw, &handled);
        if (handled) return status;
        clearerr(file);
        if (fseek(file, start, SEEK_SET) != 0)
            return mr_fail(MR_ERR_IO, "%s: cannot seek back to the PNG's start", label);
    }
    return mr_io_png_read_stream_libpng(file, label, max_dimension, raw);
}

mr_status mr_io_png_read_stream_libpng(FILE *file, const char *label, int max_dimension, mr_io_raw *raw) {
    png_session *volatile session = calloc(1, sizeof *session);
    png_structp png = session ? png_create_read_struct(PNG_LIBPNG_VER_STRING, session, on_error, on_warning) : NULL;
    png_infop info = png != NULL ? png_create_info_struct(png) : NULL;
    if (png == NULL || info == NULL) {
        png_destroy_read_struct(png ? &png : NULL, NULL, NULL);
        free(session);
        return mr_fail(MR_ERR_NOMEM, "%s: out of memory for the PNG decoder", label);
    }
    unsigned char *volatile bytes = NULL;
    png_bytep *volatile rows = NULL;
    volatile mr_status failure = MR_ERR_FORMAT; // with own_message: a failure of ours, not libpng's
    volatile int own_message = 0;
    if (setjmp(png_jmpbuf(png))) {
        png_destroy_read_struct(&png, &info, NULL);
        free(bytes);
        free(rows);
        char why[sizeof session->error], warned[sizeof session->warning];
        memcpy(why, session->error, sizeof why);
        memcpy(warned, session->warning, sizeof warned);
        free(session);
        if (own_message) return mr_fail(failure, "%s: %s", label, why);
        if (warned[0] != '\0' && strcmp(warned, why) != 0)
            return mr_fail(MR_ERR_FORMAT, "%s: cannot decode PNG (corrupt or truncated?): %s (libpng warned: %s)",
                           label, why, warned);
        return mr_fail(MR_ERR_FORMAT, "%s: cannot decode PNG (corrupt or truncated?): %s", label, why);
    }
    png_init_io(png, file);
    png_set_user_limits(png, 0x7fffffff, 0x7fffffff); // ours is checked below, with our message
    png_read_info(png, info);
    const png_uint_32 width = png_get_image_width(png, info), height = png_get_image_height(png, info);
    if ((long)width > max_dimension || (long)height > max_dimension) {
        own_message = 1;
        snprintf(session->error, sizeof session->error, "%lux%lu pixels exceeds the maximum dimension %d",
                 (unsigned long)width, (unsigned long)height, max_dimension);
        png_longjmp(png, 1);
    }
    png_set_expand(png); // palette -> RGB, grey below 8 bits -> 8, tRNS -> alpha
    if (png_get_bit_depth(png, info) == 16 && host_is_little_endian()) png_set_swap(png); // to host order
    png_set_interlace_handling(png);
    png_read_update_info(png, info);
    const int channels = png_get_channels(png, info), bits = png_get_bit_depth(png, info);
    const size_t row_bytes = png_get_rowbytes(png, info);
    if ((bits != 8 && bits != 16) || channels < 1 || channels > 4) {
        own_message = 1;
        snprintf(session->error, sizeof session->error, "unsupported layout (%d channels of %d bits)", channels, bits);
        png_longjmp(png, 1);
    }
    const size_t count = (size_t)width * (size_t)height;
    if (count > SIZE_MAX / sizeof(float) / (size_t)channels || row_bytes > SIZE_MAX / height) {
        failure = MR_ERR_NOMEM;
        own_message = 1;
        snprintf(session->error, sizeof session->error, "%lux%lu pixels do not fit in memory", (unsigned long)width,
                 (unsigned long)height);
        png_longjmp(png, 1);
    }
    bytes = malloc(row_bytes * height);
    rows = malloc(height * sizeof *rows);
    if (bytes == NULL || rows == NULL) {
        failure = MR_ERR_NOMEM;
        own_message = 1;
        snprintf(session->error, sizeof session->error, "out of memory for %lux%lu pixels", (unsigned long)width,
                 (unsigned long)height);
        png_longjmp(png, 1);
    }
    for (png_uint_32 y = 0; y < height; y++) rows[y] = bytes + (size_t)y * row_bytes;
    png_read_image(png, rows);
    png_read_end(png, NULL);
    float *pixels = malloc(count * (size_t)channels * sizeof *pixels);
    if (pixels == NULL) {
        failure = MR_ERR_NOMEM;
        own_message = 1;
        snprintf(session->error, sizeof session->error, "out of memory for %lux%lu pixels", (unsigned long)width,
                 (unsigned long)height);
        png_longjmp(png, 1);
    }
    // code / (2^bits - 1), as OpenImageIO converts unsigned integers to float (multiplied by the reciprocal).
    if (bits == 8) {
        const float scale = 1.0f / 255.0f;
        for (size_t y = 0, at = 0; y < height; y++)
            for (size_t x = 0; x < width * (size_t)channels; x++, at++) pixels[at] = (float)rows[y][x] * scale;
    } else {
        const float scale = 1.0f / 65535.0f;
        for (size_t y = 0, at = 0; y < height; y++) {
            const uint16_t *row = (const uint16_t *)(const void *)rows[y];
            for (size_t x = 0; x < width * (size_t)channels; x++, at++) pixels[at] = (float)row[x] * scale;
        }
    }
    png_destroy_read_struct(&png, &info, NULL);
    free(bytes);
    free(rows);
    free(session);
    raw->width = (int)width;
    raw->height = (int)height;
    raw->channels = channels;
    raw->encoded = 1;
    raw->bits = bits;
    raw->pixels = pixels;
    return MR_OK;
}

/* ---- writing ------------------------------------------------------------------------------------------------ */

static void buffer_write(png_structp png, png_bytep data, size_t length) {
    png_session *b = png_get_io_ptr(png);
    if (b->size + length > b->capacity) {
        size_t capacity = b->capacity ? b->capacity : 1 << 16;
        while (capacity < b->size + length) capacity *= 2;
        unsigned char *grown = realloc(b->data, capacity);
        if (grown == NULL) {
            b->out_of_memory = 1;
            png_error(png, "out of memory for the encoded file");
        }
        b->data = grown;
        b->capacity = capacity;
    }
    memcpy(b->data + b->size, data, length);
    b->size += length;
}

static void buffer_flush(png_structp png) { (void)png; }

static mr_status libpng_encode(const char *path, int width, int height, int channels, int bits, const void *data,
                               int srgb_tag, const mr_io_png_settings *settings, unsigned char **bytes, size_t *size) {
    static const int color_types[5] = {0, PNG_COLOR_TYPE_GRAY, PNG_COLOR_TYPE_GRAY_ALPHA, PNG_COLOR_TYPE_RGB,
                                       PNG_COLOR_TYPE_RGB_ALPHA};
    png_session *volatile session = calloc(1, sizeof *session);
    png_structp png = session ? png_create_write_struct(PNG_LIBPNG_VER_STRING, session, on_error, on_warning) : NULL;
    png_infop info = png != NULL ? png_create_info_struct(png) : NULL;
    png_bytep *volatile rows = malloc((size_t)height * sizeof *rows);
    if (png == NULL || info == NULL || rows == NULL) {
        png_destroy_write_struct(png ? &png : NULL, info ? &info : NULL);
        free(rows);
        free(session);
        return mr_fail(MR_ERR_NOMEM, "image '%s': out of memory for the PNG encoder", path);
    }
    if (setjmp(png_jmpbuf(png))) {
        png_destroy_write_struct(&png, &info);
        free(rows);
        mr_status status = mr_fail(session->out_of_memory ? MR_ERR_NOMEM : MR_ERR_EXTERNAL,
                                   "image '%s': PNG encoding failed: %s", path, session->error);
        free(session->data);
        free(session);
        return status;
    }
    png_set_write_fn(png, session, buffer_write, buffer_flush);
    png_set_IHDR(png, info, (png_uint_32)width, (png_uint_32)height, bits, color_types[channels], PNG_INTERLACE_NONE,
                 PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    if (srgb_tag) png_set_sRGB_gAMA_and_cHRM(png, info, PNG_sRGB_INTENT_PERCEPTUAL);
    png_set_compression_level(png, settings->level);
    png_set_filter(png, PNG_FILTER_TYPE_BASE, settings->filters);
    png_write_info(png, info);
    if (bits == 16 && host_is_little_endian()) png_set_swap(png); // host order in, big-endian in the file
    const size_t row_bytes = (size_t)width * (size_t)channels * (size_t)(bits / 8);
    for (int y = 0; y < height; y++) rows[y] = (png_bytep)((const unsigned char *)data + (size_t)y * row_bytes);
    png_write_image(png, rows);
    png_write_end(png, NULL);
    png_destroy_write_struct(&png, &info);
    free(rows);
    *bytes = session->data;
    *size = session->size;
    free(session);
    return MR_OK;
}

mr_status mr_io_png_encode(const char *path, int width, int height, int channels, int bits, const void *data,
                           int srgb_tag, const mr_io_png_settings *settings, unsigned char **bytes, size_t *size) {
    if (width < 1 || height < 1 || channels < 1 || channels > 4 || (bits != 8 && bits != 16) || data == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "image '%s': cannot write %dx%d pixels of %d channels at %d bits as PNG",
                       path, width, height, channels, bits);
    const int most = settings->libpng ? 9 : 12;
    if (settings->level < 0 || settings->level > most || settings->filters == 0 ||
        (settings->filters & ~MR_IO_PNG_ALL_FILTERS) != 0)
        return mr_fail(MR_ERR_INVALID_ARG, "image '%s': PNG level %d, filters 0x%x (valid: level 0-%d for %s, "
                       "filters a non-empty set of 0x08 none, 0x10 sub, 0x20 up, 0x40 average, 0x80 Paeth)", path,
                       settings->level, (unsigned)settings->filters, most, settings->libpng ? "zlib" : "libdeflate");
    return (settings->libpng ? libpng_encode : mr_io_png_deflate_encode)(path, width, height, channels, bits, data,
                                                                          srgb_tag, settings, bytes, size);
}

mr_status mr_io_png_write(const char *path, int width, int height, int channels, int bits, const void *data,
                          int srgb_tag, const mr_io_png_settings *settings) {
    unsigned char *bytes = NULL;
    size_t size = 0;
    mr_status status = mr_io_png_encode(path, width, height, channels, bits, data, srgb_tag, settings, &bytes, &size);
    if (status == MR_OK) status = mr_atomic_write_bytes(path, bytes, size);
    free(bytes);
    return status;
}
