/*
 * learned_plots.h — the paper's cross sections of a learned transform (`matremap learn --plots DIR`), written with
 * the transform as one set of files.
 *
 * Main call:
 *   mr_learned_plots_result r;
 *   mr_learned_write_with_plots(t, &rows, "ward-ggx.mrt", "plots", NULL, &r);   // the .mrt and DIR's files
 *
 * The cross sections cut through the transform's source roughness (a one-channel nonlinear parameter) and source
 * specular (a linear specular parameter, scalar or grey), and show the target's roughness and specular there:
 *   DIR/rows.csv       source_roughness,source_specular,target_roughness,target_specular: every row of the sweeps
 *   DIR/curves.csv     the learned curves (gnuplot data sets separated by two blank lines): the target roughness
 *                      over the roughness domain (specular at the domain's middle, 201 points), then the target
 *                      specular along 6 roughnesses spaced logarithmically across the domain, from 0 to 1.5 x the
 *                      rows' largest specular (51 points each; beyond the rows is extrapolation); every other
 *                      source value from the first row
 *   DIR/roughness.svg  target roughness against source roughness: rows and curve       (gnuplot, when it runs)
 *   DIR/specular.svg   target specular against source specular, coloured by roughness  (gnuplot, when it runs)
 * Numbers %.9g in the C locale. A transform without such a pair writes no plots (result->cut = 0) and DIR is not
 * made. gnuplot is run through popen ("gnuplot", its stderr discarded) on the temporary files; when it is missing or
 * fails, the SVGs are left out (result->drawn = 0) and the data files are still written.
 *
 * All or none: the plots are prepared as temporary files beside their targets, then the transform is written
 * (mr_learned_write), then the plots are renamed over their targets; a failure at any step leaves none of this
 * call's files (a transform already renamed is removed again) and removes DIR if this call made it (and it is
 * empty). DIR is made with mode 0777 (less the umask) when missing; its parent must exist.
 * Nothing is printed. Threads: one thread.
 */
#ifndef MR_LEARNED_PLOTS_H
#define MR_LEARNED_PLOTS_H

#include "../mr_status.h"
#include "learned.h"
#include "sweep_table.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MR_LEARNED_PLOT_FILES 4

/* The plots' file names in DIR, k = 0 .. MR_LEARNED_PLOT_FILES - 1: "rows.csv", "curves.csv", "roughness.svg",
 * "specular.svg" (for a caller that checks them against its inputs first); NULL outside. */
const char *mr_learned_plot_file_name(int k);

typedef struct mr_learned_plots_options {
    const char *folder_hint; /* how messages name DIR ("HINT 'DIR': cannot create the folder: ..."), e.g. the
                                option that gave it ("--plots"); NULL: "plots folder" */
} mr_learned_plots_options;

typedef struct mr_learned_plots_result {
    int cut;   /* 1: the transform has a roughness and specular pair and its plots were written; 0: no plots */
    int drawn; /* 1: gnuplot drew the SVGs; 0: only the CSVs (gnuplot missing or failed) or no plots */
} mr_learned_plots_result;

/* Write the transform t at `path` (mr_learned_write) and, when dir is not NULL, its cross sections through the
 * rows it was learned from in dir (above), all or none. opts and result may be NULL. MR_ERR_INVALID_ARG for NULL t,
 * rows or path; MR_ERR_IO naming a folder or file that cannot be made or written (or a DIR/NAME too long), or
 * gnuplot's input that cannot be written; mr_learned_write's and the transform's evaluation failures. */
mr_status mr_learned_write_with_plots(const mr_learned *t, const mr_sweep_table *rows, const char *path,
                                      const char *dir, const mr_learned_plots_options *opts,
                                      mr_learned_plots_result *result);

#ifdef __cplusplus
}
#endif

#endif /* MR_LEARNED_PLOTS_H */
