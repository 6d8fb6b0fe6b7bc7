/*
 * test_gltf_geometry.c — a glTF scene's world-space triangles (mr_gltf_get_triangles, gltf/geometry.cpp): every
 * shared asset against an independent reading of its JSON and buffers, known answers on hand-made assets, general
 * transforms, and bad or mutated inputs. (Split from test_gltf.c.)
 */
#include "gltf/mr_gltf.h"

#include "gltf_support.h"
#include "harness.h"

/* ---- geometry (mr_gltf_get_triangles) --------------------------------------------------------------------- */

/* Checks every group's internal consistency: indices in range, unit normals, unit tangents with w = +-1, finite
 * values, flags matching the arrays, totals and box covering every vertex. */
static void check_triangles_consistent(const mr_gltf_triangles *t, const char *what) {
    int vertices = 0, triangles = 0, primitives = 0, bad = 0;
    for (int gi = 0; gi < t->group_count; gi++) {
        const mr_gltf_triangle_group *g = &t->groups[gi];
        vertices += g->vertex_count;
        triangles += g->triangle_count;
        primitives += g->primitive_count;
        if ((g->normals != NULL) != g->has_normals || (g->tangents != NULL) != g->has_tangents ||
            (g->uv0 != NULL) != g->has_uv0 || (g->uv1 != NULL) != g->has_uv1 || g->positions == NULL)
            bad++;
        for (int i = 0; i < 3 * g->triangle_count; i++) bad += g->indices[i] >= (uint32_t)g->vertex_count;
        for (int v = 0; v < g->vertex_count; v++) {
            for (int k = 0; k < 3; k++) {
                double x = g->positions[3 * v + k];
                bad += !isfinite(x) || x < t->bbox_min[k] || x > t->bbox_max[k];
            }
            if (g->has_normals) {
                const float *n = g->normals + 3 * v;
                bad += fabs(sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]) - 1.0) > 1e-5;
            }
            if (g->has_tangents) {
                const float *a = g->tangents + 4 * v;
                bad += fabs(sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]) - 1.0) > 1e-5 || fabs(a[3]) != 1.0f;
            }
        }
    }
    MR_CHECK_MSG(bad == 0, "%s: %d inconsistent values", what, bad);
    MR_CHECK_MSG(vertices == t->vertex_count && triangles == t->triangle_count && primitives == t->primitive_count,
                 "%s: totals %d/%d/%d, groups %d/%d/%d", what, t->vertex_count, t->triangle_count,
                 t->primitive_count, vertices, triangles, primitives);
}

/* Every shared asset against tests/lib/gltf_geometry_expect.py, which reads the JSON and the .bin itself:
 * triangle count (index counts / 3 over reachable primitives, once per instancing node), primitive instances,
 * skipped ones and the world box of the positions. */
MR_TEST(geometry_every_asset) {
    const char *root = getenv("MR_ROOT");
    for (int i = 0; i < ASSET_COUNT; i++) {
        char cmd[2048];
        snprintf(cmd, sizeof cmd, "python3 '%s/tests/lib/gltf_geometry_expect.py' '%s'", root ? root : ".",
                 asset_path(ASSETS[i].rel));
        FILE *f = popen(cmd, "r");
        int tris = -1, prims = -1, skipped = -1;
        double lo[3] = {0}, hi[3] = {0};
        int got = f ? fscanf(f, "triangles %d primitives %d skipped %d bbox %lf %lf %lf %lf %lf %lf", &tris, &prims,
                             &skipped, &lo[0], &lo[1], &lo[2], &hi[0], &hi[1], &hi[2])
                    : 0;
        if (f) pclose(f);
        MR_CHECK_MSG(got == 9, "%s: %s gave %d values", ASSETS[i].name, cmd, got);
        mr_gltf *g = load_asset(ASSETS[i].name);
        if (g == NULL || got != 9) {
            mr_gltf_free(g);
            continue;
        }
        mr_gltf_triangles *t = NULL;
        MR_CHECK_OK(mr_gltf_get_triangles(g, -1, &t));
        if (t != NULL) {
            MR_CHECK_MSG(t->triangle_count == tris && t->primitive_count == prims && t->skipped_primitives == skipped,
                         "%s: %d triangles, %d primitives, %d skipped; expected %d, %d, %d", ASSETS[i].name,
                         t->triangle_count, t->primitive_count, t->skipped_primitives, tris, prims, skipped);
            double size = 0;
            for (int k = 0; k < 3; k++) size = fmax(size, hi[k] - lo[k]);
            for (int k = 0; k < 3; k++) {
                MR_CHECK_NEAR(t->bbox_min[k], lo[k], 1e-6 * size);
                MR_CHECK_NEAR(t->bbox_max[k], hi[k], 1e-6 * size);
            }
            MR_CHECK(t->flipped_primitives == 0);
            check_triangles_consistent(t, ASSETS[i].name);
            double blo[3], bhi[3];
            int count = -1;
            MR_CHECK_OK(mr_gltf_get_bounds(g, -1, blo, bhi, &count));
            MR_CHECK(count == t->vertex_count && memcmp(blo, t->bbox_min, sizeof blo) == 0 &&
                     memcmp(bhi, t->bbox_max, sizeof bhi) == 0);
        }
        mr_gltf_triangles_free(t);
        mr_gltf_free(g);
    }
}

