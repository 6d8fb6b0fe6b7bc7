/*
 * test_sweep.c — parameter sweeps (src/remap/sweep.h): grid order, endpoints and log spacing; random samples
 * that depend only on (seed, index) and stay in bounds; exact CSV round trips; resume: header mismatches
 * refused with the file untouched, torn last lines cut, unsorted rows sorted at the end, a finished file left
 * alone, a write cut short by a full disk (a file-size limit) taken back; the same file for 1 and 2 threads.
 */
#include <locale.h>
#include <omp.h>
#include <pthread.h>
#include <signal.h>
#include <stdint.h>
#include <sys/resource.h>
#include <unistd.h>

#include "harness.h"
#include "matremap.h"
#include "remap/sweep.h"
#include "remap/sweep_file.h"

static char tmpdir[64];

static void cleanup(void) {
    const char *names[] = {"threads1.csv", "threads2.csv",    "mismatch.csv",    "reference.csv",  "torn.csv",
                           "progress.csv", "limit_ref.csv",   "limit.csv",       "ranks_ref.csv",  "ranks2.csv",
                           "ranks3.csv",   "refused.csv",     "shard_ref.csv",   "shard0.csv",     "shard1.csv",
                           "shard2.csv",   "shard1_copy.csv", "other_seed1.csv", "half1.csv",      "other_to1.csv",
                           "merged.csv",   "bad_shard.csv",   "insane.csv",      "insane_ref.csv", "unfinished.csv"};
    char path[256];
    for (size_t k = 0; k < sizeof names / sizeof names[0]; k++) {
        snprintf(path, sizeof path, "%s/%s", tmpdir, names[k]);
        unlink(path);
    }
    rmdir(tmpdir);
}

