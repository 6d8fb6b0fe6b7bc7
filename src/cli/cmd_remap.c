/*
 * cmd_remap.c — `matremap remap`: fit a target model to a built-in source material, or to renders of the fit
 * scene made by any renderer (remap.h has the method and the outcome definitions).
 */
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "remap/remap.h"
#include "remap/translate.h"

#define MAX_ASSIGNMENTS 64

static void print_help(void) {
    printf("Usage: matremap remap --from MODEL [name=value ...] --to MODEL [name=value ...] [options]\n"
           "       matremap remap --from MODEL [name=value ...] --to MODEL --method materialx [options]\n"
           "       matremap remap --from-images FULL.exr [--diffuse D.exr --specular S.exr]\n"
           "                      [--match-irradiance REF.exr] --to MODEL [options]\n"
           "\n"
           "Finds the parameters of the target model whose render of the fit scene (a unit sphere under a point\n"
           "light, Sztrajman et al. 2019, section 4.1) matches the source's, by minimising the L2 difference of\n"
           "linear HDR images. Prints the target parameters, the final RMSE and SSIM, the number of renders, the\n"
           "wall time, and how the fit ended:\n"
           "  converged      the fit is good (residual below 25 %% of the source's RMS radiance)\n"
           "  at-bound       a parameter ends on its range's edge: the source wants more than the target allows\n"
           "  unreachable    the target cannot reproduce the source (e.g. Ward's energy trimming engages)\n"
           "  local-minimum  the fit is trapped or ambiguous (see the detail line)\n"
           "\n"
           "Source:\n"
           "  --from MODEL [name=value ...]   a built-in model; unnamed parameters keep their defaults\n"
           "  --from blender:FILE.blend:MATERIAL ['NODE.SOCKET=value' ...]\n"
           "                                  a material of a .blend file rendered by Blender (any node tree);\n"
           "                                  its unlinked float and colour inputs can be set (r,g,b for a colour);\n"
           "                                  the inputs it exposes are listed by --list-inputs\n"
           "  --from-images FULL              renders of the fit scene by another renderer (linear EXR/HDR, square,\n"
           "                                  top row up; docs/cycles-peer.md explains how to make them)\n"
           "  --diffuse FILE, --specular FILE its diffuse-only and specular-only renders (for --strategy two/three)\n"
           "  --match-irradiance REF          that renderer's diffuse-only render of a Lambertian sphere of albedo\n"
           "                                  0.5 (see --reference-albedo) in the same scene: the source images are\n"
           "                                  scaled by matremap's Lambert render / REF (paper section 4)\n"
           "  --reference-albedo A            the albedo of that reference sphere (default 0.5)\n"
           "\n"
           "Target:\n"
           "  --to MODEL [name=value ...]     values given here hold fixed parameters (e.g. glTF's ior) and\n"
           "                                  switches (Ward's trim) at those values, and start the others\n"
           "  --hold NAME[=VALUE][,...]       hold these target parameters at VALUE (or their given or default\n"
           "                                  values) instead of fitting them, e.g. a roughness both models\n"
           "                                  share; the model's own default holds (extension factors, coats,\n"
           "                                  what a fit scene cannot separate: 'matremap models MODEL') are\n"
           "                                  held too, and the result's 'held:' line lists every hold used\n"
           "  --free NAME[,...]               fit these parameters although the target holds them by default, e.g.\n"
           "                                  --to gltf --free specular_color: KHR_materials_specular's colour\n"
           "                                  factor for a highlight brighter than a 4 %% dielectric's (engines\n"
           "                                  without the extension show the core values only)\n");
    printf("  --tie TARGET=SOURCE[,...]|none  hold target parameters at the source's value instead of fitting them;\n"
           "                                  default: what the source states, a metalness (which the fit scene\n"
           "                                  cannot tell from the base colour at high roughness) and the IOR,\n"
           "                                  coat and specular tint the target holds (standard-surface -> gltf:\n"
           "                                  metallic=metalness, specular_color=specular_color, ior=specular_ior);\n"
           "                                  a 'tied:' line says which (docs/remap.md, \"Ties\")\n"
           "\n");
    printf("Method:\n"
           "  --method fit        (default) fit the target by images, as above\n"
           "  --method materialx  no fit: MaterialX 1.39.5's closed-form translation graph for the pair\n"
           "                      (libraries/bxdf/translation): standard-surface -> gltf, standard-surface ->\n"
           "                      usd-preview, openpbr -> standard-surface; other pairs are refused. Prints the\n"
           "                      translated values, what the graph does not carry, and the RMSE and SSIM of\n"
           "                      its render against the source's in the fit scene (--size, --light, --images\n"
           "                      as for a fit; no name=value after --to, --hold, --tie, --strategy,\n"
           "                      --grid-points); a baseline beside the fit (docs/remap.md,\n"
           "                      docs/evaluation-translations.md)\n"
           "\n"
           "Options:\n"
           "  --strategy S       auto (default): affine parameters solved exactly, each lobe's roughness\n"
           "                     searched globally against that lobe's render (smooth across materials);\n"
           "                     joint: the same search against the full render only (lowest L2 error);\n"
           "                     single, two, three: the paper's local fits from the defaults\n"
           "  --local M          the local stage: auto (default: gradient for auto and joint where the\n"
           "                     target model has analytic derivatives, bobyqa for the paper's strategies),\n"
           "                     gradient (Levenberg-Marquardt on the image residual with the model's\n"
           "                     derivatives) or bobyqa (derivative-free, one render per trial)\n"
           "  --size N           fit-scene side in pixels (default %d; with --from-images: the images' size)\n"
           "  --grid-points N    auto/joint: global grid points per nonlinear parameter (default 16 for one,\n"
           "                     8 for two, 6 for three; more is slower and misses fewer narrow minima)\n"
           "  --light L          45 (default) or frontal\n"
           "  --threads N        OpenMP threads of the fit's renders (default 0: automatic, one thread at the\n"
           "                     default size, where a team costs more than it saves; copies run side by side)\n"
           "  --images PREFIX    also write PREFIX_source.png, PREFIX_target.png and PREFIX_ssim.png (no '_'\n"
           "                     after a PREFIX ending in '/', '_', '-' or '.': --images out/ writes out/source.png)\n"
           "  --list-inputs      with --from blender:FILE.blend:MATERIAL: list the material's inputs and stop\n"
           "  --json             machine-readable result on stdout\n"
           "  --help             this text\n"
           "\n",
           MR_REMAP_DEFAULT_SIZE);
    cli_renderers_help(stdout);
    printf("\n"
           "Examples:\n"
           "  matremap remap --from as f0=0.9 alpha=0.05 --to ward\n"
           "  matremap remap --from ggx-plastic ior=1.3 diffuse=0.5 alpha=0.1 --to ward --strategy single --json\n"
           "  matremap remap --from-images cycles.exr --match-irradiance cycles_lambert.exr --to ggx\n"
           "  matremap remap --from standard-surface metalness=1 base_color=0.944,0.776,0.373 --to gltf \\\n"
           "      --method materialx\n"
           "  matremap remap --from blender:data/blender/node_materials.blend:DiffuseGlossyAdd --to gltf\n"
           "  matremap remap --from gltf base_color=0.8,0.1,0.1 roughness=0.3 --to gltf --to-renderer three\n");
}

