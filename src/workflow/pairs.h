/*
 * pairs.h — the training pairs of the learned specular -> metallic converter (`matremap dataset`,
 * docs/training.md): spec-gloss texels drawn as 8-bit textures store them, each labelled by the image objective
 * of labels.h, written as a pairs file; and the comparison of every objective's labels, the analytic inverses
 * and networks by how alike they render under other lights (`matremap dataset --compare`).
 *
 * Main calls:
 *   mr_wf_pairs_options o = {0};                      // 16000 texels, seed 0, luma labels, automatic threads
 *   mr_wf_pairs_summary s;
 *   mr_wf_pairs_make(&o, "pairs.csv", &s);            // draw, label, write (atomically)
 *   mr_wf_dataset_load(&path, 1, NULL, &d);           // the file's reader (dataset.h), as `matremap train` loads it
 *
 *   mr_wf_compare_options c = {0};  c.envs = envs;  c.env_count = 2;
 *   mr_wf_compare_table *t;
 *   mr_wf_pairs_compare(&c, &t);  ...  mr_wf_compare_table_free(t);
 *
 *   mr_wf_method_error e[MR_WF_EVALUATED_METHODS];
 *   mr_wf_pairs_evaluate(net, &held_out, 0, e);       // each converter's error against held-out labels
 *
 * Texels. Sample i is a pure function of (seed, i), so files do not depend on the thread count. Its category comes
 * from a fixed mixture (30 % asset texels when the pool holds any, the rest shared as listed below); its values are
 * 8-bit sRGB codes decoded to linear (mr_wf_pair_category says which codes). A pool holds texels of textured
 * materials (mr_wf_texel_pool_add_maps; gltf/mr_gltf.h's mr_gltf_add_specgloss_texels fills it from an asset).
 *
 * The pairs file: a comment line "# matremap dataset: objective O, seed S, N pairs (docs/training.md)", a header,
 * then one row per pair: index, category, sg_diffuse_r/g/b (the texel's spec-gloss diffuse), diffuse_r/g/b (the
 * diffuse lobe d (1 - max s), what the network reads), f0_r/g/b, to_albedo_r/g/b, to_metallic (the label), loss,
 * analytic_loss, kept_analytic (mr_wf_label_result) and outcome: converged when the label renders like the texel
 * within one 8-bit code rms (loss <= MR_WF_PAIRS_CONVERGED_LOSS), else unreachable (the closest metal-rough
 * answer). Numbers in the C locale (%.9g, losses %.6g). mr_wf_dataset_load reads it.
 *
 * Threads: the labels are fitted (and --compare's answers judged) by an OpenMP team of `threads` (0: the automatic
 * rule, every core for two pairs or more) with a dynamic schedule (texels differ in cost), and the label scenes
 * render with it; no process-wide setting is changed. Results do not depend on it.
 * Progress: opts->progress (NULL: none) is called from the team, one call at a time, after every 256th pair of a
 * stage (a stage: the labels of one objective), and once when the stage is done (done == total) from the calling
 * thread; it must not call back into this module.
 * Ownership: a table has one owner and one free (mr_wf_compare_table_free, NULL-safe); a pool likewise
 * (mr_wf_texel_pool_free). Nothing is printed.
 */
#ifndef MR_WF_PAIRS_H
#define MR_WF_PAIRS_H

#include <stddef.h>
#include <stdint.h>

#include "../mr_image.h"
#include "../mr_status.h"
#include "dataset.h"
#include "labels.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Where a drawn texel comes from. */
typedef enum mr_wf_pair_category {
    MR_WF_PAIR_UNIFORM = 0, /* every code equally likely, channels independent (coloured specular too) */
    MR_WF_PAIR_DIELECTRIC,  /* specular in the 8-bit dielectric band 40-70 (grey, sometimes a code or two apart),
                               dark, saturated or uniform diffuse */
    MR_WF_PAIR_GREY,        /* grey diffuse and grey specular */
    MR_WF_PAIR_METAL,       /* dark diffuse, bright (tinted) specular */
    MR_WF_PAIR_MIXED,       /* Eq. 2 of a partly metallic texel, stored in 8 bits */
    MR_WF_PAIR_ASSET,       /* a texel of the pool */
    MR_WF_PAIR_CATEGORY_COUNT
} mr_wf_pair_category;

/* "uniform", "dielectric", "grey", "metal", "mixed", "asset"; NULL outside the enum. */
const char *mr_wf_pair_category_name(mr_wf_pair_category category);

