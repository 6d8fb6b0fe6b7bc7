/*
 * bench_png.c — PNG read and write: libpng (src/io/png_io.c) against OpenImageIO, and the writer's settings
 * (make bench; docs/performance.md, "PNG settings").
 *
 * For each PNG named on the command line (the 2048^2 spec-gloss textures of ../shared/assets), one thread:
 *   - reading: mr_io_png_read against mr_io_oiio_read (the module already loaded, so its load is not counted);
 *   - writing the same 8-bit samples: OpenImageIO's PNG writer (its default, zlib level 6 with adaptive filters:
 *     the size every setting is compared with) and libpng at zlib levels 1-6 with adaptive filters, or with a
 *     single filter (none, sub, up, Paeth). (Level 9 was measured once: 7 % smaller than OpenImageIO's files and
 *     7 times slower; it is left out to keep the run short.)
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

static const setting settings[] = {
    {"OpenImageIO (level 6, adaptive)", {-1, 0}},
    {"libpng level 1, adaptive", {1, MR_IO_PNG_ALL_FILTERS}},
    {"libpng level 2, adaptive", {2, MR_IO_PNG_ALL_FILTERS}},
    {"libpng level 3, adaptive", {3, MR_IO_PNG_ALL_FILTERS}},
    {"libpng level 4, adaptive", {4, MR_IO_PNG_ALL_FILTERS}},
    {"libpng level 6, adaptive", {6, MR_IO_PNG_ALL_FILTERS}},
    {"libpng level 1, no filter", {1, 0x08}},
    {"libpng level 1, sub", {1, 0x10}},
    {"libpng level 1, up", {1, 0x20}},
    {"libpng level 1, Paeth", {1, 0x80}},
    {"libpng level 2, up", {2, 0x20}},
    {"libpng level 3, up", {3, 0x20}},
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

    double read_png = 0.0, read_oiio = 0.0, megapixels = 0.0;
    double write_ms[SETTING_COUNT] = {0};
    long write_bytes[SETTING_COUNT] = {0}, input_bytes = 0;
    mr_io_raw warm = {0, 0, 0, 0, 0, NULL};
    if (mr_io_oiio_read(argv[1], 16384, &warm) != MR_OK) fail(argv[1]); // loads the module outside the timings
    free(warm.pixels);
    for (int f = 1; f <= files; f++) {
        const char *path = argv[f];
        input_bytes += file_size(path);
        double t_png[RUNS], t_oiio[RUNS];
        mr_io_raw raw = {0, 0, 0, 0, 0, NULL};
        for (int r = 0; r < RUNS; r++) {
            mr_io_raw a = {0, 0, 0, 0, 0, NULL}, b = {0, 0, 0, 0, 0, NULL};
            double t0 = bench_now();
            if (mr_io_png_read(path, 16384, &a) != MR_OK) fail(path);
            double t1 = bench_now();
            if (mr_io_oiio_read(path, 16384, &b) != MR_OK) fail(path);
            double t2 = bench_now();
            t_png[r] = t1 - t0;
            t_oiio[r] = t2 - t1;
            free(b.pixels);
            if (r == 0)
                raw = a;
            else
                free(a.pixels);
        }
        read_png += bench_median(t_png, RUNS);
        read_oiio += bench_median(t_oiio, RUNS);
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

    printf("%d PNG textures, %.1f megapixels in all (%.1f MB as shipped); one thread, medians of %d runs.\n\n", files,
           megapixels, input_bytes / 1e6, RUNS);
    printf("| reader | ms for all | Mpixels/s | speed-up |\n|---|---:|---:|---:|\n");
    printf("| OpenImageIO (module loaded) | %.0f | %.1f | 1.00× |\n", 1e3 * read_oiio, megapixels / read_oiio);
    printf("| libpng (png_io.c) | %.0f | %.1f | %.2f× |\n\n", 1e3 * read_png, megapixels / read_png,
           read_oiio / read_png);
    printf("| writer and settings | ms for all | Mpixels/s | size (MB) | size / OpenImageIO's | speed-up |\n");
    printf("|---|---:|---:|---:|---:|---:|\n");
    for (int s = 0; s < SETTING_COUNT; s++)
        printf("| %s | %.0f | %.1f | %.2f | %.3f | %.2f× |\n", settings[s].name, write_ms[s],
               megapixels / (write_ms[s] / 1e3), write_bytes[s] / 1e6, (double)write_bytes[s] / write_bytes[0],
               write_ms[0] / write_ms[s]);
    return 0;
}
