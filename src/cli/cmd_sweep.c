/*
 * cmd_sweep.c — `matremap sweep`: remap a grid or a seeded random sample of source materials into a target
 * model and stream one CSV row per remap into a crash-safe, resumable file (sweep.h has the file format and
 * the guarantees; docs/sweep.md the walk-through).
 */
#include <errno.h>
#include <fcntl.h>
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
           "                              range (log-uniformly for roughness-like parameters flagged log-scale);\n"
           "                              parameters given after --from, switches and fixed extension factors are\n"
           "                              held\n"
           "  --region R                  where --random draws: texture (default): the values texture maps hold,\n"
           "                              RGB parameters grey (learn applies them per channel) and only where the\n"
           "                              source is linear in its reflectances (Ward, Phong: diffuse + specular\n"
           "                              <= 1, no energy trimming); range: every parameter over its whole range,\n"
           "                              RGB channels independently\n"
           "  --seed S                    seed of --random (default 1); sample i depends only on (S, i)\n"
           "Values given after --from hold for every sample; a grid axis overrides them. Values given after --to\n"
           "hold the target's fixed parameters and switches (e.g. Ward's trim), as in 'matremap remap';\n"
           "--hold NAME[=VALUE][,...] holds target parameters at VALUE (or those values) instead of fitting them; the\n"
           "target model's default holds are held too, and the summary's 'held:' line lists them all (the header's\n"
           "'# to:' and 'held=' record them, which learn reads).\n"
           "--tie TARGET=SOURCE[,...]|none holds target parameters at each sample's source value instead of fitting\n"
           "them; by default what the source states: a metalness (gltf -> openpbr: base_metalness=metallic), which\n"
           "the fit scene cannot tell from the base colour at high roughness, and the IOR, coat and specular tint\n"
           "the target holds (docs/remap.md, \"Ties\"); 'tied:' says which, the header's 'tied='\n"
           "records them, and learn carries them as they are (docs/remap.md, \"Ties\").\n"
           "\n");
    printf("Options:\n"
           "  -o, --output FILE     the CSV file (required); it must not exist unless --resume is given\n"
           "  --resume              continue FILE: its header must match this run exactly (models, values,\n"
           "                        sampling, strategy, scene), a torn last line is removed, and only the\n"
           "                        missing samples run; a missing FILE is started afresh\n"
           "  --strategy S          auto (default), joint, single, two or three (see 'matremap remap --help')\n"
           "  --local M             the fits' local stage: auto (default), gradient or bobyqa (see 'matremap\n"
           "                        remap --help')\n"
           "  --size N              fit-scene side in pixels (default %d)\n"
           "  --light L             45 (default) or frontal\n"
           "  --threads T           samples at once in this process (default 0: automatic, all cores; under\n"
           "                        mpirun, the cores this rank may use divided by the ranks on its machine, at\n"
           "                        least 1, so that N ranks on one machine share its cores; OMP_NUM_THREADS=T\n"
           "                        sets T for every rank); each sample runs single-threaded\n"
           "  --shard K/N           compute only shard K of N (0 <= K < N): the samples whose index %% N == K,\n"
           "                        into a file of its own (one per job of a job array; it resumes like any\n"
           "                        sweep); 'matremap sweep merge' joins the N files into the sweep's file\n"
           "  --json                the run's summary as one JSON object on stdout (instead of the summary line):\n"
           "                        output, samples, computed, already_done, seconds, threads, outcomes\n"
           "  --help                this text\n"
           "\n",
           MR_REMAP_DEFAULT_SIZE);
    cli_renderers_help(stdout);
    printf("                        (each worker thread gets its own renderer process; a process that dies is\n"
           "                        restarted and its sample rendered again: nothing is lost)\n"
           "\n"
           "The file starts with '# ' lines describing the run (tool version, models and values, remap options,\n"
           "scene, sampling, sample count, command line), then the column names. Rows are appended as samples\n"
           "finish, each in one write, so killing the run (Ctrl-C, kill -9) loses only the samples in flight;\n"
           "--resume picks up from there. When the last sample is in, the file is rewritten sorted by index, so a\n"
           "finished file is the same whether or not it was interrupted, and for any --threads (the seconds\n"
           "column aside). A progress bar is drawn when stderr is a terminal; a summary line ends every run.\n"
           "\n");
    printf("Several processes: 'mpirun -np N matremap sweep ...' (Open MPI; as root add --allow-run-as-root, and\n"
           "--oversubscribe for more ranks than cores) splits the missing samples round-robin between the ranks;\n"
           "rank 0 writes every row into FILE as above, so the file is the one a single process writes (the\n"
           "seconds column aside), a run killed at any moment resumes with --resume on any number of ranks, and\n"
           "only rank 0 needs FILE's folder. Needs the MPI module libmatremap-mpi.so (built where Open MPI's\n"
           "development files are installed); without it the run stops with exit 2.\n"
           "\n"
           "Merging shards: matremap sweep merge SHARD... -o FILE   (see 'matremap sweep merge --help')\n"
           "\n"
           "Exit codes: 0 done, 1 usage error, 2 bad input (unknown model or parameter, bad grid, a FILE that\n"
           "exists without --resume, belongs to another sweep or holds a row that is not a sane row of it: a\n"
           "value outside its parameter's range or not finite), 3 internal failure.\n"
           "\n"
           "Examples:\n"
           "  matremap sweep --from ggx diffuse=0 --to ward-balanced --grid alpha=0.01:1:25:log -o alpha.csv\n"
           "  matremap sweep --from ggx --to ward-balanced --grid alpha=0.02:0.5:8:log f0=0.02:1:5 -o ggx_ward.csv\n"
           "  matremap sweep --from gltf --to blender-ward --random 1000 --seed 7 --threads 2 -o gltf.csv\n"
           "  matremap sweep --from gltf --to blender-ward --random 1000 --seed 7 --threads 2 -o gltf.csv --resume\n"
           "  mpirun -np 8 matremap sweep --from gltf --to blender-ward --random 100000 --seed 7 -o big.csv --resume\n"
           "  matremap sweep --from ggx --to ward --random 4000 --shard $K/16 -o s$K.csv   # K=$SLURM_ARRAY_TASK_ID\n"
           "  matremap sweep merge s*.csv -o ggx_ward.csv\n");
}

