/*
 * doc_convert.c — a document's materials converted to another model (doc.h: mr_doc_convert) and its map files
 * rebased to another folder (mr_doc_rebase).
 */
#include "doc/doc.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "doc/doc_internal.h"
#include "io/image_io.h"
#include "mr_internal.h"
#include "render/render.h"

/* ---- paths ------------------------------------------------------------------------------------------------- */

/* `path` made lexically normal in place: "//" and "/./" collapsed, "dir/.." removed (a leading ".." of a relative
 * path kept). */
static void normalize(char *path) {
    int absolute = path[0] == '/';
    char *parts[512];
    int n = 0;
    char *save = NULL;
    char copy[4096];
    snprintf(copy, sizeof copy, "%s", path);
    for (char *t = strtok_r(copy, "/", &save); t && n < 512; t = strtok_r(NULL, "/", &save)) {
        if (strcmp(t, ".") == 0) continue;
        if (strcmp(t, "..") == 0 && n > 0 && strcmp(parts[n - 1], "..") != 0) {
            n--;
            continue;
        }
        if (strcmp(t, "..") == 0 && absolute) continue;
        parts[n++] = t;
    }
    char out[4096];
    size_t used = 0;
    out[0] = '\0';
    if (absolute) used += (size_t)snprintf(out, sizeof out, "/");
    for (int i = 0; i < n && used < sizeof out; i++)
        used += (size_t)snprintf(out + used, sizeof out - used, "%s%s", i ? "/" : "", parts[i]);
    if (!absolute && n == 0) snprintf(out, sizeof out, ".");
    snprintf(path, 4096, "%s", out);
}

/* The absolute, normal folder of document `doc` into out (4096 bytes); 0 if it does not fit. */
static int folder_of(const char *doc, char *out) {
    char cwd[4096] = "";
    if (doc[0] != '/' && getcwd(cwd, sizeof cwd) == NULL) return 0;
    char joined[8192];
    snprintf(joined, sizeof joined, "%s%s%s", cwd, cwd[0] ? "/" : "", doc);
    char *slash = strrchr(joined, '/');
    if (slash) *slash = '\0';
    const size_t len = strlen(joined);
    if (len >= 4096) return 0;
    if (len == 0) memcpy(out, "/", 2);
    else memcpy(out, joined, len + 1); // a copy, not snprintf: gcc -O1 cannot see the length check above
    normalize(out);
    return 1;
}

/* The folders of an absolute normal path (strtok_r over a copy in buf). */
static int split(const char *path, char *buf, size_t size, char **parts, int max) {
    snprintf(buf, size, "%s", path);
    int n = 0;
    char *save = NULL;
    for (char *t = strtok_r(buf, "/", &save); t && n < max; t = strtok_r(NULL, "/", &save)) parts[n++] = t;
    return n;
}

/* `target` (absolute, normal) named relative to folder `folder` (absolute, normal). */
static void relative_path(const char *folder, const char *target, char *out, size_t size) {
    char fb[4096], tb[4096];
    char *f[512], *t[512];
    int nf = split(folder, fb, sizeof fb, f, 512), nt = split(target, tb, sizeof tb, t, 512);
    int common = 0;
    while (common < nf && common < nt - 1 && strcmp(f[common], t[common]) == 0) common++;
    size_t used = 0;
    out[0] = '\0';
    for (int i = common; i < nf && used < size; i++) used += (size_t)snprintf(out + used, size - used, "../");
    for (int i = common; i < nt && used < size; i++)
        used += (size_t)snprintf(out + used, size - used, "%s%s", t[i], i + 1 < nt ? "/" : "");
}

/* v->file replaced by `file` (under folder `at`, absolute and normal) named relative to folder `to`. MR_ERR_INVALID_ARG
 * (`what` naming the map) when the joined path does not fit; MR_ERR_NOMEM. */
static mr_status set_relative_file(mr_doc_value *v, const char *at, const char *file, const char *to,
                                   const char *what) {
    char target[8192], rel[8192];
    snprintf(target, sizeof target, "%s/%s", at, file);
    if (strlen(target) >= 4096) return mr_fail(MR_ERR_INVALID_ARG, "material document: %s: path too long", what);
    normalize(target);
    relative_path(to, target, rel, sizeof rel);
    const size_t len = strlen(rel) + 1;
    char *copy = malloc(len);
    if (copy == NULL) return mr_fail(MR_ERR_NOMEM, "material document: out of memory");
    memcpy(copy, rel, len);
    free(v->file);
    v->file = copy;
    return MR_OK;
}

