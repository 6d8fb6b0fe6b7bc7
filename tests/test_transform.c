/*
 * test_transform.c — transforms as descriptors (src/transform/transform.h): every kind names real model
 * parameters, the repeated-value path gives the bits of the per-texel converters, the extension route moves values,
 * Eq. 2 and Eq. 3 invert each other through the descriptors, and bad input is refused with a message.
 */
#include <stdint.h>
#include <unistd.h>

#include "harness.h"
#include "matremap.h"

/* A batch's read-only input view of maps (workflow.h, mr_wf_spec_input / mr_wf_metal_input). */
#define SPEC_IN(m) (&(mr_wf_spec_input){(m).diffuse, (m).specular, (m).roughness})
#define METAL_IN(m) (&(mr_wf_metal_input){(m).albedo, (m).metallic, (m).roughness})

/* Every kind's slots are parameters of its models, with the models' channel counts. */
MR_TEST(kinds_name_model_parameters) {
    int kinds = 0;
    for (const mr_transform_kind *const *k = mr_transforms(); *k != NULL; k++, kinds++) {
        const mr_brdf_model *src = mr_brdf_find((*k)->source), *dst = mr_brdf_find((*k)->target);
        MR_CHECK_MSG(src != NULL && dst != NULL, "%s: models %s -> %s", (*k)->name, (*k)->source, (*k)->target);
        if (src == NULL || dst == NULL) continue;
        for (int i = 0; i < (*k)->input_count; i++) {
            int p = mr_brdf_param_index(src, (*k)->inputs[i].name);
            MR_CHECK_MSG(p >= 0 && src->params[p].channels == (*k)->inputs[i].channels, "%s: input %s of %s",
                         (*k)->name, (*k)->inputs[i].name, src->name);
        }
        for (int j = 0; j < (*k)->output_count; j++) {
            int p = mr_brdf_param_index(dst, (*k)->outputs[j].name);
            MR_CHECK_MSG(p >= 0 && dst->params[p].channels == (*k)->outputs[j].channels, "%s: output %s of %s",
                         (*k)->name, (*k)->outputs[j].name, dst->name);
            int from = (*k)->outputs[j].copy_of;
            MR_CHECK(from < (*k)->input_count);
            if (from >= 0) MR_CHECK((*k)->inputs[from].channels == (*k)->outputs[j].channels);
        }
        MR_CHECK(mr_transform_find((*k)->source, (*k)->target, (*k)->name) == *k);
    }
    MR_CHECK(kinds >= 11);
    MR_CHECK(strcmp(mr_transform_find("gltf-specgloss", "gltf", NULL)->name, "weighted") == 0);
    MR_CHECK(mr_transform_find("gltf-specgloss", "gltf", "bogus") == NULL);
    MR_CHECK_MSG(strstr(mr_last_error(), "valid: weighted, mlp, mean, khronos, extension") != NULL, "%s",
                 mr_last_error());
    MR_CHECK(mr_transform_find("ward", "ggx", NULL) == NULL);
    MR_CHECK_MSG(strstr(mr_last_error(), "no transform from ward to ggx") != NULL, "%s", mr_last_error());
}

static uint32_t next_random(uint32_t *state) {
    *state = *state * 1664525u + 1013904223u;
    return *state >> 8;
}

/* 8-bit values (repeated often) with a few hard ones: NaN, out of range, black. */
static float texel_value(uint32_t *state, size_t i) {
    if (i % 9973 == 5) return NAN;
    if (i % 7919 == 3) return 1.5f;
    return (float)(next_random(state) % 24) / 23.0f;
}

/* The deduplicated path of `weighted` gives the bits of mr_wf_spec_to_metal_batch, flags included, for one and two
 * threads and quantised inputs. */
MR_TEST(repeated_values_give_the_per_texel_bits) {
    const size_t n = 200000;
    float *d = malloc(3 * n * sizeof *d), *s = malloc(3 * n * sizeof *s), *g = malloc(n * sizeof *g);
    float *rough = malloc(n * sizeof *rough), *a = malloc(3 * n * sizeof *a), *m = malloc(n * sizeof *m);
    float *a2 = malloc(3 * n * sizeof *a2), *m2 = malloc(n * sizeof *m2), *r2 = malloc(n * sizeof *r2);
    uint8_t *f = malloc(n), *f2 = malloc(n);
    uint32_t state = 7;
    for (size_t i = 0; i < 3 * n; i++) {
        d[i] = texel_value(&state, i);
        s[i] = texel_value(&state, i + 1) * 0.5f;
    }
    for (size_t i = 0; i < n; i++) g[i] = texel_value(&state, i + 2);
    mr_wf_options w = mr_wf_options_default();
    w.spec_diffuse = MR_WF_DIFFUSE_SPECGLOSS;
    w.diffuse_quantisation = (mr_wf_quantisation){8, 1, {1, 1, 1}};
    for (size_t i = 0; i < n; i++) rough[i] = 1.0f - g[i];
    mr_wf_spec_maps in = {d, s, rough};
    mr_wf_metal_maps out = {a, m, rough};
    MR_CHECK(mr_wf_spec_to_metal_batch(SPEC_IN(in), n, &w, &out, f) == MR_OK);

    mr_transform *t = NULL;
    MR_CHECK(mr_transform_create(mr_transform_find("gltf-specgloss", "gltf", "weighted"), NULL, &t) == MR_OK);
    for (int threads = 1; t != NULL && threads <= 2; threads++) {
        mr_transform_batch b = {0};
        b.n = n;
        b.in[0] = d;
        b.in[1] = s;
        b.in[2] = g;
        b.out[0] = a2;
        b.out[1] = m2;
        b.out[2] = r2;
        b.stored[0] = w.diffuse_quantisation;
        b.flags = f2;
        b.threads = threads;
        MR_CHECK(mr_transform_apply(t, &b) == MR_OK);
        MR_CHECK(memcmp(a, a2, 3 * n * sizeof *a) == 0);
        MR_CHECK(memcmp(m, m2, n * sizeof *m) == 0);
        MR_CHECK(memcmp(rough, r2, n * sizeof *r2) == 0);
        MR_CHECK(memcmp(f, f2, n) == 0);
    }
    mr_transform_free(t);
    free(d), free(s), free(g), free(rough), free(a), free(m), free(a2), free(m2), free(r2), free(f), free(f2);
}

