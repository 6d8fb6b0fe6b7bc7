/*
 * sweep_table.c — sweep files read as packed parameter vectors (contract in sweep_table.h), through the sweep
 * file's reader by column name (src/remap/sweep_file.h).
 */
#include "learn/sweep_table.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "c_locale.h"
#include "mr_internal.h"
#include "remap/remap_file.h"
#include "remap/sweep_file.h"

#define MAX_COLUMNS 128
#define MAX_LINE 8190 /* without the '\n' */

/* Where each packed slot of a model is among a file's columns. */
typedef struct file_columns {
    int source[MR_BRDF_MAX_VALUES], target[MR_BRDF_MAX_VALUES];
    int ssim, outcome, count;
} file_columns;

/* One file's header facts, compared between the files of one table. */
typedef struct file_header {
    char from_model[64], to_line[1024], scene[256];
} file_header;

/* "MODEL name=v name=v ..." (the text after "# from: " or "# to: "): the model, and its values into values[]
 * (defaults for parameters not named). */
static mr_status parse_model_line(const char *path, long line_number, const char *text, const mr_brdf_model **model,
                                  double *values) {
    mr_status status = mr_sweep_file_parse_model(text, strcspn(text, "\r\n"), model, values);
    return status == MR_OK ? MR_OK : mr_fail_context(MR_ERR_FORMAT, "%s:%ld", path, line_number);
}

/* The column of every packed slot of `model` (prefix "" or "to_"). */
static mr_status map_model_columns(const char *path, char **names, int count, const mr_brdf_model *model,
                                   const char *prefix, int *slots) {
    for (int k = 0; k < mr_brdf_value_count(model); k++) {
        char name[96];
        mr_sweep_file_slot_name(model, k, prefix, name, sizeof name);
        slots[k] = mr_sweep_file_find_column(names, count, name);
        if (slots[k] < 0)
            return mr_fail(MR_ERR_FORMAT, "%s: no column '%s' (model %s): not a sweep file of this model pair", path,
                           name, model->name);
    }
    return MR_OK;
}

static mr_status grow(mr_sweep_table *t, size_t *capacity) {
    if (t->n < *capacity) return MR_OK;
    size_t grown = *capacity ? 2 * *capacity : 256;
    double *s = realloc(t->source_values, grown * (size_t)t->source_count * sizeof *s);
    if (s != NULL) t->source_values = s;
    double *g = s ? realloc(t->target_values, grown * (size_t)t->target_count * sizeof *g) : NULL;
    if (g != NULL) t->target_values = g;
    double *q = g ? realloc(t->ssim, grown * sizeof *q) : NULL;
    if (q != NULL) t->ssim = q;
    mr_fit_outcome *o = q ? realloc(t->outcome, grown * sizeof *o) : NULL;
    if (o != NULL) t->outcome = o;
    if (o == NULL) return mr_fail(MR_ERR_NOMEM, "sweep table: out of memory at %zu rows", t->n);
    *capacity = grown;
    return MR_OK;
}

static mr_status append_text(char **text, size_t *length, const char *add) {
    size_t more = strlen(add);
    char *grown = realloc(*text, *length + more + 1);
    if (grown == NULL) return mr_fail(MR_ERR_NOMEM, "sweep table: out of memory");
    memcpy(grown + *length, add, more + 1);
    *text = grown;
    *length += more;
    return MR_OK;
}

/* Check a value against its parameter's range (every slot of the model). */
static mr_status check_range(const char *path, long line_number, const mr_brdf_model *model, const char *prefix,
                             const double *values) {
    for (int p = 0, k = 0; p < model->param_count; p++)
        for (int c = 0; c < model->params[p].channels; c++, k++)
            if (values[k] < model->params[p].min_value || values[k] > model->params[p].max_value)
                return mr_fail(MR_ERR_FORMAT, "%s:%ld: %s%s = %.17g is outside the parameter's range [%g, %g]", path,
                               line_number, prefix, model->params[p].name, values[k], model->params[p].min_value,
                               model->params[p].max_value);
    return MR_OK;
}

