/* output_plan.c — no output replaces an input: a job's files listed and checked, its folders made (contract in
 * output_plan.h). */
#define _XOPEN_SOURCE 700 /* realpath (X/Open): where an input lies, for folder outputs */
#include "io/output_plan.h"

#include <errno.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "mr_internal.h"

#define OUT_OF_MEMORY_LISTING "out of memory listing the inputs and outputs"

/* 1 if a and b name the same existing file (st_dev and st_ino: links, "./x" and other spellings included). */
static int same_file(const char *a, const char *b) {
    struct stat sa, sb;
    return stat(a, &sa) == 0 && stat(b, &sb) == 0 && sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
}

/* ---- listing ------------------------------------------------------------------------------------------------ */

static char *format_label(const char *fmt, va_list args) {
    va_list copy;
    va_copy(copy, args);
    int n = vsnprintf(NULL, 0, fmt, copy);
    va_end(copy);
    char *label = n >= 0 ? malloc((size_t)n + 1) : NULL;
    if (label != NULL) vsnprintf(label, (size_t)n + 1, fmt, args);
    return label;
}

/* The plan remembers a failed registration, so that the next check reports it. */
static mr_status out_of_memory(mr_output_plan *plan) {
    plan->out_of_memory = 1;
    return mr_fail(MR_ERR_NOMEM, OUT_OF_MEMORY_LISTING);
}

/* Append (path, label) to the inputs, or to the outputs when `output`; the label (may be NULL) is taken over. On
 * failure the label is freed and the plan remembers it. A NULL path lists nothing. */
static mr_status add(mr_output_plan *plan, int output, const char *path, char *label, int folder) {
    mr_output_plan_entry **list = output ? &plan->outputs : &plan->inputs;
    int *count = output ? &plan->output_count : &plan->input_count;
    int *capacity = output ? &plan->output_capacity : &plan->input_capacity;
    char *copy = path != NULL ? strdup(path) : NULL;
    if (copy != NULL && *count == *capacity) {
        int grown = *capacity ? 2 * *capacity : 16;
        mr_output_plan_entry *more = realloc(*list, (size_t)grown * sizeof *more);
        if (more != NULL) {
            *list = more;
            *capacity = grown;
        }
    }
    if (copy == NULL || *count == *capacity) {
        free(copy);
        free(label);
        return path != NULL ? out_of_memory(plan) : MR_OK;
    }
    (*list)[(*count)++] = (mr_output_plan_entry){copy, label, folder};
    return MR_OK;
}

/* A copy of `label` (NULL for NULL); *failed set when it cannot be made. */
static char *copy_label(const char *label, int *failed) {
    char *copy = label != NULL ? strdup(label) : NULL;
    *failed = label != NULL && copy == NULL;
    return copy;
}

static mr_status add_copied(mr_output_plan *plan, int output, const char *path, const char *label, int folder) {
    if (plan == NULL) return mr_fail(MR_ERR_INVALID_ARG, "output plan: NULL plan");
    int failed;
    char *copy = copy_label(label, &failed);
    if (failed) return out_of_memory(plan);
    return add(plan, output, path, copy, folder);
}

mr_status mr_output_plan_input(mr_output_plan *plan, const char *path, const char *label) {
    return add_copied(plan, 0, path, label, 0);
}

mr_status mr_output_plan_output(mr_output_plan *plan, const char *path, const char *label) {
    return add_copied(plan, 1, path, label, 0);
}

mr_status mr_output_plan_output_folder(mr_output_plan *plan, const char *path, const char *label) {
    return add_copied(plan, 1, path, label, 1);
}

/* An entry labelled by label_fmt and its arguments (NULL: no label). */
static mr_status add_formatted(mr_output_plan *plan, int output, const char *path, const char *label_fmt,
                               va_list args) {
    if (plan == NULL) return mr_fail(MR_ERR_INVALID_ARG, "output plan: NULL plan");
    char *label = NULL;
    if (label_fmt != NULL && (label = format_label(label_fmt, args)) == NULL) return out_of_memory(plan);
    return add(plan, output, path, label, 0);
}

mr_status mr_output_plan_inputf(mr_output_plan *plan, const char *path, const char *label_fmt, ...) {
    va_list args;
    va_start(args, label_fmt);
    mr_status status = add_formatted(plan, 0, path, label_fmt, args);
    va_end(args);
    return status;
}

mr_status mr_output_plan_outputf(mr_output_plan *plan, const char *path, const char *label_fmt, ...) {
    va_list args;
    va_start(args, label_fmt);
    mr_status status = add_formatted(plan, 1, path, label_fmt, args);
    va_end(args);
    return status;
}

/* ---- checking ----------------------------------------------------------------------------------------------- */

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
    if (strcmp(a, b) == 0 || same_file(a, b)) return 1;
    const char *name_a = strrchr(a, '/'), *name_b = strrchr(b, '/');
    name_a = name_a ? name_a + 1 : a;
    name_b = name_b ? name_b + 1 : b;
    if (name_a[0] == '\0' || strcmp(name_a, name_b) != 0) return 0;
    char *dir_a = strndup(name_a > a ? a : ".", name_a > a ? (size_t)(name_a - a) : 1);
    char *dir_b = strndup(name_b > b ? b : ".", name_b > b ? (size_t)(name_b - b) : 1);
    int same = dir_a != NULL && dir_b != NULL && same_file(dir_a, dir_b);
    free(dir_a);
    free(dir_b);
    return same;
}

/* "output 'PATH'" or "output folder 'PATH' (LABEL)", as messages name an output, into text[size]. */
static void name_output(const mr_output_plan_entry *out, char *text, size_t size) {
    snprintf(text, size, "output %s'%s'%s%s%s", out->folder ? "folder " : "", out->path, out->label ? " (" : "",
             out->label ? out->label : "", out->label ? ")" : "");
}

