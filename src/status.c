/* status.c — status names and the thread-local last-error message (contract in mr_status.h). */
#include "mr_internal.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#define MR_ERROR_CAPACITY 1024

static _Thread_local char last_error[MR_ERROR_CAPACITY];

static const char *const status_names[MR_STATUS_COUNT] = {
    "MR_OK",           "MR_ERR_INVALID_ARG", "MR_ERR_NOMEM",    "MR_ERR_IO",        "MR_ERR_FORMAT",
    "MR_ERR_UNSUPPORTED", "MR_ERR_NUMERIC",  "MR_ERR_EXTERNAL", "MR_ERR_CANCELLED",
};

const char *mr_status_str(mr_status status) {
    if ((int)status < 0 || status >= MR_STATUS_COUNT) return "MR_STATUS_UNKNOWN";
    return status_names[status];
}

const char *mr_last_error(void) { return last_error; }

void mr_clear_error(void) { last_error[0] = '\0'; }

mr_status mr_fail(mr_status status, const char *fmt, ...) {
    va_list args;
    va_start(args, fmt);
    vsnprintf(last_error, sizeof last_error, fmt, args);
    va_end(args);
    return status;
}

mr_status mr_fail_context(mr_status status, const char *fmt, ...) {
    char inner[MR_ERROR_CAPACITY];
    char outer[MR_ERROR_CAPACITY];
    memcpy(inner, last_error, sizeof inner);
    va_list args;
    va_start(args, fmt);
    vsnprintf(outer, sizeof outer, fmt, args);
    va_end(args);
    // Concatenate by hand: truncation to the buffer is intended, and snprintf("%s: %s") would make gcc's
    // -Wformat-truncation object to it.
    size_t used = strnlen(outer, sizeof outer - 1);
    memcpy(last_error, outer, used);
    if (inner[0] != '\0' && used + 2 < sizeof last_error) {
        memcpy(last_error + used, ": ", 2);
        used += 2;
        size_t rest = strnlen(inner, sizeof last_error - 1 - used);
        memcpy(last_error + used, inner, rest);
        used += rest;
    }
    last_error[used] = '\0';
    return status;
}
