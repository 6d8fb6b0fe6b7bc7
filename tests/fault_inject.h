/*
 * fault_inject.h — the one hook fault_inject.c shares with fault_inject_new.cpp (the fault build only; see
 * fault_inject.c for the mechanism and the environment variables).
 */
#ifndef MR_FAULT_INJECT_H
#define MR_FAULT_INJECT_H

#ifdef __cplusplus
extern "C" {
#endif

/* Count one allocation named `name`; 1 if it must fail. `spare` (may be NULL) is called only when it would: if it
 * returns 1, the allocation goes through and is counted as spared. */
int mr_fault_alloc_hit(const char *name, int (*spare)(void));

#ifdef __cplusplus
}
#endif

#endif /* MR_FAULT_INJECT_H */
