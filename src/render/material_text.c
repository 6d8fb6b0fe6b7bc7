/*
 * material_text.c — a material given as text (contract in render.h, "materials given as text"): MODEL followed by
 * name=value and name=@MAP[:r|g|b|a][:linear|srgb] assignments, as the render, report and convert commands take it.
 * Maps are read by the library's one rule (mr_map_ref_read, io/image_io.h: colour parameters sRGB-decoded from
 * 8/16-bit files, everything else linear, float files linear, unless the map says :linear or :srgb) and bound to a
 * new mr_material, which owns them.
 */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>

#include "../io/image_io.h"
#include "../mr_internal.h"
#include "render.h"

/* A failure at the level of the text (a command line's usage error): status MR_ERR_INVALID_ARG, *usage set. */
#if defined(__GNUC__)
__attribute__((format(printf, 2, 3)))
#endif
static mr_status usage_error(int *usage, const char *fmt, ...) {
    char message[1024];
    va_list args;
    va_start(args, fmt);
    vsnprintf(message, sizeof message, fmt, args);
    va_end(args);
    *usage = 1;
    return mr_fail(MR_ERR_INVALID_ARG, "%s", message);
}

/* Read one map, "name=@FILE[:c][:e]", the way its parameter needs it (mr_map_ref_read: the one rule, or the map's
 * :linear or :srgb) and bind it to m (which then owns the image). */
static mr_status load_map(mr_material *m, const char *assignment, const mr_img_read_options *read, int *usage) {
    const mr_brdf_model *model = m->model;
    const char *eq = strchr(assignment, '='), *file = eq + 2;
    if (eq == assignment)
        return usage_error(usage, "'%s': expected name=@FILE[:r|g|b|a][:linear|srgb]", assignment);
    mr_status status = mr_map_ref_check(assignment, file, 1);
    if (status != MR_OK) {
        *usage = status == MR_ERR_INVALID_ARG;
        return status;
    }
    size_t path_length;
    int channel;
    mr_map_encoding encoding;
    mr_map_ref_split(file, 1, &path_length, &channel, &encoding);
    char *name = strndup(assignment, (size_t)(eq - assignment)), *path = strndup(file, path_length);
    if (name == NULL || path == NULL) {
        free(name);
        free(path);
        return mr_fail(MR_ERR_NOMEM, "out of memory for '%s'", assignment);
    }
    int index = mr_brdf_param_index(model, name);
    const mr_brdf_param *param = index >= 0 ? &model->params[index] : NULL;
    mr_image *image = NULL;
    if (param == NULL) {
        mr_param_textures unused = {0};
        status = mr_param_textures_set(&unused, model, name, NULL, 0); // names the valid parameters
    } else if (param->channels == 3 && channel >= 0) {
        status = usage_error(usage, "'%s': %s is an RGB parameter and takes the whole image (no :%c)", assignment,
                             param->name, "rgba"[channel]);
    } else {
        status = mr_map_ref_read(assignment, file, 1, param, read, &image, NULL, usage);
    }
    if (param != NULL && param->channels == 3) channel = 0; // an RGB parameter reads channels 0-2
    if (status == MR_OK && channel < 0) {
        channel = 0;
        if (image->channels >= 3) {
            // A grey picture saved as RGB is fine; real colour needs the user to say which channel to use.
            size_t pixels = (size_t)image->width * (size_t)image->height;
            const float *px = image->pixels;
            for (size_t p = 0; p < pixels && status == MR_OK; p++, px += image->channels)
                if (px[0] != px[1] || px[0] != px[2])
                    status = usage_error(usage, "'%s': %s holds colour, but %s takes one value: pick a channel "
                                         "with @%s:r, :g, :b or :a", assignment, path, param->name, path);
        }
    }
    if (status == MR_OK) {
        // The source as people read it (report's thumbnails): the file, and an override if the map gives one.
        char source[4200];
        snprintf(source, sizeof source, "%s%s", path,
                 encoding == MR_MAP_LINEAR ? ":linear" : encoding == MR_MAP_SRGB ? ":srgb" : "");
        status = mr_material_add_map(m, name, image, channel, source, NULL);
        if (status == MR_OK) image = NULL; // m owns it
    }
    mr_image_free(image);
    free(name);
    free(path);
    return status;
}

