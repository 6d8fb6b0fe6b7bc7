/*
 * learned_file.c — the transform file (.mrt) of learned.h: writing, reading, and their strict checks.
 */
#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "c_locale.h"
#include "learn/learned.h"
#include "learn/svr.h"
#include "mr_internal.h"
#include "nn/mlp.h"
#include "remap/remap_file.h"
#include "text_lines.h"

#define MAX_TOKEN 63
#define MAX_FILE_BYTES ((size_t)1 << 30)
#define MAX_SUPPORT_VECTORS 1000000

static const char *const kind_names[3] = {"scalar", "grey", "channel"};

static uint32_t fnv1a(const char *text, size_t length) {
    uint32_t h = 2166136261u;
    for (size_t i = 0; i < length; i++) {
        h ^= (unsigned char)text[i];
        h *= 16777619u;
    }
    return h;
}

/* ---- writing ---------------------------------------------------------------------------------------------- */

typedef struct text_out {
    char *text;
    size_t length, capacity;
    int failed;
} text_out;

#if defined(__GNUC__)
__attribute__((format(printf, 2, 3)))
#endif
static void put(text_out *o, const char *fmt, ...) {
    if (o->failed) return;
    for (;;) {
        va_list args;
        va_start(args, fmt);
        int n = vsnprintf(o->text + o->length, o->capacity - o->length, fmt, args);
        va_end(args);
        if (n < 0) {
            o->failed = 1;
            return;
        }
        if ((size_t)n < o->capacity - o->length) {
            o->length += (size_t)n;
            return;
        }
        size_t grown = 2 * o->capacity + (size_t)n + 1;
        char *t = realloc(o->text, grown);
        if (t == NULL) {
            o->failed = 1;
            return;
        }
        o->text = t;
        o->capacity = grown;
    }
}

static void put_values(text_out *o, const char *key, const double *v, int count) {
    put(o, "%s", key);
    for (int i = 0; i < count; i++) put(o, " %a", v[i]);
    put(o, "\n");
}

static void put_slot(text_out *o, const char *key, const mr_brdf_model *model, const mr_learned_slot *s, int domain) {
    put(o, "%s %s %s %d", key, model->params[s->param].name, kind_names[s->kind], s->channel);
    if (domain) put(o, " %a %a", s->min, s->max);
    put(o, "\n");
}

/* The comment lines a person reads: the parametric curves in decimal. */
static void put_parametric_comment(text_out *o, const mr_learned *t) {
    const char *a = t->source->params[t->features[0].param].name;
    put(o, "# %s' = ", t->target->params[t->outputs[0].param].name);
    for (int k = 0; k <= t->roughness_degree; k++)
        if (k > 0 || !t->roughness_origin) put(o, "%s%.6g %s^%d", k > (t->roughness_origin ? 1 : 0) ? " + " : "",
                                               t->roughness[k], a, k);
    const double *c = t->slope.c;
    put(o, "\n# %s' = %s * [%.6g + %.6g e^(-%.6g %s) + %.6g e^(-%.6g %s^2)",
        t->target->params[t->outputs[1].param].name, t->source->params[t->features[1].param].name, c[0], c[1], c[2], a,
        c[3], c[4], a);
    if (t->slope.with_inverse) put(o, " + %.6g / %s", c[5], a);
    put(o, "]\n");
    if (t->output_count == 3) {
        const double *d = t->diffuse_slope.c;
        put(o, "# %s' = carried + %s * [%.6g + %.6g e^(-%.6g %s) + %.6g e^(-%.6g %s^2)",
            t->target->params[t->outputs[2].param].name, t->source->params[t->features[1].param].name, d[0], d[1],
            d[2], a, d[3], d[4], a);
        if (t->diffuse_slope.with_inverse) put(o, " + %.6g / %s", d[5], a);
        put(o, "]\n");
    }
}

