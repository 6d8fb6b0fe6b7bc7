/*
 * srgb.c — the sRGB transfer functions (contract in image_io.h).
 *
 * IEC 61966-2-1:1999 (sRGB), exact piecewise form, evaluated in double:
 *   decode  V <= 0.04045   : L = V / 12.92          else L = ((V + 0.055) / 1.055)^2.4
 *   encode  L <= 0.0031308 : V = 12.92 L            else V = 1.055 L^(1/2.4) - 0.055
 * The breakpoints are the standard's (0.04045 / 0.0031308), not the 0.03928 of the 1996 draft. Inputs outside
 * [0,1] follow the same formulas mirrored through 0 (odd extension), so negative values stay negative instead
 * of turning into NaN; callers that need display values clamp first. NaN stays NaN.
 */
#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <string.h>

#include "image_io.h"
#include "io_internal.h"
#include "mr_internal.h"

double mr_srgb_decode_double(double v) {
    double a = fabs(v);
    double l = a <= 0.04045 ? a / 12.92 : pow((a + 0.055) / 1.055, 2.4);
    return v < 0.0 ? -l : (v >= 0.0 ? l : v);
}

float mr_srgb_to_linear(float encoded) { return (float)mr_srgb_decode_double(encoded); }

double mr_srgb_encode_double(double l) {
    double a = fabs(l);
    double v = a <= 0.0031308 ? 12.92 * a : 1.055 * pow(a, 1.0 / 2.4) - 0.055;
    return l < 0.0 ? -v : (l >= 0.0 ? v : l);
}

float mr_linear_to_srgb(float linear) { return (float)mr_srgb_encode_double(linear); }

/* ---- 8-bit sRGB codes by table ----
 * code(v) = floor(clamp(enc(clamp(v)), 0, 1) * 255 + 0.5) with enc = mr_linear_to_srgb, the writer's rule
 * (image_io.c, quantise()), costs a pow per value. It is a non-decreasing step function of v, so it is fully
 * described by its 255 steps: threshold[q] = the smallest float v with code(v) >= q, found by bisection over the
 * ordered bit patterns of the non-negative floats with code() itself, so the table answers exactly as code() does.
 * A coarse index (1024 cells over [0, 1]) gives the first candidate; sRGB's steepest slope (12.92 near 0) puts at
 * most a few steps in a cell. */
#define SRGB8_CELLS 1024
static float srgb8_threshold[257]; /* [q] for q = 1..255; [256] = +inf */
static unsigned char srgb8_cell_code[SRGB8_CELLS + 1];
static pthread_once_t srgb8_once = PTHREAD_ONCE_INIT;

static unsigned srgb8_code_slow(float v) {
    double x = mr_clampd(v, 0.0, 1.0);
    x = mr_linear_to_srgb((float)x);
    return (unsigned)floor(mr_clampd(x, 0.0, 1.0) * 255.0 + 0.5);
}

static void srgb8_init(void) {
    for (unsigned q = 1; q <= 255; q++) {
        uint32_t lo = 0, hi = 0x3f800000u; // bits of 0.0f and 1.0f: code(lo) < q <= code(hi)
        while (hi - lo > 1) {
            uint32_t mid = lo + (hi - lo) / 2;
            float v;
            memcpy(&v, &mid, sizeof v);
            if (srgb8_code_slow(v) >= q) hi = mid;
            else lo = mid;
        }
        memcpy(&srgb8_threshold[q], &hi, sizeof hi);
    }
    srgb8_threshold[256] = INFINITY;
    for (int cell = 0; cell <= SRGB8_CELLS; cell++)
        srgb8_cell_code[cell] = (unsigned char)srgb8_code_slow((float)cell / SRGB8_CELLS);
}

void mr_srgb8_init(void) { pthread_once(&srgb8_once, srgb8_init); }

unsigned char mr_srgb8_encode(float linear) {
    if (!(linear > 0.0f)) return 0; // NaN, 0 and negatives
    if (linear >= 1.0f) return 255;
    unsigned q = srgb8_cell_code[(int)(linear * SRGB8_CELLS)];
    while (linear >= srgb8_threshold[q + 1]) q++;
    return (unsigned char)q;
}
