/*
 * test_workflow.c — the metallic <-> specular workflow converters (src/workflow/workflow.h): Eq. 2 known answers,
 * exact round trips, Eq. 3 against the paper's closed form, the MEAN and WEIGHTED single-metallic formulas, the
 * Khronos converter against its JS, every hard case, the custom-method slot, batch == per texel, thread-count
 * independence and argument errors.
 *
 * Expected values are written out here independently of the library (the paper's division forms of Eq. 3, the
 * JS's formulas), never by calling it.
 */
#include <float.h>
#include <math.h>
#include <omp.h>
#include <stdint.h>
#include <string.h>

#include "harness.h"
#include "matremap.h"
#include "workflow/workflow.h"
#include "workflow/workflow_internal.h"
#include "nn/mlp.h"

/* A batch's read-only input view of maps (workflow.h, mr_wf_spec_input / mr_wf_metal_input). */
#define SPEC_IN(m) (&(mr_wf_spec_input){(m).diffuse, (m).specular, (m).roughness})
#define METAL_IN(m) (&(mr_wf_metal_input){(m).albedo, (m).metallic, (m).roughness})

static mr_wf_options options(mr_wf_method method, double f0) {
    mr_wf_options o = mr_wf_options_default();
    o.method = method;
    o.dielectric_f0 = f0;
    return o;
}

static mr_wf_spec to_spec(const mr_wf_options *o, double r, double g, double b, double m, unsigned *flags) {
    mr_wf_metal in = {{r, g, b}, m, 0.5};
    mr_wf_spec out;
    memset(&out, 0, sizeof out);
    MR_CHECK_OK(mr_wf_metal_to_spec(&in, o, &out, flags));
    return out;
}

static mr_wf_metal to_metal(const mr_wf_options *o, const double d[3], const double s[3], unsigned *flags) {
    mr_wf_spec in = {{d[0], d[1], d[2]}, {s[0], s[1], s[2]}, 0.5};
    mr_wf_metal out;
    memset(&out, 0, sizeof out);
    MR_CHECK_OK(mr_wf_spec_to_metal(&in, o, &out, flags));
    return out;
}

/* Every output value finite and in [0, 1]. */
static int metal_in_range(const mr_wf_metal *m) {
    int ok = isfinite(m->metallic) && m->metallic >= 0.0 && m->metallic <= 1.0 && isfinite(m->roughness);
    for (int c = 0; c < 3; c++) ok = ok && isfinite(m->albedo[c]) && m->albedo[c] >= 0.0 && m->albedo[c] <= 1.0;
    return ok;
}

static int spec_in_range(const mr_wf_spec *s) {
    int ok = isfinite(s->roughness);
    for (int c = 0; c < 3; c++)
        ok = ok && isfinite(s->diffuse[c]) && s->diffuse[c] >= 0.0 && s->diffuse[c] <= 1.0 && isfinite(s->specular[c])
             && s->specular[c] >= 0.0 && s->specular[c] <= 1.0;
    return ok;
}

