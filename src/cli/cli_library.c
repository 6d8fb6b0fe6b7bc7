/*
 * cli_library.c — what the commands that run over many items share (cli.h): `--shard K/N` (sweep, gltf, export)
 * and the progress and cancelling of a many-asset run (gltf, export: mr_gltf_library_options).
 */
#include <errno.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"

int cli_parse_shard(const char *command, const char *text, long max, long *k, long *n) {
    char *end = NULL;
    errno = 0;
    long a = strtol(text, &end, 10), b = -1;
    int ok = text[0] >= '0' && text[0] <= '9' && *end == '/' && errno != ERANGE;
    if (ok) {
        const char *rest = end + 1;
        b = strtol(rest, &end, 10);
        ok = rest[0] >= '0' && rest[0] <= '9' && *end == '\0' && errno != ERANGE && b >= 1 && a < b && b <= max;
    }
    if (!ok) {
        cli_usage_error(command, "--shard '%s': expected K/N with integers 0 <= K < N (shard K of N)", text);
        return 0;
    }
    *k = a;
    *n = b;
    return 1;
}

void cli_library_progress(void *user, const mr_gltf_library_progress *p) {
    const cli_library_view *view = user;
    if (view->tty) {
        const int width = 30, filled = p->total > 0 ? width * p->done / p->total : width;
        const double rate = p->seconds > 0.0 ? (double)p->texels / p->seconds : 0.0;
        const double left = p->done > 0 ? p->seconds / p->done * (p->total - p->done) : 0.0;
        fprintf(stderr, "\r\033[K[%.*s%.*s] %d/%d assets", filled, "##############################", width - filled,
                "..............................", p->done, p->total);
        if (rate > 0.0) fprintf(stderr, ", %.2f Mtexel/s", rate / 1e6);
        fprintf(stderr, ", %d:%02d left", (int)left / 60, (int)left % 60);
        if (p->failed > 0) fprintf(stderr, ", %d failed", p->failed);
        if (strcmp(p->status, "failed") == 0) fprintf(stderr, "\r\033[Kfailed: %s: %s\n", p->asset, p->error);
        if (p->done == p->total) fprintf(stderr, "\n");
        fflush(stderr);
    } else if (strcmp(p->status, "failed") == 0) {
        printf("[%d/%d] failed: %s: %s\n", p->done, p->total, p->asset, p->error);
        fflush(stdout);
    } else {
        printf("[%d/%d] %s: %s (%.2f s)\n", p->done, p->total,
               strcmp(p->status, "converted") == 0 && view->done_word ? view->done_word : p->status, p->asset,
               p->asset_seconds);
        fflush(stdout);
    }
}

/* SIGINT or SIGTERM during a many-asset run: the assets under way finish, the rest are recorded "cancelled". */
static volatile sig_atomic_t library_cancel = 0;
static void on_signal(int sig) {
    (void)sig;
    library_cancel = 1;
}

volatile sig_atomic_t *cli_library_cancel_begin(struct sigaction old[2]) {
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_signal;
    sigemptyset(&sa.sa_mask);
    library_cancel = 0;
    sigaction(SIGINT, &sa, &old[0]);
    sigaction(SIGTERM, &sa, &old[1]);
    return &library_cancel;
}

void cli_library_cancel_end(const struct sigaction old[2]) {
    sigaction(SIGINT, &old[0], NULL);
    sigaction(SIGTERM, &old[1], NULL);
}

int cli_library_report(const char *command, const char *label, const char *json_head, const char *done_word,
                       const char *output, int json, mr_status status, mr_gltf_library_result *r) {
    if (status != MR_OK && r->items == NULL) return cli_fail(command, status);
    int code = status != MR_OK ? cli_fail(command, status) : CLI_EXIT_OK;
    for (int i = 0; i < r->count; i++)
        if (strcmp(r->items[i].status, "failed") == 0)
            fprintf(stderr, "matremap %s: %s failed: %s\n", command, r->items[i].input, r->items[i].error);
    if (json) {
        printf("{%s, \"output\": ", json_head);
        cli_json_string(stdout, output);
        printf(", \"assets\": %d, \"%s\": %d, \"resumed\": %d, \"failed\": %d, \"cancelled\": %d, "
               "\"texels\": %zu, \"seconds\": %.6f, \"failures\": [", r->count, done_word, r->converted, r->resumed,
               r->failed, r->cancelled, r->texels, r->seconds);
        for (int i = 0, first = 1; i < r->count; i++)
            if (strcmp(r->items[i].status, "failed") == 0) {
                printf("%s{\"input\": ", first ? "" : ", ");
                cli_json_string(stdout, r->items[i].input);
                printf(", \"error\": ");
                cli_json_string(stdout, r->items[i].error);
                printf("}");
                first = 0;
            }
        printf("]}\n");
    } else {
        const int finished = r->count - r->cancelled;
        printf("matremap %s: %d asset%s: %d %s, %d resumed, %d failed", label, r->count, r->count == 1 ? "" : "s",
               r->converted, done_word, r->resumed, r->failed);
        if (r->cancelled > 0) printf(", %d cancelled", r->cancelled);
        const size_t len = strlen(output);
        const char *sep = len > 0 && output[len - 1] == '/' ? "" : "/";
        printf(" in %.2f s (%.1f assets/min); wrote %s%ssummary.json and %s%sindex.html\n", r->seconds,
               r->seconds > 0 ? 60.0 * finished / r->seconds : 0.0, output, sep, output, sep);
    }
    if (code == CLI_EXIT_OK && r->failed > 0) code = CLI_EXIT_BAD_INPUT;
    mr_gltf_library_result_free(r);
    return code;
}
