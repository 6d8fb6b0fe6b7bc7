/*
 * mtlx_read.c — a MaterialX document read into the document model (doc.h: mr_doc_read_mtlx), over expat.
 *
 * The XML is parsed by expat (Debian's libexpat1-dev) into a small tree of elements (tag, attributes, line); a
 * document type declaration is refused before anything it declares is used (no entities, so no expansion), and the
 * tree is bounded (MAX_ELEMENTS elements, MAX_DEPTH levels, MAX_BYTES bytes). Then each top-level surfacematerial is
 * followed (docs/documents.md, "Reading MaterialX" has the table): its surfaceshader to a surface node of the four
 * models (open_pbr_surface, standard_surface, gltf_pbr, MaterialX's UsdPreviewSurface), whose inputs are constants
 * or connections, through a nodegraph's output (nodegraph=, output=) or a top-level node (nodename=), to the chains
 * the writer emits: image|tiledimage (+ texcoord) (+ extract) (+ multiply). Every element on the way is checked
 * against its node definition (mr_doc_node_inputs: input names and types); anything else a material uses is
 * MR_ERR_UNSUPPORTED naming the file, the line, the material and what cannot be followed. Elements no material
 * uses are not read.
 */
#include "doc/doc.h"

#include <ctype.h>
#include <errno.h>
#include <expat.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "c_locale.h"
#include "mr_core.h"
#include "mr_internal.h"

#define MAX_ELEMENTS 200000
#define MAX_DEPTH 64
#define MAX_BYTES (64u << 20)
#define MAX_CHAIN 8

/* ---- the element tree ------------------------------------------------------------------------------------- */
typedef struct elem {
    char *tag;
    char **attrs; /* name, value, ..., NULL */
    int line;
    int parent, first, last, next; /* indices, -1: none */
} elem;

typedef struct tree {
    elem *e;
    int count, capacity;
    int stack[MAX_DEPTH];
    int depth;
    int refused; /* 0, or why the parse was stopped: REFUSE_* */
    int refused_line;
    XML_Parser parser;
} tree;

enum { REFUSE_DTD = 1, REFUSE_COUNT, REFUSE_DEPTH, REFUSE_NOMEM };

static char *dup_text(const char *s) {
    size_t n = strlen(s) + 1;
    char *c = malloc(n);
    if (c) memcpy(c, s, n);
    return c;
}

static void stop(tree *t, int why) {
    if (t->refused) return;
    t->refused = why;
    t->refused_line = (int)XML_GetCurrentLineNumber(t->parser);
    XML_StopParser(t->parser, XML_FALSE);
}

static void XMLCALL on_start(void *data, const XML_Char *name, const XML_Char **atts) {
    tree *t = data;
    if (t->refused) return;
    if (t->depth >= MAX_DEPTH) { stop(t, REFUSE_DEPTH); return; }
    if (t->count >= MAX_ELEMENTS) { stop(t, REFUSE_COUNT); return; }
    if (t->count == t->capacity) {
        int capacity = t->capacity ? 2 * t->capacity : 64;
        elem *grown = realloc(t->e, (size_t)capacity * sizeof(*grown));
        if (grown == NULL) { stop(t, REFUSE_NOMEM); return; }
        t->e = grown;
        t->capacity = capacity;
    }
    int n = 0;
    while (atts[n]) n++;
    elem *e = &t->e[t->count];
    memset(e, 0, sizeof(*e));
    e->parent = e->first = e->last = e->next = -1;
    e->line = (int)XML_GetCurrentLineNumber(t->parser);
    e->tag = dup_text(name);
    e->attrs = calloc((size_t)n + 1, sizeof(char *));
    t->count++; // counted first: the free releases what was made
    if (e->tag == NULL || e->attrs == NULL) { stop(t, REFUSE_NOMEM); return; }
    for (int i = 0; i < n; i++)
        if ((e->attrs[i] = dup_text(atts[i])) == NULL) { stop(t, REFUSE_NOMEM); return; }
    int self = t->count - 1;
    if (t->depth > 0) {
        int parent = t->stack[t->depth - 1];
        e->parent = parent;
        if (t->e[parent].last >= 0)
            t->e[t->e[parent].last].next = self;
        else
            t->e[parent].first = self;
        t->e[parent].last = self;
    }
    t->stack[t->depth++] = self;
}

static void XMLCALL on_end(void *data, const XML_Char *name) {
    tree *t = data;
    (void)name;
    if (!t->refused && t->depth > 0) t->depth--;
}

static void XMLCALL on_doctype(void *data, const XML_Char *name, const XML_Char *sysid, const XML_Char *pubid,
                               int internal) {
    (void)name, (void)sysid, (void)pubid, (void)internal;
    stop(data, REFUSE_DTD);
}

static void tree_free(tree *t) {
    for (int i = 0; i < t->count; i++) {
        free(t->e[i].tag);
        if (t->e[i].attrs)
            for (char **a = t->e[i].attrs; *a; a++) free(*a);
        free(t->e[i].attrs);
    }
    free(t->e);
}