static void print_merge_help(void) {
    printf("Usage: matremap sweep merge SHARD.csv... -o DATA.csv [--json]\n"
           "\n"
           "Joins the N files of a sweep run in shards ('matremap sweep ... --shard K/N', e.g. the jobs of a job\n"
           "array) into DATA.csv: the file a single 'matremap sweep' with the same arguments writes (its header with\n"
           "this command line and no shard line, then every row in index order, each as in its shard). The shards\n"
           "are given in any order and must belong together: every header line the same but '# shard:' and\n"
           "'# command:' (models, values, remap options, scene, sampling, seed, sample count), the same N, each K\n"
           "from 0 to N-1 exactly once, each shard finished (all its rows, in order, no torn last line: run an\n"
           "interrupted shard again with --resume first) and not being written, every row a sane row of the sweep\n"
           "(values finite and inside their parameters' ranges, the sample's source values). DATA.csv must not\n"
           "exist; it is written to a temporary file and renamed into place, so it appears complete or not at all.\n"
           "Missing folders of DATA.csv are made. --json prints the summary as one JSON object on stdout (output,\n"
           "samples, shards, seconds) instead of the summary line.\n"
           "\n"
           "Exit codes: 0 merged, 1 usage error, 2 shards that do not belong together or are unfinished or\n"
           "corrupt (the message names the file, the line and what disagrees), or an existing DATA.csv,\n"
           "3 internal failure.\n");
}

