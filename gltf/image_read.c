/*
 * image_read.c — decoding a glTF asset's images for the library's conversions and renders (mr_gltf.h,
 * mr_gltf_image_read): an external image from its file, an embedded one (data URI, buffer view) from the asset's
 * bytes in memory (mr_img_read_memory), so that nothing is written to disk and errors name the asset and image.
 */
#include <stdio.h>

#include "gltf/mr_gltf.h"
#include "mr_internal.h"

mr_status mr_gltf_image_read(const mr_gltf *asset, int image, const mr_img_read_options *opts, mr_image **out,
                             mr_img_stored *stored) {
    if (asset == NULL || out == NULL) return mr_fail(MR_ERR_INVALID_ARG, "glTF image read: NULL argument");
    *out = NULL;
    mr_gltf_image im;
    mr_status status = mr_gltf_get_image(asset, image, &im);
    if (status != MR_OK) return status;
    if (im.path[0] != '\0') {
        status = mr_img_read_stored(im.path, opts, out, stored);
        return status == MR_OK ? MR_OK : mr_fail_context(status, "glTF '%s': image %d", mr_gltf_path(asset), image);
    }
    if (im.bytes == NULL || im.size == 0)
        return mr_fail(MR_ERR_FORMAT, "glTF '%s': image %d has no bytes", mr_gltf_path(asset), image);
    char name[1024];
    snprintf(name, sizeof name, "glTF '%s': image %d", mr_gltf_path(asset), image);
    return mr_img_read_memory(im.bytes, im.size, name, opts, out, stored);
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
