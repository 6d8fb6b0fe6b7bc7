/*
 * registry.c — the list of registered BRDF models and the parameter-vector helpers (contracts in brdf.h).
 *
 * Adding a model: write src/brdf/<name>.c exporting `const mr_brdf_model mr_brdf_<name>`, declare it in
 * models.h and add it to `registered` below. Every generic test (tests/test_brdf.c) then covers it.
 */
#include "brdf.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../c_locale.h"
#include "../mr_internal.h"
#include "models.h"

static const mr_brdf_model *const registered[] = {
    MR_BRDF_REGISTERED_MODELS
    NULL,
};

const mr_brdf_model *const *mr_brdf_models(void) { return registered; }

int mr_brdf_model_count(void) { return (int)(sizeof registered / sizeof registered[0]) - 1; }

/* Append `name` to the ", "-separated list in buf (capacity size); names that no longer fit are left out, so
 * an error message stays one bounded line. */
static void append_name(char *buf, size_t size, const char *name) {
    size_t used = strlen(buf), len = strlen(name), sep = used ? 2 : 0;
    if (used + sep + len + 1 > size) return;
    memcpy(buf + used, ", ", sep);
    memcpy(buf + used + sep, name, len + 1);
}

const mr_brdf_model *mr_brdf_find(const char *name) {
    for (int i = 0; registered[i] != NULL; i++)
        if (name != NULL && strcmp(registered[i]->name, name) == 0) return registered[i];
    char list[768] = "";
    for (int i = 0; registered[i] != NULL; i++) append_name(list, sizeof list, registered[i]->name);
    mr_fail(MR_ERR_INVALID_ARG, "unknown BRDF model '%s' (valid: %s)", name ? name : "(null)", list);
    return NULL;
}

int mr_brdf_value_count(const mr_brdf_model *model) {
    int count = 0;
    for (int i = 0; i < model->param_count; i++) count += model->params[i].channels;
    return count;
}

int mr_brdf_param_offset(const mr_brdf_model *model, int index) {
    if (index < 0 || index >= model->param_count) return -1;
    int offset = 0;
    for (int i = 0; i < index; i++) offset += model->params[i].channels;
    return offset;
}

int mr_brdf_param_index(const mr_brdf_model *model, const char *name) {
    for (int i = 0; i < model->param_count; i++)
        if (strcmp(model->params[i].name, name) == 0) return i;
    return -1;
}

void mr_brdf_default_values(const mr_brdf_model *model, double *values) {
    int slot = 0;
    for (int i = 0; i < model->param_count; i++)
        for (int c = 0; c < model->params[i].channels; c++)
            values[slot++] = mr_brdf_param_default(&model->params[i], c);
}

double mr_brdf_param_default(const mr_brdf_param *param, int channel) {
    return param->default_rgb ? param->default_rgb[channel] : param->default_value;
}

const char *mr_param_role_name(mr_param_role role) {
    static const char *const names[MR_PARAM_ROLE_COUNT] = {"linear", "affine", "nonlinear", "switch"};
    return (unsigned)role < MR_PARAM_ROLE_COUNT ? names[role] : NULL;
}

const char *mr_param_lobe_name(mr_param_lobe lobe) {
    return lobe == MR_LOBE_DIFFUSE ? "diffuse" : lobe == MR_LOBE_SPECULAR ? "specular" : "both";
}

static mr_status unknown_param(const mr_brdf_model *model, const char *name, size_t name_len) {
    char list[512] = "";
    for (int i = 0; i < model->param_count; i++) append_name(list, sizeof list, model->params[i].name);
    return mr_fail(MR_ERR_INVALID_ARG, "model '%s' has no parameter '%.*s' (valid: %s)", model->name,
                   (int)name_len, name, list);
}

