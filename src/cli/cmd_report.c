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
/* Defaults chosen from `make bench BENCH_ARGS="--only report-accuracy"` (docs/performance.md, "Defaults for
 * matremap report"): from N = 256 every view of the assets is within SSIM 0.9966 of N = 16384 and the report's
 * SSIM within 0.0001; 384² is within 0.002 of 512² and keeps its ranking. Cheaper than 1024 at 256². */
#define DEFAULT_ENV_SAMPLES 256
#define DEFAULT_SIZE 384
/* Directions about each pixel's mirror direction (mr_light.reflection_samples): without them a smooth material
 * (the CesiumMilkTruck's glossiness 1) shows the pattern's directions as sparkles instead of the map. 10 fix the
 * truck's mirrors; glossy lobes (GGX alpha 0.003 - 0.1) need about 40 for SSIM 0.99 (docs/rendering.md,
 * "Reflection samples"), for about a quarter more report time. */
#define DEFAULT_REFLECTION_SAMPLES 40

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
           "over the sphere (docs/rendering.md). glTF assets (.gltf, .glb) are rendered as their scene's triangles,\n"
           "each with its material (spec-gloss when the material carries it, else metal-rough with\n"
           "KHR_materials_specular and _ior), factors times textures through their samplers (wrap modes,\n"
           "TEXCOORD_0/1, KHR_texture_transform), with normal, occlusion and emissive maps, single-sided backs\n"
           "culled, seen from a three-quarter view onto the reference's broadest side (docs/report.md).\n"
           "\n"
           "Options:\n"
           "  -o, --output DIR     the report folder (created if missing; its files are replaced)\n"
           "  --env FILE           equirectangular HDR map (.hdr, .exr); without it, the fit scene's point light\n"
           "  --rotations N        views: the map turned by 360/N degrees each (default 4; 1 without --env)\n"
           "  --env-scale S        radiance scale (default: the map's mean luminance brought to 0.5)\n"
           "  --env-samples N      environment directions (default %d, 1-%d)\n"
           "  --env-reflection-samples M  directions about each pixel's mirror direction, combined with the\n"
           "                       environment's by MIS, so that smooth materials reflect the map (default %d,\n"
           "                       0-%d; 0 = the environment's pattern alone; the option of `render`)\n"
           "  --size N             render side in pixels (default %d)\n"
           "  --threads N          OpenMP threads of plans and renders (default 0: automatic, a team for work\n"
           "                       large enough to gain from it)\n"
           "  --camera-direction X,Y,Z  glTF assets: the direction from the reference's centre to the camera\n"
           "                       (default: a three-quarter view onto its broadest side); the camera frames its\n"
           "                       bounds\n"
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
           DEFAULT_ENV_SAMPLES, MR_ENV_MAX_SAMPLES, DEFAULT_REFLECTION_SAMPLES, MR_ENV_MAX_REFLECTION_SAMPLES,
           DEFAULT_SIZE);
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
    int has_from;
    double from[3];             /* --camera-direction: for glTF assets */
    int reflection_samples;     /* -1: DEFAULT_REFLECTION_SAMPLES */
    int threads;                /* mr_scene.threads: 0 automatic */
} options;

