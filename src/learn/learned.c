/*
 * learned.c — applying learned transforms and chains of them (contract in learned.h). Training is learn.c, the
 * file learned_file.c.
 */
#include "learn/learned.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "learn/svr.h"
#include "mr_internal.h"
#include "nn/mlp.h"
#include "remap/direct.h"
#include "workflow/workflow.h"

static const char *const method_names[MR_LEARN_METHOD_COUNT] = {"parametric", "svr", "mlp"};

static const mr_flag_colour learned_colours[] = {
    {MR_WF_EXTRAPOLATED | MR_WF_UNCONVERGED | MR_WF_UNCHECKED, {1.0f, 0.0f, 0.0f}}, /* red */
    {MR_WF_CLAMPED_OUTPUT, {0.0f, 1.0f, 0.0f}},                                     /* green */
    {MR_WF_CLAMPED_INPUT | MR_WF_NONFINITE_INPUT, {0.0f, 0.0f, 1.0f}},              /* blue */
};
const mr_flag_code mr_learned_flag_code = {MR_FLAG_PAINT_EACH,
                                           (int)(sizeof learned_colours / sizeof learned_colours[0]),
                                           learned_colours};

const char *mr_learn_method_name(mr_learn_method method) {
    return (unsigned)method < MR_LEARN_METHOD_COUNT ? method_names[method] : NULL;
}

const char *mr_learned_slot_name(const mr_brdf_model *model, const mr_learned_slot *slot, char *buf, size_t size) {
    static const char *const suffix[3] = {"_r", "_g", "_b"};
    if (buf == NULL || size == 0) return buf;
    const int channel = slot->kind == MR_LEARNED_CHANNEL && slot->channel >= 0 && slot->channel < 3 ? slot->channel
                                                                                                      : -1;
    snprintf(buf, size, "%s%s", model->params[slot->param].name, channel >= 0 ? suffix[channel] : "");
    return buf;
}

mr_status mr_learn_method_from_name(const char *name, mr_learn_method *out) {
    for (int m = 0; name != NULL && m < MR_LEARN_METHOD_COUNT; m++)
        if (strcmp(name, method_names[m]) == 0) {
            *out = (mr_learn_method)m;
            return MR_OK;
        }
    return mr_fail(MR_ERR_INVALID_ARG, "method '%s': unknown (valid: parametric, svr, mlp)", name ? name : "(null)");
}

/* The packed slot of a slot's first channel in its model. */
static int slot_offset(const mr_brdf_model *model, const mr_learned_slot *s) {
    return mr_brdf_param_offset(model, s->param) + (s->kind == MR_LEARNED_CHANNEL ? s->channel : 0);
}

/* The regression alone on `rows` rows: features x[rows][feature_count] -> outputs y[rows][output_count]. Runs on
 * the calling thread (the texture-set conversion spreads blocks over threads). xf/yf: float scratch of the same
 * sizes for the network. */
static mr_status regress(const mr_learned *t, const double *x, size_t rows, double *y, float *xf, float *yf) {
    const size_t F = (size_t)t->feature_count, O = (size_t)t->output_count;
    switch (t->method) {
    case MR_LEARN_PARAMETRIC:
        for (size_t r = 0; r < rows; r++) {
            const double *xr = x + r * F;
            double *yr = y + r * O;
            yr[0] = mr_polynomial_eval(t->roughness, t->roughness_degree, xr[0]);
            yr[1] = mr_specular_slope_eval(&t->slope, xr[0]) * xr[1];
            if (O == 3) yr[2] = mr_specular_slope_eval(&t->diffuse_slope, xr[0]) * xr[1];
        }
        return MR_OK;
    case MR_LEARN_SVR:
        return mr_svr_predict_threads(t->svr, x, rows, y, 1);
    case MR_LEARN_MLP: {
        for (size_t k = 0; k < rows * F; k++) xf[k] = (float)x[k];
        mr_status status = mr_mlp_predict_threads(t->mlp, xf, rows, yf, 1);
        for (size_t k = 0; status == MR_OK && k < rows * O; k++) y[k] = yf[k];
        return status;
    }
    default:
        return mr_fail(MR_ERR_INVALID_ARG, "transform: unknown method %d", (int)t->method);
    }
}

/* Is v inside [min, max] up to rounding (the domain was measured on the same numbers, perhaps through float)? */
static int inside(double v, double min, double max) {
    const double slack = 1e-6 * (max - min) + 1e-9 * fabs(max);
    return v >= min - slack && v <= max + slack;
}

/* Is x outside [lo, hi] by more than a float's rounding? Texture maps hold floats, and a map at a parameter's
 * bound is no clamped input: (double)0.4f = 0.40000000596 lies above Blender's rms maximum 0.4. */