/* The ties the "# remap:" line's " tied=t:s,..." names (the sweep's ties: target parameters held at a source
 * parameter's value, brdf.h) into *ties. MR_ERR_FORMAT naming the file for a name the models do not have. */
static mr_status parse_tied(const char *path, const char *remap_line, const mr_brdf_model *source,
                            const mr_brdf_model *target, mr_brdf_ties *ties) {
    memset(ties, 0, sizeof *ties);
    const char *at = strstr(remap_line, " tied=");
    if (at == NULL) return MR_OK;
    at += 6;
    for (;;) {
        const size_t length = strcspn(at, ", \r\n");
        char item[160];
        snprintf(item, sizeof item, "%.*s", (int)length, at);
        char *colon = strchr(item, ':');
        const int t = colon ? (*colon = '\0', mr_brdf_param_index(target, item)) : -1;
        const int s = colon ? mr_brdf_param_index(source, colon + 1) : -1;
        if (t < 0 || t >= 32 || s < 0 || target->params[t].channels != source->params[s].channels)
            return mr_fail(MR_ERR_FORMAT, "%s: the '# remap:' line ties '%.*s', which is not TARGET:SOURCE of '%s' "
                           "and '%s'", path, (int)length, at, target->name, source->name);
        ties->tied |= 1u << t;
        ties->source[t] = (signed char)s;
        if (at[length] != ',') return MR_OK;
        at += length + 1;
    }
}

/* The target parameters the "# remap:" line's " held=a,b" names (the sweep's --hold; none without the word) into
 * *held. MR_ERR_FORMAT naming the file for a name the target does not have. */
static mr_status parse_held(const char *path, const char *remap_line, const mr_brdf_model *target, unsigned *held) {
    *held = 0;
    const char *at = strstr(remap_line, " held=");
    if (at == NULL) return MR_OK;
    at += 6;
    for (;;) {
        size_t length = strcspn(at, ", \r\n");
        int found = -1;
        for (int p = 0; p < target->param_count && p < 32; p++)
            if (strlen(target->params[p].name) == length && strncmp(target->params[p].name, at, length) == 0) found = p;
        if (found < 0)
            return mr_fail(MR_ERR_FORMAT, "%s: the '# remap:' line holds '%.*s', which is not a parameter of '%s'",
                           path, (int)length, at, target->name);
        *held |= 1u << found;
        if (at[length] != ',') return MR_OK;
        at += length + 1;
    }
}

