/*
 * test_brdf.c — the BRDF models (src/brdf): generic property tests over every registered model, known answers
 * computed independently of src/brdf, and the registry's parameter parsing.
 *
 * Every model returned by mr_brdf_models() is enrolled automatically in: table sanity, non-negativity and
 * finiteness, reciprocity, below-horizon zeros, robustness at parameter bounds / grazing angles / non-finite
 * inputs, the white-furnace energy bound, the analytic gradient against central differences, and the truthfulness
 * of parameter roles (LINEAR, AFFINE) and lobes. Random streams use splitmix64 with fixed seeds, so every run
 * checks the same points.
 */
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "brdf/brdf.h"
#include "brdf/brdf_internal.h" /* the GGX albedo table lookups of known_openpbr and known_standard_surface */
#include "brdf/dual.h"          /* the prepared derivative state of the layered models */
#include "harness.h"
#include "io/image_io.h"

#define PI 3.14159265358979323846

/* ---------------------------------------------------------------------------------------------------------- */
/* helpers */

static uint64_t splitmix64(uint64_t *state) {
    uint64_t z = (*state += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

/* Uniform in [0, 1). */
static double rnd(uint64_t *state) { return (double)(splitmix64(state) >> 11) * 0x1.0p-53; }

static void dir_from_angles(double theta, double phi, double w[3]) {
    w[0] = sin(theta) * cos(phi);
    w[1] = sin(theta) * sin(phi);
    w[2] = cos(theta);
}

/* A direction with z uniform in [zmin, 1) and uniform azimuth. */
static void random_dir(uint64_t *rng, double zmin, double w[3]) {
    double z = zmin + (1.0 - zmin) * rnd(rng), phi = 2.0 * PI * rnd(rng);
    double r = sqrt(fmax(1.0 - z * z, 0.0));
    w[0] = r * cos(phi);
    w[1] = r * sin(phi);
    w[2] = z;
}

static const mr_brdf_param *param_named(const mr_brdf_model *m, const char *name, int *offset) {
    int i = mr_brdf_param_index(m, name);
    if (i < 0) return NULL;
    if (offset) *offset = mr_brdf_param_offset(m, i);
    return &m->params[i];
}

/* Sets every channel of parameter `name`. */
static void set_param(const mr_brdf_model *m, double *values, const char *name, double v) {
    int offset;
    const mr_brdf_param *p = param_named(m, name, &offset);
    MR_CHECK_MSG(p != NULL, "model %s has no parameter %s", m->name, name);
    if (p)
        for (int c = 0; c < p->channels; c++) values[offset + c] = v;
}

static void set_rgb(const mr_brdf_model *m, double *values, const char *name, double r, double g, double b) {
    int offset;
    const mr_brdf_param *p = param_named(m, name, &offset);
    MR_CHECK_MSG(p != NULL && p->channels == 3, "model %s has no RGB parameter %s", m->name, name);
    if (p && p->channels == 3) {
        values[offset] = r;
        values[offset + 1] = g;
        values[offset + 2] = b;
    }
}

static const mr_brdf_model *model_named(const char *name) {
    const mr_brdf_model *m = mr_brdf_find(name);
    MR_CHECK_MSG(m != NULL, "model '%s' is not registered: %s", name, mr_last_error());
    return m;
}

/* prepare + eval into d[3], s[3]. */
static void eval_parts(const mr_brdf_model *m, const double *values, const double wi[3], const double wo[3],
                       double d[3], double s[3]) {
    mr_brdf_state state;
    m->prepare(m, values, state.bytes);
    m->eval(state.bytes, wi, wo, d, s);
}

/* A random in-bound value for parameter p: switches take an integer value, log-scale parameters are drawn
 * log-uniformly, the rest uniformly, each within [min + margin, max - margin] of its (log-)range. */
static double random_value(const mr_brdf_param *p, uint64_t *rng, double margin) {
    double u = margin + (1.0 - 2.0 * margin) * rnd(rng);
    if (p->role == MR_PARAM_SWITCH) return floor(p->min_value + u * (p->max_value - p->min_value + 1.0 - 1e-9));
    if (p->flags & MR_PARAM_LOG_SCALE) return p->min_value * pow(p->max_value / p->min_value, u);
    return p->min_value + u * (p->max_value - p->min_value);
}

static void random_values(const mr_brdf_model *m, uint64_t *rng, double margin, double *values) {
    int slot = 0;
    for (int i = 0; i < m->param_count; i++)
        for (int c = 0; c < m->params[i].channels; c++) values[slot++] = random_value(&m->params[i], rng, margin);
}

/* Every SWITCH parameter at its minimum (for Mitsuba's trim: 0 = off, the case where roles are exact). */
static void switches_off(const mr_brdf_model *m, double *values) {
    for (int i = 0; i < m->param_count; i++)
        if (m->params[i].role == MR_PARAM_SWITCH) set_param(m, values, m->params[i].name, m->params[i].min_value);
}

static int finite_nonneg3(const double v[3]) {
    for (int c = 0; c < 3; c++)
        if (!(isfinite(v[c]) && v[c] >= 0.0)) return 0;
    return 1;
}

static int close_rel(double a, double b, double rel) {
    return fabs(a - b) <= rel * fmax(fabs(a), fabs(b)) + 1e-300;
}

/* ---------------------------------------------------------------------------------------------------------- */
/* registry and tables */

MR_TEST(registry_tables_are_consistent) {
    const mr_brdf_model *const *models = mr_brdf_models();
    int count = mr_brdf_model_count();
    MR_CHECK(count >= 21);
    MR_CHECK(models[count] == NULL);
    for (int k = 0; k < count; k++) {
        const mr_brdf_model *m = models[k];
        MR_CHECK(m->name && m->name[0] && m->summary && m->summary[0] && m->source && m->source[0]);
        MR_CHECK(m->prepare && m->eval && m->params && m->param_count > 0);
        MR_CHECK_MSG(mr_brdf_find(m->name) == m, "%s", m->name);
        for (int j = 0; j < k; j++) MR_CHECK_MSG(strcmp(models[j]->name, m->name) != 0, "duplicate %s", m->name);
        MR_CHECK_MSG((m->flags & ~(unsigned)(MR_BRDF_NOT_ENERGY_CONSERVING | MR_BRDF_INDEPENDENT_LOBES |
                                             MR_BRDF_NON_RECIPROCAL)) == 0,
                     "%s", m->name);
        int n = mr_brdf_value_count(m);
        MR_CHECK_MSG(n >= 1 && n <= MR_BRDF_MAX_VALUES, "%s: %d values", m->name, n);
        for (int i = 0; i < m->param_count; i++) {
            const mr_brdf_param *p = &m->params[i];
            MR_CHECK_MSG(p->name && p->name[0] && p->meaning && p->meaning[0], "%s param %d", m->name, i);
            MR_CHECK_MSG(p->channels == 1 || p->channels == 3, "%s.%s", m->name, p->name);
            MR_CHECK_MSG(p->min_value <= p->default_value && p->default_value <= p->max_value, "%s.%s", m->name,
                         p->name);
            MR_CHECK_MSG(p->role >= MR_PARAM_LINEAR && p->role < MR_PARAM_ROLE_COUNT, "%s.%s", m->name, p->name);
            MR_CHECK_MSG(p->lobe == MR_LOBE_DIFFUSE || p->lobe == MR_LOBE_SPECULAR || p->lobe == MR_LOBE_BOTH,
                         "%s.%s", m->name, p->name);
            if (p->flags & MR_PARAM_LOG_SCALE) MR_CHECK_MSG(p->min_value > 0.0, "%s.%s", m->name, p->name);
            if (p->role == MR_PARAM_SWITCH)
                MR_CHECK_MSG(p->channels == 1 && p->default_value == floor(p->default_value) &&
                                 p->min_value == floor(p->min_value) && p->max_value == floor(p->max_value),
                             "%s.%s", m->name, p->name);
            if (p->default_rgb) {
                MR_CHECK_MSG(p->channels == 3 && p->default_rgb[1] == p->default_value, "%s.%s", m->name, p->name);
                for (int c = 0; c < 3; c++)
                    MR_CHECK_MSG(p->min_value <= p->default_rgb[c] && p->default_rgb[c] <= p->max_value, "%s.%s",
                                 m->name, p->name);
            }
            MR_CHECK_MSG(mr_brdf_param_index(m, p->name) == i, "%s.%s duplicate", m->name, p->name);
        }
        MR_CHECK(mr_brdf_param_offset(m, -1) == -1 && mr_brdf_param_offset(m, m->param_count) == -1);
        MR_CHECK(mr_brdf_param_index(m, "no-such-parameter") == -1);
    }
}

MR_TEST(map_encodings_follow_one_rule) {
    /* Colour parameters (reflectances and albedos given as RGB colours) are flagged MR_PARAM_SRGB_MAP in every
     * model, whatever their range (Ward's and Phong's specular go to 10); nothing else is. */
    static const char *const colours[] = {"diffuse", "specular", "albedo", "f0", "base_color", "specular_color",
                                          "diffuse_color", "coat_color", "specular_tint", "coat_tint"};
    for (const mr_brdf_model *const *mp = mr_brdf_models(); *mp; mp++) {
        const mr_brdf_model *m = *mp;
        for (int i = 0; i < m->param_count; i++) {
            const mr_brdf_param *p = &m->params[i];
            MR_CHECK_MSG((p->flags & ~(unsigned)(MR_PARAM_LOG_SCALE | MR_PARAM_FIT_FIXED | MR_PARAM_SRGB_MAP)) == 0,
                         "%s.%s", m->name, p->name);
            int colour = 0;
            for (size_t k = 0; k < sizeof colours / sizeof colours[0]; k++)
                colour |= p->channels == 3 && strcmp(p->name, colours[k]) == 0;
            MR_CHECK_MSG(((p->flags & MR_PARAM_SRGB_MAP) != 0) == colour, "%s.%s: %s", m->name, p->name,
                         colour ? "a colour without MR_PARAM_SRGB_MAP" : "MR_PARAM_SRGB_MAP on a non-colour");
            MR_CHECK_MSG(mr_brdf_param_map_encoding(p, MR_MAP_AS_PARAMETER) == (colour ? MR_IMG_COLOR : MR_IMG_DATA),
                         "%s.%s", m->name, p->name);
        }
    }
    /* glTF fixes its textures' encodings (baseColor, specularColor, diffuse and specularGlossiness RGB sRGB;
     * metallicRoughness, specular and glossiness linear): the gltf and gltf-specgloss models agree. */
    static const struct {
        const char *model, *param;
        mr_img_encoding encoding;
    } gltf[] = {
        {"gltf", "base_color", MR_IMG_COLOR},          {"gltf", "metallic", MR_IMG_DATA},
        {"gltf", "roughness", MR_IMG_DATA},            {"gltf", "specular", MR_IMG_DATA},
        {"gltf", "specular_color", MR_IMG_COLOR},      {"gltf-specgloss", "diffuse", MR_IMG_COLOR},
        {"gltf-specgloss", "specular", MR_IMG_COLOR},  {"gltf-specgloss", "glossiness", MR_IMG_DATA},
    };
    for (size_t k = 0; k < sizeof gltf / sizeof gltf[0]; k++) {
        const mr_brdf_model *m = mr_brdf_find(gltf[k].model);
        const int i = m ? mr_brdf_param_index(m, gltf[k].param) : -1;
        MR_CHECK_MSG(i >= 0 && mr_brdf_param_map_encoding(&m->params[i], MR_MAP_AS_PARAMETER) == gltf[k].encoding,
                     "%s.%s", gltf[k].model, gltf[k].param);
    }
}

MR_TEST(find_unknown_lists_valid_names) {
    mr_clear_error();
    MR_CHECK(mr_brdf_find("ggxx") == NULL);
    const char *msg = mr_last_error();
    MR_CHECK(strstr(msg, "ggxx") != NULL);
    for (const mr_brdf_model *const *m = mr_brdf_models(); *m; m++)
        MR_CHECK_MSG(strstr(msg, (*m)->name) != NULL, "'%s' missing from: %s", (*m)->name, msg);
    MR_CHECK(mr_brdf_find(NULL) == NULL);
}

MR_TEST(default_values_use_per_channel_defaults) {
    const mr_brdf_model *m = model_named("ggx-conductor");
    if (!m) return;
    double v[MR_BRDF_MAX_VALUES] = {0};
    mr_brdf_default_values(m, v);
    int eta = 0, k = 0;
    param_named(m, "eta", &eta);
    param_named(m, "k", &k);
    MR_CHECK(v[eta] == 0.200438 && v[eta + 1] == 0.924033 && v[eta + 2] == 1.10221);
    MR_CHECK(v[k] == 3.91295 && v[k + 1] == 2.45285 && v[k + 2] == 2.14219);
    // One parameter's default by channel, as mr_brdf_default_values writes it (coloured or not).
    const int eta_index = mr_brdf_param_index(m, "eta"), rough_index = mr_brdf_param_index(m, "alpha");
    for (int c = 0; c < 3; c++) MR_CHECK(mr_brdf_param_default(&m->params[eta_index], c) == v[eta + c]);
    if (rough_index >= 0)
        MR_CHECK(mr_brdf_param_default(&m->params[rough_index], 0) == m->params[rough_index].default_value);
    // The names `matremap models` prints for roles and lobes.
    MR_CHECK(strcmp(mr_param_role_name(MR_PARAM_LINEAR), "linear") == 0 &&
             strcmp(mr_param_role_name(MR_PARAM_AFFINE), "affine") == 0 &&
             strcmp(mr_param_role_name(MR_PARAM_NONLINEAR), "nonlinear") == 0 &&
             strcmp(mr_param_role_name(MR_PARAM_SWITCH), "switch") == 0);
    MR_CHECK(mr_param_role_name(MR_PARAM_ROLE_COUNT) == NULL);
    MR_CHECK(strcmp(mr_param_lobe_name(MR_LOBE_DIFFUSE), "diffuse") == 0 &&
             strcmp(mr_param_lobe_name(MR_LOBE_SPECULAR), "specular") == 0 &&
             strcmp(mr_param_lobe_name(MR_LOBE_BOTH), "both") == 0);
}

MR_TEST(parse_assignment_accepts_and_rejects) {
    const mr_brdf_model *m = model_named("ward");
    if (!m) return;
    double v[MR_BRDF_MAX_VALUES] = {0}, before[MR_BRDF_MAX_VALUES];
    mr_brdf_default_values(m, v);
    int d = 0, a = 0, t = 0;
    param_named(m, "diffuse", &d);
    param_named(m, "alpha", &a);
    param_named(m, "trim", &t);

    MR_CHECK_OK(mr_brdf_parse_assignment(m, "alpha=0.25", v));
    MR_CHECK(v[a] == 0.25);
    MR_CHECK_OK(mr_brdf_parse_assignment(m, "diffuse=0.1,0.2,0.3", v));
    MR_CHECK(v[d] == 0.1 && v[d + 1] == 0.2 && v[d + 2] == 0.3);
    MR_CHECK_OK(mr_brdf_parse_assignment(m, "diffuse=0.4", v));
    MR_CHECK(v[d] == 0.4 && v[d + 1] == 0.4 && v[d + 2] == 0.4);
    MR_CHECK_OK(mr_brdf_parse_assignment(m, "trim=0", v));
    MR_CHECK(v[t] == 0.0);
    MR_CHECK_OK(mr_brdf_parse_assignment(m, "alpha=1e-4", v)); /* the inclusive minimum */

    static const char *const bad[] = {
        "foo=1",               /* unknown parameter */
        "alpha=5",             /* above max */
        "alpha=0",             /* below min */
        "alpha=-1",            /* below min */
        "alpha=nan",           /* not a number */
        "alpha=inf",           /* out of range */
        "alpha=abc",           /* not a number */
        "alpha=",              /* empty */
        "=0.1",                /* no name */
        "alpha",               /* no '=' */
        "alpha=0.1x",          /* trailing junk */
        "diffuse=0.1,0.2",     /* wrong channel count */
        "diffuse=0.1,0.2,0.3,0.4", /* too many */
        "diffuse=0.1,,0.3",    /* empty channel */
        "alpha=0.1,0.2,0.3",   /* three values for a scalar */
        "trim=0.5",            /* switch must be an integer */
        "trim=2",              /* switch out of range */
        "diffuse=1e999",       /* overflow */
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        memcpy(before, v, sizeof v);
        mr_clear_error();
        mr_status s = mr_brdf_parse_assignment(m, bad[i], v);
        MR_CHECK_MSG(s == MR_ERR_INVALID_ARG, "'%s' accepted", bad[i]);
        MR_CHECK_MSG(mr_last_error()[0] != '\0', "'%s': no message", bad[i]);
        MR_CHECK_MSG(memcmp(before, v, sizeof v) == 0, "'%s' changed the values", bad[i]);
    }
    mr_brdf_parse_assignment(m, "foo=1", v);
    MR_CHECK_MSG(strstr(mr_last_error(), "valid: diffuse, specular, alpha, trim") != NULL, "%s", mr_last_error());
    mr_brdf_parse_assignment(m, "alpha=5", v);
    MR_CHECK_MSG(strstr(mr_last_error(), "outside") != NULL, "%s", mr_last_error());
}

/* ---------------------------------------------------------------------------------------------------------- */
/* generic properties */

MR_TEST(random_values_are_finite_and_nonnegative) {
    uint64_t rng = 1;
    for (const mr_brdf_model *const *mp = mr_brdf_models(); *mp; mp++) {
        const mr_brdf_model *m = *mp;
        int bad = 0, mismatched = 0;
        for (int k = 0; k < 200; k++) {
            double v[MR_BRDF_MAX_VALUES] = {0};
            random_values(m, &rng, 0.0, v);
            mr_brdf_state state;
            m->prepare(m, v, state.bytes);
            for (int j = 0; j < 10; j++) {
                double wi[3], wo[3], d[3], s[3], d_only[3], s_only[3];
                random_dir(&rng, 0.0, wi);
                random_dir(&rng, 0.0, wo);
                m->eval(state.bytes, wi, wo, d, s);
                if (!finite_nonneg3(d) || !finite_nonneg3(s)) bad++;
                /* either output may be NULL, and asking for one part does not change it */
                m->eval(state.bytes, wi, wo, d_only, NULL);
                m->eval(state.bytes, wi, wo, NULL, s_only);
                m->eval(state.bytes, wi, wo, NULL, NULL);
                if (memcmp(d, d_only, sizeof d) != 0 || memcmp(s, s_only, sizeof s) != 0) mismatched++;
            }
        }
        MR_CHECK_MSG(bad == 0, "%s: %d non-finite or negative values", m->name, bad);
        MR_CHECK_MSG(mismatched == 0, "%s: %d evals differ with a NULL output", m->name, mismatched);
    }
}

MR_TEST(reciprocity) {
    uint64_t rng = 2;
    for (const mr_brdf_model *const *mp = mr_brdf_models(); *mp; mp++) {
        const mr_brdf_model *m = *mp;
        if (m->flags & MR_BRDF_NON_RECIPROCAL) {
            printf("      %-20s [NON_RECIPROCAL: not checked]\n", m->name);
            continue;
        }
        int bad = 0;
        double worst = 0.0;
        for (int k = 0; k < 100; k++) {
            double v[MR_BRDF_MAX_VALUES] = {0};
            random_values(m, &rng, 0.0, v);
            for (int j = 0; j < 10; j++) {
                double wi[3], wo[3], d1[3], s1[3], d2[3], s2[3];
                random_dir(&rng, 0.0, wi);
                random_dir(&rng, 0.0, wo);
                eval_parts(m, v, wi, wo, d1, s1);
                eval_parts(m, v, wo, wi, d2, s2);
                for (int c = 0; c < 3; c++) {
                    if (!close_rel(d1[c], d2[c], 1e-9) || !close_rel(s1[c], s2[c], 1e-9)) bad++;
                    double scale = fmax(fmax(d1[c], s1[c]), 1e-300);
                    worst = fmax(worst, fmax(fabs(d1[c] - d2[c]), fabs(s1[c] - s2[c])) / scale);
                }
            }
        }
        MR_CHECK_MSG(bad == 0, "%s: %d non-reciprocal values (worst relative %.3g)", m->name, bad, worst);
    }
}

MR_TEST(below_horizon_is_exactly_zero) {
    uint64_t rng = 3;
    const double below[][3] = {{0.6, 0.0, -0.8}, {0.0, 0.0, -1.0}, {1.0, 0.0, 0.0}, {1.0, 0.0, -0.0}};
    for (const mr_brdf_model *const *mp = mr_brdf_models(); *mp; mp++) {
        const mr_brdf_model *m = *mp;
        double v[MR_BRDF_MAX_VALUES] = {0};
        random_values(m, &rng, 0.0, v);
        int n = mr_brdf_value_count(m);
        for (size_t b = 0; b < sizeof below / sizeof below[0]; b++) {
            double up[3], d[3], s[3];
            random_dir(&rng, 0.0, up);
            for (int swap = 0; swap < 2; swap++) {
                const double *wi = swap ? up : below[b], *wo = swap ? below[b] : up;
                eval_parts(m, v, wi, wo, d, s);
                for (int c = 0; c < 3; c++)
                    MR_CHECK_MSG(d[c] == 0.0 && s[c] == 0.0, "%s: %g %g below the horizon", m->name, d[c], s[c]);
                if (m->eval_grad) {
                    double gd[MR_BRDF_MAX_VALUES * 3], gs[MR_BRDF_MAX_VALUES * 3];
                    m->eval_grad(m, v, wi, wo, gd, gs);
                    for (int j = 0; j < n * 3; j++)
                        MR_CHECK_MSG(gd[j] == 0.0 && gs[j] == 0.0, "%s: gradient below the horizon", m->name);
                }
            }
        }
    }
}

/* Direction pairs that stress grazing angles: cos = 1e-7 for wi, wo or both, in every azimuth relation, plus a
 * denormal cosine. */
static int stress_pairs(double wi[][3], double wo[][3]) {
    const double zs[] = {1e-7, 1e-310, 0.3, 1.0};
    const double phis[] = {0.0, 0.5 * PI, PI};
    int n = 0;
    for (size_t a = 0; a < 4; a++)
        for (size_t b = 0; b < 4; b++)
            for (size_t p = 0; p < 3; p++) {
                double za = zs[a], zb = zs[b];
                double ra = sqrt(1.0 - za * za), rb = sqrt(1.0 - zb * zb);
                wi[n][0] = ra, wi[n][1] = 0.0, wi[n][2] = za;
                wo[n][0] = rb * cos(phis[p]), wo[n][1] = rb * sin(phis[p]), wo[n][2] = zb;
                n++;
            }
    return n;
}

/* Evaluates at the stress pairs and random pairs; counts non-finite or negative outputs (values and, for in-bound
 * vectors, gradients). */
static int count_bad(const mr_brdf_model *m, const double *v, int check_grad, uint64_t *rng) {
    double wi[64][3], wo[64][3];
    int n = stress_pairs(wi, wo), bad = 0;
    for (int k = 0; k < 8; k++, n++) {
        random_dir(rng, 0.0, wi[n]);
        random_dir(rng, 0.0, wo[n]);
    }
    int count = mr_brdf_value_count(m);
    for (int k = 0; k < n; k++) {
        double d[3], s[3];
        eval_parts(m, v, wi[k], wo[k], d, s);
        if (!finite_nonneg3(d) || !finite_nonneg3(s)) bad++;
        if (check_grad && m->eval_grad) {
            double gd[MR_BRDF_MAX_VALUES * 3], gs[MR_BRDF_MAX_VALUES * 3];
            m->eval_grad(m, v, wi[k], wo[k], gd, gs);
            for (int j = 0; j < count * 3; j++)
                if (!isfinite(gd[j]) || !isfinite(gs[j])) bad++;
        }
    }
    return bad;
}

MR_TEST(robust_at_bounds_grazing_and_nonfinite_inputs) {
    uint64_t rng = 4;
    for (const mr_brdf_model *const *mp = mr_brdf_models(); *mp; mp++) {
        const mr_brdf_model *m = *mp;
        double def[MR_BRDF_MAX_VALUES] = {0}, v[MR_BRDF_MAX_VALUES];
        mr_brdf_default_values(m, def);
        MR_CHECK_MSG(count_bad(m, def, 1, &rng) == 0, "%s: defaults", m->name);
        /* each parameter at its min and at its max, the others at default */
        for (int i = 0; i < m->param_count; i++)
            for (int end = 0; end < 2; end++) {
                memcpy(v, def, sizeof v);
                set_param(m, v, m->params[i].name, end ? m->params[i].max_value : m->params[i].min_value);
                MR_CHECK_MSG(count_bad(m, v, 1, &rng) == 0, "%s: %s at %s", m->name, m->params[i].name,
                             end ? "max" : "min");
            }
        /* every parameter at its min, then every one at its max (minimum roughness with extreme reflectances) */
        for (int end = 0; end < 2; end++) {
            for (int i = 0; i < m->param_count; i++)
                set_param(m, v, m->params[i].name, end ? m->params[i].max_value : m->params[i].min_value);
            MR_CHECK_MSG(count_bad(m, v, 1, &rng) == 0, "%s: all at %s", m->name, end ? "max" : "min");
        }
        /* roughness-like (log-scale) parameters at their min, reflectances at max */
        memcpy(v, def, sizeof v);
        for (int i = 0; i < m->param_count; i++) {
            const mr_brdf_param *p = &m->params[i];
            if (p->flags & MR_PARAM_LOG_SCALE) set_param(m, v, p->name, p->min_value);
            else if (p->role == MR_PARAM_LINEAR || p->role == MR_PARAM_AFFINE) set_param(m, v, p->name, p->max_value);
        }
        MR_CHECK_MSG(count_bad(m, v, 1, &rng) == 0, "%s: minimum roughness", m->name);
        /* non-finite inputs are clamped by prepare: NaN -> min, +Inf -> max, -Inf -> min */
        const double specials[] = {NAN, INFINITY, -INFINITY, DBL_MAX, -DBL_MAX};
        int slots = mr_brdf_value_count(m);
        for (int j = 0; j < slots; j++)
            for (size_t k = 0; k < sizeof specials / sizeof specials[0]; k++) {
                memcpy(v, def, sizeof v);
                v[j] = specials[k];
                MR_CHECK_MSG(count_bad(m, v, 0, &rng) == 0, "%s: slot %d = %g", m->name, j, specials[k]);
            }
        /* NaN behaves exactly like the minimum */
        for (int i = 0; i < m->param_count; i++) {
            double vn[MR_BRDF_MAX_VALUES] = {0}, vm[MR_BRDF_MAX_VALUES], wi[3], wo[3], d1[3], s1[3], d2[3], s2[3];
            memcpy(vn, def, sizeof vn);
            memcpy(vm, def, sizeof vm);
            set_param(m, vn, m->params[i].name, NAN);
            set_param(m, vm, m->params[i].name, m->params[i].min_value);
            random_dir(&rng, 0.05, wi);
            random_dir(&rng, 0.05, wo);
            eval_parts(m, vn, wi, wo, d1, s1);
            eval_parts(m, vm, wi, wo, d2, s2);
            MR_CHECK_MSG(memcmp(d1, d2, sizeof d1) == 0 && memcmp(s1, s2, sizeof s1) == 0, "%s: %s = NaN", m->name,
                         m->params[i].name);
        }
    }
}

/* ---------------------------------------------------------------------------------------------------------- */
/* white furnace */

/* Directional albedo a(wi) = integral of f_r cos(theta_o) d omega_o per channel and part, integrated over the
 * half vector: d omega_o = 4 (wi.h) d omega_h. Every specular lobe here (Ward, microfacet, Phong's mirror lobe) is
 * centred on h = n, so a grid that is logarithmic in tan(theta_h) resolves lobes of any width from alpha = 1e-4 to
 * 1 with the same few hundred rings; diffuse lobes are smooth in h too. The models are isotropic and wi lies in the
 * xz plane, so the azimuth integral covers [0, pi] and doubles. Midpoint rule in both variables; the Lambert model
 * checks the accuracy (error below 1e-3). */
#define FURNACE_RINGS 320
#define FURNACE_SECTORS 40
#define FURNACE_LOG_TAN_MIN (-14.0) /* tan(theta_h) = 8e-7: far inside the narrowest lobe (alpha = 1e-4) */
#define FURNACE_LOG_TAN_MAX 6.0     /* tan(theta_h) = 400: beyond any h that reflects wi (<= 85 deg) upwards */

static void furnace(const mr_brdf_model *m, const double *values, double theta_i, double diffuse[3],
                    double specular[3]) {
    mr_brdf_state state;
    m->prepare(m, values, state.bytes);
    double wi[3];
    dir_from_angles(theta_i, 0.0, wi);
    double ds = (FURNACE_LOG_TAN_MAX - FURNACE_LOG_TAN_MIN) / FURNACE_RINGS, dphi = PI / FURNACE_SECTORS;
    double sum_d[3] = {0, 0, 0}, sum_s[3] = {0, 0, 0};
    for (int i = 0; i < FURNACE_RINGS; i++) {
        double t = exp(FURNACE_LOG_TAN_MIN + (i + 0.5) * ds);
        double cos_h = 1.0 / sqrt(1.0 + t * t), sin_h = t * cos_h;
        double jac = t * t * cos_h * cos_h * cos_h; /* sin(theta) d theta / ds = t^2/(1+t^2)^(3/2) */
        for (int j = 0; j < FURNACE_SECTORS; j++) {
            double phi = (j + 0.5) * dphi;
            double h[3] = {sin_h * cos(phi), sin_h * sin(phi), cos_h};
            double dot = wi[0] * h[0] + wi[1] * h[1] + wi[2] * h[2];
            if (dot <= 0.0) continue;
            double wo[3] = {2.0 * dot * h[0] - wi[0], 2.0 * dot * h[1] - wi[1], 2.0 * dot * h[2] - wi[2]};
            if (wo[2] <= 0.0) continue;
            double len = sqrt(wo[0] * wo[0] + wo[1] * wo[1] + wo[2] * wo[2]);
            for (int c = 0; c < 3; c++) wo[c] /= len;
            double d[3], s[3];
            m->eval(state.bytes, wi, wo, d, s);
            double w = wo[2] * 4.0 * dot * jac;
            for (int c = 0; c < 3; c++) {
                sum_d[c] += d[c] * w;
                sum_s[c] += s[c] * w;
            }
        }
    }
    for (int c = 0; c < 3; c++) {
        diffuse[c] = 2.0 * sum_d[c] * ds * dphi;
        specular[c] = 2.0 * sum_s[c] * ds * dphi;
    }
}

MR_TEST(white_furnace_quadrature_is_accurate) {
    const mr_brdf_model *m = model_named("lambert");
    if (!m) return;
    double v[MR_BRDF_MAX_VALUES] = {1.0, 0.5, 0.25};
    const double angles[] = {0.0, 40.0, 65.0, 80.0, 85.0};
    for (size_t k = 0; k < sizeof angles / sizeof angles[0]; k++) {
        double d[3], s[3];
        furnace(m, v, angles[k] * PI / 180.0, d, s);
        MR_CHECK_NEAR(d[0], 1.0, 1e-3);
        MR_CHECK_NEAR(d[1], 0.5, 5e-4);
        MR_CHECK_NEAR(s[0], 0.0, 0.0);
    }
    /* a narrow lobe: the Phong lobe at normal incidence integrates to exactly rho_s */
    m = model_named("phong");
    if (!m) return;
    mr_brdf_default_values(m, v);
    set_param(m, v, "diffuse", 0.0);
    set_param(m, v, "specular", 1.0);
    set_param(m, v, "trim", 0.0);
    const double exponents[] = {1.0, 30.0, 10000.0};
    for (size_t k = 0; k < 3; k++) {
        double d[3], s[3];
        set_param(m, v, "exponent", exponents[k]);
        furnace(m, v, 0.0, d, s);
        MR_CHECK_NEAR(s[1], 1.0, 2e-3);
    }
}

/* Reflectance-like parameters (LINEAR/AFFINE) of `lobe_on` at max, those only of the other lobe at min, BOTH-lobe
 * ones at max; switches at default. */
enum { CONFIG_ALL = 0, CONFIG_DIFFUSE, CONFIG_SPECULAR, CONFIG_COUNT };

static void energy_config(const mr_brdf_model *m, int config, double *v) {
    for (int i = 0; i < m->param_count; i++) {
        const mr_brdf_param *p = &m->params[i];
        if (p->role != MR_PARAM_LINEAR && p->role != MR_PARAM_AFFINE) continue;
        int on = config == CONFIG_ALL || p->lobe == MR_LOBE_BOTH ||
                 (config == CONFIG_DIFFUSE && p->lobe == MR_LOBE_DIFFUSE) ||
                 (config == CONFIG_SPECULAR && p->lobe == MR_LOBE_SPECULAR);
        set_param(m, v, p->name, on ? p->max_value : p->min_value);
    }
}

/* The parameter settings the energy test visits: all NONLINEAR parameters at default (setting 0), then each one at
 * its min and at its max (1 .. 2K), then every corner of their box (all at min or max, 2^K settings). A model with
 * more than ENERGY_MAX_CORNER_BITS nonlinear parameters (openpbr: 13) visits 2^ENERGY_MAX_CORNER_BITS corners
 * spread over the box by an odd multiplier (a bijection modulo 2^K), not all of them: the full box would take
 * minutes. */
#define ENERGY_MAX_CORNER_BITS 8

static int energy_settings(const mr_brdf_model *m, int nonlinear[], int *k_out) {
    int k = 0;
    for (int i = 0; i < m->param_count; i++)
        if (m->params[i].role == MR_PARAM_NONLINEAR) nonlinear[k++] = i;
    *k_out = k;
    return 1 + 2 * k + (1 << (k < ENERGY_MAX_CORNER_BITS ? k : ENERGY_MAX_CORNER_BITS));
}

static void energy_setting(const mr_brdf_model *m, const int nonlinear[], int k, int setting, double *v) {
    if (setting == 0) return;
    if (setting <= 2 * k) {
        const mr_brdf_param *p = &m->params[nonlinear[(setting - 1) / 2]];
        set_param(m, v, p->name, (setting - 1) % 2 ? p->max_value : p->min_value);
        return;
    }
    int corner = setting - 1 - 2 * k;
    if (k > ENERGY_MAX_CORNER_BITS) corner = (int)(((unsigned)corner * 2654435761u) & ((1u << k) - 1u));
    for (int b = 0; b < k; b++) {
        const mr_brdf_param *p = &m->params[nonlinear[b]];
        set_param(m, v, p->name, (corner >> b) & 1 ? p->max_value : p->min_value);
    }
}

MR_TEST(white_furnace_energy_bound) {
    /* 88 degrees finds the normalisations that blow up towards grazing (ward-duer exceeds 1 from about 85) */
    const double angles[] = {0.0, 40.0, 65.0, 80.0, 88.0};
    const double tol = 1.01;
    for (const mr_brdf_model *const *mp = mr_brdf_models(); *mp; mp++) {
        const mr_brdf_model *m = *mp;
        int skip = (m->flags & MR_BRDF_NOT_ENERGY_CONSERVING) != 0;
        int per_lobe = (m->flags & MR_BRDF_INDEPENDENT_LOBES) != 0;
        int nonlinear[MR_BRDF_MAX_VALUES], k;
        int settings = energy_settings(m, nonlinear, &k);
        double max_total = 0.0, max_d = 0.0, max_s = 0.0, at_angle = 0.0;
        int at_setting = 0, at_config = 0, failures = 0;
        for (int setting = 0; setting < settings; setting++)
            for (int config = 0; config < CONFIG_COUNT; config++) {
                double v[MR_BRDF_MAX_VALUES] = {0};
                mr_brdf_default_values(m, v);
                energy_setting(m, nonlinear, k, setting, v);
                energy_config(m, config, v);
                for (size_t a = 0; a < sizeof angles / sizeof angles[0]; a++) {
                    double d[3], s[3];
                    furnace(m, v, angles[a] * PI / 180.0, d, s);
                    for (int c = 0; c < 3; c++) {
                        max_d = fmax(max_d, d[c]);
                        max_s = fmax(max_s, s[c]);
                        if (d[c] + s[c] > max_total) {
                            max_total = d[c] + s[c];
                            at_angle = angles[a];
                            at_setting = setting;
                            at_config = config;
                        }
                        int over = per_lobe ? (d[c] > tol || s[c] > tol) : d[c] + s[c] > tol;
                        if (!skip && over && failures++ < 3)
                            fprintf(stderr, "    %s: albedo %.4f (diffuse %.4f, specular %.4f) at %g deg, setting %d, "
                                    "config %d\n", m->name, d[c] + s[c], d[c], s[c], angles[a], setting, config);
                    }
                }
            }
        MR_CHECK_MSG(failures == 0, "%s: %d albedos above %g", m->name, failures, tol);
        printf("      %-20s max albedo %.4f at %2.0f deg (setting %d, config %d); max diffuse part %.4f, specular part "
               "%.4f%s\n", m->name, max_total, at_angle, at_setting, at_config, max_d, max_s,
               skip       ? "  [NOT_ENERGY_CONSERVING: not checked]"
               : per_lobe ? "  [INDEPENDENT_LOBES: checked per lobe]"
                          : "");
    }
}

/* ---------------------------------------------------------------------------------------------------------- */
/* gradients */

/* f at v with slot j moved to x: the 6 outputs (diffuse RGB, specular RGB). */
static void eval6(const mr_brdf_model *m, const double *v, int j, double x, const double wi[3], const double wo[3],
                  double out[6]) {
    double w[MR_BRDF_MAX_VALUES];
    memcpy(w, v, sizeof w);
    w[j] = x;
    eval_parts(m, w, wi, wo, out, out + 3);
}

MR_TEST(gradient_matches_central_differences) {
    uint64_t rng = 5;
    for (const mr_brdf_model *const *mp = mr_brdf_models(); *mp; mp++) {
        const mr_brdf_model *m = *mp;
        /* every model gives its derivatives (issue 31): the fit's local stage relies on them */
        MR_CHECK_MSG(m->eval_grad != NULL, "%s: no eval_grad (analytic parameter derivatives)", m->name);
        if (!m->eval_grad) continue;
        int n = mr_brdf_value_count(m), checks = 0, kinks = 0, bad = 0;
        /* slot -> parameter */
        int param_of[MR_BRDF_MAX_VALUES];
        for (int i = 0, slot = 0; i < m->param_count; i++)
            for (int c = 0; c < m->params[i].channels; c++) param_of[slot++] = i;
        for (int k = 0; k < 60; k++) {
            double v[MR_BRDF_MAX_VALUES] = {0}, wi[3], wo[3], gd[MR_BRDF_MAX_VALUES * 3], gs[MR_BRDF_MAX_VALUES * 3];
            random_values(m, &rng, 0.03, v);
            random_dir(&rng, 0.1, wi);
            random_dir(&rng, 0.1, wo);
            m->eval_grad(m, v, wi, wo, gd, gs);
            double f[6];
            eval6(m, v, 0, v[0], wi, wo, f);
            for (int j = 0; j < n; j++) {
                const mr_brdf_param *p = &m->params[param_of[j]];
                if (p->role == MR_PARAM_SWITCH) {
                    for (int c = 0; c < 3; c++)
                        MR_CHECK_MSG(gd[j * 3 + c] == 0.0 && gs[j * 3 + c] == 0.0, "%s: switch gradient", m->name);
                    continue;
                }
                /* the natural unit of the parameter: its value on a log scale, its range otherwise */
                double unit = (p->flags & MR_PARAM_LOG_SCALE) ? v[j] : p->max_value - p->min_value;
                double h = 1e-5 * unit;
                double fp[6], fm[6], fp2[6], fm2[6];
                eval6(m, v, j, v[j] + h, wi, wo, fp);
                eval6(m, v, j, v[j] - h, wi, wo, fm);
                eval6(m, v, j, v[j] + 0.5 * h, wi, wo, fp2);
                eval6(m, v, j, v[j] - 0.5 * h, wi, wo, fm2);
                for (int o = 0; o < 6; o++) {
                    double fd = (fp[o] - fm[o]) / (2.0 * h), fd2 = (fp2[o] - fm2[o]) / h;
                    double fd_r = (4.0 * fd2 - fd) / 3.0; /* Richardson: error O(h^4) */
                    double an = o < 3 ? gd[j * 3 + o] : gs[j * 3 + (o - 3)];
                    double natural = (fabs(f[o]) + fabs(fp[o]) + fabs(fm[o])) / unit; /* |f| per unit */
                    checks++;
                    /* 1e-250: below it the values are denormal-scale and differences carry no digits */
                    double floor_abs = 1e-9 * natural + 1e-250;
                    /* a kink (trim boundary, a clamp, the G1 switch) between v - h and v + h: the two step sizes
                     * disagree far beyond truncation error (steep exponentials like cos^10000 stay below 1e-3) */
                    if (fabs(fd - fd2) > 1e-3 * fmax(fabs(fd), fabs(fd2)) + floor_abs) {
                        kinks++;
                        continue;
                    }
                    if (!(fabs(an - fd_r) <= 1e-4 * fmax(fabs(an), fabs(fd_r)) + 100.0 * floor_abs)) {
                        if (bad < 5)
                            fprintf(stderr, "    %s: d%s[%d]/d%s(slot %d) analytic %.10g, differences %.10g (f %.6g)\n",
                                    m->name, o < 3 ? "diffuse" : "specular", o % 3, p->name, j, an, fd_r, f[o]);
                        bad++;
                    }
                }
            }
        }
        printf("      %-20s %d gradient entries checked, %d skipped at kinks\n", m->name, checks - kinks, kinks);
        MR_CHECK_MSG(bad == 0, "%s: %d of %d gradient entries disagree", m->name, bad, checks);
        MR_CHECK_MSG(kinks * 20 <= checks, "%s: %d of %d checks skipped as kinks", m->name, kinks, checks);
    }
}

/* The derivatives at each model's defaults, where fits hold most parameters and several sit at an end of their
 * range (a coat weight, metalness or diffuse roughness of 0, a tint of 1) or on a node of the albedo table (ior 1.5
 * is the node eta = 1 + 2 (12/24)^2, where the interpolated albedo has a corner): compared there with one-sided
 * differences from inside the range (forward at the minimum, backward at the maximum), each with a Richardson step.
 * Inside the range, where the forward and backward derivatives agree, with the central difference as above; where
 * they do not (a corner at the value itself), the analytic derivative must be one of the two (the documented
 * one-sided derivative). So held parameters have the derivatives a fit leaving them needs. */
MR_TEST(gradient_at_defaults_matches_one_sided_differences) {
    uint64_t rng = 9;
    for (const mr_brdf_model *const *mp = mr_brdf_models(); *mp; mp++) {
        const mr_brdf_model *m = *mp;
        if (!m->eval_grad) continue; /* gradient_matches_central_differences fails it */
        int n = mr_brdf_value_count(m), checks = 0, kinks = 0, corners = 0, bad = 0;
        int param_of[MR_BRDF_MAX_VALUES];
        for (int i = 0, slot = 0; i < m->param_count; i++)
            for (int c = 0; c < m->params[i].channels; c++) param_of[slot++] = i;
        double v[MR_BRDF_MAX_VALUES] = {0};
        mr_brdf_default_values(m, v);
        for (int k = 0; k < 20; k++) {
            double wi[3], wo[3], gd[MR_BRDF_MAX_VALUES * 3], gs[MR_BRDF_MAX_VALUES * 3], f[6];
            random_dir(&rng, 0.1, wi);
            random_dir(&rng, 0.1, wo);
            m->eval_grad(m, v, wi, wo, gd, gs);
            eval6(m, v, 0, v[0], wi, wo, f);
            for (int j = 0; j < n; j++) {
                const mr_brdf_param *p = &m->params[param_of[j]];
                if (p->role == MR_PARAM_SWITCH) continue;
                double unit = (p->flags & MR_PARAM_LOG_SCALE) ? v[j] : p->max_value - p->min_value;
                double h = 1e-5 * unit;
                int fwd_ok = v[j]<p->max_value, bwd_ok = v[j]> p->min_value;
                double fa[6], fa2[6], fb[6], fb2[6];
                eval6(m, v, j, fwd_ok ? v[j] + h : v[j], wi, wo, fa);
                eval6(m, v, j, fwd_ok ? v[j] + 0.5 * h : v[j], wi, wo, fa2);
                eval6(m, v, j, bwd_ok ? v[j] - h : v[j], wi, wo, fb);
                eval6(m, v, j, bwd_ok ? v[j] - 0.5 * h : v[j], wi, wo, fb2);
                for (int o = 0; o < 6; o++) {
                    double an = o < 3 ? gd[j * 3 + o] : gs[j * 3 + (o - 3)];
                    double natural = (fabs(f[o]) + fabs(fa[o]) + fabs(fb[o])) / unit;
                    double floor_abs = 1e-9 * natural + 1e-250;
                    /* one-sided differences and their Richardson steps (error O(h^2)) */
                    double df1 = (fa[o] - f[o]) / h, df2 = (fa2[o] - f[o]) / (0.5 * h), fwd = 2.0 * df2 - df1;
                    double db1 = (f[o] - fb[o]) / h, db2 = (f[o] - fb2[o]) / (0.5 * h), bwd = 2.0 * db2 - db1;
                    int fwd_smooth = fwd_ok && fabs(df1 - df2) <= 2e-3 * fmax(fabs(df1), fabs(df2)) + floor_abs;
                    int bwd_smooth = bwd_ok && fabs(db1 - db2) <= 2e-3 * fmax(fabs(db1), fabs(db2)) + floor_abs;
                    checks++;
                    if (!fwd_smooth && !bwd_smooth) { /* a kink within h of the value, not at it */
                        kinks++;
                        continue;
                    }
                    int ok;
                    if (fwd_smooth && bwd_smooth && fabs(fwd - bwd) <= 1e-3 * fmax(fabs(fwd), fabs(bwd)) + floor_abs) {
                        double c1 = (fa[o] - fb[o]) / (2.0 * h), c2 = (fa2[o] - fb2[o]) / h,
                               central = (4.0 * c2 - c1) / 3.0;
                        ok = fabs(an - central) <= 1e-4 * fmax(fabs(an), fabs(central)) + 100.0 * floor_abs;
                    } else {
                        /* at an end of the range, or a corner at the value: the analytic one is a one-sided one */
                        int corner = fwd_smooth && bwd_smooth;
                        corners += corner;
                        ok = (fwd_smooth && fabs(an - fwd) <= 1e-4 * fmax(fabs(an), fabs(fwd)) + 100.0 * floor_abs) ||
                             (bwd_smooth && fabs(an - bwd) <= 1e-4 * fmax(fabs(an), fabs(bwd)) + 100.0 * floor_abs);
                    }
                    if (!ok) {
                        if (bad < 5)
                            fprintf(stderr,
                                    "    %s defaults: d%s[%d]/d%s(slot %d) analytic %.10g, forward %.10g, "
                                    "backward %.10g (f %.6g)\n",
                                    m->name, o < 3 ? "diffuse" : "specular", o % 3, p->name, j, an, fwd_ok ? fwd : NAN,
                                    bwd_ok ? bwd : NAN, f[o]);
                        bad++;
                    }
                }
            }
        }
        if (corners || kinks)
            printf("      %-20s at the defaults: %d entries one-sided at a corner, %d skipped at kinks, of %d\n",
                   m->name, corners, kinks, checks);
        MR_CHECK_MSG(bad == 0, "%s: %d of %d gradient entries at the defaults disagree", m->name, bad, checks);
        MR_CHECK_MSG(kinks * 20 <= checks, "%s: %d of %d checks at the defaults skipped as kinks", m->name, kinks,
                     checks);
    }
}

/* eval_grad is finite wherever eval is: every slot at its minimum, its maximum or between (switches either way),
 * directions down to grazing (z = 1e-9) and straight up. The square roots, logarithms and table coordinates whose
 * slopes are infinite at an end of their range (r = 0.01, eps = 0, a colour of 0) must give the documented one-sided
 * 0 there, not Inf or NaN. */
MR_TEST(gradient_is_finite_at_the_ends_of_the_ranges) {
    uint64_t rng = 12;
    for (const mr_brdf_model *const *mp = mr_brdf_models(); *mp; mp++) {
        const mr_brdf_model *m = *mp;
        if (!m->eval_grad) continue;
        int n = mr_brdf_value_count(m), bad = 0;
        for (int k = 0; k < 400; k++) {
            double v[MR_BRDF_MAX_VALUES] = {0}, wi[3], wo[3], gd[MR_BRDF_MAX_VALUES * 3], gs[MR_BRDF_MAX_VALUES * 3];
            random_values(m, &rng, 0.0, v);
            for (int i = 0, slot = 0; i < m->param_count; i++)
                for (int c = 0; c < m->params[i].channels; c++, slot++) {
                    double u = rnd(&rng);
                    if (u < 0.35) v[slot] = m->params[i].min_value;
                    else if (u < 0.7) v[slot] = m->params[i].max_value;
                }
            random_dir(&rng, 0.0, wi);
            random_dir(&rng, 0.0, wo);
            if (k % 4 == 1) dir_from_angles(PI / 2 - 1e-9, 0.3, wi);
            if (k % 4 == 2) dir_from_angles(0.0, 0.0, wo);
            if (k % 4 == 3) {
                dir_from_angles(0.0, 0.0, wi);
                dir_from_angles(0.0, 0.0, wo);
            }
            m->eval_grad(m, v, wi, wo, gd, gs);
            for (int j = 0; j < n * 3; j++)
                if (!isfinite(gd[j]) || !isfinite(gs[j])) {
                    if (bad < 3)
                        fprintf(stderr, "    %s: d f/d slot %d not finite (%g, %g)\n", m->name, j / 3, gd[j], gs[j]);
                    bad++;
                }
        }
        MR_CHECK_MSG(bad == 0, "%s: %d gradient entries not finite", m->name, bad);
    }
}

/* eval_grad's derivatives gd, gs (at v, wi, wo) in every channel of parameter p (its first slot `offset`) against
 * the secant over p's whole range, within 1e-9 of the secant's scale; `context` names the setting in messages.
 * Returns the entries checked. */
static int secants_match(const mr_brdf_model *m, const double *v, const mr_brdf_param *p, int offset,
                         const double wi[3], const double wo[3], const double *gd, const double *gs,
                         const char *context) {
    int checked = 0;
    for (int c = 0; c < p->channels; c++) {
        const int j = offset + c;
        double hi[6], lo[6];
        eval6(m, v, j, p->max_value, wi, wo, hi);
        eval6(m, v, j, p->min_value, wi, wo, lo);
        for (int o = 0; o < 6; o++) {
            double secant = (hi[o] - lo[o]) / (p->max_value - p->min_value);
            double an = o < 3 ? gd[j * 3 + o] : gs[j * 3 + o - 3];
            double scale = (fabs(hi[o]) + fabs(lo[o])) / (p->max_value - p->min_value);
            MR_CHECK_MSG(fabs(an - secant) <= 1e-9 * scale + 1e-300, "%s (%s): d f[%d]/d %s[%d] %.12g, secant %.12g",
                         m->name, context, o, p->name, c, an, secant);
            checked++;
        }
    }
    return checked;
}

/* Where f is affine in one value, its derivative is the secant over the whole range: d f/d v_j = (f(v_j = max) -
 * f(v_j = min))/(max - min), exactly (to rounding). Every LINEAR or AFFINE parameter (switches off, where roles hold,
 * as roles_are_truthful), and the layered models' parameters that are affine in a region their roles cannot state:
 * base colours with no metal, no coat and a Lambert diffuse, and metalness where nothing couples it (no coat). */
MR_TEST(gradient_is_the_secant_where_affine) {
    typedef struct affine_case {
        const char *model, *param, *settings[4];
    } affine_case;
    static const affine_case cases[] = {
        {"openpbr", "base_color", {"base_metalness=0", "coat_weight=0", "base_diffuse_roughness=0", NULL}},
        {"openpbr", "base_metalness", {"coat_weight=0", NULL}},
        {"blender-principled", "base_color", {"metallic=0", "coat_weight=0", NULL}},
        {"blender-principled", "metallic", {NULL}},
        {"standard-surface", "base_color", {"metalness=0", "coat=0", NULL}},
        {"usd-preview", "diffuse_color", {"use_specular_workflow=1", NULL}},
    };
    uint64_t rng = 10;
    int checked = 0;
    /* the generic part: every LINEAR/AFFINE parameter of every model */
    for (const mr_brdf_model *const *mp = mr_brdf_models(); *mp; mp++) {
        const mr_brdf_model *m = *mp;
        if (!m->eval_grad) continue;
        for (int i = 0; i < m->param_count; i++) {
            const mr_brdf_param *p = &m->params[i];
            if (p->role != MR_PARAM_LINEAR && p->role != MR_PARAM_AFFINE) continue;
            for (int k = 0; k < 10; k++) {
                double v[MR_BRDF_MAX_VALUES] = {0}, wi[3], wo[3];
                random_values(m, &rng, 0.0, v);
                switches_off(m, v);
                random_dir(&rng, 0.05, wi);
                random_dir(&rng, 0.05, wo);
                double gd[MR_BRDF_MAX_VALUES * 3], gs[MR_BRDF_MAX_VALUES * 3];
                m->eval_grad(m, v, wi, wo, gd, gs);
                checked += secants_match(m, v, p, mr_brdf_param_offset(m, i), wi, wo, gd, gs, "");
            }
        }
    }
    /* the layered models' affine regions */
    for (size_t n = 0; n < sizeof cases / sizeof cases[0]; n++) {
        const mr_brdf_model *m = model_named(cases[n].model);
        if (!m || !m->eval_grad) continue;
        int i = mr_brdf_param_index(m, cases[n].param);
        MR_CHECK_MSG(i >= 0, "%s has no %s", m->name, cases[n].param);
        if (i < 0) continue;
        const mr_brdf_param *p = &m->params[i];
        for (int k = 0; k < 10; k++) {
            double v[MR_BRDF_MAX_VALUES] = {0}, wi[3], wo[3];
            random_values(m, &rng, 0.0, v);
            for (int s = 0; cases[n].settings[s]; s++)
                MR_CHECK(mr_brdf_parse_assignment(m, cases[n].settings[s], v) == MR_OK);
            random_dir(&rng, 0.05, wi);
            random_dir(&rng, 0.05, wo);
            double gd[MR_BRDF_MAX_VALUES * 3], gs[MR_BRDF_MAX_VALUES * 3];
            m->eval_grad(m, v, wi, wo, gd, gs);
            checked += secants_match(m, v, p, mr_brdf_param_offset(m, i), wi, wo, gd, gs,
                                     cases[n].settings[0] ? cases[n].settings[0] : "");
        }
    }
    printf("      %d derivatives equal to the secant over the range\n", checked);
}

/* A prepared derivative state (brdf.h, grad_ops) gives eval_grad's numbers for the slots it was prepared for: for
 * random subsets of the slots in random order (1 to all of them), at random values (ends of the ranges included),
 * at the defaults, with the parameters fits hold at their defaults and with a slot at 0 (the terms a prepared state
 * skips when a slot it leaves out is a constant 0: dual.h, mr_dual_is_const_zero), over random direction pairs
 * (some below the horizon): every entry equal as doubles (==: the same operations in the same order; only the sign
 * of a zero may differ, where the full eval_grad adds a zero column's product), or both NaN. */
MR_TEST(prepared_gradient_equals_eval_grad_for_any_slots) {
    uint64_t rng = 31;
    int models = 0;
    for (const mr_brdf_model *const *mp = mr_brdf_models(); *mp; mp++) {
        const mr_brdf_model *m = *mp;
        if (!m->grad_ops) continue;
        MR_CHECK_MSG(m->eval_grad != NULL, "%s: grad_ops without eval_grad", m->name);
        if (!m->eval_grad) continue;
        models++;
        int n = mr_brdf_value_count(m), checked = 0, bad = 0;
        void *state = malloc(m->grad_ops->state_bytes);
        MR_CHECK(state != NULL);
        if (!state) continue;
        for (int trial = 0; trial < 30 + 2 * n; trial++) {
            double v[MR_BRDF_MAX_VALUES] = {0};
            if (trial == 0)
                mr_brdf_default_values(m, v);
            else
                random_values(m, &rng, trial % 4 == 0 ? 0.0 : 0.03, v);
            if (trial % 3 == 2) { /* as a fit holds them: the parameters it does not fit at their defaults (a coat
                                     weight of 0, whose terms a prepared state then skips), the others random */
                double d[MR_BRDF_MAX_VALUES];
                mr_brdf_default_values(m, d);
                for (int i = 0; i < m->param_count; i++)
                    if (m->params[i].flags & MR_PARAM_FIT_FIXED)
                        for (int c = 0; c < m->params[i].channels; c++)
                            v[mr_brdf_param_offset(m, i) + c] = d[mr_brdf_param_offset(m, i) + c];
            }
            if (trial % 5 == 4) /* a metalness (or any slot) held at 0, as a tie from a dielectric source gives */
                v[(int)(rnd(&rng) * n)] = 0.0;
            /* a random subset in random order: shuffle all slots, keep the first k */
            int slots[MR_BRDF_MAX_VALUES], k = trial == 1 ? n : 1 + (int)(rnd(&rng) * n);
            for (int j = 0; j < n; j++) slots[j] = j;
            for (int j = n - 1; j > 0; j--) {
                int o = (int)(rnd(&rng) * (j + 1)), t = slots[j];
                slots[j] = slots[o];
                slots[o] = t;
            }
            if (k > n) k = n;
            if (trial >= 30) { /* one slot alone, each in turn: the fits' projection asks for the shape alone, which
                                  the hand-written models compute by themselves */
                slots[0] = trial % n;
                k = 1;
            }
            m->grad_ops->prepare(m, v, slots, k, state);
            if (m->grad_ops->state_bytes == sizeof(mr_dual_grad_state)) { /* the layered models' dual tape: room left */
                const mr_dual_tape *tape = &((const mr_dual_grad_state *)state)->tape;
                MR_CHECK_MSG(tape->used + tape->width <= tape->capacity, "%s: prepared tape full (%d of %d)", m->name,
                             tape->used, tape->capacity);
            }
            for (int pair = 0; pair < 25; pair++) {
                double wi[3], wo[3];
                random_dir(&rng, 0.02, wi);
                random_dir(&rng, 0.02, wo);
                if (pair % 8 == 7) wo[2] = -wo[2]; /* below the horizon: all 0 */
                double gd[MR_BRDF_MAX_VALUES * 3], gs[MR_BRDF_MAX_VALUES * 3];
                double pd[MR_BRDF_MAX_VALUES * 3], ps[MR_BRDF_MAX_VALUES * 3];
                m->eval_grad(m, v, wi, wo, gd, gs);
                m->grad_ops->eval(state, wi, wo, pd, ps);
                for (int c = 0; c < k; c++)
                    for (int ch = 0; ch < 3; ch++) {
                        double a = gd[slots[c] * 3 + ch], b = pd[c * 3 + ch];
                        double a2 = gs[slots[c] * 3 + ch], b2 = ps[c * 3 + ch];
                        int same = (a == b || (isnan(a) && isnan(b))) && (a2 == b2 || (isnan(a2) && isnan(b2)));
                        if (!same && bad++ < 5)
                            fprintf(stderr, "    %s: slot %d (column %d of %d) channel %d: eval_grad %.17g %.17g, "
                                    "prepared %.17g %.17g\n", m->name, slots[c], c, k, ch, a, a2, b, b2);
                        checked += 2;
                    }
            }
        }
        free(state);
        printf("      %-20s %d prepared derivatives equal to eval_grad's\n", m->name, checked - 2 * bad);
        MR_CHECK_MSG(bad == 0, "%s: %d of %d prepared derivatives differ from eval_grad's", m->name, bad, checked / 2);
    }
    MR_CHECK(models >= 3); /* openpbr, blender-principled, standard-surface */
}

/* ---------------------------------------------------------------------------------------------------------- */
/* roles and lobes */

/* Scaling one channel of a LINEAR parameter by t scales that channel of the parts of its lobe by t and leaves the
 * other channels alone; an AFFINE parameter's midpoint gives the midpoint of the parts. */
MR_TEST(roles_are_truthful) {
    uint64_t rng = 6;
    const double rel = 1e-12;
    for (const mr_brdf_model *const *mp = mr_brdf_models(); *mp; mp++) {
        const mr_brdf_model *m = *mp;
        int bad = 0;
        for (int k = 0; k < 20; k++) {
            double v[MR_BRDF_MAX_VALUES] = {0};
            random_values(m, &rng, 0.0, v);
            switches_off(m, v);
            double wi[3], wo[3], d0[6];
            random_dir(&rng, 0.02, wi);
            random_dir(&rng, 0.02, wo);
            eval6(m, v, 0, v[0], wi, wo, d0);
            for (int i = 0; i < m->param_count; i++) {
                const mr_brdf_param *p = &m->params[i];
                int off = mr_brdf_param_offset(m, i);
                if (p->role != MR_PARAM_LINEAR && p->role != MR_PARAM_AFFINE) continue;
                for (int c = 0; c < p->channels; c++) {
                    int j = off + c;
                    double out_a[6], out_b[6], out_mid[6];
                    if (p->role == MR_PARAM_LINEAR) {
                        double t = 0.37;
                        eval6(m, v, j, v[j] * t, wi, wo, out_a);
                        for (int o = 0; o < 6; o++) {
                            int in_lobe = o < 3 ? (p->lobe & MR_LOBE_DIFFUSE) : (p->lobe & MR_LOBE_SPECULAR);
                            int same_channel = p->channels == 1 || o % 3 == c;
                            double expect = (in_lobe && same_channel) ? t * d0[o] : d0[o];
                            if (!close_rel(out_a[o], expect, rel)) bad++;
                        }
                    } else {
                        double a = p->min_value, b = p->max_value; /* 0 and 1 for F0, base colour */
                        eval6(m, v, j, a, wi, wo, out_a);
                        eval6(m, v, j, b, wi, wo, out_b);
                        eval6(m, v, j, 0.5 * (a + b), wi, wo, out_mid);
                        for (int o = 0; o < 6; o++) {
                            if (!close_rel(out_mid[o], 0.5 * (out_a[o] + out_b[o]), 1e-11)) bad++;
                            int same_channel = p->channels == 1 || o % 3 == c;
                            if (!same_channel && !close_rel(out_a[o], d0[o], rel)) bad++;
                        }
                    }
                }
            }
        }
        MR_CHECK_MSG(bad == 0, "%s: %d role violations", m->name, bad);
    }
}

/* The LINEAR and AFFINE parameters together: f is jointly affine in them (what the optimiser's linear solve
 * assumes), so f at the midpoint of two such vectors is the midpoint of f. */
MR_TEST(linear_and_affine_parameters_are_jointly_affine) {
    uint64_t rng = 7;
    for (const mr_brdf_model *const *mp = mr_brdf_models(); *mp; mp++) {
        const mr_brdf_model *m = *mp;
        int bad = 0;
        for (int k = 0; k < 20; k++) {
            double u[MR_BRDF_MAX_VALUES] = {0}, w[MR_BRDF_MAX_VALUES] = {0}, mid[MR_BRDF_MAX_VALUES] = {0};
            double r[MR_BRDF_MAX_VALUES] = {0};
            random_values(m, &rng, 0.0, u);
            switches_off(m, u);
            memcpy(w, u, sizeof w);
            random_values(m, &rng, 0.0, r);
            for (int i = 0; i < m->param_count; i++) {
                const mr_brdf_param *p = &m->params[i];
                if (p->role != MR_PARAM_LINEAR && p->role != MR_PARAM_AFFINE) continue;
                int off = mr_brdf_param_offset(m, i);
                for (int c = 0; c < p->channels; c++) w[off + c] = r[off + c];
            }
            for (int j = 0; j < mr_brdf_value_count(m); j++) mid[j] = 0.5 * (u[j] + w[j]);
            double wi[3], wo[3], fu[6], fw[6], fm[6];
            random_dir(&rng, 0.02, wi);
            random_dir(&rng, 0.02, wo);
            eval6(m, u, 0, u[0], wi, wo, fu);
            eval6(m, w, 0, w[0], wi, wo, fw);
            eval6(m, mid, 0, mid[0], wi, wo, fm);
            for (int o = 0; o < 6; o++)
                if (!close_rel(fm[o], 0.5 * (fu[o] + fw[o]), 1e-11)) bad++;
        }
        MR_CHECK_MSG(bad == 0, "%s: %d violations of joint affinity", m->name, bad);
    }
}

/* A DIFFUSE-lobe parameter never changes the specular part, and a SPECULAR-lobe one never the diffuse part. */
MR_TEST(lobes_are_truthful) {
    uint64_t rng = 8;
    for (const mr_brdf_model *const *mp = mr_brdf_models(); *mp; mp++) {
        const mr_brdf_model *m = *mp;
        int bad = 0;
        for (int k = 0; k < 20; k++) {
            double v[MR_BRDF_MAX_VALUES] = {0}, r[MR_BRDF_MAX_VALUES], wi[3], wo[3], f0[6], f1[6];
            random_values(m, &rng, 0.0, v);
            switches_off(m, v);
            random_values(m, &rng, 0.0, r);
            random_dir(&rng, 0.02, wi);
            random_dir(&rng, 0.02, wo);
            eval6(m, v, 0, v[0], wi, wo, f0);
            for (int i = 0; i < m->param_count; i++) {
                const mr_brdf_param *p = &m->params[i];
                if (p->lobe == MR_LOBE_BOTH || p->role == MR_PARAM_SWITCH) continue;
                int off = mr_brdf_param_offset(m, i);
                double w[MR_BRDF_MAX_VALUES];
                memcpy(w, v, sizeof w);
                for (int c = 0; c < p->channels; c++) w[off + c] = r[off + c];
                eval6(m, w, 0, w[0], wi, wo, f1);
                int fixed = p->lobe == MR_LOBE_DIFFUSE ? 3 : 0; /* the part that must not move */
                for (int o = fixed; o < fixed + 3; o++)
                    if (f1[o] != f0[o]) bad++;
            }
        }
        MR_CHECK_MSG(bad == 0, "%s: %d lobe violations", m->name, bad);
    }
}

/* ---------------------------------------------------------------------------------------------------------- */
/* known answers, computed here from the published formulas */

static const double normal[3] = {0.0, 0.0, 1.0};

MR_TEST(known_lambert) {
    const mr_brdf_model *m = model_named("lambert");
    if (!m) return;
    double v[3] = {0.2, 0.5, 0.9}, wi[3], wo[3], d[3], s[3];
    dir_from_angles(0.7, 0.3, wi);
    dir_from_angles(1.2, 2.0, wo);
    eval_parts(m, v, wi, wo, d, s);
    for (int c = 0; c < 3; c++) {
        MR_CHECK_NEAR(d[c], v[c] / PI, 1e-15);
        MR_CHECK(s[c] == 0.0);
    }
}

MR_TEST(known_microfacet_normal_incidence) {
    /* wi = wo = n: h = n, Schlick F = F0, D(n) = 1/(pi alpha^2) for all three distributions (EPhong: (n+2)/(2 pi)
     * with n = 2/alpha^2 - 2), G1 = 1, so f_s = F0/(4 pi alpha^2). */
    const char *names[] = {"beckmann", "ggx", "as"};
    for (int k = 0; k < 3; k++) {
        const mr_brdf_model *m = model_named(names[k]);
        if (!m) continue;
        double v[MR_BRDF_MAX_VALUES] = {0}, d[3], s[3];
        mr_brdf_default_values(m, v);
        set_param(m, v, "alpha", 0.3);
        set_rgb(m, v, "f0", 0.1, 0.5, 0.9);
        eval_parts(m, v, normal, normal, d, s);
        const double f0[3] = {0.1, 0.5, 0.9};
        for (int c = 0; c < 3; c++) {
            MR_CHECK_NEAR(s[c], f0[c] / (4.0 * PI * 0.09), 1e-12 * s[c]);
            MR_CHECK(d[c] == 0.0);
        }
    }
}

/* Beckmann's rational Smith G1 (Walter et al. 2007), in terms of a = cot(theta)/alpha. */
static double beckmann_g1(double theta, double alpha) {
    double a = cos(theta) / (alpha * sin(theta));
    return a >= 1.6 ? 1.0 : (3.535 * a + 2.181 * a * a) / (1.0 + 2.276 * a + 2.577 * a * a);
}

MR_TEST(known_microfacet_off_normal) {
    double ti = 0.5, to = 0.9, alpha = 0.35, wi[3], wo[3];
    dir_from_angles(ti, 0.0, wi);
    dir_from_angles(to, 2.1, wo);
    double h[3] = {wi[0] + wo[0], wi[1] + wo[1], wi[2] + wo[2]};
    double hl = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
    double ch = h[2] / hl, th = acos(ch), c_ih = (wi[0] * h[0] + wi[1] * h[1] + wi[2] * h[2]) / hl;
    double a2 = alpha * alpha, t2 = tan(th) * tan(th);
    double f0 = 0.3, F = f0 + (1.0 - f0) * pow(1.0 - c_ih, 5.0);
    /* GGX: Karis' forms, D = a^2/(pi ((n.h)^2 (a^2 - 1) + 1)^2), G1 = 2 n.v/(n.v + sqrt(a^2 + (1 - a^2)(n.v)^2)) */
    double dd = ch * ch * (a2 - 1.0) + 1.0;
    double D_ggx = a2 / (PI * dd * dd);
    double g1i = 2.0 * cos(ti) / (cos(ti) + sqrt(a2 + (1.0 - a2) * cos(ti) * cos(ti)));
    double g1o = 2.0 * cos(to) / (cos(to) + sqrt(a2 + (1.0 - a2) * cos(to) * cos(to)));
    double ggx = F * D_ggx * g1i * g1o / (4.0 * cos(ti) * cos(to));
    double D_beck = exp(-t2 / a2) / (PI * a2 * pow(ch, 4.0));
    double beck = F * D_beck * beckmann_g1(ti, alpha) * beckmann_g1(to, alpha) / (4.0 * cos(ti) * cos(to));
    double n = 2.0 / a2 - 2.0, D_as = (n + 2.0) / (2.0 * PI) * pow(ch, n);
    double as = F * D_as * beckmann_g1(ti, alpha) * beckmann_g1(to, alpha) / (4.0 * cos(ti) * cos(to));
    const char *names[] = {"ggx", "beckmann", "as"};
    const double expect[] = {ggx, beck, as};
    for (int k = 0; k < 3; k++) {
        const mr_brdf_model *m = model_named(names[k]);
        if (!m) continue;
        double v[MR_BRDF_MAX_VALUES] = {0}, d[3], s[3];
        mr_brdf_default_values(m, v);
        set_param(m, v, "alpha", alpha);
        set_param(m, v, "f0", f0);
        eval_parts(m, v, wi, wo, d, s);
        MR_CHECK_MSG(close_rel(s[1], expect[k], 1e-10), "%s: %.15g vs %.15g", names[k], s[1], expect[k]);
    }
}

MR_TEST(known_conductor_fresnel) {
    const mr_brdf_model *m = model_named("ggx-conductor");
    const mr_brdf_model *none = model_named("ggx-nofresnel");
    if (!m || !none) return;
    uint64_t rng = 9;
    double v[MR_BRDF_MAX_VALUES] = {0}, vn[MR_BRDF_MAX_VALUES], d[3], s[3], dn[3], sn[3];
    mr_brdf_default_values(m, v);
    mr_brdf_default_values(none, vn);
    set_param(m, v, "alpha", 0.2);
    set_param(none, vn, "alpha", 0.2);
    for (int k = 0; k < 20; k++) {
        double wi[3], wo[3];
        random_dir(&rng, 0.01, wi);
        random_dir(&rng, 0.01, wo);
        /* eta = 1, k = 0: the interface vanishes, F = 0 */
        set_param(m, v, "eta", 1.0);
        set_param(m, v, "k", 0.0);
        eval_parts(m, v, wi, wo, d, s);
        eval_parts(none, vn, wi, wo, dn, sn);
        for (int c = 0; c < 3; c++) MR_CHECK(s[c] <= 1e-12 * sn[c]);
        /* Mitsuba's "none": eta = 0, k = 1 gives F = 1, i.e. the F = 1 model */
        set_param(m, v, "eta", 0.0);
        set_param(m, v, "k", 1.0);
        eval_parts(m, v, wi, wo, d, s);
        for (int c = 0; c < 3; c++) MR_CHECK_MSG(close_rel(s[c], sn[c], 1e-12), "%.17g vs %.17g", s[c], sn[c]);
    }
    /* normal incidence, default Cu: F = ((eta - 1)^2 + k^2)/((eta + 1)^2 + k^2) */
    mr_brdf_default_values(m, v);
    set_param(m, v, "alpha", 0.2);
    eval_parts(m, v, normal, normal, d, s);
    const double eta[3] = {0.200438, 0.924033, 1.10221}, kk[3] = {3.91295, 2.45285, 2.14219};
    for (int c = 0; c < 3; c++) {
        double F = ((eta[c] - 1) * (eta[c] - 1) + kk[c] * kk[c]) / ((eta[c] + 1) * (eta[c] + 1) + kk[c] * kk[c]);
        MR_CHECK_MSG(close_rel(s[c], F / (4.0 * PI * 0.04), 1e-12), "channel %d: %.17g", c, s[c]);
        MR_CHECK(d[c] == 0.0);
    }
}

MR_TEST(known_plastic) {
    const mr_brdf_model *m = model_named("beckmann-plastic");
    if (!m) return;
    double v[MR_BRDF_MAX_VALUES] = {0}, d[3], s[3];
    mr_brdf_default_values(m, v);
    set_param(m, v, "alpha", 0.25);
    set_rgb(m, v, "diffuse", 0.2, 0.4, 0.6);
    set_param(m, v, "specular", 0.5);
    set_param(m, v, "ior", 1.7);
    eval_parts(m, v, normal, normal, d, s);
    double F0 = (0.7 / 2.7) * (0.7 / 2.7);
    const double rd[3] = {0.2, 0.4, 0.6};
    for (int c = 0; c < 3; c++) {
        MR_CHECK(close_rel(d[c], rd[c] / PI * (1.0 - F0) * (1.0 - F0), 1e-12));
        MR_CHECK(close_rel(s[c], 0.5 * F0 / (4.0 * PI * 0.0625), 1e-12));
    }
    /* ior = 1: no interface at all, a Lambert base and no specular */
    set_param(m, v, "ior", 1.0);
    double wi[3], wo[3];
    dir_from_angles(1.3, 0.0, wi);
    dir_from_angles(0.4, 2.5, wo);
    eval_parts(m, v, wi, wo, d, s);
    for (int c = 0; c < 3; c++) {
        MR_CHECK(close_rel(d[c], rd[c] / PI, 1e-12));
        MR_CHECK(s[c] <= 1e-15);
    }
}

MR_TEST(known_ward_variants) {
    /* wi = wo = n: all three normalisations give rho_s/(4 pi alpha^2) + rho_d/pi */
    const char *names[] = {"ward", "ward-duer", "ward-balanced"};
    for (int k = 0; k < 3; k++) {
        const mr_brdf_model *m = model_named(names[k]);
        if (!m) continue;
        double v[MR_BRDF_MAX_VALUES] = {0}, d[3], s[3];
        mr_brdf_default_values(m, v);
        set_rgb(m, v, "diffuse", 0.1, 0.2, 0.3);
        set_rgb(m, v, "specular", 0.3, 0.2, 0.1);
        set_param(m, v, "alpha", 0.15);
        eval_parts(m, v, normal, normal, d, s);
        const double rd[3] = {0.1, 0.2, 0.3}, rs[3] = {0.3, 0.2, 0.1};
        for (int c = 0; c < 3; c++) {
            MR_CHECK(close_rel(d[c], rd[c] / PI, 1e-14));
            MR_CHECK_MSG(close_rel(s[c], rs[c] / (4.0 * PI * 0.0225), 1e-12), "%s %.17g", names[k], s[c]);
        }
        /* off-normal, independently: exp(-tan^2(theta_h)/alpha^2) times the variant's normalisation */
        double wi[3], wo[3];
        dir_from_angles(0.6, 0.0, wi);
        dir_from_angles(0.8, 2.8, wo);
        double H[3] = {wi[0] + wo[0], wi[1] + wo[1], wi[2] + wo[2]};
        double e = exp(-(H[0] * H[0] + H[1] * H[1]) / (H[2] * H[2]) / 0.0225);
        double N = k == 0   ? 1.0 / (4.0 * PI * 0.0225 * sqrt(wi[2] * wo[2]))
                   : k == 1 ? 1.0 / (4.0 * PI * 0.0225 * wi[2] * wo[2])
                            : (H[0] * H[0] + H[1] * H[1] + H[2] * H[2]) / (PI * 0.0225 * pow(H[2], 4.0));
        eval_parts(m, v, wi, wo, d, s);
        MR_CHECK_MSG(close_rel(s[0], 0.3 * N * e, 1e-12), "%s: %.17g vs %.17g", names[k], s[0], 0.3 * N * e);
    }
}

MR_TEST(known_trimming) {
    /* Mitsuba's ensureEnergyConservation: max(rho_d + rho_s) = 1.4 > 1, so both are scaled by 0.99/1.4 */
    const char *names[] = {"ward", "ward-balanced", "phong"};
    for (int k = 0; k < 3; k++) {
        const mr_brdf_model *m = model_named(names[k]);
        if (!m) continue;
        double on[MR_BRDF_MAX_VALUES] = {0}, off[MR_BRDF_MAX_VALUES], wi[3], wo[3], d1[3], s1[3], d2[3], s2[3];
        mr_brdf_default_values(m, on);
        set_rgb(m, on, "diffuse", 0.8, 0.5, 0.2);
        set_rgb(m, on, "specular", 0.6, 0.3, 0.1);
        set_param(m, on, "trim", 1.0);
        double q = 0.99 / 1.4;
        memcpy(off, on, sizeof off);
        set_rgb(m, off, "diffuse", 0.8 * q, 0.5 * q, 0.2 * q);
        set_rgb(m, off, "specular", 0.6 * q, 0.3 * q, 0.1 * q);
        set_param(m, off, "trim", 0.0);
        dir_from_angles(0.3, 0.0, wi);
        dir_from_angles(0.35, 3.0, wo);
        eval_parts(m, on, wi, wo, d1, s1);
        eval_parts(m, off, wi, wo, d2, s2);
        for (int c = 0; c < 3; c++) MR_CHECK(close_rel(d1[c], d2[c], 1e-14) && close_rel(s1[c], s2[c], 1e-14));
        /* below the threshold trimming changes nothing */
        set_rgb(m, on, "diffuse", 0.5, 0.5, 0.5);
        set_rgb(m, on, "specular", 0.5, 0.2, 0.1);
        memcpy(off, on, sizeof off);
        set_param(m, off, "trim", 0.0);
        eval_parts(m, on, wi, wo, d1, s1);
        eval_parts(m, off, wi, wo, d2, s2);
        MR_CHECK(memcmp(d1, d2, sizeof d1) == 0 && memcmp(s1, s2, sizeof s1) == 0);
    }
}

MR_TEST(known_phong) {
    const mr_brdf_model *m = model_named("phong");
    if (!m) return;
    double v[MR_BRDF_MAX_VALUES] = {0}, wi[3], wo[3], d[3], s[3];
    mr_brdf_default_values(m, v);
    set_param(m, v, "trim", 0.0);
    set_param(m, v, "exponent", 12.0);
    set_param(m, v, "specular", 0.4);
    set_param(m, v, "diffuse", 0.3);
    eval_parts(m, v, normal, normal, d, s);
    MR_CHECK(close_rel(s[0], 0.4 * 14.0 / (2.0 * PI), 1e-14));
    MR_CHECK(close_rel(d[0], 0.3 / PI, 1e-14));
    /* off the mirror direction: cos(angle to r)^n with r the mirror of wi */
    dir_from_angles(0.5, 0.0, wi);
    dir_from_angles(0.6, PI + 0.2, wo);
    double r[3] = {-wi[0], -wi[1], wi[2]};
    double c = r[0] * wo[0] + r[1] * wo[1] + r[2] * wo[2];
    eval_parts(m, v, wi, wo, d, s);
    MR_CHECK(close_rel(s[0], 0.4 * 14.0 / (2.0 * PI) * pow(c, 12.0), 1e-12));
    /* behind the mirror lobe (wo.r <= 0): only the diffuse part */
    dir_from_angles(1.4, 0.0, wi);
    dir_from_angles(1.4, 0.0, wo);
    eval_parts(m, v, wi, wo, d, s);
    MR_CHECK(s[0] == 0.0 && d[0] > 0.0);
}

MR_TEST(known_blender_ward) {
    const mr_brdf_model *m = model_named("blender-ward");
    if (!m) return;
    double v[MR_BRDF_MAX_VALUES] = {0}, wi[3], wo[3], d[3], s[3];
    mr_brdf_default_values(m, v);
    set_param(m, v, "rms", 0.2);
    eval_parts(m, v, normal, normal, d, s);
    for (int c = 0; c < 3; c++) {
        MR_CHECK(close_rel(d[c], 0.64, 1e-15)); /* no 1/pi */
        MR_CHECK(close_rel(s[c], 0.5 / (4.0 * PI * 0.04), 1e-13));
    }
    /* WardIso_Spec / n.l, from its angles: exp(-tan^2(acos(n.h))/rms^2) / (4 pi rms^2 sqrt(n.v n.l)) */
    dir_from_angles(0.9, 0.0, wi);
    dir_from_angles(0.4, 2.0, wo);
    double h[3] = {wi[0] + wo[0], wi[1] + wo[1], wi[2] + wo[2]};
    double nh = h[2] / sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
    double ang = tan(acos(nh));
    double expect = 0.5 * exp(-ang * ang / 0.04) / (4.0 * PI * 0.04 * sqrt(wi[2] * wo[2]));
    eval_parts(m, v, wi, wo, d, s);
    MR_CHECK_MSG(close_rel(s[2], expect, 1e-10), "%.17g vs %.17g", s[2], expect);
}

/* glTF Appendix B, written out independently: returns diffuse/specular of the metallic-roughness model with the
 * KHR_materials_specular/ior extensions. */
static void gltf_reference(const double base[3], double metallic, double rough, double spec, const double color[3],
                           double ior, const double wi[3], const double wo[3], double d[3], double s[3]) {
    double h[3] = {wi[0] + wo[0], wi[1] + wo[1], wi[2] + wo[2]};
    double hl = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
    double nh = h[2] / hl, vh = (wo[0] * h[0] + wo[1] * h[1] + wo[2] * h[2]) / hl;
    double nl = wi[2], nv = wo[2], a = rough * rough, a2 = a * a;
    double dd = nh * nh * (a2 - 1.0) + 1.0, D = a2 / (PI * dd * dd);
    double V = 0.5 / (nv * sqrt(a2 + (1 - a2) * nl * nl) + nl * sqrt(a2 + (1 - a2) * nv * nv));
    double w = pow(1.0 - fabs(vh), 5.0), f0i = pow((ior - 1) / (ior + 1), 2.0);
    double F[3], Fmax = 0.0;
    for (int c = 0; c < 3; c++) {
        double f0 = fmin(f0i * color[c], 1.0) * spec;
        F[c] = f0 + (spec - f0) * w; /* mix(f0, f90 = specular, w) */
        Fmax = fmax(Fmax, F[c]);
    }
    for (int c = 0; c < 3; c++) {
        double metal = (base[c] + (1.0 - base[c]) * w) * D * V;
        d[c] = (1.0 - metallic) * (1.0 - Fmax) * base[c] / PI;
        s[c] = (1.0 - metallic) * F[c] * D * V + metallic * metal;
    }
}

MR_TEST(known_gltf) {
    const mr_brdf_model *m = model_named("gltf");
    if (!m) return;
    double v[MR_BRDF_MAX_VALUES] = {0}, d[3], s[3], rd[3], rs[3];
    const double base[3] = {0.9, 0.5, 0.1}, white[3] = {1, 1, 1};
    mr_brdf_default_values(m, v);
    set_rgb(m, v, "base_color", 0.9, 0.5, 0.1);
    set_param(m, v, "roughness", 0.4);
    /* metallic = 1 at normal incidence: base D V with D = 1/(pi alpha^2), V = 1/4 */
    eval_parts(m, v, normal, normal, d, s);
    for (int c = 0; c < 3; c++) {
        MR_CHECK(close_rel(s[c], base[c] / (PI * 0.0256) / 4.0, 1e-12));
        MR_CHECK(d[c] == 0.0);
    }
    /* dielectric defaults at normal incidence: F = 0.04 */
    set_param(m, v, "metallic", 0.0);
    eval_parts(m, v, normal, normal, d, s);
    for (int c = 0; c < 3; c++) {
        MR_CHECK(close_rel(s[c], 0.04 / (PI * 0.0256) / 4.0, 1e-12));
        MR_CHECK(close_rel(d[c], 0.96 * base[c] / PI, 1e-12));
    }
    /* everything at once, off-normal */
    double wi[3], wo[3];
    const double color[3] = {2.0, 1.0, 0.5};
    dir_from_angles(1.1, 0.0, wi);
    dir_from_angles(0.7, 2.4, wo);
    set_param(m, v, "metallic", 0.3);
    set_param(m, v, "specular", 0.8);
    set_rgb(m, v, "specular_color", 2.0, 1.0, 0.5);
    set_param(m, v, "ior", 1.8);
    eval_parts(m, v, wi, wo, d, s);
    gltf_reference(base, 0.3, 0.4, 0.8, color, 1.8, wi, wo, rd, rs);
    for (int c = 0; c < 3; c++) {
        MR_CHECK_MSG(close_rel(d[c], rd[c], 1e-11), "diffuse %d: %.17g vs %.17g", c, d[c], rd[c]);
        MR_CHECK_MSG(close_rel(s[c], rs[c], 1e-11), "specular %d: %.17g vs %.17g", c, s[c], rs[c]);
    }
    /* the core specification (no extensions) is the defaults of the extensions */
    mr_brdf_default_values(m, v);
    set_rgb(m, v, "base_color", 0.9, 0.5, 0.1);
    set_param(m, v, "metallic", 0.6);
    set_param(m, v, "roughness", 0.7);
    eval_parts(m, v, wi, wo, d, s);
    gltf_reference(base, 0.6, 0.7, 1.0, white, 1.5, wi, wo, rd, rs);
    for (int c = 0; c < 3; c++) MR_CHECK(close_rel(d[c], rd[c], 1e-11) && close_rel(s[c], rs[c], 1e-11));
}

MR_TEST(known_gltf_specgloss) {
    const mr_brdf_model *m = model_named("gltf-specgloss");
    if (!m) return;
    double v[MR_BRDF_MAX_VALUES] = {0}, d[3], s[3];
    mr_brdf_default_values(m, v);
    set_rgb(m, v, "diffuse", 0.8, 0.6, 0.4);
    set_rgb(m, v, "specular", 0.04, 0.2, 0.1);
    set_param(m, v, "glossiness", 0.6); /* alpha = 0.16 */
    eval_parts(m, v, normal, normal, d, s);
    const double dif[3] = {0.8, 0.6, 0.4}, sp[3] = {0.04, 0.2, 0.1};
    for (int c = 0; c < 3; c++) {
        MR_CHECK(close_rel(s[c], sp[c] / (PI * 0.0256) / 4.0, 1e-12));
        MR_CHECK(close_rel(d[c], (1.0 - sp[c]) * dif[c] * (1.0 - 0.2) / PI, 1e-12));
    }
}

MR_TEST(known_cycles_principled) {
    const mr_brdf_model *m = model_named("cycles-principled");
    if (!m) return;
    uint64_t rng = 10;
    double v[MR_BRDF_MAX_VALUES] = {0}, d[3], s[3], wi[3], wo[3];
    mr_brdf_default_values(m, v);
    set_param(m, v, "roughness", 0.3); /* alpha = 0.09 */
    /* defaults at normal incidence: F = F0 = 0.08 * 0.5; Burley's factor is 1 at normal incidence */
    eval_parts(m, v, normal, normal, d, s);
    for (int c = 0; c < 3; c++) {
        MR_CHECK(close_rel(s[c], 0.04 / (4.0 * PI * 0.0081), 1e-6));
        MR_CHECK(close_rel(d[c], 0.8 / PI, 1e-14));
    }
    /* specular = 0, metallic = 0: no specular reflection at normal incidence (ior = 1, cspec0 = 0) */
    set_param(m, v, "specular", 0.0);
    eval_parts(m, v, normal, normal, d, s);
    for (int c = 0; c < 3; c++) MR_CHECK(s[c] == 0.0);
    for (int k = 0; k < 10; k++) {
        random_dir(&rng, 0.01, wi);
        random_dir(&rng, 0.01, wo);
        eval_parts(m, v, wi, wo, d, s);
        for (int c = 0; c < 3; c++) MR_CHECK(s[c] <= 1e-12);
    }
    /* metallic = 1 at normal incidence: F = cspec0 = base */
    set_param(m, v, "metallic", 1.0);
    set_param(m, v, "specular", 0.5);
    set_rgb(m, v, "base_color", 0.9, 0.6, 0.3);
    eval_parts(m, v, normal, normal, d, s);
    const double base[3] = {0.9, 0.6, 0.3};
    for (int c = 0; c < 3; c++) {
        MR_CHECK(close_rel(s[c], base[c] / (4.0 * PI * 0.0081), 1e-12));
        MR_CHECK(d[c] == 0.0);
    }
    /* specular tint = 1: F0 = 0.08 specular base/lum with lum = 0.3 R + 0.6 G + 0.1 B (Cycles 3.x) */
    set_param(m, v, "metallic", 0.0);
    set_param(m, v, "specular_tint", 1.0);
    set_rgb(m, v, "base_color", 0.2, 0.5, 0.8);
    eval_parts(m, v, normal, normal, d, s);
    const double b2[3] = {0.2, 0.5, 0.8};
    double lum = 0.3 * 0.2 + 0.6 * 0.5 + 0.1 * 0.8;
    for (int c = 0; c < 3; c++) MR_CHECK(close_rel(s[c], 0.04 * b2[c] / lum / (4.0 * PI * 0.0081), 1e-6));
    /* Burley off-normal: (1 + (F_d90 - 1) F_L)(1 + (F_d90 - 1) F_V), F_d90 = 0.5 + 2 roughness (l.h)^2 */
    dir_from_angles(1.2, 0.0, wi);
    dir_from_angles(0.5, 1.0, wo);
    double h[3] = {wi[0] + wo[0], wi[1] + wo[1], wi[2] + wo[2]};
    double lh = (wi[0] * h[0] + wi[1] * h[1] + wi[2] * h[2]) / sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
    double fd90 = 0.5 + 2.0 * 0.3 * lh * lh, FL = pow(1.0 - wi[2], 5.0), FV = pow(1.0 - wo[2], 5.0);
    eval_parts(m, v, wi, wo, d, s);
    for (int c = 0; c < 3; c++)
        MR_CHECK(close_rel(d[c], b2[c] / PI * (1.0 + (fd90 - 1.0) * FL) * (1.0 + (fd90 - 1.0) * FV), 1e-12));
}

/* cycles-ggx: with the separable G it is `ggx` at alpha = roughness^2, bit for bit (the same D, G1 and Schlick
 * code), except where Mitsuba's cut-off D cos_h < 1e-20 zeroes ggx; with correlated = 1, Cycles 3.5's
 * G2 = 1/(1 + L(wi) + L(wo)) written here from the Lambdas, independently of src/brdf. */
MR_TEST(known_cycles_ggx) {
    const mr_brdf_model *m = model_named("cycles-ggx"), *ggx = model_named("ggx");
    if (!m || !ggx) return;
    uint64_t rng = 11;
    int compared = 0, differ = 0, cut = 0;
    for (int k = 0; k < 2000; k++) {
        double v[MR_BRDF_MAX_VALUES] = {0}, g[MR_BRDF_MAX_VALUES] = {0}, wi[3], wo[3], d[3], s[3], dg[3], sg[3];
        random_values(m, &rng, 0.0, v);
        set_param(m, v, "correlated", 0.0);
        mr_brdf_default_values(ggx, g);
        double r = v[mr_brdf_param_offset(m, mr_brdf_param_index(m, "roughness"))];
        set_param(ggx, g, "alpha", r * r);
        for (int c = 0; c < 3; c++) {
            g[mr_brdf_param_offset(ggx, mr_brdf_param_index(ggx, "f0")) + c] =
                v[mr_brdf_param_offset(m, mr_brdf_param_index(m, "f0")) + c];
            g[mr_brdf_param_offset(ggx, mr_brdf_param_index(ggx, "diffuse")) + c] =
                v[mr_brdf_param_offset(m, mr_brdf_param_index(m, "diffuse")) + c];
        }
        random_dir(&rng, k < 1000 ? 0.02 : 0.0, wi);
        random_dir(&rng, k < 1000 ? 0.02 : 0.0, wo);
        eval_parts(m, v, wi, wo, d, s);
        eval_parts(ggx, g, wi, wo, dg, sg);
        for (int c = 0; c < 3; c++) {
            compared++;
            if (sg[c] == 0.0 && s[c] > 0.0 && s[c] < 1e-12) {
                cut++;
                continue;
            }
            if (d[c] != dg[c] || s[c] != sg[c]) differ++;
        }
    }
    MR_CHECK_MSG(differ == 0, "%d of %d values differ from ggx at alpha = roughness^2", differ, compared);
    printf("      cycles-ggx == ggx(alpha = roughness^2) bit for bit on %d values (%d under Mitsuba's cut-off)\n",
           compared - cut, cut);

    /* normal incidence, either G: D = 1/(pi alpha^2), G = 1, F = F0: f = F0/(4 pi alpha^2) */
    double v[MR_BRDF_MAX_VALUES] = {0}, d[3], s[3];
    mr_brdf_default_values(m, v);
    set_param(m, v, "roughness", 0.3); /* alpha = 0.09 */
    set_rgb(m, v, "f0", 0.04, 0.5, 0.9);
    set_rgb(m, v, "diffuse", 0.2, 0.4, 0.6);
    const double f0[3] = {0.04, 0.5, 0.9}, rho[3] = {0.2, 0.4, 0.6};
    for (int corr = 0; corr < 2; corr++) {
        set_param(m, v, "correlated", corr);
        eval_parts(m, v, normal, normal, d, s);
        for (int c = 0; c < 3; c++) {
            MR_CHECK_MSG(close_rel(s[c], f0[c] / (4.0 * PI * 0.0081), 1e-12), "correlated %d: %.17g", corr, s[c]);
            MR_CHECK(close_rel(d[c], rho[c] / PI, 1e-15));
        }
    }

    /* height-correlated off normal, from Cycles 3.5's Lambda form */
    set_param(m, v, "correlated", 1.0);
    const double rough[] = {0.05, 0.3, 0.7, 1.0};
    for (size_t k = 0; k < sizeof rough / sizeof rough[0]; k++) {
        double wi[3], wo[3];
        dir_from_angles(0.4 + 0.3 * k, 0.0, wi);
        dir_from_angles(1.1 - 0.2 * k, 2.3, wo);
        double h[3] = {wi[0] + wo[0], wi[1] + wo[1], wi[2] + wo[2]};
        double hl = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]), ch = h[2] / hl;
        double c_ih = (wi[0] * h[0] + wi[1] * h[1] + wi[2] * h[2]) / hl;
        double a2 = pow(rough[k], 4.0), dd = 1.0 + (a2 - 1.0) * ch * ch, D = a2 / (PI * dd * dd);
        double ti2 = (1.0 - wi[2] * wi[2]) / (wi[2] * wi[2]), to2 = (1.0 - wo[2] * wo[2]) / (wo[2] * wo[2]);
        double Li = 0.5 * (sqrt(1.0 + a2 * ti2) - 1.0), Lo = 0.5 * (sqrt(1.0 + a2 * to2) - 1.0);
        double G2 = 1.0 / (1.0 + Li + Lo);
        set_param(m, v, "roughness", rough[k]);
        eval_parts(m, v, wi, wo, d, s);
        for (int c = 0; c < 3; c++) {
            double F = f0[c] + (1.0 - f0[c]) * pow(1.0 - c_ih, 5.0);
            double expect = F * D * G2 / (4.0 * wi[2] * wo[2]);
            MR_CHECK_MSG(close_rel(s[c], expect, 1e-10), "roughness %g: %.15g vs %.15g", rough[k], s[c], expect);
        }
    }

    /* the height-correlated G keeps more light than the separable one, and stays below 1 (f0 = 1, white furnace) */
    set_rgb(m, v, "f0", 1.0, 1.0, 1.0);
    set_rgb(m, v, "diffuse", 0.0, 0.0, 0.0);
    for (size_t k = 0; k < sizeof rough / sizeof rough[0]; k++) {
        double sep[3], cor[3], dd[3];
        set_param(m, v, "roughness", rough[k]);
        for (int a = 0; a < 3; a++) {
            double theta = (double)a * 40.0 * PI / 180.0; /* 0, 40, 80 degrees */
            set_param(m, v, "correlated", 0.0);
            furnace(m, v, theta, dd, sep);
            set_param(m, v, "correlated", 1.0);
            furnace(m, v, theta, dd, cor);
            MR_CHECK_MSG(cor[0] >= sep[0] - 1e-9 && cor[0] <= 1.0 + 1e-3, "roughness %g, %g deg: %.4f vs %.4f",
                         rough[k], theta * 180.0 / PI, cor[0], sep[0]);
            if (k == 3 && a == 2)
                printf("      roughness 1 at 80 deg: albedo %.4f separable, %.4f correlated\n", sep[0], cor[0]);
        }
    }
}