static mr_status parse_assignment(const mr_brdf_model *model, const char *assignment, double *values) {
    const char *equals = strchr(assignment, '=');
    if (equals == NULL || equals == assignment)
        return mr_fail(MR_ERR_INVALID_ARG, "parameter '%s': expected name=value or name=r,g,b", assignment);
    size_t name_len = (size_t)(equals - assignment);
    int index = -1;
    for (int i = 0; i < model->param_count; i++)
        if (strlen(model->params[i].name) == name_len && strncmp(model->params[i].name, assignment, name_len) == 0)
            index = i;
    if (index < 0) return unknown_param(model, assignment, name_len);
    const mr_brdf_param *param = &model->params[index];

    double parsed[3];
    int count = 0;
    const char *cursor = equals + 1;
    for (;;) {
        char *end = NULL;
        errno = 0;
        double v = strtod(cursor, &end);
        if (end == cursor || errno == ERANGE || v != v)
            return mr_fail(MR_ERR_INVALID_ARG, "parameter '%s' of model '%s': '%s' is not a number", param->name,
                           model->name, equals + 1);
        if (count == 3)
            return mr_fail(MR_ERR_INVALID_ARG, "parameter '%s' of model '%s': more than 3 values in '%s'",
                           param->name, model->name, equals + 1);
        parsed[count++] = v;
        if (*end == '\0') break;
        if (*end != ',')
            return mr_fail(MR_ERR_INVALID_ARG, "parameter '%s' of model '%s': unexpected '%c' in '%s'", param->name,
                           model->name, *end, equals + 1);
        cursor = end + 1;
    }
    if (count != 1 && count != param->channels)
        return mr_fail(MR_ERR_INVALID_ARG, "parameter '%s' of model '%s' takes %d value%s, got %d", param->name,
                       model->name, param->channels, param->channels == 1 ? "" : "s (or one for all)", count);
    for (int c = 0; c < count; c++)
        if (!(parsed[c] >= param->min_value && parsed[c] <= param->max_value))
            return mr_fail(MR_ERR_INVALID_ARG, "parameter '%s' of model '%s': %g is outside [%g, %g]", param->name,
                           model->name, parsed[c], param->min_value, param->max_value);
    if (param->role == MR_PARAM_SWITCH && parsed[0] != (double)(long)parsed[0])
        return mr_fail(MR_ERR_INVALID_ARG, "parameter '%s' of model '%s' is a switch: %g is not an integer",
                       param->name, model->name, parsed[0]);
    int offset = mr_brdf_param_offset(model, index);
    for (int c = 0; c < param->channels; c++) values[offset + c] = parsed[count == 1 ? 0 : c];
    return MR_OK;
}

/* "0.5" is a number in any host locale (c_locale.h). */
mr_status mr_brdf_parse_assignment(const mr_brdf_model *model, const char *assignment, double *values) {
    if (model == NULL || assignment == NULL || values == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "parameter assignment: NULL model, text or values");
    mr_c_numeric locale;
    mr_status status = mr_c_numeric_enter(&locale, "parameter assignment");
    if (status != MR_OK) return status;
    status = parse_assignment(model, assignment, values);
    mr_c_numeric_leave(&locale);
    return status;
}

/* The end of a number at `text` if the whole of it up to the next ',' (or the end) is one: the commas of an RGB
 * value are told from those between items this way (a parameter name is never a number). NULL otherwise. */
static const char *number_item_end(const char *text) {
    char *end = NULL;
    errno = 0;
    (void)strtod(text, &end);
    if (end == text || (*end != ',' && *end != '\0')) return NULL;
    return end;
}

