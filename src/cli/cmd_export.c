/*
 * cmd_export.c — `matremap export INPUT -o OUT.mtlx|OUT.usda|OUT.gltf|OUT.glb [--to MODEL]`: a glTF asset's or a
 * MaterialX document's materials written as a MaterialX or USD document, or as a glTF asset, by one library call
 * (src/doc/doc.h: mr_doc_export_file); here the options, the progress line and one line per material. Many assets
 * (`export FOLDER|GLOB|ASSET... -o DIR --format F`): mr_doc_export_library, one line per asset and a total.
 */
#include <errno.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "cli.h"
#include "matremap.h"

static void print_help(void) {
    printf("usage: matremap export INPUT -o OUT.mtlx|OUT.usda|OUT.gltf|OUT.glb [--to MODEL] [options]\n"
           "       matremap export FOLDER|GLOB|ASSET... -o DIR --format mtlx|usda|gltf|glb [--resume] [--shard K/N]\n"
           "                       [options]\n"
           "\n"
           "Writes the materials of INPUT, a glTF asset (.gltf, .glb) or a MaterialX document (.mtlx), as a material\n"
           "document or a glTF asset. OUT's extension chooses the format:\n"
           "  .mtlx   MaterialX 1.39: a surfacematerial per material over an open_pbr_surface node (the default),\n"
           "          standard_surface (--to standard-surface) or gltf_pbr (--to gltf); maps as image nodes in a\n"
           "          nodegraph, colour maps with colorspace srgb_texture, data maps in the document's lin_rec709\n"
           "  .usda   USD: a Material per material with a UsdPreviewSurface (metallic workflow), a UsdUVTexture per\n"
           "          map (sourceColorSpace sRGB or raw) reading the \"st\" primvar; --to usd-preview (the default)\n"
           "  .gltf, .glb  glTF 2.0 (--to gltf, the only model): from a glTF asset, the asset itself (its materials\n"
           "          copied: the same parameters); from a .mtlx, an asset holding the materials as\n"
           "          pbrMetallicRoughness (+ KHR_materials_specular, _ior off their defaults), images, no meshes\n"
           "\n"
           "A MaterialX input is read by its surfacematerials: surface nodes open_pbr_surface, standard_surface,\n"
           "gltf_pbr and UsdPreviewSurface with constant inputs, and maps through image/tiledimage nodes (with\n"
           "texcoord, extract, multiply) in nodegraphs or at the top level; colorspace and fileprefix are read, map\n"
           "paths rewritten relative to OUT. Anything else a material uses (other nodes, interfacename, looks, node\n"
           "definitions) is refused naming the file, line, material and node (exit 2). Constant inputs of lobes\n"
           "matremap's models do not have (transmission, subsurface, emission, sheen, ...) are carried when the\n"
           "output node is the same; otherwise each material's line says which were not carried.\n"
           "\n"
           "How each material is converted (one line each is printed, with its route):\n"
           "  the same model: copy  every value, map and extra input unchanged (exact)\n"
           "  uniform (no maps), another model: remap  the values fitted by a remap in the fit scene (as\n"
           "          `matremap remap --from MODEL ... --to MODEL`, with --hold and the ties), the outcome and SSIM\n"
           "          printed\n"
           "  textured, gltf <-> usd-preview: maps  base colour -> diffuseColor/base_color (sRGB), metallic and\n"
           "          roughness (linear; a glTF metallic-roughness texture's B and G), factors as scales\n"
           "  textured, any other pair (e.g. to openpbr or standard-surface): direct  the maps (a .mtlx's read\n"
           "          from its files, scales folded in) converted as `matremap convert --direct` does (every\n"
           "          distinct texel, quantised to --tolerance, remapped; the target's default holds and --hold\n"
           "          held, --tie tied), or learned  through the transforms of --transforms (as `convert\n"
           "          --transforms`); the texels, distinct values, texels not converged (or extrapolated) and the\n"
           "          time printed. A parameter whose converted map holds one value is written as a constant,\n"
           "          every other as OUT_<material>_<parameter>.png (8-bit: sRGB for colours, linear otherwise),\n"
           "          with the flag picture OUT_<material>_flags.png (red: not converged or extrapolated; green:\n"
           "          clamped output).\n"
           "          Not into a .gltf/.glb output (a .mtlx's textured materials of another model: exit 2)\n"
           "The images a glTF asset's maps use are written beside OUT, named after it: OUT_image<K>.png|jpg; a\n"
           ".mtlx's maps stay where they are (named relative to OUT), or are copied beside a glTF OUT as\n"
           "OUT_<name>. Normal, occlusion, emission and alpha maps are not written yet. docs/documents.md says\n"
           "what is exact and what not.\n"
           "\n");
    printf("Many assets (several inputs, a folder walked for .gltf/.glb, a quoted glob, or --format) go into -o DIR\n"
           "(made if missing, never inside an input folder), each exported as one asset is to DIR/<its path below\n"
           "the inputs' common root> with the extension of --format, side by side on --threads (each asset's own\n"
           "work then on one thread): one line per asset, then a total; DIR/summary.json (per asset its status,\n"
           "materials with routes and figures, images and maps) and DIR/index.html. A .gltf/.glb output is rendered\n"
           "against its input (thumbnails and object SSIM, as 'matremap gltf' does); .mtlx and .usda outputs hold no\n"
           "geometry and are not rendered. An asset that fails is named and the others go on (exit 2). SIGINT or\n"
           "SIGTERM lets the assets under way finish and records the rest as cancelled (exit 3; --resume goes on).\n"
           "With --cache the assets run one at a time (the cache file takes one user at a time).\n"
           "  --format F            mtlx, usda, gltf or glb: the outputs' format (many assets)\n"
           "  --resume              skip assets an earlier run into DIR exported with the same options from the\n"
           "                        same input files (summary.json's fingerprints)\n"
           "  --shard K/N           export only the assets at sorted index i with i %% N == K (job arrays)\n"
           "  --no-renders          no thumbnails and no object SSIM for glTF outputs\n"
           "\n");
    printf("options:\n"
           "  -o OUT                the output (.mtlx, .usda, .gltf or .glb); never one of the input's files\n"
           "  --to MODEL            openpbr (.mtlx default), standard-surface, gltf (.gltf/.glb: the only one),\n"
           "                        usd-preview (.usda default)\n"
           "  --direct              textured materials by the direct remap (the default without --transforms)\n"
           "  --transforms PATH     textured materials through learned transforms: PATH a .mrt file or a folder of\n"
           "                        them (repeatable); the chain from the material's model to MODEL is found as\n"
           "                        convert finds it\n"
           "  --tolerance T         direct: the quantisation step (default 6/255 = 0.0235, convert's: colours\n"
           "                        in sRGB-encoded units, 43 levels per channel; roughness in ln units, 2.4 %%\n"
           "                        relative; metallic 0.024 absolute); 12/255 takes a third of the time, 1/255\n"
           "                        keeps 8-bit maps exact (a 2048x2048 set: ~1.5 min on 2 cores by default)\n"
           "  --hold NAME[=VALUE][,...]  remap and direct: hold these target parameters at VALUE (or their\n"
           "                        defaults), as 'matremap remap --hold'; the target's default holds are held too,\n"
           "                        and a 'held:' line lists them\n"
           "  --tie TARGET=SOURCE[,...]|none  remap and direct from a glTF asset: hold target parameters at the\n"
           "                        glTF material's (or texel's) value; default (a .mtlx's materials too, which take\n"
           "                        only --tie none): what the source states, a metalness (which the fit scene\n"
           "                        cannot tell from the base colour at high roughness) and the IOR, coat and\n"
           "                        specular tint the target holds (gltf -> openpbr: base_metalness=metallic,\n"
           "                        specular_color=specular_color, specular_ior=ior); a 'tied:' line\n"
           "  --cache FILE          direct: answers kept across runs (as convert --cache)\n"
           "  --size N              the fit scene's side of remaps and direct remaps (default 64)\n"
           "  --threads N           threads (0 = automatic, the default)\n"
           "  --json                a JSON summary on stdout\n"
           "\n"
           "examples:\n"
           "  matremap export WaterBottle.gltf -o bottle.usda\n"
           "  matremap export Duck.gltf -o duck.mtlx --to standard-surface\n"
           "  matremap export WaterBottle.gltf -o bottle.mtlx              # openpbr, maps by direct remaps\n"
           "  matremap export standard_surface_gold.mtlx -o gold.mtlx      # to open_pbr_surface by a remap\n"
           "  matremap export bottle.mtlx -o bottle.usda                   # gltf_pbr maps to UsdPreviewSurface\n"
           "Exit status: 0 written; 1 usage; 2 bad input or a refused material (nothing written); 3 internal error.\n");
}

