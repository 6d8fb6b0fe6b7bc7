/*
 * fuzz_exr.c — OpenEXR through the OpenImageIO module (body in fuzz_image.h).
 */
#include "fuzz_image.h"

int mr_fuzz_exr(const uint8_t *data, size_t size) {
    return fuzz_image_bytes(data, size, "\x76\x2f\x31\x01", 4, "in.exr");
}

MR_FUZZ_ENTRY(mr_fuzz_exr)
