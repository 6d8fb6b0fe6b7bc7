/*
 * direct.h — the direct remap of a spatially varying material: every texel's source parameters remapped into the
 * target model by the image-based optimiser itself (mr_remap, remap.h), with no regression in between. It is the
 * reference that learned transforms are judged against (`matremap convert --direct`).
 *
 * Main calls:
 *   mr_direct_options o = {0};                       // zero = defaults
 *   o.cache_path = "ggx_to_ward.cache";              // optional: answers kept across runs
 *   mr_direct_summary s;
 *   mr_direct_remap(mr_brdf_find("ggx"), mr_brdf_find("ward-balanced"), in, n, &o, out, outcomes, &s);
 * `in` holds n texels, each a packed source value vector (mr_brdf_value_count(source) doubles, brdf.h); `out`
 * receives n packed target vectors (mr_brdf_value_count(target) doubles, fixed parameters and switches included).
 *
 * What a texel gets:
 *   1. Its values are clamped into each parameter's [min, max] (counted in summary->clamped; the renderer clamps
 *      them the same way, so this is the material it shows). A value that is NaN or infinite is refused.
 *   2. They are quantised (mr_direct_quantise) with step t = opts->tolerance (default MR_DIRECT_DEFAULT_TOLERANCE):
 *        - a colour (an RGB parameter: diffuse, specular, F0, base colour), channel by channel in sRGB-encoded
 *          units (IEC 61966-2-1, its curve continued above 1 for reflectances allowed beyond it):
 *          q = decode(t * round(encode(v) / t)). So t = 1/255 keeps an 8-bit sRGB texture's texels exactly, and a
 *          coarser step errs alike to the eye in dark and bright texels (in linear units a step of 6/255 would
 *          be more than a dark reflectance of 0.02 and 3 % of 0.8);
 *        - a scalar flagged MR_PARAM_LOG_SCALE with min > 0 (roughness, Phong's exponent): in log space with
 *          its own step t_r = opts->roughness_tolerance (0: t_r = t), q = exp(t_r * round(ln v / t_r)), a
 *          relative step of e^t_r - 1 (~ t_r), at t_r = t as fine as the colours' at mid grey. A step per kind
 *          buys accuracy where it shows: on FloppyDisk (docs/performance.md) colours at 1/255 (an 8-bit map's
 *          texels exactly) and roughness at 4/255 keep every sampled texel's quantisation error under 1 % image
 *          RMSE (median 0.17 %) with 84,000 distinct values, where t = 1/255 for both needs 105,000 and
 *          t = 2/255 errs by 1.8 % (median, 7 % at the 90th percentile) with 64,000;
 *        - a switch (Ward's trim): kept exactly;
 *        - any other scalar (metallic, glossiness, IOR, a scalar specular): q = t * round(v / t), an absolute
 *          step of t in the parameter's own units;
 *      and then clamped into [min, max] again. The quantised vector is a fixed point: quantising it gives it back.
 *   3. Texels whose quantised vectors are equal (bit for bit) share one answer: the remap of that quantised vector,
 *      the "unique value". So a texel's answer depends on its own value and the tolerance only, never on the
 *      other texels it was remapped with, except through the warm start (below).
 * The answer of a unique value is mr_remap(plan, source, q, target, &remap) in the fit scene of opts->scene, with
 * opts->remap as options (target_values and held there say which target values are fixed), run one of two ways:
 *   - full: exactly that call (bit-identical to calling it yourself with the same plan size, light and options);
 *   - warm-started: the same call with remap.initial_values set to an already solved, nearby unique value's
 *     answer (remap.h: for AUTO and JOINT one local refinement from there instead of the global grid search)
 *     and remap.xtol raised to MR_DIRECT_WARM_XTOL.
 *     The unique values are sorted along a Morton (Z-order) curve through their quantised coordinates (with
 *     shared shapes, below: through the shape slots first, then through the others among values equal in
 *     those, so that a shape's siblings lie side by side) and cut into chains of opts->chain_length (default
 *     MR_DIRECT_DEFAULT_CHAIN); in each chain, in order, a value starts from the answer of its shape sibling
 *     (below) if it has one, else of the nearest value of its chain already answered with a seedable outcome,
 *     CONVERGED or UNDER_RESOLVED (Euclidean distance in quantisation steps; the earliest in the chain on a tie;
 *     a cache hit counts as answered); a value with no such neighbour (the first of a chain) gets a full remap.
 *     The guard: a warm-started answer is kept only if its outcome is CONVERGED, or UNDER_RESOLVED with an
 *     under-resolved seed, and its relative RMSE is at most MR_DIRECT_GUARD_GAIN times its seed's plus
 *     MR_DIRECT_GUARD_FLOOR (neighbours fit about equally well; a warm start that fell into another basin does
 *     not). Otherwise the value gets a full remap, whose outcome
 *     stands (a fallback). A warm-started answer is the full remap's minimum when both find the same basin, up
 *     to the local fit's tolerance: on the shared texture sets within 1e-4 (largest parameter difference, alpha
 *     relative, reflectances absolute; tests/bench_direct.c), checked within 2e-3 by tests/test_direct.c.
 *     UNDER_RESOLVED answers seed and are kept too: the lobe is narrower than the pixels, but the image error
 *     still has a minimum in the roughness, which the warm refinement finds as the full remap's grid does (on
 *     the FloppyDisk set at 6/255 within 1e-2 of the earlier answers, alpha relative, median 1e-5, their renders
 *     within 3e-5 relative RMSE, no outcome changed; tests/test_direct.c); refusing them cost a full remap for
 *     every glossy texel of a chain before its first converged one (1,400 of the set's 1,900 full remaps). A warm
 *     answer that turns under-resolved from a converged seed still falls back: at the edge of a glossy region
 *     the verdict sits on its threshold (one value of the set flipped to under-resolved, which its full remap
 *     calls converged, when those were kept).
 *   - Shared shapes (opts->fit_every_shape = 0, the default): AUTO fits the shape (the nonlinear parameters) of
 *     a lobe against the source's render of that lobe alone and only then solves the linear parameters against
 *     the full render (remap.h). So when every fitted nonlinear target parameter shapes the specular lobe
 *     (GGX's, Ward's, Phong's roughness; the strategy AUTO, built-in renderers, warm starts on), two texels
 *     whose sources render the same specular lobe, bit for bit, get the same shape from the same start: a
 *     Ward texel's shape depends on its specular colour and alpha, not on its diffuse colour. Not on the colour
 *     alone would be wrong: GGX's Schlick term makes its lobe affine, not linear, in F0, so the best alpha for
 *     s * L(alpha) depends on s. A value's shape sibling is the earliest value of its chain already answered
 *     with a seedable outcome whose quantised source values are equal in every slot not confined to the
 *     diffuse lobe (the shape slots) and whose source specular render (the fit scene's, one component render
 *     per value that has a candidate, hashed: FNV-1a 64 of its bits) is identical; the value then starts from
 *     the sibling's answer with its shape kept: remap.max_evaluations = 1 for it, so the local refinement
 *     evaluates the start only, and the linear parameters and every verdict (outcome, resolution, the closer
 *     look) are the value's own, as in any remap. Under the guard as any warm start (counted in `warm`, and in
 *     `shared_shapes`). Its answer is what the warm refinement from the sibling's answer converges to, up to the
 *     refinement's own tolerance (xtol MR_DIRECT_WARM_XTOL). On FloppyDisk at 6/255, 14,000 of 19,400 values
 *     share a shape, and a remap takes 13 counted renders instead of 24.
 *     What a warm start cannot report: an AUTO fit's ambiguity (two minima within 1 %: LOCAL_MINIMUM) needs the
 *     global grid, so a kept warm answer is CONVERGED where a full remap might have said LOCAL_MINIMUM.
 *     opts->cold = 1 gives every unique value a full remap (slower; no warm start at all).
 *
 * Cache (opts->cache_path, optional): a text file of answers that later runs reuse. Its header says everything an
 * answer depends on; a file whose header differs is refused, untouched (MR_ERR_INVALID_ARG naming the first
 * differing line: use another cache file per configuration):
 *   # matremap VERSION direct-cache
 *   # from: SOURCE_MODEL
 *   # to: TARGET_MODEL name=v ...                 (the target values: fixed values, switches, starts)
 *   # remap: strategy=auto max_evaluations=400 ... [held=...]   (defaults written out: {0} = the defaults)
 *   # scene: fit size=64 light=45 intensity=10 edge_samples=4 highlight_samples=integrated
 *   # direct: tolerance=0.023529411764705882 [roughness_tolerance=T_R] start=warm|cold   (T_R if it is not t)
 *   <source columns>,<to_ target columns>,relative_rmse,outcome,how
 * then one line per unique value: its quantised source vector, its target vector, the relative RMSE and outcome
 * of its remap, and how it was found ("full" or "warm"), numbers with %.17g in the C numeric locale (they read
 * back bit for bit). A value found in the cache is not remapped: its answer is the cached one, bit for bit (the
 * first line for it, should a file hold two). New answers are appended as they are found, each line in one
 * write() of O_APPEND (remap_file.h): a run killed at any moment keeps every answer written; the next run cuts
 * a torn last line off and goes on from them. An advisory lock refuses a second process using the same file at
 * once (MR_ERR_IO). A line that does not parse, or whose source vector is not a quantised value of this
 * tolerance, is MR_ERR_FORMAT naming the line (the file is not touched). A missing file is created; an empty
 * one (killed before its header) is started afresh.
 * With a cache, a value's answer is the one of the run that first computed it: a warm start from another chain
 * can differ from this run's own at the level of the fit's tolerance, so output can differ in the last digits
 * between a run that found some values cached and one that did not.
 *
 * Determinism: without cache hits, out, outcomes and every count of the summary (but seconds) are the same, bit
 * for bit, for any opts->threads: the chains are fixed by the input alone, each chain runs on one thread, and
 * mr_remap is deterministic. A run whose values are all in the cache reproduces the run that wrote it exactly.
 * Threads: chains are spread over opts->threads threads (OpenMP, dynamic); every remap runs single-threaded
 * inside (as sweeps do, sweep.h), and no more threads are opened than there are chains with work. The progress
 * callback is called serialised, after each unique value is answered (cache hits are reported once, at the
 * start).
 * Errors (nothing is printed; mr_last_error() has the message): MR_ERR_INVALID_ARG for a NULL model, a NULL
 * in/out with n > 0, a non-finite value (naming the texel and the parameter), bad options (naming them), a
 * foreign cache; MR_ERR_FORMAT for a corrupt cache; MR_ERR_IO for a cache that cannot be read, locked or
 * appended to; a remap's own failure (MR_ERR_EXTERNAL, MR_ERR_NOMEM) stops the run. On any failure out and
 * outcomes are not written (the cache keeps the answers already appended). n = 0 is MR_OK and does nothing (no
 * cache is opened).
 * Ownership: the caller owns every array; nothing returned needs freeing.
 */
