/* scene.c — the paper's fit scene, environment lights, scene validation and the enum names of render.h. */
#include <math.h>
#include <string.h>

#include "../mr_internal.h"
#include "render.h"
#include "vec3.h"

static const char *const component_names[MR_COMPONENT_COUNT] = {"full", "diffuse", "specular"};
static const char *const fit_light_names[MR_FIT_LIGHT_COUNT] = {"45", "frontal"};

/* Index of `name` in a name table of `count` entries, or -1. */
static int find_name(const char *const *names, int count, const char *name) {
    for (int i = 0; i < count; i++)
        if (name != NULL && strcmp(name, names[i]) == 0) return i;
    return -1;
}

const char *mr_component_name(mr_component component) {
    return (unsigned)component < MR_COMPONENT_COUNT ? component_names[component] : NULL;
}

mr_status mr_component_from_name(const char *name, mr_component *out) {
    int index = find_name(component_names, MR_COMPONENT_COUNT, name);
    if (index < 0)
        return mr_fail(MR_ERR_INVALID_ARG, "unknown component '%s' (valid: full, diffuse, specular)",
                       name ? name : "(null)");
    *out = (mr_component)index;
    return MR_OK;
}

const char *mr_fit_light_name(mr_fit_light light) {
    return (unsigned)light < MR_FIT_LIGHT_COUNT ? fit_light_names[light] : NULL;
}

mr_status mr_fit_light_from_name(const char *name, mr_fit_light *out) {
    int index = find_name(fit_light_names, MR_FIT_LIGHT_COUNT, name);
    if (index < 0)
        return mr_fail(MR_ERR_INVALID_ARG, "unknown light position '%s' (valid: 45, frontal)", name ? name : "(null)");
    *out = (mr_fit_light)index;
    return MR_OK;
}

/* Fit-scene constants (paper section 4.1 gives the sphere and the light; the camera is ours, see render.h). */
#define FIT_CAMERA_DISTANCE 4.0
#define FIT_CAMERA_FOV_Y 35.0
#define FIT_LIGHT_DISTANCE 3.0
#define FIT_LIGHT_ANGLE_DEGREES 45.0
#define FIT_DEFAULT_SIZE 512
#define FIT_DEFAULT_INTENSITY 10.0

mr_camera mr_camera_paper(void) {
    const mr_camera camera = {{0.0, 0.0, -1.5}, {0.0, 0.0, 0.0}, {0.0, 1.0, 0.0}, 40.0};
    return camera;
}

mr_scene mr_scene_fit(const mr_fit_scene_options *opts) {
    mr_fit_scene_options o = {0};
    if (opts != NULL) o = *opts;
    int size = o.size > 0 ? o.size : FIT_DEFAULT_SIZE;
    double intensity = o.intensity > 0.0 ? o.intensity : FIT_DEFAULT_INTENSITY;
    double angle = o.light == MR_FIT_LIGHT_FRONTAL ? 0.0 : FIT_LIGHT_ANGLE_DEGREES * MR_PI / 180.0;

    mr_scene scene;
    memset(&scene, 0, sizeof scene);
    scene.width = size;
    scene.height = size;
    scene.camera = (mr_camera){{0.0, 0.0, FIT_CAMERA_DISTANCE}, {0.0, 0.0, 0.0}, {0.0, 1.0, 0.0}, FIT_CAMERA_FOV_Y};
    scene.shape = (mr_shape){MR_SHAPE_SPHERE, {0.0, 0.0, 0.0}, 1.0, NULL};
    scene.light_count = 1;
    scene.lights[0].type = MR_LIGHT_POINT;
    // The light turns from the view axis (+z, towards the camera) about +y, towards +x (image right).
    scene.lights[0].position[0] = FIT_LIGHT_DISTANCE * sin(angle);
    scene.lights[0].position[1] = 0.0;
    scene.lights[0].position[2] = FIT_LIGHT_DISTANCE * cos(angle);
    for (int c = 0; c < 3; c++) scene.lights[0].intensity[c] = intensity;
    return scene;
}

