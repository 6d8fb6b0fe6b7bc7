/*
 * render.h — scenes (camera + object + lights) rendered to linear HDR float RGB with any BRDF descriptor.
 *
 * Main calls, in order:
 *   mr_scene scene = mr_scene_fit(NULL);          // the paper's fit scene (section 4.1), or fill in your own
 *   mr_render_plan *plan; mr_render_plan_create(&scene, &plan);
 *   mr_image *img; mr_render(plan, model, values, MR_COMPONENT_FULL, &img);   // as often as needed
 *   mr_render_textured(plan, model, values, &textures, MR_COMPONENT_FULL, &img); // parameters from maps
 *   mr_render_plan_free(plan);
 * Environment lighting: scene.lights[i] = mr_light_environment(map, 1.0, 0.0, 0) (an equirectangular HDR
 * image, e.g. read with mr_img_read) in place of, or beside, the point light. docs/rendering.md has the details.
 * Triangle meshes: scene.shape.type = MR_SHAPE_MESH, scene.shape.mesh = &mesh (an mr_mesh the caller fills, e.g.
 * from a glTF primitive, or one read from an OBJ file by mr_obj_load, io/obj_load.h), and
 * mr_camera_frame_mesh(&mesh, NULL, &scene.camera) to frame it.
 *
 * Design (docs/design.md principle 2, "simulate only the effects a scene calls for"):
 *   - A plan is built once per scene. It traces one primary ray through each pixel centre and keeps the hits on
 *     the object that receive light: the view direction in the local shading frame, the frame itself and the
 *     texture coordinates (u, v) (the sphere's, or a mesh's TEXCOORD_0). For each light it stores the hit's
 *     shading samples. Pixels that see the object but no light are black and carry no sample. Pixels on the
 *     silhouette get a fixed grid of
 *     edge_samples^2 sub-pixel rays (hits) instead, each weighted by its share of the pixel, so edges are
 *     box-filtered (as a path tracer's are) rather than aliased; the rest of the image needs no extra rays.
 *   - Rendering a material is then only BRDF evaluations on the stored samples: radiance = sum over the
 *     pixel's samples of f_r(view, light) * weight. Nothing geometric is traced again.
 *   - A lone sphere is convex, so nothing can shadow a point it lights: no shadow rays; nor for a convex mesh.
 *     A mesh that can occlude itself gets shadow rays, traced once in the plan, which keeps only the samples
 *     that see their light, so renders still cost only BRDF evaluations (mr_render_plan_shadow_ray_count,
 *     docs/rendering.md "Triangle meshes"). A point light is a delta: no sampling, each lit pixel is
 *     evaluated exactly; its sample holds the local light direction and
 *     the weight I*cos(theta_light)/d^2. Primary rays are never jittered, so renders are noise-free and
 *     deterministic, and the optimiser sees a smooth objective.
 *   - An environment light is sampled with one fixed set of N directions, the same for every pixel:
 *     Hammersley points warped by the map's luminance x sin(theta) (importance sampling), each direction
 *     carrying L(w) / (pdf(w) N). A hit keeps the directions above its horizon (cos > 0, the only visibility
 *     test a convex object needs). Such a sample is stored as the direction's 2-byte index: the render turns
 *     it into the local light direction (3 dot products with the hit's frame) and the weight
 *     L/(pdf N) * cos * share, far cheaper than the BRDF evaluation it feeds, and 20-40 times less memory
 *     than storing directions and weights. The pattern does not change between renders, so images have no
 *     noise; its error is a fixed bias that shrinks as N grows (docs/rendering.md has the estimator, its error
 *     against N and the cost).
 *   - Extension points: new object types add an intersector producing hit records (position, shading frame,
 *     texture coordinates); new light types add a sample generator over those hit records; objects that can
 *     occlude themselves (non-convex triangle meshes, through their BVH) add shadow rays in that generator.
 *     Nothing in mr_render changes.
 * Units: point-light intensity is radiant intensity in W/sr per RGB channel (Mitsuba's point emitter); an
 * environment map holds radiance; pixels hold radiance. World space is right-handed with +y up; the default
 * camera looks down -z.
 * Coordinate conventions (docs/rendering.md draws them):
 *   - Environment maps are equirectangular, seen from inside like a panorama: column u in [0,1) is the azimuth,
 *     row v in [0,1] the polar angle from +y (top row = up). The map's centre (u = 0.5, v = 0.5) lies in
 *     direction -z, straight ahead of the default camera (behind the sphere), and u grows towards +x (the
 *     camera's right), so the panorama reads as the camera would see it; the seam u = 0 = 1 lies at +z,
 *     behind the camera. Direction of (u, v): theta = pi v, phi = 2 pi (u - 0.5),
 *     w = (sin theta sin phi, cos theta, -sin theta cos phi). A rotation of R degrees then turns the map about
 *     +y, right-handed (counter-clockwise seen from above: what lay at +z moves towards +x for R = 90).
 *   - The sphere's texture coordinates come from its unit normal n (world axes; the sphere does not rotate),
 *     seen from outside: u = 0.5 + atan2(n.x, n.z) / (2 pi), v = acos(n.y) / pi. The texture's centre faces
 *     +z (the default camera), u grows to the right of the image (+x), v = 0 (the texture's top row) is the
 *     north pole (+y); the seam u = 0 = 1 is the meridian at -z, hidden from the default camera, which sees
 *     the cap within 75.5 degrees of +z (u in [0.29, 0.71] along the equator).
 * Threads: the plan's creation and mr_render parallelise over pixels with OpenMP, as many threads as
 * mr_scene.threads says (by default a team only for work large enough to gain from it); each pixel is summed in a
 * fixed order, so output is bit-identical for any thread count. A plan is immutable after creation and may be
 * shared between threads.
 */