/* `matremap sweep merge SHARD... -o OUT`. */
static int cmd_sweep_merge(int argc, char **argv) {
    const char *output = NULL;
    const char **shards = calloc((size_t)argc + 1, sizeof *shards);
    int count = 0, json = 0;
    if (shards == NULL)
        return cli_usage_error("sweep merge", "out of memory");
    for (int i = 1; i < argc; i++) {
        const char *value = NULL;
        int taken;
        if (cli_is_help(argv[i])) {
            print_merge_help();
            free(shards);
            return CLI_EXIT_OK;
        }
        if ((taken = cli_take_option("sweep merge", argc, argv, &i, "--output", &value)) ||
            (taken = cli_take_option("sweep merge", argc, argv, &i, "-o", &value))) {
            if (taken < 0) {
                free(shards);
                return CLI_EXIT_USAGE;
            }
            output = value;
        } else if (strcmp(argv[i], "--json") == 0) {
            json = 1;
        } else if (argv[i][0] == '-' && argv[i][1] != '\0') {
            free(shards);
            return cli_usage_error("sweep merge", "unknown option '%s'", argv[i]);
        } else {
            shards[count++] = argv[i];
        }
    }
    int rc;
    if (count == 0) {
        rc = cli_usage_error("sweep merge", "no shard files given");
    } else if (output == NULL) {
        rc = cli_usage_error("sweep merge", "missing -o DATA.csv");
    } else {
        // The shards against the output (the library refuses it too), and the output's folders made.
        mr_output_plan io = {0};
        for (int k = 0; k < count; k++) mr_output_plan_inputf(&io, shards[k], "shard %s", shards[k]);
        mr_output_plan_output(&io, output, NULL);
        rc = cli_plan_check("sweep merge", &io);
        mr_output_plan_free(&io);
        char *command = NULL; // out of memory: no "# command:" text (the merge records an empty one)
        if (rc == CLI_EXIT_OK) mr_sweep_command_line("matremap sweep", argc, (const char *const *)argv, &command);
        mr_sweep_merge_summary summary;
        const double started = cli_now();
        mr_status status = rc == CLI_EXIT_OK ? mr_sweep_merge(shards, count, output, command, &summary) : MR_OK;
        free(command);
        if (rc != CLI_EXIT_OK) {
            // said by cli_plan_check
        } else if (status != MR_OK) {
            rc = cli_fail("sweep merge", status);
        } else if (json) {
            printf("{\"command\": \"sweep merge\", \"output\": ");
            cli_json_string(stdout, output);
            printf(", \"samples\": %ld, \"shards\": %ld, \"inputs\": [", summary.total, summary.shards);
            for (int k = 0; k < count; k++) {
                printf("%s", k ? ", " : "");
                cli_json_string(stdout, shards[k]);
            }
            printf("], \"seconds\": %.6f}\n", cli_now() - started);
        } else {
            fprintf(stderr, "matremap sweep merge: '%s' written: %ld samples from %ld shards\n", output, summary.total,
                    summary.shards);
        }
    }
    free(shards);
    return rc;
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


/* What the command line asks for. */
typedef struct sweep_args {
    mr_sweep_spec spec;
    const char *output;
    int resume, threads, json, ties_given;
    long shard_index, shard_count;
} sweep_args;

/* Parse the arguments into *a: CLI_EXIT_OK to run, else the exit code (messages printed). */
static int parse_args(int argc, char **argv, sweep_args *a, int *help) {
    const char *from_name = NULL, *to_name = NULL, *hold_list = NULL, *tie_list = NULL;
    const char *from_assignments[MAX_ASSIGNMENTS], *to_assignments[MAX_ASSIGNMENTS];
    const char *grid_axes[MR_SWEEP_MAX_AXES];
    int from_count = 0, to_count = 0, axis_count = 0, random_count = 0, seed_given = 0, region_given = 0;
    mr_sweep_region region = MR_SWEEP_REGION_TEXTURE;
    unsigned long long seed = 1;
    mr_fit_scene_options scene = {0};
    mr_remap_strategy strategy = MR_REMAP_AUTO;
    mr_local_method local_method = MR_LOCAL_AUTO;
    cli_renderers renderers;
    memset(&renderers, 0, sizeof renderers);
    enum { NONE, FROM, TO } collecting = NONE;
    memset(a, 0, sizeof *a);
    *help = 0;

    for (int i = 1; i < argc; i++) {
        const char *value = NULL;
        int taken;
        if (cli_is_help(argv[i])) {
            print_help();
            *help = 1;
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
        } else if ((taken = cli_take_option("sweep", argc, argv, &i, "--tie", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            tie_list = value;
        } else if ((taken = cli_take_option("sweep", argc, argv, &i, "--hold", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            hold_list = value;
        } else if ((taken = cli_take_option("sweep", argc, argv, &i, "--seed", &value))) {
            if (taken < 0 || !parse_seed(value, &seed)) return CLI_EXIT_USAGE;
            seed_given = 1;
        } else if ((taken = cli_take_option("sweep", argc, argv, &i, "--region", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            if (mr_sweep_region_from_name(value, &region) != MR_OK)
                return cli_usage_error("sweep", "--region %s", mr_last_error());
            region_given = 1;
        } else if ((taken = cli_take_option("sweep", argc, argv, &i, "--output", &value)) ||
                   (taken = cli_take_option("sweep", argc, argv, &i, "-o", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            a->output = value;
        } else if (strcmp(argv[i], "--resume") == 0) {
            a->resume = 1;
        } else if ((taken = cli_take_renderer_option("sweep", argc, argv, &i, &renderers))) {
            if (taken < 0) return CLI_EXIT_USAGE;
        } else if (strcmp(argv[i], "--json") == 0) {
            a->json = 1;
        } else if ((taken = cli_take_option("sweep", argc, argv, &i, "--strategy", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            if (mr_remap_strategy_from_name(value, &strategy) != MR_OK)
                return cli_usage_error("sweep", "%s", mr_last_error());
        } else if ((taken = cli_take_option("sweep", argc, argv, &i, "--local", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            if (mr_local_method_from_name(value, &local_method) != MR_OK)
                return cli_usage_error("sweep", "--local: %s", mr_last_error());
        } else if ((taken = cli_take_option("sweep", argc, argv, &i, "--size", &value))) {
            if (taken < 0 || !cli_parse_int("sweep", "--size", value, 16, 4096, &scene.size)) return CLI_EXIT_USAGE;
        } else if ((taken = cli_take_option("sweep", argc, argv, &i, "--light", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            if (mr_fit_light_from_name(value, &scene.light) != MR_OK)
                return cli_usage_error("sweep", "%s", mr_last_error());
        } else if ((taken = cli_take_option("sweep", argc, argv, &i, "--threads", &value))) {
            if (taken < 0 || !cli_parse_int("sweep", "--threads", value, 0, 1024, &a->threads))
                return CLI_EXIT_USAGE;
        } else if ((taken = cli_take_option("sweep", argc, argv, &i, "--shard", &value))) {
            if (taken < 0 || !cli_parse_shard("sweep", value, MR_SWEEP_MAX_SAMPLES, &a->shard_index, &a->shard_count))
                return CLI_EXIT_USAGE;
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
    if (region_given && random_count == 0) return cli_usage_error("sweep", "--region goes with --random");
    if (a->output == NULL)
        return cli_usage_error("sweep", "missing -o DATA.csv");

    const mr_brdf_model *from = mr_brdf_find(from_name), *to = NULL;
    if (from == NULL) return cli_fail("sweep", MR_ERR_INVALID_ARG);
    to = mr_brdf_find(to_name);
    if (to == NULL) return cli_fail("sweep", MR_ERR_INVALID_ARG);
    mr_sweep_spec *spec = &a->spec;
    mr_sweep_spec_init(spec, from, to);
    for (int k = 0; k < from_count; k++) {
        mr_status status = mr_brdf_parse_assignment(from, from_assignments[k], spec->source_values);
        if (status != MR_OK) return cli_fail("sweep", status);
        const char *equals = strchr(from_assignments[k], '=');
        for (int p = 0; p < from->param_count; p++)
            if (strlen(from->params[p].name) == (size_t)(equals - from_assignments[k]) &&
                strncmp(from->params[p].name, from_assignments[k], (size_t)(equals - from_assignments[k])) == 0)
                spec->held |= 1u << p;
    }
    for (int k = 0; k < to_count; k++) {
        mr_status status = mr_brdf_parse_assignment(to, to_assignments[k], spec->target_values);
        if (status != MR_OK) return cli_fail("sweep", status);
    }
    spec->remap.strategy = strategy;
    spec->remap.local_method = local_method;
    if (hold_list != NULL && !cli_parse_held("sweep", to, hold_list, spec->target_values, &spec->remap.held))
        return CLI_EXIT_USAGE;
    if (!cli_parse_ties("sweep", from, to, tie_list, spec->remap.held, &spec->remap.ties)) return CLI_EXIT_USAGE;
    a->ties_given = tie_list != NULL;
    spec->scene = scene;
    for (int k = 0; k < 2; k++) {
        static const char *const options[2] = {"--from-renderer", "--to-renderer"};
        const mr_brdf_model *side = k == 0 ? from : to;
        if (renderers.names[k] != NULL && mr_renderer_check(renderers.names[k], side) != MR_OK)
            return cli_usage_error("sweep", "%s %s: %s", options[k], renderers.names[k], mr_last_error());
    }
    snprintf(spec->renderers.source, sizeof spec->renderers.source, "%s", renderers.names[0] ? renderers.names[0] : "");
    snprintf(spec->renderers.target, sizeof spec->renderers.target, "%s", renderers.names[1] ? renderers.names[1] : "");
    spec->renderers.samples = renderers.samples;
    if (random_count > 0) {
        spec->sampling = MR_SWEEP_RANDOM;
        spec->random_count = random_count;
        spec->seed = seed;
        spec->region = region;
    } else {
        spec->sampling = MR_SWEEP_GRID;
        for (int k = 0; k < axis_count; k++) {
            mr_status status = mr_sweep_parse_axis(from, grid_axes[k], &spec->axes[k]);
            if (status != MR_OK) return cli_fail("sweep", status);
        }
        spec->axis_count = axis_count;
    }
    mr_status status = mr_sweep_check(spec);
    if (status != MR_OK) return cli_fail("sweep", status);
    long total = mr_sweep_sample_count(spec);
    if (a->shard_count > total)
        return cli_usage_error("sweep", "--shard %ld/%ld: %ld shards for a sweep of %ld samples (some would be empty)",
                               a->shard_index, a->shard_count, a->shard_count, total);
    return CLI_EXIT_OK;
}

/* Point descriptor fd at /dev/null; returns a copy of the old one for unmute (-1 if it could not). */
static int mute(int fd) {
    fflush(fd == STDOUT_FILENO ? stdout : stderr);
    int saved = dup(fd), null = open("/dev/null", O_WRONLY | O_CLOEXEC);
    if (saved >= 0 && null >= 0)
        dup2(null, fd);
    if (null >= 0)
        close(null);
    return saved;
}

static void unmute(int fd, int saved) {
    if (saved < 0)
        return;
    fflush(fd == STDOUT_FILENO ? stdout : stderr);
    dup2(saved, fd);
    close(saved);
}

int cmd_sweep(int argc, char **argv) {
    if (argc > 1 && strcmp(argv[1], "merge") == 0)
        return cmd_sweep_merge(argc - 1, argv + 1);

    // Under mpirun every rank parses the same arguments: only rank 0 speaks about them.
    int mpi_size = 1, mpi_rank = 0;
    const char *mpi_variable = NULL;
    const int under_mpi = mr_sweep_mpi_launched(&mpi_size, &mpi_rank, &mpi_variable);
    int saved_out = -1, saved_err = -1;
    if (under_mpi && mpi_rank != 0) {
        saved_out = mute(STDOUT_FILENO);
        saved_err = mute(STDERR_FILENO);
    }
    sweep_args a;
    int help = 0;
    int rc = parse_args(argc, argv, &a, &help);
    if (under_mpi && mpi_rank != 0) {
        unmute(STDOUT_FILENO, saved_out);
        unmute(STDERR_FILENO, saved_err);
    }
    if (rc != CLI_EXIT_OK || help)
        return rc;
    const char *output = a.output;

    // The library refuses an existing file too (race-free, O_EXCL); this check only words it for the CLI. Under
    // MPI only rank 0 sees the file (the other ranks may run elsewhere): rank 0's library says it to all.
    struct stat st;
    if (!under_mpi && !a.resume && stat(output, &st) == 0) {
        fprintf(stderr, "matremap sweep: error: '%s' already exists: use --resume to continue it, or remove it\n",
                output);
        return CLI_EXIT_BAD_INPUT;
    }

    // The output's folders, made by rank 0 (the one that writes the file) before any work.
    if (mpi_rank == 0) {
        mr_output_plan io = {0};
        mr_output_plan_output(&io, output, NULL);
        rc = cli_plan_check("sweep", &io);
        mr_output_plan_free(&io);
        if (rc != CLI_EXIT_OK) return rc;
    }

    mr_sweep_comm comm;
    int local_size = 1;
    if (under_mpi) {
        mr_status status = mr_sweep_mpi_start(&comm, &local_size);
        if (status != MR_OK) {
            // Every rank meets the same missing module; a rank elsewhere may meet its own: each says so once.
            fprintf(stderr, "matremap sweep: error: rank %d of %d (%s): %s\n", mpi_rank, mpi_size, mpi_variable,
                    mr_last_error());
            return cli_exit_code(status);
        }
        mpi_rank = comm.rank;
        // N ranks on a machine share its cores; a launcher that bound this rank to fewer cores shrinks them too.
        if (a.threads == 0) a.threads = mr_sweep_rank_threads(local_size);
    }

    char *command = NULL;
    if (mr_sweep_command_line("matremap", argc, (const char *const *)argv, &command) != MR_OK) {
        // the file's header records it: no sweep without it
        fprintf(stderr, "matremap sweep: error: out of memory for the command line\n");
        return CLI_EXIT_INTERNAL;
    }
    progress_bar bar = {cli_now(), 0.0, 0};
    mr_sweep_options opts = {0};
    opts.resume = a.resume;
    opts.threads = a.threads;
    opts.command_line = command;
    opts.shard_index = a.shard_index;
    opts.shard_count = a.shard_count;
    opts.comm = under_mpi ? &comm : NULL;
    if (isatty(STDERR_FILENO) && mpi_rank == 0) {
        opts.progress = draw_progress;
        opts.progress_user = &bar;
        signal(SIGINT, on_interrupt);
        signal(SIGTERM, on_interrupt);
    }
    mr_sweep_summary summary;
    mr_status status = mr_sweep_run(&a.spec, output, &opts, &summary);
    free(command);
    if (bar.drawn && status != MR_OK) fprintf(stderr, "\n");
    // Rank 0 reports for the run (the other ranks' failures reach it as messages), and before MPI ends: a rank
    // that leaves with a non-zero code makes mpirun kill the others, and MPI's finalize holds every rank until all
    // reach it, so the message is out before any rank can leave.
    if (mpi_rank == 0 && status != MR_OK)
        fprintf(stderr, "matremap sweep: error: %s\n", mr_last_error()[0] ? mr_last_error() : mr_status_str(status));
    if (under_mpi)
        mr_sweep_mpi_finish(&comm);
    if (mpi_rank != 0 || status != MR_OK)
        return cli_exit_code(status);

    if (a.json) {
        printf("{\"command\": \"sweep\", \"output\": ");
        cli_json_string(stdout, output);
        printf(", \"samples\": %ld, \"sweep_samples\": %ld, \"computed\": %ld, \"already_done\": %ld, "
               "\"truncated_bytes\": %ld, \"shard\": ", summary.file_total, summary.total, summary.computed,
               summary.already_done, summary.truncated_bytes);
        if (a.shard_count > 0)
            printf("{\"index\": %ld, \"count\": %ld}", a.shard_index, a.shard_count);
        else
            printf("null");
        printf(", \"seconds\": %.6f, \"threads\": %d, \"processes\": %d, \"threads_total\": %ld, \"outcomes\": {",
               summary.seconds, summary.threads, summary.processes, summary.threads_total);
        for (int o = 0; o < MR_FIT_OUTCOME_COUNT; o++)
            printf("%s\"%s\": %ld", o ? ", " : "", mr_fit_outcome_name((mr_fit_outcome)o), summary.outcomes[o]);
        printf("}, \"tied\": ");
        cli_print_ties_json(stdout, a.spec.source, a.spec.target, &a.spec.remap.ties, a.ties_given);
        printf(", \"held\": ");
        cli_print_holds_json(stdout, a.spec.target, a.spec.target_values, a.spec.remap.held,
                             a.spec.remap.ties.tied);
        printf(", \"renderers\": {\"source\": \"%s\", \"target\": \"%s\", \"samples\": %d, \"renders\": %ld, "
               "\"process_starts\": %ld}}\n", a.spec.renderers.source[0] ? a.spec.renderers.source : "builtin",
               a.spec.renderers.target[0] ? a.spec.renderers.target : "builtin", a.spec.renderers.samples,
               summary.renderer_renders, summary.renderer_starts);
        return CLI_EXIT_OK;
    }
    char what[64] = "";
    if (a.shard_count > 0)
        snprintf(what, sizeof what, " (shard %ld/%ld of %ld samples)", a.shard_index, a.shard_count, summary.total);
    if (summary.truncated_bytes > 0)
        fprintf(stderr, "matremap sweep: removed a torn last line (%ld bytes) from '%s'\n", summary.truncated_bytes,
                output);
    if (summary.computed == 0) {
        fprintf(stderr, "matremap sweep: '%s'%s is complete: all %ld samples were already there; nothing to do\n",
                output, what, summary.file_total);
        return CLI_EXIT_OK;
    }
    fprintf(stderr, "matremap sweep: '%s'%s is complete: %ld samples; %ld computed in %.1f s (%.2f rows/s, ", output,
            what, summary.file_total, summary.computed, summary.seconds, (double)summary.computed / summary.seconds);
    if (summary.processes > 1)
        fprintf(stderr, "%d ranks, %ld threads in all)", summary.processes, summary.threads_total);
    else
        fprintf(stderr, "%d threads)", summary.threads);
    if (summary.already_done > 0) fprintf(stderr, ", %ld were already there", summary.already_done);
    fprintf(stderr, "; outcomes:");
    int first = 1;
    for (int o = 0; o < MR_FIT_OUTCOME_COUNT; o++)
        if (summary.outcomes[o] > 0) {
            fprintf(stderr, "%s %s %ld", first ? "" : ",", mr_fit_outcome_name((mr_fit_outcome)o), summary.outcomes[o]);
            first = 0;
        }
    fprintf(stderr, "\n");
    if (mr_remap_renderers_external(&a.spec.renderers))
        fprintf(stderr, "matremap sweep: renderers: source %s, target %s: %ld renders, %ld process%s started%s\n",
                a.spec.renderers.source[0] ? a.spec.renderers.source : "builtin",
                a.spec.renderers.target[0] ? a.spec.renderers.target : "builtin", summary.renderer_renders,
                summary.renderer_starts, summary.renderer_starts == 1 ? "" : "es",
                summary.renderer_starts > summary.threads ? " (restarts after a crash included)" : "");
    cli_print_holds_tied(stderr, "matremap sweep: ", a.spec.target, a.spec.target_values, a.spec.remap.held,
                         a.spec.remap.ties.tied);
    cli_print_ties(stderr, "matremap sweep: ", a.spec.source, a.spec.target, &a.spec.remap.ties, a.ties_given);
    return CLI_EXIT_OK;
}
