/*
 * cmd_sweep.c — `matremap sweep`: remap a grid or a seeded random sample of source materials into a target
 * model and stream one CSV row per remap into a crash-safe, resumable file (sweep.h has the file format and
 * the guarantees; docs/sweep.md the walk-through).
 */
#include <errno.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "cli.h"
#include "remap/sweep.h"

#define MAX_ASSIGNMENTS 64

static void print_help(void) {
    printf("Usage: matremap sweep --from MODEL [name=value ...] --to MODEL [name=value ...]\n"
           "                      (--grid name=lo:hi:n[:log] ... | --random N [--seed S]) -o DATA.csv [options]\n"
           "\n"
           "Remaps many source materials into the target model, one 'matremap remap' per sample, and writes one\n"
           "CSV row per sample: the sample's index, its source values, the fitted target values (columns 'to_*'),\n"
           "rmse, relative_rmse, ssim, outcome, renders and seconds. Samples run in parallel, one per thread.\n"
           "\n"
           "Samples:\n"
           "  --grid name=lo:hi:n[:log]   an axis of n values of source parameter 'name' from lo to hi inclusive,\n"
           "                              evenly spaced, or geometrically with ':log' (lo > 0); an RGB parameter\n"
           "                              gets the value on all three channels. Repeat --grid (or list further\n"
           "                              axes after it) for a Cartesian product, first axis slowest: sample\n"
           "                              index = ((i1 * n2) + i2) * n3 + i3 ...\n"
           "  --random N                  N samples, each continuous source parameter drawn uniformly from its\n"
           "                              range (log-uniformly for roughness-like parameters flagged log-scale),\n"
           "                              RGB channels independently; parameters given after --from, switches and\n"
           "                              fixed extension factors are held\n"
           "  --seed S                    seed of --random (default 1); sample i depends only on (S, i)\n"
           "Values given after --from hold for every sample; a grid axis overrides them. Values given after --to\n"
           "hold the target's fixed parameters and switches (e.g. Ward's trim), as in 'matremap remap';\n"
           "--hold NAME[,NAME] holds target parameters at those values instead of fitting them.\n"
           "\n"
           "Options:\n"
           "  -o, --output FILE     the CSV file (required); it must not exist unless --resume is given\n"
           "  --resume              continue FILE: its header must match this run exactly (models, values,\n"
           "                        sampling, strategy, scene), a torn last line is removed, and only the\n"
           "                        missing samples run; a missing FILE is started afresh\n"
           "  --strategy S          auto (default), joint, single, two or three (see 'matremap remap --help')\n"
           "  --size N              fit-scene side in pixels (default %d)\n"
           "  --light L             45 (default) or frontal\n"
           "  --threads T           samples at once (default: all cores); each sample runs single-threaded\n"
           "  --help                this text\n"
           "\n"
           "The file starts with '# ' lines describing the run (tool version, models and values, remap options,\n"
           "scene, sampling, sample count, command line), then the column names. Rows are appended as samples\n"
           "finish, each in one write, so killing the run (Ctrl-C, kill -9) loses only the samples in flight;\n"
           "--resume picks up from there. When the last sample is in, the file is rewritten sorted by index, so a\n"
           "finished file is the same whether or not it was interrupted, and for any --threads (the seconds\n"
           "column aside). A progress bar is drawn when stderr is a terminal; a summary line ends every run.\n"
           "\n"
           "Exit codes: 0 done, 1 usage error, 2 bad input (unknown model or parameter, bad grid, a FILE that\n"
           "exists without --resume or belongs to another sweep), 3 internal failure.\n"
           "\n"
           "Examples:\n"
           "  matremap sweep --from ggx diffuse=0 --to ward-balanced --grid alpha=0.01:1:25:log -o alpha.csv\n"
           "  matremap sweep --from ggx --to ward-balanced --grid alpha=0.02:0.5:8:log f0=0.02:1:5 -o ggx_ward.csv\n"
           "  matremap sweep --from gltf --to blender-ward --random 1000 --seed 7 --threads 2 -o gltf.csv\n"
           "  matremap sweep --from gltf --to blender-ward --random 1000 --seed 7 --threads 2 -o gltf.csv --resume\n",
           MR_REMAP_DEFAULT_SIZE);
}

