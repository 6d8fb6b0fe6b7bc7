/*
 * test_translate.c — MaterialX's translation graphs (src/remap/translate.h): known answers worked by hand from the
 * nodegraphs of MaterialX 1.39.5 (libraries/bxdf/translation/), the exact errors for pairs without a graph, and
 * the fit-scene comparison against renders made here.
 */
#include <math.h>
#include <string.h>

#include "harness.h"
#include "matremap.h"
#include "remap/translate.h"

/* values[] of `model`: its defaults with the space-separated "name=value" assignments applied. */
static void material(const mr_brdf_model *model, const char *assignments, double *values) {
    mr_brdf_default_values(model, values);
    char copy[512];
    snprintf(copy, sizeof copy, "%s", assignments ? assignments : "");
    for (char *token = strtok(copy, " "); token != NULL; token = strtok(NULL, " "))
        MR_CHECK_OK(mr_brdf_parse_assignment(model, token, values));
}

/* Channel c of parameter `name` in a packed vector of `model`. */
static double value_of(const mr_brdf_model *model, const double *values, const char *name, int c) {
    int index = mr_brdf_param_index(model, name);
    MR_CHECK_MSG(index >= 0, "%s has no parameter %s", model->name, name);
    return index < 0 ? NAN : values[mr_brdf_param_offset(model, index) + (model->params[index].channels == 3 ? c : 0)];
}

/* Translate `assignments` of `from` into `to`; out holds to's values. */
static void translate(const char *from, const char *assignments, const char *to, double *out) {
    const mr_brdf_model *f = mr_brdf_find(from), *t = mr_brdf_find(to);
    MR_CHECK(f != NULL && t != NULL);
    double in[MR_BRDF_MAX_VALUES];
    material(f, assignments, in);
    for (int k = 0; k < MR_BRDF_MAX_VALUES; k++) out[k] = NAN;
    MR_CHECK_OK(mr_translate(f, in, t, out));
}

#define EXPECT(model, out, name, c, expected) MR_CHECK_NEAR(value_of(model, out, name, c), expected, 1e-12)

/* Gold from MaterialX's resources/Materials/Examples/StandardSurface/standard_surface_gold.mtlx, with base 0.5:
 * glTF's base colour is base x base_color, the specular colour (the metal's edge tint in Standard Surface) goes to
 * KHR_materials_specular's specularColorFactor unchanged, roughness stays r (sqrt of the alpha r^2). */
MR_TEST(gold_to_gltf) {
    const mr_brdf_model *gltf = mr_brdf_find("gltf");
    double out[MR_BRDF_MAX_VALUES];
    translate("standard-surface",
              "base=0.5 base_color=0.944,0.776,0.373 specular_color=0.998,0.981,0.751 specular_roughness=0.02 "
              "metalness=1",
              "gltf", out);
    EXPECT(gltf, out, "base_color", 0, 0.472);
    EXPECT(gltf, out, "base_color", 1, 0.388);
    EXPECT(gltf, out, "base_color", 2, 0.1865);
    EXPECT(gltf, out, "metallic", 0, 1.0);
    EXPECT(gltf, out, "roughness", 0, 0.02);
    EXPECT(gltf, out, "specular", 0, 1.0);
    EXPECT(gltf, out, "specular_color", 0, 0.998);
    EXPECT(gltf, out, "specular_color", 2, 0.751);
    EXPECT(gltf, out, "ior", 0, 1.5);
}

/* Copper from standard_surface_copper.mtlx (a white metal under a coloured coat): with coat 1 the base colour
 * becomes coat_color; with coat 0.5 mix(1, coat_color, 0.5). A black coat_color takes the graph's other branch
 * (hasCoatColor = 0): the base colour is left as it is. specular_ior 1.33 goes to ior. */
