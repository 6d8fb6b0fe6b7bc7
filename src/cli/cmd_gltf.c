/*
 * cmd_gltf.c — `matremap gltf spec2metal|metal2spec IN -o OUT [options]`: converts the materials of a glTF asset
 * between KHR_materials_pbrSpecularGlossiness and core pbrMetallicRoughness through the workflow converters
 * (src/workflow/workflow.h, the network of nn/ for --method mlp), texel by texel, and saves the asset with its new
 * textures beside it (gltf/mr_gltf.h). Everything else in the asset is left as it was.
 *
 * Per material (spec2metal): the spec-gloss factors multiply their textures in linear values (colour textures
 * sRGB-decoded, glossiness linear, glTF's rule), the product is converted with glossiness -> roughness = 1 -
 * glossiness and the spec-gloss diffuse read as glTF renders it (--convention), and the result becomes
 * factors alone (no textures) or a base-colour texture (RGBA when the diffuse has alpha) plus a packed
 * metallic-roughness texture (G roughness, B metallic) with factors 1. Both textures keep the UV set,
 * KHR_texture_transform and sampler of the source textures; the two source textures must share their UV mapping
 * (they do in practice: one texel of each describes one surface point) and are brought to one size (bilinear).
 * A spec-gloss material that carries core metal-rough values of its own (the authors' fallback) is kept, not
 * converted, unless --overwrite-metal-rough; the output says so per material. The off-manifold tolerance of each
 * input value follows its texture's encoding (half a code, times the factor; workflow.h, "Tolerances") unless
 * --eps. metal2spec is the inverse: the spec-gloss extension is added beside the core material, which stays as
 * the fallback glTF asks for.
 */
#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include <signal.h>
#include <sys/stat.h>

#include "cli.h"
#include "gltf/mr_gltf.h"
#include "gltf/mr_gltf_library.h"


