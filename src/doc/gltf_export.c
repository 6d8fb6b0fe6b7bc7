/*
 * gltf_export.c — a glTF asset's materials as a material document (doc.h: mr_doc_from_gltf, mr_doc_gltf_write).
 */
#include "doc/doc.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <unistd.h>

#include "gltf/mr_gltf.h"
#include "gltf/mr_gltf_scene.h"
#include "io/image_io.h"
#include "doc/doc_internal.h"
#include "learn/learned.h"
#include "mr_internal.h"
#include "remap/direct.h"
#include "remap/remap.h"
#include "render/render.h"
#include "transform/transform.h"

const char *mr_doc_route_name(mr_doc_route route) {
    switch (route) {
    case MR_DOC_ROUTE_COPY: return "copy";
    case MR_DOC_ROUTE_REMAP: return "remap";
    case MR_DOC_ROUTE_MAPS: return "maps";
    case MR_DOC_ROUTE_DIRECT: return "direct";
    case MR_DOC_ROUTE_LEARNED: return "learned";
    }
    return NULL;
}

mr_status mr_doc_choose_route(const mr_brdf_model *source, const mr_brdf_model *target, int textured,
                              int have_transforms, mr_doc_route *out) {
    if (source == NULL || target == NULL || out == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "document route: NULL model or result");
    if (!textured)
        *out = source == target ? MR_DOC_ROUTE_COPY : MR_DOC_ROUTE_REMAP;
    else if (source == target ||
             (strcmp(source->name, "gltf") == 0 && strcmp(target->name, "usd-preview") == 0) ||
             (strcmp(source->name, "usd-preview") == 0 && strcmp(target->name, "gltf") == 0))
        *out = MR_DOC_ROUTE_MAPS;
    else
        *out = have_transforms ? MR_DOC_ROUTE_LEARNED : MR_DOC_ROUTE_DIRECT;
    return MR_OK;
}

void mr_doc_gltf_result_free(mr_doc_gltf_result *result) {
    if (result == NULL) return;
    mr_doc_free(result->doc);
    free(result->materials);
    free(result->images);
    for (int i = 0; i < result->map_count; i++) mr_image_free(result->maps[i].image);
    free(result->maps);
    free(result);
}

/* The extension an image is written with: by its MIME type, else its URI's; NULL when neither says PNG or JPEG. */
static const char *image_extension(const mr_gltf_image *image) {
    if (strcmp(image->mime_type, "image/png") == 0) return "png";
    if (strcmp(image->mime_type, "image/jpeg") == 0) return "jpg";
    const char *dot = strrchr(image->uri, '.');
    if (dot && strcasecmp(dot, ".png") == 0) return "png";
    if (dot && (strcasecmp(dot, ".jpg") == 0 || strcasecmp(dot, ".jpeg") == 0)) return "jpg";
    return NULL;
}

/* The file the document names for texture `ref` of material `k`: the texture's image, added to the result's images
 * once (written as PREFIX_image<K>.<ext>). */
