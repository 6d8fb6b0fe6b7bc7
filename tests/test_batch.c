/*
 * test_batch.c — batched BRDF evaluation (brdf.h eval_batch, brdf_batch.h) and the batched render (render.c).
 *
 * Every registered model's batch, with the AVX2/FMA kernels and with the portable ones, equals its eval within the
 * contract's tolerance (MR_BRDF_BATCH_RTOL relative to the pair's largest output, or MR_BRDF_BATCH_ATOL) over random
 * parameter values (tiny roughness, zero reflectances and the range ends among them) and random direction pairs
 * (grazing ones, and some below the horizon); a pair's value does not depend on its place in the batch; the vector
 * exp/log/pow stay within their stated ulp bounds; batched renders equal the per-sample loop within 1e-6 relative
 * (float images of values that differ by ~1e-13), under a point light and under an environment with reflection
 * samples, and are bit-identical on 1 and 2 threads (at 512^2 under the point light).
 * The float kernels (brdf/brdf_float.h) equal eval within MR_BRDF_FLOAT_RTOL (5e-5) of the pair's largest value or
 * MR_BRDF_FLOAT_ATOL, finite everywhere, at random and hard inputs; their exp/log/log1p stay within their stated
 * ulp of libm's expf/logf/log1pf; float renders are bit-identical on 1 and 2 threads, differ from double ones only
 * for models with a float kernel, and the per-plan switch reaches the plan's closer look.
 * The prepared derivatives over a batch (grad_ops eval_batch: the lobe's shape of the Ward and microfacet families)
 * equal grad_ops eval within the double kernels' contract, with both kernels.
 */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "brdf/brdf_batch.h"
#include "brdf/brdf_float.h"
#include "harness.h"
#include "matremap.h"
#include "render/render_internal.h"
#include "render_support.h"

#define PAIRS 301 /* odd: the kernels' remainder loops run too */

/* A random unit vector; one in four grazing (z from 1e-13 to 1e-3), one in sixteen below the horizon. */
static void random_direction(uint64_t *rng, double w[3]) {
    const double u = test_random(rng), kind = test_random(rng);
    double z = 2.0 * test_random(rng) - 1.0;
    if (kind < 0.25)
        z = pow(10.0, -13.0 + 10.0 * test_random(rng));
    else if (kind < 0.9375)
        z = fabs(z);
    const double r = sqrt(fmax(0.0, 1.0 - z * z)), phi = 2.0 * MR_PI * u;
    w[0] = r * cos(phi);
    w[1] = r * sin(phi);
    w[2] = z;
}

/* Random packed values for `model`: draw 0 the defaults, 1 every parameter at its minimum (tiny roughness, zero
 * reflectances), 2 at its maximum, else uniform (log-uniform for log-scale parameters), a reflectance zero now and
 * then. */
static void random_values(const mr_brdf_model *model, uint64_t *rng, int draw, double *values) {
    mr_brdf_default_values(model, values);
    int slot = 0;
    for (int p = 0; p < model->param_count; p++) {
        const mr_brdf_param *param = &model->params[p];
        for (int c = 0; c < param->channels; c++, slot++) {
            const double lo = param->min_value, hi = param->max_value, u = test_random(rng);
            if (draw == 0) continue;
            if (draw == 1) {
                values[slot] = lo;
            } else if (draw == 2) {
                values[slot] = hi;
            } else if (param->role == MR_PARAM_SWITCH) {
                values[slot] = u < 0.5 ? lo : hi;
            } else if ((param->flags & MR_PARAM_LOG_SCALE) && lo > 0.0) {
                values[slot] = lo * pow(hi / lo, u);
            } else {
                values[slot] = test_random(rng) < 0.1 ? lo : lo + (hi - lo) * u;
            }
        }
    }
}

/* Largest |batch - eval| over the pairs, as a multiple of the bound max(rtol * the pair's largest |value|, atol)
 * (<= 1 passes); infinite where the batch is not finite. */
static double worst_ratio_within(const mr_brdf_model *model, const void *state, const mr_brdf_batch *b, double rtol,
                                 double atol, int *worst_pair) {
    double worst = 0.0;
    for (int i = 0; i < b->n; i++) {
        const double wi[3] = {b->wi[0][i], b->wi[1][i], b->wi[2][i]};
        const double wo[3] = {b->wo[0][i], b->wo[1][i], b->wo[2][i]};
        double fd[3], fs[3];
        model->eval(state, wi, wo, fd, fs);
        double scale = 0.0;
        for (int c = 0; c < 3; c++) scale = fmax(scale, fmax(fabs(fd[c]), fabs(fs[c])));
        const double bound = fmax(rtol * scale, atol);
        for (int c = 0; c < 3; c++) {
            const double ed = fabs(b->diffuse[c][i] - fd[c]) / bound, es = fabs(b->specular[c][i] - fs[c]) / bound;
            const double e = isfinite(b->diffuse[c][i]) && isfinite(b->specular[c][i]) ? fmax(ed, es) : INFINITY;
            if (e > worst) {
                worst = e;
                *worst_pair = i;
            }
        }
    }
    return worst;
}

