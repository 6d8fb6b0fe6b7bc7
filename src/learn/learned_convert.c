/*
 * learned_convert.c — the job of `matremap convert` as library calls (contract in learned.h, "converting a
 * material"): transforms read from files and folders with their names kept (mr_learned_set), a given chain's ends
 * checked, why a converted texel was flagged (mr_learned_explain_texel), and a material given as text converted
 * through a learned chain or the direct remap, its outputs and flag picture written all or none
 * (mr_learned_convert_material).
 */
#include <dirent.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io/image_io.h"
#include "learn/learned.h"
#include "mr_internal.h"
#include "remap/direct.h"
#include "render/render.h"
#include "transform/transform.h"

/* ---- sets of transforms read from files ------------------------------------------------------------------------ */

mr_status mr_learned_set_add_file(mr_learned_set *set, const char *path) {
    if (set == NULL || path == NULL) return mr_fail(MR_ERR_INVALID_ARG, "transform set: NULL set or path");
    if (set->count == MR_LEARNED_SET_MAX)
        return mr_fail(MR_ERR_INVALID_ARG, "more than %d transforms", MR_LEARNED_SET_MAX);
    mr_learned *t = NULL;
    mr_status status = mr_learned_read(path, &t);
    if (status != MR_OK) return status;
    char *copy = strdup(path);
    if (copy == NULL) {
        mr_learned_free(t);
        return mr_fail(MR_ERR_NOMEM, "out of memory for the transform '%s'", path);
    }
    set->all[set->count] = t;
    set->paths[set->count++] = copy;
    return MR_OK;
}

static int by_name(const void *a, const void *b) { return strcmp(*(char *const *)a, *(char *const *)b); }

mr_status mr_learned_set_add_folder(mr_learned_set *set, const char *dir, const char *label) {
    if (set == NULL || dir == NULL) return mr_fail(MR_ERR_INVALID_ARG, "transform set: NULL set or folder");
    char fallback[4200];
    if (label == NULL) {
        snprintf(fallback, sizeof fallback, "folder '%s'", dir);
        label = fallback;
    }
    DIR *d = opendir(dir);
    if (d == NULL) return mr_fail(MR_ERR_IO, "%s: %s", label, strerror(errno));
    // Sorted names, so the chain chosen among equals does not depend on the directory's order.
    char *names[MR_LEARNED_SET_MAX];
    int count = 0;
    mr_status status = MR_OK;
    struct dirent *e;
    while ((e = readdir(d)) != NULL && status == MR_OK) {
        size_t n = strlen(e->d_name);
        if (n < 5 || strcmp(e->d_name + n - 4, ".mrt") != 0) continue;
        if (count == MR_LEARNED_SET_MAX) break;
        names[count] = strdup(e->d_name);
        if (names[count] == NULL) status = mr_fail(MR_ERR_NOMEM, "%s: out of memory", label);
        else count++;
    }
    closedir(d);
    qsort(names, (size_t)count, sizeof *names, by_name);
    for (int i = 0; i < count; i++) {
        char path[4096];
        snprintf(path, sizeof path, "%s/%s", dir, names[i]);
        if (status == MR_OK) status = mr_learned_set_add_file(set, path);
        free(names[i]);
    }
    if (status == MR_OK && count == 0) status = mr_fail(MR_ERR_IO, "%s: no *.mrt files there", label);
    return status;
}

void mr_learned_set_free(mr_learned_set *set) {
    if (set == NULL) return;
    for (int i = 0; i < set->count; i++) {
        mr_learned_free(set->all[i]);
        free(set->paths[i]);
    }
    set->count = 0;
}

mr_status mr_learned_check_ends(const mr_learned *const *chain, const char *const *names, int hops,
                                const mr_brdf_model *source, const mr_brdf_model *target) {
    if (chain == NULL || names == NULL || hops < 1 || source == NULL || target == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "chain check: NULL argument or no hops");
    const mr_learned *first = chain[0], *last = chain[hops - 1];
    const mr_learned *bad = first->source != source ? first : last->target != target ? last : NULL;
    if (bad == NULL) return MR_OK;
    return mr_fail(MR_ERR_INVALID_ARG, "'%s' converts %s to %s, but the conversion asked is %s to %s",
                   names[bad == first ? 0 : hops - 1], bad->source->name, bad->target->name, source->name,
                   target->name);
}

/* ---- why a texel was flagged ---------------------------------------------------------------------------------- */

/* "name v", "name r,g,b": parameter p of `model` in packed `values`, appended to text. */
static void append_param(char *text, size_t size, const mr_brdf_model *model, const double *values, int p) {
    const int at = mr_brdf_param_offset(model, p);
    size_t used = strlen(text);
    if (model->params[p].channels == 3)
        snprintf(text + used, size - used, "%s %.4g,%.4g,%.4g", model->params[p].name, values[at], values[at + 1],
                 values[at + 2]);
    else
        snprintf(text + used, size - used, "%s %.4g", model->params[p].name, values[at]);
}

