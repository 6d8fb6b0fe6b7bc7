/*
 * models.h — declarations of every model descriptor, and the registration order (internal to src/brdf and
 * the tests; callers use mr_brdf_find / mr_brdf_models).
 */
#ifndef MR_BRDF_MODELS_H
#define MR_BRDF_MODELS_H

#include "brdf.h"

extern const mr_brdf_model mr_brdf_lambert;

/* Display order of `matremap models`; registry.c expands it into its table. */
#define MR_BRDF_REGISTERED_MODELS \
    &mr_brdf_lambert,

#endif /* MR_BRDF_MODELS_H */
