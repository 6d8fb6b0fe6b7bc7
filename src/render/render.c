/*
 * render.c — render plans (geometry traced once per scene) and material renders (BRDF evaluations only).
 * Contract and design in render.h.
 *
 * A plan is built in two stages, kept apart so later object and light types slot in without touching the
 * other stage or mr_render:
 *   1. primary visibility: one ray per pixel centre -> hit records (pixel, position, shading frame, view
 *      direction); the intersector is chosen by the shape type;
 *   2. lighting: each light type turns hit records into shading samples (local view and light directions and a
 *      weight); a point light gives at most one sample per hit and needs no shadow ray on a convex object.
 */
#include <stdlib.h>
#include <string.h>

#include "../mr_internal.h"
#include "render.h"
#include "vec3.h"

typedef struct hit_record {
    int pixel;
    double position[3];
    double normal[3];
    double tangent[3];
    double bitangent[3];
    double view_local[3]; /* unit direction towards the camera, in the shading frame */
} hit_record;

typedef struct shading_sample {
    double view[3];   /* local frame, unit, z > 0 */
    double light[3];  /* local frame, unit, z > 0 */
    double weight[3]; /* radiance = f_r(view, light) * weight, per RGB channel */
} shading_sample;

struct mr_render_plan {
    mr_scene scene;
    unsigned char *object_mask; /* width*height: 1 where the primary ray hits the object */
    int object_pixels;
    int lit_pixels;
    int *lit_pixel_index; /* [lit_pixels]: image pixel of each lit pixel, ascending */
    int *sample_begin;    /* [lit_pixels + 1]: samples of lit pixel i are sample_begin[i] .. [i+1]-1 */
    shading_sample *samples;
};

/* Orthonormal basis with n as third axis, continuous except at n.z = -1 (Duff et al., "Building an
 * Orthonormal Basis, Revisited", JCGT 6(1), 2017). Isotropic models only need n; the tangents give
 * anisotropic models and normal maps a defined frame later. */
static void frame_from_normal(const double n[3], double t[3], double b[3]) {
    double sign = n[2] >= 0.0 ? 1.0 : -1.0;
    double a = -1.0 / (sign + n[2]);
    double c = n[0] * n[1] * a;
    t[0] = 1.0 + sign * n[0] * n[0] * a;
    t[1] = sign * c;
    t[2] = -sign * n[0];
    b[0] = c;
    b[1] = sign + n[1] * n[1] * a;
    b[2] = -n[1];
}

static void to_local(const hit_record *hit, const double world[3], double local[3]) {
    local[0] = vec3_dot(hit->tangent, world);
    local[1] = vec3_dot(hit->bitangent, world);
    local[2] = vec3_dot(hit->normal, world);
}

/* Nearest intersection of the ray origin + t*dir (dir unit) with the sphere, t > 0; returns 0 on a miss. */
static int intersect_sphere(const mr_shape *sphere, const double origin[3], const double dir[3], double *t_out) {
    double oc[3];
    vec3_sub(origin, sphere->center, oc);
    double b = vec3_dot(oc, dir);
    double c = vec3_dot(oc, oc) - sphere->radius * sphere->radius;
    double discriminant = b * b - c;
    if (discriminant < 0.0) return 0;
    double root = sqrt(discriminant);
    // The camera is outside the sphere (mr_scene_validate), so the nearer root is the visible surface.
    double t = -b - root;
    if (!(t > 0.0)) return 0;
    *t_out = t;
    return 1;
}

/* Stage 1: primary visibility. Fills hits[] (capacity width*height) and the object mask. */
static int trace_primary(const mr_scene *scene, unsigned char *mask, hit_record *hits) {
    const mr_camera *cam = &scene->camera;
    double forward[3], right[3], up[3];
    vec3_sub(cam->target, cam->position, forward);
    vec3_normalize(forward);
    vec3_cross(forward, cam->up, right);
    vec3_normalize(right);
    vec3_cross(right, forward, up);
    double tan_half = tan(0.5 * cam->fov_y_degrees * MR_PI / 180.0);
    double aspect = (double)scene->width / (double)scene->height;

    int count = 0;
    for (int y = 0; y < scene->height; y++) {
        double v = (1.0 - 2.0 * (y + 0.5) / scene->height) * tan_half;
        for (int x = 0; x < scene->width; x++) {
            double u = (2.0 * (x + 0.5) / scene->width - 1.0) * tan_half * aspect;
            double dir[3];
            for (int k = 0; k < 3; k++) dir[k] = forward[k] + u * right[k] + v * up[k];
            vec3_normalize(dir);
            int pixel = y * scene->width + x;
            double t;
            if (!intersect_sphere(&scene->shape, cam->position, dir, &t)) continue;
            mask[pixel] = 1;
            hit_record *hit = &hits[count];
            hit->pixel = pixel;
            for (int k = 0; k < 3; k++) {
                hit->position[k] = cam->position[k] + t * dir[k];
                hit->normal[k] = (hit->position[k] - scene->shape.center[k]) / scene->shape.radius;
            }
            vec3_normalize(hit->normal);
            frame_from_normal(hit->normal, hit->tangent, hit->bitangent);
            double to_camera[3] = {-dir[0], -dir[1], -dir[2]};
            to_local(hit, to_camera, hit->view_local);
            count++;
        }
    }
    return count;
}

