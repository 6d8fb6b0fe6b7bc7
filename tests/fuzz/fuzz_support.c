/*
 * fuzz_support.c — the scratch folder the path-based readers are fuzzed through (contract in fuzz.h).
 */
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "fuzz.h"
#include "matremap.h"

static char scratch_dir[512];
static char scratch_path[1024];

static void remove_scratch(void) {
    // The folder holds what the targets wrote (inputs and what the glTF writer saved): remove it whole.
    char command[600];
    if (scratch_dir[0] == '\0') return;
    snprintf(command, sizeof command, "rm -rf '%s'", scratch_dir);
    if (system(command) != 0) return;
}

const char *fuzz_scratch_path(const char *name) {
    if (scratch_dir[0] == '\0') {
        // $TMPDIR, else /dev/shm: a file rewritten at every execution on ext4 is flushed to the disk at each
        // close (its replace-by-truncate heuristic), which made the file-reading targets 3x slower.
        const char *tmp = getenv("TMPDIR");
        if (tmp == NULL || tmp[0] == '\0') tmp = access("/dev/shm", W_OK) == 0 ? "/dev/shm" : "/tmp";
        snprintf(scratch_dir, sizeof scratch_dir, "%s/matremap-fuzz-XXXXXX", tmp);
        if (mkdtemp(scratch_dir) == NULL) {
            scratch_dir[0] = '\0';
            return NULL;
        }
        atexit(remove_scratch);
    }
    snprintf(scratch_path, sizeof scratch_path, "%s/%s", scratch_dir, name);
    return scratch_path;
}

const char *fuzz_write_scratch(const char *name, const uint8_t *data, size_t size) {
    const char *path = fuzz_scratch_path(name);
    if (path == NULL) return NULL;
    int fd = open(path, O_WRONLY | O_CREAT | O_TRUNC, 0600);
    if (fd < 0) return NULL;
    size_t done = 0;
    while (done < size) {
        ssize_t n = write(fd, data + done, size - done);
        if (n <= 0) {
            close(fd);
            return NULL;
        }
        done += (size_t)n;
    }
    close(fd);
    return path;
}

void fuzz_require_setup(void) {
    static int checked;
    if (checked) return;
    checked = 1;
    static const char pixel[] = "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 1 +X 1\n\x80\x80\x80\x81";
    mr_image *image = NULL;
    if (mr_img_read_memory(pixel, sizeof pixel - 1, "the set-up check's pixel", NULL, &image, NULL) != MR_OK) {
        fprintf(stderr, "fuzz: the build is incomplete: %s\n", mr_last_error());
        abort();
    }
    mr_image_free(image);
}
