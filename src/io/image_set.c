/*
 * image_set.c — a set of images written all or none (contract in image_io.h, "output sets").
 *
 * Each image is written by mr_img_write (itself atomic) to a temporary name beside its target; the renames come
 * only after every write succeeded. The writes run side by side: PNG compression is most of a 2048^2 texture
 * set's conversion time, and image_io is thread-safe. mr_last_error() is per thread, so each write keeps its own
 * message and the first failure in item order is the one reported.
 */
#include <errno.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "image_io.h"
#include "mr_internal.h"

#define SET_PATH_SIZE 4160 /* a target's path and the temporary prefix ".matremap-<pid>-" */
#define SET_MESSAGE_SIZE 1024

typedef struct set_job {
    char temp[SET_PATH_SIZE];
    int skipped; /* not written: an earlier item had failed (the set is lost anyway) */
    mr_status status;
    char message[SET_MESSAGE_SIZE];
} set_job;

/* Refuse a target that is a folder or that another item names too, before anything is written. */
static mr_status check_targets(const mr_img_set_item *items, int count, int *failed) {
    for (int k = 0; k < count; k++) {
        struct stat st;
        *failed = k;
        if (items[k].path == NULL || items[k].image == NULL)
            return mr_fail(MR_ERR_INVALID_ARG, "mr_img_write_set: item %d has no %s", k,
                           items[k].path == NULL ? "path" : "image");
        if (stat(items[k].path, &st) == 0 && S_ISDIR(st.st_mode)) {
            if (items[k].label != NULL)
                return mr_fail(MR_ERR_INVALID_ARG, "output '%s' (%s) is a folder", items[k].path, items[k].label);
            return mr_fail(MR_ERR_INVALID_ARG, "output '%s' is a folder", items[k].path);
        }
        for (int j = 0; j < k; j++)
            if (strcmp(items[j].path, items[k].path) == 0)
                return mr_fail(MR_ERR_INVALID_ARG, "output '%s' is named twice in one set", items[k].path);
    }
    *failed = -1;
    return MR_OK;
}

mr_status mr_img_write_set(const mr_img_set_item *items, int count, const mr_img_set_options *opts, int *failed) {
    int failed_index = -1;
    if (failed == NULL) failed = &failed_index;
    *failed = -1;
    if (count <= 0) return MR_OK;
    mr_status status = check_targets(items, count, failed);
    if (status != MR_OK) return status;
    set_job *jobs = calloc((size_t)count, sizeof *jobs);
    if (jobs == NULL) return mr_fail(MR_ERR_NOMEM, "out of memory");
    for (int k = 0; k < count; k++) {
        const char *path = items[k].path, *slash = strrchr(path, '/');
        const int head = slash ? (int)(slash - path) + 1 : 0;
        const int n = snprintf(jobs[k].temp, sizeof jobs[k].temp, "%.*s.matremap-%ld-%s", head, path,
                               (long)getpid(), path + head);
        if (n < 0 || (size_t)n >= sizeof jobs[k].temp) {
            free(jobs);
            *failed = k;
            return mr_fail(MR_ERR_INVALID_ARG, "output '%s': path too long", path);
        }
    }
    const int requested = opts != NULL ? opts->threads : 0;
    const int allowed = mr_auto_threads(requested, count, 2);
    const int team = allowed < count ? allowed : count;
    // Once a write has failed the set is lost: the items not yet started are skipped. Items are handed out in
    // order, so every skipped item comes after a failed one, which is the one reported.
    atomic_int stop = 0;
#pragma omp parallel for schedule(dynamic, 1) num_threads(team) if (team > 1)
    for (int k = 0; k < count; k++) {
        if (atomic_load(&stop)) {
            jobs[k].skipped = 1;
            continue;
        }
        jobs[k].status = mr_img_write(jobs[k].temp, items[k].image, &items[k].options);
        if (jobs[k].status != MR_OK) {
            snprintf(jobs[k].message, sizeof jobs[k].message, "%s", mr_last_error());
            atomic_store(&stop, 1);
        }
    }
    for (int k = 0; k < count && status == MR_OK; k++)
        if (jobs[k].status != MR_OK) { // the message names the temporary file: say which output it was
            *failed = k;
            status = mr_fail(jobs[k].status, "writing '%s': %s", items[k].path,
                             jobs[k].message[0] ? jobs[k].message : mr_status_str(jobs[k].status));
        }
    for (int k = 0; status == MR_OK && k < count; k++)
        if (rename(jobs[k].temp, items[k].path) != 0) {
            // Leave none of this set: a set half replaced would not belong together.
            const int err = errno;
            for (int j = 0; j < k; j++) remove(items[j].path);
            *failed = k;
            status = mr_fail(MR_ERR_IO, "cannot rename '%s' to '%s': %s%s", jobs[k].temp, items[k].path,
                             strerror(err), k ? " (the outputs renamed before it removed)" : "");
        }
    if (status != MR_OK)
        for (int k = 0; k < count; k++) unlink(jobs[k].temp); // the renamed ones are gone already
    free(jobs);
    return status;
}

mr_status mr_img_prefixed_name(char *out, size_t size, const char *prefix, const char *name) {
    const size_t length = strlen(prefix);
    const int direct = length == 0 || strchr("/_-.", prefix[length - 1]) != NULL;
    const int n = snprintf(out, size, "%s%s%s", prefix, direct ? "" : "_", name);
    if (n < 0 || (size_t)n >= size) return mr_fail(MR_ERR_INVALID_ARG, "prefix '%s': the name of '%s' is too long",
                                                   prefix, name);
    return MR_OK;
}
