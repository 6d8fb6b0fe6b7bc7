/*
 * cmd_workflow.c — `matremap spec2metal` and `matremap metal2spec`, also commands of their own (main.c dispatches
 * on the program's name, so `ln -s matremap spec2metal` works): texture maps of one workflow in, the other's out,
 * through a transform of src/transform (docs/architecture.md, "A conversion").
 *
 * One driver serves both directions (run_conversion), told by a `conversion` table which maps feed the
 * transform's input slots and how its output slots are packed into files. The steps: parse the maps (an image
 * file or a constant each), name the outputs and refuse any that is an input, then the library's texture-set
 * conversion (mr_transform_convert_texture_set: read and check the files, one size, constants broadcast; convert;
 * pack), write the outputs and the flag picture all or none (mr_texture_set_write), print one summary line or JSON
 * (its figures: mr_texture_set_stats). Constants, formats and output names follow transform.h's rules.
 */
#include <float.h>
#include <stdint.h>
#include <string.h>

#include "cli.h"

#define NETWORK_FILE "spec2metal.mlp"
#define MAX_MAPS 5
#define MAX_OUTPUTS 3
#define PATH_SIZE 4096

/* ---- maps given on the command line ----------------------------------------------------------------------- */

typedef enum map_kind {
    MAP_COLOR,  /* RGB(A) colour; a constant is one number (grey) or R,G,B */
    MAP_DATA,   /* one linear value per texel (a grey RGB file will do); a constant is one number */
    MAP_PACKED  /* channels read by index (--specular-glossiness, --metallic-roughness); files only */
} map_kind;

typedef struct map_arg {
    const char *option;       /* "--diffuse": names the map in messages */
    map_kind kind;
    const char *model, *param; /* the BRDF parameter the map holds: how 8/16-bit files are decoded follows the one
                                  rule (mr_img_read_param_map: a packed map, by its RGB's parameter) */
    int min_channels;         /* MAP_PACKED: the channels it must have (3 or 4) */
    const char *layout;       /* MAP_PACKED: what those channels hold, for messages */
    const char *text;         /* as given; NULL when absent */
    char path[PATH_SIZE];     /* a file: the file, the text without its :linear or :srgb */
    mr_map_encoding how;      /* a file: the encoding it gives (MR_MAP_AS_PARAMETER when none) */
    int is_constant;
    double constant[3];       /* grey broadcast */
} map_arg;

static map_arg map_colour(const char *option, const char *model, const char *param) {
    return (map_arg){.option = option, .kind = MAP_COLOR, .model = model, .param = param};
}
static map_arg map_data(const char *option, const char *model, const char *param) {
    return (map_arg){.option = option, .kind = MAP_DATA, .model = model, .param = param};
}
static map_arg map_packed(const char *option, const char *model, const char *param, int channels,
                          const char *layout) {
    return (map_arg){.option = option, .kind = MAP_PACKED, .model = model, .param = param, .min_channels = channels,
                     .layout = layout};
}

/* The descriptor entry of the parameter a map holds (the models and names are this file's own: never NULL). */
static const mr_brdf_param *map_param(const map_arg *m) {
    const mr_brdf_model *model = mr_brdf_find(m->model);
    const int index = model != NULL ? mr_brdf_param_index(model, m->param) : -1;
    return index >= 0 ? &model->params[index] : NULL;
}

/* Take the text of a map option: a constant (text made only of number characters: one number, or R,G,B for a
 * colour map, in [0, 1]) or a file name ("./0.5" names a file), FILE[:linear|srgb] (cli.h). Returns 0 and prints a
 * usage error for a malformed constant or file, a second use of the option, or a constant where only files will
 * do. */
static int set_map(const char *command, map_arg *m, const char *text) {
    if (m->text != NULL) return cli_usage_error(command, "%s given twice", m->option) == 0;
    m->text = text;
    if (!mr_texture_constant_like(text)) {
        char label[PATH_SIZE + 64];
        snprintf(label, sizeof label, "%s %s", m->option, text);
        if (mr_map_ref_check(label, text, 0) != MR_OK) return cli_usage_error(command, "%s", mr_last_error()) == 0;
        size_t length;
        int channel;
        mr_map_ref_split(text, 0, &length, &channel, &m->how);
        if (length >= sizeof m->path) return cli_usage_error(command, "%s: the file name is too long", m->option) == 0;
        memcpy(m->path, text, length);
        m->path[length] = '\0';
        return 1;
    }
    if (m->kind == MAP_PACKED)
        return cli_usage_error(command, "%s '%s': expected an image file (%s)", m->option, text, m->layout) == 0;
    mr_status status = mr_texture_constant_parse(text, m->kind == MAP_COLOR, m->constant);
    if (status == MR_OK) {
        m->is_constant = 1;
        return 1;
    }
    if (status == MR_ERR_INVALID_ARG) // a number outside [0, 1], named by the library
        return cli_usage_error(command, "%s '%s': %s", m->option, text, mr_last_error()) == 0;
    return cli_usage_error(command, "%s '%s': expected an image file or %s", m->option, text,
                           m->kind == MAP_COLOR ? "a constant (one number or R,G,B in [0, 1])"
                                                : "a constant (one number in [0, 1])") == 0;
}

static int is_file(const map_arg *m) { return m->text != NULL && !m->is_constant; }

/* The maps as the library's texture-set conversion takes them: each file's path, the parameter it holds (the one
 * rule: the parameter's encoding, or the map's :linear or :srgb), what its file must be (a data map grey, a packed
 * map's channels), its label for messages (labels[k]: "--glossiness 'g.png'") and its constant. */
