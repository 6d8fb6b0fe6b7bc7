/*
 * renderer_process.c — external renderers as long-lived server processes (renderer.h; the protocol is
 * docs/renderers.md, "The protocol").
 *
 * Each server is a child process whose stdin and stdout are one end of a Unix socket pair (a socket, not pipes:
 * send(MSG_NOSIGNAL) to a server that died returns EPIPE instead of raising SIGPIPE in the host program) and whose
 * stderr is a log file in the renderer's temporary folder. Requests are one JSON line each; answers are lines
 * starting "@matremap " (anything else the renderer prints, such as Blender's progress lines, is skipped). Images
 * come back as raw float32 RGBA files in the temporary folder, read and removed at once.
 *
 * A pool of servers, guarded by one mutex: a render takes an idle server, or starts one while fewer than
 * `processes` run, or waits for one to come back. A server that dies or times out is killed and its render retried
 * on a new one (RENDER_ATTEMPTS in all).
 */
#define _GNU_SOURCE /* mkdtemp, uselocale through c_locale.h, MSG_NOSIGNAL */
#include "renderer_internal.h"

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <math.h>
#include <omp.h>
#include <poll.h>
#include <pthread.h>
#include <signal.h>
#include <spawn.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "../c_locale.h"
#include "../mr_internal.h"

extern char **environ;

#define RENDER_ATTEMPTS 3
#define DEFAULT_TIMEOUT 300.0
#define QUIT_GRACE_SECONDS 5.0
#define LINE_MAX_BYTES 65536
#define PREFIX "@matremap "
/* The mean absolute difference of the renderer's coverage from the plan's above which it frames the scene
 * differently (silhouette pixels differ by their filters: Cycles' box over the pixel against the plan's 4 x 4 edge
 * samples, a few hundredths on the edge ring, under 0.005 over the image). */
#define COVERAGE_TOLERANCE 0.02

typedef struct server {
    pid_t pid; /* 0: not running */
    int fd;
    int busy;
    char *buffer; /* unread bytes from the server */
    size_t used;
    char log_path[PATH_MAX + 96];
} server;

struct external_pool {
    const mr_renderer_kind *kind;
    mr_renderer_options opts;
    char program[PATH_MAX];
    char script[PATH_MAX];
    char folder[PATH_MAX];
    pthread_mutex_t lock;
    pthread_cond_t idle;
    server *servers;
    int capacity;
    long next_id;
    long renders;
    long starts;
    char version[128];
};

/* ---- small helpers ---------------------------------------------------------------------------------------- */