static const char *attr(const elem *e, const char *name) {
    for (char **a = e->attrs; a && a[0] && a[1]; a += 2)
        if (strcmp(a[0], name) == 0) return a[1];
    return NULL;
}

/* ---- the reader ------------------------------------------------------------------------------------------- */
typedef struct reader {
    const char *path;
    tree t;
    int root;
    const char *material; /* the material being read, for messages (NULL: none yet) */
} reader;

/* "MaterialX 'PATH' line L: material 'M': <message>" (without the material before one is read). */
static mr_status fail_at(reader *r, mr_status status, int el, const char *fmt, ...) {
    char message[768];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(message, sizeof message, fmt, ap);
    va_end(ap);
    int line = el >= 0 ? r->t.e[el].line : 0;
    if (r->material)
        return mr_fail(status, "MaterialX '%s' line %d: material '%s': %s", r->path, line, r->material, message);
    return mr_fail(status, "MaterialX '%s' line %d: %s", r->path, line, message);
}

static const char *name_of(reader *r, int el) {
    const char *n = attr(&r->t.e[el], "name");
    return n ? n : "";
}

/* The child of `scope` (an element) whose name attribute is `name`, -1 if none. */
static int find_named(reader *r, int scope, const char *name) {
    for (int c = r->t.e[scope].first; c >= 0; c = r->t.e[c].next)
        if (strcmp(r->t.e[c].tag, "input") != 0 && strcmp(r->t.e[c].tag, "output") != 0 &&
            strcmp(name_of(r, c), name) == 0)
            return c;
    return -1;
}

/* Attributes a node may carry that do not change what it computes: names, types, documentation and layout. */
static int harmless_attr(const char *a) {
    static const char *const names[] = {"name", "type", "doc", "xpos", "ypos", "width", "height", "nodedef"};
    for (size_t i = 0; i < sizeof(names) / sizeof(names[0]); i++)
        if (strcmp(a, names[i]) == 0) return 1;
    return strncmp(a, "ui", 2) == 0;
}

/* Every attribute of `el` harmless or among `allowed` (NULL-terminated); otherwise MR_ERR_UNSUPPORTED naming it. */
static mr_status check_attrs(reader *r, int el, const char *const *allowed) {
    const elem *e = &r->t.e[el];
    for (char **a = e->attrs; a && a[0] && a[1]; a += 2) {
        int ok = harmless_attr(a[0]);
        for (const char *const *x = allowed; !ok && x && *x; x++) ok = strcmp(a[0], *x) == 0;
        if (!ok)
            return fail_at(r, MR_ERR_UNSUPPORTED, el, "attribute %s=\"%s\" of <%s name=\"%s\"> is not followed",
                           a[0], a[1], e->tag, name_of(r, el));
    }
    return MR_OK;
}

/* Numbers "a, b, c" (commas, optional spaces) in the C locale: exactly n finite values. */
static int parse_numbers(const char *text, int n, double *out) {
    const char *s = text;
    for (int i = 0; i < n; i++) {
        while (isspace((unsigned char)*s)) s++;
        if (i > 0) {
            if (*s != ',') return 0;
            s++;
        }
        char *end = NULL;
        errno = 0;
        double v = strtod(s, &end);
        if (end == s || !isfinite(v) || errno == ERANGE) return 0;
        out[i] = v;
        s = end;
    }
    while (isspace((unsigned char)*s)) s++;
    return *s == '\0';
}

static int channels_of(const char *type) {
    return strcmp(type, "color3") == 0 || strcmp(type, "vector3") == 0 ? 3 : strcmp(type, "vector2") == 0 ? 2 : 1;
}

/* A value of a declared MaterialX type into out (float, color3, vector2, vector3, integer, boolean). */
static mr_status parse_value(reader *r, int el, const char *input, const char *type, const char *text, double *out) {
    if (strcmp(type, "boolean") == 0) {
        if (strcmp(text, "true") == 0 || strcmp(text, "false") == 0) {
            out[0] = text[0] == 't';
            return MR_OK;
        }
    } else if (strcmp(type, "integer") == 0) {
        char *end = NULL;
        errno = 0;
        long v = strtol(text, &end, 10);
        if (end != text && *end == '\0' && errno == 0 && v >= INT_MIN && v <= INT_MAX) {
            out[0] = (double)v;
            return MR_OK;
        }
    } else if (strcmp(type, "float") == 0 || strcmp(type, "color3") == 0 || strcmp(type, "vector2") == 0 ||
               strcmp(type, "vector3") == 0) {
        if (parse_numbers(text, channels_of(type), out)) return MR_OK;
    } else {
        return fail_at(r, MR_ERR_UNSUPPORTED, el, "input '%s' of type %s is not followed", input, type);
    }
    return fail_at(r, MR_ERR_FORMAT, el, "input '%s': \"%s\" is no %s value", input, text, type);
}