static const char *tmp_path(const char *name) {
    static char path[32][256]; /* a ring: a test holds up to 32 at once */
    static int next;
    char *p = path[next++ % 32];
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

static int same_bytes(const char *path, const char *text) {
    char *now = mr_test_read_file(path, NULL);
    int same = now != NULL && text != NULL && strcmp(now, text) == 0;
    free(now);
    return same;
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
    spec.region = MR_SWEEP_REGION_RANGE; /* each channel its own draw */
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

/* The TEXTURE region (the default): RGB parameters grey, and only values where Ward does not trim (diffuse +
 * specular <= 1), spread over that whole region; the RANGE region over Ward's whole ranges is nearly all trimmed
 * (the README's sweep before regions: 95 % of its rows were). Headers say which; a file of one is not resumed as
 * the other, and a header without a region word (files from before regions) reads as RANGE. */
MR_TEST(the_texture_region_draws_grey_linear_values) {
    const mr_brdf_model *ward = mr_brdf_find("ward");
    mr_sweep_spec spec;
    mr_sweep_spec_init(&spec, ward, mr_brdf_find("ggx"));
    spec.sampling = MR_SWEEP_RANDOM;
    spec.random_count = 2000;
    MR_CHECK(spec.region == MR_SWEEP_REGION_TEXTURE);
    const int d = mr_brdf_param_offset(ward, mr_brdf_param_index(ward, "diffuse"));
    const int s = mr_brdf_param_offset(ward, mr_brdf_param_index(ward, "specular"));
    int grey = 0, trimmed = 0, high_specular = 0, high_diffuse = 0;
    for (long i = 0; i < spec.random_count; i++) {
        double v[MR_BRDF_MAX_VALUES];
        MR_CHECK_OK(mr_sweep_sample(&spec, i, v));
        grey += v[d] == v[d + 1] && v[d] == v[d + 2] && v[s] == v[s + 1] && v[s] == v[s + 2];
        trimmed += ward->rescales(ward, v) != 0;
        high_specular += v[s] > 0.75;
        high_diffuse += v[d] > 0.75;
    }
    MR_CHECK_MSG(grey == 2000 && trimmed == 0, "grey %d, trimmed %d", grey, trimmed);
    // Uniform over the triangle d + s <= 1: 1/16 of it has s > 0.75 (and as much d > 0.75): 125 of 2000.
    MR_CHECK_MSG(high_specular > 90 && high_specular < 160 && high_diffuse > 90 && high_diffuse < 160, "%d, %d",
                 high_specular, high_diffuse);
    spec.region = MR_SWEEP_REGION_RANGE;
    trimmed = 0;
    for (long i = 0; i < 200; i++) {
        double v[MR_BRDF_MAX_VALUES];
        MR_CHECK_OK(mr_sweep_sample(&spec, i, v));
        trimmed += ward->rescales(ward, v) != 0;
    }
    MR_CHECK_MSG(trimmed > 190, "%d of 200 trimmed", trimmed);
    // Held values that leave nothing linear to draw are refused by name.
    spec.region = MR_SWEEP_REGION_TEXTURE;
    MR_CHECK_OK(mr_brdf_parse_assignment(ward, "diffuse=1", spec.source_values));
    spec.held = 1u << mr_brdf_param_index(ward, "diffuse");
    MR_CHECK_OK(mr_sweep_check(&spec));
    MR_CHECK_OK(mr_brdf_parse_assignment(ward, "specular=0.5", spec.source_values));
    spec.held |= 1u << mr_brdf_param_index(ward, "specular");
    MR_CHECK(mr_sweep_check(&spec) == MR_ERR_INVALID_ARG && strstr(mr_last_error(), "rescales") != NULL);

    // The header names the region; RANGE writes none (as files from before regions, which read as RANGE).
    mr_sweep_spec texture = random_spec(3, 5, 16), range = texture;
    range.region = MR_SWEEP_REGION_RANGE;
    const char *path = tmp_path("region.csv");
    mr_sweep_summary sum;
    unlink(path);
    MR_CHECK_OK(run(&texture, path, 0, 1, &sum));
    char *text = mr_test_read_file(path, NULL);
    MR_CHECK(text && strstr(text, "# sampling: random=3 seed=5 region=texture over alpha,f0,diffuse\n") != NULL);
    free(text);
    MR_CHECK(run(&range, path, 1, 1, &sum) == MR_ERR_INVALID_ARG); /* another sweep: not resumed */
    unlink(path);
    MR_CHECK_OK(run(&range, path, 0, 1, &sum));
    text = mr_test_read_file(path, NULL);
    MR_CHECK(text && strstr(text, "# sampling: random=3 seed=5 over alpha,f0,diffuse\n") != NULL);
    free(text);
    MR_CHECK_OK(run(&range, path, 1, 1, &sum));
    MR_CHECK(sum.already_done == 3 && sum.computed == 0);
    unlink(path);
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
        MR_CHECK(strstr(a, "# sampling: random=6 seed=11 region=texture over alpha,f0,diffuse\n") != NULL);
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

/* Holds (issue 28): a target parameter held at a value (mr_brdf_parse_holds into the spec's target values and held
 * mask) is in every row at that value, the header records both ("# to:" and held= of "# remap:"), and the sweep table
 * learn reads gives them back (target_fixed, target_held: what learn prints and leaves out of its notes). A second
 * file that fits the parameter makes it fitted for the table (held only where every file held it). */
MR_TEST(held_targets_are_recorded_in_the_header_and_read_back) {
    const mr_brdf_model *ward = mr_brdf_find("ward"), *op = mr_brdf_find("openpbr");
    mr_sweep_spec spec;
    mr_sweep_spec_init(&spec, ward, op);
    spec.sampling = MR_SWEEP_RANDOM;
    spec.random_count = 3;
    spec.seed = 5;
    spec.scene.size = 16;
    MR_CHECK_OK(mr_brdf_parse_holds(op, "base_metalness=0.25", spec.target_values, &spec.remap.held));
    const int metal = mr_brdf_param_index(op, "base_metalness"), at = mr_brdf_param_offset(op, metal);
    const char *held = tmp_path("held.csv"), *fitted = tmp_path("fitted.csv");
    unlink(held);
    unlink(fitted);
    MR_CHECK_OK(run(&spec, held, 0, 2, NULL));
    char *text = mr_test_read_file(held, NULL);
    MR_CHECK(text != NULL && strstr(text, " base_metalness=0.25 ") != NULL);
    MR_CHECK(text != NULL && strstr(text, " held=base_metalness\n") != NULL);
    free(text);
    mr_sweep_table tab;
    MR_CHECK_OK(mr_sweep_table_load(&held, 1, NULL, &tab));
    MR_CHECK(tab.n == 3 && tab.target_held == 1u << metal && tab.target_fixed[at] == 0.25);
    for (size_t r = 0; r < tab.n; r++) MR_CHECK(tab.target_values[r * (size_t)tab.target_count + (size_t)at] == 0.25);
    mr_sweep_table_free(&tab);
    // The same target values, the parameter fitted: the two files' table holds nothing the caller held.
    spec.remap.held = 0;
    MR_CHECK_OK(run(&spec, fitted, 0, 2, NULL));
    const char *both[2] = {held, fitted};
    MR_CHECK_OK(mr_sweep_table_load(both, 2, NULL, &tab));
    MR_CHECK(tab.n + tab.skipped == 6 && tab.target_held == 0);
    mr_sweep_table_free(&tab);
    unlink(held);
    unlink(fitted);
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
    MR_CHECK(s.outcomes[0] + s.outcomes[1] + s.outcomes[2] + s.outcomes[3] + s.outcomes[4] == 8);
    MR_CHECK(s.seconds > 0.0);
    unlink(path);
}

/* ---- several ranks in one process ---------------------------------------------------------------------------
 * A transport over threads with what MPI gives the sweep (mr_sweep_comm: a broadcast from rank 0, buffered
 * messages that arrive in order per pair of ranks), so that the protocol between ranks is tested where Open MPI
 * is not installed; tests/sweep_mpi.sh runs the real thing under mpirun. */

#define FAKE_MAX_RANKS 4

typedef struct fake_message {
    struct fake_message *next;
    int from, tag;
    size_t bytes;
    unsigned char data[MR_SWEEP_MESSAGE_MAX];
} fake_message;

typedef struct fake_net {
    pthread_mutex_t lock;
    pthread_cond_t changed;
    int size;
    fake_message *head[FAKE_MAX_RANKS], *tail[FAKE_MAX_RANKS];
    const void *broadcast;
    size_t broadcast_bytes;
    long broadcast_round;
    int broadcast_unread;
    long messages; /* sent, all ranks */
} fake_net;

typedef struct fake_rank {
    fake_net *net;
    int rank;
    long round; /* the last broadcast this rank read */
    mr_sweep_comm comm;
    mr_sweep_spec spec;
    const char *path;
    mr_sweep_options opts;
    mr_sweep_summary summary;
    mr_status status;
    char message[1024];
} fake_rank;

static mr_status fake_broadcast(void *user, void *buf, size_t bytes) {
    fake_rank *r = user;
    fake_net *n = r->net;
    mr_status status = MR_OK;
    pthread_mutex_lock(&n->lock);
    if (r->rank == 0) {
        n->broadcast = buf;
        n->broadcast_bytes = bytes;
        n->broadcast_round++;
        n->broadcast_unread = n->size - 1;
        pthread_cond_broadcast(&n->changed);
        while (n->broadcast_unread > 0)
            pthread_cond_wait(&n->changed, &n->lock); /* buf stays valid till then */
    } else {
        while (n->broadcast_round <= r->round)
            pthread_cond_wait(&n->changed, &n->lock);
        if (bytes != n->broadcast_bytes)
            status = MR_ERR_EXTERNAL; /* a collective with mismatched sizes */
        memcpy(buf, n->broadcast, bytes < n->broadcast_bytes ? bytes : n->broadcast_bytes);
        r->round = n->broadcast_round;
        n->broadcast_unread--;
        pthread_cond_broadcast(&n->changed);
    }
    pthread_mutex_unlock(&n->lock);
    return status;
}

static mr_status fake_send(void *user, int to, int tag, const void *buf, size_t bytes) {
    fake_rank *r = user;
    fake_net *n = r->net;
    if (to < 0 || to >= n->size || bytes > MR_SWEEP_MESSAGE_MAX)
        return MR_ERR_INVALID_ARG;
    fake_message *m = calloc(1, sizeof *m);
    if (m == NULL)
        return MR_ERR_NOMEM;
    m->from = r->rank;
    m->tag = tag;
    m->bytes = bytes;
    memcpy(m->data, buf, bytes);
    pthread_mutex_lock(&n->lock);
    if (n->tail[to] != NULL)
        n->tail[to]->next = m;
    else
        n->head[to] = m;
    n->tail[to] = m;
    n->messages++;
    pthread_cond_broadcast(&n->changed);
    pthread_mutex_unlock(&n->lock);
    return MR_OK;
}

static mr_status fake_receive(void *user, int wait, int *from, int *tag, void *buf, size_t *bytes, int *got) {
    fake_rank *r = user;
    fake_net *n = r->net;
    pthread_mutex_lock(&n->lock);
    while (wait && n->head[r->rank] == NULL)
        pthread_cond_wait(&n->changed, &n->lock);
    fake_message *m = n->head[r->rank];
    if (m != NULL) {
        n->head[r->rank] = m->next;
        if (m->next == NULL)
            n->tail[r->rank] = NULL;
    }
    pthread_mutex_unlock(&n->lock);
    *got = m != NULL;
    if (m != NULL) {
        *from = m->from;
        *tag = m->tag;
        *bytes = m->bytes;
        memcpy(buf, m->data, m->bytes);
        free(m);
    }
    return MR_OK;
}

static mr_status fake_flush(void *user) {
    (void)user;
    return MR_OK;
}

static void *fake_rank_main(void *arg) {
    fake_rank *r = arg;
    r->status = mr_sweep_run(&r->spec, r->path, &r->opts, &r->summary);
    snprintf(r->message, sizeof r->message, "%s", r->status == MR_OK ? "" : mr_last_error());
    return NULL;
}

/* Run the sweep `specs[k]` on `size` ranks, rank k with threads[k] threads, each in a thread of its own. Every
 * rank's outcome is in ranks[k]. Returns the number of messages left undelivered (0 when the protocol drained). */
static long run_ranks(int size, const mr_sweep_spec *specs, const int *threads, const char *path, int resume,
                      fake_rank *ranks) {
    fake_net net;
    memset(&net, 0, sizeof net);
    pthread_mutex_init(&net.lock, NULL);
    pthread_cond_init(&net.changed, NULL);
    net.size = size;
    pthread_t tids[FAKE_MAX_RANKS];
    for (int k = 0; k < size; k++) {
        fake_rank *r = &ranks[k];
        memset(r, 0, sizeof *r);
        r->net = &net;
        r->rank = k;
        r->comm.rank = k;
        r->comm.size = size;
        r->comm.user = r;
        r->comm.broadcast = fake_broadcast;
        r->comm.send = fake_send;
        r->comm.receive = fake_receive;
        r->comm.flush = fake_flush;
        r->spec = specs[k];
        r->path = path;
        r->opts.resume = resume;
        r->opts.threads = threads[k];
        r->opts.command_line = "test_sweep ranks";
        r->opts.comm = &r->comm;
    }
    for (int k = 0; k < size; k++)
        pthread_create(&tids[k], NULL, fake_rank_main, &ranks[k]);
    for (int k = 0; k < size; k++)
        pthread_join(tids[k], NULL);
    long left = 0;
    for (int k = 0; k < size; k++)
        while (net.head[k] != NULL) {
            fake_message *m = net.head[k];
            net.head[k] = m->next;
            free(m);
            left++;
        }
    pthread_mutex_destroy(&net.lock);
    pthread_cond_destroy(&net.changed);
    return left;
}

static int same_rows(const char *path_a, const char *path_b) {
    char *a = mr_test_read_file(path_a, NULL), *b = mr_test_read_file(path_b, NULL);
    int same = 0;
    if (a != NULL && b != NULL) {
        char *ca = comparable(a), *cb = comparable(b);
        same = strcmp(ca, cb) == 0;
        if (!same)
            fprintf(stderr, "      '%s' and '%s' differ:\n%s\n---\n%s\n", path_a, path_b, ca, cb);
        free(ca);
        free(cb);
    }
    free(a);
    free(b);
    return same;
}

MR_TEST(two_and_three_ranks_write_the_single_process_file_and_resume_it) {
    mr_sweep_spec spec = random_spec(11, 13, 16);
    const char *reference = tmp_path("ranks_ref.csv"), *two = tmp_path("ranks2.csv"), *three = tmp_path("ranks3.csv");
    unlink(reference);
    unlink(two);
    unlink(three);
    MR_CHECK_OK(run(&spec, reference, 0, 1, NULL));

    // Two ranks, one thread each, from nothing.
    mr_sweep_spec specs[FAKE_MAX_RANKS] = {spec, spec, spec};
    fake_rank ranks[FAKE_MAX_RANKS];
    int ones[FAKE_MAX_RANKS] = {1, 1, 1};
    MR_CHECK(run_ranks(2, specs, ones, two, 0, ranks) == 0);
    for (int k = 0; k < 2; k++)
        MR_CHECK_MSG(ranks[k].status == MR_OK, "rank %d: %s", k, ranks[k].message);
    MR_CHECK(ranks[0].summary.computed == 11 && ranks[0].summary.processes == 2); /* sorted unless in order */
    MR_CHECK(ranks[0].summary.threads_total == 2 && ranks[1].summary.computed == 5); /* rank 1: samples 1, 3, .. 9 */
    MR_CHECK(same_rows(reference, two));

    // Three ranks (1, 2 and 1 threads) resume a file a killed run left: rows 7 and 2, and a torn row 4.
    char *full = mr_test_read_file(reference, NULL);
    MR_CHECK(full != NULL);
    if (full == NULL)
        return;
    const char *rows = strstr(full, "\n0,") + 1, *r7 = strstr(full, "\n7,") + 1, *r2 = strstr(full, "\n2,") + 1;
    const char *r4 = strstr(full, "\n4,") + 1;
    char *partial = malloc(strlen(full) + 1);
    size_t n = (size_t)(rows - full), l7 = (size_t)(strchr(r7, '\n') + 1 - r7),
           l2 = (size_t)(strchr(r2, '\n') + 1 - r2);
    memcpy(partial, full, n);
    memcpy(partial + n, r7, l7);
    memcpy(partial + n + l7, r2, l2);
    memcpy(partial + n + l7 + l2, r4, 20);
    write_text(three, partial, n + l7 + l2 + 20);
    int mixed[FAKE_MAX_RANKS] = {1, 2, 1};
    MR_CHECK(run_ranks(3, specs, mixed, three, 1, ranks) == 0);
    for (int k = 0; k < 3; k++)
        MR_CHECK_MSG(ranks[k].status == MR_OK, "rank %d: %s", k, ranks[k].message);
    MR_CHECK(ranks[0].summary.already_done == 2 && ranks[0].summary.computed == 9 &&
             ranks[0].summary.truncated_bytes == 20 && ranks[0].summary.threads_total == 4);
    MR_CHECK(ranks[0].summary.computed == ranks[0].summary.outcomes[0] + ranks[0].summary.outcomes[1] +
                                              ranks[0].summary.outcomes[2] + ranks[0].summary.outcomes[3] +
                                              ranks[0].summary.outcomes[4]);
    MR_CHECK(same_rows(reference, three));
    // The resumed file kept its own header (the first run's command line) and is sorted.
    char *resumed = mr_test_read_file(three, NULL);
    MR_CHECK(resumed != NULL && strncmp(resumed, full, (size_t)(rows - full)) == 0);
    free(resumed);

    // A finished file resumed by two ranks: nothing to do, not a byte changed.
    char *before = mr_test_read_file(three, NULL);
    MR_CHECK(run_ranks(2, specs, ones, three, 1, ranks) == 0);
    MR_CHECK(ranks[0].status == MR_OK && ranks[1].status == MR_OK && ranks[0].summary.computed == 0);
    MR_CHECK(same_bytes(three, before));
    free(before);
    free(partial);
    free(full);
}

MR_TEST(a_rank_running_another_sweep_is_refused_before_the_file_is_made) {
    mr_sweep_spec spec = random_spec(4, 5, 16), other = spec;
    other.seed = 6;
    const char *path = tmp_path("refused.csv");
    unlink(path);
    mr_sweep_spec specs[FAKE_MAX_RANKS] = {spec, other};
    fake_rank ranks[FAKE_MAX_RANKS];
    int ones[FAKE_MAX_RANKS] = {1, 1};
    MR_CHECK(run_ranks(2, specs, ones, path, 0, ranks) == 0);
    MR_CHECK_MSG(ranks[0].status == MR_ERR_INVALID_ARG && strstr(ranks[0].message, "rank 1 runs another sweep"), "%s",
                 ranks[0].message);
    MR_CHECK(ranks[1].status == MR_ERR_INVALID_ARG && strstr(ranks[1].message, "rank 0 did not start"));
    MR_CHECK(access(path, F_OK) != 0); /* nothing written */

    // Rank 0's own refusal (the file exists, no resume) reaches every rank with its status.
    MR_CHECK_OK(run(&spec, path, 0, 1, NULL));
    char *before = mr_test_read_file(path, NULL);
    specs[1] = spec;
    MR_CHECK(run_ranks(2, specs, ones, path, 0, ranks) == 0);
    MR_CHECK(ranks[0].status == MR_ERR_INVALID_ARG && strstr(ranks[0].message, "already exists"));
    MR_CHECK(ranks[1].status == MR_ERR_INVALID_ARG);
    MR_CHECK(same_bytes(path, before));
    free(before);
}

static mr_status run_shard(const mr_sweep_spec *spec, const char *path, long k, long n, int resume) {
    mr_sweep_options o = {0};
    o.resume = resume;
    o.threads = 2;
    o.shard_index = k;
    o.shard_count = n;
    o.command_line = "test_sweep shard";
    return mr_sweep_run(spec, path, &o, NULL);
}

MR_TEST(shards_merge_into_the_single_process_file) {
    mr_sweep_spec spec = random_spec(10, 21, 16);
    const char *reference = tmp_path("shard_ref.csv"), *merged = tmp_path("merged.csv");
    const char *shard[3] = {tmp_path("shard0.csv"), tmp_path("shard1.csv"), tmp_path("shard2.csv")};
    unlink(reference);
    unlink(merged);
    MR_CHECK_OK(run(&spec, reference, 0, 1, NULL));
    for (int k = 0; k < 3; k++) {
        unlink(shard[k]);
        mr_sweep_options o = {0};
        o.threads = 2;
        o.shard_index = k;
        o.shard_count = 3;
        o.command_line = "test_sweep shard";
        mr_sweep_summary s;
        MR_CHECK_OK(mr_sweep_run(&spec, shard[k], &o, &s));
        MR_CHECK(s.total == 10 && s.file_total == (k == 0 ? 4 : 3) && s.computed == s.file_total);
    }
    char *text = mr_test_read_file(shard[1], NULL);
    MR_CHECK(text != NULL && strstr(text, "# samples: 10\n# shard: 1/3\n# command: test_sweep shard\n") != NULL);
    MR_CHECK(text != NULL && strstr(text, "\n1,") != NULL && strstr(text, "\n4,") != NULL && !strstr(text, "\n2,"));
    free(text);
    // A shard resumes as a shard: finished, nothing to do; as another shard, refused naming the line.
    MR_CHECK_OK(run_shard(&spec, shard[1], 1, 3, 1));
    MR_CHECK(run_shard(&spec, shard[1], 2, 3, 1) == MR_ERR_INVALID_ARG && strstr(mr_last_error(), "line 8 is '# "
                                                                                                  "shard: 1/3'"));
    MR_CHECK(run_shard(&spec, shard[1], 0, 0, 1) == MR_ERR_INVALID_ARG);
    MR_CHECK(run_shard(&spec, shard[1], 3, 3, 1) == MR_ERR_INVALID_ARG && strstr(mr_last_error(), "0 <= K < N"));
    MR_CHECK(run_shard(&spec, shard[1], 0, 11, 1) == MR_ERR_INVALID_ARG && strstr(mr_last_error(), "empty"));

    const char *order[3] = {shard[2], shard[0], shard[1]}; /* any order */
    mr_sweep_merge_summary ms;
    MR_CHECK_OK(mr_sweep_merge(order, 3, merged, "test_sweep merge", &ms));
    MR_CHECK(ms.total == 10 && ms.shards == 3);
    MR_CHECK(same_rows(reference, merged));
    text = mr_test_read_file(merged, NULL);
    MR_CHECK(text != NULL && strstr(text, "# shard:") == NULL && strstr(text, "# command: test_sweep merge\n"));
    free(text);
    // The merged file is a finished sweep: resuming it does nothing.
    mr_sweep_summary s;
    MR_CHECK_OK(run(&spec, merged, 1, 1, &s));
    MR_CHECK(s.computed == 0 && s.already_done == 10);
    // A merged file is never overwritten.
    MR_CHECK(mr_sweep_merge(order, 3, merged, NULL, NULL) == MR_ERR_INVALID_ARG &&
             strstr(mr_last_error(), "already exists"));
    // One shard of one is the whole sweep.
    mr_sweep_spec small = random_spec(2, 3, 16);
    unlink(shard[0]);
    unlink(merged);
    MR_CHECK_OK(run_shard(&small, shard[0], 0, 1, 0));
    MR_CHECK_OK(mr_sweep_merge(shard, 1, merged, "one", &ms));
    MR_CHECK(ms.total == 2 && ms.shards == 1);
    unlink(merged);
}

/* mr_sweep_merge must fail with `status` and a message holding both fragments, and write nothing. */
static int merge_fails(const char *const *paths, int count, mr_status status, const char *a, const char *b) {
    const char *merged = tmp_path("merged.csv");
    unlink(merged);
    mr_status got = mr_sweep_merge(paths, count, merged, NULL, NULL);
    int ok = got == status && strstr(mr_last_error(), a) != NULL && (b == NULL || strstr(mr_last_error(), b));
    if (!ok)
        fprintf(stderr, "      %s: %s\n", mr_status_str(got), mr_last_error());
    return ok && access(merged, F_OK) != 0;
}

MR_TEST(merge_refuses_shards_that_do_not_belong_together) {
    mr_sweep_spec spec = random_spec(6, 31, 16);
    const char *s0 = tmp_path("shard0.csv"), *s1 = tmp_path("shard1.csv"), *s2 = tmp_path("shard2.csv");
    const char *copy = tmp_path("shard1_copy.csv"), *seed1 = tmp_path("other_seed1.csv");
    const char *half1 = tmp_path("half1.csv"), *to1 = tmp_path("other_to1.csv"), *bad = tmp_path("bad_shard.csv");
    const char *whole = tmp_path("shard_ref.csv");
    const char *all[] = {s0, s1, s2, copy, seed1, half1, to1, bad, whole};
    for (size_t k = 0; k < sizeof all / sizeof all[0]; k++)
        unlink(all[k]);
    MR_CHECK_OK(run_shard(&spec, s0, 0, 3, 0));
    MR_CHECK_OK(run_shard(&spec, s1, 1, 3, 0));
    MR_CHECK_OK(run_shard(&spec, s2, 2, 3, 0));
    char *text1 = mr_test_read_file(s1, NULL);
    write_text(copy, text1, strlen(text1));
    mr_sweep_spec other = spec;
    other.seed = 32;
    MR_CHECK_OK(run_shard(&other, seed1, 1, 3, 0));
    MR_CHECK_OK(run_shard(&spec, half1, 1, 2, 0));
    other = spec;
    other.target = mr_brdf_find("ward");
    mr_brdf_default_values(other.target, other.target_values);
    MR_CHECK_OK(run_shard(&other, to1, 1, 3, 0));
    MR_CHECK_OK(run(&spec, whole, 0, 1, NULL));

    const char *missing[] = {s2, s0};
    MR_CHECK(merge_fails(missing, 2, MR_ERR_INVALID_ARG, "missing: 1/3", NULL));
    const char *twice[] = {s0, s1, copy, s2};
    MR_CHECK(merge_fails(twice, 4, MR_ERR_INVALID_ARG, "both shard 1/3", copy));
    const char *same[] = {s0, s1, s1};
    MR_CHECK(merge_fails(same, 3, MR_ERR_INVALID_ARG, "are the same file", NULL));
    const char *seeds[] = {s0, seed1, s2};
    MR_CHECK(merge_fails(seeds, 3, MR_ERR_INVALID_ARG, "from different sweeps", "# sampling: random=6 seed=32"));
    const char *models[] = {s0, to1, s2};
    MR_CHECK(merge_fails(models, 3, MR_ERR_INVALID_ARG, "from different sweeps", "'# to: ward "));
    const char *halves[] = {s0, half1, s2};
    MR_CHECK(merge_fails(halves, 3, MR_ERR_INVALID_ARG, "split the sweep differently", "1/2"));
    const char *whole_file[] = {whole};
    MR_CHECK(merge_fails(whole_file, 1, MR_ERR_FORMAT, "is a whole sweep, not a shard", NULL));
    const char *absent[] = {s0, tmp_path("no_such_shard.csv"), s2};
    MR_CHECK(merge_fails(absent, 3, MR_ERR_INVALID_ARG, "no_such_shard.csv", "cannot open"));

    // Shards that are unfinished or corrupt: a missing last row, a torn one, an edited value, another version.
    const char *with_bad[] = {s0, bad, s2};
    size_t len1 = strlen(text1);
    const char *last = text1 + len1 - 1;
    while (last > text1 && last[-1] != '\n')
        last--;
    write_text(bad, text1, (size_t)(last - text1));
    MR_CHECK(merge_fails(with_bad, 3, MR_ERR_INVALID_ARG, "ends after 1 of its 2 rows", "--resume"));
    write_text(bad, text1, len1 - 1);
    MR_CHECK(merge_fails(with_bad, 3, MR_ERR_INVALID_ARG, "line 12 is torn", NULL));
    char *edited = strdup(text1);
    char *row = strstr(edited, "\n1,") + 1;
    char *col = row;
    for (int c = 0; c < 8; c++)
        col = strchr(col, ',') + 1; /* column 9: to_diffuse_r */
    char *end = strchr(col, ',');
    char rebuilt[8192];
    snprintf(rebuilt, sizeof rebuilt, "%.*s-0.5%s", (int)(col - edited), edited, end);
    write_text(bad, rebuilt, strlen(rebuilt));
    MR_CHECK(merge_fails(with_bad, 3, MR_ERR_FORMAT, "bad_shard.csv': line 11: column 9 (to_diffuse_r)",
                         "outside diffuse's range"));
    snprintf(rebuilt, sizeof rebuilt, "# matremap 0.0.1 sweep\n%s", strchr(text1, '\n') + 1);
    write_text(bad, rebuilt, strlen(rebuilt));
    MR_CHECK(merge_fails(with_bad, 3, MR_ERR_FORMAT, "line 1 is '# matremap 0.0.1 sweep'", "another matremap"));
    free(edited);
    free(text1);

    // A merge never replaces the output, and an output that is a shard is refused the same way.
    const char *good[] = {s0, s1, s2};
    char *before = mr_test_read_file(s1, NULL);
    MR_CHECK(mr_sweep_merge(good, 3, s1, NULL, NULL) == MR_ERR_INVALID_ARG && same_bytes(s1, before));
    free(before);
}

/* A copy of `text` with field `column` (0-based) of the row of sample `index` replaced by `value`. */
static char *replace_field(const char *text, long index, int column, const char *value) {
    char want[32];
    snprintf(want, sizeof want, "\n%ld,", index);
    const char *row = strstr(text, want) + 1, *at = row;
    for (int c = 0; c < column; c++)
        at = strchr(at, ',') + 1;
    const char *end = at + strcspn(at, ",\n");
    char *out = malloc(strlen(text) + strlen(value) + 1);
    sprintf(out, "%.*s%s%s", (int)(at - text), text, value, end);
    return out;
}

MR_TEST(resume_refuses_rows_that_are_not_sane_naming_line_and_column) {
    mr_sweep_spec spec = random_spec(4, 5, 16);
    const char *reference = tmp_path("insane_ref.csv"), *path = tmp_path("insane.csv");
    unlink(reference);
    MR_CHECK_OK(run(&spec, reference, 0, 1, NULL));
    char *full = mr_test_read_file(reference, NULL);
    if (full == NULL) {
        MR_CHECK(full != NULL);
        return;
    }
    // Columns: 1 index, 2 alpha, 3-5 f0, 6-8 diffuse, 9-11 to_diffuse, 12-14 to_specular, 15 to_alpha,
    // 16 to_trim, 17 rmse, 18 relative_rmse, 19 ssim, 20 outcome, 21 renders, 22 seconds. Sample 1 is line 11.
    struct {
        int column; /* 0-based field */
        const char *value, *message;
    } cases[] = {
        {8, "-0.5", "line 11: column 9 (to_diffuse_r): -0.5 is outside diffuse's range [0, 1]"},
        {11, "1e300", "line 11: column 12 (to_specular_r): 1.0000000000000001e+300 is outside"},
        {14, "inf", "line 11: column 15 (to_alpha): inf is not a finite number"},
        {1, "nan", "line 11: column 2 (alpha): nan is not a finite number"},
        {3, "-inf", "line 11: column 4 (f0_g): -inf is not a finite number"},
        {15, "0.5", "line 11: column 16 (to_trim): 0.5 is not an integer (trim is a switch"},
        {16, "nan", "line 11: column 17 (rmse): nan is not a finite number >= 0"},
        {16, "-1", "line 11: column 17 (rmse): -1 is not"},
        {17, "nan", "line 11: column 18 (relative_rmse): nan is not a number >= 0 (or inf)"},
        {18, "1.5", "line 11: column 19 (ssim): 1.5 is not a number in [-1, 1]"},
        {21, "inf", "line 11: column 22 (seconds): inf is not a finite number >= 0"},
        {20, "-3", "line 11: column 21: '-3' is not a valid value"},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        char *edited = replace_field(full, 1, cases[k].column, cases[k].value);
        write_text(path, edited, strlen(edited));
        mr_sweep_summary s;
        mr_status status = run(&spec, path, 1, 1, &s);
        MR_CHECK_MSG(status == MR_ERR_FORMAT && strstr(mr_last_error(), "sweep file '") != NULL &&
                         strstr(mr_last_error(), "insane.csv': ") != NULL &&
                         strstr(mr_last_error(), cases[k].message) != NULL,
                     "%s=%s: %s: %s", cases[k].message, cases[k].value, mr_status_str(status), mr_last_error());
        MR_CHECK_MSG(same_bytes(path, edited), "the refused file was changed (%s)", cases[k].value);
        free(edited);
    }
    // relative_rmse = inf is what a black source gives: a sane row.
    char *black = replace_field(full, 1, 17, "inf");
    write_text(path, black, strlen(black));
    MR_CHECK_OK(run(&spec, path, 1, 1, NULL));
    free(black);
    // The same check as a library call.
    mr_sweep_row row;
    const char *line = strstr(full, "\n2,") + 1;
    MR_CHECK_OK(mr_sweep_parse_row(&spec, line, (size_t)(strchr(line, '\n') + 1 - line), &row));
    MR_CHECK_OK(mr_sweep_check_row(&spec, &row));
    row.target[0] = -1e-3;
    MR_CHECK(mr_sweep_check_row(&spec, &row) == MR_ERR_FORMAT && strstr(mr_last_error(), "column 9 (to_diffuse_r)"));
    free(full);
}

MR_TEST(a_torn_last_row_is_never_counted_even_when_only_its_line_end_is_missing) {
    mr_sweep_spec spec = random_spec(4, 5, 16);
    const char *reference = tmp_path("insane_ref.csv"), *path = tmp_path("unfinished.csv");
    char *full = mr_test_read_file(reference, NULL);
    if (full == NULL) { /* the test above made it; run alone, make it */
        MR_CHECK_OK(run(&spec, reference, 0, 1, NULL));
        full = mr_test_read_file(reference, NULL);
    }
    MR_CHECK(full != NULL);
    if (full == NULL)
        return;
    size_t len = strlen(full);
    write_text(path, full, len - 1); /* row 3 complete but for its '\n' */
    mr_sweep_summary s;
    MR_CHECK_OK(run(&spec, path, 1, 1, &s));
    const char *row3 = strstr(full, "\n3,") + 1;
    MR_CHECK(s.already_done == 3 && s.computed == 1 && s.truncated_bytes == (long)(full + len - 1 - row3));
    MR_CHECK(same_rows(reference, path));
    // A torn line that holds garbage (half a number, a NaN) is cut the same way: it was never a row.
    char torn[8192];
    snprintf(torn, sizeof torn, "%.*s3,nan,1e30", (int)(row3 - full), full);
    write_text(path, torn, strlen(torn));
    MR_CHECK_OK(run(&spec, path, 1, 1, &s));
    MR_CHECK_MSG(s.already_done == 3 && s.computed == 1 && s.truncated_bytes == 10, "%ld %ld %ld", s.already_done,
                 s.computed, s.truncated_bytes);
    MR_CHECK(same_rows(reference, path));
    free(full);
}

/* The texts after the "# from:", "# to:", "# remap:", "# scene:" and "# sampling:" prefixes of a header (each
 * without its line end), as merge finds them. 0 after a failed check when one is missing. */
static int header_texts(const char *header, char texts[5][MR_SWEEP_MAX_LINE]) {
    const char *prefixes[5] = {MR_SWEEP_FROM_PREFIX, MR_SWEEP_TO_PREFIX, MR_SWEEP_REMAP_PREFIX, MR_SWEEP_SCENE_PREFIX,
                               MR_SWEEP_SAMPLING_PREFIX};
    for (int i = 0; i < 5; i++) {
        const char *at = header != NULL ? strstr(header, prefixes[i]) : NULL;
        MR_CHECK(at != NULL);
        if (at == NULL) return 0;
        at += strlen(prefixes[i]);
        snprintf(texts[i], MR_SWEEP_MAX_LINE, "%.*s", (int)strcspn(at, "\n"), at);
    }
    return 1;
}

/* The sweep file's module (sweep_file.h): a header read back into its sweep rebuilds byte for byte (what merge
 * relies on), and the column-name reader that learn and train use finds the columns, counts lines and refuses an
 * over-long one naming file and line. */
MR_TEST(sweep_file_header_reads_back_and_the_column_reader_counts_lines) {
    mr_sweep_spec spec;
    mr_sweep_spec_init(&spec, mr_brdf_find("ward"), mr_brdf_find("ggx"));
    spec.sampling = MR_SWEEP_RANDOM;
    spec.random_count = 5;
    spec.seed = 7;
    spec.scene.size = 16;
    mr_strbuf header = {0};
    MR_CHECK_OK(mr_sweep_file_header(&spec, "cmd", 1, 3, &header));
    // The texts after each prefix, as merge finds them.
    char texts[5][MR_SWEEP_MAX_LINE];
    if (!header_texts(header.text, texts)) return;
    mr_sweep_spec back;
    const char *step = NULL;
    MR_CHECK_OK(mr_sweep_file_spec_from_header(texts[0], texts[1], texts[2], texts[3], texts[4], &back, &step));
    mr_strbuf rebuilt = {0};
    MR_CHECK_OK(mr_sweep_file_header(&back, "cmd", 1, 3, &rebuilt));
    MR_CHECK(rebuilt.length == header.length && memcmp(rebuilt.text, header.text, header.length) == 0);
    // A "# from:" line naming no model fails at that step.
    MR_CHECK(mr_sweep_file_spec_from_header("", texts[1], texts[2], texts[3], texts[4], &back, &step) ==
             MR_ERR_FORMAT);
    MR_CHECK(strcmp(step, "# from:") == 0 && strstr(mr_last_error(), "no model named") != NULL);

    // The column-name reader over the header, two rows and a line longer than its limit.
    const char *path = tmp_path("column_reader.csv");
    FILE *f = fopen(path, "w");
    fprintf(f, "%sa,b\n", header.text);
    for (int i = 0; i < 300; i++) fputc('9', f);
    fputc('\n', f);
    fclose(f);
    mr_sweep_reader reader = {0};
    MR_CHECK_OK(mr_sweep_reader_open(&reader, path, 200));
    mr_status status = MR_OK;
    long lines = 0;
    char *names[64];
    int column_of_seconds = -1;
    while (mr_sweep_reader_next(&reader, &status) > 0) {
        lines++;
        MR_CHECK(reader.line_number == lines);
        if (strncmp(reader.line, "index,", 6) == 0) {
            int count = mr_csv_split(reader.line, names, 64);
            column_of_seconds = mr_sweep_file_find_column(names, count, "seconds");
            MR_CHECK(mr_sweep_file_find_column(names, count, "no such column") == -1);
        }
    }
    long before_long = 1; /* the header's lines (the column line last), then "a,b" */
    for (const char *c = header.text; *c; c++) before_long += *c == '\n';
    MR_CHECK_MSG(lines == before_long, "%ld lines before the long one, expected %ld", lines, before_long);
    MR_CHECK(column_of_seconds ==
             mr_brdf_value_count(spec.source) + mr_brdf_value_count(spec.target) + MR_SWEEP_ROW_TAIL_COLUMNS);
    char where[64];
    snprintf(where, sizeof where, ":%ld: line longer than 200 bytes", before_long + 1);
    MR_CHECK_MSG(status == MR_ERR_FORMAT && strstr(mr_last_error(), where) != NULL, "%s", mr_last_error());
    mr_sweep_reader_close(&reader);
    double x = 0.0;
    MR_CHECK(mr_sweep_file_parse_number("0.25", &x) && x == 0.25);
    MR_CHECK(!mr_sweep_file_parse_number("inf", &x) && !mr_sweep_file_parse_number("1x", &x));
    free(header.text);
    free(rebuilt.text);
}

/* Split a "# command:" text as a POSIX shell would: words separated by spaces, '...' quoting anything, \' outside
 * quotes a quote. Up to max words into words[] (each its own malloc'ed string); returns the count. */
static int shell_split(const char *text, char **words, int max) {
    int n = 0;
    const char *p = text;
    while (*p && n < max) {
        while (*p == ' ') p++;
        if (*p == '\0') break;
        char *w = malloc(strlen(p) + 1), *o = w;
        while (*p && *p != ' ') {
            if (*p == '\'') {
                for (p++; *p && *p != '\''; p++) *o++ = *p;
                if (*p) p++;
            } else if (*p == '\\' && p[1]) {
                *o++ = p[1];
                p += 2;
            } else {
                *o++ = *p++;
            }
        }
        *o = '\0';
        words[n++] = w;
    }
    return n;
}

/* mr_sweep_command_line: plain arguments as they are, the others single-quoted ('\'' for a quote, '' for an empty
 * one); the "# command:" line of a header built with it splits back into the same arguments (a line break in one
 * becomes a space there, and only there). */
MR_TEST(command_line_quoting_round_trips_through_the_header) {
    const char *argv[] = {"sweep", "--from", "ggx", "alpha=0.1:0.5:3", "-o", "out dir/s.csv", "it's", "", "a\"b$c",
                          "x\ny"};
    const int argc = (int)(sizeof argv / sizeof argv[0]);
    char *line = NULL;
    MR_CHECK_OK(mr_sweep_command_line("matremap", argc, argv, &line));
    if (line == NULL) return;
    MR_CHECK_MSG(strcmp(line, "matremap sweep --from ggx alpha=0.1:0.5:3 -o 'out dir/s.csv' 'it'\\''s' '' "
                              "'a\"b$c' 'x\ny'") == 0, "%s", line);
    mr_sweep_spec spec = random_spec(5, 7, 16);
    mr_strbuf header = {0};
    MR_CHECK_OK(mr_sweep_file_header(&spec, line, 0, 0, &header));
    const char *at = header.text != NULL ? strstr(header.text, MR_SWEEP_COMMAND_PREFIX) : NULL;
    MR_CHECK(at != NULL);
    if (at != NULL) {
        at += strlen(MR_SWEEP_COMMAND_PREFIX);
        char text[1024];
        snprintf(text, sizeof text, "%.*s", (int)strcspn(at, "\n"), at);
        char *words[32];
        const int n = shell_split(text, words, 32);
        MR_CHECK(n == argc + 1 && strcmp(words[0], "matremap") == 0);
        for (int k = 1; k < n && k <= argc; k++)
            MR_CHECK_MSG(strcmp(words[k], k == argc ? "x y" : argv[k - 1]) == 0, "word %d '%s'", k, words[k]);
        for (int k = 0; k < n; k++) free(words[k]);
    }
    free(header.text);
    free(line);
    MR_CHECK_OK(mr_sweep_command_line("matremap sweep", 0, NULL, &line));
    MR_CHECK(line != NULL && strcmp(line, "matremap sweep") == 0);
    free(line);
    MR_CHECK(mr_sweep_command_line(NULL, 0, NULL, &line) == MR_ERR_INVALID_ARG && line == NULL);
}

/* The remap and scene lines read by one name=value loop: a word without '=' and a name this version does not know
 * refused with the line's own noun; a scene name it does not write let through. */
MR_TEST(header_settings_refuse_what_they_do_not_know) {
    mr_fit_scene_options scene;
    MR_CHECK_OK(mr_sweep_scene_parse("fit size=32 light=frontal intensity=5 future=1", &scene));
    MR_CHECK(scene.size == 32 && scene.light == MR_FIT_LIGHT_FRONTAL && scene.intensity == 5.0);
    MR_CHECK(mr_sweep_scene_parse("fit size", &scene) == MR_ERR_FORMAT);
    MR_CHECK_MSG(strcmp(mr_last_error(), "'size' is not name=value") == 0, "%s", mr_last_error());
    MR_CHECK(mr_sweep_scene_parse("fit light=sideways", &scene) == MR_ERR_FORMAT);
    MR_CHECK_MSG(strcmp(mr_last_error(), "'light=sideways' is not a scene setting this version knows") == 0, "%s",
                 mr_last_error());
    MR_CHECK(mr_sweep_scene_parse("sphere size=32", &scene) == MR_ERR_FORMAT);

    mr_sweep_spec spec = random_spec(5, 7, 16);
    mr_strbuf header = {0};
    MR_CHECK_OK(mr_sweep_file_header(&spec, "cmd", 0, 0, &header));
    char texts[5][MR_SWEEP_MAX_LINE];
    const int found = header_texts(header.text, texts);
    free(header.text);
    if (!found) return;
    mr_sweep_spec back;
    const char *step = NULL;
    MR_CHECK_OK(mr_sweep_file_spec_from_header(texts[0], texts[1], texts[2], texts[3], texts[4], &back, &step));
    MR_CHECK(back.remap.strategy == spec.remap.strategy && back.remap.grid_points == spec.remap.grid_points);
    char remap[MR_SWEEP_MAX_LINE + 32];
    snprintf(remap, sizeof remap, "%s held=alpha", texts[2]);
    MR_CHECK_OK(mr_sweep_file_spec_from_header(texts[0], texts[1], remap, texts[3], texts[4], &back, &step));
    MR_CHECK(back.remap.held == 1u << mr_brdf_param_index(back.target, "alpha"));
    snprintf(remap, sizeof remap, "%s colour=blue", texts[2]);
    MR_CHECK(mr_sweep_file_spec_from_header(texts[0], texts[1], remap, texts[3], texts[4], &back, &step) ==
             MR_ERR_FORMAT);
    MR_CHECK(step != NULL && strcmp(step, "# remap:") == 0);
    MR_CHECK_MSG(strcmp(mr_last_error(), "'colour=blue' is not a remap option this version knows") == 0, "%s",
                 mr_last_error());
    snprintf(remap, sizeof remap, "%s held=alpha,nothing", texts[2]);
    MR_CHECK(mr_sweep_file_spec_from_header(texts[0], texts[1], remap, texts[3], texts[4], &back, &step) ==
             MR_ERR_FORMAT);
    MR_CHECK_MSG(strstr(mr_last_error(), "'held=alpha") != NULL, "%s", mr_last_error());
}

MR_TEST_MAIN(MR_TEST_ENTRY(grid_is_cartesian_first_axis_slowest_with_exact_endpoints),
             MR_TEST_ENTRY(held_targets_are_recorded_in_the_header_and_read_back),
             MR_TEST_ENTRY(command_line_quoting_round_trips_through_the_header),
             MR_TEST_ENTRY(header_settings_refuse_what_they_do_not_know),
             MR_TEST_ENTRY(grid_log_spacing_is_geometric), MR_TEST_ENTRY(grid_errors_name_the_bad_value),
             MR_TEST_ENTRY(random_samples_depend_only_on_seed_and_index_and_stay_in_bounds),
             MR_TEST_ENTRY(the_texture_region_draws_grey_linear_values),
             MR_TEST_ENTRY(rows_round_trip_exactly), MR_TEST_ENTRY(one_and_two_threads_write_the_same_file),
             MR_TEST_ENTRY(an_existing_file_is_never_overwritten_and_a_mismatching_one_never_touched),
             MR_TEST_ENTRY(resume_cuts_a_torn_line_and_ends_with_the_uninterrupted_file),
             MR_TEST_ENTRY(a_full_disk_leaves_whole_rows_and_the_sweep_resumes),
             MR_TEST_ENTRY(progress_is_reported_once_per_row_in_order),
             MR_TEST_ENTRY(two_and_three_ranks_write_the_single_process_file_and_resume_it),
             MR_TEST_ENTRY(a_rank_running_another_sweep_is_refused_before_the_file_is_made),
             MR_TEST_ENTRY(shards_merge_into_the_single_process_file),
             MR_TEST_ENTRY(merge_refuses_shards_that_do_not_belong_together),
             MR_TEST_ENTRY(resume_refuses_rows_that_are_not_sane_naming_line_and_column),
             MR_TEST_ENTRY(a_torn_last_row_is_never_counted_even_when_only_its_line_end_is_missing),
             MR_TEST_ENTRY(sweep_file_header_reads_back_and_the_column_reader_counts_lines))