static double now_seconds(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* The last lines of a server's log (its stderr), flattened onto one line for an error message. */
static void log_tail(const char *path, char *out, size_t size) {
    out[0] = '\0';
    FILE *f = fopen(path, "rb");
    if (f == NULL) return;
    char text[1024];
    long length = 0;
    if (fseek(f, 0, SEEK_END) == 0 && (length = ftell(f)) > 0) {
        long start = length > (long)sizeof text - 1 ? length - (long)sizeof text + 1 : 0;
        fseek(f, start, SEEK_SET);
        size_t n = fread(text, 1, sizeof text - 1, f);
        text[n] = '\0';
        // Keep the last three non-empty lines.
        int lines = 0;
        char *from = text + n;
        while (from > text) {
            --from;
            if (*from == '\n' && from[1] != '\0' && from[1] != '\n' && ++lines == 4) {
                from++;
                break;
            }
        }
        size_t k = 0;
        for (const char *p = from; *p && k + 1 < size; p++) out[k++] = (*p == '\n' || *p == '\r') ? ' ' : *p;
        while (k > 0 && out[k - 1] == ' ') k--;
        out[k] = '\0';
    }
    fclose(f);
}

/* JSON string literal of s appended at *at in buf[size]. */
static void json_string(char *buf, size_t size, size_t *at, const char *s) {
    if (*at + 1 < size) buf[(*at)++] = '"';
    for (; *s && *at + 8 < size; s++) {
        unsigned char c = (unsigned char)*s;
        if (c == '"' || c == '\\') {
            buf[(*at)++] = '\\';
            buf[(*at)++] = (char)c;
        } else if (c < 0x20) {
            *at += (size_t)snprintf(buf + *at, size - *at, "\\u%04x", c);
        } else {
            buf[(*at)++] = (char)c;
        }
    }
    if (*at + 1 < size) buf[(*at)++] = '"';
    buf[*at < size ? *at : size - 1] = '\0';
}

typedef struct request {
    char *text;
    size_t length, capacity;
    int failed;
} request;

#if defined(__GNUC__)
__attribute__((format(printf, 2, 3)))
#endif
static void append(request *r, const char *fmt, ...) {
    if (r->failed) return;
    for (;;) {
        va_list args;
        va_start(args, fmt);
        int n = vsnprintf(r->text + r->length, r->capacity - r->length, fmt, args);
        va_end(args);
        if (n < 0) {
            r->failed = 1;
            return;
        }
        if (r->length + (size_t)n < r->capacity) {
            r->length += (size_t)n;
            return;
        }
        size_t capacity = 2 * r->capacity + (size_t)n + 256;
        char *grown = realloc(r->text, capacity);
        if (grown == NULL) {
            r->failed = 1;
            return;
        }
        r->text = grown;
        r->capacity = capacity;
    }
}

static void append_string(request *r, const char *s) {
    char quoted[PATH_MAX * 2 + 16];
    size_t at = 0;
    json_string(quoted, sizeof quoted, &at, s);
    append(r, "%s", quoted);
}

static void append_vector(request *r, const double *v, int n) {
    append(r, "[");
    for (int i = 0; i < n; i++) append(r, "%s%.17g", i ? ", " : "", v[i]);
    append(r, "]");
}

/* ---- one server ------------------------------------------------------------------------------------------- */

/* Kill (SIGKILL unless `grace` > 0: close its input and wait that long first) and reap a server. */
static void end_server(server *s, double grace) {
    if (s->pid <= 0) return;
    if (s->fd >= 0) close(s->fd);
    s->fd = -1;
    int status;
    double deadline = now_seconds() + grace;
    pid_t done = 0;
    while (grace > 0.0 && (done = waitpid(s->pid, &status, WNOHANG)) == 0 && now_seconds() < deadline) {
        struct timespec pause = {0, 20000000};
        nanosleep(&pause, NULL);
    }
    if (done != s->pid) {
        kill(s->pid, SIGKILL);
        while (waitpid(s->pid, &status, 0) < 0 && errno == EINTR) {
        }
    }
    s->pid = 0;
    s->used = 0;
}

/* Read one answer line ("@matremap ..." with the prefix cut) into line[size] by `deadline`. 1: a line; 0: the
 * server closed its output (died); -1: timed out; -2: a read error. */
static int read_answer(server *s, double deadline, char *line, size_t size) {
    for (;;) {
        char *newline = s->used ? memchr(s->buffer, '\n', s->used) : NULL;
        while (newline != NULL) {
            size_t length = (size_t)(newline - s->buffer);
            int ours = length >= strlen(PREFIX) && memcmp(s->buffer, PREFIX, strlen(PREFIX)) == 0;
            if (ours) {
                size_t n = MR_MIN(length - strlen(PREFIX), size - 1);
                memcpy(line, s->buffer + strlen(PREFIX), n);
                line[n] = '\0';
                if (n > 0 && line[n - 1] == '\r') line[n - 1] = '\0';
            }
            memmove(s->buffer, newline + 1, s->used - length - 1);
            s->used -= length + 1;
            if (ours) return 1;
            newline = s->used ? memchr(s->buffer, '\n', s->used) : NULL;
        }
        if (s->used == LINE_MAX_BYTES) s->used = 0; // a line of chatter longer than the buffer: not ours, dropped
        double left = deadline - now_seconds();
        if (left <= 0.0) return -1;
        struct pollfd p = {s->fd, POLLIN, 0};
        int ready = poll(&p, 1, (int)MR_MIN(left * 1000.0 + 1.0, 60000.0));
        if (ready < 0 && errno != EINTR) return -2;
        if (ready <= 0) continue;
        ssize_t got = read(s->fd, s->buffer + s->used, LINE_MAX_BYTES - s->used);
        if (got == 0) return 0;
        if (got < 0) {
            if (errno == EINTR || errno == EAGAIN) continue;
            return errno == ECONNRESET ? 0 : -2;
        }
        s->used += (size_t)got;
    }
}

/* The words of a "ready" line: NAME VERSION key=value...; the version ("blender 3.4.1") into pool->version. */
static mr_status check_ready(external_pool *pool, const char *line) {
    char name[64] = "", version[64] = "";
    if (sscanf(line, "ready %63s %63s", name, version) != 2 || strcmp(name, pool->kind->name) != 0)
        return mr_fail(MR_ERR_EXTERNAL, "renderer '%s': its server '%s' answered '%.80s' instead of 'ready %s ...'",
                       pool->kind->name, pool->script, line, pool->kind->name);
    pthread_mutex_lock(&pool->lock);
    snprintf(pool->version, sizeof pool->version, "%s %s", name, version);
    pthread_mutex_unlock(&pool->lock);
    return MR_OK;
}

/* Start server s (not running) and wait for its ready line. */
static mr_status start_server(external_pool *pool, server *s, int index) {
    snprintf(s->log_path, sizeof s->log_path, "%s/%s-%d.log", pool->folder, pool->kind->name, index);
    int pair[2];
    if (socketpair(AF_UNIX, SOCK_STREAM | SOCK_CLOEXEC, 0, pair) != 0)
        return mr_fail(MR_ERR_EXTERNAL, "renderer '%s': socketpair: %s", pool->kind->name, strerror(errno));
    char *argv[16];
    int argc = 0;
    argv[argc++] = pool->program;
    for (int i = 0; pool->kind->arguments[i] != NULL; i++)
        argv[argc++] = strcmp(pool->kind->arguments[i], "SCRIPT") == 0 ? pool->script
                                                                        : (char *)pool->kind->arguments[i];
    argv[argc] = NULL;
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_adddup2(&actions, pair[1], STDIN_FILENO);
    posix_spawn_file_actions_adddup2(&actions, pair[1], STDOUT_FILENO);
    posix_spawn_file_actions_addopen(&actions, STDERR_FILENO, s->log_path, O_WRONLY | O_CREAT | O_APPEND, 0644);
    pid_t pid = 0;
    int error = posix_spawnp(&pid, pool->program, &actions, NULL, argv, environ);
    posix_spawn_file_actions_destroy(&actions);
    close(pair[1]);
    if (error != 0) {
        close(pair[0]);
        if (error == ENOENT)
            return mr_fail(MR_ERR_EXTERNAL, "renderer '%s': program '%s' not found (install Debian's %s package: "
                           "scripts/install-deps.sh, or set %s)", pool->kind->name, pool->program,
                           pool->kind->package, pool->kind->program_variable);
        return mr_fail(MR_ERR_EXTERNAL, "renderer '%s': cannot start '%s': %s", pool->kind->name, pool->program,
                       strerror(error));
    }
    s->pid = pid;
    s->fd = pair[0];
    s->used = 0;
    pthread_mutex_lock(&pool->lock);
    pool->starts++;
    pthread_mutex_unlock(&pool->lock);
    char line[512];
    int got = read_answer(s, now_seconds() + pool->opts.timeout_seconds, line, sizeof line);
    if (got == 1) {
        mr_status status = check_ready(pool, line);
        if (status != MR_OK) end_server(s, 0.0);
        return status;
    }
    end_server(s, 0.0);
    char tail[600];
    log_tail(s->log_path, tail, sizeof tail);
    return mr_fail(MR_ERR_EXTERNAL, "renderer '%s': '%s %s' %s before it was ready%s%s", pool->kind->name,
                   pool->program, pool->script,
                   got == 0 ? "ended" : got == -1 ? "did not answer in time" : "could not be read",
                   tail[0] ? ": " : "", tail);
}

/* Send one request line and wait for its answer; param lines ("param ID ...") go to on_param. 1 answered ok; 0 an
 * error answer (message set); -1 the server died or timed out (killed; message set). */
typedef void (*param_sink)(void *user, const char *rest);
static int exchange(external_pool *pool, server *s, long id, const request *r, param_sink on_param, void *user) {
    const char *text = r->text;
    size_t left = r->length;
    const char *why = NULL;
    while (left > 0 && why == NULL) {
        ssize_t sent = send(s->fd, text, left, MSG_NOSIGNAL);
        if (sent < 0) {
            if (errno == EINTR) continue;
            why = "could not be sent the request";
            break;
        }
        text += sent;
        left -= (size_t)sent;
    }
    double deadline = now_seconds() + pool->opts.timeout_seconds;
    char line[LINE_MAX_BYTES];
    while (why == NULL) {
        int got = read_answer(s, deadline, line, sizeof line);
        if (got != 1) {
            why = got == 0 ? "died" : got == -1 ? "did not answer in time" : "could not be read";
            break;
        }
        long answer_id = -2;
        int skip = 0;
        if (sscanf(line, "ok %ld", &answer_id) == 1 && answer_id == id) return 1;
        if (sscanf(line, "error %ld %n", &answer_id, &skip) == 1 && (answer_id == id || answer_id == -1)) {
            mr_fail(MR_ERR_EXTERNAL, "renderer '%s': %s", pool->kind->name, line + skip);
            return 0;
        }
        if (sscanf(line, "param %ld %n", &answer_id, &skip) == 1 && answer_id == id && on_param)
            on_param(user, line + skip);
    }
    char tail[600];
    log_tail(s->log_path, tail, sizeof tail);
    end_server(s, 0.0);
    mr_fail(MR_ERR_EXTERNAL, "renderer '%s': its process %s%s%s", pool->kind->name, why, tail[0] ? ": " : "", tail);
    return -1;
}

/* ---- the pool ----------------------------------------------------------------------------------------------- */

static mr_status take_server(external_pool *pool, int *index) {
    pthread_mutex_lock(&pool->lock);
    for (;;) {
        int idle = -1, stopped = -1;
        for (int i = 0; i < pool->capacity; i++) {
            if (pool->servers[i].busy) continue;
            if (pool->servers[i].pid > 0 && idle < 0) idle = i;
            if (pool->servers[i].pid <= 0 && stopped < 0) stopped = i;
        }
        int chosen = idle >= 0 ? idle : stopped;
        if (chosen >= 0) {
            pool->servers[chosen].busy = 1;
            pthread_mutex_unlock(&pool->lock);
            *index = chosen;
            return MR_OK;
        }
        pthread_cond_wait(&pool->idle, &pool->lock);
    }
}

static void give_back(external_pool *pool, int index) {
    pthread_mutex_lock(&pool->lock);
    pool->servers[index].busy = 0;
    pthread_cond_signal(&pool->idle);
    pthread_mutex_unlock(&pool->lock);
}

/* Run request r (built for `id`) on a server of the pool, starting or restarting one as needed. */
static mr_status run(external_pool *pool, long id, const request *r, param_sink on_param, void *user) {
    if (r->failed) return mr_fail(MR_ERR_NOMEM, "renderer '%s': out of memory for a request", pool->kind->name);
    int index;
    mr_status status = take_server(pool, &index);
    if (status != MR_OK) return status;
    server *s = &pool->servers[index];
    for (int attempt = 1; attempt <= RENDER_ATTEMPTS; attempt++) {
        if (s->pid <= 0 && (status = start_server(pool, s, index)) != MR_OK) break;
        int answered = exchange(pool, s, id, r, on_param, user);
        status = answered == 1 ? MR_OK : MR_ERR_EXTERNAL;
        if (answered >= 0) break; // an answer, good or bad: retrying would give the same
        if (attempt == RENDER_ATTEMPTS)
            mr_fail_context(MR_ERR_EXTERNAL, "after %d attempts", RENDER_ATTEMPTS);
    }
    give_back(pool, index);
    return status;
}

static long next_id(external_pool *pool) {
    pthread_mutex_lock(&pool->lock);
    long id = ++pool->next_id;
    pthread_mutex_unlock(&pool->lock);
    return id;
}

mr_status mr_external_pool_open(const mr_renderer_kind *kind, const mr_renderer_options *opts,
                                external_pool **out) {
    *out = NULL;
    external_pool *pool = calloc(1, sizeof *pool);
    if (pool == NULL) return mr_fail(MR_ERR_NOMEM, "renderer '%s': out of memory", kind->name);
    pool->kind = kind;
    pool->opts = *opts;
    if (pool->opts.samples <= 0) pool->opts.samples = kind->default_samples;
    if (!(pool->opts.timeout_seconds > 0.0)) pool->opts.timeout_seconds = DEFAULT_TIMEOUT;
    pool->capacity = pool->opts.processes > 0 ? pool->opts.processes : MR_MAX(omp_get_max_threads(), 1);
    if (pool->opts.threads <= 0) pool->opts.threads = MR_MAX(omp_get_num_procs() / pool->capacity, 1);
    const char *program = opts->program;
    if (program == NULL || program[0] == '\0') program = getenv(kind->program_variable);
    if (program == NULL || program[0] == '\0') program = kind->default_program;
    snprintf(pool->program, sizeof pool->program, "%s", program);
    mr_status status = mr_data_path(kind->script, pool->script, sizeof pool->script);
    if (status != MR_OK) {
        free(pool);
        return mr_fail_context(MR_ERR_EXTERNAL, "renderer '%s': its server script is missing", kind->name);
    }
    if (kind->installed_check != NULL) {
        char path[PATH_MAX];
        if (mr_data_path(kind->installed_check, path, sizeof path) != MR_OK) {
            free(pool);
            return mr_fail(MR_ERR_EXTERNAL, "renderer '%s': its npm packages are not installed (%s is missing: run "
                           "scripts/install-deps.sh, which runs npm ci beside %s)", kind->name,
                           kind->installed_check, pool->script);
        }
    }
    const char *tmp = getenv("TMPDIR");
    snprintf(pool->folder, sizeof pool->folder, "%s/matremap-%s-XXXXXX", tmp && tmp[0] ? tmp : "/tmp", kind->name);
    pool->servers = calloc((size_t)pool->capacity, sizeof *pool->servers);
    if (pool->servers == NULL) {
        free(pool);
        return mr_fail(MR_ERR_NOMEM, "renderer: out of memory");
    }
    if (mkdtemp(pool->folder) == NULL) {
        int err = errno;
        free(pool->servers);
        free(pool);
        return mr_fail(MR_ERR_IO, "renderer '%s': cannot make a temporary folder: %s", kind->name, strerror(err));
    }
    for (int i = 0; i < pool->capacity; i++) {
        pool->servers[i].fd = -1;
        pool->servers[i].buffer = malloc(LINE_MAX_BYTES);
        if (pool->servers[i].buffer == NULL) {
            mr_external_pool_free(pool);
            return mr_fail(MR_ERR_NOMEM, "renderer: out of memory");
        }
    }
    pthread_mutex_init(&pool->lock, NULL);
    pthread_cond_init(&pool->idle, NULL);
    *out = pool;
    return MR_OK;
}

void mr_external_pool_free(external_pool *pool) {
    if (pool == NULL) return;
    for (int i = 0; i < pool->capacity; i++) {
        end_server(&pool->servers[i], QUIT_GRACE_SECONDS);
        if (pool->servers[i].log_path[0]) unlink(pool->servers[i].log_path);
        free(pool->servers[i].buffer);
    }
    rmdir(pool->folder); // what the servers wrote there was read and removed; a leftover keeps the folder
    pthread_mutex_destroy(&pool->lock);
    pthread_cond_destroy(&pool->idle);
    free(pool->servers);
    free(pool);
}

mr_status mr_external_pool_start(external_pool *pool, char *version, size_t size) {
    int index;
    mr_status status = take_server(pool, &index);
    if (status != MR_OK) return status;
    if (pool->servers[index].pid <= 0) status = start_server(pool, &pool->servers[index], index);
    give_back(pool, index);
    if (status == MR_OK && version != NULL && size > 0) {
        pthread_mutex_lock(&pool->lock);
        snprintf(version, size, "%s", pool->version);
        pthread_mutex_unlock(&pool->lock);
    }
    return status;
}

long mr_external_pool_renders(const external_pool *pool) {
    return pool->renders;
}

long mr_external_pool_starts(const external_pool *pool) {
    return pool->starts;
}

/* ---- render requests ---------------------------------------------------------------------------------------- */

/* The request's scene: the plan's camera, sphere and point lights. */
static mr_status append_scene(external_pool *pool, request *r, const mr_render_plan *plan) {
    const mr_scene *scene = mr_render_plan_scene(plan);
    if (scene->shape.type != MR_SHAPE_SPHERE)
        return mr_fail(MR_ERR_UNSUPPORTED, "renderer '%s' renders the fit scene's sphere, not a mesh",
                       pool->kind->name);
    if (scene->width != scene->height)
        return mr_fail(MR_ERR_UNSUPPORTED, "renderer '%s' renders square scenes, not %dx%d", pool->kind->name,
                       scene->width, scene->height);
    append(r, "\"size\": %d, \"samples\": %d, \"seed\": %lu, \"threads\": %d, \"camera\": {\"position\": ",
           scene->width, pool->opts.samples, pool->opts.seed, pool->opts.threads);
    append_vector(r, scene->camera.position, 3);
    append(r, ", \"target\": ");
    append_vector(r, scene->camera.target, 3);
    append(r, ", \"up\": ");
    append_vector(r, scene->camera.up, 3);
    append(r, ", \"fov_y\": %.17g}, \"sphere\": {\"center\": ", scene->camera.fov_y_degrees);
    append_vector(r, scene->shape.center, 3);
    append(r, ", \"radius\": %.17g}, \"lights\": [", scene->shape.radius);
    for (int k = 0; k < scene->light_count; k++) {
        const mr_light *light = &scene->lights[k];
        if (light->type != MR_LIGHT_POINT)
            return mr_fail(MR_ERR_UNSUPPORTED, "renderer '%s' renders point lights only, not environment lights",
                           pool->kind->name);
        append(r, "%s{\"position\": ", k ? ", " : "");
        append_vector(r, light->position, 3);
        append(r, ", \"intensity\": ");
        append_vector(r, light->intensity, 3);
        append(r, "}");
    }
    append(r, "]");
    return MR_OK;
}

/* Read OUTPUT.<component>.f32 (RGBA float32, rows from the top) into `into` (RGB, the plan's size) over the
 * plan's background and check its coverage against the plan's (render_request removes the file). */
static mr_status read_component(external_pool *pool, const mr_render_plan *plan, const char *output,
                                const char *component, mr_image *into) {
    const mr_scene *scene = mr_render_plan_scene(plan);
    const size_t pixels = (size_t)scene->width * (size_t)scene->height;
    char path[PATH_MAX + 64];
    snprintf(path, sizeof path, "%s.%s.f32", output, component);
    FILE *f = fopen(path, "rb");
    if (f == NULL)
        return mr_fail(MR_ERR_EXTERNAL, "renderer '%s' answered ok but wrote no '%s'", pool->kind->name, path);
    float *rgba = malloc(pixels * 4 * sizeof *rgba);
    size_t got = rgba ? fread(rgba, sizeof *rgba, pixels * 4, f) : 0;
    int extra = rgba ? fgetc(f) != EOF : 0;
    fclose(f);
    if (rgba == NULL) return mr_fail(MR_ERR_NOMEM, "renderer: out of memory");
    mr_status status = MR_OK;
    if (got != pixels * 4 || extra)
        status = mr_fail(MR_ERR_EXTERNAL, "renderer '%s': '%s' holds %s%zu floats: expected %dx%dx4 = %zu",
                         pool->kind->name, path, extra ? "more than " : "", got, scene->width, scene->height,
                         pixels * 4);
    const float *coverage = mr_render_plan_coverage(plan);
    double coverage_difference = 0.0, interior_alpha = 0.0;
    size_t interior = 0;
    for (size_t p = 0; status == MR_OK && p < pixels; p++) {
        const float *v = rgba + p * 4;
        for (int c = 0; c < 4; c++)
            if (!isfinite(v[c]) || v[c] < -1e-6f) {
                status = mr_fail(MR_ERR_EXTERNAL, "renderer '%s': %s render, pixel (%zu, %zu) channel %d is %g: "
                                 "expected finite radiance >= 0", pool->kind->name, component,
                                 p % (size_t)scene->width, p / (size_t)scene->width, c, (double)v[c]);
                break;
            }
        const float alpha = fminf(fmaxf(v[3], 0.0f), 1.0f);
        coverage_difference += fabs((double)alpha - (double)coverage[p]);
        if (coverage[p] >= 1.0f) {
            interior_alpha += alpha;
            interior++;
        }
        for (int c = 0; c < 3; c++)
            into->pixels[p * 3 + c] = fmaxf(v[c], 0.0f) + (1.0f - alpha) * (float)scene->background[c];
    }
    free(rgba);
    // A see-through material (a Transparent or Holdout shader) lowers the alpha inside the sphere: say so, rather
    // than blame the framing.
    if (status == MR_OK && interior > 0 && interior_alpha < (1.0 - COVERAGE_TOLERANCE) * (double)interior)
        status = mr_fail(MR_ERR_INVALID_ARG, "renderer '%s': the material is not opaque: its alpha inside the sphere "
                         "is %.3f on average, not 1 (a Transparent or Holdout shader?); fits take opaque materials",
                         pool->kind->name, interior_alpha / (double)interior);
    if (status == MR_OK && coverage_difference > COVERAGE_TOLERANCE * (double)pixels)
        status = mr_fail(MR_ERR_EXTERNAL, "renderer '%s' frames the scene differently: its coverage differs from the "
                         "fit scene's by %.3f per pixel on average (at most %.2f expected)", pool->kind->name,
                         coverage_difference / (double)pixels, COVERAGE_TOLERANCE);
    return status;
}

static mr_status check_images(const mr_render_plan *plan, mr_image *const images[3]) {
    const mr_scene *scene = mr_render_plan_scene(plan);
    int any = 0;
    for (int k = 0; k < 3; k++) {
        if (images[k] == NULL) continue;
        any = 1;
        if (images[k]->width != scene->width || images[k]->height != scene->height || images[k]->channels != 3)
            return mr_fail(MR_ERR_INVALID_ARG, "renderer: a %s image of %dx%dx%d for a %dx%d scene",
                           mr_component_name((mr_component)k), images[k]->width, images[k]->height,
                           images[k]->channels, scene->width, scene->height);
    }
    return any ? MR_OK : mr_fail(MR_ERR_INVALID_ARG, "renderer: no image to render into");
}

/* The request of a render: scene, `material` (a JSON object, already formatted), components; run it, read the
 * images. */
static mr_status render_request(external_pool *pool, const mr_render_plan *plan, const char *material,
                                mr_image *const images[3]) {
    mr_status status = check_images(plan, images);
    if (status != MR_OK) return status;
    if ((images[1] || images[2]) && !pool->kind->components)
        return mr_fail(MR_ERR_UNSUPPORTED, "renderer '%s' renders the full image only, not its diffuse and specular "
                       "parts", pool->kind->name);
    const long id = next_id(pool);
    char output[PATH_MAX + 32];
    snprintf(output, sizeof output, "%s/r%ld", pool->folder, id);
    request r = {0};
    mr_c_numeric numeric;
    status = mr_c_numeric_enter(&numeric, "renderer request");
    if (status != MR_OK) return status;
    append(&r, "{\"op\": \"render\", \"id\": %ld, ", id);
    status = append_scene(pool, &r, plan);
    if (status == MR_OK) {
        append(&r, ", \"material\": %s, \"components\": [", material);
        static const char *const names[3] = {"full", "diffuse", "specular"};
        int listed = 0;
        for (int k = 0; k < 3; k++)
            if (images[k]) append(&r, "%s\"%s\"", listed++ ? ", " : "", names[k]);
        append(&r, "], \"output\": ");
        append_string(&r, output);
        append(&r, "}\n");
    }
    mr_c_numeric_leave(&numeric);
    if (status == MR_OK) status = run(pool, id, &r, NULL, NULL);
    free(r.text);
    static const char *const files[3] = {"full", "diffuse", "specular"};
    for (int k = 0; k < 3; k++) {
        if (images[k] == NULL) continue;
        if (status == MR_OK) status = read_component(pool, plan, output, files[k], images[k]);
        char path[PATH_MAX + 64];
        snprintf(path, sizeof path, "%s.%s.f32", output, files[k]);
        unlink(path); // read or not
    }
    if (status == MR_OK) {
        pthread_mutex_lock(&pool->lock);
        pool->renders++;
        pthread_mutex_unlock(&pool->lock);
    }
    return status;
}

mr_status mr_external_pool_render(external_pool *pool, const mr_render_plan *plan, const mr_brdf_model *model,
                                  const double *values, mr_image *const images[3]) {
    double clamped[MR_BRDF_MAX_VALUES];
    for (int i = 0; i < model->param_count; i++) {
        const mr_brdf_param *p = &model->params[i];
        const int offset = mr_brdf_param_offset(model, i);
        for (int c = 0; c < p->channels; c++) {
            const double v = values[offset + c];
            if (!isfinite(v))
                return mr_fail(MR_ERR_INVALID_ARG, "renderer '%s': %s %s = %g is not finite", pool->kind->name,
                               model->name, p->name, v);
            clamped[offset + c] = mr_clampd(v, p->min_value, p->max_value);
        }
    }
    request material = {0};
    mr_c_numeric numeric;
    mr_status status = mr_c_numeric_enter(&numeric, "renderer request");
    if (status != MR_OK) return status;
    append(&material, "{\"model\": \"%s\", \"values\": {", model->name);
    for (int i = 0; i < model->param_count; i++) {
        const mr_brdf_param *p = &model->params[i];
        const double *v = clamped + mr_brdf_param_offset(model, i);
        append(&material, "%s\"%s\": ", i ? ", " : "", p->name);
        if (p->channels == 1)
            append(&material, "%.17g", v[0]);
        else
            append_vector(&material, v, p->channels);
    }
    append(&material, "}}");
    mr_c_numeric_leave(&numeric);
    if (material.failed) status = mr_fail(MR_ERR_NOMEM, "renderer: out of memory");
    if (status == MR_OK) status = render_request(pool, plan, material.text, images);
    free(material.text);
    return status;
}

/* ---- external materials ------------------------------------------------------------------------------------- */

struct mr_external_material {
    char reference[PATH_MAX + 256];
    char file[PATH_MAX];  /* absolute */
    char name[256];
    int count;
    mr_external_param *params;
};

typedef struct describe_sink {
    mr_external_material *material;
    int failed;
} describe_sink;

/* One "param" answer: KIND MIN MAX V... PATH. */
static void take_param(void *user, const char *rest) {
    describe_sink *sink = user;
    mr_external_material *m = sink->material;
    char kind[16];
    int skip = 0;
    mr_external_param p;
    memset(&p, 0, sizeof p);
    if (sscanf(rest, "%15s %lf %lf %n", kind, &p.min_value, &p.max_value, &skip) != 3) {
        sink->failed = 1;
        return;
    }
    p.channels = strcmp(kind, "color") == 0 ? 3 : strcmp(kind, "float") == 0 ? 1 : 0;
    if (p.channels == 0) {
        sink->failed = 1;
        return;
    }
    rest += skip;
    for (int c = 0; c < p.channels; c++) {
        int n = 0;
        if (sscanf(rest, "%lf %n", &p.values[c], &n) != 1) {
            sink->failed = 1;
            return;
        }
        rest += n;
    }
    for (int c = p.channels; c < 3; c++) p.values[c] = p.values[0];
    if (rest[0] == '\0' || strlen(rest) >= sizeof p.path) {
        sink->failed = 1;
        return;
    }
    snprintf(p.path, sizeof p.path, "%s", rest);
    mr_external_param *grown = realloc(m->params, (size_t)(m->count + 1) * sizeof *grown);
    if (grown == NULL) {
        sink->failed = 1;
        return;
    }
    m->params = grown;
    m->params[m->count++] = p;
}

mr_status mr_external_pool_describe(external_pool *pool, const char *reference, mr_external_material **out) {
    *out = NULL;
    if (!pool->kind->materials)
        return mr_fail(MR_ERR_UNSUPPORTED, "renderer '%s' has no materials of its own (only models by values)",
                       pool->kind->name);
    const char *colon = strrchr(reference, ':');
    if (colon == NULL || colon == reference || colon[1] == '\0')
        return mr_fail(MR_ERR_INVALID_ARG, "material '%s': expected FILE.blend:MATERIAL", reference);
    mr_external_material *m = calloc(1, sizeof *m);
    if (m == NULL) return mr_fail(MR_ERR_NOMEM, "renderer: out of memory");
    snprintf(m->reference, sizeof m->reference, "%s", reference);
    char file[PATH_MAX];
    const size_t file_length = (size_t)(colon - reference);
    if (file_length >= sizeof file || strlen(colon + 1) >= sizeof m->name) {
        free(m);
        return mr_fail(MR_ERR_INVALID_ARG, "material '%s': name too long", reference);
    }
    memcpy(file, reference, file_length);
    file[file_length] = '\0';
    snprintf(m->name, sizeof m->name, "%s", colon + 1);
    struct stat st;
    if (stat(file, &st) != 0 || !S_ISREG(st.st_mode) || realpath(file, m->file) == NULL) {
        int err = errno;
        free(m);
        return mr_fail(MR_ERR_IO, "material '%s': cannot open '%s': %s", reference, file,
                       err ? strerror(err) : "not a regular file");
    }
    const long id = next_id(pool);
    request r = {0};
    append(&r, "{\"op\": \"describe\", \"id\": %ld, \"material\": {\"blend\": ", id);
    append_string(&r, m->file);
    append(&r, ", \"name\": ");
    append_string(&r, m->name);
    append(&r, "}}\n");
    describe_sink sink = {m, 0};
    mr_c_numeric numeric;
    mr_status status = mr_c_numeric_enter(&numeric, "renderer answer");
    if (status == MR_OK) {
        status = run(pool, id, &r, take_param, &sink);
        mr_c_numeric_leave(&numeric);
    }
    free(r.text);
    if (status == MR_OK && sink.failed)
        status = mr_fail(MR_ERR_EXTERNAL, "renderer '%s': a malformed parameter line describing '%s'",
                         pool->kind->name, reference);
    if (status != MR_OK) {
        // The server's "no material" answer is the caller's mistake: say it as such.
        if (status == MR_ERR_EXTERNAL && strstr(mr_last_error(), "no material") != NULL) status = MR_ERR_INVALID_ARG;
        mr_external_material_free(m);
        return status;
    }
    *out = m;
    return MR_OK;
}

void mr_external_material_free(mr_external_material *material) {
    if (material == NULL) return;
    free(material->params);
    free(material);
}

const char *mr_external_material_reference(const mr_external_material *material) {
    return material ? material->reference : NULL;
}

int mr_external_material_param_count(const mr_external_material *material) {
    return material ? material->count : 0;
}

const char *mr_external_material_param(const mr_external_material *material, int k, int *channels, double *min_value,
                                       double *max_value, double *values) {
    if (material == NULL || k < 0 || k >= material->count) {
        if (channels) *channels = 0;
        return NULL;
    }
    const mr_external_param *p = &material->params[k];
    if (channels) *channels = p->channels;
    if (min_value) *min_value = p->min_value;
    if (max_value) *max_value = p->max_value;
    if (values) memcpy(values, p->values, sizeof p->values);
    return p->path;
}

mr_status mr_external_material_set(mr_external_material *material, const char *path, const double *values,
                                   int count) {
    if (material == NULL || path == NULL || values == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "material input: NULL argument");
    for (int k = 0; k < material->count; k++) {
        mr_external_param *p = &material->params[k];
        if (strcmp(p->path, path) != 0) continue;
        if (!(count == p->channels || (count == 1 && p->channels == 3)))
            return mr_fail(MR_ERR_INVALID_ARG, "material '%s': input '%s' takes %d value%s, not %d",
                           material->reference, path, p->channels, p->channels == 1 ? "" : "s", count);
        for (int c = 0; c < count; c++)
            if (!isfinite(values[c]))
                return mr_fail(MR_ERR_INVALID_ARG, "material '%s': input '%s' = %g is not finite",
                               material->reference, path, values[c]);
        for (int c = 0; c < p->channels; c++) p->values[c] = values[count == 1 ? 0 : c];
        return MR_OK;
    }
    char list[1024] = "";
    for (int k = 0; k < material->count && strlen(list) + 8 < sizeof list; k++)
        snprintf(list + strlen(list), sizeof list - strlen(list), "%s'%s'", k ? ", " : "", material->params[k].path);
    return mr_fail(MR_ERR_INVALID_ARG, "material '%s' has no input '%s' (it has %s)", material->reference, path,
                   material->count ? list : "none");
}

mr_status mr_external_pool_render_material(external_pool *pool, const mr_render_plan *plan,
                                           const mr_external_material *material, mr_image *const images[3]) {
    if (!pool->kind->materials)
        return mr_fail(MR_ERR_UNSUPPORTED, "renderer '%s' has no materials of its own", pool->kind->name);
    request m = {0};
    mr_c_numeric numeric;
    mr_status status = mr_c_numeric_enter(&numeric, "renderer request");
    if (status != MR_OK) return status;
    append(&m, "{\"blend\": ");
    append_string(&m, material->file);
    append(&m, ", \"name\": ");
    append_string(&m, material->name);
    append(&m, ", \"inputs\": {");
    for (int k = 0; k < material->count; k++) {
        const mr_external_param *p = &material->params[k];
        append(&m, "%s", k ? ", " : "");
        append_string(&m, p->path);
        append(&m, ": ");
        append_vector(&m, p->values, p->channels);
    }
    append(&m, "}}");
    mr_c_numeric_leave(&numeric);
    if (m.failed) status = mr_fail(MR_ERR_NOMEM, "renderer: out of memory");
    if (status == MR_OK) status = render_request(pool, plan, m.text, images);
    free(m.text);
    return status;
}
