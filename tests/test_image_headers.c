/*
 * test_image_headers.c — the structure checks that run before OpenImageIO sees a file (src/io/exr_check.c,
 * src/io/jpeg_check.c, src/io/canvas_check.c): valid files of every layout still read (scan lines in every
 * compression, tiles, mipmaps; JPEGs carrying metadata; GIF, BMP and WebP; several parts pass the check, and the
 * reader refuses them), and files whose headers lie about their sizes are refused with a message naming the file and
 * the field, before anything large is allocated.
 * Files are made by the library's own writers and by oiiotool, then edited byte by byte.
 */
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../src/io/image_io.h"
#include "harness.h"

/* ---- helpers ---------------------------------------------------------------------------------------------- */

/* The whole file (harness.h's reader), as bytes. */
static unsigned char *slurp(const char *path, size_t *size) { return (unsigned char *)mr_test_read_file(path, size); }

/* A small test picture (8 x 6, a gradient) written as `name` in the scratch folder; its path. */
static const char *write_picture(const char *name, int channels) {
    mr_image *image = NULL;
    if (mr_image_create(8, 6, channels, &image) != MR_OK) return NULL;
    for (int y = 0; y < 6; y++)
        for (int x = 0; x < 8; x++)
            for (int c = 0; c < channels; c++) mr_image_at(image, x, y)[c] = (float)(x + 2 * y + c) / 24.0f;
    const char *path = mr_test_tmp_path(name);
    mr_status status = mr_img_write(path, image, NULL);
    mr_image_free(image);
    return status == MR_OK ? path : NULL;
}

/* Offset of the value of the EXR header attribute `name` (its size field at offset - 4), or 0. */
static size_t exr_attribute(const unsigned char *bytes, size_t size, const char *name) {
    size_t at = 8;
    while (at < size && bytes[at] != '\0') {
        const char *attr = (const char *)bytes + at;
        at += strlen(attr) + 1;
        at += strlen((const char *)bytes + at) + 1;
        uint32_t length = (uint32_t)bytes[at] | (uint32_t)bytes[at + 1] << 8 | (uint32_t)bytes[at + 2] << 16 |
                          (uint32_t)bytes[at + 3] << 24;
        at += 4;
        if (strcmp(attr, name) == 0) return at;
        at += length;
    }
    return 0;
}

static void put32(unsigned char *p, uint32_t v) {
    for (int i = 0; i < 4; i++) p[i] = (unsigned char)(v >> (8 * i));
}

/* Reads `bytes` from memory and as a file `name`: both must fail with `status`, and the message must hold
 * `needle`. */
static void check_refused(const unsigned char *bytes, size_t size, const char *name, mr_status expected,
                          const char *needle) {
    mr_image *image = NULL;
    mr_status status = mr_img_read_memory(bytes, size, name, NULL, &image, NULL);
    MR_CHECK_MSG(status == expected && strstr(mr_last_error(), needle) != NULL, "%s from memory: %s: %s", name,
                 mr_status_str(status), mr_last_error());
    mr_image_free(image);
    image = NULL;
    const char *path = mr_test_tmp_path(name);
    MR_CHECK(mr_test_write_file(path, bytes, size));
    status = mr_img_read(path, NULL, &image);
    MR_CHECK_MSG(status == expected && strstr(mr_last_error(), needle) != NULL && strstr(mr_last_error(), name),
                 "%s from its file: %s: %s", name, mr_status_str(status), mr_last_error());
    mr_image_free(image);
}

static int have_oiiotool(void) { return system("oiiotool --help >/dev/null 2>&1") == 0; }

/* ---- EXR -------------------------------------------------------------------------------------------------- */

