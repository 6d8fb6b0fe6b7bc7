/*
 * test_mesh.c — triangle meshes in the renderer (render.h, src/render/mesh.c): a mesh sphere against the analytic
 * one, the BVH against brute force, shadows, framing, generated normals and tangents, double- and single-sided
 * surfaces, several materials, texture sampling on meshes, normal/occlusion/emission maps. (Split from
 * test_render.c, which keeps the sphere, environment-light and highlight tests.)
 */
#include <math.h>
#include <omp.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "harness.h"
#include "matremap.h"
#include "render/mesh.h"
#include "render/render_internal.h"
#include "render/texture.h"
#include "render_support.h"

/* ---- triangle meshes ------------------------------------------------------------------------------------------ */

/* A mesh with its own arrays (the test's side of the borrowed mr_mesh). */
typedef struct test_mesh {
    mr_mesh mesh;
    float *positions, *normals, *uvs, *tangents;
    uint32_t *indices;
} test_mesh;

static void test_mesh_free(test_mesh *m) {
    free(m->positions);
    free(m->normals);
    free(m->uvs);
    free(m->tangents);
    free(m->indices);
    memset(m, 0, sizeof *m);
}

static void test_mesh_alloc(test_mesh *m, int vertices, int triangles) {
    memset(m, 0, sizeof *m);
    m->positions = calloc((size_t)vertices * 3, sizeof(float));
    m->normals = calloc((size_t)vertices * 3, sizeof(float));
    m->uvs = calloc((size_t)vertices * 2, sizeof(float));
    m->tangents = calloc((size_t)vertices * 4, sizeof(float));
    m->indices = calloc((size_t)triangles * 3, sizeof(uint32_t));
    m->mesh.vertex_count = vertices;
    m->mesh.triangle_count = triangles;
    m->mesh.positions = m->positions;
    m->mesh.indices = m->indices;
}

/* A unit UV sphere at the origin in the sphere's own texture layout (render.h): vertex (i, j) at v = i/stacks,
 * u = j/slices, theta = pi v, phi = 2 pi (u - 0.5), p = (sin theta sin phi, cos theta, sin theta cos phi);
 * exact normals (= p) and UVs; the seam and pole vertices are duplicated, pole rows are single triangles.
 * welded != 0: no UVs or normals, one vertex per pole and none duplicated on the seam (generated normals). */
static test_mesh uv_sphere(int stacks, int slices, int welded) {
    test_mesh m;
    int columns = welded ? slices : slices + 1;
    int vertices = welded ? (stacks - 1) * slices + 2 : (stacks + 1) * columns;
    test_mesh_alloc(&m, vertices, 2 * stacks * slices - 2 * slices);
    for (int i = 0; i <= stacks; i++)
        for (int j = 0; j < columns; j++) {
            int index = welded ? (i == 0 ? 0 : i == stacks ? vertices - 1 : 1 + (i - 1) * slices + j) : i * columns + j;
            if (welded && (i == 0 || i == stacks) && j > 0) continue;
            double theta = TEST_PI * i / stacks, phi = 2.0 * TEST_PI * ((double)j / slices - 0.5);
            double p[3] = {sin(theta) * sin(phi), cos(theta), sin(theta) * cos(phi)};
            if (i == 0 || i == stacks) p[0] = 0.0, p[2] = 0.0, p[1] = i == 0 ? 1.0 : -1.0;
            for (int k = 0; k < 3; k++) m.positions[3 * index + k] = m.normals[3 * index + k] = (float)p[k];
            m.uvs[2 * index] = (float)j / slices;
            m.uvs[2 * index + 1] = (float)i / stacks;
        }
    int t = 0;
    for (int i = 0; i < stacks; i++)
        for (int j = 0; j < slices; j++) {
            int jn = welded ? (j + 1) % slices : j + 1;
            uint32_t a, b, c, d; // a top-left, b bottom-left, c bottom-right, d top-right (seen from outside)
            if (welded) {
                a = i == 0 ? 0 : (uint32_t)(1 + (i - 1) * slices + j);
                d = i == 0 ? 0 : (uint32_t)(1 + (i - 1) * slices + jn);
                b = i + 1 == stacks ? (uint32_t)vertices - 1 : (uint32_t)(1 + i * slices + j);
                c = i + 1 == stacks ? (uint32_t)vertices - 1 : (uint32_t)(1 + i * slices + jn);
            } else {
                a = (uint32_t)(i * columns + j), d = (uint32_t)(i * columns + jn);
                b = (uint32_t)((i + 1) * columns + j), c = (uint32_t)((i + 1) * columns + jn);
            }
            if (i + 1 < stacks) m.indices[3 * t] = a, m.indices[3 * t + 1] = b, m.indices[3 * t + 2] = c, t++;
            if (i > 0) m.indices[3 * t] = a, m.indices[3 * t + 1] = c, m.indices[3 * t + 2] = d, t++;
        }
    if (!welded) {
        m.mesh.normals = m.normals;
        m.mesh.uvs = m.uvs;
    }
    return m;
}

/* Add an axis-aligned rectangle in the plane y = height, x and z in [lo, hi], facing +y (CCW seen from above),
 * as vertices 4q..4q+3 and triangles 2q, 2q+1; UVs: u along +x, v along +z (0..1). */
static void add_floor_quad(test_mesh *m, int q, double height, double lo, double hi) {
    const double corner[4][2] = {{lo, lo}, {lo, hi}, {hi, hi}, {hi, lo}};
    for (int k = 0; k < 4; k++) {
        float *p = m->positions + 3 * (4 * q + k);
        p[0] = (float)corner[k][0], p[1] = (float)height, p[2] = (float)corner[k][1];
        m->uvs[2 * (4 * q + k)] = corner[k][0] == lo ? 0.0f : 1.0f;
        m->uvs[2 * (4 * q + k) + 1] = corner[k][1] == lo ? 0.0f : 1.0f;
    }
    const uint32_t base = (uint32_t)(4 * q), tri[6] = {0, 1, 2, 0, 2, 3};
    for (int k = 0; k < 6; k++) m->indices[6 * q + k] = base + tri[k];
}

/* A scene showing `mesh` with the fit scene's camera and light (size x size). */
static mr_scene mesh_fit_scene(const test_mesh *m, int size, mr_fit_light light) {
    mr_scene scene = mr_scene_fit(&(mr_fit_scene_options){size, light, 0});
    scene.shape.type = MR_SHAPE_MESH;
    scene.shape.mesh = &m->mesh;
    return scene;
}

/* Max |a - b| over the pixels both objects cover fully (the silhouette's pixels are filtered only where the
 * corner test finds an edge, so a sub-pixel shift there can switch a pixel between 1 and 16 samples), relative
 * to the largest value of a; the RMSE over every pixel either image covers, relative to a's mean there. */
static void image_difference(const mr_image *a, const mr_image *b, const float *cover_a, const float *cover_b,
                             double *max_rel, double *rmse_rel) {
    double peak = 0.0, max_diff = 0.0, sum2 = 0.0, sum = 0.0;
    long count = 0;
    for (size_t i = 0; i < mr_image_value_count(a); i++) {
        peak = fmax(peak, a->pixels[i]);
        double d = fabs((double)a->pixels[i] - b->pixels[i]);
        if (cover_a[i / 3] == 1.0f && cover_b[i / 3] == 1.0f) max_diff = fmax(max_diff, d);
        if (a->pixels[i] > 0.0f || b->pixels[i] > 0.0f) sum2 += d * d, sum += a->pixels[i], count++;
    }
    *max_rel = max_diff / peak;
    *rmse_rel = count ? sqrt(sum2 / count) / (sum / count) : 0.0;
}

/* Render `model` at its defaults on the analytic sphere and on the mesh with the same scene; returns the
 * differences (image_difference). */
static void mesh_vs_sphere(const test_mesh *m, int size, const mr_light *light, const mr_brdf_model *model,
                           int edge_samples, double *max_rel, double *rmse_rel) {
    mr_scene sphere = mr_scene_fit(&(mr_fit_scene_options){size, MR_FIT_LIGHT_45, 0});
    sphere.highlight_samples = 1; // meshes sample pixel centres at highlights: compare like with like
    sphere.edge_samples = edge_samples;
    if (light != NULL) sphere.lights[0] = *light;
    mr_scene mesh = sphere;
    mesh.shape.type = MR_SHAPE_MESH;
    mesh.shape.mesh = &m->mesh;
    double values[MR_BRDF_MAX_VALUES];
    mr_brdf_default_values(model, values);
    mr_render_plan *ps = NULL, *pm = NULL;
    mr_image *is = NULL, *im = NULL;
    *max_rel = *rmse_rel = INFINITY;
    MR_CHECK_OK(mr_render_plan_create(&sphere, &ps));
    MR_CHECK_OK(mr_render_plan_create(&mesh, &pm));
    if (ps && pm) {
        MR_CHECK_OK(mr_render(ps, model, values, MR_COMPONENT_FULL, &is));
        MR_CHECK_OK(mr_render(pm, model, values, MR_COMPONENT_FULL, &im));
        MR_CHECK(mr_render_plan_shadow_ray_count(pm) == 0 && !mr_render_plan_self_occluding(pm));
    }
    if (is && im)
        image_difference(is, im, mr_render_plan_coverage(ps), mr_render_plan_coverage(pm), max_rel, rmse_rel);
    mr_image_free(is);
    mr_image_free(im);
    mr_render_plan_free(ps);
    mr_render_plan_free(pm);
}

