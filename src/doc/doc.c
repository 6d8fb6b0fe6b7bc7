/*
 * doc.c — the material document (doc.h): materials, the node tables (facts), the MaterialX and USD writers.
 */
#include "doc/doc.h"

#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "c_locale.h"
#include "io/image_io.h"
#include "mr_internal.h"

struct mr_doc {
    mr_doc_material *materials;
    int count, capacity;
};

/* ---- node tables: facts ----------------------------------------------------------------------------------------
 * Read from MaterialX 1.39's libraries (libraries/bxdf/open_pbr_surface.mtlx ND_open_pbr_surface_surfaceshader,
 * standard_surface.mtlx ND_standard_surface_surfaceshader_100 which 1.0.1 inherits, gltf_pbr.mtlx
 * ND_gltf_pbr_surfaceshader; stdlib_defs.mtlx ND_image_*, ND_extract_*, ND_multiply_*, ND_texcoord_vector2;
 * pbrlib_defs.mtlx ND_surfacematerial) and the UsdPreviewSurface specification (OpenUSD). Every input name and
 * type of those definitions is listed, in their order, whether or not this module writes it. */
typedef struct node_table {
    mr_doc_format format;
    const char *node;
    const mr_doc_node_input *inputs;
    int count;
    const mr_doc_node_input *outputs;
    int output_count;
} node_table;

#define N(array) (int)(sizeof(array) / sizeof(array[0]))

static const mr_doc_node_input open_pbr_in[] = {
    {"base_weight", "float"}, {"base_color", "color3"}, {"base_diffuse_roughness", "float"},
    {"base_metalness", "float"}, {"specular_weight", "float"}, {"specular_color", "color3"},
    {"specular_roughness", "float"}, {"specular_ior", "float"}, {"specular_roughness_anisotropy", "float"},
    {"transmission_weight", "float"}, {"transmission_color", "color3"}, {"transmission_depth", "float"},
    {"transmission_scatter", "color3"}, {"transmission_scatter_anisotropy", "float"},
    {"transmission_dispersion_scale", "float"}, {"transmission_dispersion_abbe_number", "float"},
    {"subsurface_weight", "float"}, {"subsurface_color", "color3"}, {"subsurface_radius", "float"},
    {"subsurface_radius_scale", "color3"}, {"subsurface_scatter_anisotropy", "float"}, {"fuzz_weight", "float"},
    {"fuzz_color", "color3"}, {"fuzz_roughness", "float"}, {"coat_weight", "float"}, {"coat_color", "color3"},
    {"coat_roughness", "float"}, {"coat_roughness_anisotropy", "float"}, {"coat_ior", "float"},
    {"coat_darkening", "float"}, {"thin_film_weight", "float"}, {"thin_film_thickness", "float"},
    {"thin_film_ior", "float"}, {"emission_luminance", "float"}, {"emission_color", "color3"},
    {"geometry_opacity", "float"}, {"geometry_thin_walled", "boolean"}, {"geometry_normal", "vector3"},
    {"geometry_coat_normal", "vector3"}, {"geometry_tangent", "vector3"}, {"geometry_coat_tangent", "vector3"},
};
static const mr_doc_node_input standard_surface_in[] = {
    {"base", "float"}, {"base_color", "color3"}, {"diffuse_roughness", "float"}, {"metalness", "float"},
    {"specular", "float"}, {"specular_color", "color3"}, {"specular_roughness", "float"}, {"specular_IOR", "float"},
    {"specular_anisotropy", "float"}, {"specular_rotation", "float"}, {"transmission", "float"},
    {"transmission_color", "color3"}, {"transmission_depth", "float"}, {"transmission_scatter", "color3"},
    {"transmission_scatter_anisotropy", "float"}, {"transmission_dispersion", "float"},
    {"transmission_extra_roughness", "float"}, {"subsurface", "float"}, {"subsurface_color", "color3"},
    {"subsurface_radius", "color3"}, {"subsurface_scale", "float"}, {"subsurface_anisotropy", "float"},
    {"sheen", "float"}, {"sheen_color", "color3"}, {"sheen_roughness", "float"}, {"coat", "float"},
    {"coat_color", "color3"}, {"coat_roughness", "float"}, {"coat_anisotropy", "float"}, {"coat_rotation", "float"},
    {"coat_IOR", "float"}, {"coat_normal", "vector3"}, {"coat_affect_color", "float"},
    {"coat_affect_roughness", "float"}, {"thin_film_thickness", "float"}, {"thin_film_IOR", "float"},
    {"emission", "float"}, {"emission_color", "color3"}, {"opacity", "color3"}, {"thin_walled", "boolean"},
    {"normal", "vector3"}, {"tangent", "vector3"},
};
static const mr_doc_node_input gltf_pbr_in[] = {
    {"base_color", "color3"}, {"metallic", "float"}, {"roughness", "float"}, {"normal", "vector3"},
    {"tangent", "vector3"}, {"occlusion", "float"}, {"transmission", "float"}, {"specular", "float"},
    {"specular_color", "color3"}, {"ior", "float"}, {"alpha", "float"}, {"alpha_mode", "integer"},
    {"alpha_cutoff", "float"}, {"iridescence", "float"}, {"iridescence_ior", "float"},
    {"iridescence_thickness", "float"}, {"sheen_color", "color3"}, {"sheen_roughness", "float"},
    {"clearcoat", "float"}, {"clearcoat_roughness", "float"}, {"clearcoat_normal", "vector3"},
    {"emissive", "color3"}, {"emissive_strength", "float"}, {"thickness", "float"},
    {"attenuation_distance", "float"}, {"attenuation_color", "color3"}, {"anisotropy_strength", "float"},
    {"anisotropy_rotation", "float"}, {"dispersion", "float"},
};
static const mr_doc_node_input surfaceshader_out[] = {{"out", "surfaceshader"}};
#define IMAGE_INPUTS(T)                                                                                      \
    {"file", "filename"}, {"layer", "string"}, {"default", T}, {"texcoord", "vector2"},                     \
        {"uaddressmode", "string"}, {"vaddressmode", "string"}, {"filtertype", "string"},                   \
        {"framerange", "string"}, {"frameoffset", "integer"}, { "frameendaction", "string" }