MR_TEST(exr_layouts_all_pass_the_check) {
    const char *png = write_picture("source.png", 3);
    MR_CHECK(png != NULL);
    if (png == NULL || !have_oiiotool()) {
        printf("    (oiiotool missing: only the library's own EXR checked)\n");
    } else {
        static const char *const variants[] = {
            "-d half --compression none",  "-d half --compression rle",  "-d float --compression zips",
            "-d half --compression zip",   "-d half --compression piz",  "-d float --compression pxr24",
            "-d half --compression b44",   "-d half --compression b44a", "-d half --compression dwaa",
            "-d half --compression dwab",  "-d half --tile 4 4",         "-d float --tile 3 5 --compression zip",
            "-d half -otex:resize=0",      "-d half --ch R,G",
        };
        for (size_t i = 0; i < sizeof variants / sizeof variants[0]; i++) {
            char command[1024], name[64];
            snprintf(name, sizeof name, "variant%zu.exr", i);
            const char *out = mr_test_tmp_path(name);
            int texture = strstr(variants[i], "-otex") != NULL;
            snprintf(command, sizeof command, "oiiotool '%s' %s %s'%s' >/dev/null 2>&1", png, variants[i],
                     texture ? "" : "-o ", out);
            MR_CHECK_MSG(system(command) == 0, "%s", command);
            mr_image *image = NULL;
            mr_status status = mr_img_read(out, NULL, &image);
            MR_CHECK_MSG(status == MR_OK && image->width == 8 && image->height == 6, "oiiotool %s: %s", variants[i],
                         mr_last_error());
            mr_image_free(image);
        }
        // Two parts: past the header check, refused by the reader (which part is meant is not the file's to say).
        char command[1024];
        const char *multi = mr_test_tmp_path("multipart.exr");
        snprintf(command, sizeof command, "oiiotool '%s' --attrib oiio:subimagename a '%s' --ch R "
                 "--attrib oiio:subimagename b --siappend -d half -o '%s' >/dev/null 2>&1", png, png, multi);
        MR_CHECK(system(command) == 0);
        mr_image *image = NULL;
        MR_CHECK_MSG(mr_img_read(multi, NULL, &image) == MR_ERR_UNSUPPORTED && image == NULL &&
                         strstr(mr_last_error(), "a multi-part EXR (2 parts)") != NULL,
                     "%s", mr_last_error());
    }
    const char *own = write_picture("own.exr", 4);
    mr_image *image = NULL;
    MR_CHECK_MSG(own != NULL && mr_img_read(own, NULL, &image) == MR_OK, "%s", mr_last_error());
    mr_image_free(image);
}

MR_TEST(exr_headers_that_lie_are_refused) {
    const char *path = write_picture("good.exr", 3);
    size_t size = 0;
    unsigned char *good = path ? slurp(path, &size) : NULL;
    MR_CHECK(good != NULL && size > 100);
    if (good == NULL) return;
    unsigned char *bad = malloc(size);

    // An attribute claiming more bytes than the file holds (OpenEXR would allocate and zero them).
    memcpy(bad, good, size);
    size_t value = exr_attribute(bad, size, "compression");
    MR_CHECK(value > 0);
    put32(bad + value - 4, 0x7ffffff0u);
    check_refused(bad, size, "huge_attribute.exr", MR_ERR_FORMAT, "claims 2147483632 bytes");

    // A data window of 100000 columns on a file of a few hundred bytes.
    memcpy(bad, good, size);
    value = exr_attribute(bad, size, "dataWindow");
    MR_CHECK(value > 0);
    put32(bad + value + 8, 99999);
    check_refused(bad, size, "wide.exr", MR_ERR_FORMAT, "100000 x 6 pixels is larger than the limit");

    // An empty data window (max < min).
    memcpy(bad, good, size);
    put32(bad + value + 12, (uint32_t)-5);
    check_refused(bad, size, "empty_window.exr", MR_ERR_FORMAT, "is empty");

    // A chunk offset pointing past the end of the file.
    memcpy(bad, good, size);
    size_t table = 8;
    while (bad[table] != '\0') { /* to the end of the header */
        table += strlen((const char *)bad + table) + 1;
        table += strlen((const char *)bad + table) + 1;
        uint32_t length;
        memcpy(&length, bad + table, 4);
        table += 4 + length;
    }
    table++;
    put32(bad + table, 0x00ffffffu);
    check_refused(bad, size, "offset.exr", MR_ERR_FORMAT, "chunk 0 is at byte 16777215");

    // A channel list whose attribute claims 4 bytes more than the list (OpenEXR reads the list to its terminator
    // and the next attribute from there: found by fuzzing), and a float attribute claiming 8 bytes.
    memcpy(bad, good, size);
    value = exr_attribute(bad, size, "channels");
    MR_CHECK(value > 0);
    uint32_t list_size;
    memcpy(&list_size, bad + value - 4, 4);
    put32(bad + value - 4, list_size + 4);
    check_refused(bad, size, "long_chlist.exr", MR_ERR_FORMAT, "the channel list ends at byte");
    memcpy(bad, good, size);
    value = exr_attribute(bad, size, "pixelAspectRatio");
    MR_CHECK(value > 0);
    put32(bad + value - 4, 8);
    check_refused(bad, size, "long_float.exr", MR_ERR_FORMAT, "of type float claims 8 bytes (the type has 4)");

    // Cut inside the header, and a deep-data flag.
    check_refused(good, 40, "cut.exr", MR_ERR_FORMAT, "truncated");
    memcpy(bad, good, size);
    bad[5] |= 0x08;
    check_refused(bad, size, "deep.exr", MR_ERR_UNSUPPORTED, "deep");
    free(bad);
    free(good);
}

