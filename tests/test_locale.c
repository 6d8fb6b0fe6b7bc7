/*
 * test_locale.c — text files are written and read in the C locale whatever the host program's (src/c_locale.h).
 *
 * The program switches itself to a decimal-comma locale (de_DE.UTF-8; built with localedef into a scratch
 * LOCPATH when the system has not generated it: scripts/install-deps.sh installs Debian's `locales` data), checks
 * that printf now writes "0,5", and then round-trips a sweep, a weight file, summary.json, a parameter assignment
 * and a dataset through the library. After every call the host's locale must still be the decimal-comma one.
 */
#include <locale.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "matremap.h"
#include "nn/mlp.h"
#include "remap/sweep.h"
#include "report/report.h"
#include "workflow/dataset.h"

#include "harness.h"

static char tmpdir[64];

static const char *tmp_path(const char *name) {
    static char paths[8][256];
    static int next;
    char *p = paths[next++ % 8];
    snprintf(p, sizeof paths[0], "%s/%s", tmpdir, name);
    return p;
}

/* A digit, a comma and a digit: a number written with a decimal comma (our files separate fields with ", "
 * in JSON and "," in CSV, so a CSV row is checked field by field instead). */
static int has_decimal_comma_json(const char *text) {
    for (const char *p = text; p[0] && p[1] && p[2]; p++)
        if (p[0] >= '0' && p[0] <= '9' && p[1] == ',' && p[2] >= '0' && p[2] <= '9') return 1;
    return 0;
}

/* The host's locale is still the decimal-comma one. */
static int host_locale_kept(void) {
    char buf[16];
    snprintf(buf, sizeof buf, "%.1f", 0.5);
    return strcmp(buf, "0,5") == 0;
}

/* Switch the process to a decimal-comma locale, generating one if the system has none. 1 on success. */
static int enter_decimal_comma_locale(void) {
    static const char *const names[] = {"de_DE.UTF-8", "de_DE.utf8", "fr_FR.UTF-8", "fr_FR.utf8"};
    for (size_t k = 0; k < sizeof names / sizeof names[0]; k++)
        if (setlocale(LC_ALL, names[k]) != NULL && host_locale_kept()) return 1;
    char command[256];
    snprintf(command, sizeof command, "localedef -i de_DE -f UTF-8 %s/de_DE.UTF-8 >/dev/null 2>&1", tmpdir);
    if (system(command) != 0) return 0;
    setenv("LOCPATH", tmpdir, 1);
    return setlocale(LC_ALL, "de_DE.UTF-8") != NULL && host_locale_kept();
}

MR_TEST(the_host_locale_writes_a_decimal_comma) {
    MR_CHECK_MSG(host_locale_kept(), "setlocale(LC_ALL, de_DE.UTF-8) failed: neither generated nor buildable with "
                                     "localedef (Debian package `locales`, scripts/install-deps.sh)");
}

MR_TEST(a_sweep_writes_and_resumes_in_the_c_locale) {
    mr_sweep_spec spec;
    mr_sweep_spec_init(&spec, mr_brdf_find("ggx"), mr_brdf_find("ward"));
    MR_CHECK_OK(mr_sweep_parse_axis(spec.source, "alpha=0.15:0.35:2", &spec.axes[0]));
    spec.axis_count = 1;
    MR_CHECK(host_locale_kept());
    spec.scene.size = 32;
    const char *path = tmp_path("sweep.csv");
    mr_sweep_options o = {0};
    o.threads = 1;
    mr_sweep_summary s;
    MR_CHECK_OK(mr_sweep_run(&spec, path, &o, &s));
    MR_CHECK(s.computed == 2);
    MR_CHECK(host_locale_kept());
    char *text = mr_test_read_file(path, NULL);
    MR_CHECK(text != NULL && strstr(text, "0.15") != NULL && strstr(text, "0,15") == NULL);
    free(text);
    // Resuming reads every row back: a row parsed under the comma locale would be torn at its first number.
    o.resume = 1;
    MR_CHECK_OK(mr_sweep_run(&spec, path, &o, &s));
    MR_CHECK_MSG(s.already_done == 2 && s.computed == 0, "resume found %ld rows, computed %ld", s.already_done,
                 s.computed);
    MR_CHECK(host_locale_kept());
}

MR_TEST(a_weight_file_round_trips_exactly) {
    mr_mlp *net = NULL, *back = NULL;
    MR_CHECK_OK(mr_mlp_create(3, 5, 2, &net));
    if (net == NULL) return;
    for (size_t q = 0; q < net->data_count; q++) net->data[q] = 0.5f + 0.001f * (float)q;
    const char *path = tmp_path("net.mlp");
    MR_CHECK_OK(mr_mlp_write(net, path));
    MR_CHECK(host_locale_kept());
    MR_CHECK_OK(mr_mlp_read(path, &back));
    MR_CHECK(host_locale_kept());
    MR_CHECK(back != NULL && back->data_count == net->data_count &&
             memcmp(back->data, net->data, net->data_count * sizeof *net->data) == 0);
    mr_mlp_free(net);
    mr_mlp_free(back);
}

