/*
 * sweep_file.c — the sweep file's format: the header written and read back into a sweep, rows formatted, parsed
 * and checked, lines read (contract in sweep_file.h; the file is described in sweep.h). Everything here runs in
 * the C numeric locale its callers entered, so numbers read back bit for bit whatever the host's locale.
 */
#include "sweep_file.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../c_locale.h"
#include "../mr_internal.h"
#include "sweep_internal.h"

/* ---- the header and the rows ------------------------------------------------------------------------------- */

/* The header for this run (every line '\n'-terminated, the column line last), in the C numeric locale; a shard
 * (shard_count > 0) adds "# shard: K/N" before the command line. */
mr_status mr_sweep_command_line(const char *prefix, int argc, const char *const *argv, char **out) {
    if (out != NULL) *out = NULL;
    if (prefix == NULL || out == NULL || argc < 0 || (argc > 0 && argv == NULL))
        return mr_fail(MR_ERR_INVALID_ARG, "sweep command line: NULL argument");
    size_t size = strlen(prefix) + 1;
    for (int i = 0; i < argc; i++) size += 4 * strlen(argv[i]) + 3; // every character a quote ('\''), two quotes
    char *text = malloc(size), *o = text;
    if (text == NULL) return mr_fail(MR_ERR_NOMEM, "sweep command line: out of memory");
    o += sprintf(o, "%s", prefix);
    for (int i = 0; i < argc; i++) {
        const char *a = argv[i];
        *o++ = ' ';
        int plain = a[0] != '\0';
        for (const char *c = a; *c && plain; c++)
            plain = strchr("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_./:=,+-@%", *c) != NULL;
        if (plain) {
            o += sprintf(o, "%s", a);
            continue;
        }
        *o++ = '\'';
        for (const char *c = a; *c; c++) {
            if (*c == '\'') {
                memcpy(o, "'\\''", 4);
                o += 4;
            } else {
                *o++ = *c;
            }
        }
        *o++ = '\'';
    }
    *o = '\0';
    *out = text;
    return MR_OK;
}

mr_status mr_sweep_file_header(const mr_sweep_spec *spec, const char *command_line, long shard_index,
                               long shard_count, mr_strbuf *sb) {
    mr_strbuf_printf(sb, "# matremap %s sweep\n", mr_version());
    mr_strbuf_printf(sb, "# from: %s", spec->source->name);
    mr_strbuf_values(sb, spec->source, spec->source_values);
    mr_strbuf_printf(sb, "\n# to: %s", spec->target->name);
    mr_strbuf_values(sb, spec->target, spec->target_values);
    mr_strbuf_printf(sb, "\n");
    mr_strbuf_remap_lines(sb, spec->source, spec->target, &spec->remap, &spec->scene, &spec->renderers);
    if (spec->sampling == MR_SWEEP_GRID) {
        mr_strbuf_printf(sb, "# sampling: grid");
        for (int a = 0; a < spec->axis_count; a++) {
            const mr_sweep_axis *axis = &spec->axes[a];
            mr_strbuf_printf(sb, " %s=%.17g:%.17g:%ld%s", spec->source->params[axis->param].name, axis->lo, axis->hi,
                      axis->count, axis->log_scale ? ":log" : "");
        }
    } else {
        mr_strbuf_printf(sb, "# sampling: random=%ld seed=%llu", spec->random_count, spec->seed);
        // Files from before regions have no region word, and are RANGE (parse_sampling_line).
        if (spec->region != MR_SWEEP_REGION_RANGE)
            mr_strbuf_printf(sb, " region=%s", mr_sweep_region_name(spec->region));
        mr_strbuf_printf(sb, " over");
        int first = 1;
        for (int p = 0; p < spec->source->param_count; p++)
            if (mr_sweep_draws_param(spec, p)) {
                mr_strbuf_printf(sb, "%s%s", first ? " " : ",", spec->source->params[p].name);
                first = 0;
            }
    }
    mr_strbuf_printf(sb, "\n# samples: %ld\n", mr_sweep_total_unchecked(spec));
    if (shard_count > 0)
        mr_strbuf_printf(sb, MR_SWEEP_SHARD_PREFIX "%ld/%ld\n", shard_index, shard_count);
    mr_strbuf_printf(sb, MR_SWEEP_COMMAND_PREFIX);
    // The command line is informational; a line break in an argument must not start a line of its own.
    for (const char *c = command_line ? command_line : ""; *c; c++)
        mr_strbuf_printf(sb, "%c", *c == '\n' || *c == '\r' ? ' ' : *c);
    mr_strbuf_printf(sb, "\nindex");
    mr_strbuf_columns(sb, spec->source, "");
    mr_strbuf_columns(sb, spec->target, "to_");
    mr_strbuf_printf(sb, ",rmse,relative_rmse,ssim,outcome,renders,seconds\n");
    return sb->failed ? mr_fail(MR_ERR_NOMEM, "sweep: out of memory building the header") : MR_OK;
}

