/*
 * cmd_report.c — `matremap report -o DIR [options] REFERENCE [-- MATERIAL ...]`: renders materials on a sphere
 * under an HDR environment map from several directions (or in the fit scene), compares every material with the
 * first by SSIM and relative RMSE, and writes a report folder a person opens in a browser (src/report/report.h):
 * index.html, the renders, SSIM maps and parameter-map thumbnails as PNG, summary.json.
 *
 * A material is written as for `matremap render`: MODEL name=value ... name=@MAP[:c] ... (cli_material.c), with
 * an optional `--label TEXT` in its group. Steps: parse; load every material (maps read once); for each view,
 * one render plan shared by all materials; render, picture, compare; thumbnails; the page.
 */
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "cli.h"
#include "gltf/mr_gltf.h"
#include "report/report.h"

#define MAX_MATERIALS 16
#define MAX_VIEWS 36
#define MAX_ARGS 64
#define THUMBNAIL_SIDE 128

static void print_help(void) {
    printf("Usage: matremap report -o DIR [options] MODEL [name=value|name=@MAP ...]\n"
           "                       [-- [--label TEXT] MODEL [name=value|name=@MAP ...]] ...\n"
           "       matremap report -o DIR [options] A.gltf [-- [--label TEXT] B.gltf] ...\n"
           "\n"
           "Renders each material on a sphere under an HDR environment map, seen with the map turned to N\n"
           "directions (or once in the fit scene without --env), compares every material with the first (the\n"
           "reference) by SSIM and relative RMSE, and writes a report folder to open in a browser: index.html\n"
           "(renders side by side, SSIM maps, a summary table, each material's parameters and map thumbnails),\n"
           "the pictures as PNG, and summary.json with the numbers. Materials are separated by '--' and written\n"
           "as for 'matremap render': parameters as name=value, or name=@MAP[:r|g|b|a] from a texture wrapped\n"
           "over the sphere (docs/rendering.md). glTF assets (.gltf, .glb) are rendered as their triangles with\n"
           "their material (spec-gloss when the material carries it, else metal-rough with KHR_materials_specular\n"
           "and _ior), factors times textures, seen from a three-quarter view onto the reference's broadest side;\n"
           "single-material assets so far.\n"
           "\n"
           "Options:\n"
           "  -o, --output DIR     the report folder (created if missing; its files are replaced)\n"
           "  --env FILE           equirectangular HDR map (.hdr, .exr); without it, the fit scene's point light\n"
           "  --rotations N        views: the map turned by 360/N degrees each (default 4; 1 without --env)\n"
           "  --env-scale S        radiance scale (default: the map's mean luminance brought to 0.5)\n"
           "  --env-samples N      environment directions (default 1024, 1-%d)\n"
           "  --size N             render side in pixels (default 256)\n"
           "  --exposure E         display exposure of the pictures and of SSIM (default: the reference's\n"
           "                       object pixels in the first view to a mean luminance of 0.18)\n"
           "  --title TEXT         the page's title\n"
           "  --label TEXT         (inside a material's group) its name in the report (default: the model)\n"
           "  --help               this text\n"
           "\n"
           "Prints each material's mean SSIM and relative RMSE and the page's path.\n"
           "\n"
           "Example:\n"
           "  matremap report -o out/avocado --env studio.hdr \\\n"
           "      --label original gltf-specgloss diffuse=@d.png specular=@s.png glossiness=@g.png \\\n"
           "      -- --label weighted gltf base_color=@w_basecolor.png metallic=@w_mr.png:b roughness=@w_mr.png:g\n",
           MR_ENV_MAX_SAMPLES);
}

/* One material's group on the command line. */
typedef struct group {
    const char *label;
    const char *model_name;
    const char *assignments[MAX_ARGS];
    int count;
} group;

typedef struct options {
    const char *dir, *env_path, *title;
    int rotations, env_samples, size;
    double env_scale, exposure; /* 0: automatic */
} options;