/* worst_ratio_within for the double kernels' contract (brdf.h). */
static double worst_ratio(const mr_brdf_model *model, const void *state, const mr_brdf_batch *b, int *worst_pair) {
    return worst_ratio_within(model, state, b, MR_BRDF_BATCH_RTOL, MR_BRDF_BATCH_ATOL, worst_pair);
}

/* Every model, both kernels, against eval; and the place of a pair in its batch changes nothing. */
MR_TEST(batch_equals_eval_for_every_model) {
    static double in[6][PAIRS + 1], out[2][6][PAIRS + 1], shifted[6][PAIRS + 1];
    uint64_t rng = 0x5eed0031u;
    const mr_brdf_model *const *models = mr_brdf_models();
    for (int m = 0; models[m] != NULL; m++) {
        const mr_brdf_model *model = models[m];
        double overall = 0.0;
        for (int draw = 0; draw < 12; draw++) {
            double values[MR_BRDF_MAX_VALUES];
            random_values(model, &rng, draw, values);
            mr_brdf_state st;
            model->prepare(model, values, st.bytes);
            for (int i = 0; i < PAIRS; i++) {
                double wi[3], wo[3];
                random_direction(&rng, wi);
                random_direction(&rng, wo);
                if (i % 7 == 3) memcpy(wo, wi, sizeof wo); // the highlight's centre: h = n for wi = wo mirrored
                if (i % 7 == 3) wo[0] = -wo[0], wo[1] = -wo[1];
                for (int k = 0; k < 3; k++) {
                    in[k][i + 1] = wi[k];
                    in[3 + k][i + 1] = wo[k];
                }
            }
            for (int vector = 0; vector < 2; vector++) {
                double (*o)[PAIRS + 1] = out[vector];
                const mr_brdf_batch b = {PAIRS, {in[0] + 1, in[1] + 1, in[2] + 1}, {in[3] + 1, in[4] + 1, in[5] + 1},
                                         {o[0], o[1], o[2]}, {o[3], o[4], o[5]}};
                mr_brdf_eval_batch(model, st.bytes, &b, vector);
                int pair = 0;
                const double ratio = worst_ratio(model, st.bytes, &b, &pair);
                overall = fmax(overall, ratio);
                MR_CHECK_MSG(ratio <= 1.0, "%s (%s kernel, draw %d): pair %d off by %.3g of the tolerance",
                             model->name, vector ? "AVX2/FMA" : "portable", draw, pair, ratio);
                // The same pairs one place later in a batch one longer: the same bits.
                const mr_brdf_batch later = {PAIRS, {in[0], in[1], in[2]}, {in[3], in[4], in[5]},
                                             {shifted[0], shifted[1], shifted[2]},
                                             {shifted[3], shifted[4], shifted[5]}};
                for (int k = 0; k < 6; k++) in[k][0] = in[k][1];
                mr_brdf_batch longer = later;
                longer.n = PAIRS + 1;
                mr_brdf_eval_batch(model, st.bytes, &longer, vector);
                int same = 1;
                for (int k = 0; k < 6; k++) same &= memcmp(shifted[k] + 1, o[k], PAIRS * sizeof(double)) == 0;
                MR_CHECK_MSG(same, "%s (%s kernel): a pair's value depends on its place in the batch", model->name,
                             vector ? "AVX2/FMA" : "portable");
            }
        }
        if (getenv("MR_TEST_VERBOSE")) printf("    %-22s worst |batch - eval| = %.3g of the tolerance\n", model->name,
                                               overall);
    }
}

/* Distance in units in the last place between two positive finite doubles. */
static double ulps(double a, double b) {
    if (a == b) return 0.0;
    const double spacing = nextafter(fmax(a, b), INFINITY) - fmax(a, b);
    return fabs(a - b) / spacing;
}

/* mr_batch_exp and mr_batch_log within 2 ulp of libm (itself within 1 ulp of the true value: the bound stated is 2
 * of the true value, checked here with 1 more for libm's own error), with and without fused multiply-adds; the
 * documented ends; pow within (2 + 6 |y ln x|) + 1 ulp. */
