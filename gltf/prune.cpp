// prune.cpp — mr_gltf_prune_unused (contract in gltf/mr_gltf.h, "Pruning"): unreferenced textures, then
// images, then samplers removed and every reference renumbered, also inside JSON the shim does not know.
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
#include "gltf/gltf_internal.hpp"

#include <ctype.h>
#include <limits.h>
#include <string.h>

#include <algorithm>
#include <cmath>

using namespace mr_gltf_internal;

namespace {

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
    nlohmann::json &orig = original_json(g);
    scan_original(orig, a, NULL);
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
    scan_original(orig, b, remove);
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
        nlohmann::json original = orig;
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
        orig.swap(original);
    }
    if (stats != NULL) *stats = st;
    return MR_OK;
}

} // namespace

// ---- the C API -------------------------------------------------------------------------------------------

extern "C" {

mr_status mr_gltf_prune_unused(mr_gltf *g, mr_gltf_prune_stats *stats) {
    if (stats != NULL) memset(stats, 0, sizeof *stats);
    if (g == NULL) return mr_fail(MR_ERR_INVALID_ARG, "glTF: NULL asset");
    MR_GLTF_GUARD(g->path.c_str(), return prune_impl(g, stats);)
}

} // extern "C"
