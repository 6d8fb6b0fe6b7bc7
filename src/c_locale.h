/*
 * c_locale.h — numbers in text files are written and read in the C locale, whatever the host program's
 * (internal; not installed).
 *
 * printf's "%g" and strtod follow LC_NUMERIC: a program that called setlocale(LC_ALL, "") under a decimal-comma
 * locale would write "0,99" into our sweeps, weight files and summary.json, and could not read them back. Every
 * function of the library that formats or parses numbers in text brackets that work with mr_c_numeric_enter /
 * mr_c_numeric_leave, which switch the calling thread alone to the C numeric locale with uselocale() (POSIX.1-2008):
 * the host's locale is neither used by us nor changed for its other threads. tests/test_locale.c checks it under a
 * decimal-comma locale.
 */
#ifndef MR_C_LOCALE_H
#define MR_C_LOCALE_H

#include <locale.h>

#include "mr_status.h"

typedef struct mr_c_numeric {
    locale_t c;     /* the C numeric locale this bracket created */
    locale_t saved; /* the thread's locale before it (restored on leave) */
} mr_c_numeric;

/* Switch this thread to the C numeric locale until mr_c_numeric_leave(s). `what` names the caller in the error
 * (MR_ERR_NOMEM: the locale object could not be created; nothing changed then, and leave must not be called). */
mr_status mr_c_numeric_enter(mr_c_numeric *s, const char *what);

/* Restore the thread's previous locale and free the bracket's. */
void mr_c_numeric_leave(mr_c_numeric *s);

#endif /* MR_C_LOCALE_H */
