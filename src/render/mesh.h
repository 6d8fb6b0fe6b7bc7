/* mesh.h — the render plan's world-space triangle mesh and its BVH (internal; the public mr_mesh is in
 * render.h). Built once per plan by mr_mesh_world_build, immutable afterwards, so any number of threads may trace
 * rays through it. */
#ifndef MR_MESH_H
#define MR_MESH_H

#include <math.h>
#include <stddef.h>
#include <stdint.h>

#include "render.h"

#ifdef __cplusplus
extern "C" {
#endif

/* A BVH node: an interior node's children are nodes[first] and nodes[first + 1]; a leaf (count > 0) holds
 * triangles order[first .. first + count - 1]. */
typedef struct bvh_node {
    double lo[3], hi[3];
    int first;
    int count;
} bvh_node;

typedef struct mesh_world {
    int vertex_count, triangle_count;
    double (*position)[3];  /* world space */
    double (*normal)[3];    /* world space, unit (given or generated) */
    double (*tangent)[4];   /* world space xyz + handedness w; NULL without tangents and UVs */
    double (*uv)[2];        /* NULL without TEXCOORD_0 */
    double (*uv1)[2];       /* NULL without TEXCOORD_1 */
    uint16_t *material;     /* [triangle_count] material of each triangle; NULL = all 0 */
    int material_count;     /* >= 1 */
    unsigned char *material_double_sided; /* [material_count] */
    uint32_t (*triangle)[3];
    bvh_node *nodes;
    int node_count;
    int *order;             /* triangle indices in leaf order */
    double scale;           /* bounding-box diagonal: the unit of the geometric tolerances */
    int convex;             /* 1: cannot occlude itself, no shadow rays */
} mesh_world;

/* Is triangle f shaded on both sides (its material's surface, or mr_mesh.double_sided)? */
static inline int mesh_double_sided(const mesh_world *mesh, int f) {
    return mesh->material_double_sided[mesh->material != NULL ? mesh->material[f] : 0];
}

/* Material of triangle f. */
static inline int mesh_material(const mesh_world *mesh, int f) { return mesh->material ? mesh->material[f] : 0; }

/* A ray's hit: distance, triangle and barycentrics (u at vertex 1, v at vertex 2). */
typedef struct mesh_hit {
    double t, u, v;
    int triangle;
} mesh_hit;

/* Build *mesh (zeroed by the caller) from a validated mr_mesh: world-space attributes, generated normals and
 * tangents, the BVH, the convexity test. threads: mr_scene.threads (0 = automatic: a team only for a mesh of at
 * least MR_MESH_PARALLEL_FACES triangles; n >= 1: n threads), used by the convexity test. MR_ERR_NOMEM
 * (mr_mesh_world_free cleans up) or MR_ERR_INVALID_ARG. */
mr_status mr_mesh_world_build(const mr_mesh *src, int threads, mesh_world *mesh);

/* The convexity test's automatic thread rule: a face costs about one root-to-leaf BVH walk (~1 us), so below
 * this a team costs more to start than it saves, and copies running side by side would share cores for nothing. */
#define MR_MESH_PARALLEL_FACES 4096

void mr_mesh_world_free(mesh_world *mesh);
size_t mr_mesh_world_bytes(const mesh_world *mesh);

/* Which single-sided triangles a ray passes through (glTF's back-face culling). */
enum { CULL_NONE = 0, CULL_CAMERA = 1 /* those it sees from behind */, CULL_LIGHT = -1 /* those the light, at the
                                                                          ray's far end, sees from behind */ };

/* Nearest hit with 0 < t < t_max (dir need not be unit); skip = a triangle to ignore, or -1; cull: CULL_NONE, or
 * CULL_CAMERA for camera rays. */
int mr_mesh_intersect(const mesh_world *mesh, const double origin[3], const double dir[3], double t_max, int skip,
                   int cull, mesh_hit *hit);
/* The same by testing every triangle. */
int mr_mesh_intersect_brute(const mesh_world *mesh, const double origin[3], const double dir[3], double t_max,
                         int skip, int cull, mesh_hit *hit);
/* Any hit with 0 < t < t_max, skipping triangle `skip`: a shadow ray from a surface towards a light at the ray's
 * far end. The light passes through single-sided triangles it sees from behind (CULL_LIGHT), as through those the
 * camera sees from behind: a closed mesh still shadows, by the faces the light sees from the front. */
int mr_mesh_occluded(const mesh_world *mesh, const double origin[3], const double dir[3], double t_max, int skip);

/* The shading attributes at a hit: unit shading normal, tangent and bitangent (a frame), unit geometric normal
 * (by the winding), texture coordinates of both sets ((0, 0) for a set the mesh lacks). */
void mr_mesh_shade(const mesh_world *mesh, const mesh_hit *hit, double normal[3], double tangent[3],
                double bitangent[3], double geometric[3], double uv[2], double uv1[2]);

/* The angle of a triangle's corner at a, between its edges to b and c (0 for a degenerate corner): the weight of
 * a triangle's normal and tangent at that corner, here and in the OBJ reader's smooth normals (inline: the reader
 * lives in the C++ module, src/cxx_module.c). */
static inline double mr_mesh_corner_angle(const double a[3], const double b[3], const double c[3]) {
    const double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    const double x[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
    const double s = sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]), d = u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
    return s > 0.0 ? atan2(s, d) : 0.0;
}

#ifdef __cplusplus
}
#endif

#endif /* MR_MESH_H */