MR_TEST(mesh_sphere_matches_the_analytic_sphere) {
    // A 256 x 512 UV sphere (261k triangles) with exact normals, and a welded one with generated normals,
    // against the analytic unit sphere: point light (Lambert, GGX) and environment light, silhouettes filtered.
    test_mesh fine = uv_sphere(256, 512, 0), welded = uv_sphere(128, 256, 1);
    mr_image *map = linear_map(32, 16);
    mr_light env = mr_light_environment(map, 1.0, 30.0, 256);
    const mr_brdf_model *lambert = mr_brdf_find("lambert");
    const mr_brdf_model *ggx = mr_brdf_find("ggx") ? mr_brdf_find("ggx") : lambert;
    struct {
        const test_mesh *mesh;
        const mr_light *light;
        const mr_brdf_model *model;
        double max_rel, rmse_rel; // thresholds: measured values (docs/rendering.md) with margin
    } cases[] = {
        {&fine, NULL, lambert, 1e-3, 4e-3},  // measured 2.6e-4, 2.2e-3
        {&fine, NULL, ggx, 1e-3, 4e-3},      // measured 3.4e-4, 1.6e-3
        {&fine, &env, lambert, 1e-3, 4e-3},  // measured 9.8e-5, 2.4e-3
        {&welded, NULL, lambert, 4e-3, 5e-3}, // measured 1.1e-3, 2.6e-3 (128 x 256, generated normals)
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        double max_rel, rmse_rel;
        mesh_vs_sphere(cases[k].mesh, 128, cases[k].light, cases[k].model, 0, &max_rel, &rmse_rel);
        printf("    case %zu (%s, %s, %s normals): max %.3g of peak, RMSE %.3g of mean\n", k, cases[k].model->name,
               cases[k].light ? "environment" : "point light", cases[k].mesh == &fine ? "given" : "generated",
               max_rel, rmse_rel);
        MR_CHECK_MSG(max_rel < cases[k].max_rel && rmse_rel < cases[k].rmse_rel, "case %zu: max %.3g, RMSE %.3g",
                     k, max_rel, rmse_rel);
    }
    // A coarse sphere must not pass: the test can tell a faceted mesh from the sphere.
    test_mesh coarse = uv_sphere(8, 16, 0);
    double max_rel, rmse_rel;
    mesh_vs_sphere(&coarse, 128, NULL, lambert, 0, &max_rel, &rmse_rel);
    printf("    coarse 8 x 16 sphere: max %.3g of peak, RMSE %.3g of mean\n", max_rel, rmse_rel);
    MR_CHECK_MSG(max_rel > 4e-3 && rmse_rel > 5e-3, "coarse: max %.3g, RMSE %.3g", max_rel, rmse_rel);
    test_mesh_free(&coarse);
    test_mesh_free(&fine);
    test_mesh_free(&welded);
    mr_image_free(map);
}

MR_TEST(mesh_bvh_agrees_with_brute_force) {
    // A sphere plus 400 random triangles (overlapping, thin, some degenerate): 5000 random rays, half of them
    // aimed at a random point of a random triangle. Hit or miss and the nearest t must agree exactly.
    test_mesh sphere = uv_sphere(24, 48, 0);
    const int extra = 400, nv = sphere.mesh.vertex_count + 3 * extra, nt = sphere.mesh.triangle_count + extra;
    test_mesh m;
    test_mesh_alloc(&m, nv, nt);
    memcpy(m.positions, sphere.positions, (size_t)sphere.mesh.vertex_count * 3 * sizeof(float));
    memcpy(m.indices, sphere.indices, (size_t)sphere.mesh.triangle_count * 3 * sizeof(uint32_t));
    uint64_t seed = 0x9E3779B97F4A7C15ull;
    for (int k = 0; k < extra; k++) {
        double c[3];
        for (int i = 0; i < 3; i++) c[i] = 4.0 * test_random(&seed) - 2.0;
        for (int v = 0; v < 3; v++) {
            int index = sphere.mesh.vertex_count + 3 * k + v;
            for (int i = 0; i < 3; i++)
                m.positions[3 * index + i] = (float)(c[i] + (k % 10 == 0 ? 0.0 : 0.6 * test_random(&seed) - 0.3));
            m.indices[3 * (sphere.mesh.triangle_count + k) + v] = (uint32_t)index;
        }
    }
    mr_scene scene = mesh_fit_scene(&m, 8, MR_FIT_LIGHT_45);
    scene.camera.position[2] = 10.0;
    mr_render_plan *plan = NULL;
    MR_CHECK_OK(mr_render_plan_create(&scene, &plan));
    int hits = 0, disagreements = 0;
    for (int r = 0; r < 5000 && plan != NULL; r++) {
        double origin[3], dir[3];
        for (int i = 0; i < 3; i++) origin[i] = 8.0 * test_random(&seed) - 4.0;
        if (r % 2 == 0) {
            for (int i = 0; i < 3; i++) dir[i] = 2.0 * test_random(&seed) - 1.0;
        } else {
            int f = (int)(test_random(&seed) * nt);
            double a = test_random(&seed), b = test_random(&seed);
            if (a + b > 1.0) a = 1.0 - a, b = 1.0 - b;
            for (int i = 0; i < 3; i++) {
                double p0 = m.positions[3 * m.indices[3 * f] + i], p1 = m.positions[3 * m.indices[3 * f + 1] + i];
                double p2 = m.positions[3 * m.indices[3 * f + 2] + i];
                dir[i] = p0 + a * (p1 - p0) + b * (p2 - p0) - origin[i];
            }
        }
        double t_bvh = -1.0, t_brute = -1.0;
        int f_bvh = -1, f_brute = -1;
        int h_bvh = mr_render_plan_trace_mesh(plan, origin, dir, 0, &t_bvh, &f_bvh);
        int h_brute = mr_render_plan_trace_mesh(plan, origin, dir, 1, &t_brute, &f_brute);
        hits += h_brute;
        if (h_bvh != h_brute || t_bvh != t_brute) {
            if (disagreements++ < 5)
                fprintf(stderr, "    ray %d: bvh %d t %.17g (triangle %d), brute force %d t %.17g (triangle %d)\n", r,
                        h_bvh, t_bvh, f_bvh, h_brute, t_brute, f_brute);
        }
    }
    MR_CHECK_MSG(disagreements == 0, "%d of 5000 rays disagree", disagreements);
    MR_CHECK_MSG(hits > 2500 && hits < 5000, "%d hits: the rays should both hit and miss", hits);
    mr_render_plan_free(plan);
    test_mesh_free(&m);
    test_mesh_free(&sphere);
}

/* A 2 x 2 floor (y = 0, x and z in [-2, 2]) and a 1 x 1 plate floating above it (y = 1, [-0.5, 0.5]),
 * both facing up: a mesh that shadows itself. */
static test_mesh floor_and_plate(void) {
    test_mesh m;
    test_mesh_alloc(&m, 8, 4);
    add_floor_quad(&m, 0, 0.0, -2.0, 2.0);
    add_floor_quad(&m, 1, 1.0, -0.5, 0.5);
    return m;
}

/* Unit direction of the ray through pixel centre (x + 0.5, y + 0.5), from render.h's camera model alone:
 * forward = target - position, right = forward x up, true up = right x forward. */
static void test_camera_ray(const mr_scene *s, double px, double py, double dir[3]) {
    const mr_camera *c = &s->camera;
    double f[3], r[3], u[3];
    for (int i = 0; i < 3; i++) f[i] = c->target[i] - c->position[i];
    double lf = sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
    for (int i = 0; i < 3; i++) f[i] /= lf;
    r[0] = f[1] * c->up[2] - f[2] * c->up[1], r[1] = f[2] * c->up[0] - f[0] * c->up[2];
    r[2] = f[0] * c->up[1] - f[1] * c->up[0];
    double lr = sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
    for (int i = 0; i < 3; i++) r[i] /= lr;
    u[0] = r[1] * f[2] - r[2] * f[1], u[1] = r[2] * f[0] - r[0] * f[2], u[2] = r[0] * f[1] - r[1] * f[0];
    double th = tan(c->fov_y_degrees * TEST_PI / 360.0), aspect = (double)s->width / s->height;
    double a = (2.0 * px / s->width - 1.0) * th * aspect, b = (1.0 - 2.0 * py / s->height) * th;
    for (int i = 0; i < 3; i++) dir[i] = f[i] + a * r[i] + b * u[i];
}

