/*
 * mesh.c — triangle meshes for the render plan: validation, world-space attributes, generated normals and
 * tangents, a binned-SAH BVH, ray-triangle intersection, the convexity test, and camera framing.
 * Contract in render.h (mr_mesh) and mesh.h; the rendering side in render.c; docs/rendering.md, "Meshes".
 *
 * Ray-triangle intersection is Moeller-Trumbore ("Fast, Minimum Storage Ray/Triangle Intersection", JGT 2(1),
 * 1997) in double precision on the float input positions (converted exactly), with inclusive edge tests, so a
 * ray through a shared edge hits at least one of its two triangles. The BVH is built sequentially (binned SAH,
 * Wald 2007, 16 bins per axis; an object-median split past depth 48 keeps the traversal stack bounded), so it
 * is the same for any thread count; its boxes are padded and the slab test is conservative, so it finds
 * exactly the nearest t the brute-force loop finds.
 */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../mr_internal.h"
#include "mesh.h"
#include "vec3.h"

#define BVH_BINS 16
#define BVH_LEAF_MAX 4
#define BVH_MEDIAN_DEPTH 48
#define BVH_STACK 128
/* Relative tolerance of the convexity test, in units of the bounding-box diagonal. */
#define CONVEX_TOLERANCE 1e-6

/* ---- validation ---------------------------------------------------------------------------------------------- */

static int finite_floats(const float *v, int n) {
    for (int k = 0; k < n; k++)
        if (!isfinite(v[k])) return 0;
    return 1;
}

/* The 3x3 part's determinant of a column-major 4x4 matrix. */
static double det3(const double m[16]) {
    return m[0] * (m[5] * m[10] - m[9] * m[6]) - m[4] * (m[1] * m[10] - m[9] * m[2]) +
           m[8] * (m[1] * m[6] - m[5] * m[2]);
}

/* A surface map: a usable image (at least `min_channels`, or a grey one when that is allowed) sampled validly. */
static mr_status validate_surface_map(const mr_image *map, const mr_texture_sampling *sampling, int min_channels,
                                      int material, const char *what) {
    char name[64];
    snprintf(name, sizeof name, "mesh: material %d: %s", material, what);
    if (map == NULL) return MR_OK;
    if (map->width < 1 || map->height < 1 || map->pixels == NULL ||
        (map->channels != 1 && map->channels != 3 && map->channels != 4) || map->channels < min_channels)
        return mr_fail(MR_ERR_INVALID_ARG, "%s: not a usable image (%dx%d, %d channels; %s)", name, map->width,
                       map->height, map->channels, min_channels > 1 ? "3 or 4 channels" : "1, 3 or 4 channels");
    return mr_texture_sampling_validate(sampling, name);
}

/* Material indices in range and every surface usable. */
static mr_status validate_materials(const mr_mesh *mesh) {
    if (mesh->material_count < 0 || mesh->material_count > MR_MESH_MAX_MATERIALS)
        return mr_fail(MR_ERR_INVALID_ARG, "mesh: %d materials: expected 0 to %d", mesh->material_count,
                       MR_MESH_MAX_MATERIALS);
    const int count = mesh->material_count > 0 ? mesh->material_count : 1;
    if (mesh->triangle_materials != NULL)
        for (int f = 0; f < mesh->triangle_count; f++)
            if (mesh->triangle_materials[f] >= count)
                return mr_fail(MR_ERR_INVALID_ARG, "mesh: triangle %d: material %d out of range (%d materials)", f,
                               (int)mesh->triangle_materials[f], count);
    for (int m = 0; mesh->surfaces != NULL && m < count; m++) {
        const mr_surface *surface = &mesh->surfaces[m];
        mr_status status = validate_surface_map(surface->normal_map, &surface->normal_sampling, 3, m, "normal map");
        if (status == MR_OK)
            status = validate_surface_map(surface->occlusion_map, &surface->occlusion_sampling, 1, m, "occlusion map");
        if (status == MR_OK)
            status = validate_surface_map(surface->emissive_map, &surface->emissive_sampling, 1, m, "emissive map");
        if (status != MR_OK) return status;
        if (!isfinite(surface->normal_scale) || !isfinite(surface->occlusion_strength))
            return mr_fail(MR_ERR_INVALID_ARG, "mesh: material %d: normal scale %g or occlusion strength %g is not "
                           "finite", m, surface->normal_scale, surface->occlusion_strength);
        for (int c = 0; c < 3; c++)
            if (!(isfinite(surface->emission[c]) && surface->emission[c] >= 0.0))
                return mr_fail(MR_ERR_INVALID_ARG, "mesh: material %d: emission (%g, %g, %g): expected finite and "
                               ">= 0", m, surface->emission[0], surface->emission[1], surface->emission[2]);
    }
    return MR_OK;
}

