/* texture.c — bilinear texture lookups with wrap modes, coordinate sets and KHR_texture_transform. Contract in
 * render.h ("texture sampling") and texture.h. Wrap modes act on texel indices, as GPUs apply them: a lookup
 * between the last and the first texel blends them under REPEAT, blends the last with itself under CLAMP, and
 * mirrors the neighbourhood under MIRRORED_REPEAT (the glTF 2.0 sampler modes, OpenGL 4.6 section 8.14.2). Also
 * the binding of maps to a model's parameters (mr_param_textures_set) and its checks. */
#include <math.h>
#include <stddef.h>
#include <stdio.h>

#include "../mr_internal.h"
#include "texture.h"

mr_status mr_texture_sampling_validate(const mr_texture_sampling *sampling, const char *what) {
    if (sampling == NULL) return MR_OK;
    if ((int)sampling->wrap_u < 0 || sampling->wrap_u >= MR_WRAP_COUNT || (int)sampling->wrap_v < 0 ||
        sampling->wrap_v >= MR_WRAP_COUNT)
        return mr_fail(MR_ERR_INVALID_ARG, "%s: unknown wrap mode (%d, %d)", what, (int)sampling->wrap_u,
                       (int)sampling->wrap_v);
    if (sampling->texcoord != 0 && sampling->texcoord != 1)
        return mr_fail(MR_ERR_INVALID_ARG, "%s: texture coordinate set %d (0 or 1 are supported)", what,
                       sampling->texcoord);
    if (sampling->has_transform &&
        !(isfinite(sampling->offset[0]) && isfinite(sampling->offset[1]) && isfinite(sampling->rotation) &&
          isfinite(sampling->scale[0]) && isfinite(sampling->scale[1])))
        return mr_fail(MR_ERR_INVALID_ARG, "%s: texture transform (offset %g %g, rotation %g, scale %g %g) is not "
                       "finite", what, sampling->offset[0], sampling->offset[1], sampling->rotation,
                       sampling->scale[0], sampling->scale[1]);
    return MR_OK;
}

void mr_texture_sampler_init(texture_sampler *sampler, const mr_image *map, const mr_texture_sampling *sampling,
                          int channel, int count) {
    static const mr_texture_sampling defaults;
    if (sampling == NULL) sampling = &defaults;
    sampler->map = map;
    sampler->wrap_u = sampling->wrap_u == MR_WRAP_DEFAULT ? MR_WRAP_REPEAT : sampling->wrap_u;
    sampler->wrap_v = sampling->wrap_v == MR_WRAP_DEFAULT ? MR_WRAP_CLAMP : sampling->wrap_v;
    sampler->texcoord = sampling->texcoord;
    sampler->has_transform = sampling->has_transform;
    const double c = cos(sampling->rotation), s = sin(sampling->rotation);
    sampler->offset[0] = sampling->offset[0];
    sampler->offset[1] = sampling->offset[1];
    // KHR_texture_transform: T R S with R = [[cos, sin], [-sin, cos]] and S = diag(scale).
    sampler->matrix[0] = c * sampling->scale[0];
    sampler->matrix[1] = s * sampling->scale[1];
    sampler->matrix[2] = -s * sampling->scale[0];
    sampler->matrix[3] = c * sampling->scale[1];
    sampler->channel = channel;
    sampler->count = count;
}

/* Texel index i (any integer) brought into [0, n) by the wrap mode. */
static long wrap_index(long i, long n, mr_wrap mode) {
    if (mode == MR_WRAP_CLAMP) return i < 0 ? 0 : (i >= n ? n - 1 : i);
    if (mode == MR_WRAP_MIRROR) {
        long period = 2 * n, k = i % period;
        if (k < 0) k += period;
        return k < n ? k : period - 1 - k;
    }
    long k = i % n;
    return k < 0 ? k + n : k;
}

/* A stored texel as the renderer reads it: NaN and infinities as 0, negative values clamped to 0 (every parameter's
 * range starts at 0 or above; docs/rendering.md, "Texels that are not parameter values"). Finite values >= 0 pass
 * unchanged, so a clean map renders as it always did. mr_material_map_invalid_texels counts the others. */
static inline double texel_value(float stored) {
    return stored >= 0.0f && stored < INFINITY ? (double)stored : 0.0;
}

/* Coordinates beyond this many texels are clamped before the conversion to long (no overflow): a lookup that
 * far out has lost every fractional bit of its coordinate anyway. */
