/*
 * env_sampling.c — how a render plan samples its environment lights (contract in env_sampling.h; the estimator in
 * docs/rendering.md, "The estimator"): each light's fixed pattern of directions importance-sampled from its map,
 * and the reflection samples' directions about a hit's mirror direction, tabled once per plan.
 */
#include "env_sampling.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "../mr_internal.h"

/* ---- the fixed sample pattern -------------------------------------------------------------------------------- */

/* Number of directions of an environment light's pattern. */
int mr_env_light_samples(const mr_light *light) {
    return light->samples > 0 ? light->samples : MR_ENV_DEFAULT_SAMPLES;
}

/* Van der Corput radical inverse of i in base 2, in [0, 1): the second coordinate of the Hammersley set. */
static double radical_inverse2(uint32_t i) {
    i = (i << 16) | (i >> 16);
    i = ((i & 0x55555555u) << 1) | ((i & 0xAAAAAAAAu) >> 1);
    i = ((i & 0x33333333u) << 2) | ((i & 0xCCCCCCCCu) >> 2);
    i = ((i & 0x0F0F0F0Fu) << 4) | ((i & 0xF0F0F0F0u) >> 4);
    i = ((i & 0x00FF00FFu) << 8) | ((i & 0xFF00FF00u) >> 8);
    return (double)i * (1.0 / 4294967296.0);
}

/* The bin of a piecewise-constant distribution holding xi: cdf[0] = 0 <= xi < cdf[n] = 1, the result b has
 * cdf[b] <= xi < cdf[b+1], so empty bins are never chosen. */
static int cdf_find(const double *cdf, int n, double xi) {
    int lo = 0, hi = n;
    while (hi - lo > 1) {
        int mid = lo + (hi - lo) / 2;
        if (cdf[mid] <= xi)
            lo = mid;
        else
            hi = mid;
    }
    return lo;
}

/* Rec. 709 luminance of a map pixel (a grey map is its own luminance): what the pattern importance-samples. */
static double env_luminance(const float *px, int channels) {
    if (channels == 1) return px[0];
    return 0.2126 * px[0] + 0.7152 * px[1] + 0.0722 * px[2];
}

/* Fill the n directions and weights of one environment light (docs/rendering.md, "The estimator"): the
 * Hammersley point (xi1, xi2) = ((k + 0.5)/n, radical_inverse(k)) picks a map row from the marginal of
 * p(row, column) = luminance * sin(theta_row) and a column from that row's conditional (continuous inversion
 * inside the chosen texel), so pdf_uv = p / mean(p) over the unit square and, in solid angle,
 * pdf(w) = pdf_uv / (2 pi^2 sin theta). The weight is L(w) * scale / (pdf(w) n), with L the chosen texel (the
 * map is piecewise constant, like the pdf). xi1 grows with k, so rows come in order and each row's conditional
 * is built once, in a buffer of one row: O(width * height) time, O(width + height) memory. With npdf, each
 * direction's N pdf(w) (what MIS weighs the pattern by) goes there; *total gets the normaliser (0: a black map).
 * Returns 0 on allocation failure. */
