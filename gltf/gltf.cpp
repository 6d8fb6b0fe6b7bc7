// gltf.cpp — the tinygltf shim behind gltf/mr_gltf.h (contract there; coverage and limits in gltf/README.md).
//
// tinygltf 2.7 (Debian's libtinygltf) parses and serialises the JSON; this file keeps images undecoded (its
// image loader callback stores the encoded bytes), maps materials to and from mr_gltf_material, and writes
// the output itself: tinygltf's file writer is neither atomic nor careful about input files, so the shim
// serialises to memory, fixes up the buffers[] and images[] entries, and writes every file through the
// project's atomic-file protocol. No exception crosses the C boundary.
#include "gltf/mr_gltf.h"

#include <errno.h>
#include <limits.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <tiny_gltf.h>

#include "io/io_internal.h"
#include "mr_internal.h"

using tinygltf::Value;
typedef Value::Object Object;

struct mr_gltf {
    tinygltf::Model model;
    std::string path;                     // the file read
    std::string base_dir;                 // its directory ("." if none)
    std::vector<std::string> image_paths; // per image: resolved source file ("" for embedded images)
    std::vector<std::string> buffer_paths; // per buffer: resolved source file ("" for embedded buffers)
    nlohmann::json original;               // the file's JSON, for what tinygltf does not keep (merge_original)
};

