/*
 * test_labels.c — image-based labels (src/workflow/labels.h): the basis renders every material exactly as the
 * renderer does, texels on the manifold keep the analytic answer, grey texels get grey labels, the objective
 * separates what it should.
 */
#include "harness.h"

/* A batch's read-only input view of maps (workflow.h, mr_wf_spec_input / mr_wf_metal_input). */
#define SPEC_IN(m) (&(mr_wf_spec_input){(m).diffuse, (m).specular, (m).roughness})
#define METAL_IN(m) (&(mr_wf_metal_input){(m).albedo, (m).metallic, (m).roughness})

#include "brdf/brdf.h"
#include "nn/mlp.h"
#include "render/render.h"
#include "workflow/labels.h"

static mr_wf_label_scene *small_scene(mr_wf_objective objective) {
    mr_wf_label_options o = mr_wf_label_options_default();
    o.objective = objective;
    o.size = 24;
    o.env_samples = 64;
    o.reflection_samples = 8;
    o.glossiness_count = 2;
    o.glossiness[0] = 0.4;
    o.glossiness[1] = 0.9;
    mr_wf_label_scene *scene = NULL;
    MR_CHECK_OK(mr_wf_label_scene_create(&o, &scene));
    return scene;
}

static double max_abs_difference(const mr_image *a, const mr_image *b) {
    double worst = 0.0;
    for (size_t i = 0; i < mr_image_value_count(a); i++) worst = fmax(worst, fabs(a->pixels[i] - b->pixels[i]));
    return worst;
}

static double max_value(const mr_image *a) {
    double m = 0.0;
    for (size_t i = 0; i < mr_image_value_count(a); i++) m = fmax(m, a->pixels[i]);
    return m;
}

/* The basis combination equals mr_render of both glTF models (same scene, same sample pattern). */
MR_TEST(basis_matches_renderer) {
    mr_wf_label_options o = mr_wf_label_options_default();
    o.size = 24;
    o.env_samples = 64;
    o.reflection_samples = 8;
    o.glossiness_count = 1;
    o.glossiness[0] = 0.7;
    mr_wf_label_scene *scene = NULL;
    MR_CHECK_OK(mr_wf_label_scene_create(&o, &scene));
    if (scene == NULL) return;
    mr_image *env = NULL;
    MR_CHECK_OK(mr_wf_label_builtin_env(0, &env));
    mr_fit_scene_options fit = {24, MR_FIT_LIGHT_45, 0.0};
    mr_scene s = mr_scene_fit(&fit);
    double mean = 0.0;
    for (int i = 0; i < env->width * env->height; i++) mean += env->pixels[i];
    mean /= env->width * env->height;
    s.lights[0] = mr_light_environment(env, 0.5 / mean, 0.0, 64);
    s.lights[0].reflection_samples = 8;
    mr_render_plan *plan = NULL;
    MR_CHECK_OK(mr_render_plan_create(&s, &plan));
    mr_image *direct = NULL, *basis = NULL;
    MR_CHECK_OK(mr_image_create(24, 24, 3, &basis));
    /* a coloured spec-gloss texel with a coloured specular */
    mr_wf_spec spec = {{0.6, 0.3, 0.1}, {0.2, 0.05, 0.5}, 0};
    double sg[7] = {0.6, 0.3, 0.1, 0.2, 0.05, 0.5, 0.7};
    MR_CHECK_OK(mr_render(plan, mr_brdf_find("gltf-specgloss"), sg, MR_COMPONENT_FULL, &direct));
    MR_CHECK_OK(mr_wf_label_render(scene, 0, &spec, NULL, basis));
    MR_CHECK_MSG(max_abs_difference(direct, basis) <= 1e-5 * max_value(direct), "spec-gloss: %g of %g",
                 max_abs_difference(direct, basis), max_value(direct));
    mr_image_free(direct);
    direct = NULL;
    /* a half metal in glTF metal-rough (roughness 1 - glossiness) */
    mr_wf_metal metal = {{0.9, 0.5, 0.2}, 0.4, 0};
    const mr_brdf_model *gltf = mr_brdf_find("gltf");
    double mr[10] = {0.9, 0.5, 0.2, 0.4, 0.3, 1, 1, 1, 1, 1.5};
    MR_CHECK_OK(mr_render(plan, gltf, mr, MR_COMPONENT_FULL, &direct));
    MR_CHECK_OK(mr_wf_label_render(scene, 0, NULL, &metal, basis));
    MR_CHECK_MSG(max_abs_difference(direct, basis) <= 1e-5 * max_value(direct), "metal-rough: %g of %g",
                 max_abs_difference(direct, basis), max_value(direct));
    mr_image_free(direct);
    mr_image_free(basis);
    mr_image_free(env);
    mr_render_plan_free(plan);
    mr_wf_label_scene_free(scene);
}