/* The declared type of `input` of the node definition `node` (mr_doc_node_inputs' key); NULL if not declared. */
static const char *declared_type(const char *node, const char *input) {
    int n = 0;
    const mr_doc_node_input *in = mr_doc_node_inputs(MR_DOC_FORMAT_MTLX, node, &n);
    for (int i = 0; i < n; i++)
        if (strcmp(in[i].name, input) == 0) return in[i].type;
    return NULL;
}

/* Every child of node `el` an <input> its definition `def` declares, with the declared type. */
static mr_status check_inputs(reader *r, int el, const char *def) {
    for (int c = r->t.e[el].first; c >= 0; c = r->t.e[c].next) {
        const elem *e = &r->t.e[c];
        if (strcmp(e->tag, "input") != 0)
            return fail_at(r, MR_ERR_UNSUPPORTED, c, "<%s> inside <%s name=\"%s\"> is not followed", e->tag,
                           r->t.e[el].tag, name_of(r, el));
        const char *name = attr(e, "name"), *type = attr(e, "type");
        if (name == NULL || type == NULL)
            return fail_at(r, MR_ERR_FORMAT, c, "an input of '%s' without a name or a type", name_of(r, el));
        const char *want = declared_type(def, name);
        if (want == NULL)
            return fail_at(r, MR_ERR_FORMAT, c, "input '%s' of '%s' is not in the node definition of %s", name,
                           name_of(r, el), r->t.e[el].tag);
        if (strcmp(want, type) != 0)
            return fail_at(r, MR_ERR_FORMAT, c, "input '%s' of '%s' is a %s: %s declares it %s", name,
                           name_of(r, el), type, r->t.e[el].tag, want);
        static const char *const input_attrs[] = {"value", "nodename", "nodegraph", "output", "colorspace",
                                                  "fileprefix", NULL};
        mr_status st = check_attrs(r, c, input_attrs);
        if (st != MR_OK) return st;
    }
    return MR_OK;
}

static int input_of(reader *r, int el, const char *name) {
    for (int c = r->t.e[el].first; c >= 0; c = r->t.e[c].next)
        if (strcmp(r->t.e[c].tag, "input") == 0 && strcmp(name_of(r, c), name) == 0) return c;
    return -1;
}

/* The nearest value of attribute `a` on `el` or an ancestor (NULL if none). */
static const char *inherited(reader *r, int el, const char *a) {
    for (; el >= 0; el = r->t.e[el].parent) {
        const char *v = attr(&r->t.e[el], a);
        if (v) return v;
    }
    return NULL;
}

/* What a chain of nodes reads: image|tiledimage (+ texcoord) (+ extract) (+ multiply). */
typedef struct chain {
    char file[4096];
    int srgb; /* the file's colour space: 1 srgb_texture, 0 lin_rec709 */
    int channel, uv_set;
    double scale[3];
    mr_doc_wrap wrap_s, wrap_t;
    int image_el;
} chain;

static mr_status follow(reader *r, int scope, const char *name, const char *type, int from, int depth, chain *c);

/* A connection of input element `in` inside scope `scope` (nodename=) to a node of type `type`. */
static mr_status follow_input(reader *r, int scope, int in, const char *type, int depth, chain *c) {
    const elem *e = &r->t.e[in];
    const char *node = attr(e, "nodename");
    if (attr(e, "output") || attr(e, "nodegraph"))
        return fail_at(r, MR_ERR_UNSUPPORTED, in, "input '%s' connects to a node's named output or a nested "
                       "nodegraph, which is not followed", name_of(r, in));
    if (node == NULL) return fail_at(r, MR_ERR_FORMAT, in, "input '%s' has no nodename", name_of(r, in));
    return follow(r, scope, node, type, in, depth + 1, c);
}

