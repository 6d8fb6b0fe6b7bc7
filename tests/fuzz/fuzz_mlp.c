/*
 * fuzz_mlp.c — the network file reader (nn/mlp.h, mr_mlp_parse: the .mlp text `spec2metal --weights` and
 * `train` read), then one prediction through what it built, so that a network the reader accepts is also one
 * the predictor can run.
 */
#include <stdlib.h>

#include "fuzz.h"
#include "nn/mlp.h"

int mr_fuzz_mlp(const uint8_t *data, size_t size) {
    mr_mlp *net = NULL;
    if (mr_mlp_parse((const char *)data, size, "fuzz.mlp", &net) != MR_OK) return 0;
    float *in = calloc((size_t)net->n_in, sizeof *in), *out = calloc((size_t)net->n_out, sizeof *out);
    if (in != NULL && out != NULL) {
        for (int i = 0; i < net->n_in; i++) in[i] = 0.5f;
        (void)mr_mlp_predict_threads(net, in, 1, out, 1);
    }
    free(in);
    free(out);
    mr_mlp_free(net);
    return 0;
}

MR_FUZZ_ENTRY(mr_fuzz_mlp)
