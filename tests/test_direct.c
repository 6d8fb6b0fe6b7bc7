/*
 * test_direct.c — the direct remap of texels (src/remap/direct.h): the documented quantisation (sRGB steps for
 * colours, log steps for roughness, exact switches, a fixed point, 8-bit sRGB texels kept at t = 1/255);
 * duplicated texels sharing one answer; cold answers bit-identical to mr_remap of the quantised value and warm
 * ones within the stated tolerance of it; the same bits for 1 and 2 threads; the cache's round trip (a second run
 * all hits, the same bits), its growth, its torn last line, and foreign, corrupt and locked caches refused
 * untouched; bad input. Small fit scenes (32^2) and a few dozen unique values keep it to seconds.
 */
#include <fcntl.h>
#include <signal.h>
#include <stdint.h>
#include <sys/wait.h>
#include <unistd.h>

#include "harness.h"
#include "matremap.h"
#include "remap/direct.h"

#define FIT_SIZE 32
#define STEP (2.0 / 255.0)
/* How close a warm-started answer stays to the full remap of the same value (direct.h): alpha relative,
 * reflectances absolute. The bench measures ~2e-4 at most on real texture sets at 64^2. */
#define WARM_TOLERANCE 2e-3

static const mr_brdf_model *model(const char *name) {
    const mr_brdf_model *m = mr_brdf_find(name);
    if (m == NULL) {
        fprintf(stderr, "no model %s\n", name);
        exit(2);
    }
    return m;
}

static void set(const mr_brdf_model *m, double *values, const char *name, const double *v) {
    const int p = mr_brdf_param_index(m, name), offset = mr_brdf_param_offset(m, p);
    for (int c = 0; c < m->params[p].channels; c++) values[offset + c] = v[c];
}

static double srgb_encode(double v) { return v <= 0.0031308 ? 12.92 * v : 1.055 * pow(v, 1.0 / 2.4) - 0.055; }
static double srgb_decode(double e) { return e <= 0.04045 ? e / 12.92 : pow((e + 0.055) / 1.055, 2.4); }

/* A small GGX texture: 6 roughnesses x 4 colours, each texel twice (once shifted by a tenth of a step, which
 * quantises to the same value), 48 texels, 24 unique values. */
#define TEXELS 48
static void ggx_texture(double *values) {
    const mr_brdf_model *ggx = model("ggx");
    const int nv = mr_brdf_value_count(ggx);
    for (int i = 0; i < TEXELS / 2; i++) {
        double *v = values + (size_t)i * (size_t)nv, *twin = values + (size_t)(i + TEXELS / 2) * (size_t)nv;
        const int a = i % 6, c = i / 6;
        const double alpha[1] = {0.06 * pow(1.25, a)};
        const double f0[3] = {0.03 + 0.02 * c, 0.04 + 0.01 * c, 0.05};
        const double diffuse[3] = {0.2 + 0.1 * c, 0.3, 0.4 - 0.05 * c};
        mr_brdf_default_values(ggx, v);
        set(ggx, v, "alpha", alpha);
        set(ggx, v, "f0", f0);
        set(ggx, v, "diffuse", diffuse);
        double q[MR_BRDF_MAX_VALUES];
        MR_CHECK_OK(mr_direct_quantise(ggx, STEP, v, q));
        memcpy(v, q, (size_t)nv * sizeof *v); // on the grid, so that the shifted twin stays in its cell
        memcpy(twin, v, (size_t)nv * sizeof *v);
        const int d = mr_brdf_param_offset(ggx, mr_brdf_param_index(ggx, "diffuse"));
        twin[d] = srgb_decode(srgb_encode(twin[d]) + 0.1 * STEP);
    }
}

static mr_direct_options options(void) {
    mr_direct_options o;
    memset(&o, 0, sizeof o);
    o.tolerance = STEP;
    o.scene.size = FIT_SIZE;
    o.threads = 1;
    return o;
}

static mr_render_plan *fit_plan(void) {
    mr_scene scene = mr_scene_fit(&(mr_fit_scene_options){FIT_SIZE, MR_FIT_LIGHT_45, 0});
    mr_render_plan *plan = NULL;
    MR_CHECK_OK(mr_render_plan_create(&scene, &plan));
    return plan;
}

/* What most cases use: the models (ggx -> ward-balanced), the texture, two answer sets and default options. */
typedef struct fixture {
    const mr_brdf_model *ggx, *ward;
    int ns, nt;
    double in[TEXELS * MR_BRDF_MAX_VALUES], a[TEXELS * MR_BRDF_MAX_VALUES], b[TEXELS * MR_BRDF_MAX_VALUES];
    mr_fit_outcome oa[TEXELS], ob[TEXELS];
    mr_direct_options o;
    mr_direct_summary sa, sb;
} fixture;

static fixture *fixture_new(void) {
    static fixture f;
    memset(&f, 0, sizeof f);
    f.ggx = model("ggx");
    f.ward = model("ward-balanced");
    f.ns = mr_brdf_value_count(f.ggx);
    f.nt = mr_brdf_value_count(f.ward);
    ggx_texture(f.in);
    f.o = options();
    return &f;
}