static mr_status format_svr(text_out *o, const mr_svr *m) {
    put(o, "svr %d %d\n", m->n_in, m->n_out);
    put_values(o, "in_mean", m->in_mean, m->n_in);
    put_values(o, "in_std", m->in_std, m->n_in);
    put_values(o, "out_mean", m->out_mean, m->n_out);
    put_values(o, "out_std", m->out_std, m->n_out);
    for (int j = 0; j < m->n_out; j++) {
        const mr_svr_output *out = &m->outputs[j];
        put(o, "model %d %a %a %a %a %a %a\n", out->sv_count, out->gamma, out->C, out->epsilon, out->rho,
            out->validation_rmse, out->grid_rmse);
        for (int s = 0; s < out->sv_count; s++) {
            put(o, "sv %a", out->coef[s]);
            for (int i = 0; i < m->n_in; i++) put(o, " %a", out->sv[(size_t)s * (size_t)m->n_in + (size_t)i]);
            put(o, "\n");
        }
    }
    return MR_OK;
}

static mr_status format_all(const mr_learned *t, text_out *o) {
    put(o, "%s %d\n", MR_LEARNED_FILE_MAGIC, MR_LEARNED_FILE_VERSION);
    put(o, "# a transform learned by matremap from uniform remaps (docs/learn.md); machine-written: the checksum "
        "refuses edits\n");
    put(o, "source %s\ntarget %s\nmethod %s\n", t->source->name, t->target->name, mr_learn_method_name(t->method));
    put(o, "features %d\n", t->feature_count);
    for (int i = 0; i < t->feature_count; i++) put_slot(o, "feature", t->source, &t->features[i], 1);
    put(o, "outputs %d\n", t->output_count);
    for (int j = 0; j < t->output_count; j++) put_slot(o, "output", t->target, &t->outputs[j], 0);
    put_values(o, "base", t->base, mr_brdf_value_count(t->target));
    put(o, "carries %d\n", t->carry_count);
    for (int i = 0; i < t->carry_count; i++) {
        const mr_learned_carry *c = &t->carries[i];
        put(o, "carry %s %s %s", t->target->params[c->target_param].name, t->source->params[c->source_param].name,
            c->learned ? "learned" : "lobes");
        put_values(o, "", c->factor, t->target->params[c->target_param].channels);
    }
    put(o, "validation %a %llu %ld %ld\n", t->validation_fraction, t->seed, t->train_rows, t->validation_rows);
    put_values(o, "rmse", t->rmse, t->output_count);
    const mr_learned_check *k = &t->check;
    put(o, "check %ld %d %a %a", k->done ? k->rows : 0L, k->done && k->passed, k->done ? k->dssim_mean : 0.0,
        k->done ? k->dssim_p90 : 0.0);
    for (int j = 0; j < t->output_count; j++)
        put(o, " %a %a", k->done ? k->relative_median[j] : 0.0, k->done ? k->relative_p90[j] : 0.0);
    put(o, "\n");
    long lines = 0;
    for (const char *p = t->provenance; p && *p; p++) lines += *p == '\n';
    put(o, "provenance %ld\n", lines);
    for (const char *p = t->provenance; p && *p;) {
        const char *e = strchr(p, '\n');
        put(o, "| %.*s\n", (int)(e - p), p);
        p = e + 1;
    }
    switch (t->method) {
    case MR_LEARN_PARAMETRIC:
        put_parametric_comment(o, t);
        put(o, "roughness %d %d", t->roughness_degree, t->roughness_origin);
        put_values(o, "", t->roughness, MR_POLY_MAX_DEGREE + 1);
        put(o, "slope %d", t->slope.with_inverse);
        put_values(o, "", t->slope.c, 6);
        if (t->output_count == 3) {
            put(o, "diffuse_slope %d", t->diffuse_slope.with_inverse);
            put_values(o, "", t->diffuse_slope.c, 6);
        }
        break;
    case MR_LEARN_SVR: format_svr(o, t->svr); break;
    default: {
        char *mlp = NULL;
        size_t length = 0;
        mr_status status = mr_mlp_format(t->mlp, "transform", &mlp, &length);
        if (status != MR_OK) return status;
        long count = 0;
        for (size_t k = 0; k < length; k++) count += mlp[k] == '\n';
        put(o, "mlp %ld\n%s", count, mlp);
        free(mlp);
    }
    }
    if (o->failed) return mr_fail(MR_ERR_NOMEM, "transform write: out of memory");
    put(o, "checksum %08x\nend\n", (unsigned)fnv1a(o->text, o->length));
    return o->failed ? mr_fail(MR_ERR_NOMEM, "transform write: out of memory") : MR_OK;
}

