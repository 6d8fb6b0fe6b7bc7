/*
 * cmd_render.c — `matremap render MODEL [name=value|name=@MAP ...] [--size N] [--light 45|frontal]
 *                [--env FILE [--env-rotation DEG] [--env-samples N] [--env-reflection-samples M] [--env-scale S]]
 *                [--mesh FILE.obj] [--camera auto|paper]
 *                [--component full|diffuse|specular] [--exposure E] [--mask FILE] [--json] -o OUT`
 *                and `matremap render ASSET.gltf|.glb [--camera-direction X,Y,Z] [the same options] -o OUT`
 * Renders a material in the paper's fit scene (render.h), or under an environment map, optionally with
 * parameters from texture maps over the sphere, and writes it in the format of OUT's extension; --mask writes
 * the plan's coverage (mr_render_plan_coverage_mask), the object mask `matremap ssim --mask` takes. --mesh puts
 * an OBJ mesh (io/obj_load.h) in the sphere's place, its maps read at the mesh's UVs; the point light then keeps
 * its place relative to the camera and the object's size (mr_scene_fit_light_to_mesh, render.h). A glTF asset in
 * MODEL's place is rendered as `matremap report` renders one (mr_gltf_scene_from_asset: its triangles, each with
 * its material), seen from report's three-quarter view (or --camera-direction), lit by the scaled point light or
 * --env.
 */
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "gltf/mr_gltf_scene.h"
#include "io/obj_load.h"