MR_TEST(mesh_convex_needs_no_shadow_rays_concave_gets_them) {
    // Convex: a sphere and a flat-shaded cube (24 vertices, normals per face); no shadow rays, under a point
    // light and an environment light. The floor with a plate above it is not convex: it traces them.
    test_mesh sphere = uv_sphere(16, 32, 0), cube;
    test_mesh_alloc(&cube, 24, 12);
    for (int face = 0; face < 6; face++) {
        int axis = face / 2;
        double sign = face % 2 ? -1.0 : 1.0;
        int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
        const double corner[4][2] = {{-1, -1}, {1, -1}, {1, 1}, {-1, 1}};
        for (int k = 0; k < 4; k++) {
            float *p = cube.positions + 3 * (4 * face + k), *n = cube.normals + 3 * (4 * face + k);
            p[axis] = (float)sign, n[axis] = (float)sign;
            p[a1] = (float)corner[k][0], p[a2] = (float)(corner[k][1] * sign); // CCW seen from outside
        }
        const uint32_t tri[6] = {0, 1, 2, 0, 2, 3};
        for (int k = 0; k < 6; k++) cube.indices[6 * face + k] = (uint32_t)(4 * face) + tri[k];
    }
    cube.mesh.normals = cube.normals;
    test_mesh plate = floor_and_plate();
    mr_image *map = constant_map(16, 8, 1, 1.0f);
    const test_mesh *meshes[3] = {&sphere, &cube, &plate};
    for (int k = 0; k < 3; k++)
        for (int with_env = 0; with_env < 2; with_env++) {
            mr_scene scene = mesh_fit_scene(meshes[k], 32, MR_FIT_LIGHT_45);
            scene.camera.position[1] = 3.0; // look down a little, so the floor shows
            if (with_env) scene.lights[scene.light_count++] = mr_light_environment(map, 1.0, 0.0, 64);
            mr_render_plan *plan = NULL;
            MR_CHECK_OK(mr_render_plan_create(&scene, &plan));
            if (plan == NULL) continue;
            long rays = mr_render_plan_shadow_ray_count(plan);
            MR_CHECK_MSG(mr_render_plan_object_pixel_count(plan) > 100, "mesh %d: object not seen", k);
            MR_CHECK_MSG(k < 2 ? rays == 0 : rays > 0, "mesh %d, env %d: %ld shadow rays", k, with_env, rays);
            MR_CHECK(mr_render_plan_self_occluding(plan) == (k == 2));
            mr_render_plan_free(plan);
        }
    mr_image_free(map);
    test_mesh_free(&sphere);
    test_mesh_free(&cube);
    test_mesh_free(&plate);
}

MR_TEST(mesh_shadow_of_a_plate_under_a_point_light) {
    // Point light at (0, 3, 0) above the plate: the plate's shadow on the floor is the square |x|, |z| < 0.75
    // (similar triangles: 0.5 * 3 / (3 - 1)). Floor pixels well inside it are black, floor pixels well outside
    // hold the Lambert answer rho/pi * I * cos / d^2 = rho/pi * I * 3 / d^3, pixel centres only.
    test_mesh m = floor_and_plate();
    mr_scene scene = mesh_fit_scene(&m, 65, MR_FIT_LIGHT_45);
    scene.edge_samples = 1;
    scene.camera = (mr_camera){{0.0, 4.0, 4.5}, {0.0, 0.0, 0.0}, {0.0, 1.0, 0.0}, 50.0};
    scene.lights[0].position[0] = 0.0, scene.lights[0].position[1] = 3.0, scene.lights[0].position[2] = 0.0;
    mr_render_plan *plan = NULL;
    mr_image *img = NULL;
    const double rho = 0.5, values[3] = {rho, rho, rho}, intensity = scene.lights[0].intensity[0];
    MR_CHECK_OK(mr_render_plan_create(&scene, &plan));
    if (plan) MR_CHECK_OK(mr_render(plan, mr_brdf_find("lambert"), values, MR_COMPONENT_FULL, &img));
    int dark = 0, lit = 0, wrong = 0;
    for (int y = 0; y < 65 && img != NULL; y++)
        for (int x = 0; x < 65; x++) {
            double dir[3];
            test_camera_ray(&scene, x + 0.5, y + 0.5, dir);
            const double *o = scene.camera.position;
            double tp = (1.0 - o[1]) / dir[1], px = o[0] + tp * dir[0], pz = o[2] + tp * dir[2];
            if (tp > 0.0 && fabs(px) <= 0.52 && fabs(pz) <= 0.52) continue; // the plate, or close to its edge
            double tf = -o[1] / dir[1], fx = o[0] + tf * dir[0], fz = o[2] + tf * dir[2];
            double reach = fmax(fabs(fx), fabs(fz));
            if (!(tf > 0.0) || reach > 1.95 || (reach > 0.72 && reach < 0.78)) continue;
            double value = mr_image_at(img, x, y)[0], expected = 0.0;
            if (reach < 0.75) {
                dark++;
            } else {
                double d = sqrt(fx * fx + 9.0 + fz * fz);
                expected = rho / TEST_PI * intensity * 3.0 / (d * d * d);
                lit++;
            }
            if (fabs(value - expected) > 1e-5 * fmax(expected, 1e-3) && wrong++ < 5)
                fprintf(stderr, "    pixel (%d, %d), floor (%.3f, %.3f): %.7g, expected %.7g\n", x, y, fx, fz, value,
                        expected);
        }
    MR_CHECK_MSG(wrong == 0, "%d floor pixels off the known answer", wrong);
    MR_CHECK_MSG(dark > 40 && lit > 400, "%d shadowed and %d lit floor pixels checked", dark, lit);
    mr_image_free(img);
    mr_render_plan_free(plan);
    test_mesh_free(&m);
}

MR_TEST(mesh_plate_occludes_a_constant_environment) {
    // Under a constant environment L, a Lambertian floor point directly below the plate's centre receives
    // E = pi L (1 - F), F the view factor of the 1 x 1 plate at height 1: four corner rectangles A = B = 0.5,
    // F = 4 / (2 pi) [A / sqrt(1 + A^2) atan(B / sqrt(1 + A^2)) + (A <-> B)] = 0.2394; radiance rho L (1 - F).
    test_mesh m = floor_and_plate();
    mr_image *map = constant_map(64, 32, 1, 1.0f);
    mr_scene scene = mesh_fit_scene(&m, 65, MR_FIT_LIGHT_45);
    scene.camera = (mr_camera){{0.0, 0.6, 5.0}, {0.0, 0.0, 0.0}, {0.0, 1.0, 0.0}, 30.0};
    scene.lights[0] = mr_light_environment(map, 1.0, 0.0, 4096);
    mr_render_plan *plan = NULL;
    mr_image *img = NULL;
    const double rho = 0.5, values[3] = {rho, rho, rho};
    MR_CHECK_OK(mr_render_plan_create(&scene, &plan));
    if (plan) MR_CHECK_OK(mr_render(plan, mr_brdf_find("lambert"), values, MR_COMPONENT_FULL, &img));
    double a = 0.5, s = sqrt(1.0 + a * a);
    double view_factor = 4.0 / (2.0 * TEST_PI) * 2.0 * (a / s * atan(a / s));
    if (img != NULL) {
        double centre = mr_image_at(img, 32, 32)[0], expected = rho * (1.0 - view_factor);
        printf("    under the plate: %.5f, expected %.5f (view factor %.4f), error %.2g\n", centre, expected,
               view_factor, fabs(centre / expected - 1.0));
        MR_CHECK_NEAR(centre, expected, 0.01 * expected);
        MR_CHECK(mr_render_plan_shadow_ray_count(plan) > 0);
    }
    mr_image_free(img);
    mr_render_plan_free(plan);
    mr_image_free(map);
    test_mesh_free(&m);
}