/* The extension route moves values and sanitises them; its constants are the same for every texel. */
MR_TEST(extension_route_moves_values) {
    const mr_transform_kind *kind = mr_transform_find("gltf-specgloss", "gltf", "extension");
    mr_transform *t = NULL;
    MR_CHECK(kind != NULL && mr_transform_create(kind, NULL, &t) == MR_OK);
    if (t == NULL) return;
    double in[7] = {0.5, 0.25, 2.0, 0.9, 0.8, 0.7, NAN}, out[12];
    unsigned flags = 0;
    MR_CHECK(mr_transform_apply_values(t, in, out, &flags) == MR_OK);
    MR_CHECK(out[0] == 0.5 && out[1] == 0.25 && out[2] == 1.0); // base colour: the diffuse, clamped
    MR_CHECK(out[3] == 0.0);                                     // metallic
    MR_CHECK(out[4] == 1.0);                                     // a NaN glossiness is glossiness 0
    MR_CHECK(out[5] == 1.0);                                     // specular strength
    MR_CHECK_NEAR(out[6], 0.9, 1e-7);                            // specular colour: the specular
    MR_CHECK(out[9] == 1000.0);                                  // ior
    MR_CHECK(flags == (MR_WF_CLAMPED_INPUT | MR_WF_NONFINITE_INPUT));
    MR_CHECK(kind->outputs[0].copy_of == 0 && kind->outputs[4].copy_of == 1);
    mr_transform_free(t);
}

/* Eq. 2 then Eq. 3 through the descriptors gives the metallic texel back (glTF and paper pairs), and the
 * glossiness of the glTF pair is 1 - roughness. */
MR_TEST(eq2_and_eq3_invert_each_other) {
    const char *const pairs[2][2] = {{"gltf", "gltf-specgloss"}, {"ggx-metallic", "ggx"}};
    for (int p = 0; p < 2; p++) {
        mr_transform *forward = NULL, *back = NULL;
        MR_CHECK(mr_transform_create(mr_transform_find(pairs[p][0], pairs[p][1], "eq2"), NULL, &forward) == MR_OK);
        MR_CHECK(mr_transform_create(mr_transform_find(pairs[p][1], pairs[p][0], "weighted"), NULL, &back) == MR_OK);
        if (forward == NULL || back == NULL) continue;
        double metal[5] = {0.9, 0.6, 0.2, 0.7, 0.3}, spec[7], again[5];
        unsigned flags = 1;
        MR_CHECK(mr_transform_apply_values(forward, metal, spec, &flags) == MR_OK && flags == 0);
        MR_CHECK(mr_transform_apply_values(back, spec, again, &flags) == MR_OK);
        MR_CHECK_MSG(flags == 0, "flags %u", flags);
        for (int k = 0; k < 5; k++) MR_CHECK_NEAR(again[k], metal[k], 2e-6);
        MR_CHECK_NEAR(spec[6], p == 0 ? 0.7 : 0.3, 1e-7); // glossiness 1 - 0.3, or alpha passed through
        mr_transform_free(forward);
        mr_transform_free(back);
    }
}

