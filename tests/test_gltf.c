/*
 * test_gltf.c — the glTF shim (contract in gltf/mr_gltf.h): every asset of ../shared/assets loads, with known
 * answers read from each; read -> write -> read keeps every material field, the images' bytes and the counts of
 * everything else, as .gltf and as .glb; data-URI and GLB-embedded resources; material edits (drop SG, set MR
 * factors, add a texture, KHR_materials_specular/ior, texture transforms) read back; bad inputs fail with a
 * message naming the file and leave no output. Every case works in a private mkdtemp() directory.
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

#include "harness.h"

static char test_dir[256];

static void remove_test_dir(void) {
    if (test_dir[0] == '\0') return;
    char cmd[512];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", test_dir);
    if (system(cmd) != 0) fprintf(stderr, "could not remove %s\n", test_dir);
}

static const char *tmp_path(const char *name) {
    static char paths[32][512];
    static int slot;
    if (test_dir[0] == '\0') {
        strcpy(test_dir, "/tmp/mr_test_gltf.XXXXXX");
        if (mkdtemp(test_dir) == NULL) {
            perror("mkdtemp");
            exit(2);
        }
        atexit(remove_test_dir);
    }
    char *p = paths[slot++ % 32];
    snprintf(p, 512, "%s/%s", test_dir, name);
    return p;
}

static const char *asset_path(const char *rel) {
    static char paths[8][1024];
    static int slot;
    const char *shared = getenv("MR_SHARED");
    char *p = paths[slot++ % 8];
    snprintf(p, 1024, "%s/assets/%s", shared ? shared : "../shared", rel);
    return p;
}

static int file_exists(const char *path) {
    struct stat st;
    return stat(path, &st) == 0;
}

static long file_size(const char *path) {
    struct stat st;
    return stat(path, &st) == 0 ? (long)st.st_size : -1;
}

static unsigned char *slurp(const char *path, long *size) {
    FILE *f = fopen(path, "rb");
    if (f == NULL) return NULL;
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    unsigned char *buf = malloc(n > 0 ? (size_t)n : 1);
    if (buf != NULL && fread(buf, 1, (size_t)n, f) != (size_t)n) {
        free(buf);
        buf = NULL;
    }
    fclose(f);
    *size = n;
    return buf;
}

static int write_bytes(const char *path, const void *bytes, size_t n) {
    FILE *f = fopen(path, "wb");
    if (f == NULL) return 0;
    int ok = fwrite(bytes, 1, n, f) == n;
    return fclose(f) == 0 && ok;
}

static int copy_file(const char *from, const char *to) {
    long n;
    unsigned char *b = slurp(from, &n);
    if (b == NULL) return 0;
    int ok = write_bytes(to, b, (size_t)n);
    free(b);
    return ok;
}

/* Number of directory entries (not . and ..). */
static int count_entries(const char *dir) {
    DIR *d = opendir(dir);
    if (d == NULL) return -1;
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d)) != NULL)
        if (strcmp(e->d_name, ".") != 0 && strcmp(e->d_name, "..") != 0) n++;
    closedir(d);
    return n;
}

static const struct {
    const char *name;
    const char *rel;
} ASSETS[] = {
    {"Avocado", "specgloss/Avocado-pbrSpecularGlossiness/glTF-pbrSpecularGlossiness/Avocado.gltf"},
    {"CesiumMilkTruck", "specgloss/CesiumMilkTruck-pbrSpecularGlossiness/glTF-pbrSpecularGlossiness/"
                        "CesiumMilkTruck.gltf"},
    {"Duck", "specgloss/Duck-pbrSpecularGlossiness/glTF-pbrSpecularGlossiness/Duck.gltf"},
    {"FloppyDisk", "specgloss/FloppyDisk-sketchfab/scene.gltf"},
    {"TextureSettingsTest", "metalrough/TextureSettingsTest/glTF/TextureSettingsTest.gltf"},
    {"WaterBottle", "metalrough/WaterBottle/glTF/WaterBottle.gltf"},
};
#define ASSET_COUNT ((int)(sizeof ASSETS / sizeof ASSETS[0]))

