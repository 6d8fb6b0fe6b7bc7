// load_save.cpp — the glTF shim's file I/O (contract in gltf/mr_gltf.h, coverage in gltf/README.md): loading
// through tinygltf 2.7 with images kept undecoded (its image loader callback stores the encoded bytes), saving
// .gltf and .glb (GLB packing), and restoring what tinygltf's writer drops from the file's own JSON. tinygltf's
// file writer is neither atomic nor careful about input files, so the shim serialises to memory, fixes up the
// buffers[] and images[] entries, and writes every file through the project's atomic-file protocol.
#include "gltf/gltf_internal.hpp"

#include <errno.h>
#include <stdint.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <memory>
#include <set>
#include <sstream>


using namespace mr_gltf_internal;

namespace {

// ---- small helpers ------------------------------------------------------------------------------------

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

// tinygltf's image callback: keep the encoded bytes, decode nothing. `user` is the model being loaded: tinygltf 2.7
// hands an image in a buffer view over as &buffer.data[byteOffset] with the view's byteLength, unchecked, so a view
// that runs past its buffer would be read past the buffer's end; it is checked here first.
bool keep_image_bytes(tinygltf::Image *image, const int index, std::string *err, std::string *, int, int,
                      const unsigned char *bytes, int size, void *user) {
    const tinygltf::Model *m = static_cast<const tinygltf::Model *>(user);
    if (image->bufferView >= 0) { // tinygltf has checked the view's and its buffer's index
        const tinygltf::BufferView &v = m->bufferViews[(size_t)image->bufferView];
        const tinygltf::Buffer &b = m->buffers[(size_t)v.buffer];
        if (v.byteOffset > b.data.size() || v.byteLength > b.data.size() - v.byteOffset ||
            v.byteLength > (size_t)INT_MAX) {
            if (err != NULL)
                *err += "image " + std::to_string(index) + ": buffer view " + std::to_string(image->bufferView) +
                        " (byteOffset " + std::to_string(v.byteOffset) + ", byteLength " +
                        std::to_string(v.byteLength) + ") runs past the end of buffer " + std::to_string(v.buffer) +
                        " (" + std::to_string(b.data.size()) + " bytes)\n";
            return false;
        }
        bytes = b.data.data() + v.byteOffset;
        size = (int)v.byteLength;
    }
    if (size < 0 || (size > 0 && bytes == NULL)) {
        if (err != NULL)
            *err += "image " + std::to_string(index) + ": no bytes\n";
        return false;
    }
    image->image.assign(bytes, bytes + size);
    image->as_is = true;
    image->width = image->height = image->component = image->bits = -1;
    if (image->mimeType.empty()) image->mimeType = sniff_mime(image->image);
    return true;
}

// tinygltf's file callbacks (tinygltf::FsCallbacks), replacing its own: its FileExists fopen()s the file, which
// blocks on a FIFO; its ReadWholeFile takes the size of a folder (2^63 - 1 on ext4) and allocates it; and a file it
// does not find beside the asset it looks for in the working directory. These look beside the asset only, and
// read regular files only (read_file), recording why the last read failed so that the message can name the buffer.
struct fs_context {
    std::string prefix; // what every path tinygltf asks for starts with: the asset's directory and '/'
    std::string failed; // the last file that could not be read, and why (mr_last_error() then)
    std::string why;
    mr_status status = MR_OK;
};

bool fs_exists(const std::string &path, void *user) {
    const fs_context *ctx = static_cast<const fs_context *>(user);
    struct stat st;
    return path.compare(0, ctx->prefix.size(), ctx->prefix) == 0 && stat(path.c_str(), &st) == 0;
}

std::string fs_expand(const std::string &path, void *) { return path; }

bool fs_read(std::vector<unsigned char> *out, std::string *err, const std::string &path, void *user) {
    fs_context *ctx = static_cast<fs_context *>(user);
    std::vector<unsigned char> bytes;
    mr_status s = read_file(path, &bytes, NULL);
    if (s != MR_OK) {
        ctx->failed = path;
        ctx->status = s;
        ctx->why = mr_last_error();
        if (err != NULL)
            *err += ctx->why;
        return false;
    }
    out->swap(bytes);
    return true;
}

bool fs_write(std::string *err, const std::string &, const std::vector<unsigned char> &, void *) {
    if (err != NULL)
        *err += "the glTF shim writes files itself";
    return false;
}

// The last non-empty line of tinygltf's error text: it appends its fatal error last, after any complaints it
// recorded and went on from.
std::string last_line(const std::string &s) {
    std::string t = s;
    while (!t.empty() && (t.back() == '\n' || t.back() == '\r'))
        t.pop_back();
    size_t nl = t.find_last_of('\n');
    return nl == std::string::npos ? t : t.substr(nl + 1);
}

// tinygltf's image writer callback: write nothing (the shim writes images itself).
bool skip_image_write(const std::string *, const std::string *, const tinygltf::Image *, bool, std::string *,
                      void *) {
    return false;
}

// ---- restoring what tinygltf's writer drops; GLB packing -------------------------------------------------

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

// tinygltf 2.7 fills in bufferView.target from the meshes' use of each view when it loads; the file's own is
// kept (absent stays absent), so that a round trip does not add fields.
void drop_inferred_targets(nlohmann::json &doc, const nlohmann::json &orig) {
    if (!orig.is_object() || !orig.contains("bufferViews") || !orig["bufferViews"].is_array()) return;
    if (!doc.contains("bufferViews") || !doc["bufferViews"].is_array()) return;
    const nlohmann::json &views = orig["bufferViews"];
    nlohmann::json &out = doc["bufferViews"];
    for (size_t i = 0; i < views.size() && i < out.size(); i++) {
        if (views[i].is_object() && !views[i].contains("target") && out[i].is_object()) out[i].erase("target");
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
    std::string what;                // "buffer 0", "image 3": how messages name it
    std::string rel;                 // relative path under the output directory (decoded)
    const std::vector<unsigned char> *bytes;
    std::string source;              // real path of the file these bytes came from, "" if none
    std::string target;              // full path
    bool skip = false;               // the target is this resource's own unchanged source
    bool created = false;            // written by this save where no file was: removed if the save fails
};

std::string with_suffix(const std::string &rel, int n) {
    size_t slash = rel.find_last_of('/');
    size_t dot = rel.find_last_of('.');
    if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) dot = rel.size();
    return rel.substr(0, dot) + "_" + std::to_string(n) + rel.substr(dot);
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
    std::string made = dir; // copied before mkdir: recording it after cannot fail (the caller reserved the room)
    if (mkdir(dir.c_str(), 0777) != 0 && errno != EEXIST)
        return mr_fail(MR_ERR_IO, "output directory '%s': cannot create: %s", dir.c_str(), strerror(errno));
    created->push_back(std::move(made));
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

// The side file name `rel` (relative, decoded) of a resource under the naming after the output (stem STEM): the same
// folder, its file name prefixed "STEM_" unless it already starts so (a converted texture, or the file of an
// earlier output of the same name).
std::string named_after(const std::string &stem, const std::string &rel) {
    size_t slash = rel.find_last_of('/');
    std::string dir = slash == std::string::npos ? "" : rel.substr(0, slash + 1);
    std::string name = slash == std::string::npos ? rel : rel.substr(slash + 1);
    if (name.compare(0, stem.size() + 1, stem + "_") == 0) return rel;
    return dir + stem + "_" + name;
}

// The files an existing glTF at `out_path` refers to by URI (buffers and images; data URIs and URIs that leave its
// folder aside), as canonical paths of existing files: the side files of the output a save replaces, which it may
// replace too. Empty when there is no such file or it is not a glTF (unreadable, not JSON, nested too deep).
std::set<std::string> files_of_existing_output(const std::string &out_path, const std::string &out_dir) {
    std::set<std::string> owned;
    struct stat st;
    if (stat(out_path.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) return owned;
    std::vector<unsigned char> bytes;
    if (read_file(out_path, &bytes, NULL) != MR_OK) return owned;
    const char *text = (const char *)bytes.data();
    size_t n = bytes.size(), base = 0;
    if (n >= 4 && memcmp(text, "glTF", 4) == 0) { // a .glb: its JSON chunk
        if (n < 20 || memcmp(text + 16, "JSON", 4) != 0) return owned;
        uint32_t len = (uint32_t)bytes[12] | (uint32_t)bytes[13] << 8 | (uint32_t)bytes[14] << 16 |
                       (uint32_t)bytes[15] << 24;
        if (len > n - 20) return owned;
        text += 20;
        n = len;
        base = 20;
    }
    json_span materials;
    if (n == 0 || scan_json(text, n, base, out_path, &materials) != MR_OK) return owned; // bounded nesting first
    nlohmann::json doc = nlohmann::json::parse(text, text + n, nullptr, false);
    if (!doc.is_object()) return owned;
    for (const char *key : {"buffers", "images"}) {
        if (!doc.contains(key) || !doc[key].is_array()) continue;
        for (const nlohmann::json &o : doc[key]) {
            if (!o.is_object() || !o.contains("uri") || !o["uri"].is_string()) continue;
            const std::string uri = o["uri"].get<std::string>();
            const std::string decoded = url_decode(uri);
            if (is_data_uri(uri) || !is_safe_relative(decoded)) continue;
            std::string real = real_path(join_path(out_dir, decoded));
            if (!real.empty()) owned.insert(real);
        }
    }
    return owned;
}

bool ends_with(const std::string &s, const char *suffix) {
    size_t n = strlen(suffix);
    if (s.size() < n) return false;
    return strcasecmp(s.c_str() + s.size() - n, suffix) == 0;
}

mr_status save_impl(mr_gltf *g, const char *path_c, const mr_gltf_save_options &opts) {
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
    for (const auto &p : g->source_files) inputs.insert(real_path(p)); // pruned images' files included
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

    const nlohmann::json &original = original_json(g);
    drop_inferred_targets(doc, original);
    merge_original(doc, original);

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
        f.what = "buffer " + std::to_string(i);
        f.bytes = &buf.data;
        std::string decoded = url_decode(buf.uri);
        const std::string own_name = stem + (i == 0 ? "" : "_" + std::to_string(i)) + ".bin";
        if (!buf.uri.empty() && is_safe_relative(decoded)) {
            f.rel = decoded;
            if (opts.name_after_output) {
                size_t slash = decoded.find_last_of('/');
                f.rel = (slash == std::string::npos ? "" : decoded.substr(0, slash + 1)) + own_name;
            }
            f.source = real_path(g->buffer_paths[i]);
        } else {
            f.rel = own_name;
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
        f.what = "image " + std::to_string(i);
        f.bytes = &im.image;
        std::string decoded = url_decode(im.uri);
        f.rel = is_safe_relative(decoded) ? decoded : "image_" + std::to_string(i) + "." +
                                                          (im.mimeType == "image/jpeg" ? "jpg" : "png");
        if (opts.name_after_output) f.rel = named_after(stem, f.rel);
        f.source = real_path(g->image_paths[i]);
        uri_slots.push_back({&o, files.size()});
        files.push_back(f);
    }

    // Targets: an unchanged resource landing on its own source stays; one landing on another input file, on
    // the output itself or on another resource's target gets a fresh name. One landing on any other existing file
    // is refused (nothing written) unless that file belongs to the output being replaced (the existing file at
    // `path` refers to it) or opts.replace_files.
    const std::set<std::string> owned = opts.replace_files ? std::set<std::string>()
                                                           : files_of_existing_output(out_path, out_dir);
    const pending_file *refused = NULL;
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
            if (!real.empty() && !opts.replace_files && !owned.count(real) && refused == NULL) refused = &f;
            break;
        }
    }
    if (refused != NULL) {
        const char *hint = opts.replace_hint != NULL && opts.replace_hint[0] ? opts.replace_hint : "replace_files";
        return mr_fail(MR_ERR_INVALID_ARG, "glTF output '%s': its %s would be written to '%s', which exists and is "
                       "not a file of an earlier '%s' (another asset's, perhaps); refusing to replace it (%s allows "
                       "it)", out_path.c_str(), refused->what.c_str(), refused->target.c_str(), out_path.c_str(), hint);
    }
    for (auto &slot : uri_slots) (*slot.first)["uri"] = uri_encode_spaces(files[slot.second].rel);

    std::string json_text = binary ? doc.dump() : doc.dump(2) + "\n";
    std::vector<unsigned char> main_bytes;
    if (binary) main_bytes = make_glb(json_text, glb_bin);
    else main_bytes.assign(json_text.begin(), json_text.end());

    // Write the resources, then the main file; on failure, a status or an exception (out of memory), remove what
    // this call created. The record of it allocates nothing once writing has begun (flags in `files`, the folders'
    // room reserved: at most one per '/' of the targets), so the clean-up knows everything it must remove.
    std::vector<std::string> created_dirs;
    size_t depth = 0;
    for (const pending_file &f : files)
        depth += (size_t)std::count(f.target.begin(), f.target.end(), '/');
    created_dirs.reserve(depth);
    auto clean_up = [&files, &created_dirs]() {
        for (const pending_file &f : files)
            if (f.created)
                unlink(f.target.c_str());
        for (auto it = created_dirs.rbegin(); it != created_dirs.rend(); ++it)
            rmdir(it->c_str());
    };
    mr_status status = MR_OK;
    try {
        for (pending_file &f : files) {
            if (f.skip)
                continue;
            status = make_dirs(dir_of(f.target), &created_dirs);
            if (status != MR_OK)
                break;
            struct stat st;
            bool existed = stat(f.target.c_str(), &st) == 0;
            status = mr_atomic_write_bytes(f.target.c_str(), f.bytes->data(), f.bytes->size());
            if (status != MR_OK)
                break;
            f.created = !existed;
        }
        if (status == MR_OK)
            status = mr_atomic_write_bytes(out_path.c_str(), main_bytes.data(), main_bytes.size());
    } catch (...) {
        clean_up();
        throw;
    }
    if (status != MR_OK) {
        clean_up();
        return mr_fail_context(status, "glTF output '%s'", out_path.c_str());
    }
    return MR_OK;
}


// ---- loading -------------------------------------------------------------------------------------------

mr_status load_impl(const char *path_c, mr_gltf **out) {
    const std::string path = path_c;
    std::vector<unsigned char> bytes;
    mr_status s = read_file(path, &bytes, "glTF");
    if (s != MR_OK) return s;

    // The JSON: the whole file, or a .glb's JSON chunk (when its header says where that is; tinygltf refuses it
    // otherwise). Its nesting is bounded before tinygltf parses it (scan_json).
    const bool is_glb = bytes.size() >= 4 && memcmp(bytes.data(), "glTF", 4) == 0;
    const char *text = (const char *)bytes.data();
    size_t text_size = bytes.size(), text_base = 0;
    if (is_glb) {
        text_size = 0;
        if (bytes.size() >= 20 && memcmp(bytes.data() + 16, "JSON", 4) == 0) {
            uint32_t len =
                (uint32_t)bytes[12] | (uint32_t)bytes[13] << 8 | (uint32_t)bytes[14] << 16 | (uint32_t)bytes[15] << 24;
            if (len <= bytes.size() - 20)
                text_size = len;
            text += 20;
            text_base = 20;
        }
    }
    json_span materials;
    if (text_size > 0) {
        s = scan_json(text, text_size, text_base, path, &materials);
        if (s != MR_OK)
            return s;
    }

    std::unique_ptr<mr_gltf> g(new mr_gltf()); // released to the caller on success, freed on any other way out
    g->path = path;
    g->base_dir = dir_of(path);
    tinygltf::TinyGLTF loader;
    loader.SetImageLoader(keep_image_bytes, &g->model);
    fs_context fs;
    fs.prefix = g->base_dir.back() == '/' ? g->base_dir : g->base_dir + "/";
    loader.SetFsCallbacks(tinygltf::FsCallbacks{fs_exists, fs_expand, fs_read, fs_write, &fs});
    std::string err, warn;
    bool ok;
    try {
        if (is_glb) {
            ok = loader.LoadBinaryFromMemory(&g->model, &err, &warn, bytes.data(), (unsigned)bytes.size(), g->base_dir);
        } else {
            ok = loader.LoadASCIIFromString(&g->model, &err, &warn, (const char *)bytes.data(), (unsigned)bytes.size(),
                                            g->base_dir);
        }
    } catch (const std::bad_alloc &) {
        throw;
    } catch (const std::exception &e) {
        // tinygltf 2.7 throws on some malformed files (a GLB buffer of byteLength 0: std::vector::at).
        return mr_fail(MR_ERR_FORMAT, "glTF '%s': malformed (tinygltf threw: %s)", path.c_str(), e.what());
    }
    if (!ok) {
        // tinygltf turns exceptions into its error text, std::bad_alloc included: out of memory is not bad input.
        if (err.find("bad_alloc") != std::string::npos)
            return mr_fail(MR_ERR_NOMEM, "glTF '%s': out of memory", path.c_str());
        // A buffer that could not be read: buffers are parsed first, and appended one by one, so the one that
        // failed is the next one.
        const size_t buffer = g->model.buffers.size();
        auto relative = [&](const std::string &p) {
            return p.compare(0, fs.prefix.size(), fs.prefix) == 0 ? p.substr(fs.prefix.size()) : p;
        };
        if (fs.status != MR_OK && err.find(fs.failed) != std::string::npos)
            return mr_fail(fs.status, "glTF '%s': buffer %zu ('%s'): %s", path.c_str(), buffer,
                           relative(fs.failed).c_str(), fs.why.c_str());
        const std::string not_found = "File not found : ";
        size_t at = err.find(not_found);
        if (at != std::string::npos) {
            std::string name = err.substr(at + not_found.size());
            name = name.substr(0, name.find('\n'));
            return mr_fail(MR_ERR_IO, "glTF '%s': buffer %zu ('%s'): not found (looked up relative to '%s')",
                           path.c_str(), buffer, name.c_str(), g->base_dir.c_str());
        }
        mr_status code = err.find("Failed to load") != std::string::npos ? MR_ERR_IO : MR_ERR_FORMAT;
        std::string why = last_line(err.empty() ? warn : err);
        if (why.empty()) why = is_glb ? "not a valid binary glTF" : "not a valid glTF";
        if (why.compare(0, 15, "[json.exception") == 0)
            why = "invalid JSON: " + why;
        if (code == MR_ERR_IO) why += " (resources are looked up relative to '" + g->base_dir + "')";
        else if (is_glb && (why.find("binary") != std::string::npos || why.find("Chunk") != std::string::npos))
            why += " (" + std::to_string(bytes.size()) + " bytes read; truncated?)";
        return mr_fail(code, "glTF '%s': %s", path.c_str(), why.c_str());
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
            // tinygltf goes on without an image it cannot read: say why, naming the asset, the image and its URI.
            std::vector<unsigned char> probe;
            mr_status rs = read_file(p, &probe, NULL);
            std::string why = rs != MR_OK ? mr_last_error() : "is empty";
            if (rs == MR_OK)
                rs = MR_ERR_FORMAT;
            return mr_fail(rs, "glTF '%s': image %zu ('%s'): %s", path.c_str(), i, im.uri.c_str(), why.c_str());
        }
        g->image_paths.push_back(p);
    }
    s = validate_materials(g.get(), text, materials);
    if (s != MR_OK)
        return s;
    // The JSON text is kept for what tinygltf drops, and parsed only if it is needed (original_json).
    g->original_text.assign(text, text_size);
    g->source_files.push_back(g->path);
    for (const std::vector<std::string> *list : {&g->buffer_paths, &g->image_paths})
        for (const std::string &p : *list)
            if (!p.empty()) g->source_files.push_back(p);
    *out = g.release();
    return MR_OK;
}

} // namespace

