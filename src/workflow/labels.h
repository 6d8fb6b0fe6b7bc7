/*
 * labels.h — image-based labels for the learned specular -> metallic converter (docs/training.md): for one
 * spec-gloss texel, the glTF metal-rough material that renders most like it, on a sphere under several
 * environments and glossinesses, by a chosen image objective.
 *
 * Main calls:
 *   mr_wf_label_options o = mr_wf_label_options_default();    // built-in synthetic lights, 4 glossinesses
 *   mr_wf_label_scene *scene;  mr_wf_label_scene_create(&o, &scene);
 *   mr_wf_label_fit(scene, &(mr_wf_spec){{0.5, 0.1, 0.1}, {0.04, 0.04, 0.04}, 0}, &metal, &result);
 *   mr_wf_label_scene_free(scene);
 *
 * Why a basis, not renders. Both glTF models are linear in their colours once glossiness and metallic are
 * fixed. With w = (1 - |wi.h|)^5 (Schlick), S = D V (GGX, height-correlated Smith) and, per pixel and channel,
 *     P  = sum over light samples of L cos (1 - w) / pi,   Q0 = sum of L cos (1 - w) S,   Q1 = sum of L cos w S,
 * the renders of the two materials at one glossiness g (roughness 1 - g on the metal-rough side) are
 *     spec-gloss (d, s):   d_c (1 - max s)(1 - s_c) P + s_c Q0 + Q1                      (gltf_specgloss.c)
 *     metal-rough (A, m):  0.96 (1 - m) A_c P + ((1 - m) 0.04 + m A_c) Q0 + Q1            (gltf.c, ior 1.5)
 * so one render of three basis materials per view (mr_render with `gltf-specgloss`, its diffuse and specular
 * components at d = 1, s = 0 and s = 1) gives every material's render exactly, up to float rounding (a test
 * checks it against mr_render of both models). A label fit then costs pixel arithmetic, not renders.
 *
 * Views: every environment map (equirectangular, borrowed during create) at every glossiness, on the unit
 * sphere of the fit scene's camera (mr_scene_fit) at `size`² pixels, with the renderer's fixed sample pattern
 * (env_samples directions plus reflection_samples about each mirror direction). Environments are scaled to a
 * mean luminance of 0.5. Without maps, two synthetic grey environments are built (a studio of three soft boxes
 * over a dark floor, and a sky with a sun over a dark ground): the lights the labels are made under are then
 * none of the maps the evaluation uses, and grey, so a grey texel's label is grey.
 *
 * Objectives (mr_wf_objective), on the interior pixels (coverage 1) of each view, radiance x scaled by the
 * view's exposure e (a white Lambertian sphere's mean interior radiance maps to 1):
 *   LINEAR   (e x_target - e x_source)^2                              the paper's L2 on linear HDR renders
 *   DISPLAY  (T(e x_target) - T(e x_source))^2, T(y) = sqrt(y / (1 + y))   display-referred: Reinhard's
 *            compression then a gamma-2 encoding, so dark and bright texels weigh as a viewer sees them
 *   LOG      (log(e x_target + 0.01) - log(e x_source + 0.01))^2      log radiance (relative errors)
 *   EXPOSED  DISPLAY's T, with e chosen per texel and view so that the source render's mean interior luminance
 *            is 0.18: how SSIM reports see a picture (each exposed to its own mid-grey, docs/metrics.md)
 *   LUMA     EXPOSED on the Rec. 709 luminance of each pixel, plus chroma_weight x EXPOSED's per-channel term:
 *            what SSIM measures (structure of the display-referred luma) first, colour second
 * averaged over pixels, channels and views, plus regularisation * (|A - A_w|^2 + (m - m_w)^2), where (A_w, m_w)
 * is the albedo-weighted analytic inverse (workflow.h, MR_WF_WEIGHTED, glTF reading of the diffuse): where the
 * images cannot tell metallic values apart (dark texels), the label keeps the analytic answer instead of an
 * arbitrary optimum.
 *
 * The fit (variable projection): for a fixed metallic the albedo is solved (per channel: closed form for LINEAR,
 * projected Gauss-Newton from the LINEAR solution with step halving for DISPLAY, LOG and EXPOSED; jointly in all
 * three channels for LUMA, whose luminance couples them); the metallic is searched on a grid of 11 values then
 * refined by golden-section search around the best, and the analytic metallic is a candidate too (so a texel on
 * the Eq. 2 manifold keeps it: it renders exactly). About 20 ms per texel for LUMA at the defaults on one core.
 *
 * Threads: a scene is immutable after creation; mr_wf_label_fit may be called from several threads at once and
 * is deterministic. Ownership: one owner, one free (mr_wf_label_scene_free, NULL-safe). Nothing is printed.
 */
#ifndef MR_WF_LABELS_H
#define MR_WF_LABELS_H

#include "../mr_image.h"
#include "../mr_status.h"
#include "workflow.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The objectives run from MR_WF_OBJECTIVE_LINEAR to MR_WF_OBJECTIVE_COUNT - 1; 0 is the default, so that a zeroed
 * mr_wf_label_options is the defaults. */
typedef enum mr_wf_objective {
    MR_WF_OBJECTIVE_DEFAULT = 0, /* MR_WF_OBJECTIVE_LUMA */
    MR_WF_OBJECTIVE_LINEAR,
    MR_WF_OBJECTIVE_DISPLAY,
    MR_WF_OBJECTIVE_LOG,
    MR_WF_OBJECTIVE_EXPOSED,
    MR_WF_OBJECTIVE_LUMA,
    MR_WF_OBJECTIVE_COUNT
} mr_wf_objective;

