/*
 * render.c — render plans (geometry traced once per scene) and material renders (BRDF evaluations only).
 * Contract and design in render.h.
 *
 * A plan is built in two stages, kept apart so later object and light types slot in without touching the
 * other stage or mr_render:
 *   1. primary visibility: a ray through each pixel centre (n x n sub-pixel rays on the silhouette) -> hit
 *      records (position, shading frame, view direction); the intersector is chosen by the shape type;
 *   2. lighting: each light type turns hit records into shading samples (local view and light directions and a
 *      weight); a point light gives at most one sample per hit and needs no shadow ray on a convex object.
 * Rows are traced in parallel into per-row buffers and concatenated in image order, so the plan is identical
 * for any thread count.
 */
#include <limits.h>
#include <stdlib.h>
#include <string.h>

#include "../mr_internal.h"
#include "render.h"
#include "vec3.h"

typedef struct hit_record {
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
    float *coverage;      /* width*height: fraction of each pixel the object covers (1 inside, 0 outside) */
    int object_pixels;    /* pixels with coverage > 0 */
    int lit_pixels;
    int *lit_pixel_index; /* [lit_pixels]: image pixel of each lit pixel, ascending */
    int *sample_begin;    /* [lit_pixels + 1]: samples of lit pixel i are sample_begin[i] .. [i+1]-1 */
    shading_sample *samples;
};

/* The camera as the primary-ray generator needs it. */
typedef struct camera_frame {
    double origin[3], forward[3], right[3], up[3];
    double tan_half, aspect;
    int width, height;
} camera_frame;

static void camera_frame_init(const mr_scene *scene, camera_frame *cf) {
    const mr_camera *cam = &scene->camera;
    for (int k = 0; k < 3; k++) cf->origin[k] = cam->position[k];
    vec3_sub(cam->target, cam->position, cf->forward);
    vec3_normalize(cf->forward);
    vec3_cross(cf->forward, cam->up, cf->right);
    vec3_normalize(cf->right);
    vec3_cross(cf->right, cf->forward, cf->up);
    cf->tan_half = tan(0.5 * cam->fov_y_degrees * MR_PI / 180.0);
    cf->aspect = (double)scene->width / (double)scene->height;
    cf->width = scene->width;
    cf->height = scene->height;
}

/* Unit direction of the ray through image position (px, py), in pixels from the top-left corner of the image
 * ((x + 0.5, y + 0.5) is the centre of pixel (x, y)). */
static void camera_ray(const camera_frame *cf, double px, double py, double dir[3]) {
    double u = (2.0 * px / cf->width - 1.0) * cf->tan_half * cf->aspect;
    double v = (1.0 - 2.0 * py / cf->height) * cf->tan_half;
    for (int k = 0; k < 3; k++) dir[k] = cf->forward[k] + u * cf->right[k] + v * cf->up[k];
    vec3_normalize(dir);
}

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

/* Stage 1: the primary ray through image position (px, py). Returns 1 and fills *hit (if not NULL) when it
 * meets the object. The intersector is the place where other shape types (triangle meshes) plug in. */