#define APPEND(note, ...) snprintf((note) + strlen(note), sizeof(note) - strlen(note), __VA_ARGS__)

void mr_learned_explain_texel(const mr_learned *const *chain, int hops, const mr_brdf_model *source,
                              const double *source_values, const mr_brdf_model *target, const double *target_values,
                              unsigned flags, mr_learned_note_fn note_fn, void *user) {
    double values[2][MR_BRDF_MAX_VALUES];
    memcpy(values[0], source_values, (size_t)mr_brdf_value_count(source) * sizeof values[0][0]);
    for (int h = 0; h <= hops; h++) {
        const mr_learned *t = h < hops ? chain[h] : NULL;
        const mr_brdf_model *in_model = t ? t->source : source, *out_model = t ? t->target : target;
        const double *in = values[h % 2];
        double *out = values[(h + 1) % 2];
        unsigned f = flags;
        if (t != NULL)
            mr_learned_apply(t, in, out, &f);
        else if (hops == 0) // the direct remap: the converted values as they are
            memcpy(out, target_values, (size_t)mr_brdf_value_count(target) * sizeof out[0]);
        else
            break;
        if ((f & (MR_WF_EXTRAPOLATED | MR_WF_UNCONVERGED | MR_WF_CLAMPED_OUTPUT | MR_WF_CLAMPED_INPUT |
                  MR_WF_NONFINITE_INPUT | MR_WF_UNCHECKED)) == 0)
            continue;
        char note[2048] = "";
        if (t != NULL && (f & MR_WF_UNCHECKED))
            APPEND(note, "the transform failed its check against the remaps when it was learned; ");
        if (t != NULL && (f & MR_WF_EXTRAPOLATED)) {
            APPEND(note, "extrapolated, outside its training domain:");
            for (int k = 0; k < t->feature_count; k++) {
                const mr_learned_slot *slot = &t->features[k];
                const int at = mr_brdf_param_offset(in_model, slot->param);
                const int channels = slot->kind == MR_LEARNED_GREY ? 3 : 1;
                const int first = slot->kind == MR_LEARNED_CHANNEL ? slot->channel : 0;
                int outside = 0;
                for (int c = first; c < first + channels; c++)
                    outside |= in[at + c] < slot->min || in[at + c] > slot->max;
                if (!outside) continue;
                APPEND(note, " ");
                append_param(note, sizeof note, in_model, in, slot->param);
                APPEND(note, " (trained on [%.4g, %.4g])", slot->min, slot->max);
            }
            APPEND(note, "; ");
        }
        if (t == NULL && (f & MR_WF_UNCONVERGED)) APPEND(note, "the fit did not converge; ");
        if (f & MR_WF_CLAMPED_OUTPUT) {
            APPEND(note, "clamped into its range:");
            for (int p = 0; p < out_model->param_count; p++) {
                const mr_brdf_param *param = &out_model->params[p];
                const int at = mr_brdf_param_offset(out_model, p);
                int bound = 0;
                for (int c = 0; c < param->channels; c++)
                    bound |= out[at + c] <= param->min_value || out[at + c] >= param->max_value;
                if (!bound || param->role == MR_PARAM_SWITCH || param->min_value == param->max_value) continue;
                APPEND(note, " ");
                append_param(note, sizeof note, out_model, out, p);
                APPEND(note, " (range [%g, %g])", param->min_value, param->max_value);
            }
            APPEND(note, "; ");
        }
        if (f & (MR_WF_CLAMPED_INPUT | MR_WF_NONFINITE_INPUT)) APPEND(note, "an input was clamped or not finite; ");
        note[strlen(note) - 2] = '\0'; // the last "; "
        if (note_fn != NULL) note_fn(h, note, user);
        flags = 0; // a chain's hops raise their own
    }
}

/* ---- converting a material ------------------------------------------------------------------------------------- */

void mr_learned_conversion_free(mr_learned_conversion *r) {
    if (r == NULL) return;
    for (int j = 0; j < MR_TRANSFORM_MAX_SLOTS; j++) mr_image_free(r->converted[j]);
    free(r->flags);
    mr_material_free(r->material);
    memset(r, 0, sizeof *r);
}