/* A dielectric and a metal of Eq. 2 render exactly as their analytic inverse: the label keeps it. */
MR_TEST(manifold_texels_keep_the_analytic_answer) {
    for (int objective = MR_WF_OBJECTIVE_LINEAR; objective < MR_WF_OBJECTIVE_COUNT; objective++) {
        mr_wf_label_scene *scene = small_scene((mr_wf_objective)objective);
        if (scene == NULL) return;
        const mr_wf_spec texels[] = {
            {{0.0037 / 0.96, 0.0037 / 0.96, 0.0037 / 0.96}, {0.04, 0.04, 0.04}, 0}, /* the black plastic */
            {{0.8, 0.1, 0.05}, {0.04, 0.04, 0.04}, 0},                             /* red plastic */
            {{0, 0, 0}, {0.95, 0.64, 0.54}, 0},                                    /* copper */
        };
        for (int k = 0; k < 3; k++) {
            mr_wf_metal out;
            mr_wf_label_result r;
            MR_CHECK_OK(mr_wf_label_fit(scene, &texels[k], &out, &r));
            MR_CHECK_MSG(r.loss <= 1e-12, "objective %d texel %d: loss %g", objective, k, r.loss);
            MR_CHECK_MSG(k == 2 ? out.metallic >= 0.999 : out.metallic <= 1e-3, "objective %d texel %d: m %g",
                         objective, k, out.metallic);
        }
        mr_wf_label_scene_free(scene);
    }
}

/* A grey texel off the manifold gets a grey label under the built-in (grey) lights. */
MR_TEST(grey_in_grey_out) {
    mr_wf_label_scene *scene = small_scene(MR_WF_OBJECTIVE_DISPLAY);
    if (scene == NULL) return;
    mr_wf_spec grey = {{1, 1, 1}, {0, 0, 0}, 0}, dim = {{0.3, 0.3, 0.3}, {0.2, 0.2, 0.2}, 0};
    const mr_wf_spec *texels[] = {&grey, &dim};
    for (int k = 0; k < 2; k++) {
        mr_wf_metal out;
        MR_CHECK_OK(mr_wf_label_fit(scene, texels[k], &out, NULL));
        MR_CHECK_NEAR(out.albedo[1], out.albedo[0], 1e-9);
        MR_CHECK_NEAR(out.albedo[2], out.albedo[0], 1e-9);
    }
    mr_wf_label_scene_free(scene);
}

/* Off the manifold the label renders at least as close as the analytic answer, by its own measure. */
MR_TEST(label_beats_analytic_off_manifold) {
    mr_wf_label_scene *scene = small_scene(MR_WF_OBJECTIVE_DISPLAY);
    if (scene == NULL) return;
    mr_wf_spec texel = {{0.5, 0.5, 0.5}, {0.9, 0.2, 0.2}, 0};
    mr_wf_metal out;
    mr_wf_label_result r;
    MR_CHECK_OK(mr_wf_label_fit(scene, &texel, &out, &r));
    MR_CHECK_MSG(r.loss < 0.9 * r.analytic_loss, "label %g, analytic %g", r.loss, r.analytic_loss);
    double again;
    MR_CHECK_OK(mr_wf_label_loss(scene, &texel, &out, &again));
    MR_CHECK_NEAR(again, r.loss, 1e-15);
    mr_wf_label_scene_free(scene);
}

/* The label and its loss of an off-manifold texel under scene options o. */
static void label_with(const mr_wf_label_options *o, mr_wf_metal *out, mr_wf_label_result *r) {
    mr_wf_label_scene *scene = NULL;
    memset(out, 0, sizeof *out);
    memset(r, 0, sizeof *r);
    MR_CHECK_OK(mr_wf_label_scene_create(o, &scene));
    if (scene == NULL) return;
    const mr_wf_spec texel = {{0.6, 0.3, 0.1}, {0.5, 0.2, 0.1}, 0};
    MR_CHECK_OK(mr_wf_label_fit(scene, &texel, out, r));
    mr_wf_label_scene_free(scene);
}