/* Options that do not apply, and a network that cannot be found, are refused with a message naming them. */
MR_TEST(bad_options_are_refused) {
    mr_transform *t = NULL;
    mr_transform_options o = {0};
    o.dielectric_f0 = 0.03;
    MR_CHECK(mr_transform_create(mr_transform_find("gltf-specgloss", "gltf", "extension"), &o, &t) ==
             MR_ERR_INVALID_ARG);
    MR_CHECK(strstr(mr_last_error(), "takes no dielectric F0") != NULL && t == NULL);
    MR_CHECK(mr_transform_create(mr_transform_find("gltf-specgloss", "gltf", "khronos"), &o, &t) ==
             MR_ERR_INVALID_ARG); // Khronos's F0 is 0.04
    MR_CHECK_MSG(strstr(mr_last_error(), "transform khronos") != NULL && strstr(mr_last_error(), "0.04") != NULL,
                 "%s", mr_last_error());
    o.dielectric_f0 = 0.04;
    MR_CHECK(mr_transform_create(mr_transform_find("gltf-specgloss", "gltf", "khronos"), &o, &t) == MR_OK);
    mr_transform_batch b = {0};
    float one[3] = {0.5f, 0.5f, 0.5f}, out[3];
    b.n = 1;
    b.in[0] = one;
    b.out[0] = out;
    MR_CHECK(mr_transform_apply(t, &b) == MR_ERR_INVALID_ARG);
    MR_CHECK(strstr(mr_last_error(), "input plane 'specular' is NULL") != NULL);
    mr_transform_free(t);
    o.dielectric_f0 = 1.5;
    MR_CHECK(mr_transform_create(mr_transform_find("gltf-specgloss", "gltf", "weighted"), &o, &t) ==
             MR_ERR_INVALID_ARG);
    MR_CHECK(strstr(mr_last_error(), "dielectric_f0 1.5") != NULL);
    setenv("MATREMAP_WEIGHTS", "/nonexistent/net.mlp", 1);
    MR_CHECK(mr_transform_create(mr_transform_find("gltf-specgloss", "gltf", "mlp"), NULL, &t) == MR_ERR_IO);
    MR_CHECK_MSG(strstr(mr_last_error(), "/nonexistent/net.mlp") != NULL, "%s", mr_last_error());
    unsetenv("MATREMAP_WEIGHTS");
    char path[4096];
    MR_CHECK(mr_data_path("spec2metal.mlp", path, sizeof path) == MR_OK); // the source tree's data/
    MR_CHECK(mr_data_path("no-such-file.bin", path, sizeof path) == MR_ERR_IO);
    MR_CHECK(strstr(mr_last_error(), "no-such-file.bin") != NULL);
}

/* Texture-set conversion: maps (images and constants, a roughness map complemented into the glossiness slot) give
 * each texel what mr_transform_apply_values gives it; maps of different sizes and missing channels are refused. */
MR_TEST(maps_convert_texel_by_texel) {
    mr_transform *t = NULL;
    MR_CHECK(mr_transform_create(mr_transform_find("gltf-specgloss", "gltf", "weighted"), NULL, &t) == MR_OK);
    mr_image *diffuse = NULL, *rough = NULL, *small = NULL;
    MR_CHECK(mr_image_create(3, 2, 3, &diffuse) == MR_OK && mr_image_create(3, 2, 1, &rough) == MR_OK &&
             mr_image_create(2, 2, 1, &small) == MR_OK);
    if (t == NULL || diffuse == NULL || rough == NULL || small == NULL) return;
    for (int k = 0; k < 18; k++) diffuse->pixels[k] = (float)(k % 7) / 7.0f;
    for (int k = 0; k < 6; k++) rough->pixels[k] = (float)k / 5.0f;
    mr_transform_map in[3] = {{diffuse, 0, 0, {0, 0, 0}, {0, 0, {1, 1, 1}}},
                              {NULL, 0, 0, {0.5, 0.3, 0.04}, {0, 0, {1, 1, 1}}},
                              {rough, 0, 1, {0, 0, 0}, {0, 0, {1, 1, 1}}}};
    mr_image *out[3] = {NULL, NULL, NULL};
    uint8_t *flags = NULL;
    MR_CHECK(mr_transform_convert_maps(t, in, out, &flags) == MR_OK);
    for (int k = 0; out[0] != NULL && k < 6; k++) {
        double texel[7] = {diffuse->pixels[3 * k], diffuse->pixels[3 * k + 1], diffuse->pixels[3 * k + 2], 0.5, 0.3,
                           0.04, 1.0f - rough->pixels[k]};
        double expected[5];
        unsigned f = 0;
        MR_CHECK(mr_transform_apply_values(t, texel, expected, &f) == MR_OK);
        for (int c = 0; c < 3; c++) MR_CHECK(out[0]->pixels[3 * k + c] == (float)expected[c]);
        MR_CHECK(out[1]->pixels[k] == (float)expected[3] && out[2]->pixels[k] == (float)expected[4]);
        MR_CHECK(flags[k] == f);
    }
    MR_CHECK(out[0] != NULL && out[0]->width == 3 && out[0]->height == 2 && out[1]->channels == 1);
    for (int j = 0; j < 3; j++) {
        mr_image_free(out[j]);
        out[j] = NULL;
    }
    free(flags);
    in[2].image = small;
    MR_CHECK(mr_transform_convert_maps(t, in, out, NULL) == MR_ERR_INVALID_ARG);
    MR_CHECK_MSG(strstr(mr_last_error(), "'glossiness' is 2x2") != NULL, "%s", mr_last_error());
    in[2].image = rough;
    in[2].channel = 2;
    MR_CHECK(mr_transform_convert_maps(t, in, out, NULL) == MR_ERR_INVALID_ARG);
    MR_CHECK(strstr(mr_last_error(), "channel 2") != NULL && out[0] == NULL);
    mr_image_free(diffuse);
    mr_image_free(rough);
    mr_image_free(small);
    mr_transform_free(t);
}

