/*
 * mr_core.h — the core of libmatremap: what every layer needs, in one header.
 *
 *   the version            MR_VERSION_*, mr_version()                         (version.c)
 *   the data path          mr_data_path(): where installed data files are     (data_dir.c)
 *   the one RNG            splitmix64: mr_rng_mix, mr_rng_next, mr_rng_unit, mr_rng_stream (inline, below)
 *   atomic output files    mr_atomic_begin / commit / abort / write_bytes     (io/atomic_file.c)
 *   input files            mr_io_open_input: regular files only, never blocks  (io/input_file.c)
 *   the thread rule        mr_auto_threads: what `threads = 0` means            (threads.c)
 *
 * Why a header of its own, and public: every module of the library (render, remap, learn, report, workflow, nn,
 * gltf) and every front end (the CLI today; bindings tomorrow) needs these, and none of them belongs to one module.
 * Library code reaches them through mr_internal.h, which includes this header; it never includes the umbrella
 * matremap.h (which includes this one) nor another module's *_internal.h. Installed with the public headers.
 * C and C++ (the image-I/O and glTF shims) both include it, so it uses no C-only syntax.
 */
#ifndef MR_CORE_H
#define MR_CORE_H

#define MR_VERSION_MAJOR 0
#define MR_VERSION_MINOR 1
#define MR_VERSION_PATCH 0
#define MR_VERSION_STRING "0.1.0"

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "mr_status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- version and data ------------------------------------------------------------------------------------ */

/* The library's version string, MR_VERSION_STRING of the build it was compiled from. */
const char *mr_version(void);

/* The path of the installed data file `file` (e.g. "spec2metal.mlp") in out[size]: beside the running executable
 * (PREFIX/bin -> PREFIX/share/matremap/, or a build tree's build/bin -> data/), else the install directory fixed at
 * build time (MR_DATA_DIR). MR_ERR_IO listing the places tried when none has it. */
mr_status mr_data_path(const char *file, char *out, size_t size);

/* ---- the one random number generator --------------------------------------------------------------------
 * splitmix64 (Steele, Lea, Flood, "Fast splittable pseudorandom number generators", OOPSLA 2014): 64 bits of
 * state, advanced by the golden-ratio increment and mixed by a bijective finaliser. Every seeded draw of the
 * library (sweep samples, multi-start points, dataset texels, the MLP's and the SVR's splits and shuffles, learn's
 * permutations) comes from here, so one seed gives the same numbers on every machine and thread count. These
 * streams are part of the files' contract (a sweep file's rows, a dataset's texels follow from their seed):
 * tests/test_headers.c pins the first values for seed 1, and any change to them changes outputs. */

/* splitmix64's finaliser: a bijection of 64-bit words (distinct inputs, distinct outputs). Callers derive start
 * states from it (e.g. mr_rng_mix(mr_rng_mix(seed) + index): distinct indices never share a start). */
