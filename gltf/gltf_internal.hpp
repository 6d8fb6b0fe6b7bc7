// gltf_internal.hpp — what the files of the tinygltf shim share (gltf/README.md lists them; the contract is
// gltf/mr_gltf.h): the asset behind the opaque mr_gltf, the helpers more than one file uses, and the guard that
// keeps C++ exceptions from crossing the C boundary. C++ only; not installed.
#ifndef MR_GLTF_INTERNAL_HPP
#define MR_GLTF_INTERNAL_HPP

#include <limits.h>

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
    // Every file the asset was read from, as loaded: the asset, then its external buffers and images. Kept when
    // edits remove images or buffers (mr_gltf_prune_unused), so that a save never writes over a file that was read,
    // even one nothing refers to any more.
    std::vector<std::string> source_files;
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

// ---- limits on what a file may make the loader do (documented in mr_gltf.h, "Limits") ----------------------

// The most bytes the shim reads from one file: the asset, an external buffer, an external image. tinygltf 2.7
// passes image sizes as int and the asset's size as unsigned, so anything larger would be cut short.
const size_t MAX_INPUT_BYTES = (size_t)INT_MAX;

// The deepest nesting of arrays and objects in an asset's JSON. tinygltf and nlohmann/json recurse once per level
// (converting to tinygltf::Value, destroying the tree), so tens of thousands of levels overflow the stack; a
// real asset nests about 10 deep, extras included.
const int MAX_JSON_DEPTH = 128;

// The whole file, if it is a regular file of at most MAX_INPUT_BYTES (mr_io_open_input: a folder, a FIFO or a
// device is refused by name); errors name it as "<what> '<path>'" (MR_ERR_IO, MR_ERR_FORMAT for the size), or are
// the reason alone ("is a directory") when what is NULL.
mr_status read_file(const std::string &path, std::vector<unsigned char> *out, const char *what);

// Where the top-level "materials" value lies in an asset's JSON text (byte offsets into it).
struct json_span {
    bool found = false;
    size_t begin = 0, end = 0;
};

// One pass over JSON text of n bytes, outside strings, before any parser sees it: nesting deeper than
// MAX_JSON_DEPTH is MR_ERR_FORMAT naming `file`, the limit and the byte offset (`base` + the offset in text: the
// JSON chunk of a .glb starts at byte 20). *materials receives the span of the root object's "materials" value, so
// that it alone can be parsed again for what tinygltf does not check (validate_materials). Malformed JSON is left
// to the parser.
mr_status scan_json(const char *text, size_t n, size_t base, const std::string &file, json_span *materials);

bool list_has(const std::vector<std::string> &list, const char *name);

nlohmann::json to_json(const Value &v);

// The keys of the material schema (the model holds them; the file's own are stale once a material is set).
bool is_material_key(const std::string &key);

// The file's materials (the JSON text of the top-level "materials" value, parsed alone) against the parts of the
// glTF schema the shim and its users read, which tinygltf 2.7 does not check or silently drops: every material an
// object; a material's extensions an object of objects (tinygltf drops an extension that is not one, and the
// material then reads as if it had none); the factors of the core material, KHR_materials_pbrSpecularGlossiness,
// KHR_materials_specular and KHR_materials_ior numbers of the right count, finite and within the schema's range;
// every textureInfo (core and in those extensions) an object whose index names a texture of the asset, with a
// non-negative integer texCoord and a well-formed KHR_texture_transform; alphaMode one of glTF's three. Also each
// texture's source and sampler in range. MR_ERR_FORMAT naming the file, the material (index and name) and the
// field, with its value. (material.cpp)
mr_status validate_materials(const mr_gltf *g, const char *text, const json_span &span);

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
