/*
 * sweep_mpi_module.c — libmatremap-mpi.so: every MPI call of `matremap sweep`, in a module of its own that
 * sweep_mpi.c loads when the tool runs under mpirun (why a module: sweep_mpi.c). Built only where Open MPI's
 * development files are installed (pkg-config mpi-c); the library and the tool build and run without them.
 *
 * The interface is plain C with ints, so that the module shares no type with the library: each function returns
 * 0 on success or an MPI error code, and mr_mpi_module_error() says what failed (per thread). The library calls
 * it one thread at a time (mr_sweep_comm, sweep.h), so MPI_THREAD_SERIALIZED is asked for.
 *
 * Sends are non-blocking (MPI_Isend from a copy of the bytes, the request kept until it completes): a rank never
 * waits for rank 0 to be ready to receive a row. A waiting receive polls (MPI_Iprobe) and sleeps 1 ms between
 * polls instead of spinning in MPI_Recv, so a rank that waits (rank 0 for the last rows, the others for the end)
 * leaves its core to the ranks still computing.
 */
#include <mpi.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define EXPORT __attribute__((visibility("default")))

/* Bumped whenever a function below changes: sweep_mpi.c refuses a module of another version. */
#define MODULE_ABI 1

static _Thread_local char error_text[512];

typedef struct pending_send {
    MPI_Request request;
    void *bytes;
} pending_send;

static pending_send *sends;
static int send_count, send_capacity;

static int fail(int rc, const char *what) {
    char text[MPI_MAX_ERROR_STRING] = "";
    int len = 0;
    if (MPI_Error_string(rc, text, &len) != MPI_SUCCESS)
        snprintf(text, sizeof text, "error %d", rc);
    snprintf(error_text, sizeof error_text, "%s: %s", what, text);
    return rc == 0 ? -1 : rc;
}

EXPORT int mr_mpi_module_abi(void) { return MODULE_ABI; }

EXPORT const char *mr_mpi_module_error(void) { return error_text; }

EXPORT int mr_mpi_module_init(int *rank, int *size, int *local_size) {
    int provided = 0, rc = MPI_Init_thread(NULL, NULL, MPI_THREAD_SERIALIZED, &provided);
    if (rc != MPI_SUCCESS)
        return fail(rc, "MPI_Init_thread");
    if (provided < MPI_THREAD_SERIALIZED) {
        snprintf(error_text, sizeof error_text,
                 "this MPI provides thread level %d, the sweep needs MPI_THREAD_SERIALIZED (%d)", provided,
                 MPI_THREAD_SERIALIZED);
        MPI_Finalize();
        return -1;
    }
    MPI_Comm_rank(MPI_COMM_WORLD, rank);
    MPI_Comm_size(MPI_COMM_WORLD, size);
    MPI_Comm local;
    *local_size = 1;
    if (MPI_Comm_split_type(MPI_COMM_WORLD, MPI_COMM_TYPE_SHARED, 0, MPI_INFO_NULL, &local) == MPI_SUCCESS) {
        MPI_Comm_size(local, local_size);
        MPI_Comm_free(&local);
    }
    return 0;
}

/* MPI counts are ints: larger buffers go in pieces. */
EXPORT int mr_mpi_module_broadcast(void *buf, size_t bytes) {
    for (size_t at = 0; at < bytes;) {
        int n = bytes - at > (size_t)1 << 30 ? 1 << 30 : (int)(bytes - at);
        int rc = MPI_Bcast((char *)buf + at, n, MPI_BYTE, 0, MPI_COMM_WORLD);
        if (rc != MPI_SUCCESS)
            return fail(rc, "MPI_Bcast");
        at += (size_t)n;
    }
    return 0;
}

/* Forget the sends that have completed. */
static int reap_sends(void) {
    int kept = 0;
    for (int i = 0; i < send_count; i++) {
        int done = 0;
        int rc = MPI_Test(&sends[i].request, &done, MPI_STATUS_IGNORE);
        if (rc != MPI_SUCCESS)
            return fail(rc, "MPI_Test");
        if (done)
            free(sends[i].bytes);
        else
            sends[kept++] = sends[i];
    }
    send_count = kept;
    return 0;
}

EXPORT int mr_mpi_module_send(int to, int tag, const void *buf, size_t bytes) {
    int rc = reap_sends();
    if (rc != 0)
        return rc;
    if (send_count == send_capacity) {
        int capacity = send_capacity ? 2 * send_capacity : 64;
        pending_send *grown = realloc(sends, (size_t)capacity * sizeof *grown);
        if (grown == NULL) {
            snprintf(error_text, sizeof error_text, "out of memory queueing a message");
            return -1;
        }
        sends = grown;
        send_capacity = capacity;
    }
    void *copy = malloc(bytes ? bytes : 1);
    if (copy == NULL) {
        snprintf(error_text, sizeof error_text, "out of memory queueing a message of %zu bytes", bytes);
        return -1;
    }
    memcpy(copy, buf, bytes);
    rc = MPI_Isend(copy, (int)bytes, MPI_BYTE, to, tag, MPI_COMM_WORLD, &sends[send_count].request);
    if (rc != MPI_SUCCESS) {
        free(copy);
        return fail(rc, "MPI_Isend");
    }
    sends[send_count++].bytes = copy;
    return 0;
}

EXPORT int mr_mpi_module_receive(int wait, int *from, int *tag, void *buf, size_t capacity, size_t *bytes, int *got) {
    *got = 0;
    for (;;) {
        int flag = 0;
        MPI_Status status;
        int rc = MPI_Iprobe(MPI_ANY_SOURCE, MPI_ANY_TAG, MPI_COMM_WORLD, &flag, &status);
        if (rc != MPI_SUCCESS)
            return fail(rc, "MPI_Iprobe");
        if (flag) {
            int count = 0;
            MPI_Get_count(&status, MPI_BYTE, &count);
            if (count < 0 || (size_t)count > capacity) {
                snprintf(error_text, sizeof error_text, "a message of %d bytes from rank %d (at most %zu expected)",
                         count, status.MPI_SOURCE, capacity);
                return -1;
            }
            rc = MPI_Recv(buf, count, MPI_BYTE, status.MPI_SOURCE, status.MPI_TAG, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
            if (rc != MPI_SUCCESS)
                return fail(rc, "MPI_Recv");
            *from = status.MPI_SOURCE;
            *tag = status.MPI_TAG;
            *bytes = (size_t)count;
            *got = 1;
            return 0;
        }
        if (!wait)
            return reap_sends();
        struct timespec pause = {0, 1000000};
        nanosleep(&pause, NULL);
    }
}

EXPORT int mr_mpi_module_flush(void) {
    while (send_count > 0) {
        int rc = reap_sends();
        if (rc != 0)
            return rc;
        if (send_count > 0) {
            struct timespec pause = {0, 1000000};
            nanosleep(&pause, NULL);
        }
    }
    return 0;
}

EXPORT int mr_mpi_module_finalize(void) {
    int rc = mr_mpi_module_flush();
    free(sends);
    sends = NULL;
    send_capacity = 0;
    // Every rank waits here for all: rank 0 reports before it comes, and a rank that then leaves with an error
    // makes mpirun kill the rest (MPI_Finalize need not synchronise by itself).
    MPI_Barrier(MPI_COMM_WORLD);
    int fin = MPI_Finalize();
    if (rc != 0)
        return rc;
    return fin == MPI_SUCCESS ? 0 : fail(fin, "MPI_Finalize");
}
