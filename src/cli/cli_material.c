/*
 * cli_material.c — a material given on the command line, as `render` and `report` take it: MODEL followed by
 * name=value and name=@MAP[:r|g|b|a] assignments (cli.h). Maps are read the way their parameter needs them:
 * colour parameters (RGB, range within [0,1]) sRGB-decoded from 8/16-bit files, everything else linear. The
 * result is the library's mr_material (render/render.h), which owns the maps; this file only parses and reads.
 */
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>

#include "cli.h"

/* A map assignment split up: "name=@FILE[:c]". */
typedef struct map_assignment {
    const char *text; /* as given: "roughness=@orm.png:g" */
    char *name, *path; /* owned copies */
    int channel;       /* -1: none given */
} map_assignment;

/* Split "name=@FILE[:c]" into map's name, path and channel; returns a CLI exit code (CLI_EXIT_USAGE after a usage
 * error if malformed, CLI_EXIT_INTERNAL when out of memory). */
static int parse_map_assignment(const char *command, const char *assignment, map_assignment *map) {
    const char *eq = strchr(assignment, '=');
    size_t name_length = (size_t)(eq - assignment);
    const char *file = eq + 2;
    size_t file_length = strlen(file);
    map->text = assignment;
    map->channel = -1;
    if (file_length >= 3 && file[file_length - 2] == ':') {
        const char *letters = "rgba";
        const char *hit = strchr(letters, file[file_length - 1]);
        if (hit != NULL && *hit != '\0') {
            map->channel = (int)(hit - letters);
            file_length -= 2;
        }
    }
    if (name_length == 0 || file_length == 0)
        return cli_usage_error(command, "'%s': expected name=@FILE or name=@FILE:r|g|b|a", assignment);
    map->name = malloc(name_length + 1);
    map->path = malloc(file_length + 1);
    if (map->name == NULL || map->path == NULL) { // not a usage error: the caller frees what was allocated
        fprintf(stderr, "matremap %s: error: out of memory for '%s'\n", command, assignment);
        return CLI_EXIT_INTERNAL;
    }
    memcpy(map->name, assignment, name_length);
    map->name[name_length] = '\0';
    memcpy(map->path, file, file_length);
    map->path[file_length] = '\0';
    return CLI_EXIT_OK;
}

/* Read one map the way its parameter needs it and bind it to m (which then owns the image); returns a CLI exit
 * code (CLI_EXIT_OK on success). */
static int load_map(const char *command, mr_material *m, const map_assignment *map) {
    const mr_brdf_model *model = m->model;
    int index = mr_brdf_param_index(model, map->name);
    if (index < 0) {
        mr_param_textures unused = {0};
        return cli_fail(command, mr_param_textures_set(&unused, model, map->name, NULL, 0));
    }
    const mr_brdf_param *param = &model->params[index];
    int colour = param->channels == 3 && param->min_value >= 0.0 && param->max_value <= 1.0;
    if (param->channels == 3 && map->channel >= 0)
        return cli_usage_error(command, "'%s': %s is an RGB parameter and takes the whole image (no :%c)",
                               map->text, param->name, "rgba"[map->channel]);
    mr_img_read_options read = {colour ? MR_IMG_COLOR : MR_IMG_DATA, 0, 0};
    mr_image *image = NULL;
    mr_status status = mr_img_read(map->path, &read, &image);
    if (status != MR_OK) return cli_fail(command, status);
    int channel = param->channels == 3 ? 0 : map->channel; // an RGB parameter reads channels 0-2
    if (param->channels == 1 && channel < 0) {
        channel = 0;
        if (image->channels >= 3) {
            // A grey picture saved as RGB is fine; real colour needs the user to say which channel to use.
            size_t pixels = (size_t)image->width * (size_t)image->height;
            const float *px = image->pixels;
            for (size_t p = 0; p < pixels; p++, px += image->channels)
                if (px[0] != px[1] || px[0] != px[2]) {
                    mr_image_free(image);
                    return cli_usage_error(command, "'%s': %s holds colour, but %s takes one value: pick a "
                                           "channel with @%s:r, :g, :b or :a", map->text, map->path, param->name,
                                           map->path);
                }
        }
    }
    status = mr_material_add_map(m, map->name, image, channel, map->path, NULL);
    if (status != MR_OK) {
        mr_image_free(image);
        return cli_fail(command, status);
    }
    return CLI_EXIT_OK;
}

/* 1 if a value that is not a number looks like a file meant as a map: an image's extension (before an optional
 * ":r|g|b|a"), or the name of an existing file. */
static int looks_like_file(const char *value) {
    static const char *const extensions[] = {"png", "jpg", "jpeg", "exr", "hdr", "tif", "tiff", "bmp", "tga", "pfm"};
    const char *dot = strrchr(value, '.');
    size_t length = dot != NULL ? strcspn(dot + 1, ":") : 0;
    for (size_t k = 0; dot != NULL && strchr(dot, '/') == NULL && k < sizeof extensions / sizeof *extensions; k++)
        if (strlen(extensions[k]) == length && strncasecmp(dot + 1, extensions[k], length) == 0) return 1;
    struct stat st;
    return stat(value, &st) == 0 && S_ISREG(st.st_mode);
}

/* One name=value or name=@MAP[:c] assignment into m; returns a CLI exit code. */
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
    map_assignment map = {0};
    int code = parse_map_assignment(command, assignment, &map);
    if (code == CLI_EXIT_OK)
        code = load_map(command, m, &map);
    free(map.name);
    free(map.path);
    return code;
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
