/*
 * test_obj.c — Wavefront OBJ meshes (src/io/obj_load.h): the paper's material-test sphere read whole (its counts,
 * box, unit normals, UVs in range; load time printed), small hand-written files with known answers (a quad
 * without normals triangulated and given computed ones, polygons, relative indices, the v flip, normals shared
 * across a UV seam, triangles turned to face their normals), malformed files rejected with the file and line, and
 * the sphere rendered under the Tabac Plant probe with a textured Ward material (finite, lit object pixels; the
 * probe's rotation changes the image). Assets come from ../shared/assets (MR_SHARED overrides ../shared).
 */
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <time.h>

#include "harness.h"
#include "matremap.h"

#define MATSPHERE "paper/matsphere.obj"
#define TABAC "hdri/tabac_plant_vogl.hdr"

/* Write `text` to a scratch file called `name`; its path. */
static const char *obj_file(const char *name, const char *text) {
    const char *path = mr_test_tmp_path(name);
    MR_CHECK_MSG(mr_test_write_file(path, text, strlen(text)), "cannot write %s", path);
    return path;
}

/* mr_obj_load, checked; NULL after a failed check. */
static mr_obj_mesh *load(const char *path, const mr_obj_options *opts) {
    mr_obj_mesh *obj = NULL;
    MR_CHECK_OK(mr_obj_load(path, opts, &obj));
    return obj;
}

static double now_ms(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return 1e3 * (double)t.tv_sec + 1e-6 * (double)t.tv_nsec;
}

static void vertex(const mr_mesh *m, int v, double p[3]) {
    for (int i = 0; i < 3; i++) p[i] = m->positions[3 * v + i];
}

