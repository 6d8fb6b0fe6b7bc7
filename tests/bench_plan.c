/*
 * bench_plan.c — what building a render plan costs (make bench): milliseconds per plan of the fit scene at 64²
 * (the one every remap builds), of its closer look (the 8x zoom on the highlight that a converged remap checks)
 * and at 512², one thread: the first two plans of the process, as a standalone remap builds them (their memory is
 * new to the process: the page faults are counted), then the median of repeated builds. Asserts nothing.
 *
 * --digest prints, instead, what the plans hold as a digest: per scene its counts (lit and object pixels,
 * shading samples) and a hash of its coverage and of the full render of every built-in model at its default
 * values. Two builds of the library that print the same digest build the same plans (bit for bit, as far as any
 * render can tell); this is how a change to plan creation is checked to keep the plan (docs/performance.md).
 * Usage: bench_plan [--quick | --digest]
 */
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <sys/resource.h>

#include "bench_util.h"
#include "matremap.h"
#include "render/render_internal.h"

#define CLOSER_ZOOM 8.0 /* remap.c's ZOOM */

/* FNV-1a over the bytes of `count` floats. */
static uint64_t hash_floats(const float *values, size_t count) {
    uint64_t h = 1469598103934665603ull;
    const unsigned char *bytes = (const unsigned char *)values;
    for (size_t i = 0; i < count * sizeof *values; i++) {
        h ^= bytes[i];
        h *= 1099511628211ull;
    }
    return h;
}

static int make_plan(const mr_scene *scene, mr_render_plan **plan) {
    if (mr_render_plan_create(scene, plan) == MR_OK) return 1;
    fprintf(stderr, "bench_plan: %s\n", mr_last_error());
    return 0;
}

/* Minor page faults of the process so far. */
static long page_faults(void) {
    struct rusage usage;
    return getrusage(RUSAGE_SELF, &usage) == 0 ? usage.ru_minflt : 0;
}

/* Build the plan of `scene` once, keeping it: its ms and the page faults it took, into *ms and *faults. */
static mr_render_plan *first_plan(const mr_scene *scene, double *ms, long *faults) {
    mr_render_plan *plan = NULL;
    const long f0 = page_faults();
    const double t0 = bench_now();
    if (!make_plan(scene, &plan)) exit(3);
    *ms = 1e3 * (bench_now() - t0);
    *faults = page_faults() - f0;
    return plan;
}

/* Median ms of building the plan of `scene` (one thread). */
static double time_plan(const mr_scene *scene, int reps) {
    double samples[64];
    if (reps > 64) reps = 64;
    for (int r = 0; r < reps; r++) {
        mr_render_plan *plan = NULL;
        double t0 = bench_now();
        if (!make_plan(scene, &plan)) exit(3);
        samples[r] = 1e3 * (bench_now() - t0);
        mr_render_plan_free(plan);
    }
    return bench_median(samples, reps);
}

static void digest(const char *name, const mr_scene *scene, int all_models) {
    mr_render_plan *plan = NULL;
    if (!make_plan(scene, &plan)) exit(3);
    const size_t pixels = (size_t)scene->width * (size_t)scene->height;
    printf("%s: %dx%d lit %d object %d samples %ld reflection %ld coverage %016llx\n", name, scene->width,
           scene->height, mr_render_plan_lit_pixel_count(plan), mr_render_plan_object_pixel_count(plan),
           mr_render_plan_sample_count(plan), mr_render_plan_reflection_sample_count(plan),
           (unsigned long long)hash_floats(mr_render_plan_coverage(plan), pixels));
    mr_image *image = NULL;
    if (mr_image_create(scene->width, scene->height, 3, &image) != MR_OK) exit(3);
    const mr_brdf_model *const *models = mr_brdf_models();
    for (int m = 0; models[m] != NULL && (all_models || m < 3); m++) {
        double values[MR_BRDF_MAX_VALUES];
        mr_brdf_default_values(models[m], values);
        if (mr_render_into_threads(plan, 1, models[m], values, MR_COMPONENT_FULL, image) != MR_OK) {
            fprintf(stderr, "bench_plan: %s\n", mr_last_error());
            exit(3);
        }
        printf("  %s %016llx\n", models[m]->name, (unsigned long long)hash_floats(image->pixels, 3 * pixels));
    }
    mr_image_free(image);
    mr_render_plan_free(plan);
}

/* An equirectangular sky with some structure and a bright spot, for the environment-lit digests. */
static mr_image *sky_map(void) {
    mr_image *map = NULL;
    if (mr_image_create(32, 16, 3, &map) != MR_OK) exit(3);
    for (int j = 0; j < 16; j++)
        for (int i = 0; i < 32; i++)
            for (int c = 0; c < 3; c++)
                map->pixels[(j * 32 + i) * 3 + c] =
                    (float)(0.2 + 0.8 * fabs(sin(0.3 * i + 0.7 * j + c)) + (i == 20 && j == 5 ? 40.0 : 0.0));
    return map;
}