/* An input as messages name it: its label, or 'PATH' when it has none. */
static void name_input(const mr_output_plan_entry *in, char *text, size_t size) {
    if (in->label != NULL)
        snprintf(text, size, "%s", in->label);
    else
        snprintf(text, size, "'%s'", in->path);
}

/* Record `folder` (just made) in the plan; 0, or -1 when it cannot be (out of memory). */
static int record_folder(mr_output_plan *plan, const char *folder) {
    if (plan->folders_made_count == plan->folders_made_capacity) {
        int grown = plan->folders_made_capacity ? 2 * plan->folders_made_capacity : 8;
        char **more = realloc(plan->folders_made, (size_t)grown * sizeof *more);
        if (more == NULL) return -1;
        plan->folders_made = more;
        plan->folders_made_capacity = grown;
    }
    char *copy = strdup(folder);
    if (copy == NULL) return -1;
    plan->folders_made[plan->folders_made_count++] = copy;
    return 0;
}

/* Make the folder `folder` and every missing folder above it (mkdir -p; the umask applies), each recorded in the
 * plan. 0, or -1 with errno set and `failed` (size bytes) naming the folder that could not be made: a missing one
 * that mkdir refused, or a component that is there but is not a folder (ENOTDIR), or one made that could not be
 * recorded (ENOMEM; removed again). */
static int make_folders(mr_output_plan *plan, const char *folder, char *failed, size_t size) {
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
            if (record_folder(plan, path) != 0) {
                rmdir(path);
                snprintf(failed, size, "%s", path);
                errno = ENOMEM;
                return -1;
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

/* Make the missing folders every output is to be written in (output_plan.h). */
static mr_status io_make_folders(mr_output_plan *plan) {
    for (int o = 0; o < plan->output_count; o++) {
        const mr_output_plan_entry *out = &plan->outputs[o];
        char parent[4096], failed[4096], output[8192];
        output_parent(out->path, parent, sizeof parent);
        if (parent[0] == '\0' || make_folders(plan, parent, failed, sizeof failed) == 0) continue;
        const int err = errno;
        name_output(out, output, sizeof output);
        return mr_fail(err == ENOMEM ? MR_ERR_NOMEM : MR_ERR_IO, "%s: cannot create the folder '%s': %s", output,
                       failed, strerror(err));
    }
    return MR_OK;
}

mr_status mr_output_plan_check(mr_output_plan *plan) {
    if (plan == NULL) return MR_OK;
    if (plan->out_of_memory) return mr_fail(MR_ERR_NOMEM, OUT_OF_MEMORY_LISTING);
    char output[8192], other[8192];
    for (int o = 0; o < plan->output_count; o++) {
        const mr_output_plan_entry *out = &plan->outputs[o];
        struct stat st;
        if (stat(out->path, &st) != 0) continue; // not there yet: no input can be it
        for (int i = 0; i < plan->input_count; i++) {
            const mr_output_plan_entry *in = &plan->inputs[i];
            const int hit =
                out->folder && S_ISDIR(st.st_mode) ? io_inside(in->path, &st) : same_file(out->path, in->path);
            if (!hit) continue;
            name_output(out, output, sizeof output);
            name_input(in, other, sizeof other);
            if (out->folder && !same_file(out->path, in->path))
                return mr_fail(MR_ERR_INVALID_ARG, "%s holds the input %s; refusing to replace it", output, other);
            return mr_fail(MR_ERR_INVALID_ARG, "%s is the input %s; refusing to overwrite it", output, other);
        }
    }
    for (int o = 0; o < plan->output_count; o++)
        for (int p = 0; p < o; p++) {
            const mr_output_plan_entry *a = &plan->outputs[p], *b = &plan->outputs[o];
            if (!io_same_output(a->path, b->path)) continue;
            name_output(b, output, sizeof output);
            return mr_fail(MR_ERR_INVALID_ARG, "%s is also the output '%s'%s%s%s; refusing to write one over the other",
                           output, a->path, a->label ? " (" : "", a->label ? a->label : "", a->label ? ")" : "");
        }
    return io_make_folders(plan);
}

/* ---- folders made, and the end ------------------------------------------------------------------------------ */

void mr_output_plan_unmake_folders(mr_output_plan *plan) {
    if (plan == NULL) return;
    while (plan->folders_made_count > 0) {
        char *folder = plan->folders_made[--plan->folders_made_count];
        rmdir(folder); // fails, as it should, on a folder that holds anything
        free(folder);
    }
}

char **mr_output_plan_take_folders(mr_output_plan *plan, int *count) {
    *count = 0;
    if (plan == NULL) return NULL;
    char **folders = plan->folders_made;
    *count = plan->folders_made_count;
    if (*count == 0) {
        free(folders); // an empty list's spare room
        folders = NULL;
    }
    plan->folders_made = NULL;
    plan->folders_made_count = plan->folders_made_capacity = 0;
    return folders;
}

void mr_output_plan_free(mr_output_plan *plan) {
    if (plan == NULL) return;
    for (int k = 0; k < plan->input_count; k++) {
        free(plan->inputs[k].path);
        free(plan->inputs[k].label);
    }
    for (int k = 0; k < plan->output_count; k++) {
        free(plan->outputs[k].path);
        free(plan->outputs[k].label);
    }
    for (int k = 0; k < plan->folders_made_count; k++) free(plan->folders_made[k]);
    free(plan->inputs);
    free(plan->outputs);
    free(plan->folders_made);
    memset(plan, 0, sizeof *plan);
}
