/*
 * render.c — render plans (geometry traced once per scene) and material renders (BRDF evaluations only).
 * Contract and design in render.h; the environment estimator in docs/rendering.md.
 *
 * A plan is built in two stages, kept apart so later object and light types slot in without touching the
 * other stage or mr_render:
 *   1. primary visibility: a ray through each pixel centre (n x n sub-pixel rays on the silhouette) -> hit
 *      records (position, shading frame, view direction, texture coordinates); the intersector is chosen by the
 *      shape type;
 *   2. lighting: each light type turns hit records into shading samples. A point light gives at most one sample
 *      per hit (local light direction and weight) and needs no shadow ray on a convex object. An environment
 *      light gives the indices of its fixed directions above the hit's horizon; the directions and their
 *      L/(pdf N) weights are tabled once per plan (env_sampling.c). With reflection samples, each hit also gets M
 *      directions drawn around its mirror direction, with their weights; both sets are combined by multiple
 *      importance sampling (the pattern's factor is computed by the render, from the hit's mirror direction).
 * Rows are traced in parallel into per-row buffers and concatenated in image order, so the plan is identical
 * for any thread count.
 */
#include <limits.h>
#include <omp.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../mr_internal.h"
#include "env_sampling.h"
#include "highlight.h"
#include "mesh.h"
#include "render.h"
#include "render_internal.h"
#include "../brdf/brdf_float.h"
#include "texture.h"
#include "vec3.h"

typedef struct hit_record {
    double position[3];
    double normal[3];
    double tangent[3];
    double bitangent[3];
    double view_local[3]; /* unit direction towards the camera, in the shading frame */
    double uv[2];         /* the mesh's TEXCOORD_0 (render.h); unset on a sphere, whose coordinates (sphere_uv)
                             only the hits a plan keeps need: add_hit computes them */
    double uv1[2];        /* the mesh's TEXCOORD_1; (0, 0) without */
    double geometric[3];  /* meshes: the hit triangle's unit normal (by its winding) */
    int triangle;         /* meshes: the hit triangle; -1 on a sphere */
    int material;         /* meshes: the triangle's material; 0 on a sphere */
    double occlusion;     /* the surface's ambient occlusion ao' (1 without a map) */
    double emission[3];   /* the surface's emitted radiance (0 without) */
} hit_record;

/* A point-light sample: radiance += f_r(hit view, light) * weight. */
typedef struct point_sample {
    double light[3];  /* local frame, unit, z > 0 */
    double weight[3]; /* I * cos(theta_l) / d^2 * the hit's share of its pixel, per RGB channel */
} point_sample;


/* A lit hit: what the render needs of the geometry. Environment samples are direction indices; the frame turns
 * the tabled world directions into local ones. */
typedef struct plan_hit {
    /* What every render reads of every hit comes first, in one cache line with the next hit's sample offsets
     * (the fields after `emission` are read only where maps or environment samples ask for them). */
    double view[3];                         /* local frame, unit, z > 0 */
    int point_begin;   /* its point samples: point_samples[point_begin .. next hit's point_begin - 1] */
    int material;      /* index into the materials of mr_render_materials */
    size_t env_begin;  /* its environment samples: env_samples[env_begin .. next hit's env_begin - 1] */
    size_t reflection_begin; /* its reflection samples: reflection_samples[reflection_begin .. next hit's - 1] */
    double emission[3]; /* emitted radiance x share (full renders add it) */
    double uv[2], uv1[2];
    double env_share;  /* the hit's share of its pixel (1, or 1/n^2 for a silhouette sub-pixel ray) x the
                          surface's ambient occlusion: what environment samples are weighted by */
} plan_hit;

/* What environment samples need of a hit besides its plan_hit, kept apart (and only by plans with an environment
 * light) so that a point-light plan's hits are 40 % of the size: fewer pages to fault in, fewer cache lines to
 * read per render. */
typedef struct hit_frame {
    double tangent[3], bitangent[3], normal[3]; /* the shading frame, world space */
    struct reflection_frame mirror; /* with reflection samples: the hit's mirror direction and lobe frame */
} hit_frame;

/* A direction drawn around a hit's mirror direction: radiance += f_r(view, light) * weight * cos * env_share. */
typedef struct reflection_sample {
    float light[3];  /* local frame, unit, z > 0 */
    float weight[3]; /* sum over the lights that take reflection samples of L(w) / (N pdf(w) + M q(w)) */
} reflection_sample;


struct mr_render_plan {
    mr_scene scene;
    float *coverage;      /* width*height: fraction of each pixel the object covers (1 inside, 0 outside) */
    int object_pixels;    /* pixels with coverage > 0 */
    int lit_pixels;
    int *lit_pixel_index; /* [lit_pixels]: image pixel of each lit pixel, ascending */
    int *hit_begin;       /* [lit_pixels + 1]: hits of lit pixel i are hits[hit_begin[i] .. hit_begin[i+1]-1] */
    int hit_count;
    plan_hit *hits;       /* [hit_count + 1]: the last one only holds the end offsets of the sample arrays */
    hit_frame *frames;    /* [hit_count + 1] with an environment light, else NULL */
    point_sample *point_samples;
    uint16_t *env_samples; /* direction indices into env */
    reflection_sample *reflection_samples;
    env_table env;
    mesh_world mesh;       /* MR_SHAPE_MESH: the world-space mesh and its BVH; zero otherwise */
    long shadow_rays;      /* traced while building the plan */
    int render_threads;    /* OpenMP threads a render uses (render.h, mr_scene.threads) */
    int emits;             /* some hit has emission (else renders skip adding it) */
    /* The closer look (render.h, mr_render_plan_zoomed): built on first use by whichever thread asks
     * first, installed with a compare-and-swap (a thread that loses frees its copy), freed with this plan. */
    _Atomic(struct mr_render_plan *) zoomed;
    double zoom;           /* of a plan made by mr_render_plan_zoomed: its zoom factor */
    /* The point samples as structure of arrays for batched renders (point_soa below): built on first use like
     * `zoomed`, freed with this plan. */
    _Atomic(struct point_soa *) point_soa;
    int float_kernels; /* batched renders in float (render_internal.h, mr_render_plan_set_float_kernels) */
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

/* Image-plane coordinates of image position (px, py), in pixels from the top-left corner of the image
 * ((x + 0.5, y + 0.5) is the centre of pixel (x, y)): the ray's direction is forward + u right + v up. */
static double camera_u(const camera_frame *cf, double px) {
    return (2.0 * px / cf->width - 1.0) * cf->tan_half * cf->aspect;
}
static double camera_v(const camera_frame *cf, double py) { return (1.0 - 2.0 * py / cf->height) * cf->tan_half; }

/* The ray's direction, not normalised, from its image-plane coordinates u = camera_u(px), v = camera_v(py). */
static void camera_ray_uv(const camera_frame *cf, double u, double v, double dir[3]) {
    for (int k = 0; k < 3; k++) dir[k] = cf->forward[k] + u * cf->right[k] + v * cf->up[k];
}

/* Unit direction of the ray through image position (px, py). */
static void camera_ray(const camera_frame *cf, double px, double py, double dir[3]) {
    camera_ray_uv(cf, camera_u(cf, px), camera_v(cf, py), dir);
    vec3_normalize(dir);
}

/* A mesh material's surface maps, prepared for lookups during the plan's creation. */
typedef struct surface_sampler {
    const mr_surface *surface;
    texture_sampler normal, occlusion, emissive;
} surface_sampler;

/* What primary rays need: the scene, its world-space mesh (meshes only), the camera and the mesh's surfaces
 * (NULL without). */
typedef struct tracer {
    const mr_scene *scene;
    const mesh_world *mesh;
    camera_frame camera;
    const surface_sampler *surfaces;
    int highlight_count;                              /* discs around point-light highlights (spheres only) */
    highlight_disc highlights[HIGHLIGHT_MAX_DISCS];
    highlight_quadrature quadrature;                  /* their pixels' samples, made once per plan */
    /* camera_u of every pixel corner column (x = 0 .. width) and of every pixel centre (x + 0.5): the same values
     * camera_ray computes, computed once per plan instead of once per ray (a division each) */
    double *corner_u, *centre_u;
    /* Spheres: the ray from the camera along d (not normalised) surely misses the sphere if
     * (d.w)^2 < miss_below |d|^2 or d.w <= 0, w the vector from the camera to the centre (sphere_misses);
     * screen says whether the test is made */
    double to_centre[3], miss_below;
    int screen;
    int vector_rays; /* spheres, rays four at a time (mr_plan_rays: AVX2, MATREMAP_SIMD not "scalar") */
} tracer;

/* The angle a between the ray and the direction to the sphere's centre exceeds the sphere's angular radius
 * asin(r / |w|), cos^2 a < 1 - r^2/|w|^2, by a margin (a relative 1e-6 on cos^2): intersect_sphere's
 * discriminant, r^2 - |w|^2 sin^2 a, is then below -1e-6 (|w|^2 - r^2), and its rounding (a few 1e-16 |w|^2)
 * cannot lift it to 0 unless the camera grazes the sphere, |w|^2 - r^2 < 1e-6 |w|^2, where no ray is skipped.
 * So a skipped ray is one the exact test misses too, and every answer is kept. Costs no division or square
 * root, which the exact test does. */
static int sphere_misses(const tracer *tr, const double d[3]) {
    const double dw = vec3_dot(d, tr->to_centre);
    return tr->screen && (!(dw > 0.0) || dw * dw < tr->miss_below * vec3_dot(d, d));
}

static void sphere_screen_init(const mr_scene *scene, tracer *tr) {
    vec3_sub(scene->shape.center, tr->camera.origin, tr->to_centre);
    const double w2 = vec3_dot(tr->to_centre, tr->to_centre), r = scene->shape.radius;
    tr->miss_below = (1.0 - 1e-6) * (w2 - r * r);
    tr->screen = w2 - r * r > 1e-6 * w2;
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

/* The sphere's texture coordinates at unit normal n (render.h): u from the azimuth about +y, 0.5 at +z and
 * growing towards +x, the seam at -z; v from the polar angle, 0 at +y. */
static void sphere_uv(const double n[3], double uv[2]) {
    uv[0] = 0.5 + atan2(n[0], n[2]) * (0.5 * MR_INV_PI);
    uv[1] = acos(mr_clampd(n[1], -1.0, 1.0)) * MR_INV_PI;
}

/* How far above the view horizon a normal-mapped normal is kept (render.h, "surfaces"). */
#define NORMAL_MAP_MIN_COS 0.01

/* The shading normal tilted by a normal-map texel (render.h): the frame follows, keeping its handedness. */
static void tilt_normal(const surface_sampler *ss, hit_record *hit, const double to_camera[3]) {
    double texel[3];
    mr_texture_sampler_read(&ss->normal, hit->uv, hit->uv1, texel);
    const double scale = ss->surface->normal_scale;
    const double x = (2.0 * texel[0] - 1.0) * scale, y = (2.0 * texel[1] - 1.0) * scale, z = 2.0 * texel[2] - 1.0;
    double n[3];
    for (int k = 0; k < 3; k++) n[k] = x * hit->tangent[k] + y * hit->bitangent[k] + z * hit->normal[k];
    if (!(vec3_normalize(n) > 1e-12)) return; // a (0.5, 0.5, 0.5) texel has no direction: keep the normal
    const double facing = vec3_dot(n, to_camera);
    if (vec3_dot(hit->normal, to_camera) > 0.0 && facing < NORMAL_MAP_MIN_COS) {
        // Bend it back over the view horizon, keeping its azimuth about the view direction.
        double across[3];
        for (int k = 0; k < 3; k++) across[k] = n[k] - facing * to_camera[k];
        double keep = vec3_normalize(across) > 1e-12 ? sqrt(1.0 - NORMAL_MAP_MIN_COS * NORMAL_MAP_MIN_COS) : 0.0;
        for (int k = 0; k < 3; k++) n[k] = keep * across[k] + (keep > 0.0 ? NORMAL_MAP_MIN_COS : 1.0) * to_camera[k];
        vec3_normalize(n);
    }
    double handed_axis[3];
    vec3_cross(hit->normal, hit->tangent, handed_axis);
    const double handedness = vec3_dot(handed_axis, hit->bitangent) < 0.0 ? -1.0 : 1.0;
    double t[3];
    const double along = vec3_dot(hit->tangent, n);
    for (int k = 0; k < 3; k++) t[k] = hit->tangent[k] - along * n[k];
    for (int k = 0; k < 3; k++) hit->normal[k] = n[k];
    if (!(vec3_normalize(t) > 1e-6)) {
        vec3_frame_from_normal(hit->normal, hit->tangent, hit->bitangent);
        return;
    }
    for (int k = 0; k < 3; k++) hit->tangent[k] = t[k];
    vec3_cross(hit->normal, hit->tangent, hit->bitangent);
    for (int k = 0; k < 3; k++) hit->bitangent[k] *= handedness;
}

/* The hit's surface maps (render.h, "surfaces"): the normal map tilts the frame, occlusion and emission are
 * read for the plan. */
static void apply_surface(const surface_sampler *ss, hit_record *hit, const double to_camera[3]) {
    hit->occlusion = 1.0;
    for (int c = 0; c < 3; c++) hit->emission[c] = 0.0;
    if (ss == NULL) return;
    const mr_surface *surface = ss->surface;
    if (surface->normal_map != NULL) tilt_normal(ss, hit, to_camera);
    if (surface->occlusion_map != NULL) {
        double ao;
        mr_texture_sampler_read(&ss->occlusion, hit->uv, hit->uv1, &ao);
        hit->occlusion = MR_MAX(0.0, 1.0 + surface->occlusion_strength * (ao - 1.0));
    }
    double texel[3] = {1.0, 1.0, 1.0};
    if (surface->emissive_map != NULL) mr_texture_sampler_read(&ss->emissive, hit->uv, hit->uv1, texel);
    for (int c = 0; c < 3; c++) hit->emission[c] = MR_MAX(0.0, surface->emission[c] * texel[c]);
}

/* Stage 1: the primary ray through image-plane coordinates (u, v) (camera_u, camera_v). Returns 1 and fills *hit
 * (if not NULL) when it meets the object. The intersector is the place where other shape types (triangle meshes)
 * plug in. */
static int trace_primary_uv(const tracer *tr, double u, double v, hit_record *hit) {
    const camera_frame *cf = &tr->camera;
    const mesh_world *mesh = tr->mesh;
    double dir[3], t;
    camera_ray_uv(cf, u, v, dir);
    if (tr->scene->shape.type == MR_SHAPE_SPHERE && sphere_misses(tr, dir)) return 0;
    vec3_normalize(dir);
    if (tr->scene->shape.type == MR_SHAPE_MESH) {
        mesh_hit mh;
        if (!mr_mesh_intersect(mesh, cf->origin, dir, INFINITY, -1, CULL_CAMERA, &mh)) return 0;
        if (hit == NULL) return 1;
        for (int k = 0; k < 3; k++) hit->position[k] = cf->origin[k] + mh.t * dir[k];
        mr_mesh_shade(mesh, &mh, hit->normal, hit->tangent, hit->bitangent, hit->geometric, hit->uv, hit->uv1);
        hit->triangle = mh.triangle;
        hit->material = mesh_material(mesh, mh.triangle);
        double to_camera[3] = {-dir[0], -dir[1], -dir[2]};
        if (mesh_double_sided(mesh, mh.triangle) && vec3_dot(hit->geometric, to_camera) < 0.0)
            for (int k = 0; k < 3; k++) { // the back of a double-sided triangle: shade it as a front
                hit->normal[k] = -hit->normal[k];
                hit->bitangent[k] = -hit->bitangent[k];
                hit->geometric[k] = -hit->geometric[k];
            }
        apply_surface(tr->surfaces ? &tr->surfaces[hit->material] : NULL, hit, to_camera);
        to_local(hit, to_camera, hit->view_local);
        return 1;
    }
    if (!intersect_sphere(&tr->scene->shape, cf->origin, dir, &t)) return 0;
    if (hit == NULL) return 1;
    hit->triangle = -1;
    hit->material = 0;
    hit->occlusion = 1.0;
    hit->uv1[0] = hit->uv1[1] = 0.0;
    for (int k = 0; k < 3; k++) hit->emission[k] = 0.0;
    for (int k = 0; k < 3; k++) {
        hit->position[k] = cf->origin[k] + t * dir[k];
        hit->normal[k] = (hit->position[k] - tr->scene->shape.center[k]) / tr->scene->shape.radius;
    }
    vec3_normalize(hit->normal);
    vec3_frame_from_normal(hit->normal, hit->tangent, hit->bitangent);
    double to_camera[3] = {-dir[0], -dir[1], -dir[2]};
    to_local(hit, to_camera, hit->view_local);
    for (int k = 0; k < 3; k++) hit->geometric[k] = hit->normal[k];
    return 1;
}


#if defined(__x86_64__) || defined(__i386__)
#define MR_RAYS_X86 1
#include <immintrin.h>

static inline __attribute__((target("avx2"), always_inline)) __m256d dot4(const __m256d a[3], const __m256d b[3]) {
    return _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(a[0], b[0]), _mm256_mul_pd(a[1], b[1])),
                         _mm256_mul_pd(a[2], b[2]));
}