static mr_status texture_file(const mr_gltf *asset, const mr_doc_gltf_options *o, mr_doc_gltf_result *r, int k,
                              const char *label, const mr_gltf_texture_ref *ref, const char **file,
                              mr_doc_wrap wrap[2]) {
    const char *path = mr_gltf_path(asset);
    mr_gltf_material gm;
    mr_gltf_get_material(asset, k, &gm);
    if (ref->has_transform)
        return mr_fail(MR_ERR_UNSUPPORTED, "glTF '%s': material %d ('%s'): %s has a KHR_texture_transform, which "
                       "export does not write yet", path, k, gm.name, label);
    mr_gltf_texture texture;
    mr_status st = mr_gltf_get_texture(asset, ref->index, &texture);
    if (st != MR_OK) return st;
    // glTF's wraps; a sampler without them (MR_WRAP_DEFAULT) is glTF's default, REPEAT.
    wrap[0] = texture.params.wrap_s == MR_WRAP_CLAMP ? MR_DOC_WRAP_CLAMP
              : texture.params.wrap_s == MR_WRAP_MIRROR ? MR_DOC_WRAP_MIRROR : MR_DOC_WRAP_REPEAT;
    wrap[1] = texture.params.wrap_t == MR_WRAP_CLAMP ? MR_DOC_WRAP_CLAMP
              : texture.params.wrap_t == MR_WRAP_MIRROR ? MR_DOC_WRAP_MIRROR : MR_DOC_WRAP_REPEAT;
    if (texture.image < 0)
        return mr_fail(MR_ERR_UNSUPPORTED, "glTF '%s': material %d ('%s'): %s (texture %d) has no image", path, k,
                       gm.name, label, ref->index);
    for (int i = 0; i < r->image_count; i++)
        if (r->images[i].image == texture.image) {
            *file = r->images[i].file;
            return MR_OK;
        }
    mr_gltf_image image;
    st = mr_gltf_get_image(asset, texture.image, &image);
    if (st != MR_OK) return st;
    const char *ext = image_extension(&image);
    if (ext == NULL)
        return mr_fail(MR_ERR_UNSUPPORTED, "glTF '%s': image %d ('%s') is neither PNG nor JPEG", path, texture.image,
                       image.uri);
    if (o->image_prefix == NULL || o->image_prefix[0] == '\0')
        return mr_fail(MR_ERR_INVALID_ARG, "glTF '%s': material %d ('%s') is textured: no image prefix given", path,
                       k, gm.name);
    mr_doc_gltf_image *grown = realloc(r->images, (size_t)(r->image_count + 1) * sizeof(*grown));
    if (grown == NULL) return mr_fail(MR_ERR_NOMEM, "glTF export: out of memory");
    r->images = grown;
    mr_doc_gltf_image *out = &r->images[r->image_count];
    memset(out, 0, sizeof(*out));
    out->image = texture.image;
    char name[64];
    snprintf(name, sizeof(name), "image%d.%s", texture.image, ext);
    st = mr_img_prefixed_name(out->path, sizeof(out->path), o->image_prefix, name);
    if (st != MR_OK) return st;
    const char *slash = strrchr(out->path, '/');
    snprintf(out->file, sizeof(out->file), "%s", slash ? slash + 1 : out->path);
    r->image_count++;
    *file = out->file;
    return MR_OK;
}

static int textured(const mr_gltf_material *gm) {
    return gm->base_color_texture.index >= 0 || gm->metallic_roughness_texture.index >= 0 ||
           (gm->has_specular && (gm->specular_texture.index >= 0 || gm->specular_color_texture.index >= 0));
}

/* The gltf model's packed values of a material's factors (KHR_materials_specular and _ior when present). */
static void gltf_values(const mr_brdf_model *gltf, const mr_gltf_material *gm, double *values) {
    mr_brdf_default_values(gltf, values);
    int p = mr_brdf_param_offset(gltf, mr_brdf_param_index(gltf, "base_color"));
    for (int c = 0; c < 3; c++) values[p + c] = gm->base_color_factor[c];
    values[mr_brdf_param_offset(gltf, mr_brdf_param_index(gltf, "metallic"))] = gm->metallic_factor;
    values[mr_brdf_param_offset(gltf, mr_brdf_param_index(gltf, "roughness"))] = gm->roughness_factor;
    if (gm->has_specular) {
        values[mr_brdf_param_offset(gltf, mr_brdf_param_index(gltf, "specular"))] = gm->specular_strength;
        p = mr_brdf_param_offset(gltf, mr_brdf_param_index(gltf, "specular_color"));
        for (int c = 0; c < 3; c++) values[p + c] = gm->specular_color_factor[c];
    }
    if (gm->has_ior) values[mr_brdf_param_offset(gltf, mr_brdf_param_index(gltf, "ior"))] = gm->ior;
}

