/*
 * remap_file.c — the crash-safe text files of the remap layer (contract in remap_file.h; sweep.c and direct.c use
 * it).
 *
 * Why the protocol is what it is:
 *   - O_APPEND + one write() per complete line: the kernel places each write at the end of the file as a unit,
 *     so lines of different threads never interleave, and a process killed at any instant has written each line
 *     or not, except that a write can end early: on a full disk (we cut the partial line back ourselves) or,
 *     in principle, on SIGKILL between two pages of the page cache. The next run removes such a torn tail.
 *     stdio buffering would split lines across write()s, so it is not used for them.
 *   - Numbers use the C numeric locale through uselocale(), which is per thread (the callers switch): a host
 *     program that called setlocale() with a decimal comma neither breaks our files nor sees its locale changed.
 */
#include "remap_file.h"

#include <errno.h>
#include <fcntl.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#ifdef _OPENMP
#include <omp.h>
#endif

#include "../c_locale.h"
#include "../mr_internal.h"

/* ---- a growing string ------------------------------------------------------------------------------------ */

void mr_strbuf_printf(mr_strbuf *sb, const char *fmt, ...) {
    if (sb->failed) return;
    for (;;) {
        va_list args;
        va_start(args, fmt);
        size_t room = sb->capacity - sb->length;
        int n = vsnprintf(sb->text ? sb->text + sb->length : NULL, sb->text ? room : 0, fmt, args);
        va_end(args);
        if (n < 0) {
            sb->failed = 1;
            return;
        }
        if (sb->text != NULL && (size_t)n < room) {
            sb->length += (size_t)n;
            return;
        }
        size_t capacity = MR_MAX(2 * sb->capacity, sb->length + (size_t)n + 256);
        char *grown = realloc(sb->text, capacity);
        if (grown == NULL) {
            sb->failed = 1;
            return;
        }
        sb->text = grown;
        sb->capacity = capacity;
    }
}

void mr_strbuf_values(mr_strbuf *sb, const mr_brdf_model *m, const double *values) {
    int slot = 0;
    for (int i = 0; i < m->param_count; i++) {
        const mr_brdf_param *p = &m->params[i];
        const double *v = values + slot;
        slot += p->channels;
        mr_strbuf_printf(sb, " %s=%.17g", p->name, v[0]);
        if (p->channels == 3 && !(v[1] == v[0] && v[2] == v[0])) mr_strbuf_printf(sb, ",%.17g,%.17g", v[1], v[2]);
    }
}

void mr_strbuf_columns(mr_strbuf *sb, const mr_brdf_model *m, const char *prefix) {
    static const char *const suffix[3] = {"_r", "_g", "_b"};
    for (int i = 0; i < m->param_count; i++) {
        const mr_brdf_param *p = &m->params[i];
        if (p->channels == 1)
            mr_strbuf_printf(sb, ",%s%s", prefix, p->name);
        else
            for (int c = 0; c < p->channels; c++) mr_strbuf_printf(sb, ",%s%s%s", prefix, p->name, suffix[c]);
    }
}

mr_scene mr_remap_file_scene(const mr_fit_scene_options *scene) {
    mr_fit_scene_options o = *scene;
    if (o.size == 0) o.size = MR_REMAP_DEFAULT_SIZE;
    return mr_scene_fit(&o);
}

int mr_remap_renderers_external(const mr_remap_renderers *renderers) {
    if (renderers == NULL) return 0;
    const char *names[2] = {renderers->source, renderers->target};
    for (int k = 0; k < 2; k++)
        if (names[k][0] != '\0' && strcmp(names[k], "builtin") != 0) return 1;
    return 0;
}