#ifndef MR_DIRECT_H
#define MR_DIRECT_H

#include <stddef.h>

#include "../brdf/brdf.h"
#include "../mr_status.h"
#include "../render/render.h"
#include "../transform/transform.h"
#include "remap.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The default quantisation step t (see the header comment for what it means per parameter), chosen from the
 * figures of tests/bench_direct.c (docs/performance.md, "Direct remaps"): the finest step with which both 1024^2
 * texture sets of the shared assets (Avocado, FloppyDisk, read as Ward and remapped into GGX) remapped in at most
 * 60 s on 2 cores when it was chosen: FloppyDisk has 19,000-21,000 distinct values at 6/255 (33,000 at 4/255,
 * 56,000-64,000 at 2/255), and with shared shapes a value costs about 2 ms of CPU (38 s of CPU for the set, 19 s on
 * 2 idle cores). What the step costs in accuracy: the answers' renders differ from those of the exact texels'
 * remaps by 3-4 % relative RMSE (median; up to 20 % on a dark texel), a third of what a Ward -> GGX fit leaves
 * itself (~9 %); under 1 % needs colours at 1/255 (roughness_tolerance: roughness may stay at 4/255). */
#define MR_DIRECT_DEFAULT_TOLERANCE (6.0 / 255.0)
#define MR_DIRECT_MIN_TOLERANCE 1e-9 /* the smallest quantisation step: exact values for any input */
/* Unique values per chain (the header comment): the first of each gets a full remap, the others warm starts. */
#define MR_DIRECT_DEFAULT_CHAIN 64
/* A warm start's local refinement stops at steps of max(remap.xtol, MR_DIRECT_WARM_XTOL) in normalised
 * coordinates (remap.h): a factor 1.001 in a GGX alpha, a quarter of a step of 1/255 in ln alpha; it takes a fifth
 * fewer renders than the default 1e-6, and its answers stay as close to full remaps (tests/bench_direct.c). */