MR_TEST(mesh_renders_are_identical_for_one_and_two_threads) {
    // Plan (with shadow rays) and render, under one thread and under two: the same bytes.
    test_mesh m = floor_and_plate();
    mr_image *map = linear_map(32, 16);
    mr_scene scene = mesh_fit_scene(&m, 48, MR_FIT_LIGHT_45);
    scene.camera.position[1] = 3.0;
    scene.lights[1] = mr_light_environment(map, 1.0, 20.0, 128);
    scene.light_count = 2;
    const mr_brdf_model *model = mr_brdf_find("ggx") ? mr_brdf_find("ggx") : mr_brdf_find("lambert");
    double values[MR_BRDF_MAX_VALUES];
    mr_brdf_default_values(model, values);
    mr_image *img[2] = {NULL, NULL};
    long rays[2] = {-1, -2};
    for (int k = 0; k < 2; k++) {
        scene.threads = k + 1;
        mr_render_plan *plan = NULL;
        MR_CHECK_OK(mr_render_plan_create(&scene, &plan));
        if (plan) {
            MR_CHECK_OK(mr_render(plan, model, values, MR_COMPONENT_FULL, &img[k]));
            rays[k] = mr_render_plan_shadow_ray_count(plan);
        }
        mr_render_plan_free(plan);
    }
    MR_CHECK(rays[0] == rays[1] && rays[0] > 0);
    MR_CHECK(same_pixels(img[0], img[1]));
    mr_image_free(img[0]);
    mr_image_free(img[1]);
    mr_image_free(map);
    test_mesh_free(&m);
}

MR_TEST(mesh_textures_sample_the_mesh_uvs) {
    // A quad facing the camera, UV (0, 0) at its top-left and (1, 1) at its bottom-right; an albedo map whose
    // left half is red and right half blue paints the quad's left half red and its right half blue.
    test_mesh m;
    test_mesh_alloc(&m, 4, 2);
    const float pos[4][3] = {{-1, 1, 0}, {-1, -1, 0}, {1, -1, 0}, {1, 1, 0}};
    const float uv[4][2] = {{0, 0}, {0, 1}, {1, 1}, {1, 0}};
    for (int k = 0; k < 4; k++) {
        memcpy(m.positions + 3 * k, pos[k], sizeof pos[k]);
        memcpy(m.uvs + 2 * k, uv[k], sizeof uv[k]);
    }
    const uint32_t tri[6] = {0, 1, 2, 0, 2, 3};
    memcpy(m.indices, tri, sizeof tri);
    m.mesh.uvs = m.uvs;
    mr_image *map = constant_map(16, 8, 3, 0.0f);
    for (int j = 0; j < 8; j++)
        for (int i = 0; i < 16; i++) mr_image_at(map, i, j)[i < 8 ? 0 : 2] = 1.0f;
    mr_scene scene = mesh_fit_scene(&m, 64, MR_FIT_LIGHT_FRONTAL);
    const mr_brdf_model *lambert = mr_brdf_find("lambert");
    double values[3] = {0.5, 0.5, 0.5};
    mr_param_textures textures = {0};
    MR_CHECK_OK(mr_param_textures_set(&textures, lambert, "albedo", map, 0));
    mr_render_plan *plan = NULL;
    mr_image *img = NULL;
    MR_CHECK_OK(mr_render_plan_create(&scene, &plan));
    if (plan) MR_CHECK_OK(mr_render_textured(plan, lambert, values, &textures, MR_COMPONENT_FULL, &img));
    // The quad spans pixels 32 -+ 32 / (4 tan 17.5) = 32 -+ 25.4: probe 10 pixels either side of the centre.
    const int probes[4][2] = {{22, 20}, {22, 44}, {42, 20}, {42, 44}};
    for (int k = 0; k < 4 && img != NULL; k++) {
        const float *px = mr_image_at(img, probes[k][0], probes[k][1]);
        int left = k < 2;
        MR_CHECK_MSG(px[left ? 0 : 2] > 0.1f && px[left ? 2 : 0] == 0.0f && px[1] == 0.0f,
                     "pixel (%d, %d): %g %g %g, expected %s", probes[k][0], probes[k][1], px[0], px[1], px[2],
                     left ? "red" : "blue");
    }
    mr_image_free(img);
    mr_image_free(map);
    mr_render_plan_free(plan);
    test_mesh_free(&m);
}

MR_TEST(mesh_bad_meshes_are_rejected_with_messages) {
    test_mesh m = floor_and_plate();
    mr_scene scene = mesh_fit_scene(&m, 16, MR_FIT_LIGHT_45);
    mr_render_plan *plan = NULL;
    struct {
        const char *what, *message;
    } expect[] = {
        {"index", "triangle 1: index 8 out of range (8 vertices)"},
        {"nan", "vertex 5: position ("},
        {"zero", "0 triangles: expected at least 1"},
        {"degenerate", "all 4 triangles are degenerate"},
        {"tangent", "vertex 0: tangent"},
        {"normal", "vertex 3: normal (0, nan, 0) is not finite"},
        {"singular", "transform is singular"},
        {"null", "mesh shape without a mesh"},
    };
    for (size_t k = 0; k < sizeof expect / sizeof expect[0]; k++) {
        test_mesh bad = floor_and_plate();
        scene.shape.mesh = &bad.mesh;
        if (k == 0) bad.indices[4] = 8;
        if (k == 1) bad.positions[3 * 5 + 1] = NAN;
        if (k == 2) bad.mesh.triangle_count = 0;
        if (k == 3)
            for (int v = 0; v < 8; v++) bad.positions[3 * v] = 0.0f; // every vertex on the line x = 0, y
        if (k == 3)
            for (int v = 0; v < 8; v++) bad.positions[3 * v + 2] = 0.0f;
        if (k == 4) bad.mesh.tangents = bad.tangents; // w = 0.5
        if (k == 4)
            for (int v = 0; v < 8; v++) bad.tangents[4 * v + 3] = 0.5f;
        if (k == 5) {
            for (int v = 0; v < 8; v++) bad.normals[3 * v + 1] = v == 3 ? NAN : 1.0f;
            bad.mesh.normals = bad.normals;
        }
        if (k == 6) bad.mesh.has_transform = 1; // an all-zero matrix
        if (k == 6) bad.mesh.transform[15] = 1.0;
        if (k == 7) scene.shape.mesh = NULL;
        MR_CHECK(mr_render_plan_create(&scene, &plan) == MR_ERR_INVALID_ARG && plan == NULL);
        MR_CHECK_MSG(strstr(mr_last_error(), expect[k].message) != NULL, "%s: '%s'", expect[k].what, mr_last_error());
        test_mesh_free(&bad);
    }
    MR_CHECK(mr_mesh_validate(&m.mesh) == MR_OK);
    MR_CHECK(mr_mesh_validate(NULL) == MR_ERR_INVALID_ARG);
    test_mesh_free(&m);
}

MR_TEST(mesh_camera_framing_fits_the_bounding_sphere) {
    // The unit sphere mesh (its bounding sphere is the unit sphere: poles and equator points are vertices),
    // scaled by 2 and moved to (5, 0, 0): the camera looks at (5, 0, 0) from +z at 2 / sin(0.9 * 17.5 deg),
    // and the render shows the whole sphere with a margin.
    test_mesh m = uv_sphere(32, 64, 0);
    m.mesh.has_transform = 1;
    const double matrix[16] = {2, 0, 0, 0, 0, 2, 0, 0, 0, 0, 2, 0, 5, 0, 0, 1};
    memcpy(m.mesh.transform, matrix, sizeof matrix);
    mr_camera camera;
    MR_CHECK_OK(mr_camera_frame_mesh(&m.mesh, NULL, &camera));
    double distance = 2.0 / sin(0.9 * 17.5 * TEST_PI / 180.0);
    MR_CHECK_NEAR(camera.position[0], 5.0, 1e-6);
    MR_CHECK_NEAR(camera.position[2], distance, 1e-6);
    MR_CHECK_NEAR(camera.target[0], 5.0, 1e-6);
    MR_CHECK_NEAR(camera.fov_y_degrees, 35.0, 0.0);
    mr_frame_options wide = {64, 32, 0.0, {0.0, 1.0, 0.0}, 0.5};
    mr_camera above;
    MR_CHECK_OK(mr_camera_frame_mesh(&m.mesh, &wide, &above));
    MR_CHECK_NEAR(above.position[1], 2.0 / sin(0.5 * 17.5 * TEST_PI / 180.0), 1e-6);
    MR_CHECK(above.up[2] != 0.0);
    wide.fill = 2.0;
    MR_CHECK(mr_camera_frame_mesh(&m.mesh, &wide, &above) == MR_ERR_INVALID_ARG);
    mr_scene scene = mesh_fit_scene(&m, 64, MR_FIT_LIGHT_FRONTAL);
    scene.camera = camera;
    scene.lights[0].position[0] = 5.0, scene.lights[0].position[2] = 20.0;
    mr_render_plan *plan = NULL;
    MR_CHECK_OK(mr_render_plan_create(&scene, &plan));
    if (plan != NULL) {
        const float *coverage = mr_render_plan_coverage(plan);
        double border = 0.0, total = 0.0;
        for (int y = 0; y < 64; y++)
            for (int x = 0; x < 64; x++) {
                total += coverage[y * 64 + x];
                if (x < 2 || y < 2 || x > 61 || y > 61) border += coverage[y * 64 + x];
            }
        // The sphere spans 0.9 of the frame: a disc of radius about 0.9 * 32 pixels (perspective makes it a
        // little wider than the angular ratio), nothing on the border.
        MR_CHECK_MSG(border == 0.0, "coverage %g on the border", border);
        MR_CHECK_MSG(total > 2000.0 && total < 3000.0, "coverage %g pixels", total);
    }
    mr_render_plan_free(plan);
    test_mesh_free(&m);
}

