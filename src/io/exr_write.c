/*
 * exr_write.c — EXR output through the OpenEXR Core C API (OpenEXR 3.1, openexr.h; contract in io_internal.h).
 *
 * One scanline part, ZIP compression (16 lines per chunk), FLOAT or HALF channels named R,G,B(,A) or Y. The
 * sequence is the one openexr_context.h and openexr_encode.h document for writing: exr_start_write ->
 * exr_add_part -> exr_initialize_required_attr_simple -> exr_add_channel... -> exr_write_header -> per chunk:
 * exr_write_scanline_chunk_info, exr_encoding_initialize (first) or exr_encoding_update, point every channel
 * at its samples, exr_encoding_choose_default_routines (first), exr_encoding_run -> exr_finish, which writes
 * the chunk offset table.
 *
 * Core stores channels sorted by name (A, B, G, R), so the encoder's channel list is matched to our
 * interleaved R,G,B,A by channel_name, never by position. The input stays interleaved: each channel reads
 * with a pixel stride of channels*4 bytes, and Core's generic packer converts float to half when asked.
 * Reading EXR is OpenImageIO's job (image_io_oiio.cpp): Core 3.1.5 cannot decode DWAA/DWAB and mis-orders
 * interleaved HALF decodes (../shared/docs/toolchain.md); its encoder has no such problems, and the tests
 * read every file written here back through OpenImageIO (the OpenEXR C++ library) as an independent check.
 * Core reports errors through a callback that would print to stderr by default; ours keeps the first message
 * for mr_last_error instead (library code never prints).
 */
#include <openexr.h>
#include <stdio.h>
#include <string.h>

#include "../mr_internal.h"
#include "io_internal.h"

typedef struct exr_errbuf {
    char text[512];
} exr_errbuf;

static void exr_error_handler(exr_const_context_t ctxt, exr_result_t code, const char *msg) {
    void *user = NULL;
    if (exr_get_user_data(ctxt, &user) != EXR_ERR_SUCCESS || user == NULL) return;
    exr_errbuf *buf = user;
    if (buf->text[0] != '\0') return; /* keep the first (root-cause) message */
    snprintf(buf->text, sizeof buf->text, "%s (%s)", msg ? msg : "", exr_get_error_code_as_string(code));
}

/* Record a failure of Core call `what`, preferring the handler's message over the generic one. */
static mr_status exr_fail(const char *name, const char *what, exr_result_t rv, const exr_errbuf *buf) {
    mr_status status = rv == EXR_ERR_OUT_OF_MEMORY ? MR_ERR_NOMEM
                       : (rv == EXR_ERR_FILE_ACCESS || rv == EXR_ERR_WRITE_IO) ? MR_ERR_IO
                                                                                 : MR_ERR_EXTERNAL;
    if (buf->text[0] != '\0')
        return mr_fail(status, "image '%s': OpenEXR %s failed: %s", name, what, buf->text);
    return mr_fail(status, "image '%s': OpenEXR %s failed: %s", name, what, exr_get_default_error_message(rv));
}

/* Index of EXR channel `name` in our interleaved layout, or -1. */
static int channel_index(const char *name, int channels) {
    if (channels == 1) return strcmp(name, "Y") == 0 ? 0 : -1;
    static const char *const rgba[4] = {"R", "G", "B", "A"};
    for (int c = 0; c < channels; c++)
        if (strcmp(name, rgba[c]) == 0) return c;
    return -1;
}