static int outside_range(double x, double lo, double hi) {
    return x < lo - FLT_EPSILON * fabs(lo) || x > hi + FLT_EPSILON * fabs(hi);
}

/* Texels a batch handles at once, and the scratch they need: per texel its sanitised values and carries, and up to
 * 4 regression rows (the channel means, then each channel of a coloured texel whose features include GREY ones). */
#define CHUNK 256
#define MAXV MR_BRDF_MAX_VALUES
#define MAXS MR_LEARNED_MAX_SLOTS
typedef struct apply_work {
    double *v, *carry; /* [texel][MAXV] */
    double *x, *y;     /* [4 texels][MAXS] */
    float *xf, *yf;
    int *coloured;     /* [texel] */
    void *block;
} apply_work;

/* Scratch for m <= CHUNK texels in one block. */
static int apply_work_alloc(apply_work *wk, size_t m) {
    const size_t doubles = 2 * m * MAXV + 8 * m * MAXS, floats = 8 * m * MAXS;
    wk->block = malloc(doubles * sizeof(double) + floats * sizeof(float) + m * sizeof(int));
    if (wk->block == NULL) return 0;
    double *d = wk->block;
    wk->v = d;
    wk->carry = d + m * MAXV;
    wk->x = d + 2 * m * MAXV;
    wk->y = wk->x + 4 * m * MAXS;
    wk->xf = (float *)(d + doubles);
    wk->yf = wk->xf + 4 * m * MAXS;
    wk->coloured = (int *)(wk->xf + floats);
    return 1;
}

/* Texels [0, n) (n <= CHUNK) of packed source rows `in` into packed target rows `out`. */
static mr_status apply_chunk(const mr_learned *t, size_t n, const double *in, double *out, unsigned *flags,
                             apply_work *wk) {
    const mr_brdf_model *src = t->source, *tgt = t->target;
    const int sc = mr_brdf_value_count(src), tc = mr_brdf_value_count(tgt);
    const size_t F = (size_t)t->feature_count, O = (size_t)t->output_count;
    int grey = 0, carried[MR_BRDF_MAX_VALUES] = {0};
    for (int i = 0; i < t->feature_count; i++) grey |= t->features[i].kind == MR_LEARNED_GREY;
    for (int i = 0; i < t->carry_count; i++) carried[t->carries[i].target_param] = 1;
    size_t rows = n; // rows 0..n-1: the channel means; then 3 per coloured texel
    for (size_t i = 0; i < n; i++) {
        unsigned f = 0;
        double *v = wk->v + i * MAXV, *w = out + i * (size_t)tc;
        for (int p = 0, k = 0; p < src->param_count; p++)
            for (int c = 0; c < src->params[p].channels; c++, k++) {
                const double lo = src->params[p].min_value, hi = src->params[p].max_value, x = in[i * (size_t)sc + k];
                if (!isfinite(x)) f |= MR_WF_NONFINITE_INPUT;
                else if (outside_range(x, lo, hi)) f |= MR_WF_CLAMPED_INPUT;
                v[k] = mr_clampd(x, lo, hi);
            }
        memcpy(w, t->base, (size_t)tc * sizeof *w);
        for (int j = 0; j < t->carry_count; j++) {
            const mr_learned_carry *c = &t->carries[j];
            const int to = mr_brdf_param_offset(tgt, c->target_param);
            const int from = mr_brdf_param_offset(src, c->source_param);
            for (int ch = 0; ch < tgt->params[c->target_param].channels; ch++)
                w[to + ch] = c->factor[ch] * v[from + ch];
        }
        memcpy(wk->carry + i * MAXV, w, (size_t)tc * sizeof *w);
        // Features: GREY ones at their channel mean (and, per channel, below), each channel checked against the domain.
        double *x = wk->x + i * F;
        int coloured = 0;
        for (int k = 0; k < t->feature_count; k++) {
            const mr_learned_slot *s = &t->features[k];
            const int at = slot_offset(src, s);
            if (s->kind == MR_LEARNED_GREY) {
                x[k] = (v[at] + v[at + 1] + v[at + 2]) / 3.0;
                coloured |= v[at] != v[at + 1] || v[at] != v[at + 2];
                for (int ch = 0; ch < 3; ch++)
                    if (!inside(v[at + ch], s->min, s->max)) f |= MR_WF_EXTRAPOLATED;
            } else {
                x[k] = v[at];
                if (!inside(x[k], s->min, s->max)) f |= MR_WF_EXTRAPOLATED;
            }
        }
        wk->coloured[i] = grey && coloured;
        if (t->check.done && !t->check.passed) f |= MR_WF_UNCHECKED;
        if (flags != NULL) flags[i] = f;
    }
    for (size_t i = 0; i < n; i++) { // per channel: channel c of the GREY features in, channel c of GREY outputs out
        if (!wk->coloured[i]) continue;
        for (int ch = 0; ch < 3; ch++, rows++)
            for (int k = 0; k < t->feature_count; k++)
                wk->x[rows * F + (size_t)k] =
                    t->features[k].kind == MR_LEARNED_GREY
                        ? wk->v[i * MAXV + (size_t)slot_offset(src, &t->features[k]) + (size_t)ch]
                        : wk->x[i * F + (size_t)k];
    }
    mr_status status = regress(t, wk->x, rows, wk->y, wk->xf, wk->yf);
    if (status != MR_OK) return status;
    // Outputs replace the base; on a carried parameter they add to the carry (the part the carry does not explain).
    size_t row = n;
    for (size_t i = 0; i < n; i++) {
        double *w = out + i * (size_t)tc;
        const double *carry = wk->carry + i * MAXV;
        for (size_t j = 0; j < O; j++) {
            const mr_learned_slot *s = &t->outputs[j];
            const int at = slot_offset(tgt, s), add = carried[s->param];
            for (int ch = 0; ch < (s->kind == MR_LEARNED_GREY ? 3 : 1); ch++) {
                const double y = s->kind == MR_LEARNED_GREY && wk->coloured[i] ? wk->y[(row + (size_t)ch) * O + j]
                                                                                : wk->y[i * O + j];
                w[at + ch] = (add ? carry[at + ch] : 0.0) + y;
            }
        }
        if (wk->coloured[i]) row += 3;
        unsigned f = 0;
        for (int p = 0, k = 0; p < tgt->param_count; p++)
            for (int c = 0; c < tgt->params[p].channels; c++, k++) {
                const double lo = tgt->params[p].min_value, hi = tgt->params[p].max_value;
                if (!(w[k] >= lo && w[k] <= hi)) {
                    f |= MR_WF_CLAMPED_OUTPUT;
                    w[k] = mr_clampd(w[k], lo, hi);
                }
            }
        if (flags != NULL) flags[i] |= f;
    }
    return MR_OK;
}