static const mr_doc_node_input image_float_in[] = {IMAGE_INPUTS("float")};
static const mr_doc_node_input image_color3_in[] = {IMAGE_INPUTS("color3")};
static const mr_doc_node_input image_color4_in[] = {IMAGE_INPUTS("color4")};
#define TILEDIMAGE_INPUTS(T)                                                                                 \
    {"file", "filename"}, {"default", T}, {"texcoord", "vector2"}, {"uvtiling", "vector2"},                   \
        {"uvoffset", "vector2"}, {"realworldimagesize", "vector2"}, {"realworldtilesize", "vector2"},        \
        {"filtertype", "string"}, {"framerange", "string"}, {"frameoffset", "integer"},                     \
    {                                                                                                        \
        "frameendaction", "string"                                                                           \
    }
static const mr_doc_node_input tiledimage_float_in[] = {TILEDIMAGE_INPUTS("float")};
static const mr_doc_node_input tiledimage_color3_in[] = {TILEDIMAGE_INPUTS("color3")};
static const mr_doc_node_input tiledimage_color4_in[] = {TILEDIMAGE_INPUTS("color4")};
static const mr_doc_node_input out_float[] = {{"out", "float"}};
static const mr_doc_node_input out_color3[] = {{"out", "color3"}};
static const mr_doc_node_input out_color4[] = {{"out", "color4"}};
static const mr_doc_node_input out_vector2[] = {{"out", "vector2"}};
static const mr_doc_node_input extract_color3_in[] = {{"in", "color3"}, {"index", "integer"}};
static const mr_doc_node_input extract_color4_in[] = {{"in", "color4"}, {"index", "integer"}};
static const mr_doc_node_input multiply_float_in[] = {{"in1", "float"}, {"in2", "float"}};
static const mr_doc_node_input multiply_color3_in[] = {{"in1", "color3"}, {"in2", "color3"}};
static const mr_doc_node_input texcoord_in[] = {{"index", "integer"}};
static const mr_doc_node_input surfacematerial_in[] = {
    {"surfaceshader", "surfaceshader"}, {"backsurfaceshader", "surfaceshader"},
    {"displacementshader", "displacementshader"}};
static const mr_doc_node_input surfacematerial_out[] = {{"out", "material"}};

static const mr_doc_node_input usd_preview_in[] = {
    {"diffuseColor", "color3f"}, {"emissiveColor", "color3f"}, {"useSpecularWorkflow", "int"},
    {"specularColor", "color3f"}, {"metallic", "float"}, {"roughness", "float"}, {"clearcoat", "float"},
    {"clearcoatRoughness", "float"}, {"opacity", "float"}, {"opacityMode", "token"}, {"opacityThreshold", "float"},
    {"ior", "float"}, {"normal", "normal3f"}, {"displacement", "float"}, {"occlusion", "float"},
};
/* MaterialX's own definition of the node (libraries/bxdf/usd_preview_surface.mtlx,
 * ND_UsdPreviewSurface_surfaceshader), which the MaterialX reader follows: MaterialX types (opacityMode an integer). */
static const mr_doc_node_input usd_preview_mtlx_in[] = {
    {"diffuseColor", "color3"}, {"emissiveColor", "color3"}, {"useSpecularWorkflow", "integer"},
    {"specularColor", "color3"}, {"metallic", "float"}, {"roughness", "float"}, {"clearcoat", "float"},
    {"clearcoatRoughness", "float"}, {"opacity", "float"}, {"opacityMode", "integer"}, {"opacityThreshold", "float"},
    {"ior", "float"}, {"normal", "vector3"}, {"displacement", "float"}, {"occlusion", "float"},
};
static const mr_doc_node_input usd_preview_out[] = {{"surface", "token"}, {"displacement", "token"}};
static const mr_doc_node_input usd_uv_texture_in[] = {
    {"file", "asset"}, {"st", "float2"}, {"wrapS", "token"}, {"wrapT", "token"}, {"fallback", "float4"},
    {"scale", "float4"}, {"bias", "float4"}, {"sourceColorSpace", "token"},
};
static const mr_doc_node_input usd_uv_texture_out[] = {
    {"r", "float"}, {"g", "float"}, {"b", "float"}, {"a", "float"}, {"rgb", "float3"}};
/* The specification's varname is a token since its version 2.3 (a string before). */
static const mr_doc_node_input usd_primvar_in[] = {{"varname", "token"}, {"fallback", "float2"}};
static const mr_doc_node_input usd_primvar_out[] = {{"result", "float2"}};

