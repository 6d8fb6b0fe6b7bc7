/*
 * translate.c — MaterialX's closed-form translation graphs (translate.h), written from the nodegraphs of
 * MaterialX 1.39.5 (the .mtlx files of libraries/bxdf/translation/, commit 4177b2cb), node by node; docs/remap.md
 * lists each graph's formulas. Only the outputs a surface BRDF of this project holds are computed (transmission, sheen,
 * subsurface, emission, thin film, opacity, normals and anisotropy are outside every model here and enter the
 * graphs only through inputs that are zero for an opaque isotropic material).
 */
#include <math.h>
#include <string.h>

#include "mr_internal.h"
#include "metrics/metrics.h"
#include "remap/translate.h"

static const mr_translation SS_TO_GLTF = {
    "standard-surface", "gltf", "NG_standard_surface_to_gltf_pbr",
    "libraries/bxdf/translation/standard_surface_to_gltf_pbr.mtlx",
    "diffuse_roughness, coat_ior, coat_affect_color, coat_affect_roughness; the graph's clearcoat "
    "(coat x mean(coat_color)) and clearcoat_roughness, which need KHR_materials_clearcoat (not in the gltf model)"};
static const mr_translation SS_TO_USD = {
    "standard-surface", "usd-preview", "NG_standard_surface_to_UsdPreviewSurface",
    "libraries/bxdf/translation/standard_surface_to_usd.mtlx",
    "specular, specular_color, diffuse_roughness, coat_ior, coat_affect_color, coat_affect_roughness "
    "(the metallic workflow has no specular inputs; the clearcoat takes the specular ior)"};
static const mr_translation OPENPBR_TO_SS = {
    "openpbr", "standard-surface", "NG_open_pbr_surface_to_standard_surface",
    "libraries/bxdf/translation/open_pbr_to_standard_surface.mtlx",
    "nothing by name; coat_darkening is folded into base_color, the coat's roughness into specular_roughness, "
    "and coat_affect_roughness is set to 1"};

static const mr_translation *const TRANSLATIONS[] = {&SS_TO_GLTF, &SS_TO_USD, &OPENPBR_TO_SS, NULL};

const mr_translation *const *mr_translations(void) {
    return TRANSLATIONS;
}

mr_status mr_translate_find(const mr_brdf_model *from, const mr_brdf_model *to, const mr_translation **out) {
    if (from == NULL || to == NULL) return mr_fail(MR_ERR_INVALID_ARG, "translate: a model is NULL");
    for (int k = 0; TRANSLATIONS[k] != NULL; k++) {
        if (strcmp(TRANSLATIONS[k]->from, from->name) == 0 && strcmp(TRANSLATIONS[k]->to, to->name) == 0) {
            *out = TRANSLATIONS[k];
            return MR_OK;
        }
    }
    return mr_fail(MR_ERR_UNSUPPORTED,
                   "no MaterialX translation graph from '%s' to '%s' (graphs: standard-surface -> gltf, "
                   "standard-surface -> usd-preview, openpbr -> standard-surface)",
                   from->name, to->name);
}

/* Named access to packed vectors; a name missing from a descriptor is recorded, not dereferenced. */
typedef struct access {
    const mr_brdf_model *from, *to;
    const double *in;
    double *out;
    const char *missing; /* the first parameter name a descriptor lacks */
} access;

static int slot(const mr_brdf_model *model, const char *name) {
    int index = mr_brdf_param_index(model, name);
    return index < 0 ? -1 : mr_brdf_param_offset(model, index);
}

static double get(access *a, const char *name, int channel) {
    int s = slot(a->from, name);
    if (s < 0) {
        if (a->missing == NULL) a->missing = name;
        return 0.0;
    }
    int index = mr_brdf_param_index(a->from, name);
    return a->in[s + (a->from->params[index].channels == 3 ? channel : 0)];
}

static void get3(access *a, const char *name, double rgb[3]) {
    for (int c = 0; c < 3; c++) rgb[c] = get(a, name, c);
}

static void set(access *a, const char *name, double value) {
    int s = slot(a->to, name);
    if (s < 0) {
        if (a->missing == NULL) a->missing = name;
        return;
    }
    a->out[s] = value;
}

static void set3(access *a, const char *name, const double rgb[3]) {
    int s = slot(a->to, name);
    if (s < 0) {
        if (a->missing == NULL) a->missing = name;
        return;
    }
    for (int c = 0; c < 3; c++) a->out[s + c] = rgb[c];
}

static double mix(double bg, double fg, double t) {
    return bg * (1.0 - t) + fg * t; /* MaterialX's mix: fg at mix = 1 */
}

