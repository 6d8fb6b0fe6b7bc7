/*
 * test_sweep.c — parameter sweeps (src/remap/sweep.h): grid order, endpoints and log spacing; random samples
 * that depend only on (seed, index) and stay in bounds; exact CSV round trips; resume: header mismatches
 * refused with the file untouched, torn last lines cut, unsorted rows sorted at the end, a finished file left
 * alone, a write cut short by a full disk (a file-size limit) taken back; the same file for 1 and 2 threads.
 */
#include <locale.h>
#include <omp.h>
#include <signal.h>
#include <sys/resource.h>
#include <stdint.h>
#include <unistd.h>

#include "harness.h"
#include "matremap.h"
#include "remap/sweep.h"

static char tmpdir[64];

static void cleanup(void) {
    const char *names[] = {"threads1.csv", "threads2.csv", "mismatch.csv", "reference.csv", "torn.csv",
                           "progress.csv", "limit_ref.csv", "limit.csv"};
    char path[256];
    for (size_t k = 0; k < sizeof names / sizeof names[0]; k++) {
        snprintf(path, sizeof path, "%s/%s", tmpdir, names[k]);
        unlink(path);
    }
    rmdir(tmpdir);
}

static const char *tmp_path(const char *name) {
    static char path[4][256];
    static int next;
    char *p = path[next++ % 4];
    if (tmpdir[0] == '\0') {
        strcpy(tmpdir, "/tmp/mr_test_sweep.XXXXXX");
        if (mkdtemp(tmpdir) == NULL)
            strcpy(tmpdir, "/tmp");
        else
            atexit(cleanup);
    }
    snprintf(p, sizeof path[0], "%s/%s", tmpdir, name);
    return p;
}

static void write_text(const char *path, const char *text, size_t length) {
    FILE *f = fopen(path, "wb");
    if (f == NULL) return;
    fwrite(text, 1, length, f);
    fclose(f);
}

/* The file without its "# command:" line and without each row's last column (seconds, the only value that
 * may differ between runs). malloc'ed. */
static char *comparable(const char *text) {
    char *out = malloc(strlen(text) + 1), *o = out;
    for (const char *line = text; *line;) {
        const char *nl = strchr(line, '\n');
        size_t len = nl ? (size_t)(nl - line) : strlen(line);
        if (strncmp(line, "# command:", 10) != 0) {
            size_t keep = len;
            if (line[0] != '#' && strncmp(line, "index,", 6) != 0)
                while (keep > 0 && line[keep - 1] != ',') keep--;
            memcpy(o, line, keep);
            o += keep;
            *o++ = '\n';
        }
        line += len + (nl ? 1 : 0);
    }
    *o = '\0';
    return out;
}

static mr_sweep_spec ggx_to_ward(int size) {
    mr_sweep_spec spec;
    mr_sweep_spec_init(&spec, mr_brdf_find("ggx"), mr_brdf_find("ward-balanced"));
    spec.scene.size = size;
    return spec;
}

static mr_sweep_spec random_spec(long count, unsigned long long seed, int size) {
    mr_sweep_spec spec = ggx_to_ward(size);
    spec.sampling = MR_SWEEP_RANDOM;
    spec.random_count = count;
    spec.seed = seed;
    return spec;
}

static mr_status run(const mr_sweep_spec *spec, const char *path, int resume, int threads, mr_sweep_summary *s) {
    mr_sweep_options o = {0};
    o.resume = resume;
    o.threads = threads;
    o.command_line = "test_sweep";
    return mr_sweep_run(spec, path, &o, s);
}

