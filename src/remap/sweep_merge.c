/*
 * sweep_merge.c — the shards of a sweep merged into the file a single run would have written (mr_sweep_merge,
 * contract in sweep.h): each shard's header read back into a sweep and rebuilt byte for byte (sweep_file.c), the
 * shards checked to be the N parts of one sweep, each once, complete and no longer being written, then their rows
 * interleaved in index order, every one checked as on resume, into a temporary file renamed into place.
 */
#include "sweep.h"

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "../c_locale.h"
#include "../mr_internal.h"
#include "remap_file.h"
#include "sweep_file.h"
#include "sweep_internal.h"

/* Longest line merge reads (a header's command line can be long; a row is at most MR_SWEEP_MAX_LINE): a file
 * that is one endless line is refused, not swallowed. */
#define MERGE_MAX_LINE (1L << 20)

/* The next line of fp into *buf (grown as needed, NUL-terminated, '\n' kept) and *len; 0 at the end of the file,
 * -1 for a line longer than MERGE_MAX_LINE (MR_ERR_FORMAT) or out of memory (MR_ERR_NOMEM) in *failure, the
 * message naming `path` and the line. */
static int read_line(FILE *fp, const char *path, long line_number, char **buf, size_t *cap, size_t *len,
                     mr_status *failure) {
    *len = 0;
    for (;;) {
        if (*cap - *len < 2) {
            size_t grown = *cap ? 2 * *cap : 4096;
            char *p = realloc(*buf, grown);
            if (p == NULL) {
                *failure = mr_fail(MR_ERR_NOMEM, "shard file '%s': out of memory reading line %ld", path, line_number);
                return -1;
            }
            *buf = p;
            *cap = grown;
        }
        if (fgets(*buf + *len, (int)MR_MIN(*cap - *len, (size_t)INT_MAX), fp) == NULL)
            return *len > 0;
        *len += strlen(*buf + *len);
        if (*len > 0 && (*buf)[*len - 1] == '\n')
            return 1;
        if (*len > (size_t)MERGE_MAX_LINE) {
            *failure = mr_fail(MR_ERR_FORMAT, "shard file '%s': line %ld is longer than %ld bytes", path, line_number,
                               MERGE_MAX_LINE);
            return -1;
        }
    }
}

/* The text after `prefix` of the header line that starts with it, or NULL. */
static const char *header_field(char *const *lines, int count, const char *prefix) {
    size_t n = strlen(prefix);
    for (int i = 0; i < count; i++)
        if (strncmp(lines[i], prefix, n) == 0)
            return lines[i] + n;
    return NULL;
}

static int parse_whole_long(const char *text, long *out) { return mr_csv_parse_long(text, strlen(text), out); }

/* One shard file being merged. */
typedef struct merge_shard {
    const char *path;
    FILE *fp;
    mr_sweep_spec spec;
    long k, n;
    char *bare;       /* the header without its "# shard:" and "# command:" lines: equal for shards of one sweep */
    long line_number; /* of the last line read */
    dev_t dev;
    ino_t ino;
} merge_shard;

/* The first line where the texts *x and *y differ: its number (from 1), with *x and *y moved to its start in
 * each, for a message that shows both. */
static long first_differing_line(const char **x, const char **y) {
    const char *a = *x, *b = *y, *start = *x;
    long line = 1;
    while (*a && *a == *b) {
        if (*a == '\n')
            line++;
        a++;
        b++;
    }
    while (a > start && a[-1] != '\n')
        a--, b--;
    *x = a;
    *y = b;
    return line;
}