/* "linear", "display", "log", "exposed", "luma" (DEFAULT: "luma"); NULL outside the enum. */
const char *mr_wf_objective_name(mr_wf_objective objective);
/* Parse one of the names above (never into DEFAULT); MR_ERR_INVALID_ARG listing them otherwise (*out untouched). */
mr_status mr_wf_objective_from_name(const char *name, mr_wf_objective *out);

#define MR_WF_LABEL_MAX_ENVS 8
#define MR_WF_LABEL_MAX_GLOSS 8

/* For reflection_samples, chroma_weight and regularisation, whose 0 means the default: none at all. */
#define MR_WF_LABEL_OFF (-1)

/* Zero-initialised = defaults: every 0 below reads as the default it names. */
typedef struct mr_wf_label_options {
    mr_wf_objective objective;      /* 0 = MR_WF_OBJECTIVE_LUMA (docs/training.md, "Objectives") */
    int size;                       /* sphere image side in pixels, 16 .. 1024; 0 = 32 */
    int glossiness_count;           /* 1 .. MR_WF_LABEL_MAX_GLOSS; 0 = 4, at the default glossinesses */
    double glossiness[MR_WF_LABEL_MAX_GLOSS]; /* default 0.3, 0.6, 0.8, 0.95 (GGX alpha 0.49 .. 0.0025); read
                                                 only when glossiness_count > 0 */
    int env_count;                  /* 0 = the two built-in synthetic environments; else 1 .. MAX_ENVS */
    const mr_image *envs[MR_WF_LABEL_MAX_ENVS]; /* borrowed by mr_wf_label_scene_create only */
    int env_samples;                /* pattern directions per environment; 0 = 256 */
    int reflection_samples;         /* 0 = 40 (as matremap report); MR_WF_LABEL_OFF: none */
    double chroma_weight;           /* LUMA only: weight of the per-channel term, > 0; 0 = 0.1; MR_WF_LABEL_OFF:
                                       none */
    double regularisation;          /* weight of the pull towards the analytic answer, > 0; 0 = 1e-4, MR_WF_LABEL_OFF:
                                       none. 1e-4: a unit change of a parameter must buy a mean squared display
                                       difference of 1e-4 (about 2.5 8-bit codes rms) */
    int threads;                    /* OpenMP threads of the scene's renders (mr_render_plan_create, the scene's
                                       `threads`): 0 (default) = automatic, n = 1 .. 1024: n. Fits are one thread
                                       each (the caller runs them side by side); nothing depends on it */
} mr_wf_label_options;

/* The defaults spelt out (the same scene as a zeroed struct), for callers that change a field or two. */
mr_wf_label_options mr_wf_label_options_default(void);

typedef struct mr_wf_label_scene mr_wf_label_scene;

/* Render the basis of every view. MR_ERR_INVALID_ARG for options outside the ranges above (naming the field),
 * MR_ERR_NOMEM. On success *out is the caller's. */
mr_status mr_wf_label_scene_create(const mr_wf_label_options *opts, mr_wf_label_scene **out);
void mr_wf_label_scene_free(mr_wf_label_scene *scene);

/* Views (environments x glossinesses, environment-major) and their image side. */
int mr_wf_label_view_count(const mr_wf_label_scene *scene);
int mr_wf_label_size(const mr_wf_label_scene *scene);

/* What a fit found. */
typedef struct mr_wf_label_result {
    double loss;          /* the objective at the label (without the regularisation term) */
    double analytic_loss; /* the objective at the analytic answer (A_w, m_w) */
    int kept_analytic;    /* 1: the analytic answer was (within the regularisation) the best candidate */
} mr_wf_label_result;

/* The label of one spec-gloss texel: `in` holds glTF spec-gloss values (diffuse as the extension stores it,
 * specular F0; roughness ignored: the views fix it), clamped to [0, 1] (non-finite -> 0). *out gets albedo and
 * metallic (roughness 0); *result (may be NULL) the losses. MR_ERR_INVALID_ARG for NULL pointers. */
mr_status mr_wf_label_fit(const mr_wf_label_scene *scene, const mr_wf_spec *in, mr_wf_metal *out,
                          mr_wf_label_result *result);

/* The objective's value for any metal-rough answer (without regularisation): how the caller compares methods
 * by the labels' own measure. */
mr_status mr_wf_label_loss(const mr_wf_label_scene *scene, const mr_wf_spec *in, const mr_wf_metal *metal,
                           double *loss);

/* The render of view `view` (size² RGB, background 0) of a spec-gloss material (metal == NULL, spec given) or a
 * metal-rough one (spec == NULL), built from the basis; `image` must be 3-channel and size x size. The coverage
 * of the sphere (size² floats, 1 inside) is mr_wf_label_coverage. */
mr_status mr_wf_label_render(const mr_wf_label_scene *scene, int view, const mr_wf_spec *spec,
                             const mr_wf_metal *metal, mr_image *image);
const float *mr_wf_label_coverage(const mr_wf_label_scene *scene);

/* How close a metal-rough answer looks to the spec-gloss texel where people look: SSIM (metrics.h) over the largest
 * square inside the sphere (object pixels only, no background), each picture exposed so that the source's square
 * has a mean luminance of 0.18 (as the evaluations do), averaged over the scene's views. MR_ERR_INVALID_ARG for
 * NULL arguments or a sphere too small for an 11 x 11 square (size < 24). */
mr_status mr_wf_label_ssim(const mr_wf_label_scene *scene, const mr_wf_spec *spec, const mr_wf_metal *metal,
                           double *ssim);

/* The two built-in synthetic environments (grey, 512 x 256, equirectangular), index 0 (studio) or 1 (sky), in
 * *out (the caller's). */
mr_status mr_wf_label_builtin_env(int index, mr_image **out);

#ifdef __cplusplus
}
#endif

#endif /* MR_WF_LABELS_H */
