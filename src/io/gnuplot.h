/*
 * gnuplot.h — plots drawn by gnuplot (gnuplot.c): what src/io offers the modules that draw figures beside their data
 * (learn's cross sections, train's loss curve). Not installed.
 */
#ifndef MR_IO_GNUPLOT_H
#define MR_IO_GNUPLOT_H

#include "../mr_status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* A plot is a convenience beside the data it draws: the script (printf-style) is piped to "gnuplot" (popen, its
 * stderr discarded), which draws into the files the script names (the callers' temporary files). *drawn is 1 when
 * gnuplot ran and succeeded, 0 when it is missing or failed (the caller then aborts the pictures and keeps the
 * data). MR_ERR_IO "cannot write the plot script to gnuplot: REASON" only when writing to a gnuplot that started
 * failed. */
#if defined(__GNUC__)
__attribute__((format(printf, 2, 3)))
#endif
mr_status mr_gnuplot_draw(int *drawn, const char *script, ...);

#ifdef __cplusplus
}
#endif

#endif /* MR_IO_GNUPLOT_H */
