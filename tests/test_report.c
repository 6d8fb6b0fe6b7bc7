/*
 * test_report.c — making reports in the library (report/report.h, mr_report_make), and what it renders: materials
 * that own their maps (render/render.h, mr_material) and glTF scenes for the renderer (gltf/mr_gltf_scene.h).
 *
 * Scenes are real assets of ../shared/assets (MR_SHARED overrides ../shared): their triangles against
 * mr_gltf_get_triangles, their materials' models, names and maps, factors folded into the maps texel by texel,
 * and the refusals (a missing file, TEXCOORD_2, no triangles) with messages naming the asset, material and
 * texture. Reports: a material against itself is SSIM 1 and writes index.html and summary.json, another one is
 * below 1, glTF scenes, the progress callback (and stopping through it), and bad inputs and options refused with
 * a message naming the value and nothing written. Materials on an OBJ mesh (the paper's material-test sphere) under
 * a turning map: deterministic, SSIM 1 against themselves over the object, below 1 for another material, and the
 * mesh options' refusals. Every case works in the binary's scratch folder.
 */
#include "report/report.h"

#include <dirent.h>
#include <sys/stat.h>

#include "gltf/mr_gltf_scene.h"
#include "harness.h"
#include "io/obj_load.h"
#include "matremap.h"

static const char *asset_path(const char *rel) { return mr_test_asset_path(rel); }

#define AVOCADO "specgloss/Avocado-pbrSpecularGlossiness/glTF-pbrSpecularGlossiness/Avocado.gltf"
#define DUCK_DIR "specgloss/Duck-pbrSpecularGlossiness/glTF-pbrSpecularGlossiness"
#define TRUCK "specgloss/CesiumMilkTruck-pbrSpecularGlossiness/glTF-pbrSpecularGlossiness/CesiumMilkTruck.gltf"
#define FLOPPY "specgloss/FloppyDisk-sketchfab/scene.gltf"
#define BOTTLE "metalrough/WaterBottle/glTF/WaterBottle.gltf"

static int file_exists(const char *path) {
    struct stat st;
    return stat(path, &st) == 0;
}

static int contains(const char *text, const char *part) { return text != NULL && strstr(text, part) != NULL; }

/* The material's map of parameter `name` (the one bound), or NULL. */
static const mr_material_map *map_of(const mr_material *m, const char *name) {
    int p = mr_brdf_param_index(m->model, name);
    for (int k = 0; p >= 0 && k < m->map_count; k++)
        if (m->maps[k].param == p && m->maps[k].image == m->textures.maps[p]) return &m->maps[k];
    return NULL;
}

/* ---- glTF scenes ----------------------------------------------------------------------------------------- */

MR_TEST(avocado_scene_has_the_assets_triangles_and_its_specgloss_material) {
    mr_gltf_scene *s = NULL;
    MR_CHECK_OK(mr_gltf_scene_load(asset_path(AVOCADO), NULL, &s));
    mr_gltf *asset = NULL;
    mr_gltf_triangles *t = NULL;
    MR_CHECK_OK(mr_gltf_load(asset_path(AVOCADO), &asset));
    MR_CHECK_OK(mr_gltf_get_triangles(asset, -1, &t));
    if (s == NULL || t == NULL) goto done;
    MR_CHECK(s->mesh.triangle_count == t->triangle_count);
    MR_CHECK(s->mesh.vertex_count == t->vertex_count);
    MR_CHECK(s->mesh.triangle_count == 682);
    MR_CHECK(memcmp(s->bbox_min, t->bbox_min, sizeof s->bbox_min) == 0);
    MR_CHECK(memcmp(s->bbox_max, t->bbox_max, sizeof s->bbox_max) == 0);
    MR_CHECK(strcmp(s->path, asset_path(AVOCADO)) == 0);
    MR_CHECK_OK(mr_mesh_validate(&s->mesh));
    MR_CHECK(s->material_count == 1 && s->mesh.material_count == 1 && s->mesh.surfaces == s->surfaces);
    const mr_gltf_scene_material *slot = &s->materials[0];
    MR_CHECK(strcmp(slot->name, "2256_Avocado_d") == 0);
    MR_CHECK(slot->gltf_material == 0);
    MR_CHECK(strcmp(slot->brdf->model->name, "gltf-specgloss") == 0);
    // The spec-gloss textures bound to their parameters: diffuse RGB, specular RGB and glossiness (its alpha).
    const mr_material_map *diffuse = map_of(slot->brdf, "diffuse"), *gloss = map_of(slot->brdf, "glossiness");
    MR_CHECK(diffuse != NULL && strcmp(diffuse->source, "diffuseTexture") == 0 && diffuse->image->channels == 3);
    MR_CHECK(map_of(slot->brdf, "specular") != NULL);
    MR_CHECK(gloss != NULL && strcmp(gloss->source, "specularGlossinessTexture A") == 0 && gloss->image->channels == 1);
    MR_CHECK(slot->brdf->map_count == 3);
    // Its normal map is the surface's; the binding is the material.
    MR_CHECK(slot->normal_map != NULL && s->surfaces[0].normal_map == slot->normal_map);
    MR_CHECK(slot->occlusion_map == NULL && slot->emissive_map == NULL);
    MR_CHECK(s->bindings[0].model == slot->brdf->model && s->bindings[0].values == slot->brdf->values &&
             s->bindings[0].textures == &slot->brdf->textures);
done:
    mr_gltf_triangles_free(t);
    mr_gltf_free(asset);
    mr_gltf_scene_free(s);
}

