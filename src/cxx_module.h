/*
 * cxx_module.h — the library's calls into C++ (the glTF shim over tinygltf, the OBJ reader over tinyobjloader, and
 * libsvm), listed once for the C++ module that holds them (libmatremap-cxx.so) and for the loader that forwards the
 * library's calls to it (src/cxx_module.c says why and how).
 *
 * The lists are X-macros: each entry names a function, its parameters and the arguments that pass them on. A list
 * is expanded with a macro X(name, parameters, arguments), plus the result type (and, for the value lists, what the
 * forwarder answers when no module could be loaded) where the list says so.
 */
#ifndef MR_CXX_MODULE_H
#define MR_CXX_MODULE_H

#include <libsvm/svm.h>

#include "gltf/mr_gltf.h"
#include "io/obj_load.h"
#include "mr_status.h"

/* The functions that report failure with a status: the forwarder fails with MR_ERR_EXTERNAL when the module cannot
 * be loaded, and carries the module's last-error message over on failure. X(name, parameters, arguments). */
#define MR_CXX_STATUS_CALLS(X)                                                                                     \
    X(mr_gltf_load, (const char *path, mr_gltf **out), (path, out))                                                \
    X(mr_gltf_create, (const char *label, mr_gltf **out), (label, out))                                            \
    X(mr_gltf_get_material, (const mr_gltf *asset, int material, mr_gltf_material *out), (asset, material, out))  \
    X(mr_gltf_set_material, (mr_gltf *asset, int material, const mr_gltf_material *in), (asset, material, in))    \
    X(mr_gltf_remove_material_extension, (mr_gltf *asset, int material, const char *name, int *removed),          \
      (asset, material, name, removed))                                                                            \
    X(mr_gltf_add_material, (mr_gltf *asset, const mr_gltf_material *in, int *out_material),                       \
      (asset, in, out_material))                                                                                   \
    X(mr_gltf_get_texture, (const mr_gltf *asset, int texture, mr_gltf_texture *out), (asset, texture, out))       \
    X(mr_gltf_get_image, (const mr_gltf *asset, int image, mr_gltf_image *out), (asset, image, out))               \
    X(mr_gltf_image_write_file, (const mr_gltf *asset, int image, const char *path), (asset, image, path))        \
    X(mr_gltf_add_image_file, (mr_gltf *asset, const char *file, const char *uri, int *out_image),                \
      (asset, file, uri, out_image))                                                                               \
    X(mr_gltf_add_image_bytes, (mr_gltf *asset, const void *bytes, size_t size, const char *uri, int *out_image), \
      (asset, bytes, size, uri, out_image))                                                                        \
    X(mr_gltf_add_texture, (mr_gltf *asset, int image, const mr_gltf_sampler *sampler, int *out_texture),         \
      (asset, image, sampler, out_texture))                                                                        \
    X(mr_gltf_set_extension_required, (mr_gltf *asset, const char *name, int required), (asset, name, required))  \
    X(mr_gltf_prune_unused, (mr_gltf *asset, mr_gltf_prune_stats *stats), (asset, stats))                          \
    X(mr_gltf_get_triangles, (const mr_gltf *asset, int scene, mr_gltf_triangles **out), (asset, scene, out))      \
    X(mr_gltf_get_bounds, (const mr_gltf *asset, int scene, double lo[3], double hi[3], int *count),               \
      (asset, scene, lo, hi, count))                                                                               \
    X(mr_gltf_save, (mr_gltf *asset, const char *path), (asset, path))                                             \
    X(mr_gltf_save_with, (mr_gltf *asset, const char *path, const mr_gltf_save_options *opts), (asset, path, opts)) \
    X(mr_obj_load, (const char *path, const mr_obj_options *opts, mr_obj_mesh **out), (path, opts, out))

/* Functions of an object the module made (an asset, a triangle set, a mesh): without a module there is no such
 * object, so the forwarder answers `fallback` (what the function answers for NULL). X(type, name, parameters,
 * arguments, fallback). */