/* Known answers written out from the JSON: the WaterBottle's box is its POSITION accessor's min/max under the
 * node's rotation (0,1,0,0), a half turn about y (x, z negated); the Duck's mesh sits under a 0.01 scale matrix;
 * counts are the index accessors' counts / 3. */
MR_TEST(geometry_water_bottle_and_duck) {
    mr_gltf *g = load_asset("WaterBottle");
    mr_gltf_triangles *t = NULL;
    if (g != NULL) MR_CHECK_OK(mr_gltf_get_triangles(g, -1, &t));
    if (t != NULL) {
        const double mn[3] = {-0.05445001, -0.130220339, -0.0544500239}, mx[3] = {0.05445001, 0.130220339,
                                                                                  0.0544500239};
        const double lo[3] = {-mx[0], mn[1], -mx[2]}, hi[3] = {-mn[0], mx[1], -mn[2]};
        for (int k = 0; k < 3; k++) {
            MR_CHECK_NEAR(t->bbox_min[k], lo[k], 1e-7);
            MR_CHECK_NEAR(t->bbox_max[k], hi[k], 1e-7);
        }
        MR_CHECK(t->triangle_count == 13530 / 3 && t->vertex_count == 2549 && t->group_count == 1);
        if (t->group_count == 1) {
            const mr_gltf_triangle_group *w = &t->groups[0];
            MR_CHECK(w->material == 0 && w->has_normals && w->has_tangents && w->has_uv0 && !w->has_uv1);
            /* The group fills the renderer's mesh as it is. */
            mr_mesh mesh = {.vertex_count = w->vertex_count, .positions = w->positions, .normals = w->normals,
                            .tangents = w->tangents, .uvs = w->uv0, .triangle_count = w->triangle_count,
                            .indices = w->indices};
            MR_CHECK_OK(mr_mesh_validate(&mesh));
        }
    }
    mr_gltf_triangles_free(t);
    mr_gltf_free(g);
    t = NULL;
    g = load_asset("Duck");
    if (g != NULL) MR_CHECK_OK(mr_gltf_get_triangles(g, 0, &t));
    if (t != NULL) {
        const double lo[3] = {-69.29850006103516, 9.929369926452637, -61.32819747924805};
        const double hi[3] = {96.17990112304688, 163.97000122070312, 53.92519760131836};
        for (int k = 0; k < 3; k++) {
            MR_CHECK_NEAR(t->bbox_min[k], lo[k] * 0.009999999776482582, 1e-6);
            MR_CHECK_NEAR(t->bbox_max[k], hi[k] * 0.009999999776482582, 1e-6);
        }
        MR_CHECK(t->triangle_count == 12636 / 3 && t->vertex_count == 2399 && t->group_count == 1);
        if (t->group_count == 1) {
            const mr_gltf_triangle_group *d = &t->groups[0];
            MR_CHECK(d->material == 0 && d->has_normals && !d->has_tangents && d->has_uv0 && !d->has_uv1);
        }
    }
    mr_gltf_triangles_free(t);
    mr_gltf_free(g);
}

