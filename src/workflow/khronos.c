/*
 * khronos.c — the Khronos glTF converter between the metal-rough and spec-gloss workflows, as a baseline.
 *
 * Source: KhronosGroup/glTF, extensions/2.0/Archived/KHR_materials_pbrSpecularGlossiness/examples/
 * convert-between-workflows/js/three.pbrUtilities.js and three.colorExtensions.js (brdf-reference 5.4). This is a
 * reference port: the operations are the JS's, in its order, in double precision like JS numbers, so a value
 * computed here equals the JS's up to the last bit of Math.sqrt. Around it, workflow.c clamps the inputs to [0, 1]
 * and the metal -> spec results too (the JS's diffuse can round ~1e-12 above 1); the JS clamps the base colour of
 * its spec -> metal result itself, and so does this port.
 *
 *   P(c) = sqrt(0.299 r^2 + 0.587 g^2 + 0.114 b^2)   (Color.getPerceivedBrightness)
 *   maxC(c) = max(r, g, b)                           (Color.getMaxComponent)
 *   metal -> spec:  specular = lerp(0.04, base, m);  diffuse = base (1 - 0.04)(1 - m) / max(1 - maxC(specular), eps)
 *   spec -> metal:  o = 1 - maxC(specular);  s = P(specular);  d = P(diffuse)
 *                   m = 0 if s < 0.04, else the clamped larger root of 0.04 m^2 + b m + c = 0 with
 *                   b = d o / (1 - 0.04) + s - 0.08, c = 0.04 - s (discriminant floored at 0)
 *                   base = clamp(lerp(diffuse o / (1 - 0.04) / max(1 - m, eps),
 *                                     (specular - 0.04 (1 - m)) / max(m, eps), m^2), 0, 1)
 */
#include <math.h>

#include "../mr_internal.h"
#include "workflow_internal.h"

/* THREE.Math.clamp(value, min, max) = Math.max(min, Math.min(max, value)). */
static double js_clamp(double value, double lo, double hi) { return fmax(lo, fmin(hi, value)); }

/* Color.lerp(color, alpha): this += (color - this) * alpha. */
static double js_lerp(double from, double to, double alpha) { return from + (to - from) * alpha; }

static double max_component(const double c[3]) { return fmax(fmax(c[0], c[1]), c[2]); }

static double perceived_brightness(const double c[3]) {
    return sqrt(0.299 * c[0] * c[0] + 0.587 * c[1] * c[1] + 0.114 * c[2] * c[2]);
}

void mr_wf_khronos_metal_to_spec(const double base[3], double metallic, double diffuse[3], double specular[3]) {
    const double f0 = MR_WF_KHRONOS_F0;
    for (int c = 0; c < 3; c++) specular[c] = js_lerp(f0, base[c], metallic);
    double one_minus_specular_strength = 1.0 - max_component(specular);
    double scale = (1.0 - f0) * (1.0 - metallic) / fmax(one_minus_specular_strength, MR_WF_KHRONOS_EPSILON);
    for (int c = 0; c < 3; c++) diffuse[c] = base[c] * scale;
}

/* solveMetallic(diffuse, specular, oneMinusSpecularStrength) of the JS, on perceived brightnesses. */
static double solve_metallic(double diffuse, double specular, double one_minus_specular_strength) {
    const double f0 = MR_WF_KHRONOS_F0;
    if (specular < f0) return 0.0;
    double a = f0;
    double b = diffuse * one_minus_specular_strength / (1.0 - f0) + specular - 2.0 * f0;
    double c = f0 - specular;
    double discriminant = fmax(b * b - 4.0 * a * c, 0.0);
    return js_clamp((-b + sqrt(discriminant)) / (2.0 * a), 0.0, 1.0);
}

void mr_wf_khronos_spec_to_metal(const double diffuse[3], const double specular[3], double base[3], double *metallic) {
    const double f0 = MR_WF_KHRONOS_F0;
    double one_minus_specular_strength = 1.0 - max_component(specular);
    double m = solve_metallic(perceived_brightness(diffuse), perceived_brightness(specular),
                              one_minus_specular_strength);
    double diffuse_scale = one_minus_specular_strength / (1.0 - f0) / fmax(1.0 - m, MR_WF_KHRONOS_EPSILON);
    double specular_scale = 1.0 / fmax(m, MR_WF_KHRONOS_EPSILON);
    for (int c = 0; c < 3; c++) {
        double from_diffuse = diffuse[c] * diffuse_scale;
        double from_specular = (specular[c] - f0 * (1.0 - m)) * specular_scale;
        base[c] = js_clamp(js_lerp(from_diffuse, from_specular, m * m), 0.0, 1.0);
    }
    *metallic = m;
}