/* NG_standard_surface_to_gltf_pbr: base colour scaled by base and, where coat_color is not black, attenuated by
 * mix(1, coat_color, coat) (nodes scaledBaseColor, coatAttenuation, baseColor: an exact test of the sum of
 * coat_color against 0); metallic = metalness; roughness = sqrt of roughness_anisotropy's alpha_y, which is
 * clamp(r^2, eps, 1) at anisotropy 0, so r itself; specular, specular_color, ior passed through. */
static void standard_surface_to_gltf(access *a) {
    double base = get(a, "base", 0), color[3], coat_color[3], coat = get(a, "coat", 0);
    get3(a, "base_color", color);
    get3(a, "coat_color", coat_color);
    const int has_coat_color = coat_color[0] + coat_color[1] + coat_color[2] != 0.0;
    double out[3];
    for (int c = 0; c < 3; c++) out[c] = base * color[c] * (has_coat_color ? mix(1.0, coat_color[c], coat) : 1.0);
    set3(a, "base_color", out);
    set(a, "metallic", get(a, "metalness", 0));
    double r = get(a, "specular_roughness", 0);
    set(a, "roughness", sqrt(fmin(fmax(r * r, 1.1920929e-7), 1.0))); /* M_FLOAT_EPS of the genglsl node */
    set(a, "specular", get(a, "specular", 0));
    double specular_color[3];
    get3(a, "specular_color", specular_color);
    set3(a, "specular_color", specular_color);
    set(a, "ior", get(a, "specular_ior", 0));
}

/* NG_standard_surface_to_UsdPreviewSurface: diffuseColor = base base_color mix(1, coat_color, coat) (subsurface
 * 0); metallic, roughness, ior passed through; clearcoat = mean over channels of coat coat_color;
 * clearcoatRoughness = coat_roughness. useSpecularWorkflow stays 0 (the graph drives the metallic workflow). */
static void standard_surface_to_usd(access *a) {
    double base = get(a, "base", 0), color[3], coat_color[3], coat = get(a, "coat", 0);
    get3(a, "base_color", color);
    get3(a, "coat_color", coat_color);
    double diffuse[3];
    for (int c = 0; c < 3; c++) diffuse[c] = base * color[c] * mix(1.0, coat_color[c], coat);
    set3(a, "diffuse_color", diffuse);
    set(a, "use_specular_workflow", 0.0);
    set(a, "metallic", get(a, "metalness", 0));
    set(a, "roughness", get(a, "specular_roughness", 0));
    set(a, "ior", get(a, "specular_ior", 0));
    set(a, "clearcoat", coat * (coat_color[0] + coat_color[1] + coat_color[2]) / 3.0);
    set(a, "clearcoat_roughness", get(a, "coat_roughness", 0));
}

/* NG_open_pbr_surface_to_standard_surface. Coat darkening folded into the base colour: Kcoat = 1 - (1 - F0_c) /
 * n_c^2 with F0_c = ((n_c - 1)/(n_c + 1))^2; Ebase = mix(base_color, base_color specular_weight, metalness)
 * (subsurface 0); darkening = (1 - Kcoat)/(1 - Ebase Kcoat) per channel, applied as mix(1, darkening,
 * coat_weight coat_darkening). specular_roughness = mix(specular_roughness, coat_roughness, coat_weight);
 * coat_affect_roughness = 1; every other output passes its input through. */
static void openpbr_to_standard_surface(access *a) {
    double color[3], n_c = get(a, "coat_ior", 0), coat = get(a, "coat_weight", 0);
    double metalness = get(a, "base_metalness", 0), specular = get(a, "specular_weight", 0);
    get3(a, "base_color", color);
    const double f0_root = (n_c - 1.0) / (n_c + 1.0);
    const double k_coat = 1.0 - (1.0 - f0_root * f0_root) / (n_c * n_c);
    const double darkening_weight = coat * get(a, "coat_darkening", 0);
    double base_color[3];
    for (int c = 0; c < 3; c++) {
        double e_base = mix(color[c], color[c] * specular, metalness);
        double darkening = (1.0 - k_coat) / (1.0 - e_base * k_coat);
        base_color[c] = color[c] * mix(1.0, darkening, darkening_weight);
    }
    set(a, "base", get(a, "base_weight", 0));
    set3(a, "base_color", base_color);
    set(a, "diffuse_roughness", get(a, "base_diffuse_roughness", 0));
    set(a, "metalness", metalness);
    set(a, "specular", specular);
    double rgb[3];
    get3(a, "specular_color", rgb);
    set3(a, "specular_color", rgb);
    set(a, "specular_roughness", mix(get(a, "specular_roughness", 0), get(a, "coat_roughness", 0), coat));
    set(a, "specular_ior", get(a, "specular_ior", 0));
    set(a, "coat", coat);
    get3(a, "coat_color", rgb);
    set3(a, "coat_color", rgb);
    set(a, "coat_roughness", get(a, "coat_roughness", 0));
    set(a, "coat_ior", n_c);
    set(a, "coat_affect_roughness", 1.0);
}