/* Every parameter of the material set to the packed values. */
mr_status mr_doc_set_all(mr_doc_material *m, const double *values) {
    for (int p = 0; p < m->model->param_count; p++) {
        mr_status st = mr_doc_set_constant(m, m->model->params[p].name, values + mr_brdf_param_offset(m->model, p));
        if (st != MR_OK) return st;
    }
    return MR_OK;
}

mr_status mr_doc_remap_values(mr_doc_remapper *rm, const mr_brdf_model *from, const double *values,
                              const mr_brdf_model *to, mr_doc_gltf_material *info, double *out) {
    mr_status st;
    if (rm->plan == NULL) {
        // The fit scene every other fit of the tool uses (remap, sweep, convert --direct), not the paper's
        // 512 x 512 frame: 64 times the pixels for the same verdict.
        mr_fit_scene_options so = {0};
        so.size = rm->size > 0 ? rm->size : MR_REMAP_DEFAULT_SIZE;
        mr_scene scene = mr_scene_fit(&so);
        scene.threads = rm->threads;
        if ((st = mr_render_plan_create(&scene, &rm->plan)) != MR_OK) return st;
    }
    mr_remap_options ro = mr_remap_options_default();
    ro.threads = rm->threads;
    ro.target_values = rm->target_values;
    ro.held = rm->held;
    ro.ties = rm->ties ? *rm->ties : mr_brdf_default_ties(from, to);
    ro.ties.tied &= ~rm->held; // a hold wins over a tie
    mr_remap_result fit;
    if ((st = mr_remap(rm->plan, from, values, to, &ro, &fit)) != MR_OK) return st;
    info->route = MR_DOC_ROUTE_REMAP;
    info->outcome = (int)fit.outcome;
    info->ssim = fit.ssim;
    info->relative_rmse = fit.relative_rmse;
    snprintf(info->detail, sizeof(info->detail), "%s", fit.detail);
    memcpy(out, fit.values, sizeof(fit.values));
    return MR_OK;
}

mr_doc_remapper mr_doc_remapper_of(const mr_doc_gltf_options *o) {
    mr_doc_remapper rm = {NULL, o->threads, o->size, o->target_values, o->held, o->ties};
    return rm;
}

void mr_doc_remapper_free(mr_doc_remapper *rm) {
    if (rm == NULL) return;
    mr_render_plan_free(rm->plan);
    rm->plan = NULL;
}

