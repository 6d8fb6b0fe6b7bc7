/* cli.c — shared command-line plumbing (contracts in cli.h). */
#include "cli.h"
#include "gltf/mr_gltf_scene.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

int cli_exit_code(mr_status status) {
    switch (status) {
    case MR_OK: return CLI_EXIT_OK;
    case MR_ERR_INVALID_ARG:
    case MR_ERR_IO:
    case MR_ERR_FORMAT:
    case MR_ERR_UNSUPPORTED: return CLI_EXIT_BAD_INPUT;
    default: return CLI_EXIT_INTERNAL;
    }
}

int cli_fail(const char *command, mr_status status) {
    const char *message = mr_last_error();
    // A status the front end made itself (after mr_clear_error) has no message: out of memory is said in words.
    fprintf(stderr, "matremap %s: error: %s\n", command,
            message[0]               ? message
            : status == MR_ERR_NOMEM ? "out of memory"
                                     : mr_status_str(status));
    return cli_exit_code(status);
}

int cli_usage_error(const char *command, const char *fmt, ...) {
    va_list args;
    va_start(args, fmt);
    fprintf(stderr, "matremap %s: ", command);
    vfprintf(stderr, fmt, args);
    fprintf(stderr, "\nTry 'matremap %s --help'.\n", command);
    va_end(args);
    return CLI_EXIT_USAGE;
}

int cli_parse_held(const char *command, const mr_brdf_model *model, const char *list, double *values, unsigned *held) {
    if (mr_brdf_parse_holds(model, list, values, held) == MR_OK) return 1;
    return cli_usage_error(command, "--hold: %s", mr_last_error()) == 0;
}

int cli_parse_ties(const char *command, const mr_brdf_model *source, const mr_brdf_model *target, const char *list,
                   unsigned held, mr_brdf_ties *ties) {
    if (list == NULL)
        *ties = mr_brdf_default_ties(source, target);
    else if (mr_brdf_parse_ties(source, target, list, ties) != MR_OK)
        return cli_usage_error(command, "--tie: %s", mr_last_error()) == 0;
    ties->tied &= ~held;
    return 1;
}

void cli_print_ties(FILE *out, const char *prefix, const mr_brdf_model *source, const mr_brdf_model *target,
                    const mr_brdf_ties *ties, int given) {
    char line[1024];
    if (mr_brdf_format_ties(source, target, ties, line, sizeof line) == 0) return;
    if (given)
        fprintf(out, "%stied: %s (--tie)\n", prefix ? prefix : "", line);
    else
        fprintf(out, "%stied: %s (default for %s -> %s)\n", prefix ? prefix : "", line, source->name, target->name);
}

void cli_print_ties_json(FILE *out, const mr_brdf_model *source, const mr_brdf_model *target,
                         const mr_brdf_ties *ties, int given) {
    fprintf(out, "[");
    for (int p = 0, first = 1; p < target->param_count && p < 32; p++) {
        if (!((ties->tied >> p) & 1u)) continue;
        fprintf(out, "%s{\"name\": ", first ? "" : ", ");
        cli_json_string(out, target->params[p].name);
        fprintf(out, ", \"source\": ");
        cli_json_string(out, source->params[ties->source[p]].name);
        fprintf(out, ", \"by\": \"%s\"}", given ? "--tie" : "default");
        first = 0;
    }
    fprintf(out, "]");
}

void cli_print_holds(FILE *out, const char *prefix, const mr_brdf_model *model, const double *values, unsigned held) {
    cli_print_holds_tied(out, prefix, model, values, held, 0u);
}

void cli_print_holds_tied(FILE *out, const char *prefix, const mr_brdf_model *model, const double *values,
                          unsigned held, unsigned tied) {
    char line[2048];
    if (mr_brdf_format_holds_tied(model, values, held, tied, "--hold", line, sizeof line) == 0) return;
    fprintf(out, "%sheld: %s\n", prefix ? prefix : "", line);
}