MR_TEST(grid_is_cartesian_first_axis_slowest_with_exact_endpoints) {
    mr_sweep_spec spec = ggx_to_ward(0);
    MR_CHECK_OK(mr_sweep_parse_axis(spec.source, "alpha=0.1:0.5:3", &spec.axes[0]));
    MR_CHECK_OK(mr_sweep_parse_axis(spec.source, "f0=0.2:0.7:2", &spec.axes[1]));
    spec.axis_count = 2;
    MR_CHECK(mr_sweep_sample_count(&spec) == 6);
    const double alphas[3] = {0.1, 0.3, 0.5}, f0s[2] = {0.2, 0.7};
    const mr_brdf_model *m = spec.source;
    int a = mr_brdf_param_offset(m, mr_brdf_param_index(m, "alpha"));
    int f = mr_brdf_param_offset(m, mr_brdf_param_index(m, "f0"));
    int d = mr_brdf_param_offset(m, mr_brdf_param_index(m, "diffuse"));
    for (long i = 0; i < 6; i++) {
        double v[MR_BRDF_MAX_VALUES];
        MR_CHECK_OK(mr_sweep_sample(&spec, i, v));
        MR_CHECK_NEAR(v[a], alphas[i / 2], 1e-15);
        for (int c = 0; c < 3; c++) MR_CHECK(v[f + c] == f0s[i % 2]); /* RGB: every channel, endpoints exact */
        MR_CHECK(v[d] == spec.source_values[d]);                      /* not on an axis: the fixed value */
    }
    double v[MR_BRDF_MAX_VALUES];
    MR_CHECK_OK(mr_sweep_sample(&spec, 5, v));
    MR_CHECK(v[a] == 0.5); /* hi exactly, not lo + 1.0 * (hi - lo) */
    MR_CHECK(mr_sweep_sample(&spec, 6, v) == MR_ERR_INVALID_ARG);
    MR_CHECK(mr_sweep_sample(&spec, -1, v) == MR_ERR_INVALID_ARG);

    // A grid overrides a fixed value of the same parameter; n = 1 samples lo.
    spec.source_values[a] = 0.9;
    MR_CHECK_OK(mr_sweep_parse_axis(spec.source, "alpha=0.25:0.5:1", &spec.axes[0]));
    MR_CHECK(mr_sweep_sample_count(&spec) == 2);
    MR_CHECK_OK(mr_sweep_sample(&spec, 1, v));
    MR_CHECK(v[a] == 0.25);
}

MR_TEST(grid_log_spacing_is_geometric) {
    mr_sweep_spec spec = ggx_to_ward(0);
    MR_CHECK_OK(mr_sweep_parse_axis(spec.source, "alpha=0.001:1:4:log", &spec.axes[0]));
    MR_CHECK(spec.axes[0].log_scale == 1);
    spec.axis_count = 1;
    const double expected[4] = {0.001, 0.01, 0.1, 1.0};
    int a = mr_brdf_param_offset(spec.source, mr_brdf_param_index(spec.source, "alpha"));
    for (long i = 0; i < 4; i++) {
        double v[MR_BRDF_MAX_VALUES];
        MR_CHECK_OK(mr_sweep_sample(&spec, i, v));
        MR_CHECK_NEAR(v[a] / expected[i], 1.0, 1e-13);
        if (i == 0 || i == 3) MR_CHECK(v[a] == expected[i]);
    }
}

