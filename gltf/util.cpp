// util.cpp — helpers more than one file of the glTF shim uses (declared in gltf_internal.hpp).
#include "gltf/gltf_internal.hpp"

#include <errno.h>
#include <limits.h>
#include <stdlib.h>
#include <string.h>

#include <algorithm>
#include <iterator>
#include <set>
#include <sstream>

namespace mr_gltf_internal {

bool is_data_uri(const std::string &uri) { return uri.compare(0, 5, "data:") == 0; }

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

std::string uri_encode_spaces(const std::string &rel) {
    std::string out;
    for (char c : rel) {
        if (c == ' ') out += "%20";
        else if (c == '%') out += "%25";
        else out += c;
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

bool is_material_key(const std::string &key) {
    static const std::set<std::string> keys = {
        "name", "extensions", "extras", "pbrMetallicRoughness", "normalTexture", "occlusionTexture",
        "emissiveTexture", "emissiveFactor", "alphaMode", "alphaCutoff", "doubleSided"};
    return keys.count(key) > 0;
}

nlohmann::json &original_json(mr_gltf *g) {
    if (g->original_parsed) return g->original;
    nlohmann::json doc = nlohmann::json::parse(g->original_text, nullptr, false);
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
    g->original_parsed = true;
    std::string().swap(g->original_text);
    return g->original;
}

// Leaf first: the last element of the deepest non-empty container on the path of last elements is a scalar or an
// empty container, whose destruction allocates nothing; erase it and start again from the top. O(size x depth),
// no recursion, no allocation.
void release_json(nlohmann::json &j) noexcept {
    auto nonempty = [](const nlohmann::json &v) { return (v.is_array() || v.is_object()) && !v.empty(); };
    while (nonempty(j)) {
        nlohmann::json *p = &j;
        while (nonempty(p->back()))
            p = &p->back();
        p->erase(std::prev(p->end()));
    }
    j = nullptr;
}

} // namespace mr_gltf_internal

mr_gltf::~mr_gltf() { mr_gltf_internal::release_json(original); }