void cli_print_holds_json(FILE *out, const mr_brdf_model *model, const double *values, unsigned held, unsigned tied) {
    fprintf(out, "[");
    for (int p = 0, first = 1; p < model->param_count; p++) {
        const mr_hold_reason why = mr_brdf_hold_reason(model, held, p);
        if ((why != MR_HOLD_MODEL && why != MR_HOLD_CALLER) || (p < 32 && ((tied >> p) & 1u))) continue;
        const double *v = values + mr_brdf_param_offset(model, p);
        fprintf(out, "%s{\"name\": ", first ? "" : ", ");
        cli_json_string(out, model->params[p].name);
        if (model->params[p].channels == 3)
            fprintf(out, ", \"value\": [%.9g, %.9g, %.9g]", v[0], v[1], v[2]);
        else
            fprintf(out, ", \"value\": %.9g", v[0]);
        fprintf(out, ", \"by\": \"%s\"}", why == MR_HOLD_MODEL ? "default" : "--hold");
        first = 0;
    }
    fprintf(out, "]");
}

/* ---- inputs and outputs (cli.h; the plan is the library's, io/output_plan.h) --------------------------------- */

/* The folders the plans' checks made in this process, in the order made (cli_unmake_folders). */
static char **made_folders;
static int made_folder_count, made_folder_capacity;

int cli_plan_check(const char *command, mr_output_plan *plan) {
    mr_status status = mr_output_plan_check(plan);
    // The folders made, by a check that passed or one that failed half-way, become the process's: main.c removes
    // those still empty when the command fails, after the command has freed its plan.
    if (made_folder_count + plan->folders_made_count > made_folder_capacity) {
        int grown = 2 * (made_folder_count + plan->folders_made_count);
        char **more = realloc(made_folders, (size_t)grown * sizeof *more);
        if (more == NULL) {
            mr_output_plan_unmake_folders(plan); // one that cannot be recorded is not kept
            if (status == MR_OK) {
                mr_clear_error(); // cli_fail says "out of memory"
                status = MR_ERR_NOMEM;
            }
        } else {
            made_folders = more;
            made_folder_capacity = grown;
        }
    }
    int count = 0;
    char **folders = mr_output_plan_take_folders(plan, &count);
    for (int k = 0; k < count; k++) made_folders[made_folder_count++] = folders[k];
    free(folders);
    return status == MR_OK ? CLI_EXIT_OK : cli_fail(command, status);
}

void cli_unmake_folders(void) {
    while (made_folder_count > 0) {
        char *folder = made_folders[--made_folder_count];
        rmdir(folder); // fails, as it should, on a folder that holds anything
        free(folder);
    }
    free(made_folders);
    made_folders = NULL;
    made_folder_capacity = 0;
}

void cli_plan_material(mr_output_plan *plan, const char *const *assignments, const char *const *labels, int count) {
    for (int k = 0; k < count; k++) {
        const char *eq = strchr(assignments[k], '=');
        if (eq == NULL || eq[1] != '@') continue;
        // The file as cli_material_load reads it: "name=@FILE[:r|g|b|a][:linear|srgb]".
        const char *file = eq + 2;
        size_t length = 0;
        int channel;
        mr_map_encoding encoding;
        mr_map_ref_split(file, 1, &length, &channel, &encoding);
        char *path = malloc(length + 1);
        if (path == NULL) {
            plan->out_of_memory = 1; // the check says so
            continue;
        }
        memcpy(path, file, length);
        path[length] = '\0';
        mr_output_plan_input(plan, path, labels != NULL ? labels[k] : assignments[k]);
        free(path);
    }
}

void cli_plan_gltf(mr_output_plan *plan, const mr_gltf *asset, const char *label) {
    const char *file;
    for (int k = 0; (file = mr_gltf_source_file(asset, k)) != NULL; k++)
        if (k == 0)
            mr_output_plan_input(plan, file, label);
        else
            mr_output_plan_inputf(plan, file, "a file of %s", label);
}

int cli_parse_direction(const char *command, const char *option, const char *text, double out[3]) {
    const char *p = text;
    for (int k = 0; k < 3; k++) {
        char *end = NULL;
        out[k] = strtod(p, &end);
        if (end == p || !isfinite(out[k]) || *end != (k < 2 ? ',' : '\0'))
            return cli_usage_error(command, "%s '%s': expected three numbers X,Y,Z", option, text) == 0;
        p = end + 1;
    }
    if (out[0] == 0.0 && out[1] == 0.0 && out[2] == 0.0)
        return cli_usage_error(command, "%s '%s': the direction must not be zero", option, text) == 0;
    return 1;
}

