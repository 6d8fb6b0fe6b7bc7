/*
 * gltf_support.h — what test_gltf.c and test_gltf_geometry.c share: the shared assets they read and small file
 * helpers. Included by test files only (static: each test binary gets its own copy).
 */
#ifndef MR_TEST_GLTF_SUPPORT_H
#define MR_TEST_GLTF_SUPPORT_H

#include <dirent.h>
#include <stdint.h>
#include <sys/stat.h>
#include <unistd.h>

#include "gltf/mr_gltf.h"
#include "harness.h"

static inline const char *asset_path(const char *rel) { return mr_test_asset_path(rel); }

static inline int file_exists(const char *path) {
    struct stat st;
    return stat(path, &st) == 0;
}

static inline long file_size(const char *path) {
    struct stat st;
    return stat(path, &st) == 0 ? (long)st.st_size : -1;
}

static inline int copy_file(const char *from, const char *to) {
    size_t n;
    char *b = mr_test_read_file(from, &n);
    if (b == NULL) return 0;
    int ok = mr_test_write_file(to, b, n);
    free(b);
    return ok;
}

/* Number of directory entries (not . and ..). */
static inline int count_entries(const char *dir) {
    DIR *d = opendir(dir);
    if (d == NULL) return -1;
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d)) != NULL)
        if (strcmp(e->d_name, ".") != 0 && strcmp(e->d_name, "..") != 0) n++;
    closedir(d);
    return n;
}

static const struct {
    const char *name;
    const char *rel;
} ASSETS[] = {
    {"Avocado", "specgloss/Avocado-pbrSpecularGlossiness/glTF-pbrSpecularGlossiness/Avocado.gltf"},
    {"CesiumMilkTruck", "specgloss/CesiumMilkTruck-pbrSpecularGlossiness/glTF-pbrSpecularGlossiness/"
                        "CesiumMilkTruck.gltf"},
    {"Duck", "specgloss/Duck-pbrSpecularGlossiness/glTF-pbrSpecularGlossiness/Duck.gltf"},
    {"FloppyDisk", "specgloss/FloppyDisk-sketchfab/scene.gltf"},
    {"TextureSettingsTest", "metalrough/TextureSettingsTest/glTF/TextureSettingsTest.gltf"},
    {"WaterBottle", "metalrough/WaterBottle/glTF/WaterBottle.gltf"},
};
#define ASSET_COUNT ((int)(sizeof ASSETS / sizeof ASSETS[0]))

static inline mr_gltf *load_asset(const char *name) {
    for (int i = 0; i < ASSET_COUNT; i++) {
        if (strcmp(ASSETS[i].name, name) != 0) continue;
        mr_gltf *g = NULL;
        MR_CHECK_OK(mr_gltf_load(asset_path(ASSETS[i].rel), &g));
        return g;
    }
    return NULL;
}

#endif /* MR_TEST_GLTF_SUPPORT_H */
