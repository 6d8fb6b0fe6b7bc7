/*
 * test_gltf.c — the glTF shim (contract in gltf/mr_gltf.h): every asset of ../shared/assets loads, with known
 * answers read from each; read -> write -> read keeps every material field, the images' bytes and the counts of
 * everything else, as .gltf and as .glb; data-URI and GLB-embedded resources; material edits (drop SG, set MR
 * factors, add a texture, KHR_materials_specular/ior, texture transforms) read back; embedded images decode from
 * memory to what their files decode to; bad inputs fail with a message naming the file and leave no output. Every
 * case works in a private mkdtemp() directory.
 *
 * MR_GLTF_KEEP=DIR keeps the round-tripped copies of every asset in DIR/<asset>/ and the edited FloppyDisk in
 * DIR/Edited/, and MR_GLTF_IN/MR_GLTF_OUT
 * round-trip one more file (tests/gltf_validate.sh validates them and compares their JSON with the originals).
 */
#include "gltf/mr_gltf.h"

#include <dirent.h>
#include <stdint.h>
#include <sys/stat.h>
#include <unistd.h>

#include "gltf_support.h"
#include "harness.h"
#include "render/render.h"

/* ---- comparisons ---------------------------------------------------------------------------------------- */

static int same_ref(const mr_gltf_texture_ref *a, const mr_gltf_texture_ref *b, const char *what) {
    int same = a->index == b->index && a->tex_coord == b->tex_coord && a->value == b->value &&
               a->has_transform == b->has_transform && a->offset[0] == b->offset[0] &&
               a->offset[1] == b->offset[1] && a->rotation == b->rotation && a->scale[0] == b->scale[0] &&
               a->scale[1] == b->scale[1] && a->transform_tex_coord == b->transform_tex_coord;
    if (!same) fprintf(stderr, "    texture reference %s differs (index %d vs %d)\n", what, a->index, b->index);
    return same;
}

#define SAME_ARRAY(a, b, n) (memcmp((a), (b), sizeof(double) * (n)) == 0)

/* Every field, exactly (doubles survive the JSON round trip bit for bit). */
static int same_material(const mr_gltf_material *a, const mr_gltf_material *b) {
    int same = 1;
    same &= strcmp(a->name, b->name) == 0;
    same &= SAME_ARRAY(a->base_color_factor, b->base_color_factor, 4);
    same &= a->metallic_factor == b->metallic_factor && a->roughness_factor == b->roughness_factor;
    same &= same_ref(&a->base_color_texture, &b->base_color_texture, "baseColor");
    same &= same_ref(&a->metallic_roughness_texture, &b->metallic_roughness_texture, "metallicRoughness");
    same &= same_ref(&a->normal_texture, &b->normal_texture, "normal");
    same &= same_ref(&a->occlusion_texture, &b->occlusion_texture, "occlusion");
    same &= same_ref(&a->emissive_texture, &b->emissive_texture, "emissive");
    same &= SAME_ARRAY(a->emissive_factor, b->emissive_factor, 3);
    same &= a->alpha_mode == b->alpha_mode && a->alpha_cutoff == b->alpha_cutoff;
    same &= a->double_sided == b->double_sided;
    same &= a->has_spec_gloss == b->has_spec_gloss && SAME_ARRAY(a->diffuse_factor, b->diffuse_factor, 4);
    same &= SAME_ARRAY(a->specular_factor, b->specular_factor, 3) && a->glossiness_factor == b->glossiness_factor;
    same &= same_ref(&a->diffuse_texture, &b->diffuse_texture, "diffuse");
    same &= same_ref(&a->specular_glossiness_texture, &b->specular_glossiness_texture, "specularGlossiness");
    same &= a->has_specular == b->has_specular && a->specular_strength == b->specular_strength;
    same &= SAME_ARRAY(a->specular_color_factor, b->specular_color_factor, 3);
    same &= same_ref(&a->specular_texture, &b->specular_texture, "specular");
    same &= same_ref(&a->specular_color_texture, &b->specular_color_texture, "specularColor");
    same &= a->has_ior == b->has_ior && a->ior == b->ior;
    return same;
}

/* Materials, textures, samplers, image bytes and the counts of everything else agree. A .glb is packed (one
 * buffer, images in buffer views of their own), so buffers and buffer views are not counted for one. */
static void check_same_asset_as(const mr_gltf *a, const mr_gltf *b, const char *what, int packed) {
    mr_gltf_counts ca, cb;
    mr_gltf_get_counts(a, &ca);
    mr_gltf_get_counts(b, &cb);
    if (packed) {
        MR_CHECK_MSG(cb.buffers <= 1 && cb.buffer_views >= ca.buffer_views, "%s: %d buffers, %d views (from %d)",
                     what, cb.buffers, cb.buffer_views, ca.buffer_views);
        ca.buffers = cb.buffers = ca.buffer_views = cb.buffer_views = 0;
    }
    MR_CHECK_MSG(memcmp(&ca, &cb, sizeof ca) == 0, "%s: counts differ (materials %d/%d, nodes %d/%d, meshes %d/%d, "
                 "accessors %d/%d, animations %d/%d, buffers %d/%d)", what, ca.materials, cb.materials, ca.nodes,
                 cb.nodes, ca.meshes, cb.meshes, ca.accessors, cb.accessors, ca.animations, cb.animations,
                 ca.buffers, cb.buffers);
    if (ca.materials != cb.materials || ca.textures != cb.textures || ca.images != cb.images) return;
    for (int i = 0; i < ca.materials; i++) {
        mr_gltf_material ma, mb;
        MR_CHECK_OK(mr_gltf_get_material(a, i, &ma));
        MR_CHECK_OK(mr_gltf_get_material(b, i, &mb));
        MR_CHECK_MSG(same_material(&ma, &mb), "%s: material %d ('%s') differs", what, i, ma.name);
    }
    for (int i = 0; i < ca.textures; i++) {
        mr_gltf_texture ta, tb;
        MR_CHECK_OK(mr_gltf_get_texture(a, i, &ta));
        MR_CHECK_OK(mr_gltf_get_texture(b, i, &tb));
        MR_CHECK_MSG(memcmp(&ta, &tb, sizeof ta) == 0, "%s: texture %d differs", what, i);
    }
    for (int i = 0; i < ca.images; i++) {
        mr_gltf_image ia, ib;
        MR_CHECK_OK(mr_gltf_get_image(a, i, &ia));
        MR_CHECK_OK(mr_gltf_get_image(b, i, &ib));
        MR_CHECK_MSG(ia.size == ib.size && ia.size > 0 && memcmp(ia.bytes, ib.bytes, ia.size) == 0,
                     "%s: image %d bytes differ (%zu vs %zu)", what, i, ia.size, ib.size);
        MR_CHECK_MSG(strcmp(ia.mime_type, ib.mime_type) == 0, "%s: image %d mime '%s' vs '%s'", what, i,
                     ia.mime_type, ib.mime_type);
    }
    const char *exts[] = {"KHR_materials_pbrSpecularGlossiness", "KHR_materials_specular", "KHR_materials_ior",
                          "KHR_texture_transform"};
    for (int i = 0; i < 4; i++) {
        MR_CHECK_MSG(mr_gltf_extension_used(a, exts[i]) == mr_gltf_extension_used(b, exts[i]),
                     "%s: extensionsUsed %s", what, exts[i]);
        MR_CHECK_MSG(mr_gltf_extension_required(a, exts[i]) == mr_gltf_extension_required(b, exts[i]),
                     "%s: extensionsRequired %s", what, exts[i]);
    }
}

static void check_same_asset(const mr_gltf *a, const mr_gltf *b, const char *what) {
    check_same_asset_as(a, b, what, 0);
}

/* ---- loading and known answers --------------------------------------------------------------------------- */

MR_TEST(every_asset_loads) {
    for (int i = 0; i < ASSET_COUNT; i++) {
        mr_gltf *g = NULL;
        MR_CHECK_OK(mr_gltf_load(asset_path(ASSETS[i].rel), &g));
        if (g == NULL) continue;
        mr_gltf_counts c;
        mr_gltf_get_counts(g, &c);
        MR_CHECK_MSG(c.materials > 0 && c.meshes > 0 && c.nodes > 0, "%s", ASSETS[i].name);
        for (int k = 0; k < c.images; k++) {
            mr_gltf_image im;
            MR_CHECK_OK(mr_gltf_get_image(g, k, &im));
            MR_CHECK_MSG(im.size > 8 && strcmp(im.mime_type, "image/png") == 0 && im.bytes[0] == 0x89 &&
                             file_exists(im.path),
                         "%s image %d: %zu bytes, mime '%s', path '%s'", ASSETS[i].name, k, im.size, im.mime_type,
                         im.path);
        }
        for (int k = 0; k < c.materials; k++) {
            mr_gltf_material m;
            MR_CHECK_OK(mr_gltf_get_material(g, k, &m));
        }
        mr_gltf_free(g);
    }
}