static mr_status follow_image(reader *r, int el, int tiled, chain *c) {
    const elem *e = &r->t.e[el];
    char def[64];
    snprintf(def, sizeof def, "%s_%s", e->tag, attr(e, "type"));
    static const char *const image_attrs[] = {"colorspace", "fileprefix", NULL};
    mr_status st = check_attrs(r, el, image_attrs);
    if (st == MR_OK) st = check_inputs(r, el, def);
    if (st != MR_OK) return st;
    int file = input_of(r, el, "file");
    const char *value = file >= 0 ? attr(&r->t.e[file], "value") : NULL;
    if (value == NULL || value[0] == '\0')
        return fail_at(r, MR_ERR_FORMAT, el, "image '%s' has no file", name_of(r, el));
    const char *prefix = inherited(r, file, "fileprefix");
    if (value[0] == '/') prefix = NULL;
    snprintf(c->file, sizeof c->file, "%s%s", prefix ? prefix : "", value);
    const char *space = inherited(r, file, "colorspace");
    if (space == NULL || strcmp(space, "lin_rec709") == 0)
        c->srgb = 0;
    else if (strcmp(space, "srgb_texture") == 0)
        c->srgb = 1;
    else
        return fail_at(r, MR_ERR_UNSUPPORTED, file, "file '%s' is in colour space '%s': export reads srgb_texture "
                       "and lin_rec709", value, space);
    c->image_el = el;
    for (int i = r->t.e[el].first; i >= 0; i = r->t.e[i].next) {
        const char *input = name_of(r, i), *v = attr(&r->t.e[i], "value");
        const char *link = attr(&r->t.e[i], "nodename");
        if (strcmp(input, "file") == 0 || strcmp(input, "filtertype") == 0 || strcmp(input, "default") == 0) {
            // file read above; the filter and the fallback colour of a missing file are not written (documents.md)
        } else if (strcmp(input, "uaddressmode") == 0 || strcmp(input, "vaddressmode") == 0) {
            mr_doc_wrap w = MR_DOC_WRAP_UNSET;
            if (v && strcmp(v, "periodic") == 0) w = MR_DOC_WRAP_REPEAT;
            else if (v && strcmp(v, "clamp") == 0) w = MR_DOC_WRAP_CLAMP;
            else if (v && strcmp(v, "mirror") == 0) w = MR_DOC_WRAP_MIRROR;
            else
                return fail_at(r, MR_ERR_UNSUPPORTED, i, "%s \"%s\" of image '%s' is not followed (periodic, clamp, "
                               "mirror)", input, v ? v : "(connected)", name_of(r, el));
            *(input[0] == 'u' ? &c->wrap_s : &c->wrap_t) = w;
        } else if (strcmp(input, "texcoord") == 0 && link) {
            int tc = find_named(r, r->t.e[el].parent, link);
            if (tc < 0) return fail_at(r, MR_ERR_FORMAT, i, "no node '%s' for the texcoord of '%s'", link,
                                       name_of(r, el));
            const elem *te = &r->t.e[tc];
            if (strcmp(te->tag, "texcoord") != 0 || attr(te, "type") == NULL ||
                strcmp(attr(te, "type"), "vector2") != 0)
                return fail_at(r, MR_ERR_UNSUPPORTED, tc, "node '%s' is a %s %s, which export does not follow as "
                               "texture coordinates (it follows texcoord)", link, attr(te, "type") ? attr(te, "type")
                               : "", te->tag);
            if ((st = check_attrs(r, tc, NULL)) != MR_OK || (st = check_inputs(r, tc, "texcoord_vector2")) != MR_OK)
                return st;
            int index = input_of(r, tc, "index");
            double uv = 0;
            if (index >= 0) {
                const char *iv = attr(&r->t.e[index], "value");
                if (iv == NULL)
                    return fail_at(r, MR_ERR_UNSUPPORTED, index, "the index of texcoord '%s' is connected", link);
                if ((st = parse_value(r, index, "index", "integer", iv, &uv)) != MR_OK) return st;
                if (uv < 0) return fail_at(r, MR_ERR_FORMAT, index, "texcoord '%s': index %d", link, (int)uv);
            }
            c->uv_set = (int)uv;
        } else if (tiled && (strcmp(input, "uvtiling") == 0 || strcmp(input, "uvoffset") == 0) && v && !link) {
            double t[2];
            if ((st = parse_value(r, i, input, "vector2", v, t)) != MR_OK) return st;
            double identity = input[2] == 't' ? 1.0 : 0.0;
            if (t[0] != identity || t[1] != identity)
                return fail_at(r, MR_ERR_UNSUPPORTED, i, "%s \"%s\" of tiledimage '%s': tiling and offsets are not "
                               "carried", input, v, name_of(r, el));
        } else if (strcmp(input, "layer") == 0 && v && v[0] == '\0') {
        } else {
            return fail_at(r, MR_ERR_UNSUPPORTED, i, "input '%s' of %s '%s' is not followed", input, r->t.e[el].tag,
                           name_of(r, el));
        }
    }
    return MR_OK;
}

