// obj_load.cpp — Wavefront OBJ meshes through tinyobjloader (contract in src/io/obj_load.h): the file parsed and
// triangulated by tinyobjloader, every index checked here, vertices made unique per (v, vt, vn), missing normals
// computed per position, and errors given the file's line (found by scanning the file again, on failure only).
#include "io/obj_load.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include <fstream>
#include <new>
#include <stdexcept>
#include <string>
#include <unordered_map>
#include <vector>

#include <tiny_obj_loader.h>

#include "mr_internal.h"
#include "render/mesh.h" /* mr_mesh_corner_angle: the renderer's weighting of smooth normals */

namespace {

// The renderer's limits (mesh.c): at most INT32_MAX / 3 triangles and INT32_MAX / 4 vertices.
const size_t max_triangles = INT32_MAX / 3;
const size_t max_vertices = INT32_MAX / 4;

char *dup_string(const std::string &s) {
    char *p = (char *)malloc(s.size() + 1);
    if (p == NULL) throw std::bad_alloc();
    memcpy(p, s.c_str(), s.size() + 1);
    return p;
}

// tinyobjloader's message lines, trimmed, without the empty ones and its lone "." (it ends some with "\n.").
std::vector<std::string> message_lines(const std::string &text) {
    std::vector<std::string> lines;
    size_t start = 0;
    while (start < text.size()) {
        size_t end = text.find('\n', start);
        if (end == std::string::npos) end = text.size();
        std::string line = text.substr(start, end - start);
        while (!line.empty() && (line.back() == ' ' || line.back() == '\r')) line.pop_back();
        if (!line.empty() && line != ".") lines.push_back(line);
        start = end + 1;
    }
    return lines;
}

// An error message on one line: its lines joined by "; ".
std::string one_line(const std::string &text) {
    std::string out;
    for (const std::string &line : message_lines(text)) out += (out.empty() ? "" : "; ") + line;
    return out;
}

// The warnings to keep, one per line: tinyobjloader's, without the "material not found" ones (no .mtl is read on
// purpose).
std::string kept_warnings(const std::string &text) {
    std::string out;
    for (const std::string &line : message_lines(text))
        if (line.find("not found in .mtl") == std::string::npos) out += line + "\n";
    return out;
}

// ---- locating a line, on the error path only ------------------------------------------------------------------

// The record kinds whose lines are counted.
enum record { REC_V = 0, REC_VT, REC_VN, REC_F, REC_COUNT };

// The kind of a line ("v ", "vt ", "vn ", "f "), or REC_COUNT.
record line_kind(const char *p) {
    p += strspn(p, " \t");
    if (p[0] == 'v' && (p[1] == ' ' || p[1] == '\t')) return REC_V;
    if (p[0] == 'v' && p[1] == 't' && (p[2] == ' ' || p[2] == '\t')) return REC_VT;
    if (p[0] == 'v' && p[1] == 'n' && (p[2] == ' ' || p[2] == '\t')) return REC_VN;
    if (p[0] == 'f' && (p[1] == ' ' || p[1] == '\t')) return REC_F;
    return REC_COUNT;
}

// What is wrong with face line `p`, "" if nothing: fewer than 3 corners, or an index (v/vt/vn, 1-based or
// negative = relative to the records before the line) that is 0, not a number or outside the file's records.
// `so_far` counts v, vt, vn records before the line, `totals` in the whole file.
std::string face_fault(const char *p, const long so_far[3], const long totals[3]) {
    static const char *const names[3] = {"v", "vt", "vn"};
    p += strspn(p, " \t") + 1; // past "f"
    int corners = 0;
    for (;;) {
        p += strspn(p, " \t\r\n");
        if (*p == '\0' || *p == '#') break;
        size_t len = strcspn(p, " \t\r\n");
        std::string token(p, len);
        p += len;
        corners++;
        // "v", "v/vt", "v//vn" or "v/vt/vn": up to three fields, the first required
        size_t field_start = 0;
        for (int k = 0; k < 3 && field_start <= token.size(); k++) {
            size_t slash = token.find('/', field_start);
            std::string field = token.substr(field_start, slash == std::string::npos ? std::string::npos
                                                                                     : slash - field_start);
            if (!field.empty() || k == 0) {
                char *end = NULL;
                long i = strtol(field.c_str(), &end, 10);
                long resolved = i > 0 ? i - 1 : so_far[k] + i;
                std::string what = std::string(names[k]) + " index '" + field + "'";
                if (end == field.c_str() || i == 0) return what + ": not an index (1-based, or negative)";
                if (resolved < 0)
                    return what + ": before the first " + names[k] + " record (" + std::to_string(so_far[k]) +
                           " before this line)";
                if (resolved >= totals[k])
                    return what + ": out of range (" + std::to_string(totals[k]) + " " + names[k] + " records)";
            }
            if (slash == std::string::npos) break;
            field_start = slash + 1;
        }
    }
    if (corners < 3) return "a face of " + std::to_string(corners) + " vertices (at least 3)";
    return "";
}

// The 1-based line of the `ordinal`-th record of `kind` (0-based), or with ordinal < 0 (faces) of the first
// faulty face, whose fault goes to *fault; 0 if there is none (or the file cannot be read again).
long locate_line(const std::string &path, record kind, long ordinal, const long totals[3], std::string *fault) {
    FILE *f = fopen(path.c_str(), "rb");
    if (f == NULL) return 0;
    long counts[REC_COUNT] = {0, 0, 0, 0}, line = 0, found = 0;
    std::string text;
    char chunk[4096];
    bool more = true;
    while (more && found == 0) {
        text.clear();
        for (;;) { // one line, however long
            if (fgets(chunk, sizeof chunk, f) == NULL) {
                more = false;
                break;
            }
            text += chunk;
            if (!text.empty() && text.back() == '\n') break;
        }
        if (!more && text.empty()) break;
        line++;
        record k = line_kind(text.c_str());
        if (k == REC_COUNT) continue;
        if (k == kind) {
            if (ordinal >= 0 && counts[k] == ordinal) found = line;
            if (ordinal < 0 && !(*fault = face_fault(text.c_str(), counts, totals)).empty()) found = line;
        }
        counts[k]++;
    }
    fclose(f);
    return found;
}

// "OBJ 'path', line N" or "OBJ 'path'" when the line is unknown.
std::string where(const std::string &path, long line) {
    return "OBJ '" + path + "'" + (line > 0 ? ", line " + std::to_string(line) : std::string());
}

// ---- the mesh -------------------------------------------------------------------------------------------------

struct corner_key {
    int v, vt, vn;
    bool operator==(const corner_key &o) const { return v == o.v && vt == o.vt && vn == o.vn; }
};

struct corner_hash {
    size_t operator()(const corner_key &k) const {
        uint64_t h = (uint64_t)(uint32_t)k.v * 0x9E3779B97F4A7C15ull;
        h ^= (uint64_t)(uint32_t)k.vt * 0xC2B2AE3D27D4EB4Full + (h << 6) + (h >> 2);
        h ^= (uint64_t)(uint32_t)k.vn * 0x165667B19E3779F9ull + (h << 6) + (h >> 2);
        return (size_t)(h ^ (h >> 29));
    }
};

void sub3(const double *a, const double *b, double *out) {
    for (int i = 0; i < 3; i++) out[i] = a[i] - b[i];
}

void cross3(const double *a, const double *b, double *out) {
    out[0] = a[1] * b[2] - a[2] * b[1];
    out[1] = a[2] * b[0] - a[0] * b[2];
    out[2] = a[0] * b[1] - a[1] * b[0];
}

double dot3(const double *a, const double *b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

// A file normal made unit; false when it is zero or not finite (then a computed one is used).
bool unit_normal(const std::vector<tinyobj::real_t> &normals, int vn, double out[3]) {
    if (vn < 0) return false;
    for (int i = 0; i < 3; i++) out[i] = normals[(size_t)vn * 3 + i];
    double len = sqrt(dot3(out, out));
    if (!(len > 0.0) || !isfinite(len)) return false;
    for (int i = 0; i < 3; i++) out[i] /= len;
    return true;
}

struct loader {
    std::string path;
    mr_obj_options opts;
    tinyobj::attrib_t attrib;
    std::vector<tinyobj::shape_t> shapes;
    std::string warnings;

    long totals[3] = {0, 0, 0};

    mr_status format_error(long line, const std::string &what) {
        return mr_fail(MR_ERR_FORMAT, "%s: %s", where(path, line).c_str(), what.c_str());
    }

    mr_status parse() {
        struct stat st;
        if (stat(path.c_str(), &st) != 0)
            return mr_fail(MR_ERR_IO, "OBJ '%s': cannot open: %s", path.c_str(), strerror(errno));
        if (S_ISDIR(st.st_mode)) return mr_fail(MR_ERR_IO, "OBJ '%s': cannot read: is a directory", path.c_str());
        // A FIFO would block the read, a device (/dev/zero) never end it: regular files only (mr_core.h).
        if (!S_ISREG(st.st_mode))
            return mr_fail(MR_ERR_IO, "OBJ '%s': cannot read: is not a regular file", path.c_str());
        std::ifstream in(path.c_str(), std::ios::in | std::ios::binary);
        if (!in.is_open()) return mr_fail(MR_ERR_IO, "OBJ '%s': cannot open: %s", path.c_str(), strerror(errno));
        std::vector<tinyobj::material_t> materials;
        std::string warn, err;
        // No material reader: mtllib is skipped and no .mtl is opened. Vertex colours (kept by tinyobjloader when
        // every v has them) are not used.
        bool ok = tinyobj::LoadObj(&attrib, &shapes, &materials, &warn, &err, &in, NULL, true, false);
        if (in.bad()) return mr_fail(MR_ERR_IO, "OBJ '%s': read error", path.c_str());
        totals[0] = (long)(attrib.vertices.size() / 3);
        totals[1] = (long)(attrib.texcoords.size() / 2);
        totals[2] = (long)(attrib.normals.size() / 3);
        if (!ok || !err.empty()) {
            // tinyobjloader names the line itself, last (" line 12.)"); put it where ours go.
            std::string message = one_line(err.empty() ? std::string("tinyobjloader failed") : err);
            long line = 0;
            size_t at = message.rfind("line ");
            if (at != std::string::npos) line = strtol(message.c_str() + at + 5, NULL, 10);
            return format_error(line, "tinyobjloader: " + message);
        }
        // Faces tinyobjloader dropped or could not index: an error here, with the face's line.
        if (warn.find("Degenerated face") != std::string::npos || warn.find("out of bounds") != std::string::npos ||
            warn.find("invalid vertex index") != std::string::npos)
            return bad_face_error();
        warnings = kept_warnings(warn);
        return MR_OK;
    }

    // A face tinyobjloader dropped or indexed out of range: the first faulty face line, found again.
    mr_status bad_face_error() {
        std::string fault;
        long line = locate_line(path, REC_F, -1, totals, &fault);
        if (fault.empty())
            fault = "a face of fewer than 3 vertices or an index out of range (" + std::to_string(totals[0]) +
                    " v, " + std::to_string(totals[1]) + " vt, " + std::to_string(totals[2]) + " vn records)";
        return format_error(line, fault);
    }

    mr_status nonfinite_error(record kind, long ordinal, const char *name) {
        long line = locate_line(path, kind, ordinal, totals, NULL);
        return format_error(line, std::string(name) + " record " + std::to_string(ordinal + 1) + " is not finite");
    }

    mr_status build(mr_obj_mesh *out) {
        size_t corners = 0;
        for (const tinyobj::shape_t &s : shapes) corners += s.mesh.indices.size();
        size_t triangle_count = corners / 3;
        if (triangle_count == 0)
            return mr_fail(MR_ERR_FORMAT, "OBJ '%s': no faces (%ld v records)", path.c_str(), totals[0]);
        if (triangle_count > max_triangles)
            return mr_fail(MR_ERR_FORMAT, "OBJ '%s': %zu triangles: more than the renderer's %zu", path.c_str(),
                           triangle_count, max_triangles);

        // Every index within its array (tinyobjloader passes relative indices before the first record through).
        bool has_vt = false;
        for (const tinyobj::shape_t &s : shapes) {
            for (const tinyobj::index_t &i : s.mesh.indices) {
                if (i.vertex_index < 0 || i.vertex_index >= totals[0] || i.texcoord_index < -1 ||
                    i.texcoord_index >= totals[1] || i.normal_index < -1 || i.normal_index >= totals[2])
                    return bad_face_error();
                has_vt |= i.texcoord_index >= 0;
            }
            for (unsigned char n : s.mesh.num_face_vertices)
                if (n != 3) return format_error(0, "tinyobjloader left a face of " + std::to_string(n) + " vertices");
        }

        // The corners' (v, vt, vn) made unique: the output vertices, in order of first use.
        std::vector<uint32_t> index(corners);
        std::vector<corner_key> vertices;
        std::unordered_map<corner_key, uint32_t, corner_hash> unique;
        unique.reserve(corners);
        size_t c = 0;
        for (const tinyobj::shape_t &s : shapes)
            for (const tinyobj::index_t &i : s.mesh.indices) {
                corner_key key = {i.vertex_index, i.texcoord_index, opts.ignore_normals ? -1 : i.normal_index};
                auto it = unique.emplace(key, (uint32_t)vertices.size());
                if (it.second) {
                    if (vertices.size() >= max_vertices)
                        return mr_fail(MR_ERR_FORMAT, "OBJ '%s': more than the renderer's %zu vertices", path.c_str(),
                                       max_vertices);
                    vertices.push_back(key);
                }
                index[c++] = it.first->second;
            }
        size_t vertex_count = vertices.size();

        // Positions (double for the geometry below), checked finite.
        const std::vector<tinyobj::real_t> &v = attrib.vertices;
        std::vector<double> pos(vertex_count * 3);
        for (size_t k = 0; k < vertex_count; k++)
            for (int i = 0; i < 3; i++) {
                pos[k * 3 + i] = v[(size_t)vertices[k].v * 3 + i];
                if (!isfinite(pos[k * 3 + i])) return nonfinite_error(REC_V, vertices[k].v, "v");
            }

        // Normals: the file's where usable; turn triangles whose three file normals all face away.
        std::vector<double> normal(vertex_count * 3, 0.0);
        std::vector<unsigned char> given(vertex_count, 0);
        for (size_t k = 0; k < vertex_count; k++) {
            const corner_key &key = vertices[k];
            if (key.vn >= 0 && !unit_normal(attrib.normals, key.vn, &normal[k * 3])) {
                double x[3];
                for (int i = 0; i < 3; i++) x[i] = attrib.normals[(size_t)key.vn * 3 + i];
                if (!isfinite(x[0]) || !isfinite(x[1]) || !isfinite(x[2]))
                    return nonfinite_error(REC_VN, key.vn, "vn");
            }
            given[k] = key.vn >= 0 && dot3(&normal[k * 3], &normal[k * 3]) > 0.0;
        }
        int turned = 0;
        for (size_t f = 0; f < triangle_count; f++) {
            uint32_t *t = &index[f * 3];
            if (!given[t[0]] || !given[t[1]] || !given[t[2]]) continue;
            double e1[3], e2[3], n[3], sum[3];
            sub3(&pos[t[1] * 3], &pos[t[0] * 3], e1);
            sub3(&pos[t[2] * 3], &pos[t[0] * 3], e2);
            cross3(e1, e2, n);
            for (int i = 0; i < 3; i++) sum[i] = normal[t[0] * 3 + i] + normal[t[1] * 3 + i] + normal[t[2] * 3 + i];
            if (dot3(n, sum) < 0.0) {
                uint32_t swap = t[1];
                t[1] = t[2];
                t[2] = swap;
                turned++;
            }
        }
        // Computed normals, per position (v record), for the vertices without a usable file normal.
        int computed = 0;
        for (size_t k = 0; k < vertex_count; k++) computed += !given[k];
        if (computed > 0) {
            std::unordered_map<int, size_t> slot; // v record -> accumulator
            std::vector<double> acc;
            for (size_t k = 0; k < vertex_count; k++)
                if (!given[k] && slot.emplace(vertices[k].v, acc.size()).second) acc.insert(acc.end(), 3, 0.0);
            for (size_t f = 0; f < triangle_count; f++) {
                const uint32_t *t = &index[f * 3];
                const double *p0 = &pos[t[0] * 3], *p1 = &pos[t[1] * 3], *p2 = &pos[t[2] * 3];
                double e1[3], e2[3], n[3];
                sub3(p1, p0, e1);
                sub3(p2, p0, e2);
                cross3(e1, e2, n);
                double len = sqrt(dot3(n, n));
                if (!(len > 0.0)) continue;
                double angle[3] = {mr_mesh_corner_angle(p0, p1, p2), mr_mesh_corner_angle(p1, p2, p0),
                                   mr_mesh_corner_angle(p2, p0, p1)};
                for (int j = 0; j < 3; j++) {
                    auto it = slot.find(vertices[t[j]].v);
                    if (it == slot.end()) continue;
                    for (int i = 0; i < 3; i++) acc[it->second + i] += angle[j] * n[i] / len;
                }
            }
            for (size_t k = 0; k < vertex_count; k++) {
                if (given[k]) continue;
                const double *a = &acc[slot[vertices[k].v]];
                double len = sqrt(dot3(a, a));
                // zero (a position only in degenerate triangles): left (0, 0, 0), which the renderer fills in
                for (int i = 0; i < 3; i++) normal[k * 3 + i] = len > 0.0 ? a[i] / len : 0.0;
            }
        }

        // The mesh's arrays.
        float *positions = (float *)malloc(vertex_count * 3 * sizeof(float));
        float *normals = (float *)malloc(vertex_count * 3 * sizeof(float));
        float *uvs = has_vt ? (float *)malloc(vertex_count * 2 * sizeof(float)) : NULL;
        uint32_t *indices = (uint32_t *)malloc(triangle_count * 3 * sizeof(uint32_t));
        out->mesh.positions = positions;
        out->mesh.normals = normals;
        out->mesh.uvs = uvs;
        out->mesh.indices = indices;
        if (positions == NULL || normals == NULL || (has_vt && uvs == NULL) || indices == NULL)
            return mr_fail(MR_ERR_NOMEM, "OBJ '%s': out of memory for %zu vertices", path.c_str(), vertex_count);
        for (int i = 0; i < 3; i++) out->bbox_min[i] = INFINITY, out->bbox_max[i] = -INFINITY;
        for (size_t k = 0; k < vertex_count; k++) {
            for (int i = 0; i < 3; i++) {
                positions[k * 3 + i] = v[(size_t)vertices[k].v * 3 + i];
                normals[k * 3 + i] = (float)normal[k * 3 + i];
                out->bbox_min[i] = fmin(out->bbox_min[i], positions[k * 3 + i]);
                out->bbox_max[i] = fmax(out->bbox_max[i], positions[k * 3 + i]);
            }
            if (uvs != NULL) {
                int vt = vertices[k].vt;
                double u = vt >= 0 ? attrib.texcoords[(size_t)vt * 2] : 0.0;
                double w = vt >= 0 ? attrib.texcoords[(size_t)vt * 2 + 1] : 0.0;
                if (vt >= 0 && !opts.keep_v) w = 1.0 - w;
                if (!isfinite(u) || !isfinite(w)) return nonfinite_error(REC_VT, vt, "vt");
                uvs[k * 2] = (float)u;
                uvs[k * 2 + 1] = (float)w;
            }
        }
        memcpy(indices, index.data(), triangle_count * 3 * sizeof(uint32_t));
        out->mesh.vertex_count = (int)vertex_count;
        out->mesh.triangle_count = (int)triangle_count;
        out->mesh.double_sided = opts.double_sided != 0;
        out->position_records = (int)totals[0];
        out->texcoord_records = (int)totals[1];
        out->normal_records = (int)totals[2];
        out->shape_count = (int)shapes.size();
        out->computed_normals = computed;
        out->turned_triangles = turned;
        return MR_OK;
    }
};

} // namespace

extern "C" mr_status mr_obj_load(const char *path, const mr_obj_options *opts, mr_obj_mesh **out) {
    if (path == NULL || out == NULL) return mr_fail(MR_ERR_INVALID_ARG, "mr_obj_load: NULL path or output");
    mr_obj_mesh *obj = NULL;
    mr_status status = MR_OK;
    try {
        loader l;
        l.path = path;
        l.opts = opts != NULL ? *opts : mr_obj_options{0, 0, 0};
        status = l.parse();
        if (status == MR_OK) {
            obj = (mr_obj_mesh *)calloc(1, sizeof *obj);
            if (obj == NULL) return mr_fail(MR_ERR_NOMEM, "OBJ '%s': out of memory", path);
            status = l.build(obj);
        }
        if (status == MR_OK) {
            obj->path = dup_string(l.path);
            obj->warnings = dup_string(l.warnings);
        }
    } catch (const std::bad_alloc &) {
        status = mr_fail(MR_ERR_NOMEM, "OBJ '%s': out of memory", path);
    } catch (const std::exception &e) {
        status = mr_fail(MR_ERR_EXTERNAL, "OBJ '%s': %s", path, e.what());
    } catch (...) {
        status = mr_fail(MR_ERR_EXTERNAL, "OBJ '%s': unexpected exception", path);
    }
    if (status != MR_OK) {
        mr_obj_mesh_free(obj);
        return status;
    }
    *out = obj;
    return MR_OK;
}

extern "C" void mr_obj_mesh_free(mr_obj_mesh *obj) {
    if (obj == NULL) return;
    // The mesh's arrays are this struct's: const only as the renderer reads them.
    free((void *)obj->mesh.positions);
    free((void *)obj->mesh.normals);
    free((void *)obj->mesh.uvs);
    free((void *)obj->mesh.indices);
    free(obj->path);
    free(obj->warnings);
    free(obj);
}
