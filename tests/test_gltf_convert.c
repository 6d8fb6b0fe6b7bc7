/*
 * test_gltf_convert.c — glTF asset conversion in the library (gltf/mr_gltf_convert.h): the new textures hold what
 * the workflow converters give texel by texel, materials with the same sources share one conversion, the extension
 * route reuses textures and turns a uniform result into factors, and bad options are refused.
 */
#include <stdint.h>
#include <sys/stat.h>
#include <unistd.h>

#include "harness.h"
#include "io/io_internal.h"
#include "matremap.h"

#define DUCK "specgloss/Duck-pbrSpecularGlossiness/glTF-pbrSpecularGlossiness/Duck.gltf"
#define FLOPPY "specgloss/FloppyDisk-sketchfab/scene.gltf"
#define TRUCK "specgloss/CesiumMilkTruck-pbrSpecularGlossiness/glTF-pbrSpecularGlossiness/CesiumMilkTruck.gltf"

static mr_transform *make_transform(const char *source, const char *target, const char *name) {
    mr_transform *t = NULL;
    const mr_transform_kind *kind = mr_transform_find(source, target, name);
    MR_CHECK(kind != NULL && mr_transform_create(kind, NULL, &t) == MR_OK);
    return t;
}

/* Asset `rel` (one spec-gloss material, textures of one size) through `weighted`: the new base colour and
 * metallic-roughness textures hold exactly the 8-bit codes of mr_wf_spec_to_metal_batch's answers texel by texel
 * (inputs decoded to floats by the image reader, factors applied as glTF says), as the image writer stores them.
 * Whichever route the conversion took (palette, 8-bit codes, floats) must give these. */
static void check_codes_against_the_batch(const char *rel, int size) {
    mr_gltf *asset = NULL;
    mr_transform *t = make_transform("gltf-specgloss", "gltf", "weighted");
    MR_CHECK(mr_gltf_load(mr_test_asset_path(rel), &asset) == MR_OK);
    if (asset == NULL || t == NULL) return;
    mr_gltf_material before, after;
    MR_CHECK(mr_gltf_get_material(asset, 0, &before) == MR_OK);
    mr_image *tex[2] = {NULL, NULL}, *base = NULL, *mr = NULL;
    mr_img_stored stored[2];
    const mr_gltf_texture_ref *refs[2] = {&before.diffuse_texture, &before.specular_glossiness_texture};
    for (int k = 0; k < 2; k++)
        if (refs[k]->index >= 0) MR_CHECK(mr_gltf_texture_read(asset, refs[k]->index, NULL, &tex[k], &stored[k]) == 0);
    mr_gltf_convert_options o = {0};
    o.transform = t;
    o.overwrite = 1;
    mr_gltf_material_report report;
    MR_CHECK(mr_gltf_convert(asset, &o, &report) == MR_OK);
    MR_CHECK(report.outcome == MR_GLTF_CONVERTED && report.width == size && report.height == size);
    MR_CHECK(mr_gltf_get_material(asset, 0, &after) == MR_OK);
    MR_CHECK(!after.has_spec_gloss && after.base_color_texture.index >= 0 &&
             after.metallic_roughness_texture.index >= 0);
    mr_img_read_options data = {0};
    data.encoding = MR_IMG_DATA; // the stored codes
    MR_CHECK(mr_gltf_texture_read(asset, after.base_color_texture.index, &data, &base, NULL) == MR_OK);
    MR_CHECK(mr_gltf_texture_read(asset, after.metallic_roughness_texture.index, &data, &mr, NULL) == MR_OK);
    const size_t n = (size_t)size * (size_t)size;
    float *d = malloc(3 * n * sizeof *d), *s = malloc(3 * n * sizeof *s), *r = malloc(n * sizeof *r);
    float *a = malloc(3 * n * sizeof *a), *m = malloc(n * sizeof *m);
    for (size_t i = 0; base != NULL && mr != NULL && i < n; i++) {
        float px[2][4] = {{1, 1, 1, 1}, {1, 1, 1, 1}};
        for (int k = 0; k < 2; k++)
            for (int c = 0; tex[k] != NULL && c < 4; c++)
                px[k][c] = c == 3 ? (tex[k]->channels == 4 ? tex[k]->pixels[4 * i + 3] : 1.0f)
                                  : tex[k]->pixels[i * (size_t)tex[k]->channels + (tex[k]->channels < 3 ? 0 : c)];
        for (int c = 0; c < 3; c++) {
            d[3 * i + c] = (float)(px[0][c] * before.diffuse_factor[c]);
            s[3 * i + c] = (float)(px[1][c] * before.specular_factor[c]);
        }
        r[i] = 1.0f - (float)(px[1][3] * before.glossiness_factor);
    }
    mr_wf_options w = mr_wf_options_default();
    w.spec_diffuse = MR_WF_DIFFUSE_SPECGLOSS;
    if (tex[0] != NULL) w.diffuse_quantisation = mr_wf_quantisation_of(&stored[0], before.diffuse_factor);
    if (tex[1] != NULL) w.specular_quantisation = mr_wf_quantisation_of(&stored[1], before.specular_factor);
    MR_CHECK(mr_wf_spec_to_metal_batch(&(mr_wf_spec_input){d, s, r}, n, &w, &(mr_wf_metal_maps){a, m, r}, NULL) ==
             MR_OK);
    mr_srgb8_init();
    size_t wrong_colour = 0, wrong_data = 0;
    for (size_t i = 0; base != NULL && mr != NULL && i < n; i++) {
        for (int c = 0; c < 3; c++) {
            const long code = lrint(base->pixels[(size_t)base->channels * i + c] * 255.0);
            wrong_colour += code != mr_srgb8_encode(a[3 * i + c]);
        }
        wrong_data += lrint(mr->pixels[3 * i + 2] * 255.0) != (long)floor(fmin(fmax(m[i], 0.0f), 1.0f) * 255.0 + 0.5);
        wrong_data += lrint(mr->pixels[3 * i + 1] * 255.0) != (long)floor(fmin(fmax(r[i], 0.0f), 1.0f) * 255.0 + 0.5);
    }
    MR_CHECK_MSG(wrong_colour == 0, "%s: %zu base colour codes differ", rel, wrong_colour);
    MR_CHECK_MSG(wrong_data == 0, "%s: %zu metallic or roughness codes differ", rel, wrong_data);
    free(d), free(s), free(r), free(a), free(m);
    mr_image_free(tex[0]);
    mr_image_free(tex[1]);
    mr_image_free(base);
    mr_image_free(mr);
    mr_gltf_free(asset);
    mr_transform_free(t);
}

