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

#include "image_io.h"
#include "io_internal.h"

double mr_srgb_decode_double(double v) {
    double a = fabs(v);
    double l = a <= 0.04045 ? a / 12.92 : pow((a + 0.055) / 1.055, 2.4);
    return v < 0.0 ? -l : (v >= 0.0 ? l : v);
}

float mr_srgb_to_linear(float encoded) { return (float)mr_srgb_decode_double(encoded); }

float mr_linear_to_srgb(float linear) {
    double l = linear, a = fabs(l);
    double v = a <= 0.0031308 ? 12.92 * a : 1.055 * pow(a, 1.0 / 2.4) - 0.055;
    return (float)(l < 0.0 ? -v : (l >= 0.0 ? v : l));
}