MR_TEST(grid_errors_name_the_bad_value) {
    const mr_brdf_model *ggx = mr_brdf_find("ggx");
    mr_sweep_axis axis = {0};
    struct {
        const char *text, *message;
    } cases[] = {
        {"alpha", "expected name=lo:hi:n"},
        {"alpha=0.1:0.5", "expected name=lo:hi:n"},
        {"alpha=0.1:x:3", "expected name=lo:hi:n"},
        {"alpha=0.1:0.5:2.5", "expected name=lo:hi:n"},
        {"rough=0:1:3", "no parameter 'rough' (valid: alpha, f0, diffuse)"},
        {"alpha=0.1:0.5:0", "n = 0, expected at least 1"},
        {"alpha=0.5:0.1:3", "lo 0.5 is greater than hi 0.1"},
        {"alpha=0.1:2:3", "2 is outside alpha's range"},
        {"f0=0:1:3:log", "log spacing needs lo > 0"},
        {"alpha=0.1:0.5:3:cubic", "unknown spacing 'cubic'"},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        mr_status s = mr_sweep_parse_axis(ggx, cases[k].text, &axis);
        MR_CHECK_MSG(s == MR_ERR_INVALID_ARG && strstr(mr_last_error(), cases[k].message) != NULL &&
                         strstr(mr_last_error(), cases[k].text) != NULL,
                     "'%s' -> %s: %s", cases[k].text, mr_status_str(s), mr_last_error());
    }
    const mr_brdf_model *ward = mr_brdf_find("ward-balanced");
    MR_CHECK(mr_sweep_parse_axis(ward, "trim=0:1:3", &axis) == MR_ERR_INVALID_ARG);
    MR_CHECK(strstr(mr_last_error(), "switch") != NULL);
    MR_CHECK_OK(mr_sweep_parse_axis(ward, "trim=0:1:2", &axis));

    // The same parameter on two axes, and a grid without axes, are refused by the spec check.
    mr_sweep_spec spec = ggx_to_ward(0);
    MR_CHECK(mr_sweep_check(&spec) == MR_ERR_INVALID_ARG);
    MR_CHECK_OK(mr_sweep_parse_axis(spec.source, "alpha=0.1:0.5:3", &spec.axes[0]));
    spec.axes[1] = spec.axes[0];
    spec.axis_count = 2;
    MR_CHECK(mr_sweep_check(&spec) == MR_ERR_INVALID_ARG && strstr(mr_last_error(), "two grid axes") != NULL);
    // A warm start for every sample would be hidden from the file's header: refused.
    spec.axis_count = 1;
    MR_CHECK_OK(mr_sweep_check(&spec));
    spec.remap.initial_values = spec.target_values;
    MR_CHECK(mr_sweep_check(&spec) == MR_ERR_INVALID_ARG && strstr(mr_last_error(), "initial_values") != NULL);
}

MR_TEST(random_samples_depend_only_on_seed_and_index_and_stay_in_bounds) {
    mr_sweep_spec spec = random_spec(1000, 7, 0);
    const mr_brdf_model *m = spec.source;
    int d = mr_brdf_param_index(m, "diffuse");
    spec.held = 1u << d; /* diffuse given by the user: held */
    spec.source_values[mr_brdf_param_offset(m, d)] = 0.25;
    mr_sweep_spec small = spec, other_seed = spec;
    small.random_count = 50;
    other_seed.seed = 8;
    int a = mr_brdf_param_offset(m, mr_brdf_param_index(m, "alpha"));
    int f = mr_brdf_param_offset(m, mr_brdf_param_index(m, "f0"));
    const mr_brdf_param *alpha = &m->params[mr_brdf_param_index(m, "alpha")];
    MR_CHECK(alpha->flags & MR_PARAM_LOG_SCALE);
    int below_geometric_mean = 0, channels_differ = 0;
    double geometric_mean = sqrt(alpha->min_value * alpha->max_value);
    for (long i = 0; i < 1000; i++) {
        double v[MR_BRDF_MAX_VALUES], again[MR_BRDF_MAX_VALUES];
        MR_CHECK_OK(mr_sweep_sample(&spec, i, v));
        MR_CHECK_OK(mr_sweep_sample(&spec, i, again));
        MR_CHECK(memcmp(v, again, sizeof(double) * (size_t)mr_brdf_value_count(m)) == 0);
        if (i < 50) {
            MR_CHECK_OK(mr_sweep_sample(&small, i, again)); /* the sample count does not matter */
            MR_CHECK(memcmp(v, again, sizeof(double) * (size_t)mr_brdf_value_count(m)) == 0);
            MR_CHECK_OK(mr_sweep_sample(&other_seed, i, again));
            MR_CHECK(v[a] != again[a]);
        }
        for (int p = 0; p < m->param_count; p++)
            for (int c = 0; c < m->params[p].channels; c++) {
                double x = v[mr_brdf_param_offset(m, p) + c];
                MR_CHECK(x >= m->params[p].min_value && x <= m->params[p].max_value);
            }
        for (int c = 0; c < 3; c++) MR_CHECK(v[mr_brdf_param_offset(m, d) + c] == (c == 0 ? 0.25 : 0.0));
        below_geometric_mean += v[a] < geometric_mean;
        channels_differ += v[f] != v[f + 1];
    }
    // Log-uniform: half the draws below the geometric mean of the range (uniform would put ~1 % there).
    MR_CHECK_MSG(below_geometric_mean > 430 && below_geometric_mean < 570, "%d of 1000", below_geometric_mean);
    MR_CHECK(channels_differ == 1000); /* RGB channels drawn independently */

    // Nothing left to randomise is an error.
    spec.held = (1u << m->param_count) - 1;
    MR_CHECK(mr_sweep_check(&spec) == MR_ERR_INVALID_ARG && strstr(mr_last_error(), "randomise") != NULL);
}