#ifndef MR_RENDER_H
#define MR_RENDER_H

#include "../brdf/brdf.h"
#include "../mr_image.h"
#include "../mr_status.h"

#include <stdint.h>

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
    MR_LIGHT_ENVIRONMENT, /* an equirectangular radiance map at infinity, sampled with a fixed pattern */
    MR_LIGHT_TYPE_COUNT
} mr_light_type;

typedef struct mr_light {
    mr_light_type type;
    double position[3];  /* MR_LIGHT_POINT: world position; ignored by environment lights */
    double intensity[3]; /* MR_LIGHT_POINT: radiant intensity, W/sr, linear RGB;
                            MR_LIGHT_ENVIRONMENT: RGB factor on the map's radiance (1,1,1 = as stored) */
    /* MR_LIGHT_ENVIRONMENT only (ignored by point lights): */
    const mr_image *environment; /* equirectangular radiance map (conventions in the header comment), linear,
                                    1 (grey), 3 or 4 channels (alpha ignored), finite and >= 0. Borrowed: it is
                                    read by mr_render_plan_create only; the plan keeps no reference to it (the
                                    copy in mr_render_plan_scene() is the caller's pointer, maybe stale) */
    double rotation_degrees;     /* turns the map about +y (right-handed); any finite value, 360 = 0 exactly */
    int samples;                 /* N, directions of the fixed sample pattern; 0 = MR_ENV_DEFAULT_SAMPLES;
                                    1 .. MR_ENV_MAX_SAMPLES, and all environment lights of a scene together
                                    at most MR_ENV_MAX_SAMPLES */
    int reflection_samples;      /* M, directions drawn around each hit's mirror direction (the view reflected
                                    about the shading normal) in addition to the pattern, both combined by
                                    multiple importance sampling (balance heuristic; docs/rendering.md,
                                    "Reflection samples"). They find the lobes of smooth materials (GGX alpha
                                    down to 1e-4) that the pattern misses. 0 = the pattern alone (default);
                                    0 .. MR_ENV_MAX_REFLECTION_SAMPLES; a scene uses the largest M of its
                                    environment lights for every light that asks for reflection samples. */
} mr_light;

/* Environment-light sample counts (docs/rendering.md tables error and time against N). */
#define MR_ENV_DEFAULT_SAMPLES 256
#define MR_ENV_MAX_SAMPLES 65536
#define MR_ENV_MAX_REFLECTION_SAMPLES 1024

/* An environment light: `map` (borrowed, see mr_light) times `scale` in every channel, turned by
 * rotation_degrees about +y, sampled with `samples` directions (0 = MR_ENV_DEFAULT_SAMPLES). Values are checked
 * by mr_scene_validate, not here. */
mr_light mr_light_environment(const mr_image *map, double scale, double rotation_degrees, int samples);

