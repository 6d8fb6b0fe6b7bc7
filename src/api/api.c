/* api.c — flat entry points for the Python package (api.h): the commands' library calls behind names, strings and
 * caller-owned buffers. JSON answers are built in an open_memstream buffer. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "c_locale.h"
#include "mr_internal.h"
#include "api/api.h"
#include "brdf/brdf.h"
#include "gltf/mr_gltf.h"
#include "gltf/mr_gltf_convert.h"
#include "gltf/mr_gltf_scene.h"
#include "report/report.h"
#include "workflow/workflow.h"
#include "io/image_io.h"
#include "remap/remap.h"
#include "render/render.h"
#include "transform/transform.h"

void mr_api_free(void *text) {
    free(text);
}

static void json_string(FILE *out, const char *text) {
    fputc('"', out);
    for (const unsigned char *c = (const unsigned char *)(text ? text : ""); *c; c++) {
        if (*c == '"' || *c == '\\')
            fprintf(out, "\\%c", *c);
        else if (*c < 0x20)
            fprintf(out, "\\u%04x", *c);
        else
            fputc(*c, out);
    }
    fputc('"', out);
}

/* A text stream for a JSON answer, its numbers in the C locale whatever the host's (Blender's Python may set one
 * with a decimal comma); *json_out set by json_close. */
typedef struct json_text {
    FILE *out;
    char *text;
    size_t size;
    mr_c_numeric locale;
} json_text;

static mr_status json_open(json_text *j) {
    memset(j, 0, sizeof *j);
    mr_status status = mr_c_numeric_enter(&j->locale, "JSON text");
    if (status != MR_OK) return status;
    j->out = open_memstream(&j->text, &j->size);
    if (j->out != NULL) return MR_OK;
    mr_c_numeric_leave(&j->locale);
    return mr_fail(MR_ERR_NOMEM, "JSON text: out of memory");
}

static mr_status json_close(json_text *j, mr_status status, char **json_out) {
    int bad = ferror(j->out);
    fclose(j->out);
    mr_c_numeric_leave(&j->locale);
    if (status == MR_OK && bad) status = mr_fail(MR_ERR_NOMEM, "JSON text: out of memory");
    if (status == MR_OK)
        *json_out = j->text;
    else
        free(j->text);
    return status;
}

static void values_json(FILE *out, const mr_brdf_model *model, const double *values) {
    for (int i = 0; i < model->param_count; i++) {
        const mr_brdf_param *p = &model->params[i];
        int offset = mr_brdf_param_offset(model, i);
        fprintf(out, "%s", i ? ", " : "");
        json_string(out, p->name);
        if (p->channels == 3)
            fprintf(out, ": [%.17g, %.17g, %.17g]", values[offset], values[offset + 1], values[offset + 2]);
        else
            fprintf(out, ": %.17g", values[offset]);
    }
}

mr_status mr_api_models_json(char **json_out) {
    if (json_out == NULL) return mr_fail(MR_ERR_INVALID_ARG, "models: NULL argument");
    *json_out = NULL;
    json_text j;
    mr_status status = json_open(&j);
    if (status != MR_OK) return status;
    const mr_brdf_model *const *models = mr_brdf_models();
    fprintf(j.out, "[");
    for (int k = 0; models[k] != NULL; k++) {
        const mr_brdf_model *m = models[k];
        fprintf(j.out, "%s{\"name\": ", k ? ", " : "");
        json_string(j.out, m->name);
        fprintf(j.out, ", \"summary\": ");
        json_string(j.out, m->summary);
        fprintf(j.out, ", \"params\": [");
        for (int i = 0; i < m->param_count; i++) {
            const mr_brdf_param *p = &m->params[i];
            fprintf(j.out, "%s{\"name\": ", i ? ", " : "");
            json_string(j.out, p->name);
            fprintf(j.out, ", \"channels\": %d, \"default\": ", p->channels);
            if (p->channels == 3)
                fprintf(j.out, "[%.17g, %.17g, %.17g]", mr_brdf_param_default(p, 0), mr_brdf_param_default(p, 1),
                        mr_brdf_param_default(p, 2));
            else
                fprintf(j.out, "%.17g", p->default_value);
            fprintf(j.out, ", \"min\": %.17g, \"max\": %.17g, \"role\": \"%s\", \"lobe\": \"%s\", \"fit\": \"%s\", "
                    "\"meaning\": ", p->min_value, p->max_value, mr_param_role_name(p->role),
                    mr_param_lobe_name(p->lobe), mr_brdf_hold_reason(m, 0, i) == MR_HOLD_FITTED ? "fitted"
                    : mr_brdf_hold_reason(m, 0, i) == MR_HOLD_SWITCH ? "switch" : "held");
            json_string(j.out, p->meaning);
            fprintf(j.out, "}");
        }
        fprintf(j.out, "]}");
    }
    fprintf(j.out, "]");
    return json_close(&j, MR_OK, json_out);
}

