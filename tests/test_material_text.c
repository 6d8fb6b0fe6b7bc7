/*
 * test_material_text.c — materials given as text (render/render.h, "materials given as text"; io/image_io.h, "maps
 * named in text"), without the command line: map references split and checked, values and maps with selectors
 * (:g:linear) bound, the faults of the text told apart from those of a file or a value, an unknown parameter named
 * with the valid ones, and the texels that are no parameter values described.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "harness.h"
#include "io/image_io.h"
#include "render/render.h"

/* A width x 1 image of `channels` channels from `values` written to the scratch file `name` (8-bit PNG, linear, or
 * float EXR by the name); returns its path (a copy in `path`). */
static const char *write_image(char *path, size_t size, const char *name, int width, int channels,
                               const float *values) {
    snprintf(path, size, "%s", mr_test_tmp_path(name));
    mr_image *im = NULL;
    if (mr_image_create(width, 1, channels, &im) != MR_OK) return path;
    memcpy(im->pixels, values, (size_t)width * (size_t)channels * sizeof *values);
    mr_img_write_options o = {MR_IMG_DATA, 0, 0};
    if (mr_img_write(path, im, &o) != MR_OK) fprintf(stderr, "    writing %s: %s\n", path, mr_last_error());
    mr_image_free(im);
    return path;
}

MR_TEST(map_reference_split_and_checked) {
    size_t length;
    int channel;
    mr_map_encoding encoding;
    mr_map_ref_split("orm.png:g:linear", 1, &length, &channel, &encoding);
    MR_CHECK(length == 7 && channel == 1 && encoding == MR_MAP_LINEAR);
    mr_map_ref_split("orm.png:g", 0, &length, &channel, &encoding); // no channels picked: ":g" is the file's
    MR_CHECK(length == 9 && channel == -1 && encoding == MR_MAP_AS_PARAMETER);
    mr_map_ref_split("odd:linear:srgb", 1, &length, &channel, &encoding);
    MR_CHECK(length == 10 && channel == -1 && encoding == MR_MAP_SRGB);
    MR_CHECK_OK(mr_map_ref_check("x", "a.png:a:srgb", 1));
    MR_CHECK(mr_map_ref_check("s=@", "", 1) == MR_ERR_INVALID_ARG);
    MR_CHECK_MSG(strcmp(mr_last_error(), "'s=@': no file name (expected FILE[:r|g|b|a][:linear|srgb])") == 0,
                 "%s", mr_last_error());
    MR_CHECK(mr_map_ref_check("--specular x.png:linear:g", "x.png:linear:g", 1) == MR_ERR_INVALID_ARG);
    MR_CHECK_MSG(strcmp(mr_last_error(), "'--specular x.png:linear:g': the channel comes before the encoding: "
                        "x.png:g:linear") == 0, "%s", mr_last_error());
}

MR_TEST(values_and_maps_bound) {
    char orm[512], albedo[512];
    const float orm_px[6] = {1.0f, 0.2f, 0.0f, 1.0f, 0.6f, 1.0f}; // colour: occlusion, roughness, metallic
    const float albedo_px[6] = {0.5f, 0.25f, 0.0f, 1.0f, 1.0f, 1.0f};
    write_image(orm, sizeof orm, "orm.png", 2, 3, orm_px);
    write_image(albedo, sizeof albedo, "albedo.png", 2, 3, albedo_px);
    char a0[600], a1[600];
    snprintf(a0, sizeof a0, "roughness=@%s:g:linear", orm);
    snprintf(a1, sizeof a1, "base_color=@%s", albedo);
    const char *assignments[3] = {a0, "metallic=0.25", a1};
    mr_material *m = NULL;
    mr_material_text_report report;
    MR_CHECK_OK(mr_material_from_assignments("gltf", assignments, 3, NULL, &m, &report));
    if (m == NULL) return;
    MR_CHECK(report.failed == -1 && report.usage == 0);
    MR_CHECK(strcmp(m->model->name, "gltf") == 0 && m->map_count == 2);
    const int rough = mr_brdf_param_index(m->model, "roughness"), base = mr_brdf_param_index(m->model, "base_color");
    MR_CHECK(m->maps[0].param == rough && m->maps[0].channel == 1 && m->textures.maps[rough] == m->maps[0].image);
    char source[600];
    snprintf(source, sizeof source, "%s:linear", orm);
    MR_CHECK_MSG(strcmp(m->maps[0].source, source) == 0, "%s", m->maps[0].source);
    MR_CHECK_NEAR(m->maps[0].image->pixels[1], 51.0 / 255.0, 1e-6); // linear: the stored code
    MR_CHECK(m->maps[1].param == base && m->maps[1].channel == 0);
    MR_CHECK_NEAR(m->maps[1].image->pixels[0], mr_srgb_to_linear(128.0f / 255.0f), 1e-6); // colour: sRGB
    MR_CHECK_NEAR(m->values[mr_brdf_param_offset(m->model, mr_brdf_param_index(m->model, "metallic"))], 0.25, 0);
    char note[256];
    MR_CHECK(mr_material_describe_invalid_texels(m, 0, note, sizeof note) == 0 && note[0] == '\0');
    mr_material_free(m);
}

/* Each fault: its status, whether the text was at fault (a command line's usage error), which assignment, and words
 * naming it. */
