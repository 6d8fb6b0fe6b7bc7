/*
 * report.c — the HTML page and JSON summary of an SSIM evaluation report (contract in report.h).
 *
 * Both documents are composed in memory (open_memstream) and written with the atomic-file protocol, so a reader
 * never sees half a page. The page is plain HTML with an inline style sheet and no script: pictures are <img>
 * elements with relative paths, the tables are tables.
 */
#include "report.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../c_locale.h"
#include "../mr_internal.h"

/* ---- escaping ---------------------------------------------------------------------------------------------- */

static void html_text(FILE *out, const char *s) {
    for (; s != NULL && *s; s++) {
        switch (*s) {
        case '&': fputs("&amp;", out); break;
        case '<': fputs("&lt;", out); break;
        case '>': fputs("&gt;", out); break;
        case '"': fputs("&quot;", out); break;
        case '\'': fputs("&#39;", out); break;
        default: fputc(*s, out);
        }
    }
}

/* A path inside an attribute: HTML-escaped, and the characters a URL must not hold raw percent-encoded. */
static void html_url(FILE *out, const char *s) {
    for (; *s; s++) {
        unsigned char c = (unsigned char)*s;
        if (c <= ' ' || c == '%' || c == '#' || c == '?' || c >= 0x7f)
            fprintf(out, "%%%02X", c);
        else if (c == '&' || c == '"' || c == '\'' || c == '<' || c == '>')
            fprintf(out, "&#%d;", c);
        else
            fputc(c, out);
    }
}

static void json_string(FILE *out, const char *s) {
    if (s == NULL) {
        fputs("null", out);
        return;
    }
    fputc('"', out);
    for (; *s; s++) {
        unsigned char c = (unsigned char)*s;
        if (c == '"' || c == '\\')
            fprintf(out, "\\%c", c);
        else if (c == '\n')
            fputs("\\n", out);
        else if (c < 0x20)
            fprintf(out, "\\u%04x", c);
        else
            fputc(c, out);
    }
    fputc('"', out);
}

/* ---- checks ------------------------------------------------------------------------------------------------ */

/* Whether the candidates carry figures over the object (all or none do: check_report). */
static int has_object(const mr_report *r) { return r->material_count > 1 && r->materials[1].object_ssim != NULL; }

static mr_status check_report(const mr_report *r, const char *dir) {
    if (r == NULL || dir == NULL) return mr_fail(MR_ERR_INVALID_ARG, "report: NULL report or folder");
    if (r->view_count < 1 || r->views == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "report: %d views: expected at least one, named", r->view_count);
    if (r->material_count < 1 || r->materials == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "report: %d materials: expected at least the reference",
                       r->material_count);
    for (int v = 0; v < r->view_count; v++)
        if (r->views[v] == NULL) return mr_fail(MR_ERR_INVALID_ARG, "report: view %d has no name", v);
    for (int k = 0; k < r->material_count; k++) {
        const mr_report_material *m = &r->materials[k];
        const char *label = m->label ? m->label : "(unnamed)";
        if (m->label == NULL || m->renders == NULL)
            return mr_fail(MR_ERR_INVALID_ARG, "report: material %d needs a label and its renders", k);
        if (m->thumbnail_count < 0 || (m->thumbnail_count > 0 && (!m->thumbnails || !m->thumbnail_labels)))
            return mr_fail(MR_ERR_INVALID_ARG, "report: material '%s': %d thumbnails without their paths or labels",
                           label, m->thumbnail_count);
        if (k > 0 && (m->ssim == NULL || m->relative_rmse == NULL || m->ssim_maps == NULL))
            return mr_fail(MR_ERR_INVALID_ARG, "report: material '%s' needs SSIM, relative RMSE and SSIM maps "
                           "against the reference", label);
        if (k > 0 && ((m->object_ssim != NULL) != has_object(r) || (m->object_relative_rmse != NULL) != has_object(r)))
            return mr_fail(MR_ERR_INVALID_ARG, "report: material '%s': object SSIM and relative RMSE must be given "
                           "for every candidate or for none", label);
        if (!isfinite(m->seconds))
            return mr_fail(MR_ERR_INVALID_ARG, "report: material '%s': time is not finite", label);
        for (int v = 0; v < r->view_count; v++) {
            if (m->renders[v] == NULL || (k > 0 && m->ssim_maps[v] == NULL))
                return mr_fail(MR_ERR_INVALID_ARG, "report: material '%s', view '%s': a picture is missing", label,
                               r->views[v]);
            if (k > 0 && !(isfinite(m->ssim[v]) && isfinite(m->relative_rmse[v])))
                return mr_fail(MR_ERR_INVALID_ARG, "report: material '%s', view '%s': SSIM %g, relative RMSE %g: "
                               "expected finite values", label, r->views[v], m->ssim[v], m->relative_rmse[v]);
            if (k > 0 && has_object(r) && !(isfinite(m->object_ssim[v]) && isfinite(m->object_relative_rmse[v])))
                return mr_fail(MR_ERR_INVALID_ARG, "report: material '%s', view '%s': object SSIM %g, relative RMSE "
                               "%g: expected finite values", label, r->views[v], m->object_ssim[v],
                               m->object_relative_rmse[v]);
        }
        for (int t = 0; t < m->thumbnail_count; t++)
            if (m->thumbnails[t] == NULL || m->thumbnail_labels[t] == NULL)
                return mr_fail(MR_ERR_INVALID_ARG, "report: material '%s': thumbnail %d has no path or label",
                               label, t);
    }
    return MR_OK;
}