/* Normalise the lanes whose length is > 0, as vec3_normalize does each (the same square root and divisions). */
static inline __attribute__((target("avx2"), always_inline)) void normalize4(__m256d a[3]) {
    const __m256d len = _mm256_sqrt_pd(dot4(a, a));
    const __m256d positive = _mm256_cmp_pd(len, _mm256_setzero_pd(), _CMP_GT_OQ);
    for (int k = 0; k < 3; k++) a[k] = _mm256_blendv_pd(a[k], _mm256_div_pd(a[k], len), positive);
}

/* trace_primary_uv of four rays on a sphere, lane for lane the same operations in the same order (AVX2 without
 * FMA: every product and sum rounded as the scalar code, compiled without contraction (ISO C), rounds it; square
 * roots and divisions are correctly rounded in both), so the same bits (test_render's
 * plan_rays_four_at_a_time_match_one_at_a_time; bench_plan --digest with and without MATREMAP_SIMD=scalar).
 * found[i] says whether ray i meets the sphere; hits (NULL for yes or no) gets its record. */
__attribute__((target("avx2"))) static void sphere_rays4(const tracer *tr, const double *u, const double *v,
                                                         hit_record *hits, int *found) {
    const camera_frame *cf = &tr->camera;
    const mr_shape *sphere = &tr->scene->shape;
    const __m256d U = _mm256_loadu_pd(u), V = _mm256_loadu_pd(v), zero = _mm256_setzero_pd();
    __m256d d[3], w[3], oc[3];
    for (int k = 0; k < 3; k++) {
        const __m256d along_u = _mm256_mul_pd(U, _mm256_set1_pd(cf->right[k]));
        d[k] = _mm256_add_pd(_mm256_add_pd(_mm256_set1_pd(cf->forward[k]), along_u),
                             _mm256_mul_pd(V, _mm256_set1_pd(cf->up[k])));
        w[k] = _mm256_set1_pd(tr->to_centre[k]);
        oc[k] = _mm256_set1_pd(cf->origin[k] - sphere->center[k]);
    }
    // sphere_misses
    const __m256d dw = dot4(d, w);
    __m256d missed = _mm256_or_pd(_mm256_cmp_pd(dw, zero, _CMP_NGT_UQ),
                                  _mm256_cmp_pd(_mm256_mul_pd(dw, dw),
                                                _mm256_mul_pd(_mm256_set1_pd(tr->miss_below), dot4(d, d)), _CMP_LT_OQ));
    if (!tr->screen) missed = zero;
    normalize4(d);
    // intersect_sphere
    const double c = (cf->origin[0] - sphere->center[0]) * (cf->origin[0] - sphere->center[0]) +
                     (cf->origin[1] - sphere->center[1]) * (cf->origin[1] - sphere->center[1]) +
                     (cf->origin[2] - sphere->center[2]) * (cf->origin[2] - sphere->center[2]) -
                     sphere->radius * sphere->radius;
    const __m256d b = dot4(oc, d);
    const __m256d discriminant = _mm256_sub_pd(_mm256_mul_pd(b, b), _mm256_set1_pd(c));
    missed = _mm256_or_pd(missed, _mm256_cmp_pd(discriminant, zero, _CMP_LT_OQ));
    const __m256d t = _mm256_sub_pd(_mm256_sub_pd(zero, b), _mm256_sqrt_pd(discriminant));
    const __m256d met = _mm256_andnot_pd(missed, _mm256_cmp_pd(t, zero, _CMP_GT_OQ));
    const int mask = _mm256_movemask_pd(met);
    for (int i = 0; i < 4; i++) found[i] = (mask >> i) & 1;
    if (hits == NULL || mask == 0) return;
    __m256d position[3], n[3], tangent[3], bitangent[3], to_camera[3], view[3];
    const __m256d sign_bit = _mm256_set1_pd(-0.0);
    for (int k = 0; k < 3; k++) {
        position[k] = _mm256_add_pd(_mm256_set1_pd(cf->origin[k]), _mm256_mul_pd(t, d[k]));
        n[k] = _mm256_div_pd(_mm256_sub_pd(position[k], _mm256_set1_pd(sphere->center[k])),
                             _mm256_set1_pd(sphere->radius));
        to_camera[k] = _mm256_xor_pd(d[k], sign_bit);
    }
    normalize4(n);
    // vec3_frame_from_normal
    const __m256d one = _mm256_set1_pd(1.0);
    const __m256d sign = _mm256_blendv_pd(_mm256_set1_pd(-1.0), one, _mm256_cmp_pd(n[2], zero, _CMP_GE_OQ));
    const __m256d a = _mm256_div_pd(_mm256_set1_pd(-1.0), _mm256_add_pd(sign, n[2]));
    const __m256d cross = _mm256_mul_pd(_mm256_mul_pd(n[0], n[1]), a);
    tangent[0] = _mm256_add_pd(one, _mm256_mul_pd(_mm256_mul_pd(_mm256_mul_pd(sign, n[0]), n[0]), a));
    tangent[1] = _mm256_mul_pd(sign, cross);
    tangent[2] = _mm256_mul_pd(_mm256_xor_pd(sign, sign_bit), n[0]);
    bitangent[0] = cross;
    bitangent[1] = _mm256_add_pd(sign, _mm256_mul_pd(_mm256_mul_pd(n[1], n[1]), a));
    bitangent[2] = _mm256_xor_pd(n[1], sign_bit);
    view[0] = dot4(tangent, to_camera);
    view[1] = dot4(bitangent, to_camera);
    view[2] = dot4(n, to_camera);
    double lanes[15][4];
    for (int k = 0; k < 3; k++) {
        _mm256_storeu_pd(lanes[k], position[k]);
        _mm256_storeu_pd(lanes[3 + k], n[k]);
        _mm256_storeu_pd(lanes[6 + k], tangent[k]);
        _mm256_storeu_pd(lanes[9 + k], bitangent[k]);
        _mm256_storeu_pd(lanes[12 + k], view[k]);
    }
    for (int i = 0; i < 4; i++) {
        if (!found[i]) continue;
        hit_record *hit = &hits[i];
        hit->triangle = -1;
        hit->material = 0;
        hit->occlusion = 1.0;
        hit->uv1[0] = hit->uv1[1] = 0.0;
        for (int k = 0; k < 3; k++) {
            hit->emission[k] = 0.0;
            hit->position[k] = lanes[k][i];
            hit->normal[k] = hit->geometric[k] = lanes[3 + k][i];
            hit->tangent[k] = lanes[6 + k][i];
            hit->bitangent[k] = lanes[9 + k][i];
            hit->view_local[k] = lanes[12 + k][i];
        }
    }
}
#else
#define MR_RAYS_X86 0
#endif

/* trace_primary_uv of `count` rays (u[i], v[i]): found[i] whether ray i meets the object, hits[i] its record
 * (hits NULL: yes or no only). Spheres on AVX2, four at a time; the same answers either way. */
static void trace_rays(const tracer *tr, int count, const double *u, const double *v, hit_record *hits, int *found) {
    int i = 0;
#if MR_RAYS_X86
    if (tr->vector_rays)
        for (; i + 4 <= count; i += 4) sphere_rays4(tr, u + i, v + i, hits ? hits + i : NULL, found + i);
#endif
    for (; i < count; i++) found[i] = trace_primary_uv(tr, u[i], v[i], hits ? &hits[i] : NULL);
}

/* Stage 2 for a point light: the exact contribution I*cos(theta_l)/d^2, no shadow ray (convex object). Returns
 * 1 and fills *sample if the point is lit and seen from the front, 0 otherwise. */
static int point_light_sample(const mr_light *light, const hit_record *hit, point_sample *sample) {
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
        sample->light[k] = local[k];
        sample->weight[k] = light->intensity[k] * falloff;
    }
    return 1;
}

/* Shadow rays (self-occluding meshes only): does the mesh block the way from the hit along unit dir within
 * `distance`? The ray starts a hair (1e-9 of the mesh's size) off the hit triangle's plane on dir's side and
 * skips that triangle, so it never finds the surface it leaves. */
static int shadowed(const mesh_world *mesh, const hit_record *hit, const double dir[3], double distance) {
    double offset = (vec3_dot(hit->geometric, dir) >= 0.0 ? 1e-9 : -1e-9) * mesh->scale;
    double origin[3];
    for (int k = 0; k < 3; k++) origin[k] = hit->position[k] + offset * hit->geometric[k];
    return mr_mesh_occluded(mesh, origin, dir, distance, hit->triangle);
}


/* ---- stage 2 over a row of hits, and the plan ---------------------------------------------------------------- */

/* What one image row contributes to the plan; rows are traced in parallel and concatenated in order. Sample
 * offsets inside the row's hits are relative to the row until the concatenation. */
typedef struct row_result {
    int object_pixels;
    int lit;
    int *pixels;      /* [lit] image pixel of each lit pixel */
    int *hit_counts;  /* [lit] hits of each lit pixel */
    plan_hit *hits;
    size_t hit_count, hit_capacity;
    hit_frame *frames;  /* with an environment light: each hit's frame */
    size_t frame_capacity;
    point_sample *points;
    size_t point_count, point_capacity;
    uint16_t *env;
    size_t env_count, env_capacity;
    reflection_sample *reflections;
    size_t reflection_count, reflection_capacity;
    long shadow_rays;
} row_result;

static void row_result_free(row_result *row) {
    free(row->pixels);
    free(row->hit_counts);
    free(row->frames);
    free(row->hits);
    free(row->points);
    free(row->env);
    free(row->reflections);
}

/* Make room for `needed` elements of `size` bytes in *buffer (capacity in elements); 0 on allocation failure. */
static int reserve(void **buffer, size_t *capacity, size_t needed, size_t size) {
    if (needed <= *capacity) return 1;
    size_t grown_capacity = MR_MAX(2 * *capacity, needed);
    void *grown = realloc(*buffer, grown_capacity * size);
    if (grown == NULL) return 0;
    *buffer = grown;
    *capacity = grown_capacity;
    return 1;
}