namespace {

const char *const EXT_SPEC_GLOSS = "KHR_materials_pbrSpecularGlossiness";
const char *const EXT_SPECULAR = "KHR_materials_specular";
const char *const EXT_IOR = "KHR_materials_ior";
const char *const EXT_TRANSFORM = "KHR_texture_transform";

// ---- small helpers ------------------------------------------------------------------------------------

std::string first_line(const std::string &s) {
    std::string t = s;
    while (!t.empty() && (t.back() == '\n' || t.back() == '\r')) t.pop_back();
    for (char &c : t) {
        if (c == '\n') c = ';';
    }
    return t;
}

std::string dir_of(const std::string &path) {
    size_t slash = path.find_last_of('/');
    if (slash == std::string::npos) return ".";
    if (slash == 0) return "/";
    return path.substr(0, slash);
}

std::string join_path(const std::string &dir, const std::string &rel) {
    if (dir.empty() || dir == ".") return rel;
    if (dir.back() == '/') return dir + rel;
    return dir + "/" + rel;
}

bool is_data_uri(const std::string &uri) { return uri.compare(0, 5, "data:") == 0; }

std::string url_decode(const std::string &s) {
    std::string out;
    for (size_t i = 0; i < s.size(); i++) {
        if (s[i] == '%' && i + 2 < s.size() && isxdigit((unsigned char)s[i + 1]) &&
            isxdigit((unsigned char)s[i + 2])) {
            out += (char)strtol(s.substr(i + 1, 2).c_str(), NULL, 16);
            i += 2;
        } else {
            out += s[i];
        }
    }
    return out;
}

// A relative URI that stays inside the output directory: not absolute, no scheme, no ".." segment.
bool is_safe_relative(const std::string &decoded) {
    if (decoded.empty() || decoded[0] == '/' || decoded.find("://") != std::string::npos) return false;
    std::stringstream ss(decoded);
    std::string seg;
    while (std::getline(ss, seg, '/')) {
        if (seg == "..") return false;
    }
    return decoded.back() != '/';
}

std::string real_path(const std::string &path) {
    char buf[PATH_MAX];
    if (realpath(path.c_str(), buf) == NULL) return "";
    return buf;
}

std::string base64_encode(const unsigned char *p, size_t n) {
    static const char table[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    out.reserve((n + 2) / 3 * 4);
    for (size_t i = 0; i < n; i += 3) {
        unsigned v = (unsigned)p[i] << 16;
        if (i + 1 < n) v |= (unsigned)p[i + 1] << 8;
        if (i + 2 < n) v |= p[i + 2];
        out += table[(v >> 18) & 63];
        out += table[(v >> 12) & 63];
        out += i + 1 < n ? table[(v >> 6) & 63] : '=';
        out += i + 2 < n ? table[v & 63] : '=';
    }
    return out;
}

std::string sniff_mime(const std::vector<unsigned char> &b) {
    if (b.size() >= 8 && b[0] == 0x89 && b[1] == 'P' && b[2] == 'N' && b[3] == 'G') return "image/png";
    if (b.size() >= 3 && b[0] == 0xFF && b[1] == 0xD8 && b[2] == 0xFF) return "image/jpeg";
    if (b.size() >= 4 && b[0] == 0x76 && b[1] == 0x2f && b[2] == 0x31 && b[3] == 0x01) return "image/x-exr";
    if (b.size() >= 12 && memcmp(b.data(), "RIFF", 4) == 0 && memcmp(b.data() + 8, "WEBP", 4) == 0)
        return "image/webp";
    if (b.size() >= 4 && b[0] == 0xAB && b[1] == 'K' && b[2] == 'T' && b[3] == 'X') return "image/ktx2";
    return "";
}

mr_status read_file(const std::string &path, std::vector<unsigned char> *out, const char *what) {
    FILE *f = fopen(path.c_str(), "rb");
    if (f == NULL) return mr_fail(MR_ERR_IO, "%s '%s': cannot open: %s", what, path.c_str(), strerror(errno));
    std::vector<unsigned char> bytes;
    unsigned char chunk[65536];
    size_t n;
    while ((n = fread(chunk, 1, sizeof chunk, f)) > 0) bytes.insert(bytes.end(), chunk, chunk + n);
    int failed = ferror(f);
    fclose(f);
    if (failed) return mr_fail(MR_ERR_IO, "%s '%s': read error", what, path.c_str());
    out->swap(bytes);
    return MR_OK;
}

// tinygltf's image callback: keep the encoded bytes, decode nothing.
bool keep_image_bytes(tinygltf::Image *image, const int, std::string *, std::string *, int, int,
                      const unsigned char *bytes, int size, void *) {
    image->image.assign(bytes, bytes + size);
    image->as_is = true;
    image->width = image->height = image->component = image->bits = -1;
    if (image->mimeType.empty()) image->mimeType = sniff_mime(image->image);
    return true;
}

// tinygltf's image writer callback: write nothing (the shim writes images itself).
bool skip_image_write(const std::string *, const std::string *, const tinygltf::Image *, bool, std::string *,
                      void *) {
    return false;
}

// ---- values ------------------------------------------------------------------------------------------

double get_num(const Object &o, const char *key, double def) {
    auto it = o.find(key);
    if (it == o.end() || !it->second.IsNumber()) return def;
    return it->second.GetNumberAsDouble();
}

void get_nums(const Object &o, const char *key, double *out, int n, const double *def) {
    for (int i = 0; i < n; i++) out[i] = def[i];
    auto it = o.find(key);
    if (it == o.end() || !it->second.IsArray() || (int)it->second.ArrayLen() != n) return;
    for (int i = 0; i < n; i++) {
        const Value &v = it->second.Get(i);
        if (v.IsNumber()) out[i] = v.GetNumberAsDouble();
    }
}

// Writes key only when the value differs from what the object means now (explicit values stay explicit).
void set_num(Object &o, const char *key, double value, double def) {
    if (get_num(o, key, def) == value && (o.count(key) || value == def)) return;
    o[key] = Value(value);
}

void set_nums(Object &o, const char *key, const double *value, int n, const double *def) {
    double now[4];
    get_nums(o, key, now, n, def);
    bool same = true, is_def = true;
    for (int i = 0; i < n; i++) {
        same = same && now[i] == value[i];
        is_def = is_def && value[i] == def[i];
    }
    if (same && (o.count(key) || is_def)) return;
    Value::Array a;
    for (int i = 0; i < n; i++) a.push_back(Value(value[i]));
    o[key] = Value(std::move(a));
}

Object *as_object(Value &v) {
    if (!v.IsObject()) v = Value(Object());
    return &v.Get<Object>();
}

const double ZERO2[2] = {0, 0}, ONE2[2] = {1, 1}, ONE3[3] = {1, 1, 1}, ONE4[4] = {1, 1, 1, 1};
const double ZERO3[3] = {0, 0, 0};

void read_transform(const tinygltf::ExtensionMap &exts, mr_gltf_texture_ref *r) {
    auto it = exts.find(EXT_TRANSFORM);
    if (it == exts.end() || !it->second.IsObject()) return;
    const Object &t = it->second.Get<Object>();
    r->has_transform = 1;
    get_nums(t, "offset", r->offset, 2, ZERO2);
    r->rotation = get_num(t, "rotation", 0.0);
    get_nums(t, "scale", r->scale, 2, ONE2);
    r->transform_tex_coord = (int)get_num(t, "texCoord", -1.0);
}

void write_transform(tinygltf::ExtensionMap &exts, const mr_gltf_texture_ref *r) {
    if (!r->has_transform) {
        exts.erase(EXT_TRANSFORM);
        return;
    }
    Object *t = as_object(exts[EXT_TRANSFORM]);
    set_nums(*t, "offset", r->offset, 2, ZERO2);
    set_num(*t, "rotation", r->rotation, 0.0);
    set_nums(*t, "scale", r->scale, 2, ONE2);
    if (r->transform_tex_coord >= 0) {
        (*t)["texCoord"] = Value(r->transform_tex_coord);
    } else {
        t->erase("texCoord");
    }
}

template <typename Info> void read_core_tex(const Info &info, mr_gltf_texture_ref *r) {
    mr_gltf_texture_ref_none(r);
    if (info.index < 0) return;
    r->index = info.index;
    r->tex_coord = info.texCoord;
    read_transform(info.extensions, r);
}

template <typename Info> void write_core_tex(Info &info, const mr_gltf_texture_ref *r) {
    if (r->index < 0) {
        info = Info();
        return;
    }
    info.index = r->index;
    info.texCoord = r->tex_coord;
    write_transform(info.extensions, r);
}

// A textureInfo stored as a JSON object inside an extension.
void read_value_tex(const Object &ext, const char *key, mr_gltf_texture_ref *r) {
    mr_gltf_texture_ref_none(r);
    auto it = ext.find(key);
    if (it == ext.end() || !it->second.IsObject()) return;
    const Object &t = it->second.Get<Object>();
    r->index = (int)get_num(t, "index", -1.0);
    r->tex_coord = (int)get_num(t, "texCoord", 0.0);
    auto e = t.find("extensions");
    if (e != t.end() && e->second.IsObject()) read_transform(e->second.Get<Object>(), r);
}

void write_value_tex(Object &ext, const char *key, const mr_gltf_texture_ref *r) {
    if (r->index < 0) {
        ext.erase(key);
        return;
    }
    Object *t = as_object(ext[key]);
    (*t)["index"] = Value(r->index);
    if (r->tex_coord != 0 || t->count("texCoord")) (*t)["texCoord"] = Value(r->tex_coord);
    Object *exts = as_object((*t)["extensions"]);
    write_transform(*exts, r);
    if (exts->empty()) t->erase("extensions");
}

mr_status check_tex(const mr_gltf *g, const mr_gltf_texture_ref *r, const char *what) {
    if (r->index < -1 || r->index >= (int)g->model.textures.size())
        return mr_fail(MR_ERR_INVALID_ARG, "glTF '%s': %s texture %d does not exist (the asset has %zu)",
                       g->path.c_str(), what, r->index, g->model.textures.size());
    if (r->index >= 0 && r->tex_coord < 0)
        return mr_fail(MR_ERR_INVALID_ARG, "glTF '%s': %s texCoord %d is negative", g->path.c_str(), what,
                       r->tex_coord);
    return MR_OK;
}

// Whether a Value tree holds an "extensions" object with key `name` (texture transforms inside extensions).
bool value_uses(const Value &v, const char *name) {
    if (v.IsObject()) {
        const Object &o = v.Get<Object>();
        for (const auto &kv : o) {
            if (kv.first == "extensions" && kv.second.IsObject() && kv.second.Get<Object>().count(name)) return true;
            if (value_uses(kv.second, name)) return true;
        }
    } else if (v.IsArray()) {
        for (size_t i = 0; i < v.ArrayLen(); i++) {
            if (value_uses(v.Get((int)i), name)) return true;
        }
    }
    return false;
}

bool material_uses(const tinygltf::Material &m, const char *name) {
    if (m.extensions.count(name)) return true;
    const tinygltf::ExtensionMap *maps[] = {&m.pbrMetallicRoughness.baseColorTexture.extensions,
                                            &m.pbrMetallicRoughness.metallicRoughnessTexture.extensions,
                                            &m.normalTexture.extensions, &m.occlusionTexture.extensions,
                                            &m.emissiveTexture.extensions};
    for (const auto *map : maps) {
        if (map->count(name)) return true;
    }
    for (const auto &kv : m.extensions) {
        if (value_uses(kv.second, name)) return true;
    }
    return false;
}

bool list_has(const std::vector<std::string> &list, const char *name) {
    return std::find(list.begin(), list.end(), name) != list.end();
}

nlohmann::json to_json(const Value &v) {
    switch (v.Type()) {
    case tinygltf::BOOL_TYPE: return v.Get<bool>();
    case tinygltf::INT_TYPE: return v.Get<int>();
    case tinygltf::REAL_TYPE: return v.Get<double>();
    case tinygltf::STRING_TYPE: return v.Get<std::string>();
    case tinygltf::ARRAY_TYPE: {
        nlohmann::json a = nlohmann::json::array();
        for (size_t i = 0; i < v.ArrayLen(); i++) a.push_back(to_json(v.Get((int)i)));
        return a;
    }
    case tinygltf::OBJECT_TYPE: {
        nlohmann::json o = nlohmann::json::object();
        for (const auto &kv : v.Get<Object>()) o[kv.first] = to_json(kv.second);
        return o;
    }
    default: return nullptr;
    }
}

// Adds to `out` every key of `orig` it lacks, recursively (arrays element by element when their lengths
// agree). Never overwrites a value.
void merge_missing(nlohmann::json &out, const nlohmann::json &orig) {
    if (out.is_object() && orig.is_object()) {
        for (auto it = orig.begin(); it != orig.end(); ++it) {
            if (!out.contains(it.key())) out[it.key()] = it.value();
            else merge_missing(out[it.key()], it.value());
        }
    } else if (out.is_array() && orig.is_array() && out.size() == orig.size()) {
        for (size_t i = 0; i < out.size(); i++) merge_missing(out[i], orig[i]);
    }
}

// The keys of the material schema (the model holds them; the file's own are stale once a material is set).
bool is_material_key(const std::string &key) {
    static const std::set<std::string> keys = {
        "name", "extensions", "extras", "pbrMetallicRoughness", "normalTexture", "occlusionTexture",
        "emissiveTexture", "emissiveFactor", "alphaMode", "alphaCutoff", "doubleSided"};
    return keys.count(key) > 0;
}

// What tinygltf 2.7 parses but does not write back (asset.minVersion, skins' extras, properties outside the
// schema such as unknown top-level keys) and the default values its writer drops, taken from the file's own
// JSON. Only keys the output lacks are added, so nothing the model holds is overridden. Sections this API
// edits are limited: a material gets back only keys outside the material schema (a removed extension, texture
// or default-valued factor must stay removed), buffers and images never get their uri/bufferView/mimeType
// back (the writer decides those), and extensionsUsed/Required are left to mr_gltf_sync_extensions.
void merge_original(nlohmann::json &doc, const nlohmann::json &orig) {
    if (!orig.is_object()) return;
    for (auto it = orig.begin(); it != orig.end(); ++it) {
        const std::string &key = it.key();
        const nlohmann::json &value = it.value();
        if (key == "extensionsUsed" || key == "extensionsRequired") continue;
        if (!doc.contains(key)) {
            if (key != "materials" && key != "buffers" && key != "images") doc[key] = value;
            continue;
        }
        nlohmann::json &out = doc[key];
        if (key == "materials" || key == "buffers" || key == "images") {
            if (!out.is_array() || !value.is_array()) continue;
            for (size_t i = 0; i < out.size() && i < value.size(); i++) {
                if (!out[i].is_object() || !value[i].is_object()) continue;
                for (auto f = value[i].begin(); f != value[i].end(); ++f) {
                    bool managed = key == "materials" ? is_material_key(f.key())
                                                      : f.key() == "uri" || f.key() == "bufferView" ||
                                                            f.key() == "mimeType" || f.key() == "byteLength";
                    if (managed) continue;
                    if (!out[i].contains(f.key())) out[i][f.key()] = f.value();
                    else merge_missing(out[i][f.key()], f.value());
                }
            }
            continue;
        }
        merge_missing(out, value);
    }
}

// A self-contained .glb: every buffer concatenated (4-byte aligned) into the binary chunk, the buffer views
// moved accordingly, and every image that is not in a buffer view yet appended to it with a view of its own.
// Only the first buffer's name and extras survive (there is one buffer left).
void pack_glb(const tinygltf::Model &m, nlohmann::json &doc, std::vector<unsigned char> *blob) {
    auto align = [blob]() {
        while (blob->size() % 4) blob->push_back(0);
    };
    std::vector<size_t> offsets;
    for (const tinygltf::Buffer &b : m.buffers) {
        align();
        offsets.push_back(blob->size());
        blob->insert(blob->end(), b.data.begin(), b.data.end());
    }
    if (doc.contains("bufferViews")) {
        for (auto &v : doc["bufferViews"]) {
            size_t buffer = v.value("buffer", (size_t)0);
            size_t offset = v.value("byteOffset", (size_t)0) + (buffer < offsets.size() ? offsets[buffer] : 0);
            v["buffer"] = 0;
            if (offset > 0) v["byteOffset"] = offset;
        }
    }
    for (size_t i = 0; i < m.images.size(); i++) {
        const tinygltf::Image &im = m.images[i];
        nlohmann::json &o = doc["images"][i];
        o.erase("uri");
        int view = im.bufferView;
        if (view < 0) {
            align();
            nlohmann::json v = {{"buffer", 0}, {"byteLength", im.image.size()}};
            if (!blob->empty()) v["byteOffset"] = blob->size();
            blob->insert(blob->end(), im.image.begin(), im.image.end());
            doc["bufferViews"].push_back(v);
            view = (int)doc["bufferViews"].size() - 1;
        }
        o["bufferView"] = view;
        o["mimeType"] = im.mimeType.empty() ? sniff_mime(im.image) : im.mimeType;
    }
    if (blob->empty()) {
        doc.erase("buffers");
        return;
    }
    nlohmann::json first = doc.contains("buffers") && !doc["buffers"].empty() ? doc["buffers"][0]
                                                                              : nlohmann::json::object();
    first.erase("uri");
    first["byteLength"] = blob->size();
    doc["buffers"] = nlohmann::json::array({first});
}

// ---- saving --------------------------------------------------------------------------------------------

struct pending_file {
    std::string rel;                 // relative path under the output directory (decoded)
    const std::vector<unsigned char> *bytes;
    std::string source;              // real path of the file these bytes came from, "" if none
    std::string target;              // full path
    bool skip = false;               // the target is this resource's own unchanged source
};

std::string with_suffix(const std::string &rel, int n) {
    size_t slash = rel.find_last_of('/');
    size_t dot = rel.find_last_of('.');
    if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) dot = rel.size();
    return rel.substr(0, dot) + "_" + std::to_string(n) + rel.substr(dot);
}

std::string uri_encode_spaces(const std::string &rel) {
    std::string out;
    for (char c : rel) {
        if (c == ' ') out += "%20";
        else if (c == '%') out += "%25";
        else out += c;
    }
    return out;
}

mr_status make_dirs(const std::string &dir, std::vector<std::string> *created) {
    if (dir.empty() || dir == "." || dir == "/") return MR_OK;
    struct stat st;
    if (stat(dir.c_str(), &st) == 0) {
        if (S_ISDIR(st.st_mode)) return MR_OK;
        return mr_fail(MR_ERR_IO, "output directory '%s': exists and is not a directory", dir.c_str());
    }
    mr_status s = make_dirs(dir_of(dir), created);
    if (s != MR_OK) return s;
    if (mkdir(dir.c_str(), 0777) != 0 && errno != EEXIST)
        return mr_fail(MR_ERR_IO, "output directory '%s': cannot create: %s", dir.c_str(), strerror(errno));
    created->push_back(dir);
    return MR_OK;
}

std::vector<unsigned char> make_glb(const std::string &json, const std::vector<unsigned char> *bin) {
    std::string j = json;
    while (j.size() % 4) j += ' ';
    size_t bin_len = bin ? (bin->size() + 3) / 4 * 4 : 0;
    size_t total = 12 + 8 + j.size() + (bin ? 8 + bin_len : 0);
    std::vector<unsigned char> out;
    out.reserve(total);
    auto u32 = [&out](uint32_t v) {
        for (int i = 0; i < 4; i++) out.push_back((unsigned char)(v >> (8 * i)));
    };
    out.insert(out.end(), {'g', 'l', 'T', 'F'});
    u32(2);
    u32((uint32_t)total);
    u32((uint32_t)j.size());
    out.insert(out.end(), {'J', 'S', 'O', 'N'});
    out.insert(out.end(), j.begin(), j.end());
    if (bin) {
        u32((uint32_t)bin_len);
        out.insert(out.end(), {'B', 'I', 'N', '\0'});
        out.insert(out.end(), bin->begin(), bin->end());
        out.resize(out.size() + (bin_len - bin->size()), 0);
    }
    return out;
}

bool ends_with(const std::string &s, const char *suffix) {
    size_t n = strlen(suffix);
    if (s.size() < n) return false;
    return strcasecmp(s.c_str() + s.size() - n, suffix) == 0;
}

mr_status save_impl(mr_gltf *g, const char *path_c) {
    const std::string out_path = path_c;
    bool binary;
    if (ends_with(out_path, ".glb")) binary = true;
    else if (ends_with(out_path, ".gltf")) binary = false;
    else
        return mr_fail(MR_ERR_INVALID_ARG, "glTF output '%s': unknown extension (expected .gltf or .glb)",
                       out_path.c_str());
    const std::string out_dir = dir_of(out_path);
    struct stat dir_st;
    if (stat(out_dir.c_str(), &dir_st) != 0 || !S_ISDIR(dir_st.st_mode))
        return mr_fail(MR_ERR_IO, "glTF output '%s': directory '%s' does not exist", out_path.c_str(),
                       out_dir.c_str());

    // Input files the output must never replace.
    std::set<std::string> inputs;
    inputs.insert(real_path(g->path));
    for (const auto &p : g->buffer_paths) {
        if (!p.empty()) inputs.insert(real_path(p));
    }
    for (const auto &p : g->image_paths) {
        if (!p.empty()) inputs.insert(real_path(p));
    }
    inputs.erase("");
    std::string out_real = real_path(out_path);
    if (!out_real.empty() && inputs.count(out_real))
        return mr_fail(MR_ERR_INVALID_ARG, "glTF output '%s': is a file the asset was read from ('%s')",
                       out_path.c_str(), g->path.c_str());

    mr_gltf_sync_extensions(g);
    tinygltf::Model &m = g->model;

    // Serialise everything but buffers[] and images[] with tinygltf, then set those two ourselves.
    tinygltf::TinyGLTF writer;
    writer.SetImageWriter(skip_image_write, NULL);
    std::ostringstream ss;
    if (!writer.WriteGltfSceneToStream(&m, ss, false, false))
        return mr_fail(MR_ERR_EXTERNAL, "glTF output '%s': tinygltf could not serialise the asset", out_path.c_str());
    nlohmann::json doc = nlohmann::json::parse(ss.str());

    // What tinygltf 2.7's writer leaves out: a sampler's name and extensions.
    for (size_t i = 0; i < m.samplers.size(); i++) {
        const tinygltf::Sampler &smp = m.samplers[i];
        if (!smp.name.empty()) doc["samplers"][i]["name"] = smp.name;
        if (!smp.extensions.empty()) {
            nlohmann::json exts = nlohmann::json::object();
            for (const auto &kv : smp.extensions) {
                nlohmann::json e = to_json(kv.second);
                exts[kv.first] = e.is_null() ? nlohmann::json::object() : e;
            }
            doc["samplers"][i]["extensions"] = exts;
        }
    }

    merge_original(doc, g->original);

    std::string stem = out_path.substr(out_path.find_last_of('/') == std::string::npos
                                           ? 0 : out_path.find_last_of('/') + 1);
    stem = stem.substr(0, stem.find_last_of('.'));
    std::vector<pending_file> files;
    std::vector<std::pair<nlohmann::json *, size_t>> uri_slots; // JSON object, index into files
    const std::vector<unsigned char> *glb_bin = NULL;
    // A .glb holds everything, unless an extension points into buffers by index (meshopt compression).
    std::vector<unsigned char> packed;
    bool pack = binary && !list_has(m.extensionsUsed, "EXT_meshopt_compression");
    if (pack) {
        pack_glb(m, doc, &packed);
        if (!packed.empty()) glb_bin = &packed;
    }

    for (size_t i = 0; i < m.buffers.size() && !pack; i++) {
        nlohmann::json &b = doc["buffers"][i];
        const tinygltf::Buffer &buf = m.buffers[i];
        b["byteLength"] = buf.data.size();
        if (binary && i == 0 && buf.uri.empty()) {
            b.erase("uri");
            glb_bin = &buf.data;
            continue;
        }
        if (is_data_uri(buf.uri)) continue; // tinygltf wrote it as a data URI again
        pending_file f;
        f.bytes = &buf.data;
        std::string decoded = url_decode(buf.uri);
        if (!buf.uri.empty() && is_safe_relative(decoded)) {
            f.rel = decoded;
            f.source = real_path(g->buffer_paths[i]);
        } else {
            f.rel = stem + (i == 0 ? "" : "_" + std::to_string(i)) + ".bin";
            f.source = buf.uri.empty() ? "" : real_path(g->buffer_paths[i]);
        }
        uri_slots.push_back({&b, files.size()});
        files.push_back(f);
    }
    for (size_t i = 0; i < m.images.size() && !pack; i++) {
        nlohmann::json &o = doc["images"][i];
        const tinygltf::Image &im = m.images[i];
        o.erase("uri");
        o.erase("bufferView");
        o.erase("mimeType");
        if (im.bufferView >= 0) {
            o["bufferView"] = im.bufferView;
            o["mimeType"] = im.mimeType.empty() ? sniff_mime(im.image) : im.mimeType;
            continue;
        }
        if (im.uri.empty()) { // a data URI when read
            std::string mime = im.mimeType.empty() ? "application/octet-stream" : im.mimeType;
            o["uri"] = "data:" + mime + ";base64," + base64_encode(im.image.data(), im.image.size());
            continue;
        }
        if (im.image.empty())
            return mr_fail(MR_ERR_IO, "glTF output '%s': image %zu ('%s') has no data to write", out_path.c_str(),
                           i, im.uri.c_str());
        pending_file f;
        f.bytes = &im.image;
        std::string decoded = url_decode(im.uri);
        f.rel = is_safe_relative(decoded) ? decoded : "image_" + std::to_string(i) + "." +
                                                          (im.mimeType == "image/jpeg" ? "jpg" : "png");
        f.source = real_path(g->image_paths[i]);
        uri_slots.push_back({&o, files.size()});
        files.push_back(f);
    }

    // Targets: an unchanged resource landing on its own source stays; one landing on another input file, on
    // the output itself or on another resource's target gets a fresh name.
    std::set<std::string> taken;
    taken.insert(out_real.empty() ? out_path : out_real);
    for (pending_file &f : files) {
        for (int n = 0;; n++) {
            std::string rel = n == 0 ? f.rel : with_suffix(f.rel, n);
            std::string target = join_path(out_dir, rel);
            std::string real = real_path(target);
            std::string key = real.empty() ? target : real;
            bool duplicate = false;
            for (const pending_file &p : files) {
                if (&p == &f) break;
                if (p.target == target) duplicate = true;
            }
            if (duplicate) {
                // Same bytes already written under this name (two references to one file): share it.
                for (const pending_file &p : files) {
                    if (&p == &f) break;
                    if (p.target == target && *p.bytes == *f.bytes) {
                        f.rel = rel;
                        f.target = target;
                        f.skip = true;
                    }
                }
                if (f.skip) break;
                continue;
            }
            if (!real.empty() && inputs.count(real)) {
                if (real == f.source) {
                    f.rel = rel;
                    f.target = target;
                    f.skip = true;
                    break;
                }
                continue;
            }
            if (taken.count(key)) continue;
            taken.insert(key);
            f.rel = rel;
            f.target = target;
            break;
        }
    }
    for (auto &slot : uri_slots) (*slot.first)["uri"] = uri_encode_spaces(files[slot.second].rel);

    std::string json_text = binary ? doc.dump() : doc.dump(2) + "\n";
    std::vector<unsigned char> main_bytes;
    if (binary) main_bytes = make_glb(json_text, glb_bin);
    else main_bytes.assign(json_text.begin(), json_text.end());

    // Write the resources, then the main file; on failure remove what this call created.
    std::vector<std::string> created_files, created_dirs;
    mr_status status = MR_OK;
    for (const pending_file &f : files) {
        if (f.skip) continue;
        status = make_dirs(dir_of(f.target), &created_dirs);
        if (status != MR_OK) break;
        struct stat st;
        bool existed = stat(f.target.c_str(), &st) == 0;
        status = mr_atomic_write_bytes(f.target.c_str(), f.bytes->data(), f.bytes->size());
        if (status != MR_OK) break;
        if (!existed) created_files.push_back(f.target);
    }
    if (status == MR_OK) status = mr_atomic_write_bytes(out_path.c_str(), main_bytes.data(), main_bytes.size());
    if (status != MR_OK) {
        for (const auto &f : created_files) unlink(f.c_str());
        for (auto it = created_dirs.rbegin(); it != created_dirs.rend(); ++it) rmdir(it->c_str());
        return mr_fail_context(status, "glTF output '%s'", out_path.c_str());
    }
    return MR_OK;
}

mr_status load_impl(const char *path_c, mr_gltf **out) {
    const std::string path = path_c;
    struct stat st;
    if (stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode))
        return mr_fail(MR_ERR_IO, "glTF '%s': is a directory", path.c_str());
    std::vector<unsigned char> bytes;
    mr_status s = read_file(path, &bytes, "glTF");
    if (s != MR_OK) return s;

