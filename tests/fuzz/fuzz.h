/*
 * fuzz.h — what the fuzz targets of tests/fuzz/ share (docs/reliability.md, "Fuzzing").
 *
 * Each target is one function `int mr_fuzz_NAME(const uint8_t *data, size_t size)` that feeds the bytes to one
 * reader and returns 0 whatever the reader says: a target fails only by crashing, leaking, tripping a sanitizer
 * or taking too long. The same object serves two builds:
 *   - `make fuzz` compiles it with clang and -DMR_FUZZ_LIBFUZZER, which makes MR_FUZZ_ENTRY below define
 *     libFuzzer's LLVMFuzzerTestOneInput (and LLVMFuzzerInitialize) around the target;
 *   - `make check` links every target into tests/test_fuzz_inputs.c, which replays the seed corpora and the
 *     regression inputs (tests/fuzz/regressions/NAME/: every finding, kept) on the normal and the ASan build.
 * Targets keep no state between calls other than what fuzz_scratch_path prepares once.
 */
#ifndef MR_TESTS_FUZZ_H
#define MR_TESTS_FUZZ_H

#include <stddef.h>
#include <stdint.h>

typedef int (*mr_fuzz_fn)(const uint8_t *data, size_t size);

/* Every target (tests/fuzz/fuzz_NAME.c). */
int mr_fuzz_gltf(const uint8_t *data, size_t size);
int mr_fuzz_png(const uint8_t *data, size_t size);
int mr_fuzz_jpeg(const uint8_t *data, size_t size);
int mr_fuzz_exr(const uint8_t *data, size_t size);
int mr_fuzz_hdr(const uint8_t *data, size_t size);
int mr_fuzz_mlp(const uint8_t *data, size_t size);
int mr_fuzz_mrt(const uint8_t *data, size_t size);
int mr_fuzz_sweep(const uint8_t *data, size_t size);
int mr_fuzz_cli_value(const uint8_t *data, size_t size);
int mr_fuzz_obj(const uint8_t *data, size_t size);
int mr_fuzz_mtlx(const uint8_t *data, size_t size);

/* A file path private to this process (a folder made once under $TMPDIR or /tmp, removed at exit) whose name
 * ends in `name`, e.g. fuzz_scratch_path("in.glb"); the same name gives the same path. NULL if the folder cannot
 * be made. */
const char *fuzz_scratch_path(const char *name);

/* Write data[size] to fuzz_scratch_path(name), replacing it; the path, or NULL on failure. */
const char *fuzz_write_scratch(const char *name, const uint8_t *data, size_t size);

/* Stops the run (abort) unless the OpenImageIO module loads: a fuzzer whose copied build lacks lib/matremap/ would
 * otherwise run at full speed through one early error and cover nothing (it happened: fuzz_hdr reached 65 edges at
 * 20k executions/s). Checked once, by reading a one-pixel Radiance HDR from memory, never from a message (an error
 * message quotes the input, and the fuzzer learns the words a target looks for: matching "cannot load the
 * OpenImageIO module" in mr_last_error() stopped fuzz_exr within a minute). */
void fuzz_require_setup(void);

#ifdef MR_FUZZ_LIBFUZZER
#define MR_FUZZ_ENTRY(fn)                                                                                              \
    int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);                                                      \
    int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size) { return fn(data, size); }
#else
#define MR_FUZZ_ENTRY(fn)
#endif

#endif /* MR_TESTS_FUZZ_H */