/* The largest difference between two target vectors: log-scale parameters relative, the others absolute. */
static double largest_difference(const mr_brdf_model *m, const double *a, const double *b) {
    double worst = 0.0;
    for (int i = 0, slot = 0; i < m->param_count; slot += m->params[i].channels, i++)
        for (int c = 0; c < m->params[i].channels; c++) {
            const double x = a[slot + c], y = b[slot + c];
            worst = fmax(worst, (m->params[i].flags & MR_PARAM_LOG_SCALE) ? fabs(x - y) / y : fabs(x - y));
        }
    return worst;
}

MR_TEST(quantisation_is_the_documented_one) {
    const mr_brdf_model *ggx = model("ggx"), *ward = model("ward"), *gltf = model("gltf");
    double v[MR_BRDF_MAX_VALUES], q[MR_BRDF_MAX_VALUES], again[MR_BRDF_MAX_VALUES];
    const double t = 1.0 / 255.0;
    mr_brdf_default_values(ggx, v);
    set(ggx, v, "alpha", (double[]){0.1});
    set(ggx, v, "f0", (double[]){0.04, 0.5, 1.0});
    set(ggx, v, "diffuse", (double[]){0.0, 0.2, 0.8});
    MR_CHECK_OK(mr_direct_quantise(ggx, t, v, q));
    MR_CHECK(q[0] == exp(t * nearbyint(log(0.1) / t)));
    for (int c = 0; c < 3; c++) {
        MR_CHECK_NEAR(q[1 + c], srgb_decode(t * nearbyint(srgb_encode(v[1 + c]) / t)), 1e-15);
        MR_CHECK_NEAR(q[4 + c], srgb_decode(t * nearbyint(srgb_encode(v[4 + c]) / t)), 1e-15);
    }
    MR_CHECK(q[3] == 1.0 && q[4] == 0.0);
    MR_CHECK_OK(mr_direct_quantise(ggx, t, q, again)); // a fixed point, bit for bit
    MR_CHECK(memcmp(q, again, (size_t)mr_brdf_value_count(ggx) * sizeof *q) == 0);
    // Every 8-bit sRGB code survives t = 1/255 (a texel read from a PNG as a float).
    int kept = 1;
    for (int code = 0; code < 256; code++) {
        for (int c = 0; c < 3; c++) v[1 + c] = (float)srgb_decode(code / 255.0);
        MR_CHECK_OK(mr_direct_quantise(ggx, t, v, q));
        kept &= fabs(srgb_encode(q[1]) * 255.0 - code) < 1e-9;
    }
    MR_CHECK(kept);
    // Out of range: clamped first (alpha 0 -> its floor 1e-4, F0 1.5 -> 1), then quantised and clamped again.
    set(ggx, v, "alpha", (double[]){0.0});
    set(ggx, v, "f0", (double[]){1.5, -0.2, 0.5});
    MR_CHECK_OK(mr_direct_quantise(ggx, t, v, q));
    MR_CHECK(q[0] >= 1e-4 && q[0] < 1e-4 * (1.0 + 2.0 * t) && q[1] == 1.0 && q[2] == 0.0);
    // Switches exactly; other scalars in linear steps of t (glTF metallic, roughness).
    mr_brdf_default_values(ward, v);
    MR_CHECK_OK(mr_direct_quantise(ward, 0.1, v, q));
    MR_CHECK(q[mr_brdf_value_count(ward) - 1] == 1.0);
    mr_brdf_default_values(gltf, v);
    set(gltf, v, "metallic", (double[]){0.33});
    MR_CHECK_OK(mr_direct_quantise(gltf, 0.1, v, q));
    const int metallic = mr_brdf_param_offset(gltf, mr_brdf_param_index(gltf, "metallic"));
    MR_CHECK(q[metallic] == 3 * 0.1);
    // Errors name the value.
    mr_brdf_default_values(ggx, v);
    v[2] = NAN;
    MR_CHECK(mr_direct_quantise(ggx, t, v, q) == MR_ERR_INVALID_ARG && strstr(mr_last_error(), "f0[1]") != NULL);
    MR_CHECK(mr_direct_quantise(ggx, 2.0, q, q) == MR_ERR_INVALID_ARG && strstr(mr_last_error(), "tolerance 2"));
    MR_CHECK(mr_direct_quantise(ggx, -1.0, q, q) == MR_ERR_INVALID_ARG);
    MR_CHECK(mr_direct_quantise(NULL, t, q, q) == MR_ERR_INVALID_ARG);
    mr_brdf_default_values(ggx, v);
    MR_CHECK_OK(mr_direct_quantise(ggx, 0.0, v, q)); // 0: the default step
    MR_CHECK(q[0] == exp(MR_DIRECT_DEFAULT_TOLERANCE * nearbyint(log(0.1) / MR_DIRECT_DEFAULT_TOLERANCE)));
}