/* OpenPBR (openpbr.c). GGX D and the height-correlated V written out here, not taken from brdf_internal.h. */
static double op_test_dv(double alpha, const double wi[3], const double wo[3]) {
    double h[3] = {wi[0] + wo[0], wi[1] + wo[1], wi[2] + wo[2]};
    double len = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]), ch = h[2] / len, a2 = alpha * alpha;
    double dd = 1.0 + (a2 - 1.0) * ch * ch, D = a2 / (PI * dd * dd);
    double nl = wo[2], nv = wi[2];
    double V = 0.5 / (nv * sqrt(a2 + (1.0 - a2) * nl * nl) + nl * sqrt(a2 + (1.0 - a2) * nv * nv));
    return D * V;
}

MR_TEST(known_openpbr) {
    const mr_brdf_model *m = model_named("openpbr");
    if (!m) return;
    double v[MR_BRDF_MAX_VALUES], d[3], s[3];
    const double n[3] = {0.0, 0.0, 1.0};

    /* dielectric F0 at normal incidence: ((ior - 1)/(ior + 1))^2, no diffuse with base_weight 0 */
    mr_brdf_default_values(m, v);
    set_param(m, v, "base_weight", 0.0);
    set_param(m, v, "specular_roughness", 0.5);
    const double iors[] = {1.2, 1.5, 2.4};
    for (int k = 0; k < 3; k++) {
        set_param(m, v, "specular_ior", iors[k]);
        eval_parts(m, v, n, n, d, s);
        double f0 = pow((iors[k] - 1.0) / (iors[k] + 1.0), 2.0), dv = op_test_dv(0.25, n, n);
        MR_CHECK_MSG(close_rel(s[1], f0 * dv, 1e-12) && d[1] == 0.0, "ior %g: %.15g vs %.15g", iors[k], s[1],
                     f0 * dv);
    }

    /* metal F0 = base_color at normal incidence (times Turquin's factor 1 + F0 (1 - E_1)/E_1 of the F = 1 table) */
    mr_brdf_default_values(m, v);
    set_param(m, v, "base_metalness", 1.0);
    set_param(m, v, "specular_roughness", 0.5);
    set_rgb(m, v, "base_color", 0.9, 0.6, 0.3);
    eval_parts(m, v, n, n, d, s);
    const double base[3] = {0.9, 0.6, 0.3};
    for (int c = 0; c < 3; c++) {
        double e1 = mr_ggx_albedo_one(1.0, 0.5), turquin = 1.0 + base[c] * (1.0 - e1) / e1;
        double expect = base[c] * op_test_dv(0.25, n, n) * turquin;
        MR_CHECK_MSG(close_rel(s[c], expect, 1e-12) && d[c] == 0.0, "metal F0 channel %d: %.15g vs %.15g", c, s[c],
                     expect);
    }

    /* F82 tint: at wi.h = 1/7 (h = n, both directions at acos(1/7)) the metal's Fresnel is specular_color times
     * Schlick's value there */
    double mu = 1.0 / 7.0, sn = sqrt(1.0 - mu * mu);
    const double wi82[3] = {sn, 0.0, mu}, wo82[3] = {-sn, 0.0, mu}, tint[3] = {0.5, 0.8, 1.0};
    set_rgb(m, v, "specular_color", tint[0], tint[1], tint[2]);
    eval_parts(m, v, wi82, wo82, d, s);
    for (int c = 0; c < 3; c++) {
        double e1 = mr_ggx_albedo_one(mu, 0.5), turquin = 1.0 + base[c] * (1.0 - e1) / e1;
        double schlick = base[c] + (1.0 - base[c]) * pow(1.0 - mu, 5.0);
        double expect = tint[c] * schlick * op_test_dv(0.25, wi82, wo82) * turquin;
        MR_CHECK_MSG(close_rel(s[c], expect, 1e-12), "F82 channel %d: %.15g vs %.15g", c, s[c], expect);
    }

    /* no specular, no coat, no metal, diffuse roughness 0: Lambert of base_weight base_color (to rounding) */
    mr_brdf_default_values(m, v);
    set_param(m, v, "specular_weight", 0.0);
    set_param(m, v, "base_weight", 0.7);
    set_rgb(m, v, "base_color", 0.9, 0.5, 0.2);
    uint64_t rng = 77;
    int bad = 0;
    for (int k = 0; k < 200; k++) {
        double wi[3], wo[3];
        random_dir(&rng, 0.0, wi);
        random_dir(&rng, 0.0, wo);
        eval_parts(m, v, wi, wo, d, s);
        const double rho[3] = {0.9, 0.5, 0.2};
        for (int c = 0; c < 3; c++)
            if (!close_rel(d[c], 0.7 * rho[c] / PI, 1e-14) || s[c] != 0.0) bad++;
    }
    MR_CHECK_MSG(bad == 0, "%d values differ from Lambert", bad);

    /* white furnace (the quadrature above, independent of the albedo tables): white base_color and specular_color,
     * metal or dielectric, rough or smooth, with and without a coat. Dielectrics are exactly energy preserving by
     * albedo scaling (up to the tables' error); metals by Turquin's factor (up to the same). */
    const double rough[] = {0.1, 0.3, 0.6, 1.0}, angles[] = {0.0, 40.0, 65.0, 80.0};
    double lo = 1e9, hi = 0.0;
    for (int metal = 0; metal < 2; metal++)
        for (int coat = 0; coat < 2; coat++)
            for (int dr = 0; dr < 2; dr++)
                for (size_t r = 0; r < sizeof rough / sizeof rough[0]; r++) {
                    mr_brdf_default_values(m, v);
                    set_rgb(m, v, "base_color", 1.0, 1.0, 1.0);
                    set_param(m, v, "base_metalness", metal);
                    set_param(m, v, "base_diffuse_roughness", dr);
                    set_param(m, v, "specular_roughness", rough[r]);
                    set_param(m, v, "coat_weight", coat);
                    set_param(m, v, "coat_roughness", 0.2);
                    for (size_t a = 0; a < sizeof angles / sizeof angles[0]; a++) {
                        furnace(m, v, angles[a] * PI / 180.0, d, s);
                        double total = d[0] + s[0];
                        lo = fmin(lo, total);
                        hi = fmax(hi, total);
                        MR_CHECK_MSG(total <= 1.005 && total >= 0.995,
                                     "metal %d coat %d sigma %d roughness %g, %g deg: albedo %.4f", metal, coat, dr,
                                     rough[r], angles[a], total);
                    }
                }
    printf("      openpbr white furnace (0-80 deg, roughness 0.1-1, metal/dielectric, coat on/off): %.4f .. %.4f\n",
           lo, hi);
}