mr_status mr_learned_format(const mr_learned *t, char **text, size_t *length) {
    if (t == NULL || text == NULL) return mr_fail(MR_ERR_INVALID_ARG, "transform write: NULL argument");
    *text = NULL;
    mr_c_numeric locale;
    mr_status status = mr_c_numeric_enter(&locale, "transform write");
    if (status != MR_OK) return status;
    text_out o = {NULL, 0, 0, 0};
    o.capacity = 4096;
    o.text = malloc(o.capacity);
    status = o.text ? format_all(t, &o) : mr_fail(MR_ERR_NOMEM, "transform write: out of memory");
    mr_c_numeric_leave(&locale);
    if (status != MR_OK) {
        free(o.text);
        return status;
    }
    *text = o.text;
    if (length) *length = o.length;
    return MR_OK;
}

mr_status mr_learned_write(const mr_learned *t, const char *path) {
    if (path == NULL || path[0] == '\0') return mr_fail(MR_ERR_INVALID_ARG, "transform write: empty path");
    char *text = NULL;
    size_t length = 0;
    mr_status status = mr_learned_format(t, &text, &length);
    if (status == MR_OK) status = mr_atomic_write_bytes(path, text, length);
    free(text);
    return status;
}

/* ---- reading ---------------------------------------------------------------------------------------------- */

typedef struct parser {
    const char *name;
    mr_text_lines text; /* the lines and their tokens (src/text_lines.h); text.line_start: where the current
                           line began (the checksum covers what precedes it) */
} parser;

#if defined(__GNUC__)
__attribute__((format(printf, 2, 3)))
#endif
static mr_status bad(const parser *ps, const char *fmt, ...) {
    char why[512];
    va_list args;
    va_start(args, fmt);
    vsnprintf(why, sizeof why, fmt, args);
    va_end(args);
    return mr_fail(MR_ERR_FORMAT, "transform '%s': line %ld: %s", ps->name, ps->text.line, why);
}

/* The next line that is not a comment; `raw` also takes comment lines (provenance, mlp blocks keep theirs). */
static mr_status next_line(parser *ps, const char *expected, int raw) {
    for (;;) {
        mr_text_line_result got = mr_text_lines_next(&ps->text);
        if (got == MR_TEXT_END) return bad(ps, "the file ends early: expected %s (a truncated file?)", expected);
        if (got == MR_TEXT_NO_LINE_END)
            return bad(ps, "the last line has no line end: expected %s (a truncated file?)", expected);
        if (raw || ps->text.s == ps->text.e || ps->text.s[0] != '#') return MR_OK;
    }
}

static int token(parser *ps, const char **tok, size_t *len) { return mr_text_lines_token(&ps->text, tok, len); }

static mr_status expect_key(parser *ps, const char *key) {
    mr_status status = next_line(ps, key, 0);
    if (status != MR_OK) return status;
    const char *tok;
    size_t len;
    if (!token(ps, &tok, &len) || len != strlen(key) || memcmp(tok, key, len) != 0)
        return bad(ps, "expected '%s', found '%.*s'", key, (int)MR_MIN(ps->text.e - ps->text.line_start, 40),
                   ps->text.line_start);
    return MR_OK;
}

static mr_status word(parser *ps, const char *what, char *out, size_t size) {
    const char *tok;
    size_t len;
    if (!token(ps, &tok, &len)) return bad(ps, "missing %s", what);
    if (len >= size) return bad(ps, "%s '%.*s...' is too long", what, 20, tok);
    memcpy(out, tok, len);
    out[len] = '\0';
    return MR_OK;
}

static mr_status number(parser *ps, const char *what, double *out) {
    char buf[MAX_TOKEN + 1];
    mr_status status = word(ps, what, buf, sizeof buf);
    if (status != MR_OK) return status;
    char *end = NULL;
    errno = 0;
    double v = strtod(buf, &end);
    if (end == buf || *end != '\0' || !isfinite(v)) return bad(ps, "%s '%s' is not a finite number", what, buf);
    *out = v;
    return MR_OK;
}

static mr_status integer(parser *ps, const char *what, long lo, long hi, long *out) {
    char buf[MAX_TOKEN + 1];
    mr_status status = word(ps, what, buf, sizeof buf);
    if (status != MR_OK) return status;
    char *end = NULL;
    errno = 0;
    long v = strtol(buf, &end, 10);
    if (end == buf || *end != '\0' || errno != 0) return bad(ps, "%s '%s' is not an integer", what, buf);
    if (v < lo || v > hi) return bad(ps, "%s %ld is outside %ld .. %ld", what, v, lo, hi);
    *out = v;
    return MR_OK;
}