static mr_status parse_holds(const mr_brdf_model *model, const char *text, double *values, unsigned *held) {
    const char *item = text;
    if (*item == '\0') return mr_fail(MR_ERR_INVALID_ARG, "hold list of model '%s' is empty", model->name);
    for (;;) {
        size_t name_len = strcspn(item, ",=");
        if (name_len == 0)
            return mr_fail(MR_ERR_INVALID_ARG, "hold list '%s': an empty parameter name (expected NAME or "
                           "NAME=VALUE, ','-separated)", text);
        int index = -1;
        for (int i = 0; i < model->param_count; i++)
            if (strlen(model->params[i].name) == name_len && strncmp(model->params[i].name, item, name_len) == 0)
                index = i;
        if (index < 0) {
            char list[512] = "";
            for (int i = 0; i < model->param_count; i++) append_name(list, sizeof list, model->params[i].name);
            return mr_fail(MR_ERR_INVALID_ARG, "'%.*s' is not a parameter of '%s' (valid: %s)", (int)name_len, item,
                           model->name, list);
        }
        if (index >= 32)
            return mr_fail(MR_ERR_INVALID_ARG, "parameter '%s' of model '%s' is beyond the 32 a hold mask holds",
                           model->params[index].name, model->name);
        const char *next = item + name_len;
        if (*next == '=') {
            // The value: its first number, then every ",number" that follows (an RGB parameter's r,g,b).
            const char *end = next + 1;
            const char *number = number_item_end(end);
            if (number != NULL) {
                end = number;
                while (*end == ',' && (number = number_item_end(end + 1)) != NULL) end = number;
            } else {
                end += strcspn(end, ",");
            }
            char assignment[256];
            if ((size_t)(end - item) >= sizeof assignment)
                return mr_fail(MR_ERR_INVALID_ARG, "hold '%.*s...': too long", 40, item);
            memcpy(assignment, item, (size_t)(end - item));
            assignment[end - item] = '\0';
            if (end == next + 1)
                return mr_fail(MR_ERR_INVALID_ARG, "parameter '%s' of model '%s': '%s' holds no value (expected "
                               "NAME=VALUE or NAME)", model->params[index].name, model->name, assignment);
            mr_status status = parse_assignment(model, assignment, values);
            if (status != MR_OK) return status;
            next = end;
        }
        *held |= 1u << index;
        if (*next == '\0') return MR_OK;
        item = next + 1; // *next == ','
        if (*item == '\0')
            return mr_fail(MR_ERR_INVALID_ARG, "hold list '%s': an empty parameter name after the last ','", text);
    }
}

mr_status mr_brdf_parse_holds(const mr_brdf_model *model, const char *text, double *values, unsigned *held) {
    if (model == NULL || text == NULL || values == NULL || held == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "hold list: NULL model, text, values or mask");
    double work[MR_BRDF_MAX_VALUES];
    const int count = mr_brdf_value_count(model);
    memcpy(work, values, (size_t)count * sizeof *work);
    unsigned mask = *held;
    mr_c_numeric locale;
    mr_status status = mr_c_numeric_enter(&locale, "hold list");
    if (status != MR_OK) return status;
    status = parse_holds(model, text, work, &mask);
    mr_c_numeric_leave(&locale);
    if (status != MR_OK) return status;
    memcpy(values, work, (size_t)count * sizeof *work);
    *held = mask;
    return MR_OK;
}

mr_hold_reason mr_brdf_hold_reason(const mr_brdf_model *model, unsigned held, int p) {
    if (model == NULL || p < 0 || p >= model->param_count) return MR_HOLD_FITTED;
    const mr_brdf_param *param = &model->params[p];
    if (param->role == MR_PARAM_SWITCH) return MR_HOLD_SWITCH;
    if (p < 32 && ((held >> p) & 1u)) return MR_HOLD_CALLER;
    if (param->flags & MR_PARAM_FIT_FIXED) return MR_HOLD_MODEL;
    return MR_HOLD_FITTED;
}

size_t mr_brdf_format_holds(const mr_brdf_model *model, const double *values, unsigned held, const char *held_label,
                            char *buf, size_t size) {
    return mr_brdf_format_holds_tied(model, values, held, 0u, held_label, buf, size);
}