MR_TEST(truck_scene_has_a_slot_per_material) {
    mr_gltf_scene *s = NULL;
    MR_CHECK_OK(mr_gltf_scene_load(asset_path(TRUCK), NULL, &s));
    if (s == NULL) return;
    static const char *const names[4] = {"truck", "glass", "window_trim", "wheels"};
    MR_CHECK(s->material_count == 4);
    for (int k = 0; k < 4 && k < s->material_count; k++) {
        MR_CHECK_MSG(strcmp(s->materials[k].name, names[k]) == 0, "slot %d is '%s'", k, s->materials[k].name);
        MR_CHECK(strcmp(s->materials[k].brdf->model->name, "gltf-specgloss") == 0);
    }
    int used[4] = {0, 0, 0, 0};
    for (int i = 0; i < s->mesh.triangle_count; i++)
        if (s->mesh.triangle_materials[i] < 4) used[s->mesh.triangle_materials[i]]++;
    MR_CHECK(used[0] > 0 && used[1] > 0 && used[2] > 0 && used[3] > 0);
    MR_CHECK(used[0] + used[1] + used[2] + used[3] == s->mesh.triangle_count);
    MR_CHECK_OK(mr_mesh_validate(&s->mesh));
    mr_gltf_scene_free(s);
}

MR_TEST(water_bottle_scene_is_metal_rough_with_surface_maps) {
    mr_gltf_scene *s = NULL;
    MR_CHECK_OK(mr_gltf_scene_load(asset_path(BOTTLE), NULL, &s));
    if (s == NULL) return;
    const mr_gltf_scene_material *slot = &s->materials[0];
    MR_CHECK(strcmp(slot->brdf->model->name, "gltf") == 0);
    const mr_material_map *base = map_of(slot->brdf, "base_color"), *metallic = map_of(slot->brdf, "metallic");
    const mr_material_map *roughness = map_of(slot->brdf, "roughness");
    MR_CHECK(base != NULL && strcmp(base->source, "baseColorTexture") == 0);
    MR_CHECK(metallic != NULL && strcmp(metallic->source, "metallicRoughnessTexture B") == 0);
    MR_CHECK(roughness != NULL && strcmp(roughness->source, "metallicRoughnessTexture G") == 0);
    MR_CHECK(slot->normal_map != NULL && slot->occlusion_map != NULL && slot->emissive_map != NULL);
    MR_CHECK(s->surfaces[0].occlusion_map == slot->occlusion_map && s->surfaces[0].emissive_map == slot->emissive_map);
    mr_gltf_scene_free(s);
}

/* FloppyDisk's factors differ from 1: every map texel is the decoded texture's times the factor. */
MR_TEST(factors_are_folded_into_the_maps) {
    mr_gltf *asset = NULL;
    mr_gltf_scene *s = NULL;
    mr_image *diffuse = NULL, *specgloss = NULL;
    MR_CHECK_OK(mr_gltf_load(asset_path(FLOPPY), &asset));
    if (asset == NULL) return;
    MR_CHECK_OK(mr_gltf_scene_from_asset(asset, NULL, &s));
    mr_gltf_material mat;
    MR_CHECK_OK(mr_gltf_get_material(asset, 0, &mat));
    mr_img_read_options colour = {MR_IMG_COLOR, 0, 0};
    MR_CHECK_OK(mr_gltf_texture_read(asset, mat.diffuse_texture.index, &colour, &diffuse, NULL));
    MR_CHECK_OK(mr_gltf_texture_read(asset, mat.specular_glossiness_texture.index, &colour, &specgloss, NULL));
    if (s == NULL || diffuse == NULL || specgloss == NULL) goto done;
    const mr_material *m = s->materials[0].brdf;
    const mr_material_map *d = map_of(m, "diffuse"), *g = map_of(m, "glossiness");
    MR_CHECK(d != NULL && g != NULL && specgloss->channels == 4);
    if (d == NULL || g == NULL || specgloss->channels != 4) goto done;
    MR_CHECK(d->image->width == diffuse->width && g->image->height == specgloss->height);
    int mismatches = 0;
    for (int y = 0; y < diffuse->height; y += 97)
        for (int x = 0; x < diffuse->width; x += 89) {
            for (int c = 0; c < 3; c++)
                mismatches += mr_image_at(d->image, x, y)[c] !=
                              (float)(mr_image_at(diffuse, x, y)[c] * mat.diffuse_factor[c]);
            mismatches += mr_image_at(g->image, x, y)[0] != (float)(mr_image_at(specgloss, x, y)[3] * 0.91);
        }
    MR_CHECK_MSG(mismatches == 0, "%d texels differ from texture x factor", mismatches);
    MR_CHECK_NEAR(mat.glossiness_factor, 0.91, 1e-12);
    MR_CHECK_NEAR(mat.diffuse_factor[0], 0.93, 1e-12);
done:
    mr_image_free(diffuse);
    mr_image_free(specgloss);
    mr_gltf_scene_free(s);
    mr_gltf_free(asset);
}