MR_TEST(floppy_disk_spec_gloss_factors) {
    mr_gltf *g = load_asset("FloppyDisk");
    if (g == NULL) return;
    mr_gltf_material m;
    MR_CHECK_OK(mr_gltf_get_material(g, 0, &m));
    MR_CHECK(strcmp(m.name, "material_0") == 0);
    MR_CHECK(m.has_spec_gloss && !m.has_specular && !m.has_ior);
    for (int c = 0; c < 3; c++) {
        MR_CHECK_NEAR(m.diffuse_factor[c], 0.93, 1e-12);
        MR_CHECK_NEAR(m.specular_factor[c], 0.89, 1e-12);
    }
    MR_CHECK_NEAR(m.diffuse_factor[3], 1.0, 0);
    MR_CHECK_NEAR(m.glossiness_factor, 0.91, 1e-12);
    MR_CHECK(m.diffuse_texture.index == 0 && m.specular_glossiness_texture.index == 1);
    MR_CHECK(m.normal_texture.index == 2 && m.normal_texture.value == 1.0);
    MR_CHECK(m.base_color_texture.index == -1 && m.metallic_roughness_texture.index == -1);
    MR_CHECK(mr_gltf_extension_used(g, "KHR_materials_pbrSpecularGlossiness"));
    MR_CHECK(mr_gltf_extension_required(g, "KHR_materials_pbrSpecularGlossiness"));
    /* A fallback added: the extension stays used, no longer required (and back). */
    MR_CHECK_OK(mr_gltf_set_extension_required(g, "KHR_materials_pbrSpecularGlossiness", 0));
    MR_CHECK(!mr_gltf_extension_required(g, "KHR_materials_pbrSpecularGlossiness"));
    MR_CHECK(mr_gltf_extension_used(g, "KHR_materials_pbrSpecularGlossiness"));
    MR_CHECK_OK(mr_gltf_set_extension_required(g, "KHR_materials_pbrSpecularGlossiness", 1));
    MR_CHECK(mr_gltf_extension_required(g, "KHR_materials_pbrSpecularGlossiness"));
    MR_CHECK_OK(mr_gltf_set_extension_required(g, "EXT_new", 1));
    MR_CHECK(mr_gltf_extension_used(g, "EXT_new") && mr_gltf_extension_required(g, "EXT_new"));
    mr_gltf_texture t;
    MR_CHECK_OK(mr_gltf_get_texture(g, 1, &t));
    MR_CHECK(t.image == 1 && t.sampler == 0 && t.params.mag_filter == MR_GLTF_FILTER_LINEAR &&
             t.params.min_filter == MR_GLTF_FILTER_LINEAR_MIPMAP_LINEAR);
    mr_gltf_image im;
    MR_CHECK_OK(mr_gltf_get_image(g, 1, &im));
    MR_CHECK(strcmp(im.uri, "textures/material_0_specularGlossiness.png") == 0);
    MR_CHECK(strstr(im.path, "FloppyDisk-sketchfab/textures/material_0_specularGlossiness.png") != NULL);
    MR_CHECK((long)im.size == file_size(im.path) && im.buffer_view == -1);
    mr_gltf_free(g);
}

MR_TEST(avocado_carries_both_workflows) {
    mr_gltf *g = load_asset("Avocado");
    if (g == NULL) return;
    mr_gltf_material m;
    MR_CHECK_OK(mr_gltf_get_material(g, 0, &m));
    MR_CHECK(strcmp(m.name, "2256_Avocado_d") == 0);
    MR_CHECK(m.base_color_texture.index == 0 && m.metallic_roughness_texture.index == 1);
    MR_CHECK(m.has_spec_gloss && m.diffuse_texture.index == 3 && m.specular_glossiness_texture.index == 4);
    MR_CHECK(m.metallic_factor == 1.0 && m.roughness_factor == 1.0 && m.glossiness_factor == 1.0);
    MR_CHECK(mr_gltf_extension_used(g, "KHR_materials_pbrSpecularGlossiness"));
    MR_CHECK(!mr_gltf_extension_required(g, "KHR_materials_pbrSpecularGlossiness"));
    mr_gltf_texture t;
    MR_CHECK_OK(mr_gltf_get_texture(g, 4, &t));
    MR_CHECK(t.image == 4 && t.sampler == -1 && t.params.wrap_s == MR_WRAP_REPEAT &&
             t.params.min_filter == MR_GLTF_FILTER_UNSET);
    mr_gltf_free(g);
}

MR_TEST(water_bottle_packed_orm) {
    mr_gltf *g = load_asset("WaterBottle");
    if (g == NULL) return;
    mr_gltf_material m;
    MR_CHECK_OK(mr_gltf_get_material(g, 0, &m));
    MR_CHECK(strcmp(m.name, "BottleMat") == 0 && !m.has_spec_gloss);
    MR_CHECK(m.metallic_roughness_texture.index == 1 && m.occlusion_texture.index == 1);
    MR_CHECK(m.occlusion_texture.value == 1.0);
    MR_CHECK(m.emissive_texture.index == 3);
    MR_CHECK(m.emissive_factor[0] == 1.0 && m.emissive_factor[1] == 1.0 && m.emissive_factor[2] == 1.0);
    mr_gltf_texture t;
    MR_CHECK_OK(mr_gltf_get_texture(g, 1, &t));
    mr_gltf_image im;
    MR_CHECK_OK(mr_gltf_get_image(g, t.image, &im));
    MR_CHECK(strcmp(im.uri, "WaterBottle_occlusionRoughnessMetallic.png") == 0);
    mr_gltf_free(g);
}

MR_TEST(texture_settings_samplers) {
    mr_gltf *g = load_asset("TextureSettingsTest");
    if (g == NULL) return;
    mr_gltf_counts c;
    mr_gltf_get_counts(g, &c);
    MR_CHECK(c.materials == 10 && c.textures == 9 && c.samplers == 5 && c.images == 3);
    /* texture -> expected wrapS, wrapT (TextureSettingsTest.gltf's samplers by name) */
    const int wraps[][3] = {{0, MR_WRAP_REPEAT, MR_WRAP_MIRROR}, {1, MR_WRAP_MIRROR, MR_WRAP_REPEAT},
                            {2, MR_WRAP_CLAMP, MR_WRAP_REPEAT}, {3, MR_WRAP_REPEAT, MR_WRAP_CLAMP},
                            {6, MR_WRAP_REPEAT, MR_WRAP_REPEAT}};
    for (int i = 0; i < 5; i++) {
        mr_gltf_texture t;
        MR_CHECK_OK(mr_gltf_get_texture(g, wraps[i][0], &t));
        MR_CHECK_MSG((int)t.params.wrap_s == wraps[i][1] && (int)t.params.wrap_t == wraps[i][2] &&
                         t.params.mag_filter == MR_GLTF_FILTER_LINEAR &&
                         t.params.min_filter == MR_GLTF_FILTER_NEAREST_MIPMAP_LINEAR,
                     "texture %d: wrap %d/%d", wraps[i][0], t.params.wrap_s, t.params.wrap_t);
    }
    int double_sided = 0;
    for (int i = 0; i < c.materials; i++) {
        mr_gltf_material m;
        MR_CHECK_OK(mr_gltf_get_material(g, i, &m));
        MR_CHECK(m.metallic_factor == 0.0 && m.roughness_factor == 0.9);
        if (strcmp(m.name, "DoubleSidedMaterial") == 0) {
            MR_CHECK(m.double_sided == 1);
            double_sided++;
        } else {
            MR_CHECK_MSG(m.double_sided == 0, "%s", m.name);
        }
        if (strcmp(m.name, "BackgroundMaterial") == 0) {
            MR_CHECK_NEAR(m.base_color_factor[2], 0.6399999856948853, 0);
            MR_CHECK(m.base_color_texture.index == -1);
        }
    }
    MR_CHECK(double_sided == 1);
    mr_gltf_free(g);
}

MR_TEST(duck_and_truck) {
    mr_gltf *g = load_asset("Duck");
    if (g != NULL) {
        mr_gltf_material m;
        MR_CHECK_OK(mr_gltf_get_material(g, 0, &m));
        MR_CHECK(m.has_spec_gloss && m.metallic_factor == 0.0);
        MR_CHECK_NEAR(m.glossiness_factor, 0.30000001192092896, 0);
        MR_CHECK(m.specular_factor[0] == 0.0 && m.diffuse_texture.index == 0);
        mr_gltf_counts c;
        mr_gltf_get_counts(g, &c);
        MR_CHECK(c.cameras == 1);
        mr_gltf_free(g);
    }
    g = load_asset("CesiumMilkTruck");
    if (g != NULL) {
        mr_gltf_counts c;
        mr_gltf_get_counts(g, &c);
        MR_CHECK(c.materials == 4 && c.animations == 1);
        mr_gltf_material m;
        MR_CHECK_OK(mr_gltf_get_material(g, 1, &m));
        MR_CHECK(strcmp(m.name, "glass") == 0);
        MR_CHECK_NEAR(m.specular_factor[1], 0.6499999761581421, 0);
        MR_CHECK_NEAR(m.diffuse_factor[1], 0.04050629958510399, 0);
        mr_gltf_free(g);
    }
}

/* ---- round trips ------------------------------------------------------------------------------------------ */

MR_TEST(round_trip_every_asset) {
    const char *keep = getenv("MR_GLTF_KEEP");
    for (int i = 0; i < ASSET_COUNT; i++) {
        mr_gltf *a = NULL;
        MR_CHECK_OK(mr_gltf_load(asset_path(ASSETS[i].rel), &a));
        if (a == NULL) continue;
        const char *fmts[] = {"gltf", "glb"};
        for (int f = 0; f < 2; f++) {
            char dir[512], out[600];
            if (keep != NULL) snprintf(dir, sizeof dir, "%s/%s", keep, ASSETS[i].name);
            else snprintf(dir, sizeof dir, "%s", mr_test_tmp_path(ASSETS[i].name));
            mkdir(dir, 0777);
            snprintf(out, sizeof out, "%s/%s.%s", dir, ASSETS[i].name, fmts[f]);
            MR_CHECK_OK(mr_gltf_save(a, out));
            mr_gltf *b = NULL;
            MR_CHECK_OK(mr_gltf_load(out, &b));
            if (b == NULL) continue;
            char what[700];
            snprintf(what, sizeof what, "%s as .%s", ASSETS[i].name, fmts[f]);
            check_same_asset_as(a, b, what, f == 1);
            /* Twice round: the written copy writes the same again. */
            char out2[620];
            snprintf(out2, sizeof out2, "%s/%s_again.%s", dir, ASSETS[i].name, fmts[f]);
            MR_CHECK_OK(mr_gltf_save(b, out2));
            mr_gltf *c = NULL;
            MR_CHECK_OK(mr_gltf_load(out2, &c));
            if (c != NULL) check_same_asset_as(a, c, what, f == 1);
            mr_gltf_free(c);
            mr_gltf_free(b);
        }
        mr_gltf_free(a);
    }
}

/* MR_GLTF_IN=FILE MR_GLTF_OUT=FILE: one file through load -> save -> load (tests/gltf_validate.sh); a no-op
 * without them. */