#define MR_DIRECT_WARM_XTOL 1e-4
/* The warm start's guard: kept while relative RMSE <= GAIN x the seed's + FLOOR. */
#define MR_DIRECT_GUARD_GAIN 1.25
#define MR_DIRECT_GUARD_FLOOR 0.005

/* What the progress callback sees. */
typedef struct mr_direct_progress {
    size_t done;       /* unique values answered so far, cache hits included */
    size_t total;      /* unique values */
    size_t cache_hits; /* of them, found in the cache */
} mr_direct_progress;

/* Called serialised (never twice at once), on the thread that answered the value; keep it short. */
typedef void (*mr_direct_progress_fn)(const mr_direct_progress *progress, void *user);

/* Zero-initialised = defaults. */
typedef struct mr_direct_options {
    double tolerance;            /* quantisation step t in [MR_DIRECT_MIN_TOLERANCE, 1]; 0 = the default */
    double roughness_tolerance;  /* the step t_r of log-scale parameters (roughness), in ln units, in the same
                                    range; 0 = t */
    mr_remap_options remap;      /* every remap's options ({0} = mr_remap_options_default()): strategy, tolerances,
                                    target_values (fixed target values; NULL = the target's defaults) and held.
                                    Its initial_values and threads are the direct remap's to set: must be NULL / 0 */
    mr_fit_scene_options scene;  /* the fit scene: size 0 = MR_REMAP_DEFAULT_SIZE, light, intensity 0 = 10 */
    int threads;                 /* threads at most; 0 = automatic (mr_auto_threads: a team of
                                    omp_get_max_threads() for two chains with work or more, never more threads
                                    than such chains) */
    int chain_length;            /* unique values per chain, >= 1; 0 = MR_DIRECT_DEFAULT_CHAIN */
    int cold;                    /* 1: no warm starts, a full remap for every unique value */
    int fit_every_shape;         /* 1: no shared shapes (header comment): every warm start refines its shape */
    const char *cache_path;      /* optional cache file (header comment); NULL = none */
    mr_direct_progress_fn progress; /* optional */
    void *progress_user;
} mr_direct_options;

