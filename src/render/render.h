/*
 * render.h — scenes (camera + object + lights) rendered to linear HDR float RGB with any BRDF descriptor.
 *
 * Main calls, in order:
 *   mr_scene scene = mr_scene_fit(NULL);          // the paper's fit scene (section 4.1), or fill in your own
 *   mr_render_plan *plan; mr_render_plan_create(&scene, &plan);
 *   mr_image *img; mr_render(plan, model, values, MR_COMPONENT_FULL, &img);   // as often as needed
 *   mr_render_plan_free(plan);
 *
 * Design (docs/design.md principle 2, "simulate only the effects a scene calls for"):
 *   - A plan is built once per scene. It traces one primary ray through each pixel centre, keeps the pixels
 *     that hit the object, and for each light stores the shading sample: the view and light directions in the
 *     local shading frame and the light's contribution weight I*cos(theta_light)/d^2. Pixels that see the
 *     object but no light are black and carry no sample. Pixels on the silhouette get a fixed grid of
 *     edge_samples^2 sub-pixel rays instead, each weighted by its share of the pixel, so edges are
 *     box-filtered (as a path tracer's are) rather than aliased; the rest of the image needs no extra rays.
 *   - Rendering a material is then only BRDF evaluations on the stored samples: radiance = sum over the
 *     pixel's samples of f_r(view, light) * weight. Nothing geometric is recomputed.
 *   - A lone sphere is convex, so nothing can shadow a point it lights: no shadow rays. A point light is a
 *     delta: no sampling, each lit pixel is evaluated exactly. Primary rays are never jittered, so renders are
 *     noise-free and deterministic, and the optimiser sees a smooth objective.
 *   - Extension points: new object types add an intersector producing hit records (position, shading frame);
 *     new light types (environment maps with a fixed sample pattern) add a sample generator over those hit
 *     records; objects that can occlude themselves (triangle meshes) add shadow rays in that generator.
 *     Nothing in mr_render changes.
 * Units: light intensity is radiant intensity in W/sr per RGB channel (Mitsuba's point emitter); pixels hold
 * radiance. World space is right-handed with +y up; the default camera looks down -z.
 * Threads: mr_render parallelises over pixels with OpenMP; each pixel is summed in a fixed order, so output is
 * bit-identical for any thread count. A plan is immutable after creation and may be shared between threads.
 */
#ifndef MR_RENDER_H
#define MR_RENDER_H

#include "../brdf/brdf.h"
#include "../mr_image.h"
#include "../mr_status.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum mr_component {
    MR_COMPONENT_FULL = 0, /* diffuse + specular */
    MR_COMPONENT_DIFFUSE,
    MR_COMPONENT_SPECULAR,
    MR_COMPONENT_COUNT
} mr_component;

/* "full", "diffuse", "specular"; NULL outside the enum. */
const char *mr_component_name(mr_component component);
/* Parse one of the names above; MR_ERR_INVALID_ARG listing them otherwise. */
mr_status mr_component_from_name(const char *name, mr_component *out);

typedef struct mr_camera {
    double position[3];
    double target[3];
    double up[3];
    double fov_y_degrees; /* vertical field of view of the perspective camera, (0, 180) */
} mr_camera;

typedef enum mr_light_type {
    MR_LIGHT_POINT = 0,
    MR_LIGHT_TYPE_COUNT
} mr_light_type;

typedef struct mr_light {
    mr_light_type type;
    double position[3];
    double intensity[3]; /* radiant intensity, W/sr, linear RGB */
} mr_light;

typedef enum mr_shape_type {
    MR_SHAPE_SPHERE = 0,
    MR_SHAPE_TYPE_COUNT
} mr_shape_type;

typedef struct mr_shape {
    mr_shape_type type;
    double center[3];
    double radius;
} mr_shape;

#define MR_SCENE_MAX_LIGHTS 8

typedef struct mr_scene {
    int width;  /* pixels, 1 .. MR_RENDER_MAX_SIZE */
    int height;
    mr_camera camera;
    mr_shape shape;
    int light_count; /* 1 .. MR_SCENE_MAX_LIGHTS */
    mr_light lights[MR_SCENE_MAX_LIGHTS];
    double background[3]; /* radiance of pixels that miss the object */
    int edge_samples;     /* silhouette pixels are box-filtered with edge_samples x edge_samples sub-pixel rays;
                             1 = pixel centres only (aliased edges); 0 = MR_SCENE_DEFAULT_EDGE_SAMPLES; <= 16 */
} mr_scene;

