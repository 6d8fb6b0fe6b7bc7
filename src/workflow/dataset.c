/*
 * dataset.c — sweep files -> (specular, metallic) training pairs. Contract in dataset.h. The files are read
 * through the sweep file's reader by column name (src/remap/sweep_file.h).
 */
#include "dataset.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../c_locale.h"
#include "../mr_internal.h"
#include "../remap/remap_file.h"
#include "../remap/sweep_file.h"
#include "workflow.h"

#define MAX_COLUMNS 256

/* Column indices a file provides (-1: absent). */
typedef struct columns {
    int diffuse[3], f0[3];                  /* specular-workflow source */
    int albedo[3], metallic, dielectric_f0; /* metallic-workflow source */
    int to_albedo[3], to_metallic, outcome;
} columns;

static mr_status map_columns(const char *path, char **names, int count, columns *c, int *metallic_source) {
    static const char rgb[3] = {'r', 'g', 'b'};
    char name[64];
    int have_specular = 1, have_metallic = 1, have_output = 1;
    for (int k = 0; k < 3; k++) {
        snprintf(name, sizeof name, "diffuse_%c", rgb[k]);
        c->diffuse[k] = mr_sweep_file_find_column(names, count, name);
        snprintf(name, sizeof name, "f0_%c", rgb[k]);
        c->f0[k] = mr_sweep_file_find_column(names, count, name);
        snprintf(name, sizeof name, "albedo_%c", rgb[k]);
        c->albedo[k] = mr_sweep_file_find_column(names, count, name);
        snprintf(name, sizeof name, "to_albedo_%c", rgb[k]);
        c->to_albedo[k] = mr_sweep_file_find_column(names, count, name);
        have_specular &= c->diffuse[k] >= 0 && c->f0[k] >= 0;
        have_metallic &= c->albedo[k] >= 0;
        have_output &= c->to_albedo[k] >= 0;
    }
    c->metallic = mr_sweep_file_find_column(names, count, "metallic");
    c->dielectric_f0 = mr_sweep_file_find_column(names, count, "dielectric_f0");
    c->to_metallic = mr_sweep_file_find_column(names, count, "to_metallic");
    c->outcome = mr_sweep_file_find_column(names, count, "outcome");
    have_metallic &= c->metallic >= 0 && c->dielectric_f0 >= 0;
    have_output &= c->to_metallic >= 0;
    if (!have_output || c->outcome < 0)
        return mr_fail(MR_ERR_FORMAT, "%s: no to_albedo_r/g/b, to_metallic or outcome column: expected a sweep "
                       "into a metallic-workflow model (e.g. --to ggx-metallic)", path);
    if (!have_specular && !have_metallic)
        return mr_fail(MR_ERR_FORMAT, "%s: the source has neither diffuse_r/g/b + f0_r/g/b columns (a specular "
                       "source, e.g. ggx) nor albedo_r/g/b + metallic + dielectric_f0 (e.g. ggx-metallic)", path);
    *metallic_source = !have_specular;
    return MR_OK;
}

/* Append one row's pair to d (growing the arrays); returns MR_OK, or a failure naming path:line. */
static mr_status take_row(const char *path, long line_number, char **fields, int field_count, const columns *c,
                          int metallic_source, mr_wf_dataset *d, size_t *capacity) {
    double in[6], out[4];
    int needed[12], used = 0;
    if (metallic_source) {
        for (int k = 0; k < 3; k++) needed[used++] = c->albedo[k];
        needed[used++] = c->metallic;
        needed[used++] = c->dielectric_f0;
    } else {
        for (int k = 0; k < 3; k++) needed[used++] = c->diffuse[k];
        for (int k = 0; k < 3; k++) needed[used++] = c->f0[k];
    }
    for (int k = 0; k < 3; k++) needed[used++] = c->to_albedo[k];
    needed[used++] = c->to_metallic;
    double values[12];
    for (int i = 0; i < used; i++) {
        if (needed[i] >= field_count || !mr_sweep_file_parse_number(fields[needed[i]], &values[i]))
            return mr_fail(MR_ERR_FORMAT, "%s:%ld: field %d is missing or not a finite number", path, line_number,
                           needed[i] + 1);
    }
    if (metallic_source) {
        mr_wf_options o = mr_wf_options_default();
        o.dielectric_f0 = values[4];
        mr_wf_metal metal = {{values[0], values[1], values[2]}, values[3], 0.0};
        mr_wf_spec spec;
        mr_status status = mr_wf_metal_to_spec(&metal, &o, &spec, NULL);
        if (status != MR_OK) return mr_fail_context(status, "%s:%ld", path, line_number);
        for (int k = 0; k < 3; k++) {
            in[k] = spec.diffuse[k];
            in[3 + k] = spec.specular[k];
        }
        for (int k = 0; k < 4; k++) out[k] = values[5 + k];
    } else {
        for (int k = 0; k < 6; k++) in[k] = values[k];
        for (int k = 0; k < 4; k++) out[k] = values[6 + k];
    }
    if (d->n == *capacity) {
        size_t grown = *capacity ? 2 * *capacity : 1024;
        float *x = realloc(d->x, grown * MR_WF_DATASET_INPUTS * sizeof *x);
        if (x == NULL) return mr_fail(MR_ERR_NOMEM, "dataset: out of memory at %zu pairs", d->n);
        d->x = x;
        float *y = realloc(d->y, grown * MR_WF_DATASET_OUTPUTS * sizeof *y);
        if (y == NULL) return mr_fail(MR_ERR_NOMEM, "dataset: out of memory at %zu pairs", d->n);
        d->y = y;
        *capacity = grown;
    }
    for (int k = 0; k < MR_WF_DATASET_INPUTS; k++) d->x[d->n * MR_WF_DATASET_INPUTS + k] = (float)in[k];
    for (int k = 0; k < MR_WF_DATASET_OUTPUTS; k++) d->y[d->n * MR_WF_DATASET_OUTPUTS + k] = (float)out[k];
    d->n++;
    return MR_OK;
}