static int env_fill(const mr_light *light, int n, double (*direction)[3], double (*weight)[3], double *npdf,
                    double *total_out) {
    const mr_image *map = light->environment;
    const int width = map->width, height = map->height, channels = map->channels;
    double *row_cdf = malloc((size_t)(height + 1) * sizeof *row_cdf);
    double *col_cdf = malloc((size_t)(width + 1) * sizeof *col_cdf);
    if (row_cdf == NULL || col_cdf == NULL) {
        free(row_cdf);
        free(col_cdf);
        return 0;
    }
    row_cdf[0] = 0.0;
    for (int j = 0; j < height; j++) {
        double sum = 0.0;
        for (int i = 0; i < width; i++) sum += env_luminance(mr_image_at(map, i, j), channels);
        row_cdf[j + 1] = row_cdf[j] + sum * sin(MR_PI * (j + 0.5) / height);
    }
    const double total = row_cdf[height];
    *total_out = 0.0;
    if (!(total > 0.0 && isfinite(total))) {
        // A black map: no direction carries light (weight 0: the plan stores none of them).
        for (int k = 0; k < n; k++) {
            for (int c = 0; c < 3; c++) {
                direction[k][c] = c == 1 ? 1.0 : 0.0;
                weight[k][c] = 0.0;
            }
            if (npdf) npdf[k] = 0.0;
        }
        free(row_cdf);
        free(col_cdf);
        return 1;
    }
    for (int j = 1; j < height; j++) row_cdf[j] /= total;
    row_cdf[height] = 1.0;
    *total_out = total;

    // fmod first, so that whole turns (360, -720 ...) are the identity exactly.
    const double turn = fmod(light->rotation_degrees, 360.0) * MR_PI / 180.0;
    const double cos_turn = cos(turn), sin_turn = sin(turn);
    int row = -1;
    for (int k = 0; k < n; k++) {
        double xi1 = (k + 0.5) / n, xi2 = radical_inverse2((uint32_t)k);
        int j = cdf_find(row_cdf, height, xi1);
        if (j != row) {
            row = j;
            col_cdf[0] = 0.0;
            for (int i = 0; i < width; i++)
                col_cdf[i + 1] = col_cdf[i] + env_luminance(mr_image_at(map, i, j), channels);
            double row_total = col_cdf[width];
            for (int i = 1; i < width; i++) col_cdf[i] /= row_total;
            col_cdf[width] = 1.0;
        }
        int i = cdf_find(col_cdf, width, xi2);
        double dv = (xi1 - row_cdf[j]) / (row_cdf[j + 1] - row_cdf[j]);
        double du = (xi2 - col_cdf[i]) / (col_cdf[i + 1] - col_cdf[i]);
        double u = (i + du) / width, v = (j + dv) / height;
        double theta = MR_PI * v, phi = 2.0 * MR_PI * (u - 0.5);
        double sin_theta = sin(theta);
        double x = sin_theta * sin(phi), y = cos(theta), z = -sin_theta * cos(phi);
        direction[k][0] = x * cos_turn + z * sin_turn;
        direction[k][1] = y;
        direction[k][2] = -x * sin_turn + z * cos_turn;

        const float *px = mr_image_at(map, i, j);
        double pdf_uv = env_luminance(px, channels) * sin(MR_PI * (j + 0.5) / height) * width * height / total;
        double factor = pdf_uv > 0.0 && sin_theta > 0.0 ? 2.0 * MR_PI * MR_PI * sin_theta / (pdf_uv * n) : 0.0;
        for (int c = 0; c < 3; c++)
            weight[k][c] = (double)px[channels == 1 ? 0 : c] * light->intensity[c] * factor;
        if (npdf) npdf[k] = factor > 0.0 ? 1.0 / factor : 0.0;
    }
    free(row_cdf);
    free(col_cdf);
    return 1;
}

/* ---- reflection samples: directions about the mirror direction, combined with the pattern by MIS ------------- */

double mr_env_source_lookup(const env_source *source, const double w[3], double L[3]) {
    const mr_image *map = source->map;
    // Undo the rotation about +y, then the map's angles (env_fill: x = sin t sin p, y = cos t, z = -sin t cos p).
    double x = w[0] * source->cos_turn - w[2] * source->sin_turn;
    double z = w[0] * source->sin_turn + w[2] * source->cos_turn;
    double y = w[1] < -1.0 ? -1.0 : w[1] > 1.0 ? 1.0 : w[1];
    double theta = acos(y), phi = atan2(x, -z), sin_theta = hypot(x, z);
    double u = phi / (2.0 * MR_PI) + 0.5, v = theta / MR_PI;
    int i = (int)(u * map->width), j = (int)(v * map->height);
    i = i < 0 ? 0 : i >= map->width ? map->width - 1 : i;
    j = j < 0 ? 0 : j >= map->height ? map->height - 1 : j;
    const float *px = mr_image_at(map, i, j);
    for (int c = 0; c < 3; c++) L[c] = (double)px[map->channels == 1 ? 0 : c] * source->intensity[c];
    if (!(sin_theta > 1e-12)) return INFINITY; // the poles: a set of measure zero the pattern never leaves empty
    double pdf_uv = env_luminance(px, map->channels) * sin(MR_PI * (j + 0.5) / map->height) * map->width *
                    map->height / source->total;
    return source->n * pdf_uv / (2.0 * MR_PI * MR_PI * sin_theta);
}

