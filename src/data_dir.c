/* data_dir.c — where the library finds its installed data files (mr_core.h, mr_data_path) and its modules
 * (mr_internal.h, mr_module_beside_executable): beside the executable, and beside the library itself when it is the
 * shared libmatremap.so (a program without matremap's executable, e.g. Python: dladdr on a function of ours names
 * the file it lives in; in a static link that is the executable again). */
#define _GNU_SOURCE 1 /* dladdr */
#include <dlfcn.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "mr_internal.h"

#ifndef MR_MODULE_DIR
#define MR_MODULE_DIR "/usr/local/lib/matremap"
#endif
#ifndef MR_DATA_DIR
#define MR_DATA_DIR "/usr/local/share/matremap"
#endif

/* Cut the last path component off `path` in place; 0 if there is none. */
static int cut_last(char *path) {
    char *slash = strrchr(path, '/');
    if (slash == NULL) return 0;
    *slash = '\0';
    return 1;
}

/* The directory of the file holding this code (libmatremap.so's, or the executable's in a static link) in out; 0 when
 * dladdr cannot tell or it is the executable's (which the callers try first). */
static const char library_anchor = 0; // an object of ours: ISO C has no function-to-object pointer cast

static int library_dir(char *out, size_t size) {
    Dl_info info;
    if (dladdr(&library_anchor, &info) == 0 || info.dli_fname == NULL || info.dli_fname[0] != '/') return 0;
    char exe[PATH_MAX];
    ssize_t length = readlink("/proc/self/exe", exe, sizeof exe - 1);
    if (length > 0) {
        exe[length] = '\0';
        if (strcmp(exe, info.dli_fname) == 0) return 0;
    }
    if (strlen(info.dli_fname) >= size) return 0;
    memcpy(out, info.dli_fname, strlen(info.dli_fname) + 1);
    return cut_last(out);
}

mr_status mr_data_path(const char *file, char *out, size_t size) {
    if (file == NULL || file[0] == '\0' || out == NULL || size == 0)
        return mr_fail(MR_ERR_INVALID_ARG, "data file: NULL or empty argument");
    // The same places as the OpenImageIO module (src/io/oiio_module.c): beside the executable first, so a build
    // tree and a relocated install find their own files, then the install directory fixed at build time.
    char tried[7][PATH_MAX + 64];
    int count = 0;
    char exe[PATH_MAX];
    ssize_t length = readlink("/proc/self/exe", exe, sizeof exe - 1);
    if (length > 0) {
        exe[length] = '\0';
        if (cut_last(exe) && cut_last(exe)) { // exe is now the executable's directory's parent
            snprintf(tried[count++], sizeof tried[0], "%s/share/matremap/%s", exe, file); // PREFIX/bin -> share
            // The source tree's data/ above build/bin, or above build/asan/bin (make asan's build).
            for (int up = 0; up < 2 && cut_last(exe); up++)
                snprintf(tried[count++], sizeof tried[0], "%s/data/%s", exe, file);
        }
    }
    // The shared library: PREFIX/lib -> PREFIX/share/matremap; the build tree's build/lib -> build/share/matremap,
    // and the source tree's data/ above build/lib (or build/asan/lib).
    char lib[PATH_MAX];
    if (library_dir(lib, sizeof lib) && cut_last(lib)) {
        snprintf(tried[count++], sizeof tried[0], "%s/share/matremap/%s", lib, file);
        for (int up = 0; up < 2 && cut_last(lib); up++)
            snprintf(tried[count++], sizeof tried[0], "%s/data/%s", lib, file);
    }
    snprintf(tried[count++], sizeof tried[0], "%s/%s", MR_DATA_DIR, file);
    for (int k = 0; k < count; k++)
        if (access(tried[k], R_OK) == 0) {
            if (strlen(tried[k]) >= size) return mr_fail(MR_ERR_INVALID_ARG, "data file '%s': path too long", tried[k]);
            memcpy(out, tried[k], strlen(tried[k]) + 1);
            return MR_OK;
        }
    char list[7 * (PATH_MAX + 64) + 8] = "";
    for (int k = 0; k < count; k++) snprintf(list + strlen(list), sizeof list - strlen(list), "%s%s", k ? ", " : "",
                                             tried[k]);
    return mr_fail(MR_ERR_IO, "data file '%s' not found (tried %s)", file, list);
}

int mr_module_beside_executable(const char *file, char *out, size_t size) {
    char exe[PATH_MAX];
    ssize_t length = readlink("/proc/self/exe", exe, sizeof exe - 1);
    if (length > 0) {
        exe[length] = '\0';
        int n = cut_last(exe) ? snprintf(out, size, "%s/../lib/matremap/%s", exe, file) : -1;
        if (n > 0 && (size_t)n < size && access(out, F_OK) == 0) return 1;
    }
    // The shared library: its modules in the matremap/ folder beside it (PREFIX/lib/matremap, build/lib/matremap).
    char lib[PATH_MAX];
    if (!library_dir(lib, sizeof lib)) return 0;
    int n = snprintf(out, size, "%s/matremap/%s", lib, file);
    return n > 0 && (size_t)n < size && access(out, F_OK) == 0;
}

/* Append "PATH: TEXT" to why[size], after "; " when it holds a reason already. */
static void append_why(char *why, size_t size, const char *path, const char *text) {
    size_t used = strlen(why);
    if (used + 1 < size) snprintf(why + used, size - used, "%s%s: %s", used ? "; " : "", path, text);
}

/* The candidate at `path`: its handle with every symbol in entries[], or NULL (and why appended). */
static void *open_candidate(const mr_module_spec *spec, const char *path, void **entries, char *why, size_t size) {
    void *handle = dlopen(path, RTLD_NOW | RTLD_LOCAL);
    if (handle == NULL) {
        const char *reason = dlerror(); // names the path itself
        size_t used = strlen(why);
        if (used + 1 < size)
            snprintf(why + used, size - used, "%s%s", used ? "; " : "", reason != NULL ? reason : path);
        return NULL;
    }
    char reason[512];
    for (int k = 0; k < spec->symbol_count; k++) {
        entries[k] = dlsym(handle, spec->symbols[k]);
        if (entries[k] == NULL) {
            snprintf(reason, sizeof reason, "not a matremap %s module (no %s)", spec->kind, spec->symbols[k]);
            append_why(why, size, path, reason);
            dlclose(handle);
            return NULL;
        }
    }
    if (spec->check != NULL && spec->check(entries, reason, sizeof reason) != NULL) {
        append_why(why, size, path, reason);
        dlclose(handle);
        return NULL;
    }
    return handle;
}

void *mr_module_open(const mr_module_spec *spec, void **entries, char *why, size_t size) {
    const char *override = getenv(spec->variable);
    if (override != NULL && override[0] != '\0') return open_candidate(spec, override, entries, why, size);
    char candidate[PATH_MAX + 64];
    void *handle = NULL;
    if (mr_module_beside_executable(spec->file, candidate, sizeof candidate))
        handle = open_candidate(spec, candidate, entries, why, size);
    if (handle == NULL) {
        snprintf(candidate, sizeof candidate, "%s/%s", MR_MODULE_DIR, spec->file);
        handle = open_candidate(spec, candidate, entries, why, size);
    }
    return handle;
}
