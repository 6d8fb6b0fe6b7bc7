/*
 * fuzz_sweep.c — the sweep-file readers: `learn`'s (mr_sweep_table_load: any model pair), `train`'s
 * (mr_wf_dataset_load: the specular -> metallic dataset), `sweep merge`'s (mr_sweep_merge: the header read back
 * into a sweep, every row checked; the bytes as a one-shard set), and the row parser and checks a resumed sweep
 * reads its rows with (mr_sweep_parse_row, mr_sweep_check_row), for a Ward -> GGX sweep and for the dataset's
 * spec-gloss -> metal-rough one.
 */
#include <string.h>
#include <unistd.h>

#include "fuzz.h"
#include "matremap.h"

static void parse_rows(const char *source, const char *target, const uint8_t *data, size_t size) {
    mr_sweep_spec spec;
    mr_sweep_spec_init(&spec, mr_brdf_find(source), mr_brdf_find(target));
    const char *text = (const char *)data, *end = text + size;
    while (text < end) {
        const char *newline = memchr(text, '\n', (size_t)(end - text));
        size_t length = newline != NULL ? (size_t)(newline - text + 1) : (size_t)(end - text);
        mr_sweep_row row;
        if (mr_sweep_parse_row(&spec, text, length, &row) == MR_OK) (void)mr_sweep_check_row(&spec, &row);
        text += length;
    }
}

int mr_fuzz_sweep(const uint8_t *data, size_t size) {
    const char *path = fuzz_write_scratch("in.csv", data, size);
    if (path == NULL) return 0;
    mr_sweep_table table;
    if (mr_sweep_table_load(&path, 1, NULL, &table) == MR_OK) mr_sweep_table_free(&table);
    mr_wf_dataset dataset;
    if (mr_wf_dataset_load(&path, 1, NULL, &dataset) == MR_OK) mr_wf_dataset_free(&dataset);
    const char *merged = fuzz_scratch_path("merged.csv");
    mr_sweep_merge_summary summary;
    if (merged != NULL && mr_sweep_merge(&path, 1, merged, "fuzz", &summary) == MR_OK) unlink(merged);
    parse_rows("ward", "ggx", data, size);
    parse_rows("gltf-specgloss", "gltf", data, size);
    return 0;
}

MR_FUZZ_ENTRY(mr_fuzz_sweep)
