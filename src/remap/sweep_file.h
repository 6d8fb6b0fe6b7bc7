/*
 * sweep_file.h — the sweep file's format, in one place: its header written and read back into a sweep, its rows
 * formatted, parsed and checked, its lines read by column name; used by the sweep (sweep.c: writing, resume),
 * the shard merge (sweep_merge.c), learn's sweep table (src/learn/sweep_table.c) and train's dataset
 * (src/workflow/dataset.c).
 * Not installed, not public: sweep.h describes the file, and its public calls (mr_sweep_format_row,
 * mr_sweep_parse_row, mr_sweep_check_row, mr_sweep_scene_parse) are defined in sweep_file.c on top of these.
 *
 * Two kinds of reader use it. The sweep and the merge know the sweep (an mr_sweep_spec) and read a row as exactly
 * its columns (mr_sweep_file_parse_row, mr_sweep_file_check_row). Learn and train take whatever sweep they are
 * given and find their columns by name in the column line (mr_sweep_reader, mr_sweep_file_find_column,
 * mr_sweep_file_slot_name), each with messages of its own.
 *
 * Every function here expects the C numeric locale to be in force (c_locale.h): the callers enter it once per
 * file or run. Messages: the parsers' say what is wrong, not where; callers add the file and line
 * (mr_fail_context), except where a function's comment says it names them.
 */
#ifndef MR_REMAP_SWEEP_FILE_H
#define MR_REMAP_SWEEP_FILE_H

#include <stddef.h>
#include <stdio.h>

#include "../mr_status.h"
#include "remap_file.h"
#include "sweep.h"

/* The header lines a reader looks for. "# command:" and "# shard:" are the only lines a run may change without
 * making another sweep (resume ignores the first; merge drops both). */
#define MR_SWEEP_FROM_PREFIX "# from: "
#define MR_SWEEP_TO_PREFIX "# to: "
#define MR_SWEEP_REMAP_PREFIX "# remap: "
#define MR_SWEEP_SCENE_PREFIX "# scene: "
#define MR_SWEEP_SAMPLING_PREFIX "# sampling: "
#define MR_SWEEP_SHARD_PREFIX "# shard: "
#define MR_SWEEP_COMMAND_PREFIX "# command: "

/* Columns after the target's: rmse, relative_rmse, ssim, outcome, renders, seconds. */
#define MR_SWEEP_ROW_TAIL_COLUMNS 6

/* ---- writing ---- */

/* The header of sweep `spec` (every line '\n'-terminated, the column line last) appended to *sb; a shard
 * (shard_count > 0) adds "# shard: K/N" before the command line (command_line NULL = empty; its line breaks become
 * spaces). MR_ERR_NOMEM if sb failed. */
mr_status mr_sweep_file_header(const mr_sweep_spec *spec, const char *command_line, long shard_index,
                               long shard_count, mr_strbuf *sb);

/* The column name of packed slot `slot` of model m, after `prefix` ("" for the source, "to_" for the target): the
 * parameter's name, with _r/_g/_b for an RGB parameter's channels; into buf[size]. */
void mr_sweep_file_slot_name(const mr_brdf_model *m, int slot, const char *prefix, char *buf, size_t size);

/* mr_sweep_format_row without the argument checks and locale switch. */
mr_status mr_sweep_file_format_row(const mr_sweep_spec *spec, const mr_sweep_row *row, char *buf, size_t size,
                                   size_t *length);

/* ---- rows of a known sweep ---- */

/* mr_sweep_parse_row for a sweep of `total` samples (the index must lie below it), without the spec check. */
mr_status mr_sweep_file_parse_row(const mr_sweep_spec *spec, long total, const char *line, size_t length,
                                  mr_sweep_row *out);

/* mr_sweep_check_row without the spec check. */
mr_status mr_sweep_file_check_row(const mr_sweep_spec *spec, const mr_sweep_row *row);

/* ---- the header read back ---- */

/* "MODEL name=v ..." (text[0, length): the text after "# from: " or "# to: ", without its line end) into the model
 * and its packed values (defaults for the parameters not named). MR_ERR_FORMAT: "the line is too long" (length
 * >= MR_SWEEP_MAX_LINE), "no model named", or mr_brdf_find's / mr_brdf_parse_assignment's message. */
mr_status mr_sweep_file_parse_model(const char *text, size_t length, const mr_brdf_model **model,
                                    double *values);

/* The header lines' texts (after their prefixes, without line ends) back into *spec: the models and values, the
 * remap options, the scene and the sampling, then mr_sweep_check. MR_ERR_FORMAT with the message of the line that
 * failed, and *step (may be NULL) naming it ("# from:", "# to:", "# remap:", "# scene:", "# sampling:", or "the
 * header" when the check failed). The result is only the sweep the lines describe: whether they are the lines
 * this version would write shows when the header is rebuilt from it (mr_sweep_file_header) and compared. */
mr_status mr_sweep_file_spec_from_header(const char *from, const char *to, const char *remap, const char *scene,
                                         const char *sampling, mr_sweep_spec *spec, const char **step);

/* ---- reading by column name ---- */

/* A sweep file read line by line, for the readers that find their columns by name. Zero it, then
 * mr_sweep_reader_open; mr_sweep_reader_close releases it (also after a failed open). */
typedef struct mr_sweep_reader {
    const char *path;  /* borrowed */
    FILE *fp;
    size_t max_line;   /* longest line accepted, without its '\n'; 0: any */
    char *line;        /* the current line (getline: NUL-terminated, '\n' kept; a NUL byte in it ends it as a
                          C string, as the readers take it) */
    size_t length, capacity;
    long line_number;  /* of the current line, from 1 */
} mr_sweep_reader;

/* Open `path` (a regular file: a FIFO would block; the message names the path as mr_io_open_input does). */
mr_status mr_sweep_reader_open(mr_sweep_reader *r, const char *path, size_t max_line);

/* The next line into r->line: 1, or 0 at the end of the file; -1 on failure, with *failure: MR_ERR_FORMAT
 * "PATH:LINE: line longer than MAX bytes", MR_ERR_NOMEM "PATH: out of memory reading line LINE", MR_ERR_IO
 * "PATH: read error: ..." (found at the end). */
int mr_sweep_reader_next(mr_sweep_reader *r, mr_status *failure);

void mr_sweep_reader_close(mr_sweep_reader *r);

/* The index of the first of names[0, count) equal to `name`, or -1. */
int mr_sweep_file_find_column(char *const *names, int count, const char *name);

/* A field that is entirely a finite number (strtod, in the current numeric locale) into *out; 0 otherwise. */
int mr_sweep_file_parse_number(const char *text, double *out);

#endif /* MR_REMAP_SWEEP_FILE_H */