/* Flags counted by reason, and drawn in each code: the workflow code paints a texel's most severe flag, the learned
 * code one channel per kind of reason; clean texels are black. */
MR_TEST(flags_counted_and_drawn_by_their_code) {
    const uint8_t flags[6] = {0, MR_WF_CLAMPED_INPUT, MR_WF_NONFINITE_INPUT | MR_WF_METHOD_FAILED, MR_WF_OFF_MANIFOLD,
                              MR_WF_EXTRAPOLATED | MR_WF_CLAMPED_OUTPUT, MR_WF_UNCONVERGED | MR_WF_CLAMPED_INPUT};
    const unsigned reasons[4] = {MR_WF_CLAMPED_INPUT, MR_WF_NONFINITE_INPUT | MR_WF_OFF_MANIFOLD, 0xFFu,
                                 MR_WF_UNCHECKED};
    size_t counts[4] = {9, 9, 9, 9};
    mr_flags_count(flags, 6, reasons, 4, counts);
    MR_CHECK(counts[0] == 2 && counts[1] == 2 && counts[2] == 5 && counts[3] == 0);
    mr_flags_count(NULL, 6, reasons, 4, counts);
    MR_CHECK(counts[0] == 0 && counts[2] == 0);

    static const float workflow[6][3] = {{0, 0, 0}, {0, 0.5f, 1}, {1, 0, 0}, {1, 0.5f, 0}, {0, 0, 0}, {0, 0.5f, 1}};
    static const float learned[6][3] = {{0, 0, 0}, {0, 0, 1}, {0, 0, 1}, {0, 0, 0}, {1, 1, 0}, {1, 0, 1}};
    const mr_flag_code *codes[2] = {&mr_workflow_flag_code, &mr_learned_flag_code};
    const float (*expected[2])[3] = {workflow, learned};
    for (int c = 0; c < 2; c++) {
        mr_image *picture = NULL;
        MR_CHECK_OK(mr_flag_picture(flags, 3, 2, codes[c], &picture));
        MR_CHECK(picture->width == 3 && picture->height == 2 && picture->channels == 3);
        for (int i = 0; i < 6; i++)
            MR_CHECK_MSG(memcmp(picture->pixels + 3 * i, expected[c][i], sizeof expected[c][i]) == 0,
                         "code %d, texel %d: %g %g %g", c, i, picture->pixels[3 * i], picture->pixels[3 * i + 1],
                         picture->pixels[3 * i + 2]);
        mr_image_free(picture);
    }
    mr_image *none = NULL;
    MR_CHECK(mr_flag_picture(NULL, 3, 2, &mr_workflow_flag_code, &none) == MR_ERR_INVALID_ARG && none == NULL);
}

/* mr_image_pack copies channels as they are (glTF's metallicRoughness: R fill, G roughness, B metallic);
 * mr_image_with_alpha appends a 4-channel source's alpha to an RGB image, and is the image itself otherwise. */
MR_TEST(outputs_packed_channel_by_channel) {
    mr_image *metallic = NULL, *roughness = NULL, *rgb = NULL, *rgba = NULL, *packed = NULL, *with = NULL;
    MR_CHECK_OK(mr_image_create(2, 1, 1, &metallic));
    MR_CHECK_OK(mr_image_create(2, 1, 1, &roughness));
    MR_CHECK_OK(mr_image_create(2, 1, 3, &rgb));
    MR_CHECK_OK(mr_image_create(2, 1, 4, &rgba));
    for (int i = 0; i < 2; i++) {
        metallic->pixels[i] = 0.25f + (float)i;
        roughness->pixels[i] = -0.5f - (float)i; // values are copied, never clamped
        for (int c = 0; c < 3; c++) rgb->pixels[3 * i + c] = 0.1f * (float)(c + 3 * i);
        for (int c = 0; c < 4; c++) rgba->pixels[4 * i + c] = 0.7f + 0.01f * (float)(c + 4 * i);
    }
    const mr_image_channel mr[3] = {{NULL, 0}, {roughness, 0}, {metallic, 0}};
    MR_CHECK_OK(mr_image_pack(2, 1, 3, mr, 0.0f, &packed));
    for (int i = 0; i < 2; i++)
        MR_CHECK(packed->pixels[3 * i] == 0.0f && packed->pixels[3 * i + 1] == roughness->pixels[i] &&
                 packed->pixels[3 * i + 2] == metallic->pixels[i]);
    MR_CHECK_OK(mr_image_with_alpha(rgb, rgba, &with));
    MR_CHECK(with != rgb && with->channels == 4);
    for (int i = 0; i < 2; i++)
        MR_CHECK(memcmp(with->pixels + 4 * i, rgb->pixels + 3 * i, 3 * sizeof(float)) == 0 &&
                 with->pixels[4 * i + 3] == rgba->pixels[4 * i + 3]);
    mr_image_free(with);
    MR_CHECK_OK(mr_image_with_alpha(rgb, NULL, &with));
    MR_CHECK(with == rgb);
    MR_CHECK_OK(mr_image_with_alpha(metallic, rgba, &with));
    MR_CHECK(with == metallic);
    const mr_image_channel missing[1] = {{rgb, 3}};
    mr_image *none = NULL;
    MR_CHECK(mr_image_pack(2, 1, 1, missing, 0.0f, &none) == MR_ERR_INVALID_ARG && none == NULL);
    mr_image_free(packed);
    mr_image_free(metallic);
    mr_image_free(roughness);
    mr_image_free(rgb);
    mr_image_free(rgba);
}