static void texture_maps(map_arg *const *maps, int count, mr_img_param_map *reads, char (*labels)[PATH_SIZE + 64],
                         double (*constants)[3]) {
    for (int k = 0; k < count; k++) {
        const map_arg *m = maps[k];
        snprintf(labels[k], sizeof labels[k], "%s '%s'", m->option, m->text ? m->text : "");
        reads[k] = (mr_img_param_map){is_file(m) ? m->path : NULL, map_param(m), m->how, NULL, {0}, labels[k],
                                      m->kind == MAP_PACKED ? m->min_channels : 0, m->layout, m->kind == MAP_DATA,
                                      strcmp(m->option, "--glossiness") == 0
                                          ? " (an RGBA spec-gloss texture goes to --specular-glossiness)" : NULL};
        memcpy(constants[k], m->constant, sizeof constants[k]);
    }
}

/* ---- outputs ---------------------------------------------------------------------------------------------- */

typedef struct output {
    char path[PATH_SIZE];
} output;

/* The shared output options. */
typedef struct out_options {
    const char *prefix;     /* NULL: print only (every map a constant) */
    const char *format;     /* png, exr, tif; NULL = from the first input file */
    const char *flags_path; /* --flags */
    int bits, pack, json;
    int threads;            /* --threads: mr_wf_options.threads (0 automatic) */
} out_options;

/* Name the outputs PREFIX_<name>.EXT (mr_texture_output_path) and check the options; refuse (exit 2, cli_plan_check)
 * an output that is an input (a map, --weights, or the installed network the transform loaded, `network`, "" for
 * none) or another output (--flags named like one). */
static int plan_outputs(const char *command, out_options *o, map_arg *const *maps, int map_count, const char *weights,
                        const char *network, const mr_texture_layout *layouts, output *outputs, int count) {
    if (o->format == NULL) {
        const char *paths[MAX_MAPS];
        for (int k = 0; k < map_count; k++) paths[k] = is_file(maps[k]) ? maps[k]->path : NULL;
        o->format = mr_texture_default_format(paths, map_count);
    }
    if (mr_texture_check_bits(o->format, o->bits) != MR_OK)
        return cli_usage_error(command, "--bits %d: %s", o->bits, mr_last_error());
    if (o->prefix == NULL) return CLI_EXIT_OK; // nothing is written
    for (int k = 0; k < count; k++)
        if (mr_texture_output_path(o->prefix, &layouts[k], o->format, outputs[k].path, sizeof outputs[k].path) != MR_OK)
            return cli_usage_error(command, "-o '%s': the prefix is too long", o->prefix);
    mr_output_plan io = {0};
    for (int m = 0; m < map_count; m++)
        if (is_file(maps[m])) mr_output_plan_inputf(&io, maps[m]->path, "%s %s", maps[m]->option, maps[m]->text);
    if (weights != NULL) mr_output_plan_inputf(&io, weights, "--weights %s", weights);
    if (network != NULL && network[0] != '\0') mr_output_plan_inputf(&io, network, "the network %s", network);
    for (int k = 0; k < count; k++) mr_output_plan_outputf(&io, outputs[k].path, "-o %s", o->prefix);
    if (o->flags_path != NULL) mr_output_plan_output(&io, o->flags_path, "--flags");
    int code = cli_plan_check(command, &io);
    mr_output_plan_free(&io);
    return code;
}

/* Write the outputs and the flag map (if asked), all or none (mr_texture_set_write). Returns an exit code (messages
 * printed). */
static int write_outputs(const char *command, const out_options *o, const mr_texture_layout *layouts,
                         const mr_texture_result *result, int count) {
    char label[PATH_SIZE + 8];
    snprintf(label, sizeof label, "-o %s", o->prefix);
    const mr_texture_write_options wo = {o->prefix, label, o->format, o->bits, o->flags_path, "--flags", NULL,
                                         o->threads};
    const mr_status status = mr_texture_set_write(result, layouts, count, &wo);
    return status == MR_OK ? CLI_EXIT_OK : cli_fail(command, status);
}

/* ---- the summary ------------------------------------------------------------------------------------------- */

typedef struct quantity {
    const char *name;
    const float *values;
    int channels; /* 1 or 3 */
} quantity;

typedef struct summary {
    const char *command, *method, *weights;
    const char *convention; /* "gltf" or "paper"; NULL where it does not apply (khronos) */
    double f0;           /* < 0: not applicable (mlp) */
    int off_manifold;    /* 0: the method does not compute the flag */
    int width, height;
    double seconds[3];   /* read, convert, write */
    const uint8_t *flags;
    quantity values[3];
    const mr_texture_result *result; /* the conversion: its figures (mr_texture_set_stats) */
    int input_tolerances; /* spec2metal: off-manifold tolerances from the inputs' encodings (else eps) */
    double eps;           /* spec2metal: the tolerance given by --eps */
} summary;