MR_TEST(rows_round_trip_exactly) {
    mr_sweep_spec spec = random_spec(100, 1, 0);
    mr_sweep_row row;
    memset(&row, 0, sizeof row);
    row.index = 99;
    const double awkward[] = {0.1, 1.0 / 3.0, 5e-324, 1e-300, 0.0, 1.0, 0.12345678901234567, 2.5e-5};
    for (int k = 0; k < MR_BRDF_MAX_VALUES; k++) {
        row.source[k] = awkward[k % 8];
        row.target[k] = awkward[(k + 3) % 8] * 7.0;
    }
    row.rmse = 0.0031;
    row.relative_rmse = HUGE_VAL; /* a black source: the library reports infinity */
    row.ssim = 0.99999999999999989;
    row.outcome = MR_FIT_LOCAL_MINIMUM;
    row.renders = 123456789;
    row.seconds = 0.0123;
    char line[MR_SWEEP_MAX_LINE], again[MR_SWEEP_MAX_LINE];
    size_t length = 0, length2 = 0;
    MR_CHECK_OK(mr_sweep_format_row(&spec, &row, line, sizeof line, &length));
    MR_CHECK(length == strlen(line) && line[length - 1] == '\n');
    MR_CHECK(strncmp(line, "99,0.10000000000000001,", 23) == 0);
    MR_CHECK(strstr(line, ",local-minimum,123456789,") != NULL);
    mr_sweep_row back;
    MR_CHECK_OK(mr_sweep_parse_row(&spec, line, length, &back));
    int ns = mr_brdf_value_count(spec.source), nt = mr_brdf_value_count(spec.target);
    MR_CHECK(back.index == 99 && back.outcome == MR_FIT_LOCAL_MINIMUM && back.renders == 123456789);
    MR_CHECK(memcmp(back.source, row.source, sizeof(double) * (size_t)ns) == 0);
    MR_CHECK(memcmp(back.target, row.target, sizeof(double) * (size_t)nt) == 0);
    MR_CHECK(back.rmse == row.rmse && back.relative_rmse == row.relative_rmse && back.ssim == row.ssim &&
             back.seconds == row.seconds);
    MR_CHECK_OK(mr_sweep_format_row(&spec, &back, again, sizeof again, &length2));
    MR_CHECK(length2 == length && strcmp(line, again) == 0);
    MR_CHECK(mr_sweep_format_row(&spec, &row, again, 40, NULL) == MR_ERR_INVALID_ARG);

    // A decimal-comma process locale must not leak into the file (checked where such a locale is installed).
    const char *comma_locales[] = {"de_DE.UTF-8", "de_DE.utf8", "fr_FR.UTF-8", "fr_FR.utf8"};
    for (size_t k = 0; k < sizeof comma_locales / sizeof comma_locales[0]; k++) {
        if (setlocale(LC_NUMERIC, comma_locales[k]) == NULL) continue;
        MR_CHECK_OK(mr_sweep_format_row(&spec, &row, again, sizeof again, NULL));
        MR_CHECK(strcmp(line, again) == 0);
        MR_CHECK_OK(mr_sweep_parse_row(&spec, line, length, &back));
        MR_CHECK(back.rmse == row.rmse);
        setlocale(LC_NUMERIC, "C");
        break;
    }

    // Malformed rows are refused with the column named.
    struct {
        const char *line, *message;
    } bad[] = {
        {"1,2,3\n", "columns"},
        {"100,", "index '100'"},
        {"-1,", "index '-1'"},
        {"x,", "index 'x'"},
    };
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++) {
        mr_status s = mr_sweep_parse_row(&spec, bad[k].line, strlen(bad[k].line), &back);
        MR_CHECK_MSG(s == MR_ERR_FORMAT && strstr(mr_last_error(), bad[k].message) != NULL, "'%s': %s",
                     bad[k].line, mr_last_error());
    }
    char edited[MR_SWEEP_MAX_LINE];
    snprintf(edited, sizeof edited, "%.*s,extra\n", (int)length - 1, line);
    MR_CHECK(mr_sweep_parse_row(&spec, edited, strlen(edited), &back) == MR_ERR_FORMAT);
    snprintf(edited, sizeof edited, "%s", line);
    char *outcome = strstr(edited, "local-minimum");
    memcpy(outcome, "local-maximum", 13);
    MR_CHECK(mr_sweep_parse_row(&spec, edited, strlen(edited), &back) == MR_ERR_FORMAT);
    MR_CHECK(strstr(mr_last_error(), "local-maximum") != NULL);
    snprintf(edited, sizeof edited, "%s", line);
    edited[3] = 'z'; /* 0.10000000000000001 -> 0.z0000000000000001 */
    MR_CHECK(mr_sweep_parse_row(&spec, edited, strlen(edited), &back) == MR_ERR_FORMAT);
}

