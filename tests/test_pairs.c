/*
 * test_pairs.c — the training pairs of the learned converter (src/workflow/pairs.h) through the library, not the
 * CLI: a pairs file made, read back by its reader (mr_wf_dataset_load) and the same on any thread count; the texel
 * pool and an asset's texels; the objectives compared; converters evaluated against labels.
 */
#include <stdint.h>
#include <unistd.h>

#include "harness.h"

#include "gltf/mr_gltf.h"
#include "nn/mlp.h"
#include "workflow/pairs.h"

/* Small, fast label scenes: 16-pixel spheres, few samples, two glossinesses. */
static mr_wf_label_options small_labels(void) {
    mr_wf_label_options o = mr_wf_label_options_default();
    o.size = 16;
    o.env_samples = 32;
    o.reflection_samples = 4;
    o.glossiness_count = 2;
    o.glossiness[0] = 0.4;
    o.glossiness[1] = 0.9;
    return o;
}

typedef struct progress_log {
    int calls;
    size_t last_done, last_total;
    const char *last_stage;
} progress_log;

static void log_progress(const char *stage, size_t done, size_t total, void *user) {
    progress_log *p = user;
    p->calls++;
    p->last_done = done;
    p->last_total = total;
    p->last_stage = stage;
}

/* mr_wf_pairs_make: the file's rows, read back as `matremap train` reads them, identical for 1 and 2 threads. */
MR_TEST(pairs_file_made_and_read_back) {
    const mr_wf_label_options labels = small_labels();
    progress_log log = {0, 0, 0, NULL};
    mr_wf_pairs_options o = {0};
    o.samples = 30;
    o.seed = 5;
    o.labels = &labels;
    o.threads = 1;
    o.progress = log_progress;
    o.progress_user = &log;
    const char *one = mr_test_tmp_path("pairs1.csv"), *two = mr_test_tmp_path("pairs2.csv");
    mr_wf_pairs_summary s;
    MR_CHECK_OK(mr_wf_pairs_make(&o, one, &s));
    MR_CHECK(s.pairs == 30 && s.converged + s.unreachable == 30);
    size_t by_category = 0;
    for (int c = 0; c < MR_WF_PAIR_CATEGORY_COUNT; c++) by_category += s.categories[c];
    MR_CHECK(by_category == 30 && s.categories[MR_WF_PAIR_ASSET] == 0); // no pool, no asset texels
    MR_CHECK(log.calls >= 1 && log.last_done == 30 && log.last_total == 30 && strcmp(log.last_stage, "labels") == 0);
    o.threads = 2;
    o.progress = NULL;
    MR_CHECK_OK(mr_wf_pairs_make(&o, two, NULL));
    size_t n1 = 0, n2 = 0;
    char *a = mr_test_read_file(one, &n1), *b = mr_test_read_file(two, &n2);
    MR_CHECK(a != NULL && b != NULL && n1 == n2 && memcmp(a, b, n1) == 0);
    MR_CHECK(a != NULL && strncmp(a, "# matremap dataset: objective luma, seed 5, 30 pairs", 52) == 0);
    free(a);
    free(b);
    mr_wf_dataset d;
    mr_wf_dataset_options keep = {1};
    MR_CHECK_OK(mr_wf_dataset_load(&one, 1, &keep, &d));
    MR_CHECK(d.n == 30 && d.skipped == 0);
    for (size_t i = 0; i < d.n; i++)
        for (int k = 0; k < MR_WF_DATASET_INPUTS + MR_WF_DATASET_OUTPUTS; k++) {
            const float v = k < MR_WF_DATASET_INPUTS ? d.x[i * MR_WF_DATASET_INPUTS + k]
                                                     : d.y[i * MR_WF_DATASET_OUTPUTS + k - MR_WF_DATASET_INPUTS];
            MR_CHECK_MSG(v >= 0.0f && v <= 1.0f, "pair %zu value %d: %g", i, k, (double)v);
        }
    mr_wf_dataset_free(&d);
    // Refused: NULL options or path, negative samples, threads out of range.
    MR_CHECK(mr_wf_pairs_make(NULL, one, NULL) == MR_ERR_INVALID_ARG);
    MR_CHECK(mr_wf_pairs_make(&o, NULL, NULL) == MR_ERR_INVALID_ARG);
    o.samples = -1;
    MR_CHECK(mr_wf_pairs_make(&o, one, NULL) == MR_ERR_INVALID_ARG);
    o.samples = 1;
    o.threads = -1;
    MR_CHECK(mr_wf_pairs_make(&o, one, NULL) == MR_ERR_INVALID_ARG);
    MR_CHECK(strcmp(mr_wf_pair_category_name(MR_WF_PAIR_METAL), "metal") == 0);
    MR_CHECK(mr_wf_pair_category_name(MR_WF_PAIR_CATEGORY_COUNT) == NULL);
}

