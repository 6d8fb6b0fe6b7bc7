/*
 * text_lines.h — a text held in memory read line by line and each line token by token: the tokenizer of the
 * library's strict text formats, the learned transform (.mrt, src/learn/learned_file.c) and the network weights
 * (.mlp, nn/weights.c). Lines end in '\n' (every one, the last included: a missing one means a truncated file);
 * tokens are separated by spaces. It sets no message: each format names its file and what it expected its way.
 * Internal; a plain struct over borrowed bytes (copy it to remember a place and go back to it), nothing to free.
 */
#ifndef MR_TEXT_LINES_H
#define MR_TEXT_LINES_H

#include <stddef.h>

typedef struct mr_text_lines {
    const char *start, *p, *end; /* the whole text [start, end); the unread bytes from p */
    long line;                   /* the current line's number (1-based); 0 before the first */
    const char *line_start;      /* where the current line began */
    const char *s, *e;           /* the current line's unread part, without its '\n' */
} mr_text_lines;

/* What mr_text_lines_next found. */
typedef enum mr_text_line_result {
    MR_TEXT_LINE = 0,    /* the next line: line counted, line_start, s and e set */
    MR_TEXT_END,         /* no bytes left */
    MR_TEXT_NO_LINE_END  /* bytes left, but no '\n' after them */
} mr_text_line_result;

/* Start reading text[0, size) (text may be NULL when size is 0). */
void mr_text_lines_init(mr_text_lines *t, const char *text, size_t size);

/* Step to the next line. On MR_TEXT_END and MR_TEXT_NO_LINE_END nothing changes. */
mr_text_line_result mr_text_lines_next(mr_text_lines *t);

/* The next space-separated token of the current line into *tok / *len; 0 at the end of the line. */
int mr_text_lines_token(mr_text_lines *t, const char **tok, size_t *len);

/* 1 if tok[0, len) is exactly `word`. */
int mr_text_token_is(const char *tok, size_t len, const char *word);

#endif /* MR_TEXT_LINES_H */