#define MR_SCENE_DEFAULT_EDGE_SAMPLES 4

#define MR_RENDER_MAX_SIZE 16384

/* Where the fit scene's point light sits. */
typedef enum mr_fit_light {
    MR_FIT_LIGHT_45 = 0,  /* 45 degrees from the view direction, in the horizontal plane, to the camera's right */
    MR_FIT_LIGHT_FRONTAL, /* on the view axis, between camera and sphere ("headlight", paper section 9) */
    MR_FIT_LIGHT_COUNT
} mr_fit_light;

/* "45", "frontal"; NULL outside the enum. */
const char *mr_fit_light_name(mr_fit_light light);
/* Parse "45" or "frontal"; MR_ERR_INVALID_ARG listing them otherwise. */
mr_status mr_fit_light_from_name(const char *name, mr_fit_light *out);

typedef struct mr_fit_scene_options {
    int size;            /* image side in pixels; 0 = 512 (the paper's) */
    mr_fit_light light;  /* 0 = MR_FIT_LIGHT_45 (the paper's) */
    double intensity;    /* point-light radiant intensity in W/sr; 0 = 10 */
} mr_fit_scene_options;

/* The paper's fit scene (section 4.1): unit sphere at the origin; point light at distance 3 from the origin,
 * 45 degrees from the view direction (or frontal); black background; size x size pixels. The paper does not
 * give its camera; ours is a perspective camera at (0,0,4) looking at the origin, vertical field of view 35
 * degrees, so the sphere (angular radius asin(1/4) = 14.5 degrees) fills 83 % of the frame height.
 * opts may be NULL for all defaults. */
mr_scene mr_scene_fit(const mr_fit_scene_options *opts);

/* Check a scene's values (sizes, finite vectors, radius > 0, camera not inside the sphere, non-degenerate
 * camera frame, light count). MR_ERR_INVALID_ARG with the offending field otherwise. */
mr_status mr_scene_validate(const mr_scene *scene);

typedef struct mr_render_plan mr_render_plan;

/* Trace the scene's geometry once (see the header comment). *out is owned by the caller (mr_render_plan_free).
 * Fails with MR_ERR_INVALID_ARG (mr_scene_validate) or MR_ERR_NOMEM. */
mr_status mr_render_plan_create(const mr_scene *scene, mr_render_plan **out);

void mr_render_plan_free(mr_render_plan *plan);

/* The scene the plan was built from. */
const mr_scene *mr_render_plan_scene(const mr_render_plan *plan);

/* Number of pixels that see the object and receive light, i.e. the BRDF evaluations per light per render. */
int mr_render_plan_lit_pixel_count(const mr_render_plan *plan);

/* Number of shading samples, i.e. the BRDF evaluations one render makes (lit pixels x lights, plus the extra
 * sub-pixel samples of silhouette pixels). */
long mr_render_plan_sample_count(const mr_render_plan *plan);

/* Number of pixels that see the object at all (lit or not, fully or partly covered). */
int mr_render_plan_object_pixel_count(const mr_render_plan *plan);

/* The fraction of each pixel the object covers (width*height floats, row-major, top-left first): 1 inside the
 * silhouette, 0 outside, in between on it. Owned by the plan. Useful as a mask for fits and metrics. */
const float *mr_render_plan_coverage(const mr_render_plan *plan);

/* Render `component` of the material (model, packed values as in brdf.h) into a new RGB image (*out, owned
 * by the caller). values are clamped into the model's bounds by its prepare(). */
mr_status mr_render(const mr_render_plan *plan, const mr_brdf_model *model, const double *values,
                    mr_component component, mr_image **out);

/* Like mr_render, into an existing 3-channel image of the plan's size (no allocation: the optimiser's inner
 * loop). Every pixel is written. */
mr_status mr_render_into(const mr_render_plan *plan, const mr_brdf_model *model, const double *values,
                         mr_component component, mr_image *image);

/* The diffuse and specular components in one pass (either image may be NULL); both 3-channel, plan-sized.
 * full = diffuse + specular pixel by pixel, up to float rounding. */
mr_status mr_render_components_into(const mr_render_plan *plan, const mr_brdf_model *model,
                                    const double *values, mr_image *diffuse, mr_image *specular);

#ifdef __cplusplus
}
#endif

#endif /* MR_RENDER_H */