mr_status mr_scene_fit_light_to_mesh(mr_scene *scene, const mr_mesh *mesh, mr_fit_light light) {
    if (scene == NULL || scene->light_count < 1)
        return mr_fail(MR_ERR_INVALID_ARG, "fit light for a mesh: %s", scene == NULL ? "NULL scene" : "no light");
    double centre[3] = {0.0, 0.0, 0.0}, radius = 1.0;
    if (mesh != NULL) {
        double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
        for (int v = 0; v < mesh->vertex_count; v++)
            for (int i = 0; i < 3; i++) {
                lo[i] = fmin(lo[i], mesh->positions[3 * v + i]);
                hi[i] = fmax(hi[i], mesh->positions[3 * v + i]);
            }
        radius = 0.0;
        for (int i = 0; i < 3; i++) centre[i] = 0.5 * (lo[i] + hi[i]);
        for (int v = 0; v < mesh->vertex_count; v++) {
            double d2 = 0.0;
            for (int i = 0; i < 3; i++) d2 += (mesh->positions[3 * v + i] - centre[i]) * (mesh->positions[3 * v + i] -
                                                                                         centre[i]);
            radius = fmax(radius, sqrt(d2));
        }
    }
    const mr_camera *cam = &scene->camera;
    double back[3], right[3], len = 0.0; /* towards the camera; the camera's right = up x back */
    for (int i = 0; i < 3; i++) back[i] = cam->position[i] - cam->target[i], len += back[i] * back[i];
    for (int i = 0; i < 3; i++) back[i] /= sqrt(len);
    right[0] = cam->up[1] * back[2] - cam->up[2] * back[1];
    right[1] = cam->up[2] * back[0] - cam->up[0] * back[2];
    right[2] = cam->up[0] * back[1] - cam->up[1] * back[0];
    len = sqrt(right[0] * right[0] + right[1] * right[1] + right[2] * right[2]);
    double angle = light == MR_FIT_LIGHT_FRONTAL ? 0.0 : atan(1.0); /* pi/4 */
    for (int i = 0; i < 3; i++)
        scene->lights[0].position[i] = centre[i] + 3.0 * radius * (cos(angle) * back[i] + sin(angle) * right[i] / len);
    for (int c = 0; c < 3; c++) scene->lights[0].intensity[c] *= radius * radius;
    return MR_OK;
}

mr_light mr_light_environment(const mr_image *map, double scale, double rotation_degrees, int samples) {
    mr_light light;
    memset(&light, 0, sizeof light);
    light.type = MR_LIGHT_ENVIRONMENT;
    for (int c = 0; c < 3; c++) light.intensity[c] = scale;
    light.environment = map;
    light.rotation_degrees = rotation_degrees;
    light.samples = samples;
    return light;
}

/* An environment light's own values: the map (size, channels, every value finite and >= 0), rotation and
 * sample count. */
static mr_status validate_environment(int index, const mr_light *light) {
    const mr_image *map = light->environment;
    if (map == NULL || map->pixels == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "scene: light %d is an environment light without a map", index);
    if (map->width < 1 || map->height < 1 || (map->channels != 1 && map->channels != 3 && map->channels != 4))
        return mr_fail(MR_ERR_INVALID_ARG, "scene: light %d: environment map %dx%d with %d channels: expected 1, 3 "
                       "or 4 channels", index, map->width, map->height, map->channels);
    if (!isfinite(light->rotation_degrees))
        return mr_fail(MR_ERR_INVALID_ARG, "scene: light %d: environment rotation must be finite", index);
    if (light->samples < 0 || light->samples > MR_ENV_MAX_SAMPLES)
        return mr_fail(MR_ERR_INVALID_ARG, "scene: light %d: %d environment samples: expected 0 (default %d) to %d",
                       index, light->samples, MR_ENV_DEFAULT_SAMPLES, MR_ENV_MAX_SAMPLES);
    if (light->reflection_samples < 0 || light->reflection_samples > MR_ENV_MAX_REFLECTION_SAMPLES)
        return mr_fail(MR_ERR_INVALID_ARG, "scene: light %d: %d reflection samples: expected 0 (none) to %d", index,
                       light->reflection_samples, MR_ENV_MAX_REFLECTION_SAMPLES);
    const int colour_channels = map->channels == 1 ? 1 : 3;
    for (int y = 0; y < map->height; y++)
        for (int x = 0; x < map->width; x++) {
            const float *px = mr_image_at(map, x, y);
            for (int c = 0; c < colour_channels; c++)
                if (!(isfinite(px[c]) && px[c] >= 0.0f))
                    return mr_fail(MR_ERR_INVALID_ARG, "scene: light %d: environment map value %g at pixel (%d, %d): "
                                   "expected finite radiance >= 0", index, (double)px[c], x, y);
        }
    return MR_OK;
}

