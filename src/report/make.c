/*
 * make.c — making a report from materials or glTF scenes (contract in report.h, "Making a report"): checks, the
 * environment map, the folder; for each view one render plan shared by all inputs, renders, pictures and
 * comparisons; thumbnails of every map; then the page and summary (mr_report_write, report.c).
 */
#include <dirent.h>
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "../mr_internal.h"
#include "gltf/mr_gltf_scene.h"
#include "metrics/metrics.h"
#include "render/renderer.h"
#include "report.h"

/* A generated description is cut here: the page shows it in one table cell. */
#define DESCRIPTION_SIZE 2048

/* What the report holds per input while it is made: the names of its pictures, its figures, its thumbnails. */
typedef struct entry {
    const char *label;
    char description[DESCRIPTION_SIZE];
    char render_names[MR_REPORT_MAX_VIEWS][64], map_names[MR_REPORT_MAX_VIEWS][64];
    const char *renders[MR_REPORT_MAX_VIEWS], *ssim_maps[MR_REPORT_MAX_VIEWS];
    double ssim[MR_REPORT_MAX_VIEWS], relative_rmse[MR_REPORT_MAX_VIEWS];               /* the whole frame */
    double object_ssim[MR_REPORT_MAX_VIEWS], object_relative_rmse[MR_REPORT_MAX_VIEWS]; /* the object */
    double seconds;
    char thumb_names[MR_REPORT_MAX_THUMBNAILS][64], thumb_labels[MR_REPORT_MAX_THUMBNAILS][512];
    const char *thumbs[MR_REPORT_MAX_THUMBNAILS], *thumb_label_ptrs[MR_REPORT_MAX_THUMBNAILS];
    int thumb_count;
} entry;

/* The options with every default resolved. */
typedef struct settings {
    int size, views, env_samples, reflection_samples, threads;
    const mr_image *env; /* NULL: the fit scene's point light */
    const char *env_name;
    double env_scale, exposure; /* exposure 0: pick it from the first render */
    int has_camera_direction;
    double camera_direction[3];
    const mr_mesh *mesh;  /* materials on a mesh; NULL: the unit sphere */
    const char *mesh_name;
    mr_camera camera;     /* with mesh: the camera every view uses */
    const char *title;
    int (*progress)(void *user, int done, int total, const char *what);
    void *progress_user;
} settings;

/* ---- pixels ------------------------------------------------------------------------------------------------ */

/* Rec. 709 luminance of a linear RGB pixel. */
static double luminance(const float *p) { return 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2]; }

/* The environment scale that brings the map's mean luminance to 0.5 (a white Lambertian sphere then renders
 * about 0.5); 1 for a black map. */
static double auto_env_scale(const mr_image *map) {
    double sum = 0.0;
    size_t n = (size_t)map->width * (size_t)map->height;
    for (size_t i = 0; i < n; i++) {
        const float *p = map->pixels + i * (size_t)map->channels;
        sum += map->channels >= 3 ? luminance(p) : p[0];
    }
    return sum > 0.0 ? 0.5 * (double)n / sum : 1.0;
}

/* The exposure that brings the mean luminance of the pixels the object covers (coverage > 0.5) to 0.18. */
static double auto_exposure(const mr_render_plan *plan, const mr_image *image) {
    const float *coverage = mr_render_plan_coverage(plan);
    double sum = 0.0;
    size_t count = 0, n = (size_t)image->width * (size_t)image->height;
    for (size_t i = 0; i < n; i++)
        if (coverage[i] > 0.5f) {
            sum += luminance(image->pixels + 3 * i);
            count++;
        }
    return count > 0 && sum > 0.0 ? 0.18 * (double)count / sum : 1.0;
}

/* The mask a candidate is compared over: the reference's coverage, or, when the candidate has a plan of its own
 * (other geometry), the union (per-pixel maximum) of both, so that what either shows counts. */
static mr_status comparison_mask(const mr_image *reference_mask, const mr_render_plan *plan, int own_plan,
                                 mr_image **out) {
    mr_status status = mr_image_clone(reference_mask, out);
    if (status != MR_OK || !own_plan) return status;
    const float *coverage = mr_render_plan_coverage(plan);
    size_t n = mr_image_value_count(*out);
    for (size_t i = 0; i < n; i++)
        if (coverage[i] > (*out)->pixels[i]) (*out)->pixels[i] = coverage[i];
    return MR_OK;
}

/* Root mean square of an image's RGB values. */
static double rms(const mr_image *image) {
    double sum = 0.0;
    size_t n = mr_image_value_count(image);
    for (size_t i = 0; i < n; i++) sum += (double)image->pixels[i] * image->pixels[i];
    return sqrt(sum / (double)(n > 0 ? n : 1));
}

/* Write image x exposure as an sRGB PNG at dir/name. */
static mr_status write_picture(const char *dir, const char *name, const mr_image *image, double exposure) {
    mr_image *scaled = NULL;
    mr_status status = mr_image_create(image->width, image->height, image->channels, &scaled);
    if (status != MR_OK) return status;
    size_t n = mr_image_value_count(image);
    for (size_t i = 0; i < n; i++) scaled->pixels[i] = (float)(image->pixels[i] * exposure);
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    status = mr_img_write(path, scaled, NULL);
    mr_image_free(scaled);
    return status;
}

/* A thumbnail of a material's map, as its parameter reads it (the RGB, or the one channel), box-filtered to at
 * most MR_REPORT_THUMBNAIL_SIDE pixels on its longer side, written to dir/name. */