/* The hit's reflection samples (env->reflections of them, fewer below the horizon, in the shadow or where no
 * light shines): directions about its mirror direction (frame f), each weighted by the balance
 * heuristic's sum over the lights that take part, L(w) / (N pdf(w) + M q(w)). Returns 0 on allocation
 * failure. */
static int add_reflection_samples(const env_table *env, const mesh_world *occluder, const hit_record *hit,
                                  const struct reflection_frame *f, row_result *row) {
    if (!reserve((void **)&row->reflections, &row->reflection_capacity,
                 row->reflection_count + (size_t)env->reflections, sizeof *row->reflections))
        return 0;
    for (int j = 0, next = 0; j < REFLECTION_LOBES; j++)
        for (int k = 0; k < env->per_lobe[j]; k++, next++) {
            // w = normalize(sx a + sy b + r), the unit slopes stretched by the lobe's widths.
            const double sx = reflection_beta[j] * env->unit_slopes[next][0];
            const double sy = reflection_beta[j] * f->squash * env->unit_slopes[next][1];
            double w[3];
            for (int c = 0; c < 3; c++) w[c] = sx * f->a[c] + sy * f->b[c] + f->r[c];
            vec3_normalize(w);
            if (!(vec3_dot(hit->normal, w) > 0.0)) continue;
            const double mq = reflection_density(env, f, w);
            if (!(mq > 0.0)) continue; // outside q's cone: the pattern alone weighs this direction
            double weight[3] = {0.0, 0.0, 0.0};
            for (int l = 0; l < env->source_count; l++) {
                const env_source *source = &env->sources[l];
                if (!source->reflections) continue;
                double L[3];
                const double npdf = mr_env_source_lookup(source, w, L);
                for (int c = 0; c < 3; c++) weight[c] += L[c] / (npdf + mq);
            }
            if (weight[0] == 0.0 && weight[1] == 0.0 && weight[2] == 0.0) continue;
            if (occluder != NULL) {
                row->shadow_rays++;
                if (shadowed(occluder, hit, w, INFINITY)) continue;
            }
            double local[3];
            to_local(hit, w, local);
            reflection_sample *sample = &row->reflections[row->reflection_count++];
            for (int c = 0; c < 3; c++) {
                sample->light[c] = (float)local[c];
                sample->weight[c] = (float)weight[c];
            }
        }
    return 1;
}

/* Stage 2 for one hit carrying `share` of its pixel: its samples from every light, in light order; the hit is
 * kept if any light reaches it. `occluder` is the mesh when it can occlude itself (then every sample is kept
 * only if its shadow ray is clear), NULL otherwise. Returns 0 on allocation failure. */
static int add_hit(const mr_scene *scene, const env_table *env, const mesh_world *occluder, const hit_record *hit,
                   double share, row_result *row) {
    const size_t points_before = row->point_count, env_before = row->env_count;
    const size_t reflections_before = row->reflection_count;
    if (!reserve((void **)&row->points, &row->point_capacity, row->point_count + (size_t)scene->light_count,
                 sizeof *row->points))
        return 0;
    int env_offset = 0;
    for (int l = 0; l < scene->light_count; l++) {
        const mr_light *light = &scene->lights[l];
        if (light->type == MR_LIGHT_POINT) {
            point_sample *sample = &row->points[row->point_count];
            if (!point_light_sample(light, hit, sample)) continue;
            if (occluder != NULL) {
                double to_light[3];
                vec3_sub(light->position, hit->position, to_light);
                double distance = vec3_normalize(to_light);
                row->shadow_rays++;
                if (shadowed(occluder, hit, to_light, distance)) continue;
            }
            for (int k = 0; k < 3; k++) sample->weight[k] *= share;
            row->point_count++;
            continue;
        }
        // An environment light: its directions above the hit's horizon (a convex object cannot occlude
        // itself, so this is the whole visibility test) that carry light; on a self-occluding mesh, those
        // whose shadow ray escapes.
        int n = mr_env_light_samples(light);
        if (hit->view_local[2] > 0.0) {
            if (!reserve((void **)&row->env, &row->env_capacity, row->env_count + (size_t)n, sizeof *row->env))
                return 0;
            for (int k = env_offset; k < env_offset + n; k++) {
                const double *w = env->weight[k];
                if (w[0] == 0.0 && w[1] == 0.0 && w[2] == 0.0) continue;
                if (!(vec3_dot(hit->normal, env->direction[k]) > 0.0)) continue;
                if (occluder != NULL) {
                    row->shadow_rays++;
                    if (shadowed(occluder, hit, env->direction[k], INFINITY)) continue;
                }
                row->env[row->env_count++] = (uint16_t)k;
            }
        }
        env_offset += n;
    }
    // The view reflected about the shading normal, r = 2 (n.v) n - v (v the view in world space), and the
    // lobe frame: a = the normal's part perpendicular to r (any perpendicular at normal incidence), b = r x a.
    struct reflection_frame mirror;
    memset(&mirror, 0, sizeof mirror);
    if (env->reflections > 0 && hit->view_local[2] > 0.0) {
        const double nv = hit->view_local[2];
        for (int c = 0; c < 3; c++) {
            double v = hit->view_local[0] * hit->tangent[c] + hit->view_local[1] * hit->bitangent[c] +
                       nv * hit->normal[c];
            mirror.r[c] = 2.0 * nv * hit->normal[c] - v;
        }
        vec3_normalize(mirror.r);
        const double nr = vec3_dot(hit->normal, mirror.r);
        for (int c = 0; c < 3; c++) mirror.a[c] = hit->normal[c] - nr * mirror.r[c];
        if (vec3_normalize(mirror.a) < 1e-9) vec3_frame_from_normal(mirror.r, mirror.a, mirror.b);
        vec3_cross(mirror.r, mirror.a, mirror.b);
        mirror.squash = MR_MAX(nv, 0.02);
        if (!add_reflection_samples(env, occluder, hit, &mirror, row)) return 0;
    }
    const int emits = hit->view_local[2] > 0.0 &&
                      (hit->emission[0] > 0.0 || hit->emission[1] > 0.0 || hit->emission[2] > 0.0);
    if (row->point_count == points_before && row->env_count == env_before &&
        row->reflection_count == reflections_before && !emits)
        return 1;
    if (!reserve((void **)&row->hits, &row->hit_capacity, row->hit_count + 1, sizeof *row->hits)) return 0;
    if (env->count > 0) {
        if (!reserve((void **)&row->frames, &row->frame_capacity, row->hit_count + 1, sizeof *row->frames))
            return 0;
        hit_frame *frame = &row->frames[row->hit_count];
        for (int k = 0; k < 3; k++) {
            frame->tangent[k] = hit->tangent[k];
            frame->bitangent[k] = hit->bitangent[k];
            frame->normal[k] = hit->normal[k];
        }
        frame->mirror = mirror;
    }
    plan_hit *kept = &row->hits[row->hit_count++];
    for (int k = 0; k < 3; k++) kept->view[k] = hit->view_local[k];
    if (hit->triangle < 0) { // a sphere: its coordinates are made here, for the hits kept (an atan2 and an acos)
        sphere_uv(hit->normal, kept->uv);
    } else {
        kept->uv[0] = hit->uv[0];
        kept->uv[1] = hit->uv[1];
    }
    kept->uv1[0] = hit->uv1[0];
    kept->uv1[1] = hit->uv1[1];
    kept->env_share = share * hit->occlusion;
    for (int c = 0; c < 3; c++) kept->emission[c] = emits ? hit->emission[c] * share : 0.0;
    kept->material = hit->material;
    kept->point_begin = (int)points_before; // row-relative; the plan's concatenation checks the total
    kept->env_begin = env_before;
    kept->reflection_begin = reflections_before;
    return 1;
}

/* Where the sphere shows the point light's mirror reflection, the centre of every highlight the light makes
 * (a lobe peaks where the half vector is the normal): the point whose normal bisects the directions to the camera
 * and to the light, found by bisection on the great circle through them, projected to the image. Returns 0 when
 * that point is not seen lit (the light behind the sphere) or falls outside the image. */
static int sphere_highlight(const mr_scene *scene, const camera_frame *cf, const mr_light *light, double *px,
                            double *py) {
    const double *centre = scene->shape.center, radius = scene->shape.radius;
    double e[3], l[3], across[3];
    vec3_sub(cf->origin, centre, e);
    vec3_normalize(e);
    vec3_sub(light->position, centre, l);
    if (!(vec3_normalize(l) > radius)) return 0; // a light inside the sphere lights nothing we see
    const double el = mr_clampd(vec3_dot(e, l), -1.0, 1.0);
    for (int k = 0; k < 3; k++) across[k] = l[k] - el * e[k];
    const double theta_light = acos(el);
    if (vec3_normalize(across) < 1e-12) { // light and camera on one axis: the point facing both (or none)
        if (el < 0.0) return 0;
        vec3_frame_from_normal(e, across, l); // any direction across; theta stays 0
    }
    double lo = 0.0, hi = theta_light, p[3], n[3];
    for (int it = 0; it < 200 && hi - lo > 1e-15; it++) {
        const double theta = 0.5 * (lo + hi);
        double to_camera[3], to_light[3];
        for (int k = 0; k < 3; k++) {
            n[k] = cos(theta) * e[k] + sin(theta) * across[k];
            p[k] = centre[k] + radius * n[k];
        }
        vec3_sub(cf->origin, p, to_camera);
        vec3_sub(light->position, p, to_light);
        vec3_normalize(to_camera);
        vec3_normalize(to_light);
        // the angle to the camera grows with theta, the angle to the light shrinks: equal at the mirror point
        if (vec3_dot(n, to_camera) > vec3_dot(n, to_light))
            lo = theta;
        else
            hi = theta;
    }
    const double theta = 0.5 * (lo + hi);
    double to_camera[3], to_light[3], d[3];
    for (int k = 0; k < 3; k++) {
        n[k] = cos(theta) * e[k] + sin(theta) * across[k];
        p[k] = centre[k] + radius * n[k];
    }
    vec3_sub(cf->origin, p, to_camera);
    vec3_sub(light->position, p, to_light);
    if (!(vec3_dot(n, to_camera) > 0.0) || !(vec3_dot(n, to_light) > 0.0)) return 0;
    vec3_sub(p, cf->origin, d);
    const double z = vec3_dot(d, cf->forward);
    if (!(z > 0.0)) return 0;
    const double u = vec3_dot(d, cf->right) / z, v = vec3_dot(d, cf->up) / z;
    *px = (u / (cf->tan_half * cf->aspect) + 1.0) * 0.5 * cf->width;
    *py = (1.0 - v / cf->tan_half) * 0.5 * cf->height;
    return *px >= 0.0 && *px <= cf->width && *py >= 0.0 && *py <= cf->height;
}

int mr_scene_zoom_on_highlight(const mr_scene *scene, double zoom, mr_scene *out) {
    if (scene == NULL || out == NULL || !(zoom >= 1.0) || scene->shape.type != MR_SHAPE_SPHERE) return 0;
    camera_frame cf;
    camera_frame_init(scene, &cf);
    for (int l = 0; l < scene->light_count; l++) {
        double px, py, dir[3];
        if (scene->lights[l].type != MR_LIGHT_POINT || !sphere_highlight(scene, &cf, &scene->lights[l], &px, &py))
            continue;
        camera_ray(&cf, px, py, dir);
        mr_scene zoomed = *scene;
        for (int k = 0; k < 3; k++) zoomed.camera.target[k] = scene->camera.position[k] + dir[k];
        const double half = atan(tan(0.5 * scene->camera.fov_y_degrees * MR_PI / 180.0) / zoom);
        zoomed.camera.fov_y_degrees = 2.0 * half * 180.0 / MR_PI;
        *out = zoomed;
        return 1;
    }
    return 0;
}

/* The discs of the scene's highlights (render.h, mr_scene.highlight_samples): one per point light on a sphere,
 * HIGHLIGHT_RADIUS wide, shrunk to half the distance between two that would overlap. */
static void find_highlights(const mr_scene *scene, tracer *tr) {
    tr->highlight_count = 0;
    if (scene->shape.type != MR_SHAPE_SPHERE || scene->highlight_samples == 1) return;
    for (int l = 0; l < scene->light_count && tr->highlight_count < HIGHLIGHT_MAX_DISCS; l++) {
        double px, py;
        const mr_light *light = &scene->lights[l];
        if (light->type != MR_LIGHT_POINT || !sphere_highlight(scene, &tr->camera, light, &px, &py)) continue;
        tr->highlights[tr->highlight_count++] = (highlight_disc){px, py, HIGHLIGHT_RADIUS};
    }
    for (int a = 0; a < tr->highlight_count; a++)
        for (int b = a + 1; b < tr->highlight_count; b++) {
            highlight_disc *da = &tr->highlights[a], *db = &tr->highlights[b];
            const double half = 0.5 * hypot(da->cx - db->cx, da->cy - db->cy);
            da->radius = MR_MIN(da->radius, half);
            db->radius = MR_MIN(db->radius, half);
        }
    // Two lights whose highlights coincide share one disc (a disc of radius 0 samples nothing).
    int kept = 0;
    for (int a = 0; a < tr->highlight_count; a++)
        if (tr->highlights[a].radius > 2.0 * HIGHLIGHT_INNER) tr->highlights[kept++] = tr->highlights[a];
    tr->highlight_count = kept;
}

/* Close pixel `pixel` of a row: `covered`, the share of it the object covers (at most 1, up to rounding), and its
 * hits, those the row gained since `first`, which make it a lit pixel. */
static void finish_pixel(row_result *row, float *coverage, int pixel, double covered, size_t first) {
    coverage[pixel] = (float)MR_MIN(covered, 1.0);
    if (covered > 0.0) row->object_pixels++;
    if (row->hit_count > first) {
        row->pixels[row->lit] = pixel;
        row->hit_counts[row->lit] = (int)(row->hit_count - first);
        row->lit++;
    }
}