static void print_summary(const summary *s, const out_options *o, const output *outputs, int count) {
    size_t n = (size_t)s->width * (size_t)s->height;
    static const unsigned reasons[4] = {MR_WF_CLAMPED_INPUT, MR_WF_NONFINITE_INPUT, MR_WF_OFF_MANIFOLD,
                                        MR_WF_METHOD_FAILED};
    size_t counts[4];
    mr_flags_count(s->flags, n, reasons, 4, counts);
    const size_t clamped = counts[0], nonfinite = counts[1], off = counts[2], failed = counts[3];
    if (!o->json) {
        printf("matremap %s: %dx%d = %zu texel%s, method %s", s->command, s->width, s->height, n, n == 1 ? "" : "s",
               s->method);
        if (s->weights) printf(" (%s)", s->weights);
        if (s->f0 >= 0.0) printf(" (F0 %g)", s->f0);
        if (s->convention) printf(", %s convention", s->convention);
        printf(": read %.3f s, convert %.3f s, write %.3f s; flagged: %zu clamped input, %zu non-finite input",
               s->seconds[0], s->seconds[1], s->seconds[2], clamped, nonfinite);
        if (strcmp(s->command, "spec2metal") == 0) { // metal -> spec is a closed formula: neither flag applies
            if (s->off_manifold && s->input_tolerances)
                printf(", %zu off-manifold (tolerance from each input's encoding)", off);
            else if (s->off_manifold)
                printf(", %zu off-manifold (tolerance %g)", off, s->eps);
            else
                printf(", off-manifold not computed");
            printf(", %zu method failed", failed);
        } else if (s->off_manifold) { // metal2spec, glTF convention: diffuse that spec-gloss cannot store
            printf(", %zu off-manifold (spec-gloss diffuse above 1, clamped)", off);
        }
        printf("\n");
        if (n == 1) { // a single texel (constants): its values, in the name=value form of other commands
            for (int q = 0; q < 3; q++) {
                const quantity *v = &s->values[q];
                if (v->channels == 3)
                    printf("%s%s=%.6g,%.6g,%.6g", q ? " " : "", v->name, v->values[0], v->values[1], v->values[2]);
                else
                    printf("%s%s=%.6g", q ? " " : "", v->name, v->values[0]);
            }
            printf("\n");
        }
        if (o->prefix != NULL) {
            fprintf(stderr, "matremap %s: wrote", s->command);
            for (int k = 0; k < count; k++) fprintf(stderr, " %s", outputs[k].path);
            if (o->flags_path) fprintf(stderr, " %s", o->flags_path);
            fprintf(stderr, "\n");
        }
        return;
    }
    printf("{\"command\": \"%s\", \"width\": %d, \"height\": %d, \"texels\": %zu, \"method\": \"%s\", \"weights\": ",
           s->command, s->width, s->height, n, s->method);
    if (s->weights)
        cli_json_string(stdout, s->weights);
    else
        printf("null");
    if (s->f0 >= 0.0)
        printf(", \"f0\": %.17g", s->f0);
    else
        printf(", \"f0\": null");
    printf(", \"convention\": ");
    if (s->convention)
        cli_json_string(stdout, s->convention);
    else
        printf("null");
    printf(", \"seconds\": {\"read\": %.6f, \"convert\": %.6f, \"write\": %.6f}", s->seconds[0], s->seconds[1],
           s->seconds[2]);
    if (strcmp(s->command, "spec2metal") == 0 && s->off_manifold)
        printf(", \"tolerance\": \"%s\", \"eps\": %.17g", s->input_tolerances ? "encoding" : "eps",
               s->input_tolerances ? MR_WF_DEFAULT_EPS : s->eps);
    else
        printf(", \"tolerance\": null, \"eps\": null");
    printf(", \"flags\": {\"clamped_input\": %zu, \"nonfinite_input\": %zu, \"off_manifold\": ", clamped, nonfinite);
    if (s->off_manifold)
        printf("%zu", off);
    else
        printf("null");
    printf(", \"method_failed\": %zu}, \"outputs\": [", failed);
    for (int k = 0; o->prefix != NULL && k < count; k++) {
        printf("%s", k ? ", " : "");
        cli_json_string(stdout, outputs[k].path);
    }
    if (o->flags_path) {
        printf("%s", o->prefix != NULL && count ? ", " : "");
        cli_json_string(stdout, o->flags_path);
    }
    printf("], \"values\": {");
    // Each quantity's minimum, mean and maximum as converted (before the files' quantisation).
    for (int q = 0; q < 3; q++) {
        const quantity *v = &s->values[q];
        mr_texture_stats st = {0};
        mr_texture_set_stats(s->result, q, &st); // never fails: the result holds every slot
        printf("%s\"%s\": {", q ? ", " : "", v->name);
        const char *keys[3] = {"min", "mean", "max"};
        for (int k = 0; k < 3; k++) {
            printf("%s\"%s\": %s", k ? ", " : "", keys[k], v->channels == 3 ? "[" : "");
            for (int c = 0; c < v->channels; c++)
                printf("%s%.9g", c ? ", " : "", k == 0 ? st.min[c] : (k == 1 ? st.mean[c] : st.max[c]));
            printf("%s", v->channels == 3 ? "]" : "");
        }
        printf("}");
    }
    printf("}}\n");
}

/* ---- options both commands share --------------------------------------------------------------------------- */

/* Take one of the output options at argv[*i]. Returns 1 if taken, 0 if argv[*i] is something else, -1 after a
 * usage error. */
static int take_output_option(const char *command, int argc, char **argv, int *i, out_options *o) {
    const char *value = NULL;
    int taken;
    if ((taken = cli_take_option(command, argc, argv, i, "--output", &value)) ||
        (taken = cli_take_option(command, argc, argv, i, "-o", &value))) {
        if (taken > 0) o->prefix = value;
    } else if ((taken = cli_take_option(command, argc, argv, i, "--format", &value))) {
        if (taken > 0 && (o->format = mr_texture_format_from_name(value)) == NULL) {
            cli_usage_error(command, "--format '%s': unknown format (valid: png, exr, tif)", value);
            taken = -1;
        }
    } else if ((taken = cli_take_option(command, argc, argv, i, "--bits", &value))) {
        if (taken > 0 && !cli_parse_int(command, "--bits", value, 8, 32, &o->bits)) taken = -1;
    } else if ((taken = cli_take_option(command, argc, argv, i, "--flags", &value))) {
        if (taken > 0) o->flags_path = value;
    } else if ((taken = cli_take_option(command, argc, argv, i, "--threads", &value))) {
        if (taken > 0 && !cli_parse_int(command, "--threads", value, 0, 1024, &o->threads)) taken = -1;
    } else if (strcmp(argv[*i], "--pack") == 0) {
        o->pack = taken = 1;
    } else if (strcmp(argv[*i], "--json") == 0) {
        o->json = taken = 1;
    }
    return taken;
}

