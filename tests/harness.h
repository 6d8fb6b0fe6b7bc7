/*
 * harness.h — the project's tiny test harness (after redis' testhelp.h).
 *
 * A test file defines cases with MR_TEST(name) { ... } and lists them in MR_TEST_MAIN(case, case, ...).
 * Checks record a failure with file:line and the values involved, and let the case go on. Each case prints a
 * numbered "ok"/"FAIL" line; the binary ends with "N passed, N failed" and exits non-zero on any failure.
 * `tests/test_x NAME` runs only the case called NAME.
 */
#ifndef MR_TEST_HARNESS_H
#define MR_TEST_HARNESS_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct mr_test_case {
    const char *name;
    void (*run)(void);
} mr_test_case;

static int mr_test_failures_in_case;

#define MR_TEST(name) static void name(void)

#define MR_CHECK(cond)                                                                   \
    do {                                                                                 \
        if (!(cond)) {                                                                   \
            fprintf(stderr, "    %s:%d: check failed: %s\n", __FILE__, __LINE__, #cond); \
            mr_test_failures_in_case++;                                                  \
        }                                                                                \
    } while (0)

/* Like MR_CHECK, with a printf-style explanation printed on failure. */
#define MR_CHECK_MSG(cond, ...)                                                          \
    do {                                                                                 \
        if (!(cond)) {                                                                   \
            fprintf(stderr, "    %s:%d: check failed: %s: ", __FILE__, __LINE__, #cond); \
            fprintf(stderr, __VA_ARGS__);                                                \
            fputc('\n', stderr);                                                         \
            mr_test_failures_in_case++;                                                  \
        }                                                                                \
    } while (0)

/* |actual - expected| <= tol, and both finite. */
#define MR_CHECK_NEAR(actual, expected, tol)                                                         \
    do {                                                                                             \
        double mr_a_ = (double)(actual), mr_e_ = (double)(expected), mr_t_ = (double)(tol);          \
        if (!(isfinite(mr_a_) && fabs(mr_a_ - mr_e_) <= mr_t_)) {                                    \
            fprintf(stderr, "    %s:%d: %s = %.17g, expected %.17g within %.3g\n", __FILE__, __LINE__, \
                    #actual, mr_a_, mr_e_, mr_t_);                                                   \
            mr_test_failures_in_case++;                                                              \
        }                                                                                            \
    } while (0)

/* The whole file at `path`, NUL-terminated (so text can be searched as a string; binary files too), its length
 * into *size (may be NULL); NULL if it cannot be read. The caller frees it. */
static inline char *mr_test_read_file(const char *path, size_t *size) {
    FILE *f = fopen(path, "rb");
    if (f == NULL) return NULL;
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *bytes = n >= 0 ? malloc((size_t)n + 1) : NULL;
    if (bytes != NULL && fread(bytes, 1, (size_t)n, f) != (size_t)n) {
        free(bytes);
        bytes = NULL;
    }
    fclose(f);
    if (bytes != NULL) bytes[n] = '\0';
    if (size != NULL) *size = bytes != NULL ? (size_t)n : 0;
    return bytes;
}

/* An mr_status call that must succeed; prints mr_last_error() otherwise. */
#define MR_CHECK_OK(call)                                                                          \
    do {                                                                                           \
        mr_status mr_s_ = (call);                                                                  \
        if (mr_s_ != MR_OK) {                                                                      \
            fprintf(stderr, "    %s:%d: %s -> %s: %s\n", __FILE__, __LINE__, #call, mr_status_str(mr_s_), \
                    mr_last_error());                                                              \
            mr_test_failures_in_case++;                                                            \
        }                                                                                          \
    } while (0)

static int mr_test_run_all(const mr_test_case *cases, int count, int argc, char **argv) {
    int passed = 0, failed = 0, number = 0;
    for (int i = 0; i < count; i++) {
        if (argc > 1 && strcmp(argv[1], cases[i].name) != 0) continue;
        mr_test_failures_in_case = 0;
        cases[i].run();
        number++;
        if (mr_test_failures_in_case == 0) {
            printf("%3d ok    %s\n", number, cases[i].name);
            passed++;
        } else {
            printf("%3d FAIL  %s (%d failed checks)\n", number, cases[i].name, mr_test_failures_in_case);
            failed++;
        }
        fflush(stdout);
    }
    if (argc > 1 && number == 0) {
        fprintf(stderr, "no test case named '%s'\n", argv[1]);
        return 2;
    }
    printf("%d passed, %d failed\n", passed, failed);
    return failed == 0 ? 0 : 1;
}

/* ---- a private scratch folder ---------------------------------------------------------------------------- */

static inline char *mr_test_scratch_buffer(void) {
    static char dir[256];
    return dir;
}

static inline void mr_test_scratch_remove(void) {
    const char *dir = mr_test_scratch_buffer();
    if (dir[0] == '\0') return;
    char cmd[300];
    snprintf(cmd, sizeof cmd, "rm -rf '%s'", dir);
    if (system(cmd) != 0) fprintf(stderr, "could not remove %s\n", dir);
}

/* The test binary's scratch folder in /tmp, created on first use and removed with everything in it at exit. */
static inline const char *mr_test_scratch_dir(void) {
    char *dir = mr_test_scratch_buffer();
    if (dir[0] == '\0') {
        strcpy(dir, "/tmp/mr_test.XXXXXX");
        if (mkdtemp(dir) == NULL) {
            perror("mkdtemp");
            exit(2);
        }
        atexit(mr_test_scratch_remove);
    }
    return dir;
}

/* A path inside the scratch folder, from a ring of 32 buffers (a caller that keeps a path longer copies it). */
static inline const char *mr_test_tmp_path(const char *name) {
    static char paths[32][512];
    static int slot;
    const char *dir = mr_test_scratch_dir();
    char *p = paths[slot++ % 32];
    snprintf(p, 512, "%s/%s", dir, name);
    return p;
}

/* The path of `rel` among the shared test assets: $MR_SHARED/assets/rel, or ../shared/assets/rel (the project root
 * is the working folder of `make check`). From a ring of 8 buffers. */
/* Write n bytes to `path` (created or truncated); 1 on success. */
static inline int mr_test_write_file(const char *path, const void *data, size_t n) {
    FILE *f = fopen(path, "wb");
    if (f == NULL) return 0;
    int ok = fwrite(data, 1, n, f) == n;
    return fclose(f) == 0 && ok;
}

static inline const char *mr_test_asset_path(const char *rel) {
    static char paths[8][1024];
    static int slot;
    const char *shared = getenv("MR_SHARED");
    char *p = paths[slot++ % 8];
    snprintf(p, 1024, "%s/assets/%s", shared ? shared : "../shared", rel);
    return p;
}

#define MR_TEST_ENTRY(fn) {#fn, fn}

#define MR_TEST_MAIN(...)                                                                   \
    int main(int argc, char **argv) {                                                       \
        static const mr_test_case cases[] = {__VA_ARGS__};                                  \
        return mr_test_run_all(cases, (int)(sizeof cases / sizeof cases[0]), argc, argv); \
    }

#endif /* MR_TEST_HARNESS_H */
