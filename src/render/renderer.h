/*
 * renderer.h — renderers behind one set of calls: the built-in renderer (render.h) and real ones run as
 * long-lived server processes (Blender Cycles, three.js in headless Chromium), so that a remap, a sweep, a report
 * or a texture set's direct remap can take its source images from one renderer and fit its target in another
 * (the paper treats both renderers as black boxes: Sztrajman et al. 2019, section 3).
 *
 * Main calls:
 *   mr_renderer *r;  mr_renderer_open("blender", NULL, &r);              // nothing starts yet
 *   mr_renderer_render(r, plan, model, values, full, diffuse, specular);  // the plan's scene, by the renderer
 *   mr_external_material *m;  mr_renderer_describe(r, "shop.blend:Lacquer", &m);  // a renderer's own material
 *   mr_external_material_set(m, "Mix Shader.Fac", (double[]){0.3}, 1);
 *   mr_renderer_render_external(r, plan, m, full, diffuse, specular);
 *   mr_external_material_free(m);  mr_renderer_free(r);                 // ends the processes
 *
 * The scene is a render plan's (render.h): an external renderer is sent its camera, its sphere and its point
 * lights, and renders exactly that framing (docs/renderers.md), so the plan's pixels, coverage and background are
 * valid for its images; the image it returns is checked against the plan's coverage (a renderer that frames the
 * scene differently fails, it is not fitted). Meshes and environment lights are the built-in renderer's only.
 *
 * External renderers (src/render/renderer_process.c; the protocol is docs/renderers.md's): one server process per
 * worker, started on the first render that needs one (a render waits for an idle process or starts another, at
 * most mr_renderer_options.processes), kept for the renderer's life so that start-up is paid once. A process that
 * dies or stops answering within the timeout is ended and restarted, and the render retried on the new one (twice
 * at most), so a sweep loses nothing to a crash: the same request renders the same image (fixed seed). Every call
 * is safe from several threads at once (sweeps call from OpenMP threads).
 *
 * Errors: MR_ERR_EXTERNAL when the renderer cannot start (the message names the program and the Debian package
 * that provides it), dies three times on one render, or answers with an error (its message, and the tail of its
 * log); MR_ERR_UNSUPPORTED for a model the renderer does not render by values, a component it cannot separate,
 * a scene it cannot show (a mesh, an environment light); MR_ERR_INVALID_ARG for bad arguments.
 */
#ifndef MR_RENDERER_H
#define MR_RENDERER_H

#include "../brdf/brdf.h"
#include "../mr_image.h"
#include "../mr_status.h"
#include "render.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct mr_renderer mr_renderer;
typedef struct mr_external_material mr_external_material;

typedef struct mr_renderer_options {
    int samples;            /* path tracers' samples per pixel (Blender), three.js's sub-pixel grid (s x s with
                               s = floor(sqrt(samples)), at most 8): 0 = the renderer's default
                               (MR_RENDERER_DEFAULT_SAMPLES_*) */
    unsigned long seed;     /* the path tracer's fixed seed: 0 */
    int processes;          /* server processes at most (one per worker): 0 = omp_get_max_threads() */
    int threads;            /* CPU threads per process's render: 0 = all cores shared by the processes
                               (cores / processes, at least 1) */
    double timeout_seconds; /* longest wait for one answer (start-up or render) before the process is ended and
                               restarted: 0 = 300 */
    const char *program;    /* the server's program: NULL = $MATREMAP_BLENDER or "blender" (blender), $MATREMAP_NODE
                               or "node" (three) */
} mr_renderer_options;

/* Blender's default sample count at the fit scene's 64^2: Cycles' noise floor there, two seeds apart, is below
 * the fits' own residuals (docs/renderers.md, "Noise floor"). three.js: a 4 x 4 sub-pixel grid. */
#define MR_RENDERER_DEFAULT_SAMPLES_BLENDER 256
#define MR_RENDERER_DEFAULT_SAMPLES_THREE 16

/* The renderers' names, in order: "builtin", "blender", "three"; NULL past the end. */
const char *mr_renderer_name_at(int index);

