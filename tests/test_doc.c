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
        MR_CHECK(dm->values[ior].kind == MR_DOC_CONSTANT && dm->values[ior].constant[0] == 1.5);
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

MR_TEST_MAIN(MR_TEST_ENTRY(every_parameter_maps_to_a_declared_input), MR_TEST_ENTRY(mtlx_writes_declared_inputs_only),
             MR_TEST_ENTRY(usda_writes_declared_inputs_only), MR_TEST_ENTRY(the_colour_space_rule),
             MR_TEST_ENTRY(bad_values_are_refused), MR_TEST_ENTRY(the_write_is_atomic),
             MR_TEST_ENTRY(uniform_materials_are_remapped_and_converge), MR_TEST_ENTRY(the_route_decision),
             MR_TEST_ENTRY(a_textured_material_converts_by_the_direct_route))
