/*
 * workflow_internal.h — the Khronos converter shared by workflow.c and khronos.c, and the batch's anchors for
 * tests; not installed, not public.
 *
 * Both functions take sanitised values (finite, in [0, 1]) and write finite values in [0, 1]; they are pure.
 */
#ifndef MR_WORKFLOW_INTERNAL_H
#define MR_WORKFLOW_INTERNAL_H

#include <stddef.h>

struct mr_wf_residual_anchor;

/* The Khronos converter's constants (three.pbrUtilities.js: dielectricSpecular, epsilon). */
#define MR_WF_KHRONOS_F0 0.04
#define MR_WF_KHRONOS_EPSILON 1e-6

/* ConvertToSpecularGlossiness without the glossiness: base colour and metallic -> diffuse, specular. */
void mr_wf_khronos_metal_to_spec(const double base[3], double metallic, double diffuse[3], double specular[3]);

/* ConvertToMetallicRoughness without the roughness: diffuse, specular -> base colour, metallic. */
void mr_wf_khronos_spec_to_metal(const double diffuse[3], const double specular[3], double base[3], double *metallic);

/* The residual anchors (workflow.h, mr_wf_residual_anchor_of) of `count` rows whose lobe and specular channel c are
 * planes[c * stride + r] and planes[(3 + c) * stride + r] (sanitised doubles), into out[0 .. count): at most at
 * vector level `level` (2: eight rows at a time with AVX-512, 1: four with AVX2, 0: one at a time), as far as the
 * CPU allows and MR_WF_SCALAR_ANCHORS (set and non-empty: 0) permits; the same bits at every level (workflow.c).
 * Returns the level used. For tests. */
int mr_wf_residual_anchors(const double *planes, size_t stride, size_t count, int level,
                           struct mr_wf_residual_anchor *out);

#endif /* MR_WORKFLOW_INTERNAL_H */
