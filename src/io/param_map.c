/*
 * param_map.c — the one rule for texture maps of BRDF parameters (image_io.h, "maps of BRDF parameters"): how an
 * 8/16-bit map of a parameter is decoded follows the parameter's MR_PARAM_SRGB_MAP flag, unless the map says
 * otherwise; float files are linear.
 */
#include <stdio.h>
#include <string.h>
#include <stdlib.h>
#include <sys/stat.h>

#include "image_io.h"
#include "io_internal.h"
#include "mr_internal.h"

mr_img_encoding mr_brdf_param_map_encoding(const mr_brdf_param *param, mr_map_encoding how) {
    if (how == MR_MAP_SRGB) return MR_IMG_COLOR;
    if (how == MR_MAP_LINEAR) return MR_IMG_DATA;
    return param != NULL && (param->flags & MR_PARAM_SRGB_MAP) ? MR_IMG_COLOR : MR_IMG_DATA;
}

const char *mr_img_encoding_name(mr_img_encoding encoding) {
    return encoding == MR_IMG_COLOR ? "sRGB" : "linear";
}

mr_status mr_img_read_param_map(const char *path, const mr_brdf_param *param, mr_map_encoding how,
                                const mr_img_read_options *opts, mr_image **out, mr_img_stored *stored) {
    if ((int)how < 0 || how >= MR_MAP_ENCODING_COUNT)
        return mr_fail(MR_ERR_INVALID_ARG, "mr_img_read_param_map: unknown map encoding %d (valid: "
                       "MR_MAP_AS_PARAMETER, MR_MAP_SRGB, MR_MAP_LINEAR)", (int)how);
    mr_img_read_options o = {MR_IMG_COLOR, 0, 0};
    if (opts != NULL) o = *opts;
    o.encoding = mr_brdf_param_map_encoding(param, how);
    mr_image *image = NULL;
    mr_img_stored s;
    mr_status status = mr_img_read_stored(path, &o, &image, &s);
    if (status != MR_OK) return status;
    if (how == MR_MAP_SRGB && s.encoding != MR_IMG_COLOR) { // read as colour, yet not decoded: float samples
        mr_image_free(image);
        char label[MR_IO_LABEL_SIZE];
        mr_io_file_label(label, path);
        return mr_fail(MR_ERR_INVALID_ARG, "%s stores floating-point samples, which are linear: sRGB decoding "
                       "(:srgb) applies to 8/16-bit files", label);
    }
    *out = image;
    if (stored != NULL) *stored = s;
    return MR_OK;
}

mr_status mr_img_read_param_maps(mr_img_param_map *maps, int count, const mr_img_read_options *opts, int threads,
                                 int *failed) {
    int failed_index = -1;
    if (failed == NULL) failed = &failed_index;
    *failed = -1;
    if (count <= 0) return MR_OK;
    // mr_last_error() is per thread: each read keeps its own message for the report.
    typedef struct read_job {
        mr_status status;
        char message[1024];
    } read_job;
    read_job *jobs = calloc((size_t)count, sizeof *jobs);
    if (jobs == NULL) return mr_fail(MR_ERR_NOMEM, "out of memory");
    // Decoded side by side: PNG decoding is a third of a 2048^2 texture set's conversion.
    const int allowed = mr_auto_threads(threads, count, 2);
    const int team = allowed < count ? allowed : count;
#pragma omp parallel for schedule(dynamic, 1) num_threads(team) if (team > 1)
    for (int k = 0; k < count; k++) {
        jobs[k].status = MR_OK;
        if (maps[k].path == NULL) continue;
        jobs[k].status = mr_img_read_param_map(maps[k].path, maps[k].param, maps[k].how, opts, &maps[k].image,
                                               &maps[k].stored);
        if (jobs[k].status != MR_OK) snprintf(jobs[k].message, sizeof jobs[k].message, "%s", mr_last_error());
    }
    mr_status status = MR_OK;
    for (int k = 0; k < count && status == MR_OK; k++)
        if (jobs[k].status != MR_OK) {
            *failed = k;
            status = jobs[k].status;
            if (jobs[k].message[0])
                mr_fail(status, "%s", jobs[k].message);
            else
                mr_clear_error();
        }
    free(jobs);
    return status;
}

/* The name of map m in messages: its label, or "map 'PATH'" in `buffer`. */
static const char *map_label(const mr_img_param_map *m, char *buffer, size_t size) {
    if (m->label != NULL) return m->label;
    snprintf(buffer, size, "map '%s'", m->path ? m->path : "");
    return buffer;
}

/* The checks m's fields ask for, once its file is read. */
static mr_status check_map(const mr_img_param_map *m) {
    const mr_image *im = m->image;
    char buffer[1100];
    if (im == NULL) return MR_OK;
    if (m->min_channels > 0 && im->channels < m->min_channels)
        return mr_fail(MR_ERR_INVALID_ARG, "%s has %s; expected %s", map_label(m, buffer, sizeof buffer),
                       im->channels == 1 ? "one channel" : "no alpha channel", m->layout ? m->layout : "more");
    if (m->grey && im->channels >= 3) {
        const size_t n = (size_t)im->width * (size_t)im->height;
        for (size_t i = 0; i < n; i++) {
            const float *p = im->pixels + i * (size_t)im->channels;
            if (p[0] != p[1] || p[0] != p[2])
                return mr_fail(MR_ERR_INVALID_ARG, "%s is a colour image (pixel %zu, %zu is %g, %g, %g); expected one "
                               "channel, or grey%s", map_label(m, buffer, sizeof buffer), i % (size_t)im->width,
                               i / (size_t)im->width, p[0], p[1], p[2], m->hint ? m->hint : "");
        }
    }
    return MR_OK;
}

