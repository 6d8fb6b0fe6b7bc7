/*
 * lambert.c — the Lambertian (ideal diffuse) BRDF.
 *
 *   f_r = albedo / pi   (diffuse part; the specular part is 0)
 *
 * Parameters: albedo (RGB, [0,1], default 0.5 as Mitsuba's `diffuse`).
 * Source: Mitsuba 0.6 src/bsdfs/diffuse.cpp (eval() there includes cos(theta_o); ours does not, see brdf.h).
 * Energy: the white-furnace albedo is exactly `albedo` for every incident direction.
 */
#include "../mr_internal.h"
#include "brdf.h"

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
    .eval_grad = lambert_eval_grad,
};