/* A zeroed mr_wf_label_options is the defaults (labels.h): the same labels, bit for bit; and each field's 0 reads
 * as its default on its own, MR_WF_LABEL_OFF as none. */
MR_TEST(zeroed_options_are_the_defaults) {
    const mr_wf_label_options defaults = mr_wf_label_options_default();
    mr_wf_label_options zeroed;
    memset(&zeroed, 0, sizeof zeroed);
    mr_wf_metal a, b;
    mr_wf_label_result ra, rb;
    label_with(&defaults, &a, &ra);
    label_with(&zeroed, &b, &rb);
    MR_CHECK(memcmp(&a, &b, sizeof a) == 0 && ra.loss == rb.loss);
    MR_CHECK(strcmp(mr_wf_objective_name(MR_WF_OBJECTIVE_DEFAULT), "luma") == 0);
    mr_wf_objective obj = MR_WF_OBJECTIVE_DEFAULT;
    MR_CHECK_OK(mr_wf_objective_from_name("luma", &obj));
    MR_CHECK(obj == MR_WF_OBJECTIVE_LUMA);

    // One field at a time on a small scene: 0 against the default written out; OFF against a differing scene.
    mr_wf_label_options small = defaults;
    small.size = 16;
    small.env_samples = 32;
    small.glossiness_count = 2;
    small.glossiness[0] = 0.5;
    small.glossiness[1] = 0.9;
    label_with(&small, &a, &ra);
    mr_wf_label_options z = small;
    z.objective = 0;
    z.reflection_samples = 0;
    z.chroma_weight = 0.0;
    z.regularisation = 0.0;
    label_with(&z, &b, &rb);
    MR_CHECK(memcmp(&a, &b, sizeof a) == 0 && ra.loss == rb.loss);
    z = small;
    z.regularisation = MR_WF_LABEL_OFF;
    z.chroma_weight = MR_WF_LABEL_OFF;
    z.reflection_samples = MR_WF_LABEL_OFF;
    label_with(&z, &b, &rb);
    MR_CHECK(rb.loss != ra.loss);
}

MR_TEST(bad_options_are_refused) {
    mr_wf_label_options o = mr_wf_label_options_default();
    mr_wf_label_scene *scene = NULL;
    o.size = 8;
    MR_CHECK(mr_wf_label_scene_create(&o, &scene) == MR_ERR_INVALID_ARG);
    o = mr_wf_label_options_default();
    o.glossiness[1] = 1.5;
    MR_CHECK(mr_wf_label_scene_create(&o, &scene) == MR_ERR_INVALID_ARG);
    o = mr_wf_label_options_default();
    o.regularisation = -0.5; /* negative, and not MR_WF_LABEL_OFF */
    MR_CHECK(mr_wf_label_scene_create(&o, &scene) == MR_ERR_INVALID_ARG);
    o = mr_wf_label_options_default();
    o.objective = MR_WF_OBJECTIVE_COUNT;
    MR_CHECK(mr_wf_label_scene_create(&o, &scene) == MR_ERR_INVALID_ARG);
    MR_CHECK(scene == NULL);
    mr_wf_objective obj;
    MR_CHECK(mr_wf_objective_from_name("ssim", &obj) == MR_ERR_INVALID_ARG);
    MR_CHECK_OK(mr_wf_objective_from_name("log", &obj));
    MR_CHECK(obj == MR_WF_OBJECTIVE_LOG);
}

/* A network of the design card's shape with seeded random weights (any network: the form must hold for all). */
static mr_mlp *random_residual_net(unsigned seed) {
    mr_mlp *net = NULL;
    MR_CHECK_OK(mr_mlp_create(6, 300, 4, &net));
    if (net == NULL) return NULL;
    unsigned state = seed;
    for (size_t i = 0; i < net->data_count; i++) {
        state = state * 1664525u + 1013904223u;
        net->data[i] = ((float)(state >> 8) / 16777216.0f - 0.5f) * 0.2f;
    }
    for (int k = 0; k < 6; k++) {
        net->in_mean[k] = 0.3f;
        net->in_std[k] = 0.3f;
    }
    for (int k = 0; k < 4; k++) {
        net->out_mean[k] = 0.0f;
        net->out_std[k] = 0.5f;
    }
    snprintf(net->kind, sizeof net->kind, "%s", MR_WF_MLP_RESIDUAL_KIND);
    return net;
}