/* A copy of the Duck in scratch folder `name` whose JSON has its first `from` replaced by `to`; its path, or NULL. */
static const char *edited_duck(const char *name, const char *from, const char *to) {
    char *json = mr_test_read_file(asset_path(DUCK_DIR "/Duck.gltf"), NULL);
    char *hit = json != NULL ? strstr(json, from) : NULL;
    static char path[600];
    char command[2048];
    snprintf(path, sizeof path, "%s", mr_test_tmp_path(name));
    snprintf(command, sizeof command, "mkdir -p '%s' && cp '%s' '%s' '%s/'", path, asset_path(DUCK_DIR "/Duck0.bin"),
             asset_path(DUCK_DIR "/DuckCM.png"), path);
    strcat(path, "/duck.gltf");
    FILE *f = hit != NULL && system(command) == 0 ? fopen(path, "wb") : NULL;
    if (f != NULL) {
        fwrite(json, 1, (size_t)(hit - json), f);
        fputs(to, f);
        fputs(hit + strlen(from), f);
        fclose(f);
    }
    free(json);
    return f != NULL ? path : NULL;
}

MR_TEST(scene_refusals_name_the_asset_material_and_texture) {
    mr_gltf_scene *s = (mr_gltf_scene *)&s; // must become NULL
    MR_CHECK(mr_gltf_scene_load(mr_test_tmp_path("missing.gltf"), NULL, &s) == MR_ERR_IO);
    MR_CHECK(s == NULL && contains(mr_last_error(), "missing.gltf"));
    // A texture through TEXCOORD_2: the renderer reads sets 0 and 1.
    const char *uv2 = edited_duck("uv2", "\"diffuseTexture\": {", "\"diffuseTexture\": {\"texCoord\": 2,");
    MR_CHECK(uv2 != NULL);
    if (uv2 != NULL) {
        MR_CHECK(mr_gltf_scene_load(uv2, NULL, &s) == MR_ERR_UNSUPPORTED);
        const char *e = mr_last_error();
        MR_CHECK_MSG(contains(e, uv2) && contains(e, "blinn3-fx") && contains(e, "diffuseTexture") &&
                     contains(e, "TEXCOORD_2"), "message: %s", e);
    }
    // A scene without triangles, and a scene that does not exist.
    const char *empty = mr_test_tmp_path("empty.gltf");
    FILE *f = fopen(empty, "w");
    if (f != NULL) {
        fputs("{\"asset\": {\"version\": \"2.0\"}, \"scenes\": [{\"nodes\": []}], \"scene\": 0}", f);
        fclose(f);
    }
    MR_CHECK(mr_gltf_scene_load(empty, NULL, &s) == MR_ERR_INVALID_ARG);
    MR_CHECK(contains(mr_last_error(), "empty.gltf") && contains(mr_last_error(), "no triangles"));
    mr_gltf_scene_options bad_scene = {1, 7};
    MR_CHECK(mr_gltf_scene_load(asset_path(AVOCADO), &bad_scene, &s) == MR_ERR_INVALID_ARG);
    MR_CHECK(s == NULL);
    MR_CHECK(mr_gltf_scene_from_asset(NULL, NULL, &s) == MR_ERR_INVALID_ARG);
    mr_gltf_scene_free(NULL);
}

/* ---- materials ------------------------------------------------------------------------------------------- */

MR_TEST(material_owns_its_maps_and_refuses_without_change) {
    mr_material *m = NULL;
    MR_CHECK(mr_material_create(NULL, &m) == MR_ERR_INVALID_ARG && m == NULL);
    MR_CHECK_OK(mr_material_create(mr_brdf_find("gltf"), &m));
    if (m == NULL) return;
    double defaults[MR_BRDF_MAX_VALUES];
    mr_brdf_default_values(m->model, defaults);
    MR_CHECK(memcmp(defaults, m->values, (size_t)mr_brdf_value_count(m->model) * sizeof(double)) == 0);
    mr_image *grey = NULL, *rgb = NULL;
    MR_CHECK_OK(mr_image_create(4, 4, 1, &grey));
    MR_CHECK_OK(mr_image_create(4, 4, 3, &rgb));
    // Refused: an unknown parameter, a one-channel parameter's channel past the map's: nothing changes.
    MR_CHECK(mr_material_add_map(m, "shininess", grey, 0, "g.png", NULL) == MR_ERR_INVALID_ARG);
    MR_CHECK(contains(mr_last_error(), "shininess"));
    MR_CHECK(mr_material_add_map(m, "roughness", grey, 2, "g.png", NULL) == MR_ERR_INVALID_ARG);
    MR_CHECK(m->map_count == 0 && m->textures.maps[mr_brdf_param_index(m->model, "roughness")] == NULL);
    mr_texture_sampling clamp = {MR_WRAP_CLAMP, MR_WRAP_CLAMP, 1, 0, {0, 0}, 0, {1, 1}};
    MR_CHECK_OK(mr_material_add_map(m, "roughness", grey, 0, "g.png", &clamp));
    MR_CHECK_OK(mr_material_add_map(m, "base_color", rgb, 0, NULL, NULL));
    const int r = mr_brdf_param_index(m->model, "roughness");
    MR_CHECK(m->map_count == 2 && m->maps[0].param == r && strcmp(m->maps[0].source, "g.png") == 0);
    MR_CHECK(m->textures.maps[r] == grey && m->textures.sampling[r].wrap_u == MR_WRAP_CLAMP);
    MR_CHECK(strcmp(m->maps[1].source, "") == 0);
    mr_material_binding b = mr_material_binding_of(m);
    MR_CHECK(b.model == m->model && b.values == m->values && b.textures == &m->textures);
    mr_material_free(m); // frees both maps
    mr_material_free(NULL);
}

/* ---- reports --------------------------------------------------------------------------------------------- */

