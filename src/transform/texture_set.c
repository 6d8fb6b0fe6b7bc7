/*
 * texture_set.c — a texture set converted: maps read and checked, converted, packed into output images (contract in
 * transform.h, "texture-set conversions").
 */
#include <stdlib.h>
#include <string.h>

#include "mr_internal.h"
#include "render/render.h"
#include "transform.h"

void mr_texture_result_free(mr_texture_result *r) {
    if (r == NULL) return;
    for (int j = 0; j < MR_TRANSFORM_MAX_SLOTS; j++) mr_image_free(r->converted[j]);
    for (int l = 0; l < MR_TEXTURE_MAX_OUTPUTS; l++) mr_image_free(r->outputs[l]);
    free(r->flags);
    memset(r, 0, sizeof *r);
    r->failed_map = -1;
}

static void free_maps(const mr_texture_set *set) {
    for (int k = 0; k < set->map_count; k++) {
        mr_image_free(set->maps[k].image);
        set->maps[k].image = NULL;
    }
}

/* The set's sources and layouts name maps, slots and channels that exist. */
static mr_status check_set(const mr_transform_kind *kind, const mr_texture_set *set) {
    if (set->layout_count < 0 || set->layout_count > MR_TEXTURE_MAX_OUTPUTS || set->map_count < 1)
        return mr_fail(MR_ERR_INVALID_ARG, "texture set: %d maps and %d layouts (1 map or more, at most %d layouts)",
                       set->map_count, set->layout_count, MR_TEXTURE_MAX_OUTPUTS);
    for (int i = 0; i < kind->input_count; i++)
        if (set->inputs[i].map < 0 || set->inputs[i].map >= set->map_count || set->inputs[i].channel > 3)
            return mr_fail(MR_ERR_INVALID_ARG, "texture set: input %s reads map %d channel %d, which is not there",
                           kind->inputs[i].name, set->inputs[i].map, set->inputs[i].channel);
    for (int l = 0; l < set->layout_count; l++) {
        const mr_texture_layout *lay = &set->layouts[l];
        if (lay->channels < 1 || lay->channels > 4)
            return mr_fail(MR_ERR_INVALID_ARG, "texture set: layout %s has %d channels", lay->name, lay->channels);
        for (int c = 0; c < lay->channels; c++) {
            const int j = lay->slot[c];
            if (j == MR_LAYOUT_ZERO || (j == MR_LAYOUT_ALPHA && c == lay->channels - 1)) continue;
            if (j < 0 || j >= kind->output_count || lay->channel[c] < 0 ||
                lay->channel[c] >= kind->outputs[j].channels)
                return mr_fail(MR_ERR_INVALID_ARG, "texture set: layout %s channel %d reads output %d channel %d, "
                               "which is not there", lay->name, c, j, lay->channel[c]);
        }
    }
    return MR_OK;
}

