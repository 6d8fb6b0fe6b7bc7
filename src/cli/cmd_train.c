/*
 * cmd_train.c — `matremap train`: fit the specular -> metallic MLP (nn/mlp.h) to sweep files of specular
 * materials remapped to metallic ones (src/workflow/dataset.h; scripts/dataset.sh makes them), write the weight
 * file, the loss curve (CSV + SVG plot) and, with --test, the errors of every method on held-out sweep files.
 */
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cli.h"
#include "workflow/pairs.h"

#define MAX_FILES 64

static void print_help(void) {
    printf("Usage: matremap train DATASET.csv [DATASET.csv ...] -o WEIGHTS.mlp [options]\n"
           "\n"
           "Trains the specular -> metallic network: 6 inputs (diffuse RGB, specular F0 RGB) -> one hidden layer of\n"
           "ReLU units -> 4 outputs (albedo RGB, metallic), on the pairs of 'matremap dataset' files (image-objective\n"
           "labels; 'make dataset' makes the default set, docs/training.md) or of 'matremap sweep' files of specular\n"
           "materials remapped into the metallic workflow (a ggx or ggx-metallic source, a ggx-metallic target;\n"
           "sweep them with --random N --region range: coloured pairs, as textures hold them).\n"
           "Rows whose outcome is local-minimum are left out.\n"
           "Training: Adam on minibatches, inputs and outputs normalised, a seeded validation split and early\n"
           "stopping that keeps the best epoch (nn/mlp.h). Deterministic for a seed on any thread count.\n"
           "\n"
           "Options:\n"
           "  -o, --output FILE    the weight file (required; written atomically)\n"
           "  --hidden N           hidden units (default 300)\n"
           "  --epochs N           most epochs (default 200)\n"
           "  --patience N         stop after N epochs without a better validation loss (default 20)\n"
           "  --batch N            rows per Adam step (default 64)\n"
           "  --lr X               Adam learning rate (default 0.001)\n"
           "  --validation F       share of the rows held out for early stopping (default 0.1)\n"
           "  --seed S             split, initialisation and shuffles (default 1)\n"
           "  --form F             residual (default): the network learns the correction to the albedo-weighted\n"
           "                       inverse, applied gated (zero where Eq. 2 is exactly invertible) and colour-\n"
           "                       neutral (src/workflow/workflow.h); plain: it learns the labels themselves\n"
           "  --threads T          OpenMP threads (default 0: automatic, all cores); results do not depend on it\n"
           "  --loss-curve PREFIX  write PREFIX.csv (epoch, train and validation loss) and PREFIX.svg (a plot, when\n"
           "                       gnuplot is installed); default: WEIGHTS without its extension + '_loss'\n"
           "  --test FILE.csv      held-out sweep files (repeatable): print each method's error on them\n"
           "                       (mlp, weighted, mean, khronos) against the labels (the fitted metal-rough answers)\n"
           "  --json               the summary as JSON on stdout\n"
           "  --help               this text\n"
           "\n"
           "Losses are mean squared errors of the normalised outputs (each output scaled by its standard deviation\n"
           "over the training split). Progress goes to stderr when it is a terminal.\n"
           "\n"
           "Examples:\n"
           "  matremap train build/dataset/on-manifold.csv build/dataset/off-manifold.csv -o data/spec2metal.mlp\n"
           "  matremap train sweep.csv -o small.mlp --hidden 32 --test test.csv --json\n");
}

/* Per-epoch state: the loss curve in memory and the terminal progress line. */
typedef struct curve {
    int count, capacity;
    mr_mlp_epoch *epochs;
    int draw;
    double started;
} curve;