static void expect_fault(const char *model, const char *assignment, mr_status status, int usage, const char *words) {
    const char *assignments[2] = {"metallic=0.5", assignment};
    mr_material *m = (mr_material *)1;
    mr_material_text_report report;
    mr_status got = mr_material_from_assignments(model, assignments, 2, NULL, &m, &report);
    MR_CHECK_MSG(got == status && m == NULL, "%s: %s (%s)", assignment, mr_status_str(got), mr_last_error());
    MR_CHECK_MSG(report.usage == usage, "%s: usage %d", assignment, report.usage);
    MR_CHECK_MSG(report.failed == (strcmp(model, "gltf") == 0 ? 1 : -1), "%s: failed %d", assignment, report.failed);
    MR_CHECK_MSG(strstr(mr_last_error(), words) != NULL, "%s: '%s' lacks '%s'", assignment, mr_last_error(), words);
}

MR_TEST(faults_told_apart) {
    char orm[512], grey[512], exr[512], bad[600];
    const float orm_px[6] = {1.0f, 0.2f, 0.0f, 1.0f, 0.6f, 1.0f};
    const float grey_px[2] = {0.5f, 0.25f};
    write_image(orm, sizeof orm, "orm2.png", 2, 3, orm_px);
    write_image(grey, sizeof grey, "grey.png", 2, 1, grey_px);
    write_image(exr, sizeof exr, "rough.exr", 2, 1, grey_px);
    snprintf(bad, sizeof bad, "roughness=@%s", orm);
    expect_fault("gltf", bad, MR_ERR_INVALID_ARG, 1, "holds colour, but roughness takes one value: pick a channel");
    snprintf(bad, sizeof bad, "base_color=@%s:r", orm);
    expect_fault("gltf", bad, MR_ERR_INVALID_ARG, 1,
                 "base_color is an RGB parameter and takes the whole image (no :r)");
    snprintf(bad, sizeof bad, "roughness=@%s:linear:g", grey);
    expect_fault("gltf", bad, MR_ERR_INVALID_ARG, 1, "the channel comes before the encoding");
    snprintf(bad, sizeof bad, "roughness=@%s:srgb", exr);
    expect_fault("gltf", bad, MR_ERR_INVALID_ARG, 1, "(:srgb) applies to 8/16-bit files");
    expect_fault("gltf", "roughness", MR_ERR_INVALID_ARG, 1, "is not a NAME=VALUE or NAME=@FILE assignment");
    expect_fault("gltf", "=@x.png", MR_ERR_INVALID_ARG, 1, "expected name=@FILE");
    // Not the text's fault: an unknown parameter (the valid ones listed), a missing file, a value out of range.
    snprintf(bad, sizeof bad, "bogus=@%s", grey);
    expect_fault("gltf", bad, MR_ERR_INVALID_ARG, 0, "has no parameter 'bogus' (valid: base_color");
    snprintf(bad, sizeof bad, "roughness=@%s/missing.png", grey);
    MR_CHECK(mr_material_from_assignments("gltf", (const char *const[]){bad}, 1, NULL,
                                          &(mr_material *){NULL}, NULL) != MR_OK);
    expect_fault("gltf", "roughness=7", MR_ERR_INVALID_ARG, 0, "roughness");
    expect_fault("gltf", "base_color=albedo.png", MR_ERR_INVALID_ARG, 0,
                 "; did you mean base_color=@albedo.png? (a map is given as name=@FILE)");
    expect_fault("no-such-model", "roughness=0.5", MR_ERR_INVALID_ARG, 0, "no-such-model");
    // The grey file is fine for a one-value parameter without a channel.
    snprintf(bad, sizeof bad, "roughness=@%s", grey);
    mr_material *m = NULL;
    MR_CHECK_OK(mr_material_from_assignments("gltf", (const char *const[]){bad}, 1, NULL, &m, NULL));
    mr_material_free(m);
}

MR_TEST(invalid_texels_described) {
    char exr[512];
    const float px[4] = {NAN, -0.5f, 0.25f, INFINITY};
    write_image(exr, sizeof exr, "invalid.exr", 4, 1, px);
    char a[600];
    snprintf(a, sizeof a, "roughness=@%s", exr);
    mr_material *m = NULL;
    MR_CHECK_OK(mr_material_from_assignments("gltf", (const char *const[]){a}, 1, NULL, &m, NULL));
    if (m == NULL) return;
    size_t nonfinite = 0, negative = 0;
    MR_CHECK_OK(mr_material_map_invalid_texels(m, 0, &nonfinite, &negative));
    MR_CHECK(nonfinite == 2 && negative == 1);
    char note[1024], expected[1024];
    snprintf(expected, sizeof expected, "roughness=@%s: 2 texels not finite, read as 0; 1 negative, clamped to 0", exr);
    MR_CHECK(mr_material_describe_invalid_texels(m, 0, note, sizeof note) == 1);
    MR_CHECK_MSG(strcmp(note, expected) == 0, "'%s'", note);
    MR_CHECK(mr_material_describe_invalid_texels(m, 1, note, sizeof note) == 0);
    mr_material_free(m);
}

MR_TEST_MAIN(MR_TEST_ENTRY(map_reference_split_and_checked), MR_TEST_ENTRY(values_and_maps_bound),
             MR_TEST_ENTRY(faults_told_apart), MR_TEST_ENTRY(invalid_texels_described))