/* Print the packed values of `model` as name=value words (RGB as r,g,b), the form other commands accept. */
static void print_values(FILE *out, const mr_brdf_model *model, const double *values, int json) {
    for (int i = 0; i < model->param_count; i++) {
        const mr_brdf_param *p = &model->params[i];
        int offset = mr_brdf_param_offset(model, i);
        if (json) {
            fprintf(out, "%s", i ? ", " : "");
            cli_json_string(out, p->name);
            if (p->channels == 3)
                fprintf(out, ": [%.17g, %.17g, %.17g]", values[offset], values[offset + 1], values[offset + 2]);
            else
                fprintf(out, ": %.17g", values[offset]);
        } else if (p->channels == 3) {
            fprintf(out, " %s=%.6g,%.6g,%.6g", p->name, values[offset], values[offset + 1], values[offset + 2]);
        } else {
            fprintf(out, " %s=%.6g", p->name, values[offset]);
        }
    }
}

/* --method materialx: MaterialX's translation graph (translate.h) instead of a fit, measured in the fit scene. */
/* The three pictures of --images PREFIX (source, target, SSIM map) as outputs of the plan; none without it. */
static void plan_pictures(mr_output_plan *io, const char *images_prefix) {
    for (int k = 0; images_prefix != NULL && k < 3; k++) {
        char path[4096];
        mr_remap_picture_path(images_prefix, k, path, sizeof path); // an overlong prefix: refused by the write
        mr_output_plan_outputf(io, path, "--images %s", images_prefix);
    }
}

