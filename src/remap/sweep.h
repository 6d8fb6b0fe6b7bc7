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
 *   mr_sweep_command_line("matremap", argc, argv, &line);  o.command_line = line;     // the header's record
 *   mr_sweep_summary s;
 *   mr_sweep_run(&spec, "alpha.csv", &o, &s);
 *
 * Samples. Sample i (0 <= i < mr_sweep_sample_count()) is a full packed source value vector:
 *   - GRID: the Cartesian product of the axes, first axis slowest (the index is a mixed-radix number whose last
 *     digit is the last axis). An axis spaces `count` values from lo to hi inclusive, linearly or (log_scale)
 *     geometrically; an RGB parameter gets the value in all three channels. Axes override source_values.
 *   - RANDOM: every source parameter that is not a switch, not MR_PARAM_FIT_FIXED, not held (bit p of `held`)
 *     and has a non-empty range is drawn uniformly from [min, max], log-uniformly if the descriptor flags
 *     MR_PARAM_LOG_SCALE (and min > 0). In the TEXTURE region (the default) an RGB parameter is drawn grey, one
 *     number for its three channels, and a draw where the source rescales its reflectances (Ward's or Phong's
 *     energy trimming: mr_brdf_model.rescales) is drawn again from the same stream, so the samples are uniform
 *     over the part of the ranges where the source is linear: where texture maps' texels lie, and what a learned
 *     transform's per-channel form assumes. (At most MR_SWEEP_MAX_DRAWS draws; should every one rescale, the
 *     drawn reflectances are set to their minimum, which mr_sweep_spec_check has made sure does not.) In the
 *     RANGE region each channel is drawn independently and every draw is kept. The draws come from a
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
 *   # sampling: grid alpha=... | random=N seed=S region=R over p,q,...
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
 * Shards (mr_sweep_options.shard_index/shard_count, the CLI's --shard K/N for job arrays): shard K of N holds
 * exactly the samples whose index % N == K, in a file of its own whose header carries "# shard: K/N" after
 * "# samples:"; it is resumed and finished (sorted) like a whole sweep. mr_sweep_merge() checks that a set of
 * shard files is one complete sweep and writes the file a single run would have written.
 *
 * Several processes (mr_sweep_options.comm; the CLI's `mpirun -np N matremap sweep`, through mr_sweep_mpi_start):
 * rank 0 alone opens, locks, checks, appends to and sorts the file, exactly as above; the samples still missing
 * (in index order) are dealt out round-robin, the k-th to rank k % N; every rank computes its share with its own
 * threads and sends each row to rank 0 as its text line, which rank 0 checks (a row of this sweep, not yet in the
 * file) and appends in one write() like its own. So the file is the same, byte for byte apart from the seconds
 * column and the command line, for any number of ranks and threads, and a run killed at any moment (any rank:
 * mpirun then ends them all) resumes like a single process, with any number of ranks.
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
/* RANDOM in the TEXTURE region: draws per sample before giving up on a linear one (Ward's grey diffuse in [0, 1]
 * and specular in [0, 10] are linear in 1 draw of 20). */
#define MR_SWEEP_MAX_DRAWS 100000

typedef enum mr_sweep_sampling {
    MR_SWEEP_GRID = 0,
    MR_SWEEP_RANDOM,
    MR_SWEEP_SAMPLING_COUNT
} mr_sweep_sampling;

/* Where RANDOM draws (the header's "region=" word; a header without one is RANGE, the only region of files
 * written before regions existed). */
typedef enum mr_sweep_region {
    MR_SWEEP_REGION_TEXTURE = 0, /* the values texture maps hold: an RGB parameter grey (one draw for its three
                                    channels, which learn then applies per channel), and only values where the
                                    source is linear in its reflectances (mr_brdf_model.rescales false: Ward with
                                    diffuse + specular <= 1), drawn again until they are */
    MR_SWEEP_REGION_RANGE,       /* every parameter over its whole range, each channel independently */
    MR_SWEEP_REGION_COUNT
} mr_sweep_region;

/* "texture", "range"; NULL outside the enum. */
const char *mr_sweep_region_name(mr_sweep_region region);
/* MR_ERR_INVALID_ARG naming the valid names for an unknown one. */
mr_status mr_sweep_region_from_name(const char *name, mr_sweep_region *out);

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
    mr_sweep_region region;                   /* RANDOM: default TEXTURE */
    mr_remap_renderers renderers;             /* who renders the sources and the targets' fits (zeroed: the
                                                 built-in renderer both sides); each worker thread of a run gets
                                                 its own process of an external one (renderer.h) */
} mr_sweep_spec;

/* The fit scene of a sweep file's "# scene:" line (its text after "# scene: ", e.g. "fit size=64 light=45
 * intensity=10 ..."): size, light and intensity into *out (zeroed first). MR_ERR_FORMAT naming what is not a scene
 * setting this version knows. */
mr_status mr_sweep_scene_parse(const char *text, mr_fit_scene_options *out);

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

/* The largest message a sweep's processes exchange (mr_sweep_comm): a row line, or a failure with its text. */
#define MR_SWEEP_MESSAGE_MAX (MR_SWEEP_MAX_LINE + 1024)

/* How the processes of one sweep talk (one rank per process; see the header comment). The library calls these
 * from one thread at a time (the calling thread, or a worker thread under the sweep's lock), so an MPI
 * implementation needs MPI_THREAD_SERIALIZED. Each call returns MR_OK or a failure status (after mr_fail()ing a
 * message where the implementation can); a failure ends the run on that rank with the status. */
typedef struct mr_sweep_comm {
    int rank; /* this process, 0 .. size - 1; rank 0 owns the file */
    int size; /* processes in the run, >= 1 (1: the same as no comm) */
    void *user;
    /* Collective: every rank calls it at the same point of the run with the same `bytes`; on return every
     * rank's buf[0, bytes) holds rank 0's. */
    mr_status (*broadcast)(void *user, void *buf, size_t bytes);
    /* Queue `bytes` (<= MR_SWEEP_MESSAGE_MAX) bytes with `tag` for rank `to`; returns without waiting for the
     * receiver (the bytes are copied). Messages from one rank to another arrive in the order they were sent. */
    mr_status (*send)(void *user, int to, int tag, const void *buf, size_t bytes);
    /* The next message for this rank, from any rank, into buf[MR_SWEEP_MESSAGE_MAX]: *from, *tag, *bytes.
     * `wait` 0: *got = 0 at once when none has arrived; `wait` 1: returns with *got = 1 (without burning a core
     * while it waits, ideally). */
    mr_status (*receive)(void *user, int wait, int *from, int *tag, void *buf, size_t *bytes, int *got);
    /* Wait until every message this rank sent has been delivered. */
    mr_status (*flush)(void *user);
} mr_sweep_comm;

/* The automatic thread rule's threshold (mr_sweep_options.threads = 0): each sample runs on one thread, so a
 * second thread gains from two samples on. */
#define MR_SWEEP_PARALLEL_SAMPLES 2

/* Zero-initialised = defaults. */
typedef struct mr_sweep_options {
    int resume;                   /* 0: the file must not exist; 1: continue it (see the header comment) */
    int threads;                  /* samples at once (in this process); 0 = automatic (mr_auto_threads: a team of
                                     omp_get_max_threads() for MR_SWEEP_PARALLEL_SAMPLES samples or more) */
    const char *command_line;     /* recorded as "# command: ..." (line breaks become spaces); NULL = empty */
    mr_sweep_progress_fn progress; /* optional; called after each row, serialised (rank 0: every rank's rows) */
    void *progress_user;
    long shard_index, shard_count; /* this file is shard K = shard_index of N = shard_count (0 <= K < N); N = 0:
                                      the whole sweep (see the header comment) */
    const mr_sweep_comm *comm;     /* NULL: this process alone; else the ranks of the run (every rank calls
                                      mr_sweep_run with the same spec, path, resume and shard) */
} mr_sweep_options;

typedef struct mr_sweep_summary {
    long total;                              /* samples in the sweep */
    long file_total;                         /* samples this file holds: total, or the shard's share */
    long already_done;                       /* rows found in the file on resume */
    long computed;                           /* rows this run wrote */
    long outcomes[MR_FIT_OUTCOME_COUNT];     /* this run's rows by outcome */
    long truncated_bytes;                    /* size of the torn last line removed on resume (0: none) */
    int sorted;                              /* 1: the finished file was rewritten in index order */
    int threads;                             /* threads used (by this process) */
    int processes;                           /* ranks that computed (1 without a comm) */
    long threads_total;                      /* threads used by all ranks together */
    double seconds;                          /* wall time of this call */
    long renderer_renders;                   /* renders by external renderers (spec->renderers), this process */
    long renderer_starts;                    /* their processes started, restarts after a crash included */
} mr_sweep_summary;

/* Check a parsed row against `spec`: every value finite (relative_rmse may be +inf: a black source), source
 * and target values inside their parameters' [min, max] (switches integers), rmse >= 0, ssim in [-1, 1],
 * seconds >= 0. MR_ERR_FORMAT naming the column by number and name and the value otherwise ("column 9
 * (to_diffuse_r): -0.5 is outside diffuse's range [0, 1] of model 'ward-balanced'"). Resume and merge check
 * every row of a file this way (mr_sweep_parse_row alone checks only the syntax). */
mr_status mr_sweep_check_row(const mr_sweep_spec *spec, const mr_sweep_row *row);

/* Run (or continue, opts->resume) the sweep `spec` into the CSV file `path`, as described in the header
 * comment. opts may be NULL. On MR_OK every sample (of the shard) has its row and the file is sorted; *out (may
 * be NULL) gets the summary (on every rank; rank 0's counts cover all ranks). On failure the rows written so far
 * stay and a resume continues: a bad spec or file (MR_ERR_INVALID_ARG / MR_ERR_FORMAT / MR_ERR_IO) stops the
 * run at once; a remap that fails does not stop the other samples: the run finishes them, leaves the failed
 * ones out of the file (unsorted, as it is incomplete) and returns the status of the lowest failed sample, the
 * message giving the count and that sample. With a comm, every rank returns rank 0's status; the message is
 * rank 0's (the others say that rank 0 reports it), and a rank whose spec or version differs from rank 0's
 * makes rank 0 refuse the run (MR_ERR_INVALID_ARG naming the rank) before the file is opened. */
mr_status mr_sweep_run(const mr_sweep_spec *spec, const char *path, const mr_sweep_options *opts,
                       mr_sweep_summary *out);

/* What mr_sweep_merge found. */
typedef struct mr_sweep_merge_summary {
    long total;  /* samples in the sweep (rows written) */
    long shards; /* shard files merged (N) */
} mr_sweep_merge_summary;

/* Merge the shard files paths[0 .. count) (in any order) into `output`, the file a single run of the sweep
 * would have written: its header (with "# command: " + command_line, NULL = empty, and no shard line), then
 * every row in index order, byte for byte as in the shards. Written atomically (a temporary file renamed into
 * place); `output` must not exist yet, nor be one of the shards. Each shard's header must be one this version
 * writes (it is parsed back into the sweep and rebuilt, byte for byte), and the shards must belong together:
 * the same sweep (models, values, remap options, scene, sampling, seed, sample count: every header line but
 * "# shard:" and "# command:"), the same N, each K in 0 .. N-1 exactly once, each shard complete (every one of
 * its samples once, in order: a finished shard is sorted), every row checked as on resume (mr_sweep_parse_row,
 * mr_sweep_check_row, the sample's source values), no torn last line, and no shard still being written (its
 * lock is held). MR_ERR_INVALID_ARG (shards that do not fit together, an existing output) or MR_ERR_FORMAT (a
 * bad file, naming it and the line) with a message naming the file(s) and what disagrees; MR_ERR_IO for
 * unreadable files or a failed write. Nothing is written on failure. */
mr_status mr_sweep_merge(const char *const *paths, int count, const char *output, const char *command_line,
                         mr_sweep_merge_summary *out);

/* The command line a sweep file records (mr_sweep_options.command_line, mr_sweep_merge's): `prefix` ("matremap",
 * "matremap sweep") then each of argv[0 .. argc), a space before each, quoted for a POSIX shell where needed: an
 * argument made only of letters, digits and _./:=,+-@% is written as it is, any other (the empty one too) inside
 * single quotes, a quote in it as '\'' ("a b" -> 'a b', "it's" -> 'it'\''s'), so that pasting the line into a shell
 * runs the same command. *out is malloc'ed (the caller frees it). MR_ERR_INVALID_ARG for a NULL argument or a
 * negative argc; MR_ERR_NOMEM. */
mr_status mr_sweep_command_line(const char *prefix, int argc, const char *const *argv, char **out);

/* ---- running under MPI (sweep_mpi.c) ----
 * The library itself never links MPI: a small module, libmatremap-mpi.so (src/remap/sweep_mpi_module.c, built
 * only where Open MPI's development files are installed), holds every MPI call, and is loaded on demand, like
 * the OpenImageIO module: from the file named by $MR_MPI_MODULE, else <executable's directory>/../lib/matremap/,
 * else the install directory MR_MODULE_DIR. */

/* 1 if the environment says this process was started by an MPI launcher as one of several processes, with
 * *size and *rank (either may be NULL) from the launcher's variables and *variable (may be NULL) naming the
 * one read: OMPI_COMM_WORLD_SIZE/_RANK (Open MPI's mpirun), PMI_SIZE/PMI_RANK (MPICH's Hydra, Slurm's
 * srun --mpi=pmi2). 0 otherwise, and for a launch of a single process (size 1). */
int mr_sweep_mpi_launched(int *size, int *rank, const char **variable);

/* Load the module, start MPI (MPI_Init_thread, MPI_THREAD_SERIALIZED) and fill *comm with MPI_COMM_WORLD's
 * rank and size; *local_size (may be NULL) gets the number of ranks on this machine (MPI_COMM_TYPE_SHARED).
 * MR_ERR_UNSUPPORTED if the module cannot be loaded (the message says where it looked and why), MR_ERR_EXTERNAL
 * if MPI does not start. Call once per process; end with mr_sweep_mpi_finish. A communication failure later
 * ends the whole job (MPI's default error handler), as the death of a rank does. */
mr_status mr_sweep_mpi_start(mr_sweep_comm *comm, int *local_size);

/* The threads each rank of a run uses unless told (mr_sweep_options.threads for a rank), when `local_size` ranks
 * (mr_sweep_mpi_start) share this machine: the cores this process may use divided among them, at least 1, so
 * that N ranks on one machine do not each start a team of every core; 0 (the automatic rule, which reads it) when
 * OMP_NUM_THREADS is set, which says the count for every rank. */
int mr_sweep_rank_threads(int local_size);

/* Wait for this rank's messages to be delivered and end MPI (MPI_Finalize). */
mr_status mr_sweep_mpi_finish(mr_sweep_comm *comm);

#ifdef __cplusplus
}
#endif

#endif /* MR_SWEEP_H */
