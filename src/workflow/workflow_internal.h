/*
 * workflow_internal.h — the Khronos converter shared by workflow.c and khronos.c; not installed, not public.
 *
 * Both functions take sanitised values (finite, in [0, 1]) and write finite values in [0, 1]; they are pure.
 */
#ifndef MR_WORKFLOW_INTERNAL_H
#define MR_WORKFLOW_INTERNAL_H

/* The Khronos converter's constants (three.pbrUtilities.js: dielectricSpecular, epsilon). */
#define MR_WF_KHRONOS_F0 0.04
#define MR_WF_KHRONOS_EPSILON 1e-6

/* ConvertToSpecularGlossiness without the glossiness: base colour and metallic -> diffuse, specular. */
void mr_wf_khronos_metal_to_spec(const double base[3], double metallic, double diffuse[3], double specular[3]);

/* ConvertToMetallicRoughness without the roughness: diffuse, specular -> base colour, metallic. */
void mr_wf_khronos_spec_to_metal(const double diffuse[3], const double specular[3], double base[3], double *metallic);

#endif /* MR_WORKFLOW_INTERNAL_H */