static int run_materialx(const mr_brdf_model *from, const double *source_values, const mr_brdf_model *to, int size,
                         mr_fit_scene_options *scene_opts, const char *images_prefix, int json) {
    const mr_translation *t = NULL;
    if (mr_translate_find(from, to, &t) != MR_OK)
        return cli_usage_error("remap", "--method materialx: %s", mr_last_error());
    mr_output_plan io = {0};
    plan_pictures(&io, images_prefix);
    int exit_code = cli_plan_check("remap", &io);
    mr_output_plan_free(&io);
    if (exit_code != CLI_EXIT_OK) return exit_code;

    scene_opts->size = size > 0 ? size : MR_REMAP_DEFAULT_SIZE;
    mr_scene scene = mr_scene_fit(scene_opts);
    mr_render_plan *plan = NULL;
    mr_image *source = NULL;
    mr_translate_result r;
    mr_status status = mr_render_plan_create(&scene, &plan);
    if (status == MR_OK) status = mr_translate_compare(plan, from, source_values, to, &r);
    if (status == MR_OK && images_prefix != NULL) {
        status = mr_render(plan, from, source_values, MR_COMPONENT_FULL, &source);
        if (status == MR_OK) status = mr_remap_write_pictures(images_prefix, plan, source, to, r.values);
    }
    mr_image_free(source);
    mr_render_plan_free(plan);
    if (status != MR_OK) return cli_fail("remap", status);

    const char *light = mr_fit_light_name(scene_opts->light);
    if (json) {
        printf("{\"to\": ");
        cli_json_string(stdout, to->name);
        printf(", \"from\": {\"model\": ");
        cli_json_string(stdout, from->name);
        printf(", \"values\": {");
        print_values(stdout, from, source_values, 1);
        printf("}}, \"method\": \"materialx\", \"graph\": ");
        cli_json_string(stdout, t->graph);
        printf(", \"file\": ");
        cli_json_string(stdout, t->file);
        printf(", \"materialx\": \"%s\", \"not_carried\": ", MR_TRANSLATE_MATERIALX_VERSION);
        cli_json_string(stdout, t->dropped);
        printf(", \"size\": %d, \"light\": \"%s\", \"values\": {", scene_opts->size, light);
        print_values(stdout, to, r.values, 1);
        printf("}, \"rmse\": %.17g, \"relative_rmse\": %.17g, \"ssim\": %.17g, \"seconds\": %.6f}\n", r.rmse,
               r.relative_rmse, r.ssim, r.seconds);
    } else {
        printf("%s", to->name);
        print_values(stdout, to, r.values, 0);
        printf("\n");
        printf("method: materialx (%s, MaterialX %s %s)\n", t->graph, MR_TRANSLATE_MATERIALX_VERSION, t->file);
        printf("not carried: %s\n", t->dropped);
        printf("RMSE %.6g (%.3g %% of the source's RMS radiance), SSIM %.6f, %.1f ms, fit scene %d², light %s\n",
               r.rmse, 100.0 * r.relative_rmse, r.ssim, 1e3 * r.seconds, scene_opts->size, light);
    }
    return CLI_EXIT_OK;
}

