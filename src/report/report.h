/*
 * report.h — SSIM evaluation reports: a self-contained folder a person opens in a browser (index.html, the PNG
 * pictures it shows, summary.json with the same numbers for scripts).
 *
 *   mr_report_input in[2] = {{"original", NULL, NULL, avocado}, {"weighted", NULL, NULL, converted}};
 *   mr_report_options o = {0};                 // zero: the defaults
 *   o.env_path = "studio.hdr";
 *   mr_report_result *r = NULL;
 *   mr_report_make(in, 2, "out/report", &o, &r); // renders, pictures, index.html, summary.json
 *   printf("%.4f\n", r->materials[1].mean_object_ssim);
 *   mr_report_result_free(r);
 *
 *   mr_report_material m[2] = {{"original", "gltf-specgloss ...", ...}, {"weighted", ...}};
 *   mr_report r = {"Avocado: spec-gloss -> metal-rough", "512², studio HDR ...", 4, rotations, 2, m};
 *   mr_report_write(&r, "out/report");         // writes out/report/index.html and out/report/summary.json
 *
 * Two levels. mr_report_make does everything from materials (mr_material, render/render.h) or glTF scenes
 * (mr_gltf_scene, gltf/mr_gltf_scene.h): it renders them, picks the exposure, compares, writes the pictures and
 * thumbnails and then the page (see "Making a report" below); it is what `matremap report` calls.
 * mr_report_write only lays out a page: its caller renders and writes the pictures (renders, SSIM maps,
 * parameter-map thumbnails) into the folder and gives their paths relative to it; this module lays them out: a
 * summary table (mean and per-view SSIM and relative RMSE of every material against the reference, and its
 * time), then one section per view with the renders side by side over their SSIM maps, then each material's
 * parameters and map thumbnails. Nothing is
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
 * exist for mr_report_write; mr_report_make writes a whole folder atomically, see "The folder" below). The
 * library never prints: mr_report_make tells its progress to a callback. Thread-safe (no global state besides the
 * thread-local last error).
 */
#ifndef MR_REPORT_H
#define MR_REPORT_H

#include "../mr_image.h"
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

/* ---- Making a report (make.c) ----------------------------------------------------------------------------------
 * mr_report_make renders every input for every view and compares it with the first (the reference):
 *   - Inputs are all materials, each rendered on the unit sphere of the fit scene (render.h, mr_scene_fit) or on
 *     options.mesh (the paper's material-test sphere, say) seen by options.camera, or all
 *     glTF scenes, each rendered as its mesh with its materials, seen by the camera that frames the reference
 *     (mr_camera_frame_mesh) from camera_direction, by default a three-quarter view onto the reference's broadest
 *     side (along the axis of its smallest extent, raised and turned a little).
 *   - Light: without an environment map the fit scene's point light, one view; with one, the map alone, turned
 *     by 360/rotations degrees for each view.
 *   - One render plan per view is shared by every input (an input with geometry of its own, i.e. a scene whose
 *     mesh or surfaces differ from the one before it, gets its own plan and is compared over the union of both
 *     coverages).
 *   - Exposure: unless given, the one that brings the reference's object pixels (coverage > 0.5) in the first
 *     view to a mean luminance of 0.18; pictures and SSIM use it.
 *   - Figures per candidate and view: SSIM and relative RMSE (RMSE / RMS of the reference) over the whole frame,
 *     and over the object (metrics.h masks; object RMSE / the reference's mean radiance there).
 *   - Files in `dir` (see "The folder" below): view<V>_material<K>.png (renders, sRGB at the exposure),
 *     ssim_view<V>_material<K>.png (SSIM maps, candidates only), map_material<K>_<N>.png (thumbnails of every
 *     map: each material's BRDF maps, then a scene's normal, occlusion and emissive maps; box-filtered to at most
 *     MR_REPORT_THUMBNAIL_SIDE pixels, at most MR_REPORT_MAX_THUMBNAILS per input), then index.html and
 *     summary.json (mr_report_write). Every file is written atomically.
 * Failure: MR_ERR_INVALID_ARG naming the input or option (count < 1, an input with neither or both of material
 * and scene, materials mixed with scenes, an option out of range, environment options without a map, a mesh
 * with scenes or without a map, a camera without a mesh, an invalid mesh: mr_mesh_validate's message), the
 * environment map's read error (naming the file), MR_ERR_IO naming the folder when it cannot be created or is
 * not a folder, MR_ERR_INVALID_ARG naming the entry when the folder holds something no report writes, a render's
 * or a write's error, MR_ERR_CANCELLED when the progress callback asks to stop. Nothing is written before the
 * inputs, the options and the map have been checked.
 *
 * The folder is an output as a whole: everything is written into a scratch folder beside `dir` (the same parent,
 * a hidden name: ".NAME.matremap-new-<pid>-<n>") and renamed to `dir` once complete. When `dir` exists, it is
 * replaced only then: the previous report is renamed aside (".NAME.matremap-old-<pid>-<n>"), the new one in, and
 * the old one removed (if the second rename fails, the old one is renamed back). So a failure at any point (a full
 * disk, a render error, a cancel) leaves the previous report, or nothing, never a part of a report, and a report
 * made with fewer views or inputs leaves no picture of the one before it. Which folders may be replaced: a missing
 * one, an empty one, or one that holds only files a report writes (index.html, summary.json and pictures named as
 * above); a folder holding anything else (a file of someone else's, a sub-folder) is refused, naming the entry, and
 * left untouched: a report never deletes what it did not write. The caller keeps its inputs out of `dir` (it is
 * replaced; `matremap report` refuses an input inside it). A process killed midway leaves its scratch folder
 * beside `dir` (hidden; remove it by hand); the folder itself is as it was. Between the two renames, for an
 * instant, `dir` does not exist. */