static mr_status write_thumbnail(const char *dir, const char *name, const mr_image *im, int channel, int rgb,
                                 int colour) {
    int longest = im->width > im->height ? im->width : im->height;
    int factor = (longest + MR_REPORT_THUMBNAIL_SIDE - 1) / MR_REPORT_THUMBNAIL_SIDE;
    int width = (im->width + factor - 1) / factor, height = (im->height + factor - 1) / factor;
    int channels = rgb ? 3 : 1;
    mr_image *thumb = NULL;
    mr_status status = mr_image_create(width, height, channels, &thumb);
    if (status != MR_OK) return status;
    for (int y = 0; y < height; y++)
        for (int x = 0; x < width; x++)
            for (int c = 0; c < channels; c++) {
                int source = im->channels == 1 ? 0 : (rgb ? c : channel);
                double sum = 0.0;
                int count = 0;
                for (int j = y * factor; j < (y + 1) * factor && j < im->height; j++)
                    for (int i = x * factor; i < (x + 1) * factor && i < im->width; i++, count++)
                        sum += mr_image_at(im, i, j)[source];
                mr_image_at(thumb, x, y)[c] = (float)(sum / count);
            }
    char path[4096];
    if (snprintf(path, sizeof path, "%s/%s", dir, name) >= (int)sizeof path) {
        mr_image_free(thumb);
        return mr_fail(MR_ERR_INVALID_ARG, "report folder '%s': the path of '%s' is longer than %zu bytes", dir, name,
                       sizeof path - 1);
    }
    mr_img_write_options wo = {0};
    wo.encoding = colour ? MR_IMG_COLOR : MR_IMG_DATA;
    status = mr_img_write(path, thumb, &wo);
    mr_image_free(thumb);
    return status;
}

/* ---- checks and defaults ----------------------------------------------------------------------------------- */

/* Every input is one material or one scene, all of one kind; *scenes says which. */
static mr_status check_inputs(const mr_report_input *inputs, int count, int *scenes) {
    if (inputs == NULL || count < 1)
        return mr_fail(MR_ERR_INVALID_ARG, "report: %d inputs: expected at least the reference", count);
    for (int k = 0; k < count; k++) {
        const mr_report_input *in = &inputs[k];
        const int kinds = (in->material != NULL) + (in->scene != NULL) + (in->external != NULL);
        if (kinds != 1)
            return mr_fail(MR_ERR_INVALID_ARG, "report input %d: expected a material, a glTF scene or a renderer's "
                           "material (%s)", k, kinds == 0 ? "it has none" : "it has more than one");
        const int external = !mr_renderer_is_builtin(in->renderer);
        if (in->external != NULL && !external)
            return mr_fail(MR_ERR_INVALID_ARG, "report input %d: material '%s' needs its renderer", k,
                           mr_external_material_reference(in->external));
        if (external && in->scene != NULL)
            return mr_fail(MR_ERR_UNSUPPORTED, "report input %d: renderer '%s' renders materials on the fit scene's "
                           "sphere, not glTF scenes", k, mr_renderer_name(in->renderer));
        if (external && in->material != NULL && in->material->map_count > 0)
            return mr_fail(MR_ERR_UNSUPPORTED, "report input %d: renderer '%s' renders uniform materials, not maps",
                           k, mr_renderer_name(in->renderer));
        if (in->material != NULL && in->material->model == NULL)
            return mr_fail(MR_ERR_INVALID_ARG, "report input %d: its material has no model", k);
        if (in->scene == NULL && in->material == NULL) continue; // a renderer's own: a material on the sphere
        if ((in->scene != NULL) != (inputs[0].scene != NULL))
            return mr_fail(MR_ERR_INVALID_ARG, "report input %d is a %s and input 0 a %s: give materials or glTF "
                           "scenes, not both", k, in->scene ? "glTF scene" : "material",
                           inputs[0].scene ? "glTF scene" : "material");
    }
    *scenes = inputs[0].scene != NULL;
    return MR_OK;
}

/* An option that must be 0 (its default) or within [lo, hi]. */
static mr_status check_int(const char *name, int value, int lo, int hi) {
    if (value == 0 || (value >= lo && value <= hi)) return MR_OK;
    return mr_fail(MR_ERR_INVALID_ARG, "report option %s %d: expected 0 (the default) or %d .. %d", name, value, lo,
                   hi);
}

/* A factor that must be 0 (automatic) or positive and finite. */
static mr_status check_factor(const char *name, double value) {
    if (value >= 0.0 && isfinite(value)) return MR_OK;
    return mr_fail(MR_ERR_INVALID_ARG, "report option %s %g: expected 0 (automatic) or > 0", name, value);
}

