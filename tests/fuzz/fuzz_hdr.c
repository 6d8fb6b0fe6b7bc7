/*
 * fuzz_hdr.c — Radiance HDR (RGBE) through the OpenImageIO module (body in fuzz_image.h).
 */
#include "fuzz_image.h"

int mr_fuzz_hdr(const uint8_t *data, size_t size) { return fuzz_image_bytes(data, size, "#?", 2, "in.hdr"); }

MR_FUZZ_ENTRY(mr_fuzz_hdr)
