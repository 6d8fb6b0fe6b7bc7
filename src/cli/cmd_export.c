/*
 * cmd_export.c — `matremap export ASSET.gltf -o OUT.mtlx|OUT.usda [--to MODEL]`: a glTF asset's materials written
 * as a MaterialX or USD document (src/doc/doc.h: mr_doc_from_gltf, then mr_doc_gltf_write).
 */
#include <stdio.h>
#include <string.h>

#include "cli.h"
#include "matremap.h"

static void print_help(void) {
    printf("usage: matremap export ASSET.gltf|ASSET.glb -o OUT.mtlx|OUT.usda [--to MODEL] [--threads N] [--json]\n"
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
           "  textured, --to openpbr or standard-surface: refused (exit 2, naming the material): no texture route\n"
           "          to those models yet; use --to usd-preview, --to gltf, or `matremap convert --direct` on maps\n"
           "The images the maps use are written beside OUT, named after it: OUT_image<K>.png|jpg. Normal,\n"
           "occlusion, emission and alpha are not written yet. docs/documents.md says what is exact and what not.\n"
           "\n"
           "options:\n"
           "  -o OUT                the document (.mtlx or .usda); never one of the asset's files\n"
           "  --to MODEL            openpbr (.mtlx default), standard-surface, gltf, usd-preview (.usda default)\n"
           "  --threads N           threads of the remaps (0 = automatic, the default)\n"
           "  --json                a JSON summary on stdout\n"
           "\n"
           "examples:\n"
           "  matremap export WaterBottle.gltf -o bottle.usda\n"
           "  matremap export Duck.gltf -o duck.mtlx --to standard-surface\n"
           "Exit status: 0 written; 1 usage; 2 bad input or a refused material (nothing written); 3 internal error.\n");
}

typedef struct options {
    const char *input, *output, *to;
    int threads, json;
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
    return CLI_EXIT_OK;
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

    mr_gltf *asset = NULL;
    mr_status st = mr_gltf_load(o.input, &asset);
    if (st != MR_OK) return cli_fail("export", st);
    // Nothing written over a file read, checked before any work (the remaps): OUT against the asset and its files;
    // the images beside OUT once the conversion has named them.
    char label[4096 + 8];
    snprintf(label, sizeof label, "asset %s", o.input);
    mr_output_plan io = {0};
    cli_plan_gltf(&io, asset, label);
    mr_output_plan_output(&io, o.output, NULL);
    code = cli_plan_check("export", &io);
    mr_output_plan_free(&io);
    if (code != CLI_EXIT_OK) {
        mr_gltf_free(asset);
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
    mr_doc_gltf_result *result = NULL;
    st = mr_doc_from_gltf(asset, &opts, &result);
    if (st != MR_OK) {
        mr_gltf_free(asset);
        return cli_fail("export", st);
    }

    io = (mr_output_plan){0};
    cli_plan_gltf(&io, asset, label);
    mr_output_plan_output(&io, o.output, NULL);
    for (int i = 0; i < result->image_count; i++) mr_output_plan_output(&io, result->images[i].path, NULL);
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
            printf("\n");
        }
        for (int i = 0; i < result->image_count; i++) printf("wrote %s\n", result->images[i].path);
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
            printf("}");
        }
        printf("], \"images\": [");
        for (int i = 0; i < result->image_count; i++) {
            printf("%s", i ? ", " : "");
            cli_json_string(stdout, result->images[i].path);
        }
        printf("]}\n");
    }
    mr_doc_gltf_result_free(result);
    mr_gltf_free(asset);
    return code;
}