MR_TEST(duplicated_texels_share_one_answer) {
    fixture *f = fixture_new();
    const mr_direct_summary *s = &f->sa;
    MR_CHECK_OK(mr_direct_remap(f->ggx, f->ward, f->in, TEXELS, &f->o, f->a, f->oa, &f->sa));
    MR_CHECK(s->texels == TEXELS && s->unique == TEXELS / 2 && s->clamped == 0 && s->cache_hits == 0);
    MR_CHECK(s->full + s->warm == s->unique && s->remaps == s->full + s->warm + s->fallbacks && s->threads == 1);
    size_t by_outcome = 0;
    for (int k = 0; k < MR_FIT_OUTCOME_COUNT; k++) by_outcome += s->outcomes[k];
    MR_CHECK(by_outcome == s->unique && s->renders > 0 && s->seconds > 0.0);
    const size_t row = (size_t)f->nt * sizeof f->a[0];
    for (int i = 0; i < TEXELS / 2; i++) {
        const int j = i + TEXELS / 2;
        MR_CHECK_MSG(memcmp(f->a + (size_t)i * (size_t)f->nt, f->a + (size_t)j * (size_t)f->nt, row) == 0,
                     "texels %d and %d quantise alike but got different answers", i, j);
        MR_CHECK(f->oa[i] == f->oa[j]);
    }
}

MR_TEST(cold_answers_are_mr_remap_of_the_quantised_value_bit_for_bit) {
    fixture *f = fixture_new();
    f->o.cold = 1;
    MR_CHECK_OK(mr_direct_remap(f->ggx, f->ward, f->in, TEXELS, &f->o, f->a, f->oa, &f->sa));
    MR_CHECK(f->sa.full == f->sa.unique && f->sa.warm == 0 && f->sa.fallbacks == 0);
    mr_render_plan *plan = fit_plan();
    for (int i = 0; i < TEXELS; i += 5) {
        double q[MR_BRDF_MAX_VALUES];
        MR_CHECK_OK(mr_direct_quantise(f->ggx, STEP, f->in + (size_t)i * (size_t)f->ns, q));
        mr_remap_options ro = mr_remap_options_default();
        mr_remap_result r;
        MR_CHECK_OK(mr_remap(plan, f->ggx, q, f->ward, &ro, &r));
        MR_CHECK_MSG(memcmp(r.values, f->a + (size_t)i * (size_t)f->nt, (size_t)f->nt * sizeof r.values[0]) == 0,
                     "texel %d: the cold answer is not mr_remap's", i);
        MR_CHECK(r.outcome == f->oa[i]);
    }
    mr_render_plan_free(plan);
}

MR_TEST(warm_answers_stay_within_the_stated_tolerance_of_full_remaps) {
    // At 32^2 the texture's two smallest roughnesses are under-resolved: they are warm-started and kept like
    // converged ones (direct.h), with the full remap's outcome and answers as close to it.
    fixture *f = fixture_new();
    const mr_direct_summary *s = &f->sa;
    MR_CHECK_OK(mr_direct_remap(f->ggx, f->ward, f->in, TEXELS, &f->o, f->a, f->oa, &f->sa));
    MR_CHECK_MSG(s->warm >= s->unique / 2, "only %zu of %zu values were warm-started", s->warm, s->unique);
    MR_CHECK(s->full >= 1 && s->outcomes[MR_FIT_UNDER_RESOLVED] >= 2);
    MR_CHECK_MSG(s->full + s->fallbacks < 1 + s->outcomes[MR_FIT_UNDER_RESOLVED],
                 "%zu full remaps and %zu fallbacks for %zu under-resolved values: they were not kept warm", s->full,
                 s->fallbacks, s->outcomes[MR_FIT_UNDER_RESOLVED]);
    f->o.cold = 1;
    MR_CHECK_OK(mr_direct_remap(f->ggx, f->ward, f->in, TEXELS, &f->o, f->b, f->ob, NULL));
    double worst = 0.0;
    for (int i = 0; i < TEXELS; i++) {
        const size_t at = (size_t)i * (size_t)f->nt;
        worst = fmax(worst, largest_difference(f->ward, f->a + at, f->b + at));
        MR_CHECK(f->oa[i] == f->ob[i]);
    }
    MR_CHECK_MSG(worst <= WARM_TOLERANCE, "warm answers differ from full remaps by up to %g", worst);
    printf("    warm against full remaps: %zu warm, %zu full, %zu fallbacks; largest difference %.2g\n", s->warm,
           s->full, s->fallbacks, worst);
}

MR_TEST(a_warm_start_refines_locally_from_initial_values) {
    // remap.h, initial_values: AUTO refines from the start only; from the full fit's own answer it stays there.
    const mr_brdf_model *ggx = model("ggx"), *ward = model("ward-balanced");
    double v[MR_BRDF_MAX_VALUES];
    mr_brdf_default_values(ggx, v);
    set(ggx, v, "alpha", (double[]){0.15});
    set(ggx, v, "f0", (double[]){0.05, 0.05, 0.05});
    set(ggx, v, "diffuse", (double[]){0.3, 0.2, 0.1});
    mr_render_plan *plan = fit_plan();
    mr_remap_options o = mr_remap_options_default();
    mr_remap_result full, warm, far;
    MR_CHECK_OK(mr_remap(plan, ggx, v, ward, &o, &full));
    o.initial_values = full.values;
    MR_CHECK_OK(mr_remap(plan, ggx, v, ward, &o, &warm));
    MR_CHECK(largest_difference(ward, warm.values, full.values) < 1e-4);
    MR_CHECK(warm.renders < full.renders && warm.outcome == full.outcome);
    // From a start two-fold off in alpha it still finds the same minimum (one basin).
    double start[MR_BRDF_MAX_VALUES];
    memcpy(start, full.values, sizeof start);
    start[mr_brdf_param_offset(ward, mr_brdf_param_index(ward, "alpha"))] *= 2.0;
    o.initial_values = start;
    MR_CHECK_OK(mr_remap(plan, ggx, v, ward, &o, &far));
    MR_CHECK(largest_difference(ward, far.values, full.values) < 1e-3);
    mr_render_plan_free(plan);
}