MR_TEST(vector_exp_log_pow_within_their_bounds) {
    double worst_exp = 0.0, worst_log = 0.0, worst_pow = 0.0;
    uint64_t rng = 77;
    for (int fused = 0; fused < 2; fused++) {
        for (int i = 0; i <= 200000; i++) {
            const double x = -708.0 + 1417.0 * i / 200000.0 + 1e-3 * test_random(&rng);
            if (x > 709.0) continue;
            worst_exp = fmax(worst_exp, ulps(mr_batch_exp(x, fused), exp(x)));
            const double small = 0.5 * test_random(&rng); // where most of the lobes' arguments are
            worst_exp = fmax(worst_exp, ulps(mr_batch_exp(-small, fused), exp(-small)));
        }
        for (int i = 0; i < 200000; i++) {
            const double x = pow(10.0, -300.0 + 600.0 * test_random(&rng));
            const double near_one = 1.0 + (test_random(&rng) - 0.5) * 1e-3;
            worst_log = fmax(worst_log, ulps(fabs(mr_batch_log(x, fused)), fabs(log(x))));
            if (near_one != 1.0)
                worst_log = fmax(worst_log, ulps(fabs(mr_batch_log(near_one, fused)), fabs(log(near_one))));
            const double c = fmax(test_random(&rng), 1e-12), y = pow(10.0, 5.0 * test_random(&rng));
            const double expected = pow(c, y);
            if (expected > 1e-300)
                worst_pow = fmax(worst_pow, ulps(mr_batch_pow(c, y, fused), expected) / (3.0 + 6.0 * fabs(y * log(c))));
        }
        MR_CHECK(mr_batch_exp(0.0, fused) == 1.0);
        MR_CHECK(mr_batch_exp(-708.5, fused) == 0.0);
        MR_CHECK(isinf(mr_batch_exp(709.5, fused)));
        MR_CHECK(isnan(mr_batch_exp(NAN, fused)));
        MR_CHECK(mr_batch_log(1.0, fused) == 0.0);
        MR_CHECK(mr_batch_pow(1.0, 12345.0, fused) == 1.0);
        MR_CHECK(mr_batch_pow(0.3, 0.0, fused) == 1.0);
    }
    MR_CHECK_MSG(worst_exp <= 3.0, "exp: %.3g ulp from libm", worst_exp);
    MR_CHECK_MSG(worst_log <= 3.0, "log: %.3g ulp from libm", worst_log);
    MR_CHECK_MSG(worst_pow <= 1.0, "pow: %.3g of the bound", worst_pow);
    if (getenv("MR_TEST_VERBOSE"))
        printf("    exp %.3g ulp, log %.3g ulp from libm; pow %.3g of its bound\n", worst_exp, worst_log, worst_pow);
}

/* Largest |a - b| / max(|a|, |b|, 1e-30) over the images' values. */
static double image_rel_diff(const mr_image *a, const mr_image *b) {
    double worst = 0.0;
    const size_t n = (size_t)a->width * (size_t)a->height * (size_t)a->channels;
    for (size_t i = 0; i < n; i++) {
        const double x = a->pixels[i], y = b->pixels[i];
        worst = fmax(worst, fabs(x - y) / fmax(fmax(fabs(x), fabs(y)), 1e-30));
    }
    return worst;
}

/* For each model of names[] at random values drawn from `seed`, every component: the batched render on both kernels
 * equals the per-sample one within 1e-6 relative; with `two` (not NULL), it is also the same bits on 2 threads as on
 * 1. The images are scratch of the plan's size. */
static void check_batched_paths(const mr_render_plan *plan, const char *const *names, size_t count, uint64_t seed,
                                mr_image *reference, mr_image *batched, mr_image *two) {
    uint64_t rng = seed;
    for (size_t m = 0; m < count; m++) {
        const mr_brdf_model *model = mr_brdf_find(names[m]);
        MR_CHECK(model != NULL);
        if (model == NULL) continue;
        double values[MR_BRDF_MAX_VALUES];
        random_values(model, &rng, 3, values);
        for (int component = MR_COMPONENT_FULL; component <= MR_COMPONENT_SPECULAR; component++) {
            MR_CHECK_OK(mr_render_into_path(plan, 1, model, values, (mr_component)component, reference,
                                            MR_RENDER_PATH_PER_SAMPLE));
            for (int path = MR_RENDER_PATH_BATCH_PORTABLE; path <= MR_RENDER_PATH_BATCH_VECTOR; path++) {
                MR_CHECK_OK(mr_render_into_path(plan, 1, model, values, (mr_component)component, batched,
                                                (mr_render_path)path));
                const double diff = image_rel_diff(reference, batched);
                MR_CHECK_MSG(diff <= 1e-6, "%s component %d path %d: %.3g relative", names[m], component, path,
                             diff);
                if (two == NULL) continue;
                MR_CHECK_OK(mr_render_into_path(plan, 2, model, values, (mr_component)component, two,
                                                (mr_render_path)path));
                MR_CHECK_MSG(same_pixels(batched, two), "%s path %d: 1 and 2 threads differ", names[m], path);
            }
        }
    }
}