/* A model against a reference file: rows of packed values, wi, wo, expected diffuse and specular parts, written by
 * an independent numpy implementation (tests/NAME_reference.py; tests/NAME_reference.sh checks the file is what
 * the script writes). Every value must agree to 1e-6 relative. */
static void check_reference_file(const char *model, const char *file, const char *what) {
    const mr_brdf_model *m = model_named(model);
    if (!m) return;
    const char *root = getenv("MR_ROOT");
    char path[1024];
    snprintf(path, sizeof path, "%s/tests/%s", root ? root : ".", file);
    FILE *f = fopen(path, "r");
    MR_CHECK_MSG(f != NULL, "cannot open %s", path);
    if (!f) return;
    int rows = 0, bad = 0, n = mr_brdf_value_count(m);
    double worst = 0.0;
    for (;;) {
        double v[MR_BRDF_MAX_VALUES], wi[3], wo[3], ed[3], es[3], d[3], s[3];
        int got = 0;
        for (int j = 0; j < n; j++) got += fscanf(f, "%lf", &v[j]) == 1;
        for (int j = 0; j < 3; j++) got += fscanf(f, "%lf", &wi[j]) == 1;
        for (int j = 0; j < 3; j++) got += fscanf(f, "%lf", &wo[j]) == 1;
        for (int j = 0; j < 3; j++) got += fscanf(f, "%lf", &ed[j]) == 1;
        for (int j = 0; j < 3; j++) got += fscanf(f, "%lf", &es[j]) == 1;
        if (got == 0) break;
        MR_CHECK_MSG(got == n + 12, "row %d: %d numbers", rows, got);
        if (got != n + 12) break;
        eval_parts(m, v, wi, wo, d, s);
        for (int c = 0; c < 3; c++) {
            double err_d = fabs(d[c] - ed[c]) / fmax(fabs(ed[c]), 1e-9);
            double err_s = fabs(s[c] - es[c]) / fmax(fabs(es[c]), 1e-9);
            worst = fmax(worst, fmax(err_d, err_s));
            if (err_d > 1e-6 || err_s > 1e-6) {
                if (bad++ < 3)
                    fprintf(stderr, "    row %d channel %d: diffuse %.12g vs %.12g, specular %.12g vs %.12g\n", rows,
                            c, d[c], ed[c], s[c], es[c]);
            }
        }
        rows++;
    }
    fclose(f);
    MR_CHECK(rows >= 40);
    MR_CHECK_MSG(bad == 0, "%d of %d values differ by more than 1e-6 relative", bad, rows * 6);
    printf("      %s vs the numpy reference: %d direction pairs, largest relative difference %.3g\n", what, rows,
           worst);
}

