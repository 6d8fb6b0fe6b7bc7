/*
 * thread_count.c — a preloaded counter of the threads a process starts, for tests/threads_cli.sh: "--threads 1
 * opens no thread" (the brief: many copies run at once, so a run never opens threads its work cannot use).
 *
 * Built as build/tests/libthread_count.so and given to the tool with LD_PRELOAD. Its pthread_create comes before
 * glibc's in the symbol search, so every thread anyone in the process starts is counted: our OpenMP loops (libgomp
 * starts its workers with pthread_create), OpenImageIO's and OpenEXR's pools, std::thread. The call is passed on
 * to the next definition (glibc's, or AddressSanitizer's interceptor in the ASan build: the test then sets
 * verify_asan_link_order=0, since ASan wants to be first in the list). Threads started with clone() directly are
 * not seen; none of our libraries does that.
 *
 * Threads started by a shared library's initialiser while the dynamic loader loads it are counted apart: no
 * option of ours can prevent them (OpenImageIO's module pulls in OpenVDB, whose log4cplus starts an idle pool of
 * 4 as it is loaded). They are recognised by the loader on the call stack (a frame in ld-linux, which runs the
 * initialisers).
 *
 * At exit the counts are appended, as "threads N" (started by running code) and "at_load N" (by initialisers),
 * one per line, to the file named by MR_THREAD_COUNT_FILE (nothing is written when it is unset). Not built with
 * the sanitizers: it is a test instrument, not project code.
 */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <errno.h>
#include <execinfo.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef int (*create_fn)(pthread_t *, const pthread_attr_t *, void *(*)(void *), void *);

static atomic_long started, at_load;

/* Is the dynamic loader on the stack, i.e. is a library initialiser running? */
static int loading(void) {
    void *frames[64];
    const int n = backtrace(frames, 64);
    for (int i = 1; i < n; i++) {
        Dl_info info;
        if (dladdr(frames[i], &info) != 0 && info.dli_fname != NULL && strstr(info.dli_fname, "/ld-linux") != NULL)
            return 1;
    }
    return 0;
}

int pthread_create(pthread_t *thread, const pthread_attr_t *attr, void *(*start)(void *), void *arg) {
    union { void *object; create_fn function; } next = {dlsym(RTLD_NEXT, "pthread_create")}; // ISO C has no cast
    if (next.object == NULL) return EAGAIN;
    atomic_fetch_add(loading() ? &at_load : &started, 1);
    return next.function(thread, attr, start, arg);
}

/* backtrace() loads libgcc's unwinder on its first call: done here, not in the middle of a dlopen. */
__attribute__((constructor)) static void prepare(void) {
    void *frame[1];
    (void)backtrace(frame, 1);
}

__attribute__((destructor)) static void report_count(void) {
    const char *path = getenv("MR_THREAD_COUNT_FILE");
    if (path == NULL || path[0] == '\0') return;
    FILE *f = fopen(path, "a");
    if (f == NULL) return;
    fprintf(f, "threads %ld\nat_load %ld\n", atomic_load(&started), atomic_load(&at_load));
    fclose(f);
}