MR_TEST(round_trip_file_from_env) {
    const char *in = getenv("MR_GLTF_IN"), *out = getenv("MR_GLTF_OUT");
    if (in == NULL || out == NULL) return;
    mr_gltf *a = NULL, *b = NULL;
    MR_CHECK_OK(mr_gltf_load(in, &a));
    if (a == NULL) return;
    MR_CHECK_OK(mr_gltf_save(a, out));
    MR_CHECK_OK(mr_gltf_load(out, &b));
    size_t n = strlen(out);
    if (b != NULL) check_same_asset_as(a, b, in, n > 4 && strcmp(out + n - 4, ".glb") == 0);
    mr_gltf_free(b);
    mr_gltf_free(a);
}

/* A GLB whose images live in buffer views of its binary chunk: read, written as .glb and as .gltf. */
MR_TEST(glb_embedded_resources) {
    mr_gltf *src = load_asset("Duck");
    if (src == NULL) return;
    mr_gltf_image im;
    MR_CHECK_OK(mr_gltf_get_image(src, 0, &im));
    /* A hand-made GLB: one triangle-free scene, one material, the duck's PNG in buffer view 0. */
    char json[1024];
    int n = snprintf(json, sizeof json,
                     "{\"asset\":{\"version\":\"2.0\"},\"buffers\":[{\"byteLength\":%zu}],"
                     "\"bufferViews\":[{\"buffer\":0,\"byteLength\":%zu}],"
                     "\"images\":[{\"bufferView\":0,\"mimeType\":\"image/png\"}],"
                     "\"textures\":[{\"source\":0}],\"materials\":[{\"name\":\"m\",\"pbrMetallicRoughness\":"
                     "{\"baseColorTexture\":{\"index\":0},\"metallicFactor\":0.25}}],"
                     "\"nodes\":[{\"name\":\"n\"}],\"scenes\":[{\"nodes\":[0]}],\"scene\":0}",
                     (im.size + 3) / 4 * 4, im.size);
    while (n % 4) json[n++] = ' ';
    size_t bin = (im.size + 3) / 4 * 4;
    size_t total = 12 + 8 + (size_t)n + 8 + bin;
    unsigned char *glb = calloc(total, 1);
    uint32_t header[3] = {0x46546C67u, 2, (uint32_t)total};
    uint32_t jc[2] = {(uint32_t)n, 0x4E4F534Au};
    uint32_t bc[2] = {(uint32_t)bin, 0x004E4942u};
    memcpy(glb, header, 12);
    memcpy(glb + 12, jc, 8);
    memcpy(glb + 20, json, (size_t)n);
    memcpy(glb + 20 + n, bc, 8);
    memcpy(glb + 28 + n, im.bytes, im.size);
    const char *in = mr_test_tmp_path("embedded.glb");
    MR_CHECK(mr_test_write_file(in, glb, total));
    mr_gltf *g = NULL;
    MR_CHECK_OK(mr_gltf_load(in, &g));
    if (g != NULL) {
        mr_gltf_image e;
        MR_CHECK_OK(mr_gltf_get_image(g, 0, &e));
        MR_CHECK(e.buffer_view == 0 && e.size == im.size && memcmp(e.bytes, im.bytes, im.size) == 0);
        MR_CHECK(strcmp(e.mime_type, "image/png") == 0 && e.path[0] == '\0');
        const char *outs[] = {"embedded_out.glb", "embedded_out.gltf"};
        for (int f = 0; f < 2; f++) {
            MR_CHECK_OK(mr_gltf_save(g, mr_test_tmp_path(outs[f])));
            mr_gltf *b = NULL;
            MR_CHECK_OK(mr_gltf_load(mr_test_tmp_path(outs[f]), &b));
            if (b != NULL) check_same_asset_as(g, b, outs[f], f == 0);
            mr_gltf_free(b);
        }
        /* A .glb of a .gltf with external files holds them all: nothing beside it. */
        MR_CHECK(mkdir(mr_test_tmp_path("packed"), 0777) == 0);
        mr_gltf *floppy = load_asset("FloppyDisk");
        if (floppy != NULL) {
            MR_CHECK_OK(mr_gltf_save(floppy, mr_test_tmp_path("packed/floppy.glb")));
            MR_CHECK(count_entries(mr_test_tmp_path("packed")) == 1);
            mr_gltf *b = NULL;
            MR_CHECK_OK(mr_gltf_load(mr_test_tmp_path("packed/floppy.glb"), &b));
            if (b != NULL) {
                check_same_asset_as(floppy, b, "packed FloppyDisk", 1);
                mr_gltf_image pi;
                MR_CHECK_OK(mr_gltf_get_image(b, 2, &pi));
                MR_CHECK(pi.buffer_view >= 0 && pi.path[0] == '\0' && strcmp(pi.mime_type, "image/png") == 0);
            }
            mr_gltf_free(b);
            mr_gltf_free(floppy);
        }
        /* The .gltf holds the binary chunk as a file beside it. */
        MR_CHECK(file_size(mr_test_tmp_path("embedded_out.bin")) == (long)bin);
        /* Decoding goes through a file: the image's bytes written out. */
        MR_CHECK_OK(mr_gltf_image_write_file(g, 0, mr_test_tmp_path("embedded_image.png")));
        MR_CHECK(file_size(mr_test_tmp_path("embedded_image.png")) == (long)im.size);
        MR_CHECK(mr_gltf_image_write_file(g, 0, in) == MR_ERR_INVALID_ARG);
    }
    free(glb);
    mr_gltf_free(g);
    mr_gltf_free(src);
}

/* Data-URI buffer and image: read, kept as data URIs on write. */
MR_TEST(data_uri_resources) {
    /* A 1x1 PNG and 12 bytes of buffer (three floats). */
    const char *png = "iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAIAAACQd1PeAAAADElEQVR4nGP4z8AAAAMBAQDJ/pLvAAAAAElFTkSuQmCC";
    char json[2048];
    snprintf(json, sizeof json,
             "{\"asset\":{\"version\":\"2.0\"},"
             "\"buffers\":[{\"byteLength\":12,\"uri\":\"data:application/octet-stream;base64,AACAPwAAAEAAAEBA\"}],"
             "\"bufferViews\":[{\"buffer\":0,\"byteLength\":12}],"
             "\"accessors\":[{\"bufferView\":0,\"componentType\":5126,\"count\":1,\"type\":\"VEC3\","
             "\"min\":[1,2,3],\"max\":[1,2,3]}],"
             "\"images\":[{\"uri\":\"data:image/png;base64,%s\"}],\"samplers\":[{\"wrapS\":33071}],"
             "\"textures\":[{\"source\":0,\"sampler\":0}],"
             "\"materials\":[{\"name\":\"d\",\"emissiveTexture\":{\"index\":0,\"texCoord\":1,"
             "\"extensions\":{\"KHR_texture_transform\":{\"offset\":[0.5,0],\"rotation\":0.25,\"scale\":[2,3],"
             "\"texCoord\":0}}},\"extras\":{\"keep\":\"me\"}}],\"extensionsUsed\":[\"KHR_texture_transform\"],"
             "\"nodes\":[{\"name\":\"n\",\"extras\":{\"id\":7}}],\"scenes\":[{\"nodes\":[0]}],\"scene\":0}\n",
             png);
    const char *in = mr_test_tmp_path("datauri.gltf");
    MR_CHECK(mr_test_write_file(in, json, strlen(json)));
    mr_gltf *g = NULL;
    MR_CHECK_OK(mr_gltf_load(in, &g));
    if (g == NULL) return;
    mr_gltf_image im;
    MR_CHECK_OK(mr_gltf_get_image(g, 0, &im));
    MR_CHECK(im.size == 69 && im.bytes[1] == 'P' && strcmp(im.mime_type, "image/png") == 0 && im.path[0] == 0);
    mr_gltf_material m;
    MR_CHECK_OK(mr_gltf_get_material(g, 0, &m));
    MR_CHECK(m.emissive_texture.index == 0 && m.emissive_texture.tex_coord == 1 && m.emissive_texture.has_transform);
    MR_CHECK(m.emissive_texture.offset[0] == 0.5 && m.emissive_texture.rotation == 0.25);
    MR_CHECK(m.emissive_texture.scale[1] == 3.0 && m.emissive_texture.transform_tex_coord == 0);
    mr_gltf_texture t;
    MR_CHECK_OK(mr_gltf_get_texture(g, 0, &t));
    MR_CHECK(t.params.wrap_s == MR_WRAP_CLAMP && t.params.wrap_t == MR_WRAP_REPEAT);
    const char *out = mr_test_tmp_path("datauri_out.gltf");
    MR_CHECK_OK(mr_gltf_save(g, out));
    char *text = mr_test_read_file(out, NULL);
    if (text != NULL) {
        MR_CHECK(strstr(text, "data:application/octet-stream;base64,AACAPwAAAEAAAEBA") != NULL);
        MR_CHECK(strstr(text, png) != NULL && strstr(text, "data:image/png;base64,") != NULL);
        MR_CHECK(strstr(text, "\"keep\": \"me\"") != NULL && strstr(text, "\"id\": 7") != NULL);
        free(text);
    }
    /* Only the .gltf itself (and the input) in the directory: no side files for data URIs. */
    MR_CHECK(!file_exists(mr_test_tmp_path("datauri_out.bin")));
    mr_gltf *b = NULL;
    MR_CHECK_OK(mr_gltf_load(out, &b));
    if (b != NULL) check_same_asset(g, b, "data URIs");
    mr_gltf_free(b);
    mr_gltf_free(g);
}

/* ---- decoding an asset's images ------------------------------------------------------------------------- */