/* mr_transform_convert_texture_set: files read by the one rule, a constant broadcast, the slots fed (a roughness map
 * complemented into glossiness), packed as glTF does with the diffuse's alpha carried; the same values as the steps
 * taken one by one. A map refused names itself (failed_map, failed_reading). */
MR_TEST(texture_sets_convert_in_one_call) {
    const mr_brdf_model *sg = mr_brdf_find("gltf-specgloss"), *gltf = mr_brdf_find("gltf");
    const mr_brdf_param *diffuse_param = &sg->params[mr_brdf_param_index(sg, "diffuse")];
    const mr_brdf_param *rough_param = &gltf->params[mr_brdf_param_index(gltf, "roughness")];
    mr_image *diffuse = NULL, *rough = NULL;
    MR_CHECK_OK(mr_image_create(3, 2, 4, &diffuse));
    MR_CHECK_OK(mr_image_create(3, 2, 1, &rough));
    for (int k = 0; k < 24; k++) diffuse->pixels[k] = (float)(k % 5) / 5.0f;
    for (int k = 0; k < 6; k++) rough->pixels[k] = (float)k / 5.0f;
    char d[600], r[600];
    snprintf(d, sizeof d, "%s", mr_test_tmp_path("set_diffuse.png"));
    snprintf(r, sizeof r, "%s", mr_test_tmp_path("set_rough.png"));
    MR_CHECK_OK(mr_img_write(d, diffuse, NULL));
    MR_CHECK_OK(mr_img_write(r, rough, &(mr_img_write_options){MR_IMG_DATA, 0, 0}));
    mr_transform *t = NULL;
    MR_CHECK_OK(mr_transform_create(mr_transform_find("gltf-specgloss", "gltf", "weighted"), NULL, &t));
    if (t == NULL) return;

    mr_img_param_map maps[3] = {{.path = d, .param = diffuse_param, .label = "--diffuse d"},
                                {.path = NULL, .label = "--specular 0.04"},
                                {.path = r, .param = rough_param, .label = "--roughness r", .grey = 1}};
    const double constants[3][3] = {{0, 0, 0}, {0.04, 0.04, 0.04}, {0, 0, 0}};
    const mr_texture_source inputs[3] = {{0, -1, 0}, {1, -1, 0}, {2, 0, 1}};
    const mr_texture_layout packed[2] = {
        {"basecolor", MR_IMG_COLOR, 4, {0, 0, 0, MR_LAYOUT_ALPHA}, {0, 1, 2, 0}},
        {"metallicRoughness", MR_IMG_DATA, 3, {MR_LAYOUT_ZERO, 2, 1}, {0, 0, 0}}};
    const mr_texture_set set = {maps, constants, 3, inputs, 0, packed, 2, 0};
    mr_texture_result result;
    MR_CHECK_OK(mr_transform_convert_texture_set(t, &set, &result));
    MR_CHECK(result.width == 3 && result.height == 2 && result.flags != NULL && maps[0].image == NULL);

    // The steps one by one.
    mr_image *d_read = NULL, *r_read = NULL, *out[3] = {NULL, NULL, NULL};
    mr_img_stored d_stored, r_stored;
    MR_CHECK_OK(mr_img_read_param_map(d, diffuse_param, MR_MAP_AS_PARAMETER, NULL, &d_read, &d_stored));
    MR_CHECK_OK(mr_img_read_param_map(r, rough_param, MR_MAP_AS_PARAMETER, NULL, &r_read, &r_stored));
    mr_transform_map in[3] = {{d_read, 0, 0, {0, 0, 0}, mr_wf_quantisation_of(&d_stored, NULL)},
                              {NULL, 0, 0, {0.04, 0.04, 0.04}, mr_wf_quantisation_of(NULL, NULL)},
                              {r_read, 0, 1, {0, 0, 0}, mr_wf_quantisation_of(&r_stored, NULL)}};
    uint8_t *flags = NULL;
    MR_CHECK_OK(mr_transform_convert_maps(t, in, out, &flags));
    if (out[0] != NULL && result.outputs[0] != NULL && result.outputs[1] != NULL) {
        MR_CHECK(result.outputs[0]->channels == 4 && result.outputs[1]->channels == 3);
        for (int k = 0; k < 6; k++) {
            MR_CHECK(memcmp(result.outputs[0]->pixels + 4 * k, out[0]->pixels + 3 * k, 3 * sizeof(float)) == 0);
            MR_CHECK(result.outputs[0]->pixels[4 * k + 3] == d_read->pixels[4 * k + 3]);
            MR_CHECK(result.outputs[1]->pixels[3 * k] == 0.0f);
            MR_CHECK(result.outputs[1]->pixels[3 * k + 1] == out[2]->pixels[k]);
            MR_CHECK(result.outputs[1]->pixels[3 * k + 2] == out[1]->pixels[k]);
            MR_CHECK(result.flags[k] == flags[k]);
            MR_CHECK(memcmp(result.converted[0]->pixels + 3 * k, out[0]->pixels + 3 * k, 3 * sizeof(float)) == 0);
        }
    }
    mr_texture_result_free(&result);
    MR_CHECK(result.outputs[0] == NULL && result.flags == NULL);
    for (int j = 0; j < 3; j++) mr_image_free(out[j]);
    free(flags);

    // A colour file where a grey one is expected: refused by its label, read but checked.
    maps[2].path = d;
    MR_CHECK(mr_transform_convert_texture_set(t, &set, &result) == MR_ERR_INVALID_ARG);
    MR_CHECK(result.failed_map == 2 && !result.failed_reading && maps[2].image == NULL);
    MR_CHECK_MSG(strstr(mr_last_error(), "--roughness r is a colour image") != NULL, "%s", mr_last_error());
    // A missing file: its read failed.
    maps[2].path = mr_test_tmp_path("set_missing.png");
    MR_CHECK(mr_transform_convert_texture_set(t, &set, &result) == MR_ERR_IO);
    MR_CHECK(result.failed_map == 2 && result.failed_reading && result.outputs[0] == NULL);
    mr_image_free(d_read);
    mr_image_free(r_read);
    mr_image_free(diffuse);
    mr_image_free(rough);
    mr_transform_free(t);
}