MR_TEST(one_and_two_threads_write_the_same_file) {
    mr_sweep_spec spec = random_spec(6, 11, 32);
    const char *one = tmp_path("threads1.csv"), *two = tmp_path("threads2.csv");
    unlink(one);
    unlink(two);
    mr_sweep_summary s1, s2;
    MR_CHECK_OK(run(&spec, one, 0, 1, &s1));
    MR_CHECK_OK(run(&spec, two, 0, 2, &s2));
    MR_CHECK(s1.computed == 6 && s2.computed == 6 && s1.threads == 1 && s2.threads == 2);
    char *a = mr_test_read_file(one, NULL), *b = mr_test_read_file(two, NULL);
    MR_CHECK(a != NULL && b != NULL);
    if (a && b) {
        char *ca = comparable(a), *cb = comparable(b);
        MR_CHECK_MSG(strcmp(ca, cb) == 0, "files differ:\n%s\n---\n%s", ca, cb);
        MR_CHECK(strstr(a, "# sampling: random=6 seed=11 over alpha,f0,diffuse\n") != NULL);
        MR_CHECK(strstr(a, "\nindex,alpha,f0_r,f0_g,f0_b,diffuse_r,diffuse_g,diffuse_b,to_diffuse_r,") != NULL);
        // Rows are in index order at the end.
        const char *row = strstr(a, "\n0,");
        for (int i = 1; row && i < 6; i++) {
            char want[16];
            snprintf(want, sizeof want, "\n%d,", i);
            const char *next = strstr(row + 1, want);
            MR_CHECK(next != NULL && next > row);
            row = next;
        }
        free(ca);
        free(cb);
    }
    free(a);
    free(b);

    // The same for a grid (ggx -> ward-balanced, the grid of the docs' example).
    spec = ggx_to_ward(32);
    MR_CHECK_OK(mr_sweep_parse_axis(spec.source, "alpha=0.05:0.4:3:log", &spec.axes[0]));
    MR_CHECK_OK(mr_sweep_parse_axis(spec.source, "f0=0.04:0.9:2", &spec.axes[1]));
    spec.axis_count = 2;
    unlink(one);
    unlink(two);
    MR_CHECK_OK(run(&spec, one, 0, 1, NULL));
    MR_CHECK_OK(run(&spec, two, 0, 2, NULL));
    a = mr_test_read_file(one, NULL);
    b = mr_test_read_file(two, NULL);
    if (a && b) {
        char *ca = comparable(a), *cb = comparable(b);
        MR_CHECK(strcmp(ca, cb) == 0);
        free(ca);
        free(cb);
    }
    free(a);
    free(b);
}

