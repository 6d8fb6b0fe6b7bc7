/*
 * test_render_derivatives.c — the parameter derivatives of a render (render.h, mr_render_derivatives_into), which
 * the fits' gradient local stage steps by: against central differences of renders, for every model with analytic
 * derivatives, per component; the same images for any thread count, and through prepared derivatives (grad_ops)
 * as through eval_grad; the lobe's shape in batches as per sample; refusals.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "harness.h"
#include "matremap.h"
#include "render/render.h"
#include "render_support.h"

/* Values inside every parameter's range, away from the bounds where clamps put kinks: 30 % .. 70 % of the range
 * (geometric for log-scale parameters), varied per slot so that channels differ. */
static void interior_values(const mr_brdf_model *m, double *values) {
    mr_brdf_default_values(m, values);
    for (int p = 0, slot = 0; p < m->param_count; p++)
        for (int c = 0; c < m->params[p].channels; c++, slot++) {
            const mr_brdf_param *q = &m->params[p];
            if (q->role == MR_PARAM_SWITCH) continue;
            double t = 0.3 + 0.4 * fmod(0.37 * (slot + 1) + 0.11 * p, 1.0);
            if ((q->flags & MR_PARAM_LOG_SCALE) && q->min_value > 0.0)
                values[slot] = q->min_value * pow(q->max_value / q->min_value, t);
            else
                values[slot] = q->min_value + t * (fmin(q->max_value, 4.0) - q->min_value);
        }
}

MR_TEST(derivatives_match_central_differences_for_every_model) {
    mr_render_plan *plan = fit_scene_plan(32);
    mr_image *d = NULL, *plus = NULL, *minus = NULL;
    MR_CHECK_OK(mr_image_create(32, 32, 3, &d));
    MR_CHECK_OK(mr_image_create(32, 32, 3, &plus));
    MR_CHECK_OK(mr_image_create(32, 32, 3, &minus));
    int models = 0;
    for (const mr_brdf_model *const *mp = mr_brdf_models(); *mp; mp++) {
        const mr_brdf_model *m = *mp;
        if (m->eval_grad == NULL) continue; // test_brdf requires it of every model; counted below
        models++;
        double values[MR_BRDF_MAX_VALUES];
        interior_values(m, values);
        for (int slot = 0, p = 0; p < m->param_count; p++)
            for (int c = 0; c < m->params[p].channels; c++, slot++) {
                const mr_brdf_param *q = &m->params[p];
                if (q->role == MR_PARAM_SWITCH) continue;
                for (int component = 0; component < MR_COMPONENT_COUNT; component++) {
                    MR_CHECK_OK(mr_render_derivatives_into(plan, 1, m, values, (mr_component)component, &slot, 1,
                                                           &d));
                    // Central differences of renders in float: a step of 1e-3 of the value's scale keeps the
                    // truncation and the float rounding both near 1e-6 of the image.
                    const double h = 1e-3 * fmax(fabs(values[slot]), 0.1 * (fmin(q->max_value, 4.0) - q->min_value));
                    double v[MR_BRDF_MAX_VALUES];
                    memcpy(v, values, sizeof v);
                    v[slot] = values[slot] + h;
                    MR_CHECK_OK(mr_render_into(plan, m, v, (mr_component)component, plus));
                    v[slot] = values[slot] - h;
                    MR_CHECK_OK(mr_render_into(plan, m, v, (mr_component)component, minus));
                    // Weighted sums over the image (all ones, and a pattern that tells pixels and channels
                    // apart): summing averages the float rounding of each render out of the differences.
                    for (int weighting = 0; weighting < 2; weighting++) {
                        double analytic = 0.0, scale = 0.0, numeric = 0.0, level = 0.0;
                        for (int i = 0; i < 32 * 32 * 3; i++) {
                            const double w = weighting == 0 ? 1.0 : (double)((i / 3 + i / 96 + i % 3) % 3) - 1.0;
                            analytic += w * d->pixels[i];
                            scale += fabs(w * d->pixels[i]);
                            numeric += w * ((double)plus->pixels[i] - (double)minus->pixels[i]) / (2.0 * h);
                            level += fabs(w * plus->pixels[i]);
                        }
                        const double rounding = 1e-7 * level / h; // float rounding of the two renders' sums
                        MR_CHECK_MSG(fabs(analytic - numeric) <= 1e-3 * scale + 4.0 * rounding,
                                     "%s: d %s / d %s[%d], weighting %d: analytic %.8g, central differences "
                                     "%.8g (scale %.3g, rounding %.3g)", m->name,
                                     mr_component_name((mr_component)component), q->name, c, weighting, analytic,
                                     numeric, scale, rounding);
                    }
                }
            }
    }
    MR_CHECK(models >= 15);
    mr_image_free(d);
    mr_image_free(plus);
    mr_image_free(minus);
    mr_render_plan_free(plan);
}

