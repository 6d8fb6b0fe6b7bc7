/*
 * renderer.c — the renderers behind renderer.h's calls: the built-in one (render.h, in process) and the external
 * ones, whose servers renderer_process.c runs.
 */
#include "renderer.h"

#include <math.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "../mr_internal.h"
#include "renderer_internal.h"

static const char *const blender_arguments[] = {"-b", "--factory-startup", "--python-exit-code", "3", "--python",
                                                "SCRIPT", "--", NULL};
static const char *const blender_models[] = {"cycles-principled", "lambert", NULL};
static const char *const three_arguments[] = {"SCRIPT", NULL};
static const char *const three_models[] = {"gltf", "lambert", NULL};

static const mr_renderer_kind kinds[] = {
    {"blender", "MATREMAP_BLENDER", "blender", "blender", blender_arguments, "renderers/blender_server.py", NULL,
     blender_models, 1, 1, MR_RENDERER_DEFAULT_SAMPLES_BLENDER},
    {"three", "MATREMAP_NODE", "node", "nodejs", three_arguments, "renderers/three/server.mjs",
     "renderers/three/node_modules/three/package.json", three_models, 0, 0, MR_RENDERER_DEFAULT_SAMPLES_THREE},
};
#define KIND_COUNT ((int)(sizeof kinds / sizeof kinds[0]))

struct mr_renderer {
    const mr_renderer_kind *kind; /* NULL: the built-in renderer */
    external_pool *pool;
    int threads;                  /* the built-in renderer's: mr_renderer_options.threads */
    _Atomic long builtin_renders;
};

const char *mr_renderer_name_at(int index) {
    if (index == 0) return "builtin";
    return index > 0 && index <= KIND_COUNT ? kinds[index - 1].name : NULL;
}

static const mr_renderer_kind *find_kind(const char *name) {
    for (int k = 0; name != NULL && k < KIND_COUNT; k++)
        if (strcmp(kinds[k].name, name) == 0) return &kinds[k];
    return NULL;
}

static int kind_supports(const mr_renderer_kind *kind, const mr_brdf_model *model) {
    for (int i = 0; kind->models[i] != NULL; i++)
        if (strcmp(kind->models[i], model->name) == 0) return 1;
    return 0;
}

static mr_status unsupported(const mr_renderer_kind *kind, const mr_brdf_model *model) {
    char list[256] = "";
    for (int i = 0; kind->models[i] != NULL; i++)
        snprintf(list + strlen(list), sizeof list - strlen(list), "%s%s", i ? ", " : "", kind->models[i]);
    return mr_fail(MR_ERR_UNSUPPORTED, "renderer '%s' does not render model '%s' by values (it renders: %s)",
                   kind->name, model->name, list);
}

mr_status mr_renderer_check(const char *name, const mr_brdf_model *model) {
    if (name != NULL && strcmp(name, "builtin") == 0) return MR_OK;
    const mr_renderer_kind *kind = find_kind(name);
    if (kind == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "unknown renderer '%s' (valid: builtin, blender, three)",
                       name ? name : "(null)");
    return model == NULL || kind_supports(kind, model) ? MR_OK : unsupported(kind, model);
}

mr_status mr_renderer_open(const char *name, const mr_renderer_options *opts_in, mr_renderer **out) {
    if (name == NULL || out == NULL) return mr_fail(MR_ERR_INVALID_ARG, "renderer: NULL name or output");
    *out = NULL;
    mr_renderer_options opts;
    memset(&opts, 0, sizeof opts);
    if (opts_in) opts = *opts_in;
    if (opts.samples < 0 || opts.processes < 0 || opts.threads < 0 || opts.threads > 1024 ||
        !(opts.timeout_seconds >= 0.0) || !isfinite(opts.timeout_seconds))
        return mr_fail(MR_ERR_INVALID_ARG, "renderer '%s': samples %d, processes %d, threads %d, timeout %g: "
                       "expected counts >= 0 (threads <= 1024) and a finite timeout >= 0", name, opts.samples,
                       opts.processes, opts.threads, opts.timeout_seconds);
    mr_status checked = mr_renderer_check(name, NULL);
    if (checked != MR_OK) return checked;
    const mr_renderer_kind *kind = find_kind(name);
    mr_renderer *r = calloc(1, sizeof *r);
    if (r == NULL) return mr_fail(MR_ERR_NOMEM, "renderer: out of memory");
    r->kind = kind;
    r->threads = opts.threads;
    if (kind != NULL) {
        mr_status status = mr_external_pool_open(kind, &opts, &r->pool);
        if (status != MR_OK) {
            free(r);
            return status;
        }
    }
    *out = r;
    return MR_OK;
}