static double mean(const double *x, int n) {
    double sum = 0.0;
    for (int i = 0; i < n; i++) sum += x[i];
    return sum / n;
}

/* The SSIM a candidate is ranked and captioned by: over the object when the report has it. */
static const double *headline_ssim(const mr_report *r, int k) {
    return has_object(r) ? r->materials[k].object_ssim : r->materials[k].ssim;
}

/* ---- the page ---------------------------------------------------------------------------------------------- */

static const char style_sheet[] =
    "body{font-family:DejaVu Sans,Helvetica,Arial,sans-serif;margin:24px;background:#fafafa;color:#222}"
    "h1{font-size:1.5em;margin-bottom:0.2em}h2{font-size:1.15em;margin-top:1.6em}"
    "p.scene{color:#555;margin-top:0}"
    "table{border-collapse:collapse;margin:0.6em 0}td,th{border:1px solid #ccc;padding:4px 8px;text-align:right}"
    "th{background:#eee}td.name,th.name{text-align:left}"
    ".row{display:flex;flex-wrap:wrap;gap:10px}"
    "figure{margin:0;background:#fff;border:1px solid #ddd;padding:6px}"
    "figure img{display:block;width:256px;height:auto;image-rendering:auto}"
    "figure.thumb img{width:128px}figure.spacer{width:256px;visibility:hidden}"
    "figcaption{font-size:0.85em;margin-top:4px;max-width:256px;word-wrap:break-word}"
    ".best{font-weight:bold}code{font-size:0.85em;word-break:break-all}";

static void figure(FILE *out, const char *path, const char *caption, const char *css_class) {
    fprintf(out, "<figure%s%s%s><img src=\"", css_class ? " class=\"" : "", css_class ? css_class : "",
            css_class ? "\"" : "");
    html_url(out, path);
    fputs("\" alt=\"", out);
    html_text(out, caption);
    fputs("\"><figcaption>", out);
    html_text(out, caption);
    fputs("</figcaption></figure>\n", out);
}

