/*
 * remap.h — uniform image-based remapping: fit a target BRDF model's parameters so that its render of the fit
 * scene matches a source's (Sztrajman et al. 2019, sections 3 and 4).
 *
 * Main calls:
 *   mr_render_plan *plan;  mr_render_plan_create(&scene, &plan);          // the fit scene, once
 *   mr_remap_options o = mr_remap_options_default();                       // strategy, tolerances, seed
 *   mr_remap_result r;
 *   mr_remap(plan, source_model, source_values, target_model, &o, &r);     // built-in source
 *   mr_remap_images(plan, &(mr_remap_source){full, diffuse, specular}, target_model, &o, &r);  // any renderer
 *   mr_remap_read_render(path, &full);  mr_remap_write_pictures(prefix, plan, full, target_model, r.values);
 *
 * Objective: the L2 difference of linear HDR RGB images over the plan's pixels (the paper's metric).
 *
 * Strategies (mr_remap_strategy):
 *   - SINGLE, TWO, THREE are the paper's schemes (section 3.1), run as the paper ran them: a local bounded
 *     optimisation (nlopt BOBYQA, parameters normalised to [0,1], log scale where the descriptor says so)
 *     started from the target's defaults. SINGLE fits every parameter to the full render; TWO fits the
 *     diffuse-lobe parameters to the diffuse-only render and then the specular-lobe ones to the specular-only
 *     render (parameters touching both lobes are fitted in the second stage against the full render); THREE
 *     starts a SINGLE fit from the TWO result. TWO and THREE need the source's component images.
 *   - JOINT removes the diffuse/specular coupling that traps the paper's single-stage fits (docs/design.md
 *     principle 3): for fixed values of the nonlinear parameters (roughness, IOR, metallic) the image is affine
 *     in the LINEAR/AFFINE parameters (the descriptor's roles), so their best values are a small bounded linear
 *     least-squares solve over basis renders ("variable projection"). The remaining one to three nonlinear
 *     parameters are searched on a global grid and the best grid minima refined locally (BOBYQA); with more
 *     than three, the refinement is multi-started from seeded points. It finds the global
 *     L2 optimum of the full render.
 *   - AUTO (the default) is JOINT lobe by lobe where it can be: when the source has component images and
 *     every nonlinear target parameter belongs to one lobe (Ward's, GGX's, Phong's roughness), each lobe's
 *     shape is searched the same way against the source's render of that lobe alone (the paper's two-stage
 *     idea, without its local fits), then all linear parameters are solved jointly against the full render.
 *     The full render's global optimum can switch branch as the source varies (a plastic's faint highlight at
 *     IOR 1.02-1.14 fitted by a broad Ward lobe at alpha = 1 that reshapes the diffuse, then a narrow one):
 *     remaps of neighbouring texels would then jump. AUTO follows the source's own lobes and so stays smooth,
 *     for a slightly higher L2 error (docs/analyses.md section 3, docs/performance.md). Otherwise AUTO = JOINT.
 * Parameters flagged MR_PARAM_FIT_FIXED (e.g. glTF's KHR_materials_specular factors), switches and the parameters
 * the caller holds (opts->held) keep the values given in opts->target_values (or the defaults) and are not fitted.
 *
 * Outcome (mr_fit_outcome): the run finishing is MR_OK; how the fit ended is reported separately:
 *   - CONVERGED;
 *   - AT_BOUND: a fitted parameter ends on its range's edge while the residual stays above 1 % of the source's
 *     RMS radiance: the source wants a value the target cannot express;
 *   - UNREACHABLE: the target cannot reproduce the source: the residual stays above 25 % of the source's RMS
 *     radiance, or the model's own nonlinearity (Mitsuba's energy trimming of Ward with diffuse + specular > 1)
 *     engaged at the solution, so that its render departs from the fit, or the best affine solution at the
 *     fit's nonlinear values lies where the model rescales, so that the fit is pinned at the edge of that
 *     region (AUTO/JOINT see this while fitting; for SINGLE/TWO/THREE one projection checks it afterwards);
 *   - LOCAL_MINIMUM: AUTO/JOINT found distinct minima with nearly equal error, so the scene does not determine
 *     the parameters (not counted for a lobe carrying under 0.1 % of the energy, whose shape does not show); or
 *     a local strategy stopped where JOINT's global search, rendered, has more than 10 % less squared error
 *     (the diffuse/specular coupling trap of the paper's figure 8), unless its residual is already under
 *     0.1 % of the source's RMS radiance.
   - UNDER_RESOLVED: the render matches, but a roughness-like parameter (a nonlinear one searched on a log
 *     scale) of a lobe that shows (at least 0.1 % of the fitted render's energy) is only bounded: every value in
 *     a range whose lobes differ 4 times in width renders within 0.5 % of the source's RMS radiance of the fit
 *     (the lobe is narrower than the scene's pixels resolve). The detail names the range and the fit-scene size
 *     that would resolve the value found (pixels scale with the lobe's width). It replaces CONVERGED and a
 *     LOCAL_MINIMUM whose only ambiguity is such a parameter. The check walks each such parameter in factors of
 *     2 until the render changes: a components render and two renders per parameter for a resolved lobe, up to
 *     25 for one that is not, not counted in `renders`. mr_remap (a model source, which can be rendered anew)
 *     also looks closer: a CONVERGED fit of a source that is not black is rendered with the source 8 times
 *     closer to the first point light's highlight (same image size); if it misses there by more than 5 % and by
 *     3 times its own relative RMSE (at least 1 %), the fit matched the pixels but not the lobe (GGX's narrow
 *     lobe imitated by a wider Ward one whose spread over the pixels looks the same): UNDER_RESOLVED, naming a
 *     size 8 times larger. Two renders, not counted in `renders`, and the closer plan, which `plan` keeps
 *     (built by the first remap that needs it, shared by later ones and by concurrent threads, freed with it).
 * A black source (RMS radiance under 1e-4) or a lobe carrying under 0.1 % of the fitted render's energy has no
 * shape to determine: the fit is CONVERGED with the reflectances it solved (zero for a black source), whatever
 * distinct shapes fit equally well.
 * UNREACHABLE's rescaling test is the same for every strategy: the render at the solution must be affine in the
 * linear parameters along the segment from 0 to their values (R(b) - 2 R(b/2) + R(0) under 0.5 % of the
 * source's RMS radiance; two extra renders, not counted in `renders`).
 * Work is bounded: at most opts->max_evaluations renders per local fit, a fixed grid, a fixed start count.
 * Deterministic: the same inputs and seed give the same result for any thread count.
 */