static mr_gltf *load_asset(const char *name) {
    for (int i = 0; i < ASSET_COUNT; i++) {
        if (strcmp(ASSETS[i].name, name) != 0) continue;
        mr_gltf *g = NULL;
        MR_CHECK_OK(mr_gltf_load(asset_path(ASSETS[i].rel), &g));
        return g;
    }
    return NULL;
}

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
    MR_CHECK(t.image == 1 && t.sampler == 0 && t.params.mag_filter == 9729 && t.params.min_filter == 9987);
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
    MR_CHECK(t.image == 4 && t.sampler == -1 && t.params.wrap_s == 10497 && t.params.min_filter == -1);
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
    const int wraps[][3] = {{0, 10497, 33648}, {1, 33648, 10497}, {2, 33071, 10497}, {3, 10497, 33071},
                            {6, 10497, 10497}};
    for (int i = 0; i < 5; i++) {
        mr_gltf_texture t;
        MR_CHECK_OK(mr_gltf_get_texture(g, wraps[i][0], &t));
        MR_CHECK_MSG(t.params.wrap_s == wraps[i][1] && t.params.wrap_t == wraps[i][2] &&
                         t.params.mag_filter == 9729 && t.params.min_filter == 9986,
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
            else snprintf(dir, sizeof dir, "%s", tmp_path(ASSETS[i].name));
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
    const char *in = tmp_path("embedded.glb");
    MR_CHECK(write_bytes(in, glb, total));
    mr_gltf *g = NULL;
    MR_CHECK_OK(mr_gltf_load(in, &g));
    if (g != NULL) {
        mr_gltf_image e;
        MR_CHECK_OK(mr_gltf_get_image(g, 0, &e));
        MR_CHECK(e.buffer_view == 0 && e.size == im.size && memcmp(e.bytes, im.bytes, im.size) == 0);
        MR_CHECK(strcmp(e.mime_type, "image/png") == 0 && e.path[0] == '\0');
        const char *outs[] = {"embedded_out.glb", "embedded_out.gltf"};
        for (int f = 0; f < 2; f++) {
            MR_CHECK_OK(mr_gltf_save(g, tmp_path(outs[f])));
            mr_gltf *b = NULL;
            MR_CHECK_OK(mr_gltf_load(tmp_path(outs[f]), &b));
            if (b != NULL) check_same_asset_as(g, b, outs[f], f == 0);
            mr_gltf_free(b);
        }
        /* A .glb of a .gltf with external files holds them all: nothing beside it. */
        MR_CHECK(mkdir(tmp_path("packed"), 0777) == 0);
        mr_gltf *floppy = load_asset("FloppyDisk");
        if (floppy != NULL) {
            MR_CHECK_OK(mr_gltf_save(floppy, tmp_path("packed/floppy.glb")));
            MR_CHECK(count_entries(tmp_path("packed")) == 1);
            mr_gltf *b = NULL;
            MR_CHECK_OK(mr_gltf_load(tmp_path("packed/floppy.glb"), &b));
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
        MR_CHECK(file_size(tmp_path("embedded_out.bin")) == (long)bin);
        /* Decoding goes through a file: the image's bytes written out. */
        MR_CHECK_OK(mr_gltf_image_write_file(g, 0, tmp_path("embedded_image.png")));
        MR_CHECK(file_size(tmp_path("embedded_image.png")) == (long)im.size);
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
    const char *in = tmp_path("datauri.gltf");
    MR_CHECK(write_bytes(in, json, strlen(json)));
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
    MR_CHECK(t.params.wrap_s == 33071 && t.params.wrap_t == 10497);
    const char *out = tmp_path("datauri_out.gltf");
    MR_CHECK_OK(mr_gltf_save(g, out));
    long size;
    char *text = (char *)slurp(out, &size);
    if (text != NULL) {
        text = realloc(text, (size_t)size + 1);
        text[size] = '\0';
        MR_CHECK(strstr(text, "data:application/octet-stream;base64,AACAPwAAAEAAAEBA") != NULL);
        MR_CHECK(strstr(text, png) != NULL && strstr(text, "data:image/png;base64,") != NULL);
        MR_CHECK(strstr(text, "\"keep\": \"me\"") != NULL && strstr(text, "\"id\": 7") != NULL);
        free(text);
    }
    /* Only the .gltf itself (and the input) in the directory: no side files for data URIs. */
    MR_CHECK(!file_exists(tmp_path("datauri_out.bin")));
    mr_gltf *b = NULL;
    MR_CHECK_OK(mr_gltf_load(out, &b));
    if (b != NULL) check_same_asset(g, b, "data URIs");
    mr_gltf_free(b);
    mr_gltf_free(g);
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
    mr_gltf_sampler clamp = {9729, 9729, 33071, 33071};
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

    MR_CHECK(mkdir(tmp_path("edit"), 0777) == 0);
    const char *out = tmp_path("edit/floppy.gltf");
    MR_CHECK_OK(mr_gltf_save(g, out));
    /* extensionsUsed/Required follow the materials. */
    MR_CHECK(!mr_gltf_extension_used(g, "KHR_materials_pbrSpecularGlossiness"));
    MR_CHECK(!mr_gltf_extension_required(g, "KHR_materials_pbrSpecularGlossiness"));
    MR_CHECK(mr_gltf_extension_used(g, "KHR_materials_specular") && mr_gltf_extension_used(g, "KHR_materials_ior"));
    MR_CHECK(mr_gltf_extension_used(g, "KHR_texture_transform"));
    MR_CHECK(file_size(tmp_path("edit/maps/base color.png")) == (long)diffuse.size);
    MR_CHECK(file_exists(tmp_path("edit/textures/material_0_normal.png")));
    MR_CHECK(file_exists(tmp_path("edit/scene.bin")));
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
    MR_CHECK(mr_gltf_add_image_file(g, tmp_path("missing.png"), "x.png", &image) == MR_ERR_IO);
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
    expect_load_error(tmp_path("missing.gltf"), MR_ERR_IO, NULL);
    const char *bad_json = tmp_path("bad.gltf");
    MR_CHECK(write_bytes(bad_json, "{\"asset\": {\"version\": \"2.0\"}, \"nodes\": [", 40));
    expect_load_error(bad_json, MR_ERR_FORMAT, NULL);
    const char *empty = tmp_path("empty.gltf");
    MR_CHECK(write_bytes(empty, "", 0));
    expect_load_error(empty, MR_ERR_FORMAT, NULL);
    expect_load_error(test_dir, MR_ERR_IO, "directory");

    /* A buffer URI that does not exist. */
    const char *nobuf = tmp_path("nobuf.gltf");
    const char *j = "{\"asset\":{\"version\":\"2.0\"},\"buffers\":[{\"byteLength\":12,\"uri\":\"gone.bin\"}]}";
    MR_CHECK(write_bytes(nobuf, j, strlen(j)));
    expect_load_error(nobuf, MR_ERR_IO, "gone.bin");
    /* An image file that does not exist. */
    const char *noimg = tmp_path("noimg.gltf");
    j = "{\"asset\":{\"version\":\"2.0\"},\"images\":[{\"uri\":\"gone.png\"}]}";
    MR_CHECK(write_bytes(noimg, j, strlen(j)));
    expect_load_error(noimg, MR_ERR_IO, "gone.png");

    /* Truncated .glb: a valid one cut in half, then cut inside its header. */
    mr_gltf *g = load_asset("Duck");
    if (g == NULL) return;
    const char *glb = tmp_path("duck.glb");
    MR_CHECK_OK(mr_gltf_save(g, glb));
    long size;
    unsigned char *bytes = slurp(glb, &size);
    if (bytes != NULL) {
        const char *cut = tmp_path("cut.glb");
        MR_CHECK(write_bytes(cut, bytes, (size_t)size / 2));
        expect_load_error(cut, MR_ERR_FORMAT, NULL);
        MR_CHECK(write_bytes(cut, bytes, 10));
        expect_load_error(cut, MR_ERR_FORMAT, NULL);
        free(bytes);
    }

    /* Saving: unknown extension, over the input, into a missing directory. */
    MR_CHECK(mr_gltf_save(g, tmp_path("x.obj")) == MR_ERR_INVALID_ARG);
    MR_CHECK(mr_gltf_save(g, mr_gltf_path(g)) == MR_ERR_INVALID_ARG);
    MR_CHECK(strstr(mr_last_error(), "read from") != NULL);
    MR_CHECK(mr_gltf_save(g, tmp_path("no/such/dir/x.gltf")) == MR_ERR_IO);
    MR_CHECK(!file_exists(tmp_path("no")));
    mr_gltf_free(g);
}

/* Truncated and byte-flipped copies of a .glb and a .gltf: each load succeeds or fails with a message naming the
 * file; none crashes (make asan runs this under AddressSanitizer). Fixed seed. */
MR_TEST(mutated_inputs_fail_cleanly) {
    mr_gltf *g = load_asset("Duck");
    if (g == NULL) return;
    const char *sources[] = {tmp_path("fuzz_src.glb"), tmp_path("fuzz_src.gltf")};
    const char *mutants[] = {tmp_path("fuzz.glb"), tmp_path("fuzz.gltf")};
    MR_CHECK_OK(mr_gltf_save(g, sources[0]));
    MR_CHECK(mkdir(tmp_path("fuzzdir"), 0777) == 0);
    MR_CHECK_OK(mr_gltf_save(g, tmp_path("fuzzdir/Duck.gltf")));
    MR_CHECK(copy_file(tmp_path("fuzzdir/Duck.gltf"), sources[1]));
    MR_CHECK(copy_file(tmp_path("fuzzdir/Duck0.bin"), tmp_path("Duck0.bin")));
    MR_CHECK(copy_file(tmp_path("fuzzdir/DuckCM.png"), tmp_path("DuckCM.png")));
    mr_gltf_free(g);
    unsigned seed = 12345;
    for (int s = 0; s < 2; s++) {
        long n;
        unsigned char *bytes = slurp(sources[s], &n);
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
            MR_CHECK(write_bytes(mutants[s], c, (size_t)len));
            free(c);
            mr_gltf *m = NULL;
            if (mr_gltf_load(mutants[s], &m) == MR_OK) {
                loaded++;
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
    MR_CHECK(mkdir(tmp_path("duck"), 0777) == 0);
    const char *dir = asset_path("specgloss/Duck-pbrSpecularGlossiness/glTF-pbrSpecularGlossiness");
    const char *names[] = {"Duck.gltf", "Duck0.bin", "DuckCM.png"};
    for (int i = 0; i < 3; i++) {
        char from[1200], to[600];
        snprintf(from, sizeof from, "%s/%s", dir, names[i]);
        snprintf(to, sizeof to, "%s", tmp_path("duck"));
        strncat(to, "/", sizeof to - strlen(to) - 1);
        strncat(to, names[i], sizeof to - strlen(to) - 1);
        MR_CHECK(copy_file(from, to));
    }
    mr_gltf *g = NULL;
    MR_CHECK_OK(mr_gltf_load(tmp_path("duck/Duck.gltf"), &g));
    if (g == NULL) return;
    /* The output's name is taken by a directory: the rename fails, the side files written go again. */
    MR_CHECK(mkdir(tmp_path("blocked"), 0777) == 0);
    MR_CHECK(mkdir(tmp_path("blocked/out.gltf"), 0777) == 0);
    MR_CHECK(mr_gltf_save(g, tmp_path("blocked/out.gltf")) == MR_ERR_IO);
    MR_CHECK_MSG(strstr(mr_last_error(), "out.gltf") != NULL, "%s", mr_last_error());
    MR_CHECK(count_entries(tmp_path("blocked")) == 1);

    /* Beside the input: the unchanged .bin and .png are the inputs' own, left in place. */
    long bin_before = file_size(tmp_path("duck/Duck0.bin"));
    MR_CHECK_OK(mr_gltf_save(g, tmp_path("duck/Duck_copy.gltf")));
    MR_CHECK(count_entries(tmp_path("duck")) == 4);
    MR_CHECK(file_size(tmp_path("duck/Duck0.bin")) == bin_before);
    mr_gltf *b = NULL;
    MR_CHECK_OK(mr_gltf_load(tmp_path("duck/Duck_copy.gltf"), &b));
    if (b != NULL) check_same_asset(g, b, "Duck beside itself");
    mr_gltf_free(b);
    /* A .glb beside it holds its buffer and image: one more file. */
    MR_CHECK_OK(mr_gltf_save(g, tmp_path("duck/Duck_copy.glb")));
    MR_CHECK(count_entries(tmp_path("duck")) == 5);
    mr_gltf_free(g);
}

MR_TEST_MAIN(MR_TEST_ENTRY(every_asset_loads), MR_TEST_ENTRY(floppy_disk_spec_gloss_factors),
             MR_TEST_ENTRY(avocado_carries_both_workflows), MR_TEST_ENTRY(water_bottle_packed_orm),
             MR_TEST_ENTRY(texture_settings_samplers), MR_TEST_ENTRY(duck_and_truck),
             MR_TEST_ENTRY(round_trip_every_asset), MR_TEST_ENTRY(round_trip_file_from_env),
             MR_TEST_ENTRY(glb_embedded_resources),
             MR_TEST_ENTRY(data_uri_resources), MR_TEST_ENTRY(drop_spec_gloss_set_metal_rough_add_texture),
             MR_TEST_ENTRY(bad_inputs), MR_TEST_ENTRY(mutated_inputs_fail_cleanly),
             MR_TEST_ENTRY(no_partial_output_no_input_overwrite))
