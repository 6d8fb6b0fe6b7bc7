/* vec3.h — the few double-precision 3-vector operations the renderer needs (internal). */
#ifndef MR_VEC3_H
#define MR_VEC3_H

#include <math.h>

static inline double vec3_dot(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

static inline void vec3_sub(const double a[3], const double b[3], double out[3]) {
    out[0] = a[0] - b[0];
    out[1] = a[1] - b[1];
    out[2] = a[2] - b[2];
}

static inline void vec3_cross(const double a[3], const double b[3], double out[3]) {
    double x = a[1] * b[2] - a[2] * b[1];
    double y = a[2] * b[0] - a[0] * b[2];
    double z = a[0] * b[1] - a[1] * b[0];
    out[0] = x;
    out[1] = y;
    out[2] = z;
}

static inline double vec3_length(const double a[3]) { return sqrt(vec3_dot(a, a)); }

/* Normalise in place; returns the original length (0 leaves the vector unchanged). */
static inline double vec3_normalize(double a[3]) {
    double len = vec3_length(a);
    if (len > 0.0) {
        a[0] /= len;
        a[1] /= len;
        a[2] /= len;
    }
    return len;
}

static inline int vec3_is_finite(const double a[3]) { return isfinite(a[0]) && isfinite(a[1]) && isfinite(a[2]); }

/* Orthonormal basis with n as third axis, continuous except at n.z = -1 (Duff et al., "Building an
 * Orthonormal Basis, Revisited", JCGT 6(1), 2017). Isotropic models only need n; the tangents give
 * anisotropic models and normal maps a defined frame where a surface has no tangents of its own. */
static inline void vec3_frame_from_normal(const double n[3], double t[3], double b[3]) {
    double sign = n[2] >= 0.0 ? 1.0 : -1.0;
    double a = -1.0 / (sign + n[2]);
    double c = n[0] * n[1] * a;
    t[0] = 1.0 + sign * n[0] * n[0] * a;
    t[1] = sign * c;
    t[2] = -sign * n[0];
    b[0] = c;
    b[1] = sign + n[1] * n[1] * a;
    b[2] = -n[1];
}

#endif /* MR_VEC3_H */
