/*
 * fuzz_cli_value.c — the command line's value parsers: a material's NAME=VALUE assignments
 * (mr_brdf_parse_assignment, and cli_material_load over several), sweep axes NAME=LO:HI:N[:log]
 * (mr_sweep_parse_axis), --hold lists, --convention, and the numeric options (cli_parse_double, cli_parse_int).
 * The first byte picks the model, the rest is split at newlines into arguments. Map assignments (NAME=@FILE) are
 * left out: they name files, which the image targets cover.
 */
#include <stdlib.h>
#include <string.h>

#include "cli/cli.h"
#include "fuzz.h"
#include "matremap.h"

#define MAX_ARGS 8

int mr_fuzz_cli_value(const uint8_t *data, size_t size) {
    if (size < 1) return 0;
    int model_count = 0;
    const mr_brdf_model *const *models = mr_brdf_models();
    while (models[model_count] != NULL) model_count++;
    const mr_brdf_model *model = models[data[0] % model_count];

    char *text = malloc(size);
    if (text == NULL) return 0;
    memcpy(text, data + 1, size - 1);
    text[size - 1] = '\0';
    const char *args[MAX_ARGS];
    int count = 0, has_map = 0;
    for (char *p = text; p != NULL && count < MAX_ARGS;) {
        args[count++] = p;
        p = strchr(p, '\n');
        if (p != NULL) *p++ = '\0';
    }
    double values[MR_BRDF_MAX_VALUES];
    for (int i = 0; i < count; i++) {
        mr_brdf_default_values(model, values);
        (void)mr_brdf_parse_assignment(model, args[i], values);
        mr_sweep_axis axis;
        (void)mr_sweep_parse_axis(model, args[i], &axis);
        unsigned held = 0;
        (void)cli_parse_held("fuzz", model, args[i], values, &held);
        mr_wf_diffuse convention;
        (void)cli_parse_convention("fuzz", args[i], &convention);
        double d;
        (void)cli_parse_double("fuzz", "--value", args[i], -1e300, 1e300, &d);
        int n;
        (void)cli_parse_int("fuzz", "--count", args[i], -1000000, 1000000, &n);
        if (strchr(args[i], '@') != NULL || strchr(args[i], '=') == NULL) has_map = 1;
    }
    if (!has_map) {
        mr_material *m = NULL;
        if (cli_material_load("fuzz", model->name, args, count, &m) == CLI_EXIT_OK) mr_material_free(m);
    }
    free(text);
    return 0;
}

MR_FUZZ_ENTRY(mr_fuzz_cli_value)
