/*
 * mr_gltf_library.h — many glTF assets converted in one call (what `matremap gltf spec2metal|metal2spec IN... -o DIR`
 * does with folders, globs or several files): each asset through mr_gltf_convert_file (mr_gltf_convert.h) into an
 * output folder mirroring the input tree, side by side within a thread budget, with a progress callback, a cancel
 * flag, resume and shards; the folder gets summary.json and index.html (before/after thumbnails, materials, flags,
 * object SSIM, worst first).
 *
 *   char **assets; int n; char *root;
 *   mr_gltf_library_list(inputs, input_count, &assets, &n, &root);      // files, folders (recursive), globs
 *   mr_gltf_library_options o = {0};  o.convert = convert_options;  o.settings = "spec2metal weighted ...";
 *   mr_gltf_library_result r;
 *   mr_gltf_convert_library(inputs, input_count, "out", &o, &r);  // r.failed > 0: some failed
 *   mr_gltf_library_result_free(&r);  mr_gltf_library_list_free(assets, n, root);
 *
 * Listing: a file is taken as it is; a folder is walked recursively for *.gltf and *.glb (case-insensitive, hidden
 * entries skipped); an input that does not exist but holds * ? or [ is expanded as a shell glob (POSIX glob), each
 * match again a file or a folder. The list is sorted by path (strcmp) with duplicates removed; the common root is
 * the deepest folder holding every asset. An input that matches nothing is MR_ERR_IO naming it; none at all too.
 *
 * Outputs: asset ROOT/a/b.gltf is written to DIR/a/b.gltf (a .glb stays .glb), its side files named after it as
 * mr_gltf_convert_file names them; thumbnails to DIR/thumbnails/a/b.before.png and .after.png; DIR/summary.json
 * and DIR/index.html. DIR is made if missing. Refused before any work (MR_ERR_INVALID_ARG): DIR inside an input
 * folder (or the root), an existing summary.json or index.html that is not an earlier run's own (its first line
 * names this writer). Every file is written atomically (mr_core.h); an asset's conversion never replaces its
 * inputs nor another asset's files (mr_gltf_convert_file's rules), and an asset whose output exists fails unless
 * DIR/summary.json records an earlier run writing that output from that input.
 *
 * Shards: with shard_count N > 1 only the assets at sorted index k with k % N == shard_index are converted (the
 * sweep's rule). Resume: with `resume`, an asset whose entry in an earlier DIR/summary.json has status
 * "converted", the same settings string and the same fingerprint (FNV-1a 64 of the bytes of every file the asset
 * was read from: the .gltf/.glb, its buffers and images) and whose output still exists is not converted again; its
 * earlier entry is kept. Entries of the earlier summary for assets outside this run (another shard) are kept too.
 *
 * The object SSIM: both the input (spec-gloss as an engine supporting the extension shows it) and the output
 * (mr_gltf_scene_load) rendered at thumbnail_size with the camera and light `matremap render ASSET` places
 * (mr_gltf_scene_frame, the fit scene's light), compared over the object's coverage (mr_ssim with the plan's mask).
 * A render that fails leaves the asset converted with SSIM null and the reason in "render_error"; no_renders skips
 * them (the renders decode every texture again, in and out: on 2048² assets they cost about what the conversion
 * does, docs/performance.md).
 *
 * Threads: assets run side by side on a team of mr_auto_threads(threads, assets, 2) threads, never more than the
 * assets to convert (their conversions' own parallel regions then run on one thread each: OpenMP's default of one
 * active level); with one asset the conversion's own threads (the transform's option) do the work. Results do
 * not depend on the team (each asset's conversion is the single-asset one). The progress callback is called after
 * each asset (under a lock, from any thread of the team); the cancel flag is read before each asset starts: the
 * rest are recorded "cancelled" and the call returns MR_ERR_CANCELLED after writing the summary.
 * Jobs: with opts->job each asset is job->run's instead of a conversion (the output named with job->extension),
 * the rest as above (two inputs that would be written to one output, a.gltf and a.glb, refused before any work:
 * MR_ERR_INVALID_ARG naming both); a fingerprint of an asset that is not .gltf/.glb is of its one file. Statuses stay
 * "converted" (the job done), "resumed", "failed", "cancelled".
 * Errors: an asset's failure is recorded (its status "failed", the library's message) and the others go on; the
 * call itself fails only for bad arguments, the refusals above, and writing the summary or the index. Nothing is
 * printed.
 */
#ifndef MR_GLTF_LIBRARY_H
#define MR_GLTF_LIBRARY_H

#include <signal.h>
#include <stddef.h>

#include "gltf/mr_gltf_convert.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Where a run stands, passed to the progress callback after each asset. */
typedef struct mr_gltf_library_progress {
    int done, total;         /* assets finished (converted, resumed, failed or cancelled) and to do */
    int failed;              /* of those, failed */
    const char *asset;       /* the asset just finished (its input path) */
    const char *status;      /* "converted", "resumed", "failed" or "cancelled" */
    const char *error;       /* its message when failed, "" otherwise */
    double asset_seconds;    /* its conversion time */
    double seconds;          /* since the call began */
    size_t texels;           /* texels so far: per asset mr_gltf_convert_totals.texels, or its extension's texels
                                (total.texels) when larger (materials kept but given KHR_materials_specular) */
} mr_gltf_library_progress;

