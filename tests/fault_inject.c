/*
 * fault_inject.c — the allocation and I/O fault injector of the fault build (`make faults`, scripts/faults.sh).
 *
 * In the spirit of SQLite's malloc and I/O-error tests (src/test_malloc.c, test_vfs.c): a counter per class of
 * call, and the N-th call of a class fails; with MR_FAULT_PERSIST=1 every later call of that class fails too
 * (SQLite's "persistent" mode), so error paths that allocate or write again are exercised as well.
 *
 * Mechanism: GNU ld's --wrap. The fault build links build/faults/bin/matremap with
 * -Wl,--wrap=malloc,--wrap=calloc,... (FAULT_WRAP in the Makefile), which sends every call that the project's
 * own, statically linked objects make to malloc (etc.) to __wrap_malloc here, and __real_malloc reaches the real
 * one — ASan's, in this build, so leak and overflow checking stay underneath. Only the project's calls are
 * counted: the shared libraries (glibc, libstdc++, libpng, OpenEXR, OpenImageIO, tinygltf, libgomp) keep calling
 * their own allocator and writes directly. That is the point: the contract under test is that *our* code checks
 * what it calls; a library failing inside is reported through that library's own error return, which our code
 * checks as well. C++ operator new (the glTF and image shims) is counted too (fault_inject_new.cpp throws
 * std::bad_alloc, which the shims must catch and turn into MR_ERR_NOMEM).
 *
 * Classes and what an injected failure looks like (the errno a real failure would leave):
 *   alloc  malloc, calloc, realloc, strdup (NULL, ENOMEM) and operator new (std::bad_alloc; the nothrow forms
 *          NULL). realloc(p, n) fails leaving p allocated, as the real one does.
 *   io     writes to files (never stdin/stdout/stderr, never memory streams of fmemopen/open_memstream, whose
 *          growth is glibc's own allocation): fopen for writing (NULL), open for writing or creating (-1), write,
 *          fwrite, fputs, fputc, putc, fprintf, vfprintf, fflush (ENOSPC), fclose of a written stream (EOF, ENOSPC;
 *          the stream is closed and freed all the same, as glibc does), fsync, ftruncate, rename (EIO), mkdir
 *          (ENOSPC). A failed stdio write also sets the stream's error indicator, as a real one does, so code that
 *          checks ferror() at the end sees it.
 * Reads, unlink/rmdir/remove (cleanup) and stdout/stderr are not counted: a failing read is the fuzzers' subject
 * (issue 16, part 6), and cleanup that fails cannot be recovered from.
 *
 * Counting starts when main() starts (main is wrapped as well): allocations of C++ static initialisers cannot
 * report a failure to anyone, and would make every run's first faults abort before the command ran.
 *
 * Environment (read once, at the start of main):
 *   MR_FAULT_ALLOC=N       fail the N-th counted allocation (1-based; unset or 0: none)
 *   MR_FAULT_IO=N          fail the N-th counted I/O call
 *   MR_FAULT_PERSIST=1     after the first injected failure of a class, fail every later call of that class too
 *   MR_FAULT_COUNT_FILE=F  at exit, write to F: "alloc A", "io W" (calls counted), "injected_alloc K",
 *                          "injected_io K" (failures injected), "spared K" (operator new calls of nlohmann/json's
 *                          destructor let through: fault_inject_new.cpp) and "first NAME": the first call that
 *                          failed (e.g. "first rename"; "-": none), one per line
 *   MR_FAULT_TRACE=F       append a backtrace of every injected failure to F (for finding the call site:
 *                          addr2line -e build/faults/bin/matremap OFFSET)
 * Counters are atomic, but which call is the N-th is only reproducible with one thread: the driver sets
 * OMP_NUM_THREADS=1.
 */
#include <errno.h>
#include <execinfo.h>
#include <fcntl.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <unistd.h>

#include "fault_inject.h"

/* glibc's FILE flags (libio): a stream opened read-only carries _IO_NO_WRITES; _IO_ERR_SEEN is what ferror()
 * reports. The fault build is a glibc + GNU ld build by construction (--wrap), so relying on them is fine. */
#define FAULT_IO_NO_WRITES 0x0008
#ifndef _IO_ERR_SEEN
#define _IO_ERR_SEEN 0x0020
#endif

typedef struct fault_class {
    long target;          /* the call number to fail, 0: none */
    atomic_long calls;    /* calls counted so far */
    atomic_long injected; /* failures injected so far */
} fault_class;

static fault_class alloc_class, io_class;
static int persist;
static atomic_int armed; /* set when main starts */
static const char *count_file, *trace_file;
static char first_name[32];