/* Textured material k carried over to gltf_pbr or usd-preview's metallic workflow (doc.h: MR_DOC_ROUTE_MAPS). */
static mr_status carry_maps(const mr_gltf *asset, const mr_doc_gltf_options *o, mr_doc_gltf_result *r, int k,
                            const mr_gltf_material *gm, mr_doc_material *m, const double *gltf_v) {
    int usd = strcmp(m->model->name, "usd-preview") == 0;
    const char *colour = usd ? "diffuse_color" : "base_color";
    const char *file = NULL;
    mr_doc_wrap w[2];
    mr_status st;
    // Constants first (every parameter the target has from the factors), textures over them.
    if (usd) {
        double v[3] = {gm->base_color_factor[0], gm->base_color_factor[1], gm->base_color_factor[2]};
        double zero = 0, ior = gm->has_ior ? gm->ior : 1.5;
        if ((st = mr_doc_set_constant(m, "diffuse_color", v)) != MR_OK ||
            (st = mr_doc_set_constant(m, "use_specular_workflow", &zero)) != MR_OK ||
            (st = mr_doc_set_constant(m, "metallic", &gm->metallic_factor)) != MR_OK ||
            (st = mr_doc_set_constant(m, "roughness", &gm->roughness_factor)) != MR_OK ||
            (st = mr_doc_set_constant(m, "ior", &ior)) != MR_OK)
            return st;
        if (gm->has_specular && (gm->specular_texture.index >= 0 || gm->specular_color_texture.index >= 0))
            return mr_fail(MR_ERR_UNSUPPORTED, "glTF '%s': material %d ('%s'): KHR_materials_specular textures have "
                           "no place in usd-preview's metallic workflow (--to gltf keeps them)", mr_gltf_path(asset),
                           k, gm->name);
    } else if ((st = mr_doc_set_all(m, gltf_v)) != MR_OK) {
        return st;
    }
    if (gm->base_color_texture.index >= 0) {
        if ((st = texture_file(asset, o, r, k, "baseColorTexture", &gm->base_color_texture, &file, w)) != MR_OK ||
            (st = mr_doc_set_texture(m, colour, file, -1, gm->base_color_texture.tex_coord, gm->base_color_factor)) !=
                MR_OK ||
            (st = mr_doc_set_texture_wrap(m, colour, w[0], w[1])) != MR_OK)
            return st;
    }
    if (gm->metallic_roughness_texture.index >= 0) {
        const mr_gltf_texture_ref *t = &gm->metallic_roughness_texture;
        if ((st = texture_file(asset, o, r, k, "metallicRoughnessTexture", t, &file, w)) != MR_OK ||
            (st = mr_doc_set_texture(m, "metallic", file, 2, t->tex_coord, &gm->metallic_factor)) != MR_OK ||
            (st = mr_doc_set_texture(m, "roughness", file, 1, t->tex_coord, &gm->roughness_factor)) != MR_OK ||
            (st = mr_doc_set_texture_wrap(m, "metallic", w[0], w[1])) != MR_OK ||
            (st = mr_doc_set_texture_wrap(m, "roughness", w[0], w[1])) != MR_OK)
            return st;
    }
    if (!usd && gm->has_specular && gm->specular_texture.index >= 0) {
        if ((st = texture_file(asset, o, r, k, "specularTexture", &gm->specular_texture, &file, w)) != MR_OK ||
            (st = mr_doc_set_texture(m, "specular", file, 3, gm->specular_texture.tex_coord,
                                     &gm->specular_strength)) != MR_OK ||
            (st = mr_doc_set_texture_wrap(m, "specular", w[0], w[1])) != MR_OK)
            return st;
    }
    if (!usd && gm->has_specular && gm->specular_color_texture.index >= 0) {
        const mr_gltf_texture_ref *t = &gm->specular_color_texture;
        if ((st = texture_file(asset, o, r, k, "specularColorTexture", t, &file, w)) != MR_OK ||
            (st = mr_doc_set_texture(m, "specular_color", file, -1, gm->specular_color_texture.tex_coord,
                                     gm->specular_color_factor)) != MR_OK ||
            (st = mr_doc_set_texture_wrap(m, "specular_color", w[0], w[1])) != MR_OK)
            return st;
    }
    return MR_OK;
}

/* The textures of material k that a conversion reads, with what the converted maps take from them: they must share
 * one UV set and one pair of wraps (a converted map holds every parameter of a texel of that set), and carry no
 * KHR_texture_transform. *uv_set and wrap[] receive them. */