/* What spec2metal and metal2spec decide from text, in the library: a constant (grey or R,G,B; the first number
 * outside [0, 1] named), the output format (named, or the first input file's), the bits a format takes, and the
 * output names (mr_img_prefixed_name's rule: '_' after a prefix unless it ends in '/', '_', '-' or '.'). */
MR_TEST(texture_set_text_rules) {
    MR_CHECK(mr_texture_constant_like("0.5") && mr_texture_constant_like("0.9,0.6,0.2") &&
             mr_texture_constant_like("1e-3"));
    MR_CHECK(!mr_texture_constant_like("") && !mr_texture_constant_like("./0.5") && !mr_texture_constant_like("a.png"));
    double v[3] = {-1, -1, -1};
    MR_CHECK_OK(mr_texture_constant_parse("0.25", 0, v));
    MR_CHECK(v[0] == 0.25 && v[1] == 0.25 && v[2] == 0.25);
    MR_CHECK_OK(mr_texture_constant_parse("0.9,0.6,0.2", 1, v));
    MR_CHECK(v[0] == 0.9 && v[1] == 0.6 && v[2] == 0.2);
    MR_CHECK(mr_texture_constant_parse("0.9,0.6,0.2", 0, v) == MR_ERR_FORMAT); // three numbers: colour maps only
    MR_CHECK(v[0] == 0.9); // untouched on failure
    MR_CHECK(mr_texture_constant_parse("0.5,0.5", 1, v) == MR_ERR_FORMAT);
    MR_CHECK(mr_texture_constant_parse("0.1,0.2,0.3,0.4", 1, v) == MR_ERR_FORMAT);
    MR_CHECK(mr_texture_constant_parse("1e999", 0, v) == MR_ERR_FORMAT);
    MR_CHECK(mr_texture_constant_parse("0.5,2,-1", 1, v) == MR_ERR_INVALID_ARG);
    MR_CHECK_MSG(strcmp(mr_last_error(), "2 is outside [0, 1]") == 0, "%s", mr_last_error());

    MR_CHECK(strcmp(mr_texture_format_from_name("PNG"), "png") == 0);
    MR_CHECK(strcmp(mr_texture_format_from_name("tiff"), "tif") == 0);
    MR_CHECK(strcmp(mr_texture_format_from_name("Exr"), "exr") == 0);
    MR_CHECK(mr_texture_format_from_name("jpg") == NULL);
    const char *first_exr[3] = {NULL, "maps/d.EXR", "s.tif"}, *first_jpg[2] = {"d.jpg", "s.exr"};
    const char *no_extension[1] = {"maps.v2/diffuse"}, *none[2] = {NULL, NULL};
    MR_CHECK(strcmp(mr_texture_default_format(first_exr, 3), "exr") == 0);
    MR_CHECK(strcmp(mr_texture_default_format(first_jpg, 2), "png") == 0); // the first file decides
    MR_CHECK(strcmp(mr_texture_default_format(no_extension, 1), "png") == 0);
    MR_CHECK(strcmp(mr_texture_default_format(none, 2), "png") == 0);

    MR_CHECK_OK(mr_texture_check_bits("png", 0));
    MR_CHECK_OK(mr_texture_check_bits("tif", 16));
    MR_CHECK_OK(mr_texture_check_bits("exr", 32));
    MR_CHECK(mr_texture_check_bits("exr", 8) == MR_ERR_INVALID_ARG);
    MR_CHECK_MSG(strcmp(mr_last_error(), "exr files take 16 (half) or 32 (float)") == 0, "%s", mr_last_error());
    MR_CHECK(mr_texture_check_bits("png", 32) == MR_ERR_INVALID_ARG);
    MR_CHECK_MSG(strcmp(mr_last_error(), "png files take 8 or 16") == 0, "%s", mr_last_error());

    const mr_texture_layout base = {"basecolor", MR_IMG_COLOR, 3, {0, 0, 0}, {0, 1, 2}};
    char path[64];
    MR_CHECK_OK(mr_texture_output_path("avocado", &base, "png", path, sizeof path));
    MR_CHECK(strcmp(path, "avocado_basecolor.png") == 0);
    MR_CHECK_OK(mr_texture_output_path("out/", &base, "exr", path, sizeof path));
    MR_CHECK(strcmp(path, "out/basecolor.exr") == 0);
    MR_CHECK_OK(mr_texture_output_path("gold-", &base, "tif", path, sizeof path));
    MR_CHECK(strcmp(path, "gold-basecolor.tif") == 0);
    MR_CHECK(mr_texture_output_path("a_very_long_prefix_that_does_not_fit", &base, "png", path, 24) ==
             MR_ERR_INVALID_ARG);
    MR_CHECK_OK(mr_img_prefixed_name(path, sizeof path, "", "alpha.exr"));
    MR_CHECK(strcmp(path, "alpha.exr") == 0);
    MR_CHECK_OK(mr_img_prefixed_name(path, sizeof path, "pfx/ggx.", "alpha.exr"));
    MR_CHECK(strcmp(path, "pfx/ggx.alpha.exr") == 0);
}

