/*
 * lambert.c — the Lambertian (ideal diffuse) BRDF.
 *
 *   f_r = albedo / pi   (diffuse part; the specular part is 0)
 *
 * Parameters: albedo (RGB, [0,1], default 0.5 as Mitsuba's `diffuse`).
 * Source: Mitsuba 0.6 src/bsdfs/diffuse.cpp (eval() there includes cos(theta_o); ours does not, see brdf.h).
 * Energy: the white-furnace albedo is exactly `albedo` for every incident direction.
 */
#include "brdf_batch.h"

typedef struct lambert_state {
    double albedo_over_pi[3];
} lambert_state;

static const mr_brdf_param lambert_params[] = {
    {"albedo", 3, 0.5, 0.0, 1.0, MR_PARAM_LINEAR, MR_LOBE_DIFFUSE, MR_PARAM_SRGB_MAP,
     "diffuse reflectance (linear RGB)", NULL},
};

static void lambert_prepare(const mr_brdf_model *model, const double *values, void *state_bytes) {
    (void)model;
    lambert_state *state = state_bytes;
    for (int c = 0; c < 3; c++) state->albedo_over_pi[c] = mr_clampd(values[c], 0.0, 1.0) * MR_INV_PI;
}

static void lambert_eval(const void *state_bytes, const double wi[3], const double wo[3], double diffuse[3],
                         double specular[3]) {
    const lambert_state *state = state_bytes;
    int lit = wi[2] > 0.0 && wo[2] > 0.0;
    for (int c = 0; c < 3; c++) {
        if (diffuse) diffuse[c] = lit ? state->albedo_over_pi[c] : 0.0;
        if (specular) specular[c] = 0.0;
    }
}

/* eval over a batch (brdf.h eval_batch). */
MR_BATCH_INLINE void lambert_batch_body(const void *state_bytes, const mr_brdf_batch *batch, const int fused) {
    (void)fused;
    const lambert_state *state = state_bytes;
    const double a0 = state->albedo_over_pi[0], a1 = state->albedo_over_pi[1], a2 = state->albedo_over_pi[2];
    MR_BATCH_ARRAYS(batch);
    (void)ix_, (void)iy_, (void)ox_, (void)oy_;
#pragma omp simd
    for (int i = 0; i < n_; i++) {
        const int lit = (iz_[i] > 0.0) & (oz_[i] > 0.0);
        d0_[i] = lit ? a0 : 0.0;
        d1_[i] = lit ? a1 : 0.0;
        d2_[i] = lit ? a2 : 0.0;
        s0_[i] = s1_[i] = s2_[i] = 0.0;
    }
}

MR_BATCH_KERNEL(lambert_eval_batch, lambert_batch_body)

static void lambert_eval_grad(const mr_brdf_model *model, const double *values, const double wi[3],
                              const double wo[3], double *d_diffuse, double *d_specular) {
    (void)model;
    (void)values;
    int lit = wi[2] > 0.0 && wo[2] > 0.0;
    for (int j = 0; j < 3; j++)
        for (int c = 0; c < 3; c++) {
            d_diffuse[j * 3 + c] = (lit && j == c) ? MR_INV_PI : 0.0;
            d_specular[j * 3 + c] = 0.0;
        }
}

const mr_brdf_model mr_brdf_lambert = {
    .name = "lambert",
    .summary = "ideal diffuse reflector, f = albedo/pi",
    .source = "Mitsuba 0.6 diffuse.cpp",
    .param_count = (int)(sizeof lambert_params / sizeof lambert_params[0]),
    .params = lambert_params,
    .flags = 0,
    .config = NULL,
    .prepare = lambert_prepare,
    .eval = lambert_eval,
    .eval_batch = lambert_eval_batch,
    .eval_grad = lambert_eval_grad,
};
