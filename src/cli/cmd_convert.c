/*
 * cmd_convert.c — `matremap convert`: texture maps (or constants) of one BRDF model's parameters converted to
 * another model's, per texel, through learned transforms (one, a chain given or found) or the direct remap. The job
 * is the library's (learn/learned.h: mr_learned_set_add_file / _folder, mr_learned_find_chain or
 * mr_learned_check_ends, mr_learned_convert_material, mr_learned_explain_texel); this file parses, checks that no
 * output replaces an input, and prints; see docs/learn.md.
 */
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cli.h"
#include "learn/learned.h"

#define COMMAND "convert"

static void print_help(void) {
    printf(
        "Usage: matremap convert --from MODEL --to MODEL NAME=FILE|VALUE ...\n"
        "                        (--transform T.mrt [--transform T2.mrt ...] | --transforms DIR [--via MODEL,...] |\n"
        "                         --direct [--tolerance T] [--roughness-tolerance T] [--cache FILE] [--size N]\n"
        "                                  [--light 45|frontal]\n"
        "                                  [--hold NAME[=VALUE],...])\n"
        "                        -o PREFIX [options]\n"
        "\n"
        "Converts a material of one BRDF model into another, texel by texel: every NAME=FILE (or NAME=@FILE) gives\n"
        "a parameter of the source model as a texture map (any format the tool reads), NAME=VALUE (or NAME=R,G,B)\n"
        "a constant; parameters not given keep the model's defaults ('matremap models MODEL' lists them). Maps\n"
        "must share one size; constants broadcast. With constants only, the one texel is converted and printed as\n"
        "'MODEL name=value ...'.\n"
        "\n"
        "Maps hold the parameter's own values, by one rule for every command: 8/16-bit maps of colour parameters\n"
        "(the ENCODING column of 'matremap models MODEL': diffuse, specular, f0, base colour ...) are sRGB-decoded\n"
        "whatever the parameter's range, every other parameter is read linearly, and float files (EXR, HDR, float\n"
        "TIFF) are always linear. FILE:linear or FILE:srgb overrides it for one map (:srgb on a float file is an\n"
        "error); FILE:r|g|b|a picks one channel for a one-channel parameter, before the encoding: orm.png:g:linear.\n"
        "\n"
        "How:\n"
        "  --transform T.mrt   a transform made by 'matremap learn'; repeat it to chain transforms in order\n"
        "  --transforms DIR    every *.mrt in DIR: the chain from --from to --to with the fewest hops (then the\n"
        "                      least held-out error) is found; --via MODEL[,MODEL...] makes it pass those models\n"
        "  --direct            no regression: every distinct texel value, quantised to --tolerance, remapped by the\n"
        "                      image-based optimiser itself (as 'matremap remap'), each warm-started from a solved\n"
        "                      neighbour; the reference the learned transforms are judged against. Slow: seconds\n"
        "                      to minutes per texture set (progress on stderr)\n"
        "  --tolerance T       --direct: quantisation step, colours in sRGB-encoded units, roughness in ln units\n"
        "                      (default 6/255 = 0.0235 with maps; 1/255 keeps 8-bit maps exact and costs more;\n"
        "                      constants alone are remapped at their exact values: 1e-9)\n"
        "  --roughness-tolerance T  --direct: the step of roughness-like parameters alone, in ln units (default:\n"
        "                      --tolerance). --tolerance 0.003922 --roughness-tolerance 0.01569 (1/255, 4/255)\n"
        "                      keeps 8-bit colour maps exact and errs under 1 %% image RMSE (docs/performance.md)\n"
        "  --cache FILE        --direct: answers kept across runs (created if missing; refused if it was made\n"
        "                      for other models, options or scene)\n"
        "  --size N, --light L --direct: the fit scene (default 64, 45; as 'matremap remap')\n"
        "  --hold NAME[=VALUE][,...]  --direct: hold these target parameters at VALUE (or their defaults)\n"
        "                      instead of fitting them, as 'matremap remap --hold'; the target model's default\n"
        "                      holds are held too, and a 'held:' line lists every hold used\n"
        "  --tie TARGET=SOURCE[,...]|none  --direct: hold target parameters at each texel's source value; by\n"
        "                      default what the source states: a metalness, and the IOR, coat and specular\n"
        "                      tint the target holds (gltf -> openpbr: base_metalness=metallic, specular_ior=ior);\n"
        "                      a 'tied:' line says which (docs/remap.md, \"Ties\")\n"
        "\n");
    printf(
        "Outputs: PREFIX_<param>.exr (linear float; --format png: 8-bit by the same rule, colour parameters\n"
        "sRGB-encoded, so they read back as written) for every parameter of the target model, the first input\n"
        "map's alpha carried into RGB outputs, and\n"
        "PREFIX_flags.png: red where a texel lay outside a learned transform's training domain (extrapolated:\n"
        "the paper's Fig. 19 failure) or was converted by a transform that failed its check against the remaps\n"
        "('matremap learn' warns; every texel is then red), or, with --direct, where its fit did not converge\n"
        "(under-resolved, at-bound, unreachable), green where an output left its parameter's range and was\n"
        "clamped, blue where an input was clamped or not finite. The '_' is left out after a PREFIX ending in\n"
        "'/', '_', '-' or '.' (-o out/ writes out/alpha.exr; -o out/ggx and -o out/ggx_ both write\n"
        "out/ggx_alpha.exr); missing folders are made. No output may be an input (exit 2). The outputs are\n"
        "written all or none: to hidden files beside them, renamed into place when every\n"
        "one is written, so a failure leaves the files of an earlier run as they were.\n"
        "\n"
        "Options:\n"
        "  --format exr|png    output format (default exr)\n"
        "  --threads T         OpenMP threads (default 0: automatic, a team for work large enough to gain\n"
        "                      from it); the result does not depend on it\n"
        "  --json              the summary as JSON on stdout\n"
        "  --help              this text\n"
        "\n"
        "Examples:\n"
        "  matremap convert --from ward --to ggx alpha=@rough.exr specular=@spec.png diffuse=@diff.png \\\n"
        "                   --transform ward_ggx.mrt -o out/ggx_\n"
        "  matremap convert --from blender-ward --to ggx specular=0.1 rms=0.2 --transforms transforms/ \\\n"
        "                   --via ward\n");
}

