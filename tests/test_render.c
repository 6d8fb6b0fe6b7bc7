/*
 * test_render.c — the fit-scene renderer: known answers, component sums, symmetry, determinism, validation.
 */
#include <math.h>
#include <omp.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "harness.h"
#include "matremap.h"
#include "render/highlight.h"
#include "render/mesh.h"
#include "render/render_internal.h"
#include "render/texture.h"


/* The radiance of a Lambertian sphere seen through image position (px, py) (in pixels from the top-left
 * corner), computed independently of src/render: the textbook quadratic a t^2 + b t + c = 0 for the camera
 * ray, then L = rho/pi * I * cos(theta_l) / d^2. Returns -1 where the ray misses the sphere. */
static double lambert_reference(const mr_scene *s, double px, double py, double rho) {
    const double *eye = s->camera.position;
    double tan_half = tan(s->camera.fov_y_degrees * 3.14159265358979323846 / 360.0);
    // Camera at (0,0,4) looking down -z with +y up: right = +x, up = +y.
    double dir[3] = {(2.0 * px / s->width - 1.0) * tan_half, (1.0 - 2.0 * py / s->height) * tan_half, -1.0};
    double a = dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2];
    double b = 2.0 * (eye[0] * dir[0] + eye[1] * dir[1] + eye[2] * dir[2]);
    double c = eye[0] * eye[0] + eye[1] * eye[1] + eye[2] * eye[2] - 1.0;
    double disc = b * b - 4.0 * a * c;
    if (disc < 0.0) return -1.0;
    double t = (-b - sqrt(disc)) / (2.0 * a);
    double p[3] = {eye[0] + t * dir[0], eye[1] + t * dir[1], eye[2] + t * dir[2]};
    double l[3] = {s->lights[0].position[0] - p[0], s->lights[0].position[1] - p[1], s->lights[0].position[2] - p[2]};
    double d2 = l[0] * l[0] + l[1] * l[1] + l[2] * l[2];
    double cos_l = (p[0] * l[0] + p[1] * l[1] + p[2] * l[2]) / sqrt(d2); // the normal of a unit sphere is p
    if (cos_l <= 0.0) return 0.0;
    return rho / 3.14159265358979323846 * s->lights[0].intensity[0] * cos_l / d2;
}

/* A fit-scene plan; edge_samples 0 is the default silhouette filtering, 1 pixel centres only; highlight_samples
 * 0 integrates the pixels about the highlight, 1 samples their centres too (for the tests that check point-sampled
 * values against a formula at each pixel's centre). */
static mr_render_plan *fit_plan_sampled(int size, mr_fit_light light, int edge_samples, int highlight_samples) {
    mr_fit_scene_options o = {0};
    o.size = size;
    o.light = light;
    mr_scene scene = mr_scene_fit(&o);
    scene.edge_samples = edge_samples;
    scene.highlight_samples = highlight_samples;
    mr_render_plan *plan = NULL;
    MR_CHECK_OK(mr_render_plan_create(&scene, &plan));
    return plan;
}

static mr_render_plan *fit_plan_edges(int size, mr_fit_light light, int edge_samples) {
    return fit_plan_sampled(size, light, edge_samples, 0);
}

static mr_render_plan *fit_plan_centres(int size, mr_fit_light light, int edge_samples) {
    return fit_plan_sampled(size, light, edge_samples, 1);
}

static mr_render_plan *fit_plan(int size, mr_fit_light light) { return fit_plan_edges(size, light, 0); }

/* What a pixel of the Lambert sphere must hold: the centre value inside or outside the silhouette, the box
 * filter of n x n sub-pixel values on it (misses count as black). The silhouette test is the renderer's rule
 * (corners and centre disagree), recomputed with the reference's own ray-sphere test. */
static double lambert_pixel(const mr_scene *s, int x, int y, double rho, int n) {
    int hits = 0;
    const double corners[4][2] = {{x, y}, {x + 1, y}, {x, y + 1}, {x + 1, y + 1}};
    for (int k = 0; k < 4; k++) hits += lambert_reference(s, corners[k][0], corners[k][1], rho) >= 0.0;
    double centre = lambert_reference(s, x + 0.5, y + 0.5, rho);
    if (n == 1 || hits == 4 * (centre >= 0.0)) return centre < 0.0 ? 0.0 : centre;
    double sum = 0.0;
    for (int j = 0; j < n; j++)
        for (int i = 0; i < n; i++) sum += fmax(0.0, lambert_reference(s, x + (i + 0.5) / n, y + (j + 0.5) / n, rho));
    return sum / (n * n);
}

MR_TEST(lambert_sphere_matches_point_light_formula) {
    // Every pixel, both light positions, with pixel-centre sampling (1) and with box-filtered edges (4); pixel
    // centres at the highlight too (its quadrature has a test of its own, below).
    const mr_brdf_model *lambert = mr_brdf_find("lambert");
    double values[3] = {0.25, 0.5, 0.75};
    for (int light = 0; light < MR_FIT_LIGHT_COUNT; light++)
        for (int n = 1; n <= 4; n += 3) {
            mr_render_plan *plan = fit_plan_centres(96, (mr_fit_light)light, n);
            const mr_scene *scene = mr_render_plan_scene(plan);
            mr_image *img = NULL;
            MR_CHECK_OK(mr_render(plan, lambert, values, MR_COMPONENT_FULL, &img));
            int mismatches = 0;
            double worst = 0.0;
            for (int y = 0; y < 96; y++)
                for (int x = 0; x < 96; x++)
                    for (int ch = 0; ch < 3; ch++) {
                        double expected = lambert_pixel(scene, x, y, values[ch], n);
                        double err = fabs(mr_image_at(img, x, y)[ch] - expected);
                        if (err > worst) worst = err;
                        if (err > 1e-6 + 1e-5 * expected) mismatches++;
                    }
            MR_CHECK_MSG(mismatches == 0, "light %s, %dx%d edge samples: %d channel values differ from "
                         "rho/pi*I*cos/d^2 (worst %.3g)", mr_fit_light_name(light), n, n, mismatches, worst);
            mr_image_free(img);
            mr_render_plan_free(plan);
        }
}

MR_TEST(edge_filtering_measures_the_silhouette) {
    // The coverage of box-filtered edges integrates to the projected disc's area far more closely than
    // counting pixel centres does, and is 0 or 1 away from the silhouette.
    int size = 256;
    double r = tan(asin(0.25)) / tan(17.5 * 3.14159265358979323846 / 180.0) * size / 2.0;
    double disc = 3.14159265358979323846 * r * r;
    mr_render_plan *centres = fit_plan_edges(size, MR_FIT_LIGHT_45, 1);
    mr_render_plan *filtered = fit_plan(size, MR_FIT_LIGHT_45);
    double sum_centres = 0.0, sum_filtered = 0.0;
    int partial = 0, bad_values = 0;
    for (int p = 0; p < size * size; p++) {
        float c = mr_render_plan_coverage(filtered)[p];
        sum_centres += mr_render_plan_coverage(centres)[p];
        sum_filtered += c;
        if (c > 0.0f && c < 1.0f) partial++;
        if (!(c >= 0.0f && c <= 1.0f) || fmodf(c * 16.0f, 1.0f) != 0.0f) bad_values++;
    }
    MR_CHECK_NEAR(sum_filtered / disc, 1.0, 2e-4);
    MR_CHECK(fabs(sum_filtered / disc - 1.0) < fabs(sum_centres / disc - 1.0));
    MR_CHECK(bad_values == 0);
    // Only the silhouette is filtered: about its circumference in pixels, not the whole disc.
    MR_CHECK(partial > 2.0 * r && partial < 4.0 * 3.14159265358979323846 * r);
    mr_render_plan_free(centres);
    mr_render_plan_free(filtered);
}

MR_TEST(coverage_mask_is_the_plans_coverage) {
    // The mask image holds the plan's coverage bit for bit; the unlit part of the sphere (the point light at 45°
    // leaves a crescent dark) is covered although it renders black, and the mask is the same for any material.
    mr_render_plan *plan = fit_plan(64, MR_FIT_LIGHT_45);
    mr_image *mask = NULL, *image = NULL;
    MR_CHECK_OK(mr_render_plan_coverage_mask(plan, &mask));
    MR_CHECK(mask != NULL && mask->width == 64 && mask->height == 64 && mask->channels == 1);
    if (mask != NULL)
        MR_CHECK(memcmp(mask->pixels, mr_render_plan_coverage(plan), 64 * 64 * sizeof(float)) == 0);
    double rho[3] = {0.5, 0.5, 0.5};
    MR_CHECK_OK(mr_render(plan, mr_brdf_find("lambert"), rho, MR_COMPONENT_FULL, &image));
    int dark_covered = 0, lit_uncovered = 0;
    for (int p = 0; mask != NULL && image != NULL && p < 64 * 64; p++) {
        float m = mask->pixels[p], v = image->pixels[3 * p];
        dark_covered += m == 1.0f && v == 0.0f;
        lit_uncovered += m == 0.0f && v != 0.0f;
    }
    MR_CHECK_MSG(dark_covered > 50 && lit_uncovered == 0, "%d covered pixels are unlit, %d lit ones uncovered",
                 dark_covered, lit_uncovered);
    static mr_image sentinel; // *out stays untouched on failure
    mr_image *untouched = &sentinel;
    MR_CHECK(mr_render_plan_coverage_mask(NULL, &untouched) == MR_ERR_INVALID_ARG);
    MR_CHECK(untouched == &sentinel);
    MR_CHECK(mr_render_plan_coverage_mask(plan, NULL) == MR_ERR_INVALID_ARG);
    mr_image_free(mask);
    mr_image_free(image);
    mr_render_plan_free(plan);
}

MR_TEST(background_fills_the_uncovered_part_of_each_pixel) {
    mr_scene scene = mr_scene_fit(&(mr_fit_scene_options){64, MR_FIT_LIGHT_FRONTAL, 0});
    scene.background[0] = 0.5, scene.background[1] = 0.25, scene.background[2] = 0.125;
    mr_render_plan *plan = NULL;
    MR_CHECK_OK(mr_render_plan_create(&scene, &plan));
    double black[3] = {0.0, 0.0, 0.0};
    mr_image *full = NULL, *diffuse = NULL;
    MR_CHECK_OK(mr_render(plan, mr_brdf_find("lambert"), black, MR_COMPONENT_FULL, &full));
    MR_CHECK_OK(mr_render(plan, mr_brdf_find("lambert"), black, MR_COMPONENT_DIFFUSE, &diffuse));
    int bad = 0;
    for (int p = 0; p < 64 * 64; p++)
        for (int c = 0; c < 3; c++) {
            double expected = scene.background[c] * (1.0 - mr_render_plan_coverage(plan)[p]);
            if (fabs(full->pixels[p * 3 + c] - expected) > 1e-7 || diffuse->pixels[p * 3 + c] != 0.0f) bad++;
        }
    MR_CHECK_MSG(bad == 0, "%d values differ from background x (1 - coverage)", bad);
    mr_image_free(full);
    mr_image_free(diffuse);
    mr_render_plan_free(plan);
}

MR_TEST(frontal_centre_pixel_known_value) {
    // Odd size: the centre pixel's ray is the view axis and hits (0,0,1); the light is at (0,0,3), d = 2,
    // cos = 1, so L = rho/pi * 10 / 4 (at the pixel's centre: the highlight's quadrature is off).
    mr_render_plan *plan = fit_plan_centres(65, MR_FIT_LIGHT_FRONTAL, 0);
    double values[3] = {0.5, 0.5, 0.5};
    mr_image *img = NULL;
    MR_CHECK_OK(mr_render(plan, mr_brdf_find("lambert"), values, MR_COMPONENT_FULL, &img));
    MR_CHECK_NEAR(mr_image_at(img, 32, 32)[1], 0.5 / 3.14159265358979323846 * 2.5, 1e-6);
    mr_image_free(img);
    mr_render_plan_free(plan);
}

MR_TEST(silhouette_area_matches_projection) {
    // Angular radius asin(1/4); projected radius in pixels = tan(asin(1/4)) / tan(17.5 deg) * size/2.
    int size = 256;
    mr_render_plan *plan = fit_plan(size, MR_FIT_LIGHT_45);
    double r = tan(asin(0.25)) / tan(17.5 * 3.14159265358979323846 / 180.0) * size / 2.0;
    double expected = 3.14159265358979323846 * r * r;
    MR_CHECK_NEAR(mr_render_plan_object_pixel_count(plan) / expected, 1.0, 0.01);
    // The 45-degree light leaves a crescent of the visible hemisphere unlit.
    MR_CHECK(mr_render_plan_lit_pixel_count(plan) < mr_render_plan_object_pixel_count(plan));
    MR_CHECK(mr_render_plan_lit_pixel_count(plan) > mr_render_plan_object_pixel_count(plan) / 2);
    mr_render_plan_free(plan);
}