/* Whether renderer `name` exists and renders `model` by values (NULL model: the name only), without starting it:
 * MR_OK, MR_ERR_INVALID_ARG for an unknown name (listing the known ones), MR_ERR_UNSUPPORTED naming the models it
 * renders. */
mr_status mr_renderer_check(const char *name, const mr_brdf_model *model);

/* A renderer by name (*out, freed by mr_renderer_free). Starts nothing: the first render starts its first
 * process. opts may be NULL (defaults). MR_ERR_INVALID_ARG for an unknown name (listing the known ones) or bad
 * options. */
mr_status mr_renderer_open(const char *name, const mr_renderer_options *opts, mr_renderer **out);

/* Ends the renderer's processes (asks them to quit, then kills what is left after 5 s) and removes its temporary
 * folder. NULL is ignored. */
void mr_renderer_free(mr_renderer *renderer);

/* "builtin", "blender", "three". */
const char *mr_renderer_name(const mr_renderer *renderer);

/* 1 for the built-in renderer: callers that hold one may take their faster in-process path (remap.h does). */
int mr_renderer_is_builtin(const mr_renderer *renderer);

/* 1 if the renderer renders `model` by values (built-in: every model; blender: cycles-principled, lambert; three:
 * gltf, lambert). */
int mr_renderer_supports(const mr_renderer *renderer, const mr_brdf_model *model);

/* 1 if it returns a material's diffuse and specular parts apart (built-in, blender: yes; three: no). */
int mr_renderer_has_components(const mr_renderer *renderer);

/* Start one process now (a no-op for the built-in renderer) and return its version line in version[size] (e.g.
 * "blender 3.4.1"), so that a command can fail early, before any work, when the renderer cannot start. */
mr_status mr_renderer_start(mr_renderer *renderer, char *version, size_t size);

/* Render the material (model, packed values as brdf.h) in `plan`'s scene: the full render into `full`, its diffuse
 * and specular parts into `diffuse` and `specular` (each 3-channel, the plan's size; any may be NULL, not all).
 * Linear radiance, the plan's background where the object is not. */
mr_status mr_renderer_render(mr_renderer *renderer, const mr_render_plan *plan, const mr_brdf_model *model,
                             const double *values, mr_image *full, mr_image *diffuse, mr_image *specular);

/* Renders so far, and the processes started (restarts included), for reports. */
long mr_renderer_render_count(const mr_renderer *renderer);
long mr_renderer_process_starts(const mr_renderer *renderer);

/* ---- a renderer's own materials (Blender: a material of a .blend file) ---------------------------------------- */

/* The material `reference` names, "FILE.blend:MATERIAL" (blender), and the inputs it exposes as parameters: every
 * unlinked float or colour input of its node tree's shading nodes, by path "NODE.SOCKET" (docs/renderers.md),
 * at the values the file holds (*out, freed by mr_external_material_free). MR_ERR_IO for a missing file,
 * MR_ERR_INVALID_ARG for a material that is not there (listing the ones that are), MR_ERR_UNSUPPORTED for a
 * renderer without materials of its own. */
mr_status mr_renderer_describe(mr_renderer *renderer, const char *reference, mr_external_material **out);
void mr_external_material_free(mr_external_material *material);

/* "FILE.blend:MATERIAL" as given. */
const char *mr_external_material_reference(const mr_external_material *material);
int mr_external_material_param_count(const mr_external_material *material);
/* Parameter k: its path, its value count (1 or 3: a colour), its range and current values (values[3]). NULL / 0
 * for k out of range. */
const char *mr_external_material_param(const mr_external_material *material, int k, int *channels, double *min_value,
                                       double *max_value, double *values);
/* Set parameter `path` to values[0..count) (count 1, or 3 for a colour; one value sets a colour grey).
 * MR_ERR_INVALID_ARG for an unknown path (listing the known ones), a wrong count, a value that is not finite. */
mr_status mr_external_material_set(mr_external_material *material, const char *path, const double *values,
                                   int count);

/* Render it as mr_renderer_render does a model. */
mr_status mr_renderer_render_external(mr_renderer *renderer, const mr_render_plan *plan,
                                      const mr_external_material *material, mr_image *full, mr_image *diffuse,
                                      mr_image *specular);

#ifdef __cplusplus
}
#endif

#endif /* MR_RENDERER_H */