static mr_status line_end(parser *ps) {
    const char *tok;
    size_t len;
    if (token(ps, &tok, &len)) return bad(ps, "unexpected '%.*s' at the end of the line", (int)MR_MIN(len, 40), tok);
    return MR_OK;
}

static mr_status numbers(parser *ps, const char *what, double *v, int count) {
    for (int i = 0; i < count; i++) {
        mr_status status = number(ps, what, &v[i]);
        if (status != MR_OK) return status;
    }
    return line_end(ps);
}

static mr_status model_line(parser *ps, const char *key, const mr_brdf_model **out) {
    mr_status status = expect_key(ps, key);
    char name[64];
    if (status == MR_OK) status = word(ps, "model name", name, sizeof name);
    if (status != MR_OK) return status;
    *out = mr_brdf_find(name);
    if (*out == NULL) return bad(ps, "%s", mr_last_error());
    return line_end(ps);
}

static mr_status slot_line(parser *ps, const char *key, const mr_brdf_model *model, int domain, mr_learned_slot *s) {
    mr_status status = expect_key(ps, key);
    char name[64], kind[16];
    long channel = 0;
    if (status == MR_OK) status = word(ps, "parameter", name, sizeof name);
    if (status == MR_OK) status = word(ps, "slot kind", kind, sizeof kind);
    if (status == MR_OK) status = integer(ps, "channel", 0, 2, &channel);
    if (status != MR_OK) return status;
    s->param = mr_brdf_param_index(model, name);
    if (s->param < 0) return bad(ps, "%s has no parameter '%s'", model->name, name);
    int k = -1;
    for (int i = 0; i < 3; i++)
        if (strcmp(kind, kind_names[i]) == 0) k = i;
    if (k < 0) return bad(ps, "slot kind '%s': expected scalar, grey or channel", kind);
    s->kind = (mr_learned_slot_kind)k;
    s->channel = (int)channel;
    const int channels = model->params[s->param].channels;
    if ((s->kind == MR_LEARNED_SCALAR) != (channels == 1) || (s->kind != MR_LEARNED_CHANNEL && channel != 0))
        return bad(ps, "%s %s has %d channel%s: '%s %ld' does not fit it", model->name, name, channels,
                   channels == 1 ? "" : "s", kind, channel);
    if (domain) {
        if ((status = number(ps, "domain minimum", &s->min)) != MR_OK) return status;
        if ((status = number(ps, "domain maximum", &s->max)) != MR_OK) return status;
        if (!(s->min <= s->max)) return bad(ps, "domain [%g, %g] is empty", s->min, s->max);
    }
    return line_end(ps);
}

static mr_status count_line(parser *ps, const char *key, long hi, long *out) {
    mr_status status = expect_key(ps, key);
    if (status == MR_OK) status = integer(ps, key, 0, hi, out);
    return status == MR_OK ? line_end(ps) : status;
}