/* Read and check a shard's header: parsed back into a sweep, which must rebuild the header byte for byte. */
static mr_status read_shard_header(merge_shard *s) {
    enum { MAX_HEADER_LINES = 32 };
    char *lines[MAX_HEADER_LINES] = {0};
    int count = 0;
    char *buf = NULL;
    size_t cap = 0, len = 0;
    mr_status status = MR_OK;
    mr_strbuf file_header = {0}, rebuilt = {0}, bare = {0};
    for (;;) { /* the '#' lines and the column line */
        int got = read_line(s->fp, s->path, s->line_number + 1, &buf, &cap, &len, &status);
        if (got < 0)
            break;
        if (got == 0 || buf[len - 1] != '\n') {
            status = mr_fail(MR_ERR_FORMAT, "shard file '%s': the header ends early, at line %ld (%s)", s->path,
                             s->line_number + 1, got ? "a torn line" : "the end of the file");
            break;
        }
        s->line_number++;
        if (count == MAX_HEADER_LINES) {
            status = mr_fail(MR_ERR_FORMAT, "shard file '%s': no column line after %d header lines", s->path, count);
            break;
        }
        mr_strbuf_printf(&file_header, "%s", buf);
        buf[len - 1] = '\0';
        lines[count] = strdup(buf);
        if (lines[count++] == NULL) {
            status = mr_fail(MR_ERR_NOMEM, "shard file '%s': out of memory", s->path);
            break;
        }
        if (buf[0] != '#')
            break; /* the column line ends the header */
    }
    free(buf);
    const char *from = NULL, *to = NULL, *remap = NULL, *scene = NULL, *sampling = NULL, *shard = NULL;
    const char *command = NULL;
    if (status == MR_OK) {
        from = header_field(lines, count, MR_SWEEP_FROM_PREFIX);
        to = header_field(lines, count, MR_SWEEP_TO_PREFIX);
        remap = header_field(lines, count, MR_SWEEP_REMAP_PREFIX);
        scene = header_field(lines, count, MR_SWEEP_SCENE_PREFIX);
        sampling = header_field(lines, count, MR_SWEEP_SAMPLING_PREFIX);
        shard = header_field(lines, count, MR_SWEEP_SHARD_PREFIX);
        command = header_field(lines, count, MR_SWEEP_COMMAND_PREFIX);
        if (strncmp(lines[0], "# matremap ", 11) != 0 || from == NULL || to == NULL || remap == NULL || scene == NULL ||
            sampling == NULL || command == NULL)
            status = mr_fail(MR_ERR_FORMAT,
                             "shard file '%s' is not a sweep file (its header lacks a '# from:', "
                             "'# to:', '# remap:', '# scene:', '# sampling:' or '# command:' line)",
                             s->path);
        else if (shard == NULL)
            status = mr_fail(MR_ERR_FORMAT,
                             "'%s' is a whole sweep, not a shard (its header has no '# shard: K/N' "
                             "line): merge takes the files of 'matremap sweep ... --shard K/N' runs",
                             s->path);
    }
    if (status == MR_OK) {
        const char *slash = strchr(shard, '/');
        char kbuf[32];
        size_t klen = slash ? (size_t)(slash - shard) : 0;
        if (klen > 0 && klen < sizeof kbuf) {
            memcpy(kbuf, shard, klen);
            kbuf[klen] = '\0';
        }
        if (slash == NULL || klen == 0 || klen >= sizeof kbuf || !parse_whole_long(kbuf, &s->k) ||
            !parse_whole_long(slash + 1, &s->n) || s->n < 1 || s->k >= s->n)
            status =
                mr_fail(MR_ERR_FORMAT, "shard file '%s': '# shard: %s' is not K/N with 0 <= K < N", s->path, shard);
    }
    // The sweep, read back. A line this version would write otherwise shows in the comparison below.
    if (status == MR_OK) {
        const char *step = NULL;
        status = mr_sweep_file_spec_from_header(from, to, remap, scene, sampling, &s->spec, &step);
        if (status != MR_OK)
            status = mr_fail_context(MR_ERR_FORMAT, "shard file '%s': %s line", s->path, step);
    }
    if (status == MR_OK) {
        status = mr_sweep_file_header(&s->spec, command, s->k, s->n, &rebuilt);
        if (status == MR_OK && (file_header.failed || rebuilt.length != file_header.length ||
                                memcmp(rebuilt.text, file_header.text, rebuilt.length) != 0)) {
            const char *a = file_header.text ? file_header.text : "", *b = rebuilt.text;
            const long line = first_differing_line(&a, &b);
            status =
                mr_fail(MR_ERR_FORMAT,
                        "shard file '%s': line %ld is '%.*s', but the sweep its header describes would have "
                        "'%.*s' (written by another matremap version, or edited?)",
                        s->path, line, (int)MR_MIN(strcspn(a, "\n"), 200), a, (int)MR_MIN(strcspn(b, "\n"), 200), b);
        }
    }
    if (status == MR_OK) {
        for (int i = 0; i < count; i++)
            if (strncmp(lines[i], MR_SWEEP_SHARD_PREFIX, strlen(MR_SWEEP_SHARD_PREFIX)) != 0 &&
                strncmp(lines[i], MR_SWEEP_COMMAND_PREFIX, strlen(MR_SWEEP_COMMAND_PREFIX)) != 0)
                mr_strbuf_printf(&bare, "%s\n", lines[i]);
        if (bare.failed)
            status = mr_fail(MR_ERR_NOMEM, "shard file '%s': out of memory", s->path);
        s->bare = bare.text;
        bare.text = NULL;
    }
    for (int i = 0; i < count; i++)
        free(lines[i]);
    free(file_header.text);
    free(rebuilt.text);
    free(bare.text);
    return status;
}