/* 1 if a value that is not a number looks like a file meant as a map: an image's extension (before optional
 * ":r|g|b|a" and ":linear|srgb"), or the name of an existing file. */
static int looks_like_file(const char *value) {
    static const char *const extensions[] = {"png", "jpg", "jpeg", "exr", "hdr", "tif", "tiff", "bmp", "tga", "pfm"};
    const char *dot = strrchr(value, '.');
    size_t length = dot != NULL ? strcspn(dot + 1, ":") : 0;
    for (size_t k = 0; dot != NULL && strchr(dot, '/') == NULL && k < sizeof extensions / sizeof *extensions; k++)
        if (strlen(extensions[k]) == length && strncasecmp(dot + 1, extensions[k], length) == 0) return 1;
    struct stat st;
    return stat(value, &st) == 0 && S_ISREG(st.st_mode);
}

/* One name=value or name=@MAP[:c][:e] assignment into m. */
static mr_status assign(mr_material *m, const char *assignment, const mr_img_read_options *read, int *usage) {
    const char *eq = strchr(assignment, '=');
    if (eq == NULL) return usage_error(usage, "'%s' is not a NAME=VALUE or NAME=@FILE assignment", assignment);
    if (eq[1] == '@') return load_map(m, assignment, read, usage);
    mr_status status = mr_brdf_parse_assignment(m->model, assignment, m->values);
    if (status == MR_ERR_INVALID_ARG && looks_like_file(eq + 1)) { // "base_color=a.png": maps take '@'
        char message[1024];
        snprintf(message, sizeof message, "%s", mr_last_error());
        return mr_fail(status, "%s; did you mean %.*s=@%s? (a map is given as name=@FILE)", message,
                       (int)(eq - assignment), assignment, eq + 1);
    }
    return status;
}

mr_status mr_material_from_assignments(const char *model_name, const char *const *assignments, int count,
                                       const mr_material_text_options *options, mr_material **out,
                                       mr_material_text_report *report) {
    mr_material_text_report ignored;
    if (report == NULL) report = &ignored;
    report->failed = -1;
    report->usage = 0;
    if (out == NULL || model_name == NULL || (count > 0 && assignments == NULL))
        return mr_fail(MR_ERR_INVALID_ARG, "material from assignments: NULL model name, assignments or output");
    *out = NULL;
    const mr_brdf_model *model = mr_brdf_find(model_name);
    if (model == NULL) return MR_ERR_INVALID_ARG; // its message lists the models
    mr_img_read_options read = {MR_IMG_COLOR, 0, options != NULL ? options->max_dimension : 0};
    mr_material *m = NULL;
    mr_status status = mr_material_create(model, &m);
    for (int k = 0; k < count && status == MR_OK; k++) {
        status = assign(m, assignments[k], &read, &report->usage);
        if (status != MR_OK) report->failed = k;
    }
    if (status != MR_OK) {
        mr_material_free(m);
        return status;
    }
    *out = m;
    return MR_OK;
}

int mr_material_describe_invalid_texels(const mr_material *m, int k, char *text, size_t size) {
    size_t nonfinite = 0, negative = 0;
    if (size > 0) text[0] = '\0';
    if (mr_material_map_invalid_texels(m, k, &nonfinite, &negative) != MR_OK || nonfinite + negative == 0) return 0;
    const mr_material_map *map = &m->maps[k];
    size_t used = 0;
#define APPEND(...)                                                                     \
    do {                                                                                \
        if (used < size) used += (size_t)snprintf(text + used, size - used, __VA_ARGS__); \
    } while (0)
    APPEND("%s=@%s:", m->model->params[map->param].name, map->source);
    if (nonfinite > 0)
        APPEND(" %zu texel%s not finite, read as 0%s", nonfinite, nonfinite == 1 ? "" : "s", negative > 0 ? ";" : "");
    if (negative > 0) APPEND(" %zu negative, clamped to 0", negative);
#undef APPEND
    return 1;
}
