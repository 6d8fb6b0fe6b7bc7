/*
 * jpeg_check.c — a JPEG's marker segments checked, and its metadata dropped, before OpenImageIO decodes it
 * (contract in io_internal.h, mr_io_jpeg_clean).
 *
 * Why: OpenImageIO 2.4.7 parses the metadata segments of a JPEG's header itself (Exif in APP1, ICC profiles in
 * APP2, IPTC in APP13), and its IPTC parser reads past the end of its buffer on a malformed record (an
 * AddressSanitizer heap overflow in decode_iptc_iim, found by fuzzing). matremap uses none of that metadata: a
 * texture's pixels are all it reads (orientation is not applied, colour is the file's, as for every format). So the
 * header is rewritten without those segments, each segment's length checked against the bytes on the way, and the
 * decoder only ever sees the segments libjpeg itself interprets: the frame, tables, restart interval, JFIF (APP0)
 * and Adobe (APP14, which says how a 3- or 4-channel image is coded).
 *
 * The layout (ITU T.81, B.1.1): SOI (FF D8), then segments FF xx with a two-byte big-endian length that counts
 * itself, up to the first SOS (FF DA), after which the entropy-coded data and any later segments (progressive
 * scans' tables) are copied unchanged: libjpeg reads metadata only before the first scan.
 */
#include <stdlib.h>
#include <string.h>

#include "../mr_internal.h"
#include "io_internal.h"

/* Segments dropped: APP1..APP13, APP15 and comments. */
static int is_dropped(unsigned char marker) {
    return (marker >= 0xE1 && marker <= 0xED) || marker == 0xEF || marker == 0xFE;
}

mr_status mr_io_jpeg_clean(const unsigned char *bytes, size_t size, const char *label, unsigned char **out,
                           size_t *out_size) {
    if (size < 4 || bytes[0] != 0xFF || bytes[1] != 0xD8)
        return mr_fail(MR_ERR_FORMAT, "%s: not a JPEG file (no start-of-image marker)", label);
    unsigned char *clean = malloc(size);
    if (clean == NULL) return mr_fail(MR_ERR_NOMEM, "%s: out of memory for %zu bytes", label, size);
    memcpy(clean, bytes, 2);
    size_t at = 2, used = 2;
    for (;;) {
        if (at >= size || bytes[at] != 0xFF) {
            free(clean);
            return mr_fail(MR_ERR_FORMAT, "%s: corrupt JPEG: no marker at byte %zu of the header", label, at);
        }
        while (at < size && bytes[at] == 0xFF) at++; /* fill bytes */
        if (at >= size) break;
        const unsigned char marker = bytes[at++];
        if (marker == 0xD8 || marker == 0xD9 || marker == 0x01 || (marker >= 0xD0 && marker <= 0xD7)) {
            // No length: a stray SOI, an early EOI, TEM or a restart marker; the decoder judges them.
            clean[used++] = 0xFF;
            clean[used++] = marker;
            if (marker == 0xD9) break;
            continue;
        }
        if (at + 2 > size) break;
        const size_t length = (size_t)bytes[at] << 8 | bytes[at + 1];
        if (length < 2 || length > size - at) {
            free(clean);
            return mr_fail(MR_ERR_FORMAT, "%s: corrupt JPEG: the segment of marker FF %02X at byte %zu claims %zu "
                           "bytes, %zu are left", label, marker, at - 2, length, size - at);
        }
        if (marker == 0xDA) {
            // The first scan: everything from here on as it is.
            clean[used++] = 0xFF;
            memcpy(clean + used, bytes + at - 1, size - (at - 1));
            used += size - (at - 1);
            *out = clean;
            *out_size = used;
            return MR_OK;
        }
        if (!is_dropped(marker)) {
            clean[used++] = 0xFF;
            memcpy(clean + used, bytes + at - 1, length + 1);
            used += length + 1;
        }
        at += length;
    }
    free(clean);
    return mr_fail(MR_ERR_FORMAT, "%s: truncated JPEG: no image data after its header (%zu bytes)", label, size);
}
