/*
 * exr_check.c — an OpenEXR file's structure checked before OpenImageIO (and the OpenEXR library under it) reads it
 * (contract in io_internal.h, mr_io_exr_check).
 *
 * Why: OpenEXR 3.1 takes the sizes in a header as given. A 1.4 kB file whose string attribute claims 11 MB, or
 * whose data window claims 2^31 lines, makes it allocate and zero-fill that much before anything fails (seen
 * while fuzzing: 18 s and 2 GB for one such file). Every size here is checked against the bytes that are in the
 * file and against max_dimension before the library sees the file, with 64-bit arithmetic throughout.
 *
 * The layout (OpenEXR's "OpenEXR File Layout" document): the magic number 20000630 and a version word (bits
 * 0-7 the version, 2; bit 9 single-part tiled, bit 10 long names, bit 11 deep data, bit 12 multi-part), then
 * per part a header of attributes -- name NUL, type NUL, int32 size, value -- ended by an empty name (a
 * multi-part file ends its list of headers with one more), then the offset table: one uint64 per chunk, each
 * the position of a chunk in the file.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../mr_internal.h"
#include "io_internal.h"

#define EXR_MAX_ATTRIBUTES 4096 /* per header; real files have tens */
#define EXR_MAX_CHANNELS 1024
#define EXR_MAX_PARTS 64
#define EXR_MAX_SMALL_TILE 1024 /* tile side allowed on any image; larger ones no larger than the image */

typedef struct exr_reader {
    FILE *stream;
    const char *label;
    int64_t size; /* bytes in the file */
} exr_reader;

typedef struct exr_header {
    int has_channels, has_compression, has_data_window, has_tiles;
    int channels;
    int compression; /* 0 none ... 9 DWAB */
    int64_t x_min, y_min, x_max, y_max;
    uint32_t tile_x, tile_y;
    int level_mode, rounding; /* tiles: 0 one level, 1 mipmap, 2 ripmap; 0 round down, 1 up */
    int64_t chunk_count;      /* multi-part: the chunkCount attribute; -1 if absent */
} exr_header;

