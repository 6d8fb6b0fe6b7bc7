/*
 * fuzz_obj.c — the OBJ mesh reader (src/io/obj_load.h: tinyobjloader and our checks on what it returns; the
 * meshes of `render --mesh` and `report --mesh`).
 */
#include "fuzz.h"
#include "matremap.h"

int mr_fuzz_obj(const uint8_t *data, size_t size) {
    const char *path = fuzz_write_scratch("in.obj", data, size);
    if (path == NULL) return 0;
    mr_obj_mesh *mesh = NULL;
    if (mr_obj_load(path, NULL, &mesh) == MR_OK) mr_obj_mesh_free(mesh);
    return 0;
}

MR_FUZZ_ENTRY(mr_fuzz_obj)
