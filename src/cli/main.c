/*
 * main.c — the `matremap` command: dispatches to one function per sub-command (cmd_*.c).
 * Thin by design: commands parse argv into option structs, call the library, print results and map
 * mr_status to exit codes (cli.h).
 */
#include <stdio.h>
#include <string.h>

#include "cli.h"

typedef struct command {
    const char *name;
    int (*run)(int argc, char **argv);
    const char *summary;
} command;

static const command commands[] = {
    {"models", cmd_models, "list the BRDF models and their parameters"},
    {"render", cmd_render, "render a material in the fit scene to EXR/HDR/PNG"},
    {"ssim", cmd_ssim, "compare two images: SSIM (display-referred) and RMSE (linear)"},
    {"remap", cmd_remap, "fit a target model to a source material or to renders of the fit scene"},
    {"sweep", cmd_sweep, "remap a grid or random sample of source materials into a resumable CSV file"},
    {"dataset", cmd_dataset, "make the specular -> metallic training pairs (image labels); compare objectives"},
    {"train", cmd_train, "train the specular -> metallic network on sweep files (the dataset)"},
    {"learn", cmd_learn, "learn a transform between two models from sweep files (parametric, svr, mlp)"},
    {"convert", cmd_convert, "convert texture maps from one model to another (learned, chained or direct)"},
    {"spec2metal", cmd_spec2metal, "convert specular-workflow texture maps to metallic ones (also a command)"},
    {"metal2spec", cmd_metal2spec, "convert metallic-workflow texture maps to specular ones (also a command)"},
    {"gltf", cmd_gltf, "convert a glTF asset's materials: gltf spec2metal|metal2spec IN -o OUT"},
    {"export", cmd_export, "write a glTF asset's materials as MaterialX (.mtlx) or USD (.usda)"},
    {"report", cmd_report, "render materials under an HDR map and compare them in an HTML report (SSIM)"},
};

static void print_usage(FILE *out) {
    fprintf(out,
            "matremap %s — translate material appearance between BRDF models by comparing renders\n"
            "\n"
            "Usage: matremap COMMAND [ARGS...]\n"
            "\n"
            "Commands:\n",
            mr_version());
    for (size_t i = 0; i < sizeof commands / sizeof commands[0]; i++)
        fprintf(out, "  %-10s %s\n", commands[i].name, commands[i].summary);
    fprintf(out,
            "\n"
            "'matremap COMMAND --help' (or 'matremap help COMMAND') describes a command.\n"
            "Exit codes: 0 ok, 1 usage error, 2 bad input, 3 internal or external failure.\n");
}

/* A command's exit code; a failed run leaves none of the empty folders it made for its outputs (cli.h). */
static int finished(int code) {
    if (code != CLI_EXIT_OK) cli_unmake_folders();
    return code;
}

int main(int argc, char **argv) {
    const char *self = argc > 0 && argv[0] ? (strrchr(argv[0], '/') ? strrchr(argv[0], '/') + 1 : argv[0]) : "";
    if (strcmp(self, "spec2metal") == 0) return finished(cmd_spec2metal(argc, argv)); // `ln -s matremap spec2metal`
    if (strcmp(self, "metal2spec") == 0) return finished(cmd_metal2spec(argc, argv));
    if (argc < 2) {
        print_usage(stderr);
        return CLI_EXIT_USAGE;
    }
    if (cli_is_help(argv[1]) || (strcmp(argv[1], "help") == 0 && argc == 2)) {
        print_usage(stdout);
        return CLI_EXIT_OK;
    }
    if (strcmp(argv[1], "help") == 0) { // `matremap help CMD` is `matremap CMD --help`
        const int sweep_merge = argc == 4 && strcmp(argv[2], "sweep") == 0 && strcmp(argv[3], "merge") == 0;
        if (argc > 3 && !sweep_merge) {
            fprintf(stderr, "matremap help: expected one command, got '%s' and more\nTry 'matremap --help'.\n",
                    argv[2]);
            return CLI_EXIT_USAGE;
        }
        const char *name = argv[2];
        char help_flag[] = "--help";
        for (size_t i = 0; !sweep_merge && i < sizeof commands / sizeof commands[0]; i++)
            if (strcmp(name, commands[i].name) == 0) {
                char *help_argv[] = {argv[2], help_flag, NULL};
                return commands[i].run(2, help_argv);
            }
        if (sweep_merge) { // sweep's sub-command: `matremap help sweep merge`
            char sweep[] = "sweep", merge[] = "merge";
            char *help_argv[] = {sweep, merge, help_flag, NULL};
            return cmd_sweep(3, help_argv);
        }
        fprintf(stderr, "matremap help: unknown command '%s' (valid:", name);
        for (size_t i = 0; i < sizeof commands / sizeof commands[0]; i++)
            fprintf(stderr, "%s %s", i ? "," : "", commands[i].name);
        fprintf(stderr, ")\nTry 'matremap --help'.\n");
        return CLI_EXIT_USAGE;
    }
    if (strcmp(argv[1], "--version") == 0) {
        printf("matremap %s\n", mr_version());
        return CLI_EXIT_OK;
    }
    for (size_t i = 0; i < sizeof commands / sizeof commands[0]; i++)
        if (strcmp(argv[1], commands[i].name) == 0) return finished(commands[i].run(argc - 1, argv + 1));
    fprintf(stderr, "matremap: unknown command '%s' (valid:", argv[1]);
    for (size_t i = 0; i < sizeof commands / sizeof commands[0]; i++)
        fprintf(stderr, "%s %s", i ? "," : "", commands[i].name);
    fprintf(stderr, ")\nTry 'matremap --help'.\n");
    return CLI_EXIT_USAGE;
}