mr_status mr_scene_validate(const mr_scene *scene) {
    if (scene->width < 1 || scene->height < 1 || scene->width > MR_RENDER_MAX_SIZE ||
        scene->height > MR_RENDER_MAX_SIZE)
        return mr_fail(MR_ERR_INVALID_ARG, "scene: image size %dx%d: each side must be in [1, %d]", scene->width,
                       scene->height, MR_RENDER_MAX_SIZE);
    const mr_camera *cam = &scene->camera;
    if (!vec3_is_finite(cam->position) || !vec3_is_finite(cam->target) || !vec3_is_finite(cam->up))
        return mr_fail(MR_ERR_INVALID_ARG, "scene: camera position, target and up must be finite");
    if (!(cam->fov_y_degrees > 0.0 && cam->fov_y_degrees < 180.0))
        return mr_fail(MR_ERR_INVALID_ARG, "scene: camera field of view %g: expected (0, 180) degrees",
                       cam->fov_y_degrees);
    double forward[3], side[3];
    vec3_sub(cam->target, cam->position, forward);
    if (vec3_normalize(forward) <= 0.0)
        return mr_fail(MR_ERR_INVALID_ARG, "scene: camera target equals its position");
    vec3_cross(forward, cam->up, side);
    if (vec3_length(side) < 1e-9 * vec3_length(cam->up) || vec3_length(cam->up) == 0.0)
        return mr_fail(MR_ERR_INVALID_ARG, "scene: camera up vector is zero or parallel to the view direction");
    if ((unsigned)scene->shape.type >= MR_SHAPE_TYPE_COUNT)
        return mr_fail(MR_ERR_INVALID_ARG, "scene: unknown shape type %d", (int)scene->shape.type);
    const int sphere = scene->shape.type == MR_SHAPE_SPHERE;
    if (sphere) {
        if (!vec3_is_finite(scene->shape.center) || !(scene->shape.radius > 0.0 && isfinite(scene->shape.radius)))
            return mr_fail(MR_ERR_INVALID_ARG, "scene: sphere radius %g: expected a finite value > 0",
                           scene->shape.radius);
        double to_camera[3];
        vec3_sub(cam->position, scene->shape.center, to_camera);
        if (vec3_length(to_camera) <= scene->shape.radius)
            return mr_fail(MR_ERR_INVALID_ARG, "scene: the camera is inside the sphere");
    } else {
        // A mesh may surround the camera (an interior); the primary rays simply see its inside.
        if (scene->shape.mesh == NULL) return mr_fail(MR_ERR_INVALID_ARG, "scene: mesh shape without a mesh");
        mr_status status = mr_mesh_validate(scene->shape.mesh);
        if (status != MR_OK) return mr_fail_context(status, "scene");
    }
    if (scene->light_count < 1 || scene->light_count > MR_SCENE_MAX_LIGHTS)
        return mr_fail(MR_ERR_INVALID_ARG, "scene: %d lights: expected 1 to %d", scene->light_count,
                       MR_SCENE_MAX_LIGHTS);
    long env_samples = 0;
    for (int i = 0; i < scene->light_count; i++) {
        const mr_light *light = &scene->lights[i];
        if ((unsigned)light->type >= MR_LIGHT_TYPE_COUNT)
            return mr_fail(MR_ERR_INVALID_ARG, "scene: light %d has unknown type %d", i, (int)light->type);
        if (light->type == MR_LIGHT_ENVIRONMENT) {
            if (!vec3_is_finite(light->intensity) || light->intensity[0] < 0.0 || light->intensity[1] < 0.0 ||
                light->intensity[2] < 0.0)
                return mr_fail(MR_ERR_INVALID_ARG, "scene: light %d: environment scale must be finite and >= 0", i);
            mr_status status = validate_environment(i, light);
            if (status != MR_OK) return status;
            env_samples += light->samples > 0 ? light->samples : MR_ENV_DEFAULT_SAMPLES;
            if (env_samples > MR_ENV_MAX_SAMPLES)
                return mr_fail(MR_ERR_INVALID_ARG, "scene: the environment lights take %ld samples together: at most "
                               "%d", env_samples, MR_ENV_MAX_SAMPLES);
            continue;
        }
        if (!vec3_is_finite(light->position) || !vec3_is_finite(light->intensity))
            return mr_fail(MR_ERR_INVALID_ARG, "scene: light %d: position and intensity must be finite", i);
        if (light->intensity[0] < 0.0 || light->intensity[1] < 0.0 || light->intensity[2] < 0.0)
            return mr_fail(MR_ERR_INVALID_ARG, "scene: light %d: negative intensity", i);
        double to_light[3];
        vec3_sub(light->position, scene->shape.center, to_light);
        if (sphere && vec3_length(to_light) <= scene->shape.radius)
            return mr_fail(MR_ERR_INVALID_ARG, "scene: light %d is inside the sphere", i);
    }
    if (scene->threads < 0 || scene->threads > 1024)
        return mr_fail(MR_ERR_INVALID_ARG, "scene: threads %d: expected 0 (automatic) to 1024", scene->threads);
    if (scene->highlight_samples != 0 && scene->highlight_samples != 1)
        return mr_fail(MR_ERR_INVALID_ARG, "scene: highlight_samples %d: expected 0 (on) or 1 (off)",
                       scene->highlight_samples);
    if (scene->edge_samples < 0 || scene->edge_samples > 16)
        return mr_fail(MR_ERR_INVALID_ARG, "scene: edge_samples %d: expected 0 (default %d) to 16",
                       scene->edge_samples, MR_SCENE_DEFAULT_EDGE_SAMPLES);
    if (!vec3_is_finite(scene->background))
        return mr_fail(MR_ERR_INVALID_ARG, "scene: background radiance must be finite");
    return MR_OK;
}
