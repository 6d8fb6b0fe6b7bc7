/*
 * test_doc.c — material documents (src/doc/doc.h) without the command line: every parameter of the four written
 * models maps to an input its node declares, with the right type; the writers write only declared inputs (every
 * `<input name=` of a node in the MaterialX text and every `inputs:NAME` of a Shader in the USD text is looked up in
 * the node tables); colour spaces follow the one rule (sRGB for MR_PARAM_SRGB_MAP parameters in 8/16-bit files,
 * data otherwise, float files linear); bad values are refused; the write is atomic (a failed write leaves the old
 * file). tests/export_cli.sh parses the files back with python3's XML parser.
 */
#include "doc/doc.h" /* first: the header is self-contained */

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "matremap.h"

#include "harness.h"

static const char *const models[] = {"openpbr", "standard-surface", "gltf", "usd-preview"};

static int declared(mr_doc_format format, const char *node, const char *input, const char **type) {
    int n = 0;
    const mr_doc_node_input *in = mr_doc_node_inputs(format, node, &n);
    for (int i = 0; i < n; i++)
        if (strcmp(in[i].name, input) == 0) {
            if (type) *type = in[i].type;
            return 1;
        }
    return 0;
}

MR_TEST(every_parameter_maps_to_a_declared_input) {
    for (size_t k = 0; k < sizeof(models) / sizeof(models[0]); k++) {
        const mr_brdf_model *model = mr_brdf_find(models[k]);
        MR_CHECK(model != NULL);
        mr_doc_format format = strcmp(models[k], "usd-preview") == 0 ? MR_DOC_FORMAT_USDA : MR_DOC_FORMAT_MTLX;
        const char *node = mr_doc_surface_node(model, format);
        MR_CHECK(node != NULL);
        for (int p = 0; p < model->param_count; p++) {
            const char *input = mr_doc_input_name(model, p, format), *type = NULL;
            MR_CHECK_MSG(input && declared(format, node, input, &type), "%s.%s -> %s", models[k],
                         model->params[p].name, input ? input : "(none)");
            if (type == NULL) continue;
            const char *want = model->params[p].role == MR_PARAM_SWITCH ? "int"
                               : model->params[p].channels == 3 ? (format == MR_DOC_FORMAT_USDA ? "color3f" : "color3")
                                                                : "float";
            MR_CHECK_MSG(strcmp(type, want) == 0, "%s.%s: %s, not %s", models[k], input, type, want);
        }
    }
    MR_CHECK(strcmp(mr_doc_input_name(mr_brdf_find("usd-preview"), 0, MR_DOC_FORMAT_USDA), "diffuseColor") == 0);
    MR_CHECK(mr_doc_surface_node(mr_brdf_find("usd-preview"), MR_DOC_FORMAT_MTLX) == NULL);
    MR_CHECK(mr_doc_surface_node(mr_brdf_find("openpbr"), MR_DOC_FORMAT_USDA) == NULL);
    MR_CHECK(mr_doc_surface_node(mr_brdf_find("ggx"), MR_DOC_FORMAT_MTLX) == NULL);
}

/* A document with constants and maps of every kind (colour, scalar by channel incl. alpha, scaled, UV set 1). */
static mr_doc *sample(const char *model_name) {
    const mr_brdf_model *model = mr_brdf_find(model_name);
    mr_doc *doc = mr_doc_create();
    mr_doc_material *m = NULL;
    MR_CHECK_OK(mr_doc_add_material(doc, "Brushed metal #1", model, &m));
    int colour = -1, scalar = -1, scalar2 = -1;
    for (int p = 0; p < model->param_count; p++) {
        const mr_brdf_param *d = &model->params[p];
        if (d->channels == 3 && colour < 0)
            colour = p;
        else if (d->channels == 1 && d->role != MR_PARAM_SWITCH && scalar < 0)
            scalar = p;
        else if (d->channels == 1 && d->role != MR_PARAM_SWITCH && scalar2 < 0)
            scalar2 = p;
        else
            MR_CHECK_OK(mr_doc_set_constant(m, d->name, (double[3]){0.25, 0.5, 0.75}));
    }
    MR_CHECK_OK(mr_doc_set_texture(m, model->params[colour].name, "base.png", -1, 0, (double[3]){0.5, 1, 1}));
    MR_CHECK_OK(mr_doc_set_texture_wrap(m, model->params[colour].name, MR_DOC_WRAP_CLAMP, MR_DOC_WRAP_MIRROR));
    MR_CHECK_OK(mr_doc_set_texture(m, model->params[scalar].name, "mr.png", 2, 1, NULL));
    MR_CHECK_OK(mr_doc_set_texture(m, model->params[scalar2].name, "mr.png", 3, 0, (double[1]){0.5}));
    mr_doc_material *m2 = NULL;
    MR_CHECK_OK(mr_doc_add_material(doc, "Brushed metal #1", model, &m2)); // the same name: made unique
    MR_CHECK_OK(mr_doc_set_texture(m2, model->params[colour].name, "base.exr", -1, 0, NULL));
    return doc;
}

static int count(const char *text, const char *what) {
    int n = 0;
    for (const char *p = strstr(text, what); p; p = strstr(p + 1, what)) n++;
    return n;
}

MR_TEST(mtlx_writes_declared_inputs_only) {
    for (int k = 0; k < 3; k++) {
        mr_doc *doc = sample(models[k]);
        // Extras too (inputs of lobes the models do not have), written after the parameters.
        static const char *const extra[3][2] = {{"emission_color", "color3"}, {"thin_walled", "boolean"},
                                                {"alpha_mode", "integer"}};
        MR_CHECK_OK(mr_doc_add_extra(mr_doc_material_at(doc, 0), extra[k][0], extra[k][1], (double[3]){1, 1, 1}));
        MR_CHECK(mr_doc_add_extra(mr_doc_material_at(doc, 0), "nope", "float", (double[1]){1}) == MR_ERR_INVALID_ARG);
        MR_CHECK(mr_doc_add_extra(mr_doc_material_at(doc, 0), extra[k][0], "float", (double[1]){1}) ==
                 MR_ERR_INVALID_ARG); // the declared type only
        char *text = NULL;
        MR_CHECK_OK(mr_doc_to_text(doc, MR_DOC_FORMAT_MTLX, &text));
        // Each element <NODE name=".." type="T"> opens a node; each <input name="X" inside it is declared by it.
        char node[96] = "";
        for (char *line = strtok(text, "\n"); line; line = strtok(NULL, "\n")) {
            while (*line == ' ') line++;
            char name[64], type[64];
            if (sscanf(line, "<input name=\"%63[^\"]\"", name) == 1) {
                MR_CHECK_MSG(node[0] && declared(MR_DOC_FORMAT_MTLX, node, name, NULL), "%s: input %s", node, name);
            } else if (sscanf(line, "<%63[a-z_] name=\"%*[^\"]\" type=\"%63[^\"]\"", node, type) == 2) {
                // The stdlib nodes are named in the table by their output type; extract by its input's (float out;
                // extract_color3 and _color4 declare the same input names).
                if (strcmp(node, "extract") == 0) {
                    snprintf(node, sizeof node, "extract_color3");
                } else if (strcmp(node, "image") == 0 || strcmp(node, "multiply") == 0 ||
                           strcmp(node, "texcoord") == 0) {
                    char full[96];
                    snprintf(full, sizeof full, "%.40s_%.40s", node, type);
                    snprintf(node, sizeof node, "%s", full);
                }
                if (strcmp(node, "output") == 0) node[0] = '\0';
            }
        }
        free(text);
        MR_CHECK_OK(mr_doc_to_text(doc, MR_DOC_FORMAT_MTLX, &text));
        MR_CHECK(strstr(text, "<materialx version=\"1.39\" colorspace=\"lin_rec709\">") != NULL);
        MR_CHECK_MSG(count(text, "colorspace=\"srgb_texture\"") == 1, "%s", text); // base.png; not base.exr nor mr.png
        MR_CHECK(strstr(text, "value=\"base.exr\" />") != NULL);
        MR_CHECK(count(text, "<surfacematerial ") == 2 && strstr(text, "name=\"Brushed_metal__1_2\"") != NULL);
        MR_CHECK(strstr(text, "<input name=\"index\" type=\"integer\" value=\"3\" />") != NULL); // alpha
        MR_CHECK(strstr(text, "<image name=") != NULL && strstr(text, "type=\"color4\"") != NULL);
        MR_CHECK(strstr(text, "<input name=\"in2\" type=\"color3\" value=\"0.5, 1, 1\" />") != NULL);
        MR_CHECK(strstr(text, "<texcoord ") != NULL);
        MR_CHECK(strstr(text, "<input name=\"uaddressmode\" type=\"string\" value=\"clamp\" />") != NULL);
        MR_CHECK(strstr(text, "<input name=\"vaddressmode\" type=\"string\" value=\"mirror\" />") != NULL);
        free(text);
        MR_CHECK(mr_doc_to_text(doc, MR_DOC_FORMAT_USDA, &text) == MR_ERR_INVALID_ARG);
        MR_CHECK(strstr(mr_last_error(), "does not write") != NULL);
        mr_doc_free(doc);
    }
}