mr_status mr_img_read_texture_set(mr_img_param_map *maps, int count, const mr_img_read_options *opts, int threads,
                                  int *width, int *height, int *failed) {
    int failed_index = -1;
    if (failed == NULL) failed = &failed_index;
    int read_failed = -1;
    const mr_status read = mr_img_read_param_maps(maps, count, opts, threads, &read_failed);
    *failed = -1;
    if (read != MR_OK && read_failed < 0) return read; // out of memory before any read
    const mr_img_param_map *first = NULL;
    for (int k = 0; k < count; k++) {
        *failed = k;
        if (k == read_failed) return read; // its message is the calling thread's already
        mr_status status = check_map(&maps[k]);
        if (status != MR_OK) return status;
        const mr_image *im = maps[k].image;
        if (im == NULL) continue;
        if (first == NULL) {
            first = &maps[k];
        } else if (im->width != first->image->width || im->height != first->image->height) {
            char a[1100], b[1100];
            return mr_fail(MR_ERR_INVALID_ARG, "%s is %dx%d but %s is %dx%d: maps must have the same size "
                           "(constants broadcast)", map_label(&maps[k], a, sizeof a), im->width, im->height,
                           map_label(first, b, sizeof b), first->image->width, first->image->height);
        }
    }
    *failed = -1;
    if (width != NULL) *width = first ? first->image->width : 1;
    if (height != NULL) *height = first ? first->image->height : 1;
    return MR_OK;
}

/* ---- maps named in text: FILE[:r|g|b|a][:linear|srgb] ---------------------------------------------------------- */

/* 1 if text[0..*length) ends in ":suffix" (and holds something before it); then *length drops it. */
static int strip_suffix(const char *text, size_t *length, const char *suffix) {
    const size_t n = strlen(suffix);
    if (*length < n + 2 || text[*length - n - 1] != ':' || strncmp(text + *length - n, suffix, n) != 0) return 0;
    *length -= n + 1;
    return 1;
}

void mr_map_ref_split(const char *text, int channels, size_t *path_length, int *channel, mr_map_encoding *encoding) {
    size_t length = strlen(text);
    *encoding = strip_suffix(text, &length, "linear") ? MR_MAP_LINEAR
                : strip_suffix(text, &length, "srgb")  ? MR_MAP_SRGB
                                                       : MR_MAP_AS_PARAMETER;
    static const char *const letters[4] = {"r", "g", "b", "a"};
    *channel = -1;
    for (int c = 0; channels && c < 4 && *channel < 0; c++)
        if (strip_suffix(text, &length, letters[c])) *channel = c;
    *path_length = length;
}

mr_status mr_map_ref_check(const char *label, const char *text, int channels) {
    if (label == NULL) label = text;
    size_t length;
    int channel;
    mr_map_encoding encoding;
    mr_map_ref_split(text, channels, &length, &channel, &encoding);
    const char *syntax = channels ? "FILE[:r|g|b|a][:linear|srgb]" : "FILE[:linear|srgb]";
    if (length == 0) return mr_fail(MR_ERR_INVALID_ARG, "'%s': no file name (expected %s)", label, syntax);
    size_t rest = length;
    int misplaced = channel >= 0 && (strip_suffix(text, &rest, "linear") || strip_suffix(text, &rest, "srgb"));
    if (misplaced) {
        struct stat st;
        char *path = strndup(text, length);
        misplaced = path != NULL && stat(path, &st) != 0; // a file really named "x.png:linear" is read as it is
        free(path);
    }
    if (misplaced)
        return mr_fail(MR_ERR_INVALID_ARG, "'%s': the channel comes before the encoding: %.*s:%c%.*s", label,
                       (int)rest, text, "rgba"[channel], (int)(length - rest), text + rest);
    return MR_OK;
}

mr_status mr_map_ref_read(const char *label, const char *text, int channels, const mr_brdf_param *param,
                          const mr_img_read_options *opts, mr_image **out, mr_img_stored *stored, int *usage) {
    int ignored;
    if (usage == NULL) usage = &ignored;
    *usage = 0;
    if (label == NULL) label = text;
    mr_status status = mr_map_ref_check(label, text, channels);
    if (status != MR_OK) {
        *usage = status == MR_ERR_INVALID_ARG;
        return status;
    }
    size_t length;
    int selected;
    mr_map_encoding encoding;
    mr_map_ref_split(text, channels, &length, &selected, &encoding);
    char *path = strndup(text, length);
    if (path == NULL) return mr_fail(MR_ERR_NOMEM, "out of memory for '%s'", label);
    status = mr_img_read_param_map(path, param, encoding, opts, out, stored);
    free(path);
    if (status == MR_ERR_INVALID_ARG && encoding == MR_MAP_SRGB) { // :srgb on a float file: the request is the error
        char message[1024];
        snprintf(message, sizeof message, "%s", mr_last_error());
        *usage = 1;
        return mr_fail(status, "'%s': %s", label, message);
    }
    return status;
}
