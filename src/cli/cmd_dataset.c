/*
 * cmd_dataset.c — `matremap dataset`: training pairs for the learned spec -> metal converter, labelled by the
 * image objective of src/workflow/labels.h (docs/training.md), and `matremap dataset --compare`: how well each
 * objective's labels, and each converter, keep the look under other lights (object SSIM of spheres).
 *
 * The command parses, reads the assets (mr_gltf_add_specgloss_texels) and maps, calls the library's pipeline
 * (src/workflow/pairs.h: mr_wf_pairs_make, mr_wf_pairs_compare) and prints: progress, the table, the summary.
 */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cli.h"
#include "gltf/mr_gltf.h"
#include "workflow/pairs.h"

#define MAX_ASSETS 16
#define MAX_ENVS 4
#define MAX_WEIGHTS MR_WF_COMPARE_MAX_WEIGHTS

static void print_help(void) {
    printf("Usage: matremap dataset -o PAIRS.csv [options]\n"
           "       matremap dataset --compare --env MAP.hdr [--env MAP.hdr ...] [options]\n"
           "\n"
           "Makes training pairs for the specular -> metallic network: spec-gloss texels (diffuse, specular) and\n"
           "the glTF metal-rough material (base colour, metallic) that renders most like each one, on a sphere\n"
           "under two synthetic grey environments (a studio and a sky, none of the maps evaluations use) at four\n"
           "glossinesses (0.3, 0.6, 0.8, 0.95), by an image objective (docs/training.md). Texels are drawn as\n"
           "8-bit textures store them: uniform codes, the dielectric F0 band (specular 40-70/255) with dark and\n"
           "saturated diffuse, grey inputs, metals, partly metallic texels of Eq. 2, and texels of --asset files.\n"
           "The file loads in 'matremap train' (its diffuse columns hold the diffuse lobe d (1 - max specular)).\n"
           "A pair's outcome is converged when the label renders like the texel within one 8-bit code (rms),\n"
           "else unreachable (no metal-rough material matches it; the label is the closest one).\n"
           "\n"
           "With --compare, fits the labels of every objective for a set of texels (the named hard cases, texels\n"
           "of --asset files and drawn ones), and prints a table of how close each objective's labels, each\n"
           "analytic inverse and each --weights network render to the original under the --env maps: SSIM over\n"
           "the sphere's inner square (the object's pixels), mean and worst over texels.\n"
           "\n"
           "Options:\n"
           "  -o, --output FILE     the pairs (CSV, written atomically); with --compare, the table (markdown)\n"
           "  --samples N           drawn texels (default 16000; --compare: 400)\n"
           "  --seed S              seed of the draws (default 1); sample i depends only on (S, i)\n"
           "  --objective O         luma (default), exposed, display, log or linear (labels.h)\n"
           "  --asset FILE.gltf     spec-gloss assets whose texels join the mixture (repeatable; 30 %% of the\n"
           "                        samples, shared equally)\n"
           "  --size N              label sphere side in pixels (default 32)\n"
           "  --label-env FILE      an environment the labels are made under, instead of the built-in synthetic\n"
           "                        studio and sky (repeatable, at most %d)\n"
           "  --chroma-weight W     luma objective: weight of the per-channel colour term (default 0.1)\n"
           "  --regularisation L    pull towards the analytic answer (default 1e-4, labels.h)\n"
           "  --threads T           OpenMP threads (default 0: automatic, all cores); results do not depend on it\n"
           "  --compare             the objective comparison (needs --env)\n"
           "  --env FILE            an environment map for --compare (repeatable, at most %d)\n"
           "  --weights FILE        a network to compare too (repeatable, at most %d)\n"
           "  --json                a summary as one JSON object on stdout: the output, pair count, outcomes\n"
           "                        (converged, unreachable), categories, seconds; with --compare (which then\n"
           "                        needs -o for the table) each column's mean and worst SSIM\n"
           "  --help                this text\n"
           "\n"
           "Exit codes: 0 done, 1 usage error, 2 bad input (an asset or map that cannot be read, an asset without\n"
           "spec-gloss materials, an output that cannot be written), 3 internal failure.\n"
           "\n"
           "Examples:\n"
           "  matremap dataset -o pairs.csv --samples 2000 --asset Duck.gltf --asset Avocado.gltf\n"
           "  matremap dataset --compare --env studio.hdr --env tabac.hdr --weights data/spec2metal.mlp\n",
           MAX_ENVS, MAX_ENVS, MAX_WEIGHTS);
}