MR_TEST(derivative_images_do_not_depend_on_the_thread_count) {
    mr_render_plan *plan = fit_scene_plan(128);
    const mr_brdf_model *m = mr_brdf_find("gltf");
    double values[MR_BRDF_MAX_VALUES];
    interior_values(m, values);
    int slots[3] = {3, 4, 0}; // metallic, roughness, base colour R
    mr_image *one[3], *two[3];
    for (int k = 0; k < 3; k++) {
        MR_CHECK_OK(mr_image_create(128, 128, 3, &one[k]));
        MR_CHECK_OK(mr_image_create(128, 128, 3, &two[k]));
    }
    MR_CHECK_OK(mr_render_derivatives_into(plan, 1, m, values, MR_COMPONENT_FULL, slots, 3, one));
    MR_CHECK_OK(mr_render_derivatives_into(plan, 2, m, values, MR_COMPONENT_FULL, slots, 3, two));
    for (int k = 0; k < 3; k++) {
        MR_CHECK(memcmp(one[k]->pixels, two[k]->pixels, 128 * 128 * 3 * sizeof(float)) == 0);
        mr_image_free(one[k]);
        mr_image_free(two[k]);
    }
    mr_render_plan_free(plan);
}

/* A model with prepared derivatives (brdf.h, grad_ops) renders through them; a slot list with a repeat takes the
 * per-sample eval_grad instead (render.c). Both must give the same images: equal floats (==, so a zero's sign may
 * differ) for three slots, at interior values and with the parameters fits hold at their defaults (coat weight 0,
 * whose terms the prepared path skips), on 1 and 2 threads; the prepared images bit for bit the same on both. */
MR_TEST(prepared_derivatives_render_the_same_images_as_eval_grad) {
    mr_render_plan *plan = fit_scene_plan(32);
    mr_image *fast[3], *full[4], *one_thread[3];
    for (int k = 0; k < 4; k++) {
        if (k < 3) MR_CHECK_OK(mr_image_create(32, 32, 3, &fast[k]));
        if (k < 3) MR_CHECK_OK(mr_image_create(32, 32, 3, &one_thread[k]));
        MR_CHECK_OK(mr_image_create(32, 32, 3, &full[k]));
    }
    int models = 0;
    for (const mr_brdf_model *const *mp = mr_brdf_models(); *mp; mp++) {
        const mr_brdf_model *m = *mp;
        if (m->grad_ops == NULL) continue;
        models++;
        for (int setting = 0; setting < 2; setting++) {
            double values[MR_BRDF_MAX_VALUES], defaults[MR_BRDF_MAX_VALUES];
            interior_values(m, values);
            mr_brdf_default_values(m, defaults);
            int slots[4], k = 0;
            for (int p = 0, slot = 0; p < m->param_count; p++)
                for (int c = 0; c < m->params[p].channels; c++, slot++) {
                    const int held = (m->params[p].flags & MR_PARAM_FIT_FIXED) != 0;
                    if (setting == 1 && held) values[slot] = defaults[slot];
                    if (!held && m->params[p].role != MR_PARAM_SWITCH && k < 3 && (c == 0 || setting == 0))
                        slots[k++] = slot;
                }
            MR_CHECK(k == 3);
            slots[3] = slots[0];
            for (int threads = 1; threads <= 2; threads++) {
                MR_CHECK_OK(mr_render_derivatives_into(plan, threads, m, values, MR_COMPONENT_FULL, slots, 3, fast));
                MR_CHECK_OK(mr_render_derivatives_into(plan, threads, m, values, MR_COMPONENT_FULL, slots, 4, full));
                int differ = 0;
                for (int j = 0; j < 3; j++)
                    for (int i = 0; i < 32 * 32 * 3; i++) differ += fast[j]->pixels[i] != full[j]->pixels[i];
                MR_CHECK_MSG(differ == 0, "%s (setting %d, %d threads): %d pixels differ between grad_ops and "
                             "eval_grad", m->name, setting, threads, differ);
                // and bit for bit the same images on 1 and 2 threads
                const size_t bytes = 32 * 32 * 3 * sizeof(float);
                for (int j = 0; j < 3; j++)
                    if (threads == 1)
                        memcpy(one_thread[j]->pixels, fast[j]->pixels, bytes);
                    else
                        MR_CHECK_MSG(memcmp(one_thread[j]->pixels, fast[j]->pixels, bytes) == 0,
                                     "%s (setting %d): image %d differs between 1 and 2 threads", m->name, setting, j);
            }
        }
    }
    MR_CHECK(models >= 3);
    for (int k = 0; k < 4; k++) {
        if (k < 3) mr_image_free(fast[k]);
        if (k < 3) mr_image_free(one_thread[k]);
        mr_image_free(full[k]);
    }
    mr_render_plan_free(plan);
}

/* The lobe's shape alone, which the fits ask for at every step, is rendered in batches where the model's grad_ops
 * has a batched form (brdf.h eval_batch): per component, the same image as the per-sample path gives it (asked
 * together with a second slot, which takes that path) within 1e-6 relative to the image's largest value (the batched
 * exp is within 2 ulp of libm's); the same bits on 1 and 2 threads; the diffuse component's image zero. */