/* The fit scene rendered per sample and batched (both kernels, every component) for a few models: the same image
 * within 1e-6 relative (the BRDF values agree to ~1e-13; the image is float, so a value may round to its
 * neighbour: 6e-8). */
MR_TEST(batched_render_equals_per_sample_render) {
    const char *names[] = {"ward", "ggx", "as-conductor", "beckmann-plastic", "gltf", "cycles-principled", "phong",
                           "openpbr"};
    mr_scene scene = mr_scene_fit(&(mr_fit_scene_options){64, MR_FIT_LIGHT_45, 0});
    mr_render_plan *plan = NULL;
    MR_CHECK_OK(mr_render_plan_create(&scene, &plan));
    mr_image *reference = NULL, *batched = NULL;
    MR_CHECK_OK(mr_image_create(64, 64, 3, &reference));
    MR_CHECK_OK(mr_image_create(64, 64, 3, &batched));
    if (plan && reference && batched)
        check_batched_paths(plan, names, sizeof names / sizeof names[0], 31, reference, batched, NULL);
    mr_image_free(reference);
    mr_image_free(batched);
    mr_render_plan_free(plan);
}

/* Under an environment with reflection samples beside the point light (batches gathered from the hits): batched
 * renders equal the per-sample loop within 1e-6 relative, and 1 and 2 threads give the same bits. */
MR_TEST(batched_environment_render_equals_per_sample_render) {
    const char *names[] = {"ward-balanced", "as-plastic", "gltf", "cycles-ggx", "openpbr"};
    mr_image *map = linear_map(32, 16);
    mr_scene scene = mr_scene_fit(&(mr_fit_scene_options){96, MR_FIT_LIGHT_45, 0});
    scene.lights[1] = mr_light_environment(map, 1.0, 30.0, 64);
    scene.lights[1].reflection_samples = 16;
    scene.light_count = 2;
    scene.threads = 2;
    mr_render_plan *plan = NULL;
    MR_CHECK_OK(mr_render_plan_create(&scene, &plan));
    mr_image *reference = NULL, *batched = NULL, *two = NULL;
    MR_CHECK_OK(mr_image_create(96, 96, 3, &reference));
    MR_CHECK_OK(mr_image_create(96, 96, 3, &batched));
    MR_CHECK_OK(mr_image_create(96, 96, 3, &two));
    if (plan && reference && batched && two)
        check_batched_paths(plan, names, sizeof names / sizeof names[0], 5, reference, batched, two);
    mr_image_free(reference);
    mr_image_free(batched);
    mr_image_free(two);
    mr_image_free(map);
    mr_render_plan_free(plan);
}

/* At 512^2 (blocks of pixels run on different threads), batched renders on 1 and 2 threads are bit-identical. */
MR_TEST(batched_render_same_bits_on_one_and_two_threads) {
    mr_scene scene = mr_scene_fit(&(mr_fit_scene_options){512, MR_FIT_LIGHT_FRONTAL, 0});
    scene.threads = 2;
    mr_render_plan *plan = NULL;
    MR_CHECK_OK(mr_render_plan_create(&scene, &plan));
    mr_image *one = NULL, *two = NULL;
    MR_CHECK_OK(mr_image_create(512, 512, 3, &one));
    MR_CHECK_OK(mr_image_create(512, 512, 3, &two));
    const char *names[] = {"ward", "ggx", "gltf"};
    for (size_t m = 0; plan && one && two && m < sizeof names / sizeof names[0]; m++) {
        const mr_brdf_model *model = mr_brdf_find(names[m]);
        double values[MR_BRDF_MAX_VALUES];
        mr_brdf_default_values(model, values);
        for (int path = MR_RENDER_PATH_AUTO; path <= MR_RENDER_PATH_BATCH_VECTOR; path++) {
            if (path == MR_RENDER_PATH_PER_SAMPLE) continue;
            MR_CHECK_OK(mr_render_into_path(plan, 1, model, values, MR_COMPONENT_FULL, one, (mr_render_path)path));
            MR_CHECK_OK(mr_render_into_path(plan, 2, model, values, MR_COMPONENT_FULL, two, (mr_render_path)path));
            MR_CHECK_MSG(same_pixels(one, two), "%s path %d: 1 and 2 threads differ", names[m], path);
        }
    }
    mr_image_free(one);
    mr_image_free(two);
    mr_render_plan_free(plan);
}

