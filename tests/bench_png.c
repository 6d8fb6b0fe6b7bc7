/*
 * bench_png.c — PNG read and write: libdeflate (src/io/png_deflate.c) and libpng (src/io/png_io.c) against
 * OpenImageIO, and the writer's settings (make bench; docs/performance.md, "PNG read and write").
 *
 * For each PNG named on the command line (the 2048^2 spec-gloss textures of ../shared/assets), one thread:
 *   - reading: mr_io_png_read (libdeflate, libpng for what it leaves), libpng alone and mr_io_oiio_read (the module
 *     already loaded, so its load is not counted);
 *   - writing the same 8-bit samples: OpenImageIO's PNG writer (its default, zlib level 6 with adaptive filters:
 *     the size every setting is compared with), libpng + zlib (the writer before libdeflate; level 3 adaptive was
 *     its default) and libdeflate at levels 1-6 with adaptive filters (libpng's heuristic), or with a single
 *     filter (none, sub, up, Paeth). (libdeflate's level 9 was measured once: files 6.5 % smaller than
 *     OpenImageIO's, 2.6 times as slow to write; left out to keep the run short.)
 * Times are medians of 3 runs; sizes are summed over the files. Prints Markdown on stdout; asserts nothing.
 * Usage: bench_png FILE.png ...
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>


#include "../src/io/io_internal.h"
#include "bench_util.h"
#include "matremap.h"

#define RUNS 3
#define MAX_FILES 16

typedef struct setting {
    const char *name;
    mr_io_png_settings png; /* level < 0: OpenImageIO's writer */
} setting;

#define ALL MR_IO_PNG_ALL_FILTERS
static const setting settings[] = {
    {"OpenImageIO (zlib level 6, adaptive)", {-1, 0, 0}},
    {"libpng level 1, adaptive", {1, ALL, 1}},
    {"libpng level 3, adaptive (the earlier default)", {3, ALL, 1}},
    {"libpng level 4, adaptive", {4, ALL, 1}},
    {"libdeflate level 1, adaptive", {1, ALL, 0}},
    {"libdeflate level 2, adaptive", {2, ALL, 0}},
    {"libdeflate level 3, adaptive", {3, ALL, 0}},
    {"libdeflate level 4, adaptive", {4, ALL, 0}},
    {"libdeflate level 5, adaptive", {5, ALL, 0}},
    {"libdeflate level 6, adaptive", {6, ALL, 0}},
    {"libdeflate level 1, no filter", {1, MR_IO_PNG_FILTER_NONE, 0}},
    {"libdeflate level 1, sub", {1, MR_IO_PNG_FILTER_SUB, 0}},
    {"libdeflate level 1, up", {1, MR_IO_PNG_FILTER_UP, 0}},
    {"libdeflate level 1, Paeth", {1, MR_IO_PNG_FILTER_PAETH, 0}},
    {"libdeflate level 2, up", {2, MR_IO_PNG_FILTER_UP, 0}},
    {"libdeflate level 2, Paeth", {2, MR_IO_PNG_FILTER_PAETH, 0}},
    {"libdeflate level 3, up", {3, MR_IO_PNG_FILTER_UP, 0}},
    {"libdeflate level 3, Paeth", {3, MR_IO_PNG_FILTER_PAETH, 0}},
    {"libdeflate level 5, Paeth", {5, MR_IO_PNG_FILTER_PAETH, 0}},
};
#define SETTING_COUNT ((int)(sizeof settings / sizeof settings[0]))

static long file_size(const char *path) {
    struct stat st;
    return stat(path, &st) == 0 ? (long)st.st_size : -1;
}

static void fail(const char *what) {
    fprintf(stderr, "bench_png: %s: %s\n", what, mr_last_error());
    exit(3);
}

/* Median seconds of RUNS reads of `path` by reader k (0 OpenImageIO, 1 libpng alone, 2 mr_io_png_read); the first
 * run's image into *keep when keep is not NULL. */
static double time_reader(int k, const char *path, mr_io_raw *keep) {
    double t[RUNS];
    for (int r = 0; r < RUNS; r++) {
        mr_io_raw a = {0, 0, 0, 0, 0, NULL};
        double t0 = bench_now();
        mr_status status = MR_OK;
        if (k == 0) {
            status = mr_io_oiio_read(path, 16384, &a);
        } else if (k == 1) {
            FILE *file = fopen(path, "rb");
            status = file ? mr_io_png_read_stream_libpng(file, path, 16384, &a) : MR_ERR_IO;
            if (file) fclose(file);
        } else {
            status = mr_io_png_read(path, 16384, &a);
        }
        t[r] = bench_now() - t0;
        if (status != MR_OK) fail(path);
        if (r == 0 && keep != NULL)
            *keep = a;
        else
            free(a.pixels);
    }
    return bench_median(t, RUNS);
}