// ---- the C API -------------------------------------------------------------------------------------------

extern "C" {

mr_status mr_gltf_load(const char *path, mr_gltf **out) {
    if (path == NULL || path[0] == '\0' || out == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "glTF: empty path or NULL output");
    MR_GLTF_GUARD(path, return load_impl(path, out);)
}

void mr_gltf_free(mr_gltf *asset) { delete asset; }

const char *mr_gltf_path(const mr_gltf *asset) { return asset ? asset->path.c_str() : ""; }

const char *mr_gltf_source_file(const mr_gltf *asset, int k) {
    if (asset == NULL || k < 0 || (size_t)k >= asset->source_files.size()) return NULL;
    return asset->source_files[(size_t)k].c_str();
}

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

mr_status mr_gltf_save(mr_gltf *g, const char *path) {
    if (g == NULL || path == NULL || path[0] == '\0')
        return mr_fail(MR_ERR_INVALID_ARG, "glTF: NULL asset or empty output path");
    mr_gltf_save_options opts = {0, 1, NULL}; // names as read; existing files replaced (as before the options)
    MR_GLTF_GUARD(path, return save_impl(g, path, opts);)
}

mr_status mr_gltf_save_with(mr_gltf *g, const char *path, const mr_gltf_save_options *opts) {
    if (g == NULL || path == NULL || path[0] == '\0')
        return mr_fail(MR_ERR_INVALID_ARG, "glTF: NULL asset or empty output path");
    mr_gltf_save_options o = {0, 0, NULL};
    if (opts != NULL) o = *opts;
    MR_GLTF_GUARD(path, return save_impl(g, path, o);)
}

} // extern "C"
