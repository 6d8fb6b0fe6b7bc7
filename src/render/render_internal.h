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

/* The plan of `plan`'s scene zoomed on its highlight (mr_scene_zoom_on_highlight), built on the first call and
 * kept by `plan` (freed with it; safe to call from several threads at once), so that repeated remaps with one
 * plan (sweeps) build it once. *out = NULL with MR_OK when the scene has no highlight to look at. A plan keeps
 * one zoom factor: a later call with another fails (MR_ERR_INVALID_ARG). */
mr_status mr_render_plan_zoomed(const mr_render_plan *plan, double zoom, const mr_render_plan **out);

#endif /* MR_RENDER_INTERNAL_H */