#define MR_CXX_VALUE_CALLS(X)                                                                                      \
    X(const char *, mr_gltf_path, (const mr_gltf *asset), (asset), "")                                             \
    X(const char *, mr_gltf_source_file, (const mr_gltf *asset, int k), (asset, k), NULL)                          \
    X(int, mr_gltf_material_has_extension, (const mr_gltf *asset, int material, const char *name),                 \
      (asset, material, name), 0)                                                                                  \
    X(int, mr_gltf_extension_used, (const mr_gltf *asset, const char *name), (asset, name), 0)                     \
    X(int, mr_gltf_extension_required, (const mr_gltf *asset, const char *name), (asset, name), 0)

/* The same without a result: without a module the forwarder does nothing. X(name, parameters, arguments). */
#define MR_CXX_VOID_CALLS(X)                                                                                       \
    X(mr_gltf_free, (mr_gltf *asset), (asset))                                                                     \
    X(mr_gltf_sync_extensions, (mr_gltf *asset), (asset))                                                          \
    X(mr_gltf_triangles_free, (mr_gltf_triangles *triangles), (triangles))                                         \
    X(mr_obj_mesh_free, (mr_obj_mesh *obj), (obj))

/* libsvm's functions the SVR trainer uses (src/learn/svr.c), under their own names. X(type, name, parameters,
 * arguments). */
#define MR_CXX_SVM_CALLS(X)                                                                                        \
    X(const char *, svm_check_parameter, (const struct svm_problem *prob, const struct svm_parameter *param),      \
      (prob, param))                                                                                               \
    X(struct svm_model *, svm_train, (const struct svm_problem *prob, const struct svm_parameter *param),          \
      (prob, param))                                                                                               \
    X(double, svm_predict, (const struct svm_model *model, const struct svm_node *x), (model, x))                  \
    X(void, svm_free_and_destroy_model, (struct svm_model **model), (model))                                      \
    X(void, svm_set_print_string_function, (void (*print)(const char *)), (print))

/* What the module hands the loader: its interface version (MR_CXX_MODULE_ABI and the table's size: a module of
 * another build is refused), the thread's last-error message of the module's own copy of status.c, and one pointer
 * per function above. */
#define MR_CXX_MODULE_ABI 1
#define MR_CXX_POINTER(name, params, args) mr_status(*name) params;
#define MR_CXX_VALUE_POINTER(type, name, params, args, fallback) type(*name) params;
#define MR_CXX_VOID_POINTER(name, params, args) void(*name) params;
#define MR_CXX_SVM_POINTER(type, name, params, args) type(*name) params;
typedef struct mr_cxx_table {
    int abi;
    size_t size; /* sizeof (mr_cxx_table) in the module's build */
    const char *(*last_error)(void);
    MR_CXX_STATUS_CALLS(MR_CXX_POINTER)
    MR_CXX_VALUE_CALLS(MR_CXX_VALUE_POINTER)
    MR_CXX_VOID_CALLS(MR_CXX_VOID_POINTER)
    /* written by hand: without a module its forwarder still clears *out */
    void (*mr_gltf_get_counts)(const mr_gltf *asset, mr_gltf_counts *out);
    MR_CXX_SVM_CALLS(MR_CXX_SVM_POINTER)
} mr_cxx_table;

/* The module's one exported symbol: its table (src/cxx_module_table.c). */
#define MR_CXX_TABLE_SYMBOL "mr_cxx_module_table"

/* The table of libsvm's functions, for src/learn/svr.c: on success *out points to a table whose svm_* members are
 * set (in a build without the module, libsvm linked in; otherwise the module's, loaded on first use). On failure,
 * MR_ERR_EXTERNAL naming `what` and why the module could not be loaded. */
mr_status mr_cxx_svm(const char *what, const mr_cxx_table **out);

#endif