mr_status mr_doc_rebase(mr_doc *doc, const char *from, const char *to) {
    if (doc == NULL || from == NULL || to == NULL) return mr_fail(MR_ERR_INVALID_ARG, "material document: rebase");
    char a[4096], b[4096];
    if (!folder_of(from, a) || !folder_of(to, b))
        return mr_fail(MR_ERR_INVALID_ARG, "material document: cannot name the folders of '%s' and '%s'", from, to);
    for (int k = 0; k < mr_doc_material_count(doc); k++) {
        mr_doc_material *m = mr_doc_material_at(doc, k);
        for (int p = 0; p < m->model->param_count; p++) {
            mr_doc_value *v = &m->values[p];
            if (v->kind != MR_DOC_TEXTURE || v->file[0] == '/') continue;
            char what[640];
            snprintf(what, sizeof what, "map '%s' of material '%s'", v->file, m->name);
            mr_status st = set_relative_file(v, a, v->file, b, what);
            if (st != MR_OK) return st;
        }
    }
    return MR_OK;
}

/* ---- conversion -------------------------------------------------------------------------------------------- */

/* The material's packed values: the model's defaults, its constants over them. Textured parameters keep the
 * default (callers look at them apart). */
static void packed_values(const mr_doc_material *m, double *values) {
    mr_brdf_default_values(m->model, values);
    for (int p = 0; p < m->model->param_count; p++)
        if (m->values[p].kind == MR_DOC_CONSTANT)
            for (int c = 0; c < m->model->params[p].channels; c++)
                values[mr_brdf_param_offset(m->model, p) + c] = m->values[p].constant[c];
}

static int is_textured(const mr_doc_material *m) {
    for (int p = 0; p < m->model->param_count; p++)
        if (m->values[p].kind == MR_DOC_TEXTURE) return 1;
    return 0;
}

static mr_status copy_value(mr_doc_material *to, const char *param, const mr_doc_value *v) {
    if (v->kind == MR_DOC_UNSET) return MR_OK;
    if (v->kind == MR_DOC_CONSTANT) return mr_doc_set_constant(to, param, v->constant);
    mr_status st = mr_doc_set_texture(to, param, v->file, v->channel, v->uv_set, v->scale);
    if (st == MR_OK && (v->wrap_s || v->wrap_t)) st = mr_doc_set_texture_wrap(to, param, v->wrap_s, v->wrap_t);
    return st;
}

static const mr_doc_value *value_of(const mr_doc_material *m, const char *param) {
    int p = mr_brdf_param_index(m->model, param);
    return p >= 0 ? &m->values[p] : NULL;
}

/* A parameter constant at `want` (every channel) or unset with the model's default at it. */
static int at_value(const mr_doc_material *m, const char *param, double want) {
    int p = mr_brdf_param_index(m->model, param);
    if (p < 0) return 1;
    const mr_doc_value *v = &m->values[p];
    if (v->kind == MR_DOC_TEXTURE) return 0;
    double values[MR_BRDF_MAX_VALUES];
    packed_values(m, values);
    for (int c = 0; c < m->model->params[p].channels; c++)
        if (values[mr_brdf_param_offset(m->model, p) + c] != want) return 0;
    return 1;
}

/* The MAPS routes between models (mr_doc_choose_route decides; doc.h): maps carried unchanged where the parameters
 * are the same quantities. A route returns MR_OK having filled `to`, MR_ERR_UNSUPPORTED with the reason (why) when
 * the material has something the route cannot carry, and -1 when there is none (mr_doc_choose_route and this
 * disagree: an internal error). */