mr_status mr_translate(const mr_brdf_model *from, const double *values, const mr_brdf_model *to, double *out) {
    const mr_translation *t = NULL;
    mr_status status = mr_translate_find(from, to, &t);
    if (status != MR_OK) return status;
    if (values == NULL || out == NULL) return mr_fail(MR_ERR_INVALID_ARG, "translate: values or out is NULL");
    for (int p = 0; p < from->param_count; p++) {
        const int offset = mr_brdf_param_offset(from, p);
        for (int c = 0; c < from->params[p].channels; c++) {
            if (!isfinite(values[offset + c]))
                return mr_fail(MR_ERR_INVALID_ARG, "translate: %s %s = %g: expected a finite value", from->name,
                               from->params[p].name, values[offset + c]);
        }
    }
    double result[MR_BRDF_MAX_VALUES];
    mr_brdf_default_values(to, result);
    access a = {from, to, values, result, NULL};
    if (t == &SS_TO_GLTF) standard_surface_to_gltf(&a);
    else if (t == &SS_TO_USD) standard_surface_to_usd(&a);
    else openpbr_to_standard_surface(&a);
    if (a.missing != NULL)
        return mr_fail(MR_ERR_UNSUPPORTED, "translate %s -> %s: the models have no parameter '%s' the graph %s uses",
                       from->name, to->name, a.missing, t->graph);
    // Into the target's ranges, so the values can be given back to any command (a roughness 0 -> the floor).
    for (int p = 0; p < to->param_count; p++) {
        const mr_brdf_param *param = &to->params[p];
        const int offset = mr_brdf_param_offset(to, p);
        for (int c = 0; c < param->channels; c++)
            result[offset + c] = fmin(fmax(result[offset + c], param->min_value), param->max_value);
    }
    memcpy(out, result, (size_t)mr_brdf_value_count(to) * sizeof *out);
    return MR_OK;
}

mr_status mr_translate_compare(const mr_render_plan *plan, const mr_brdf_model *from, const double *values,
                               const mr_brdf_model *to, mr_translate_result *out) {
    const double start = mr_now_seconds();
    mr_translate_result r;
    memset(&r, 0, sizeof r);
    mr_status status = mr_translate(from, values, to, r.values);
    if (status != MR_OK) return status;
    if (plan == NULL) return mr_fail(MR_ERR_INVALID_ARG, "translate: the render plan is NULL");
    mr_image *source = NULL, *translated = NULL, *mask = NULL;
    status = mr_render(plan, from, values, MR_COMPONENT_FULL, &source);
    if (status == MR_OK) status = mr_render(plan, to, r.values, MR_COMPONENT_FULL, &translated);
    if (status == MR_OK) status = mr_rmse(translated, source, &r.rmse);
    if (status == MR_OK) status = mr_ssim(translated, source, NULL, &r.ssim, NULL);
    if (status == MR_OK) status = mr_render_plan_coverage_mask(plan, &mask);
    if (status == MR_OK) {
        // As mr_remap: RMS difference over the covered pixels relative to the source's RMS radiance there, the
        // latter floored at 1e-4 (a black source).
        double diff = 0.0, energy = 0.0;
        long covered = 0;
        for (int y = 0; y < source->height; y++) {
            for (int x = 0; x < source->width; x++) {
                if (!(*mr_image_at(mask, x, y) > 0.0f)) continue;
                const float *s = mr_image_at(source, x, y), *t = mr_image_at(translated, x, y);
                for (int c = 0; c < 3; c++) {
                    diff += ((double)t[c] - s[c]) * ((double)t[c] - s[c]);
                    energy += (double)s[c] * s[c];
                }
                covered++;
            }
        }
        const double n = covered > 0 ? 3.0 * (double)covered : 1.0;
        r.relative_rmse = sqrt(diff / n) / fmax(sqrt(energy / n), 1e-4);
    }
    mr_image_free(source);
    mr_image_free(translated);
    mr_image_free(mask);
    if (status != MR_OK) return status;
    r.seconds = mr_now_seconds() - start;
    *out = r;
    return MR_OK;
}
