/*
 * mr_internal.h — helpers shared by the library's translation units; not installed, not public.
 *
 * Every library file includes this header (and never the umbrella matremap.h): it brings the core every layer
 * needs, mr_core.h (the version, the data path, the one RNG, atomic output files, input files, the automatic
 * thread rule), and adds what only the library's own code uses (mr_fail, the clamps, the hash).
 * C and C++ (the image-I/O and glTF shims) both include it, so it uses no C-only syntax.
 */
#ifndef MR_INTERNAL_H
#define MR_INTERNAL_H

#include <stdint.h>

#include "mr_core.h"
#include "mr_image.h"
#include "mr_status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* pi to double precision; strict C11 has no M_PI. */
#define MR_PI 3.14159265358979323846
#define MR_INV_PI 0.31830988618379067154

/* Record a printf-style message in this thread's last-error buffer and return `status`, so a failure site
 * reads `return mr_fail(MR_ERR_IO, "image '%s': cannot open: %s", path, strerror(errno));` */
#if defined(__GNUC__)
__attribute__((format(printf, 2, 3)))
#endif
mr_status mr_fail(mr_status status, const char *fmt, ...);

/* Prepend context to the message already recorded by a failing callee ("outer: inner") and return `status`. */
#if defined(__GNUC__)
__attribute__((format(printf, 2, 3)))
#endif
mr_status mr_fail_context(mr_status status, const char *fmt, ...);

/* mr_image_check_radiance (mr_image.h), or with allow_negative only finiteness ("expected finite values"): what
 * the metrics ask of the images they compare. */
mr_status mr_image_check_values(const mr_image *image, const char *label, int allow_negative);

#define MR_MIN(a, b) ((a) < (b) ? (a) : (b))
#define MR_MAX(a, b) ((a) > (b) ? (a) : (b))

/* For a hot helper called with constant arguments that must be specialised at each call (GCC and Clang; a
 * plain `inline` elsewhere): the compiler otherwise clones it once for all callers. */
#if defined(__GNUC__)
#define MR_ALWAYS_INLINE inline __attribute__((always_inline))
#else
#define MR_ALWAYS_INLINE inline
#endif

/* A module `file` (libmatremap-oiio.so, libmatremap-mpi.so) beside the running executable, in
 * <its directory>/../lib/matremap/ (the build tree's build/bin -> build/lib/matremap, an install's PREFIX/bin ->
 * PREFIX/lib/matremap): its path into out[size] and 1 when that file exists, else 0 (data_dir.c). */
int mr_module_beside_executable(const char *file, char *out, size_t size);

/* What a module loader asks of mr_module_open: the file, the environment variable naming another path, the symbols
 * a candidate must have (all of them), what to call it in messages ("image" says "not a matremap image module"),
 * and optionally a check of a candidate whose symbols were found: NULL when it serves, else why not (e.g. an
 * interface version of another build), written into reason[size]. */
typedef struct mr_module_spec {
    const char *file, *variable, *kind;
    const char *const *symbols;
    int symbol_count;
    const char *(*check)(void *const *entries, char *reason, size_t size);
} mr_module_spec;

/* Load the module `spec` describes, trying in order: the path in spec->variable when it is set (then nothing else:
 * an explicit choice is not second-guessed), the file beside the executable (mr_module_beside_executable),
 * MR_MODULE_DIR/file (the install directory fixed at build time); a candidate serves when it loads, has every symbol
 * and passes the check. Returns its dlopen handle with entries[k] the address of symbols[k], or NULL with why each
 * candidate failed, naming its path, appended to why[size] ("; " between them). */
void *mr_module_open(const mr_module_spec *spec, void **entries, char *why, size_t size);

/* Seconds on the monotonic clock (an arbitrary origin): for durations the library reports. */
double mr_now_seconds(void);

/* A 32-bit hash of n words (splitmix64's mixing, word by word): the deduplication tables of the batch converters
 * (transform.c, workflow.c) key texels by the bits of their values. */
static inline uint32_t mr_hash_words(const uint32_t *k, int n) {
    uint64_t h = 0x9e3779b97f4a7c15ULL;
    for (int i = 0; i < n; i++) {
        h = (h ^ k[i]) * 0xbf58476d1ce4e5b9ULL;
        h ^= h >> 29;
    }
    return (uint32_t)(h >> 32);
}

static inline double mr_clampd(double x, double lo, double hi) {
    /* NaN maps to lo: no NaN may leave a clamp (design principle 6). */
    return x >= lo ? (x <= hi ? x : hi) : lo;
}

#ifdef __cplusplus
}
#endif

#endif /* MR_INTERNAL_H */