/* Rays traced together by trace_row: a chunk of a row's pixel centres, or one pixel's sub-pixel rays. */
#define ROW_RAYS 64

/* Room for a row's rays in flight (trace_row's); one allocation. */
typedef struct ray_scratch {
    double *u, *v;
    int *found;
    hit_record *hits;
    highlight_sample *samples; /* a highlight pixel's quadrature (NULL without highlights) */
    void *block;
} ray_scratch;

/* The most samples mr_highlight_quadrature_pixel gives any pixel of q: a sample per grid cell at most, and each
 * disc's samples of the pixel (a bound of the actual quadrature, far below mr_highlight_max_samples'). */
static int quadrature_max_samples(const highlight_quadrature *q) {
    int most = HIGHLIGHT_GRID * HIGHLIGHT_GRID;
    for (int d = 0; d < q->count; d++) {
        const highlight_disc_pixels *dp = &q->pixels[d];
        int disc_most = 0;
        for (int p = 0; p < dp->nx * dp->ny; p++) disc_most = MR_MAX(disc_most, dp->begin[p + 1] - dp->begin[p]);
        most += disc_most;
    }
    return most;
}

static int ray_scratch_init(const tracer *tr, int edge_n, ray_scratch *rs) {
    memset(rs, 0, sizeof *rs);
    const int max_samples = tr->highlight_count > 0 ? quadrature_max_samples(&tr->quadrature) : 0;
    // a chunk's centres, then one pixel's sub-pixel rays or quadrature after them
    const size_t rays = ROW_RAYS + (size_t)MR_MAX(edge_n * edge_n, max_samples);
    const size_t hits_bytes = rays * sizeof *rs->hits, uv_bytes = rays * sizeof *rs->u;
    const size_t samples_bytes = (size_t)max_samples * sizeof *rs->samples;
    // hit records, then doubles (u, v, samples), then ints: each part's alignment suits the next
    unsigned char *block = malloc(hits_bytes + 2 * uv_bytes + samples_bytes + rays * sizeof *rs->found);
    if (block == NULL) return 0;
    rs->block = block;
    rs->hits = (hit_record *)block;
    rs->u = (double *)(block + hits_bytes);
    rs->v = (double *)(block + hits_bytes + uv_bytes);
    rs->samples = max_samples > 0 ? (highlight_sample *)(block + hits_bytes + 2 * uv_bytes) : NULL;
    rs->found = (int *)(block + hits_bytes + 2 * uv_bytes + samples_bytes);
    return 1;
}

/* Trace row y: pixels well inside or outside the silhouette (all four corners and the centre agree) get one
 * primary ray through their centre; pixels on the silhouette get n x n rays on a regular sub-pixel grid, each
 * weighted 1/n^2, so they are box-filtered like a path tracer's pixels instead of aliased (docs/design.md
 * principle 2: the extra rays go only where the image has an edge). Rays are traced a chunk of pixel centres or
 * a pixel's sub-pixel rays at a time (trace_rays), their hits added in pixel and ray order. Returns 0 on
 * allocation failure. */
static int trace_row(const tracer *tr, const env_table *env, const unsigned char *corner_hit, int edge_n, int y,
                     float *coverage, row_result *row) {
    const mr_scene *scene = tr->scene;
    const mesh_world *occluder = scene->shape.type == MR_SHAPE_MESH && !tr->mesh->convex ? tr->mesh : NULL;
    const int width = scene->width;
    row->pixels = malloc((size_t)width * sizeof *row->pixels);
    row->hit_counts = malloc((size_t)width * sizeof *row->hit_counts);
    if (row->pixels == NULL || row->hit_counts == NULL) return 0;
    ray_scratch rs;
    if (!ray_scratch_init(tr, edge_n, &rs)) return 0;
    const double centre_v = camera_v(&tr->camera, y + 0.5);
    const unsigned char *corners_above = corner_hit + (size_t)y * (size_t)(width + 1);
    const unsigned char *corners_below = corners_above + width + 1;
    // Can any pixel of the row meet a highlight's disc? Those that do lie in its window (highlight.h).
    int row_meets_highlight = 0;
    for (int d = 0; rs.samples != NULL && d < tr->quadrature.count; d++) {
        const highlight_disc_pixels *dp = &tr->quadrature.pixels[d];
        row_meets_highlight |= y >= dp->y0 && y < dp->y0 + dp->ny;
    }
    int ok = 1;
    for (int x0 = 0; x0 < width && ok; x0 += ROW_RAYS) {
        const int x1 = MR_MIN(width, x0 + ROW_RAYS);
        // The chunk's centre rays. With edge_n > 1 a centre's hit is used only when all four corners see the
        // object too (n = 1); with corners that disagree the pixel is on the silhouette whatever the centre
        // sees, and with none it is asked yes or no. With edge_n = 1 the centre is the pixel's one ray in every
        // case. Pixels around a highlight take the quadrature of highlight.h instead.
        int centre[ROW_RAYS], slot[ROW_RAYS], around_highlight[ROW_RAYS], full = 0, asked = 0;
        for (int x = x0; x < x1; x++) {
            const int corners = corners_above[x] + corners_above[x + 1] + corners_below[x] + corners_below[x + 1];
            around_highlight[x - x0] =
                row_meets_highlight && mr_highlight_touches(tr->quadrature.discs, tr->quadrature.count, x, y);
            slot[x - x0] = -1;
            centre[x - x0] = corners; // the corner count, until the centre is known
            if (around_highlight[x - x0] || (corners > 0 && corners < 4 && edge_n > 1)) continue;
            if (corners == 4 || edge_n == 1) slot[x - x0] = full++;
        }
        for (int x = x0, f = 0; x < x1; x++)
            if (slot[x - x0] >= 0) {
                rs.u[f] = tr->centre_u[x];
                rs.v[f++] = centre_v;
            }
        trace_rays(tr, full, rs.u, rs.v, rs.hits, rs.found);
        int centre_found[ROW_RAYS];
        for (int x = x0; x < x1; x++) centre_found[x - x0] = slot[x - x0] >= 0 ? rs.found[slot[x - x0]] : 0;
        // Yes or no: the centres between four corners that miss (edge_n > 1).
        int asked_pixel[ROW_RAYS];
        for (int x = x0; x < x1; x++)
            if (centre[x - x0] == 0 && slot[x - x0] < 0 && !around_highlight[x - x0]) {
                asked_pixel[asked] = x - x0;
                rs.u[full + asked] = tr->centre_u[x];
                rs.v[full + asked++] = centre_v;
            }
        trace_rays(tr, asked, rs.u + full, rs.v + full, NULL, rs.found + full);
        for (int k = 0; k < asked; k++) centre_found[asked_pixel[k]] = rs.found[full + k];
        hit_record *centre_hits = rs.hits; // kept until the chunk's centre pixels are added
        for (int x = x0; x < x1 && ok; x++) {
            const int pixel = y * width + x;
            const int corners = centre[x - x0];
            const int sample_count =
                around_highlight[x - x0] ? mr_highlight_quadrature_pixel(&tr->quadrature, x, y, rs.samples) : -1;
            if (sample_count >= 0) { // around a highlight
                // its rays go after the chunk's centre hits, which later pixels of the chunk still need
                for (int k = 0; k < sample_count; k++) {
                    rs.u[full + k] = camera_u(&tr->camera, rs.samples[k].x);
                    rs.v[full + k] = camera_v(&tr->camera, rs.samples[k].y);
                }
                trace_rays(tr, sample_count, rs.u + full, rs.v + full, centre_hits + full, rs.found + full);
                size_t first = row->hit_count;
                double covered = 0.0;
                for (int k = 0; k < sample_count && ok; k++) {
                    if (!rs.found[full + k]) continue;
                    covered += rs.samples[k].weight;
                    ok = add_hit(scene, env, occluder, &centre_hits[full + k], rs.samples[k].weight, row);
                }
                finish_pixel(row, coverage, pixel, covered, first);
                continue;
            }
            const int seen = centre_found[x - x0];
            const int n = (corners == 4 * seen) ? 1 : edge_n;
            const double weight = 1.0 / ((double)n * n);
            const size_t first = row->hit_count;
            int hits = 0;
            if (n == 1) {
                if (seen) {
                    hits = 1;
                    ok = add_hit(scene, env, occluder, &centre_hits[slot[x - x0]], weight, row);
                }
            } else {
                for (int j = 0, r = 0; j < n; j++)
                    for (int i = 0; i < n; i++, r++) {
                        rs.u[full + r] = camera_u(&tr->camera, x + (i + 0.5) / n);
                        rs.v[full + r] = camera_v(&tr->camera, y + (j + 0.5) / n);
                    }
                trace_rays(tr, n * n, rs.u + full, rs.v + full, centre_hits + full, rs.found + full);
                for (int r = 0; r < n * n && ok; r++) {
                    if (!rs.found[full + r]) continue;
                    hits++;
                    ok = add_hit(scene, env, occluder, &centre_hits[full + r], weight, row);
                }
            }
            finish_pixel(row, coverage, pixel, hits * weight, first);
        }
    }
    free(rs.block);
    return ok;
}

/* The plan's point samples in plan order as structure of arrays, what a batched render reads: sample s is lit from
 * light[.][s] with weight[.][s] and seen from view[.][s] (its hit's view, repeated for each of the hit's samples). */
typedef struct point_soa {
    double *view[3], *light[3], *weight[3]; /* x, y, z (view, light) and R, G, B (weight) arrays */
    double *block;                          /* the one allocation all nine arrays live in */
    int *pixel_begin; /* [lit_pixels + 1]: lit pixel i's samples are [pixel_begin[i], pixel_begin[i + 1]) (its hits'
                         samples follow each other in plan order, so a render need not walk the hits) */
} point_soa;

static void point_soa_free(point_soa *soa) {
    if (soa == NULL) return;
    free(soa->block);
    free(soa->pixel_begin);
    free(soa);
}

void mr_render_plan_free(mr_render_plan *plan) {
    if (plan == NULL) return;
    mr_render_plan_free(atomic_load(&plan->zoomed));
    point_soa_free(atomic_load(&plan->point_soa));
    free(plan->coverage);
    free(plan->lit_pixel_index);
    free(plan->hit_begin);
    free(plan->hits);
    free(plan->frames);
    free(plan->point_samples);
    free(plan->env_samples);
    free(plan->reflection_samples);
    mr_env_table_free(&plan->env);
    mr_mesh_world_free(&plan->mesh);
    free(plan);
}

mr_status mr_render_plan_create(const mr_scene *scene, mr_render_plan **out) {
    return mr_render_plan_create_rays(scene, MR_PLAN_RAYS_AUTO, out);
}

