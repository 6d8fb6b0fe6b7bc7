/*
 * cli_renderer.c — the renderer options shared by remap, sweep and report (cli.h; renderer.h has the renderers).
 */
#include <stdlib.h>
#include <string.h>

#include "cli.h"

void cli_renderers_help(FILE *out) {
    fprintf(out,
            "Renderers (docs/renderers.md):\n"
            "  --from-renderer R  who renders the source: builtin (default), blender (Cycles in Blender 3.4:\n"
            "                     cycles-principled, lambert) or three (three.js in headless Chromium: gltf,\n"
            "                     lambert); --from blender:FILE.blend:MATERIAL implies blender\n"
            "  --to-renderer R    who renders the target during the fit, the same names: the values fitted are\n"
            "                     the ones that renderer needs (e.g. --to gltf --to-renderer three for a web\n"
            "                     viewer). One long-lived process per worker; start-up is paid once\n"
            "  --samples N        the external renderers' samples per pixel (Blender, default %d; three.js: an\n"
            "                     s x s sub-pixel grid, s = floor(sqrt(N)), default %d)\n",
            MR_RENDERER_DEFAULT_SAMPLES_BLENDER, MR_RENDERER_DEFAULT_SAMPLES_THREE);
}

int cli_take_renderer_option(const char *command, int argc, char **argv, int *i, cli_renderers *r) {
    static const char *const options[2] = {"--from-renderer", "--to-renderer"};
    const char *value = NULL;
    for (int k = 0; k < 2; k++) {
        int taken = cli_take_option(command, argc, argv, i, options[k], &value);
        if (taken < 0) return -1;
        if (taken == 0) continue;
        if (mr_renderer_check(value, NULL) != MR_OK) {
            cli_usage_error(command, "%s: %s", options[k], mr_last_error());
            return -1;
        }
        r->names[k] = value;
        return 1;
    }
    int taken = cli_take_option(command, argc, argv, i, "--samples", &value);
    if (taken <= 0) return taken;
    return cli_parse_int(command, "--samples", value, 1, 1 << 20, &r->samples) ? 1 : -1;
}

int cli_open_renderers(const char *command, cli_renderers *r, const mr_brdf_model *source,
                       const mr_brdf_model *target, int processes) {
    const mr_brdf_model *models[2] = {source, target};
    static const char *const options[2] = {"--from-renderer", "--to-renderer"};
    for (int k = 0; k < 2; k++)
        if (r->names[k] != NULL && models[k] != NULL && mr_renderer_check(r->names[k], models[k]) != MR_OK)
            return cli_usage_error(command, "%s %s: %s", options[k], r->names[k], mr_last_error());
    for (int k = 0; k < 2; k++) {
        if (r->names[k] == NULL || strcmp(r->names[k], "builtin") == 0) {
            snprintf(r->versions[k], sizeof r->versions[k], "builtin");
            continue;
        }
        // One renderer serves both sides when they name the same one.
        if (k == 1 && r->opened[0] != NULL && strcmp(r->names[0], r->names[1]) == 0) {
            r->opened[1] = r->opened[0];
            snprintf(r->versions[1], sizeof r->versions[1], "%s", r->versions[0]);
            continue;
        }
        mr_renderer_options ro = {0};
        ro.samples = r->samples;
        ro.seed = r->seed;
        ro.processes = processes;
        mr_status status = mr_renderer_open(r->names[k], &ro, &r->opened[k]);
        if (status == MR_OK) status = mr_renderer_start(r->opened[k], r->versions[k], sizeof r->versions[k]);
        if (status != MR_OK) {
            int code = cli_fail(command, status);
            cli_close_renderers(r);
            return code;
        }
    }
    return CLI_EXIT_OK;
}

void cli_close_renderers(cli_renderers *r) {
    if (r->opened[1] != r->opened[0]) mr_renderer_free(r->opened[1]);
    mr_renderer_free(r->opened[0]);
    r->opened[0] = r->opened[1] = NULL;
}