/* ---- triangle meshes (MR_SHAPE_MESH) ----------------------------------------------------------------------
 * A mesh is plain data the caller owns (the glTF loader fills one per primitive): flat float arrays as glTF
 * accessors hold them, 32-bit triangle indices, and an object-to-world transform. mr_render_plan_create reads
 * it once into the plan's own world-space copy (positions transformed, normals by the inverse transpose,
 * tangents by the matrix with their handedness flipped by a mirroring transform) and keeps no reference, like
 * environment maps. Missing attributes are generated in world space:
 *   - normals: smooth vertex normals, each face's unit normal weighted by the vertex's corner angle
 *     (Thuermer and Wuethrich 1998), so the result does not depend on how a face is split into triangles;
 *   - tangents (only with UVs): per-triangle tangents along +u and bitangents along -v (glTF's v grows
 *     downwards, normal maps' +y is up), each normalised and weighted by the corner angle, accumulated per
 *     vertex, made orthogonal to the normal; w = -1 where the accumulated bitangent is on the side of
 *     -cross(n, t) (mirrored UVs). MikkTSpace-like, not bit-compatible with MikkTSpace (no vertex splitting).
 * Shading at a hit interpolates normal, tangent and UV with the barycentrics; the frame is
 * (t orthogonalised against n, w * cross(n, t), n), or an arbitrary frame about n without tangents. UVs
 * (TEXCOORD_0) feed mr_param_textures maps (0, 0 without UVs). Camera rays do not see the back of a
 * single-sided triangle (its winding seen clockwise from the camera): they pass through to what lies behind, as
 * glTF's back-face culling asks, and light passes through the single-sided triangles it sees from behind (a
 * closed mesh still shadows itself, through the faces the light sees from the front). A hit whose interpolated
 * normal faces away from the camera is covered but unlit (black); with double_sided set, a hit on a triangle's
 * back has its normal and bitangent reversed first, as glTF's doubleSided materials ask.
 * With surfaces, each hit then reads its triangle's material's surface (mr_surface):
 *   - a normal map tilts the shading frame: n' = normalize(s x t + s y b + z n) with (x, y, z) = 2 texel - 1 and
 *     s = normal_scale; the tangent is made orthogonal to n' again and the bitangent follows. A tilted normal
 *     that faces away from the camera while the surface faces it is bent back towards the camera until
 *     n'.view = 0.01 (else grazing pixels of bumpy surfaces turn black).
 *   - occlusion multiplies the environment light's samples at the hit by ao' (glTF applies occlusion to the
 *     ambient, image-based light; point lights are not occluded by it);
 *   - emission adds emission x map radiance at the hit to full renders (not to component renders, so diffuse
 *     + specular = full holds for non-emissive surfaces only). An emitting hit is kept even when no light
 *     reaches it. */
/* ---- texture sampling (BRDF parameter maps and mesh surface maps) --------------------------------------------
 * Every map is sampled bilinearly, texel centres at ((i + 0.5)/width, (j + 0.5)/height), without mipmaps (a map
 * much finer than the object's pixels aliases; shrink it first), at the hit's texture coordinates after the map's
 * mr_texture_sampling: the coordinate set, KHR_texture_transform, then the wrap mode of each axis applied to the
 * texel indices. A zero-initialised mr_texture_sampling is the sphere's convention: TEXCOORD_0, no transform,
 * repeat along u (the seam) and clamp along v (the poles). */
typedef enum mr_wrap {
    MR_WRAP_DEFAULT = 0, /* repeat along u, clamp along v */
    MR_WRAP_REPEAT,      /* glTF 10497 */
    MR_WRAP_CLAMP,       /* glTF 33071, CLAMP_TO_EDGE */
    MR_WRAP_MIRROR,      /* glTF 33648, MIRRORED_REPEAT */
    MR_WRAP_COUNT
} mr_wrap;

typedef struct mr_texture_sampling {
    mr_wrap wrap_u, wrap_v;
    int texcoord;        /* 0: TEXCOORD_0 (a sphere's (u, v)); 1: a mesh's TEXCOORD_1 ((0, 0) where it has none) */
    int has_transform;   /* KHR_texture_transform: uv' = offset + R(rotation) (scale * uv), with
                            R(r) (x, y) = (cos r x + sin r y, -sin r x + cos r y) (rotation in radians) */
    double offset[2], rotation, scale[2];
} mr_texture_sampling;

/* MR_ERR_INVALID_ARG naming `what` for an unknown wrap mode, a texcoord other than 0 or 1, or a non-finite
 * transform. */
mr_status mr_texture_sampling_validate(const mr_texture_sampling *sampling, const char *what);

/* ---- surfaces: what a mesh material adds to its BRDF (glTF's normal, occlusion and emissive textures) --------
 * A mesh may carry several materials (triangle_materials); each has a surface. Surfaces are geometry as far as
 * the renderer is concerned: the plan samples them once at every hit (like the shading frame), so renders still
 * cost only BRDF evaluations, and every material rendered on the plan shares them (a conversion of an asset
 * keeps its normal, occlusion and emissive textures). */
typedef struct mr_surface {
    int double_sided;               /* as mr_mesh.double_sided, for this material's triangles */
    const mr_image *normal_map;     /* tangent-space normals, linear RGB (channels 0-2; 2c - 1 per axis, +y up as
                                       glTF), on the mesh's tangent frame; NULL = none */
    mr_texture_sampling normal_sampling;
    double normal_scale;            /* glTF normalTexture.scale, on x and y; used as given (glTF's default: 1) */
    const mr_image *occlusion_map;  /* ambient occlusion in channel 0 (R), linear; NULL = none */
    mr_texture_sampling occlusion_sampling;
    double occlusion_strength;      /* ao' = 1 + strength (ao - 1); as given (glTF's default: 1) */
    double emission[3];             /* emitted radiance, linear RGB (glTF emissiveFactor x emissive strength) */
    const mr_image *emissive_map;   /* multiplies emission: linear RGB (sRGB-decoded when read); NULL = none */
    mr_texture_sampling emissive_sampling;
} mr_surface;