mr_status mr_mesh_validate(const mr_mesh *mesh) {
    if (mesh == NULL) return mr_fail(MR_ERR_INVALID_ARG, "mesh: NULL mesh");
    if (mesh->vertex_count < 3)
        return mr_fail(MR_ERR_INVALID_ARG, "mesh: %d vertices: expected at least 3", mesh->vertex_count);
    if (mesh->triangle_count < 1)
        return mr_fail(MR_ERR_INVALID_ARG, "mesh: %d triangles: expected at least 1", mesh->triangle_count);
    if (mesh->triangle_count > INT32_MAX / 3 || mesh->vertex_count > INT32_MAX / 4)
        return mr_fail(MR_ERR_INVALID_ARG, "mesh: %d vertices, %d triangles: too many", mesh->vertex_count,
                       mesh->triangle_count);
    if (mesh->positions == NULL || mesh->indices == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "mesh: NULL positions or indices");
    for (int v = 0; v < mesh->vertex_count; v++) {
        if (!finite_floats(mesh->positions + 3 * (size_t)v, 3))
            return mr_fail(MR_ERR_INVALID_ARG, "mesh: vertex %d: position (%g, %g, %g) is not finite", v,
                           (double)mesh->positions[3 * (size_t)v], (double)mesh->positions[3 * (size_t)v + 1],
                           (double)mesh->positions[3 * (size_t)v + 2]);
        if (mesh->normals != NULL) {
            const float *n = mesh->normals + 3 * (size_t)v;
            if (!finite_floats(n, 3))
                return mr_fail(MR_ERR_INVALID_ARG, "mesh: vertex %d: normal (%g, %g, %g) is not finite", v,
                               (double)n[0], (double)n[1], (double)n[2]);
        }
        if (mesh->tangents != NULL) {
            const float *t = mesh->tangents + 4 * (size_t)v;
            if (!finite_floats(t, 4) || (t[3] != 1.0f && t[3] != -1.0f && t[3] != 0.0f))
                return mr_fail(MR_ERR_INVALID_ARG, "mesh: vertex %d: tangent (%g, %g, %g, %g): expected finite "
                               "xyz and w = +1 or -1 (or 0: generated)", v, (double)t[0], (double)t[1],
                               (double)t[2], (double)t[3]);
        }
        if (mesh->uvs != NULL && !finite_floats(mesh->uvs + 2 * (size_t)v, 2))
            return mr_fail(MR_ERR_INVALID_ARG, "mesh: vertex %d: texture coordinates are not finite", v);
        if (mesh->uvs1 != NULL && !finite_floats(mesh->uvs1 + 2 * (size_t)v, 2))
            return mr_fail(MR_ERR_INVALID_ARG, "mesh: vertex %d: TEXCOORD_1 is not finite", v);
    }
    mr_status status = validate_materials(mesh);
    if (status != MR_OK) return status;
    int area = 0;
    for (int f = 0; f < mesh->triangle_count; f++) {
        const uint32_t *tri = mesh->indices + 3 * (size_t)f;
        for (int k = 0; k < 3; k++)
            if (tri[k] >= (uint32_t)mesh->vertex_count)
                return mr_fail(MR_ERR_INVALID_ARG, "mesh: triangle %d: index %u out of range (%d vertices)", f,
                               (unsigned)tri[k], mesh->vertex_count);
        if (!area) {
            double p[3][3], e1[3], e2[3], c[3];
            for (int k = 0; k < 3; k++)
                for (int i = 0; i < 3; i++) p[k][i] = mesh->positions[3 * (size_t)tri[k] + (size_t)i];
            vec3_sub(p[1], p[0], e1);
            vec3_sub(p[2], p[0], e2);
            vec3_cross(e1, e2, c);
            area = vec3_length(c) > 0.0;
        }
    }
    if (!area)
        return mr_fail(MR_ERR_INVALID_ARG, "mesh: all %d triangles are degenerate (zero area)", mesh->triangle_count);
    if (mesh->has_transform) {
        const double *m = mesh->transform;
        for (int k = 0; k < 16; k++)
            if (!isfinite(m[k])) return mr_fail(MR_ERR_INVALID_ARG, "mesh: transform element %d is not finite", k);
        if (m[3] != 0.0 || m[7] != 0.0 || m[11] != 0.0 || m[15] != 1.0)
            return mr_fail(MR_ERR_INVALID_ARG, "mesh: transform is not affine (last row %g %g %g %g, expected "
                           "0 0 0 1)", m[3], m[7], m[11], m[15]);
        if (!(fabs(det3(m)) > 1e-300))
            return mr_fail(MR_ERR_INVALID_ARG, "mesh: transform is singular (determinant %g)", det3(m));
    }
    return MR_OK;
}

/* ---- world-space attributes ---------------------------------------------------------------------------------- */

static void transform_point(const double m[16], const float p[3], double out[3]) {
    for (int i = 0; i < 3; i++) out[i] = m[i] * p[0] + m[4 + i] * p[1] + m[8 + i] * p[2] + m[12 + i];
}

static void transform_vector(const double m[16], const double v[3], double out[3]) {
    for (int i = 0; i < 3; i++) out[i] = m[i] * v[0] + m[4 + i] * v[1] + m[8 + i] * v[2];
}

/* The inverse transpose of the 3x3 part (as a column-major 4x4, translation 0), for normals: the cofactor
 * matrix divided by the determinant. */
static void normal_matrix(const double m[16], double out[16]) {
    double a[3][3];
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++) a[r][c] = m[4 * c + r];
    double det = det3(m);
    memset(out, 0, 16 * sizeof *out);
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++) {
            int r1 = (r + 1) % 3, r2 = (r + 2) % 3, c1 = (c + 1) % 3, c2 = (c + 2) % 3;
            double cof = a[r1][c1] * a[r2][c2] - a[r1][c2] * a[r2][c1];
            out[4 * c + r] = cof / det; // (A^-1)^T = cof(A) / det
        }
    out[15] = 1.0;
}

/* Smooth normals: the unit face normals weighted by corner angle, for the vertices with missing[v] set (every
 * vertex when missing is NULL); the others keep theirs. Vertices only in degenerate triangles get +y (no ray
 * ever hits them: a degenerate triangle has no area). */