int cli_is_gltf_path(const char *text) {
    size_t n = strlen(text);
    return (n > 5 && strcmp(text + n - 5, ".gltf") == 0) || (n > 4 && strcmp(text + n - 4, ".glb") == 0);
}

int cli_gltf_scene_load(const char *command, const char *path, mr_output_plan *io, mr_gltf_scene **out) {
    mr_gltf *asset = NULL;
    mr_status status = mr_gltf_load(path, &asset);
    if (status == MR_OK) {
        char label[4096 + 8];
        snprintf(label, sizeof label, "asset %s", path);
        cli_plan_gltf(io, asset, label);
        int code = cli_plan_check(command, io);
        if (code != CLI_EXIT_OK) {
            mr_gltf_free(asset);
            return code;
        }
        status = mr_gltf_scene_from_asset(asset, NULL, out);
    }
    mr_gltf_free(asset);
    return status == MR_OK ? CLI_EXIT_OK : cli_fail(command, status);
}

mr_status cli_check_radiance(const mr_image *image, const char *path) {
    char label[4096 + 16];
    snprintf(label, sizeof label, "image '%s'", path);
    return mr_image_check_radiance(image, label);
}

int cli_is_help(const char *arg) { return strcmp(arg, "--help") == 0 || strcmp(arg, "-h") == 0; }

int cli_take_option(const char *command, int argc, char **argv, int *i, const char *name, const char **value) {
    const char *arg = argv[*i];
    size_t len = strlen(name);
    if (strncmp(arg, name, len) != 0) return 0;
    if (arg[len] == '=') {
        *value = arg + len + 1;
        return 1;
    }
    if (arg[len] != '\0') return 0;
    if (*i + 1 >= argc) {
        cli_usage_error(command, "option %s needs a value", name);
        return -1;
    }
    *value = argv[++*i];
    return 1;
}

int cli_parse_int(const char *command, const char *option, const char *text, int lo, int hi, int *out) {
    char *end = NULL;
    errno = 0;
    long v = strtol(text, &end, 10);
    if (end == text || *end != '\0' || errno == ERANGE || v < lo || v > hi) {
        cli_usage_error(command, "%s '%s': expected an integer in [%d, %d]", option, text, lo, hi);
        return 0;
    }
    *out = (int)v;
    return 1;
}

int cli_parse_double(const char *command, const char *option, const char *text, double lo, double hi,
                     double *out) {
    char *end = NULL;
    errno = 0;
    double v = strtod(text, &end);
    if (end == text || *end != '\0' || errno == ERANGE || !isfinite(v) || v < lo || v > hi) {
        cli_usage_error(command, "%s '%s': expected a number in [%g, %g]", option, text, lo, hi);
        return 0;
    }
    *out = v;
    return 1;
}

void cli_json_string(FILE *out, const char *s) {
    fputc('"', out);
    for (const unsigned char *p = (const unsigned char *)s; *p; p++) {
        if (*p == '"' || *p == '\\')
            fprintf(out, "\\%c", *p);
        else if (*p < 0x20)
            fprintf(out, "\\u%04x", *p);
        else
            fputc(*p, out);
    }
    fputc('"', out);
}

double cli_now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* The names are the library's (mr_wf_diffuse_name): "gltf", the specular side's diffuse is glTF spec-gloss's, whose
 * lobe is d (1 - max s) (the default: these are glTF maps); "paper", d is the Lambert lobe itself, Eq. 2 as printed
 * (docs/workflow.md, "The spec-gloss diffuse convention"). Returns 0 after a usage error. */
int cli_parse_convention(const char *command, const char *value, mr_wf_diffuse *out) {
    if (mr_wf_diffuse_from_name(value, out) != MR_OK)
        return cli_usage_error(command, "--convention: %s", mr_last_error()) == 0;
    return 1;
}