void *__real_malloc(size_t size);
void *__real_calloc(size_t count, size_t size);
void *__real_realloc(void *ptr, size_t size);
char *__real_strdup(const char *s);
FILE *__real_fopen(const char *path, const char *mode);
int __real_open(const char *path, int flags, ...);
ssize_t __real_write(int fd, const void *buf, size_t count);
size_t __real_fwrite(const void *ptr, size_t size, size_t count, FILE *stream);
int __real_fputs(const char *s, FILE *stream);
int __real_fputc(int c, FILE *stream);
int __real_putc(int c, FILE *stream);
int __real_vfprintf(FILE *stream, const char *fmt, va_list args);
int __real_fflush(FILE *stream);
int __real_fclose(FILE *stream);
int __real_fsync(int fd);
int __real_ftruncate(int fd, off_t length);
int __real_rename(const char *from, const char *to);
int __real_mkdir(const char *path, mode_t mode);
int __real_main(int argc, char **argv, char **envp);

static void trace(const char *name) {
    if (trace_file == NULL)
        return;
    int fd = __real_open(trace_file, O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0666);
    if (fd < 0)
        return;
    char head[96];
    int n = snprintf(head, sizeof head, "-- injected: %s\n", name);
    if (n > 0)
        (void)!__real_write(fd, head, (size_t)n);
    void *frames[48];
    int depth = backtrace(frames, 48);
    backtrace_symbols_fd(frames, depth, fd);
    close(fd);
}

static atomic_long spared; /* failures not injected because `spare` said so (mr_fault_alloc_hit) */

/* Count a call of class c; 1 if this call must fail. `spare` (may be NULL) is asked only when the call would fail:
 * if it returns 1 the call goes through after all, and is counted as spared. */
static int fault_hit(fault_class *c, const char *name, int (*spare)(void)) {
    if (!atomic_load(&armed))
        return 0;
    long n = atomic_fetch_add(&c->calls, 1) + 1;
    if (c->target <= 0 || n < c->target)
        return 0;
    if (n > c->target && !persist)
        return 0;
    if (spare != NULL && spare()) {
        atomic_fetch_add(&spared, 1);
        return 0;
    }
    if (atomic_fetch_add(&c->injected, 1) == 0 && first_name[0] == '\0')
        snprintf(first_name, sizeof first_name, "%s", name);
    trace(name);
    return 1;
}

int mr_fault_alloc_hit(const char *name, int (*spare)(void)) { return fault_hit(&alloc_class, name, spare); }

/* ---- allocation -------------------------------------------------------------------------------------------- */

void *__wrap_malloc(size_t size) {
    if (fault_hit(&alloc_class, "malloc", NULL)) {
        errno = ENOMEM;
        return NULL;
    }
    return __real_malloc(size);
}

void *__wrap_calloc(size_t count, size_t size) {
    if (fault_hit(&alloc_class, "calloc", NULL)) {
        errno = ENOMEM;
        return NULL;
    }
    return __real_calloc(count, size);
}

void *__wrap_realloc(void *ptr, size_t size) {
    if (fault_hit(&alloc_class, "realloc", NULL)) {
        errno = ENOMEM;
        return NULL; /* ptr stays allocated, as with a real failure */
    }
    return __real_realloc(ptr, size);
}

char *__wrap_strdup(const char *s) {
    if (fault_hit(&alloc_class, "strdup", NULL)) {
        errno = ENOMEM;
        return NULL;
    }
    return __real_strdup(s);
}

/* ---- I/O ----------------------------------------------------------------------------------------------------- */

/* A stream whose writes are counted: a file written by the program (not a standard stream, not a memory stream,
 * not opened read-only). */
static int counted_stream(FILE *f) {
    if (f == NULL || f == stdin || f == stdout || f == stderr)
        return 0;
    if (fileno(f) < 0)
        return 0; /* fmemopen / open_memstream */
    return (f->_flags & FAULT_IO_NO_WRITES) == 0;
}

static int stream_fault(FILE *f, const char *name) {
    if (!counted_stream(f) || !fault_hit(&io_class, name, NULL))
        return 0;
    f->_flags |= _IO_ERR_SEEN;
    errno = ENOSPC;
    return 1;
}

FILE *__wrap_fopen(const char *path, const char *mode) {
    int writes = mode != NULL && strpbrk(mode, "wa+") != NULL;
    if (writes && fault_hit(&io_class, "fopen", NULL)) {
        errno = ENOSPC;
        return NULL;
    }
    return __real_fopen(path, mode);
}