static void generate_normals(mesh_world *mesh, const unsigned char *missing) {
    for (int v = 0; v < mesh->vertex_count; v++)
        if (missing == NULL || missing[v]) mesh->normal[v][0] = mesh->normal[v][1] = mesh->normal[v][2] = 0.0;
    for (int f = 0; f < mesh->triangle_count; f++) {
        const uint32_t *tri = mesh->triangle[f];
        const double *p0 = mesh->position[tri[0]], *p1 = mesh->position[tri[1]], *p2 = mesh->position[tri[2]];
        double e1[3], e2[3], n[3];
        vec3_sub(p1, p0, e1);
        vec3_sub(p2, p0, e2);
        vec3_cross(e1, e2, n);
        if (!(vec3_normalize(n) > 0.0)) continue;
        double angle[3] = {mr_mesh_corner_angle(p0, p1, p2), mr_mesh_corner_angle(p1, p2, p0),
                           mr_mesh_corner_angle(p2, p0, p1)};
        for (int k = 0; k < 3; k++)
            if (missing == NULL || missing[tri[k]])
                for (int i = 0; i < 3; i++) mesh->normal[tri[k]][i] += angle[k] * n[i];
    }
    for (int v = 0; v < mesh->vertex_count; v++)
        if ((missing == NULL || missing[v]) && !(vec3_normalize(mesh->normal[v]) > 0.0)) {
            mesh->normal[v][0] = 0.0, mesh->normal[v][1] = 1.0, mesh->normal[v][2] = 0.0;
        }
}

/* Tangents from the UVs (render.h, mr_mesh): per triangle, dP/du and -dP/dv, normalised and weighted by the
 * corner angle; per vertex, t orthogonalised against n and w from the accumulated bitangent. Only vertices
 * with missing[v] set are written (all when missing is NULL). `bitangent` is scratch space of vertex_count
 * entries. */
static void generate_tangents(mesh_world *mesh, double (*bitangent)[3], const unsigned char *missing) {
    for (int v = 0; v < mesh->vertex_count; v++)
        if (missing == NULL || missing[v])
            mesh->tangent[v][0] = mesh->tangent[v][1] = mesh->tangent[v][2] = mesh->tangent[v][3] = 0.0;
    memset(bitangent, 0, (size_t)mesh->vertex_count * sizeof *bitangent);
    for (int f = 0; f < mesh->triangle_count; f++) {
        const uint32_t *tri = mesh->triangle[f];
        const double *p0 = mesh->position[tri[0]], *p1 = mesh->position[tri[1]], *p2 = mesh->position[tri[2]];
        const double *t0 = mesh->uv[tri[0]], *t1 = mesh->uv[tri[1]], *t2 = mesh->uv[tri[2]];
        double e1[3], e2[3];
        vec3_sub(p1, p0, e1);
        vec3_sub(p2, p0, e2);
        // v flipped: the bitangent points to decreasing glTF v, "up" in the texture image.
        double du1 = t1[0] - t0[0], dv1 = -(t1[1] - t0[1]), du2 = t2[0] - t0[0], dv2 = -(t2[1] - t0[1]);
        double r = du1 * dv2 - du2 * dv1;
        if (!(fabs(r) > 0.0)) continue;
        double s[3], b[3];
        for (int i = 0; i < 3; i++) {
            s[i] = (e1[i] * dv2 - e2[i] * dv1) / r;
            b[i] = (e2[i] * du1 - e1[i] * du2) / r;
        }
        if (!(vec3_normalize(s) > 0.0) || !(vec3_normalize(b) > 0.0)) continue;
        double angle[3] = {mr_mesh_corner_angle(p0, p1, p2), mr_mesh_corner_angle(p1, p2, p0),
                           mr_mesh_corner_angle(p2, p0, p1)};
        for (int k = 0; k < 3; k++)
            for (int i = 0; i < 3; i++) {
                mesh->tangent[tri[k]][i] += angle[k] * s[i];
                bitangent[tri[k]][i] += angle[k] * b[i];
            }
    }
    for (int v = 0; v < mesh->vertex_count; v++) {
        if (missing != NULL && !missing[v]) continue;
        double *t = mesh->tangent[v];
        const double *n = mesh->normal[v];
        double d = vec3_dot(n, t);
        for (int i = 0; i < 3; i++) t[i] -= d * n[i];
        if (!(vec3_normalize(t) > 1e-12)) {
            t[0] = t[1] = t[2] = 0.0; // no usable UV gradient here: the shading frame falls back
            t[3] = 1.0;
            continue;
        }
        double c[3];
        vec3_cross(n, t, c);
        t[3] = vec3_dot(c, bitangent[v]) < 0.0 ? -1.0 : 1.0;
    }
}

/* ---- BVH ----------------------------------------------------------------------------------------------------- */

typedef struct box {
    double lo[3], hi[3];
} box;

static void box_empty(box *b) {
    for (int i = 0; i < 3; i++) b->lo[i] = DBL_MAX, b->hi[i] = -DBL_MAX;
}

static void box_add(box *b, const double p[3]) {
    for (int i = 0; i < 3; i++) {
        if (p[i] < b->lo[i]) b->lo[i] = p[i];
        if (p[i] > b->hi[i]) b->hi[i] = p[i];
    }
}

static void box_merge(box *b, const box *o) {
    for (int i = 0; i < 3; i++) {
        if (o->lo[i] < b->lo[i]) b->lo[i] = o->lo[i];
        if (o->hi[i] > b->hi[i]) b->hi[i] = o->hi[i];
    }
}

static double box_area(const box *b) {
    double d[3];
    for (int i = 0; i < 3; i++) d[i] = b->hi[i] > b->lo[i] ? b->hi[i] - b->lo[i] : 0.0;
    return d[0] * d[1] + d[1] * d[2] + d[2] * d[0];
}

typedef struct median_key {
    double key;
    int triangle;
} median_key;

