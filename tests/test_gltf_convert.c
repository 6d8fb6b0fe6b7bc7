/*
 * test_gltf_convert.c — glTF asset conversion in the library (gltf/mr_gltf_convert.h): the new textures hold what
 * the workflow converters give texel by texel, materials with the same sources share one conversion, the extension
 * route reuses textures and turns a uniform result into factors, and bad options are refused.
 */
#include <math.h>
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

/* three.js's MeshPhysicalMaterial F0 (lights_physical_fragment: mix(min(pow2((ior - 1) / (ior + 1)) *
 * specularColor, 1) * specularIntensity, diffuseColor, metalness)), written here from its formula, not the
 * library's. */
static double three_f0(double base, double metallic, double specular_color, double specular_intensity, double ior) {
    const double r = (ior - 1.0) / (ior + 1.0);
    const double dielectric = fmin(r * r * specular_color, 1.0) * specular_intensity;
    return dielectric * (1.0 - metallic) + base * metallic;
}

/* The per-texel solve: a texel on the metallic manifold (its F0 the core's own mix(0.04, b, m)) needs no change
 * (colour 1, the extension's default); a coloured specular over a dielectric diffuse gives that colour as F0 under
 * three.js's formula, at ior 1.5 and 1000; clamped texels are flagged with the reason. */
MR_TEST(specular_solve_known_answers) {
    const float base[3] = {0.8f, 0.5f, 0.2f};
    float colour[3];
    for (int k = 0; k <= 4; k++) {
        const float m = 0.2f * (float)k;
        float f0[3];
        for (int c = 0; c < 3; c++) f0[c] = (float)(0.04 * (1.0 - m) + base[c] * m);
        const unsigned flags = mr_gltf_specular_color_solve(base, m, f0, 1.5, colour);
        MR_CHECK_MSG(flags == 0, "metallic %g: flags %u", m, flags);
        for (int c = 0; c < 3; c++) MR_CHECK_NEAR(colour[c], 1.0, 2e-5);
    }
    const float plastic[3] = {0.5f, 0.4f, 0.3f}, specular[3] = {0.2f, 0.5f, 0.9f};
    const double iors[2] = {1.5, 1000.0};
    for (int k = 0; k < 2; k++) {
        MR_CHECK(mr_gltf_specular_color_solve(plastic, 0.0f, specular, iors[k], colour) == 0);
        for (int c = 0; c < 3; c++)
            MR_CHECK_NEAR(three_f0(plastic[c], 0.0, colour[c], 1.0, iors[k]), specular[c], 1e-6);
    }
    MR_CHECK_NEAR(colour[2], 0.9 / (999.0 * 999.0 / (1001.0 * 1001.0)), 1e-5);
    // Part metal: the dielectric part makes up the rest (up to 0.75 + 0.25 base).
    const float reachable[3] = {0.2f, 0.5f, 0.6f};
    MR_CHECK(mr_gltf_specular_color_solve(plastic, 0.25f, reachable, 1.5, colour) == 0);
    for (int c = 0; c < 3; c++) MR_CHECK_NEAR(three_f0(plastic[c], 0.25, colour[c], 1.0, 1.5), reachable[c], 1e-6);
    // The metal part alone reflects more than the target: colour 0, flagged below.
    const float white[3] = {1.0f, 1.0f, 1.0f}, black[3] = {0.0f, 0.0f, 0.0f}, dim[3] = {0.1f, 0.1f, 0.1f};
    MR_CHECK(mr_gltf_specular_color_solve(white, 0.5f, dim, 1.5, colour) == MR_GLTF_F0_BELOW);
    MR_CHECK(colour[0] == 0.0f && colour[1] == 0.0f && colour[2] == 0.0f);
    // Half metal over black: the dielectric half reaches 0.5 at most: 1 / F0(ior), flagged above.
    const float bright[3] = {0.9f, 0.9f, 0.9f};
    MR_CHECK(mr_gltf_specular_color_solve(black, 0.5f, bright, 1.5, colour) == MR_GLTF_F0_ABOVE);
    MR_CHECK_NEAR(colour[0], 25.0, 1e-4);
    MR_CHECK_NEAR(three_f0(0.0, 0.5, colour[0], 1.0, 1.5), 0.5, 1e-6);
    // Metallic 1: F0 is the base colour, flagged when it is not the target; the colour a dielectric would take.
    MR_CHECK(mr_gltf_specular_color_solve(bright, 1.0f, bright, 1.5, colour) == 0);
    MR_CHECK_NEAR(colour[0], 0.9 / 0.04, 1e-4);
    MR_CHECK(mr_gltf_specular_color_solve(bright, 1.0f, dim, 1.5, colour) == MR_GLTF_F0_METAL);
    // Within one 8-bit code nothing is flagged.
    float near[3] = {0.04f + 0.5f / 255.0f, 0.04f, 0.04f};
    MR_CHECK(mr_gltf_specular_color_solve(black, 1.0f, near, 1.5, colour) == MR_GLTF_F0_METAL);
    near[0] = near[1] = near[2] = 0.5f / 255.0f;
    MR_CHECK(mr_gltf_specular_color_solve(black, 1.0f, near, 1.5, colour) == 0);
}

