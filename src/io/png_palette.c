/*
 * png_palette.c — paletted PNGs taken apart and put together again with another palette (io_internal.h, "Paletted
 * PNG"). A per-texel conversion of a paletted texture is a conversion of its palette: every texel of one index gets
 * the same answer, so the converted texture is the same index stream (IDAT, copied byte for byte: no decoding, no
 * filtering, no deflate) under a converted palette. The index histogram (how many texels use each entry, for the
 * conversion's flag counts and for uniformity over the entries actually used) needs the stream inflated once.
 *
 * PNG layout: ISO/IEC 15948 (PNG 2nd edition): chunks (section 5.3: length, type, data, CRC over type and data),
 * IHDR (11.2.2), PLTE (11.2.3), tRNS for colour type 3 (11.3.2.1), filters (9.2; a paletted image filters bytes
 * with bpp 1), non-interlaced scanlines (7.2).
 */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <libdeflate.h>

#include "../mr_internal.h"
#include "io_internal.h"

static const unsigned char png_signature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};

int mr_io_png_is_paletted(const unsigned char *bytes, size_t size) {
    // Signature, then IHDR first (length 13): colour type is byte 25, interlace byte 28.
    return bytes != NULL && size >= 33 && memcmp(bytes, png_signature, 8) == 0 && mr_io_be32(bytes + 8) == 13 &&
           memcmp(bytes + 12, "IHDR", 4) == 0 && bytes[25] == 3 && bytes[28] == 0;
}

mr_status mr_io_png_palette_read(const unsigned char *bytes, size_t size, const char *label, mr_io_png_palette *out) {
    memset(out, 0, sizeof *out);
    if (!mr_io_png_is_paletted(bytes, size))
        return mr_fail(MR_ERR_FORMAT, "%s: not a non-interlaced paletted PNG", label);
    memcpy(out->ihdr, bytes + 16, 13);
    out->width = (int)mr_io_be32(bytes + 16);
    out->height = (int)mr_io_be32(bytes + 20);
    out->bit_depth = bytes[24];
    const int depth = out->bit_depth;
    if (out->width < 1 || out->height < 1 || (depth != 1 && depth != 2 && depth != 4 && depth != 8))
        return mr_fail(MR_ERR_FORMAT, "%s: paletted PNG of %dx%d at %d bits", label, out->width, out->height, depth);
    for (int e = 0; e < 256; e++) out->alpha[e] = 255;
    // The chunks: every length inside the data, every CRC right; PLTE, tRNS and the IDAT stream kept.
    size_t idat_size = 0, offset = 8;
    mr_status status = MR_OK;
    for (int pass = 0; pass < 2 && status == MR_OK; pass++) { // pass 0 measures IDAT, pass 1 copies it
        if (pass == 1 && (out->idat = malloc(idat_size ? idat_size : 1)) == NULL)
            return mr_fail(MR_ERR_NOMEM, "%s: out of memory for %zu bytes of image data", label, idat_size);
        size_t copied = 0;
        int ended = 0;
        for (offset = 8; !ended;) {
            if (size - offset < 12)
                return mr_fail(MR_ERR_FORMAT, "%s: truncated PNG: chunk at byte %zu", label, offset);
            const uint32_t length = mr_io_be32(bytes + offset);
            const unsigned char *type = bytes + offset + 4, *data = type + 4;
            if (length > size - offset - 12)
                return mr_fail(MR_ERR_FORMAT, "%s: truncated PNG: chunk '%.4s' at byte %zu claims %lu bytes", label,
                               (const char *)type, offset, (unsigned long)length);
            if (pass == 0 && libdeflate_crc32(0, type, (size_t)length + 4) != mr_io_be32(data + length))
                return mr_fail(MR_ERR_FORMAT, "%s: corrupt PNG: CRC mismatch in chunk '%.4s' at byte %zu", label,
                               (const char *)type, offset);
            if (memcmp(type, "IDAT", 4) == 0) {
                if (pass == 1) memcpy(out->idat + copied, data, length);
                copied += length;
            } else if (pass == 0 && memcmp(type, "PLTE", 4) == 0) {
                if (length % 3 != 0 || length == 0 || length / 3 > (1u << depth))
                    return mr_fail(MR_ERR_FORMAT, "%s: PLTE of %lu bytes for %d-bit indices", label,
                                   (unsigned long)length, depth);
                out->entries = (int)(length / 3);
                memcpy(out->rgb, data, length);
            } else if (pass == 0 && memcmp(type, "tRNS", 4) == 0) {
                if (length > 256) return mr_fail(MR_ERR_FORMAT, "%s: tRNS of %lu bytes", label, (unsigned long)length);
                memcpy(out->alpha, data, length);
                out->has_alpha = 1;
            }
            ended = memcmp(type, "IEND", 4) == 0;
            offset += 12 + (size_t)length;
        }
        idat_size = copied;
    }
    out->idat_size = idat_size;
    if (out->entries == 0) {
        mr_io_png_palette_free(out);
        return mr_fail(MR_ERR_FORMAT, "%s: paletted PNG without PLTE", label);
    }
    // The index histogram: inflate, unfilter, count (an index past the palette is an error, as in libpng). The
    // sizes IHDR claims are held against the readers' limit and against what the IDAT chunks can inflate to (deflate
    // makes at most 1032 bytes of each, after the zlib stream's 6 bytes of header and checksum) before the index
    // stream is allocated.
    if (out->width > MR_IO_MAX_DIMENSION_DEFAULT || out->height > MR_IO_MAX_DIMENSION_DEFAULT) {
        mr_io_png_palette_free(out);
        return mr_fail(MR_ERR_FORMAT, "%s: %dx%d pixels exceeds the maximum dimension %d", label, out->width,
                       out->height, MR_IO_MAX_DIMENSION_DEFAULT);
    }
    const size_t row_bytes = ((size_t)out->width * (size_t)depth + 7) / 8;
    const size_t raw_size = (size_t)out->height * (row_bytes + 1);
    if (idat_size < 6 || (idat_size - 6) * 1032 < raw_size) {
        mr_io_png_palette_free(out);
        return mr_fail(MR_ERR_FORMAT,
                       "%s: truncated PNG: IHDR claims %dx%d pixels (%zu bytes of image data), but its "
                       "IDAT chunks hold %zu compressed bytes",
                       label, out->width, out->height, raw_size, idat_size);
    }
    unsigned char *raw = calloc(raw_size + row_bytes, 1);
    struct libdeflate_decompressor *inflater = raw ? libdeflate_alloc_decompressor() : NULL;
    if (inflater == NULL) {
        free(raw);
        mr_io_png_palette_free(out);
        return mr_fail(MR_ERR_NOMEM, "%s: out of memory for the index stream", label);
    }
    size_t got = 0;
    enum libdeflate_result z = libdeflate_zlib_decompress(inflater, out->idat, idat_size, raw, raw_size, &got);
    libdeflate_free_decompressor(inflater);
    int ok = z == LIBDEFLATE_SUCCESS && got == raw_size;
    const unsigned char *previous = raw + raw_size; // the zero row above the first
    for (int y = 0; y < out->height && ok; y++) {
        unsigned char *row = raw + (size_t)y * (row_bytes + 1);
        ok = mr_io_png_unfilter_row(row[0], row + 1, previous, row_bytes, 1); // bpp 1: a paletted image's bytes
        previous = row + 1;
    }
    if (!ok) {
        free(raw);
        mr_io_png_palette_free(out);
        return mr_fail(MR_ERR_FORMAT, "%s: corrupt PNG: the image data does not inflate to %dx%d filtered indices",
                       label, out->width, out->height);
    }
    const int per_byte = 8 / depth, mask = (1 << depth) - 1;
    for (int y = 0; y < out->height; y++) {
        const unsigned char *row = raw + (size_t)y * (row_bytes + 1) + 1;
        for (int x = 0; x < out->width; x++) {
            int index = depth == 8 ? row[x] : (row[x / per_byte] >> (8 - depth * (x % per_byte + 1))) & mask;
            out->counts[index]++;
        }
    }
    free(raw);
    for (int e = out->entries; e < 256; e++)
        if (out->counts[e] > 0) {
            mr_io_png_palette_free(out);
            return mr_fail(MR_ERR_FORMAT, "%s: index %d past the %d palette entries", label, e, out->entries);
        }
    return MR_OK;
}

