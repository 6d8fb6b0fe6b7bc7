/*
 * cmd_learn.c — `matremap learn`: a transform between two BRDF models learned from sweep files (src/learn/learned.h),
 * written as a .mrt file, with the paper's cross-section plots on request.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cli.h"
#include "learn/learned.h"
#include "learn/learned_plots.h"
#include "learn/svr.h"

#define MAX_FILES 64
#define COMMAND "learn"

static void print_help(void) {
    printf(
        "Usage: matremap learn SWEEP.csv [SWEEP.csv ...] --method parametric|svr|mlp -o T.mrt [options]\n"
        "\n"
        "Learns a transform from one BRDF model's parameters to another's (paper sections 5-7) from the rows of\n"
        "'matremap sweep' files (uniform remaps of the same model pair, target values and fit scene), and writes it\n"
        "as a transform file that 'matremap convert --transform' applies to texture maps. The rows decide what is\n"
        "learned: source parameters that vary are the inputs, fitted target parameters that vary the outputs; an\n"
        "RGB parameter swept grey (a grid axis) is learned as one number and applied per channel; a diffuse albedo\n"
        "held in the sweeps is carried by the ratio of the two models' Lambertian lobes; the rest keep the values\n"
        "of the rows. Rows whose outcome is local-minimum are left out.\n"
        "\n"
        "Methods:\n"
        "  parametric  (default) section 7: target roughness a polynomial of the source roughness (degree <= 4,\n"
        "              through the origin), each specular channel the source's times one slope\n"
        "              k(a) = c0 + c1 e^(-c2 a) + c3 e^(-c4 a^2) [+ c5/a]: chromaticity kept, linear extrapolation.\n"
        "              The exponents are searched on a bounded log grid, the rest by least squares (the free fit is\n"
        "              ill-conditioned: the paper's printed fits drift to c0 ~ -900). Needs sweeps of a roughness\n"
        "              and a specular reflectance only.\n"
        "  svr         epsilon-SVR with RBF kernels (libsvm), one per output, C, gamma and epsilon searched on a grid\n"
        "              then locally on a seeded validation split; accurate inside the sweep, not beyond it.\n"
        "  mlp         one hidden ReLU layer (nn/), Adam with early stopping.\n"
        "\n"
        "Options:\n"
        "  -o, --output FILE   the transform file (required; written atomically; never one of the inputs)\n"
        "  --method M          parametric, svr or mlp (default parametric)\n"
        "  --validation F      share of rows held out to measure the error (default 0.2); parametric and svr\n"
        "                      are then refitted on every row\n"
        "  --seed S            the split (and the MLP's initialisation) (default 1)\n"
        "  --degree N          parametric: roughness polynomial degree 1..4 (default 4)\n"
        "  --intercept         parametric: give the roughness polynomial a constant term (default: none)\n"
        "  --inverse auto|yes|no  parametric: the c5/a term of the authors' code (default auto: kept when it\n"
        "                      lowers the held-out error by 1 %% or more)\n"
        "  --hidden N          mlp: hidden units (default 64)\n"
        "  --epochs N          mlp: most epochs (default 2000)\n"
        "  --svr-c C, --svr-gamma G, --svr-epsilon E\n"
        "                      svr: fix that hyper-parameter for every output (normalised units) instead\n"
        "                      of searching it (the search fits up to ~200 candidates per output)\n"
        "  --threads T         svr search / mlp training threads (default 0: automatic, all cores); results do\n"
        "                      not depend on it\n"
        "  --all-outcomes      keep local-minimum rows too\n"
        "  --keep-trimmed      keep the rows where the source rescales its reflectances (Ward's and Phong's energy\n"
        "                      trimming, diffuse + specular > 1), left out by default: no texel lies there\n"
        "  --plots DIR         the paper's cross sections as SVG (gnuplot): target roughness against source\n"
        "                      roughness, target specular against source specular coloured by roughness, with\n"
        "                      the rows and the learned curves (DIR/roughness.svg, DIR/specular.svg, data as CSV)\n"
        "  --json              the summary as JSON on stdout\n"
        "  --help              this text\n"
        "\n"
        "Examples:\n"
        "  matremap sweep --from ward diffuse=0 --to ggx diffuse=0 --grid alpha=0.02:0.5:15:log \\\n"
        "                 specular=0.02:0.3:5 -o ward_ggx.csv\n"
        "  matremap learn ward_ggx.csv -o ward_ggx.mrt --plots ward_ggx_plots\n"
        "  matremap learn ward_ggx.csv --method svr -o ward_ggx_svr.mrt\n"
        "  matremap convert --from ward --to ggx specular=@spec.exr alpha=@rough.exr diffuse=@diff.png \\\n"
        "                   --transform ward_ggx.mrt -o out/ggx_\n");
}

typedef struct progress_state {
    int draw;
    double started;
} progress_state;

static void draw_progress(const char *stage, double fraction, void *user) {
    progress_state *p = user;
    if (p->draw)
        fprintf(stderr, "\rmatremap learn: %s %3.0f %%  %.1f s ", stage, 100.0 * fraction, cli_now() - p->started);
}

/* ---- the command ------------------------------------------------------------------------------------------ */