/* openpbr against tests/openpbr_reference.txt: values an independent numpy implementation of the specification's
 * equations wrote (tests/openpbr_reference.py; tests/openpbr_reference.sh checks the file is what it writes). */
MR_TEST(known_openpbr_reference) { check_reference_file("openpbr", "openpbr_reference.txt", "openpbr"); }

/* blender-principled against tests/blender_principled_reference.txt: values a numpy implementation written from
 * the Cycles sources (closure.h, bsdf_microfacet.h, bsdf_util.h) and the model's documented substitutions wrote
 * (tests/blender_principled_reference.py; tests/blender_principled_reference.sh checks the file). */
MR_TEST(known_blender_principled_reference) {
    check_reference_file("blender-principled", "blender_principled_reference.txt", "blender-principled");
}

/* blender-principled (blender_principled.c): F0, the level, F82, Lambert and glTF's metal as special cases, and the
 * white furnace with Multiscatter GGX. */
MR_TEST(known_blender_principled) {
    const mr_brdf_model *m = model_named("blender-principled");
    const mr_brdf_model *gltf = model_named("gltf");
    if (!m || !gltf) return;
    double v[MR_BRDF_MAX_VALUES], d[3], s[3];
    const double n[3] = {0.0, 0.0, 1.0};

    /* single-scatter GGX: dielectric F0 = ((ior - 1)/(ior + 1))^2 2 specular_ior_level, tinted */
    mr_brdf_default_values(m, v);
    set_param(m, v, "multiscatter", 0.0);
    set_rgb(m, v, "base_color", 0.0, 0.0, 0.0);
    set_param(m, v, "roughness", 0.5);
    const double iors[] = {1.3, 1.5, 2.2}, levels[] = {0.5, 0.25, 0.8};
    for (int k = 0; k < 3; k++) {
        set_param(m, v, "ior", iors[k]);
        set_param(m, v, "specular_ior_level", levels[k]);
        set_rgb(m, v, "specular_tint", 1.0, 0.5, 0.25);
        eval_parts(m, v, n, n, d, s);
        double f0 = pow((iors[k] - 1.0) / (iors[k] + 1.0), 2.0) * 2.0 * levels[k], dv = op_test_dv(0.25, n, n);
        const double tint[3] = {1.0, 0.5, 0.25};
        for (int c = 0; c < 3; c++)
            MR_CHECK_MSG(close_rel(s[c], f0 * tint[c] * dv, 1e-12) && d[c] == 0.0, "ior %g level %g: %.15g vs %.15g",
                         iors[k], levels[k], s[c], f0 * tint[c] * dv);
    }

    /* metal: F0 = base_color at normal incidence, specular_tint times Schlick at 1/7 */
    mr_brdf_default_values(m, v);
    set_param(m, v, "multiscatter", 0.0);
    set_param(m, v, "metallic", 1.0);
    set_param(m, v, "roughness", 0.5);
    set_rgb(m, v, "base_color", 0.9, 0.6, 0.3);
    set_rgb(m, v, "specular_tint", 0.5, 0.8, 1.0);
    const double base[3] = {0.9, 0.6, 0.3}, tint[3] = {0.5, 0.8, 1.0};
    eval_parts(m, v, n, n, d, s);
    for (int c = 0; c < 3; c++)
        MR_CHECK_MSG(close_rel(s[c], base[c] * op_test_dv(0.25, n, n), 1e-12), "metal F0 %d: %.15g", c, s[c]);
    double mu = 1.0 / 7.0, sn = sqrt(1.0 - mu * mu);
    const double wi82[3] = {sn, 0.0, mu}, wo82[3] = {-sn, 0.0, mu};
    eval_parts(m, v, wi82, wo82, d, s);
    for (int c = 0; c < 3; c++) {
        double expect = tint[c] * (base[c] + (1.0 - base[c]) * pow(1.0 - mu, 5.0)) * op_test_dv(0.25, wi82, wo82);
        MR_CHECK_MSG(close_rel(s[c], expect, 1e-12), "F82 %d: %.15g vs %.15g", c, s[c], expect);
    }

    /* special cases: no specular layer -> Lambert; a white-tinted single-scatter metal -> gltf's metal */
    double g[MR_BRDF_MAX_VALUES];
    mr_brdf_default_values(gltf, g);
    set_rgb(gltf, g, "base_color", 0.9, 0.6, 0.3);
    set_param(gltf, g, "metallic", 1.0);
    set_param(gltf, g, "roughness", 0.5);
    set_rgb(m, v, "specular_tint", 1.0, 1.0, 1.0);
    double lam[MR_BRDF_MAX_VALUES];
    mr_brdf_default_values(m, lam);
    set_param(m, lam, "specular_ior_level", 0.0);
    set_rgb(m, lam, "base_color", 0.7, 0.5, 0.2);
    uint64_t rng = 91;
    int bad_metal = 0, bad_lambert = 0;
    for (int k = 0; k < 500; k++) {
        double wi[3], wo[3], d2[3], s2[3];
        random_dir(&rng, 0.0, wi);
        random_dir(&rng, 0.0, wo);
        eval_parts(m, v, wi, wo, d, s);
        eval_parts(gltf, g, wi, wo, d2, s2);
        for (int c = 0; c < 3; c++)
            if (!close_rel(s[c], s2[c], 1e-12) || d[c] != 0.0 || d2[c] != 0.0) bad_metal++;
        eval_parts(m, lam, wi, wo, d, s);
        const double rho[3] = {0.7, 0.5, 0.2};
        for (int c = 0; c < 3; c++)
            if (!close_rel(d[c], rho[c] / PI, 1e-14) || s[c] != 0.0) bad_lambert++;
    }
    MR_CHECK_MSG(bad_metal == 0, "%d values differ from gltf's metal", bad_metal);
    MR_CHECK_MSG(bad_lambert == 0, "%d values differ from Lambert", bad_lambert);

    /* white furnace with Multiscatter GGX (the quadrature of this file) */
    const double rough[] = {0.1, 0.3, 0.6, 1.0}, angles[] = {0.0, 40.0, 65.0, 80.0};
    double lo[2] = {1e9, 1e9}, hi[2] = {0.0, 0.0};
    for (int metal = 0; metal < 2; metal++)
        for (int coat = 0; coat < 2; coat++)
            for (size_t r = 0; r < sizeof rough / sizeof rough[0]; r++) {
                mr_brdf_default_values(m, v);
                set_rgb(m, v, "base_color", 1.0, 1.0, 1.0);
                set_param(m, v, "metallic", metal);
                set_param(m, v, "roughness", rough[r]);
                set_param(m, v, "coat_weight", coat);
                set_param(m, v, "coat_roughness", 0.2);
                for (size_t a = 0; a < sizeof angles / sizeof angles[0]; a++) {
                    furnace(m, v, angles[a] * PI / 180.0, d, s);
                    double total = d[0] + s[0];
                    lo[metal] = fmin(lo[metal], total);
                    hi[metal] = fmax(hi[metal], total);
                    MR_CHECK_MSG(total <= 1.005, "metal %d coat %d roughness %g, %g deg: albedo %.4f", metal, coat,
                                 rough[r], angles[a], total);
                }
            }
    printf("      blender-principled white furnace (0-80 deg, roughness 0.1-1, coat on/off): dielectric %.4f .. %.4f, "
           "metal %.4f .. %.4f\n", lo[0], hi[0], lo[1], hi[1]);
    MR_CHECK(lo[1] > 0.99);
}