MR_TEST(exr_tiles_larger_than_the_image_are_refused) {
    const char *png = write_picture("tile_source.png", 3);
    if (png == NULL || !have_oiiotool()) {
        printf("    (oiiotool missing: skipped)\n");
        MR_CHECK(png != NULL);
        return;
    }
    const char *tiled = mr_test_tmp_path("tiled.exr");
    char command[1024];
    snprintf(command, sizeof command, "oiiotool '%s' -d half --tile 4 4 -o '%s' >/dev/null 2>&1", png, tiled);
    MR_CHECK(system(command) == 0);
    size_t size = 0;
    unsigned char *bytes = slurp(tiled, &size);
    MR_CHECK(bytes != NULL);
    if (bytes == NULL) return;
    size_t value = exr_attribute(bytes, size, "tiles");
    MR_CHECK(value > 0);
    put32(bytes + value, 6291472); /* what the fuzzer wrote: 13 s and 1 GB in OpenEXR */
    check_refused(bytes, size, "wide_tiles.exr", MR_ERR_FORMAT, "tiles of 6291472 x 4 pixels on a 8 x 6 image");
    free(bytes);
}

/* ---- JPEG ------------------------------------------------------------------------------------------------- */

/* `jpeg` with a segment (marker, payload) inserted after SOI. */
static unsigned char *with_segment(const unsigned char *jpeg, size_t size, unsigned char marker,
                                   const unsigned char *payload, size_t payload_size, size_t *out_size) {
    unsigned char *out = malloc(size + 4 + payload_size);
    memcpy(out, jpeg, 2);
    out[2] = 0xFF, out[3] = marker;
    out[4] = (unsigned char)((payload_size + 2) >> 8), out[5] = (unsigned char)(payload_size + 2);
    memcpy(out + 6, payload, payload_size);
    memcpy(out + 6 + payload_size, jpeg + 2, size - 2);
    *out_size = size + 4 + payload_size;
    return out;
}

MR_TEST(jpeg_metadata_is_dropped_and_the_pixels_kept) {
    const char *path = write_picture("plain.jpg", 3);
    size_t size = 0;
    unsigned char *plain = path ? slurp(path, &size) : NULL;
    MR_CHECK(plain != NULL);
    if (plain == NULL) return;
    mr_image *reference = NULL;
    MR_CHECK(mr_img_read_memory(plain, size, "plain.jpg", NULL, &reference, NULL) == MR_OK);

    // A Photoshop IPTC segment whose record claims more bytes than it has (OpenImageIO 2.4.7 read past its buffer
    // on such a record), and Exif and a comment: all dropped, the pixels as without them.
    static const unsigned char iptc[] = "Photoshop 3.0\0" "8BIM\x04\x04\0\0\0\0\0\x20" "\x1c\x02\x78\x7f\xff" "ab";
    size_t with_size = 0, with_more = 0;
    unsigned char *with = with_segment(plain, size, 0xED, iptc, sizeof iptc - 1, &with_size);
    static const unsigned char exif[] = "Exif\0\0MM\0*\0\0\0\x08\0\x01\x01\x12\0\x03\0\0\0\x01\0\x06\0\0";
    unsigned char *more = with_segment(with, with_size, 0xE1, exif, sizeof exif - 1, &with_more);
    free(with);
    with = with_segment(more, with_more, 0xFE, (const unsigned char *)"a comment", 9, &with_size);
    free(more);
    mr_image *image = NULL;
    mr_status status = mr_img_read_memory(with, with_size, "metadata.jpg", NULL, &image, NULL);
    MR_CHECK_MSG(status == MR_OK, "%s", mr_last_error());
    if (status == MR_OK && reference != NULL) {
        size_t n = (size_t)reference->width * reference->height * reference->channels;
        MR_CHECK(image->width == reference->width && memcmp(image->pixels, reference->pixels, n * 4) == 0);
    }
    mr_image_free(image);
    MR_CHECK(mr_test_write_file(mr_test_tmp_path("metadata.jpg"), with, with_size));
    image = NULL;
    MR_CHECK_MSG(mr_img_read(mr_test_tmp_path("metadata.jpg"), NULL, &image) == MR_OK, "%s", mr_last_error());
    mr_image_free(image);

    // A segment whose length runs past the end of the file.
    unsigned char *bad = malloc(with_size);
    memcpy(bad, with, with_size);
    bad[4] = 0xFF, bad[5] = 0xF0;
    check_refused(bad, with_size, "long_segment.jpg", MR_ERR_FORMAT, "claims 65520 bytes");
    free(bad);
    free(with);
    free(plain);
    mr_image_free(reference);
}