MR_TEST(diffuse_plus_specular_equals_full_for_every_model) {
    mr_render_plan *plan = fit_plan(64, MR_FIT_LIGHT_45);
    const mr_brdf_model *const *models = mr_brdf_models();
    for (int m = 0; models[m] != NULL; m++) {
        double values[MR_BRDF_MAX_VALUES];
        mr_brdf_default_values(models[m], values);
        mr_image *full = NULL, *diffuse = NULL, *specular = NULL;
        MR_CHECK_OK(mr_render(plan, models[m], values, MR_COMPONENT_FULL, &full));
        MR_CHECK_OK(mr_render(plan, models[m], values, MR_COMPONENT_DIFFUSE, &diffuse));
        MR_CHECK_OK(mr_render(plan, models[m], values, MR_COMPONENT_SPECULAR, &specular));
        if (!full || !diffuse || !specular) continue;
        int bad = 0, nonfinite = 0;
        double total = 0.0;
        for (size_t i = 0; i < mr_image_value_count(full); i++) {
            double sum = (double)diffuse->pixels[i] + specular->pixels[i];
            if (!isfinite(full->pixels[i]) || full->pixels[i] < 0.0f) nonfinite++;
            if (fabs(sum - full->pixels[i]) > 1e-6 * (1.0 + fabs(full->pixels[i]))) bad++;
            total += full->pixels[i];
        }
        MR_CHECK_MSG(bad == 0 && nonfinite == 0, "model %s: %d pixels with diffuse + specular != full, %d negative "
                     "or non-finite", models[m]->name, bad, nonfinite);
        MR_CHECK_MSG(total > 0.0, "model %s renders black with its defaults", models[m]->name);
        mr_image_free(full);
        mr_image_free(diffuse);
        mr_image_free(specular);
    }
    mr_render_plan_free(plan);
}

/* Isotropic BRDFs under a light in the horizontal plane through the view axis give images symmetric top to
 * bottom; a frontal light adds left-right symmetry. Catches frame and camera mistakes. */
MR_TEST(images_have_the_scene_symmetries) {
    const mr_brdf_model *ggx = mr_brdf_find("ggx");
    const mr_brdf_model *model = ggx ? ggx : mr_brdf_find("lambert");
    double values[MR_BRDF_MAX_VALUES];
    mr_brdf_default_values(model, values);
    for (int light = 0; light < MR_FIT_LIGHT_COUNT; light++) {
        mr_render_plan *plan = fit_plan(80, (mr_fit_light)light);
        mr_image *img = NULL;
        MR_CHECK_OK(mr_render(plan, model, values, MR_COMPONENT_FULL, &img));
        double worst_vertical = 0.0, worst_horizontal = 0.0;
        for (int y = 0; y < 80; y++)
            for (int x = 0; x < 80; x++)
                for (int c = 0; c < 3; c++) {
                    double v = mr_image_at(img, x, y)[c];
                    double flip_v = mr_image_at(img, x, 79 - y)[c];
                    double flip_h = mr_image_at(img, 79 - x, y)[c];
                    worst_vertical = fmax(worst_vertical, fabs(v - flip_v) / (1e-3 + v));
                    worst_horizontal = fmax(worst_horizontal, fabs(v - flip_h) / (1e-3 + v));
                }
        MR_CHECK_MSG(worst_vertical < 1e-4, "light %s: top/bottom asymmetry %.3g", mr_fit_light_name(light),
                     worst_vertical);
        if (light == MR_FIT_LIGHT_FRONTAL)
            MR_CHECK_MSG(worst_horizontal < 1e-4, "frontal light: left/right asymmetry %.3g", worst_horizontal);
        else
            MR_CHECK_MSG(worst_horizontal > 0.1, "45-degree light: image is left/right symmetric");
        // The 45-degree light is on the camera's right: the right half is brighter.
        if (light == MR_FIT_LIGHT_45) MR_CHECK(mr_image_at(img, 60, 40)[1] > mr_image_at(img, 20, 40)[1]);
        mr_image_free(img);
        mr_render_plan_free(plan);
    }
}

MR_TEST(renders_are_identical_for_any_thread_count_and_plan_reuse) {
    // 128^2 is below the automatic rule's threshold: the scenes ask for 1 and 2 threads (mr_scene.threads).
    mr_scene scenes[2];
    mr_render_plan *plans[2] = {NULL, NULL};
    for (int t = 0; t < 2; t++) {
        scenes[t] = mr_scene_fit(&(mr_fit_scene_options){128, MR_FIT_LIGHT_45, 0});
        scenes[t].threads = t + 1;
        MR_CHECK_OK(mr_render_plan_create(&scenes[t], &plans[t]));
    }
    mr_render_plan *plan = plans[1];
    const mr_brdf_model *const *models = mr_brdf_models();
    const mr_brdf_model *last = models[mr_brdf_model_count() - 1];
    double values[MR_BRDF_MAX_VALUES], other[MR_BRDF_MAX_VALUES];
    mr_brdf_default_values(last, values);
    mr_brdf_default_values(models[0], other);
    mr_image *one = NULL, *two = NULL, *between = NULL, *again = NULL;
    MR_CHECK_OK(mr_render(plans[0], last, values, MR_COMPONENT_FULL, &one));
    MR_CHECK_OK(mr_render(plan, last, values, MR_COMPONENT_FULL, &two));
    MR_CHECK_OK(mr_render(plan, models[0], other, MR_COMPONENT_FULL, &between));
    MR_CHECK_OK(mr_render(plan, last, values, MR_COMPONENT_FULL, &again));
    size_t bytes = mr_image_value_count(one) * sizeof(float);
    MR_CHECK(memcmp(one->pixels, two->pixels, bytes) == 0);
    MR_CHECK(memcmp(one->pixels, again->pixels, bytes) == 0);
    mr_image_free(one);
    mr_image_free(two);
    mr_image_free(between);
    mr_image_free(again);
    mr_render_plan_free(plans[0]);
    mr_render_plan_free(plan);
}

MR_TEST(threads_follow_the_scene_and_the_work) {
    // Automatic: one thread for the remaps' 64^2 fit scene (2,881 shading samples), a team for 512^2 (109,463);
    // a count given is used as given; out of range is refused.
    const int sizes[2] = {64, 512};
    for (int k = 0; k < 2; k++) {
        mr_scene scene = mr_scene_fit(&(mr_fit_scene_options){sizes[k], MR_FIT_LIGHT_45, 0});
        mr_render_plan *plan = NULL;
        MR_CHECK_OK(mr_render_plan_create(&scene, &plan));
        if (plan == NULL) continue;
        const int expected = k == 0 ? 1 : omp_get_max_threads();
        MR_CHECK_MSG(mr_render_plan_threads(plan) == expected, "%d^2 (%ld samples): %d threads, expected %d",
                     sizes[k], mr_render_plan_sample_count(plan), mr_render_plan_threads(plan), expected);
        MR_CHECK((mr_render_plan_sample_count(plan) >= MR_RENDER_PARALLEL_SAMPLES) == (k == 1));
        mr_render_plan_free(plan);
        scene.threads = 3;
        MR_CHECK_OK(mr_render_plan_create(&scene, &plan));
        if (plan != NULL) MR_CHECK(mr_render_plan_threads(plan) == 3);
        mr_render_plan_free(plan);
    }
    mr_scene bad = mr_scene_fit(NULL);
    bad.threads = -1;
    MR_CHECK(mr_scene_validate(&bad) == MR_ERR_INVALID_ARG && strstr(mr_last_error(), "threads -1"));
}

MR_TEST(render_into_rejects_wrong_image_size) {
    mr_render_plan *plan = fit_plan(32, MR_FIT_LIGHT_45);
    mr_image *wrong = NULL;
    MR_CHECK_OK(mr_image_create(31, 32, 3, &wrong));
    double values[3] = {0.5, 0.5, 0.5};
    MR_CHECK(mr_render_into(plan, mr_brdf_find("lambert"), values, MR_COMPONENT_FULL, wrong) == MR_ERR_INVALID_ARG);
    MR_CHECK(strstr(mr_last_error(), "31x32x3") != NULL);
    mr_image_free(wrong);
    mr_render_plan_free(plan);
}

MR_TEST(invalid_scenes_are_rejected_with_the_field_named) {
    mr_scene scene = mr_scene_fit(NULL);
    MR_CHECK(scene.width == 512 && scene.height == 512);
    mr_render_plan *plan = NULL;
    mr_scene bad = scene;
    bad.width = 0;
    MR_CHECK(mr_render_plan_create(&bad, &plan) == MR_ERR_INVALID_ARG && plan == NULL);
    bad = scene;
    bad.camera.position[2] = 0.5;
    MR_CHECK(mr_render_plan_create(&bad, &plan) == MR_ERR_INVALID_ARG);
    MR_CHECK(strstr(mr_last_error(), "inside the sphere") != NULL);
    bad = scene;
    bad.camera.up[0] = 0.0, bad.camera.up[1] = 0.0, bad.camera.up[2] = 1.0;
    MR_CHECK(mr_render_plan_create(&bad, &plan) == MR_ERR_INVALID_ARG);
    bad = scene;
    bad.lights[0].intensity[1] = NAN;
    MR_CHECK(mr_render_plan_create(&bad, &plan) == MR_ERR_INVALID_ARG);
    bad = scene;
    bad.shape.radius = -1.0;
    MR_CHECK(mr_render_plan_create(&bad, &plan) == MR_ERR_INVALID_ARG);
    bad = scene;
    bad.edge_samples = 17;
    MR_CHECK(mr_render_plan_create(&bad, &plan) == MR_ERR_INVALID_ARG);
    MR_CHECK(strstr(mr_last_error(), "edge_samples") != NULL);
    bad = scene;
    bad.light_count = 0;
    MR_CHECK(mr_render_plan_create(&bad, &plan) == MR_ERR_INVALID_ARG);
    MR_CHECK(plan == NULL);
}

MR_TEST(two_lights_add_up) {
    // A scene with both fit lights renders the sum of the two single-light renders, pixel by pixel with the same
    // samples: pixel centres (each scene would otherwise integrate the pixels about its own highlights).
    mr_scene a = mr_scene_fit(&(mr_fit_scene_options){48, MR_FIT_LIGHT_45, 0});
    mr_scene b = mr_scene_fit(&(mr_fit_scene_options){48, MR_FIT_LIGHT_FRONTAL, 0});
    a.highlight_samples = b.highlight_samples = 1;
    mr_scene both = a;
    both.light_count = 2;
    both.lights[1] = b.lights[0];
    const mr_brdf_model *model = mr_brdf_find("ggx") ? mr_brdf_find("ggx") : mr_brdf_find("lambert");
    double values[MR_BRDF_MAX_VALUES];
    mr_brdf_default_values(model, values);
    mr_render_plan *pa = NULL, *pb = NULL, *pboth = NULL;
    MR_CHECK_OK(mr_render_plan_create(&a, &pa));
    MR_CHECK_OK(mr_render_plan_create(&b, &pb));
    MR_CHECK_OK(mr_render_plan_create(&both, &pboth));
    mr_image *ia = NULL, *ib = NULL, *iboth = NULL;
    MR_CHECK_OK(mr_render(pa, model, values, MR_COMPONENT_FULL, &ia));
    MR_CHECK_OK(mr_render(pb, model, values, MR_COMPONENT_FULL, &ib));
    MR_CHECK_OK(mr_render(pboth, model, values, MR_COMPONENT_FULL, &iboth));
    double worst = 0.0;
    for (size_t i = 0; i < mr_image_value_count(ia); i++)
        worst = fmax(worst, fabs((double)ia->pixels[i] + ib->pixels[i] - iboth->pixels[i]) /
                                (1.0 + iboth->pixels[i]));
    MR_CHECK_NEAR(worst, 0.0, 1e-6);
    mr_image_free(ia);
    mr_image_free(ib);
    mr_image_free(iboth);
    mr_render_plan_free(pa);
    mr_render_plan_free(pb);
    mr_render_plan_free(pboth);
}