/* Node `name` in `scope`, of output type `type`, read into c; `from` the input that connects to it (messages). */
static mr_status follow(reader *r, int scope, const char *name, const char *type, int from, int depth, chain *c) {
    if (depth > MAX_CHAIN)
        return fail_at(r, MR_ERR_UNSUPPORTED, from, "a chain of more than %d nodes is not followed", MAX_CHAIN);
    int el = find_named(r, scope, name);
    if (el < 0)
        return fail_at(r, MR_ERR_FORMAT, from, "no node '%s'%s%s", name, scope == r->root ? "" : " in nodegraph ",
                       scope == r->root ? "" : name_of(r, scope));
    const elem *e = &r->t.e[el];
    const char *node_type = attr(e, "type");
    static const char *const followed = "it follows image, tiledimage, extract, multiply and texcoord in a nodegraph "
                                        "or at the top level";
    int image = strcmp(e->tag, "image") == 0, tiled = strcmp(e->tag, "tiledimage") == 0;
    if (!image && !tiled && strcmp(e->tag, "extract") != 0 && strcmp(e->tag, "multiply") != 0)
        return fail_at(r, MR_ERR_UNSUPPORTED, el, "node '%s' is a %s, which export cannot follow (%s)", name, e->tag,
                       followed);
    if (node_type == NULL || strcmp(node_type, type) != 0)
        return fail_at(r, MR_ERR_UNSUPPORTED, el, "node '%s' is a %s %s where a %s is read: export cannot follow it "
                       "(%s)", name, node_type ? node_type : "(untyped)", e->tag, type, followed);
    if (image || tiled) return follow_image(r, el, tiled, c);
    mr_status st = check_attrs(r, el, NULL);
    if (st != MR_OK) return st;
    if (strcmp(e->tag, "extract") == 0) {
        int in = input_of(r, el, "in"), index = input_of(r, el, "index");
        const char *in_type = in >= 0 ? attr(&r->t.e[in], "type") : NULL;
        if (in_type == NULL || (strcmp(in_type, "color3") != 0 && strcmp(in_type, "color4") != 0))
            return fail_at(r, MR_ERR_UNSUPPORTED, el, "extract '%s' from a %s is not followed (color3, color4)",
                           name, in_type ? in_type : "(nothing)");
        char def[32];
        snprintf(def, sizeof def, "extract_%s", in_type);
        if ((st = check_inputs(r, el, def)) != MR_OK) return st;
        double k = 0;
        const char *v = index >= 0 ? attr(&r->t.e[index], "value") : "0";
        if (v == NULL) return fail_at(r, MR_ERR_UNSUPPORTED, index, "the index of extract '%s' is connected", name);
        if ((st = parse_value(r, index >= 0 ? index : el, "index", "integer", v, &k)) != MR_OK) return st;
        if (k < 0 || k >= (strcmp(in_type, "color4") == 0 ? 4 : 3))
            return fail_at(r, MR_ERR_FORMAT, el, "extract '%s': index %d of a %s", name, (int)k, in_type);
        if (c->channel != -1)
            return fail_at(r, MR_ERR_UNSUPPORTED, el, "extract '%s' of an extract is not followed", name);
        c->channel = (int)k;
        return follow_input(r, scope, in, in_type, depth, c);
    }
    // multiply: one input a connection, the other a constant of the same type (the scale)
    char def[32];
    snprintf(def, sizeof def, "multiply_%s", type);
    if (strcmp(type, "float") != 0 && strcmp(type, "color3") != 0)
        return fail_at(r, MR_ERR_UNSUPPORTED, el, "multiply '%s' of %s is not followed", name, type);
    if ((st = check_inputs(r, el, def)) != MR_OK) return st;
    int in1 = input_of(r, el, "in1"), in2 = input_of(r, el, "in2");
    if (in1 < 0 || in2 < 0) return fail_at(r, MR_ERR_UNSUPPORTED, el, "multiply '%s' without in1 and in2", name);
    int linked = attr(&r->t.e[in1], "value") ? in2 : in1, constant = linked == in1 ? in2 : in1;
    const char *v = attr(&r->t.e[constant], "value");
    if (v == NULL)
        return fail_at(r, MR_ERR_UNSUPPORTED, el, "multiply '%s' of two connections is not followed (one input is "
                       "a constant scale)", name);
    double s[3] = {1, 1, 1};
    if ((st = parse_value(r, constant, name_of(r, constant), type, v, s)) != MR_OK) return st;
    int n = channels_of(type);
    for (int k = 0; k < n; k++) c->scale[k] *= s[k];
    return follow_input(r, scope, linked, type, depth, c);
}

/* ---- the one place that decides whether a map's colour space is what the writers write ---------------------- */
static mr_status check_colour_space(reader *r, const mr_brdf_param *p, const char *input, const chain *c) {
    int want = mr_doc_texture_is_srgb(p, c->file);
    if (want == c->srgb) return MR_OK;
    return fail_at(r, MR_ERR_UNSUPPORTED, c->image_el, "input '%s' reads '%s' as %s; matremap's documents read it as "
                   "%s (the one rule of parameter maps: colour maps of 8/16-bit files srgb_texture, everything else "
                   "lin_rec709), so it cannot be carried unchanged", input, c->file,
                   c->srgb ? "srgb_texture" : "lin_rec709", want ? "srgb_texture" : "lin_rec709");
}

/* The model a surface node of MaterialX is read as; NULL when none. */
static const mr_brdf_model *model_of(const char *tag) {
    if (strcmp(tag, "open_pbr_surface") == 0) return mr_brdf_find("openpbr");
    if (strcmp(tag, "standard_surface") == 0) return mr_brdf_find("standard-surface");
    if (strcmp(tag, "gltf_pbr") == 0) return mr_brdf_find("gltf");
    if (strcmp(tag, "UsdPreviewSurface") == 0) return mr_brdf_find("usd-preview");
    return NULL;
}

/* The nodedef a node may name: the definition the tables hold (ND_<node>_surfaceshader), no other version. */
static int default_nodedef(const char *tag, const char *nodedef) {
    char want[96];
    snprintf(want, sizeof want, "ND_%s_surfaceshader", tag);
    return strcmp(nodedef, want) == 0;
}