/* A ggx material with alpha `alpha`. */
static mr_material *ggx(double alpha) {
    mr_material *m = NULL;
    char assignment[64];
    snprintf(assignment, sizeof assignment, "alpha=%g", alpha);
    if (mr_material_create(mr_brdf_find("ggx"), &m) == MR_OK &&
        mr_brdf_parse_assignment(m->model, assignment, m->values) != MR_OK) {
        mr_material_free(m);
        m = NULL;
    }
    return m;
}

/* Entries of the tests' scratch folder whose name holds ".matremap-": a report's scratch folders left behind. */
static int scratch_entries(void) {
    DIR *d = opendir(mr_test_scratch_dir());
    int count = 0;
    for (struct dirent *e; d != NULL && (e = readdir(d)) != NULL;) count += strstr(e->d_name, ".matremap-") != NULL;
    if (d != NULL) closedir(d);
    return count;
}

/* A file of report folder `dir`, read whole (NULL if missing). */
static char *report_file(const char *dir, const char *name) {
    char path[600];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    return mr_test_read_file(path, NULL);
}

MR_TEST(material_against_itself_is_ssim_one_and_another_is_below) {
    mr_material *a = ggx(0.2), *same = ggx(0.2), *rougher = ggx(0.4);
    MR_CHECK(a != NULL && same != NULL && rougher != NULL);
    mr_report_input in[3] = {{NULL, NULL, a, NULL, NULL, NULL},
                             {"same", "ggx alpha=0.2", same, NULL, NULL, NULL},
                             {"rougher", NULL, rougher, NULL, NULL, NULL}};
    mr_report_options o = {0};
    o.size = 48;
    o.title = "roughness";
    const char *dir = mr_test_tmp_path("fit");
    mr_report_result *r = NULL;
    MR_CHECK_OK(mr_report_make(in, 3, dir, &o, &r));
    if (r == NULL) goto done;
    MR_CHECK(r->view_count == 1 && r->material_count == 3 && r->exposure > 0.0 && r->env_scale == 0.0);
    MR_CHECK(strcmp(r->materials[0].label, "ggx") == 0 && strcmp(r->materials[2].label, "rougher") == 0);
    MR_CHECK(r->materials[0].mean_ssim == 1.0 && r->materials[0].mean_relative_rmse == 0.0);
    MR_CHECK(r->materials[1].mean_ssim == 1.0 && r->materials[1].mean_relative_rmse == 0.0);
    MR_CHECK(r->materials[1].mean_object_ssim == 1.0 && r->materials[1].object_ssim[0] == 1.0);
    MR_CHECK_MSG(r->materials[2].mean_ssim < 0.999 && r->materials[2].mean_object_ssim < 0.999,
                 "SSIM %.6f, object %.6f", r->materials[2].mean_ssim, r->materials[2].mean_object_ssim);
    MR_CHECK(r->materials[2].mean_relative_rmse > 0.0 && r->materials[2].seconds >= 0.0);
    char *page = report_file(dir, "index.html"), *summary = report_file(dir, "summary.json");
    MR_CHECK(contains(page, "<title>roughness</title>"));
    MR_CHECK(contains(summary, "\"mean_ssim\": 1,") && contains(summary, "\"views\": [\"fit scene\"]"));
    // Descriptions: given, or made up from the model and values.
    MR_CHECK(contains(summary, "\"description\": \"ggx alpha=0.2\""));
    MR_CHECK_MSG(contains(summary, "ggx alpha=0.4 "), "%s", summary ? summary : "(no summary)");
    free(page);
    free(summary);
    MR_CHECK(file_exists(mr_test_tmp_path("fit/view0_material2.png")));
    MR_CHECK(file_exists(mr_test_tmp_path("fit/ssim_view0_material2.png")));
done:
    mr_report_result_free(r);
    mr_material_free(a);
    mr_material_free(same);
    mr_material_free(rougher);
}

/* Records the progress calls; stops at `stop_at` views done (-1: never). */
typedef struct progress_log {
    int calls, last_done, last_total, stop_at;
} progress_log;

static int log_progress(void *user, int done, int total, const char *what) {
    progress_log *log = user;
    log->calls++;
    log->last_done = done;
    log->last_total = total;
    return strcmp(what, "view") == 0 && done == log->stop_at;
}

