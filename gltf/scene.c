/*
 * scene.c — a glTF asset's scene as meshes and material bindings for the renderer (contract in mr_gltf_scene.h).
 *
 * Steps: the scene's triangles (mr_gltf_get_triangles); one slot per distinct material; per slot the BRDF
 * (load_brdf: factors folded into maps) and the surface (load_surface); then the groups merged into one mesh
 * (merge_groups). Every failure goes to one cleanup: mr_gltf_scene_free on the half-built scene.
 */
#include "gltf/mr_gltf_scene.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "mr_internal.h"

/* What the loaders need to name: the asset, and the slot's material. */
typedef struct load_context {
    const mr_gltf *asset;
    const char *path;
    const char *material; /* the slot's name */
} load_context;

/* How the renderer samples a glTF texture reference: its sampler's wrap modes, its coordinate set and its
 * KHR_texture_transform. A coordinate set past TEXCOORD_1 is MR_ERR_UNSUPPORTED naming the asset, the material
 * and the texture (`what`). */
static mr_status texture_sampling(const load_context *ctx, const mr_gltf_texture_ref *ref, const char *what,
                                  mr_texture_sampling *out) {
    memset(out, 0, sizeof *out);
    mr_gltf_texture texture;
    mr_status status = mr_gltf_get_texture(ctx->asset, ref->index, &texture);
    if (status != MR_OK)
        return mr_fail_context(status, "glTF '%s': material '%s': %s", ctx->path, ctx->material, what);
    // glTF's default is REPEAT on both axes (the renderer's MR_WRAP_DEFAULT is the sphere's convention).
    out->wrap_u = texture.params.wrap_s == MR_WRAP_DEFAULT ? MR_WRAP_REPEAT : texture.params.wrap_s;
    out->wrap_v = texture.params.wrap_t == MR_WRAP_DEFAULT ? MR_WRAP_REPEAT : texture.params.wrap_t;
    out->texcoord = ref->has_transform && ref->transform_tex_coord >= 0 ? ref->transform_tex_coord : ref->tex_coord;
    if (out->texcoord > 1)
        return mr_fail(MR_ERR_UNSUPPORTED, "glTF '%s': material '%s': %s reads TEXCOORD_%d; the renderer reads "
                       "TEXCOORD_0 and _1", ctx->path, ctx->material, what, out->texcoord);
    out->has_transform = ref->has_transform;
    out->offset[0] = ref->offset[0];
    out->offset[1] = ref->offset[1];
    out->rotation = ref->rotation;
    out->scale[0] = ref->scale[0];
    out->scale[1] = ref->scale[1];
    return MR_OK;
}

/* Decode texture `ref` (colour: RGB sRGB-decoded, alpha linear; data: all linear) into *out, with its sampling.
 * Errors name the asset, the material and the texture (`what`). */
static mr_status read_texture(const load_context *ctx, const mr_gltf_texture_ref *ref, mr_img_encoding encoding,
                              const char *what, mr_texture_sampling *sampling, mr_image **out) {
    mr_status status = texture_sampling(ctx, ref, what, sampling);
    if (status != MR_OK) return status;
    mr_img_read_options read = {0};
    read.encoding = encoding;
    status = mr_gltf_texture_read(ctx->asset, ref->index, &read, out, NULL);
    if (status != MR_OK)
        return mr_fail_context(status, "glTF '%s': material '%s': %s", ctx->path, ctx->material, what);
    return MR_OK;
}

/* One parameter's share of a texture: channels first.. (count 1 or 3) times factor, named `label`. */
typedef struct texture_fold {
    const char *name, *label;
    int first, count;
    const double *factor;
} texture_fold;

/* A map for fold's parameter of m's model: channels `first`.. of `source` (a grey source answers every channel,
 * a missing alpha is 1) times the factor, as a new image the material owns, sampled as `sampling` says. */