#ifndef MR_REMAP_H
#define MR_REMAP_H

#include "../brdf/brdf.h"
#include "../mr_image.h"
#include "../mr_status.h"
#include "../render/render.h"
#include "../render/renderer.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The fit scene's default side in pixels for remaps, chosen from the accuracy/time table of docs/performance.md
 * ("Uniform remaps"): the smallest size whose median remap takes <= 50 ms on one core while its fits,
 * re-rendered at 512^2, stay within 0.001 SSIM (mean over materials) of a 512^2 fit. Lobes narrower than its
 * pixels keep their light (the fit scene integrates the pixels about the highlight: render.h,
 * mr_scene.highlight_samples), so their reflectance is fitted; their roughness is only bounded, and the outcome
 * says so (MR_FIT_UNDER_RESOLVED, naming the size that would resolve it). */
#define MR_REMAP_DEFAULT_SIZE 64

typedef enum mr_remap_strategy {
    MR_REMAP_AUTO = 0,
    MR_REMAP_SINGLE,
    MR_REMAP_TWO,
    MR_REMAP_THREE,
    MR_REMAP_JOINT,
    MR_REMAP_STRATEGY_COUNT
} mr_remap_strategy;

/* "auto", "single", "two", "three", "joint"; NULL outside the enum. */
const char *mr_remap_strategy_name(mr_remap_strategy strategy);
/* Parse one of the names above; MR_ERR_INVALID_ARG listing them otherwise. */
mr_status mr_remap_strategy_from_name(const char *name, mr_remap_strategy *out);

typedef enum mr_fit_outcome {
    MR_FIT_CONVERGED = 0,
    MR_FIT_AT_BOUND,
    MR_FIT_UNREACHABLE,
    MR_FIT_LOCAL_MINIMUM,
    MR_FIT_UNDER_RESOLVED,
    MR_FIT_OUTCOME_COUNT
} mr_fit_outcome;

/* "converged", "at-bound", "unreachable", "local-minimum", "under-resolved"; NULL outside the enum. */
const char *mr_fit_outcome_name(mr_fit_outcome outcome);
/* Parse one of the names above into *out; MR_ERR_INVALID_ARG listing them otherwise (nothing written). Readers of
 * sweep files take outcomes through this, so that every reader knows every outcome the writer may use. */
mr_status mr_fit_outcome_from_name(const char *name, mr_fit_outcome *out);