MR_TEST(one_and_two_threads_give_the_same_bits) {
    fixture *f = fixture_new();
    f->o.chain_length = 5; // five chains
    MR_CHECK_OK(mr_direct_remap(f->ggx, f->ward, f->in, TEXELS, &f->o, f->a, f->oa, &f->sa));
    f->o.threads = 2;
    MR_CHECK_OK(mr_direct_remap(f->ggx, f->ward, f->in, TEXELS, &f->o, f->b, f->ob, &f->sb));
    MR_CHECK(memcmp(f->a, f->b, sizeof f->a) == 0 && memcmp(f->oa, f->ob, sizeof f->oa) == 0);
    const mr_direct_summary *sa = &f->sa, *sb = &f->sb;
    MR_CHECK(sa->full == sb->full && sa->warm == sb->warm && sa->fallbacks == sb->fallbacks);
    MR_CHECK(sa->renders == sb->renders && sa->threads == 1 && sb->threads == 2 && sa->full >= 5);
    // Never more threads than chains with work: one chain, one thread.
    f->o.chain_length = 1000;
    MR_CHECK_OK(mr_direct_remap(f->ggx, f->ward, f->in, TEXELS, &f->o, f->b, f->ob, &f->sb));
    MR_CHECK(f->sb.threads == 1);
}

typedef struct progress_log {
    int calls, monotonic;
    size_t last, total, hits;
} progress_log;

static void on_progress(const mr_direct_progress *p, void *user) {
    progress_log *log = user;
    log->monotonic &= p->done > log->last || log->calls == 0;
    log->last = p->done;
    log->total = p->total;
    log->hits = p->cache_hits;
    log->calls++;
}

MR_TEST(the_cache_round_trips_grows_and_survives_a_torn_line) {
    fixture *f = fixture_new();
    const char *path = mr_test_tmp_path("round_trip.cache");
    f->o.cache_path = path;
    progress_log log = {0, 1, 0, 0, 0};
    f->o.progress = on_progress;
    f->o.progress_user = &log;
    mr_direct_summary *s = &f->sa;
    // The first 12 texels first (12 values), then all of them: the cache grows.
    MR_CHECK_OK(mr_direct_remap(f->ggx, f->ward, f->in, 12, &f->o, f->a, f->oa, s));
    MR_CHECK(s->cache_hits == 0 && s->unique == 12 && log.calls == 12 && log.last == 12 && log.monotonic);
    MR_CHECK_OK(mr_direct_remap(f->ggx, f->ward, f->in, TEXELS, &f->o, f->a, f->oa, s));
    MR_CHECK(s->cache_hits == 12 && s->unique == TEXELS / 2 && s->full + s->warm == TEXELS / 2 - 12);
    size_t size = 0;
    char *text = mr_test_read_file(path, &size);
    MR_CHECK(text != NULL && strncmp(text, "# matremap ", 11) == 0 && strstr(text, "direct-cache\n# from: ggx\n"));
    MR_CHECK(text != NULL && strstr(text, "\n# direct: tolerance=0.0078431372549019607 start=warm\n") != NULL);
    MR_CHECK(text != NULL && strstr(text, "\nalpha,f0_r,f0_g,f0_b,diffuse_r,") != NULL);
    // Every value once, one line each, after a 7-line header.
    int lines = 0;
    for (size_t i = 0; text != NULL && i < size; i++) lines += text[i] == '\n';
    MR_CHECK(lines == 7 + TEXELS / 2);
    // A second run: all hits, no remap, the same bits; progress reported once.
    log = (progress_log){0, 1, 0, 0, 0};
    MR_CHECK_OK(mr_direct_remap(f->ggx, f->ward, f->in, TEXELS, &f->o, f->b, f->ob, s));
    MR_CHECK(s->cache_hits == TEXELS / 2 && s->remaps == 0 && s->renders == 0 && s->threads == 0);
    MR_CHECK(log.calls == 1 && log.last == TEXELS / 2 && log.hits == TEXELS / 2);
    MR_CHECK(memcmp(f->a, f->b, sizeof f->a) == 0 && memcmp(f->oa, f->ob, sizeof f->oa) == 0);
    // The file is untouched by a run of hits only.
    size_t size2 = 0;
    char *text2 = mr_test_read_file(path, &size2);
    MR_CHECK(text2 != NULL && size2 == size && memcmp(text, text2, size) == 0);
    free(text2);
    // A torn last line (a write cut short) is cut off, the rest kept.
    FILE *file = fopen(path, "ab");
    fputs("0.05,0.1,0.1", file);
    fclose(file);
    MR_CHECK_OK(mr_direct_remap(f->ggx, f->ward, f->in, TEXELS, &f->o, f->b, f->ob, s));
    MR_CHECK(s->cache_hits == TEXELS / 2 && s->remaps == 0);
    text2 = mr_test_read_file(path, &size2);
    MR_CHECK(text2 != NULL && size2 == size && memcmp(text, text2, size) == 0);
    free(text2);
    // Cold answers are another configuration: refused by this file.
    f->o.cold = 1;
    f->o.progress = NULL;
    MR_CHECK(mr_direct_remap(f->ggx, f->ward, f->in, TEXELS, &f->o, f->b, f->ob, s) == MR_ERR_INVALID_ARG);
    MR_CHECK(strstr(mr_last_error(), "start=warm") != NULL);
    free(text);
}