static void print_summary(const mr_learned *t, const mr_sweep_table *tab, const char *output, double seconds,
                          int json) {
    if (json) {
        printf("{\"output\": ");
        cli_json_string(stdout, output);
        printf(", \"method\": \"%s\", \"source\": \"%s\", \"target\": \"%s\", \"train_rows\": %ld, "
               "\"validation_rows\": %ld, \"seconds\": %.3f, \"features\": [",
               mr_learn_method_name(t->method), t->source->name, t->target->name, t->train_rows, t->validation_rows,
               seconds);
        for (int i = 0; i < t->feature_count; i++)
            printf("%s{\"name\": \"%s\", \"min\": %.9g, \"max\": %.9g}", i ? ", " : "",
                   t->source->params[t->features[i].param].name, t->features[i].min, t->features[i].max);
        printf("], \"validation_rmse\": {");
        char name[80];
        for (int j = 0; j < t->output_count; j++) // a CHANNEL output's key: f0_r; else the name
            printf("%s\"%s\": %.9g", j ? ", " : "", mr_learned_slot_name(t->target, &t->outputs[j], name, sizeof name),
                   t->rmse[j]);
        printf("}");
        const mr_learned_check *k = &t->check;
        printf(", \"check\": {\"done\": %s, \"passed\": %s, \"rows\": %ld, \"max_relative_error\": %g, "
               "\"max_dssim\": %g, ", k->done ? "true" : "false", k->passed ? "true" : "false", k->rows,
               MR_LEARNED_MAX_RELATIVE_ERROR, MR_LEARNED_MAX_DSSIM);
        if (k->done && !isnan(k->dssim_mean))
            printf("\"dssim_mean\": %.6g, \"dssim_p90\": %.6g, ", k->dssim_mean, k->dssim_p90);
        else
            printf("\"dssim_mean\": null, \"dssim_p90\": null, ");
        printf("\"relative_error\": {");
        for (int j = 0; j < t->output_count; j++)
            printf("%s\"%s\": {\"median\": %.6g, \"p90\": %.6g}", j ? ", " : "",
                   mr_learned_slot_name(t->target, &t->outputs[j], name, sizeof name), k->relative_median[j],
                   k->relative_p90[j]);
        printf("}}");
        if (t->method == MR_LEARN_PARAMETRIC) {
            printf(", \"roughness\": [");
            for (int k = 0; k <= t->roughness_degree; k++) printf("%s%.9g", k ? ", " : "", t->roughness[k]);
            printf("], \"slope\": [");
            for (int k = 0; k < (t->slope.with_inverse ? 6 : 5); k++) printf("%s%.9g", k ? ", " : "", t->slope.c[k]);
            printf("]");
        }
        printf(", \"held\": "); // the sweep's holds: its header's '# to:' values, held= and the model's defaults
        cli_print_holds_json(stdout, tab->target, tab->target_fixed, tab->target_held, tab->target_ties.tied);
        printf("}\n");
        return;
    }
    printf("matremap learn: %s -> %s by %s, %ld rows (+%ld held out) in %.2f s -> %s\n", t->source->name,
           t->target->name, mr_learn_method_name(t->method), t->train_rows, t->validation_rows, seconds, output);
    for (int i = 0; i < t->feature_count; i++) {
        const mr_learned_slot *s = &t->features[i];
        char name[80];
        mr_learned_slot_name(t->source, s, name, sizeof name);
        printf("  input  %-14s %s, trained over [%.4g, %.4g]\n", name,
               s->kind == MR_LEARNED_GREY ? "RGB, applied per channel" : "scalar", s->min, s->max);
    }
    for (int j = 0; j < t->output_count; j++) {
        const mr_learned_slot *s = &t->outputs[j];
        char name[80];
        mr_learned_slot_name(t->target, s, name, sizeof name);
        if (t->check.done)
            printf("  output %-14s held-out RMSE %.4g; against the remaps: median %.2g %%, 9 in 10 within %.2g %%\n",
                   name, t->rmse[j], 100.0 * t->check.relative_median[j], 100.0 * t->check.relative_p90[j]);
        else
            printf("  output %-14s held-out RMSE %.4g\n", name, t->rmse[j]);
    }
    if (t->check.done) {
        if (isnan(t->check.dssim_mean))
            printf("  check  %s: no renders (the sweep's fit scene is not one this version renders)\n",
                   t->check.passed ? "passed" : "FAILED");
        else
            printf("  check  %s: SSIM below the remaps' by %.2g on average, 9 in 10 within %.2g (%ld held-out rows; "
                   "bounds %g %%, %g)\n", t->check.passed ? "passed" : "FAILED", t->check.dssim_mean,
                   t->check.dssim_p90, t->check.rows, 100.0 * MR_LEARNED_MAX_RELATIVE_ERROR, MR_LEARNED_MAX_DSSIM);
    }
    for (int i = 0; i < t->carry_count; i++) {
        const mr_learned_carry *c = &t->carries[i];
        // A carry of a parameter that is not a Lambertian lobe is a tie (the sweep held it at the source's value).
        const mr_brdf_param *q = &t->target->params[c->target_param];
        const int tie = !c->learned && !(q->lobe == MR_LOBE_DIFFUSE && q->role == MR_PARAM_LINEAR);
        printf("  carry  %-14s = %.6g x source %s (%s)\n", q->name, c->factor[0],
               t->source->params[c->source_param].name,
               c->learned ? "fitted on the rows" : tie ? "the sweep's tie" : "ratio of the lobes");
    }
    if (t->method == MR_LEARN_PARAMETRIC) {
        const char *a = t->source->params[t->features[0].param].name;
        printf("  %s' =", t->target->params[t->outputs[0].param].name);
        for (int k = t->roughness_origin ? 1 : 0; k <= t->roughness_degree; k++)
            printf(" %+.4g %s^%d", t->roughness[k], a, k);
        const double *c = t->slope.c;
        printf("\n  k(%s) = %.4g %+.4g e^(-%.4g %s) %+.4g e^(-%.4g %s^2)", a, c[0], c[1], c[2], a, c[3], c[4], a);
        if (t->slope.with_inverse) printf(" %+.4g / %s", c[5], a);
        printf("\n");
        if (t->output_count == 3) {
            const double *d = t->diffuse_slope.c;
            printf("  %s' = carry + %s k_d(%s), k_d = %.4g %+.4g e^(-%.4g %s) %+.4g e^(-%.4g %s^2)",
                   t->target->params[t->outputs[2].param].name, t->source->params[t->features[1].param].name, a, d[0],
                   d[1], d[2], a, d[3], d[4], a);
            if (t->diffuse_slope.with_inverse) printf(" %+.4g / %s", d[5], a);
            printf("\n");
        }
    } else if (t->method == MR_LEARN_SVR) {
        for (int j = 0; j < t->svr->n_out; j++)
            printf("  svr %d: %d support vectors, C %.4g, gamma %.4g, epsilon %.4g\n", j, t->svr->outputs[j].sv_count,
                   t->svr->outputs[j].C, t->svr->outputs[j].gamma, t->svr->outputs[j].epsilon);
    }
    for (const char *p = t->provenance; p && *p;) {
        const char *e = strchr(p, '\n');
        if (strncmp(p, "note: ", 6) == 0) printf("  %.*s\n", (int)(e - p), p);
        p = e + 1;
    }
    cli_print_holds_tied(stdout, "  ", tab->target, tab->target_fixed, tab->target_held, tab->target_ties.tied);
}