mr_status mr_api_render(const char *model, const char *const *assignments, int count, int size, const char *light,
                        const char *env_path, const char *component, int threads, mr_image *out) {
    if (model == NULL || out == NULL || (count > 0 && assignments == NULL) || count < 0)
        return mr_fail(MR_ERR_INVALID_ARG, "render: NULL argument");
    if (size < 1 || size > MR_RENDER_MAX_SIZE)
        return mr_fail(MR_ERR_INVALID_ARG, "render: size %d: expected 1 .. %d", size, MR_RENDER_MAX_SIZE);
    if (out->width != size || out->height != size || out->channels != 3 || out->pixels == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "render: the output image is %dx%dx%d, expected %dx%dx3", out->width,
                       out->height, out->channels, size, size);
    if (threads < 0 || threads > 1024) return mr_fail(MR_ERR_INVALID_ARG, "render: threads %d: expected 0 .. 1024",
                                                      threads);
    mr_fit_scene_options scene_opts = {0};
    scene_opts.size = size;
    mr_status status = MR_OK;
    if (light != NULL && (status = mr_fit_light_from_name(light, &scene_opts.light)) != MR_OK) return status;
    mr_component comp = MR_COMPONENT_FULL;
    if (component != NULL && (status = mr_component_from_name(component, &comp)) != MR_OK) return status;
    mr_material *material = NULL;
    mr_material_text_report report;
    status = mr_material_from_assignments(model, assignments, count, NULL, &material, &report);
    if (status != MR_OK) return status;
    mr_image *env = NULL;
    if (env_path != NULL) {
        char label[4200];
        snprintf(label, sizeof label, "image '%s'", env_path); // named by its file, as the command names it
        status = mr_img_read(env_path, NULL, &env);
        if (status == MR_OK) status = mr_image_check_radiance(env, label);
        if (status != MR_OK) {
            mr_image_free(env);
            mr_material_free(material);
            return status;
        }
    }
    mr_scene scene = mr_scene_fit(&scene_opts);
    scene.threads = threads;
    if (env != NULL) { // as the command: the map alone, or beside the point light when a light is named
        int slot = light != NULL ? scene.light_count++ : 0;
        scene.lights[slot] = mr_light_environment(env, 1.0, 0.0, 0);
    }
    mr_render_plan *plan = NULL;
    status = mr_render_plan_create(&scene, &plan);
    if (status == MR_OK)
        status = mr_render_textured_into(plan, material->model, material->values, &material->textures, comp, out);
    mr_render_plan_free(plan);
    mr_image_free(env);
    mr_material_free(material);
    return status;
}

static mr_status parse_values(const mr_brdf_model *model, const char *const *assignments, int count, double *values) {
    mr_brdf_default_values(model, values);
    for (int k = 0; k < count; k++) {
        mr_status status = mr_brdf_parse_assignment(model, assignments[k], values);
        if (status != MR_OK) return status;
    }
    return MR_OK;
}