/* Fills in[6][1 + PAIRS] (from index 1) with random direction pairs, every seventh a highlight's centre. */
static void random_pairs(uint64_t *rng, double in[6][PAIRS + 1]) {
    for (int i = 0; i < PAIRS; i++) {
        double wi[3], wo[3];
        random_direction(rng, wi);
        random_direction(rng, wo);
        if (i % 7 == 3) memcpy(wo, wi, sizeof wo); // the highlight's centre: h = n for wi = wo mirrored
        if (i % 7 == 3) wo[0] = -wo[0], wo[1] = -wo[1];
        for (int k = 0; k < 3; k++) {
            in[k][i + 1] = wi[k];
            in[3 + k][i + 1] = wo[k];
        }
    }
}

/* Every model with a float kernel (brdf_float.h), both instruction sets, against eval within MR_BRDF_FLOAT_RTOL of
 * the pair's largest value or MR_BRDF_FLOAT_ATOL, finite everywhere; random values plus the hard ones (every
 * parameter at its minimum: alpha 1e-4, F0 0; at its maximum: alpha 1, F0 1; alpha at each end with the others
 * random); grazing pairs among the random ones; a pair's value independent of its place in the batch. */
MR_TEST(float_batch_within_its_tolerance_of_eval) {
    static double in[6][PAIRS + 1], out[6][PAIRS + 1], shifted[6][PAIRS + 1];
    uint64_t rng = 0xf10a7031u;
    const mr_brdf_model *const *models = mr_brdf_models();
    int with_kernel = 0;
    for (int m = 0; models[m] != NULL; m++) {
        const mr_brdf_model *model = models[m];
        const mr_brdf_batch_fn kernel = mr_brdf_float_kernel(model);
        if (kernel == NULL) continue;
        with_kernel++;
        double overall = 0.0;
        for (int draw = 0; draw < 24; draw++) {
            double values[MR_BRDF_MAX_VALUES];
            random_values(model, &rng, draw < 3 ? draw : 3 + draw % 2, values);
            const int alpha_slot = mr_brdf_param_offset(model, mr_brdf_param_index(model, "alpha"));
            const int rough_slot = mr_brdf_param_offset(model, mr_brdf_param_index(model, "roughness"));
            const int shape = alpha_slot >= 0 ? alpha_slot : rough_slot;
            if (shape >= 0 && draw >= 20) values[shape] = draw % 2 ? 1e-4 : 1.0; // alpha (or roughness) at its ends
            if (shape >= 0 && draw >= 20 && rough_slot >= 0) values[shape] = draw % 2 ? 0.0 : 1.0;
            // At ior = 1 exactly eval's 1 - (1 - c^2) rounds to 0 for cos < 1e-8, giving F = 1 (no light through)
            // where the true F is 0; the float kernel's cancellation-free form is right there (brdf_batch.h,
            // mr_batchf_dielectric_transmit), so the reference is taken a hair above, where eval is accurate.
            const int ior_slot = mr_brdf_param_offset(model, mr_brdf_param_index(model, "ior"));
            if (ior_slot >= 0 && values[ior_slot] < 1.0 + 1e-6) values[ior_slot] = 1.0 + 1e-6;
            mr_brdf_state st;
            model->prepare(model, values, st.bytes);
            random_pairs(&rng, in);
            for (int vector = 0; vector < 2; vector++) {
                const mr_brdf_batch b = {PAIRS, {in[0] + 1, in[1] + 1, in[2] + 1}, {in[3] + 1, in[4] + 1, in[5] + 1},
                                         {out[0], out[1], out[2]}, {out[3], out[4], out[5]}};
                mr_brdf_eval_batch_float(model, st.bytes, &b, vector);
                int pair = 0;
                const double ratio = worst_ratio_within(model, st.bytes, &b, MR_BRDF_FLOAT_RTOL, MR_BRDF_FLOAT_ATOL,
                                                        &pair);
                overall = fmax(overall, ratio);
                MR_CHECK_MSG(ratio <= 1.0, "%s (float %s kernel, draw %d): pair %d off by %.3g of the tolerance",
                             model->name, vector ? "AVX2/FMA" : "portable", draw, pair, ratio);
                for (int k = 0; k < 6; k++) in[k][0] = in[k][1];
                const mr_brdf_batch longer = {PAIRS + 1, {in[0], in[1], in[2]}, {in[3], in[4], in[5]},
                                              {shifted[0], shifted[1], shifted[2]},
                                              {shifted[3], shifted[4], shifted[5]}};
                kernel(st.bytes, &longer, vector);
                int same = 1;
                for (int k = 0; k < 6; k++) same &= memcmp(shifted[k] + 1, out[k], PAIRS * sizeof(double)) == 0;
                MR_CHECK_MSG(same, "%s (float %s kernel): a pair's value depends on its place in the batch",
                             model->name, vector ? "AVX2/FMA" : "portable");
            }
        }
        if (getenv("MR_TEST_VERBOSE"))
            printf("    %-22s worst |float batch - eval| = %.3g of the tolerance\n", model->name, overall);
    }
    MR_CHECK_MSG(with_kernel == 16, "%d models with a float kernel, expected 16 (3 Ward, 12 microfacet, gltf)",
                 with_kernel);
}

