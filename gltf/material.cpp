// material.cpp — materials, textures, images, samplers and the extensions lists of the glTF shim (contract in
// gltf/mr_gltf.h): mr_gltf_material to and from tinygltf's Material, its extensions kept as JSON Values.
#include "gltf/gltf_internal.hpp"

#include <limits.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

#include <algorithm>
#include <cmath>
#include <memory>


using namespace mr_gltf_internal;

namespace {

const char *const EXT_SPEC_GLOSS = "KHR_materials_pbrSpecularGlossiness";
const char *const EXT_SPECULAR = "KHR_materials_specular";
const char *const EXT_IOR = "KHR_materials_ior";
const char *const EXT_TRANSFORM = "KHR_texture_transform";

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

// ---- materials ---------------------------------------------------------------------------------------------

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

// Samplers: the file's GL numbers <-> mr_gltf_filter / mr_wrap (mr_gltf.h). -1 is glTF's "unset" in tinygltf.
const int gl_filters[MR_GLTF_FILTER_COUNT] = {-1, 9728, 9729, 9984, 9985, 9986, 9987};

mr_gltf_filter filter_of_gl(int gl) {
    for (int f = 1; f < MR_GLTF_FILTER_COUNT; f++)
        if (gl_filters[f] == gl) return (mr_gltf_filter)f;
    return MR_GLTF_FILTER_UNSET;
}

int gl_of_filter(mr_gltf_filter f) { return (unsigned)f < MR_GLTF_FILTER_COUNT ? gl_filters[f] : -1; }

mr_wrap wrap_of_gl(int gl) { return gl == 33071 ? MR_WRAP_CLAMP : gl == 33648 ? MR_WRAP_MIRROR : MR_WRAP_REPEAT; }

int gl_of_wrap(mr_wrap w) { return w == MR_WRAP_CLAMP ? 33071 : w == MR_WRAP_MIRROR ? 33648 : 10497; }

// ---- validating the file's materials (validate_materials) ------------------------------------------------------

// "a number", "an object", ... for messages.
std::string kind(const nlohmann::json &v) {
    switch (v.type()) {
    case nlohmann::json::value_t::object:
        return "an object";
    case nlohmann::json::value_t::array:
        return "an array";
    case nlohmann::json::value_t::string:
        return "a string";
    case nlohmann::json::value_t::boolean:
        return "a boolean";
    case nlohmann::json::value_t::null:
        return "null";
    default:
        return "a number";
    }
}

// One material's checks; every failure names the material and the field (a path such as
// "extensions.KHR_materials_pbrSpecularGlossiness.diffuseTexture.index").
struct material_check {
    const mr_gltf *g;
    std::string where; // "glTF 'x.gltf': material 2 ('Glass')"

    mr_status fail(const std::string &field, const std::string &why) const {
        if (field.empty())
            return mr_fail(MR_ERR_FORMAT, "%s: %s", where.c_str(), why.c_str());
        return mr_fail(MR_ERR_FORMAT, "%s: %s %s", where.c_str(), field.c_str(), why.c_str());
    }

    // A number within [lo, hi] (finite: JSON has no NaN, but 1e999 parses as infinity).
    mr_status number(const nlohmann::json &v, const std::string &field, double lo, double hi) const {
        if (!v.is_number())
            return fail(field, "is " + kind(v) + ", not a number");
        const double x = v.get<double>();
        char text[64];
        snprintf(text, sizeof text, "%.17g", x);
        if (!std::isfinite(x))
            return fail(field, std::string("is ") + text + ", not a finite number");
        if (x < lo || x > hi) {
            char range[96];
            if (std::isinf(hi))
                snprintf(range, sizeof range, "at least %g", lo);
            else
                snprintf(range, sizeof range, "within [%g, %g]", lo, hi);
            return fail(field, std::string("is ") + text + ", expected " + range);
        }
        return MR_OK;
    }

    // An array of exactly n numbers, each within [lo, hi].
    mr_status numbers(const nlohmann::json &v, const std::string &field, size_t n, double lo, double hi) const {
        if (!v.is_array())
            return fail(field, "is " + kind(v) + ", not an array of " + std::to_string(n) + " numbers");
        if (v.size() != n)
            return fail(field, "has " + std::to_string(v.size()) + " values, expected " + std::to_string(n));
        for (size_t i = 0; i < n; i++) {
            mr_status s = number(v[i], field + "[" + std::to_string(i) + "]", lo, hi);
            if (s != MR_OK)
                return s;
        }
        return MR_OK;
    }