/* UsdPreviewSurface 2.5 (src/brdf/usd_preview.c), written out here from the specification's words: returns the
 * diffuse and specular parts. p holds the packed values (diffuse_color RGB, use_specular_workflow, specular_color
 * RGB, metallic, roughness, clearcoat, clearcoat_roughness, ior). */
static void usd_preview_reference(const double *p, const double wi[3], const double wo[3], double d[3], double s[3]) {
    double h[3] = {wi[0] + wo[0], wi[1] + wo[1], wi[2] + wo[2]};
    double hl = sqrt(h[0] * h[0] + h[1] * h[1] + h[2] * h[2]);
    double nh = h[2] / hl, ih = (wi[0] * h[0] + wi[1] * h[1] + wi[2] * h[2]) / hl;
    double w = pow(1.0 - ih, 5.0), r2 = pow((1.0 - p[11]) / (1.0 + p[11]), 2.0), m = p[7];
    double S[2];
    for (int k = 0; k < 2; k++) { /* GGX D G2/(4 n.l n.v), height-correlated, alpha = roughness^2 */
        double a = pow(p[k ? 10 : 8], 2.0), a2 = a * a, dd = nh * nh * (a2 - 1.0) + 1.0, D = a2 / (PI * dd * dd);
        double V = 0.5 / (wo[2] * sqrt(a2 + (1 - a2) * wi[2] * wi[2]) + wi[2] * sqrt(a2 + (1 - a2) * wo[2] * wo[2]));
        S[k] = D * V;
    }
    for (int c = 0; c < 3; c++) {
        double f0, f90, weight;
        if (p[3] >= 0.5) {
            f0 = p[4 + c], f90 = 1.0, weight = 1.0;
        } else {
            double k = (1.0 - m) + m * p[c];
            f0 = (1.0 - m) * r2 * k + m * k, f90 = k, weight = 1.0 - m;
        }
        double F = f0 + (f90 - f0) * w;
        d[c] = weight * (1.0 - F) * p[c] / PI;
        s[c] = F * S[0] + p[9] * (r2 + (1.0 - r2) * w) * S[1];
    }
}