/* Distance in units in the last place between two positive finite floats. */
/* Prepared derivatives over a batch (brdf.h grad_ops eval_batch): for every model and every slot its batchable()
 * accepts, both kernels against grad_ops eval pair by pair, within the double kernels' contract (relative to the
 * pair's largest derivative); zero diffuse derivatives; finite. And where it accepts: the lobe's shape at least. */
MR_TEST(batched_derivatives_equal_prepared_ones) {
    static double in[6][PAIRS + 1], fd[3][PAIRS + 1], fs[3][PAIRS + 1];
    uint64_t rng = 0x5eed0d1fu;
    const mr_brdf_model *const *models = mr_brdf_models();
    int batched_models = 0;
    for (int m = 0; models[m] != NULL; m++) {
        const mr_brdf_model *model = models[m];
        const mr_brdf_grad_ops *ops = model->grad_ops;
        if (ops == NULL || ops->batchable == NULL) continue;
        MR_CHECK(ops->eval_batch != NULL);
        void *state = malloc(ops->state_bytes);
        MR_CHECK(state != NULL);
        int batchable_slots = 0;
        double worst = 0.0;
        for (int slot = 0; slot < mr_brdf_value_count(model); slot++)
            for (int draw = 0; draw < 6; draw++) {
                double values[MR_BRDF_MAX_VALUES];
                random_values(model, &rng, draw, values);
                ops->prepare(model, values, &slot, 1, state);
                if (!ops->batchable(state)) break;
                batchable_slots += draw == 0;
                random_pairs(&rng, in);
                for (int vector = 0; vector < 2; vector++) {
                    // random_pairs fills [1, PAIRS]
                    const mr_brdf_batch b = {PAIRS,
                                             {in[0] + 1, in[1] + 1, in[2] + 1},
                                             {in[3] + 1, in[4] + 1, in[5] + 1},
                                             {fd[0], fd[1], fd[2]},
                                             {fs[0], fs[1], fs[2]}};
                    ops->eval_batch(state, &b, vector);
                    for (int i = 0; i < PAIRS; i++) {
                        const double wi[3] = {b.wi[0][i], b.wi[1][i], b.wi[2][i]};
                        const double wo[3] = {b.wo[0][i], b.wo[1][i], b.wo[2][i]};
                        double dd[3], ds[3], scale = 0.0;
                        ops->eval(state, wi, wo, dd, ds);
                        for (int c = 0; c < 3; c++) scale = fmax(scale, fmax(fabs(dd[c]), fabs(ds[c])));
                        const double bound = fmax(MR_BRDF_BATCH_RTOL * scale, MR_BRDF_BATCH_ATOL);
                        for (int c = 0; c < 3; c++) {
                            MR_CHECK(isfinite(fs[c][i]) && fd[c][i] == 0.0 && dd[c] == 0.0);
                            worst = fmax(worst, fabs(fs[c][i] - ds[c]) / bound);
                        }
                    }
                }
            }
        free(state);
        if (getenv("MR_TEST_VERBOSE"))
            printf("    %-22s %d batched slot(s), worst |batch - eval| = %.3g of the tolerance\n", model->name,
                   batchable_slots, worst);
        MR_CHECK(batchable_slots >= 1);
        MR_CHECK(worst <= 1.0);
        batched_models++;
    }
    MR_CHECK(batched_models >= 15); // the Ward family and the twelve microfacet members
}

static double ulps_float(float a, float b) {
    if (a == b) return 0.0;
    const float big = fmaxf(a, b), spacing = nextafterf(big, INFINITY) - big;
    return fabs((double)a - (double)b) / spacing;
}

/* mr_batchf_exp within 2 ulp of libm's expf (itself within 1 ulp of the true value: checked with 1 more) over
 * [-87, 88], mr_batchf_log within 2 ulp (+1) of logf where |log x| >= 0.1 and within 2^-24 absolute elsewhere,
 * log1p within 4 ulp of log1pf; the documented ends. */