typedef struct mr_mesh {
    int vertex_count;        /* >= 3 */
    const float *positions;  /* [vertex_count * 3], object space, finite; required */
    const float *normals;    /* [vertex_count * 3], object space; NULL = generated (smooth); a vertex whose
                                normal is (0, 0, 0) gets a generated one (merged primitives, some without) */
    const float *tangents;   /* [vertex_count * 4], xyz object space, w = +-1 (bitangent = w cross(n, t));
                                NULL = generated from the UVs when there are UVs; a vertex with w = 0 gets a
                                generated one */
    const float *uvs;        /* [vertex_count * 2], TEXCOORD_0 (u right, v down, as glTF); NULL = none */
    const float *uvs1;       /* [vertex_count * 2], TEXCOORD_1, for maps that ask for it; NULL = none */
    int triangle_count;      /* >= 1; at least one triangle must have a non-zero area */
    const uint32_t *indices; /* [triangle_count * 3], each < vertex_count; counter-clockwise seen from the
                                front (the side the generated normals face) */
    int double_sided;        /* 0: backs of triangles are not shaded (glTF's default); 1: lit like fronts.
                                Ignored when surfaces is set (each surface says it for its triangles) */
    int material_count;      /* materials the triangles use; 0 = 1; <= MR_MESH_MAX_MATERIALS */
    const uint16_t *triangle_materials; /* [triangle_count] each < material_count; NULL = every triangle 0 */
    const mr_surface *surfaces;         /* [material_count] (1 when material_count is 0); NULL = no maps and
                                           double_sided for all */
    int has_transform;       /* 0: identity (transform ignored) */
    double transform[16];    /* object to world, a 4x4 column-major matrix as glTF's node.matrix; affine
                                (last row 0 0 0 1), finite, invertible */
} mr_mesh;

/* Check a mesh (NULL arrays, counts, indices in range, finite values, non-zero normals, tangent w, the
 * transform, not every triangle degenerate). MR_ERR_INVALID_ARG naming the vertex, triangle or field. */
mr_status mr_mesh_validate(const mr_mesh *mesh);

#define MR_MESH_MAX_MATERIALS 4096

typedef enum mr_shape_type {
    MR_SHAPE_SPHERE = 0,
    MR_SHAPE_MESH,
    MR_SHAPE_TYPE_COUNT
} mr_shape_type;

typedef struct mr_shape {
    mr_shape_type type;
    double center[3];     /* MR_SHAPE_SPHERE */
    double radius;        /* MR_SHAPE_SPHERE */
    const mr_mesh *mesh;  /* MR_SHAPE_MESH: borrowed, read by mr_render_plan_create only (see mr_mesh); the
                             copy in mr_render_plan_scene() is the caller's pointer, maybe stale */
} mr_shape;

/* How mr_camera_frame_mesh frames a mesh. Zero-initialise for the defaults. */
typedef struct mr_frame_options {
    int width, height;    /* the image the camera will render; 0 = square */
    double fov_y_degrees; /* 0 = 35, the fit scene's */
    double from[3];       /* direction from the mesh towards the camera; zero = +z (the fit camera's side) */
    double fill;          /* the bounding sphere's angular diameter over the narrower field of view; 0 = 0.9 */
} mr_frame_options;

/* A camera that looks at the centre of the mesh's bounding sphere (world space: the centre of its bounding
 * box, the radius to its farthest vertex) from direction `from`, at the distance where the sphere spans `fill`
 * of the narrower of the vertical and horizontal fields of view, with +y up (+z when `from` is along y).
 * opts may be NULL. MR_ERR_INVALID_ARG for an invalid mesh (mr_mesh_validate) or options. */
mr_status mr_camera_frame_mesh(const mr_mesh *mesh, const mr_frame_options *opts, mr_camera *out);

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
    int highlight_samples; /* 0 (default): on a sphere, the pixels around each point light's mirror point are
                              integrated over their area (log-polar rings about the highlight's centre plus a
                              grid for the rest: docs/rendering.md, "Narrow highlights"), so a lobe narrower
                              than a pixel, down to the models' alpha 1e-4, keeps its energy; 1 = pixel
                              centres only there too. Meshes and environment lights ignore it */
    int threads;           /* OpenMP threads for building the plan and for every render on it: 0 (default) =
                              automatic, a team of omp_get_max_threads() only for work large enough to gain
                              from one (a plan of at least MR_RENDER_PARALLEL_PIXELS traced pixels, a render of
                              at least MR_RENDER_PARALLEL_SAMPLES shading samples; the remaps' 64^2 renders are
                              not), one thread otherwise; n >= 1: n threads for all of it. <= 1024 */
} mr_scene;