MR_TEST(known_usd_preview) {
    const mr_brdf_model *m = model_named("usd-preview"), *gltf = model_named("gltf");
    if (!m || !gltf) return;
    double v[MR_BRDF_MAX_VALUES] = {0}, d[3], s[3], rd[3], rs[3];
    const double base[3] = {0.9, 0.5, 0.1};
    MR_CHECK(mr_brdf_value_count(m) == 12);
    mr_brdf_default_values(m, v);
    set_rgb(m, v, "diffuse_color", 0.9, 0.5, 0.1);
    set_param(m, v, "roughness", 0.4); /* alpha = 0.16: at normal incidence D V = 1/(4 pi alpha^2) */
    const double dv0 = 1.0 / (4.0 * PI * 0.0256);

    /* metallic workflow at normal incidence (w = 0): F0 = k ((1 - m) R2 + m), k = mix(1, diffuse, m) */
    set_param(m, v, "metallic", 0.3);
    eval_parts(m, v, normal, normal, d, s);
    for (int c = 0; c < 3; c++) {
        double k = 0.7 + 0.3 * base[c], f0 = k * (0.7 * 0.04 + 0.3);
        MR_CHECK_MSG(close_rel(s[c], f0 * dv0, 1e-12), "F0 %d: %.17g vs %.17g", c, s[c] / dv0, f0);
        MR_CHECK(close_rel(d[c], 0.7 * (1.0 - f0) * base[c] / PI, 1e-12));
    }
    /* ... metallic 1: F0 = F90 = diffuse_color at every angle, no diffuse part */
    set_param(m, v, "metallic", 1.0);
    double wi[3], wo[3];
    dir_from_angles(1.2, 0.0, wi);
    dir_from_angles(1.3, 2.0, wo);
    eval_parts(m, v, normal, normal, d, s);
    for (int c = 0; c < 3; c++) MR_CHECK(close_rel(s[c], base[c] * dv0, 1e-12) && d[c] == 0.0);
    eval_parts(m, v, wi, wo, d, s);
    usd_preview_reference(v, wi, wo, rd, rs);
    for (int c = 0; c < 3; c++) MR_CHECK(close_rel(s[c], rs[c], 1e-11) && d[c] == 0.0);

    /* specular workflow: F0 = specular_color at normal incidence, F90 = 1; metallic and ior ignored */
    set_param(m, v, "use_specular_workflow", 1.0);
    set_rgb(m, v, "specular_color", 0.05, 0.3, 0.8);
    const double sc[3] = {0.05, 0.3, 0.8};
    eval_parts(m, v, normal, normal, d, s);
    for (int c = 0; c < 3; c++) {
        MR_CHECK_MSG(close_rel(s[c], sc[c] * dv0, 1e-12), "specular F0 %d: %.17g", c, s[c] / dv0);
        MR_CHECK(close_rel(d[c], (1.0 - sc[c]) * base[c] / PI, 1e-12));
    }
    double d2[3], s2[3];
    set_param(m, v, "ior", 2.5);
    eval_parts(m, v, wi, wo, d2, s2);
    eval_parts(m, v, wi, wo, d, s);
    for (int c = 0; c < 3; c++) MR_CHECK(d[c] == d2[c] && s[c] == s2[c]);
    /* ... off normal, against the transcription above */
    usd_preview_reference(v, wi, wo, rd, rs);
    for (int c = 0; c < 3; c++)
        MR_CHECK_MSG(close_rel(d[c], rd[c], 1e-11) && close_rel(s[c], rs[c], 1e-11), "specular wf %d", c);

    /* no Lambert case: with F0 = 0 (ior 1, or specular_color 0) Schlick still gives F = w, so the diffuse is
     * (1 - w) diffuse/pi: exactly diffuse/pi on retro-reflection (wi = wo, w = 0), dimmer elsewhere */
    mr_brdf_default_values(m, v);
    set_rgb(m, v, "diffuse_color", 0.9, 0.5, 0.1);
    set_param(m, v, "ior", 1.0);
    for (int k = 0; k < 5; k++) {
        double dir[3];
        dir_from_angles(0.3 * k, 0.7 * k, dir);
        eval_parts(m, v, dir, dir, d, s);
        /* |wi + wo|/2 may round below 1: w ~ 1e-80 */
        for (int c = 0; c < 3; c++) MR_CHECK(close_rel(d[c], base[c] / PI, 1e-15) && s[c] < 1e-60);
    }
    dir_from_angles(1.4, 0.0, wi); /* mirror pair at 80 degrees: wi.h = cos 80 deg, w = 0.39 */
    dir_from_angles(1.4, PI, wo);
    eval_parts(m, v, wi, wo, d, s);
    usd_preview_reference(v, wi, wo, rd, rs);
    for (int c = 0; c < 3; c++) MR_CHECK(close_rel(d[c], rd[c], 1e-12) && d[c] < 0.7 * base[c] / PI);

    /* metallic workflow, metallic 0, no clearcoat = gltf with metallic 0 at the same ior, any colour and roughness */
    uint64_t rng = 12;
    int compared = 0, differ = 0;
    double worst = 0.0;
    for (int k = 0; k < 400; k++) {
        double g[MR_BRDF_MAX_VALUES] = {0}, dg[3], sg[3];
        mr_brdf_default_values(m, v);
        mr_brdf_default_values(gltf, g);
        double col[3] = {rnd(&rng), rnd(&rng), rnd(&rng)}, rough = 0.01 + 0.99 * rnd(&rng), ior = 1.0 + 2.0 * rnd(&rng);
        set_rgb(m, v, "diffuse_color", col[0], col[1], col[2]);
        set_rgb(gltf, g, "base_color", col[0], col[1], col[2]);
        set_param(m, v, "roughness", rough);
        set_param(gltf, g, "roughness", rough);
        set_param(m, v, "ior", ior);
        set_param(gltf, g, "ior", ior);
        set_param(gltf, g, "metallic", 0.0);
        random_dir(&rng, k < 200 ? 0.02 : 0.0, wi);
        random_dir(&rng, k < 200 ? 0.02 : 0.0, wo);
        eval_parts(m, v, wi, wo, d, s);
        eval_parts(gltf, g, wi, wo, dg, sg);
        for (int c = 0; c < 3; c++) {
            compared += 2;
            worst = fmax(worst, fabs(d[c] - dg[c]) / fmax(dg[c], 1e-300));
            worst = fmax(worst, fabs(s[c] - sg[c]) / fmax(sg[c], 1e-300));
            if (!close_rel(d[c], dg[c], 1e-12) || !close_rel(s[c], sg[c], 1e-12)) differ++;
        }
    }
    MR_CHECK_MSG(differ == 0, "%d of %d values differ from gltf (metallic 0)", differ, compared);
    printf("      usd-preview (metallic 0, clearcoat 0) == gltf (metallic 0, same ior): %d values, worst rel %.2g\n",
           compared, worst);
    /* the core glTF material (no extensions) at any metallic m is the specular workflow exactly: glTF's
     * (1 - m) F_dielectric + m F_metal is Schlick with F0 = mix(0.04, base, m) and F90 = 1, and its diffuse
     * (1 - m) 0.96 (1 - w) base/pi is (1 - F0_c)(1 - w) diffuse_c/pi with diffuse_c = (1 - m) 0.96 base_c/(1 - F0_c),
     * which stays <= 1 */
    differ = 0, compared = 0;
    for (int k = 0; k < 400; k++) {
        double g[MR_BRDF_MAX_VALUES] = {0}, dg[3], sg[3], f0[3], dc[3];
        mr_brdf_default_values(m, v);
        mr_brdf_default_values(gltf, g);
        double col[3] = {rnd(&rng), rnd(&rng), rnd(&rng)}, rough = 0.01 + 0.99 * rnd(&rng), mt = rnd(&rng);
        for (int c = 0; c < 3; c++) {
            f0[c] = (1.0 - mt) * 0.04 + mt * col[c];
            dc[c] = (1.0 - mt) * 0.96 * col[c] / (1.0 - f0[c]);
        }
        set_param(m, v, "use_specular_workflow", 1.0);
        set_rgb(m, v, "specular_color", f0[0], f0[1], f0[2]);
        set_rgb(m, v, "diffuse_color", dc[0], dc[1], dc[2]);
        set_param(m, v, "roughness", rough);
        set_rgb(gltf, g, "base_color", col[0], col[1], col[2]);
        set_param(gltf, g, "metallic", mt);
        set_param(gltf, g, "roughness", rough);
        random_dir(&rng, 0.02, wi);
        random_dir(&rng, 0.02, wo);
        eval_parts(m, v, wi, wo, d, s);
        eval_parts(gltf, g, wi, wo, dg, sg);
        for (int c = 0; c < 3; c++) {
            compared++;
            if (!close_rel(d[c] + s[c], dg[c] + sg[c], 1e-12)) differ++;
        }
    }
    MR_CHECK_MSG(differ == 0, "%d of %d values differ from core gltf (specular workflow)", differ, compared);
    /* ... but not the metallic workflow at metallic 1: gltf's metal has F90 = 1, this one F90 = the albedo */
    {
        double g[MR_BRDF_MAX_VALUES] = {0}, dg[3], sg[3];
        mr_brdf_default_values(m, v);
        mr_brdf_default_values(gltf, g);
        set_rgb(m, v, "diffuse_color", 0.9, 0.5, 0.1);
        set_rgb(gltf, g, "base_color", 0.9, 0.5, 0.1);
        set_param(m, v, "metallic", 1.0);
        set_param(m, v, "roughness", 1.0);
        dir_from_angles(1.4, 0.0, wi);
        dir_from_angles(1.4, PI, wo);
        eval_parts(m, v, wi, wo, d, s);
        eval_parts(gltf, g, wi, wo, dg, sg);
        MR_CHECK(s[2] < 0.5 * sg[2]);
    }

    /* roles in the workflow the generic test (switches at 0) does not visit: specular_color and clearcoat are
     * affine in the specular workflow, diffuse_color is linear there, and quadratic in the metallic one */
    rng = 13;
    int bad = 0, quadratic = 0;
    for (int k = 0; k < 40; k++) {
        double u[MR_BRDF_MAX_VALUES] = {0}, a[6], b[6], mid[6];
        random_values(m, &rng, 0.0, u);
        random_dir(&rng, 0.02, wi);
        random_dir(&rng, 0.02, wo);
        set_param(m, u, "use_specular_workflow", 1.0);
        const char *affine[] = {"specular_color", "clearcoat"};
        for (int i = 0; i < 2; i++) {
            double x[MR_BRDF_MAX_VALUES], y[MR_BRDF_MAX_VALUES], z[MR_BRDF_MAX_VALUES];
            memcpy(x, u, sizeof x), memcpy(y, u, sizeof y), memcpy(z, u, sizeof z);
            set_param(m, x, affine[i], 0.0), set_param(m, y, affine[i], 1.0), set_param(m, z, affine[i], 0.5);
            eval_parts(m, x, wi, wo, a, a + 3);
            eval_parts(m, y, wi, wo, b, b + 3);
            eval_parts(m, z, wi, wo, mid, mid + 3);
            for (int o = 0; o < 6; o++)
                if (!close_rel(mid[o], 0.5 * (a[o] + b[o]), 1e-11)) bad++;
        }
        for (int wf = 0; wf < 2; wf++) {
            double x[MR_BRDF_MAX_VALUES], y[MR_BRDF_MAX_VALUES];
            memcpy(x, u, sizeof x);
            set_param(m, x, "use_specular_workflow", wf);
            memcpy(y, x, sizeof y);
            for (int c = 0; c < 3; c++) y[c] = 0.37 * x[c];
            eval_parts(m, x, wi, wo, a, a + 3), eval_parts(m, y, wi, wo, b, b + 3);
            for (int c = 0; c < 3; c++) {
                int linear = close_rel(b[c], 0.37 * a[c], 1e-12);
                if (wf == 1 && (!linear || b[c + 3] != a[c + 3])) bad++;
                if (wf == 0 && !linear) quadratic++;
            }
        }
    }
    MR_CHECK_MSG(bad == 0, "%d role violations in the specular workflow", bad);
    MR_CHECK_MSG(quadratic > 60, "diffuse_color looked linear in the metallic workflow (%d of 120 not)", quadratic);

    /* white furnace, by the brute-force quadrature above: bounded where the specification conserves energy */
    double fd[3], fs[3];
    mr_brdf_default_values(m, v);
    set_param(m, v, "use_specular_workflow", 1.0);
    set_rgb(m, v, "specular_color", 1.0, 1.0, 1.0); /* F = 1: the GGX lobe's own albedo, no diffuse */
    set_rgb(m, v, "diffuse_color", 1.0, 1.0, 1.0);
    const double angles[] = {0.0, 40.0, 80.0};
    for (int a = 0; a < 3; a++) {
        furnace(m, v, angles[a] * PI / 180.0, fd, fs);
        MR_CHECK_MSG(fd[0] == 0.0 && fs[0] <= 1.0 + 1e-3 && fs[0] > 0.8, "F = 1 at %g deg: %.4f", angles[a], fs[0]);
    }
    mr_brdf_default_values(m, v);
    set_rgb(m, v, "diffuse_color", 1.0, 1.0, 1.0);
    furnace(m, v, 0.0, fd, fs);
    double at0 = fd[0] + fs[0];
    MR_CHECK_MSG(at0 <= 1.0 + 2e-3 && at0 > 0.95, "white, defaults, normal incidence: %.4f", at0);
    set_param(m, v, "roughness", 0.01);
    furnace(m, v, 80.0 * PI / 180.0, fd, fs);
    double smooth80 = fd[0] + fs[0];
    set_param(m, v, "roughness", 0.5);
    set_param(m, v, "clearcoat", 1.0);
    furnace(m, v, 0.0, fd, fs);
    double coat0 = fd[0] + fs[0];
    MR_CHECK(smooth80 > 1.01 && coat0 > at0);
    printf("      usd-preview white furnace: %.4f at 0 deg (defaults, white); %.4f at 80 deg (roughness 0.01); "
           "%.4f at 0 deg with clearcoat 1\n", at0, smooth80, coat0);
}