void mr_strbuf_remap_lines(mr_strbuf *sb, const mr_brdf_model *source, const mr_brdf_model *target,
                           const mr_remap_options *r, const mr_fit_scene_options *scene_options,
                           const mr_remap_renderers *renderers) {
    const mr_scene scene = mr_remap_file_scene(scene_options);
    // local=: rows fitted before the gradient local stage (issue 31) came from BOBYQA alone; a file written then
    // has no local= and so does not resume now (its header differs)
    mr_strbuf_printf(sb,
                     "# remap: strategy=%s max_evaluations=%d xtol=%.17g grid_points=%d starts=%d seed=%lu local=%s",
                     mr_remap_strategy_name(r->strategy), r->max_evaluations, r->xtol, r->grid_points, r->starts,
                     r->seed, mr_local_method_name(r->local_method));
    // Held target parameters are named only when there are some, so files written before --hold still resume.
    for (int p = 0, first = 1; p < target->param_count && p < 32; p++)
        if ((r->held >> p) & 1u) {
            mr_strbuf_printf(sb, "%s%s", first ? " held=" : ",", target->params[p].name);
            first = 0;
        }
    // Ties likewise: " tied=base_metalness:metallic" (target:source).
    for (int p = 0, first = 1; source != NULL && p < target->param_count && p < 32; p++)
        if (((r->ties.tied & ~r->held) >> p) & 1u) { // a hold wins over a tie
            mr_strbuf_printf(sb, "%s%s:%s", first ? " tied=" : ",", target->params[p].name,
                             source->params[r->ties.source[p]].name);
            first = 0;
        }
    if (mr_remap_renderers_external(renderers))
        mr_strbuf_printf(sb, " renderers=%s,%s samples=%d", renderers->source[0] ? renderers->source : "builtin",
                         renderers->target[0] ? renderers->target : "builtin", renderers->samples);
    mr_strbuf_printf(sb, "\n");
    // highlight_samples: rows fitted before the pixels about the highlight were integrated (issue 13) are not
    // comparable with today's, so a file written then does not resume now (its header differs)
    mr_strbuf_printf(sb, "# scene: fit size=%d light=%s intensity=%.17g edge_samples=%d highlight_samples=%s\n",
                     scene.width, mr_fit_light_name(scene_options->light), scene.lights[0].intensity[0],
                     scene.edge_samples > 0 ? scene.edge_samples : MR_SCENE_DEFAULT_EDGE_SAMPLES,
                     scene.highlight_samples == 0 ? "integrated" : "centres");
}

mr_status mr_remap_file_check_options(const char *what, const mr_remap_options *r, const mr_fit_scene_options *scene) {
    if (mr_remap_strategy_name(r->strategy) == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "%s: remap strategy %d is not one of auto, single, two, three, joint",
                       what, (int)r->strategy);
    if (mr_local_method_name(r->local_method) == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "%s: local method %d is not one of auto, gradient, bobyqa", what,
                       (int)r->local_method);
    if (r->max_evaluations < 1 || !(r->xtol >= 0.0 && isfinite(r->xtol)) || r->grid_points < 0 || r->starts < 0)
        return mr_fail(MR_ERR_INVALID_ARG,
                       "%s: remap options out of range (max_evaluations %d >= 1, xtol %g >= 0, grid_points %d "
                       ">= 0, starts %d >= 0)",
                       what, r->max_evaluations, r->xtol, r->grid_points, r->starts);
    if (scene->size < 0 || scene->size > MR_RENDER_MAX_SIZE)
        return mr_fail(MR_ERR_INVALID_ARG, "%s: scene size %d: expected 0 (default %d) to %d", what, scene->size,
                       MR_REMAP_DEFAULT_SIZE, MR_RENDER_MAX_SIZE);
    if (mr_fit_light_name(scene->light) == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "%s: fit light %d is not one of 45, frontal", what, (int)scene->light);
    if (!(scene->intensity >= 0.0 && isfinite(scene->intensity)))
        return mr_fail(MR_ERR_INVALID_ARG, "%s: light intensity %g: expected >= 0 (0: default)", what,
                       scene->intensity);
    return MR_OK;
}

mr_status mr_remap_file_check_values(const mr_brdf_model *m, const double *values, const char *which) {
    int slot = 0;
    for (int i = 0; i < m->param_count; i++) {
        const mr_brdf_param *p = &m->params[i];
        for (int c = 0; c < p->channels; c++, slot++) {
            double v = values[slot];
            if (!(v >= p->min_value && v <= p->max_value))
                return mr_fail(MR_ERR_INVALID_ARG, "%s value %s = %g of model '%s' is outside [%g, %g]", which,
                               p->name, v, m->name, p->min_value, p->max_value);
            if (p->role == MR_PARAM_SWITCH && v != floor(v))
                return mr_fail(MR_ERR_INVALID_ARG, "%s value %s = %g of model '%s' is a switch: not an integer",
                               which, p->name, v, m->name);
        }
    }
    return MR_OK;
}