static void print_help(void) {
    printf("Usage: matremap gltf spec2metal IN.gltf|IN.glb -o OUT.gltf|OUT.glb [options]\n"
           "       matremap gltf metal2spec IN.gltf|IN.glb -o OUT.gltf|OUT.glb [options]\n"
           "       matremap gltf spec2metal|metal2spec FOLDER|GLOB|ASSET... -o DIR [--resume] [--shard K/N] [options]\n"
           "\n"
           "spec2metal converts every KHR_materials_pbrSpecularGlossiness material of a glTF asset to core\n"
           "metallic-roughness: factors times textures, texel by texel, with the converters of 'matremap\n"
           "spec2metal' (docs/workflow.md). New textures (PNG, or EXR with --format exr) are written beside OUT;\n"
           "extensionsUsed/Required are updated; meshes, nodes, animations and other extensions are kept.\n"
           "A material that already carries core metal-rough values of its own beside spec-gloss (a\n"
           "baseColorTexture or metallicRoughnessTexture, or factors other than 1: the artist's own fallback, as\n"
           "in the Avocado) is kept as it is and not converted, and the output says so; its spec-gloss extension\n"
           "goes like the converted ones' (--keep-specgloss keeps it). --overwrite-metal-rough converts it anyway.\n"
           "Both readings (spec2metal's default): besides the per-texel core values (--method weighted unless\n"
           "told otherwise), every converted or kept material gets KHR_materials_specular values solved texel by\n"
           "texel over them (a specularColor texture, specular 1), so that engines reading the extension see the\n"
           "spec-gloss F0, and engines without it the core conversion; where one base colour cannot serve both\n"
           "(its diffuse) the output counts the texels.\n"
           "--core-only writes the core values alone (docs/gltf.md, \"Both readings\").\n"
           "metal2spec adds the spec-gloss extension to every metal-rough material (Eq. 2), keeping the core\n"
           "material as the fallback.\n"
           "After converting, every texture, image and sampler that nothing in the asset refers to any more is\n"
           "removed (spec2metal's old diffuse and specular-glossiness textures, but also any the input left\n"
           "unused), and its image file is not written beside OUT; references are renumbered. What an unknown\n"
           "extension might refer to is kept (gltf/mr_gltf.h, mr_gltf_prune_unused).\n"
           "\n"
           "Side files of a .gltf OUT are named after it, so that outputs in one folder never share one: for\n"
           "out/floppy.gltf, buffers floppy.bin, floppy_1.bin, ...; new textures floppy_mK_NAME.png (K the material);\n"
           "copied images floppy_FILE in the folder of their URI (textures/floppy_material_0_normal.png). A .glb\n"
           "holds everything. An existing file is replaced only when it is an earlier OUT's own (OUT exists and\n"
           "refers to it: the same command run again) or with --replace-files; otherwise nothing is written and the\n"
           "command fails (exit 2) naming the file. Inputs are never replaced.\n"
           "\n");
    printf("Options:\n"
           "  -o, --output OUT      the converted asset (.gltf with its files beside it, or .glb); never an input\n"
           "  --method M            spec2metal: weighted, mlp, mean, khronos, or extension: the lossless route of\n"
           "                        KHR_materials_specular + KHR_materials_ior (ior 1000, textures reused, metallic\n"
           "                        0; for engines that support both); default weighted for both readings (measured\n"
           "                        closest in both kinds of engine, docs/gltf.md), mlp with --core-only, --format\n"
           "                        exr or --weights; metal2spec: eq2 (default), khronos\n"
           "  --core-only           spec2metal: core metal-rough values only, no KHR_materials_specular over them\n"
           "                        (default: both readings, except with --method extension, --keep-specgloss\n"
           "                        and --format exr)\n"
           "  --extension-ior X     spec2metal: the ior the specular values are solved for (default 1.5, glTF's\n"
           "                        own, so no KHR_materials_ior is written; another value writes it)\n"
           "  --weights FILE        the network for mlp (default: the shipped one, as 'matremap spec2metal')\n"
           "  --convention C        gltf or paper: how the spec-gloss diffuse is read (docs/workflow.md); default\n"
           "                        paper for spec2metal's both readings (measured closer in both kinds of\n"
           "                        engine, docs/gltf.md), gltf with --core-only, --format exr and for\n"
           "                        metal2spec (khronos has its own reading)\n"
           "  --overwrite-metal-rough  spec2metal: also convert materials that carry metal-rough values of their\n"
           "                        own beside spec-gloss, overwriting them (default: keep them, and say so)\n"
           "  --eps E               spec2metal, weighted/mean/khronos: the off-manifold tolerance, for every value\n"
           "                        (default: per texel, half a code value of the texture it comes from, times its\n"
           "                        factor, at least 1e-6: a clean 8-bit export flags nothing; docs/workflow.md)\n"
           "  --threads N           OpenMP threads of the conversion (default 0: automatic, a team for textures of\n"
           "                        16384 texels or more)\n"
           "  --keep-specgloss      spec2metal: keep the spec-gloss extension in the output beside the new core\n"
           "                        material (default: remove it, so engines without it read the core material)\n"
           "  --format F            png (default) or exr for the new textures (EXR is not a core glTF image\n"
           "                        type: the validator reports it and many viewers cannot read it)\n"
           "  --keep-unused         keep unreferenced textures, images and samplers (default: remove them)\n"
           "  --replace-files       let OUT's side files replace existing files that are not an earlier OUT's own\n"
           "                        (another asset's, say; inputs never)\n"
           "  --json                a JSON summary on stdout\n"
           "  --help                this text\n");
    printf("\n"
           "Many assets (several inputs, a folder, a glob, or -o naming a folder): folders are searched recursively\n"
           "for .gltf and .glb, a quoted glob is expanded here; the assets convert side by side within --threads\n"
           "(0: one per core when there are two assets or more) into DIR (made if missing), mirroring their paths\n"
           "below their common folder; a progress bar on a terminal (assets done/total, texels per second, time\n"
           "left), one line per finished asset otherwise. A failed asset is named with its reason and the others go\n"
           "on (exit 2 at the end). DIR gets summary.json (every asset: input, output, status, error, materials,\n"
           "flags, object SSIM, seconds) and index.html (before/after thumbnails, worst first). DIR may not lie in\n"
           "an input folder. SIGINT or SIGTERM lets the assets under way finish, records the rest as cancelled in\n"
           "summary.json and exits 3 (--resume goes on from there).\n"
           "  --resume              skip assets an earlier run into DIR converted with the same settings from the\n"
           "                        same files (summary.json records both)\n"
           "  --shard K/N           convert only the assets at sorted index i with i %% N == K (job arrays)\n"
           "  --no-renders          no thumbnails and no object SSIM (faster: the renders decode every texture)\n"
           "\n"
           "Prints one line per material (converted: texture size, flagged texels by reason, time; kept or left as it\n"
           "is: why; then its specular solve: texels whose F0 it cannot give, texels whose core diffuse is off by\n"
           "more than 1/255), a total, the flagged texels of all conversions by reason and what was removed;\n"
           "--json gives the same, with the lists of converted and kept materials. The reasons are those of\n"
           "'matremap spec2metal' and 'metal2spec' (a texel may have several): off-manifold (spec2metal weighted,\n"
           "mean, khronos: no metal-rough material gives these maps; metal2spec, glTF convention: a diffuse above\n"
           "1, clamped), non-finite input, clamped input, method failed.\n"
           "\n"
           "Examples:\n"
           "  matremap gltf spec2metal FloppyDisk/scene.gltf -o out/floppy.gltf --method weighted\n"
           "  matremap gltf spec2metal assets/ -o converted/ --resume\n");
}

