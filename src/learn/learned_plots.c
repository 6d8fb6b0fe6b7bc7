/*
 * learned_plots.c — a learned transform's cross sections, written with it as one set of files. Contract in
 * learned_plots.h.
 */
#include "learn/learned_plots.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "c_locale.h"
#include "io/gnuplot.h"
#include "mr_internal.h"

enum { PLOT_ROWS, PLOT_CURVES, PLOT_ROUGHNESS, PLOT_SPECULAR };
static const char *const plot_names[MR_LEARNED_PLOT_FILES] = {"rows.csv", "curves.csv", "roughness.svg",
                                                               "specular.svg"};

const char *mr_learned_plot_file_name(int k) {
    return k >= 0 && k < MR_LEARNED_PLOT_FILES ? plot_names[k] : NULL;
}

/* The roughness and specular features/outputs of a transform, if it has them (the paper's cross sections). */
typedef struct plot_axes {
    int rough_feature, spec_feature, rough_output, spec_output;
} plot_axes;

/* The first roughness slot (a one-channel nonlinear parameter) and the first specular slot (a linear specular one,
 * not a single channel) among slots[0..count) of `model`, or -1. */
static void find_pair(const mr_brdf_model *model, const mr_learned_slot *slots, int count, int *rough, int *spec) {
    *rough = *spec = -1;
    for (int i = 0; i < count; i++) {
        const mr_brdf_param *p = &model->params[slots[i].param];
        if (p->channels == 1 && p->role == MR_PARAM_NONLINEAR && *rough < 0) *rough = i;
        else if ((p->lobe & MR_LOBE_SPECULAR) && p->role != MR_PARAM_NONLINEAR && *spec < 0 &&
                 slots[i].kind != MR_LEARNED_CHANNEL)
            *spec = i;
    }
}

static int find_axes(const mr_learned *t, plot_axes *a) {
    find_pair(t->source, t->features, t->feature_count, &a->rough_feature, &a->spec_feature);
    find_pair(t->target, t->outputs, t->output_count, &a->rough_output, &a->spec_output);
    return a->rough_feature >= 0 && a->spec_feature >= 0 && a->rough_output >= 0 && a->spec_output >= 0;
}

static double slot_of(const mr_brdf_model *m, const mr_learned_slot *s, const double *row) {
    const int at = mr_brdf_param_offset(m, s->param) + (s->kind == MR_LEARNED_CHANNEL ? s->channel : 0);
    return s->kind == MR_LEARNED_GREY ? (row[at] + row[at + 1] + row[at + 2]) / 3.0 : row[at];
}

/* The learned target at source roughness r and specular s (every other source value from `base_row`). */
static mr_status learned_at(const mr_learned *t, const plot_axes *a, const double *base_row, double r, double s,
                            double *rough, double *spec) {
    double v[MR_BRDF_MAX_VALUES], w[MR_BRDF_MAX_VALUES];
    memcpy(v, base_row, (size_t)mr_brdf_value_count(t->source) * sizeof *v);
    const mr_learned_slot *fr = &t->features[a->rough_feature], *fs = &t->features[a->spec_feature];
    v[mr_brdf_param_offset(t->source, fr->param)] = r;
    const int sat = mr_brdf_param_offset(t->source, fs->param);
    for (int c = 0; c < (fs->kind == MR_LEARNED_GREY ? 3 : 1); c++) v[sat + c] = s;
    mr_status status = mr_learned_apply_batch(t, 1, v, w, NULL); // (mr_learned_apply would hide a failure)
    if (status != MR_OK)
        return status;
    *rough = slot_of(t->target, &t->outputs[a->rough_output], w);
    *spec = slot_of(t->target, &t->outputs[a->spec_output], w);
    return MR_OK;
}

static void abort_all(mr_atomic_file files[MR_LEARNED_PLOT_FILES]) {
    for (int k = 0; k < MR_LEARNED_PLOT_FILES; k++) mr_atomic_abort(&files[k]);
}

/* rows.csv: every row of the sweeps at the cut; *smax gets the largest source specular. */
static mr_status write_rows(const mr_learned *t, const plot_axes *a, const mr_sweep_table *tab, const char *path,
                            mr_atomic_file *file, double *smax) {
    FILE *f = NULL;
    mr_status status = mr_atomic_open_text(path, file, &f);
    if (status != MR_OK) return status;
    const mr_learned_slot *fr = &t->features[a->rough_feature], *fs = &t->features[a->spec_feature];
    const mr_learned_slot *or_ = &t->outputs[a->rough_output], *os = &t->outputs[a->spec_output];
    fprintf(f, "source_roughness,source_specular,target_roughness,target_specular\n");
    *smax = 0.0;
    for (size_t r = 0; r < tab->n; r++) {
        const double *sv = tab->source_values + r * (size_t)tab->source_count;
        const double *tv = tab->target_values + r * (size_t)tab->target_count;
        const double s = slot_of(t->source, fs, sv);
        *smax = fmax(*smax, s);
        fprintf(f, "%.9g,%.9g,%.9g,%.9g\n", slot_of(t->source, fr, sv), s, slot_of(t->target, or_, tv),
                slot_of(t->target, os, tv));
    }
    return mr_atomic_close_text(f, file);
}