/* The default conversion (options zeroed: both readings) of the Duck given a coloured specular: the core textures
 * are the core-only conversion's, and KHR_materials_specular's colour (factor x texture, sRGB-decoded), with the
 * core base colour and metallic as an engine decodes them, gives three.js's F0 = the spec-gloss specular within
 * the 8-bit storage, except at the texels counted unmet; core_only adds nothing. */
MR_TEST(default_conversion_carries_both_readings) {
    mr_transform *t = make_transform("gltf-specgloss", "gltf", "weighted");
    mr_gltf *asset = NULL, *core = NULL;
    MR_CHECK(mr_gltf_load(mr_test_asset_path(DUCK), &asset) == MR_OK);
    MR_CHECK(mr_gltf_load(mr_test_asset_path(DUCK), &core) == MR_OK);
    if (asset == NULL || core == NULL || t == NULL) return;
    mr_gltf_material sg, hybrid, plain;
    MR_CHECK(mr_gltf_get_material(asset, 0, &sg) == MR_OK);
    sg.specular_factor[0] = 0.30; // coloured: the Duck's own specular is 0, below any metal-rough F0
    sg.specular_factor[1] = 0.20;
    sg.specular_factor[2] = 0.05;
    MR_CHECK(mr_gltf_set_material(asset, 0, &sg) == MR_OK && mr_gltf_set_material(core, 0, &sg) == MR_OK);
    mr_gltf_convert_options o = {0};
    o.transform = t;
    o.overwrite = 1;
    mr_gltf_material_report r, rc;
    MR_CHECK(mr_gltf_convert(asset, &o, &r) == MR_OK);
    o.core_only = 1;
    MR_CHECK(mr_gltf_convert(core, &o, &rc) == MR_OK);
    MR_CHECK(mr_gltf_get_material(asset, 0, &hybrid) == MR_OK && mr_gltf_get_material(core, 0, &plain) == MR_OK);
    MR_CHECK(r.extension == 1 && rc.extension == 0 && !plain.has_specular && !plain.has_ior);
    MR_CHECK(hybrid.has_specular && !hybrid.has_ior && hybrid.specular_strength == 1.0 &&
             hybrid.specular_texture.index < 0);
    // The core values are the core-only conversion's.
    mr_image *base = NULL, *mr = NULL, *base_core = NULL, *spec = NULL, *diffuse = NULL;
    MR_CHECK(mr_gltf_texture_read(asset, hybrid.base_color_texture.index, NULL, &base, NULL) == MR_OK);
    MR_CHECK(mr_gltf_texture_read(core, plain.base_color_texture.index, NULL, &base_core, NULL) == MR_OK);
    MR_CHECK(base != NULL && base_core != NULL &&
             memcmp(base->pixels, base_core->pixels, mr_image_value_count(base) * sizeof(float)) == 0);
    mr_img_read_options data = {0};
    data.encoding = MR_IMG_DATA;
    MR_CHECK(hybrid.metallic_roughness_texture.index >= 0 || hybrid.metallic_factor >= 0.0);
    if (hybrid.metallic_roughness_texture.index >= 0)
        MR_CHECK(mr_gltf_texture_read(asset, hybrid.metallic_roughness_texture.index, &data, &mr, NULL) == MR_OK);
    if (hybrid.specular_color_texture.index >= 0)
        MR_CHECK(mr_gltf_texture_read(asset, hybrid.specular_color_texture.index, NULL, &spec, NULL) == MR_OK);
    MR_CHECK(mr_gltf_texture_read(asset, sg.diffuse_texture.index, NULL, &diffuse, NULL) == MR_OK);
    size_t unmet = 0, n = base ? (size_t)base->width * (size_t)base->height : 0;
    double worst = 0.0;
    for (size_t i = 0; i < n; i++) {
        const double m = (mr ? mr->pixels[(size_t)mr->channels * i + 2] : 1.0) * hybrid.metallic_factor;
        int off = 0;
        for (int c = 0; c < 3; c++) {
            const double b = base->pixels[(size_t)base->channels * i + (size_t)c] * hybrid.base_color_factor[c];
            const double sc = (spec ? spec->pixels[3 * i + (size_t)c] : 1.0) * hybrid.specular_color_factor[c];
            const double e = fabs(three_f0(b, m, sc, 1.0, 1.5) - sg.specular_factor[c]);
            off |= e > MR_GLTF_HYBRID_TOLERANCE;
            // Stored in 8 bits (sRGB) over the largest colour: half a code at the top is 0.002 of the factor.
            if (e <= MR_GLTF_HYBRID_TOLERANCE) worst = fmax(worst, e / fmax(hybrid.specular_color_factor[c], 1.0));
        }
        unmet += off;
    }
    MR_CHECK_MSG(r.texels == n && n == 512u * 512u, "texels %zu, grid %zu", r.texels, n);
    // Counted alike here and in the library (a texel at the bound may round either way); most texels are exact.
    MR_CHECK_MSG((unmet > r.f0_unmet ? unmet - r.f0_unmet : r.f0_unmet - unmet) <= n / 1000 && unmet < n / 2,
                 "unmet %zu, the library says %zu", unmet, r.f0_unmet);
    MR_CHECK_MSG(worst < 0.002, "F0 off by %g", worst);
    MR_CHECK(r.diffuse_mean_error >= 0.0 && r.diffuse_max_error >= r.diffuse_mean_error);
    mr_image_free(base);
    mr_image_free(base_core);
    mr_image_free(mr);
    mr_image_free(spec);
    mr_image_free(diffuse);
    // An ior outside (1, 1e4] is refused, naming it; 1000 writes KHR_materials_ior.
    o.core_only = 0;
    o.extension_ior = 0.5;
    MR_CHECK(mr_gltf_convert(asset, &o, NULL) == MR_ERR_INVALID_ARG);
    MR_CHECK_MSG(strcmp(mr_last_error(), "glTF conversion: extension ior 0.5: expected a value in (1, 10000]") == 0,
                 "%s", mr_last_error());
    mr_gltf_free(asset);
    mr_gltf_free(core);
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
             MR_TEST_ENTRY(specular_solve_known_answers),
             MR_TEST_ENTRY(default_conversion_carries_both_readings),
             MR_TEST_ENTRY(duck_palette_route_gives_the_converters_codes),
             MR_TEST_ENTRY(floppy_code_route_gives_the_converters_codes),
             MR_TEST_ENTRY(truck_materials_share_a_conversion),
             MR_TEST_ENTRY(extension_route_reuses_textures_and_makes_factors),
             MR_TEST_ENTRY(bad_options_are_refused),
             MR_TEST_ENTRY(metal2spec_adds_no_specular_extension),
             MR_TEST_ENTRY(convert_file_side_files_after_the_output))