/* Run once into `path` (a fresh cache) and return its text. */
static char *fresh_cache(const char *path, size_t *size) {
    fixture *f = fixture_new();
    unlink(path);
    f->o.cache_path = path;
    MR_CHECK_OK(mr_direct_remap(f->ggx, f->ward, f->in, 6, &f->o, f->a, NULL, NULL));
    return mr_test_read_file(path, size);
}

/* Run with `o` against the cache `path`, expect `status` and `message` in the error, and the file unchanged. */
static void expect_refused(const char *path, mr_direct_options o, mr_status status, const char *message) {
    fixture *f = fixture_new();
    size_t before = 0, after = 0;
    char *was = mr_test_read_file(path, &before);
    o.cache_path = path;
    mr_status got = mr_direct_remap(f->ggx, f->ward, f->in, 6, &o, f->a, NULL, NULL);
    MR_CHECK_MSG(got == status && strstr(mr_last_error(), message) != NULL, "got %s: %s (expected '%s')",
                 mr_status_str(got), mr_last_error(), message);
    char *is = mr_test_read_file(path, &after);
    MR_CHECK(was != NULL && is != NULL && before == after && memcmp(was, is, before) == 0);
    free(was);
    free(is);
}

MR_TEST(foreign_corrupt_and_locked_caches_are_refused_untouched) {
    const char *path = mr_test_tmp_path("foreign.cache");
    size_t size = 0;
    char *text = fresh_cache(path, &size);
    MR_CHECK(text != NULL);
    if (text == NULL) return;
    // Another step, other target values, another fit scene: another configuration.
    mr_direct_options o = options();
    o.tolerance = 3.0 / 255.0;
    expect_refused(path, o, MR_ERR_INVALID_ARG, "belongs to another remap: line 6 is '# direct: tolerance=");
    o = options();
    double target[MR_BRDF_MAX_VALUES];
    mr_brdf_default_values(model("ward-balanced"), target);
    target[mr_brdf_value_count(model("ward-balanced")) - 1] = 0.0; // trim off
    o.remap.target_values = target;
    expect_refused(path, o, MR_ERR_INVALID_ARG, "line 3 is '# to: ward-balanced");
    o = options();
    o.scene.size = 48;
    expect_refused(path, o, MR_ERR_INVALID_ARG, "line 5 is '# scene: fit size=32");
    // A line that does not parse, a value off the grid (an edited file), a header cut short.
    const char *rows = strstr(text, "relative_rmse,outcome,how\n") + strlen("relative_rmse,outcome,how\n");
    const size_t header = (size_t)(rows - text);
    char *edited = malloc(size + 64);
    memcpy(edited, text, size);
    memcpy(edited + header, "x.5", 3);
    mr_test_write_file(path, edited, size);
    expect_refused(path, options(), MR_ERR_FORMAT, "line 8: column 1: 'x.5");
    memcpy(edited, text, size);
    memcpy(edited + header, "0.1", 3); // alpha 0.1 is not on the grid of ln alpha
    mr_test_write_file(path, edited, size);
    expect_refused(path, options(), MR_ERR_FORMAT, "line 8: its source values are not a quantised value");
    mr_test_write_file(path, text, header - 10);
    expect_refused(path, options(), MR_ERR_FORMAT, "the header ends early, at line 7");
    free(edited);
    // A second process holding the cache: refused, naming it.
    mr_test_write_file(path, text, size);
    int ready[2];
    MR_CHECK(pipe(ready) == 0);
    pid_t child = fork();
    if (child == 0) {
        int fd = open(path, O_RDWR);
        struct flock fl;
        memset(&fl, 0, sizeof fl);
        fl.l_type = F_WRLCK;
        fl.l_whence = SEEK_SET;
        char byte = fcntl(fd, F_SETLK, &fl) == 0 ? 'y' : 'n';
        if (write(ready[1], &byte, 1) != 1) _exit(1);
        pause();
        _exit(0);
    }
    char byte = 0;
    MR_CHECK(read(ready[0], &byte, 1) == 1 && byte == 'y');
    expect_refused(path, options(), MR_ERR_IO, "is being written by another process");
    kill(child, SIGKILL);
    waitpid(child, NULL, 0);
    close(ready[0]);
    close(ready[1]);
    free(text);
}

