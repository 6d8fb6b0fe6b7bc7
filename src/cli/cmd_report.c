/*
 * cmd_report.c — `matremap report -o DIR [options] REFERENCE [-- MATERIAL ...]`: parses the command line into
 * report inputs (materials given as for `matremap render`, cli_material.c, or glTF assets loaded as scenes,
 * mr_gltf_scene_load), an optional OBJ mesh to render the materials on (--mesh, mr_obj_load) and options,
 * calls mr_report_make (src/report/report.h), which renders, compares and
 * writes the report folder, and prints each input's mean figures and the page's path. Progress goes to stderr
 * on a terminal.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cli.h"
#include "gltf/mr_gltf_scene.h"
#include "io/obj_load.h"

#define MAX_MATERIALS 64
#define MAX_ARGS 64

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
           "as for 'matremap render': parameters as name=value, or name=@MAP[:r|g|b|a][:linear|srgb] from a\n"
           "texture wrapped over the sphere, read by the rule of 'matremap render --help' (docs/rendering.md).\n"
           "glTF assets (.gltf, .glb) are rendered as their scene's triangles, each with its material (spec-gloss\n"
           "when the material carries it, else metal-rough with KHR_materials_specular and _ior; their textures\n"
           "decoded as glTF specifies, which agrees with the rule), factors times textures through their\n"
           "samplers (wrap modes, TEXCOORD_0/1, KHR_texture_transform), with normal, occlusion and emissive maps,\n"
           "single-sided backs culled, seen from a three-quarter view onto the reference's broadest side\n"
           "(docs/report.md).\n"
           "With --mesh FILE.obj the materials are rendered on that mesh instead of the sphere (e.g. the paper's\n"
           "material-test sphere, ../shared/assets/paper/matsphere.obj), their maps at its UVs, one render plan per\n"
           "view (its shadows traced once) shared by every material.\n"
           "\n");
    printf("Options:\n"
           "  -o, --output DIR     the report folder, written whole or not at all: made beside DIR and renamed\n"
           "                       into place when complete, replacing a previous report there (a folder that\n"
           "                       holds anything a report does not write is refused, as is an input inside DIR)\n"
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
"  --mesh FILE.obj      materials: render them on this Wavefront OBJ mesh (docs/rendering.md, \"OBJ\n"
           "                       meshes\"); needs --env\n"
           "  --camera auto|paper  with --mesh: auto (default) frames the mesh from +z; paper is the paper's\n"
           "                       visualisation camera, at (0,0,-1.5) looking at the origin, 40 degrees on y\n"
           "  --exposure E         display exposure of the pictures and of SSIM (default: the reference's\n"
           "                       object pixels in the first view to a mean luminance of 0.18)\n"
           "  --title TEXT         the page's title\n"
           "  --label TEXT         (inside a material's group) its name in the report (default: the model)\n"
           "  --renderer R         (inside a material's group) who renders it: builtin (default), blender\n"
           "                       (cycles-principled, lambert, or MODEL = blender:FILE.blend:MATERIAL with\n"
           "                       'NODE.SOCKET=value' inputs) or three (gltf, lambert): a uniform material in the\n"
           "                       fit scene, no --env or --mesh (docs/renderers.md)\n"
           "  --samples N          the real renderers' samples per pixel (default: theirs)\n"
           "  --json               the figures as one JSON object on stdout instead of the table: the folder, its\n"
           "                       page and summary.json, views, exposure, each material's mean figures and seconds\n"
           "  --help               this text\n"
           "\n"
           "Prints each material's mean SSIM and relative RMSE and the page's path. Missing folders above DIR are\n"
           "made.\n"
           "\n"
           "Example:\n"
           "  matremap report -o out/avocado --env studio.hdr \\\n"
           "      --label original gltf-specgloss diffuse=@d.png specular=@s.png glossiness=@g.png \\\n"
           "      -- --label weighted gltf base_color=@w_basecolor.png metallic=@w_mr.png:b roughness=@w_mr.png:g\n",
           MR_REPORT_DEFAULT_ENV_SAMPLES, MR_ENV_MAX_SAMPLES, MR_REPORT_DEFAULT_REFLECTION_SAMPLES,
           MR_ENV_MAX_REFLECTION_SAMPLES, MR_REPORT_DEFAULT_SIZE);
}

/* One material's group on the command line. */
typedef struct group {
    const char *label;
    const char *renderer; /* --renderer inside the group: NULL = builtin */
    const char *model_name;
    const char *assignments[MAX_ARGS];
    int count;
} group;