/* The local stage of a fit: after AUTO's global grid (or from a warm start), and the SINGLE/TWO/THREE strategies'
 * whole fit, a local minimisation in the normalised coordinates.
 *   - MR_LOCAL_GRADIENT: bounded Levenberg-Marquardt (levenberg.h) on the image residual with the model's analytic
 *     derivatives (brdf.h, eval_grad) rendered per pixel (render.h, mr_render_derivatives_into); for AUTO/JOINT's
 *     variable projection, the reduced residual with Kaufman's Gauss-Newton matrix. A few steps, each one render
 *     of the value and one of the derivatives, where BOBYQA spends one render per trial point.
 *   - MR_LOCAL_BOBYQA: Powell's derivative-free BOBYQA (nlopt), the engine before issue 31.
 *   - MR_LOCAL_AUTO (0): gradient for AUTO and JOINT where it can (the target model has eval_grad, its renders are
 *     the built-in renderer's, the plan is lit by point lights only), else BOBYQA; the paper's local strategies
 *     (SINGLE, TWO, THREE) keep BOBYQA, whose traps they reproduce (docs/paper-reproduction.md).
 * A gradient method asked for where it cannot run is refused (MR_ERR_UNSUPPORTED, saying why).
 * Both find the same minima on the bench pairs (docs/performance.md, "The fit engine"). */
typedef enum mr_local_method {
    MR_LOCAL_AUTO = 0,
    MR_LOCAL_GRADIENT,
    MR_LOCAL_BOBYQA,
    MR_LOCAL_METHOD_COUNT
} mr_local_method;

/* "auto", "gradient", "bobyqa"; NULL outside the enum. */
const char *mr_local_method_name(mr_local_method method);
/* The method called `name`; MR_ERR_INVALID_ARG listing the valid names otherwise. */
mr_status mr_local_method_from_name(const char *name, mr_local_method *out);

typedef struct mr_remap_options {
    mr_remap_strategy strategy;  /* MR_REMAP_AUTO */
    int max_evaluations;         /* renders per local fit: 400 */
    double xtol;                 /* relative step tolerance of local fits, in normalised coordinates: 1e-6 */
    int grid_points;             /* AUTO's global grid per nonlinear dimension: 16 (1-D), 8 (2-D), 6 (3-D)
                                    if 0 (docs/performance.md: finer grids found the same fits) */
    int starts;                  /* AUTO/JOINT with more than 3 nonlinear parameters: multi-start count: 8 (a
                                    gradient local stage starts from twice as many: each of its local fits sees
                                    less of the range than a BOBYQA fit's first steps, for a fraction of the
                                    renders; docs/remap.md) */
    unsigned long seed;          /* seeds the multi-start points: 1 (0 = 1: a zeroed struct is the defaults) */
    const double *target_values; /* optional packed target values: the values of fixed parameters and
                                    switches (NULL: the target's defaults) */
    int skip_global_check;       /* SINGLE/TWO/THREE: 0 = also run AUTO's global search to detect a local
                                    minimum (its renders are not counted in the result); 1 = skip it */
    unsigned held;               /* bit p set: the target's parameter p is held at its target_values value (or
                                    default) instead of fitted, e.g. a roughness both sides share: 0 */
    int threads;                 /* OpenMP threads of the remap's renders: 0 = the plan's rule (render.h,
                                    mr_scene.threads: automatic by default, one thread for the default 64^2
                                    fit scene); n >= 1: n. The result does not depend on it */
    mr_brdf_ties ties;           /* target parameters held at the source's values (brdf.h; mr_remap only, which
                                    knows the source's values; mr_remap_images refuses them): zeroed = none. The
                                    commands fill mr_brdf_default_ties (gltf -> openpbr: base_metalness=metallic) */
    const double *initial_values; /* optional packed target values to start from (a warm start, e.g. a
                                    neighbouring texel's answer: src/remap/direct.h): the fitted parameters start
                                    there (fixed ones, switches and held ones still come from target_values);
                                    for AUTO and JOINT it also replaces the global grid search of the nonlinear
                                    parameters (and the multi-start) by one local refinement (local_method; BOBYQA's
                                    first steps MR_REMAP_WARM_STEP) from them, lobe by lobe for AUTO, so the fit
                                    finds the minimum of the start's basin, and no second minimum to call the
                                    fit ambiguous (LOCAL_MINIMUM by ambiguity is not reported). NULL: none */
    unsigned freed;              /* bit p set: the target's parameter p is fitted although the model holds it by
                                    default (MR_PARAM_FIT_FIXED: glTF's KHR_materials_specular factors and IOR, a
                                    coat), e.g. a glTF whose white highlight outshines a 4 % dielectric; a hold
                                    or a tie still wins; bits of parameters not held by default are refused: 0 */
    mr_renderer *target_renderer; /* who renders the target during the fit (renderer.h): NULL or the built-in one =
                                    the plan, in process, as described above; an external renderer (blender,
                                    three) renders every target render of the fit in the plan's scene, so the
                                    values fitted are the ones that renderer needs. It must render the target
                                    by values (mr_renderer_supports). AUTO and JOINT without initial_values
                                    fit the built-in model first, in process, and start from its answer as
                                    from initial_values (one local refinement through the renderer, which
                                    corrects where the two differ); `renders` counts the renderer's renders
                                    only. Its images are taken as they are: the affine-departure test of
                                    UNREACHABLE and the closer look of UNDER_RESOLVED are the built-in
                                    renderer's only (three.js is not quite affine in a metal's F0). One
                                    without component renders (three)
                                    fits AUTO against the full render only (no lobe-by-lobe stage), refuses
                                    TWO and THREE, and takes the lobes' energies of the resolution check from
                                    the built-in model. NULL: built-in */
    mr_renderer *source_renderer; /* mr_remap only: who renders the source (its full render and, when it has
                                    them, its components; the closer look of UNDER_RESOLVED too): NULL =
                                    built-in */
    mr_local_method local_method; /* how local fits step (mr_local_method): MR_LOCAL_AUTO */
} mr_remap_options;

