/*
 * renderer_internal.h — what renderer.c and renderer_process.c share: the table of external renderers and the
 * process pool that runs one (renderer.h has the contract).
 */
#ifndef MR_RENDERER_INTERNAL_H
#define MR_RENDERER_INTERNAL_H

#include "renderer.h"

/* An external renderer: how to start its server and what it can do. */
typedef struct mr_renderer_kind {
    const char *name;               /* "blender" */
    const char *program_variable;   /* environment variable naming the program: "MATREMAP_BLENDER" */
    const char *default_program;    /* "blender" */
    const char *package;            /* the Debian package that provides it, for the message when it is missing */
    const char *const *arguments;   /* argv after the program, NULL-terminated; "SCRIPT" is the server script */
    const char *script;             /* the server, under the data path: "renderers/blender_server.py" */
    const char *installed_check;    /* a data file that exists once its packages are installed, or NULL */
    const char *const *models;      /* the models it renders by values, NULL-terminated */
    int components;                 /* 1: it returns diffuse and specular parts */
    int materials;                  /* 1: it renders materials of its own (mr_renderer_describe) */
    int default_samples;
} mr_renderer_kind;

/* One input a renderer's own material exposes (mr_external_material_param). */
typedef struct mr_external_param {
    char path[256];
    int channels;
    double min_value, max_value;
    double values[3];
} mr_external_param;

typedef struct external_pool external_pool;

/* The pool of server processes of one renderer (renderer_process.c). images[3]: full, diffuse, specular (any
 * NULL, not all). */
mr_status mr_external_pool_open(const mr_renderer_kind *kind, const mr_renderer_options *opts, external_pool **out);
void mr_external_pool_free(external_pool *pool);
mr_status mr_external_pool_start(external_pool *pool, char *version, size_t size);
mr_status mr_external_pool_render(external_pool *pool, const mr_render_plan *plan, const mr_brdf_model *model,
                                  const double *values, mr_image *const images[3]);
mr_status mr_external_pool_describe(external_pool *pool, const char *reference, mr_external_material **out);
mr_status mr_external_pool_render_material(external_pool *pool, const mr_render_plan *plan,
                                           const mr_external_material *material, mr_image *const images[3]);
long mr_external_pool_renders(const external_pool *pool);
long mr_external_pool_starts(const external_pool *pool);

#endif /* MR_RENDERER_INTERNAL_H */