typedef struct options {
    const char *dir;
    const char *mesh_path; /* --mesh */
    int paper_camera;      /* --camera paper */
    int json;              /* --json */
    int samples;           /* --samples */
    mr_report_options report; /* zero: the library's defaults */
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
        } else if ((taken = cli_take_option("report", argc, argv, &i, "--renderer", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            if (mr_renderer_check(value, NULL) != MR_OK) return cli_usage_error("report", "%s", mr_last_error());
            g->renderer = value;
        } else if ((taken = cli_take_option("report", argc, argv, &i, "--samples", &value))) {
            if (taken < 0 || !cli_parse_int("report", "--samples", value, 1, 1 << 20, &o->samples))
                return CLI_EXIT_USAGE;
        } else if ((taken = cli_take_option("report", argc, argv, &i, "--output", &value)) ||
                   (taken = cli_take_option("report", argc, argv, &i, "-o", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            o->dir = value;
        } else if ((taken = cli_take_option("report", argc, argv, &i, "--env", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            o->report.env_path = value;
        } else if ((taken = cli_take_option("report", argc, argv, &i, "--title", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            o->report.title = value;
        } else if ((taken = cli_take_option("report", argc, argv, &i, "--rotations", &value))) {
            if (taken < 0 ||
                !cli_parse_int("report", "--rotations", value, 1, MR_REPORT_MAX_VIEWS, &o->report.rotations))
                return CLI_EXIT_USAGE;
        } else if ((taken = cli_take_option("report", argc, argv, &i, "--env-samples", &value))) {
            if (taken < 0 || !cli_parse_int("report", "--env-samples", value, 1, MR_ENV_MAX_SAMPLES,
                                            &o->report.env_samples))
                return CLI_EXIT_USAGE;
        } else if ((taken = cli_take_option("report", argc, argv, &i, "--threads", &value))) {
            if (taken < 0 || !cli_parse_int("report", "--threads", value, 0, 1024, &o->report.threads))
                return CLI_EXIT_USAGE;
        } else if ((taken = cli_take_option("report", argc, argv, &i, "--env-reflection-samples", &value))) {
            int samples = 0;
            if (taken < 0 || !cli_parse_int("report", "--env-reflection-samples", value, 0,
                                            MR_ENV_MAX_REFLECTION_SAMPLES, &samples))
                return CLI_EXIT_USAGE;
            o->report.reflection_samples = samples > 0 ? samples : MR_REPORT_NO_REFLECTION_SAMPLES;
        } else if (strcmp(argv[i], "--reflection-samples") == 0 || strcmp(argv[i], "--from") == 0) {
            // Renamed so that one name means one thing in every command (render's --env-reflection-samples;
            // --from names a source model in remap and sweep).
            const int reflections = argv[i][2] == 'r';
            return cli_usage_error("report", "%s is now %s", argv[i],
                                   reflections ? "--env-reflection-samples (as in render)" : "--camera-direction");
        } else if ((taken = cli_take_option("report", argc, argv, &i, "--size", &value))) {
            if (taken < 0 || !cli_parse_int("report", "--size", value, MR_REPORT_MIN_SIZE, MR_RENDER_MAX_SIZE,
                                            &o->report.size))
                return CLI_EXIT_USAGE;
        } else if ((taken = cli_take_option("report", argc, argv, &i, "--mesh", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            o->mesh_path = value;
        } else if ((taken = cli_take_option("report", argc, argv, &i, "--camera", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            if (strcmp(value, "auto") != 0 && strcmp(value, "paper") != 0)
                return cli_usage_error("report", "--camera '%s': expected auto or paper", value);
            o->paper_camera = strcmp(value, "paper") == 0;
        } else if ((taken = cli_take_option("report", argc, argv, &i, "--camera-direction", &value))) {
            if (taken < 0 || !cli_parse_direction("report", "--camera-direction", value, o->report.camera_direction))
                return CLI_EXIT_USAGE;
            o->report.has_camera_direction = 1;
        } else if ((taken = cli_take_option("report", argc, argv, &i, "--env-scale", &value))) {
            if (taken < 0 ||
                !cli_parse_double("report", "--env-scale", value, 1e-12, 1e12, &o->report.env_scale))
                return CLI_EXIT_USAGE;
        } else if ((taken = cli_take_option("report", argc, argv, &i, "--exposure", &value))) {
            if (taken < 0 ||
                !cli_parse_double("report", "--exposure", value, 1e-12, 1e12, &o->report.exposure))
                return CLI_EXIT_USAGE;
        } else if (strcmp(argv[i], "--json") == 0) {
            o->json = 1;
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
    const mr_report_options *r = &o->report;
    if (r->env_path == NULL && r->rotations > 1)
        return cli_usage_error("report", "--rotations %d needs --env FILE (the fit scene has one view)", r->rotations);
    if (o->mesh_path != NULL && r->env_path == NULL)
        return cli_usage_error("report", "--mesh needs --env FILE (the fit scene's point light is placed for the unit "
                               "sphere)");
    if (o->paper_camera && o->mesh_path == NULL)
        return cli_usage_error("report", "--camera paper places the camera for --mesh");
    if (r->env_path == NULL && (r->env_scale > 0.0 || r->env_samples > 0 || r->reflection_samples != 0))
        return cli_usage_error("report", "--env-scale, --env-samples and --env-reflection-samples need --env FILE");
    *group_count = n;
    return CLI_EXIT_OK;
}

/* The text of a group: "MODEL a=b c=@d". */
static void describe(const group *g, char *out, size_t size) {
    size_t used = (size_t)snprintf(out, size, "%s", g->model_name);
    for (int k = 0; k < g->count && used < size; k++)
        used += (size_t)snprintf(out + used, size - used, " %s", g->assignments[k]);
}

/* The renderer `name` for a group (renderers[0] blender's, [1] three's, opened once for every group that names it),
 * after checking that it renders `material`'s model (NULL: a material of its own). An exit code. */
static int report_renderer(const char *command, cli_renderers renderers[2], const char *name, int samples,
                           const mr_material *material, mr_renderer **out) {
    cli_renderers *r = &renderers[strcmp(name, "blender") == 0 ? 0 : 1];
    if (material != NULL && mr_renderer_check(name, material->model) != MR_OK)
        return cli_usage_error(command, "--renderer %s: %s", name, mr_last_error());
    if (r->opened[0] == NULL) {
        r->names[0] = name;
        r->samples = samples;
        int code = cli_open_renderers(command, r, NULL, NULL, 1);
        if (code != CLI_EXIT_OK) return code;
    }
    *out = r->opened[0];
    return CLI_EXIT_OK;
}

/* mr_report_options.progress on a terminal: "view 2/4" rewritten in place; *user (int) notes that a line was
 * started, so that it is ended afterwards. */
static int show_progress(void *user, int done, int total, const char *what) {
    if (done < total) {
        fprintf(stderr, "\rmatremap report: %s %d/%d ", what, done + 1, total);
        *(int *)user = 1;
    }
    return 0;
}

/* The mean figures of every input, the object's first and the whole frame's beside them, and the page. */
static void print_result(const mr_report_result *r, const char *dir) {
    printf("%-24s %11s %16s %10s %15s %9s\n", "material", "object SSIM", "object rel. RMSE", "frame SSIM",
           "frame rel. RMSE", "render s");
    for (int k = 0; k < r->material_count; k++) {
        const mr_report_figures *f = &r->materials[k];
        printf("%-24s %11.4f %16.4f %10.4f %15.4f %9.3f%s\n", f->label, f->mean_object_ssim,
               f->mean_object_relative_rmse, f->mean_ssim, f->mean_relative_rmse, f->seconds,
               k == 0 ? "  (reference)" : "");
    }
    printf("report: %s/index.html\n", dir);
}

/* The same as one JSON object (--json). */
static void print_json(const mr_report_result *r, const char *dir, double seconds) {
    char path[4096 + 16];
    printf("{\"command\": \"report\", \"output\": ");
    cli_json_string(stdout, dir);
    snprintf(path, sizeof path, "%s/index.html", dir);
    printf(", \"page\": ");
    cli_json_string(stdout, path);
    snprintf(path, sizeof path, "%s/summary.json", dir);
    printf(", \"summary\": ");
    cli_json_string(stdout, path);
    printf(", \"views\": %d, \"exposure\": %.9g, \"env_scale\": %.9g, \"materials\": [", r->view_count,
           r->exposure, r->env_scale);
    for (int k = 0; k < r->material_count; k++) {
        const mr_report_figures *f = &r->materials[k];
        printf("%s{\"label\": ", k ? ", " : "");
        cli_json_string(stdout, f->label);
        printf(", \"reference\": %s, \"object_ssim\": %.6f, \"object_relative_rmse\": %.6f, \"ssim\": %.6f, "
               "\"relative_rmse\": %.6f, \"seconds\": %.6f}", k == 0 ? "true" : "false", f->mean_object_ssim,
               f->mean_object_relative_rmse, f->mean_ssim, f->mean_relative_rmse, f->seconds);
    }
    printf("], \"seconds\": %.6f}\n", seconds);
}

int cmd_report(int argc, char **argv) {
    const double started = cli_now();
    for (int i = 1; i < argc; i++)
        if (cli_is_help(argv[i])) {
            print_help();
            return CLI_EXIT_OK;
        }
    options o;
    memset(&o, 0, sizeof o);
    static group groups[MAX_MATERIALS]; // large (assignments): kept off the stack
    int count = 0;
    int code = parse(argc, argv, &o, groups, &count);
    if (code != CLI_EXIT_OK) return code;
    // Inputs are all materials on the sphere, or all glTF assets (rendered as their meshes).
    int gltf_entries = 0;
    for (int k = 0; k < count; k++) gltf_entries += cli_is_gltf_path(groups[k].model_name);
    if (gltf_entries > 0 && gltf_entries < count)
        return cli_usage_error("report", "give either materials (MODEL name=value ...) or glTF assets, not both");
    for (int k = 0; gltf_entries > 0 && k < count; k++)
        if (groups[k].count > 0)
            return cli_usage_error("report", "'%s': a glTF asset takes no name=value parameters",
                                   groups[k].assignments[0]);
    if (o.mesh_path != NULL && gltf_entries > 0)
        return cli_usage_error("report", "--mesh renders materials (MODEL name=value ...); glTF assets bring their "
                               "own triangles");
    if (o.report.has_camera_direction && gltf_entries == 0)
        return cli_usage_error("report", "--camera-direction places the camera for glTF assets; spheres use the fit "
                               "camera");

    // Nothing read may lie in the folder: the report replaces it as a whole (report.h, "The folder").
    mr_output_plan io = {0};
    for (int k = 0; k < count; k++) {
        if (gltf_entries > 0) mr_output_plan_inputf(&io, groups[k].model_name, "asset %s", groups[k].model_name);
        cli_plan_material(&io, groups[k].assignments, NULL, groups[k].count);
    }
    if (o.report.env_path != NULL) mr_output_plan_inputf(&io, o.report.env_path, "--env %s", o.report.env_path);
    if (o.mesh_path != NULL) mr_output_plan_inputf(&io, o.mesh_path, "--mesh %s", o.mesh_path);
    mr_output_plan_output_folder(&io, o.dir, NULL);
    code = cli_plan_check("report", &io);
    if (code != CLI_EXIT_OK) {
        mr_output_plan_free(&io);
        return code;
    }

    mr_obj_mesh *obj = NULL;
    const mr_camera paper = mr_camera_paper();
    if (o.mesh_path != NULL) {
        mr_status status = mr_obj_load(o.mesh_path, NULL, &obj);
        if (status != MR_OK) {
            mr_output_plan_free(&io);
            return cli_fail("report", status);
        }
        if (obj->warnings[0] != '\0')
            fprintf(stderr, "matremap report: warning: OBJ '%s': %s", o.mesh_path, obj->warnings);
        o.report.mesh = &obj->mesh;
        o.report.mesh_name = o.mesh_path;
        if (o.paper_camera) o.report.camera = &paper;
    }
    mr_material *materials[MAX_MATERIALS] = {NULL};
    mr_gltf_scene *scenes[MAX_MATERIALS] = {NULL};
    mr_external_material *owns[MAX_MATERIALS] = {NULL};
    cli_renderers renderers[2]; // blender's, three's: one each for every group that names it
    memset(renderers, 0, sizeof renderers);
    static char descriptions[MAX_MATERIALS][2048];
    mr_report_input inputs[MAX_MATERIALS];
    for (int k = 0; k < count && code == CLI_EXIT_OK; k++) {
        const group *g = &groups[k];
        const int own = strncmp(g->model_name, "blender:", 8) == 0;
        const char *renderer_name = own && g->renderer == NULL ? "blender" : g->renderer;
        mr_renderer *renderer = NULL;
        if (gltf_entries > 0) { // the asset's files noted as inputs on the way
            code = cli_gltf_scene_load("report", g->model_name, &io, &scenes[k]);
        } else if (!own) {
            code = cli_material_load("report", g->model_name, g->assignments, g->count, &materials[k]);
            cli_material_note_invalid_texels("report", materials[k]);
            describe(g, descriptions[k], sizeof descriptions[k]);
        }
        if (code == CLI_EXIT_OK && renderer_name != NULL && strcmp(renderer_name, "builtin") != 0) {
            code = report_renderer("report", renderers, renderer_name, o.samples, materials[k], &renderer);
            if (code == CLI_EXIT_OK && own) {
                mr_status status = mr_renderer_describe(renderer, g->model_name + 8, &owns[k]);
                if (status != MR_OK) code = cli_fail("report", status);
                for (int a = 0; code == CLI_EXIT_OK && a < g->count; a++)
                    code = cli_set_material_input("report", owns[k], g->assignments[a]);
            }
            if (code == CLI_EXIT_OK) {
                describe(g, descriptions[k], sizeof descriptions[k]);
                size_t used = strlen(descriptions[k]);
                snprintf(descriptions[k] + used, sizeof descriptions[k] - used, " (rendered by %s)",
                         renderer == renderers[0].opened[0] ? renderers[0].versions[0] : renderers[1].versions[0]);
            }
        }
        // A scene's description (its triangles and materials) is made by the library.
        inputs[k] = (mr_report_input){g->label, gltf_entries > 0 ? NULL : descriptions[k], materials[k], scenes[k],
                                      renderer, owns[k]};
    }
    if (code == CLI_EXIT_OK) code = cli_plan_check("report", &io); // with the assets' buffers and images
    mr_output_plan_free(&io);
    if (code == CLI_EXIT_OK) {
        int progress_shown = 0;
        if (isatty(STDERR_FILENO)) {
            o.report.progress = show_progress;
            o.report.progress_user = &progress_shown;
        }
        mr_report_result *result = NULL;
        mr_status status = mr_report_make(inputs, count, o.dir, &o.report, &result);
        if (progress_shown) fputc('\n', stderr);
        if (status == MR_OK && o.json)
            print_json(result, o.dir, cli_now() - started);
        else if (status == MR_OK)
            print_result(result, o.dir);
        else
            code = cli_fail("report", status);
        mr_report_result_free(result);
    }
    for (int k = 0; k < count; k++) {
        mr_material_free(materials[k]);
        mr_gltf_scene_free(scenes[k]);
        mr_external_material_free(owns[k]);
    }
    cli_close_renderers(&renderers[0]);
    cli_close_renderers(&renderers[1]);
    mr_obj_mesh_free(obj);
    return code;
}