MR_TEST(environment_views_maps_and_progress) {
    mr_material *plain = ggx(0.3), *textured = NULL;
    mr_image *env = NULL, *albedo = NULL;
    MR_CHECK_OK(mr_material_create(mr_brdf_find("gltf"), &textured));
    MR_CHECK_OK(mr_image_create(32, 16, 3, &env));
    MR_CHECK_OK(mr_image_create(16, 16, 3, &albedo));
    if (plain == NULL || textured == NULL || env == NULL || albedo == NULL) goto done;
    for (size_t i = 0; i < mr_image_value_count(env); i++) env->pixels[i] = (float)(i % 7) / 7.0f;
    for (size_t i = 0; i < mr_image_value_count(albedo); i++) albedo->pixels[i] = (float)(i % 5) / 5.0f;
    MR_CHECK_OK(mr_material_add_map(textured, "base_color", albedo, 0, "albedo.png", NULL));
    albedo = NULL; // the material's now
    mr_report_input in[2] = {{NULL, NULL, plain, NULL, NULL, NULL}, {"textured", NULL, textured, NULL, NULL, NULL}};
    mr_report_options o = {0};
    o.size = 32;
    o.env = env;
    o.rotations = 2;
    o.env_samples = 64;
    o.reflection_samples = MR_REPORT_NO_REFLECTION_SAMPLES;
    progress_log log = {0, -1, -1, -1};
    o.progress = log_progress;
    o.progress_user = &log;
    const char *dir = mr_test_tmp_path("env");
    mr_report_result *r = NULL;
    MR_CHECK_OK(mr_report_make(in, 2, dir, &o, &r));
    MR_CHECK(log.calls == 3 && log.last_done == 2 && log.last_total == 2);
    MR_CHECK(r != NULL && r->view_count == 2 && r->env_scale > 0.0);
    char *summary = report_file(dir, "summary.json");
    MR_CHECK(contains(summary, "\"rotation 0°\", \"rotation 180°\""));
    MR_CHECK(contains(summary, "lit by an environment map") && contains(summary, "64 fixed directions and 0 about"));
    MR_CHECK(contains(summary, "\"label\": \"base_color (albedo.png)\", \"path\": \"map_material1_0.png\""));
    MR_CHECK(contains(summary, "base_color=@albedo.png"));
    free(summary);
    MR_CHECK(file_exists(mr_test_tmp_path("env/map_material1_0.png")));
    mr_report_result_free(r);
    // Stopped by the callback after one view (its pictures written): MR_ERR_CANCELLED, no figures, and no folder:
    // the pictures went to a scratch folder beside it, removed again.
    log = (progress_log){0, -1, -1, 1};
    r = (mr_report_result *)&r;
    MR_CHECK(mr_report_make(in, 2, mr_test_tmp_path("stopped"), &o, &r) == MR_ERR_CANCELLED);
    MR_CHECK(r == NULL && log.calls == 2 && !file_exists(mr_test_tmp_path("stopped")));
    MR_CHECK(scratch_entries() == 0);
    // Stopped while replacing the report made above: that report stays as it was, every file of it.
    char *before = report_file(dir, "index.html");
    log = (progress_log){0, -1, -1, 1};
    o.rotations = 3;
    MR_CHECK(mr_report_make(in, 2, dir, &o, NULL) == MR_ERR_CANCELLED);
    char *after = report_file(dir, "index.html");
    MR_CHECK(before != NULL && after != NULL && strcmp(before, after) == 0);
    MR_CHECK(file_exists(mr_test_tmp_path("env/view1_material1.png")) &&
             !file_exists(mr_test_tmp_path("env/view2_material1.png")));
    MR_CHECK(scratch_entries() == 0);
    free(before);
    free(after);
done:
    mr_image_free(env);
    mr_image_free(albedo);
    mr_material_free(plain);
    mr_material_free(textured);
}

MR_TEST(gltf_scene_against_itself_is_ssim_one) {
    mr_gltf_scene *a = NULL, *b = NULL;
    MR_CHECK_OK(mr_gltf_scene_load(asset_path(AVOCADO), NULL, &a));
    MR_CHECK_OK(mr_gltf_scene_load(asset_path(AVOCADO), NULL, &b));
    if (a == NULL || b == NULL) goto done;
    mr_report_input in[2] = {{"original", NULL, NULL, a, NULL, NULL}, {"again", NULL, NULL, b, NULL, NULL}};
    mr_report_options o = {0};
    o.size = 48;
    const char *dir = mr_test_tmp_path("avocado");
    mr_report_result *r = NULL;
    MR_CHECK_OK(mr_report_make(in, 2, dir, &o, &r));
    MR_CHECK(r != NULL && r->materials[1].mean_ssim == 1.0 && r->materials[1].mean_object_ssim == 1.0);
    char *summary = report_file(dir, "summary.json");
    MR_CHECK(contains(summary, "682 triangles, 1 material: 2256_Avocado_d (gltf-specgloss model)"));
    MR_CHECK(contains(summary, "\"label\": \"normal map\""));
    free(summary);
    mr_report_result_free(r);
    // A camera direction is for scenes: a head-on view renders as well.
    o.has_camera_direction = 1;
    o.camera_direction[2] = 1.0;
    MR_CHECK_OK(mr_report_make(in, 2, mr_test_tmp_path("avocado_front"), &o, NULL));
done:
    mr_gltf_scene_free(a);
    mr_gltf_scene_free(b);
}