static const node_table node_tables[] = {
    {MR_DOC_FORMAT_MTLX, "open_pbr_surface", open_pbr_in, N(open_pbr_in), surfaceshader_out, 1},
    {MR_DOC_FORMAT_MTLX, "standard_surface", standard_surface_in, N(standard_surface_in), surfaceshader_out, 1},
    {MR_DOC_FORMAT_MTLX, "gltf_pbr", gltf_pbr_in, N(gltf_pbr_in), surfaceshader_out, 1},
    {MR_DOC_FORMAT_MTLX, "image_float", image_float_in, N(image_float_in), out_float, 1},
    {MR_DOC_FORMAT_MTLX, "image_color3", image_color3_in, N(image_color3_in), out_color3, 1},
    {MR_DOC_FORMAT_MTLX, "image_color4", image_color4_in, N(image_color4_in), out_color4, 1},
    {MR_DOC_FORMAT_MTLX, "tiledimage_float", tiledimage_float_in, N(tiledimage_float_in), out_float, 1},
    {MR_DOC_FORMAT_MTLX, "tiledimage_color3", tiledimage_color3_in, N(tiledimage_color3_in), out_color3, 1},
    {MR_DOC_FORMAT_MTLX, "tiledimage_color4", tiledimage_color4_in, N(tiledimage_color4_in), out_color4, 1},
    {MR_DOC_FORMAT_MTLX, "extract_color3", extract_color3_in, N(extract_color3_in), out_float, 1},
    {MR_DOC_FORMAT_MTLX, "extract_color4", extract_color4_in, N(extract_color4_in), out_float, 1},
    {MR_DOC_FORMAT_MTLX, "multiply_float", multiply_float_in, N(multiply_float_in), out_float, 1},
    {MR_DOC_FORMAT_MTLX, "multiply_color3", multiply_color3_in, N(multiply_color3_in), out_color3, 1},
    {MR_DOC_FORMAT_MTLX, "texcoord_vector2", texcoord_in, N(texcoord_in), out_vector2, 1},
    {MR_DOC_FORMAT_MTLX, "UsdPreviewSurface", usd_preview_mtlx_in, N(usd_preview_mtlx_in), surfaceshader_out, 1},
    {MR_DOC_FORMAT_MTLX, "surfacematerial", surfacematerial_in, N(surfacematerial_in), surfacematerial_out, 1},
    {MR_DOC_FORMAT_USDA, "UsdPreviewSurface", usd_preview_in, N(usd_preview_in), usd_preview_out,
     N(usd_preview_out)},
    {MR_DOC_FORMAT_USDA, "UsdUVTexture", usd_uv_texture_in, N(usd_uv_texture_in), usd_uv_texture_out,
     N(usd_uv_texture_out)},
    {MR_DOC_FORMAT_USDA, "UsdPrimvarReader_float2", usd_primvar_in, N(usd_primvar_in), usd_primvar_out,
     N(usd_primvar_out)},
};

static const node_table *find_table(mr_doc_format format, const char *node) {
    if (node == NULL) return NULL;
    for (int i = 0; i < N(node_tables); i++)
        if (node_tables[i].format == format && strcmp(node_tables[i].node, node) == 0) return &node_tables[i];
    return NULL;
}

const mr_doc_node_input *mr_doc_node_inputs(mr_doc_format format, const char *node, int *count) {
    const node_table *t = find_table(format, node);
    if (count) *count = t ? t->count : 0;
    return t ? t->inputs : NULL;
}

const mr_doc_node_input *mr_doc_node_outputs(mr_doc_format format, const char *node, int *count) {
    const node_table *t = find_table(format, node);
    if (count) *count = t ? t->output_count : 0;
    return t ? t->outputs : NULL;
}

/* ---- models and formats: which node writes a model, and the parameters' input names ------------------------ */
typedef struct input_rename {
    const char *param, *input;
} input_rename;
static const input_rename standard_surface_names[] = {
    {"specular_ior", "specular_IOR"}, {"coat_ior", "coat_IOR"}, {0, 0}};
static const input_rename usd_preview_names[] = {
    {"diffuse_color", "diffuseColor"}, {"use_specular_workflow", "useSpecularWorkflow"},
    {"specular_color", "specularColor"}, {"clearcoat_roughness", "clearcoatRoughness"}, {0, 0}};
static const input_rename no_names[] = {{0, 0}};

typedef struct model_writer {
    const char *model;
    mr_doc_format format;
    const char *node;
    const input_rename *names; /* parameters whose input has another name; the others keep theirs */
} model_writer;
static const model_writer model_writers[] = {
    {"openpbr", MR_DOC_FORMAT_MTLX, "open_pbr_surface", no_names},
    {"standard-surface", MR_DOC_FORMAT_MTLX, "standard_surface", standard_surface_names},
    {"gltf", MR_DOC_FORMAT_MTLX, "gltf_pbr", no_names},
    {"usd-preview", MR_DOC_FORMAT_USDA, "UsdPreviewSurface", usd_preview_names},
};

static const model_writer *find_writer(const mr_brdf_model *model, mr_doc_format format) {
    if (model == NULL) return NULL;
    for (int i = 0; i < N(model_writers); i++)
        if (strcmp(model_writers[i].model, model->name) == 0 &&
            (format == MR_DOC_FORMAT_UNKNOWN || model_writers[i].format == format))
            return &model_writers[i];
    return NULL;
}

/* "openpbr, standard-surface, gltf (mtlx); usd-preview (usda)" for messages. */
static const char *writable_models(void) {
    return "openpbr, standard-surface, gltf (.mtlx); usd-preview (.usda)";
}

const char *mr_doc_surface_node(const mr_brdf_model *model, mr_doc_format format) {
    const model_writer *w = find_writer(model, format);
    return w && format != MR_DOC_FORMAT_UNKNOWN ? w->node : NULL;
}

const char *mr_doc_input_name(const mr_brdf_model *model, int param, mr_doc_format format) {
    const model_writer *w = find_writer(model, format);
    if (w == NULL || format == MR_DOC_FORMAT_UNKNOWN || param < 0 || param >= model->param_count) return NULL;
    const char *name = model->params[param].name;
    for (const input_rename *r = w->names; r->param; r++)
        if (strcmp(r->param, name) == 0) return r->input;
    return name;
}

mr_doc_format mr_doc_format_from_path(const char *path) {
    const char *dot = path ? strrchr(path, '.') : NULL;
    if (dot == NULL || strchr(dot, '/') != NULL) return MR_DOC_FORMAT_UNKNOWN;
    if (strcasecmp(dot, ".mtlx") == 0) return MR_DOC_FORMAT_MTLX;
    if (strcasecmp(dot, ".usda") == 0) return MR_DOC_FORMAT_USDA;
    return MR_DOC_FORMAT_UNKNOWN;
}