static mr_status converted_sampling(const mr_gltf *asset, int k, const mr_gltf_material *gm, int *uv_set,
                                    mr_doc_wrap wrap[2]) {
    const struct {
        const mr_gltf_texture_ref *ref;
        const char *label;
    } refs[4] = {{&gm->base_color_texture, "baseColorTexture"},
                 {&gm->metallic_roughness_texture, "metallicRoughnessTexture"},
                 {gm->has_specular ? &gm->specular_texture : NULL, "specularTexture"},
                 {gm->has_specular ? &gm->specular_color_texture : NULL, "specularColorTexture"}};
    const char *path = mr_gltf_path(asset), *first = NULL;
    for (int i = 0; i < 4; i++) {
        if (refs[i].ref == NULL || refs[i].ref->index < 0) continue;
        if (refs[i].ref->has_transform)
            return mr_fail(MR_ERR_UNSUPPORTED, "glTF '%s': material %d ('%s'): %s has a KHR_texture_transform, which "
                           "export does not write yet", path, k, gm->name, refs[i].label);
        mr_gltf_texture texture;
        mr_status st = mr_gltf_get_texture(asset, refs[i].ref->index, &texture);
        if (st != MR_OK) return st;
        mr_doc_wrap w[2];
        w[0] = texture.params.wrap_s == MR_WRAP_CLAMP ? MR_DOC_WRAP_CLAMP
               : texture.params.wrap_s == MR_WRAP_MIRROR ? MR_DOC_WRAP_MIRROR : MR_DOC_WRAP_REPEAT;
        w[1] = texture.params.wrap_t == MR_WRAP_CLAMP ? MR_DOC_WRAP_CLAMP
               : texture.params.wrap_t == MR_WRAP_MIRROR ? MR_DOC_WRAP_MIRROR : MR_DOC_WRAP_REPEAT;
        if (first == NULL) {
            first = refs[i].label;
            *uv_set = refs[i].ref->tex_coord;
            wrap[0] = w[0];
            wrap[1] = w[1];
        } else if (*uv_set != refs[i].ref->tex_coord || wrap[0] != w[0] || wrap[1] != w[1]) {
            return mr_fail(MR_ERR_UNSUPPORTED, "glTF '%s': material %d ('%s'): %s and %s differ in UV set or wrap "
                           "mode: a converted map holds every parameter of a texel, so its maps must share both",
                           path, k, gm->name, first, refs[i].label);
        }
    }
    return MR_OK;
}

/* Whether the parameter's first `channels` channels hold one value over the whole image. */
static int constant_image(const mr_image *image, int channels) {
    size_t n = (size_t)image->width * (size_t)image->height, stride = (size_t)image->channels;
    for (size_t i = 1; i < n; i++)
        for (int c = 0; c < channels; c++)
            if (image->pixels[i * stride + (size_t)c] != image->pixels[(size_t)c]) return 0;
    return 1;
}

/* A converted map added to the result (taking `image`), named PREFIX_<stem>_<what>.png. */
static mr_status add_map(const mr_doc_gltf_options *o, mr_doc_gltf_result *r, int k, int param, const char *stem,
                         const char *what, mr_image *image, const char **file) {
    mr_doc_gltf_map *grown = realloc(r->maps, (size_t)(r->map_count + 1) * sizeof(*grown));
    if (grown == NULL) {
        mr_image_free(image);
        return mr_fail(MR_ERR_NOMEM, "glTF export: out of memory");
    }
    r->maps = grown;
    mr_doc_gltf_map *out = &r->maps[r->map_count++];
    memset(out, 0, sizeof(*out));
    out->material = k;
    out->param = param;
    out->image = image;
    snprintf(out->stem, sizeof(out->stem), "%s", stem);
    char name[512];
    snprintf(name, sizeof(name), "%s_%s.png", stem, what);
    mr_status st = mr_img_prefixed_name(out->path, sizeof(out->path), o->image_prefix, name);
    if (st != MR_OK) return st;
    const char *slash = strrchr(out->path, '/');
    snprintf(out->file, sizeof(out->file), "%s", slash ? slash + 1 : out->path);
    if (file) *file = out->file;
    return MR_OK;
}

/* State of one material's progress callback. */
typedef struct progress_relay {
    const mr_doc_gltf_options *o;
    int material;
} progress_relay;

static void relay_progress(const mr_direct_progress *p, void *user) {
    const progress_relay *relay = user;
    relay->o->progress(relay->material, p, relay->o->progress_user);
}

/* Textured material k converted into the target by the direct remap or the learned chain (doc.h:
 * MR_DOC_ROUTE_DIRECT, MR_DOC_ROUTE_LEARNED): the source material with its factors folded in
 * (mr_gltf_material_brdf), converted by mr_doc_convert_textured. */