static void write_page(FILE *out, const mr_report *r) {
    fputs("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n<title>", out);
    html_text(out, r->title ? r->title : "matremap report");
    fprintf(out, "</title>\n<style>%s</style></head>\n<body>\n<h1>", style_sheet);
    html_text(out, r->title ? r->title : "matremap report");
    fputs("</h1>\n", out);
    if (r->scene) {
        fputs("<p class=\"scene\">", out);
        html_text(out, r->scene);
        fputs("</p>\n", out);
    }
    const int object = has_object(r);
    fprintf(out, "<p class=\"scene\">Made by matremap %s. SSIM: 1 = identical to the reference (display-referred "
                 "luma, docs/metrics.md); relative RMSE: linear RGB. SSIM maps: black = identical, brighter = lower "
                 "SSIM.</p>\n", mr_version());
    if (object)
        fputs("<p class=\"scene\">Object figures (first) look only where the object is: SSIM averaged over the "
              "pixels whose 11×11 SSIM window touches it (its coverage dilated by 5 pixels), relative RMSE over "
              "its pixels as a fraction of the reference's mean radiance there. Whole-frame figures (beside them) "
              "count every pixel, the black background included (relative RMSE over the reference's RMS); "
              "they dilute differences by the frame's emptiness.</p>\n", out);
    else
        fputs("<p class=\"scene\">Over the whole frame, background included; relative RMSE over the reference's "
              "RMS.</p>\n", out);

    // Summary: the best mean headline SSIM (the object's when there is one) among the candidates in bold.
    int best = -1;
    for (int k = 1; k < r->material_count; k++)
        if (best < 0 || mean(headline_ssim(r, k), r->view_count) > mean(headline_ssim(r, best), r->view_count))
            best = k;
    fputs("<h2>Summary</h2>\n<table>\n<tr><th class=\"name\">material</th>", out);
    if (object) fputs("<th>object SSIM (mean)</th><th>object rel. RMSE (mean)</th>", out);
    else fputs("<th>mean SSIM</th><th>mean rel. RMSE</th>", out);
    for (int v = 0; v < r->view_count; v++) {
        fputs(object ? "<th>object SSIM " : "<th>SSIM ", out);
        html_text(out, r->views[v]);
        fputs("</th>", out);
    }
    if (object) fputs("<th>whole-frame SSIM (mean)</th><th>whole-frame rel. RMSE (mean)</th>", out);
    fputs("<th>", out);
    html_text(out, r->time_label ? r->time_label : "time");
    fputs("</th></tr>\n", out);
    for (int k = 0; k < r->material_count; k++) {
        const mr_report_material *m = &r->materials[k];
        fprintf(out, "<tr%s><td class=\"name\">", k == best && r->material_count > 2 ? " class=\"best\"" : "");
        html_text(out, m->label);
        if (k == 0) {
            fputs(" (reference)</td><td>1</td><td>0</td>", out);
            for (int v = 0; v < r->view_count; v++) fputs("<td>1</td>", out);
            if (object) fputs("<td>1</td><td>0</td>", out);
        } else {
            fprintf(out, "</td><td>%.4f</td><td>%.4f</td>", mean(headline_ssim(r, k), r->view_count),
                    mean(object ? m->object_relative_rmse : m->relative_rmse, r->view_count));
            for (int v = 0; v < r->view_count; v++) fprintf(out, "<td>%.4f</td>", headline_ssim(r, k)[v]);
            if (object)
                fprintf(out, "<td>%.4f</td><td>%.4f</td>", mean(m->ssim, r->view_count),
                        mean(m->relative_rmse, r->view_count));
        }
        if (m->seconds >= 0.0)
            fprintf(out, "<td>%.3f s</td></tr>\n", m->seconds);
        else
            fputs("<td>–</td></tr>\n", out);
    }
    fputs("</table>\n", out);

    // One section per view: renders side by side, their SSIM maps below.
    for (int v = 0; v < r->view_count; v++) {
        fputs("<h2>", out);
        html_text(out, r->views[v]);
        fputs("</h2>\n<div class=\"row\">\n", out);
        for (int k = 0; k < r->material_count; k++) {
            const mr_report_material *m = &r->materials[k];
            char caption[512];
            if (k == 0)
                snprintf(caption, sizeof caption, "%s (reference)", m->label);
            else if (object)
                snprintf(caption, sizeof caption, "%s: object SSIM %.4f (whole frame %.4f)", m->label,
                         m->object_ssim[v], m->ssim[v]);
            else
                snprintf(caption, sizeof caption, "%s: SSIM %.4f", m->label, m->ssim[v]);
            figure(out, m->renders[v], caption, NULL);
        }
        // The maps sit under their renders: an empty cell under the reference's.
        fputs("</div>\n<div class=\"row\">\n<figure class=\"spacer\"></figure>\n", out);
        for (int k = 1; k < r->material_count; k++) {
            char caption[512];
            snprintf(caption, sizeof caption, "SSIM map, %s", r->materials[k].label);
            figure(out, r->materials[k].ssim_maps[v], caption, NULL);
        }
        fputs("</div>\n", out);
    }

    // Parameters: what each material is, with its maps.
    fputs("<h2>Materials</h2>\n", out);
    for (int k = 0; k < r->material_count; k++) {
        const mr_report_material *m = &r->materials[k];
        fputs("<h3>", out);
        html_text(out, m->label);
        fputs("</h3>\n", out);
        if (m->description) {
            fputs("<p><code>", out);
            html_text(out, m->description);
            fputs("</code></p>\n", out);
        }
        if (m->thumbnail_count > 0) {
            fputs("<div class=\"row\">\n", out);
            for (int t = 0; t < m->thumbnail_count; t++) figure(out, m->thumbnails[t], m->thumbnail_labels[t], "thumb");
            fputs("</div>\n", out);
        }
    }
    fputs("</body></html>\n", out);
}

/* ---- the summary ------------------------------------------------------------------------------------------- */

/* `, "key": [v0, v1, ...]` with %.9g numbers. */
static void json_numbers(FILE *out, const char *key, const double *values, int count) {
    fprintf(out, ", \"%s\": [", key);
    for (int v = 0; v < count; v++) fprintf(out, "%s%.9g", v ? ", " : "", values[v]);
    fputc(']', out);
}