/* Row formatting in the current (C) numeric locale. */
mr_status mr_sweep_file_format_row(const mr_sweep_spec *spec, const mr_sweep_row *row, char *buf, size_t size,
                                   size_t *length) {
    const char *outcome = mr_fit_outcome_name(row->outcome);
    if (outcome == NULL) return mr_fail(MR_ERR_INVALID_ARG, "sweep row %ld: outcome %d out of range", row->index,
                                        (int)row->outcome);
    size_t used = 0;
    int n = snprintf(buf, size, "%ld", row->index);
    int ns = mr_brdf_value_count(spec->source), nt = mr_brdf_value_count(spec->target);
    for (int k = 0; n >= 0 && k < ns + nt; k++) {
        used += (size_t)n;
        double v = k < ns ? row->source[k] : row->target[k - ns];
        n = snprintf(buf + MR_MIN(used, size), used < size ? size - used : 0, ",%.17g", v);
    }
    if (n >= 0) {
        used += (size_t)n;
        n = snprintf(buf + MR_MIN(used, size), used < size ? size - used : 0, ",%.17g,%.17g,%.17g,%s,%ld,%.17g\n",
                     row->rmse, row->relative_rmse, row->ssim, outcome, row->renders, row->seconds);
    }
    if (n < 0 || used + (size_t)n >= size)
        return mr_fail(MR_ERR_INVALID_ARG, "sweep row %ld: does not fit in a buffer of %zu bytes", row->index, size);
    if (length != NULL) *length = used + (size_t)n;
    return MR_OK;
}

mr_status mr_sweep_format_row(const mr_sweep_spec *spec, const mr_sweep_row *row, char *buf, size_t size,
                              size_t *length) {
    if (spec == NULL || spec->source == NULL || spec->target == NULL || row == NULL || buf == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "sweep: NULL spec, row or buffer");
    mr_c_numeric cn;
    mr_status status = mr_c_numeric_enter(&cn, "sweep");
    if (status != MR_OK) return status;
    status = mr_sweep_file_format_row(spec, row, buf, size, length);
    mr_c_numeric_leave(&cn);
    return status;
}

/* Row parsing in the current (C) numeric locale; `total` bounds the index. */
mr_status mr_sweep_file_parse_row(const mr_sweep_spec *spec, long total, const char *line, size_t length,
                                  mr_sweep_row *out) {
    if (length > 0 && line[length - 1] == '\n') length--;
    size_t at = 0;
    const int ns = mr_brdf_value_count(spec->source), nt = mr_brdf_value_count(spec->target);
    const int columns = 1 + ns + nt + MR_SWEEP_ROW_TAIL_COLUMNS;
    mr_sweep_row row;
    memset(&row, 0, sizeof row);
    const char *field = NULL;
    size_t len = 0;
    for (int k = 0; k < columns; k++) {
        if (!mr_csv_next_field(line, length, &at, &field, &len))
            return mr_fail(MR_ERR_FORMAT, "row has %d columns, expected %d", k, columns);
        int ok;
        if (k == 0) {
            ok = mr_csv_parse_long(field, len, &row.index) && row.index < total;
            if (!ok)
                return mr_fail(MR_ERR_FORMAT, "index '%.*s' is not a sample number in [0, %ld]",
                               (int)MR_MIN(len, 40), field, total - 1);
            continue;
        }
        int c = k - 1;
        if (c < ns) {
            ok = mr_csv_parse_double(field, len, &row.source[c]);
        } else if (c < ns + nt) {
            ok = mr_csv_parse_double(field, len, &row.target[c - ns]);
        } else {
            switch (c - ns - nt) {
            case 0: ok = mr_csv_parse_double(field, len, &row.rmse); break;
            case 1: ok = mr_csv_parse_double(field, len, &row.relative_rmse); break;
            case 2: ok = mr_csv_parse_double(field, len, &row.ssim); break;
            case 3:
                ok = 0;
                for (int o = 0; o < MR_FIT_OUTCOME_COUNT; o++) {
                    const char *name = mr_fit_outcome_name((mr_fit_outcome)o);
                    if (strlen(name) == len && memcmp(name, field, len) == 0) {
                        row.outcome = (mr_fit_outcome)o;
                        ok = 1;
                    }
                }
                break;
            case 4: ok = mr_csv_parse_long(field, len, &row.renders); break;
            default: ok = mr_csv_parse_double(field, len, &row.seconds); break;
            }
        }
        if (!ok)
            return mr_fail(MR_ERR_FORMAT, "column %d: '%.*s' is not a valid value", k + 1, (int)MR_MIN(len, 40),
                           field);
    }
    if (at != SIZE_MAX) return mr_fail(MR_ERR_FORMAT, "row has more than %d columns", columns);
    *out = row;
    return MR_OK;
}