/* The model against tests/usd_preview_reference.py, an independent numpy transcription of the specification: every
 * value to 1e-6 relative. Runs Debian's python3 (python3-numpy, scripts/install-deps.sh). */
MR_TEST(known_usd_preview_matches_python) {
    const mr_brdf_model *m = model_named("usd-preview");
    if (!m) return;
    const char *root = getenv("MR_ROOT");
    char cmd[4096];
    const char *python = access("/usr/bin/python3", X_OK) == 0 ? "/usr/bin/python3" : "python3";
    snprintf(cmd, sizeof cmd, "%s '%s/tests/usd_preview_reference.py'", python, root ? root : ".");
    FILE *pipe = popen(cmd, "r");
    MR_CHECK_MSG(pipe != NULL, "cannot run %s", cmd);
    if (!pipe) return;
    int lines = 0, bad = 0;
    double worst = 0.0, x[24];
    for (;;) {
        int n = 0;
        while (n < 24 && fscanf(pipe, "%lf", &x[n]) == 1) n++;
        if (n < 24) break;
        double d[3], s[3];
        eval_parts(m, x, x + 12, x + 15, d, s);
        for (int c = 0; c < 3; c++) {
            double pd = x[18 + c], ps = x[21 + c];
            worst = fmax(worst, fabs(d[c] - pd) / fmax(fabs(pd), 1e-300));
            worst = fmax(worst, fabs(s[c] - ps) / fmax(fabs(ps), 1e-300));
            if (!close_rel(d[c], pd, 1e-6) || !close_rel(s[c], ps, 1e-6)) {
                if (bad++ < 3)
                    fprintf(stderr, "    line %d channel %d: diffuse %.12g vs %.12g, specular %.12g vs %.12g\n",
                            lines + 1, c, d[c], pd, s[c], ps);
            }
        }
        lines++;
    }
    int status = pclose(pipe);
    MR_CHECK_MSG(status == 0, "%s exited with %d (needs python3-numpy)", cmd, status);
    MR_CHECK_MSG(lines >= 40, "%d lines read from the Python reference", lines);
    MR_CHECK_MSG(bad == 0, "%d of %d values differ from the Python reference", bad, 6 * lines);
    printf("      usd-preview vs tests/usd_preview_reference.py: %d direction pairs x 6 values, worst rel %.2g\n",
           lines, worst);
}