/* Parse argv into options and groups. Returns an exit code. */
static int parse(int argc, char **argv, options *o, group *groups, int *group_count) {
    int n = 1;
    memset(&groups[0], 0, sizeof groups[0]);
    for (int i = 1; i < argc; i++) {
        const char *value = NULL;
        int taken;
        group *g = &groups[n - 1];
        if (strcmp(argv[i], "--") == 0) {
            if (g->model_name == NULL) return cli_usage_error("report", "'--' after a group without a MODEL");
            if (n == MAX_MATERIALS) return cli_usage_error("report", "more than %d materials", MAX_MATERIALS);
            memset(&groups[n++], 0, sizeof groups[0]);
            continue;
        }
        if ((taken = cli_take_option("report", argc, argv, &i, "--label", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            g->label = value;
        } else if ((taken = cli_take_option("report", argc, argv, &i, "--output", &value)) ||
                   (taken = cli_take_option("report", argc, argv, &i, "-o", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            o->dir = value;
        } else if ((taken = cli_take_option("report", argc, argv, &i, "--env", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            o->env_path = value;
        } else if ((taken = cli_take_option("report", argc, argv, &i, "--title", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            o->title = value;
        } else if ((taken = cli_take_option("report", argc, argv, &i, "--rotations", &value))) {
            if (taken < 0 || !cli_parse_int("report", "--rotations", value, 1, MAX_VIEWS, &o->rotations))
                return CLI_EXIT_USAGE;
        } else if ((taken = cli_take_option("report", argc, argv, &i, "--env-samples", &value))) {
            if (taken < 0 || !cli_parse_int("report", "--env-samples", value, 1, MR_ENV_MAX_SAMPLES, &o->env_samples))
                return CLI_EXIT_USAGE;
        } else if ((taken = cli_take_option("report", argc, argv, &i, "--size", &value))) {
            if (taken < 0 || !cli_parse_int("report", "--size", value, 16, MR_RENDER_MAX_SIZE, &o->size))
                return CLI_EXIT_USAGE;
        } else if ((taken = cli_take_option("report", argc, argv, &i, "--env-scale", &value))) {
            if (taken < 0 || !cli_parse_double("report", "--env-scale", value, 1e-12, 1e12, &o->env_scale))
                return CLI_EXIT_USAGE;
        } else if ((taken = cli_take_option("report", argc, argv, &i, "--exposure", &value))) {
            if (taken < 0 || !cli_parse_double("report", "--exposure", value, 1e-12, 1e12, &o->exposure))
                return CLI_EXIT_USAGE;
        } else if (argv[i][0] == '-') {
            return cli_usage_error("report", "unknown option '%s'", argv[i]);
        } else if (g->model_name == NULL) {
            g->model_name = argv[i];
        } else if (strchr(argv[i], '=') != NULL) {
            if (g->count == MAX_ARGS) return cli_usage_error("report", "too many parameters for %s", g->model_name);
            g->assignments[g->count++] = argv[i];
        } else {
            return cli_usage_error("report", "unexpected argument '%s' (parameters are name=value; materials are "
                                   "separated by --)", argv[i]);
        }
    }
    if (o->dir == NULL) return cli_usage_error("report", "missing -o DIR");
    if (groups[n - 1].model_name == NULL)
        return cli_usage_error("report", n == 1 ? "missing the reference MODEL" : "'--' without a MODEL after it");
    if (o->env_path == NULL && o->rotations > 1)
        return cli_usage_error("report", "--rotations %d needs --env FILE (the fit scene has one view)", o->rotations);
    if (o->env_path == NULL && (o->env_scale > 0.0 || o->env_samples > 0))
        return cli_usage_error("report", "--env-scale and --env-samples need --env FILE");
    *group_count = n;
    return CLI_EXIT_OK;
}

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
 * most THUMBNAIL_SIDE pixels on its longer side, written to dir/name. */
static mr_status write_thumbnail(const char *dir, const char *name, const cli_material_map *map, int rgb,
                                 int colour) {
    const mr_image *im = map->image;
    int longest = im->width > im->height ? im->width : im->height;
    int factor = (longest + THUMBNAIL_SIDE - 1) / THUMBNAIL_SIDE;
    int width = (im->width + factor - 1) / factor, height = (im->height + factor - 1) / factor;
    int channels = rgb ? 3 : 1;
    mr_image *thumb = NULL;
    mr_status status = mr_image_create(width, height, channels, &thumb);
    if (status != MR_OK) return status;
    for (int y = 0; y < height; y++)
        for (int x = 0; x < width; x++)
            for (int c = 0; c < channels; c++) {
                int source = im->channels == 1 ? 0 : (rgb ? c : map->channel);
                double sum = 0.0;
                int count = 0;
                for (int j = y * factor; j < (y + 1) * factor && j < im->height; j++)
                    for (int i = x * factor; i < (x + 1) * factor && i < im->width; i++, count++)
                        sum += mr_image_at(im, i, j)[source];
                mr_image_at(thumb, x, y)[c] = (float)(sum / count);
            }
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    mr_img_write_options wo = {0};
    wo.encoding = colour ? MR_IMG_COLOR : MR_IMG_DATA;
    status = mr_img_write(path, thumb, &wo);
    mr_image_free(thumb);
    return status;
}

/* The folder: created if missing; an existing non-folder is an error. Returns an exit code. */
static int make_folder(const char *dir) {
    struct stat st;
    if (stat(dir, &st) == 0) {
        if (S_ISDIR(st.st_mode)) return CLI_EXIT_OK;
        fprintf(stderr, "matremap report: error: -o '%s' exists and is not a folder\n", dir);
        return CLI_EXIT_BAD_INPUT;
    }
    if (mkdir(dir, 0777) != 0) {
        fprintf(stderr, "matremap report: error: cannot create the folder '%s': %s\n", dir, strerror(errno));
        return CLI_EXIT_BAD_INPUT;
    }
    return CLI_EXIT_OK;
}

/* What the report holds per material, beside cli_material. */
typedef struct entry {
    char label[256];
    char description[2048];
    char render_names[MAX_VIEWS][64], map_names[MAX_VIEWS][64];
    const char *renders[MAX_VIEWS], *ssim_maps[MAX_VIEWS];
    double ssim[MAX_VIEWS], relative_rmse[MAX_VIEWS];
    double seconds;
    char thumb_names[CLI_MAX_ASSIGNMENTS][64], thumb_labels[CLI_MAX_ASSIGNMENTS][512];
    const char *thumbs[CLI_MAX_ASSIGNMENTS], *thumb_label_ptrs[CLI_MAX_ASSIGNMENTS];
    int thumb_count;
} entry;

/* The text of a group: "MODEL a=b c=@d". */
static void describe(const group *g, char *out, size_t size) {
    size_t used = (size_t)snprintf(out, size, "%s", g->model_name);
    for (int k = 0; k < g->count && used < size; k++)
        used += (size_t)snprintf(out + used, size - used, " %s", g->assignments[k]);
}

/* ---- glTF assets as report entries ------------------------------------------------------------------------- */

/* The geometry of a glTF entry; materials[k] holds its BRDF model, values and (folded) maps. */
typedef struct asset_entry {
    mr_gltf *asset;
    mr_gltf_triangles *triangles;
    mr_mesh mesh;
} asset_entry;

static int is_gltf_path(const char *text) {
    size_t n = strlen(text);
    return (n > 5 && strcmp(text + n - 5, ".gltf") == 0) || (n > 4 && strcmp(text + n - 4, ".glb") == 0);
}

/* A map for parameter `name` of m's model: channels `first`.. of `source` (count 1 or 3; a grey source answers
 * every channel) times `factor[]`, as a new image the material owns. Returns an exit code. */
static int fold_map(cli_material *m, const char *name, const char *label, const mr_image *source, int first,
                    int count, const double *factor) {
    if (m->map_count == CLI_MAX_ASSIGNMENTS) return CLI_EXIT_INTERNAL;
    cli_material_map *map = &m->maps[m->map_count];
    memset(map, 0, sizeof *map);
    mr_status status = mr_image_create(source->width, source->height, count, &map->image);
    if (status != MR_OK) return cli_fail("report", status);
    m->map_count++;
    size_t n = (size_t)source->width * (size_t)source->height;
    for (size_t i = 0; i < n; i++)
        for (int c = 0; c < count; c++) {
            int from = source->channels == 1 ? 0 : first + c;
            float value = from < source->channels ? source->pixels[i * (size_t)source->channels + (size_t)from]
                                                  : 1.0f; // a missing alpha is 1
            map->image->pixels[i * (size_t)count + (size_t)c] = (float)(value * factor[c]);
        }
    map->name = strdup(name);
    map->path = strdup(label);
    map->param = mr_brdf_param_index(m->model, name);
    map->channel = 0;
    if (map->name == NULL || map->path == NULL) return CLI_EXIT_INTERNAL;
    status = mr_param_textures_set(&m->textures, m->model, name, map->image, 0);
    return status == MR_OK ? CLI_EXIT_OK : cli_fail("report", status);
}

/* Set parameter `name` of m to `count` values. */
static void set_values(cli_material *m, const char *name, const double *v, int count) {
    int p = mr_brdf_param_index(m->model, name);
    int offset = mr_brdf_param_offset(m->model, p);
    for (int c = 0; c < count; c++) m->values[offset + c] = v[c];
}

/* Load a glTF asset as a report entry: its triangles (one material group: single-material assets) as a mesh,
 * its material as `gltf-specgloss` when it carries KHR_materials_pbrSpecularGlossiness (what an engine that
 * supports the extension renders) and as `gltf` otherwise (core metal-rough, KHR_materials_specular factors and
 * colour texture, KHR_materials_ior; an ior above 5, the model's bound, is rendered at 5 with the specular colour
 * scaled to the same F0). Factors are folded into the maps. Returns an exit code. */
static int load_gltf_entry(const char *path, const char *scratch, asset_entry *a, cli_material *m) {
    memset(m, 0, sizeof *m);
    mr_status status = mr_gltf_load(path, &a->asset);
    if (status == MR_OK) status = mr_gltf_get_triangles(a->asset, -1, &a->triangles);
    if (status != MR_OK) return cli_fail("report", status);
    if (a->triangles->group_count != 1) {
        fprintf(stderr, "matremap report: error: '%s' has %d material groups (materials, or attribute sets); the "
                "report renders single-material assets so far\n", path, a->triangles->group_count);
        return CLI_EXIT_BAD_INPUT;
    }
    const mr_gltf_triangle_group *g = &a->triangles->groups[0];
    mr_gltf_material mat;
    if (g->material >= 0) {
        status = mr_gltf_get_material(a->asset, g->material, &mat);
        if (status != MR_OK) return cli_fail("report", status);
    } else {
        mr_gltf_material_defaults(&mat);
    }
    a->mesh = (mr_mesh){g->vertex_count, g->positions, g->normals, g->tangents, g->uv0, g->triangle_count,
                        g->indices, mat.double_sided, 0, {0}};
    int code = CLI_EXIT_OK;
    mr_image *image = NULL;
    if (mat.has_spec_gloss) {
        m->model = mr_brdf_find("gltf-specgloss");
        mr_brdf_default_values(m->model, m->values);
        set_values(m, "diffuse", mat.diffuse_factor, 3);
        set_values(m, "specular", mat.specular_factor, 3);
        set_values(m, "glossiness", &mat.glossiness_factor, 1);
        if (mat.diffuse_texture.index >= 0) {
            code = cli_gltf_read_texture(a->asset, &mat.diffuse_texture, MR_IMG_COLOR, scratch, &image);
            if (code == CLI_EXIT_OK) code = fold_map(m, "diffuse", "diffuseTexture", image, 0, 3, mat.diffuse_factor);
            mr_image_free(image);
            image = NULL;
        }
        if (code == CLI_EXIT_OK && mat.specular_glossiness_texture.index >= 0) {
            code = cli_gltf_read_texture(a->asset, &mat.specular_glossiness_texture, MR_IMG_COLOR, scratch, &image);
            if (code == CLI_EXIT_OK)
                code = fold_map(m, "specular", "specularGlossinessTexture RGB", image, 0, 3, mat.specular_factor);
            if (code == CLI_EXIT_OK)
                code = fold_map(m, "glossiness", "specularGlossinessTexture A", image, 3, 1, &mat.glossiness_factor);
            mr_image_free(image);
        }
        return code;
    }
    m->model = mr_brdf_find("gltf");
    mr_brdf_default_values(m->model, m->values);
    double ior = mat.has_ior ? mat.ior : 1.5, rendered_ior = ior > 5.0 ? 5.0 : (ior < 1.0 ? 1.0 : ior);
    double f0 = pow((ior - 1.0) / (ior + 1.0), 2.0);
    double rendered_f0 = pow((rendered_ior - 1.0) / (rendered_ior + 1.0), 2.0);
    double scale = rendered_f0 > 0.0 ? f0 / rendered_f0 : 1.0;
    double colour[3];
    for (int c = 0; c < 3; c++) colour[c] = (mat.has_specular ? mat.specular_color_factor[c] : 1.0) * scale;
    double strength = mat.has_specular ? mat.specular_strength : 1.0;
    set_values(m, "base_color", mat.base_color_factor, 3);
    set_values(m, "metallic", &mat.metallic_factor, 1);
    set_values(m, "roughness", &mat.roughness_factor, 1);
    set_values(m, "specular", &strength, 1);
    set_values(m, "specular_color", colour, 3);
    set_values(m, "ior", &rendered_ior, 1);
    if (mat.base_color_texture.index >= 0) {
        code = cli_gltf_read_texture(a->asset, &mat.base_color_texture, MR_IMG_COLOR, scratch, &image);
        if (code == CLI_EXIT_OK)
            code = fold_map(m, "base_color", "baseColorTexture", image, 0, 3, mat.base_color_factor);
        mr_image_free(image);
        image = NULL;
    }
    if (code == CLI_EXIT_OK && mat.metallic_roughness_texture.index >= 0) {
        code = cli_gltf_read_texture(a->asset, &mat.metallic_roughness_texture, MR_IMG_DATA, scratch, &image);
        if (code == CLI_EXIT_OK)
            code = fold_map(m, "metallic", "metallicRoughnessTexture B", image, 2, 1, &mat.metallic_factor);
        if (code == CLI_EXIT_OK)
            code = fold_map(m, "roughness", "metallicRoughnessTexture G", image, 1, 1, &mat.roughness_factor);
        mr_image_free(image);
        image = NULL;
    }
    if (code == CLI_EXIT_OK && mat.has_specular && mat.specular_color_texture.index >= 0) {
        code = cli_gltf_read_texture(a->asset, &mat.specular_color_texture, MR_IMG_COLOR, scratch, &image);
        if (code == CLI_EXIT_OK)
            code = fold_map(m, "specular_color", "specularColorTexture", image, 0, 3, colour);
        mr_image_free(image);
    }
    return code;
}

/* Do two meshes hold the same triangles (every array equal, or absent in both)? */
static int same_mesh(const mr_mesh *a, const mr_mesh *b) {
    if (a->vertex_count != b->vertex_count || a->triangle_count != b->triangle_count ||
        a->double_sided != b->double_sided)
        return 0;
    size_t v = (size_t)a->vertex_count, t = (size_t)a->triangle_count;
    const struct {
        const void *x, *y;
        size_t bytes;
    } arrays[5] = {{a->positions, b->positions, v * 3 * sizeof(float)},
                   {a->normals, b->normals, v * 3 * sizeof(float)},
                   {a->tangents, b->tangents, v * 4 * sizeof(float)},
                   {a->uvs, b->uvs, v * 2 * sizeof(float)},
                   {a->indices, b->indices, t * 3 * sizeof(uint32_t)}};
    for (int i = 0; i < 5; i++) {
        if ((arrays[i].x == NULL) != (arrays[i].y == NULL)) return 0;
        if (arrays[i].x != NULL && memcmp(arrays[i].x, arrays[i].y, arrays[i].bytes) != 0) return 0;
    }
    return 1;
}

static void asset_entry_free(asset_entry *a) {
    mr_gltf_triangles_free(a->triangles);
    mr_gltf_free(a->asset);
    memset(a, 0, sizeof *a);
}

/* Render every material for every view, write the pictures and compare. Returns an exit code. */
static int render_views(const options *o, const mr_image *env, double env_scale, cli_material *materials,
                        const asset_entry *assets, entry *entries, int count, int views, double *exposure) {
    for (int v = 0; v < views; v++) {
        if (isatty(STDERR_FILENO)) fprintf(stderr, "\rmatremap report: view %d/%d ", v + 1, views);
        mr_fit_scene_options fit = {0};
        fit.size = o->size;
        mr_scene scene = mr_scene_fit(&fit);
        if (env != NULL)
            scene.lights[0] = mr_light_environment(env, env_scale, 360.0 * v / views, o->env_samples);
        mr_status status = MR_OK;
        if (assets != NULL) { // every entry's mesh seen by the camera that frames the reference's
            scene.shape.type = MR_SHAPE_MESH;
            scene.shape.mesh = &assets[0].mesh;
            // A three-quarter view onto the asset's broadest side: along the axis of its smallest extent, raised
            // and turned a little (a flat asset seen edge-on shows nothing of its material).
            const double *lo = assets[0].triangles->bbox_min, *hi = assets[0].triangles->bbox_max;
            int thin = 0;
            for (int c = 1; c < 3; c++)
                if (hi[c] - lo[c] < hi[thin] - lo[thin]) thin = c;
            mr_frame_options frame = {0};
            for (int c = 0; c < 3; c++) frame.from[c] = c == thin ? 1.0 : 0.35;
            status = mr_camera_frame_mesh(&assets[0].mesh, &frame, &scene.camera);
        }
        mr_render_plan *plan = NULL;
        if (status == MR_OK) status = mr_render_plan_create(&scene, &plan);
        mr_image *reference = NULL;
        for (int k = 0; k < count && status == MR_OK; k++) {
            mr_image *image = NULL;
            if (assets != NULL && k > 0 && !same_mesh(&assets[k].mesh, scene.shape.mesh)) {
                // An asset with geometry of its own gets its own plan; a conversion of the reference (the same
                // triangles) shares the reference's, shadow rays included.
                mr_render_plan_free(plan);
                plan = NULL;
                scene.shape.mesh = &assets[k].mesh;
                status = mr_render_plan_create(&scene, &plan);
                if (status != MR_OK) break;
            }
            double started = cli_now();
            status = mr_render_textured(plan, materials[k].model, materials[k].values, &materials[k].textures,
                                        MR_COMPONENT_FULL, &image);
            entries[k].seconds += cli_now() - started;
            if (status != MR_OK) break;
            if (k == 0 && v == 0 && *exposure <= 0.0) *exposure = auto_exposure(plan, image);
            snprintf(entries[k].render_names[v], sizeof entries[k].render_names[v], "view%d_material%d.png", v, k);
            entries[k].renders[v] = entries[k].render_names[v];
            status = write_picture(o->dir, entries[k].render_names[v], image, *exposure);
            if (status == MR_OK && k > 0) {
                mr_ssim_options so = {*exposure, 0};
                mr_image *map = NULL, *picture = NULL;
                double rmse = 0.0, reference_rms = rms(reference);
                status = mr_ssim(reference, image, &so, &entries[k].ssim[v], &map);
                if (status == MR_OK) status = mr_rmse(reference, image, &rmse);
                entries[k].relative_rmse[v] = reference_rms > 0.0 ? rmse / reference_rms : rmse;
                if (status == MR_OK) status = mr_ssim_map_visualise(map, 0.0, &picture);
                snprintf(entries[k].map_names[v], sizeof entries[k].map_names[v], "ssim_view%d_material%d.png", v, k);
                entries[k].ssim_maps[v] = entries[k].map_names[v];
                if (status == MR_OK) status = write_picture(o->dir, entries[k].map_names[v], picture, 1.0);
                mr_image_free(map);
                mr_image_free(picture);
            }
            if (k == 0)
                reference = image;
            else
                mr_image_free(image);
        }
        mr_image_free(reference);
        mr_render_plan_free(plan);
        if (status != MR_OK) {
            if (isatty(STDERR_FILENO)) fputc('\n', stderr);
            return cli_fail("report", status);
        }
    }
    if (isatty(STDERR_FILENO)) fputc('\n', stderr);
    return CLI_EXIT_OK;
}

int cmd_report(int argc, char **argv) {
    for (int i = 1; i < argc; i++)
        if (cli_is_help(argv[i])) {
            print_help();
            return CLI_EXIT_OK;
        }
    options o = {NULL, NULL, NULL, 0, 0, 256, 0.0, 0.0};
    static group groups[MAX_MATERIALS]; // these three are large (maps, picture names): kept off the stack
    int count = 0;
    int code = parse(argc, argv, &o, groups, &count);
    if (code != CLI_EXIT_OK) return code;
    if (o.rotations == 0) o.rotations = o.env_path ? 4 : 1;
    if (o.env_samples == 0) o.env_samples = 1024;
    int views = o.rotations;

    static cli_material materials[MAX_MATERIALS];
    static entry entries[MAX_MATERIALS];
    memset(entries, 0, sizeof entries);
    // Entries are all materials on the sphere, or all glTF assets (rendered as their meshes).
    static asset_entry asset_storage[MAX_MATERIALS];
    int gltf_entries = 0;
    for (int k = 0; k < count; k++) gltf_entries += is_gltf_path(groups[k].model_name);
    if (gltf_entries > 0 && gltf_entries < count)
        return cli_usage_error("report", "give either materials (MODEL name=value ...) or glTF assets, not both");
    for (int k = 0; gltf_entries > 0 && k < count; k++)
        if (groups[k].count > 0)
            return cli_usage_error("report", "'%s': a glTF asset takes no name=value parameters",
                                   groups[k].assignments[0]);
    asset_entry *assets = gltf_entries > 0 ? asset_storage : NULL;
    char scratch[64] = "";
    if (assets != NULL) {
        snprintf(scratch, sizeof scratch, "/tmp/matremap-report-XXXXXX");
        if (mkdtemp(scratch) == NULL) {
            fprintf(stderr, "matremap report: error: cannot create a scratch folder in /tmp: %s\n", strerror(errno));
            return CLI_EXIT_INTERNAL;
        }
    }
    int loaded = 0;
    for (; loaded < count && code == CLI_EXIT_OK; loaded++)
        code = assets ? load_gltf_entry(groups[loaded].model_name, scratch, &assets[loaded], &materials[loaded])
                      : cli_material_load("report", groups[loaded].model_name, groups[loaded].assignments,
                                          groups[loaded].count, &materials[loaded]);
    mr_image *env = NULL;
    double env_scale = o.env_scale;
    if (code == CLI_EXIT_OK && o.env_path != NULL) {
        mr_status status = mr_img_read(o.env_path, NULL, &env);
        if (status != MR_OK) code = cli_fail("report", status);
        if (code == CLI_EXIT_OK && env_scale <= 0.0) env_scale = auto_env_scale(env);
    }
    if (code == CLI_EXIT_OK) code = make_folder(o.dir);

    double exposure = o.exposure;
    if (code == CLI_EXIT_OK)
        code = render_views(&o, env, env_scale, materials, assets, entries, count, views, &exposure);

    // Thumbnails of every map, and the page.
    char view_names[MAX_VIEWS][64];
    const char *view_ptrs[MAX_VIEWS];
    for (int v = 0; v < views; v++) {
        if (env != NULL)
            snprintf(view_names[v], sizeof view_names[v], "rotation %g°", 360.0 * v / views);
        else
            snprintf(view_names[v], sizeof view_names[v], "fit scene");
        view_ptrs[v] = view_names[v];
    }
    mr_report_material report_materials[MAX_MATERIALS];
    for (int k = 0; k < count && code == CLI_EXIT_OK; k++) {
        entry *e = &entries[k];
        const cli_material *m = &materials[k];
        snprintf(e->label, sizeof e->label, "%s", groups[k].label ? groups[k].label : groups[k].model_name);
        describe(&groups[k], e->description, sizeof e->description);
        if (assets != NULL)
            snprintf(e->description, sizeof e->description, "%s: %d triangles, rendered with the %s model",
                     groups[k].model_name, assets[k].mesh.triangle_count, m->model->name);
        for (int t = 0; t < m->map_count && code == CLI_EXIT_OK; t++) {
            const mr_brdf_param *param = &m->model->params[m->maps[t].param];
            int rgb = param->channels == 3;
            int colour = rgb && param->min_value >= 0.0 && param->max_value <= 1.0;
            snprintf(e->thumb_names[t], sizeof e->thumb_names[t], "map_material%d_%d.png", k, t);
            if (rgb)
                snprintf(e->thumb_labels[t], sizeof e->thumb_labels[t], "%s (%s)", param->name, m->maps[t].path);
            else
                snprintf(e->thumb_labels[t], sizeof e->thumb_labels[t], "%s (%s, channel %c)", param->name,
                         m->maps[t].path, "RGBA"[m->maps[t].channel]);
            e->thumbs[t] = e->thumb_names[t];
            e->thumb_label_ptrs[t] = e->thumb_labels[t];
            mr_status status = write_thumbnail(o.dir, e->thumb_names[t], &m->maps[t], rgb, colour);
            if (status != MR_OK) code = cli_fail("report", status);
        }
        e->thumb_count = m->map_count;
        report_materials[k] = (mr_report_material){e->label, e->description, e->seconds, e->renders,
                                                   k ? e->ssim_maps : NULL, k ? e->ssim : NULL,
                                                   k ? e->relative_rmse : NULL, e->thumb_count, e->thumbs,
                                                   e->thumb_label_ptrs};
    }
    if (code == CLI_EXIT_OK) {
        char scene[1024];
        const char *object = assets ? "Each asset's triangles, framed as the reference's" : "Unit sphere";
        if (env != NULL)
            snprintf(scene, sizeof scene, "%s, %d² pixels, lit by %s (radiance x %.4g, %d fixed directions), "
                     "turned in %d steps of %g°; pictures at exposure %.4g.", object, o.size, o.env_path, env_scale,
                     o.env_samples, views, 360.0 / views, exposure);
        else
            snprintf(scene, sizeof scene, "The fit scene's point light at 45°: %s, %d² pixels; pictures at exposure "
                     "%.4g.", object, o.size, exposure);
        mr_report report = {o.title ? o.title : "matremap report", scene, views, view_ptrs, count, report_materials,
                            "render time (all views)"};
        mr_status status = mr_report_write(&report, o.dir);
        if (status != MR_OK) code = cli_fail("report", status);
    }
    if (code == CLI_EXIT_OK) {
        printf("%-24s %10s %14s %10s\n", "material", "mean SSIM", "mean rel. RMSE", "render s");
        for (int k = 0; k < count; k++) {
            double ssim = 0.0, rmse = 0.0;
            for (int v = 0; v < views; v++) {
                ssim += k > 0 ? entries[k].ssim[v] : 1.0;
                rmse += k > 0 ? entries[k].relative_rmse[v] : 0.0;
            }
            ssim /= views;
            rmse /= views;
            printf("%-24s %10.4f %14.4f %10.3f%s\n", entries[k].label, ssim, rmse, entries[k].seconds,
                   k == 0 ? "  (reference)" : "");
        }
        printf("report: %s/index.html\n", o.dir);
    }
    for (int k = 0; k < loaded; k++) {
        cli_material_free(&materials[k]);
        if (assets) asset_entry_free(&assets[k]);
    }
    if (scratch[0] != '\0') rmdir(scratch);
    mr_image_free(env);
    return code;
}
