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
#include "workflow/workflow.h"

static const char *const method_names[MR_LEARN_METHOD_COUNT] = {"parametric", "svr", "mlp"};

const char *mr_learn_method_name(mr_learn_method method) {
    return (unsigned)method < MR_LEARN_METHOD_COUNT ? method_names[method] : NULL;
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

/* The regression alone: features x[feature_count] -> outputs y[output_count]. */
static void regress(const mr_learned *t, const double *x, double *y) {
    switch (t->method) {
    case MR_LEARN_PARAMETRIC:
        y[0] = mr_polynomial_eval(t->roughness, t->roughness_degree, x[0]);
        y[1] = mr_specular_slope_eval(&t->slope, x[0]) * x[1];
        break;
    case MR_LEARN_SVR:
        mr_svr_predict(t->svr, x, 1, y);
        break;
    case MR_LEARN_MLP: {
        float in[MR_LEARNED_MAX_SLOTS], out[MR_LEARNED_MAX_SLOTS];
        for (int i = 0; i < t->feature_count; i++) in[i] = (float)x[i];
        mr_mlp_predict_threads(t->mlp, in, 1, out, 1);
        for (int j = 0; j < t->output_count; j++) y[j] = out[j];
        break;
    }
    default:
        for (int j = 0; j < t->output_count; j++) y[j] = 0.0;
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

void mr_learned_apply(const mr_learned *t, const double *source_values, double *target_values, unsigned *flags) {
    unsigned f = 0;
    const mr_brdf_model *src = t->source, *tgt = t->target;
    double v[MR_BRDF_MAX_VALUES], w[MR_BRDF_MAX_VALUES];
    for (int p = 0, k = 0; p < src->param_count; p++)
        for (int c = 0; c < src->params[p].channels; c++, k++) {
            const double lo = src->params[p].min_value, hi = src->params[p].max_value, x = source_values[k];
            if (!isfinite(x)) f |= MR_WF_NONFINITE_INPUT;
            else if (outside_range(x, lo, hi)) f |= MR_WF_CLAMPED_INPUT;
            v[k] = mr_clampd(x, lo, hi);
        }
    const int target_count = mr_brdf_value_count(tgt);
    memcpy(w, t->base, (size_t)target_count * sizeof *w);
    for (int i = 0; i < t->carry_count; i++) {
        const mr_learned_carry *c = &t->carries[i];
        const int to = mr_brdf_param_offset(tgt, c->target_param), from = mr_brdf_param_offset(src, c->source_param);
        for (int ch = 0; ch < tgt->params[c->target_param].channels; ch++) w[to + ch] = c->factor[ch] * v[from + ch];
    }
    // Features: GREY ones at their channel mean (and, per channel, below), each channel checked against the domain.
    double x[MR_LEARNED_MAX_SLOTS], y[MR_LEARNED_MAX_SLOTS];
    int grey = 0, coloured = 0;
    for (int i = 0; i < t->feature_count; i++) {
        const mr_learned_slot *s = &t->features[i];
        const int at = slot_offset(src, s);
        if (s->kind == MR_LEARNED_GREY) {
            grey = 1;
            x[i] = (v[at] + v[at + 1] + v[at + 2]) / 3.0;
            coloured |= v[at] != v[at + 1] || v[at] != v[at + 2];
            for (int ch = 0; ch < 3; ch++)
                if (!inside(v[at + ch], s->min, s->max)) f |= MR_WF_EXTRAPOLATED;
        } else {
            x[i] = v[at];
            if (!inside(x[i], s->min, s->max)) f |= MR_WF_EXTRAPOLATED;
        }
    }
    regress(t, x, y);
    for (int j = 0; j < t->output_count; j++) {
        const mr_learned_slot *s = &t->outputs[j];
        const int at = slot_offset(tgt, s);
        if (s->kind == MR_LEARNED_GREY)
            w[at] = w[at + 1] = w[at + 2] = y[j];
        else
            w[at] = y[j];
    }
    if (grey && coloured) { // per channel: channel c of the GREY features in, channel c of the GREY outputs out
        for (int ch = 0; ch < 3; ch++) {
            double xc[MR_LEARNED_MAX_SLOTS], yc[MR_LEARNED_MAX_SLOTS];
            for (int i = 0; i < t->feature_count; i++)
                xc[i] = t->features[i].kind == MR_LEARNED_GREY ? v[slot_offset(src, &t->features[i]) + ch] : x[i];
            regress(t, xc, yc);
            for (int j = 0; j < t->output_count; j++)
                if (t->outputs[j].kind == MR_LEARNED_GREY) w[slot_offset(tgt, &t->outputs[j]) + ch] = yc[j];
        }
    }
    for (int p = 0, k = 0; p < tgt->param_count; p++)
        for (int c = 0; c < tgt->params[p].channels; c++, k++) {
            const double lo = tgt->params[p].min_value, hi = tgt->params[p].max_value;
            if (!(w[k] >= lo && w[k] <= hi)) {
                f |= MR_WF_CLAMPED_OUTPUT;
                w[k] = mr_clampd(w[k], lo, hi);
            }
        }
    memcpy(target_values, w, (size_t)target_count * sizeof *w);
    if (flags != NULL) *flags = f;
}

mr_status mr_learned_chain_apply(const mr_learned *const *t, int hops, const double *source_values,
                                 double *target_values, unsigned *flags) {
    if (t == NULL || hops < 1 || source_values == NULL || target_values == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "transform chain: NULL argument or no hops");
    for (int h = 1; h < hops; h++)
        if (t[h - 1]->target != t[h]->source)
            return mr_fail(MR_ERR_INVALID_ARG, "transform chain: hop %d ends in %s but hop %d starts from %s", h,
                           t[h - 1]->target->name, h + 1, t[h]->source->name);
    double a[MR_BRDF_MAX_VALUES], b[MR_BRDF_MAX_VALUES];
    memcpy(a, source_values, (size_t)mr_brdf_value_count(t[0]->source) * sizeof *a);
    unsigned all = 0;
    for (int h = 0; h < hops; h++) {
        unsigned f = 0;
        mr_learned_apply(t[h], a, b, &f);
        all |= f;
        memcpy(a, b, sizeof a);
    }
    memcpy(target_values, a, (size_t)mr_brdf_value_count(t[hops - 1]->target) * sizeof *a);
    if (flags != NULL) *flags = all;
    return MR_OK;
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
