/*
 * sweep_table.h — the rows of `matremap sweep` files (src/remap/sweep.h describes the file) as packed parameter
 * vectors of any source and target model: what a learned transform (learned.h) is trained on.
 *
 * Main calls:
 *   const char *files[] = {"ward_ggx.csv", "ward_ggx_more.csv"};
 *   mr_sweep_table t;
 *   mr_sweep_table_load(files, 2, NULL, &t);   // t.source_values: t.n rows of mr_brdf_value_count(t.source)
 *   ...
 *   mr_sweep_table_free(&t);
 *
 * What is read. The header's "# from: MODEL name=v ..." and "# to: MODEL name=v ..." lines name the models (and the
 * fixed values every sample started from), "# scene:" the fit scene; the column line must hold "index", every packed
 * slot of both models (a scalar parameter's name, an RGB parameter's name_r/_g/_b; target slots prefixed "to_"),
 * "ssim" and "outcome", in any order. Several files are one table only if they agree on both models, on the target's
 * fixed values ("# to:") and on the scene ("# scene:": a fit made with another light or size is another mapping);
 * otherwise MR_ERR_FORMAT names both files and the line that differs. Rows are kept in file order, files in the order
 * given. By default rows whose outcome is local-minimum are left out (the optimiser stopped short of the best fit,
 * so the row is not the mapping) and counted in `skipped`; every other outcome is kept (under-resolved and at-bound
 * rows are still the best fit the scene resolves). A row with a missing or non-finite field, an unknown outcome or
 * a value outside its parameter's [min, max] is MR_ERR_FORMAT naming file, line and column.
 * By default rows whose source the model rescales (mr_brdf_model.rescales: Ward's energy trimming with diffuse +
 * specular > 1) are left out too and counted in `rescaled`: there the source is not linear in its reflectances, no
 * texel of a texture map lies there, and a transform fitted over them (a random sweep over Ward's whole specular
 * range [0, 10] is 95 % trimmed) is wrong for every texel that does.
 * Provenance: `provenance` holds, for each file, a line "sweep FILE rows N kept K" followed by its header lines
 * (without "# command:"), each '\n'-terminated: what a transform file records of its data.
 * Ownership: the table owns its arrays (one free: mr_sweep_table_free, which zeroes it). Nothing is printed.
 */
#ifndef MR_LEARN_SWEEP_TABLE_H
#define MR_LEARN_SWEEP_TABLE_H

#include <stddef.h>

#include "../brdf/brdf.h"
#include "../mr_status.h"
#include "../remap/remap.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct mr_sweep_table_options {
    int keep_all_outcomes; /* 1: keep local-minimum rows too; default 0 */
    int keep_rescaled;     /* 1: keep the rows whose source the model rescales too; default 0 */
} mr_sweep_table_options;

typedef struct mr_sweep_table {
    const mr_brdf_model *source, *target;
    int source_count, target_count;           /* packed value counts of the two models */
    double target_fixed[MR_BRDF_MAX_VALUES];  /* the "# to:" values (fixed parameters and switches) */
    unsigned target_held;                     /* bit p: every file's sweep held target parameter p (its "# remap:"
                                                 line's held=, the sweep's --hold) at its "# to:" value; the
                                                 model's default holds (MR_PARAM_FIT_FIXED) are not in it */
    mr_brdf_ties target_ties;                 /* target parameters every file's sweep tied to a source parameter (its
                                                 "# remap:" line's tied=; brdf.h): learn carries them (factor 1) */
    char scene[256];                          /* the "# scene:" line's text after "# scene: " */
    size_t n;                                 /* rows kept */
    size_t skipped;                           /* rows left out for their outcome */
    size_t rescaled;                          /* rows left out because the source model rescales their values */
    double *source_values;                    /* n x source_count */
    double *target_values;                    /* n x target_count */
    double *ssim;                             /* n: the fit's SSIM */
    mr_fit_outcome *outcome;                  /* n */
    char *provenance;                         /* see the header comment */
} mr_sweep_table;

/* Load `count` (>= 1) sweep files into *out (zeroed first; left empty on failure). opts may be NULL (defaults). */
mr_status mr_sweep_table_load(const char *const *paths, int count, const mr_sweep_table_options *opts,
                              mr_sweep_table *out);

/* Release t's arrays and zero it; NULL-safe. */
void mr_sweep_table_free(mr_sweep_table *t);

#ifdef __cplusplus
}
#endif

#endif /* MR_LEARN_SWEEP_TABLE_H */