/* The automatic thread rule's thresholds (mr_scene.threads = 0), measured on 2 cores (docs/performance.md,
 * "Threads"): below them a second thread costs more to start than it saves, and copies that run side by side
 * (sweeps, scripts, farms) would fight over the cores for nothing. */
#define MR_RENDER_PARALLEL_SAMPLES 32768
#define MR_RENDER_PARALLEL_PIXELS 16384

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

/* The fit scene's point light (scene->lights[0], as mr_scene_fit placed it: distance 3 from a unit sphere, frontal
 * or 45 degrees to the camera's right, `light`) scaled to an object and turned with scene->camera, for a mesh in
 * the sphere's place (`matremap render` of an OBJ or a glTF asset): at 3 bounding radii from the centre of the
 * mesh's bounding sphere (centre of its box, radius to its farthest vertex; mesh NULL: the unit sphere at the
 * origin), in the fit scene's direction relative to the camera, its intensity multiplied by radius^2, so that an
 * object of any size receives the fit scene's irradiance where the camera sees it. MR_ERR_INVALID_ARG for a NULL
 * scene or one without a light (nothing changed). */
mr_status mr_scene_fit_light_to_mesh(mr_scene *scene, const mr_mesh *mesh, mr_fit_light light);

/* The paper's visualisation camera (brdf-reference 1: Mitsuba perspective, 40 degrees on y, at (0, 0, -1.5)
 * looking at the origin, +y up; its right is -x), which frames its material-test sphere of radius 0.5
 * (../shared/assets/paper/matsphere.obj, io/obj_load.h) over 74 % of the frame. */
mr_camera mr_camera_paper(void);

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

/* The OpenMP threads a render on this plan uses (mr_scene.threads: its value, or the automatic rule's choice). */
int mr_render_plan_threads(const mr_render_plan *plan);

/* Number of pixels that see the object and receive light (from any light). */
int mr_render_plan_lit_pixel_count(const mr_render_plan *plan);

/* Number of shading samples, i.e. the BRDF evaluations one render makes: for each lit hit (one per lit pixel,
 * edge_samples^2 on the silhouette) one per point light that reaches it plus one per environment direction
 * above its horizon (pattern and reflection samples). */
long mr_render_plan_sample_count(const mr_render_plan *plan);

/* Number of environment-light shading samples among mr_render_plan_sample_count() (0 without environment
 * lights): pattern directions and reflection samples. */
long mr_render_plan_env_sample_count(const mr_render_plan *plan);

/* Number of reflection samples among mr_render_plan_env_sample_count() (0 unless an environment light asks for
 * them, mr_light.reflection_samples). */
long mr_render_plan_reflection_sample_count(const mr_render_plan *plan);

/* Number of shadow rays the plan traced (once, at creation): 0 for a sphere and for a convex mesh, which
 * cannot occlude itself (every vertex lies on the inner side of every face's plane, within 1e-6 of the mesh's
 * size, and every face's winding agrees with its vertex normals; a double-sided mesh must be flat); otherwise
 * one per point light, one per environment direction above the horizon and one per reflection sample above it,
 * for each lit hit. The plan keeps
 * only the samples that see their light, so renders cost the same BRDF evaluations either way. */
long mr_render_plan_shadow_ray_count(const mr_render_plan *plan);

/* 1 if the plan's object can occlude itself (a non-convex mesh: shadow rays were traced), 0 otherwise. */
int mr_render_plan_self_occluding(const mr_render_plan *plan);

/* Trace one ray (world space; dir need not be unit) against the plan's mesh: the nearest hit at distance
 * t > 0 (in units of |dir|) through the BVH, or with brute_force != 0 by testing every triangle (tests and
 * debugging; both give the same nearest t). Returns 1 and fills *t and *triangle (either may be NULL) on a
 * hit, 0 on a miss or when the plan's object is not a mesh. */
int mr_render_plan_trace_mesh(const mr_render_plan *plan, const double origin[3], const double dir[3],
                              int brute_force, double *t, int *triangle);

/* Bytes the plan holds (geometry, samples, coverage, direction tables), for memory budgets. */
size_t mr_render_plan_bytes(const mr_render_plan *plan);

/* Number of pixels that see the object at all (lit or not, fully or partly covered). */
int mr_render_plan_object_pixel_count(const mr_render_plan *plan);

/* The fraction of each pixel the object covers (width*height floats, row-major, top-left first): 1 inside the
 * silhouette, 0 outside, in between on it. Owned by the plan. Useful as a mask for fits and metrics.
 * Contract: a pixel whose primary rays all agree (its centre and four corners all hit, or all miss) holds 1 or
 * 0; a silhouette pixel holds k / edge_samples^2, k of its sub-pixel rays hitting. A hit counts whether or not
 * light reaches it (an unlit or shadowed part of the object is black in renders but covered), and whatever its
 * material; what a ray passes through (a single-sided triangle seen from behind) does not cover. Thin
 * features that slip between a pixel's corners and centre are missed (see mr_render_plan_create). */
