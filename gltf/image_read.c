/*
 * image_read.c — decoding a glTF asset's images for the library's conversions and renders (mr_gltf.h,
 * mr_gltf_image_read): an external image from its file, an embedded one from the asset's bytes.
 */
#define _DEFAULT_SOURCE /* mkstemps */
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "gltf/mr_gltf.h"
#include "mr_internal.h"

mr_status mr_gltf_image_read(const mr_gltf *asset, int image, const mr_img_read_options *opts, mr_image **out,
                             mr_img_stored *stored) {
    if (asset == NULL || out == NULL) return mr_fail(MR_ERR_INVALID_ARG, "glTF image read: NULL argument");
    *out = NULL;
    mr_gltf_image im;
    mr_status status = mr_gltf_get_image(asset, image, &im);
    if (status != MR_OK) return status;
    if (im.path[0] != '\0') return mr_img_read_stored(im.path, opts, out, stored);
    if (im.bytes == NULL || im.size == 0)
        return mr_fail(MR_ERR_FORMAT, "glTF '%s': image %d has no bytes", mr_gltf_path(asset), image);
    // An embedded image (data URI or buffer view) goes through a private temporary file named by its type.
    const char *dir = getenv("TMPDIR");
    char path[PATH_MAX];
    const char *suffix = strstr(im.mime_type, "jpeg") ? ".jpg" : strstr(im.mime_type, "exr") ? ".exr" : ".png";
    snprintf(path, sizeof path, "%s/matremap-image-XXXXXX%s", dir && dir[0] ? dir : "/tmp", suffix);
    int fd = mkstemps(path, (int)strlen(suffix));
    if (fd < 0) return mr_fail(MR_ERR_IO, "glTF '%s': image %d: cannot create a temporary file", mr_gltf_path(asset),
                               image);
    FILE *f = fdopen(fd, "wb");
    int written = f != NULL && fwrite(im.bytes, 1, im.size, f) == im.size;
    if (f != NULL) written &= fclose(f) == 0;
    else close(fd);
    status = written ? mr_img_read_stored(path, opts, out, stored)
                     : mr_fail(MR_ERR_IO, "glTF '%s': image %d: cannot write a temporary file", mr_gltf_path(asset),
                               image);
    remove(path);
    if (status != MR_OK)
        return mr_fail_context(status, "glTF '%s': image %d (embedded %s)", mr_gltf_path(asset), image,
                               im.mime_type[0] ? im.mime_type : "image");
    return MR_OK;
}

mr_status mr_gltf_texture_read(const mr_gltf *asset, int texture, const mr_img_read_options *opts, mr_image **out,
                               mr_img_stored *stored) {
    if (asset == NULL || out == NULL) return mr_fail(MR_ERR_INVALID_ARG, "glTF texture read: NULL argument");
    *out = NULL;
    mr_gltf_texture t;
    mr_status status = mr_gltf_get_texture(asset, texture, &t);
    if (status != MR_OK) return status;
    if (t.image < 0) return mr_fail(MR_ERR_FORMAT, "glTF '%s': texture %d has no image", mr_gltf_path(asset), texture);
    return mr_gltf_image_read(asset, t.image, opts, out, stored);
}