/* mr_texture_set_write: a result's images under the prefix and the flag picture, all or none (bits a format does
 * not take: nothing written), read back as written; mr_texture_set_stats: each converted slot's figures. */
MR_TEST(texture_set_written_and_figured) {
    mr_texture_result r = {0};
    MR_CHECK_OK(mr_image_create(2, 1, 3, &r.converted[0]));
    MR_CHECK_OK(mr_image_create(2, 1, 1, &r.converted[1]));
    MR_CHECK_OK(mr_image_create(2, 1, 3, &r.outputs[0]));
    MR_CHECK_OK(mr_image_create(2, 1, 1, &r.outputs[1]));
    r.flags = calloc(2, 1);
    if (r.converted[0] == NULL || r.converted[1] == NULL || r.outputs[0] == NULL || r.outputs[1] == NULL ||
        r.flags == NULL)
        return;
    r.width = 2;
    r.height = 1;
    const float rgb[6] = {0.1f, 0.2f, 0.3f, 0.3f, 0.6f, 0.5f}, grey[2] = {0.25f, 0.75f};
    memcpy(r.converted[0]->pixels, rgb, sizeof rgb);
    memcpy(r.converted[1]->pixels, grey, sizeof grey);
    memcpy(r.outputs[0]->pixels, rgb, sizeof rgb);
    memcpy(r.outputs[1]->pixels, grey, sizeof grey);
    r.flags[1] = MR_WF_CLAMPED_INPUT;

    mr_texture_stats st;
    MR_CHECK_OK(mr_texture_set_stats(&r, 0, &st));
    MR_CHECK(st.channels == 3);
    MR_CHECK(st.min[0] == (double)0.1f && st.max[1] == (double)0.6f);
    MR_CHECK(st.mean[2] == ((double)0.3f + (double)0.5f) / 2.0);
    MR_CHECK_OK(mr_texture_set_stats(&r, 1, &st));
    MR_CHECK(st.channels == 1 && st.min[0] == 0.25 && st.mean[0] == 0.5 && st.max[0] == 0.75);
    MR_CHECK(mr_texture_set_stats(&r, 2, &st) == MR_ERR_INVALID_ARG); // no such slot

    const mr_texture_layout layouts[2] = {{"basecolor", MR_IMG_COLOR, 3, {0, 0, 0}, {0, 1, 2}},
                                          {"metallic", MR_IMG_DATA, 1, {1}, {0}}};
    char prefix[600], flags_path[600], base[640], metal[640];
    snprintf(prefix, sizeof prefix, "%s", mr_test_tmp_path("ws"));
    snprintf(flags_path, sizeof flags_path, "%s", mr_test_tmp_path("ws_flags.png"));
    snprintf(base, sizeof base, "%s_basecolor.png", prefix);
    snprintf(metal, sizeof metal, "%s_metallic.png", prefix);
    mr_texture_write_options wo = {prefix, "-o ws", "png", 8, flags_path, "--flags", NULL, 0};
    wo.bits = 32; // png takes 8 or 16: refused before anything is written
    MR_CHECK(mr_texture_set_write(&r, layouts, 2, &wo) == MR_ERR_INVALID_ARG);
    MR_CHECK(access(base, F_OK) != 0 && access(flags_path, F_OK) != 0);
    wo.bits = 16;
    MR_CHECK_OK(mr_texture_set_write(&r, layouts, 2, &wo));
    mr_image *back = NULL, *picture = NULL, *expected = NULL;
    MR_CHECK_OK(mr_img_read(metal, &(mr_img_read_options){MR_IMG_DATA, 1, 0}, &back));
    if (back != NULL) MR_CHECK_NEAR(back->pixels[1], 0.75, 1.0 / 65535.0);
    mr_image_free(back);
    back = NULL;
    MR_CHECK_OK(mr_img_read(base, NULL, &back)); // colour: sRGB in the file, linear again once read
    if (back != NULL) MR_CHECK(back->channels == 3 && fabs(back->pixels[4] - 0.6) < 1e-3);
    MR_CHECK_OK(mr_img_read(flags_path, &(mr_img_read_options){MR_IMG_DATA, 3, 0}, &picture));
    MR_CHECK_OK(mr_flag_picture(r.flags, 2, 1, &mr_workflow_flag_code, &expected));
    if (picture != NULL && expected != NULL)
        for (int k = 0; k < 6; k++) MR_CHECK_NEAR(picture->pixels[k], expected->pixels[k], 1.0 / 255.0);
    mr_image_free(back);
    mr_image_free(picture);
    mr_image_free(expected);
    mr_texture_result_free(&r);
}