static mr_status parse_freed(const mr_brdf_model *model, const char *list, unsigned *freed) {
    char copy[1024];
    if (strlen(list) >= sizeof copy) return mr_fail(MR_ERR_INVALID_ARG, "free: list too long");
    memcpy(copy, list, strlen(list) + 1);
    char *save = NULL;
    for (char *name = strtok_r(copy, ",", &save); name != NULL; name = strtok_r(NULL, ",", &save)) {
        const int p = mr_brdf_param_index(model, name);
        if (p < 0 || p >= 32)
            return mr_fail(MR_ERR_INVALID_ARG, "free %s: '%s' has no parameter '%s'", list, model->name, name);
        if (!(model->params[p].flags & MR_PARAM_FIT_FIXED))
            return mr_fail(MR_ERR_INVALID_ARG, "free %s: '%s' fits %s already", list, model->name, name);
        *freed |= 1u << p;
    }
    return MR_OK;
}

mr_status mr_api_remap(const char *from, const char *const *from_assignments, int from_count, const char *to,
                       const char *const *to_assignments, int to_count, int size, const char *light,
                       const char *strategy, const char *hold_list, const char *tie_list, const char *free_list,
                       int threads, char **json_out) {
    if (from == NULL || to == NULL || json_out == NULL || from_count < 0 || to_count < 0)
        return mr_fail(MR_ERR_INVALID_ARG, "remap: NULL argument");
    *json_out = NULL;
    if (size != 0 && (size < 16 || size > 4096))
        return mr_fail(MR_ERR_INVALID_ARG, "remap: size %d: expected 16 .. 4096", size);
    if (threads < 0 || threads > 1024)
        return mr_fail(MR_ERR_INVALID_ARG, "remap: threads %d: expected 0 .. 1024", threads);
    mr_remap_options opts = {0};
    opts.threads = threads;
    mr_fit_scene_options scene_opts = {0};
    mr_status status = MR_OK;
    if (light != NULL && (status = mr_fit_light_from_name(light, &scene_opts.light)) != MR_OK) return status;
    if (strategy != NULL && (status = mr_remap_strategy_from_name(strategy, &opts.strategy)) != MR_OK) return status;
    const mr_brdf_model *target = mr_brdf_find(to);
    if (target == NULL) return MR_ERR_INVALID_ARG;
    double target_values[MR_BRDF_MAX_VALUES], source_values[MR_BRDF_MAX_VALUES];
    if ((status = parse_values(target, to_assignments, to_count, target_values)) != MR_OK) return status;
    opts.target_values = target_values;
    if (hold_list != NULL && (status = mr_brdf_parse_holds(target, hold_list, target_values, &opts.held)) != MR_OK)
        return status;
    if (free_list != NULL && (status = parse_freed(target, free_list, &opts.freed)) != MR_OK) return status;
    const mr_brdf_model *source = mr_brdf_find(from);
    if (source == NULL) return MR_ERR_INVALID_ARG;
    if ((status = parse_values(source, from_assignments, from_count, source_values)) != MR_OK) return status;
    if (tie_list == NULL)
        opts.ties = mr_brdf_default_ties(source, target);
    else if ((status = mr_brdf_parse_ties(source, target, tie_list, &opts.ties)) != MR_OK)
        return status;
    opts.ties.tied &= ~opts.held;

    scene_opts.size = size > 0 ? size : MR_REMAP_DEFAULT_SIZE;
    mr_scene scene = mr_scene_fit(&scene_opts);
    mr_render_plan *plan = NULL;
    mr_remap_result result;
    status = mr_render_plan_create(&scene, &plan);
    if (status == MR_OK) status = mr_remap(plan, source, source_values, target, &opts, &result);
    mr_render_plan_free(plan);
    if (status != MR_OK) return status;

    json_text j;
    if ((status = json_open(&j)) != MR_OK) return status;
    fprintf(j.out, "{\"to\": ");
    json_string(j.out, target->name);
    fprintf(j.out, ", \"from\": {\"model\": ");
    json_string(j.out, source->name);
    fprintf(j.out, ", \"values\": {");
    values_json(j.out, source, source_values);
    fprintf(j.out, "}}, \"strategy\": \"%s\", \"size\": %d, \"light\": \"%s\", \"values\": {",
            mr_remap_strategy_name(opts.strategy), scene_opts.size, mr_fit_light_name(scene_opts.light));
    values_json(j.out, target, result.values);
    fprintf(j.out, "}, \"rmse\": %.17g, \"relative_rmse\": %.17g, \"ssim\": %.17g, \"renders\": %ld, "
            "\"seconds\": %.6f, \"outcome\": \"%s\", \"detail\": ", result.rmse, result.relative_rmse, result.ssim,
            result.renders, result.seconds, mr_fit_outcome_name(result.outcome));
    json_string(j.out, result.detail);
    fprintf(j.out, "}");
    return json_close(&j, MR_OK, json_out);
}