const float *mr_render_plan_coverage(const mr_render_plan *plan);

/* The coverage above as a new 1-channel image of the plan's size (*out, owned by the caller; untouched on
 * failure): the object mask of a render, as SSIM and RMSE over the object take it (metrics.h: pixels > 0 are
 * the object's). Every render of the plan, whatever its material, has this coverage. MR_ERR_INVALID_ARG for
 * NULL arguments, MR_ERR_NOMEM. */
mr_status mr_render_plan_coverage_mask(const mr_render_plan *plan, mr_image **out);

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

/* mr_render_into and mr_render_components_into with `threads` OpenMP threads (0 = the plan's, as those calls): for
 * a caller with a thread count of its own, e.g. a remap passing mr_remap_options.threads through. */
mr_status mr_render_into_threads(const mr_render_plan *plan, int threads, const mr_brdf_model *model,
                                 const double *values, mr_component component, mr_image *image);
mr_status mr_render_components_into_threads(const mr_render_plan *plan, int threads, const mr_brdf_model *model,
                                            const double *values, mr_image *diffuse, mr_image *specular);

/* The derivatives of a render with respect to parameter values (the gradient-based local fits of remap.c):
 * images[k] receives d(render of `component`)/d values[slots[k]] at `values`, from the model's analytic eval_grad
 * (brdf.h), summed over each lit pixel's samples in plan order like a render (so the images do not depend on
 * `threads`; 0 = the plan's rule); 0 where the object is not lit. The background and emission depend on no
 * parameter. Slots are packed value indices (brdf.h), 1 to MR_BRDF_MAX_VALUES of them, images 3-channel and the
 * plan's size. MR_ERR_UNSUPPORTED for a model without eval_grad, a plan with environment or reflection samples
 * (point lights only: mr_render_plan_point_lit_only) or a mesh with several materials; MR_ERR_INVALID_ARG for
 * NULL arguments, a slot outside the model or an image of the wrong size. A model with prepared derivatives
 * (brdf.h, grad_ops) is differentiated through them, once per call for the slots asked for (distinct slots; a list
 * with a repeat takes eval_grad per sample): the same images, at a fraction of the cost. MR_ERR_NOMEM if its state
 * (about 28 KB) cannot be allocated. */
mr_status mr_render_derivatives_into(const mr_render_plan *plan, int threads, const mr_brdf_model *model,
                                     const double *values, mr_component component, const int *slots, int count,
                                     mr_image *const *images);

/* Nonzero when the plan lights its object by point lights only (no environment or reflection samples). */
int mr_render_plan_point_lit_only(const mr_render_plan *plan);

/* The plan of `plan`'s scene looking at the first point light's highlight on the sphere `zoom` times closer (the
 * same camera position, turned towards the highlight, its field of view `zoom` times narrower, the same image
 * size), built on the first call and kept by `plan` (freed with it; safe to call from several threads at once), so
 * that repeated remaps with one plan (sweeps) build it once. *out (borrowed from `plan`) = NULL with MR_OK when
 * the scene is not a sphere or no point light's highlight is seen. A plan keeps one zoom factor: a later call with
 * another fails (MR_ERR_INVALID_ARG). */
mr_status mr_render_plan_zoomed(const mr_render_plan *plan, double zoom, const mr_render_plan **out);

/* ---- textured spheres: parameters from maps over the sphere's (u, v) (conventions in the header comment) ---- */

/* Which parameters come from maps. Zero-initialise it ({0}: no maps, every parameter from values[]) and set
 * maps by parameter index (model table order) or with mr_param_textures_set(). The images are borrowed for the
 * duration of each render call. A map holds the parameter's own values in the model's units (linear: colour
 * maps are sRGB-decoded when read, image_io.h; glTF roughness must be squared into alpha by the caller), and is
 * sampled bilinearly at the hit's (u, v) with texel centres at ((i + 0.5)/width, (j + 0.5)/height), wrapping in
 * u and clamping in v unless textures->sampling says otherwise (see mr_texture_sampling), without mipmaps (a map
 * much finer than the sphere's pixels aliases; shrink it first).
 * A texel that holds no parameter value is read as one: NaN and infinities as 0, negative values clamped to 0
 * (before the bilinear blend; mr_material_map_invalid_texels counts them, docs/rendering.md). Sampled values are
 * clamped into the model's bounds by its prepare(), like constant values. */