/* The hand-made asset's buffer (280 bytes; layout in geo_json's bufferViews). */
static size_t geo_buffer(unsigned char *b) {
    memset(b, 0, 280);
    const float quad[12] = {0, 0, 0, 1, 0, 0, 1, 1, 0, 0, 1, 0};
    memcpy(b, quad, sizeof quad);                                   /* view 0: quad positions */
    for (int v = 0; v < 4; v++) {
        const float n[3] = {0, 0, 1}, tan[4] = {1, 0, 0, 1};
        memcpy(b + 48 + 12 * v, n, sizeof n);                       /* view 1: normals */
        memcpy(b + 200 + 16 * v, tan, sizeof tan);                  /* view 7: tangents */
    }
    const unsigned char uv[8] = {0, 0, 255, 0, 255, 255, 0, 255};
    for (int v = 0; v < 4; v++) memcpy(b + 96 + 4 * v, uv + 2 * v, 2); /* view 2: u8 UVs, stride 4 */
    const unsigned char idx[6] = {0, 1, 2, 0, 2, 3};
    memcpy(b + 112, idx, 6);                                        /* view 3: u8 indices */
    const float strip[16] = {7, 0, 0, 0, 7, 1, 0, 0, 7, 0, 1, 0, 7, 1, 1, 0};
    memcpy(b + 120, strip, sizeof strip);                           /* view 4: [pad, x, y, z], stride 16 */
    const uint16_t sparse_index = 2;
    const float sparse_value[3] = {2, 2, 0};
    memcpy(b + 184, &sparse_index, 2);                              /* view 5: sparse index (u16) */
    memcpy(b + 188, sparse_value, sizeof sparse_value);             /* view 6: sparse value */
    const unsigned char bad_idx[3] = {0, 1, 9};
    memcpy(b + 264, bad_idx, 3);                                    /* view 8: an index past 4 vertices */
    const float nan_pos[3] = {NAN, 0, 0};
    memcpy(b + 268, nan_pos, sizeof nan_pos);                       /* view 9: a NaN position */
    return 280;
}

/* Node 0: T(1,2,3) R(z, 90 deg) S(2) with the indexed quad (u8 indices, normals, u8-normalized UVs, material 1)
 * and child node 1 (T(0,0,1)) with a strip (interleaved positions, byteStride 16, accessor byteOffset 4) and a
 * fan (no material); node 2: scale (-1,1,1), the quad with a sparse override of vertex 2 and tangents
 * (material 0); node 3: the quad again at T(10,0,0); node 4: points (skipped). Scene 1 is node 2 alone. */
static const char *const geo_json =
    "{\"asset\": {\"version\": \"2.0\"}, \"scene\": 0,\n"
    "\"scenes\": [{\"nodes\": [0, 2, 3, 4]}, {\"nodes\": [2]}],\n"
    "\"nodes\": [{\"translation\": [1, 2, 3], \"rotation\": [0, 0, 0.70710678118654752, 0.70710678118654752],\n"
    "  \"scale\": [2, 2, 2], \"mesh\": 0, \"children\": [1]},\n"
    "  {\"translation\": [0, 0, 1], \"mesh\": 1}, {\"scale\": [-1, 1, 1], \"mesh\": 2},\n"
    "  {\"matrix\": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 10, 0, 0, 1], \"mesh\": 0}, {\"mesh\": 3}],\n"
    "\"materials\": [{\"name\": \"zero\"}, {\"name\": \"one\"}],\n"
    "\"meshes\": [\n"
    "  {\"primitives\": [{\"attributes\": {\"POSITION\": 0, \"NORMAL\": 1, \"TEXCOORD_0\": 2}, \"indices\": 3,\n"
    "    \"material\": 1}]},\n"
    "  {\"primitives\": [{\"attributes\": {\"POSITION\": 4}, \"mode\": 5}, {\"attributes\": {\"POSITION\": 0},\n"
    "    \"mode\": 6}]},\n"
    "  {\"primitives\": [{\"attributes\": {\"POSITION\": 5, \"NORMAL\": 1, \"TANGENT\": 6}, \"indices\": 3,\n"
    "    \"material\": 0}]},\n"
    "  {\"primitives\": [{\"attributes\": {\"POSITION\": 0}, \"mode\": 0}]}],\n"
    "\"accessors\": [\n"
    "  {\"bufferView\": 0, \"componentType\": 5126, \"count\": 4, \"type\": \"VEC3\", \"name\": \"quadpos\"},\n"
    "  {\"bufferView\": 1, \"componentType\": 5126, \"count\": 4, \"type\": \"VEC3\"},\n"
    "  {\"bufferView\": 2, \"componentType\": 5121, \"normalized\": true, \"count\": 4, \"type\": \"VEC2\"},\n"
    "  {\"bufferView\": 3, \"componentType\": 5121, \"count\": 6, \"type\": \"SCALAR\"},\n"
    "  {\"bufferView\": 4, \"byteOffset\": 4, \"componentType\": 5126, \"count\": 4, \"type\": \"VEC3\"},\n"
    "  {\"bufferView\": 0, \"componentType\": 5126, \"count\": 4, \"type\": \"VEC3\", \"min\": [9, 9, 9],\n"
    "   \"max\": [9, 9, 9], \"sparse\": {\"count\": 1, \"indices\": {\"bufferView\": 5, \"componentType\": 5123},\n"
    "   \"values\": {\"bufferView\": 6}}},\n"
    "  {\"bufferView\": 7, \"componentType\": 5126, \"count\": 4, \"type\": \"VEC4\"},\n"
    "  {\"bufferView\": 8, \"componentType\": 5121, \"count\": 3, \"type\": \"SCALAR\"},\n"
    "  {\"bufferView\": 9, \"componentType\": 5126, \"count\": 1, \"type\": \"VEC3\"}],\n"
    "\"bufferViews\": [{\"buffer\": 0, \"byteLength\": 48}, {\"buffer\": 0, \"byteOffset\": 48, \"byteLength\": 48},\n"
    "  {\"buffer\": 0, \"byteOffset\": 96, \"byteLength\": 16, \"byteStride\": 4},\n"
    "  {\"buffer\": 0, \"byteOffset\": 112, \"byteLength\": 6},\n"
    "  {\"buffer\": 0, \"byteOffset\": 120, \"byteLength\": 64, \"byteStride\": 16},\n"
    "  {\"buffer\": 0, \"byteOffset\": 184, \"byteLength\": 2},\n"
    "  {\"buffer\": 0, \"byteOffset\": 188, \"byteLength\": 12},\n"
    "  {\"buffer\": 0, \"byteOffset\": 200, \"byteLength\": 64},\n"
    "  {\"buffer\": 0, \"byteOffset\": 264, \"byteLength\": 3},\n"
    "  {\"buffer\": 0, \"byteOffset\": 268, \"byteLength\": 12}],\n"
    "\"buffers\": [{\"byteLength\": 280, \"uri\": \"geo.bin\"}]}\n";

