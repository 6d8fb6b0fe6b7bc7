/*
 * dataset.h — training pairs for the specular -> metallic regressors (paper section 8) from `matremap sweep`
 * files (src/remap/sweep.h describes the file; scripts/dataset.sh makes the default set).
 *
 * Main calls:
 *   mr_wf_dataset d;
 *   const char *files[] = {"build/dataset/on-manifold.csv", "build/dataset/off-manifold.csv"};
 *   mr_wf_dataset_load(files, 2, NULL, &d);     // d.x: d.n x 6, d.y: d.n x 4
 *   ...
 *   mr_wf_dataset_free(&d);
 *
 * A pair is one sweep row: the input is the source material in the specular workflow, (diffuse RGB, specular F0
 * RGB); the output is the fitted target in the metallic workflow, (albedo RGB, metallic). Which columns say so:
 *   - input: the source columns diffuse_r/g/b and f0_r/g/b (a `ggx` source); or, for a source given in the
 *     metallic workflow (albedo_r/g/b, metallic and dielectric_f0 columns: `ggx-metallic`), the specular
 *     material paper Eq. 2 makes of it (mr_wf_metal_to_spec with that row's dielectric F0), which is the
 *     material the sweep rendered;
 *   - output: the target columns to_albedo_r/g/b and to_metallic.
 * A file with neither input form, or without the output columns, is MR_ERR_FORMAT naming the file. Rows are read
 * in file order, files in the order given. By default rows whose outcome is `local-minimum` (the optimiser may
 * have stopped short of the best fit) are left out and counted in `skipped`; `converged`, `at-bound` (metallic
 * pinned at 0 or 1) and `unreachable` rows are kept: an unreachable specular material (bright diffuse and bright
 * specular at once, which no single metallic reproduces within 25 %) still has a best metallic approximation,
 * which is what the regressor must learn there (paper section 8). A row with a non-finite value, a missing field or an
 * unknown outcome is MR_ERR_FORMAT naming the file and line.
 * Ownership: d owns x and y (one free: mr_wf_dataset_free, which also zeroes d). Nothing is printed.
 */
#ifndef MR_WF_DATASET_H
#define MR_WF_DATASET_H

#include <stddef.h>

#include "../mr_status.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MR_WF_DATASET_INPUTS 6  /* diffuse RGB, specular RGB */
#define MR_WF_DATASET_OUTPUTS 4 /* albedo RGB, metallic */

typedef struct mr_wf_dataset_options {
    int keep_all_outcomes; /* 1: keep local-minimum rows too; default 0 */
} mr_wf_dataset_options;

typedef struct mr_wf_dataset {
    float *x;       /* n x MR_WF_DATASET_INPUTS, row-major */
    float *y;       /* n x MR_WF_DATASET_OUTPUTS */
    size_t n;       /* pairs kept */
    size_t skipped; /* rows left out for their outcome */
} mr_wf_dataset;

/* Load `count` sweep files into *out (zeroed first; left empty on failure). opts may be NULL (defaults). */
mr_status mr_wf_dataset_load(const char *const *paths, int count, const mr_wf_dataset_options *opts,
                             mr_wf_dataset *out);

/* Release d's arrays and zero it; NULL-safe. */
void mr_wf_dataset_free(mr_wf_dataset *d);

#ifdef __cplusplus
}
#endif

#endif /* MR_WF_DATASET_H */