static int record_epoch(const mr_mlp_epoch *epoch, void *user) {
    curve *c = user;
    if (c->count == c->capacity) {
        int grown = c->capacity ? 2 * c->capacity : 256;
        mr_mlp_epoch *more = realloc(c->epochs, (size_t)grown * sizeof *more);
        if (more == NULL) return 1; // stops training with the best weights so far; reported by the caller
        c->epochs = more;
        c->capacity = grown;
    }
    c->epochs[c->count++] = *epoch;
    if (c->draw)
        fprintf(stderr, "\rmatremap train: epoch %d/%d  train %.5f  validation %.5f  best %.5f (epoch %d)  %.0f s ",
                epoch->epoch, epoch->max_epochs, epoch->train_loss, epoch->validation_loss,
                epoch->best_validation_loss, epoch->best_epoch, cli_now() - c->started);
    return 0;
}

int cmd_train(int argc, char **argv) {
    const char *files[MAX_FILES], *tests[MAX_FILES], *output = NULL, *curve_prefix = NULL;
    int file_count = 0, test_count = 0, json = 0, threads = 0, residual = 1;
    mr_mlp_train_options opts;
    memset(&opts, 0, sizeof opts);
    opts.seed = 1;
    for (int i = 1; i < argc; i++) {
        const char *value = NULL;
        int taken, number;
        if (cli_is_help(argv[i])) {
            print_help();
            return CLI_EXIT_OK;
        }
        if ((taken = cli_take_option("train", argc, argv, &i, "--output", &value)) ||
            (taken = cli_take_option("train", argc, argv, &i, "-o", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            output = value;
        } else if ((taken = cli_take_option("train", argc, argv, &i, "--hidden", &value))) {
            if (taken < 0 || !cli_parse_int("train", "--hidden", value, 1, MR_MLP_MAX_HIDDEN, &opts.n_hidden))
                return CLI_EXIT_USAGE;
        } else if ((taken = cli_take_option("train", argc, argv, &i, "--epochs", &value))) {
            if (taken < 0 || !cli_parse_int("train", "--epochs", value, 1, 1000000, &opts.max_epochs))
                return CLI_EXIT_USAGE;
        } else if ((taken = cli_take_option("train", argc, argv, &i, "--patience", &value))) {
            if (taken < 0 || !cli_parse_int("train", "--patience", value, 1, 1000000, &opts.patience))
                return CLI_EXIT_USAGE;
        } else if ((taken = cli_take_option("train", argc, argv, &i, "--batch", &value))) {
            if (taken < 0 || !cli_parse_int("train", "--batch", value, 1, 1 << 20, &opts.batch_size))
                return CLI_EXIT_USAGE;
        } else if ((taken = cli_take_option("train", argc, argv, &i, "--lr", &value))) {
            if (taken < 0 || !cli_parse_double("train", "--lr", value, 1e-9, 1.0, &opts.learning_rate))
                return CLI_EXIT_USAGE;
        } else if ((taken = cli_take_option("train", argc, argv, &i, "--validation", &value))) {
            if (taken < 0 ||
                !cli_parse_double("train", "--validation", value, 1e-3, 0.9, &opts.validation_fraction))
                return CLI_EXIT_USAGE;
        } else if ((taken = cli_take_option("train", argc, argv, &i, "--seed", &value))) {
            if (taken < 0 || !cli_parse_int("train", "--seed", value, 0, 2147483647, &number)) return CLI_EXIT_USAGE;
            opts.seed = (unsigned long long)number;
        } else if ((taken = cli_take_option("train", argc, argv, &i, "--form", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            if (strcmp(value, "residual") != 0 && strcmp(value, "plain") != 0)
                return cli_usage_error("train", "--form '%s': expected residual or plain", value);
            residual = strcmp(value, "residual") == 0;
        } else if ((taken = cli_take_option("train", argc, argv, &i, "--threads", &value))) {
            if (taken < 0 || !cli_parse_int("train", "--threads", value, 0, 1024, &threads)) return CLI_EXIT_USAGE;
        } else if ((taken = cli_take_option("train", argc, argv, &i, "--loss-curve", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            curve_prefix = value;
        } else if ((taken = cli_take_option("train", argc, argv, &i, "--test", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            if (test_count == MAX_FILES) return cli_usage_error("train", "more than %d --test files", MAX_FILES);
            tests[test_count++] = value;
        } else if (strcmp(argv[i], "--json") == 0) {
            json = 1;
        } else if (argv[i][0] == '-') {
            return cli_usage_error("train", "unknown option '%s'", argv[i]);
        } else {
            if (file_count == MAX_FILES) return cli_usage_error("train", "more than %d dataset files", MAX_FILES);
            files[file_count++] = argv[i];
        }
    }
    if (file_count == 0) return cli_usage_error("train", "no dataset file (sweep CSV) given");
    if (output == NULL) return cli_usage_error("train", "missing -o WEIGHTS");
    char default_prefix[4096];
    if (curve_prefix == NULL) {
        snprintf(default_prefix, sizeof default_prefix, "%s", output);
        char *dot = strrchr(default_prefix, '.'), *slash = strrchr(default_prefix, '/');
        if (dot != NULL && (slash == NULL || dot > slash)) *dot = '\0';
        strncat(default_prefix, "_loss", sizeof default_prefix - strlen(default_prefix) - 1);
        curve_prefix = default_prefix;
    }
    // Nothing written over a file read: the weights and the loss curve's two files against the datasets.
    mr_output_plan io = {0};
    for (int i = 0; i < file_count; i++) mr_output_plan_inputf(&io, files[i], "dataset %s", files[i]);
    for (int t = 0; t < test_count; t++) mr_output_plan_inputf(&io, tests[t], "--test %s", tests[t]);
    mr_output_plan_output(&io, output, NULL);
    for (int k = 0; k < 2; k++) {
        char path[4096 + 8];
        snprintf(path, sizeof path, "%s.%s", curve_prefix, k == 0 ? "csv" : "svg");
        if (curve_prefix == default_prefix)
            mr_output_plan_outputf(&io, path, "the loss curve of -o %s", output);
        else
            mr_output_plan_outputf(&io, path, "--loss-curve %s", curve_prefix);
    }
    int code = cli_plan_check("train", &io);
    mr_output_plan_free(&io);
    if (code != CLI_EXIT_OK) return code;
    opts.threads = threads;

    double started = cli_now();
    mr_wf_dataset data, test[MAX_FILES];
    memset(test, 0, sizeof test);
    mr_status status = mr_wf_dataset_load(files, file_count, NULL, &data);
    if (status != MR_OK) return cli_fail("train", status);
    for (int t = 0; t < test_count && status == MR_OK; t++) status = mr_wf_dataset_load(&tests[t], 1, NULL, &test[t]);
    if (status != MR_OK) {
        mr_wf_dataset_free(&data);
        for (int t = 0; t < test_count; t++) mr_wf_dataset_free(&test[t]);
        return cli_fail("train", status);
    }
    if (data.n < 2) {
        mr_wf_dataset_free(&data);
        for (int t = 0; t < test_count; t++) mr_wf_dataset_free(&test[t]);
        fprintf(stderr, "matremap train: error: %zu usable pairs in the dataset (%zu rows left out for their "
                        "outcome): need at least 2\n", data.n, data.skipped);
        return CLI_EXIT_BAD_INPUT;
    }
    if (residual) mr_wf_residual_targets(data.x, data.y, data.n); // corrections to the analytic anchor
    curve c = {0, 0, NULL, isatty(STDERR_FILENO), cli_now()};
    opts.epoch_fn = record_epoch;
    opts.epoch_user = &c;
    mr_mlp *net = NULL;
    mr_mlp_train_report report;
    status = mr_mlp_train(data.x, data.y, data.n, MR_WF_DATASET_INPUTS, MR_WF_DATASET_OUTPUTS, &opts, &net,
                          &report);
    if (c.draw) fputc('\n', stderr);
    double train_seconds = cli_now() - c.started;
    mr_wf_method_error errors[MAX_FILES][MR_WF_EVALUATED_METHODS];
    if (status == MR_OK && report.stop == MR_MLP_STOP_CALLBACK) { // the curve's realloc
        mr_clear_error();
        status = MR_ERR_NOMEM;
    }
    if (status == MR_OK && residual) snprintf(net->kind, sizeof net->kind, "%s", MR_WF_MLP_RESIDUAL_KIND);
    // Nothing is written before every result is in; then the network and its loss curve as one set (mlp.h).
    for (int t = 0; t < test_count && status == MR_OK; t++)
        status = mr_wf_pairs_evaluate(net, &test[t], threads, errors[t]);
    char title[256];
    snprintf(title, sizeof title, "matremap train: %zu pairs, %d hidden units, seed %llu", data.n,
             net ? net->n_hidden : 0, opts.seed);
    int drawn = 0;
    if (status == MR_OK)
        status = mr_mlp_write_with_curve(net, output, c.epochs, c.count, curve_prefix, "--loss-curve", title, &drawn);
    free(c.epochs);
    mr_mlp_free(net);
    if (status != MR_OK) {
        mr_wf_dataset_free(&data);
        for (int t = 0; t < test_count; t++) mr_wf_dataset_free(&test[t]);
        return cli_fail("train", status);
    }
    if (!drawn)
        fprintf(stderr, "matremap train: note: no plot (gnuplot missing or failed); the curve is in %s.csv\n",
                curve_prefix);
    double seconds = cli_now() - started;
    if (json) {
        printf("{\"weights\": ");
        cli_json_string(stdout, output);
        printf(", \"pairs\": %zu, \"skipped\": %zu, \"train\": %zu, \"validation\": %zu, \"hidden\": %d, "
               "\"seed\": %llu, \"epochs\": %d, \"best_epoch\": %d, \"initial_validation_loss\": %.9g, "
               "\"best_validation_loss\": %.9g, \"stop\": \"%s\", \"train_seconds\": %.3f, \"seconds\": %.3f",
               data.n, data.skipped, report.n_train, report.n_validation,
               opts.n_hidden ? opts.n_hidden : MR_MLP_DEFAULT_HIDDEN, opts.seed, report.epochs, report.best_epoch,
               report.initial_validation_loss, report.best_validation_loss, mr_mlp_stop_str(report.stop),
               train_seconds, seconds);
        printf(", \"tests\": [");
        for (int t = 0; t < test_count; t++) {
            printf("%s{\"file\": ", t ? ", " : "");
            cli_json_string(stdout, tests[t]);
            printf(", \"pairs\": %zu", test[t].n);
            for (int m = 0; m < MR_WF_EVALUATED_METHODS; m++)
                printf(", \"%s\": {\"albedo_rmse\": %.6g, \"metallic_rmse\": %.6g, \"metallic_max_error\": %.6g}",
                       errors[t][m].name, errors[t][m].albedo_rmse, errors[t][m].metallic_rmse,
                       errors[t][m].metallic_max);
            printf("}");
        }
        printf("]}\n");
    } else {
        printf("%s: %d hidden units, %zu pairs (%zu left out for their outcome; %zu train, %zu validation), "
               "seed %llu\n", output, opts.n_hidden ? opts.n_hidden : MR_MLP_DEFAULT_HIDDEN, data.n, data.skipped,
               report.n_train, report.n_validation, opts.seed);
        printf("validation loss %.6g -> %.6g (best epoch %d of %d, stopped: %s), %.1f s training\n",
               report.initial_validation_loss, report.best_validation_loss, report.best_epoch, report.epochs,
               mr_mlp_stop_str(report.stop), train_seconds);
        printf("loss curve: %s.csv, %s.svg\n", curve_prefix, curve_prefix);
        for (int t = 0; t < test_count; t++) {
            printf("test %s (%zu pairs): error against the labels\n", tests[t], test[t].n);
            printf("  %-9s %12s %14s %14s\n", "method", "albedo RMSE", "metallic RMSE", "metallic max");
            for (int m = 0; m < MR_WF_EVALUATED_METHODS; m++)
                printf("  %-9s %12.5f %14.5f %14.5f\n", errors[t][m].name, errors[t][m].albedo_rmse,
                       errors[t][m].metallic_rmse, errors[t][m].metallic_max);
        }
    }
    mr_wf_dataset_free(&data);
    for (int t = 0; t < test_count; t++) mr_wf_dataset_free(&test[t]);
    return CLI_EXIT_OK;
}
