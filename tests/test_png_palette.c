/*
 * test_png_palette.c — the pieces a palette conversion is made of (src/io/png_palette.c, srgb.c, image_io.c): a
 * paletted PNG taken apart and put together again decodes as before, broken ones are refused, a code decodes as the
 * image reader decodes it, and the 8-bit sRGB table gives the writer's codes.
 */
#include <libdeflate.h>
#include <stdint.h>

#include "harness.h"
#include "io/io_internal.h"
#include "matremap.h"

#define DUCK_PNG "specgloss/Duck-pbrSpecularGlossiness/glTF-pbrSpecularGlossiness/DuckCM.png"

/* The Duck's texture apart and together again, with its own palette: the same pixels through the image reader; with
 * every entry darkened, each texel follows its entry. */
MR_TEST(palette_round_trip_keeps_the_pixels) {
    size_t size = 0;
    unsigned char *bytes = (unsigned char *)mr_test_read_file(mr_test_asset_path(DUCK_PNG), &size);
    MR_CHECK(bytes != NULL && mr_io_png_is_paletted(bytes, size));
    if (bytes == NULL) return;
    mr_io_png_palette p;
    MR_CHECK(mr_io_png_palette_read(bytes, size, "duck", &p) == MR_OK);
    MR_CHECK(p.width == 512 && p.height == 512 && p.bit_depth == 8 && p.entries > 1);
    size_t texels = 0;
    for (int e = 0; e < 256; e++) texels += p.counts[e];
    MR_CHECK(texels == 512 * 512);
    unsigned char *again = NULL, darker[256][3];
    size_t again_size = 0;
    MR_CHECK(mr_io_png_palette_write(&p, (const unsigned char(*)[3])p.rgb, NULL, 1, &again, &again_size) == MR_OK);
    mr_image *a = NULL, *b = NULL, *c = NULL;
    MR_CHECK(mr_img_read_memory(bytes, size, "original", NULL, &a, NULL) == MR_OK);
    MR_CHECK(mr_img_read_memory(again, again_size, "rewritten", NULL, &b, NULL) == MR_OK);
    if (a != NULL && b != NULL)
        MR_CHECK(a->channels == b->channels && memcmp(a->pixels, b->pixels, mr_image_value_count(a) * 4) == 0);
    for (int e = 0; e < p.entries; e++)
        for (int k = 0; k < 3; k++) darker[e][k] = (unsigned char)(p.rgb[e][k] / 2);
    free(again);
    MR_CHECK(mr_io_png_palette_write(&p, (const unsigned char(*)[3])darker, NULL, 0, &again, &again_size) == MR_OK);
    mr_img_read_options data = {0};
    data.encoding = MR_IMG_DATA;
    MR_CHECK(mr_img_read_memory(again, again_size, "darker", &data, &c, NULL) == MR_OK);
    mr_image_free(a);
    a = NULL;
    MR_CHECK(mr_img_read_memory(bytes, size, "original", &data, &a, NULL) == MR_OK);
    size_t wrong = 0;
    for (size_t i = 0; a != NULL && c != NULL && i < mr_image_value_count(a); i++)
        wrong += lrint(c->pixels[i] * 255.0) != lrint(a->pixels[i] * 255.0) / 2;
    MR_CHECK_MSG(wrong == 0, "%zu values do not follow their entry", wrong);
    mr_image_free(a);
    mr_image_free(b);
    mr_image_free(c);
    free(again);
    mr_io_png_palette_free(&p);
    free(bytes);
}