const char *mr_doc_format_name(mr_doc_format format) {
    return format == MR_DOC_FORMAT_MTLX ? "mtlx" : format == MR_DOC_FORMAT_USDA ? "usda" : NULL;
}

int mr_doc_texture_is_srgb(const mr_brdf_param *param, const char *file) {
    const char *dot = file ? strrchr(file, '.') : NULL;
    if (dot && (strcasecmp(dot, ".exr") == 0 || strcasecmp(dot, ".hdr") == 0)) return 0; // float files: linear
    return mr_brdf_param_map_encoding(param, MR_MAP_AS_PARAMETER) == MR_IMG_COLOR;
}

void mr_doc_identifier(const char *name, char *out, size_t size) {
    if (size == 0) return;
    size_t n = 0;
    if (name == NULL) name = "";
    if (!isalpha((unsigned char)name[0]) && name[0] != '_' && size > 3) {
        out[n++] = 'M';
        out[n++] = '_';
    }
    for (const char *c = name; *c && n + 1 < size; c++) out[n++] = isalnum((unsigned char)*c) ? *c : '_';
    out[n] = '\0';
}

/* ---- the document ------------------------------------------------------------------------------------------ */
mr_doc *mr_doc_create(void) { return calloc(1, sizeof(mr_doc)); }

static void clear_value(mr_doc_value *v) {
    free(v->file);
    memset(v, 0, sizeof(*v));
}

void mr_doc_free(mr_doc *doc) {
    if (doc == NULL) return;
    for (int k = 0; k < doc->count; k++) {
        free(doc->materials[k].name);
        for (int p = 0; p < MR_BRDF_MAX_VALUES; p++) clear_value(&doc->materials[k].values[p]);
        for (int e = 0; e < doc->materials[k].extra_count; e++) free(doc->materials[k].extras[e].name);
        free(doc->materials[k].extras);
    }
    free(doc->materials);
    free(doc);
}

int mr_doc_material_count(const mr_doc *doc) { return doc ? doc->count : 0; }

mr_doc_material *mr_doc_material_at(mr_doc *doc, int k) {
    return doc && k >= 0 && k < doc->count ? &doc->materials[k] : NULL;
}

const mr_doc_material *mr_doc_material_get(const mr_doc *doc, int k) {
    return doc && k >= 0 && k < doc->count ? &doc->materials[k] : NULL;
}

static char *copy_string(const char *s) {
    size_t n = strlen(s) + 1;
    char *c = malloc(n);
    if (c) memcpy(c, s, n);
    return c;
}

mr_status mr_doc_add_material(mr_doc *doc, const char *name, const mr_brdf_model *model, mr_doc_material **out) {
    if (doc == NULL || model == NULL) return mr_fail(MR_ERR_INVALID_ARG, "material document: no document or model");
    if (find_writer(model, MR_DOC_FORMAT_UNKNOWN) == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "material document: model '%s' is written by no format (models: %s)",
                       model->name, writable_models());
    if (doc->count == doc->capacity) {
        int capacity = doc->capacity ? 2 * doc->capacity : 8;
        mr_doc_material *grown = realloc(doc->materials, (size_t)capacity * sizeof(*grown));
        if (grown == NULL) return mr_fail(MR_ERR_NOMEM, "material document: out of memory");
        doc->materials = grown;
        doc->capacity = capacity;
    }
    mr_doc_material *m = &doc->materials[doc->count];
    memset(m, 0, sizeof(*m));
    m->name = copy_string(name ? name : "");
    if (m->name == NULL) return mr_fail(MR_ERR_NOMEM, "material document: out of memory");
    m->model = model;
    doc->count++;
    if (out) *out = m;
    return MR_OK;
}

static int find_param(const mr_doc_material *m, const char *param) {
    return m && m->model && param ? mr_brdf_param_index(m->model, param) : -1;
}

mr_status mr_doc_set_constant(mr_doc_material *m, const char *param, const double *values) {
    int p = find_param(m, param);
    if (p < 0 || values == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "material document: '%s' is no parameter of %s", param ? param : "(null)",
                       m && m->model ? m->model->name : "(no model)");
    int channels = m->model->params[p].channels;
    for (int c = 0; c < channels; c++)
        if (!isfinite(values[c]))
            return mr_fail(MR_ERR_INVALID_ARG, "material document: %s of material '%s' is not finite", param, m->name);
    clear_value(&m->values[p]);
    m->values[p].kind = MR_DOC_CONSTANT;
    for (int c = 0; c < channels; c++) m->values[p].constant[c] = values[c];
    return MR_OK;
}

