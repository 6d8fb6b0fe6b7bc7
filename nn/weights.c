/*
 * weights.c — the MLP weight file (format in mlp.h): writing through the atomic temp-file + rename protocol of
 * src/io/atomic_file.c, and a strict line-by-line reader.
 *
 * Hexadecimal floats ("%a") are exact: a float promoted to double prints every significant bit, and strtod
 * reads it back to the same double, whose conversion to float is exact. Both printf's and strtod's radix
 * character follow LC_NUMERIC, so each call switches its own thread to the C numeric locale with uselocale()
 * (per thread, so a host program's locale is neither used nor changed), as src/remap/sweep.c does. The whole
 * file is formatted in memory and handed to mr_atomic_write_bytes(), and read whole before parsing, so the
 * parser (mr_mlp_parse) works on bytes and can be tested and fuzzed without files.
 */
#include "mlp_internal.h"

#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../src/c_locale.h"
#include "../src/mr_internal.h"
#include "../src/text_lines.h"

/* Hidden and output activations: the only pair version 1 knows. */
#define ACTIVATIONS "relu linear"
/* Longest number token the reader accepts ("-0x1.fffffep+127" has 16 characters). */
#define MAX_TOKEN 63
/* Longest file the reader loads: MR_MLP_MAX_PARAMS numbers at 24 bytes, plus slack. */
#define MAX_FILE_BYTES ((size_t)MR_MLP_MAX_PARAMS * 24 + ((size_t)1 << 20))

/* ---- writing ---------------------------------------------------------------------------------------------- */

typedef struct out_text {
    char *text;
    size_t length, capacity;
} out_text;

#if defined(__GNUC__)
__attribute__((format(printf, 2, 3)))
#endif
static int put(out_text *o, const char *fmt, ...) {
    va_list args;
    va_start(args, fmt);
    int n = vsnprintf(o->text + o->length, o->capacity - o->length, fmt, args);
    va_end(args);
    if (n < 0 || (size_t)n >= o->capacity - o->length) return -1;
    o->length += (size_t)n;
    return 0;
}

/* "key v v v\n" */
static int put_line(out_text *o, const char *key, const float *v, size_t count) {
    if (put(o, "%s", key) != 0) return -1;
    for (size_t q = 0; q < count; q++)
        if (put(o, " %a", (double)v[q]) != 0) return -1;
    return put(o, "\n");
}

/* A kind is a word of letters, digits, '.', '_' and '-' (mr_mlp.kind), shorter than MR_MLP_KIND_MAX. */
static int kind_char(char ch) {
    return (ch >= 'a' && ch <= 'z') || (ch >= 'A' && ch <= 'Z') || (ch >= '0' && ch <= '9') || ch == '.' ||
           ch == '_' || ch == '-';
}

static mr_status check_values(const mr_mlp *net, const char *path) {
    mr_status status = mr_mlp_check_dims("mlp write", net->n_in, net->n_hidden, net->n_out);
    if (status != MR_OK) return status;
    size_t kind_len = strnlen(net->kind, MR_MLP_KIND_MAX);
    int kind_ok = kind_len < MR_MLP_KIND_MAX;
    for (size_t q = 0; kind_ok && q < kind_len; q++) kind_ok = kind_char(net->kind[q]);
    if (!kind_ok)
        return mr_fail(MR_ERR_INVALID_ARG, "mlp write '%s': kind is not a word of at most %d letters, digits, "
                       "'.', '_' or '-'", path, MR_MLP_KIND_MAX - 1);
    const size_t I = (size_t)net->n_in, H = (size_t)net->n_hidden, O = (size_t)net->n_out;
    const struct {
        const char *name;
        const float *v;
        size_t count;
        int positive;
    } arrays[8] = {
        {"w1", net->w1, I * H, 0},         {"b1", net->b1, H, 0},
        {"w2", net->w2, O * H, 0},         {"b2", net->b2, O, 0},
        {"in_mean", net->in_mean, I, 0},   {"in_std", net->in_std, I, 1},
        {"out_mean", net->out_mean, O, 0}, {"out_std", net->out_std, O, 1},
    };
    for (int a = 0; a < 8; a++) {
        if (arrays[a].v == NULL) return mr_fail(MR_ERR_INVALID_ARG, "mlp write '%s': %s is NULL", path, arrays[a].name);
        for (size_t q = 0; q < arrays[a].count; q++) {
            float v = arrays[a].v[q];
            if (!isfinite(v) || (arrays[a].positive && !(v > 0.0f)))
                return mr_fail(MR_ERR_INVALID_ARG, "mlp write '%s': %s[%zu] is %g (expected a finite value%s)", path,
                               arrays[a].name, q, (double)v, arrays[a].positive ? " > 0" : "");
        }
    }
    return MR_OK;
}

