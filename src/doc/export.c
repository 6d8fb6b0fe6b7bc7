/*
 * export.c — one asset file exported to one output file (doc.h: mr_doc_export_file): what `matremap export IN -o
 * OUT` does, the load, the route choice and conversion, the checks that nothing is written over an input, and the
 * write, in one call.
 */
#include "doc/doc.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "gltf/mr_gltf.h"
#include "io/output_plan.h"
#include "learn/learned.h"
#include "mr_internal.h"

static int is_gltf_path(const char *path) {
    const char *dot = strrchr(path, '.');
    return dot != NULL && (strcasecmp(dot, ".gltf") == 0 || strcasecmp(dot, ".glb") == 0);
}

static int is_glb_path(const char *path) {
    const char *dot = strrchr(path, '.');
    return dot != NULL && strcasecmp(dot, ".glb") == 0;
}

int mr_doc_export_output_ok(const char *path) {
    return path != NULL && (is_gltf_path(path) || mr_doc_format_from_path(path) != MR_DOC_FORMAT_UNKNOWN);
}

const mr_brdf_model *mr_doc_export_default_target(const char *output) {
    if (output == NULL) return NULL;
    if (is_gltf_path(output)) return mr_brdf_find("gltf");
    mr_doc_format format = mr_doc_format_from_path(output);
    if (format == MR_DOC_FORMAT_MTLX) return mr_brdf_find("openpbr");
    if (format == MR_DOC_FORMAT_USDA) return mr_brdf_find("usd-preview");
    return NULL;
}

void mr_doc_export_report_free(mr_doc_export_report *report) {
    if (report == NULL) return;
    mr_doc_gltf_result_free(report->result);
    memset(report, 0, sizeof *report);
}

/* The document and the maps it names as inputs of the plan. */
static void plan_document(mr_output_plan *io, const char *input, const char *label, const mr_doc *in) {
    mr_output_plan_input(io, input, label);
    for (int k = 0; k < mr_doc_material_count(in); k++) {
        const mr_doc_material *m = mr_doc_material_get(in, k);
        for (int p = 0; p < m->model->param_count; p++)
            if (m->values[p].kind == MR_DOC_TEXTURE && m->values[p].file[0] != '/') {
                char path[8192];
                const char *slash = strrchr(input, '/');
                snprintf(path, sizeof path, "%.*s%s", slash ? (int)(slash - input + 1) : 0, input, m->values[p].file);
                mr_output_plan_input(io, path, "a map of the document");
            }
    }
}

/* A glTF asset's files as inputs of the plan: the first labelled `label`, the others "a file of <label>". */
static void plan_gltf(mr_output_plan *io, const mr_gltf *asset, const char *label) {
    const char *file;
    for (int k = 0; (file = mr_gltf_source_file(asset, k)) != NULL; k++)
        if (k == 0)
            mr_output_plan_input(io, file, label);
        else
            mr_output_plan_inputf(io, file, "a file of %s", label);
}

static void plan_common(mr_output_plan *io, const char *output, const mr_doc_export_options *o) {
    mr_output_plan_output(io, output, NULL);
    for (int k = 0; o->transforms != NULL && k < o->transforms->count; k++)
        mr_output_plan_inputf(io, o->transforms->paths[k], "transform %s", o->transforms->paths[k]);
    if (o->cache_path != NULL) mr_output_plan_output(io, o->cache_path, "--cache");
}

/* The conversion's options from the export's, its maps' prefix (OUT without its extension) into prefix[4096]. */
static void conversion_options(const mr_doc_export_options *o, const mr_brdf_model *target, const char *output,
                               char prefix[4096], mr_doc_gltf_options *c) {
    snprintf(prefix, 4096, "%s", output);
    char *dot = strrchr(prefix, '.');
    if (dot) *dot = '\0';
    memset(c, 0, sizeof *c);
    c->target = target;
    c->image_prefix = prefix;
    c->threads = o->threads;
    c->size = o->size;
    c->target_values = o->target_values;
    c->held = o->held;
    c->ties = o->ties;
    c->tolerance = o->tolerance;
    c->cache_path = o->cache_path;
    c->transforms = o->transforms;
    c->progress = o->progress;
    c->progress_user = o->progress_user;
}