MR_TEST(an_existing_file_is_never_overwritten_and_a_mismatching_one_never_touched) {
    mr_sweep_spec spec = random_spec(3, 5, 16);
    const char *path = tmp_path("mismatch.csv");
    unlink(path);
    MR_CHECK_OK(run(&spec, path, 0, 1, NULL));
    char *before = mr_test_read_file(path, NULL);
    MR_CHECK(before != NULL);

    MR_CHECK(run(&spec, path, 0, 1, NULL) == MR_ERR_INVALID_ARG);
    MR_CHECK(strstr(mr_last_error(), "already exists") != NULL);

    mr_sweep_spec other = spec;
    other.seed = 6;
    MR_CHECK(run(&other, path, 1, 1, NULL) == MR_ERR_INVALID_ARG);
    MR_CHECK_MSG(strstr(mr_last_error(), "line 6 is '# sampling: random=3 seed=5") != NULL &&
                     strstr(mr_last_error(), "this run's is '# sampling: random=3 seed=6") != NULL,
                 "%s", mr_last_error());
    other = spec;
    other.target_values[mr_brdf_param_offset(other.target, mr_brdf_param_index(other.target, "trim"))] = 0.0;
    MR_CHECK(run(&other, path, 1, 1, NULL) == MR_ERR_INVALID_ARG && strstr(mr_last_error(), "line 3") != NULL);
    other = spec;
    other.scene.size = 32;
    MR_CHECK(run(&other, path, 1, 1, NULL) == MR_ERR_INVALID_ARG && strstr(mr_last_error(), "line 5") != NULL);
    other = spec;
    other.remap.strategy = MR_REMAP_SINGLE;
    MR_CHECK(run(&other, path, 1, 1, NULL) == MR_ERR_INVALID_ARG && strstr(mr_last_error(), "line 4") != NULL);

    // Only the command line may differ; a finished file is left exactly as it is.
    mr_sweep_options o = {0};
    o.resume = 1;
    o.command_line = "another command\nline";
    mr_sweep_summary s;
    MR_CHECK_OK(mr_sweep_run(&spec, path, &o, &s));
    MR_CHECK(s.computed == 0 && s.already_done == 3 && s.sorted == 0 && s.truncated_bytes == 0);
    char *after = mr_test_read_file(path, NULL);
    MR_CHECK(after != NULL && before != NULL && strcmp(before, after) == 0);
    free(after);

    // A row whose source values are not this sweep's sample, or a sample twice, is a format error.
    char *edited = malloc(strlen(before) + 512);
    char *row1 = strstr(before, "\n1,");
    MR_CHECK(row1 != NULL);
    if (row1 != NULL && edited != NULL) {
        size_t head = (size_t)(row1 - before) + 1;
        memcpy(edited, before, head);
        strcpy(edited + head, "1,0.5");
        strcat(edited, strchr(row1 + 3, ','));
        write_text(path, edited, strlen(edited));
        MR_CHECK(run(&spec, path, 1, 1, NULL) == MR_ERR_FORMAT && strstr(mr_last_error(), "line 11") != NULL);
        char *rows0 = strstr(before, "\n0,") + 1, *end0 = strchr(rows0, '\n') + 1;
        memcpy(edited, before, strlen(before) + 1);
        strncat(edited, rows0, (size_t)(end0 - rows0));
        write_text(path, edited, strlen(edited));
        MR_CHECK(run(&spec, path, 1, 1, NULL) == MR_ERR_FORMAT && strstr(mr_last_error(), "second time") != NULL);
    }
    free(edited);
    free(before);
}