/* The first line where two shards' headers (shard and command lines left out) differ, for the message. */
static mr_status shards_differ(const merge_shard *a, const merge_shard *b) {
    const char *x = a->bare, *y = b->bare;
    first_differing_line(&x, &y);
    return mr_fail(MR_ERR_INVALID_ARG,
                   "shard files '%s' and '%s' are from different sweeps: '%.*s' in the first, '%.*s' in the second",
                   a->path, b->path, (int)MR_MIN(strcspn(x, "\n"), 200), x, (int)MR_MIN(strcspn(y, "\n"), 200), y);
}

/* Open a shard and read its header. */
static mr_status open_shard(merge_shard *s) {
    // Regular files only, opened without blocking (fopen blocked on a FIFO named as a shard).
    char label[MR_IO_LABEL_SIZE + 16];
    snprintf(label, sizeof label, "shard file '%s'", s->path);
    mr_status opened = mr_io_open_input(s->path, label, 0, &s->fp, NULL);
    if (opened != MR_OK) return opened == MR_ERR_IO && errno == ENOENT ? MR_ERR_INVALID_ARG : opened;
    struct stat st;
    if (fstat(fileno(s->fp), &st) != 0 || !S_ISREG(st.st_mode))
        return mr_fail(MR_ERR_INVALID_ARG, "shard file '%s' is not a regular file", s->path);
    s->dev = st.st_dev;
    s->ino = st.st_ino;
    // A sweep still writing the shard holds its write lock (mr_text_file_lock): its rows are not all there yet.
    struct flock lock;
    memset(&lock, 0, sizeof lock);
    lock.l_type = F_WRLCK;
    lock.l_whence = SEEK_SET;
    if (fcntl(fileno(s->fp), F_GETLK, &lock) == 0 && lock.l_type != F_UNLCK)
        return mr_fail(MR_ERR_INVALID_ARG,
                       "shard file '%s' is being written by another process (pid %ld): merge it when its sweep has "
                       "finished",
                       s->path, (long)lock.l_pid);
    return read_shard_header(s);
}