/* ---- the file ------------------------------------------------------------------------------------------------ */

mr_status mr_text_file_read_all(int fd, const char *path, const char *what, char **out, size_t *out_size) {
    struct stat st;
    if (fstat(fd, &st) != 0) {
        int err = errno;
        return mr_fail(MR_ERR_IO, "%s '%s': cannot stat: %s", what, path, strerror(err));
    }
    size_t size = (size_t)st.st_size, got = 0;
    char *data = malloc(size + 1);
    if (data == NULL) return mr_fail(MR_ERR_NOMEM, "%s '%s': out of memory reading %zu bytes", what, path, size);
    while (got < size) {
        ssize_t n = pread(fd, data + got, size - got, (off_t)got);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) {
            int err = n < 0 ? errno : 0;
            free(data);
            return mr_fail(MR_ERR_IO, "%s '%s': read failed: %s", what, path, err ? strerror(err) : "file shrank");
        }
        got += (size_t)n;
    }
    data[size] = '\0';
    *out = data;
    *out_size = size;
    return MR_OK;
}

mr_status mr_text_file_append(int fd, const char *path, const char *what, const char *line, size_t length,
                              off_t *file_size) {
    size_t done = 0;
    int err = 0;
    for (int attempt = 0; attempt < 2 && done < length; attempt++) {
        ssize_t n;
        do {
            n = write(fd, line + done, length - done);
        } while (n < 0 && errno == EINTR);
        if (n < 0) {
            err = errno;
            break;
        }
        if (n == 0) err = ENOSPC; /* no progress and no errno: call it what it nearly always is */
        done += (size_t)n;
    }
    if (done == length) {
        *file_size += (off_t)length;
        return MR_OK;
    }
    if (done > 0 && ftruncate(fd, *file_size) != 0) {
        int cut = errno;
        return mr_fail(MR_ERR_IO, "%s '%s': short write (%zu of %zu bytes: %s) and cannot cut it back: %s", what,
                       path, done, length, strerror(err), strerror(cut));
    }
    return mr_fail(MR_ERR_IO, "%s '%s': cannot append to it: %s", what, path, strerror(err));
}

mr_status mr_text_file_lock(int fd, const char *path, const char *what) {
    struct flock fl;
    memset(&fl, 0, sizeof fl);
    fl.l_type = F_WRLCK;
    fl.l_whence = SEEK_SET;
    if (fcntl(fd, F_SETLK, &fl) == 0) return MR_OK;
    int err = errno;
    if (err == EACCES || err == EAGAIN) {
        memset(&fl, 0, sizeof fl);
        fl.l_type = F_WRLCK;
        fl.l_whence = SEEK_SET;
        long pid = fcntl(fd, F_GETLK, &fl) == 0 && fl.l_type != F_UNLCK ? (long)fl.l_pid : 0;
        return mr_fail(MR_ERR_IO, "%s '%s' is being written by another process (pid %ld)", what, path, pid);
    }
    return mr_fail(MR_ERR_IO, "%s '%s': cannot lock: %s", what, path, strerror(err));
}

/* Quote at most 160 characters of a line for a message. */
static void quote_line(const char *line, size_t len, char *buf, size_t size) {
    if (len > 0 && line[len - 1] == '\n') len--;
    snprintf(buf, size, "'%.*s%s'", (int)MR_MIN(len, 160), line, len > 160 ? "..." : "");
}