MR_TEST(a_report_replaces_its_folder_as_a_whole_or_not_at_all) {
    mr_material *a = ggx(0.2), *b = ggx(0.4), *c = ggx(0.6);
    if (a == NULL || b == NULL || c == NULL) goto done;
    mr_report_input three[3] = {{NULL, NULL, a, NULL, NULL, NULL},
                                {NULL, NULL, b, NULL, NULL, NULL},
                                {NULL, NULL, c, NULL, NULL, NULL}};
    mr_report_options o = {0};
    o.size = 32;
    const char *dir = mr_test_tmp_path("replaced");
    MR_CHECK_OK(mr_report_make(three, 3, dir, &o, NULL));
    MR_CHECK(file_exists(mr_test_tmp_path("replaced/view0_material2.png")));
    // Two materials over three: the old third render goes with the old report (the folder is replaced, not
    // written into); a trailing slash names the same folder.
    char slash[600];
    snprintf(slash, sizeof slash, "%s/", dir);
    MR_CHECK_OK(mr_report_make(three, 2, slash, &o, NULL));
    MR_CHECK(file_exists(mr_test_tmp_path("replaced/view0_material1.png")) &&
             !file_exists(mr_test_tmp_path("replaced/view0_material2.png")));
    char *summary = report_file(dir, "summary.json");
    MR_CHECK(contains(summary, "alpha=0.4") && !contains(summary, "alpha=0.6"));
    free(summary);
    // A folder holding anything a report does not write is not replaced: refused, naming the entry, untouched.
    const char *foreign = mr_test_tmp_path("replaced/notes.txt");
    FILE *f = fopen(foreign, "w");
    if (f != NULL) {
        fputs("mine\n", f);
        fclose(f);
    }
    char *page = report_file(dir, "index.html");
    MR_CHECK(mr_report_make(three, 3, dir, &o, NULL) == MR_ERR_INVALID_ARG);
    MR_CHECK_MSG(contains(mr_last_error(), "holds 'notes.txt'"), "%s", mr_last_error());
    char *still = report_file(dir, "index.html"), *notes = mr_test_read_file(foreign, NULL);
    MR_CHECK(page != NULL && still != NULL && strcmp(page, still) == 0);
    MR_CHECK(notes != NULL && strcmp(notes, "mine\n") == 0);
    MR_CHECK(!file_exists(mr_test_tmp_path("replaced/view0_material2.png")));
    free(page);
    free(still);
    free(notes);
    // So is a sub-folder, even one named like a picture.
    const char *empty = mr_test_tmp_path("empty");
    MR_CHECK(mkdir(empty, 0777) == 0);
    MR_CHECK_OK(mr_report_make(three, 1, empty, &o, NULL)); // an empty folder is taken
    MR_CHECK(mkdir(mr_test_tmp_path("empty/view9_material9.png"), 0777) == 0);
    MR_CHECK(mr_report_make(three, 1, empty, &o, NULL) == MR_ERR_INVALID_ARG);
    MR_CHECK_MSG(contains(mr_last_error(), "holds 'view9_material9.png'"), "%s", mr_last_error());
    // A folder is replaced by its name: ".", ".." and "/" have none to rename.
    const char *unnamed[4] = {".", "..", "/", "a/.."};
    for (int k = 0; k < 4; k++) {
        MR_CHECK(mr_report_make(three, 1, unnamed[k], &o, NULL) == MR_ERR_INVALID_ARG);
        MR_CHECK_MSG(contains(mr_last_error(), "name the folder itself"), "%s", mr_last_error());
    }
    MR_CHECK(scratch_entries() == 0);
done:
    mr_material_free(a);
    mr_material_free(b);
    mr_material_free(c);
}

MR_TEST(bad_inputs_and_options_are_named_and_write_nothing) {
    mr_material *m = ggx(0.2);
    mr_gltf_scene *s = NULL;
    MR_CHECK_OK(mr_gltf_scene_load(asset_path(AVOCADO), NULL, &s));
    if (m == NULL || s == NULL) goto done;
    const char *dir = mr_test_tmp_path("refused");
    mr_report_input one[1] = {{NULL, NULL, m, NULL, NULL, NULL}};
    mr_report_result *r = NULL;
    mr_report_options o = {0};
    o.size = -5;
    MR_CHECK(mr_report_make(one, 1, dir, &o, &r) == MR_ERR_INVALID_ARG && contains(mr_last_error(), "size -5"));
    o.size = 8;
    MR_CHECK(mr_report_make(one, 1, dir, &o, &r) == MR_ERR_INVALID_ARG && contains(mr_last_error(), "size 8"));
    o.size = 32;
    o.env_path = mr_test_tmp_path("nosky.hdr");
    MR_CHECK(mr_report_make(one, 1, dir, &o, &r) == MR_ERR_IO && contains(mr_last_error(), "nosky.hdr"));
    o.env_path = NULL;
    o.rotations = 3;
    MR_CHECK(mr_report_make(one, 1, dir, &o, &r) == MR_ERR_INVALID_ARG && contains(mr_last_error(), "rotations 3"));
    o.rotations = 0;
    o.env_samples = 16;
    MR_CHECK(mr_report_make(one, 1, dir, &o, &r) == MR_ERR_INVALID_ARG && contains(mr_last_error(), "env_samples"));
    o.env_samples = 0;
    o.exposure = -1.0;
    MR_CHECK(mr_report_make(one, 1, dir, &o, &r) == MR_ERR_INVALID_ARG && contains(mr_last_error(), "exposure -1"));
    o.exposure = 0.0;
    o.has_camera_direction = 1;
    MR_CHECK(mr_report_make(one, 1, dir, &o, &r) == MR_ERR_INVALID_ARG && contains(mr_last_error(), "spheres"));
    o.has_camera_direction = 0;
    MR_CHECK(mr_report_make(one, 0, dir, &o, &r) == MR_ERR_INVALID_ARG && contains(mr_last_error(), "0 inputs"));
    mr_report_input mixed[2] = {{NULL, NULL, m, NULL, NULL, NULL}, {NULL, NULL, NULL, s, NULL, NULL}};
    MR_CHECK(mr_report_make(mixed, 2, dir, &o, &r) == MR_ERR_INVALID_ARG && contains(mr_last_error(), "input 1"));
    mr_report_input neither[2] = {{NULL, NULL, m, NULL, NULL, NULL}, {"nothing", NULL, NULL, NULL, NULL, NULL}};
    MR_CHECK(mr_report_make(neither, 2, dir, &o, &r) == MR_ERR_INVALID_ARG && contains(mr_last_error(), "input 1"));
    MR_CHECK(r == NULL && !file_exists(dir));
    // A folder that is a file.
    const char *file = mr_test_tmp_path("a_file");
    FILE *f = fopen(file, "w");
    if (f != NULL) fclose(f);
    MR_CHECK(mr_report_make(one, 1, file, &o, &r) == MR_ERR_IO && contains(mr_last_error(), "a_file"));
    MR_CHECK(r == NULL);
done:
    mr_material_free(m);
    mr_gltf_scene_free(s);
}

