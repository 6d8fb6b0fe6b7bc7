/*
 * report.h — SSIM evaluation reports: a self-contained folder a person opens in a browser (index.html, the PNG
 * pictures it shows, summary.json with the same numbers for scripts).
 *
 *   mr_report_material m[2] = {{"original", "gltf-specgloss ...", ...}, {"weighted", ...}};
 *   mr_report r = {"Avocado: spec-gloss -> metal-rough", "512², studio HDR ...", 4, rotations, 2, m};
 *   mr_report_write(&r, "out/report");         // writes out/report/index.html and out/report/summary.json
 *
 * The caller renders and writes the pictures (renders, SSIM maps, parameter-map thumbnails) into the folder and
 * gives their paths relative to it; this module lays them out: a summary table (mean and per-view SSIM and
 * relative RMSE of every material against the reference, and its time), then one section per view with the
 * renders side by side over their SSIM maps, then each material's parameters and map thumbnails. Nothing is
 * fetched from elsewhere: the page works offline and when the folder is moved.
 *
 * Object and whole-frame figures: when the materials carry object_ssim and object_relative_rmse (SSIM and
 * relative RMSE over the object's pixels, metrics.h), the page leads with them (the summary's first columns,
 * the best candidate chosen by them, the captions) and shows the whole-frame ssim and relative_rmse beside
 * them; summary.json keeps the whole-frame figures under their old keys (ssim, mean_ssim, relative_rmse,
 * mean_relative_rmse) and adds object_ssim, mean_object_ssim, object_relative_rmse, mean_object_relative_rmse.
 * Without them the page is the whole-frame one it always was.
 *
 * Contract: every string is UTF-8 and is escaped for HTML and JSON here; numbers must be finite (NaN and infinity
 * are MR_ERR_INVALID_ARG naming the material and view). Both files are written atomically (the folder must
 * exist). The library never prints. Thread-safe (no global state besides the thread-local last error).
 */
#ifndef MR_REPORT_H
#define MR_REPORT_H

#include "../mr_status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* One material of the report; materials[0] is the reference the others are compared with. */
typedef struct mr_report_material {
    const char *label;                   /* a short name: "spec-gloss original", "weighted" */
    const char *description;             /* what it is: model and parameters, a command line; may be NULL */
    double seconds;                      /* a time to show (conversion, render); < 0: none */
    const char *const *renders;          /* [view_count] picture paths, relative to the folder */
    const char *const *ssim_maps;        /* [view_count] SSIM-map pictures; NULL for the reference */
    const double *ssim;                  /* [view_count] SSIM against the reference; NULL for the reference */
    const double *relative_rmse;         /* [view_count] RMSE / RMS of the reference; NULL for the reference */
    int thumbnail_count;
    const char *const *thumbnails;       /* [thumbnail_count] parameter-map pictures */
    const char *const *thumbnail_labels; /* [thumbnail_count] what each shows: "base_color (b.png)" */
    const double *object_ssim;           /* [view_count] SSIM over the object (metrics.h, mask); NULL for the
                                            reference, or for every material of a whole-frame report */
    const double *object_relative_rmse;  /* [view_count] RMSE over the object / the reference's mean radiance
                                            there; NULL exactly when object_ssim is */
} mr_report_material;

typedef struct mr_report {
    const char *title;
    const char *scene;          /* one line on how the pictures were made; may be NULL */
    int view_count;             /* >= 1: views (e.g. environment rotations) */
    const char *const *views;   /* [view_count] their names: "rotation 90°" */
    int material_count;         /* >= 1 */
    const mr_report_material *materials;
    const char *time_label;     /* what the materials' seconds measure: "render time"; NULL = "time" */
} mr_report;

/* Write DIR/index.html and DIR/summary.json. MR_ERR_INVALID_ARG for a malformed report (counts, NULL arrays
 * where values are needed, object figures on some candidates but not all, non-finite numbers), MR_ERR_IO naming
 * the file, MR_ERR_NOMEM. */
mr_status mr_report_write(const mr_report *report, const char *dir);

#ifdef __cplusplus
}
#endif

#endif /* MR_REPORT_H */