    mr_gltf *g = new mr_gltf();
    g->path = path;
    g->base_dir = dir_of(path);
    tinygltf::TinyGLTF loader;
    loader.SetImageLoader(keep_image_bytes, NULL);
    std::string err, warn;
    bool ok;
    bool is_glb = bytes.size() >= 4 && memcmp(bytes.data(), "glTF", 4) == 0;
    if (is_glb) {
        ok = loader.LoadBinaryFromMemory(&g->model, &err, &warn, bytes.data(), (unsigned)bytes.size(),
                                         g->base_dir);
    } else {
        ok = loader.LoadASCIIFromString(&g->model, &err, &warn, (const char *)bytes.data(),
                                        (unsigned)bytes.size(), g->base_dir);
    }
    if (!ok) {
        mr_status code = err.find("not found") != std::string::npos || err.find("Failed to load") != std::string::npos
                             ? MR_ERR_IO : MR_ERR_FORMAT;
        std::string why = first_line(err.empty() ? warn : err);
        if (why.empty()) why = is_glb ? "not a valid binary glTF" : "not a valid glTF";
        if (code == MR_ERR_IO) why += " (resources are looked up relative to '" + g->base_dir + "')";
        else if (is_glb) why += " (" + std::to_string(bytes.size()) + " bytes read; truncated?)";
        delete g;
        return mr_fail(code, "glTF '%s': %s", path.c_str(), why.c_str());
    }
    // tinygltf 2.7 fills in bufferView.target from the meshes' use of each view; keep the file's own (absent
    // stays absent), so a round trip does not add fields.
    {
        std::string json_text;
        if (is_glb && bytes.size() >= 20) {
            uint32_t len = (uint32_t)bytes[12] | (uint32_t)bytes[13] << 8 | (uint32_t)bytes[14] << 16 |
                           (uint32_t)bytes[15] << 24;
            if (len <= bytes.size() - 20) json_text.assign((const char *)bytes.data() + 20, len);
        } else {
            json_text.assign((const char *)bytes.data(), bytes.size());
        }
        nlohmann::json doc = nlohmann::json::parse(json_text, nullptr, false);
        if (!doc.is_discarded() && doc.is_object() && doc.contains("bufferViews") && doc["bufferViews"].is_array()) {
            const nlohmann::json &views = doc["bufferViews"];
            for (size_t i = 0; i < views.size() && i < g->model.bufferViews.size(); i++) {
                if (views[i].is_object() && !views[i].contains("target")) g->model.bufferViews[i].target = 0;
            }
        }
        if (!doc.is_discarded() && doc.is_object()) {
            // Base64 payloads are not needed again: the buffers and images are written from the model.
            for (const char *key : {"buffers", "images"}) {
                if (!doc.contains(key) || !doc[key].is_array()) continue;
                for (auto &item : doc[key]) {
                    if (item.is_object()) item.erase("uri");
                }
            }
            g->original = std::move(doc);
        }
    }
    for (size_t i = 0; i < g->model.buffers.size(); i++) {
        const std::string &uri = g->model.buffers[i].uri;
        g->buffer_paths.push_back(uri.empty() || is_data_uri(uri) ? "" : join_path(g->base_dir, url_decode(uri)));
    }
    for (size_t i = 0; i < g->model.images.size(); i++) {
        const tinygltf::Image &im = g->model.images[i];
        bool external = im.bufferView < 0 && !im.uri.empty();
        std::string p = external ? join_path(g->base_dir, url_decode(im.uri)) : "";
        if (external && im.image.empty()) {
            std::vector<unsigned char> probe;
            mr_status rs = read_file(p, &probe, "glTF image");
            delete g;
            if (rs != MR_OK) return mr_fail_context(rs, "glTF '%s': image %zu", path.c_str(), i);
            return mr_fail(MR_ERR_FORMAT, "glTF '%s': image %zu ('%s') is empty", path.c_str(), i, p.c_str());
        }
        g->image_paths.push_back(p);
    }
    *out = g;
    return MR_OK;
}