/* The warning of a transform that failed its check: which bound, by how much, and what to do. */
static void warn_check(const mr_learned *t) {
    const mr_learned_check *k = &t->check;
    fprintf(stderr, "matremap learn: warning: the transform fails its check against the remaps on %ld held-out rows:",
            k->rows);
    for (int j = 0; j < t->output_count; j++)
        if (k->relative_p90[j] > MR_LEARNED_MAX_RELATIVE_ERROR)
            fprintf(stderr, " %s is more than %g %% off in more than 1 row in 10 (9 in 10 within %.3g %%);",
                    t->target->params[t->outputs[j].param].name, 100.0 * MR_LEARNED_MAX_RELATIVE_ERROR,
                    100.0 * k->relative_p90[j]);
    if (!isnan(k->dssim_p90) && k->dssim_p90 > MR_LEARNED_MAX_DSSIM)
        fprintf(stderr, " its renders lose more than %g SSIM to the remaps' in more than 1 row in 10 (%.3g);",
                MR_LEARNED_MAX_DSSIM, k->dssim_p90);
    fprintf(stderr, " convert flags every texel it converts with it. Sweep more samples of the values your textures "
            "hold (sweep --random N, --region texture), try another --method, or convert with --direct.\n");
}

int cmd_learn(int argc, char **argv) {
    const char *files[MAX_FILES], *output = NULL, *plots = NULL;
    int file_count = 0, json = 0;
    mr_learn_options o = {0};
    mr_sweep_table_options to = {0};
    for (int i = 1; i < argc; i++) {
        const char *v = NULL;
        int r;
        if (cli_is_help(argv[i])) {
            print_help();
            return CLI_EXIT_OK;
        }
        if ((r = cli_take_option(COMMAND, argc, argv, &i, "--output", &v)) != 0 ||
            (r = cli_take_option(COMMAND, argc, argv, &i, "-o", &v)) != 0) {
            if (r < 0) return CLI_EXIT_USAGE;
            output = v;
        } else if ((r = cli_take_option(COMMAND, argc, argv, &i, "--method", &v)) != 0) {
            if (r < 0) return CLI_EXIT_USAGE;
            if (mr_learn_method_from_name(v, &o.method) != MR_OK)
                return cli_usage_error(COMMAND, "--method: %s", mr_last_error());
        } else if ((r = cli_take_option(COMMAND, argc, argv, &i, "--validation", &v)) != 0) {
            if (r < 0 || !cli_parse_double(COMMAND, "--validation", v, 0.01, 0.5, &o.validation_fraction))
                return CLI_EXIT_USAGE;
        } else if ((r = cli_take_option(COMMAND, argc, argv, &i, "--seed", &v)) != 0) {
            int seed = 0;
            if (r < 0 || !cli_parse_int(COMMAND, "--seed", v, 1, 2147483647, &seed)) return CLI_EXIT_USAGE;
            o.seed = (unsigned long long)seed;
        } else if ((r = cli_take_option(COMMAND, argc, argv, &i, "--degree", &v)) != 0) {
            if (r < 0 || !cli_parse_int(COMMAND, "--degree", v, 1, MR_POLY_MAX_DEGREE, &o.roughness_degree))
                return CLI_EXIT_USAGE;
        } else if (strcmp(argv[i], "--intercept") == 0) {
            o.roughness_intercept = 1;
        } else if ((r = cli_take_option(COMMAND, argc, argv, &i, "--inverse", &v)) != 0) {
            if (r < 0) return CLI_EXIT_USAGE;
            if (strcmp(v, "auto") == 0) o.slope_inverse = 0;
            else if (strcmp(v, "yes") == 0) o.slope_inverse = 1;
            else if (strcmp(v, "no") == 0) o.slope_inverse = -1;
            else return cli_usage_error(COMMAND, "--inverse '%s': expected auto, yes or no", v);
        } else if ((r = cli_take_option(COMMAND, argc, argv, &i, "--hidden", &v)) != 0) {
            if (r < 0 || !cli_parse_int(COMMAND, "--hidden", v, 1, 4096, &o.mlp_hidden)) return CLI_EXIT_USAGE;
        } else if ((r = cli_take_option(COMMAND, argc, argv, &i, "--svr-c", &v)) != 0) {
            if (r < 0 || !cli_parse_double(COMMAND, "--svr-c", v, 1e-12, 1e12, &o.svr_C)) return CLI_EXIT_USAGE;
        } else if ((r = cli_take_option(COMMAND, argc, argv, &i, "--svr-gamma", &v)) != 0) {
            if (r < 0 || !cli_parse_double(COMMAND, "--svr-gamma", v, 1e-12, 1e12, &o.svr_gamma)) return CLI_EXIT_USAGE;
        } else if ((r = cli_take_option(COMMAND, argc, argv, &i, "--svr-epsilon", &v)) != 0) {
            if (r < 0 || !cli_parse_double(COMMAND, "--svr-epsilon", v, 1e-12, 1e12, &o.svr_epsilon))
                return CLI_EXIT_USAGE;
        } else if ((r = cli_take_option(COMMAND, argc, argv, &i, "--epochs", &v)) != 0) {
            if (r < 0 || !cli_parse_int(COMMAND, "--epochs", v, 1, 1000000, &o.mlp_max_epochs)) return CLI_EXIT_USAGE;
        } else if ((r = cli_take_option(COMMAND, argc, argv, &i, "--threads", &v)) != 0) {
            if (r < 0 || !cli_parse_int(COMMAND, "--threads", v, 0, 1024, &o.threads)) return CLI_EXIT_USAGE;
        } else if ((r = cli_take_option(COMMAND, argc, argv, &i, "--plots", &v)) != 0) {
            if (r < 0) return CLI_EXIT_USAGE;
            plots = v;
        } else if (strcmp(argv[i], "--all-outcomes") == 0) {
            to.keep_all_outcomes = 1;
        } else if (strcmp(argv[i], "--keep-trimmed") == 0) {
            to.keep_rescaled = 1;
        } else if (strcmp(argv[i], "--json") == 0) {
            json = 1;
        } else if (argv[i][0] == '-' && argv[i][1] != '\0') {
            return cli_usage_error(COMMAND, "unknown option '%s'", argv[i]);
        } else {
            if (file_count == MAX_FILES) return cli_usage_error(COMMAND, "more than %d sweep files", MAX_FILES);
            files[file_count++] = argv[i];
        }
    }
    if (file_count == 0) return cli_usage_error(COMMAND, "no sweep file given");
    if (output == NULL) return cli_usage_error(COMMAND, "no output file: give -o T.mrt");
    // Nothing written over a file read: the transform and --plots DIR's files against the sweeps.
    mr_output_plan io = {0};
    for (int i = 0; i < file_count; i++) mr_output_plan_inputf(&io, files[i], "sweep %s", files[i]);
    mr_output_plan_output(&io, output, NULL);
    for (int k = 0; plots != NULL && k < MR_LEARNED_PLOT_FILES; k++) {
        char path[4096];
        snprintf(path, sizeof path, "%s/%s", plots, mr_learned_plot_file_name(k));
        mr_output_plan_outputf(&io, path, "--plots %s", plots);
    }
    int code = cli_plan_check(COMMAND, &io);
    mr_output_plan_free(&io);
    if (code != CLI_EXIT_OK) return code;
    const double started = cli_now();
    mr_sweep_table tab;
    mr_status status = mr_sweep_table_load(files, file_count, &to, &tab);
    if (status != MR_OK) return cli_fail(COMMAND, status);
    if (tab.rescaled > 0)
        fprintf(stderr, "matremap learn: note: %zu of %zu rows left out: %s rescales their source values (energy "
                "trimming, diffuse + specular > 1), where no texel of a texture lies (--keep-trimmed keeps them)\n",
                tab.rescaled, tab.rescaled + tab.n + tab.skipped, tab.source->name);
    progress_state ps = {isatty(STDERR_FILENO), started};
    o.progress = draw_progress;
    o.progress_user = &ps;
    mr_learned *t = NULL;
    status = mr_learn(&tab, &o, &t);
    if (ps.draw) fprintf(stderr, "\r\033[K");
    // The transform and its plots as one set (learned_plots.h): a failure leaves none of them.
    mr_learned_plots_options po = {"--plots"};
    mr_learned_plots_result plotted = {0, 0};
    if (status == MR_OK) status = mr_learned_write_with_plots(t, &tab, output, plots, &po, &plotted);
    if (status != MR_OK) {
        mr_sweep_table_free(&tab);
        mr_learned_free(t);
        return cli_fail(COMMAND, status);
    }
    if (plots != NULL && !plotted.cut)
        fprintf(stderr, "matremap learn: note: no plots: the transform has no roughness and specular pair to cut "
                        "through\n");
    else if (plots != NULL && !plotted.drawn)
        fprintf(stderr, "matremap learn: note: no SVG plots (gnuplot missing or failed); the data is in %s\n", plots);
    print_summary(t, &tab, output, cli_now() - started, json);
    fflush(stdout); // the summary before the warning, also when both go to one pipe
    if (!t->check.passed) warn_check(t);
    mr_sweep_table_free(&tab);
    mr_learned_free(t);
    return CLI_EXIT_OK;
}