typedef struct options {
    const char *direction, *input, *output, *method, *weights, *format;
    mr_wf_diffuse convention;
    int convention_given; /* else paper for spec2metal's both readings, gltf otherwise (docs/gltf.md) */
    double eps;    /* --eps, when eps_given */
    int eps_given; /* else each input's tolerance follows its texture's encoding */
    int threads;   /* --threads: mr_wf_options.threads (0 automatic) */
    int overwrite, keep_specgloss, keep_unused, json;
    int replace_files; /* --replace-files: side files may replace existing files that are not the output's own */
    int core_only;     /* --core-only: no KHR_materials_specular values over the core ones */
    double extension_ior; /* --extension-ior (0: 1.5) */
    const char **inputs;  /* every input (files, folders, globs); input = inputs[0] */
    int input_count;
    int library;          /* many assets into a folder (mr_gltf_convert_library) */
    int resume, shard_given, shard_index, shard_count, no_renders;
} options;

/* ---- the command -------------------------------------------------------------------------------------------- */

/* The flagged texels by reason, every reason 'matremap spec2metal|metal2spec' names (a texel with several flags
 * counts under each): "N off-manifold[ (meaning)], N non-finite input, N clamped input, N method failed";
 * off-manifold only where it is computed. */
static void print_reasons(const mr_gltf_material_report *r, int off_computed, const char *off_meaning) {
    if (off_computed) printf("%zu off-manifold%s, ", r->off_manifold, off_meaning);
    printf("%zu non-finite input, %zu clamped input, %zu method failed", r->nonfinite, r->clamped, r->failed);
}

/* The KHR_materials_specular solve of a material (or the totals): texels whose F0 it cannot give, and texels whose
 * core diffuse differs from the spec-gloss one (the base colour both readings share). */
static void print_extension(const mr_gltf_material_report *r) {
    printf("KHR_materials_specular over the core values: F0 unmet at %zu of %zu texel%s (largest |F0 - specular| "
           "%.4f), core diffuse off at %zu (mean |base (1 - metallic) - diffuse| %.4f, largest %.4f)", r->f0_unmet,
           r->texels, r->texels == 1 ? "" : "s", r->f0_max_error, r->diffuse_off, r->diffuse_mean_error,
           r->diffuse_max_error);
}

static void print_json_extension(const mr_gltf_material_report *r) {
    printf("{\"texels\": %zu, \"f0_unmet\": %zu, \"f0_max_error\": %.6g, \"diffuse_off\": %zu, "
           "\"diffuse_mean_error\": %.6g, \"diffuse_max_error\": %.6g}", r->texels, r->f0_unmet, r->f0_max_error,
           r->diffuse_off, r->diffuse_mean_error, r->diffuse_max_error);
}

/* The same as a JSON object; off_manifold null where it is not computed. */
static void print_json_reasons(const mr_gltf_material_report *r, int off_computed) {
    printf("{\"off_manifold\": ");
    if (off_computed)
        printf("%zu", r->off_manifold);
    else
        printf("null");
    printf(", \"nonfinite_input\": %zu, \"clamped_input\": %zu, \"method_failed\": %zu}", r->nonfinite, r->clamped,
           r->failed);
}