mr_status mr_transform_convert_texture_set(const mr_transform *t, const mr_texture_set *set, mr_texture_result *out) {
    memset(out, 0, sizeof *out);
    out->failed_map = -1;
    const mr_transform_kind *kind = mr_transform_kind_of(t);
    mr_status status = check_set(kind, set);
    if (status != MR_OK) return status;

    // Read: the maps into the transform's input planes.
    double started = mr_now_seconds();
    status = mr_img_read_texture_set(set->maps, set->map_count, NULL, set->threads, &out->width, &out->height,
                                     &out->failed_map);
    if (status != MR_OK) {
        out->failed_reading = out->failed_map >= 0 && set->maps[out->failed_map].image == NULL;
        free_maps(set);
        return status;
    }
    mr_transform_map in[MR_TRANSFORM_MAX_SLOTS];
    for (int i = 0; i < kind->input_count; i++) {
        const mr_texture_source *from = &set->inputs[i];
        const mr_img_param_map *map = &set->maps[from->map];
        const double *value = set->constants[from->map];
        // NaN and infinities stay non-finite through the complement: the transform reads them (flagged).
        in[i] = (mr_transform_map){map->image, from->channel < 0 ? 0 : from->channel, from->complement,
                                   {value[0], value[1], value[2]}, {0, 0, {1.0, 1.0, 1.0}}};
        if (!set->exact) // each value known to half a code of its file (workflow.h, "Tolerances")
            in[i].stored = mr_wf_quantisation_of(map->path != NULL ? &map->stored : NULL, NULL);
    }
    out->seconds[0] = mr_now_seconds() - started;

    // Convert; the first map is kept for its alpha, the rest freed.
    started = mr_now_seconds();
    status = mr_transform_convert_maps(t, in, out->converted, &out->flags);
    mr_image *alpha = NULL;
    if (set->maps[0].image != NULL && set->maps[0].image->channels == 4) {
        alpha = set->maps[0].image;
        set->maps[0].image = NULL;
    }
    free_maps(set);
    out->seconds[1] = mr_now_seconds() - started;

    // Pack the outputs.
    started = mr_now_seconds();
    for (int l = 0; l < set->layout_count && status == MR_OK; l++) {
        const mr_texture_layout *lay = &set->layouts[l];
        mr_image_channel sources[4];
        const int channels = lay->channels - (lay->slot[lay->channels - 1] == MR_LAYOUT_ALPHA && alpha == NULL);
        for (int c = 0; c < channels; c++) {
            const int j = lay->slot[c];
            sources[c] = j == MR_LAYOUT_ALPHA  ? (mr_image_channel){alpha, 3}
                         : j == MR_LAYOUT_ZERO ? (mr_image_channel){NULL, 0}
                                               : (mr_image_channel){out->converted[j], lay->channel[c]};
        }
        status = mr_image_pack(out->width, out->height, channels, sources, 0.0f, &out->outputs[l]);
    }
    mr_image_free(alpha);
    out->seconds[2] = mr_now_seconds() - started;
    if (status != MR_OK) mr_texture_result_free(out);
    return status;
}

mr_status mr_transform_convert_material(const mr_transform *t, const mr_material *material, mr_image **out,
                                        uint8_t **flags) {
    const mr_transform_kind *kind = mr_transform_kind_of(t);
    const mr_brdf_model *model = material->model;
    if (strcmp(model->name, kind->source) != 0)
        return mr_fail(MR_ERR_INVALID_ARG, "a material of %s given to a transform of %s", model->name, kind->source);
    mr_transform_map in[MR_TRANSFORM_MAX_SLOTS];
    const mr_image *alpha_source = NULL;
    for (int i = 0; i < kind->input_count; i++) {
        const int p = mr_brdf_param_index(model, kind->inputs[i].name);
        if (p < 0)
            return mr_fail(MR_ERR_INVALID_ARG, "transform input %s is no parameter of %s", kind->inputs[i].name,
                           model->name);
        const int at = mr_brdf_param_offset(model, p);
        const double *v = material->values + at;
        in[i] = (mr_transform_map){NULL, 0, 0, {v[0], v[0], v[0]}, {0}};
        if (model->params[p].channels == 3)
            for (int c = 0; c < 3; c++) in[i].value[c] = v[c];
        for (int k = 0; k < material->map_count; k++) // the last map of a parameter is the one bound
            if (material->maps[k].param == p) {
                in[i].image = material->maps[k].image;
                in[i].channel = material->maps[k].channel;
            }
        if (in[i].image != NULL && alpha_source == NULL && in[i].image->channels == 4) alpha_source = in[i].image;
    }
    mr_image *converted[MR_TRANSFORM_MAX_SLOTS] = {NULL};
    uint8_t *texel_flags = NULL;
    mr_status status = mr_transform_convert_maps(t, in, converted, &texel_flags);
    for (int j = 0; j < kind->output_count && status == MR_OK; j++) {
        mr_image *carried = NULL;
        status = mr_image_with_alpha(converted[j], alpha_source, &carried);
        if (status == MR_OK && carried != converted[j]) {
            mr_image_free(converted[j]);
            converted[j] = carried;
        }
    }
    if (status != MR_OK) {
        for (int j = 0; j < MR_TRANSFORM_MAX_SLOTS; j++) mr_image_free(converted[j]);
        free(texel_flags);
        return status;
    }
    for (int j = 0; j < kind->output_count; j++) out[j] = converted[j];
    if (flags != NULL)
        *flags = texel_flags;
    else
        free(texel_flags);
    return MR_OK;
}