size_t mr_brdf_format_holds_tied(const mr_brdf_model *model, const double *values, unsigned held, unsigned tied,
                                 const char *held_label, char *buf, size_t size) {
    size_t need = 0;
    if (buf != NULL && size > 0) buf[0] = '\0';
    if (model == NULL || values == NULL) return 0;
    // "1.5" in any host locale; should the bracket fail (it cannot but by running out of memory), the line is written
    // in the host's, which only a person reads.
    mr_c_numeric locale;
    const int entered = mr_c_numeric_enter(&locale, "hold list") == MR_OK;
    int cut = 0;
    // Two groups, the caller's holds first: "a=1, b=2 (--hold); c=3 (default for MODEL)".
    for (int group = 0; group < 2; group++) {
        const mr_hold_reason want = group == 0 ? MR_HOLD_CALLER : MR_HOLD_MODEL;
        int items = 0;
        for (int p = 0; p <= model->param_count; p++) {
            char item[192];
            if (p == model->param_count) { // the group's label
                if (items == 0) break;
                if (want == MR_HOLD_CALLER) snprintf(item, sizeof item, " (%s)", held_label ? held_label : "held");
                else snprintf(item, sizeof item, " (default for %s)", model->name);
            } else {
                if (mr_brdf_hold_reason(model, held, p) != want || (p < 32 && ((tied >> p) & 1u))) continue;
                const mr_brdf_param *param = &model->params[p];
                const double *v = values + mr_brdf_param_offset(model, p);
                char value[96];
                if (param->channels == 3 && !(v[1] == v[0] && v[2] == v[0]))
                    snprintf(value, sizeof value, "%g,%g,%g", v[0], v[1], v[2]);
                else
                    snprintf(value, sizeof value, "%g", v[0]);
                snprintf(item, sizeof item, "%s%s=%s", items ? ", " : need ? "; " : "", param->name, value);
                items++;
            }
            const size_t len = strlen(item);
            if (buf != NULL && !cut && need + len < size) memcpy(buf + need, item, len + 1);
            else cut = 1; // no later, shorter item after a gap: the line is cut where it stopped fitting
            need += len;
        }
    }
    if (entered) mr_c_numeric_leave(&locale);
    return need;
}

void mr_brdf_eval_full(const mr_brdf_model *model, const double *values, const double wi[3], const double wo[3],
                       double rgb[3]) {
    mr_brdf_state state;
    double diffuse[3], specular[3];
    model->prepare(model, values, state.bytes);
    model->eval(state.bytes, wi, wo, diffuse, specular);
    for (int c = 0; c < 3; c++) rgb[c] = diffuse[c] + specular[c];
}

/* ---- ties ------------------------------------------------------------------------------------------------------ */

/* Parameters that state one quantity under different names, in the models here (brdf.h, mr_brdf_default_ties).
 * `fitted_too`: the tie applies to a target parameter the fit would search (the metalness); otherwise only to one
 * the target holds by default (MR_PARAM_FIT_FIXED), whose held value the tie replaces. */
static const struct {
    int fitted_too;
    const char *names[4];
} same_quantity[] = {
    {1, {"metallic", "metalness", "base_metalness", NULL}}, // the metalness
    {0, {"ior", "specular_ior", NULL, NULL}},               // the dielectric's IOR
    {0, {"coat", "coat_weight", "clearcoat", NULL}},        // the coat's weight
    {0, {"coat_roughness", "clearcoat_roughness", NULL, NULL}},
    {0, {"coat_ior", NULL, NULL, NULL}},
    {0, {"coat_color", "coat_tint", NULL, NULL}},           // the coat's transmission tint (RGB)
    // The specular tint (RGB): F0's for a dielectric, the edge's (F82, Gulbrandsen's g) for a metal in OpenPBR,
    // Blender 4's Principled and Standard Surface; glTF's KHR_materials_specular colour tints the dielectric's only.
    // The 2019 Principled's scalar specular_tint (towards the base colour) differs in channels and is left out.
    {0, {"specular_color", "specular_tint", NULL, NULL}},
};

/* The first parameter of m named in group g (not a switch, within the 32 a tie mask holds), or -1. */
static int quantity_param(const mr_brdf_model *m, int g) {
    for (int k = 0; k < 4 && same_quantity[g].names[k] != NULL; k++) {
        const int p = mr_brdf_param_index(m, same_quantity[g].names[k]);
        if (p >= 0 && p < 32 && m->params[p].role != MR_PARAM_SWITCH) return p;
    }
    return -1;
}

mr_brdf_ties mr_brdf_default_ties(const mr_brdf_model *source, const mr_brdf_model *target) {
    mr_brdf_ties ties;
    memset(&ties, 0, sizeof ties);
    if (source == NULL || target == NULL || source == target) return ties;
    for (int g = 0; g < (int)(sizeof same_quantity / sizeof same_quantity[0]); g++) {
        const int s = quantity_param(source, g), t = quantity_param(target, g);
        if (s < 0 || t < 0 || source->params[s].channels != target->params[t].channels) continue;
        if (!same_quantity[g].fitted_too && !(target->params[t].flags & MR_PARAM_FIT_FIXED)) continue;
        ties.tied |= 1u << t;
        ties.source[t] = (signed char)s;
    }
    return ties;
}