static int parse(int argc, char **argv, options *o) {
    for (int i = 1; i < argc; i++) {
        const char *value = NULL;
        int taken;
        if ((taken = cli_take_option("gltf", argc, argv, &i, "--output", &value)) ||
            (taken = cli_take_option("gltf", argc, argv, &i, "-o", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            o->output = value;
        } else if ((taken = cli_take_option("gltf", argc, argv, &i, "--method", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            o->method = value;
        } else if ((taken = cli_take_option("gltf", argc, argv, &i, "--weights", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            o->weights = value;
        } else if ((taken = cli_take_option("gltf", argc, argv, &i, "--format", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            if (strcmp(value, "png") != 0 && strcmp(value, "exr") != 0)
                return cli_usage_error("gltf", "--format '%s': expected png or exr", value);
            o->format = value;
        } else if ((taken = cli_take_option("gltf", argc, argv, &i, "--convention", &value))) {
            if (taken < 0 || !cli_parse_convention("gltf", value, &o->convention)) return CLI_EXIT_USAGE;
            o->convention_given = 1;
        } else if ((taken = cli_take_option("gltf", argc, argv, &i, "--fallback", &value))) {
            return cli_usage_error("gltf", "--fallback is gone: a material's own metal-rough values are kept by "
                                   "default; --overwrite-metal-rough converts them instead");
        } else if ((taken = cli_take_option("gltf", argc, argv, &i, "--eps", &value))) {
            if (taken < 0 || !cli_parse_double("gltf", "--eps", value, 0.0, 0.5, &o->eps)) return CLI_EXIT_USAGE;
            o->eps_given = 1;
        } else if ((taken = cli_take_option("gltf", argc, argv, &i, "--threads", &value))) {
            if (taken < 0 || !cli_parse_int("gltf", "--threads", value, 0, 1024, &o->threads)) return CLI_EXIT_USAGE;
        } else if ((taken = cli_take_option("gltf", argc, argv, &i, "--extension-ior", &value))) {
            if (taken < 0 || !cli_parse_double("gltf", "--extension-ior", value, 1.0 + 1e-9, 1e4, &o->extension_ior))
                return CLI_EXIT_USAGE;
        } else if (strcmp(argv[i], "--core-only") == 0) {
            o->core_only = 1;
        } else if (strcmp(argv[i], "--overwrite-metal-rough") == 0) {
            o->overwrite = 1;
        } else if (strcmp(argv[i], "--keep-specgloss") == 0) {
            o->keep_specgloss = 1;
        } else if (strcmp(argv[i], "--keep-unused") == 0) {
            o->keep_unused = 1;
        } else if (strcmp(argv[i], "--replace-files") == 0) {
            o->replace_files = 1;
        } else if (strcmp(argv[i], "--json") == 0) {
            o->json = 1;
        } else if (strcmp(argv[i], "--resume") == 0) {
            o->resume = 1;
        } else if (strcmp(argv[i], "--no-renders") == 0) {
            o->no_renders = 1;
        } else if ((taken = cli_take_option("gltf", argc, argv, &i, "--shard", &value))) {
            long k = 0, n = 0;
            if (taken < 0 || !cli_parse_shard("gltf", value, 1000000, &k, &n)) return CLI_EXIT_USAGE;
            o->shard_index = (int)k;
            o->shard_count = (int)n;
            o->shard_given = 1;
        } else if (argv[i][0] == '-') {
            return cli_usage_error("gltf", "unknown option '%s'", argv[i]);
        } else if (o->direction == NULL) {
            o->direction = argv[i];
        } else {
            if (o->input == NULL) o->input = argv[i];
            o->inputs[o->input_count++] = argv[i];
        }
    }
    if (o->direction == NULL) return cli_usage_error("gltf", "missing spec2metal or metal2spec");
    int to_metal = strcmp(o->direction, "spec2metal") == 0;
    if (!to_metal && strcmp(o->direction, "metal2spec") != 0)
        return cli_usage_error("gltf", "'%s': expected spec2metal or metal2spec", o->direction);
    if (o->input == NULL) return cli_usage_error("gltf", "missing the input asset (.gltf or .glb)");
    if (o->output == NULL) return cli_usage_error("gltf", "missing -o OUT (.gltf or .glb, or a folder)");
    // Many assets (several inputs, a folder, a glob, or a folder as OUT) go to the library call.
    struct stat st;
    o->library = o->input_count > 1 || !cli_is_gltf_path(o->output) ||
                 (stat(o->input, &st) == 0 ? S_ISDIR(st.st_mode) : strpbrk(o->input, "*?[") != NULL);
    if (o->library && cli_is_gltf_path(o->output))
        return cli_usage_error("gltf", "-o '%s': many assets go into a folder (-o DIR), not one asset", o->output);
    if (!o->library && (o->resume || o->shard_given || o->no_renders))
        return cli_usage_error("gltf", "--resume, --shard and --no-renders go with many assets (a folder, several "
                               "files or a glob into -o DIR)");
    if (o->library && o->replace_files)
        return cli_usage_error("gltf", "--replace-files goes with one asset");
    if (o->format == NULL) o->format = "png";
    // spec2metal's default core method: weighted under both readings (measured ahead of mlp in the engines with and
    // without KHR_materials_specular, docs/evaluation.md "Both readings"); mlp for the core values alone (--core-only,
    // --format exr) and with --weights.
    if (o->method == NULL)
        o->method = !to_metal ? "eq2" : o->core_only || o->weights || strcmp(o->format, "exr") == 0 ? "mlp"
                                                                                                  : "weighted";
    if (!to_metal && (o->weights || o->overwrite || o->keep_specgloss || o->eps_given || o->core_only ||
                      o->extension_ior > 0.0))
        return cli_usage_error("gltf", "--weights, --eps, --overwrite-metal-rough, --keep-specgloss, --core-only and "
                               "--extension-ior go with spec2metal");
    if (strcmp(o->method, "extension") == 0 && (o->core_only || o->extension_ior > 0.0))
        return cli_usage_error("gltf", "--core-only and --extension-ior go with the per-texel methods; --method "
                               "extension writes the extension alone (ior 1000)");
    if (o->core_only && o->extension_ior > 0.0)
        return cli_usage_error("gltf", "--extension-ior sets the extension's values; --core-only writes none");
    // Both readings share one base colour: read as paper reads the diffuse (the base colour the lossless route keeps)
    // it is measured closer in both kinds of engine (docs/gltf.md, "Both readings"); the core-only output keeps glTF's.
    if (!o->convention_given && to_metal && !o->core_only && strcmp(o->method, "extension") != 0 &&
        strcmp(o->method, "khronos") != 0 && strcmp(o->format, "exr") != 0) // khronos has its own reading; EXR
                                                                              // textures get no extension
        o->convention = MR_WF_DIFFUSE_PLAIN;
    return CLI_EXIT_OK;
}


/* ---- many assets: mr_gltf_convert_library ------------------------------------------------------------------- */

static int run_library(const options *o, const mr_transform *transform) {
    char settings[512];
    snprintf(settings, sizeof settings, "%s method=%s convention=%s eps=%s%.17g format=%s overwrite=%d keep=%d "
             "unused=%d core_only=%d ior=%.17g weights=%s", o->direction, o->method,
             o->convention == MR_WF_DIFFUSE_PLAIN ? "paper" : "gltf", o->eps_given ? "" : "encoding:", o->eps,
             o->format, o->overwrite, o->keep_specgloss, o->keep_unused, o->core_only, o->extension_ior,
             o->weights ? o->weights : "shipped");
    mr_gltf_library_options lo = {0};
    lo.convert.transform = transform;
    lo.convert.image_format = o->format;
    lo.convert.overwrite = o->overwrite;
    lo.convert.keep_source = o->keep_specgloss;
    lo.convert.exact_inputs = o->eps_given;
    lo.convert.keep_unused = o->keep_unused;
    lo.convert.core_only = o->core_only;
    lo.convert.extension_ior = o->extension_ior;
    lo.settings = settings;
    lo.threads = o->threads;
    lo.resume = o->resume;
    lo.no_renders = o->no_renders;
    lo.shard_index = o->shard_index;
    lo.shard_count = o->shard_count;
    cli_library_view view = {isatty(STDERR_FILENO) && !o->json, NULL};
    lo.progress = o->json ? NULL : cli_library_progress;
    lo.progress_user = &view;
    struct sigaction old[2];
    lo.cancel = cli_library_cancel_begin(old);
    mr_gltf_library_result r;
    mr_status status = mr_gltf_convert_library(o->inputs, o->input_count, o->output, &lo, &r);
    cli_library_cancel_end(old);
    char label[64], head[96];
    snprintf(label, sizeof label, "gltf %s", o->direction);
    snprintf(head, sizeof head, "\"command\": \"gltf %s\"", o->direction);
    return cli_library_report("gltf", label, head, "converted", o->output, o->json, status, &r);
}

static int gltf_main(int argc, char **argv, const char **inputs) {
    options o;
    memset(&o, 0, sizeof o);
    o.inputs = inputs;
    o.convention = MR_WF_DIFFUSE_SPECGLOSS;
    int code = parse(argc, argv, &o);
    if (code != CLI_EXIT_OK) return code;
    int to_metal = strcmp(o.direction, "spec2metal") == 0;
    // Nothing written over a file read: OUT against IN and --weights here; the asset's buffers and images, and the
    // files written beside OUT, the library keeps apart (mr_gltf_save: never over a file the asset was read from).
    // Many assets: the library call checks its folder against the inputs.
    if (!o.library) {
        mr_output_plan io = {0};
        mr_output_plan_inputf(&io, o.input, "asset %s", o.input);
        if (o.weights != NULL) mr_output_plan_inputf(&io, o.weights, "--weights %s", o.weights);
        mr_output_plan_output(&io, o.output, NULL);
        code = cli_plan_check("gltf", &io);
        mr_output_plan_free(&io);
        if (code != CLI_EXIT_OK) return code;
    }

    // The transform: the method's descriptor for this pair of glTF models.
    const mr_transform_kind *kind = to_metal ? mr_transform_find("gltf-specgloss", "gltf", o.method)
                                             : mr_transform_find("gltf", "gltf-specgloss", o.method);
    if (kind == NULL) return cli_usage_error("gltf", "--method '%s': %s", o.method, mr_last_error());
    if (o.weights != NULL && !(kind->flags & MR_TRANSFORM_NEEDS_NETWORK))
        return cli_usage_error("gltf", "--weights goes with --method mlp, not %s", o.method);
    if (o.eps_given && !(kind->flags & MR_TRANSFORM_TOLERANCES))
        return cli_usage_error("gltf", "--eps applies to the analytic methods (weighted, mean, khronos); --method %s "
                               "computes no off-manifold flag", o.method);
    mr_transform_options to = {0};
    to.threads = o.threads;
    if (o.eps_given) to.eps = o.eps > 0.0 ? o.eps : DBL_MIN; // --eps 0: no tolerance but float rounding
    to.plain_diffuse = o.convention == MR_WF_DIFFUSE_PLAIN;
    mr_mlp *net = NULL;
    mr_transform *transform = NULL;
    if (o.weights != NULL) {
        mr_status status = mr_mlp_read(o.weights, &net);
        if (status != MR_OK) code = cli_fail("gltf", status);
        to.network = net;
    }
    if (code == CLI_EXIT_OK) {
        mr_status status = mr_transform_create(kind, &to, &transform);
        if (status != MR_OK) code = cli_fail("gltf", status);
    }
    const char *net_path = o.weights ? o.weights : transform ? mr_transform_network_path(transform) : "";
    double started = cli_now();
    mr_gltf_convert_result result = {0, NULL, {0, 0, 0, 0}};
    if (code == CLI_EXIT_OK && o.library) {
        code = run_library(&o, transform);
        mr_transform_free(transform);
        mr_mlp_free(net);
        return code;
    }
    if (code == CLI_EXIT_OK) {
        mr_gltf_convert_options co = {0};
        co.transform = transform;
        co.image_format = o.format;
        co.overwrite = o.overwrite;
        co.keep_source = o.keep_specgloss;
        co.exact_inputs = o.eps_given;
        co.keep_unused = o.keep_unused;
        co.replace_files = o.replace_files;
        co.replace_hint = "--replace-files";
        co.core_only = o.core_only;
        co.extension_ior = o.extension_ior;
        mr_status status = mr_gltf_convert_file(o.input, o.output, &co, &result);
        if (status != MR_OK) code = cli_fail("gltf", status);
    }
    const mr_gltf_material_report *outcomes = result.materials;
    const mr_gltf_prune_stats pruned = result.pruned;
    mr_gltf_convert_totals totals; // each conversion once (materials sharing one count it once)
    mr_gltf_convert_totals_of(&result, &totals);
    const int converted = totals.converted, kept = totals.kept;
    const size_t texels = totals.texels;
    const mr_gltf_material_report total = totals.total;
    // The off-manifold tolerance, where one is computed (analytic spec2metal methods).
    const char *tolerance = !(kind->flags & MR_TRANSFORM_TOLERANCES) ? NULL : o.eps_given ? "eps" : "encoding";
    // Where the off-manifold flag is computed, as 'matremap spec2metal|metal2spec' say it: spec2metal's analytic
    // methods (the result misses the input), metal2spec with the glTF convention (a diffuse spec-gloss cannot store,
    // clamped to 1).
    const int off_computed = tolerance != NULL || (!to_metal && (kind->flags & MR_TRANSFORM_CONVENTION) &&
                                                   o.convention == MR_WF_DIFFUSE_SPECGLOSS);
    const char *off_meaning = to_metal ? "" : " (spec-gloss diffuse above 1, clamped)";
    const int use_mlp = (kind->flags & MR_TRANSFORM_NEEDS_NETWORK) != 0;
    double seconds = cli_now() - started;
    if (code == CLI_EXIT_OK && !o.json) {
        for (int k = 0; k < result.material_count; k++) {
            const mr_gltf_material_report *r = &outcomes[k];
            printf("material %d '%s': ", k, r->name);
            if (r->outcome == MR_GLTF_KEPT) {
                printf("kept, not converted: %s; its spec-gloss extension %s; --overwrite-metal-rough converts it "
                       "instead\n", r->reason, o.keep_specgloss ? "kept (--keep-specgloss)" : "removed");
                if (r->extension) {
                    printf("material %d '%s': ", k, r->name);
                    print_extension(r);
                    printf("\n");
                }
                continue;
            }
            if (r->outcome == MR_GLTF_SKIPPED) {
                printf("left as it is: %s\n", r->reason);
                continue;
            }
            printf("converted, ");
            if (r->width > 0)
                printf("%dx%d textures", r->width, r->height);
            else
                printf("factors only");
            printf(", %zu texel%s flagged", r->flagged, r->flagged == 1 ? "" : "s");
            if (r->flagged > 0) {
                printf(" (");
                print_reasons(r, off_computed, off_meaning);
                printf(")");
            }
            printf(", %.3f s%s\n", r->seconds,
                   r->outcome == MR_GLTF_SHARED ? " (the same sources as an earlier material: its textures reused)"
                                                : "");
            if (r->extension) {
                printf("material %d '%s': ", k, r->name);
                print_extension(r);
                printf("\n");
            } else if (r->extension_note[0]) {
                printf("material %d '%s': %s\n", k, r->name, r->extension_note);
            }
        }
        printf("matremap gltf %s: %d of %d materials converted", o.direction, converted, result.material_count);
        if (kept > 0) printf(", %d kept with metal-rough values of %s own", kept, kept == 1 ? "its" : "their");
        printf(" with %s%s%s", o.method, use_mlp ? " " : "", use_mlp ? net_path : "");
        if (tolerance && o.eps_given)
            printf(" (off-manifold tolerance %g)", o.eps);
        else if (tolerance)
            printf(" (off-manifold tolerance: half a code value of each texture, times its factor)");
        printf(" in %.2f s; wrote %s\n", seconds, o.output);
        if (converted > 0) {
            printf("matremap gltf %s: %zu of %zu texel%s flagged", o.direction, total.flagged, texels,
                   texels == 1 ? "" : "s");
            if (total.flagged > 0) {
                printf(": ");
                print_reasons(&total, off_computed, off_meaning);
            }
            printf("\n");
        }
        if (totals.extensions > 0) {
            printf("matremap gltf %s: %d material%s with ", o.direction, totals.extensions,
                   totals.extensions == 1 ? "" : "s");
            print_extension(&total);
            printf("\n");
        } else if (to_metal && o.core_only) {
            printf("matremap gltf %s: core metal-rough values only (--core-only): no KHR_materials_specular\n",
                   o.direction);
        }
        if (o.keep_unused) {
            printf("unreferenced textures, images and samplers kept (--keep-unused)\n");
        } else {
            printf("pruned %d texture%s, %d image%s and %d sampler%s that nothing refers to", pruned.textures,
                   pruned.textures == 1 ? "" : "s", pruned.images, pruned.images == 1 ? "" : "s", pruned.samplers,
                   pruned.samplers == 1 ? "" : "s");
            if (pruned.uncertain > 0)
                printf(" (%d kept that only extensions or extras this tool cannot read may refer to)",
                       pruned.uncertain);
            printf("\n");
        }
    } else if (code == CLI_EXIT_OK) {
        static const char *const kinds[] = {"skipped", "converted", "kept", "converted"};
        printf("{\"command\": \"gltf %s\", \"input\": ", o.direction);
        cli_json_string(stdout, o.input);
        printf(", \"output\": ");
        cli_json_string(stdout, o.output);
        printf(", \"method\": \"%s\", \"convention\": \"%s\", \"seconds\": %.6f, \"tolerance\": ", o.method,
               o.convention == MR_WF_DIFFUSE_PLAIN ? "paper" : "gltf", seconds);
        if (tolerance)
            printf("\"%s\", \"eps\": %.17g", tolerance, o.eps_given ? o.eps : MR_WF_DEFAULT_EPS);
        else
            printf("null, \"eps\": null");
        for (int which = MR_GLTF_CONVERTED; which <= MR_GLTF_KEPT; which++) {
            printf(", \"%s\": [", kinds[which]);
            for (int k = 0, first = 1; k < result.material_count; k++)
                if (outcomes[k].outcome == (mr_gltf_convert_outcome)which ||
                    (which == MR_GLTF_CONVERTED && outcomes[k].outcome == MR_GLTF_SHARED)) {
                    printf("%s%d", first ? "" : ", ", k);
                    first = 0;
                }
            printf("]");
        }
        printf(", \"materials\": [");
        for (int k = 0; k < result.material_count; k++) {
            const mr_gltf_material_report *r = &outcomes[k];
            printf("%s{\"index\": %d, \"name\": ", k ? ", " : "", k);
            cli_json_string(stdout, r->name);
            printf(", \"outcome\": \"%s\", \"reason\": ", kinds[r->outcome]);
            if (r->outcome == MR_GLTF_CONVERTED || r->outcome == MR_GLTF_SHARED)
                printf("null");
            else
                cli_json_string(stdout, r->reason);
            printf(", \"width\": %d, \"height\": %d, \"flagged\": %zu, \"flags\": ", r->width, r->height,
                   r->flagged);
            print_json_reasons(r, off_computed && (r->outcome == MR_GLTF_CONVERTED || r->outcome == MR_GLTF_SHARED));
            printf(", \"extension\": ");
            if (r->extension)
                print_json_extension(r);
            else
                printf("null");
            printf(", \"seconds\": %.6f}", r->seconds);
        }
        printf("], \"texels\": %zu, \"flagged\": %zu, \"flags\": ", texels, total.flagged);
        print_json_reasons(&total, off_computed && converted > 0);
        printf(", \"core_only\": %s, \"extension\": ", o.core_only ? "true" : "false");
        if (totals.extensions > 0)
            print_json_extension(&total);
        else
            printf("null");
        printf(", \"keep_unused\": %s, \"pruned\": {\"textures\": %d, \"images\": %d, \"samplers\": %d, "
               "\"uncertain\": %d}}\n", o.keep_unused ? "true" : "false", pruned.textures, pruned.images,
               pruned.samplers, pruned.uncertain);
    }
    mr_gltf_convert_result_free(&result);
    mr_transform_free(transform);
    mr_mlp_free(net);
    return code;
}

int cmd_gltf(int argc, char **argv) {
    for (int i = 1; i < argc; i++)
        if (cli_is_help(argv[i])) {
            print_help();
            return CLI_EXIT_OK;
        }
    const char **inputs = calloc((size_t)argc + 1, sizeof *inputs);
    if (inputs == NULL) {
        mr_clear_error(); // cli_fail says "out of memory"
        return cli_fail("gltf", MR_ERR_NOMEM);
    }
    int code = gltf_main(argc, argv, inputs);
    free(inputs);
    return code;
}