static mr_status parse_svr(parser *ps, mr_learned *t) {
    long n_in = 0, n_out = 0;
    mr_status status = expect_key(ps, "svr");
    if (status == MR_OK) status = integer(ps, "svr inputs", 1, MR_LEARNED_MAX_SLOTS, &n_in);
    if (status == MR_OK) status = integer(ps, "svr outputs", 1, MR_LEARNED_MAX_SLOTS, &n_out);
    if (status == MR_OK) status = line_end(ps);
    if (status != MR_OK) return status;
    if (n_in != t->feature_count || n_out != t->output_count)
        return bad(ps, "svr %ld %ld does not match the %d features and %d outputs", n_in, n_out, t->feature_count,
                   t->output_count);
    // The support vector counts come per model; read the normalisation first, then each model into a growing list.
    double in_mean[MR_LEARNED_MAX_SLOTS], in_std[MR_LEARNED_MAX_SLOTS], out_mean[MR_LEARNED_MAX_SLOTS],
        out_std[MR_LEARNED_MAX_SLOTS];
    static const char *const keys[4] = {"in_mean", "in_std", "out_mean", "out_std"};
    double *arrays[4] = {in_mean, in_std, out_mean, out_std};
    for (int k = 0; k < 4 && status == MR_OK; k++) {
        status = expect_key(ps, keys[k]);
        if (status == MR_OK) status = numbers(ps, keys[k], arrays[k], k < 2 ? (int)n_in : (int)n_out);
        for (int i = 0; status == MR_OK && (k & 1) && i < (k < 2 ? n_in : n_out); i++)
            if (!(arrays[k][i] > 0.0)) status = bad(ps, "%s %g: expected > 0", keys[k], arrays[k][i]);
    }
    if (status != MR_OK) return status;
    // Support vector counts are known only model by model: remember where each model starts and read it twice.
    parser mark = *ps;
    int counts[MR_LEARNED_MAX_SLOTS];
    for (int pass = 0; pass < 2 && status == MR_OK; pass++) {
        if (pass == 1) {
            status = mr_svr_alloc((int)n_in, (int)n_out, counts, &t->svr);
            if (status != MR_OK) return status;
            memcpy(t->svr->in_mean, in_mean, (size_t)n_in * sizeof *in_mean);
            memcpy(t->svr->in_std, in_std, (size_t)n_in * sizeof *in_std);
            memcpy(t->svr->out_mean, out_mean, (size_t)n_out * sizeof *out_mean);
            memcpy(t->svr->out_std, out_std, (size_t)n_out * sizeof *out_std);
            *ps = mark;
        }
        for (int j = 0; j < n_out && status == MR_OK; j++) {
            long count = 0;
            double h[6];
            status = expect_key(ps, "model");
            if (status == MR_OK) status = integer(ps, "support vector count", 0, MAX_SUPPORT_VECTORS, &count);
            if (status == MR_OK) status = numbers(ps, "svr hyper-parameter", h, 6);
            if (status == MR_OK && !(h[0] > 0.0 && h[1] > 0.0 && h[2] >= 0.0 && h[4] >= 0.0 && h[5] >= 0.0))
                status = bad(ps, "svr gamma %g, C %g, epsilon %g, rmse %g: expected gamma > 0, C > 0, epsilon >= 0, "
                             "rmse >= 0", h[0], h[1], h[2], h[4]);
            if (status != MR_OK) break;
            counts[j] = (int)count;
            mr_svr_output *out = pass ? &t->svr->outputs[j] : NULL;
            if (out) {
                out->gamma = h[0];
                out->C = h[1];
                out->epsilon = h[2];
                out->rho = h[3];
                out->validation_rmse = h[4];
                out->grid_rmse = h[5];
            }
            for (long s = 0; s < count && status == MR_OK; s++) {
                double v[1 + MR_LEARNED_MAX_SLOTS];
                status = expect_key(ps, "sv");
                if (status == MR_OK) status = numbers(ps, "support vector value", v, 1 + (int)n_in);
                if (status == MR_OK && out) {
                    out->coef[s] = v[0];
                    memcpy(out->sv + (size_t)s * (size_t)n_in, v + 1, (size_t)n_in * sizeof *v);
                }
            }
        }
    }
    return status;
}

static mr_status parse_mlp(parser *ps, mr_learned *t) {
    long lines = 0;
    mr_status status = count_line(ps, "mlp", 100000000L, &lines);
    if (status != MR_OK) return status;
    const char *from = ps->text.p;
    for (long k = 0; k < lines && status == MR_OK; k++) status = next_line(ps, "a line of the network", 1);
    if (status != MR_OK) return status;
    char label[600];
    snprintf(label, sizeof label, "%s, its network (lines %ld-%ld)", ps->name, ps->text.line - lines + 1,
             ps->text.line);
    status = mr_mlp_parse(from, (size_t)(ps->text.p - from), label, &t->mlp);
    if (status != MR_OK) return status;
    if (t->mlp->n_in != t->feature_count || t->mlp->n_out != t->output_count)
        return bad(ps, "the network has %d inputs and %d outputs; the transform %d features and %d outputs",
                   t->mlp->n_in, t->mlp->n_out, t->feature_count, t->output_count);
    return MR_OK;
}