static int median_key_cmp(const void *a, const void *b) {
    const median_key *x = a, *y = b;
    if (x->key != y->key) return x->key < y->key ? -1 : 1;
    return (x->triangle > y->triangle) - (x->triangle < y->triangle);
}

/* Build the tree breadth-first (nodes[i] is split after every node before it), sequentially: deterministic.
 * Returns 0 on allocation failure. */
static int bvh_build(mesh_world *mesh) {
    const int n = mesh->triangle_count;
    box *tri_box = malloc((size_t)n * sizeof *tri_box);
    double (*centroid)[3] = malloc((size_t)n * sizeof *centroid);
    int *depth = malloc((size_t)(2 * n) * sizeof *depth);
    median_key *keys = malloc((size_t)n * sizeof *keys);
    mesh->order = malloc((size_t)n * sizeof *mesh->order);
    mesh->nodes = malloc((size_t)(2 * n) * sizeof *mesh->nodes);
    int ok = tri_box && centroid && depth && keys && mesh->order && mesh->nodes;
    if (!ok) goto done;
    box all;
    box_empty(&all);
    for (int f = 0; f < n; f++) {
        box_empty(&tri_box[f]);
        for (int k = 0; k < 3; k++) box_add(&tri_box[f], mesh->position[mesh->triangle[f][k]]);
        for (int i = 0; i < 3; i++) centroid[f][i] = 0.5 * (tri_box[f].lo[i] + tri_box[f].hi[i]);
        box_merge(&all, &tri_box[f]);
        mesh->order[f] = f;
    }
    // Pad every box by a hair of the scene's size, so rounding in the slab test never loses a hit on a face.
    const double pad = 1e-9 * mesh->scale + 1e-300;
    mesh->node_count = 1;
    mesh->nodes[0].first = 0;
    mesh->nodes[0].count = n;
    depth[0] = 0;
    for (int index = 0; index < mesh->node_count; index++) {
        bvh_node *node = &mesh->nodes[index];
        const int first = node->first, count = node->count;
        box bounds, cbounds;
        box_empty(&bounds);
        box_empty(&cbounds);
        for (int k = first; k < first + count; k++) {
            box_merge(&bounds, &tri_box[mesh->order[k]]);
            box_add(&cbounds, centroid[mesh->order[k]]);
        }
        for (int i = 0; i < 3; i++) node->lo[i] = bounds.lo[i] - pad, node->hi[i] = bounds.hi[i] + pad;
        if (count <= BVH_LEAF_MAX) continue;

        // Binned SAH over each axis with a centroid extent.
        int best_axis = -1, best_bin = -1;
        double best_cost = DBL_MAX;
        for (int axis = 0; axis < 3 && depth[index] < BVH_MEDIAN_DEPTH; axis++) {
            double lo = cbounds.lo[axis], extent = cbounds.hi[axis] - lo;
            if (!(extent > 0.0)) continue;
            int bin_count[BVH_BINS] = {0};
            box bin_box[BVH_BINS];
            for (int b = 0; b < BVH_BINS; b++) box_empty(&bin_box[b]);
            for (int k = first; k < first + count; k++) {
                int f = mesh->order[k];
                int b = (int)((centroid[f][axis] - lo) / extent * BVH_BINS);
                b = b < 0 ? 0 : b >= BVH_BINS ? BVH_BINS - 1 : b;
                bin_count[b]++;
                box_merge(&bin_box[b], &tri_box[f]);
            }
            double right_area[BVH_BINS];
            int right_count[BVH_BINS];
            box acc;
            box_empty(&acc);
            int c = 0;
            for (int b = BVH_BINS - 1; b > 0; b--) {
                box_merge(&acc, &bin_box[b]);
                c += bin_count[b];
                right_area[b] = box_area(&acc);
                right_count[b] = c;
            }
            box_empty(&acc);
            c = 0;
            for (int b = 0; b < BVH_BINS - 1; b++) { // split between bin b and b + 1
                box_merge(&acc, &bin_box[b]);
                c += bin_count[b];
                if (c == 0 || right_count[b + 1] == 0) continue;
                double cost = box_area(&acc) * c + right_area[b + 1] * right_count[b + 1];
                if (cost < best_cost) {
                    best_cost = cost;
                    best_axis = axis;
                    best_bin = b;
                }
            }
        }
        int mid;
        if (best_axis >= 0) {
            // A leaf costs `count` intersections; the split one traversal step plus the children's share.
            double node_area = box_area(&bounds);
            if (count <= 16 && node_area > 0.0 && 1.0 + best_cost / node_area >= count) continue;
            double lo = cbounds.lo[best_axis], extent = cbounds.hi[best_axis] - lo;
            int i = first, j = first + count - 1;
            while (i <= j) {
                int f = mesh->order[i];
                int b = (int)((centroid[f][best_axis] - lo) / extent * BVH_BINS);
                b = b < 0 ? 0 : b >= BVH_BINS ? BVH_BINS - 1 : b;
                if (b <= best_bin) {
                    i++;
                } else {
                    mesh->order[i] = mesh->order[j];
                    mesh->order[j--] = f;
                }
            }
            mid = i;
        } else {
            // Object median along the widest centroid axis (all centroids equal: any halves will do).
            int axis = 0;
            for (int a = 1; a < 3; a++)
                if (cbounds.hi[a] - cbounds.lo[a] > cbounds.hi[axis] - cbounds.lo[axis]) axis = a;
            for (int k = 0; k < count; k++) {
                keys[k].triangle = mesh->order[first + k];
                keys[k].key = centroid[keys[k].triangle][axis];
            }
            qsort(keys, (size_t)count, sizeof *keys, median_key_cmp);
            for (int k = 0; k < count; k++) mesh->order[first + k] = keys[k].triangle;
            mid = first + count / 2;
        }
        int child = mesh->node_count;
        mesh->node_count += 2;
        node = &mesh->nodes[index];
        mesh->nodes[child] = (bvh_node){{0}, {0}, first, mid - first};
        mesh->nodes[child + 1] = (bvh_node){{0}, {0}, mid, first + count - mid};
        depth[child] = depth[child + 1] = depth[index] + 1;
        node->first = child;
        node->count = 0;
    }
done:
    free(tri_box);
    free(centroid);
    free(depth);
    free(keys);
    return ok;
}