mr_status mr_render_plan_create_rays(const mr_scene *scene, mr_plan_rays rays, mr_render_plan **out) {
    if (scene == NULL || out == NULL) return mr_fail(MR_ERR_INVALID_ARG, "render plan: NULL scene or output");
    mr_status status = mr_scene_validate(scene);
    if (status != MR_OK) return status;

    const int width = scene->width, height = scene->height;
    const int edge_n = scene->edge_samples > 0 ? scene->edge_samples : MR_SCENE_DEFAULT_EDGE_SAMPLES;
    tracer tr;
    memset(&tr, 0, sizeof tr);
    tr.scene = scene;
    camera_frame_init(scene, &tr.camera);
    find_highlights(scene, &tr);
    if (scene->shape.type == MR_SHAPE_SPHERE) {
        sphere_screen_init(scene, &tr);
        tr.vector_rays = MR_RAYS_X86 && (rays == MR_PLAN_RAYS_AUTO     ? mr_brdf_batch_vector_default()
                                         : rays == MR_PLAN_RAYS_VECTOR ? mr_brdf_batch_cpu_vector()
                                                                       : 0);
    }
    surface_sampler *surfaces = NULL;
    mr_render_plan *plan = calloc(1, sizeof *plan);
    unsigned char *corner_hit = malloc((size_t)(width + 1) * (size_t)(height + 1));
    row_result *rows = calloc((size_t)height, sizeof *rows);
    double *columns_u = malloc((2 * (size_t)width + 1) * sizeof *columns_u);
    int failed = 0;
    if (plan == NULL || corner_hit == NULL || rows == NULL || columns_u == NULL) goto oom;
    tr.corner_u = columns_u;
    tr.centre_u = columns_u + width + 1;
    for (int x = 0; x <= width; x++) tr.corner_u[x] = camera_u(&tr.camera, x);
    for (int x = 0; x < width; x++) tr.centre_u[x] = camera_u(&tr.camera, x + 0.5);
    if (!mr_highlight_quadrature_build(tr.highlights, tr.highlight_count, &tr.quadrature)) goto oom;
    atomic_init(&plan->zoomed, NULL);
    atomic_init(&plan->point_soa, NULL);
    plan->scene = *scene;
    plan->coverage = calloc((size_t)width * (size_t)height, sizeof *plan->coverage);
    if (plan->coverage == NULL) goto oom;
    status = mr_env_table_setup(scene, &plan->env);
    if (status != MR_OK) goto fail;
    tr.mesh = &plan->mesh;
    if (scene->shape.type == MR_SHAPE_MESH) {
        status = mr_mesh_world_build(scene->shape.mesh, scene->threads, &plan->mesh);
        if (status != MR_OK) goto fail;
        const mr_mesh *src = scene->shape.mesh;
        if (src->surfaces != NULL) {
            surfaces = calloc((size_t)plan->mesh.material_count, sizeof *surfaces);
            if (surfaces == NULL) goto oom;
            for (int m = 0; m < plan->mesh.material_count; m++) {
                const mr_surface *surface = &src->surfaces[m];
                surfaces[m].surface = surface;
                if (surface->normal_map)
                    mr_texture_sampler_init(&surfaces[m].normal, surface->normal_map, &surface->normal_sampling, 0, 3);
                if (surface->occlusion_map)
                    mr_texture_sampler_init(&surfaces[m].occlusion, surface->occlusion_map,
                                         &surface->occlusion_sampling, 0, 1);
                if (surface->emissive_map)
                    mr_texture_sampler_init(&surfaces[m].emissive, surface->emissive_map, &surface->emissive_sampling,
                                         0, 3);
            }
            tr.surfaces = surfaces;
        }
    }

    // Which pixel corners see the object: a pixel whose corners and centre agree is entirely inside or
    // outside the silhouette (the projected sphere is convex and, at these sizes, far wider than a pixel; a
    // mesh's silhouette is handled alike, so only features thinner than a pixel that slip between its corners
    // and centre escape the filter).
    // A mesh's rays cost a BVH walk each: a plan of a mesh counts its pixels four times.
    const long trace_work = (long)width * height * (scene->shape.type == MR_SHAPE_MESH ? 4 : 1);
    const int plan_threads = mr_auto_threads(scene->threads, trace_work, MR_RENDER_PARALLEL_PIXELS);
#pragma omp parallel for schedule(static) num_threads(plan_threads) if (plan_threads > 1)
    for (int y = 0; y <= height; y++) {
        double v[ROW_RAYS];
        int found[ROW_RAYS];
        for (int k = 0; k < ROW_RAYS; k++) v[k] = camera_v(&tr.camera, y);
        for (int x0 = 0; x0 <= width; x0 += ROW_RAYS) {
            const int count = MR_MIN(width + 1 - x0, ROW_RAYS);
            trace_rays(&tr, count, tr.corner_u + x0, v, NULL, found);
            for (int k = 0; k < count; k++)
                corner_hit[(size_t)y * (size_t)(width + 1) + (size_t)(x0 + k)] = (unsigned char)found[k];
        }
    }

#pragma omp parallel for schedule(dynamic, 4) reduction(| : failed) num_threads(plan_threads) if (plan_threads > 1)
    for (int y = 0; y < height; y++)
        if (!trace_row(&tr, &plan->env, corner_hit, edge_n, y, plan->coverage, &rows[y]))
            failed = 1;
    if (failed) goto oom;

    // Concatenate the rows in image order: the plan, and so every render, is the same for any thread count.
    size_t lit = 0, hits = 0, points = 0, envs = 0, reflections = 0;
    for (int y = 0; y < height; y++) {
        lit += (size_t)rows[y].lit;
        hits += rows[y].hit_count;
        points += rows[y].point_count;
        envs += rows[y].env_count;
        reflections += rows[y].reflection_count;
        plan->object_pixels += rows[y].object_pixels;
        plan->shadow_rays += rows[y].shadow_rays;
    }
    if (hits >= (size_t)INT_MAX || points > (size_t)INT_MAX) goto oom;
    plan->lit_pixel_index = malloc((lit + 1) * sizeof *plan->lit_pixel_index);
    plan->hit_begin = malloc((lit + 1) * sizeof *plan->hit_begin);
    plan->hits = malloc((hits + 1) * sizeof *plan->hits);
    plan->point_samples = malloc((points + 1) * sizeof *plan->point_samples);
    plan->env_samples = malloc((envs + 1) * sizeof *plan->env_samples);
    plan->reflection_samples = malloc((reflections + 1) * sizeof *plan->reflection_samples);
    if (plan->env.count > 0 && (plan->frames = malloc((hits + 1) * sizeof *plan->frames)) == NULL) goto oom;
    if (plan->lit_pixel_index == NULL || plan->hit_begin == NULL || plan->hits == NULL ||
        plan->point_samples == NULL || plan->env_samples == NULL || plan->reflection_samples == NULL)
        goto oom;
    int next_lit = 0, next_hit = 0;
    size_t next_point = 0, next_env = 0, next_reflection = 0;
    for (int y = 0; y < height; y++) {
        const row_result *row = &rows[y];
        if (row->point_count > 0)
            memcpy(plan->point_samples + next_point, row->points, row->point_count * sizeof *row->points);
        if (row->env_count > 0) memcpy(plan->env_samples + next_env, row->env, row->env_count * sizeof *row->env);
        if (row->reflection_count > 0)
            memcpy(plan->reflection_samples + next_reflection, row->reflections,
                   row->reflection_count * sizeof *row->reflections);
        if (plan->frames != NULL && row->hit_count > 0)
            memcpy(plan->frames + next_hit, row->frames, row->hit_count * sizeof *row->frames);
        for (size_t h = 0; h < row->hit_count; h++) {
            plan_hit *hit = &plan->hits[next_hit + (int)h];
            *hit = row->hits[h];
            hit->point_begin += (int)next_point;
            hit->env_begin += next_env;
            hit->reflection_begin += next_reflection;
            if (hit->emission[0] != 0.0 || hit->emission[1] != 0.0 || hit->emission[2] != 0.0) plan->emits = 1;
        }
        for (int i = 0; i < row->lit; i++) {
            plan->lit_pixel_index[next_lit] = row->pixels[i];
            plan->hit_begin[next_lit] = next_hit;
            next_hit += row->hit_counts[i];
            next_lit++;
        }
        next_point += row->point_count;
        next_env += row->env_count;
        next_reflection += row->reflection_count;
    }
    plan->hit_begin[next_lit] = next_hit;
    memset(&plan->hits[next_hit], 0, sizeof plan->hits[next_hit]);
    plan->hits[next_hit].point_begin = (int)next_point;
    plan->hits[next_hit].env_begin = next_env;
    plan->hits[next_hit].reflection_begin = next_reflection;
    plan->hit_count = next_hit;
    // The maps were borrowed for the reflection samples' weights; the plan keeps no reference to them.
    free(plan->env.sources);
    plan->env.sources = NULL;
    plan->env.source_count = 0;
    plan->lit_pixels = next_lit;
    plan->render_threads =
        mr_auto_threads(scene->threads, mr_render_plan_sample_count(plan), MR_RENDER_PARALLEL_SAMPLES);
    for (int y = 0; y < height; y++) row_result_free(&rows[y]);
    free(rows);
    free(corner_hit);
    free(columns_u);
    free(surfaces);
    mr_highlight_quadrature_free(&tr.quadrature);
    *out = plan;
    return MR_OK;

oom:
    status = mr_fail(MR_ERR_NOMEM, "render plan: out of memory for a %dx%d scene", width, height);
fail:
    if (rows != NULL)
        for (int y = 0; y < height; y++) row_result_free(&rows[y]);
    free(rows);
    free(corner_hit);
    free(columns_u);
    free(surfaces);
    mr_highlight_quadrature_free(&tr.quadrature);
    mr_render_plan_free(plan);
    return status;
}

const mr_scene *mr_render_plan_scene(const mr_render_plan *plan) { return &plan->scene; }

int mr_render_plan_lit_pixel_count(const mr_render_plan *plan) { return plan->lit_pixels; }

int mr_render_plan_threads(const mr_render_plan *plan) { return plan->render_threads; }

int mr_render_plan_object_pixel_count(const mr_render_plan *plan) { return plan->object_pixels; }

long mr_render_plan_env_sample_count(const mr_render_plan *plan) {
    return (long)plan->hits[plan->hit_count].env_begin + (long)plan->hits[plan->hit_count].reflection_begin;
}

long mr_render_plan_reflection_sample_count(const mr_render_plan *plan) {
    return (long)plan->hits[plan->hit_count].reflection_begin;
}

long mr_render_plan_sample_count(const mr_render_plan *plan) {
    return (long)plan->hits[plan->hit_count].point_begin + mr_render_plan_env_sample_count(plan);
}

size_t mr_render_plan_bytes(const mr_render_plan *plan) {
    const mr_render_plan *zoomed = atomic_load(&plan->zoomed); // the closer look it keeps, if built
    size_t pixels = (size_t)plan->scene.width * (size_t)plan->scene.height;
    size_t lit = (size_t)plan->lit_pixels, hits = (size_t)plan->hit_count;
    return sizeof *plan + pixels * sizeof *plan->coverage + (lit + 1) * (sizeof *plan->lit_pixel_index +
           sizeof *plan->hit_begin) + (hits + 1) * (sizeof *plan->hits + (plan->frames ? sizeof *plan->frames : 0)) +
           ((size_t)plan->hits[hits].point_begin + 1) * sizeof *plan->point_samples +
           (plan->hits[hits].env_begin + 1) * sizeof *plan->env_samples +
           (plan->hits[hits].reflection_begin + 1) * sizeof *plan->reflection_samples +
           (size_t)plan->env.count * (sizeof *plan->env.direction + sizeof *plan->env.weight +
                                      (plan->env.mis_npdf ? sizeof *plan->env.mis_npdf : 0)) +
           mr_mesh_world_bytes(&plan->mesh) + (zoomed ? mr_render_plan_bytes(zoomed) : 0) +
           (atomic_load(&plan->point_soa) ? 9 * (size_t)plan->hits[hits].point_begin * sizeof(double) +
                                                (lit + 1) * sizeof(int) : 0);
}

mr_status mr_render_plan_zoomed(const mr_render_plan *plan, double zoom, const mr_render_plan **out) {
    if (plan == NULL || out == NULL || !(zoom > 0.0))
        return mr_fail(MR_ERR_INVALID_ARG, "render plan: closer look: NULL plan or output, or zoom %g", zoom);
    *out = NULL;
    // The plan is const to its users; its cache slot is the one field that changes, atomically (the object
    // itself was allocated writable by mr_render_plan_create).
    _Atomic(mr_render_plan *) *slot = &((mr_render_plan *)plan)->zoomed;
    mr_render_plan *made = atomic_load_explicit(slot, memory_order_acquire);
    if (made == NULL) {
        mr_scene scene;
        if (!mr_scene_zoom_on_highlight(&plan->scene, zoom, &scene)) return MR_OK; // no highlight to look at
        mr_status status = mr_render_plan_create(&scene, &made);
        if (status != MR_OK) return mr_fail_context(status, "render plan: closer look");
        made->zoom = zoom;
        made->float_kernels = plan->float_kernels;
        mr_render_plan *expected = NULL;
        if (!atomic_compare_exchange_strong_explicit(slot, &expected, made, memory_order_acq_rel,
                                                     memory_order_acquire)) {
            mr_render_plan_free(made); // another thread installed its copy first
            made = expected;
        }
    }
    if (made->zoom != zoom)
        return mr_fail(MR_ERR_INVALID_ARG, "render plan: closer look %g times: this plan keeps the one of %g times",
                       zoom, made->zoom);
    *out = made;
    return MR_OK;
}

void mr_render_plan_set_float_kernels(mr_render_plan *plan, int on) {
    plan->float_kernels = on != 0;
    mr_render_plan *zoomed = atomic_load_explicit(&plan->zoomed, memory_order_acquire);
    if (zoomed != NULL) zoomed->float_kernels = plan->float_kernels;
}

const float *mr_render_plan_coverage(const mr_render_plan *plan) { return plan->coverage; }

mr_status mr_render_plan_coverage_mask(const mr_render_plan *plan, mr_image **out) {
    if (plan == NULL || out == NULL) return mr_fail(MR_ERR_INVALID_ARG, "coverage mask: NULL plan or output");
    mr_image *mask = NULL;
    mr_status status = mr_image_create(plan->scene.width, plan->scene.height, 1, &mask);
    if (status != MR_OK) return mr_fail_context(status, "coverage mask");
    memcpy(mask->pixels, plan->coverage, mr_image_value_count(mask) * sizeof *mask->pixels);
    *out = mask;
    return MR_OK;
}

long mr_render_plan_shadow_ray_count(const mr_render_plan *plan) { return plan->shadow_rays; }

int mr_render_plan_self_occluding(const mr_render_plan *plan) {
    return plan->scene.shape.type == MR_SHAPE_MESH && !plan->mesh.convex;
}

int mr_render_plan_trace_mesh(const mr_render_plan *plan, const double origin[3], const double dir[3],
                              int brute_force, double *t, int *triangle) {
    if (plan == NULL || plan->scene.shape.type != MR_SHAPE_MESH || origin == NULL || dir == NULL) return 0;
    mesh_hit hit;
    int found = brute_force ? mr_mesh_intersect_brute(&plan->mesh, origin, dir, INFINITY, -1, CULL_NONE, &hit)
                            : mr_mesh_intersect(&plan->mesh, origin, dir, INFINITY, -1, CULL_NONE, &hit);
    if (!found) return 0;
    if (t != NULL) *t = hit.t;
    if (triangle != NULL) *triangle = hit.triangle;
    return 1;
}

/* ---- renders ------------------------------------------------------------------------------------------------- */

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
    const double *bg = plan->scene.background;
    // A black background (the fit scene's) is a memset: the fill was 8 % of a remap as a per-value loop.
    if (!with_background || (bg[0] == 0.0 && bg[1] == 0.0 && bg[2] == 0.0)) {
        memset(image->pixels, 0, pixel_count * 3 * sizeof *image->pixels);
        return;
    }
    for (size_t p = 0; p < pixel_count; p++) {
        double uncovered = 1.0 - plan->coverage[p];
        for (int c = 0; c < 3; c++) image->pixels[p * 3 + c] = (float)(bg[c] * uncovered);
    }
}

/* Environment sample e of hit h as the renders use it: its direction in the hit's shading frame and its weight, the
 * map's radiance x cos x the hit's share (x ambient occlusion), and with reflection samples the balance heuristic's
 * share of the pattern, N p / (N p + M q). A hit with environment samples has its frame (plan->frames). */