/* "check ROWS PASSED DSSIM_MEAN DSSIM_P90 (MEDIAN P90) per output" (learned.h). */
static mr_status check_line(parser *ps, mr_learned *t) {
    mr_learned_check *k = &t->check;
    long rows = 0, passed = 0;
    mr_status status = expect_key(ps, "check");
    if (status == MR_OK) status = integer(ps, "checked rows", 0, 1000000000L, &rows);
    if (status == MR_OK) status = integer(ps, "check verdict", 0, 1, &passed);
    for (int i = 0; i < 2 && status == MR_OK; i++) { // the dSSIM: a number >= -2 or nan (no render)
        char buf[MAX_TOKEN + 1];
        double *v = i == 0 ? &k->dssim_mean : &k->dssim_p90;
        status = word(ps, "dSSIM", buf, sizeof buf);
        if (status != MR_OK) break;
        char *end = NULL;
        *v = strtod(buf, &end);
        if (end == buf || *end != '\0' || !(isnan(*v) || (*v >= -2.0 && *v <= 2.0)))
            status = bad(ps, "dSSIM '%s': expected a number in [-2, 2] or nan", buf);
    }
    for (int j = 0; j < t->output_count && status == MR_OK; j++) {
        status = number(ps, "relative error", &k->relative_median[j]);
        if (status == MR_OK) status = number(ps, "relative error", &k->relative_p90[j]);
        if (status == MR_OK && (k->relative_median[j] < 0.0 || k->relative_p90[j] < 0.0))
            status = bad(ps, "a relative error is negative");
    }
    if (status == MR_OK) status = line_end(ps);
    if (status != MR_OK) return status;
    k->done = rows > 0;
    k->rows = rows;
    k->passed = (int)passed;
    if (!k->done && passed) return bad(ps, "a check of 0 rows cannot pass");
    return MR_OK;
}