/* A Ward material with a roughness map (a gradient over u), so that the mesh's UVs matter. */
static mr_material *ward_mapped(double specular) {
    mr_material *m = NULL;
    mr_image *alpha = NULL;
    char assignment[64];
    snprintf(assignment, sizeof assignment, "specular=%g", specular);
    if (mr_material_create(mr_brdf_find("ward"), &m) != MR_OK || mr_image_create(16, 8, 1, &alpha) != MR_OK ||
        mr_brdf_parse_assignment(m->model, assignment, m->values) != MR_OK)
        goto fail;
    for (int y = 0; y < 8; y++)
        for (int x = 0; x < 16; x++) mr_image_at(alpha, x, y)[0] = (float)(0.05 + 0.03 * x + 0.01 * y);
    if (mr_material_add_map(m, "alpha", alpha, 0, "gradient.exr", NULL) != MR_OK) goto fail;
    return m;
fail:
    mr_image_free(alpha);
    mr_material_free(m);
    return NULL;
}

MR_TEST(materials_on_an_obj_mesh_under_a_turning_map) {
    mr_obj_mesh *obj = NULL;
    mr_image *env = NULL;
    mr_material *a = ward_mapped(0.2), *same = ward_mapped(0.2), *other = ward_mapped(0.05);
    mr_report_result *r = NULL, *again = NULL;
    MR_CHECK_OK(mr_obj_load(asset_path("paper/matsphere.obj"), NULL, &obj));
    MR_CHECK_OK(mr_image_create(32, 16, 3, &env));
    if (obj == NULL || env == NULL || a == NULL || same == NULL || other == NULL) goto done;
    for (int y = 0; y < 16; y++) // a bright patch on one side, so that turning the map changes the picture
        for (int x = 0; x < 32; x++)
            for (int c = 0; c < 3; c++) mr_image_at(env, x, y)[c] = (x >= 4 && x < 10 && y < 8) ? 20.0f : 0.2f;
    mr_report_input in[3] = {{"source", NULL, a, NULL, NULL, NULL},
                             {"same", NULL, same, NULL, NULL, NULL},
                             {"other", NULL, other, NULL, NULL, NULL}};
    const mr_camera paper = mr_camera_paper();
    mr_report_options o = {0};
    o.size = 32;
    o.env = env;
    o.env_path = "patch.hdr";
    o.rotations = 3;
    o.env_samples = 32;
    o.reflection_samples = 4;
    o.mesh = &obj->mesh;
    o.mesh_name = "matsphere.obj";
    o.camera = &paper;
    o.threads = 2;
    const char *dir = mr_test_tmp_path("mesh");
    MR_CHECK_OK(mr_report_make(in, 3, dir, &o, &r));
    MR_CHECK_OK(mr_report_make(in, 3, mr_test_tmp_path("mesh_again"), &o, &again));
    if (r == NULL || again == NULL) goto done;
    MR_CHECK(r->view_count == 3);
    for (int v = 0; v < 3; v++) {
        MR_CHECK_MSG(r->materials[1].object_ssim[v] == 1.0, "view %d: %.17g", v, r->materials[1].object_ssim[v]);
        MR_CHECK_MSG(r->materials[2].object_ssim[v] < 0.999, "view %d: %.17g", v, r->materials[2].object_ssim[v]);
        // Deterministic: the same figures, bit for bit, from a second run (threads included).
        MR_CHECK(r->materials[2].object_ssim[v] == again->materials[2].object_ssim[v]);
        MR_CHECK(r->materials[2].object_relative_rmse[v] == again->materials[2].object_relative_rmse[v]);
    }
    // The views differ (the map turns); the identical material has no error, the other one some.
    MR_CHECK(r->materials[2].object_ssim[0] != r->materials[2].object_ssim[1]);
    MR_CHECK(r->materials[1].mean_object_relative_rmse == 0.0 && r->materials[2].mean_object_relative_rmse > 0.01);
    char *summary = report_file(dir, "summary.json");
    MR_CHECK(contains(summary, "Mesh matsphere.obj (55742 triangles), 32² pixels, lit by patch.hdr"));
    MR_CHECK(contains(summary, "\"rotation 0°\", \"rotation 120°\", \"rotation 240°\""));
    MR_CHECK(contains(summary, "alpha=@gradient.exr"));
    free(summary);
    MR_CHECK(file_exists(mr_test_tmp_path("mesh/view2_material2.png")));
    // Without a camera the mesh is framed from +z: it renders too.
    o.camera = NULL;
    o.rotations = 1;
    MR_CHECK_OK(mr_report_make(in, 2, mr_test_tmp_path("mesh_framed"), &o, NULL));
done:
    mr_report_result_free(r);
    mr_report_result_free(again);
    mr_obj_mesh_free(obj);
    mr_image_free(env);
    mr_material_free(a);
    mr_material_free(same);
    mr_material_free(other);
}