MR_TEST(resume_cuts_a_torn_line_and_ends_with_the_uninterrupted_file) {
    mr_sweep_spec spec = random_spec(6, 3, 16);
    const char *reference = tmp_path("reference.csv"), *path = tmp_path("torn.csv");
    unlink(reference);
    MR_CHECK_OK(run(&spec, reference, 0, 2, NULL));
    char *full = mr_test_read_file(reference, NULL);
    MR_CHECK(full != NULL);
    if (full == NULL) return;
    // The header, rows 4 and 1 (out of order, as threads finish), and half of row 2: a kill during a write.
    const char *rows = strstr(full, "\n0,") + 1;
    const char *r[6];
    for (int i = 0; i < 6; i++) {
        char want[16];
        snprintf(want, sizeof want, "%s%d,", i ? "\n" : "", i);
        r[i] = i ? strstr(rows, want) + 1 : rows;
    }
    char *torn = malloc(strlen(full) + 1);
    size_t n = (size_t)(rows - full);
    memcpy(torn, full, n);
    size_t len4 = (size_t)(strchr(r[4], '\n') + 1 - r[4]), len1 = (size_t)(strchr(r[1], '\n') + 1 - r[1]);
    memcpy(torn + n, r[4], len4);
    n += len4;
    memcpy(torn + n, r[1], len1);
    n += len1;
    memcpy(torn + n, r[2], 17);
    n += 17;
    unlink(path);
    write_text(path, torn, n);

    mr_sweep_summary s;
    MR_CHECK_OK(run(&spec, path, 1, 2, &s));
    MR_CHECK(s.already_done == 2 && s.computed == 4 && s.truncated_bytes == 17 && s.sorted == 1 && s.total == 6);
    char *resumed = mr_test_read_file(path, NULL);
    MR_CHECK(resumed != NULL);
    if (resumed != NULL) {
        char *a = comparable(full), *b = comparable(resumed);
        MR_CHECK_MSG(strcmp(a, b) == 0, "resumed file differs:\n%s\n---\n%s", a, b);
        free(a);
        free(b);
    }

    // A torn line alone (no complete row) and an empty file (killed before the header) resume too.
    write_text(path, torn, (size_t)(rows - full) + 5);
    MR_CHECK_OK(run(&spec, path, 1, 1, &s));
    MR_CHECK(s.computed == 6 && s.truncated_bytes == 5);
    write_text(path, "", 0);
    MR_CHECK_OK(run(&spec, path, 1, 1, &s));
    MR_CHECK(s.computed == 6);
    free(resumed);
    resumed = mr_test_read_file(path, NULL);
    if (resumed != NULL) {
        char *a = comparable(full), *b = comparable(resumed);
        MR_CHECK(strcmp(a, b) == 0);
        free(a);
        free(b);
    }
    // A header cut short is refused, not repaired: the file is not one this library finished writing.
    write_text(path, full, 30);
    MR_CHECK(run(&spec, path, 1, 1, &s) == MR_ERR_FORMAT && strstr(mr_last_error(), "header ends early") != NULL);
    free(resumed);
    free(torn);
    free(full);
}

