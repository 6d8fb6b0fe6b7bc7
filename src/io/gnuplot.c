/*
 * gnuplot.c — plots drawn by gnuplot into the callers' files (contract in io_internal.h).
 */
#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "../mr_internal.h"
#include "io_internal.h"

mr_status mr_gnuplot_draw(int *drawn, const char *script, ...) {
    *drawn = 0;
    FILE *plot = popen("gnuplot 2>/dev/null", "w");
    if (plot == NULL) return MR_OK; // no gnuplot: the data files are the plot
    va_list args;
    va_start(args, script);
    vfprintf(plot, script, args);
    va_end(args);
    const int bad = ferror(plot);
    const int err = errno;
    const int rc = pclose(plot);
    if (bad) return mr_fail(MR_ERR_IO, "cannot write the plot script to gnuplot: %s", strerror(err ? err : EIO));
    *drawn = rc == 0;
    return MR_OK;
}