/* Slab test, conservative: the ray's parameter interval inside the box is widened by a few ulps. Returns 1 and
 * the entry distance (0 from inside) when the ray meets the box before t_max. */
static int box_hit(const bvh_node *node, const double origin[3], const double inv[3], double t_max, double *entry) {
    double t0 = 0.0, t1 = t_max;
    for (int i = 0; i < 3; i++) {
        if (isinf(inv[i])) {
            if (origin[i] < node->lo[i] || origin[i] > node->hi[i]) return 0;
            continue;
        }
        double a = (node->lo[i] - origin[i]) * inv[i], b = (node->hi[i] - origin[i]) * inv[i];
        if (a > b) {
            double s = a;
            a = b;
            b = s;
        }
        b *= 1.0 + 4.0 * DBL_EPSILON;
        if (a > t0) t0 = a;
        if (b < t1) t1 = b;
        if (t0 > t1) return 0;
    }
    *entry = t0;
    return 1;
}

/* Moeller-Trumbore; 1 with *t, *u, *v when the ray meets the triangle at 0 < t < t_max. det = -dir . (e1 x e2)
 * says which side the ray meets: det < 0, it runs along the winding's normal (it sees the back). A single-sided
 * triangle is culled, for cull = CULL_CAMERA, where the ray sees its back, and for cull = CULL_LIGHT (shadow rays
 * run from the surface towards the light) where the light sees its back (det > 0). */
static int triangle_hit(const mesh_world *mesh, int f, const double origin[3], const double dir[3], double t_max,
                        int cull, double *t_out, double *u_out, double *v_out) {
    const uint32_t *tri = mesh->triangle[f];
    const double *p0 = mesh->position[tri[0]], *p1 = mesh->position[tri[1]], *p2 = mesh->position[tri[2]];
    double e1[3], e2[3], pv[3], tv[3], qv[3];
    vec3_sub(p1, p0, e1);
    vec3_sub(p2, p0, e2);
    vec3_cross(dir, e2, pv);
    double det = vec3_dot(e1, pv);
    if (det == 0.0 || !isfinite(det)) return 0;
    if (cull != CULL_NONE && det * cull < 0.0 && !mesh_double_sided(mesh, f)) return 0;
    double inv_det = 1.0 / det;
    vec3_sub(origin, p0, tv);
    double u = vec3_dot(tv, pv) * inv_det;
    if (!(u >= 0.0 && u <= 1.0)) return 0;
    vec3_cross(tv, e1, qv);
    double v = vec3_dot(dir, qv) * inv_det;
    if (!(v >= 0.0 && u + v <= 1.0)) return 0;
    double t = vec3_dot(e2, qv) * inv_det;
    if (!(t > 0.0 && t < t_max)) return 0;
    *t_out = t;
    *u_out = u;
    *v_out = v;
    return 1;
}

/* The traversal shared by nearest-hit (any_hit 0) and occlusion (any_hit 1) queries. */
static int bvh_trace(const mesh_world *mesh, const double origin[3], const double dir[3], double t_max, int skip,
                     int any_hit, int cull, mesh_hit *hit) {
    double inv[3];
    for (int i = 0; i < 3; i++) inv[i] = 1.0 / dir[i]; // +-inf for a zero component: box_hit handles it
    // Children are visited nearer first, so the nearest hit shrinks `best` early; a popped node whose box the
    // ray enters beyond the current `best` is skipped.
    int stack[BVH_STACK], top = 0, found = 0;
    double stack_entry[BVH_STACK];
    double best = t_max, entry;
    if (!box_hit(&mesh->nodes[0], origin, inv, best, &entry)) return 0;
    stack[top] = 0;
    stack_entry[top++] = entry;
    while (top > 0) {
        --top;
        if (stack_entry[top] > best) continue;
        const bvh_node *node = &mesh->nodes[stack[top]];
        if (node->count == 0) {
            double e0, e1;
            int h0 = box_hit(&mesh->nodes[node->first], origin, inv, best, &e0);
            int h1 = box_hit(&mesh->nodes[node->first + 1], origin, inv, best, &e1);
            if (h0 && h1) {
                int near_first = e0 <= e1;
                stack[top] = near_first ? node->first + 1 : node->first;
                stack_entry[top++] = near_first ? e1 : e0;
                stack[top] = near_first ? node->first : node->first + 1;
                stack_entry[top++] = near_first ? e0 : e1;
            } else if (h0 || h1) {
                stack[top] = h0 ? node->first : node->first + 1;
                stack_entry[top++] = h0 ? e0 : e1;
            }
            continue;
        }
        for (int k = node->first; k < node->first + node->count; k++) {
            int f = mesh->order[k];
            double t, u, v;
            if (f == skip || !triangle_hit(mesh, f, origin, dir, best, cull, &t, &u, &v)) continue;
            if (any_hit) return 1;
            best = t;
            found = 1;
            hit->t = t, hit->u = u, hit->v = v, hit->triangle = f;
        }
    }
    return found;
}