/* The method options both commands take: --method NAME, --f0 F, --convention gltf|paper. */
typedef struct method_options {
    const char *name;         /* as given; the command checks it */
    double f0;                /* default MR_WF_F0_GLTF */
    int f0_given;
    mr_wf_diffuse convention; /* default MR_WF_DIFFUSE_SPECGLOSS (--convention gltf) */
} method_options;

/* Take one option both commands share at argv[*i]: an output option, one of the `count` maps, or a method option.
 * Returns 1 if taken, 0 if argv[*i] is something else, -1 after a usage error. */
static int take_common_option(const char *command, int argc, char **argv, int *i, out_options *o,
                              map_arg *const *maps, int count, method_options *m) {
    const char *value = NULL;
    int taken = take_output_option(command, argc, argv, i, o);
    if (taken) return taken;
    for (int k = 0; k < count; k++)
        if ((taken = cli_take_option(command, argc, argv, i, maps[k]->option, &value)))
            return taken < 0 || !set_map(command, maps[k], value) ? -1 : 1;
    if ((taken = cli_take_option(command, argc, argv, i, "--method", &value))) {
        if (taken > 0) m->name = value;
        return taken;
    }
    if ((taken = cli_take_option(command, argc, argv, i, "--f0", &value))) {
        if (taken < 0 || !cli_parse_double(command, "--f0", value, 0.0, 0.999, &m->f0)) return -1;
        m->f0_given = 1;
        return 1;
    }
    if ((taken = cli_take_option(command, argc, argv, i, "--convention", &value)))
        return taken < 0 || !cli_parse_convention(command, value, &m->convention) ? -1 : 1;
    return 0;
}

/* The usage error for an argument neither command knows; `example` shows how a map is given. */
static int unknown_argument(const char *command, const char *arg, const char *example) {
    if (arg[0] == '-') return cli_usage_error(command, "unknown option '%s'", arg);
    return cli_usage_error(command, "unexpected argument '%s' (maps are given as options, e.g. %s)", arg, example);
}

/* -o is required unless every map is a constant (then the single texel is printed). */
static int check_prefix(const char *command, const out_options *o, map_arg *const *maps, int count) {
    if (o->prefix != NULL) return CLI_EXIT_OK;
    for (int k = 0; k < count; k++)
        if (is_file(maps[k])) return cli_usage_error(command, "missing -o PREFIX");
    if (o->flags_path != NULL || o->pack || o->format != NULL || o->bits != 0)
        return cli_usage_error(command, "--flags, --pack, --format and --bits need -o PREFIX");
    return CLI_EXIT_OK;
}

/* ---- spec2metal --------------------------------------------------------------------------------------------- */