/* ---- GIF, BMP, WebP (canvas_check.c) -------------------------------------------------------------------- */

/* Each format as oiiotool writes it (a 40 x 30 checker; WebP lossy and lossless) reads at its size; the same
 * file with its header's width raised past max_dimension (given as 64 here) is refused naming the file and the
 * size, from memory and as a file. The width's place in each header is what canvas_check.c reads. */
MR_TEST(gif_bmp_webp_declared_sizes_are_checked) {
    if (!have_oiiotool()) {
        printf("    (oiiotool missing: GIF, BMP and WebP not checked)\n");
        return;
    }
    static const struct {
        const char *name, *extra;
        size_t width_at; /* byte of the width field */
        int bytes;       /* its width in bytes, little-endian */
        unsigned minus;  /* the field holds width - minus */
    } cases[] = {
        {"checker.gif", "", 6, 2, 0},
        {"checker.bmp", "", 18, 4, 0},
        {"checker.webp", "", 26, 2, 0},
        {"checker-lossless.webp", "--attrib compression lossless", 21, 1, 1},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        const char *path = mr_test_tmp_path(cases[i].name);
        char command[1200];
        snprintf(command, sizeof command, "oiiotool --pattern checker:width=8:height=8 40x30 3 -d uint8 %s -o '%s'",
                 cases[i].extra, path);
        MR_CHECK_MSG(system(command) == 0, "%s", command);
        size_t size = 0;
        unsigned char *bytes = slurp(path, &size);
        MR_CHECK(bytes != NULL && size > 30);
        if (bytes == NULL || size <= 30) continue;
        mr_img_read_options small = {MR_IMG_COLOR, 0, 64};
        mr_image *image = NULL;
        mr_status status = mr_img_read_memory(bytes, size, cases[i].name, &small, &image, NULL);
        MR_CHECK_MSG(status == MR_OK && image->width == 40 && image->height == 30, "%s: %s", cases[i].name,
                     mr_last_error());
        mr_image_free(image);
        // 65 wide: one past the limit (a lossless WebP packs width - 1 in 14 bits from byte 21: its low 8 here).
        unsigned value = 65 - cases[i].minus;
        for (int b = 0; b < cases[i].bytes; b++)
            bytes[cases[i].width_at + (size_t)b] = (unsigned char)(value >> (8 * b));
        image = NULL;
        status = mr_img_read_memory(bytes, size, cases[i].name, &small, &image, NULL);
        const char *message = mr_last_error();
        MR_CHECK_MSG(status == MR_ERR_FORMAT && strstr(message, "declares 65 x 30 pixels (each side 1 to 64)") &&
                         strstr(message, cases[i].name),
                     "%s: %s: %s", cases[i].name, mr_status_str(status), mr_last_error());
        mr_image_free(image);
        free(bytes);
    }
}

MR_TEST_MAIN(MR_TEST_ENTRY(exr_layouts_all_pass_the_check), MR_TEST_ENTRY(exr_headers_that_lie_are_refused),
             MR_TEST_ENTRY(exr_tiles_larger_than_the_image_are_refused),
             MR_TEST_ENTRY(jpeg_metadata_is_dropped_and_the_pixels_kept),
             MR_TEST_ENTRY(gif_bmp_webp_declared_sizes_are_checked))