static mr_status fold_map(mr_material *m, const texture_fold *fold, const mr_image *source,
                          const mr_texture_sampling *sampling) {
    mr_image *map = NULL;
    mr_status status = mr_image_create(source->width, source->height, fold->count, &map);
    if (status != MR_OK) return status;
    size_t n = (size_t)source->width * (size_t)source->height;
    for (size_t i = 0; i < n; i++)
        for (int c = 0; c < fold->count; c++) {
            int from = source->channels == 1 ? 0 : fold->first + c;
            float value = from < source->channels ? source->pixels[i * (size_t)source->channels + (size_t)from]
                                                  : 1.0f;
            map->pixels[i * (size_t)fold->count + (size_t)c] = (float)(value * fold->factor[c]);
        }
    status = mr_material_add_map(m, fold->name, map, 0, fold->label, sampling);
    if (status != MR_OK) mr_image_free(map);
    return status;
}

/* Decode texture `ref` once (with `encoding`) and fold it into the `fold_count` parameters that read it (a
 * packed texture feeds two). No texture: nothing to do. */
static mr_status fold_texture(const load_context *ctx, const mr_gltf_texture_ref *ref, mr_img_encoding encoding,
                              mr_material *m, const texture_fold *folds, int fold_count) {
    if (ref->index < 0) return MR_OK;
    mr_texture_sampling sampling;
    mr_image *image = NULL;
    mr_status status = read_texture(ctx, ref, encoding, folds[0].label, &sampling, &image);
    for (int f = 0; f < fold_count && status == MR_OK; f++) status = fold_map(m, &folds[f], image, &sampling);
    mr_image_free(image);
    return status;
}

/* Set parameter `name` of m to `count` values. */
static void set_values(mr_material *m, const char *name, const double *v, int count) {
    int p = mr_brdf_param_index(m->model, name);
    int offset = mr_brdf_param_offset(m->model, p);
    for (int c = 0; c < count; c++) m->values[offset + c] = v[c];
}

/* A spec-gloss material as `gltf-specgloss`. */
static mr_status load_specgloss(const load_context *ctx, const mr_gltf_material *mat, mr_material *m) {
    set_values(m, "diffuse", mat->diffuse_factor, 3);
    set_values(m, "specular", mat->specular_factor, 3);
    set_values(m, "glossiness", &mat->glossiness_factor, 1);
    const texture_fold diffuse = {"diffuse", "diffuseTexture", 0, 3, mat->diffuse_factor};
    const texture_fold specgloss[2] = {{"specular", "specularGlossinessTexture RGB", 0, 3, mat->specular_factor},
                                       {"glossiness", "specularGlossinessTexture A", 3, 1, &mat->glossiness_factor}};
    mr_status status = fold_texture(ctx, &mat->diffuse_texture, MR_IMG_COLOR, m, &diffuse, 1);
    if (status == MR_OK)
        status = fold_texture(ctx, &mat->specular_glossiness_texture, MR_IMG_COLOR, m, specgloss, 2);
    return status;
}

/* A metal-rough material (with KHR_materials_specular and _ior) as `gltf`. */
static mr_status load_metalrough(const load_context *ctx, const mr_gltf_material *mat, mr_material *m) {
    double ior = mat->has_ior ? mat->ior : 1.5, rendered_ior = ior > 5.0 ? 5.0 : (ior < 1.0 ? 1.0 : ior);
    double f0 = pow((ior - 1.0) / (ior + 1.0), 2.0);
    double rendered_f0 = pow((rendered_ior - 1.0) / (rendered_ior + 1.0), 2.0);
    double scale = rendered_f0 > 0.0 ? f0 / rendered_f0 : 1.0;
    double colour[3];
    for (int c = 0; c < 3; c++) colour[c] = (mat->has_specular ? mat->specular_color_factor[c] : 1.0) * scale;
    double strength = mat->has_specular ? mat->specular_strength : 1.0;
    set_values(m, "base_color", mat->base_color_factor, 3);
    set_values(m, "metallic", &mat->metallic_factor, 1);
    set_values(m, "roughness", &mat->roughness_factor, 1);
    set_values(m, "specular", &strength, 1);
    set_values(m, "specular_color", colour, 3);
    set_values(m, "ior", &rendered_ior, 1);
    const texture_fold base = {"base_color", "baseColorTexture", 0, 3, mat->base_color_factor};
    const texture_fold metal_rough[2] = {{"metallic", "metallicRoughnessTexture B", 2, 1, &mat->metallic_factor},
                                         {"roughness", "metallicRoughnessTexture G", 1, 1, &mat->roughness_factor}};
    const texture_fold specular_colour = {"specular_color", "specularColorTexture", 0, 3, colour};
    const texture_fold specular = {"specular", "specularTexture A", 3, 1, &strength};
    mr_status status = fold_texture(ctx, &mat->base_color_texture, MR_IMG_COLOR, m, &base, 1);
    if (status == MR_OK)
        status = fold_texture(ctx, &mat->metallic_roughness_texture, MR_IMG_DATA, m, metal_rough, 2);
    if (status == MR_OK && mat->has_specular)
        status = fold_texture(ctx, &mat->specular_color_texture, MR_IMG_COLOR, m, &specular_colour, 1);
    if (status == MR_OK && mat->has_specular)
        status = fold_texture(ctx, &mat->specular_texture, MR_IMG_DATA, m, &specular, 1);
    return status;
}