static int texture_route(const mr_doc_material *from, mr_doc_material *to, char *why, size_t size) {
    const char *a = from->model->name, *b = to->model->name;
    mr_status st = MR_OK;
    if (strcmp(a, "gltf") == 0 && strcmp(b, "usd-preview") == 0) {
        // gltf_export.c's carry_maps, for documents: base colour, metallic, roughness; ior a constant.
        const mr_doc_value *ior = value_of(from, "ior");
        if (!at_value(from, "specular", 1) || !at_value(from, "specular_color", 1)) {
            snprintf(why, size, "its specular and specular_color (KHR_materials_specular) have no place in "
                     "usd-preview's metallic workflow (--to gltf keeps them)");
            return MR_ERR_UNSUPPORTED;
        }
        if (ior->kind == MR_DOC_TEXTURE) {
            snprintf(why, size, "its ior is a map, which UsdPreviewSurface's ior cannot be");
            return MR_ERR_UNSUPPORTED;
        }
        double zero = 0;
        if ((st = mr_doc_set_constant(to, "use_specular_workflow", &zero)) != MR_OK ||
            (st = copy_value(to, "diffuse_color", value_of(from, "base_color"))) != MR_OK ||
            (st = copy_value(to, "metallic", value_of(from, "metallic"))) != MR_OK ||
            (st = copy_value(to, "roughness", value_of(from, "roughness"))) != MR_OK ||
            (st = copy_value(to, "ior", ior)) != MR_OK)
            return st;
        return MR_OK;
    }
    if (strcmp(a, "usd-preview") == 0 && strcmp(b, "gltf") == 0) {
        const mr_doc_value *ior = value_of(from, "ior");
        if (!at_value(from, "use_specular_workflow", 0) || !at_value(from, "clearcoat", 0) ||
            ior->kind == MR_DOC_TEXTURE) {
            snprintf(why, size, "only the metallic workflow without clearcoat and with a constant ior carries its "
                     "maps to gltf_pbr (useSpecularWorkflow 0, clearcoat 0)");
            return MR_ERR_UNSUPPORTED;
        }
        if ((st = copy_value(to, "base_color", value_of(from, "diffuse_color"))) != MR_OK ||
            (st = copy_value(to, "metallic", value_of(from, "metallic"))) != MR_OK ||
            (st = copy_value(to, "roughness", value_of(from, "roughness"))) != MR_OK ||
            (st = copy_value(to, "ior", ior)) != MR_OK)
            return st;
        // UsdPreviewSurface's defaults where the material leaves them (not gltf_pbr's metallic 1, roughness 1).
        double values[MR_BRDF_MAX_VALUES];
        packed_values(from, values);
        static const char *const pairs[][2] = {{"diffuse_color", "base_color"}, {"metallic", "metallic"},
                                               {"roughness", "roughness"}, {"ior", "ior"}};
        for (int i = 0; i < 4; i++)
            if (value_of(from, pairs[i][0])->kind == MR_DOC_UNSET &&
                (st = mr_doc_set_constant(to, pairs[i][1], values + mr_brdf_param_offset(
                                              from->model, mr_brdf_param_index(from->model, pairs[i][0])))) != MR_OK)
                return st;
        return MR_OK;
    }
    return -1;
}

/* The folder of the document (NULL: the current folder) as a prefix for its relative files: "" or "DIR/". */
static void document_folder(const char *document, char *out, size_t size) {
    const char *slash = document ? strrchr(document, '/') : NULL;
    snprintf(out, size, "%.*s", slash ? (int)(slash - document + 1) : 0, slash ? document : "");
}

/* Textured material `src` as a material of its model for the DIRECT and LEARNED routes: its constants (unset ones
 * the model's defaults) and its maps read from their files (relative to the document's folder) by the one rule of
 * parameter maps, each map's scale folded into the channels its parameter reads; *uv_set and wrap[] the maps' one
 * UV set and wraps (MaterialX's default, periodic, when unset). */