MR_TEST(mesh_options_are_refused_by_name) {
    mr_obj_mesh *obj = NULL;
    mr_image *env = NULL;
    mr_material *m = ggx(0.2);
    mr_gltf_scene *s = NULL;
    MR_CHECK_OK(mr_obj_load(asset_path("paper/matsphere.obj"), NULL, &obj));
    MR_CHECK_OK(mr_image_create(8, 4, 3, &env));
    MR_CHECK_OK(mr_gltf_scene_load(asset_path(AVOCADO), NULL, &s));
    if (obj == NULL || env == NULL || m == NULL || s == NULL) goto done;
    for (size_t i = 0; i < mr_image_value_count(env); i++) env->pixels[i] = 1.0f;
    const char *dir = mr_test_tmp_path("mesh_refused");
    mr_report_input one[1] = {{NULL, NULL, m, NULL, NULL, NULL}}, scene[1] = {{NULL, NULL, NULL, s, NULL, NULL}};
    const mr_camera paper = mr_camera_paper();
    mr_report_options o = {0};
    o.size = 32;
    o.mesh = &obj->mesh;
    MR_CHECK(mr_report_make(one, 1, dir, &o, NULL) == MR_ERR_INVALID_ARG &&
             contains(mr_last_error(), "mesh needs an environment map"));
    o.env = env;
    MR_CHECK(mr_report_make(scene, 1, dir, &o, NULL) == MR_ERR_INVALID_ARG &&
             contains(mr_last_error(), "glTF scenes bring their own"));
    // A broken mesh: its message, prefixed with the mesh's name.
    mr_mesh broken = obj->mesh;
    uint32_t *indices = malloc((size_t)broken.triangle_count * 3 * sizeof *indices);
    if (indices != NULL) {
        memcpy(indices, broken.indices, (size_t)broken.triangle_count * 3 * sizeof *indices);
        indices[7] = (uint32_t)broken.vertex_count;
        broken.indices = indices;
        o.mesh = &broken;
        o.mesh_name = "broken.obj";
        MR_CHECK(mr_report_make(one, 1, dir, &o, NULL) == MR_ERR_INVALID_ARG &&
                 contains(mr_last_error(), "report mesh 'broken.obj'") && contains(mr_last_error(), "triangle 2"));
        free(indices);
    }
    o.mesh = NULL;
    o.camera = &paper;
    MR_CHECK(mr_report_make(one, 1, dir, &o, NULL) == MR_ERR_INVALID_ARG &&
             contains(mr_last_error(), "camera places the camera for a mesh"));
    MR_CHECK(!file_exists(dir));
done:
    mr_obj_mesh_free(obj);
    mr_image_free(env);
    mr_material_free(m);
    mr_gltf_scene_free(s);
}

/* The camera report and render ASSET place on a scene (mr_gltf_scene_frame): the three-quarter view along the axis of
 * the smallest extent by default, the same as that direction given, looking at the box's centre; a zero direction
 * refused. */
MR_TEST(scene_frame_looks_from_the_broad_side) {
    mr_gltf_scene *s = NULL;
    MR_CHECK_OK(mr_gltf_scene_load(asset_path(BOTTLE), NULL, &s));
    if (s == NULL) return;
    int thin = 0;
    for (int c = 1; c < 3; c++)
        if (s->bbox_max[c] - s->bbox_min[c] < s->bbox_max[thin] - s->bbox_min[thin]) thin = c;
    double three_quarter[3] = {0.35, 0.35, 0.35};
    three_quarter[thin] = 1.0;
    mr_camera by_default, given;
    MR_CHECK_OK(mr_gltf_scene_frame(s, NULL, 320, 200, &by_default));
    MR_CHECK_OK(mr_gltf_scene_frame(s, three_quarter, 320, 200, &given));
    MR_CHECK(memcmp(&by_default, &given, sizeof given) == 0);
    // Seen from the broad side: the camera is offset from the target mostly along the thin axis.
    double offset[3];
    for (int c = 0; c < 3; c++) offset[c] = by_default.position[c] - by_default.target[c];
    for (int c = 0; c < 3; c++)
        if (c != thin) MR_CHECK_NEAR(offset[c] / offset[thin], 0.35, 1e-9);
    const double zero[3] = {0.0, 0.0, 0.0};
    mr_camera unused;
    MR_CHECK(mr_gltf_scene_frame(s, zero, 0, 0, &unused) == MR_ERR_INVALID_ARG &&
             strstr(mr_last_error(), "direction") != NULL);
    mr_gltf_scene_free(s);
}

MR_TEST_MAIN(MR_TEST_ENTRY(avocado_scene_has_the_assets_triangles_and_its_specgloss_material),
             MR_TEST_ENTRY(scene_frame_looks_from_the_broad_side),
             MR_TEST_ENTRY(truck_scene_has_a_slot_per_material),
             MR_TEST_ENTRY(water_bottle_scene_is_metal_rough_with_surface_maps),
             MR_TEST_ENTRY(factors_are_folded_into_the_maps),
             MR_TEST_ENTRY(scene_refusals_name_the_asset_material_and_texture),
             MR_TEST_ENTRY(material_owns_its_maps_and_refuses_without_change),
             MR_TEST_ENTRY(material_against_itself_is_ssim_one_and_another_is_below),
             MR_TEST_ENTRY(environment_views_maps_and_progress),
             MR_TEST_ENTRY(gltf_scene_against_itself_is_ssim_one),
             MR_TEST_ENTRY(a_report_replaces_its_folder_as_a_whole_or_not_at_all),
             MR_TEST_ENTRY(bad_inputs_and_options_are_named_and_write_nothing),
             MR_TEST_ENTRY(materials_on_an_obj_mesh_under_a_turning_map),
             MR_TEST_ENTRY(mesh_options_are_refused_by_name))