/* Copy the rows of the shards, in index order (sample i is row i / N of shard i % N), into out, checking each. */
static mr_status merge_rows(merge_shard *const *by_k, long n, const mr_sweep_spec *spec, long total, FILE *out) {
    char *buf = NULL;
    size_t cap = 0, len = 0;
    mr_status status = MR_OK;
    for (long i = 0; status == MR_OK && i < total; i++) {
        merge_shard *s = by_k[i % n];
        const long want = mr_sweep_shard_size(total, s->k, s->n);
        int got = read_line(s->fp, s->path, s->line_number + 1, &buf, &cap, &len, &status);
        if (got < 0)
            break;
        if (got == 0) {
            status = mr_fail(MR_ERR_INVALID_ARG,
                             "shard file '%s' (shard %ld/%ld) ends after %ld of its %ld rows, at sample %ld: finish "
                             "it first (run its sweep again with --resume)",
                             s->path, s->k, s->n, i / n, want, i);
            break;
        }
        s->line_number++;
        if (buf[len - 1] != '\n') {
            status = mr_fail(MR_ERR_INVALID_ARG,
                             "shard file '%s': line %ld is torn (no line end): the shard was interrupted; finish it "
                             "first (run its sweep again with --resume)",
                             s->path, s->line_number);
            break;
        }
        mr_sweep_row row;
        status = mr_sweep_check_line(spec, total, s->k, s->n, buf, len, &row);
        if (status == MR_OK && row.index != i)
            status = mr_fail(row.index < i ? MR_ERR_FORMAT : MR_ERR_INVALID_ARG,
                             "sample %ld where sample %ld belongs (%s)", row.index, i,
                             row.index < i ? "a sample twice, or rows out of order: an unfinished shard? run its "
                                             "sweep again with --resume"
                                           : "samples are missing: finish the shard first (run its sweep again "
                                             "with --resume)");
        if (status != MR_OK) {
            mr_fail_context(status, "shard file '%s': line %ld", s->path, s->line_number);
            break;
        }
        if (fwrite(buf, 1, len, out) != len) {
            int err = errno;
            status = mr_fail(MR_ERR_IO, "sweep merge: cannot write: %s", strerror(err));
        }
    }
    for (long k = 0; status == MR_OK && k < n; k++) { /* nothing may follow a shard's last sample */
        merge_shard *s = by_k[k];
        int got = read_line(s->fp, s->path, s->line_number + 1, &buf, &cap, &len, &status);
        if (got > 0)
            status = mr_fail(MR_ERR_FORMAT,
                             "shard file '%s': line %ld follows the shard's last sample (%ld rows): an "
                             "edited file?",
                             s->path, s->line_number + 1, mr_sweep_shard_size(total, s->k, s->n));
    }
    free(buf);
    return status;
}

