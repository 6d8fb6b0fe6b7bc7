/*
 * fuzz_png.c — PNG through png_io.c (libdeflate, and libpng for what it leaves) (body in fuzz_image.h).
 */
#include "fuzz_image.h"

int mr_fuzz_png(const uint8_t *data, size_t size) {
    return fuzz_image_bytes(data, size, "\x89PNG\r\n\x1a\n", 8, "in.png");
}

MR_FUZZ_ENTRY(mr_fuzz_png)