int main(int argc, char **argv) {
    if (argc < 2 || argc - 1 > MAX_FILES) {
        fprintf(stderr, "usage: bench_png FILE.png ... (at most %d)\n", MAX_FILES);
        return 1;
    }
    const int files = argc - 1;
    char out[] = "/tmp/bench_png.XXXXXX";
    if (mkdtemp(out) == NULL) return 3;
    char target[64];
    snprintf(target, sizeof target, "%s/out.png", out);

    static const char *const readers[3] = {"OpenImageIO (module loaded)", "libpng (png_io.c)",
                                           "libdeflate (png_deflate.c; the reader)"};
    double read_s[3] = {0}, megapixels = 0.0;
    double write_ms[SETTING_COUNT] = {0};
    long write_bytes[SETTING_COUNT] = {0}, input_bytes = 0;
    mr_io_raw warm = {0, 0, 0, 0, 0, NULL};
    if (mr_io_oiio_read(argv[1], 16384, &warm) != MR_OK) fail(argv[1]); // loads the module outside the timings
    free(warm.pixels);
    for (int f = 1; f <= files; f++) {
        const char *path = argv[f];
        input_bytes += file_size(path);
        mr_io_raw raw = {0, 0, 0, 0, 0, NULL};
        for (int k = 0; k < 3; k++) read_s[k] += time_reader(k, path, k == 2 ? &raw : NULL);
        const size_t values = (size_t)raw.width * (size_t)raw.height * (size_t)raw.channels;
        megapixels += (double)raw.width * raw.height / 1e6;
        unsigned char *samples = malloc(values);
        if (samples == NULL) return 3;
        for (size_t i = 0; i < values; i++) samples[i] = (unsigned char)(raw.pixels[i] * 255.0f + 0.5f);
        for (int s = 0; s < SETTING_COUNT; s++) {
            double t[RUNS];
            for (int r = 0; r < RUNS; r++) {
                double t0 = bench_now();
                mr_status status =
                    settings[s].png.level < 0
                        ? mr_io_oiio_write(target, raw.width, raw.height, raw.channels, MR_IO_U8, samples, 1, 0)
                        : mr_io_png_write(target, raw.width, raw.height, raw.channels, 8, samples, 1, &settings[s].png);
                if (status != MR_OK) fail(target);
                t[r] = bench_now() - t0;
            }
                    write_ms[s] += 1e3 * bench_median(t, RUNS);
            write_bytes[s] += file_size(target);
        }
        free(samples);
        free(raw.pixels);
        fprintf(stderr, "bench_png: %s\n", path);
    }
    unlink(target);
    rmdir(out);

    printf("%d PNG textures, %.1f megapixels in all (%.1f MB as shipped); one thread, medians of %d "
           "runs.\n\n", files, megapixels, input_bytes / 1e6, RUNS);
    printf("| reader | ms for all | Mpixels/s | speed-up | against libpng |\n|---|---:|---:|---:|---:|\n");
    for (int k = 0; k < 3; k++)
        printf("| %s | %.0f | %.1f | %.2f× | %.2f× |\n", readers[k], 1e3 * read_s[k], megapixels / read_s[k],
               read_s[0] / read_s[k], read_s[1] / read_s[k]);
    const int earlier = 2; // libpng level 3, adaptive
    printf("\n| writer and settings | ms for all | Mpixels/s | size (MB) | size / OpenImageIO's | speed-up | against "
           "libpng level 3 |\n");
    printf("|---|---:|---:|---:|---:|---:|---:|\n");
    for (int s = 0; s < SETTING_COUNT; s++) {
        const mr_io_png_settings d = MR_IO_PNG_DEFAULT;
        const int is_default = settings[s].png.level == d.level && settings[s].png.filters == d.filters &&
                               settings[s].png.libpng == d.libpng;
        printf("| %s%s | %.0f | %.1f | %.2f | %.4f | %.2f× | %.2f× |\n", settings[s].name,
               is_default ? " (**the default**)" : "", write_ms[s],
               megapixels / (write_ms[s] / 1e3), write_bytes[s] / 1e6, (double)write_bytes[s] / write_bytes[0],
               write_ms[0] / write_ms[s], write_ms[earlier] / write_ms[s]);
    }
    return 0;
}