/* curves.csv: roughness over the domain (specular at the domain's middle); specular lines at 6 roughnesses across
 * the domain, drawn to 1.5 x the largest specular of the rows (what lies beyond is extrapolation). */
static mr_status write_curves(const mr_learned *t, const plot_axes *a, const mr_sweep_table *tab, double smax,
                              const char *path, mr_atomic_file *file) {
    FILE *f = NULL;
    mr_status status = mr_atomic_open_text(path, file, &f);
    if (status != MR_OK) return status;
    const mr_learned_slot *fr = &t->features[a->rough_feature], *fs = &t->features[a->spec_feature];
    const double *base_row = tab->source_values;
    const double rlo = fr->min, rhi = fr->max, smid = 0.5 * (fs->min + fs->max);
    fprintf(f, "# roughness curve\nsource_roughness,target_roughness\n");
    for (int k = 0; k <= 200 && status == MR_OK; k++) {
        const double r = rlo + (rhi - rlo) * k / 200.0;
        double tr, ts;
        status = learned_at(t, a, base_row, r, smid, &tr, &ts);
        fprintf(f, "%.9g,%.9g\n", r, tr);
    }
    for (int line = 0; line < 6 && status == MR_OK; line++) {
        const double r = rlo * pow(rhi / rlo, line / 5.0);
        fprintf(f, "\n\n# specular line at roughness %.4g\nsource_specular,target_specular,roughness\n", r);
        for (int k = 0; k <= 50 && status == MR_OK; k++) {
            const double s = 1.5 * fmax(smax, 1e-6) * k / 50.0;
            double tr, ts;
            status = learned_at(t, a, base_row, r, s, &tr, &ts);
            fprintf(f, "%.9g,%.9g,%.9g\n", s, ts, r);
        }
    }
    if (status != MR_OK) {
        fclose(f);
        mr_atomic_abort(file);
        return status;
    }
    return mr_atomic_close_text(f, file);
}

/* gnuplot draws both SVGs into their temporary files from the CSVs' temporary files (mr_gnuplot_draw: *drawn = 1
 * when it ran and succeeded). */
static mr_status draw_svgs(const mr_learned *t, const plot_axes *a, mr_atomic_file files[MR_LEARNED_PLOT_FILES],
                           int *drawn) {
    const mr_learned_slot *fr = &t->features[a->rough_feature], *fs = &t->features[a->spec_feature];
    const mr_learned_slot *or_ = &t->outputs[a->rough_output], *os = &t->outputs[a->spec_output];
    char title[256];
    snprintf(title, sizeof title, "%s -> %s (%s)", t->source->name, t->target->name, mr_learn_method_name(t->method));
    const char *sr = t->source->params[fr->param].name, *ss = t->source->params[fs->param].name;
    const char *tr = t->target->params[or_->param].name, *ts = t->target->params[os->param].name;
    const char *rows = files[PLOT_ROWS].tmp_path, *curves = files[PLOT_CURVES].tmp_path;
    return mr_gnuplot_draw(
        drawn,
            "set terminal svg size 720,520 dynamic font 'Helvetica,12' background rgb 'white'\n"
            "set datafile separator ','\nset grid\nset key top left\n"
            "set output '%s'\nset title '%s: roughness' noenhanced\n"
            "set xlabel '%s %s' noenhanced\nset ylabel '%s %s' noenhanced\n"
            "plot '%s' using 1:3 skip 1 with points pt 7 ps 0.5 lc rgb '#4477aa' title 'sweep rows', "
            "'%s' index 0 using 1:2 skip 1 with lines lw 2 lc rgb '#cc3311' title '%s'\n"
            "set output '%s'\nset title '%s: specular, coloured by source roughness' noenhanced\n"
            "set xlabel '%s %s' noenhanced\nset ylabel '%s %s' noenhanced\n"
            "set palette rgbformulae 33,13,10\nset cbrange [%.9g:%.9g]\nset logscale cb\nset cblabel '%s %s' "
            "noenhanced\n"
            "plot '%s' using 2:4:1 skip 1 with points pt 7 ps 0.5 lc palette title 'sweep rows', "
            "for [i=1:6] '%s' index i using 1:2:3 skip 1 with lines lw 1.5 lc palette notitle\n",
            files[PLOT_ROUGHNESS].tmp_path, title, t->source->name, sr, t->target->name, tr, rows, curves,
            mr_learn_method_name(t->method), files[PLOT_SPECULAR].tmp_path, title, t->source->name, ss,
            t->target->name, ts, fr->min, fr->max, t->source->name, sr, rows, curves);
}

