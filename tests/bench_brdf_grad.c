/*
 * bench_brdf_grad.c — what the analytic parameter derivatives cost against the evaluation, per model, one thread.
 *
 * For every registered model, at its default values and at random in-range values, over the same 4096 random
 * direction pairs: the nanoseconds of one eval with a prepared state (what the render loop does per hit), of one
 * prepare + eval (a parameter set per point), and of one eval_grad (which takes the values, so it includes the
 * work of prepare: the fit's local stage calls it per point sample with one parameter set). Medians of 7 runs; the
 * ratios grad/eval and grad/(prepare + eval) are what docs/brdfs.md quotes per model.
 *
 * Usage: bench_brdf_grad [--quick] [MODEL...]
 */
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include "bench_util.h"
#include "brdf/brdf.h"

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

/* ns per call of mode 0 (eval, prepared), 1 (prepare + eval), 2 (eval_grad) over the PAIRS pairs; median of RUNS */
static double time_mode(const mr_brdf_model *m, const double *values, int mode, int pairs) {
    double samples[RUNS], acc = 0.0;
    mr_brdf_state st;
    m->prepare(m, values, st.bytes);
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
            } else {
                m->eval_grad(m, values, wi[k], wo[k], gd, gs);
                acc += gd[0] + gs[3];
            }
        }
        samples[r] = (bench_now() - t0) * 1e9 / pairs;
    }
    sink = acc;
    return bench_median(samples, RUNS);
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
    printf("| model | values | eval ns | prepare+eval ns | eval_grad ns | grad/eval | grad/(prepare+eval) |\n");
    printf("|---|---|---:|---:|---:|---:|---:|\n");
    for (const mr_brdf_model *const *mp = mr_brdf_models(); *mp; mp++) {
        const mr_brdf_model *m = *mp;
        if (argc > first_model) {
            int wanted = 0;
            for (int a = first_model; a < argc; a++) wanted |= strcmp(argv[a], m->name) == 0;
            if (!wanted) continue;
        }
        if (!m->eval_grad) {
            printf("| %s | - | - | - | none | - | - |\n", m->name);
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
            printf("| %s | %s | %.0f | %.0f | %.0f | %.1f | %.2f |\n", m->name, set ? "random" : "defaults", e, pe, g,
                   g / e, g / pe);
        }
    }
    return 0;
}
