/*
 * fuzz_image.h — the image targets' one body (fuzz_png.c, fuzz_jpeg.c, fuzz_exr.c, fuzz_hdr.c): the bytes are
 * read twice, with the format's signature written over their start so that mutations stay inside the one decoder:
 * from memory as colour into as-stored channels (a glTF's embedded texture), and from a file named NAME.EXT as
 * data into one channel (a texture or environment map given on the command line: the file path of image_io.c,
 * where OpenImageIO opens the file itself).
 */
#ifndef MR_TESTS_FUZZ_IMAGE_H
#define MR_TESTS_FUZZ_IMAGE_H

#include <stdlib.h>
#include <string.h>

#include "fuzz.h"
#include "matremap.h"

static int fuzz_image_bytes(const uint8_t *data, size_t size, const char *magic, size_t magic_size,
                            const char *file_name) {
    if (size < magic_size) return 0;
    uint8_t *bytes = malloc(size);
    if (bytes == NULL) return 0;
    memcpy(bytes, data, size);
    memcpy(bytes, magic, magic_size);
    // 64 pixels a side: enough for every seed (the largest is 32), and a decoder asked for more must refuse before
    // it allocates (a mutated header claiming 64k x 64k is the case to exercise, not one decoding 1024 x 1024).
    mr_img_read_options colour = {MR_IMG_COLOR, 0, 64}, grey = {MR_IMG_DATA, 1, 64};
    mr_image *image = NULL;
    mr_img_stored stored;
    fuzz_require_setup();
    if (mr_img_read_memory(bytes, size, "fuzz", &colour, &image, &stored) == MR_OK) mr_image_free(image);
    image = NULL;
    const char *path = fuzz_write_scratch(file_name, bytes, size);
    if (path != NULL && mr_img_read(path, &grey, &image) == MR_OK) mr_image_free(image);
    free(bytes);
    return 0;
}

#endif /* MR_TESTS_FUZZ_IMAGE_H */