/* The plots as temporary files (files[] zero-initialised by the caller, their targets paths[]), or nothing when
 * the transform has no cut (*cut = 0). On failure every temporary file is removed. *created = 1 when dir was made
 * here. */
static mr_status prepare(const mr_learned *t, const mr_sweep_table *tab, const char *dir, const char *hint,
                         mr_atomic_file files[MR_LEARNED_PLOT_FILES], char paths[MR_LEARNED_PLOT_FILES][4096],
                         int *created, mr_learned_plots_result *result) {
    plot_axes a;
    if (!find_axes(t, &a)) return MR_OK;
    if (mkdir(dir, 0777) == 0)
        *created = 1;
    else if (errno != EEXIST)
        return mr_fail(MR_ERR_IO, "%s '%s': cannot create the folder: %s", hint, dir, strerror(errno));
    for (int k = 0; k < MR_LEARNED_PLOT_FILES; k++) {
        int length = snprintf(paths[k], sizeof paths[k], "%s/%s", dir, plot_names[k]);
        if (length < 0 || (size_t)length >= sizeof paths[k])
            return mr_fail(MR_ERR_IO, "%s '%s': the name is too long", hint, dir);
    }
    double smax = 0.0;
    mr_status status = write_rows(t, &a, tab, paths[PLOT_ROWS], &files[PLOT_ROWS], &smax);
    if (status == MR_OK) status = write_curves(t, &a, tab, smax, paths[PLOT_CURVES], &files[PLOT_CURVES]);
    for (int k = PLOT_ROUGHNESS; k <= PLOT_SPECULAR && status == MR_OK; k++)
        status = mr_atomic_begin(paths[k], &files[k]);
    int drawn = 0;
    if (status == MR_OK) status = draw_svgs(t, &a, files, &drawn);
    if (status != MR_OK) {
        abort_all(files);
        return status;
    }
    if (!drawn) {
        mr_atomic_abort(&files[PLOT_ROUGHNESS]);
        mr_atomic_abort(&files[PLOT_SPECULAR]);
    }
    result->cut = 1;
    result->drawn = drawn;
    return MR_OK;
}

static mr_status write_with_plots(const mr_learned *t, const mr_sweep_table *rows, const char *path,
                                  const char *dir, const char *hint, mr_learned_plots_result *result) {
    // The plots are prepared first and committed after the transform, so a failure leaves neither.
    mr_atomic_file files[MR_LEARNED_PLOT_FILES];
    memset(files, 0, sizeof files);
    char paths[MR_LEARNED_PLOT_FILES][4096];
    int created = 0;
    mr_status status = dir != NULL ? prepare(t, rows, dir, hint, files, paths, &created, result) : MR_OK;
    if (status == MR_OK) {
        status = mr_learned_write(t, path);
        if (status != MR_OK) abort_all(files);
    }
    if (status == MR_OK) status = mr_atomic_commit_set(files, MR_LEARNED_PLOT_FILES, &path, 1);
    if (status != MR_OK && created) rmdir(dir); // only if empty: nothing of this call is left in it
    return status;
}

mr_status mr_learned_write_with_plots(const mr_learned *t, const mr_sweep_table *rows, const char *path,
                                      const char *dir, const mr_learned_plots_options *opts,
                                      mr_learned_plots_result *result) {
    mr_learned_plots_result ignored;
    if (result == NULL) result = &ignored;
    memset(result, 0, sizeof *result);
    if (t == NULL || rows == NULL || path == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "learned plots: NULL transform, rows or path");
    const char *hint = opts != NULL && opts->folder_hint != NULL ? opts->folder_hint : "plots folder";
    mr_c_numeric locale; // the CSVs' and the script's numbers in the C locale whatever the host's (c_locale.h)
    mr_status status = mr_c_numeric_enter(&locale, "learned plots");
    if (status != MR_OK) return status;
    status = write_with_plots(t, rows, path, dir, hint, result);
    mr_c_numeric_leave(&locale);
    if (status != MR_OK) memset(result, 0, sizeof *result);
    return status;
}
