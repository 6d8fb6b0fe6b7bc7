/* cli.c — shared command-line plumbing (contracts in cli.h). */
#define _XOPEN_SOURCE 700 /* realpath (X/Open): where an input lies, for folder outputs */
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

/* ---- inputs and outputs (cli.h) ---------------------------------------------------------------------------- */

void cli_io_init(cli_io *io, const char *command) {
    memset(io, 0, sizeof *io);
    io->command = command;
}

static char *format_label(const char *fmt, va_list args) {
    va_list copy;
    va_copy(copy, args);
    int n = vsnprintf(NULL, 0, fmt, copy);
    va_end(copy);
    char *label = n >= 0 ? malloc((size_t)n + 1) : NULL;
    if (label != NULL) vsnprintf(label, (size_t)n + 1, fmt, args);
    return label;
}

/* Append (path, label) to *list; the label is taken over. On failure the label is freed and io remembers it. */
static void io_add(cli_io *io, cli_io_entry **list, int *count, int *capacity, const char *path, char *label,
                   int folder) {
    char *copy = path != NULL ? strdup(path) : NULL;
    if (copy != NULL && *count == *capacity) {
        int grown = *capacity ? 2 * *capacity : 16;
        cli_io_entry *more = realloc(*list, (size_t)grown * sizeof *more);
        if (more != NULL) {
            *list = more;
            *capacity = grown;
        }
    }
    if (copy == NULL || *count == *capacity) {
        io->out_of_memory |= path != NULL;
        free(copy);
        free(label);
        return;
    }
    (*list)[(*count)++] = (cli_io_entry){copy, label, folder};
}

void cli_io_input(cli_io *io, const char *path, const char *label_fmt, ...) {
    va_list args;
    va_start(args, label_fmt);
    char *label = format_label(label_fmt, args);
    va_end(args);
    if (label == NULL) io->out_of_memory = 1;
    io_add(io, &io->inputs, &io->input_count, &io->input_capacity, path, label, 0);
}

/* An output (a file, or a folder when `folder`), labelled by label_fmt and its arguments (NULL: by its path). */
static void io_add_output(cli_io *io, const char *path, int folder, const char *label_fmt, va_list args) {
    char *label = NULL;
    if (label_fmt != NULL && (label = format_label(label_fmt, args)) == NULL) io->out_of_memory = 1;
    io_add(io, &io->outputs, &io->output_count, &io->output_capacity, path, label, folder);
}

void cli_io_output(cli_io *io, const char *path, const char *label_fmt, ...) {
    va_list args;
    va_start(args, label_fmt);
    io_add_output(io, path, 0, label_fmt, args);
    va_end(args);
}

void cli_io_output_folder(cli_io *io, const char *path, const char *label_fmt, ...) {
    va_list args;
    va_start(args, label_fmt);
    io_add_output(io, path, 1, label_fmt, args);
    va_end(args);
}

void cli_io_material(cli_io *io, const char *const *assignments, const char *const *labels, int count) {
    for (int k = 0; k < count; k++) {
        const char *eq = strchr(assignments[k], '=');
        if (eq == NULL || eq[1] != '@') continue;
        // The file as cli_material_load reads it: "name=@FILE[:r|g|b|a][:linear|srgb]".
        const char *file = eq + 2;
        size_t length = 0;
        int channel;
        mr_map_encoding encoding;
        cli_split_map(file, 1, &length, &channel, &encoding);
        char *path = malloc(length + 1);
        if (path == NULL) {
            io->out_of_memory = 1;
            continue;
        }
        memcpy(path, file, length);
        path[length] = '\0';
        cli_io_input(io, path, "%s", labels != NULL ? labels[k] : assignments[k]);
        free(path);
    }
}

