/*
 * cmd_export.c — `matremap export ASSET.gltf -o OUT.mtlx|OUT.usda [--to MODEL]`: a glTF asset's materials written
 * as a MaterialX or USD document (src/doc/doc.h: mr_doc_from_gltf, then mr_doc_gltf_write).
 */
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "cli.h"
#include "matremap.h"

static void print_help(void) {
    printf("usage: matremap export ASSET.gltf|ASSET.glb -o OUT.mtlx|OUT.usda [--to MODEL] [options]\n"
           "\n"
           "Writes the materials of a glTF asset as a material document. OUT's extension chooses the format:\n"
           "  .mtlx   MaterialX 1.39: a surfacematerial per material over an open_pbr_surface node (the default),\n"
           "          standard_surface (--to standard-surface) or gltf_pbr (--to gltf); maps as image nodes in a\n"
           "          nodegraph, colour maps with colorspace srgb_texture, data maps in the document's lin_rec709\n"
           "  .usda   USD: a Material per material with a UsdPreviewSurface (metallic workflow), a UsdUVTexture per\n"
           "          map (sourceColorSpace sRGB or raw) reading the \"st\" primvar; --to usd-preview (the default)\n"
           "\n"
           "How each material is converted (one line each is printed, with its route):\n"
           "  uniform (no base colour or metallic-roughness texture): remap  the glTF factors fitted by a remap\n"
           "          in the fit scene (as `matremap remap --from gltf ... --to MODEL`), the outcome and SSIM\n"
           "          printed; --to gltf copies them (copy: exact)\n"
           "  textured, --to usd-preview or gltf: maps  base colour -> diffuseColor/base_color (sRGB), the\n"
           "          metallic-roughness texture's B -> metallic and G -> roughness (linear), factors as scales\n"
           "  textured, --to openpbr or standard-surface: direct  the maps converted as `matremap convert --direct`\n"
           "          does (every distinct texel, quantised to --tolerance, remapped; the target's default holds and\n"
           "          --hold held), or learned  through the transforms of --transforms (as `convert --transforms`);\n"
           "          the texels, distinct values, texels not converged (or extrapolated) and the time printed.\n"
           "          A parameter whose converted map holds one value is written as a constant, every other as\n"
           "          OUT_<material>_<parameter>.png (8-bit: sRGB for colours, linear otherwise), with the flag\n"
           "          picture OUT_<material>_flags.png (red: not converged or extrapolated; green: clamped output)\n"
           "The images the carried maps use are written beside OUT, named after it: OUT_image<K>.png|jpg. Normal,\n"
           "occlusion, emission and alpha are not written yet. docs/documents.md says what is exact and what not.\n"
           "\n");
    printf("options:\n"
           "  -o OUT                the document (.mtlx or .usda); never one of the asset's files\n"
           "  --to MODEL            openpbr (.mtlx default), standard-surface, gltf, usd-preview (.usda default)\n"
           "  --direct              textured materials by the direct remap (the default without --transforms)\n"
           "  --transforms PATH     textured materials through learned transforms: PATH a .mrt file or a folder of\n"
           "                        them (repeatable); the chain from gltf to MODEL is found as convert finds it\n"
           "  --tolerance T         direct: the quantisation step (default 6/255 = 0.0235, convert's: colours\n"
           "                        in sRGB-encoded units, 43 levels per channel; roughness in ln units, 2.4 %%\n"
           "                        relative; metallic 0.024 absolute); 12/255 takes a third of the time, 1/255\n"
           "                        keeps 8-bit maps exact (a 2048x2048 set: ~1.5 min on 2 cores by default)\n"
           "  --hold NAME[=VALUE][,...]  remap and direct: hold these target parameters at VALUE (or their\n"
           "                        defaults), as 'matremap remap --hold'; the target's default holds are held too,\n"
           "                        and a 'held:' line lists them\n"
           "  --tie TARGET=SOURCE[,...]|none  remap and direct: hold target parameters at the glTF material's\n"
           "                        (or texel's) value; default: the metalness (openpbr: base_metalness=metallic),\n"
           "                        which the fit scene cannot tell from the base colour at high roughness\n"
           "  --cache FILE          direct: answers kept across runs (as convert --cache)\n"
           "  --size N              the fit scene's side of remaps and direct remaps (default 64)\n"
           "  --threads N           threads (0 = automatic, the default)\n"
           "  --json                a JSON summary on stdout\n"
           "\n"
           "examples:\n"
           "  matremap export WaterBottle.gltf -o bottle.usda\n"
           "  matremap export Duck.gltf -o duck.mtlx --to standard-surface\n"
           "  matremap export WaterBottle.gltf -o bottle.mtlx            # openpbr, maps by direct remaps\n"
           "Exit status: 0 written; 1 usage; 2 bad input or a refused material (nothing written); 3 internal error.\n");
}