/* The pool: constant maps give their value times the factor, a missing map its factor; the pool's texels are
 * drawn (30 % of the samples) and its streams are the same for the same seed. */
MR_TEST(texel_pool_and_asset_draws) {
    mr_image *diffuse = NULL;
    MR_CHECK_OK(mr_image_create(4, 4, 3, &diffuse));
    if (diffuse == NULL) return;
    for (size_t i = 0; i < mr_image_value_count(diffuse); i++) diffuse->pixels[i] = 0.5f;
    const double df[3] = {1.0, 0.5, 4.0}, sf[3] = {0.2, 0.3, 0.4};
    mr_wf_texel_pool pool = {0};
    mr_wf_texel_pool_begin_source(&pool, 3);
    MR_CHECK_OK(mr_wf_texel_pool_add_maps(&pool, diffuse, NULL, df, sf, 10));
    mr_wf_texel_pool_end_source(&pool);
    MR_CHECK(pool.count == 10 && pool.sources == 1);
    for (size_t i = 0; i < pool.count; i++) {
        const float *t = pool.texels + 6 * i;
        MR_CHECK(t[0] == 0.5f && t[1] == 0.25f && t[2] == 1.0f); // 0.5 x 4 clamped to 1
        MR_CHECK(t[3] == 0.2f && t[4] == 0.3f && t[5] == 0.4f);
    }
    const mr_wf_label_options labels = small_labels();
    mr_wf_pairs_options o = {0};
    o.samples = 40;
    o.labels = &labels;
    o.pool = &pool;
    mr_wf_pairs_summary s;
    MR_CHECK_OK(mr_wf_pairs_make(&o, mr_test_tmp_path("pool.csv"), &s));
    MR_CHECK(s.categories[MR_WF_PAIR_ASSET] > 0 && s.categories[MR_WF_PAIR_ASSET] < 40);
    mr_wf_texel_pool_free(&pool);
    MR_CHECK(pool.texels == NULL && pool.count == 0);
    mr_wf_texel_pool_free(NULL);
    mr_image_free(diffuse);

    // An asset's spec-gloss texels (the shared Duck), the same twice; a metal-rough asset gives none.
    const char *duck = mr_test_asset_path("specgloss/Duck-pbrSpecularGlossiness/glTF-pbrSpecularGlossiness/Duck.gltf");
    const char *bottle = mr_test_asset_path("metalrough/WaterBottle/glTF/WaterBottle.gltf");
    if (access(duck, R_OK) != 0 || access(bottle, R_OK) != 0) {
        fprintf(stderr, "    (shared assets missing: the asset part is skipped)\n");
        return;
    }
    mr_gltf *asset = NULL;
    MR_CHECK_OK(mr_gltf_load(duck, &asset));
    mr_wf_texel_pool p1 = {0}, p2 = {0};
    int materials = 0;
    MR_CHECK_OK(mr_gltf_add_specgloss_texels(asset, 1, &p1, &materials));
    MR_CHECK(materials >= 1 && p1.count == MR_WF_POOL_SOURCE_TEXELS / (size_t)materials * (size_t)materials);
    MR_CHECK_OK(mr_gltf_add_specgloss_texels(asset, 1, &p2, &materials));
    MR_CHECK(p1.count == p2.count && memcmp(p1.texels, p2.texels, p1.count * 6 * sizeof *p1.texels) == 0);
    for (size_t i = 0; i < 6 * p1.count; i++) MR_CHECK(p1.texels[i] >= 0.0f && p1.texels[i] <= 1.0f);
    mr_gltf_free(asset);
    asset = NULL;
    MR_CHECK_OK(mr_gltf_load(bottle, &asset));
    const size_t before = p1.count;
    MR_CHECK_OK(mr_gltf_add_specgloss_texels(asset, 1, &p1, &materials));
    MR_CHECK(materials == 0 && p1.count == before);
    mr_gltf_free(asset);
    // The same from the files in one call: the Duck's texels as above, its asset handed back (to list its files);
    // the metal-rough asset refused by the caller's label, nothing added and nothing handed back.
    mr_wf_texel_pool p3 = {0};
    asset = NULL;
    MR_CHECK_OK(mr_gltf_add_specgloss_texels_from_file(duck, "--asset duck", 1, &p3, &asset));
    MR_CHECK(asset != NULL && p3.count == p2.count &&
             memcmp(p3.texels, p2.texels, p2.count * 6 * sizeof *p2.texels) == 0);
    mr_gltf_free(asset);
    MR_CHECK(mr_gltf_add_specgloss_texels_from_file(bottle, "--asset wb", 1, &p3, &asset) == MR_ERR_INVALID_ARG);
    MR_CHECK(asset == NULL && p3.count == p2.count);
    MR_CHECK_MSG(strcmp(mr_last_error(), "--asset wb: no material carries KHR_materials_pbrSpecularGlossiness") == 0,
                 "%s", mr_last_error());
    MR_CHECK(mr_gltf_add_specgloss_texels_from_file(mr_test_tmp_path("none.gltf"), NULL, 1, &p3, NULL) == MR_ERR_IO);
    mr_wf_texel_pool_free(&p3);
    mr_wf_texel_pool_free(&p1);
    mr_wf_texel_pool_free(&p2);
}

