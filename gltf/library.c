/*
 * library.c — many glTF assets converted in one call (mr_gltf_library.h): listing (files, folders, globs), the
 * parallel loop over mr_gltf_convert_file, resume and shards, thumbnails and object SSIM, summary.json and
 * index.html.
 */
#define _XOPEN_SOURCE 700 /* realpath */
#include "gltf/mr_gltf_library.h"

#include <dirent.h>
#include <errno.h>
#include <glob.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <time.h>

#include "gltf/mr_gltf_scene.h"
#include "io/image_io.h"
#include "metrics/metrics.h"
#include "mr_internal.h"
#include "render/render.h"

#ifdef _OPENMP
#include <omp.h>
#endif

#define SUMMARY_MARK "{\"writer\": \"matremap gltf library\","
#define INDEX_MARK "<!DOCTYPE html><!-- matremap gltf library -->"

/* ---- strings and paths ---------------------------------------------------------------------------------------- */

static char *dup_str(const char *s) {
    size_t n = strlen(s) + 1;
    char *d = malloc(n);
    if (d) memcpy(d, s, n);
    return d;
}

static char *join(const char *a, const char *b) {
    size_t n = strlen(a) + strlen(b) + 2;
    char *d = malloc(n);
    if (d) snprintf(d, n, "%s/%s", a, b);
    return d;
}