static mr_status find_kind(const char *source, const char *target, const char *method, const mr_transform_kind **out) {
    if (source == NULL || target == NULL || method == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "transform: NULL argument");
    *out = mr_transform_find(source, target, method);
    return *out != NULL ? MR_OK : MR_ERR_INVALID_ARG; // mr_transform_find names the methods there are
}

mr_status mr_api_transform_describe(const char *source, const char *target, const char *method, char **json_out) {
    const mr_transform_kind *kind = NULL;
    if (json_out == NULL) return mr_fail(MR_ERR_INVALID_ARG, "transform: NULL argument");
    *json_out = NULL;
    mr_status status = find_kind(source, target, method, &kind);
    if (status != MR_OK) return status;
    json_text j;
    if ((status = json_open(&j)) != MR_OK) return status;
    fprintf(j.out, "{\"name\": ");
    json_string(j.out, kind->name);
    fprintf(j.out, ", \"summary\": ");
    json_string(j.out, kind->summary);
    fprintf(j.out, ", \"inputs\": [");
    for (int i = 0; i < kind->input_count; i++) {
        const mr_transform_slot *s = &kind->inputs[i];
        fprintf(j.out, "%s{\"name\": ", i ? ", " : "");
        json_string(j.out, s->name);
        fprintf(j.out, ", \"channels\": %d, \"optional\": %s, \"min\": %.17g, \"max\": %.17g}", s->channels,
                (s->flags & MR_SLOT_OPTIONAL) ? "true" : "false", s->min, s->max);
    }
    fprintf(j.out, "], \"outputs\": [");
    for (int i = 0; i < kind->output_count; i++) {
        const mr_transform_slot *s = &kind->outputs[i];
        fprintf(j.out, "%s{\"name\": ", i ? ", " : "");
        json_string(j.out, s->name);
        fprintf(j.out, ", \"channels\": %d}", s->channels);
    }
    fprintf(j.out, "]}");
    return json_close(&j, MR_OK, json_out);
}

mr_status mr_api_transform_convert(const char *source, const char *target, const char *method, double dielectric_f0,
                                   int threads, const mr_image *const *in, mr_image *const *out) {
    const mr_transform_kind *kind = NULL;
    mr_status status = find_kind(source, target, method, &kind);
    if (status != MR_OK) return status;
    if (in == NULL || out == NULL) return mr_fail(MR_ERR_INVALID_ARG, "transform: NULL argument");
    mr_transform_map maps[MR_TRANSFORM_MAX_SLOTS];
    memset(maps, 0, sizeof maps);
    for (int i = 0; i < kind->input_count; i++) {
        const mr_transform_slot *s = &kind->inputs[i];
        maps[i].image = in[i];
        if (in[i] == NULL && !(s->flags & MR_SLOT_OPTIONAL))
            return mr_fail(MR_ERR_INVALID_ARG, "transform %s: input '%s' is required", kind->name, s->name);
        if (in[i] == NULL) return mr_fail(MR_ERR_INVALID_ARG, "transform %s: input '%s': a default is not supported "
                                          "here; give an image", kind->name, s->name);
    }
    mr_transform_options topts = {0};
    topts.threads = threads;
    topts.dielectric_f0 = dielectric_f0;
    mr_transform *t = NULL;
    if ((status = mr_transform_create(kind, &topts, &t)) != MR_OK) return status;
    mr_image *converted[MR_TRANSFORM_MAX_SLOTS] = {0};
    status = mr_transform_convert_maps(t, maps, converted, NULL);
    for (int j = 0; status == MR_OK && j < kind->output_count; j++) {
        const mr_image *c = converted[j];
        mr_image *o = out[j];
        if (o == NULL) continue;
        if (o->width != c->width || o->height != c->height || o->channels != c->channels)
            status = mr_fail(MR_ERR_INVALID_ARG, "transform %s: output '%s' is %dx%dx%d, expected %dx%dx%d",
                             kind->name, kind->outputs[j].name, o->width, o->height, o->channels, c->width,
                             c->height, c->channels);
        else
            memcpy(o->pixels, c->pixels, mr_image_value_count(c) * sizeof(float));
    }
    for (int j = 0; j < kind->output_count; j++) mr_image_free(converted[j]);
    mr_transform_free(t);
    return status;
}