mr_status mr_learned_convert_material(const mr_learned_conversion_spec *spec, mr_learned_conversion *r) {
    mr_material *given = spec != NULL ? spec->material : NULL; // taken: freed on every path but success
    if (r == NULL) {
        mr_material_free(given);
        return mr_fail(MR_ERR_INVALID_ARG, "conversion: NULL result");
    }
    memset(r, 0, sizeof *r);
    r->material_report.failed = -1;
    if (spec == NULL || spec->source == NULL || spec->target == NULL || spec->hops < 0 ||
        spec->hops > MR_LEARNED_MAX_HOPS || (spec->hops > 0 && spec->chain == NULL) ||
        (spec->assignment_count > 0 && spec->assignments == NULL) ||
        (given != NULL && (spec->assignment_count > 0 || given->model != spec->source))) {
        mr_material_free(given);
        return mr_fail(MR_ERR_INVALID_ARG, "conversion: NULL spec, models or chain, a chain of %d hops, or a "
                       "material given with assignments or of another model", spec != NULL ? spec->hops : 0);
    }
    const mr_brdf_model *target = spec->target;
    const int direct = spec->hops == 0, out_count = target->param_count;
    int maps_given = 0;
    for (int k = 0; k < spec->assignment_count; k++) {
        const char *eq = strchr(spec->assignments[k], '=');
        maps_given |= eq != NULL && eq[1] == '@';
    }
    if (given != NULL) maps_given = given->map_count > 0;
    mr_direct_options dopts = {0};
    if (spec->direct != NULL) dopts = *spec->direct;
    // Constants alone are one texel: remapped at their exact values, not at a quantised neighbour (which the
    // default step puts up to 12 % away for a dark colour), unless the tolerance is given.
    if (direct && !maps_given && dopts.tolerance == 0.0) dopts.tolerance = MR_DIRECT_MIN_TOLERANCE;
    dopts.threads = spec->threads;
    r->direct_tolerance = dopts.tolerance > 0.0 ? dopts.tolerance : MR_DIRECT_DEFAULT_TOLERANCE;
    mr_transform_kind *kind = NULL;
    mr_status status = direct ? mr_direct_kind_create(spec->source, target, &dopts, &kind)
                              : mr_learned_kind_create(spec->chain, spec->hops, &kind);
    if (status != MR_OK) {
        mr_material_free(given);
        return status;
    }

    const double started = mr_now_seconds();
    if (given != NULL)
        r->material = given;
    else
        status = mr_material_from_assignments(spec->source->name, spec->assignments, spec->assignment_count, NULL,
                                              &r->material, &r->material_report);
    mr_transform *t = NULL;
    mr_transform_options topts = {0};
    topts.threads = spec->threads;
    if (status == MR_OK) status = mr_transform_create(kind, &topts, &t);
    if (status == MR_OK) {
        const double t0 = mr_now_seconds();
        r->converting = 1;
        status = mr_transform_convert_material(t, r->material, r->converted, &r->flags);
        r->convert_seconds = mr_now_seconds() - t0;
    }
    // extrapolated or unconverged, clamped output, clamped input, any flag, by a transform that failed its check
    static const unsigned reasons[5] = {MR_WF_EXTRAPOLATED | MR_WF_UNCONVERGED, MR_WF_CLAMPED_OUTPUT,
                                        MR_WF_CLAMPED_INPUT | MR_WF_NONFINITE_INPUT, 0xFFu, MR_WF_UNCHECKED};
    if (status == MR_OK) {
        size_t counts[5] = {0};
        r->width = r->converted[0]->width;
        r->height = r->converted[0]->height;
        r->texels = (size_t)r->width * (size_t)r->height;
        mr_flags_count(r->flags, r->texels, reasons, 5, counts);
        r->extrapolated = counts[0];
        r->clamped_output = counts[1];
        r->clamped_input = counts[2];
        r->flagged = counts[3];
        r->failed_check = counts[4];
    }
    // Write: every output, then the flag map, all or none (mr_img_write_set).
    if (status == MR_OK && spec->outputs != NULL && r->material->map_count > 0) {
        mr_image *picture = NULL;
        mr_img_set_item items[MR_TRANSFORM_MAX_SLOTS + 1];
        // The rule maps are read by, so a PNG output reads back as written.
        for (int j = 0; j < out_count; j++)
            items[j] = (mr_img_set_item){spec->outputs[j], spec->output_label, r->converted[j],
                                         {mr_brdf_param_map_encoding(&target->params[j], MR_MAP_AS_PARAMETER), 0, 0}};
        status = mr_flag_picture(r->flags, r->width, r->height, &mr_learned_flag_code, &picture);
        items[out_count] = (mr_img_set_item){spec->outputs[out_count], spec->output_label, picture,
                                             {MR_IMG_DATA, 0, 0}};
        mr_img_set_options set_options = {spec->threads};
        if (status == MR_OK) status = mr_img_write_set(items, out_count + 1, &set_options, NULL);
        r->written = status == MR_OK;
        mr_image_free(picture);
    }
    r->seconds = mr_now_seconds() - started;
    if (direct && status == MR_OK) {
        r->direct = *mr_direct_kind_summary(kind);
        r->has_direct = 1;
    }
    mr_transform_free(t);
    if (direct)
        mr_direct_kind_free(kind);
    else
        mr_learned_kind_free(kind);
    if (status != MR_OK) {
        // Only the report and whether the conversion ran are kept; the images and the material are freed.
        const mr_material_text_report report = r->material_report;
        const int converting = r->converting;
        mr_learned_conversion_free(r);
        r->material_report = report;
        r->converting = converting;
    }
    return status;
}
