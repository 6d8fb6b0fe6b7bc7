/*
 * learned_kind.c — a chain of learned transforms as a transform kind of src/transform (contract in learned.h), so
 * that texture sets go through the library's one texture-set conversion (mr_transform_convert_maps).
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "learn/learned.h"
#include "mr_internal.h"
#include "transform/transform.h"

/* The kind and everything it points to, in one block. */
typedef struct learned_kind {
    mr_transform_model_kind model; /* first: the kind's address is the block's */
    const mr_learned *hops[MR_LEARNED_MAX_HOPS];
    int hop_count;
    char name[32], summary[512];
} learned_kind;

/* Texels go through the chain in blocks of this many packed rows (the regression runs on a block at a time). */
#define BLOCK 1024

static mr_status learned_apply(const mr_transform *t, const mr_transform_batch *b) {
    const learned_kind *lk = mr_transform_state(t);
    const mr_transform_kind *kind = &lk->model.kind;
    const size_t sc = (size_t)mr_brdf_value_count(lk->hops[0]->source);
    const size_t tc = (size_t)mr_brdf_value_count(lk->hops[lk->hop_count - 1]->target);
    const size_t m = MR_MIN(b->n, BLOCK);
    double *v = malloc(m * sc * sizeof *v), *w = malloc(m * tc * sizeof *w);
    unsigned *flags = malloc(m * sizeof *flags);
    mr_status status = v && w && flags ? MR_OK : mr_fail(MR_ERR_NOMEM, "transform %s: out of memory", kind->name);
    for (size_t start = 0; start < b->n && status == MR_OK; start += BLOCK) {
        const size_t count = MR_MIN(BLOCK, b->n - start);
        for (size_t i = 0; i < count; i++) {
            size_t k = 0;
            for (int s = 0; s < kind->input_count; s++)
                for (int c = 0; c < kind->inputs[s].channels; c++)
                    v[i * sc + k++] = b->in[s][(start + i) * (size_t)kind->inputs[s].channels + (size_t)c];
        }
        status = mr_learned_chain_apply_batch(lk->hops, lk->hop_count, count, v, w, flags);
        for (size_t i = 0; status == MR_OK && i < count; i++) {
            size_t k = 0;
            for (int s = 0; s < kind->output_count; s++)
                for (int c = 0; c < kind->outputs[s].channels; c++)
                    b->out[s][(start + i) * (size_t)kind->outputs[s].channels + (size_t)c] = (float)w[i * tc + k++];
            b->flags[start + i] = (uint8_t)flags[i];
        }
    }
    free(v);
    free(w);
    free(flags);
    return status;
}

mr_status mr_learned_kind_create(const mr_learned *const *hops, int count, mr_transform_kind **out) {
    if (hops == NULL || out == NULL || count < 1 || count > MR_LEARNED_MAX_HOPS)
        return mr_fail(MR_ERR_INVALID_ARG, "learned kind: NULL argument or %d hops (1 .. %d)", count,
                       MR_LEARNED_MAX_HOPS);
    for (int h = 0; h < count; h++) {
        if (hops[h] == NULL) return mr_fail(MR_ERR_INVALID_ARG, "learned kind: hop %d is NULL", h + 1);
        if (h > 0 && hops[h - 1]->target != hops[h]->source)
            return mr_fail(MR_ERR_INVALID_ARG, "transform chain: hop %d ends in %s but hop %d starts from %s", h,
                           hops[h - 1]->target->name, h + 1, hops[h]->source->name);
    }
    learned_kind *lk = calloc(1, sizeof *lk);
    if (lk == NULL) return mr_fail(MR_ERR_NOMEM, "learned kind: out of memory");
    const mr_brdf_model *source = hops[0]->source, *target = hops[count - 1]->target;
    memcpy(lk->hops, hops, (size_t)count * sizeof *hops);
    lk->hop_count = count;
    snprintf(lk->name, sizeof lk->name, "%s", count == 1 ? mr_learn_method_name(hops[0]->method) : "chain");
    int at = snprintf(lk->summary, sizeof lk->summary, "learned from sweeps: %s", source->name);
    for (int h = 0; h < count && at > 0 && (size_t)at < sizeof lk->summary; h++)
        at += snprintf(lk->summary + at, sizeof lk->summary - (size_t)at, " -(%s)-> %s",
                       mr_learn_method_name(hops[h]->method), hops[h]->target->name);
    mr_status status = mr_transform_model_kind_init(&lk->model, source, target, lk->name, lk->summary,
                                                    MR_TRANSFORM_PER_TEXEL, lk, learned_apply);
    if (status != MR_OK) {
        free(lk);
        return status;
    }
    *out = &lk->model.kind;
    return MR_OK;
}

void mr_learned_kind_free(mr_transform_kind *kind) {
    free(kind); // the kind is the first member of its learned_kind block
}