mr_status mr_sweep_parse_row(const mr_sweep_spec *spec, const char *line, size_t length, mr_sweep_row *out) {
    mr_status status = mr_sweep_check(spec);
    if (status != MR_OK) return status;
    if (line == NULL || out == NULL) return mr_fail(MR_ERR_INVALID_ARG, "sweep: NULL line or output");
    mr_c_numeric cn;
    status = mr_c_numeric_enter(&cn, "sweep");
    if (status != MR_OK) return status;
    status = mr_sweep_file_parse_row(spec, mr_sweep_total_unchecked(spec), line, length, out);
    mr_c_numeric_leave(&cn);
    return status;
}

void mr_sweep_file_slot_name(const mr_brdf_model *m, int slot, const char *prefix, char *buf, size_t size) {
    static const char *const suffix[3] = {"_r", "_g", "_b"};
    for (int p = 0; p < m->param_count; p++) {
        int offset = mr_brdf_param_offset(m, p), channels = m->params[p].channels;
        if (slot >= offset && slot < offset + channels) {
            snprintf(buf, size, "%s%s%s", prefix, m->params[p].name, channels == 3 ? suffix[slot - offset] : "");
            return;
        }
    }
    snprintf(buf, size, "?");
}

/* The name of field k of a row (0: "index"), as in the column line. */
static void column_name(const mr_sweep_spec *spec, int k, char *buf, size_t size) {
    static const char *const tail[MR_SWEEP_ROW_TAIL_COLUMNS] = {"rmse",    "relative_rmse", "ssim",
                                                                "outcome", "renders",       "seconds"};
    const int ns = mr_brdf_value_count(spec->source), nt = mr_brdf_value_count(spec->target);
    const int c = k - 1;
    if (k == 0)
        snprintf(buf, size, "index");
    else if (c < ns)
        mr_sweep_file_slot_name(spec->source, c, "", buf, size);
    else if (c < ns + nt)
        mr_sweep_file_slot_name(spec->target, c - ns, "to_", buf, size);
    else
        snprintf(buf, size, "%s", c - ns - nt < MR_SWEEP_ROW_TAIL_COLUMNS ? tail[c - ns - nt] : "?");
}

/* Range checks of a row's values (contract in sweep.h). The fitted values may lie outside a parameter's range by
 * rounding (mr_remap maps a log-scaled range's endpoints through exp(log(x)): Phong's exponent can come back as
 * 10000.000000000009), hence the band of 1e-9 of the range's width; 1e300 or a negative reflectance never fit. */