mr_status mr_doc_set_texture(mr_doc_material *m, const char *param, const char *file, int channel, int uv_set,
                             const double *scale) {
    int p = find_param(m, param);
    if (p < 0)
        return mr_fail(MR_ERR_INVALID_ARG, "material document: '%s' is no parameter of %s", param ? param : "(null)",
                       m && m->model ? m->model->name : "(no model)");
    const mr_brdf_param *d = &m->model->params[p];
    if (d->role == MR_PARAM_SWITCH)
        return mr_fail(MR_ERR_INVALID_ARG, "material document: %s of material '%s' is a switch: no texture", param,
                       m->name);
    if (file == NULL || file[0] == '\0')
        return mr_fail(MR_ERR_INVALID_ARG, "material document: %s of material '%s': no file", param, m->name);
    for (const char *c = file; *c; c++)
        if (*c == '@' || *c == '"' || (unsigned char)*c < 0x20)
            return mr_fail(MR_ERR_INVALID_ARG,
                           "material document: file '%s' of material '%s' holds '@', '\"' or a control character",
                           file, m->name);
    if (channel < -1 || channel > 3 || (d->channels == 3 && channel != -1))
        return mr_fail(MR_ERR_INVALID_ARG, "material document: %s of material '%s': channel %d (a colour takes the "
                       "map's RGB, -1; a scalar one channel, -1..3)", param, m->name, channel);
    if (uv_set < 0)
        return mr_fail(MR_ERR_INVALID_ARG, "material document: %s of material '%s': UV set %d", param, m->name, uv_set);
    double s[3] = {1, 1, 1};
    for (int c = 0; scale && c < d->channels; c++) {
        if (!isfinite(scale[c]))
            return mr_fail(MR_ERR_INVALID_ARG, "material document: %s of material '%s': scale not finite", param,
                           m->name);
        s[c] = scale[c];
    }
    char *copy = copy_string(file);
    if (copy == NULL) return mr_fail(MR_ERR_NOMEM, "material document: out of memory");
    clear_value(&m->values[p]);
    mr_doc_value *v = &m->values[p];
    v->kind = MR_DOC_TEXTURE;
    v->file = copy;
    v->channel = channel;
    v->uv_set = uv_set;
    memcpy(v->scale, s, sizeof(s));
    return MR_OK;
}

mr_status mr_doc_set_texture_wrap(mr_doc_material *m, const char *param, mr_doc_wrap wrap_s, mr_doc_wrap wrap_t) {
    int p = find_param(m, param);
    if (p < 0 || m->values[p].kind != MR_DOC_TEXTURE)
        return mr_fail(MR_ERR_INVALID_ARG, "material document: '%s' is no textured parameter of material '%s'",
                       param ? param : "(null)", m ? m->name : "(null)");
    if ((unsigned)wrap_s > MR_DOC_WRAP_MIRROR || (unsigned)wrap_t > MR_DOC_WRAP_MIRROR)
        return mr_fail(MR_ERR_INVALID_ARG, "material document: %s of material '%s': wrap %d/%d", param, m->name,
                       (int)wrap_s, (int)wrap_t);
    m->values[p].wrap_s = wrap_s;
    m->values[p].wrap_t = wrap_t;
    return MR_OK;
}

/* The MaterialX node whose definition lists a model's inputs (usd-preview: MaterialX's UsdPreviewSurface). */
static const char *mtlx_node_of(const mr_brdf_model *model) {
    const model_writer *w = find_writer(model, MR_DOC_FORMAT_UNKNOWN);
    return w == NULL ? NULL : w->format == MR_DOC_FORMAT_USDA ? "UsdPreviewSurface" : w->node;
}

mr_status mr_doc_add_extra(mr_doc_material *m, const char *input, const char *type, const double *value) {
    if (m == NULL || input == NULL || type == NULL || value == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "material document: no material, input, type or value");
    const char *node = mtlx_node_of(m->model);
    int n = 0;
    const mr_doc_node_input *in = mr_doc_node_inputs(MR_DOC_FORMAT_MTLX, node, &n);
    int declared = -1;
    for (int i = 0; i < n; i++)
        if (strcmp(in[i].name, input) == 0) declared = i;
    if (declared < 0 || strcmp(in[declared].type, type) != 0)
        return mr_fail(MR_ERR_INVALID_ARG, "material document: material '%s': %s declares no %s input '%s'", m->name,
                       node ? node : "(no node)", type, input);
    for (int p = 0; p < m->model->param_count; p++)
        if (strcmp(mr_doc_input_name(m->model, p, find_writer(m->model, MR_DOC_FORMAT_UNKNOWN)->format), input) == 0)
            return mr_fail(MR_ERR_INVALID_ARG, "material document: material '%s': '%s' is parameter %s of %s, not "
                           "an extra input", m->name, input, m->model->params[p].name, m->model->name);
    int channels = strcmp(type, "color3") == 0 || strcmp(type, "vector3") == 0 ? 3 : 1;
    for (int c = 0; c < channels; c++)
        if (!isfinite(value[c]))
            return mr_fail(MR_ERR_INVALID_ARG, "material document: %s of material '%s' is not finite", input, m->name);
    int e = 0;
    while (e < m->extra_count && strcmp(m->extras[e].name, input) != 0) e++;
    if (e == m->extra_count) {
        char *name = copy_string(input);
        mr_doc_extra *grown = name ? realloc(m->extras, (size_t)(m->extra_count + 1) * sizeof(*grown)) : NULL;
        if (grown == NULL) {
            free(name);
            return mr_fail(MR_ERR_NOMEM, "material document: out of memory");
        }
        m->extras = grown;
        memset(&m->extras[e], 0, sizeof(m->extras[e]));
        m->extras[e].name = name;
        m->extra_count++;
    }
    snprintf(m->extras[e].type, sizeof(m->extras[e].type), "%s", type);
    for (int c = 0; c < 3; c++) m->extras[e].value[c] = c < channels ? value[c] : 0;
    return MR_OK;
}

/* ---- writers ----------------------------------------------------------------------------------------------- */

/* Unique identifiers of the materials, in order: their names made identifiers, "material_K" for an empty one, and
 * "_2", "_3" ... appended to a repeat. names[k] holds 128 bytes. */
static void material_identifiers(const mr_doc *doc, char (*names)[128]) {
    for (int k = 0; k < doc->count; k++) {
        char base[112];
        if (doc->materials[k].name[0] == '\0')
            snprintf(base, sizeof(base), "material_%d", k);
        else
            mr_doc_identifier(doc->materials[k].name, base, sizeof(base));
        snprintf(names[k], 128, "%s", base);
        for (int n = 2;; n++) {
            int taken = 0;
            for (int j = 0; j < k && !taken; j++) taken = strcmp(names[j], names[k]) == 0;
            if (!taken) break;
            snprintf(names[k], 128, "%s_%d", base, n);
        }
    }
}

