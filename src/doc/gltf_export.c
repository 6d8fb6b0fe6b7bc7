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
#include "io/image_io.h"
#include "doc/doc_internal.h"
#include "mr_internal.h"
#include "remap/remap.h"
#include "render/render.h"

const char *mr_doc_route_name(mr_doc_route route) {
    switch (route) {
    case MR_DOC_ROUTE_COPY: return "copy";
    case MR_DOC_ROUTE_REMAP: return "remap";
    case MR_DOC_ROUTE_MAPS: return "maps";
    }
    return NULL;
}

void mr_doc_gltf_result_free(mr_doc_gltf_result *result) {
    if (result == NULL) return;
    mr_doc_free(result->doc);
    free(result->materials);
    free(result->images);
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
    int to_gltf = o.target == gltf, to_usd = strcmp(o.target->name, "usd-preview") == 0;
    int sg_required = mr_gltf_extension_required(asset, "KHR_materials_pbrSpecularGlossiness");

    mr_doc_gltf_result *r = calloc(1, sizeof(*r));
    if (r) r->doc = mr_doc_create();
    if (r) r->materials = calloc((size_t)counts.materials, sizeof(*r->materials));
    if (r == NULL || r->doc == NULL || r->materials == NULL) {
        mr_doc_gltf_result_free(r);
        return mr_fail(MR_ERR_NOMEM, "glTF export: out of memory");
    }
    r->material_count = counts.materials;
    mr_doc_remapper remapper = {NULL, o.threads, o.size};
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
        if (textured(&gm)) {
            if (!to_gltf && !to_usd) {
                st = mr_fail(MR_ERR_UNSUPPORTED, "glTF '%s': material %d ('%s') is textured: no texture route to %s "
                             "yet (uniform materials are remapped; textured ones export to usd-preview or gltf: "
                             "--to usd-preview, --to gltf)", path, k, gm.name, o.target->name);
                break;
            }
            rm->route = MR_DOC_ROUTE_MAPS;
            st = carry_maps(asset, &o, r, k, &gm, m, gltf_v);
        } else if (to_gltf) {
            rm->route = MR_DOC_ROUTE_COPY;
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
    if (asset == NULL || result == NULL) return mr_fail(MR_ERR_INVALID_ARG, "glTF export: no asset or result");
    if (mr_doc_format_from_path(path) == MR_DOC_FORMAT_UNKNOWN)
        return mr_fail(MR_ERR_INVALID_ARG, "material document '%s': the extension chooses the format: .mtlx or .usda",
                       path ? path : "(null)");
    // The document is made in memory first, so that a model the format does not write fails before any image.
    char *text = NULL;
    mr_status st = mr_doc_to_text(result->doc, mr_doc_format_from_path(path), &text);
    if (st != MR_OK) return st;
    int written = 0;
    for (; written < result->image_count; written++)
        if ((st = mr_gltf_image_write_file(asset, result->images[written].image, result->images[written].path)) !=
            MR_OK)
            break;
    if (st == MR_OK) st = mr_atomic_write_bytes(path, text, strlen(text));
    free(text);
    if (st != MR_OK)
        for (int i = 0; i < written; i++) unlink(result->images[i].path);
    return st;
}
