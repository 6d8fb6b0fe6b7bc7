/*
 * direct_kind.c — the direct remap (direct.h) as a transform kind of src/transform, so that `matremap convert
 * --direct` converts texture sets through the library's one texture-set conversion (mr_transform_convert_maps).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "mr_internal.h"
#include "remap/direct.h"

typedef struct direct_kind {
    mr_transform_model_kind model; /* first: the kind's address is the block's */
    const mr_brdf_model *source, *target;
    mr_direct_options opts;
    mr_direct_summary summary;
} direct_kind;

static mr_status direct_apply(const mr_transform *t, const mr_transform_batch *b) {
    direct_kind *dk = mr_transform_state(t);
    const mr_transform_kind *kind = &dk->model.kind;
    const size_t n = b->n, sc = (size_t)mr_brdf_value_count(dk->source), tc = (size_t)mr_brdf_value_count(dk->target);
    double *in = malloc(n * sc * sizeof *in), *out = malloc(n * tc * sizeof *out);
    mr_fit_outcome *outcomes = malloc(n * sizeof *outcomes);
    mr_status status = in && out && outcomes ? MR_OK : mr_fail(MR_ERR_NOMEM, "direct: out of memory for %zu texels", n);
    for (size_t i = 0; status == MR_OK && i < n; i++) {
        uint8_t f = 0;
        size_t k = 0;
        for (int s = 0; s < kind->input_count; s++)
            for (int c = 0; c < kind->inputs[s].channels; c++, k++) {
                double v = b->in[s][i * (size_t)kind->inputs[s].channels + (size_t)c];
                if (!isfinite(v)) {
                    f |= MR_WF_NONFINITE_INPUT;
                    v = kind->inputs[s].min;
                } else if (v < kind->inputs[s].min || v > kind->inputs[s].max) {
                    f |= MR_WF_CLAMPED_INPUT;
                }
                in[i * sc + k] = v;
            }
        b->flags[i] = f;
    }
    if (status == MR_OK)
        status = mr_direct_remap(dk->source, dk->target, in, n, &dk->opts, out, outcomes, &dk->summary);
    for (size_t i = 0; status == MR_OK && i < n; i++) {
        size_t k = 0;
        for (int s = 0; s < kind->output_count; s++)
            for (int c = 0; c < kind->outputs[s].channels; c++, k++)
                b->out[s][i * (size_t)kind->outputs[s].channels + (size_t)c] = (float)out[i * tc + k];
        if (outcomes[i] != MR_FIT_CONVERGED) b->flags[i] |= MR_WF_UNCONVERGED;
    }
    free(in);
    free(out);
    free(outcomes);
    return status;
}

mr_status mr_direct_kind_create(const mr_brdf_model *source, const mr_brdf_model *target, const mr_direct_options *opts,
                                mr_transform_kind **out) {
    if (source == NULL || target == NULL || out == NULL) return mr_fail(MR_ERR_INVALID_ARG, "direct: NULL argument");
    direct_kind *dk = calloc(1, sizeof *dk);
    if (dk == NULL) return mr_fail(MR_ERR_NOMEM, "direct: out of memory");
    mr_status status = mr_transform_model_kind_init(
        &dk->model, source, target, "direct",
        "every distinct (quantised) texel remapped by the image-based optimiser (direct.h)", 0, dk, direct_apply);
    if (status != MR_OK) {
        free(dk);
        return status;
    }
    dk->source = source;
    dk->target = target;
    if (opts != NULL) dk->opts = *opts;
    *out = &dk->model.kind;
    return MR_OK;
}

const mr_direct_summary *mr_direct_kind_summary(const mr_transform_kind *kind) {
    return kind ? &((const direct_kind *)kind->config)->summary : NULL;
}

void mr_direct_kind_free(mr_transform_kind *kind) { free(kind); }
