/*
 * material.c — materials that own their maps (contract in render.h, "materials that own their maps").
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "../mr_internal.h"
#include "render.h"

mr_status mr_material_create(const mr_brdf_model *model, mr_material **out) {
    if (out == NULL) return mr_fail(MR_ERR_INVALID_ARG, "material: NULL output");
    if (model == NULL) return mr_fail(MR_ERR_INVALID_ARG, "material: NULL model");
    mr_material *m = calloc(1, sizeof *m);
    if (m == NULL) return mr_fail(MR_ERR_NOMEM, "material '%s': out of memory", model->name);
    m->model = model;
    mr_brdf_default_values(model, m->values);
    *out = m;
    return MR_OK;
}

mr_status mr_material_add_map(mr_material *m, const char *param, mr_image *image, int channel, const char *source,
                              const mr_texture_sampling *sampling) {
    if (m == NULL || param == NULL || image == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "material map: NULL material, parameter or image");
    const int index = mr_brdf_param_index(m->model, param);
    // Checked on a copy, so that a refusal (or no memory below) leaves the material as it was.
    mr_param_textures textures = m->textures;
    mr_status status = mr_param_textures_set(&textures, m->model, param, image, channel);
    if (status != MR_OK) return status;
    if (sampling != NULL) textures.sampling[index] = *sampling;
    mr_material_map *maps = realloc(m->maps, ((size_t)m->map_count + 1) * sizeof *maps);
    char *copy = strdup(source != NULL ? source : "");
    if (maps != NULL) m->maps = maps;
    if (maps == NULL || copy == NULL) {
        free(copy);
        return mr_fail(MR_ERR_NOMEM, "material '%s': out of memory for the map of %s", m->model->name, param);
    }
    maps[m->map_count++] = (mr_material_map){index, channel, image, copy};
    m->textures = textures;
    return MR_OK;
}

mr_status mr_material_map_invalid_texels(const mr_material *m, int k, size_t *nonfinite, size_t *negative) {
    if (m == NULL || nonfinite == NULL || negative == NULL || k < 0 || k >= m->map_count)
        return mr_fail(MR_ERR_INVALID_ARG, "material map texels: NULL argument or map %d outside 0 .. %d", k,
                       m != NULL ? m->map_count - 1 : -1);
    const mr_material_map *map = &m->maps[k];
    const mr_image *image = map->image;
    // The channels texture sampling reads (mr_param_textures): a grey map's one, else the parameter's.
    const int count = m->model->params[map->param].channels, stride = image->channels;
    const int first = stride == 1 ? 0 : map->channel, read = stride == 1 ? 1 : count;
    const size_t texels = (size_t)image->width * (size_t)image->height;
    size_t not_finite = 0, below_zero = 0;
    for (size_t i = 0; i < texels; i++) {
        const float *px = image->pixels + i * (size_t)stride + first;
        int bad = 0, low = 0;
        for (int c = 0; c < read; c++) {
            bad |= !isfinite(px[c]);
            low |= px[c] < 0.0f;
        }
        not_finite += bad;
        below_zero += !bad && low;
    }
    *nonfinite = not_finite;
    *negative = below_zero;
    return MR_OK;
}

mr_material_binding mr_material_binding_of(const mr_material *m) {
    mr_material_binding binding = {m->model, m->values, &m->textures};
    return binding;
}

void mr_material_free(mr_material *m) {
    if (m == NULL) return;
    for (int k = 0; k < m->map_count; k++) {
        mr_image_free(m->maps[k].image);
        free(m->maps[k].source);
    }
    free(m->maps);
    free(m);
}
