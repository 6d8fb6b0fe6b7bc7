/*
 * fuzz_gltf.c — the glTF loader and everything `report`, `gltf spec2metal` and `render gltf` do with what it
 * read: materials, textures and images (decoded), the scene's triangles and bounds, and the spec-gloss
 * conversion. The writer is left out (it serialises what the loader accepted, and took half of each execution;
 * the tests and the fault-injection runs cover it). The bytes are an asset as a file holds it (.glb when they
 * start with "glTF", .gltf JSON otherwise); resources it names are looked up beside it in the scratch folder,
 * where there are none, so only data URIs and a .glb's own chunk reach the decoders (tests/fuzz/make-corpus.sh
 * makes seeds of that kind).
 */
#include <string.h>

#include "fuzz.h"
#include "gltf/mr_gltf.h"
#include "gltf/mr_gltf_convert.h"
#include "gltf/mr_gltf_scene.h"
#include "matremap.h"

int mr_fuzz_gltf(const uint8_t *data, size_t size) {
    const int glb = size >= 4 && memcmp(data, "glTF", 4) == 0;
    fuzz_require_setup();
    const char *path = fuzz_write_scratch(glb ? "in.glb" : "in.gltf", data, size);
    if (path == NULL) return 0;
    mr_gltf *asset = NULL;
    if (mr_gltf_load(path, &asset) != MR_OK) return 0;

    mr_gltf_counts counts;
    mr_gltf_get_counts(asset, &counts);
    for (int i = 0; i < counts.materials; i++) {
        mr_gltf_material material;
        (void)mr_gltf_get_material(asset, i, &material);
    }
    // Small images only: the decoders' checks are the point, not decoding a large texture again and again.
    mr_img_read_options small = {MR_IMG_COLOR, 0, 64};
    for (int i = 0; i < counts.textures; i++) {
        mr_gltf_texture texture;
        if (mr_gltf_get_texture(asset, i, &texture) != MR_OK) continue;
        mr_image *image = NULL;
        if (mr_gltf_texture_read(asset, i, &small, &image, NULL) == MR_OK) mr_image_free(image);
    }
    double lo[3], hi[3];
    int count = 0;
    (void)mr_gltf_get_bounds(asset, -1, lo, hi, &count);
    mr_gltf_scene *scene = NULL;
    if (mr_gltf_scene_from_asset(asset, NULL, &scene) == MR_OK) mr_gltf_scene_free(scene);

    // The conversion, on what survived: spec-gloss materials become metal-rough.
    mr_transform *transform = NULL;
    const mr_transform_kind *kind = mr_transform_find("gltf-specgloss", "gltf", "khronos");
    if (kind != NULL && mr_transform_create(kind, NULL, &transform) == MR_OK) {
        mr_gltf_convert_options options = {0};
        options.transform = transform;
        (void)mr_gltf_convert(asset, &options, NULL);
        mr_transform_free(transform);
    }
    mr_gltf_free(asset);
    return 0;
}

MR_FUZZ_ENTRY(mr_fuzz_gltf)