    // A non-negative integer below `limit`, which names one of `limit` elements of `what` (NULL: a plain number,
    // limit INT_MAX as tinygltf keeps it in an int).
    mr_status index(const nlohmann::json &v, const std::string &field, size_t limit, const char *what) const {
        if (!v.is_number_integer())
            return fail(field, "is " + (v.is_number() ? std::string("not an integer") : kind(v)) +
                                   ", expected a non-negative integer");
        if (!v.is_number_unsigned())
            return fail(field, "is " + std::to_string(v.get<int64_t>()) + ", expected a non-negative integer");
        const uint64_t x = v.get<uint64_t>();
        if (x >= limit)
            return fail(field, "is " + std::to_string(x) +
                                   (what != NULL ? ": no such " + std::string(what) + " (the asset has " +
                                                       std::to_string(limit) + ")"
                                                 : ", more than " + std::to_string(limit - 1)));
        return MR_OK;
    }

    // An "extensions" value: an object whose every value is an object (glTF's schema for extensions; tinygltf
    // drops those that are not, which would make the material read as if it had none).
    mr_status extensions(const nlohmann::json &v, const std::string &field) const {
        if (!v.is_object())
            return fail(field, "is " + kind(v) + ", not a JSON object");
        for (auto it = v.begin(); it != v.end(); ++it)
            if (!it.value().is_object())
                return fail(field + "." + it.key(), "is " + kind(it.value()) + ", not a JSON object");
        return MR_OK;
    }

    // A textureInfo (normalTextureInfo, occlusionTextureInfo: `extra` is their scale or strength, with its range).
    mr_status texture_info(const nlohmann::json &v, const std::string &field, const char *extra = NULL, double lo = 0,
                           double hi = 0) const {
        if (!v.is_object())
            return fail(field, "is " + kind(v) + ", not a JSON object");
        if (!v.contains("index"))
            return fail(field, "has no index");
        mr_status s = index(v["index"], field + ".index", g->model.textures.size(), "texture");
        if (s == MR_OK && v.contains("texCoord"))
            s = index(v["texCoord"], field + ".texCoord", INT_MAX, NULL);
        if (s == MR_OK && extra != NULL && v.contains(extra))
            s = number(v[extra], field + "." + extra, lo, hi);
        if (s == MR_OK && v.contains("extensions"))
            s = extensions(v["extensions"], field + ".extensions");
        if (s != MR_OK || !v.contains("extensions") || !v["extensions"].contains(EXT_TRANSFORM))
            return s;
        const nlohmann::json &t = v["extensions"][EXT_TRANSFORM];
        const std::string at = field + ".extensions." + EXT_TRANSFORM;
        const double inf = INFINITY;
        if (t.contains("offset"))
            s = numbers(t["offset"], at + ".offset", 2, -inf, inf);
        if (s == MR_OK && t.contains("rotation"))
            s = number(t["rotation"], at + ".rotation", -inf, inf);
        if (s == MR_OK && t.contains("scale"))
            s = numbers(t["scale"], at + ".scale", 2, -inf, inf);
        if (s == MR_OK && t.contains("texCoord"))
            s = index(t["texCoord"], at + ".texCoord", INT_MAX, NULL);
        return s;
    }

    // Optional members of object o: each present one checked by `check`.
    template <typename F>
    mr_status each(const nlohmann::json &o, std::initializer_list<const char *> keys, F check) const {
        for (const char *key : keys) {
            if (!o.contains(key))
                continue;
            mr_status s = check(o[key], std::string(key));
            if (s != MR_OK)
                return s;
        }
        return MR_OK;
    }