static int trace_primary(const mr_scene *scene, const camera_frame *cf, double px, double py, hit_record *hit) {
    double dir[3], t;
    camera_ray(cf, px, py, dir);
    if (!intersect_sphere(&scene->shape, cf->origin, dir, &t)) return 0;
    if (hit == NULL) return 1;
    for (int k = 0; k < 3; k++) {
        hit->position[k] = cf->origin[k] + t * dir[k];
        hit->normal[k] = (hit->position[k] - scene->shape.center[k]) / scene->shape.radius;
    }
    vec3_normalize(hit->normal);
    frame_from_normal(hit->normal, hit->tangent, hit->bitangent);
    double to_camera[3] = {-dir[0], -dir[1], -dir[2]};
    to_local(hit, to_camera, hit->view_local);
    return 1;
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

/* What one image row contributes to the plan; rows are traced in parallel and concatenated in order. */
typedef struct row_result {
    int object_pixels;
    int lit;
    int *pixels;      /* [lit] image pixel of each lit pixel */
    int *counts;      /* [lit] samples of each lit pixel */
    shading_sample *samples;
    int sample_count;
    int sample_capacity;
} row_result;

static void row_result_free(row_result *row) {
    free(row->pixels);
    free(row->counts);
    free(row->samples);
}

static int row_reserve(row_result *row, int extra) {
    if (row->sample_count + extra <= row->sample_capacity) return 1;
    int capacity = MR_MAX(2 * row->sample_capacity, row->sample_count + extra);
    shading_sample *grown = realloc(row->samples, (size_t)capacity * sizeof *grown);
    if (grown == NULL) return 0;
    row->samples = grown;
    row->sample_capacity = capacity;
    return 1;
}

/* Trace row y: pixels well inside or outside the silhouette (all four corners and the centre agree) get one
 * primary ray through their centre; pixels on the silhouette get n x n rays on a regular sub-pixel grid, each
 * weighted 1/n^2, so they are box-filtered like a path tracer's pixels instead of aliased (docs/design.md
 * principle 2: the extra rays go only where the image has an edge). Returns 0 on allocation failure. */
static int trace_row(const mr_scene *scene, const camera_frame *cf, const unsigned char *corner_hit, int edge_n,
                     int y, float *coverage, row_result *row) {
    const int width = scene->width;
    row->pixels = malloc((size_t)width * sizeof *row->pixels);
    row->counts = malloc((size_t)width * sizeof *row->counts);
    if (row->pixels == NULL || row->counts == NULL || !row_reserve(row, width * scene->light_count)) return 0;
    for (int x = 0; x < width; x++) {
        const unsigned char *top = corner_hit + (size_t)y * (size_t)(width + 1) + (size_t)x;
        const unsigned char *bottom = top + width + 1;
        hit_record hit;
        int centre = trace_primary(scene, cf, x + 0.5, y + 0.5, &hit);
        int corners = top[0] + top[1] + bottom[0] + bottom[1];
        int n = (corners == 4 * centre) ? 1 : edge_n;
        double weight = 1.0 / ((double)n * n);
        int first = row->sample_count, hits = 0;
        for (int j = 0; j < n; j++)
            for (int i = 0; i < n; i++) {
                if (n > 1 && !trace_primary(scene, cf, x + (i + 0.5) / n, y + (j + 0.5) / n, &hit)) continue;
                if (n == 1 && !centre) continue;
                hits++;
                if (!row_reserve(row, scene->light_count)) return 0;
                for (int l = 0; l < scene->light_count; l++) {
                    shading_sample *sample = &row->samples[row->sample_count];
                    if (!point_light_sample(&scene->lights[l], &hit, sample)) continue;
                    for (int k = 0; k < 3; k++) sample->weight[k] *= weight;
                    row->sample_count++;
                }
            }
        int pixel = y * width + x;
        coverage[pixel] = (float)(hits * weight);
        if (hits > 0) row->object_pixels++;
        if (row->sample_count > first) {
            row->pixels[row->lit] = pixel;
            row->counts[row->lit] = row->sample_count - first;
            row->lit++;
        }
    }
    return 1;
}

void mr_render_plan_free(mr_render_plan *plan) {
    if (plan == NULL) return;
    free(plan->coverage);
    free(plan->lit_pixel_index);
    free(plan->sample_begin);
    free(plan->samples);
    free(plan);
}

mr_status mr_render_plan_create(const mr_scene *scene, mr_render_plan **out) {
    if (scene == NULL || out == NULL) return mr_fail(MR_ERR_INVALID_ARG, "render plan: NULL scene or output");
    mr_status status = mr_scene_validate(scene);
    if (status != MR_OK) return status;

    const int width = scene->width, height = scene->height;
    const int edge_n = scene->edge_samples > 0 ? scene->edge_samples : MR_SCENE_DEFAULT_EDGE_SAMPLES;
    camera_frame cf;
    camera_frame_init(scene, &cf);
    mr_render_plan *plan = calloc(1, sizeof *plan);
    unsigned char *corner_hit = malloc((size_t)(width + 1) * (size_t)(height + 1));
    row_result *rows = calloc((size_t)height, sizeof *rows);
    int failed = 0;
    if (plan == NULL || corner_hit == NULL || rows == NULL) goto oom;
    plan->scene = *scene;
    plan->coverage = calloc((size_t)width * (size_t)height, sizeof *plan->coverage);
    if (plan->coverage == NULL) goto oom;

    // Which pixel corners see the object: a pixel whose corners and centre agree is entirely inside or
    // outside the silhouette (the projected sphere is convex and, at these sizes, far wider than a pixel).
#pragma omp parallel for schedule(static)
    for (int y = 0; y <= height; y++)
        for (int x = 0; x <= width; x++)
            corner_hit[(size_t)y * (size_t)(width + 1) + (size_t)x] =
                (unsigned char)trace_primary(scene, &cf, x, y, NULL);

#pragma omp parallel for schedule(dynamic, 4) reduction(| : failed)
    for (int y = 0; y < height; y++)
        if (!trace_row(scene, &cf, corner_hit, edge_n, y, plan->coverage, &rows[y])) failed = 1;
    if (failed) goto oom;

    // Concatenate the rows in image order: the plan, and so every render, is the same for any thread count.
    size_t lit = 0, samples = 0;
    for (int y = 0; y < height; y++) {
        lit += (size_t)rows[y].lit;
        samples += (size_t)rows[y].sample_count;
        plan->object_pixels += rows[y].object_pixels;
    }
    if (samples > (size_t)INT_MAX) goto oom;
    plan->lit_pixel_index = malloc((lit + 1) * sizeof *plan->lit_pixel_index);
    plan->sample_begin = malloc((lit + 1) * sizeof *plan->sample_begin);
    plan->samples = malloc((samples + 1) * sizeof *plan->samples);
    if (plan->lit_pixel_index == NULL || plan->sample_begin == NULL || plan->samples == NULL) goto oom;
    int next_lit = 0, next_sample = 0;
    for (int y = 0; y < height; y++) {
        const row_result *row = &rows[y];
        memcpy(plan->samples + next_sample, row->samples, (size_t)row->sample_count * sizeof *row->samples);
        for (int i = 0; i < row->lit; i++) {
            plan->lit_pixel_index[next_lit] = row->pixels[i];
            plan->sample_begin[next_lit] = next_sample;
            next_sample += row->counts[i];
            next_lit++;
        }
    }
    plan->sample_begin[next_lit] = next_sample;
    plan->lit_pixels = next_lit;
    for (int y = 0; y < height; y++) row_result_free(&rows[y]);
    free(rows);
    free(corner_hit);
    *out = plan;
    return MR_OK;

oom:
    if (rows != NULL)
        for (int y = 0; y < height; y++) row_result_free(&rows[y]);
    free(rows);
    free(corner_hit);
    mr_render_plan_free(plan);
    return mr_fail(MR_ERR_NOMEM, "render plan: out of memory for a %dx%d scene", width, height);
}

const mr_scene *mr_render_plan_scene(const mr_render_plan *plan) { return &plan->scene; }

int mr_render_plan_lit_pixel_count(const mr_render_plan *plan) { return plan->lit_pixels; }

int mr_render_plan_object_pixel_count(const mr_render_plan *plan) { return plan->object_pixels; }

long mr_render_plan_sample_count(const mr_render_plan *plan) { return plan->sample_begin[plan->lit_pixels]; }

const float *mr_render_plan_coverage(const mr_render_plan *plan) { return plan->coverage; }

static mr_status check_target(const mr_render_plan *plan, const mr_image *image, const char *what) {
    if (image == NULL) return MR_OK;
    if (image->width != plan->scene.width || image->height != plan->scene.height || image->channels != 3)
        return mr_fail(MR_ERR_INVALID_ARG, "render: %s image is %dx%dx%d, the plan needs %dx%dx3", what,
                       image->width, image->height, image->channels, plan->scene.width, plan->scene.height);
    return MR_OK;
}

/* Full renders: the background weighted by the part of each pixel the object leaves uncovered; component
 * renders: black. Lit pixels are then overwritten (full renders add their background share again). */
static void fill_unlit(const mr_render_plan *plan, mr_image *image, int with_background) {
    size_t pixel_count = (size_t)plan->scene.width * (size_t)plan->scene.height;
    for (size_t p = 0; p < pixel_count; p++) {
        double uncovered = with_background ? 1.0 - plan->coverage[p] : 0.0;
        for (int c = 0; c < 3; c++) image->pixels[p * 3 + c] = (float)(plan->scene.background[c] * uncovered);
    }
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
        size_t pixel = (size_t)plan->lit_pixel_index[i];
        double uncovered = 1.0 - plan->coverage[pixel];
        for (int c = 0; c < 3; c++)
            image->pixels[pixel * 3 + c] = (float)(sum[c] + plan->scene.background[c] * uncovered);
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