/* The Duck (512²): a paletted diffuse texture beside specular and glossiness factors, converted through its
 * palette. */
MR_TEST(duck_palette_route_gives_the_converters_codes) { check_codes_against_the_batch(DUCK, 512); }

/* The FloppyDisk (2048²): RGB diffuse and RGBA specular-glossiness textures under factors, converted from their
 * 8-bit codes. */
MR_TEST(floppy_code_route_gives_the_converters_codes) { check_codes_against_the_batch(FLOPPY, 2048); }

/* The CesiumMilkTruck: 'truck' and 'wheels' use two textures of one image with the same factors (one conversion,
 * shared textures); 'glass' has factors only. */
MR_TEST(truck_materials_share_a_conversion) {
    mr_gltf *asset = NULL;
    mr_transform *t = make_transform("gltf-specgloss", "gltf", "mean");
    MR_CHECK(mr_gltf_load(mr_test_asset_path(TRUCK), &asset) == MR_OK);
    if (asset == NULL || t == NULL) return;
    mr_gltf_convert_options o = {0};
    o.transform = t;
    o.overwrite = 1;
    mr_gltf_material_report reports[4];
    MR_CHECK(mr_gltf_convert(asset, &o, reports) == MR_OK);
    MR_CHECK(reports[0].outcome == MR_GLTF_CONVERTED && reports[0].width == 2048);
    MR_CHECK(reports[1].outcome == MR_GLTF_CONVERTED && reports[1].width == 0); // glass: factors only
    MR_CHECK(reports[3].outcome == MR_GLTF_SHARED);
    mr_gltf_material truck, glass, wheels;
    MR_CHECK(mr_gltf_get_material(asset, 0, &truck) == MR_OK && mr_gltf_get_material(asset, 1, &glass) == MR_OK &&
             mr_gltf_get_material(asset, 3, &wheels) == MR_OK);
    MR_CHECK(truck.base_color_texture.index >= 0 && truck.base_color_texture.index == wheels.base_color_texture.index);
    MR_CHECK(truck.metallic_roughness_texture.index == wheels.metallic_roughness_texture.index);
    MR_CHECK(glass.base_color_texture.index < 0 && glass.metallic_factor > 0.5); // specular 0.65: a metal
    mr_gltf_free(asset);
    mr_transform_free(t);
}

/* The extension route on the Duck: the diffuse texture becomes the base colour as it is, the specular factor the
 * specular colour, and the roughness, one value everywhere, a factor (no image). */