/* White-box: the plan's world-space mesh (src/render/mesh.h), for what renders of isotropic models cannot show. */
MR_TEST(mesh_generated_normals_and_tangents_follow_the_surface) {
    // On a 32 x 64 UV sphere: generated normals within 3e-3 of the exact p (measured 1.5e-3; welded sphere:
    // the seam and pole duplicates of the unwelded one see one side only); with exact normals and UVs but no
    // tangents, generated tangents along +u, i.e.
    // dp/dphi = (cos phi, 0, -sin phi), and w = +1 (the bitangent, -dp/dv, points up); with u mirrored
    // (u -> 1 - u) the tangent turns round and w = -1. Hit frames are orthonormal, with the bitangent w n x t.
    test_mesh welded = uv_sphere(32, 64, 1), sphere = uv_sphere(32, 64, 0);
    mesh_world w;
    memset(&w, 0, sizeof w);
    MR_CHECK_OK(mr_mesh_world_build(&welded.mesh, 0, &w));
    double worst_normal = 0.0;
    for (int v = 0; v < w.vertex_count && w.normal != NULL; v++)
        for (int k = 0; k < 3; k++) worst_normal = fmax(worst_normal, fabs(w.normal[v][k] - w.position[v][k]));
    MR_CHECK_MSG(worst_normal < 3e-3, "generated normals off by %.3g", worst_normal);
    MR_CHECK(w.convex == 1 && w.tangent == NULL);
    mr_mesh_world_free(&w);
    for (int mirrored = 0; mirrored < 2; mirrored++) {
        if (mirrored)
            for (int v = 0; v < sphere.mesh.vertex_count; v++) sphere.uvs[2 * v] = 1.0f - sphere.uvs[2 * v];
        memset(&w, 0, sizeof w);
        MR_CHECK_OK(mr_mesh_world_build(&sphere.mesh, 0, &w));
        double worst = 0.0;
        int wrong_sign = 0;
        for (int v = 0; v < w.vertex_count && w.tangent != NULL; v++) {
            const double *p = w.position[v];
            double r = sqrt(p[0] * p[0] + p[2] * p[2]);
            // Skip the poles, where phi is undefined, and the seam, whose duplicated vertices see the triangles of
            // one side only (their tangent is the one-sided chord's, half a slice off, as MikkTSpace's would be).
            float u = sphere.uvs[2 * v];
            if (r < 0.2 || u == 0.0f || u == 1.0f) continue;
            double expected[3] = {p[2] / r, 0.0, -p[0] / r}, sign = mirrored ? -1.0 : 1.0;
            for (int k = 0; k < 3; k++) worst = fmax(worst, fabs(w.tangent[v][k] - sign * expected[k]));
            wrong_sign += w.tangent[v][3] != sign;
        }
        printf("    mirrored %d: tangents off by at most %.3g\n", mirrored, worst);
        // Measured 3.9e-7 (float positions).
        MR_CHECK_MSG(worst < 1e-5 && wrong_sign == 0, "mirrored %d: tangents off by %.3g, %d wrong w", mirrored,
                     worst, wrong_sign);
        mesh_hit hit = {0.0, 0.3, 0.2, 1000};
        double n[3], t[3], b[3], g[3], uv[2], uv1[2], nxt[3];
        mr_mesh_shade(&w, &hit, n, t, b, g, uv, uv1);
        nxt[0] = n[1] * t[2] - n[2] * t[1], nxt[1] = n[2] * t[0] - n[0] * t[2], nxt[2] = n[0] * t[1] - n[1] * t[0];
        double sign = mirrored ? -1.0 : 1.0;
        MR_CHECK_NEAR(n[0] * t[0] + n[1] * t[1] + n[2] * t[2], 0.0, 1e-12);
        MR_CHECK_NEAR(t[0] * t[0] + t[1] * t[1] + t[2] * t[2], 1.0, 1e-12);
        for (int k = 0; k < 3; k++) MR_CHECK_NEAR(b[k], sign * nxt[k], 1e-12);
        MR_CHECK(n[0] * g[0] + n[1] * g[1] + n[2] * g[2] > 0.99);
        mr_mesh_world_free(&w);
    }
    test_mesh_free(&welded);
    test_mesh_free(&sphere);
}

MR_TEST(mesh_double_sided_backs_are_shaded_as_fronts) {
    // A quad facing the camera, and the same quad wound the other way (its back towards the camera): single-
    // sided, the back is culled (not seen at all); double-sided, it renders like the front. A double-sided flat quad
    // needs no shadow rays; a double-sided closed sphere does (its inside could be seen, and shadowed).
    const float pos[4][3] = {{-1, 1, 0}, {-1, -1, 0}, {1, -1, 0}, {1, 1, 0}};
    const uint32_t front[6] = {0, 1, 2, 0, 2, 3}, back[6] = {0, 2, 1, 0, 3, 2};
    test_mesh m[2];
    for (int k = 0; k < 2; k++) {
        test_mesh_alloc(&m[k], 4, 2);
        memcpy(m[k].positions, pos, sizeof pos);
        memcpy(m[k].indices, k == 0 ? front : back, sizeof front);
    }
    const mr_brdf_model *lambert = mr_brdf_find("lambert");
    double values[3] = {0.5, 0.5, 0.5};
    mr_image *img[3] = {NULL, NULL, NULL};
    long rays[3] = {-1, -1, -1};
    int lit[3] = {-1, -1, -1}, covered[3] = {-1, -1, -1};
    for (int k = 0; k < 3; k++) { // front; back single-sided; back double-sided
        test_mesh *mesh = &m[k == 0 ? 0 : 1];
        mesh->mesh.double_sided = k == 2;
        mr_scene scene = mesh_fit_scene(mesh, 32, MR_FIT_LIGHT_45);
        mr_render_plan *plan = NULL;
        MR_CHECK_OK(mr_render_plan_create(&scene, &plan));
        if (plan == NULL) continue;
        MR_CHECK_OK(mr_render(plan, lambert, values, MR_COMPONENT_FULL, &img[k]));
        rays[k] = mr_render_plan_shadow_ray_count(plan);
        lit[k] = mr_render_plan_lit_pixel_count(plan);
        covered[k] = mr_render_plan_object_pixel_count(plan);
        mr_render_plan_free(plan);
    }
    MR_CHECK_MSG(lit[0] > 500 && lit[1] == 0 && lit[2] == lit[0], "lit pixels %d %d %d", lit[0], lit[1], lit[2]);
    MR_CHECK_MSG(covered[0] > 500 && covered[1] == 0 && covered[2] == covered[0], "covered pixels %d %d %d",
                 covered[0], covered[1], covered[2]);
    MR_CHECK(rays[0] == 0 && rays[1] == 0 && rays[2] == 0);
    double worst = 0.0;
    for (size_t i = 0; img[0] && img[2] && i < mr_image_value_count(img[0]); i++)
        worst = fmax(worst, fabs((double)img[0]->pixels[i] - img[2]->pixels[i]));
    MR_CHECK_MSG(img[0] && img[2] && worst <= 1e-7, "double-sided back differs from the front by %.3g", worst);
    for (int k = 0; k < 3; k++) mr_image_free(img[k]);
    test_mesh_free(&m[0]);
    test_mesh_free(&m[1]);
    test_mesh box = uv_sphere(4, 8, 0); // closed and convex
    box.mesh.double_sided = 1;
    mr_scene scene = mesh_fit_scene(&box, 16, MR_FIT_LIGHT_45);
    mr_render_plan *plan = NULL;
    MR_CHECK_OK(mr_render_plan_create(&scene, &plan));
    MR_CHECK(plan != NULL && mr_render_plan_self_occluding(plan) && mr_render_plan_shadow_ray_count(plan) > 0);
    mr_render_plan_free(plan);
    test_mesh_free(&box);
}

/* ---- texture sampling, several materials, surfaces ----------------------------------------------------------- */