/* "matremap sweep ARGS..." with shell quoting where needed, for the file's "# command:" line. */
static char *command_line(int argc, char **argv) {
    size_t size = strlen("matremap") + 1;
    for (int i = 0; i < argc; i++) size += 4 * strlen(argv[i]) + 3;
    char *text = malloc(size), *out = text;
    if (text == NULL) return NULL;
    out += sprintf(out, "matremap");
    for (int i = 0; i < argc; i++) {
        const char *a = argv[i];
        *out++ = ' ';
        int plain = a[0] != '\0';
        for (const char *c = a; *c && plain; c++)
            plain = strchr("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_./:=,+-@%", *c) != NULL;
        if (plain) {
            out += sprintf(out, "%s", a);
            continue;
        }
        *out++ = '\'';
        for (const char *c = a; *c; c++) {
            if (*c == '\'') {
                memcpy(out, "'\\''", 4);
                out += 4;
            } else {
                *out++ = *c;
            }
        }
        *out++ = '\'';
    }
    *out = '\0';
    return text;
}

/* The progress bar: only when stderr is a terminal, at most ten redraws a second. */
typedef struct progress_bar {
    double start, last_draw;
    int drawn;
} progress_bar;

static void draw_progress(const mr_sweep_progress *p, void *user) {
    progress_bar *bar = user;
    double now = cli_now();
    int last = p->run_done == p->run_total;
    if (!last && now - bar->last_draw < 0.1) return;
    bar->last_draw = now;
    double elapsed = now - bar->start;
    double rate = elapsed > 0.0 ? (double)p->run_done / elapsed : 0.0;
    const int width = 30;
    int filled = p->total > 0 ? (int)((double)width * (double)p->done / (double)p->total) : width;
    char bar_text[64];
    for (int k = 0; k < width; k++) bar_text[k] = k < filled ? '#' : '.';
    bar_text[width] = '\0';
    fprintf(stderr, "\r[%s] %ld/%ld  %.2f rows/s", bar_text, p->done, p->total, rate);
    if (rate > 0.0 && !last) {
        long eta = (long)((double)(p->run_total - p->run_done) / rate + 0.5);
        fprintf(stderr, "  ETA %ld:%02ld:%02ld ", eta / 3600, eta / 60 % 60, eta % 60);
    } else {
        fprintf(stderr, "                ");
    }
    if (last) fprintf(stderr, "\n");
    fflush(stderr);
    bar->drawn = 1;
}

/* Ctrl-C while the bar is drawn: end its line and say how to go on, then die of the signal as usual. The file
 * needs nothing: every finished row is already in it whole (sweep.h). Only async-signal-safe calls here. */
static void on_interrupt(int sig) {
    static const char message[] = "\nmatremap sweep: interrupted; every finished row is in the file: run the same "
                                  "command with --resume to continue\n";
    ssize_t written = write(STDERR_FILENO, message, sizeof message - 1);
    (void)written;
    signal(sig, SIG_DFL);
    raise(sig);
}

static int parse_seed(const char *text, unsigned long long *out) {
    char *end = NULL;
    errno = 0;
    unsigned long long v = strtoull(text, &end, 10);
    if (text[0] < '0' || text[0] > '9' || *end != '\0' || errno == ERANGE) {
        cli_usage_error("sweep", "--seed '%s': expected a non-negative integer", text);
        return 0;
    }
    *out = v;
    return 1;
}