/* A label "converged" when its render matches the texel's within one 8-bit code (root mean square, in the
 * objective's display units); else "unreachable": the best metal-rough answer, which no metal-rough material
 * matches (e.g. a specular below the 0.04 every glTF dielectric reflects). `matremap train` keeps both. */
#define MR_WF_PAIRS_CONVERGED_LOSS (1.0 / (255.0 * 255.0))

/* Texels sampled from each textured source (an asset's spec-gloss materials share them equally). */
#define MR_WF_POOL_SOURCE_TEXELS 4096

/* Texels of textured materials, the ASSET category's draws. Zero-initialise; free with mr_wf_texel_pool_free. */
typedef struct mr_wf_texel_pool {
    float *texels;       /* count x 6: diffuse RGB, specular RGB (linear spec-gloss values in [0, 1]) */
    size_t count;
    size_t capacity;     /* texels allocated */
    int sources;         /* sources ended (mr_wf_texel_pool_end_source): each draws from its own stream */
    uint64_t draw_state; /* the current source's stream of positions */
} mr_wf_texel_pool;

/* Start a source (an asset): its positions are a stream of (seed, pool->sources). */
void mr_wf_texel_pool_begin_source(mr_wf_texel_pool *pool, uint64_t seed);
/* Add `count` texels of one material: at positions (u, v) drawn uniformly from the source's stream (the same
 * position in both maps, nearest texel), diffuse = diffuse map x diffuse_factor and specular = the first three
 * channels of specgloss x specular_factor, clamped to [0, 1]. A NULL map reads as 1 (only its factor counts); a
 * one-channel map is read grey. Maps hold linear values (sRGB-decoded as colour textures are). MR_ERR_NOMEM. */
mr_status mr_wf_texel_pool_add_maps(mr_wf_texel_pool *pool, const mr_image *diffuse, const mr_image *specgloss,
                                    const double diffuse_factor[3], const double specular_factor[3], size_t count);
/* End the current source (the next one gets the next stream). */
void mr_wf_texel_pool_end_source(mr_wf_texel_pool *pool);
/* Release the texels and zero the pool; NULL-safe. */
void mr_wf_texel_pool_free(mr_wf_texel_pool *pool);

/* Progress of a stage (its name, e.g. "labels" or "labels: luma"): `done` of `total` pairs. */
typedef void (*mr_wf_pairs_progress_fn)(const char *stage, size_t done, size_t total, void *user);

typedef struct mr_wf_pairs_options {
    int samples;                        /* drawn texels, >= 0; 0 = the default: 16000 (make), 400 (compare) */
    uint64_t seed;                      /* the draws' seed; 0 is a seed like any other (`matremap dataset`'s
                                           default is 1) */
    const mr_wf_label_options *labels;  /* how labels are made; NULL = mr_wf_label_options_default() */
    const mr_wf_texel_pool *pool;       /* asset texels (borrowed); NULL or empty: none, no ASSET category */
    int threads;                        /* 0 = automatic (mr_auto_threads); n >= 1: n OpenMP threads, for the fits
                                           and for the label scenes' renders (unless labels->threads names
                                           theirs) */
    mr_wf_pairs_progress_fn progress;   /* NULL: none */
    void *progress_user;
} mr_wf_pairs_options;

typedef struct mr_wf_pairs_summary {
    size_t pairs;                                     /* rows written */
    size_t converged, unreachable;                    /* their outcomes */
    size_t categories[MR_WF_PAIR_CATEGORY_COUNT];     /* rows per category */
} mr_wf_pairs_summary;

/* Draw opts->samples texels, label each under opts->labels, and write the pairs file at `path` (atomically: a
 * temporary file beside it, renamed when complete; nothing is left on failure). *summary (may be NULL) gets the
 * counts. MR_ERR_INVALID_ARG for NULL opts or path or options out of range (naming them), the label scene's
 * failures (labels.h), MR_ERR_IO naming a file that cannot be written, MR_ERR_NOMEM. */
mr_status mr_wf_pairs_make(const mr_wf_pairs_options *opts, const char *path, mr_wf_pairs_summary *summary);

/* The named hard cases of --compare: spec-gloss texels as 8-bit sRGB codes. */
typedef struct mr_wf_named_texel {
    const char *name;
    int diffuse[3], specular[3];
} mr_wf_named_texel;