static inline void env_sample_of_hit(const mr_render_plan *plan, int h, size_t e, double light[3], double weight[3]) {
    const int k = plan->env_samples[e];
    const double *d = plan->env.direction[k];
    const hit_frame *frame = &plan->frames[h];
    light[0] = vec3_dot(frame->tangent, d);
    light[1] = vec3_dot(frame->bitangent, d);
    light[2] = vec3_dot(frame->normal, d);
    double cos_share = light[2] * plan->hits[h].env_share;
    if (plan->env.mis_npdf != NULL && plan->env.mis_npdf[k] > 0.0) {
        const double npdf = plan->env.mis_npdf[k];
        cos_share *= npdf / (npdf + reflection_density(&plan->env, &frame->mirror, d));
    }
    for (int c = 0; c < 3; c++) weight[c] = plan->env.weight[k][c] * cos_share;
}

/* One sample's contribution: into sum_full (full renders, f_d + f_s summed first) or into sum_d / sum_s (the
 * components that are asked for). */
static inline void accumulate(const mr_brdf_model *model, const void *state, const double view[3],
                              const double light[3], const double weight[3], double *sum_full, double *sum_d,
                              double *sum_s) {
    double fd[3], fs[3];
    if (sum_full != NULL) {
        model->eval(state, view, light, fd, fs);
        for (int c = 0; c < 3; c++) sum_full[c] += (fd[c] + fs[c]) * weight[c];
        return;
    }
    model->eval(state, view, light, sum_d ? fd : NULL, sum_s ? fs : NULL);
    for (int c = 0; c < 3; c++) {
        if (sum_d) sum_d[c] += fd[c] * weight[c];
        if (sum_s) sum_s[c] += fs[c] * weight[c];
    }
}

/* A map bound to packed value slots, as the render loop reads it. */
typedef struct texture_binding {
    texture_sampler sampler; /* reads `count` values from the map */
    int slot;                /* first packed value it sets */
} texture_binding;

/* One material as the render loop uses it: its state for constant values, and its maps. */
typedef struct material_state {
    const mr_brdf_model *model;
    const double *values;
    int value_count;
    int binding_count;
    texture_binding bindings[MR_BRDF_MAX_VALUES];
    mr_brdf_state shared; /* prepared from values (the state of every hit when there are no maps) */
} material_state;

/* Check a material and prepare its state. `index` names it in errors. */
static mr_status material_state_init(const mr_material_binding *material, int index, material_state *ms) {
    const mr_brdf_model *model = material->model;
    const mr_param_textures *textures = material->textures;
    if (model == NULL || material->values == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "render: material %d: NULL model or values", index);
    ms->model = model;
    ms->values = material->values;
    ms->value_count = mr_brdf_value_count(model);
    ms->binding_count = 0;
    for (int p = 0; textures != NULL && p < model->param_count && p < MR_BRDF_MAX_VALUES; p++) {
        if (textures->maps[p] == NULL) continue;
        mr_status status = mr_texture_check_binding(model, p, textures->maps[p], textures->channel[p]);
        if (status == MR_OK) status = mr_texture_sampling_validate(&textures->sampling[p], "render: texture sampling");
        if (status != MR_OK) return status;
        const int channels = model->params[p].channels;
        texture_binding *binding = &ms->bindings[ms->binding_count++];
        mr_texture_sampler_init(&binding->sampler, textures->maps[p], &textures->sampling[p],
                             channels == 1 ? textures->channel[p] : 0, channels);
        binding->slot = mr_brdf_param_offset(model, p);
    }
    model->prepare(model, material->values, ms->shared.bytes);
    return MR_OK;
}

/* The plan's point samples as structure of arrays (point_soa), built by the first render that asks (any thread;
 * the first to finish installs its copy with a compare-and-swap, a loser frees its own). NULL when out of memory:
 * the caller then takes the per-sample loop, which needs nothing more. */
static const point_soa *plan_point_soa(const mr_render_plan *plan) {
    // The plan is const to its users; this cache slot changes, atomically (as `zoomed`, mr_render_plan_zoomed).
    _Atomic(point_soa *) *slot = &((mr_render_plan *)plan)->point_soa;
    point_soa *made = atomic_load_explicit(slot, memory_order_acquire);
    if (made != NULL) return made;
    const size_t count = (size_t)plan->hits[plan->hit_count].point_begin;
    made = calloc(1, sizeof *made);
    double *block = made ? malloc((9 * count + 1) * sizeof *block) : NULL;
    int *pixel_begin = block ? malloc(((size_t)plan->lit_pixels + 1) * sizeof *pixel_begin) : NULL;
    if (pixel_begin == NULL) {
        free(block);
        free(made);
        return NULL;
    }
    made->block = block;
    made->pixel_begin = pixel_begin;
    for (int i = 0; i <= plan->lit_pixels; i++) pixel_begin[i] = plan->hits[plan->hit_begin[i]].point_begin;
    for (int k = 0; k < 3; k++) {
        made->view[k] = block + (size_t)k * count;
        made->light[k] = block + (size_t)(3 + k) * count;
        made->weight[k] = block + (size_t)(6 + k) * count;
    }
    for (int h = 0; h < plan->hit_count; h++) {
        const plan_hit *hit = &plan->hits[h];
        for (int s = hit->point_begin; s < hit[1].point_begin; s++)
            for (int k = 0; k < 3; k++) {
                made->view[k][s] = hit->view[k];
                made->light[k][s] = plan->point_samples[s].light[k];
                made->weight[k][s] = plan->point_samples[s].weight[k];
            }
    }
    point_soa *expected = NULL;
    if (!atomic_compare_exchange_strong_explicit(slot, &expected, made, memory_order_acq_rel, memory_order_acquire)) {
        point_soa_free(made); // another thread installed its copy first
        made = expected;
    }
    return made;
}

/* Lit pixels per task of a batched render, and point samples per evaluated batch. The pixels are cut into fixed
 * blocks and each block into batches from its first sample on, whatever the thread count, so every image is the
 * same for any number of threads (and a pair's value does not depend on its batch anyway: brdf.h). */
#define RENDER_BATCH_PIXELS 64
#define RENDER_BATCH_SAMPLES 256

/* The most point samples a plan lays out as structure of arrays (about 76 bytes each, 300 MB at the limit; the fit
 * scene has 0.11 M at 512^2); larger plans, rendered once or twice rather than in an optimiser's loop, gather their
 * batches from the hits instead (render_gathered) and keep no copy. */
#define RENDER_SOA_MAX_SAMPLES (1 << 22)

/* A batch's values times their samples' weights, in place, before the pixels sum them: (fd + fs) w into fd for a full
 * render, fd w and fs w for the parts. The same products the per-sample loop adds (accumulate), in a loop the
 * compiler vectorises; the pixels' sums are then plain additions in plan order. */
static inline __attribute__((always_inline)) void weigh_batch(double fd[3][RENDER_BATCH_SAMPLES],
                                                              double fs[3][RENDER_BATCH_SAMPLES],
                                                              const double *const weight[3], int n,
                                                              const int want_full) {
    for (int c = 0; c < 3; c++) {
        double *restrict d = fd[c], *restrict f = fs[c];
        const double *restrict w = weight[c];
        if (want_full) {
#pragma omp simd
            for (int j = 0; j < n; j++) d[j] = (d[j] + f[j]) * w[j];
        } else {
#pragma omp simd
            for (int j = 0; j < n; j++) {
                d[j] *= w[j];
                f[j] *= w[j];
            }
        }
    }
}

/* A batched render's sums of lit pixel i into the images asked for (NULL: not asked): the full one over the background
 * share of the pixel the object leaves uncovered, as render_core writes them. */
static inline void store_lit_pixel(const mr_render_plan *plan, int i, mr_image *full, mr_image *diffuse,
                                   mr_image *specular, double f0, double f1, double f2, double d0, double d1, double d2,
                                   double s0, double s1, double s2) {
    const size_t pixel = (size_t)plan->lit_pixel_index[i];
    if (full) {
        const double uncovered = 1.0 - plan->coverage[pixel];
        const double *bg = plan->scene.background;
        full->pixels[pixel * 3 + 0] = (float)(f0 + bg[0] * uncovered);
        full->pixels[pixel * 3 + 1] = (float)(f1 + bg[1] * uncovered);
        full->pixels[pixel * 3 + 2] = (float)(f2 + bg[2] * uncovered);
    }
    if (diffuse) {
        diffuse->pixels[pixel * 3 + 0] = (float)d0;
        diffuse->pixels[pixel * 3 + 1] = (float)d1;
        diffuse->pixels[pixel * 3 + 2] = (float)d2;
    }
    if (specular) {
        specular->pixels[pixel * 3 + 0] = (float)s0;
        specular->pixels[pixel * 3 + 1] = (float)s1;
        specular->pixels[pixel * 3 + 2] = (float)s2;
    }
}

/* The model's batch: `kernel` (a float kernel, brdf_float.h) when the plan asks for float and the model has one,
 * else eval_batch in double (kernel NULL). */
static inline __attribute__((always_inline)) void render_eval_batch(const mr_brdf_model *model, mr_brdf_batch_fn kernel,
                                                                    const void *state, const mr_brdf_batch *batch,
                                                                    int vector) {
    if (kernel != NULL)
        kernel(state, batch, vector);
    else
        mr_brdf_eval_batch(model, state, batch, vector);
}

/* One block of lit pixels [first, end) of a batched render, for the parts asked for (constants in each call of
 * render_batched, so that the sums stay in registers): the model's eval_batch over the block's samples in batches,
 * weighed (weigh_batch), then each lit pixel sums its samples in plan order, which is accumulate()'s arithmetic
 * (and, where the surface emits, each hit's emission after its samples, as the per-sample loop does). */
static inline __attribute__((always_inline)) void render_block(const mr_render_plan *plan, const point_soa *soa,
                                                               const mr_brdf_model *model, const void *state,
                                                               mr_brdf_batch_fn kernel, int vector, int first,
                                                               int end, mr_image *full,
                                                               mr_image *diffuse, mr_image *specular,
                                                               const int want_full, const int want_diffuse,
                                                               const int want_specular) {
    double fd[3][RENDER_BATCH_SAMPLES], fs[3][RENDER_BATCH_SAMPLES];
    const int samples_end = soa->pixel_begin[end];
    int batch_begin = soa->pixel_begin[first], batch_end = batch_begin;
    for (int i = first; i < end; i++) {
        double f0 = 0.0, f1 = 0.0, f2 = 0.0, d0 = 0.0, d1 = 0.0, d2 = 0.0, s0 = 0.0, s1 = 0.0, s2 = 0.0;
        // Without emission a pixel's samples are one range; with it, hit by hit, each hit's emission after.
        const int hit_first = plan->emits ? plan->hit_begin[i] : 0;
        const int hit_end = plan->emits ? plan->hit_begin[i + 1] : 1;
        for (int h = hit_first; h < hit_end; h++) {
            const int s_first = plan->emits ? plan->hits[h].point_begin : soa->pixel_begin[i];
            const int s_end = plan->emits ? plan->hits[h + 1].point_begin : soa->pixel_begin[i + 1];
            for (int s = s_first; s < s_end; s++) {
                if (s >= batch_end) {
                    batch_begin = s;
                    batch_end = MR_MIN(samples_end, s + RENDER_BATCH_SAMPLES);
                    const mr_brdf_batch batch = {
                        batch_end - batch_begin,
                        {soa->view[0] + s, soa->view[1] + s, soa->view[2] + s},
                        {soa->light[0] + s, soa->light[1] + s, soa->light[2] + s},
                        {fd[0], fd[1], fd[2]},
                        {fs[0], fs[1], fs[2]},
                    };
                    render_eval_batch(model, kernel, state, &batch, vector);
                    const double *const weight[3] = {soa->weight[0] + s, soa->weight[1] + s, soa->weight[2] + s};
                    weigh_batch(fd, fs, weight, batch.n, want_full);
                }
                const int j = s - batch_begin;
                if (want_full) {
                    f0 += fd[0][j];
                    f1 += fd[1][j];
                    f2 += fd[2][j];
                }
                if (want_diffuse) {
                    d0 += fd[0][j];
                    d1 += fd[1][j];
                    d2 += fd[2][j];
                }
                if (want_specular) {
                    s0 += fs[0][j];
                    s1 += fs[1][j];
                    s2 += fs[2][j];
                }
            }
            if (want_full && plan->emits) {
                f0 += plan->hits[h].emission[0];
                f1 += plan->hits[h].emission[1];
                f2 += plan->hits[h].emission[2];
            }
        }
        store_lit_pixel(plan, i, want_full ? full : NULL, want_diffuse ? diffuse : NULL,
                        want_specular ? specular : NULL, f0, f1, f2, d0, d1, d2, s0, s1, s2);
    }
}

/* A batch gathered from the hits (environment and reflection samples have no stored light direction or weight: the
 * plan keeps a direction index, or float ones, per sample): each sample's view, light and weight, computed as the
 * per-sample loop computes them, and the model's value. */
typedef struct gathered_batch {
    double view[3][RENDER_BATCH_SAMPLES], light[3][RENDER_BATCH_SAMPLES], weight[3][RENDER_BATCH_SAMPLES];
    double fd[3][RENDER_BATCH_SAMPLES], fs[3][RENDER_BATCH_SAMPLES];
} gathered_batch;

/* Where a walk over a block's samples stands: hit h, its point samples (stage 0), environment samples (1) or
 * reflection samples (2), sample k of that stage's array. */
typedef struct sample_position {
    int h, stage;
    size_t k;
} sample_position;