/* Which renderer renders each side of remaps that files record (sweeps: the sweep file's "# remap:" line) by name,
 * and the external renderers' samples (mr_renderer_options.samples). Zeroed: both built-in. */
typedef struct mr_remap_renderers {
    char source[16]; /* "" or "builtin", "blender", "three" (renderer.h) */
    char target[16];
    int samples;     /* 0: each renderer's default */
} mr_remap_renderers;

/* 1 if either side names an external renderer. */
int mr_remap_renderers_external(const mr_remap_renderers *renderers);

/* The first steps of a warm-started AUTO/JOINT fit (mr_remap_options.initial_values), in normalised
 * coordinates (a parameter's range as [0, 1], log-spaced for roughness): 0.005 is a factor 1.05 in a GGX alpha
 * over [1e-4, 1], about the distance between neighbouring texels' answers; on a crop of a real texture set it
 * took 12 % fewer renders than 0.02 or 0.05, for answers as close to full remaps (src/remap/direct.h). */
#define MR_REMAP_WARM_STEP 0.005

/* The defaults listed beside each field. */
mr_remap_options mr_remap_options_default(void);

/* Renders of the fit scene by the source. `full` is required; `diffuse` and `specular` (its components) are
 * needed by the TWO and THREE strategies. All 3-channel, the plan's size, linear radiance. */
typedef struct mr_remap_source {
    const mr_image *full;
    const mr_image *diffuse;
    const mr_image *specular;
} mr_remap_source;

typedef struct mr_remap_result {
    double values[MR_BRDF_MAX_VALUES]; /* the target's packed parameter values */
    double rmse;                       /* RMS difference of the linear RGB renders, over the whole image */
    double relative_rmse;              /* rmse / RMS of the source over the pixels the object covers */
    double ssim;                       /* display-referred SSIM of the two renders (metrics.h) */
    long renders;                      /* target renders made */
    double seconds;                    /* wall time of the remap */
    mr_fit_outcome outcome;
    char detail[192];                  /* one line: why the outcome is what it is */
    mr_local_method local_method;      /* the local stage the fit ran: MR_LOCAL_GRADIENT or MR_LOCAL_BOBYQA */
} mr_remap_result;

/* Fit `target` to the source images. opts may be NULL (defaults). Fails (MR_ERR_INVALID_ARG) on images of the
 * wrong size or channel count, on a value that is not finite radiance >= 0 (NaN, Inf, negative: the message
 * names the pixel and channel), or on a TWO/THREE strategy without component images; MR_ERR_EXTERNAL if nlopt
 * fails. *out is written only on success. */
mr_status mr_remap_images(const mr_render_plan *plan, const mr_remap_source *source, const mr_brdf_model *target,
                          const mr_remap_options *opts, mr_remap_result *out);

