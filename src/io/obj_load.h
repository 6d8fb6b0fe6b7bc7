/*
 * obj_load.h — Wavefront OBJ meshes for the renderer (render/render.h, mr_mesh), read through Debian's
 * tinyobjloader (a C++ shim, obj_load.cpp). What `matremap render --mesh FILE.obj` draws, e.g. the paper's
 * material-test sphere (../shared/assets/paper/matsphere.obj) under an environment map.
 *
 *   mr_obj_mesh *obj = NULL;
 *   if (mr_obj_load("matsphere.obj", NULL, &obj) != MR_OK) { fprintf(stderr, "%s\n", mr_last_error()); ... }
 *   mr_scene scene = mr_scene_fit(NULL);
 *   scene.shape.type = MR_SHAPE_MESH;
 *   scene.shape.mesh = &obj->mesh;
 *   mr_camera_frame_mesh(&obj->mesh, NULL, &scene.camera);
 *   ... mr_render_plan_create(&scene, &plan); mr_render_textured(plan, model, values, &textures, ...) ...
 *   mr_render_plan_free(plan); mr_obj_mesh_free(obj);
 *
 * What is read (docs/rendering.md, "OBJ meshes"):
 *   - Faces (f) with their positions (v), texture coordinates (vt) and normals (vn), 1-based or negative
 *     (relative) indices. Polygons are triangulated by tinyobjloader: quads along their shorter diagonal, larger
 *     polygons by ear clipping in their plane; the winding (counter-clockwise = front, OBJ's convention) is kept.
 *   - One mesh of every face: objects and groups (o, g) are merged, and there is one material: usemtl and mtllib
 *     are ignored and no .mtl file is opened (the BRDF, its values and maps come from the caller, as the paper's
 *     sphere takes one SVBRDF). Points (p), lines (l), vertex colours, smoothing groups and vt's w are ignored.
 *   - Vertices: one per distinct (v, vt, vn) triple the faces use, in order of first use; v records no face uses
 *     are dropped. Positions are object space with has_transform 0 (the file's coordinates are world space).
 *   - Normals: the file's, normalised. Where a face corner has none (or a zero or non-finite one), a smooth
 *     normal is computed: the unit normals of the triangles around the position (the v record, not the output
 *     vertex, so UV seams do not crease the shading), each weighted by its corner angle there (as the renderer
 *     does, render.h). A triangle whose three file normals all point against its winding (their sum has a
 *     negative dot product with the face normal) is turned round (two corners swapped): the normals say which
 *     side is the front, and the renderer does not show the back of a single-sided triangle.
 *   - Texture coordinates (TEXCOORD_0): u as stored; v flipped, v' = 1 - v (OBJ's v grows upwards, the
 *     renderer's as glTF's downwards: row 0 of a map is its top), so a map's top row lies where the file's v = 1.
 *     This is Mitsuba's default (flipTexCoords) and Blender's reading. Corners without a vt get (0, 0) when other
 *     corners have one; a file without vt gives a mesh without UVs (maps read at (0, 0)).
 * Errors (the library never prints): MR_ERR_IO naming the file when it cannot be opened or read;
 * MR_ERR_FORMAT naming the file and the line for what tinyobjloader rejects (its message), an index out of
 * range (v, vt or vn; 0, beyond the records, or a relative index reaching before the first), a face of fewer
 * than 3 vertices, a non-finite coordinate, a file without faces, or more than the renderer's limits (mr_mesh's
 * int counts). tinyobjloader reads a malformed number as 0 without a word, and so does this reader. Warnings
 * tinyobjloader reports for what it skipped are kept in `warnings` (its "material not found" ones, which
 * follow from not reading .mtl files, are dropped).
 * Ownership: the result owns everything reachable from it (the mesh's arrays, path, warnings);
 * mr_obj_mesh_free (NULL-safe) releases it all. Threading: distinct loads are independent.
 */
#ifndef MR_OBJ_LOAD_H
#define MR_OBJ_LOAD_H

#include "../mr_status.h"
#include "../render/render.h"

#ifdef __cplusplus
extern "C" {
#endif

/* How to read the file. Zero-initialise for the defaults (opts may also be NULL). */
typedef struct mr_obj_options {
    int keep_v;         /* 1: texture v as stored (no flip); 0 (default): v' = 1 - v, see above */
    int ignore_normals; /* 1: ignore the file's vn and compute smooth normals everywhere */
    int double_sided;   /* copied into mesh.double_sided (1: backs lit like fronts); 0 (default): single-sided */
} mr_obj_options;

typedef struct mr_obj_mesh {
    char *path;                       /* the file, as given */
    mr_mesh mesh;                     /* every face; normals always set, uvs when the file has vt. Its arrays
                                         belong to this struct */
    double bbox_min[3], bbox_max[3];  /* the box of the mesh's vertices */
    int position_records;             /* v records in the file */
    int texcoord_records;             /* vt records */
    int normal_records;               /* vn records */
    int shape_count;                  /* tinyobjloader's shapes (objects and groups), merged */
    int computed_normals;             /* output vertices whose normal was computed (no usable vn) */
    int turned_triangles;             /* triangles turned round to face their normals */
    char *warnings;                   /* tinyobjloader's warnings kept, one per line; "" if none */
} mr_obj_mesh;

/* Read the OBJ file at `path` into *out (caller-owned: mr_obj_mesh_free). On failure *out is untouched. */
mr_status mr_obj_load(const char *path, const mr_obj_options *opts, mr_obj_mesh **out);

/* NULL-safe. */
void mr_obj_mesh_free(mr_obj_mesh *obj);

#ifdef __cplusplus
}
#endif

#endif /* MR_OBJ_LOAD_H */