static char *base64(const unsigned char *p, size_t n) {
    static const char table[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    char *out = malloc((n + 2) / 3 * 4 + 1), *o = out;
    if (out == NULL) return NULL;
    for (size_t i = 0; i < n; i += 3) {
        unsigned v = (unsigned)p[i] << 16 | (i + 1 < n ? (unsigned)p[i + 1] << 8 : 0) | (i + 2 < n ? p[i + 2] : 0);
        *o++ = table[(v >> 18) & 63];
        *o++ = table[(v >> 12) & 63];
        *o++ = i + 1 < n ? table[(v >> 6) & 63] : '=';
        *o++ = i + 2 < n ? table[v & 63] : '=';
    }
    *o = '\0';
    return out;
}

/* mr_gltf_image_read of `image` equals mr_img_read_stored of `file`, bit for bit, as colour and as data. */
static void image_reads_as(const mr_gltf *g, int image, const char *file) {
    for (int e = 0; e < 2; e++) {
        mr_img_read_options ro = {e == 0 ? MR_IMG_COLOR : MR_IMG_DATA, 0, 0};
        mr_image *a = NULL, *b = NULL;
        mr_img_stored sa = {-1, MR_IMG_COLOR}, sb = {-2, MR_IMG_DATA};
        MR_CHECK_OK(mr_gltf_image_read(g, image, &ro, &a, &sa));
        MR_CHECK_OK(mr_img_read_stored(file, &ro, &b, &sb));
        int same = a != NULL && b != NULL && a->width == b->width && a->height == b->height &&
                   a->channels == b->channels &&
                   memcmp(a->pixels, b->pixels, mr_image_value_count(a) * sizeof(float)) == 0;
        MR_CHECK_MSG(same && sa.bits == sb.bits && sa.encoding == sb.encoding, "image %d differs from %s", image,
                     file);
        mr_image_free(a);
        mr_image_free(b);
    }
}

/* Embedded images (data URIs and buffer views, PNG and JPEG) decode from memory to what their files decode to,
 * with nowhere to write a temporary file; a corrupt one fails naming the asset and the image index. */
MR_TEST(embedded_images_decode_from_memory) {
    /* A PNG of the shared assets and a JPEG the library writes from it, embedded in a .gltf. */
    char png_path[1024], jpg_path[512];
    snprintf(png_path, sizeof png_path, "%s", asset_path("metalrough/TextureSettingsTest/glTF/CheckAndX.png"));
    snprintf(jpg_path, sizeof jpg_path, "%s", mr_test_tmp_path("ref.jpg"));
    mr_image *check = NULL;
    MR_CHECK_OK(mr_img_read(png_path, NULL, &check));
    MR_CHECK_OK(mr_img_write(jpg_path, check, NULL));
    mr_image_free(check);
    size_t png_n = 0, jpg_n = 0;
    char *png = mr_test_read_file(png_path, &png_n), *jpg = mr_test_read_file(jpg_path, &jpg_n);
    MR_CHECK(png != NULL && jpg != NULL && png_n > 100 && jpg_n > 100);
    if (png == NULL || jpg == NULL || png_n <= 100 || jpg_n <= 100) {
        free(png);
        free(jpg);
        return;
    }
    MR_CHECK(mr_test_write_file(mr_test_tmp_path("ref.png"), png, png_n)); /* the external image, beside the asset */
    /* images.bin: the PNG, the JPEG and 64 bytes of garbage (4-byte aligned views) */
    size_t jpg_at = (png_n + 3) / 4 * 4, junk_at = (jpg_at + jpg_n + 3) / 4 * 4, bin_n = junk_at + 64;
    unsigned char *bin = calloc(bin_n, 1);
    memcpy(bin, png, png_n);
    memcpy(bin + jpg_at, jpg, jpg_n);
    memset(bin + junk_at, 0x5a, 64);
    MR_CHECK(mr_test_write_file(mr_test_tmp_path("images.bin"), bin, bin_n));
    char *png64 = base64((const unsigned char *)png, png_n), *jpg64 = base64((const unsigned char *)jpg, jpg_n);
    char *cut64 = base64((const unsigned char *)png, png_n / 2);
    size_t cap = strlen(png64) + strlen(jpg64) + strlen(cut64) + 4096;
    char *json = malloc(cap);
    snprintf(json, cap,
             "{\"asset\":{\"version\":\"2.0\"},\"buffers\":[{\"byteLength\":%zu,\"uri\":\"images.bin\"}],"
             "\"bufferViews\":[{\"buffer\":0,\"byteLength\":%zu},{\"buffer\":0,\"byteOffset\":%zu,\"byteLength\":%zu},"
             "{\"buffer\":0,\"byteOffset\":%zu,\"byteLength\":64}],"
             "\"images\":[{\"uri\":\"data:image/png;base64,%s\"},{\"bufferView\":0,\"mimeType\":\"image/png\"},"
             "{\"uri\":\"data:image/jpeg;base64,%s\"},{\"bufferView\":1,\"mimeType\":\"image/jpeg\"},"
             "{\"uri\":\"ref.png\"},{\"uri\":\"data:image/png;base64,%s\"},"
             "{\"bufferView\":2,\"mimeType\":\"image/png\"}],"
             "\"textures\":[{\"source\":1},{\"source\":5}]}\n",
             bin_n, png_n, jpg_at, jpg_n, junk_at, png64, jpg64, cut64);
    const char *in = mr_test_tmp_path("embedded_images.gltf");
    MR_CHECK(mr_test_write_file(in, json, strlen(json)));
    mr_gltf *g = NULL;
    MR_CHECK_OK(mr_gltf_load(in, &g));
    if (g != NULL) {
        /* Nowhere to put a temporary file: decoding must not need one. */
        const char *tmpdir = getenv("TMPDIR");
        char saved[1024] = "";
        if (tmpdir != NULL) snprintf(saved, sizeof saved, "%s", tmpdir);
        setenv("TMPDIR", "/nonexistent/matremap-tmp", 1);
        image_reads_as(g, 0, png_path);
        image_reads_as(g, 1, png_path);
        image_reads_as(g, 2, jpg_path);
        image_reads_as(g, 3, jpg_path);
        image_reads_as(g, 4, png_path);
        mr_image *img = NULL;
        MR_CHECK_OK(mr_gltf_texture_read(g, 0, NULL, &img, NULL));
        MR_CHECK(img != NULL && img->width == 512 && img->height == 512 && img->channels == 3);
        mr_image_free(img);
        img = NULL;
        /* Corrupt: half a PNG as a data URI, garbage in a buffer view. The message names the asset and the
         * image, and no temporary file. */
        char want[1200];
        const int corrupt[2] = {5, 6};
        for (int k = 0; k < 2; k++) {
            MR_CHECK(mr_gltf_image_read(g, corrupt[k], NULL, &img, NULL) == MR_ERR_FORMAT && img == NULL);
            snprintf(want, sizeof want, "glTF '%s': image %d", in, corrupt[k]);
            MR_CHECK_MSG(strstr(mr_last_error(), want) != NULL && strstr(mr_last_error(), "matremap-") == NULL &&
                             strstr(mr_last_error(), k == 0 ? "truncated PNG" : "not an image") != NULL,
                         "%s", mr_last_error());
        }
        MR_CHECK(mr_gltf_texture_read(g, 1, NULL, &img, NULL) == MR_ERR_FORMAT && img == NULL);
        snprintf(want, sizeof want, "glTF '%s': image 5", in);
        MR_CHECK_MSG(strstr(mr_last_error(), want) != NULL, "%s", mr_last_error());
        /* An external image's errors name the asset and the image too. */
        MR_CHECK(mr_test_write_file(mr_test_tmp_path("ref.png"), png, png_n / 2));
        MR_CHECK(mr_gltf_image_read(g, 4, NULL, &img, NULL) == MR_ERR_FORMAT && img == NULL);
        snprintf(want, sizeof want, "glTF '%s': image 4: image '", in);
        MR_CHECK_MSG(strstr(mr_last_error(), want) != NULL && strstr(mr_last_error(), "ref.png") != NULL, "%s",
                     mr_last_error());
        if (tmpdir != NULL) setenv("TMPDIR", saved, 1);
        else unsetenv("TMPDIR");
    }
    mr_gltf_free(g);
    free(json);
    free(png64);
    free(jpg64);
    free(cut64);
    free(bin);
    free(png);
    free(jpg);
}

/* ---- edits ------------------------------------------------------------------------------------------------ */

MR_TEST(drop_spec_gloss_set_metal_rough_add_texture) {
    mr_gltf *g = load_asset("FloppyDisk");
    if (g == NULL) return;
    mr_gltf_material m;
    MR_CHECK_OK(mr_gltf_get_material(g, 0, &m));
    /* Fields of an absent extension are ignored on set and read back as glTF's defaults. */
    mr_gltf_material defaults;
    mr_gltf_material_defaults(&defaults);
    m.has_spec_gloss = 0;
    memcpy(m.diffuse_factor, defaults.diffuse_factor, sizeof m.diffuse_factor);
    memcpy(m.specular_factor, defaults.specular_factor, sizeof m.specular_factor);
    m.glossiness_factor = 1.0;
    m.diffuse_texture = defaults.diffuse_texture;
    m.specular_glossiness_texture = defaults.specular_glossiness_texture;
    m.base_color_factor[0] = 0.25;
    m.base_color_factor[3] = 0.5;
    m.metallic_factor = 0.125;
    m.roughness_factor = 0.09;
    m.alpha_mode = MR_GLTF_ALPHA_MASK;
    m.alpha_cutoff = 0.3;
    m.double_sided = 1;
    m.name = "converted";

    mr_gltf_image diffuse;
    MR_CHECK_OK(mr_gltf_get_image(g, 0, &diffuse));
    int image = -1, texture = -1, texture2 = -1;
    MR_CHECK_OK(mr_gltf_add_image_file(g, diffuse.path, "maps/base color.png", &image));
    MR_CHECK(image == 3);
    mr_gltf_texture existing;
    MR_CHECK_OK(mr_gltf_get_texture(g, 0, &existing));
    MR_CHECK_OK(mr_gltf_add_texture(g, image, &existing.params, &texture));
    MR_CHECK(texture == 3);
    mr_gltf_counts c;
    mr_gltf_get_counts(g, &c);
    MR_CHECK(c.samplers == 1); /* the identical sampler was reused */
    mr_gltf_sampler clamp = {MR_GLTF_FILTER_LINEAR, MR_GLTF_FILTER_LINEAR, MR_WRAP_CLAMP, MR_WRAP_CLAMP};
    MR_CHECK_OK(mr_gltf_add_texture(g, 1, &clamp, &texture2));
    mr_gltf_get_counts(g, &c);
    MR_CHECK(c.samplers == 2 && texture2 == 4);

    m.base_color_texture.index = texture;
    m.base_color_texture.has_transform = 1;
    m.base_color_texture.scale[0] = 4.0;
    m.base_color_texture.rotation = 0.5;
    m.metallic_roughness_texture.index = texture2;
    m.has_specular = 1;
    m.specular_strength = 0.5;
    m.specular_color_factor[1] = 0.75;
    m.specular_color_texture.index = texture2;
    m.has_ior = 1;
    m.ior = 1000.0;
    MR_CHECK_OK(mr_gltf_set_material(g, 0, &m));

    mr_gltf_material back;
    MR_CHECK_OK(mr_gltf_get_material(g, 0, &back));
    MR_CHECK(same_material(&m, &back));
    MR_CHECK(!mr_gltf_material_has_extension(g, 0, "KHR_materials_pbrSpecularGlossiness"));
    MR_CHECK(mr_gltf_material_has_extension(g, 0, "KHR_materials_ior"));

    MR_CHECK(mkdir(mr_test_tmp_path("edit"), 0777) == 0);
    const char *out = mr_test_tmp_path("edit/floppy.gltf");
    MR_CHECK_OK(mr_gltf_save(g, out));
    /* extensionsUsed/Required follow the materials. */
    MR_CHECK(!mr_gltf_extension_used(g, "KHR_materials_pbrSpecularGlossiness"));
    MR_CHECK(!mr_gltf_extension_required(g, "KHR_materials_pbrSpecularGlossiness"));
    MR_CHECK(mr_gltf_extension_used(g, "KHR_materials_specular") && mr_gltf_extension_used(g, "KHR_materials_ior"));
    MR_CHECK(mr_gltf_extension_used(g, "KHR_texture_transform"));
    MR_CHECK(file_size(mr_test_tmp_path("edit/maps/base color.png")) == (long)diffuse.size);
    MR_CHECK(file_exists(mr_test_tmp_path("edit/textures/material_0_normal.png")));
    MR_CHECK(file_exists(mr_test_tmp_path("edit/scene.bin")));
    const char *keep = getenv("MR_GLTF_KEEP");
    if (keep != NULL) { /* for the validator (tests/gltf_validate.sh) */
        char dir[512], kept[600];
        snprintf(dir, sizeof dir, "%s/Edited", keep);
        mkdir(dir, 0777);
        snprintf(kept, sizeof kept, "%s/Edited.gltf", dir);
        MR_CHECK_OK(mr_gltf_save(g, kept));
    }

    mr_gltf *b = NULL;
    MR_CHECK_OK(mr_gltf_load(out, &b));
    if (b != NULL) {
        check_same_asset(g, b, "edited FloppyDisk");
        MR_CHECK_OK(mr_gltf_get_material(b, 0, &back));
        MR_CHECK(strcmp(back.name, "converted") == 0 && back.ior == 1000.0 && back.roughness_factor == 0.09);
        MR_CHECK(back.base_color_texture.scale[0] == 4.0 && back.metallic_roughness_texture.index == 4);
        MR_CHECK(!back.has_spec_gloss && back.alpha_mode == MR_GLTF_ALPHA_MASK && back.double_sided);
        mr_gltf_image added;
        MR_CHECK_OK(mr_gltf_get_image(b, 3, &added));
        MR_CHECK(strcmp(added.uri, "maps/base%20color.png") == 0);
        MR_CHECK(added.size == diffuse.size && memcmp(added.bytes, diffuse.bytes, diffuse.size) == 0);
        /* Drop the extensions again: they leave extensionsUsed. */
        int removed = 0;
        MR_CHECK_OK(mr_gltf_remove_material_extension(b, 0, "KHR_materials_ior", &removed));
        MR_CHECK(removed == 1);
        MR_CHECK_OK(mr_gltf_remove_material_extension(b, 0, "KHR_materials_ior", &removed));
        MR_CHECK(removed == 0);
        MR_CHECK_OK(mr_gltf_get_material(b, 0, &back));
        back.has_specular = 0;
        back.base_color_texture.has_transform = 0;
        MR_CHECK_OK(mr_gltf_set_material(b, 0, &back));
        mr_gltf_sync_extensions(b);
        MR_CHECK(!mr_gltf_extension_used(b, "KHR_materials_ior"));
        MR_CHECK(!mr_gltf_extension_used(b, "KHR_materials_specular"));
        MR_CHECK(!mr_gltf_extension_used(b, "KHR_texture_transform"));
        mr_gltf_free(b);
    }
    /* Bad edits are refused and change nothing. */
    MR_CHECK_OK(mr_gltf_get_material(g, 0, &m));
    m.normal_texture.index = 99;
    m.metallic_factor = 0.0;
    MR_CHECK(mr_gltf_set_material(g, 0, &m) == MR_ERR_INVALID_ARG);
    MR_CHECK(strstr(mr_last_error(), "texture 99") != NULL);
    MR_CHECK_OK(mr_gltf_get_material(g, 0, &back));
    MR_CHECK(back.metallic_factor == 0.125);
    MR_CHECK(mr_gltf_get_material(g, 1, &m) == MR_ERR_INVALID_ARG);
    MR_CHECK(mr_gltf_add_image_file(g, diffuse.path, "../escape.png", &image) == MR_ERR_INVALID_ARG);
    MR_CHECK(mr_gltf_add_image_file(g, mr_test_tmp_path("missing.png"), "x.png", &image) == MR_ERR_IO);
    mr_gltf_free(g);
}

/* ---- failures --------------------------------------------------------------------------------------------- */

static void expect_load_error(const char *path, mr_status expected, const char *needle) {
    mr_gltf *g = (mr_gltf *)&g; /* must stay untouched */
    mr_gltf *before = g;
    mr_status s = mr_gltf_load(path, &g);
    MR_CHECK_MSG(s == expected, "%s: %s (%s), expected %s", path, mr_status_str(s), mr_last_error(),
                 mr_status_str(expected));
    MR_CHECK(g == before);
    MR_CHECK_MSG(strstr(mr_last_error(), path) != NULL, "message '%s' does not name '%s'", mr_last_error(), path);
    if (needle != NULL)
        MR_CHECK_MSG(strstr(mr_last_error(), needle) != NULL, "message '%s' lacks '%s'", mr_last_error(), needle);
}

MR_TEST(bad_inputs) {
    expect_load_error(mr_test_tmp_path("missing.gltf"), MR_ERR_IO, NULL);
    const char *bad_json = mr_test_tmp_path("bad.gltf");
    MR_CHECK(mr_test_write_file(bad_json, "{\"asset\": {\"version\": \"2.0\"}, \"nodes\": [", 40));
    expect_load_error(bad_json, MR_ERR_FORMAT, NULL);
    const char *empty = mr_test_tmp_path("empty.gltf");
    MR_CHECK(mr_test_write_file(empty, "", 0));
    expect_load_error(empty, MR_ERR_FORMAT, NULL);
    expect_load_error(mr_test_scratch_dir(), MR_ERR_IO, "directory");

    /* A buffer URI that does not exist. */
    const char *nobuf = mr_test_tmp_path("nobuf.gltf");
    const char *j = "{\"asset\":{\"version\":\"2.0\"},\"buffers\":[{\"byteLength\":12,\"uri\":\"gone.bin\"}]}";
    MR_CHECK(mr_test_write_file(nobuf, j, strlen(j)));
    expect_load_error(nobuf, MR_ERR_IO, "gone.bin");
    /* An image file that does not exist. */
    const char *noimg = mr_test_tmp_path("noimg.gltf");
    j = "{\"asset\":{\"version\":\"2.0\"},\"images\":[{\"uri\":\"gone.png\"}]}";
    MR_CHECK(mr_test_write_file(noimg, j, strlen(j)));
    expect_load_error(noimg, MR_ERR_IO, "gone.png");

    /* Truncated .glb: a valid one cut in half, then cut inside its header. */
    mr_gltf *g = load_asset("Duck");
    if (g == NULL) return;
    const char *glb = mr_test_tmp_path("duck.glb");
    MR_CHECK_OK(mr_gltf_save(g, glb));
    size_t size;
    char *bytes = mr_test_read_file(glb, &size);
    if (bytes != NULL) {
        const char *cut = mr_test_tmp_path("cut.glb");
        MR_CHECK(mr_test_write_file(cut, bytes, (size_t)size / 2));
        expect_load_error(cut, MR_ERR_FORMAT, NULL);
        MR_CHECK(mr_test_write_file(cut, bytes, 10));
        expect_load_error(cut, MR_ERR_FORMAT, NULL);
        free(bytes);
    }

    /* Saving: unknown extension, over the input, into a missing directory. */
    MR_CHECK(mr_gltf_save(g, mr_test_tmp_path("x.obj")) == MR_ERR_INVALID_ARG);
    MR_CHECK(mr_gltf_save(g, mr_gltf_path(g)) == MR_ERR_INVALID_ARG);
    MR_CHECK(strstr(mr_last_error(), "read from") != NULL);
    MR_CHECK(mr_gltf_save(g, mr_test_tmp_path("no/such/dir/x.gltf")) == MR_ERR_IO);
    MR_CHECK(!file_exists(mr_test_tmp_path("no")));
    mr_gltf_free(g);
}

/* Writes `json` to scratch file `name` and expects mr_gltf_load to fail with `expected`, naming the file, `needle`. */
static void expect_json_error(const char *name, const char *json, mr_status expected, const char *needle) {
    const char *path = mr_test_tmp_path(name);
    MR_CHECK(mr_test_write_file(path, json, strlen(json)));
    expect_load_error(path, expected, needle);
}

/* Files that lie (issue 16): JSON nested past the limit (tens of thousands of levels overflowed the stack), URIs
 * naming a folder, a FIFO or a device (a 2^63-byte allocation, a hang), an image in a buffer view past its buffer
 * (read past the end), material extensions that are not objects (tinygltf dropped them: the material read as if
 * it had none) and fields of the wrong type, count or range. Each fails to load with MR_ERR_IO or MR_ERR_FORMAT
 * naming the file, the object and the field. */
MR_TEST(hostile_inputs) {
    // Nesting: the root object and 127 arrays are 128 levels, the limit; one more is refused, naming the byte.
    char *json = malloc(2000);
    for (int extra = 0; extra < 2 && json != NULL; extra++) {
        const int arrays = 127 + extra;
        int n = sprintf(json, "{\"asset\":{\"version\":\"2.0\"},\"extras\":");
        for (int i = 0; i < arrays; i++)
            json[n++] = '[';
        for (int i = 0; i < arrays; i++)
            json[n++] = ']';
        strcpy(json + n, "}");
        const char *path = mr_test_tmp_path(extra ? "deep129.gltf" : "deep128.gltf");
        MR_CHECK(mr_test_write_file(path, json, strlen(json)));
        if (extra) {
            expect_load_error(path, MR_ERR_FORMAT, "the JSON nests deeper than 128 levels (at byte 163)");
        } else {
            mr_gltf *g = NULL;
            MR_CHECK_OK(mr_gltf_load(path, &g));
            mr_gltf_free(g);
        }
    }
    free(json);
    // 50000 levels, as the crash had it, in a string too: brackets inside strings do not count.
    const int deep = 50000;
    json = malloc(2 * deep + 200);
    if (json != NULL) {
        int n = sprintf(json, "{\"asset\":{\"version\":\"2.0\"},\"extras\":\"[[[[\",\"x\":");
        for (int i = 0; i < deep; i++)
            json[n++] = '[';
        for (int i = 0; i < deep; i++)
            json[n++] = ']';
        strcpy(json + n, "}");
        expect_json_error("deep50000.gltf", json, MR_ERR_FORMAT, "nests deeper than 128 levels (at byte 174)");
        free(json);
    }

    // URIs naming what is not a regular file: refused by name, before a byte is read.
    MR_CHECK(mkdir(mr_test_tmp_path("folder"), 0777) == 0);
    MR_CHECK(mkfifo(mr_test_tmp_path("pipe.png"), 0666) == 0);
    expect_json_error("img_dir.gltf", "{\"asset\":{\"version\":\"2.0\"},\"images\":[{\"uri\":\"folder/\"}]}", MR_ERR_IO,
                      "image 0 ('folder/'): is a directory");
    expect_json_error("buf_dir.gltf",
                      "{\"asset\":{\"version\":\"2.0\"},\"buffers\":[{\"byteLength\":4,\"uri\":\"folder\"}]}",
                      MR_ERR_IO, "buffer 0 ('folder'): is a directory");
    expect_json_error("img_fifo.gltf", "{\"asset\":{\"version\":\"2.0\"},\"images\":[{\"uri\":\"pipe.png\"}]}",
                      MR_ERR_IO, "image 0 ('pipe.png'): is not a regular file (a FIFO)");
    expect_json_error("buf_fifo.gltf",
                      "{\"asset\":{\"version\":\"2.0\"},\"buffers\":[{\"byteLength\":4,\"uri\":\"pipe.png\"}]}",
                      MR_ERR_IO, "buffer 0 ('pipe.png'): is not a regular file (a FIFO)");
    expect_json_error("img_dev.gltf",
                      "{\"asset\":{\"version\":\"2.0\"},\"images\":[{\"uri\":\"../../../../../../../../dev/zero\"}]}",
                      MR_ERR_IO, "is not a regular file (a character device)");
    expect_load_error(mr_test_tmp_path("pipe.png"), MR_ERR_IO, "is not a regular file (a FIFO)");

    // An image in a buffer view that runs past its 4-byte buffer.
    expect_json_error(
        "img_view.gltf",
        "{\"asset\":{\"version\":\"2.0\"},\"buffers\":[{\"byteLength\":4,\"uri\":"
        "\"data:application/octet-stream;base64,AAAAAA==\"}],\"bufferViews\":[{\"buffer\":0,"
        "\"byteOffset\":2,\"byteLength\":1000}],\"images\":[{\"bufferView\":0,\"mimeType\":\"image/png\"}]}",
        MR_ERR_FORMAT,
        "image 0: buffer view 0 (byteOffset 2, byteLength 1000) runs past the end of "
        "buffer 0 (4 bytes)");

    // Materials: each field this API reads, as the schema has it.
    static const struct {
        const char *material, *needle;
    } bad[] = {
        {"{\"name\":\"M\",\"extensions\":{\"KHR_materials_pbrSpecularGlossiness\":5}}",
         "material 0 ('M'): extensions.KHR_materials_pbrSpecularGlossiness is a number, not a JSON object"},
        {"{\"extensions\":{\"KHR_materials_specular\":[]}}",
         "material 0: extensions.KHR_materials_specular is an array, not a JSON object"},
        {"{\"extensions\":{\"KHR_materials_pbrSpecularGlossiness\":{\"glossinessFactor\":\"1\"}}}",
         "extensions.KHR_materials_pbrSpecularGlossiness.glossinessFactor is a string, not a number"},
        {"{\"extensions\":{\"KHR_materials_pbrSpecularGlossiness\":{\"diffuseFactor\":[1,1,1]}}}",
         "diffuseFactor has 3 values, expected 4"},
        {"{\"extensions\":{\"KHR_materials_pbrSpecularGlossiness\":{\"specularFactor\":[1,1e999,1]}}}", "invalid JSON"},
        {"{\"extensions\":{\"KHR_materials_pbrSpecularGlossiness\":{\"diffuseTexture\":{\"index\":1}}}}",
         "diffuseTexture.index is 1: no such texture (the asset has 1)"},
        {"{\"extensions\":{\"KHR_materials_specular\":{\"specularColorTexture\":{\"index\":0,\"texCoord\":1.5}}}}",
         "specularColorTexture.texCoord is not an integer"},
        {"{\"normalTexture\":{\"index\":0,\"extensions\":{\"KHR_texture_transform\":{\"scale\":[1]}}}}",
         "normalTexture.extensions.KHR_texture_transform.scale has 1 values, expected 2"},
        {"{\"pbrMetallicRoughness\":{\"roughnessFactor\":-0.5}}",
         "pbrMetallicRoughness.roughnessFactor is -0.5, expected within [0, 1]"},
        {"{\"pbrMetallicRoughness\":{\"baseColorFactor\":\"red\"}}",
         "pbrMetallicRoughness.baseColorFactor is a string, not an array of 4 numbers"},
        {"{\"occlusionTexture\":{\"index\":0,\"strength\":2}}", "occlusionTexture.strength is 2, expected within"},
        {"{\"doubleSided\":1}", "doubleSided is a number, not a boolean"},
        {"{\"extensions\":{\"KHR_materials_ior\":{\"ior\":-1}}}", "extensions.KHR_materials_ior.ior is -1"},
        {"7", "materials' does not contain an JSON object"}, // tinygltf's own check and message
    };
    char text[1024];
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++) {
        snprintf(text, sizeof text,
                 "{\"asset\":{\"version\":\"2.0\"},\"images\":[{\"uri\":\"data:image/png;base64,iVBORw0KGgo=\"}],"
                 "\"textures\":[{\"source\":0}],\"materials\":[%s]}",
                 bad[k].material);
        expect_json_error("material.gltf", text, MR_ERR_FORMAT, bad[k].needle);
    }
    // ... and what is right loads: every field present, at the ends of its range.
    expect_json_error("texture.gltf", "{\"asset\":{\"version\":\"2.0\"},\"textures\":[{\"source\":0,\"sampler\":3}]}",
                      MR_ERR_FORMAT, "texture 0: source 0: no such image (the asset has 0)");
    const char *good = mr_test_tmp_path("good.gltf");
    snprintf(text, sizeof text,
             "{\"asset\":{\"version\":\"2.0\"},\"images\":[{\"uri\":\"data:image/png;base64,iVBORw0KGgo=\"}],"
             "\"textures\":[{\"source\":0}],\"materials\":[{\"name\":\"ok\",\"pbrMetallicRoughness\":{"
             "\"baseColorFactor\":[0,1,0.5,1],\"metallicFactor\":0,\"roughnessFactor\":1,\"baseColorTexture\":"
             "{\"index\":0,\"texCoord\":1,\"extensions\":{\"KHR_texture_transform\":{\"offset\":[-3,2],"
             "\"rotation\":7,\"scale\":[-1,40],\"texCoord\":0}}}},\"normalTexture\":{\"index\":0,\"scale\":-2},"
             "\"emissiveFactor\":[1,1,1],\"alphaMode\":\"MASK\",\"alphaCutoff\":0,\"doubleSided\":true,"
             "\"extensions\":{\"KHR_materials_ior\":{\"ior\":0},\"KHR_materials_specular\":{"
             "\"specularColorFactor\":[2,0,1]},\"VENDOR_other\":{}}}]}");
    MR_CHECK(mr_test_write_file(good, text, strlen(text)));
    mr_gltf *g = NULL;
    MR_CHECK_OK(mr_gltf_load(good, &g));
    mr_gltf_free(g);
}