static double now_seconds(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int is_asset_name(const char *name) {
    size_t n = strlen(name);
    return (n > 5 && strcasecmp(name + n - 5, ".gltf") == 0) || (n > 4 && strcasecmp(name + n - 4, ".glb") == 0);
}

/* mkdir -p of the folder holding `path` (dir_only 0) or of `path` itself. */
static mr_status make_folders(const char *path, int dir_only) {
    char *p = dup_str(path);
    if (!p) return mr_fail(MR_ERR_NOMEM, "out of memory");
    if (!dir_only) {
        char *slash = strrchr(p, '/');
        if (!slash) {
            free(p);
            return MR_OK;
        }
        *slash = '\0';
    }
    for (char *c = p + 1;; c++) {
        if (*c == '/' || *c == '\0') {
            char saved = *c;
            *c = '\0';
            struct stat st;
            if (stat(p, &st) != 0 && mkdir(p, 0777) != 0 && errno != EEXIST) {
                mr_status s = mr_fail(MR_ERR_IO, "cannot create the folder '%s': %s", p, strerror(errno));
                free(p);
                return s;
            }
            *c = saved;
            if (saved == '\0') break;
        }
    }
    free(p);
    return MR_OK;
}

/* realpath of `path` when it exists; else of its deepest existing ancestor with the rest appended. */
static char *absolute_path(const char *path) {
    char *copy = dup_str(path), *rest = NULL;
    if (!copy) return NULL;
    for (;;) {
        char *resolved = realpath(copy[0] ? copy : ".", NULL);
        if (resolved) {
            char *full = rest ? join(resolved, rest) : resolved;
            if (rest) free(resolved);
            free(copy);
            free(rest);
            return full;
        }
        char *slash = strrchr(copy, '/');
        const char *tail = slash ? slash + 1 : copy;
        char *joined = rest ? join(tail, rest) : dup_str(tail);
        free(rest);
        rest = joined;
        if (!slash) copy[0] = '\0';
        else if (slash == copy) copy[1] = '\0';
        else *slash = '\0';
        if (!rest) {
            free(copy);
            return NULL;
        }
    }
}

/* ---- listing ---------------------------------------------------------------------------------------------------- */

typedef struct strlist {
    char **items;
    int count, capacity;
} strlist;

static mr_status push(strlist *l, char *s) {
    if (!s) return mr_fail(MR_ERR_NOMEM, "out of memory listing the assets");
    if (l->count == l->capacity) {
        int cap = l->capacity ? 2 * l->capacity : 16;
        char **n = realloc(l->items, (size_t)cap * sizeof *n);
        if (!n) {
            free(s);
            return mr_fail(MR_ERR_NOMEM, "out of memory listing the assets");
        }
        l->items = n;
        l->capacity = cap;
    }
    l->items[l->count++] = s;
    return MR_OK;
}

static void strlist_free(strlist *l) {
    for (int i = 0; i < l->count; i++) free(l->items[i]);
    free(l->items);
    memset(l, 0, sizeof *l);
}

static mr_status walk(const char *dir, strlist *out, int depth) {
    if (depth > 64) return mr_fail(MR_ERR_IO, "folder '%s': nested more than 64 levels", dir);
    DIR *d = opendir(dir);
    if (!d) return mr_fail(MR_ERR_IO, "folder '%s': cannot open: %s", dir, strerror(errno));
    mr_status s = MR_OK;
    struct dirent *e;
    while (s == MR_OK && (e = readdir(d)) != NULL) {
        if (e->d_name[0] == '.') continue;
        char *p = join(dir, e->d_name);
        struct stat st;
        if (!p) s = mr_fail(MR_ERR_NOMEM, "out of memory listing the assets");
        else if (stat(p, &st) != 0) free(p);
        else if (S_ISDIR(st.st_mode)) {
            s = walk(p, out, depth + 1);
            free(p);
        } else if (S_ISREG(st.st_mode) && is_asset_name(e->d_name)) {
            s = push(out, p);
        } else {
            free(p);
        }
    }
    closedir(d);
    return s;
}

static int cmp_str(const void *a, const void *b) { return strcmp(*(char *const *)a, *(char *const *)b); }

/* `path` without trailing slashes ("/" stays); owned. */
static char *trimmed(const char *path) {
    char *p = dup_str(path);
    if (!p) return NULL;
    size_t n = strlen(p);
    while (n > 1 && p[n - 1] == '/') p[--n] = '\0';
    return p;
}

static mr_status list_one(const char *input, strlist *out, strlist *folders);

/* One input: a file, a folder, or a glob; folders found go into *folders (may be NULL). */
static mr_status list_one_trimmed(const char *input, strlist *out, strlist *folders) {
    struct stat st;
    if (stat(input, &st) == 0) {
        if (S_ISDIR(st.st_mode)) {
            size_t before = (size_t)out->count;
            if (folders) {
                mr_status s = push(folders, dup_str(input));
                if (s != MR_OK) return s;
            }
            mr_status s = walk(input, out, 0);
            if (s == MR_OK && (size_t)out->count == before)
                return mr_fail(MR_ERR_IO, "folder '%s' holds no .gltf or .glb asset", input);
            return s;
        }
        return push(out, dup_str(input));
    }
    if (strpbrk(input, "*?[") != NULL) {
        glob_t g;
        int r = glob(input, 0, NULL, &g);
        if (r != 0) {
            if (r != GLOB_NOMATCH) globfree(&g);
            return mr_fail(MR_ERR_IO, "'%s' matches no file", input);
        }
        mr_status s = MR_OK;
        size_t before = (size_t)out->count;
        for (size_t i = 0; s == MR_OK && i < g.gl_pathc; i++) {
            struct stat m;
            if (stat(g.gl_pathv[i], &m) != 0) continue;
            if (S_ISDIR(m.st_mode)) s = list_one(g.gl_pathv[i], out, folders);
            else if (is_asset_name(g.gl_pathv[i])) s = push(out, dup_str(g.gl_pathv[i]));
        }
        globfree(&g);
        if (s == MR_OK && (size_t)out->count == before)
            return mr_fail(MR_ERR_IO, "'%s' matches no .gltf or .glb asset", input);
        return s;
    }
    return mr_fail(MR_ERR_IO, "asset '%s': %s", input, strerror(errno));
}

static mr_status list_one(const char *input, strlist *out, strlist *folders) {
    char *t = trimmed(input);
    if (!t) return mr_fail(MR_ERR_NOMEM, "out of memory listing the assets");
    mr_status s = list_one_trimmed(t, out, folders);
    free(t);
    return s;
}

/* The deepest folder holding every path ("." when they are relative and share none). */
static char *common_root(char **paths, int n) {
    char *root = dup_str(paths[0]);
    if (!root) return NULL;
    char *slash = strrchr(root, '/');
    if (!slash) {
        free(root);
        return dup_str(".");
    }
    *slash = '\0';
    if (root[0] == '\0') strcpy(root, "/");
    for (int i = 1; i < n; i++) {
        for (;;) {
            size_t len = strlen(root);
            if (strcmp(root, "/") == 0 || (strncmp(paths[i], root, len) == 0 && paths[i][len] == '/')) break;
            char *s = strrchr(root, '/');
            if (!s) {
                free(root);
                return dup_str(".");
            }
            if (s == root) s[1] = '\0';
            else *s = '\0';
        }
    }
    return root;
}

static mr_status list_all(const char *const *inputs, int input_count, char ***assets, int *count, char **root,
                          strlist *folders) {
    *assets = NULL;
    *count = 0;
    *root = NULL;
    if (!inputs || input_count <= 0) return mr_fail(MR_ERR_INVALID_ARG, "no input asset");
    strlist l = {0};
    mr_status s = MR_OK;
    for (int i = 0; s == MR_OK && i < input_count; i++) s = list_one(inputs[i], &l, folders);
    if (s != MR_OK) {
        strlist_free(&l);
        return s;
    }
    qsort(l.items, (size_t)l.count, sizeof *l.items, cmp_str);
    int n = 0;
    for (int i = 0; i < l.count; i++) {
        if (n > 0 && strcmp(l.items[n - 1], l.items[i]) == 0) free(l.items[i]);
        else l.items[n++] = l.items[i];
    }
    l.count = n;
    *root = common_root(l.items, n);
    if (!*root) {
        strlist_free(&l);
        return mr_fail(MR_ERR_NOMEM, "out of memory listing the assets");
    }
    *assets = l.items;
    *count = n;
    return MR_OK;
}

mr_status mr_gltf_library_list(const char *const *inputs, int input_count, char ***assets, int *count, char **root) {
    if (!assets || !count || !root) return mr_fail(MR_ERR_INVALID_ARG, "mr_gltf_library_list: NULL output");
    return list_all(inputs, input_count, assets, count, root, NULL);
}

void mr_gltf_library_list_free(char **assets, int count, char *root) {
    for (int i = 0; assets && i < count; i++) free(assets[i]);
    free(assets);
    free(root);
}

/* ---- JSON helpers ------------------------------------------------------------------------------------------------ */

typedef struct buf {
    char *s;
    size_t len, cap;
    int nomem;
} buf;

static void bputn(buf *b, const char *s, size_t n) {
    if (b->nomem) return;
    if (b->len + n + 1 > b->cap) {
        size_t cap = b->cap ? b->cap : 256;
        while (cap < b->len + n + 1) cap *= 2;
        char *t = realloc(b->s, cap);
        if (!t) {
            b->nomem = 1;
            return;
        }
        b->s = t;
        b->cap = cap;
    }
    memcpy(b->s + b->len, s, n);
    b->len += n;
    b->s[b->len] = '\0';
}

#if defined(__GNUC__)
__attribute__((format(printf, 2, 3)))
#endif
static void bprintf(buf *b, const char *fmt, ...) {
    char tmp[1024];
    va_list ap;
    va_start(ap, fmt);
    int n = vsnprintf(tmp, sizeof tmp, fmt, ap);
    va_end(ap);
    if (n < 0) return;
    if ((size_t)n < sizeof tmp) {
        bputn(b, tmp, (size_t)n);
        return;
    }
    char *big = malloc((size_t)n + 1);
    if (!big) {
        b->nomem = 1;
        return;
    }
    va_start(ap, fmt);
    vsnprintf(big, (size_t)n + 1, fmt, ap);
    va_end(ap);
    bputn(b, big, (size_t)n);
    free(big);
}

static void bjson(buf *b, const char *s) {
    bputn(b, "\"", 1);
    for (const unsigned char *p = (const unsigned char *)s; *p; p++) {
        if (*p == '"' || *p == '\\') {
            char e[2] = {'\\', (char)*p};
            bputn(b, e, 2);
        } else if (*p < 0x20) {
            bprintf(b, "\\u%04x", *p);
        } else {
            bputn(b, (const char *)p, 1);
        }
    }
    bputn(b, "\"", 1);
}

static void bhtml(buf *b, const char *s) {
    for (const char *p = s; *p; p++) {
        if (*p == '<') bputn(b, "&lt;", 4);
        else if (*p == '>') bputn(b, "&gt;", 4);
        else if (*p == '&') bputn(b, "&amp;", 5);
        else if (*p == '"') bputn(b, "&quot;", 6);
        else bputn(b, p, 1);
    }
}

/* A relative path as a URL path: bytes other than letters, digits and / . _ - ~ percent-encoded. */
static void burl(buf *b, const char *s) {
    for (const unsigned char *p = (const unsigned char *)s; *p; p++) {
        if ((*p >= 'a' && *p <= 'z') || (*p >= 'A' && *p <= 'Z') || (*p >= '0' && *p <= '9') || strchr("/._-~", *p))
            bputn(b, (const char *)p, 1);
        else
            bprintf(b, "%%%02X", *p);
    }
}

/* The string value of "key" in a one-line JSON object written by this file (NULL if absent); owned. */
static char *json_get_string(const char *line, const char *key) {
    char pat[64];
    snprintf(pat, sizeof pat, "\"%s\": \"", key);
    const char *p = strstr(line, pat);
    if (!p) return NULL;
    p += strlen(pat);
    buf b = {0};
    bputn(&b, "", 0);
    for (; *p && *p != '"'; p++) {
        if (*p == '\\' && p[1]) {
            p++;
            if (*p == 'u' && p[1] && p[2] && p[3] && p[4]) {
                char hex[5] = {p[1], p[2], p[3], p[4], 0};
                char c = (char)strtol(hex, NULL, 16);
                bputn(&b, &c, 1);
                p += 4;
                continue;
            }
        }
        bputn(&b, p, 1);
    }
    if (b.nomem) {
        free(b.s);
        return NULL;
    }
    return b.s;
}

static double json_get_number(const char *line, const char *key) {
    char pat[64];
    snprintf(pat, sizeof pat, "\"%s\": ", key);
    const char *p = strstr(line, pat);
    if (!p) return NAN;
    p += strlen(pat);
    if (strncmp(p, "null", 4) == 0) return NAN;
    return strtod(p, NULL);
}

/* ---- fingerprint ------------------------------------------------------------------------------------------------- */

static uint64_t fnv_file(const char *path, uint64_t h, int *ok) {
    FILE *f = fopen(path, "rb");
    if (!f) {
        *ok = 0;
        return h;
    }
    unsigned char chunk[65536];
    size_t n;
    while ((n = fread(chunk, 1, sizeof chunk, f)) > 0)
        for (size_t i = 0; i < n; i++) h = (h ^ chunk[i]) * 1099511628211ULL;
    if (ferror(f)) *ok = 0;
    fclose(f);
    return h;
}

/* FNV-1a 64 over every file the asset was read from, in the order read (and each name). */
static mr_status fingerprint(const char *path, char out[17]) {
    uint64_t h = 1469598103934665603ULL;
    int ok = 1;
    if (!is_asset_name(path)) { // another job's input (e.g. a .mtlx): its one file
        for (const char *c = path; *c; c++) h = (h ^ (unsigned char)*c) * 1099511628211ULL;
        h = fnv_file(path, h, &ok);
        snprintf(out, 17, "%016llx", (unsigned long long)h);
        return ok ? MR_OK : mr_fail(MR_ERR_IO, "'%s': cannot read it: %s", path, strerror(errno));
    }
    mr_gltf *asset = NULL;
    mr_status s = mr_gltf_load(path, &asset);
    if (s != MR_OK) return s;
    for (int k = 0; ok; k++) {
        const char *file = mr_gltf_source_file(asset, k);
        if (!file) break;
        for (const char *c = file; *c; c++) h = (h ^ (unsigned char)*c) * 1099511628211ULL;
        h = fnv_file(file, h, &ok);
        if (!ok) s = mr_fail(MR_ERR_IO, "asset '%s': cannot read '%s' again: %s", path, file, strerror(errno));
    }
    mr_gltf_free(asset);
    snprintf(out, 17, "%016llx", (unsigned long long)h);
    return s;
}

/* ---- thumbnails and object SSIM ---------------------------------------------------------------------------------- */

static mr_status render_scene(const mr_gltf_scene *asset, const mr_camera *camera, int size, int threads,
                              mr_image **image, mr_image **mask) {
    mr_fit_scene_options fo = {0};
    fo.size = size;
    mr_scene scene = mr_scene_fit(&fo);
    scene.threads = threads;
    scene.shape.type = MR_SHAPE_MESH;
    scene.shape.mesh = &asset->mesh;
    scene.camera = *camera;
    mr_status s = mr_scene_fit_light_to_mesh(&scene, &asset->mesh, fo.light);
    mr_render_plan *plan = NULL;
    if (s == MR_OK) s = mr_render_plan_create(&scene, &plan);
    if (s == MR_OK) s = mr_render_materials(plan, asset->bindings, asset->material_count, MR_COMPONENT_FULL, image);
    if (s == MR_OK && mask) s = mr_render_plan_coverage_mask(plan, mask);
    mr_render_plan_free(plan);
    return s;
}

/* Before/after renders at size x size into the two PNGs; *ssim the object SSIM. */
static mr_status thumbnails(const char *before_asset, const char *after_asset, int size, int threads,
                            const char *before_png, const char *after_png, double *ssim) {
    mr_gltf_scene *a = NULL, *b = NULL;
    mr_image *ia = NULL, *ib = NULL, *mask = NULL;
    mr_camera camera;
    // One scene at a time (each holds its decoded textures): before, then after with the same camera.
    mr_status s = mr_gltf_scene_load(before_asset, NULL, &a);
    if (s == MR_OK) s = mr_gltf_scene_frame(a, NULL, size, size, &camera);
    if (s == MR_OK) s = render_scene(a, &camera, size, threads, &ia, &mask);
    mr_gltf_scene_free(a);
    a = NULL;
    if (s == MR_OK) s = mr_gltf_scene_load(after_asset, NULL, &b);
    if (s == MR_OK) s = render_scene(b, &camera, size, threads, &ib, NULL);
    if (s == MR_OK) s = make_folders(before_png, 0);
    if (s == MR_OK) s = mr_img_write(before_png, ia, NULL);
    if (s == MR_OK) s = mr_img_write(after_png, ib, NULL);
    if (s == MR_OK) {
        mr_ssim_options so = {0};
        so.mask = mask;
        so.threads = 1;
        s = mr_ssim(ia, ib, &so, ssim, NULL);
    }
    mr_image_free(ia);
    mr_image_free(ib);
    mr_image_free(mask);
    mr_gltf_scene_free(a);
    mr_gltf_scene_free(b);
    return s;
}

/* ---- one asset ------------------------------------------------------------------------------------------------ */

typedef struct entry {
    char *input, *line; /* the JSON object of summary.json (one line), owned */
    char *status;
    double ssim;
} entry;

typedef struct earlier {
    entry *e;
    int count;
} earlier;

static void entry_free(entry *e) {
    free(e->input);
    free(e->line);
    free(e->status);
}

static const char *outcome_name(mr_gltf_convert_outcome o) {
    static const char *const names[] = {"skipped", "converted", "kept", "shared"};
    return (int)o >= 0 && (int)o < 4 ? names[o] : "?";
}

/* The summary line of one asset. */
static char *entry_line(const mr_gltf_library_item *it, const char *settings, const char *fp, const char *rel_before,
                        const char *rel_after, const char *render_error, const mr_gltf_convert_result *res,
                        const char *overview, const char *job_json) {
    buf b = {0};
    bputn(&b, "{\"input\": ", 10);
    bjson(&b, it->input);
    bputn(&b, ", \"output\": ", 12);
    bjson(&b, it->output);
    bprintf(&b, ", \"status\": \"%s\", \"error\": ", it->status);
    if (it->error[0]) bjson(&b, it->error);
    else bputn(&b, "null", 4);
    bputn(&b, ", \"settings\": ", 14);
    bjson(&b, settings);
    bprintf(&b, ", \"fingerprint\": \"%s\", \"seconds\": %.3f, \"object_ssim\": ", fp, it->seconds);
    if (isfinite(it->ssim)) bprintf(&b, "%.6f", it->ssim);
    else bputn(&b, "null", 4);
    bputn(&b, ", \"render_error\": ", 18);
    if (render_error && render_error[0]) bjson(&b, render_error);
    else bputn(&b, "null", 4);
    bputn(&b, ", \"before\": ", 12);
    if (rel_before) bjson(&b, rel_before);
    else bputn(&b, "null", 4);
    bputn(&b, ", \"after\": ", 11);
    if (rel_after) bjson(&b, rel_after);
    else bputn(&b, "null", 4);
    bputn(&b, ", \"overview\": ", 14);
    bjson(&b, overview);
    const mr_gltf_convert_totals *t = &it->totals;
    bprintf(&b, ", \"converted\": %d, \"kept\": %d, \"texels\": %zu, \"flagged\": %zu, "
            "\"flags\": {\"off_manifold\": %zu, \"nonfinite_input\": %zu, \"clamped_input\": %zu, "
            "\"method_failed\": %zu}, \"extensions\": %d",
            t->converted, t->kept, t->texels, t->total.flagged, t->total.off_manifold, t->total.nonfinite,
            t->total.clamped, t->total.failed, t->extensions);
    if (job_json) {
        bputn(&b, ", ", 2);
        bputn(&b, job_json, strlen(job_json));
    } else if (res) {
        bprintf(&b, ", \"pruned\": {\"textures\": %d, \"images\": %d, \"samplers\": %d, \"uncertain\": %d}",
                res->pruned.textures, res->pruned.images, res->pruned.samplers, res->pruned.uncertain);
        bputn(&b, ", \"materials\": [", 16);
        for (int k = 0; k < res->material_count; k++) {
            const mr_gltf_material_report *r = &res->materials[k];
            bprintf(&b, "%s{\"index\": %d, \"name\": ", k ? ", " : "", k);
            bjson(&b, r->name);
            bprintf(&b, ", \"outcome\": \"%s\", \"reason\": ", outcome_name(r->outcome));
            bjson(&b, r->reason);
            bprintf(&b, ", \"width\": %d, \"height\": %d, \"flagged\": %zu, \"flags\": {\"off_manifold\": %zu, "
                    "\"nonfinite_input\": %zu, \"clamped_input\": %zu, \"method_failed\": %zu}, \"extension\": ",
                    r->width, r->height, r->flagged, r->off_manifold, r->nonfinite, r->clamped, r->failed);
            if (r->extension)
                bprintf(&b, "{\"texels\": %zu, \"f0_unmet\": %zu, \"f0_max_error\": %.6g, \"diffuse_off\": %zu, "
                        "\"diffuse_mean_error\": %.6g, \"diffuse_max_error\": %.6g}", r->texels, r->f0_unmet,
                        r->f0_max_error, r->diffuse_off, r->diffuse_mean_error, r->diffuse_max_error);
            else
                bputn(&b, "null", 4);
            bprintf(&b, ", \"seconds\": %.6f}", r->seconds);
        }
        bputn(&b, "]", 1);
    } else {
        bputn(&b, ", \"pruned\": null, \"materials\": []", 33);
    }
    bputn(&b, "}", 1);
    if (b.nomem) {
        free(b.s);
        return NULL;
    }
    return b.s;
}

/* What index.html shows of an asset's materials. */
static void overview_of(const mr_gltf_convert_result *res, const mr_gltf_convert_totals *t, char *out, size_t n) {
    size_t used = 0;
    used += (size_t)snprintf(out, n, "%d material%s: %d converted, %d kept; %zu of %zu texels flagged",
                             res->material_count, res->material_count == 1 ? "" : "s", t->converted, t->kept,
                             t->total.flagged, t->texels);
    for (int k = 0; k < res->material_count && used + 8 < n; k++) {
        const mr_gltf_material_report *r = &res->materials[k];
        used += (size_t)snprintf(out + used, n - used, "\n%s: %s", r->name[0] ? r->name : "(unnamed)",
                                 outcome_name(r->outcome));
        if (used < n && r->width > 0)
            used += (size_t)snprintf(out + used, n - used, " %dx%d, %zu flagged", r->width, r->height, r->flagged);
        if (used < n && r->reason[0]) used += (size_t)snprintf(out + used, n - used, " (%s)", r->reason);
    }
}

typedef struct run {
    const mr_gltf_library_options *o;
    const char *root, *out_dir, *settings;
    const earlier *prev;
    int size, inner_threads;
    mr_gltf_library_result *res;
    entry *entries; /* [res->count] */
    double started;
    int done;
} run;

static const entry *find_earlier(const earlier *prev, const char *input) {
    for (int i = 0; i < prev->count; i++)
        if (strcmp(prev->e[i].input, input) == 0) return &prev->e[i];
    return NULL;
}

static const char *relative(const char *root, const char *path) {
    if (strcmp(root, ".") == 0) return strncmp(path, "./", 2) == 0 ? path + 2 : path;
    size_t n = strlen(root);
    if (strcmp(root, "/") == 0) return path + 1;
    return path + n + 1;
}

static void one_asset(run *r, int i) {
    mr_gltf_library_item *it = &r->res->items[i];
    entry *en = &r->entries[i];
    const double t0 = now_seconds();
    char fp[17] = "";
    char *before = NULL, *after = NULL, *render_error = NULL;
    mr_gltf_convert_result cres = {0, NULL, {0, 0, 0, 0}};
    char overview[2048] = "";
    int have_result = 0, render_after = 1;
    mr_gltf_library_job_result jres;
    memset(&jres, 0, sizeof jres);
    it->ssim = NAN;
    if (r->o->cancel && *r->o->cancel) {
        snprintf(it->status, sizeof it->status, "cancelled");
    } else {
        mr_status s = fingerprint(it->input, fp);
        const entry *was = r->o->resume && s == MR_OK ? find_earlier(r->prev, it->input) : NULL;
        struct stat st;
        if (was && strcmp(was->status, "converted") == 0 && stat(it->output, &st) == 0) {
            char *wfp = json_get_string(was->line, "fingerprint"), *wset = json_get_string(was->line, "settings");
            int same = wfp && wset && strcmp(wfp, fp) == 0 && strcmp(wset, r->settings) == 0;
            free(wfp);
            free(wset);
            if (same) {
                snprintf(it->status, sizeof it->status, "resumed");
                it->ssim = was->ssim;
                en->line = dup_str(was->line);
                en->status = dup_str("converted");
                en->ssim = was->ssim;
                en->input = dup_str(it->input);
                it->seconds = now_seconds() - t0;
                return;
            }
        }
        // An existing output is replaced only when an earlier run into this folder wrote it (summary.json says).
        const entry *own = find_earlier(r->prev, it->input);
        char *own_output = own ? json_get_string(own->line, "output") : NULL;
        if (s == MR_OK && stat(it->output, &st) == 0 && (!own_output || strcmp(own_output, it->output) != 0))
            s = mr_fail(MR_ERR_INVALID_ARG, "output '%s' exists and no earlier library run into '%s' wrote it; "
                        "refusing to replace it", it->output, r->out_dir);
        free(own_output);
        if (s == MR_OK) s = make_folders(it->output, 0);
        if (s == MR_OK && r->o->job) {
            s = r->o->job->run(r->o->job->user, it->input, it->output, r->inner_threads, &jres);
            if (s == MR_OK) {
                it->material_count = jres.material_count;
                it->totals.texels = jres.texels;
                render_after = jres.render_after;
                snprintf(it->status, sizeof it->status, "converted");
                snprintf(overview, sizeof overview, "%s", jres.overview);
            }
        } else if (s == MR_OK) {
            mr_gltf_convert_options co = r->o->convert;
            co.progress = NULL;
            co.progress_user = NULL;
            co.image_prefix = NULL;
            s = mr_gltf_convert_file(it->input, it->output, &co, &cres);
        }
        if (s != MR_OK) {
            snprintf(it->status, sizeof it->status, "failed");
            snprintf(it->error, sizeof it->error, "%s", mr_last_error());
        } else {
            if (!r->o->job) {
                have_result = 1;
                snprintf(it->status, sizeof it->status, "converted");
                mr_gltf_convert_totals_of(&cres, &it->totals);
                it->material_count = cres.material_count;
                overview_of(&cres, &it->totals, overview, sizeof overview);
            }
            const char *rel = relative(r->root, it->input);
            size_t n = strlen(rel) + 32;
            before = r->o->no_renders || !render_after ? NULL : malloc(n);
            after = r->o->no_renders || !render_after ? NULL : malloc(n);
            if (before && after) {
                snprintf(before, n, "thumbnails/%s.before.png", rel);
                snprintf(after, n, "thumbnails/%s.after.png", rel);
                char *bp = join(r->out_dir, before), *ap = join(r->out_dir, after);
                mr_status rs = bp && ap ? thumbnails(it->input, it->output, r->size, r->inner_threads, bp, ap,
                                                     &it->ssim)
                                        : mr_fail(MR_ERR_NOMEM, "out of memory");
                if (rs != MR_OK) {
                    render_error = dup_str(mr_last_error());
                    it->ssim = NAN;
                    free(before);
                    free(after);
                    before = after = NULL;
                }
                free(bp);
                free(ap);
            }
        }
    }
    it->seconds = now_seconds() - t0;
    en->input = dup_str(it->input);
    en->status = dup_str(it->status);
    en->ssim = it->ssim;
    en->line = entry_line(it, r->settings, fp, before, after, render_error, have_result ? &cres : NULL, overview,
                          r->o->job ? (jres.json ? jres.json : "\"materials\": []") : NULL);
    free(jres.json);
    free(before);
    free(after);
    free(render_error);
    mr_gltf_convert_result_free(&cres);
}

/* ---- summary.json and index.html ------------------------------------------------------------------------------- */

static int rank(const entry *e) {
    if (strcmp(e->status, "failed") == 0) return 0;
    if (strcmp(e->status, "cancelled") == 0) return 1;
    if (!isfinite(e->ssim)) return 2;
    return 3;
}

static int cmp_worst(const void *pa, const void *pb) {
    const entry *a = *(const entry *const *)pa, *b = *(const entry *const *)pb;
    int ra = rank(a), rb = rank(b);
    if (ra != rb) return ra < rb ? -1 : 1;
    if (ra == 3 && a->ssim != b->ssim) return a->ssim < b->ssim ? -1 : 1;
    return strcmp(a->input, b->input);
}

/* An existing file at `path` that this writer did not make: refused. */
static mr_status check_own(const char *path, const char *mark) {
    FILE *f = fopen(path, "rb");
    if (!f) return MR_OK;
    char head[128] = "";
    size_t n = fread(head, 1, sizeof head - 1, f);
    head[n] = '\0';
    fclose(f);
    if (strncmp(head, mark, strlen(mark)) == 0) return MR_OK;
    return mr_fail(MR_ERR_INVALID_ARG, "'%s' exists and was not written by a library conversion; refusing to "
                   "replace it", path);
}

static mr_status read_earlier(const char *path, earlier *out) {
    memset(out, 0, sizeof *out);
    FILE *f = fopen(path, "rb");
    if (!f) return MR_OK;
    buf line = {0};
    int c;
    mr_status s = MR_OK;
    for (;;) {
        line.len = 0;
        bputn(&line, "", 0);
        while ((c = fgetc(f)) != EOF && c != '\n') {
            char ch = (char)c;
            bputn(&line, &ch, 1);
        }
        if (line.nomem) {
            s = mr_fail(MR_ERR_NOMEM, "out of memory reading '%s'", path);
            break;
        }
        const char *p = line.s;
        while (*p == ' ') p++;
        if (strncmp(p, "{\"input\": ", 10) == 0) {
            size_t len = strlen(p);
            while (len > 0 && (p[len - 1] == ',' || p[len - 1] == '\r')) len--;
            entry e = {0};
            e.line = malloc(len + 1);
            if (e.line) {
                memcpy(e.line, p, len);
                e.line[len] = '\0';
            }
            e.input = e.line ? json_get_string(e.line, "input") : NULL;
            e.status = e.line ? json_get_string(e.line, "status") : NULL;
            e.ssim = e.line ? json_get_number(e.line, "object_ssim") : NAN;
            entry *grown = realloc(out->e, (size_t)(out->count + 1) * sizeof *grown);
            if (!e.input || !e.status || !grown) {
                entry_free(&e);
                if (grown) out->e = grown;
                s = mr_fail(MR_ERR_NOMEM, "out of memory reading '%s'", path);
                break;
            }
            out->e = grown;
            out->e[out->count++] = e;
        }
        if (c == EOF) break;
    }
    free(line.s);
    fclose(f);
    return s;
}

static mr_status write_text(const char *path, const buf *b) {
    if (b->nomem) return mr_fail(MR_ERR_NOMEM, "out of memory writing '%s'", path);
    return mr_atomic_write_bytes(path, b->s, b->len);
}

static mr_status write_outputs(const run *r, const char *summary_path, const char *index_path) {
    int total = r->res->count + r->prev->count;
    const entry **all = malloc((size_t)(total ? total : 1) * sizeof *all);
    if (!all) return mr_fail(MR_ERR_NOMEM, "out of memory writing the summary");
    int n = 0;
    for (int i = 0; i < r->res->count; i++)
        if (r->entries[i].line) all[n++] = &r->entries[i];
    for (int i = 0; i < r->prev->count; i++) {
        int here = 0;
        for (int j = 0; j < r->res->count && !here; j++)
            here = strcmp(r->prev->e[i].input, r->res->items[j].input) == 0;
        if (!here) all[n++] = &r->prev->e[i];
    }
    qsort(all, (size_t)n, sizeof *all, cmp_worst);
    int failed = 0;
    for (int i = 0; i < n; i++) failed += strcmp(all[i]->status, "failed") == 0;
    buf j = {0};
    bputn(&j, SUMMARY_MARK, strlen(SUMMARY_MARK));
    bputn(&j, "\n  \"root\": ", 11);
    bjson(&j, r->root);
    bprintf(&j, ",\n  \"assets\": %d, \"failed\": %d, \"order\": \"worst first: failed, then by object SSIM\",\n"
            "  \"items\": [\n", n, failed);
    for (int i = 0; i < n; i++) bprintf(&j, "    %s%s\n", all[i]->line, i + 1 < n ? "," : "");
    bputn(&j, "  ]\n}\n", 6);
    mr_status s = write_text(summary_path, &j);
    free(j.s);

    buf h = {0};
    bputn(&h, INDEX_MARK, strlen(INDEX_MARK));
    static const char head[] = "\n<html><head><meta charset=\"utf-8\"><title>matremap gltf library</title><style>"
                               "body{font-family:sans-serif}td{vertical-align:top;padding:4px;"
                               "border-bottom:1px solid #ccc}.failed{background:#fdd}pre{margin:0;font-size:12px}"
                               "</style></head><body>\n";
    bputn(&h, head, strlen(head));
    bprintf(&h, "<h1>%d assets, %d failed</h1><p>Worst first: failed assets, then by object SSIM (after against "
            "before, over the object).</p>\n<table><tr><th>asset</th><th>before</th><th>after</th><th>object SSIM"
            "</th><th>materials and flags</th></tr>\n", n, failed);
    for (int i = 0; i < n; i++) {
        const entry *e = all[i];
        char *out = json_get_string(e->line, "output"), *err = json_get_string(e->line, "error");
        char *b = json_get_string(e->line, "before"), *a = json_get_string(e->line, "after");
        char *ov = json_get_string(e->line, "overview"), *re = json_get_string(e->line, "render_error");
        bprintf(&h, "<tr class=\"%s\"><td>", e->status);
        bhtml(&h, e->input);
        bputn(&h, "<br>&rarr; ", 11);
        bhtml(&h, out ? out : "");
        bprintf(&h, "<br>%s</td><td>", e->status);
        if (b) {
            bputn(&h, "<img src=\"", 10);
            burl(&h, b);
            bputn(&h, "\">", 2);
        }
        bputn(&h, "</td><td>", 9);
        if (a) {
            bputn(&h, "<img src=\"", 10);
            burl(&h, a);
            bputn(&h, "\">", 2);
        }
        bputn(&h, "</td><td>", 9);
        if (isfinite(e->ssim)) bprintf(&h, "%.4f", e->ssim);
        else bputn(&h, "&ndash;", 7);
        bputn(&h, "</td><td><pre>", 14);
        if (err) bhtml(&h, err);
        if (ov) bhtml(&h, ov);
        if (re) {
            bputn(&h, "\nnot rendered: ", 15);
            bhtml(&h, re);
        }
        bputn(&h, "</pre></td></tr>\n", 17);
        free(out);
        free(err);
        free(b);
        free(a);
        free(ov);
        free(re);
    }
    bputn(&h, "</table></body></html>\n", 23);
    if (s == MR_OK) s = write_text(index_path, &h);
    free(h.s);
    free(all);
    return s;
}

/* ---- the call ---------------------------------------------------------------------------------------------------- */

void mr_gltf_library_result_free(mr_gltf_library_result *result) {
    if (!result) return;
    for (int i = 0; result->items && i < result->count; i++) {
        free(result->items[i].input);
        free(result->items[i].output);
    }
    free(result->items);
    memset(result, 0, sizeof *result);
}

static int cmp_output(const void *pa, const void *pb) {
    const mr_gltf_library_item *a = *(const mr_gltf_library_item *const *)pa;
    const mr_gltf_library_item *b = *(const mr_gltf_library_item *const *)pb;
    return strcmp(a->output, b->output);
}

/* Whether `inner` is `outer` or lies below it (absolute paths). */
static int lies_in(const char *inner, const char *outer) {
    size_t n = strlen(outer);
    if (strcmp(outer, "/") == 0) return 1;
    return strncmp(inner, outer, n) == 0 && (inner[n] == '\0' || inner[n] == '/');
}

mr_status mr_gltf_convert_library(const char *const *inputs, int input_count, const char *out_dir,
                                  const mr_gltf_library_options *opts, mr_gltf_library_result *result) {
    if (result) memset(result, 0, sizeof *result);
    if (!out_dir || !out_dir[0] || !opts) return mr_fail(MR_ERR_INVALID_ARG, "mr_gltf_convert_library: no output "
                                                         "folder or options");
    if (opts->shard_count < 0 || (opts->shard_count > 1 && (opts->shard_index < 0 ||
                                                            opts->shard_index >= opts->shard_count)))
        return mr_fail(MR_ERR_INVALID_ARG, "shard %d/%d: expected K/N with 0 <= K < N", opts->shard_index,
                       opts->shard_count);
    if (opts->thumbnail_size != 0 && (opts->thumbnail_size < 32 || opts->thumbnail_size > 4096))
        return mr_fail(MR_ERR_INVALID_ARG, "thumbnail size %d: expected 32 to 4096", opts->thumbnail_size);
    char **assets = NULL, *root = NULL, *out_trimmed = trimmed(out_dir);
    if (!out_trimmed) return mr_fail(MR_ERR_NOMEM, "out of memory");
    out_dir = out_trimmed;
    int count = 0;
    strlist folders = {0};
    mr_status s = list_all(inputs, input_count, &assets, &count, &root, &folders);
    char *abs_out = NULL;
    if (s == MR_OK) {
        abs_out = absolute_path(out_dir);
        if (!abs_out) s = mr_fail(MR_ERR_NOMEM, "out of memory");
    }
    for (int i = 0; s == MR_OK && i < folders.count; i++) {
        char *abs_in = realpath(folders.items[i], NULL);
        if (abs_in && lies_in(abs_out, abs_in))
            s = mr_fail(MR_ERR_INVALID_ARG, "output folder '%s' lies inside the input folder '%s'; refusing to "
                        "write there (its outputs would be read as inputs)", out_dir, folders.items[i]);
        free(abs_in);
    }
    for (int i = 0; s == MR_OK && i < count; i++) {
        char *abs_in = realpath(assets[i], NULL);
        if (abs_in && lies_in(abs_in, abs_out))
            s = mr_fail(MR_ERR_INVALID_ARG, "output folder '%s' holds the input asset '%s'; refusing to write there",
                        out_dir, assets[i]);
        free(abs_in);
    }
    free(abs_out);
    strlist_free(&folders);
    char *summary_path = NULL, *index_path = NULL;
    if (s == MR_OK) {
        summary_path = join(out_dir, "summary.json");
        index_path = join(out_dir, "index.html");
        if (!summary_path || !index_path) s = mr_fail(MR_ERR_NOMEM, "out of memory");
    }
    if (s == MR_OK) s = check_own(summary_path, SUMMARY_MARK);
    if (s == MR_OK) s = check_own(index_path, INDEX_MARK);
    earlier prev = {0};
    if (s == MR_OK) s = read_earlier(summary_path, &prev);
    if (s == MR_OK) s = make_folders(out_dir, 1);

    mr_gltf_library_result res = {0};
    entry *entries = NULL;
    if (s == MR_OK) {
        int n = 0;
        for (int i = 0; i < count; i++)
            if (opts->shard_count <= 1 || i % opts->shard_count == opts->shard_index) n++;
        res.items = calloc((size_t)(n ? n : 1), sizeof *res.items);
        entries = calloc((size_t)(n ? n : 1), sizeof *entries);
        if (!res.items || !entries) s = mr_fail(MR_ERR_NOMEM, "out of memory");
        for (int i = 0; s == MR_OK && i < count; i++) {
            if (opts->shard_count > 1 && i % opts->shard_count != opts->shard_index) continue;
            mr_gltf_library_item *it = &res.items[res.count++];
            it->input = dup_str(assets[i]);
            it->output = join(out_dir, relative(root, assets[i]));
            if (it->output && opts->job && opts->job->extension) {
                // The job's outputs: the input's extension replaced (a.glb -> a.mtlx).
                char *dot = strrchr(it->output, '.'), *slash = strrchr(it->output, '/');
                size_t stem = dot && (!slash || dot > slash) ? (size_t)(dot - it->output) : strlen(it->output);
                char *named = malloc(stem + strlen(opts->job->extension) + 1);
                if (named) {
                    memcpy(named, it->output, stem);
                    strcpy(named + stem, opts->job->extension);
                }
                free(it->output);
                it->output = named;
            }
            it->ssim = NAN;
            if (!it->input || !it->output) s = mr_fail(MR_ERR_NOMEM, "out of memory");
        }
    }
    if (s == MR_OK && opts->job && opts->job->extension && res.count > 1) {
        // Two inputs one output (a.gltf and a.glb -> a.mtlx): refused before any work, naming both.
        mr_gltf_library_item **by_output = malloc((size_t)res.count * sizeof *by_output);
        if (!by_output) s = mr_fail(MR_ERR_NOMEM, "out of memory");
        for (int i = 0; s == MR_OK && i < res.count; i++) by_output[i] = &res.items[i];
        if (s == MR_OK) qsort(by_output, (size_t)res.count, sizeof *by_output, cmp_output);
        for (int i = 1; s == MR_OK && i < res.count; i++)
            if (strcmp(by_output[i - 1]->output, by_output[i]->output) == 0)
                s = mr_fail(MR_ERR_INVALID_ARG, "'%s' and '%s' would both be written to '%s'; refusing the run (export "
                            "one of them apart)", by_output[i - 1]->input, by_output[i]->input, by_output[i]->output);
        free(by_output);
    }
    if (s == MR_OK) {
        run r = {0};
        r.o = opts;
        r.root = root;
        r.out_dir = out_dir;
        r.settings = opts->settings ? opts->settings : "";
        r.prev = &prev;
        r.size = opts->thumbnail_size ? opts->thumbnail_size : 128;
        r.res = &res;
        r.entries = entries;
        r.started = now_seconds();
        int team = opts->serial ? 1 : mr_auto_threads(opts->threads, res.count, 2);
        if (team > res.count) team = res.count > 0 ? res.count : 1;
        r.inner_threads = team > 1 ? 1 : opts->threads;
        const int total = res.count;
#pragma omp parallel for schedule(dynamic, 1) num_threads(team)
        for (int i = 0; i < total; i++) {
            one_asset(&r, i);
#pragma omp critical(mr_gltf_library_progress)
            {
                mr_gltf_library_item *it = &res.items[i];
                r.done++;
                if (strcmp(it->status, "converted") == 0) res.converted++;
                else if (strcmp(it->status, "resumed") == 0) res.resumed++;
                else if (strcmp(it->status, "failed") == 0) res.failed++;
                else res.cancelled++;
                // Texels converted, or solved for the extension alone (kept materials): the larger count.
                res.texels += it->totals.texels > it->totals.total.texels ? it->totals.texels : it->totals.total.texels;
                if (opts->progress) {
                    mr_gltf_library_progress p = {r.done, total, res.failed, it->input, it->status, it->error,
                                                  it->seconds, now_seconds() - r.started, res.texels};
                    opts->progress(opts->progress_user, &p);
                }
            }
        }
        res.seconds = now_seconds() - r.started;
        s = write_outputs(&r, summary_path, index_path);
        if (s == MR_OK && res.cancelled > 0) s = mr_fail(MR_ERR_CANCELLED, "cancelled after %d of %d assets",
                                                       res.count - res.cancelled, res.count);
    }
    for (int i = 0; entries && i < res.count; i++) entry_free(&entries[i]);
    free(entries);
    for (int i = 0; i < prev.count; i++) entry_free(&prev.e[i]);
    free(prev.e);
    free(summary_path);
    free(index_path);
    mr_gltf_library_list_free(assets, count, root);
    free(out_trimmed);
    if (result) *result = res;
    else mr_gltf_library_result_free(&res);
    return s;
}