mr_status mr_learned_apply_batch(const mr_learned *t, size_t n, const double *source_values, double *target_values,
                                 unsigned *flags) {
    if (t == NULL || (n > 0 && (source_values == NULL || target_values == NULL)))
        return mr_fail(MR_ERR_INVALID_ARG, "transform: NULL argument");
    if (n == 0) return MR_OK;
    apply_work wk;
    if (!apply_work_alloc(&wk, MR_MIN(CHUNK, n))) return mr_fail(MR_ERR_NOMEM, "transform: out of memory");
    const size_t sc = (size_t)mr_brdf_value_count(t->source), tc = (size_t)mr_brdf_value_count(t->target);
    mr_status status = MR_OK;
    for (size_t start = 0; start < n && status == MR_OK; start += CHUNK)
        status = apply_chunk(t, MR_MIN(CHUNK, n - start), source_values + start * sc, target_values + start * tc,
                             flags ? flags + start : NULL, &wk);
    free(wk.block);
    return status;
}

void mr_learned_apply(const mr_learned *t, const double *source_values, double *target_values, unsigned *flags) {
    unsigned f = 0;
    if (mr_learned_apply_batch(t, 1, source_values, target_values, &f) != MR_OK) { // out of memory only
        mr_brdf_default_values(t->target, target_values);
        f = MR_WF_METHOD_FAILED;
    }
    if (flags != NULL) *flags = f;
}

mr_status mr_learned_chain_apply_batch(const mr_learned *const *t, int hops, size_t n, const double *source_values,
                                       double *target_values, unsigned *flags) {
    if (t == NULL || hops < 1 || (n > 0 && (source_values == NULL || target_values == NULL)))
        return mr_fail(MR_ERR_INVALID_ARG, "transform chain: NULL argument or no hops");
    for (int h = 1; h < hops; h++)
        if (t[h - 1]->target != t[h]->source)
            return mr_fail(MR_ERR_INVALID_ARG, "transform chain: hop %d ends in %s but hop %d starts from %s", h,
                           t[h - 1]->target->name, h + 1, t[h]->source->name);
    if (n == 0) return MR_OK;
    if (hops == 1) return mr_learned_apply_batch(t[0], n, source_values, target_values, flags);
    // Intermediate models' rows, CHUNK texels at a time, ping-ponged between two buffers.
    double *a = malloc(2 * MR_MIN(n, CHUNK) * MAXV * sizeof *a);
    unsigned *f = malloc(MR_MIN(n, CHUNK) * sizeof *f);
    mr_status status = a && f ? MR_OK : mr_fail(MR_ERR_NOMEM, "transform chain: out of memory");
    const size_t sc = (size_t)mr_brdf_value_count(t[0]->source);
    const size_t tc = (size_t)mr_brdf_value_count(t[hops - 1]->target);
    for (size_t start = 0; start < n && status == MR_OK; start += CHUNK) {
        const size_t m = MR_MIN(CHUNK, n - start);
        const double *from = source_values + start * sc;
        double *bufs[2] = {a, a + MR_MIN(n, CHUNK) * MAXV};
        for (int h = 0; h < hops && status == MR_OK; h++) {
            double *to = h == hops - 1 ? target_values + start * tc : bufs[h & 1];
            status = mr_learned_apply_batch(t[h], m, from, to, h == 0 ? (flags ? flags + start : NULL) : f);
            if (h > 0 && flags != NULL)
                for (size_t i = 0; i < m; i++) flags[start + i] |= f[i];
            from = to;
        }
    }
    free(a);
    free(f);
    return status;
}