/* One input of the surface node: a constant or a map of a model parameter, or an extra constant. */
static mr_status read_shader_input(reader *r, int in, const char *tag, mr_doc_material *m) {
    const elem *e = &r->t.e[in];
    const char *input = attr(e, "name"), *type = attr(e, "type"), *value = attr(e, "value");
    const mr_brdf_model *model = m->model;
    mr_doc_format names = strcmp(model->name, "usd-preview") == 0 ? MR_DOC_FORMAT_USDA : MR_DOC_FORMAT_MTLX;
    int p = -1;
    for (int k = 0; k < model->param_count && p < 0; k++)
        if (strcmp(mr_doc_input_name(model, k, names), input) == 0) p = k;
    if (attr(e, "interfacename"))
        return fail_at(r, MR_ERR_UNSUPPORTED, in, "input '%s' of '%s' uses interfacename, which is not followed",
                       input, name_of(r, e->parent));
    if (value != NULL && (attr(e, "nodename") || attr(e, "nodegraph")))
        return fail_at(r, MR_ERR_FORMAT, in, "input '%s' has both a value and a connection", input);
    mr_status st;
    if (value != NULL) {
        double v[3] = {0, 0, 0};
        if ((st = parse_value(r, in, input, type, value, v)) != MR_OK) return st;
        if (p >= 0) {
            st = mr_doc_set_constant(m, model->params[p].name, v);
            return st == MR_OK ? st : fail_at(r, st, in, "%s", mr_last_error());
        }
        st = mr_doc_add_extra(m, input, type, v);
        return st == MR_OK ? st : fail_at(r, st, in, "%s", mr_last_error());
    }
    const char *graph = attr(e, "nodegraph"), *node = attr(e, "nodename");
    if (graph == NULL && node == NULL)
        return fail_at(r, MR_ERR_FORMAT, in, "input '%s' has neither a value nor a connection", input);
    if (p < 0)
        return fail_at(r, MR_ERR_UNSUPPORTED, in, "input '%s' of %s '%s' is connected to a node: maps are carried only "
                       "for the parameters of matremap's %s model", input, tag, name_of(r, e->parent), model->name);
    const mr_brdf_param *d = &model->params[p];
    if (d->role == MR_PARAM_SWITCH)
        return fail_at(r, MR_ERR_UNSUPPORTED, in, "input '%s' is a switch connected to a node", input);
    chain c;
    memset(&c, 0, sizeof c);
    c.channel = -1;
    c.scale[0] = c.scale[1] = c.scale[2] = 1;
    if (graph != NULL) {
        int g = find_named(r, r->root, graph);
        if (g < 0) return fail_at(r, MR_ERR_FORMAT, in, "input '%s': no nodegraph '%s'", input, graph);
        const elem *ge = &r->t.e[g];
        if (strcmp(ge->tag, "nodegraph") != 0)
            return fail_at(r, MR_ERR_FORMAT, in, "input '%s': '%s' is a %s, not a nodegraph", input, graph, ge->tag);
        static const char *const graph_attrs[] = {"colorspace", "fileprefix", NULL};
        if (attr(ge, "nodedef"))
            return fail_at(r, MR_ERR_UNSUPPORTED, g, "nodegraph '%s' implements a node definition (%s), which is not "
                           "followed", graph, attr(ge, "nodedef"));
        if ((st = check_attrs(r, g, graph_attrs)) != MR_OK) return st;
        const char *out_name = attr(e, "output");
        int out = -1, outputs = 0;
        for (int k = ge->first; k >= 0; k = r->t.e[k].next) {
            if (strcmp(r->t.e[k].tag, "input") == 0)
                return fail_at(r, MR_ERR_UNSUPPORTED, k, "nodegraph '%s' has interface inputs, which are not "
                               "followed", graph);
            if (strcmp(r->t.e[k].tag, "output") != 0) continue;
            outputs++;
            if (out_name == NULL || strcmp(name_of(r, k), out_name) == 0) out = k;
        }
        if (out < 0 || (out_name == NULL && outputs != 1))
            return fail_at(r, MR_ERR_FORMAT, in, "input '%s': nodegraph '%s' has no output '%s'", input, graph,
                           out_name ? out_name : "(unnamed: it has several)");
        const elem *oe = &r->t.e[out];
        static const char *const output_attrs[] = {"nodename", NULL};
        if ((st = check_attrs(r, out, output_attrs)) != MR_OK) return st;
        if (attr(oe, "type") == NULL || strcmp(attr(oe, "type"), type) != 0)
            return fail_at(r, MR_ERR_FORMAT, out, "output '%s' of nodegraph '%s' is a %s, input '%s' a %s",
                           name_of(r, out), graph, attr(oe, "type") ? attr(oe, "type") : "(untyped)", input, type);
        if (attr(oe, "nodename") == NULL)
            return fail_at(r, MR_ERR_UNSUPPORTED, out, "output '%s' of nodegraph '%s' connects to no node",
                           name_of(r, out), graph);
        st = follow(r, g, attr(oe, "nodename"), type, out, 1, &c);
    } else {
        st = follow(r, r->root, node, type, in, 1, &c);
        if (st == MR_OK && attr(e, "output") && strcmp(attr(e, "output"), "out") != 0)
            return fail_at(r, MR_ERR_UNSUPPORTED, in, "input '%s' connects to output '%s' of node '%s', which is not "
                           "followed", input, attr(e, "output"), node);
    }
    if (st != MR_OK) return st;
    if (d->channels == 3 && c.channel != -1)
        return fail_at(r, MR_ERR_FORMAT, in, "input '%s' is a colour read from one channel", input);
    if ((st = check_colour_space(r, d, input, &c)) != MR_OK) return st;
    if ((st = mr_doc_set_texture(m, d->name, c.file, c.channel, c.uv_set, c.scale)) != MR_OK ||
        ((c.wrap_s || c.wrap_t) && (st = mr_doc_set_texture_wrap(m, d->name, c.wrap_s, c.wrap_t)) != MR_OK))
        return fail_at(r, st, in, "%s", mr_last_error());
    return MR_OK;
}