static mr_status format_net(const mr_mlp *net, out_text *o) {
    const size_t I = (size_t)net->n_in, H = (size_t)net->n_hidden, O = (size_t)net->n_out;
    // Every number takes at most 17 characters with its space ("-0x1.fffffep+127"); lines add a key each.
    o->capacity = ((I + O + 2) * H + 2 * (I + O) + O) * 17 + (I + O + 16) * 16 + 256;
    o->length = 0;
    o->text = malloc(o->capacity);
    if (o->text == NULL) return mr_fail(MR_ERR_NOMEM, "mlp write: out of memory (%zu bytes)", o->capacity);
    int bad = put(o, "%s %d\nn_in %d\nn_hidden %d\nn_out %d\nactivation %s\n", MR_MLP_FILE_MAGIC,
                  net->kind[0] ? 2 : 1, net->n_in, net->n_hidden, net->n_out, ACTIVATIONS);
    if (net->kind[0]) bad = bad || put(o, "kind %s\n", net->kind);
    bad = bad || put_line(o, "in_mean", net->in_mean, I) || put_line(o, "in_std", net->in_std, I);
    bad = bad || put_line(o, "out_mean", net->out_mean, O) || put_line(o, "out_std", net->out_std, O);
    for (size_t i = 0; i < I && !bad; i++) bad = put_line(o, "w1", net->w1 + i * H, H);
    bad = bad || put_line(o, "b1", net->b1, H);
    for (size_t k = 0; k < O && !bad; k++) bad = put_line(o, "w2", net->w2 + k * H, H);
    bad = bad || put_line(o, "b2", net->b2, O) || put(o, "end\n");
    if (bad) {
        free(o->text);
        o->text = NULL;
        return mr_fail(MR_ERR_INVALID_ARG, "mlp write: formatting failed (internal size estimate too small)");
    }
    return MR_OK;
}

mr_status mr_mlp_format(const mr_mlp *net, const char *name, char **text, size_t *length) {
    if (name == NULL) name = "<memory>";
    if (net == NULL || text == NULL) return mr_fail(MR_ERR_INVALID_ARG, "mlp write '%s': NULL argument", name);
    *text = NULL;
    mr_status status = check_values(net, name);
    if (status != MR_OK) return status;
    mr_c_numeric locale;
    status = mr_c_numeric_enter(&locale, "mlp write");
    if (status != MR_OK) return status;
    out_text o = {NULL, 0, 0};
    status = format_net(net, &o);
    mr_c_numeric_leave(&locale);
    if (status != MR_OK) return status;
    *text = o.text;
    if (length != NULL) *length = o.length;
    return MR_OK;
}

mr_status mr_mlp_write(const mr_mlp *net, const char *path) {
    if (path == NULL || path[0] == '\0') return mr_fail(MR_ERR_INVALID_ARG, "mlp write: empty path");
    char *text = NULL;
    size_t length = 0;
    mr_status status = mr_mlp_format(net, path, &text, &length);
    if (status == MR_OK) status = mr_atomic_write_bytes(path, text, length);
    free(text);
    return status;
}

/* ---- reading ---------------------------------------------------------------------------------------------- */

typedef struct parser {
    const char *name;
    mr_text_lines text; /* the lines and their tokens (src/text_lines.h) */
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
    return mr_fail(MR_ERR_FORMAT, "mlp weights '%s': line %ld: %s", ps->name, ps->text.line, why);
}