/* Writes geo_json with `from` replaced by `to` (NULL: as is) as tmp/NAME, and geo.bin beside it. */
static const char *write_geo(const char *name, const char *from, const char *to) {
    static char json[8192];
    const char *at = from ? strstr(geo_json, from) : NULL;
    MR_CHECK_MSG(from == NULL || at != NULL, "'%s' not in the test asset", from);
    if (at == NULL) {
        snprintf(json, sizeof json, "%s", geo_json);
    } else {
        snprintf(json, sizeof json, "%.*s%s%s", (int)(at - geo_json), geo_json, to, at + strlen(from));
    }
    unsigned char bin[280];
    size_t n = geo_buffer(bin);
    MR_CHECK(mr_test_write_file(mr_test_tmp_path("geo.bin"), bin, n));
    const char *path = mr_test_tmp_path(name);
    MR_CHECK(mr_test_write_file(path, json, strlen(json)));
    return path;
}

static void check_vertices(const mr_gltf_triangle_group *g, const double (*expected)[3], int n, const char *what) {
    MR_CHECK_MSG(g->vertex_count == n, "%s: %d vertices, expected %d", what, g->vertex_count, n);
    for (int v = 0; v < n && v < g->vertex_count; v++)
        for (int k = 0; k < 3; k++) MR_CHECK_NEAR(g->positions[3 * v + k], expected[v][k], 1e-6);
}

static void check_indices(const mr_gltf_triangle_group *g, const uint32_t *expected, int triangles,
                          const char *what) {
    MR_CHECK_MSG(g->triangle_count == triangles, "%s: %d triangles, expected %d", what, g->triangle_count,
                 triangles);
    if (g->triangle_count == triangles)
        for (int i = 0; i < 3 * triangles; i++)
            MR_CHECK_MSG(g->indices[i] == expected[i], "%s: index %d is %u, expected %u", what, i, g->indices[i],
                         expected[i]);
}

