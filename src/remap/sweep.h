/*
 * sweep.h — remap many source materials (a grid or a seeded random sample of the source model's parameters)
 * and stream one CSV row per remap into a file that survives crashes and can be resumed.
 *
 * Main calls:
 *   mr_sweep_spec spec;
 *   mr_sweep_spec_init(&spec, mr_brdf_find("ggx"), mr_brdf_find("ward-balanced"));   // defaults everywhere
 *   mr_brdf_parse_assignment(spec.source, "diffuse=0", spec.source_values);           // fixed source values
 *   spec.held |= 1u << mr_brdf_param_index(spec.source, "diffuse");                     // ... even by RANDOM
 *   spec.sampling = MR_SWEEP_GRID;
 *   mr_sweep_parse_axis(spec.source, "alpha=0.01:1:9:log", &spec.axes[spec.axis_count++]);
 *   mr_sweep_options o = {0};  o.resume = 1;  o.threads = 2;                          // zero = defaults
 *   mr_sweep_summary s;
 *   mr_sweep_run(&spec, "alpha.csv", &o, &s);
 *
 * Samples. Sample i (0 <= i < mr_sweep_sample_count()) is a full packed source value vector:
 *   - GRID: the Cartesian product of the axes, first axis slowest (the index is a mixed-radix number whose last
 *     digit is the last axis). An axis spaces `count` values from lo to hi inclusive, linearly or (log_scale)
 *     geometrically; an RGB parameter gets the value in all three channels. Axes override source_values.
 *   - RANDOM: every source parameter that is not a switch, not MR_PARAM_FIT_FIXED, not held (bit p of `held`)
 *     and has a non-empty range is drawn uniformly from [min, max], log-uniformly if the descriptor flags
 *     MR_PARAM_LOG_SCALE (and min > 0), each channel of an RGB parameter independently. The draws come from a
 *     splitmix64 stream started from (seed, i) alone, so sample i is the same whatever else runs, in any order,
 *     on any number of threads. The rest keep source_values.
 * Each sample is remapped with mr_remap() (remap.h) in the fit scene of `scene`, with `remap` as options and
 * target_values as the target's fixed values.
 *
 * The file (docs/sweep.md has an example). Text, '\n' line ends, numbers printed with %.17g in the C numeric
 * locale whatever the process locale is (so they read back exactly):
 *   # matremap VERSION sweep          \
 *   # from: MODEL name=v ...           |
 *   # to: MODEL name=v ...             |  the header: these lines describe the run completely; resuming
 *   # remap: strategy=auto ...         |  requires them to be identical, except "# command:", which only
 *   # scene: fit size=128 light=45 ... |  records the command line of the run that created the file
 *   # sampling: grid alpha=... | random=N seed=S over p,q,...
 *   # samples: N                       |
 *   # command: ...                    /
 *   index,<source slots>,<to_ target slots>,rmse,relative_rmse,ssim,outcome,renders,seconds
 *   0,...
 * A scalar slot is named after its parameter; an RGB parameter's slots are name_r, name_g, name_b; target
 * columns carry the prefix "to_". Values are the full packed vectors, fixed values included.
 *
 * Crash safety and resume (mr_sweep_run):
 *   - The file is opened O_APPEND and every row, like the header, goes out in ONE write() of the complete line,
 *     serialised between threads; so a killed process (kill -9, OOM, SIGINT) leaves whole rows, never an
 *     interleaving, plus at most one torn last line (Linux checks for SIGKILL between the pages a write
 *     spans, so a line crossing a page boundary can in principle be cut). A short write (full disk) is cut
 *     back off before failing. Rows are not fsync'ed one by one: a power failure can lose the last rows or
 *     tear the last line. Resume removes a torn last line.
 *   - Without `resume`, the file must not exist (MR_ERR_INVALID_ARG; it is never overwritten).
 *   - With `resume`, an existing file's header must match this run line for line (MR_ERR_INVALID_ARG naming the
 *     first differing line; the file is not touched); each complete row must parse, name a sample of this run
 *     once, and carry that sample's source values (MR_ERR_FORMAT naming the line otherwise); a torn last line
 *     is removed (ftruncate back to the last '\n'); then only the missing samples run. A missing or empty file
 *     is started afresh.
 *   - An advisory lock (fcntl F_SETLK) on the file refuses a second process writing the same file at once
 *     (MR_ERR_IO).
 *   - Rows arrive in completion order. When every sample is in the file, the file is rewritten sorted by index
 *     (temporary file + rename, atomic; the header's bytes are kept), unless it is sorted already. So a
 *     finished sweep is the same file, byte for byte except the `seconds` column (and the "# command:" line),
 *     whether or not it was interrupted and resumed, with any thread counts.
 *
 * Determinism: a row's values depend only on the spec and its index (seconds aside): mr_remap is deterministic
 * and each sample is computed on one thread.
 * Threads: mr_sweep_run runs samples in parallel (OpenMP, schedule(dynamic)) sharing one render plan; every
 * render and metric inside a sample runs single-threaded, so `threads` samples run at once. The progress
 * callback is called under a lock, from the thread that wrote the row. Other functions are reentrant.
 * Ownership: the spec is plain data (copies of the value vectors; model descriptors are borrowed statics).
 * Nothing returned needs freeing. The library never prints: the caller draws progress from the callback.
 */