#define TEXEL_LIMIT 1e15

void mr_texture_sampler_read(const texture_sampler *sampler, const double uv0[2], const double uv1[2], double *out) {
    const mr_image *map = sampler->map;
    const double *uv = sampler->texcoord == 1 ? uv1 : uv0;
    double u = uv[0], v = uv[1];
    if (sampler->has_transform) {
        const double *m = sampler->matrix;
        double tu = sampler->offset[0] + m[0] * u + m[1] * v;
        double tv = sampler->offset[1] + m[2] * u + m[3] * v;
        u = tu;
        v = tv;
    }
    double x = mr_clampd(u * map->width - 0.5, -TEXEL_LIMIT, TEXEL_LIMIT);
    double y = mr_clampd(v * map->height - 0.5, -TEXEL_LIMIT, TEXEL_LIMIT);
    double x0 = floor(x), y0 = floor(y);
    double fx = x - x0, fy = y - y0;
    long i0 = wrap_index((long)x0, map->width, sampler->wrap_u);
    long i1 = wrap_index((long)x0 + 1, map->width, sampler->wrap_u);
    long j0 = wrap_index((long)y0, map->height, sampler->wrap_v);
    long j1 = wrap_index((long)y0 + 1, map->height, sampler->wrap_v);
    const size_t stride = (size_t)map->channels;
    const float *r0 = map->pixels + (size_t)j0 * (size_t)map->width * stride;
    const float *r1 = map->pixels + (size_t)j1 * (size_t)map->width * stride;
    for (int k = 0; k < sampler->count; k++) {
        size_t c = map->channels == 1 ? 0 : (size_t)(sampler->channel + k);
        double a = texel_value(r0[(size_t)i0 * stride + c]), b = texel_value(r0[(size_t)i1 * stride + c]);
        double d = texel_value(r1[(size_t)i0 * stride + c]), e = texel_value(r1[(size_t)i1 * stride + c]);
        double top = a + fx * (b - a), bottom = d + fx * (e - d);
        out[k] = top + fy * (bottom - top);
    }
}

/* ---- maps bound to parameters (render.h, mr_param_textures) ------------------------------------------------- */

mr_status mr_texture_check_binding(const mr_brdf_model *model, int index, const mr_image *map, int channel) {
    const mr_brdf_param *param = &model->params[index];
    if (param->role == MR_PARAM_SWITCH)
        return mr_fail(MR_ERR_INVALID_ARG, "texture for %s parameter '%s': a switch cannot come from a map",
                       model->name, param->name);
    if (map->width < 1 || map->height < 1 || map->pixels == NULL ||
        (map->channels != 1 && map->channels != 3 && map->channels != 4))
        return mr_fail(MR_ERR_INVALID_ARG, "texture for %s parameter '%s': not a valid image (%dx%d, %d channels)",
                       model->name, param->name, map->width, map->height, map->channels);
    if (param->channels == 3 && channel != 0)
        return mr_fail(MR_ERR_INVALID_ARG, "texture for %s parameter '%s': an RGB parameter reads channels 0-2 "
                       "(or a grey map), so its channel must be 0, not %d", model->name, param->name, channel);
    if (param->channels == 1 && (channel < 0 || channel >= map->channels))
        return mr_fail(MR_ERR_INVALID_ARG, "texture for %s parameter '%s': channel %d requested of a %d-channel map",
                       model->name, param->name, channel, map->channels);
    return MR_OK;
}

mr_status mr_param_textures_set(mr_param_textures *textures, const mr_brdf_model *model, const char *name,
                                const mr_image *map, int channel) {
    if (textures == NULL || model == NULL || name == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "textures: NULL textures, model or parameter name");
    int index = mr_brdf_param_index(model, name);
    if (index < 0) {
        char valid[256] = "";
        size_t used = 0;
        for (int p = 0; p < model->param_count && used < sizeof valid; p++)
            used += (size_t)snprintf(valid + used, sizeof valid - used, "%s%s", p ? ", " : "", model->params[p].name);
        return mr_fail(MR_ERR_INVALID_ARG, "textures: model %s has no parameter '%s' (valid: %s)", model->name, name,
                       valid);
    }
    if (map != NULL) {
        mr_status status = mr_texture_check_binding(model, index, map, channel);
        if (status != MR_OK) return status;
    }
    textures->maps[index] = map;
    textures->channel[index] = map != NULL ? channel : 0;
    return MR_OK;
}