/* ---- progress ----------------------------------------------------------------------------------------------- */

/* The terminal line of the library's stages (pairs.h): redrawn in place, a newline when a stage ends. */
typedef struct progress_state {
    int draw;          /* stderr is a terminal */
    const char *stage; /* the stage drawn last, and when it started */
    double started;
} progress_state;

static void draw_progress(const char *stage, size_t done, size_t total, void *user) {
    progress_state *p = user;
    if (!p->draw) return;
    if (p->stage != stage) {
        p->stage = stage;
        p->started = cli_now();
    }
    fprintf(stderr, "\rmatremap dataset: %s %zu/%zu  %.0f s ", stage, done, total, cli_now() - p->started);
    if (done == total) {
        fputc('\n', stderr);
        p->stage = NULL;
    }
}

/* ---- texels of glTF assets ----------------------------------------------------------------------------------- */

/* The spec-gloss texels of the asset at `path` into the pool; the files the asset was read from are added to io's
 * inputs. Returns an exit code. */
static int add_asset_texels(const char *path, uint64_t seed, mr_wf_texel_pool *pool, mr_output_plan *io) {
    char label[4096 + 16];
    snprintf(label, sizeof label, "--asset %s", path);
    mr_gltf *asset = NULL;
    const mr_status status = mr_gltf_add_specgloss_texels_from_file(path, label, seed, pool, &asset);
    if (status != MR_OK) return cli_fail("dataset", status);
    cli_plan_gltf(io, asset, label); // its buffers and images are inputs too
    mr_gltf_free(asset);
    return CLI_EXIT_OK;
}

/* ---- --compare ------------------------------------------------------------------------------------------------ */

/* The comparison's table (markdown) into f. */
static void print_table(FILE *f, const mr_wf_compare_table *t) {
    const size_t n = t->texel_count, hard = (size_t)t->hard_case_count;
    const int ncol = t->column_count;
    fprintf(f, "| texel | diffuse codes | specular codes |");
    for (int k = 0; k < ncol; k++) fprintf(f, " %s |", t->columns[k].name);
    fprintf(f, "\n|---|---|---|");
    for (int k = 0; k < ncol; k++) fprintf(f, "---:|");
    fprintf(f, "\n");
    for (size_t i = 0; i < hard && i < n; i++) {
        const mr_wf_named_texel *h = &t->hard_cases[i];
        fprintf(f, "| %s | %d,%d,%d | %d,%d,%d |", h->name, h->diffuse[0], h->diffuse[1], h->diffuse[2],
                h->specular[0], h->specular[1], h->specular[2]);
        for (int k = 0; k < ncol; k++) fprintf(f, " %.4f |", t->columns[k].ssim[i]);
        fprintf(f, "\n");
    }
    for (int cat = 0; cat < MR_WF_PAIR_CATEGORY_COUNT; cat++) { /* the drawn texels by category */
        size_t count = 0;
        for (size_t i = hard; i < n; i++) count += t->categories[i] == (mr_wf_pair_category)cat;
        if (count == 0) continue;
        fprintf(f, "| *drawn: %s, mean* (%zu) | | |", mr_wf_pair_category_name((mr_wf_pair_category)cat), count);
        for (int k = 0; k < ncol; k++) {
            double sum = 0.0;
            for (size_t i = hard; i < n; i++)
                if (t->categories[i] == (mr_wf_pair_category)cat) sum += t->columns[k].ssim[i];
            fprintf(f, " %.4f |", sum / (double)count);
        }
        fprintf(f, "\n");
    }
    const char *groups[3] = {"hard cases: mean", "all texels: mean", "all texels: worst"};
    for (int g = 0; g < 3; g++) {
        fprintf(f, "| **%s** (%zu) | | |", groups[g], g == 0 ? hard : n);
        for (int k = 0; k < ncol; k++) {
            double sum = 0.0, worst = 1.0;
            size_t count = g == 0 ? hard : n;
            for (size_t i = 0; i < count; i++) {
                sum += t->columns[k].ssim[i];
                worst = fmin(worst, t->columns[k].ssim[i]);
            }
            fprintf(f, " %.4f |", g == 2 ? worst : sum / (double)count);
        }
        fprintf(f, "\n");
    }
}