MR_TEST(summary_json_holds_json_numbers) {
    const char *views[1] = {"front"}, *ref_renders[1] = {"a.png"}, *renders[1] = {"b.png"}, *maps[1] = {"m.png"};
    const double ssim[1] = {0.987654}, rmse[1] = {0.125};
    mr_report_material materials[2];
    memset(materials, 0, sizeof materials);
    materials[0].label = "reference";
    materials[0].renders = ref_renders;
    materials[0].seconds = 1.5;
    materials[1].label = "candidate";
    materials[1].renders = renders;
    materials[1].ssim_maps = maps;
    materials[1].ssim = ssim;
    materials[1].relative_rmse = rmse;
    materials[1].seconds = 0.25;
    mr_report r = {"locale", NULL, 1, views, 2, materials, NULL};
    char dir[256];
    snprintf(dir, sizeof dir, "%s/report", tmpdir);
    mkdir(dir, 0700);
    MR_CHECK_OK(mr_report_write(&r, dir));
    MR_CHECK(host_locale_kept());
    char path[300];
    snprintf(path, sizeof path, "%s/summary.json", dir);
    char *text = mr_test_read_file(path, NULL);
    MR_CHECK(text != NULL && strstr(text, "0.987654") != NULL);
    MR_CHECK_MSG(text != NULL && !has_decimal_comma_json(text), "summary.json: %s", text ? text : "(missing)");
    free(text);
}

MR_TEST(a_parameter_assignment_reads_a_decimal_point) {
    const mr_brdf_model *ggx = mr_brdf_find("ggx");
    double values[MR_BRDF_MAX_VALUES];
    mr_brdf_default_values(ggx, values);
    MR_CHECK_OK(mr_brdf_parse_assignment(ggx, "alpha=0.25", values));
    MR_CHECK_NEAR(values[mr_brdf_param_offset(ggx, mr_brdf_param_index(ggx, "alpha"))], 0.25, 0.0);
    MR_CHECK_OK(mr_brdf_parse_assignment(ggx, "f0=0.5,0.25,0.125", values));
    MR_CHECK_NEAR(values[mr_brdf_param_offset(ggx, mr_brdf_param_index(ggx, "f0")) + 2], 0.125, 0.0);
    MR_CHECK(host_locale_kept());
}

MR_TEST(a_dataset_reads_its_sweep) {
    mr_sweep_spec spec;
    mr_sweep_spec_init(&spec, mr_brdf_find("ggx"), mr_brdf_find("ggx-metallic"));
    MR_CHECK_OK(mr_sweep_parse_axis(spec.source, "alpha=0.25:0.25:1", &spec.axes[0]));
    spec.axis_count = 1;
    spec.scene.size = 32;
    MR_CHECK_OK(mr_brdf_parse_assignment(spec.source, "diffuse=0.5", spec.source_values));
    const char *path = tmp_path("metal.csv");
    mr_sweep_options o = {0};
    o.threads = 1;
    MR_CHECK_OK(mr_sweep_run(&spec, path, &o, NULL));
    mr_wf_dataset d;
    mr_wf_dataset_options keep = {1};
    const char *paths[1] = {path};
    MR_CHECK_OK(mr_wf_dataset_load(paths, 1, &keep, &d));
    MR_CHECK(host_locale_kept());
    MR_CHECK_MSG(d.n == 1, "%zu pairs", d.n);
    // The inputs are the source's diffuse and F0: fractions that a decimal-comma strtod would cut to 0.
    if (d.n == 1) {
        MR_CHECK_NEAR(d.x[0], 0.5, 1e-6);
        MR_CHECK_NEAR(d.x[3], 0.04, 1e-6);
    }
    mr_wf_dataset_free(&d);
}

int main(int argc, char **argv) {
    strcpy(tmpdir, "/tmp/mr_test_locale.XXXXXX");
    if (mkdtemp(tmpdir) == NULL) {
        perror("test_locale: mkdtemp");
        return 1;
    }
    enter_decimal_comma_locale();
    static const mr_test_case cases[] = {
        MR_TEST_ENTRY(the_host_locale_writes_a_decimal_comma),
        MR_TEST_ENTRY(a_sweep_writes_and_resumes_in_the_c_locale),
        MR_TEST_ENTRY(a_weight_file_round_trips_exactly),
        MR_TEST_ENTRY(summary_json_holds_json_numbers),
        MR_TEST_ENTRY(a_parameter_assignment_reads_a_decimal_point),
        MR_TEST_ENTRY(a_dataset_reads_its_sweep),
    };
    int rc = mr_test_run_all(cases, (int)(sizeof cases / sizeof cases[0]), argc, argv);
    char command[128];
    snprintf(command, sizeof command, "rm -rf %s", tmpdir);
    if (system(command) != 0) fprintf(stderr, "test_locale: could not remove %s\n", tmpdir);
    return rc;
}
