// gltf_internal.hpp — what the files of the tinygltf shim share (gltf/README.md lists them; the contract is
// gltf/mr_gltf.h): the asset behind the opaque mr_gltf, the helpers more than one file uses, and the guard that
// keeps C++ exceptions from crossing the C boundary. C++ only; not installed.
#ifndef MR_GLTF_INTERNAL_HPP
#define MR_GLTF_INTERNAL_HPP

#include <new>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>
#include <tiny_gltf.h>

#include "gltf/mr_gltf.h"
#include "mr_internal.h"

struct mr_gltf {
    tinygltf::Model model;
    std::string path;                     // the file read
    std::string base_dir;                 // its directory ("." if none)
    std::vector<std::string> image_paths; // per image: resolved source file ("" for embedded images)
    std::vector<std::string> buffer_paths; // per buffer: resolved source file ("" for embedded buffers)
    // The file's JSON, for what tinygltf does not keep: merge_original restores it on save, and
    // mr_gltf_prune_unused renumbers references in it. Loading keeps only its text; original_json parses it on
    // first use, so that a read-only use (loading an asset to render it) parses the JSON once, in tinygltf.
    std::string original_text;
    nlohmann::json original;
    bool original_parsed = false;
    ~mr_gltf(); // util.cpp: takes `original` apart without allocating (mr_gltf_internal::release_json)
};

namespace mr_gltf_internal {

using tinygltf::Value;
typedef Value::Object Object;

// ---- shared helpers (util.cpp) --------------------------------------------------------------------------

bool is_data_uri(const std::string &uri);

// A relative URI that stays inside the output directory: not absolute, no scheme, no ".." segment.
bool is_safe_relative(const std::string &decoded);

// The canonical absolute path of an existing file, "" if it does not exist.
std::string real_path(const std::string &path);

// A relative path as a URI: spaces and '%' percent-encoded (the inverse of the loader's decoding).
std::string uri_encode_spaces(const std::string &rel);

// The mime type of encoded image bytes by their signature ("" if unknown).
std::string sniff_mime(const std::vector<unsigned char> &b);

// The whole file; errors (MR_ERR_IO) name it as "<what> '<path>'".
mr_status read_file(const std::string &path, std::vector<unsigned char> *out, const char *what);

bool list_has(const std::vector<std::string> &list, const char *name);

nlohmann::json to_json(const Value &v);

// The keys of the material schema (the model holds them; the file's own are stale once a material is set).
bool is_material_key(const std::string &key);

// The asset's original JSON (struct mr_gltf), parsed from original_text on the first call; null if the text is
// not a JSON object. Buffers' and images' "uri" are dropped: their payloads are written from the model.
nlohmann::json &original_json(mr_gltf *g);

// Empty a JSON value without allocating, leaving null. nlohmann/json's destructor moves the children of an array
// or object onto a std::vector first (so that deep documents are not destroyed recursively), and a std::bad_alloc
// from a destructor terminates the program: an asset freed after running out of memory must not need memory.
void release_json(nlohmann::json &j) noexcept;

} // namespace mr_gltf_internal

// The body of every C entry point that can meet a C++ exception: `body` returns an mr_status, and whatever it
// throws becomes one (MR_ERR_NOMEM, MR_ERR_EXTERNAL) with a message naming `label` (the file or asset).
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

#endif /* MR_GLTF_INTERNAL_HPP */