mr_status mr_text_file_match_header(const char *path, const char *what, const char *owner, const char *advice,
                                    const char *data, size_t size, const char *header, size_t header_length,
                                    const char *free_prefix, size_t *rows, long *lines) {
    const char *pos = data, *end = data + size;
    const char *expected = header, *expected_end = header + header_length;
    const size_t prefix = free_prefix ? strlen(free_prefix) : 0;
    long line_number = 0;
    while (expected < expected_end) {
        const char *want_nl = memchr(expected, '\n', (size_t)(expected_end - expected));
        size_t want_len = want_nl ? (size_t)(want_nl - expected) + 1 : (size_t)(expected_end - expected);
        const char *nl = memchr(pos, '\n', (size_t)(end - pos));
        line_number++;
        if (nl == NULL)
            return mr_fail(MR_ERR_FORMAT,
                           "%s '%s': the header ends early, at line %ld (a torn file?); not touching it (remove it "
                           "to start afresh)",
                           what, path, line_number);
        size_t have_len = (size_t)(nl - pos) + 1;
        int is_free = prefix > 0 && want_len >= prefix && memcmp(expected, free_prefix, prefix) == 0;
        int same = is_free ? have_len >= prefix && memcmp(pos, free_prefix, prefix) == 0
                           : have_len == want_len && memcmp(pos, expected, want_len) == 0;
        if (!same) {
            char have_q[200], want_q[200];
            quote_line(pos, have_len, have_q, sizeof have_q);
            quote_line(expected, want_len, want_q, sizeof want_q);
            return mr_fail(MR_ERR_INVALID_ARG, "%s '%s' %s: line %ld is %s, this run's is %s; not touching it (%s)",
                           what, path, owner, line_number, have_q, want_q, advice);
        }
        pos = nl + 1;
        expected += want_len;
    }
    *rows = (size_t)(pos - data);
    *lines = line_number;
    return MR_OK;
}

/* ---- the parallel driver -------------------------------------------------------------------------------------- */

mr_status mr_remap_run_parallel(int threads, long count, int *stop, void (*work)(void *ctx, long item), void *ctx,
                                const char *what) {
    mr_status locale_status = MR_OK;
#pragma omp parallel num_threads(threads)
    {
#ifdef _OPENMP
        // Items are the unit of parallelism: renders and metrics inside an item must not spawn teams of their
        // own (2 x 2 threads on 2 cores only thrash). nthreads-var is per task, so this affects only the regions
        // this thread opens from here, not the caller's settings; it also covers threads = 1, whose one-thread
        // team is not an active level that max-active-levels would count.
        omp_set_num_threads(1);
#endif
        mr_c_numeric cn;
        mr_status entered = mr_c_numeric_enter(&cn, what);
        if (entered != MR_OK) {
#pragma omp critical(mr_remap_run_locale)
            locale_status = entered;
#pragma omp atomic write
            *stop = 1;
        }
#pragma omp for schedule(dynamic)
        for (long item = 0; item < count; item++) {
            int stopping;
#pragma omp atomic read
            stopping = *stop;
            if (!stopping) work(ctx, item);
        }
        if (entered == MR_OK) mr_c_numeric_leave(&cn);
    }
    if (locale_status != MR_OK) return mr_fail(locale_status, "%s: cannot switch a thread to the C locale", what);
    return MR_OK;
}

/* ---- fields ---------------------------------------------------------------------------------------------------- */

int mr_csv_next_field(const char *line, size_t length, size_t *at, const char **field, size_t *field_len) {
    if (*at > length) return 0;
    const char *start = line + *at;
    const char *comma = memchr(start, ',', length - *at);
    *field = start;
    *field_len = comma ? (size_t)(comma - start) : length - *at;
    *at = comma ? (size_t)(comma - line) + 1 : SIZE_MAX;
    return 1;
}

int mr_csv_parse_double(const char *field, size_t len, double *out) {
    char tmp[64];
    if (len == 0 || len >= sizeof tmp) return 0;
    memcpy(tmp, field, len);
    tmp[len] = '\0';
    char *stop = NULL;
    double v = strtod(tmp, &stop);
    if (stop != tmp + len) return 0;
    *out = v;
    return 1;
}

int mr_csv_parse_long(const char *field, size_t len, long *out) {
    char tmp[32];
    if (len == 0 || len >= sizeof tmp || field[0] == '-' || field[0] == '+' || field[0] == ' ') return 0;
    memcpy(tmp, field, len);
    tmp[len] = '\0';
    char *stop = NULL;
    errno = 0;
    long v = strtol(tmp, &stop, 10);
    if (stop != tmp + len || errno == ERANGE) return 0;
    *out = v;
    return 1;
}

int mr_csv_split(char *line, char **fields, int max) {
    line[strcspn(line, "\r\n")] = '\0';
    int count = 0;
    char *at = line;
    while (count < max) {
        fields[count++] = at;
        char *comma = strchr(at, ',');
        if (comma == NULL) break;
        *comma = '\0';
        at = comma + 1;
    }
    return count;
}