/* What a job (mr_gltf_library_options.job) tells the loop about one asset it did. */
typedef struct mr_gltf_library_job_result {
    int material_count;
    size_t texels;          /* texels the job converted (progress and the result's total) */
    int render_after;       /* 1: the output is a glTF asset, rendered as "after" against the input (thumbnails,
                               object SSIM); 0: no renders for this asset (summary.json: null, "render_error"
                               null) */
    char overview[2048];    /* what index.html shows of its materials */
    char *json;             /* malloc'ed (the loop frees it): JSON members appended to the asset's summary line in
                               place of the conversion's "pruned" and "materials", e.g. "\"materials\": [...]";
                               NULL: "\"materials\": []" */
} mr_gltf_library_job_result;

/* Another per-asset job than the conversion, run with the loop's listing, threads, progress, cancel, resume,
 * shards, summary.json and index.html (e.g. doc/doc.h's mr_doc_export_library: an export per asset). */
typedef struct mr_gltf_library_job {
    /* The job for one asset: write `output` from `input` (never over an input: the job's own checks), with at most
     * `threads` threads (the loop's rule above: 1 when assets run side by side); *out zeroed by the loop. Its
     * failure status and mr_last_error() are recorded as the asset's. Called from any thread of the team. */
    mr_status (*run)(void *user, const char *input, const char *output, int threads, mr_gltf_library_job_result *out);
    void *user;
    const char *extension;  /* the outputs' extension, e.g. ".mtlx" (the input's replaced); NULL: the input's */
} mr_gltf_library_job;

typedef struct mr_gltf_library_options {
    mr_gltf_convert_options convert; /* each asset's conversion (its progress fields and image_prefix are unused) */
    const char *settings;   /* what the conversion was told, recorded for resume ("" when NULL) */
    int threads;            /* assets side by side: 0 automatic (rule above), n >= 1 at most n */
    int serial;             /* 1: one asset at a time, each with `threads` (e.g. jobs sharing a locked file) */
    int resume;             /* 1: skip assets an earlier run converted with the same settings and input */
    int shard_index, shard_count; /* shard_count 0 or 1: every asset */
    int thumbnail_size;     /* square renders for index.html and the SSIM: 0 = 128; 0 < size < 32 refused */
    int no_renders;         /* 1: no thumbnails and no SSIM (null in summary.json; index.html lists the assets) */
    void (*progress)(void *user, const mr_gltf_library_progress *p); /* may be NULL */
    void *progress_user;
    const mr_gltf_library_job *job; /* NULL: each asset converted by mr_gltf_convert_file (`convert`); given:
                                       job->run instead (`convert` unused), its results in the summary */
    const volatile sig_atomic_t *cancel; /* may be NULL; non-zero stops before the next asset (a signal handler
                                            may set it: `matremap gltf` does on SIGINT and SIGTERM) */
} mr_gltf_library_options;

/* One asset of a run. */
typedef struct mr_gltf_library_item {
    char *input, *output;        /* owned */
    char status[16];             /* "converted", "resumed", "failed", "cancelled" */
    char error[512];             /* the reason when failed ("" otherwise) */
    double seconds;
    double ssim;                 /* object SSIM after against before; NaN when not rendered */
    mr_gltf_convert_totals totals;
    int material_count;
} mr_gltf_library_item;

typedef struct mr_gltf_library_result {
    int count;                   /* assets of this run (this shard) */
    int converted, resumed, failed, cancelled;
    mr_gltf_library_item *items; /* [count], in sorted input order; owned */
    double seconds;
    size_t texels;
} mr_gltf_library_result;

/* Expand inputs (files, folders, globs) into the sorted list of assets (*assets, *count; owned, as each string)
 * and their common root folder (*root, owned). MR_ERR_IO for an input that matches nothing. */
mr_status mr_gltf_library_list(const char *const *inputs, int input_count, char ***assets, int *count, char **root);
void mr_gltf_library_list_free(char **assets, int count, char *root);

/* Convert the assets inputs[input_count] list (mr_gltf_library_list: files, folders, globs) into out_dir, each
 * mirroring its path below their common root. *result (may be NULL) is filled whenever the run started (also on
 * MR_ERR_CANCELLED or a summary write failure), zeroed otherwise. */
mr_status mr_gltf_convert_library(const char *const *inputs, int input_count, const char *out_dir,
                                  const mr_gltf_library_options *opts, mr_gltf_library_result *result);

/* NULL-safe; leaves *result zeroed. */
void mr_gltf_library_result_free(mr_gltf_library_result *result);

#ifdef __cplusplus
}
#endif

#endif /* MR_GLTF_LIBRARY_H */
