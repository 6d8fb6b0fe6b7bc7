/*
 * cxx_module_table.c — the C++ module's one exported symbol (libmatremap-cxx.so; src/cxx_module.c says why the
 * module exists): the table of its functions, which the library's forwarders call. Compiled into the module only,
 * with the glTF shim, the OBJ reader, libsvm and their own copies of the few library functions they use.
 */
#include "cxx_module.h"

#include "mr_internal.h"

#define STATUS_ENTRY(name, params, args) .name = name,
#define VALUE_ENTRY(type, name, params, args, fallback) .name = name,
#define VOID_ENTRY(name, params, args) .name = name,
#define SVM_ENTRY(type, name, params, args) .name = name,

__attribute__((visibility("default"))) const mr_cxx_table mr_cxx_module_table = {
    .abi = MR_CXX_MODULE_ABI,
    .size = sizeof(mr_cxx_table),
    .last_error = mr_last_error,
    MR_CXX_STATUS_CALLS(STATUS_ENTRY) MR_CXX_VALUE_CALLS(VALUE_ENTRY) MR_CXX_VOID_CALLS(VOID_ENTRY)
    .mr_gltf_get_counts = mr_gltf_get_counts,
    MR_CXX_SVM_CALLS(SVM_ENTRY)};