/* The options checked, with their defaults filled in, into *st (the map not yet read: st->env is opts->env). */
static mr_status resolve_options(const mr_report_options *opts, int scenes, settings *st) {
    const int has_env = opts->env != NULL || opts->env_path != NULL;
    mr_status status = check_int("size", opts->size, MR_REPORT_MIN_SIZE, MR_RENDER_MAX_SIZE);
    if (status == MR_OK) status = check_int("rotations", opts->rotations, 1, MR_REPORT_MAX_VIEWS);
    if (status == MR_OK) status = check_int("env_samples", opts->env_samples, 1, MR_ENV_MAX_SAMPLES);
    if (status == MR_OK && opts->reflection_samples != MR_REPORT_NO_REFLECTION_SAMPLES)
        status = check_int("reflection_samples", opts->reflection_samples, 1, MR_ENV_MAX_REFLECTION_SAMPLES);
    if (status == MR_OK) status = check_int("threads", opts->threads, 1, 1024);
    if (status == MR_OK) status = check_factor("env_scale", opts->env_scale);
    if (status == MR_OK) status = check_factor("exposure", opts->exposure);
    if (status != MR_OK) return status;
    if (!has_env && opts->rotations > 1)
        return mr_fail(MR_ERR_INVALID_ARG, "report option rotations %d needs an environment map (the fit scene has "
                       "one view)", opts->rotations);
    if (!has_env && (opts->env_scale > 0.0 || opts->env_samples != 0 || opts->reflection_samples != 0))
        return mr_fail(MR_ERR_INVALID_ARG, "report options env_scale, env_samples and reflection_samples need an "
                       "environment map");
    const double *d = opts->camera_direction;
    if (opts->has_camera_direction) {
        if (!scenes)
            return mr_fail(MR_ERR_INVALID_ARG, "report option camera_direction places the camera for glTF scenes; "
                           "spheres use the fit camera");
        if (!(isfinite(d[0]) && isfinite(d[1]) && isfinite(d[2])) || (d[0] == 0.0 && d[1] == 0.0 && d[2] == 0.0))
            return mr_fail(MR_ERR_INVALID_ARG, "report option camera_direction (%g, %g, %g): expected a finite, "
                           "non-zero direction", d[0], d[1], d[2]);
    }
    if (opts->mesh != NULL && scenes)
        return mr_fail(MR_ERR_INVALID_ARG, "report option mesh renders materials; glTF scenes bring their own");
    if (opts->mesh != NULL && !has_env)
        return mr_fail(MR_ERR_INVALID_ARG, "report option mesh needs an environment map (the fit scene's point "
                       "light is placed for the unit sphere)");
    if (opts->camera != NULL && opts->mesh == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "report option camera places the camera for a mesh; %s",
                       scenes ? "glTF scenes take camera_direction" : "the sphere uses the fit camera");
    if (opts->mesh != NULL) {
        mr_status mesh_status = mr_mesh_validate(opts->mesh);
        if (mesh_status != MR_OK)
            return mr_fail_context(mesh_status, "report mesh '%s'", opts->mesh_name ? opts->mesh_name : "(unnamed)");
    }
    memset(st, 0, sizeof *st);
    st->mesh = opts->mesh;
    st->mesh_name = opts->mesh_name ? opts->mesh_name : "a mesh";
    st->size = opts->size ? opts->size : MR_REPORT_DEFAULT_SIZE;
    st->views = opts->rotations ? opts->rotations : (has_env ? 4 : 1);
    st->env_samples = opts->env_samples ? opts->env_samples : MR_REPORT_DEFAULT_ENV_SAMPLES;
    st->reflection_samples = opts->reflection_samples == 0 ? MR_REPORT_DEFAULT_REFLECTION_SAMPLES
                             : opts->reflection_samples < 0 ? 0 : opts->reflection_samples;
    st->threads = opts->threads;
    st->env = opts->env;
    st->env_name = opts->env_path ? opts->env_path : "an environment map";
    st->env_scale = opts->env_scale;
    st->exposure = opts->exposure;
    st->has_camera_direction = opts->has_camera_direction;
    memcpy(st->camera_direction, d, sizeof st->camera_direction);
    st->title = opts->title ? opts->title : "matremap report";
    st->progress = opts->progress;
    st->progress_user = opts->progress_user;
    return MR_OK;
}

/* ---- the folder (report.h, "The folder") ----------------------------------------------------------------- */

/* 1 if `name` is a file mr_report_make writes: index.html, summary.json, view<V>_material<K>.png,
 * ssim_view<V>_material<K>.png, map_material<K>_<N>.png. */
static int is_report_file(const char *name) {
    if (strcmp(name, "index.html") == 0 || strcmp(name, "summary.json") == 0) return 1;
    static const char *const patterns[3] = {"view%d_material%d.png%n", "ssim_view%d_material%d.png%n",
                                            "map_material%d_%d.png%n"};
    for (int k = 0; k < 3; k++) {
        int a, b, end = -1;
        if (sscanf(name, patterns[k], &a, &b, &end) == 2 && end == (int)strlen(name)) return 1;
    }
    return 0;
}

/* What is at `dir`: *exists 0 (nothing) or 1 (a folder the report may replace: empty, or holding only files a
 * report writes). MR_ERR_IO when it is not a folder or cannot be listed; MR_ERR_INVALID_ARG naming the first entry
 * no report writes (a file of someone else's, a sub-folder): the report refuses to replace that folder. */
static mr_status check_target(const char *dir, int *exists) {
    struct stat st;
    *exists = 0;
    if (stat(dir, &st) != 0) {
        if (errno == ENOENT) return MR_OK;
        return mr_fail(MR_ERR_IO, "report folder '%s': %s", dir, strerror(errno));
    }
    if (!S_ISDIR(st.st_mode)) return mr_fail(MR_ERR_IO, "report folder '%s' exists and is not a folder", dir);
    DIR *d = opendir(dir);
    if (d == NULL) return mr_fail(MR_ERR_IO, "report folder '%s': cannot list it: %s", dir, strerror(errno));
    mr_status status = MR_OK;
    for (struct dirent *e; status == MR_OK && (e = readdir(d)) != NULL;) {
        if (strcmp(e->d_name, ".") == 0 || strcmp(e->d_name, "..") == 0) continue;
        char path[4096];
        snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
        if (!is_report_file(e->d_name) || lstat(path, &st) != 0 || !S_ISREG(st.st_mode))
            status = mr_fail(MR_ERR_INVALID_ARG,
                             "report folder '%s' holds '%s', which no report writes: refusing to "
                             "replace the folder (a report replaces its folder as a whole); choose another",
                             dir, e->d_name);
    }
    closedir(d);
    if (status == MR_OK) *exists = 1;
    return status;
}