/* Step to the next line; `expected` names what should be there (for the end-of-file message). */
static mr_status next_line(parser *ps, const char *expected) {
    mr_text_line_result got = mr_text_lines_next(&ps->text);
    if (got == MR_TEXT_LINE) return MR_OK;
    ps->text.line++; /* the messages name the line that is missing or torn */
    if (got == MR_TEXT_END) return bad(ps, "unexpected end of file (expected %s; truncated file?)", expected);
    return bad(ps, "last line has no end of line (truncated file?)");
}

static int token(parser *ps, const char **tok, size_t *len) { return mr_text_lines_token(&ps->text, tok, len); }

/* Printable excerpt of a token for messages. */
static const char *excerpt(const char *tok, size_t len, char *buf, size_t size) {
    size_t n = MR_MIN(len, size - 4);
    for (size_t c = 0; c < n; c++) buf[c] = (tok[c] >= 32 && tok[c] < 127) ? tok[c] : '?';
    if (n < len) {
        memcpy(buf + n, "...", 3);
        n += 3;
    }
    buf[n] = '\0';
    return buf;
}

/* A line "key" followed by exactly `count` finite floats into v. */
static mr_status read_values(parser *ps, const char *key, float *v, size_t count, int positive) {
    mr_status status = next_line(ps, key);
    if (status != MR_OK) return status;
    const char *tok = ps->text.s;
    size_t len = 0;
    char shown[40];
    if (!token(ps, &tok, &len) || !mr_text_token_is(tok, len, key))
        return bad(ps, "expected '%s', found '%s'", key, excerpt(tok, len, shown, sizeof shown));
    size_t q = 0;
    for (; token(ps, &tok, &len); q++) {
        if (q == count) return bad(ps, "more than %zu values after '%s'", count, key);
        char buf[MAX_TOKEN + 1];
        if (len > MAX_TOKEN) return bad(ps, "value %zu of '%s' is not a number: '%s'", q, key,
                                        excerpt(tok, len, shown, sizeof shown));
        memcpy(buf, tok, len);
        buf[len] = '\0';
        char *stop = NULL;
        double d = strtod(buf, &stop);
        if (stop != buf + len || len == 0)
            return bad(ps, "value %zu of '%s' is not a number: '%s'", q, key, excerpt(tok, len, shown, sizeof shown));
        if (!(fabs(d) <= FLT_MAX))
            return bad(ps, "value %zu of '%s' is %s (expected a finite float)", q, key, buf);
        float f = (float)d;
        if (positive && !(f > 0.0f)) return bad(ps, "value %zu of '%s' is %s (expected a value > 0)", q, key, buf);
        v[q] = f;
    }
    if (q != count) return bad(ps, "%zu values after '%s' (expected %zu)", q, key, count);
    return MR_OK;
}

/* A line "key N" with 1 <= N <= limit. */
static mr_status read_size(parser *ps, const char *key, int limit, int *out) {
    mr_status status = next_line(ps, key);
    if (status != MR_OK) return status;
    const char *tok = ps->text.s;
    size_t len = 0;
    char shown[40];
    if (!token(ps, &tok, &len) || !mr_text_token_is(tok, len, key))
        return bad(ps, "expected '%s N', found '%s'", key, excerpt(tok, len, shown, sizeof shown));
    if (!token(ps, &tok, &len)) return bad(ps, "'%s' without a value", key);
    long value = 0;
    for (size_t c = 0; c < len; c++) {
        if (tok[c] < '0' || tok[c] > '9' || value > (long)limit)
            return bad(ps, "'%s %s' is not a size from 1 to %d", key, excerpt(tok, len, shown, sizeof shown), limit);
        value = value * 10 + (tok[c] - '0');
    }
    if (value < 1 || value > (long)limit)
        return bad(ps, "'%s %s' is not a size from 1 to %d", key, excerpt(tok, len, shown, sizeof shown), limit);
    if (token(ps, &tok, &len)) return bad(ps, "more than one value after '%s'", key);
    *out = (int)value;
    return MR_OK;
}