static void print_help(void) {
    printf("Usage: matremap render MODEL [name=value|name=@MAP ...] [options] -o OUT.exr|.hdr|.png|.jpg|.tif\n"
           "       matremap render ASSET.gltf|ASSET.glb [options] -o OUT.exr|.hdr|.png|.jpg|.tif\n"
           "\n"
           "Renders MODEL with the given parameters in the fit scene of Sztrajman et al. (section 4.1): a unit\n"
           "sphere at the origin, a point light (10 W/sr) at distance 3, 45 degrees from the view direction,\n"
           "black background, camera at distance 4 with a 35-degree field of view. Unnamed parameters keep\n"
           "their defaults ('matremap models MODEL' lists them); RGB parameters take name=r,g,b or one value.\n"
           "EXR and HDR files hold linear radiance; 8/16-bit formats are clamped to [0,1] and sRGB-encoded.\n"
           "\n"
           "Textures: name=@MAP takes the parameter from an image wrapped over the sphere (its centre faces the\n"
           "camera, its top row is the north pole; docs/rendering.md). Values are the model's own, read by the\n"
           "one rule of every command (the ENCODING column of 'matremap models MODEL'): colour parameters\n"
           "(diffuse, specular, f0, base colour ...) are sRGB-decoded from 8/16-bit files whatever their range,\n"
           "every other parameter is read linearly; EXR/HDR/float files are always linear. name=@MAP:linear or\n"
           ":srgb overrides the rule for one map (:srgb on a float file is an error). A scalar parameter reads a\n"
           "grey image, or one channel of a colour image chosen with name=@MAP:r, :g, :b or :a, before any\n"
           "encoding: @orm.png:g:linear (glTF packs roughness in g and metallic in b; a glTF roughness must still\n"
           "be squared into an alpha). Maps are sampled bilinearly, wrapping around the sphere and clamped at the\n"
           "poles, without mipmaps (on a --mesh: at its UVs, repeating in u and clamped in v, the same rule).\n"
           "\n"
           "Environment lighting: --env FILE lights the sphere with an equirectangular HDR map (its centre lies\n"
           "behind the sphere, straight ahead of the camera; the background stays black), sampled with a fixed\n"
           "pattern of N directions importance-sampled by luminance, the same for every pixel: no noise, a\n"
           "bias that shrinks as N grows. --env replaces the point light unless --light is also given.\n"
           "\n"
           "glTF assets: ASSET.gltf or ASSET.glb in MODEL's place renders the asset's scene as 'matremap report'\n"
           "does (docs/report.md): its triangles, each with its material (spec-gloss when the material carries it,\n"
           "else metal-rough with KHR_materials_specular and _ior), factors times textures through their samplers,\n"
           "normal, occlusion and emissive maps, single-sided backs culled; no name=value parameters. The camera\n"
           "frames the asset from a three-quarter view onto its broadest side (report's), or from --camera-direction;\n"
           "the point light keeps its place relative to the camera, scaled to the asset as for --mesh; --env,\n"
           "--env-*, --light, --size, --component, --exposure, --edge-samples, --bits and --mask work as for a\n"
           "material.\n"
           "\n");
    printf("Options:\n"
           "  -o, --output FILE     output image (required)\n"
           "  --size N              image side in pixels (default 512)\n"
           "  --light 45|frontal    point-light position (default 45)\n"
           "  --env FILE            environment map (.hdr, .exr, ...): no point light unless --light is given\n"
           "  --env-rotation DEG    turn the map about the vertical axis, counter-clockwise seen from above\n"
           "                        (default 0)\n"
           "  --env-samples N       directions of the sample pattern, 1-65536 (default %d)\n"
           "  --env-reflection-samples M\n"
           "                        M more directions per pixel around the mirror direction, combined with the\n"
           "                        pattern by MIS: smooth materials (GGX alpha < ~0.1) reflect the map instead\n"
           "                        of showing the pattern's directions as sparkles; 0-%d (default 0)\n"
           "  --env-scale S         multiply the map's radiance by S (default 1)\n"
           "  --mesh FILE.obj       render a Wavefront OBJ mesh instead of the sphere (faces of every object and\n"
           "                        group, one material; missing normals computed smooth; texture v flipped, so\n"
           "                        a map's top row lies at the file's v = 1; docs/rendering.md, \"OBJ meshes\").\n"
           "                        Maps are read at its UVs; the point light keeps its place relative to the\n"
           "                        camera, 3 bounding radii from the object, scaled to its size\n"
           "  --camera auto|paper   auto (default): the fit scene's camera for the sphere; for a mesh, looking down\n"
           "                        -z at its bounding sphere, which fills 90 %% of the 35-degree view. paper: the\n"
           "                        paper's visualisation camera, at (0,0,-1.5) looking at the origin, 40 degrees\n"
           "                        (made for its material-test sphere of radius 0.5; not for glTF assets)\n"
           "  --camera-direction X,Y,Z  glTF assets: the direction from the asset's centre to the camera (default:\n"
           "                        the three-quarter view of 'matremap report'); the camera frames its bounds\n"
           "  --component C         full, diffuse or specular (default full)\n"
           "  --exposure E          multiply radiance by E before writing (default 1)\n"
           "  --edge-samples N      silhouette pixels are box-filtered with NxN rays (default 4; 1 = pixel\n"
           "                        centres only, aliased edges); other pixels always take one ray\n"
           "  --threads N           OpenMP threads (default 0: automatic, a team only for renders of 32768 or\n"
           "                        more shading samples, e.g. 512^2; 64^2 renders on one thread)\n"
           "  --bits B              8 or 16 for PNG/TIFF, 16 (half) or 32 for EXR (default: 8, 32)\n",
           MR_ENV_DEFAULT_SAMPLES, MR_ENV_MAX_REFLECTION_SAMPLES);
    printf(
           "  --mask FILE           also write the object's coverage: one channel, the fraction of each pixel\n"
           "                        the sphere covers (1 inside, 0 outside, k/N^2 on the silhouette with\n"
           "                        --edge-samples N), lit or not, the same for every material; linear in every\n"
           "                        format (EXR keeps it exact). 'matremap ssim A B --mask FILE' compares renders\n"
           "                        over it (docs/metrics.md)\n"
           "  --renderer R          builtin (default), blender or three: render the fit scene with a real renderer\n"
           "                        (a uniform material of a model it renders by values, or with blender a\n"
           "                        material of a .blend file: MODEL = blender:FILE.blend:MATERIAL, its inputs as\n"
           "                        'NODE.SOCKET=value'); no maps, --env, --mesh or glTF asset (docs/renderers.md)\n"
           "  --samples N           the real renderer's samples per pixel (blender default %d; three: an s x s\n"
           "                        sub-pixel grid, s = floor(sqrt(N)), default %d)\n"
           "  --seed S              the real renderer's sampling seed (Blender; default 0): two seeds apart show\n"
           "                        its noise\n"
           "  --json                what was done as one JSON object on stdout (outputs, size, pixels, samples,\n"
           "                        timings) instead of the 'wrote' line on stderr\n"
           "  --help                this text\n"
           "\n"
           "Examples:\n"
           "  matremap render gltf base_color=0.8,0.2,0.1 metallic=0 roughness=0.4 -o sphere.exr\n"
           "  matremap render ggx diffuse=@d.png f0=@s.png alpha=0.2 --env studio.hdr --size 256 -o x.exr\n"
           "  matremap render ggx-metallic albedo=@base.png metallic=@orm.png:b alpha=@alpha.exr --env studio.hdr \\\n"
           "      --env-rotation 90 -o y.png\n"
           "  matremap render ward alpha=@rough.exr specular=@spec.png --mesh matsphere.obj --camera paper \\\n"
           "      --env tabac_plant_vogl.hdr --env-rotation 45 -o z.exr\n"
           "  matremap render WaterBottle.gltf --env studio.hdr --size 256 -o bottle.png\n"
           "  matremap render cycles-principled base_color=0.8,0.2,0.1 --renderer blender --size 256 -o cycles.exr\n"
           "  matremap render blender:data/blender/node_materials.blend:DiffuseGlossyAdd --renderer blender -o n.exr\n",
           MR_RENDERER_DEFAULT_SAMPLES_BLENDER, MR_RENDERER_DEFAULT_SAMPLES_THREE);
}