MR_TEST(extension_route_reuses_textures_and_makes_factors) {
    mr_gltf *asset = NULL;
    mr_transform *t = make_transform("gltf-specgloss", "gltf", "extension");
    MR_CHECK(mr_gltf_load(mr_test_asset_path(DUCK), &asset) == MR_OK);
    if (asset == NULL || t == NULL) return;
    mr_gltf_counts before;
    mr_gltf_get_counts(asset, &before);
    mr_gltf_material m;
    MR_CHECK(mr_gltf_get_material(asset, 0, &m) == MR_OK);
    const int diffuse_texture = m.diffuse_texture.index;
    mr_gltf_convert_options o = {0};
    o.transform = t;
    o.overwrite = 1;
    MR_CHECK(mr_gltf_convert(asset, &o, NULL) == MR_OK);
    MR_CHECK(mr_gltf_get_material(asset, 0, &m) == MR_OK);
    MR_CHECK(m.base_color_texture.index == diffuse_texture && m.metallic_factor == 0.0);
    MR_CHECK(m.metallic_roughness_texture.index < 0);
    MR_CHECK_NEAR(m.roughness_factor, 0.7, 1e-7);
    MR_CHECK(m.has_specular && m.specular_strength == 1.0 && m.specular_color_factor[0] == 0.0);
    MR_CHECK(m.has_ior && m.ior == 1000.0);
    mr_gltf_counts after;
    mr_gltf_get_counts(asset, &after);
    MR_CHECK(after.images == before.images); // no new image
    mr_gltf_free(asset);
    mr_transform_free(t);
}

/* A transform between other models, or an unknown image format, is refused before anything changes. */
MR_TEST(bad_options_are_refused) {
    mr_gltf *asset = NULL;
    MR_CHECK(mr_gltf_load(mr_test_asset_path(DUCK), &asset) == MR_OK);
    if (asset == NULL) return;
    mr_transform *paper = make_transform("ggx", "ggx-metallic", "weighted");
    mr_gltf_convert_options o = {0};
    o.transform = paper;
    MR_CHECK(mr_gltf_convert(asset, &o, NULL) == MR_ERR_INVALID_ARG);
    MR_CHECK_MSG(strstr(mr_last_error(), "converts ggx to ggx-metallic") != NULL, "%s", mr_last_error());
    mr_transform *t = make_transform("gltf-specgloss", "gltf", "weighted");
    o.transform = t;
    o.image_format = "jpg";
    MR_CHECK(mr_gltf_convert(asset, &o, NULL) == MR_ERR_INVALID_ARG);
    MR_CHECK(strstr(mr_last_error(), "'jpg'") != NULL);
    o.transform = NULL;
    MR_CHECK(mr_gltf_convert(asset, &o, NULL) == MR_ERR_INVALID_ARG);
    mr_transform_free(paper);
    mr_transform_free(t);
    mr_gltf_free(asset);
}

/* metal2spec adds the spec-gloss extension and nothing else: no KHR_materials_specular (whose "specular" slot name
 * the spec-gloss side shares), which the file would hold as an empty object beside spec-gloss. */
MR_TEST(metal2spec_adds_no_specular_extension) {
    mr_gltf *asset = NULL;
    mr_transform *t = make_transform("gltf", "gltf-specgloss", "eq2");
    MR_CHECK(mr_gltf_load(mr_test_asset_path("metalrough/WaterBottle/glTF/WaterBottle.gltf"), &asset) == MR_OK);
    if (asset == NULL || t == NULL) return;
    mr_gltf_convert_options o = {0};
    o.transform = t;
    mr_gltf_material_report report;
    MR_CHECK(mr_gltf_convert(asset, &o, &report) == MR_OK);
    MR_CHECK(report.outcome == MR_GLTF_CONVERTED);
    mr_gltf_material m;
    MR_CHECK(mr_gltf_get_material(asset, 0, &m) == MR_OK);
    MR_CHECK(m.has_spec_gloss && !m.has_specular);
    MR_CHECK(!mr_gltf_material_has_extension(asset, 0, "KHR_materials_specular"));
    mr_gltf_free(asset);
    mr_transform_free(t);
}

static int file_is(const char *path, const char *text) {
    char buf[64] = "";
    FILE *f = fopen(path, "rb");
    if (f == NULL) return 0;
    size_t n = fread(buf, 1, sizeof buf - 1, f);
    fclose(f);
    buf[n] = '\0';
    return strcmp(buf, text) == 0;
}

