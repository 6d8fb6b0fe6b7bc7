/*
 * api.h — flat entry points for front ends that reach the library without its structs: the Python package
 * (python/matremap, ctypes over libmatremap.so; docs/python.md). Each call takes names, strings and caller-owned
 * float buffers, makes the same library calls as the matching command (docs/architecture.md, "Front doors"), and
 * answers through caller buffers or a malloc'ed JSON text released with mr_api_free. Errors: an mr_status and one
 * line in mr_last_error(), as everywhere.
 */
#ifndef MR_API_H
#define MR_API_H

#include "../mr_image.h"
#include "../mr_status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Release a text returned by the calls below (NULL is allowed). */
void mr_api_free(void *text);

/* Every registered BRDF model as `matremap models --json` prints it, in *json_out (mr_api_free). */
mr_status mr_api_models_json(char **json_out);

/* `matremap render MODEL ASSIGNMENTS --size SIZE [--light LIGHT] [--env ENV] --component C --threads T`: the
 * material (mr_material_from_assignments: name=value and name=@MAP) rendered in the fit scene into `out`, an RGB
 * size x size image the caller owns (every pixel written). light NULL: "45", or none with an env; env_path NULL:
 * none; component NULL: "full". The same calls as the command, so the same pixels, bit for bit. */
mr_status mr_api_render(const char *model, const char *const *assignments, int count, int size, const char *light,
                        const char *env_path, const char *component, int threads, mr_image *out);

/* `matremap remap --from FROM A... --to TO B... --json` with --size, --light, --strategy, --hold, --tie, --free and
 * --threads (NULL or 0: the command's defaults; lists as the options take them, "alpha,ior" or "alpha=0.2"): the
 * fit's JSON object (its "values", "outcome", "detail", "rmse", "relative_rmse", "ssim", "renders", "seconds",
 * "strategy", "size", "light") in *json_out (mr_api_free). */
mr_status mr_api_remap(const char *from, const char *const *from_assignments, int from_count, const char *to,
                       const char *const *to_assignments, int to_count, int size, const char *light,
                       const char *strategy, const char *hold_list, const char *tie_list, const char *free_list,
                       int threads, char **json_out);

/* The transform SOURCE -> TARGET named `method` (transform.h: mr_transform_find) as JSON: {"name", "summary",
 * "inputs": [{"name", "channels", "optional", "default"}], "outputs": [{"name", "channels"}]} in *json_out. */
mr_status mr_api_transform_describe(const char *source, const char *target, const char *method, char **json_out);

/* Convert maps through that transform (mr_transform_convert_maps, the conversion of `matremap spec2metal` and
 * `metal2spec`): in[i] per input slot (NULL: an optional slot's default; a 1-channel slot reads channel 0), all of
 * one size; out[j] per output slot, caller-owned images of that size with the slot's channel count, written.
 * dielectric_f0 0: the kind's default. threads 0: automatic. */
mr_status mr_api_transform_convert(const char *source, const char *target, const char *method, double dielectric_f0,
                                   int threads, const mr_image *const *in, mr_image *const *out);

/* `matremap gltf DIRECTION INPUT -o OUTPUT [--method M] [--overwrite-metal-rough] [--threads T] --json` with the
 * command's defaults (direction "spec2metal" or "metal2spec"; method NULL: weighted for spec2metal, read under both
 * readings, eq2 for metal2spec; PNG textures): mr_gltf_convert_file, then {"input", "output", "direction", "method",
 * "materials": [{"name", "outcome", "reason", "width", "height", "flagged", "off_manifold", "nonfinite", "clamped",
 * "failed", "seconds", "extension"}]} in *json_out (mr_api_free). */
mr_status mr_api_gltf_convert(const char *input, const char *output, const char *direction, const char *method,
                              int overwrite, int threads, char **json_out);

/* `matremap report -o DIR [--size N] [--env FILE] [--rotations R] [--threads T] [--title T] INPUT -- INPUT ...`:
 * inputs[k] is a material, its model and assignments separated by newlines ("ggx\nalpha=0.2\nf0=@f0.png"), or a glTF
 * asset's path (.gltf, .glb); labels[k] (labels or its entries NULL: the default) names it on the page. Writes DIR's
 * index.html, pictures and summary.json (mr_report_make; DIR must exist). size, rotations, threads 0: defaults. */
mr_status mr_api_report(const char *const *inputs, const char *const *labels, int count, const char *dir, int size,
                        const char *env_path, int rotations, int threads, const char *title);

#ifdef __cplusplus
}
#endif

#endif /* MR_API_H */