static mr_status document_material(const mr_doc_material *src, const char *document, const char *where,
                                   mr_material **out, int *uv_set, mr_doc_wrap wrap[2]) {
    *out = NULL;
    mr_material *mat = NULL;
    mr_status st = mr_material_create(src->model, &mat);
    if (st != MR_OK) return st;
    packed_values(src, mat->values);
    char folder[4096];
    document_folder(document, folder, sizeof folder);
    const char *first = NULL;
    for (int p = 0; p < src->model->param_count && st == MR_OK; p++) {
        const mr_doc_value *v = &src->values[p];
        const mr_brdf_param *param = &src->model->params[p];
        if (v->kind != MR_DOC_TEXTURE) continue;
        mr_doc_wrap w[2] = {v->wrap_s ? v->wrap_s : MR_DOC_WRAP_REPEAT, v->wrap_t ? v->wrap_t : MR_DOC_WRAP_REPEAT};
        if (first == NULL) {
            first = param->name;
            *uv_set = v->uv_set;
            wrap[0] = w[0];
            wrap[1] = w[1];
        } else if (*uv_set != v->uv_set || wrap[0] != w[0] || wrap[1] != w[1]) {
            st = mr_fail(MR_ERR_UNSUPPORTED, "%s: the maps of %s and %s differ in UV set or wrap mode: a converted "
                         "map holds every parameter of a texel, so its maps must share both", where, first,
                         param->name);
            break;
        }
        char path[8192];
        snprintf(path, sizeof path, "%s%s", v->file[0] == '/' ? "" : folder, v->file);
        mr_image *image = NULL;
        if ((st = mr_img_read_param_map(path, param, MR_MAP_AS_PARAMETER, NULL, &image, NULL)) != MR_OK) {
            st = mr_fail_context(st, "%s: map of %s", where, param->name);
            break;
        }
        const int channel = v->channel < 0 ? 0 : v->channel;
        const size_t n = (size_t)image->width * (size_t)image->height, stride = (size_t)image->channels;
        if (param->channels == 3 && image->channels < 3 && (v->scale[1] != v->scale[0] || v->scale[2] != v->scale[0])) {
            mr_image_free(image);
            st = mr_fail(MR_ERR_UNSUPPORTED, "%s: a grey map '%s' of %s with a coloured scale", where, v->file,
                         param->name);
            break;
        }
        for (int c = 0; c < (param->channels == 3 && image->channels >= 3 ? 3 : 1); c++) {
            const int ch = param->channels == 1 ? channel : c;
            if (ch < image->channels && v->scale[c] != 1.0)
                for (size_t i = 0; i < n; i++) image->pixels[i * stride + (size_t)ch] *= (float)v->scale[c];
        }
        if ((st = mr_material_add_map(mat, param->name, image, param->channels == 1 ? channel : 0, path, NULL)) !=
            MR_OK) {
            mr_image_free(image);
            st = mr_fail_context(st, "%s", where);
        }
    }
    if (st != MR_OK) {
        mr_material_free(mat);
        return st;
    }
    *out = mat;
    return MR_OK;
}

/* The converted maps of material k named relative to the document's folder (as every map of a read document is,
 * so that mr_doc_rebase names them for the output). */
static mr_status name_converted_maps(const mr_doc_gltf_result *r, int k, const char *document, mr_doc_material *m) {
    char from[4096], at[4096];
    if (!folder_of(document ? document : "document", from))
        return mr_fail(MR_ERR_INVALID_ARG, "material document: cannot name the folder of '%s'", document);
    for (int i = 0; i < r->map_count; i++) {
        const mr_doc_gltf_map *map = &r->maps[i];
        if (map->material != k || map->param < 0) continue;
        if (!folder_of(map->path, at))
            return mr_fail(MR_ERR_INVALID_ARG, "material document: cannot name the folder of '%s'", map->path);
        char what[8200];
        snprintf(what, sizeof what, "'%s/%s'", at, map->file);
        mr_status st = set_relative_file(&m->values[map->param], at, map->file, from, what);
        if (st != MR_OK) return st;
    }
    return MR_OK;
}

static void list_extras(const mr_doc_material *m, char *out, size_t size) {
    size_t used = 0;
    out[0] = '\0';
    for (int e = 0; e < m->extra_count; e++) {
        size_t need = strlen(m->extras[e].name) + 2;
        if (used + need + 4 >= size) {
            snprintf(out + used, size - used, "%s...", used ? ", " : "");
            return;
        }
        used += (size_t)snprintf(out + used, size - used, "%s%s", used ? ", " : "", m->extras[e].name);
    }
}