static mr_status load_file(const char *path, const mr_wf_dataset_options *opts, mr_wf_dataset *d,
                           size_t *capacity) {
    mr_sweep_reader reader = {0};
    mr_status status = mr_sweep_reader_open(&reader, path, 0); /* lines of any length */
    char *header = NULL;
    char *names[MAX_COLUMNS], *fields[MAX_COLUMNS];
    int name_count = 0, metallic_source = 0;
    columns c;
    memset(&c, 0, sizeof c);
    while (status == MR_OK && mr_sweep_reader_next(&reader, &status) > 0) {
        char *line = reader.line;
        const long line_number = reader.line_number;
        if (line[0] == '#' || line[0] == '\n') continue;
        if (header == NULL) {
            header = strdup(line);
            if (header == NULL) {
                status = mr_fail(MR_ERR_NOMEM, "dataset: out of memory");
                break;
            }
            name_count = mr_csv_split(header, names, MAX_COLUMNS);
            status = map_columns(path, names, name_count, &c, &metallic_source);
            continue;
        }
        int field_count = mr_csv_split(line, fields, MAX_COLUMNS);
        if (field_count != name_count) {
            status = mr_fail(MR_ERR_FORMAT, "%s:%ld: %d fields, the header names %d (a torn last line? resume the "
                             "sweep to finish it)", path, line_number, field_count, name_count);
            break;
        }
        // Every outcome a sweep writes is known here (an under-resolved fit is kept, as learn's reader keeps it:
        // its label is the fit's best answer); only a local minimum, a fit known to be wrong, is left out.
        mr_fit_outcome outcome;
        if (mr_fit_outcome_from_name(fields[c.outcome], &outcome) != MR_OK) {
            status = mr_fail(MR_ERR_FORMAT, "%s:%ld: unknown outcome '%s'", path, line_number, fields[c.outcome]);
            break;
        }
        if (outcome == MR_FIT_LOCAL_MINIMUM && !(opts && opts->keep_all_outcomes)) {
            d->skipped++;
            continue;
        }
        status = take_row(path, line_number, fields, field_count, &c, metallic_source, d, capacity);
    }
    if (status == MR_OK && header == NULL) status = mr_fail(MR_ERR_FORMAT, "%s: no column header line", path);
    free(header);
    mr_sweep_reader_close(&reader);
    return status;
}

static mr_status dataset_load(const char *const *paths, int count, const mr_wf_dataset_options *opts,
                              mr_wf_dataset *out) {
    if (out == NULL || (count > 0 && paths == NULL) || count < 0)
        return mr_fail(MR_ERR_INVALID_ARG, "dataset: NULL output or file list");
    memset(out, 0, sizeof *out);
    size_t capacity = 0;
    for (int i = 0; i < count; i++) {
        mr_status status = paths[i] == NULL ? mr_fail(MR_ERR_INVALID_ARG, "dataset: file %d is NULL", i)
                                            : load_file(paths[i], opts, out, &capacity);
        if (status != MR_OK) {
            mr_wf_dataset_free(out);
            return status;
        }
    }
    return MR_OK;
}

void mr_wf_dataset_free(mr_wf_dataset *d) {
    if (d == NULL) return;
    free(d->x);
    free(d->y);
    memset(d, 0, sizeof *d);
}

/* Sweep files hold C-locale numbers, read as such in any host locale (c_locale.h). */
mr_status mr_wf_dataset_load(const char *const *paths, int count, const mr_wf_dataset_options *opts,
                             mr_wf_dataset *out) {
    mr_c_numeric locale;
    mr_status status = mr_c_numeric_enter(&locale, "dataset");
    if (status != MR_OK) return status;
    status = dataset_load(paths, count, opts, out);
    mr_c_numeric_leave(&locale);
    return status;
}