/* The comparison, its table on stdout or in `output` (atomically), the JSON summary on request. */
static int compare(const mr_wf_compare_options *co, const char *output, int json) {
    mr_wf_compare_table *t = NULL;
    mr_status status = mr_wf_pairs_compare(co, &t);
    if (status != MR_OK) return cli_fail("dataset", status);
    int code = CLI_EXIT_OK;
    if (output == NULL) {
        print_table(stdout, t);
    } else {
        mr_atomic_file file;
        FILE *f = cli_output_open("dataset", output, &file);
        if (f == NULL) {
            code = CLI_EXIT_BAD_INPUT;
        } else {
            print_table(f, t);
            if (!cli_output_close("dataset", f, &file)) code = CLI_EXIT_BAD_INPUT;
            else if ((status = mr_atomic_commit(&file)) != MR_OK) code = cli_fail("dataset", status);
        }
    }
    if (code == CLI_EXIT_OK && json) { // the columns' means and worsts over every texel, as the table's last rows
        printf("{\"command\": \"dataset --compare\", \"output\": ");
        cli_json_string(stdout, output);
        printf(", \"texels\": %zu, \"hard_cases\": %d, \"envs\": %d, \"columns\": [", t->texel_count,
               t->hard_case_count, co->env_count);
        for (int k = 0; k < t->column_count; k++) {
            double sum = 0.0, worst = 1.0;
            for (size_t i = 0; i < t->texel_count; i++) {
                sum += t->columns[k].ssim[i];
                worst = fmin(worst, t->columns[k].ssim[i]);
            }
            printf("%s{\"name\": ", k ? ", " : "");
            cli_json_string(stdout, t->columns[k].name);
            printf(", \"mean_ssim\": %.6f, \"worst_ssim\": %.6f}", sum / (double)t->texel_count, worst);
        }
        printf("]}\n");
    }
    mr_wf_compare_table_free(t);
    return code;
}