#define MAX_TRANSFORM_PATHS 64

typedef struct options {
    const char *input, *output, *to, *hold, *cache, *tie, *format;
    const char **inputs; /* [input_count]: argv's inputs (many assets) */
    int input_count, library, resume, shard_given, shard_index, shard_count, no_renders;
    const char *transforms[MAX_TRANSFORM_PATHS];
    int transform_count, direct, size, threads, json;
    double tolerance;
    char probe[32]; /* many assets: "asset.<format>" */
} options;


static int parse(int argc, char **argv, options *o) {
    for (int i = 1; i < argc; i++) {
        const char *value = NULL;
        int taken;
        if ((taken = cli_take_option("export", argc, argv, &i, "-o", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            o->output = value;
        } else if ((taken = cli_take_option("export", argc, argv, &i, "--to", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            o->to = value;
        } else if ((taken = cli_take_option("export", argc, argv, &i, "--threads", &value))) {
            if (taken < 0 || !cli_parse_int("export", "--threads", value, 0, 1024, &o->threads)) return CLI_EXIT_USAGE;
        } else if ((taken = cli_take_option("export", argc, argv, &i, "--transforms", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            if (o->transform_count == MAX_TRANSFORM_PATHS)
                return cli_usage_error("export", "--transforms: more than %d given", MAX_TRANSFORM_PATHS);
            o->transforms[o->transform_count++] = value;
        } else if ((taken = cli_take_option("export", argc, argv, &i, "--tolerance", &value))) {
            if (taken < 0 || !cli_parse_double("export", "--tolerance", value, MR_DIRECT_MIN_TOLERANCE, 1.0,
                                               &o->tolerance))
                return CLI_EXIT_USAGE;
        } else if ((taken = cli_take_option("export", argc, argv, &i, "--hold", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            o->hold = value;
        } else if ((taken = cli_take_option("export", argc, argv, &i, "--tie", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            o->tie = value;
        } else if ((taken = cli_take_option("export", argc, argv, &i, "--cache", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            o->cache = value;
        } else if ((taken = cli_take_option("export", argc, argv, &i, "--size", &value))) {
            if (taken < 0 || !cli_parse_int("export", "--size", value, 8, 4096, &o->size)) return CLI_EXIT_USAGE;
        } else if ((taken = cli_take_option("export", argc, argv, &i, "--format", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            o->format = value;
        } else if ((taken = cli_take_option("export", argc, argv, &i, "--shard", &value))) {
            long k = 0, n = 0;
            if (taken < 0 || !cli_parse_shard("export", value, 1000000, &k, &n)) return CLI_EXIT_USAGE;
            o->shard_index = (int)k;
            o->shard_count = (int)n;
            o->shard_given = 1;
        } else if (strcmp(argv[i], "--resume") == 0) {
            o->resume = 1;
        } else if (strcmp(argv[i], "--no-renders") == 0) {
            o->no_renders = 1;
        } else if (strcmp(argv[i], "--direct") == 0) {
            o->direct = 1;
        } else if (strcmp(argv[i], "--json") == 0) {
            o->json = 1;
        } else if (argv[i][0] == '-') {
            return cli_usage_error("export", "unknown option '%s'", argv[i]);
        } else {
            if (o->input == NULL) o->input = argv[i];
            o->inputs[o->input_count++] = argv[i];
        }
    }
    if (o->input == NULL) return cli_usage_error("export", "missing the input (.gltf, .glb or .mtlx)");
    // Many assets (several inputs, a folder, a glob, or --format) go into a folder, each by the one-asset export.
    struct stat st;
    o->library = o->input_count > 1 || o->format != NULL ||
                 (stat(o->input, &st) == 0 ? S_ISDIR(st.st_mode) : strpbrk(o->input, "*?[") != NULL);
    if (!o->library && (o->resume || o->shard_given || o->no_renders))
        return cli_usage_error("export", "--resume, --shard and --no-renders go with many assets (a folder, several "
                               "files or a glob into -o DIR --format F)");
    if (!o->library && !cli_is_gltf_path(o->input) && mr_doc_format_from_path(o->input) != MR_DOC_FORMAT_MTLX)
        return cli_usage_error("export", "'%s': the input is a glTF asset (.gltf or .glb) or a MaterialX document "
                               "(.mtlx)", o->input);
    if (o->output == NULL) return cli_usage_error("export", "missing -o OUT (.mtlx, .usda, .gltf or .glb)");
    if (o->library) {
        if (o->format == NULL)
            return cli_usage_error("export", "many assets go into a folder: give -o DIR --format mtlx|usda|gltf|glb");
        if (strcmp(o->format, "mtlx") != 0 && strcmp(o->format, "usda") != 0 && strcmp(o->format, "gltf") != 0 &&
            strcmp(o->format, "glb") != 0)
            return cli_usage_error("export", "--format '%s': expected mtlx, usda, gltf or glb", o->format);
        if (mr_doc_export_output_ok(o->output))
            return cli_usage_error("export", "-o '%s': many assets go into a folder (-o DIR), not one file",
                                   o->output);
        if (o->tie != NULL && strcmp(o->tie, "none") != 0) {
            for (int k = 0; k < o->input_count; k++)
                if (mr_doc_format_from_path(o->inputs[k]) == MR_DOC_FORMAT_MTLX)
                    return cli_usage_error("export", "--tie %s: a .mtlx input ('%s') takes --tie none or the default "
                                           "ties of each material's model, not a list", o->tie, o->inputs[k]);
        }
        // The checks below on the format a one-asset OUT would have.
        snprintf(o->probe, sizeof o->probe, "asset.%s", o->format);
    }
    const char *out = o->library ? o->probe : o->output; // the file (one asset's) whose extension says the format
    mr_doc_format format = mr_doc_format_from_path(out);
    int gltf_out = cli_is_gltf_path(out);
    if (format == MR_DOC_FORMAT_UNKNOWN && !gltf_out)
        return cli_usage_error("export", "-o '%s': the extension chooses the format: .mtlx, .usda, .gltf or .glb",
                               o->output);
    if (o->to == NULL) o->to = gltf_out ? "gltf" : format == MR_DOC_FORMAT_MTLX ? "openpbr" : "usd-preview";
    if (gltf_out && strcmp(o->to, "gltf") != 0)
        return cli_usage_error("export", "--to %s: a glTF output (-o '%s') holds gltf materials only (--to gltf); "
                               ".mtlx takes openpbr, standard-surface, gltf; .usda takes usd-preview", o->to,
                               o->output);
    if (o->direct && o->transform_count > 0)
        return cli_usage_error("export", "give --direct or --transforms, not both");
    if (o->transform_count > 0 && (o->tolerance != 0.0 || o->cache != NULL))
        return cli_usage_error("export", "--tolerance and --cache go with the direct route, not --transforms");
    if (!o->library && mr_doc_format_from_path(o->input) == MR_DOC_FORMAT_MTLX) {
        if (o->tie != NULL && strcmp(o->tie, "none") != 0)
            return cli_usage_error("export", "--tie %s: a .mtlx input takes --tie none or the default ties of each "
                                   "material's model (a 'tied:' line says them), not a list", o->tie);
    }
    return CLI_EXIT_OK;
}

/* The direct route's progress line on a terminal, as convert draws it. */
typedef struct progress_state {
    int draw;
    double started;
    int drawn;
} progress_state;

static void draw_progress(int material, const mr_direct_progress *p, void *user) {
    progress_state *s = user;
    if (!s->draw) return;
    fprintf(stderr, "\rmatremap export: material %d: %zu/%zu distinct values (%zu from the cache)  %.0f s", material,
            p->done, p->total, p->cache_hits, cli_now() - s->started);
    fflush(stderr);
    s->drawn = 1;
}

#define MAX_TIE_SOURCES 16

/* The holds and ties of the fits (remap, direct), said when a material was fitted: the ties per source model (a
 * glTF asset: gltf, as --tie gave them; a .mtlx: each remapped material's model, its default ties). */
typedef struct fits_said {
    const double *target_values;
    unsigned held;
    int source_count;
    const mr_brdf_model *sources[MAX_TIE_SOURCES];
    mr_brdf_ties ties[MAX_TIE_SOURCES];
    int tie_given;
} fits_said;

/* The parameters every source model ties: not held at their defaults anywhere (the "tied:" lines say them). */
static unsigned tied_by_all(const fits_said *f) {
    unsigned tied = f->source_count > 0 ? ~0u : 0u;
    for (int i = 0; i < f->source_count; i++) tied &= f->ties[i].tied;
    return tied;
}

/* One line per material (or the --json summary), the holds and ties, the images, maps and OUT. */
static void print_result(const options *o, const char *format, const mr_brdf_model *target,
                         const mr_doc_gltf_result *result, const fits_said *f) {
    int fitted = 0; // a material remapped or converted: the holds are said
    for (int k = 0; k < result->material_count; k++)
        fitted |= result->materials[k].route == MR_DOC_ROUTE_REMAP || result->materials[k].route == MR_DOC_ROUTE_DIRECT;
    if (!o->json) {
        for (int k = 0; k < result->material_count; k++) {
            const mr_doc_gltf_material *m = &result->materials[k];
            printf("material %d '%s': %s", k, m->name, mr_doc_route_name(m->route));
            if (m->route == MR_DOC_ROUTE_REMAP)
                printf(" (%s, SSIM %.4f, relative RMSE %.4f)", mr_fit_outcome_name((mr_fit_outcome)m->outcome),
                       m->ssim, m->relative_rmse);
            if (m->route == MR_DOC_ROUTE_DIRECT)
                printf(" (%dx%d = %zu texels, %zu distinct values at tolerance %.4g: %zu converged; %zu texels not "
                       "converged, %zu clamped, %zu flagged; %.1f s)", m->width, m->height, m->texels, m->unique,
                       m->tolerance, m->outcomes[MR_FIT_CONVERGED], m->unconverged, m->clamped, m->flagged,
                       m->seconds);
            if (m->route == MR_DOC_ROUTE_LEARNED)
                printf(" (%d transform%s, %dx%d = %zu texels: %zu extrapolated, %zu by a transform that failed its "
                       "check, %zu clamped, %zu flagged; %.1f s)", m->hops, m->hops == 1 ? "" : "s", m->width,
                       m->height, m->texels, m->unconverged, m->failed_check, m->clamped, m->flagged, m->seconds);
            if (m->not_carried[0]) printf("; not carried: %s", m->not_carried);
            printf("\n");
        }
        if (fitted) cli_print_holds_tied(stdout, "", target, f->target_values, f->held, tied_by_all(f));
        for (int i = 0; fitted && i < f->source_count; i++)
            cli_print_ties(stdout, "", f->sources[i], target, &f->ties[i], f->tie_given);
        for (int i = 0; i < result->image_count; i++) printf("wrote %s\n", result->images[i].path);
        for (int i = 0; i < result->map_count; i++) printf("wrote %s\n", result->maps[i].path);
        printf("wrote %s (%s, %d material%s)\n", o->output, target->name, result->material_count,
               result->material_count == 1 ? "" : "s");
        return;
    }
    printf("{\"command\": \"export\", \"input\": ");
    cli_json_string(stdout, o->input);
    printf(", \"output\": ");
    cli_json_string(stdout, o->output);
    printf(", \"format\": \"%s\", \"target\": \"%s\", \"materials\": [", format, target->name);
    for (int k = 0; k < result->material_count; k++) {
        const mr_doc_gltf_material *m = &result->materials[k];
        printf("%s{\"name\": ", k ? ", " : "");
        cli_json_string(stdout, m->name);
        printf(", \"route\": \"%s\"", mr_doc_route_name(m->route));
        if (m->route == MR_DOC_ROUTE_REMAP)
            printf(", \"outcome\": \"%s\", \"ssim\": %.6f, \"relative_rmse\": %.6f",
                   mr_fit_outcome_name((mr_fit_outcome)m->outcome), m->ssim, m->relative_rmse);
        if (m->route == MR_DOC_ROUTE_DIRECT || m->route == MR_DOC_ROUTE_LEARNED)
            printf(", \"width\": %d, \"height\": %d, \"texels\": %zu, \"unconverged_or_extrapolated\": %zu, "
                   "\"failed_check\": %zu, \"clamped\": %zu, \"flagged\": %zu, \"seconds\": %.3f", m->width,
                   m->height, m->texels, m->unconverged, m->failed_check, m->clamped, m->flagged, m->seconds);
        if (m->route == MR_DOC_ROUTE_LEARNED) printf(", \"hops\": %d", m->hops);
        if (m->route == MR_DOC_ROUTE_DIRECT) {
            printf(", \"unique\": %zu, \"tolerance\": %.9g, \"outcomes\": {", m->unique, m->tolerance);
            for (int i = 0; i < MR_FIT_OUTCOME_COUNT; i++)
                printf("%s\"%s\": %zu", i ? ", " : "", mr_fit_outcome_name((mr_fit_outcome)i), m->outcomes[i]);
            printf("}");
        }
        printf(", \"not_carried\": [");
        // not_carried is "a, b, c": printed as a JSON list of names
        const char *s = m->not_carried;
        for (int first = 1; *s;) {
            const char *comma = strstr(s, ", ");
            size_t n = comma ? (size_t)(comma - s) : strlen(s);
            char name[1024];
            snprintf(name, sizeof name, "%.*s", (int)n, s);
            printf("%s", first ? "" : ", ");
            cli_json_string(stdout, name);
            first = 0;
            s += n + (comma ? 2 : 0);
        }
        printf("]}");
    }
    printf("], \"images\": [");
    for (int i = 0; i < result->image_count; i++) {
        printf("%s", i ? ", " : "");
        cli_json_string(stdout, result->images[i].path);
    }
    printf("], \"maps\": [");
    for (int i = 0; i < result->map_count; i++) {
        printf("%s", i ? ", " : "");
        cli_json_string(stdout, result->maps[i].path);
    }
    printf("]");
    if (fitted) {
        // One source model (a glTF asset, or a .mtlx of one model): its ties as a list; several: a list per model.
        printf(", \"tied\": ");
        if (f->source_count == 1) {
            cli_print_ties_json(stdout, f->sources[0], target, &f->ties[0], f->tie_given);
        } else {
            printf("{");
            for (int i = 0; i < f->source_count; i++) {
                printf("%s\"%s\": ", i ? ", " : "", f->sources[i]->name);
                cli_print_ties_json(stdout, f->sources[i], target, &f->ties[i], f->tie_given);
            }
            printf("}");
        }
        printf(", \"held\": ");
        cli_print_holds_json(stdout, target, f->target_values, f->held, tied_by_all(f));
    }
    printf("}\n");
}

static int export_main(options *op);
static int run_library(const options *o, const mr_doc_export_options *each);

int cmd_export(int argc, char **argv) {
    for (int i = 1; i < argc; i++)
        if (cli_is_help(argv[i])) {
            print_help();
            return CLI_EXIT_OK;
        }
    options o;
    memset(&o, 0, sizeof o);
    const char **inputs = calloc((size_t)argc, sizeof *inputs);
    if (inputs == NULL) return cli_fail("export", MR_ERR_NOMEM);
    o.inputs = inputs;
    int code = parse(argc, argv, &o);
    if (code == CLI_EXIT_OK) code = export_main(&o);
    free(inputs);
    return code;
}

static int export_main(options *op) {
    options o = *op;
    int code = CLI_EXIT_OK;
    const char *out = o.library ? o.probe : o.output;
    mr_doc_format format = mr_doc_format_from_path(out);
    int gltf_out = cli_is_gltf_path(out);
    const mr_brdf_model *target = mr_brdf_find(o.to);
    if (target == NULL) return cli_usage_error("export", "--to '%s': %s", o.to, mr_last_error());
    if (!gltf_out && mr_doc_surface_node(target, format) == NULL)
        return cli_usage_error("export", "--to %s: .%s does not write it (.mtlx: openpbr, standard-surface, gltf; "
                               ".usda: usd-preview; .gltf, .glb: gltf)", o.to, mr_doc_format_name(format));
    double target_values[MR_BRDF_MAX_VALUES];
    unsigned held = 0;
    mr_brdf_default_values(target, target_values);
    if (o.hold != NULL && !cli_parse_held("export", target, o.hold, target_values, &held)) return CLI_EXIT_USAGE;
    const mr_brdf_model *gltf = mr_brdf_find("gltf");
    mr_brdf_ties ties;
    if (!cli_parse_ties("export", gltf, target, o.tie, held, &ties)) return CLI_EXIT_USAGE;
    mr_learned_set transforms = {0};
    for (int k = 0; k < o.transform_count; k++) {
        struct stat info;
        mr_status ts;
        if (stat(o.transforms[k], &info) == 0 && S_ISDIR(info.st_mode)) {
            char label[4096 + 20];
            snprintf(label, sizeof label, "--transforms '%s'", o.transforms[k]);
            ts = mr_learned_set_add_folder(&transforms, o.transforms[k], label);
        } else {
            ts = mr_learned_set_add_file(&transforms, o.transforms[k]);
        }
        if (ts != MR_OK) {
            mr_learned_set_free(&transforms);
            return cli_fail("export", ts);
        }
    }
    for (int k = 0; k < transforms.count; k++) // a transform that failed its check: said before the work
        if (transforms.all[k]->check.done && !transforms.all[k]->check.passed)
            fprintf(stderr, "matremap export: warning: transform %s (%s -> %s) failed its check against the remaps "
                    "when it was learned (docs/learn.md, \"The check\"); every texel it converts is flagged (red)\n",
                    transforms.paths[k], transforms.all[k]->source->name, transforms.all[k]->target->name);
    // One call does the work (doc/doc.h: mr_doc_export_file); here the options, the progress line and the result.
    mr_doc_export_options eo = {0};
    eo.target = target;
    eo.target_values = target_values;
    eo.held = held;
    const mr_brdf_ties no_ties = {0};
    if (o.library)
        eo.ties = o.tie != NULL ? &ties : NULL; // given (a .mtlx input: none), or each model's defaults less holds
    else if (mr_doc_format_from_path(o.input) == MR_DOC_FORMAT_MTLX)
        eo.ties = o.tie != NULL ? &no_ties : NULL; // --tie none, or each model's defaults
    else
        eo.ties = &ties;
    eo.threads = o.threads;
    eo.size = o.size;
    eo.tolerance = o.tolerance;
    eo.cache_path = o.cache;
    eo.transforms = transforms.count > 0 ? &transforms : NULL;
    progress_state progress = {isatty(STDERR_FILENO) && !o.json, cli_now(), 0};
    eo.progress = draw_progress;
    eo.progress_user = &progress;
    if (o.library) {
        eo.progress = NULL;
        code = run_library(&o, &eo);
        mr_learned_set_free(&transforms);
        return code;
    }
    mr_doc_export_report report;
    mr_status st = mr_doc_export_file(o.input, o.output, &eo, &report);
    if (progress.drawn) fprintf(stderr, "\r\033[K");
    if (st != MR_OK) {
        code = cli_fail("export", st);
    } else {
        fits_said said = {target_values, held, report.source_count, {NULL}, {{0}}, o.tie != NULL};
        for (int i = 0; i < report.source_count && i < MAX_TIE_SOURCES; i++) {
            said.sources[i] = report.sources[i];
            said.ties[i] = report.ties[i];
        }
        print_result(&o, report.format, target, report.result, &said);
    }
    mr_doc_export_report_free(&report);
    mr_learned_set_free(&transforms);
    return code;
}

/* ---- many assets: mr_doc_export_library ----------------------------------------------------------------------- */

static int run_library(const options *o, const mr_doc_export_options *each) {
    // What the export was told, recorded for --resume (an asset is exported again when any of it changes).
    char settings[8192];
    size_t used = (size_t)snprintf(settings, sizeof settings, "export format=%s to=%s hold=%s tie=%s direct=%d "
                                   "tolerance=%.17g size=%d cache=%s transforms=", o->format, o->to,
                                   o->hold ? o->hold : "", o->tie ? o->tie : "default", o->direct, o->tolerance,
                                   o->size, o->cache ? o->cache : "");
    for (int k = 0; k < o->transform_count && used < sizeof settings; k++)
        used += (size_t)snprintf(settings + used, sizeof settings - used, "%s%s", k ? "," : "", o->transforms[k]);
    mr_gltf_library_options lo = {0};
    lo.settings = settings;
    lo.threads = o->threads;
    lo.resume = o->resume;
    lo.no_renders = o->no_renders;
    lo.shard_index = o->shard_index;
    lo.shard_count = o->shard_count;
    cli_library_view view = {isatty(STDERR_FILENO) && !o->json, "exported"};
    lo.progress = o->json ? NULL : cli_library_progress;
    lo.progress_user = &view;
    struct sigaction old[2];
    lo.cancel = cli_library_cancel_begin(old);
    char extension[16];
    snprintf(extension, sizeof extension, ".%s", o->format);
    mr_gltf_library_result r;
    mr_status status = mr_doc_export_library(o->inputs, o->input_count, o->output, each, extension, &lo, &r);
    cli_library_cancel_end(old);
    char head[256];
    snprintf(head, sizeof head, "\"command\": \"export\", \"format\": \"%s\", \"target\": \"%s\"", o->format, o->to);
    return cli_library_report("export", "export", head, "exported", o->output, o->json, status, &r);
}
