/*
 * bench_brdf_grad.c — what the analytic parameter derivatives cost against the evaluation, per model, one thread.
 *
 * For every registered model, at its default values and at random in-range values, over the same 4096 random
 * direction pairs: the nanoseconds of one eval with a prepared state (what the render loop does per hit), of one
 * prepare + eval (a parameter set per point), and of one eval_grad (which takes the values, so it includes the
 * work of prepare: the fit's local stage calls it per point sample with one parameter set). Medians of 7 runs; the
 * ratios grad/eval and grad/(prepare + eval) are what docs/brdfs.md quotes per model. For models with prepared
 * derivatives (brdf.h, grad_ops), also one grad_ops->eval with the slots a fit solves (those neither switches nor
 * held by default, up to 5: openpbr's base_color, base_metalness and specular_roughness) and one grad_ops->prepare.
 *
 * A second table: one derivative render (render.h, mr_render_derivatives_into) of those slots on the 64^2 fit scene,
 * one thread, against one plain render of the same model and values (random ones): through grad_ops where the model
 * has it, and through eval_grad per sample (what every derivative render did before grad_ops: render.c takes that
 * path for a slot list with a repeat, so the list is the fitted slots plus a repeat of the first). Medians of 7.
 *
 * Usage: bench_brdf_grad [--quick] [MODEL...]
 */
#include <stdint.h>
#include <stdlib.h>
#include <stdio.h>
#include <string.h>

#include "bench_util.h"
#include "brdf/brdf.h"
#include "matremap.h"
#include "render/render.h"

#define PAIRS 4096
#define RUNS 7