/* Twice the area vector of triangle f (its winding's normal times twice its area). */
static void area_vector(const mr_mesh *m, int f, double out[3]) {
    double a[3], b[3], c[3];
    vertex(m, (int)m->indices[3 * f], a);
    vertex(m, (int)m->indices[3 * f + 1], b);
    vertex(m, (int)m->indices[3 * f + 2], c);
    double u[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, v[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    out[0] = u[1] * v[2] - u[2] * v[1];
    out[1] = u[2] * v[0] - u[0] * v[2];
    out[2] = u[0] * v[1] - u[1] * v[0];
}

/* The load fails with `status` and a message holding every one of the NULL-terminated strings. */
static void expect_failure(const char *path, mr_status status, const char *const *needles) {
    static mr_obj_mesh sentinel;
    mr_obj_mesh *obj = &sentinel; /* untouched on failure */
    mr_status got = mr_obj_load(path, NULL, &obj);
    MR_CHECK_MSG(got == status, "%s: status %s, expected %s (%s)", path, mr_status_str(got), mr_status_str(status),
                 mr_last_error());
    MR_CHECK(got == MR_OK || obj == &sentinel);
    for (const char *const *n = needles; *n != NULL; n++)
        MR_CHECK_MSG(strstr(mr_last_error(), *n) != NULL, "'%s' not in: %s", *n, mr_last_error());
    if (got == MR_OK) mr_obj_mesh_free(obj);
}

MR_TEST(matsphere_reads_whole) {
    const char *path = mr_test_asset_path(MATSPHERE);
    mr_obj_mesh *obj = NULL;
    double best = 1e30;
    for (int k = 0; k < 3; k++) {
        mr_obj_mesh_free(obj);
        obj = NULL;
        double t0 = now_ms();
        obj = load(path, NULL);
        best = fmin(best, now_ms() - t0);
        if (obj == NULL) return;
    }
    printf("      %s: %d vertices, %d triangles, read in %.1f ms (best of 3)\n", MATSPHERE, obj->mesh.vertex_count,
           obj->mesh.triangle_count, best);
    const mr_mesh *m = &obj->mesh;
    /* The file's header says 27875 vertices and 55742 faces; its faces use 29188 distinct (v, vt, vn) triples. */
    MR_CHECK(obj->position_records == 27875 && obj->normal_records == 27875 && obj->texcoord_records == 29188);
    MR_CHECK(m->triangle_count == 55742);
    MR_CHECK(m->vertex_count == 29188);
    MR_CHECK(obj->shape_count == 1);
    MR_CHECK(obj->computed_normals == 0 && obj->turned_triangles == 0);
    MR_CHECK(strcmp(obj->warnings, "") == 0);
    MR_CHECK(strcmp(obj->path, path) == 0);
    MR_CHECK(m->has_transform == 0 && m->double_sided == 0 && m->tangents == NULL && m->uvs1 == NULL);
    MR_CHECK_OK(mr_mesh_validate(m));
    /* the box, as awk finds it over the file's v records: x and z +-0.49703 and +-0.497175, y +-0.5 */
    const double lo[3] = {-0.49703, -0.5, -0.497175}, hi[3] = {0.49703, 0.5, 0.497175};
    for (int i = 0; i < 3; i++) {
        MR_CHECK_NEAR(obj->bbox_min[i], lo[i], 1e-6);
        MR_CHECK_NEAR(obj->bbox_max[i], hi[i], 1e-6);
    }
    /* normals unit (the file's are not: vn -1.208140 5.977536 -1.202746 has length 6.2), UVs inside the file's
     * range flipped: u in [0.009027, 0.997832], v' = 1 - v in [1 - 0.983030, 1 - 0.008817] */
    double worst = 0.0, umin = 1e9, umax = -1e9, vmin = 1e9, vmax = -1e9;
    for (int v = 0; v < m->vertex_count; v++) {
        const float *n = m->normals + 3 * v;
        worst = fmax(worst, fabs(sqrt((double)n[0] * n[0] + (double)n[1] * n[1] + (double)n[2] * n[2]) - 1.0));
        umin = fmin(umin, m->uvs[2 * v]), umax = fmax(umax, m->uvs[2 * v]);
        vmin = fmin(vmin, m->uvs[2 * v + 1]), vmax = fmax(vmax, m->uvs[2 * v + 1]);
    }
    MR_CHECK_MSG(worst < 1e-6, "normal length off by %g", worst);
    MR_CHECK_NEAR(umin, 0.009027, 1e-6);
    MR_CHECK_NEAR(umax, 0.997832, 1e-6);
    MR_CHECK_NEAR(vmin, 1.0 - 0.983030, 1e-6);
    MR_CHECK_NEAR(vmax, 1.0 - 0.008817, 1e-6);
    /* every triangle's winding agrees with its normals (none was turned): front faces out */
    int against = 0;
    for (int f = 0; f < m->triangle_count; f++) {
        double a[3], sum[3] = {0, 0, 0};
        area_vector(m, f, a);
        for (int k = 0; k < 3; k++)
            for (int i = 0; i < 3; i++) sum[i] += m->normals[3 * m->indices[3 * f + k] + i];
        against += a[0] * sum[0] + a[1] * sum[1] + a[2] * sum[2] < 0.0;
    }
    MR_CHECK(against == 0);
    mr_obj_mesh_free(obj);
}

MR_TEST(quad_without_normals_is_triangulated_and_given_normals) {
    const char *path = obj_file("quad.obj", "# a unit quad in z = 0, counter-clockwise seen from +z\n"
                                            "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n");
    mr_obj_mesh *obj = load(path, NULL);
    if (obj == NULL) return;
    const mr_mesh *m = &obj->mesh;
    MR_CHECK(m->vertex_count == 4 && m->triangle_count == 2);
    MR_CHECK(m->uvs == NULL && m->normals != NULL);
    MR_CHECK(obj->computed_normals == 4);
    double total = 0.0;
    for (int f = 0; f < 2; f++) {
        double a[3];
        area_vector(m, f, a);
        MR_CHECK(a[2] > 0.0 && a[0] == 0.0 && a[1] == 0.0); /* the winding kept: both face +z */
        total += 0.5 * a[2];
    }
    MR_CHECK_NEAR(total, 1.0, 1e-12);
    for (int v = 0; v < 4; v++) {
        MR_CHECK(m->normals[3 * v] == 0.0f && m->normals[3 * v + 1] == 0.0f && m->normals[3 * v + 2] == 1.0f);
        MR_CHECK(m->indices[0] < 4 && m->indices[5] < 4);
    }
    MR_CHECK_OK(mr_mesh_validate(m));
    mr_obj_mesh_free(obj);

    /* the file's normals ignored on request: a tilted vn gives way to the computed +z */
    path = obj_file("quad_vn.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvn 0 1 1\nf 1//1 2//1 3//1 4//1\n");
    mr_obj_options opts = {0};
    opts.ignore_normals = 1;
    opts.double_sided = 1;
    obj = load(path, &opts);
    if (obj == NULL) return;
    MR_CHECK(obj->mesh.normals[2] == 1.0f && obj->computed_normals == 4 && obj->mesh.double_sided == 1);
    mr_obj_mesh_free(obj);
    obj = load(path, NULL); /* kept otherwise, made unit */
    if (obj == NULL) return;
    MR_CHECK_NEAR(obj->mesh.normals[1], sqrt(0.5), 1e-7);
    MR_CHECK_NEAR(obj->mesh.normals[2], sqrt(0.5), 1e-7);
    MR_CHECK(obj->computed_normals == 0 && obj->mesh.vertex_count == 4);
    mr_obj_mesh_free(obj);
}

MR_TEST(polygons_relative_indices_and_groups) {
    /* a convex pentagon and a concave hexagon (an L), in two groups, the hexagon by relative indices */
    const char *path = obj_file("polygons.obj", "o pentagon\n"
                                                "v 0 0 0\nv 1 0 0\nv 1.3 1 0\nv 0.5 1.6 0\nv -0.3 1 0\n"
                                                "f 1 2 3 4 5\n"
                                                "g ell\n"
                                                "v 0 0 1\nv 2 0 1\nv 2 1 1\nv 1 1 1\nv 1 2 1\nv 0 2 1\n"
                                                "f -6 -5 -4 -3 -2 -1\n");
    mr_obj_mesh *obj = load(path, NULL);
    if (obj == NULL) return;
    const mr_mesh *m = &obj->mesh;
    MR_CHECK_MSG(m->triangle_count == 3 + 4, "%d triangles", m->triangle_count);
    MR_CHECK(m->vertex_count == 11);
    MR_CHECK(obj->shape_count == 2);
    double pentagon = 0.0, ell = 0.0;
    for (int f = 0; f < m->triangle_count; f++) {
        double a[3];
        area_vector(m, f, a);
        MR_CHECK(a[2] >= 0.0); /* counter-clockwise kept */
        double z = m->positions[3 * m->indices[3 * f] + 2];
        *(z == 0.0 ? &pentagon : &ell) += 0.5 * a[2];
    }
    /* shoelace areas: pentagon 1.78, the L 3 */
    MR_CHECK_NEAR(pentagon, 1.78, 1e-6);
    MR_CHECK_NEAR(ell, 3.0, 1e-6);
    mr_obj_mesh_free(obj);
}

MR_TEST(texture_v_is_flipped_unless_kept) {
    const char *path = obj_file("uv.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0.25 0 0.5\nvt 1 0.1\nvt 0 0.75\n"
                                          "f 1/1 2/2 3/3\n");
    mr_obj_mesh *obj = load(path, NULL);
    if (obj == NULL) return;
    const float expect[6] = {0.25f, 1.0f, 1.0f, 0.9f, 0.0f, 0.25f};
    for (int k = 0; k < 6; k++) MR_CHECK_NEAR(obj->mesh.uvs[k], expect[k], 1e-7);
    mr_obj_mesh_free(obj);
    mr_obj_options opts = {0};
    opts.keep_v = 1;
    obj = load(path, &opts);
    if (obj == NULL) return;
    MR_CHECK_NEAR(obj->mesh.uvs[1], 0.0, 0.0);
    MR_CHECK_NEAR(obj->mesh.uvs[3], 0.1, 1e-7);
    mr_obj_mesh_free(obj);
    /* a corner without vt beside ones with: (0, 0) */
    path = obj_file("uv_part.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0.5 0.5\nf 1/1 2/1 3/1\nf 2 4 3\n");
    obj = load(path, NULL);
    if (obj == NULL) return;
    MR_CHECK(obj->mesh.vertex_count == 4 + 2); /* 2 and 3 appear with and without vt */
    int zero = 0;
    for (int v = 0; v < obj->mesh.vertex_count; v++)
        zero += obj->mesh.uvs[2 * v] == 0.0f && obj->mesh.uvs[2 * v + 1] == 0.0f;
    MR_CHECK(zero == 3);
    mr_obj_mesh_free(obj);
}

MR_TEST(computed_normals_are_shared_across_uv_seams) {
    /* a roof: two unit squares meeting at the ridge x = 0, z = 1 (slopes of 45 degrees), the ridge's vertices with
     * different vt on each side; their computed normal is the average of both slopes, +z, on both sides */
    const char *path = obj_file("roof.obj", "v -1 0 0\nv 0 0 1\nv 0 1 1\nv -1 1 0\nv 1 0 0\nv 1 1 0\n"
                                            "vt 0 0\nvt 0.5 0\nvt 0.5 1\nvt 0 1\nvt 0.6 0\nvt 0.6 1\nvt 1 0\nvt 1 1\n"
                                            "f 1/1 2/2 3/3 4/4\nf 2/5 5/7 6/8 3/6\n");
    mr_obj_mesh *obj = load(path, NULL);
    if (obj == NULL) return;
    const mr_mesh *m = &obj->mesh;
    MR_CHECK(m->vertex_count == 8 && m->triangle_count == 4 && obj->computed_normals == 8);
    int ridge = 0;
    for (int v = 0; v < m->vertex_count; v++) {
        const float *p = m->positions + 3 * v, *n = m->normals + 3 * v;
        if (p[0] == 0.0f) {
            ridge++;
            MR_CHECK_MSG(fabs(n[0]) < 1e-6 && fabs(n[1]) < 1e-6 && fabs(n[2] - 1.0) < 1e-6, "ridge %g %g %g", n[0],
                         n[1], n[2]);
        } else {
            double s = p[0] < 0.0f ? -1.0 : 1.0; /* the eaves see one slope: (+-1, 0, 1)/sqrt 2 */
            MR_CHECK(fabs(n[0] - s * sqrt(0.5)) < 1e-6 && fabs(n[2] - sqrt(0.5)) < 1e-6);
        }
    }
    MR_CHECK(ridge == 4);
    mr_obj_mesh_free(obj);
}

MR_TEST(triangles_are_turned_to_face_their_normals) {
    /* two triangles with normals +z, the second wound clockwise seen from +z */
    const char *path = obj_file("turn.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvn 0 0 1\n"
                                            "f 1//1 2//1 3//1\nf 2//1 3//1 4//1\n");
    mr_obj_mesh *obj = load(path, NULL);
    if (obj == NULL) return;
    MR_CHECK(obj->turned_triangles == 1);
    for (int f = 0; f < 2; f++) {
        double a[3];
        area_vector(&obj->mesh, f, a);
        MR_CHECK(a[2] > 0.0);
    }
    mr_obj_mesh_free(obj);
}

MR_TEST(malformed_files_name_the_file_and_line) {
    const char *missing = mr_test_tmp_path("does_not_exist.obj");
    const char *n_missing[] = {"does_not_exist.obj", "cannot open", NULL};
    expect_failure(missing, MR_ERR_IO, n_missing);
    const char *n_dir[] = {"is a directory", NULL};
    expect_failure(mr_test_scratch_dir(), MR_ERR_IO, n_dir);

    static const struct {
        const char *name, *text, *line, *what;
    } cases[] = {
        {"beyond.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n\nf 1 2 3\nf 1 2 9\n", "line 6", "v index '9': out of range"},
        {"relative.obj", "v 0 0 0\nv 1 0 0\nf -3 -2 -1\nv 0 1 0\n", "line 3", "'-3': before the first v record"},
        {"zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", "line 4", "tinyobjloader"},
        {"two.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2\n", "line 5", "a face of 2 vertices"},
        {"vt.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/1 3/2\n", "line 5", "vt index '2': out of range"},
        {"vn.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\n# no vn\nf 1//1 2//1 3//1\n", "line 5", "vn index '1'"},
        {"quad_bad.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 4 7\n", "line 5", "v index '7'"},
        {"infinite.obj", "v 0 0 0\nv 1e999 0 0\nv 0 1 0\nf 1 2 3\n", "line 2", "v record 2 is not finite"},
        {"no_faces.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2\n", "no faces", "3 v records"},
        {"empty.obj", "", "no faces", "0 v records"},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; k++) {
        const char *path = obj_file(cases[k].name, cases[k].text);
        const char *needles[] = {cases[k].name, cases[k].line, cases[k].what, NULL};
        expect_failure(path, MR_ERR_FORMAT, needles);
        printf("      %s\n", mr_last_error());
    }
    MR_CHECK(mr_obj_load(NULL, NULL, NULL) == MR_ERR_INVALID_ARG);
    mr_obj_mesh_free(NULL);
}

/* ---- the paper's sphere rendered under the Tabac Plant probe ----------------------------------------------- */

/* A smooth w x h map of `channels` channels, values in [lo, hi], different in every channel. */
static mr_image *ramp_map(int w, int h, int channels, double lo, double hi) {
    mr_image *map = NULL;
    MR_CHECK_OK(mr_image_create(w, h, channels, &map));
    if (map == NULL) return NULL;
    for (int j = 0; j < h; j++)
        for (int i = 0; i < w; i++)
            for (int c = 0; c < channels; c++)
                mr_image_at(map, i, j)[c] =
                    (float)(lo + (hi - lo) * (0.5 + 0.5 * sin(6.0 * (i + 0.5) / w + 4.0 * (j + 0.5) / h + c)));
    return map;
}

MR_TEST(matsphere_renders_under_the_tabac_probe) {
    mr_obj_mesh *obj = NULL;
    mr_image *env = NULL;
    MR_CHECK_OK(mr_obj_load(mr_test_asset_path(MATSPHERE), NULL, &obj));
    MR_CHECK_OK(mr_img_read(mr_test_asset_path(TABAC), NULL, &env));
    const mr_brdf_model *ward = mr_brdf_find("ward");
    MR_CHECK(ward != NULL);
    if (obj == NULL || env == NULL || ward == NULL) {
        mr_obj_mesh_free(obj);
        mr_image_free(env);
        return;
    }
    /* a textured Ward: diffuse, specular and alpha from maps, trimming off */
    double values[MR_BRDF_MAX_VALUES];
    mr_brdf_default_values(ward, values);
    MR_CHECK_OK(mr_brdf_parse_assignment(ward, "trim=0", values));
    mr_image *diffuse = ramp_map(64, 32, 3, 0.1, 0.6), *specular = ramp_map(64, 32, 3, 0.05, 0.3);
    mr_image *alpha = ramp_map(64, 32, 1, 0.05, 0.4);
    mr_param_textures textures;
    memset(&textures, 0, sizeof textures);
    MR_CHECK_OK(mr_param_textures_set(&textures, ward, "diffuse", diffuse, 0));
    MR_CHECK_OK(mr_param_textures_set(&textures, ward, "specular", specular, 0));
    MR_CHECK_OK(mr_param_textures_set(&textures, ward, "alpha", alpha, 0));

    mr_image *image[2] = {NULL, NULL};
    const double rotation[2] = {0.0, 90.0};
    for (int r = 0; r < 2; r++) {
        mr_scene scene = mr_scene_fit(&(mr_fit_scene_options){64, MR_FIT_LIGHT_45, 0});
        scene.shape.type = MR_SHAPE_MESH;
        scene.shape.mesh = &obj->mesh;
        /* the paper's camera (brdf-reference 1) */
        scene.camera = (mr_camera){{0.0, 0.0, -1.5}, {0.0, 0.0, 0.0}, {0.0, 1.0, 0.0}, 40.0};
        scene.lights[0] = mr_light_environment(env, 5.0, rotation[r], 64);
        mr_render_plan *plan = NULL;
        double t0 = now_ms();
        MR_CHECK_OK(mr_render_plan_create(&scene, &plan));
        double t1 = now_ms();
        if (plan == NULL) continue;
        MR_CHECK_OK(mr_render_textured(plan, ward, values, &textures, MR_COMPONENT_FULL, &image[r]));
        double t2 = now_ms();
        const float *coverage = mr_render_plan_coverage(plan);
        int object = 0, lit = 0, nonfinite = 0;
        double sum = 0.0;
        for (int p = 0; image[r] != NULL && p < 64 * 64; p++) {
            const float *px = image[r]->pixels + 3 * p;
            for (int c = 0; c < 3; c++) nonfinite += !isfinite(px[c]);
            if (coverage[p] < 1.0f) continue;
            object++;
            lit += px[0] + px[1] + px[2] > 0.0f;
            sum += px[0] + px[1] + px[2];
        }
        MR_CHECK(nonfinite == 0);
        MR_CHECK_MSG(object > 2500, "%d object pixels", object); /* the sphere fills most of the frame */
        MR_CHECK_MSG(lit > 0.95 * object, "%d of %d object pixels lit", lit, object);
        MR_CHECK(mr_render_plan_self_occluding(plan) == 1 && mr_render_plan_shadow_ray_count(plan) > 0);
        printf("      rotation %g: %d object pixels, %d lit, mean %.4g; plan %.0f ms (%ld shadow rays), "
               "render %.1f ms\n",
               rotation[r], object, lit, sum / (3.0 * object), t1 - t0, mr_render_plan_shadow_ray_count(plan),
               t2 - t1);
        mr_render_plan_free(plan);
    }
    /* turning the probe by 90 degrees changes the picture: the object's mean relative difference */
    if (image[0] != NULL && image[1] != NULL) {
        double diff = 0.0, ref = 0.0;
        for (size_t i = 0; i < mr_image_value_count(image[0]); i++) {
            diff += fabs(image[0]->pixels[i] - image[1]->pixels[i]);
            ref += image[0]->pixels[i];
        }
        printf("      rotation 0 against 90: mean |difference| %.1f %% of the mean radiance\n", 100.0 * diff / ref);
        MR_CHECK_MSG(diff > 0.1 * ref, "difference %g of %g", diff, ref);
    }
    mr_image_free(image[0]);
    mr_image_free(image[1]);
    mr_image_free(diffuse);
    mr_image_free(specular);
    mr_image_free(alpha);
    mr_image_free(env);
    mr_obj_mesh_free(obj);
}

MR_TEST_MAIN(MR_TEST_ENTRY(matsphere_reads_whole),
             MR_TEST_ENTRY(quad_without_normals_is_triangulated_and_given_normals),
             MR_TEST_ENTRY(polygons_relative_indices_and_groups), MR_TEST_ENTRY(texture_v_is_flipped_unless_kept),
             MR_TEST_ENTRY(computed_normals_are_shared_across_uv_seams),
             MR_TEST_ENTRY(triangles_are_turned_to_face_their_normals),
             MR_TEST_ENTRY(malformed_files_name_the_file_and_line),
             MR_TEST_ENTRY(matsphere_renders_under_the_tabac_probe))
