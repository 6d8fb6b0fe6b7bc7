/*
 * cli_material.c — a material given on the command line, as `render`, `report` and `convert` take it: MODEL followed
 * by name=value and name=@MAP[:r|g|b|a][:linear|srgb] assignments (cli.h). The library reads it
 * (mr_material_from_assignments, render/render.h); this file only turns its answer into messages and exit codes.
 */
#include "cli.h"

void cli_material_note_invalid_texels(const char *command, const mr_material *m) {
    char note[4400];
    for (int k = 0; m != NULL && k < m->map_count; k++)
        if (mr_material_describe_invalid_texels(m, k, note, sizeof note))
            fprintf(stderr, "matremap %s: note: %s\n", command, note);
}

int cli_material_load(const char *command, const char *model_name, const char *const *assignments, int count,
                      mr_material **out) {
    *out = NULL;
    if (count > CLI_MAX_ASSIGNMENTS) return cli_usage_error(command, "too many parameter assignments");
    mr_material_text_report report;
    mr_status status = mr_material_from_assignments(model_name, assignments, count, NULL, out, &report);
    if (status == MR_OK) return CLI_EXIT_OK;
    return report.usage ? cli_usage_error(command, "%s", mr_last_error()) : cli_fail(command, status);
}