/* Truncated and byte-flipped copies of a .glb and a .gltf: each load succeeds or fails with a message naming the
 * file; none crashes (make asan runs this under AddressSanitizer). Fixed seed. */
MR_TEST(mutated_inputs_fail_cleanly) {
    mr_gltf *g = load_asset("Duck");
    if (g == NULL) return;
    const char *sources[] = {mr_test_tmp_path("fuzz_src.glb"), mr_test_tmp_path("fuzz_src.gltf")};
    const char *mutants[] = {mr_test_tmp_path("fuzz.glb"), mr_test_tmp_path("fuzz.gltf")};
    MR_CHECK_OK(mr_gltf_save(g, sources[0]));
    MR_CHECK(mkdir(mr_test_tmp_path("fuzzdir"), 0777) == 0);
    MR_CHECK_OK(mr_gltf_save(g, mr_test_tmp_path("fuzzdir/Duck.gltf")));
    MR_CHECK(copy_file(mr_test_tmp_path("fuzzdir/Duck.gltf"), sources[1]));
    MR_CHECK(copy_file(mr_test_tmp_path("fuzzdir/Duck0.bin"), mr_test_tmp_path("Duck0.bin")));
    MR_CHECK(copy_file(mr_test_tmp_path("fuzzdir/DuckCM.png"), mr_test_tmp_path("DuckCM.png")));
    mr_gltf_free(g);
    unsigned seed = 12345;
    for (int s = 0; s < 2; s++) {
        size_t n;
        unsigned char *bytes = (unsigned char *)mr_test_read_file(sources[s], &n);
        if (bytes == NULL || n < 16) {
            MR_CHECK(0);
            free(bytes);
            continue;
        }
        int loaded = 0, failed = 0, unnamed = 0;
        for (int it = 0; it < 150; it++) {
            unsigned char *c = malloc((size_t)n);
            memcpy(c, bytes, (size_t)n);
            long len = n;
            seed = seed * 1103515245u + 12345u;
            if (it % 3 == 0) {
                len = (long)((seed >> 8) % (unsigned)n);
            } else {
                for (int k = 0; k < 1 + it % 4; k++) {
                    seed = seed * 1103515245u + 12345u;
                    /* mostly the JSON (the first few kB), sometimes anywhere */
                    long at = (long)((seed >> 8) % (unsigned)(k == 0 && n > 4096 ? 4096 : n));
                    c[at] = (unsigned char)(seed >> 3);
                }
            }
            MR_CHECK(mr_test_write_file(mutants[s], c, (size_t)len));
            free(c);
            mr_gltf *m = NULL;
            if (mr_gltf_load(mutants[s], &m) == MR_OK) {
                loaded++;
                mr_gltf_triangles *t = NULL; /* geometry from a mangled asset: triangles or an error */
                mr_status ts = mr_gltf_get_triangles(m, -1, &t);
                MR_CHECK(ts == MR_OK ? t != NULL : t == NULL);
                mr_gltf_triangles_free(t);
                mr_gltf_free(m);
            } else {
                failed++;
                if (strstr(mr_last_error(), mutants[s]) == NULL) {
                    if (unnamed++ == 0) fprintf(stderr, "    message without the file: %s\n", mr_last_error());
                }
            }
        }
        MR_CHECK_MSG(unnamed == 0 && failed > 0, "%s: %d loaded, %d failed, %d messages without the file",
                     sources[s], loaded, failed, unnamed);
        free(bytes);
    }
}

