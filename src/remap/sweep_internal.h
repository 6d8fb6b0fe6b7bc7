/*
 * sweep_internal.h — what the sweep's files share beyond the file format (sweep_file.h): the samples of a checked
 * spec and the check of a row line against the shard it belongs to. Defined in sweep.c; used by sweep_file.c and
 * sweep_merge.c. Not installed, not public.
 */
#ifndef MR_REMAP_SWEEP_INTERNAL_H
#define MR_REMAP_SWEEP_INTERNAL_H

#include <stddef.h>

#include "../mr_status.h"
#include "sweep.h"

/* mr_sweep_sample_count without the check: more than MR_SWEEP_MAX_SAMPLES for a grid too large. */
long mr_sweep_total_unchecked(const mr_sweep_spec *spec);

/* 1 if RANDOM draws source parameter p of the spec (the header's "over" list). */
int mr_sweep_draws_param(const mr_sweep_spec *spec, int p);

/* Samples with index % shards == shard among [0, total). */
long mr_sweep_shard_size(long total, long shard, long shards);

/* Parse and check one complete row line (`length` bytes, its '\n' included) of a file that holds shard `shard`
 * of `shards` of the sweep `spec` of `total` samples: the syntax, the values (mr_sweep_file_check_row), a sample
 * of this file, and that sample's source values. The message says what is wrong, not where: callers add the file
 * and line. */
mr_status mr_sweep_check_line(const mr_sweep_spec *spec, long total, long shard, long shards, const char *line,
                              size_t length, mr_sweep_row *row);

#endif /* MR_REMAP_SWEEP_INTERNAL_H */