static mr_status convert_maps(const mr_gltf *asset, const mr_doc_gltf_options *o, mr_doc_gltf_result *r, int k,
                              const mr_gltf_material *gm, mr_doc_material *m) {
    char where[4096 + 200];
    snprintf(where, sizeof where, "glTF '%s': material %d ('%s')", mr_gltf_path(asset), k, gm->name);
    if (o->image_prefix == NULL || o->image_prefix[0] == '\0')
        return mr_fail(MR_ERR_INVALID_ARG, "%s is textured: no image prefix given", where);
    int uv_set = 0;
    mr_doc_wrap wrap[2] = {MR_DOC_WRAP_REPEAT, MR_DOC_WRAP_REPEAT};
    mr_status st = converted_sampling(asset, k, gm, &uv_set, wrap);
    if (st != MR_OK) return st;
    mr_material *source = NULL;
    if ((st = mr_gltf_material_brdf(asset, k, 0, &source)) != MR_OK) return st;
    return mr_doc_convert_textured(o, r, k, where, gm->name, source, uv_set, wrap, m);
}

mr_status mr_doc_convert_textured(const mr_doc_gltf_options *o, mr_doc_gltf_result *r, int k, const char *where,
                                  const char *name, mr_material *source, int uv_set, const mr_doc_wrap wrap[2],
                                  mr_doc_material *m) {
    mr_doc_gltf_material *rm = &r->materials[k];
    const mr_brdf_model *from = source->model, *target = m->model;
    if (o->image_prefix == NULL || o->image_prefix[0] == '\0') {
        mr_material_free(source);
        return mr_fail(MR_ERR_INVALID_ARG, "%s is textured: no image prefix given", where);
    }
    mr_status st = MR_OK;
    // The chain, for the learned route.
    const mr_learned *chain[MR_LEARNED_MAX_HOPS];
    int hops = 0;
    if (rm->route == MR_DOC_ROUTE_LEARNED) {
        int path_index[MR_LEARNED_MAX_HOPS];
        st = mr_learned_find_chain((const mr_learned *const *)o->transforms->all, o->transforms->count, from, target,
                                   NULL, 0, path_index, &hops);
        if (st != MR_OK) {
            mr_material_free(source);
            return mr_fail_context(st, "%s", where);
        }
        for (int h = 0; h < hops; h++) chain[h] = o->transforms->all[path_index[h]];
    }
    mr_direct_options d = {0};
    d.tolerance = o->tolerance > 0 ? o->tolerance : MR_DOC_DEFAULT_TOLERANCE;
    d.remap.target_values = o->target_values;
    d.remap.held = o->held;
    d.remap.ties = o->ties ? *o->ties : mr_brdf_default_ties(from, target);
    d.remap.ties.tied &= ~o->held; // a hold wins over a tie (and the cache header says so)
    d.scene.size = o->size > 0 ? o->size : MR_REMAP_DEFAULT_SIZE;
    d.cache_path = o->cache_path;
    progress_relay relay = {o, k};
    if (o->progress != NULL) {
        d.progress = relay_progress;
        d.progress_user = &relay;
    }
    const mr_learned_conversion_spec spec = {.source = from, .target = target, .chain = chain, .hops = hops,
                                             .direct = &d, .material = source, .threads = o->threads};
    mr_learned_conversion c;
    st = mr_learned_convert_material(&spec, &c); // takes `source`
    if (st != MR_OK) return mr_fail_context(st, "%s", where);
    rm->width = c.width;
    rm->height = c.height;
    rm->texels = c.texels;
    rm->unconverged = c.extrapolated;
    rm->failed_check = c.failed_check;
    rm->clamped = c.clamped_output + c.clamped_input;
    rm->flagged = c.flagged;
    rm->hops = hops;
    rm->seconds = c.seconds;
    if (c.has_direct) {
        rm->unique = c.direct.unique;
        rm->tolerance = c.direct_tolerance;
        for (int i = 0; i < MR_FIT_OUTCOME_COUNT; i++) rm->outcomes[i] = c.direct.outcomes[i];
    }
    // The maps' names: PREFIX_<material>_<parameter>.png, the material's identifier made unique in the document.
    char stem[160];
    if (name != NULL && name[0] != '\0')
        mr_doc_identifier(name, stem, sizeof(stem));
    else
        snprintf(stem, sizeof(stem), "material%d", k);
    for (int j = 0; j < r->map_count; j++)
        if (r->maps[j].material != k && strcmp(r->maps[j].stem, stem) == 0) {
            snprintf(stem + strlen(stem), sizeof(stem) - strlen(stem), "_%d", k);
            break;
        }
    for (int p = 0; p < target->param_count && st == MR_OK; p++) {
        const mr_brdf_param *param = &target->params[p];
        mr_image *image = c.converted[p];
        if (param->role == MR_PARAM_SWITCH || constant_image(image, param->channels)) {
            double v[3] = {0, 0, 0};
            for (int ch = 0; ch < param->channels; ch++) v[ch] = image->pixels[ch];
            st = mr_doc_set_constant(m, param->name, v);
            continue;
        }
        const char *file = NULL;
        c.converted[p] = NULL; // the result's now
        if ((st = add_map(o, r, k, p, stem, param->name, image, &file)) == MR_OK &&
            (st = mr_doc_set_texture(m, param->name, file, -1, uv_set, NULL)) == MR_OK)
            st = mr_doc_set_texture_wrap(m, param->name, wrap[0], wrap[1]);
    }
    mr_image *picture = NULL;
    if (st == MR_OK) st = mr_flag_picture(c.flags, c.width, c.height, &mr_learned_flag_code, &picture);
    if (st == MR_OK) st = add_map(o, r, k, -1, stem, "flags", picture, NULL);
    mr_learned_conversion_free(&c);
    return st;
}