void mr_renderer_free(mr_renderer *renderer) {
    if (renderer == NULL) return;
    mr_external_pool_free(renderer->pool);
    free(renderer);
}

const char *mr_renderer_name(const mr_renderer *renderer) {
    return renderer == NULL || renderer->kind == NULL ? "builtin" : renderer->kind->name;
}

int mr_renderer_is_builtin(const mr_renderer *renderer) {
    return renderer == NULL || renderer->kind == NULL;
}

int mr_renderer_supports(const mr_renderer *renderer, const mr_brdf_model *model) {
    if (model == NULL) return 0;
    return mr_renderer_is_builtin(renderer) || kind_supports(renderer->kind, model);
}

int mr_renderer_has_components(const mr_renderer *renderer) {
    return mr_renderer_is_builtin(renderer) || renderer->kind->components;
}

mr_status mr_renderer_start(mr_renderer *renderer, char *version, size_t size) {
    if (renderer == NULL) return mr_fail(MR_ERR_INVALID_ARG, "renderer: NULL");
    if (mr_renderer_is_builtin(renderer)) {
        if (version && size) snprintf(version, size, "builtin %s", mr_version());
        return MR_OK;
    }
    return mr_external_pool_start(renderer->pool, version, size);
}

mr_status mr_renderer_render(mr_renderer *renderer, const mr_render_plan *plan, const mr_brdf_model *model,
                             const double *values, mr_image *full, mr_image *diffuse, mr_image *specular) {
    if (renderer == NULL || plan == NULL || model == NULL || values == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "renderer: NULL renderer, plan, model or values");
    if (!mr_renderer_supports(renderer, model)) return unsupported(renderer->kind, model);
    if (mr_renderer_is_builtin(renderer)) {
        mr_status status = MR_OK;
        if (full == NULL && diffuse == NULL && specular == NULL)
            return mr_fail(MR_ERR_INVALID_ARG, "renderer: no image to render into");
        if (full) status = mr_render_into_threads(plan, renderer->threads, model, values, MR_COMPONENT_FULL, full);
        if (status == MR_OK && (diffuse || specular))
            status = mr_render_components_into_threads(plan, renderer->threads, model, values, diffuse, specular);
        if (status == MR_OK) renderer->builtin_renders++;
        return status;
    }
    mr_image *images[3] = {full, diffuse, specular};
    return mr_external_pool_render(renderer->pool, plan, model, values, images);
}

long mr_renderer_render_count(const mr_renderer *renderer) {
    if (renderer == NULL) return 0;
    return renderer->pool ? mr_external_pool_renders(renderer->pool) : renderer->builtin_renders;
}

long mr_renderer_process_starts(const mr_renderer *renderer) {
    return renderer && renderer->pool ? mr_external_pool_starts(renderer->pool) : 0;
}

mr_status mr_renderer_describe(mr_renderer *renderer, const char *reference, mr_external_material **out) {
    if (renderer == NULL || reference == NULL || out == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "renderer: NULL renderer, material or output");
    *out = NULL;
    if (mr_renderer_is_builtin(renderer))
        return mr_fail(MR_ERR_UNSUPPORTED, "the built-in renderer has no materials of its own: '%s' needs an "
                       "external renderer (blender)", reference);
    return mr_external_pool_describe(renderer->pool, reference, out);
}

mr_status mr_renderer_render_external(mr_renderer *renderer, const mr_render_plan *plan,
                                      const mr_external_material *material, mr_image *full, mr_image *diffuse,
                                      mr_image *specular) {
    if (renderer == NULL || plan == NULL || material == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "renderer: NULL renderer, plan or material");
    if (mr_renderer_is_builtin(renderer))
        return mr_fail(MR_ERR_UNSUPPORTED, "the built-in renderer cannot render material '%s'",
                       mr_external_material_reference(material));
    mr_image *images[3] = {full, diffuse, specular};
    return mr_external_pool_render_material(renderer->pool, plan, material, images);
}