/* Remove `path` and, if it is a folder, everything in it (symbolic links are removed, never followed). Best effort:
 * what cannot be removed stays. errno is kept. */
static void remove_tree(const char *path) {
    const int saved = errno;
    struct stat st;
    DIR *d = lstat(path, &st) == 0 && S_ISDIR(st.st_mode) ? opendir(path) : NULL;
    if (d != NULL) {
        for (struct dirent *e; (e = readdir(d)) != NULL;) {
            if (strcmp(e->d_name, ".") == 0 || strcmp(e->d_name, "..") == 0) continue;
            char inner[4096];
            int n = snprintf(inner, sizeof inner, "%s/%s", path, e->d_name);
            if (n > 0 && (size_t)n < sizeof inner) remove_tree(inner);
        }
        closedir(d);
        rmdir(path);
    } else {
        unlink(path);
    }
    errno = saved;
}

/* Where the last component of `dir` starts (*name) and ends (*length: trailing slashes left out, "out/" is "out").
 * MR_ERR_INVALID_ARG for a folder that cannot be renamed by its name: "/", ".", "..". */
static mr_status split_folder_name(const char *dir, size_t *name, size_t *length) {
    *length = strlen(dir);
    while (*length > 1 && dir[*length - 1] == '/') --*length;
    *name = *length;
    while (*name > 0 && dir[*name - 1] != '/') --*name;
    const size_t n = *length - *name;
    if (n == 0 || (dir[*name] == '.' && (n == 1 || (n == 2 && dir[*name + 1] == '.'))))
        return mr_fail(MR_ERR_INVALID_ARG, "report folder '%s': name the folder itself (not '/', '.' or '..')", dir);
    return MR_OK;
}

/* A new empty folder beside `dir`, hidden: "PARENT/.NAME.matremap-<what>-<pid>-<n>" in *out, the first n free
 * (mkdir is atomic, so reports made at once, by threads or processes, each get their own; the umask applies, as to
 * a folder made in place). */
static mr_status make_hidden_folder(const char *dir, const char *what, char *out, size_t size) {
    size_t name, length;
    mr_status status = split_folder_name(dir, &name, &length);
    if (status != MR_OK) return status;
    for (int k = 0; k < 10000; k++) {
        int n = snprintf(out, size, "%.*s.%.*s.matremap-%s-%ld-%d", (int)name, dir, (int)(length - name), dir + name,
                         what, (long)getpid(), k);
        if (n < 0 || (size_t)n >= size)
            return mr_fail(MR_ERR_INVALID_ARG, "report folder '%s': the name is too long", dir);
        if (mkdir(out, 0777) == 0) return MR_OK;
        if (errno != EEXIST) break;
    }
    return mr_fail(MR_ERR_IO, "cannot create the report folder '%s' (a scratch folder beside it, '%s': %s)", dir, out,
                   strerror(errno));
}

/* The failure's message with the scratch folder's name replaced by the target's (a picture is named as the user
 * knows it: "out/view0_material1.png"), and what became of the target said first. Returns status. */
static mr_status name_target(mr_status status, const char *dir, const char *scratch) {
    char message[2048], *at;
    snprintf(message, sizeof message, "%s", mr_last_error());
    const size_t from = strlen(scratch);
    size_t to = strlen(dir);
    while (to > 1 && dir[to - 1] == '/') to--; // "out/" is "out"
    while ((at = strstr(message, scratch)) != NULL && strlen(message) - from + to < sizeof message) {
        memmove(at + to, at + from, strlen(at + from) + 1);
        memcpy(at, dir, to);
    }
    return mr_fail(status, "report '%s' not written (a previous report there is left as it was): %s", dir, message);
}

/* Put the finished scratch folder in the place of `dir`: renamed there when nothing is; else the old report is
 * renamed aside, the new one in, and the old one removed (if the second rename fails, the old one goes back). */
static mr_status commit_folder(const char *dir, const char *scratch) {
    int exists = 0;
    mr_status status = check_target(dir, &exists); // again: it may have changed while the report was made
    if (status != MR_OK) return status;
    if (!exists) {
        if (rename(scratch, dir) != 0)
            return mr_fail(MR_ERR_IO, "cannot move the report into '%s': %s", dir, strerror(errno));
        return MR_OK;
    }
    char aside[4096];
    status = make_hidden_folder(dir, "old", aside, sizeof aside);
    if (status != MR_OK) return status;
    if (rename(dir, aside) != 0) { // over the empty folder just made
        status = mr_fail(MR_ERR_IO, "cannot move the previous report '%s' aside: %s", dir, strerror(errno));
        rmdir(aside);
        return status;
    }
    if (rename(scratch, dir) != 0) {
        status = mr_fail(MR_ERR_IO, "cannot move the report into '%s': %s", dir, strerror(errno));
        rename(aside, dir);
        return status;
    }
    remove_tree(aside);
    return MR_OK;
}

/* ---- descriptions ------------------------------------------------------------------------------------------- */

