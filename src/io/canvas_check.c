/*
 * canvas_check.c — the size a GIF, BMP or WebP header declares, checked before OpenImageIO opens the image
 * (contract in io_internal.h, mr_io_canvas_check).
 *
 * Why: OpenImageIO 2.4.7's readers for these formats allocate the whole picture when they open it, by the size
 * the header claims, before our check of the image's spec (image_io_oiio.cpp, check_spec) can refuse it. An 11 kB
 * glTF whose embedded image starts "GIF8" and declares a 28941 x 16316 screen made `gltf spec2metal` take 2 GB
 * and 3 s before failing (found by fuzz_gltf). So the declared width and height are read here from the fixed
 * part of each header and held against max_dimension, as exr_check.c does for EXR.
 *
 * Where the sizes are (all little-endian):
 *   GIF  (GIF89a spec, section 18): "GIF87a"/"GIF89a", then the logical screen's width and height, 16 bits each,
 *        at bytes 6 and 8. Frames are decoded a row at a time into that screen.
 *   BMP  (Microsoft's BITMAPINFOHEADER): "BM", a 14-byte file header, then the DIB header: its size at byte 14;
 *        a 12-byte BITMAPCOREHEADER has 16-bit width and height at 18 and 20, every later header 32-bit signed
 *        ones at 18 and 22 (a negative height means top-down rows).
 *   WebP (RFC 9649): "RIFF", size, "WEBP", then a chunk: "VP8X" holds the canvas, width-1 and height-1 in 24
 *        bits at bytes 24 and 27; "VP8L" a signature byte 0x2f at 20 and 14-bit width-1, height-1 packed from
 *        byte 21; "VP8 " (lossy) the frame tag, start code 9d 01 2a at 23, then 14-bit width and height at 26
 *        and 28. Both simple forms are below 16384 by construction, the extended canvas up to 2^24.
 */
#include <stdint.h>
#include <string.h>

#include "../mr_internal.h"
#include "io_internal.h"

static uint32_t le16(const unsigned char *p) {
    return (uint32_t)p[0] | (uint32_t)p[1] << 8;
}

static uint32_t le24(const unsigned char *p) {
    return le16(p) | (uint32_t)p[2] << 16;
}

static int64_t le32s(const unsigned char *p) {
    return (int32_t)(le16(p) | le16(p + 2) << 16);
}

static mr_status truncated(const char *label, const char *format, size_t size) {
    return mr_fail(MR_ERR_FORMAT, "%s: not a valid %s image: its header is truncated (%zu bytes)", label, format, size);
}

/* The declared size into *width, *height (64-bit: a BMP's may be negative or 2^31), or a failure naming the field. */
static mr_status declared_size(const unsigned char *h, size_t size, const char *format, const char *label,
                               int64_t *width, int64_t *height) {
    if (strcmp(format, "gif") == 0) {
        if (size < 10) return truncated(label, "GIF", size);
        *width = le16(h + 6);
        *height = le16(h + 8);
    } else if (strcmp(format, "bmp") == 0) {
        if (size < 26) return truncated(label, "BMP", size);
        const int64_t dib = le32s(h + 14);
        if (dib == 12) {
            *width = le16(h + 18);
            *height = le16(h + 20);
        } else if (dib >= 16) {
            *width = le32s(h + 18);
            *height = le32s(h + 22);
            if (*height < 0) *height = -*height; // top-down rows
        } else {
            return mr_fail(MR_ERR_FORMAT, "%s: not a valid BMP image: its DIB header claims %lld bytes (at least 12)",
                           label, (long long)dib);
        }
    } else if (strcmp(format, "webp") == 0) {
        if (size < 30) return truncated(label, "WebP", size);
        if (memcmp(h + 12, "VP8X", 4) == 0) {
            *width = (int64_t)le24(h + 24) + 1;
            *height = (int64_t)le24(h + 27) + 1;
        } else if (memcmp(h + 12, "VP8L", 4) == 0) {
            if (h[20] != 0x2f)
                return mr_fail(MR_ERR_FORMAT, "%s: not a valid WebP image: lossless signature 0x%02x (expected 0x2f)",
                               label, h[20]);
            const uint32_t bits = le16(h + 21) | le16(h + 23) << 16;
            *width = (int64_t)(bits & 0x3fff) + 1;
            *height = (int64_t)(bits >> 14 & 0x3fff) + 1;
        } else if (memcmp(h + 12, "VP8 ", 4) == 0) {
            if (memcmp(h + 23, "\x9d\x01\x2a", 3) != 0)
                return mr_fail(MR_ERR_FORMAT, "%s: not a valid WebP image: no lossy frame start code", label);
            *width = le16(h + 26) & 0x3fff;
            *height = le16(h + 28) & 0x3fff;
        } else {
            return mr_fail(MR_ERR_FORMAT, "%s: not a valid WebP image: first chunk '%.4s' (VP8X, VP8L or 'VP8 ')",
                           label, (const char *)h + 12);
        }
    } else {
        *width = *height = 1; // no declared size read here: OpenImageIO's spec check is the only one
    }
    return MR_OK;
}

mr_status mr_io_canvas_check(const unsigned char *head, size_t size, const char *format, const char *label,
                             int max_dimension) {
    int64_t width = 0, height = 0;
    mr_status status = declared_size(head, size, format, label, &width, &height);
    if (status != MR_OK) return status;
    if (width < 1 || height < 1 || width > max_dimension || height > max_dimension)
        return mr_fail(MR_ERR_FORMAT, "%s: its %s header declares %lld x %lld pixels (each side 1 to %d)", label,
                       strcmp(format, "bmp") == 0 ? "BMP" : strcmp(format, "gif") == 0 ? "GIF" : "WebP",
                       (long long)width, (long long)height, max_dimension);
    return MR_OK;
}