/* --free NAME[,...]: parameters `model` holds by default, fitted; an exit code. */
static int parse_freed(const mr_brdf_model *model, const char *list, unsigned *freed) {
    char copy[1024];
    if (strlen(list) >= sizeof copy) return cli_usage_error("remap", "--free: list too long");
    memcpy(copy, list, strlen(list) + 1);
    char *save = NULL;
    for (char *name = strtok_r(copy, ",", &save); name != NULL; name = strtok_r(NULL, ",", &save)) {
        const int p = mr_brdf_param_index(model, name);
        if (p < 0 || p >= 32)
            return cli_usage_error("remap", "--free %s: '%s' has no parameter '%s'", list, model->name, name);
        if (!(model->params[p].flags & MR_PARAM_FIT_FIXED))
            return cli_usage_error("remap", "--free %s: '%s' fits %s already ('matremap models %s' lists what it "
                                   "holds)", list, model->name, name, model->name);
        *freed |= 1u << p;
    }
    return CLI_EXIT_OK;
}

/* --list-inputs: a .blend material's inputs, their ranges and values. */
static int list_material_inputs(const char *reference, cli_renderers *renderers, int json) {
    int exit_code = cli_open_renderers("remap", renderers, NULL, NULL, 1);
    if (exit_code != CLI_EXIT_OK) return exit_code;
    mr_external_material *material = NULL;
    mr_status status = mr_renderer_describe(renderers->opened[0], reference, &material);
    if (status != MR_OK) {
        exit_code = cli_fail("remap", status);
    } else if (json) {
        printf("{\"material\": ");
        cli_json_string(stdout, reference);
        printf(", \"renderer\": ");
        cli_json_string(stdout, renderers->versions[0]);
        printf(", \"inputs\": [");
        for (int k = 0; k < mr_external_material_param_count(material); k++) {
            int channels = 0;
            double lo, hi, v[3];
            const char *path = mr_external_material_param(material, k, &channels, &lo, &hi, v);
            printf("%s{\"path\": ", k ? ", " : "");
            cli_json_string(stdout, path);
            printf(", \"kind\": \"%s\", \"min\": %.17g, \"max\": %.17g, \"value\": ",
                   channels == 3 ? "color" : "float", lo, hi);
            if (channels == 3)
                printf("[%.17g, %.17g, %.17g]}", v[0], v[1], v[2]);
            else
                printf("%.17g}", v[0]);
        }
        printf("]}\n");
    } else {
        printf("%s (%s): %d input%s\n", reference, renderers->versions[0], mr_external_material_param_count(material),
               mr_external_material_param_count(material) == 1 ? "" : "s");
        for (int k = 0; k < mr_external_material_param_count(material); k++) {
            int channels = 0;
            double lo, hi, v[3];
            const char *path = mr_external_material_param(material, k, &channels, &lo, &hi, v);
            if (channels == 3)
                printf("  '%s=%g,%g,%g'  colour\n", path, v[0], v[1], v[2]);
            else
                if (lo < -1e30 && hi > 1e30)
                    printf("  '%s=%g'  any number\n", path, v[0]);
                else
                    printf("  '%s=%g'  [%g, %g]\n", path, v[0], lo, hi);
        }
    }
    mr_external_material_free(material);
    cli_close_renderers(renderers);
    return exit_code;
}

