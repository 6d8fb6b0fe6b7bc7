// geometry.cpp — a scene's world-space triangles (mr_gltf_get_triangles, mr_gltf_get_bounds; contract in
// gltf/mr_gltf.h, "Geometry"): the node forest flattened, every accessor read whatever its layout.
#include "gltf/gltf_internal.hpp"

#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include <algorithm>
#include <cmath>

using namespace mr_gltf_internal;

namespace {

struct mat4 {
    double m[16]; // column-major, as glTF's node.matrix
};

mat4 mat_identity() {
    mat4 r;
    for (int i = 0; i < 16; i++) r.m[i] = (i % 5 == 0) ? 1.0 : 0.0;
    return r;
}

mat4 mat_mul(const mat4 &a, const mat4 &b) {
    mat4 r;
    for (int c = 0; c < 4; c++)
        for (int row = 0; row < 4; row++) {
            double s = 0.0;
            for (int k = 0; k < 4; k++) s += a.m[k * 4 + row] * b.m[c * 4 + k];
            r.m[c * 4 + row] = s;
        }
    return r;
}

// The node's local matrix: node.matrix, or T * R * S (a quaternion of any non-zero length is normalised).
mat4 node_local(const tinygltf::Node &n) {
    mat4 r = mat_identity();
    if (n.matrix.size() == 16) {
        for (int i = 0; i < 16; i++) r.m[i] = n.matrix[i];
        return r;
    }
    double x = 0, y = 0, z = 0, w = 1;
    if (n.rotation.size() == 4) {
        x = n.rotation[0], y = n.rotation[1], z = n.rotation[2], w = n.rotation[3];
        double len = std::sqrt(x * x + y * y + z * z + w * w);
        if (len > 0 && std::isfinite(len)) x /= len, y /= len, z /= len, w /= len;
    }
    const double rot[9] = {1 - 2 * (y * y + z * z), 2 * (x * y + z * w),     2 * (x * z - y * w),
                           2 * (x * y - z * w),     1 - 2 * (x * x + z * z), 2 * (y * z + x * w),
                           2 * (x * z + y * w),     2 * (y * z - x * w),     1 - 2 * (x * x + y * y)};
    for (int c = 0; c < 3; c++) {
        double s = n.scale.size() == 3 ? n.scale[c] : 1.0;
        for (int row = 0; row < 3; row++) r.m[c * 4 + row] = rot[c * 3 + row] * s;
    }
    if (n.translation.size() == 3)
        for (int i = 0; i < 3; i++) r.m[12 + i] = n.translation[i];
    return r;
}

int component_bytes(int type) {
    switch (type) {
    case TINYGLTF_COMPONENT_TYPE_BYTE:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return 1;
    case TINYGLTF_COMPONENT_TYPE_SHORT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return 2;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
    case TINYGLTF_COMPONENT_TYPE_FLOAT: return 4;
    default: return 0;
    }
}

// One component (little-endian, as glTF stores it), normalized integers mapped to [0,1] or [-1,1].
double read_component(const unsigned char *p, int type, bool normalized) {
    switch (type) {
    case TINYGLTF_COMPONENT_TYPE_BYTE: {
        double v = (double)(int8_t)p[0];
        return normalized ? std::max(v / 127.0, -1.0) : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return normalized ? p[0] / 255.0 : (double)p[0];
    case TINYGLTF_COMPONENT_TYPE_SHORT: {
        double v = (double)(int16_t)(uint16_t)(p[0] | p[1] << 8);
        return normalized ? std::max(v / 32767.0, -1.0) : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
        double v = (double)(uint16_t)(p[0] | p[1] << 8);
        return normalized ? v / 65535.0 : v;
    }
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT: {
        uint32_t u = (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
        return normalized ? u / 4294967295.0 : (double)u;
    }
    default: { // float
        uint32_t u = (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
        float f;
        memcpy(&f, &u, 4);
        return f;
    }
    }
}

// Where `count` elements of n components of `type` lie in buffer view `view` at `offset`: checked against the
// view and the view against its buffer (stride * (count - 1) + element size within the view, the view within the
// buffer, every step overflow-safe) before anything is allocated for them. packed ignores the view's byteStride
// (sparse arrays are tightly packed). "" on success (*base and *stride set), else the reason, naming the field.
std::string locate(const tinygltf::Model &m, int view, size_t offset, size_t count, int n, int type, bool packed,
                   const unsigned char **base, size_t *stride) {
    if (view < 0 || view >= (int)m.bufferViews.size())
        return "bufferView " + std::to_string(view) + " does not exist (the asset has " +
               std::to_string(m.bufferViews.size()) + ")";
    const tinygltf::BufferView &v = m.bufferViews[view];
    if (v.extensions.count("EXT_meshopt_compression"))
        return "buffer view " + std::to_string(view) + " is EXT_meshopt_compression-compressed (not decoded)";
    if (v.buffer < 0 || v.buffer >= (int)m.buffers.size())
        return "buffer view " + std::to_string(view) + ": buffer " + std::to_string(v.buffer) + " does not exist";
    const std::vector<unsigned char> &buf = m.buffers[v.buffer].data;
    if (v.byteOffset > buf.size() || v.byteLength > buf.size() - v.byteOffset)
        return "buffer view " + std::to_string(view) + " (byteOffset " + std::to_string(v.byteOffset) +
               ", byteLength " + std::to_string(v.byteLength) + ") exceeds buffer " + std::to_string(v.buffer) + " (" +
               std::to_string(buf.size()) + " bytes)";
    size_t cs = (size_t)component_bytes(type), elem = cs * (size_t)n;
    *stride = (!packed && v.byteStride != 0) ? v.byteStride : elem;
    if (*stride < elem)
        return "buffer view " + std::to_string(view) + ": byteStride " + std::to_string(*stride) +
               " is smaller than an element (" + std::to_string(elem) + " bytes)";
    *base = buf.data() + v.byteOffset;
    if (count == 0) return "";
    // stride * (count - 1) + elem <= byteLength - offset, without computing the product.
    size_t avail = offset <= v.byteLength ? v.byteLength - offset : 0;
    if (offset > v.byteLength || elem > avail || (count - 1) > (avail - elem) / *stride)
        return "count " + std::to_string(count) + " (" + std::to_string(elem) + "-byte elements, byteStride " +
               std::to_string(*stride) + ") at byteOffset " + std::to_string(offset) +
               " runs past the end of buffer view " + std::to_string(view) + " (byteLength " +
               std::to_string(v.byteLength) + ")";
    *base += offset;
    return "";
}

// Reads `count` elements of n components located by locate() into dst (count * n values).
void read_elements(const unsigned char *base, size_t stride, size_t count, int n, int type, bool normalized,
                   double *dst) {
    const size_t cs = (size_t)component_bytes(type);
    for (size_t i = 0; i < count; i++)
        for (int c = 0; c < n; c++) dst[i * n + c] = read_component(base + i * stride + c * cs, type, normalized);
}

std::string type_name(int type) {
    switch (type) {
    case TINYGLTF_TYPE_SCALAR: return "SCALAR";
    case TINYGLTF_TYPE_VEC2: return "VEC2";
    case TINYGLTF_TYPE_VEC3: return "VEC3";
    case TINYGLTF_TYPE_VEC4: return "VEC4";
    case TINYGLTF_TYPE_MAT2: return "MAT2";
    case TINYGLTF_TYPE_MAT3: return "MAT3";
    case TINYGLTF_TYPE_MAT4: return "MAT4";
    default: return "type " + std::to_string(type);
    }
}

// An accessor without a buffer view is zeros (sparse values on top): nothing in the file holds them, so their
// count has a limit of its own (mr_gltf.h, "Limits").
const size_t MAX_ZERO_ELEMENTS = (size_t)1 << 20;

// Where an accessor's values lie (check_accessor): its elements, and a sparse accessor's indices and values.
struct accessor_layout {
    int n = 0;                        // components per element
    const unsigned char *base = NULL; // the elements (NULL: zeros, no buffer view)
    size_t stride = 0;
    size_t sparse = 0;  // sparse.count, 0 if not sparse
    int index_type = 0; // sparse.indices.componentType
    const unsigned char *indices = NULL, *values = NULL;
    size_t index_stride = 0, value_stride = 0;
};

// Accessor `index` of glTF type want_type (TINYGLTF_TYPE_*) checked without reading it: every count, offset and
// stride against the bytes that hold it (locate()), a count without a buffer view against MAX_ZERO_ELEMENTS. ""
// on success (*layout set), else the reason, naming the accessor and the field.
std::string check_accessor(const tinygltf::Model &m, int index, int want_type, accessor_layout *layout) {
    if (index < 0 || index >= (int)m.accessors.size())
        return "accessor " + std::to_string(index) + " does not exist (the asset has " +
               std::to_string(m.accessors.size()) + ")";
    const tinygltf::Accessor &a = m.accessors[index];
    std::string name = "accessor " + std::to_string(index);
    if (a.type != want_type) return name + " is a " + type_name(a.type) + ", not a " + type_name(want_type);
    layout->n = tinygltf::GetNumComponentsInType((uint32_t)a.type);
    if (layout->n <= 0 || component_bytes(a.componentType) == 0)
        return name + " has an unknown componentType " + std::to_string(a.componentType);
    if (a.bufferView < 0 && a.count > MAX_ZERO_ELEMENTS)
        return name + ": count " + std::to_string(a.count) + " without a bufferView (at most " +
               std::to_string(MAX_ZERO_ELEMENTS) + ")";
    if (a.bufferView >= 0) {
        std::string why = locate(m, a.bufferView, a.byteOffset, a.count, layout->n, a.componentType, false,
                                 &layout->base, &layout->stride);
        if (!why.empty()) return name + ": " + why;
    } else if (a.byteOffset != 0) {
        return name + ": byteOffset " + std::to_string(a.byteOffset) + " without a bufferView";
    }
    if (!a.sparse.isSparse)
        return "";
    if (a.sparse.count < 1 || (size_t)a.sparse.count > a.count)
        return name + ": sparse.count " + std::to_string(a.sparse.count) + " out of range (1 to count " +
               std::to_string(a.count) + ")";
    layout->sparse = (size_t)a.sparse.count;
    const int it = layout->index_type = a.sparse.indices.componentType;
    if (it != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE && it != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
        it != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
        return name + ": sparse.indices.componentType " + std::to_string(it) + " is not an unsigned integer";
    if (a.sparse.indices.byteOffset < 0 || a.sparse.values.byteOffset < 0)
        return name + ": negative sparse byteOffset";
    std::string why = locate(m, a.sparse.indices.bufferView, (size_t)a.sparse.indices.byteOffset, layout->sparse, 1, it,
                             true, &layout->indices, &layout->index_stride);
    if (!why.empty())
        return name + ": sparse.indices: " + why;
    why = locate(m, a.sparse.values.bufferView, (size_t)a.sparse.values.byteOffset, layout->sparse, layout->n,
                 a.componentType, true, &layout->values, &layout->value_stride);
    if (!why.empty())
        return name + ": sparse.values: " + why;
    return "";
}

// Accessor `index` of glTF type want_type as doubles, count * components; sparse applied. Nothing is allocated
// before check_accessor has held every size against the bytes that hold it: count * n doubles are then at most 8
// times those bytes (or MAX_ZERO_ELEMENTS elements).
std::string read_accessor(const tinygltf::Model &m, int index, int want_type, std::vector<double> *out) {
    accessor_layout L;
    std::string why = check_accessor(m, index, want_type, &L);
    if (!why.empty())
        return why;
    const tinygltf::Accessor &a = m.accessors[index];
    const int n = L.n;
    out->assign(a.count * (size_t)n, 0.0);
    if (L.base != NULL)
        read_elements(L.base, L.stride, a.count, n, a.componentType, a.normalized, out->data());
    if (L.sparse > 0) {
        const size_t sc = L.sparse;
        std::vector<double> idx(sc), val(sc * (size_t)n);
        read_elements(L.indices, L.index_stride, sc, 1, L.index_type, false, idx.data());
        read_elements(L.values, L.value_stride, sc, n, a.componentType, a.normalized, val.data());
        for (size_t i = 0; i < sc; i++) {
            if (idx[i] >= (double)a.count)
                return "accessor " + std::to_string(index) + ": sparse index " + std::to_string((long long)idx[i]) +
                       " past its " + std::to_string(a.count) + " elements";
            size_t k = (size_t)idx[i];
            for (int c = 0; c < n; c++) (*out)[k * n + c] = val[i * n + c];
        }
    }
    return "";
}

enum { HAS_NORMALS = 1, HAS_TANGENTS = 2, HAS_UV0 = 4, HAS_UV1 = 8 };

struct group_build {
    int material = -1;
    int flags = 0;
    int primitives = 0;
    std::vector<float> pos, nrm, tan, uv0, uv1;
    std::vector<uint32_t> idx;
};

struct geometry_build {
    std::vector<group_build> groups;
    int primitives = 0, skipped = 0, flipped = 0;
    size_t vertices = 0, triangles = 0; // so far, over all groups
};

// The most vertices and triangles a scene may flatten to (mr_gltf.h, "Limits"): instancing repeats a mesh once per
// node, so a small file can name more geometry than its bytes hold; about 1 GB of arrays at the limit.
const size_t MAX_SCENE_VERTICES = (size_t)1 << 24, MAX_SCENE_TRIANGLES = (size_t)1 << 24;

bool all_finite(const std::vector<double> &v) {
    for (double x : v)
        if (!std::isfinite(x)) return false;
    return true;
}

// One primitive instance under world matrix w into the build; errors are MR_ERR_FORMAT naming it.
mr_status add_primitive(const mr_gltf *g, int mesh, int prim, const mat4 &w, geometry_build *b) {
    const tinygltf::Model &m = g->model;
    const tinygltf::Primitive &p = m.meshes[mesh].primitives[prim];
    std::string where = "glTF '" + g->path + "': mesh " + std::to_string(mesh) + " ('" + m.meshes[mesh].name +
                        "') primitive " + std::to_string(prim);
    int mode = p.mode < 0 ? TINYGLTF_MODE_TRIANGLES : p.mode;
    if (mode > TINYGLTF_MODE_TRIANGLE_FAN)
        return mr_fail(MR_ERR_FORMAT, "%s: unknown mode %d", where.c_str(), mode);
    if (mode < TINYGLTF_MODE_TRIANGLES) { // points, lines, line loop, line strip
        b->skipped++;
        return MR_OK;
    }
    if (p.material < -1 || p.material >= (int)m.materials.size())
        return mr_fail(MR_ERR_FORMAT, "%s: material %d does not exist", where.c_str(), p.material);
    auto attr = [&](const char *key) {
        auto it = p.attributes.find(key);
        return it == p.attributes.end() ? -1 : it->second;
    };
    if (p.extensions.count("KHR_draco_mesh_compression"))
        return mr_fail(MR_ERR_UNSUPPORTED, "%s: KHR_draco_mesh_compression is not decoded", where.c_str());
    int a_pos = attr("POSITION");
    if (a_pos < 0) { // glTF: a primitive without positions is not rendered
        b->skipped++;
        return MR_OK;
    }
    const double *M = w.m;
    double det = M[0] * (M[5] * M[10] - M[9] * M[6]) - M[4] * (M[1] * M[10] - M[9] * M[2]) +
                 M[8] * (M[1] * M[6] - M[5] * M[2]);
    if (!std::isfinite(det)) return mr_fail(MR_ERR_FORMAT, "%s: its node transform is not finite", where.c_str());
    if (det == 0.0) { // a zero scale hides the instance
        b->skipped++;
        return MR_OK;
    }
    // POSITION checked against its bytes, then its count against the scene's limit, before anything is read for
    // this instance (instancing repeats a mesh once per node).
    accessor_layout layout;
    std::string why = check_accessor(m, a_pos, TINYGLTF_TYPE_VEC3, &layout);
    if (!why.empty())
        return mr_fail(MR_ERR_FORMAT, "%s: POSITION: %s", where.c_str(), why.c_str());
    if (m.accessors[a_pos].count > MAX_SCENE_VERTICES - b->vertices)
        return mr_fail(MR_ERR_FORMAT,
                       "%s: POSITION: accessor %d: count %zu takes the scene past the limit of %zu "
                       "vertices (%zu so far)",
                       where.c_str(), a_pos, m.accessors[a_pos].count, MAX_SCENE_VERTICES, b->vertices);
    std::vector<double> pos, nrm, tan, uv0, uv1, ind;
    why = read_accessor(m, a_pos, TINYGLTF_TYPE_VEC3, &pos);
    if (!why.empty()) return mr_fail(MR_ERR_FORMAT, "%s: POSITION: %s", where.c_str(), why.c_str());
    size_t nv = pos.size() / 3;
    for (size_t i = 0; i < pos.size(); i++)
        if (!std::isfinite(pos[i]))
            return mr_fail(MR_ERR_FORMAT, "%s: POSITION %zu is not finite", where.c_str(), i / 3);
    struct opt_attr {
        const char *key;
        int type, comps, flag;
        std::vector<double> *dst;
    } opts[] = {{"NORMAL", TINYGLTF_TYPE_VEC3, 3, HAS_NORMALS, &nrm},
                {"TANGENT", TINYGLTF_TYPE_VEC4, 4, HAS_TANGENTS, &tan},
                {"TEXCOORD_0", TINYGLTF_TYPE_VEC2, 2, HAS_UV0, &uv0},
                {"TEXCOORD_1", TINYGLTF_TYPE_VEC2, 2, HAS_UV1, &uv1}};
    int flags = 0;
    for (auto &o : opts) {
        int a = attr(o.key);
        if (a < 0) continue;
        why = read_accessor(m, a, o.type, o.dst);
        if (!why.empty()) return mr_fail(MR_ERR_FORMAT, "%s: %s: %s", where.c_str(), o.key, why.c_str());
        if (o.dst->size() != nv * (size_t)o.comps)
            return mr_fail(MR_ERR_FORMAT, "%s: %s has %zu elements, POSITION %zu", where.c_str(), o.key,
                           o.dst->size() / o.comps, nv);
        // Unusable values (not finite, zero normal or tangent) drop the attribute: the renderer generates it.
        if (all_finite(*o.dst)) flags |= o.flag;
    }
    // Normals by the inverse transpose (cofactors, signed by det: renormalised below), tangents by the matrix.
    double cof[9];
    for (int c = 0; c < 3; c++)
        for (int r = 0; r < 3; r++) {
            int c1 = (c + 1) % 3, c2 = (c + 2) % 3, r1 = (r + 1) % 3, r2 = (r + 2) % 3;
            cof[c * 3 + r] = (M[c1 * 4 + r1] * M[c2 * 4 + r2] - M[c2 * 4 + r1] * M[c1 * 4 + r2]) * (det < 0 ? -1 : 1);
        }
    std::vector<float> wp(nv * 3), wn, wt;
    for (size_t i = 0; i < nv; i++)
        for (int r = 0; r < 3; r++) {
            double v = M[12 + r];
            for (int k = 0; k < 3; k++) v += M[k * 4 + r] * pos[i * 3 + k];
            wp[i * 3 + r] = (float)v;
            if (!std::isfinite(wp[i * 3 + r]))
                return mr_fail(MR_ERR_FORMAT, "%s: POSITION %zu is not finite in world space", where.c_str(), i);
        }
    if (flags & HAS_NORMALS) {
        wn.resize(nv * 3);
        for (size_t i = 0; i < nv && (flags & HAS_NORMALS); i++) {
            double v[3], len = 0;
            for (int r = 0; r < 3; r++) {
                v[r] = 0;
                for (int k = 0; k < 3; k++) v[r] += cof[k * 3 + r] * nrm[i * 3 + k];
                len += v[r] * v[r];
            }
            len = std::sqrt(len);
            if (!(len > 0 && std::isfinite(len))) flags &= ~HAS_NORMALS;
            for (int r = 0; r < 3; r++) wn[i * 3 + r] = (float)(v[r] / len);
        }
    }
    if (flags & HAS_TANGENTS) {
        wt.resize(nv * 4);
        for (size_t i = 0; i < nv && (flags & HAS_TANGENTS); i++) {
            double v[3], len = 0;
            for (int r = 0; r < 3; r++) {
                v[r] = 0;
                for (int k = 0; k < 3; k++) v[r] += M[k * 4 + r] * tan[i * 4 + k];
                len += v[r] * v[r];
            }
            len = std::sqrt(len);
            if (!(len > 0 && std::isfinite(len))) flags &= ~HAS_TANGENTS;
            for (int r = 0; r < 3; r++) wt[i * 4 + r] = (float)(v[r] / len);
            wt[i * 4 + 3] = (float)((tan[i * 4 + 3] < 0 ? -1.0 : 1.0) * (det < 0 ? -1.0 : 1.0));
        }
    }
    // Indices, then the mode's triangles.
    if (p.indices >= 0) {
        int ct = p.indices < (int)m.accessors.size() ? m.accessors[p.indices].componentType : -1;
        if (ct >= 0 && ct != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE && ct != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
            ct != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
            return mr_fail(MR_ERR_FORMAT, "%s: indices: accessor %d has componentType %d, not an unsigned integer",
                           where.c_str(), p.indices, ct);
        why = read_accessor(m, p.indices, TINYGLTF_TYPE_SCALAR, &ind);
        if (!why.empty()) return mr_fail(MR_ERR_FORMAT, "%s: indices: %s", where.c_str(), why.c_str());
        for (size_t i = 0; i < ind.size(); i++)
            if (ind[i] >= (double)nv)
                return mr_fail(MR_ERR_FORMAT, "%s: index %zu is %.0f, past the %zu vertices", where.c_str(), i,
                               ind[i], nv);
    } else {
        ind.resize(nv);
        for (size_t i = 0; i < nv; i++) ind[i] = (double)i;
    }
    std::vector<uint32_t> tri;
    size_t ni = ind.size();
    const size_t triangles = mode == TINYGLTF_MODE_TRIANGLES ? ni / 3 : (ni >= 3 ? ni - 2 : 0);
    if (triangles > MAX_SCENE_TRIANGLES - b->triangles)
        return mr_fail(MR_ERR_FORMAT, "%s: its %zu triangles take the scene past the limit of %zu triangles",
                       where.c_str(), triangles, MAX_SCENE_TRIANGLES);
    if (mode == TINYGLTF_MODE_TRIANGLES) {
        for (size_t i = 0; i + 2 < ni; i += 3)
            for (int k = 0; k < 3; k++) tri.push_back((uint32_t)ind[i + k]);
    } else {
        for (size_t i = 0; i + 2 < ni; i++) {
            size_t v[3];
            if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) // glTF: {v_i, v_i+(1+i%2), v_i+(2-i%2)}
                v[0] = i, v[1] = i + 1 + i % 2, v[2] = i + 2 - i % 2;
            else // fan: {v_i+1, v_i+2, v_0}
                v[0] = i + 1, v[1] = i + 2, v[2] = 0;
            for (int k = 0; k < 3; k++) tri.push_back((uint32_t)ind[v[k]]);
        }
    }
    if (det < 0) {
        for (size_t t = 0; t + 2 < tri.size(); t += 3) std::swap(tri[t + 1], tri[t + 2]);
        b->flipped++;
    }
    group_build *grp = NULL;
    for (auto &gb : b->groups)
        if (gb.material == p.material && gb.flags == flags) grp = &gb;
    if (grp == NULL) {
        b->groups.emplace_back();
        grp = &b->groups.back();
        grp->material = p.material;
        grp->flags = flags;
    }
    size_t base = grp->pos.size() / 3;
    if (base + nv > (size_t)INT_MAX / 4 || grp->idx.size() + tri.size() > (size_t)INT_MAX)
        return mr_fail(MR_ERR_FORMAT, "%s: too many vertices or triangles for one material", where.c_str());
    grp->pos.insert(grp->pos.end(), wp.begin(), wp.end());
    if (flags & HAS_NORMALS) grp->nrm.insert(grp->nrm.end(), wn.begin(), wn.end());
    if (flags & HAS_TANGENTS) grp->tan.insert(grp->tan.end(), wt.begin(), wt.end());
    if (flags & HAS_UV0)
        for (double x : uv0) grp->uv0.push_back((float)x);
    if (flags & HAS_UV1)
        for (double x : uv1) grp->uv1.push_back((float)x);
    for (uint32_t t : tri) grp->idx.push_back(t + (uint32_t)base);
    grp->primitives++;
    b->primitives++;
    b->vertices += nv;
    b->triangles += triangles;
    return MR_OK;
}

template <typename T> T *copy_out(const std::vector<T> &v) {
    if (v.empty()) return NULL;
    T *p = (T *)malloc(v.size() * sizeof(T));
    if (p == NULL) throw std::bad_alloc();
    memcpy(p, v.data(), v.size() * sizeof(T));
    return p;
}

mr_status get_triangles_impl(const mr_gltf *g, int scene, mr_gltf_triangles **out) {
    const tinygltf::Model &m = g->model;
    if (scene < -1 || scene >= (int)m.scenes.size())
        return mr_fail(MR_ERR_INVALID_ARG, "glTF '%s': scene %d does not exist (%zu scenes)", g->path.c_str(),
                       scene, m.scenes.size());
    if (scene == -1) scene = m.scenes.empty() ? -1 : (m.defaultScene >= 0 && m.defaultScene < (int)m.scenes.size()
                                                          ? m.defaultScene : 0);
    geometry_build b;
    if (scene >= 0) {
        // Depth-first over the node forest, without recursion; a node reached twice means a cycle or a node
        // with two parents, which glTF forbids.
        std::vector<char> seen(m.nodes.size(), 0);
        std::vector<std::pair<int, mat4>> stack;
        const std::vector<int> &roots = m.scenes[scene].nodes;
        for (size_t i = roots.size(); i-- > 0;) stack.emplace_back(roots[i], mat_identity());
        while (!stack.empty()) {
            int n = stack.back().first;
            mat4 parent = stack.back().second;
            stack.pop_back();
            if (n < 0 || n >= (int)m.nodes.size())
                return mr_fail(MR_ERR_FORMAT, "glTF '%s': scene %d refers to node %d, which does not exist",
                               g->path.c_str(), scene, n);
            if (seen[n])
                return mr_fail(MR_ERR_FORMAT, "glTF '%s': node %d is reached twice from scene %d (a cycle or two "
                               "parents)", g->path.c_str(), n, scene);
            seen[n] = 1;
            const tinygltf::Node &node = m.nodes[n];
            mat4 w = mat_mul(parent, node_local(node));
            if (node.mesh >= (int)m.meshes.size() || node.mesh < -1)
                return mr_fail(MR_ERR_FORMAT, "glTF '%s': node %d refers to mesh %d, which does not exist",
                               g->path.c_str(), n, node.mesh);
            if (node.mesh >= 0)
                for (size_t p = 0; p < m.meshes[node.mesh].primitives.size(); p++) {
                    mr_status s = add_primitive(g, node.mesh, (int)p, w, &b);
                    if (s != MR_OK) return s;
                }
            for (size_t i = node.children.size(); i-- > 0;) stack.emplace_back(node.children[i], w);
        }
    }
    mr_gltf_triangles *t = (mr_gltf_triangles *)calloc(1, sizeof *t);
    if (t == NULL) throw std::bad_alloc();
    t->scene = scene;
    t->primitive_count = b.primitives;
    t->skipped_primitives = b.skipped;
    t->flipped_primitives = b.flipped;
    try {
        if (!b.groups.empty()) {
            t->groups = (mr_gltf_triangle_group *)calloc(b.groups.size(), sizeof *t->groups);
            if (t->groups == NULL) throw std::bad_alloc();
        }
        for (size_t i = 0; i < 3; i++) t->bbox_min[i] = INFINITY, t->bbox_max[i] = -INFINITY;
        for (const group_build &gb : b.groups) {
            mr_gltf_triangle_group *o = &t->groups[t->group_count++];
            o->material = gb.material;
            o->vertex_count = (int)(gb.pos.size() / 3);
            o->triangle_count = (int)(gb.idx.size() / 3);
            o->primitive_count = gb.primitives;
            o->has_normals = (gb.flags & HAS_NORMALS) != 0;
            o->has_tangents = (gb.flags & HAS_TANGENTS) != 0;
            o->has_uv0 = (gb.flags & HAS_UV0) != 0;
            o->has_uv1 = (gb.flags & HAS_UV1) != 0;
            o->positions = copy_out(gb.pos);
            o->normals = copy_out(gb.nrm);
            o->tangents = copy_out(gb.tan);
            o->uv0 = copy_out(gb.uv0);
            o->uv1 = copy_out(gb.uv1);
            o->indices = copy_out(gb.idx);
            if (t->vertex_count > INT_MAX - o->vertex_count || t->triangle_count > INT_MAX - o->triangle_count)
                throw std::length_error("more than INT_MAX vertices or triangles");
            t->vertex_count += o->vertex_count;
            t->triangle_count += o->triangle_count;
            for (size_t v = 0; v < gb.pos.size(); v++) {
                t->bbox_min[v % 3] = std::min(t->bbox_min[v % 3], (double)gb.pos[v]);
                t->bbox_max[v % 3] = std::max(t->bbox_max[v % 3], (double)gb.pos[v]);
            }
        }
        if (t->vertex_count == 0)
            for (size_t i = 0; i < 3; i++) t->bbox_min[i] = t->bbox_max[i] = 0.0;
    } catch (...) {
        mr_gltf_triangles_free(t);
        throw;
    }
    *out = t;
    return MR_OK;
}

} // namespace

// ---- the C API -------------------------------------------------------------------------------------------

extern "C" {

mr_status mr_gltf_get_triangles(const mr_gltf *g, int scene, mr_gltf_triangles **out) {
    if (out != NULL) *out = NULL;
    if (g == NULL || out == NULL) return mr_fail(MR_ERR_INVALID_ARG, "glTF: NULL asset or triangles output");
    MR_GLTF_GUARD(g->path.c_str(), return get_triangles_impl(g, scene, out);)
}

void mr_gltf_triangles_free(mr_gltf_triangles *t) {
    if (t == NULL) return;
    for (int i = 0; i < t->group_count; i++) {
        mr_gltf_triangle_group *o = &t->groups[i];
        free(o->positions);
        free(o->normals);
        free(o->tangents);
        free(o->uv0);
        free(o->uv1);
        free(o->indices);
    }
    free(t->groups);
    free(t);
}

mr_status mr_gltf_get_bounds(const mr_gltf *g, int scene, double lo[3], double hi[3], int *count) {
    if (lo == NULL || hi == NULL) return mr_fail(MR_ERR_INVALID_ARG, "glTF: NULL bounds output");
    mr_gltf_triangles *t = NULL;
    mr_status s = mr_gltf_get_triangles(g, scene, &t);
    if (s != MR_OK) return s;
    for (int i = 0; i < 3; i++) lo[i] = t->bbox_min[i], hi[i] = t->bbox_max[i];
    if (count != NULL) *count = t->vertex_count;
    mr_gltf_triangles_free(t);
    return MR_OK;
}

} // extern "C"
