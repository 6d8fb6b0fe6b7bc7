/*
 * bench_mesh.c — triangle meshes: plan build, render and BVH cost against the triangle count (make bench).
 *
 * Prints a Markdown table on stdout; asserts nothing. docs/rendering.md shows it (scripts/bench.sh rewrites its
 * bench:mesh section). Rows: the analytic unit sphere, then UV-sphere meshes of about 2k, 20k and 200k
 * triangles (exact normals and UVs) in its place, 256^2, the fit camera, lit by the studio HDR map
 * (N = 256 directions, the default); then the 20k sphere standing on a floor quad, a mesh that occludes itself,
 * so the plan traces shadow rays. Columns: plan creation (mesh copy, generated attributes, BVH, convexity test,
 * primary and shadow rays), median render time with the plan prepared (GGX), 1 and 2 OpenMP threads, shadow
 * rays, and the BVH's speed on random rays through the mesh's bounding box (one thread).
 * Usage: bench_mesh HDRI_DIR [--quick]   (HDRI_DIR holds studio_small_03_1k.hdr)
 */
#include <math.h>
#include <omp.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench_util.h"
#include "matremap.h"

#define SIZE 256
#define PI 3.14159265358979323846

static void die(const char *what) {
    fprintf(stderr, "bench_mesh: %s: %s\n", what, mr_last_error());
    exit(3);
}

typedef struct bench_mesh {
    mr_mesh mesh;
    float *positions, *normals, *uvs;
    uint32_t *indices;
} bench_mesh;

/* A unit UV sphere (stacks x 2 stacks quads, pole rows as single triangles), optionally with a floor quad
 * at y = -1, x and z in [-3, 3], facing up. */
static bench_mesh make_sphere(int stacks, int with_floor) {
    bench_mesh m;
    int slices = 2 * stacks, columns = slices + 1;
    int vertices = (stacks + 1) * columns + (with_floor ? 4 : 0);
    int triangles = 2 * stacks * slices - 2 * slices + (with_floor ? 2 : 0);
    m.positions = malloc((size_t)vertices * 3 * sizeof(float));
    m.normals = malloc((size_t)vertices * 3 * sizeof(float));
    m.uvs = malloc((size_t)vertices * 2 * sizeof(float));
    m.indices = malloc((size_t)triangles * 3 * sizeof(uint32_t));
    if (!m.positions || !m.normals || !m.uvs || !m.indices) {
        fprintf(stderr, "bench_mesh: out of memory\n");
        exit(3);
    }
    for (int i = 0; i <= stacks; i++)
        for (int j = 0; j < columns; j++) {
            int v = i * columns + j;
            double theta = PI * i / stacks, phi = 2.0 * PI * ((double)j / slices - 0.5);
            double p[3] = {sin(theta) * sin(phi), cos(theta), sin(theta) * cos(phi)};
            for (int k = 0; k < 3; k++) m.positions[3 * v + k] = m.normals[3 * v + k] = (float)p[k];
            m.uvs[2 * v] = (float)j / slices;
            m.uvs[2 * v + 1] = (float)i / stacks;
        }
    int t = 0;
    for (int i = 0; i < stacks; i++)
        for (int j = 0; j < slices; j++) {
            uint32_t a = (uint32_t)(i * columns + j), d = a + 1, b = a + (uint32_t)columns, c = b + 1;
            if (i + 1 < stacks) m.indices[3 * t] = a, m.indices[3 * t + 1] = b, m.indices[3 * t + 2] = c, t++;
            if (i > 0) m.indices[3 * t] = a, m.indices[3 * t + 1] = c, m.indices[3 * t + 2] = d, t++;
        }
    if (with_floor) {
        int base = (stacks + 1) * columns;
        const float corner[4][2] = {{-3, -3}, {-3, 3}, {3, 3}, {3, -3}};
        for (int k = 0; k < 4; k++) {
            float *p = m.positions + 3 * (base + k), *n = m.normals + 3 * (base + k);
            p[0] = corner[k][0], p[1] = -1.0f, p[2] = corner[k][1];
            n[0] = 0.0f, n[1] = 1.0f, n[2] = 0.0f;
            m.uvs[2 * (base + k)] = m.uvs[2 * (base + k) + 1] = 0.0f;
        }
        const uint32_t tri[6] = {0, 1, 2, 0, 2, 3};
        for (int k = 0; k < 6; k++) m.indices[3 * t + k] = (uint32_t)base + tri[k];
    }
    memset(&m.mesh, 0, sizeof m.mesh);
    m.mesh.vertex_count = vertices;
    m.mesh.triangle_count = triangles;
    m.mesh.positions = m.positions;
    m.mesh.normals = m.normals;
    m.mesh.uvs = m.uvs;
    m.mesh.indices = m.indices;
    return m;
}

static void free_mesh(bench_mesh *m) {
    free(m->positions);
    free(m->normals);
    free(m->uvs);
    free(m->indices);
}