MR_TEST(coated_copper_to_gltf) {
    const mr_brdf_model *gltf = mr_brdf_find("gltf");
    double out[MR_BRDF_MAX_VALUES];
    const char *copper = "base_color=1 specular=0 specular_roughness=0.25 metalness=1 coat_roughness=0.2 "
                         "coat_color=0.96467984,0.37626296,0.25818297 specular_ior=1.33";
    char text[512];
    snprintf(text, sizeof text, "%s coat=1", copper);
    translate("standard-surface", text, "gltf", out);
    EXPECT(gltf, out, "base_color", 0, 0.96467984);
    EXPECT(gltf, out, "base_color", 1, 0.37626296);
    EXPECT(gltf, out, "base_color", 2, 0.25818297);
    EXPECT(gltf, out, "specular", 0, 0.0);
    EXPECT(gltf, out, "ior", 0, 1.33);
    EXPECT(gltf, out, "roughness", 0, 0.25);
    snprintf(text, sizeof text, "%s coat=0.5", copper);
    translate("standard-surface", text, "gltf", out);
    EXPECT(gltf, out, "base_color", 0, 0.98233992);
    EXPECT(gltf, out, "base_color", 1, 0.68813148);
    EXPECT(gltf, out, "base_color", 2, 0.629091485);
    translate("standard-surface", "base=0.8 base_color=0.5,0.25,1 coat=1 coat_color=0", "gltf", out);
    EXPECT(gltf, out, "base_color", 0, 0.4);
    EXPECT(gltf, out, "base_color", 1, 0.2);
    EXPECT(gltf, out, "base_color", 2, 0.8);
}

/* The same copper into UsdPreviewSurface: diffuseColor = coat_color, clearcoat = mean(coat coat_color) =
 * (0.96467984 + 0.37626296 + 0.25818297)/3; a black coat colour under a full coat makes the diffuse colour black
 * (no branch in this graph). Roughness passes through (alpha = r^2 on both sides). */
MR_TEST(coated_copper_to_usd) {
    const mr_brdf_model *usd = mr_brdf_find("usd-preview");
    double out[MR_BRDF_MAX_VALUES];
    translate("standard-surface",
              "base_color=1 specular=0 specular_roughness=0.01 metalness=1 coat=1 coat_roughness=0.2 "
              "coat_color=0.96467984,0.37626296,0.25818297 specular_ior=1.4",
              "usd-preview", out);
    EXPECT(usd, out, "diffuse_color", 0, 0.96467984);
    EXPECT(usd, out, "diffuse_color", 2, 0.25818297);
    EXPECT(usd, out, "metallic", 0, 1.0);
    EXPECT(usd, out, "roughness", 0, 0.01);
    EXPECT(usd, out, "clearcoat", 0, (0.96467984 + 0.37626296 + 0.25818297) / 3.0);
    EXPECT(usd, out, "clearcoat_roughness", 0, 0.2);
    EXPECT(usd, out, "ior", 0, 1.4);
    EXPECT(usd, out, "use_specular_workflow", 0, 0.0);
    EXPECT(usd, out, "specular_color", 1, 0.0); /* the default: the graph drives the metallic workflow */
    translate("standard-surface", "base_color=0.5 coat=1 coat_color=0", "usd-preview", out);
    EXPECT(usd, out, "diffuse_color", 0, 0.0);
    EXPECT(usd, out, "clearcoat", 0, 0.0);
    translate("standard-surface", "base=0.5 base_color=0.2,0.4,0.6 coat=0.25 coat_color=0.6,0.6,0.2",
              "usd-preview", out);
    EXPECT(usd, out, "diffuse_color", 0, 0.1 * 0.9);
    EXPECT(usd, out, "diffuse_color", 2, 0.3 * 0.8);
    EXPECT(usd, out, "clearcoat", 0, 0.25 * (0.6 + 0.6 + 0.2) / 3.0);
}

/* OpenPBR's coat darkening folded into the base colour. Coat ior 1.5: F0 = 0.04, Kcoat = 1 - 0.96/2.25 =
 * 0.57333..., a dielectric base 0.5: darkening (1 - K)/(1 - 0.5 K) = 0.42667/0.71333 = 0.598131, base colour
 * 0.299065; coat_darkening 0 leaves it; a metal (base_metalness 1, specular_weight 0.5, base 0.8) has
 * Ebase = 0.4, darkening 0.42667/0.77067 = 0.553633. Roughness mix(0.3, 0.1, coat); coat_affect_roughness 1. */