/* ---- environment lights ------------------------------------------------------------------------------------ */

#define TEST_PI 3.14159265358979323846

/* A width x height map with `channels` channels, every value `value`. */
static mr_image *constant_map(int width, int height, int channels, float value) {
    mr_image *map = NULL;
    MR_CHECK_OK(mr_image_create(width, height, channels, &map));
    if (map == NULL) return NULL;
    for (size_t i = 0; i < mr_image_value_count(map); i++) map->pixels[i] = value;
    return map;
}

static int same_pixels(const mr_image *a, const mr_image *b) {
    return a != NULL && b != NULL && a->width == b->width && a->height == b->height && a->channels == b->channels &&
           memcmp(a->pixels, b->pixels, mr_image_value_count(a) * sizeof(float)) == 0;
}

/* The direction of map position (u, v) turned by `degrees` about +y, from render.h's header comment alone:
 * theta = pi v, phi = 2 pi (u - 0.5), w = (sin theta sin phi, cos theta, -sin theta cos phi), then the
 * right-handed rotation about +y (+z goes to +x for 90 degrees). */
static void map_direction(double u, double v, double degrees, double w[3]) {
    double theta = TEST_PI * v, phi = 2.0 * TEST_PI * (u - 0.5), a = degrees * TEST_PI / 180.0;
    double x = sin(theta) * sin(phi), y = cos(theta), z = -sin(theta) * cos(phi);
    w[0] = x * cos(a) + z * sin(a);
    w[1] = y;
    w[2] = -x * sin(a) + z * cos(a);
}

/* The fit scene's camera and sphere with the point light replaced by one environment light. */
static mr_scene env_scene(int size, const mr_image *map, double rotation, int samples) {
    mr_scene scene = mr_scene_fit(&(mr_fit_scene_options){size, MR_FIT_LIGHT_45, 0});
    scene.lights[0] = mr_light_environment(map, 1.0, rotation, samples);
    return scene;
}

static mr_render_plan *env_plan(int size, const mr_image *map, double rotation, int samples) {
    mr_scene scene = env_scene(size, map, rotation, samples);
    mr_render_plan *plan = NULL;
    MR_CHECK_OK(mr_render_plan_create(&scene, &plan));
    return plan;
}

/* World normal and unit direction towards the camera of the point seen through image position (px, py), with
 * the textbook ray-sphere quadratic (as lambert_reference). Returns 0 on a miss. */
static int pixel_geometry(const mr_scene *s, double px, double py, double n[3], double view[3]) {
    const double *eye = s->camera.position;
    double tan_half = tan(s->camera.fov_y_degrees * TEST_PI / 360.0);
    double dir[3] = {(2.0 * px / s->width - 1.0) * tan_half, (1.0 - 2.0 * py / s->height) * tan_half, -1.0};
    double len = sqrt(dir[0] * dir[0] + dir[1] * dir[1] + dir[2] * dir[2]);
    for (int k = 0; k < 3; k++) dir[k] /= len;
    double b = eye[0] * dir[0] + eye[1] * dir[1] + eye[2] * dir[2];
    double c = eye[0] * eye[0] + eye[1] * eye[1] + eye[2] * eye[2] - 1.0;
    if (b * b - c < 0.0) return 0;
    double t = -b - sqrt(b * b - c);
    for (int k = 0; k < 3; k++) {
        n[k] = eye[k] + t * dir[k];
        view[k] = -dir[k];
    }
    return 1;
}

/* Whether pixel (x, y) lies inside the silhouette by the renderer's rule (all four corners see the sphere):
 * then its value is that of the single ray through its centre, not a box filter of sub-pixel rays. */
static int interior_pixel(const mr_scene *s, int x, int y) {
    double n[3], view[3];
    return pixel_geometry(s, x, y, n, view) && pixel_geometry(s, x + 1, y, n, view) &&
           pixel_geometry(s, x, y + 1, n, view) && pixel_geometry(s, x + 1, y + 1, n, view);
}

/* The radiance the environment map reflects towards `view` at a point of normal n, by brute force over the
 * map's texels, independent of the renderer's sampler: each texel (piecewise-constant radiance) is cut into
 * sub x sub cells, each cell contributing f_r * L * cos * (its exact solid angle), f_r and cos taken at the
 * cell's centre. The BRDF's frame is any orthonormal frame around n (isotropic models only). */
static void env_brute_force(const mr_brdf_model *model, const double *values, const mr_image *map, double scale,
                            double rotation, const double n[3], const double view[3], int sub, double out[3]) {
    double t[3], b[3];
    double helper[3] = {fabs(n[0]) < 0.9 ? 1.0 : 0.0, fabs(n[0]) < 0.9 ? 0.0 : 1.0, 0.0};
    t[0] = helper[1] * n[2] - helper[2] * n[1];
    t[1] = helper[2] * n[0] - helper[0] * n[2];
    t[2] = helper[0] * n[1] - helper[1] * n[0];
    double tl = sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]);
    for (int k = 0; k < 3; k++) t[k] /= tl;
    b[0] = n[1] * t[2] - n[2] * t[1];
    b[1] = n[2] * t[0] - n[0] * t[2];
    b[2] = n[0] * t[1] - n[1] * t[0];
    double wo[3] = {t[0] * view[0] + t[1] * view[1] + t[2] * view[2], b[0] * view[0] + b[1] * view[1] +
                    b[2] * view[2], n[0] * view[0] + n[1] * view[1] + n[2] * view[2]};
    mr_brdf_state state;
    model->prepare(model, values, state.bytes);
    const int cols = map->width * sub, rows = map->height * sub;
    double sum[3] = {0.0, 0.0, 0.0};
    for (int r = 0; r < rows; r++) {
        double solid = 2.0 * TEST_PI / cols * (cos(TEST_PI * r / rows) - cos(TEST_PI * (r + 1) / rows));
        for (int q = 0; q < cols; q++) {
            double w[3];
            map_direction((q + 0.5) / cols, (r + 0.5) / rows, rotation, w);
            double cos_n = n[0] * w[0] + n[1] * w[1] + n[2] * w[2];
            if (cos_n <= 0.0) continue;
            double wi[3] = {t[0] * w[0] + t[1] * w[1] + t[2] * w[2], b[0] * w[0] + b[1] * w[1] + b[2] * w[2],
                            cos_n};
            double fd[3], fs[3];
            model->eval(state.bytes, wi, wo, fd, fs);
            const float *px = mr_image_at(map, q / sub, r / sub);
            for (int c = 0; c < 3; c++) sum[c] += (fd[c] + fs[c]) * px[map->channels == 1 ? 0 : c] * cos_n * solid;
        }
    }
    for (int c = 0; c < 3; c++) out[c] = sum[c] * scale;
}

/* Largest error over every pixel that sees the sphere, relative to albedo * L, of a Lambert sphere under a
 * constant environment L with background radiance `bg`: each hit reflects albedo * L, so a pixel holds
 * coverage * albedo * L + (1 - coverage) * bg, silhouette pixels included. */
static double constant_env_error(const mr_render_plan *plan, const mr_image *img, const double *albedo, double L,
                                 double bg, int *covered) {
    const mr_scene *s = mr_render_plan_scene(plan);
    const float *coverage = mr_render_plan_coverage(plan);
    double worst = 0.0;
    *covered = 0;
    for (int p = 0; p < s->width * s->height; p++) {
        if (coverage[p] == 0.0f) continue;
        (*covered)++;
        for (int c = 0; c < 3; c++) {
            double expected = coverage[p] * albedo[c] * L + (1.0 - coverage[p]) * bg;
            worst = fmax(worst, fabs(img->pixels[(size_t)p * 3 + c] - expected) / (albedo[c] * L));
        }
    }
    return worst;
}

MR_TEST(env_constant_map_lambert_known_answer) {
    // A Lambertian sphere under a constant environment of radiance L reflects albedo * L everywhere: the
    // estimator's error is then the pattern's alone. It must be small and shrink as N grows. Every pixel that
    // sees the sphere is checked (64^2 image, silhouette pixels against their coverage, over a grey background).
    // Limits: the measured worst relative errors (2.74e-2, 8.05e-3, 4.86e-4) with a 1.5x margin.
    const int ns[] = {64, 256, 4096};
    const double limits[] = {0.041, 0.012, 7.3e-4};
    const mr_brdf_model *lambert = mr_brdf_find("lambert");
    double albedo[3] = {0.25, 0.5, 0.75};
    const double L = 2.5, bg = 0.1;
    mr_image *map = constant_map(32, 16, 3, (float)L);
    double previous = INFINITY;
    for (int k = 0; k < 3; k++) {
        mr_scene scene = env_scene(64, map, 0.0, ns[k]);
        scene.background[0] = scene.background[1] = scene.background[2] = bg;
        mr_render_plan *plan = NULL;
        MR_CHECK_OK(mr_render_plan_create(&scene, &plan));
        if (plan == NULL) continue;
        mr_image *img = NULL;
        MR_CHECK_OK(mr_render(plan, lambert, albedo, MR_COMPONENT_FULL, &img));
        int covered = 0;
        double err = img != NULL ? constant_env_error(plan, img, albedo, L, bg, &covered) : INFINITY;
        MR_CHECK(covered == mr_render_plan_object_pixel_count(plan) && covered > 2000);
        MR_CHECK_MSG(err <= limits[k], "N %d: worst relative error %.3g > %.3g", ns[k], err, limits[k]);
        MR_CHECK_MSG(err < previous, "N %d: error %.3g does not shrink (%.3g before)", ns[k], err, previous);
        previous = err;
        mr_image_free(img);
        mr_render_plan_free(plan);
    }
    mr_image_free(map);
}

MR_TEST(env_map_channels_scale_and_sample_counts) {
    // A grey map, the same map as RGB and as RGBA (alpha ignored, even NaN), and half the radiance at scale 2
    // all light the sphere alike (to float rounding of the luminance weights); the plan keeps, per hit, the
    // directions above its horizon: about N/2 for a constant map.
    const int N = 1024;
    mr_image *grey = constant_map(16, 8, 1, 0.0f), *rgb = constant_map(16, 8, 3, 0.0f);
    mr_image *rgba = constant_map(16, 8, 4, 0.0f), *half = constant_map(16, 8, 3, 0.0f);
    for (int j = 0; j < 8; j++)
        for (int i = 0; i < 16; i++) {
            float value = (float)(0.5 + 0.25 * ((i * 7 + j * 3) % 5)); // uneven, so the pattern has structure
            mr_image_at(grey, i, j)[0] = value;
            for (int c = 0; c < 3; c++) {
                mr_image_at(rgb, i, j)[c] = mr_image_at(rgba, i, j)[c] = value;
                mr_image_at(half, i, j)[c] = 0.5f * value;
            }
            mr_image_at(rgba, i, j)[3] = (i + j) % 2 ? NAN : -1.0f;
        }
    const mr_brdf_model *ggx = mr_brdf_find("ggx");
    double values[7] = {0.2, 0.3, 0.3, 0.3, 0.4, 0.3, 0.2};
    mr_image *img[4] = {NULL, NULL, NULL, NULL};
    const mr_image *maps[4] = {grey, rgb, rgba, half};
    for (int k = 0; k < 4; k++) {
        mr_scene scene = env_scene(48, maps[k], 15.0, N);
        for (int c = 0; c < 3; c++) scene.lights[0].intensity[c] = k == 3 ? 2.0 : 1.0;
        scene.edge_samples = 1;
        mr_render_plan *plan = NULL;
        MR_CHECK_OK(mr_render_plan_create(&scene, &plan));
        if (plan == NULL) continue;
        double per_hit = (double)mr_render_plan_env_sample_count(plan) / mr_render_plan_lit_pixel_count(plan);
        MR_CHECK_MSG(fabs(per_hit / N - 0.5) < 0.02, "map %d: %.1f directions per hit of %d", k, per_hit, N);
        MR_CHECK(mr_render_plan_sample_count(plan) == mr_render_plan_env_sample_count(plan));
        MR_CHECK(mr_render_plan_bytes(plan) > (size_t)mr_render_plan_env_sample_count(plan) * 2);
        MR_CHECK_OK(mr_render(plan, ggx, values, MR_COMPONENT_FULL, &img[k]));
        mr_render_plan_free(plan);
    }
    MR_CHECK(same_pixels(img[1], img[2]));
    for (int k = 0; k < 4; k += 3) {
        if (img[k] == NULL || img[1] == NULL) continue;
        double worst = 0.0;
        for (size_t i = 0; i < mr_image_value_count(img[1]); i++)
            worst = fmax(worst, fabs(img[k]->pixels[i] - img[1]->pixels[i]) / (1e-3 + img[1]->pixels[i]));
        MR_CHECK_MSG(worst < 1e-5, "map %d differs from the RGB map by %.3g", k, worst);
    }
    for (int k = 0; k < 4; k++) mr_image_free(img[k]);
    mr_image_free(grey);
    mr_image_free(rgb);
    mr_image_free(rgba);
    mr_image_free(half);
}