int cmd_dataset(int argc, char **argv) {
    const char *output = NULL, *assets[MAX_ASSETS], *env_paths[MAX_ENVS], *weights[MAX_WEIGHTS];
    const char *label_env_paths[MAX_ENVS];
    int asset_count = 0, env_count = 0, label_env_count = 0, weight_count = 0;
    int samples = -1, seed = 1, threads = 0, do_compare = 0, json = 0;
    const double started = cli_now();
    mr_wf_label_options lo = mr_wf_label_options_default();
    for (int i = 1; i < argc; i++) {
        const char *value = NULL;
        int taken;
        if (cli_is_help(argv[i])) {
            print_help();
            return CLI_EXIT_OK;
        }
        if ((taken = cli_take_option("dataset", argc, argv, &i, "--output", &value)) ||
            (taken = cli_take_option("dataset", argc, argv, &i, "-o", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            output = value;
        } else if ((taken = cli_take_option("dataset", argc, argv, &i, "--samples", &value))) {
            if (taken < 0 || !cli_parse_int("dataset", "--samples", value, 1, 10000000, &samples))
                return CLI_EXIT_USAGE;
        } else if ((taken = cli_take_option("dataset", argc, argv, &i, "--seed", &value))) {
            if (taken < 0 || !cli_parse_int("dataset", "--seed", value, 0, 2147483647, &seed)) return CLI_EXIT_USAGE;
        } else if ((taken = cli_take_option("dataset", argc, argv, &i, "--objective", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            if (mr_wf_objective_from_name(value, &lo.objective) != MR_OK)
                return cli_usage_error("dataset", "--objective '%s': expected luma, exposed, display, log or linear",
                                       value);
        } else if ((taken = cli_take_option("dataset", argc, argv, &i, "--asset", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            if (asset_count == MAX_ASSETS) return cli_usage_error("dataset", "more than %d --asset files", MAX_ASSETS);
            assets[asset_count++] = value;
        } else if ((taken = cli_take_option("dataset", argc, argv, &i, "--env", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            if (env_count == MAX_ENVS) return cli_usage_error("dataset", "more than %d --env maps", MAX_ENVS);
            env_paths[env_count++] = value;
        } else if ((taken = cli_take_option("dataset", argc, argv, &i, "--label-env", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            if (label_env_count == MAX_ENVS)
                return cli_usage_error("dataset", "more than %d --label-env maps", MAX_ENVS);
            label_env_paths[label_env_count++] = value;
        } else if ((taken = cli_take_option("dataset", argc, argv, &i, "--weights", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            if (weight_count == MAX_WEIGHTS) return cli_usage_error("dataset", "more than %d --weights", MAX_WEIGHTS);
            weights[weight_count++] = value;
        } else if ((taken = cli_take_option("dataset", argc, argv, &i, "--size", &value))) {
            if (taken < 0 || !cli_parse_int("dataset", "--size", value, 16, 1024, &lo.size)) return CLI_EXIT_USAGE;
        } else if ((taken = cli_take_option("dataset", argc, argv, &i, "--regularisation", &value))) {
            if (taken < 0 || !cli_parse_double("dataset", "--regularisation", value, 0.0, 1.0, &lo.regularisation))
                return CLI_EXIT_USAGE;
            if (lo.regularisation == 0.0) lo.regularisation = MR_WF_LABEL_OFF; // 0 in the options: the default
        } else if ((taken = cli_take_option("dataset", argc, argv, &i, "--chroma-weight", &value))) {
            if (taken < 0 || !cli_parse_double("dataset", "--chroma-weight", value, 0.0, 100.0, &lo.chroma_weight))
                return CLI_EXIT_USAGE;
            if (lo.chroma_weight == 0.0) lo.chroma_weight = MR_WF_LABEL_OFF;
        } else if ((taken = cli_take_option("dataset", argc, argv, &i, "--threads", &value))) {
            if (taken < 0 || !cli_parse_int("dataset", "--threads", value, 0, 1024, &threads)) return CLI_EXIT_USAGE;
        } else if (strcmp(argv[i], "--compare") == 0) {
            do_compare = 1;
        } else if (strcmp(argv[i], "--json") == 0) {
            json = 1;
        } else {
            return cli_usage_error("dataset", "%s '%s'", argv[i][0] == '-' ? "unknown option" : "unexpected argument",
                                   argv[i]);
        }
    }
    if (!do_compare && output == NULL) return cli_usage_error("dataset", "missing -o PAIRS.csv");
    if (do_compare && env_count == 0) return cli_usage_error("dataset", "--compare needs at least one --env map");
    if (!do_compare && (env_count || weight_count))
        return cli_usage_error("dataset", "--env and --weights go with --compare");
    if (do_compare && json && output == NULL)
        return cli_usage_error("dataset", "--compare --json needs -o TABLE.md (the table; the JSON has its summary)");
    if (samples < 0) samples = do_compare ? 400 : 16000;

    // Nothing written over a file read: -o against the maps, the networks and the assets with their files.
    mr_output_plan io = {0};
    for (int e = 0; e < env_count; e++) mr_output_plan_inputf(&io, env_paths[e], "--env %s", env_paths[e]);
    for (int e = 0; e < label_env_count; e++)
        mr_output_plan_inputf(&io, label_env_paths[e], "--label-env %s", label_env_paths[e]);
    for (int w = 0; w < weight_count; w++) mr_output_plan_inputf(&io, weights[w], "--weights %s", weights[w]);
    for (int a = 0; a < asset_count; a++) mr_output_plan_inputf(&io, assets[a], "--asset %s", assets[a]);
    if (output != NULL) mr_output_plan_output(&io, output, NULL);
    mr_wf_texel_pool pool = {0};
    int code = cli_plan_check("dataset", &io);
    for (int a = 0; code == CLI_EXIT_OK && a < asset_count; a++)
        code = add_asset_texels(assets[a], (uint64_t)seed, &pool, &io);
    if (code == CLI_EXIT_OK) code = cli_plan_check("dataset", &io); // with the assets' files
    mr_output_plan_free(&io);
    mr_image *label_envs[MAX_ENVS] = {NULL}, *envs[MAX_ENVS] = {NULL};
    for (int e = 0; code == CLI_EXIT_OK && e < label_env_count; e++) {
        mr_img_read_options ro = {MR_IMG_DATA, 3, 0};
        mr_status status = mr_img_read(label_env_paths[e], &ro, &label_envs[e]);
        if (status == MR_OK) status = cli_check_radiance(label_envs[e], label_env_paths[e]);
        if (status != MR_OK) code = cli_fail("dataset", status);
        lo.envs[e] = label_envs[e];
        lo.env_count = e + 1;
    }
    for (int e = 0; code == CLI_EXIT_OK && do_compare && e < env_count; e++) {
        mr_img_read_options ro = {MR_IMG_DATA, 3, 0};
        mr_status status = mr_img_read(env_paths[e], &ro, &envs[e]);
        if (status == MR_OK) status = cli_check_radiance(envs[e], env_paths[e]);
        if (status != MR_OK) code = cli_fail("dataset", status);
    }
    progress_state progress = {isatty(STDERR_FILENO), NULL, 0.0};
    mr_wf_pairs_options po = {samples, (uint64_t)seed, &lo, &pool, threads, draw_progress, &progress};
    if (code == CLI_EXIT_OK && do_compare) {
        mr_wf_compare_options co = {po, (const mr_image *const *)envs, env_count, weights, weight_count};
        code = compare(&co, output, json);
    } else if (code == CLI_EXIT_OK) {
        mr_wf_pairs_summary summary;
        mr_status status = mr_wf_pairs_make(&po, output, &summary);
        if (status != MR_OK) code = cli_fail("dataset", status);
        if (code == CLI_EXIT_OK && json) {
            printf("{\"command\": \"dataset\", \"output\": ");
            cli_json_string(stdout, output);
            printf(", \"pairs\": %zu, \"objective\": \"%s\", \"seed\": %d, \"assets\": %d, \"outcomes\": "
                   "{\"converged\": %zu, \"unreachable\": %zu}, \"categories\": {", summary.pairs,
                   mr_wf_objective_name(lo.objective), seed, asset_count, summary.converged, summary.unreachable);
            for (int c = 0; c < MR_WF_PAIR_CATEGORY_COUNT; c++)
                printf("%s\"%s\": %zu", c ? ", " : "", mr_wf_pair_category_name((mr_wf_pair_category)c),
                       summary.categories[c]);
            printf("}, \"seconds\": %.6f}\n", cli_now() - started);
        }
    }
    mr_wf_texel_pool_free(&pool);
    for (int e = 0; e < MAX_ENVS; e++) {
        mr_image_free(label_envs[e]);
        mr_image_free(envs[e]);
    }
    return code;
}