/* Fills `out` with the samples from `at` on, in plan order, up to RENDER_BATCH_SAMPLES or hit `hit_end`, and
 * evaluates them; returns how many. The light and weight of each are the per-sample loop's (render_core), operation
 * for operation. */
static int gather_batch(const mr_render_plan *plan, sample_position at, int hit_end, const mr_brdf_model *model,
                        const void *state, mr_brdf_batch_fn kernel, int vector, gathered_batch *out) {
    int n = 0;
    for (int h = at.h; h < hit_end && n < RENDER_BATCH_SAMPLES; h++) {
        const plan_hit *hit = &plan->hits[h];
        const int stage_first = h == at.h ? at.stage : 0;
        for (int stage = stage_first; stage < 3 && n < RENDER_BATCH_SAMPLES; stage++) {
            size_t begin = stage == 0 ? (size_t)hit->point_begin : stage == 1 ? hit->env_begin : hit->reflection_begin;
            const size_t end = stage == 0 ? (size_t)hit[1].point_begin
                                          : stage == 1 ? hit[1].env_begin : hit[1].reflection_begin;
            if (h == at.h && stage == at.stage) begin = at.k;
            for (size_t e = begin; e < end && n < RENDER_BATCH_SAMPLES; e++, n++) {
                double light[3], weight[3];
                if (stage == 0) {
                    const point_sample *sample = &plan->point_samples[e];
                    for (int c = 0; c < 3; c++) {
                        light[c] = sample->light[c];
                        weight[c] = sample->weight[c];
                    }
                } else if (stage == 1) {
                    env_sample_of_hit(plan, h, e, light, weight);
                } else {
                    const reflection_sample *sample = &plan->reflection_samples[e];
                    for (int c = 0; c < 3; c++) light[c] = sample->light[c];
                    const double cos_share = light[2] * hit->env_share;
                    for (int c = 0; c < 3; c++) weight[c] = sample->weight[c] * cos_share;
                }
                for (int c = 0; c < 3; c++) {
                    out->view[c][n] = hit->view[c];
                    out->light[c][n] = light[c];
                    out->weight[c][n] = weight[c];
                }
            }
        }
    }
    const mr_brdf_batch batch = {n,
                                 {out->view[0], out->view[1], out->view[2]},
                                 {out->light[0], out->light[1], out->light[2]},
                                 {out->fd[0], out->fd[1], out->fd[2]},
                                 {out->fs[0], out->fs[1], out->fs[2]}};
    render_eval_batch(model, kernel, state, &batch, vector);
    return n;
}

/* render_block for plans with environment or reflection samples: the block's samples gathered batch by batch in
 * plan order (gather_batch) and weighed (weigh_batch), each lit pixel summing its hits' point, environment and
 * reflection samples and then the hit's emission, in the per-sample loop's order and arithmetic. */
static inline __attribute__((always_inline)) void render_block_gathered(const mr_render_plan *plan,
                                                                        const mr_brdf_model *model,
                                                                        const void *state, mr_brdf_batch_fn kernel,
                                                                        int vector, int first,
                                                                        int end, gathered_batch *buf,
                                                                        mr_image *full, mr_image *diffuse,
                                                                        mr_image *specular, const int want_full,
                                                                        const int want_diffuse,
                                                                        const int want_specular) {
    const int hit_end = plan->hit_begin[end];
    int n = 0, j = 0;
    for (int i = first; i < end; i++) {
        double f0 = 0.0, f1 = 0.0, f2 = 0.0, d0 = 0.0, d1 = 0.0, d2 = 0.0, s0 = 0.0, s1 = 0.0, s2 = 0.0;
        for (int h = plan->hit_begin[i]; h < plan->hit_begin[i + 1]; h++) {
            const plan_hit *hit = &plan->hits[h];
            for (int stage = 0; stage < 3; stage++) {
                const size_t begin = stage == 0 ? (size_t)hit->point_begin
                                                : stage == 1 ? hit->env_begin : hit->reflection_begin;
                const size_t stop = stage == 0 ? (size_t)hit[1].point_begin
                                               : stage == 1 ? hit[1].env_begin : hit[1].reflection_begin;
                for (size_t e = begin; e < stop; e++, j++) {
                    if (j == n) {
                        n = gather_batch(plan, (sample_position){h, stage, e}, hit_end, model, state, kernel, vector,
                                         buf);
                        const double *const weight[3] = {buf->weight[0], buf->weight[1], buf->weight[2]};
                        weigh_batch(buf->fd, buf->fs, weight, n, want_full);
                        j = 0;
                    }
                    if (want_full) {
                        f0 += buf->fd[0][j];
                        f1 += buf->fd[1][j];
                        f2 += buf->fd[2][j];
                    }
                    if (want_diffuse) {
                        d0 += buf->fd[0][j];
                        d1 += buf->fd[1][j];
                        d2 += buf->fd[2][j];
                    }
                    if (want_specular) {
                        s0 += buf->fs[0][j];
                        s1 += buf->fs[1][j];
                        s2 += buf->fs[2][j];
                    }
                }
            }
            if (want_full && plan->emits) {
                f0 += hit->emission[0];
                f1 += hit->emission[1];
                f2 += hit->emission[2];
            }
        }
        store_lit_pixel(plan, i, want_full ? full : NULL, want_diffuse ? diffuse : NULL,
                        want_specular ? specular : NULL, f0, f1, f2, d0, d1, d2, s0, s1, s2);
    }
}

/* render_core for one material without maps over a plan with environment or reflection samples (or too many point
 * samples for point_soa), in fixed blocks of lit pixels (render_block_gathered). Returns 0 when out of memory for the
 * batch buffers (nothing rendered). */
static int render_gathered(const mr_render_plan *plan, int threads, const mr_brdf_model *model, const void *state,
                           mr_brdf_batch_fn kernel, int vector, mr_image *full, mr_image *diffuse,
                           mr_image *specular) {
    const int lit = plan->lit_pixels, blocks = (lit + RENDER_BATCH_PIXELS - 1) / RENDER_BATCH_PIXELS;
    const int team = threads > 1 ? threads : 1;
    gathered_batch *buffers = malloc((size_t)team * sizeof *buffers); // 60 kB each: too much for a thread's stack
    if (buffers == NULL) return 0;
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads) if (threads > 1)
    for (int b = 0; b < blocks; b++) {
        gathered_batch *buf = &buffers[team > 1 ? omp_get_thread_num() : 0];
        const int first = b * RENDER_BATCH_PIXELS, end = MR_MIN(lit, first + RENDER_BATCH_PIXELS);
        if (full)
            render_block_gathered(plan, model, state, kernel, vector, first, end, buf, full, NULL, NULL, 1, 0, 0);
        else if (diffuse && specular)
            render_block_gathered(plan, model, state, kernel, vector, first, end, buf, NULL, diffuse, specular, 0, 1,
                                  1);
        else if (diffuse)
            render_block_gathered(plan, model, state, kernel, vector, first, end, buf, NULL, diffuse, NULL, 0, 1, 0);
        else
            render_block_gathered(plan, model, state, kernel, vector, first, end, buf, NULL, NULL, specular, 0, 0, 1);
    }
    free(buffers);
    return 1;
}


/* render_core for one uniform material over point samples only, in fixed blocks of lit pixels (render_block). */
static void render_batched(const mr_render_plan *plan, const point_soa *soa, int threads, const mr_brdf_model *model,
                           const void *state, mr_brdf_batch_fn kernel, int vector, mr_image *full, mr_image *diffuse,
                           mr_image *specular) {
    const int lit = plan->lit_pixels, blocks = (lit + RENDER_BATCH_PIXELS - 1) / RENDER_BATCH_PIXELS;
#pragma omp parallel for schedule(dynamic, 1) num_threads(threads) if (threads > 1)
    for (int b = 0; b < blocks; b++) {
        const int first = b * RENDER_BATCH_PIXELS, end = MR_MIN(lit, first + RENDER_BATCH_PIXELS);
        if (full)
            render_block(plan, soa, model, state, kernel, vector, first, end, full, NULL, NULL, 1, 0, 0);
        else if (diffuse && specular)
            render_block(plan, soa, model, state, kernel, vector, first, end, NULL, diffuse, specular, 0, 1, 1);
        else if (diffuse)
            render_block(plan, soa, model, state, kernel, vector, first, end, NULL, diffuse, NULL, 0, 1, 0);
        else
            render_block(plan, soa, model, state, kernel, vector, first, end, NULL, NULL, specular, 0, 0, 1);
    }
}

/* Every render: `full` alone, or either or both of `diffuse` and `specular`, with one material for every hit
 * (count 1) or materials[hit's material]. Each lit pixel sums its hits' samples in plan order (the same for any
 * thread count); a textured material prepares the BRDF state per hit. One material without maps is evaluated in
 * batches (render_batched, render_gathered) unless `path` asks for the per-sample loop (render_internal.h). */
static mr_status render_core(const mr_render_plan *plan, int threads, const mr_material_binding *materials,
                             int count, mr_image *full, mr_image *diffuse, mr_image *specular, mr_render_path path) {
    mr_status status = check_target(plan, full, "output");
    if (status == MR_OK) status = check_target(plan, diffuse, "diffuse");
    if (status == MR_OK) status = check_target(plan, specular, "specular");
    if (status != MR_OK) return status;
    const int needed = mr_render_plan_material_count(plan);
    if (materials == NULL || count < 1 || (count != 1 && count < needed))
        return mr_fail(MR_ERR_INVALID_ARG, "render: %d materials given, the plan's mesh uses %d (give them all, or "
                       "one for every triangle)", materials == NULL ? 0 : count, needed);
    const int used = count == 1 ? 1 : needed;
    // One material (every render of the optimiser's loop) stays on the stack; a scene's materials go to the heap.
    material_state single, *states = used == 1 ? &single : malloc((size_t)used * sizeof *states);
    if (states == NULL) return mr_fail(MR_ERR_NOMEM, "render: out of memory for %d materials", used);
    for (int m = 0; m < used; m++) {
        status = material_state_init(&materials[m], m, &states[m]);
        if (status != MR_OK) {
            if (states != &single) free(states);
            return status;
        }
    }

    // The background is light that never met the material; it belongs to the full render only, and a
    // diffuse-only or specular-only render is black there, so diffuse + specular = full on the object.
    if (full) fill_unlit(plan, full, 1);
    if (diffuse) fill_unlit(plan, diffuse, 0);
    if (specular) fill_unlit(plan, specular, 0);

    if (threads <= 0) threads = plan->render_threads;
    // One material without maps over point samples alone (the fit scene, every render of the optimiser's loop):
    // batched, the model's eval_batch over the samples as structure of arrays.
    const size_t env_samples = plan->hits[plan->hit_count].env_begin;
    const size_t reflection_samples = plan->hits[plan->hit_count].reflection_begin;
    // With environment or reflection samples, or more point samples than RENDER_SOA_MAX_SAMPLES, batches are
    // gathered from the hits as the render goes.
    if (path != MR_RENDER_PATH_PER_SAMPLE && used == 1 && states[0].binding_count == 0) {
        const int vector = path == MR_RENDER_PATH_AUTO ? mr_brdf_batch_vector_default()
                                                       : path == MR_RENDER_PATH_BATCH_VECTOR;
        const int points = plan->hits[plan->hit_count].point_begin;
        const point_soa *soa = env_samples == 0 && reflection_samples == 0 && points <= RENDER_SOA_MAX_SAMPLES
                                   ? plan_point_soa(plan)
                                   : NULL;
        const mr_brdf_batch_fn kernel = plan->float_kernels ? mr_brdf_float_kernel(states[0].model) : NULL;
        if (soa != NULL) {
            render_batched(plan, soa, threads, states[0].model, states[0].shared.bytes, kernel, vector, full, diffuse,
                           specular);
            return MR_OK;
        }
        if (render_gathered(plan, threads, states[0].model, states[0].shared.bytes, kernel, vector, full, diffuse,
                            specular))
            return MR_OK;
    }

    const int lit = plan->lit_pixels;
    // Pixels cost from one BRDF evaluation (a point light) to N * edge_samples^2 (an environment on the
    // silhouette): small dynamic chunks keep both threads busy. The order inside a pixel is fixed.
#pragma omp parallel for schedule(dynamic, 64) num_threads(threads) if (threads > 1)
    for (int i = 0; i < lit; i++) {
        double sum_f[3] = {0.0, 0.0, 0.0}, sum_d[3] = {0.0, 0.0, 0.0}, sum_s[3] = {0.0, 0.0, 0.0};
        double *acc_f = full ? sum_f : NULL, *acc_d = diffuse ? sum_d : NULL, *acc_s = specular ? sum_s : NULL;
        mr_brdf_state local;
        for (int h = plan->hit_begin[i]; h < plan->hit_begin[i + 1]; h++) {
            const plan_hit *hit = &plan->hits[h];
            const material_state *ms = &states[used == 1 ? 0 : hit->material];
            const mr_brdf_model *model = ms->model;
            const void *state = ms->shared.bytes;
            if (ms->binding_count > 0) {
                double hit_values[MR_BRDF_MAX_VALUES];
                memcpy(hit_values, ms->values, (size_t)ms->value_count * sizeof *hit_values);
                for (int b = 0; b < ms->binding_count; b++)
                    mr_texture_sampler_read(&ms->bindings[b].sampler, hit->uv, hit->uv1,
                                         hit_values + ms->bindings[b].slot);
                model->prepare(model, hit_values, local.bytes);
                state = local.bytes;
            }
            for (int s = hit->point_begin; s < hit[1].point_begin; s++) {
                const point_sample *sample = &plan->point_samples[s];
                accumulate(model, state, hit->view, sample->light, sample->weight, acc_f, acc_d, acc_s);
            }
            for (size_t e = hit->env_begin; e < hit[1].env_begin; e++) {
                double light[3], weight[3];
                env_sample_of_hit(plan, h, e, light, weight);
                accumulate(model, state, hit->view, light, weight, acc_f, acc_d, acc_s);
            }
            for (size_t e = hit->reflection_begin; e < hit[1].reflection_begin; e++) {
                const reflection_sample *sample = &plan->reflection_samples[e];
                double light[3] = {sample->light[0], sample->light[1], sample->light[2]};
                double cos_share = light[2] * hit->env_share, weight[3];
                for (int c = 0; c < 3; c++) weight[c] = sample->weight[c] * cos_share;
                accumulate(model, state, hit->view, light, weight, acc_f, acc_d, acc_s);
            }
            if (acc_f && plan->emits)
                for (int c = 0; c < 3; c++) sum_f[c] += hit->emission[c];
        }
        size_t pixel = (size_t)plan->lit_pixel_index[i];
        if (full) {
            double uncovered = 1.0 - plan->coverage[pixel];
            for (int c = 0; c < 3; c++)
                full->pixels[pixel * 3 + c] = (float)(sum_f[c] + plan->scene.background[c] * uncovered);
        }
        for (int c = 0; c < 3; c++) {
            if (diffuse) diffuse->pixels[pixel * 3 + c] = (float)sum_d[c];
            if (specular) specular->pixels[pixel * 3 + c] = (float)sum_s[c];
        }
    }
    if (states != &single) free(states);
    return MR_OK;
}