/* mr_gltf_convert_file names the side files after the output (a.gltf: a.bin, a_m0_...), so a second output in the
 * same folder shares none; an existing file that is no side file of the earlier output is refused, nothing
 * written, the hint named; replace_files replaces it; the same conversion again replaces its own files. */
MR_TEST(convert_file_side_files_after_the_output) {
    mr_transform *t = make_transform("gltf-specgloss", "gltf", "weighted");
    if (t == NULL) return;
    mr_gltf_convert_options o = {0};
    o.transform = t;
    o.overwrite = 1;
    char dir[512];
    snprintf(dir, sizeof dir, "%s", mr_test_tmp_path("sides"));
    MR_CHECK(mkdir(dir, 0777) == 0);
    char a[600], b[600], path[600];
    snprintf(a, sizeof a, "%s/a.gltf", dir);
    snprintf(b, sizeof b, "%s/b.gltf", dir);
    MR_CHECK_OK(mr_gltf_convert_file(mr_test_asset_path(DUCK), a, &o, NULL));
    const char *made[] = {"a.bin", "a_m0_basecolor.png", "a_m0_metallicRoughness.png"};
    for (int k = 0; k < 3; k++) {
        snprintf(path, sizeof path, "%s/%s", dir, made[k]);
        MR_CHECK_MSG(access(path, F_OK) == 0, "%s", path);
    }
    snprintf(path, sizeof path, "%s/b.bin", dir);
    MR_CHECK(mr_test_write_file(path, "someone's", 9));
    o.replace_hint = "--replace-files";
    MR_CHECK(mr_gltf_convert_file(mr_test_asset_path(DUCK), b, &o, NULL) == MR_ERR_INVALID_ARG);
    MR_CHECK_MSG(strstr(mr_last_error(), "buffer 0") && strstr(mr_last_error(), "b.bin") &&
                 strstr(mr_last_error(), "--replace-files"), "%s", mr_last_error());
    MR_CHECK(file_is(path, "someone's") && access(b, F_OK) != 0);
    snprintf(path, sizeof path, "%s/b_m0_basecolor.png", dir);
    MR_CHECK(access(path, F_OK) != 0); // nothing written
    MR_CHECK_OK(mr_gltf_convert_file(mr_test_asset_path(DUCK), a, &o, NULL)); // its own files, again
    o.replace_files = 1;
    MR_CHECK_OK(mr_gltf_convert_file(mr_test_asset_path(DUCK), b, &o, NULL));
    snprintf(path, sizeof path, "%s/b.bin", dir);
    MR_CHECK(!file_is(path, "someone's"));
    mr_transform_free(t);
}

/* A conversion's totals: converted counts shared materials too, texels and flags each conversion once (a shared
 * material's textures are the earlier one's), factors-only a texel; kept and skipped materials add nothing else. */
MR_TEST(totals_count_each_conversion_once) {
    mr_gltf_material_report m[4];
    memset(m, 0, sizeof m);
    m[0].outcome = MR_GLTF_CONVERTED;
    m[0].width = 4;
    m[0].height = 2;
    m[0].flagged = 3;
    m[0].clamped = 2;
    m[0].off_manifold = 1;
    m[1] = m[0];
    m[1].outcome = MR_GLTF_SHARED;
    m[2].outcome = MR_GLTF_CONVERTED; // factors only
    m[2].flagged = m[2].failed = 1;
    m[3].outcome = MR_GLTF_KEPT;
    m[3].flagged = 7;
    const mr_gltf_convert_result result = {4, m, {0}};
    mr_gltf_convert_totals t;
    mr_gltf_convert_totals_of(&result, &t);
    MR_CHECK(t.converted == 3 && t.kept == 1 && t.texels == 9);
    MR_CHECK(t.total.flagged == 4 && t.total.clamped == 2 && t.total.off_manifold == 1 && t.total.failed == 1 &&
             t.total.nonfinite == 0);
    mr_gltf_convert_totals_of(NULL, &t);
    MR_CHECK(t.converted == 0 && t.texels == 0 && t.total.flagged == 0);
}

MR_TEST_MAIN(MR_TEST_ENTRY(totals_count_each_conversion_once),
             MR_TEST_ENTRY(duck_palette_route_gives_the_converters_codes),
             MR_TEST_ENTRY(floppy_code_route_gives_the_converters_codes),
             MR_TEST_ENTRY(truck_materials_share_a_conversion),
             MR_TEST_ENTRY(extension_route_reuses_textures_and_makes_factors),
             MR_TEST_ENTRY(bad_options_are_refused),
             MR_TEST_ENTRY(metal2spec_adds_no_specular_extension),
             MR_TEST_ENTRY(convert_file_side_files_after_the_output))