MR_TEST(texture_wrap_modes_coordinate_sets_and_transform_known_answers) {
    // A 4 x 1 map holding 0, 1, 2, 3: texel i's centre is at u = (i + 0.5) / 4, so u = 0.125 reads 0 exactly.
    mr_image *map = constant_map(4, 1, 1, 0.0f);
    for (int i = 0; map != NULL && i < 4; i++) map->pixels[i] = (float)i;
    struct {
        mr_wrap wrap;
        double u, expected;
    } cases[] = {
        {MR_WRAP_REPEAT, 0.125, 0.0},  {MR_WRAP_REPEAT, 1.125, 0.0}, {MR_WRAP_REPEAT, 0.0, 1.5},
        {MR_WRAP_REPEAT, -0.125, 3.0}, {MR_WRAP_CLAMP, 0.0, 0.0},    {MR_WRAP_CLAMP, 2.0, 3.0},
        {MR_WRAP_CLAMP, 0.5, 1.5},     {MR_WRAP_MIRROR, 1.125, 3.0}, {MR_WRAP_MIRROR, -0.125, 0.0},
        {MR_WRAP_MIRROR, 1.0, 3.0},    {MR_WRAP_MIRROR, 2.125, 0.0}, {MR_WRAP_DEFAULT, 1.125, 0.0},
    };
    const double uv1[2] = {0.625, 0.5};
    for (size_t k = 0; map != NULL && k < sizeof cases / sizeof cases[0]; k++) {
        mr_texture_sampling sampling = {0};
        sampling.wrap_u = cases[k].wrap;
        texture_sampler sampler;
        mr_texture_sampler_init(&sampler, map, &sampling, 0, 1);
        double uv[2] = {cases[k].u, 0.5}, value = -1.0;
        mr_texture_sampler_read(&sampler, uv, uv1, &value);
        MR_CHECK_MSG(value == cases[k].expected, "wrap %d at u = %g: %g, expected %g", (int)cases[k].wrap,
                     cases[k].u, value, cases[k].expected);
    }
    // The v axis: the default clamps (a 1 x 4 map would tell; here every row is the same, so v never matters).
    // TEXCOORD_1 and KHR_texture_transform: u' = 0.25 + 0.5 u reads texel 1 at u = 0.25; a quarter turn maps
    // (u, v) to (v, -u), so (0.3, 0.625) reads u' = 0.625 (texel 2).
    mr_texture_sampling second = {0}, scaled = {0}, turned = {0};
    second.texcoord = 1;
    scaled.has_transform = 1, scaled.offset[0] = 0.25, scaled.scale[0] = 0.5, scaled.scale[1] = 1.0;
    turned.has_transform = 1, turned.rotation = 0.5 * 3.14159265358979323846, turned.scale[0] = turned.scale[1] = 1;
    const struct {
        const mr_texture_sampling *sampling;
        double u, v, expected;
    } transformed[] = {{&second, 0.0, 0.0, 2.0}, {&scaled, 0.25, 0.0, 1.0}, {&turned, 0.3, 0.625, 2.0}};
    for (size_t k = 0; map != NULL && k < 3; k++) {
        texture_sampler sampler;
        mr_texture_sampler_init(&sampler, map, transformed[k].sampling, 0, 1);
        double uv[2] = {transformed[k].u, transformed[k].v}, value = -1.0;
        mr_texture_sampler_read(&sampler, uv, uv1, &value);
        MR_CHECK_MSG(fabs(value - transformed[k].expected) < 1e-12, "case %zu: %g, expected %g", k, value,
                     transformed[k].expected);
    }
    mr_texture_sampling bad = {0};
    bad.wrap_u = (mr_wrap)7;
    MR_CHECK(mr_texture_sampling_validate(&bad, "t") == MR_ERR_INVALID_ARG);
    bad.wrap_u = MR_WRAP_REPEAT, bad.texcoord = 2;
    MR_CHECK(mr_texture_sampling_validate(&bad, "t") == MR_ERR_INVALID_ARG &&
             strstr(mr_last_error(), "coordinate set 2") != NULL);
    bad.texcoord = 0, bad.has_transform = 1, bad.rotation = NAN;
    MR_CHECK(mr_texture_sampling_validate(&bad, "t") == MR_ERR_INVALID_ARG);
    // A parameter map with a bad sampling is refused by the render, naming it.
    const mr_brdf_model *lambert = mr_brdf_find("lambert");
    double values[3] = {0.5, 0.5, 0.5};
    mr_param_textures textures = {0};
    MR_CHECK_OK(mr_param_textures_set(&textures, lambert, "albedo", map, 0));
    textures.sampling[0].texcoord = 3;
    mr_render_plan *plan = NULL;
    mr_image *img = NULL;
    mr_scene scene = mr_scene_fit(&(mr_fit_scene_options){16, MR_FIT_LIGHT_45, 0});
    MR_CHECK_OK(mr_render_plan_create(&scene, &plan));
    MR_CHECK(plan && mr_render_textured(plan, lambert, values, &textures, MR_COMPONENT_FULL, &img) ==
                         MR_ERR_INVALID_ARG && img == NULL);
    mr_render_plan_free(plan);
    mr_image_free(map);
}

/* A quad in the plane z = `z` spanning [-1, 1]^2, UV (0, 0) at its top-left, facing +z (the fit camera) or, with
 * facing_away, wound the other way; its triangles are 2q and 2q + 1 of m (lower-left, then upper-right). */
static void put_quad(test_mesh *m, int q, float z, int facing_away) {
    const float pos[4][3] = {{-1, 1, 0}, {-1, -1, 0}, {1, -1, 0}, {1, 1, 0}};
    const float uv[4][2] = {{0, 0}, {0, 1}, {1, 1}, {1, 0}};
    for (int k = 0; k < 4; k++) {
        memcpy(m->positions + 3 * (4 * q + k), pos[k], sizeof pos[k]);
        m->positions[3 * (4 * q + k) + 2] = z;
        memcpy(m->uvs + 2 * (4 * q + k), uv[k], sizeof uv[k]);
    }
    const uint32_t front[6] = {0, 1, 2, 0, 2, 3}, back[6] = {0, 2, 1, 0, 3, 2};
    for (int k = 0; k < 6; k++) m->indices[6 * q + k] = (uint32_t)(4 * q) + (facing_away ? back : front)[k];
}

MR_TEST(mesh_materials_shade_their_own_triangles) {
    // One quad, its lower-left triangle material 0 (red Lambert), its upper-right one material 1 (blue Phong).
    test_mesh m;
    test_mesh_alloc(&m, 4, 2);
    put_quad(&m, 0, 0.0f, 0);
    const uint16_t materials[2] = {0, 1};
    m.mesh.material_count = 2;
    m.mesh.triangle_materials = materials;
    mr_scene scene = mesh_fit_scene(&m, 64, MR_FIT_LIGHT_FRONTAL);
    const mr_brdf_model *lambert = mr_brdf_find("lambert"), *phong = mr_brdf_find("phong");
    double red[3] = {0.8, 0.0, 0.0}, blue[MR_BRDF_MAX_VALUES];
    mr_brdf_default_values(phong, blue);
    MR_CHECK(mr_brdf_param_index(phong, "diffuse") == 0); // an RGB albedo in values 0-2
    blue[0] = blue[1] = 0.0, blue[2] = 0.8;
    mr_material_binding bindings[3] = {{lambert, red, NULL}, {phong, blue, NULL}, {lambert, red, NULL}};
    mr_render_plan *plan = NULL;
    mr_image *img = NULL, *one = NULL, *single = NULL;
    MR_CHECK_OK(mr_render_plan_create(&scene, &plan));
    if (plan != NULL) {
        MR_CHECK(mr_render_plan_material_count(plan) == 2);
        MR_CHECK_OK(mr_render_materials(plan, bindings, 2, MR_COMPONENT_FULL, &img));
        MR_CHECK_OK(mr_render_materials(plan, bindings, 1, MR_COMPONENT_FULL, &one));
        MR_CHECK_OK(mr_render(plan, lambert, red, MR_COMPONENT_FULL, &single));
        mr_image *extra = NULL; // more materials than the mesh uses: the extra ones are unused
        MR_CHECK_OK(mr_render_materials(plan, bindings, 3, MR_COMPONENT_FULL, &extra));
        MR_CHECK(same_pixels(img, extra));
        mr_image_free(extra);
        MR_CHECK(mr_render_materials(plan, bindings, 0, MR_COMPONENT_FULL, &extra) == MR_ERR_INVALID_ARG);
        MR_CHECK(mr_render_materials(plan, NULL, 2, MR_COMPONENT_FULL, &extra) == MR_ERR_INVALID_ARG);
    }
    // Count 1 is one material for every triangle, exactly what mr_render gives.
    MR_CHECK(same_pixels(one, single));
    for (int k = 0; img != NULL && k < 2; k++) {
        const float *px = mr_image_at(img, k == 0 ? 20 : 44, k == 0 ? 44 : 20); // lower-left, upper-right
        MR_CHECK_MSG(k == 0 ? (px[0] > 0.05f && px[2] == 0.0f) : (px[2] > px[0] + 0.1f && px[0] == px[1]),
                     "triangle %d: %g %g %g", k, px[0], px[1], px[2]);
    }
    mr_image_free(img);
    mr_image_free(one);
    mr_image_free(single);
    mr_render_plan_free(plan);
    // A triangle naming a material the mesh does not have is refused.
    const uint16_t wrong[2] = {0, 5};
    m.mesh.triangle_materials = wrong;
    MR_CHECK(mr_render_plan_create(&scene, &plan) == MR_ERR_INVALID_ARG &&
             strstr(mr_last_error(), "triangle 1: material 5 out of range") != NULL);
    test_mesh_free(&m);
}

