/*
 * text_lines.c — line-by-line, token-by-token reading of a text in memory (contract in text_lines.h).
 */
#include "text_lines.h"

#include <string.h>

void mr_text_lines_init(mr_text_lines *t, const char *text, size_t size) {
    const char *start = text != NULL ? text : "";
    memset(t, 0, sizeof *t);
    t->start = t->p = start;
    t->end = start + (text != NULL ? size : 0);
}

mr_text_line_result mr_text_lines_next(mr_text_lines *t) {
    if (t->p >= t->end) return MR_TEXT_END;
    const char *nl = memchr(t->p, '\n', (size_t)(t->end - t->p));
    if (nl == NULL) return MR_TEXT_NO_LINE_END;
    t->line++;
    t->line_start = t->s = t->p;
    t->e = nl;
    t->p = nl + 1;
    return MR_TEXT_LINE;
}

int mr_text_lines_token(mr_text_lines *t, const char **tok, size_t *len) {
    while (t->s < t->e && *t->s == ' ') t->s++;
    if (t->s >= t->e) return 0;
    *tok = t->s;
    while (t->s < t->e && *t->s != ' ') t->s++;
    *len = (size_t)(t->s - *tok);
    return 1;
}

int mr_text_token_is(const char *tok, size_t len, const char *word) {
    return len == strlen(word) && memcmp(tok, word, len) == 0;
}