/* "MODEL name=v name=r,g,b name=@source ...": a material's values, and the maps that replace them. */
static void describe_material(const mr_material *m, char *out, size_t size) {
    size_t used = (size_t)snprintf(out, size, "%s", m->model->name);
    for (int p = 0; p < m->model->param_count && used < size; p++) {
        const mr_brdf_param *param = &m->model->params[p];
        const char *source = NULL;
        for (int k = 0; k < m->map_count; k++)
            if (m->maps[k].param == p && m->maps[k].image == m->textures.maps[p]) source = m->maps[k].source;
        if (source != NULL) {
            used += (size_t)snprintf(out + used, size - used, " %s=@%s", param->name, source);
            continue;
        }
        const double *v = m->values + mr_brdf_param_offset(m->model, p);
        used += (size_t)snprintf(out + used, size - used, " %s=%.6g", param->name, v[0]);
        for (int c = 1; c < param->channels && used < size; c++)
            used += (size_t)snprintf(out + used, size - used, ",%.6g", v[c]);
    }
}

/* "PATH: N triangles, M materials: name (model model), ...". */
static void describe_scene(const mr_gltf_scene *s, char *out, size_t size) {
    const int slots = s->material_count;
    size_t used = (size_t)snprintf(out, size, "%s: %d triangles, %d material%s:", s->path, s->mesh.triangle_count,
                                   slots, slots == 1 ? "" : "s");
    for (int m = 0; m < slots && used < size; m++)
        used += (size_t)snprintf(out + used, size - used, "%s %s (%s model)", m ? "," : "", s->materials[m].name,
                                 s->materials[m].brdf->model->name);
}

/* ---- renders ----------------------------------------------------------------------------------------------- */

static int same_image(const mr_image *a, const mr_image *b) {
    if (a == NULL || b == NULL) return a == b;
    return a->width == b->width && a->height == b->height && a->channels == b->channels &&
           memcmp(a->pixels, b->pixels, mr_image_value_count(a) * sizeof *a->pixels) == 0;
}

/* Do two meshes give the same render plan: the same triangles (every array equal, or absent in both), materials
 * of the triangles, and surfaces (the plan samples them)? */
static int same_mesh(const mr_mesh *a, const mr_mesh *b) {
    if (a->vertex_count != b->vertex_count || a->triangle_count != b->triangle_count ||
        a->material_count != b->material_count)
        return 0;
    size_t v = (size_t)a->vertex_count, t = (size_t)a->triangle_count;
    const struct {
        const void *x, *y;
        size_t bytes;
    } arrays[7] = {{a->positions, b->positions, v * 3 * sizeof(float)},
                   {a->normals, b->normals, v * 3 * sizeof(float)},
                   {a->tangents, b->tangents, v * 4 * sizeof(float)},
                   {a->uvs, b->uvs, v * 2 * sizeof(float)},
                   {a->uvs1, b->uvs1, v * 2 * sizeof(float)},
                   {a->indices, b->indices, t * 3 * sizeof(uint32_t)},
                   {a->triangle_materials, b->triangle_materials, t * sizeof(uint16_t)}};
    for (int i = 0; i < 7; i++) {
        if ((arrays[i].x == NULL) != (arrays[i].y == NULL)) return 0;
        if (arrays[i].x != NULL && memcmp(arrays[i].x, arrays[i].y, arrays[i].bytes) != 0) return 0;
    }
    for (int k = 0; k < a->material_count; k++) {
        const mr_surface *x = &a->surfaces[k], *y = &b->surfaces[k];
        if (x->double_sided != y->double_sided || x->normal_scale != y->normal_scale ||
            x->occlusion_strength != y->occlusion_strength ||
            memcmp(x->emission, y->emission, sizeof x->emission) != 0 ||
            memcmp(&x->normal_sampling, &y->normal_sampling, sizeof x->normal_sampling) != 0 ||
            memcmp(&x->occlusion_sampling, &y->occlusion_sampling, sizeof x->occlusion_sampling) != 0 ||
            memcmp(&x->emissive_sampling, &y->emissive_sampling, sizeof x->emissive_sampling) != 0 ||
            !same_image(x->normal_map, y->normal_map) || !same_image(x->occlusion_map, y->occlusion_map) ||
            !same_image(x->emissive_map, y->emissive_map))
            return 0;
    }
    return 1;
}

/* Compare candidate e's render `image` of view v with the reference's (whole frame, and over `mask`) on the
 * report's threads; write its SSIM map picture. */
static mr_status compare(const char *dir, int v, int k, const mr_image *reference, const mr_image *image,
                         const mr_image *mask, double exposure, int threads, entry *e) {
    mr_ssim_options so = {exposure, 0, NULL, threads};
    mr_image *map = NULL, *picture = NULL;
    double rmse = 0.0, reference_rms = rms(reference), object_rmse = 0.0, object_mean = 0.0;
    mr_status status = mr_ssim(reference, image, &so, &e->ssim[v], &map);
    if (status == MR_OK) status = mr_rmse_masked(reference, image, NULL, threads, &rmse, NULL);
    e->relative_rmse[v] = reference_rms > 0.0 ? rmse / reference_rms : rmse;
    // The same over the object: what a viewer looks at (metrics.h, masks).
    so.mask = mask;
    if (status == MR_OK) status = mr_ssim(reference, image, &so, &e->object_ssim[v], NULL);
    if (status == MR_OK) status = mr_rmse_masked(reference, image, mask, threads, &object_rmse, &object_mean);
    e->object_relative_rmse[v] = object_mean > 0.0 ? object_rmse / object_mean : object_rmse;
    if (status == MR_OK) status = mr_ssim_map_visualise(map, 0.0, &picture);
    snprintf(e->map_names[v], sizeof e->map_names[v], "ssim_view%d_material%d.png", v, k);
    e->ssim_maps[v] = e->map_names[v];
    if (status == MR_OK) status = write_picture(dir, e->map_names[v], picture, 1.0);
    mr_image_free(map);
    mr_image_free(picture);
    return status;
}