#ifndef MR_SWEEP_H
#define MR_SWEEP_H

#include <stddef.h>

#include "../brdf/brdf.h"
#include "../mr_status.h"
#include "../render/render.h"
#include "remap.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MR_SWEEP_MAX_AXES 16
/* Upper bound on the samples of one sweep (the resume bookkeeping holds one byte per sample). */
#define MR_SWEEP_MAX_SAMPLES 100000000L
/* Enough for any row or header line the library writes (39 numbers at most, each < 26 characters). */
#define MR_SWEEP_MAX_LINE 4096

typedef enum mr_sweep_sampling {
    MR_SWEEP_GRID = 0,
    MR_SWEEP_RANDOM,
    MR_SWEEP_SAMPLING_COUNT
} mr_sweep_sampling;

/* One grid axis: `count` values of source parameter `param` from lo to hi inclusive. */
typedef struct mr_sweep_axis {
    int param;     /* index into the source model's parameter table */
    double lo, hi; /* lo <= hi, both within the parameter's [min, max] */
    long count;    /* >= 1; 1 samples lo only */
    int log_scale; /* 1: geometric spacing (needs lo > 0); 0: linear */
} mr_sweep_axis;

typedef struct mr_sweep_spec {
    const mr_brdf_model *source;
    double source_values[MR_BRDF_MAX_VALUES]; /* packed; every sample starts from these */
    unsigned held;                            /* bit p set: RANDOM leaves source parameter p at its value */
    const mr_brdf_model *target;
    double target_values[MR_BRDF_MAX_VALUES]; /* packed; passed as mr_remap_options.target_values */
    mr_remap_options remap;                   /* strategy, tolerances; its target_values field is ignored */
    mr_fit_scene_options scene;               /* size 0 = MR_REMAP_DEFAULT_SIZE; light; intensity 0 = 10 */
    mr_sweep_sampling sampling;
    mr_sweep_axis axes[MR_SWEEP_MAX_AXES];    /* GRID */
    int axis_count;
    long random_count;                        /* RANDOM: number of samples */
    unsigned long long seed;                  /* RANDOM */
} mr_sweep_spec;

/* Fill *spec for a sweep from `source` to `target`: both models' default values, nothing held,
 * mr_remap_options_default(), the default fit scene, GRID with no axes yet, seed 1. */
void mr_sweep_spec_init(mr_sweep_spec *spec, const mr_brdf_model *source, const mr_brdf_model *target);

/* Parse "name=lo:hi:n" or "name=lo:hi:n:log" for a parameter of `source` into *out. MR_ERR_INVALID_ARG with
 * a message naming the text and what is wrong: syntax, unknown parameter (listing the valid ones), n < 1,
 * lo > hi, a bound outside the parameter's range, log spacing from lo <= 0, a switch given non-integer steps.
 * *out is written only on success. */
mr_status mr_sweep_parse_axis(const mr_brdf_model *source, const char *text, mr_sweep_axis *out);

/* Check a spec completely (what mr_sweep_parse_axis checks, plus value vectors in range, no parameter on two
 * axes, at least one axis or random sample, something to randomise, at most MR_SWEEP_MAX_SAMPLES samples).
 * MR_ERR_INVALID_ARG naming the problem. */
mr_status mr_sweep_check(const mr_sweep_spec *spec);