/* "name=VALUE" keeps its form, "name=FILE" becomes "name=@FILE" (cli_material's map syntax); *owned gets the copy. */
static const char *as_material_assignment(const char *arg, char **owned) {
    const char *eq = strchr(arg, '=');
    *owned = NULL;
    if (eq == NULL || eq[1] == '@' || eq[1] == '\0') return arg;
    char *end = NULL;
    (void)strtod(eq + 1, &end);
    if (end != eq + 1 && (*end == '\0' || *end == ',')) return arg; // a number or a list of numbers
    size_t n = strlen(arg);
    char *copy = malloc(n + 2);
    if (copy == NULL) return arg;
    size_t head = (size_t)(eq - arg) + 1;
    memcpy(copy, arg, head);
    copy[head] = '@';
    memcpy(copy + head + 1, eq + 1, n - head + 1);
    *owned = copy;
    return copy;
}

typedef struct progress_state {
    int draw;
    double started;
} progress_state;

static void draw_progress(const mr_direct_progress *p, void *user) {
    progress_state *s = user;
    if (!s->draw || p->total == 0) return;
    const double elapsed = cli_now() - s->started, fraction = (double)p->done / (double)p->total;
    fprintf(stderr, "\rmatremap convert: --direct: %zu/%zu distinct values (%zu from the cache)  %.0f s", p->done,
            p->total, p->cache_hits, elapsed);
    if (fraction > 0.02) fprintf(stderr, ", ETA %.0f s ", elapsed * (1.0 - fraction) / fraction);
}

/* One note of mr_learned_explain_texel, printed with the hop's file and models (or as --direct's). */
typedef struct explain_state {
    const mr_learned *const *chain;
    const char *const *paths;
    int hops;
    const mr_brdf_model *source, *target;
} explain_state;