static inline uint64_t mr_rng_mix(uint64_t z) {
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

/* The next 64 random bits of the stream at *state (which advances). */
static inline uint64_t mr_rng_next(uint64_t *state) {
    *state += 0x9e3779b97f4a7c15ULL;
    return mr_rng_mix(*state);
}

/* Uniform in [0, 1): the top 53 bits of mr_rng_next, so every value is a double exactly. */
static inline double mr_rng_unit(uint64_t *state) { return (double)(mr_rng_next(state) >> 11) * 0x1p-53; }

/* The start state of stream `stream` of `seed`: independent streams of one seed (the MLP's split, initial weights
 * and epoch shuffles are streams 1, 2, 3) that do not overlap in practice. */
static inline uint64_t mr_rng_stream(uint64_t seed, uint64_t stream) {
    return mr_rng_mix(seed ^ mr_rng_mix(stream + 0x6a09e667f3bcc909ULL));
}

/* ---- atomic output files (io/atomic_file.c) ----------------------------------------------------------------
 * Protocol (after redis' rdbSave): mr_atomic_begin() creates an empty, exclusive temporary file beside the
 * target, named "<target>.tmp.<pid>.<n>" (same directory, so rename(2) cannot cross file systems); the writer
 * fills tmp_path; mr_atomic_commit() fsyncs it and renames it over the target; on any failure the caller
 * calls mr_atomic_abort(), which unlinks the temporary file. A target that existed before is never opened
 * for writing, so a failed write leaves it untouched. Every file the library or the CLI writes goes through it. */
typedef struct mr_atomic_file {
    char tmp_path[4096]; /* the temporary file to write */
    const char *target;  /* borrowed: the final path */
    int active;          /* 1 between a successful begin and commit/abort */
} mr_atomic_file;

/* Create the temporary file for `target`. MR_ERR_IO (naming the target and the reason, e.g. a missing or
 * unwritable directory) or MR_ERR_INVALID_ARG (path too long). On failure nothing is left on disk. */
mr_status mr_atomic_begin(const char *target, mr_atomic_file *file);

/* fsync the finished temporary file and rename it to the target. On failure the temporary file is removed
 * (the caller need not call mr_atomic_abort, though doing so is harmless). */
mr_status mr_atomic_commit(mr_atomic_file *file);

/* The whole protocol for a file already encoded in memory: begin, fwrite + fflush + fclose (every result
 * checked), commit; abort on any failure. Errors (MR_ERR_IO) name the target and the system's reason. */
mr_status mr_atomic_write_bytes(const char *target, const void *bytes, size_t size);

/* Remove the temporary file (if still there). Safe to call twice, and after a successful commit (no-op).
 * Preserves errno and the recorded last-error message. */
void mr_atomic_abort(mr_atomic_file *file);

/* A text file written through stdio under the protocol: mr_atomic_open_text begins and opens the temporary file
 * for writing (*out; on failure NULL and nothing left: mr_atomic_begin's errors, or MR_ERR_IO "cannot write
 * 'TARGET': REASON"); mr_atomic_close_text closes it and checks every write (the stream's error indicator, the
 * last flush): MR_OK with the file still to commit (or abort), or MR_ERR_IO "cannot write 'TARGET': REASON" with
 * the temporary file removed. Messages as the command line's outputs have always said them. */
mr_status mr_atomic_open_text(const char *target, mr_atomic_file *file, FILE **out);
mr_status mr_atomic_close_text(FILE *f, mr_atomic_file *file);

/* Commit a set of prepared files all or none: every active file of files[0..n) in order; when one fails, the files
 * of the set committed before it are removed, and so are written[0..n_written) (outputs the caller committed just
 * before, e.g. the file the set goes with), the rest aborted, and MR_ERR_IO is returned with the commit's message
 * followed by " (the outputs written before it removed)". Inactive files (aborted, or never begun) are skipped. */
mr_status mr_atomic_commit_set(mr_atomic_file *files, int n, const char *const *written, int n_written);

/* ---- input files (io/input_file.c) --------------------------------------------------------------------------
 * Every file the library opens because a user (or a file the user gave) named it goes through mr_io_open_input:
 * only a regular file is read. A folder, a FIFO, a device (/dev/zero) or a socket is refused by name before a byte
 * is read, where fopen would open a folder (whose size, asked by seeking, is 2^63 - 1), block on a FIFO or read a
 * device without end. */

/* Open `path` for reading as a stdio stream (*out; the caller fcloses it) if it is a regular file of at most
 * max_bytes bytes (0: any size); *size (may be NULL) receives its size. Failures, with messages "<label>: <why>"
 * (just "<why>" when label is NULL): MR_ERR_IO "cannot open: <system reason>", "is a directory", "is not a
 * regular file (a FIFO)" (or a character device, a block device, a socket); MR_ERR_FORMAT "<n> bytes, more than
 * the limit of <max_bytes>". Never blocks: the file is opened with O_NONBLOCK and checked on its descriptor. */
mr_status mr_io_open_input(const char *path, const char *label, uint64_t max_bytes, FILE **out, uint64_t *size);

/* The size of the label a message gives a file it reads ("image '<path>'", "transform '<path>'"): longer labels
 * are cut to the size of mr_last_error's buffer, which would cut them anyway. */
#define MR_IO_LABEL_SIZE 1024

/* ---- the automatic thread rule (threads.c) -------------------------------------------------------------- */

/* OpenMP threads for a piece of work: `requested` when it is > 0 (an option the caller set), else the automatic
 * rule: a team of omp_get_max_threads() when `work` reaches `threshold` (work too small to gain from a second
 * thread stays on one: copies run side by side), 1 otherwise. Every options struct's `threads = 0` means this
 * rule; the thresholds are the callers' (threads.c lists them). */
int mr_auto_threads(int requested, long work, long threshold);

#ifdef __cplusplus
}
#endif

#endif /* MR_CORE_H */