/* The comparison: the hard cases first, a column per objective, inverse and network; the analytic inverses render
 * an on-manifold black plastic exactly. */
MR_TEST(objectives_compared) {
    mr_image *env = NULL;
    MR_CHECK_OK(mr_wf_label_builtin_env(1, &env));
    if (env == NULL) return;
    mr_mlp *net = NULL;
    MR_CHECK_OK(mr_mlp_create(6, 4, 4, &net));
    const char *weights = mr_test_tmp_path("zero.mlp");
    if (net != NULL) {
        for (int i = 0; i < 6; i++) net->in_std[i] = 1.0f;
        for (int i = 0; i < 4; i++) net->out_std[i] = 1.0f;
        MR_CHECK_OK(mr_mlp_write(net, weights));
    }
    mr_mlp_free(net);
    const mr_wf_label_options labels = small_labels();
    const mr_image *envs[1] = {env};
    mr_wf_compare_options o = {0};
    o.pairs.samples = 3;
    o.pairs.labels = &labels;
    o.envs = envs;
    o.env_count = 1;
    o.weights = &weights;
    o.weight_count = 1;
    mr_wf_compare_table *t = NULL;
    MR_CHECK_OK(mr_wf_pairs_compare(&o, &t));
    if (t != NULL) {
        MR_CHECK(t->texel_count == (size_t)t->hard_case_count + 3 && t->hard_case_count >= 10);
        MR_CHECK(t->column_count == MR_WF_COMPARE_OBJECTIVES + 3 + 1);
        MR_CHECK(strcmp(t->columns[0].name, "labels: linear") == 0);
        MR_CHECK(strcmp(t->columns[MR_WF_COMPARE_OBJECTIVES].name, "weighted") == 0);
        MR_CHECK(strncmp(t->columns[t->column_count - 1].name, "mlp zero.mlp", 12) == 0);
        MR_CHECK(strcmp(t->hard_cases[0].name, "black plastic") == 0);
        MR_CHECK_NEAR(t->columns[MR_WF_COMPARE_OBJECTIVES].ssim[0], 1.0, 1e-3);
        for (int k = 0; k < t->column_count; k++)
            for (size_t i = 0; i < t->texel_count; i++)
                MR_CHECK(t->columns[k].ssim[i] >= -1.0 && t->columns[k].ssim[i] <= 1.0 + 1e-9);
        for (int i = 0; i < t->hard_case_count; i++) MR_CHECK(t->categories[i] == MR_WF_PAIR_UNIFORM);
    }
    mr_wf_compare_table_free(t);
    mr_wf_compare_table_free(NULL);
    o.env_count = 0;
    t = NULL;
    MR_CHECK(mr_wf_pairs_compare(&o, &t) == MR_ERR_INVALID_ARG && t == NULL);
    MR_CHECK(mr_wf_pairs_compare(NULL, &t) == MR_ERR_INVALID_ARG);
    mr_image_free(env);
}