static const char *outcome_name(mr_gltf_convert_outcome outcome) {
    static const char *const names[] = {"skipped", "converted", "kept", "shared"};
    return (unsigned)outcome < sizeof names / sizeof names[0] ? names[outcome] : "?";
}

mr_status mr_api_gltf_convert(const char *input, const char *output, const char *direction, const char *method,
                              int overwrite, int threads, char **json_out) {
    if (input == NULL || output == NULL || direction == NULL || json_out == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "gltf: NULL argument");
    *json_out = NULL;
    int to_metal = strcmp(direction, "spec2metal") == 0;
    if (!to_metal && strcmp(direction, "metal2spec") != 0)
        return mr_fail(MR_ERR_INVALID_ARG, "gltf: direction '%s': expected spec2metal or metal2spec", direction);
    if (threads < 0 || threads > 1024)
        return mr_fail(MR_ERR_INVALID_ARG, "gltf: threads %d: expected 0 .. 1024", threads);
    if (method == NULL) method = to_metal ? "weighted" : "eq2"; // the command's defaults for PNG textures
    const mr_transform_kind *kind = to_metal ? mr_transform_find("gltf-specgloss", "gltf", method)
                                             : mr_transform_find("gltf", "gltf-specgloss", method);
    if (kind == NULL) return MR_ERR_INVALID_ARG;
    mr_transform_options to = {0};
    to.threads = threads;
    // As the command: both readings share a base colour read as the paper reads the diffuse (docs/gltf.md).
    to.plain_diffuse = to_metal && (kind->flags & MR_TRANSFORM_CONVENTION) && strcmp(method, "extension") != 0 &&
                       strcmp(method, "khronos") != 0;
    mr_transform *t = NULL;
    mr_status status = mr_transform_create(kind, &to, &t);
    if (status != MR_OK) return status;
    mr_gltf_convert_result result = {0, NULL, {0, 0, 0, 0}};
    mr_gltf_convert_options co = {0};
    co.transform = t;
    co.image_format = "png";
    co.overwrite = overwrite != 0;
    status = mr_gltf_convert_file(input, output, &co, &result);
    mr_transform_free(t);
    if (status != MR_OK) return status;
    json_text j;
    if ((status = json_open(&j)) != MR_OK) {
        mr_gltf_convert_result_free(&result);
        return status;
    }
    fprintf(j.out, "{\"input\": ");
    json_string(j.out, input);
    fprintf(j.out, ", \"output\": ");
    json_string(j.out, output);
    fprintf(j.out, ", \"direction\": \"%s\", \"method\": ", direction);
    json_string(j.out, method);
    fprintf(j.out, ", \"materials\": [");
    for (int k = 0; k < result.material_count; k++) {
        const mr_gltf_material_report *r = &result.materials[k];
        fprintf(j.out, "%s{\"name\": ", k ? ", " : "");
        json_string(j.out, r->name);
        fprintf(j.out, ", \"outcome\": \"%s\", \"reason\": ", outcome_name(r->outcome));
        json_string(j.out, r->reason);
        fprintf(j.out, ", \"width\": %d, \"height\": %d, \"flagged\": %zu, \"off_manifold\": %zu, "
                "\"nonfinite\": %zu, \"clamped\": %zu, \"failed\": %zu, \"seconds\": %.6f, \"extension\": %s}",
                r->width, r->height, r->flagged, r->off_manifold, r->nonfinite, r->clamped, r->failed, r->seconds,
                r->extension ? "true" : "false");
    }
    fprintf(j.out, "]}");
    mr_gltf_convert_result_free(&result);
    return json_close(&j, MR_OK, json_out);
}