/* One glTF material as a BRDF material (see "Materials" in the header) into *out. */
static mr_status load_brdf(const load_context *ctx, const mr_gltf_material *mat, mr_material **out) {
    const mr_brdf_model *model = mr_brdf_find(mat->has_spec_gloss ? "gltf-specgloss" : "gltf");
    mr_status status = mr_material_create(model, out);
    if (status != MR_OK) return status;
    return mat->has_spec_gloss ? load_specgloss(ctx, mat, *out) : load_metalrough(ctx, mat, *out);
}

mr_status mr_gltf_material_brdf(const mr_gltf *asset, int material, int spec_gloss, mr_material **out) {
    if (out != NULL) *out = NULL;
    if (asset == NULL || out == NULL) return mr_fail(MR_ERR_INVALID_ARG, "glTF material: NULL asset or result");
    mr_gltf_material mat;
    mr_status status = mr_gltf_get_material(asset, material, &mat);
    if (status != MR_OK) return status;
    char name[160];
    if (mat.name[0] != '\0')
        snprintf(name, sizeof name, "%s", mat.name);
    else
        snprintf(name, sizeof name, "material %d", material);
    const load_context ctx = {asset, mr_gltf_path(asset), name};
    if (spec_gloss < 0) {
        status = load_brdf(&ctx, &mat, out);
    } else if (spec_gloss && !mat.has_spec_gloss) {
        return mr_fail(MR_ERR_INVALID_ARG, "glTF '%s': material '%s' has no KHR_materials_pbrSpecularGlossiness",
                       ctx.path, name);
    } else {
        status = mr_material_create(mr_brdf_find(spec_gloss ? "gltf-specgloss" : "gltf"), out);
        if (status == MR_OK) status = spec_gloss ? load_specgloss(&ctx, &mat, *out) : load_metalrough(&ctx, &mat, *out);
    }
    if (status != MR_OK) {
        mr_material_free(*out);
        *out = NULL;
    }
    return status;
}

/* The material's surface: sidedness, normal map and scale, occlusion map and strength, emission (factor times
 * map). Decoded maps go to the slot (owned by the scene). */
static mr_status load_surface(const load_context *ctx, const mr_gltf_material *mat, mr_surface *surface,
                              mr_gltf_scene_material *slot) {
    memset(surface, 0, sizeof *surface);
    surface->double_sided = mat->double_sided;
    surface->normal_scale = mat->normal_texture.value;
    surface->occlusion_strength = mat->occlusion_texture.value;
    for (int c = 0; c < 3; c++) surface->emission[c] = mat->emissive_factor[c];
    const struct {
        const mr_gltf_texture_ref *ref;
        mr_img_encoding encoding;
        const char *what;
        mr_image **owned;
        const mr_image **map;
        mr_texture_sampling *sampling;
    } textures[3] = {
        {&mat->normal_texture, MR_IMG_DATA, "normalTexture", &slot->normal_map, &surface->normal_map,
         &surface->normal_sampling},
        {&mat->occlusion_texture, MR_IMG_DATA, "occlusionTexture", &slot->occlusion_map, &surface->occlusion_map,
         &surface->occlusion_sampling},
        {&mat->emissive_texture, MR_IMG_COLOR, "emissiveTexture", &slot->emissive_map, &surface->emissive_map,
         &surface->emissive_sampling},
    };
    for (int k = 0; k < 3; k++) {
        if (textures[k].ref->index < 0) continue;
        if (k == 2 && !(surface->emission[0] > 0.0 || surface->emission[1] > 0.0 || surface->emission[2] > 0.0))
            continue; // a black emissive factor: the map changes nothing
        mr_status status = read_texture(ctx, textures[k].ref, textures[k].encoding, textures[k].what,
                                        textures[k].sampling, textures[k].owned);
        if (status != MR_OK) return status;
        const mr_image *map = *textures[k].owned;
        if (k == 0 && map->channels < 3)
            return mr_fail(MR_ERR_FORMAT, "glTF '%s': material '%s': normalTexture has %d channel(s), expected RGB",
                           ctx->path, ctx->material, map->channels);
        *textures[k].map = map;
    }
    return MR_OK;
}