MR_TEST(usda_writes_declared_inputs_only) {
    mr_doc *doc = sample("usd-preview");
    MR_CHECK_OK(mr_doc_add_extra(mr_doc_material_at(doc, 0), "emissiveColor", "color3", (double[3]){1, 0.5, 0}));
    MR_CHECK_OK(mr_doc_add_extra(mr_doc_material_at(doc, 0), "opacityMode", "integer", (double[1]){0}));
    MR_CHECK(mr_doc_add_extra(mr_doc_material_at(doc, 0), "metallic", "float", (double[1]){0}) ==
             MR_ERR_INVALID_ARG); // a parameter of the model, not an extra
    char *text = NULL;
    MR_CHECK_OK(mr_doc_to_text(doc, MR_DOC_FORMAT_USDA, &text));
    char *copy = strdup(text);
    const char *node = NULL;
    for (char *line = strtok(copy, "\n"); line; line = strtok(NULL, "\n")) {
        char id[64], name[64];
        if (sscanf(line, " uniform token info:id = \"%63[^\"]\"", id) == 1) {
            node = strcmp(id, "UsdPreviewSurface") == 0    ? "UsdPreviewSurface"
                   : strcmp(id, "UsdUVTexture") == 0       ? "UsdUVTexture"
                   : strcmp(id, "UsdPrimvarReader_float2") == 0 ? "UsdPrimvarReader_float2"
                                                                 : NULL;
            MR_CHECK_MSG(node != NULL, "unknown shader %s", id);
        }
        const char *in = strstr(line, " inputs:");
        if (in && strstr(line, "def ") == NULL && sscanf(in, " inputs:%63[A-Za-z0-9_]", name) == 1)
            MR_CHECK_MSG(node && declared(MR_DOC_FORMAT_USDA, node, name, NULL), "%s: inputs:%s", node, name);
        const char *outp = strstr(line, "outputs:");
        if (outp && node && strstr(line, ".connect") == NULL && sscanf(outp, "outputs:%63[A-Za-z0-9_]", name) == 1) {
            int n = 0, found = 0;
            const mr_doc_node_input *o = mr_doc_node_outputs(MR_DOC_FORMAT_USDA, node, &n);
            for (int i = 0; i < n; i++) found |= strcmp(o[i].name, name) == 0;
            MR_CHECK_MSG(found, "%s: outputs:%s", node, name);
        }
        if (strstr(line, "def Material") != NULL) node = NULL;
    }
    free(copy);
    MR_CHECK(strstr(text, "#usda 1.0") == text);
    MR_CHECK(count(text, "sourceColorSpace = \"sRGB\"") == 1 && count(text, "sourceColorSpace = \"raw\"") == 3);
    MR_CHECK(strstr(text, "token inputs:varname = \"st\"") && strstr(text, "token inputs:varname = \"st1\""));
    MR_CHECK(strstr(text, "outputs:rgb>") && strstr(text, "outputs:b>") && strstr(text, "outputs:a>"));
    MR_CHECK(strstr(text, "float4 inputs:scale = (0.5, 1, 1, 1)") != NULL);
    MR_CHECK(strstr(text, "token inputs:wrapS = \"clamp\"") && strstr(text, "token inputs:wrapT = \"mirror\""));
    MR_CHECK(strstr(text, "int inputs:useSpecularWorkflow = 0") != NULL); // 0.25 rounds to 0
    MR_CHECK(strstr(text, "color3f inputs:emissiveColor = (1, 0.5, 0)") != NULL);
    MR_CHECK(strstr(text, "token inputs:opacityMode = \"transparent\"") != NULL);
    free(text);
    mr_doc_free(doc);
}

MR_TEST(the_colour_space_rule) {
    const mr_brdf_model *op = mr_brdf_find("openpbr");
    const mr_brdf_param *colour = &op->params[mr_brdf_param_index(op, "base_color")];
    const mr_brdf_param *rough = &op->params[mr_brdf_param_index(op, "specular_roughness")];
    MR_CHECK(mr_doc_texture_is_srgb(colour, "a.png") == 1 && mr_doc_texture_is_srgb(colour, "a.JPG") == 1);
    MR_CHECK(mr_doc_texture_is_srgb(colour, "a.exr") == 0 && mr_doc_texture_is_srgb(colour, "a.HDR") == 0);
    MR_CHECK(mr_doc_texture_is_srgb(rough, "a.png") == 0);
}

/* The metallic workflow's layer leaves out a constant specularColor (no effect by the specification; three.js's
 * USDLoader would take it as the dielectric's F0 tint); the specular workflow's keeps it. */
MR_TEST(usda_specular_color_only_in_the_specular_workflow) {
    const mr_brdf_model *usd = mr_brdf_find("usd-preview");
    for (int workflow = -1; workflow <= 1; workflow++) { // -1: useSpecularWorkflow unset, the node's default 0
        mr_doc *doc = mr_doc_create();
        mr_doc_material *m = NULL;
        MR_CHECK_OK(mr_doc_add_material(doc, "x", usd, &m));
        MR_CHECK_OK(mr_doc_set_constant(m, "specular_color", (double[3]){0.25, 0.5, 0.75}));
        MR_CHECK_OK(mr_doc_set_constant(m, "metallic", (double[1]){0}));
        if (workflow >= 0) MR_CHECK_OK(mr_doc_set_constant(m, "use_specular_workflow", (double[1]){workflow}));
        char *text = NULL;
        MR_CHECK_OK(mr_doc_to_text(doc, MR_DOC_FORMAT_USDA, &text));
        int written = text && strstr(text, "color3f inputs:specularColor = (0.25, 0.5, 0.75)") != NULL;
        MR_CHECK_MSG(written == (workflow == 1), "workflow %d:\n%s", workflow, text ? text : "");
        MR_CHECK(text && strstr(text, "float inputs:metallic = 0") != NULL);
        free(text);
        mr_doc_free(doc);
    }
}

MR_TEST(bad_values_are_refused) {
    const mr_brdf_model *usd = mr_brdf_find("usd-preview");
    mr_doc *doc = mr_doc_create();
    mr_doc_material *m = NULL;
    MR_CHECK(mr_doc_add_material(doc, "x", mr_brdf_find("ggx"), &m) == MR_ERR_INVALID_ARG);
    MR_CHECK_OK(mr_doc_add_material(doc, "x", usd, &m));
    MR_CHECK(mr_doc_set_constant(m, "nope", (double[3]){0, 0, 0}) == MR_ERR_INVALID_ARG);
    MR_CHECK(mr_doc_set_texture(m, "diffuse_color", "a.png", 1, 0, NULL) == MR_ERR_INVALID_ARG);
    MR_CHECK(mr_doc_set_texture(m, "use_specular_workflow", "a.png", 0, 0, NULL) == MR_ERR_INVALID_ARG);
    MR_CHECK(mr_doc_set_texture(m, "metallic", "a@b.png", 0, 0, NULL) == MR_ERR_INVALID_ARG);
    MR_CHECK(mr_doc_set_texture(m, "metallic", "a.png", 4, 0, NULL) == MR_ERR_INVALID_ARG);
    MR_CHECK(mr_doc_set_texture(m, "metallic", "a.png", 0, -1, NULL) == MR_ERR_INVALID_ARG);
    MR_CHECK(mr_doc_set_texture_wrap(m, "metallic", MR_DOC_WRAP_CLAMP, MR_DOC_WRAP_CLAMP) == MR_ERR_INVALID_ARG);
    MR_CHECK(mr_doc_format_from_path("a.MTLX") == MR_DOC_FORMAT_MTLX && mr_doc_format_from_path("a.usd") == 0);
    MR_CHECK(mr_doc_write(doc, mr_test_tmp_path("x.txt")) == MR_ERR_INVALID_ARG);
    mr_doc_free(doc);
}