MR_TEST(a_full_disk_leaves_whole_rows_and_the_sweep_resumes) {
    // A file-size limit stands in for a full disk: the second row's write() is cut short by the kernel.
    mr_sweep_spec spec = random_spec(4, 9, 16);
    const char *reference = tmp_path("limit_ref.csv"), *path = tmp_path("limit.csv");
    unlink(reference);
    unlink(path);
    MR_CHECK_OK(run(&spec, reference, 0, 1, NULL));
    char *full = mr_test_read_file(reference, NULL);
    if (full == NULL) {
        MR_CHECK(full != NULL);
        return;
    }
    const char *row1 = strstr(full, "\n1,");
    MR_CHECK(row1 != NULL);
    struct rlimit saved, limited;
    MR_CHECK(getrlimit(RLIMIT_FSIZE, &saved) == 0);
    limited = saved;
    limited.rlim_cur = (rlim_t)(row1 - full) + 1 + 25; /* the header, row 0 and 25 bytes of row 1 */
    void (*previous)(int) = signal(SIGXFSZ, SIG_IGN);  /* EFBIG instead of a signal */
    MR_CHECK(setrlimit(RLIMIT_FSIZE, &limited) == 0);
    mr_status s = run(&spec, path, 0, 1, NULL);
    setrlimit(RLIMIT_FSIZE, &saved);
    signal(SIGXFSZ, previous);
    MR_CHECK_MSG(s == MR_ERR_IO && strstr(mr_last_error(), "File too large") != NULL, "%s: %s", mr_status_str(s),
                 mr_last_error());
    char *cut = mr_test_read_file(path, NULL);
    // The header and row 0 stayed, the 25 bytes of row 1 were cut back off (seconds aside, row 0 is the reference's).
    MR_CHECK(cut != NULL && strlen(cut) > 0 && cut[strlen(cut) - 1] == '\n');
    if (cut != NULL) {
        char *a = comparable(full), *b = comparable(cut);
        MR_CHECK(strncmp(a, b, strlen(b)) == 0 && strstr(b, "\n0,") != NULL && strstr(b, "\n1,") == NULL);
        free(a);
        free(b);
    }
    mr_sweep_summary summary;
    MR_CHECK_OK(run(&spec, path, 1, 1, &summary));
    MR_CHECK(summary.already_done == 1 && summary.computed == 3 && summary.truncated_bytes == 0);
    char *resumed = mr_test_read_file(path, NULL);
    if (resumed != NULL) {
        char *a = comparable(full), *b = comparable(resumed);
        MR_CHECK(strcmp(a, b) == 0);
        free(a);
        free(b);
    }
    free(resumed);
    free(cut);
    free(full);
}

typedef struct progress_log {
    long calls, last_done, last_run_done, run_total;
    int monotonic;
} progress_log;

static void on_progress(const mr_sweep_progress *p, void *user) {
    progress_log *log = user;
    log->monotonic &= p->done == log->last_done + 1 && p->run_done == log->last_run_done + 1;
    log->monotonic &= p->row != NULL && p->row->index >= 0 && p->row->index < p->total;
    log->calls++;
    log->last_done = p->done;
    log->last_run_done = p->run_done;
    log->run_total = p->run_total;
}

MR_TEST(progress_is_reported_once_per_row_in_order) {
    mr_sweep_spec spec = random_spec(8, 2, 16);
    const char *path = tmp_path("progress.csv");
    unlink(path);
    progress_log log = {0, 0, 0, 0, 1};
    mr_sweep_options o = {0};
    o.threads = 2;
    o.progress = on_progress;
    o.progress_user = &log;
    mr_sweep_summary s;
    int threads_before = omp_get_max_threads();
    MR_CHECK_OK(mr_sweep_run(&spec, path, &o, &s));
    MR_CHECK(omp_get_max_threads() == threads_before); /* the single-threaded samples leave the caller's ICV */
    MR_CHECK(log.calls == 8 && log.monotonic && log.run_total == 8 && log.last_done == 8);
    MR_CHECK(s.outcomes[0] + s.outcomes[1] + s.outcomes[2] + s.outcomes[3] == 8);
    MR_CHECK(s.seconds > 0.0);
    unlink(path);
}

MR_TEST_MAIN(MR_TEST_ENTRY(grid_is_cartesian_first_axis_slowest_with_exact_endpoints),
             MR_TEST_ENTRY(grid_log_spacing_is_geometric), MR_TEST_ENTRY(grid_errors_name_the_bad_value),
             MR_TEST_ENTRY(random_samples_depend_only_on_seed_and_index_and_stay_in_bounds),
             MR_TEST_ENTRY(rows_round_trip_exactly), MR_TEST_ENTRY(one_and_two_threads_write_the_same_file),
             MR_TEST_ENTRY(an_existing_file_is_never_overwritten_and_a_mismatching_one_never_touched),
             MR_TEST_ENTRY(resume_cuts_a_torn_line_and_ends_with_the_uninterrupted_file),
             MR_TEST_ENTRY(a_full_disk_leaves_whole_rows_and_the_sweep_resumes),
             MR_TEST_ENTRY(progress_is_reported_once_per_row_in_order))