/* Number of samples of a checked spec (0 if the spec is invalid). */
long mr_sweep_sample_count(const mr_sweep_spec *spec);

/* Packed source values of sample `index` (0 <= index < mr_sweep_sample_count) into values[]
 * (mr_brdf_value_count(spec->source) doubles). MR_ERR_INVALID_ARG for a bad spec or index. */
mr_status mr_sweep_sample(const mr_sweep_spec *spec, long index, double *values);

/* One row of the file. */
typedef struct mr_sweep_row {
    long index;
    double source[MR_BRDF_MAX_VALUES]; /* the sample's packed source values */
    double target[MR_BRDF_MAX_VALUES]; /* the fitted packed target values */
    double rmse, relative_rmse, ssim;  /* as in mr_remap_result */
    mr_fit_outcome outcome;
    long renders;
    double seconds;
} mr_sweep_row;

/* Format `row` as the file's line for `spec` (ending in '\n', NUL-terminated) into buf[size]; *length (may be
 * NULL) receives the line's length without the NUL. MR_ERR_INVALID_ARG if it does not fit (MR_SWEEP_MAX_LINE
 * always does) or a value is out of place (bad outcome). Uses the C numeric locale regardless of the process's. */
mr_status mr_sweep_format_row(const mr_sweep_spec *spec, const mr_sweep_row *row, char *buf, size_t size,
                              size_t *length);

/* Parse one row line (`length` bytes; a trailing '\n' is allowed) of a file made for `spec`: the exact column
 * count, every number complete, a known outcome name, an index within the sweep. MR_ERR_FORMAT naming the
 * offending field otherwise. *out is written only on success. Inverse of mr_sweep_format_row, exactly. */
mr_status mr_sweep_parse_row(const mr_sweep_spec *spec, const char *line, size_t length, mr_sweep_row *out);

/* What the progress callback sees after each row is written. */
typedef struct mr_sweep_progress {
    long done;                /* rows in the file now (earlier runs' included) */
    long total;               /* samples in the sweep */
    long run_done;            /* rows this run has written */
    long run_total;           /* rows this run set out to write */
    const mr_sweep_row *row;  /* the row just written (valid during the call) */
} mr_sweep_progress;

/* Called after each row is written, under the sweep's file lock (so calls never overlap), on the worker
 * thread that wrote it, while that thread uses the C numeric locale. Keep it short: other rows wait. */
typedef void (*mr_sweep_progress_fn)(const mr_sweep_progress *progress, void *user);

/* Zero-initialised = defaults. */
typedef struct mr_sweep_options {
    int resume;                   /* 0: the file must not exist; 1: continue it (see the header comment) */
    int threads;                  /* samples at once; 0 = omp_get_max_threads() */
    const char *command_line;     /* recorded as "# command: ..." (line breaks become spaces); NULL = empty */
    mr_sweep_progress_fn progress; /* optional; called after each row, serialised */
    void *progress_user;
} mr_sweep_options;

typedef struct mr_sweep_summary {
    long total;                              /* samples in the sweep */
    long already_done;                       /* rows found in the file on resume */
    long computed;                           /* rows this run wrote */
    long outcomes[MR_FIT_OUTCOME_COUNT];     /* this run's rows by outcome */
    long truncated_bytes;                    /* size of the torn last line removed on resume (0: none) */
    int sorted;                              /* 1: the finished file was rewritten in index order */
    int threads;                             /* threads used */
    double seconds;                          /* wall time of this call */
} mr_sweep_summary;

/* Run (or continue, opts->resume) the sweep `spec` into the CSV file `path`, as described in the header
 * comment. opts may be NULL. On MR_OK every sample has its row and the file is sorted; *out (may be NULL)
 * gets the summary. On failure the rows written so far stay and a resume continues: a bad spec or file
 * (MR_ERR_INVALID_ARG / MR_ERR_FORMAT / MR_ERR_IO) stops the run at once; a remap that fails does not stop the
 * other samples: the run finishes them, leaves the failed ones out of the file (unsorted, as it is incomplete)
 * and returns the status of the lowest failed sample, the message giving the count and that sample. */
mr_status mr_sweep_run(const mr_sweep_spec *spec, const char *path, const mr_sweep_options *opts,
                       mr_sweep_summary *out);

#ifdef __cplusplus
}
#endif

#endif /* MR_SWEEP_H */
