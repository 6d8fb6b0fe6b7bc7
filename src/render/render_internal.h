/*
 * render_internal.h — renders with a thread count of the caller's choosing (internal to the library: remaps pass
 * mr_remap_options.threads through here; render.h's calls use the plan's rule, mr_scene.threads).
 */
#ifndef MR_RENDER_INTERNAL_H
#define MR_RENDER_INTERNAL_H

#include "render.h"

/* mr_render_into and mr_render_components_into with `threads` OpenMP threads (0 = the plan's). */
mr_status mr_render_into_threads(const mr_render_plan *plan, int threads, const mr_brdf_model *model,
                                 const double *values, mr_component component, mr_image *image);
mr_status mr_render_components_into_threads(const mr_render_plan *plan, int threads, const mr_brdf_model *model,
                                            const double *values, mr_image *diffuse, mr_image *specular);

/* A scene that looks at the first point light's highlight on the sphere (render.c, sphere_highlight) `zoom`
 * times closer: the same camera position, turned towards the highlight, its field of view `zoom` times
 * narrower, the same image size. Returns 0 (out untouched) when the scene is not a sphere or no point light's
 * highlight is seen. */
int mr_scene_zoom_on_highlight(const mr_scene *scene, double zoom, mr_scene *out);

#endif /* MR_RENDER_INTERNAL_H */