/* A failed save leaves nothing behind, and never writes over the asset's own files. */
MR_TEST(no_partial_output_no_input_overwrite) {
    MR_CHECK(mkdir(mr_test_tmp_path("duck"), 0777) == 0);
    const char *dir = asset_path("specgloss/Duck-pbrSpecularGlossiness/glTF-pbrSpecularGlossiness");
    const char *names[] = {"Duck.gltf", "Duck0.bin", "DuckCM.png"};
    for (int i = 0; i < 3; i++) {
        char from[1200], to[600];
        snprintf(from, sizeof from, "%s/%s", dir, names[i]);
        snprintf(to, sizeof to, "%s", mr_test_tmp_path("duck"));
        strncat(to, "/", sizeof to - strlen(to) - 1);
        strncat(to, names[i], sizeof to - strlen(to) - 1);
        MR_CHECK(copy_file(from, to));
    }
    mr_gltf *g = NULL;
    MR_CHECK_OK(mr_gltf_load(mr_test_tmp_path("duck/Duck.gltf"), &g));
    if (g == NULL) return;
    /* The output's name is taken by a directory: the rename fails, the side files written go again. */
    MR_CHECK(mkdir(mr_test_tmp_path("blocked"), 0777) == 0);
    MR_CHECK(mkdir(mr_test_tmp_path("blocked/out.gltf"), 0777) == 0);
    MR_CHECK(mr_gltf_save(g, mr_test_tmp_path("blocked/out.gltf")) == MR_ERR_IO);
    MR_CHECK_MSG(strstr(mr_last_error(), "out.gltf") != NULL, "%s", mr_last_error());
    MR_CHECK(count_entries(mr_test_tmp_path("blocked")) == 1);

    /* Beside the input: the unchanged .bin and .png are the inputs' own, left in place. */
    long bin_before = file_size(mr_test_tmp_path("duck/Duck0.bin"));
    MR_CHECK_OK(mr_gltf_save(g, mr_test_tmp_path("duck/Duck_copy.gltf")));
    MR_CHECK(count_entries(mr_test_tmp_path("duck")) == 4);
    MR_CHECK(file_size(mr_test_tmp_path("duck/Duck0.bin")) == bin_before);
    mr_gltf *b = NULL;
    MR_CHECK_OK(mr_gltf_load(mr_test_tmp_path("duck/Duck_copy.gltf"), &b));
    if (b != NULL) check_same_asset(g, b, "Duck beside itself");
    mr_gltf_free(b);
    /* A .glb beside it holds its buffer and image: one more file. */
    MR_CHECK_OK(mr_gltf_save(g, mr_test_tmp_path("duck/Duck_copy.glb")));
    MR_CHECK(count_entries(mr_test_tmp_path("duck")) == 5);
    mr_gltf_free(g);
}

