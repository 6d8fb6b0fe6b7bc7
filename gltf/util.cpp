// util.cpp — helpers more than one file of the glTF shim uses (declared in gltf_internal.hpp).
#include "gltf/gltf_internal.hpp"


#include <errno.h>
#include <limits.h>
#include <stdlib.h>
#include <string.h>

#include <algorithm>
#include <memory>
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
    const std::string label = what != NULL ? std::string(what) + " '" + path + "'" : "";
    FILE *file = NULL;
    uint64_t size = 0;
    mr_status s = mr_io_open_input(path.c_str(), what != NULL ? label.c_str() : NULL, MAX_INPUT_BYTES, &file, &size);
    if (s != MR_OK)
        return s;
    std::unique_ptr<FILE, int (*)(FILE *)> f(file, fclose); // closed however this returns (resize may throw)
    // The size fstat gave when the file was opened (a file that shrinks meanwhile is read as far as it goes).
    std::vector<unsigned char> bytes((size_t)size);
    size_t got = 0, n;
    while (got < bytes.size() && (n = fread(bytes.data() + got, 1, bytes.size() - got, f.get())) > 0)
        got += n;
    if (ferror(f.get())) {
        if (what == NULL)
            return mr_fail(MR_ERR_IO, "read error");
        return mr_fail(MR_ERR_IO, "%s: read error", label.c_str());
    }
    bytes.resize(got);
    out->swap(bytes);
    return MR_OK;
}

// ---- the JSON text, before any parser sees it ----------------------------------------------------------------

mr_status scan_json(const char *text, size_t n, size_t base, const std::string &file, json_span *materials) {
    *materials = json_span();
    // Where the root object stands: expecting a key, inside one, expecting its ':', inside its value.
    enum { KEY, IN_KEY, COLON, VALUE } top = KEY;
    bool in_string = false, escaped = false, key_escaped = false, root_object = false;
    size_t depth = 0, key_begin = 0, key_end = 0, value_begin = std::string::npos;
    auto end_value = [&](size_t at) {
        if (value_begin == std::string::npos)
            return;
        std::string key(text + key_begin + 1, key_end - key_begin - 1);
        if (key_escaped) { // a key written with escapes ("materi\u0061ls") means what it decodes to
            nlohmann::json k = nlohmann::json::parse(text + key_begin, text + key_end + 1, nullptr, false);
            key = k.is_string() ? k.get<std::string>() : "";
        }
        if (key == "materials") { // JSON's last duplicate wins, in nlohmann and tinygltf alike
            materials->found = true;
            materials->begin = value_begin;
            materials->end = at;
        }
    };
    for (size_t i = 0; i < n; i++) {
        const char c = text[i];
        if (in_string) {
            if (escaped) {
                escaped = false;
            } else if (c == '\\') {
                escaped = true;
                if (depth == 1 && top == IN_KEY)
                    key_escaped = true;
            } else if (c == '"') {
                in_string = false;
                if (depth == 1 && top == IN_KEY) {
                    key_end = i;
                    top = COLON;
                }
            }
            continue;
        }
        const bool top_value = depth == 1 && root_object && top == VALUE && value_begin == std::string::npos;
        switch (c) {
        case ' ':
        case '\t':
        case '\n':
        case '\r':
            break;
        case '"':
            in_string = true;
            if (depth == 1 && root_object && top == KEY) {
                top = IN_KEY;
                key_begin = i;
                key_escaped = false;
            } else if (top_value) {
                value_begin = i;
            }
            break;
        case '{':
        case '[':
            if (depth == 0)
                root_object = c == '{';
            if (top_value)
                value_begin = i;
            if (++depth > MAX_JSON_DEPTH)
                return mr_fail(MR_ERR_FORMAT, "glTF '%s': the JSON nests deeper than %d levels (at byte %zu)",
                               file.c_str(), MAX_JSON_DEPTH, base + i);
            break;
        case '}':
        case ']':
            if (depth == 1 && root_object && top == VALUE)
                end_value(i);
            if (depth > 0)
                depth--;
            break;
        case ':':
            if (depth == 1 && root_object && top == COLON) {
                top = VALUE;
                value_begin = std::string::npos;
            }
            break;
        case ',':
            if (depth == 1 && root_object && top == VALUE) {
                end_value(i);
                top = KEY;
            }
            break;
        default:
            if (top_value)
                value_begin = i;
            break;
        }
    }
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