mr_status mr_sweep_file_check_row(const mr_sweep_spec *spec, const mr_sweep_row *row) {
    char name[64];
    int column = 1;
    for (int side = 0; side < 2; side++) {
        const mr_brdf_model *m = side ? spec->target : spec->source;
        const double *v = side ? row->target : row->source;
        for (int p = 0; p < m->param_count; p++) {
            const mr_brdf_param *param = &m->params[p];
            const double band = 1e-9 * (param->max_value - param->min_value);
            for (int c = 0; c < param->channels; c++, column++) {
                const double x = v[mr_brdf_param_offset(m, p) + c];
                if (isfinite(x) && x >= param->min_value - band && x <= param->max_value + band &&
                    (param->role != MR_PARAM_SWITCH || x == floor(x)))
                    continue;
                column_name(spec, column, name, sizeof name);
                if (!isfinite(x))
                    return mr_fail(MR_ERR_FORMAT, "column %d (%s): %g is not a finite number", column + 1, name, x);
                if (x < param->min_value - band || x > param->max_value + band)
                    return mr_fail(MR_ERR_FORMAT, "column %d (%s): %.17g is outside %s's range [%g, %g] (model '%s')",
                                   column + 1, name, x, param->name, param->min_value, param->max_value, m->name);
                return mr_fail(MR_ERR_FORMAT, "column %d (%s): %.17g is not an integer (%s is a switch of model '%s')",
                               column + 1, name, x, param->name, m->name);
            }
        }
    }
    // column is now the first tail column's field index (rmse).
    const struct {
        double value;
        int ok;
        const char *expected;
    } tail[] = {
        {row->rmse, isfinite(row->rmse) && row->rmse >= 0.0, "a finite number >= 0"},
        {row->relative_rmse, row->relative_rmse >= 0.0, "a number >= 0 (or inf)"},
        {row->ssim, isfinite(row->ssim) && fabs(row->ssim) <= 1.0 + 1e-9, "a number in [-1, 1]"},
    };
    for (int t = 0; t < 3; t++)
        if (!tail[t].ok) {
            column_name(spec, column + t, name, sizeof name);
            return mr_fail(MR_ERR_FORMAT, "column %d (%s): %g is not %s", column + t + 1, name, tail[t].value,
                           tail[t].expected);
        }
    if ((int)row->outcome < 0 || row->outcome >= MR_FIT_OUTCOME_COUNT)
        return mr_fail(MR_ERR_FORMAT, "column %d (outcome): %d is not an outcome", column + 4, (int)row->outcome);
    if (row->renders < 0)
        return mr_fail(MR_ERR_FORMAT, "column %d (renders): %ld is negative", column + 5, row->renders);
    if (!(isfinite(row->seconds) && row->seconds >= 0.0))
        return mr_fail(MR_ERR_FORMAT, "column %d (seconds): %g is not a finite number >= 0", column + 6, row->seconds);
    return MR_OK;
}

mr_status mr_sweep_check_row(const mr_sweep_spec *spec, const mr_sweep_row *row) {
    mr_status status = mr_sweep_check(spec);
    if (status != MR_OK)
        return status;
    if (row == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "sweep: NULL row");
    return mr_sweep_file_check_row(spec, row);
}

/* ---- the header read back ---------------------------------------------------------------------------------- */

/* text[0, length) copied into copy[MR_SWEEP_MAX_LINE] and split there at spaces into words[0 .. *n), at most `max`
 * (*n = -1 if there are more). MR_ERR_FORMAT if the text does not fit the copy. */
static mr_status split_line(const char *text, size_t length, char *copy, char **words, int max, int *n) {
    if (length >= MR_SWEEP_MAX_LINE)
        return mr_fail(MR_ERR_FORMAT, "the line is too long");
    memcpy(copy, text, length);
    copy[length] = '\0';
    *n = 0;
    char *save = NULL;
    for (char *w = strtok_r(copy, " ", &save); w != NULL; w = strtok_r(NULL, " ", &save)) {
        if (*n == max) {
            *n = -1;
            break;
        }
        words[(*n)++] = w;
    }
    return MR_OK;
}

mr_status mr_sweep_file_parse_model(const char *text, size_t length, const mr_brdf_model **model, double *values) {
    char copy[MR_SWEEP_MAX_LINE], *words[MR_SWEEP_MAX_LINE / 2 + 1]; /* as many words as the line can hold */
    int n = 0;
    mr_status status = split_line(text, length, copy, words, MR_SWEEP_MAX_LINE / 2 + 1, &n);
    if (status != MR_OK)
        return status;
    if (n < 1)
        return mr_fail(MR_ERR_FORMAT, "no model named");
    *model = mr_brdf_find(words[0]);
    if (*model == NULL)
        return MR_ERR_FORMAT; /* mr_brdf_find's message lists the models */
    mr_brdf_default_values(*model, values);
    for (int k = 1; k < n; k++)
        if (mr_brdf_parse_assignment(*model, words[k], values) != MR_OK)
            return MR_ERR_FORMAT; /* its message names the assignment */
    return MR_OK;
}