static void xml_text(FILE *f, const char *s) {
    for (; *s; s++) {
        switch (*s) {
        case '&': fputs("&amp;", f); break;
        case '<': fputs("&lt;", f); break;
        case '>': fputs("&gt;", f); break;
        case '"': fputs("&quot;", f); break;
        case '\'': fputs("&apos;", f); break;
        default: fputc(*s, f);
        }
    }
}

static int all_one(const double *s, int channels) {
    for (int c = 0; c < channels; c++)
        if (s[c] != 1.0) return 0;
    return 1;
}

/* One textured parameter of a MaterialX nodegraph: image (+ texcoord) (+ extract) (+ multiply) -> output. */
static void mtlx_texture(FILE *f, const mr_brdf_param *d, const mr_doc_value *v, const char *input) {
    int colour = d->channels == 3;
    const char *image_type = colour || (v->channel >= 0 && v->channel < 3) ? "color3"
                             : v->channel == 3                              ? "color4"
                                                                            : "float";
    if (v->uv_set != 0) {
        fprintf(f, "    <texcoord name=\"%s_texcoord\" type=\"vector2\">\n", input);
        fprintf(f, "      <input name=\"index\" type=\"integer\" value=\"%d\" />\n", v->uv_set);
        fprintf(f, "    </texcoord>\n");
    }
    fprintf(f, "    <image name=\"%s_image\" type=\"%s\">\n", input, image_type);
    fprintf(f, "      <input name=\"file\" type=\"filename\" value=\"");
    xml_text(f, v->file);
    if (mr_doc_texture_is_srgb(d, v->file))
        fprintf(f, "\" colorspace=\"srgb_texture\" />\n");
    else
        fprintf(f, "\" />\n");
    static const char *const mtlx_wrap[] = {NULL, "periodic", "clamp", "mirror"};
    if (v->wrap_s)
        fprintf(f, "      <input name=\"uaddressmode\" type=\"string\" value=\"%s\" />\n", mtlx_wrap[v->wrap_s]);
    if (v->wrap_t)
        fprintf(f, "      <input name=\"vaddressmode\" type=\"string\" value=\"%s\" />\n", mtlx_wrap[v->wrap_t]);
    if (v->uv_set != 0)
        fprintf(f, "      <input name=\"texcoord\" type=\"vector2\" nodename=\"%s_texcoord\" />\n", input);
    fprintf(f, "    </image>\n");
    const char *last = "image";
    if (!colour && v->channel >= 0) {
        fprintf(f, "    <extract name=\"%s_extract\" type=\"float\">\n", input);
        fprintf(f, "      <input name=\"in\" type=\"%s\" nodename=\"%s_image\" />\n", image_type, input);
        fprintf(f, "      <input name=\"index\" type=\"integer\" value=\"%d\" />\n", v->channel);
        fprintf(f, "    </extract>\n");
        last = "extract";
    }
    const char *type = colour ? "color3" : "float";
    if (!all_one(v->scale, d->channels)) {
        fprintf(f, "    <multiply name=\"%s_scale\" type=\"%s\">\n", input, type);
        fprintf(f, "      <input name=\"in1\" type=\"%s\" nodename=\"%s_%s\" />\n", type, input, last);
        if (colour)
            fprintf(f, "      <input name=\"in2\" type=\"color3\" value=\"%.9g, %.9g, %.9g\" />\n", v->scale[0],
                    v->scale[1], v->scale[2]);
        else
            fprintf(f, "      <input name=\"in2\" type=\"float\" value=\"%.9g\" />\n", v->scale[0]);
        fprintf(f, "    </multiply>\n");
        last = "scale";
    }
    fprintf(f, "    <output name=\"%s_out\" type=\"%s\" nodename=\"%s_%s\" />\n", input, type, input, last);
}

static void write_mtlx(FILE *f, const mr_doc *doc, char (*names)[128]) {
    fprintf(f, "<?xml version=\"1.0\"?>\n");
    fprintf(f, "<!-- written by matremap: only inputs the node definitions declare; data maps read in the document's "
               "colour space, lin_rec709 (no conversion) -->\n");
    fprintf(f, "<materialx version=\"1.39\" colorspace=\"lin_rec709\">\n");
    for (int k = 0; k < doc->count; k++) {
        const mr_doc_material *m = &doc->materials[k];
        const mr_brdf_model *model = m->model;
        int textured = 0;
        for (int p = 0; p < model->param_count; p++) textured |= m->values[p].kind == MR_DOC_TEXTURE;
        if (textured) {
            fprintf(f, "  <nodegraph name=\"NG_%s\">\n", names[k]);
            for (int p = 0; p < model->param_count; p++)
                if (m->values[p].kind == MR_DOC_TEXTURE)
                    mtlx_texture(f, &model->params[p], &m->values[p],
                                 mr_doc_input_name(model, p, MR_DOC_FORMAT_MTLX));
            fprintf(f, "  </nodegraph>\n");
        }
        const char *node = mr_doc_surface_node(model, MR_DOC_FORMAT_MTLX);
        fprintf(f, "  <%s name=\"SR_%s\" type=\"surfaceshader\">\n", node, names[k]);
        for (int p = 0; p < model->param_count; p++) {
            const mr_doc_value *v = &m->values[p];
            const char *input = mr_doc_input_name(model, p, MR_DOC_FORMAT_MTLX);
            const char *type = model->params[p].channels == 3 ? "color3" : "float";
            if (v->kind == MR_DOC_CONSTANT && model->params[p].channels == 3)
                fprintf(f, "    <input name=\"%s\" type=\"color3\" value=\"%.9g, %.9g, %.9g\" />\n", input,
                        v->constant[0], v->constant[1], v->constant[2]);
            else if (v->kind == MR_DOC_CONSTANT)
                fprintf(f, "    <input name=\"%s\" type=\"float\" value=\"%.9g\" />\n", input, v->constant[0]);
            else if (v->kind == MR_DOC_TEXTURE)
                fprintf(f, "    <input name=\"%s\" type=\"%s\" nodegraph=\"NG_%s\" output=\"%s_out\" />\n", input,
                        type, names[k], input);
        }
        for (int e = 0; e < m->extra_count; e++) {
            const mr_doc_extra *x = &m->extras[e];
            fprintf(f, "    <input name=\"%s\" type=\"%s\" value=\"", x->name, x->type);
            if (strcmp(x->type, "color3") == 0 || strcmp(x->type, "vector3") == 0)
                fprintf(f, "%.9g, %.9g, %.9g", x->value[0], x->value[1], x->value[2]);
            else if (strcmp(x->type, "boolean") == 0)
                fprintf(f, "%s", x->value[0] != 0 ? "true" : "false");
            else if (strcmp(x->type, "integer") == 0)
                fprintf(f, "%d", (int)x->value[0]);
            else
                fprintf(f, "%.9g", x->value[0]);
            fprintf(f, "\" />\n");
        }
        fprintf(f, "  </%s>\n", node);
        fprintf(f, "  <surfacematerial name=\"%s\" type=\"material\">\n", names[k]);
        fprintf(f, "    <input name=\"surfaceshader\" type=\"surfaceshader\" nodename=\"SR_%s\" />\n", names[k]);
        fprintf(f, "  </surfacematerial>\n");
    }
    fprintf(f, "</materialx>\n");
}

