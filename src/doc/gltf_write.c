/*
 * gltf_write.c — a document of gltf materials as a glTF asset (doc.h: mr_doc_to_gltf), over gltf/mr_gltf.h.
 */
#include "doc/doc.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "gltf/mr_gltf.h"
#include "mr_internal.h"

typedef struct image_slot {
    char file[4096]; /* as the document names it */
    int image;       /* the asset's image index */
} image_slot;

typedef struct writer {
    mr_gltf *asset;
    const char *doc_path, *label;
    image_slot *images;
    int image_count;
} writer;

static mr_wrap wrap_of(mr_doc_wrap w) {
    return w == MR_DOC_WRAP_CLAMP ? MR_WRAP_CLAMP : w == MR_DOC_WRAP_MIRROR ? MR_WRAP_MIRROR : MR_WRAP_REPEAT;
}

/* The texture of map v (an image per file, once; a texture per image and sampler, mr_gltf_add_texture reusing
 * samplers). */
static mr_status texture_of(writer *w, const char *material, const char *param, const mr_doc_value *v,
                            mr_gltf_texture_ref *ref) {
    const char *dot = strrchr(v->file, '.');
    if (dot == NULL || (strcasecmp(dot, ".png") != 0 && strcasecmp(dot, ".jpg") != 0 &&
                        strcasecmp(dot, ".jpeg") != 0))
        return mr_fail(MR_ERR_UNSUPPORTED, "%s: material '%s': the %s map '%s' is neither PNG nor JPEG, which glTF "
                       "needs", w->label, material, param, v->file);
    int image = -1;
    for (int i = 0; i < w->image_count && image < 0; i++)
        if (strcmp(w->images[i].file, v->file) == 0) image = w->images[i].image;
    if (image < 0) {
        char path[8192];
        const char *slash = strrchr(w->doc_path, '/');
        if (v->file[0] == '/' || slash == NULL)
            snprintf(path, sizeof path, "%s", v->file);
        else
            snprintf(path, sizeof path, "%.*s/%s", (int)(slash - w->doc_path), w->doc_path, v->file);
        // The file's name as its URI; a name already taken by another file gets the image's index before it.
        const char *base = strrchr(v->file, '/');
        base = base ? base + 1 : v->file;
        char uri[1024];
        snprintf(uri, sizeof uri, "%s", base);
        for (int i = 0; i < w->image_count; i++) {
            const char *other = strrchr(w->images[i].file, '/');
            if (strcmp(other ? other + 1 : w->images[i].file, base) == 0)
                snprintf(uri, sizeof uri, "%d_%s", w->image_count, base);
        }
        mr_status st = mr_gltf_add_image_file(w->asset, path, uri, &image);
        if (st != MR_OK) return st;
        image_slot *grown = realloc(w->images, (size_t)(w->image_count + 1) * sizeof(*grown));
        if (grown == NULL) return mr_fail(MR_ERR_NOMEM, "%s: out of memory", w->label);
        w->images = grown;
        snprintf(w->images[w->image_count].file, sizeof(w->images[0].file), "%s", v->file);
        w->images[w->image_count++].image = image;
    }
    mr_gltf_sampler sampler;
    memset(&sampler, 0, sizeof sampler);
    sampler.wrap_s = wrap_of(v->wrap_s);
    sampler.wrap_t = wrap_of(v->wrap_t);
    mr_gltf_texture_ref_none(ref);
    ref->tex_coord = v->uv_set;
    return mr_gltf_add_texture(w->asset, image, &sampler, &ref->index);
}

static mr_status refuse(writer *w, const char *material, const char *param, const char *why) {
    return mr_fail(MR_ERR_UNSUPPORTED, "%s: material '%s': the %s map: %s", w->label, material, param, why);
}