MR_TEST(float_exp_log_within_their_bounds) {
    double worst_exp = 0.0, worst_log = 0.0, worst_log_abs = 0.0, worst_log1p = 0.0;
    uint64_t rng = 31;
    for (int fused = 0; fused < 2; fused++) {
        for (int i = 0; i <= 400000; i++) {
            const float x = (float)(-87.0 + 175.0 * i / 400000.0 + 1e-4 * test_random(&rng));
            if (x > 88.0f) continue;
            worst_exp = fmax(worst_exp, ulps_float(mr_batchf_exp(x, fused), expf(x)));
            const float small = (float)(-0.5 * test_random(&rng));
            worst_exp = fmax(worst_exp, ulps_float(mr_batchf_exp(small, fused), expf(small)));
            const float y = (float)pow(10.0, -37.0 + 74.0 * test_random(&rng));
            const float ly = mr_batchf_log(y, fused), ref = logf(y);
            if (fabsf(ref) >= 0.1f)
                worst_log = fmax(worst_log, ulps_float(fabsf(ly), fabsf(ref)));
            else
                worst_log_abs = fmax(worst_log_abs, fabs((double)ly - (double)ref));
            const float t = (float)pow(10.0, -12.0 + 36.0 * test_random(&rng));
            worst_log1p = fmax(worst_log1p, ulps_float(mr_batchf_log1p(t, fused), log1pf(t)));
        }
        MR_CHECK(mr_batchf_exp(0.0f, fused) == 1.0f);
        MR_CHECK(mr_batchf_exp(-87.5f, fused) == 0.0f);
        MR_CHECK(isinf(mr_batchf_exp(88.5f, fused)));
        MR_CHECK(isnan(mr_batchf_exp(NAN, fused)));
        MR_CHECK(mr_batchf_log(1.0f, fused) == 0.0f);
        MR_CHECK(mr_batchf_log1p(0.0f, fused) == 0.0f);
    }
    MR_CHECK_MSG(worst_exp <= 3.0, "float exp: %.3g ulp from expf", worst_exp);
    MR_CHECK_MSG(worst_log <= 3.0, "float log: %.3g ulp from logf", worst_log);
    MR_CHECK_MSG(worst_log_abs <= 0x1p-24, "float log near 1: %.3g from logf", worst_log_abs);
    MR_CHECK_MSG(worst_log1p <= 4.0, "float log1p: %.3g ulp from log1pf", worst_log1p);
    if (getenv("MR_TEST_VERBOSE"))
        printf("    float exp %.3g ulp, log %.3g ulp (%.3g absolute near 1), log1p %.3g ulp\n", worst_exp, worst_log,
               worst_log_abs, worst_log1p);
}

/* The float switch reaches a plan's closer look (mr_render_plan_zoomed), whether that was built before or after it
 * was set: the closer render of ward differs from the double plan's, and equals it again once switched off. */
MR_TEST(float_switch_reaches_the_closer_look) {
    mr_scene scene = mr_scene_fit(&(mr_fit_scene_options){64, MR_FIT_LIGHT_45, 0});
    mr_render_plan *plan_float = NULL, *plan_double = NULL;
    MR_CHECK_OK(mr_render_plan_create(&scene, &plan_float));
    MR_CHECK_OK(mr_render_plan_create(&scene, &plan_double));
    if (plan_float == NULL || plan_double == NULL) return;
    const mr_render_plan *close_double = NULL, *close_before = NULL;
    MR_CHECK_OK(mr_render_plan_zoomed(plan_double, 8.0, &close_double));
    MR_CHECK_OK(mr_render_plan_zoomed(plan_float, 8.0, &close_before)); // built while the plan is double
    mr_render_plan_set_float_kernels(plan_float, 1);
    const mr_brdf_model *ward = mr_brdf_find("ward");
    double values[MR_BRDF_MAX_VALUES];
    mr_brdf_default_values(ward, values);
    mr_image *a = NULL, *b = NULL;
    MR_CHECK_OK(mr_image_create(64, 64, 3, &a));
    MR_CHECK_OK(mr_image_create(64, 64, 3, &b));
    if (close_double && close_before && a && b) {
        MR_CHECK_OK(mr_render_into_threads(close_double, 1, ward, values, MR_COMPONENT_FULL, a));
        MR_CHECK_OK(mr_render_into_threads(close_before, 1, ward, values, MR_COMPONENT_FULL, b));
        MR_CHECK_MSG(!same_pixels(a, b), "the closer look built before the switch still renders in double");
        mr_render_plan_set_float_kernels(plan_float, 0);
        MR_CHECK_OK(mr_render_into_threads(close_before, 1, ward, values, MR_COMPONENT_FULL, b));
        MR_CHECK_MSG(same_pixels(a, b), "switched off, the closer look does not render as the double plan's");
    }
    mr_render_plan *plan_late = NULL; // switched on before its closer look is built
    MR_CHECK_OK(mr_render_plan_create(&scene, &plan_late));
    const mr_render_plan *close_after = NULL;
    if (plan_late) mr_render_plan_set_float_kernels(plan_late, 1);
    if (plan_late) MR_CHECK_OK(mr_render_plan_zoomed(plan_late, 8.0, &close_after));
    if (close_after && close_double && a && b) {
        MR_CHECK_OK(mr_render_into_threads(close_after, 1, ward, values, MR_COMPONENT_FULL, b));
        MR_CHECK_MSG(!same_pixels(a, b), "the closer look built after the switch renders in double");
    }
    mr_image_free(a);
    mr_image_free(b);
    mr_render_plan_free(plan_float);
    mr_render_plan_free(plan_double);
    mr_render_plan_free(plan_late);
}