MR_TEST(bad_input_is_refused_or_clamped_as_documented) {
    fixture *f = fixture_new();
    const mr_brdf_model *ggx = f->ggx, *ward = f->ward;
    const int ns = f->ns, nt = f->nt;
    double *in = f->in, *out = f->a;
    mr_direct_options o = options();
    mr_direct_summary s;
    MR_CHECK(mr_direct_remap(NULL, ward, in, 4, &o, out, NULL, NULL) == MR_ERR_INVALID_ARG);
    MR_CHECK(mr_direct_remap(ggx, NULL, in, 4, &o, out, NULL, NULL) == MR_ERR_INVALID_ARG);
    MR_CHECK(mr_direct_remap(ggx, ward, NULL, 4, &o, out, NULL, NULL) == MR_ERR_INVALID_ARG);
    MR_CHECK(mr_direct_remap(ggx, ward, in, 4, &o, NULL, NULL, NULL) == MR_ERR_INVALID_ARG);
    // n = 0: nothing to do, nothing opened.
    o.cache_path = mr_test_tmp_path("never.cache");
    s.texels = 99;
    MR_CHECK_OK(mr_direct_remap(ggx, ward, NULL, 0, &o, NULL, NULL, &s));
    MR_CHECK(s.texels == 0 && s.unique == 0 && access(o.cache_path, F_OK) != 0);
    o.cache_path = NULL;
    // A NaN texel: refused, naming the texel and the parameter; out untouched.
    double bad[4 * MR_BRDF_MAX_VALUES];
    memcpy(bad, in, sizeof bad);
    bad[3 * ns] = NAN;
    out[0] = -7.0;
    MR_CHECK(mr_direct_remap(ggx, ward, bad, 4, &o, out, NULL, NULL) == MR_ERR_INVALID_ARG);
    MR_CHECK(strstr(mr_last_error(), "texel 3: alpha = nan") != NULL && out[0] == -7.0);
    // Out of range: clamped and counted; the answer is the clamped value's.
    memcpy(bad, in, sizeof bad);
    bad[1] = 1.7;       // f0_r of texel 0
    bad[ns + 0] = 5.0;  // alpha of texel 1
    double clamped[4 * MR_BRDF_MAX_VALUES], a[4 * MR_BRDF_MAX_VALUES], b[4 * MR_BRDF_MAX_VALUES];
    memcpy(clamped, bad, sizeof clamped);
    clamped[1] = 1.0;
    clamped[ns + 0] = 1.0;
    MR_CHECK_OK(mr_direct_remap(ggx, ward, bad, 4, &o, a, NULL, &s));
    MR_CHECK(s.clamped == 2);
    MR_CHECK_OK(mr_direct_remap(ggx, ward, clamped, 4, &o, b, NULL, &s));
    MR_CHECK(s.clamped == 0 && memcmp(a, b, 4 * (size_t)nt * sizeof *a) == 0);
    // Options out of range, each named.
    o = options();
    o.tolerance = 2.0;
    MR_CHECK(mr_direct_remap(ggx, ward, in, 4, &o, out, NULL, NULL) == MR_ERR_INVALID_ARG);
    MR_CHECK(strstr(mr_last_error(), "tolerance 2") != NULL);
    o = options();
    o.chain_length = -1;
    MR_CHECK(mr_direct_remap(ggx, ward, in, 4, &o, out, NULL, NULL) == MR_ERR_INVALID_ARG);
    o = options();
    o.threads = -2;
    MR_CHECK(mr_direct_remap(ggx, ward, in, 4, &o, out, NULL, NULL) == MR_ERR_INVALID_ARG);
    o = options();
    o.remap.initial_values = in;
    MR_CHECK(mr_direct_remap(ggx, ward, in, 4, &o, out, NULL, NULL) == MR_ERR_INVALID_ARG);
    MR_CHECK(strstr(mr_last_error(), "initial_values") != NULL);
    o = options();
    o.remap.strategy = (mr_remap_strategy)42;
    MR_CHECK(mr_direct_remap(ggx, ward, in, 4, &o, out, NULL, NULL) == MR_ERR_INVALID_ARG);
    o = options();
    double target[MR_BRDF_MAX_VALUES];
    mr_brdf_default_values(ward, target);
    target[0] = 3.0; // diffuse_r outside [0, 1]
    o.remap.target_values = target;
    MR_CHECK(mr_direct_remap(ggx, ward, in, 4, &o, out, NULL, NULL) == MR_ERR_INVALID_ARG);
    MR_CHECK(strstr(mr_last_error(), "diffuse = 3") != NULL);
}


/* A Ward texture whose texels share specular lobes (direct.h, "Shared shapes"): SHAPES specular colour and alpha
 * pairs, each under DIFFUSES diffuse colours (none of them trimmed: diffuse + specular < 0.99). */
#define SHAPES 4
#define DIFFUSES 6
static void ward_texture(const mr_brdf_model *ward, double *values) {
    const int nv = mr_brdf_value_count(ward);
    for (int i = 0; i < SHAPES * DIFFUSES; i++) {
        double *v = values + (size_t)i * (size_t)nv;
        const int shape = i % SHAPES, d = i / SHAPES;
        mr_brdf_default_values(ward, v); // trimming on
        set(ward, v, "alpha", (double[]){0.08 * pow(1.6, shape)});
        set(ward, v, "specular", (double[]){0.04 + 0.03 * shape, 0.05, 0.06});
        set(ward, v, "diffuse", (double[]){0.1 + 0.1 * d, 0.3, 0.5 - 0.05 * d});
        double q[MR_BRDF_MAX_VALUES];
        MR_CHECK_OK(mr_direct_quantise(ward, STEP, v, q));
        memcpy(v, q, (size_t)nv * sizeof *v);
    }
}

