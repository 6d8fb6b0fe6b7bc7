/* texture.h — bilinear texture lookups with glTF's sampling options (internal; mr_texture_sampling is in
 * render.h). A texture_sampler is prepared once per map and render (the transform's sine and cosine, the wrap
 * modes resolved), then read at every hit by any number of threads. */
#ifndef MR_TEXTURE_H
#define MR_TEXTURE_H

#include "render.h"

typedef struct texture_sampler {
    const mr_image *map;
    mr_wrap wrap_u, wrap_v; /* resolved: never MR_WRAP_DEFAULT */
    int texcoord;
    int has_transform;
    double offset[2], matrix[4]; /* uv' = offset + matrix (2x2, row-major) uv: KHR_texture_transform's R S */
    int channel;                 /* first channel read; a grey map answers every channel */
    int count;                   /* values read: 1 or 3 */
} texture_sampler;

/* Prepare a sampler of `count` values from `channel` on (sampling NULL = the zero default). The sampling must
 * be valid (mr_texture_sampling_validate). */
void mr_texture_sampler_init(texture_sampler *sampler, const mr_image *map, const mr_texture_sampling *sampling,
                          int channel, int count);

/* The bilinear lookup at the hit's TEXCOORD_0 uv0 or TEXCOORD_1 uv1 (render.h, "texture sampling"). Each lerp
 * is a + t (b - a), so a constant map gives its value exactly. */
void mr_texture_sampler_read(const texture_sampler *sampler, const double uv0[2], const double uv1[2], double *out);

/* Can parameter `index` of `model` come from `map`, read at `channel` (render.h, mr_param_textures)? MR_OK, or
 * MR_ERR_INVALID_ARG naming the model, the parameter and what is wrong: a switch, not a valid image, an RGB
 * parameter read from a channel other than 0, a channel the map does not have. */
mr_status mr_texture_check_binding(const mr_brdf_model *model, int index, const mr_image *map, int channel);

#endif /* MR_TEXTURE_H */
