/*
 * texture_set.c — a texture set converted: maps read and checked, converted, packed into output images (contract in
 * transform.h, "texture-set conversions").
 */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

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

/* ---- a texture set's maps as text, its files and its figures ------------------------------------------------ */

int mr_texture_constant_like(const char *text) {
    return text != NULL && text[0] != '\0' && strspn(text, "0123456789.,+-eE") == strlen(text);
}

mr_status mr_texture_constant_parse(const char *text, int colour, double out[3]) {
    if (text == NULL || out == NULL) return mr_fail(MR_ERR_INVALID_ARG, "texture constant: NULL argument");
    double values[3];
    int count = 0;
    for (const char *p = text;;) { // left to right: the first number outside [0, 1] is the one named
        char *end = NULL;
        errno = 0;
        double v = strtod(p, &end);
        if (end == p || errno == ERANGE || !isfinite(v) || count == 3 || (*end != ',' && *end != '\0')) {
            count = -1;
            break;
        }
        if (v < 0.0 || v > 1.0) return mr_fail(MR_ERR_INVALID_ARG, "%g is outside [0, 1]", v);
        values[count++] = v;
        if (*end == '\0') break;
        p = end + 1;
    }
    if (count == 1) values[1] = values[2] = values[0];
    if (count == 1 || (count == 3 && colour)) {
        memcpy(out, values, sizeof values);
        return MR_OK;
    }
    return mr_fail(MR_ERR_FORMAT, "'%s': expected one number%s in [0, 1]", text, colour ? " or R,G,B" : "");
}

const char *mr_texture_format_from_name(const char *text) {
    static const char *const formats[] = {"png", "exr", "tif", "tiff"};
    for (int k = 0; text != NULL && k < 4; k++)
        if (strcasecmp(text, formats[k]) == 0) return formats[k < 3 ? k : 2];
    return NULL;
}

const char *mr_texture_default_format(const char *const *paths, int count) {
    for (int k = 0; paths != NULL && k < count; k++) {
        if (paths[k] == NULL) continue;
        const char *dot = strrchr(paths[k], '.');
        const char *format = dot != NULL && strchr(dot, '/') == NULL ? mr_texture_format_from_name(dot + 1) : NULL;
        return format ? format : "png";
    }
    return "png";
}

mr_status mr_texture_check_bits(const char *format, int bits) {
    if (format == NULL) return mr_fail(MR_ERR_INVALID_ARG, "texture bits: NULL format");
    const int exr = strcmp(format, "exr") == 0;
    if (bits == 0 || (exr ? (bits == 16 || bits == 32) : (bits == 8 || bits == 16))) return MR_OK;
    return mr_fail(MR_ERR_INVALID_ARG, "%s files take %s", format, exr ? "16 (half) or 32 (float)" : "8 or 16");
}

mr_status mr_texture_output_path(const char *prefix, const mr_texture_layout *layout, const char *format, char *out,
                                 size_t size) {
    if (prefix == NULL || layout == NULL || layout->name == NULL || format == NULL || out == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "texture output path: NULL argument");
    char name[256];
    const int n = snprintf(name, sizeof name, "%s.%s", layout->name, format);
    if (n < 0 || (size_t)n >= sizeof name)
        return mr_fail(MR_ERR_INVALID_ARG, "output name '%s': too long", layout->name);
    return mr_img_prefixed_name(out, size, prefix, name);
}

#define WRITE_PATH_SIZE 4096

mr_status mr_texture_set_write(const mr_texture_result *result, const mr_texture_layout *layouts, int count,
                               const mr_texture_write_options *opts) {
    if (result == NULL || layouts == NULL || opts == NULL || opts->prefix == NULL || count < 0 ||
        count > MR_TEXTURE_MAX_OUTPUTS)
        return mr_fail(MR_ERR_INVALID_ARG, "texture set write: NULL argument or %d outputs", count);
    const char *format = opts->format != NULL ? opts->format : "png";
    mr_status status = mr_texture_check_bits(format, opts->bits);
    if (status != MR_OK) return status;
    mr_img_set_item items[MR_TEXTURE_MAX_OUTPUTS + 1];
    char paths[MR_TEXTURE_MAX_OUTPUTS][WRITE_PATH_SIZE];
    int item_count = 0;
    for (int k = 0; k < count; k++) {
        if (result->outputs[k] == NULL)
            return mr_fail(MR_ERR_INVALID_ARG, "texture set write: output %d (%s) not in the result", k,
                           layouts[k].name);
        if ((status = mr_texture_output_path(opts->prefix, &layouts[k], format, paths[k], sizeof paths[k])) != MR_OK)
            return status;
        items[item_count++] = (mr_img_set_item){paths[k], opts->prefix_label, result->outputs[k],
                                                {layouts[k].encoding, opts->bits, 0}};
    }
    mr_image *picture = NULL;
    if (opts->flags_path != NULL) {
        status = mr_flag_picture(result->flags, result->width, result->height,
                                 opts->flag_code != NULL ? opts->flag_code : &mr_workflow_flag_code, &picture);
        if (status != MR_OK) return status;
        // MR_IMG_DATA: the exact colours of the code.
        items[item_count++] = (mr_img_set_item){opts->flags_path, opts->flags_label, picture, {MR_IMG_DATA, 0, 0}};
    }
    const mr_img_set_options set_options = {opts->threads};
    status = mr_img_write_set(items, item_count, &set_options, NULL);
    mr_image_free(picture);
    return status;
}

mr_status mr_texture_set_stats(const mr_texture_result *result, int slot, mr_texture_stats *out) {
    if (result == NULL || out == NULL || slot < 0 || slot >= MR_TRANSFORM_MAX_SLOTS || result->converted[slot] == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "texture set stats: no converted slot %d", slot);
    const mr_image *image = result->converted[slot];
    const int channels = image->channels;
    if (channels != 1 && channels != 3)
        return mr_fail(MR_ERR_INVALID_ARG, "texture set stats: slot %d has %d channels", slot, channels);
    const size_t n = (size_t)result->width * (size_t)result->height;
    double lo[3], hi[3], sum[3];
    for (int c = 0; c < channels; c++) {
        lo[c] = INFINITY;
        hi[c] = -INFINITY;
        sum[c] = 0.0;
    }
    for (size_t i = 0; i < n; i++)
        for (int c = 0; c < channels; c++) {
            double x = image->pixels[i * (size_t)channels + (size_t)c];
            lo[c] = x < lo[c] ? x : lo[c];
            hi[c] = x > hi[c] ? x : hi[c];
            sum[c] += x;
        }
    memset(out, 0, sizeof *out);
    out->channels = channels;
    for (int c = 0; c < channels; c++) {
        out->min[c] = lo[c];
        out->mean[c] = sum[c] / (double)n;
        out->max[c] = hi[c];
    }
    return MR_OK;
}