    mr_status material(const nlohmann::json &m) const {
        const double inf = INFINITY;
        mr_status s = MR_OK;
        if (m.contains("pbrMetallicRoughness")) {
            const nlohmann::json &pbr = m["pbrMetallicRoughness"];
            const std::string at = "pbrMetallicRoughness";
            if (!pbr.is_object())
                return fail(at, "is " + kind(pbr) + ", not a JSON object");
            if (pbr.contains("baseColorFactor"))
                s = numbers(pbr["baseColorFactor"], at + ".baseColorFactor", 4, 0, 1);
            if (s == MR_OK)
                s = each(pbr, {"metallicFactor", "roughnessFactor"},
                         [&](const nlohmann::json &v, const std::string &k) { return number(v, at + "." + k, 0, 1); });
            if (s == MR_OK)
                s = each(pbr, {"baseColorTexture", "metallicRoughnessTexture"},
                         [&](const nlohmann::json &v, const std::string &k) { return texture_info(v, at + "." + k); });
            if (s == MR_OK && pbr.contains("extensions"))
                s = extensions(pbr["extensions"], at + ".extensions");
            if (s != MR_OK)
                return s;
        }
        if (m.contains("normalTexture"))
            s = texture_info(m["normalTexture"], "normalTexture", "scale", -inf, inf);
        if (s == MR_OK && m.contains("occlusionTexture"))
            s = texture_info(m["occlusionTexture"], "occlusionTexture", "strength", 0, 1);
        if (s == MR_OK && m.contains("emissiveTexture"))
            s = texture_info(m["emissiveTexture"], "emissiveTexture");
        if (s == MR_OK && m.contains("emissiveFactor"))
            s = numbers(m["emissiveFactor"], "emissiveFactor", 3, 0, 1);
        if (s == MR_OK && m.contains("alphaMode")) {
            const nlohmann::json &mode = m["alphaMode"];
            if (!mode.is_string())
                return fail("alphaMode", "is " + kind(mode) + ", not a string");
            const std::string v = mode.get<std::string>();
            if (v != "OPAQUE" && v != "MASK" && v != "BLEND")
                return fail("alphaMode", "is '" + v + "', expected OPAQUE, MASK or BLEND");
        }
        if (s == MR_OK && m.contains("alphaCutoff"))
            s = number(m["alphaCutoff"], "alphaCutoff", 0, inf);
        if (s == MR_OK && m.contains("doubleSided") && !m["doubleSided"].is_boolean())
            return fail("doubleSided", "is " + kind(m["doubleSided"]) + ", not a boolean");
        if (s == MR_OK && m.contains("name") && !m["name"].is_string())
            return fail("name", "is " + kind(m["name"]) + ", not a string");
        if (s != MR_OK || !m.contains("extensions"))
            return s;
        const nlohmann::json &exts = m["extensions"];
        s = extensions(exts, "extensions");
        if (s == MR_OK && exts.contains(EXT_SPEC_GLOSS)) {
            const nlohmann::json &e = exts[EXT_SPEC_GLOSS];
            const std::string at = std::string("extensions.") + EXT_SPEC_GLOSS;
            if (e.contains("diffuseFactor"))
                s = numbers(e["diffuseFactor"], at + ".diffuseFactor", 4, 0, 1);
            if (s == MR_OK && e.contains("specularFactor"))
                s = numbers(e["specularFactor"], at + ".specularFactor", 3, 0, 1);
            if (s == MR_OK && e.contains("glossinessFactor"))
                s = number(e["glossinessFactor"], at + ".glossinessFactor", 0, 1);
            if (s == MR_OK)
                s = each(e, {"diffuseTexture", "specularGlossinessTexture"},
                         [&](const nlohmann::json &v, const std::string &k) { return texture_info(v, at + "." + k); });
        }
        if (s == MR_OK && exts.contains(EXT_SPECULAR)) {
            const nlohmann::json &e = exts[EXT_SPECULAR];
            const std::string at = std::string("extensions.") + EXT_SPECULAR;
            if (e.contains("specularFactor"))
                s = number(e["specularFactor"], at + ".specularFactor", 0, 1);
            if (s == MR_OK && e.contains("specularColorFactor"))
                s = numbers(e["specularColorFactor"], at + ".specularColorFactor", 3, 0, inf);
            if (s == MR_OK)
                s = each(e, {"specularTexture", "specularColorTexture"},
                         [&](const nlohmann::json &v, const std::string &k) { return texture_info(v, at + "." + k); });
        }
        if (s == MR_OK && exts.contains(EXT_IOR) && exts[EXT_IOR].contains("ior")) {
            const nlohmann::json &ior = exts[EXT_IOR]["ior"];
            const std::string at = std::string("extensions.") + EXT_IOR + ".ior";
            // KHR_materials_ior: at least 1, or 0 (a thin-walled limit the extension allows).
            if (!(ior.is_number() && ior.get<double>() == 0.0))
                s = number(ior, at, 1, inf);
        }
        return s;
    }
};

} // namespace