static mr_status parse_all(parser *ps, mr_learned *t) {
    mr_status status = next_line(ps, "the magic line", 0);
    if (status != MR_OK) return status;
    char magic[32];
    long version = 0;
    if (word(ps, "magic", magic, sizeof magic) != MR_OK || strcmp(magic, MR_LEARNED_FILE_MAGIC) != 0)
        return bad(ps, "not a matremap transform file (expected '%s %d' first)", MR_LEARNED_FILE_MAGIC,
                   MR_LEARNED_FILE_VERSION);
    if ((status = integer(ps, "version", 1, 1000000, &version)) != MR_OK) return status;
    if (version < 1 || version > MR_LEARNED_FILE_VERSION)
        return bad(ps, "version %ld; this matremap reads versions 1 to %d (a newer matremap wrote it?)", version,
                   MR_LEARNED_FILE_VERSION);
    if ((status = line_end(ps)) != MR_OK) return status;
    if ((status = model_line(ps, "source", &t->source)) != MR_OK) return status;
    if ((status = model_line(ps, "target", &t->target)) != MR_OK) return status;
    char method[32];
    if ((status = expect_key(ps, "method")) != MR_OK) return status;
    if ((status = word(ps, "method", method, sizeof method)) != MR_OK) return status;
    if (mr_learn_method_from_name(method, &t->method) != MR_OK) return bad(ps, "%s", mr_last_error());
    if ((status = line_end(ps)) != MR_OK) return status;
    long count = 0;
    if ((status = count_line(ps, "features", MR_LEARNED_MAX_SLOTS, &count)) != MR_OK) return status;
    t->feature_count = (int)count;
    for (int i = 0; i < t->feature_count; i++)
        if ((status = slot_line(ps, "feature", t->source, 1, &t->features[i])) != MR_OK) return status;
    if ((status = count_line(ps, "outputs", MR_LEARNED_MAX_SLOTS, &count)) != MR_OK) return status;
    t->output_count = (int)count;
    for (int j = 0; j < t->output_count; j++)
        if ((status = slot_line(ps, "output", t->target, 0, &t->outputs[j])) != MR_OK) return status;
    if (t->feature_count < 1 || t->output_count < 1) return bad(ps, "a transform needs a feature and an output");
    if (t->method == MR_LEARN_PARAMETRIC &&
        (t->feature_count != 2 || t->output_count < 2 || t->output_count > 3 ||
         t->features[0].kind != MR_LEARNED_SCALAR || t->outputs[0].kind != MR_LEARNED_SCALAR))
        return bad(ps, "a parametric transform has 2 features and 2 or 3 outputs, the first of each a scalar "
                   "roughness");
    if ((status = expect_key(ps, "base")) != MR_OK) return status;
    const int target_count = mr_brdf_value_count(t->target);
    if ((status = numbers(ps, "base value", t->base, target_count)) != MR_OK) return status;
    if ((status = count_line(ps, "carries", MR_LEARNED_MAX_SLOTS, &count)) != MR_OK) return status;
    t->carry_count = (int)count;
    for (int i = 0; i < t->carry_count; i++) {
        mr_learned_carry *c = &t->carries[i];
        char to[64], from[64], how[16];
        if ((status = expect_key(ps, "carry")) != MR_OK) return status;
        if ((status = word(ps, "target parameter", to, sizeof to)) != MR_OK) return status;
        if ((status = word(ps, "source parameter", from, sizeof from)) != MR_OK) return status;
        if ((status = word(ps, "carry kind", how, sizeof how)) != MR_OK) return status;
        c->target_param = mr_brdf_param_index(t->target, to);
        c->source_param = mr_brdf_param_index(t->source, from);
        if (c->target_param < 0 || c->source_param < 0)
            return bad(ps, "carry %s <- %s: %s has no parameter '%s'", to, from,
                       c->target_param < 0 ? t->target->name : t->source->name, c->target_param < 0 ? to : from);
        const int channels = t->target->params[c->target_param].channels;
        if (channels != t->source->params[c->source_param].channels)
            return bad(ps, "carry %s <- %s: channel counts differ", to, from);
        if (strcmp(how, "learned") != 0 && strcmp(how, "lobes") != 0)
            return bad(ps, "carry kind '%s': expected learned or lobes", how);
        c->learned = strcmp(how, "learned") == 0;
        if ((status = numbers(ps, "carry factor", c->factor, channels)) != MR_OK) return status;
        for (int ch = channels; ch < 3; ch++) c->factor[ch] = 0.0;
    }
    if ((status = expect_key(ps, "validation")) != MR_OK) return status;
    char seed[32];
    long train = 0, held = 0;
    if ((status = number(ps, "validation fraction", &t->validation_fraction)) != MR_OK) return status;
    if ((status = word(ps, "seed", seed, sizeof seed)) != MR_OK) return status;
    char *end = NULL;
    errno = 0;
    t->seed = strtoull(seed, &end, 10);
    if (end == seed || *end != '\0' || errno != 0 || seed[0] == '-') return bad(ps, "seed '%s' is not a count", seed);
    if ((status = integer(ps, "training rows", 0, 1000000000L, &train)) != MR_OK) return status;
    if ((status = integer(ps, "validation rows", 0, 1000000000L, &held)) != MR_OK) return status;
    if ((status = line_end(ps)) != MR_OK) return status;
    t->train_rows = train;
    t->validation_rows = held;
    if ((status = expect_key(ps, "rmse")) != MR_OK) return status;
    if ((status = numbers(ps, "rmse", t->rmse, t->output_count)) != MR_OK) return status;
    for (int j = 0; j < t->output_count; j++)
        if (t->rmse[j] < 0.0) return bad(ps, "rmse %g is negative", t->rmse[j]);
    if (version >= 2 && (status = check_line(ps, t)) != MR_OK) return status;
    if ((status = count_line(ps, "provenance", MR_LEARNED_MAX_PROVENANCE, &count)) != MR_OK) return status;
    size_t length = 0;
    for (long k = 0; k < count; k++) {
        if ((status = next_line(ps, "a provenance line", 1)) != MR_OK) return status;
        if (ps->text.e - ps->text.s < 2 || ps->text.s[0] != '|' || ps->text.s[1] != ' ')
            return bad(ps, "expected a provenance line '| ...'");
        const size_t add = (size_t)(ps->text.e - ps->text.s - 2);
        char *grown = realloc(t->provenance, length + add + 2);
        if (grown == NULL) return mr_fail(MR_ERR_NOMEM, "transform '%s': out of memory", ps->name);
        memcpy(grown + length, ps->text.s + 2, add);
        length += add;
        grown[length++] = '\n';
        grown[length] = '\0';
        t->provenance = grown;
    }
    switch (t->method) {
    case MR_LEARN_PARAMETRIC: {
        long degree = 0, origin = 0, inverse = 0;
        if ((status = expect_key(ps, "roughness")) != MR_OK) return status;
        if ((status = integer(ps, "degree", 1, MR_POLY_MAX_DEGREE, &degree)) != MR_OK) return status;
        if ((status = integer(ps, "through-origin flag", 0, 1, &origin)) != MR_OK) return status;
        if ((status = numbers(ps, "roughness coefficient", t->roughness, MR_POLY_MAX_DEGREE + 1)) != MR_OK)
            return status;
        t->roughness_degree = (int)degree;
        t->roughness_origin = (int)origin;
        if ((status = expect_key(ps, "slope")) != MR_OK) return status;
        if ((status = integer(ps, "inverse-term flag", 0, 1, &inverse)) != MR_OK) return status;
        if ((status = numbers(ps, "slope coefficient", t->slope.c, 6)) != MR_OK) return status;
        t->slope.with_inverse = (int)inverse;
        if (t->output_count == 3) {
            if ((status = expect_key(ps, "diffuse_slope")) != MR_OK) return status;
            if ((status = integer(ps, "inverse-term flag", 0, 1, &inverse)) != MR_OK) return status;
            if ((status = numbers(ps, "diffuse slope coefficient", t->diffuse_slope.c, 6)) != MR_OK) return status;
            t->diffuse_slope.with_inverse = (int)inverse;
        }
        break;
    }
    case MR_LEARN_SVR:
        if ((status = parse_svr(ps, t)) != MR_OK) return status;
        break;
    default:
        if ((status = parse_mlp(ps, t)) != MR_OK) return status;
    }
    if ((status = expect_key(ps, "checksum")) != MR_OK) return status;
    const uint32_t computed = fnv1a(ps->text.start, (size_t)(ps->text.line_start - ps->text.start));
    char sum[16];
    if ((status = word(ps, "checksum", sum, sizeof sum)) != MR_OK) return status;
    end = NULL;
    unsigned long stored = strtoul(sum, &end, 16);
    if (end == sum || *end != '\0' || strlen(sum) != 8)
        return bad(ps, "checksum '%s': expected 8 hexadecimal digits", sum);
    if (stored != computed)
        return bad(ps, "checksum mismatch (file says %08lx, its bytes give %08x): the file was changed or damaged "
                   "after matremap wrote it; learn it again", stored, (unsigned)computed);
    if ((status = line_end(ps)) != MR_OK) return status;
    if ((status = expect_key(ps, "end")) != MR_OK) return status;
    if ((status = line_end(ps)) != MR_OK) return status;
    if (ps->text.p != ps->text.end) {
        ps->text.line++;
        return bad(ps, "text after 'end'");
    }
    return MR_OK;
}