static void print_spec2metal_help(void) {
    printf("Usage: matremap spec2metal --diffuse MAP --specular MAP (--glossiness MAP | --roughness MAP)\n"
           "                           -o PREFIX [options]\n"
           "       matremap spec2metal --diffuse MAP --specular-glossiness SG.png -o PREFIX [options]\n"
           "       (also a command of its own: 'spec2metal ARGS' is 'matremap spec2metal ARGS')\n"
           "\n"
           "Converts specular-workflow texture maps (diffuse colour, specular F0 colour, glossiness or roughness)\n"
           "into metallic-workflow ones (base colour, metallic, roughness), texel by texel (docs/workflow.md).\n"
           "\n"
           "A MAP is an image file or a constant: one number, or R,G,B for a colour, linear in [0, 1] (a file named\n"
           "like a number is written ./0.5). Files are read by the one rule of every command ('matremap models\n"
           "gltf-specgloss' and 'models gltf' show it per parameter): colour maps (diffuse, specular, base colour)\n"
           "are sRGB-encoded in 8/16-bit files; data maps (glossiness, roughness, metallic) are linear, and a grey\n"
           "RGB file serves as one; float files (EXR, float TIFF) are always linear. FILE:linear or FILE:srgb\n"
           "overrides it for one map (:srgb on a float file is an error). Files must have the same size and\n"
           "constants broadcast to it; with constants only, the one texel is converted and printed. roughness =\n"
           "1 - glossiness (the spec-gloss convention). The diffuse map's alpha, if it has one, becomes the base\n"
           "colour's alpha.\n"
           "\n"
           "Inputs:\n"
           "  --diffuse MAP              diffuse colour, RGB or RGBA\n"
           "  --specular MAP             specular colour (F0)\n"
           "  --glossiness MAP           glossiness\n"
           "  --roughness MAP            roughness (passes through)\n"
           "  --specular-glossiness SG   the KHR_materials_pbrSpecularGlossiness texture: RGB specular (sRGB in\n"
           "                             8/16-bit files) and A glossiness (linear); replaces --specular and\n"
           "                             --glossiness\n"
           "\n");
    printf("Method:\n"
           "  --method M        mlp (default): the trained network (6 x 300 x 4, docs/training.md): weighted\n"
           "                    wherever Eq. 2 is exactly invertible, a learned correction off it (first on the\n"
           "                    shared assets by object SSIM, docs/evaluation.md);\n"
           "                    weighted: Eq. 3 per channel, one albedo-weighted metallic (the paper's strategy 2);\n"
           "                    mean: Eq. 3 per channel, the mean metallic (strategy 1);\n"
           "                    khronos: the glTF project's converter (perceived brightness)\n"
           "  --weights FILE    the network for mlp; default: $MATREMAP_WEIGHTS, else " NETWORK_FILE " in the\n"
           "                    source tree's data/ or in share/matremap/ of the installed tree\n"
           "  --f0 F            the dielectric F0 of weighted and mean: 0.04 (default, glTF) or the paper's 0.03;\n"
           "                    khronos takes only 0.04, and mlp learned its own from its training data\n"
           "  --eps E           the reflectance tolerance of weighted, mean and khronos, for every value: a texel\n"
           "                    is off-manifold when converting it back misses it by more than the tolerances of\n"
           "                    its diffuse and specular, and an Eq. 3 root within E of F0 is ambiguous. Default:\n"
           "                    each value's own, half a code value of its file at that texel (8/16-bit, sRGB\n"
           "                    or linear), at least 1e-6 (float files and constants), so a clean 8-bit\n"
           "                    metal-rough export flags nothing (docs/workflow.md, \"Tolerances\")\n"
           "  --convention C    how the diffuse map is read: gltf (default): as glTF renders spec-gloss, dimmed by\n"
           "                    1 - max specular, so the result looks the same in a glTF renderer; paper: as the\n"
           "                    Lambert lobe itself (Eq. 2 as printed, the `ggx` model). khronos has its own\n"
           "\n");
    printf("Output:\n"
           "  -o, --output PREFIX   PREFIX_basecolor.EXT (RGB, or RGBA with the diffuse's alpha), PREFIX_metallic.EXT\n"
           "                        and PREFIX_roughness.EXT; required unless every MAP is a constant. No '_'\n"
           "                        after a PREFIX ending in '/', '_', '-' or '.' (-o out/ writes out/basecolor.png);\n"
           "                        missing folders are made\n"
           "  --pack                glTF packing: PREFIX_basecolor.EXT and PREFIX_metallicRoughness.EXT\n"
           "                        (R 0, G roughness, B metallic)\n"
           "  --format F            png, exr or tif (default: the first input file's, if one of these; else png)\n"
           "  --bits N              8 (default) or 16 for png and tif; 16 (half) or 32 (default) for exr\n"
           "  --flags FILE          a picture of the flagged texels: black clean, red method failed, magenta\n"
           "                        non-finite input, blue clamped input, orange off-manifold (a texel with several\n"
           "                        flags takes the first of these colours)\n"
           "  --json                the summary as JSON on stdout (with each output's minimum, mean and maximum)\n"
           "  --threads N           OpenMP threads (default 0: automatic, a team for maps of 16384 texels or more)\n"
           "  --help                this text\n"
           "\n");
    printf("Prints one line: the size, the method, the read, convert and write times, and the texels flagged as\n"
           "clamped input (a value outside [0, 1]), non-finite input (NaN or infinity, from EXR: read as 0, and a\n"
           "non-finite glossiness or roughness as roughness 1), off-manifold (no metallic material has these maps\n"
           "within their tolerance: a coloured dielectric specular, specular above the albedo or below F0; not\n"
           "computed for mlp) and method failed (the network returned NaN). The inputs are never overwritten.\n"
           "\n"
           "Examples:\n"
           "  matremap spec2metal --diffuse Avocado_diffuse.png --specular-glossiness Avocado_specularGlossiness.png\n"
           "                      -o avocado --pack\n"
           "  matremap spec2metal --diffuse d.exr --specular 0.04 --roughness r.exr --method weighted -o out\n"
           "  spec2metal --diffuse 0.5,0.2,0.1 --specular 0.04 --glossiness 0.6 --method weighted\n");
}

/* ---- one conversion, either direction ---------------------------------------------------------------------- */

/* What a command converts: the transform's models, its maps and how they feed the slots, its outputs. */
typedef struct conversion {
    const char *command, *source, *target;
    map_arg *const *maps;
    int map_count;
    mr_texture_source inputs[3];      /* feeding the transform's input slots */
    const mr_texture_layout *layouts; /* unpacked: one file per output slot (their names name the printed values) */
    int layout_count;
    const mr_texture_layout *packed;  /* --pack */
    int packed_count;
} conversion;

/* Convert as `cv` says with the method options `m`, the output options `o`, the network file `weights` (NULL:
 * the installed one) and the tolerance `eps` (when eps_given). Returns an exit code. */
