/*
 * test_render.c — the fit-scene renderer: known answers, component sums, symmetry, determinism, validation.
 */
#include <math.h>
#include <omp.h>
#include <string.h>

#include "harness.h"
#include "matremap.h"

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

/* A fit-scene plan; edge_samples 0 is the default silhouette filtering, 1 pixel centres only. */
static mr_render_plan *fit_plan_edges(int size, mr_fit_light light, int edge_samples) {
    mr_fit_scene_options o = {0};
    o.size = size;
    o.light = light;
    mr_scene scene = mr_scene_fit(&o);
    scene.edge_samples = edge_samples;
    mr_render_plan *plan = NULL;
    MR_CHECK_OK(mr_render_plan_create(&scene, &plan));
    return plan;
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
    // Every pixel, both light positions, with pixel-centre sampling (1) and with box-filtered edges (4).
    const mr_brdf_model *lambert = mr_brdf_find("lambert");
    double values[3] = {0.25, 0.5, 0.75};
    for (int light = 0; light < MR_FIT_LIGHT_COUNT; light++)
        for (int n = 1; n <= 4; n += 3) {
            mr_render_plan *plan = fit_plan_edges(96, (mr_fit_light)light, n);
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
    // cos = 1, so L = rho/pi * 10 / 4.
    mr_render_plan *plan = fit_plan(65, MR_FIT_LIGHT_FRONTAL);
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
    mr_render_plan *plan = fit_plan(128, MR_FIT_LIGHT_45);
    const mr_brdf_model *const *models = mr_brdf_models();
    const mr_brdf_model *last = models[mr_brdf_model_count() - 1];
    double values[MR_BRDF_MAX_VALUES], other[MR_BRDF_MAX_VALUES];
    mr_brdf_default_values(last, values);
    mr_brdf_default_values(models[0], other);
    int saved = omp_get_max_threads();
    mr_image *one = NULL, *two = NULL, *between = NULL, *again = NULL;
    omp_set_num_threads(1);
    MR_CHECK_OK(mr_render(plan, last, values, MR_COMPONENT_FULL, &one));
    omp_set_num_threads(2);
    MR_CHECK_OK(mr_render(plan, last, values, MR_COMPONENT_FULL, &two));
    MR_CHECK_OK(mr_render(plan, models[0], other, MR_COMPONENT_FULL, &between));
    MR_CHECK_OK(mr_render(plan, last, values, MR_COMPONENT_FULL, &again));
    omp_set_num_threads(saved);
    size_t bytes = mr_image_value_count(one) * sizeof(float);
    MR_CHECK(memcmp(one->pixels, two->pixels, bytes) == 0);
    MR_CHECK(memcmp(one->pixels, again->pixels, bytes) == 0);
    mr_image_free(one);
    mr_image_free(two);
    mr_image_free(between);
    mr_image_free(again);
    mr_render_plan_free(plan);
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
    // A scene with both fit lights renders the sum of the two single-light renders.
    mr_scene a = mr_scene_fit(&(mr_fit_scene_options){48, MR_FIT_LIGHT_45, 0});
    mr_scene b = mr_scene_fit(&(mr_fit_scene_options){48, MR_FIT_LIGHT_FRONTAL, 0});
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

MR_TEST_MAIN(MR_TEST_ENTRY(lambert_sphere_matches_point_light_formula),
             MR_TEST_ENTRY(edge_filtering_measures_the_silhouette),
             MR_TEST_ENTRY(background_fills_the_uncovered_part_of_each_pixel),
             MR_TEST_ENTRY(frontal_centre_pixel_known_value),
             MR_TEST_ENTRY(silhouette_area_matches_projection),
             MR_TEST_ENTRY(diffuse_plus_specular_equals_full_for_every_model),
             MR_TEST_ENTRY(images_have_the_scene_symmetries),
             MR_TEST_ENTRY(renders_are_identical_for_any_thread_count_and_plan_reuse),
             MR_TEST_ENTRY(render_into_rejects_wrong_image_size),
             MR_TEST_ENTRY(invalid_scenes_are_rejected_with_the_field_named),
             MR_TEST_ENTRY(two_lights_add_up))