static mr_status load_file(const char *path, const mr_sweep_table_options *opts, int first, file_header *reference,
                           const char *reference_path, mr_sweep_table *t, size_t *capacity, size_t *prov_length) {
    mr_sweep_reader reader = {0};
    mr_status status = mr_sweep_reader_open(&reader, path, MAX_LINE);
    char *header_text = NULL;
    size_t header_length = 0;
    file_header h = {{0}, {0}, {0}};
    const mr_brdf_model *source = NULL, *target = NULL;
    double source_fixed[MR_BRDF_MAX_VALUES], target_fixed[MR_BRDF_MAX_VALUES];
    file_columns cols;
    char remap_line[1024] = "";
    int have_columns = 0;
    size_t rows = 0, kept = 0;
    while (status == MR_OK && mr_sweep_reader_next(&reader, &status) > 0) {
        char *line = reader.line;
        const long line_number = reader.line_number;
        if (line[0] == '#') {
            if (have_columns) {
                status = mr_fail(MR_ERR_FORMAT, "%s:%ld: a '#' line after the column line", path, line_number);
                break;
            }
            if (strncmp(line, MR_SWEEP_COMMAND_PREFIX, 10) != 0)
                status = append_text(&header_text, &header_length, line);
            if (status != MR_OK)
                break; // (the header line's own parse below would overwrite the status)
            if (strncmp(line, MR_SWEEP_FROM_PREFIX, 8) == 0) {
                status = parse_model_line(path, line_number, line + 8, &source, source_fixed);
                if (source) snprintf(h.from_model, sizeof h.from_model, "%s", source->name);
            } else if (strncmp(line, MR_SWEEP_TO_PREFIX, 6) == 0) {
                snprintf(h.to_line, sizeof h.to_line, "%s", line + 6);
                h.to_line[strcspn(h.to_line, "\r\n")] = '\0';
                status = parse_model_line(path, line_number, line + 6, &target, target_fixed);
            } else if (strncmp(line, MR_SWEEP_REMAP_PREFIX, 9) == 0) {
                snprintf(remap_line, sizeof remap_line, "%s", line + 9);
            } else if (strncmp(line, MR_SWEEP_SCENE_PREFIX, 9) == 0) {
                snprintf(h.scene, sizeof h.scene, "%s", line + 9);
                h.scene[strcspn(h.scene, "\r\n")] = '\0';
            }
            continue;
        }
        if (!have_columns) {
            if (source == NULL || target == NULL) {
                status = mr_fail(MR_ERR_FORMAT, "%s:%ld: no '# from:' or '# to:' header line before the columns: not "
                                 "a matremap sweep file", path, line_number);
                break;
            }
            unsigned held = 0;
            mr_brdf_ties ties;
            status = parse_held(path, remap_line, target, &held);
            if (status == MR_OK) status = parse_tied(path, remap_line, source, target, &ties);
            if (status != MR_OK) break;
            if (first) {
                t->target_held = held;
                t->target_ties = ties;
                *reference = h;
                t->source = source;
                t->target = target;
                t->source_count = mr_brdf_value_count(source);
                t->target_count = mr_brdf_value_count(target);
                memcpy(t->target_fixed, target_fixed, sizeof target_fixed);
                snprintf(t->scene, sizeof t->scene, "%s", h.scene);
            } else {
                const char *what = strcmp(h.from_model, reference->from_model) != 0 ? "source model"
                                   : strcmp(h.to_line, reference->to_line) != 0   ? "'# to:' line"
                                   : strcmp(h.scene, reference->scene) != 0       ? "'# scene:' line"
                                                                                  : NULL;
                if (what != NULL) {
                    status = mr_fail(MR_ERR_FORMAT, "%s and %s differ in their %s: one transform learns one mapping "
                                     "(same models, target values and fit scene)", reference_path, path, what);
                    break;
                }
                t->target_held &= held; // held only where every file held it
                for (int p = 0; p < 32; p++) // tied only where every file tied it alike
                    if (((t->target_ties.tied >> p) & 1u) &&
                        (!((ties.tied >> p) & 1u) || ties.source[p] != t->target_ties.source[p]))
                        t->target_ties.tied &= ~(1u << p);

            }
            char *names[MAX_COLUMNS];
            int count = mr_csv_split(line, names, MAX_COLUMNS);
            status = map_model_columns(path, names, count, source, "", cols.source);
            if (status == MR_OK) status = map_model_columns(path, names, count, target, "to_", cols.target);
            cols.ssim = cols.outcome = -1;
            for (int i = 0; i < count; i++) {
                if (strcmp(names[i], "ssim") == 0) cols.ssim = i;
                if (strcmp(names[i], "outcome") == 0) cols.outcome = i;
            }
            cols.count = count;
            if (status == MR_OK && (cols.ssim < 0 || cols.outcome < 0))
                status = mr_fail(MR_ERR_FORMAT, "%s:%ld: no 'ssim' or 'outcome' column", path, line_number);
            have_columns = 1;
            continue;
        }
        char *fields[MAX_COLUMNS];
        int count = mr_csv_split(line, fields, MAX_COLUMNS);
        if (count != cols.count) {
            status = mr_fail(MR_ERR_FORMAT, "%s:%ld: %d fields, the column line has %d (a torn or edited row)", path,
                             line_number, count, cols.count);
            break;
        }
        rows++;
        mr_fit_outcome outcome;
        if (mr_fit_outcome_from_name(fields[cols.outcome], &outcome) != MR_OK) {
            status = mr_fail(MR_ERR_FORMAT, "%s:%ld: unknown outcome '%s'", path, line_number, fields[cols.outcome]);
            break;
        }
        if (outcome == MR_FIT_LOCAL_MINIMUM && !(opts && opts->keep_all_outcomes)) {
            t->skipped++;
            continue;
        }
        status = grow(t, capacity);
        if (status != MR_OK) break;
        double *sv = t->source_values + t->n * (size_t)t->source_count;
        double *tv = t->target_values + t->n * (size_t)t->target_count;
        for (int k = 0; k < t->source_count + t->target_count + 1 && status == MR_OK; k++) {
            int column = k < t->source_count                     ? cols.source[k]
                         : k < t->source_count + t->target_count ? cols.target[k - t->source_count]
                                                                 : cols.ssim;
            double *into = k < t->source_count                     ? sv + k
                           : k < t->source_count + t->target_count ? tv + (k - t->source_count)
                                                                   : t->ssim + t->n;
            if (!mr_sweep_file_parse_number(fields[column], into))
                status = mr_fail(MR_ERR_FORMAT, "%s:%ld: column %d ('%s') is not a finite number", path, line_number,
                                 column + 1, fields[column]);
        }
        if (status == MR_OK) status = check_range(path, line_number, source, "", sv);
        if (status == MR_OK) status = check_range(path, line_number, target, "to_", tv);
        if (status != MR_OK) break;
        if (source->rescales != NULL && source->rescales(source, sv) && !(opts && opts->keep_rescaled)) {
            t->rescaled++;
            continue;
        }
        t->outcome[t->n++] = outcome;
        kept++;
    }
    if (status == MR_OK && !have_columns)
        status = mr_fail(MR_ERR_FORMAT, "%s: no column line: not a matremap sweep file (or an empty one)", path);
    if (status == MR_OK) {
        char summary[4200];
        snprintf(summary, sizeof summary, "sweep %s rows %zu kept %zu\n", path, rows, kept);
        status = append_text(&t->provenance, prov_length, summary);
        if (status == MR_OK && header_text) status = append_text(&t->provenance, prov_length, header_text);
    }
    free(header_text);
    mr_sweep_reader_close(&reader);
    return status;
}