namespace mr_gltf_internal {

mr_status validate_materials(const mr_gltf *g, const char *text, const json_span &span) {
    const tinygltf::Model &model = g->model;
    for (size_t t = 0; t < model.textures.size(); t++) {
        const tinygltf::Texture &tex = model.textures[t];
        if (tex.source < -1 || tex.source >= (int)model.images.size())
            return mr_fail(MR_ERR_FORMAT, "glTF '%s': texture %zu: source %d: no such image (the asset has %zu)",
                           g->path.c_str(), t, tex.source, model.images.size());
        if (tex.sampler < -1 || tex.sampler >= (int)model.samplers.size())
            return mr_fail(MR_ERR_FORMAT, "glTF '%s': texture %zu: sampler %d: no such sampler (the asset has %zu)",
                           g->path.c_str(), t, tex.sampler, model.samplers.size());
    }
    if (!span.found)
        return MR_OK;
    nlohmann::json materials = nlohmann::json::parse(text + span.begin, text + span.end, nullptr, false);
    if (materials.is_discarded() || !materials.is_array())
        return mr_fail(MR_ERR_FORMAT, "glTF '%s': materials is %s, not an array", g->path.c_str(),
                       materials.is_discarded() ? "not valid JSON" : kind(materials).c_str());
    for (size_t k = 0; k < materials.size(); k++) {
        const nlohmann::json &m = materials[k];
        material_check check{g, "glTF '" + g->path + "': material " + std::to_string(k)};
        if (!m.is_object())
            return check.fail("", "is " + kind(m) + ", not a JSON object");
        if (m.contains("name") && m["name"].is_string())
            check.where += " ('" + m["name"].get<std::string>() + "')";
        mr_status s = check.material(m);
        if (s != MR_OK)
            return s;
    }
    return MR_OK;
}

} // namespace mr_gltf_internal

// ---- the C API -------------------------------------------------------------------------------------------

extern "C" {

// mr_gltf_texture_ref_none and mr_gltf_material_defaults are C (material_defaults.c): no module needed.

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

mr_status mr_gltf_create(const char *label, mr_gltf **out) {
    if (out == NULL) return mr_fail(MR_ERR_INVALID_ARG, "glTF: NULL output");
    *out = NULL;
    MR_GLTF_GUARD(label ? label : "glTF", {
        std::unique_ptr<mr_gltf> g(new mr_gltf());
        g->path = label ? label : "";
        g->base_dir = ".";
        g->model.asset.version = "2.0";
        g->model.asset.generator = "matremap";
        g->original_parsed = true; // no JSON was read: nothing to merge on save
        *out = g.release();
        return MR_OK;
    })
}

mr_status mr_gltf_add_material(mr_gltf *g, const mr_gltf_material *in, int *out_material) {
    if (g == NULL || in == NULL) return mr_fail(MR_ERR_INVALID_ARG, "glTF: NULL asset or material");
    MR_GLTF_GUARD(g->path.c_str(), {
        g->model.materials.emplace_back();
        int index = (int)g->model.materials.size() - 1;
        mr_status s = set_material_impl(g, index, in);
        if (s != MR_OK) {
            g->model.materials.pop_back();
            return s;
        }
        if (out_material) *out_material = index;
        return MR_OK;
    })
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
    r.params.mag_filter = r.params.min_filter = MR_GLTF_FILTER_UNSET;
    r.params.wrap_s = r.params.wrap_t = MR_WRAP_REPEAT;
    if (t.sampler >= 0 && t.sampler < (int)g->model.samplers.size()) {
        const tinygltf::Sampler &s = g->model.samplers[t.sampler];
        r.params.mag_filter = filter_of_gl(s.magFilter);
        r.params.min_filter = filter_of_gl(s.minFilter);
        r.params.wrap_s = wrap_of_gl(s.wrapS);
        r.params.wrap_t = wrap_of_gl(s.wrapT);
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
            for (const auto &p : g->source_files) {
                if (real == real_path(p)) goto is_input;
            }
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
                if (s.magFilter == gl_of_filter(sampler->mag_filter) &&
                    s.minFilter == gl_of_filter(sampler->min_filter) && s.wrapS == gl_of_wrap(sampler->wrap_s) &&
                    s.wrapT == gl_of_wrap(sampler->wrap_t) && s.name.empty() &&
                    s.extras.Type() == tinygltf::NULL_TYPE && s.extensions.empty())
                    found = (int)i;
            }
            if (found < 0) {
                tinygltf::Sampler s;
                s.magFilter = gl_of_filter(sampler->mag_filter);
                s.minFilter = gl_of_filter(sampler->min_filter);
                s.wrapS = gl_of_wrap(sampler->wrap_s);
                s.wrapT = gl_of_wrap(sampler->wrap_t);
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

} // extern "C"