void cli_io_gltf(cli_io *io, const mr_gltf *asset, const char *label) {
    const char *file;
    for (int k = 0; (file = mr_gltf_source_file(asset, k)) != NULL; k++)
        if (k == 0)
            cli_io_input(io, file, "%s", label);
        else
            cli_io_input(io, file, "a file of %s", label);
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

int cli_gltf_scene_load(const char *command, const char *path, cli_io *io, mr_gltf_scene **out) {
    mr_gltf *asset = NULL;
    mr_status status = mr_gltf_load(path, &asset);
    if (status == MR_OK) {
        char label[4096 + 8];
        snprintf(label, sizeof label, "asset %s", path);
        cli_io_gltf(io, asset, label);
        int code = cli_io_check(io);
        if (code != CLI_EXIT_OK) {
            mr_gltf_free(asset);
            return code;
        }
        status = mr_gltf_scene_from_asset(asset, NULL, out);
    }
    mr_gltf_free(asset);
    return status == MR_OK ? CLI_EXIT_OK : cli_fail(command, status);
}

/* 1 if `inner` (an existing file or folder) lies inside the existing folder `folder`, or is it: some folder on
 * the way from inner's real path up to the root is the folder (device and inode). */
static int io_inside(const char *inner, const struct stat *folder) {
    char *real = realpath(inner, NULL);
    if (real == NULL) return 0;
    int inside = 0;
    for (;;) { // "/a/b/c", "/a/b", "/a", "/"
        struct stat st;
        if (stat(real, &st) == 0 && st.st_dev == folder->st_dev && st.st_ino == folder->st_ino) {
            inside = 1;
            break;
        }
        char *slash = strrchr(real, '/');
        if (slash == NULL || strcmp(real, "/") == 0) break;
        slash[slash == real] = '\0';
    }
    free(real);
    return inside;
}

/* 1 if outputs a and b are one file, existing or still to be written: the same text, the same existing file, or
 * the same name in the same existing folder ("./x.png" and "x.png" before either is written). */
static int io_same_output(const char *a, const char *b) {
    if (strcmp(a, b) == 0 || cli_same_file(a, b)) return 1;
    const char *name_a = strrchr(a, '/'), *name_b = strrchr(b, '/');
    name_a = name_a ? name_a + 1 : a;
    name_b = name_b ? name_b + 1 : b;
    if (name_a[0] == '\0' || strcmp(name_a, name_b) != 0) return 0;
    char *dir_a = strndup(name_a > a ? a : ".", name_a > a ? (size_t)(name_a - a) : 1);
    char *dir_b = strndup(name_b > b ? b : ".", name_b > b ? (size_t)(name_b - b) : 1);
    int same = dir_a != NULL && dir_b != NULL && cli_same_file(dir_a, dir_b);
    free(dir_a);
    free(dir_b);
    return same;
}

/* "output 'PATH'" or "output 'PATH' (LABEL)", as messages name an output. */
static void io_print_output(const char *command, const cli_io_entry *out) {
    fprintf(stderr, "matremap %s: error: output %s'%s'", command, out->folder ? "folder " : "", out->path);
    if (out->label != NULL) fprintf(stderr, " (%s)", out->label);
}

/* The folders cli_io_check made in this process, in the order made (cli_io_unmake_folders). */
#define MAX_MADE_FOLDERS 64
static char *made_folders[MAX_MADE_FOLDERS];
static int made_folder_count;

void cli_io_unmake_folders(void) {
    while (made_folder_count > 0) {
        char *folder = made_folders[--made_folder_count];
        rmdir(folder); // fails, as it should, on a folder that holds anything
        free(folder);
    }
}

/* Make the folder `folder` and every missing folder above it (mkdir -p; the umask applies). 0, or -1 with errno set
 * and `failed` (size bytes) naming the folder that could not be made: a missing one that mkdir refused, or a
 * component that is there but is not a folder (ENOTDIR). */
static int make_folders(const char *folder, char *failed, size_t size) {
    char path[4096];
    const size_t length = strlen(folder);
    if (length == 0 || length >= sizeof path) {
        snprintf(failed, size, "%s", folder);
        errno = length ? ENAMETOOLONG : ENOENT;
        return -1;
    }
    memcpy(path, folder, length + 1);
    // From the top down: "a", "a/b", "a/b/c" (a leading '/' and repeated slashes are skipped).
    for (size_t end = 1; end <= length; end++) {
        if (path[end] != '/' && path[end] != '\0') continue;
        if (path[end - 1] == '/') continue;
        const char kept = path[end];
        path[end] = '\0';
        struct stat st;
        if (stat(path, &st) == 0) {
            if (!S_ISDIR(st.st_mode)) {
                snprintf(failed, size, "%s", path);
                errno = ENOTDIR;
                return -1;
            }
        } else if (mkdir(path, 0777) == 0) {
            // Recorded so that a failed run removes it; one that cannot be recorded (out of memory) is not kept.
            if (made_folder_count < MAX_MADE_FOLDERS) {
                char *kept_path = strdup(path);
                if (kept_path == NULL) {
                    rmdir(path);
                    snprintf(failed, size, "%s", path);
                    errno = ENOMEM;
                    return -1;
                }
                made_folders[made_folder_count++] = kept_path;
            }
        } else if (errno != EEXIST) { // EEXIST: made meanwhile by another process
            snprintf(failed, size, "%s", path);
            return -1;
        }
        path[end] = kept;
    }
    return 0;
}

/* The folder an output is written in (for a folder output, the one it is made beside), when the path names one:
 * "a/b/c/out.png" -> "a/b/c", "out.png" -> "" (the working folder, which exists). */
static void output_parent(const char *path, char *parent, size_t size) {
    size_t length = strlen(path);
    while (length > 1 && path[length - 1] == '/') length--; // "report/" is the folder "report"
    size_t slash = length;
    while (slash > 0 && path[slash - 1] != '/') slash--;
    if (slash == 0) {
        parent[0] = '\0';
        return;
    }
    size_t keep = slash - 1;
    while (keep > 0 && path[keep - 1] == '/') keep--; // "a//b" -> "a"
    if (keep == 0) keep = 1;                          // "/out.png" -> "/"
    snprintf(parent, size, "%.*s", (int)keep, path);
}

/* Make the missing folders every output is to be written in (cli.h). */
static int io_make_folders(const cli_io *io) {
    for (int o = 0; o < io->output_count; o++) {
        const cli_io_entry *out = &io->outputs[o];
        char parent[4096], failed[4096];
        output_parent(out->path, parent, sizeof parent);
        if (parent[0] == '\0' || make_folders(parent, failed, sizeof failed) == 0) continue;
        const int err = errno;
        io_print_output(io->command, out);
        fprintf(stderr, ": cannot create the folder '%s': %s\n", failed, strerror(err));
        return CLI_EXIT_BAD_INPUT;
    }
    return CLI_EXIT_OK;
}

int cli_io_check(const cli_io *io) {
    if (io->out_of_memory) {
        fprintf(stderr, "matremap %s: error: out of memory listing the inputs and outputs\n", io->command);
        return CLI_EXIT_INTERNAL;
    }
    for (int o = 0; o < io->output_count; o++) {
        const cli_io_entry *out = &io->outputs[o];
        struct stat st;
        if (stat(out->path, &st) != 0) continue; // not there yet: no input can be it
        for (int i = 0; i < io->input_count; i++) {
            const cli_io_entry *in = &io->inputs[i];
            const int hit =
                out->folder && S_ISDIR(st.st_mode) ? io_inside(in->path, &st) : cli_same_file(out->path, in->path);
            if (!hit) continue;
            io_print_output(io->command, out);
            if (out->folder && !cli_same_file(out->path, in->path))
                fprintf(stderr, " holds the input %s; refusing to replace it\n", in->label);
            else
                fprintf(stderr, " is the input %s; refusing to overwrite it\n", in->label);
            return CLI_EXIT_BAD_INPUT;
        }
    }
    for (int o = 0; o < io->output_count; o++)
        for (int p = 0; p < o; p++) {
            const cli_io_entry *a = &io->outputs[p], *b = &io->outputs[o];
            if (!io_same_output(a->path, b->path)) continue;
            io_print_output(io->command, b);
            fprintf(stderr, " is also the output '%s'", a->path);
            if (a->label != NULL) fprintf(stderr, " (%s)", a->label);
            fprintf(stderr, "; refusing to write one over the other\n");
            return CLI_EXIT_BAD_INPUT;
        }
    return io_make_folders(io);
}

void cli_io_free(cli_io *io) {
    for (int k = 0; k < io->input_count; k++) {
        free(io->inputs[k].path);
        free(io->inputs[k].label);
    }
    for (int k = 0; k < io->output_count; k++) {
        free(io->outputs[k].path);
        free(io->outputs[k].label);
    }
    free(io->inputs);
    free(io->outputs);
    cli_io_init(io, io->command);
}

mr_status cli_check_radiance(const mr_image *image, const char *path) {
    char label[4096 + 16];
    snprintf(label, sizeof label, "image '%s'", path);
    return mr_image_check_radiance(image, label);
}

void cli_split_map(const char *text, int channels, size_t *path_length, int *channel, mr_map_encoding *encoding) {
    mr_map_ref_split(text, channels, path_length, channel, encoding);
}

int cli_check_map(const char *command, const char *label, const char *text, int channels) {
    mr_status status = mr_map_ref_check(label, text, channels);
    if (status == MR_ERR_INVALID_ARG) return cli_usage_error(command, "%s", mr_last_error());
    return status == MR_OK ? CLI_EXIT_OK : cli_fail(command, status);
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