typedef struct mr_param_textures {
    const mr_image *maps[MR_BRDF_MAX_VALUES]; /* maps[i]: parameter i's map; NULL = values[] constant. An RGB
                                                 parameter reads channels 0-2 of a 3- or 4-channel map, or the
                                                 single channel of a grey one; a scalar parameter reads
                                                 channel[i] */
    int channel[MR_BRDF_MAX_VALUES];          /* scalar parameters: the map channel holding the value (0 = the
                                                 first: grey, or R; glTF packs roughness in 1 = G, metallic in
                                                 2 = B); must be 0 for RGB parameters */
    mr_texture_sampling sampling[MR_BRDF_MAX_VALUES]; /* how maps[i] is read (coordinate set, transform, wrap
                                                         modes); zero = the sphere's convention */
} mr_param_textures;

/* Set parameter `name`'s map (NULL clears it) and channel, after checking that `model` has the parameter, that
 * it is not a switch, and that the map's channels suit it (see mr_param_textures). MR_ERR_INVALID_ARG naming
 * the parameter otherwise; *textures is unchanged then. */
mr_status mr_param_textures_set(mr_param_textures *textures, const mr_brdf_model *model, const char *name,
                                const mr_image *map, int channel);

/* Like mr_render, mr_render_into and mr_render_components_into, with the parameters that have a map in
 * `textures` read from it at each hit (each silhouette sub-pixel hit at its own (u, v)); values[] gives the
 * others (and must hold a full vector: mapped slots are ignored). textures == NULL, or one without maps, is
 * exactly mr_render*; maps of a single value render bit-identically to that value passed in values[] (when it
 * is representable as a float). Textures cost one bilinear lookup per map and one prepare() per hit, on top of
 * the BRDF evaluations. MR_ERR_INVALID_ARG for unsuitable maps, as mr_param_textures_set. */
mr_status mr_render_textured(const mr_render_plan *plan, const mr_brdf_model *model, const double *values,
                             const mr_param_textures *textures, mr_component component, mr_image **out);
mr_status mr_render_textured_into(const mr_render_plan *plan, const mr_brdf_model *model, const double *values,
                                  const mr_param_textures *textures, mr_component component, mr_image *image);
mr_status mr_render_textured_components_into(const mr_render_plan *plan, const mr_brdf_model *model,
                                              const double *values, const mr_param_textures *textures,
                                              mr_image *diffuse, mr_image *specular);

/* ---- meshes with several materials -------------------------------------------------------------------------- */

/* One material of a multi-material render: its model, a full value vector and its maps (NULL = none). */
typedef struct mr_material_binding {
    const mr_brdf_model *model;
    const double *values;
    const mr_param_textures *textures;
} mr_material_binding;

/* Materials the plan's object uses: its mesh's material_count (1 for a sphere or a mesh without materials). */
int mr_render_plan_material_count(const mr_render_plan *plan);

/* Render a mesh whose triangles carry several materials (mr_mesh.triangle_materials): every hit is shaded with
 * materials[its triangle's material], each material with its own model, values and maps; hits of different
 * materials in one silhouette pixel are box-filtered together. count is mr_render_plan_material_count(plan) or
 * more (extra ones are unused), or 1: every hit with materials[0], which is what mr_render_textured does on any
 * plan. Otherwise MR_ERR_INVALID_ARG, as for unsuitable maps (mr_param_textures_set). */
mr_status mr_render_materials_into(const mr_render_plan *plan, const mr_material_binding *materials, int count,
                                   mr_component component, mr_image *image);
mr_status mr_render_materials(const mr_render_plan *plan, const mr_material_binding *materials, int count,
                              mr_component component, mr_image **out);

/* ---- materials that own their maps ----------------------------------------------------------------------------
 * An mr_material is a model, a full value vector and the maps bound to its parameters, all in one object: what a
 * material given on the command line (`MODEL name=value name=@MAP`) or a glTF material becomes, and what
 * mr_report_make (report/report.h) takes. The maps are images the material owns; textures.maps[] point at them.
 *
 *   mr_material *m = NULL;
 *   mr_material_create(mr_brdf_find("gltf"), &m);       // the model's defaults
 *   mr_brdf_parse_assignment(m->model, "roughness=0.4", m->values);
 *   mr_material_add_map(m, "base_color", image, 0, "albedo.png", NULL);   // m now owns image
 *   mr_render_textured(plan, m->model, m->values, &m->textures, MR_COMPONENT_FULL, &out);
 *   mr_material_free(m);
 */
typedef struct mr_material_map {
    int param;       /* the parameter's index in the model's table */
    int channel;     /* the map channel read (0 for RGB parameters and for one-channel maps) */
    mr_image *image; /* owned by the material */
    char *source;    /* where the map came from, for people: a file, "baseColorTexture" (owned) */
} mr_material_map;

typedef struct mr_material {
    const mr_brdf_model *model;
    double values[MR_BRDF_MAX_VALUES]; /* a full vector: the model's defaults until the caller changes them */
    mr_param_textures textures;        /* the maps bound to their parameters (textures.maps[] point into maps[]) */
    int map_count;
    mr_material_map *maps;             /* [map_count], in the order they were added; a later map of the same
                                          parameter is the one bound, the earlier stays listed */
} mr_material;