static int is_gltf_path(const char *text) {
    size_t n = strlen(text);
    return strchr(text, '\n') == NULL && ((n > 5 && strcmp(text + n - 5, ".gltf") == 0) ||
                                          (n > 4 && strcmp(text + n - 4, ".glb") == 0));
}

/* One report input from its text: a material (model and assignments, one a line) or a glTF asset's scene. */
static mr_status report_input(const char *text, mr_material **material, mr_gltf_scene **scene) {
    if (is_gltf_path(text)) {
        mr_gltf *asset = NULL;
        mr_status status = mr_gltf_load(text, &asset);
        if (status == MR_OK) status = mr_gltf_scene_from_asset(asset, NULL, scene);
        mr_gltf_free(asset);
        return status;
    }
    char *copy = strdup(text);
    if (copy == NULL) return mr_fail(MR_ERR_NOMEM, "report: out of memory");
    const char *words[256];
    int count = 0;
    char *save = NULL;
    for (char *w = strtok_r(copy, "\n", &save); w != NULL; w = strtok_r(NULL, "\n", &save)) {
        if (count == 256) {
            free(copy);
            return mr_fail(MR_ERR_INVALID_ARG, "report: more than 255 parameter assignments");
        }
        words[count++] = w;
    }
    mr_status status = count == 0 ? mr_fail(MR_ERR_INVALID_ARG, "report: an empty input")
                                  : mr_material_from_assignments(words[0], words + 1, count - 1, NULL, material, NULL);
    free(copy);
    return status;
}

mr_status mr_api_report(const char *const *inputs, const char *const *labels, int count, const char *dir, int size,
                        const char *env_path, int rotations, int threads, const char *title) {
    if (inputs == NULL || dir == NULL || count < 1 || count > 1024)
        return mr_fail(MR_ERR_INVALID_ARG, "report: expected 1 .. 1024 inputs and a folder");
    mr_report_input *in = calloc((size_t)count, sizeof *in);
    mr_material **materials = calloc((size_t)count, sizeof *materials);
    mr_gltf_scene **scenes = calloc((size_t)count, sizeof *scenes);
    char **descriptions = calloc((size_t)count, sizeof *descriptions);
    mr_status status = in && materials && scenes && descriptions ? MR_OK
                                                                 : mr_fail(MR_ERR_NOMEM, "report: out of memory");
    for (int k = 0; status == MR_OK && k < count; k++) {
        if (inputs[k] == NULL) {
            status = mr_fail(MR_ERR_INVALID_ARG, "report: input %d is NULL", k);
            break;
        }
        status = report_input(inputs[k], &materials[k], &scenes[k]);
        in[k].label = labels != NULL ? labels[k] : NULL;
        in[k].material = materials[k];
        in[k].scene = scenes[k];
        if (status == MR_OK && materials[k] != NULL) { // described as the command describes it: its words
            descriptions[k] = strdup(inputs[k]);
            if (descriptions[k] == NULL) status = mr_fail(MR_ERR_NOMEM, "report: out of memory");
            for (char *c = descriptions[k]; c != NULL && *c; c++)
                if (*c == '\n') *c = ' ';
            in[k].description = descriptions[k];
        }
    }
    if (status == MR_OK) {
        mr_report_options opts = {0};
        opts.size = size;
        opts.env_path = env_path;
        opts.rotations = rotations;
        opts.threads = threads;
        opts.title = title;
        status = mr_report_make(in, count, dir, &opts, NULL);
    }
    for (int k = 0; k < count && materials && scenes && descriptions; k++) {
        mr_material_free(materials[k]);
        mr_gltf_scene_free(scenes[k]);
        free(descriptions[k]);
    }
    free(descriptions);
    free(in);
    free(materials);
    free(scenes);
    return status;
}