/* Stage 2 for a point light: the exact contribution I*cos(theta_l)/d^2, no shadow ray (convex object). Returns
 * 1 and fills *sample if the point is lit and seen from the front, 0 otherwise. */
static int point_light_sample(const mr_light *light, const hit_record *hit, shading_sample *sample) {
    if (!(hit->view_local[2] > 0.0)) return 0;
    double to_light[3];
    vec3_sub(light->position, hit->position, to_light);
    double distance = vec3_normalize(to_light);
    if (!(distance > 0.0)) return 0;
    double local[3];
    to_local(hit, to_light, local);
    if (!(local[2] > 0.0)) return 0;
    double falloff = local[2] / (distance * distance);
    for (int k = 0; k < 3; k++) {
        sample->view[k] = hit->view_local[k];
        sample->light[k] = local[k];
        sample->weight[k] = light->intensity[k] * falloff;
    }
    return 1;
}

void mr_render_plan_free(mr_render_plan *plan) {
    if (plan == NULL) return;
    free(plan->object_mask);
    free(plan->lit_pixel_index);
    free(plan->sample_begin);
    free(plan->samples);
    free(plan);
}

mr_status mr_render_plan_create(const mr_scene *scene, mr_render_plan **out) {
    if (scene == NULL || out == NULL) return mr_fail(MR_ERR_INVALID_ARG, "render plan: NULL scene or output");
    mr_status status = mr_scene_validate(scene);
    if (status != MR_OK) return status;

    size_t pixel_count = (size_t)scene->width * (size_t)scene->height;
    mr_render_plan *plan = calloc(1, sizeof *plan);
    hit_record *hits = NULL;
    if (plan == NULL) goto oom;
    plan->scene = *scene;
    plan->object_mask = calloc(pixel_count, 1);
    hits = malloc(pixel_count * sizeof *hits);
    if (plan->object_mask == NULL || hits == NULL) goto oom;

    int hit_count = trace_primary(scene, plan->object_mask, hits);
    plan->object_pixels = hit_count;
    size_t max_samples = (size_t)hit_count * (size_t)scene->light_count;
    plan->lit_pixel_index = malloc(((size_t)hit_count + 1) * sizeof *plan->lit_pixel_index);
    plan->sample_begin = malloc(((size_t)hit_count + 1) * sizeof *plan->sample_begin);
    plan->samples = malloc((max_samples + 1) * sizeof *plan->samples);
    if (plan->lit_pixel_index == NULL || plan->sample_begin == NULL || plan->samples == NULL) goto oom;

    int lit = 0, samples = 0;
    for (int h = 0; h < hit_count; h++) {
        int first = samples;
        for (int l = 0; l < scene->light_count; l++)
            samples += point_light_sample(&scene->lights[l], &hits[h], &plan->samples[samples]);
        if (samples > first) {
            plan->lit_pixel_index[lit] = hits[h].pixel;
            plan->sample_begin[lit] = first;
            lit++;
        }
    }
    plan->sample_begin[lit] = samples;
    plan->lit_pixels = lit;
    free(hits);
    *out = plan;
    return MR_OK;

oom:
    free(hits);
    mr_render_plan_free(plan);
    return mr_fail(MR_ERR_NOMEM, "render plan: out of memory for a %dx%d scene", scene->width, scene->height);
}

const mr_scene *mr_render_plan_scene(const mr_render_plan *plan) { return &plan->scene; }

int mr_render_plan_lit_pixel_count(const mr_render_plan *plan) { return plan->lit_pixels; }

int mr_render_plan_object_pixel_count(const mr_render_plan *plan) { return plan->object_pixels; }

static mr_status check_target(const mr_render_plan *plan, const mr_image *image, const char *what) {
    if (image == NULL) return MR_OK;
    if (image->width != plan->scene.width || image->height != plan->scene.height || image->channels != 3)
        return mr_fail(MR_ERR_INVALID_ARG, "render: %s image is %dx%dx%d, the plan needs %dx%dx3", what,
                       image->width, image->height, image->channels, plan->scene.width, plan->scene.height);
    return MR_OK;
}