static mr_status export_mtlx(const char *input, const char *output, const mr_doc_export_options *o,
                             const mr_brdf_model *target, mr_output_plan *io, mr_doc_export_report *report) {
    mr_doc *in = NULL;
    mr_status st = mr_doc_read_mtlx(input, &in);
    if (st != MR_OK) return st;
    char label[4096 + 16];
    snprintf(label, sizeof label, "MaterialX '%s'", input);
    // Nothing written over a file read: OUT against the document and the maps it names.
    plan_document(io, input, label, in);
    plan_common(io, output, o);
    st = mr_output_plan_check(io);
    for (int k = 0; st == MR_OK && is_gltf_path(output) && k < mr_doc_material_count(in); k++) {
        // Converted maps cannot go into a glTF output: said before the work.
        const mr_doc_material *m = mr_doc_material_get(in, k);
        int textured = 0;
        for (int p = 0; p < m->model->param_count; p++) textured |= m->values[p].kind == MR_DOC_TEXTURE;
        mr_doc_route route = MR_DOC_ROUTE_COPY;
        if (mr_doc_choose_route(m->model, target, textured, o->transforms != NULL, &route) == MR_OK &&
            (route == MR_DOC_ROUTE_DIRECT || route == MR_DOC_ROUTE_LEARNED))
            st = mr_fail(MR_ERR_UNSUPPORTED, "MaterialX '%s': material '%s' (%s) converts its maps to gltf by the %s "
                         "route, whose maps a glTF output cannot hold yet: write .mtlx or .usda", input, m->name,
                         m->model->name, mr_doc_route_name(route));
    }
    if (st != MR_OK) {
        mr_doc_free(in);
        return st;
    }
    char prefix[4096];
    mr_doc_gltf_options c;
    conversion_options(o, target, output, prefix, &c);
    c.document_path = input;
    st = mr_doc_convert(in, label, &c, &report->result);
    // The ties the remaps took: the defaults of each remapped material's model (a hold wins), or those given.
    for (int k = 0; st == MR_OK && k < report->result->material_count; k++) {
        const mr_brdf_model *source = mr_doc_material_get(in, k)->model;
        int known = report->result->materials[k].route != MR_DOC_ROUTE_REMAP;
        for (int i = 0; i < report->source_count && !known; i++) known = report->sources[i] == source;
        if (known || report->source_count == MR_DOC_EXPORT_MAX_SOURCES) continue;
        report->sources[report->source_count] = source;
        report->ties[report->source_count] = o->ties != NULL ? *o->ties : mr_brdf_default_ties(source, target);
        report->ties[report->source_count++].tied &= ~o->held;
    }
    if (st == MR_OK && report->result->map_count > 0) {
        // Converted maps (never into a glTF output: refused above), never over an input.
        for (int i = 0; i < report->result->map_count; i++)
            mr_output_plan_output(io, report->result->maps[i].path, NULL);
        st = mr_output_plan_check(io);
    }
    if (st == MR_OK && is_gltf_path(output)) {
        // A glTF asset of the materials (no meshes), its images the maps' files copied beside OUT, named after it.
        mr_gltf *asset = NULL;
        st = mr_doc_to_gltf(report->result->doc, input, label, &asset);
        mr_gltf_save_options so = {1, 0, NULL};
        if (st == MR_OK) st = mr_gltf_save_with(asset, output, &so);
        mr_gltf_free(asset);
    } else if (st == MR_OK) {
        st = mr_doc_rebase(report->result->doc, input, output);
        if (st == MR_OK) st = mr_doc_gltf_write(NULL, report->result, output); // the converted maps, then OUT
    }
    mr_doc_free(in);
    return st;
}