/* splitmix64: a deterministic stream of doubles in [0, 1). */
static double uniform(uint64_t *state) {
    uint64_t z = (*state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    z ^= z >> 31;
    return (double)(z >> 11) * 0x1.0p-53;
}

/* A texel value: mostly in [0, 1], sometimes a hard one (0, 1, F0d, outside [0, 1], NaN, infinities). */
static float texel_value(uint64_t *state) {
    double u = uniform(state), v = uniform(state);
    if (u < 0.85) return (float)v;
    static const float hard[] = {0.0f, 1.0f, 0.04f, 0.03f, 0.02f, -0.5f, 1.5f, NAN, INFINITY, -INFINITY};
    return hard[(int)(v * (sizeof hard / sizeof hard[0]))];
}

/* ---- names and defaults --------------------------------------------------------------------------------------- */

MR_TEST(method_names_round_trip) {
    for (int i = 0; i < MR_WF_METHOD_COUNT; i++) {
        const char *name = mr_wf_method_name((mr_wf_method)i);
        MR_CHECK(name != NULL);
        mr_wf_method back = MR_WF_METHOD_COUNT;
        MR_CHECK_OK(mr_wf_method_from_name(name, &back));
        MR_CHECK(back == (mr_wf_method)i);
    }
    MR_CHECK(strcmp(mr_wf_method_name(MR_WF_WEIGHTED), "weighted") == 0);
    MR_CHECK(mr_wf_method_name(MR_WF_METHOD_COUNT) == NULL);
    MR_CHECK(mr_wf_method_name((mr_wf_method)-1) == NULL);
    mr_wf_method untouched = MR_WF_KHRONOS;
    MR_CHECK(mr_wf_method_from_name("mlp", &untouched) == MR_ERR_INVALID_ARG);
    MR_CHECK_MSG(strstr(mr_last_error(), "'mlp'") && strstr(mr_last_error(), "weighted"), "%s", mr_last_error());
    MR_CHECK(untouched == MR_WF_KHRONOS);
    MR_CHECK(mr_wf_method_from_name(NULL, &untouched) == MR_ERR_INVALID_ARG);
}

MR_TEST(default_options_are_the_documented_ones) {
    mr_wf_options o = mr_wf_options_default();
    MR_CHECK(o.dielectric_f0 == 0.04 && MR_WF_F0_GLTF == 0.04 && MR_WF_F0_PAPER == 0.03);
    MR_CHECK(o.method == MR_WF_WEIGHTED);
    MR_CHECK(o.eps == 1e-6 && MR_WF_DEFAULT_EPS == 1e-6);
    MR_CHECK(o.custom == NULL && o.custom_data == NULL);
    MR_CHECK_OK(mr_wf_options_check(&o));
    MR_CHECK_OK(mr_wf_options_check(NULL));
    // NULL options are the defaults.
    double d[3] = {0.3, 0.2, 0.1}, s[3] = {0.1, 0.3, 0.05};
    mr_wf_spec in = {{d[0], d[1], d[2]}, {s[0], s[1], s[2]}, 0.25};
    mr_wf_metal a, b;
    unsigned fa = 99, fb = 98;
    MR_CHECK_OK(mr_wf_spec_to_metal(&in, NULL, &a, &fa));
    MR_CHECK_OK(mr_wf_spec_to_metal(&in, &o, &b, &fb));
    MR_CHECK(memcmp(&a, &b, sizeof a) == 0 && fa == fb);
}

/* ---- Eq. 2 ---------------------------------------------------------------------------------------------------- */

MR_TEST(equation_2_known_answers) {
    unsigned flags = 99;
    // albedo (0.9, 0.5, 0.2), m 0.7, F0d 0.04: d = A * 0.3; s = 0.04 * 0.3 + 0.7 A = 0.012 + 0.7 A.
    mr_wf_options gltf = options(MR_WF_WEIGHTED, 0.04);
    mr_wf_spec s = to_spec(&gltf, 0.9, 0.5, 0.2, 0.7, &flags);
    MR_CHECK(flags == 0);
    MR_CHECK_NEAR(s.diffuse[0], 0.27, 1e-15);
    MR_CHECK_NEAR(s.diffuse[1], 0.15, 1e-15);
    MR_CHECK_NEAR(s.diffuse[2], 0.06, 1e-15);
    MR_CHECK_NEAR(s.specular[0], 0.642, 1e-15);
    MR_CHECK_NEAR(s.specular[1], 0.362, 1e-15);
    MR_CHECK_NEAR(s.specular[2], 0.152, 1e-15);
    MR_CHECK(s.roughness == 0.5);
    // The paper's F0d 0.03, m 0.5, albedo (1, 0, 0.5): d = (0.5, 0, 0.25), s = 0.015 + (0.5, 0, 0.25).
    mr_wf_options paper = options(MR_WF_MEAN, 0.03);
    s = to_spec(&paper, 1.0, 0.0, 0.5, 0.5, &flags);
    MR_CHECK_NEAR(s.diffuse[0], 0.5, 1e-15);
    MR_CHECK_NEAR(s.diffuse[1], 0.0, 1e-15);
    MR_CHECK_NEAR(s.diffuse[2], 0.25, 1e-15);
    MR_CHECK_NEAR(s.specular[0], 0.515, 1e-15);
    MR_CHECK_NEAR(s.specular[1], 0.015, 1e-15);
    MR_CHECK_NEAR(s.specular[2], 0.265, 1e-15);
    // A dielectric: diffuse = albedo, specular = F0d; a metal: no diffuse, specular = albedo.
    s = to_spec(&paper, 0.8, 0.6, 0.4, 0.0, &flags);
    for (int c = 0; c < 3; c++) MR_CHECK(s.specular[c] == 0.03);
    MR_CHECK(s.diffuse[0] == 0.8 && s.diffuse[1] == 0.6 && s.diffuse[2] == 0.4);
    s = to_spec(&gltf, 0.95, 0.64, 0.54, 1.0, &flags);
    for (int c = 0; c < 3; c++) MR_CHECK(s.diffuse[c] == 0.0);
    MR_CHECK(s.specular[0] == 0.95 && s.specular[1] == 0.64 && s.specular[2] == 0.54);
    MR_CHECK(flags == 0);
    // Every analytic method and CUSTOM share Eq. 2 for metal -> spec.
    mr_wf_options mean = options(MR_WF_MEAN, 0.04);
    mr_wf_spec t = to_spec(&mean, 0.9, 0.5, 0.2, 0.7, NULL);
    s = to_spec(&gltf, 0.9, 0.5, 0.2, 0.7, NULL);
    MR_CHECK(memcmp(&s, &t, sizeof s) == 0);
}

/* ---- Eq. 3 ---------------------------------------------------------------------------------------------------- */

MR_TEST(round_trip_is_exact_for_mean_and_weighted) {
    static const double albedos[] = {0.05, 0.1, 0.2, 0.35, 0.5, 0.65, 0.8, 0.95, 1.0};
    static const double f0s[] = {MR_WF_F0_GLTF, MR_WF_F0_PAPER};
    const int na = (int)(sizeof albedos / sizeof albedos[0]);
    for (int f = 0; f < 2; f++)
        for (int method = MR_WF_WEIGHTED; method <= MR_WF_MEAN; method++) {
            mr_wf_options o = options((mr_wf_method)method, f0s[f]);
            double worst = 0.0;
            int flagged = 0;
            for (int r = 0; r < na; r++)
                for (int g = 0; g < na; g++)
                    for (int b = 0; b < na; b++)
                        for (int k = 0; k <= 10; k++) {
                            double m = k / 10.0;
                            unsigned f1, f2;
                            mr_wf_spec s = to_spec(&o, albedos[r], albedos[g], albedos[b], m, &f1);
                            mr_wf_metal back = to_metal(&o, s.diffuse, s.specular, &f2);
                            worst = fmax(worst, fabs(back.metallic - m));
                            worst = fmax(worst, fabs(back.albedo[0] - albedos[r]));
                            worst = fmax(worst, fabs(back.albedo[1] - albedos[g]));
                            worst = fmax(worst, fabs(back.albedo[2] - albedos[b]));
                            flagged += (f1 | f2) != 0;
                        }
            MR_CHECK_MSG(worst <= 1e-12, "%s F0d %g: worst round-trip error %g", mr_wf_method_name(o.method),
                         o.dielectric_f0, worst);
            MR_CHECK_MSG(flagged == 0, "%s F0d %g: %d texels flagged", mr_wf_method_name(o.method),
                         o.dielectric_f0, flagged);
        }
}

MR_TEST(float_batch_round_trip_is_exact_within_float_rounding) {
    enum { N = 2000 };
    static float albedo[3 * N], metallic[N], diffuse[3 * N], specular[3 * N], albedo2[3 * N], metallic2[N];
    static uint8_t flags[N];
    uint64_t rng = 7;
    for (int i = 0; i < N; i++) {
        for (int c = 0; c < 3; c++) albedo[3 * i + c] = (float)(0.05 + 0.95 * uniform(&rng));
        metallic[i] = (float)uniform(&rng);
    }
    for (int method = MR_WF_WEIGHTED; method <= MR_WF_MEAN; method++) {
        mr_wf_options o = options((mr_wf_method)method, MR_WF_F0_PAPER);
        mr_wf_metal_maps metal = {albedo, metallic, NULL}, back = {albedo2, metallic2, NULL};
        mr_wf_spec_maps spec = {diffuse, specular, NULL};
        MR_CHECK_OK(mr_wf_metal_to_spec_batch(METAL_IN(metal), N, &o, &spec, flags));
        MR_CHECK_OK(mr_wf_spec_to_metal_batch(SPEC_IN(spec), N, &o, &back, flags));
        double worst = 0.0;
        int flagged = 0;
        for (int i = 0; i < N; i++) {
            worst = fmax(worst, fabs(metallic2[i] - metallic[i]));
            for (int c = 0; c < 3; c++) worst = fmax(worst, fabs(albedo2[3 * i + c] - albedo[3 * i + c]));
            flagged += flags[i] != 0;
        }
        MR_CHECK_MSG(worst <= 1e-6, "%s: worst float round-trip error %g", mr_wf_method_name(o.method), worst);
        MR_CHECK_MSG(flagged == 0, "%s: %d texels flagged", mr_wf_method_name(o.method), flagged);
    }
}

/* The paper's Eq. 3 with F0d = 0.03 in the closed form of brdf-reference 5.4 "[derived]", divisions and all. */
static void paper_eq3(double d, double s, double *albedo, double *metallic) {
    *albedo = (s + d) / 2.0 * (1.0 + sqrt(1.0 - 0.12 * d / ((s + d) * (s + d))));
    *metallic = (s - 0.03) / (*albedo - 0.03);
}

MR_TEST(equation_3_matches_the_closed_form_with_the_papers_f0) {
    // Grey texels: every (d, s) whose Eq. 3 solution is a metallic material (A in (0.03, 1], m in [0, 1]) is on
    // the manifold, so both methods must return the closed form exactly.
    int compared = 0;
    for (int i = 0; i <= 40; i++)
        for (int j = 0; j <= 40; j++) {
            double d = i / 40.0, s = j / 40.0;
            if (s + d == 0.0 || 1.0 - 0.12 * d / ((s + d) * (s + d)) < 0.0) continue;
            double a, m;
            paper_eq3(d, s, &a, &m);
            if (!(a > 0.03 + 1e-3 && a <= 1.0 && m >= 0.0 && m <= 1.0)) continue;
            for (int method = MR_WF_WEIGHTED; method <= MR_WF_MEAN; method++) {
                mr_wf_options o = options((mr_wf_method)method, MR_WF_F0_PAPER);
                double dd[3] = {d, d, d}, ss[3] = {s, s, s};
                unsigned flags;
                mr_wf_metal out = to_metal(&o, dd, ss, &flags);
                MR_CHECK_NEAR(out.metallic, m, 1e-12);
                for (int c = 0; c < 3; c++) MR_CHECK_NEAR(out.albedo[c], a, 1e-12);
                MR_CHECK_MSG(flags == 0, "d %g s %g: flags %u", d, s, flags);
            }
            compared++;
        }
    MR_CHECK_MSG(compared > 300, "only %d grey texels in the domain", compared);
}

/* Residual of Eq. 2 with albedo a and metallic m against (d, s), F0d f0. */
static double eq2_residual(double a, double m, double f0, double d, double s) {
    double rd = a * (1.0 - m) - d, rs = f0 + m * (a - f0) - s;
    return rd * rd + rs * rs;
}

MR_TEST(mean_and_weighted_follow_their_formulas_off_the_manifold) {
    // A coloured texel whose channels want different metallic values (off the manifold); each channel's Eq. 3
    // solution is in the ordinary region (A > 0.03, m in [0, 1]).
    double d[3] = {0.5, 0.2, 0.05}, s[3] = {0.3, 0.1, 0.6};
    double a[3], m[3];
    for (int c = 0; c < 3; c++) {
        paper_eq3(d[c], s[c], &a[c], &m[c]);
        MR_CHECK(a[c] > 0.03 && m[c] >= 0.0 && m[c] <= 1.0);
    }
    double mean = (m[0] + m[1] + m[2]) / 3.0;
    double weighted = (a[0] * m[0] + a[1] * m[1] + a[2] * m[2]) / (a[0] + a[1] + a[2]);
    // On Eq. 3's solutions A m = A - d, so the weighted mean is also 1 - sum d / sum A.
    MR_CHECK_NEAR(weighted, 1.0 - (d[0] + d[1] + d[2]) / (a[0] + a[1] + a[2]), 1e-12);
    for (int method = MR_WF_WEIGHTED; method <= MR_WF_MEAN; method++) {
        mr_wf_options o = options((mr_wf_method)method, MR_WF_F0_PAPER);
        unsigned flags;
        mr_wf_metal out = to_metal(&o, d, s, &flags);
        double want = method == MR_WF_MEAN ? mean : weighted;
        MR_CHECK_NEAR(out.metallic, want, 1e-12);
        MR_CHECK(flags == MR_WF_OFF_MANIFOLD);
        for (int c = 0; c < 3; c++) {
            // The albedo is the least-squares fit of Eq. 2 for that metallic, clamped to [0, 1].
            double k = 1.0 - want;
            double lsq = (k * d[c] + want * (s[c] - 0.03 * k)) / (k * k + want * want);
            MR_CHECK_NEAR(out.albedo[c], fmin(fmax(lsq, 0.0), 1.0), 1e-12);
            // ... and no nearby albedo does better.
            if (lsq > 1e-3 && lsq < 1.0 - 1e-3) {
                double best = eq2_residual(out.albedo[c], want, 0.03, d[c], s[c]);
                MR_CHECK(best <= eq2_residual(out.albedo[c] + 1e-3, want, 0.03, d[c], s[c]));
                MR_CHECK(best <= eq2_residual(out.albedo[c] - 1e-3, want, 0.03, d[c], s[c]));
            }
        }
    }
}

/* ---- Khronos -------------------------------------------------------------------------------------------------- */

/* The JS's formulas written out for one texel (brdf-reference 5.4), independently of src/workflow/khronos.c. */
static double js_brightness(const double c[3]) {
    return sqrt(0.299 * c[0] * c[0] + 0.587 * c[1] * c[1] + 0.114 * c[2] * c[2]);
}

static void js_spec_to_metal(const double diffuse[3], const double specular[3], double base[3], double *metallic) {
    double o = 1.0 - fmax(specular[0], fmax(specular[1], specular[2]));
    double s = js_brightness(specular), d = js_brightness(diffuse), m = 0.0;
    if (s >= 0.04) {
        double b = d * o / 0.96 + s - 0.08, c = 0.04 - s;
        m = (-b + sqrt(fmax(b * b - 0.16 * c, 0.0))) / 0.08;
        m = fmin(fmax(m, 0.0), 1.0);
    }
    for (int k = 0; k < 3; k++) {
        double from_diffuse = diffuse[k] * o / 0.96 / fmax(1.0 - m, 1e-6);
        double from_specular = (specular[k] - 0.04 * (1.0 - m)) / fmax(m, 1e-6);
        base[k] = fmin(fmax(from_diffuse + (from_specular - from_diffuse) * m * m, 0.0), 1.0);
    }
    *metallic = m;
}

MR_TEST(khronos_matches_its_javascript) {
    mr_wf_options o = options(MR_WF_KHRONOS, 0.04);
    // metal -> spec. Literals: the archived three.pbrUtilities.js run under node 20 with a three.js Color shim
    // (17 significant digits). The formulas are also written out for the first texel.
    static const struct {
        double base[3], metallic, diffuse[3], specular[3];
    } forward[] = {
        {{0.9, 0.5, 0.2}, 0.7, {0.72402234636871521, 0.40223463687150846, 0.16089385474860340}, {0.642, 0.362, 0.152}},
        {{0.8, 0.2, 0.1}, 0.0, {0.8, 0.2, 0.1}, {0.04, 0.04, 0.04}},
        {{1.0, 0.78, 0.34}, 1.0, {0.0, 0.0, 0.0}, {1.0, 0.78, 0.34}},
        {{0.3, 0.6, 0.9}, 0.35, {0.28406676783004547, 0.56813353566009095, 0.85220030349013653},
         {0.131, 0.236, 0.341}},
    };
    // specular = lerp(0.04, base, 0.7) = (0.642, 0.362, 0.152); diffuse = base * 0.96 * 0.3 / (1 - 0.642).
    MR_CHECK_NEAR(forward[0].diffuse[0], 0.9 * 0.96 * 0.3 / 0.358, 1e-15);
    MR_CHECK_NEAR(forward[0].diffuse[2], 0.2 * 0.96 * 0.3 / 0.358, 1e-15);
    for (size_t i = 0; i < sizeof forward / sizeof forward[0]; i++) {
        unsigned flags;
        mr_wf_spec s = to_spec(&o, forward[i].base[0], forward[i].base[1], forward[i].base[2], forward[i].metallic,
                               &flags);
        MR_CHECK(flags == 0);
        for (int c = 0; c < 3; c++) {
            MR_CHECK_NEAR(s.diffuse[c], forward[i].diffuse[c], 1e-15);
            MR_CHECK_NEAR(s.specular[c], forward[i].specular[c], 1e-15);
        }
    }
    // spec -> metal, the same way; plus the formulas above for each texel.
    static const struct {
        double diffuse[3], specular[3], base[3], metallic;
    } backward[] = {
        {{0.5, 0.3, 0.1}, {0.04, 0.04, 0.04}, {0.5, 0.3, 0.1}, 0.0},
        {{0.1, 0.1, 0.2}, {0.5, 0.4, 0.3}, {0.53011266092627907, 0.44272753139521870, 0.45293882349491893},
         0.87385129531060357},
        {{0.2, 0.1, 0.05}, {0.03, 0.02, 0.01}, {0.20208333333333336, 0.10104166666666668, 0.050520833333333341}, 0.0},
        {{0.0, 0.0, 0.0}, {0.95, 0.64, 0.54}, {0.94999999999999951, 0.63999999999999979, 0.53999999999999981},
         0.99999999999999944},
    };
    for (size_t i = 0; i < sizeof backward / sizeof backward[0]; i++) {
        unsigned flags;
        mr_wf_metal m = to_metal(&o, backward[i].diffuse, backward[i].specular, &flags);
        double base[3], metallic;
        js_spec_to_metal(backward[i].diffuse, backward[i].specular, base, &metallic);
        MR_CHECK_NEAR(m.metallic, backward[i].metallic, 1e-14);
        MR_CHECK_NEAR(m.metallic, metallic, 1e-14);
        for (int c = 0; c < 3; c++) {
            MR_CHECK_NEAR(m.albedo[c], backward[i].base[c], 1e-12);
            MR_CHECK_NEAR(m.albedo[c], base[c], 1e-12);
        }
        MR_CHECK(metal_in_range(&m));
    }
    // An albedo channel of 1 makes the JS's diffuse 0.96 (1 - m) / (1 - (0.04 + 0.96 m)), 1 in exact arithmetic
    // but up to ~1e-12 above it in doubles; the library's results stay within [0, 1].
    for (int k = 0; k <= 1000; k++) {
        mr_wf_spec s = to_spec(&o, 1.0, 0.3, 0.7, k / 1000.0, NULL);
        MR_CHECK_MSG(spec_in_range(&s), "metallic %g: diffuse %.17g", k / 1000.0, s.diffuse[0]);
        MR_CHECK_NEAR(s.diffuse[0], k == 1000 ? 0.0 : 1.0, 1e-11);
    }
    // The specular below 0.04 of the third texel is not reachable by Khronos's forward conversion.
    unsigned flags;
    to_metal(&o, backward[2].diffuse, backward[2].specular, &flags);
    MR_CHECK(flags == MR_WF_OFF_MANIFOLD);
}

MR_TEST(khronos_round_trip_within_its_known_tolerance) {
    // Khronos's inverse works on perceived brightness, a norm that is linear along grey only: its round trip is
    // exact for grey bases and at metallic 0 and 1, and lossy for coloured partial metals. Over this grid
    // (channels in [0.05, 1]) the loss is at most 0.055 in metallic and 0.036 in base colour.
    static const double vals[] = {0.05, 0.1, 0.2, 0.35, 0.5, 0.65, 0.8, 0.9, 1.0};
    const int nv = (int)(sizeof vals / sizeof vals[0]);
    mr_wf_options o = options(MR_WF_KHRONOS, 0.04);
    double worst_m = 0.0, worst_a = 0.0, worst_exact = 0.0;
    for (int r = 0; r < nv; r++)
        for (int g = 0; g < nv; g++)
            for (int b = 0; b < nv; b++)
                for (int k = 0; k <= 10; k++) {
                    double m = k / 10.0;
                    mr_wf_spec s = to_spec(&o, vals[r], vals[g], vals[b], m, NULL);
                    mr_wf_metal back = to_metal(&o, s.diffuse, s.specular, NULL);
                    double em = fabs(back.metallic - m), ea = 0.0;
                    ea = fmax(ea, fabs(back.albedo[0] - vals[r]));
                    ea = fmax(ea, fabs(back.albedo[1] - vals[g]));
                    ea = fmax(ea, fabs(back.albedo[2] - vals[b]));
                    worst_m = fmax(worst_m, em);
                    worst_a = fmax(worst_a, ea);
                    if ((r == g && g == b) || k == 0 || k == 10) worst_exact = fmax(worst_exact, fmax(em, ea));
                }
    MR_CHECK_MSG(worst_exact <= 1e-9, "grey / m in {0, 1}: worst %g", worst_exact);
    MR_CHECK_MSG(worst_m <= 0.06, "worst metallic error %g", worst_m);
    MR_CHECK_MSG(worst_a <= 0.04, "worst base colour error %g", worst_a);
    MR_CHECK_MSG(worst_m >= 0.01, "worst metallic error %g: the known loss vanished?", worst_m);
}

/* ---- hard cases ----------------------------------------------------------------------------------------------- */

MR_TEST(black_is_a_black_metal) {
    // d = s = 0 is reachable only with albedo 0 and metallic 1 (a dielectric always reflects F0d).
    double zero[3] = {0.0, 0.0, 0.0};
    static const double f0s[] = {0.04, 0.03};
    for (int f = 0; f < 2; f++)
        for (int method = MR_WF_WEIGHTED; method <= MR_WF_MEAN; method++) {
            mr_wf_options o = options((mr_wf_method)method, f0s[f]);
            unsigned flags;
            mr_wf_metal m = to_metal(&o, zero, zero, &flags);
            MR_CHECK(m.metallic == 1.0 && m.albedo[0] == 0.0 && m.albedo[1] == 0.0 && m.albedo[2] == 0.0);
            MR_CHECK(flags == 0);
            mr_wf_spec s = to_spec(&o, m.albedo[0], m.albedo[1], m.albedo[2], m.metallic, NULL);
            for (int c = 0; c < 3; c++) MR_CHECK(s.diffuse[c] == 0.0 && s.specular[c] == 0.0);
        }
    // With a vanishing F0d (DBL_MIN; 0 is the default 0.04) black is albedo 0 with any metallic; the least
    // metallic, 0, is returned.
    mr_wf_options o = options(MR_WF_WEIGHTED, DBL_MIN);
    unsigned flags;
    mr_wf_metal m = to_metal(&o, zero, zero, &flags);
    MR_CHECK(m.metallic == 0.0 && m.albedo[0] == 0.0 && flags == 0);
    // Khronos reads black as a black dielectric (it cannot reproduce it: F0 0.04).
    o = options(MR_WF_KHRONOS, 0.04);
    m = to_metal(&o, zero, zero, &flags);
    MR_CHECK(m.metallic == 0.0 && m.albedo[0] == 0.0 && flags == MR_WF_OFF_MANIFOLD);
    // Nearly black, unreachable inputs stay finite and flagged.
    double tiny[3] = {1e-7, 1e-7, 1e-7};
    for (int method = MR_WF_WEIGHTED; method < MR_WF_CUSTOM; method++) {
        o = options((mr_wf_method)method, 0.04);
        m = to_metal(&o, tiny, tiny, &flags);
        MR_CHECK(metal_in_range(&m));
    }
}

/* metal -> spec -> metal of albedo (r, g, b) and metallic m is exact and clean under MEAN and WEIGHTED. */
static void exact_under_mean_and_weighted(double r, double g, double b, double m) {
    static const mr_wf_method methods[2] = {MR_WF_MEAN, MR_WF_WEIGHTED};
    for (int k = 0; k < 2; k++) {
        const mr_wf_method method = methods[k];
        mr_wf_options o = options(method, 0.04);
        unsigned flags;
        mr_wf_spec s = to_spec(&o, r, g, b, m, NULL);
        mr_wf_metal back = to_metal(&o, s.diffuse, s.specular, &flags);
        MR_CHECK_NEAR(back.metallic, m, 1e-12);
        MR_CHECK_NEAR(back.albedo[0], r, 1e-12);
        MR_CHECK_NEAR(back.albedo[1], g, 1e-12);
        MR_CHECK_NEAR(back.albedo[2], b, 1e-12);
        MR_CHECK(flags == 0);
    }
}

MR_TEST(albedo_at_or_below_the_dielectric_f0) {
    // Dark dielectrics (albedo <= F0d, m = 0): Eq. 3's root is F0d itself, whose m = 1 - d/F0d would call them
    // metals; the channel is ambiguous and the less metallic solution, m = 0 with A = d, is taken.
    for (int method = MR_WF_WEIGHTED; method <= MR_WF_MEAN; method++)
        for (int f = 0; f < 2; f++) {
            double f0 = f == 0 ? 0.04 : 0.03;
            mr_wf_options o = options((mr_wf_method)method, f0);
            static const double darks[][3] = {{0.02, 0.02, 0.02}, {0.0, 0.0, 0.0}, {0.8, 0.01, 0.02},
                                              {0.03, 0.03, 0.03}, {0.04, 0.04, 0.04}, {0.5, 0.3, 0.0}};
            for (size_t i = 0; i < sizeof darks / sizeof darks[0]; i++) {
                unsigned f1, f2;
                mr_wf_spec s = to_spec(&o, darks[i][0], darks[i][1], darks[i][2], 0.0, &f1);
                mr_wf_metal m = to_metal(&o, s.diffuse, s.specular, &f2);
                MR_CHECK_MSG(m.metallic <= 1e-9, "%s F0d %g texel %zu: metallic %g", mr_wf_method_name(o.method), f0,
                             i, m.metallic);
                for (int c = 0; c < 3; c++) MR_CHECK_NEAR(m.albedo[c], darks[i][c], 1e-9);
                MR_CHECK(f1 == 0 && f2 == 0);
            }
            // ... also through float storage, where 0.04f is not 0.04 (eps absorbs it).
            float alb[3] = {0.02f, 0.8f, 0.01f}, met = 0.0f, d[3], sp[3], a2[3], m2;
            uint8_t fl;
            mr_wf_metal_maps in = {alb, &met, NULL}, back = {a2, &m2, NULL};
            mr_wf_spec_maps spec = {d, sp, NULL};
            MR_CHECK_OK(mr_wf_metal_to_spec_batch(METAL_IN(in), 1, &o, &spec, &fl));
            MR_CHECK_OK(mr_wf_spec_to_metal_batch(SPEC_IN(spec), 1, &o, &back, &fl));
            MR_CHECK(m2 <= 1e-6f && fabsf(a2[0] - 0.02f) <= 1e-6f && fabsf(a2[2] - 0.01f) <= 1e-6f && fl == 0);
        }
    // A partial metal darker than F0d on the double root: (A 0.02, m 0.5) is the only solution, recovered exactly.
    mr_wf_options o = options(MR_WF_MEAN, 0.04);
    unsigned flags;
    mr_wf_spec s = to_spec(&o, 0.02, 0.02, 0.02, 0.5, NULL);
    mr_wf_metal m = to_metal(&o, s.diffuse, s.specular, &flags);
    MR_CHECK_NEAR(m.metallic, 0.5, 1e-6);
    MR_CHECK_NEAR(m.albedo[0], 0.02, 1e-6);
    MR_CHECK(flags == 0);
    // A metal darker than F0d: d = 0, s = 0.02 is also (A 0, m 0.5); the less metallic twin is returned, and it
    // renders the same (no flag).
    s = to_spec(&o, 0.02, 0.02, 0.02, 1.0, NULL);
    m = to_metal(&o, s.diffuse, s.specular, &flags);
    MR_CHECK_NEAR(m.metallic, 0.5, 1e-12);
    MR_CHECK_NEAR(m.albedo[0], 0.0, 1e-12);
    MR_CHECK(flags == 0);
    // Such a channel in a bright metal: ambiguous, it takes the reading the other channels agree with (1, not its
    // twin's 0.5), so both single-metallic choices stay exact (the plain mean used to average in the 0.5).
    exact_under_mean_and_weighted(0.9, 0.6, 0.02, 1.0);
    // ... and in a partial metal: albedo (0.6, 0.3, 0.03), m 0.5 gives blue (d 0.015, s 0.035), whose roots are
    // 0.03 (m 0.5) and 0.02 (m 0.25); the red and green channels say 0.5, so blue takes 0.5 and the texel is exact.
    exact_under_mean_and_weighted(0.6, 0.3, 0.03, 0.5);
    // Every channel ambiguous: nothing to follow, the less metallic reading stays (a dark grey metal, A 0.03, m 1:
    // d 0, s 0.03, read as its twin A 0, m 0.25; it renders the same).
    s = to_spec(&o, 0.03, 0.03, 0.03, 1.0, NULL);
    m = to_metal(&o, s.diffuse, s.specular, &flags);
    MR_CHECK_NEAR(m.metallic, 0.25, 1e-12);
    MR_CHECK_NEAR(m.albedo[0], 0.0, 1e-12);
    MR_CHECK(flags == 0);
}

MR_TEST(negative_discriminant_and_specular_above_albedo) {
    mr_wf_options o = options(MR_WF_MEAN, 0.04);
    unsigned flags;
    // (s + d)^2 < 4 F0d d: no exact solution. The discriminant is clamped to 0, A = (s + d)/2 = 0.0205 <= F0d, so
    // the less metallic reading m = 1 - A/F0d applies.
    double d[3] = {0.02, 0.02, 0.02}, s[3] = {0.021, 0.021, 0.021};
    MR_CHECK((0.041 * 0.041) - 4.0 * 0.04 * 0.02 < 0.0);
    mr_wf_metal m = to_metal(&o, d, s, &flags);
    MR_CHECK_NEAR(m.metallic, 1.0 - 0.0205 / 0.04, 1e-12);
    MR_CHECK(metal_in_range(&m) && flags == MR_WF_OFF_MANIFOLD);
    // A negative discriminant with A > F0d: m_c = 1 - d/A < 0 is clamped to 0.
    double d2[3] = {0.1, 0.1, 0.1}, s2[3] = {0.0, 0.0, 0.0};
    m = to_metal(&o, d2, s2, &flags);
    MR_CHECK(m.metallic == 0.0 && metal_in_range(&m) && flags == MR_WF_OFF_MANIFOLD);
    MR_CHECK_NEAR(m.albedo[0], 0.1, 1e-12);
    // Specular far above what the albedo allows (Eq. 2 would need albedo 1.39): the least-squares albedo exceeds 1
    // and is clamped. Khronos's model, whose diffuse is renormalised by (1 - max s)/0.96, does reach this texel
    // (base 0.950, metallic 0.945), so it is not flagged there.
    double d3[3] = {0.5, 0.5, 0.5}, s3[3] = {0.9, 0.9, 0.9};
    for (int method = MR_WF_WEIGHTED; method < MR_WF_CUSTOM; method++) {
        o = options((mr_wf_method)method, 0.04);
        m = to_metal(&o, d3, s3, &flags);
        MR_CHECK(metal_in_range(&m));
        if (method != MR_WF_KHRONOS) MR_CHECK(m.albedo[0] == 1.0 && flags == MR_WF_OFF_MANIFOLD);
        if (method == MR_WF_KHRONOS) MR_CHECK_NEAR(m.albedo[0], 0.94989009714781059, 1e-12);
        if (method == MR_WF_KHRONOS) MR_CHECK(flags == 0);
    }
    // A white Lambertian with no specular: a dielectric must reflect F0d, so it is read as m = 0, albedo 1.
    double d4[3] = {1.0, 1.0, 1.0}, s4[3] = {0.0, 0.0, 0.0};
    o = options(MR_WF_WEIGHTED, 0.04);
    m = to_metal(&o, d4, s4, &flags);
    MR_CHECK(m.metallic == 0.0 && m.albedo[0] == 1.0 && flags == MR_WF_OFF_MANIFOLD);
}

MR_TEST(inputs_outside_0_1_are_clamped_and_flagged) {
    for (int method = MR_WF_WEIGHTED; method < MR_WF_CUSTOM; method++) {
        mr_wf_options o = options((mr_wf_method)method, 0.04);
        unsigned flags, clean_flags;
        mr_wf_spec in = {{1.5, -0.2, 0.5}, {0.3, 2.0, -1e30}, 7.0};
        mr_wf_spec clamped = {{1.0, 0.0, 0.5}, {0.3, 1.0, 0.0}, 1.0};
        mr_wf_metal a, b;
        MR_CHECK_OK(mr_wf_spec_to_metal(&in, &o, &a, &flags));
        MR_CHECK_OK(mr_wf_spec_to_metal(&clamped, &o, &b, &clean_flags));
        MR_CHECK(memcmp(&a, &b, sizeof a) == 0 && a.roughness == 1.0);
        MR_CHECK(flags == (clean_flags | MR_WF_CLAMPED_INPUT));
        MR_CHECK(metal_in_range(&a));

        mr_wf_metal min = {{2.0, 0.5, -3.0}, -1.0, -0.5}, mclamped = {{1.0, 0.5, 0.0}, 0.0, 0.0};
        mr_wf_spec sa, sb;
        MR_CHECK_OK(mr_wf_metal_to_spec(&min, &o, &sa, &flags));
        MR_CHECK_OK(mr_wf_metal_to_spec(&mclamped, &o, &sb, &clean_flags));
        MR_CHECK(memcmp(&sa, &sb, sizeof sa) == 0 && flags == MR_WF_CLAMPED_INPUT && clean_flags == 0);
        MR_CHECK(spec_in_range(&sa));
        // Only the roughness out of range.
        mr_wf_metal rough = {{0.5, 0.5, 0.5}, 0.5, 1.25};
        MR_CHECK_OK(mr_wf_metal_to_spec(&rough, &o, &sa, &flags));
        MR_CHECK(flags == MR_WF_CLAMPED_INPUT && sa.roughness == 1.0);
    }
}

/* Non-finite colours and metallic read as 0; a non-finite roughness as 1 (fully rough, never a mirror). */
MR_TEST(non_finite_inputs_are_flagged_and_read_as_zero) {
    static const double bad[] = {NAN, INFINITY, -INFINITY};
    for (int method = MR_WF_WEIGHTED; method < MR_WF_CUSTOM; method++) {
        mr_wf_options o = options((mr_wf_method)method, 0.04);
        for (int k = 0; k < 3; k++)
            for (int slot = 0; slot < 7; slot++) {
                // spec -> metal: the bad value in each of the 7 inputs.
                mr_wf_spec in = {{0.3, 0.2, 0.1}, {0.5, 0.4, 0.3}, 0.6};
                double *v = slot < 3 ? &in.diffuse[slot] : slot < 6 ? &in.specular[slot - 3] : &in.roughness;
                mr_wf_spec zeroed = in;
                double *z = slot < 3   ? &zeroed.diffuse[slot]
                            : slot < 6 ? &zeroed.specular[slot - 3]
                                       : &zeroed.roughness;
                *v = bad[k];
                *z = slot == 6 ? 1.0 : 0.0;
                mr_wf_metal a, b;
                unsigned flags, zero_flags;
                MR_CHECK_OK(mr_wf_spec_to_metal(&in, &o, &a, &flags));
                MR_CHECK_OK(mr_wf_spec_to_metal(&zeroed, &o, &b, &zero_flags));
                MR_CHECK(metal_in_range(&a) && memcmp(&a, &b, sizeof a) == 0);
                MR_CHECK_MSG(flags == (zero_flags | MR_WF_NONFINITE_INPUT), "%s slot %d: flags %u",
                             mr_wf_method_name(o.method), slot, flags);
            }
        for (int k = 0; k < 3; k++)
            for (int slot = 0; slot < 5; slot++) {
                mr_wf_metal in = {{0.9, 0.5, 0.2}, 0.7, 0.4};
                double *v = slot < 3 ? &in.albedo[slot] : slot == 3 ? &in.metallic : &in.roughness;
                *v = bad[k];
                mr_wf_spec s;
                unsigned flags;
                MR_CHECK_OK(mr_wf_metal_to_spec(&in, &o, &s, &flags));
                MR_CHECK(spec_in_range(&s) && flags == MR_WF_NONFINITE_INPUT);
                MR_CHECK(s.roughness == (slot == 4 ? 1.0 : 0.4));
            }
        // Everything NaN: a defined, finite texel.
        mr_wf_spec all = {{NAN, NAN, NAN}, {NAN, NAN, NAN}, NAN};
        mr_wf_metal m;
        unsigned flags;
        MR_CHECK_OK(mr_wf_spec_to_metal(&all, &o, &m, &flags));
        MR_CHECK(metal_in_range(&m) && (flags & MR_WF_NONFINITE_INPUT) && m.roughness == 1.0);
    }
    // The batches too, spec -> metal (the analytic methods and the network) and metal -> spec: NaN and both
    // infinities in the roughness map become 1 and are flagged; a finite one passes through.
    float d[12] = {0.3f, 0.2f, 0.1f, 0.3f, 0.2f, 0.1f, 0.3f, 0.2f, 0.1f, 0.3f, 0.2f, 0.1f}, sp[12];
    float rough[4] = {NAN, INFINITY, -INFINITY, 0.25f}, a[12], m[4], r[4];
    uint8_t flags[4];
    for (int i = 0; i < 12; i++) sp[i] = 0.04f;
    mr_wf_spec_maps in = {d, sp, rough};
    mr_wf_metal_maps out = {a, m, r};
    MR_CHECK_OK(mr_wf_spec_to_metal_batch(SPEC_IN(in), 4, NULL, &out, flags));
    for (int i = 0; i < 4; i++) {
        MR_CHECK_MSG(r[i] == (i < 3 ? 1.0f : 0.25f), "texel %d: roughness %g", i, (double)r[i]);
        MR_CHECK(((flags[i] & MR_WF_NONFINITE_INPUT) != 0) == (i < 3));
    }
    mr_mlp *net = NULL;
    MR_CHECK_OK(mr_mlp_create(6, 4, 4, &net));
    if (net != NULL) {
        for (int i = 0; i < 6; i++) net->in_std[i] = 1.0f;
        for (int i = 0; i < 4; i++) net->out_std[i] = 1.0f;
        memset(r, 0, sizeof r);
        MR_CHECK_OK(mr_wf_spec_to_metal_mlp_batch(net, SPEC_IN(in), 4, NULL, &out, flags));
        for (int i = 0; i < 4; i++)
            MR_CHECK(r[i] == (i < 3 ? 1.0f : 0.25f) && ((flags[i] & MR_WF_NONFINITE_INPUT) != 0) == (i < 3));
        mr_mlp_free(net);
    }
    mr_wf_metal_maps metal = {a, m, rough};
    mr_wf_spec_maps spec = {d, sp, r};
    for (int i = 0; i < 4; i++)
        m[i] = 0.5f;
    MR_CHECK_OK(mr_wf_metal_to_spec_batch(METAL_IN(metal), 4, NULL, &spec, flags));
    for (int i = 0; i < 4; i++)
        MR_CHECK(r[i] == (i < 3 ? 1.0f : 0.25f) && ((flags[i] & MR_WF_NONFINITE_INPUT) != 0) == (i < 3));
}

/* ---- the custom-method slot ----------------------------------------------------------------------------------- */

typedef struct custom_probe {
    int calls;
    int mode; /* 0: return the weighted answer; 1: fail; 2: return garbage */
    double seen_f0;
} custom_probe;

static int probe_method(const mr_wf_options *opts, const double diffuse[3], const double specular[3],
                        double albedo[3], double *metallic) {
    custom_probe *p = opts->custom_data;
    p->calls++;
    p->seen_f0 = opts->dielectric_f0;
    if (p->mode == 1) return 3;
    if (p->mode == 2) {
        albedo[0] = NAN;
        albedo[1] = 2.0;
        albedo[2] = 0.5;
        *metallic = -1.0;
        return 0;
    }
    mr_wf_options w = *opts;
    w.method = MR_WF_WEIGHTED;
    mr_wf_spec in = {{diffuse[0], diffuse[1], diffuse[2]}, {specular[0], specular[1], specular[2]}, 0.0};
    mr_wf_metal out;
    if (mr_wf_spec_to_metal(&in, &w, &out, NULL) != MR_OK) return 1;
    memcpy(albedo, out.albedo, sizeof out.albedo);
    *metallic = out.metallic;
    return 0;
}

MR_TEST(the_custom_slot_calls_back_and_sanitises) {
    custom_probe probe = {0, 0, 0.0};
    mr_wf_options o = options(MR_WF_CUSTOM, 0.03);
    o.custom = probe_method;
    o.custom_data = &probe;
    mr_wf_options w = options(MR_WF_WEIGHTED, 0.03);
    double d[3] = {0.3, 0.2, 0.1}, s[3] = {0.2, 0.1, 0.4};
    unsigned fc, fw;
    mr_wf_metal a = to_metal(&o, d, s, &fc), b = to_metal(&w, d, s, &fw);
    MR_CHECK(probe.calls == 1 && probe.seen_f0 == 0.03);
    MR_CHECK(memcmp(&a, &b, sizeof a) == 0 && fc == fw);
    // It receives sanitised inputs.
    double dn[3] = {NAN, 2.0, 0.1};
    to_metal(&o, dn, s, &fc);
    MR_CHECK(fc & MR_WF_NONFINITE_INPUT && fc & MR_WF_CLAMPED_INPUT);
    // A failure zeroes the texel; garbage is sanitised; both are flagged.
    probe.mode = 1;
    a = to_metal(&o, d, s, &fc);
    MR_CHECK(a.metallic == 0.0 && a.albedo[0] == 0.0 && a.albedo[1] == 0.0 && a.albedo[2] == 0.0);
    MR_CHECK(fc & MR_WF_METHOD_FAILED);
    probe.mode = 2;
    a = to_metal(&o, d, s, &fc);
    MR_CHECK(metal_in_range(&a) && a.albedo[0] == 0.0 && a.albedo[1] == 1.0 && a.metallic == 0.0);
    MR_CHECK(fc & MR_WF_METHOD_FAILED);
    // metal -> spec under CUSTOM is Eq. 2 and does not call back.
    int calls = probe.calls;
    mr_wf_spec sc = to_spec(&o, 0.9, 0.5, 0.2, 0.7, NULL), sw = to_spec(&w, 0.9, 0.5, 0.2, 0.7, NULL);
    MR_CHECK(memcmp(&sc, &sw, sizeof sc) == 0 && probe.calls == calls);
}

/* ---- batches -------------------------------------------------------------------------------------------------- */

enum { BATCH_N = 3000 };

typedef struct batch_data {
    float albedo[3 * BATCH_N], metallic[BATCH_N], rough[BATCH_N];
    float diffuse[3 * BATCH_N], specular[3 * BATCH_N];
} batch_data;

static void fill(batch_data *b, uint64_t seed) {
    uint64_t rng = seed;
    for (int i = 0; i < 3 * BATCH_N; i++) {
        b->albedo[i] = texel_value(&rng);
        b->diffuse[i] = texel_value(&rng);
        b->specular[i] = texel_value(&rng);
    }
    for (int i = 0; i < BATCH_N; i++) {
        b->metallic[i] = texel_value(&rng);
        b->rough[i] = texel_value(&rng);
    }
}

MR_TEST(batch_equals_per_texel) {
    static batch_data in, out;
    static uint8_t flags[BATCH_N];
    fill(&in, 11);
    custom_probe probe = {0, 0, 0.0};
    for (int method = 0; method < MR_WF_METHOD_COUNT; method++) {
        mr_wf_options o = options((mr_wf_method)method, 0.04);
        o.custom = probe_method;
        o.custom_data = &probe;
        mr_wf_metal_maps metal_in = {in.albedo, in.metallic, in.rough};
        mr_wf_spec_maps spec_out = {out.diffuse, out.specular, out.rough};
        MR_CHECK_OK(mr_wf_metal_to_spec_batch(METAL_IN(metal_in), BATCH_N, &o, &spec_out, flags));
        int mismatches = 0;
        for (int i = 0; i < BATCH_N; i++) {
            mr_wf_metal t = {{in.albedo[3 * i], in.albedo[3 * i + 1], in.albedo[3 * i + 2]}, in.metallic[i],
                             in.rough[i]};
            mr_wf_spec s;
            unsigned f;
            MR_CHECK_OK(mr_wf_metal_to_spec(&t, &o, &s, &f));
            int same = flags[i] == f && out.rough[i] == (float)s.roughness;
            for (int c = 0; c < 3; c++)
                same = same && out.diffuse[3 * i + c] == (float)s.diffuse[c]
                       && out.specular[3 * i + c] == (float)s.specular[c];
            mismatches += !same;
        }
        MR_CHECK_MSG(mismatches == 0, "%s metal -> spec: %d texels differ", mr_wf_method_name(o.method), mismatches);

        mr_wf_spec_maps spec_in = {in.diffuse, in.specular, in.rough};
        mr_wf_metal_maps metal_out = {out.albedo, out.metallic, out.rough};
        MR_CHECK_OK(mr_wf_spec_to_metal_batch(SPEC_IN(spec_in), BATCH_N, &o, &metal_out, flags));
        mismatches = 0;
        int flagged = 0;
        for (int i = 0; i < BATCH_N; i++) {
            mr_wf_spec t = {{in.diffuse[3 * i], in.diffuse[3 * i + 1], in.diffuse[3 * i + 2]},
                            {in.specular[3 * i], in.specular[3 * i + 1], in.specular[3 * i + 2]},
                            in.rough[i]};
            mr_wf_metal m;
            unsigned f;
            MR_CHECK_OK(mr_wf_spec_to_metal(&t, &o, &m, &f));
            int same = flags[i] == f && out.rough[i] == (float)m.roughness && out.metallic[i] == (float)m.metallic;
            for (int c = 0; c < 3; c++) same = same && out.albedo[3 * i + c] == (float)m.albedo[c];
            mismatches += !same;
            flagged += (flags[i] & (MR_WF_NONFINITE_INPUT | MR_WF_CLAMPED_INPUT)) != 0;
        }
        MR_CHECK_MSG(mismatches == 0, "%s spec -> metal: %d texels differ", mr_wf_method_name(o.method), mismatches);
        MR_CHECK(flagged > 100); // the hard values are there
    }
    // Without roughness maps and without flags; in place (albedo over diffuse, both 3n) gives the same.
    mr_wf_options o = mr_wf_options_default();
    static float diffuse_copy[3 * BATCH_N], metallic2[BATCH_N];
    memcpy(diffuse_copy, in.diffuse, sizeof diffuse_copy);
    mr_wf_spec_maps spec_in = {in.diffuse, in.specular, NULL};
    mr_wf_metal_maps metal_out = {out.albedo, out.metallic, NULL};
    MR_CHECK_OK(mr_wf_spec_to_metal_batch(SPEC_IN(spec_in), BATCH_N, &o, &metal_out, NULL));
    mr_wf_spec_maps in_place_in = {diffuse_copy, in.specular, NULL};
    mr_wf_metal_maps in_place_out = {diffuse_copy, metallic2, NULL};
    MR_CHECK_OK(mr_wf_spec_to_metal_batch(SPEC_IN(in_place_in), BATCH_N, &o, &in_place_out, NULL));
    MR_CHECK(memcmp(diffuse_copy, out.albedo, sizeof diffuse_copy) == 0);
    MR_CHECK(memcmp(metallic2, out.metallic, sizeof metallic2) == 0);
    // n = 0 does nothing, even with no maps.
    mr_wf_spec_maps none = {NULL, NULL, NULL};
    mr_wf_metal_maps none_out = {NULL, NULL, NULL};
    MR_CHECK_OK(mr_wf_spec_to_metal_batch(SPEC_IN(none), 0, &o, &none_out, NULL));
}

MR_TEST(results_are_identical_for_one_and_two_threads) {
    static batch_data in, one, two;
    static uint8_t flags_one[2 * BATCH_N], flags_two[2 * BATCH_N];
    fill(&in, 23);
    for (int method = 0; method < MR_WF_CUSTOM; method++) {
        mr_wf_options o = options((mr_wf_method)method, 0.04);
        for (int pass = 0; pass < 2; pass++) {
            batch_data *out = pass == 0 ? &one : &two;
            uint8_t *flags = pass == 0 ? flags_one : flags_two;
            o.threads = pass + 1; // a count given (the automatic rule keeps small batches on one thread)
            mr_wf_spec_maps spec_in = {in.diffuse, in.specular, in.rough};
            mr_wf_metal_maps metal_out = {out->albedo, out->metallic, out->rough};
            MR_CHECK_OK(mr_wf_spec_to_metal_batch(SPEC_IN(spec_in), BATCH_N, &o, &metal_out, flags));
            mr_wf_metal_maps metal_in = {in.albedo, in.metallic, in.rough};
            mr_wf_spec_maps spec_out = {out->diffuse, out->specular, out->rough};
            MR_CHECK_OK(mr_wf_metal_to_spec_batch(METAL_IN(metal_in), BATCH_N, &o, &spec_out, flags + BATCH_N));
        }
        MR_CHECK(memcmp(&one, &two, sizeof one) == 0);
        MR_CHECK(memcmp(flags_one, flags_two, sizeof flags_one) == 0);
    }
}

/* ---- errors --------------------------------------------------------------------------------------------------- */

/* Expect MR_ERR_INVALID_ARG with `needle` in the message. */
#define CHECK_REJECTED(call, needle)                                                                  \
    do {                                                                                              \
        mr_clear_error();                                                                             \
        mr_status s_ = (call);                                                                        \
        MR_CHECK_MSG(s_ == MR_ERR_INVALID_ARG, "%s -> %s", #call, mr_status_str(s_));                 \
        MR_CHECK_MSG(strstr(mr_last_error(), needle) != NULL, "%s: message '%s' lacks '%s'", #call,   \
                     mr_last_error(), needle);                                                        \
    } while (0)

MR_TEST(bad_arguments_are_rejected_with_a_message) {
    mr_wf_options o = mr_wf_options_default();
    mr_wf_spec spec = {{0.3, 0.2, 0.1}, {0.04, 0.04, 0.04}, 0.5};
    mr_wf_metal metal = {{0.5, 0.5, 0.5}, 0.5, 0.5};
    mr_wf_metal out_m;
    mr_wf_spec out_s;
    memset(&out_m, 0x5a, sizeof out_m);
    memset(&out_s, 0x5a, sizeof out_s);
    unsigned char before_m[sizeof out_m], before_s[sizeof out_s];
    memcpy(before_m, &out_m, sizeof out_m);
    memcpy(before_s, &out_s, sizeof out_s);
    unsigned flags = 12345;

    CHECK_REJECTED(mr_wf_spec_to_metal(NULL, &o, &out_m, &flags), "NULL");
    CHECK_REJECTED(mr_wf_spec_to_metal(&spec, &o, NULL, &flags), "NULL");
    CHECK_REJECTED(mr_wf_metal_to_spec(NULL, &o, &out_s, &flags), "NULL");
    CHECK_REJECTED(mr_wf_metal_to_spec(&metal, &o, NULL, &flags), "NULL");

    static const double bad_f0[] = {1.0, -0.01, 1.5, NAN, INFINITY};
    for (size_t i = 0; i < sizeof bad_f0 / sizeof bad_f0[0]; i++) {
        o = mr_wf_options_default();
        o.dielectric_f0 = bad_f0[i];
        CHECK_REJECTED(mr_wf_spec_to_metal(&spec, &o, &out_m, &flags), "dielectric_f0");
        CHECK_REJECTED(mr_wf_metal_to_spec(&metal, &o, &out_s, &flags), "dielectric_f0");
        CHECK_REJECTED(mr_wf_options_check(&o), "(0, 1)");
    }
    o = mr_wf_options_default();
    o.eps = -1e-9;
    CHECK_REJECTED(mr_wf_spec_to_metal(&spec, &o, &out_m, &flags), "eps");
    o.eps = NAN;
    CHECK_REJECTED(mr_wf_spec_to_metal(&spec, &o, &out_m, &flags), "eps");
    o = mr_wf_options_default();
    o.method = MR_WF_METHOD_COUNT;
    CHECK_REJECTED(mr_wf_spec_to_metal(&spec, &o, &out_m, &flags), "method");
    o.method = MR_WF_CUSTOM;
    CHECK_REJECTED(mr_wf_spec_to_metal(&spec, &o, &out_m, &flags), "callback");
    CHECK_REJECTED(mr_wf_metal_to_spec(&metal, &o, &out_s, &flags), "callback");
    o = options(MR_WF_KHRONOS, MR_WF_F0_PAPER);
    CHECK_REJECTED(mr_wf_spec_to_metal(&spec, &o, &out_m, &flags), "0.04");
    MR_CHECK(memcmp(before_m, &out_m, sizeof out_m) == 0);
    MR_CHECK(memcmp(before_s, &out_s, sizeof out_s) == 0);
    MR_CHECK(flags == 12345);
    // The edges of the valid ranges are fine.
    o = options(MR_WF_WEIGHTED, DBL_MIN);
    o.eps = DBL_MIN;
    MR_CHECK_OK(mr_wf_spec_to_metal(&spec, &o, &out_m, &flags));
    o.dielectric_f0 = 0.999;
    MR_CHECK_OK(mr_wf_spec_to_metal(&spec, &o, &out_m, &flags));
    MR_CHECK(metal_in_range(&out_m));

    // Batches.
    o = mr_wf_options_default();
    float d[6] = {0.1f, 0.2f, 0.3f, 0.4f, 0.5f, 0.6f}, s[6] = {0}, a[6], m[2], r[2] = {0.5f, 0.5f};
    mr_wf_spec_maps sin = {d, s, NULL}, s_no_d = {NULL, s, NULL}, s_rough = {d, s, r};
    mr_wf_metal_maps mout = {a, m, NULL}, m_no_m = {a, NULL, NULL}, m_rough = {a, m, r};
    CHECK_REJECTED(mr_wf_spec_to_metal_batch(NULL, 2, &o, &mout, NULL), "NULL");
    CHECK_REJECTED(mr_wf_spec_to_metal_batch(SPEC_IN(sin), 2, &o, NULL, NULL), "NULL");
    CHECK_REJECTED(mr_wf_spec_to_metal_batch(SPEC_IN(s_no_d), 2, &o, &mout, NULL), "diffuse");
    CHECK_REJECTED(mr_wf_spec_to_metal_batch(SPEC_IN(sin), 2, &o, &m_no_m, NULL), "metallic");
    CHECK_REJECTED(mr_wf_spec_to_metal_batch(SPEC_IN(sin), 2, &o, &m_rough, NULL), "roughness");
    CHECK_REJECTED(mr_wf_spec_to_metal_batch(SPEC_IN(s_rough), 2, &o, &mout, NULL), "roughness");
    CHECK_REJECTED(mr_wf_spec_to_metal_batch(SPEC_IN(sin), SIZE_MAX / 2, &o, &mout, NULL), "texels");
    mr_wf_metal_maps min = {a, m, NULL}, m_no_a = {NULL, m, NULL};
    mr_wf_spec_maps sout = {d, s, NULL}, s_no_s = {d, NULL, NULL};
    CHECK_REJECTED(mr_wf_metal_to_spec_batch(METAL_IN(m_no_a), 2, &o, &sout, NULL), "albedo");
    CHECK_REJECTED(mr_wf_metal_to_spec_batch(METAL_IN(min), 2, &o, &s_no_s, NULL), "specular");
    o.dielectric_f0 = 2.0;
    CHECK_REJECTED(mr_wf_metal_to_spec_batch(METAL_IN(min), 2, &o, &sout, NULL), "dielectric_f0");
    CHECK_REJECTED(mr_wf_spec_to_metal_batch(SPEC_IN(sin), 2, &o, &mout, NULL), "dielectric_f0");
}

/* ---- the spec-gloss diffuse convention (MR_WF_DIFFUSE_SPECGLOSS) --------------------------------------------- */

MR_TEST(specgloss_convention_known_answers_and_names) {
    MR_CHECK(strcmp(mr_wf_diffuse_name(MR_WF_DIFFUSE_PLAIN), "paper") == 0);
    MR_CHECK(strcmp(mr_wf_diffuse_name(MR_WF_DIFFUSE_SPECGLOSS), "gltf") == 0);
    MR_CHECK(mr_wf_diffuse_name(MR_WF_DIFFUSE_COUNT) == NULL);
    for (int d = 0; d < MR_WF_DIFFUSE_COUNT; d++) { // the names round-trip
        mr_wf_diffuse back = MR_WF_DIFFUSE_COUNT;
        MR_CHECK_OK(mr_wf_diffuse_from_name(mr_wf_diffuse_name((mr_wf_diffuse)d), &back));
        MR_CHECK(back == (mr_wf_diffuse)d);
    }
    mr_wf_diffuse untouched = MR_WF_DIFFUSE_SPECGLOSS;
    MR_CHECK(mr_wf_diffuse_from_name("specgloss", &untouched) == MR_ERR_INVALID_ARG);
    MR_CHECK(untouched == MR_WF_DIFFUSE_SPECGLOSS);
    MR_CHECK(strstr(mr_last_error(), "expected gltf") != NULL);
    MR_CHECK(mr_wf_options_default().spec_diffuse == MR_WF_DIFFUSE_PLAIN);
    mr_wf_options o = options(MR_WF_WEIGHTED, 0.04);
    o.spec_diffuse = MR_WF_DIFFUSE_COUNT;
    MR_CHECK(mr_wf_options_check(&o) == MR_ERR_INVALID_ARG);
    MR_CHECK_MSG(strstr(mr_last_error(), "spec_diffuse"), "%s", mr_last_error());

    o.spec_diffuse = MR_WF_DIFFUSE_SPECGLOSS;
    // A grey dielectric: the lobe A (1 - m) = 0.5 is d (1 - 0.04), so d = 0.5 / 0.96.
    unsigned flags = 99;
    mr_wf_spec s = to_spec(&o, 0.5, 0.5, 0.5, 0.0, &flags);
    MR_CHECK(flags == 0);
    for (int c = 0; c < 3; c++) {
        MR_CHECK_NEAR(s.diffuse[c], 0.5 / 0.96, 1e-15);
        MR_CHECK_NEAR(s.specular[c], 0.04, 1e-15);
    }
    mr_wf_metal m = to_metal(&o, s.diffuse, s.specular, &flags);
    MR_CHECK(flags == 0);
    MR_CHECK_NEAR(m.metallic, 0.0, 1e-12);
    for (int c = 0; c < 3; c++) MR_CHECK_NEAR(m.albedo[c], 0.5, 1e-12);
    // A coloured partial metal: d = A (1 - m) / (1 - max s), s = lerp(0.04, A, m).
    s = to_spec(&o, 0.9, 0.5, 0.2, 0.4, &flags);
    double max_s = 0.04 * 0.6 + 0.4 * 0.9;
    MR_CHECK(flags == 0);
    MR_CHECK_NEAR(s.specular[0], max_s, 1e-15);
    MR_CHECK_NEAR(s.diffuse[1], 0.5 * 0.6 / (1.0 - max_s), 1e-15);
    // A white dielectric needs a spec-gloss diffuse of 1/0.96: clamped to 1 and flagged (plain is exact).
    s = to_spec(&o, 1.0, 1.0, 1.0, 0.0, &flags);
    MR_CHECK(flags == MR_WF_OFF_MANIFOLD);
    MR_CHECK(s.diffuse[0] == 1.0 && spec_in_range(&s));
    mr_wf_options plain = options(MR_WF_WEIGHTED, 0.04);
    s = to_spec(&plain, 1.0, 1.0, 1.0, 0.0, &flags);
    MR_CHECK(flags == 0 && s.diffuse[0] == 1.0);
    // A pure white metal: max s = 1 and no diffuse lobe: d = 0, clean (no division by 1 - max s = 0).
    s = to_spec(&o, 1.0, 1.0, 1.0, 1.0, &flags);
    MR_CHECK(flags == 0 && s.diffuse[0] == 0.0 && s.specular[0] == 1.0);
    // Spec -> metal with max s = 1 and a diffuse: the lobe is d * 0 = 0, a white metal.
    double d1[3] = {0.7, 0.7, 0.7}, s1[3] = {1.0, 1.0, 1.0};
    m = to_metal(&o, d1, s1, &flags);
    MR_CHECK(metal_in_range(&m));
    MR_CHECK_NEAR(m.metallic, 1.0, 1e-12);
    // KHRONOS ignores the option (it renormalises its own way).
    mr_wf_options k = options(MR_WF_KHRONOS, 0.04), k_sg = k;
    k_sg.spec_diffuse = MR_WF_DIFFUSE_SPECGLOSS;
    double d2[3] = {0.3, 0.4, 0.5}, s2[3] = {0.2, 0.2, 0.3};
    mr_wf_metal a = to_metal(&k, d2, s2, NULL), b = to_metal(&k_sg, d2, s2, NULL);
    MR_CHECK(memcmp(&a, &b, sizeof a) == 0);
}

MR_TEST(specgloss_round_trip_is_exact_where_representable) {
    uint64_t rng = 42;
    int checked = 0;
    static const mr_wf_method methods[2] = {MR_WF_MEAN, MR_WF_WEIGHTED};
    for (int k = 0; k < 2; k++) {
        const mr_wf_method method = methods[k];
        mr_wf_options o = options(method, 0.04);
        o.spec_diffuse = MR_WF_DIFFUSE_SPECGLOSS;
        for (int i = 0; i < 2000; i++) {
            double g = uniform(&rng), m = uniform(&rng) < 0.3 ? (uniform(&rng) < 0.5 ? 0.0 : 1.0) : uniform(&rng);
            // A grey-ish albedo above F0d in every channel, so that no channel is ambiguous (docs/workflow.md).
            double albedo[3] = {0.05 + 0.95 * g, 0.05 + 0.95 * uniform(&rng), 0.05 + 0.95 * uniform(&rng)};
            unsigned flags;
            mr_wf_spec s = to_spec(&o, albedo[0], albedo[1], albedo[2], m, &flags);
            if (flags != 0) continue; // the spec-gloss diffuse would exceed 1
            mr_wf_metal back = to_metal(&o, s.diffuse, s.specular, &flags);
            MR_CHECK_MSG(flags == 0, "flags %u for A (%g, %g, %g) m %g", flags, albedo[0], albedo[1], albedo[2], m);
            if (method == MR_WF_MEAN && m > 0.0 && m < 1.0) continue; // MEAN weighs ill-conditioned channels
            MR_CHECK_NEAR(back.metallic, m, 1e-9);
            for (int c = 0; c < 3; c++) MR_CHECK_NEAR(back.albedo[c], albedo[c], 1e-9);
            checked++;
        }
    }
    MR_CHECK_MSG(checked > 2000, "only %d texels checked", checked);
}

/* f_r of a model at (wi, wo), summed over its parts, per channel. */
static void eval_model(const char *name, const double *values, const double wi[3], const double wo[3],
                       double out[3]) {
    const mr_brdf_model *model = mr_brdf_find(name);
    MR_CHECK(model != NULL);
    if (model == NULL) return;
    mr_brdf_state state;
    model->prepare(model, values, state.bytes);
    double d[3], s[3];
    model->eval(state.bytes, wi, wo, d, s);
    for (int c = 0; c < 3; c++) out[c] = d[c] + s[c];
}

/* The converted texel renders like the source through the glTF models (gltf-specgloss and gltf, brdf/): exactly
 * at metallic 0 and 1, where glTF's normative mix and spec-gloss's single lobe agree; the plain reading misses
 * the dielectric's diffuse by its factor 1 - 0.04. */
MR_TEST(specgloss_convention_matches_the_gltf_brdfs) {
    mr_wf_options sg = options(MR_WF_WEIGHTED, 0.04), plain = sg;
    sg.spec_diffuse = MR_WF_DIFFUSE_SPECGLOSS;
    const double roughness = 0.5;
    const double wi[3] = {0.3, -0.2, sqrt(1.0 - 0.13)}, wo[3] = {-0.5, 0.1, sqrt(1.0 - 0.26)};
    const double albedos[3][3] = {{0.8, 0.3, 0.1}, {0.5, 0.5, 0.5}, {0.95, 0.64, 0.54}};
    double worst_sg = 0.0, worst_plain = 0.0;
    for (int a = 0; a < 3; a++)
        for (int metal = 0; metal <= 1; metal++) {
            const double *A = albedos[a];
            double mr_values[10] = {A[0], A[1], A[2], metal, roughness, 1.0, 1.0, 1.0, 1.0, 1.5};
            double reference[3];
            eval_model("gltf", mr_values, wi, wo, reference);
            for (int pass = 0; pass < 2; pass++) {
                mr_wf_spec s = to_spec(pass ? &plain : &sg, A[0], A[1], A[2], metal, NULL);
                double sg_values[7] = {s.diffuse[0], s.diffuse[1], s.diffuse[2], s.specular[0], s.specular[1],
                                       s.specular[2], 1.0 - roughness};
                double f[3];
                eval_model("gltf-specgloss", sg_values, wi, wo, f);
                for (int c = 0; c < 3; c++) {
                    double rel = fabs(f[c] - reference[c]) / reference[c];
                    if (pass)
                        worst_plain = fmax(worst_plain, rel);
                    else
                        worst_sg = fmax(worst_sg, rel);
                }
            }
        }
    MR_CHECK_MSG(worst_sg < 1e-12, "spec-gloss reading: relative difference %g", worst_sg);
    MR_CHECK_MSG(worst_plain > 1e-3, "the plain reading should miss: %g", worst_plain);
}

/* The network sees the diffuse lobe: SPECGLOSS on (d, s) equals PLAIN on (d (1 - max s), s). */
MR_TEST(mlp_batch_reads_the_specgloss_diffuse_lobe) {
    mr_mlp *net = NULL;
    MR_CHECK_OK(mr_mlp_create(6, 8, 4, &net));
    if (net == NULL) return;
    uint64_t rng = 7;
    for (size_t i = 0; i < net->data_count; i++) net->data[i] = (float)(uniform(&rng) - 0.5);
    for (int i = 0; i < 6; i++) net->in_std[i] = 1.0f;
    for (int i = 0; i < 4; i++) net->out_std[i] = 1.0f;
    enum { N = 64 };
    float d[3 * N], dim[3 * N], s[3 * N], a1[3 * N], a2[3 * N], m1[N], m2[N];
    for (int i = 0; i < N; i++) {
        float max_s = 0.0f;
        for (int c = 0; c < 3; c++) {
            d[3 * i + c] = (float)uniform(&rng);
            s[3 * i + c] = (float)uniform(&rng);
            max_s = fmaxf(max_s, s[3 * i + c]);
        }
        for (int c = 0; c < 3; c++) dim[3 * i + c] = (float)((double)d[3 * i + c] * (1.0 - (double)max_s));
    }
    mr_wf_options sg = mr_wf_options_default(), plain = sg;
    sg.spec_diffuse = MR_WF_DIFFUSE_SPECGLOSS;
    mr_wf_spec_maps in_sg = {d, s, NULL}, in_plain = {dim, s, NULL};
    mr_wf_metal_maps out1 = {a1, m1, NULL}, out2 = {a2, m2, NULL};
    MR_CHECK_OK(mr_wf_spec_to_metal_mlp_batch(net, SPEC_IN(in_sg), N, &sg, &out1, NULL));
    MR_CHECK_OK(mr_wf_spec_to_metal_mlp_batch(net, SPEC_IN(in_plain), N, &plain, &out2, NULL));
    MR_CHECK(memcmp(a1, a2, sizeof a1) == 0 && memcmp(m1, m2, sizeof m1) == 0);
    mr_wf_metal_maps out3 = {a2, m2, NULL};
    MR_CHECK_OK(mr_wf_spec_to_metal_mlp_batch(net, SPEC_IN(in_sg), N, &plain, &out3, NULL));
    MR_CHECK(memcmp(a1, a2, sizeof a1) != 0); // and the option does change the answer
    mr_mlp_free(net);
}

/* The network batch converts each distinct value once and copies the answer (workflow.c): over several blocks,
 * parts that repeat a few values (with -0, NaN, out-of-range and dimmed spec-gloss texels among them) and parts of
 * distinct values (where it stops looking values up), for 1-3 threads and in place, it must give exactly the
 * bits and flags of converting every texel alone. */
MR_TEST(mlp_batch_of_repeated_values_equals_texel_by_texel) {
    enum { N = 150000, PALETTE = 40 };
    static float d[3 * N], s[3 * N], rough[N], a[3 * N], m[N], r[N], ref_a[3 * N], ref_m[N], ref_r[N];
    static float d2[3 * N], rough2[N];
    static uint8_t flags[N], ref_flags[N];
    float palette[PALETTE][6];
    uint64_t rng = 11;
    for (int k = 0; k < PALETTE; k++)
        for (int c = 0; c < 6; c++) palette[k][c] = (float)uniform(&rng);
    palette[1][0] = -0.0f;
    palette[2][0] = 0.0f; // the same value as palette[1] but other bits: its own row, the same answer
    palette[3][4] = NAN;
    palette[4][1] = 1.5f;
    palette[5][3] = -0.25f;
    palette[6][3] = palette[6][4] = palette[6][5] = 0.04f;
    for (size_t i = 0; i < N; i++) {
        // 65536..100000 (the third chunk of 32768 texels, whatever the thread count): distinct values, where the
        // lookups stop; elsewhere the palette
        int distinct = i >= 65536 && i < 100000;
        int k = (int)(uniform(&rng) * PALETTE);
        for (int c = 0; c < 3; c++) {
            d[3 * i + c] = distinct ? (float)uniform(&rng) : palette[k][c];
            s[3 * i + c] = distinct ? (float)uniform(&rng) : palette[k][3 + c];
        }
        rough[i] = (float)(uniform(&rng) * 1.2 - 0.1);
    }
    for (int form = 0; form < 2; form++) {
        mr_mlp *net = NULL;
        MR_CHECK_OK(mr_mlp_create(6, 16, 4, &net));
        if (net == NULL) return;
        for (size_t i = 0; i < net->data_count; i++) net->data[i] = (float)(uniform(&rng) - 0.5);
        for (int i = 0; i < 6; i++) net->in_std[i] = 1.0f;
        for (int i = 0; i < 4; i++) net->out_std[i] = 0.1f;
        if (form == 1) snprintf(net->kind, sizeof net->kind, "%s", MR_WF_MLP_RESIDUAL_KIND);
        mr_wf_options o = mr_wf_options_default();
        o.spec_diffuse = MR_WF_DIFFUSE_SPECGLOSS;
        for (size_t i = 0; i < N; i++) {
            mr_wf_spec_maps in = {d + 3 * i, s + 3 * i, rough + i};
            mr_wf_metal_maps out = {ref_a + 3 * i, ref_m + i, ref_r + i};
            MR_CHECK_OK(mr_wf_spec_to_metal_mlp_batch(net, SPEC_IN(in), 1, &o, &out, ref_flags + i));
        }
        int saved = omp_get_max_threads();
        for (int threads = 1; threads <= 3; threads++) {
            omp_set_num_threads(threads);
            mr_wf_spec_maps in = {d, s, rough};
            mr_wf_metal_maps out = {a, m, r};
            MR_CHECK_OK(mr_wf_spec_to_metal_mlp_batch(net, SPEC_IN(in), N, &o, &out, flags));
            MR_CHECK_MSG(memcmp(a, ref_a, sizeof a) == 0 && memcmp(m, ref_m, sizeof m) == 0 &&
                             memcmp(r, ref_r, sizeof r) == 0 && memcmp(flags, ref_flags, sizeof flags) == 0,
                         "form %d, %d threads: the batch differs from texel by texel", form, threads);
            // in place: the albedo over the diffuse, the metallic over the roughness it reads
            memcpy(d2, d, sizeof d2);
            memcpy(rough2, rough, sizeof rough2);
            mr_wf_spec_maps in2 = {d2, s, rough2};
            mr_wf_metal_maps out2 = {d2, rough2, r};
            MR_CHECK_OK(mr_wf_spec_to_metal_mlp_batch(net, SPEC_IN(in2), N, &o, &out2, flags));
            MR_CHECK_MSG(memcmp(d2, ref_a, sizeof d2) == 0 && memcmp(rough2, ref_m, sizeof rough2) == 0 &&
                             memcmp(r, ref_r, sizeof r) == 0,
                         "form %d, %d threads: in place differs from texel by texel", form, threads);
        }
        omp_set_num_threads(saved);
        mr_mlp_free(net);
    }
}

/* The network batch's anchors eight at a time (AVX-512) and four at a time (AVX2) give the bits of one at a time,
 * on random rows and on the hard ones: black, white, -0, channels at and around F0d and below it (ambiguous: those
 * lanes go scalar inside the vector pass), grey and saturated, points on the Eq. 2 manifold, and a count that leaves
 * a remainder. */
MR_TEST(vector_anchors_equal_scalar_anchors) {
    enum { N = 4099 };
    static double planes[6 * N];
    static mr_wf_residual_anchor vec[N], one[N];
    static const double hard[] = {0.0, -0.0, 1.0, 0.04, 0.039, 0.041, 0.02, 1e-300, 0.5, 0.999999};
    const int hard_count = (int)(sizeof hard / sizeof hard[0]);
    uint64_t rng = 99;
    for (size_t r = 0; r < N; r++) {
        int kind = (int)(uniform(&rng) * 4);
        for (int c = 0; c < 6; c++) {
            double v = uniform(&rng);
            if (kind == 1) v = hard[(int)(uniform(&rng) * hard_count)];
            if (kind == 2) v *= 0.05; // dark: often ambiguous
            planes[(size_t)c * N + r] = v;
        }
        if (kind == 3) { // on the manifold: Eq. 2 of a random (albedo, metallic)
            double m = uniform(&rng);
            for (int c = 0; c < 3; c++) {
                double albedo = uniform(&rng);
                planes[(size_t)c * N + r] = albedo * (1.0 - m);
                planes[(size_t)(3 + c) * N + r] = MR_WF_F0_GLTF * (1.0 - m) + m * albedo;
            }
        }
    }
    MR_CHECK(mr_wf_residual_anchors(planes, N, N, 0, one) == 0);
    int best = 0;
    for (int level = 1; level <= 2; level++) {
        memset(vec, 0, sizeof vec);
        int used = mr_wf_residual_anchors(planes, N, N, level, vec);
        best = used > best ? used : best;
        MR_CHECK_MSG(memcmp(vec, one, sizeof vec) == 0, "vector level %d (used %d) differs from the scalar anchors",
                     level, used);
    }
    // The anchors are mr_wf_residual_anchor_of's.
    for (size_t r = 0; r < N; r += 97) {
        double lobe[3], spec[3];
        for (int c = 0; c < 3; c++) {
            lobe[c] = planes[(size_t)c * N + r];
            spec[c] = planes[(size_t)(3 + c) * N + r];
        }
        mr_wf_residual_anchor a;
        mr_wf_residual_anchor_of(lobe, spec, &a);
        MR_CHECK(memcmp(&a, &one[r], sizeof a) == 0);
    }
    __builtin_cpu_init();
    if (getenv("MR_WF_SCALAR_ANCHORS") == NULL)
        MR_CHECK(best == (__builtin_cpu_supports("avx512f") ? 2 : __builtin_cpu_supports("avx2") ? 1 : 0));
}

/* ---- quantised inputs: tolerances (workflow.h, "Tolerances") --------------------------------------------------- */

/* What an 8-bit sRGB texture stores for v, decoded as mr_img_read decodes it: the code the writer rounds to. */
static float store8(float v) {
    double code = floor(fmin(fmax(mr_linear_to_srgb(v), 0.0f), 1.0f) * 255.0 + 0.5);
    return mr_srgb_to_linear((float)(code / 255.0));
}

static mr_wf_quantisation srgb8(void) {
    mr_wf_quantisation q = {8, 1, {1.0, 1.0, 1.0}};
    return q;
}

/* A clean metal-rough texture set, written as an 8-bit spec-gloss one (diffuse and specular quantised as PNG
 * stores them) and converted back: with each input's quantisation WEIGHTED flags nothing, at the default eps most
 * texels. The set: every albedo with channels in {0, 0.01, 0.03, 0.04, 0.05, 0.2, 0.5, 0.8, 0.95} at metallic 0,
 * 0.3, 0.7 and 1, less the texels spec-gloss cannot store (metal -> spec flags them: a white dielectric's diffuse
 * above 1), and less the near-black partial metals (every channel <= 0.05), whose metallic a code of diffuse
 * moves by several hundredths: some of those are flagged (docs/workflow.md, "Tolerances"). MEAN and KHRONOS flag
 * nothing on the dielectrics and metals; on partial metals they have their known misses (MEAN averages
 * ill-conditioned dark channels in, KHRONOS is lossy for coloured partial metals), and KHRONOS reads a metal whose
 * perceived brightness is below 0.04 as a black dielectric. */
MR_TEST(clean_8bit_exports_flag_nothing) {
    static const float levels[] = {0.0f, 0.01f, 0.03f, 0.04f, 0.05f, 0.2f, 0.5f, 0.8f, 0.95f};
    static const float metals[] = {0.0f, 0.3f, 0.7f, 1.0f};
    enum { L = 9, N = L * L * L * 4 };
    static float albedo[3 * N], metallic[N], diffuse[3 * N], specular[3 * N], back_albedo[3 * N], back_metal[N];
    static uint8_t flags[N];
    int n = 0;
    for (int m = 0; m < 4; m++)
        for (int r = 0; r < L; r++)
            for (int g = 0; g < L; g++)
                for (int b = 0; b < L; b++) {
                    float a[3] = {levels[r], levels[g], levels[b]};
                    int dark = a[0] <= 0.05f && a[1] <= 0.05f && a[2] <= 0.05f;
                    if (dark && metals[m] > 0.0f && metals[m] < 1.0f) continue;
                    memcpy(&albedo[3 * n], a, sizeof a);
                    metallic[n++] = metals[m];
                }
    for (int method = MR_WF_WEIGHTED; method <= MR_WF_KHRONOS; method++) {
        mr_wf_options o = options((mr_wf_method)method, 0.04);
        o.spec_diffuse = MR_WF_DIFFUSE_SPECGLOSS; // as the spec2metal commands read glTF maps
        mr_wf_metal_maps metal_in = {albedo, metallic, NULL};
        mr_wf_spec_maps spec = {diffuse, specular, NULL};
        MR_CHECK_OK(mr_wf_metal_to_spec_batch(METAL_IN(metal_in), (size_t)n, &o, &spec, flags));
        int kept = 0;
        for (int i = 0; i < n; i++) { // keep what spec-gloss can store, quantised
            int partial = metallic[i] > 0.0f && metallic[i] < 1.0f;
            const float *a = &albedo[3 * i];
            int dark_metal = metallic[i] == 1.0f && a[0] <= 0.05f && a[1] <= 0.05f && a[2] <= 0.05f;
            if (flags[i] != 0 || (partial && method != MR_WF_WEIGHTED) || (dark_metal && method == MR_WF_KHRONOS))
                continue;
            for (int c = 0; c < 3; c++) {
                diffuse[3 * kept + c] = store8(diffuse[3 * i + c]);
                specular[3 * kept + c] = store8(specular[3 * i + c]);
            }
            kept++;
        }
        MR_CHECK(kept > (method == MR_WF_WEIGHTED ? 2000 : 1000));
        mr_wf_metal_maps metal_out = {back_albedo, back_metal, NULL};
        int off[2] = {0, 0};
        for (int quantised = 0; quantised < 2; quantised++) {
            if (quantised)
                o.diffuse_quantisation = o.specular_quantisation = srgb8();
            MR_CHECK_OK(mr_wf_spec_to_metal_batch(SPEC_IN(spec), (size_t)kept, &o, &metal_out, flags));
            for (int i = 0; i < kept; i++)
                off[quantised] += (flags[i] & MR_WF_OFF_MANIFOLD) != 0;
        }
        MR_CHECK_MSG(off[1] == 0, "%s: %d of %d texels flagged with 8-bit tolerances", mr_wf_method_name(o.method),
                     off[1], kept);
        MR_CHECK_MSG(off[0] > kept / 3, "%s: only %d of %d texels flagged at eps 1e-6", mr_wf_method_name(o.method),
                     off[0], kept);
    }
}

MR_TEST(quantisation_known_answers) {
    mr_wf_options exact = options(MR_WF_WEIGHTED, 0.04), q8 = exact;
    q8.diffuse_quantisation = q8.specular_quantisation = srgb8();
    unsigned flags;
    // A dark grey dielectric (albedo 0.035) as 8-bit stores it: specular 0.04 -> code 56 = 0.0395. Read exactly,
    // the discriminant is negative, the readings are m = 1 - ((s + d) / 2) / F0d = 0.068 and 1 - 2 d / (s + d) =
    // 0.061, neither exact, and the closest fit is between them, flagged; with its
    // 8-bit tolerance (0.00068 at code 56) the specular is within reach of F0d: a dielectric, m = 0, A = d, clean.
    double s56 = mr_srgb_to_linear(56.0f / 255.0f), d = 0.035;
    MR_CHECK(fabs(s56 - 0.04) > 4e-4 && fabs(s56 - 0.04) < 5e-4);
    double dd[3] = {d, d, d}, ss[3] = {s56, s56, s56};
    mr_wf_metal m = to_metal(&exact, dd, ss, &flags);
    MR_CHECK_MSG(m.metallic > 0.06 && m.metallic < 0.07, "metallic %g", m.metallic);
    MR_CHECK(flags == MR_WF_OFF_MANIFOLD);
    m = to_metal(&q8, dd, ss, &flags);
    MR_CHECK(m.metallic == 0.0 && flags == 0);
    for (int c = 0; c < 3; c++) MR_CHECK_NEAR(m.albedo[c], d, 1e-12);
    // Genuinely off the manifold stays flagged: a coloured specular (0.9, 0.2, 0.2) over a diffuse of 0.5 misses by
    // far more than half a code.
    double d2[3] = {store8(0.5f), store8(0.5f), store8(0.5f)};
    double s2[3] = {store8(0.9f), store8(0.2f), store8(0.2f)};
    for (int method = MR_WF_WEIGHTED; method <= MR_WF_KHRONOS; method++) {
        q8.method = (mr_wf_method)method;
        to_metal(&q8, d2, s2, &flags);
        MR_CHECK_MSG(flags == MR_WF_OFF_MANIFOLD, "%s: flags %u", mr_wf_method_name(q8.method), flags);
    }
    // The tolerance is each value's own and scales with the factor: a grey dielectric whose specular is 0.0015
    // under F0d, with linear 8-bit codes (half a code 0.00196 on each input): both values may miss by the sum
    // 0.0039 (not flagged); with factors 0.25 (0.00098) it is flagged; on the specular alone at scale 1 and the
    // diffuse exact (0.00196 + 1e-6), still not.
    mr_wf_options lin = options(MR_WF_WEIGHTED, 0.04);
    lin.diffuse_quantisation.bits = lin.specular_quantisation.bits = 8;
    double d3[3] = {0.5, 0.5, 0.5}, s3[3] = {0.0385, 0.0385, 0.0385};
    to_metal(&lin, d3, s3, &flags);
    MR_CHECK(flags == 0);
    for (int c = 0; c < 3; c++) lin.diffuse_quantisation.scale[c] = lin.specular_quantisation.scale[c] = 0.25;
    to_metal(&lin, d3, s3, &flags);
    MR_CHECK(flags == MR_WF_OFF_MANIFOLD);
    lin.diffuse_quantisation.bits = 0;
    for (int c = 0; c < 3; c++) lin.specular_quantisation.scale[c] = 1.0;
    to_metal(&lin, d3, s3, &flags);
    MR_CHECK(flags == 0);
    lin.specular_quantisation.bits = 16; // 16-bit codes are 257 times finer: flagged
    to_metal(&lin, d3, s3, &flags);
    MR_CHECK(flags == MR_WF_OFF_MANIFOLD);
    // Bad quantisations are rejected with a message, outputs untouched.
    mr_wf_options bad = q8;
    bad.specular_quantisation.bits = 12;
    mr_wf_metal untouched = {{7, 7, 7}, 7, 7};
    mr_wf_spec in = {{0.5, 0.5, 0.5}, {0.04, 0.04, 0.04}, 0.5};
    MR_CHECK(mr_wf_spec_to_metal(&in, &bad, &untouched, NULL) == MR_ERR_INVALID_ARG);
    MR_CHECK_MSG(strstr(mr_last_error(), "specular_quantisation.bits 12") != NULL, "%s", mr_last_error());
    bad = q8;
    bad.diffuse_quantisation.scale[1] = NAN;
    MR_CHECK(mr_wf_spec_to_metal(&in, &bad, &untouched, NULL) == MR_ERR_INVALID_ARG);
    bad.diffuse_quantisation.scale[1] = -0.5;
    MR_CHECK(mr_wf_spec_to_metal(&in, &bad, &untouched, NULL) == MR_ERR_INVALID_ARG);
    MR_CHECK(untouched.metallic == 7.0);
    // The defaults: exact inputs, scale 1.
    mr_wf_options def = mr_wf_options_default();
    MR_CHECK(def.diffuse_quantisation.bits == 0 && def.specular_quantisation.bits == 0);
    MR_CHECK(def.diffuse_quantisation.scale[0] == 1.0 && def.specular_quantisation.scale[2] == 1.0);
}

/* The batch looks tolerances up in tables; the per-texel API computes them. Same answers, bit for bit, for 8 and
 * 16-bit sRGB and linear codes with factors, on values at and around every code's interval edges. */
MR_TEST(quantised_batch_equals_per_texel) {
    enum { N = 4096 };
    static float d[3 * N], sp[3 * N], a[3 * N], m[N];
    static uint8_t flags[N];
    uint64_t rng = 5;
    for (int bits = 8; bits <= 16; bits += 8)
        for (int srgb = 0; srgb < 2; srgb++) {
            double max = bits == 8 ? 255.0 : 65535.0;
            for (int i = 0; i < 3 * N; i++) {
                // half the texels on the manifold (a grey metal-rough texel through Eq. 2), the other half
                // anywhere; half the diffuse values on an interval edge (q + 1/2) or a float step beside it
                double q = floor(uniform(&rng) * max);
                float edge = mr_srgb_to_linear((float)((q + 0.5) / max));
                int k = (int)(uniform(&rng) * 4.0);
                if (i / 3 % 2 == 0 && i % 3 == 0) {
                    double albedo = uniform(&rng), metal = uniform(&rng) < 0.5 ? 0.0 : uniform(&rng);
                    for (int c = 0; c < 3; c++) {
                        d[i + c] = (float)(albedo * (1.0 - metal));
                        sp[i + c] = (float)(0.04 * (1.0 - metal) + metal * albedo);
                    }
                }
                if (i / 3 % 2 == 1) {
                    d[i] = (float)uniform(&rng);
                    sp[i] = k == 2 ? edge : (float)(uniform(&rng) * 0.3);
                }
                if (k < 2) d[i] = k == 0 ? edge : nextafterf(edge, 0.0f);
            }
            mr_wf_options o = options(MR_WF_WEIGHTED, 0.04);
            mr_wf_quantisation q = {bits, srgb, {1.0, 0.8, 0.5}};
            o.diffuse_quantisation = o.specular_quantisation = q;
            mr_wf_spec_maps in = {d, sp, NULL};
            mr_wf_metal_maps out = {a, m, NULL};
            MR_CHECK_OK(mr_wf_spec_to_metal_batch(SPEC_IN(in), N, &o, &out, flags));
            int mismatches = 0, flagged = 0;
            for (int i = 0; i < N; i++) {
                double di[3] = {d[3 * i], d[3 * i + 1], d[3 * i + 2]};
                double si[3] = {sp[3 * i], sp[3 * i + 1], sp[3 * i + 2]};
                unsigned f;
                mr_wf_metal t = to_metal(&o, di, si, &f);
                int same = f == flags[i] && (float)t.metallic == m[i];
                for (int c = 0; c < 3; c++) same = same && (float)t.albedo[c] == a[3 * i + c];
                mismatches += !same;
                flagged += f != 0;
            }
            MR_CHECK_MSG(mismatches == 0, "%d bits, srgb %d: %d texels differ", bits, srgb, mismatches);
            MR_CHECK(flagged > 0 && flagged < N); // both kinds are there
        }
}

/* A zeroed mr_wf_options is the defaults (F0d 0.04, WEIGHTED, eps 1e-6): the same bits on a batch with hard texels. */
MR_TEST(zeroed_options_are_the_defaults) {
    enum { N = 64 };
    float d[3 * N], s[3 * N], a1[3 * N], a2[3 * N], m1[N], m2[N];
    uint8_t f1[N], f2[N];
    for (int i = 0; i < 3 * N; i++) {
        d[i] = (float)((i * 37) % 101) / 100.0f;
        s[i] = i % 7 == 0 ? 0.04f : (float)((i * 53) % 97) / 96.0f;
    }
    mr_wf_options zeroed;
    memset(&zeroed, 0, sizeof zeroed);
    const mr_wf_options defaults = mr_wf_options_default();
    MR_CHECK(mr_wf_options_check(&zeroed) == MR_OK);
    MR_CHECK(mr_wf_spec_to_metal_batch(&(mr_wf_spec_input){d, s, NULL}, N, &zeroed, &(mr_wf_metal_maps){a1, m1, NULL},
                                       f1) == MR_OK);
    MR_CHECK(mr_wf_spec_to_metal_batch(&(mr_wf_spec_input){d, s, NULL}, N, &defaults,
                                       &(mr_wf_metal_maps){a2, m2, NULL}, f2) == MR_OK);
    MR_CHECK(memcmp(a1, a2, sizeof a1) == 0 && memcmp(m1, m2, sizeof m1) == 0 && memcmp(f1, f2, sizeof f1) == 0);
    MR_CHECK(strcmp(mr_wf_method_name(zeroed.method), "weighted") == 0);
}

MR_TEST_MAIN(MR_TEST_ENTRY(method_names_round_trip), MR_TEST_ENTRY(vector_anchors_equal_scalar_anchors),
             MR_TEST_ENTRY(default_options_are_the_documented_ones),
             MR_TEST_ENTRY(equation_2_known_answers),
             MR_TEST_ENTRY(round_trip_is_exact_for_mean_and_weighted),
             MR_TEST_ENTRY(float_batch_round_trip_is_exact_within_float_rounding),
             MR_TEST_ENTRY(equation_3_matches_the_closed_form_with_the_papers_f0),
             MR_TEST_ENTRY(mean_and_weighted_follow_their_formulas_off_the_manifold),
             MR_TEST_ENTRY(khronos_matches_its_javascript),
             MR_TEST_ENTRY(khronos_round_trip_within_its_known_tolerance),
             MR_TEST_ENTRY(black_is_a_black_metal),
             MR_TEST_ENTRY(albedo_at_or_below_the_dielectric_f0),
             MR_TEST_ENTRY(negative_discriminant_and_specular_above_albedo),
             MR_TEST_ENTRY(inputs_outside_0_1_are_clamped_and_flagged),
             MR_TEST_ENTRY(non_finite_inputs_are_flagged_and_read_as_zero),
             MR_TEST_ENTRY(the_custom_slot_calls_back_and_sanitises),
             MR_TEST_ENTRY(batch_equals_per_texel),
             MR_TEST_ENTRY(results_are_identical_for_one_and_two_threads),
             MR_TEST_ENTRY(bad_arguments_are_rejected_with_a_message),
             MR_TEST_ENTRY(specgloss_convention_known_answers_and_names),
             MR_TEST_ENTRY(specgloss_round_trip_is_exact_where_representable),
             MR_TEST_ENTRY(specgloss_convention_matches_the_gltf_brdfs),
             MR_TEST_ENTRY(mlp_batch_reads_the_specgloss_diffuse_lobe),
             MR_TEST_ENTRY(mlp_batch_of_repeated_values_equals_texel_by_texel),
             MR_TEST_ENTRY(clean_8bit_exports_flag_nothing),
             MR_TEST_ENTRY(quantisation_known_answers),
             MR_TEST_ENTRY(quantised_batch_equals_per_texel),
             MR_TEST_ENTRY(zeroed_options_are_the_defaults))
