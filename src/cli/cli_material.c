/*
 * cli_material.c — a material given on the command line, as `render` and `report` take it: MODEL followed by
 * name=value and name=@MAP[:r|g|b|a][:linear|srgb] assignments (cli.h). Maps are read by the library's one rule
 * (mr_img_read_param_map, io/image_io.h): colour parameters (flagged MR_PARAM_SRGB_MAP) sRGB-decoded from 8/16-bit
 * files, everything else linear, float files linear, unless the map says :linear or :srgb. The result is the
 * library's mr_material (render/render.h), which owns the maps; this file only parses and reads.
 */
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>

#include "cli.h"

/* Read one map, "name=@FILE[:c][:e]", the way its parameter needs it (cli_read_map: the library's one rule, or the
 * map's :linear or :srgb) and bind it to m (which then owns the image); returns a CLI exit code (CLI_EXIT_OK on
 * success). */
static int load_map(const char *command, mr_material *m, const char *assignment) {
    const mr_brdf_model *model = m->model;
    const char *eq = strchr(assignment, '='), *file = eq + 2;
    if (eq == assignment)
        return cli_usage_error(command, "'%s': expected name=@FILE[:r|g|b|a][:linear|srgb]", assignment);
    int code = cli_check_map(command, assignment, file, 1);
    if (code != CLI_EXIT_OK) return code;
    size_t path_length;
    int channel;
    mr_map_encoding encoding;
    cli_split_map(file, 1, &path_length, &channel, &encoding);
    char *name = strndup(assignment, (size_t)(eq - assignment)), *path = strndup(file, path_length);
    if (name == NULL || path == NULL) {
        free(name);
        free(path);
        fprintf(stderr, "matremap %s: error: out of memory for '%s'\n", command, assignment);
        return CLI_EXIT_INTERNAL;
    }
    int index = mr_brdf_param_index(model, name);
    const mr_brdf_param *param = index >= 0 ? &model->params[index] : NULL;
    mr_image *image = NULL;
    if (param == NULL) {
        mr_param_textures unused = {0};
        code = cli_fail(command, mr_param_textures_set(&unused, model, name, NULL, 0));
    } else if (param->channels == 3 && channel >= 0) {
        code = cli_usage_error(command, "'%s': %s is an RGB parameter and takes the whole image (no :%c)", assignment,
                               param->name, "rgba"[channel]);
    } else {
        code = cli_read_map(command, assignment, file, 1, param, NULL, &image, NULL);
    }
    if (param != NULL && param->channels == 3) channel = 0; // an RGB parameter reads channels 0-2
    if (code == CLI_EXIT_OK && channel < 0) {
        channel = 0;
        if (image->channels >= 3) {
            // A grey picture saved as RGB is fine; real colour needs the user to say which channel to use.
            size_t pixels = (size_t)image->width * (size_t)image->height;
            const float *px = image->pixels;
            for (size_t p = 0; p < pixels && code == CLI_EXIT_OK; p++, px += image->channels)
                if (px[0] != px[1] || px[0] != px[2])
                    code = cli_usage_error(command, "'%s': %s holds colour, but %s takes one value: pick a channel "
                                           "with @%s:r, :g, :b or :a", assignment, path, param->name, path);
        }
    }
    if (code == CLI_EXIT_OK) {
        // The source as people read it (report's thumbnails): the file, and an override if the map gives one.
        char source[4200];
        snprintf(source, sizeof source, "%s%s", path,
                 encoding == MR_MAP_LINEAR ? ":linear" : encoding == MR_MAP_SRGB ? ":srgb" : "");
        mr_status status = mr_material_add_map(m, name, image, channel, source, NULL);
        if (status == MR_OK) image = NULL; // m owns it
        else code = cli_fail(command, status);
    }
    mr_image_free(image);
    free(name);
    free(path);
    return code;
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

/* One name=value or name=@MAP[:c][:e] assignment into m; returns a CLI exit code. */
static int assign(const char *command, mr_material *m, const char *assignment) {
    const char *eq = strchr(assignment, '=');
    if (eq == NULL) return cli_usage_error(command, "'%s' is not a NAME=VALUE or NAME=@FILE assignment", assignment);
    if (eq[1] != '@') {
        mr_status status = mr_brdf_parse_assignment(m->model, assignment, m->values);
        if (status == MR_OK) return CLI_EXIT_OK;
        if (status == MR_ERR_INVALID_ARG && looks_like_file(eq + 1)) { // "base_color=a.png": maps take '@'
            fprintf(stderr, "matremap %s: error: %s; did you mean %.*s=@%s? (a map is given as name=@FILE)\n",
                    command, mr_last_error(), (int)(eq - assignment), assignment, eq + 1);
            return cli_exit_code(status);
        }
        return cli_fail(command, status);
    }
    return load_map(command, m, assignment);
}

void cli_material_note_invalid_texels(const char *command, const mr_material *m) {
    for (int k = 0; m != NULL && k < m->map_count; k++) {
        size_t nonfinite = 0, negative = 0;
        if (mr_material_map_invalid_texels(m, k, &nonfinite, &negative) != MR_OK || nonfinite + negative == 0)
            continue;
        const mr_material_map *map = &m->maps[k];
        fprintf(stderr, "matremap %s: note: %s=@%s:", command, m->model->params[map->param].name, map->source);
        if (nonfinite > 0)
            fprintf(stderr, " %zu texel%s not finite, read as 0%s", nonfinite, nonfinite == 1 ? "" : "s",
                    negative > 0 ? ";" : "");
        if (negative > 0) fprintf(stderr, " %zu negative, clamped to 0", negative);
        fprintf(stderr, "\n");
    }
}

int cli_material_load(const char *command, const char *model_name, const char *const *assignments, int count,
                      mr_material **out) {
    *out = NULL;
    if (count > CLI_MAX_ASSIGNMENTS) return cli_usage_error(command, "too many parameter assignments");
    const mr_brdf_model *model = mr_brdf_find(model_name);
    if (model == NULL) return cli_fail(command, MR_ERR_INVALID_ARG);
    mr_material *m = NULL;
    mr_status status = mr_material_create(model, &m);
    if (status != MR_OK) return cli_fail(command, status);
    int code = CLI_EXIT_OK;
    for (int k = 0; k < count && code == CLI_EXIT_OK; k++) code = assign(command, m, assignments[k]);
    if (code != CLI_EXIT_OK) {
        mr_material_free(m);
        return code;
    }
    *out = m;
    return CLI_EXIT_OK;
}
