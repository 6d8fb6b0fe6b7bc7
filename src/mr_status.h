/*
 * mr_status.h — the one status enum of libmatremap and its thread-local last-error message.
 *
 * Every fallible public function returns mr_status and writes its results through out-pointers, which are
 * left untouched on failure. After a non-OK return, mr_last_error() holds a one-line message naming what
 * failed, the offending value and what was expected ("what: where: why"). Like errno, the message is only
 * meaningful right after a failing call, and it is per thread (C11 _Thread_local), so parallel callers do not
 * see each other's messages.
 *
 * Library code never prints, exits or aborts on bad input; only the command-line front ends print.
 */
#ifndef MR_STATUS_H
#define MR_STATUS_H

#ifdef __cplusplus
extern "C" {
#endif

/* Values are append-only: new codes may be added at the end (before MR_STATUS_COUNT). */
typedef enum mr_status {
    MR_OK = 0,
    MR_ERR_INVALID_ARG,  /* a caller-supplied value is out of range, unknown or inconsistent */
    MR_ERR_NOMEM,        /* an allocation failed */
    MR_ERR_IO,           /* a file could not be opened, read, written or renamed */
    MR_ERR_FORMAT,       /* a file was read but its content is malformed or not what was expected */
    MR_ERR_UNSUPPORTED,  /* a valid request this build or this model cannot honour */
    MR_ERR_NUMERIC,      /* a computation produced a non-finite value that could not be guarded */
    MR_ERR_EXTERNAL,     /* a third-party library (OpenImageIO, OpenEXR, nlopt, ...) failed */
    MR_ERR_CANCELLED,    /* the caller asked the operation to stop */
    MR_STATUS_COUNT
} mr_status;

/* The constant's name, e.g. "MR_ERR_IO"; "MR_STATUS_UNKNOWN" for values outside the enum. */
const char *mr_status_str(mr_status status);

/* The message recorded by the last failing call on this thread; "" if none. Never NULL. */
const char *mr_last_error(void);

/* Forget the recorded message (the next mr_last_error() returns ""). */
void mr_clear_error(void);

#ifdef __cplusplus
}
#endif

#endif /* MR_STATUS_H */