static int side_samples(const cli_renderers *r, int k) {
    if (r->samples > 0) return r->samples;
    if (strcmp(r->names[k], "blender") == 0) return MR_RENDERER_DEFAULT_SAMPLES_BLENDER;
    return MR_RENDERER_DEFAULT_SAMPLES_THREE;
}

void cli_print_renderers(FILE *out, const cli_renderers *r) {
    fprintf(out, "renderers:");
    static const char *const sides[2] = {"source", "target"};
    for (int k = 0; k < 2; k++) {
        fprintf(out, "%s %s %s", k ? "," : "", sides[k], r->versions[k][0] ? r->versions[k] : "builtin");
        if (r->opened[k] != NULL)
        {
            const long renders = mr_renderer_render_count(r->opened[k]);
            const long starts = mr_renderer_process_starts(r->opened[k]);
            fprintf(out, " (%d samples, %ld render%s, %ld process start%s)", side_samples(r, k), renders,
                    renders == 1 ? "" : "s", starts, starts == 1 ? "" : "s");
        }
        if (k == 1 && r->opened[1] != NULL && r->opened[1] == r->opened[0]) fprintf(out, " (the same process)");
    }
    fprintf(out, "\n");
}

void cli_print_renderers_json(FILE *out, const cli_renderers *r) {
    fprintf(out, "{");
    static const char *const sides[2] = {"source", "target"};
    for (int k = 0; k < 2; k++) {
        fprintf(out, "%s\"%s\": {\"renderer\": ", k ? ", " : "", sides[k]);
        cli_json_string(out, r->versions[k][0] ? r->versions[k] : "builtin");
        if (r->opened[k] != NULL)
            fprintf(out, ", \"samples\": %d, \"renders\": %ld, \"process_starts\": %ld", side_samples(r, k),
                    mr_renderer_render_count(r->opened[k]), mr_renderer_process_starts(r->opened[k]));
        fprintf(out, "}");
    }
    fprintf(out, "}");
}

/* 'NODE.SOCKET=v' or '=r,g,b' of a .blend material (the path may hold spaces and dots: split at the last '='). */
int cli_set_material_input(const char *command, mr_external_material *material, const char *assignment) {
    const char *equals = strrchr(assignment, '=');
    char path[256];
    if (equals == NULL || equals == assignment || (size_t)(equals - assignment) >= sizeof path)
        return cli_usage_error(command, "'%s': expected NODE.SOCKET=value", assignment);
    memcpy(path, assignment, (size_t)(equals - assignment));
    path[equals - assignment] = '\0';
    double values[3];
    int count = 0;
    const char *at = equals + 1;
    for (; count < 3; count++) {
        char *end = NULL;
        values[count] = strtod(at, &end);
        if (end == at) break;
        at = end;
        if (*at != ',') {
            count++;
            break;
        }
        at++;
    }
    if (count == 0 || *at != '\0')
        return cli_usage_error(command, "'%s': the value '%s' is not a number or r,g,b", assignment, equals + 1);
    mr_status status = mr_external_material_set(material, path, values, count);
    return status == MR_OK ? CLI_EXIT_OK : cli_fail(command, status);
}

void cli_print_material_inputs_json(FILE *out, const mr_external_material *material) {
    fprintf(out, "{");
    for (int k = 0; k < mr_external_material_param_count(material); k++) {
        int channels = 0;
        double lo, hi, v[3];
        const char *path = mr_external_material_param(material, k, &channels, &lo, &hi, v);
        fprintf(out, "%s", k ? ", " : "");
        cli_json_string(out, path);
        if (channels == 3)
            fprintf(out, ": [%.17g, %.17g, %.17g]", v[0], v[1], v[2]);
        else
            fprintf(out, ": %.17g", v[0]);
    }
    fprintf(out, "}");
}
