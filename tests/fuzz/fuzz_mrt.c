/*
 * fuzz_mrt.c — the learned-transform file reader (src/learn/learned.h, mr_learned_parse: the .mrt text
 * `convert --transform` reads), then the transform applied to its source model's defaults and to one batch, so
 * that a transform the reader accepts is also one the converter can run.
 */
#include "fuzz.h"
#include "matremap.h"

int mr_fuzz_mrt(const uint8_t *data, size_t size) {
    mr_learned *t = NULL;
    if (mr_learned_parse((const char *)data, size, "fuzz.mrt", &t) != MR_OK) return 0;
    // Two texels packed back to back (the batch's layout): the source model's defaults, and the same times 4,
    // outside most domains (the extrapolation flag's path).
    const int n = mr_brdf_value_count(t->source);
    double source[2 * MR_BRDF_MAX_VALUES], target[2 * MR_BRDF_MAX_VALUES];
    unsigned flags[2] = {0, 0};
    mr_brdf_default_values(t->source, source);
    for (int i = 0; i < n; i++) source[n + i] = 4.0 * source[i];
    mr_learned_apply(t, source, target, &flags[0]);
    (void)mr_learned_apply_batch(t, 2, source, target, flags);
    mr_learned_free(t);
    return 0;
}

MR_FUZZ_ENTRY(mr_fuzz_mrt)
