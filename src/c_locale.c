/*
 * c_locale.c — the per-thread C numeric locale of text I/O (c_locale.h says why).
 */
#include "c_locale.h"

#include "mr_internal.h"

mr_status mr_c_numeric_enter(mr_c_numeric *s, const char *what) {
    s->saved = (locale_t)0;
    s->c = newlocale(LC_NUMERIC_MASK, "C", (locale_t)0);
    if (s->c == (locale_t)0) return mr_fail(MR_ERR_NOMEM, "%s: cannot create the C numeric locale", what);
    s->saved = uselocale(s->c);
    return MR_OK;
}

void mr_c_numeric_leave(mr_c_numeric *s) {
    uselocale(s->saved);
    freelocale(s->c);
}