mr_status mr_io_exr_write(const char *name_for_errors, const char *file_path, int width, int height,
                          int channels, const float *pixels, int half) {
    static const char *const rgba[4] = {"R", "G", "B", "A"};
    const char *name = name_for_errors;
    exr_errbuf errbuf;
    errbuf.text[0] = '\0';
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = exr_error_handler;
    init.user_data = &errbuf;

    exr_context_t ctxt = NULL;
    exr_encode_pipeline_t encoder;
    memset(&encoder, 0, sizeof encoder);
    int encoder_ready = 0;
    mr_status status = MR_OK;
    exr_result_t rv;
    int part = 0;

    /* WRITE_FILE_DIRECTLY: the caller already writes to a private temporary file (atomic_file.c). */
    rv = exr_start_write(&ctxt, file_path, EXR_WRITE_FILE_DIRECTLY, &init);
    if (rv != EXR_ERR_SUCCESS) {
        status = exr_fail(name, "exr_start_write", rv, &errbuf);
        ctxt = NULL;
        goto done;
    }
    rv = exr_add_part(ctxt, "", EXR_STORAGE_SCANLINE, &part);
    if (rv != EXR_ERR_SUCCESS) {
        status = exr_fail(name, "exr_add_part", rv, &errbuf);
        goto done;
    }
    rv = exr_initialize_required_attr_simple(ctxt, part, width, height, EXR_COMPRESSION_ZIP);
    if (rv != EXR_ERR_SUCCESS) {
        status = exr_fail(name, "exr_initialize_required_attr_simple", rv, &errbuf);
        goto done;
    }
    exr_pixel_type_t stored = half ? EXR_PIXEL_HALF : EXR_PIXEL_FLOAT;
    for (int c = 0; c < channels; c++) {
        rv = exr_add_channel(ctxt, part, channels == 1 ? "Y" : rgba[c], stored, EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1);
        if (rv != EXR_ERR_SUCCESS) {
            status = exr_fail(name, "exr_add_channel", rv, &errbuf);
            goto done;
        }
    }
    rv = exr_write_header(ctxt);
    if (rv != EXR_ERR_SUCCESS) {
        status = exr_fail(name, "exr_write_header", rv, &errbuf);
        goto done;
    }
    int32_t lines_per_chunk = 0;
    rv = exr_get_scanlines_per_chunk(ctxt, part, &lines_per_chunk);
    if (rv != EXR_ERR_SUCCESS || lines_per_chunk < 1) {
        status = exr_fail(name, "exr_get_scanlines_per_chunk", rv, &errbuf);
        goto done;
    }

    const size_t row_floats = (size_t)width * (size_t)channels;
    for (int y = 0; y < height; y += lines_per_chunk) {
        exr_chunk_info_t chunk;
        rv = exr_write_scanline_chunk_info(ctxt, part, y, &chunk);
        if (rv != EXR_ERR_SUCCESS) {
            status = exr_fail(name, "exr_write_scanline_chunk_info", rv, &errbuf);
            goto done;
        }
        rv = encoder_ready ? exr_encoding_update(ctxt, part, &chunk, &encoder)
                           : exr_encoding_initialize(ctxt, part, &chunk, &encoder);
        if (rv != EXR_ERR_SUCCESS) {
            status = exr_fail(name, "exr_encoding_initialize", rv, &errbuf);
            goto done;
        }
        int first = !encoder_ready;
        encoder_ready = 1;
        const float *rows = pixels + (size_t)chunk.start_y * row_floats;
        for (int i = 0; i < encoder.channel_count; i++) {
            exr_coding_channel_info_t *ch = &encoder.channels[i];
            int c = channel_index(ch->channel_name, channels);
            if (c < 0) {
                status = mr_fail(MR_ERR_EXTERNAL, "image '%s': OpenEXR reported an unexpected channel '%s'", name,
                                 ch->channel_name);
                goto done;
            }
            ch->encode_from_ptr = (const uint8_t *)(rows + c);
            ch->user_data_type = EXR_PIXEL_FLOAT;
            ch->user_bytes_per_element = (int16_t)sizeof(float);
            ch->user_pixel_stride = (int32_t)((size_t)channels * sizeof(float));
            ch->user_line_stride = (int32_t)(row_floats * sizeof(float));
        }
        if (first) {
            rv = exr_encoding_choose_default_routines(ctxt, part, &encoder);
            if (rv != EXR_ERR_SUCCESS) {
                status = exr_fail(name, "exr_encoding_choose_default_routines", rv, &errbuf);
                goto done;
            }
        }
        rv = exr_encoding_run(ctxt, part, &encoder);
        if (rv != EXR_ERR_SUCCESS) {
            status = exr_fail(name, "exr_encoding_run", rv, &errbuf);
            goto done;
        }
    }

done:
    if (encoder_ready) {
        rv = exr_encoding_destroy(ctxt, &encoder);
        if (rv != EXR_ERR_SUCCESS && status == MR_OK) status = exr_fail(name, "exr_encoding_destroy", rv, &errbuf);
    }
    if (ctxt != NULL) {
        /* exr_finish writes the chunk offset table: its failure is a failed write. */
        rv = exr_finish(&ctxt);
        if (rv != EXR_ERR_SUCCESS && status == MR_OK) status = exr_fail(name, "exr_finish", rv, &errbuf);
    }
    return status;
}
