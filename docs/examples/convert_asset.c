/*
 * convert_asset.c — a glTF asset's spec-gloss materials converted to metal-rough through libmatremap, in one call.
 *
 *   cc convert_asset.c -o convert_asset $(pkg-config --cflags --libs matremap)
 *   ./convert_asset Avocado.gltf out/avocado.gltf weighted
 *
 * METHOD is any transform from gltf-specgloss to gltf (`matremap gltf --help` lists them: weighted, mlp, mean,
 * khronos, extension). tests/install_cli.sh compiles this file against an installed tree and runs it on a shared
 * asset, so it cannot go stale.
 */
#include <stdio.h>

#include <matremap.h>

int main(int argc, char **argv) {
    if (argc != 4) {
        fprintf(stderr, "usage: %s IN.gltf OUT.gltf METHOD\n", argv[0]);
        return 1;
    }
    mr_transform *transform = NULL;
    const mr_transform_kind *kind = mr_transform_find("gltf-specgloss", "gltf", argv[3]);
    if (kind == NULL || mr_transform_create(kind, NULL, &transform) != MR_OK) {
        fprintf(stderr, "%s\n", mr_last_error());
        return 1;
    }
    mr_gltf_convert_options options = {0}; // zeroed: the documented defaults
    options.transform = transform;
    options.overwrite = 1; // convert materials that carry metal-rough values of their own too
    mr_gltf_convert_result result;
    mr_status status = mr_gltf_convert_file(argv[1], argv[2], &options, &result);
    if (status != MR_OK) {
        fprintf(stderr, "%s\n", mr_last_error());
    } else {
        for (int k = 0; k < result.material_count; k++) {
            const mr_gltf_material_report *m = &result.materials[k];
            printf("material %d '%s': %s, %dx%d, %zu texels flagged\n", k, m->name,
                   m->outcome == MR_GLTF_SKIPPED ? "skipped" : m->outcome == MR_GLTF_KEPT ? "kept" : "converted",
                   m->width, m->height, m->flagged);
        }
    }
    mr_gltf_convert_result_free(&result);
    mr_transform_free(transform);
    return status == MR_OK ? 0 : 1;
}