MR_TEST(the_write_is_atomic) {
    const char *path = mr_test_tmp_path("doc.mtlx");
    MR_CHECK(mr_test_write_file(path, "old", 3) == 1);
    mr_doc *doc = mr_doc_create();
    MR_CHECK_OK(mr_doc_add_material(doc, "u", mr_brdf_find("usd-preview"), NULL));
    MR_CHECK(mr_doc_write(doc, path) == MR_ERR_INVALID_ARG); // usd-preview in .mtlx: refused, nothing written
    size_t size = 0;
    char *text = mr_test_read_file(path, &size);
    MR_CHECK(text && size == 3 && memcmp(text, "old", 3) == 0);
    free(text);
    mr_doc_free(doc);
    doc = mr_doc_create();
    MR_CHECK_OK(mr_doc_add_material(doc, "g", mr_brdf_find("gltf"), NULL));
    MR_CHECK_OK(mr_doc_write(doc, path));
    text = mr_test_read_file(path, &size);
    MR_CHECK(text && strstr(text, "<gltf_pbr name=\"SR_g\"") != NULL);
    free(text);
    mr_doc_free(doc);
}

/* A uniform glTF material to usd-preview and openpbr: fitted by a remap in remap's default fit scene (size 0), whose
 * verdict and SSIM the result carries; a plastic and a gold metal both converge and match. */
MR_TEST(uniform_materials_are_remapped_and_converge) {
    static const char asset_text[] =
        "{\"asset\": {\"version\": \"2.0\"}, \"materials\": ["
        "{\"name\": \"Gold\", \"pbrMetallicRoughness\": {\"baseColorFactor\": [1.0, 0.77, 0.34, 1], "
        "\"metallicFactor\": 1.0, \"roughnessFactor\": 0.3}}, "
        "{\"name\": \"Red plastic\", \"pbrMetallicRoughness\": {\"baseColorFactor\": [0.6, 0.05, 0.04, 1], "
        "\"metallicFactor\": 0.0, \"roughnessFactor\": 0.5}}]}";
    const char *path = mr_test_tmp_path("uniform.gltf");
    MR_CHECK(mr_test_write_file(path, asset_text, sizeof asset_text - 1) == 1);
    mr_gltf *asset = NULL;
    MR_CHECK_OK(mr_gltf_load(path, &asset));
    if (asset == NULL) return;
    const char *targets[] = {"usd-preview", "openpbr"};
    for (int t = 0; t < 2; t++) {
        mr_doc_gltf_options o = {0};
        o.target = mr_brdf_find(targets[t]);
        mr_doc_gltf_result *r = NULL;
        MR_CHECK_OK(mr_doc_from_gltf(asset, &o, &r));
        if (r == NULL) continue;
        MR_CHECK(r->material_count == 2 && r->image_count == 0);
        for (int k = 0; k < r->material_count; k++) {
            const mr_doc_gltf_material *m = &r->materials[k];
            MR_CHECK_MSG(m->route == MR_DOC_ROUTE_REMAP && m->outcome == MR_FIT_CONVERGED && m->ssim > 0.999,
                         "%s %s: route %d, outcome %d, SSIM %.5f (%s)", targets[t], m->name, (int)m->route,
                         m->outcome, m->ssim, m->detail);
        }
        mr_doc_gltf_result_free(r);
    }
    mr_gltf_free(asset);
}

/* The one route decision (doc.h, mr_doc_choose_route) that every document export calls. */
MR_TEST(the_route_decision) {
    const mr_brdf_model *gltf = mr_brdf_find("gltf"), *op = mr_brdf_find("openpbr"),
                        *ss = mr_brdf_find("standard-surface"), *usd = mr_brdf_find("usd-preview");
    static const struct {
        int source, target, textured, transforms;
        mr_doc_route want;
    } cases[] = {
        {0, 0, 0, 0, MR_DOC_ROUTE_COPY},   {0, 1, 0, 0, MR_DOC_ROUTE_REMAP},  {0, 1, 0, 1, MR_DOC_ROUTE_REMAP},
        {0, 3, 0, 0, MR_DOC_ROUTE_REMAP},  {0, 0, 1, 0, MR_DOC_ROUTE_MAPS},   {0, 3, 1, 0, MR_DOC_ROUTE_MAPS},
        {0, 3, 1, 1, MR_DOC_ROUTE_MAPS},   {0, 1, 1, 0, MR_DOC_ROUTE_DIRECT}, {0, 2, 1, 0, MR_DOC_ROUTE_DIRECT},
        {0, 1, 1, 1, MR_DOC_ROUTE_LEARNED}, {0, 2, 1, 1, MR_DOC_ROUTE_LEARNED}, {1, 1, 1, 0, MR_DOC_ROUTE_MAPS},
        {1, 2, 0, 0, MR_DOC_ROUTE_REMAP},  {1, 2, 1, 0, MR_DOC_ROUTE_DIRECT},
        // a MaterialX document's materials (mr_doc_convert): usd-preview's maps back to gltf, the rest direct
        {3, 0, 1, 0, MR_DOC_ROUTE_MAPS},   {3, 0, 0, 0, MR_DOC_ROUTE_REMAP},  {2, 1, 1, 0, MR_DOC_ROUTE_DIRECT},
        {3, 1, 1, 0, MR_DOC_ROUTE_DIRECT}, {2, 0, 1, 1, MR_DOC_ROUTE_LEARNED},
    };
    const mr_brdf_model *m[4] = {gltf, op, ss, usd};
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        mr_doc_route r = (mr_doc_route)-1;
        MR_CHECK_OK(mr_doc_choose_route(m[cases[i].source], m[cases[i].target], cases[i].textured,
                                        cases[i].transforms, &r));
        MR_CHECK_MSG(r == cases[i].want, "%s -> %s textured %d transforms %d: %s, expected %s",
                     m[cases[i].source]->name, m[cases[i].target]->name, cases[i].textured, cases[i].transforms,
                     mr_doc_route_name(r) ? mr_doc_route_name(r) : "?", mr_doc_route_name(cases[i].want));
    }
    mr_doc_route r;
    MR_CHECK(mr_doc_choose_route(NULL, op, 1, 0, &r) == MR_ERR_INVALID_ARG);
    MR_CHECK(strcmp(mr_doc_route_name(MR_DOC_ROUTE_DIRECT), "direct") == 0 &&
             strcmp(mr_doc_route_name(MR_DOC_ROUTE_LEARNED), "learned") == 0);
}

/* A textured glTF material to openpbr by the direct route, without the command line: 4 x 4 maps (two base colours,
 * two roughnesses, metallic 0) converted, the target's default holds written as constants (specular_ior 1.5), a
 * caller's hold (base_metalness=0.25) too, the parameters that vary as maps of the map's size the result owns; the
 * counts of the conversion carried; a material whose maps lie on two UV sets refused, naming both textures. */