int cmd_remap(int argc, char **argv) {
    const char *from_name = NULL, *to_name = NULL, *images_prefix = NULL;
    const char *image_paths[3] = {NULL, NULL, NULL}; /* full, diffuse, specular */
    const char *reference_path = NULL, *hold_list = NULL, *tie_list = NULL, *free_list = NULL;
    double reference_albedo = 0.5;
    const char *from_assignments[MAX_ASSIGNMENTS], *to_assignments[MAX_ASSIGNMENTS];
    int from_count = 0, to_count = 0, json = 0, size = 0, materialx = 0, fit_option = 0, list_inputs = 0;
    cli_renderers renderers;
    memset(&renderers, 0, sizeof renderers);
    mr_fit_scene_options scene_opts = {0};
    mr_remap_options opts = mr_remap_options_default();
    enum { NONE, FROM, TO } collecting = NONE;

    for (int i = 1; i < argc; i++) {
        const char *value = NULL;
        int taken;
        if (cli_is_help(argv[i])) {
            print_help();
            return CLI_EXIT_OK;
        }
        if ((taken = cli_take_option("remap", argc, argv, &i, "--from", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            from_name = value;
            collecting = FROM;
        } else if ((taken = cli_take_option("remap", argc, argv, &i, "--to", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            to_name = value;
            collecting = TO;
        } else if ((taken = cli_take_option("remap", argc, argv, &i, "--from-images", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            image_paths[0] = value;
            collecting = NONE;
        } else if ((taken = cli_take_option("remap", argc, argv, &i, "--diffuse", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            image_paths[1] = value;
        } else if ((taken = cli_take_option("remap", argc, argv, &i, "--specular", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            image_paths[2] = value;
        } else if ((taken = cli_take_option("remap", argc, argv, &i, "--match-irradiance", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            reference_path = value;
        } else if ((taken = cli_take_option("remap", argc, argv, &i, "--reference-albedo", &value))) {
            if (taken < 0 || !cli_parse_double("remap", "--reference-albedo", value, 1e-3, 1.0, &reference_albedo))
                return CLI_EXIT_USAGE;
        } else if ((taken = cli_take_option("remap", argc, argv, &i, "--strategy", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            if (mr_remap_strategy_from_name(value, &opts.strategy) != MR_OK)
                return cli_usage_error("remap", "%s", mr_last_error());
            fit_option = 1;
        } else if ((taken = cli_take_option("remap", argc, argv, &i, "--local", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            if (mr_local_method_from_name(value, &opts.local_method) != MR_OK)
                return cli_usage_error("remap", "--local: %s", mr_last_error());
            fit_option = 1;
        } else if ((taken = cli_take_option("remap", argc, argv, &i, "--method", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            if (strcmp(value, "fit") != 0 && strcmp(value, "materialx") != 0)
                return cli_usage_error("remap", "--method '%s': expected fit or materialx", value);
            materialx = strcmp(value, "materialx") == 0;
        } else if ((taken = cli_take_option("remap", argc, argv, &i, "--threads", &value))) {
            if (taken < 0 || !cli_parse_int("remap", "--threads", value, 0, 1024, &opts.threads)) return CLI_EXIT_USAGE;
        } else if ((taken = cli_take_option("remap", argc, argv, &i, "--size", &value))) {
            if (taken < 0 || !cli_parse_int("remap", "--size", value, 16, 4096, &size)) return CLI_EXIT_USAGE;
        } else if ((taken = cli_take_option("remap", argc, argv, &i, "--tie", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            tie_list = value;
            fit_option = 1;
        } else if ((taken = cli_take_option("remap", argc, argv, &i, "--hold", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            hold_list = value;
            fit_option = 1;
        } else if ((taken = cli_take_option("remap", argc, argv, &i, "--free", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            free_list = value;
            fit_option = 1;
        } else if ((taken = cli_take_option("remap", argc, argv, &i, "--grid-points", &value))) {
            if (taken < 0 || !cli_parse_int("remap", "--grid-points", value, 2, 64, &opts.grid_points))
                return CLI_EXIT_USAGE;
            fit_option = 1;
        } else if ((taken = cli_take_option("remap", argc, argv, &i, "--light", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            if (mr_fit_light_from_name(value, &scene_opts.light) != MR_OK)
                return cli_usage_error("remap", "%s", mr_last_error());
        } else if ((taken = cli_take_option("remap", argc, argv, &i, "--images", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            images_prefix = value;
        } else if ((taken = cli_take_renderer_option("remap", argc, argv, &i, &renderers))) {
            if (taken < 0) return CLI_EXIT_USAGE;
        } else if (strcmp(argv[i], "--list-inputs") == 0) {
            list_inputs = 1;
        } else if (strcmp(argv[i], "--json") == 0) {
            json = 1;
        } else if (argv[i][0] == '-') {
            return cli_usage_error("remap", "unknown option '%s'", argv[i]);
        } else if (strchr(argv[i], '=') != NULL && collecting != NONE) {
            int *count = collecting == FROM ? &from_count : &to_count;
            if (*count == MAX_ASSIGNMENTS) return cli_usage_error("remap", "too many parameter assignments");
            (collecting == FROM ? from_assignments : to_assignments)[(*count)++] = argv[i];
        } else {
            return cli_usage_error("remap", "unexpected argument '%s' (parameters follow --from MODEL or --to MODEL "
                                   "as name=value)", argv[i]);
        }
    }
    // --from blender:FILE.blend:MATERIAL: a material of Blender's own, rendered by Blender.
    const char *external = NULL;
    if (from_name != NULL && strncmp(from_name, "blender:", 8) == 0) {
        external = from_name + 8;
        if (renderers.names[0] != NULL && strcmp(renderers.names[0], "blender") != 0)
            return cli_usage_error("remap", "--from %s is rendered by blender, not --from-renderer %s", from_name,
                                   renderers.names[0]);
        renderers.names[0] = "blender";
    }
    if (list_inputs && external == NULL)
        return cli_usage_error("remap", "--list-inputs goes with --from blender:FILE.blend:MATERIAL");
    if (list_inputs) return list_material_inputs(external, &renderers, json);
    if (to_name == NULL) return cli_usage_error("remap", "missing --to MODEL");
    if ((from_name == NULL) == (image_paths[0] == NULL))
        return cli_usage_error("remap", "give exactly one source: --from MODEL or --from-images FULL.exr");
    if (from_name != NULL && (image_paths[1] || image_paths[2] || reference_path))
        return cli_usage_error("remap", "--diffuse, --specular and --match-irradiance go with --from-images");
    if ((image_paths[1] == NULL) != (image_paths[2] == NULL))
        return cli_usage_error("remap", "give both --diffuse and --specular, or neither");
    if (materialx && from_name == NULL)
        return cli_usage_error("remap", "--method materialx translates a model's values: give --from MODEL");
    if (materialx && (renderers.names[0] || renderers.names[1]))
        return cli_usage_error("remap", "--method materialx is a closed-form translation measured by the built-in "
                               "renderer: --from-renderer and --to-renderer go with --method fit");
    if (materialx && (fit_option || to_count > 0))
        return cli_usage_error("remap", "--method materialx sets every target parameter from its graph: --hold, "
                               "--tie, --strategy, --grid-points and name=value after --to go with --method fit");

    const mr_brdf_model *to = mr_brdf_find(to_name);
    if (to == NULL) return cli_fail("remap", MR_ERR_INVALID_ARG);
    double target_values[MR_BRDF_MAX_VALUES];
    mr_brdf_default_values(to, target_values);
    for (int k = 0; k < to_count; k++) {
        mr_status status = mr_brdf_parse_assignment(to, to_assignments[k], target_values);
        if (status != MR_OK) return cli_fail("remap", status);
    }
    opts.target_values = target_values;
    if (hold_list != NULL && !cli_parse_held("remap", to, hold_list, target_values, &opts.held))
        return CLI_EXIT_USAGE;
    if (free_list != NULL) {
        int freed_code = parse_freed(to, free_list, &opts.freed);
        if (freed_code != CLI_EXIT_OK) return freed_code;
    }

    const mr_brdf_model *from = NULL;
    double source_values[MR_BRDF_MAX_VALUES];
    if (external != NULL) {
        if (tie_list != NULL)
            return cli_usage_error("remap", "--tie needs --from MODEL (a material of Blender's own has no model "
                                   "values to tie to)");
    } else if (from_name != NULL) {
        from = mr_brdf_find(from_name);
        if (from == NULL) return cli_fail("remap", MR_ERR_INVALID_ARG);
        mr_brdf_default_values(from, source_values);
        for (int k = 0; k < from_count; k++) {
            mr_status status = mr_brdf_parse_assignment(from, from_assignments[k], source_values);
            if (status != MR_OK) return cli_fail("remap", status);
        }
        if (!cli_parse_ties("remap", from, to, tie_list, opts.held, &opts.ties)) return CLI_EXIT_USAGE;
    } else if (tie_list != NULL) {
        return cli_usage_error("remap", "--tie needs --from MODEL (a tie takes the source's value)");
    }
    if (materialx) return run_materialx(from, source_values, to, size, &scene_opts, images_prefix, json);

    // Nothing written over a file read: --images PREFIX's pictures against the renders.
    static const char *const image_options[3] = {"--from-images", "--diffuse", "--specular"};
    mr_output_plan io = {0};
    for (int k = 0; k < 3; k++)
        if (image_paths[k]) mr_output_plan_inputf(&io, image_paths[k], "%s %s", image_options[k], image_paths[k]);
    if (reference_path) mr_output_plan_inputf(&io, reference_path, "--match-irradiance %s", reference_path);
    plan_pictures(&io, images_prefix);
    int exit_code = cli_plan_check("remap", &io);
    mr_output_plan_free(&io);
    if (exit_code != CLI_EXIT_OK) return exit_code;
    // The renderers start before any work, so a missing one fails at once.
    if ((exit_code = cli_open_renderers("remap", &renderers, from, to, 1)) != CLI_EXIT_OK) return exit_code;
    opts.source_renderer = renderers.opened[0];
    opts.target_renderer = renderers.opened[1];
    mr_external_material *material = NULL;
    if (external != NULL) {
        mr_status status = mr_renderer_describe(renderers.opened[0], external, &material);
        if (status != MR_OK) exit_code = cli_fail("remap", status);
        for (int k = 0; exit_code == CLI_EXIT_OK && k < from_count; k++)
            exit_code = cli_set_material_input("remap", material, from_assignments[k]);
        if (exit_code != CLI_EXIT_OK) {
            mr_external_material_free(material);
            cli_close_renderers(&renderers);
            return exit_code;
        }
    }

    // Source images (black-box renders) decide the scene size; they must all agree and be square.
    mr_image *images[3] = {NULL, NULL, NULL}, *reference = NULL;
    mr_status status = mr_remap_read_sources(image_paths, reference_path, images, &reference);
    if (status != MR_OK) exit_code = cli_fail("remap", status);
    if (images[0] != NULL) size = images[0]->width;
    mr_render_plan *plan = NULL;
    mr_remap_result result;
    double irradiance_scale = 1.0;
    if (exit_code == CLI_EXIT_OK) {
        scene_opts.size = size > 0 ? size : MR_REMAP_DEFAULT_SIZE;
        mr_scene scene = mr_scene_fit(&scene_opts);
        status = mr_render_plan_create(&scene, &plan);
        if (status == MR_OK && reference != NULL) {
            status = mr_irradiance_scale(plan, reference, reference_albedo, &irradiance_scale);
            for (int k = 0; k < 3 && status == MR_OK; k++) mr_image_scale(images[k], irradiance_scale);
        }
        if (status == MR_OK && material != NULL) { // a material of Blender's own: its renders are the source
            status = mr_image_create(scene_opts.size, scene_opts.size, 3, &images[0]); // kept for --images
            if (status == MR_OK)
                status = mr_remap_external(plan, renderers.opened[0], material, to, &opts, &result, images[0]);
        } else if (status == MR_OK) {
            if (from != NULL) {
                status = mr_remap(plan, from, source_values, to, &opts, &result);
            } else {
                mr_remap_source source = {images[0], images[1], images[2]};
                status = mr_remap_images(plan, &source, to, &opts, &result);
            }
        }
        if (status == MR_OK && images_prefix != NULL) {
            if (images[0] == NULL) { // a model source: rendered again, by its renderer
                status = mr_image_create(scene_opts.size, scene_opts.size, 3, &images[0]);
                if (status == MR_OK)
                    status = mr_renderer_is_builtin(opts.source_renderer)
                                 ? mr_render_into(plan, from, source_values, MR_COMPONENT_FULL, images[0])
                                 : mr_renderer_render(opts.source_renderer, plan, from, source_values, images[0],
                                                      NULL, NULL);
            }
            if (status == MR_OK)
                status = mr_remap_write_pictures_by(images_prefix, plan, images[0], opts.target_renderer, to,
                                                    result.values);
        }
        if (status != MR_OK) exit_code = cli_fail("remap", status);
    }

    if (exit_code == CLI_EXIT_OK) {
        const char *strategy = mr_remap_strategy_name(opts.strategy);
        if (json) {
            printf("{\"to\": ");
            cli_json_string(stdout, to->name);
            printf(", \"from\": ");
            if (from != NULL) {
                printf("{\"model\": ");
                cli_json_string(stdout, from->name);
                printf(", \"values\": {");
                print_values(stdout, from, source_values, 1);
                printf("}}");
            } else if (material != NULL) {
                printf("{\"material\": ");
                cli_json_string(stdout, external);
                printf(", \"inputs\": ");
                cli_print_material_inputs_json(stdout, material);
                printf("}");
            } else {
                printf("{\"images\": ");
                cli_json_string(stdout, image_paths[0]);
                printf(", \"irradiance_scale\": %.17g}", irradiance_scale);
            }
            printf(", \"strategy\": \"%s\", \"local_method\": \"%s\", \"size\": %d, \"light\": \"%s\", \"values\": {",
                   strategy, mr_local_method_name(result.local_method), scene_opts.size,
                   mr_fit_light_name(scene_opts.light));
            print_values(stdout, to, result.values, 1);
            printf("}, \"rmse\": %.17g, \"relative_rmse\": %.17g, \"ssim\": %.17g, \"renders\": %ld, "
                   "\"seconds\": %.6f, \"outcome\": \"%s\", \"detail\": ",
                   result.rmse, result.relative_rmse, result.ssim, result.renders, result.seconds,
                   mr_fit_outcome_name(result.outcome));
            cli_json_string(stdout, result.detail);
            if (from != NULL) {
                printf(", \"tied\": ");
                cli_print_ties_json(stdout, from, to, &opts.ties, tie_list != NULL);
            }
            printf(", \"held\": ");
            cli_print_holds_json(stdout, to, target_values, opts.held, opts.ties.tied | opts.freed);
            printf(", \"freed\": [");
            for (int p = 0, first = 1; p < to->param_count && p < 32; p++)
                if ((opts.freed >> p) & 1u) {
                    printf("%s", first ? "" : ", ");
                    cli_json_string(stdout, to->params[p].name);
                    first = 0;
                }
            printf("]");
            printf(", \"renderers\": ");
            cli_print_renderers_json(stdout, &renderers);
            printf("}\n");
        } else {
            printf("%s", to->name);
            print_values(stdout, to, result.values, 0);
            printf("\n");
            printf("outcome: %s (%s)\n", mr_fit_outcome_name(result.outcome), result.detail);
            printf("RMSE %.6g (%.3g %% of the source's RMS radiance), SSIM %.6f, %ld renders, %.1f ms, strategy %s, "
                   "local %s, fit scene %d², light %s\n",
                   result.rmse, 100.0 * result.relative_rmse, result.ssim, result.renders, 1e3 * result.seconds,
                   strategy, mr_local_method_name(result.local_method), scene_opts.size,
                   mr_fit_light_name(scene_opts.light));
            if (reference != NULL) printf("irradiance scale applied to the source images: %.6g\n", irradiance_scale);
            cli_print_holds_tied(stdout, NULL, to, target_values, opts.held, opts.ties.tied | opts.freed);
            for (int p = 0, first = 1; p < to->param_count && p < 32; p++)
                if ((opts.freed >> p) & 1u) {
                    printf("%s%s", first ? "freed (fitted although the model holds it by default): " : ", ",
                           to->params[p].name);
                    first = 0;
                    if (p == to->param_count - 1 || (opts.freed >> (p + 1)) == 0) printf("\n");
                }
            if (from != NULL) cli_print_ties(stdout, NULL, from, to, &opts.ties, tie_list != NULL);
            if (renderers.opened[0] != NULL || renderers.opened[1] != NULL) cli_print_renderers(stdout, &renderers);
        }
    }
    mr_external_material_free(material);
    cli_close_renderers(&renderers);
    for (int k = 0; k < 3; k++) mr_image_free(images[k]);
    mr_image_free(reference);
    mr_render_plan_free(plan);
    return exit_code;
}