MR_TEST(mesh_single_sided_backs_are_culled_double_sided_ones_seen) {
    // A quad at z = 0.5 with its back to the camera (material 0, emitting red) in front of one at z = 0 facing
    // it (material 1, emitting blue). Single-sided, the front quad is culled and the centre pixel is blue;
    // double-sided, it is red. Black BRDFs: only emission shows, so its shadow on the back quad does not matter.
    test_mesh m;
    test_mesh_alloc(&m, 8, 4);
    put_quad(&m, 0, 0.5f, 1);
    put_quad(&m, 1, 0.0f, 0);
    const uint16_t materials[4] = {0, 0, 1, 1};
    mr_surface surfaces[2];
    memset(surfaces, 0, sizeof surfaces);
    surfaces[0].emission[0] = 1.0, surfaces[1].emission[2] = 1.0;
    m.mesh.material_count = 2;
    m.mesh.triangle_materials = materials;
    m.mesh.surfaces = surfaces;
    const mr_brdf_model *lambert = mr_brdf_find("lambert");
    double black[3] = {0.0, 0.0, 0.0};
    for (int sided = 0; sided < 2; sided++) {
        surfaces[0].double_sided = sided;
        mr_scene scene = mesh_fit_scene(&m, 32, MR_FIT_LIGHT_45);
        mr_render_plan *plan = NULL;
        mr_image *img = NULL;
        MR_CHECK_OK(mr_render_plan_create(&scene, &plan));
        if (plan) MR_CHECK_OK(mr_render(plan, lambert, black, MR_COMPONENT_FULL, &img));
        const float *px = img ? mr_image_at(img, 16, 16) : (const float[3]){0, 0, 0};
        MR_CHECK_MSG(sided ? px[0] == 1.0f && px[2] == 0.0f : px[0] == 0.0f && px[2] == 1.0f,
                     "double-sided %d: centre %g %g %g", sided, px[0], px[1], px[2]);
        mr_image_free(img);
        mr_render_plan_free(plan);
    }
    test_mesh_free(&m);
}

/* Render the quad (put_quad, UVs, generated tangents: +x, bitangent +y) with `surface` under the frontal
 * light (or `light`), Lambert albedo 0.5 (or black), 64^2. */
static mr_image *render_surface_quad(const mr_surface *surface, const mr_light *light, int black,
                                     mr_component component) {
    test_mesh m;
    test_mesh_alloc(&m, 4, 2);
    put_quad(&m, 0, 0.0f, 0);
    m.mesh.uvs = m.uvs;
    m.mesh.surfaces = surface;
    mr_scene scene = mesh_fit_scene(&m, 64, MR_FIT_LIGHT_FRONTAL);
    if (light != NULL) scene.lights[0] = *light;
    const mr_brdf_model *lambert = mr_brdf_find("lambert");
    double values[3] = {0.5, 0.5, 0.5};
    if (black) values[0] = values[1] = values[2] = 0.0;
    mr_render_plan *plan = NULL;
    mr_image *img = NULL; // NULL on failure (the callers expect some): mr_last_error() says why
    if (mr_render_plan_create(&scene, &plan) == MR_OK) mr_render(plan, lambert, values, component, &img);
    mr_render_plan_free(plan);
    test_mesh_free(&m);
    return img;
}

/* Largest |a - r b| over the pixels, relative to a's peak. */
static double scaled_difference(const mr_image *a, const mr_image *b, double r) {
    double peak = 0.0, worst = 0.0;
    for (size_t i = 0; a && b && i < mr_image_value_count(a); i++) {
        peak = fmax(peak, fabs(a->pixels[i]));
        worst = fmax(worst, fabs(a->pixels[i] - r * b->pixels[i]));
    }
    return a && b && peak > 0.0 ? worst / peak : INFINITY;
}

MR_TEST(mesh_surfaces_normal_occlusion_and_emission_known_answers) {
    mr_surface plain;
    memset(&plain, 0, sizeof plain);
    mr_image *base = render_surface_quad(&plain, NULL, 0, MR_COMPONENT_FULL);
    mr_image *nothing = render_surface_quad(NULL, NULL, 0, MR_COMPONENT_FULL);
    MR_CHECK(same_pixels(base, nothing)); // a surface without maps or emission changes nothing
    mr_image_free(nothing);

    // A flat normal map (0.5, 0.5, 1) renders like none; one tilted 30 degrees towards the tangent (+x) dims the
    // centre pixel, lit head-on by the frontal light, to cos 30 degrees (Lambert).
    const double tilt = 30.0 * 3.14159265358979323846 / 180.0;
    const float flat_texel[3] = {0.5f, 0.5f, 1.0f};
    const float tilted_texel[3] = {(float)(0.5 * sin(tilt) + 0.5), 0.5f, (float)(0.5 * cos(tilt) + 0.5)};
    mr_image *flat = constant_map(4, 4, 3, 0.0f), *tilted = constant_map(4, 4, 3, 0.0f);
    for (int i = 0; flat && tilted && i < 16; i++)
        for (int c = 0; c < 3; c++) {
            flat->pixels[3 * i + c] = flat_texel[c];
            tilted->pixels[3 * i + c] = tilted_texel[c];
        }
    mr_surface bumpy = plain;
    bumpy.normal_map = flat;
    bumpy.normal_scale = 1.0;
    mr_image *img = render_surface_quad(&bumpy, NULL, 0, MR_COMPONENT_FULL);
    MR_CHECK_MSG(scaled_difference(base, img, 1.0) < 1e-6, "flat normal map: %.3g", scaled_difference(base, img, 1.0));
    mr_image_free(img);
    bumpy.normal_map = tilted;
    img = render_surface_quad(&bumpy, NULL, 0, MR_COMPONENT_FULL);
    if (img && base) { // the four pixels round the centre: their offsets from the axis cancel to first order
        double tilted_sum = 0.0, base_sum = 0.0;
        for (int k = 0; k < 4; k++) {
            tilted_sum += mr_image_at(img, 31 + k % 2, 31 + k / 2)[1];
            base_sum += mr_image_at(base, 31 + k % 2, 31 + k / 2)[1];
        }
        double ratio = tilted_sum / base_sum;
        printf("    tilted normal map: centre ratio %.5f (cos 30 = %.5f)\n", ratio, cos(tilt));
        MR_CHECK_NEAR(ratio, cos(tilt), 2e-4);
    }
    mr_image_free(img);
    bumpy.normal_scale = 0.0; // scale 0 flattens any map
    img = render_surface_quad(&bumpy, NULL, 0, MR_COMPONENT_FULL);
    MR_CHECK(scaled_difference(base, img, 1.0) < 1e-6);
    mr_image_free(img);

    // Occlusion scales the environment light only: ao 0.25 at strength 1 -> 0.25, at strength 0.5 -> 0.625;
    // under the point light it changes nothing.
    mr_image *sky = constant_map(8, 4, 3, 1.0f), *ao = constant_map(4, 4, 1, 0.25f);
    mr_light env = mr_light_environment(sky, 1.0, 0.0, 64);
    mr_image *env_base = render_surface_quad(&plain, &env, 0, MR_COMPONENT_FULL);
    mr_surface occluded = plain;
    occluded.occlusion_map = ao;
    const double strengths[2] = {1.0, 0.5}, expected[2] = {0.25, 0.625};
    for (int k = 0; k < 2; k++) {
        occluded.occlusion_strength = strengths[k];
        img = render_surface_quad(&occluded, &env, 0, MR_COMPONENT_FULL);
        MR_CHECK_MSG(scaled_difference(img, env_base, expected[k]) < 1e-6, "strength %g: %.3g", strengths[k],
                     scaled_difference(img, env_base, expected[k]));
        mr_image_free(img);
    }
    img = render_surface_quad(&occluded, NULL, 0, MR_COMPONENT_FULL);
    MR_CHECK(same_pixels(img, base));
    mr_image_free(img);

    // Emission adds its radiance to full renders, lit or not (the light behind the quad reaches nothing), times
    // the emissive map; component renders leave it out.
    mr_light behind = mr_scene_fit(NULL).lights[0];
    behind.position[0] = behind.position[1] = 0.0, behind.position[2] = -3.0;
    mr_surface glowing = plain;
    glowing.emission[0] = 0.2, glowing.emission[1] = 0.4, glowing.emission[2] = 0.6;
    mr_image *half = constant_map(2, 2, 1, 0.5f);
    for (int k = 0; k < 3; k++) {
        glowing.emissive_map = k == 1 ? half : NULL;
        img = render_surface_quad(&glowing, &behind, 1, k == 2 ? MR_COMPONENT_DIFFUSE : MR_COMPONENT_FULL);
        const float *px = img ? mr_image_at(img, 32, 32) : (const float[3]){-1, -1, -1};
        double factor = k == 0 ? 1.0 : (k == 1 ? 0.5 : 0.0);
        for (int c = 0; c < 3; c++)
            MR_CHECK_MSG(px[c] == (float)(glowing.emission[c] * factor), "case %d channel %d: %g", k, c, px[c]);
        mr_image_free(img);
    }

    // Bad surfaces are refused, naming the material and the map.
    mr_surface bad = plain;
    bad.normal_map = ao; // one channel
    img = render_surface_quad(&bad, NULL, 0, MR_COMPONENT_FULL);
    MR_CHECK(img == NULL && strstr(mr_last_error(), "material 0: normal map") != NULL);
    bad = plain;
    bad.emission[1] = -1.0;
    img = render_surface_quad(&bad, NULL, 0, MR_COMPONENT_FULL);
    MR_CHECK(img == NULL && strstr(mr_last_error(), "emission") != NULL);
    mr_image_free(base);
    mr_image_free(env_base);
    mr_image_free(flat);
    mr_image_free(tilted);
    mr_image_free(sky);
    mr_image_free(ao);
    mr_image_free(half);
}