/* A bumpy height field over [-1, 1]^2 facing the camera (+z), with UVs: it shadows itself. */
enum { FIELD = 12 };
static float field_positions[(FIELD + 1) * (FIELD + 1) * 3], field_uvs[(FIELD + 1) * (FIELD + 1) * 2];
static uint32_t field_indices[FIELD * FIELD * 6];
static mr_mesh bumpy_field(void) {
    for (int j = 0; j <= FIELD; j++)
        for (int i = 0; i <= FIELD; i++) {
            const int v = j * (FIELD + 1) + i;
            const double x = 2.0 * i / FIELD - 1.0, y = 2.0 * j / FIELD - 1.0;
            field_positions[3 * v] = (float)x;
            field_positions[3 * v + 1] = (float)y;
            field_positions[3 * v + 2] = (float)(0.4 * sin(5.0 * x) * cos(4.0 * y));
            field_uvs[2 * v] = (float)i / FIELD;
            field_uvs[2 * v + 1] = (float)j / FIELD;
        }
    int t = 0;
    for (int j = 0; j < FIELD; j++)
        for (int i = 0; i < FIELD; i++) {
            const uint32_t a = (uint32_t)(j * (FIELD + 1) + i), b = a + 1, c = a + FIELD + 1, d = c + 1;
            const uint32_t quad[6] = {a, b, d, a, d, c};
            for (int k = 0; k < 6; k++) field_indices[t++] = quad[k];
        }
    return (mr_mesh){.vertex_count = (FIELD + 1) * (FIELD + 1), .positions = field_positions, .uvs = field_uvs,
                     .triangle_count = 2 * FIELD * FIELD, .indices = field_indices, .double_sided = 1};
}

int main(int argc, char **argv) {
    const int quick = argc > 1 && strcmp(argv[1], "--quick") == 0;
    const int digests = argc > 1 && strcmp(argv[1], "--digest") == 0;
    mr_scene fit64 = mr_scene_fit(&(mr_fit_scene_options){64, MR_FIT_LIGHT_45, 0});
    mr_scene frontal64 = mr_scene_fit(&(mr_fit_scene_options){64, MR_FIT_LIGHT_FRONTAL, 0});
    mr_scene fit512 = mr_scene_fit(&(mr_fit_scene_options){512, MR_FIT_LIGHT_45, 0});
    mr_scene closer64, closer_frontal64;
    if (!mr_scene_zoom_on_highlight(&fit64, CLOSER_ZOOM, &closer64) ||
        !mr_scene_zoom_on_highlight(&frontal64, CLOSER_ZOOM, &closer_frontal64)) {
        fprintf(stderr, "bench_plan: the fit scene has no highlight to zoom on\n");
        return 3;
    }
    fit64.threads = frontal64.threads = fit512.threads = closer64.threads = closer_frontal64.threads = 1;
    if (digests) {
        mr_scene fit16 = mr_scene_fit(&(mr_fit_scene_options){16, MR_FIT_LIGHT_45, 0});
        mr_scene fit200 = mr_scene_fit(&(mr_fit_scene_options){200, MR_FIT_LIGHT_FRONTAL, 0});
        mr_scene edges = fit64, centres = fit64, one_ray = fit64;
        edges.edge_samples = 7;
        one_ray.edge_samples = 1; // one ray per pixel, the silhouette's too
        centres.highlight_samples = 1;
        digest("fit 64 45", &fit64, 1);
        digest("fit 64 frontal", &frontal64, 1);
        digest("closer 64 45", &closer64, 1);
        digest("closer 64 frontal", &closer_frontal64, 1);
        digest("fit 16 45", &fit16, 1);
        digest("fit 64 45 edge 7", &edges, 0);
        digest("fit 64 45 edge 1", &one_ray, 0);
        digest("fit 64 45 centres only", &centres, 0);
        digest("fit 200 frontal", &fit200, 0);
        digest("fit 512 45", &fit512, 0);
        fit512.threads = 2; // traced by a team, in bands
        digest("fit 512 45, two threads", &fit512, 0);
        // An environment light (with reflection samples) beside the point light, on the sphere and on a mesh
        // that shadows itself; one thread and two.
        mr_image *sky = sky_map();
        mr_scene lit = fit64;
        lit.lights[lit.light_count++] = mr_light_environment(sky, 0.5, 30.0, 128);
        lit.lights[1].reflection_samples = 8;
        digest("fit 64 45 + environment", &lit, 1);
        const mr_mesh field = bumpy_field();
        mr_scene mesh = lit;
        mesh.shape.type = MR_SHAPE_MESH;
        mesh.shape.mesh = &field;
        digest("mesh 64 45 + environment", &mesh, 1);
        mesh.width = mesh.height = 160;
        mesh.threads = 2;
        digest("mesh 160 45 + environment, two threads", &mesh, 0);
        mr_image_free(sky);
        return 0;
    }
    // As a remap builds them: the fit plan, then its closer look, kept while the fit runs; then a 512² plan, as
    // `matremap render` builds it.
    double first_ms[3];
    long first_faults[3];
    mr_render_plan *first = first_plan(&fit64, &first_ms[0], &first_faults[0]);
    mr_render_plan *second = first_plan(&closer64, &first_ms[1], &first_faults[1]);
    mr_render_plan_free(first);
    mr_render_plan_free(second);
    mr_render_plan_free(first_plan(&fit512, &first_ms[2], &first_faults[2]));
    const int reps = quick ? 5 : 31;
    const double ms64 = time_plan(&fit64, reps), closer = time_plan(&closer64, reps);
    const double ms512 = time_plan(&fit512, quick ? 3 : 7);
    printf("| plan (one thread) | 64², 45° light | its closer look (8×) | 512², 45° light |\n");
    printf("|---|---:|---:|---:|\n");
    printf("| first of the process: ms (page faults) | %.2f (%ld) | %.2f (%ld) | %.1f (%ld) |\n", first_ms[0],
           first_faults[0], first_ms[1], first_faults[1], first_ms[2], first_faults[2]);
    printf("| ms per plan, repeated (median of %d, %d at 512²) | %.2f | %.2f | %.1f |\n", reps, quick ? 3 : 7, ms64,
           closer, ms512);
    return 0;
}
