/*
 * output_plan.h — what a job reads and writes, checked before it writes anything: no output ever replaces an input.
 *
 * Main calls:
 *   mr_output_plan plan = {0};                                  // zeroed: an empty plan
 *   mr_output_plan_inputf(&plan, "t.png", "base_color=@%s", "t.png");
 *   mr_output_plan_input(&plan, "env.hdr", "--env env.hdr");
 *   mr_output_plan_output(&plan, "out/x.png", NULL);            // NULL label: the path says it all
 *   if (mr_output_plan_check(&plan) != MR_OK) fprintf(stderr, "%s\n", mr_last_error());
 *   ... write the outputs; on failure: mr_output_plan_unmake_folders(&plan);
 *   mr_output_plan_free(&plan);
 *
 * A job (a command of the command line, a call of another front end) lists its inputs (every file it reads: maps,
 * environment maps, datasets, the files a glTF asset refers to, ...) and its outputs (every file it writes, derived
 * names included: a loss curve's PREFIX.csv and PREFIX.svg, a remap's pictures, a report's folder), then calls
 * mr_output_plan_check before it writes anything; the check may be called again once more inputs are known (a glTF
 * asset's files, after it is read), and checks every pair each time.
 *
 * Refused (MR_ERR_INVALID_ARG):
 *   - an output that is the same file as an input: the same device and inode (stat), so "./x", "dir/../x", hard
 *     links and symbolic links count; an output that does not exist yet, or lies in a folder that does not, cannot
 *     be one;
 *   - a folder output (mr_output_plan_output_folder: a folder the job replaces as a whole) that holds an input;
 *   - two outputs that name one file (the same existing file, or the same name in the same existing folder): the
 *     second would replace the first.
 * The message (mr_last_error) names both, each as the caller labelled it:
 *   output 't.png' is the input base_color=@t.png; refusing to overwrite it
 *   output 'ds.csv' (--loss-curve ds) is the input dataset ds.csv; refusing to overwrite it
 *   output folder 'r' holds the input --env r/env.hdr; refusing to replace it
 *   output './x.png' is also the output 'x.png'; refusing to write one over the other
 * Labels say how the user gave the file, as a noun phrase ("--env env.hdr", "base_color=@t.png", "dataset ds.csv");
 * an input with no label (NULL) is named "'PATH'"; an output's label (may be NULL) says where a derived name comes
 * from and is printed in parentheses after its path.
 *
 * Folders: when every check passes, the check makes the missing folders the outputs are to be written in, nested
 * as mkdir -p does ("a/b/c/x.png" makes a, a/b and a/b/c; for a folder output its parent, not the folder itself; the
 * umask applies), so that a job takes an output in a folder that does not exist yet, and says so before any work
 * when it cannot (MR_ERR_IO):
 *   output 'f/x/y.png': cannot create the folder 'f': Not a directory
 * The folders made are recorded in the plan, in the order made (parents first). A job that fails afterwards calls
 * mr_output_plan_unmake_folders, which removes those still empty, deepest first; a caller that frees the plan before
 * it knows whether the job succeeded takes the list first (mr_output_plan_take_folders: matremap's command line
 * keeps one list per process and removes them when a command exits non-zero).
 *
 * Out of memory: a registration that cannot copy its path or label returns MR_ERR_NOMEM and marks the plan, so that
 * callers may register without checking each call: the next check returns MR_ERR_NOMEM ("out of memory listing the
 * inputs and outputs") before looking at any file. A folder made that cannot be recorded is removed again, and the
 * check returns MR_ERR_NOMEM ("output 'P': cannot create the folder 'F': Cannot allocate memory").
 *
 * Ownership: the plan owns copies of every path and label and the list of folders made; mr_output_plan_free
 * releases them (NULL-safe) and leaves the plan empty (zeroed), ready for reuse; it removes no folder. A NULL path
 * lists nothing (MR_OK): optional options may be passed as they are. The plan is not thread-safe; distinct plans are
 * independent. Nothing is printed. POSIX only (stat, realpath, mkdir, rmdir).
 */
#ifndef MR_IO_OUTPUT_PLAN_H
#define MR_IO_OUTPUT_PLAN_H

#include "../mr_status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* A file listed in a plan. */
typedef struct mr_output_plan_entry {
    char *path;  /* owned copy */
    char *label; /* owned copy; NULL when none was given */
    int folder;  /* an output folder, replaced as a whole */
} mr_output_plan_entry;

/* Zero-initialise (an empty plan); change only through the functions below; release with mr_output_plan_free. */
typedef struct mr_output_plan {
    mr_output_plan_entry *inputs, *outputs;
    int input_count, output_count, input_capacity, output_capacity;
    char **folders_made; /* owned: the folders the checks made, in the order made (parents first) */
    int folders_made_count, folders_made_capacity;
    int out_of_memory; /* a registration failed: the next check reports it (a caller that could not make the path
                          it meant to list, out of memory, may set it too) */
} mr_output_plan;

/* List an input file (`label` copied; may be NULL). MR_OK, or MR_ERR_NOMEM (the plan remembers it). */
mr_status mr_output_plan_input(mr_output_plan *plan, const char *path, const char *label);
/* An output file, labelled by `label` (NULL: by its path alone). MR_OK or MR_ERR_NOMEM, as above. */
mr_status mr_output_plan_output(mr_output_plan *plan, const char *path, const char *label);
/* An output folder whose contents the job replaces as a whole. MR_OK or MR_ERR_NOMEM, as above. */
mr_status mr_output_plan_output_folder(mr_output_plan *plan, const char *path, const char *label);

/* mr_output_plan_input and mr_output_plan_output with a printf-formatted label (label_fmt NULL: no label). */
#if defined(__GNUC__)
__attribute__((format(printf, 3, 4)))
#endif
mr_status mr_output_plan_inputf(mr_output_plan *plan, const char *path, const char *label_fmt, ...);
#if defined(__GNUC__)
__attribute__((format(printf, 3, 4)))
#endif
mr_status mr_output_plan_outputf(mr_output_plan *plan, const char *path, const char *label_fmt, ...);

/* Check every output against every input and every other output, then make the outputs' missing folders (above).
 * MR_OK; MR_ERR_INVALID_ARG for a refused output, MR_ERR_IO for a folder that cannot be made, MR_ERR_NOMEM; the
 * message names the output and the input, the other output or the folder. A NULL or empty plan is MR_OK. */
mr_status mr_output_plan_check(mr_output_plan *plan);

/* Remove the folders the plan's checks made that are still empty, deepest first (rmdir: a folder that holds
 * anything stays), and forget them all. NULL-safe. */
void mr_output_plan_unmake_folders(mr_output_plan *plan);

/* Hand over the folders the plan's checks made so far, in the order made (parents first), and forget them: the
 * caller owns the array and each string (free() both) and removes them, or not, itself. NULL and *count = 0 when
 * there are none. */
char **mr_output_plan_take_folders(mr_output_plan *plan, int *count);

/* Release the plan's copies and lists and leave it empty; the folders it made stay. NULL-safe. */
void mr_output_plan_free(mr_output_plan *plan);

#ifdef __cplusplus
}
#endif

#endif /* MR_IO_OUTPUT_PLAN_H */