static int run_conversion(const conversion *cv, const method_options *m, out_options *o, const char *weights,
                          double eps, int eps_given) {
    const char *command = cv->command;
    const mr_transform_kind *kind = mr_transform_find(cv->source, cv->target, m->name);
    if (kind == NULL) return cli_usage_error(command, "--method '%s': %s", m->name, mr_last_error());
    for (int j = 0; j < kind->output_count; j++) { // every computed output must have a file to go to
        int placed = (kind->outputs[j].flags & MR_SLOT_CONSTANT) != 0;
        for (int l = 0; l < cv->layout_count && !placed; l++) placed = cv->layouts[l].slot[0] == j;
        if (!placed)
            return cli_usage_error(command, "--method %s writes %s, which texture maps here cannot hold (it is a "
                                   "glTF route: matremap gltf %s --method %s)", m->name, kind->outputs[j].name,
                                   command, m->name);
    }
    if (m->f0_given && !(kind->flags & MR_TRANSFORM_USES_F0))
        return cli_usage_error(command, "--f0 applies to the analytic methods (weighted, mean, khronos); the network "
                               "of --method %s learned the F0 of its training data", m->name);
    if (eps_given && !(kind->flags & MR_TRANSFORM_TOLERANCES))
        return cli_usage_error(command, "--eps applies to the analytic methods (weighted, mean, khronos); --method "
                               "%s computes no off-manifold flag", m->name);
    if (weights != NULL && !(kind->flags & MR_TRANSFORM_NEEDS_NETWORK))
        return cli_usage_error(command, "--weights goes with --method mlp, not %s", m->name);
    if (weights != NULL && weights[0] == '\0') return cli_usage_error(command, "--weights: empty file name");
    mr_transform_options to = {0};
    to.threads = o->threads;
    to.dielectric_f0 = m->f0_given ? m->f0 : 0.0;
    if (m->f0_given && m->f0 == 0.0) return cli_usage_error(command, "--f0 0: expected a dielectric F0 above 0");
    if (eps_given) to.eps = eps > 0.0 ? eps : DBL_MIN; // --eps 0: no tolerance but float rounding
    to.plain_diffuse = m->convention == MR_WF_DIFFUSE_PLAIN;
    mr_transform *t = NULL;
    mr_mlp *net = NULL;
    mr_status status = MR_OK;
    if (weights != NULL && (status = mr_mlp_read(weights, &net)) != MR_OK) {
        fprintf(stderr, "matremap %s: error: %s (given by --weights)\n", command, mr_last_error());
        return cli_exit_code(status);
    }
    to.network = net;
    status = mr_transform_create(kind, &to, &t);
    if (status != MR_OK) {
        mr_mlp_free(net);
        if (status == MR_ERR_INVALID_ARG && m->f0_given)
            return cli_usage_error(command, "--f0 %g with --method %s: %s", m->f0, m->name, mr_last_error());
        const char *hint = "; give --weights FILE or set MATREMAP_WEIGHTS, or choose an analytic --method (weighted, "
                           "mean, khronos)";
        fprintf(stderr, "matremap %s: error: %s%s\n", command, mr_last_error(),
                kind->flags & MR_TRANSFORM_NEEDS_NETWORK ? hint : "");
        return cli_exit_code(status);
    }
    const mr_texture_layout *layouts = o->pack ? cv->packed : cv->layouts;
    const int output_count = o->pack ? cv->packed_count : cv->layout_count;
    output outputs[MAX_OUTPUTS];
    memset(outputs, 0, sizeof outputs);
    int code = check_prefix(command, o, cv->maps, cv->map_count);
    if (code == CLI_EXIT_OK)
        code = plan_outputs(command, o, cv->maps, cv->map_count, weights, mr_transform_network_path(t), layouts,
                            outputs, output_count);

    // Read, convert and pack: the library's texture-set conversion.
    mr_img_param_map reads[MAX_MAPS];
    char labels[MAX_MAPS][PATH_SIZE + 64];
    double constants[MAX_MAPS][3];
    texture_maps(cv->maps, cv->map_count, reads, labels, constants);
    const mr_texture_set set = {reads, (const double(*)[3])constants, cv->map_count, cv->inputs, eps_given,
                                layouts, o->prefix != NULL ? output_count : 0, o->threads};
    mr_texture_result result = {0};
    double seconds[3] = {0.0, 0.0, 0.0};
    if (code == CLI_EXIT_OK && (status = mr_transform_convert_texture_set(t, &set, &result)) != MR_OK) {
        const map_arg *refused = result.failed_map >= 0 ? cv->maps[result.failed_map] : NULL;
        // :srgb on a float file is a usage error, as the option's text is
        if (refused != NULL && result.failed_reading && status == MR_ERR_INVALID_ARG && refused->how == MR_MAP_SRGB)
            code = cli_usage_error(command, "'%s %s': %s", refused->option, refused->text, mr_last_error());
        else
            code = cli_fail(command, status);
    }
    if (code == CLI_EXIT_OK) memcpy(seconds, result.seconds, sizeof seconds);

    // Write.
    const double started = cli_now();
    if (code == CLI_EXIT_OK && o->prefix != NULL)
        code = write_outputs(command, o, layouts, &result, output_count);
    seconds[2] += cli_now() - started; // packing and writing

    if (code == CLI_EXIT_OK) {
        const mr_transform_options *used = mr_transform_options_of(t);
        const int convention = (kind->flags & MR_TRANSFORM_CONVENTION) != 0;
        summary s = {command, kind->name,
                     kind->flags & MR_TRANSFORM_NEEDS_NETWORK ? (weights ? weights : mr_transform_network_path(t))
                                                              : NULL,
                     convention ? mr_wf_diffuse_name(m->convention) : NULL,
                     kind->flags & MR_TRANSFORM_USES_F0 ? used->dielectric_f0 : -1.0,
                     (kind->flags & MR_TRANSFORM_TOLERANCES) ||
                         (convention && m->convention == MR_WF_DIFFUSE_SPECGLOSS && strcmp(command, "metal2spec") == 0),
                     result.width, result.height, {seconds[0], seconds[1], seconds[2]}, result.flags,
                     {{cv->layouts[0].name, result.converted[0]->pixels, 3},
                      {cv->layouts[1].name, result.converted[1]->pixels, kind->outputs[1].channels},
                      {cv->layouts[2].name, result.converted[2]->pixels, 1}},
                     &result, !eps_given, eps};
        print_summary(&s, o, outputs, output_count);
    }
    mr_texture_result_free(&result);
    mr_transform_free(t);
    mr_mlp_free(net);
    return code;
}

/* ---- spec2metal --------------------------------------------------------------------------------------------- */

