/*
 * input_file.c — opening a file the user names as an input (mr_core.h, "input files").
 *
 * Why not fopen: a path from the command line or from inside a downloaded file (a glTF URI) may name a folder, a
 * FIFO, a terminal or a device such as /dev/zero. fopen opens a folder happily (and a reader that asks its size by
 * seeking to the end gets 2^63 - 1 from ext4, then tries to allocate that), blocks forever on a FIFO without a
 * writer, and reads /dev/zero until memory runs out. So the file is opened without blocking (O_NONBLOCK: a FIFO
 * opens at once), its type and size taken from the open descriptor (fstat: no window between the check and the
 * read for the file to be swapped), and only a regular file is handed on, as a blocking stdio stream.
 */
#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "../mr_internal.h"
#include "io_internal.h"

/* What a non-regular file is, for the message. */
static const char *kind_of(mode_t mode) {
    if (S_ISFIFO(mode))
        return "a FIFO";
    if (S_ISCHR(mode))
        return "a character device";
    if (S_ISBLK(mode))
        return "a block device";
    if (S_ISSOCK(mode))
        return "a socket";
    return "not a file";
}

/* The message: "<label>: <why>", or <why> alone when label is NULL. */
#define INPUT_FAIL(status, label, ...)                                                                                 \
    ((label) != NULL ? mr_fail_context(mr_fail(status, __VA_ARGS__), "%s", (label)) : mr_fail(status, __VA_ARGS__))

mr_status mr_io_open_input(const char *path, const char *label, uint64_t max_bytes, FILE **out, uint64_t *size) {
    if (path == NULL || out == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "mr_io_open_input: NULL path or output");
    *out = NULL;
    int fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    if (fd < 0) {
        const int err = errno;
        return INPUT_FAIL(MR_ERR_IO, label, "cannot open: %s", strerror(err));
    }
    struct stat st;
    if (fstat(fd, &st) != 0) {
        const int err = errno;
        close(fd);
        return INPUT_FAIL(MR_ERR_IO, label, "cannot read: %s", strerror(err));
    }
    if (S_ISDIR(st.st_mode)) {
        close(fd);
        return INPUT_FAIL(MR_ERR_IO, label, "is a directory");
    }
    if (!S_ISREG(st.st_mode)) {
        close(fd);
        return INPUT_FAIL(MR_ERR_IO, label, "is not a regular file (%s)", kind_of(st.st_mode));
    }
    if (max_bytes > 0 && (uint64_t)st.st_size > max_bytes) {
        close(fd);
        return INPUT_FAIL(MR_ERR_FORMAT, label, "%llu bytes, more than the limit of %llu",
                          (unsigned long long)st.st_size, (unsigned long long)max_bytes);
    }
    // Blocking again for the reads (a regular file never blocks, but stdio need not know about O_NONBLOCK).
    const int flags = fcntl(fd, F_GETFL);
    if (flags < 0 || fcntl(fd, F_SETFL, flags & ~O_NONBLOCK) != 0) {
        const int err = errno;
        close(fd);
        return INPUT_FAIL(MR_ERR_IO, label, "cannot read: %s", strerror(err));
    }
    FILE *f = fdopen(fd, "rb");
    if (f == NULL) {
        const int err = errno;
        close(fd);
        return INPUT_FAIL(err == ENOMEM ? MR_ERR_NOMEM : MR_ERR_IO, label, "cannot open: %s", strerror(err));
    }
    if (size != NULL)
        *size = (uint64_t)st.st_size;
    *out = f;
    return MR_OK;
}