static int64_t le32(const unsigned char *p) {
    return (int32_t)((uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24);
}

static uint64_t le64(const unsigned char *p) {
    uint64_t v = 0;
    for (int i = 7; i >= 0; i--) v = v << 8 | p[i];
    return v;
}

static mr_status truncated(const exr_reader *r, const char *what) {
    return mr_fail(MR_ERR_FORMAT, "%s: not a valid EXR file: truncated in %s (%lld bytes)", r->label, what,
                   (long long)r->size);
}

/* A NUL-terminated name of at most max_length characters into buf[256]; 0 at end of file or when too long. */
static int read_name(exr_reader *r, char *buf, int max_length) {
    for (int i = 0; i <= max_length; i++) {
        int c = fgetc(r->stream);
        if (c == EOF) return 0;
        buf[i] = (char)c;
        if (c == '\0') return 1;
    }
    return 0;
}

static mr_status read_channels(exr_reader *r, const unsigned char *value, int64_t size, exr_header *h) {
    int64_t at = 0;
    while (at < size && value[at] != '\0') {
        const unsigned char *end = memchr(value + at, '\0', (size_t)(size - at));
        if (end == NULL || end - (value + at) > 255 || (int64_t)(end - value) + 1 + 16 > size)
            return mr_fail(MR_ERR_FORMAT, "%s: not a valid EXR file: channel list entry %d is malformed", r->label,
                           h->channels);
        const unsigned char *fields = end + 1;
        int64_t type = le32(fields), x_sampling = le32(fields + 8), y_sampling = le32(fields + 12);
        if (type < 0 || type > 2 || x_sampling < 1 || y_sampling < 1)
            return mr_fail(MR_ERR_FORMAT, "%s: not a valid EXR file: channel '%s' has pixel type %lld, sampling "
                           "%lld x %lld", r->label, (const char *)(value + at), (long long)type,
                           (long long)x_sampling, (long long)y_sampling);
        if (++h->channels > EXR_MAX_CHANNELS)
            return mr_fail(MR_ERR_FORMAT, "%s: more than %d channels", r->label, EXR_MAX_CHANNELS);
        at = (int64_t)(fields - value) + 16;
    }
    if (at >= size) return mr_fail(MR_ERR_FORMAT, "%s: not a valid EXR file: unterminated channel list", r->label);
    // OpenEXR reads a channel list up to its terminator, whatever the attribute's size says, and reads the next
    // attribute from there: a list shorter than its size makes it read the next one from inside this one (fuzzing:
    // a 230-byte file whose list ended 18 bytes early; the bytes after it gave a string of 1.6 GB).
    if (at != size - 1)
        return mr_fail(MR_ERR_FORMAT, "%s: not a valid EXR file: the channel list ends at byte %lld of the %lld "
                       "its attribute claims", r->label, (long long)at + 1, (long long)size);
    h->has_channels = 1;
    return MR_OK;
}

/* One attribute's value, checked where its type matters to the reader's allocations. */
static mr_status take_attribute(exr_reader *r, const char *name, const char *type, const unsigned char *value,
                                int64_t size, exr_header *h) {
    if (strcmp(type, "chlist") == 0 && strcmp(name, "channels") == 0) return read_channels(r, value, size, h);
    if (strcmp(name, "compression") == 0) {
        if (size != 1 || value[0] > 9)
            return mr_fail(MR_ERR_FORMAT, "%s: not a valid EXR file: compression %d", r->label, size ? value[0] : -1);
        h->compression = value[0];
        h->has_compression = 1;
    } else if (strcmp(name, "dataWindow") == 0) {
        if (size != 16 || strcmp(type, "box2i") != 0)
            return mr_fail(MR_ERR_FORMAT, "%s: not a valid EXR file: dataWindow of type %s, %lld bytes", r->label,
                           type, (long long)size);
        h->x_min = le32(value), h->y_min = le32(value + 4), h->x_max = le32(value + 8), h->y_max = le32(value + 12);
        h->has_data_window = 1;
    } else if (strcmp(name, "tiles") == 0) {
        if (size != 9) return mr_fail(MR_ERR_FORMAT, "%s: not a valid EXR file: tile description", r->label);
        h->tile_x = (uint32_t)le32(value), h->tile_y = (uint32_t)le32(value + 4);
        h->level_mode = value[8] & 0x0f, h->rounding = value[8] >> 4;
        if (h->tile_x < 1 || h->tile_y < 1 || h->tile_x > (1u << 24) || h->tile_y > (1u << 24) ||
            h->level_mode > 2 || h->rounding > 1)
            return mr_fail(MR_ERR_FORMAT, "%s: not a valid EXR file: tiles %u x %u, level mode %d", r->label,
                           h->tile_x, h->tile_y, h->level_mode);
        h->has_tiles = 1;
    } else if (strcmp(name, "chunkCount") == 0) {
        if (size != 4 || le32(value) < 0)
            return mr_fail(MR_ERR_FORMAT, "%s: not a valid EXR file: chunkCount", r->label);
        h->chunk_count = le32(value);
    }
    return MR_OK;
}

/* The bytes OpenEXR 3.1 reads for a value of `type` whatever the attribute's size says (each type's
 * readValueFrom), or -1 for the types it reads by their size (string, floatvector, opaque ones) or by their content
 * (chlist, preview, stringvector: checked on their own). A size that differs would make the library read the next
 * attribute from the wrong place. */
static int64_t fixed_size_of(const char *type) {
    static const struct {
        const char *type;
        int64_t size;
    } fixed[] = {
        {"int", 4},          {"float", 4},       {"double", 8},     {"compression", 1}, {"lineOrder", 1},
        {"envmap", 1},       {"deepImageState", 1}, {"tiledesc", 9}, {"box2i", 16},      {"box2f", 16},
        {"v2i", 8},          {"v2f", 8},         {"v2d", 16},       {"v3i", 12},        {"v3f", 12},
        {"v3d", 24},         {"m33f", 36},       {"m33d", 72},      {"m44f", 64},       {"m44d", 128},
        {"rational", 8},     {"timecode", 8},    {"keycode", 28},   {"chromaticities", 32},
    };
    for (size_t i = 0; i < sizeof fixed / sizeof fixed[0]; i++)
        if (strcmp(type, fixed[i].type) == 0) return fixed[i].size;
    return -1;
}

/* A preview (width, height, then 4 bytes a pixel) or a string vector (int32 length, then the bytes, repeated) whose
 * content is exactly `size` bytes: OpenEXR allocates what the content says (a preview's width x height x 4, each
 * string's length) before it reads it. `stream` is at the value and is left after it. */
static mr_status check_sized_content(exr_reader *r, const char *name, const char *type, int64_t size) {
    if (strcmp(type, "preview") == 0) {
        unsigned char wh[8];
        if (size < 8 || fread(wh, 1, 8, r->stream) != 8)
            return mr_fail(MR_ERR_FORMAT, "%s: not a valid EXR file: preview '%s' of %lld bytes", r->label, name,
                           (long long)size);
        const int64_t width = (uint32_t)le32(wh), height = (uint32_t)le32(wh + 4);
        const int64_t pixels = (size - 8) / 4; // size < 2^31: width is held to it before the product is formed
        if (width == 0 || height == 0 ? size != 8
                                      : (size - 8) % 4 != 0 || width > pixels || height != pixels / width ||
                                            width * height != pixels)
            return mr_fail(MR_ERR_FORMAT, "%s: not a valid EXR file: preview '%s' of %lld x %lld pixels in %lld "
                           "bytes", r->label, name, (long long)width, (long long)height, (long long)size);
        return fseek(r->stream, (long)(size - 8), SEEK_CUR) == 0 ? MR_OK : truncated(r, "a preview");
    }
    for (int64_t at = 0; at < size;) { // stringvector
        unsigned char length_bytes[4];
        if (size - at < 4 || fread(length_bytes, 1, 4, r->stream) != 4)
            return mr_fail(MR_ERR_FORMAT, "%s: not a valid EXR file: string vector '%s' malformed at byte %lld",
                           r->label, name, (long long)at);
        const int64_t length = le32(length_bytes);
        at += 4;
        if (length < 0 || length > size - at)
            return mr_fail(MR_ERR_FORMAT, "%s: not a valid EXR file: string vector '%s' holds a string of %lld "
                           "bytes with %lld left", r->label, name, (long long)length, (long long)(size - at));
        if (fseek(r->stream, (long)length, SEEK_CUR) != 0) return truncated(r, "a string vector");
        at += length;
    }
    return MR_OK;
}

/* One header, up to and including its terminating empty name. *empty: the header had no attribute at all (the
 * end of a multi-part file's list). */
static mr_status read_header(exr_reader *r, int long_names, exr_header *h, int *empty) {
    memset(h, 0, sizeof *h);
    h->chunk_count = -1;
    *empty = 1;
    unsigned char value[64]; /* values of the attributes checked above are at most 16 bytes; channels are read
                                separately */
    for (int count = 0;; count++) {
        char name[256], type[256];
        if (!read_name(r, name, long_names ? 255 : 31)) return truncated(r, "an attribute name");
        if (name[0] == '\0') return MR_OK;
        *empty = 0;
        if (count >= EXR_MAX_ATTRIBUTES)
            return mr_fail(MR_ERR_FORMAT, "%s: more than %d header attributes", r->label, EXR_MAX_ATTRIBUTES);
        if (!read_name(r, type, long_names ? 255 : 31)) return truncated(r, "an attribute type");
        unsigned char size_bytes[4];
        if (fread(size_bytes, 1, 4, r->stream) != 4) return truncated(r, "an attribute size");
        int64_t size = le32(size_bytes), at = ftell(r->stream);
        if (size < 0 || at < 0 || size > r->size - at)
            return mr_fail(MR_ERR_FORMAT, "%s: not a valid EXR file: attribute '%s' claims %lld bytes, the file "
                           "has %lld after it", r->label, name, (long long)size, (long long)(r->size - at));
        const int64_t fixed = fixed_size_of(type);
        if (fixed >= 0 && size != fixed)
            return mr_fail(MR_ERR_FORMAT, "%s: not a valid EXR file: attribute '%s' of type %s claims %lld bytes "
                           "(the type has %lld)", r->label, name, type, (long long)size, (long long)fixed);
        if (strcmp(type, "preview") == 0 || strcmp(type, "stringvector") == 0) {
            mr_status status = check_sized_content(r, name, type, size);
            if (status != MR_OK) return status;
        } else if (strcmp(type, "chlist") == 0) {
            unsigned char *list = malloc((size_t)size + 1);
            if (list == NULL) return mr_fail(MR_ERR_NOMEM, "%s: out of memory", r->label);
            exr_header other; // a channel list by another name is checked the same way, and counts for nothing
            memset(&other, 0, sizeof other);
            mr_status status = fread(list, 1, (size_t)size, r->stream) == (size_t)size
                                   ? read_channels(r, list, size, strcmp(name, "channels") == 0 ? h : &other)
                                   : truncated(r, "the channel list");
            free(list);
            if (status != MR_OK) return status;
        } else if (size <= (int64_t)sizeof value) {
            if (fread(value, 1, (size_t)size, r->stream) != (size_t)size) return truncated(r, "an attribute");
            mr_status status = take_attribute(r, name, type, value, size, h);
            if (status != MR_OK) return status;
        } else if (fseek(r->stream, (long)size, SEEK_CUR) != 0) {
            return truncated(r, "an attribute");
        }
    }
}

/* Chunks of a part: scan-line blocks, or tiles over every level. -1 for a layout that is not valid. */
static int64_t chunk_count(const exr_header *h, int64_t width, int64_t height) {
    static const int lines_per_block[10] = {1, 1, 1, 16, 32, 16, 32, 32, 32, 256};
    if (!h->has_tiles) return (height + lines_per_block[h->compression] - 1) / lines_per_block[h->compression];
    int64_t levels_x = 1, levels_y = 1;
    if (h->level_mode != 0) {
        // log2 of the larger side (mipmap) or of each side (ripmap), rounded as the file says, plus one.
        int64_t sides[2] = {h->level_mode == 1 ? (width > height ? width : height) : width,
                            h->level_mode == 1 ? (width > height ? width : height) : height};
        int64_t levels[2];
        for (int k = 0; k < 2; k++) {
            int64_t n = 0, s = sides[k];
            while (s > 1) {
                s = h->rounding ? (s + 1) / 2 : s / 2;
                n++;
            }
            levels[k] = n + 1;
        }
        levels_x = levels[0], levels_y = h->level_mode == 1 ? 1 : levels[1];
    }
    int64_t total = 0;
    for (int64_t lx = 0; lx < levels_x; lx++) {
        for (int64_t ly = 0; ly < (h->level_mode == 1 ? 1 : levels_y); ly++) {
            int64_t w = width, hh = height;
            int64_t sx = lx, sy = h->level_mode == 1 ? lx : ly; /* a mipmap level halves both sides */
            for (int64_t i = 0; i < sx; i++) w = h->rounding ? (w + 1) / 2 : w / 2;
            for (int64_t i = 0; i < sy; i++) hh = h->rounding ? (hh + 1) / 2 : hh / 2;
            if (w < 1) w = 1;
            if (hh < 1) hh = 1;
            total += ((w + h->tile_x - 1) / h->tile_x) * ((hh + h->tile_y - 1) / h->tile_y);
            if (total > ((int64_t)1 << 40)) return -1;
        }
    }
    return total;
}

mr_status mr_io_exr_check(FILE *stream, const char *label, int max_dimension) {
    exr_reader r = {stream, label, 0};
    if (fseek(stream, 0, SEEK_END) != 0 || (r.size = ftell(stream)) < 0 || fseek(stream, 0, SEEK_SET) != 0)
        return mr_fail(MR_ERR_IO, "%s: cannot seek in the file", label);
    unsigned char start[8];
    if (fread(start, 1, 8, stream) != 8) return truncated(&r, "the version");
    int64_t version = le32(start + 4);
    if ((version & 0xff) != 2)
        return mr_fail(MR_ERR_FORMAT, "%s: EXR version %lld (this reader knows version 2)", label,
                       (long long)(version & 0xff));
    if (version & 0x800) return mr_fail(MR_ERR_UNSUPPORTED, "%s: a deep EXR image (deep data is not supported)", label);
    const int multi_part = (version & 0x1000) != 0, long_names = (version & 0x400) != 0;

    exr_header headers[EXR_MAX_PARTS];
    int parts = 0;
    for (;;) {
        exr_header h;
        int empty = 0;
        mr_status status = read_header(&r, long_names, &h, &empty);
        if (status != MR_OK) return status;
        if (empty && multi_part && parts > 0) break;
        if (empty) return mr_fail(MR_ERR_FORMAT, "%s: not a valid EXR file: a header without attributes", label);
        if (!h.has_channels || !h.has_compression || !h.has_data_window)
            return mr_fail(MR_ERR_FORMAT, "%s: not a valid EXR file: part %d lacks its %s", label, parts,
                           !h.has_channels ? "channel list" : !h.has_compression ? "compression" : "data window");
        int64_t width = h.x_max - h.x_min + 1, height = h.y_max - h.y_min + 1;
        if (h.x_max < h.x_min || h.y_max < h.y_min)
            return mr_fail(MR_ERR_FORMAT, "%s: not a valid EXR file: data window (%lld, %lld) - (%lld, %lld) is empty",
                           label, (long long)h.x_min, (long long)h.y_min, (long long)h.x_max, (long long)h.y_max);
        if (width > max_dimension || height > max_dimension)
            return mr_fail(MR_ERR_FORMAT, "%s: %lld x %lld pixels is larger than the limit of %d a side", label,
                           (long long)width, (long long)height, max_dimension);
        if (h.channels < 1) return mr_fail(MR_ERR_FORMAT, "%s: an EXR part without channels", label);
        // A tile larger than its image is legal but buys nothing, and the library allocates whole tiles: one of
        // 6 million x 16 pixels on a 32 x 32 image took 13 s and 1 GB (found by fuzzing).
        if (h.has_tiles && (h.tile_x > (width > EXR_MAX_SMALL_TILE ? width : EXR_MAX_SMALL_TILE) ||
                            h.tile_y > (height > EXR_MAX_SMALL_TILE ? height : EXR_MAX_SMALL_TILE)))
            return mr_fail(MR_ERR_FORMAT, "%s: not a valid EXR file: tiles of %u x %u pixels on a %lld x %lld image",
                           label, h.tile_x, h.tile_y, (long long)width, (long long)height);
        if (parts == EXR_MAX_PARTS) return mr_fail(MR_ERR_FORMAT, "%s: more than %d parts", label, EXR_MAX_PARTS);
        if (!multi_part && !(version & 0x200)) h.has_tiles = 0; /* scan lines: a tiles attribute means nothing */
        if (!multi_part && (version & 0x200) && !h.has_tiles)
            return mr_fail(MR_ERR_FORMAT, "%s: not a valid EXR file: tiled, without a tile description", label);
        headers[parts++] = h;
        if (!multi_part) break;
    }

    // The offset tables: every chunk inside the file, after the tables.
    int64_t chunks[EXR_MAX_PARTS], total = 0;
    for (int p = 0; p < parts; p++) {
        const exr_header *h = &headers[p];
        chunks[p] = multi_part ? h->chunk_count
                               : chunk_count(h, h->x_max - h->x_min + 1, h->y_max - h->y_min + 1);
        if (chunks[p] < 0)
            return mr_fail(MR_ERR_FORMAT, "%s: not a valid EXR file: part %d has no valid chunk count", label, p);
        total += chunks[p];
    }
    int64_t table_start = ftell(stream);
    if (table_start < 0 || total > (r.size - table_start) / 8)
        return mr_fail(MR_ERR_FORMAT, "%s: not a valid EXR file: %lld chunks need an offset table of %lld bytes, "
                       "the file has %lld after its header", label, (long long)total, (long long)total * 8,
                       (long long)(r.size - table_start));
    int64_t table_end = table_start + 8 * total;
    for (int64_t i = 0; i < total; i++) {
        unsigned char entry[8];
        if (fread(entry, 1, 8, stream) != 8) return truncated(&r, "the offset table");
        uint64_t offset = le64(entry);
        // Zero marks a chunk a writer never wrote (an incomplete file), which the library reports itself.
        if (offset != 0 && (offset < (uint64_t)table_end || offset >= (uint64_t)r.size))
            return mr_fail(MR_ERR_FORMAT, "%s: not a valid EXR file: chunk %lld is at byte %llu, outside the %lld "
                           "bytes after the offset table", label, (long long)i, (unsigned long long)offset,
                           (long long)(r.size - table_end));
    }
    return MR_OK;
}