mr_status check_material(const mr_gltf *g, int material) {
    if (g == NULL) return mr_fail(MR_ERR_INVALID_ARG, "glTF: NULL asset");
    if (material < 0 || material >= (int)g->model.materials.size())
        return mr_fail(MR_ERR_INVALID_ARG, "glTF '%s': material %d does not exist (the asset has %zu)",
                       g->path.c_str(), material, g->model.materials.size());
    return MR_OK;
}

void get_material_impl(const mr_gltf *g, int index, mr_gltf_material *out) {
    const tinygltf::Material &m = g->model.materials[index];
    mr_gltf_material r;
    mr_gltf_material_defaults(&r);
    r.name = m.name.c_str();
    const tinygltf::PbrMetallicRoughness &pbr = m.pbrMetallicRoughness;
    for (int i = 0; i < 4 && i < (int)pbr.baseColorFactor.size(); i++) r.base_color_factor[i] = pbr.baseColorFactor[i];
    r.metallic_factor = pbr.metallicFactor;
    r.roughness_factor = pbr.roughnessFactor;
    read_core_tex(pbr.baseColorTexture, &r.base_color_texture);
    read_core_tex(pbr.metallicRoughnessTexture, &r.metallic_roughness_texture);
    read_core_tex(m.normalTexture, &r.normal_texture);
    if (r.normal_texture.index >= 0) r.normal_texture.value = m.normalTexture.scale;
    read_core_tex(m.occlusionTexture, &r.occlusion_texture);
    if (r.occlusion_texture.index >= 0) r.occlusion_texture.value = m.occlusionTexture.strength;
    read_core_tex(m.emissiveTexture, &r.emissive_texture);
    for (int i = 0; i < 3 && i < (int)m.emissiveFactor.size(); i++) r.emissive_factor[i] = m.emissiveFactor[i];
    r.alpha_mode = m.alphaMode == "MASK" ? MR_GLTF_ALPHA_MASK
                   : m.alphaMode == "BLEND" ? MR_GLTF_ALPHA_BLEND : MR_GLTF_ALPHA_OPAQUE;
    r.alpha_cutoff = m.alphaCutoff;
    r.double_sided = m.doubleSided ? 1 : 0;

    auto sg = m.extensions.find(EXT_SPEC_GLOSS);
    if (sg != m.extensions.end()) {
        static const Object empty;
        const Object &o = sg->second.IsObject() ? sg->second.Get<Object>() : empty;
        r.has_spec_gloss = 1;
        get_nums(o, "diffuseFactor", r.diffuse_factor, 4, ONE4);
        get_nums(o, "specularFactor", r.specular_factor, 3, ONE3);
        r.glossiness_factor = get_num(o, "glossinessFactor", 1.0);
        read_value_tex(o, "diffuseTexture", &r.diffuse_texture);
        read_value_tex(o, "specularGlossinessTexture", &r.specular_glossiness_texture);
    }
    auto sp = m.extensions.find(EXT_SPECULAR);
    if (sp != m.extensions.end()) {
        static const Object empty;
        const Object &o = sp->second.IsObject() ? sp->second.Get<Object>() : empty;
        r.has_specular = 1;
        r.specular_strength = get_num(o, "specularFactor", 1.0);
        get_nums(o, "specularColorFactor", r.specular_color_factor, 3, ONE3);
        read_value_tex(o, "specularTexture", &r.specular_texture);
        read_value_tex(o, "specularColorTexture", &r.specular_color_texture);
    }
    auto io = m.extensions.find(EXT_IOR);
    if (io != m.extensions.end()) {
        static const Object empty;
        r.has_ior = 1;
        r.ior = get_num(io->second.IsObject() ? io->second.Get<Object>() : empty, "ior", 1.5);
    }
    *out = r;
}

mr_status set_material_impl(mr_gltf *g, int index, const mr_gltf_material *in) {
    const mr_gltf_texture_ref *refs[] = {&in->base_color_texture, &in->metallic_roughness_texture,
                                         &in->normal_texture, &in->occlusion_texture, &in->emissive_texture,
                                         &in->diffuse_texture, &in->specular_glossiness_texture,
                                         &in->specular_texture, &in->specular_color_texture};
    const char *names[] = {"baseColorTexture", "metallicRoughnessTexture", "normalTexture", "occlusionTexture",
                           "emissiveTexture", "diffuseTexture", "specularGlossinessTexture", "specularTexture",
                           "specularColorTexture"};
    for (int i = 0; i < 9; i++) {
        mr_status s = check_tex(g, refs[i], names[i]);
        if (s != MR_OK) return mr_fail_context(s, "material %d", index);
    }
    if (in->alpha_mode < MR_GLTF_ALPHA_OPAQUE || in->alpha_mode > MR_GLTF_ALPHA_BLEND)
        return mr_fail(MR_ERR_INVALID_ARG, "glTF '%s': material %d: alpha mode %d is not OPAQUE, MASK or BLEND",
                       g->path.c_str(), index, (int)in->alpha_mode);
    const double *all[] = {in->base_color_factor, in->emissive_factor, in->diffuse_factor, in->specular_factor,
                           in->specular_color_factor};
    const int lens[] = {4, 3, 4, 3, 3};
    for (int a = 0; a < 5; a++) {
        for (int i = 0; i < lens[a]; i++) {
            if (!std::isfinite(all[a][i]))
                return mr_fail(MR_ERR_INVALID_ARG, "glTF '%s': material %d: a factor is not finite",
                               g->path.c_str(), index);
        }
    }
    double scalars[] = {in->metallic_factor, in->roughness_factor, in->alpha_cutoff, in->glossiness_factor,
                        in->specular_strength, in->ior, in->normal_texture.value, in->occlusion_texture.value};
    for (double v : scalars) {
        if (!std::isfinite(v))
            return mr_fail(MR_ERR_INVALID_ARG, "glTF '%s': material %d: a factor is not finite", g->path.c_str(),
                           index);
    }

    tinygltf::Material &m = g->model.materials[index];
    m.name = in->name ? in->name : "";
    tinygltf::PbrMetallicRoughness &pbr = m.pbrMetallicRoughness;
    pbr.baseColorFactor.assign(in->base_color_factor, in->base_color_factor + 4);
    pbr.metallicFactor = in->metallic_factor;
    pbr.roughnessFactor = in->roughness_factor;
    write_core_tex(pbr.baseColorTexture, &in->base_color_texture);
    write_core_tex(pbr.metallicRoughnessTexture, &in->metallic_roughness_texture);
    write_core_tex(m.normalTexture, &in->normal_texture);
    if (in->normal_texture.index >= 0) m.normalTexture.scale = in->normal_texture.value;
    write_core_tex(m.occlusionTexture, &in->occlusion_texture);
    if (in->occlusion_texture.index >= 0) m.occlusionTexture.strength = in->occlusion_texture.value;
    write_core_tex(m.emissiveTexture, &in->emissive_texture);
    m.emissiveFactor.assign(in->emissive_factor, in->emissive_factor + 3);
    m.alphaMode = in->alpha_mode == MR_GLTF_ALPHA_MASK ? "MASK" : in->alpha_mode == MR_GLTF_ALPHA_BLEND ? "BLEND"
                                                                                                       : "OPAQUE";
    m.alphaCutoff = in->alpha_cutoff;
    m.doubleSided = in->double_sided != 0;

    if (!in->has_spec_gloss) {
        m.extensions.erase(EXT_SPEC_GLOSS);
    } else {
        Object *o = as_object(m.extensions[EXT_SPEC_GLOSS]);
        set_nums(*o, "diffuseFactor", in->diffuse_factor, 4, ONE4);
        set_nums(*o, "specularFactor", in->specular_factor, 3, ONE3);
        set_num(*o, "glossinessFactor", in->glossiness_factor, 1.0);
        write_value_tex(*o, "diffuseTexture", &in->diffuse_texture);
        write_value_tex(*o, "specularGlossinessTexture", &in->specular_glossiness_texture);
    }
    if (!in->has_specular) {
        m.extensions.erase(EXT_SPECULAR);
    } else {
        Object *o = as_object(m.extensions[EXT_SPECULAR]);
        set_num(*o, "specularFactor", in->specular_strength, 1.0);
        set_nums(*o, "specularColorFactor", in->specular_color_factor, 3, ONE3);
        write_value_tex(*o, "specularTexture", &in->specular_texture);
        write_value_tex(*o, "specularColorTexture", &in->specular_color_texture);
    }
    if (!in->has_ior) {
        m.extensions.erase(EXT_IOR);
    } else {
        Object *o = as_object(m.extensions[EXT_IOR]);
        set_num(*o, "ior", in->ior, 1.5);
    }
    return MR_OK;
}