MR_TEST(a_textured_material_converts_by_the_direct_route) {
    mr_image *base = NULL, *mr = NULL;
    MR_CHECK_OK(mr_image_create(4, 4, 3, &base));
    MR_CHECK_OK(mr_image_create(4, 4, 3, &mr));
    if (base == NULL || mr == NULL) return;
    for (int i = 0; i < 16; i++)
        for (int c = 0; c < 3; c++) {
            base->pixels[i * 3 + c] = i < 8 ? 0.5f : (c == 0 ? 0.8f : 0.2f);
            mr->pixels[i * 3 + c] = c == 1 ? (i % 2 ? 0.3f : 0.7f) : 0.0f;
        }
    mr_img_write_options colour = {MR_IMG_COLOR, 8, 0}, data = {MR_IMG_DATA, 8, 0};
    MR_CHECK_OK(mr_img_write(mr_test_tmp_path("route_base.png"), base, &colour));
    MR_CHECK_OK(mr_img_write(mr_test_tmp_path("route_mr.png"), mr, &data));
    mr_image_free(base);
    mr_image_free(mr);
    char text[1024];
    for (int uv1 = 0; uv1 < 2; uv1++) {
        snprintf(text, sizeof text,
                 "{\"asset\": {\"version\": \"2.0\"}, \"images\": [{\"uri\": \"route_base.png\"}, {\"uri\": "
                 "\"route_mr.png\"}], \"textures\": [{\"source\": 0}, {\"source\": 1}], \"materials\": [{\"name\": "
                 "\"T\", \"pbrMetallicRoughness\": {\"baseColorTexture\": {\"index\": 0}, "
                 "\"metallicRoughnessTexture\": {\"index\": 1, \"texCoord\": %d}}}]}", uv1);
        const char *path = mr_test_tmp_path("route.gltf");
        MR_CHECK(mr_test_write_file(path, text, strlen(text)) == 1);
        mr_gltf *asset = NULL;
        MR_CHECK_OK(mr_gltf_load(path, &asset));
        if (asset == NULL) return;
        const mr_brdf_model *op = mr_brdf_find("openpbr");
        double values[MR_BRDF_MAX_VALUES];
        unsigned held = 0;
        mr_brdf_default_values(op, values);
        MR_CHECK_OK(mr_brdf_parse_holds(op, "base_metalness=0.25", values, &held));
        mr_doc_gltf_options o = {0};
        o.target = op;
        o.image_prefix = mr_test_tmp_path("route_out");
        o.size = 16;
        o.threads = 1;
        o.target_values = values;
        o.held = held;
        mr_doc_gltf_result *r = NULL;
        mr_status st = mr_doc_from_gltf(asset, &o, &r);
        mr_gltf_free(asset);
        if (uv1) {
            MR_CHECK(st == MR_ERR_UNSUPPORTED && r == NULL);
            MR_CHECK_MSG(strstr(mr_last_error(), "baseColorTexture and metallicRoughnessTexture differ in UV set"),
                         "%s", mr_last_error());
            continue;
        }
        MR_CHECK_OK(st);
        if (r == NULL) return;
        const mr_doc_gltf_material *m = &r->materials[0];
        MR_CHECK_MSG(m->route == MR_DOC_ROUTE_DIRECT && m->texels == 16 && m->width == 4 && m->unique == 4,
                     "route %s, %zu texels, %zu distinct", mr_doc_route_name(m->route), m->texels, m->unique);
        const mr_doc_material *dm = mr_doc_material_get(r->doc, 0);
        const int ior = mr_brdf_param_index(op, "specular_ior"), metal = mr_brdf_param_index(op, "base_metalness");
        const int colour_p = mr_brdf_param_index(op, "base_color");
        const int rough = mr_brdf_param_index(op, "specular_roughness");
        MR_CHECK(dm->values[ior].kind == MR_DOC_CONSTANT && dm->values[ior].constant[0] == 1.5); // tied: exact
        MR_CHECK(dm->values[metal].kind == MR_DOC_CONSTANT && dm->values[metal].constant[0] == 0.25);
        MR_CHECK(dm->values[colour_p].kind == MR_DOC_TEXTURE && dm->values[rough].kind == MR_DOC_TEXTURE);
        int maps = 0;
        for (int i = 0; i < r->map_count; i++) {
            MR_CHECK(r->maps[i].image->width == 4 && r->maps[i].image->height == 4);
            maps += r->maps[i].param == colour_p || r->maps[i].param == rough || r->maps[i].param == -1;
        }
        MR_CHECK_MSG(r->map_count == 3 && maps == 3, "%d maps", r->map_count);
        mr_doc_gltf_result_free(r);
    }
}

/* ---- reading MaterialX (mtlx_read.c) ------------------------------------------------------------------------- */

static void same_values(const mr_doc_material *a, const mr_doc_material *b) {
    MR_CHECK(a->model == b->model);
    for (int p = 0; p < a->model->param_count; p++) {
        const mr_doc_value *x = &a->values[p], *y = &b->values[p];
        const char *name = a->model->params[p].name;
        MR_CHECK_MSG(x->kind == y->kind, "%s.%s: kind %d, read %d", a->name, name, (int)x->kind, (int)y->kind);
        if (x->kind == MR_DOC_CONSTANT)
            for (int c = 0; c < a->model->params[p].channels; c++)
                MR_CHECK_MSG(x->constant[c] == y->constant[c], "%s.%s[%d]: %.17g, read %.17g", a->name, name, c,
                             x->constant[c], y->constant[c]);
        if (x->kind != MR_DOC_TEXTURE || y->kind != MR_DOC_TEXTURE) continue;
        MR_CHECK_MSG(strcmp(x->file, y->file) == 0, "%s.%s: %s, read %s", a->name, name, x->file, y->file);
        MR_CHECK_MSG(x->channel == y->channel && x->uv_set == y->uv_set, "%s.%s: channel %d/%d, uv %d/%d", a->name,
                     name, x->channel, y->channel, x->uv_set, y->uv_set);
        MR_CHECK_MSG(x->wrap_s == y->wrap_s && x->wrap_t == y->wrap_t, "%s.%s: wraps", a->name, name);
        for (int c = 0; c < a->model->params[p].channels; c++)
            MR_CHECK_MSG(x->scale[c] == y->scale[c], "%s.%s: scale[%d] %g, read %g", a->name, name, c, x->scale[c],
                         y->scale[c]);
    }
}

/* What the writer writes, the reader reads back exactly: constants, maps (colour, channels R..A, scales, UV set 1,
 * wraps, an .exr), for the three models .mtlx writes; names as written (identifiers); extras. */
MR_TEST(mtlx_round_trip) {
    for (int k = 0; k < 3; k++) {
        mr_doc *doc = sample(models[k]);
        mr_doc_material *m0 = mr_doc_material_at(doc, 0);
        const char *extra = k == 0 ? "transmission_weight" : k == 1 ? "sheen" : "transmission";
        MR_CHECK_OK(mr_doc_add_extra(m0, extra, "float", (double[1]){0.375}));
        if (k == 0) MR_CHECK_OK(mr_doc_add_extra(m0, "geometry_thin_walled", "boolean", (double[1]){1}));
        const char *path = mr_test_tmp_path("round.mtlx");
        MR_CHECK_OK(mr_doc_write(doc, path));
        mr_doc *back = NULL;
        MR_CHECK_OK(mr_doc_read_mtlx(path, &back));
        if (back == NULL) {
            mr_doc_free(doc);
            continue;
        }
        MR_CHECK(mr_doc_material_count(back) == 2);
        MR_CHECK(strcmp(mr_doc_material_get(back, 0)->name, "Brushed_metal__1") == 0);
        MR_CHECK(strcmp(mr_doc_material_get(back, 1)->name, "Brushed_metal__1_2") == 0);
        for (int i = 0; i < 2; i++) same_values(mr_doc_material_get(doc, i), mr_doc_material_get(back, i));
        const mr_doc_material *b0 = mr_doc_material_get(back, 0);
        MR_CHECK(b0->extra_count == (k == 0 ? 2 : 1) && strcmp(b0->extras[0].name, extra) == 0 &&
                 b0->extras[0].value[0] == 0.375);
        // Written again, the same text.
        char *t1 = NULL, *t2 = NULL;
        MR_CHECK_OK(mr_doc_to_text(doc, MR_DOC_FORMAT_MTLX, &t1));
        MR_CHECK_OK(mr_doc_to_text(back, MR_DOC_FORMAT_MTLX, &t2));
        MR_CHECK_MSG(t1 && t2 && strcmp(t1, t2) == 0, "%s: the text differs after a round trip", models[k]);
        free(t1);
        free(t2);
        mr_doc_free(back);
        mr_doc_free(doc);
    }
}

