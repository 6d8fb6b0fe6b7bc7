/*
 * learn.c — training learned transforms from sweep rows (contract in learned.h): which parameters are features,
 * outputs, carries and base values; the held-out split; the three methods.
 */
#include <math.h>
#include <stdint.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "learn/learned.h"
#include "learn/svr.h"
#include "mr_internal.h"
#include "metrics/metrics.h"
#include "remap/remap_file.h"
#include "remap/sweep.h"
#include "nn/mlp.h"

#define DEFAULT_VALIDATION 0.2
#define DEFAULT_DEGREE 4
#define DEFAULT_HIDDEN 64
#define DEFAULT_EPOCHS 2000
#define MIN_ROWS 10

/* A fitted target value varies over the rows only when it moves by more than this share of its parameter's range:
 * a lobe the source does not have (a diffuse held at 0 on both sides) is fitted to 0 in most rows and to a residue
 * of the solver (1e-12 .. 1e-7) in a few, which is not something to learn. Source values are compared exactly. */
#define TARGET_NOISE 1e-5

/* How a parameter behaves over the rows. */
typedef struct param_use {
    int varies; /* some slot differs between rows by more than the tolerance */
    int grey;   /* RGB and r = g = b in every row (up to a relative 1e-9) */
} param_use;

static param_use use_of(const double *values, size_t n, int count, int offset, int channels, double tolerance) {
    param_use u = {0, channels == 3};
    for (size_t i = 0; i < n; i++) {
        const double *row = values + i * (size_t)count + offset;
        for (int c = 0; c < channels; c++)
            if (fabs(row[c] - values[offset + c]) > tolerance) u.varies = 1;
        if (channels == 3) {
            const double tol = 1e-9 * fmax(1.0, fabs(row[0]));
            if (fabs(row[1] - row[0]) > tol || fabs(row[2] - row[0]) > tol) u.grey = 0;
        }
    }
    return u;
}

/* A seeded permutation of 0 .. n-1 (Fisher-Yates). */
static size_t *shuffled(size_t n, unsigned long long seed) {
    size_t *order = malloc(n * sizeof *order);
    if (order == NULL) return NULL;
    for (size_t i = 0; i < n; i++) order[i] = i;
    uint64_t state = seed;
    for (size_t i = n; i > 1; i--) {
        size_t j = (size_t)(mr_rng_next(&state) % i);
        size_t tmp = order[i - 1];
        order[i - 1] = order[j];
        order[j] = tmp;
    }
    return order;
}

/* The value a slot takes in one row (GREY: the channel mean). */
static double slot_value(const mr_brdf_model *model, const mr_learned_slot *s, const double *row) {
    const int at = mr_brdf_param_offset(model, s->param) + (s->kind == MR_LEARNED_CHANNEL ? s->channel : 0);
    return s->kind == MR_LEARNED_GREY ? (row[at] + row[at + 1] + row[at + 2]) / 3.0 : row[at];
}

static void add_slot(mr_learned_slot *slots, int *count, int param, int channels, int grey) {
    if (channels == 3 && !grey) {
        for (int c = 0; c < 3; c++) slots[(*count)++] = (mr_learned_slot){param, MR_LEARNED_CHANNEL, c, 0.0, 0.0};
    } else {
        slots[(*count)++] = (mr_learned_slot){param, channels == 3 ? MR_LEARNED_GREY : MR_LEARNED_SCALAR, 0, 0.0, 0.0};
    }
}