/* --mask FILE: the plan's coverage, one linear channel (a fraction, not a colour). */
static mr_status write_mask(const mr_render_plan *plan, const char *mask_path) {
    mr_image *mask = NULL;
    mr_img_write_options mask_opts = {0};
    mask_opts.encoding = MR_IMG_DATA;
    mr_status status = mr_render_plan_coverage_mask(plan, &mask);
    if (status == MR_OK) status = mr_img_write(mask_path, mask, &mask_opts);
    mr_image_free(mask);
    return status;
}

/* ', "outputs": [OUT, MASK]' of --json. */
static void print_outputs_json(const char *output, const char *mask_path) {
    printf(", \"outputs\": [");
    cli_json_string(stdout, output);
    if (mask_path != NULL) {
        printf(", ");
        cli_json_string(stdout, mask_path);
    }
    printf("]");
}

/* --renderer R: the fit scene rendered by an external renderer (renderer.h). */
static int render_by(const char *name, int samples, int seed, const char *model_name, int external,
                     const char *const *assignments, int assignment_count, const mr_fit_scene_options *scene_opts,
                     int edge_samples, mr_component component, double exposure, const char *output,
                     const char *mask_path, const mr_img_write_options *write_opts, int json) {
    mr_output_plan io = {0};
    if (external) {
        char file[4096];
        const char *colon = strrchr(model_name, ':');
        snprintf(file, sizeof file, "%.*s", colon ? (int)(colon - model_name) : (int)strlen(model_name), model_name);
        mr_output_plan_inputf(&io, file, "%s", model_name);
    }
    mr_output_plan_output(&io, output, NULL);
    if (mask_path != NULL) mr_output_plan_output(&io, mask_path, "--mask");
    int code = cli_plan_check("render", &io);
    mr_output_plan_free(&io);
    if (code != CLI_EXIT_OK) return code;
    mr_material *material = NULL;
    if (!external) {
        code = cli_material_load("render", model_name, assignments, assignment_count, &material);
        if (code != CLI_EXIT_OK) return code;
    }
    cli_renderers renderers;
    memset(&renderers, 0, sizeof renderers);
    renderers.names[0] = name;
    renderers.samples = samples;
    renderers.seed = (unsigned long)seed;
    code = cli_open_renderers("render", &renderers, material ? material->model : NULL, NULL, 1);
    if (code != CLI_EXIT_OK) {
        mr_material_free(material);
        return code;
    }
    mr_external_material *own = NULL;
    mr_status status = MR_OK;
    if (external) {
        status = mr_renderer_describe(renderers.opened[0], model_name, &own);
        if (status != MR_OK) code = cli_fail("render", status);
        for (int k = 0; code == CLI_EXIT_OK && k < assignment_count; k++)
            code = cli_set_material_input("render", own, assignments[k]);
    }
    double start = cli_now();
    mr_scene scene = mr_scene_fit(scene_opts);
    scene.edge_samples = edge_samples;
    mr_render_plan *plan = NULL;
    mr_image *image = NULL;
    if (code == CLI_EXIT_OK) {
        status = mr_render_plan_create(&scene, &plan);
        if (status == MR_OK) status = mr_image_create(scene.width, scene.height, 3, &image);
        mr_image *parts[3] = {NULL, NULL, NULL};
        parts[component] = image;
        if (status == MR_OK && own != NULL)
            status = mr_renderer_render_external(renderers.opened[0], plan, own, parts[0], parts[1], parts[2]);
        else if (status == MR_OK)
            status = mr_renderer_render(renderers.opened[0], plan, material->model, material->values, parts[0],
                                        parts[1], parts[2]);
        if (status == MR_OK && exposure != 1.0) mr_image_scale(image, exposure);
        if (status == MR_OK) status = mr_img_write(output, image, write_opts);
        if (status == MR_OK && mask_path != NULL) status = write_mask(plan, mask_path);
        if (status != MR_OK) code = cli_fail("render", status);
    }
    const double seconds = cli_now() - start;
    if (code == CLI_EXIT_OK && json) {
        printf("{\"command\": \"render\", \"model\": ");
        cli_json_string(stdout, external ? "blender material" : material->model->name);
        printf(", \"material\": ");
        if (own != NULL) {
            cli_json_string(stdout, model_name);
            printf(", \"inputs\": ");
            cli_print_material_inputs_json(stdout, own);
        } else {
            printf("null");
        }
        print_outputs_json(output, mask_path);
        printf(", \"component\": \"%s\", \"width\": %d, \"height\": %d, \"renderers\": ",
               mr_component_name(component), scene.width, scene.height);
        cli_print_renderers_json(stdout, &renderers);
        printf(", \"seconds\": {\"render\": %.6f}}\n", seconds);
    } else if (code == CLI_EXIT_OK) {
        fprintf(stderr, "matremap render: wrote %s (%s, %dx%d, %s, %s in %.1f ms)\n", output,
                mr_component_name(component), scene.width, scene.height, external ? model_name : material->model->name,
                renderers.versions[0], 1e3 * seconds);
    }
    mr_image_free(image);
    mr_render_plan_free(plan);
    mr_external_material_free(own);
    mr_material_free(material);
    cli_close_renderers(&renderers);
    return code;
}