static const char *write_text(const char *name, const char *text) {
    const char *path = mr_test_tmp_path(name);
    MR_CHECK(mr_test_write_file(path, text, strlen(text)) == 1);
    return path;
}

/* MaterialX's UsdPreviewSurface (ND_UsdPreviewSurface_surfaceshader), top-level image nodes (nodename=),
 * tiledimage with identity tiling, fileprefix on the document, colour spaces, extras written to USD. */
MR_TEST(mtlx_reads_usd_preview_and_top_level_images) {
    const char *path = write_text("usdps.mtlx",
        "<?xml version=\"1.0\"?>\n<materialx version=\"1.39\" colorspace=\"lin_rec709\" fileprefix=\"tex/\">\n"
        "  <image name=\"albedo\" type=\"color3\">\n"
        "    <input name=\"file\" type=\"filename\" value=\"albedo.png\" colorspace=\"srgb_texture\" />\n"
        "    <input name=\"uaddressmode\" type=\"string\" value=\"clamp\" />\n  </image>\n"
        "  <tiledimage name=\"rough\" type=\"float\">\n"
        "    <input name=\"file\" type=\"filename\" value=\"rough.png\" />\n"
        "    <input name=\"uvtiling\" type=\"vector2\" value=\"1, 1\" />\n  </tiledimage>\n"
        "  <UsdPreviewSurface name=\"SR\" type=\"surfaceshader\" xpos=\"1\">\n"
        "    <input name=\"diffuseColor\" type=\"color3\" nodename=\"albedo\" />\n"
        "    <input name=\"roughness\" type=\"float\" nodename=\"rough\" />\n"
        "    <input name=\"metallic\" type=\"float\" value=\"0.25\" />\n"
        "    <input name=\"useSpecularWorkflow\" type=\"integer\" value=\"0\" />\n"
        "    <input name=\"emissiveColor\" type=\"color3\" value=\"0.5, 0.25, 0\" />\n"
        "    <input name=\"opacityMode\" type=\"integer\" value=\"1\" />\n"
        "  </UsdPreviewSurface>\n"
        "  <surfacematerial name=\"M\" type=\"material\">\n"
        "    <input name=\"surfaceshader\" type=\"surfaceshader\" nodename=\"SR\" />\n  </surfacematerial>\n"
        "</materialx>\n");
    mr_doc *doc = NULL;
    MR_CHECK_OK(mr_doc_read_mtlx(path, &doc));
    if (doc == NULL) return;
    const mr_doc_material *m = mr_doc_material_get(doc, 0);
    const mr_brdf_model *usd = mr_brdf_find("usd-preview");
    MR_CHECK(m->model == usd);
    const mr_doc_value *d = &m->values[mr_brdf_param_index(usd, "diffuse_color")];
    const mr_doc_value *r = &m->values[mr_brdf_param_index(usd, "roughness")];
    MR_CHECK(d->kind == MR_DOC_TEXTURE && strcmp(d->file, "tex/albedo.png") == 0 && d->wrap_s == MR_DOC_WRAP_CLAMP &&
             d->wrap_t == MR_DOC_WRAP_UNSET && d->channel == -1);
    MR_CHECK(r->kind == MR_DOC_TEXTURE && strcmp(r->file, "tex/rough.png") == 0 && r->channel == -1);
    MR_CHECK(m->values[mr_brdf_param_index(usd, "metallic")].constant[0] == 0.25);
    MR_CHECK(m->extra_count == 2 && strcmp(m->extras[0].name, "emissiveColor") == 0 && m->extras[0].value[1] == 0.25);
    char *text = NULL;
    MR_CHECK_OK(mr_doc_to_text(doc, MR_DOC_FORMAT_USDA, &text));
    MR_CHECK(text && strstr(text, "color3f inputs:emissiveColor = (0.5, 0.25, 0)") != NULL);
    MR_CHECK(text && strstr(text, "token inputs:opacityMode = \"presence\"") != NULL);
    MR_CHECK(text && strstr(text, "asset inputs:file = @tex/albedo.png@") != NULL);
    free(text);
    // Rebased: the maps named from another folder.
    char from[1200], to[1200];
    snprintf(from, sizeof from, "%s", mr_test_tmp_path("a/b/doc.mtlx"));
    snprintf(to, sizeof to, "%s", mr_test_tmp_path("a/c/d/out.usda"));
    MR_CHECK_OK(mr_doc_rebase(doc, from, to));
    MR_CHECK_MSG(strcmp(d->file, "../../b/tex/albedo.png") == 0, "%s", d->file);
    MR_CHECK_OK(mr_doc_rebase(doc, "x/doc.mtlx", "x/doc2.mtlx"));
    MR_CHECK_MSG(strcmp(d->file, "../../b/tex/albedo.png") == 0, "%s", d->file);
    mr_doc_free(doc);
}

static const char *example(const char *name) {
    static char path[4][1024];
    static int slot;
    const char *root = getenv("MR_ROOT");
    char *p = path[slot++ % 4];
    snprintf(p, 1024, "%s/tests/data/materialx/%s", root ? root : ".", name);
    return p;
}

/* MaterialX's own examples (tests/data/materialx, Apache-2.0): the values they author; extras kept. */
MR_TEST(mtlx_reads_materialx_examples) {
    mr_doc *doc = NULL;
    MR_CHECK_OK(mr_doc_read_mtlx(example("standard_surface_gold.mtlx"), &doc));
    if (doc == NULL) return;
    const mr_doc_material *m = mr_doc_material_get(doc, 0);
    const mr_brdf_model *ss = mr_brdf_find("standard-surface");
    MR_CHECK(m && strcmp(m->name, "Gold") == 0 && m->model == ss);
    const mr_doc_value *bc = &m->values[mr_brdf_param_index(ss, "base_color")];
    MR_CHECK(bc->kind == MR_DOC_CONSTANT && bc->constant[0] == 0.944 && bc->constant[1] == 0.776 &&
             bc->constant[2] == 0.373);
    MR_CHECK(m->values[mr_brdf_param_index(ss, "specular_roughness")].constant[0] == 0.02);
    MR_CHECK(m->values[mr_brdf_param_index(ss, "metalness")].constant[0] == 1);
    MR_CHECK(m->values[mr_brdf_param_index(ss, "specular_color")].constant[2] == 0.751);
    MR_CHECK(m->values[mr_brdf_param_index(ss, "coat")].kind == MR_DOC_UNSET && m->extra_count == 0);
    mr_doc_free(doc);
    MR_CHECK_OK(mr_doc_read_mtlx(example("standard_surface_copper.mtlx"), &doc));
    m = mr_doc_material_get(doc, 0);
    MR_CHECK(m && strcmp(m->name, "Copper") == 0 &&
             m->values[mr_brdf_param_index(ss, "coat_color")].constant[0] == 0.96467984 &&
             m->values[mr_brdf_param_index(ss, "coat_roughness")].constant[0] == 0.20000000298023224);
    mr_doc_free(doc);
    MR_CHECK_OK(mr_doc_read_mtlx(example("standard_surface_plastic.mtlx"), &doc));
    m = mr_doc_material_get(doc, 0);
    MR_CHECK(m && m->values[mr_brdf_param_index(ss, "base_color")].constant[2] == 0.81800002);
    mr_doc_free(doc);
    // OpenPBR pearl: subsurface and thin film are extras of open_pbr_surface, kept with their values.
    const mr_brdf_model *op = mr_brdf_find("openpbr");
    MR_CHECK_OK(mr_doc_read_mtlx(example("open_pbr_pearl.mtlx"), &doc));
    m = mr_doc_material_get(doc, 0);
    MR_CHECK(m && m->model == op && m->values[mr_brdf_param_index(op, "coat_ior")].constant[0] == 1.68);
    MR_CHECK(m && m->extra_count == 6 && strcmp(m->extras[0].name, "subsurface_weight") == 0 &&
             strcmp(m->extras[5].name, "thin_film_ior") == 0 && m->extras[5].value[0] == 2);
    mr_doc_free(doc);
    // Brass: tiledimage maps through a nodegraph, under the document's fileprefix; one map on two inputs.
    MR_CHECK_OK(mr_doc_read_mtlx(example("standard_surface_brass_tiled.mtlx"), &doc));
    m = mr_doc_material_get(doc, 0);
    const mr_doc_value *cc = m ? &m->values[mr_brdf_param_index(ss, "coat_color")] : NULL;
    MR_CHECK(cc && cc->kind == MR_DOC_TEXTURE && strcmp(cc->file, "../../../Images/brass_color.jpg") == 0);
    MR_CHECK(m && m->values[mr_brdf_param_index(ss, "coat_roughness")].kind == MR_DOC_TEXTURE &&
             strcmp(m->values[mr_brdf_param_index(ss, "specular_roughness")].file,
                    "../../../Images/brass_roughness.jpg") == 0);
    mr_doc_free(doc);
}