static const char *usd_channel[] = {"r", "g", "b", "a"};

/* The index of a constant specularColor that the metallic workflow ignores (useSpecularWorkflow 0, written or the
 * default), or -1. It is left out: a conforming reader gives it no effect either way (the UsdPreviewSurface
 * specification's specularColor is the specular workflow's F0 only; src/brdf/usd_preview.c), but three.js's
 * USDLoader (r187) does not read the
 * workflow and takes it as the dielectric's F0 tint, so a (0, 0, 0) written there turns off every highlight
 * (docs/evaluation-clients.md). */
static int usd_unused_specular_color(const mr_doc_material *m) {
    int workflow = mr_brdf_param_index(m->model, "use_specular_workflow");
    int color = mr_brdf_param_index(m->model, "specular_color");
    if (workflow < 0 || color < 0 || m->values[color].kind != MR_DOC_CONSTANT) return -1;
    const mr_doc_value *w = &m->values[workflow];
    if (w->kind == MR_DOC_TEXTURE || (w->kind == MR_DOC_CONSTANT && lround(w->constant[0]) != 0)) return -1;
    return color;
}

static void write_usda(FILE *f, const mr_doc *doc, char (*names)[128]) {
    fprintf(f, "#usda 1.0\n(\n    defaultPrim = \"Materials\"\n");
    fprintf(f, "    doc = \"written by matremap: UsdPreviewSurface\"\n)\n\n");
    fprintf(f, "def Scope \"Materials\"\n{\n");
    for (int k = 0; k < doc->count; k++) {
        const mr_doc_material *m = &doc->materials[k];
        const mr_brdf_model *model = m->model;
        const char *id = names[k];
        if (k > 0) fprintf(f, "\n");
        fprintf(f, "    def Material \"%s\"\n    {\n", id);
        fprintf(f, "        token outputs:surface.connect = </Materials/%s/Surface.outputs:surface>\n\n", id);
        fprintf(f, "        def Shader \"Surface\"\n        {\n");
        fprintf(f, "            uniform token info:id = \"UsdPreviewSurface\"\n");
        int skipped = usd_unused_specular_color(m);
        for (int p = 0; p < model->param_count; p++) {
            const mr_doc_value *v = &m->values[p];
            const mr_brdf_param *d = &model->params[p];
            const char *input = mr_doc_input_name(model, p, MR_DOC_FORMAT_USDA);
            if (p == skipped) continue;
            if (v->kind == MR_DOC_CONSTANT && d->role == MR_PARAM_SWITCH)
                fprintf(f, "            int inputs:%s = %d\n", input, (int)lround(v->constant[0]));
            else if (v->kind == MR_DOC_CONSTANT && d->channels == 3)
                fprintf(f, "            color3f inputs:%s = (%.9g, %.9g, %.9g)\n", input, v->constant[0],
                        v->constant[1], v->constant[2]);
            else if (v->kind == MR_DOC_CONSTANT)
                fprintf(f, "            float inputs:%s = %.9g\n", input, v->constant[0]);
            else if (v->kind == MR_DOC_TEXTURE && d->channels == 3)
                fprintf(f, "            color3f inputs:%s.connect = </Materials/%s/%s_texture.outputs:rgb>\n", input,
                        id, input);
            else if (v->kind == MR_DOC_TEXTURE)
                fprintf(f, "            float inputs:%s.connect = </Materials/%s/%s_texture.outputs:%s>\n", input, id,
                        input, usd_channel[v->channel < 0 ? 0 : v->channel]);
        }
        for (int e = 0; e < m->extra_count; e++) { // MaterialX's types as USD's (the specification's)
            const mr_doc_extra *x = &m->extras[e];
            if (strcmp(x->name, "opacityMode") == 0)
                fprintf(f, "            token inputs:opacityMode = \"%s\"\n",
                        x->value[0] != 0 ? "presence" : "transparent");
            else if (strcmp(x->type, "color3") == 0 || strcmp(x->type, "vector3") == 0)
                fprintf(f, "            %s inputs:%s = (%.9g, %.9g, %.9g)\n",
                        strcmp(x->type, "color3") == 0 ? "color3f" : "normal3f", x->name, x->value[0], x->value[1],
                        x->value[2]);
            else if (strcmp(x->type, "integer") == 0)
                fprintf(f, "            int inputs:%s = %d\n", x->name, (int)x->value[0]);
            else
                fprintf(f, "            float inputs:%s = %.9g\n", x->name, x->value[0]);
        }
        fprintf(f, "            token outputs:surface\n        }\n");
        // One primvar reader per UV set the material's maps use.
        for (int uv = 0;; uv++) {
            int used = 0, more = 0;
            for (int p = 0; p < model->param_count; p++)
                if (m->values[p].kind == MR_DOC_TEXTURE) {
                    used |= m->values[p].uv_set == uv;
                    more |= m->values[p].uv_set > uv;
                }
            if (used) {
                fprintf(f, "\n        def Shader \"uv%d_reader\"\n        {\n", uv);
                fprintf(f, "            uniform token info:id = \"UsdPrimvarReader_float2\"\n");
                if (uv == 0)
                    fprintf(f, "            token inputs:varname = \"st\"\n");
                else
                    fprintf(f, "            token inputs:varname = \"st%d\"\n", uv);
                fprintf(f, "            float2 outputs:result\n        }\n");
            }
            if (!more) break;
        }
        for (int p = 0; p < model->param_count; p++) {
            const mr_doc_value *v = &m->values[p];
            const mr_brdf_param *d = &model->params[p];
            if (v->kind != MR_DOC_TEXTURE) continue;
            const char *input = mr_doc_input_name(model, p, MR_DOC_FORMAT_USDA);
            fprintf(f, "\n        def Shader \"%s_texture\"\n        {\n", input);
            fprintf(f, "            uniform token info:id = \"UsdUVTexture\"\n");
            fprintf(f, "            asset inputs:file = @%s@\n", v->file);
            fprintf(f, "            token inputs:sourceColorSpace = \"%s\"\n",
                    mr_doc_texture_is_srgb(d, v->file) ? "sRGB" : "raw");
            fprintf(f, "            float2 inputs:st.connect = </Materials/%s/uv%d_reader.outputs:result>\n", id,
                    v->uv_set);
            static const char *const usd_wrap[] = {NULL, "repeat", "clamp", "mirror"};
            if (v->wrap_s) fprintf(f, "            token inputs:wrapS = \"%s\"\n", usd_wrap[v->wrap_s]);
            if (v->wrap_t) fprintf(f, "            token inputs:wrapT = \"%s\"\n", usd_wrap[v->wrap_t]);
            if (!all_one(v->scale, d->channels)) {
                if (d->channels == 3)
                    fprintf(f, "            float4 inputs:scale = (%.9g, %.9g, %.9g, 1)\n", v->scale[0], v->scale[1],
                            v->scale[2]);
                else
                    fprintf(f, "            float4 inputs:scale = (%.9g, %.9g, %.9g, %.9g)\n", v->scale[0],
                            v->scale[0], v->scale[0], v->scale[0]);
            }
            if (d->channels == 3)
                fprintf(f, "            float3 outputs:rgb\n");
            else
                fprintf(f, "            float outputs:%s\n", usd_channel[v->channel < 0 ? 0 : v->channel]);
            fprintf(f, "        }\n");
        }
        fprintf(f, "    }\n");
    }
    fprintf(f, "}\n");
}

