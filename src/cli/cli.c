/* cli.c — shared command-line plumbing (contracts in cli.h). */
#include "cli.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

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

int cli_parse_held(const char *command, const mr_brdf_model *model, const char *list, unsigned *held) {
    const char *name = list;
    while (*name) {
        size_t length = strcspn(name, ",");
        int found = -1;
        for (int p = 0; p < model->param_count && p < 32; p++)
            if (strlen(model->params[p].name) == length && strncmp(model->params[p].name, name, length) == 0) found = p;
        if (found < 0) {
            char valid[512] = "";
            for (int p = 0; p < model->param_count; p++)
                snprintf(valid + strlen(valid), sizeof valid - strlen(valid), "%s%s", p ? ", " : "",
                         model->params[p].name);
            return cli_usage_error(command, "--hold: '%.*s' is not a parameter of '%s' (valid: %s)", (int)length, name,
                                   model->name, valid) == 0;
        }
        *held |= 1u << found;
        name += length + (name[length] == ',');
    }
    return 1;
}

int cli_same_file(const char *a, const char *b) {
    struct stat sa, sb;
    return stat(a, &sa) == 0 && stat(b, &sb) == 0 && sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
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
