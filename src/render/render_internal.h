/*
 * render_internal.h — what render.c shares with the render module's tests only (internal: not installed). The
 * calls other modules use (renders with a thread count of the caller's, the plan zoomed on the highlight) are
 * public, in render.h.
 */
#ifndef MR_RENDER_INTERNAL_H
#define MR_RENDER_INTERNAL_H

#include "render.h"

/* A scene that looks at the first point light's highlight on the sphere (render.c, sphere_highlight) `zoom`
 * times closer: the same camera position, turned towards the highlight, its field of view `zoom` times
 * narrower, the same image size. Returns 0 (out untouched) when the scene is not a sphere or no point light's
 * highlight is seen (mr_render_plan_zoomed builds its plan from this scene). */
int mr_scene_zoom_on_highlight(const mr_scene *scene, double zoom, mr_scene *out);

#endif /* MR_RENDER_INTERNAL_H */