/* View v: one plan shared by the inputs (an input with geometry of its own gets its own), every input rendered,
 * written and compared with the reference. */
static mr_status render_view(const settings *st, const char *dir, const mr_report_input *inputs, int count, int v,
                             entry *entries, double *exposure) {
    const int scenes = inputs[0].scene != NULL;
    mr_fit_scene_options fit = {0};
    fit.size = st->size;
    mr_scene scene = mr_scene_fit(&fit);
    scene.threads = st->threads;
    if (st->env != NULL) {
        scene.lights[0] = mr_light_environment(st->env, st->env_scale, 360.0 * v / st->views, st->env_samples);
        scene.lights[0].reflection_samples = st->reflection_samples;
    }
    mr_status status = MR_OK;
    if (scenes) { // every scene's mesh seen by the camera that frames the reference's
        scene.shape.type = MR_SHAPE_MESH;
        scene.shape.mesh = &inputs[0].scene->mesh;
        // From camera_direction, or a three-quarter view onto its broadest side (a flat asset seen edge-on shows
        // nothing of its material).
        status = mr_gltf_scene_frame(inputs[0].scene, st->has_camera_direction ? st->camera_direction : NULL, 0, 0,
                                     &scene.camera);
    } else if (st->mesh != NULL) { // every material on the one mesh, one plan for all
        scene.shape.type = MR_SHAPE_MESH;
        scene.shape.mesh = st->mesh;
        scene.camera = st->camera;
    }
    mr_render_plan *plan = NULL;
    mr_image *reference = NULL, *reference_mask = NULL; // the reference's render and coverage
    if (status == MR_OK) status = mr_render_plan_create(&scene, &plan);
    if (status == MR_OK) status = mr_render_plan_coverage_mask(plan, &reference_mask);
    int plan_entry = 0; // the input whose mesh the plan holds
    for (int k = 0; k < count && status == MR_OK; k++) {
        mr_image *image = NULL;
        if (scenes && k > 0 && !same_mesh(&inputs[k].scene->mesh, &inputs[plan_entry].scene->mesh)) {
            // A scene with geometry of its own gets its own plan; a conversion of the reference (the same
            // triangles and surfaces) shares the reference's, shadow rays included.
            mr_render_plan_free(plan);
            plan = NULL;
            scene.shape.mesh = &inputs[k].scene->mesh;
            plan_entry = k;
            status = mr_render_plan_create(&scene, &plan);
            if (status != MR_OK) break;
        }
        entry *e = &entries[k];
        double started = mr_now_seconds();
        if (scenes) {
            const mr_gltf_scene *s = inputs[k].scene;
            status = mr_render_materials(plan, s->bindings, s->material_count, MR_COMPONENT_FULL, &image);
        } else if (!mr_renderer_is_builtin(inputs[k].renderer)) {
            const mr_material *m = inputs[k].material;
            status = mr_image_create(scene.width, scene.height, 3, &image);
            if (status == MR_OK && m != NULL)
                status = mr_renderer_render(inputs[k].renderer, plan, m->model, m->values, image, NULL, NULL);
            else if (status == MR_OK)
                status = mr_renderer_render_external(inputs[k].renderer, plan, inputs[k].external, image, NULL, NULL);
        } else {
            const mr_material *m = inputs[k].material;
            status = mr_render_textured(plan, m->model, m->values, &m->textures, MR_COMPONENT_FULL, &image);
        }
        e->seconds += mr_now_seconds() - started;
        if (status != MR_OK) break;
        if (k == 0 && v == 0 && *exposure <= 0.0) *exposure = auto_exposure(plan, image);
        snprintf(e->render_names[v], sizeof e->render_names[v], "view%d_material%d.png", v, k);
        e->renders[v] = e->render_names[v];
        status = write_picture(dir, e->render_names[v], image, *exposure);
        if (status == MR_OK && k > 0) {
            mr_image *mask = NULL;
            status = comparison_mask(reference_mask, plan, plan_entry != 0, &mask);
            if (status == MR_OK) status = compare(dir, v, k, reference, image, mask, *exposure, st->threads, e);
            mr_image_free(mask);
        }
        if (k == 0)
            reference = image;
        else
            mr_image_free(image);
    }
    mr_image_free(reference);
    mr_image_free(reference_mask);
    mr_render_plan_free(plan);
    return status;
}

/* ---- thumbnails and the page ------------------------------------------------------------------------------ */

/* Thumbnails of every map of input k: each material's BRDF maps, then (scenes) its normal, occlusion and
 * emissive maps; at most MR_REPORT_MAX_THUMBNAILS per material. */