MR_TEST(geometry_hand_made_asset) {
    const char *path = write_geo("geo.gltf", NULL, NULL);
    mr_gltf *g = NULL;
    MR_CHECK_OK(mr_gltf_load(path, &g));
    if (g == NULL) return;
    mr_gltf_triangles *t = NULL;
    MR_CHECK_OK(mr_gltf_get_triangles(g, -1, &t));
    if (t == NULL) {
        mr_gltf_free(g);
        return;
    }
    MR_CHECK(t->scene == 0 && t->group_count == 3 && t->triangle_count == 10 && t->vertex_count == 20);
    MR_CHECK(t->primitive_count == 5 && t->skipped_primitives == 1 && t->flipped_primitives == 1);
    check_triangles_consistent(t, "hand-made");
    const double lo[3] = {-2, 0, 0}, hi[3] = {11, 4, 5};
    for (int k = 0; k < 3; k++) {
        MR_CHECK_NEAR(t->bbox_min[k], lo[k], 1e-6);
        MR_CHECK_NEAR(t->bbox_max[k], hi[k], 1e-6);
    }
    if (t->group_count == 3) {
        /* Material 1: the quad under node 0, p -> (1 - 2y, 2 + 2x, 3 + 2z), then under node 3, p + (10,0,0). */
        const mr_gltf_triangle_group *q = &t->groups[0];
        MR_CHECK(q->material == 1 && q->primitive_count == 2 && q->has_normals && q->has_uv0 && !q->has_tangents &&
                 !q->has_uv1);
        const double qv[8][3] = {{1, 2, 3}, {1, 4, 3}, {-1, 4, 3}, {-1, 2, 3},
                                 {10, 0, 0}, {11, 0, 0}, {11, 1, 0}, {10, 1, 0}};
        check_vertices(q, qv, 8, "quad");
        const uint32_t qi[12] = {0, 1, 2, 0, 2, 3, 4, 5, 6, 4, 6, 7};
        check_indices(q, qi, 4, "quad");
        const double quv[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
        if (q->has_uv0 && q->has_normals && q->vertex_count == 8)
            for (int v = 0; v < 8; v++) {
                MR_CHECK(q->uv0[2 * v] == quv[v % 4][0] && q->uv0[2 * v + 1] == quv[v % 4][1]);
                MR_CHECK_NEAR(q->normals[3 * v + 2], 1.0, 1e-6);
            }
        /* No material: the strip and the fan under node 1, p -> (1 - 2y, 2 + 2x, 5 + 2z); the strip's second
         * triangle is {v1, v3, v2}, the fan's {v1, v2, v0} and {v2, v3, v0}. */
        const mr_gltf_triangle_group *s = &t->groups[1];
        MR_CHECK(s->material == -1 && s->primitive_count == 2 && !s->has_normals && !s->has_tangents &&
                 !s->has_uv0 && s->normals == NULL && s->uv0 == NULL);
        const double sv[8][3] = {{1, 2, 5}, {1, 4, 5}, {-1, 2, 5}, {-1, 4, 5},
                                 {1, 2, 5}, {1, 4, 5}, {-1, 4, 5}, {-1, 2, 5}};
        check_vertices(s, sv, 8, "strip and fan");
        const uint32_t si[12] = {0, 1, 2, 1, 3, 2, 5, 6, 4, 6, 7, 4};
        check_indices(s, si, 4, "strip and fan");
        /* Material 0: the sparse quad (vertex 2 = (2,2,0)) mirrored in x: winding reversed, normal still +z,
         * tangent (1,0,0,+1) -> (-1,0,0,-1), so w * cross(n, t) = -(0,-1,0) = +y, the mirrored bitangent. */
        const mr_gltf_triangle_group *m = &t->groups[2];
        MR_CHECK(m->material == 0 && m->has_normals && m->has_tangents && !m->has_uv0);
        const double mv[4][3] = {{0, 0, 0}, {-1, 0, 0}, {-2, 2, 0}, {0, 1, 0}};
        check_vertices(m, mv, 4, "mirrored sparse quad");
        const uint32_t mi[6] = {0, 2, 1, 0, 3, 2};
        check_indices(m, mi, 2, "mirrored sparse quad");
        if (m->has_normals && m->has_tangents && m->vertex_count == 4) {
            for (int v = 0; v < 4; v++) {
                MR_CHECK_NEAR(m->normals[3 * v + 2], 1.0, 1e-6);
                MR_CHECK(m->tangents[4 * v] == -1.0f && m->tangents[4 * v + 3] == -1.0f);
            }
            /* The geometric normal of the first triangle by its (counter-clockwise) winding is +z. */
            const float *a = m->positions, *b = m->positions + 3 * m->indices[1], *c = m->positions + 3 * m->indices[2];
            double e1[2] = {b[0] - a[0], b[1] - a[1]}, e2[2] = {c[0] - a[0], c[1] - a[1]};
            MR_CHECK(e1[0] * e2[1] - e1[1] * e2[0] > 0);
        }
    }
    mr_gltf_triangles_free(t);

    /* Scene 1 is the mirrored quad alone; the bounds helper agrees. */
    t = NULL;
    MR_CHECK_OK(mr_gltf_get_triangles(g, 1, &t));
    if (t != NULL) MR_CHECK(t->scene == 1 && t->group_count == 1 && t->triangle_count == 2 && t->vertex_count == 4);
    mr_gltf_triangles_free(t);
    double blo[3], bhi[3];
    int count = 0;
    MR_CHECK_OK(mr_gltf_get_bounds(g, 1, blo, bhi, NULL));
    MR_CHECK(blo[0] == -2 && blo[1] == 0 && blo[2] == 0 && bhi[0] == 0 && bhi[1] == 2 && bhi[2] == 0);
    MR_CHECK_OK(mr_gltf_get_bounds(g, 0, blo, bhi, &count));
    MR_CHECK(count == 20 && blo[0] == -2 && bhi[0] == 11 && bhi[2] == 5);
    t = (mr_gltf_triangles *)&t;
    MR_CHECK(mr_gltf_get_triangles(g, 2, &t) == MR_ERR_INVALID_ARG && t == NULL);
    MR_CHECK(mr_gltf_get_triangles(NULL, 0, &t) == MR_ERR_INVALID_ARG);
    mr_gltf_triangles_free(NULL);
    mr_gltf_free(g);

    /* Without "scene", scene 0; without scenes, nothing. */
    path = write_geo("geo_noscene.gltf", "\"scene\": 0,", "");
    g = NULL;
    MR_CHECK_OK(mr_gltf_load(path, &g));
    t = NULL;
    if (g != NULL) MR_CHECK_OK(mr_gltf_get_triangles(g, -1, &t));
    if (t != NULL) MR_CHECK(t->scene == 0 && t->triangle_count == 10);
    mr_gltf_triangles_free(t);
    mr_gltf_free(g);
}

/* Under any affine node matrix, mirroring or not, non-uniform and sheared, the mirrored-quad group stays
 * consistent: each triangle's winding normal equals its vertices' normals (inverse transpose, flipped winding),
 * tangents lie in the plane, and w * cross(n, t) points along the transformed bitangent M (0,1,0). */
MR_TEST(geometry_general_transforms) {
    const char *matrices[] = {"[1, 0.3, 0.4, 0, 0.5, 2, 0.2, 0, 0.2, 0.1, 0.7, 0, 5, -6, 7, 1]",
                              "[1, 0.3, 0.4, 0, 0.5, -2, 0.2, 0, 0.2, 0.1, 0.7, 0, 5, -6, 7, 1]",
                              "[0, 0, 3, 0, 0, 1, 0, 0, 1, 0, 0, 0, 0, 0, 0, 1]"};
    const double by[3][3] = {{0.5, 2, 0.2}, {0.5, -2, 0.2}, {0, 1, 0}}; /* M (0,1,0): the second column */
    for (int mi = 0; mi < 3; mi++) {
        char node[200];
        snprintf(node, sizeof node, "{\"matrix\": %s, \"mesh\": 2}", matrices[mi]);
        const char *path = write_geo("geo_matrix.gltf", "{\"scale\": [-1, 1, 1], \"mesh\": 2}", node);
        mr_gltf *g = NULL;
        MR_CHECK_OK(mr_gltf_load(path, &g));
        mr_gltf_triangles *t = NULL;
        if (g != NULL) MR_CHECK_OK(mr_gltf_get_triangles(g, 1, &t));
        if (t != NULL && t->group_count == 1 && t->groups[0].has_normals && t->groups[0].has_tangents) {
            const mr_gltf_triangle_group *q = &t->groups[0];
            MR_CHECK(t->flipped_primitives == (mi == 0 ? 0 : 1));
            for (int tri = 0; tri < q->triangle_count; tri++) {
                const float *p[3];
                for (int k = 0; k < 3; k++) p[k] = q->positions + 3 * q->indices[3 * tri + k];
                double e1[3], e2[3], f[3];
                for (int k = 0; k < 3; k++) e1[k] = p[1][k] - p[0][k], e2[k] = p[2][k] - p[0][k];
                f[0] = e1[1] * e2[2] - e1[2] * e2[1];
                f[1] = e1[2] * e2[0] - e1[0] * e2[2];
                f[2] = e1[0] * e2[1] - e1[1] * e2[0];
                double len = sqrt(f[0] * f[0] + f[1] * f[1] + f[2] * f[2]);
                for (int k = 0; k < 3; k++) {
                    const float *n = q->normals + 3 * q->indices[3 * tri + k];
                    const float *a = q->tangents + 4 * q->indices[3 * tri + k];
                    MR_CHECK_NEAR((f[0] * n[0] + f[1] * n[1] + f[2] * n[2]) / len, 1.0, 1e-5);
                    MR_CHECK_NEAR(a[0] * n[0] + a[1] * n[1] + a[2] * n[2], 0.0, 1e-5);
                    double b[3] = {a[3] * (n[1] * a[2] - n[2] * a[1]), a[3] * (n[2] * a[0] - n[0] * a[2]),
                                   a[3] * (n[0] * a[1] - n[1] * a[0])};
                    MR_CHECK_MSG(b[0] * by[mi][0] + b[1] * by[mi][1] + b[2] * by[mi][2] > 0,
                                 "matrix %d: the bitangent is reversed", mi);
                }
            }
        } else {
            MR_CHECK_MSG(0, "matrix %d: no normals and tangents", mi);
        }
        mr_gltf_triangles_free(t);
        mr_gltf_free(g);
    }
    /* An asset without scenes gives nothing, box 0. */
    const char *path = write_geo("geo_none.gltf", "\"scene\": 0,\n\"scenes\": [{\"nodes\": [0, 2, 3, 4]}, "
                                 "{\"nodes\": [2]}],", "");
    mr_gltf *g = NULL;
    MR_CHECK_OK(mr_gltf_load(path, &g));
    mr_gltf_triangles *t = NULL;
    if (g != NULL) MR_CHECK_OK(mr_gltf_get_triangles(g, -1, &t));
    if (t != NULL)
        MR_CHECK(t->scene == -1 && t->group_count == 0 && t->triangle_count == 0 && t->bbox_min[0] == 0 &&
                 t->bbox_max[2] == 0);
    mr_gltf_triangles_free(t);
    mr_gltf_free(g);
}

/* Each bad asset fails with MR_ERR_FORMAT and a message naming the file and `needle` (mesh and primitive). */
static void expect_geometry_error(const char *name, const char *from, const char *to, const char *needle) {
    const char *path = write_geo(name, from, to);
    mr_gltf *g = NULL;
    mr_status s = mr_gltf_load(path, &g);
    if (s != MR_OK) { /* tinygltf's own checks may catch it first: then the load names the file */
        MR_CHECK_MSG(s == MR_ERR_FORMAT && strstr(mr_last_error(), path) != NULL, "%s: load: %s", name,
                     mr_last_error());
        return;
    }
    mr_gltf_triangles *t = (mr_gltf_triangles *)&g;
    s = mr_gltf_get_triangles(g, -1, &t);
    MR_CHECK_MSG(s == MR_ERR_FORMAT && t == NULL, "%s: %s (%s)", name, mr_status_str(s), mr_last_error());
    MR_CHECK_MSG(strstr(mr_last_error(), path) != NULL && strstr(mr_last_error(), needle) != NULL,
                 "%s: message '%s' lacks the file or '%s'", name, mr_last_error(), needle);
    mr_gltf_free(g);
}

MR_TEST(geometry_bad_inputs) {
    /* index 9 of 4 vertices; an accessor that does not exist; 400 elements in a 48-byte view; a NaN position */
    expect_geometry_error("g_index.gltf", "\"indices\": 3,\n    \"material\": 1", "\"indices\": 7, \"material\": 1",
                          "mesh 0 ('') primitive 0: index 2 is 9, past the 4 vertices");
    expect_geometry_error("g_acc.gltf", "\"indices\": 3,\n    \"material\": 0", "\"indices\": 99, \"material\": 0",
                          "mesh 2 ('') primitive 0: indices: accessor 99 does not exist");
    expect_geometry_error("g_view.gltf", "\"count\": 4, \"type\": \"VEC3\", \"name\": \"quadpos\"",
                          "\"count\": 400, \"type\": \"VEC3\"", "mesh 0 ('') primitive 0: POSITION: accessor 0");
    /* a count of 2^30 (and 2^62, whose byte size overflows) is held against the view's bytes before anything is
     * allocated for it: 24 GiB of doubles were asked for before it was */
    expect_geometry_error("g_huge.gltf", "\"count\": 4, \"type\": \"VEC3\", \"name\": \"quadpos\"",
                          "\"count\": 1073741824, \"type\": \"VEC3\"",
                          "POSITION: accessor 0: count 1073741824 (12-byte elements, byteStride 12) at byteOffset 0 "
                          "runs past the end of buffer view");
    expect_geometry_error("g_overflow.gltf", "\"count\": 4, \"type\": \"VEC3\", \"name\": \"quadpos\"",
                          "\"count\": 4611686018427387904, \"type\": \"VEC3\"",
                          "POSITION: accessor 0: count 4611686018427387904");
    expect_geometry_error("g_nan.gltf", "\"POSITION\": 5,", "\"POSITION\": 8,",
                          "mesh 2 ('') primitive 0: POSITION 0 is not finite");
    /* POSITION of type VEC2; NORMAL with fewer elements; sparse index past the count; mode 7 */
    expect_geometry_error("g_type.gltf", "\"POSITION\": 4}", "\"POSITION\": 2}",
                          "mesh 1 ('') primitive 0: POSITION: accessor 2 is a VEC2, not a VEC3");
    expect_geometry_error("g_count.gltf", "\"NORMAL\": 1, \"TANGENT\"", "\"NORMAL\": 8, \"TANGENT\"",
                          "mesh 2 ('') primitive 0: NORMAL has 1 elements, POSITION 4");
    expect_geometry_error("g_sparse.gltf", "\"sparse\": {\"count\": 1,", "\"sparse\": {\"count\": 5,",
                          "mesh 2 ('') primitive 0: POSITION: accessor 5: sparse.count 5 out of range");
    expect_geometry_error("g_mode.gltf", "\"mode\": 6", "\"mode\": 7", "mesh 1 ('') primitive 1: unknown mode 7");
    /* a node cycle; a node naming a missing mesh */
    expect_geometry_error("g_cycle.gltf", "\"mesh\": 1}", "\"mesh\": 1, \"children\": [0]}", "node 0 is reached twice");
    expect_geometry_error("g_mesh.gltf", "{\"mesh\": 3}", "{\"mesh\": 30}", "node 4 refers to mesh 30");
}

/* Random bytes in the buffer and random truncations of it: triangles or MR_ERR_FORMAT, never a crash. */
MR_TEST(geometry_mutated_buffers) {
    char path[512], bin_path[512]; /* tmp_path's slots are reused */
    snprintf(path, sizeof path, "%s", write_geo("geo_fuzz.gltf", NULL, NULL));
    snprintf(bin_path, sizeof bin_path, "%s", mr_test_tmp_path("geo.bin"));
    unsigned char bin[280];
    geo_buffer(bin);
    unsigned seed = 777;
    int ok = 0, failed = 0, bad = 0;
    for (int it = 0; it < 300; it++) {
        unsigned char c[280];
        memcpy(c, bin, sizeof c);
        for (int k = 0; k < 1 + it % 6; k++) {
            seed = seed * 1103515245u + 12345u;
            c[(seed >> 8) % 280] = (unsigned char)(seed >> 20);
        }
        MR_CHECK(mr_test_write_file(bin_path, c, sizeof c));
        mr_gltf *g = NULL;
        if (mr_gltf_load(path, &g) != MR_OK) continue;
        mr_gltf_triangles *t = NULL;
        mr_status s = mr_gltf_get_triangles(g, -1, &t);
        if (s == MR_OK) {
            ok++;
            check_triangles_consistent(t, "mutated");
        } else {
            failed++;
            bad += s != MR_ERR_FORMAT || strstr(mr_last_error(), path) == NULL;
        }
        mr_gltf_triangles_free(t);
        mr_gltf_free(g);
    }
    MR_CHECK_MSG(ok > 0 && failed > 0 && bad == 0 && ok + failed == 300,
                 "%d ok, %d failed, %d without MR_ERR_FORMAT and the file", ok, failed, bad);
}

MR_TEST_MAIN(MR_TEST_ENTRY(geometry_every_asset),
             MR_TEST_ENTRY(geometry_water_bottle_and_duck),
             MR_TEST_ENTRY(geometry_hand_made_asset),
             MR_TEST_ENTRY(geometry_general_transforms),
             MR_TEST_ENTRY(geometry_bad_inputs),
             MR_TEST_ENTRY(geometry_mutated_buffers))