static mr_status note(mr_learned *t, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static mr_status note(mr_learned *t, const char *fmt, ...) {
    char line[512];
    va_list args;
    va_start(args, fmt);
    vsnprintf(line, sizeof line, fmt, args);
    va_end(args);
    size_t have = t->provenance ? strlen(t->provenance) : 0, more = strlen(line);
    char *grown = realloc(t->provenance, have + more + 8);
    if (grown == NULL) return mr_fail(MR_ERR_NOMEM, "learn: out of memory");
    memcpy(grown + have, "note: ", 6);
    memcpy(grown + have + 6, line, more);
    memcpy(grown + have + 6 + more, "\n", 2);
    t->provenance = grown;
    return MR_OK;
}

/* f_r's diffuse part of `model` at normal incidence and at a grazing pair, with parameter p at `value` and the rest
 * at `values`. */
static void diffuse_at(const mr_brdf_model *model, const double *values, int p, double value, double out[2][3]) {
    double v[MR_BRDF_MAX_VALUES];
    memcpy(v, values, sizeof v);
    const int at = mr_brdf_param_offset(model, p);
    if (model->rescales != NULL) // the lobe alone: the others' reflectances must not trim it (brdf.h, rescales)
        for (int q = 0; q < model->param_count; q++)
            if (q != p && model->params[q].role == MR_PARAM_LINEAR)
                for (int c = 0; c < model->params[q].channels; c++)
                    v[mr_brdf_param_offset(model, q) + c] = model->params[q].min_value;
    for (int c = 0; c < model->params[p].channels; c++) v[at + c] = value;
    static const double n[3] = {0.0, 0.0, 1.0}, g1[3] = {0.8, 0.0, 0.6}, g2[3] = {-0.28, 0.96, 0.0};
    double g2n[3] = {g2[0], g2[1], 0.0}; // below: lifted to z = 0.3 and normalised
    const double len = sqrt(g2[0] * g2[0] + g2[1] * g2[1] + 0.09);
    for (int k = 0; k < 2; k++) g2n[k] = g2[k] / len;
    g2n[2] = 0.3 / len;
    mr_brdf_state st;
    model->prepare(model, v, st.bytes);
    model->eval(st.bytes, n, n, out[0], NULL);
    model->eval(st.bytes, g1, g2n, out[1], NULL);
}

/* The factor carrying a Lambertian parameter of the source into one of the target: f_src(1) / f_tgt(1) when both
 * are linear in f_r and direction-independent (Lambert), else 0 (no carry). */
static double lobe_ratio(const mr_brdf_model *src, const double *src_values, int sp, const mr_brdf_model *tgt,
                         const double *tgt_values, int tp) {
    double s1[2][3], s2[2][3], t1[2][3], t2[2][3];
    diffuse_at(src, src_values, sp, 0.25, s1);
    diffuse_at(src, src_values, sp, 0.5, s2);
    diffuse_at(tgt, tgt_values, tp, 0.25, t1);
    diffuse_at(tgt, tgt_values, tp, 0.5, t2);
    const double rel = 1e-9;
    for (int k = 0; k < 2; k++) // linear, and the same at both direction pairs
        if (fabs(s2[k][0] - 2.0 * s1[k][0]) > rel * s2[k][0] || fabs(t2[k][0] - 2.0 * t1[k][0]) > rel * t2[k][0])
            return 0.0;
    if (!(s1[0][0] > 0.0 && t1[0][0] > 0.0)) return 0.0;
    if (fabs(s1[1][0] - s1[0][0]) > rel * s1[0][0] || fabs(t1[1][0] - t1[0][0]) > rel * t1[0][0]) return 0.0;
    return s1[0][0] / t1[0][0];
}

/* ---- methods ---------------------------------------------------------------------------------------------- */

/* What an output learns in one row: the target's value less what a carry into the same parameter gives (GREY: the
 * channel means). */
static double output_value(const mr_learned *t, const mr_learned_slot *s, const double *sv, const double *tv) {
    double v = slot_value(t->target, s, tv);
    for (int i = 0; i < t->carry_count; i++) {
        const mr_learned_carry *c = &t->carries[i];
        if (c->target_param != s->param) continue;
        const int from = mr_brdf_param_offset(t->source, c->source_param);
        if (s->kind == MR_LEARNED_GREY)
            v -= (c->factor[0] * sv[from] + c->factor[1] * sv[from + 1] + c->factor[2] * sv[from + 2]) / 3.0;
        else
            v -= c->factor[s->kind == MR_LEARNED_CHANNEL ? s->channel : 0] *
                 sv[from + (s->kind == MR_LEARNED_CHANNEL ? s->channel : 0)];
    }
    return v;
}

/* Rows `idx[0..m)` as feature and output matrices (outputs GREY: channel mean). */
static void gather(const mr_sweep_table *tab, const mr_learned *t, const size_t *idx, size_t m, double *x, double *y) {
    for (size_t r = 0; r < m; r++) {
        const double *sv = tab->source_values + idx[r] * (size_t)tab->source_count;
        const double *tv = tab->target_values + idx[r] * (size_t)tab->target_count;
        for (int i = 0; i < t->feature_count; i++)
            x[r * t->feature_count + i] = slot_value(t->source, &t->features[i], sv);
        for (int j = 0; j < t->output_count; j++) y[r * t->output_count + j] = output_value(t, &t->outputs[j], sv, tv);
    }
}

static mr_status fit_parametric(const mr_sweep_table *tab, mr_learned *t, const size_t *idx, size_t m,
                                const mr_learn_options *o, int with_inverse) {
    double *alpha = malloc(m * sizeof *alpha), *alpha2 = malloc(m * sizeof *alpha2);
    double *ss = malloc(3 * m * sizeof *ss), *st = malloc(3 * m * sizeof *st);
    mr_status status = alpha && alpha2 && ss && st ? MR_OK : mr_fail(MR_ERR_NOMEM, "learn: out of memory");
    const int s_at = mr_brdf_param_offset(t->source, t->features[1].param);
    const int t_at = mr_brdf_param_offset(t->target, t->outputs[1].param);
    const int s_ch = t->source->params[t->features[1].param].channels;
    const int t_ch = t->target->params[t->outputs[1].param].channels;
    for (size_t r = 0; status == MR_OK && r < m; r++) {
        const double *sv = tab->source_values + idx[r] * (size_t)tab->source_count;
        const double *tv = tab->target_values + idx[r] * (size_t)tab->target_count;
        alpha[r] = slot_value(t->source, &t->features[0], sv);
        alpha2[r] = slot_value(t->target, &t->outputs[0], tv);
        for (int c = 0; c < 3; c++) {
            ss[3 * r + c] = sv[s_at + (s_ch == 3 ? c : 0)];
            // a one-channel target specular learns from the mean of a coloured source (what apply feeds it)
            st[3 * r + c] = tv[t_at + (t_ch == 3 ? c : 0)];
            if (t_ch == 1 && s_ch == 3) ss[3 * r + c] = (sv[s_at] + sv[s_at + 1] + sv[s_at + 2]) / 3.0;
        }
    }
    if (status == MR_OK)
        status = mr_fit_polynomial_ex(alpha, alpha2, m, t->roughness_degree, t->roughness_origin, t->roughness, NULL);
    if (status == MR_OK) status = mr_fit_specular_slope(alpha, ss, st, m, with_inverse, &t->slope);
    if (status == MR_OK && t->output_count == 3) { // the diffuse the fits add: k_d(alpha) s, the carry removed
        // Rows whose fitted diffuse sits on its lower bound are left out: there the fit wanted less than the range
        // allows (a diffuse taking back what a wider target lobe adds, from a source diffuse smaller than that),
        // so the row shows a bound, not the slope (keeping them bends k_d toward 0 everywhere).
        // (Unless too few are off it to fit the slope's five coefficients well: then every row.)
        const mr_brdf_param *q = &t->target->params[t->outputs[2].param];
        double floor_value = q->min_value + 1e-9 * (q->max_value - q->min_value);
        size_t off_bound = 0;
        for (size_t r = 0; r < m; r++) {
            const double *tv = tab->target_values + idx[r] * (size_t)tab->target_count;
            off_bound += slot_value(t->target, &t->outputs[2], tv) > floor_value;
        }
        if (off_bound < MIN_ROWS) floor_value = -INFINITY;
        size_t kept = 0;
        for (size_t r = 0; r < m; r++) {
            const double *sv = tab->source_values + idx[r] * (size_t)tab->source_count;
            const double *tv = tab->target_values + idx[r] * (size_t)tab->target_count;
            if (slot_value(t->target, &t->outputs[2], tv) <= floor_value) continue;
            const double d = output_value(t, &t->outputs[2], sv, tv);
            alpha[kept] = alpha[r];
            for (int c = 0; c < 3; c++) {
                st[3 * kept + c] = d;
                // per channel: the grey rows make d the same in each, against each channel's specular
                ss[3 * kept + c] = s_ch == 3 ? sv[s_at + c] : ss[3 * r + c];
            }
            kept++;
        }
        status = mr_fit_specular_slope(alpha, ss, st, kept, with_inverse, &t->diffuse_slope);
    }
    (void)o;
    free(alpha);
    free(alpha2);
    free(ss);
    free(st);
    return status == MR_OK ? MR_OK : mr_fail_context(status, "learn parametric");
}

static mr_status fit_svr(const mr_sweep_table *tab, mr_learned *t, const size_t *idx, size_t m,
                         const mr_learn_options *o) {
    double *x = malloc(m * (size_t)t->feature_count * sizeof *x), *y = malloc(m * (size_t)t->output_count * sizeof *y);
    if (x == NULL || y == NULL) {
        free(x);
        free(y);
        return mr_fail(MR_ERR_NOMEM, "learn: out of memory");
    }
    gather(tab, t, idx, m, x, y);
    mr_svr_train_options so = {0};
    so.seed = t->seed;
    so.threads = o->threads;
    so.C = o->svr_C;
    so.gamma = o->svr_gamma;
    so.epsilon = o->svr_epsilon;
    mr_svr_free(t->svr);
    t->svr = NULL;
    mr_status status = mr_svr_train(x, y, m, t->feature_count, t->output_count, &so, &t->svr, NULL);
    free(x);
    free(y);
    return status == MR_OK ? MR_OK : mr_fail_context(status, "learn svr");
}

static mr_status fit_mlp(const mr_sweep_table *tab, mr_learned *t, const size_t *idx, size_t m,
                         const mr_learn_options *o) {
    double *x = malloc(m * (size_t)t->feature_count * sizeof *x), *y = malloc(m * (size_t)t->output_count * sizeof *y);
    float *xf = malloc(m * (size_t)t->feature_count * sizeof *xf),
          *yf = malloc(m * (size_t)t->output_count * sizeof *yf);
    mr_status status = x && y && xf && yf ? MR_OK : mr_fail(MR_ERR_NOMEM, "learn: out of memory");
    if (status == MR_OK) {
        gather(tab, t, idx, m, x, y);
        for (size_t k = 0; k < m * (size_t)t->feature_count; k++) xf[k] = (float)x[k];
        for (size_t k = 0; k < m * (size_t)t->output_count; k++) yf[k] = (float)y[k];
        mr_mlp_train_options mo = {0};
        mo.n_hidden = o->mlp_hidden > 0 ? o->mlp_hidden : DEFAULT_HIDDEN;
        mo.max_epochs = o->mlp_max_epochs > 0 ? o->mlp_max_epochs : DEFAULT_EPOCHS;
        // Sweeps are small (tens to thousands of rows): small batches, a larger step and a long patience let the
        // network settle (measured on ward -> ggx, 60 rows: held-out f0 RMSE 0.0036, against 0.0059 with
        // batch 32, rate 1e-3 and patience 100).
        mo.patience = 500;
        mo.batch_size = 16;
        mo.validation_fraction = 0.2;
        mo.learning_rate = 0.003;
        mo.seed = t->seed;
        mo.threads = o->threads;
        mr_mlp_free(t->mlp);
        t->mlp = NULL;
        status = mr_mlp_train(xf, yf, m, t->feature_count, t->output_count, &mo, &t->mlp, NULL);
        if (status != MR_OK) status = mr_fail_context(status, "learn mlp");
    }
    free(x);
    free(y);
    free(xf);
    free(yf);
    return status;
}

static mr_status fit(const mr_sweep_table *tab, mr_learned *t, const size_t *idx, size_t m, const mr_learn_options *o,
                     int with_inverse) {
    switch (t->method) {
    case MR_LEARN_PARAMETRIC: return fit_parametric(tab, t, idx, m, o, with_inverse);
    case MR_LEARN_SVR: return fit_svr(tab, t, idx, m, o);
    default: return fit_mlp(tab, t, idx, m, o);
    }
}

/* Each output's RMSE over rows idx[0..m) through the whole transform (carries, clamps and all); GREY outputs over
 * their three channels. Learned carries are refitted by the caller before this. */
static mr_status measure(const mr_sweep_table *tab, const mr_learned *t, const size_t *idx, size_t m, double *rmse) {
    const size_t sc = (size_t)tab->source_count, tc = (size_t)tab->target_count;
    double *in = malloc(m * sc * sizeof *in), *out = malloc(m * tc * sizeof *out);
    mr_status status = in && out ? MR_OK : mr_fail(MR_ERR_NOMEM, "learn: out of memory");
    for (size_t r = 0; status == MR_OK && r < m; r++)
        memcpy(in + r * sc, tab->source_values + idx[r] * sc, sc * sizeof *in);
    if (status == MR_OK) status = mr_learned_apply_batch(t, m, in, out, NULL);
    double sum[MR_LEARNED_MAX_SLOTS] = {0};
    long count[MR_LEARNED_MAX_SLOTS] = {0};
    for (size_t r = 0; status == MR_OK && r < m; r++) {
        const double *tv = tab->target_values + idx[r] * tc, *w = out + r * tc;
        for (int j = 0; j < t->output_count; j++) {
            const mr_learned_slot *s = &t->outputs[j];
            const int at = mr_brdf_param_offset(t->target, s->param) + (s->kind == MR_LEARNED_CHANNEL ? s->channel : 0);
            for (int c = 0; c < (s->kind == MR_LEARNED_GREY ? 3 : 1); c++) {
                const double d = w[at + c] - tv[at + c];
                sum[j] += d * d;
                count[j]++;
            }
        }
    }
    for (int j = 0; j < t->output_count; j++) rmse[j] = count[j] ? sqrt(sum[j] / (double)count[j]) : 0.0;
    free(in);
    free(out);
    return status;
}

static int is_roughness(const mr_brdf_param *p);

/* ---- the check against the remaps (learned.h, mr_learned_check) ---------------------------------------------- */

static int compare_doubles(const void *a, const void *b) {
    const double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* The q-quantile of v[0..n) (sorted in place; nearest rank), 0 for n = 0. */
static double quantile(double *v, size_t n, double q) {
    if (n == 0) return 0.0;
    qsort(v, n, sizeof *v, compare_doubles);
    size_t k = (size_t)ceil(q * (double)n);
    return v[k > 0 ? k - 1 : 0];
}

/* dSSIM of rows idx[0..m) (at most MR_LEARNED_CHECK_MAX_RENDERS of them) into d[], their count into *n: the row's
 * own SSIM less the SSIM of the learned answer w (rows of the target's packed values) to the source's render, in
 * the rows' fit scene. MR_ERR_FORMAT when the scene line is not one this version renders (the caller reports NaN). */
static mr_status check_renders(const mr_sweep_table *tab, const mr_learned *t, const size_t *idx, size_t m,
                               const double *w, double *d, size_t *n) {
    mr_fit_scene_options fit;
    *n = 0;
    mr_status status = mr_sweep_scene_parse(tab->scene, &fit);
    if (status != MR_OK) return status;
    mr_scene scene = mr_remap_file_scene(&fit);
    mr_render_plan *plan = NULL;
    status = mr_render_plan_create(&scene, &plan);
    const size_t count = m < MR_LEARNED_CHECK_MAX_RENDERS ? m : MR_LEARNED_CHECK_MAX_RENDERS;
    for (size_t r = 0; status == MR_OK && r < count; r++) {
        mr_image *source = NULL, *learned = NULL;
        double ssim = 0.0;
        status = mr_render(plan, t->source, tab->source_values + idx[r] * (size_t)tab->source_count,
                           MR_COMPONENT_FULL, &source);
        if (status == MR_OK)
            status = mr_render(plan, t->target, w + r * (size_t)tab->target_count, MR_COMPONENT_FULL, &learned);
        if (status == MR_OK) status = mr_ssim(learned, source, NULL, &ssim, NULL);
        if (status == MR_OK) d[(*n)++] = tab->ssim[idx[r]] - ssim;
        mr_image_free(source);
        mr_image_free(learned);
    }
    mr_render_plan_free(plan);
    return status;
}

/* t's check on the held-out rows idx[0..m): see learned.h. */
static mr_status check(const mr_sweep_table *tab, const mr_learned *t, const size_t *idx, size_t m,
                       mr_learned_check *out) {
    const size_t sc = (size_t)tab->source_count, tc = (size_t)tab->target_count;
    double *in = malloc(m * sc * sizeof *in), *w = malloc(m * tc * sizeof *w);
    double *rel = malloc(3 * m * sizeof *rel), *d = malloc(m * sizeof *d);
    mr_status status = in && w && rel && d ? MR_OK : mr_fail(MR_ERR_NOMEM, "learn: out of memory");
    for (size_t r = 0; status == MR_OK && r < m; r++)
        memcpy(in + r * sc, tab->source_values + idx[r] * sc, sc * sizeof *in);
    if (status == MR_OK) status = mr_learned_apply_batch(t, m, in, w, NULL);
    memset(out, 0, sizeof *out);
    out->passed = 1;
    for (int j = 0; status == MR_OK && j < t->output_count; j++) {
        const mr_learned_slot *s = &t->outputs[j];
        const mr_brdf_param *q = &t->target->params[s->param];
        const int at = mr_brdf_param_offset(t->target, s->param) + (s->kind == MR_LEARNED_CHANNEL ? s->channel : 0);
        const double floor_value = MR_LEARNED_CHECK_FLOOR * fmin(1.0, q->max_value - q->min_value);
        size_t n = 0;
        for (size_t r = 0; r < m; r++) {
            if (is_roughness(q) && tab->outcome[idx[r]] == MR_FIT_UNDER_RESOLVED) continue; // only bounded
            const double *tv = tab->target_values + idx[r] * tc;
            for (int c = 0; c < (s->kind == MR_LEARNED_GREY ? 3 : 1); c++)
                rel[n++] = fabs(w[r * tc + (size_t)(at + c)] - tv[at + c]) / fmax(fabs(tv[at + c]), floor_value);
        }
        out->relative_p90[j] = quantile(rel, n, 0.9);
        out->relative_median[j] = quantile(rel, n, 0.5);
        if (out->relative_p90[j] > MR_LEARNED_MAX_RELATIVE_ERROR) out->passed = 0;
    }
    size_t n = 0;
    if (status == MR_OK) {
        mr_status rendered = check_renders(tab, t, idx, m, w, d, &n);
        if (rendered == MR_ERR_NOMEM) status = rendered;
        if (rendered != MR_OK) n = 0;
    }
    if (status == MR_OK) {
        double sum = 0.0;
        for (size_t r = 0; r < n; r++) sum += d[r];
        out->dssim_mean = n ? sum / (double)n : NAN;
        out->dssim_p90 = n ? quantile(d, n, 0.9) : NAN;
        if (n && out->dssim_p90 > MR_LEARNED_MAX_DSSIM) out->passed = 0;
        out->rows = (long)m;
        out->done = m > 0;
        if (!out->done) out->passed = 0;
    }
    free(in);
    free(w);
    free(rel);
    free(d);
    return status;
}

/* Learned carries: per-channel slopes through the origin over rows idx[0..m). */
static void fit_carries(const mr_sweep_table *tab, mr_learned *t, const size_t *idx, size_t m) {
    for (int i = 0; i < t->carry_count; i++) {
        mr_learned_carry *c = &t->carries[i];
        if (!c->learned) continue;
        const int to = mr_brdf_param_offset(t->target, c->target_param);
        const int from = mr_brdf_param_offset(t->source, c->source_param);
        for (int ch = 0; ch < t->target->params[c->target_param].channels; ch++) {
            double sxy = 0.0, sxx = 0.0;
            for (size_t r = 0; r < m; r++) {
                const double xv = tab->source_values[idx[r] * (size_t)tab->source_count + (size_t)(from + ch)];
                const double yv = tab->target_values[idx[r] * (size_t)tab->target_count + (size_t)(to + ch)];
                sxy += xv * yv;
                sxx += xv * xv;
            }
            c->factor[ch] = sxx > 0.0 ? sxy / sxx : 1.0;
        }
    }
}

/* ---- roles ------------------------------------------------------------------------------------------------ */

static int is_roughness(const mr_brdf_param *p) {
    return p->channels == 1 && p->role == MR_PARAM_NONLINEAR && (p->lobe & MR_LOBE_SPECULAR);
}
static int is_linear(const mr_brdf_param *p) { return p->role == MR_PARAM_LINEAR || p->role == MR_PARAM_AFFINE; }

/* Decide features, outputs, carries and base values from how the rows use each parameter. */
static mr_status plan(const mr_sweep_table *tab, mr_learned *t) {
    const mr_brdf_model *src = tab->source, *tgt = tab->target;
    param_use su[MR_BRDF_MAX_VALUES], tu[MR_BRDF_MAX_VALUES];
    for (int p = 0; p < src->param_count; p++)
        su[p] = use_of(tab->source_values, tab->n, tab->source_count, mr_brdf_param_offset(src, p),
                       src->params[p].channels, 0.0);
    for (int p = 0; p < tgt->param_count; p++)
        tu[p] = use_of(tab->target_values, tab->n, tab->target_count, mr_brdf_param_offset(tgt, p),
                       tgt->params[p].channels, TARGET_NOISE * (tgt->params[p].max_value - tgt->params[p].min_value));
    memcpy(t->base, tab->target_values, (size_t)tab->target_count * sizeof *t->base);
    // carried[tp]: 1 the target parameter is a carry alone; 2 a carry plus a learned residual (an output).
    int carried[MR_BRDF_MAX_VALUES] = {0}, used_source[MR_BRDF_MAX_VALUES] = {0};
    // Ties (the sweep held these target parameters at a source parameter's value, brdf.h): carried with factor 1,
    // not learned; the source parameter stays a feature of the regression for the other outputs.
    for (int tp = 0; tp < tgt->param_count && tp < 32; tp++) {
        if (!((tab->target_ties.tied >> tp) & 1u)) continue;
        const int sp = tab->target_ties.source[tp];
        t->carries[t->carry_count++] = (mr_learned_carry){tp, sp, 0, {1.0, 1.0, 1.0}};
        carried[tp] = 1;
        mr_status status = note(t, "target %s is tied to source %s (the sweep's tie): carried as it is",
                                tgt->params[tp].name, src->params[sp].name);
        if (status != MR_OK) return status;
    }
    // Carries: a Lambertian target parameter from a Lambertian source parameter. A source held in the rows is carried
    // by the lobes' ratio, and what the fits still put into the target (a diffuse that stands in for a lobe's tail)
    // is learned on top as an output; a source the rows vary is carried by a fitted slope under the parametric
    // method (the other methods take it as a feature).
    for (int tp = 0; tp < tgt->param_count; tp++) {
        const mr_brdf_param *q = &tgt->params[tp];
        if (q->lobe != MR_LOBE_DIFFUSE || q->role != MR_PARAM_LINEAR) continue;
        if (carried[tp]) continue; // tied
        for (int sp = 0; sp < src->param_count; sp++) {
            const mr_brdf_param *p = &src->params[sp];
            if (p->lobe != MR_LOBE_DIFFUSE || p->role != MR_PARAM_LINEAR || p->channels != q->channels) continue;
            if (used_source[sp]) continue;
            mr_learned_carry c = {tp, sp, 0, {1.0, 1.0, 1.0}};
            const double ratio = lobe_ratio(src, tab->source_values, sp, tgt, tab->target_values, tp);
            if (su[sp].varies && t->method != MR_LEARN_PARAMETRIC) continue; // a feature of the regression
            if (ratio > 0.0) {
                for (int ch = 0; ch < 3; ch++) c.factor[ch] = ratio;
            } else if (su[sp].varies && tu[tp].varies) {
                c.learned = 1;
            } else {
                continue;
            }
            t->carries[t->carry_count++] = c;
            carried[tp] = !c.learned && tu[tp].varies ? 2 : 1;
            used_source[sp] = 1;
            break;
        }
    }
    for (int tp = 0; tp < tgt->param_count; tp++) {
        const mr_brdf_param *q = &tgt->params[tp];
        // A parameter the sweep held (its --hold, in the header) is constant by choice: written as the held value
        // without a note, as the model's default holds are.
        if (!tu[tp].varies && !carried[tp] && mr_brdf_hold_reason(tgt, tab->target_held, tp) == MR_HOLD_FITTED) {
            char value[64];
            snprintf(value, sizeof value, "%g", t->base[mr_brdf_param_offset(tgt, tp)]);
            mr_status status = note(t, "target %s is %s in every row: written as that constant (vary it in the sweep "
                                    "to learn it)", q->name, value);
            if (status != MR_OK) return status;
        }
    }
    if (t->method == MR_LEARN_PARAMETRIC) {
        int rough = -1, spec = -1;
        for (int p = 0; p < src->param_count; p++) {
            if (!su[p].varies || used_source[p]) continue;
            const mr_brdf_param *q = &src->params[p];
            if (is_roughness(q) && rough < 0) {
                rough = p;
            } else if ((q->lobe & MR_LOBE_SPECULAR) && q->role == MR_PARAM_NONLINEAR && spec < 0 && q->channels == 1 &&
                       rough >= 0) {
                return mr_fail(MR_ERR_INVALID_ARG, "parametric: the source's specular parameter %s %s is not linear "
                               "in f_r (an index of refraction?): the paper changes variable first (its Eq. 1, "
                               "F0 = ((ior - 1) / (ior + 1))^2); use svr or mlp, or sweep an F0-parameterised model",
                               src->name, q->name);
            } else if ((q->lobe & MR_LOBE_SPECULAR) && is_linear(q) && spec < 0) {
                spec = p;
            } else {
                return mr_fail(MR_ERR_INVALID_ARG, "parametric: the rows vary the source's %s %s, which is neither "
                               "its roughness nor its specular reflectance: the paper's parametric form does not "
                               "cover it (use svr or mlp, or hold it in the sweep)", src->name, q->name);
            }
        }
        int trough = -1, tspec = -1, tdiff = -1;
        for (int p = 0; p < tgt->param_count; p++) {
            if (!tu[p].varies || carried[p] == 1) continue;
            const mr_brdf_param *q = &tgt->params[p];
            if (carried[p] == 2 && tdiff < 0) tdiff = p;
            else if (is_roughness(q) && trough < 0) trough = p;
            else if ((q->lobe & MR_LOBE_SPECULAR) && is_linear(q) && tspec < 0) tspec = p;
            else
                return mr_fail(MR_ERR_INVALID_ARG, "parametric: the fitted target %s %s varies over the rows, but the "
                               "parametric form writes only a roughness and a specular reflectance (use svr or mlp)",
                               tgt->name, q->name);
        }
        if (rough < 0 || spec < 0 || trough < 0 || tspec < 0)
            return mr_fail(MR_ERR_INVALID_ARG, "parametric: needs rows that vary the source's roughness and specular "
                           "reflectance (%s%s) and a target roughness and specular that follow (%s%s)",
                           rough < 0 ? "no roughness varies" : "roughness ok",
                           spec < 0 ? ", no specular varies" : ", specular ok",
                           trough < 0 ? "no target roughness varies" : "target roughness ok",
                           tspec < 0 ? ", no target specular varies" : ", target specular ok");
        t->features[0] = (mr_learned_slot){rough, MR_LEARNED_SCALAR, 0, 0.0, 0.0};
        t->features[1] = (mr_learned_slot){spec, src->params[spec].channels == 3 ? MR_LEARNED_GREY : MR_LEARNED_SCALAR,
                                           0, 0.0, 0.0};
        t->outputs[0] = (mr_learned_slot){trough, MR_LEARNED_SCALAR, 0, 0.0, 0.0};
        t->outputs[1] = (mr_learned_slot){tspec, tgt->params[tspec].channels == 3 ? MR_LEARNED_GREY : MR_LEARNED_SCALAR,
                                          0, 0.0, 0.0};
        t->feature_count = t->output_count = 2;
        if (tdiff >= 0) // the diffuse the fits add, linear in the specular: k_d(alpha) s (a second slope)
            t->outputs[t->output_count++] =
                (mr_learned_slot){tdiff, tgt->params[tdiff].channels == 3 ? MR_LEARNED_GREY : MR_LEARNED_SCALAR, 0,
                                  0.0, 0.0};
    } else {
        for (int p = 0; p < src->param_count; p++)
            if (su[p].varies && !used_source[p]) add_slot(t->features, &t->feature_count, p, src->params[p].channels,
                                                          su[p].grey);
        for (int p = 0; p < tgt->param_count; p++)
            if (tu[p].varies && carried[p] != 1) add_slot(t->outputs, &t->output_count, p, tgt->params[p].channels,
                                                      tu[p].grey);
        if (t->feature_count == 0 || t->output_count == 0)
            return mr_fail(MR_ERR_INVALID_ARG, "learn: the rows vary %s: nothing to learn",
                           t->feature_count == 0 ? "no source parameter" : "no fitted target parameter");
    }
    // Training domains: over every row (GREY: every channel).
    for (int i = 0; i < t->feature_count; i++) {
        mr_learned_slot *s = &t->features[i];
        const int at = mr_brdf_param_offset(src, s->param) + (s->kind == MR_LEARNED_CHANNEL ? s->channel : 0);
        const int channels = s->kind == MR_LEARNED_GREY ? 3 : 1;
        s->min = INFINITY;
        s->max = -INFINITY;
        for (size_t r = 0; r < tab->n; r++)
            for (int c = 0; c < channels; c++) {
                const double v = tab->source_values[r * (size_t)tab->source_count + (size_t)(at + c)];
                s->min = fmin(s->min, v);
                s->max = fmax(s->max, v);
            }
    }
    return MR_OK;
}

mr_status mr_learn(const mr_sweep_table *tab, const mr_learn_options *opts, mr_learned **out) {
    if (tab == NULL || out == NULL || tab->source == NULL) return mr_fail(MR_ERR_INVALID_ARG, "learn: NULL argument");
    mr_learn_options o = opts ? *opts : (mr_learn_options){0};
    if (o.validation_fraction == 0.0) o.validation_fraction = DEFAULT_VALIDATION;
    if (o.seed == 0) o.seed = 1;
    if (o.roughness_degree == 0) o.roughness_degree = DEFAULT_DEGREE;
    if ((unsigned)o.method >= MR_LEARN_METHOD_COUNT)
        return mr_fail(MR_ERR_INVALID_ARG, "learn: method %d: unknown", (int)o.method);
    if (!(o.validation_fraction > 0.0 && o.validation_fraction <= 0.5))
        return mr_fail(MR_ERR_INVALID_ARG, "learn: validation fraction %g: expected (0, 0.5]", o.validation_fraction);
    if (o.roughness_degree < 1 || o.roughness_degree > MR_POLY_MAX_DEGREE)
        return mr_fail(MR_ERR_INVALID_ARG, "learn: roughness degree %d: expected 1 .. %d", o.roughness_degree,
                       MR_POLY_MAX_DEGREE);
    if (o.slope_inverse < -1 || o.slope_inverse > 1)
        return mr_fail(MR_ERR_INVALID_ARG, "learn: slope_inverse %d: expected -1, 0 or 1", o.slope_inverse);
    if (o.threads < 0 || o.mlp_hidden < 0 || o.mlp_max_epochs < 0)
        return mr_fail(MR_ERR_INVALID_ARG, "learn: negative threads, hidden units or epochs");
    if (!(o.svr_C >= 0.0 && o.svr_gamma >= 0.0 && o.svr_epsilon >= 0.0 && isfinite(o.svr_C) &&
          isfinite(o.svr_gamma) && isfinite(o.svr_epsilon)))
        return mr_fail(MR_ERR_INVALID_ARG, "learn: svr C %g, gamma %g, epsilon %g: expected 0 (searched) or > 0",
                       o.svr_C, o.svr_gamma, o.svr_epsilon);
    if (tab->n < MIN_ROWS)
        return mr_fail(MR_ERR_INVALID_ARG, "learn: %zu rows; at least %d are needed (a validation split is held out)",
                       tab->n, MIN_ROWS);
    mr_learned *t = calloc(1, sizeof *t);
    if (t == NULL) return mr_fail(MR_ERR_NOMEM, "learn: out of memory");
    t->source = tab->source;
    t->target = tab->target;
    t->method = o.method;
    t->validation_fraction = o.validation_fraction;
    t->seed = o.seed;
    t->roughness_degree = o.roughness_degree;
    t->roughness_origin = !o.roughness_intercept;
    if (tab->provenance != NULL) {
        t->provenance = strdup(tab->provenance);
        if (t->provenance == NULL) {
            free(t);
            return mr_fail(MR_ERR_NOMEM, "learn: out of memory");
        }
    }
    mr_status status = plan(tab, t);
    size_t *order = status == MR_OK ? shuffled(tab->n, o.seed) : NULL;
    if (status == MR_OK && order == NULL) status = mr_fail(MR_ERR_NOMEM, "learn: out of memory");
    size_t n_val = (size_t)llround(o.validation_fraction * (double)tab->n);
    if (n_val < 1) n_val = 1;
    const size_t n_train = tab->n - n_val;
    t->train_rows = (long)n_train;
    t->validation_rows = (long)n_val;
    if (o.progress) o.progress("fit", 0.0, o.progress_user);
    // Fit on the training rows; measure on the held-out ones. PARAMETRIC with slope_inverse 0 tries both forms.
    int inverse = o.slope_inverse > 0;
    if (status == MR_OK) {
        fit_carries(tab, t, order + n_val, n_train);
        status = fit(tab, t, order + n_val, n_train, &o, inverse);
        if (status == MR_OK) status = measure(tab, t, order, n_val, t->rmse);
    }
    int checked = 0;
    if (status == MR_OK && t->method == MR_LEARN_PARAMETRIC && o.slope_inverse == 0) {
        mr_learned trial = *t;
        trial.svr = NULL;
        trial.mlp = NULL;
        double rmse[MR_LEARNED_MAX_SLOTS];
        if (fit(tab, &trial, order + n_val, n_train, &o, 1) == MR_OK &&
            measure(tab, &trial, order, n_val, rmse) == MR_OK) {
            if (rmse[1] < 0.99 * t->rmse[1]) { // clearly better held-out specular: keep the c5 / alpha term
                inverse = 1;
                memcpy(t->rmse, rmse, sizeof rmse);
                status = check(tab, &trial, order, n_val, &t->check);
                checked = 1;
            }
        }
        if (status != MR_ERR_NOMEM) status = MR_OK;
    }
    // The check runs on the transform fitted without the held-out rows, which thus test it fairly; the one
    // returned is refitted on every row below.
    if (status == MR_OK && !checked) status = check(tab, t, order, n_val, &t->check);
    if (o.progress) o.progress("fit", 0.5, o.progress_user);
    // The transform returned: refitted on every row (the MLP keeps its early-stopped network).
    if (status == MR_OK && t->method != MR_LEARN_MLP) {
        fit_carries(tab, t, order, tab->n);
        status = fit(tab, t, order, tab->n, &o, inverse);
    }
    if (o.progress) o.progress("fit", 1.0, o.progress_user);
    free(order);
    if (status != MR_OK) {
        mr_learned_free(t);
        return status;
    }
    *out = t;
    return MR_OK;
}