/* mr_transform_convert_material: each slot reads its parameter's bound map or value, as mr_transform_convert_maps
 * would be fed by hand; an RGB output carries the first 4-channel map's alpha; a material of another model is
 * refused. */
MR_TEST(materials_convert_in_one_call) {
    const mr_brdf_model *sg = mr_brdf_find("gltf-specgloss");
    mr_material *m = NULL;
    MR_CHECK_OK(mr_material_create(sg, &m));
    mr_image *diffuse = NULL, *gloss = NULL;
    MR_CHECK_OK(mr_image_create(2, 2, 4, &diffuse));
    MR_CHECK_OK(mr_image_create(2, 2, 1, &gloss));
    for (int k = 0; k < 16; k++) diffuse->pixels[k] = 0.05f * (float)(k + 1);
    for (int k = 0; k < 4; k++) gloss->pixels[k] = 0.2f * (float)(k + 1);
    const int spec_at = mr_brdf_param_offset(sg, mr_brdf_param_index(sg, "specular"));
    for (int c = 0; c < 3; c++) m->values[spec_at + c] = 0.04 + 0.01 * c;
    mr_transform_map in[3] = {{diffuse, 0, 0, {0, 0, 0}, {0}},
                              {NULL, 0, 0, {0.04, 0.05, 0.06}, {0}},
                              {gloss, 0, 0, {0, 0, 0}, {0}}};
    mr_transform *t = NULL;
    MR_CHECK_OK(mr_transform_create(mr_transform_find("gltf-specgloss", "gltf", "weighted"), NULL, &t));
    mr_image *by_hand[3] = {NULL, NULL, NULL}, *out[3] = {NULL, NULL, NULL};
    uint8_t *hand_flags = NULL, *flags = NULL;
    MR_CHECK_OK(mr_transform_convert_maps(t, in, by_hand, &hand_flags));
    MR_CHECK_OK(mr_material_add_map(m, "diffuse", diffuse, 0, "diffuse", NULL)); // m owns them now
    MR_CHECK_OK(mr_material_add_map(m, "glossiness", gloss, 0, "glossiness", NULL));
    MR_CHECK_OK(mr_transform_convert_material(t, m, out, &flags));
    if (out[0] != NULL && by_hand[0] != NULL) {
        MR_CHECK(out[0]->channels == 4 && out[1]->channels == 1 && out[2]->channels == 1);
        for (int k = 0; k < 4; k++) {
            MR_CHECK(memcmp(out[0]->pixels + 4 * k, by_hand[0]->pixels + 3 * k, 3 * sizeof(float)) == 0);
            MR_CHECK(out[0]->pixels[4 * k + 3] == diffuse->pixels[4 * k + 3]);
            MR_CHECK(out[1]->pixels[k] == by_hand[1]->pixels[k] && out[2]->pixels[k] == by_hand[2]->pixels[k]);
            MR_CHECK(flags[k] == hand_flags[k]);
        }
    }
    for (int j = 0; j < 3; j++) {
        mr_image_free(out[j]);
        mr_image_free(by_hand[j]);
        out[j] = NULL;
    }
    free(flags);
    free(hand_flags);
    mr_material *other = NULL;
    MR_CHECK_OK(mr_material_create(mr_brdf_find("gltf"), &other));
    MR_CHECK(mr_transform_convert_material(t, other, out, NULL) == MR_ERR_INVALID_ARG && out[0] == NULL);
    mr_material_free(other);
    mr_material_free(m);
    mr_transform_free(t);
}

MR_TEST_MAIN(MR_TEST_ENTRY(kinds_name_model_parameters),
             MR_TEST_ENTRY(repeated_values_give_the_per_texel_bits),
             MR_TEST_ENTRY(extension_route_moves_values),
             MR_TEST_ENTRY(eq2_and_eq3_invert_each_other),
             MR_TEST_ENTRY(bad_options_are_refused),
             MR_TEST_ENTRY(maps_convert_texel_by_texel),
             MR_TEST_ENTRY(flags_counted_and_drawn_by_their_code),
             MR_TEST_ENTRY(outputs_packed_channel_by_channel),
             MR_TEST_ENTRY(texture_sets_convert_in_one_call),
             MR_TEST_ENTRY(texture_set_text_rules),
             MR_TEST_ENTRY(texture_set_written_and_figured),
             MR_TEST_ENTRY(materials_convert_in_one_call))
