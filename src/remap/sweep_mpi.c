/*
 * sweep_mpi.c — `matremap sweep` under mpirun: finds out whether an MPI launcher started this process, loads
 * the MPI module (libmatremap-mpi.so, sweep_mpi_module.c) and wraps it as an mr_sweep_comm (contracts in
 * sweep.h).
 *
 * Why a module: the library and the tool must build and run where Open MPI is not installed, and linking libmpi
 * into every program costs start-up time and ties the binary to one MPI. The plain `matremap` binary therefore
 * loads MPI only when a launcher started it, as it loads OpenImageIO only for the images that need it
 * (src/io/oiio_module.c, which this file follows). Where the module is looked for, in order:
 *   1. the file named by the environment variable MR_MPI_MODULE, if set;
 *   2. <directory of the running executable>/../lib/matremap/libmatremap-mpi.so (build tree and install tree);
 *   3. MR_MODULE_DIR/libmatremap-mpi.so.
 */
#include <omp.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "../mr_internal.h"
#include "sweep.h"

#ifndef MR_MODULE_DIR
#define MR_MODULE_DIR "/usr/local/lib/matremap"
#endif

#define MODULE_FILE "libmatremap-mpi.so"
#define MODULE_ABI 1 /* sweep_mpi_module.c's */

typedef struct mpi_module {
    int (*abi)(void);
    const char *(*error)(void);
    int (*init)(int *, int *, int *);
    int (*broadcast)(void *, size_t);
    int (*send)(int, int, const void *, size_t);
    int (*receive)(int, int *, int *, void *, size_t, size_t *, int *);
    int (*flush)(void);
    int (*finalize)(void);
} mpi_module;

static mpi_module module;
static int state; /* 0: MPI not started, 1: running, 2: finished (MPI cannot start twice in a process) */

int mr_sweep_mpi_launched(int *size, int *rank, const char **variable) {
    static const char *const vars[][2] = {{"OMPI_COMM_WORLD_SIZE", "OMPI_COMM_WORLD_RANK"}, {"PMI_SIZE", "PMI_RANK"}};
    for (size_t k = 0; k < sizeof vars / sizeof vars[0]; k++) {
        const char *s = getenv(vars[k][0]), *r = getenv(vars[k][1]);
        if (s == NULL || s[0] == '\0')
            continue;
        long n = strtol(s, NULL, 10), me = r ? strtol(r, NULL, 10) : 0;
        if (n <= 1)
            return 0;
        if (size)
            *size = (int)MR_MIN(n, INT_MAX);
        if (rank)
            *rank = (int)MR_MIN(me, INT_MAX);
        if (variable)
            *variable = vars[k][0];
        return 1;
    }
    return 0;
}

/* mr_module_spec's check: the interface of this build (entries[0] is mr_mpi_module_abi). */
static const char *check_abi(void *const *entries, char *reason, size_t size) {
    int (*abi)(void);
    memcpy(&abi, &entries[0], sizeof entries[0]);
    if (abi() == MODULE_ABI) return NULL;
    snprintf(reason, size, "module interface %d, this matremap needs %d (a module of another build)", abi(),
             MODULE_ABI);
    return reason;
}

/* The module's functions into `module`; 0 with why it could not be loaded in why[]. */
static int load_module(char *why, size_t size) {
    static const char *const names[] = {"mr_mpi_module_abi",       "mr_mpi_module_error",   "mr_mpi_module_init",
                                        "mr_mpi_module_broadcast", "mr_mpi_module_send",    "mr_mpi_module_receive",
                                        "mr_mpi_module_flush",     "mr_mpi_module_finalize"};
    static const mr_module_spec spec = {MODULE_FILE, "MR_MPI_MODULE", "MPI", names, 8, check_abi};
    void *syms[8];
    if (mr_module_open(&spec, syms, why, size) == NULL) return 0;
    // POSIX allows converting dlsym's void * to a function pointer; ISO C does not, hence the memcpy.
    mpi_module m;
    memcpy(&m.abi, &syms[0], sizeof syms[0]);
    memcpy(&m.error, &syms[1], sizeof syms[1]);
    memcpy(&m.init, &syms[2], sizeof syms[2]);
    memcpy(&m.broadcast, &syms[3], sizeof syms[3]);
    memcpy(&m.send, &syms[4], sizeof syms[4]);
    memcpy(&m.receive, &syms[5], sizeof syms[5]);
    memcpy(&m.flush, &syms[6], sizeof syms[6]);
    memcpy(&m.finalize, &syms[7], sizeof syms[7]);
    module = m;
    return 1;
}

/* mr_sweep_comm's functions over the module. */
static mr_status module_status(int rc, const char *what) {
    if (rc == 0)
        return MR_OK;
    return mr_fail(MR_ERR_EXTERNAL, "MPI: %s: %s", what, module.error());
}

static mr_status comm_broadcast(void *user, void *buf, size_t bytes) {
    (void)user;
    return module_status(module.broadcast(buf, bytes), "broadcast");
}

static mr_status comm_send(void *user, int to, int tag, const void *buf, size_t bytes) {
    (void)user;
    return module_status(module.send(to, tag, buf, bytes), "send");
}

static mr_status comm_receive(void *user, int wait, int *from, int *tag, void *buf, size_t *bytes, int *got) {
    (void)user;
    return module_status(module.receive(wait, from, tag, buf, MR_SWEEP_MESSAGE_MAX, bytes, got), "receive");
}

static mr_status comm_flush(void *user) {
    (void)user;
    return module_status(module.flush(), "flush");
}

mr_status mr_sweep_mpi_start(mr_sweep_comm *comm, int *local_size) {
    if (comm == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "sweep: NULL comm");
    if (state != 0)
        return mr_fail(MR_ERR_INVALID_ARG, "sweep: MPI was started already (once per process)");
    char why[2048] = "";
    if (module.init == NULL && !load_module(why, sizeof why))
        return mr_fail(MR_ERR_UNSUPPORTED,
                       "started by an MPI launcher, but this matremap has no MPI module: " MODULE_FILE
                       " is built only where Open MPI's development files are installed (scripts/install-deps.sh, "
                       "then make); looked beside the executable in ../lib/matremap and in " MR_MODULE_DIR
                       " (set MR_MPI_MODULE to its path): %s",
                       why);
    int rank = 0, size = 1, local = 1;
    int rc = module.init(&rank, &size, &local);
    if (rc != 0)
        return mr_fail(MR_ERR_EXTERNAL, "MPI did not start: %s", module.error());
    state = 1;
    memset(comm, 0, sizeof *comm);
    comm->rank = rank;
    comm->size = size;
    comm->broadcast = comm_broadcast;
    comm->send = comm_send;
    comm->receive = comm_receive;
    comm->flush = comm_flush;
    if (local_size != NULL)
        *local_size = local;
    return MR_OK;
}

mr_status mr_sweep_mpi_finish(mr_sweep_comm *comm) {
    if (state != 1)
        return mr_fail(MR_ERR_INVALID_ARG, "sweep: MPI is not running");
    state = 2;
    if (comm != NULL)
        memset(comm, 0, sizeof *comm);
    return module_status(module.finalize(), "finalize");
}

int mr_sweep_rank_threads(int local_size) {
    if (getenv("OMP_NUM_THREADS") != NULL) return 0;
    const int share = omp_get_num_procs() / (local_size > 1 ? local_size : 1);
    return share > 1 ? share : 1;
}