static int parse_whole_long(const char *text, long *out) { return mr_csv_parse_long(text, strlen(text), out); }

/* One "name=value" setting of a header line taken into *spec: 1, or 0 for a name or value this version does not
 * know. The value may be changed (held's list is cut at its commas). */
typedef int (*setting_fn)(const char *name, char *value, mr_sweep_spec *spec);

/* A header line's text: its words (after `head`, a first word the line must have, e.g. "fit"; NULL: none, else
 * MR_ERR_FORMAT `not_head`), each "name=value", given to take in order. MR_ERR_FORMAT "'WORD' is not name=value",
 * or "'NAME=VALUE' is not a WHAT this version knows" for the first one take refuses; split_line's errors. */
static mr_status parse_settings(const char *text, const char *head, const char *not_head, const char *what,
                                setting_fn take, mr_sweep_spec *spec) {
    char copy[MR_SWEEP_MAX_LINE], *words[16];
    int n = 0;
    mr_status status = split_line(text, strlen(text), copy, words, 16, &n);
    if (status != MR_OK)
        return status;
    const int first = head != NULL;
    if (head != NULL && (n < 1 || strcmp(words[0], head) != 0))
        return mr_fail(MR_ERR_FORMAT, "%s", not_head);
    for (int k = first; k < n; k++) {
        char *eq = strchr(words[k], '=');
        if (eq == NULL)
            return mr_fail(MR_ERR_FORMAT, "'%s' is not name=value", words[k]);
        *eq = '\0';
        if (!take(words[k], eq + 1, spec))
            return mr_fail(MR_ERR_FORMAT, "'%s=%s' is not a %s this version knows", words[k], eq + 1, what);
    }
    return MR_OK;
}

/* A setting of the remap line into spec->remap. */
static int take_remap_setting(const char *key, char *value, mr_sweep_spec *spec) {
    long v = 0;
    if (strcmp(key, "strategy") == 0)
        return mr_remap_strategy_from_name(value, &spec->remap.strategy) == MR_OK;
    if (strcmp(key, "xtol") == 0)
        return mr_csv_parse_double(value, strlen(value), &spec->remap.xtol);
    if (strcmp(key, "local") == 0) return mr_local_method_from_name(value, &spec->remap.local_method) == MR_OK;
    if (strcmp(key, "held") == 0) {
        int ok = 1;
        char *save = NULL;
        for (char *name = strtok_r(value, ",", &save); ok && name != NULL; name = strtok_r(NULL, ",", &save)) {
            int p = mr_brdf_param_index(spec->target, name);
            ok = p >= 0 && p < 32;
            if (ok)
                spec->remap.held |= 1u << p;
        }
        return ok;
    }
    if (strcmp(key, "tied") == 0) { // "target:source,..."
        int ok = 1;
        char *save = NULL;
        for (char *item = strtok_r(value, ",", &save); ok && item != NULL; item = strtok_r(NULL, ",", &save)) {
            char *colon = strchr(item, ':');
            ok = colon != NULL;
            if (!ok) break;
            *colon = '\0';
            const int t = mr_brdf_param_index(spec->target, item), s = mr_brdf_param_index(spec->source, colon + 1);
            ok = t >= 0 && t < 32 && s >= 0 && spec->target->params[t].channels == spec->source->params[s].channels;
            if (ok) {
                spec->remap.ties.tied |= 1u << t;
                spec->remap.ties.source[t] = (signed char)s;
            }
        }
        return ok;
    }
    if (strcmp(key, "renderers") == 0) { // "source,target"
        char *comma = strchr(value, ',');
        if (comma == NULL || (size_t)(comma - value) >= sizeof spec->renderers.source ||
            strlen(comma + 1) >= sizeof spec->renderers.target)
            return 0;
        *comma = '\0';
        snprintf(spec->renderers.source, sizeof spec->renderers.source, "%s", value);
        snprintf(spec->renderers.target, sizeof spec->renderers.target, "%s", comma + 1);
        return mr_renderer_check(spec->renderers.source, spec->source) == MR_OK &&
               mr_renderer_check(spec->renderers.target, spec->target) == MR_OK;
    }
    if (!parse_whole_long(value, &v) || v > INT_MAX)
        return 0;
    if (strcmp(key, "samples") == 0)
        spec->renderers.samples = (int)v;
    else if (strcmp(key, "max_evaluations") == 0)
        spec->remap.max_evaluations = (int)v;
    else if (strcmp(key, "grid_points") == 0)
        spec->remap.grid_points = (int)v;
    else if (strcmp(key, "starts") == 0)
        spec->remap.starts = (int)v;
    else if (strcmp(key, "seed") == 0)
        spec->remap.seed = (unsigned long)v;
    else
        return 0;
    return 1;
}