typedef struct mr_direct_summary {
    size_t texels;                           /* n */
    size_t clamped;                          /* texels with a value outside its parameter's range */
    size_t unique;                           /* distinct quantised values */
    size_t cache_hits;                       /* unique values answered by the cache */
    size_t full;                             /* unique values answered by a full remap (chain starts, fallbacks,
                                                every one with cold) */
    size_t warm;                             /* unique values answered by a warm start the guard kept */
    size_t fallbacks;                        /* warm starts the guard refused (their value then had a full
                                                remap: counted in `full` too) */
    size_t remaps;                           /* remaps run: full + warm + fallbacks */
    size_t shared_shapes;                    /* of the warm ones, started from a shape sibling's answer with its
                                                shape kept (header comment, "Shared shapes") */
    size_t outcomes[MR_FIT_OUTCOME_COUNT];   /* unique values by the outcome of their answer (hits included) */
    long renders;                            /* target renders of the remaps run (mr_remap_result.renders) */
    int threads;                             /* threads used (0: nothing was remapped) */
    double seconds;                          /* wall time of the call */
} mr_direct_summary;

/* Quantise one packed source vector (mr_brdf_value_count(source) doubles) with step `tolerance` (0 = default)
 * into q[] as the header comment says (clamped into range, then quantised): the value whose remap a texel of
 * these values gets. in and q may be the same array. MR_ERR_INVALID_ARG for a NULL argument, a tolerance outside
 * [1e-9, 1], or a value that is NaN or infinite (naming the parameter). */
mr_status mr_direct_quantise(const mr_brdf_model *source, double tolerance, const double *in, double *q);

/* The same with the step t_r of log-scale parameters (mr_direct_options.roughness_tolerance; 0 = tolerance). */
mr_status mr_direct_quantise_steps(const mr_brdf_model *source, double tolerance, double roughness_tolerance,
                                   const double *in, double *q);

/* Remap n texels from `source` to `target` as the header comment says. in: n * mr_brdf_value_count(source)
 * doubles; out: n * mr_brdf_value_count(target) doubles; outcomes (optional): n outcomes, each texel's answer's;
 * summary (optional). opts may be NULL (defaults). */
mr_status mr_direct_remap(const mr_brdf_model *source, const mr_brdf_model *target, const double *in, size_t n,
                          const mr_direct_options *opts, double *out, mr_fit_outcome *outcomes,
                          mr_direct_summary *summary);

/* Flag of a texel whose direct answer is not a converged fit (under-resolved, at-bound, unreachable or a local
 * minimum), beside workflow.h's mr_wf_flag bits and learned.h's. */
enum { MR_WF_UNCONVERGED = 1u << 6 };

/* A transform kind (transform.h) that converts texture sets by mr_direct_remap with `opts` (copied; its cache path
 * and progress callback are borrowed and must outlive the kind): inputs every parameter of `source` (optional: a
 * missing map is the default), outputs every parameter of `target`. Not PER_TEXEL: the direct remap deduplicates
 * (quantised) values itself, over the whole set. A non-finite input texel is read as its parameter's minimum and
 * flagged MR_WF_NONFINITE_INPUT (mr_direct_remap itself refuses them), one outside its range MR_WF_CLAMPED_INPUT, a
 * texel whose answer did not converge MR_WF_UNCONVERGED. One conversion at a time per kind (it keeps the last
 * summary: mr_direct_kind_summary). Freed by mr_direct_kind_free. */
mr_status mr_direct_kind_create(const mr_brdf_model *source, const mr_brdf_model *target, const mr_direct_options *opts,
                                mr_transform_kind **out);
/* The summary of the kind's last conversion (zeroed before the first). */
const mr_direct_summary *mr_direct_kind_summary(const mr_transform_kind *kind);
void mr_direct_kind_free(mr_transform_kind *kind);

#ifdef __cplusplus
}
#endif

#endif /* MR_DIRECT_H */