mr_status mr_doc_convert(const mr_doc *in, const char *label, const mr_doc_gltf_options *opts,
                         mr_doc_gltf_result **out) {
    mr_doc_gltf_options o = opts ? *opts : (mr_doc_gltf_options){0};
    if (in == NULL || out == NULL) return mr_fail(MR_ERR_INVALID_ARG, "material document: no document or result");
    if (label == NULL) label = "material document";
    if (o.target == NULL) o.target = mr_brdf_find("openpbr");
    if (o.target == NULL) return MR_ERR_INVALID_ARG; // the registry's message
    int count = mr_doc_material_count(in);
    if (count == 0) return mr_fail(MR_ERR_INVALID_ARG, "%s: no materials to convert", label);
    mr_doc_gltf_result *r = calloc(1, sizeof(*r));
    if (r) r->doc = mr_doc_create();
    if (r) r->materials = calloc((size_t)count, sizeof(*r->materials));
    if (r == NULL || r->doc == NULL || r->materials == NULL) {
        mr_doc_gltf_result_free(r);
        return mr_fail(MR_ERR_NOMEM, "%s: out of memory", label);
    }
    r->material_count = count;
    mr_doc_remapper remapper = mr_doc_remapper_of(&o);
    mr_status st = MR_OK;
    for (int k = 0; k < count && st == MR_OK; k++) {
        const mr_doc_material *src = mr_doc_material_get(in, k);
        mr_doc_gltf_material *info = &r->materials[k];
        snprintf(info->name, sizeof(info->name), "%s", src->name);
        info->outcome = -1;
        info->ssim = 1;
        mr_doc_material *m = NULL;
        if ((st = mr_doc_add_material(r->doc, src->name, o.target, &m)) != MR_OK) break;
        if (src->model == o.target) {
            info->route = MR_DOC_ROUTE_COPY;
            for (int p = 0; p < src->model->param_count && st == MR_OK; p++)
                st = copy_value(m, src->model->params[p].name, &src->values[p]);
            for (int e = 0; e < src->extra_count && st == MR_OK; e++)
                st = mr_doc_add_extra(m, src->extras[e].name, src->extras[e].type, src->extras[e].value);
            continue;
        }
        list_extras(src, info->not_carried, sizeof(info->not_carried));
        if ((st = mr_doc_choose_route(src->model, o.target, is_textured(src), o.transforms != NULL,
                                      &info->route)) != MR_OK)
            break;
        if (info->route == MR_DOC_ROUTE_DIRECT || info->route == MR_DOC_ROUTE_LEARNED) {
            char where[4096 + 400];
            snprintf(where, sizeof where, "%s: material '%s' (%s) to %s by the %s route", label, src->name,
                     src->model->name, o.target->name, mr_doc_route_name(info->route));
            mr_material *source = NULL;
            int uv_set = 0;
            mr_doc_wrap wrap[2] = {MR_DOC_WRAP_REPEAT, MR_DOC_WRAP_REPEAT};
            if ((st = document_material(src, o.document_path, where, &source, &uv_set, wrap)) != MR_OK) break;
            if ((st = mr_doc_convert_textured(&o, r, k, where, src->name, source, uv_set, wrap, m)) != MR_OK) break;
            st = name_converted_maps(r, k, o.document_path, m);
            continue;
        }
        if (info->route == MR_DOC_ROUTE_MAPS) {
            char why[512] = "";
            int route = texture_route(src, m, why, sizeof why);
            if (route == MR_ERR_UNSUPPORTED)
                st = mr_fail(MR_ERR_UNSUPPORTED, "%s: material '%s' (%s) to %s: %s", label, src->name,
                             src->model->name, o.target->name, why);
            else if (route == -1)
                st = mr_fail(MR_ERR_UNSUPPORTED, "%s: material '%s': no maps route from %s to %s", label, src->name,
                             src->model->name, o.target->name);
            else
                st = (mr_status)route;
            continue;
        }
        double values[MR_BRDF_MAX_VALUES], fitted[MR_BRDF_MAX_VALUES];
        packed_values(src, values);
        // A value outside the model's range would be clamped by the model (prepare()) and the clamped material
        // remapped: refused instead, by name. Below a positive lower bound (roughness 0) the clamp is what
        // renderers do, and passes.
        for (int p = 0; p < src->model->param_count && st == MR_OK; p++) {
            const mr_brdf_param *d = &src->model->params[p];
            for (int c = 0; c < d->channels && st == MR_OK; c++) {
                double v = values[mr_brdf_param_offset(src->model, p) + c];
                if ((v < d->min_value && !(v >= 0 && d->min_value > 0)) || v > d->max_value)
                    st = mr_fail(MR_ERR_INVALID_ARG, "%s: material '%s': %s %.9g is outside %s's range [%g, %g]: "
                                 "not remapped", label, src->name, d->name, v, src->model->name, d->min_value,
                                 d->max_value);
            }
        }
        if (st != MR_OK) break;
        if ((st = mr_doc_remap_values(&remapper, src->model, values, o.target, info, fitted)) != MR_OK) break;
        st = mr_doc_set_all(m, fitted);
    }
    mr_doc_remapper_free(&remapper);
    if (st != MR_OK) {
        mr_doc_gltf_result_free(r);
        return st;
    }
    *out = r;
    return MR_OK;
}
