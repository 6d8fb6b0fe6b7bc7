/*
 * doc_internal.h — what the files of src/doc/ share and nothing else includes: the remap route of uniform materials
 * (one fit scene made on first use, for every material of a conversion, with the holds and ties) and setting every
 * parameter at once.
 */
#ifndef MR_DOC_INTERNAL_H
#define MR_DOC_INTERNAL_H

#include "doc/doc.h"

struct mr_render_plan;

typedef struct mr_doc_remapper {
    struct mr_render_plan *plan; /* made on the first remap */
    int threads;                 /* 0: automatic */
    int size;                    /* the fit scene's side, 0: MR_REMAP_DEFAULT_SIZE */
    const double *target_values; /* held parameters' values (NULL: the target's defaults), as mr_remap_options */
    unsigned held;               /* parameters held beside the target's default holds (mr_doc_gltf_options.held) */
    const mr_brdf_ties *ties;    /* NULL: the pair's defaults, mr_brdf_default_ties; a hold wins over a tie */
} mr_doc_remapper;

/* The remapper of a conversion with options `o` (its threads, size, holds and ties). */
mr_doc_remapper mr_doc_remapper_of(const mr_doc_gltf_options *o);

/* `values` of model `from` fitted to `to` by mr_remap in the fit scene (remap's default) with the remapper's holds
 * and ties (the ties of the pair `from` -> `to` by default, as export's DIRECT route takes them); the route,
 * outcome, SSIM, RMSE and detail into *info (route MR_DOC_ROUTE_REMAP), the fitted packed values into out. */
mr_status mr_doc_remap_values(mr_doc_remapper *rm, const mr_brdf_model *from, const double *values,
                              const mr_brdf_model *to, mr_doc_gltf_material *info, double *out);
void mr_doc_remapper_free(mr_doc_remapper *rm);

/* Every parameter of the material set to the packed values (constants). */
mr_status mr_doc_set_all(mr_doc_material *m, const double *values);

struct mr_material;

/* Textured material k (of result r, its document material m, already routed DIRECT or LEARNED in r->materials[k])
 * converted from `source` (a material of the source model with its maps, factors folded in: TAKEN, freed here) by
 * mr_learned_convert_material (hops 0 with o's tolerance, holds, ties, scene size and cache; or the chain among
 * o->transforms): every target parameter whose converted map holds one value set as that constant, every other a
 * new map of r (PREFIX_<name>_<param>.png, o->image_prefix) read through `uv_set` and `wrap`, plus the flag
 * picture. `where` names the material in messages ("glTF 'a.gltf': material 0 ('M')"). */
mr_status mr_doc_convert_textured(const mr_doc_gltf_options *o, mr_doc_gltf_result *r, int k, const char *where,
                                  const char *name, struct mr_material *source, int uv_set, const mr_doc_wrap wrap[2],
                                  mr_doc_material *m);

#endif /* MR_DOC_INTERNAL_H */
