/*
 * pictures.c — a remap's files: the renders it fits read and checked, the pictures of its result written as a set
 * (contract in remap.h, "a remap's files").
 */
#include <stdio.h>

#include "../io/image_io.h"
#include "../metrics/metrics.h"
#include "../mr_internal.h"
#include "remap.h"

#define PICTURE_PATH_SIZE 4096

/* The pictures' names after the prefix, in mr_remap_picture_path's order. */
static const char *const picture_names[MR_REMAP_PICTURE_COUNT] = {"source.png", "target.png", "ssim.png"};

mr_status mr_remap_read_render(const char *path, mr_image **out) {
    if (out == NULL) return mr_fail(MR_ERR_INVALID_ARG, "remap render: NULL argument");
    *out = NULL;
    if (path == NULL) return mr_fail(MR_ERR_INVALID_ARG, "remap render: NULL path");
    mr_img_read_options ro = {0};
    ro.channels = 3;
    mr_image *image = NULL;
    mr_status status = mr_img_read(path, &ro, &image);
    if (status == MR_OK) {
        char label[PICTURE_PATH_SIZE + 16];
        snprintf(label, sizeof label, "image '%s'", path);
        status = mr_image_check_radiance(image, label);
    }
    if (status != MR_OK) {
        mr_image_free(image);
        return status;
    }
    *out = image;
    return MR_OK;
}

mr_status mr_remap_read_sources(const char *const paths[3], const char *reference_path, mr_image *images[3],
                                mr_image **reference) {
    if (paths == NULL || images == NULL || reference == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "remap renders: NULL argument");
    mr_image *read[4] = {NULL, NULL, NULL, NULL};
    const char *all[4] = {paths[0], paths[1], paths[2], reference_path};
    mr_status status = MR_OK;
    for (int k = 0; k < 4 && status == MR_OK; k++)
        if (all[k] != NULL) status = mr_remap_read_render(all[k], &read[k]);
    const mr_image *full = read[0];
    if (status == MR_OK && full != NULL && full->width != full->height)
        status = mr_fail(MR_ERR_INVALID_ARG, "'%s' is %dx%d: fit-scene renders are square", all[0], full->width,
                         full->height);
    for (int k = 1; k < 4 && status == MR_OK && full != NULL; k++)
        if (read[k] != NULL && (read[k]->width != full->width || read[k]->height != full->height))
            status = mr_fail(MR_ERR_INVALID_ARG, "'%s' is %dx%d but '%s' is %dx%d: all renders must have the same size",
                             all[k], read[k]->width, read[k]->height, all[0], full->width, full->height);
    for (int k = 0; k < 4 && status != MR_OK; k++) {
        mr_image_free(read[k]);
        read[k] = NULL;
    }
    for (int k = 0; k < 3; k++) images[k] = read[k];
    *reference = read[3];
    return status;
}

mr_status mr_remap_picture_path(const char *prefix, int k, char *out, size_t size) {
    if (prefix == NULL || out == NULL || k < 0 || k >= MR_REMAP_PICTURE_COUNT)
        return mr_fail(MR_ERR_INVALID_ARG, "remap picture %d: no such picture", k);
    return mr_img_prefixed_name(out, size, prefix, picture_names[k]);
}

mr_status mr_remap_write_pictures(const char *prefix, const mr_render_plan *plan, const mr_image *source,
                                  const mr_brdf_model *target, const double *values) {
    return mr_remap_write_pictures_by(prefix, plan, source, NULL, target, values);
}

mr_status mr_remap_write_pictures_by(const char *prefix, const mr_render_plan *plan, const mr_image *source,
                                     mr_renderer *renderer, const mr_brdf_model *target, const double *values) {
    if (prefix == NULL || plan == NULL || source == NULL || target == NULL || values == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "remap pictures: NULL argument");
    mr_image *target_image = NULL, *map = NULL, *picture = NULL;
    double ssim;
    mr_status status;
    if (mr_renderer_is_builtin(renderer)) {
        status = mr_render(plan, target, values, MR_COMPONENT_FULL, &target_image);
    } else {
        status = mr_image_create(source->width, source->height, 3, &target_image);
        if (status == MR_OK) status = mr_renderer_render(renderer, plan, target, values, target_image, NULL, NULL);
    }
    if (status == MR_OK) status = mr_ssim(source, target_image, NULL, &ssim, &map);
    if (status == MR_OK) status = mr_ssim_map_visualise(map, 0.0, &picture);
    // The three belong together: written all or none.
    const mr_image *pictures[MR_REMAP_PICTURE_COUNT] = {source, target_image, picture};
    char paths[MR_REMAP_PICTURE_COUNT][PICTURE_PATH_SIZE];
    mr_img_set_item items[MR_REMAP_PICTURE_COUNT];
    for (int k = 0; k < MR_REMAP_PICTURE_COUNT && status == MR_OK; k++) {
        status = mr_remap_picture_path(prefix, k, paths[k], sizeof paths[k]);
        items[k] = (mr_img_set_item){paths[k], NULL, pictures[k], {MR_IMG_COLOR, 0, 0}};
    }
    if (status == MR_OK) status = mr_img_write_set(items, MR_REMAP_PICTURE_COUNT, NULL, NULL);
    mr_image_free(target_image);
    mr_image_free(map);
    mr_image_free(picture);
    return status;
}