#define MR_REPORT_DEFAULT_SIZE 384
/* Defaults chosen with `make bench BENCH_ARGS="--only report-accuracy"` (docs/performance.md, "Defaults for
 * matremap report"): from N = 256 every view of the assets is within SSIM 0.9966 of N = 16384 and the report's
 * SSIM within 0.0001; 384² is within 0.002 of 512² and keeps its ranking. Cheaper than 1024 at 256². */
#define MR_REPORT_DEFAULT_ENV_SAMPLES 256
/* Directions about each pixel's mirror direction (mr_light.reflection_samples): without them a smooth material
 * (the CesiumMilkTruck's glossiness 1) shows the pattern's directions as sparkles instead of the map. 10 fix the
 * truck's mirrors; glossy lobes (GGX alpha 0.003 - 0.1) need about 40 for SSIM 0.99 (docs/rendering.md,
 * "Reflection samples"), for about a quarter more report time. */
#define MR_REPORT_DEFAULT_REFLECTION_SAMPLES 40
#define MR_REPORT_NO_REFLECTION_SAMPLES (-1) /* mr_report_options.reflection_samples: the pattern alone */
#define MR_REPORT_MIN_SIZE 16
#define MR_REPORT_MAX_VIEWS 36
#define MR_REPORT_THUMBNAIL_SIDE 128
#define MR_REPORT_MAX_THUMBNAILS 64

struct mr_material;    /* render/render.h */
struct mr_mesh;        /* render/render.h */
struct mr_camera;      /* render/render.h */
struct mr_gltf_scene;  /* gltf/mr_gltf_scene.h */

/* One thing to compare: exactly one of material and scene (both borrowed for the call). */
typedef struct mr_report_input {
    const char *label;                  /* its name in the report; NULL = the material's model, the scene's path */
    const char *description;            /* what it is (a command line, say); NULL = made up: a material's model
                                           and values ("ggx alpha=0.2 f0=0.5,0.5,0.5 ...", maps as name=@source),
                                           a scene's path, triangle count and materials with their models */
    const struct mr_material *material; /* rendered on the sphere */
    const struct mr_gltf_scene *scene;  /* rendered as its mesh */
    struct mr_renderer *renderer;       /* materials only: who renders it (render/renderer.h): NULL = the built-in
                                           renderer; an external one (blender, three) renders the fit scene (no
                                           environment map, no mesh) and a uniform material (no maps) */
    const struct mr_external_material *external; /* instead of `material`: a renderer's own material (a .blend
                                           file's), rendered by `renderer`; no thumbnails */
} mr_report_input;

