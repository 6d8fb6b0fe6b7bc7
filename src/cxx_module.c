/*
 * cxx_module.c — the library's C++ dependencies (tinygltf under the glTF shim, tinyobjloader under the OBJ reader,
 * libsvm under the SVR trainer, and with them the C++ runtime) live in a module, libmatremap-cxx.so, loaded on first
 * use; this file loads it and forwards the library's calls to it (the list is cxx_module.h's).
 *
 * Why a module: linked into every program, these libraries and libstdc++ are mapped and relocated at every start —
 * 0.8 ms of the 8 ms a one-material `matremap remap` takes (docs/performance.md, "The fit engine at its floor"),
 * paid by every command that never reads a glTF, an OBJ or trains an SVR. The module is found where the OpenImageIO
 * module is (mr_module_open: MR_CXX_MODULE, beside the executable, MR_MODULE_DIR).
 *
 * Built with MR_CXX_MODULE=0 (the fault-injection and fuzzing builds, whose instrumentation must reach the glTF
 * and OBJ readers' own allocations and branches), the C++ code is linked into the library instead and only
 * mr_cxx_svm is defined here, over libsvm linked directly.
 *
 * The module's copy of status.c keeps its own thread-local message: a forwarder carries it over when a call fails.
 */
#include "cxx_module.h"

#include <stdatomic.h>
#include <string.h>

#include "mr_internal.h"

#ifndef MR_CXX_MODULE
#define MR_CXX_MODULE 1
#endif

#if MR_CXX_MODULE

#include <pthread.h>
#include <stdio.h>

#ifndef MR_MODULE_DIR
#define MR_MODULE_DIR "/usr/local/lib/matremap"
#endif

#define MODULE_FILE "libmatremap-cxx.so"

static pthread_once_t load_once = PTHREAD_ONCE_INIT;
static _Atomic(const mr_cxx_table *) loaded; /* set (release) once the module's table is checked */
static char load_failure[2048];              /* why loading failed; written once inside pthread_once */

/* mr_module_spec's check: the table of this build's interface (a module of another build is refused). */
static const char *check_table(void *const *entries, char *reason, size_t size) {
    const mr_cxx_table *table = entries[0]; // the symbol is the table itself, an object
    if (table->abi == MR_CXX_MODULE_ABI && table->size == sizeof *table) return NULL;
    snprintf(reason, size, "a module of another build (interface %d, %zu bytes; this matremap needs %d, %zu bytes)",
             table->abi, table->size, MR_CXX_MODULE_ABI, sizeof *table);
    return reason;
}

static void load_module(void) {
    static const char *const symbols[] = {MR_CXX_TABLE_SYMBOL};
    static const mr_module_spec spec = {MODULE_FILE, "MR_CXX_MODULE", "C++", symbols, 1, check_table};
    void *entries[1];
    if (mr_module_open(&spec, entries, load_failure, sizeof load_failure) != NULL)
        atomic_store_explicit(&loaded, (const mr_cxx_table *)entries[0], memory_order_release);
}

/* The table, loading the module on the first call; MR_ERR_EXTERNAL naming `what` (glTF, OBJ, svr train: what the
 * caller was about to read or do) when it cannot be loaded. */
static mr_status table_for(const char *what, const mr_cxx_table **out) {
    pthread_once(&load_once, load_module);
    *out = atomic_load_explicit(&loaded, memory_order_acquire);
    if (*out != NULL) return MR_OK;
    return mr_fail(MR_ERR_EXTERNAL,
                   "%s: cannot load matremap's C++ module " MODULE_FILE " (glTF, OBJ and SVR support; looked beside "
                   "the executable in ../lib/matremap and in " MR_MODULE_DIR "; set MR_CXX_MODULE to its path): %s",
                   what, load_failure);
}

/* The table if the module is loaded already (an object of the module exists only then), else NULL. */
static const mr_cxx_table *table_if_loaded(void) { return atomic_load_explicit(&loaded, memory_order_acquire); }

static mr_status forward_status(const mr_cxx_table *table, mr_status status) {
    if (status != MR_OK) mr_fail(status, "%s", table->last_error());
    return status;
}

#define STATUS_FORWARDER(name, params, args)                                                                       \
    mr_status name params {                                                                                        \
        const mr_cxx_table *table;                                                                                 \
        mr_status status = table_for(strncmp(#name, "mr_obj", 6) == 0 ? "OBJ" : "glTF", &table);                  \
        return status != MR_OK ? status : forward_status(table, table->name args);                                 \
    }
MR_CXX_STATUS_CALLS(STATUS_FORWARDER)

#define VALUE_FORWARDER(type, name, params, args, fallback)                                                        \
    type name params {                                                                                             \
        const mr_cxx_table *table = table_if_loaded();                                                             \
        return table != NULL ? table->name args : fallback;                                                        \
    }
MR_CXX_VALUE_CALLS(VALUE_FORWARDER)

#define VOID_FORWARDER(name, params, args)                                                                         \
    void name params {                                                                                             \
        const mr_cxx_table *table = table_if_loaded();                                                             \
        if (table != NULL) table->name args;                                                                       \
    }
MR_CXX_VOID_CALLS(VOID_FORWARDER)

/* Not in the lists: without a module (so without an asset) it still clears *out, as it does for a NULL asset. */
void mr_gltf_get_counts(const mr_gltf *asset, mr_gltf_counts *out) {
    const mr_cxx_table *table = table_if_loaded();
    if (table != NULL)
        table->mr_gltf_get_counts(asset, out);
    else
        memset(out, 0, sizeof *out);
}

mr_status mr_cxx_svm(const char *what, const mr_cxx_table **out) { return table_for(what, out); }

#else /* !MR_CXX_MODULE: the C++ code is linked in; only libsvm's table is needed */

#define SVM_ENTRY(type, name, params, args) .name = name,
static const mr_cxx_table linked_svm = {.abi = MR_CXX_MODULE_ABI, .size = sizeof(mr_cxx_table),
                                        MR_CXX_SVM_CALLS(SVM_ENTRY)};

mr_status mr_cxx_svm(const char *what, const mr_cxx_table **out) {
    (void)what;
    *out = &linked_svm;
    return MR_OK;
}

#endif