static mr_status read_material(reader *r, int el, mr_doc *doc) {
    const elem *e = &r->t.e[el];
    const char *name = attr(e, "name");
    if (name == NULL) return fail_at(r, MR_ERR_FORMAT, el, "a surfacematerial without a name");
    r->material = name;
    mr_status st;
    if (attr(e, "type") == NULL || strcmp(attr(e, "type"), "material") != 0)
        return fail_at(r, MR_ERR_FORMAT, el, "surfacematerial '%s' is not of type material", name);
    if (attr(e, "nodedef") && strcmp(attr(e, "nodedef"), "ND_surfacematerial") != 0)
        return fail_at(r, MR_ERR_UNSUPPORTED, el, "nodedef '%s' is not followed", attr(e, "nodedef"));
    if ((st = check_attrs(r, el, NULL)) != MR_OK || (st = check_inputs(r, el, "surfacematerial")) != MR_OK) return st;
    int shader_in = -1;
    for (int c = e->first; c >= 0; c = r->t.e[c].next) {
        const char *input = name_of(r, c), *value = attr(&r->t.e[c], "value");
        int linked = attr(&r->t.e[c], "nodename") || attr(&r->t.e[c], "nodegraph");
        if (strcmp(input, "surfaceshader") == 0)
            shader_in = c;
        else if (linked || (value && value[0]))
            return fail_at(r, MR_ERR_UNSUPPORTED, c, "its %s is not followed (only surfaceshader)", input);
    }
    const char *shader = shader_in >= 0 ? attr(&r->t.e[shader_in], "nodename") : NULL;
    if (shader == NULL) return fail_at(r, MR_ERR_FORMAT, el, "no surfaceshader nodename");
    if (attr(&r->t.e[shader_in], "output"))
        return fail_at(r, MR_ERR_UNSUPPORTED, shader_in, "a surfaceshader from output '%s' is not followed",
                       attr(&r->t.e[shader_in], "output"));
    int node = find_named(r, r->root, shader);
    if (node < 0) return fail_at(r, MR_ERR_FORMAT, shader_in, "no node '%s' for its surfaceshader", shader);
    const elem *ne = &r->t.e[node];
    const mr_brdf_model *model = model_of(ne->tag);
    if (model == NULL)
        return fail_at(r, MR_ERR_UNSUPPORTED, node, "its surface shader '%s' is a %s, which export cannot follow (it "
                       "reads open_pbr_surface, standard_surface, gltf_pbr and UsdPreviewSurface)", shader, ne->tag);
    if (attr(ne, "type") == NULL || strcmp(attr(ne, "type"), "surfaceshader") != 0)
        return fail_at(r, MR_ERR_FORMAT, node, "node '%s' is not of type surfaceshader", shader);
    if (attr(ne, "nodedef") && !default_nodedef(ne->tag, attr(ne, "nodedef")))
        return fail_at(r, MR_ERR_UNSUPPORTED, node, "nodedef '%s' of '%s' is not followed (ND_%s_surfaceshader)",
                       attr(ne, "nodedef"), shader, ne->tag);
    if ((st = check_attrs(r, node, NULL)) != MR_OK || (st = check_inputs(r, node, ne->tag)) != MR_OK) return st;
    mr_doc_material *m = NULL;
    if ((st = mr_doc_add_material(doc, name, model, &m)) != MR_OK) return st;
    for (int c = ne->first; c >= 0 && st == MR_OK; c = r->t.e[c].next) st = read_shader_input(r, c, ne->tag, m);
    return st;
}