MR_TEST(openpbr_coat_darkening_to_standard_surface) {
    const mr_brdf_model *ss = mr_brdf_find("standard-surface");
    double out[MR_BRDF_MAX_VALUES];
    const double k = 1.0 - 0.96 / 2.25;
    translate("openpbr", "base_color=0.5 coat_weight=1 coat_ior=1.5 coat_roughness=0.1 coat_color=0.9,0.8,0.7",
              "standard-surface", out);
    EXPECT(ss, out, "base_color", 0, 0.5 * (1.0 - k) / (1.0 - 0.5 * k));
    MR_CHECK_NEAR(value_of(ss, out, "base_color", 1), 0.299065, 1e-6);
    EXPECT(ss, out, "specular_roughness", 0, 0.1);
    EXPECT(ss, out, "coat", 0, 1.0);
    EXPECT(ss, out, "coat_color", 2, 0.7);
    EXPECT(ss, out, "coat_roughness", 0, 0.1);
    EXPECT(ss, out, "coat_ior", 0, 1.5);
    EXPECT(ss, out, "coat_affect_roughness", 0, 1.0);
    EXPECT(ss, out, "coat_affect_color", 0, 0.0);
    EXPECT(ss, out, "specular", 0, 1.0);
    EXPECT(ss, out, "specular_ior", 0, 1.5);
    translate("openpbr", "base_color=0.5 coat_weight=1 coat_ior=1.5 coat_darkening=0", "standard-surface", out);
    EXPECT(ss, out, "base_color", 0, 0.5);
    EXPECT(ss, out, "coat_roughness", 0, 0.01); /* openpbr's default 0, into the floor */
    translate("openpbr",
              "base_color=0.8 base_metalness=1 specular_weight=0.5 specular_color=0.9,0.8,0.7 "
              "specular_roughness=0.3 coat_weight=0.5 coat_ior=1.5 coat_roughness=0.1 specular_ior=1.7",
              "standard-surface", out);
    const double d = (1.0 - k) / (1.0 - 0.4 * k);
    MR_CHECK_NEAR(d, 0.553633, 1e-6);
    EXPECT(ss, out, "base_color", 0, 0.8 * (0.5 + 0.5 * d));
    EXPECT(ss, out, "metalness", 0, 1.0);
    EXPECT(ss, out, "specular", 0, 0.5);
    EXPECT(ss, out, "specular_color", 1, 0.8);
    EXPECT(ss, out, "specular_roughness", 0, 0.2);
    EXPECT(ss, out, "specular_ior", 0, 1.7);
    EXPECT(ss, out, "coat", 0, 0.5);
}

/* Without a coat every graph is a pass-through of what the target holds: OpenPBR's defaults into Standard
 * Surface keep base_color 0.8 and roughness 0.3 (coat_weight 0: no darkening, no roughness mix). */
MR_TEST(uncoated_is_pass_through) {
    const mr_brdf_model *ss = mr_brdf_find("standard-surface");
    double out[MR_BRDF_MAX_VALUES];
    translate("openpbr", "base_diffuse_roughness=0.4 base_weight=0.9", "standard-surface", out);
    EXPECT(ss, out, "base_color", 0, 0.8);
    EXPECT(ss, out, "base", 0, 0.9);
    EXPECT(ss, out, "diffuse_roughness", 0, 0.4);
    EXPECT(ss, out, "specular_roughness", 0, 0.3);
    EXPECT(ss, out, "coat", 0, 0.0);
    const mr_brdf_model *gltf = mr_brdf_find("gltf");
    translate("standard-surface", "", "gltf", out);
    EXPECT(gltf, out, "base_color", 1, 0.8);
    EXPECT(gltf, out, "metallic", 0, 0.0);
    EXPECT(gltf, out, "roughness", 0, 0.2);
}

/* Pairs without a graph: the exact message, nothing written. */
MR_TEST(unsupported_pairs) {
    const mr_brdf_model *gltf = mr_brdf_find("gltf"), *openpbr = mr_brdf_find("openpbr");
    const mr_brdf_model *ss = mr_brdf_find("standard-surface");
    const mr_translation *t = NULL;
    MR_CHECK(mr_translate_find(gltf, openpbr, &t) == MR_ERR_UNSUPPORTED);
    MR_CHECK(t == NULL);
    MR_CHECK_MSG(strcmp(mr_last_error(), "no MaterialX translation graph from 'gltf' to 'openpbr' (graphs: "
                                         "standard-surface -> gltf, standard-surface -> usd-preview, openpbr -> "
                                         "standard-surface)") == 0,
                 "%s", mr_last_error());
    double in[MR_BRDF_MAX_VALUES], out[MR_BRDF_MAX_VALUES];
    mr_brdf_default_values(ss, in);
    out[0] = 42.0;
    MR_CHECK(mr_translate(ss, in, openpbr, out) == MR_ERR_UNSUPPORTED);
    MR_CHECK(strstr(mr_last_error(), "from 'standard-surface' to 'openpbr'") != NULL);
    MR_CHECK(out[0] == 42.0);
    MR_CHECK(mr_translate_find(NULL, gltf, &t) == MR_ERR_INVALID_ARG);
    MR_CHECK_OK(mr_translate_find(ss, gltf, &t));
    MR_CHECK(t != NULL && strcmp(t->graph, "NG_standard_surface_to_gltf_pbr") == 0);
    int count = 0;
    for (const mr_translation *const *k = mr_translations(); *k != NULL; k++) {
        MR_CHECK(mr_brdf_find((*k)->from) != NULL && mr_brdf_find((*k)->to) != NULL);
        count++;
    }
    MR_CHECK(count == 3);
    in[mr_brdf_param_offset(ss, mr_brdf_param_index(ss, "coat"))] = NAN;
    MR_CHECK(mr_translate(ss, in, gltf, out) == MR_ERR_INVALID_ARG);
    MR_CHECK_MSG(strcmp(mr_last_error(), "translate: standard-surface coat = nan: expected a finite value") == 0, "%s",
                 mr_last_error());
}

