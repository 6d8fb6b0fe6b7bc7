/* cli_output.c — text files the commands write themselves, atomically (contract in cli.h). */
#include <errno.h>
#include <stdio.h>
#include <string.h>

#include "cli.h"

int cli_output_name(char *out, size_t size, const char *prefix, const char *name) {
    const size_t length = strlen(prefix);
    const int direct = length == 0 || strchr("/_-.", prefix[length - 1]) != NULL;
    const int n = snprintf(out, size, "%s%s%s", prefix, direct ? "" : "_", name);
    return n >= 0 && (size_t)n < size;
}

FILE *cli_output_open(const char *command, const char *path, mr_atomic_file *file) {
    mr_status status = mr_atomic_begin(path, file);
    if (status != MR_OK) {
        cli_fail(command, status);
        return NULL;
    }
    FILE *f = fopen(file->tmp_path, "w");
    if (f == NULL) {
        int err = errno;
        mr_atomic_abort(file);
        fprintf(stderr, "matremap %s: error: cannot write '%s': %s\n", command, path, strerror(err));
    }
    return f;
}

int cli_output_close(const char *command, FILE *f, mr_atomic_file *file) {
    // A failed write leaves the stream's error indicator and its errno; fclose may fail by itself (the last flush).
    const int bad = ferror(f);
    const int write_errno = errno;
    errno = 0;
    const int closed = fclose(f) == 0;
    int err = !closed ? errno : bad ? write_errno : 0;
    if (closed && !bad)
        return 1;
    if (err == 0)
        err = EIO;
    fprintf(stderr, "matremap %s: error: cannot write '%s': %s\n", command, file->target, strerror(err));
    mr_atomic_abort(file);
    return 0;
}

int cli_gnuplot_close(const char *command, FILE *plot, int *drawn) {
    *drawn = 0;
    if (plot == NULL)
        return 1;
    const int bad = ferror(plot);
    const int err = errno;
    const int rc = pclose(plot);
    if (bad) {
        fprintf(stderr, "matremap %s: error: cannot write the plot script to gnuplot: %s\n", command,
                strerror(err ? err : EIO));
        return 0;
    }
    *drawn = rc == 0;
    return 1;
}

void cli_outputs_abort(mr_atomic_file *files, int n) {
    for (int i = 0; i < n; i++)
        mr_atomic_abort(&files[i]);
}

int cli_outputs_commit(const char *command, mr_atomic_file *files, int n, const char *const *written, int n_written) {
    for (int i = 0; i < n; i++) {
        if (!files[i].active)
            continue;
        mr_status status = mr_atomic_commit(&files[i]);
        if (status == MR_OK) {
            files[i].tmp_path[0] = '\0'; // marks it committed for the clean-up below
            continue;
        }
        // Leave none of this run's outputs: a set of files half replaced would not belong together.
        for (int k = 0; k < i; k++)
            if (files[k].target != NULL && files[k].tmp_path[0] == '\0')
                remove(files[k].target);
        for (int k = 0; k < n_written; k++)
            remove(written[k]);
        cli_outputs_abort(files, n);
        fprintf(stderr, "matremap %s: error: %s (the outputs written before it removed)\n", command, mr_last_error());
        return 0;
    }
    return 1;
}