/* The single-material calls as a one-material render. */
static mr_status render_one(const mr_render_plan *plan, int threads, const mr_brdf_model *model,
                            const double *values, const mr_param_textures *textures, mr_image *full,
                            mr_image *diffuse, mr_image *specular) {
    mr_material_binding material = {model, values, textures};
    return render_core(plan, threads, &material, 1, full, diffuse, specular, MR_RENDER_PATH_AUTO);
}

int mr_render_plan_material_count(const mr_render_plan *plan) {
    return plan->scene.shape.type == MR_SHAPE_MESH ? plan->mesh.material_count : 1;
}

mr_status mr_render_materials_into(const mr_render_plan *plan, const mr_material_binding *materials, int count,
                                   mr_component component, mr_image *image) {
    if (plan == NULL || materials == NULL || image == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "render: NULL plan, materials or image");
    switch (component) {
    case MR_COMPONENT_FULL: return render_core(plan, 0, materials, count, image, NULL, NULL, MR_RENDER_PATH_AUTO);
    case MR_COMPONENT_DIFFUSE: return render_core(plan, 0, materials, count, NULL, image, NULL, MR_RENDER_PATH_AUTO);
    case MR_COMPONENT_SPECULAR: return render_core(plan, 0, materials, count, NULL, NULL, image, MR_RENDER_PATH_AUTO);
    default: return mr_fail(MR_ERR_INVALID_ARG, "render: unknown component %d", (int)component);
    }
}

mr_status mr_render_materials(const mr_render_plan *plan, const mr_material_binding *materials, int count,
                              mr_component component, mr_image **out) {
    if (plan == NULL || out == NULL) return mr_fail(MR_ERR_INVALID_ARG, "render: NULL plan or output");
    mr_image *image = NULL;
    mr_status status = mr_image_create(plan->scene.width, plan->scene.height, 3, &image);
    if (status != MR_OK) return status;
    status = mr_render_materials_into(plan, materials, count, component, image);
    if (status != MR_OK) {
        mr_image_free(image);
        return status;
    }
    *out = image;
    return MR_OK;
}

static mr_status components_into(const mr_render_plan *plan, int threads, const mr_brdf_model *model,
                                  const double *values, const mr_param_textures *textures, mr_image *diffuse,
                                  mr_image *specular) {
    if (plan == NULL || model == NULL || values == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "render: NULL plan, model or values");
    if (diffuse == NULL && specular == NULL) return MR_OK;
    return render_one(plan, threads, model, values, textures, NULL, diffuse, specular);
}

mr_status mr_render_textured_components_into(const mr_render_plan *plan, const mr_brdf_model *model,
                                              const double *values, const mr_param_textures *textures,
                                              mr_image *diffuse, mr_image *specular) {
    return components_into(plan, 0, model, values, textures, diffuse, specular);
}

mr_status mr_render_components_into(const mr_render_plan *plan, const mr_brdf_model *model, const double *values,
                                    mr_image *diffuse, mr_image *specular) {
    return components_into(plan, 0, model, values, NULL, diffuse, specular);
}

mr_status mr_render_components_into_threads(const mr_render_plan *plan, int threads, const mr_brdf_model *model,
                                            const double *values, mr_image *diffuse, mr_image *specular) {
    return components_into(plan, threads, model, values, NULL, diffuse, specular);
}

static mr_status textured_into(const mr_render_plan *plan, int threads, const mr_brdf_model *model,
                               const double *values, const mr_param_textures *textures, mr_component component,
                               mr_image *image) {
    if (plan == NULL || model == NULL || values == NULL || image == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "render: NULL plan, model, values or image");
    switch (component) {
    case MR_COMPONENT_FULL: return render_one(plan, threads, model, values, textures, image, NULL, NULL);
    case MR_COMPONENT_DIFFUSE: return render_one(plan, threads, model, values, textures, NULL, image, NULL);
    case MR_COMPONENT_SPECULAR: return render_one(plan, threads, model, values, textures, NULL, NULL, image);
    default: return mr_fail(MR_ERR_INVALID_ARG, "render: unknown component %d", (int)component);
    }
}

mr_status mr_render_textured_into(const mr_render_plan *plan, const mr_brdf_model *model, const double *values,
                                  const mr_param_textures *textures, mr_component component, mr_image *image) {
    return textured_into(plan, 0, model, values, textures, component, image);
}

mr_status mr_render_into(const mr_render_plan *plan, const mr_brdf_model *model, const double *values,
                         mr_component component, mr_image *image) {
    return textured_into(plan, 0, model, values, NULL, component, image);
}

mr_status mr_render_into_threads(const mr_render_plan *plan, int threads, const mr_brdf_model *model,
                                 const double *values, mr_component component, mr_image *image) {
    return textured_into(plan, threads, model, values, NULL, component, image);
}

mr_status mr_render_textured(const mr_render_plan *plan, const mr_brdf_model *model, const double *values,
                             const mr_param_textures *textures, mr_component component, mr_image **out) {
    if (plan == NULL || out == NULL) return mr_fail(MR_ERR_INVALID_ARG, "render: NULL plan or output");
    mr_image *image = NULL;
    mr_status status = mr_image_create(plan->scene.width, plan->scene.height, 3, &image);
    if (status != MR_OK) return status;
    status = mr_render_textured_into(plan, model, values, textures, component, image);
    if (status != MR_OK) {
        mr_image_free(image);
        return status;
    }
    *out = image;
    return MR_OK;
}

mr_status mr_render(const mr_render_plan *plan, const mr_brdf_model *model, const double *values,
                    mr_component component, mr_image **out) {
    return mr_render_textured(plan, model, values, NULL, component, out);
}

mr_status mr_render_into_path(const mr_render_plan *plan, int threads, const mr_brdf_model *model,
                              const double *values, mr_component component, mr_image *image, mr_render_path path) {
    if (plan == NULL || model == NULL || values == NULL || image == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "render: NULL plan, model, values or image");
    mr_material_binding material = {model, values, NULL};
    switch (component) {
    case MR_COMPONENT_FULL: return render_core(plan, threads, &material, 1, image, NULL, NULL, path);
    case MR_COMPONENT_DIFFUSE: return render_core(plan, threads, &material, 1, NULL, image, NULL, path);
    case MR_COMPONENT_SPECULAR: return render_core(plan, threads, &material, 1, NULL, NULL, image, path);
    default: return mr_fail(MR_ERR_INVALID_ARG, "render: unknown component %d", (int)component);
    }
}

/* ---- parameter derivatives of a render (render.h, mr_render_derivatives_into) ---------------------------- */

int mr_render_plan_point_lit_only(const mr_render_plan *plan) {
    return plan != NULL && plan->hits[plan->hit_count].env_begin == 0 &&
           plan->hits[plan->hit_count].reflection_begin == 0;
}

mr_status mr_render_derivatives_into(const mr_render_plan *plan, int threads, const mr_brdf_model *model,
                                     const double *values, mr_component component, const int *slots, int count,
                                     mr_image *const *images) {
    if (plan == NULL || model == NULL || values == NULL || slots == NULL || images == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "render derivatives: NULL plan, model, values, slots or images");
    if (model->eval_grad == NULL)
        return mr_fail(MR_ERR_UNSUPPORTED, "render derivatives: model '%s' has no analytic derivatives", model->name);
    if (!mr_render_plan_point_lit_only(plan))
        return mr_fail(MR_ERR_UNSUPPORTED, "render derivatives: the plan has environment samples (point lights only)");
    if (mr_render_plan_material_count(plan) != 1)
        return mr_fail(MR_ERR_UNSUPPORTED, "render derivatives: the plan's mesh has several materials");
    if ((unsigned)component > MR_COMPONENT_SPECULAR)
        return mr_fail(MR_ERR_INVALID_ARG, "render derivatives: unknown component %d", (int)component);
    const int value_count = mr_brdf_value_count(model);
    if (count < 1 || count > MR_BRDF_MAX_VALUES)
        return mr_fail(MR_ERR_INVALID_ARG, "render derivatives: %d slots (1 to %d)", count, MR_BRDF_MAX_VALUES);
    for (int k = 0; k < count; k++) {
        if (slots[k] < 0 || slots[k] >= value_count)
            return mr_fail(MR_ERR_INVALID_ARG, "render derivatives: slot %d outside model '%s' (%d values)", slots[k],
                           model->name, value_count);
        if (images[k] == NULL) return mr_fail(MR_ERR_INVALID_ARG, "render derivatives: NULL image %d", k);
        mr_status status = check_target(plan, images[k], "derivative");
        if (status != MR_OK) return status;
        memset(images[k]->pixels, 0, (size_t)plan->scene.width * plan->scene.height * 3 * sizeof(float));
    }
    const int lit = plan->lit_pixels;
    if (threads <= 0) threads = plan->render_threads;
    // A model with prepared derivatives (brdf.h, grad_ops) differentiates the value-only part once here, for the
    // slots asked for only; each sample then carries `count` derivatives instead of all the model's. Repeated slots
    // (no caller of the library passes them) take eval_grad's path.
    const mr_brdf_grad_ops *ops = model->grad_ops;
    for (int k = 0; k < count && ops != NULL; k++)
        for (int l = 0; l < k; l++)
            if (slots[l] == slots[k]) ops = NULL;
    void *grad_state = NULL;
    if (ops != NULL) {
        grad_state = malloc(ops->state_bytes);
        if (grad_state == NULL)
            return mr_fail(MR_ERR_NOMEM, "render derivatives of model '%s': out of memory (%zu bytes of state)",
                           model->name, ops->state_bytes);
        ops->prepare(model, values, slots, count, grad_state);
        // The lobe's shape alone (what the fits ask for at every step) in batches, as a render of the specular part
        // with the derivative for f_r: the same sums in the same order (render_block), from the batched kernel's
        // numbers. Its diffuse part is zero, so the full image is the specular one and the diffuse one stays zero.
        const int points = plan->hits[plan->hit_count].point_begin;
        const point_soa *soa = ops->batchable != NULL && ops->batchable(grad_state) && points <= RENDER_SOA_MAX_SAMPLES
                                   ? plan_point_soa(plan)
                                   : NULL;
        if (soa != NULL) {
            if (component != MR_COMPONENT_DIFFUSE)
                render_batched(plan, soa, threads, model, grad_state, ops->eval_batch,
                               mr_brdf_batch_vector_default(), NULL, NULL, images[0]);
            free(grad_state);
            return MR_OK;
        }
    }
    // Each lit pixel sums its samples in plan order, as render_core does: the images do not depend on the thread
    // count. The background and the emission do not depend on any parameter.
#pragma omp parallel for schedule(dynamic, 64) num_threads(threads) if (threads > 1)
    for (int i = 0; i < lit; i++) {
        double sum[MR_BRDF_MAX_VALUES][3] = {{0.0}};
        double d_diffuse[MR_BRDF_MAX_VALUES * 3], d_specular[MR_BRDF_MAX_VALUES * 3];
        for (int h = plan->hit_begin[i]; h < plan->hit_begin[i + 1]; h++) {
            const plan_hit *hit = &plan->hits[h];
            for (int s = hit->point_begin; s < hit[1].point_begin; s++) {
                const point_sample *sample = &plan->point_samples[s];
                if (ops != NULL)
                    ops->eval(grad_state, hit->view, sample->light, d_diffuse, d_specular);
                else
                    model->eval_grad(model, values, hit->view, sample->light, d_diffuse, d_specular);
                for (int k = 0; k < count; k++)
                    for (int c = 0; c < 3; c++) {
                        const int at = (ops != NULL ? k : slots[k]) * 3 + c;
                        double d = component == MR_COMPONENT_DIFFUSE    ? d_diffuse[at]
                                   : component == MR_COMPONENT_SPECULAR ? d_specular[at]
                                                                        : d_diffuse[at] + d_specular[at];
                        sum[k][c] += d * sample->weight[c];
                    }
            }
        }
        const size_t pixel = (size_t)plan->lit_pixel_index[i];
        for (int k = 0; k < count; k++)
            for (int c = 0; c < 3; c++) images[k]->pixels[pixel * 3 + c] = (float)sum[k][c];
    }
    free(grad_state);
    return MR_OK;
}