/* ---- pruning ------------------------------------------------------------------------------------------- */

/* A 1x1 PNG (never decoded: the shim keeps the bytes). */
static const unsigned char PNG_1X1[] = {
    0x89, 'P', 'N', 'G', 0x0d, 0x0a, 0x1a, 0x0a, 0, 0, 0, 0x0d, 'I', 'H', 'D', 'R', 0, 0, 0, 1, 0, 0, 0, 1, 8,
    2, 0, 0, 0, 0x90, 0x77, 0x53, 0xde, 0, 0, 0, 0x0c, 'I', 'D', 'A', 'T', 0x78, 0x9c, 0x63, 0xf8, 0xcf, 0xc0,
    0, 0, 0x03, 0x01, 0x01, 0x00, 0xc9, 0xfe, 0x92, 0xef, 0, 0, 0, 0, 'I', 'E', 'N', 'D', 0xae, 0x42, 0x60,
    0x82};

/* The image URI of texture t ("" when it has none or on error). */
static const char *texture_uri(const mr_gltf *g, int t) {
    mr_gltf_texture tex;
    mr_gltf_image im;
    if (mr_gltf_get_texture(g, t, &tex) != MR_OK || tex.image < 0 || mr_gltf_get_image(g, tex.image, &im) != MR_OK)
        return "";
    return im.uri;
}

/* The file's text without whitespace (NULL if unreadable; caller frees), to look for compact JSON. */
static char *squeezed_text(const char *path) {
    size_t size;
    char *text = mr_test_read_file(path, &size);
    if (text == NULL) return NULL;
    size_t n = 0;
    for (size_t i = 0; i < size; i++)
        if (text[i] != ' ' && text[i] != '\n' && text[i] != '\t' && text[i] != '\r') text[n++] = text[i];
    char *out = realloc(text, (size_t)n + 1);
    if (out == NULL) {
        free(text);
        return NULL;
    }
    out[n] = '\0';
    return out;
}

/* Write `json` to the test folder's `name`, load it and prune it into *st; the asset, or NULL after a failed
 * check. */
static mr_gltf *load_and_prune(const char *name, const char *json, mr_gltf_prune_stats *st) {
    const char *in = mr_test_tmp_path(name);
    MR_CHECK(mr_test_write_file(in, json, strlen(json)));
    mr_gltf *g = NULL;
    MR_CHECK_OK(mr_gltf_load(in, &g));
    if (g != NULL) MR_CHECK_OK(mr_gltf_prune_unused(g, st));
    return g;
}

/* A hand-made asset with every kind of reference mr_gltf_prune_unused knows, and known answers. Images
 * a..f.png, samplers s0..s3 (told apart by their filters), textures:
 *   t0 a s0   referenced by nothing, but below an uncertain reference: kept
 *   t1 b      an uncertain reference (material extras "myThing": {"index": 1}): kept
 *   t2 f s1   referenced by nothing: removed, and with it f.png and s1
 *   t3 d s2   normalTexture
 *   t4 c s3   clearcoatTexture of an extension the shim does not know; KHR_texture_basisu source e.png
 *   t5 d      referenced by nothing: removed (d.png stays, t3 uses it)
 *   t6 e      a KHR_animation_pointer-style "pointer" in a node extension
 *   t7 a      a material property outside the schema ("customTexture", kept only in the file's JSON)
 * After pruning: t0 t1 t3 t4 t6 t7 -> 0..5; images a b c d e -> 0..4; samplers s0 s2 s3 -> 0..2. */