MR_TEST(shared_shapes_keep_the_answers_and_outcomes_of_full_remaps) {
    const mr_brdf_model *ward = model("ward"), *ggx = model("ggx");
    const int nw = mr_brdf_value_count(ward), ng = mr_brdf_value_count(ggx), n = SHAPES * DIFFUSES;
    static double in[SHAPES * DIFFUSES * MR_BRDF_MAX_VALUES], shared[SHAPES * DIFFUSES * MR_BRDF_MAX_VALUES],
        own[SHAPES * DIFFUSES * MR_BRDF_MAX_VALUES], cold[SHAPES * DIFFUSES * MR_BRDF_MAX_VALUES],
        two[SHAPES * DIFFUSES * MR_BRDF_MAX_VALUES];
    mr_fit_outcome o_shared[SHAPES * DIFFUSES], o_own[SHAPES * DIFFUSES], o_cold[SHAPES * DIFFUSES],
        o_two[SHAPES * DIFFUSES];
    ward_texture(ward, in);
    mr_direct_options o = options();
    mr_direct_summary s_shared, s_own, s_two;
    MR_CHECK_OK(mr_direct_remap(ward, ggx, in, (size_t)n, &o, shared, o_shared, &s_shared));
    // Every value but the first of each shape shares it (one chain holds them all).
    MR_CHECK_MSG(s_shared.shared_shapes == (size_t)(n - SHAPES), "%zu of %d values shared a shape",
                 s_shared.shared_shapes, n);
    o.fit_every_shape = 1;
    MR_CHECK_OK(mr_direct_remap(ward, ggx, in, (size_t)n, &o, own, o_own, &s_own));
    MR_CHECK(s_own.shared_shapes == 0 && s_shared.renders < s_own.renders);
    o.fit_every_shape = 0;
    o.cold = 1;
    MR_CHECK_OK(mr_direct_remap(ward, ggx, in, (size_t)n, &o, cold, o_cold, NULL));
    const int alpha = mr_brdf_param_offset(ggx, mr_brdf_param_index(ggx, "alpha"));
    double worst = 0.0, worst_own = 0.0;
    for (int i = 0; i < n; i++) {
        const size_t at = (size_t)i * (size_t)ng;
        worst = fmax(worst, largest_difference(ggx, shared + at, cold + at));
        worst_own = fmax(worst_own, largest_difference(ggx, own + at, cold + at));
        MR_CHECK_MSG(o_shared[i] == o_cold[i] && o_own[i] == o_cold[i], "texel %d: outcomes %s (shared) %s (own) "
                     "%s (full)", i, mr_fit_outcome_name(o_shared[i]), mr_fit_outcome_name(o_own[i]),
                     mr_fit_outcome_name(o_cold[i]));
        // The shape is the sibling's: the same alpha (up to the normalised coordinates' rounding) for every
        // diffuse colour.
        const size_t first = (size_t)(i % SHAPES) * (size_t)ng;
        MR_CHECK_NEAR(shared[at + (size_t)alpha] / shared[first + (size_t)alpha], 1.0, 1e-12);
    }
    MR_CHECK_MSG(worst <= WARM_TOLERANCE, "shared shapes differ from full remaps by up to %g", worst);
    printf("    shared shapes: %zu of %zu values, %ld renders (%ld without); largest difference from full remaps "
           "%.2g (%.2g without)\n", s_shared.shared_shapes, s_shared.unique, s_shared.renders, s_own.renders, worst,
           worst_own);
    // The same bits for 1 and 2 threads (chains of 5).
    o.cold = 0;
    o.chain_length = 5;
    MR_CHECK_OK(mr_direct_remap(ward, ggx, in, (size_t)n, &o, shared, o_shared, &s_shared));
    o.threads = 2;
    MR_CHECK_OK(mr_direct_remap(ward, ggx, in, (size_t)n, &o, two, o_two, &s_two));
    MR_CHECK(memcmp(shared, two, (size_t)n * (size_t)ng * sizeof *two) == 0);
    MR_CHECK(memcmp(o_shared, o_two, sizeof o_two) == 0 && s_shared.shared_shapes == s_two.shared_shapes);
    MR_CHECK(s_shared.shared_shapes > 0 && s_shared.renders == s_two.renders && s_two.threads == 2);
    (void)nw;
}