/* mr_wf_pairs_evaluate: on pairs labelled by Eq. 2's own inverse (texels on the manifold, exact dielectrics and
 * metals) the weighted inverse has no error; a network predicting constants has the constants' error. */
MR_TEST(converters_evaluated_against_labels) {
    enum { N = 3 };
    const mr_wf_metal metals[N] = {{{0.8f, 0.2f, 0.1f}, 0.0, 0.0}, {{0.9f, 0.7f, 0.3f}, 1.0, 0.0},
                                   {{0.5f, 0.5f, 0.5f}, 0.0, 0.0}};
    float x[N * MR_WF_DATASET_INPUTS], y[N * MR_WF_DATASET_OUTPUTS];
    mr_wf_options wo = mr_wf_options_default();
    for (int i = 0; i < N; i++) {
        mr_wf_spec s;
        MR_CHECK_OK(mr_wf_metal_to_spec(&metals[i], &wo, &s, NULL));
        for (int c = 0; c < 3; c++) {
            x[MR_WF_DATASET_INPUTS * i + c] = (float)s.diffuse[c];
            x[MR_WF_DATASET_INPUTS * i + 3 + c] = (float)s.specular[c];
            y[MR_WF_DATASET_OUTPUTS * i + c] = (float)metals[i].albedo[c];
        }
        y[MR_WF_DATASET_OUTPUTS * i + 3] = (float)metals[i].metallic;
    }
    mr_wf_dataset d = {x, y, N, 0};
    mr_mlp *net = NULL;
    MR_CHECK_OK(mr_mlp_create(6, 4, 4, &net));
    if (net == NULL) return;
    for (int i = 0; i < 6; i++) net->in_std[i] = 1.0f;
    for (int i = 0; i < 4; i++) {
        net->out_std[i] = 1.0f;
        net->out_mean[i] = 0.5f; // zero weights: every answer is (0.5, 0.5, 0.5), metallic 0.5
    }
    mr_wf_method_error e[MR_WF_EVALUATED_METHODS];
    MR_CHECK_OK(mr_wf_pairs_evaluate(net, &d, 0, e));
    MR_CHECK(strcmp(e[0].name, "mlp") == 0 && strcmp(e[1].name, "weighted") == 0 && strcmp(e[3].name, "khronos") == 0);
    MR_CHECK_NEAR(e[0].metallic_rmse, 0.5, 1e-6);
    MR_CHECK_NEAR(e[0].metallic_max, 0.5, 1e-6);
    MR_CHECK(e[1].albedo_rmse < 1e-5 && e[1].metallic_max < 1e-5);
    mr_wf_method_error e2[MR_WF_EVALUATED_METHODS];
    MR_CHECK_OK(mr_wf_pairs_evaluate(net, &d, 2, e2)); // any thread count, the same errors
    for (int m = 0; m < MR_WF_EVALUATED_METHODS; m++)
        MR_CHECK(e2[m].albedo_rmse == e[m].albedo_rmse && e2[m].metallic_max == e[m].metallic_max);
    MR_CHECK(mr_wf_pairs_evaluate(NULL, &d, 0, e) == MR_ERR_INVALID_ARG);
    mr_mlp_free(net);
}

MR_TEST_MAIN(MR_TEST_ENTRY(pairs_file_made_and_read_back), MR_TEST_ENTRY(texel_pool_and_asset_draws),
             MR_TEST_ENTRY(objectives_compared), MR_TEST_ENTRY(converters_evaluated_against_labels))