static uint64_t rng_state = 42;
static double rnd(void) {
    uint64_t z = (rng_state += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return (double)((z ^ (z >> 31)) >> 11) * 0x1.0p-53;
}

static void random_dir(double w[3]) {
    double z = 0.05 + 0.95 * rnd(), phi = 6.283185307179586 * rnd(), r = sqrt(1.0 - z * z);
    w[0] = r * cos(phi);
    w[1] = r * sin(phi);
    w[2] = z;
}

static double wi[PAIRS][3], wo[PAIRS][3];
static volatile double sink;

/* The slots a fit solves by default, up to 5 (not switches, not MR_PARAM_FIT_FIXED); returns their count. */
static int fitted_slots(const mr_brdf_model *m, int *slots) {
    int k = 0;
    for (int i = 0, slot = 0; i < m->param_count; i++)
        for (int c = 0; c < m->params[i].channels; c++, slot++)
            if (m->params[i].role != MR_PARAM_SWITCH && !(m->params[i].flags & MR_PARAM_FIT_FIXED) && k < 5)
                slots[k++] = slot;
    return k;
}

/* ns per call of mode 0 (eval, prepared), 1 (prepare + eval), 2 (eval_grad), 3 (grad_ops->eval of the fitted slots,
 * prepared), 4 (grad_ops->prepare) over the PAIRS pairs; median of RUNS */
static double time_mode(const mr_brdf_model *m, const double *values, int mode, int pairs) {
    double samples[RUNS], acc = 0.0;
    mr_brdf_state st;
    m->prepare(m, values, st.bytes);
    int slots[5], slot_count = fitted_slots(m, slots);
    void *grad_state = m->grad_ops ? malloc(m->grad_ops->state_bytes) : NULL;
    if (grad_state) m->grad_ops->prepare(m, values, slots, slot_count, grad_state);
    for (int r = 0; r < RUNS; r++) {
        double t0 = bench_now();
        for (int k = 0; k < pairs; k++) {
            double d[3], s[3], gd[MR_BRDF_MAX_VALUES * 3], gs[MR_BRDF_MAX_VALUES * 3];
            if (mode == 0) {
                m->eval(st.bytes, wi[k], wo[k], d, s);
                acc += d[0] + s[2];
            } else if (mode == 1) {
                mr_brdf_state local;
                m->prepare(m, values, local.bytes);
                m->eval(local.bytes, wi[k], wo[k], d, s);
                acc += d[0] + s[2];
            } else if (mode == 2) {
                m->eval_grad(m, values, wi[k], wo[k], gd, gs);
                acc += gd[0] + gs[3];
            } else if (mode == 3) {
                m->grad_ops->eval(grad_state, wi[k], wo[k], gd, gs);
                acc += gd[0] + gs[3];
            } else {
                m->grad_ops->prepare(m, values, slots, slot_count, grad_state);
            }
        }
        samples[r] = (bench_now() - t0) * 1e9 / pairs;
    }
    sink = acc;
    free(grad_state);
    return bench_median(samples, RUNS);
}

/* Whether model m is among the names argv[first_model..argc) (every model when there are none). */
static int model_wanted(const mr_brdf_model *m, int argc, char **argv, int first_model) {
    if (argc <= first_model) return 1;
    for (int a = first_model; a < argc; a++)
        if (strcmp(argv[a], m->name) == 0) return 1;
    return 0;
}

/* Median ms of one render (slot_count 0) or derivative render of slots[0..slot_count) on 1 thread. */
static double time_render(const mr_render_plan *plan, const mr_brdf_model *m, const double *values, const int *slots,
                          int slot_count, mr_image *const *images) {
    double samples[RUNS];
    for (int r = 0; r < RUNS; r++) {
        double t0 = bench_now();
        mr_status status = slot_count == 0 ? mr_render_into_threads(plan, 1, m, values, MR_COMPONENT_FULL, images[0])
                                           : mr_render_derivatives_into(plan, 1, m, values, MR_COMPONENT_FULL, slots,
                                                                        slot_count, images);
        if (status != MR_OK) fprintf(stderr, "bench_brdf_grad: %s\n", mr_last_error());
        samples[r] = 1e3 * (bench_now() - t0);
    }
    return bench_median(samples, RUNS);
}

static void render_table(int argc, char **argv, int first_model) {
    mr_scene scene = mr_scene_fit(&(mr_fit_scene_options){64, MR_FIT_LIGHT_45, 0});
    mr_render_plan *plan = NULL;
    mr_image *images[6] = {NULL};
    if (mr_render_plan_create(&scene, &plan) != MR_OK) {
        fprintf(stderr, "bench_brdf_grad: %s\n", mr_last_error());
        return;
    }
    for (int k = 0; k < 6; k++)
        if (mr_image_create(64, 64, 3, &images[k]) != MR_OK) return;
    printf("\n| model | k slots | render ms | derivative render ms (grad_ops) | /render | "
           "derivative render ms (eval_grad, k+1) | /render |\n|---|---:|---:|---:|---:|---:|---:|\n");
    for (const mr_brdf_model *const *mp = mr_brdf_models(); *mp; mp++) {
        const mr_brdf_model *m = *mp;
        if (!model_wanted(m, argc, argv, first_model)) continue;
        if (!m->eval_grad) continue;
        double values[MR_BRDF_MAX_VALUES];
        mr_brdf_default_values(m, values);
        for (int i = 0, slot = 0; i < m->param_count; i++)
            for (int c = 0; c < m->params[i].channels; c++, slot++)
                if (m->params[i].role != MR_PARAM_SWITCH && !(m->params[i].flags & MR_PARAM_FIT_FIXED))
                    values[slot] = m->params[i].min_value + (0.1 + 0.8 * rnd()) * (fmin(m->params[i].max_value,
                                                                                        4.0) - m->params[i].min_value);
        int slots[6], k = fitted_slots(m, slots);
        slots[k] = slots[0];
        double plain = time_render(plan, m, values, NULL, 0, images);
        double fast = m->grad_ops ? time_render(plan, m, values, slots, k, images) : 0.0;
        double full = time_render(plan, m, values, slots, k + 1, images);
        if (m->grad_ops)
            printf("| %s | %d | %.3f | %.3f | %.1f | %.3f | %.1f |\n", m->name, k, plain, fast, fast / plain, full,
                   full / plain);
        else
            printf("| %s | %d | %.3f | - | - | %.3f | %.1f |\n", m->name, k, plain, full, full / plain);
    }
    for (int k = 0; k < 6; k++) mr_image_free(images[k]);
    mr_render_plan_free(plan);
}

int main(int argc, char **argv) {
    int pairs = PAIRS, first_model = 1;
    if (argc > 1 && strcmp(argv[1], "--quick") == 0) {
        pairs = PAIRS / 8;
        first_model = 2;
    }
    for (int k = 0; k < PAIRS; k++) {
        random_dir(wi[k]);
        random_dir(wo[k]);
    }
    printf("| model | values | eval ns | prepare+eval ns | eval_grad ns | grad/eval | grad/(prepare+eval) | "
           "prepared grad, k slots: ns | /eval | grad prepare ns |\n");
    printf("|---|---|---:|---:|---:|---:|---:|---:|---:|---:|\n");
    for (const mr_brdf_model *const *mp = mr_brdf_models(); *mp; mp++) {
        const mr_brdf_model *m = *mp;
        if (!model_wanted(m, argc, argv, first_model)) continue;
        if (!m->eval_grad) {
            printf("| %s | - | - | - | none | - | - | - | - | - |\n", m->name);
            continue;
        }
        double values[2][MR_BRDF_MAX_VALUES];
        mr_brdf_default_values(m, values[0]);
        for (int i = 0, slot = 0; i < m->param_count; i++) {
            const mr_brdf_param *p = &m->params[i];
            for (int c = 0; c < p->channels; c++, slot++)
                values[1][slot] = p->role == MR_PARAM_SWITCH ? values[0][slot]
                                                            : p->min_value + (0.1 + 0.8 * rnd()) * (p->max_value -
                                                                                                   p->min_value);
        }
        for (int set = 0; set < 2; set++) {
            double e = time_mode(m, values[set], 0, pairs), pe = time_mode(m, values[set], 1, pairs);
            double g = time_mode(m, values[set], 2, pairs);
            printf("| %s | %s | %.0f | %.0f | %.0f | %.1f | %.2f |", m->name, set ? "random" : "defaults", e, pe, g,
                   g / e, g / pe);
            if (m->grad_ops) {
                int slots[5], k = fitted_slots(m, slots);
                double pg = time_mode(m, values[set], 3, pairs), pp = time_mode(m, values[set], 4, pairs);
                printf(" k=%d: %.0f | %.1f | %.0f |\n", k, pg, pg / e, pp);
            } else {
                printf(" - | - | - |\n");
            }
        }
    }
    render_table(argc, argv, first_model);
    return 0;
}