/* "strategy=S max_evaluations=N xtol=X grid_points=G starts=S seed=S[ held=a,b]" into spec->remap. */
static mr_status parse_remap_line(const char *text, mr_sweep_spec *spec) {
    return parse_settings(text, NULL, NULL, "remap option", take_remap_setting, spec);
}

/* A setting of the scene line into spec->scene; names this version does not write are let through (the rebuilt
 * header shows whether they match). */
static int take_scene_setting(const char *key, char *value, mr_sweep_spec *spec) {
    long v = 0;
    if (strcmp(key, "size") == 0)
        return parse_whole_long(value, &v) && v <= MR_RENDER_MAX_SIZE && (spec->scene.size = (int)v, 1);
    if (strcmp(key, "light") == 0)
        return mr_fit_light_from_name(value, &spec->scene.light) == MR_OK;
    if (strcmp(key, "intensity") == 0)
        return mr_csv_parse_double(value, strlen(value), &spec->scene.intensity);
    return 1;
}

/* "fit size=N light=L intensity=I ..." into spec->scene (the other fields are fixed by the version: the rebuilt
 * header shows whether they match). */
static mr_status parse_scene_line(const char *text, mr_sweep_spec *spec) {
    return parse_settings(text, "fit", "not a fit scene", "scene setting", take_scene_setting, spec);
}

mr_status mr_sweep_scene_parse(const char *text, mr_fit_scene_options *out) {
    mr_sweep_spec spec;
    memset(&spec, 0, sizeof spec);
    mr_status status = text != NULL && out != NULL ? parse_scene_line(text, &spec)
                                                    : mr_fail(MR_ERR_INVALID_ARG, "sweep scene: NULL argument");
    if (status == MR_OK) *out = spec.scene;
    return status;
}

/* "grid AXIS ..." or "random=N seed=S over p,q,..." into the spec's sampling. */
static mr_status parse_sampling_line(const char *text, mr_sweep_spec *spec) {
    char copy[MR_SWEEP_MAX_LINE], *words[MR_SWEEP_MAX_AXES + 1];
    int n = 0;
    mr_status status = split_line(text, strlen(text), copy, words, MR_SWEEP_MAX_AXES + 1, &n);
    if (status != MR_OK)
        return status;
    if (n >= 2 && strcmp(words[0], "grid") == 0) {
        spec->sampling = MR_SWEEP_GRID;
        for (int k = 1; k < n; k++) {
            mr_status status = mr_sweep_parse_axis(spec->source, words[k], &spec->axes[k - 1]);
            if (status != MR_OK)
                return MR_ERR_FORMAT;
        }
        spec->axis_count = n - 1;
        return MR_OK;
    }
    spec->region = MR_SWEEP_REGION_RANGE; // a header without a region word
    if (n == 5 && strncmp(words[2], "region=", 7) == 0) {
        if (mr_sweep_region_from_name(words[2] + 7, &spec->region) != MR_OK)
            return mr_fail(MR_ERR_FORMAT, "'%s': expected region=texture or region=range", words[2]);
        words[2] = words[3];
        words[3] = words[4];
        n = 4;
    }
    if (n == 4 && strncmp(words[0], "random=", 7) == 0 && strncmp(words[1], "seed=", 5) == 0 &&
        strcmp(words[2], "over") == 0) {
        spec->sampling = MR_SWEEP_RANDOM;
        char *end = NULL;
        errno = 0;
        unsigned long long seed = strtoull(words[1] + 5, &end, 10);
        if (!parse_whole_long(words[0] + 7, &spec->random_count) || words[1][5] < '0' || words[1][5] > '9' ||
            *end != '\0' || errno == ERANGE)
            return mr_fail(MR_ERR_FORMAT, "'%s %s': expected random=N seed=S", words[0], words[1]);
        spec->seed = seed;
        // Every parameter not drawn is held (switches and fixed factors are never drawn anyway).
        spec->held = spec->source->param_count >= 32 ? ~0u : (1u << spec->source->param_count) - 1;
        char *save = NULL;
        for (char *name = strtok_r(words[3], ",", &save); name != NULL; name = strtok_r(NULL, ",", &save)) {
            int p = mr_brdf_param_index(spec->source, name);
            if (p < 0 || p >= 32)
                return mr_fail(MR_ERR_FORMAT, "model '%s' has no parameter '%s'", spec->source->name, name);
            spec->held &= ~(1u << p);
        }
        return MR_OK;
    }
    return mr_fail(MR_ERR_FORMAT, "expected 'grid AXIS ...' or 'random=N seed=S [region=R] over PARAMETERS'");
}

