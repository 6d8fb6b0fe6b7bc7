/*
 * test_headers.c — the public headers are self-contained in C (each included first in its own unit would be
 * stricter; here every header is included alone before matremap.h pulls the rest), the version macros agree
 * with mr_version(), status names round-trip, and the core RNG gives splitmix64's stream. tests/headers_cpp.cpp
 * compiles them as C++.
 */
#include "brdf/brdf.h"
#include "io/image_io.h"
#include "io/obj_load.h"
#include "metrics/metrics.h"
#include "render/render.h"
#include "remap/direct.h"
#include "remap/sweep.h"
#include "workflow/workflow.h"
#include "workflow/dataset.h"
#include "workflow/pairs.h"
#include "learn/learned_plots.h"
#include "report/report.h"
#include "nn/mlp.h"
#include "gltf/mr_gltf.h"
#include "gltf/mr_gltf_scene.h"
#include "gltf/mr_gltf_library.h"
#include "doc/doc.h"
#include "mr_core.h"
#include "matremap.h"

#include <omp.h>
#include <stdio.h>

#include "harness.h"

MR_TEST(version_string_matches_macros) {
    char expected[32];
    snprintf(expected, sizeof expected, "%d.%d.%d", MR_VERSION_MAJOR, MR_VERSION_MINOR, MR_VERSION_PATCH);
    MR_CHECK(strcmp(mr_version(), expected) == 0);
    MR_CHECK(strcmp(MR_VERSION_STRING, expected) == 0);
}

MR_TEST(status_names_are_complete) {
    MR_CHECK(strcmp(mr_status_str(MR_OK), "MR_OK") == 0);
    MR_CHECK(strcmp(mr_status_str(MR_ERR_CANCELLED), "MR_ERR_CANCELLED") == 0);
    MR_CHECK(strcmp(mr_status_str(MR_STATUS_COUNT), "MR_STATUS_UNKNOWN") == 0);
    MR_CHECK(strcmp(mr_status_str((mr_status)-1), "MR_STATUS_UNKNOWN") == 0);
    for (int s = 0; s < MR_STATUS_COUNT; s++) MR_CHECK(strncmp(mr_status_str((mr_status)s), "MR_", 3) == 0);
}

MR_TEST(last_error_is_per_thread_and_clearable) {
    mr_clear_error();
    MR_CHECK(mr_last_error()[0] == '\0');
    MR_CHECK(mr_image_create(0, 1, 3, NULL) == MR_ERR_INVALID_ARG);
    MR_CHECK(strstr(mr_last_error(), "0x1") != NULL);
    // A worker thread starts with no message, and its own failure does not overwrite the main thread's.
    int worker_started_empty = 0, worker_ran = 0;
#pragma omp parallel num_threads(2)
    {
        if (omp_get_thread_num() == 1) {
            worker_ran = 1;
            worker_started_empty = mr_last_error()[0] == '\0';
            mr_image_create(1, 1, 2, NULL); // "2 channels" message on the worker only
        }
    }
    if (worker_ran) MR_CHECK(worker_started_empty);
    MR_CHECK(strstr(mr_last_error(), "0x1") != NULL);
    mr_clear_error();
    MR_CHECK(mr_last_error()[0] == '\0');
}

/* The core RNG's stream is part of the outputs' contract (a sweep's samples, a dataset's texels, a network's and an
 * SVR's split follow from their seed): its first values for seed 1, as splitmix64's reference gives them, so a
 * change of the stream fails here before it changes a file. */
MR_TEST(rng_stream_is_splitmix64) {
    uint64_t state = 1;
    MR_CHECK(mr_rng_next(&state) == 0x910a2dec89025cc1ULL);
    MR_CHECK(mr_rng_next(&state) == 0xbeeb8da1658eec67ULL);
    MR_CHECK(mr_rng_next(&state) == 0xf893a2eefb32555eULL);
    state = 1;
    MR_CHECK(mr_rng_unit(&state) == 5103132997656651.0 * 0x1p-53); // the top 53 bits of the first value
    MR_CHECK(mr_rng_unit(&state) == 6717404888216029.0 * 0x1p-53);
    MR_CHECK(mr_rng_mix(1) == 0x5692161d100b05e5ULL);
    MR_CHECK(mr_rng_stream(1, 1) == 0xc8a9e97d2c18711aULL);
}

MR_TEST_MAIN(MR_TEST_ENTRY(version_string_matches_macros), MR_TEST_ENTRY(status_names_are_complete),
             MR_TEST_ENTRY(last_error_is_per_thread_and_clearable), MR_TEST_ENTRY(rng_stream_is_splitmix64))
