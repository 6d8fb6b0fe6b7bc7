/*
 * cli_material.c — a material given on the command line, as `render` and `report` take it: MODEL followed by
 * name=value and name=@MAP[:r|g|b|a] assignments (cli.h). Maps are read the way their parameter needs them:
 * colour parameters (RGB, range within [0,1]) sRGB-decoded from 8/16-bit files, everything else linear.
 */
#include <stdlib.h>
#include <string.h>

#include "cli.h"

/* Split "name=@FILE[:c]" into map's name, path and channel; returns 0 (after a usage error) if malformed. */
static int parse_map_assignment(const char *command, const char *assignment, cli_material_map *map) {
    const char *eq = strchr(assignment, '=');
    size_t name_length = (size_t)(eq - assignment);
    const char *file = eq + 2;
    size_t file_length = strlen(file);
    map->assignment = assignment;
    map->channel = -1;
    if (file_length >= 3 && file[file_length - 2] == ':') {
        const char *letters = "rgba";
        const char *hit = strchr(letters, file[file_length - 1]);
        if (hit != NULL && *hit != '\0') {
            map->channel = (int)(hit - letters);
            file_length -= 2;
        }
    }
    if (name_length == 0 || file_length == 0) {
        cli_usage_error(command, "'%s': expected name=@FILE or name=@FILE:r|g|b|a", assignment);
        return 0;
    }
    map->name = malloc(name_length + 1);
    map->path = malloc(file_length + 1);
    if (map->name == NULL || map->path == NULL) {
        cli_usage_error(command, "out of memory");
        return 0;
    }
    memcpy(map->name, assignment, name_length);
    map->name[name_length] = '\0';
    memcpy(map->path, file, file_length);
    map->path[file_length] = '\0';
    return 1;
}

/* Read one map the way its parameter needs it and bind it; returns a CLI exit code (CLI_EXIT_OK on success). */
static int load_map(const char *command, const mr_brdf_model *model, cli_material_map *map,
                    mr_param_textures *textures) {
    int index = mr_brdf_param_index(model, map->name);
    if (index < 0) return cli_fail(command, mr_param_textures_set(textures, model, map->name, NULL, 0));
    const mr_brdf_param *param = &model->params[index];
    int colour = param->channels == 3 && param->min_value >= 0.0 && param->max_value <= 1.0;
    if (param->channels == 3 && map->channel >= 0)
        return cli_usage_error(command, "'%s': %s is an RGB parameter and takes the whole image (no :%c)",
                               map->assignment, param->name, "rgba"[map->channel]);
    mr_img_read_options read = {colour ? MR_IMG_COLOR : MR_IMG_DATA, 0, 0};
    mr_status status = mr_img_read(map->path, &read, &map->image);
    if (status != MR_OK) return cli_fail(command, status);
    int channel = param->channels == 3 ? 0 : map->channel; // an RGB parameter reads channels 0-2
    if (param->channels == 1 && channel < 0) {
        channel = 0;
        if (map->image->channels >= 3) {
            // A grey picture saved as RGB is fine; real colour needs the user to say which channel to use.
            size_t pixels = (size_t)map->image->width * (size_t)map->image->height;
            const float *px = map->image->pixels;
            for (size_t p = 0; p < pixels; p++, px += map->image->channels)
                if (px[0] != px[1] || px[0] != px[2])
                    return cli_usage_error(command, "'%s': %s holds colour, but %s takes one value: pick a channel "
                                           "with @%s:r, :g, :b or :a", map->assignment, map->path, param->name,
                                           map->path);
        }
    }
    map->param = index;
    map->channel = channel;
    status = mr_param_textures_set(textures, model, map->name, map->image, channel);
    if (status != MR_OK) return cli_fail(command, status);
    return CLI_EXIT_OK;
}

int cli_material_load(const char *command, const char *model_name, const char *const *assignments, int count,
                      cli_material *m) {
    memset(m, 0, sizeof *m);
    if (count > CLI_MAX_ASSIGNMENTS) return cli_usage_error(command, "too many parameter assignments");
    m->model = mr_brdf_find(model_name);
    if (m->model == NULL) return cli_fail(command, MR_ERR_INVALID_ARG);
    mr_brdf_default_values(m->model, m->values);
    for (int k = 0; k < count; k++) {
        int code = CLI_EXIT_OK;
        if (strchr(assignments[k], '=')[1] == '@') {
            cli_material_map *map = &m->maps[m->map_count++];
            code = parse_map_assignment(command, assignments[k], map)
                       ? load_map(command, m->model, map, &m->textures) : CLI_EXIT_USAGE;
        } else {
            mr_status status = mr_brdf_parse_assignment(m->model, assignments[k], m->values);
            if (status != MR_OK) code = cli_fail(command, status);
        }
        if (code != CLI_EXIT_OK) return code;
    }
    return CLI_EXIT_OK;
}

void cli_material_free(cli_material *m) {
    for (int k = 0; k < m->map_count; k++) {
        free(m->maps[k].name);
        free(m->maps[k].path);
        mr_image_free(m->maps[k].image);
    }
    m->map_count = 0;
}