/* Every refusal with its exact message. */
MR_TEST(mtlx_refusals_name_file_line_material_and_node) {
    mr_doc *doc = NULL;
    char want[2048];
    const char *boombox = example("gltf_pbr_boombox.mtlx");
    MR_CHECK(mr_doc_read_mtlx(boombox, &doc) == MR_ERR_UNSUPPORTED && doc == NULL);
    snprintf(want, sizeof want, "MaterialX '%s' line 3: material 'Material_boombox': node 'image_basecolor' is a "
             "gltf_colorimage, which export cannot follow (it follows image, tiledimage, extract, multiply and "
             "texcoord in a nodegraph or at the top level)", boombox);
    MR_CHECK_MSG(strcmp(mr_last_error(), want) == 0, "%s", mr_last_error());
    const char *marble = example("standard_surface_marble_solid.mtlx");
    MR_CHECK(mr_doc_read_mtlx(marble, &doc) == MR_ERR_UNSUPPORTED);
    snprintf(want, sizeof want, "MaterialX '%s' line 4: material 'Marble_3D': nodegraph 'NG_marble1' has interface "
             "inputs, which are not followed", marble);
    MR_CHECK_MSG(strcmp(mr_last_error(), want) == 0, "%s", mr_last_error());

    static const char head[] = "<?xml version=\"1.0\"?>\n<materialx version=\"1.39\">\n";
    static const char material[] = "  <surfacematerial name=\"M\" type=\"material\">\n"
                                   "    <input name=\"surfaceshader\" type=\"surfaceshader\" nodename=\"SR\" />\n"
                                   "  </surfacematerial>\n</materialx>\n";
    struct {
        const char *body;
        mr_status status;
        const char *message; /* after "MaterialX 'PATH' " */
    } cases[] = {
        {"  <open_pbr_surface name=\"SR\" type=\"surfaceshader\">\n"
         "    <input name=\"base_colour\" type=\"color3\" value=\"1, 0, 0\" />\n  </open_pbr_surface>\n",
         MR_ERR_FORMAT, "line 4: material 'M': input 'base_colour' of 'SR' is not in the node definition of "
                        "open_pbr_surface"},
        {"  <open_pbr_surface name=\"SR\" type=\"surfaceshader\">\n"
         "    <input name=\"base_color\" type=\"float\" value=\"1\" />\n  </open_pbr_surface>\n",
         MR_ERR_FORMAT, "line 4: material 'M': input 'base_color' of 'SR' is a float: open_pbr_surface declares it "
                        "color3"},
        {"  <open_pbr_surface name=\"SR\" type=\"surfaceshader\">\n"
         "    <input name=\"base_color\" type=\"color3\" value=\"1, 0\" />\n  </open_pbr_surface>\n",
         MR_ERR_FORMAT, "line 4: material 'M': input 'base_color': \"1, 0\" is no color3 value"},
        {"  <open_pbr_surface name=\"SR\" type=\"surfaceshader\">\n"
         "    <input name=\"base_color\" type=\"color3\" value=\"1, nan, 0\" />\n  </open_pbr_surface>\n",
         MR_ERR_FORMAT, "line 4: material 'M': input 'base_color': \"1, nan, 0\" is no color3 value"},
        {"  <open_pbr_surface name=\"SR\" type=\"surfaceshader\">\n"
         "    <input name=\"specular_roughness\" type=\"float\" value=\"1e999\" />\n  </open_pbr_surface>\n",
         MR_ERR_FORMAT, "line 4: material 'M': input 'specular_roughness': \"1e999\" is no float value"},
        {"  <standard_surface name=\"SR\" type=\"surfaceshader\">\n"
         "    <input name=\"base\" type=\"float\" interfacename=\"b\" />\n  </standard_surface>\n",
         MR_ERR_UNSUPPORTED, "line 4: material 'M': attribute interfacename=\"b\" of <input name=\"base\"> is not "
                             "followed"},
        {"  <noise2d name=\"n\" type=\"float\" />\n  <gltf_pbr name=\"SR\" type=\"surfaceshader\">\n"
         "    <input name=\"roughness\" type=\"float\" nodename=\"n\" />\n  </gltf_pbr>\n",
         MR_ERR_UNSUPPORTED, "line 3: material 'M': node 'n' is a noise2d, which export cannot follow (it follows "
                             "image, tiledimage, extract, multiply and texcoord in a nodegraph or at the top level)"},
        {"  <image name=\"e\" type=\"color3\">\n    <input name=\"file\" type=\"filename\" value=\"e.png\" />\n"
         "  </image>\n  <gltf_pbr name=\"SR\" type=\"surfaceshader\">\n"
         "    <input name=\"emissive\" type=\"color3\" nodename=\"e\" />\n  </gltf_pbr>\n",
         MR_ERR_UNSUPPORTED, "line 7: material 'M': input 'emissive' of gltf_pbr 'SR' is connected to a node: maps "
                             "are carried only for the parameters of matremap's gltf model"},
        {"  <image name=\"c\" type=\"color3\">\n    <input name=\"file\" type=\"filename\" value=\"c.png\" />\n"
         "  </image>\n  <gltf_pbr name=\"SR\" type=\"surfaceshader\">\n"
         "    <input name=\"base_color\" type=\"color3\" nodename=\"c\" />\n  </gltf_pbr>\n",
         MR_ERR_UNSUPPORTED, "line 3: material 'M': input 'base_color' reads 'c.png' as lin_rec709; matremap's "
                             "documents read it as srgb_texture (the one rule of parameter maps: colour maps of "
                             "8/16-bit files srgb_texture, everything else lin_rec709), so it cannot be carried "
                             "unchanged"},
        {"  <disney_principled name=\"SR\" type=\"surfaceshader\" />\n", MR_ERR_UNSUPPORTED,
         "line 3: material 'M': its surface shader 'SR' is a disney_principled, which export cannot follow (it "
         "reads open_pbr_surface, standard_surface, gltf_pbr and UsdPreviewSurface)"},
        {"  <look name=\"L\" />\n  <gltf_pbr name=\"SR\" type=\"surfaceshader\" />\n", MR_ERR_UNSUPPORTED,
         "line 3: look 'L': looks and their material assignments are not read"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        char text[4096];
        snprintf(text, sizeof text, "%s%s%s", head, cases[i].body, material);
        const char *path = write_text("bad.mtlx", text);
        mr_status st = mr_doc_read_mtlx(path, &doc);
        snprintf(want, sizeof want, "MaterialX '%s' %s", path, cases[i].message);
        MR_CHECK_MSG(st == cases[i].status && doc == NULL, "case %zu: status %d", i, (int)st);
        MR_CHECK_MSG(strcmp(mr_last_error(), want) == 0, "case %zu:\n  %s\nwant\n  %s", i, mr_last_error(), want);
    }
    const char *dtd = write_text("dtd.mtlx", "<?xml version=\"1.0\"?>\n<!DOCTYPE m [<!ENTITY a \"aaaa\">]>\n"
                                             "<materialx version=\"1.39\">&a;</materialx>\n");
    MR_CHECK(mr_doc_read_mtlx(dtd, &doc) == MR_ERR_UNSUPPORTED);
    snprintf(want, sizeof want, "MaterialX '%s' line 2: a document type declaration (DOCTYPE) is not read", dtd);
    MR_CHECK_MSG(strcmp(mr_last_error(), want) == 0, "%s", mr_last_error());
    const char *broken = write_text("broken.mtlx", "<materialx version=\"1.39\">\n<a></b>\n");
    MR_CHECK(mr_doc_read_mtlx(broken, &doc) == MR_ERR_FORMAT);
    snprintf(want, sizeof want, "MaterialX '%s' line 2: not well-formed XML: mismatched tag", broken);
    MR_CHECK_MSG(strcmp(mr_last_error(), want) == 0, "%s", mr_last_error());
}

/* A read document converted: the same model copies (extras too), another remaps (the extras listed as not
 * carried), a textured standard-surface material's direct route to openpbr runs from glTF only (refused by name),
 * gltf maps reach usd-preview. */
MR_TEST(mtlx_convert_routes) {
    mr_doc *doc = NULL;
    MR_CHECK_OK(mr_doc_read_mtlx(example("open_pbr_pearl.mtlx"), &doc));
    if (doc == NULL) return;
    mr_doc_gltf_options o = {0};
    mr_doc_gltf_result *r = NULL;
    MR_CHECK_OK(mr_doc_convert(doc, "pearl", &o, &r)); // openpbr: copy
    MR_CHECK(r && r->materials[0].route == MR_DOC_ROUTE_COPY && r->materials[0].not_carried[0] == '\0' &&
             mr_doc_material_get(r->doc, 0)->extra_count == 6);
    if (r) same_values(mr_doc_material_get(doc, 0), mr_doc_material_get(r->doc, 0));
    mr_doc_gltf_result_free(r);
    o.target = mr_brdf_find("gltf");
    MR_CHECK_OK(mr_doc_convert(doc, "pearl", &o, &r));
    MR_CHECK(r && r->materials[0].route == MR_DOC_ROUTE_REMAP && r->materials[0].ssim > 0.98);
    MR_CHECK_MSG(r && strcmp(r->materials[0].not_carried, "subsurface_weight, subsurface_color, "
                             "subsurface_radius_scale, thin_film_weight, thin_film_thickness, thin_film_ior") == 0,
                 "%s", r ? r->materials[0].not_carried : "");
    mr_doc_gltf_result_free(r);
    mr_doc_free(doc);
    MR_CHECK_OK(mr_doc_read_mtlx(example("standard_surface_brass_tiled.mtlx"), &doc));
    o.target = NULL;
    o.document_path = example("standard_surface_brass_tiled.mtlx"); // its maps are not in the repository
    MR_CHECK(mr_doc_convert(doc, "MaterialX 'brass.mtlx'", &o, &r) == MR_ERR_IO);
    MR_CHECK_MSG(strstr(mr_last_error(), "MaterialX 'brass.mtlx': material 'Tiled_Brass' (standard-surface) to "
                        "openpbr by the direct route: map of specular_roughness: image '") == mr_last_error() &&
                 strstr(mr_last_error(), "/Images/brass_roughness.jpg': cannot open") != NULL,
                 "%s", mr_last_error());
    o.document_path = NULL;
    mr_doc_free(doc);
    // A value outside the model's range is refused by name, not clamped and remapped; roughness 0 passes.
    const char *odd = write_text("odd.mtlx", "<materialx version=\"1.39\">\n"
        "  <standard_surface name=\"SR\" type=\"surfaceshader\">\n"
        "    <input name=\"specular_roughness\" type=\"float\" value=\"0\" />\n"
        "    <input name=\"metalness\" type=\"float\" value=\"5\" />\n  </standard_surface>\n"
        "  <surfacematerial name=\"M\" type=\"material\">\n"
        "    <input name=\"surfaceshader\" type=\"surfaceshader\" nodename=\"SR\" />\n"
        "  </surfacematerial>\n</materialx>\n");
    MR_CHECK_OK(mr_doc_read_mtlx(odd, &doc));
    MR_CHECK(mr_doc_convert(doc, "odd", &o, &r) == MR_ERR_INVALID_ARG);
    MR_CHECK_MSG(strcmp(mr_last_error(), "odd: material 'M': metalness 5 is outside standard-surface's range [0, 1]: "
                        "not remapped") == 0, "%s", mr_last_error());
    mr_doc_free(doc);
    doc = sample("gltf");
    o.target = mr_brdf_find("usd-preview");
    MR_CHECK(mr_doc_convert(doc, "s", &o, &r) == MR_ERR_UNSUPPORTED); // sample's specular 0.25: no place in USD
    MR_CHECK_MSG(strstr(mr_last_error(), "have no place in usd-preview's metallic workflow") != NULL, "%s",
                 mr_last_error());
    mr_doc_free(doc);
    doc = mr_doc_create();
    mr_doc_material *m = NULL;
    MR_CHECK_OK(mr_doc_add_material(doc, "tex", mr_brdf_find("gltf"), &m));
    MR_CHECK_OK(mr_doc_set_texture(m, "base_color", "b.png", -1, 1, (double[3]){0.5, 0.5, 0.5}));
    MR_CHECK_OK(mr_doc_set_texture(m, "roughness", "mr.png", 1, 0, NULL));
    MR_CHECK_OK(mr_doc_convert(doc, "s", &o, &r));
    const mr_doc_material *u = r ? mr_doc_material_get(r->doc, 0) : NULL;
    const mr_brdf_model *usd = mr_brdf_find("usd-preview");
    MR_CHECK(u && r->materials[0].route == MR_DOC_ROUTE_MAPS &&
             u->values[mr_brdf_param_index(usd, "diffuse_color")].kind == MR_DOC_TEXTURE &&
             u->values[mr_brdf_param_index(usd, "diffuse_color")].uv_set == 1 &&
             u->values[mr_brdf_param_index(usd, "roughness")].channel == 1 &&
             u->values[mr_brdf_param_index(usd, "metallic")].kind == MR_DOC_UNSET);
    mr_doc_gltf_result_free(r);
    mr_doc_free(doc);
}

/* A textured material read from a document converts by the direct route, as a glTF material does: its maps read
 * from files relative to the document (a grey roughness map, a base colour map with a scale), the converted maps
 * named relative to the document; maps on two UV sets refused naming both; no image prefix refused. */
MR_TEST(mtlx_textured_material_converts_by_the_direct_route) {
    mr_image *base = NULL, *rough = NULL;
    MR_CHECK_OK(mr_image_create(2, 2, 3, &base));
    MR_CHECK_OK(mr_image_create(2, 2, 1, &rough));
    if (base == NULL || rough == NULL) return;
    for (int i = 0; i < 4; i++) {
        for (int c = 0; c < 3; c++) base->pixels[i * 3 + c] = i < 2 ? 0.5f : (c == 0 ? 0.8f : 0.2f);
        rough->pixels[i] = i % 2 ? 0.3f : 0.7f;
    }
    mr_img_write_options colour = {MR_IMG_COLOR, 8, 0}, data = {MR_IMG_DATA, 8, 0};
    MR_CHECK(mkdir(mr_test_tmp_path("maps"), 0755) == 0 && mkdir(mr_test_tmp_path("out"), 0755) == 0);
    MR_CHECK_OK(mr_img_write(mr_test_tmp_path("maps/base.png"), base, &colour));
    MR_CHECK_OK(mr_img_write(mr_test_tmp_path("maps/rough.png"), rough, &data));
    mr_image_free(base);
    mr_image_free(rough);
    for (int uv1 = 0; uv1 < 2; uv1++) {
        mr_doc *doc = mr_doc_create();
        mr_doc_material *m = NULL;
        MR_CHECK_OK(mr_doc_add_material(doc, "T", mr_brdf_find("gltf"), &m));
        if (m == NULL) return;
        MR_CHECK_OK(mr_doc_set_texture(m, "base_color", "maps/base.png", -1, 0, (double[3]){0.5, 0.9, 1}));
        MR_CHECK_OK(mr_doc_set_texture(m, "roughness", "maps/rough.png", -1, uv1, NULL));
        MR_CHECK_OK(mr_doc_set_constant(m, "metallic", (double[1]){0}));
        mr_doc_gltf_options o = {0};
        o.size = 16;
        o.document_path = mr_test_tmp_path("doc.mtlx");
        mr_doc_gltf_result *r = NULL;
        mr_status st = mr_doc_convert(doc, "d", &o, &r);
        MR_CHECK_MSG(uv1 || (st == MR_ERR_INVALID_ARG && strstr(mr_last_error(), "no image prefix given")), "%s",
                     mr_last_error());
        o.image_prefix = mr_test_tmp_path("out/doc");
        st = mr_doc_convert(doc, "d", &o, &r);
        mr_doc_free(doc);
        if (uv1) {
            MR_CHECK(st == MR_ERR_UNSUPPORTED);
            MR_CHECK_MSG(strcmp(mr_last_error(), "d: material 'T' (gltf) to openpbr by the direct route: the maps of "
                                "base_color and roughness differ in UV set or wrap mode: a converted map holds every "
                                "parameter of a texel, so its maps must share both") == 0, "%s", mr_last_error());
            continue;
        }
        MR_CHECK_OK(st);
        if (r == NULL) return;
        const mr_doc_gltf_material *info = &r->materials[0];
        MR_CHECK_MSG(info->route == MR_DOC_ROUTE_DIRECT && info->texels == 4 && info->width == 2 && info->unique == 4,
                     "route %s, %zu texels, %zu distinct", mr_doc_route_name(info->route), info->texels, info->unique);
        const mr_doc_material *out = mr_doc_material_get(r->doc, 0);
        const mr_brdf_model *op = mr_brdf_find("openpbr");
        const mr_doc_value *bc = &out->values[mr_brdf_param_index(op, "base_color")];
        const mr_doc_value *sr = &out->values[mr_brdf_param_index(op, "specular_roughness")];
        const mr_doc_value *bm = &out->values[mr_brdf_param_index(op, "base_metalness")];
        MR_CHECK_MSG(bc->kind == MR_DOC_TEXTURE && strcmp(bc->file, "out/doc_T_base_color.png") == 0, "%s",
                     bc->kind == MR_DOC_TEXTURE ? bc->file : "not a map");
        MR_CHECK(sr->kind == MR_DOC_TEXTURE && strcmp(sr->file, "out/doc_T_specular_roughness.png") == 0);
        MR_CHECK(bm->kind == MR_DOC_CONSTANT && bm->constant[0] == 0); // tied to metallic 0
        MR_CHECK(r->map_count == 3 && r->maps[2].param == -1);
        // The scale is folded in: the converted base colour of the scaled texels is darker in red than green's 0.9
        // would make it, and the (0.8, 0.2, 0.2) texels' red stays above their green.
        if (r->map_count == 3) {
            const mr_image *img = r->maps[0].image;
            MR_CHECK_MSG(img->pixels[0] < img->pixels[1] && img->pixels[2 * 3] > img->pixels[2 * 3 + 1],
                         "%g %g %g / %g %g", img->pixels[0], img->pixels[1], img->pixels[2], img->pixels[6],
                         img->pixels[7]);
        }
        MR_CHECK_OK(mr_doc_gltf_write(NULL, r, mr_test_tmp_path("out/doc.mtlx")));
        FILE *f = fopen(mr_test_tmp_path("out/doc_T_base_color.png"), "rb");
        MR_CHECK(f != NULL);
        if (f) fclose(f);
        mr_doc_gltf_result_free(r);
    }
}

/* mr_doc_export_file: one asset to one file in one call; the report says what was done; refusals name the file and
 * write nothing. */
static void export_file_in_one_call(void) {
    char in[1024], out[1024], bad[1024];
    snprintf(in, sizeof in, "%s", mr_test_tmp_path("one_call.gltf"));
    snprintf(out, sizeof out, "%s", mr_test_tmp_path("one_call_out/doc.mtlx"));
    snprintf(bad, sizeof bad, "%s", mr_test_tmp_path("one_call_out/doc.obj"));
    FILE *f = fopen(in, "w");
    MR_CHECK(f != NULL);
    if (!f) return;
    fputs("{\"asset\": {\"version\": \"2.0\"}, \"materials\": [{\"name\": \"Gold\", \"pbrMetallicRoughness\": "
          "{\"baseColorFactor\": [1.0, 0.77, 0.34, 1], \"metallicFactor\": 1.0, \"roughnessFactor\": 0.3}}]}\n", f);
    fclose(f);
    mr_doc_export_options o = {0};
    o.target = mr_brdf_find("gltf");
    mr_doc_export_report rep;
    MR_CHECK_OK(mr_doc_export_file(in, out, &o, &rep));
    MR_CHECK(rep.result != NULL && rep.result->material_count == 1 && strcmp(rep.format, "mtlx") == 0);
    MR_CHECK(rep.result != NULL && rep.result->materials[0].route == MR_DOC_ROUTE_COPY);
    MR_CHECK(rep.target == o.target && rep.source_count == 1 && strcmp(rep.sources[0]->name, "gltf") == 0);
    struct stat st;
    MR_CHECK(stat(out, &st) == 0 && st.st_size > 0);
    mr_doc_export_report_free(&rep);
    MR_CHECK(rep.result == NULL);
    // Refused: another extension; a model the format does not write; the output over the input.
    MR_CHECK(mr_doc_export_file(in, bad, NULL, &rep) == MR_ERR_INVALID_ARG);
    MR_CHECK(strstr(mr_last_error(), "doc.obj") != NULL && rep.result == NULL);
    o.target = mr_brdf_find("openpbr");
    snprintf(bad, sizeof bad, "%s", mr_test_tmp_path("one_call_out/doc.glb"));
    MR_CHECK(mr_doc_export_file(in, bad, &o, &rep) == MR_ERR_INVALID_ARG);
    MR_CHECK(strstr(mr_last_error(), "openpbr") != NULL && stat(bad, &st) != 0);
    MR_CHECK(mr_doc_export_file(in, in, NULL, &rep) != MR_OK);
    MR_CHECK(strstr(mr_last_error(), "one_call.gltf") != NULL);
    MR_CHECK(mr_doc_export_default_target("x.usda") == mr_brdf_find("usd-preview"));
    MR_CHECK(mr_doc_export_default_target("x.obj") == NULL && !mr_doc_export_output_ok("x.obj"));
}

MR_TEST_MAIN(MR_TEST_ENTRY(every_parameter_maps_to_a_declared_input), MR_TEST_ENTRY(mtlx_writes_declared_inputs_only),
             MR_TEST_ENTRY(usda_writes_declared_inputs_only), MR_TEST_ENTRY(the_colour_space_rule),
             MR_TEST_ENTRY(usda_specular_color_only_in_the_specular_workflow),
             MR_TEST_ENTRY(bad_values_are_refused), MR_TEST_ENTRY(the_write_is_atomic),
             MR_TEST_ENTRY(uniform_materials_are_remapped_and_converge), MR_TEST_ENTRY(the_route_decision),
             MR_TEST_ENTRY(a_textured_material_converts_by_the_direct_route), MR_TEST_ENTRY(mtlx_round_trip),
             MR_TEST_ENTRY(mtlx_reads_usd_preview_and_top_level_images), MR_TEST_ENTRY(mtlx_reads_materialx_examples),
             MR_TEST_ENTRY(mtlx_refusals_name_file_line_material_and_node), MR_TEST_ENTRY(mtlx_convert_routes),
             MR_TEST_ENTRY(mtlx_textured_material_converts_by_the_direct_route),
             MR_TEST_ENTRY(export_file_in_one_call))