mr_status mr_learned_parse(const char *text, size_t size, const char *name, mr_learned **out) {
    if (name == NULL) name = "<memory>";
    if (out == NULL || (text == NULL && size > 0))
        return mr_fail(MR_ERR_INVALID_ARG, "transform '%s': NULL argument", name);
    mr_learned *t = calloc(1, sizeof *t);
    if (t == NULL) return mr_fail(MR_ERR_NOMEM, "transform '%s': out of memory", name);
    parser ps = {name, {0}};
    mr_text_lines_init(&ps.text, text, size);
    mr_c_numeric locale;
    mr_status status = mr_c_numeric_enter(&locale, "transform read");
    if (status == MR_OK) {
        status = parse_all(&ps, t);
        mr_c_numeric_leave(&locale);
    }
    if (status != MR_OK) {
        mr_learned_free(t);
        return status;
    }
    *out = t;
    return MR_OK;
}

mr_status mr_learned_read(const char *path, mr_learned **out) {
    if (path == NULL || path[0] == '\0') return mr_fail(MR_ERR_INVALID_ARG, "transform read: empty path");
    if (out == NULL) return mr_fail(MR_ERR_INVALID_ARG, "transform read '%s': NULL output", path);
    // Only a regular file, of at most MAX_FILE_BYTES, is opened (a FIFO named as a transform blocked open()).
    char label[MR_IO_LABEL_SIZE + 16];
    snprintf(label, sizeof label, "transform '%s'", path);
    FILE *file = NULL;
    mr_status status = mr_io_open_input(path, label, MAX_FILE_BYTES, &file, NULL);
    if (status != MR_OK) return status;
    char *text = NULL;
    size_t length = 0;
    status = mr_text_file_read_all(fileno(file), path, "transform", &text, &length);
    fclose(file);
    if (status == MR_OK) status = mr_learned_parse(text, length, path, out);
    free(text);
    return status;
}
