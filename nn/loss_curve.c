/*
 * loss_curve.c — a trained network written with its loss curve as one set of files (contract in mlp.h,
 * mr_mlp_write_with_curve).
 */
#include <stdio.h>
#include <string.h>

#include "../src/c_locale.h"
#include "../src/io/gnuplot.h"
#include "../src/mr_internal.h"
#include "mlp.h"

/* PREFIX.csv and, if gnuplot runs, PREFIX.svg, prepared as the temporary files files[0] and files[1] (their targets
 * paths[0] and paths[1]). On failure every temporary file is removed. */
static mr_status prepare_curve(const mr_mlp_epoch *epochs, int count, const char *prefix, const char *hint,
                               const char *title, mr_atomic_file files[2], char paths[2][4096], int *drawn) {
    char *path = paths[0], *svg = paths[1];
    int length = snprintf(path, sizeof paths[0], "%s.csv", prefix);
    int svg_length = snprintf(svg, sizeof paths[1], "%s.svg", prefix);
    if (length < 0 || (size_t)length >= sizeof paths[0] || svg_length < 0 || (size_t)svg_length >= sizeof paths[1])
        return mr_fail(MR_ERR_IO, "%s '%s': the name is too long", hint, prefix);
    FILE *f = NULL;
    mr_status status = mr_atomic_open_text(path, &files[0], &f);
    if (status != MR_OK) return status;
    fprintf(f, "epoch,train_loss,validation_loss,best_epoch\n");
    for (int i = 0; i < count; i++)
        fprintf(f, "%d,%.9g,%.9g,%d\n", epochs[i].epoch, epochs[i].train_loss, epochs[i].validation_loss,
                epochs[i].best_epoch);
    status = mr_atomic_close_text(f, &files[0]);
    if (status != MR_OK) return status;
    // The plot is a convenience: without gnuplot the CSV is the curve. gnuplot draws into the SVG's temporary file.
    status = mr_atomic_begin(svg, &files[1]);
    if (status == MR_OK)
        status = mr_gnuplot_draw(drawn,
                                 "set terminal svg size 800,480 dynamic font 'Helvetica,12' background rgb 'white'\n"
                                 "set output '%s'\nset datafile separator ','\nset logscale y\nset grid\n"
                                 "set xlabel 'epoch'\nset ylabel 'loss (MSE of normalised outputs)'\n"
                                 "set title '%s' noenhanced\n"
                                 "plot '%s' using 1:2 skip 1 with lines lw 2 title 'train', "
                                 "'' using 1:3 skip 1 with lines lw 2 title 'validation'\n",
                                 files[1].tmp_path, title, files[0].tmp_path);
    if (status != MR_OK) {
        mr_atomic_abort(&files[0]);
        mr_atomic_abort(&files[1]);
        return status;
    }
    if (!*drawn) mr_atomic_abort(&files[1]);
    return MR_OK;
}

mr_status mr_mlp_write_with_curve(const mr_mlp *net, const char *path, const mr_mlp_epoch *epochs, int count,
                                  const char *prefix, const char *prefix_hint, const char *title, int *drawn) {
    int ignored;
    if (drawn == NULL) drawn = &ignored;
    *drawn = 0;
    if (net == NULL || path == NULL || prefix == NULL || (count > 0 && epochs == NULL) || count < 0)
        return mr_fail(MR_ERR_INVALID_ARG, "loss curve: NULL network, path, prefix or epochs");
    mr_c_numeric locale; // the CSV's numbers in the C locale whatever the host's (c_locale.h)
    mr_status status = mr_c_numeric_enter(&locale, "loss curve");
    if (status != MR_OK) return status;
    mr_atomic_file files[2];
    memset(files, 0, sizeof files);
    char paths[2][4096];
    status = prepare_curve(epochs, count, prefix, prefix_hint ? prefix_hint : "loss curve", title ? title : "", files,
                           paths, drawn);
    mr_c_numeric_leave(&locale);
    if (status == MR_OK) {
        status = mr_mlp_write(net, path);
        if (status != MR_OK) {
            mr_atomic_abort(&files[0]);
            mr_atomic_abort(&files[1]);
        }
    }
    if (status == MR_OK) status = mr_atomic_commit_set(files, 2, &path, 1);
    if (status != MR_OK) *drawn = 0;
    return status;
}
