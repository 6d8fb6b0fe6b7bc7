/*
 * export_library.c — many assets exported in one call (doc.h: mr_doc_export_library): gltf/'s library loop
 * (mr_gltf_convert_library: listing, threads, progress, resume, shards, summary.json, index.html) with a job that
 * runs mr_doc_export_file per asset.
 */
#include "doc/doc.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gltf/mr_gltf_library.h"
#include "mr_internal.h"

typedef struct job_state {
    const mr_doc_export_options *each;
} job_state;

typedef struct text {
    char *s;
    size_t len, cap;
    int nomem;
} text;

static void put(text *t, const char *s, size_t n) {
    if (t->nomem) return;
    if (t->len + n + 1 > t->cap) {
        size_t cap = t->cap ? t->cap : 512;
        while (cap < t->len + n + 1) cap *= 2;
        char *grown = realloc(t->s, cap);
        if (grown == NULL) {
            t->nomem = 1;
            return;
        }
        t->s = grown;
        t->cap = cap;
    }
    memcpy(t->s + t->len, s, n);
    t->len += n;
    t->s[t->len] = '\0';
}

static void puts_(text *t, const char *s) { put(t, s, strlen(s)); }

static void put_json(text *t, const char *s) {
    puts_(t, "\"");
    for (; *s; s++) {
        char esc[8];
        unsigned char c = (unsigned char)*s;
        if (c == '"' || c == '\\') {
            esc[0] = '\\';
            esc[1] = (char)c;
            put(t, esc, 2);
        } else if (c < 0x20) {
            snprintf(esc, sizeof esc, "\\u%04x", c);
            puts_(t, esc);
        } else {
            put(t, (const char *)&c, 1);
        }
    }
    puts_(t, "\"");
}

/* The summary line's members of one export: the format, the target, per material its route and figures, the images
 * and maps written. */
static char *summary_json(const mr_doc_export_report *rep) {
    text t = {0};
    char num[256];
    puts_(&t, "\"format\": ");
    put_json(&t, rep->format);
    puts_(&t, ", \"target\": ");
    put_json(&t, rep->target->name);
    puts_(&t, ", \"materials\": [");
    for (int k = 0; k < rep->result->material_count; k++) {
        const mr_doc_gltf_material *m = &rep->result->materials[k];
        snprintf(num, sizeof num, "%s{\"index\": %d, \"name\": ", k ? ", " : "", k);
        puts_(&t, num);
        put_json(&t, m->name);
        snprintf(num, sizeof num, ", \"route\": \"%s\"", mr_doc_route_name(m->route));
        puts_(&t, num);
        if (m->route == MR_DOC_ROUTE_REMAP) {
            snprintf(num, sizeof num, ", \"outcome\": \"%s\", \"ssim\": %.6f, \"relative_rmse\": %.6f",
                     mr_fit_outcome_name((mr_fit_outcome)m->outcome), m->ssim, m->relative_rmse);
            puts_(&t, num);
        }
        if (m->route == MR_DOC_ROUTE_DIRECT || m->route == MR_DOC_ROUTE_LEARNED) {
            snprintf(num, sizeof num, ", \"width\": %d, \"height\": %d, \"texels\": %zu, \"unconverged\": %zu, "
                     "\"flagged\": %zu, \"seconds\": %.3f", m->width, m->height, m->texels, m->unconverged,
                     m->flagged, m->seconds);
            puts_(&t, num);
        }
        puts_(&t, ", \"not_carried\": ");
        put_json(&t, m->not_carried);
        puts_(&t, "}");
    }
    puts_(&t, "], \"images\": [");
    for (int i = 0; i < rep->result->image_count; i++) {
        if (i) puts_(&t, ", ");
        put_json(&t, rep->result->images[i].path);
    }
    puts_(&t, "], \"maps\": [");
    for (int i = 0; i < rep->result->map_count; i++) {
        if (i) puts_(&t, ", ");
        put_json(&t, rep->result->maps[i].path);
    }
    puts_(&t, "]");
    if (t.nomem) {
        free(t.s);
        return NULL;
    }
    return t.s;
}

static mr_status export_one(void *user, const char *input, const char *output, int threads,
                            mr_gltf_library_job_result *out) {
    const job_state *job = user;
    mr_doc_export_options o = *job->each;
    o.threads = threads;
    o.progress = NULL; // one progress line per asset is the loop's
    o.progress_user = NULL;
    mr_doc_export_report rep;
    mr_status st = mr_doc_export_file(input, output, &o, &rep);
    if (st != MR_OK) return st;
    const mr_doc_gltf_result *r = rep.result;
    out->material_count = r->material_count;
    // A glTF output of a glTF input is rendered against it; a document (in or out) has no geometry to render.
    out->render_after = (strcmp(rep.format, "gltf") == 0 || strcmp(rep.format, "glb") == 0) &&
                        mr_doc_format_from_path(input) != MR_DOC_FORMAT_MTLX;
    size_t used = (size_t)snprintf(out->overview, sizeof out->overview, "%d material%s to %s (%s)",
                                   r->material_count, r->material_count == 1 ? "" : "s", rep.target->name, rep.format);
    for (int k = 0; k < r->material_count; k++) {
        const mr_doc_gltf_material *m = &r->materials[k];
        out->texels += m->texels;
        if (used + 8 < sizeof out->overview)
            used += (size_t)snprintf(out->overview + used, sizeof out->overview - used, "\n%s: %s",
                                     m->name[0] ? m->name : "(unnamed)", mr_doc_route_name(m->route));
        if (used + 8 < sizeof out->overview && m->route == MR_DOC_ROUTE_REMAP)
            used += (size_t)snprintf(out->overview + used, sizeof out->overview - used, " (SSIM %.4f)", m->ssim);
        if (used + 8 < sizeof out->overview && (m->route == MR_DOC_ROUTE_DIRECT || m->route == MR_DOC_ROUTE_LEARNED))
            used += (size_t)snprintf(out->overview + used, sizeof out->overview - used, " %dx%d, %zu flagged",
                                     m->width, m->height, m->flagged);
    }
    out->json = summary_json(&rep);
    mr_doc_export_report_free(&rep);
    return out->json != NULL ? MR_OK : mr_fail(MR_ERR_NOMEM, "out of memory summarising '%s'", input);
}

mr_status mr_doc_export_library(const char *const *inputs, int input_count, const char *out_dir,
                                const mr_doc_export_options *each, const char *extension,
                                const struct mr_gltf_library_options *library, struct mr_gltf_library_result *result) {
    if (result) memset(result, 0, sizeof *result);
    if (extension == NULL || library == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "mr_doc_export_library: no extension or library options");
    char probe[64];
    snprintf(probe, sizeof probe, "x%s", extension);
    if (extension[0] != '.' || !mr_doc_export_output_ok(probe))
        return mr_fail(MR_ERR_INVALID_ARG, "'%s': the outputs' extension is .mtlx, .usda, .gltf or .glb", extension);
    mr_doc_export_options zero = {0};
    job_state state = {each != NULL ? each : &zero};
    mr_gltf_library_job job = {export_one, &state, extension};
    mr_gltf_library_options o = *library;
    o.job = &job;
    // The direct remap's cache takes one user at a time (an advisory lock, remap/direct.h): assets one by one.
    if (state.each->cache_path != NULL) o.serial = 1;
    return mr_gltf_convert_library(inputs, input_count, out_dir, &o, result);
}