int cmd_sweep(int argc, char **argv) {
    const char *from_name = NULL, *to_name = NULL, *output = NULL, *hold_list = NULL;
    const char *from_assignments[MAX_ASSIGNMENTS], *to_assignments[MAX_ASSIGNMENTS];
    const char *grid_axes[MR_SWEEP_MAX_AXES];
    int from_count = 0, to_count = 0, axis_count = 0, random_count = 0, seed_given = 0, resume = 0, threads = 0;
    unsigned long long seed = 1;
    mr_fit_scene_options scene = {0};
    mr_remap_strategy strategy = MR_REMAP_AUTO;
    enum { NONE, FROM, TO } collecting = NONE;

    for (int i = 1; i < argc; i++) {
        const char *value = NULL;
        int taken;
        if (cli_is_help(argv[i])) {
            print_help();
            return CLI_EXIT_OK;
        }
        if ((taken = cli_take_option("sweep", argc, argv, &i, "--from", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            from_name = value;
            collecting = FROM;
        } else if ((taken = cli_take_option("sweep", argc, argv, &i, "--to", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            to_name = value;
            collecting = TO;
        } else if ((taken = cli_take_option("sweep", argc, argv, &i, "--grid", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            if (axis_count == MR_SWEEP_MAX_AXES)
                return cli_usage_error("sweep", "more than %d grid axes", MR_SWEEP_MAX_AXES);
            grid_axes[axis_count++] = value;
        } else if ((taken = cli_take_option("sweep", argc, argv, &i, "--random", &value))) {
            if (taken < 0 || !cli_parse_int("sweep", "--random", value, 1, (int)MR_SWEEP_MAX_SAMPLES, &random_count))
                return CLI_EXIT_USAGE;
        } else if ((taken = cli_take_option("sweep", argc, argv, &i, "--hold", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            hold_list = value;
        } else if ((taken = cli_take_option("sweep", argc, argv, &i, "--seed", &value))) {
            if (taken < 0 || !parse_seed(value, &seed)) return CLI_EXIT_USAGE;
            seed_given = 1;
        } else if ((taken = cli_take_option("sweep", argc, argv, &i, "--output", &value)) ||
                   (taken = cli_take_option("sweep", argc, argv, &i, "-o", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            output = value;
        } else if (strcmp(argv[i], "--resume") == 0) {
            resume = 1;
        } else if ((taken = cli_take_option("sweep", argc, argv, &i, "--strategy", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            if (mr_remap_strategy_from_name(value, &strategy) != MR_OK)
                return cli_usage_error("sweep", "%s", mr_last_error());
        } else if ((taken = cli_take_option("sweep", argc, argv, &i, "--size", &value))) {
            if (taken < 0 || !cli_parse_int("sweep", "--size", value, 16, 4096, &scene.size)) return CLI_EXIT_USAGE;
        } else if ((taken = cli_take_option("sweep", argc, argv, &i, "--light", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            if (mr_fit_light_from_name(value, &scene.light) != MR_OK)
                return cli_usage_error("sweep", "%s", mr_last_error());
        } else if ((taken = cli_take_option("sweep", argc, argv, &i, "--threads", &value))) {
            if (taken < 0 || !cli_parse_int("sweep", "--threads", value, 1, 1024, &threads)) return CLI_EXIT_USAGE;
        } else if (argv[i][0] == '-') {
            return cli_usage_error("sweep", "unknown option '%s'", argv[i]);
        } else if (strchr(argv[i], '=') != NULL && strchr(argv[i], ':') != NULL && axis_count > 0) {
            // Further axes may follow --grid directly ("--grid a=0:1:3 b=0:1:3"); values never contain ':'.
            if (axis_count == MR_SWEEP_MAX_AXES)
                return cli_usage_error("sweep", "more than %d grid axes", MR_SWEEP_MAX_AXES);
            grid_axes[axis_count++] = argv[i];
        } else if (strchr(argv[i], '=') != NULL && collecting != NONE) {
            int *count = collecting == FROM ? &from_count : &to_count;
            if (*count == MAX_ASSIGNMENTS) return cli_usage_error("sweep", "too many parameter assignments");
            (collecting == FROM ? from_assignments : to_assignments)[(*count)++] = argv[i];
        } else {
            return cli_usage_error("sweep", "unexpected argument '%s' (parameters follow --from MODEL or --to MODEL "
                                   "as name=value; grid axes follow --grid as name=lo:hi:n)", argv[i]);
        }
    }
    if (from_name == NULL) return cli_usage_error("sweep", "missing --from MODEL");
    if (to_name == NULL) return cli_usage_error("sweep", "missing --to MODEL");
    if (axis_count > 0 && random_count > 0)
        return cli_usage_error("sweep", "give either --grid or --random, not both");
    if (axis_count == 0 && random_count == 0)
        return cli_usage_error("sweep", "missing the samples: --grid name=lo:hi:n[:log] or --random N");
    if (seed_given && random_count == 0) return cli_usage_error("sweep", "--seed goes with --random");
    if (output == NULL) return cli_usage_error("sweep", "missing -o DATA.csv");

    const mr_brdf_model *from = mr_brdf_find(from_name), *to = NULL;
    if (from == NULL) return cli_fail("sweep", MR_ERR_INVALID_ARG);
    to = mr_brdf_find(to_name);
    if (to == NULL) return cli_fail("sweep", MR_ERR_INVALID_ARG);
    mr_sweep_spec spec;
    mr_sweep_spec_init(&spec, from, to);
    for (int k = 0; k < from_count; k++) {
        mr_status status = mr_brdf_parse_assignment(from, from_assignments[k], spec.source_values);
        if (status != MR_OK) return cli_fail("sweep", status);
        const char *equals = strchr(from_assignments[k], '=');
        for (int p = 0; p < from->param_count; p++)
            if (strlen(from->params[p].name) == (size_t)(equals - from_assignments[k]) &&
                strncmp(from->params[p].name, from_assignments[k], (size_t)(equals - from_assignments[k])) == 0)
                spec.held |= 1u << p;
    }
    for (int k = 0; k < to_count; k++) {
        mr_status status = mr_brdf_parse_assignment(to, to_assignments[k], spec.target_values);
        if (status != MR_OK) return cli_fail("sweep", status);
    }
    spec.remap.strategy = strategy;
    if (hold_list != NULL && !cli_parse_held("sweep", to, hold_list, &spec.remap.held)) return CLI_EXIT_USAGE;
    spec.scene = scene;
    if (random_count > 0) {
        spec.sampling = MR_SWEEP_RANDOM;
        spec.random_count = random_count;
        spec.seed = seed;
    } else {
        spec.sampling = MR_SWEEP_GRID;
        for (int k = 0; k < axis_count; k++) {
            mr_status status = mr_sweep_parse_axis(from, grid_axes[k], &spec.axes[k]);
            if (status != MR_OK) return cli_fail("sweep", status);
        }
        spec.axis_count = axis_count;
    }
    mr_status status = mr_sweep_check(&spec);
    if (status != MR_OK) return cli_fail("sweep", status);

    // The library refuses an existing file too (race-free, O_EXCL); this check only words it for the CLI.
    struct stat st;
    if (!resume && stat(output, &st) == 0) {
        fprintf(stderr, "matremap sweep: error: '%s' already exists: use --resume to continue it, or remove it\n",
                output);
        return CLI_EXIT_BAD_INPUT;
    }

    char *command = command_line(argc, argv);
    if (command == NULL) { // the file's header records it: no sweep without it
        fprintf(stderr, "matremap sweep: error: out of memory for the command line\n");
        return CLI_EXIT_INTERNAL;
    }
    progress_bar bar = {cli_now(), 0.0, 0};
    mr_sweep_options opts = {0};
    opts.resume = resume;
    opts.threads = threads;
    opts.command_line = command;
    if (isatty(STDERR_FILENO)) {
        opts.progress = draw_progress;
        opts.progress_user = &bar;
        signal(SIGINT, on_interrupt);
        signal(SIGTERM, on_interrupt);
    }
    mr_sweep_summary summary;
    status = mr_sweep_run(&spec, output, &opts, &summary);
    free(command);
    if (bar.drawn && status != MR_OK) fprintf(stderr, "\n");
    if (status != MR_OK) return cli_fail("sweep", status);

    if (summary.truncated_bytes > 0)
        fprintf(stderr, "matremap sweep: removed a torn last line (%ld bytes) from '%s'\n", summary.truncated_bytes,
                output);
    if (summary.computed == 0) {
        fprintf(stderr, "matremap sweep: '%s' is complete: all %ld samples were already there; nothing to do\n",
                output, summary.total);
        return CLI_EXIT_OK;
    }
    fprintf(stderr, "matremap sweep: '%s' is complete: %ld samples; %ld computed in %.1f s (%.2f rows/s, %d threads)",
            output, summary.total, summary.computed, summary.seconds, (double)summary.computed / summary.seconds,
            summary.threads);
    if (summary.already_done > 0) fprintf(stderr, ", %ld were already there", summary.already_done);
    fprintf(stderr, "; outcomes:");
    int first = 1;
    for (int o = 0; o < MR_FIT_OUTCOME_COUNT; o++)
        if (summary.outcomes[o] > 0) {
            fprintf(stderr, "%s %s %ld", first ? "" : ",", mr_fit_outcome_name((mr_fit_outcome)o), summary.outcomes[o]);
            first = 0;
        }
    fprintf(stderr, "\n");
    return CLI_EXIT_OK;
}