/* With the float kernels (render_internal.h), batched renders on 1 and 2 threads are bit-identical at 512^2, and
 * models without a float kernel render exactly as in double. */
MR_TEST(float_render_same_bits_on_one_and_two_threads) {
    mr_scene scene = mr_scene_fit(&(mr_fit_scene_options){512, MR_FIT_LIGHT_FRONTAL, 0});
    scene.threads = 2;
    mr_render_plan *plan = NULL, *plan_double = NULL;
    MR_CHECK_OK(mr_render_plan_create(&scene, &plan));
    MR_CHECK_OK(mr_render_plan_create(&scene, &plan_double));
    if (plan) mr_render_plan_set_float_kernels(plan, 1);
    mr_image *one = NULL, *two = NULL;
    MR_CHECK_OK(mr_image_create(512, 512, 3, &one));
    MR_CHECK_OK(mr_image_create(512, 512, 3, &two));
    const char *names[] = {"ward", "ggx", "as", "gltf", "lambert"};
    for (size_t m = 0; plan && plan_double && one && two && m < sizeof names / sizeof names[0]; m++) {
        const mr_brdf_model *model = mr_brdf_find(names[m]);
        double values[MR_BRDF_MAX_VALUES];
        mr_brdf_default_values(model, values);
        for (int path = MR_RENDER_PATH_BATCH_PORTABLE; path <= MR_RENDER_PATH_BATCH_VECTOR; path++) {
            MR_CHECK_OK(mr_render_into_path(plan, 1, model, values, MR_COMPONENT_FULL, one, (mr_render_path)path));
            MR_CHECK_OK(mr_render_into_path(plan, 2, model, values, MR_COMPONENT_FULL, two, (mr_render_path)path));
            MR_CHECK_MSG(same_pixels(one, two), "%s float path %d: 1 and 2 threads differ", names[m], path);
            MR_CHECK_OK(mr_render_into_path(plan_double, 1, model, values, MR_COMPONENT_FULL, two,
                                            (mr_render_path)path));
            const int has_float = mr_brdf_float_kernel(model) != NULL;
            MR_CHECK_MSG(same_pixels(one, two) == !has_float, "%s path %d: float and double renders %s", names[m],
                         path, has_float ? "identical" : "differ");
            // The images agree to about float's precision where they are not tiny (per-pixel sums of float values).
            MR_CHECK_MSG(image_rel_diff(one, two) <= 1e-3, "%s path %d: float render %.3g from double", names[m],
                         path, image_rel_diff(one, two));
        }
    }
    mr_image_free(one);
    mr_image_free(two);
    mr_render_plan_free(plan);
    mr_render_plan_free(plan_double);
}

MR_TEST_MAIN(MR_TEST_ENTRY(batch_equals_eval_for_every_model), MR_TEST_ENTRY(vector_exp_log_pow_within_their_bounds),
             MR_TEST_ENTRY(batched_render_equals_per_sample_render),
             MR_TEST_ENTRY(batched_environment_render_equals_per_sample_render),
             MR_TEST_ENTRY(batched_render_same_bits_on_one_and_two_threads),
             MR_TEST_ENTRY(float_batch_within_its_tolerance_of_eval), MR_TEST_ENTRY(float_exp_log_within_their_bounds),
             MR_TEST_ENTRY(float_render_same_bits_on_one_and_two_threads),
             MR_TEST_ENTRY(float_switch_reaches_the_closer_look),
             MR_TEST_ENTRY(batched_derivatives_equal_prepared_ones))