mr_status mr_brdf_parse_ties(const mr_brdf_model *source, const mr_brdf_model *target, const char *text,
                             mr_brdf_ties *out) {
    if (source == NULL || target == NULL || text == NULL || out == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "tie list: NULL argument");
    mr_brdf_ties ties;
    memset(&ties, 0, sizeof ties);
    if (strcmp(text, "none") != 0) {
        const char *item = text;
        for (;;) {
            const char *end = strchr(item, ',');
            size_t len = end ? (size_t)(end - item) : strlen(item);
            char buf[128];
            if (len == 0 || len >= sizeof buf)
                return mr_fail(MR_ERR_INVALID_ARG, "tie list '%s': an empty or overlong item", text);
            memcpy(buf, item, len);
            buf[len] = '\0';
            char *eq = strchr(buf, '=');
            if (eq == NULL)
                return mr_fail(MR_ERR_INVALID_ARG, "tie list '%s': '%s' is not TARGET=SOURCE (a parameter of '%s' "
                               "held at one of '%s')", text, buf, target->name, source->name);
            *eq = '\0';
            const int t = mr_brdf_param_index(target, buf), s = mr_brdf_param_index(source, eq + 1);
            if (t < 0 || t >= 32 || target->params[t].role == MR_PARAM_SWITCH)
                return mr_fail(MR_ERR_INVALID_ARG, "tie list '%s': '%s' is not a parameter of '%s' a fit can tie",
                               text, buf, target->name);
            if (s < 0 || source->params[s].role == MR_PARAM_SWITCH)
                return mr_fail(MR_ERR_INVALID_ARG, "tie list '%s': '%s' is not a parameter of '%s'", text, eq + 1,
                               source->name);
            if (source->params[s].channels != target->params[t].channels)
                return mr_fail(MR_ERR_INVALID_ARG, "tie list '%s': %s has %d channel(s), %s %d", text, buf,
                               target->params[t].channels, eq + 1, source->params[s].channels);
            ties.tied |= 1u << t;
            ties.source[t] = (signed char)s;
            if (end == NULL) break;
            item = end + 1;
        }
    }
    *out = ties;
    return MR_OK;
}

size_t mr_brdf_format_ties(const mr_brdf_model *source, const mr_brdf_model *target, const mr_brdf_ties *ties,
                           char *buf, size_t size) {
    size_t need = 0;
    if (buf != NULL && size > 0) buf[0] = '\0';
    if (source == NULL || target == NULL || ties == NULL) return 0;
    for (int p = 0; p < target->param_count && p < 32; p++) {
        if (!((ties->tied >> p) & 1u)) continue;
        char item[160];
        snprintf(item, sizeof item, "%s%s=%s", need ? ", " : "", target->params[p].name,
                 source->params[ties->source[p]].name);
        const size_t len = strlen(item);
        if (buf != NULL && need + len < size) memcpy(buf + need, item, len + 1);
        need += len;
    }
    return need;
}

void mr_brdf_apply_ties(const mr_brdf_model *source, const double *source_values, const mr_brdf_model *target,
                        const mr_brdf_ties *ties, double *target_values, unsigned *held) {
    if (source == NULL || source_values == NULL || target == NULL || ties == NULL || target_values == NULL) return;
    const unsigned caller = held ? *held : 0u;
    for (int p = 0; p < target->param_count && p < 32; p++) {
        if (!((ties->tied >> p) & 1u) || ((caller >> p) & 1u)) continue; // a caller's hold wins over a tie
        const mr_brdf_param *q = &target->params[p];
        const double *from = source_values + mr_brdf_param_offset(source, ties->source[p]);
        double *to = target_values + mr_brdf_param_offset(target, p);
        for (int c = 0; c < q->channels; c++) to[c] = fmin(q->max_value, fmax(q->min_value, from[c]));
        if (held) *held |= 1u << p;
    }
}