static mr_status export_gltf(const char *input, const char *output, const mr_doc_export_options *o,
                             const mr_brdf_model *target, mr_output_plan *io, mr_doc_export_report *report) {
    mr_gltf *asset = NULL;
    mr_status st = mr_gltf_load(input, &asset);
    if (st != MR_OK) return st;
    // Nothing written over a file read, checked before any work (the remaps): OUT against the asset and its files;
    // the images beside OUT once the conversion has named them.
    char label[4096 + 8];
    snprintf(label, sizeof label, "asset %s", input);
    plan_gltf(io, asset, label);
    plan_common(io, output, o);
    st = mr_output_plan_check(io);
    char prefix[4096];
    mr_doc_gltf_options c;
    conversion_options(o, target, output, prefix, &c);
    // The ties: those given, or gltf's default ties to the target less the holds.
    const mr_brdf_model *gltf = mr_brdf_find("gltf");
    mr_brdf_ties ties = o->ties != NULL ? *o->ties : mr_brdf_default_ties(gltf, target);
    if (o->ties == NULL) ties.tied &= ~o->held;
    c.ties = &ties;
    if (st == MR_OK) st = mr_doc_from_gltf(asset, &c, &report->result);
    if (st == MR_OK) {
        report->source_count = 1;
        report->sources[0] = gltf;
        report->ties[0] = ties;
    }
    if (st == MR_OK && is_gltf_path(output)) {
        // glTF to glTF: every material copies (or carries its maps) exactly, so the asset itself is the output,
        // saved with its side files named after OUT (mr_gltf_save_with), never over an input.
        mr_gltf_save_options so = {1, 0, NULL};
        report->result->image_count = 0; // the asset's own images go with it
        st = mr_gltf_save_with(asset, output, &so);
    } else if (st == MR_OK) {
        for (int i = 0; i < report->result->image_count; i++)
            mr_output_plan_output(io, report->result->images[i].path, NULL);
        for (int i = 0; i < report->result->map_count; i++)
            mr_output_plan_output(io, report->result->maps[i].path, NULL);
        st = mr_output_plan_check(io);
        if (st == MR_OK) st = mr_doc_gltf_write(asset, report->result, output);
    }
    mr_gltf_free(asset);
    return st;
}

mr_status mr_doc_export_file(const char *input, const char *output, const mr_doc_export_options *opts,
                             mr_doc_export_report *report) {
    if (report == NULL) return mr_fail(MR_ERR_INVALID_ARG, "mr_doc_export_file: report is NULL");
    memset(report, 0, sizeof *report);
    if (input == NULL || output == NULL) return mr_fail(MR_ERR_INVALID_ARG, "mr_doc_export_file: a NULL path");
    mr_doc_export_options zero = {0};
    const mr_doc_export_options *o = opts != NULL ? opts : &zero;
    int mtlx_in = mr_doc_format_from_path(input) == MR_DOC_FORMAT_MTLX;
    if (!is_gltf_path(input) && !mtlx_in)
        return mr_fail(MR_ERR_INVALID_ARG, "'%s': the input is a glTF asset (.gltf or .glb) or a MaterialX document "
                       "(.mtlx)", input);
    if (!mr_doc_export_output_ok(output))
        return mr_fail(MR_ERR_INVALID_ARG, "'%s': the extension chooses the format: .mtlx, .usda, .gltf or .glb",
                       output);
    const mr_brdf_model *target = o->target != NULL ? o->target : mr_doc_export_default_target(output);
    if (target == NULL) return mr_fail(MR_ERR_INVALID_ARG, "'%s': no default model found", output);
    mr_doc_format format = mr_doc_format_from_path(output);
    if (is_gltf_path(output) ? strcmp(target->name, "gltf") != 0 : mr_doc_surface_node(target, format) == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "'%s': model %s cannot be written there (.mtlx: openpbr, standard-surface, "
                       "gltf; .usda: usd-preview; .gltf, .glb: gltf)", output, target->name);
    report->target = target;
    snprintf(report->format, sizeof report->format, "%s",
             is_gltf_path(output) ? (is_glb_path(output) ? "glb" : "gltf") : mr_doc_format_name(format));
    mr_output_plan io = {0};
    mr_status st = mtlx_in ? export_mtlx(input, output, o, target, &io, report)
                           : export_gltf(input, output, o, target, &io, report);
    if (st != MR_OK) {
        mr_output_plan_unmake_folders(&io);
        mr_doc_gltf_result_free(report->result);
        report->result = NULL;
    }
    mr_output_plan_free(&io);
    return st;
}