// ---- geometry (mr_gltf_get_triangles) -------------------------------------------------------------------

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

// Reads `count` elements of n components from buffer view `view` at `offset` into dst; packed ignores the
// view's byteStride (sparse arrays are tightly packed). "" on success, else the reason.
std::string read_view(const tinygltf::Model &m, int view, size_t offset, size_t count, int n, int type,
                      bool normalized, bool packed, double *dst) {
    if (view < 0 || view >= (int)m.bufferViews.size())
        return "buffer view " + std::to_string(view) + " does not exist";
    const tinygltf::BufferView &v = m.bufferViews[view];
    if (v.extensions.count("EXT_meshopt_compression"))
        return "buffer view " + std::to_string(view) + " is EXT_meshopt_compression-compressed (not decoded)";
    if (v.buffer < 0 || v.buffer >= (int)m.buffers.size())
        return "buffer view " + std::to_string(view) + ": buffer " + std::to_string(v.buffer) + " does not exist";
    const std::vector<unsigned char> &buf = m.buffers[v.buffer].data;
    if (v.byteOffset > buf.size() || v.byteLength > buf.size() - v.byteOffset)
        return "buffer view " + std::to_string(view) + " (offset " + std::to_string(v.byteOffset) + ", length " +
               std::to_string(v.byteLength) + ") exceeds buffer " + std::to_string(v.buffer) + " (" +
               std::to_string(buf.size()) + " bytes)";
    size_t cs = (size_t)component_bytes(type), elem = cs * (size_t)n;
    size_t stride = (!packed && v.byteStride != 0) ? v.byteStride : elem;
    if (stride < elem)
        return "buffer view " + std::to_string(view) + ": byteStride " + std::to_string(stride) +
               " is smaller than an element (" + std::to_string(elem) + " bytes)";
    if (count == 0) return "";
    size_t avail = offset <= v.byteLength ? v.byteLength - offset : 0;
    if (offset > v.byteLength || elem > avail || (count - 1) > (avail - elem) / stride)
        return std::to_string(count) + " elements at offset " + std::to_string(offset) + " run past the end of "
               "buffer view " + std::to_string(view) + " (" + std::to_string(v.byteLength) + " bytes)";
    const unsigned char *base = buf.data() + v.byteOffset + offset;
    for (size_t i = 0; i < count; i++)
        for (int c = 0; c < n; c++) dst[i * n + c] = read_component(base + i * stride + c * cs, type, normalized);
    return "";
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

const size_t MAX_ZERO_ELEMENTS = (size_t)1 << 24; // an accessor without a buffer view: zeros, capped

// Accessor `index` of glTF type want_type (TINYGLTF_TYPE_*) as doubles, count * components; sparse applied.
std::string read_accessor(const tinygltf::Model &m, int index, int want_type, std::vector<double> *out) {
    if (index < 0 || index >= (int)m.accessors.size()) return "accessor " + std::to_string(index) + " does not exist";
    const tinygltf::Accessor &a = m.accessors[index];
    std::string name = "accessor " + std::to_string(index);
    if (a.type != want_type) return name + " is a " + type_name(a.type) + ", not a " + type_name(want_type);
    int n = tinygltf::GetNumComponentsInType((uint32_t)a.type);
    if (n <= 0 || component_bytes(a.componentType) == 0)
        return name + " has an unknown componentType " + std::to_string(a.componentType);
    if (a.bufferView < 0 && a.count > MAX_ZERO_ELEMENTS)
        return name + " has no buffer view and " + std::to_string(a.count) + " elements";
    if (a.count > (size_t)INT_MAX) return name + " has too many elements";
    out->assign(a.count * (size_t)n, 0.0);
    if (a.bufferView >= 0) {
        std::string why = read_view(m, a.bufferView, a.byteOffset, a.count, n, a.componentType, a.normalized,
                                    false, out->data());
        if (!why.empty()) return name + ": " + why;
    }
    if (a.sparse.isSparse) {
        if (a.sparse.count < 0 || (size_t)a.sparse.count > a.count)
            return name + ": sparse count " + std::to_string(a.sparse.count) + " out of range";
        size_t sc = (size_t)a.sparse.count;
        int it = a.sparse.indices.componentType;
        if (it != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE && it != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
            it != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT)
            return name + ": sparse indices have componentType " + std::to_string(it);
        if (a.sparse.indices.byteOffset < 0 || a.sparse.values.byteOffset < 0)
            return name + ": negative sparse byteOffset";
        std::vector<double> idx(sc), val(sc * (size_t)n);
        std::string why = read_view(m, a.sparse.indices.bufferView, (size_t)a.sparse.indices.byteOffset, sc, 1, it,
                                    false, true, idx.data());
        if (why.empty())
            why = read_view(m, a.sparse.values.bufferView, (size_t)a.sparse.values.byteOffset, sc, n,
                            a.componentType, a.normalized, true, val.data());
        if (!why.empty()) return name + ": sparse " + why;
        for (size_t i = 0; i < sc; i++) {
            if (idx[i] >= (double)a.count)
                return name + ": sparse index " + std::to_string((long long)idx[i]) + " past its " +
                       std::to_string(a.count) + " elements";
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
};

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
    std::vector<double> pos, nrm, tan, uv0, uv1, ind;
    std::string why = read_accessor(m, a_pos, TINYGLTF_TYPE_VEC3, &pos);
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

// ---- pruning (mr_gltf_prune_unused) ---------------------------------------------------------------------
//
// References are found in three places: the model's typed fields (material textureInfos, texture
// source/sampler), every extensions/extras Value of every object (converted to JSON and walked), and the parts
// of the file's own JSON that merge_original restores on save (properties outside the schema). Inside those
// trees a reference is "known" when its meaning is certain: an object with an integer "index" under a key
// ending in "Texture"/"Textures" (every textureInfo of every Khronos and vendor material extension is named
// so), a "source" inside a texture's extensions (KHR_texture_basisu, EXT_texture_webp, EXT_texture_avif,
// MSFT_texture_dds), and a JSON pointer "/textures/N/...", "/images/N/...", "/samplers/N/..." under the key
// "pointer" (KHR_animation_pointer). Known references keep their target and are renumbered. Anything else that
// may be an index (an "index" under another key, integers under keys naming an image, texture, sampler or
// "source", e.g. EXT_lights_image_based's specularImages) is "uncertain": its target is kept and, since
// renumbering it could corrupt a value that is not an index at all, nothing at or below it is removed, so it
// never changes.

enum { KIND_TEXTURE = 0, KIND_IMAGE = 1, KIND_SAMPLER = 2, KIND_COUNT = 3 };
const char *const KIND_ARRAYS[KIND_COUNT] = {"textures", "images", "samplers"};

std::string lower(const std::string &s) {
    std::string t = s;
    for (char &c : t) c = (char)tolower((unsigned char)c);
    return t;
}

bool has_suffix(const std::string &s, const char *suffix) {
    size_t n = strlen(suffix);
    return s.size() >= n && s.compare(s.size() - n, n, suffix) == 0;
}

// A JSON number that is a non-negative integer (2.0 counts: a writer may spell an index so).
bool as_index(const nlohmann::json &j, long long *out) {
    if (j.is_number_unsigned()) {
        unsigned long long u = j.get<unsigned long long>();
        *out = u > (unsigned long long)LLONG_MAX ? -1 : (long long)u;
    } else if (j.is_number_integer()) {
        *out = j.get<long long>();
    } else if (j.is_number_float()) {
        double d = j.get<double>();
        if (!std::isfinite(d) || d != std::floor(d) || d < 0 || d > 1e15) return false;
        *out = (long long)d;
    } else {
        return false;
    }
    return *out >= 0;
}

struct prune_pass {
    bool renumber = false;           // false: record references; true: rewrite known ones through remap
    size_t size[KIND_COUNT] = {0, 0, 0};
    std::vector<char> used[KIND_COUNT];   // referenced (known or uncertain)
    std::vector<char> certain[KIND_COUNT]; // referenced by a known reference
    long long pin[KIND_COUNT] = {-1, -1, -1}; // highest uncertain index: nothing at or below it is removed
    std::vector<int> remap[KIND_COUNT];  // old -> new index, -1 = removed (renumber pass)
    bool changed = false;                // the renumber pass rewrote something in the current tree

    void init(const tinygltf::Model &m) {
        size[KIND_TEXTURE] = m.textures.size();
        size[KIND_IMAGE] = m.images.size();
        size[KIND_SAMPLER] = m.samplers.size();
        for (int k = 0; k < KIND_COUNT; k++) {
            used[k].assign(size[k], 0);
            certain[k].assign(size[k], 0);
        }
    }
    // A reference whose meaning is certain. An index past the array (a broken file) is left alone: removing
    // objects cannot make it valid.
    long long known(int kind, long long v) {
        if (v < 0 || (size_t)v >= size[kind]) return v;
        if (!renumber) {
            used[kind][(size_t)v] = certain[kind][(size_t)v] = 1;
            return v;
        }
        int to = remap[kind][(size_t)v];
        return to < 0 ? v : to;
    }
    void known_int(int kind, int *v) {
        long long to = known(kind, *v);
        if (to != *v) *v = (int)to;
    }
    void known_json(int kind, nlohmann::json &j) {
        long long v;
        if (!as_index(j, &v)) return;
        long long to = known(kind, v);
        if (to != v) {
            j = to;
            changed = true;
        }
    }
    void uncertain(int kind, long long v) {
        if (renumber || v < 0 || (size_t)v >= size[kind]) return;
        used[kind][(size_t)v] = 1;
        pin[kind] = std::max(pin[kind], v);
    }
};

// "/textures/3/..." -> kind and the index's position; false if the string is no such pointer.
bool parse_pointer(const std::string &s, int *kind, size_t *begin, size_t *end) {
    for (int k = 0; k < KIND_COUNT; k++) {
        std::string head = std::string("/") + KIND_ARRAYS[k] + "/";
        if (s.compare(0, head.size(), head) != 0) continue;
        size_t e = head.size();
        while (e < s.size() && isdigit((unsigned char)s[e])) e++;
        if (e == head.size() || e - head.size() > 9 || (e < s.size() && s[e] != '/')) return false;
        *kind = k;
        *begin = head.size();
        *end = e;
        return true;
    }
    return false;
}

// Walks a JSON tree found under `key`. texture_ext: inside a texture's extensions, where "source" is an image.
void scan_json(nlohmann::json &j, const std::string &key, bool texture_ext, prune_pass &p) {
    if (j.is_object()) {
        auto idx = j.find("index");
        long long v;
        bool has_index = idx != j.end() && as_index(*idx, &v);
        if (has_index) {
            std::string k = lower(key);
            if (has_suffix(k, "texture") || has_suffix(k, "textures")) p.known_json(KIND_TEXTURE, *idx);
            else p.uncertain(KIND_TEXTURE, v);
        }
        for (auto it = j.begin(); it != j.end(); ++it) {
            if (has_index && it.key() == "index") continue;
            scan_json(it.value(), it.key(), texture_ext, p);
        }
    } else if (j.is_array()) {
        for (auto &e : j) scan_json(e, key, texture_ext, p);
    } else if (j.is_string()) {
        const std::string &s = j.get_ref<const std::string &>();
        int kind;
        size_t b, e;
        if (!parse_pointer(s, &kind, &b, &e)) return;
        long long v = std::stoll(s.substr(b, e - b));
        // Only a "pointer" (KHR_animation_pointer's key) is certainly one; a name that looks like one is kept.
        if (key != "pointer") {
            p.uncertain(kind, v);
            return;
        }
        long long to = p.known(kind, v);
        if (to != v) {
            j = s.substr(0, b) + std::to_string(to) + s.substr(e);
            p.changed = true;
        }
    } else {
        long long v;
        if (!as_index(j, &v)) return;
        if (key == "source" && texture_ext) {
            p.known_json(KIND_IMAGE, j);
            return;
        }
        std::string k = lower(key);
        if (k == "source" || k.find("image") != std::string::npos) p.uncertain(KIND_IMAGE, v);
        if (k.find("texture") != std::string::npos) p.uncertain(KIND_TEXTURE, v);
        if (k.find("sampler") != std::string::npos) p.uncertain(KIND_SAMPLER, v);
    }
}

Value from_json(const nlohmann::json &j) {
    switch (j.type()) {
    case nlohmann::json::value_t::boolean: return Value(j.get<bool>());
    case nlohmann::json::value_t::number_integer:
    case nlohmann::json::value_t::number_unsigned: {
        double d = j.get<double>();
        if (d >= INT_MIN && d <= INT_MAX) return Value(j.get<int>());
        return Value(d);
    }
    case nlohmann::json::value_t::number_float: return Value(j.get<double>());
    case nlohmann::json::value_t::string: return Value(j.get<std::string>());
    case nlohmann::json::value_t::array: {
        Value::Array a;
        for (const auto &e : j) a.push_back(from_json(e));
        return Value(std::move(a));
    }
    case nlohmann::json::value_t::object: {
        Object o;
        for (auto it = j.begin(); it != j.end(); ++it) o[it.key()] = from_json(it.value());
        return Value(std::move(o));
    }
    default: return Value();
    }
}

// Every extensions/extras Value of the model, as f(value, key, owner kind (-1: not a texture, image or
// sampler), owner index, inside a texture's extensions).
template <typename F> void for_each_value(tinygltf::Model &m, F f) {
    auto exts = [&](tinygltf::ExtensionMap &e, int kind, int i, bool texture) {
        for (auto &kv : e) f(kv.second, kv.first, kind, (int)i, texture);
    };
    auto both = [&](tinygltf::ExtensionMap &e, Value &extras, int kind = -1, size_t i = 0, bool texture = false) {
        exts(e, kind, (int)i, texture);
        f(extras, std::string("extras"), kind, (int)i, false);
    };
    both(m.extensions, m.extras);
    both(m.asset.extensions, m.asset.extras);
    for (auto &a : m.accessors) both(a.extensions, a.extras);
    for (auto &a : m.animations) {
        both(a.extensions, a.extras);
        for (auto &c : a.channels) both(c.extensions, c.extras);
        for (auto &s : a.samplers) both(s.extensions, s.extras);
    }
    for (auto &b : m.buffers) both(b.extensions, b.extras);
    for (auto &v : m.bufferViews) both(v.extensions, v.extras);
    for (auto &c : m.cameras) {
        both(c.extensions, c.extras);
        both(c.perspective.extensions, c.perspective.extras);
        both(c.orthographic.extensions, c.orthographic.extras);
    }
    for (size_t i = 0; i < m.images.size(); i++) both(m.images[i].extensions, m.images[i].extras, KIND_IMAGE, i);
    for (auto &mat : m.materials) {
        both(mat.extensions, mat.extras);
        both(mat.pbrMetallicRoughness.extensions, mat.pbrMetallicRoughness.extras);
        both(mat.pbrMetallicRoughness.baseColorTexture.extensions, mat.pbrMetallicRoughness.baseColorTexture.extras);
        both(mat.pbrMetallicRoughness.metallicRoughnessTexture.extensions,
             mat.pbrMetallicRoughness.metallicRoughnessTexture.extras);
        both(mat.normalTexture.extensions, mat.normalTexture.extras);
        both(mat.occlusionTexture.extensions, mat.occlusionTexture.extras);
        both(mat.emissiveTexture.extensions, mat.emissiveTexture.extras);
    }
    for (auto &mesh : m.meshes) {
        both(mesh.extensions, mesh.extras);
        for (auto &prim : mesh.primitives) both(prim.extensions, prim.extras);
    }
    for (auto &n : m.nodes) both(n.extensions, n.extras);
    for (size_t i = 0; i < m.samplers.size(); i++)
        both(m.samplers[i].extensions, m.samplers[i].extras, KIND_SAMPLER, i);
    for (auto &s : m.scenes) both(s.extensions, s.extras);
    for (auto &s : m.skins) both(s.extensions, s.extras);
    for (size_t i = 0; i < m.textures.size(); i++)
        both(m.textures[i].extensions, m.textures[i].extras, KIND_TEXTURE, i, true);
    for (auto &l : m.lights) {
        both(l.extensions, l.extras);
        both(l.spot.extensions, l.spot.extras);
    }
}

// The typed references: material textureInfos, texture source and sampler. skip[k][i]: object i of kind k is
// being removed, its references do not count (and need no renumbering).
void scan_typed(tinygltf::Model &m, prune_pass &p, const std::vector<char> *skip) {
    for (auto &mat : m.materials) {
        p.known_int(KIND_TEXTURE, &mat.pbrMetallicRoughness.baseColorTexture.index);
        p.known_int(KIND_TEXTURE, &mat.pbrMetallicRoughness.metallicRoughnessTexture.index);
        p.known_int(KIND_TEXTURE, &mat.normalTexture.index);
        p.known_int(KIND_TEXTURE, &mat.occlusionTexture.index);
        p.known_int(KIND_TEXTURE, &mat.emissiveTexture.index);
    }
    for (size_t i = 0; i < m.textures.size(); i++) {
        if (skip && skip[KIND_TEXTURE][i]) continue;
        p.known_int(KIND_IMAGE, &m.textures[i].source);
        p.known_int(KIND_SAMPLER, &m.textures[i].sampler);
    }
}

bool skipped(const std::vector<char> *skip, int kind, int i) {
    return skip != NULL && kind >= 0 && (size_t)i < skip[kind].size() && skip[kind][(size_t)i];
}

// Every extensions/extras Value, converted to JSON and walked; with p.renumber the rewritten trees are
// collected in *rewritten instead of being stored (the caller commits them once nothing can fail).
void scan_values(tinygltf::Model &m, prune_pass &p, const std::vector<char> *skip,
                 std::vector<std::pair<Value *, Value>> *rewritten) {
    for_each_value(m, [&](Value &v, const std::string &key, int kind, int i, bool texture_ext) {
        if (skipped(skip, kind, i) || v.Type() == tinygltf::NULL_TYPE) return;
        nlohmann::json j = to_json(v);
        p.changed = false;
        scan_json(j, key, texture_ext, p);
        if (p.renumber && p.changed && rewritten != NULL) rewritten->push_back({&v, from_json(j)});
    });
}

// What merge_original may restore from the file's JSON: keys of a material outside its schema, and
// everything of the other objects (their schema keys agree with the model's, so scanning them again adds
// nothing). A texture's source and sampler are typed references; an animation channel's "sampler" is the
// animation's, not a texture sampler.
void scan_original(nlohmann::json &doc, prune_pass &p, const std::vector<char> *skip) {
    if (!doc.is_object()) return;
    for (auto it = doc.begin(); it != doc.end(); ++it) {
        const std::string &key = it.key();
        nlohmann::json &v = it.value();
        if (key == "materials" && v.is_array()) {
            for (auto &mat : v) {
                if (!mat.is_object()) continue;
                for (auto f = mat.begin(); f != mat.end(); ++f)
                    if (!is_material_key(f.key())) scan_json(f.value(), f.key(), false, p);
            }
        } else if (key == "textures" && v.is_array()) {
            for (size_t i = 0; i < v.size(); i++) {
                if (!v[i].is_object() || skipped(skip, KIND_TEXTURE, (int)i)) continue;
                for (auto f = v[i].begin(); f != v[i].end(); ++f) {
                    if (f.key() == "source") p.known_json(KIND_IMAGE, f.value());
                    else if (f.key() == "sampler") p.known_json(KIND_SAMPLER, f.value());
                    else if (f.key() == "extensions" && f.value().is_object()) {
                        for (auto e = f.value().begin(); e != f.value().end(); ++e)
                            scan_json(e.value(), e.key(), true, p);
                    } else scan_json(f.value(), f.key(), false, p);
                }
            }
        } else if ((key == "images" || key == "samplers") && v.is_array()) {
            int kind = key == "images" ? KIND_IMAGE : KIND_SAMPLER;
            for (size_t i = 0; i < v.size(); i++)
                if (!skipped(skip, kind, (int)i)) scan_json(v[i], key, false, p);
        } else if (key == "animations" && v.is_array()) {
            for (auto &a : v) {
                if (!a.is_object()) continue;
                for (auto f = a.begin(); f != a.end(); ++f) {
                    if (f.key() != "channels" || !f.value().is_array()) {
                        scan_json(f.value(), f.key(), false, p);
                        continue;
                    }
                    for (auto &c : f.value()) {
                        if (!c.is_object()) continue;
                        for (auto g = c.begin(); g != c.end(); ++g)
                            if (g.key() != "sampler") scan_json(g.value(), g.key(), false, p);
                    }
                }
            }
        } else {
            scan_json(v, key, false, p);
        }
    }
}

// Moves the kept elements of `v` to its front (keep[i] for i < keep.size(); elements past it are kept).
template <typename T> void compact(std::vector<T> &v, const std::vector<char> &keep) {
    size_t to = 0;
    for (size_t i = 0; i < v.size(); i++) {
        if (i < keep.size() && !keep[i]) continue;
        if (to != i) v[to] = std::move(v[i]);
        to++;
    }
    v.erase(v.begin() + (std::ptrdiff_t)to, v.end());
}

void compact_json(nlohmann::json &a, const std::vector<char> &keep) {
    if (!a.is_array()) return;
    nlohmann::json out = nlohmann::json::array();
    for (size_t i = 0; i < a.size(); i++)
        if (i >= keep.size() || keep[i]) out.push_back(std::move(a[i]));
    a = std::move(out);
}

mr_status prune_impl(mr_gltf *g, mr_gltf_prune_stats *stats) {
    tinygltf::Model &m = g->model;
    mr_gltf_prune_stats st;
    memset(&st, 0, sizeof st);

    // 1. Textures: referenced from anywhere (an unused texture's own values count too: keeping is safe).
    prune_pass a;
    a.init(m);
    scan_typed(m, a, NULL);
    scan_values(m, a, NULL, NULL);
    scan_original(g->original, a, NULL);
    std::vector<char> remove[KIND_COUNT];
    remove[KIND_TEXTURE].assign(m.textures.size(), 0);
    for (size_t i = 0; i < m.textures.size(); i++)
        remove[KIND_TEXTURE][i] = !a.used[KIND_TEXTURE][i] && (long long)i > a.pin[KIND_TEXTURE];
    remove[KIND_IMAGE].assign(m.images.size(), 0);
    remove[KIND_SAMPLER].assign(m.samplers.size(), 0);

    // 2. Images and samplers: referenced from what stays (a removed texture's source no longer counts).
    prune_pass b;
    b.init(m);
    scan_typed(m, b, remove);
    scan_values(m, b, remove, NULL);
    scan_original(g->original, b, remove);
    for (int k = KIND_IMAGE; k <= KIND_SAMPLER; k++)
        for (size_t i = 0; i < b.size[k]; i++) remove[k][i] = !b.used[k][i] && (long long)i > b.pin[k];

    // 3. The new numbering and every rewritten value, computed before anything changes, so that a failure
    // (out of memory) leaves the asset as it was.
    prune_pass c;
    c.init(m);
    c.renumber = true;
    std::vector<char> keep[KIND_COUNT];
    for (int k = 0; k < KIND_COUNT; k++) {
        const prune_pass &from = k == KIND_TEXTURE ? a : b;
        c.remap[k].assign(c.size[k], -1);
        keep[k].assign(c.size[k], 1);
        int next = 0;
        for (size_t i = 0; i < c.size[k]; i++) {
            if (remove[k][i]) {
                keep[k][i] = 0;
                continue;
            }
            c.remap[k][i] = next++;
            if (!from.certain[k][i]) st.uncertain++;
        }
    }
    st.textures = (int)std::count(remove[KIND_TEXTURE].begin(), remove[KIND_TEXTURE].end(), 1);
    st.images = (int)std::count(remove[KIND_IMAGE].begin(), remove[KIND_IMAGE].end(), 1);
    st.samplers = (int)std::count(remove[KIND_SAMPLER].begin(), remove[KIND_SAMPLER].end(), 1);
    if (st.textures + st.images + st.samplers > 0) {
        std::vector<std::pair<Value *, Value>> rewritten;
        scan_values(m, c, remove, &rewritten);
        nlohmann::json original = g->original;
        if (original.is_object()) {
            for (int k = 0; k < KIND_COUNT; k++)
                if (original.contains(KIND_ARRAYS[k])) compact_json(original[KIND_ARRAYS[k]], keep[k]);
            scan_original(original, c, NULL);
        }
        std::vector<std::string> image_paths = g->image_paths;
        compact(image_paths, keep[KIND_IMAGE]);

        // Commit: moves and swaps only.
        for (auto &r : rewritten) std::swap(*r.first, r.second);
        scan_typed(m, c, remove);
        compact(m.textures, keep[KIND_TEXTURE]);
        compact(m.images, keep[KIND_IMAGE]);
        compact(m.samplers, keep[KIND_SAMPLER]);
        g->image_paths.swap(image_paths);
        g->original.swap(original);
    }
    if (stats != NULL) *stats = st;
    return MR_OK;
}

} // namespace

// ---- the C API -------------------------------------------------------------------------------------------

#define MR_GLTF_GUARD(label, body)                                                                 \
    try {                                                                                         \
        body                                                                                      \
    } catch (const std::bad_alloc &) {                                                            \
        return mr_fail(MR_ERR_NOMEM, "%s: out of memory", label);                                  \
    } catch (const std::exception &e) {                                                           \
        return mr_fail(MR_ERR_EXTERNAL, "%s: %s", label, e.what());                                \
    } catch (...) {                                                                               \
        return mr_fail(MR_ERR_EXTERNAL, "%s: unexpected exception", label);                        \
    }

extern "C" {

mr_status mr_gltf_load(const char *path, mr_gltf **out) {
    if (path == NULL || path[0] == '\0' || out == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "glTF: empty path or NULL output");
    MR_GLTF_GUARD(path, return load_impl(path, out);)
}

void mr_gltf_free(mr_gltf *asset) { delete asset; }

const char *mr_gltf_path(const mr_gltf *asset) { return asset ? asset->path.c_str() : ""; }

void mr_gltf_get_counts(const mr_gltf *g, mr_gltf_counts *out) {
    memset(out, 0, sizeof *out);
    if (g == NULL) return;
    const tinygltf::Model &m = g->model;
    out->materials = (int)m.materials.size();
    out->textures = (int)m.textures.size();
    out->images = (int)m.images.size();
    out->samplers = (int)m.samplers.size();
    out->meshes = (int)m.meshes.size();
    out->nodes = (int)m.nodes.size();
    out->scenes = (int)m.scenes.size();
    out->accessors = (int)m.accessors.size();
    out->buffer_views = (int)m.bufferViews.size();
    out->buffers = (int)m.buffers.size();
    out->animations = (int)m.animations.size();
    out->skins = (int)m.skins.size();
    out->cameras = (int)m.cameras.size();
}

void mr_gltf_texture_ref_none(mr_gltf_texture_ref *r) {
    r->index = -1;
    r->tex_coord = 0;
    r->value = 1.0;
    r->has_transform = 0;
    r->offset[0] = r->offset[1] = 0.0;
    r->rotation = 0.0;
    r->scale[0] = r->scale[1] = 1.0;
    r->transform_tex_coord = -1;
}

void mr_gltf_material_defaults(mr_gltf_material *m) {
    memset(m, 0, sizeof *m);
    m->name = "";
    for (int i = 0; i < 4; i++) m->base_color_factor[i] = m->diffuse_factor[i] = 1.0;
    for (int i = 0; i < 3; i++) m->specular_factor[i] = m->specular_color_factor[i] = 1.0;
    m->metallic_factor = m->roughness_factor = 1.0;
    m->alpha_mode = MR_GLTF_ALPHA_OPAQUE;
    m->alpha_cutoff = 0.5;
    m->glossiness_factor = 1.0;
    m->specular_strength = 1.0;
    m->ior = 1.5;
    mr_gltf_texture_ref *refs[] = {&m->base_color_texture, &m->metallic_roughness_texture, &m->normal_texture,
                                   &m->occlusion_texture, &m->emissive_texture, &m->diffuse_texture,
                                   &m->specular_glossiness_texture, &m->specular_texture,
                                   &m->specular_color_texture};
    for (auto *r : refs) mr_gltf_texture_ref_none(r);
}

mr_status mr_gltf_get_material(const mr_gltf *g, int material, mr_gltf_material *out) {
    mr_status s = check_material(g, material);
    if (s != MR_OK) return s;
    if (out == NULL) return mr_fail(MR_ERR_INVALID_ARG, "glTF: NULL material output");
    MR_GLTF_GUARD(g->path.c_str(), get_material_impl(g, material, out); return MR_OK;)
}

mr_status mr_gltf_set_material(mr_gltf *g, int material, const mr_gltf_material *in) {
    mr_status s = check_material(g, material);
    if (s != MR_OK) return s;
    if (in == NULL) return mr_fail(MR_ERR_INVALID_ARG, "glTF: NULL material");
    MR_GLTF_GUARD(g->path.c_str(), return set_material_impl(g, material, in);)
}

mr_status mr_gltf_remove_material_extension(mr_gltf *g, int material, const char *name, int *removed) {
    mr_status s = check_material(g, material);
    if (s != MR_OK) return s;
    if (name == NULL) return mr_fail(MR_ERR_INVALID_ARG, "glTF: NULL extension name");
    size_t n = g->model.materials[material].extensions.erase(name);
    if (removed) *removed = n > 0;
    return MR_OK;
}

int mr_gltf_material_has_extension(const mr_gltf *g, int material, const char *name) {
    if (g == NULL || name == NULL || material < 0 || material >= (int)g->model.materials.size()) return 0;
    return g->model.materials[material].extensions.count(name) > 0;
}

mr_status mr_gltf_get_texture(const mr_gltf *g, int texture, mr_gltf_texture *out) {
    if (g == NULL || out == NULL) return mr_fail(MR_ERR_INVALID_ARG, "glTF: NULL argument");
    if (texture < 0 || texture >= (int)g->model.textures.size())
        return mr_fail(MR_ERR_INVALID_ARG, "glTF '%s': texture %d does not exist (the asset has %zu)",
                       g->path.c_str(), texture, g->model.textures.size());
    const tinygltf::Texture &t = g->model.textures[texture];
    mr_gltf_texture r;
    r.image = t.source;
    r.sampler = t.sampler;
    r.params.mag_filter = r.params.min_filter = -1;
    r.params.wrap_s = r.params.wrap_t = 10497;
    if (t.sampler >= 0 && t.sampler < (int)g->model.samplers.size()) {
        const tinygltf::Sampler &s = g->model.samplers[t.sampler];
        r.params.mag_filter = s.magFilter;
        r.params.min_filter = s.minFilter;
        r.params.wrap_s = s.wrapS;
        r.params.wrap_t = s.wrapT;
    }
    *out = r;
    return MR_OK;
}

mr_status mr_gltf_get_image(const mr_gltf *g, int image, mr_gltf_image *out) {
    if (g == NULL || out == NULL) return mr_fail(MR_ERR_INVALID_ARG, "glTF: NULL argument");
    if (image < 0 || image >= (int)g->model.images.size())
        return mr_fail(MR_ERR_INVALID_ARG, "glTF '%s': image %d does not exist (the asset has %zu)",
                       g->path.c_str(), image, g->model.images.size());
    const tinygltf::Image &im = g->model.images[image];
    out->bytes = im.image.empty() ? NULL : im.image.data();
    out->size = im.image.size();
    out->mime_type = im.mimeType.c_str();
    out->uri = im.uri.c_str();
    out->path = g->image_paths[image].c_str();
    out->buffer_view = im.bufferView;
    return MR_OK;
}

mr_status mr_gltf_image_write_file(const mr_gltf *g, int image, const char *path) {
    mr_gltf_image im;
    mr_status s = mr_gltf_get_image(g, image, &im);
    if (s != MR_OK) return s;
    if (path == NULL || path[0] == '\0') return mr_fail(MR_ERR_INVALID_ARG, "glTF: empty image output path");
    MR_GLTF_GUARD(path, {
        std::string real = real_path(path);
        if (!real.empty()) {
            if (real == real_path(g->path)) goto is_input;
            for (const auto &p : g->image_paths) {
                if (!p.empty() && real == real_path(p)) goto is_input;
            }
            for (const auto &p : g->buffer_paths) {
                if (!p.empty() && real == real_path(p)) goto is_input;
            }
        }
        return mr_atomic_write_bytes(path, im.bytes, im.size);
    is_input:
        return mr_fail(MR_ERR_INVALID_ARG, "image output '%s': is a file the asset '%s' was read from", path,
                       g->path.c_str());
    })
}

mr_status mr_gltf_add_image_file(mr_gltf *g, const char *file, const char *uri, int *out_image) {
    if (g == NULL || file == NULL || uri == NULL || out_image == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "glTF: NULL argument");
    MR_GLTF_GUARD(file, {
        if (!is_safe_relative(uri) || is_data_uri(uri))
            return mr_fail(MR_ERR_INVALID_ARG, "glTF image URI '%s': expected a relative path inside the output "
                           "directory (no '..', not absolute)", uri);
        tinygltf::Image im;
        mr_status s = read_file(file, &im.image, "image");
        if (s != MR_OK) return s;
        im.mimeType = sniff_mime(im.image);
        if (im.mimeType.empty())
            return mr_fail(MR_ERR_FORMAT, "image '%s': not a PNG, JPEG or EXR file", file);
        im.as_is = true;
        im.uri = uri_encode_spaces(uri);
        g->model.images.push_back(std::move(im));
        g->image_paths.push_back(file);
        *out_image = (int)g->model.images.size() - 1;
        return MR_OK;
    })
}

mr_status mr_gltf_add_image_bytes(mr_gltf *g, const void *bytes, size_t size, const char *uri, int *out_image) {
    if (g == NULL || (bytes == NULL && size > 0) || uri == NULL || out_image == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "glTF: NULL argument");
    MR_GLTF_GUARD(uri, {
        if (!is_safe_relative(uri) || is_data_uri(uri))
            return mr_fail(MR_ERR_INVALID_ARG, "glTF image URI '%s': expected a relative path inside the output "
                           "directory (no '..', not absolute)", uri);
        tinygltf::Image im;
        const unsigned char *p = static_cast<const unsigned char *>(bytes);
        im.image.assign(p, p + size);
        im.mimeType = sniff_mime(im.image);
        if (im.mimeType.empty())
            return mr_fail(MR_ERR_FORMAT, "image '%s': not a PNG, JPEG or EXR file", uri);
        im.as_is = true;
        im.uri = uri_encode_spaces(uri);
        g->model.images.push_back(std::move(im));
        g->image_paths.push_back("");
        *out_image = (int)g->model.images.size() - 1;
        return MR_OK;
    })
}

mr_status mr_gltf_add_texture(mr_gltf *g, int image, const mr_gltf_sampler *sampler, int *out_texture) {
    if (g == NULL || out_texture == NULL) return mr_fail(MR_ERR_INVALID_ARG, "glTF: NULL argument");
    if (image < 0 || image >= (int)g->model.images.size())
        return mr_fail(MR_ERR_INVALID_ARG, "glTF '%s': image %d does not exist (the asset has %zu)",
                       g->path.c_str(), image, g->model.images.size());
    MR_GLTF_GUARD(g->path.c_str(), {
        tinygltf::Texture t;
        t.source = image;
        if (sampler != NULL) {
            int found = -1;
            for (size_t i = 0; i < g->model.samplers.size() && found < 0; i++) {
                const tinygltf::Sampler &s = g->model.samplers[i];
                if (s.magFilter == sampler->mag_filter && s.minFilter == sampler->min_filter &&
                    s.wrapS == sampler->wrap_s && s.wrapT == sampler->wrap_t && s.name.empty() &&
                    s.extras.Type() == tinygltf::NULL_TYPE && s.extensions.empty())
                    found = (int)i;
            }
            if (found < 0) {
                tinygltf::Sampler s;
                s.magFilter = sampler->mag_filter;
                s.minFilter = sampler->min_filter;
                s.wrapS = sampler->wrap_s;
                s.wrapT = sampler->wrap_t;
                g->model.samplers.push_back(s);
                found = (int)g->model.samplers.size() - 1;
            }
            t.sampler = found;
        }
        g->model.textures.push_back(t);
        *out_texture = (int)g->model.textures.size() - 1;
        return MR_OK;
    })
}

void mr_gltf_sync_extensions(mr_gltf *g) {
    if (g == NULL) return;
    const char *managed[] = {EXT_SPEC_GLOSS, EXT_SPECULAR, EXT_IOR, EXT_TRANSFORM};
    tinygltf::Model &m = g->model;
    for (const char *name : managed) {
        bool used = false;
        for (const auto &mat : m.materials) used = used || material_uses(mat, name);
        auto &u = m.extensionsUsed;
        auto &r = m.extensionsRequired;
        if (used && !list_has(u, name)) u.push_back(name);
        if (!used) {
            u.erase(std::remove(u.begin(), u.end(), name), u.end());
            r.erase(std::remove(r.begin(), r.end(), name), r.end());
        }
    }
}

mr_status mr_gltf_set_extension_required(mr_gltf *g, const char *name, int required) {
    if (g == NULL || name == NULL || name[0] == '\0') return mr_fail(MR_ERR_INVALID_ARG, "glTF: NULL or empty name");
    MR_GLTF_GUARD(name, {
        auto &u = g->model.extensionsUsed;
        auto &r = g->model.extensionsRequired;
        if (required) {
            if (!list_has(u, name)) u.push_back(name);
            if (!list_has(r, name)) r.push_back(name);
        } else {
            r.erase(std::remove(r.begin(), r.end(), name), r.end());
        }
        return MR_OK;
    })
}

int mr_gltf_extension_used(const mr_gltf *g, const char *name) {
    return g != NULL && name != NULL && list_has(g->model.extensionsUsed, name);
}

int mr_gltf_extension_required(const mr_gltf *g, const char *name) {
    return g != NULL && name != NULL && list_has(g->model.extensionsRequired, name);
}

mr_status mr_gltf_prune_unused(mr_gltf *g, mr_gltf_prune_stats *stats) {
    if (stats != NULL) memset(stats, 0, sizeof *stats);
    if (g == NULL) return mr_fail(MR_ERR_INVALID_ARG, "glTF: NULL asset");
    MR_GLTF_GUARD(g->path.c_str(), return prune_impl(g, stats);)
}

mr_status mr_gltf_save(mr_gltf *g, const char *path) {
    if (g == NULL || path == NULL || path[0] == '\0')
        return mr_fail(MR_ERR_INVALID_ARG, "glTF: NULL asset or empty output path");
    MR_GLTF_GUARD(path, return save_impl(g, path);)
}

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
