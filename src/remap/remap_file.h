/*
 * remap_file.h — what the remap layer's batch runs share (sweep.c's CSV files, direct.c's caches): the crash-safe
 * text files and the parallel driver; not installed, not public.
 *
 * The protocol (sweep.h and direct.h say what each file holds): a header of "# " lines that describes the run
 * completely, then one line per result. The file is opened O_APPEND and every line leaves the process in ONE
 * write() of the complete line, serialised between threads, so a killed process leaves whole lines plus at most
 * one torn last line, which the next run cuts off; a short write (full disk) is cut back off at once. An advisory
 * fcntl lock refuses a second process writing the same file. Numbers are written with %.17g in the C numeric
 * locale (c_locale.h), so they read back bit for bit.
 *
 * `what` names the file in messages ("sweep file", "direct cache"): "<what> '<path>': <reason>".
 */
#ifndef MR_REMAP_FILE_H
#define MR_REMAP_FILE_H

#include <stddef.h>
#include <sys/types.h>

#include "../brdf/brdf.h"
#include "../mr_status.h"
#include "../render/render.h"
#include "remap.h"

/* ---- a growing string ---- */

typedef struct mr_strbuf {
    char *text; /* NUL-terminated once anything was printed; free() it */
    size_t length, capacity;
    int failed; /* an allocation failed: the content is incomplete */
} mr_strbuf;

/* Append printf-style text; on an allocation failure sets sb->failed and appends nothing more. */
#if defined(__GNUC__)
__attribute__((format(printf, 2, 3)))
#endif
void mr_strbuf_printf(mr_strbuf *sb, const char *fmt, ...);

/* " name=v" per parameter of m (%.17g), one value for an RGB parameter whose channels agree (so the text can be
 * pasted back as command-line arguments). */
void mr_strbuf_values(mr_strbuf *sb, const mr_brdf_model *m, const double *values);

/* ",name" per scalar slot of m, ",name_r,name_g,name_b" for an RGB parameter, each name after `prefix`. */
void mr_strbuf_columns(mr_strbuf *sb, const mr_brdf_model *m, const char *prefix);

/* The fit scene a file's remaps ran in: `scene` with size 0 read as MR_REMAP_DEFAULT_SIZE. */
mr_scene mr_remap_file_scene(const mr_fit_scene_options *scene);

/* The two header lines that say how a file's remaps into `target` ran:
 *   "# remap: strategy=auto max_evaluations=400 xtol=... grid_points=0 starts=8 seed=1[ held=a,b][ tied=t:s,...]
 *    [ renderers=SOURCE,TARGET samples=N]\n"
 *   "# scene: fit size=64 light=45 intensity=10 edge_samples=4 highlight_samples=integrated\n"
 * The remap options are written as given (sweeps store them defaulted). `renderers` (NULL, or both names
 * "builtin": no words, as files written before renderers) names who rendered each side and the external
 * renderers' sample count. */
void mr_strbuf_remap_lines(mr_strbuf *sb, const mr_brdf_model *source, const mr_brdf_model *target,
                           const mr_remap_options *remap, const mr_fit_scene_options *scene,
                           const mr_remap_renderers *renderers);

/* Range checks of the remap options and fit scene a file's remaps use; MR_ERR_INVALID_ARG "<what>: ..." naming the
 * field. */
mr_status mr_remap_file_check_options(const char *what, const mr_remap_options *remap,
                                      const mr_fit_scene_options *scene);

/* Every value of m's packed vector inside its parameter's [min, max] (a switch an integer); MR_ERR_INVALID_ARG
 * "<which> value NAME = V of model 'M' is outside [min, max]" otherwise. */
mr_status mr_remap_file_check_values(const mr_brdf_model *m, const double *values, const char *which);

/* ---- the file ---- */

/* The whole file behind fd into a malloc'ed, NUL-terminated buffer (*out, the caller frees it). */
mr_status mr_text_file_read_all(int fd, const char *path, const char *what, char **out, size_t *out_size);

/* One write() of the line at the end of the file (O_APPEND). If the kernel takes only part of it (a full disk, a
 * file-size limit), the rest is tried once more, which either completes the line or yields the real errno; then
 * the partial line is cut back off, so the file keeps only whole lines. *file_size tracks the size (only this
 * process writes: the lock). */
mr_status mr_text_file_append(int fd, const char *path, const char *what, const char *line, size_t length,
                              off_t *file_size);

/* Take the advisory write lock (fcntl F_SETLK) on the whole file; MR_ERR_IO naming the other process's pid when
 * another process holds it. The lock goes away with the descriptor (or the process). */
mr_status mr_text_file_lock(int fd, const char *path, const char *what);

/* Check that data[0, size) begins with `header` line by line; a line starting with `free_prefix` (may be NULL)
 * only has to start with it in the file too (e.g. the "# command: " a sweep records). On success *rows (the
 * offset just after the header) and *lines (the header's line count). A file that ends inside the header is
 * MR_ERR_FORMAT ("the header ends early, at line N (a torn file?)"); a differing line is MR_ERR_INVALID_ARG:
 * "<what> '<path>' <owner>: line N is '...', this run's is '...'; not touching it (<advice>)". */
mr_status mr_text_file_match_header(const char *path, const char *what, const char *owner, const char *advice,
                                    const char *data, size_t size, const char *header, size_t header_length,
                                    const char *free_prefix, size_t *rows, long *lines);

/* ---- the parallel driver ---- */

/* Run work(ctx, item) for every item in [0, count) on `threads` OpenMP threads, handed out one at a time
 * (schedule(dynamic)); an item not yet started is skipped once *stop (read atomically; the work sets it atomically
 * to stop the run) is set. Each thread runs its items single-threaded inside (the renders and metrics of a remap
 * open no teams of their own: the items are the parallelism) and in the C numeric locale. MR_OK, or the status of
 * a thread that could not switch locale ("<what>: cannot switch a thread to the C locale"; *stop is then set). */
mr_status mr_remap_run_parallel(int threads, long count, int *stop, void (*work)(void *ctx, long item), void *ctx,
                                const char *what);

/* ---- fields of a comma-separated line ---- */

/* The next ','-separated field of line[0, length) from *at into *field / *field_len; *at becomes SIZE_MAX after
 * the last field. Returns 0 when there is no field left (*at was SIZE_MAX). */
int mr_csv_next_field(const char *line, size_t length, size_t *at, const char **field, size_t *field_len);

/* Split `line` in place at commas (a trailing '\r' or '\n' cut off) into fields[0 .. result), at most max. */
int mr_csv_split(char *line, char **fields, int max);

/* The whole field as a number (strtod in the current numeric locale) / a non-negative decimal integer; 0 if the
 * field is empty, too long or not entirely the number. */
int mr_csv_parse_double(const char *field, size_t len, double *out);
int mr_csv_parse_long(const char *field, size_t len, long *out);

#endif /* MR_REMAP_FILE_H */