MR_TEST(shapes_are_shared_only_between_identical_specular_renders) {
    // Three Ward texels with one specular colour and alpha: diffuse 0.2 and 0.3 render the same specular lobe;
    // diffuse 0.8 engages Mitsuba's trimming (diffuse + specular > 0.99), which scales it: no sibling.
    const mr_brdf_model *ward = model("ward"), *ggx = model("ggx");
    const int nw = mr_brdf_value_count(ward), ng = mr_brdf_value_count(ggx);
    double in[3 * MR_BRDF_MAX_VALUES], out[3 * MR_BRDF_MAX_VALUES];
    const double diffuse[3] = {0.2, 0.8, 0.3};
    for (int i = 0; i < 3; i++) {
        double *v = in + (size_t)i * (size_t)nw;
        mr_brdf_default_values(ward, v);
        set(ward, v, "alpha", (double[]){0.2});
        set(ward, v, "specular", (double[]){0.3, 0.3, 0.3});
        set(ward, v, "diffuse", (double[]){diffuse[i], diffuse[i], diffuse[i]});
    }
    mr_direct_options o = options();
    mr_direct_summary s;
    MR_CHECK_OK(mr_direct_remap(ward, ggx, in, 3, &o, out, NULL, &s));
    MR_CHECK_MSG(s.unique == 3 && s.shared_shapes == 1, "%zu of %zu values shared a shape", s.shared_shapes,
                 s.unique);
    // Not where AUTO does not fit the specular lobe's shape alone: strategy joint; a held alpha (no shape).
    o.remap.strategy = MR_REMAP_JOINT;
    MR_CHECK_OK(mr_direct_remap(ward, ggx, in, 3, &o, out, NULL, &s));
    MR_CHECK(s.shared_shapes == 0);
    o.remap.strategy = MR_REMAP_AUTO;
    o.remap.held = 1u << mr_brdf_param_index(ggx, "alpha");
    MR_CHECK_OK(mr_direct_remap(ward, ggx, in, 3, &o, out, NULL, &s));
    MR_CHECK(s.shared_shapes == 0);
    (void)ng;
}

MR_TEST(roughness_has_its_own_step_when_given) {
    const mr_brdf_model *ggx = model("ggx");
    const int nv = mr_brdf_value_count(ggx);
    double v[MR_BRDF_MAX_VALUES], q[MR_BRDF_MAX_VALUES], same[MR_BRDF_MAX_VALUES];
    const double t = 1.0 / 255.0, tr = 4.0 / 255.0;
    mr_brdf_default_values(ggx, v);
    set(ggx, v, "alpha", (double[]){0.1234});
    set(ggx, v, "f0", (double[]){0.04, 0.5, 0.9});
    MR_CHECK_OK(mr_direct_quantise_steps(ggx, t, tr, v, q));
    MR_CHECK(q[0] == exp(tr * nearbyint(log(0.1234) / tr))); // alpha in ln steps of t_r
    for (int c = 0; c < 3; c++) MR_CHECK_NEAR(q[1 + c], srgb_decode(t * nearbyint(srgb_encode(v[1 + c]) / t)), 1e-15);
    MR_CHECK_OK(mr_direct_quantise_steps(ggx, t, tr, q, same)); // a fixed point
    MR_CHECK(memcmp(q, same, (size_t)nv * sizeof *q) == 0);
    MR_CHECK_OK(mr_direct_quantise_steps(ggx, t, 0.0, v, q)); // 0: t
    MR_CHECK_OK(mr_direct_quantise(ggx, t, v, same));
    MR_CHECK(memcmp(q, same, (size_t)nv * sizeof *q) == 0);
    MR_CHECK(mr_direct_quantise_steps(ggx, t, 2.0, v, q) == MR_ERR_INVALID_ARG &&
             strstr(mr_last_error(), "roughness tolerance 2") != NULL);
    // The remap: the cache header says the step only when it is not t (older caches keep matching).
    fixture *f = fixture_new();
    const char *path = mr_test_tmp_path("roughness_step.cache");
    f->o.cache_path = path;
    f->o.roughness_tolerance = tr;
    MR_CHECK_OK(mr_direct_remap(f->ggx, f->ward, f->in, 6, &f->o, f->a, f->oa, &f->sa));
    size_t size = 0;
    char *text = mr_test_read_file(path, &size);
    MR_CHECK(text != NULL && strstr(text, "\n# direct: tolerance=0.0078431372549019607 roughness_tolerance="
                                          "0.015686274509803921 start=warm\n") != NULL);
    free(text);
    // The same file with the step of t: another configuration, refused.
    f->o.roughness_tolerance = 0.0;
    MR_CHECK(mr_direct_remap(f->ggx, f->ward, f->in, 6, &f->o, f->a, f->oa, &f->sa) == MR_ERR_INVALID_ARG);
    f->o.roughness_tolerance = -1.0;
    f->o.cache_path = NULL;
    MR_CHECK(mr_direct_remap(f->ggx, f->ward, f->in, 6, &f->o, f->a, f->oa, &f->sa) == MR_ERR_INVALID_ARG);
}

MR_TEST_MAIN(MR_TEST_ENTRY(quantisation_is_the_documented_one), MR_TEST_ENTRY(duplicated_texels_share_one_answer),
             MR_TEST_ENTRY(cold_answers_are_mr_remap_of_the_quantised_value_bit_for_bit),
             MR_TEST_ENTRY(warm_answers_stay_within_the_stated_tolerance_of_full_remaps),
             MR_TEST_ENTRY(a_warm_start_refines_locally_from_initial_values),
             MR_TEST_ENTRY(one_and_two_threads_give_the_same_bits),
             MR_TEST_ENTRY(the_cache_round_trips_grows_and_survives_a_torn_line),
             MR_TEST_ENTRY(foreign_corrupt_and_locked_caches_are_refused_untouched),
             MR_TEST_ENTRY(bad_input_is_refused_or_clamped_as_documented),
             MR_TEST_ENTRY(shared_shapes_keep_the_answers_and_outcomes_of_full_remaps),
             MR_TEST_ENTRY(shapes_are_shared_only_between_identical_specular_renders),
             MR_TEST_ENTRY(roughness_has_its_own_step_when_given))