/* The first line: magic and version. */
static mr_status read_magic(parser *ps, int *version_out) {
    mr_status status = next_line(ps, "'" MR_MLP_FILE_MAGIC " 1'");
    if (status != MR_OK) return status;
    const char *tok = ps->text.s;
    size_t len = 0;
    char shown[40];
    if (!token(ps, &tok, &len) || !mr_text_token_is(tok, len, MR_MLP_FILE_MAGIC))
        return bad(ps, "not an MLP weight file (expected '%s %d', found '%s')", MR_MLP_FILE_MAGIC, MR_MLP_FILE_VERSION,
                   excerpt(tok, len, shown, sizeof shown));
    if (!token(ps, &tok, &len)) return bad(ps, "no version after '%s'", MR_MLP_FILE_MAGIC);
    if (mr_text_token_is(tok, len, "1"))
        *version_out = 1;
    else if (mr_text_token_is(tok, len, "2"))
        *version_out = 2;
    else
        return bad(ps, "unsupported version '%s' (this build reads versions 1 to %d)",
                   excerpt(tok, len, shown, sizeof shown), MR_MLP_FILE_VERSION);
    if (token(ps, &tok, &len))
        return bad(ps, "unexpected '%s' after the version", excerpt(tok, len, shown, sizeof shown));
    return MR_OK;
}

static mr_status parse_net(parser *ps, mr_mlp **out) {
    int version = 0;
    mr_status status = read_magic(ps, &version);
    int n_in = 0, n_hidden = 0, n_out = 0;
    if (status == MR_OK) status = read_size(ps, "n_in", MR_MLP_MAX_IO, &n_in);
    if (status == MR_OK) status = read_size(ps, "n_hidden", MR_MLP_MAX_HIDDEN, &n_hidden);
    if (status == MR_OK) status = read_size(ps, "n_out", MR_MLP_MAX_IO, &n_out);
    if (status != MR_OK) return status;
    mr_status fits = mr_mlp_check_dims("shape", n_in, n_hidden, n_out);
    if (fits != MR_OK) return bad(ps, "%s", mr_last_error());
    status = next_line(ps, "'activation " ACTIVATIONS "'");
    if (status != MR_OK) return status;
    static const char *const activation_words[] = {"activation", "relu", "linear"};
    for (int w = 0; w < 4; w++) {
        const char *tok = ps->text.s;
        size_t len = 0;
        char shown[40];
        int got = token(ps, &tok, &len);
        if (w == 3 ? got : !got || !mr_text_token_is(tok, len, activation_words[w]))
            return bad(ps, "unsupported activations (expected 'activation " ACTIVATIONS "', found '%s')",
                       excerpt(tok, len, shown, sizeof shown));
    }
    char kind[MR_MLP_KIND_MAX] = "";
    if (version == 2) {
        status = next_line(ps, "'kind WORD'");
        if (status != MR_OK) return status;
        const char *tok = ps->text.s, *word = NULL;
        size_t len = 0, word_len = 0;
        char shown[40];
        int ok = token(ps, &tok, &len) && mr_text_token_is(tok, len, "kind") && token(ps, &word, &word_len) &&
                 word_len < MR_MLP_KIND_MAX && !token(ps, &tok, &len);
        for (size_t q = 0; ok && q < word_len; q++) ok = kind_char(word[q]);
        if (!ok)
            return bad(ps, "expected 'kind WORD' (a word of at most %d letters, digits, '.', '_' or '-'), found '%s'",
                       MR_MLP_KIND_MAX - 1, excerpt(ps->text.s - len, len, shown, sizeof shown));
        memcpy(kind, word, word_len);
        kind[word_len] = '\0';
    }
    mr_mlp *net = NULL;
    status = mr_mlp_create(n_in, n_hidden, n_out, &net);
    if (status != MR_OK) return status;
    memcpy(net->kind, kind, sizeof kind);
    const size_t I = (size_t)n_in, H = (size_t)n_hidden, O = (size_t)n_out;
    status = read_values(ps, "in_mean", net->in_mean, I, 0);
    if (status == MR_OK) status = read_values(ps, "in_std", net->in_std, I, 1);
    if (status == MR_OK) status = read_values(ps, "out_mean", net->out_mean, O, 0);
    if (status == MR_OK) status = read_values(ps, "out_std", net->out_std, O, 1);
    for (size_t i = 0; i < I && status == MR_OK; i++) status = read_values(ps, "w1", net->w1 + i * H, H, 0);
    if (status == MR_OK) status = read_values(ps, "b1", net->b1, H, 0);
    for (size_t k = 0; k < O && status == MR_OK; k++) status = read_values(ps, "w2", net->w2 + k * H, H, 0);
    if (status == MR_OK) status = read_values(ps, "b2", net->b2, O, 0);
    if (status == MR_OK) status = next_line(ps, "'end'");
    if (status == MR_OK && !mr_text_token_is(ps->text.s, (size_t)(ps->text.e - ps->text.s), "end")) {
        char shown[40];
        status = bad(ps, "expected 'end', found '%s'",
                     excerpt(ps->text.s, (size_t)(ps->text.e - ps->text.s), shown, sizeof shown));
    }
    if (status == MR_OK && ps->text.p < ps->text.end) {
        ps->text.line++;
        status = bad(ps, "unexpected content after 'end'");
    }
    if (status == MR_OK) status = mr_mlp_pack(net); // the inference kernels' layout, once (mlp.h, "Ownership")
    if (status != MR_OK) {
        mr_mlp_free(net);
        return status;
    }
    *out = net;
    return MR_OK;
}

