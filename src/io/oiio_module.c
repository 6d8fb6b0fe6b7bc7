/*
 * oiio_module.c — loads the OpenImageIO shim (libmatremap-oiio.so, image_io_oiio.cpp) on first use and
 * forwards mr_io_oiio_read / mr_io_oiio_read_memory / mr_io_oiio_write to it (contracts in io_internal.h).
 *
 * Why a module: linking OpenImageIO into every program costs ~0.4 s of start-up on Debian 12 (its ~250
 * dependent libraries run their static initialisers, OpenCV's videoio alone 0.2 s), paid even by commands
 * that read no image. Loaded lazily, only commands that decode PNG/JPEG/TIFF/HDR/EXR or encode non-EXR
 * formats pay it, once.
 *
 * Where the module is looked for, in order:
 *   1. the file named by the environment variable MR_OIIO_MODULE, if set;
 *   2. <directory of the running executable>/../lib/matremap/libmatremap-oiio.so — both the build tree
 *      (build/bin, build/tests -> build/lib/matremap) and an installed tree (PREFIX/bin -> PREFIX/lib/matremap);
 *   3. MR_MODULE_DIR/libmatremap-oiio.so, the install directory fixed at build time (for programs elsewhere
 *      that link libmatremap.a).
 * Loading happens once per process (pthread_once); its outcome, success or the reason for failure, is kept.
 */
#include <pthread.h>
#include <stdio.h>
#include <string.h>

#include "../mr_internal.h"
#include "io_internal.h"

#ifndef MR_MODULE_DIR
#define MR_MODULE_DIR "/usr/local/lib/matremap"
#endif

#define MODULE_FILE "libmatremap-oiio.so"

typedef mr_status (*module_read_fn)(const char *, int, mr_io_raw *);
typedef mr_status (*module_read_as_fn)(const char *, const char *, int, mr_io_raw *);
typedef mr_status (*module_read_memory_fn)(const void *, size_t, const char *, const char *, int, mr_io_raw *);
typedef mr_status (*module_write_fn)(const char *, int, int, int, mr_io_sample, const void *, int, int);
typedef const char *(*module_error_fn)(void);

static pthread_once_t load_once = PTHREAD_ONCE_INIT;
static module_read_fn module_read;
static module_read_as_fn module_read_as;
static module_read_memory_fn module_read_memory;
static module_write_fn module_write;
static module_error_fn module_error;
static char load_failure[2048]; /* why loading failed; written once inside pthread_once */

static void load_module(void) {
    static const char *const symbols[] = {"mr_oiio_module_read", "mr_oiio_module_read_as",
                                          "mr_oiio_module_read_memory", "mr_oiio_module_write",
                                          "mr_oiio_module_last_error"};
    static const mr_module_spec spec = {MODULE_FILE, "MR_OIIO_MODULE", "image", symbols, 5, NULL};
    void *entries[5];
    if (mr_module_open(&spec, entries, load_failure, sizeof load_failure) == NULL) return;
    // POSIX allows converting dlsym's void * to a function pointer; ISO C does not, hence the memcpy.
    memcpy(&module_read_as, &entries[1], sizeof entries[1]);
    memcpy(&module_read_memory, &entries[2], sizeof entries[2]);
    memcpy(&module_write, &entries[3], sizeof entries[3]);
    memcpy(&module_error, &entries[4], sizeof entries[4]);
    memcpy(&module_read, &entries[0], sizeof entries[0]); // last: module_read set means loaded
}

/* `label` names the image the module is loaded for (io_internal.h, "what messages call an image"). */
static mr_status ensure_loaded(const char *label) {
    pthread_once(&load_once, load_module);
    if (module_read != NULL) return MR_OK;
    return mr_fail(MR_ERR_EXTERNAL,
                   "%s: cannot load the OpenImageIO module " MODULE_FILE
                   " (looked beside the executable in ../lib/matremap and in " MR_MODULE_DIR
                   "; set MR_OIIO_MODULE to its path): %s",
                   label, load_failure);
}

/* The module records failures in its own thread-local buffer; carry the message over to ours. */
static mr_status forward_status(mr_status status) {
    if (status != MR_OK) mr_fail(status, "%s", module_error());
    return status;
}

mr_status mr_io_oiio_read(const char *path, int max_dimension, mr_io_raw *raw) {
    char label[MR_IO_LABEL_SIZE];
    mr_status status = ensure_loaded(mr_io_file_label(label, path));
    if (status != MR_OK) return status;
    return forward_status(module_read(path, max_dimension, raw));
}

mr_status mr_io_oiio_read_as(const char *path, const char *format, int max_dimension, mr_io_raw *raw) {
    char label[MR_IO_LABEL_SIZE];
    mr_status status = ensure_loaded(mr_io_file_label(label, path));
    if (status != MR_OK) return status;
    return forward_status(module_read_as(path, format, max_dimension, raw));
}

mr_status mr_io_oiio_read_memory(const void *bytes, size_t size, const char *format, const char *label,
                                 int max_dimension, mr_io_raw *raw) {
    mr_status status = ensure_loaded(label);
    if (status != MR_OK) return status;
    return forward_status(module_read_memory(bytes, size, format, label, max_dimension, raw));
}

mr_status mr_io_oiio_write(const char *path, int width, int height, int channels, mr_io_sample sample,
                           const void *data, int srgb_tag, int jpeg_quality) {
    char label[MR_IO_LABEL_SIZE];
    mr_status status = ensure_loaded(mr_io_file_label(label, path));
    if (status != MR_OK) return status;
    return forward_status(module_write(path, width, height, channels, sample, data, srgb_tag, jpeg_quality));
}