mr_status mr_sweep_file_spec_from_header(const char *from, const char *to, const char *remap, const char *scene,
                                         const char *sampling, mr_sweep_spec *spec, const char **step) {
    const mr_brdf_model *source = NULL, *target = NULL;
    double sv[MR_BRDF_MAX_VALUES], tv[MR_BRDF_MAX_VALUES];
    const char *at = "# from:";
    mr_status status = mr_sweep_file_parse_model(from, strlen(from), &source, sv);
    if (status == MR_OK) {
        at = "# to:";
        status = mr_sweep_file_parse_model(to, strlen(to), &target, tv);
    }
    if (status == MR_OK) {
        mr_sweep_spec_init(spec, source, target);
        memcpy(spec->source_values, sv, sizeof sv);
        memcpy(spec->target_values, tv, sizeof tv);
        at = "# remap:";
        status = parse_remap_line(remap, spec);
    }
    if (status == MR_OK) {
        at = "# scene:";
        status = parse_scene_line(scene, spec);
    }
    if (status == MR_OK) {
        at = "# sampling:";
        status = parse_sampling_line(sampling, spec);
    }
    if (status == MR_OK) {
        at = "the header";
        status = mr_sweep_check(spec);
    }
    if (step != NULL)
        *step = at;
    return status == MR_OK ? MR_OK : MR_ERR_FORMAT;
}

/* ---- reading by column name ------------------------------------------------------------------------------- */

mr_status mr_sweep_reader_open(mr_sweep_reader *r, const char *path, size_t max_line) {
    r->path = path;
    r->max_line = max_line;
    return mr_io_open_input(path, path, 0, &r->fp, NULL); /* regular files only: a FIFO would block */
}

int mr_sweep_reader_next(mr_sweep_reader *r, mr_status *failure) {
    errno = 0;
    ssize_t length = getline(&r->line, &r->capacity, r->fp);
    if (length < 0) {
        if (errno == ENOMEM) {
            *failure = mr_fail(MR_ERR_NOMEM, "%s: out of memory reading line %ld", r->path, r->line_number + 1);
            return -1;
        }
        if (!ferror(r->fp))
            return 0;
        *failure = mr_fail(MR_ERR_IO, "%s: read error: %s", r->path, strerror(errno));
        return -1;
    }
    r->length = (size_t)length;
    r->line_number++;
    if (r->max_line > 0 && r->length - (r->line[r->length - 1] == '\n') > r->max_line) {
        *failure = mr_fail(MR_ERR_FORMAT, "%s:%ld: line longer than %zu bytes", r->path, r->line_number,
                           r->max_line);
        return -1;
    }
    return 1;
}

void mr_sweep_reader_close(mr_sweep_reader *r) {
    if (r == NULL)
        return;
    if (r->fp != NULL)
        fclose(r->fp);
    free(r->line);
    memset(r, 0, sizeof *r);
}

int mr_sweep_file_find_column(char *const *names, int count, const char *name) {
    for (int i = 0; i < count; i++)
        if (strcmp(names[i], name) == 0)
            return i;
    return -1;
}

int mr_sweep_file_parse_number(const char *text, double *out) {
    char *end = NULL;
    errno = 0;
    double v = strtod(text, &end);
    if (end == text || *end != '\0' || !isfinite(v))
        return 0;
    *out = v;
    return 1;
}