static void print_note(int hop, const char *note, void *user) {
    const explain_state *e = user;
    if (e->hops > 0)
        fprintf(stderr, "matremap convert: note: hop %d of %d (%s, %s -> %s): %s\n", hop + 1, e->hops,
                e->paths[hop], e->chain[hop]->source->name, e->chain[hop]->target->name, note);
    else
        fprintf(stderr, "matremap convert: note: --direct %s -> %s: %s\n", e->source->name, e->target->name, note);
}

int cmd_convert(int argc, char **argv) {
    const char *from = NULL, *to = NULL, *prefix = NULL, *format = "exr", *dir = NULL, *via_list = NULL;
    const char *hold_list = NULL, *tie_list = NULL;
    const char *assignments[CLI_MAX_ASSIGNMENTS], *transform_paths[MR_LEARNED_MAX_HOPS];
    char *owned[CLI_MAX_ASSIGNMENTS];
    int assignment_count = 0, transform_count = 0, json = 0, threads = 0, direct = 0;
    mr_direct_options dopts = {0};
    for (int i = 1; i < argc; i++) {
        const char *v = NULL;
        int r;
        if (cli_is_help(argv[i])) {
            print_help();
            return CLI_EXIT_OK;
        }
        if ((r = cli_take_option(COMMAND, argc, argv, &i, "--from", &v)) != 0) {
            if (r < 0) return CLI_EXIT_USAGE;
            from = v;
        } else if ((r = cli_take_option(COMMAND, argc, argv, &i, "--to", &v)) != 0) {
            if (r < 0) return CLI_EXIT_USAGE;
            to = v;
        } else if ((r = cli_take_option(COMMAND, argc, argv, &i, "--output", &v)) != 0 ||
                   (r = cli_take_option(COMMAND, argc, argv, &i, "-o", &v)) != 0) {
            if (r < 0) return CLI_EXIT_USAGE;
            prefix = v;
        } else if ((r = cli_take_option(COMMAND, argc, argv, &i, "--transform", &v)) != 0) {
            if (r < 0) return CLI_EXIT_USAGE;
            if (transform_count == MR_LEARNED_MAX_HOPS)
                return cli_usage_error(COMMAND, "more than %d --transform files", MR_LEARNED_MAX_HOPS);
            transform_paths[transform_count++] = v;
        } else if ((r = cli_take_option(COMMAND, argc, argv, &i, "--transforms", &v)) != 0) {
            if (r < 0) return CLI_EXIT_USAGE;
            dir = v;
        } else if ((r = cli_take_option(COMMAND, argc, argv, &i, "--via", &v)) != 0) {
            if (r < 0) return CLI_EXIT_USAGE;
            via_list = v;
        } else if ((r = cli_take_option(COMMAND, argc, argv, &i, "--format", &v)) != 0) {
            if (r < 0) return CLI_EXIT_USAGE;
            if (strcmp(v, "exr") != 0 && strcmp(v, "png") != 0)
                return cli_usage_error(COMMAND, "--format '%s': expected exr or png", v);
            format = v;
        } else if ((r = cli_take_option(COMMAND, argc, argv, &i, "--threads", &v)) != 0) {
            if (r < 0 || !cli_parse_int(COMMAND, "--threads", v, 0, 1024, &threads)) return CLI_EXIT_USAGE;
        } else if (strcmp(argv[i], "--direct") == 0) {
            direct = 1;
        } else if ((r = cli_take_option(COMMAND, argc, argv, &i, "--tolerance", &v)) != 0) {
            if (r < 0 || !cli_parse_double(COMMAND, "--tolerance", v, MR_DIRECT_MIN_TOLERANCE, 1.0, &dopts.tolerance))
                return CLI_EXIT_USAGE;
        } else if ((r = cli_take_option(COMMAND, argc, argv, &i, "--roughness-tolerance", &v)) != 0) {
            if (r < 0 || !cli_parse_double(COMMAND, "--roughness-tolerance", v, MR_DIRECT_MIN_TOLERANCE, 1.0,
                                           &dopts.roughness_tolerance))
                return CLI_EXIT_USAGE;
        } else if ((r = cli_take_option(COMMAND, argc, argv, &i, "--tie", &v)) != 0) {
            if (r < 0) return CLI_EXIT_USAGE;
            tie_list = v;
        } else if ((r = cli_take_option(COMMAND, argc, argv, &i, "--hold", &v)) != 0) {
            if (r < 0) return CLI_EXIT_USAGE;
            hold_list = v;
        } else if ((r = cli_take_option(COMMAND, argc, argv, &i, "--cache", &v)) != 0) {
            if (r < 0) return CLI_EXIT_USAGE;
            dopts.cache_path = v;
        } else if ((r = cli_take_option(COMMAND, argc, argv, &i, "--size", &v)) != 0) {
            if (r < 0 || !cli_parse_int(COMMAND, "--size", v, 8, 4096, &dopts.scene.size)) return CLI_EXIT_USAGE;
        } else if ((r = cli_take_option(COMMAND, argc, argv, &i, "--light", &v)) != 0) {
            if (r < 0) return CLI_EXIT_USAGE;
            if (mr_fit_light_from_name(v, &dopts.scene.light) != MR_OK)
                return cli_usage_error(COMMAND, "--light '%s': expected 45 or frontal", v);
        } else if (strcmp(argv[i], "--json") == 0) {
            json = 1;
        } else if (argv[i][0] == '-' && argv[i][1] != '\0') {
            return cli_usage_error(COMMAND, "unknown option '%s'", argv[i]);
        } else if (strchr(argv[i], '=') != NULL) {
            if (assignment_count == CLI_MAX_ASSIGNMENTS) return cli_usage_error(COMMAND, "too many assignments");
            assignments[assignment_count] = argv[i];
            owned[assignment_count++] = NULL;
        } else {
            return cli_usage_error(COMMAND, "'%s': expected NAME=FILE or NAME=VALUE", argv[i]);
        }
    }
    if (from == NULL || to == NULL) return cli_usage_error(COMMAND, "give --from MODEL and --to MODEL");
    if ((transform_count > 0) + (dir != NULL) + direct != 1)
        return cli_usage_error(COMMAND, "give one of --transform T.mrt (repeatable), --transforms DIR or --direct");
    if (!direct && (dopts.tolerance != 0.0 || dopts.roughness_tolerance != 0.0 || dopts.cache_path ||
                    dopts.scene.size || dopts.scene.light))
        return cli_usage_error(COMMAND, "--tolerance, --roughness-tolerance, --cache, --size and --light go with "
                               "--direct");
    if (!direct && hold_list != NULL)
        return cli_usage_error(COMMAND, "--hold goes with --direct (a learned transform holds what its sweep held)");
    if (via_list != NULL && dir == NULL) return cli_usage_error(COMMAND, "--via needs --transforms DIR");
    const mr_brdf_model *source = mr_brdf_find(from), *target = source ? mr_brdf_find(to) : NULL;
    if (source == NULL || target == NULL) return cli_fail(COMMAND, MR_ERR_INVALID_ARG);
    // --direct's target values: the defaults, with --hold's values; the model's default holds and --hold's are held.
    double target_values[MR_BRDF_MAX_VALUES];
    mr_brdf_default_values(target, target_values);
    if (hold_list != NULL && !cli_parse_held(COMMAND, target, hold_list, target_values, &dopts.remap.held))
        return CLI_EXIT_USAGE;
    if (!direct && tie_list != NULL)
        return cli_usage_error(COMMAND, "--tie goes with --direct (a learned transform ties what its sweep tied)");
    if (direct && !cli_parse_ties(COMMAND, source, target, tie_list, dopts.remap.held, &dopts.remap.ties))
        return CLI_EXIT_USAGE;
    if (direct) dopts.remap.target_values = target_values;

    // The chain.
    mr_learned_set l = {0};
    int code = CLI_EXIT_OK, path[MR_LEARNED_MAX_HOPS], hops = 0;
    mr_status status = MR_OK;
    for (int k = 0; k < transform_count && status == MR_OK; k++) {
        status = mr_learned_set_add_file(&l, transform_paths[k]);
        path[hops++] = k;
    }
    if (status == MR_OK && dir != NULL) {
        char label[4096 + 20];
        snprintf(label, sizeof label, "--transforms '%s'", dir);
        status = mr_learned_set_add_folder(&l, dir, label);
    }
    if (direct || status != MR_OK) {
        // no transforms to find
    } else if (dir != NULL) {
        const mr_brdf_model *via[MR_LEARNED_MAX_HOPS];
        int via_count = 0;
        char list[1024];
        snprintf(list, sizeof list, "%s", via_list ? via_list : "");
        for (char *save = NULL, *w = strtok_r(list, ",", &save); w && status == MR_OK; w = strtok_r(NULL, ",", &save)) {
            if (via_count == MR_LEARNED_MAX_HOPS) break;
            via[via_count] = mr_brdf_find(w);
            if (via[via_count++] == NULL) status = MR_ERR_INVALID_ARG;
        }
        if (status == MR_OK)
            status = mr_learned_find_chain((const mr_learned *const *)l.all, l.count, source, target, via, via_count,
                                           path, &hops);
    } else {
        status = mr_learned_check_ends((const mr_learned *const *)l.all, (const char *const *)l.paths, hops, source,
                                       target);
    }
    if (status != MR_OK) {
        mr_learned_set_free(&l);
        return cli_fail(COMMAND, status);
    }
    // Maps and constants as cli_material_load takes them (NAME=FILE is NAME=@FILE there).
    const char *labels[CLI_MAX_ASSIGNMENTS]; // as given, for messages
    int maps_given = 0;
    for (int k = 0; k < assignment_count; k++) {
        labels[k] = assignments[k];
        assignments[k] = as_material_assignment(assignments[k], &owned[k]);
        maps_given |= strchr(assignments[k], '=')[1] == '@';
    }
    // Outputs: named, checked against every input before anything is written.
    char names[MR_TRANSFORM_MAX_SLOTS + 1][4096];
    const int out_count = target->param_count;
    if (out_count > MR_TRANSFORM_MAX_SLOTS) { // the names and outputs below have room for that many (and the flags)
        fprintf(stderr, "matremap convert: error: model '%s' has %d parameters, more than the %d a conversion writes\n",
                target->name, out_count, MR_TRANSFORM_MAX_SLOTS);
        code = CLI_EXIT_BAD_INPUT;
    }
    if (code == CLI_EXIT_OK && maps_given) {
        if (prefix == NULL) code = cli_usage_error(COMMAND, "maps given: name the outputs with -o PREFIX");
        for (int j = 0; code == CLI_EXIT_OK && j <= out_count; j++) {
            char name[256];
            if (j < out_count)
                snprintf(name, sizeof name, "%s.%s", target->params[j].name, format);
            else
                snprintf(name, sizeof name, "flags.png");
            if (mr_img_prefixed_name(names[j], sizeof names[j], prefix, name) != MR_OK)
                code = cli_usage_error(COMMAND, "-o '%s': too long", prefix);
        }
    }
    if (code == CLI_EXIT_OK) {
        mr_output_plan io = {0};
        cli_plan_material(&io, assignments, labels, assignment_count);
        for (int k = 0; k < l.count; k++) mr_output_plan_inputf(&io, l.paths[k], "transform %s", l.paths[k]);
        for (int j = 0; maps_given && j <= out_count; j++) mr_output_plan_outputf(&io, names[j], "-o %s", prefix);
        // The cache is read and rewritten: an output, never over another input or output.
        if (dopts.cache_path != NULL) mr_output_plan_output(&io, dopts.cache_path, "--cache");
        code = cli_plan_check(COMMAND, &io);
        mr_output_plan_free(&io);
    }
    if (code != CLI_EXIT_OK) {
        for (int k = 0; k < assignment_count; k++) free(owned[k]);
        mr_learned_set_free(&l);
        return code;
    }
    const mr_learned *chain[MR_LEARNED_MAX_HOPS];
    const char *hop_paths[MR_LEARNED_MAX_HOPS];
    for (int h = 0; h < hops; h++) {
        chain[h] = l.all[path[h]];
        hop_paths[h] = l.paths[path[h]];
    }
    for (int h = 0; h < hops && !direct; h++) // a transform that failed its check: said before the work
        if (chain[h]->check.done && !chain[h]->check.passed)
            fprintf(stderr, "matremap convert: warning: transform %s (%s -> %s by %s) failed its check against the "
                    "remaps when it was learned (docs/learn.md, \"The check\"); every texel it converts is flagged "
                    "(red)\n", hop_paths[h], chain[h]->source->name, chain[h]->target->name,
                    mr_learn_method_name(chain[h]->method));

    // The job: the kind, the material, the conversion, the outputs written all or none.
    progress_state progress = {isatty(STDERR_FILENO) && !json, cli_now()};
    dopts.progress = draw_progress;
    dopts.progress_user = &progress;
    const char *outputs[MR_TRANSFORM_MAX_SLOTS + 1];
    for (int j = 0; j <= out_count; j++) outputs[j] = names[j];
    char label[4096 + 8];
    snprintf(label, sizeof label, "-o %s", prefix ? prefix : "");
    const mr_learned_conversion_spec spec = {.source = source, .target = target, .chain = chain,
                                             .hops = direct ? 0 : hops, .direct = &dopts,
                                             .assignments = assignments, .assignment_count = assignment_count,
                                             .outputs = maps_given ? outputs : NULL, .output_label = label,
                                             .threads = threads};
    mr_learned_conversion r;
    status = mr_learned_convert_material(&spec, &r);
    if (progress.draw && direct && r.converting) fprintf(stderr, "\r\033[K");
    if (status != MR_OK) {
        code = r.material_report.usage ? cli_usage_error(COMMAND, "%s", mr_last_error()) : cli_fail(COMMAND, status);
        for (int k = 0; k < assignment_count; k++) free(owned[k]);
        mr_learned_set_free(&l);
        return code;
    }
    const mr_direct_summary *ds = r.has_direct ? &r.direct : NULL;
    if (ds != NULL && !json)
        fprintf(stderr,
                "matremap convert: --direct: %zu distinct values (tolerance %.4g): %zu from the cache, %zu full "
                "remaps, %zu warm-started (%zu fell back to full, %zu shared a shape), %ld renders; outcomes: %zu "
                "converged, %zu under-resolved, %zu at-bound, %zu unreachable, %zu local-minimum\n",
                ds->unique, r.direct_tolerance, ds->cache_hits, ds->full, ds->warm, ds->fallbacks, ds->shared_shapes,
                ds->renders,
                ds->outcomes[MR_FIT_CONVERGED], ds->outcomes[MR_FIT_UNDER_RESOLVED], ds->outcomes[MR_FIT_AT_BOUND],
                ds->outcomes[MR_FIT_UNREACHABLE], ds->outcomes[MR_FIT_LOCAL_MINIMUM]);
    if (ds != NULL && !json) {
        cli_print_holds_tied(stderr, "matremap convert: --direct: ", target, target_values, dopts.remap.held,
                             dopts.remap.ties.tied);
        cli_print_ties(stderr, "matremap convert: --direct: ", source, target, &dopts.remap.ties, tie_list != NULL);
    }
    mr_image *const *out = r.converted;
    const int any_map = r.material->map_count > 0;
    if (json) {
        printf("{\"source\": \"%s\", \"target\": \"%s\", \"method\": \"%s\", ", source->name, target->name,
               direct ? "direct" : "learned");
        if (ds != NULL)
            printf("\"direct\": {\"unique\": %zu, \"cache_hits\": %zu, \"full\": %zu, \"warm\": %zu, "
                   "\"fallbacks\": %zu, \"shared_shapes\": %zu, \"renders\": %ld, \"converged\": %zu, "
                   "\"outcomes\": {",
                   ds->unique, ds->cache_hits, ds->full, ds->warm, ds->fallbacks, ds->shared_shapes, ds->renders,
                   ds->outcomes[MR_FIT_CONVERGED]);
        for (int o = 0; ds != NULL && o < MR_FIT_OUTCOME_COUNT; o++)
            printf("%s\"%s\": %zu", o ? ", " : "", mr_fit_outcome_name((mr_fit_outcome)o), ds->outcomes[o]);
        if (ds != NULL) {
            printf("}, \"tied\": ");
            cli_print_ties_json(stdout, source, target, &dopts.remap.ties, tie_list != NULL);
            printf(", \"held\": ");
            cli_print_holds_json(stdout, target, target_values, dopts.remap.held, dopts.remap.ties.tied);
            printf("}, ");
        }
        printf("\"chain\": [");
        for (int h = 0; h < hops; h++) {
            printf("%s", h ? ", " : "");
            cli_json_string(stdout, hop_paths[h]);
        }
        printf("], \"width\": %d, \"height\": %d, \"texels\": %zu, \"seconds\": {\"convert\": %.6f, \"total\": "
               "%.6f}, \"flags\": {\"extrapolated_or_unconverged\": %zu, \"clamped_output\": %zu, "
               "\"clamped_input\": %zu, \"failed_check\": %zu, "
               "\"any\": %zu}, \"outputs\": [",
               r.width, r.height, r.texels, r.convert_seconds, r.seconds, r.extrapolated, r.clamped_output,
               r.clamped_input, r.failed_check, r.flagged);
        for (int j = 0; any_map && j <= out_count; j++) {
            printf("%s", j ? ", " : "");
            cli_json_string(stdout, names[j]);
        }
        printf("], \"values\": {");
        for (int j = 0; !any_map && j < out_count; j++)
            if (target->params[j].channels == 3)
                printf("%s\"%s\": [%.9g, %.9g, %.9g]", j ? ", " : "", target->params[j].name, out[j]->pixels[0],
                       out[j]->pixels[1], out[j]->pixels[2]);
            else
                printf("%s\"%s\": %.9g", j ? ", " : "", target->params[j].name, out[j]->pixels[0]);
        printf("}}\n");
    } else if (!any_map) {
        printf("%s", target->name);
        for (int j = 0; j < out_count; j++)
            if (target->params[j].channels == 3)
                printf(" %s=%.6g,%.6g,%.6g", target->params[j].name, out[j]->pixels[0], out[j]->pixels[1],
                       out[j]->pixels[2]);
            else
                printf(" %s=%.6g", target->params[j].name, out[j]->pixels[0]);
        printf("\n");
        if (r.flagged) {
            double converted[MR_BRDF_MAX_VALUES];
            for (int j = 0; j < out_count; j++)
                for (int c = 0; c < target->params[j].channels; c++)
                    converted[mr_brdf_param_offset(target, j) + c] = out[j]->pixels[c];
            explain_state e = {chain, hop_paths, direct ? 0 : hops, source, target};
            mr_learned_explain_texel(chain, e.hops, source, r.material->values, target, converted, r.flags[0],
                                     print_note, &e);
        }
    } else {
        if (direct)
            printf("matremap convert: %s -> %s by direct remaps, %dx%d = %zu texels in %.2f s (convert %.3f s): "
                   "%zu not converged, %zu clamped outputs, %zu clamped or non-finite inputs\n",
                   source->name, target->name, r.width, r.height, r.texels, r.seconds, r.convert_seconds,
                   r.extrapolated, r.clamped_output, r.clamped_input);
        else
            printf("matremap convert: %s -> %s through %d transform%s, %dx%d = %zu texels in %.2f s (convert %.3f "
                   "s): %zu extrapolated (outside the training domain), %zu by a transform that failed its check, "
                   "%zu clamped outputs, %zu clamped or non-finite inputs\n",
                   source->name, target->name, hops, hops == 1 ? "" : "s", r.width, r.height, r.texels, r.seconds,
                   r.convert_seconds, r.extrapolated, r.failed_check, r.clamped_output, r.clamped_input);
        fprintf(stderr, "matremap convert: wrote");
        for (int j = 0; j <= out_count; j++) fprintf(stderr, " %s", names[j]);
        fprintf(stderr, "\n");
    }
    mr_learned_conversion_free(&r);
    for (int k = 0; k < assignment_count; k++) free(owned[k]);
    mr_learned_set_free(&l);
    return code;
}