MR_TEST(mesh_zero_normals_and_tangents_are_generated_per_vertex) {
    // Primitives merged into one mesh may carry normals and tangents for some vertices only: a zero normal and a
    // w = 0 tangent ask for generated ones. All zero = none given; the first half given keeps its own.
    test_mesh m = uv_sphere(8, 16, 0);
    m.mesh.uvs = m.uvs;
    mesh_world generated, zeros, half;
    memset(&generated, 0, sizeof generated);
    memset(&zeros, 0, sizeof zeros);
    memset(&half, 0, sizeof half);
    m.mesh.normals = NULL;
    MR_CHECK_OK(mr_mesh_world_build(&m.mesh, 0, &generated));
    float *given = m.normals;
    float *none = calloc((size_t)m.mesh.vertex_count * 3, sizeof(float));
    float *no_tangents = calloc((size_t)m.mesh.vertex_count * 4, sizeof(float));
    m.mesh.normals = none;
    m.mesh.tangents = no_tangents;
    MR_CHECK_OK(mr_mesh_world_build(&m.mesh, 0, &zeros));
    const int nv = m.mesh.vertex_count;
    for (int v = nv / 2; v < nv; v++) given[3 * v] = given[3 * v + 1] = given[3 * v + 2] = 0.0f;
    m.mesh.normals = given;
    MR_CHECK_OK(mr_mesh_world_build(&m.mesh, 0, &half));
    int same = 1, kept = 1;
    for (int v = 0; v < nv && generated.normal && zeros.normal && half.normal; v++)
        for (int k = 0; k < 3; k++) {
            same &= zeros.normal[v][k] == generated.normal[v][k];
            if (k < 3 && v < nv / 2) kept &= fabs(half.normal[v][k] - given[3 * v + k]) < 1e-6;
            if (v >= nv / 2) same &= half.normal[v][k] == generated.normal[v][k];
        }
    for (int v = 0; v < nv && generated.tangent && zeros.tangent; v++)
        for (int k = 0; k < 4; k++) same &= zeros.tangent[v][k] == generated.tangent[v][k];
    MR_CHECK(same && kept);
    mr_mesh_world_free(&generated);
    mr_mesh_world_free(&zeros);
    mr_mesh_world_free(&half);
    free(none);
    free(no_tangents);
    test_mesh_free(&m);
}

MR_TEST(mesh_single_sided_backs_let_light_through) {
    // The floor and plate under a point light above them, the plate turned upside down: single-sided, the camera
    // above and the light both see its back, so it is culled for both and the render is the floor's alone (no
    // shadow); double-sided, it is seen and casts its shadow.
    test_mesh floor_only = floor_and_plate(), flipped = floor_and_plate();
    floor_only.mesh.triangle_count = 2;
    const uint32_t turned[6] = {4, 6, 5, 4, 7, 6};
    memcpy(flipped.indices + 6, turned, sizeof turned);
    mr_image *img[3] = {NULL, NULL, NULL};
    long rays[3] = {0, 0, 0};
    const double values[3] = {0.5, 0.5, 0.5};
    for (int k = 0; k < 3; k++) { // floor alone; flipped single-sided plate; flipped double-sided plate
        test_mesh *m = k == 0 ? &floor_only : &flipped;
        m->mesh.double_sided = k == 2;
        mr_scene scene = mesh_fit_scene(m, 48, MR_FIT_LIGHT_45);
        scene.camera = (mr_camera){{0.0, 4.0, 4.5}, {0.0, 0.0, 0.0}, {0.0, 1.0, 0.0}, 50.0};
        scene.lights[0].position[0] = 0.0, scene.lights[0].position[1] = 3.0, scene.lights[0].position[2] = 0.0;
        mr_render_plan *plan = NULL;
        MR_CHECK_OK(mr_render_plan_create(&scene, &plan));
        if (plan) MR_CHECK_OK(mr_render(plan, mr_brdf_find("lambert"), values, MR_COMPONENT_FULL, &img[k]));
        if (plan) rays[k] = mr_render_plan_shadow_ray_count(plan);
        mr_render_plan_free(plan);
    }
    MR_CHECK_MSG(rays[0] == 0 && rays[1] > 0 && rays[2] > 0, "shadow rays %ld %ld %ld", rays[0], rays[1], rays[2]);
    MR_CHECK(same_pixels(img[0], img[1]));
    MR_CHECK(img[2] != NULL && !same_pixels(img[0], img[2]));
    for (int k = 0; k < 3; k++) mr_image_free(img[k]);
    test_mesh_free(&floor_only);
    test_mesh_free(&flipped);
}

/* mr_mesh_corner_angle, the weight of a triangle's normal at a corner (the renderer's and the OBJ reader's). */
MR_TEST(mesh_corner_angle_known_answers) {
    const double o[3] = {0, 0, 0}, x[3] = {2, 0, 0}, y[3] = {0, 3, 0}, xy[3] = {1, 1, 0}, pi = acos(-1.0);
    MR_CHECK_NEAR(mr_mesh_corner_angle(o, x, y), pi / 2, 1e-15);
    MR_CHECK_NEAR(mr_mesh_corner_angle(o, x, xy), pi / 4, 1e-15);
    MR_CHECK(mr_mesh_corner_angle(o, x, x) == 0.0); /* degenerate: no area, no weight */
    MR_CHECK(mr_mesh_corner_angle(o, o, y) == 0.0);
    const double angles = mr_mesh_corner_angle(o, x, y) + mr_mesh_corner_angle(x, y, o) + mr_mesh_corner_angle(y, o, x);
    MR_CHECK_NEAR(angles, pi, 1e-14);
}

MR_TEST_MAIN(MR_TEST_ENTRY(mesh_sphere_matches_the_analytic_sphere), MR_TEST_ENTRY(mesh_corner_angle_known_answers),
             MR_TEST_ENTRY(mesh_bvh_agrees_with_brute_force),
             MR_TEST_ENTRY(mesh_convex_needs_no_shadow_rays_concave_gets_them),
             MR_TEST_ENTRY(mesh_shadow_of_a_plate_under_a_point_light),
             MR_TEST_ENTRY(mesh_plate_occludes_a_constant_environment),
             MR_TEST_ENTRY(mesh_renders_are_identical_for_one_and_two_threads),
             MR_TEST_ENTRY(mesh_textures_sample_the_mesh_uvs),
             MR_TEST_ENTRY(mesh_bad_meshes_are_rejected_with_messages),
             MR_TEST_ENTRY(mesh_camera_framing_fits_the_bounding_sphere),
             MR_TEST_ENTRY(mesh_generated_normals_and_tangents_follow_the_surface),
             MR_TEST_ENTRY(mesh_double_sided_backs_are_shaded_as_fronts),
             MR_TEST_ENTRY(texture_wrap_modes_coordinate_sets_and_transform_known_answers),
             MR_TEST_ENTRY(mesh_materials_shade_their_own_triangles),
             MR_TEST_ENTRY(mesh_single_sided_backs_are_culled_double_sided_ones_seen),
             MR_TEST_ENTRY(mesh_surfaces_normal_occlusion_and_emission_known_answers),
             MR_TEST_ENTRY(mesh_zero_normals_and_tangents_are_generated_per_vertex),
             MR_TEST_ENTRY(mesh_single_sided_backs_let_light_through))
