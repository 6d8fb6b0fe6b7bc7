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
#include "render_support.h"


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

MR_TEST(texels_that_are_no_values_are_read_as_documented) {
    // render.h, mr_param_textures: a NaN or infinite texel reads as 0 and a negative one as 0, before the blend, so
    // a map holding them renders exactly as the map with those texels replaced by 0; mr_material_map_invalid_texels
    // counts them per map, over the channels the parameter reads (a texel once, non-finite before negative).
    const mr_brdf_model *gltf = mr_brdf_find("gltf");
    mr_image *bad = constant_map(8, 8, 3, 0.5f), *sane = constant_map(8, 8, 3, 0.5f);
    mr_image_at(bad, 1, 1)[0] = NAN;
    mr_image_at(bad, 3, 2)[1] = INFINITY;
    mr_image_at(bad, 4, 2)[2] = -INFINITY;
    mr_image_at(bad, 4, 2)[0] = -1.0f; // non-finite in another channel: counted once, as not finite
    mr_image_at(bad, 5, 6)[2] = -0.25f;
    mr_image_at(bad, 6, 6)[2] = -0.25f;
    mr_image_at(sane, 1, 1)[0] = 0.0f;
    mr_image_at(sane, 3, 2)[1] = 0.0f;
    mr_image_at(sane, 4, 2)[2] = 0.0f;
    mr_image_at(sane, 4, 2)[0] = 0.0f;
    mr_image_at(sane, 5, 6)[2] = 0.0f;
    mr_image_at(sane, 6, 6)[2] = 0.0f;
    mr_material *m = NULL;
    MR_CHECK_OK(mr_material_create(gltf, &m));
    if (m == NULL) return;
    mr_image *blue = NULL;
    MR_CHECK_OK(mr_image_clone(bad, &blue));
    MR_CHECK_OK(mr_material_add_map(m, "base_color", bad, 0, "bad.exr", NULL));
    MR_CHECK_OK(mr_material_add_map(m, "metallic", blue, 2, "bad.exr", NULL));
    size_t nonfinite = 99, negative = 99;
    MR_CHECK_OK(mr_material_map_invalid_texels(m, 0, &nonfinite, &negative));
    MR_CHECK_MSG(nonfinite == 3 && negative == 2, "base_color: %zu not finite, %zu negative", nonfinite, negative);
    MR_CHECK_OK(mr_material_map_invalid_texels(m, 1, &nonfinite, &negative));
    MR_CHECK_MSG(nonfinite == 1 && negative == 2, "metallic (B): %zu not finite, %zu negative", nonfinite, negative);
    MR_CHECK(mr_material_map_invalid_texels(m, 2, &nonfinite, &negative) == MR_ERR_INVALID_ARG);
    mr_clear_error();

    mr_render_plan *plan = NULL;
    mr_scene scene = mr_scene_fit(&(mr_fit_scene_options){48, MR_FIT_LIGHT_45, 0});
    MR_CHECK_OK(mr_render_plan_create(&scene, &plan));
    mr_image *from_bad = NULL, *from_sane = NULL;
    mr_param_textures textures = {0};
    MR_CHECK_OK(mr_param_textures_set(&textures, gltf, "base_color", sane, 0));
    MR_CHECK_OK(mr_param_textures_set(&textures, gltf, "metallic", sane, 2));
    if (plan != NULL) {
        MR_CHECK_OK(mr_render_textured(plan, gltf, m->values, &m->textures, MR_COMPONENT_FULL, &from_bad));
        MR_CHECK_OK(mr_render_textured(plan, gltf, m->values, &textures, MR_COMPONENT_FULL, &from_sane));
        MR_CHECK(from_bad != NULL && from_sane != NULL && same_pixels(from_bad, from_sane));
    }
    mr_image_free(from_bad);
    mr_image_free(from_sane);
    mr_render_plan_free(plan);
    mr_material_free(m);
    mr_image_free(sane);
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
    // Design principle 6: a NaN or infinite texel is read as 0 (render.h, mr_param_textures); no NaN leaves.
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

MR_TEST(highlight_quadrature_made_once_matches_pixel_by_pixel) {
    // The plan's quadrature (every pixel's samples made at once) against the definition, pixel by pixel: the same
    // samples in the same order, bit for bit, for one or two discs anywhere, centres on pixel edges and corners,
    // shrunk discs, and the pixels around and beyond them.
    uint64_t rng = 11;
    highlight_sample *expected = malloc((size_t)mr_highlight_max_samples(2) * sizeof *expected);
    highlight_sample *got = malloc((size_t)mr_highlight_max_samples(2) * sizeof *got);
    long pixels_checked = 0;
    for (int k = 0; k < 60 && expected != NULL && got != NULL; k++) {
        const double snap = k % 3 == 0 ? 0.5 : 1.0; // every third layout: centres on pixel edges or corners
        highlight_disc discs[2] = {{10.0 + snap * floor(6.0 * test_random(&rng)) / 2.0,
                                    10.0 + snap * floor(6.0 * test_random(&rng)) / 2.0, HIGHLIGHT_RADIUS},
                                   {10.0 + 4.0 * test_random(&rng), 16.0 + test_random(&rng), HIGHLIGHT_RADIUS}};
        if (k % 3 != 0) {
            discs[0].cx = 10.0 + 3.0 * test_random(&rng);
            discs[0].cy = 10.0 + 3.0 * test_random(&rng);
        }
        const int count = 1 + k % 2;
        if (count == 2) { // as find_highlights shrinks them: half the distance between them, at most
            const double half = 0.5 * hypot(discs[0].cx - discs[1].cx, discs[0].cy - discs[1].cy);
            discs[0].radius = discs[1].radius = fmin(HIGHLIGHT_RADIUS, half);
        }
        highlight_quadrature q;
        MR_CHECK(mr_highlight_quadrature_build(discs, count, &q));
        for (int y = 6; y < 21; y++)
            for (int x = 6; x < 18; x++) {
                const int n = mr_highlight_pixel_samples(discs, count, x, y, expected);
                const int m = mr_highlight_quadrature_pixel(&q, x, y, got);
                int same = n == m;
                for (int i = 0; same && i < n; i++)
                    same = memcmp(&expected[i], &got[i], sizeof got[i]) == 0;
                MR_CHECK_MSG(same, "discs (%g, %g, %g) (%g, %g, %g) x %d, pixel (%d, %d): %d samples, quadrature %d",
                             discs[0].cx, discs[0].cy, discs[0].radius, discs[1].cx, discs[1].cy, discs[1].radius,
                             count, x, y, n, m);
                pixels_checked += n > 0;
            }
        mr_highlight_quadrature_free(&q);
    }
    MR_CHECK(pixels_checked > 1000);
    free(expected);
    free(got);
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

/* The closer look of remaps (render.h, mr_render_plan_zoomed): one plan, built by whichever thread asks first, the
 * same for every later caller, with the zoomed camera, and freed with its plan (ASan's leak check in make asan). */
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

/* A plan's primary rays four at a time (AVX2, render.c sphere_rays4) give the plan of one at a time, bit for bit:
 * the same coverage, counts and renders (tolerance zero: the lanes do the scalar code's operations, unfused, in its
 * order), on the fit scene from both lights, its closer look, small and odd sizes (a row's tail traced one at a
 * time), one edge ray and many, and pixel centres only. Where the CPU lacks AVX2 both plans are the scalar one. */
MR_TEST(plan_rays_four_at_a_time_match_one_at_a_time) {
    mr_scene scenes[9];
    int count = 0;
    scenes[count++] = mr_scene_fit(&(mr_fit_scene_options){64, MR_FIT_LIGHT_45, 0});
    scenes[count++] = mr_scene_fit(&(mr_fit_scene_options){64, MR_FIT_LIGHT_FRONTAL, 0});
    if (mr_scene_zoom_on_highlight(&scenes[0], 8.0, &scenes[count])) count++;
    scenes[count++] = mr_scene_fit(&(mr_fit_scene_options){16, MR_FIT_LIGHT_45, 0});
    scenes[count++] = mr_scene_fit(&(mr_fit_scene_options){37, MR_FIT_LIGHT_45, 0});
    scenes[count] = scenes[0];
    scenes[count++].edge_samples = 1;
    scenes[count] = scenes[0];
    scenes[count++].edge_samples = 7;
    scenes[count] = scenes[1];
    scenes[count++].highlight_samples = 1;
    MR_CHECK(count == 8);
    const mr_brdf_model *models[3] = {mr_brdf_find("lambert"), mr_brdf_find("ward"), mr_brdf_find("ggx")};
    for (int s = 0; s < count; s++) {
        mr_scene *scene = &scenes[s];
        scene->threads = 1;
        mr_render_plan *one = NULL, *four = NULL;
        MR_CHECK_OK(mr_render_plan_create_rays(scene, MR_PLAN_RAYS_SCALAR, &one));
        MR_CHECK_OK(mr_render_plan_create_rays(scene, MR_PLAN_RAYS_VECTOR, &four));
        if (one == NULL || four == NULL) {
            mr_render_plan_free(one);
            mr_render_plan_free(four);
            continue;
        }
        const size_t pixels = (size_t)scene->width * (size_t)scene->height;
        MR_CHECK_MSG(mr_render_plan_lit_pixel_count(one) == mr_render_plan_lit_pixel_count(four) &&
                         mr_render_plan_object_pixel_count(one) == mr_render_plan_object_pixel_count(four) &&
                         mr_render_plan_sample_count(one) == mr_render_plan_sample_count(four),
                     "scene %d: lit %d/%d, object %d/%d, samples %ld/%ld", s, mr_render_plan_lit_pixel_count(one),
                     mr_render_plan_lit_pixel_count(four), mr_render_plan_object_pixel_count(one),
                     mr_render_plan_object_pixel_count(four), mr_render_plan_sample_count(one),
                     mr_render_plan_sample_count(four));
        MR_CHECK_MSG(memcmp(mr_render_plan_coverage(one), mr_render_plan_coverage(four), pixels * sizeof(float)) == 0,
                     "scene %d: coverage differs", s);
        for (int m = 0; m < 3; m++) {
            MR_CHECK(models[m] != NULL);
            if (models[m] == NULL) continue;
            double values[MR_BRDF_MAX_VALUES];
            mr_brdf_default_values(models[m], values);
            mr_image *a = NULL, *b = NULL;
            MR_CHECK_OK(mr_image_create(scene->width, scene->height, 3, &a));
            MR_CHECK_OK(mr_image_create(scene->width, scene->height, 3, &b));
            if (a != NULL && b != NULL) {
                MR_CHECK_OK(mr_render_into_threads(one, 1, models[m], values, MR_COMPONENT_FULL, a));
                MR_CHECK_OK(mr_render_into_threads(four, 1, models[m], values, MR_COMPONENT_FULL, b));
                MR_CHECK_MSG(memcmp(a->pixels, b->pixels, 3 * pixels * sizeof(float)) == 0,
                             "scene %d, %s: the renders differ", s, models[m]->name);
            }
            mr_image_free(a);
            mr_image_free(b);
        }
        mr_render_plan_free(one);
        mr_render_plan_free(four);
    }
}

/* mr_image_scale (render's --exposure, remap's irradiance scale): every value, alpha included, times the factor
 * and rounded to float once; NULL does nothing. */
MR_TEST(image_scale_multiplies_every_value_once) {
    mr_image *image = NULL;
    MR_CHECK_OK(mr_image_create(2, 1, 4, &image));
    if (image == NULL) return;
    const float values[8] = {0.1f, 0.2f, 0.3f, 1.0f, 3.0f, -1.0f, 0.0f, 0.5f};
    memcpy(image->pixels, values, sizeof values);
    mr_image_scale(image, 1.0 / 3.0);
    for (int k = 0; k < 8; k++) MR_CHECK(image->pixels[k] == (float)(values[k] * (1.0 / 3.0)));
    mr_image_scale(NULL, 2.0);
    mr_image_free(image);
}

/* mr_scene_fit_light_to_mesh: with no mesh (the unit sphere) the fit scene's light stays where mr_scene_fit put it;
 * a box of corners (1,1,1) and (3,3,3) (centre (2,2,2), bounding radius sqrt 3) gets it at 3 sqrt 3 from its centre
 * towards the camera (frontal), 3 times stronger; turned with the camera (45 degrees: to the camera's right). */
MR_TEST(fit_light_follows_the_mesh_and_the_camera) {
    for (int which = 0; which < MR_FIT_LIGHT_COUNT; which++) {
        mr_fit_scene_options o = {64, (mr_fit_light)which, 0.0};
        const mr_scene fit = mr_scene_fit(&o);
        mr_scene scene = fit;
        MR_CHECK_OK(mr_scene_fit_light_to_mesh(&scene, NULL, (mr_fit_light)which));
        for (int i = 0; i < 3; i++) {
            MR_CHECK_NEAR(scene.lights[0].position[i], fit.lights[0].position[i], 1e-12);
            MR_CHECK(scene.lights[0].intensity[i] == fit.lights[0].intensity[i]);
        }
    }
    float corners[8 * 3];
    for (int v = 0; v < 8; v++)
        for (int i = 0; i < 3; i++) corners[3 * v + i] = (v >> i) & 1 ? 3.0f : 1.0f;
    const mr_mesh box = {.vertex_count = 8, .positions = corners};
    mr_fit_scene_options o = {64, MR_FIT_LIGHT_FRONTAL, 0.0};
    mr_scene scene = mr_scene_fit(&o);
    const double intensity = scene.lights[0].intensity[0], r = sqrt(3.0);
    MR_CHECK_OK(mr_scene_fit_light_to_mesh(&scene, &box, MR_FIT_LIGHT_FRONTAL));
    MR_CHECK_NEAR(scene.lights[0].position[0], 2.0, 1e-12);
    MR_CHECK_NEAR(scene.lights[0].position[1], 2.0, 1e-12);
    MR_CHECK_NEAR(scene.lights[0].position[2], 2.0 + 3.0 * r, 1e-12);
    MR_CHECK_NEAR(scene.lights[0].intensity[0], intensity * 3.0, 1e-12);
    // The camera looking down -x from +x: the light at 45 degrees lies between +x (back) and the camera's right.
    scene = mr_scene_fit(&(mr_fit_scene_options){64, MR_FIT_LIGHT_45, 0.0});
    scene.camera.position[0] = 4.0;
    scene.camera.position[2] = 0.0;
    MR_CHECK_OK(mr_scene_fit_light_to_mesh(&scene, NULL, MR_FIT_LIGHT_45));
    const double h = 3.0 * sqrt(0.5); // up (0,1,0) x back (1,0,0) = (0,0,-1): the right
    MR_CHECK_NEAR(scene.lights[0].position[0], h, 1e-12);
    MR_CHECK_NEAR(scene.lights[0].position[1], 0.0, 1e-12);
    MR_CHECK_NEAR(scene.lights[0].position[2], -h, 1e-12);
    MR_CHECK(mr_scene_fit_light_to_mesh(NULL, NULL, MR_FIT_LIGHT_45) == MR_ERR_INVALID_ARG);
}

MR_TEST_MAIN(MR_TEST_ENTRY(lambert_sphere_matches_point_light_formula),
             MR_TEST_ENTRY(fit_light_follows_the_mesh_and_the_camera),
             MR_TEST_ENTRY(image_scale_multiplies_every_value_once),
             MR_TEST_ENTRY(texels_that_are_no_values_are_read_as_documented),
             MR_TEST_ENTRY(closer_look_plan_is_built_once_and_shared),
             MR_TEST_ENTRY(plan_rays_four_at_a_time_match_one_at_a_time),
             MR_TEST_ENTRY(highlight_quadrature_shares_each_pixel_exactly),
             MR_TEST_ENTRY(highlight_quadrature_made_once_matches_pixel_by_pixel),
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
             MR_TEST_ENTRY(texture_non_finite_texels_render_finite))
