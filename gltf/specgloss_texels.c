/*
 * specgloss_texels.c — an asset's spec-gloss texels for the training pairs' draws (mr_gltf.h,
 * mr_gltf_add_specgloss_texels; the pool and its draws: src/workflow/pairs.h).
 */
#include <stdio.h>

#include "gltf/mr_gltf.h"
#include "mr_internal.h"
#include "workflow/pairs.h"

mr_status mr_gltf_add_specgloss_texels(const mr_gltf *asset, uint64_t seed, struct mr_wf_texel_pool *pool,
                                       int *materials) {
    if (asset == NULL || pool == NULL || materials == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "glTF spec-gloss texels: NULL argument");
    mr_gltf_counts counts;
    mr_gltf_get_counts(asset, &counts);
    int sg_materials = 0;
    for (int k = 0; k < counts.materials; k++) {
        mr_gltf_material m;
        if (mr_gltf_get_material(asset, k, &m) == MR_OK && m.has_spec_gloss) sg_materials++;
    }
    *materials = sg_materials;
    if (sg_materials == 0) return MR_OK;
    const size_t per = MR_WF_POOL_SOURCE_TEXELS / (size_t)sg_materials;
    mr_status status = MR_OK;
    mr_wf_texel_pool_begin_source(pool, seed);
    for (int k = 0; status == MR_OK && k < counts.materials; k++) {
        mr_gltf_material m;
        if (mr_gltf_get_material(asset, k, &m) != MR_OK || !m.has_spec_gloss) continue;
        mr_image *diffuse = NULL, *sg = NULL; // colour textures: the reader's default
        if (m.diffuse_texture.index >= 0)
            status = mr_gltf_texture_read(asset, m.diffuse_texture.index, NULL, &diffuse, NULL);
        if (status == MR_OK && m.specular_glossiness_texture.index >= 0)
            status = mr_gltf_texture_read(asset, m.specular_glossiness_texture.index, NULL, &sg, NULL);
        if (status == MR_OK)
            status = mr_wf_texel_pool_add_maps(pool, diffuse, sg, m.diffuse_factor, m.specular_factor, per);
        mr_image_free(diffuse);
        mr_image_free(sg);
    }
    mr_wf_texel_pool_end_source(pool);
    return status;
}

mr_status mr_gltf_add_specgloss_texels_from_file(const char *path, const char *label, uint64_t seed,
                                                 struct mr_wf_texel_pool *pool, mr_gltf **asset) {
    if (asset != NULL) *asset = NULL;
    if (path == NULL || pool == NULL) return mr_fail(MR_ERR_INVALID_ARG, "glTF spec-gloss texels: NULL argument");
    mr_gltf *loaded = NULL;
    mr_status status = mr_gltf_load(path, &loaded);
    if (status != MR_OK) return status;
    int materials = 0;
    status = mr_gltf_add_specgloss_texels(loaded, seed, pool, &materials);
    if (status == MR_OK && materials == 0) {
        char quoted[4096 + 3];
        if (label == NULL) snprintf(quoted, sizeof quoted, "'%s'", path);
        status = mr_fail(MR_ERR_INVALID_ARG, "%s: no material carries KHR_materials_pbrSpecularGlossiness",
                         label != NULL ? label : quoted);
    }
    if (status == MR_OK && asset != NULL)
        *asset = loaded;
    else
        mr_gltf_free(loaded);
    return status;
}