/* mr_translate_compare measures what a render made here measures: the same values, the same SSIM and RMSE. And a
 * plain dielectric, which every graph carries, renders nearly alike on both sides (different BRDFs: exact Fresnel
 * against Schlick), while the coated copper into glTF, whose clearcoat the gltf model cannot hold, does not. */
MR_TEST(compare_matches_renders) {
    mr_fit_scene_options o = {0};
    o.size = 48;
    mr_scene scene = mr_scene_fit(&o);
    mr_render_plan *plan = NULL;
    MR_CHECK_OK(mr_render_plan_create(&scene, &plan));
    const mr_brdf_model *ss = mr_brdf_find("standard-surface"), *usd = mr_brdf_find("usd-preview");
    const mr_brdf_model *gltf = mr_brdf_find("gltf");
    double in[MR_BRDF_MAX_VALUES], out[MR_BRDF_MAX_VALUES];
    material(ss, "base_color=0.6,0.3,0.1 specular_roughness=0.4", in);
    mr_translate_result r;
    MR_CHECK_OK(mr_translate_compare(plan, ss, in, usd, &r));
    MR_CHECK_OK(mr_translate(ss, in, usd, out));
    MR_CHECK(memcmp(out, r.values, (size_t)mr_brdf_value_count(usd) * sizeof *out) == 0);
    mr_image *a = NULL, *b = NULL;
    MR_CHECK_OK(mr_render(plan, ss, in, MR_COMPONENT_FULL, &a));
    MR_CHECK_OK(mr_render(plan, usd, out, MR_COMPONENT_FULL, &b));
    double ssim = 0.0, rmse = 0.0;
    MR_CHECK_OK(mr_ssim(b, a, NULL, &ssim, NULL));
    MR_CHECK_OK(mr_rmse(b, a, &rmse));
    MR_CHECK(ssim == r.ssim && rmse == r.rmse);
    MR_CHECK_MSG(r.ssim > 0.99 && r.relative_rmse < 0.1, "ssim %g, relative rmse %g", r.ssim, r.relative_rmse);
    mr_image_free(a);
    mr_image_free(b);
    material(ss, "base_color=1 specular=0 specular_roughness=0.25 metalness=1 coat=1 coat_roughness=0.2 "
                 "coat_color=0.96467984,0.37626296,0.25818297", in);
    mr_translate_result coated;
    MR_CHECK_OK(mr_translate_compare(plan, ss, in, gltf, &coated));
    MR_CHECK_MSG(coated.relative_rmse > r.relative_rmse, "coated %g, plain %g", coated.relative_rmse,
                 r.relative_rmse);
    MR_CHECK(mr_translate_compare(plan, gltf, out, ss, &coated) == MR_ERR_UNSUPPORTED);
    mr_render_plan_free(plan);
}

MR_TEST_MAIN(MR_TEST_ENTRY(gold_to_gltf),
             MR_TEST_ENTRY(coated_copper_to_gltf),
             MR_TEST_ENTRY(coated_copper_to_usd),
             MR_TEST_ENTRY(openpbr_coat_darkening_to_standard_surface),
             MR_TEST_ENTRY(uncoated_is_pass_through),
             MR_TEST_ENTRY(unsupported_pairs),
             MR_TEST_ENTRY(compare_matches_renders))