/* Map whose texel centres hold R = 1 + w.y, G = 1 + 0.8 w.x, B = 1.2 - w.z (w the texel centre's direction
 * by render.h's convention): smooth, different in every channel and every axis. */
static mr_image *linear_map(int width, int height) {
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

/* Map of dim grey 0.02 with one bright coloured patch of 4x3 texels (u 0.875-0.9375, v 0.31-0.41 on a 64x32
 * map: above the camera's right shoulder, in front of the sphere). */
static mr_image *patch_map(void) {
    mr_image *map = constant_map(64, 32, 3, 0.02f);
    if (map == NULL) return NULL;
    for (int j = 10; j < 13; j++)
        for (int i = 56; i < 60; i++) {
            float *px = mr_image_at(map, i, j);
            px[0] = 40.0f, px[1] = 30.0f, px[2] = 20.0f;
        }
    return map;
}

/* Pixels inside the silhouette of a 64^2 fit-scene image spread over the sphere: centre, the four sides, diagonals and
 * two near the silhouette. */
static const int probe_pixels[][2] = {{32, 32}, {18, 32}, {46, 32}, {32, 17}, {32, 47}, {22, 22},
                                      {43, 42}, {24, 44}, {41, 21}, {9, 32}, {32, 55}};
#define PROBE_COUNT ((int)(sizeof probe_pixels / sizeof probe_pixels[0]))

/* Largest error of the renderer's probe pixels against env_brute_force (sub x sub cells per texel), for one map,
 * model and rotation at N samples and M reflection samples, relative to max(reference, 5 % of the brightest
 * reference value among the probes): relative where the sphere is bright, and without letting dark pixels (a few
 * samples of a dim background) dominate. */
static double probe_error(const mr_image *map, double rotation, int samples, int reflection_samples, int sub,
                          const mr_brdf_model *model, const double *values) {
    mr_scene env = env_scene(64, map, rotation, samples);
    env.lights[0].reflection_samples = reflection_samples;
    mr_render_plan *plan = NULL;
    MR_CHECK_OK(mr_render_plan_create(&env, &plan));
    if (plan == NULL) return INFINITY;
    const mr_scene *scene = mr_render_plan_scene(plan);
    mr_image *img = NULL;
    MR_CHECK_OK(mr_render(plan, model, values, MR_COMPONENT_FULL, &img));
    double ref[PROBE_COUNT][3], peak = 0.0;
    for (int k = 0; k < PROBE_COUNT; k++) {
        int x = probe_pixels[k][0], y = probe_pixels[k][1];
        MR_CHECK_MSG(interior_pixel(scene, x, y), "probe (%d, %d) is not inside the silhouette", x, y);
        double n[3], view[3];
        MR_CHECK(pixel_geometry(scene, x + 0.5, y + 0.5, n, view));
        env_brute_force(model, values, map, 1.0, rotation, n, view, sub, ref[k]);
        for (int c = 0; c < 3; c++) peak = fmax(peak, ref[k][c]);
    }
    double worst = img == NULL ? INFINITY : 0.0;
    for (int k = 0; k < PROBE_COUNT && img != NULL; k++)
        for (int c = 0; c < 3; c++) {
            double r = mr_image_at(img, probe_pixels[k][0], probe_pixels[k][1])[c];
            worst = fmax(worst, fabs(r - ref[k][c]) / fmax(ref[k][c], 0.05 * peak));
        }
    mr_image_free(img);
    mr_render_plan_free(plan);
    return worst;
}

/* probe_error at 8 x 8 cells per texel: enough for lobes wider than a texel. */
static double env_probe_error(const mr_image *map, double rotation, int samples, int reflection_samples,
                              const mr_brdf_model *model, const double *values) {
    return probe_error(map, rotation, samples, reflection_samples, 8, model, values);
}

/* probe_error at 16 x 16 cells per texel (0.006 rad on a 64 x 32 map), unrotated: for lobes of a few cells. */
static double sharp_probe_error(const mr_image *map, int samples, int reflection_samples, const mr_brdf_model *model,
                                const double *values) {
    return probe_error(map, 0.0, samples, reflection_samples, 16, model, values);
}

MR_TEST(env_brute_force_matches_the_lambert_integral) {
    // First the reference itself: for L(w) = a + b.w the Lambertian integral is exact,
    // albedo/pi * E = albedo * (a + 2/3 b.n); the texel discretisation of a 64x32 map costs ~1e-3.
    mr_image *map = linear_map(64, 32);
    mr_scene scene = env_scene(64, map, 0.0, 0);
    const mr_brdf_model *lambert = mr_brdf_find("lambert");
    double albedo[3] = {0.5, 0.5, 0.5};
    double worst = 0.0;
    for (int k = 0; k < PROBE_COUNT; k++) {
        double n[3], view[3], ref[3];
        MR_CHECK(pixel_geometry(&scene, probe_pixels[k][0] + 0.5, probe_pixels[k][1] + 0.5, n, view));
        env_brute_force(lambert, albedo, map, 1.0, 0.0, n, view, 8, ref);
        double exact[3] = {0.5 * (1.0 + 2.0 / 3.0 * n[1]), 0.5 * (1.0 + 0.8 * 2.0 / 3.0 * n[0]),
                           0.5 * (1.2 - 2.0 / 3.0 * n[2])};
        for (int c = 0; c < 3; c++) worst = fmax(worst, fabs(ref[c] - exact[c]) / exact[c]);
    }
    MR_CHECK_MSG(worst < 2e-3, "brute force vs analytic Lambert integral: %.3g", worst);
    mr_image_free(map);
}

MR_TEST(env_render_matches_brute_force_integral) {
    // The renderer against the sampler-independent integral at the default N and at N = 4096, for a smooth map
    // and a map lit by one small bright patch, for Lambert and for a glossy GGX (alpha 0.3, f0 0.5, no diffuse).
    // The patch takes most of the pattern's directions, so the dim rest of the map (all that lights the probes
    // facing away from the patch) is sampled coarsely: the error measure caps its weight (env_probe_error).
    // With 40 reflection samples (MIS, own limits): the combination must not bias these lobes, which the pattern
    // alone already samples well. At the default N it helps the glossy cases (0.046 -> 0.023, 0.104 -> 0.032); at
    // N 4096 the 40 fixed directions, which do not grow with N, cap the accuracy near the mirror direction
    // (0.0020 -> 0.0081 on the patch map): converged references need more of them (docs/rendering.md).
    const mr_brdf_model *lambert = mr_brdf_find("lambert"), *ggx = mr_brdf_find("ggx");
    double albedo[3] = {0.6, 0.6, 0.6};
    double glossy[7] = {0.3, 0.5, 0.5, 0.5, 0.0, 0.0, 0.0}; // alpha, f0, diffuse
    mr_image *smooth = linear_map(64, 32), *patch = patch_map();
    const struct {
        const char *what;
        const mr_image *map;
        const mr_brdf_model *model;
        const double *values;
        double limit_default, limit_4096;     // measured worst errors x 1.5
        double limit_default_m, limit_4096_m; // the same with 40 reflection samples
    } cases[] = { // measured: 1.03e-2, 9.5e-4, 1.89e-2, 9.5e-4; 4.64e-2, 1.66e-3, 2.28e-2, 3.5e-3;
                  // 3.52e-2, 5.2e-4, 2.25e-2, 1.18e-3; 0.104, 1.98e-3, 3.25e-2, 8.07e-3
        {"smooth map, lambert", smooth, lambert, albedo, 0.016, 1.5e-3, 0.029, 1.5e-3},
        {"smooth map, ggx alpha 0.3", smooth, ggx, glossy, 0.07, 2.5e-3, 0.035, 5.3e-3},
        {"patch map, lambert", patch, lambert, albedo, 0.053, 8e-4, 0.034, 1.8e-3},
        {"patch map, ggx alpha 0.3", patch, ggx, glossy, 0.16, 3e-3, 0.049, 0.0121},
    };
    for (int k = 0; k < (int)(sizeof cases / sizeof cases[0]); k++)
        for (int m = 0; m <= 40; m += 40) {
            const double limit = m ? cases[k].limit_default_m : cases[k].limit_default;
            const double limit_4096 = m ? cases[k].limit_4096_m : cases[k].limit_4096;
            double err = env_probe_error(cases[k].map, 0.0, 0, m, cases[k].model, cases[k].values);
            MR_CHECK_MSG(err <= limit, "%s, default N, M %d: worst relative error %.3g > %.3g", cases[k].what, m, err,
                         limit);
            double err_4096 = env_probe_error(cases[k].map, 0.0, 4096, m, cases[k].model, cases[k].values);
            MR_CHECK_MSG(err_4096 <= limit_4096 && err_4096 < err, "%s, N 4096, M %d: worst relative error %.3g > %.3g "
                         "(default N: %.3g)", cases[k].what, m, err_4096, limit_4096, err);
        }
    mr_image_free(smooth);
    mr_image_free(patch);
}

/* The texel of `map` (rotation 0) that direction w falls in, by render.h's convention (map_direction inverted). */
static const float *map_texel(const mr_image *map, const double w[3]) {
    double u = atan2(w[0], -w[2]) / (2.0 * TEST_PI) + 0.5, v = acos(fmax(-1.0, fmin(1.0, w[1]))) / TEST_PI;
    int i = (int)(u * map->width), j = (int)(v * map->height);
    return mr_image_at(map, i < 0 ? 0 : i >= map->width ? map->width - 1 : i,
                       j < 0 ? 0 : j >= map->height ? map->height - 1 : j);
}

MR_TEST(env_reflection_samples_mirror_known_answer) {
    // A GGX mirror at the models' floor (alpha 1e-4) with f0 = 1 (Fresnel 1 at every angle, no diffuse) reflects
    // exactly the radiance behind its mirror direction r = 2 (n.v) n - v, times a directional albedo within
    // 1e-3 of 1 at this alpha: each probe must hold the texel r falls in. The pattern alone (256 directions)
    // almost never falls inside a 2e-4 rad lobe: the probes are then far off, which is what reflection samples
    // are for. The map is smooth (neighbouring texels differ by < 2 %), so a lobe across a texel border is fine.
    // Measured: 1 (the pattern alone) and 9.8e-3 (40 reflection samples; the probes sit ~1 % low, the share of
    // the lobe's heavy tail that 8 directions per lobe leave out).
    mr_image *map = linear_map(256, 128);
    const mr_brdf_model *ggx = mr_brdf_find("ggx");
    double mirror[7] = {1e-4, 1.0, 1.0, 1.0, 0.0, 0.0, 0.0};
    double worst[2] = {0.0, 0.0};
    const int counts[2] = {0, 40};
    for (int m = 0; m < 2; m++) {
        mr_scene scene = env_scene(64, map, 0.0, 256);
        scene.lights[0].reflection_samples = counts[m];
        mr_render_plan *plan = NULL;
        MR_CHECK_OK(mr_render_plan_create(&scene, &plan));
        mr_image *img = NULL;
        if (plan != NULL) MR_CHECK_OK(mr_render(plan, ggx, mirror, MR_COMPONENT_FULL, &img));
        if (img == NULL) {
            mr_render_plan_free(plan);
            continue;
        }
        const long hits = mr_render_plan_lit_pixel_count(plan);
        MR_CHECK_MSG(mr_render_plan_reflection_sample_count(plan) <= (long)counts[m] * hits * 16 &&
                     (counts[m] == 0) == (mr_render_plan_reflection_sample_count(plan) == 0),
                     "M %d: %ld reflection samples for %ld lit pixels", counts[m],
                     mr_render_plan_reflection_sample_count(plan), hits);
        for (int k = 0; k < PROBE_COUNT; k++) {
            double n[3], view[3], r[3];
            MR_CHECK(pixel_geometry(&scene, probe_pixels[k][0] + 0.5, probe_pixels[k][1] + 0.5, n, view));
            double nv = n[0] * view[0] + n[1] * view[1] + n[2] * view[2];
            for (int c = 0; c < 3; c++) r[c] = 2.0 * nv * n[c] - view[c];
            const float *expected = map_texel(map, r);
            for (int c = 0; c < 3; c++) {
                double got = mr_image_at(img, probe_pixels[k][0], probe_pixels[k][1])[c];
                worst[m] = fmax(worst[m], fabs(got - expected[c]) / expected[c]);
            }
        }
        for (size_t i = 0; i < mr_image_value_count(img); i++)
            if (!isfinite(img->pixels[i])) {
                MR_CHECK_MSG(0, "M %d: value %zu is %g", counts[m], i, img->pixels[i]);
                break;
            }
        mr_image_free(img);
        mr_render_plan_free(plan);
    }
    MR_CHECK_MSG(worst[0] > 0.5, "the pattern alone: worst relative error %.3g (expected the lobe missed)", worst[0]);
    MR_CHECK_MSG(worst[1] < 0.02, "40 reflection samples: worst relative error %.3g > 0.02", worst[1]);
    mr_image_free(map);
}

MR_TEST(env_reflection_samples_match_brute_force_on_sharp_lobes) {
    // GGX alpha 0.02 (f0 0.9, no diffuse): a lobe of ~0.04 rad, narrower than the pattern's spacing at N = 256
    // (~0.2 rad), against the brute-force integral (16 x 16 cells per texel, 0.006 rad). With 40 reflection
    // samples the probes must be close; the pattern alone must be far worse, and more directions (N 4096) do not
    // rescue it. Smooth map and the patch map (the lobe sees the patch at some probes only). Measured: 0.064 and
    // 0.044 with reflection samples; 0.91 and 1.88 without at N 256, 0.52 and 0.85 at N 4096.
    const mr_brdf_model *ggx = mr_brdf_find("ggx");
    double sharp[7] = {0.02, 0.9, 0.9, 0.9, 0.0, 0.0, 0.0};
    mr_image *maps[2] = {linear_map(64, 32), patch_map()};
    const char *names[2] = {"smooth map", "patch map"};
    const double limits[2] = {0.096, 0.066}; // measured 0.0639, 0.0441
    for (int k = 0; k < 2; k++) {
        double with = sharp_probe_error(maps[k], 256, 40, ggx, sharp);
        double without = sharp_probe_error(maps[k], 256, 0, ggx, sharp);
        double dense = sharp_probe_error(maps[k], 4096, 0, ggx, sharp);
        MR_CHECK_MSG(with < limits[k], "%s, 40 reflection samples: worst relative error %.3g > %.3g", names[k],
                     with, limits[k]);
        MR_CHECK_MSG(without > 3.0 * with && dense > 2.0 * with, "%s: the pattern alone %.3g (N 256), %.3g (N 4096) "
                     "against %.3g with reflection samples", names[k], without, dense, with);
        mr_image_free(maps[k]);
    }
}

/* Map of 64x32 black texels but a bright 2x2 patch straddling the seam at the horizon: u = 0 = 1, v = 0.5,
 * i.e. direction +z (behind the camera) before rotation. */
static mr_image *seam_patch_map(void) {
    mr_image *map = constant_map(64, 32, 3, 0.0f);
    if (map == NULL) return NULL;
    const int columns[2] = {0, 63};
    for (int j = 15; j < 17; j++)
        for (int k = 0; k < 2; k++) {
            float *px = mr_image_at(map, columns[k], j);
            px[0] = px[1] = px[2] = 100.0f;
        }
    return map;
}

/* Luminance-weighted mean column of an image: where its light is, left (small) to right. */
static double brightness_centroid_x(const mr_image *img) {
    double sum = 0.0, weighted = 0.0;
    for (int y = 0; y < img->height; y++)
        for (int x = 0; x < img->width; x++) {
            const float *px = mr_image_at(img, x, y);
            double lum = px[0] + px[1] + px[2];
            sum += lum;
            weighted += lum * (x + 0.5);
        }
    return sum > 0.0 ? weighted / sum : -1.0;
}

static mr_image *render_env(const mr_image *map, double rotation, int samples, const mr_brdf_model *model,
                            const double *values) {
    mr_render_plan *plan = env_plan(64, map, rotation, samples);
    mr_image *img = NULL;
    if (plan != NULL) MR_CHECK_OK(mr_render(plan, model, values, MR_COMPONENT_FULL, &img));
    mr_render_plan_free(plan);
    return img;
}

MR_TEST(env_rotation_by_whole_turns_is_the_identity) {
    const mr_brdf_model *ggx = mr_brdf_find("ggx");
    double values[MR_BRDF_MAX_VALUES];
    mr_brdf_default_values(ggx, values);
    values[4] = values[5] = values[6] = 0.3; // some diffuse as well
    mr_image *map = patch_map();
    mr_image *zero = render_env(map, 0.0, 0, ggx, values);
    const double turns[] = {360.0, -360.0, 720.0, 3600.0};
    for (int k = 0; k < 4; k++) {
        mr_image *img = render_env(map, turns[k], 0, ggx, values);
        MR_CHECK_MSG(same_pixels(zero, img), "rotation %g differs from 0", turns[k]);
        mr_image_free(img);
    }
    // A non-trivial rotation does change the image (the patch is not on the axis).
    mr_image *quarter = render_env(map, 90.0, 0, ggx, values);
    MR_CHECK(!same_pixels(zero, quarter));
    mr_image_free(quarter);
    mr_image_free(zero);
    mr_image_free(map);
}

MR_TEST(env_constant_map_is_rotation_invariant) {
    // The pattern turns with the map, so the images differ by the pattern's error only: at most twice the
    // known-answer bound at the default N (1.2 % of albedo * L), as both images carry it.
    const mr_brdf_model *lambert = mr_brdf_find("lambert");
    double albedo[3] = {0.5, 0.5, 0.5};
    mr_image *map = constant_map(32, 16, 1, 1.0f);
    mr_image *zero = render_env(map, 0.0, 0, lambert, albedo);
    const double angles[] = {37.0, 90.0, -123.0};
    for (int k = 0; k < 3 && zero != NULL; k++) {
        mr_image *img = render_env(map, angles[k], 0, lambert, albedo);
        if (img == NULL) continue;
        double worst = 0.0;
        for (size_t i = 0; i < mr_image_value_count(img); i++)
            worst = fmax(worst, fabs(img->pixels[i] - zero->pixels[i]));
        MR_CHECK_MSG(worst <= 2.0 * 0.012 * 0.5, "rotation %g: difference %.3g", angles[k], worst); // measured 4.1e-3
        mr_image_free(img);
    }
    mr_image_free(zero);
    mr_image_free(map);
}

MR_TEST(env_rotation_moves_light_from_plus_z_to_plus_x) {
    // render.h: a rotation of +90 degrees takes what lay at +z (behind the camera: the sphere's front is lit)
    // towards +x (the camera's right: the right half is lit); -90 towards -x.
    const mr_brdf_model *lambert = mr_brdf_find("lambert");
    double albedo[3] = {0.5, 0.5, 0.5};
    mr_image *map = seam_patch_map();
    mr_image *front = render_env(map, 0.0, 0, lambert, albedo);
    mr_image *right = render_env(map, 90.0, 0, lambert, albedo);
    mr_image *left = render_env(map, -90.0, 0, lambert, albedo);
    if (front != NULL && right != NULL && left != NULL) {
        double cf = brightness_centroid_x(front), cr = brightness_centroid_x(right), cl = brightness_centroid_x(left);
        MR_CHECK_MSG(fabs(cf - 32.0) < 1.0, "unrotated: light centroid at column %.2f, expected the centre", cf);
        MR_CHECK_MSG(cr > 40.0, "+90 degrees: light centroid at column %.2f, expected the right (+x)", cr);
        MR_CHECK_MSG(cl < 24.0, "-90 degrees: light centroid at column %.2f, expected the left (-x)", cl);
        MR_CHECK_NEAR(cr - 32.0, 32.0 - cl, 0.05);
        // At +90 the sphere's left limb (normal -x) faces away from the light: black.
        MR_CHECK(mr_image_at(right, 9, 32)[1] == 0.0f && mr_image_at(right, 54, 32)[1] > 0.0f);
    }
    // The same rotations against the brute-force integral of the documented direction and rotation formulas,
    // also for an angle that is not a quarter turn (a wrong sign or axis gives errors of order 1).
    double err_right = env_probe_error(map, 90.0, 4096, 0, lambert, albedo);
    double err_odd = env_probe_error(map, -37.0, 4096, 0, lambert, albedo);
    // Limit 6e-3: the measured 2.1e-3 (+90), 3.5e-5 (-37) and 4.1e-3 (glossy, -60) with margin.
    MR_CHECK_MSG(err_right < 6e-3 && err_odd < 6e-3,
                 "rotated patch vs brute force: %.3g (+90), %.3g (-37)", err_right, err_odd);
    mr_image *patch = patch_map();
    const mr_brdf_model *ggx = mr_brdf_find("ggx");
    double glossy[7] = {0.3, 0.5, 0.5, 0.5, 0.0, 0.0, 0.0};
    double err_glossy = env_probe_error(patch, -60.0, 4096, 0, ggx, glossy);
    MR_CHECK_MSG(err_glossy < 6e-3, "patch map at -60 degrees, ggx: %.3g", err_glossy);
    // Reflection samples look the map up through the same rotation (env_source_lookup's inverse mapping).
    double err_glossy_mis = env_probe_error(patch, -60.0, 4096, 40, ggx, glossy);
    MR_CHECK_MSG(err_glossy_mis < 6e-3, "patch map at -60 degrees, ggx, 40 reflection samples: %.3g", err_glossy_mis);

    mr_image_free(patch);
    mr_image_free(front);
    mr_image_free(right);
    mr_image_free(left);
    mr_image_free(map);
}

MR_TEST(env_renders_are_identical_for_one_and_two_threads) {
    // Plan creation and render, environment (with reflection samples) + point light, a textured parameter:
    // byte-identical for 1 and 2 OpenMP threads.
    mr_image *map = patch_map(), *alpha_map = linear_map(16, 8);
    mr_scene scene = mr_scene_fit(&(mr_fit_scene_options){96, MR_FIT_LIGHT_45, 0});
    scene.light_count = 2;
    scene.lights[1] = mr_light_environment(map, 0.5, 30.0, 1024);
    scene.lights[1].reflection_samples = 40;
    const mr_brdf_model *ggx = mr_brdf_find("ggx");
    double values[7] = {0.2, 0.04, 0.04, 0.04, 0.3, 0.2, 0.1};
    mr_param_textures textures = {0};
    MR_CHECK_OK(mr_param_textures_set(&textures, ggx, "alpha", alpha_map, 2)); // B = 1.2 - w.z: 0.2 .. 2.2
    mr_image *img[2] = {NULL, NULL};
    long samples[2] = {0, 0};
    for (int t = 0; t < 2; t++) {
        scene.threads = t + 1;
        mr_render_plan *plan = NULL;
        MR_CHECK_OK(mr_render_plan_create(&scene, &plan));
        if (plan == NULL) continue;
        samples[t] = mr_render_plan_sample_count(plan);
        MR_CHECK_OK(mr_render_textured(plan, ggx, values, &textures, MR_COMPONENT_FULL, &img[t]));
        mr_render_plan_free(plan);
    }
    MR_CHECK(samples[0] == samples[1] && samples[0] > 0);
    MR_CHECK(same_pixels(img[0], img[1]));
    mr_image_free(img[0]);
    mr_image_free(img[1]);
    mr_image_free(map);
    mr_image_free(alpha_map);
}

MR_TEST(env_and_point_light_add_up) {
    // An environment light beside the point light adds its own render; a black environment adds nothing.
    mr_image *map = linear_map(32, 16), *black = constant_map(32, 16, 3, 0.0f);
    mr_scene point = mr_scene_fit(&(mr_fit_scene_options){48, MR_FIT_LIGHT_45, 0});
    point.highlight_samples = 1; // the same samples in every scene (the env-only scene has no highlight disc)
    mr_scene env = point, both = point, point_black = point;
    env.lights[0] = mr_light_environment(map, 0.7, 10.0, 512);
    both.light_count = 2;
    both.lights[1] = env.lights[0];
    point_black.light_count = 2;
    point_black.lights[1] = mr_light_environment(black, 1.0, 0.0, 0);
    const mr_brdf_model *ggx = mr_brdf_find("ggx");
    double values[7] = {0.2, 0.5, 0.3, 0.1, 0.3, 0.2, 0.1};
    mr_image *ip = NULL, *ie = NULL, *iboth = NULL, *iblack = NULL;
    mr_render_plan *plan = NULL;
    const mr_scene *scenes[4] = {&point, &env, &both, &point_black};
    mr_image **outs[4] = {&ip, &ie, &iboth, &iblack};
    for (int k = 0; k < 4; k++) {
        plan = NULL;
        MR_CHECK_OK(mr_render_plan_create(scenes[k], &plan));
        if (plan != NULL) MR_CHECK_OK(mr_render(plan, ggx, values, MR_COMPONENT_FULL, outs[k]));
        mr_render_plan_free(plan);
    }
    if (ip != NULL && ie != NULL && iboth != NULL) {
        double worst = 0.0;
        for (size_t i = 0; i < mr_image_value_count(ip); i++)
            worst = fmax(worst, fabs((double)ip->pixels[i] + ie->pixels[i] - iboth->pixels[i]) /
                                    (1e-3 + iboth->pixels[i]));
        MR_CHECK_NEAR(worst, 0.0, 1e-6);
    }
    MR_CHECK(same_pixels(ip, iblack));
    mr_image_free(ip);
    mr_image_free(ie);
    mr_image_free(iboth);
    mr_image_free(iblack);
    mr_image_free(map);
    mr_image_free(black);
}

MR_TEST(env_black_map_renders_black) {
    // No direction carries light: no pixel is lit, the image is the (black) background, finite everywhere, for
    // every model; grey and RGBA maps too.
    const int channels[3] = {1, 3, 4};
    for (int k = 0; k < 3; k++) {
        mr_image *black = constant_map(16, 8, channels[k], 0.0f);
        mr_render_plan *plan = env_plan(32, black, 45.0, 0);
        if (plan == NULL) {
            mr_image_free(black);
            continue;
        }
        MR_CHECK(mr_render_plan_lit_pixel_count(plan) == 0);
        MR_CHECK(mr_render_plan_env_sample_count(plan) == 0);
        MR_CHECK(mr_render_plan_object_pixel_count(plan) > 0);
        const mr_brdf_model *const *models = mr_brdf_models();
        for (int m = 0; models[m] != NULL; m++) {
            double values[MR_BRDF_MAX_VALUES];
            mr_brdf_default_values(models[m], values);
            mr_image *img = NULL;
            MR_CHECK_OK(mr_render(plan, models[m], values, MR_COMPONENT_FULL, &img));
            int bad = img == NULL;
            for (size_t i = 0; img != NULL && i < mr_image_value_count(img); i++) bad += img->pixels[i] != 0.0f;
            MR_CHECK_MSG(bad == 0, "%s, %d-channel black map: %d non-black values", models[m]->name, channels[k], bad);
            mr_image_free(img);
        }
        mr_render_plan_free(plan);
        mr_image_free(black);
    }
}

/* mr_render_plan_create must fail with MR_ERR_INVALID_ARG, a message containing `needle`, and no plan. */
static void expect_invalid_scene(const mr_scene *scene, const char *needle, const char *what) {
    mr_render_plan *plan = NULL;
    mr_status status = mr_render_plan_create(scene, &plan);
    MR_CHECK_MSG(status == MR_ERR_INVALID_ARG && plan == NULL, "%s: status %s", what, mr_status_str(status));
    MR_CHECK_MSG(strstr(mr_last_error(), needle) != NULL, "%s: message '%s' lacks '%s'", what, mr_last_error(),
                 needle);
    mr_render_plan_free(plan);
}

MR_TEST(env_bad_inputs_are_rejected) {
    mr_image *map = constant_map(8, 4, 3, 1.0f);
    mr_image *bad = constant_map(8, 4, 3, 1.0f);
    mr_scene scene = env_scene(16, map, 0.0, 0);
    mr_scene s = scene;
    s.lights[0].environment = NULL;
    expect_invalid_scene(&s, "without a map", "NULL map");
    mr_image_at(bad, 3, 2)[1] = NAN;
    s = env_scene(16, bad, 0.0, 0);
    expect_invalid_scene(&s, "(3, 2)", "NaN texel");
    mr_image_at(bad, 3, 2)[1] = INFINITY;
    expect_invalid_scene(&s, "(3, 2)", "infinite texel");
    mr_image_at(bad, 3, 2)[1] = -0.5f;
    expect_invalid_scene(&s, "-0.5", "negative texel");
    mr_image_at(bad, 3, 2)[1] = 1.0f;
    bad->channels = 2; // a 2-channel view of the buffer (mr_image_create makes none)
    expect_invalid_scene(&s, "2 channels", "2-channel map");
    bad->channels = 3;
    s = scene;
    s.lights[0].samples = -1;
    expect_invalid_scene(&s, "-1 environment samples", "negative samples");
    s.lights[0].samples = MR_ENV_MAX_SAMPLES + 1;
    expect_invalid_scene(&s, "65537 environment samples", "samples over the maximum");
    s = scene;
    s.lights[0].reflection_samples = -1;
    expect_invalid_scene(&s, "-1 reflection samples", "negative reflection samples");
    s.lights[0].reflection_samples = MR_ENV_MAX_REFLECTION_SAMPLES + 1;
    expect_invalid_scene(&s, "1025 reflection samples", "reflection samples over the maximum");
    s = scene;
    s.light_count = 3;
    s.lights[0].samples = MR_ENV_MAX_SAMPLES / 2;
    s.lights[1] = mr_light_environment(map, 1.0, 0.0, MR_ENV_MAX_SAMPLES / 2);
    s.lights[2] = mr_light_environment(map, 1.0, 90.0, 0);
    expect_invalid_scene(&s, "at most 65536", "total samples over the maximum");
    s.light_count = 2; // exactly the maximum is fine
    mr_render_plan *plan = NULL;
    MR_CHECK_OK(mr_render_plan_create(&s, &plan));
    mr_render_plan_free(plan);
    s = scene;
    s.lights[0].rotation_degrees = NAN;
    expect_invalid_scene(&s, "rotation", "NaN rotation");
    s.lights[0].rotation_degrees = INFINITY;
    expect_invalid_scene(&s, "rotation", "infinite rotation");
    s = scene;
    s.lights[0].intensity[2] = -1.0;
    expect_invalid_scene(&s, "scale", "negative scale");
    s.lights[0].intensity[2] = NAN;
    expect_invalid_scene(&s, "scale", "NaN scale");
    mr_image_free(map);
    mr_image_free(bad);
}

/* ---- textured spheres ---------------------------------------------------------------------------------------- */

MR_TEST(texture_constant_maps_render_like_values) {
    // render.h: a map of one value renders bit-identically to that value in values[], under a point light and
    // under an environment, including a grey map for an RGB parameter and a channel other than 0.
    const mr_brdf_model *ggx = mr_brdf_find("ggx");
    mr_image *env = linear_map(32, 16);
    mr_scene point_scene = mr_scene_fit(&(mr_fit_scene_options){48, MR_FIT_LIGHT_45, 0});
    mr_scene env_only = env_scene(48, env, 20.0, 512);
    const mr_scene *scenes[2] = {&point_scene, &env_only};
    double values[7] = {0.25, 0.5, 0.375, 0.125, 0.75, 0.5, 0.25};
    mr_image *f0_grey = constant_map(8, 4, 1, 0.375f), *alpha_rgb = constant_map(8, 4, 4, 0.9f);
    mr_image *diffuse_rgb = constant_map(5, 3, 3, 0.0f);
    for (int p = 0; p < 45; p++) diffuse_rgb->pixels[p] = (float)values[4 + p % 3];
    for (int p = 0; p < 32; p++) alpha_rgb->pixels[p * 4 + 2] = 0.25f; // alpha read from channel 2 (B)
    double f0_grey_values[7] = {0.25, 0.375, 0.375, 0.375, 0.75, 0.5, 0.25};
    for (int k = 0; k < 2; k++) {
        mr_render_plan *plan = NULL;
        MR_CHECK_OK(mr_render_plan_create(scenes[k], &plan));
        if (plan == NULL) continue;
        mr_image *plain = NULL, *grey_plain = NULL, *textured = NULL, *grey = NULL, *none = NULL, *null = NULL;
        MR_CHECK_OK(mr_render(plan, ggx, values, MR_COMPONENT_FULL, &plain));
        MR_CHECK_OK(mr_render(plan, ggx, f0_grey_values, MR_COMPONENT_FULL, &grey_plain));
        mr_param_textures textures = {0};
        MR_CHECK_OK(mr_render_textured(plan, ggx, values, &textures, MR_COMPONENT_FULL, &none));
        MR_CHECK_OK(mr_render_textured(plan, ggx, values, NULL, MR_COMPONENT_FULL, &null));
        MR_CHECK_OK(mr_param_textures_set(&textures, ggx, "alpha", alpha_rgb, 2));
        MR_CHECK_OK(mr_param_textures_set(&textures, ggx, "diffuse", diffuse_rgb, 0));
        double junk[7] = {0.9, 0.5, 0.375, 0.125, 0.1, 0.1, 0.1}; // mapped slots are ignored
        MR_CHECK_OK(mr_render_textured(plan, ggx, junk, &textures, MR_COMPONENT_FULL, &textured));
        MR_CHECK_OK(mr_param_textures_set(&textures, ggx, "f0", f0_grey, 0));
        MR_CHECK_OK(mr_render_textured(plan, ggx, junk, &textures, MR_COMPONENT_FULL, &grey));
        const char *what = k == 0 ? "point light" : "environment";
        MR_CHECK_MSG(same_pixels(plain, none) && same_pixels(plain, null), "%s: empty textures differ", what);
        MR_CHECK_MSG(same_pixels(plain, textured), "%s: constant alpha (channel 2) and diffuse maps differ", what);
        MR_CHECK_MSG(same_pixels(grey_plain, grey), "%s: a grey f0 map differs from f0 = 0.375", what);
        mr_image_free(plain);
        mr_image_free(grey_plain);
        mr_image_free(textured);
        mr_image_free(grey);
        mr_image_free(none);
        mr_image_free(null);
        mr_render_plan_free(plan);
    }
    mr_image_free(env);
    mr_image_free(f0_grey);
    mr_image_free(alpha_rgb);
    mr_image_free(diffuse_rgb);
}

MR_TEST(texture_coordinates_follow_the_documented_layout) {
    // Albedo map R = u, G = v at texel centres (ramps, which bilinear filtering reproduces exactly away from the
    // wrap), B = 0.5: every pixel inside the silhouette (box-filtered edge pixels aside) of a frontally lit Lambert
    // sphere must then show rho/pi * I * cos / d^2 with rho = (u, v, 0.5) at its centre, by the documented mapping
    // u = 0.5 + atan2(n.x, n.z) / 2 pi, v = acos(n.y) / pi. So u grows to the right (+x), u = 0.5 faces the
    // camera, v = 0 is up. (Pixel centres at the highlight too.)
    const int W = 64, H = 32;
    mr_image *map = constant_map(W, H, 3, 0.5f);
    for (int j = 0; j < H; j++)
        for (int i = 0; i < W; i++) {
            mr_image_at(map, i, j)[0] = (float)((i + 0.5) / W);
            mr_image_at(map, i, j)[1] = (float)((j + 0.5) / H);
        }
    mr_render_plan *plan = fit_plan_centres(64, MR_FIT_LIGHT_FRONTAL, 0);
    const mr_scene *scene = mr_render_plan_scene(plan);
    const mr_brdf_model *lambert = mr_brdf_find("lambert");
    double values[3] = {0.1, 0.1, 0.1};
    mr_param_textures textures = {0};
    MR_CHECK_OK(mr_param_textures_set(&textures, lambert, "albedo", map, 0));
    mr_image *img = NULL;
    MR_CHECK_OK(mr_render_textured(plan, lambert, values, &textures, MR_COMPONENT_FULL, &img));
    int checked = 0, bad = 0, left = 0, right = 0;
    double worst = 0.0;
    for (int y = 0; y < 64 && img != NULL; y++)
        for (int x = 0; x < 64; x++) {
            if (!interior_pixel(scene, x, y)) continue;
            double n[3], view[3];
            if (!pixel_geometry(scene, x + 0.5, y + 0.5, n, view)) continue;
            double u = 0.5 + atan2(n[0], n[2]) / (2.0 * TEST_PI), v = acos(n[1]) / TEST_PI;
            double rho[3] = {u, v, 0.5};
            for (int c = 0; c < 3; c++) {
                double expected = lambert_reference(scene, x + 0.5, y + 0.5, rho[c]);
                double err = fabs(mr_image_at(img, x, y)[c] - expected);
                worst = fmax(worst, err / expected);
                bad += err > 1e-6 + 1e-5 * expected;
            }
            checked++;
            left += x < 32 && u < 0.5;
            right += x >= 32 && u > 0.5;
        }
    MR_CHECK(checked > 1500 && left + right == checked);
    MR_CHECK_MSG(bad == 0, "%d channel values differ from the (u, v) ramps (worst relative %.3g)", bad, worst);
    // The image's centre shows u = 0.5 (the map's middle column) and v = 0.5 (the equator).
    if (img != NULL) {
        double centre = lambert_reference(scene, 32.0, 32.0, 1.0);
        MR_CHECK_NEAR((mr_image_at(img, 31, 31)[0] + mr_image_at(img, 32, 32)[0]) / 2.0 / centre, 0.5, 0.01);
    }
    mr_image_free(img);
    mr_image_free(map);
    mr_render_plan_free(plan);
}

MR_TEST(texture_halves_land_on_their_sides) {
    // A map whose left half (u < 0.5) holds 0.2 and right half 0.8 paints the sphere's left half (image left)
    // 0.2 and its right half 0.8, away from the seam's bilinear blend; same for a top/bottom split in v.
    mr_image *lr = constant_map(16, 8, 1, 0.2f), *tb = constant_map(16, 8, 1, 0.2f);
    for (int j = 0; j < 8; j++)
        for (int i = 0; i < 16; i++) {
            if (i >= 8) mr_image_at(lr, i, j)[0] = 0.8f;
            if (j >= 4) mr_image_at(tb, i, j)[0] = 0.8f;
        }
    mr_render_plan *plan = fit_plan(64, MR_FIT_LIGHT_FRONTAL);
    const mr_scene *scene = mr_render_plan_scene(plan);
    const mr_brdf_model *lambert = mr_brdf_find("lambert");
    double values[3] = {0.5, 0.5, 0.5};
    mr_param_textures textures = {0};
    MR_CHECK_OK(mr_param_textures_set(&textures, lambert, "albedo", lr, 0));
    mr_image *img_lr = NULL, *img_tb = NULL;
    MR_CHECK_OK(mr_render_textured(plan, lambert, values, &textures, MR_COMPONENT_FULL, &img_lr));
    MR_CHECK_OK(mr_param_textures_set(&textures, lambert, "albedo", tb, 0));
    MR_CHECK_OK(mr_render_textured(plan, lambert, values, &textures, MR_COMPONENT_FULL, &img_tb));
    // Pixels 10 columns (rows) from the centre: u (v) about 0.5 -/+ 0.07, well past the blend of +-1/16.
    const int probes[4][2] = {{22, 32}, {42, 32}, {32, 22}, {32, 42}};
    const double expected_rho[4] = {0.2, 0.8, 0.2, 0.8};
    for (int k = 0; k < 4 && img_lr != NULL && img_tb != NULL; k++) {
        const mr_image *img = k < 2 ? img_lr : img_tb;
        int x = probes[k][0], y = probes[k][1];
        double expected = lambert_reference(scene, x + 0.5, y + 0.5, expected_rho[k]);
        MR_CHECK_MSG(fabs(mr_image_at(img, x, y)[1] - expected) < 1e-5 * expected, "pixel (%d, %d): %.6g, "
                     "expected albedo %.1f: %.6g", x, y, mr_image_at(img, x, y)[1], expected_rho[k], expected);
    }
    mr_image_free(img_lr);
    mr_image_free(img_tb);
    mr_image_free(lr);
    mr_image_free(tb);
    mr_render_plan_free(plan);
}

MR_TEST(texture_bad_inputs_are_rejected) {
    const mr_brdf_model *ward = mr_brdf_find("ward"), *ggx = mr_brdf_find("ggx");
    mr_image *rgb = constant_map(4, 4, 3, 0.5f), *grey = constant_map(4, 4, 1, 0.5f);
    mr_param_textures textures = {0};
    MR_CHECK(mr_param_textures_set(&textures, ward, "trim", grey, 0) == MR_ERR_INVALID_ARG);
    MR_CHECK(strstr(mr_last_error(), "trim") != NULL && strstr(mr_last_error(), "switch") != NULL);
    MR_CHECK(mr_param_textures_set(&textures, ggx, "roughness", grey, 0) == MR_ERR_INVALID_ARG);
    MR_CHECK(strstr(mr_last_error(), "roughness") != NULL && strstr(mr_last_error(), "alpha") != NULL);
    MR_CHECK(mr_param_textures_set(&textures, ggx, "alpha", rgb, 3) == MR_ERR_INVALID_ARG);
    MR_CHECK(strstr(mr_last_error(), "channel 3") != NULL);
    MR_CHECK(mr_param_textures_set(&textures, ggx, "alpha", rgb, -1) == MR_ERR_INVALID_ARG);
    MR_CHECK(mr_param_textures_set(&textures, ggx, "alpha", grey, 1) == MR_ERR_INVALID_ARG);
    MR_CHECK(mr_param_textures_set(&textures, ggx, "f0", rgb, 1) == MR_ERR_INVALID_ARG);
    MR_CHECK(strstr(mr_last_error(), "f0") != NULL);
    rgb->channels = 2;
    MR_CHECK(mr_param_textures_set(&textures, ggx, "alpha", rgb, 0) == MR_ERR_INVALID_ARG);
    MR_CHECK(strstr(mr_last_error(), "2 channels") != NULL);
    rgb->channels = 3;
    MR_CHECK(mr_param_textures_set(NULL, ggx, "alpha", rgb, 0) == MR_ERR_INVALID_ARG);
    MR_CHECK(mr_param_textures_set(&textures, ggx, NULL, rgb, 0) == MR_ERR_INVALID_ARG);
    // Failed calls left the textures empty.
    for (int p = 0; p < MR_BRDF_MAX_VALUES; p++) MR_CHECK(textures.maps[p] == NULL && textures.channel[p] == 0);
    // A textures struct filled by hand is checked by the render as well, and nothing is written.
    mr_render_plan *plan = fit_plan(16, MR_FIT_LIGHT_45);
    double values[7] = {0.2, 0.04, 0.04, 0.04, 0.5, 0.5, 0.5};
    mr_image *img = NULL;
    textures.maps[0] = rgb;
    textures.channel[0] = 5;
    MR_CHECK(mr_render_textured(plan, ggx, values, &textures, MR_COMPONENT_FULL, &img) == MR_ERR_INVALID_ARG);
    MR_CHECK(img == NULL && strstr(mr_last_error(), "channel 5") != NULL);
    textures.channel[0] = 0;
    textures.maps[1] = rgb;
    textures.channel[1] = 1;
    MR_CHECK(mr_render_textured(plan, ggx, values, &textures, MR_COMPONENT_FULL, &img) == MR_ERR_INVALID_ARG);
    MR_CHECK(img == NULL);
    // Setting NULL clears a map.
    MR_CHECK_OK(mr_param_textures_set(&textures, ggx, "f0", NULL, 0));
    MR_CHECK(textures.maps[1] == NULL);
    MR_CHECK_OK(mr_render_textured(plan, ggx, values, &textures, MR_COMPONENT_FULL, &img));
    mr_image_free(img);
    mr_render_plan_free(plan);
    mr_image_free(rgb);
    mr_image_free(grey);
}

MR_TEST(texture_non_finite_texels_render_finite) {
    // Design principle 6: a NaN or infinite texel is clamped by prepare() like any value; no NaN leaves.
    const mr_brdf_model *ggx = mr_brdf_find("ggx");
    mr_image *alpha = constant_map(8, 4, 1, 0.3f), *f0 = constant_map(8, 4, 3, 0.5f);
    for (int j = 0; j < 4; j++)
        for (int i = 0; i < 8; i++) {
            mr_image_at(alpha, i, j)[0] = (i + j) % 2 ? NAN : INFINITY;
            mr_image_at(f0, i, j)[1] = (i + j) % 2 ? -INFINITY : NAN;
        }
    mr_image *env = linear_map(16, 8);
    mr_scene scene = env_scene(32, env, 0.0, 128);
    scene.light_count = 2;
    scene.lights[1] = mr_scene_fit(NULL).lights[0];
    mr_render_plan *plan = NULL;
    MR_CHECK_OK(mr_render_plan_create(&scene, &plan));
    mr_param_textures textures = {0};
    MR_CHECK_OK(mr_param_textures_set(&textures, ggx, "alpha", alpha, 0));
    MR_CHECK_OK(mr_param_textures_set(&textures, ggx, "f0", f0, 0));
    double values[7] = {0.2, 0.04, 0.04, 0.04, 0.5, 0.5, 0.5};
    mr_image *img = NULL;
    if (plan != NULL) MR_CHECK_OK(mr_render_textured(plan, ggx, values, &textures, MR_COMPONENT_FULL, &img));
    int bad = img == NULL;
    for (size_t i = 0; img != NULL && i < mr_image_value_count(img); i++)
        bad += !(isfinite(img->pixels[i]) && img->pixels[i] >= 0.0f);
    MR_CHECK_MSG(bad == 0, "%d non-finite or negative values", bad);
    mr_image_free(img);
    mr_render_plan_free(plan);
    mr_image_free(alpha);
    mr_image_free(f0);
    mr_image_free(env);
}

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

/* xorshift64*: the tests' own deterministic random numbers in [0, 1). */
static double test_random(uint64_t *state) {
    *state ^= *state >> 12;
    *state ^= *state << 25;
    *state ^= *state >> 27;
    return (double)((*state * 2685821657736338717ull) >> 11) * (1.0 / 9007199254740992.0);
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
    MR_CHECK_OK(mr_mesh_world_build(&welded.mesh, &w));
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
        MR_CHECK_OK(mr_mesh_world_build(&sphere.mesh, &w));
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
    MR_CHECK_OK(mr_mesh_world_build(&m.mesh, &generated));
    float *given = m.normals;
    float *none = calloc((size_t)m.mesh.vertex_count * 3, sizeof(float));
    float *no_tangents = calloc((size_t)m.mesh.vertex_count * 4, sizeof(float));
    m.mesh.normals = none;
    m.mesh.tangents = no_tangents;
    MR_CHECK_OK(mr_mesh_world_build(&m.mesh, &zeros));
    const int nv = m.mesh.vertex_count;
    for (int v = nv / 2; v < nv; v++) given[3 * v] = given[3 * v + 1] = given[3 * v + 2] = 0.0f;
    m.mesh.normals = given;
    MR_CHECK_OK(mr_mesh_world_build(&m.mesh, &half));
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

/* ---- narrow highlights (mr_scene.highlight_samples, src/render/highlight.c) --------------------------------- */

MR_TEST(highlight_quadrature_shares_each_pixel_exactly) {
    // The disc-rectangle area in closed form: known answers, then a fine grid count.
    const double pi = 3.14159265358979323846;
    MR_CHECK_NEAR(mr_highlight_disc_rect_area(0.5, 0.5, 0.3, 0, 0, 1, 1), pi * 0.09, 1e-14);      // inside
    MR_CHECK_NEAR(mr_highlight_disc_rect_area(1.0, 1.0, 0.3, 0, 0, 1, 1), pi * 0.09 / 4, 1e-14);  // a quadrant
    MR_CHECK_NEAR(mr_highlight_disc_rect_area(1.0, 0.5, 0.3, 0, 0, 1, 1), pi * 0.09 / 2, 1e-14);  // a half
    MR_CHECK_NEAR(mr_highlight_disc_rect_area(3.0, 3.0, 0.3, 0, 0, 1, 1), 0.0, 0.0);             // apart
    MR_CHECK_NEAR(mr_highlight_disc_rect_area(0.5, 0.5, 2.0, 0, 0, 1, 1), 1.0, 1e-14);           // covering
    uint64_t rng = 5;
    for (int k = 0; k < 40; k++) {
        double cx = 1.5 * test_random(&rng) - 0.25, cy = 1.5 * test_random(&rng) - 0.25, r = 0.05 + test_random(&rng);
        const int n = 600;
        long inside = 0;
        for (int j = 0; j < n; j++)
            for (int i = 0; i < n; i++) {
                double x = (i + 0.5) / n - cx, y = (j + 0.5) / n - cy;
                inside += x * x + y * y < r * r;
            }
        double exact = mr_highlight_disc_rect_area(cx, cy, r, 0, 0, 1, 1), counted = (double)inside / ((double)n * n);
        MR_CHECK_MSG(fabs(exact - counted) < 3e-3, "disc (%g, %g, %g): %g against a %d^2 grid's %g", cx, cy, r,
                     exact, n, counted);
    }
    // A pixel's samples: inside the pixel, weights adding up to 1, for discs anywhere about it.
    highlight_sample *samples = malloc((size_t)mr_highlight_max_samples(2) * sizeof *samples);
    for (int k = 0; k < 200 && samples != NULL; k++) {
        highlight_disc discs[2] = {{10.0 + 3.0 * test_random(&rng), 10.0 + 3.0 * test_random(&rng), HIGHLIGHT_RADIUS},
                                   {20.0, 20.0, HIGHLIGHT_RADIUS}};
        for (int y = 8; y < 15; y++)
            for (int x = 8; x < 15; x++) {
                int count = mr_highlight_pixel_samples(discs, 2, x, y, samples);
                if (count < 0) continue;
                double sum = 0.0;
                int outside = 0;
                for (int i = 0; i < count; i++) {
                    sum += samples[i].weight;
                    const highlight_sample *q = &samples[i];
                    outside += !(q->x >= x && q->x <= x + 1 && q->y >= y && q->y <= y + 1);
                }
                MR_CHECK_MSG(fabs(sum - 1.0) < 1e-12 && outside == 0 && count <= mr_highlight_max_samples(2),
                             "disc at (%g, %g), pixel (%d, %d): %d samples, weights sum to %.15g, %d outside",
                             discs[0].cx, discs[0].cy, x, y, count, sum, outside);
            }
    }
    free(samples);
}

/* The sum of a render's first channel over the image, times 4096 / pixels: the light a 64^2 image holds, the
 * same at any size when every pixel holds its area's mean radiance. */
static double image_light(const mr_image *img) {
    double sum = 0.0;
    for (int i = 0; i < img->width * img->height; i++) sum += img->pixels[3 * i];
    return sum * 4096.0 / ((double)img->width * img->height);
}

static double specular_light(int size, mr_fit_light light, double alpha, int highlight_samples) {
    const mr_brdf_model *ggx = mr_brdf_find("ggx");
    double values[MR_BRDF_MAX_VALUES];
    mr_brdf_default_values(ggx, values);
    char assignment[64];
    snprintf(assignment, sizeof assignment, "alpha=%g", alpha);
    MR_CHECK_OK(mr_brdf_parse_assignment(ggx, assignment, values));
    MR_CHECK_OK(mr_brdf_parse_assignment(ggx, "f0=0.04", values));
    mr_scene scene = mr_scene_fit(&(mr_fit_scene_options){size, light, 0});
    scene.highlight_samples = highlight_samples;
    mr_render_plan *plan = NULL;
    mr_image *img = NULL;
    MR_CHECK_OK(mr_render_plan_create(&scene, &plan));
    if (plan != NULL) MR_CHECK_OK(mr_render(plan, ggx, values, MR_COMPONENT_SPECULAR, &img));
    double light_sum = img ? image_light(img) : NAN;
    mr_image_free(img);
    mr_render_plan_free(plan);
    return light_sum;
}

MR_TEST(narrow_highlights_keep_their_energy) {
    // The reference: a lobe pixel centres resolve (alpha 0.02 is 9 pixels wide at 1024^2). A narrower lobe
    // carries the same light (GGX is normalised; its F and G hardly change below 0.02): at 64^2 the pixels
    // about the highlight must hold it, down to the models' alpha 1e-4, where pixel centres alone see ~nothing.
    for (int light = 0; light < MR_FIT_LIGHT_COUNT; light++) {
        const double reference = specular_light(1024, (mr_fit_light)light, 0.02, 1);
        const double alphas[] = {1e-4, 1e-3, 0.005, 0.02};
        for (int a = 0; a < 4; a++) {
            double held = specular_light(64, (mr_fit_light)light, alphas[a], 0);
            printf("    light %s, alpha %g: 64^2 holds %.4f of the 1024^2 reference's light\n",
                   mr_fit_light_name((mr_fit_light)light), alphas[a], held / reference);
            MR_CHECK_MSG(fabs(held / reference - 1.0) < 0.03, "light %s, alpha %g: %.4f of the light",
                         mr_fit_light_name((mr_fit_light)light), alphas[a], held / reference);
        }
        double centres = specular_light(64, (mr_fit_light)light, 1e-4, 1);
        MR_CHECK_MSG(centres < 0.1 * reference, "pixel centres alone hold %.4f of the light", centres / reference);
    }
    // The Lambert sphere's pixels about the highlight hold their area's mean radiance: each one against a
    // 64 x 64 sub-pixel average of the independent formula.
    mr_render_plan *plan = fit_plan(48, MR_FIT_LIGHT_45);
    const mr_scene *scene = mr_render_plan_scene(plan);
    double values[3] = {0.5, 0.5, 0.5};
    mr_render_plan *centres = fit_plan_centres(48, MR_FIT_LIGHT_45, 0);
    mr_image *img = NULL, *at_centres = NULL;
    MR_CHECK_OK(mr_render(plan, mr_brdf_find("lambert"), values, MR_COMPONENT_FULL, &img));
    MR_CHECK_OK(mr_render(centres, mr_brdf_find("lambert"), values, MR_COMPONENT_FULL, &at_centres));
    int checked = 0;
    double error_sq = 0.0, centre_error_sq = 0.0;
    for (int y = 0; img != NULL && at_centres != NULL && y < 48; y++)
        for (int x = 0; x < 48; x++) {
            double got = mr_image_at(img, x, y)[0];
            if (got == mr_image_at(at_centres, x, y)[0]) continue; // not about the highlight: its centre
            double sum = 0.0;
            const int n = 64;
            for (int j = 0; j < n; j++)
                for (int i = 0; i < n; i++) sum += lambert_reference(scene, x + (i + 0.5) / n, y + (j + 0.5) / n, 0.5);
            double mean = sum / (n * n);
            checked++;
            double centre = mr_image_at(at_centres, x, y)[0];
            error_sq += (got - mean) * (got - mean);
            centre_error_sq += (centre - mean) * (centre - mean);
            MR_CHECK_MSG(fabs(got - mean) < 2e-4 * mean, "pixel (%d, %d): %.8g against the area mean %.8g", x, y, got,
                         mean);
        }
    // Smooth shading is integrated within 2e-4 of the mean (measured RMS 1.1e-5: a sector two pixels share is
    // divided between them in eighths of its size), better than pixel centres do, whose error is the shading's
    // curvature (measured RMS 7.9e-5).
    printf("    Lambert: %d pixels integrated, RMS error %.3g (pixel centres: %.3g)\n", checked,
           sqrt(error_sq / (checked > 0 ? checked : 1)), sqrt(centre_error_sq / (checked > 0 ? checked : 1)));
    MR_CHECK_MSG(checked >= 4 && error_sq < 0.5 * centre_error_sq, "%d pixels integrated about the highlight, squared "
                 "error %.3g against their centres' %.3g", checked, error_sq, centre_error_sq);
    mr_image_free(img);
    mr_image_free(at_centres);
    mr_render_plan_free(plan);
    mr_render_plan_free(centres);
}

/* The closer look of remaps (render_internal.h): one plan, built by whichever thread asks first, the same for
 * every later caller, with the zoomed camera, and freed with its plan (ASan's leak check in make asan). */
MR_TEST(closer_look_plan_is_built_once_and_shared) {
    mr_scene scene = mr_scene_fit(&(mr_fit_scene_options){64, MR_FIT_LIGHT_45, 0});
    mr_render_plan *plan = NULL;
    MR_CHECK_OK(mr_render_plan_create(&scene, &plan));
    if (plan == NULL) return;
    const mr_render_plan *seen[2] = {NULL, NULL};
    mr_status status[2] = {MR_ERR_CANCELLED, MR_ERR_CANCELLED}; // neither yet
#pragma omp parallel for num_threads(2)
    for (int t = 0; t < 2; t++) status[t] = mr_render_plan_zoomed(plan, 8.0, &seen[t]);
    MR_CHECK(status[0] == MR_OK && status[1] == MR_OK);
    MR_CHECK(seen[0] != NULL && seen[0] == seen[1]);
    if (seen[0] != NULL) {
        const mr_scene *zoomed = mr_render_plan_scene(seen[0]);
        MR_CHECK(zoomed->width == 64 && zoomed->height == 64);
        MR_CHECK(zoomed->camera.fov_y_degrees < scene.camera.fov_y_degrees / 4.0);
    }
    const mr_render_plan *again = NULL;
    MR_CHECK_OK(mr_render_plan_zoomed(plan, 8.0, &again));
    MR_CHECK(again == seen[0]);
    MR_CHECK(mr_render_plan_zoomed(plan, 4.0, &again) == MR_ERR_INVALID_ARG);
    MR_CHECK(mr_render_plan_bytes(plan) > mr_render_plan_bytes(seen[0]));
    mr_render_plan_free(plan);
}

MR_TEST_MAIN(MR_TEST_ENTRY(lambert_sphere_matches_point_light_formula),
             MR_TEST_ENTRY(closer_look_plan_is_built_once_and_shared),
             MR_TEST_ENTRY(highlight_quadrature_shares_each_pixel_exactly),
             MR_TEST_ENTRY(narrow_highlights_keep_their_energy),
             MR_TEST_ENTRY(threads_follow_the_scene_and_the_work),
             MR_TEST_ENTRY(edge_filtering_measures_the_silhouette),
             MR_TEST_ENTRY(coverage_mask_is_the_plans_coverage),
             MR_TEST_ENTRY(background_fills_the_uncovered_part_of_each_pixel),
             MR_TEST_ENTRY(frontal_centre_pixel_known_value),
             MR_TEST_ENTRY(silhouette_area_matches_projection),
             MR_TEST_ENTRY(diffuse_plus_specular_equals_full_for_every_model),
             MR_TEST_ENTRY(images_have_the_scene_symmetries),
             MR_TEST_ENTRY(renders_are_identical_for_any_thread_count_and_plan_reuse),
             MR_TEST_ENTRY(render_into_rejects_wrong_image_size),
             MR_TEST_ENTRY(invalid_scenes_are_rejected_with_the_field_named),
             MR_TEST_ENTRY(two_lights_add_up),
             MR_TEST_ENTRY(env_constant_map_lambert_known_answer),
             MR_TEST_ENTRY(env_map_channels_scale_and_sample_counts),
             MR_TEST_ENTRY(env_brute_force_matches_the_lambert_integral),
             MR_TEST_ENTRY(env_render_matches_brute_force_integral),
             MR_TEST_ENTRY(env_reflection_samples_mirror_known_answer),
             MR_TEST_ENTRY(env_reflection_samples_match_brute_force_on_sharp_lobes),
             MR_TEST_ENTRY(env_rotation_by_whole_turns_is_the_identity),
             MR_TEST_ENTRY(env_constant_map_is_rotation_invariant),
             MR_TEST_ENTRY(env_rotation_moves_light_from_plus_z_to_plus_x),
             MR_TEST_ENTRY(env_renders_are_identical_for_one_and_two_threads),
             MR_TEST_ENTRY(env_and_point_light_add_up),
             MR_TEST_ENTRY(env_black_map_renders_black),
             MR_TEST_ENTRY(env_bad_inputs_are_rejected),
             MR_TEST_ENTRY(texture_constant_maps_render_like_values),
             MR_TEST_ENTRY(texture_coordinates_follow_the_documented_layout),
             MR_TEST_ENTRY(texture_halves_land_on_their_sides),
             MR_TEST_ENTRY(texture_bad_inputs_are_rejected),
             MR_TEST_ENTRY(texture_non_finite_texels_render_finite),
             MR_TEST_ENTRY(mesh_sphere_matches_the_analytic_sphere),
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
             MR_TEST_ENTRY(mesh_single_sided_backs_let_light_through),
             MR_TEST_ENTRY(mesh_surfaces_normal_occlusion_and_emission_known_answers),
             MR_TEST_ENTRY(mesh_zero_normals_and_tangents_are_generated_per_vertex))
