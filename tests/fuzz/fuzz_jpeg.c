/*
 * fuzz_jpeg.c — JPEG through the OpenImageIO module (body in fuzz_image.h).
 */
#include "fuzz_image.h"

int mr_fuzz_jpeg(const uint8_t *data, size_t size) { return fuzz_image_bytes(data, size, "\xff\xd8\xff", 3, "in.jpg"); }

MR_FUZZ_ENTRY(mr_fuzz_jpeg)