/* Direction k of the m of lobe j, as slopes of a lobe of unit widths: a Hammersley point mapped through the unit
 * GGX slope distribution's inverse CDF (radius^2 = xi / (1 - xi)), each lobe turned by a golden-ratio fraction of
 * a turn so that no two lobes line up. The same for every hit: tabled once per plan. */
static void reflection_unit_slopes(int j, int k, int m, double slopes[2]) {
    const double xi1 = (k + 0.5) / m, xi2 = fmod(radical_inverse2((uint32_t)k) + 0.6180339887498949 * j, 1.0);
    const double radius = sqrt(xi1 / (1.0 - xi1)), phi = 2.0 * MR_PI * xi2;
    slopes[0] = radius * cos(phi);
    slopes[1] = radius * sin(phi);
}

void mr_env_table_free(env_table *env) {
    free(env->direction);
    free(env->weight);
    free(env->mis_npdf);
    free(env->unit_slopes);
    free(env->sources);
    memset(env, 0, sizeof *env);
}

mr_status mr_env_table_setup(const mr_scene *scene, env_table *env) {
    int total = 0, lights = 0, reflections = 0;
    for (int l = 0; l < scene->light_count; l++)
        if (scene->lights[l].type == MR_LIGHT_ENVIRONMENT) {
            total += mr_env_light_samples(&scene->lights[l]);
            lights++;
            reflections = MR_MAX(reflections, scene->lights[l].reflection_samples);
        }
    env->count = total;
    if (total == 0) return MR_OK;
    env->direction = malloc((size_t)total * sizeof *env->direction);
    env->weight = malloc((size_t)total * sizeof *env->weight);
    env->sources = calloc((size_t)lights, sizeof *env->sources);
    if (env->direction == NULL || env->weight == NULL || env->sources == NULL) goto oom;
    if (reflections > 0) {
        env->mis_npdf = malloc((size_t)total * sizeof *env->mis_npdf);
        env->unit_slopes = malloc((size_t)reflections * sizeof *env->unit_slopes);
        if (env->mis_npdf == NULL || env->unit_slopes == NULL) goto oom;
        env->reflections = reflections;
        int next = 0;
        for (int j = 0; j < REFLECTION_LOBES; j++) {
            env->per_lobe[j] = reflections / REFLECTION_LOBES + (j < reflections % REFLECTION_LOBES);
            for (int k = 0; k < env->per_lobe[j]; k++)
                reflection_unit_slopes(j, k, env->per_lobe[j], env->unit_slopes[next++]);
        }
    }
    int offset = 0;
    for (int l = 0; l < scene->light_count; l++) {
        const mr_light *light = &scene->lights[l];
        if (light->type != MR_LIGHT_ENVIRONMENT) continue;
        int n = mr_env_light_samples(light);
        env_source *source = &env->sources[env->source_count++];
        source->map = light->environment;
        source->n = n;
        const double turn = fmod(light->rotation_degrees, 360.0) * MR_PI / 180.0;
        source->cos_turn = cos(turn);
        source->sin_turn = sin(turn);
        for (int c = 0; c < 3; c++) source->intensity[c] = light->intensity[c];
        source->reflections = reflections > 0 && light->reflection_samples > 0;
        double *npdf = env->mis_npdf ? env->mis_npdf + offset : NULL;
        if (!env_fill(light, n, env->direction + offset, env->weight + offset, npdf, &source->total)) goto oom;
        if (npdf && !source->reflections)
            for (int k = 0; k < n; k++) npdf[k] = 0.0; // this light's pattern keeps its plain weights
        if (!(source->total > 0.0)) source->reflections = 0;
        offset += n;
    }
    return MR_OK;
oom:
    mr_env_table_free(env);
    return mr_fail(MR_ERR_NOMEM, "render plan: out of memory for %d environment directions", total);
}