/* How to make the report. Zero-initialise for the defaults (opts may also be NULL). */
typedef struct mr_report_options {
    int size;                  /* render side in pixels: 0 = MR_REPORT_DEFAULT_SIZE, else MR_REPORT_MIN_SIZE ..
                                  MR_RENDER_MAX_SIZE */
    const char *env_path;      /* an equirectangular HDR map (.hdr, .exr) read by mr_report_make; NULL = none */
    const mr_image *env;       /* or a map in memory (borrowed); env_path, if also set, only names it on the page */
    double env_scale;          /* the map's radiance scale: 0 = its mean luminance brought to 0.5; else > 0 */
    int rotations;             /* views: 0 = 4 with a map, 1 without; else 1 .. MR_REPORT_MAX_VIEWS (more than 1
                                  needs a map) */
    int env_samples;           /* the map's fixed directions: 0 = MR_REPORT_DEFAULT_ENV_SAMPLES, else 1 ..
                                  MR_ENV_MAX_SAMPLES */
    int reflection_samples;    /* directions about each pixel's mirror direction: 0 =
                                  MR_REPORT_DEFAULT_REFLECTION_SAMPLES, MR_REPORT_NO_REFLECTION_SAMPLES = none,
                                  else 1 .. MR_ENV_MAX_REFLECTION_SAMPLES */
    double exposure;           /* display exposure of pictures and SSIM: 0 = automatic (see above); else > 0 */
    int has_camera_direction;  /* scenes only: camera_direction is the direction from the reference's centre to
                                  the camera (non-zero); 0 = the three-quarter view */
    double camera_direction[3];
    const struct mr_mesh *mesh; /* materials only: render them on this mesh (borrowed for the call, e.g. an OBJ
                                  file's: io/obj_load.h) instead of the unit sphere, their maps read at its UVs;
                                  needs an environment map (the fit scene's point light is placed for the unit
                                  sphere). NULL = the sphere */
    const char *mesh_name;     /* names the mesh on the page ("matsphere.obj"); NULL = "a mesh" */
    const struct mr_camera *camera; /* with mesh: the camera (e.g. mr_camera_paper(), render.h); NULL = the mesh
                                  framed from +z (mr_camera_frame_mesh's defaults) */
    int threads;               /* mr_scene.threads of plans and renders: 0 = automatic, else 1 .. 1024 */
    const char *title;         /* the page's title; NULL = "matremap report" */
    /* Called before each view is rendered (done = views finished, total = views, what = "view") and once when
     * all are (done == total); NULL = none. A non-zero return stops the report with MR_ERR_CANCELLED. */
    int (*progress)(void *user, int done, int total, const char *what);
    void *progress_user;
} mr_report_options;

/* One input's figures. The reference's are 1 (SSIM) and 0 (relative RMSE) in every view. */
typedef struct mr_report_figures {
    char *label;                   /* as on the page */
    double seconds;                /* render time over all views */
    double *ssim, *relative_rmse;  /* [view_count], the whole frame */
    double *object_ssim, *object_relative_rmse; /* [view_count], over the object */
    double mean_ssim, mean_relative_rmse, mean_object_ssim, mean_object_relative_rmse; /* over the views */
} mr_report_figures;

typedef struct mr_report_result {
    int view_count;
    double exposure;               /* the exposure used */
    double env_scale;              /* the map's radiance scale used; 0 without a map */
    int material_count;            /* the inputs */
    mr_report_figures *materials;  /* [material_count] */
} mr_report_result;

/* Make the report of inputs[0 .. count-1] in folder `dir` (see above). *out (may be NULL: no figures wanted)
 * receives the figures, caller-owned (mr_report_result_free); it is NULL on failure. */
mr_status mr_report_make(const mr_report_input *inputs, int count, const char *dir, const mr_report_options *opts,
                         mr_report_result **out);

/* NULL-safe. */
void mr_report_result_free(mr_report_result *result);

#ifdef __cplusplus
}
#endif

#endif /* MR_REPORT_H */