/* Metal-rough texels put through Eq. 2 come back exactly (as WEIGHTED) whatever the network says. */
MR_TEST(residual_form_is_exact_on_the_manifold) {
    mr_mlp *net = random_residual_net(7);
    if (net == NULL) return;
    enum { N = 200 };
    float dif[3 * N], spe[3 * N], alb[3 * N], met[N], walb[3 * N], wmet[N];
    unsigned state = 3;
    for (int i = 0; i < N; i++) {
        mr_wf_metal m = {{0, 0, 0}, 0, 0};
        for (int c = 0; c < 4; c++) {
            state = state * 1664525u + 1013904223u;
            double u = (double)(state >> 8) / 16777216.0;
            if (c < 3)
                m.albedo[c] = 0.05 + 0.95 * u;
            else
                m.metallic = i % 3 == 0 ? 0.0 : i % 3 == 1 ? 1.0 : u;
        }
        mr_wf_spec s;
        MR_CHECK_OK(mr_wf_metal_to_spec(&m, NULL, &s, NULL));
        for (int c = 0; c < 3; c++) {
            dif[3 * i + c] = (float)s.diffuse[c];
            spe[3 * i + c] = (float)s.specular[c];
        }
    }
    mr_wf_spec_input in = {dif, spe, NULL};
    mr_wf_metal_maps out = {alb, met, NULL}, wout = {walb, wmet, NULL};
    MR_CHECK_OK(mr_wf_spec_to_metal_mlp_batch(net, &in, N, NULL, &out, NULL));
    MR_CHECK_OK(mr_wf_spec_to_metal_batch(&in, N, NULL, &wout, NULL));
    double worst = 0.0;
    for (int i = 0; i < N; i++) {
        worst = fmax(worst, fabs(met[i] - wmet[i]));
        for (int c = 0; c < 3; c++) worst = fmax(worst, fabs(alb[3 * i + c] - walb[3 * i + c]));
    }
    /* float inputs leave Eq. 2 a few 1e-8 off: the gate opens by r / 0.01, about 1e-6 of the correction */
    MR_CHECK_MSG(worst <= 1e-5, "worst difference from WEIGHTED %g", worst);
    mr_mlp_free(net);
}

/* Grey inputs (off the manifold too) give grey outputs, whatever the network says. */
MR_TEST(residual_form_is_colour_neutral) {
    mr_mlp *net = random_residual_net(11);
    if (net == NULL) return;
    enum { N = 64 };
    float dif[3 * N], spe[3 * N], alb[3 * N], met[N];
    for (int i = 0; i < N; i++)
        for (int c = 0; c < 3; c++) {
            dif[3 * i + c] = (float)(i % 8) / 7.0f;
            spe[3 * i + c] = (float)(i / 8) / 7.0f;
        }
    mr_wf_spec_maps in = {dif, spe, NULL};
    mr_wf_metal_maps out = {alb, met, NULL};
    MR_CHECK_OK(mr_wf_spec_to_metal_mlp_batch(net, SPEC_IN(in), N, NULL, &out, NULL));
    double worst = 0.0, moved = 0.0;
    for (int i = 0; i < N; i++) {
        worst = fmax(worst, fmax(fabs(alb[3 * i + 1] - alb[3 * i]), fabs(alb[3 * i + 2] - alb[3 * i])));
        moved = fmax(moved, fabs(alb[3 * i] - alb[3 * i + 1]) + fabs(met[i]));
    }
    MR_CHECK_MSG(worst <= 1e-7, "a grey input came out coloured by %g", worst);
    /* a coloured input may come out with channels moved differently (the form does not freeze colour) */
    float cd[3] = {0.8f, 0.2f, 0.1f}, cs[3] = {0.9f, 0.3f, 0.3f}, ca[3], cm;
    mr_wf_spec_input cin = {cd, cs, NULL};
    mr_wf_metal_maps cout_ = {ca, &cm, NULL};
    MR_CHECK_OK(mr_wf_spec_to_metal_mlp_batch(net, &cin, 1, NULL, &cout_, NULL));
    float wa[3], wm;
    mr_wf_metal_maps wout = {wa, &wm, NULL};
    MR_CHECK_OK(mr_wf_spec_to_metal_batch(&cin, 1, NULL, &wout, NULL));
    MR_CHECK(fabs(ca[0] - wa[0]) + fabs(ca[1] - wa[1]) + fabs(ca[2] - wa[2]) + fabs(cm - wm) > 1e-4);
    mr_mlp_free(net);
}

