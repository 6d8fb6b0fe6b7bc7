/*
 * atomic_file.c — write-to-temporary-then-rename for every output file (protocol in mr_core.h).
 *
 * After redis' rdbSave(): the data goes to a temporary file in the target's directory; only when every write,
 * flush and close has succeeded is it fsync'ed and rename(2)d over the target, which POSIX makes atomic, so
 * readers see either the old file or the complete new one. The temporary name carries the process id and a
 * per-process counter and is created with O_EXCL, so concurrent writers (threads or processes) never share
 * one; it is created with mode 0666 filtered by the umask, like any ordinary output file.
 */
#include <errno.h>
#include <fcntl.h>
#include <stdatomic.h>
#include <stdio.h>
#include <string.h>
#include <unistd.h>

#include "../mr_internal.h"
#include "io_internal.h"

static atomic_uint counter;

mr_status mr_atomic_begin(const char *target, mr_atomic_file *file) {
    file->active = 0;
    file->target = target;
    file->tmp_path[0] = '\0';
    if (target == NULL || target[0] == '\0') return mr_fail(MR_ERR_INVALID_ARG, "output file: empty path");
    for (int attempt = 0; attempt < 100; attempt++) {
        unsigned n = atomic_fetch_add(&counter, 1u);
        int len = snprintf(file->tmp_path, sizeof file->tmp_path, "%s.tmp.%ld.%u", target, (long)getpid(), n);
        if (len < 0 || (size_t)len >= sizeof file->tmp_path) {
            file->tmp_path[0] = '\0';
            return mr_fail(MR_ERR_INVALID_ARG, "output file '%s': path too long", target);
        }
        int fd = open(file->tmp_path, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
        if (fd >= 0) {
            if (close(fd) != 0) {
                int err = errno;
                unlink(file->tmp_path);
                return mr_fail(MR_ERR_IO, "output file '%s': cannot create temporary file '%s': %s", target,
                               file->tmp_path, strerror(err));
            }
            file->active = 1;
            return MR_OK;
        }
        if (errno != EEXIST) {
            int err = errno;
            return mr_fail(MR_ERR_IO, "output file '%s': cannot create a file in its directory: %s", target,
                           strerror(err));
        }
        /* A stale temporary of a crashed process with the same pid: try the next counter value. */
    }
    return mr_fail(MR_ERR_IO, "output file '%s': cannot find a free temporary name (last tried '%s')", target,
                   file->tmp_path);
}

mr_status mr_atomic_commit(mr_atomic_file *file) {
    if (!file->active)
        return mr_fail(MR_ERR_INVALID_ARG, "output file '%s': commit without a temporary file",
                       file->target ? file->target : "");
    /* Make the data durable before the rename publishes it (otherwise a crash could leave an empty target). */
    int fd = open(file->tmp_path, O_RDONLY | O_CLOEXEC);
    if (fd < 0 || fsync(fd) != 0) {
        int err = errno;
        if (fd >= 0) close(fd);
        mr_atomic_abort(file);
        return mr_fail(MR_ERR_IO, "output file '%s': cannot flush temporary file '%s': %s", file->target,
                       file->tmp_path, strerror(err));
    }
    if (close(fd) != 0) {
        int err = errno;
        mr_atomic_abort(file);
        return mr_fail(MR_ERR_IO, "output file '%s': cannot close temporary file: %s", file->target, strerror(err));
    }
    if (rename(file->tmp_path, file->target) != 0) {
        int err = errno;
        mr_atomic_abort(file);
        return mr_fail(MR_ERR_IO, "output file '%s': cannot rename the finished temporary file over it: %s",
                       file->target, strerror(err));
    }
    file->active = 0;
    return MR_OK;
}

mr_status mr_atomic_write_bytes(const char *target, const void *bytes, size_t size) {
    mr_atomic_file file;
    mr_status status = mr_atomic_begin(target, &file);
    if (status != MR_OK) return status;
    FILE *out = fopen(file.tmp_path, "wb");
    if (out == NULL) {
        int err = errno;
        mr_atomic_abort(&file);
        return mr_fail(MR_ERR_IO, "output file '%s': cannot open temporary file: %s", target, strerror(err));
    }
    /* errno is read right at each failure, before any other call can change it */
    int err = 0;
    errno = 0;
    if (size > 0 && fwrite(bytes, 1, size, out) != size) err = errno ? errno : EIO;
    if (err == 0) {
        errno = 0;
        if (fflush(out) != 0) err = errno ? errno : EIO;
    }
    errno = 0;
    if (fclose(out) != 0 && err == 0) err = errno ? errno : EIO;
    if (err != 0) {
        mr_atomic_abort(&file);
        return mr_fail(MR_ERR_IO, "output file '%s': cannot write %zu bytes: %s", target, size, strerror(err));
    }
    return mr_atomic_commit(&file);
}

void mr_atomic_abort(mr_atomic_file *file) {
    if (!file->active) return;
    int saved = errno;
    unlink(file->tmp_path); /* ENOENT (a library already removed it) is fine */
    errno = saved;
    file->active = 0;
}

mr_status mr_atomic_open_text(const char *target, mr_atomic_file *file, FILE **out) {
    *out = NULL;
    mr_status status = mr_atomic_begin(target, file);
    if (status != MR_OK) return status;
    *out = fopen(file->tmp_path, "w");
    if (*out != NULL) return MR_OK;
    int err = errno;
    mr_atomic_abort(file);
    return mr_fail(MR_ERR_IO, "cannot write '%s': %s", target, strerror(err));
}

mr_status mr_atomic_close_text(FILE *f, mr_atomic_file *file) {
    // A failed write leaves the stream's error indicator and its errno; fclose may fail by itself (the last flush).
    const int bad = ferror(f);
    const int write_errno = errno;
    errno = 0;
    const int closed = fclose(f) == 0;
    int err = !closed ? errno : bad ? write_errno : 0;
    if (closed && !bad) return MR_OK;
    if (err == 0) err = EIO;
    mr_status status = mr_fail(MR_ERR_IO, "cannot write '%s': %s", file->target, strerror(err));
    mr_atomic_abort(file);
    return status;
}

mr_status mr_atomic_commit_set(mr_atomic_file *files, int n, const char *const *written, int n_written) {
    for (int i = 0; i < n; i++) {
        if (!files[i].active) continue;
        if (mr_atomic_commit(&files[i]) == MR_OK) {
            files[i].tmp_path[0] = '\0'; // marks it committed for the clean-up below
            continue;
        }
        // Leave none of this set: files half replaced would not belong together.
        char why[1024];
        snprintf(why, sizeof why, "%s", mr_last_error());
        for (int k = 0; k < i; k++)
            if (files[k].target != NULL && files[k].tmp_path[0] == '\0') remove(files[k].target);
        for (int k = 0; k < n_written; k++) remove(written[k]);
        for (int k = 0; k < n; k++) mr_atomic_abort(&files[k]);
        return mr_fail(MR_ERR_IO, "%s (the outputs written before it removed)", why);
    }
    return MR_OK;
}