static const mr_texture_layout metal_layouts[] = {
    {"basecolor", MR_IMG_COLOR, 4, {0, 0, 0, MR_LAYOUT_ALPHA}, {0, 1, 2, 0}},
    {"metallic", MR_IMG_DATA, 1, {1}, {0}},
    {"roughness", MR_IMG_DATA, 1, {2}, {0}},
};
static const mr_texture_layout metal_packed[] = {
    {"basecolor", MR_IMG_COLOR, 4, {0, 0, 0, MR_LAYOUT_ALPHA}, {0, 1, 2, 0}},
    {"metallicRoughness", MR_IMG_DATA, 3, {MR_LAYOUT_ZERO, 2, 1}, {0, 0, 0}}, // glTF: G roughness, B metallic
};

int cmd_spec2metal(int argc, char **argv) {
    const char *command = "spec2metal";
    map_arg diffuse = map_colour("--diffuse", "gltf-specgloss", "diffuse");
    map_arg specular = map_colour("--specular", "gltf-specgloss", "specular");
    map_arg glossiness = map_data("--glossiness", "gltf-specgloss", "glossiness");
    map_arg roughness = map_data("--roughness", "gltf", "roughness");
    // RGB specular (sRGB in 8/16-bit files, as the specular parameter), A glossiness (alpha: always linear).
    map_arg packed = map_packed("--specular-glossiness", "gltf-specgloss", "specular", 4,
                                "RGBA: specular RGB, glossiness A");
    map_arg *all[] = {&diffuse, &specular, &glossiness, &roughness, &packed};
    const char *weights = NULL;
    double eps = MR_WF_DEFAULT_EPS;
    int eps_given = 0;
    method_options m = {"mlp", MR_WF_F0_GLTF, 0, MR_WF_DIFFUSE_SPECGLOSS};
    out_options o = {0};

    for (int i = 1; i < argc; i++) {
        const char *value = NULL;
        if (cli_is_help(argv[i])) {
            print_spec2metal_help();
            return CLI_EXIT_OK;
        }
        int taken = take_common_option(command, argc, argv, &i, &o, all, 5, &m);
        if (taken < 0) return CLI_EXIT_USAGE;
        if (taken) continue;
        if ((taken = cli_take_option(command, argc, argv, &i, "--weights", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            weights = value;
        } else if ((taken = cli_take_option(command, argc, argv, &i, "--eps", &value))) {
            if (taken < 0 || !cli_parse_double(command, "--eps", value, 0.0, 0.5, &eps)) return CLI_EXIT_USAGE;
            eps_given = 1;
        } else {
            return unknown_argument(command, argv[i], "--diffuse D.png");
        }
    }
    if (diffuse.text == NULL) return cli_usage_error(command, "missing --diffuse MAP");
    if ((specular.text != NULL) + (packed.text != NULL) != 1)
        return cli_usage_error(command, "give the specular colour once: --specular MAP or --specular-glossiness SG");
    if ((glossiness.text != NULL) + (roughness.text != NULL) + (packed.text != NULL) != 1)
        return cli_usage_error(command, "give exactly one of --glossiness, --roughness and --specular-glossiness");
    // The gltf-specgloss -> gltf transforms; --convention paper reads the diffuse as Eq. 2 prints it.
    conversion cv = {command, "gltf-specgloss", "gltf", all, 5,
                     {{0, -1, 0}, {packed.text ? 4 : 1, -1, 0},
                      packed.text ? (mr_texture_source){4, 3, 0} : glossiness.text ? (mr_texture_source){2, 0, 0}
                                                                             : (mr_texture_source){3, 0, 1}},
                     metal_layouts, 3, metal_packed, 2};
    return run_conversion(&cv, &m, &o, weights, eps, eps_given);
}

/* ---- metal2spec --------------------------------------------------------------------------------------------- */

static void print_metal2spec_help(void) {
    printf("Usage: matremap metal2spec --basecolor MAP --metallic MAP --roughness MAP -o PREFIX [options]\n"
           "       matremap metal2spec --basecolor MAP --metallic-roughness MR.png -o PREFIX [options]\n"
           "       (also a command of its own: 'metal2spec ARGS' is 'matremap metal2spec ARGS')\n"
           "\n"
           "Converts metallic-workflow texture maps (base colour, metallic, roughness) into specular-workflow ones\n"
           "(diffuse colour, specular F0 colour, glossiness), texel by texel (docs/workflow.md):\n"
           "  diffuse = basecolor (1 - metallic),  specular = F0 (1 - metallic) + metallic basecolor  (Eq. 2),\n"
           "  glossiness = 1 - roughness.\n"
           "\n"
           "A MAP is an image file or a constant: one number, or R,G,B for a colour, linear in [0, 1] (a file named\n"
           "like a number is written ./0.5). Files are read by the one rule of every command ('matremap models\n"
           "gltf' shows it per parameter): colour maps (base colour) are sRGB-encoded in 8/16-bit files; data maps\n"
           "(metallic, roughness) are linear, and a grey RGB file serves as one; float files (EXR, float TIFF) are\n"
           "always linear. FILE:linear or FILE:srgb overrides it for one map (:srgb on a float file is an error).\n"
           "The outputs follow the same rule (diffuse and specular sRGB in png/tif). Files must have the same size\n"
           "and constants broadcast to it; with constants only, the one texel is converted and printed. The base\n"
           "colour's alpha, if it has one, becomes the diffuse map's alpha.\n"
           "\n"
           "Inputs:\n"
           "  --basecolor MAP            base colour, RGB or RGBA\n"
           "  --metallic MAP             metallic\n"
           "  --roughness MAP            roughness\n"
           "  --metallic-roughness MR    the glTF metallicRoughness texture (linear): G roughness, B metallic;\n"
           "                             replaces --metallic and --roughness\n"
           "\n");
    printf("Method:\n"
           "  --method M        eq2 (default): the paper's Eq. 2, exact; khronos: the glTF project's converter\n"
           "                    (its diffuse is renormalised by (1 - max specular) / (1 - 0.04))\n"
           "  --f0 F            the dielectric F0 of eq2: 0.04 (default, glTF) or the paper's 0.03; khronos takes\n"
           "                    only 0.04\n"
           "  --convention C    how the diffuse map is written: gltf (default): for glTF spec-gloss, which dims it\n"
           "                    by 1 - max specular, so eq2's diffuse is divided by that (a texel needing more\n"
           "                    than 1, e.g. a white dielectric, is clamped and flagged off-manifold); paper: Eq. 2's\n"
           "                    diffuse as it is. khronos has its own\n"
           "\n");
    printf("Output:\n"
           "  -o, --output PREFIX   PREFIX_diffuse.EXT (RGB, or RGBA with the base colour's alpha),\n"
           "                        PREFIX_specular.EXT and PREFIX_glossiness.EXT; required unless every MAP is a\n"
           "                        constant. No '_' after a PREFIX ending in '/', '_', '-' or '.' (-o out/ writes\n"
           "                        out/diffuse.png); missing folders are made\n"
           "  --pack                KHR_materials_pbrSpecularGlossiness packing: PREFIX_diffuse.EXT and\n"
           "                        PREFIX_specularGlossiness.EXT (RGB specular, sRGB in png/tif; A glossiness,\n"
           "                        linear)\n"
           "  --format F            png, exr or tif (default: the first input file's, if one of these; else png)\n"
           "  --bits N              8 (default) or 16 for png and tif; 16 (half) or 32 (default) for exr\n"
           "  --flags FILE          a picture of the flagged texels: black clean, magenta non-finite input, blue\n"
           "                        clamped input, orange off-manifold\n"
           "  --json                the summary as JSON on stdout (with each output's minimum, mean and maximum)\n"
           "  --threads N           OpenMP threads (default 0: automatic, a team for maps of 16384 texels or more)\n"
           "  --help                this text\n"
           "\n");
    printf("Prints one line: the size, the method, the read, convert and write times, and the texels flagged as\n"
           "clamped input (a value outside [0, 1]), non-finite input (NaN or infinity, from EXR) and, with the gltf\n"
           "convention, off-manifold (a diffuse spec-gloss cannot store: clamped to 1). The inputs are never\n"
           "overwritten.\n"
           "\n"
           "Examples:\n"
           "  matremap metal2spec --basecolor Avocado_baseColor.png "
           "--metallic-roughness Avocado_roughnessMetallic.png\n"
           "                      -o avocado --pack\n"
           "  matremap metal2spec --basecolor b.exr --metallic 1 --roughness 0.3 -o gold --format exr\n"
           "  metal2spec --basecolor 0.9,0.6,0.2 --metallic 1 --roughness 0.3\n");
}

static const mr_texture_layout spec_layouts[] = {
    {"diffuse", MR_IMG_COLOR, 4, {0, 0, 0, MR_LAYOUT_ALPHA}, {0, 1, 2, 0}},
    {"specular", MR_IMG_COLOR, 3, {1, 1, 1}, {0, 1, 2}},
    {"glossiness", MR_IMG_DATA, 1, {2}, {0}},
};
static const mr_texture_layout spec_packed[] = {
    {"diffuse", MR_IMG_COLOR, 4, {0, 0, 0, MR_LAYOUT_ALPHA}, {0, 1, 2, 0}},
    // RGB specular sRGB-encoded, A glossiness linear: what image_io does for a colour image with alpha.
    {"specularGlossiness", MR_IMG_COLOR, 4, {1, 1, 1, 2}, {0, 1, 2, 0}},
};

int cmd_metal2spec(int argc, char **argv) {
    const char *command = "metal2spec";
    map_arg basecolor = map_colour("--basecolor", "gltf", "base_color");
    map_arg metallic = map_data("--metallic", "gltf", "metallic");
    map_arg roughness = map_data("--roughness", "gltf", "roughness");
    map_arg packed = map_packed("--metallic-roughness", "gltf", "roughness", 3, "RGB: G roughness, B metallic");
    map_arg *all[] = {&basecolor, &metallic, &roughness, &packed};
    method_options m = {"eq2", MR_WF_F0_GLTF, 0, MR_WF_DIFFUSE_SPECGLOSS};
    out_options o = {0};

    for (int i = 1; i < argc; i++) {
        if (cli_is_help(argv[i])) {
            print_metal2spec_help();
            return CLI_EXIT_OK;
        }
        int taken = take_common_option(command, argc, argv, &i, &o, all, 4, &m);
        if (taken < 0) return CLI_EXIT_USAGE;
        if (!taken) return unknown_argument(command, argv[i], "--basecolor B.png");
    }
    if (basecolor.text == NULL) return cli_usage_error(command, "missing --basecolor MAP");
    if (packed.text != NULL ? (metallic.text || roughness.text) : (!metallic.text || !roughness.text))
        return cli_usage_error(command, "give --metallic MAP and --roughness MAP, or --metallic-roughness MR");
    conversion cv = {command, "gltf", "gltf-specgloss", all, 4,
                     {{0, -1, 0}, packed.text ? (mr_texture_source){3, 2, 0} : (mr_texture_source){1, 0, 0},
                      packed.text ? (mr_texture_source){3, 1, 0} : (mr_texture_source){2, 0, 0}},
                     spec_layouts, 3, spec_packed, 2};
    return run_conversion(&cv, &m, &o, NULL, 0.0, 0);
}
