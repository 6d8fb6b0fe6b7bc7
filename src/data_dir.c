/* data_dir.c — where the library finds its installed data files (mr_core.h, mr_data_path) and its modules
 * (mr_internal.h, mr_module_beside_executable). */
#include <limits.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "mr_internal.h"

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

mr_status mr_data_path(const char *file, char *out, size_t size) {
    if (file == NULL || file[0] == '\0' || out == NULL || size == 0)
        return mr_fail(MR_ERR_INVALID_ARG, "data file: NULL or empty argument");
    // The same places as the OpenImageIO module (src/io/oiio_module.c): beside the executable first, so a build
    // tree and a relocated install find their own files, then the install directory fixed at build time.
    char tried[4][PATH_MAX + 64];
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
    snprintf(tried[count++], sizeof tried[0], "%s/%s", MR_DATA_DIR, file);
    for (int k = 0; k < count; k++)
        if (access(tried[k], R_OK) == 0) {
            if (strlen(tried[k]) >= size) return mr_fail(MR_ERR_INVALID_ARG, "data file '%s': path too long", tried[k]);
            memcpy(out, tried[k], strlen(tried[k]) + 1);
            return MR_OK;
        }
    char list[4 * (PATH_MAX + 64) + 8] = "";
    for (int k = 0; k < count; k++) snprintf(list + strlen(list), sizeof list - strlen(list), "%s%s", k ? ", " : "",
                                             tried[k]);
    return mr_fail(MR_ERR_IO, "data file '%s' not found (tried %s)", file, list);
}

int mr_module_beside_executable(const char *file, char *out, size_t size) {
    char exe[PATH_MAX];
    ssize_t length = readlink("/proc/self/exe", exe, sizeof exe - 1);
    if (length <= 0) return 0;
    exe[length] = '\0';
    if (!cut_last(exe)) return 0;
    int n = snprintf(out, size, "%s/../lib/matremap/%s", exe, file);
    return n > 0 && (size_t)n < size && access(out, F_OK) == 0;
}
