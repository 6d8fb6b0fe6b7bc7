/*
 * fault_inject_new.cpp — operator new for the fault build (fault_inject.c has the mechanism): the project's C++
 * (gltf/, the image and OBJ shims) allocates through new, and a failure there is a std::bad_alloc that each shim
 * entry point must catch and return as MR_ERR_NOMEM. Linked with -Wl,--wrap=_Znwm etc., so only the project's own
 * objects' calls arrive here (the mangled names: new(size_t), new[](size_t) and their nothrow forms).
 *
 * One exemption: an allocation made by nlohmann/json's destructor is not failed. nlohmann/json 3.11's basic_json
 * destructor (json_value::destroy) moves the children of an array or object onto a std::vector first, so that deep
 * documents are not destroyed recursively; a std::bad_alloc there leaves a destructor, which terminates the program.
 * That is a limit of the third-party header, not of our error handling (the glTF shim's own long-lived document is
 * taken apart without allocating: release_json in gltf/util.cpp). The calls spared are counted (MR_FAULT_COUNT_FILE's
 * "spared") and reported in docs/reliability.md. They are recognised by the caller's symbol, which dladdr finds
 * because the fault build exports it (--export-dynamic-symbol, that symbol alone: exporting everything would let
 * the shared libraries bind to our template instances, and count their allocations too); the look-up runs only for a
 * call that would fail.
 */
#include <dlfcn.h>
#include <execinfo.h>

#include <cstddef>
#include <cstring>
#include <new>

#include "fault_inject.h"

namespace {

// 1 if nlohmann::json's json_value::destroy is among the callers (a few frames up: std::vector::reserve and the
// allocator lie between).
int in_json_destructor() {
    void *frames[10];
    const int depth = backtrace(frames, 10);
    for (int i = 1; i < depth; i++) {
        Dl_info info;
        if (dladdr(frames[i], &info) != 0 && info.dli_sname != nullptr &&
            std::strstr(info.dli_sname, "json_value7destroy") != nullptr)
            return 1;
    }
    return 0;
}

} // namespace

extern "C" {
void *__real__Znwm(std::size_t size);
void *__real__Znam(std::size_t size);
void *__real__ZnwmRKSt9nothrow_t(std::size_t size, const std::nothrow_t &tag) noexcept;
void *__real__ZnamRKSt9nothrow_t(std::size_t size, const std::nothrow_t &tag) noexcept;

void *__wrap__Znwm(std::size_t size) {
    if (mr_fault_alloc_hit("operator new", in_json_destructor))
        throw std::bad_alloc();
    return __real__Znwm(size);
}

void *__wrap__Znam(std::size_t size) {
    if (mr_fault_alloc_hit("operator new[]", in_json_destructor))
        throw std::bad_alloc();
    return __real__Znam(size);
}

void *__wrap__ZnwmRKSt9nothrow_t(std::size_t size, const std::nothrow_t &tag) noexcept {
    if (mr_fault_alloc_hit("operator new(nothrow)", nullptr))
        return nullptr;
    return __real__ZnwmRKSt9nothrow_t(size, tag);
}

void *__wrap__ZnamRKSt9nothrow_t(std::size_t size, const std::nothrow_t &tag) noexcept {
    if (mr_fault_alloc_hit("operator new[](nothrow)", nullptr))
        return nullptr;
    return __real__ZnamRKSt9nothrow_t(size, tag);
}
}