#define MR_WF_COMPARE_MAX_WEIGHTS 4
/* The objectives compared: every one from MR_WF_OBJECTIVE_LINEAR on (labels.h), in the enum's order. */
#define MR_WF_COMPARE_OBJECTIVES ((int)MR_WF_OBJECTIVE_COUNT - (int)MR_WF_OBJECTIVE_LINEAR)
#define MR_WF_COMPARE_MAX_COLUMNS (MR_WF_COMPARE_OBJECTIVES + 3 + MR_WF_COMPARE_MAX_WEIGHTS)

typedef struct mr_wf_compare_options {
    mr_wf_pairs_options pairs;  /* the drawn texels (samples 0 = 400) and how the objectives' labels are made
                                   (pairs.labels' objective is replaced by each objective in turn) */
    const mr_image *const *envs; /* the environments the answers are judged under (equirectangular radiance,
                                    borrowed), 1 .. MR_WF_LABEL_MAX_ENVS of them */
    int env_count;
    const char *const *weights; /* networks (.mlp files) compared too, 0 .. MR_WF_COMPARE_MAX_WEIGHTS */
    int weight_count;
} mr_wf_compare_options;

/* One converter's SSIM for every texel. */
typedef struct mr_wf_compare_column {
    char name[96];  /* "labels: luma", "weighted", "mean", "khronos", "mlp FILE" (the weights' base name) */
    double *ssim;   /* texel_count values */
} mr_wf_compare_column;

typedef struct mr_wf_compare_table {
    size_t texel_count;                   /* hard cases first, then the drawn texels */
    int hard_case_count;                  /* texels 0 .. hard_case_count - 1 are hard_cases[] */
    const mr_wf_named_texel *hard_cases;  /* a static table (not freed) */
    mr_wf_pair_category *categories;      /* per texel (hard cases: MR_WF_PAIR_UNIFORM) */
    int column_count;                     /* MR_WF_COMPARE_OBJECTIVES objectives' labels, then weighted, mean,
                                             khronos, then the networks */
    mr_wf_compare_column columns[MR_WF_COMPARE_MAX_COLUMNS];
} mr_wf_compare_table;

/* Fit every objective's labels for the hard cases and opts->pairs.samples drawn texels under opts->pairs.labels
 * (each objective in turn), convert the same texels with the analytic inverses (spec-gloss reading of the diffuse)
 * and each network, and measure how close each answer renders to its texel under opts->envs (mr_wf_label_ssim on a
 * 96-pixel sphere at glossinesses 0.3, 0.6 and 0.9). On success *out is the caller's. MR_ERR_INVALID_ARG for NULL
 * arguments or counts out of range, the networks' read failures (nn/mlp.h), the scenes' (labels.h), MR_ERR_NOMEM. */
mr_status mr_wf_pairs_compare(const mr_wf_compare_options *opts, mr_wf_compare_table **out);
void mr_wf_compare_table_free(mr_wf_compare_table *table);

/* ---- converters against labels (`matremap train --test`) ---- */

/* The converters evaluated, in this order: the network, then the analytic WEIGHTED, MEAN and KHRONOS. */
#define MR_WF_EVALUATED_METHODS 4

typedef struct mr_wf_method_error {
    const char *name;     /* "mlp", "weighted", "mean", "khronos" (static) */
    double albedo_rmse;   /* over every pair and channel */
    double metallic_rmse;
    double metallic_max;  /* the largest |metallic - label| */
} mr_wf_method_error;

struct mr_mlp;
/* Each converter's error on labelled pairs (a dataset of mr_wf_dataset_load: x the spec-gloss inputs as the file
 * stores them, y the labels): `net` (a spec -> metal network, nn/mlp.h, applied by mr_wf_spec_to_metal_mlp_batch),
 * then the analytic inverses with the default options (plain reading of the diffuse, F0d 0.04), into
 * errors[MR_WF_EVALUATED_METHODS]. No pairs: every error 0. `threads` is the batches' (workflow.h; 0 = automatic);
 * the errors do not depend on it. MR_ERR_INVALID_ARG for NULL arguments or a network of another shape,
 * MR_ERR_NOMEM. */
mr_status mr_wf_pairs_evaluate(const struct mr_mlp *net, const mr_wf_dataset *pairs, int threads,
                               mr_wf_method_error errors[MR_WF_EVALUATED_METHODS]);

#ifdef __cplusplus
}
#endif

#endif /* MR_WF_PAIRS_H */