int __wrap_open(const char *path, int flags, ...) {
    mode_t mode = 0;
    if (flags & O_CREAT) {
        va_list args;
        va_start(args, flags);
        mode = (mode_t)va_arg(args, int);
        va_end(args);
    }
    int writes = (flags & (O_WRONLY | O_RDWR | O_CREAT | O_TRUNC | O_APPEND)) != 0;
    if (writes && fault_hit(&io_class, "open", NULL)) {
        errno = ENOSPC;
        return -1;
    }
    return __real_open(path, flags, mode);
}

ssize_t __wrap_write(int fd, const void *buf, size_t count) {
    if (fd > 2 && fault_hit(&io_class, "write", NULL)) {
        errno = ENOSPC;
        return -1;
    }
    return __real_write(fd, buf, count);
}

size_t __wrap_fwrite(const void *ptr, size_t size, size_t count, FILE *stream) {
    if (stream_fault(stream, "fwrite"))
        return 0;
    return __real_fwrite(ptr, size, count, stream);
}

int __wrap_fputs(const char *s, FILE *stream) {
    if (stream_fault(stream, "fputs"))
        return EOF;
    return __real_fputs(s, stream);
}

int __wrap_fputc(int c, FILE *stream) {
    if (stream_fault(stream, "fputc"))
        return EOF;
    return __real_fputc(c, stream);
}

int __wrap_putc(int c, FILE *stream) {
    if (stream_fault(stream, "putc"))
        return EOF;
    return __real_putc(c, stream);
}

int __wrap_vfprintf(FILE *stream, const char *fmt, va_list args) {
    if (stream_fault(stream, "vfprintf"))
        return -1;
    return __real_vfprintf(stream, fmt, args);
}

int __wrap_fprintf(FILE *stream, const char *fmt, ...) {
    if (stream_fault(stream, "fprintf"))
        return -1;
    va_list args;
    va_start(args, fmt);
    int n = __real_vfprintf(stream, fmt, args);
    va_end(args);
    return n;
}

int __wrap_fflush(FILE *stream) {
    if (stream_fault(stream, "fflush"))
        return EOF;
    return __real_fflush(stream);
}

int __wrap_fclose(FILE *stream) {
    int counted = counted_stream(stream) && fault_hit(&io_class, "fclose", NULL);
    int rc = __real_fclose(stream); /* closed and freed even when it fails, as glibc's */
    if (counted) {
        errno = ENOSPC;
        return EOF;
    }
    return rc;
}

int __wrap_fsync(int fd) {
    if (fault_hit(&io_class, "fsync", NULL)) {
        errno = EIO;
        return -1;
    }
    return __real_fsync(fd);
}

int __wrap_ftruncate(int fd, off_t length) {
    if (fault_hit(&io_class, "ftruncate", NULL)) {
        errno = EIO;
        return -1;
    }
    return __real_ftruncate(fd, length);
}

int __wrap_rename(const char *from, const char *to) {
    if (fault_hit(&io_class, "rename", NULL)) {
        errno = EIO;
        return -1;
    }
    return __real_rename(from, to);
}

int __wrap_mkdir(const char *path, mode_t mode) {
    if (fault_hit(&io_class, "mkdir", NULL)) {
        errno = ENOSPC;
        return -1;
    }
    return __real_mkdir(path, mode);
}

/* ---- set-up and the count file ------------------------------------------------------------------------------- */

static long env_long(const char *name) {
    const char *text = getenv(name);
    return text != NULL ? strtol(text, NULL, 10) : 0;
}

/* Runs at exit() and after main returns, so every way a command ends normally reports its counts. */
__attribute__((destructor)) static void write_counts(void) {
    if (count_file == NULL || !atomic_load(&armed))
        return;
    atomic_store(&armed, 0); /* the report's own calls are not counted */
    char text[256];
    int n =
        snprintf(text, sizeof text, "alloc %ld\nio %ld\ninjected_alloc %ld\ninjected_io %ld\nspared %ld\nfirst %s\n",
                 atomic_load(&alloc_class.calls), atomic_load(&io_class.calls), atomic_load(&alloc_class.injected),
                 atomic_load(&io_class.injected), atomic_load(&spared), first_name[0] ? first_name : "-");
    int fd = __real_open(count_file, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
    if (fd < 0)
        return;
    if (n > 0)
        (void)!__real_write(fd, text, (size_t)n);
    close(fd);
}

int __wrap_main(int argc, char **argv, char **envp) {
    alloc_class.target = env_long("MR_FAULT_ALLOC");
    io_class.target = env_long("MR_FAULT_IO");
    persist = env_long("MR_FAULT_PERSIST") != 0;
    count_file = getenv("MR_FAULT_COUNT_FILE");
    trace_file = getenv("MR_FAULT_TRACE");
    atomic_store(&armed, 1);
    return __real_main(argc, argv, envp);
}