void mr_io_png_palette_free(mr_io_png_palette *p) {
    if (p == NULL) return;
    free(p->idat);
    p->idat = NULL;
}

mr_status mr_io_png_palette_write(const mr_io_png_palette *p, const unsigned char rgb[][3],
                                  const unsigned char *alpha, int srgb_tag, unsigned char **bytes, size_t *size) {
    // tRNS holds the entries up to the last one that is not opaque.
    int transparent = 0;
    for (int e = 0; alpha != NULL && e < p->entries; e++)
        if (alpha[e] != 255) transparent = e + 1;
    // The colour-space chunks libpng writes for png_set_sRGB_gAMA_and_cHRM (perceptual intent).
    static const unsigned char srgb[1] = {0}, gama[4] = {0, 0, 0xb1, 0x8f};
    static const unsigned char chrm[32] = {0, 0, 0x7a, 0x26, 0, 0, 0x80, 0x84, 0, 0, 0xfa, 0, 0, 0, 0x80, 0xe8,
                                           0, 0, 0x75, 0x30, 0, 0, 0xea, 0x60, 0, 0, 0x3a, 0x98, 0, 0, 0x17, 0x70};
    const size_t total = 8 + (12 + 13) + (srgb_tag ? 3 * 12 + 1 + 4 + 32 : 0) + (12 + 3 * (size_t)p->entries) +
                         (transparent ? 12 + (size_t)transparent : 0) + (12 + p->idat_size) + 12;
    unsigned char *buffer = malloc(total), packed[3 * 256];
    if (buffer == NULL) return mr_fail(MR_ERR_NOMEM, "paletted PNG: out of memory for %zu bytes", total);
    unsigned char *at = buffer + 8;
    memcpy(buffer, png_signature, 8);
    at = mr_io_png_put_chunk(at, "IHDR", p->ihdr, 13);
    if (srgb_tag) {
        at = mr_io_png_put_chunk(at, "gAMA", gama, 4);
        at = mr_io_png_put_chunk(at, "cHRM", chrm, 32);
        at = mr_io_png_put_chunk(at, "sRGB", srgb, 1);
    }
    for (int e = 0; e < p->entries; e++) memcpy(packed + 3 * e, rgb[e], 3);
    at = mr_io_png_put_chunk(at, "PLTE", packed, 3 * (size_t)p->entries);
    if (transparent) at = mr_io_png_put_chunk(at, "tRNS", alpha, (size_t)transparent);
    at = mr_io_png_put_chunk(at, "IDAT", p->idat, p->idat_size);
    at = mr_io_png_put_chunk(at, "IEND", NULL, 0);
    *bytes = buffer;
    *size = (size_t)(at - buffer);
    return MR_OK;
}