mr_status mr_learned_chain_apply(const mr_learned *const *t, int hops, const double *source_values,
                                 double *target_values, unsigned *flags) {
    return mr_learned_chain_apply_batch(t, hops, 1, source_values, target_values, flags);
}

double mr_learned_error(const mr_learned *t) {
    double e = 0.0;
    for (int j = 0; j < t->output_count; j++) {
        const mr_brdf_param *p = &t->target->params[t->outputs[j].param];
        const double range = p->max_value - p->min_value;
        e += t->rmse[j] / (range > 0.0 ? range : 1.0);
    }
    return e;
}

void mr_learned_free(mr_learned *t) {
    if (t == NULL) return;
    mr_svr_free(t->svr);
    mr_mlp_free(t->mlp);
    free(t->provenance);
    free(t);
}

/* ---- chains ------------------------------------------------------------------------------------------------ */

/* Depth-first search over chains of at most `limit` hops from `at` that pass via[next..] in order and end in
 * `target`; keeps the best (fewest hops, then least error). */
typedef struct chain_search {
    const mr_learned *const *all;
    int n;
    const mr_brdf_model *target;
    const mr_brdf_model *const *via;
    int via_count;
    int path[MR_LEARNED_MAX_HOPS], best[MR_LEARNED_MAX_HOPS];
    int best_hops;
    double best_error;
} chain_search;

static void search(chain_search *s, const mr_brdf_model *at, int next_via, int depth, double error, int limit) {
    if (at == s->target && next_via == s->via_count && depth > 0) {
        if (depth < s->best_hops || (depth == s->best_hops && error < s->best_error)) {
            s->best_hops = depth;
            s->best_error = error;
            memcpy(s->best, s->path, (size_t)depth * sizeof *s->path);
        }
        return;
    }
    if (depth == limit) return;
    for (int i = 0; i < s->n; i++) {
        if (s->all[i]->source != at) continue;
        int used = 0; // a transform once per chain
        for (int d = 0; d < depth; d++) used |= s->path[d] == i;
        if (used) continue;
        const mr_brdf_model *to = s->all[i]->target;
        const int passes = next_via < s->via_count && to == s->via[next_via];
        s->path[depth] = i;
        search(s, to, next_via + passes, depth + 1, error + mr_learned_error(s->all[i]), limit);
    }
}

mr_status mr_learned_find_chain(const mr_learned *const *all, int n, const mr_brdf_model *source,
                                const mr_brdf_model *target, const mr_brdf_model *const *via, int via_count,
                                int *path, int *hops) {
    if ((all == NULL && n > 0) || source == NULL || target == NULL || path == NULL || hops == NULL ||
        (via == NULL && via_count > 0))
        return mr_fail(MR_ERR_INVALID_ARG, "transform chain: NULL argument");
    chain_search s = {all, n, target, via, via_count, {0}, {0}, 0, 0.0};
    // Iterative deepening: the first depth with a chain has the fewest hops.
    for (int limit = 1; limit <= MR_LEARNED_MAX_HOPS && s.best_hops == 0; limit++) {
        s.best_hops = MR_LEARNED_MAX_HOPS + 1;
        s.best_error = INFINITY;
        search(&s, source, 0, 0, 0.0, limit);
        if (s.best_hops > MR_LEARNED_MAX_HOPS) s.best_hops = 0;
    }
    if (s.best_hops == 0) {
        char pairs[1024] = "";
        for (int i = 0; i < n; i++)
            snprintf(pairs + strlen(pairs), sizeof pairs - strlen(pairs), "%s%s -> %s", i ? ", " : "",
                     all[i]->source->name, all[i]->target->name);
        return mr_fail(MR_ERR_INVALID_ARG, "no chain of transforms from %s to %s%s (of at most %d hops); the "
                       "transforms go %s", source->name, target->name, via_count ? " through the given models" : "",
                       MR_LEARNED_MAX_HOPS, n ? pairs : "nowhere (none given)");
    }
    memcpy(path, s.best, (size_t)s.best_hops * sizeof *path);
    *hops = s.best_hops;
    return MR_OK;
}