/* Texels whose gate is shut skip the network; the others must come out as if each were converted alone. */
MR_TEST(residual_form_batch_equals_single_texels) {
    mr_mlp *net = random_residual_net(13);
    if (net == NULL) return;
    enum { N = 6 };
    float dif[3 * N] = {0, 0, 0, 0.5f, 0.2f, 0.1f, 0, 0, 0, 0.3f, 0.3f, 0.3f, 0.9f, 0.1f, 0.4f, 0, 0, 0};
    float spe[3 * N] = {0.5f, 0.5f, 0.5f, 0.9f, 0.3f, 0.2f, 0.25f, 0.25f, 0.25f,
                        0.7f, 0.7f, 0.7f, 0.02f, 0.02f, 0.02f, 1, 1, 1};
    float alb[3 * N], met[N];
    mr_wf_spec_maps in = {dif, spe, NULL};
    mr_wf_metal_maps out = {alb, met, NULL};
    MR_CHECK_OK(mr_wf_spec_to_metal_mlp_batch(net, SPEC_IN(in), N, NULL, &out, NULL));
    for (int i = 0; i < N; i++) {
        float a[3], m;
        mr_wf_spec_input one = {dif + 3 * i, spe + 3 * i, NULL};
        mr_wf_metal_maps o = {a, &m, NULL};
        MR_CHECK_OK(mr_wf_spec_to_metal_mlp_batch(net, &one, 1, NULL, &o, NULL));
        MR_CHECK_MSG(memcmp(a, alb + 3 * i, sizeof a) == 0 && m == met[i], "texel %d differs alone", i);
    }
    /* the pure metals (gate shut) are exactly WEIGHTED: albedo = specular, metallic 1 */
    MR_CHECK(met[0] == 1.0f && alb[0] == 0.5f && met[2] == 1.0f && alb[6] == 0.25f);
    mr_mlp_free(net);
}

/* The kind survives the weight file (version 2); plain networks keep version 1; a bad kind is refused. */
MR_TEST(network_kind_round_trip) {
    mr_mlp *net = random_residual_net(5), *back = NULL;
    if (net == NULL) return;
    const char *path = mr_test_tmp_path("residual.mlp");
    MR_CHECK_OK(mr_mlp_write(net, path));
    FILE *f = fopen(path, "r");
    char line[64] = "";
    MR_CHECK(f != NULL && fgets(line, sizeof line, f) != NULL);
    if (f) fclose(f);
    MR_CHECK(strcmp(line, "matremap-mlp 2\n") == 0);
    MR_CHECK_OK(mr_mlp_read(path, &back));
    MR_CHECK(back != NULL && strcmp(back->kind, MR_WF_MLP_RESIDUAL_KIND) == 0);
    mr_mlp_free(back);
    back = NULL;
    net->kind[0] = '\0';
    MR_CHECK_OK(mr_mlp_write(net, path));
    f = fopen(path, "r");
    MR_CHECK(f != NULL && fgets(line, sizeof line, f) != NULL);
    if (f) fclose(f);
    MR_CHECK(strcmp(line, "matremap-mlp 1\n") == 0);
    snprintf(net->kind, sizeof net->kind, "bad kind");
    MR_CHECK(mr_mlp_write(net, path) == MR_ERR_INVALID_ARG);
    /* an unknown kind is refused by the converter, not misread */
    snprintf(net->kind, sizeof net->kind, "something-else");
    float d[3] = {0.5f, 0.5f, 0.5f}, s[3] = {0.04f, 0.04f, 0.04f}, a[3], m;
    mr_wf_spec_maps in = {d, s, NULL};
    mr_wf_metal_maps out = {a, &m, NULL};
    MR_CHECK(mr_wf_spec_to_metal_mlp_batch(net, SPEC_IN(in), 1, NULL, &out, NULL) == MR_ERR_INVALID_ARG);
    mr_mlp_free(net);
}

MR_TEST_MAIN(MR_TEST_ENTRY(residual_form_is_exact_on_the_manifold), MR_TEST_ENTRY(residual_form_is_colour_neutral),
             MR_TEST_ENTRY(residual_form_batch_equals_single_texels),
             MR_TEST_ENTRY(network_kind_round_trip), MR_TEST_ENTRY(basis_matches_renderer),
             MR_TEST_ENTRY(manifold_texels_keep_the_analytic_answer),
             MR_TEST_ENTRY(grey_in_grey_out), MR_TEST_ENTRY(label_beats_analytic_off_manifold),
             MR_TEST_ENTRY(zeroed_options_are_the_defaults), MR_TEST_ENTRY(bad_options_are_refused))