/* Concatenate the groups' vertices into the scene's mesh (an attribute some groups lack is zero there: normals
 * and tangents generated by the renderer, UVs (0, 0)); triangle material = the slot of the group's material. */
static mr_status merge_groups(const mr_gltf_triangles *t, const int *slot_of_group, mr_gltf_scene *s) {
    const size_t nv = (size_t)t->vertex_count, nt = (size_t)t->triangle_count;
    int any_normals = 0, any_tangents = 0, any_uv0 = 0, any_uv1 = 0;
    for (int g = 0; g < t->group_count; g++) {
        any_normals |= t->groups[g].has_normals;
        any_tangents |= t->groups[g].has_tangents;
        any_uv0 |= t->groups[g].has_uv0;
        any_uv1 |= t->groups[g].has_uv1;
    }
    float *positions = malloc(nv * 3 * sizeof(float));
    uint32_t *indices = malloc(nt * 3 * sizeof(uint32_t));
    uint16_t *triangle_materials = malloc(nt * sizeof(uint16_t));
    float *normals = any_normals ? calloc(nv * 3, sizeof(float)) : NULL;
    float *tangents = any_tangents ? calloc(nv * 4, sizeof(float)) : NULL;
    float *uvs = any_uv0 ? calloc(nv * 2, sizeof(float)) : NULL;
    float *uvs1 = any_uv1 ? calloc(nv * 2, sizeof(float)) : NULL;
    // The mesh owns them from here on (mr_gltf_scene_free releases them, whichever were allocated).
    s->mesh.positions = positions;
    s->mesh.indices = indices;
    s->mesh.triangle_materials = triangle_materials;
    s->mesh.normals = normals;
    s->mesh.tangents = tangents;
    s->mesh.uvs = uvs;
    s->mesh.uvs1 = uvs1;
    if (!positions || !indices || !triangle_materials || (any_normals && !normals) || (any_tangents && !tangents) ||
        (any_uv0 && !uvs) || (any_uv1 && !uvs1))
        return mr_fail(MR_ERR_NOMEM, "glTF '%s': out of memory for %zu vertices", s->path, nv);
    size_t vertex_base = 0, triangle_base = 0;
    for (int g = 0; g < t->group_count; g++) {
        const mr_gltf_triangle_group *group = &t->groups[g];
        const size_t v = (size_t)group->vertex_count, f = (size_t)group->triangle_count;
        memcpy(positions + 3 * vertex_base, group->positions, v * 3 * sizeof(float));
        if (group->has_normals) memcpy(normals + 3 * vertex_base, group->normals, v * 3 * sizeof(float));
        if (group->has_tangents) memcpy(tangents + 4 * vertex_base, group->tangents, v * 4 * sizeof(float));
        if (group->has_uv0) memcpy(uvs + 2 * vertex_base, group->uv0, v * 2 * sizeof(float));
        if (group->has_uv1) memcpy(uvs1 + 2 * vertex_base, group->uv1, v * 2 * sizeof(float));
        for (size_t i = 0; i < 3 * f; i++) indices[3 * triangle_base + i] = group->indices[i] + (uint32_t)vertex_base;
        for (size_t i = 0; i < f; i++) triangle_materials[triangle_base + i] = (uint16_t)slot_of_group[g];
        vertex_base += v;
        triangle_base += f;
    }
    s->mesh.vertex_count = t->vertex_count;
    s->mesh.triangle_count = t->triangle_count;
    s->mesh.material_count = s->material_count;
    s->mesh.surfaces = s->surfaces;
    return MR_OK;
}