/* A material of `model` with its default values and no maps into *out (caller-owned: mr_material_free).
 * MR_ERR_INVALID_ARG for a NULL model, MR_ERR_NOMEM. */
mr_status mr_material_create(const mr_brdf_model *model, mr_material **out);

/* Bind `image` to parameter `param` (by name), reading `channel` (as mr_param_textures_set checks it), sampled as
 * `sampling` says (NULL = the sphere's convention), and record `source` (copied; NULL = ""). On success the
 * material owns the image; on failure (MR_ERR_INVALID_ARG naming the parameter, MR_ERR_NOMEM) the caller still
 * does and the material is unchanged. */
mr_status mr_material_add_map(mr_material *material, const char *param, mr_image *image, int channel,
                              const char *source, const mr_texture_sampling *sampling);

/* The texels of material->maps[k] that texture sampling reads as something else than stored (mr_param_textures),
 * over the channels its parameter reads: *nonfinite those holding a NaN or an infinity in any of them (read as 0),
 * *negative the others holding a negative value (clamped to 0). What a command names in its output (the render
 * and report commands: "note: base_color=@nan.exr: 3 texels not finite, read as 0; ..."). MR_ERR_INVALID_ARG for a
 * NULL argument or k outside 0 .. map_count - 1. */
mr_status mr_material_map_invalid_texels(const mr_material *material, int k, size_t *nonfinite, size_t *negative);

/* The material as mr_render_materials takes it (pointers into *material). */
mr_material_binding mr_material_binding_of(const mr_material *material);

/* Releases the material and its maps; NULL-safe. */
void mr_material_free(mr_material *material);

/* ---- materials given as text (material_text.c) ----------------------------------------------------------------
 * MODEL followed by assignments, as the command line takes a material (render, report, convert):
 *   name=VALUE, name=R,G,B     a value (mr_brdf_parse_assignment)
 *   name=@FILE[:r|g|b|a][:linear|srgb]   a map (io/image_io.h, "maps named in text"): read by the one rule of
 *                              mr_img_read_param_map, bound with mr_material_add_map (its source "FILE[:e]"). A
 *                              one-value parameter takes a channel selector, or a one-channel or grey file (a colour
 *                              file without a selector is refused); an RGB parameter takes the whole image.
 *   mr_material *m;  mr_material_text_report why;
 *   const char *a[] = {"roughness=@orm.png:g:linear", "base_color=@albedo.png", "metallic=0"};
 *   if (mr_material_from_assignments("gltf", a, 3, NULL, &m, &why) != MR_OK) ... mr_last_error(), why.failed
 */
typedef struct mr_material_text_options {
    int max_dimension; /* largest side of a map; 0 = the reader's default (mr_img_read_options) */
} mr_material_text_options;

typedef struct mr_material_text_report {
    int failed; /* the assignment refused (an index into assignments), or -1 (none, or the model itself) */
    int usage;  /* 1: the text is at fault, not a file or a value (a command line's usage error): an assignment
                   without '=', a map without a name, malformed selectors ("'x.png:linear:g': the channel comes before
                   the encoding ..."), a channel selector on an RGB parameter, :srgb on a float file, a colour file
                   for a one-value parameter without a channel selector */
} mr_material_text_report;

/* A material of the model named `model_name` (mr_brdf_find) with assignments[0..count) applied in order into *out
 * (caller-owned: mr_material_free; NULL on failure). options may be NULL (zero = defaults); report (may be NULL)
 * says which assignment failed and whether the text was at fault. Errors, one line in mr_last_error() naming the
 * assignment as given: MR_ERR_INVALID_ARG for an unknown model (listing the models), an unknown parameter ("textures:
 * model M has no parameter 'x' (valid: ...)"), a value out of range (mr_brdf_parse_assignment's message; a value
 * that looks like a file adds "; did you mean name=@FILE? (a map is given as name=@FILE)"), the usage-level faults
 * above ("'roughness=@c.png': c.png holds colour, but roughness takes one value: pick a channel with @c.png:r, :g,
 * :b or :a"); the errors of reading a map (mr_map_ref_read); MR_ERR_NOMEM. */
mr_status mr_material_from_assignments(const char *model_name, const char *const *assignments, int count,
                                       const mr_material_text_options *options, mr_material **out,
                                       mr_material_text_report *report);

/* What material->maps[k] holds that is not parameter values (mr_material_map_invalid_texels) as one line into
 * text[size] (truncated to fit), e.g. "base_color=@nan.exr: 3 texels not finite, read as 0; 2 negative, clamped to
 * 0": 1 when there is something to say, else 0 (text then ""; also for k out of range). */
int mr_material_describe_invalid_texels(const mr_material *material, int k, char *text, size_t size);

#ifdef __cplusplus
}
#endif

#endif /* MR_RENDER_H */