/* Background where the primary ray missed, black on the object; lit pixels are overwritten afterwards. */
static void fill_unlit(const mr_render_plan *plan, mr_image *image, int with_background) {
    size_t pixel_count = (size_t)plan->scene.width * (size_t)plan->scene.height;
    for (size_t p = 0; p < pixel_count; p++)
        for (int c = 0; c < 3; c++)
            image->pixels[p * 3 + c] =
                (with_background && !plan->object_mask[p]) ? (float)plan->scene.background[c] : 0.0f;
}

mr_status mr_render_components_into(const mr_render_plan *plan, const mr_brdf_model *model, const double *values,
                                    mr_image *diffuse, mr_image *specular) {
    if (plan == NULL || model == NULL || values == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "render: NULL plan, model or values");
    mr_status status = check_target(plan, diffuse, "diffuse");
    if (status == MR_OK) status = check_target(plan, specular, "specular");
    if (status != MR_OK) return status;

    mr_brdf_state state;
    model->prepare(model, values, state.bytes);
    // The background is light that never met the material; it belongs to the full render only, and a
    // diffuse-only or specular-only render is black there, so diffuse + specular = full on the object.
    if (diffuse) fill_unlit(plan, diffuse, 0);
    if (specular) fill_unlit(plan, specular, 0);

    const int lit = plan->lit_pixels;
#pragma omp parallel for schedule(static)
    for (int i = 0; i < lit; i++) {
        double sum_d[3] = {0.0, 0.0, 0.0}, sum_s[3] = {0.0, 0.0, 0.0};
        for (int s = plan->sample_begin[i]; s < plan->sample_begin[i + 1]; s++) {
            const shading_sample *sample = &plan->samples[s];
            double fd[3], fs[3];
            model->eval(state.bytes, sample->view, sample->light, diffuse ? fd : NULL, specular ? fs : NULL);
            for (int c = 0; c < 3; c++) {
                if (diffuse) sum_d[c] += fd[c] * sample->weight[c];
                if (specular) sum_s[c] += fs[c] * sample->weight[c];
            }
        }
        size_t p = (size_t)plan->lit_pixel_index[i] * 3;
        for (int c = 0; c < 3; c++) {
            if (diffuse) diffuse->pixels[p + c] = (float)sum_d[c];
            if (specular) specular->pixels[p + c] = (float)sum_s[c];
        }
    }
    return MR_OK;
}

mr_status mr_render_into(const mr_render_plan *plan, const mr_brdf_model *model, const double *values,
                         mr_component component, mr_image *image) {
    if (plan == NULL || model == NULL || values == NULL || image == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "render: NULL plan, model, values or image");
    if (component != MR_COMPONENT_FULL) {
        if (component == MR_COMPONENT_DIFFUSE) return mr_render_components_into(plan, model, values, image, NULL);
        if (component == MR_COMPONENT_SPECULAR) return mr_render_components_into(plan, model, values, NULL, image);
        return mr_fail(MR_ERR_INVALID_ARG, "render: unknown component %d", (int)component);
    }
    mr_status status = check_target(plan, image, "output");
    if (status != MR_OK) return status;

    mr_brdf_state state;
    model->prepare(model, values, state.bytes);
    fill_unlit(plan, image, 1);
    const int lit = plan->lit_pixels;
#pragma omp parallel for schedule(static)
    for (int i = 0; i < lit; i++) {
        double sum[3] = {0.0, 0.0, 0.0};
        for (int s = plan->sample_begin[i]; s < plan->sample_begin[i + 1]; s++) {
            const shading_sample *sample = &plan->samples[s];
            double fd[3], fs[3];
            model->eval(state.bytes, sample->view, sample->light, fd, fs);
            for (int c = 0; c < 3; c++) sum[c] += (fd[c] + fs[c]) * sample->weight[c];
        }
        size_t p = (size_t)plan->lit_pixel_index[i] * 3;
        for (int c = 0; c < 3; c++) image->pixels[p + c] = (float)sum[c];
    }
    return MR_OK;
}

mr_status mr_render(const mr_render_plan *plan, const mr_brdf_model *model, const double *values,
                    mr_component component, mr_image **out) {
    if (plan == NULL || out == NULL) return mr_fail(MR_ERR_INVALID_ARG, "render: NULL plan or output");
    mr_image *image = NULL;
    mr_status status = mr_image_create(plan->scene.width, plan->scene.height, 3, &image);
    if (status != MR_OK) return status;
    status = mr_render_into(plan, model, values, component, image);
    if (status != MR_OK) {
        mr_image_free(image);
        return status;
    }
    *out = image;
    return MR_OK;
}
