/*
 * material_defaults.c — the glTF 2.0 defaults of a material and of a texture reference (mr_gltf.h). Plain C, apart
 * from the C++ shim: callers fill materials to write without loading the C++ module (src/cxx_module.c), and the
 * module compiles its own copy.
 */
#include <string.h>

#include "gltf/mr_gltf.h"

void mr_gltf_texture_ref_none(mr_gltf_texture_ref *r) {
    r->index = -1;
    r->tex_coord = 0;
    r->value = 1.0;
    r->has_transform = 0;
    r->offset[0] = r->offset[1] = 0.0;
    r->rotation = 0.0;
    r->scale[0] = r->scale[1] = 1.0;
    r->transform_tex_coord = -1;
}

void mr_gltf_material_defaults(mr_gltf_material *m) {
    memset(m, 0, sizeof *m);
    m->name = "";
    for (int i = 0; i < 4; i++) m->base_color_factor[i] = m->diffuse_factor[i] = 1.0;
    for (int i = 0; i < 3; i++) m->specular_factor[i] = m->specular_color_factor[i] = 1.0;
    m->metallic_factor = m->roughness_factor = 1.0;
    m->alpha_mode = MR_GLTF_ALPHA_OPAQUE;
    m->alpha_cutoff = 0.5;
    m->glossiness_factor = 1.0;
    m->specular_strength = 1.0;
    m->ior = 1.5;
    mr_gltf_texture_ref *refs[] = {&m->base_color_texture,          &m->metallic_roughness_texture,
                                   &m->normal_texture,              &m->occlusion_texture,
                                   &m->emissive_texture,            &m->diffuse_texture,
                                   &m->specular_glossiness_texture, &m->specular_texture,
                                   &m->specular_color_texture};
    for (size_t k = 0; k < sizeof refs / sizeof refs[0]; k++) mr_gltf_texture_ref_none(refs[k]);
}