/* One slot per distinct material (groups of one material with different attribute sets share it): the slots'
 * glTF materials into s, each group's slot into slot_of_group[]. */
static mr_status make_slots(const mr_gltf_triangles *t, int *slot_of_group, mr_gltf_scene *s) {
    int *gltf_material = malloc((size_t)t->group_count * sizeof *gltf_material);
    if (gltf_material == NULL) return mr_fail(MR_ERR_NOMEM, "glTF '%s': out of memory", s->path);
    int count = 0;
    for (int g = 0; g < t->group_count; g++) {
        int slot = 0;
        while (slot < count && gltf_material[slot] != t->groups[g].material) slot++;
        if (slot == count) gltf_material[count++] = t->groups[g].material;
        slot_of_group[g] = slot;
    }
    if (count > MR_MESH_MAX_MATERIALS) {
        free(gltf_material);
        return mr_fail(MR_ERR_UNSUPPORTED, "glTF '%s': its scene uses %d materials; the renderer takes at most %d",
                       s->path, count, MR_MESH_MAX_MATERIALS);
    }
    s->materials = calloc((size_t)count, sizeof *s->materials);
    s->surfaces = calloc((size_t)count, sizeof *s->surfaces);
    s->bindings = calloc((size_t)count, sizeof *s->bindings);
    if (s->materials != NULL) s->material_count = count; // what mr_gltf_scene_free walks
    for (int k = 0; s->materials != NULL && k < count; k++) s->materials[k].gltf_material = gltf_material[k];
    free(gltf_material);
    if (s->materials == NULL || s->surfaces == NULL || s->bindings == NULL)
        return mr_fail(MR_ERR_NOMEM, "glTF '%s': out of memory for %d materials", s->path, count);
    return MR_OK;
}

/* Slot k: its name, BRDF, surface and binding. */
static mr_status load_slot(const mr_gltf *asset, mr_gltf_scene *s, int k) {
    mr_gltf_scene_material *slot = &s->materials[k];
    mr_gltf_material mat;
    if (slot->gltf_material >= 0) {
        mr_status status = mr_gltf_get_material(asset, slot->gltf_material, &mat);
        if (status != MR_OK) return status;
    } else {
        mr_gltf_material_defaults(&mat);
    }
    char fallback[32];
    snprintf(fallback, sizeof fallback, "material %d", slot->gltf_material);
    slot->name = strdup(mat.name != NULL && mat.name[0] != '\0' ? mat.name : fallback);
    if (slot->name == NULL) return mr_fail(MR_ERR_NOMEM, "glTF '%s': out of memory", s->path);
    const load_context ctx = {asset, s->path, slot->name};
    mr_status status = load_brdf(&ctx, &mat, &slot->brdf);
    if (status == MR_OK) status = load_surface(&ctx, &mat, &s->surfaces[k], slot);
    if (status == MR_OK) s->bindings[k] = mr_material_binding_of(slot->brdf);
    return status;
}