mr_status mr_sweep_merge(const char *const *paths, int count, const char *output, const char *command_line,
                         mr_sweep_merge_summary *out) {
    if (paths == NULL || count < 1)
        return mr_fail(MR_ERR_INVALID_ARG, "sweep merge: no shard files given");
    if (output == NULL || output[0] == '\0')
        return mr_fail(MR_ERR_INVALID_ARG, "sweep merge: empty output path");
    struct stat ost;
    if (lstat(output, &ost) == 0)
        return mr_fail(MR_ERR_INVALID_ARG,
                       "sweep merge: '%s' already exists; not overwriting it (remove it, or "
                       "choose another -o)",
                       output);
    merge_shard *shards = calloc((size_t)count, sizeof *shards);
    merge_shard **by_k = calloc((size_t)count, sizeof *by_k);
    mr_c_numeric cn;
    mr_status status = mr_c_numeric_enter(&cn, "sweep merge");
    if (status != MR_OK) {
        free(shards);
        free(by_k);
        return status;
    }
    if (shards == NULL || by_k == NULL)
        status = mr_fail(MR_ERR_NOMEM, "sweep merge: out of memory");
    for (int i = 0; status == MR_OK && i < count; i++) {
        shards[i].path = paths[i];
        status = open_shard(&shards[i]);
        for (int j = 0; status == MR_OK && j < i; j++)
            if (shards[j].dev == shards[i].dev && shards[j].ino == shards[i].ino)
                status = mr_fail(MR_ERR_INVALID_ARG, "sweep merge: '%s' and '%s' are the same file", shards[j].path,
                                 shards[i].path);
    }
    // They must be the N shards of one sweep, each once.
    const long n = status == MR_OK ? shards[0].n : 0;
    for (int i = 0; status == MR_OK && i < count; i++) {
        merge_shard *s = &shards[i];
        if (s->n != n)
            status = mr_fail(MR_ERR_INVALID_ARG,
                             "shard files '%s' and '%s' split the sweep differently: shard %ld/%ld and %ld/%ld (all "
                             "shards must come from runs with the same N)",
                             shards[0].path, s->path, shards[0].k, shards[0].n, s->k, s->n);
        else if (strcmp(s->bare, shards[0].bare) != 0)
            status = shards_differ(&shards[0], s);
        for (int j = 0; status == MR_OK && j < i; j++)
            if (shards[j].k == s->k)
                status = mr_fail(MR_ERR_INVALID_ARG, "shard files '%s' and '%s' are both shard %ld/%ld", shards[j].path,
                                 s->path, s->k, n);
    }
    if (status == MR_OK && count != n) {
        char missing[512] = "";
        size_t used = 0;
        for (long k = 0, listed = 0; k < n && used + 32 < sizeof missing; k++) {
            int given = 0;
            for (int i = 0; i < count; i++)
                given |= shards[i].k == k;
            if (given)
                continue;
            used += (size_t)snprintf(missing + used, sizeof missing - used, "%s%ld/%ld", listed++ ? ", " : "", k, n);
        }
        status = mr_fail(MR_ERR_INVALID_ARG,
                         "sweep merge: %d shard files given, the sweep has %ld shards; missing: "
                         "%s",
                         count, n, missing);
    }
    for (int i = 0; status == MR_OK && i < count; i++)
        by_k[shards[i].k] = &shards[i]; /* K < N = count */
    mr_atomic_file tmp;
    memset(&tmp, 0, sizeof tmp);
    FILE *fp = NULL;
    long total = 0;
    if (status == MR_OK) {
        total = mr_sweep_total_unchecked(&shards[0].spec);
        status = mr_atomic_begin(output, &tmp);
    }
    if (status == MR_OK && (fp = fopen(tmp.tmp_path, "w")) == NULL) {
        int err = errno;
        status =
            mr_fail(MR_ERR_IO, "sweep merge: cannot open the temporary file '%s': %s", tmp.tmp_path, strerror(err));
    }
    if (status == MR_OK) {
        mr_strbuf header = {0};
        status = mr_sweep_file_header(&shards[0].spec, command_line, 0, 0, &header);
        if (status == MR_OK && fwrite(header.text, 1, header.length, fp) != header.length) {
            int err = errno;
            status = mr_fail(MR_ERR_IO, "sweep merge: cannot write '%s': %s", tmp.tmp_path, strerror(err));
        }
        free(header.text);
    }
    if (status == MR_OK)
        status = merge_rows(by_k, n, &shards[0].spec, total, fp);
    if (fp != NULL) {
        int err = 0;
        if (fflush(fp) != 0)
            err = errno;
        if (fclose(fp) != 0 && err == 0)
            err = errno;
        if (err != 0 && status == MR_OK)
            status = mr_fail(MR_ERR_IO, "sweep merge: cannot write '%s': %s", tmp.tmp_path, strerror(err));
    }
    // Checked again just before the rename: the output may have appeared meanwhile (it is never replaced).
    if (status == MR_OK && lstat(output, &ost) == 0)
        status = mr_fail(MR_ERR_INVALID_ARG, "sweep merge: '%s' appeared while merging; not overwriting it", output);
    if (status == MR_OK)
        status = mr_atomic_commit(&tmp);
    if (status != MR_OK && tmp.active)
        mr_atomic_abort(&tmp);
    mr_c_numeric_leave(&cn);
    for (int i = 0; shards != NULL && i < count; i++) {
        if (shards[i].fp != NULL)
            fclose(shards[i].fp);
        free(shards[i].bare);
    }
    free(shards);
    free(by_k);
    if (status == MR_OK && out != NULL) {
        out->total = total;
        out->shards = n;
    }
    return status;
}