static mr_status one_material(writer *w, const mr_doc_material *m) {
    const mr_brdf_model *model = m->model;
    const mr_doc_value *v[6];
    static const char *const names[6] = {"base_color", "metallic", "roughness", "specular", "specular_color", "ior"};
    double values[MR_BRDF_MAX_VALUES];
    mr_brdf_default_values(model, values);
    for (int i = 0; i < 6; i++) {
        int p = mr_brdf_param_index(model, names[i]);
        v[i] = &m->values[p];
        if (v[i]->kind == MR_DOC_CONSTANT)
            for (int c = 0; c < model->params[p].channels; c++)
                values[mr_brdf_param_offset(model, p) + c] = v[i]->constant[c];
        else if (v[i]->kind == MR_DOC_TEXTURE)
            for (int c = 0; c < model->params[p].channels; c++)
                values[mr_brdf_param_offset(model, p) + c] = v[i]->scale[c];
    }
#define VAL(name) (values + mr_brdf_param_offset(model, mr_brdf_param_index(model, name)))
    mr_gltf_material g;
    mr_gltf_material_defaults(&g);
    g.name = m->name;
    memcpy(g.base_color_factor, VAL("base_color"), 3 * sizeof(double));
    g.metallic_factor = *VAL("metallic");
    g.roughness_factor = *VAL("roughness");
    mr_status st;
    if (v[0]->kind == MR_DOC_TEXTURE && (st = texture_of(w, m->name, "base_color", v[0], &g.base_color_texture)))
        return st;
    const mr_doc_value *metal = v[1]->kind == MR_DOC_TEXTURE ? v[1] : NULL;
    const mr_doc_value *rough = v[2]->kind == MR_DOC_TEXTURE ? v[2] : NULL;
    if (metal && metal->channel != 2)
        return refuse(w, m->name, "metallic", "glTF's metallicRoughnessTexture holds metallic in B (channel 2)");
    if (rough && rough->channel != 1)
        return refuse(w, m->name, "roughness", "glTF's metallicRoughnessTexture holds roughness in G (channel 1)");
    if (metal && rough && (strcmp(metal->file, rough->file) != 0 || metal->uv_set != rough->uv_set ||
                           metal->wrap_s != rough->wrap_s || metal->wrap_t != rough->wrap_t))
        return refuse(w, m->name, "metallic and roughness", "glTF holds them in one texture: one file, UV set and "
                      "wraps");
    if ((metal || rough) &&
        (st = texture_of(w, m->name, "metallic-roughness", metal ? metal : rough, &g.metallic_roughness_texture)))
        return st;
    // The extensions only where they say something: a map, or a factor other than the extension's default.
    const double *sc = VAL("specular_color");
    int specular = v[3]->kind == MR_DOC_TEXTURE || v[4]->kind == MR_DOC_TEXTURE || *VAL("specular") != 1 ||
                   sc[0] != 1 || sc[1] != 1 || sc[2] != 1;
    if (specular) {
        g.has_specular = 1;
        g.specular_strength = *VAL("specular");
        memcpy(g.specular_color_factor, VAL("specular_color"), 3 * sizeof(double));
        if (v[3]->kind == MR_DOC_TEXTURE && v[3]->channel != 3)
            return refuse(w, m->name, "specular", "KHR_materials_specular holds it in A (channel 3)");
        if (v[3]->kind == MR_DOC_TEXTURE && (st = texture_of(w, m->name, "specular", v[3], &g.specular_texture)))
            return st;
        if (v[4]->kind == MR_DOC_TEXTURE &&
            (st = texture_of(w, m->name, "specular_color", v[4], &g.specular_color_texture)))
            return st;
    }
    if (v[5]->kind == MR_DOC_TEXTURE) return refuse(w, m->name, "ior", "KHR_materials_ior's ior is a constant");
    if (v[5]->kind == MR_DOC_CONSTANT && *VAL("ior") != 1.5) {
        g.has_ior = 1;
        g.ior = *VAL("ior");
    }
#undef VAL
    return mr_gltf_add_material(w->asset, &g, NULL);
}

mr_status mr_doc_to_gltf(const mr_doc *doc, const char *doc_path, const char *label, mr_gltf **out) {
    if (doc == NULL || doc_path == NULL || out == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "material document to glTF: no document, path or output");
    if (label == NULL) label = "material document";
    const mr_brdf_model *gltf = mr_brdf_find("gltf");
    for (int k = 0; k < mr_doc_material_count(doc); k++)
        if (mr_doc_material_get(doc, k)->model != gltf)
            return mr_fail(MR_ERR_INVALID_ARG, "%s: material '%s' is %s: glTF holds gltf materials (convert first)",
                           label, mr_doc_material_get(doc, k)->name, mr_doc_material_get(doc, k)->model->name);
    writer w;
    memset(&w, 0, sizeof w);
    w.doc_path = doc_path;
    w.label = label;
    mr_status st = mr_gltf_create(label, &w.asset);
    for (int k = 0; k < mr_doc_material_count(doc) && st == MR_OK; k++)
        st = one_material(&w, mr_doc_material_get(doc, k));
    if (st == MR_OK) mr_gltf_sync_extensions(w.asset);
    free(w.images);
    if (st != MR_OK) {
        mr_gltf_free(w.asset);
        return st;
    }
    *out = w.asset;
    return MR_OK;
}