/* standard-surface (Autodesk Standard Surface 1.0.1): the spec's special cases, Gulbrandsen's round trip, the
 * Lambert reduction, the white furnace with base_color 1 (its albedo table's accuracy shows as |albedo - 1|), and
 * the non-reciprocity the spec accepts. The Python cross-check is tests/standard_surface_reference.sh. */
MR_TEST(known_standard_surface) {
    const mr_brdf_model *m = model_named("standard-surface"), *lambert = model_named("lambert");
    if (!m || !lambert) return;
    double v[MR_BRDF_MAX_VALUES], d[3], s[3];
    const double alpha = 0.09; /* specular_roughness 0.3 */
    const double lobe0 = 1.0 / (4.0 * PI * alpha * alpha); /* D V at normal incidence: 1/(pi a^2) x 1/4 */

    /* dielectric F0 = ((ior - 1)/(ior + 1))^2 specular specular_color ("Specular reflection"); base 0: no diffuse */
    const double sc[3] = {0.9, 0.5, 0.2}, iors[] = {1.3, 1.5, 2.4};
    for (size_t k = 0; k < sizeof iors / sizeof iors[0]; k++) {
        mr_brdf_default_values(m, v);
        set_param(m, v, "base", 0.0);
        set_param(m, v, "specular", 0.7);
        set_rgb(m, v, "specular_color", sc[0], sc[1], sc[2]);
        set_param(m, v, "specular_roughness", 0.3);
        set_param(m, v, "specular_ior", iors[k]);
        eval_parts(m, v, normal, normal, d, s);
        double f0 = (iors[k] - 1.0) * (iors[k] - 1.0) / ((iors[k] + 1.0) * (iors[k] + 1.0));
        for (int c = 0; c < 3; c++) {
            MR_CHECK_MSG(close_rel(s[c], f0 * 0.7 * sc[c] * lobe0, 1e-12), "ior %g: %.17g", iors[k], s[c]);
            MR_CHECK(d[c] == 0.0);
        }
    }

    /* metal at normal incidence reflects base base_color, whatever the edge tint ("Metal", Gulbrandsen) */
    const double bc[3] = {0.9, 0.6, 0.3};
    mr_brdf_default_values(m, v);
    set_param(m, v, "metalness", 1.0);
    set_param(m, v, "base", 0.9);
    set_rgb(m, v, "base_color", bc[0], bc[1], bc[2]);
    set_param(m, v, "specular", 0.8);
    set_rgb(m, v, "specular_color", 0.5, 1.0, 0.2);
    set_param(m, v, "specular_roughness", 0.3);
    eval_parts(m, v, normal, normal, d, s);
    for (int c = 0; c < 3; c++) {
        MR_CHECK_MSG(close_rel(s[c], 0.9 * bc[c] * lobe0, 1e-9), "channel %d: %.17g", c, s[c] / lobe0);
        MR_CHECK(d[c] == 0.0);
    }

    /* Gulbrandsen's (r, g) -> (n, k) -> normal-incidence reflectance, both by the closed form and by the exact
     * conductor Fresnel; r = 1 is clamped to 1 - 1e-9. Above r = 1 - 1e-6 with g near 1 (n ~ (1 - r)/2, k ~ 1)
     * mr_fresnel_conductor's a = sqrt((A + t)/2) cancels (A + t ~ 2 n^2 k^2 next to 1): 1e-8 at r = 1 - 1e-8. */
    const double rs[] = {0.0, 1e-6, 0.01, 0.04, 0.3, 0.5, 0.9, 0.99, 0.999999, 0.99999999, 1.0};
    const double gs[] = {0.0, 0.3, 0.7, 1.0};
    double worst = 0.0;
    for (size_t i = 0; i < sizeof rs / sizeof rs[0]; i++)
        for (size_t j = 0; j < sizeof gs / sizeof gs[0]; j++) {
            double n, k;
            mr_artistic_ior(rs[i], gs[j], &n, &k);
            double closed = ((n - 1.0) * (n - 1.0) + k * k) / ((n + 1.0) * (n + 1.0) + k * k);
            double exact = mr_fresnel_conductor(1.0, n, k, NULL, NULL), want = fmin(rs[i], MR_ARTISTIC_R_MAX);
            if (rs[i] <= 0.999999) worst = fmax(worst, fmax(fabs(closed - want), fabs(exact - want)));
            MR_CHECK_MSG(fabs(closed - want) <= 1e-12 && fabs(exact - want) <= (rs[i] <= 0.999999 ? 1e-9 : 2e-8),
                         "r %g g %g: n %g k %g -> %.12g, %.12g", rs[i], gs[j], n, k, closed, exact);
        }
    /* the edge tint raises the grazing reflectance (g = 1: towards white at grazing) */
    double n0, k0, n1, k1;
    mr_artistic_ior(0.5, 0.0, &n0, &k0);
    mr_artistic_ior(0.5, 1.0, &n1, &k1);
    double graze = cos(80.0 * PI / 180.0);
    MR_CHECK(mr_fresnel_conductor(graze, n1, k1, NULL, NULL) > mr_fresnel_conductor(graze, n0, k0, NULL, NULL));
    printf("      artistic IOR round trip: worst |R(n, k) - r| = %.2g for r <= 1 - 1e-6 (%zu (r, g) pairs in all)\n",
           worst, sizeof rs / sizeof rs[0] * (sizeof gs / sizeof gs[0]));

    /* diffuse_roughness 0, specular 0, coat 0, metalness 0: Lambert with albedo base base_color, exactly */
    uint64_t rng = 29;
    double lv[MR_BRDF_MAX_VALUES] = {0};
    mr_brdf_default_values(m, v);
    set_param(m, v, "base", 0.8);
    set_rgb(m, v, "base_color", 0.3, 0.6, 0.9);
    set_param(m, v, "specular", 0.0);
    set_rgb(lambert, lv, "albedo", 0.8 * 0.3, 0.8 * 0.6, 0.8 * 0.9);
    int differ = 0;
    for (int k = 0; k < 500; k++) {
        double wi[3], wo[3], dl[3], sl[3];
        random_dir(&rng, k < 400 ? 0.01 : 0.0, wi);
        random_dir(&rng, k < 400 ? 0.01 : 0.0, wo);
        eval_parts(m, v, wi, wo, d, s);
        eval_parts(lambert, lv, wi, wo, dl, sl);
        for (int c = 0; c < 3; c++) differ += d[c] != dl[c] || s[c] != 0.0;
    }
    MR_CHECK_MSG(differ == 0, "%d values differ from lambert", differ);

    /* reciprocal without the albedo weights (specular 0, coat 0), not with them (the spec's "Reciprocity") */
    double wi[3], wo[3], d2[3], s2[3];
    dir_from_angles(1.2, 0.0, wi);
    dir_from_angles(0.3, 2.0, wo);
    set_param(m, v, "metalness", 0.5);
    set_param(m, v, "diffuse_roughness", 0.6);
    eval_parts(m, v, wi, wo, d, s);
    eval_parts(m, v, wo, wi, d2, s2);
    for (int c = 0; c < 3; c++) MR_CHECK(close_rel(d[c], d2[c], 1e-12) && close_rel(s[c], s2[c], 1e-12));
    mr_brdf_default_values(m, v);
    eval_parts(m, v, wi, wo, d, s);
    eval_parts(m, v, wo, wi, d2, s2);
    MR_CHECK_MSG(!close_rel(d[0], d2[0], 1e-3), "defaults: diffuse %.9g vs %.9g", d[0], d2[0]);

    /* the slice prepare stores (mr_ggx_albedo_slice_init) finishes at eval to the shared table's trilinear lookup
     * (mr_ggx_albedo_dielectric, what openpbr and blender-principled call) bit for bit, and the derivatives' lookup
     * (mr_ggx_albedo_dielectric_grad) gives the same value */
    uint64_t arng = 5;
    int slice_differs = 0;
    for (int k = 0; k < 300; k++) {
        double r = 0.01 + 0.99 * rnd(&arng), eta = 1.0 + 2.0 * rnd(&arng), mu = rnd(&arng), dr, deps;
        double eps = (eta - 1.0) / (eta + 1.0), direct = mr_ggx_albedo_dielectric(mu, r, eps);
        mr_ggx_albedo_slice slice;
        mr_ggx_albedo_slice_init(r, eps, &slice);
        if (mr_ggx_albedo_slice_at(&slice, mu) != direct || mr_ggx_albedo_dielectric_grad(mu, r, eps, &dr, &deps) !=
                                                                  direct)
            slice_differs++;
    }
    MR_CHECK_MSG(slice_differs == 0, "albedo slice or gradient lookup vs trilinear lookup: %d of 300 differ",
                 slice_differs);

    /* White furnace, base_color 1 (base 1): a dielectric over Lambert reflects E_s + (1 - E_s) = 1 exactly, so
     * |albedo - 1| is the albedo table's error (plus the quadrature's, ~1e-3 towards grazing). Over ior x
     * roughness x angle. */
    const double t_ior[] = {1.05, 1.3, 1.5, 2.2, 3.0}, t_rough[] = {0.01, 0.1, 0.3, 0.6, 1.0};
    const double t_angle[] = {0.0, 40.0, 65.0, 80.0, 88.0};
    double worst_all = 0.0, worst_80 = 0.0;
    for (size_t a = 0; a < sizeof t_ior / sizeof t_ior[0]; a++)
        for (size_t b = 0; b < sizeof t_rough / sizeof t_rough[0]; b++)
            for (size_t c = 0; c < sizeof t_angle / sizeof t_angle[0]; c++) {
                mr_brdf_default_values(m, v);
                set_rgb(m, v, "base_color", 1.0, 1.0, 1.0);
                set_param(m, v, "specular_ior", t_ior[a]);
                set_param(m, v, "specular_roughness", t_rough[b]);
                furnace(m, v, t_angle[c] * PI / 180.0, d, s);
                double err = fabs(d[0] + s[0] - 1.0);
                worst_all = fmax(worst_all, err);
                if (t_angle[c] <= 80.0) worst_80 = fmax(worst_80, err);
            }
    MR_CHECK_MSG(worst_all <= 0.01, "dielectric over Lambert: |albedo - 1| up to %.4f", worst_all);
    printf("      white furnace, dielectric over white Lambert: |albedo - 1| <= %.4f (<= %.4f up to 80 deg) over "
           "ior 1.05-3, roughness 0.01-1\n", worst_all, worst_80);

    /* other white configurations: coat over it, a white metal, rough Oren-Nayar; all at most 1 (+1e-2) */
    static const struct {
        const char *label, *assignments[6];
    } white[] = {
        {"coat 1 over defaults", {"base_color=1", "coat=1", "coat_roughness=0.1", NULL}},
        {"coat 1, rough, coat_ior 2.5", {"base_color=1", "coat=1", "coat_roughness=0.7", "coat_ior=2.5", NULL}},
        {"white metal, roughness 0.2", {"base_color=1", "metalness=1", NULL}},
        {"white metal, roughness 1", {"base_color=1", "metalness=1", "specular_roughness=1", NULL}},
        {"Oren-Nayar sigma 1", {"base_color=1", "diffuse_roughness=1", "specular=0", NULL}},
    };
    for (size_t k = 0; k < sizeof white / sizeof white[0]; k++) {
        mr_brdf_default_values(m, v);
        for (int j = 0; white[k].assignments[j]; j++)
            MR_CHECK_OK(mr_brdf_parse_assignment(m, white[k].assignments[j], v));
        double lo = 2.0, hi = 0.0;
        for (size_t c = 0; c < sizeof t_angle / sizeof t_angle[0]; c++) {
            furnace(m, v, t_angle[c] * PI / 180.0, d, s);
            lo = fmin(lo, d[0] + s[0]);
            hi = fmax(hi, d[0] + s[0]);
        }
        MR_CHECK_MSG(hi <= 1.01, "%s: albedo up to %.4f", white[k].label, hi);
        printf("      white furnace, %-28s albedo %.4f .. %.4f (0-88 deg)\n", white[k].label, lo, hi);
    }
}

MR_TEST_MAIN(MR_TEST_ENTRY(registry_tables_are_consistent), MR_TEST_ENTRY(map_encodings_follow_one_rule),
             MR_TEST_ENTRY(find_unknown_lists_valid_names),
             MR_TEST_ENTRY(default_values_use_per_channel_defaults),
             MR_TEST_ENTRY(parse_assignment_accepts_and_rejects),
             MR_TEST_ENTRY(random_values_are_finite_and_nonnegative), MR_TEST_ENTRY(reciprocity),
             MR_TEST_ENTRY(below_horizon_is_exactly_zero), MR_TEST_ENTRY(robust_at_bounds_grazing_and_nonfinite_inputs),
             MR_TEST_ENTRY(white_furnace_quadrature_is_accurate), MR_TEST_ENTRY(white_furnace_energy_bound),
             MR_TEST_ENTRY(gradient_matches_central_differences),
             MR_TEST_ENTRY(gradient_at_defaults_matches_one_sided_differences),
             MR_TEST_ENTRY(gradient_is_the_secant_where_affine),
             MR_TEST_ENTRY(prepared_gradient_equals_eval_grad_for_any_slots),
             MR_TEST_ENTRY(gradient_is_finite_at_the_ends_of_the_ranges), MR_TEST_ENTRY(roles_are_truthful),
             MR_TEST_ENTRY(linear_and_affine_parameters_are_jointly_affine), MR_TEST_ENTRY(lobes_are_truthful),
             MR_TEST_ENTRY(known_lambert), MR_TEST_ENTRY(known_microfacet_normal_incidence),
             MR_TEST_ENTRY(known_microfacet_off_normal), MR_TEST_ENTRY(known_conductor_fresnel),
             MR_TEST_ENTRY(known_plastic), MR_TEST_ENTRY(known_ward_variants), MR_TEST_ENTRY(known_trimming),
             MR_TEST_ENTRY(known_phong), MR_TEST_ENTRY(known_blender_ward), MR_TEST_ENTRY(known_gltf),
             MR_TEST_ENTRY(known_gltf_specgloss), MR_TEST_ENTRY(known_cycles_principled),
             MR_TEST_ENTRY(known_cycles_ggx), MR_TEST_ENTRY(known_openpbr),
             MR_TEST_ENTRY(known_openpbr_reference),
             MR_TEST_ENTRY(known_blender_principled),
             MR_TEST_ENTRY(known_blender_principled_reference),
             MR_TEST_ENTRY(known_usd_preview), MR_TEST_ENTRY(known_usd_preview_matches_python),
             MR_TEST_ENTRY(known_standard_surface))