mr_status mr_doc_from_gltf(const mr_gltf *asset, const mr_doc_gltf_options *opts, mr_doc_gltf_result **out) {
    mr_doc_gltf_options o = opts ? *opts : (mr_doc_gltf_options){0};
    if (asset == NULL || out == NULL) return mr_fail(MR_ERR_INVALID_ARG, "glTF export: no asset or result");
    const mr_brdf_model *gltf = mr_brdf_find("gltf");
    if (o.target == NULL) o.target = mr_brdf_find("openpbr");
    if (gltf == NULL || o.target == NULL) return MR_ERR_INVALID_ARG; // the registry's message
    const char *path = mr_gltf_path(asset);
    mr_gltf_counts counts;
    mr_gltf_get_counts(asset, &counts);
    if (counts.materials == 0) return mr_fail(MR_ERR_INVALID_ARG, "glTF '%s': no materials to export", path);
    if (mr_doc_surface_node(o.target, MR_DOC_FORMAT_MTLX) == NULL &&
        mr_doc_surface_node(o.target, MR_DOC_FORMAT_USDA) == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "glTF export: no document writes model '%s' (openpbr, standard-surface, "
                       "gltf, usd-preview)", o.target->name);
    int sg_required = mr_gltf_extension_required(asset, "KHR_materials_pbrSpecularGlossiness");

    mr_doc_gltf_result *r = calloc(1, sizeof(*r));
    if (r) r->doc = mr_doc_create();
    if (r) r->materials = calloc((size_t)counts.materials, sizeof(*r->materials));
    if (r == NULL || r->doc == NULL || r->materials == NULL) {
        mr_doc_gltf_result_free(r);
        return mr_fail(MR_ERR_NOMEM, "glTF export: out of memory");
    }
    r->material_count = counts.materials;
    mr_doc_remapper remapper = mr_doc_remapper_of(&o);
    mr_status st = MR_OK;
    for (int k = 0; k < counts.materials && st == MR_OK; k++) {
        mr_gltf_material gm;
        if ((st = mr_gltf_get_material(asset, k, &gm)) != MR_OK) break;
        mr_doc_gltf_material *rm = &r->materials[k];
        snprintf(rm->name, sizeof(rm->name), "%s", gm.name);
        rm->outcome = -1;
        rm->ssim = 1;
        if (sg_required && gm.has_spec_gloss) {
            st = mr_fail(MR_ERR_UNSUPPORTED, "glTF '%s': material %d ('%s') is spec-gloss only "
                         "(KHR_materials_pbrSpecularGlossiness required): convert it first with "
                         "'matremap gltf spec2metal'", path, k, gm.name);
            break;
        }
        double gltf_v[MR_BRDF_MAX_VALUES];
        gltf_values(gltf, &gm, gltf_v);
        mr_doc_material *m = NULL;
        if ((st = mr_doc_add_material(r->doc, gm.name, o.target, &m)) != MR_OK) break;
        if ((st = mr_doc_choose_route(gltf, o.target, textured(&gm), o.transforms != NULL, &rm->route)) != MR_OK)
            break;
        if (rm->route == MR_DOC_ROUTE_MAPS) {
            st = carry_maps(asset, &o, r, k, &gm, m, gltf_v);
        } else if (rm->route == MR_DOC_ROUTE_DIRECT || rm->route == MR_DOC_ROUTE_LEARNED) {
            st = convert_maps(asset, &o, r, k, &gm, m);
        } else if (rm->route == MR_DOC_ROUTE_COPY) {
            st = mr_doc_set_all(m, gltf_v);
        } else {
            double fitted[MR_BRDF_MAX_VALUES];
            if ((st = mr_doc_remap_values(&remapper, gltf, gltf_v, o.target, rm, fitted)) != MR_OK) break;
            st = mr_doc_set_all(m, fitted);
        }
    }
    mr_doc_remapper_free(&remapper);
    if (st != MR_OK) {
        mr_doc_gltf_result_free(r);
        return st;
    }
    *out = r;
    return MR_OK;
}