#define MAX_TRANSFORM_PATHS 64

typedef struct options {
    const char *input, *output, *to, *hold, *cache, *tie;
    const char *transforms[MAX_TRANSFORM_PATHS];
    int transform_count, direct, size, threads, json;
    double tolerance;
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
        } else if (strcmp(argv[i], "--direct") == 0) {
            o->direct = 1;
        } else if (strcmp(argv[i], "--json") == 0) {
            o->json = 1;
        } else if (argv[i][0] == '-') {
            return cli_usage_error("export", "unknown option '%s'", argv[i]);
        } else if (o->input == NULL) {
            o->input = argv[i];
        } else {
            return cli_usage_error("export", "unexpected argument '%s' (one input asset)", argv[i]);
        }
    }
    if (o->input == NULL) return cli_usage_error("export", "missing the input asset (.gltf or .glb)");
    if (!cli_is_gltf_path(o->input))
        return cli_usage_error("export", "'%s': the input is a glTF asset (.gltf or .glb); reading .mtlx is not "
                               "done yet", o->input);
    if (o->output == NULL) return cli_usage_error("export", "missing -o OUT (.mtlx or .usda)");
    mr_doc_format format = mr_doc_format_from_path(o->output);
    if (format == MR_DOC_FORMAT_UNKNOWN)
        return cli_usage_error("export", "-o '%s': the extension chooses the format: .mtlx or .usda", o->output);
    if (o->to == NULL) o->to = format == MR_DOC_FORMAT_MTLX ? "openpbr" : "usd-preview";
    if (o->direct && o->transform_count > 0)
        return cli_usage_error("export", "give --direct or --transforms, not both");
    if (o->transform_count > 0 && (o->tolerance != 0.0 || o->cache != NULL))
        return cli_usage_error("export", "--tolerance and --cache go with the direct route, not --transforms");
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