int mr_mesh_intersect(const mesh_world *mesh, const double origin[3], const double dir[3], double t_max, int skip,
                   int cull, mesh_hit *hit) {
    return bvh_trace(mesh, origin, dir, t_max, skip, 0, cull, hit);
}

int mr_mesh_occluded(const mesh_world *mesh, const double origin[3], const double dir[3], double t_max, int skip) {
    return bvh_trace(mesh, origin, dir, t_max, skip, 1, CULL_LIGHT, NULL);
}

int mr_mesh_intersect_brute(const mesh_world *mesh, const double origin[3], const double dir[3], double t_max,
                         int skip, int cull, mesh_hit *hit) {
    double best = t_max;
    int found = 0;
    for (int f = 0; f < mesh->triangle_count; f++) {
        double t, u, v;
        if (f == skip || !triangle_hit(mesh, f, origin, dir, best, cull, &t, &u, &v)) continue;
        best = t;
        found = 1;
        hit->t = t, hit->u = u, hit->v = v, hit->triangle = f;
    }
    return found;
}

/* ---- convexity ----------------------------------------------------------------------------------------------- */

/* Does any vertex lie more than tol in front of the plane n.x = d? Nodes whose box lies behind it are skipped,
 * so a convex mesh costs about one root-to-leaf walk per face. */
static int any_vertex_in_front(const mesh_world *mesh, const double n[3], double d, double tol) {
    int stack[BVH_STACK], top = 0;
    stack[top++] = 0;
    while (top > 0) {
        const bvh_node *node = &mesh->nodes[stack[--top]];
        double reach = -d;
        for (int i = 0; i < 3; i++) reach += n[i] > 0.0 ? n[i] * node->hi[i] : n[i] * node->lo[i];
        if (reach <= tol) continue;
        if (node->count == 0) {
            stack[top++] = node->first;
            stack[top++] = node->first + 1;
            continue;
        }
        for (int k = node->first; k < node->first + node->count; k++) {
            const uint32_t *tri = mesh->triangle[mesh->order[k]];
            for (int c = 0; c < 3; c++)
                if (vec3_dot(n, mesh->position[tri[c]]) - d > tol) return 1;
        }
    }
    return 0;
}

/* Convex (render.h, mr_render_plan_shadow_ray_count): each non-degenerate face's plane has every vertex on its
 * inner side (against the winding's normal), and the winding agrees with the face's vertex normals. A
 * double-sided mesh shows its backs too, which face the rest of a convex mesh: it must then be flat (every
 * vertex on both sides, i.e. on every face's plane) to need no shadow rays. */
static int mesh_is_convex(const mesh_world *mesh, int threads) {
    const double tol = CONVEX_TOLERANCE * mesh->scale;
    int convex = 1;
#pragma omp parallel for schedule(dynamic, 256) reduction(&& : convex) num_threads(threads) if (threads > 1)
    for (int f = 0; f < mesh->triangle_count; f++) {
        if (!convex) continue;
        const uint32_t *tri = mesh->triangle[f];
        const double *p0 = mesh->position[tri[0]];
        double e1[3], e2[3], n[3];
        vec3_sub(mesh->position[tri[1]], p0, e1);
        vec3_sub(mesh->position[tri[2]], p0, e2);
        vec3_cross(e1, e2, n);
        if (!(vec3_normalize(n) > 0.0)) continue;
        double mean[3] = {0.0, 0.0, 0.0};
        for (int c = 0; c < 3; c++)
            for (int i = 0; i < 3; i++) mean[i] += mesh->normal[tri[c]][i];
        if (vec3_dot(mean, n) <= 0.0 || any_vertex_in_front(mesh, n, vec3_dot(n, p0), tol)) convex = 0;
        double back[3] = {-n[0], -n[1], -n[2]};
        if (convex && mesh_double_sided(mesh, f) && any_vertex_in_front(mesh, back, vec3_dot(back, p0), tol))
            convex = 0;
    }
    return convex;
}

/* ---- the plan's mesh ----------------------------------------------------------------------------------------- */

void mr_mesh_world_free(mesh_world *mesh) {
    if (mesh == NULL) return;
    free(mesh->position);
    free(mesh->normal);
    free(mesh->tangent);
    free(mesh->uv);
    free(mesh->uv1);
    free(mesh->material);
    free(mesh->material_double_sided);
    free(mesh->triangle);
    free(mesh->nodes);
    free(mesh->order);
    memset(mesh, 0, sizeof *mesh);
}

size_t mr_mesh_world_bytes(const mesh_world *mesh) {
    size_t v = (size_t)mesh->vertex_count;
    return v * (sizeof *mesh->position + sizeof *mesh->normal) + (mesh->tangent ? v * sizeof *mesh->tangent : 0) +
           (mesh->uv ? v * sizeof *mesh->uv : 0) + (mesh->uv1 ? v * sizeof *mesh->uv1 : 0) +
           (size_t)mesh->triangle_count * (sizeof *mesh->triangle + sizeof *mesh->order +
           (mesh->material ? sizeof *mesh->material : 0)) + (size_t)mesh->node_count * sizeof *mesh->nodes +
           (size_t)mesh->material_count;
}

