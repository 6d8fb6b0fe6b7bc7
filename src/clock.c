/*
 * clock.c — the monotonic clock for the times the library reports (mr_internal.h).
 */
#include <time.h>

#include "mr_internal.h"

double mr_now_seconds(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}
