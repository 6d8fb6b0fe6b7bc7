/*
 * test_fuzz_inputs.c — every fuzz target of tests/fuzz/ run over the inputs kept for it: the findings
 * (tests/fuzz/regressions/NAME/, each a file that once crashed, leaked or hung, kept after its fix) and, when one
 * has been made, the seed corpus (tests/fuzz/make-corpus.sh; `make fuzz` makes build/fuzz/corpus; MR_FUZZ_CORPUS
 * names another). A target fails only by crashing or tripping a sanitizer (make asan runs this too), so the
 * checks here are that the inputs were found and each call returned.
 */
#include <dirent.h>
#include <stdint.h>
#include <sys/stat.h>

#include "fuzz/fuzz.h"
#include "harness.h"

typedef struct target {
    const char *name;
    mr_fuzz_fn run;
} target;

static const target targets[] = {
    {"gltf", mr_fuzz_gltf},   {"png", mr_fuzz_png}, {"jpeg", mr_fuzz_jpeg},   {"exr", mr_fuzz_exr},
    {"hdr", mr_fuzz_hdr},     {"mlp", mr_fuzz_mlp}, {"mrt", mr_fuzz_mrt},     {"sweep", mr_fuzz_sweep},
    {"cli_value", mr_fuzz_cli_value}, {"obj", mr_fuzz_obj}, {"mtlx", mr_fuzz_mtlx},
};

static unsigned char *read_whole(const char *path, size_t *size) {
    FILE *f = fopen(path, "rb");
    if (f == NULL) return NULL;
    unsigned char *bytes = NULL;
    size_t capacity = 0, used = 0;
    for (;;) {
        if (used == capacity) {
            capacity = capacity ? 2 * capacity : 65536;
            unsigned char *grown = realloc(bytes, capacity);
            if (grown == NULL) break;
            bytes = grown;
        }
        size_t n = fread(bytes + used, 1, capacity - used, f);
        used += n;
        if (n == 0) break;
    }
    fclose(f);
    *size = used;
    return bytes;
}

/* Runs `t` over every regular file in dir (missing: 0 files); returns the count, -1 if one could not be read. */
static int replay_dir(const target *t, const char *dir) {
    DIR *d = opendir(dir);
    if (d == NULL) return 0;
    int count = 0;
    struct dirent *e;
    while ((e = readdir(d)) != NULL) {
        char path[4096];
        struct stat st;
        snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
        if (stat(path, &st) != 0 || !S_ISREG(st.st_mode)) continue;
        size_t size = 0;
        unsigned char *bytes = read_whole(path, &size);
        if (bytes == NULL && size != 0) {
            count = -1;
            break;
        }
        // Printed first, so that a crash names its input.
        printf("    %s %s (%zu bytes)\n", t->name, path, size);
        fflush(stdout);
        t->run(bytes != NULL ? bytes : (const uint8_t *)"", size);
        free(bytes);
        count++;
    }
    closedir(d);
    return count;
}

MR_TEST(every_target_replays_its_findings_and_corpus) {
    const char *root = getenv("MR_ROOT");
    const char *corpus = getenv("MR_FUZZ_CORPUS");
    char dir[8192], default_corpus[4096];
    snprintf(default_corpus, sizeof default_corpus, "%s/build/fuzz/corpus", root ? root : ".");
    if (corpus == NULL) corpus = default_corpus;
    int total = 0;
    for (size_t i = 0; i < sizeof targets / sizeof targets[0]; i++) {
        snprintf(dir, sizeof dir, "%s/tests/fuzz/regressions/%s", root ? root : ".", targets[i].name);
        int kept = replay_dir(&targets[i], dir);
        snprintf(dir, sizeof dir, "%s/%s", corpus, targets[i].name);
        int seeds = replay_dir(&targets[i], dir);
        MR_CHECK_MSG(kept >= 0 && seeds >= 0, "%s: an input could not be read", targets[i].name);
        total += kept + seeds;
    }
    printf("    %d inputs replayed\n", total);
    MR_CHECK(total > 0);
}

MR_TEST_MAIN(MR_TEST_ENTRY(every_target_replays_its_findings_and_corpus))