mr_status mr_doc_gltf_write(const mr_gltf *asset, const mr_doc_gltf_result *result, const char *path) {
    if ((asset == NULL && result != NULL && result->image_count > 0) || result == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "glTF export: no asset or result");
    if (mr_doc_format_from_path(path) == MR_DOC_FORMAT_UNKNOWN)
        return mr_fail(MR_ERR_INVALID_ARG, "material document '%s': the extension chooses the format: .mtlx or .usda",
                       path ? path : "(null)");
    // The document is made in memory first, so that a model the format does not write fails before any image.
    char *text = NULL;
    mr_status st = mr_doc_to_text(result->doc, mr_doc_format_from_path(path), &text);
    if (st != MR_OK) return st;
    int written = 0, maps_written = 0;
    for (; written < result->image_count; written++)
        if ((st = mr_gltf_image_write_file(asset, result->images[written].image, result->images[written].path)) !=
            MR_OK)
            break;
    // The converted maps, all or none, by the one rule of parameter maps (so they read back as written).
    if (st == MR_OK && result->map_count > 0) {
        mr_img_set_item *items = calloc((size_t)result->map_count, sizeof(*items));
        if (items == NULL) st = mr_fail(MR_ERR_NOMEM, "glTF export: out of memory");
        for (int i = 0; st == MR_OK && i < result->map_count; i++) {
            const mr_doc_gltf_map *map = &result->maps[i];
            const mr_doc_material *m = mr_doc_material_get(result->doc, map->material);
            mr_img_encoding encoding = MR_IMG_DATA;
            if (map->param >= 0 && m != NULL)
                encoding = mr_brdf_param_map_encoding(&m->model->params[map->param], MR_MAP_AS_PARAMETER);
            items[i] = (mr_img_set_item){map->path, NULL, map->image, {encoding, 8, 0}};
        }
        mr_img_set_options set_options = {0};
        if (st == MR_OK) st = mr_img_write_set(items, result->map_count, &set_options, NULL);
        if (st == MR_OK) maps_written = 1;
        free(items);
    }
    if (st == MR_OK) st = mr_atomic_write_bytes(path, text, strlen(text));
    free(text);
    if (st != MR_OK) {
        for (int i = 0; i < written; i++) unlink(result->images[i].path);
        for (int i = 0; maps_written && i < result->map_count; i++) unlink(result->maps[i].path);
    }
    return st;
}