MR_TEST(prune_unused_hand_made) {
    mkdir(mr_test_tmp_path("prune_in"), 0777);
    mkdir(mr_test_tmp_path("prune_out"), 0777);
    const char *names[] = {"a", "b", "c", "d", "e", "f"};
    for (int i = 0; i < 6; i++) {
        char rel[64];
        snprintf(rel, sizeof rel, "prune_in/%s.png", names[i]);
        MR_CHECK(mr_test_write_file(mr_test_tmp_path(rel), PNG_1X1, sizeof PNG_1X1));
    }
    const char *json =
        "{\"asset\":{\"version\":\"2.0\"},"
        "\"images\":[{\"uri\":\"a.png\"},{\"uri\":\"f.png\"},{\"uri\":\"b.png\"},{\"uri\":\"c.png\"},"
        "{\"uri\":\"d.png\"},{\"uri\":\"e.png\"}],"
        "\"samplers\":[{\"magFilter\":9728},{\"magFilter\":9729},{\"minFilter\":9728},{\"minFilter\":9729}],"
        "\"textures\":[{\"source\":0,\"sampler\":0},{\"source\":2},{\"source\":1,\"sampler\":1},"
        "{\"source\":4,\"sampler\":2},"
        "{\"source\":3,\"sampler\":3,\"extensions\":{\"KHR_texture_basisu\":{\"source\":5}}},"
        "{\"source\":4},{\"source\":5},{\"source\":0}],"
        "\"materials\":[{\"name\":\"m\",\"normalTexture\":{\"index\":3},"
        "\"extensions\":{\"KHR_materials_clearcoat\":{\"clearcoatFactor\":1,\"clearcoatTexture\":{\"index\":4}}},"
        "\"extras\":{\"myThing\":{\"index\":1}},\"customTexture\":{\"index\":7}}],"
        "\"nodes\":[{\"name\":\"n\",\"extensions\":{\"EXT_test_pointer\":{\"pointer\":\"/textures/6/extras/x\"}}}],"
        "\"scenes\":[{\"nodes\":[0]}],\"scene\":0,"
        "\"extensionsUsed\":[\"KHR_materials_clearcoat\",\"KHR_texture_basisu\",\"EXT_test_pointer\"]}\n";
    mr_gltf_prune_stats st;
    mr_gltf *g = load_and_prune("prune_in/in.gltf", json, &st);
    if (g == NULL) return;
    MR_CHECK_MSG(st.textures == 2 && st.images == 1 && st.samplers == 1 && st.uncertain == 2,
                 "removed %d textures, %d images, %d samplers; %d uncertain", st.textures, st.images, st.samplers,
                 st.uncertain);
    mr_gltf_counts c;
    mr_gltf_get_counts(g, &c);
    MR_CHECK(c.textures == 6 && c.images == 5 && c.samplers == 3);
    static const char *const uris[6] = {"a.png", "b.png", "d.png", "c.png", "e.png", "a.png"};
    for (int t = 0; t < 6 && t < c.textures; t++)
        MR_CHECK_MSG(strcmp(texture_uri(g, t), uris[t]) == 0, "texture %d: '%s', expected '%s'", t,
                     texture_uri(g, t), uris[t]);
    /* Samplers renumbered with their textures: s0, s2 (min NEAREST), s3 (min LINEAR). */
    mr_gltf_texture tex;
    MR_CHECK_OK(mr_gltf_get_texture(g, 0, &tex));
    MR_CHECK(tex.sampler == 0 && tex.params.mag_filter == MR_GLTF_FILTER_NEAREST);
    MR_CHECK_OK(mr_gltf_get_texture(g, 2, &tex));
    MR_CHECK(tex.sampler == 1 && tex.params.min_filter == MR_GLTF_FILTER_NEAREST);
    MR_CHECK_OK(mr_gltf_get_texture(g, 3, &tex));
    MR_CHECK(tex.sampler == 2 && tex.params.min_filter == MR_GLTF_FILTER_LINEAR);
    MR_CHECK_OK(mr_gltf_get_texture(g, 1, &tex));
    MR_CHECK(tex.sampler == -1);
    mr_gltf_material m;
    MR_CHECK_OK(mr_gltf_get_material(g, 0, &m));
    MR_CHECK(m.normal_texture.index == 2);

    /* Nothing is left to remove. */
    mr_gltf_prune_stats again;
    MR_CHECK_OK(mr_gltf_prune_unused(g, &again));
    MR_CHECK(again.textures == 0 && again.images == 0 && again.samplers == 0);

    /* Saved: the references inside the JSON trees renumbered, f.png not written. */
    const char *out = mr_test_tmp_path("prune_out/out.gltf");
    MR_CHECK_OK(mr_gltf_save(g, out));
    mr_gltf_free(g);
    char *text = squeezed_text(out);
    MR_CHECK(text != NULL);
    if (text != NULL) {
        const char *expect[] = {"\"clearcoatTexture\":{\"index\":3}", "\"KHR_texture_basisu\":{\"source\":4}",
                                "\"pointer\":\"/textures/4/extras/x\"", "\"customTexture\":{\"index\":5}",
                                "\"myThing\":{\"index\":1}", "\"normalTexture\":{\"index\":2}"};
        for (size_t i = 0; i < sizeof expect / sizeof expect[0]; i++)
            MR_CHECK_MSG(strstr(text, expect[i]) != NULL, "%s not in %s", expect[i], text);
        free(text);
    }
    MR_CHECK(!file_exists(mr_test_tmp_path("prune_out/f.png")));
    MR_CHECK(file_exists(mr_test_tmp_path("prune_out/a.png")) && file_exists(mr_test_tmp_path("prune_out/e.png")));
    MR_CHECK(count_entries(mr_test_tmp_path("prune_out")) == 6);
    g = NULL;
    MR_CHECK_OK(mr_gltf_load(out, &g));
    if (g != NULL) {
        mr_gltf_get_counts(g, &c);
        MR_CHECK(c.textures == 6 && c.images == 5 && c.samplers == 3);
        for (int t = 0; t < 6 && t < c.textures; t++) MR_CHECK(strcmp(texture_uri(g, t), uris[t]) == 0);
    }
    mr_gltf_free(g);
    MR_CHECK(mr_gltf_prune_unused(NULL, &st) == MR_ERR_INVALID_ARG && st.textures == 0);
}

/* An uncertain image reference (EXT_lights_image_based's specularImages) pins the images at and below it;
 * an unused texture above it still goes. */
MR_TEST(prune_unused_uncertain_images) {
    mkdir(mr_test_tmp_path("ibl"), 0777);
    const char *names[] = {"ibl/p.png", "ibl/q.png", "ibl/r.png"};
    for (int i = 0; i < 3; i++) MR_CHECK(mr_test_write_file(mr_test_tmp_path(names[i]), PNG_1X1, sizeof PNG_1X1));
    const char *json =
        "{\"asset\":{\"version\":\"2.0\"},\"images\":[{\"uri\":\"p.png\"},{\"uri\":\"q.png\"},{\"uri\":\"r.png\"}],"
        "\"textures\":[{\"source\":2},{\"source\":0}],\"materials\":[{\"emissiveTexture\":{\"index\":0}}],"
        "\"extensions\":{\"EXT_lights_image_based\":{\"lights\":[{\"specularImages\":[[1,1,1,1,1,1]]}]}},"
        "\"extensionsUsed\":[\"EXT_lights_image_based\"]}\n";
    mr_gltf_prune_stats st;
    mr_gltf *g = load_and_prune("ibl/ibl.gltf", json, &st);
    if (g == NULL) return;
    /* t1 (p.png) goes; p.png is below the light's image 1, so it stays with q.png; r.png is t0's. */
    MR_CHECK_MSG(st.textures == 1 && st.images == 0 && st.uncertain == 2, "%d textures, %d images, %d uncertain",
                 st.textures, st.images, st.uncertain);
    mr_gltf_counts c;
    mr_gltf_get_counts(g, &c);
    MR_CHECK(c.textures == 1 && c.images == 3 && strcmp(texture_uri(g, 0), "r.png") == 0);
    mr_gltf_free(g);
}

/* The conversions' case on a real asset: Avocado without its core textures keeps the spec-gloss ones, renumbered
 * inside the extension; without the extension, the spec-gloss textures go. */
MR_TEST(prune_unused_avocado) {
    for (int drop_sg = 0; drop_sg < 2; drop_sg++) {
        mr_gltf *g = load_asset("Avocado");
        if (g == NULL) return;
        mr_gltf_material m;
        MR_CHECK_OK(mr_gltf_get_material(g, 0, &m));
        if (drop_sg) {
            m.has_spec_gloss = 0;
        } else {
            mr_gltf_texture_ref_none(&m.base_color_texture);
            mr_gltf_texture_ref_none(&m.metallic_roughness_texture);
        }
        MR_CHECK_OK(mr_gltf_set_material(g, 0, &m));
        mr_gltf_prune_stats st;
        MR_CHECK_OK(mr_gltf_prune_unused(g, &st));
        MR_CHECK(st.textures == 2 && st.images == 2 && st.samplers == 0 && st.uncertain == 0);
        MR_CHECK_OK(mr_gltf_get_material(g, 0, &m));
        if (drop_sg) {
            MR_CHECK(m.base_color_texture.index == 0 && m.metallic_roughness_texture.index == 1);
            MR_CHECK(strcmp(texture_uri(g, 0), "Avocado_baseColor.png") == 0);
            MR_CHECK(strcmp(texture_uri(g, 1), "Avocado_roughnessMetallic.png") == 0);
        } else {
            MR_CHECK(m.normal_texture.index == 0 && m.diffuse_texture.index == 1 &&
                     m.specular_glossiness_texture.index == 2);
            MR_CHECK(strcmp(texture_uri(g, 1), "Avocado_diffuse.png") == 0);
            MR_CHECK(strcmp(texture_uri(g, 2), "Avocado_specularGlossiness.png") == 0);
        }
        MR_CHECK(strcmp(texture_uri(g, m.normal_texture.index), "Avocado_normal.png") == 0);
        mr_gltf_free(g);
    }
}

MR_TEST_MAIN(MR_TEST_ENTRY(every_asset_loads), MR_TEST_ENTRY(floppy_disk_spec_gloss_factors),
             MR_TEST_ENTRY(avocado_carries_both_workflows), MR_TEST_ENTRY(water_bottle_packed_orm),
             MR_TEST_ENTRY(texture_settings_samplers), MR_TEST_ENTRY(duck_and_truck),
             MR_TEST_ENTRY(round_trip_every_asset), MR_TEST_ENTRY(round_trip_file_from_env),
             MR_TEST_ENTRY(glb_embedded_resources), MR_TEST_ENTRY(data_uri_resources),
             MR_TEST_ENTRY(embedded_images_decode_from_memory),
             MR_TEST_ENTRY(drop_spec_gloss_set_metal_rough_add_texture), MR_TEST_ENTRY(bad_inputs),
             MR_TEST_ENTRY(hostile_inputs), MR_TEST_ENTRY(mutated_inputs_fail_cleanly),
             MR_TEST_ENTRY(no_partial_output_no_input_overwrite), MR_TEST_ENTRY(prune_unused_hand_made),
             MR_TEST_ENTRY(prune_unused_uncertain_images), MR_TEST_ENTRY(prune_unused_avocado))