mr_status mr_gltf_scene_from_asset(const mr_gltf *asset, const mr_gltf_scene_options *opts, mr_gltf_scene **out) {
    if (out == NULL) return mr_fail(MR_ERR_INVALID_ARG, "glTF scene: NULL output");
    *out = NULL;
    if (asset == NULL) return mr_fail(MR_ERR_INVALID_ARG, "glTF scene: NULL asset");
    const mr_gltf_scene_options defaults = {0};
    if (opts == NULL) opts = &defaults;
    if (opts->has_scene && opts->scene < 0)
        return mr_fail(MR_ERR_INVALID_ARG, "glTF '%s': scene %d: expected a scenes[] index", mr_gltf_path(asset),
                       opts->scene);
    mr_gltf_scene *s = calloc(1, sizeof *s);
    if (s == NULL || (s->path = strdup(mr_gltf_path(asset))) == NULL) {
        free(s);
        return mr_fail(MR_ERR_NOMEM, "glTF '%s': out of memory", mr_gltf_path(asset));
    }
    mr_gltf_triangles *t = NULL;
    int *slot_of_group = NULL;
    mr_status status = mr_gltf_get_triangles(asset, opts->has_scene ? opts->scene : -1, &t);
    if (status == MR_OK && t->triangle_count == 0)
        status = mr_fail(MR_ERR_INVALID_ARG, "'%s': its scene has no triangles to render", s->path);
    if (status == MR_OK) {
        slot_of_group = malloc((size_t)t->group_count * sizeof *slot_of_group);
        if (slot_of_group == NULL) status = mr_fail(MR_ERR_NOMEM, "glTF '%s': out of memory", s->path);
    }
    if (status == MR_OK) status = make_slots(t, slot_of_group, s);
    for (int k = 0; status == MR_OK && k < s->material_count; k++) status = load_slot(asset, s, k);
    if (status == MR_OK) status = merge_groups(t, slot_of_group, s);
    if (status == MR_OK) {
        memcpy(s->bbox_min, t->bbox_min, sizeof s->bbox_min);
        memcpy(s->bbox_max, t->bbox_max, sizeof s->bbox_max);
        s->primitive_count = t->primitive_count;
    }
    free(slot_of_group);
    mr_gltf_triangles_free(t);
    if (status != MR_OK) {
        mr_gltf_scene_free(s);
        return status;
    }
    *out = s;
    return MR_OK;
}

mr_status mr_gltf_scene_load(const char *path, const mr_gltf_scene_options *opts, mr_gltf_scene **out) {
    if (out == NULL) return mr_fail(MR_ERR_INVALID_ARG, "glTF scene: NULL output");
    *out = NULL;
    mr_gltf *asset = NULL;
    mr_status status = mr_gltf_load(path, &asset);
    if (status == MR_OK) status = mr_gltf_scene_from_asset(asset, opts, out);
    mr_gltf_free(asset);
    return status;
}

mr_status mr_gltf_scene_frame(const mr_gltf_scene *scene, const double *direction, int width, int height,
                              mr_camera *out) {
    if (scene == NULL || out == NULL) return mr_fail(MR_ERR_INVALID_ARG, "glTF scene frame: NULL argument");
    const double *lo = scene->bbox_min, *hi = scene->bbox_max;
    int thin = 0;
    for (int c = 1; c < 3; c++)
        if (hi[c] - lo[c] < hi[thin] - lo[thin]) thin = c;
    mr_frame_options frame = {0};
    frame.width = width;
    frame.height = height;
    for (int c = 0; c < 3; c++) frame.from[c] = direction != NULL ? direction[c] : (c == thin ? 1.0 : 0.35);
    if (direction != NULL && frame.from[0] == 0.0 && frame.from[1] == 0.0 && frame.from[2] == 0.0)
        return mr_fail(MR_ERR_INVALID_ARG, "glTF scene '%s': a camera direction of (0, 0, 0) points nowhere",
                       scene->path ? scene->path : "?");
    return mr_camera_frame_mesh(&scene->mesh, &frame, out);
}

void mr_gltf_scene_free(mr_gltf_scene *s) {
    if (s == NULL) return;
    for (int k = 0; s->materials != NULL && k < s->material_count; k++) {
        mr_gltf_scene_material *slot = &s->materials[k];
        free(slot->name);
        mr_material_free(slot->brdf);
        mr_image_free(slot->normal_map);
        mr_image_free(slot->occlusion_map);
        mr_image_free(slot->emissive_map);
    }
    free(s->materials);
    free(s->surfaces);
    free(s->bindings);
    // The mesh's arrays are the scene's (merge_groups): const only as the renderer reads them.
    free((void *)s->mesh.positions);
    free((void *)s->mesh.normals);
    free((void *)s->mesh.tangents);
    free((void *)s->mesh.uvs);
    free((void *)s->mesh.uvs1);
    free((void *)s->mesh.indices);
    free((void *)s->mesh.triangle_materials);
    free(s->path);
    free(s);
}
