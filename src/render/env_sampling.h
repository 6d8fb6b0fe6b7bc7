/*
 * env_sampling.h — the environment lights of a render plan as the plan and its renders sample them (internal to
 * src/render/; render.c builds and reads it, env_sampling.c fills it): per light, a fixed pattern of directions
 * importance-sampled from its map, with their L / (N pdf) weights; with reflection samples, M directions about
 * each hit's mirror direction, combined with the pattern by multiple importance sampling (balance heuristic).
 * docs/rendering.md, "The estimator", derives the weights. Built once per plan (mr_env_table_setup), read-only
 * afterwards, so any number of threads may render from it.
 */
#ifndef MR_RENDER_ENV_SAMPLING_H
#define MR_RENDER_ENV_SAMPLING_H

#include "../mr_internal.h"
#include "../mr_status.h"
#include "render.h"
#include "vec3.h"

/* Where a hit's reflection samples go (world space): r, the view reflected about the shading normal; a, the
 * unit direction perpendicular to r in the plane of r and the normal; b = r x a; and squash = n.v (at least
 * 0.02). A GGX lobe about the normal of width alpha reflects to a lobe about r of width 2 alpha along a and
 * 2 alpha n.v along b: tilting the half vector out of the plane of incidence turns the reflection by only
 * 2 (v.h) times the tilt. */
struct reflection_frame {
    double r[3], a[3], b[3];
    double squash;
};

/* What a direction that is not in the pattern needs of an environment light: its radiance and pattern pdf.
 * The map is borrowed while the plan is built and forgotten afterwards. */
typedef struct env_source {
    const mr_image *map;
    double total;               /* sum of luminance * sin(theta_row) over the map: the pattern's normaliser */
    int n;                      /* the light's pattern size N */
    double cos_turn, sin_turn;  /* its rotation about +y */
    double intensity[3];
    int reflections;            /* 1 if it takes part in the reflection samples' MIS */
} env_source;

/* The reflection samples' distribution q: an equal mixture of lobes about the mirror direction r, each shaped
 * like an anisotropic GGX distribution of normals about r, of widths beta along the frame's a and
 * beta * squash along b (struct reflection_frame): in slopes (x/z, y/z) of a direction (x, y, z) in the frame
 * (a, b, r), q = P22(slopes) / z^3 with P22 = 1 / (pi bx by (1 + (x/z)^2 / bx^2 + (y/z)^2 / by^2)^2) (the
 * hemisphere about r). Near r a GGX material of roughness alpha reflects a lobe of this shape with beta ~
 * 2 alpha, heavy tails included, so the widths run from 2e-4 (alpha 1e-4, the models' floor) to 0.125
 * (alpha ~ 0.06): a lobe much wider than the pattern's spacing is already well sampled by the pattern, whose
 * MIS weight then dominates. */
#define REFLECTION_LOBES 5
static const double reflection_beta[REFLECTION_LOBES] = {0.125, 0.025, 0.005, 0.001, 0.0002};

/* The fixed directions of every environment light of the scene, concatenated in light order. */
typedef struct env_table {
    int count;
    double (*direction)[3]; /* world space, unit */
    double (*weight)[3];    /* L(w) * scale / (pdf(w) * N) per RGB channel; 0 for directions never used */
    double *mis_npdf;       /* N pdf(w) of a direction whose light takes reflection samples, 0 otherwise */
    int reflections;        /* M: reflection samples per hit (0: none, and mis_npdf is NULL) */
    int per_lobe[REFLECTION_LOBES]; /* how many of the M each lobe of q draws */
    double (*unit_slopes)[2]; /* [M]: the lobes' directions as slopes of a unit-width lobe, lobe by lobe */
    int source_count;
    env_source *sources;    /* [source_count], while the plan is built only */
} env_table;

/* Number of directions of an environment light's pattern (its samples, or MR_ENV_DEFAULT_SAMPLES). */
int mr_env_light_samples(const mr_light *light);

/* The directions of every environment light of the scene, concatenated in light order, into *env (zeroed by the
 * caller); the maps are borrowed until the plan is built (env->sources). MR_ERR_NOMEM (env freed) on allocation
 * failure. */
mr_status mr_env_table_setup(const mr_scene *scene, env_table *env);

/* Release env's arrays and zero it. */
void mr_env_table_free(env_table *env);

/* The radiance of `source` along world direction w (unit), into L (RGB, intensity included), and N pdf(w) of
 * its pattern: the inverse of env_fill's mapping, with the same piecewise-constant texel and pdf. */
double mr_env_source_lookup(const env_source *source, const double w[3], double L[3]);

/* M q(w): the reflection samples' density at unit direction w, times their number. The slopes come from dot
 * products with a and b, which keep their precision at the narrowest lobe (1 - r.w would cancel). q is taken as
 * 0 more than acos(REFLECTION_CONE_COS) = 53 degrees from r (about 10 widths of the widest lobe): the MIS weights
 * stay a partition of unity as long as the pattern's factor and the reflection samples' weights use the same q
 * (a reflection sample out there would weigh 0; none of the fixed ones is), and the render skips the lobes for
 * most pattern directions with one dot product. */
#define REFLECTION_CONE_COS 0.6
static inline double reflection_density(const env_table *env, const struct reflection_frame *f, const double w[3]) {
    const double z = vec3_dot(f->r, w);
    if (!(z > REFLECTION_CONE_COS)) return 0.0;
    const double sx = vec3_dot(f->a, w) / z, sy = vec3_dot(f->b, w) / z, z3 = z * z * z;
    double sum = 0.0;
    for (int j = 0; j < REFLECTION_LOBES; j++) {
        const double bx = reflection_beta[j], by = reflection_beta[j] * f->squash;
        const double d = 1.0 + sx * sx / (bx * bx) + sy * sy / (by * by);
        sum += env->per_lobe[j] / (MR_PI * bx * by * z3 * d * d);
    }
    return sum;
}

#endif /* MR_RENDER_ENV_SAMPLING_H */