/* xorshift64*, in [0, 1). */
static double rnd(uint64_t *s) {
    *s ^= *s >> 12;
    *s ^= *s << 25;
    *s ^= *s >> 27;
    return (double)((*s * 2685821657736338717ull) >> 11) * (1.0 / 9007199254740992.0);
}

/* Random rays from a box around the mesh towards random points inside it: million rays per second (BVH). */
static double bvh_mrays(const mr_render_plan *plan, int rays) {
    uint64_t seed = 12345;
    double t0 = bench_now();
    int hits = 0;
    for (int r = 0; r < rays; r++) {
        double origin[3], dir[3];
        for (int k = 0; k < 3; k++) {
            origin[k] = 6.0 * rnd(&seed) - 3.0;
            dir[k] = 2.0 * rnd(&seed) - 1.0 - origin[k];
        }
        hits += mr_render_plan_trace_mesh(plan, origin, dir, 0, NULL, NULL);
    }
    double seconds = bench_now() - t0;
    return hits >= 0 ? rays / seconds / 1e6 : 0.0;
}

int main(int argc, char **argv) {
    if (argc < 2) {
        fprintf(stderr, "usage: bench_mesh HDRI_DIR [--quick]\n");
        return 1;
    }
    int quick = argc > 2 && strcmp(argv[2], "--quick") == 0;
    char path[4096];
    snprintf(path, sizeof path, "%s/studio_small_03_1k.hdr", argv[1]);
    mr_image *map = NULL;
    if (mr_img_read(path, NULL, &map) != MR_OK) die(path);
    const mr_brdf_model *ggx = mr_brdf_find("ggx");
    double values[MR_BRDF_MAX_VALUES];
    mr_brdf_default_values(ggx, values);
    const int renders = quick ? 3 : 7;
    const int saved_threads = omp_get_max_threads();

    printf("Fit-scene camera, %d², lit by studio_small_03_1k.hdr (N = %d directions), GGX at its defaults. Plan: "
           "median of 3 creations\n(2 threads); render: median of %d renders with the plan prepared; BVH: random "
           "rays through the bounding box,\none thread, nearest hit.\n\n", SIZE, MR_ENV_DEFAULT_SAMPLES, renders);
    printf("| object | triangles | plan ms (2 threads) | render ms, 1 thread | render ms, 2 threads | shadow rays | "
           "plan MB | BVH M rays/s |\n");
    printf("|---|---:|---:|---:|---:|---:|---:|---:|\n");
    const int stacks[] = {23, 71, 224, 71};
    const char *labels[] = {"UV sphere", "UV sphere", "UV sphere", "UV sphere on a floor quad"};
    for (int row = -1; row < 4; row++) {
        if (quick && row == 2) continue;
        bench_mesh m;
        memset(&m, 0, sizeof m);
        mr_scene scene = mr_scene_fit(&(mr_fit_scene_options){SIZE, MR_FIT_LIGHT_45, 0});
        scene.lights[0] = mr_light_environment(map, 1.0, 0.0, 0);
        if (row >= 0) {
            m = make_sphere(stacks[row], row == 3);
            scene.shape.type = MR_SHAPE_MESH;
            scene.shape.mesh = &m.mesh;
            if (row == 3) scene.camera.position[1] = 2.0;
        }
        omp_set_num_threads(saved_threads < 2 ? saved_threads : 2);
        double plan_ms[3];
        mr_render_plan *plan = NULL;
        for (int k = 0; k < 3; k++) {
            mr_render_plan_free(plan);
            plan = NULL;
            double t0 = bench_now();
            if (mr_render_plan_create(&scene, &plan) != MR_OK) die("plan");
            plan_ms[k] = 1e3 * (bench_now() - t0);
        }
        double render_ms[2];
        mr_image *img = NULL;
        if (mr_image_create(SIZE, SIZE, 3, &img) != MR_OK) die("image");
        for (int t = 0; t < 2; t++) {
            omp_set_num_threads(t + 1);
            double samples[16];
            for (int r = 0; r < renders; r++) {
                double t0 = bench_now();
                if (mr_render_into(plan, ggx, values, MR_COMPONENT_FULL, img) != MR_OK) die("render");
                samples[r] = 1e3 * (bench_now() - t0);
            }
            render_ms[t] = bench_median(samples, renders);
        }
        omp_set_num_threads(saved_threads);
        char bvh[32] = "-";
        if (row >= 0) snprintf(bvh, sizeof bvh, "%.2f", bvh_mrays(plan, quick ? 100000 : 1000000));
        char triangles[32] = "-";
        if (row >= 0) snprintf(triangles, sizeof triangles, "%d", m.mesh.triangle_count);
        printf("| %s | %s | %.1f | %.1f | %.1f | %ld | %.1f | %s |\n", row < 0 ? "analytic sphere" : labels[row],
               triangles, bench_median(plan_ms, 3), render_ms[0], render_ms[1], mr_render_plan_shadow_ray_count(plan),
               mr_render_plan_bytes(plan) / 1e6, bvh);
        fflush(stdout);
        mr_image_free(img);
        mr_render_plan_free(plan);
        if (row >= 0) free_mesh(&m);
    }
    mr_image_free(map);
    return 0;
}