static void write_summary(FILE *out, const mr_report *r) {
    fputs("{\n  \"matremap\": ", out);
    json_string(out, mr_version());
    fputs(",\n  \"title\": ", out);
    json_string(out, r->title);
    fputs(",\n  \"scene\": ", out);
    json_string(out, r->scene);
    fputs(",\n  \"time_label\": ", out);
    json_string(out, r->time_label ? r->time_label : "time");
    fputs(",\n  \"views\": [", out);
    for (int v = 0; v < r->view_count; v++) {
        fputs(v ? ", " : "", out);
        json_string(out, r->views[v]);
    }
    fputs("],\n  \"materials\": [", out);
    for (int k = 0; k < r->material_count; k++) {
        const mr_report_material *m = &r->materials[k];
        fprintf(out, "%s\n    {\"label\": ", k ? "," : "");
        json_string(out, m->label);
        fputs(", \"reference\": ", out);
        fputs(k == 0 ? "true" : "false", out);
        fputs(", \"description\": ", out);
        json_string(out, m->description);
        if (m->seconds >= 0.0)
            fprintf(out, ", \"seconds\": %.6f", m->seconds);
        else
            fputs(", \"seconds\": null", out);
        fputs(", \"renders\": [", out);
        for (int v = 0; v < r->view_count; v++) {
            fputs(v ? ", " : "", out);
            json_string(out, m->renders[v]);
        }
        fputs("]", out);
        if (k > 0) {
            // The whole-frame figures keep their keys; the object's are added beside them.
            fprintf(out, ", \"mean_ssim\": %.9g, \"mean_relative_rmse\": %.9g", mean(m->ssim, r->view_count),
                    mean(m->relative_rmse, r->view_count));
            json_numbers(out, "ssim", m->ssim, r->view_count);
            json_numbers(out, "relative_rmse", m->relative_rmse, r->view_count);
            if (has_object(r)) {
                fprintf(out, ", \"mean_object_ssim\": %.9g, \"mean_object_relative_rmse\": %.9g",
                        mean(m->object_ssim, r->view_count), mean(m->object_relative_rmse, r->view_count));
                json_numbers(out, "object_ssim", m->object_ssim, r->view_count);
                json_numbers(out, "object_relative_rmse", m->object_relative_rmse, r->view_count);
            }
            fputs(", \"ssim_maps\": [", out);
            for (int v = 0; v < r->view_count; v++) {
                fputs(v ? ", " : "", out);
                json_string(out, m->ssim_maps[v]);
            }
            fputs("]", out);
        }
        fputs(", \"thumbnails\": [", out);
        for (int t = 0; t < m->thumbnail_count; t++) {
            fputs(t ? ", " : "", out);
            fputs("{\"label\": ", out);
            json_string(out, m->thumbnail_labels[t]);
            fputs(", \"path\": ", out);
            json_string(out, m->thumbnails[t]);
            fputs("}", out);
        }
        fputs("]}", out);
    }
    fputs("\n  ]\n}\n", out);
}

/* Compose a document with `write` and store it at dir/name atomically. */
static mr_status store(const char *dir, const char *name, void (*write)(FILE *, const mr_report *),
                       const mr_report *r) {
    char *text = NULL;
    size_t size = 0;
    FILE *out = open_memstream(&text, &size);
    if (out == NULL) return mr_fail(MR_ERR_NOMEM, "report: no memory to compose %s", name);
    write(out, r);
    int failed = ferror(out);
    if (fclose(out) != 0 || failed) {
        free(text);
        return mr_fail(MR_ERR_NOMEM, "report: no memory to compose %s", name);
    }
    size_t length = strlen(dir) + strlen(name) + 2;
    char *path = malloc(length);
    if (path == NULL) {
        free(text);
        return mr_fail(MR_ERR_NOMEM, "report: no memory for a path");
    }
    snprintf(path, length, "%s/%s", dir, name);
    mr_status status = mr_atomic_write_bytes(path, text, size);
    free(path);
    free(text);
    return status;
}

mr_status mr_report_write(const mr_report *report, const char *dir) {
    mr_status status = check_report(report, dir);
    if (status != MR_OK) return status;
    mr_c_numeric locale; // summary.json's numbers are JSON's, "0.99", in any host locale (c_locale.h)
    if ((status = mr_c_numeric_enter(&locale, "report")) != MR_OK) return status;
    status = store(dir, "index.html", write_page, report);
    if (status == MR_OK) status = store(dir, "summary.json", write_summary, report);
    mr_c_numeric_leave(&locale);
    return status;
}