static mr_status write_thumbnails(const char *dir, const mr_report_input *in, int k, entry *e) {
    const mr_gltf_scene *s = in->scene;
    const int slots = s != NULL ? s->material_count : in->material != NULL ? 1 : 0; // a renderer's own: none
    e->thumb_count = 0;
    for (int slot = 0; slot < slots; slot++) {
        const mr_material *m = s != NULL ? s->materials[slot].brdf : in->material;
        char prefix[140] = "";
        if (slots > 1) snprintf(prefix, sizeof prefix, "%s: ", s->materials[slot].name);
        for (int t = 0; t < m->map_count + 3; t++) {
            const mr_image *im;
            int channel = 0, rgb, colour;
            char what[300];
            if (t < m->map_count) {
                const mr_brdf_param *param = &m->model->params[m->maps[t].param];
                im = m->maps[t].image;
                channel = m->maps[t].channel;
                rgb = param->channels == 3;
                colour = rgb && mr_brdf_param_map_encoding(param, MR_MAP_AS_PARAMETER) == MR_IMG_COLOR;
                if (rgb || im->channels == 1) // a one-channel map (a folded glTF map) says its source itself
                    snprintf(what, sizeof what, "%s (%s)", param->name, m->maps[t].source);
                else
                    snprintf(what, sizeof what, "%s (%s, channel %c)", param->name, m->maps[t].source,
                             "RGBA"[channel]);
            } else {
                static const char *const surface_names[3] = {"normal map", "occlusion (channel R)", "emissive map"};
                const int which = t - m->map_count;
                if (s == NULL) continue;
                const mr_gltf_scene_material *sm = &s->materials[slot];
                im = which == 0 ? sm->normal_map : which == 1 ? sm->occlusion_map : sm->emissive_map;
                if (im == NULL) continue;
                rgb = which != 1;
                colour = which == 2;
                snprintf(what, sizeof what, "%s", surface_names[which]);
            }
            if (e->thumb_count == MR_REPORT_MAX_THUMBNAILS) break;
            const int n = e->thumb_count++;
            snprintf(e->thumb_names[n], sizeof e->thumb_names[n], "map_material%d_%d.png", k, n);
            snprintf(e->thumb_labels[n], sizeof e->thumb_labels[n], "%s%s", prefix, what);
            e->thumbs[n] = e->thumb_names[n];
            e->thumb_label_ptrs[n] = e->thumb_labels[n];
            mr_status status = write_thumbnail(dir, e->thumb_names[n], im, channel, rgb, colour);
            if (status != MR_OK) return status;
        }
    }
    return MR_OK;
}

/* index.html and summary.json. */
static mr_status write_page(const settings *st, const char *dir, int scenes, const entry *entries, int count,
                            double exposure) {
    char view_names[MR_REPORT_MAX_VIEWS][64];
    const char *view_ptrs[MR_REPORT_MAX_VIEWS];
    for (int v = 0; v < st->views; v++) {
        if (st->env != NULL)
            snprintf(view_names[v], sizeof view_names[v], "rotation %g°", 360.0 * v / st->views);
        else
            snprintf(view_names[v], sizeof view_names[v], "fit scene");
        view_ptrs[v] = view_names[v];
    }
    mr_report_material *materials = calloc((size_t)count, sizeof *materials);
    if (materials == NULL) return mr_fail(MR_ERR_NOMEM, "report: out of memory");
    for (int k = 0; k < count; k++) {
        const entry *e = &entries[k];
        materials[k] = (mr_report_material){e->label, e->description, e->seconds, e->renders,
                                            k ? e->ssim_maps : NULL, k ? e->ssim : NULL,
                                            k ? e->relative_rmse : NULL, e->thumb_count, e->thumbs,
                                            e->thumb_label_ptrs, k ? e->object_ssim : NULL,
                                            k ? e->object_relative_rmse : NULL};
    }
    char scene[1024], mesh[512];
    snprintf(mesh, sizeof mesh, "Mesh %s (%d triangles)", st->mesh_name, st->mesh ? st->mesh->triangle_count : 0);
    const char *object = scenes ? "Each asset's triangles, framed as the reference's" : st->mesh ? mesh : "Unit sphere";
    if (st->env != NULL)
        snprintf(scene, sizeof scene, "%s, %d² pixels, lit by %s (radiance x %.4g, %d fixed directions and %d "
                 "about each pixel's mirror direction), turned in %d steps of %g°; pictures at exposure %.4g.",
                 object, st->size, st->env_name, st->env_scale, st->env_samples, st->reflection_samples, st->views,
                 360.0 / st->views, exposure);
    else
        snprintf(scene, sizeof scene, "The fit scene's point light at 45°: %s, %d² pixels; pictures at exposure "
                 "%.4g.", object, st->size, exposure);
    mr_report report = {st->title, scene, st->views, view_ptrs, count, materials, "render time (all views)"};
    mr_status status = mr_report_write(&report, dir);
    free(materials);
    return status;
}

/* ---- the call ---------------------------------------------------------------------------------------------- */

void mr_report_result_free(mr_report_result *r) {
    if (r == NULL) return;
    for (int k = 0; r->materials != NULL && k < r->material_count; k++) {
        free(r->materials[k].label);
        free(r->materials[k].ssim); // one block holds the four arrays (make_result)
    }
    free(r->materials);
    free(r);
}

/* The figures of every entry, with the means over the views (the reference: 1 and 0). */
static mr_status make_result(const settings *st, const entry *entries, int count, double exposure,
                             mr_report_result **out) {
    const int views = st->views;
    mr_report_result *r = calloc(1, sizeof *r);
    if (r == NULL || (r->materials = calloc((size_t)count, sizeof *r->materials)) == NULL) {
        free(r);
        return mr_fail(MR_ERR_NOMEM, "report: out of memory for the figures");
    }
    r->view_count = views;
    r->exposure = exposure;
    r->env_scale = st->env != NULL ? st->env_scale : 0.0;
    r->material_count = count;
    for (int k = 0; k < count; k++) {
        const entry *e = &entries[k];
        mr_report_figures *f = &r->materials[k];
        double *block = malloc(4 * (size_t)views * sizeof *block);
        f->label = strdup(e->label);
        if (block == NULL || f->label == NULL) {
            free(block);
            mr_report_result_free(r);
            return mr_fail(MR_ERR_NOMEM, "report: out of memory for the figures");
        }
        f->ssim = block;
        f->relative_rmse = block + views;
        f->object_ssim = block + 2 * views;
        f->object_relative_rmse = block + 3 * views;
        f->seconds = e->seconds;
        double sums[4] = {0.0, 0.0, 0.0, 0.0};
        for (int v = 0; v < views; v++) {
            f->ssim[v] = k ? e->ssim[v] : 1.0;
            f->relative_rmse[v] = k ? e->relative_rmse[v] : 0.0;
            f->object_ssim[v] = k ? e->object_ssim[v] : 1.0;
            f->object_relative_rmse[v] = k ? e->object_relative_rmse[v] : 0.0;
            sums[0] += f->ssim[v];
            sums[1] += f->relative_rmse[v];
            sums[2] += f->object_ssim[v];
            sums[3] += f->object_relative_rmse[v];
        }
        f->mean_ssim = sums[0] / views;
        f->mean_relative_rmse = sums[1] / views;
        f->mean_object_ssim = sums[2] / views;
        f->mean_object_relative_rmse = sums[3] / views;
    }
    *out = r;
    return MR_OK;
}