MR_TEST(batched_shape_derivative_equals_the_per_sample_one) {
    mr_render_plan *plan = fit_scene_plan(32);
    mr_image *alone, *pair[2], *two_threads;
    MR_CHECK_OK(mr_image_create(32, 32, 3, &alone));
    MR_CHECK_OK(mr_image_create(32, 32, 3, &two_threads));
    for (int k = 0; k < 2; k++) MR_CHECK_OK(mr_image_create(32, 32, 3, &pair[k]));
    int models = 0;
    for (const mr_brdf_model *const *mp = mr_brdf_models(); *mp; mp++) {
        const mr_brdf_model *m = *mp;
        if (m->grad_ops == NULL || m->grad_ops->batchable == NULL) continue;
        double values[MR_BRDF_MAX_VALUES];
        interior_values(m, values);
        for (int slot = 0; slot < mr_brdf_value_count(m); slot++) {
            void *state = malloc(m->grad_ops->state_bytes);
            MR_CHECK(state != NULL);
            m->grad_ops->prepare(m, values, &slot, 1, state);
            const int batched = m->grad_ops->batchable(state);
            free(state);
            if (!batched) continue;
            models++;
            const int slots[2] = {slot, slot == 0 ? 1 : 0};
            for (int component = MR_COMPONENT_FULL; component <= MR_COMPONENT_SPECULAR; component++) {
                MR_CHECK_OK(mr_render_derivatives_into(plan, 1, m, values, component, slots, 1, &alone));
                MR_CHECK_OK(mr_render_derivatives_into(plan, 2, m, values, component, slots, 1, &two_threads));
                MR_CHECK_OK(mr_render_derivatives_into(plan, 1, m, values, component, slots, 2, pair));
                double scale = 0.0, worst = 0.0;
                for (int i = 0; i < 32 * 32 * 3; i++) scale = fmax(scale, fabs(pair[0]->pixels[i]));
                for (int i = 0; i < 32 * 32 * 3; i++) worst = fmax(worst, fabs(alone->pixels[i] - pair[0]->pixels[i]));
                MR_CHECK_MSG(worst <= 1e-6 * scale, "%s slot %d component %d: batched and per-sample derivative "
                             "images differ by %.3g (largest value %.3g)", m->name, slot, component, worst, scale);
                MR_CHECK(memcmp(alone->pixels, two_threads->pixels, 32 * 32 * 3 * sizeof(float)) == 0);
                if (component == MR_COMPONENT_DIFFUSE) MR_CHECK(scale == 0.0);
                if (component != MR_COMPONENT_DIFFUSE) MR_CHECK(scale > 0.0);
            }
        }
    }
    MR_CHECK(models >= 15); // the Ward family and the twelve microfacet members, their shape slot
    mr_image_free(alone);
    mr_image_free(two_threads);
    for (int k = 0; k < 2; k++) mr_image_free(pair[k]);
    mr_render_plan_free(plan);
}

MR_TEST(what_cannot_be_differentiated_is_refused) {
    mr_render_plan *plan = fit_scene_plan(16);
    mr_image *d = NULL, *wrong = NULL;
    MR_CHECK_OK(mr_image_create(16, 16, 3, &d));
    MR_CHECK_OK(mr_image_create(8, 8, 3, &wrong));
    const mr_brdf_model *ward = mr_brdf_find("ward");
    double values[MR_BRDF_MAX_VALUES];
    mr_brdf_default_values(ward, values);
    int slot = 99;
    MR_CHECK(mr_render_derivatives_into(plan, 1, ward, values, MR_COMPONENT_FULL, &slot, 1, &d) ==
             MR_ERR_INVALID_ARG);
    MR_CHECK(strstr(mr_last_error(), "slot 99 outside model 'ward'") != NULL);
    slot = 0;
    MR_CHECK(mr_render_derivatives_into(plan, 1, ward, values, MR_COMPONENT_FULL, &slot, 1, &wrong) ==
             MR_ERR_INVALID_ARG);
    MR_CHECK(mr_render_derivatives_into(plan, 1, ward, values, (mr_component)7, &slot, 1, &d) == MR_ERR_INVALID_ARG);
    MR_CHECK(mr_render_plan_point_lit_only(plan));
    // An environment light: its samples are not differentiated (the fits' scenes are point-lit).
    mr_render_plan *lit = environment_fit_plan(16);
    MR_CHECK(!mr_render_plan_point_lit_only(lit));
    MR_CHECK(mr_render_derivatives_into(lit, 1, ward, values, MR_COMPONENT_FULL, &slot, 1, &d) ==
             MR_ERR_UNSUPPORTED);
    MR_CHECK(strstr(mr_last_error(), "point lights only") != NULL);
    mr_render_plan_free(lit);
    mr_image_free(d);
    mr_image_free(wrong);
    mr_render_plan_free(plan);
}

MR_TEST_MAIN(MR_TEST_ENTRY(derivatives_match_central_differences_for_every_model),
             MR_TEST_ENTRY(derivative_images_do_not_depend_on_the_thread_count),
             MR_TEST_ENTRY(prepared_derivatives_render_the_same_images_as_eval_grad),
             MR_TEST_ENTRY(what_cannot_be_differentiated_is_refused),
             MR_TEST_ENTRY(batched_shape_derivative_equals_the_per_sample_one))