static mr_status read_tree(reader *r, mr_doc *doc) {
    const elem *root = &r->t.e[r->root];
    if (strcmp(root->tag, "materialx") != 0)
        return fail_at(r, MR_ERR_FORMAT, r->root, "the root element is <%s>, not <materialx>", root->tag);
    const char *version = attr(root, "version");
    if (version == NULL || (strcmp(version, "1.38") != 0 && strcmp(version, "1.39") != 0))
        return fail_at(r, MR_ERR_UNSUPPORTED, r->root, "version \"%s\": export reads MaterialX 1.38 and 1.39",
                       version ? version : "(none)");
    const char *space = attr(root, "colorspace");
    if (space && space[0] && strcmp(space, "lin_rec709") != 0)
        return fail_at(r, MR_ERR_UNSUPPORTED, r->root, "working colour space '%s': export reads lin_rec709", space);
    int materials = 0;
    mr_status st = MR_OK;
    for (int c = root->first; c >= 0 && st == MR_OK; c = r->t.e[c].next) {
        const char *tag = r->t.e[c].tag;
        if (strcmp(tag, "xi:include") == 0)
            st = fail_at(r, MR_ERR_UNSUPPORTED, c, "xi:include \"%s\": included documents are not read",
                         attr(&r->t.e[c], "href") ? attr(&r->t.e[c], "href") : "");
        else if (strcmp(tag, "look") == 0 || strcmp(tag, "lookgroup") == 0)
            st = fail_at(r, MR_ERR_UNSUPPORTED, c, "%s '%s': looks and their material assignments are not read", tag,
                         name_of(r, c));
    }
    for (int c = root->first; c >= 0 && st == MR_OK; c = r->t.e[c].next)
        if (strcmp(r->t.e[c].tag, "surfacematerial") == 0) {
            r->material = NULL;
            st = read_material(r, c, doc);
            materials++;
        }
    r->material = NULL;
    if (st == MR_OK && materials == 0)
        st = fail_at(r, MR_ERR_FORMAT, r->root, "no surfacematerial to read");
    return st;
}

mr_status mr_doc_read_mtlx(const char *path, mr_doc **out) {
    if (path == NULL || out == NULL) return mr_fail(MR_ERR_INVALID_ARG, "MaterialX: no path or output");
    *out = NULL;
    char label[MR_IO_LABEL_SIZE];
    snprintf(label, sizeof label, "MaterialX '%s'", path);
    FILE *f = NULL;
    uint64_t size = 0;
    mr_status st = mr_io_open_input(path, label, MAX_BYTES, &f, &size);
    if (st != MR_OK) return st;
    char *bytes = malloc(size > 0 ? (size_t)size : 1);
    if (bytes == NULL) {
        fclose(f);
        return mr_fail(MR_ERR_NOMEM, "%s: out of memory", label);
    }
    size_t got = fread(bytes, 1, (size_t)size, f);
    int bad = ferror(f);
    fclose(f);
    if (bad || got != (size_t)size) {
        free(bytes);
        return mr_fail(MR_ERR_IO, "%s: cannot read", label);
    }
    reader r;
    memset(&r, 0, sizeof r);
    r.path = path;
    r.t.parser = XML_ParserCreate("UTF-8");
    if (r.t.parser == NULL) {
        free(bytes);
        return mr_fail(MR_ERR_NOMEM, "%s: out of memory", label);
    }
    XML_SetUserData(r.t.parser, &r.t);
    XML_SetElementHandler(r.t.parser, on_start, on_end);
    XML_SetStartDoctypeDeclHandler(r.t.parser, on_doctype);
    enum XML_Status parsed = XML_Parse(r.t.parser, bytes, (int)got, XML_TRUE);
    free(bytes);
    if (r.t.refused == REFUSE_NOMEM)
        st = mr_fail(MR_ERR_NOMEM, "%s: out of memory", label);
    else if (r.t.refused)
        st = mr_fail(r.t.refused == REFUSE_DTD ? MR_ERR_UNSUPPORTED : MR_ERR_FORMAT, "%s line %d: %s", label,
                     r.t.refused_line, r.t.refused == REFUSE_DTD ? "a document type declaration (DOCTYPE) is not read"
                     : r.t.refused == REFUSE_COUNT ? "more than 200000 elements"
                                                   : "elements nested more than 64 deep");
    else if (parsed != XML_STATUS_OK)
        st = mr_fail(MR_ERR_FORMAT, "%s line %d: not well-formed XML: %s", label,
                     (int)XML_GetCurrentLineNumber(r.t.parser), XML_ErrorString(XML_GetErrorCode(r.t.parser)));
    XML_ParserFree(r.t.parser);
    r.t.parser = NULL;
    mr_doc *doc = NULL;
    mr_c_numeric numeric;
    int entered = 0;
    if (st == MR_OK && r.t.count == 0) st = mr_fail(MR_ERR_FORMAT, "%s: no element", label);
    if (st == MR_OK && (doc = mr_doc_create()) == NULL) st = mr_fail(MR_ERR_NOMEM, "%s: out of memory", label);
    if (st == MR_OK && (st = mr_c_numeric_enter(&numeric, label)) == MR_OK) entered = 1;
    if (st == MR_OK) st = read_tree(&r, doc);
    if (entered) mr_c_numeric_leave(&numeric);
    tree_free(&r.t);
    if (st != MR_OK) {
        mr_doc_free(doc);
        return st;
    }
    *out = doc;
    return MR_OK;
}