mr_status mr_doc_to_text(const mr_doc *doc, mr_doc_format format, char **out) {
    if (doc == NULL || out == NULL || (format != MR_DOC_FORMAT_MTLX && format != MR_DOC_FORMAT_USDA))
        return mr_fail(MR_ERR_INVALID_ARG, "material document: no document, or a format other than mtlx and usda");
    for (int k = 0; k < doc->count; k++)
        if (find_writer(doc->materials[k].model, format) == NULL)
            return mr_fail(MR_ERR_INVALID_ARG, "material document: material '%s' is %s, which .%s does not write "
                           "(models: %s)", doc->materials[k].name, doc->materials[k].model->name,
                           mr_doc_format_name(format), writable_models());
    char (*names)[128] = calloc(doc->count > 0 ? (size_t)doc->count : 1, sizeof(*names));
    if (names == NULL) return mr_fail(MR_ERR_NOMEM, "material document: out of memory");
    material_identifiers(doc, names);
    char *text = NULL;
    size_t size = 0;
    FILE *f = open_memstream(&text, &size);
    if (f == NULL) {
        free(names);
        return mr_fail(MR_ERR_NOMEM, "material document: out of memory");
    }
    mr_c_numeric numeric;
    mr_status st = mr_c_numeric_enter(&numeric, "material document");
    if (st == MR_OK) {
        if (format == MR_DOC_FORMAT_MTLX)
            write_mtlx(f, doc, names);
        else
            write_usda(f, doc, names);
        mr_c_numeric_leave(&numeric);
    }
    int bad = ferror(f);
    fclose(f);
    free(names);
    if (st != MR_OK || bad) {
        free(text);
        return st != MR_OK ? st : mr_fail(MR_ERR_NOMEM, "material document: out of memory");
    }
    *out = text;
    return MR_OK;
}

mr_status mr_doc_write(const mr_doc *doc, const char *path) {
    mr_doc_format format = mr_doc_format_from_path(path);
    if (format == MR_DOC_FORMAT_UNKNOWN)
        return mr_fail(MR_ERR_INVALID_ARG, "material document '%s': the extension chooses the format: .mtlx or .usda",
                       path ? path : "(null)");
    char *text = NULL;
    mr_status st = mr_doc_to_text(doc, format, &text);
    if (st != MR_OK) return st;
    st = mr_atomic_write_bytes(path, text, strlen(text));
    free(text);
    return st;
}