int cmd_render(int argc, char **argv) {
    const char *model_name = NULL, *output = NULL, *env_path = NULL, *mask_path = NULL, *mesh_path = NULL;
    int paper = 0;
    mr_fit_scene_options scene_opts = {0};
    int light_given = 0, env_option = 0, env_samples = 0, reflection_samples = 0;
    double env_rotation = 0.0, env_scale = 1.0;
    mr_component component = MR_COMPONENT_FULL;
    double exposure = 1.0;
    int edge_samples = 0, threads = 0, json = 0, has_direction = 0;
    double direction[3] = {0.0, 0.0, 0.0};
    mr_img_write_options write_opts = {0};
    const char *assignments[CLI_MAX_ASSIGNMENTS];
    int assignment_count = 0;
    const char *renderer_name = NULL;
    int samples = 0, seed = 0;

    for (int i = 1; i < argc; i++) {
        const char *value = NULL;
        int taken;
        if (cli_is_help(argv[i])) {
            print_help();
            return CLI_EXIT_OK;
        }
        if ((taken = cli_take_option("render", argc, argv, &i, "--output", &value)) ||
            (taken = cli_take_option("render", argc, argv, &i, "-o", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            output = value;
        } else if ((taken = cli_take_option("render", argc, argv, &i, "--size", &value))) {
            if (taken < 0 || !cli_parse_int("render", "--size", value, 16, 8192, &scene_opts.size))
                return CLI_EXIT_USAGE;
        } else if ((taken = cli_take_option("render", argc, argv, &i, "--light", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            if (mr_fit_light_from_name(value, &scene_opts.light) != MR_OK)
                return cli_usage_error("render", "%s", mr_last_error());
            light_given = 1;
        } else if ((taken = cli_take_option("render", argc, argv, &i, "--env", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            env_path = value;
        } else if ((taken = cli_take_option("render", argc, argv, &i, "--env-rotation", &value))) {
            if (taken < 0 || !cli_parse_double("render", "--env-rotation", value, -1e6, 1e6, &env_rotation))
                return CLI_EXIT_USAGE;
            env_option = 1;
        } else if ((taken = cli_take_option("render", argc, argv, &i, "--env-samples", &value))) {
            if (taken < 0 ||
                !cli_parse_int("render", "--env-samples", value, 1, MR_ENV_MAX_SAMPLES, &env_samples))
                return CLI_EXIT_USAGE;
            env_option = 1;
        } else if ((taken = cli_take_option("render", argc, argv, &i, "--env-reflection-samples", &value))) {
            if (taken < 0 || !cli_parse_int("render", "--env-reflection-samples", value, 0,
                                            MR_ENV_MAX_REFLECTION_SAMPLES, &reflection_samples))
                return CLI_EXIT_USAGE;
            env_option = 1;
        } else if ((taken = cli_take_option("render", argc, argv, &i, "--env-scale", &value))) {
            if (taken < 0 || !cli_parse_double("render", "--env-scale", value, 0.0, 1e9, &env_scale))
                return CLI_EXIT_USAGE;
            env_option = 1;
        } else if ((taken = cli_take_option("render", argc, argv, &i, "--mesh", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            mesh_path = value;
        } else if ((taken = cli_take_option("render", argc, argv, &i, "--camera-direction", &value))) {
            if (taken < 0 || !cli_parse_direction("render", "--camera-direction", value, direction))
                return CLI_EXIT_USAGE;
            has_direction = 1;
        } else if ((taken = cli_take_option("render", argc, argv, &i, "--renderer", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            if (mr_renderer_check(value, NULL) != MR_OK) return cli_usage_error("render", "%s", mr_last_error());
            renderer_name = value;
        } else if ((taken = cli_take_option("render", argc, argv, &i, "--samples", &value))) {
            if (taken < 0 || !cli_parse_int("render", "--samples", value, 1, 1 << 20, &samples)) return CLI_EXIT_USAGE;
        } else if ((taken = cli_take_option("render", argc, argv, &i, "--seed", &value))) {
            if (taken < 0 || !cli_parse_int("render", "--seed", value, 0, 1 << 30, &seed)) return CLI_EXIT_USAGE;
        } else if (strcmp(argv[i], "--json") == 0) {
            json = 1;
        } else if ((taken = cli_take_option("render", argc, argv, &i, "--camera", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            if (strcmp(value, "auto") != 0 && strcmp(value, "paper") != 0)
                return cli_usage_error("render", "--camera '%s': expected auto or paper", value);
            paper = strcmp(value, "paper") == 0;
        } else if ((taken = cli_take_option("render", argc, argv, &i, "--component", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            if (mr_component_from_name(value, &component) != MR_OK)
                return cli_usage_error("render", "%s", mr_last_error());
        } else if ((taken = cli_take_option("render", argc, argv, &i, "--exposure", &value))) {
            if (taken < 0 || !cli_parse_double("render", "--exposure", value, 0.0, 1e9, &exposure))
                return CLI_EXIT_USAGE;
        } else if ((taken = cli_take_option("render", argc, argv, &i, "--threads", &value))) {
            if (taken < 0 || !cli_parse_int("render", "--threads", value, 0, 1024, &threads)) return CLI_EXIT_USAGE;
        } else if ((taken = cli_take_option("render", argc, argv, &i, "--edge-samples", &value))) {
            if (taken < 0 || !cli_parse_int("render", "--edge-samples", value, 1, 16, &edge_samples))
                return CLI_EXIT_USAGE;
        } else if ((taken = cli_take_option("render", argc, argv, &i, "--mask", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            mask_path = value;
        } else if ((taken = cli_take_option("render", argc, argv, &i, "--bits", &value))) {
            if (taken < 0 || !cli_parse_int("render", "--bits", value, 8, 32, &write_opts.bits)) return CLI_EXIT_USAGE;
        } else if (argv[i][0] == '-') {
            return cli_usage_error("render", "unknown option '%s'", argv[i]);
        } else if (model_name == NULL) {
            model_name = argv[i];
        } else if (strchr(argv[i], '=') != NULL) {
            if (assignment_count == CLI_MAX_ASSIGNMENTS)
                return cli_usage_error("render", "too many parameter assignments");
            assignments[assignment_count++] = argv[i];
        } else {
            return cli_usage_error("render", "unexpected argument '%s' (parameters are name=value)", argv[i]);
        }
    }
    if (model_name == NULL) return cli_usage_error("render", "missing MODEL ('matremap models' lists them)");
    if (output == NULL) return cli_usage_error("render", "missing -o OUT (an .exr, .hdr, .png, .jpg or .tif file)");
    if (env_option && env_path == NULL)
        return cli_usage_error("render", "--env-rotation, --env-samples, --env-reflection-samples and --env-scale need "
                               "--env FILE");
    const int external = strncmp(model_name, "blender:", 8) == 0;
    if (external && renderer_name == NULL) renderer_name = "blender";
    if (renderer_name != NULL && strcmp(renderer_name, "builtin") != 0) {
        if (env_path != NULL || mesh_path != NULL || paper || has_direction || cli_is_gltf_path(model_name))
            return cli_usage_error("render", "--renderer %s renders the fit scene's sphere under its point light: "
                                   "no --env, --mesh, --camera or glTF asset", renderer_name);
        if (external && strcmp(renderer_name, "blender") != 0)
            return cli_usage_error("render", "'%s' is a material of Blender's: --renderer blender", model_name);
        for (int k = 0; k < assignment_count; k++)
            if (strchr(assignments[k], '@') != NULL)
                return cli_usage_error("render", "'%s': --renderer %s renders uniform materials (no maps)",
                                       assignments[k], renderer_name);
        scene_opts.size = scene_opts.size > 0 ? scene_opts.size : 512;
        return render_by(renderer_name, samples, seed, model_name + (external ? 8 : 0), external, assignments,
                         assignment_count, &scene_opts, edge_samples, component, exposure, output, mask_path,
                         &write_opts, json);
    }
    const int gltf = cli_is_gltf_path(model_name);
    if (gltf && assignment_count > 0)
        return cli_usage_error("render", "'%s': a glTF asset takes no name=value parameters (its materials are its "
                               "own)", assignments[0]);
    if (gltf && mesh_path != NULL)
        return cli_usage_error("render", "--mesh renders a material (MODEL name=value ...); a glTF asset brings its "
                               "own triangles");
    if (gltf && paper)
        return cli_usage_error("render", "--camera paper is placed for the paper's sphere; a glTF asset is framed by "
                               "--camera-direction");
    if (!gltf && has_direction)
        return cli_usage_error("render", "--camera-direction places the camera for glTF assets");

    // Nothing written over a file read (maps, the map, the mesh).
    mr_output_plan io = {0};
    cli_plan_material(&io, assignments, NULL, assignment_count);
    if (env_path != NULL) mr_output_plan_inputf(&io, env_path, "--env %s", env_path);
    if (mesh_path != NULL) mr_output_plan_inputf(&io, mesh_path, "--mesh %s", mesh_path);
    if (gltf) mr_output_plan_inputf(&io, model_name, "asset %s", model_name);
    mr_output_plan_output(&io, output, NULL);
    if (mask_path != NULL) mr_output_plan_output(&io, mask_path, "--mask");
    int code = cli_plan_check("render", &io);

    mr_material *material = NULL;
    mr_gltf_scene *asset = NULL;
    double asset_seconds = 0.0;
    if (code == CLI_EXIT_OK && gltf) {
        double t0 = cli_now();
        code = cli_gltf_scene_load("render", model_name, &io, &asset);
        asset_seconds = cli_now() - t0;
    } else if (code == CLI_EXIT_OK) {
        code = cli_material_load("render", model_name, assignments, assignment_count, &material);
        cli_material_note_invalid_texels("render", material);
    }
    mr_output_plan_free(&io);

    mr_image *env = NULL, *image = NULL;
    mr_render_plan *plan = NULL;
    mr_obj_mesh *obj = NULL;
    mr_status status = MR_OK;
    if (code == CLI_EXIT_OK && env_path != NULL) {
        status = mr_img_read(env_path, NULL, &env);
        if (status == MR_OK) status = cli_check_radiance(env, env_path); // named by its file
        if (status != MR_OK) code = cli_fail("render", status);
    }
    double load_seconds = 0.0;
    if (code == CLI_EXIT_OK && mesh_path != NULL) {
        double t0 = cli_now();
        status = mr_obj_load(mesh_path, NULL, &obj);
        load_seconds = cli_now() - t0;
        if (status != MR_OK) code = cli_fail("render", status);
        else if (obj->warnings[0] != '\0')
            fprintf(stderr, "matremap render: warning: OBJ '%s': %s", mesh_path, obj->warnings);
    }
    double start = cli_now(), plan_seconds = 0.0;
    mr_scene scene = mr_scene_fit(&scene_opts);
    scene.edge_samples = edge_samples;
    scene.threads = threads;
    if (obj != NULL) {
        scene.shape.type = MR_SHAPE_MESH;
        scene.shape.mesh = &obj->mesh;
        mr_frame_options frame = {0};
        frame.width = scene.width;
        frame.height = scene.height;
        if (!paper) status = mr_camera_frame_mesh(&obj->mesh, &frame, &scene.camera);
        if (status != MR_OK) code = cli_fail("render", status);
    }
    if (asset != NULL) {
        scene.shape.type = MR_SHAPE_MESH;
        scene.shape.mesh = &asset->mesh;
        status = mr_gltf_scene_frame(asset, has_direction ? direction : NULL, scene.width, scene.height,
                                     &scene.camera);
        if (status != MR_OK) code = cli_fail("render", status);
    }
    if (paper) scene.camera = mr_camera_paper();
    if (obj != NULL || asset != NULL || paper)
        mr_scene_fit_light_to_mesh(&scene, obj != NULL ? &obj->mesh : asset != NULL ? &asset->mesh : NULL,
                                   scene_opts.light); // never fails: the fit scene has its light
    if (env != NULL) {
        // --env alone lights with the map only; with an explicit --light the point light stays as well.
        int slot = light_given ? scene.light_count++ : 0;
        scene.lights[slot] = mr_light_environment(env, env_scale, env_rotation, env_samples);
        scene.lights[slot].reflection_samples = reflection_samples;
    }
    if (code == CLI_EXIT_OK) {
        status = mr_render_plan_create(&scene, &plan);
        plan_seconds = cli_now() - start;
        if (status == MR_OK && asset != NULL)
            status = mr_render_materials(plan, asset->bindings, asset->material_count, component, &image);
        else if (status == MR_OK)
            status = mr_render_textured(plan, material->model, material->values, &material->textures, component,
                                        &image);
        if (status == MR_OK && exposure != 1.0) mr_image_scale(image, exposure);
        double render_seconds = cli_now() - start - plan_seconds;
        if (status == MR_OK) status = mr_img_write(output, image, &write_opts);
        if (status == MR_OK && mask_path != NULL) status = write_mask(plan, mask_path);
        const mr_mesh *mesh = obj != NULL ? &obj->mesh : asset != NULL ? &asset->mesh : NULL;
        if (status != MR_OK) {
            code = cli_fail("render", status);
        } else if (json) {
            printf("{\"command\": \"render\", \"model\": ");
            cli_json_string(stdout, asset != NULL ? "gltf asset" : material->model->name);
            printf(", \"asset\": ");
            if (asset != NULL)
                cli_json_string(stdout, model_name);
            else
                printf("null");
            printf(", \"mesh\": ");
            if (obj != NULL)
                cli_json_string(stdout, mesh_path);
            else
                printf("null");
            print_outputs_json(output, mask_path);
            printf(", \"component\": \"%s\", \"width\": %d, \"height\": %d, \"lit_pixels\": %d, "
                   "\"shading_samples\": %ld, \"shadow_rays\": %ld, \"triangles\": %d, \"materials\": %d, ",
                   mr_component_name(component), scene.width, scene.height, mr_render_plan_lit_pixel_count(plan),
                   mr_render_plan_sample_count(plan), mr_render_plan_shadow_ray_count(plan),
                   mesh != NULL ? mesh->triangle_count : 0, asset != NULL ? asset->material_count : 1);
            printf("\"seconds\": {\"load\": %.6f, \"plan\": %.6f, \"render\": %.6f}}\n",
                   obj != NULL ? load_seconds : asset_seconds, plan_seconds, render_seconds);
        } else {
            if (mesh != NULL)
                fprintf(stderr, "matremap render: %s %s: %d triangles, %d vertices, read in %.1f ms; %ld shadow rays\n",
                        obj != NULL ? "mesh" : "asset", obj != NULL ? mesh_path : model_name, mesh->triangle_count,
                        mesh->vertex_count, 1e3 * (obj != NULL ? load_seconds : asset_seconds),
                        mr_render_plan_shadow_ray_count(plan));
            fprintf(stderr, "matremap render: wrote %s (%s, %dx%d, %d lit pixels, %ld shading samples, plan %.1f ms, "
                    "rendered in %.1f ms)\n", output, mr_component_name(component), scene.width, scene.height,
                    mr_render_plan_lit_pixel_count(plan), mr_render_plan_sample_count(plan), 1e3 * plan_seconds,
                    1e3 * render_seconds);
        }
    }
    mr_image_free(image);
    mr_render_plan_free(plan);
    mr_image_free(env);
    mr_obj_mesh_free(obj);
    mr_gltf_scene_free(asset);
    mr_material_free(material);
    return code;
}