int cmd_export(int argc, char **argv) {
    for (int i = 1; i < argc; i++)
        if (cli_is_help(argv[i])) {
            print_help();
            return CLI_EXIT_OK;
        }
    options o;
    memset(&o, 0, sizeof o);
    int code = parse(argc, argv, &o);
    if (code != CLI_EXIT_OK) return code;
    mr_doc_format format = mr_doc_format_from_path(o.output);
    const mr_brdf_model *target = mr_brdf_find(o.to);
    if (target == NULL) return cli_usage_error("export", "--to '%s': %s", o.to, mr_last_error());
    if (mr_doc_surface_node(target, format) == NULL)
        return cli_usage_error("export", "--to %s: .%s does not write it (.mtlx: openpbr, standard-surface, gltf; "
                               ".usda: usd-preview)", o.to, mr_doc_format_name(format));

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

    mr_gltf *asset = NULL;
    mr_status st = mr_gltf_load(o.input, &asset);
    if (st != MR_OK) {
        mr_learned_set_free(&transforms);
        return cli_fail("export", st);
    }
    // Nothing written over a file read, checked before any work (the remaps): OUT against the asset and its files;
    // the images beside OUT once the conversion has named them.
    char label[4096 + 8];
    snprintf(label, sizeof label, "asset %s", o.input);
    mr_output_plan io = {0};
    cli_plan_gltf(&io, asset, label);
    mr_output_plan_output(&io, o.output, NULL);
    for (int k = 0; k < transforms.count; k++) mr_output_plan_inputf(&io, transforms.paths[k], "transform %s",
                                                                     transforms.paths[k]);
    if (o.cache != NULL) mr_output_plan_output(&io, o.cache, "--cache");
    code = cli_plan_check("export", &io);
    mr_output_plan_free(&io);
    if (code != CLI_EXIT_OK) {
        mr_gltf_free(asset);
        mr_learned_set_free(&transforms);
        return code;
    }

    // OUT without its extension: the prefix the images beside it are named after.
    char prefix[4096];
    snprintf(prefix, sizeof prefix, "%s", o.output);
    char *dot = strrchr(prefix, '.');
    if (dot) *dot = '\0';
    mr_doc_gltf_options opts = {0};
    opts.target = target;
    opts.image_prefix = prefix;
    opts.threads = o.threads;
    opts.size = o.size;
    opts.target_values = target_values;
    opts.held = held;
    opts.ties = &ties;
    opts.tolerance = o.tolerance;
    opts.cache_path = o.cache;
    opts.transforms = transforms.count > 0 ? &transforms : NULL;
    progress_state progress = {isatty(STDERR_FILENO) && !o.json, cli_now(), 0};
    opts.progress = draw_progress;
    opts.progress_user = &progress;
    mr_doc_gltf_result *result = NULL;
    st = mr_doc_from_gltf(asset, &opts, &result);
    if (progress.drawn) fprintf(stderr, "\r\033[K");
    if (st != MR_OK) {
        mr_gltf_free(asset);
        mr_learned_set_free(&transforms);
        return cli_fail("export", st);
    }
    int fitted = 0; // a material remapped or converted: the holds are said
    for (int k = 0; k < result->material_count; k++)
        fitted |= result->materials[k].route == MR_DOC_ROUTE_REMAP || result->materials[k].route == MR_DOC_ROUTE_DIRECT;

    io = (mr_output_plan){0};
    cli_plan_gltf(&io, asset, label);
    mr_output_plan_output(&io, o.output, NULL);
    for (int i = 0; i < result->image_count; i++) mr_output_plan_output(&io, result->images[i].path, NULL);
    for (int i = 0; i < result->map_count; i++) mr_output_plan_output(&io, result->maps[i].path, NULL);
    for (int k = 0; k < transforms.count; k++) mr_output_plan_inputf(&io, transforms.paths[k], "transform %s",
                                                                     transforms.paths[k]);
    code = cli_plan_check("export", &io);
    mr_output_plan_free(&io);
    if (code == CLI_EXIT_OK) {
        st = mr_doc_gltf_write(asset, result, o.output);
        if (st != MR_OK) code = cli_fail("export", st);
    }
    if (code == CLI_EXIT_OK && !o.json) {
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
            printf("\n");
        }
        if (fitted) cli_print_holds(stdout, "", target, target_values, held);
        if (fitted) cli_print_ties(stdout, "", gltf, target, &ties, o.tie != NULL);
        for (int i = 0; i < result->image_count; i++) printf("wrote %s\n", result->images[i].path);
        for (int i = 0; i < result->map_count; i++) printf("wrote %s\n", result->maps[i].path);
        printf("wrote %s (%s, %d material%s)\n", o.output, target->name, result->material_count,
               result->material_count == 1 ? "" : "s");
    } else if (code == CLI_EXIT_OK) {
        printf("{\"command\": \"export\", \"input\": ");
        cli_json_string(stdout, o.input);
        printf(", \"output\": ");
        cli_json_string(stdout, o.output);
        printf(", \"format\": \"%s\", \"target\": \"%s\", \"materials\": [", mr_doc_format_name(format), target->name);
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
            printf("}");
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
            printf(", \"tied\": ");
            cli_print_ties_json(stdout, gltf, target, &ties, o.tie != NULL);
            printf(", \"held\": ");
            cli_print_holds_json(stdout, target, target_values, held);
        }
        printf("}\n");
    }
    mr_doc_gltf_result_free(result);
    mr_gltf_free(asset);
    mr_learned_set_free(&transforms);
    return code;
}