/* Render the source material (full, diffuse, specular) with `plan` and fit `target` to it. */
mr_status mr_remap(const mr_render_plan *plan, const mr_brdf_model *source_model, const double *source_values,
                   const mr_brdf_model *target, const mr_remap_options *opts, mr_remap_result *out);

/* A renderer's own material as the source (renderer.h: a .blend material from mr_renderer_describe): its full
 * render of the plan's scene and, when the renderer gives them, its diffuse and specular parts, fitted as
 * mr_remap_images fits images (opts->source_renderer is not used; `renderer` renders). `full` (optional, 3-channel,
 * the plan's size) receives the source's full render, e.g. for mr_remap_write_pictures_by. Errors: the renderer's
 * and mr_remap_images'. */
mr_status mr_remap_external(const mr_render_plan *plan, mr_renderer *renderer, const mr_external_material *material,
                            const mr_brdf_model *target, const mr_remap_options *opts, mr_remap_result *out,
                            mr_image *full);

/* Irradiance matching (paper section 4): renders by another renderer use its own light units. Given that
 * renderer's diffuse-only render of a Lambertian sphere of albedo `albedo` in the fit scene (`reference`),
 * *scale is the factor that brings its images to matremap's units: the ratio of matremap's Lambert render to
 * the reference, summed over pixels fully inside the silhouette and lit above 1 % of the peak (edges and the
 * terminator are left out, where filters and shading normals differ most). Multiply the source images by it.
 * MR_ERR_INVALID_ARG if the reference has the wrong size or is black where matremap's render is lit. */
mr_status mr_irradiance_scale(const mr_render_plan *plan, const mr_image *reference, double albedo,
                              double *scale);

/* ---- a remap's files: the renders read, the pictures written (pictures.c) ---------------------------------- */

/* Read a render to fit (a source image or an irradiance reference) from `path` as RGB (*out, the caller frees it),
 * every value finite radiance >= 0 (mr_image_check_radiance labelled "image 'PATH'"). mr_img_read's errors, or
 * MR_ERR_INVALID_ARG naming the file, the pixel, the channel and the value; on failure *out is NULL. */
mr_status mr_remap_read_render(const char *path, mr_image **out);

/* The renders of a remap from images (`matremap remap --from-images`): paths[0] the full render, paths[1] and
 * paths[2] its diffuse and specular parts (NULL when absent), `reference_path` a Lambert render for
 * mr_irradiance_scale (NULL when absent), each read by mr_remap_read_render into images[k] and *reference (NULL for
 * an absent one; the caller frees them). The full render decides the scene's size: it must be square and every
 * other render its size. Errors: mr_remap_read_render's; MR_ERR_INVALID_ARG "'PATH' is WxH: fit-scene renders are
 * square", "'PATH' is WxH but 'FULL' is WxH: all renders must have the same size". On failure nothing is left
 * allocated (every output NULL). */
mr_status mr_remap_read_sources(const char *const paths[3], const char *reference_path, mr_image *images[3],
                                mr_image **reference);

#define MR_REMAP_PICTURE_COUNT 3

/* The file of picture k (0 the source's render, 1 the target's, 2 the SSIM map) under `prefix`: PREFIX_source.png,
 * PREFIX_target.png, PREFIX_ssim.png by mr_img_prefixed_name's rule (io/image_io.h: "out/" + "source.png" ->
 * "out/source.png"), into out (size bytes). MR_ERR_INVALID_ARG for k outside [0, MR_REMAP_PICTURE_COUNT) or a
 * name that does not fit. */
mr_status mr_remap_picture_path(const char *prefix, int k, char *out, size_t size);

/* The pictures of a remap (`matremap remap --images PREFIX`), all or none (mr_img_write_set): the source's full
 * render `source` (the plan's size), the target's render with `values` on `plan`, and the SSIM map between them
 * (mr_ssim_map_visualise), each sRGB PNG at mr_remap_picture_path(prefix, k). Errors: mr_render's, mr_ssim's and
 * mr_img_write_set's (naming the file); nothing is written on failure. */
mr_status mr_remap_write_pictures(const char *prefix, const mr_render_plan *plan, const mr_image *source,
                                  const mr_brdf_model *target, const double *values);
/* The same with the target rendered by `renderer` (NULL: built-in), as the fit saw it. */
mr_status mr_remap_write_pictures_by(const char *prefix, const mr_render_plan *plan, const mr_image *source,
                                     mr_renderer *renderer, const mr_brdf_model *target, const double *values);

#ifdef __cplusplus
}
#endif

#endif /* MR_REMAP_H */