mr_status mr_sweep_table_load(const char *const *paths, int count, const mr_sweep_table_options *opts,
                              mr_sweep_table *out) {
    if (out == NULL) return mr_fail(MR_ERR_INVALID_ARG, "sweep table: NULL output");
    memset(out, 0, sizeof *out);
    if (paths == NULL || count < 1) return mr_fail(MR_ERR_INVALID_ARG, "sweep table: no files");
    mr_c_numeric locale;
    mr_status status = mr_c_numeric_enter(&locale, "sweep table");
    if (status != MR_OK) return status;
    file_header reference;
    size_t capacity = 0, prov_length = 0;
    for (int i = 0; i < count && status == MR_OK; i++) {
        if (paths[i] == NULL) status = mr_fail(MR_ERR_INVALID_ARG, "sweep table: file %d is NULL", i);
        if (status == MR_OK) status = load_file(paths[i], opts, i == 0, &reference, paths[0], out, &capacity,
                                                &prov_length);
    }
    mr_c_numeric_leave(&locale);
    if (status == MR_OK && out->n == 0)
        status = mr_fail(MR_ERR_FORMAT, "%s%s: no usable rows (%zu left out for their outcome, %zu because model '%s' "
                         "rescales their source values%s)", paths[0], count > 1 ? " ..." : "", out->skipped,
                         out->rescaled, out->source ? out->source->name : "?",
                         out->rescaled ? ": a sweep of the values textures hold is 'sweep --random N' with the "
                                         "default --region texture" : "");
    if (status != MR_OK) mr_sweep_table_free(out);
    return status;
}

void mr_sweep_table_free(mr_sweep_table *t) {
    if (t == NULL) return;
    free(t->source_values);
    free(t->target_values);
    free(t->ssim);
    free(t->outcome);
    free(t->provenance);
    memset(t, 0, sizeof *t);
}