/* Parse "X,Y,Z" (a non-zero direction) for `option`. Returns 1, or 0 after printing a usage error. */
static int parse_direction(const char *option, const char *text, double out[3]) {
    const char *p = text;
    for (int k = 0; k < 3; k++) {
        char *end = NULL;
        out[k] = strtod(p, &end);
        if (end == p || !isfinite(out[k]) || *end != (k < 2 ? ',' : '\0')) {
            cli_usage_error("report", "%s '%s': expected three numbers X,Y,Z", option, text);
            return 0;
        }
        p = end + 1;
    }
    if (out[0] == 0.0 && out[1] == 0.0 && out[2] == 0.0) {
        cli_usage_error("report", "%s '%s': the direction must not be zero", option, text);
        return 0;
    }
    return 1;
}

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
        } else if ((taken = cli_take_option("report", argc, argv, &i, "--threads", &value))) {
            if (taken < 0 || !cli_parse_int("report", "--threads", value, 0, 1024, &o->threads)) return CLI_EXIT_USAGE;
        } else if ((taken = cli_take_option("report", argc, argv, &i, "--env-reflection-samples", &value))) {
            if (taken < 0 || !cli_parse_int("report", "--env-reflection-samples", value, 0,
                                            MR_ENV_MAX_REFLECTION_SAMPLES, &o->reflection_samples))
                return CLI_EXIT_USAGE;
        } else if (strcmp(argv[i], "--reflection-samples") == 0 || strcmp(argv[i], "--from") == 0) {
            // Renamed so that one name means one thing in every command (render's --env-reflection-samples;
            // --from names a source model in remap and sweep).
            const int reflections = argv[i][2] == 'r';
            return cli_usage_error("report", "%s is now %s", argv[i],
                                   reflections ? "--env-reflection-samples (as in render)" : "--camera-direction");
        } else if ((taken = cli_take_option("report", argc, argv, &i, "--size", &value))) {
            if (taken < 0 || !cli_parse_int("report", "--size", value, 16, MR_RENDER_MAX_SIZE, &o->size))
                return CLI_EXIT_USAGE;
        } else if ((taken = cli_take_option("report", argc, argv, &i, "--camera-direction", &value))) {
            if (taken < 0 || !parse_direction("--camera-direction", value, o->from)) return CLI_EXIT_USAGE;
            o->has_from = 1;
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
    if (o->env_path == NULL && (o->env_scale > 0.0 || o->env_samples > 0 || o->reflection_samples >= 0))
        return cli_usage_error("report", "--env-scale, --env-samples and --env-reflection-samples need --env FILE");
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
 * most THUMBNAIL_SIDE pixels on its longer side, written to dir/name. */
static mr_status write_thumbnail(const char *dir, const char *name, const mr_image *im, int channel, int rgb,
                                 int colour) {
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
                int source = im->channels == 1 ? 0 : (rgb ? c : channel);
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
    double ssim[MAX_VIEWS], relative_rmse[MAX_VIEWS];               /* the whole frame */
    double object_ssim[MAX_VIEWS], object_relative_rmse[MAX_VIEWS]; /* the object (metrics.h, masks) */
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

/* A glTF entry: its triangles merged into one mesh whose triangles carry material slots, and per slot the BRDF
 * material (model, values, folded maps) and the surface (normal, occlusion, emissive maps). */
typedef struct asset_entry {
    mr_gltf *asset;
    mr_gltf_triangles *triangles;
    float *positions, *normals, *tangents, *uvs, *uvs1; /* merged over the groups (owned) */
    uint32_t *indices;
    uint16_t *triangle_materials;
    mr_mesh mesh;
    int material_count;
    int *gltf_material;            /* [material_count] materials[] index in the asset, -1 = glTF's default */
    char (*material_names)[128];   /* [material_count] */
    cli_material *materials;       /* [material_count] */
    mr_surface *surfaces;          /* [material_count] */
    mr_image **surface_maps;       /* [3 * material_count]: normal, occlusion, emissive (owned, maybe NULL) */
    mr_material_binding *bindings; /* [material_count] */
} asset_entry;

static int is_gltf_path(const char *text) {
    size_t n = strlen(text);
    return (n > 5 && strcmp(text + n - 5, ".gltf") == 0) || (n > 4 && strcmp(text + n - 4, ".glb") == 0);
}

/* How the renderer samples a glTF texture reference: its sampler's wrap modes, its coordinate set and its
 * KHR_texture_transform. Returns an exit code (a coordinate set past TEXCOORD_1 is refused with the file). */
static int gltf_sampling(const char *path, const mr_gltf *asset, const mr_gltf_texture_ref *ref, const char *what,
                         mr_texture_sampling *out) {
    memset(out, 0, sizeof *out);
    mr_gltf_texture texture;
    mr_status status = mr_gltf_get_texture(asset, ref->index, &texture);
    if (status != MR_OK) return cli_fail("report", status);
    const int wraps[2] = {texture.params.wrap_s, texture.params.wrap_t};
    mr_wrap *modes[2] = {&out->wrap_u, &out->wrap_v};
    for (int k = 0; k < 2; k++)
        *modes[k] = wraps[k] == 33071 ? MR_WRAP_CLAMP : (wraps[k] == 33648 ? MR_WRAP_MIRROR : MR_WRAP_REPEAT);
    out->texcoord = ref->has_transform && ref->transform_tex_coord >= 0 ? ref->transform_tex_coord : ref->tex_coord;
    if (out->texcoord > 1) {
        fprintf(stderr, "matremap report: error: '%s': %s reads TEXCOORD_%d; the renderer reads TEXCOORD_0 and _1\n",
                path, what, out->texcoord);
        return CLI_EXIT_BAD_INPUT;
    }
    out->has_transform = ref->has_transform;
    out->offset[0] = ref->offset[0];
    out->offset[1] = ref->offset[1];
    out->rotation = ref->rotation;
    out->scale[0] = ref->scale[0];
    out->scale[1] = ref->scale[1];
    return CLI_EXIT_OK;
}

/* A map for parameter `name` of m's model: channels `first`.. of `source` (count 1 or 3; a grey source answers
 * every channel) times `factor[]`, as a new image the material owns, sampled as `sampling` says. Returns an exit
 * code. */
static int fold_map(cli_material *m, const char *name, const char *label, const mr_image *source, int first,
                    int count, const double *factor, const mr_texture_sampling *sampling) {
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
    if (status != MR_OK) return cli_fail("report", status);
    m->textures.sampling[map->param] = *sampling;
    return CLI_EXIT_OK;
}

/* Set parameter `name` of m to `count` values. */
static void set_values(cli_material *m, const char *name, const double *v, int count) {
    int p = mr_brdf_param_index(m->model, name);
    int offset = mr_brdf_param_offset(m->model, p);
    for (int c = 0; c < count; c++) m->values[offset + c] = v[c];
}

/* One parameter's share of a texture: channels first.. (count 1 or 3) times factor. */
typedef struct texture_fold {
    const char *name, *label;
    int first, count;
    const double *factor;
} texture_fold;

/* Decode texture `ref` of the asset once (with `encoding`) and fold it into the `fold_count` parameters that read
 * it (a packed texture feeds two). No texture: nothing to do. Returns an exit code. */
static int fold_texture(const char *path, const mr_gltf *asset, const mr_gltf_texture_ref *ref,
                        mr_img_encoding encoding, const char *scratch, cli_material *m, const texture_fold *folds,
                        int fold_count) {
    if (ref->index < 0) return CLI_EXIT_OK;
    mr_texture_sampling sampling;
    int code = gltf_sampling(path, asset, ref, folds[0].label, &sampling);
    mr_image *image = NULL;
    if (code == CLI_EXIT_OK) code = cli_gltf_read_texture(asset, ref, encoding, scratch, &image);
    for (int f = 0; f < fold_count && code == CLI_EXIT_OK; f++)
        code = fold_map(m, folds[f].name, folds[f].label, image, folds[f].first, folds[f].count, folds[f].factor,
                        &sampling);
    mr_image_free(image);
    return code;
}

/* One glTF material as a BRDF material: `gltf-specgloss` when it carries KHR_materials_pbrSpecularGlossiness
 * (what an engine that supports the extension renders) and `gltf` otherwise (core metal-rough,
 * KHR_materials_specular factors and colour texture, KHR_materials_ior; an ior above 5, the model's bound, is
 * rendered at 5 with the specular colour scaled to the same F0). Factors are folded into the maps. Returns an
 * exit code. */
static int load_gltf_brdf(const char *path, const mr_gltf *asset, const mr_gltf_material *mat, const char *scratch,
                          cli_material *m) {
    memset(m, 0, sizeof *m);
    if (mat->has_spec_gloss) {
        m->model = mr_brdf_find("gltf-specgloss");
        mr_brdf_default_values(m->model, m->values);
        set_values(m, "diffuse", mat->diffuse_factor, 3);
        set_values(m, "specular", mat->specular_factor, 3);
        set_values(m, "glossiness", &mat->glossiness_factor, 1);
        const texture_fold diffuse = {"diffuse", "diffuseTexture", 0, 3, mat->diffuse_factor};
        const texture_fold specgloss[2] = {
            {"specular", "specularGlossinessTexture RGB", 0, 3, mat->specular_factor},
            {"glossiness", "specularGlossinessTexture A", 3, 1, &mat->glossiness_factor}};
        int code = fold_texture(path, asset, &mat->diffuse_texture, MR_IMG_COLOR, scratch, m, &diffuse, 1);
        if (code == CLI_EXIT_OK)
            code = fold_texture(path, asset, &mat->specular_glossiness_texture, MR_IMG_COLOR, scratch, m, specgloss,
                                2);
        return code;
    }
    m->model = mr_brdf_find("gltf");
    mr_brdf_default_values(m->model, m->values);
    double ior = mat->has_ior ? mat->ior : 1.5, rendered_ior = ior > 5.0 ? 5.0 : (ior < 1.0 ? 1.0 : ior);
    double f0 = pow((ior - 1.0) / (ior + 1.0), 2.0);
    double rendered_f0 = pow((rendered_ior - 1.0) / (rendered_ior + 1.0), 2.0);
    double scale = rendered_f0 > 0.0 ? f0 / rendered_f0 : 1.0;
    double colour[3];
    for (int c = 0; c < 3; c++) colour[c] = (mat->has_specular ? mat->specular_color_factor[c] : 1.0) * scale;
    double strength = mat->has_specular ? mat->specular_strength : 1.0;
    set_values(m, "base_color", mat->base_color_factor, 3);
    set_values(m, "metallic", &mat->metallic_factor, 1);
    set_values(m, "roughness", &mat->roughness_factor, 1);
    set_values(m, "specular", &strength, 1);
    set_values(m, "specular_color", colour, 3);
    set_values(m, "ior", &rendered_ior, 1);
    const texture_fold base = {"base_color", "baseColorTexture", 0, 3, mat->base_color_factor};
    const texture_fold metal_rough[2] = {
        {"metallic", "metallicRoughnessTexture B", 2, 1, &mat->metallic_factor},
        {"roughness", "metallicRoughnessTexture G", 1, 1, &mat->roughness_factor}};
    const texture_fold specular_colour = {"specular_color", "specularColorTexture", 0, 3, colour};
    const texture_fold specular = {"specular", "specularTexture A", 3, 1, &strength};
    int code = fold_texture(path, asset, &mat->base_color_texture, MR_IMG_COLOR, scratch, m, &base, 1);
    if (code == CLI_EXIT_OK)
        code = fold_texture(path, asset, &mat->metallic_roughness_texture, MR_IMG_DATA, scratch, m, metal_rough, 2);
    if (code == CLI_EXIT_OK && mat->has_specular)
        code = fold_texture(path, asset, &mat->specular_color_texture, MR_IMG_COLOR, scratch, m, &specular_colour, 1);
    if (code == CLI_EXIT_OK && mat->has_specular)
        code = fold_texture(path, asset, &mat->specular_texture, MR_IMG_DATA, scratch, m, &specular, 1);
    return code;
}

/* The material's surface: sidedness, normal map and scale, occlusion map and strength, emission (factor times
 * map). Decoded maps go to maps[0..2] (owned by the entry). Returns an exit code. */
static int load_gltf_surface(const char *path, const mr_gltf *asset, const mr_gltf_material *mat,
                             const char *scratch, mr_surface *surface, mr_image **maps) {
    memset(surface, 0, sizeof *surface);
    surface->double_sided = mat->double_sided;
    surface->normal_scale = mat->normal_texture.value;
    surface->occlusion_strength = mat->occlusion_texture.value;
    for (int c = 0; c < 3; c++) surface->emission[c] = mat->emissive_factor[c];
    const struct {
        const mr_gltf_texture_ref *ref;
        mr_img_encoding encoding;
        const char *what;
        const mr_image **map;
        mr_texture_sampling *sampling;
    } textures[3] = {
        {&mat->normal_texture, MR_IMG_DATA, "normalTexture", &surface->normal_map, &surface->normal_sampling},
        {&mat->occlusion_texture, MR_IMG_DATA, "occlusionTexture", &surface->occlusion_map,
         &surface->occlusion_sampling},
        {&mat->emissive_texture, MR_IMG_COLOR, "emissiveTexture", &surface->emissive_map,
         &surface->emissive_sampling},
    };
    for (int k = 0; k < 3; k++) {
        if (textures[k].ref->index < 0) continue;
        if (k == 2 && !(surface->emission[0] > 0.0 || surface->emission[1] > 0.0 || surface->emission[2] > 0.0))
            continue; // a black emissive factor: the map changes nothing
        int code = gltf_sampling(path, asset, textures[k].ref, textures[k].what, textures[k].sampling);
        if (code == CLI_EXIT_OK) code = cli_gltf_read_texture(asset, textures[k].ref, textures[k].encoding, scratch,
                                                              &maps[k]);
        if (code != CLI_EXIT_OK) return code;
        if (k == 0 && maps[k]->channels < 3) {
            fprintf(stderr, "matremap report: error: '%s': normalTexture has %d channel(s), expected RGB\n", path,
                    maps[k]->channels);
            return CLI_EXIT_BAD_INPUT;
        }
        *textures[k].map = maps[k];
    }
    return CLI_EXIT_OK;
}

/* Concatenate the groups' vertices into the entry's mesh (an attribute some groups lack is zero there: normals
 * and tangents generated by the renderer, UVs (0, 0)); triangle material = the slot of the group's material. */
static int merge_groups(const char *path, asset_entry *a, const int *slot_of_group) {
    const mr_gltf_triangles *t = a->triangles;
    const size_t nv = (size_t)t->vertex_count, nt = (size_t)t->triangle_count;
    int any_normals = 0, any_tangents = 0, any_uv0 = 0, any_uv1 = 0;
    for (int g = 0; g < t->group_count; g++) {
        any_normals |= t->groups[g].has_normals;
        any_tangents |= t->groups[g].has_tangents;
        any_uv0 |= t->groups[g].has_uv0;
        any_uv1 |= t->groups[g].has_uv1;
    }
    a->positions = malloc(nv * 3 * sizeof(float));
    a->indices = malloc(nt * 3 * sizeof(uint32_t));
    a->triangle_materials = malloc(nt * sizeof(uint16_t));
    if (any_normals) a->normals = calloc(nv * 3, sizeof(float));
    if (any_tangents) a->tangents = calloc(nv * 4, sizeof(float));
    if (any_uv0) a->uvs = calloc(nv * 2, sizeof(float));
    if (any_uv1) a->uvs1 = calloc(nv * 2, sizeof(float));
    if (!a->positions || !a->indices || !a->triangle_materials || (any_normals && !a->normals) ||
        (any_tangents && !a->tangents) || (any_uv0 && !a->uvs) || (any_uv1 && !a->uvs1)) {
        fprintf(stderr, "matremap report: error: '%s': out of memory for %zu vertices\n", path, nv);
        return CLI_EXIT_INTERNAL;
    }
    size_t vertex_base = 0, triangle_base = 0;
    for (int g = 0; g < t->group_count; g++) {
        const mr_gltf_triangle_group *group = &t->groups[g];
        const size_t v = (size_t)group->vertex_count, f = (size_t)group->triangle_count;
        memcpy(a->positions + 3 * vertex_base, group->positions, v * 3 * sizeof(float));
        if (group->has_normals) memcpy(a->normals + 3 * vertex_base, group->normals, v * 3 * sizeof(float));
        if (group->has_tangents) memcpy(a->tangents + 4 * vertex_base, group->tangents, v * 4 * sizeof(float));
        if (group->has_uv0) memcpy(a->uvs + 2 * vertex_base, group->uv0, v * 2 * sizeof(float));
        if (group->has_uv1) memcpy(a->uvs1 + 2 * vertex_base, group->uv1, v * 2 * sizeof(float));
        for (size_t i = 0; i < 3 * f; i++)
            a->indices[3 * triangle_base + i] = group->indices[i] + (uint32_t)vertex_base;
        for (size_t i = 0; i < f; i++) a->triangle_materials[triangle_base + i] = (uint16_t)slot_of_group[g];
        vertex_base += v;
        triangle_base += f;
    }
    memset(&a->mesh, 0, sizeof a->mesh);
    a->mesh.vertex_count = t->vertex_count;
    a->mesh.positions = a->positions;
    a->mesh.normals = a->normals;
    a->mesh.tangents = a->tangents;
    a->mesh.uvs = a->uvs;
    a->mesh.uvs1 = a->uvs1;
    a->mesh.triangle_count = t->triangle_count;
    a->mesh.indices = a->indices;
    a->mesh.material_count = a->material_count;
    a->mesh.triangle_materials = a->triangle_materials;
    a->mesh.surfaces = a->surfaces;
    return CLI_EXIT_OK;
}

/* Load a glTF asset as a report entry: its scene's triangles as one mesh, each material (load_gltf_brdf) with
 * its surface (load_gltf_surface). Returns an exit code. */
static int load_gltf_entry(const char *path, const char *scratch, asset_entry *a) {
    memset(a, 0, sizeof *a);
    mr_status status = mr_gltf_load(path, &a->asset);
    if (status == MR_OK) status = mr_gltf_get_triangles(a->asset, -1, &a->triangles);
    if (status != MR_OK) return cli_fail("report", status);
    const mr_gltf_triangles *t = a->triangles;
    if (t->triangle_count == 0) {
        fprintf(stderr, "matremap report: error: '%s': its scene has no triangles to render\n", path);
        return CLI_EXIT_BAD_INPUT;
    }
    // One slot per distinct material (groups of one material with different attribute sets share it).
    int *slot_of_group = malloc((size_t)t->group_count * sizeof *slot_of_group);
    a->gltf_material = malloc((size_t)t->group_count * sizeof *a->gltf_material);
    if (slot_of_group == NULL || a->gltf_material == NULL) {
        free(slot_of_group);
        return CLI_EXIT_INTERNAL;
    }
    for (int g = 0; g < t->group_count; g++) {
        int slot = 0;
        while (slot < a->material_count && a->gltf_material[slot] != t->groups[g].material) slot++;
        if (slot == a->material_count) a->gltf_material[a->material_count++] = t->groups[g].material;
        slot_of_group[g] = slot;
    }
    const int n = a->material_count;
    a->materials = calloc((size_t)n, sizeof *a->materials);
    a->surfaces = calloc((size_t)n, sizeof *a->surfaces);
    a->surface_maps = calloc((size_t)n * 3, sizeof *a->surface_maps);
    a->bindings = calloc((size_t)n, sizeof *a->bindings);
    a->material_names = calloc((size_t)n, sizeof *a->material_names);
    int code = a->materials && a->surfaces && a->surface_maps && a->bindings && a->material_names ? CLI_EXIT_OK
                                                                                                 : CLI_EXIT_INTERNAL;
    for (int k = 0; k < n && code == CLI_EXIT_OK; k++) {
        mr_gltf_material mat;
        if (a->gltf_material[k] >= 0) {
            status = mr_gltf_get_material(a->asset, a->gltf_material[k], &mat);
            if (status != MR_OK) code = cli_fail("report", status);
        } else {
            mr_gltf_material_defaults(&mat);
        }
        if (code != CLI_EXIT_OK) break;
        if (mat.name != NULL && mat.name[0] != '\0')
            snprintf(a->material_names[k], sizeof a->material_names[k], "%s", mat.name);
        else
            snprintf(a->material_names[k], sizeof a->material_names[k], "material %d", a->gltf_material[k]);
        code = load_gltf_brdf(path, a->asset, &mat, scratch, &a->materials[k]);
        if (code == CLI_EXIT_OK)
            code = load_gltf_surface(path, a->asset, &mat, scratch, &a->surfaces[k], a->surface_maps + 3 * k);
        a->bindings[k] = (mr_material_binding){a->materials[k].model, a->materials[k].values,
                                               &a->materials[k].textures};
    }
    if (code == CLI_EXIT_OK) code = merge_groups(path, a, slot_of_group);
    free(slot_of_group);
    return code;
}

static int same_image(const mr_image *a, const mr_image *b) {
    if (a == NULL || b == NULL) return a == b;
    return a->width == b->width && a->height == b->height && a->channels == b->channels &&
           memcmp(a->pixels, b->pixels, mr_image_value_count(a) * sizeof *a->pixels) == 0;
}

/* Do two entries' meshes give the same render plan: the same triangles (every array equal, or absent in both),
 * materials of the triangles, and surfaces (the plan samples them)? */
static int same_mesh(const asset_entry *ea, const asset_entry *eb) {
    const mr_mesh *a = &ea->mesh, *b = &eb->mesh;
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

static void asset_entry_free(asset_entry *a) {
    for (int k = 0; a->materials != NULL && k < a->material_count; k++) cli_material_free(&a->materials[k]);
    for (int k = 0; a->surface_maps != NULL && k < 3 * a->material_count; k++) mr_image_free(a->surface_maps[k]);
    free(a->materials);
    free(a->surfaces);
    free(a->surface_maps);
    free(a->bindings);
    free(a->material_names);
    free(a->gltf_material);
    free(a->positions);
    free(a->normals);
    free(a->tangents);
    free(a->uvs);
    free(a->uvs1);
    free(a->indices);
    free(a->triangle_materials);
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
        scene.threads = o->threads;
        if (env != NULL) {
            scene.lights[0] = mr_light_environment(env, env_scale, 360.0 * v / views, o->env_samples);
            scene.lights[0].reflection_samples = o->reflection_samples;
        }
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
            for (int c = 0; c < 3; c++) frame.from[c] = o->has_from ? o->from[c] : (c == thin ? 1.0 : 0.35);
            status = mr_camera_frame_mesh(&assets[0].mesh, &frame, &scene.camera);
        }
        mr_render_plan *plan = NULL;
        mr_image *reference = NULL, *reference_mask = NULL; // the reference's render and coverage
        if (status == MR_OK) status = mr_render_plan_create(&scene, &plan);
        if (status == MR_OK) status = mr_render_plan_coverage_mask(plan, &reference_mask);
        int plan_entry = 0; // the entry whose mesh the plan holds
        for (int k = 0; k < count && status == MR_OK; k++) {
            mr_image *image = NULL;
            if (assets != NULL && k > 0 && !same_mesh(&assets[k], &assets[plan_entry])) {
                // An asset with geometry of its own gets its own plan; a conversion of the reference (the same
                // triangles and surfaces) shares the reference's, shadow rays included.
                mr_render_plan_free(plan);
                plan = NULL;
                scene.shape.mesh = &assets[k].mesh;
                plan_entry = k;
                status = mr_render_plan_create(&scene, &plan);
                if (status != MR_OK) break;
            }
            double started = cli_now();
            if (assets != NULL)
                status = mr_render_materials(plan, assets[k].bindings, assets[k].material_count, MR_COMPONENT_FULL,
                                             &image);
            else
                status = mr_render_textured(plan, materials[k].model, materials[k].values, &materials[k].textures,
                                            MR_COMPONENT_FULL, &image);
            entries[k].seconds += cli_now() - started;
            if (status != MR_OK) break;
            if (k == 0 && v == 0 && *exposure <= 0.0) *exposure = auto_exposure(plan, image);
            snprintf(entries[k].render_names[v], sizeof entries[k].render_names[v], "view%d_material%d.png", v, k);
            entries[k].renders[v] = entries[k].render_names[v];
            status = write_picture(o->dir, entries[k].render_names[v], image, *exposure);
            if (status == MR_OK && k > 0) {
                mr_ssim_options so = {*exposure, 0, NULL};
                mr_image *map = NULL, *picture = NULL, *mask = NULL;
                double rmse = 0.0, reference_rms = rms(reference), object_rmse = 0.0, object_mean = 0.0;
                status = mr_ssim(reference, image, &so, &entries[k].ssim[v], &map);
                if (status == MR_OK) status = mr_rmse(reference, image, &rmse);
                entries[k].relative_rmse[v] = reference_rms > 0.0 ? rmse / reference_rms : rmse;
                // The same over the object: what a viewer looks at (metrics.h, masks).
                if (status == MR_OK) status = comparison_mask(reference_mask, plan, plan_entry != 0, &mask);
                so.mask = mask;
                if (status == MR_OK) status = mr_ssim(reference, image, &so, &entries[k].object_ssim[v], NULL);
                if (status == MR_OK) status = mr_rmse_masked(reference, image, mask, &object_rmse, &object_mean);
                entries[k].object_relative_rmse[v] = object_mean > 0.0 ? object_rmse / object_mean : object_rmse;
                mr_image_free(mask);
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
        mr_image_free(reference_mask);
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
    options o = {NULL, NULL, NULL, 0, 0, DEFAULT_SIZE, 0.0, 0.0, 0, {0.0, 0.0, 0.0}, -1, 0};
    static group groups[MAX_MATERIALS]; // these three are large (maps, picture names): kept off the stack
    int count = 0;
    int code = parse(argc, argv, &o, groups, &count);
    if (code != CLI_EXIT_OK) return code;
    if (o.rotations == 0) o.rotations = o.env_path ? 4 : 1;
    if (o.env_samples == 0) o.env_samples = DEFAULT_ENV_SAMPLES;
    if (o.reflection_samples < 0) o.reflection_samples = DEFAULT_REFLECTION_SAMPLES;
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
    if (o.has_from && gltf_entries == 0)
        return cli_usage_error("report", "--camera-direction places the camera for glTF assets; spheres use the fit "
                               "camera");
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
        code = assets ? load_gltf_entry(groups[loaded].model_name, scratch, &assets[loaded])
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
        snprintf(e->label, sizeof e->label, "%s", groups[k].label ? groups[k].label : groups[k].model_name);
        describe(&groups[k], e->description, sizeof e->description);
        const int slots = assets ? assets[k].material_count : 1;
        if (assets != NULL) {
            size_t used = (size_t)snprintf(e->description, sizeof e->description, "%s: %d triangles, %d material%s:",
                                           groups[k].model_name, assets[k].mesh.triangle_count, slots,
                                           slots == 1 ? "" : "s");
            for (int m = 0; m < slots && used < sizeof e->description; m++)
                used += (size_t)snprintf(e->description + used, sizeof e->description - used, "%s %s (%s model)",
                                         m ? "," : "", assets[k].material_names[m], assets[k].materials[m].model->name);
        }
        // Thumbnails of every map: each material's BRDF maps, then (glTF) its normal, occlusion and emissive maps.
        e->thumb_count = 0;
        for (int slot = 0; slot < slots && code == CLI_EXIT_OK; slot++) {
            const cli_material *m = assets ? &assets[k].materials[slot] : &materials[k];
            char prefix[140] = "";
            if (slots > 1) snprintf(prefix, sizeof prefix, "%s: ", assets[k].material_names[slot]);
            for (int t = 0; t < m->map_count + 3 && code == CLI_EXIT_OK; t++) {
                const mr_image *im;
                int channel = 0, rgb, colour;
                char what[300];
                if (t < m->map_count) {
                    const mr_brdf_param *param = &m->model->params[m->maps[t].param];
                    im = m->maps[t].image;
                    channel = m->maps[t].channel;
                    rgb = param->channels == 3;
                    colour = rgb && param->min_value >= 0.0 && param->max_value <= 1.0;
                    if (rgb || im->channels == 1) // a one-channel map (a folded glTF map) says its source itself
                        snprintf(what, sizeof what, "%s (%s)", param->name, m->maps[t].path);
                    else
                        snprintf(what, sizeof what, "%s (%s, channel %c)", param->name, m->maps[t].path,
                                 "RGBA"[channel]);
                } else {
                    static const char *const surface_names[3] = {"normal map", "occlusion (channel R)",
                                                                 "emissive map"};
                    if (assets == NULL || (im = assets[k].surface_maps[3 * slot + t - m->map_count]) == NULL) continue;
                    rgb = t - m->map_count != 1;
                    colour = t - m->map_count == 2;
                    snprintf(what, sizeof what, "%s", surface_names[t - m->map_count]);
                }
                if (e->thumb_count == CLI_MAX_ASSIGNMENTS) break;
                const int n = e->thumb_count++;
                snprintf(e->thumb_names[n], sizeof e->thumb_names[n], "map_material%d_%d.png", k, n);
                snprintf(e->thumb_labels[n], sizeof e->thumb_labels[n], "%s%s", prefix, what);
                e->thumbs[n] = e->thumb_names[n];
                e->thumb_label_ptrs[n] = e->thumb_labels[n];
                mr_status status = write_thumbnail(o.dir, e->thumb_names[n], im, channel, rgb, colour);
                if (status != MR_OK) code = cli_fail("report", status);
            }
        }
        report_materials[k] = (mr_report_material){e->label, e->description, e->seconds, e->renders,
                                                   k ? e->ssim_maps : NULL, k ? e->ssim : NULL,
                                                   k ? e->relative_rmse : NULL, e->thumb_count, e->thumbs,
                                                   e->thumb_label_ptrs, k ? e->object_ssim : NULL,
                                                   k ? e->object_relative_rmse : NULL};
    }
    if (code == CLI_EXIT_OK) {
        char scene[1024];
        const char *object = assets ? "Each asset's triangles, framed as the reference's" : "Unit sphere";
        if (env != NULL)
            snprintf(scene, sizeof scene, "%s, %d² pixels, lit by %s (radiance x %.4g, %d fixed directions and %d "
                     "about each pixel's mirror direction), turned in %d steps of %g°; pictures at exposure %.4g.",
                     object, o.size, o.env_path, env_scale, o.env_samples, o.reflection_samples, views, 360.0 / views,
                     exposure);
        else
            snprintf(scene, sizeof scene, "The fit scene's point light at 45°: %s, %d² pixels; pictures at exposure "
                     "%.4g.", object, o.size, exposure);
        mr_report report = {o.title ? o.title : "matremap report", scene, views, view_ptrs, count, report_materials,
                            "render time (all views)"};
        mr_status status = mr_report_write(&report, o.dir);
        if (status != MR_OK) code = cli_fail("report", status);
    }
    if (code == CLI_EXIT_OK) {
        // Means over the views: the object's figures first, the whole frame's beside them.
        printf("%-24s %11s %16s %10s %15s %9s\n", "material", "object SSIM", "object rel. RMSE", "frame SSIM",
               "frame rel. RMSE", "render s");
        for (int k = 0; k < count; k++) {
            const entry *e = &entries[k];
            double sums[4] = {0.0, 0.0, 0.0, 0.0};
            for (int v = 0; v < views && k > 0; v++) {
                sums[0] += e->object_ssim[v];
                sums[1] += e->object_relative_rmse[v];
                sums[2] += e->ssim[v];
                sums[3] += e->relative_rmse[v];
            }
            if (k == 0) sums[0] = sums[2] = views;
            printf("%-24s %11.4f %16.4f %10.4f %15.4f %9.3f%s\n", e->label, sums[0] / views, sums[1] / views,
                   sums[2] / views, sums[3] / views, e->seconds, k == 0 ? "  (reference)" : "");
        }
        printf("report: %s/index.html\n", o.dir);
    }
    for (int k = 0; k < loaded; k++) {
        if (assets)
            asset_entry_free(&assets[k]);
        else
            cli_material_free(&materials[k]);
    }
    if (scratch[0] != '\0') rmdir(scratch);
    mr_image_free(env);
    return code;
}
