/*
 * render_support.h — what the render and fit tests share: environment maps made for the tests, the fit scene's plan
 * (point-lit, or lit by a constant environment), image comparison, deterministic random numbers. Included by test
 * files only (static inline: each test binary gets its own copy).
 */
#ifndef MR_TEST_RENDER_SUPPORT_H
#define MR_TEST_RENDER_SUPPORT_H

#include <math.h>
#include <stdint.h>
#include <string.h>

#include "harness.h"
#include "matremap.h"

#define TEST_PI 3.14159265358979323846

/* A width x height map with `channels` channels, every value `value`. */
static inline mr_image *constant_map(int width, int height, int channels, float value) {
    mr_image *map = NULL;
    MR_CHECK_OK(mr_image_create(width, height, channels, &map));
    if (map == NULL) return NULL;
    for (size_t i = 0; i < mr_image_value_count(map); i++) map->pixels[i] = value;
    return map;
}

/* The default fit scene's plan at `size` (its renders on one thread by the automatic rule). */
static inline mr_render_plan *fit_scene_plan(int size) {
    mr_fit_scene_options o = {0};
    o.size = size;
    mr_scene scene = mr_scene_fit(&o);
    mr_render_plan *plan = NULL;
    MR_CHECK_OK(mr_render_plan_create(&scene, &plan));
    return plan;
}

/* The fit scene at `size` with its point light replaced by a constant environment of radiance 0.5 (16 samples):
 * a plan that is not point-lit. */
static inline mr_render_plan *environment_fit_plan(int size) {
    mr_image *map = constant_map(8, 4, 3, 0.5f);
    mr_fit_scene_options o = {0};
    o.size = size;
    mr_scene scene = mr_scene_fit(&o);
    scene.lights[0] = mr_light_environment(map, 1.0, 0.0, 16);
    mr_render_plan *plan = NULL;
    MR_CHECK_OK(mr_render_plan_create(&scene, &plan));
    mr_image_free(map); // the plan keeps what it needs of the map
    return plan;
}

static inline int same_pixels(const mr_image *a, const mr_image *b) {
    return a != NULL && b != NULL && a->width == b->width && a->height == b->height && a->channels == b->channels &&
           memcmp(a->pixels, b->pixels, mr_image_value_count(a) * sizeof(float)) == 0;
}

/* The direction of map position (u, v) turned by `degrees` about +y, from render.h's header comment alone:
 * theta = pi v, phi = 2 pi (u - 0.5), w = (sin theta sin phi, cos theta, -sin theta cos phi), then the
 * right-handed rotation about +y (+z goes to +x for 90 degrees). */
static inline void map_direction(double u, double v, double degrees, double w[3]) {
    double theta = TEST_PI * v, phi = 2.0 * TEST_PI * (u - 0.5), a = degrees * TEST_PI / 180.0;
    double x = sin(theta) * sin(phi), y = cos(theta), z = -sin(theta) * cos(phi);
    w[0] = x * cos(a) + z * sin(a);
    w[1] = y;
    w[2] = -x * sin(a) + z * cos(a);
}

/* Map whose texel centres hold R = 1 + w.y, G = 1 + 0.8 w.x, B = 1.2 - w.z (w the texel centre's direction
 * by render.h's convention): smooth, different in every channel and every axis. */
static inline mr_image *linear_map(int width, int height) {
    mr_image *map = NULL;
    MR_CHECK_OK(mr_image_create(width, height, 3, &map));
    if (map == NULL) return NULL;
    for (int j = 0; j < height; j++)
        for (int i = 0; i < width; i++) {
            double w[3];
            map_direction((i + 0.5) / width, (j + 0.5) / height, 0.0, w);
            float *px = mr_image_at(map, i, j);
            px[0] = (float)(1.0 + w[1]);
            px[1] = (float)(1.0 + 0.8 * w[0]);
            px[2] = (float)(1.2 - w[2]);
        }
    return map;
}

/* xorshift64*: the tests' own deterministic random numbers in [0, 1). */
static inline double test_random(uint64_t *state) {
    *state ^= *state >> 12;
    *state ^= *state << 25;
    *state ^= *state >> 27;
    return (double)((*state * 2685821657736338717ull) >> 11) * (1.0 / 9007199254740992.0);
}

#endif /* MR_TEST_RENDER_SUPPORT_H */