/* Tell the progress callback; MR_ERR_CANCELLED if it asks to stop. */
static mr_status progress(const settings *st, int done) {
    if (st->progress != NULL && st->progress(st->progress_user, done, st->views, "view") != 0)
        return mr_fail(MR_ERR_CANCELLED, "report: stopped by the progress callback after %d of %d views", done,
                       st->views);
    return MR_OK;
}

mr_status mr_report_make(const mr_report_input *inputs, int count, const char *dir, const mr_report_options *opts,
                         mr_report_result **out) {
    if (out != NULL) *out = NULL;
    if (dir == NULL) return mr_fail(MR_ERR_INVALID_ARG, "report: NULL folder");
    const mr_report_options defaults = {0};
    if (opts == NULL) opts = &defaults;
    int scenes = 0;
    settings st = {0};
    mr_status status = check_inputs(inputs, count, &scenes);
    if (status == MR_OK) status = resolve_options(opts, scenes, &st);
    for (int k = 0; status == MR_OK && k < count; k++)
        if (!mr_renderer_is_builtin(inputs[k].renderer) && (opts->env != NULL || opts->env_path != NULL || st.mesh))
            status = mr_fail(MR_ERR_UNSUPPORTED, "report input %d: renderer '%s' renders the fit scene (its point "
                             "light and sphere), not an environment map or a mesh", k,
                             mr_renderer_name(inputs[k].renderer));
    if (status != MR_OK) return status;
    mr_image *env = NULL; // read here when only its path is given
    if (st.env == NULL && opts->env_path != NULL) {
        status = mr_img_read(opts->env_path, NULL, &env);
        char label[4096 + 32];
        snprintf(label, sizeof label, "environment map '%s'", opts->env_path);
        if (status == MR_OK) status = mr_image_check_radiance(env, label); // named here, before any render
        st.env = env;
    }
    if (status == MR_OK && st.env != NULL && st.env_scale <= 0.0) st.env_scale = auto_env_scale(st.env);
    if (status == MR_OK && st.mesh != NULL) { // the camera: given, or the mesh framed from +z
        mr_frame_options frame = {0};
        if (opts->camera != NULL)
            st.camera = *opts->camera;
        else
            status = mr_camera_frame_mesh(st.mesh, &frame, &st.camera);
    }
    entry *entries = NULL;
    if (status == MR_OK && (entries = calloc((size_t)count, sizeof *entries)) == NULL)
        status = mr_fail(MR_ERR_NOMEM, "report: out of memory for %d inputs", count);
    for (int k = 0; status == MR_OK && k < count; k++) {
        const mr_report_input *in = &inputs[k];
        entry *e = &entries[k];
        e->label = in->label      ? in->label
                   : in->scene    ? in->scene->path
                   : in->material ? in->material->model->name
                                  : mr_external_material_reference(in->external);
        if (in->description != NULL)
            snprintf(e->description, sizeof e->description, "%s", in->description);
        else if (in->external != NULL)
            snprintf(e->description, sizeof e->description, "%s rendered by %s",
                     mr_external_material_reference(in->external), mr_renderer_name(in->renderer));
        else if (in->scene != NULL)
            describe_scene(in->scene, e->description, sizeof e->description);
        else
            describe_material(in->material, e->description, sizeof e->description);
    }
    // Everything is written into a scratch folder beside `dir`, put in its place once complete.
    char scratch[4096] = "";
    int exists = 0;
    size_t name_at, name_end;
    if (status == MR_OK) status = split_folder_name(dir, &name_at, &name_end);
    if (status == MR_OK) status = check_target(dir, &exists);
    if (status == MR_OK) status = make_hidden_folder(dir, "new", scratch, sizeof scratch);
    const int made = status == MR_OK;
    double exposure = st.exposure;
    for (int v = 0; v < st.views && status == MR_OK; v++) {
        status = progress(&st, v);
        if (status == MR_OK) status = render_view(&st, scratch, inputs, count, v, entries, &exposure);
    }
    if (status == MR_OK) status = progress(&st, st.views);
    for (int k = 0; k < count && status == MR_OK; k++) status = write_thumbnails(scratch, &inputs[k], k, &entries[k]);
    if (status == MR_OK) status = write_page(&st, scratch, scenes, entries, count, exposure);
    if (status == MR_OK && out != NULL) status = make_result(&st, entries, count, exposure, out);
    if (status == MR_OK) status = commit_folder(dir, scratch);
    if (made && status != MR_OK) {
        remove_tree(scratch); // the previous report, if any, is as it was
        status = name_target(status, dir, scratch);
    }
    if (status != MR_OK && out != NULL) {
        mr_report_result_free(*out);
        *out = NULL;
    }
    free(entries);
    mr_image_free(env);
    return status;
}