mr_status mr_mesh_world_build(const mr_mesh *src, int threads, mesh_world *mesh) {
    mr_status status = mr_mesh_validate(src);
    if (status != MR_OK) return status;
    const int nv = src->vertex_count, nt = src->triangle_count;
    const size_t v = (size_t)nv;
    double identity[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1}, nm[16];
    const double *m = src->has_transform ? src->transform : identity;
    normal_matrix(m, nm);
    const double handedness = det3(m) < 0.0 ? -1.0 : 1.0;
    double (*scratch)[3] = NULL;
    unsigned char *missing_normal = NULL, *missing_tangent = NULL;
    int missing_normals = 0, missing_tangents = 0;
    mesh->vertex_count = nv;
    mesh->triangle_count = nt;
    mesh->material_count = src->material_count > 0 ? src->material_count : 1;
    mesh->material_double_sided = malloc((size_t)mesh->material_count);
    if (src->triangle_materials != NULL) mesh->material = malloc((size_t)nt * sizeof *mesh->material);
    if (src->uvs1 != NULL) mesh->uv1 = malloc(v * sizeof *mesh->uv1);
    if (!mesh->material_double_sided || (src->triangle_materials && !mesh->material) || (src->uvs1 && !mesh->uv1))
        goto oom;
    for (int k = 0; k < mesh->material_count; k++)
        mesh->material_double_sided[k] = (unsigned char)((src->surfaces ? src->surfaces[k].double_sided
                                                                         : src->double_sided) != 0);
    if (src->triangle_materials != NULL)
        memcpy(mesh->material, src->triangle_materials, (size_t)nt * sizeof *mesh->material);
    mesh->position = malloc(v * sizeof *mesh->position);
    mesh->normal = malloc(v * sizeof *mesh->normal);
    mesh->triangle = malloc((size_t)nt * sizeof *mesh->triangle);
    if (src->uvs != NULL) mesh->uv = malloc(v * sizeof *mesh->uv);
    if (src->tangents != NULL || src->uvs != NULL) mesh->tangent = malloc(v * sizeof *mesh->tangent);
    if (src->uvs != NULL) scratch = malloc(v * sizeof *scratch);
    if (src->normals != NULL) missing_normal = calloc(v, 1);
    if (src->tangents != NULL) missing_tangent = calloc(v, 1);
    if (!mesh->position || !mesh->normal || !mesh->triangle || (src->uvs && !mesh->uv) ||
        ((src->tangents || src->uvs) && !mesh->tangent) || (src->uvs && !scratch) ||
        (src->normals && !missing_normal) || (src->tangents && !missing_tangent))
        goto oom;
    memcpy(mesh->triangle, src->indices, (size_t)nt * sizeof *mesh->triangle);
    box all;
    box_empty(&all);
    for (int i = 0; i < nv; i++) {
        transform_point(m, src->positions + 3 * (size_t)i, mesh->position[i]);
        box_add(&all, mesh->position[i]);
        if (src->uvs != NULL) {
            mesh->uv[i][0] = src->uvs[2 * (size_t)i];
            mesh->uv[i][1] = src->uvs[2 * (size_t)i + 1];
        }
        if (src->uvs1 != NULL) {
            mesh->uv1[i][0] = src->uvs1[2 * (size_t)i];
            mesh->uv1[i][1] = src->uvs1[2 * (size_t)i + 1];
        }
        if (src->normals != NULL) {
            const float *n = src->normals + 3 * (size_t)i;
            double on[3] = {n[0], n[1], n[2]};
            if (n[0] == 0.0f && n[1] == 0.0f && n[2] == 0.0f) { // generated below
                missing_normal[i] = 1;
                missing_normals++;
                on[1] = 1.0;
            }
            transform_vector(nm, on, mesh->normal[i]);
            if (!(vec3_normalize(mesh->normal[i]) > 0.0)) goto degenerate;
        }
        if (src->tangents != NULL && src->tangents[4 * (size_t)i + 3] == 0.0f) {
            missing_tangent[i] = 1;
            missing_tangents++;
        } else if (src->tangents != NULL) {
            const float *t = src->tangents + 4 * (size_t)i;
            double ot[3] = {t[0], t[1], t[2]};
            transform_vector(m, ot, mesh->tangent[i]);
            mesh->tangent[i][3] = t[3] * handedness;
        }
    }
    double diagonal[3];
    vec3_sub(all.hi, all.lo, diagonal);
    mesh->scale = vec3_length(diagonal);
    if (!(mesh->scale > 0.0 && isfinite(mesh->scale))) goto no_extent;
    if (src->normals == NULL || missing_normals > 0) generate_normals(mesh, missing_normal);
    if (src->uvs != NULL && (src->tangents == NULL || missing_tangents > 0))
        generate_tangents(mesh, scratch, missing_tangent);
    else if (missing_tangents > 0) // no UVs to derive them from: the shading frame falls back
        for (int i = 0; i < nv; i++)
            if (missing_tangent[i]) {
                mesh->tangent[i][0] = mesh->tangent[i][1] = mesh->tangent[i][2] = 0.0;
                mesh->tangent[i][3] = 1.0;
            }
    free(scratch);
    free(missing_normal);
    free(missing_tangent);
    scratch = NULL;
    missing_normal = missing_tangent = NULL;
    if (!bvh_build(mesh)) goto oom;
    mesh->convex = mesh_is_convex(mesh, mr_auto_threads(threads, nt, MR_MESH_PARALLEL_FACES));
    return MR_OK;
no_extent:
    free(scratch);
    free(missing_normal);
    free(missing_tangent);
    return mr_fail(MR_ERR_INVALID_ARG, "mesh: the transformed mesh has no extent or overflows");
degenerate:
    free(scratch);
    free(missing_normal);
    free(missing_tangent);
    return mr_fail(MR_ERR_INVALID_ARG, "mesh: a normal vanishes under the transform");
oom:
    free(scratch);
    free(missing_normal);
    free(missing_tangent);
    return mr_fail(MR_ERR_NOMEM, "mesh: out of memory for %d vertices, %d triangles", nv, nt);
}