/* A broken CRC, an index past the palette and a PNG of another colour type are refused naming the data. */
MR_TEST(broken_palettes_are_refused) {
    size_t size = 0;
    unsigned char *bytes = (unsigned char *)mr_test_read_file(mr_test_asset_path(DUCK_PNG), &size);
    if (bytes == NULL) return;
    mr_io_png_palette p;
    bytes[40] ^= 0x5a; // inside the first chunk after IHDR
    MR_CHECK(mr_io_png_palette_read(bytes, size, "broken duck", &p) == MR_ERR_FORMAT);
    MR_CHECK_MSG(strstr(mr_last_error(), "broken duck") != NULL && strstr(mr_last_error(), "CRC") != NULL, "%s",
                 mr_last_error());
    bytes[40] ^= 0x5a;
    MR_CHECK(mr_io_png_palette_read(bytes, size - 20, "short duck", &p) == MR_ERR_FORMAT);
    MR_CHECK(strstr(mr_last_error(), "truncated") != NULL);
    // IHDR claiming more than the readers take, or more than the IDAT chunks can inflate to: refused before the
    // index stream is allocated (a few bytes once asked for 256 MB here, or 2^62 bytes past 2^31 pixels a side).
    unsigned char ihdr[17];
    memcpy(ihdr, bytes + 12, 17);
    const uint32_t sides[2] = {20000, 16000};
    const char *needles[2] = {"20000x20000 pixels exceeds the maximum dimension 16384",
                              "truncated PNG: IHDR claims 16000x16000 pixels"};
    for (int k = 0; k < 2; k++) {
        for (int b = 0; b < 4; b++)
            bytes[16 + b] = bytes[20 + b] = (unsigned char)(sides[k] >> (24 - 8 * b));
        const uint32_t crc = libdeflate_crc32(0, bytes + 12, 17);
        unsigned char saved[4];
        memcpy(saved, bytes + 29, 4);
        for (int b = 0; b < 4; b++)
            bytes[29 + b] = (unsigned char)(crc >> (24 - 8 * b));
        MR_CHECK(mr_io_png_palette_read(bytes, size, "big duck", &p) == MR_ERR_FORMAT && p.idat == NULL);
        MR_CHECK_MSG(strstr(mr_last_error(), "big duck") != NULL && strstr(mr_last_error(), needles[k]) != NULL, "%s",
                     mr_last_error());
        memcpy(bytes + 29, saved, 4);
    }
    memcpy(bytes + 12, ihdr, 17);
    // The same indices under a palette of 2 entries: indices past it.
    MR_CHECK(mr_io_png_palette_read(bytes, size, "duck", &p) == MR_OK);
    mr_io_png_palette two = p;
    two.entries = 2;
    unsigned char *rewritten = NULL;
    size_t rewritten_size = 0;
    MR_CHECK(mr_io_png_palette_write(&two, (const unsigned char(*)[3])p.rgb, NULL, 0, &rewritten, &rewritten_size) ==
             MR_OK);
    mr_io_png_palette q;
    MR_CHECK(mr_io_png_palette_read(rewritten, rewritten_size, "two entries", &q) == MR_ERR_FORMAT);
    MR_CHECK_MSG(strstr(mr_last_error(), "past the 2 palette entries") != NULL, "%s", mr_last_error());
    free(rewritten);
    mr_io_png_palette_free(&p);
    free(bytes);
    const char *rgb_png =
        mr_test_asset_path("specgloss/Avocado-pbrSpecularGlossiness/glTF-pbrSpecularGlossiness/Avocado_normal.png");
    unsigned char *other = (unsigned char *)mr_test_read_file(rgb_png, &size);
    MR_CHECK(other != NULL && !mr_io_png_is_paletted(other, size));
    free(other);
}

/* Every 8-bit code decodes as the image reader decodes it, as colour and as data. */
MR_TEST(codes_decode_as_the_reader_decodes_them) {
    mr_image *ramp = NULL;
    MR_CHECK(mr_image_create(256, 1, 1, &ramp) == MR_OK);
    for (int q = 0; q < 256; q++) ramp->pixels[q] = (float)q / 255.0f;
    unsigned char *png = NULL;
    size_t size = 0;
    uint8_t codes[256];
    for (int q = 0; q < 256; q++) codes[q] = (uint8_t)q;
    const mr_io_png_settings settings = MR_IO_PNG_DEFAULT;
    MR_CHECK(mr_io_png_encode("ramp", 256, 1, 1, 8, codes, 0, &settings, &png, &size) == MR_OK);
    for (int srgb = 0; srgb < 2; srgb++) {
        mr_img_read_options o = {0};
        o.encoding = srgb ? MR_IMG_COLOR : MR_IMG_DATA;
        mr_image *read = NULL;
        MR_CHECK(mr_img_read_memory(png, size, "ramp", &o, &read, NULL) == MR_OK);
        int wrong = 0;
        for (int q = 0; read != NULL && q < 256; q++)
            wrong += read->pixels[q] != mr_io_decode_code((unsigned)q, 8, srgb);
        MR_CHECK_MSG(wrong == 0, "%d codes decode otherwise (%s)", wrong, srgb ? "colour" : "data");
        mr_image_free(read);
    }
    free(png);
    mr_image_free(ramp);
}

/* The 8-bit sRGB table gives the codes of the writer's rule, floor(clamp(encode(v)) * 255 + 0.5), on a dense sample
 * of the floats in [0, 1] and on the hard cases around it. */
MR_TEST(srgb8_table_gives_the_writers_codes) {
    mr_srgb8_init();
    long wrong = 0, checked = 0;
    for (uint32_t bits = 0; bits <= 0x3f800000u; bits += 997, checked++) {
        float v;
        memcpy(&v, &bits, sizeof v);
        double x = mr_linear_to_srgb(v);
        unsigned expected = (unsigned)floor(fmin(fmax(x, 0.0), 1.0) * 255.0 + 0.5);
        wrong += mr_srgb8_encode(v) != expected;
    }
    MR_CHECK_MSG(wrong == 0, "%ld of %ld floats encode otherwise", wrong, checked);
    MR_CHECK(mr_srgb8_encode(NAN) == 0 && mr_srgb8_encode(-1.0f) == 0 && mr_srgb8_encode(INFINITY) == 255);
    MR_CHECK(mr_srgb8_encode(2.0f) == 255 && mr_srgb8_encode(1.0f) == 255 && mr_srgb8_encode(0.0f) == 0);
}

MR_TEST_MAIN(MR_TEST_ENTRY(palette_round_trip_keeps_the_pixels), MR_TEST_ENTRY(broken_palettes_are_refused),
             MR_TEST_ENTRY(codes_decode_as_the_reader_decodes_them), MR_TEST_ENTRY(srgb8_table_gives_the_writers_codes))