mr_status mr_mlp_parse(const char *text, size_t size, const char *name, mr_mlp **out) {
    if (name == NULL) name = "<memory>";
    if (out == NULL) return mr_fail(MR_ERR_INVALID_ARG, "mlp weights '%s': NULL output pointer", name);
    if (text == NULL && size > 0) return mr_fail(MR_ERR_INVALID_ARG, "mlp weights '%s': NULL text", name);
    if (text == NULL) text = "";
    parser ps = {name, {0}};
    mr_text_lines_init(&ps.text, text, size);
    mr_c_numeric locale;
    mr_status status = mr_c_numeric_enter(&locale, "mlp read");
    if (status != MR_OK) return status;
    status = parse_net(&ps, out);
    mr_c_numeric_leave(&locale);
    return status;
}

mr_status mr_mlp_read(const char *path, mr_mlp **out) {
    if (path == NULL || path[0] == '\0') return mr_fail(MR_ERR_INVALID_ARG, "mlp read: empty path");
    if (out == NULL) return mr_fail(MR_ERR_INVALID_ARG, "mlp read '%s': NULL output pointer", path);
    FILE *in = NULL;
    char label[MR_IO_LABEL_SIZE + 16];
    snprintf(label, sizeof label, "mlp weights '%s'", path);
    mr_status opened = mr_io_open_input(path, label, 0, &in, NULL); /* regular files only: a FIFO would block */
    if (opened != MR_OK) return opened;
    size_t length = 0, capacity = 1 << 16;
    char *text = malloc(capacity);
    mr_status status = MR_OK;
    for (;;) {
        if (text == NULL) {
            status = mr_fail(MR_ERR_NOMEM, "mlp weights '%s': out of memory (%zu bytes)", path, capacity);
            break;
        }
        errno = 0;
        size_t got = fread(text + length, 1, capacity - length, in);
        length += got;
        if (got == 0 || length < capacity) {
            if (ferror(in)) {
                int err = errno ? errno : EIO;
                status = mr_fail(MR_ERR_IO, "mlp weights '%s': cannot read: %s", path, strerror(err));
            }
            if (status == MR_OK && !feof(in)) continue;
            break;
        }
        if (capacity >= MAX_FILE_BYTES) {
            status = mr_fail(MR_ERR_FORMAT, "mlp weights '%s': larger than %zu bytes, the most a network within the "
                             "size limits takes", path, (size_t)MAX_FILE_BYTES);
            break;
        }
        char *grown = realloc(text, MR_MIN(2 * capacity, (size_t)MAX_FILE_BYTES));
        if (grown == NULL) free(text);
        text = grown;
        capacity = MR_MIN(2 * capacity, (size_t)MAX_FILE_BYTES);
    }
    fclose(in);
    if (status == MR_OK) status = mr_mlp_parse(text, length, path, out);
    free(text);
    return status;
}