void mr_mesh_shade(const mesh_world *mesh, const mesh_hit *hit, double normal[3], double tangent[3],
                double bitangent[3], double geometric[3], double uv[2], double uv1[2]) {
    const uint32_t *tri = mesh->triangle[hit->triangle];
    const double w[3] = {1.0 - hit->u - hit->v, hit->u, hit->v};
    double e1[3], e2[3];
    vec3_sub(mesh->position[tri[1]], mesh->position[tri[0]], e1);
    vec3_sub(mesh->position[tri[2]], mesh->position[tri[0]], e2);
    vec3_cross(e1, e2, geometric);
    vec3_normalize(geometric);
    for (int i = 0; i < 3; i++)
        normal[i] = w[0] * mesh->normal[tri[0]][i] + w[1] * mesh->normal[tri[1]][i] + w[2] * mesh->normal[tri[2]][i];
    if (!(vec3_normalize(normal) > 1e-12))
        for (int i = 0; i < 3; i++) normal[i] = geometric[i];
    uv[0] = uv[1] = 0.0;
    if (mesh->uv != NULL)
        for (int k = 0; k < 2; k++)
            uv[k] = w[0] * mesh->uv[tri[0]][k] + w[1] * mesh->uv[tri[1]][k] + w[2] * mesh->uv[tri[2]][k];
    uv1[0] = uv1[1] = 0.0;
    if (mesh->uv1 != NULL)
        for (int k = 0; k < 2; k++)
            uv1[k] = w[0] * mesh->uv1[tri[0]][k] + w[1] * mesh->uv1[tri[1]][k] + w[2] * mesh->uv1[tri[2]][k];
    if (mesh->tangent != NULL) {
        for (int i = 0; i < 3; i++)
            tangent[i] = w[0] * mesh->tangent[tri[0]][i] + w[1] * mesh->tangent[tri[1]][i] +
                         w[2] * mesh->tangent[tri[2]][i];
        double d = vec3_dot(normal, tangent);
        for (int i = 0; i < 3; i++) tangent[i] -= d * normal[i];
        if (vec3_normalize(tangent) > 1e-6) {
            double handed = w[0] * mesh->tangent[tri[0]][3] + w[1] * mesh->tangent[tri[1]][3] +
                            w[2] * mesh->tangent[tri[2]][3];
            double sign = handed < 0.0 ? -1.0 : 1.0;
            vec3_cross(normal, tangent, bitangent);
            for (int i = 0; i < 3; i++) bitangent[i] *= sign;
            return;
        }
    }
    vec3_frame_from_normal(normal, tangent, bitangent);
}

/* ---- camera framing ------------------------------------------------------------------------------------------ */

mr_status mr_camera_frame_mesh(const mr_mesh *mesh, const mr_frame_options *opts, mr_camera *out) {
    if (out == NULL) return mr_fail(MR_ERR_INVALID_ARG, "frame mesh: NULL output");
    mr_status status = mr_mesh_validate(mesh);
    if (status != MR_OK) return status;
    mr_frame_options o = {0};
    if (opts != NULL) o = *opts;
    if (o.width < 0 || o.height < 0 || (o.width == 0) != (o.height == 0))
        return mr_fail(MR_ERR_INVALID_ARG, "frame mesh: image size %dx%d: give both sides or neither", o.width,
                       o.height);
    double fov = o.fov_y_degrees == 0.0 ? 35.0 : o.fov_y_degrees;
    double fill = o.fill == 0.0 ? 0.9 : o.fill;
    if (!(fov > 0.0 && fov < 180.0))
        return mr_fail(MR_ERR_INVALID_ARG, "frame mesh: field of view %g: expected (0, 180) degrees", fov);
    if (!(fill > 0.0 && fill <= 1.0))
        return mr_fail(MR_ERR_INVALID_ARG, "frame mesh: fill %g: expected (0, 1]", fill);
    double from[3] = {o.from[0], o.from[1], o.from[2]};
    if (!vec3_is_finite(from)) return mr_fail(MR_ERR_INVALID_ARG, "frame mesh: direction must be finite");
    if (!(vec3_normalize(from) > 0.0)) from[0] = 0.0, from[1] = 0.0, from[2] = 1.0;
    double identity[16] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1};
    const double *m = mesh->has_transform ? mesh->transform : identity;
    box all;
    box_empty(&all);
    for (int i = 0; i < mesh->vertex_count; i++) {
        double p[3];
        transform_point(m, mesh->positions + 3 * (size_t)i, p);
        box_add(&all, p);
    }
    double centre[3], radius = 0.0;
    for (int i = 0; i < 3; i++) centre[i] = 0.5 * (all.lo[i] + all.hi[i]);
    for (int i = 0; i < mesh->vertex_count; i++) {
        double p[3], d[3];
        transform_point(m, mesh->positions + 3 * (size_t)i, p);
        vec3_sub(p, centre, d);
        radius = fmax(radius, vec3_length(d));
    }
    double half_y = 0.5 * fov * MR_PI / 180.0;
    double aspect = o.width > 0 ? (double)o.width / o.height : 1.0;
    double half = fmin(half_y, atan(tan(half_y) * aspect));
    double distance = radius / sin(fill * half);
    if (!(radius > 0.0 && isfinite(distance)))
        return mr_fail(MR_ERR_INVALID_ARG, "frame mesh: the mesh's bounding sphere has radius %g", radius);
    for (int i = 0; i < 3; i++) {
        out->position[i] = centre[i] + distance * from[i];
        out->target[i] = centre[i];
    }
    int vertical = fabs(from[1]) > 0.999;
    out->up[0] = 0.0;
    out->up[1] = vertical ? 0.0 : 1.0;
    out->up[2] = vertical ? (from[1] > 0.0 ? -1.0 : 1.0) : 0.0;
    out->fov_y_degrees = fov;
    return MR_OK;
}
