/*
 * cmd_convert.c — `matremap convert`: texture maps (or constants) of one BRDF model's parameters converted to
 * another model's, per texel, through learned transforms (one, a chain given or found), through the library's
 * conversion of a material (mr_transform_convert_material); the outputs and the flag picture (mr_flag_picture,
 * mr_learned_flag_code) written all or none (mr_img_write_set); see docs/learn.md.
 */
#include <dirent.h>
#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cli.h"
#include "learn/learned.h"

#define COMMAND "convert"
#define MAX_TRANSFORMS 256

static void print_help(void) {
    printf(
        "Usage: matremap convert --from MODEL --to MODEL NAME=FILE|VALUE ...\n"
        "                        (--transform T.mrt [--transform T2.mrt ...] | --transforms DIR [--via MODEL,...] |\n"
        "                         --direct [--tolerance T] [--cache FILE] [--size N] [--light 45|frontal])\n"
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
        "  --cache FILE        --direct: answers kept across runs (created if missing; refused if it was made\n"
        "                      for other models, options or scene)\n"
        "  --size N, --light L --direct: the fit scene (default 64, 45; as 'matremap remap')\n"
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

typedef struct loaded {
    mr_learned *all[MAX_TRANSFORMS];
    char *paths[MAX_TRANSFORMS];
    int count;
} loaded;

static void loaded_free(loaded *l) {
    for (int i = 0; i < l->count; i++) {
        mr_learned_free(l->all[i]);
        free(l->paths[i]);
    }
    l->count = 0;
}

static int load_one(loaded *l, const char *path) {
    if (l->count == MAX_TRANSFORMS) return cli_usage_error(COMMAND, "more than %d transforms", MAX_TRANSFORMS);
    mr_status status = mr_learned_read(path, &l->all[l->count]);
    if (status != MR_OK) return cli_fail(COMMAND, status);
    l->paths[l->count] = strdup(path);
    l->count++;
    return CLI_EXIT_OK;
}

static int load_dir(loaded *l, const char *dir) {
    DIR *d = opendir(dir);
    if (d == NULL) {
        fprintf(stderr, "matremap convert: error: --transforms '%s': %s\n", dir, strerror(errno));
        return CLI_EXIT_BAD_INPUT;
    }
    // Sorted names, so the chain chosen among equals does not depend on the directory's order.
    char *names[MAX_TRANSFORMS];
    int count = 0, code = CLI_EXIT_OK;
    struct dirent *e;
    while ((e = readdir(d)) != NULL) {
        size_t n = strlen(e->d_name);
        if (n < 5 || strcmp(e->d_name + n - 4, ".mrt") != 0) continue;
        if (count == MAX_TRANSFORMS) break;
        names[count++] = strdup(e->d_name);
    }
    closedir(d);
    for (int i = 1; i < count; i++)
        for (int j = i; j > 0 && strcmp(names[j - 1], names[j]) > 0; j--) {
            char *t = names[j];
            names[j] = names[j - 1];
            names[j - 1] = t;
        }
    for (int i = 0; i < count; i++) {
        char path[4096];
        snprintf(path, sizeof path, "%s/%s", dir, names[i]);
        if (code == CLI_EXIT_OK) code = load_one(l, path);
        free(names[i]);
    }
    if (code == CLI_EXIT_OK && count == 0) {
        fprintf(stderr, "matremap convert: error: --transforms '%s': no *.mrt files there\n", dir);
        code = CLI_EXIT_BAD_INPUT;
    }
    return code;
}

/* "name v", "name r,g,b": parameter p of `model` in packed `values`, appended to text. */
static void append_param(char *text, size_t size, const mr_brdf_model *model, const double *values, int p) {
    const int at = mr_brdf_param_offset(model, p);
    size_t used = strlen(text);
    if (model->params[p].channels == 3)
        snprintf(text + used, size - used, "%s %.4g,%.4g,%.4g", model->params[p].name, values[at], values[at + 1],
                 values[at + 2]);
    else
        snprintf(text + used, size - used, "%s %.4g", model->params[p].name, values[at]);
}

/* What the flags of a converted constant texel came from, one note per hop that raised one: the transform (its
 * file, its models), the source parameters outside its training domain, the target parameters it clamped into their
 * ranges (those left on a bound of their range), inputs clamped or not finite. The chain is run again hop by hop on
 * the texel (mr_learned_apply: the values of the chain, each hop's own flags). With --direct (no hops), the
 * parameters on a bound are named. */
static void explain_texel(const mr_learned *const *chain, const char *const *paths, int hops,
                          const mr_brdf_model *source, const double *source_values, const mr_brdf_model *target,
                          const double *target_values, unsigned flags) {
    double values[2][MR_BRDF_MAX_VALUES];
    memcpy(values[0], source_values, (size_t)mr_brdf_value_count(source) * sizeof values[0][0]);
    for (int h = 0; h <= hops; h++) {
        const mr_learned *t = h < hops ? chain[h] : NULL;
        const mr_brdf_model *in_model = t ? t->source : source, *out_model = t ? t->target : target;
        const double *in = values[h % 2];
        double *out = values[(h + 1) % 2];
        unsigned f = flags;
        if (t != NULL)
            mr_learned_apply(t, in, out, &f);
        else if (hops == 0) // --direct: the converted values as they are
            memcpy(out, target_values, (size_t)mr_brdf_value_count(target) * sizeof out[0]);
        else
            break;
        if ((f & (MR_WF_EXTRAPOLATED | MR_WF_UNCONVERGED | MR_WF_CLAMPED_OUTPUT | MR_WF_CLAMPED_INPUT |
                  MR_WF_NONFINITE_INPUT | MR_WF_UNCHECKED)) == 0)
            continue;
        char note[2048] = "";
        if (t != NULL && (f & MR_WF_UNCHECKED))
            snprintf(note + strlen(note), sizeof note - strlen(note),
                     "the transform failed its check against the remaps when it was learned; ");
        if (t != NULL && (f & MR_WF_EXTRAPOLATED)) {
            snprintf(note + strlen(note), sizeof note - strlen(note), "extrapolated, outside its training domain:");
            for (int k = 0; k < t->feature_count; k++) {
                const mr_learned_slot *slot = &t->features[k];
                const int at = mr_brdf_param_offset(in_model, slot->param);
                const int channels = slot->kind == MR_LEARNED_GREY ? 3 : 1;
                const int first = slot->kind == MR_LEARNED_CHANNEL ? slot->channel : 0;
                int outside = 0;
                for (int c = first; c < first + channels; c++)
                    outside |= in[at + c] < slot->min || in[at + c] > slot->max;
                if (!outside) continue;
                snprintf(note + strlen(note), sizeof note - strlen(note), " ");
                append_param(note, sizeof note, in_model, in, slot->param);
                snprintf(note + strlen(note), sizeof note - strlen(note), " (trained on [%.4g, %.4g])", slot->min,
                         slot->max);
            }
            snprintf(note + strlen(note), sizeof note - strlen(note), "; ");
        }
        if (t == NULL && (f & MR_WF_UNCONVERGED))
            snprintf(note + strlen(note), sizeof note - strlen(note), "the fit did not converge; ");
        if (f & MR_WF_CLAMPED_OUTPUT) {
            snprintf(note + strlen(note), sizeof note - strlen(note), "clamped into its range:");
            for (int p = 0; p < out_model->param_count; p++) {
                const mr_brdf_param *param = &out_model->params[p];
                const int at = mr_brdf_param_offset(out_model, p);
                int bound = 0;
                for (int c = 0; c < param->channels; c++)
                    bound |= out[at + c] <= param->min_value || out[at + c] >= param->max_value;
                if (!bound || param->role == MR_PARAM_SWITCH || param->min_value == param->max_value) continue;
                snprintf(note + strlen(note), sizeof note - strlen(note), " ");
                append_param(note, sizeof note, out_model, out, p);
                snprintf(note + strlen(note), sizeof note - strlen(note), " (range [%g, %g])", param->min_value,
                         param->max_value);
            }
            snprintf(note + strlen(note), sizeof note - strlen(note), "; ");
        }
        if (f & (MR_WF_CLAMPED_INPUT | MR_WF_NONFINITE_INPUT))
            snprintf(note + strlen(note), sizeof note - strlen(note), "an input was clamped or not finite; ");
        note[strlen(note) - 2] = '\0'; // the last "; "
        if (t != NULL)
            fprintf(stderr, "matremap convert: note: hop %d of %d (%s, %s -> %s): %s\n", h + 1, hops, paths[h],
                    t->source->name, t->target->name, note);
        else
            fprintf(stderr, "matremap convert: note: --direct %s -> %s: %s\n", source->name, target->name, note);
        flags = 0; // a chain's hops raise their own
    }
}

int cmd_convert(int argc, char **argv) {
    const char *from = NULL, *to = NULL, *prefix = NULL, *format = "exr", *dir = NULL, *via_list = NULL;
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
    if (!direct && (dopts.tolerance != 0.0 || dopts.cache_path || dopts.scene.size || dopts.scene.light))
        return cli_usage_error(COMMAND, "--tolerance, --cache, --size and --light go with --direct");
    if (via_list != NULL && dir == NULL) return cli_usage_error(COMMAND, "--via needs --transforms DIR");
    const mr_brdf_model *source = mr_brdf_find(from), *target = source ? mr_brdf_find(to) : NULL;
    if (source == NULL || target == NULL) return cli_fail(COMMAND, MR_ERR_INVALID_ARG);

    // The chain.
    loaded l = {{NULL}, {NULL}, 0};
    int code = CLI_EXIT_OK, path[MR_LEARNED_MAX_HOPS], hops = 0;
    for (int k = 0; k < transform_count && code == CLI_EXIT_OK; k++) {
        code = load_one(&l, transform_paths[k]);
        path[hops++] = k;
    }
    if (code == CLI_EXIT_OK && dir != NULL) code = load_dir(&l, dir);
    if (code != CLI_EXIT_OK) {
        loaded_free(&l);
        return code;
    }
    if (direct) {
        // no transforms to find
    } else if (dir != NULL) {
        const mr_brdf_model *via[MR_LEARNED_MAX_HOPS];
        int via_count = 0;
        char list[1024];
        snprintf(list, sizeof list, "%s", via_list ? via_list : "");
        for (char *save = NULL, *w = strtok_r(list, ",", &save); w; w = strtok_r(NULL, ",", &save)) {
            if (via_count == MR_LEARNED_MAX_HOPS) break;
            via[via_count] = mr_brdf_find(w);
            if (via[via_count++] == NULL) {
                loaded_free(&l);
                return cli_fail(COMMAND, MR_ERR_INVALID_ARG);
            }
        }
        mr_status status = mr_learned_find_chain((const mr_learned *const *)l.all, l.count, source, target, via,
                                                 via_count, path, &hops);
        if (status != MR_OK) {
            loaded_free(&l);
            return cli_fail(COMMAND, status);
        }
    } else {
        const mr_learned *first = l.all[path[0]], *last = l.all[path[hops - 1]];
        const char *bad = first->source != source ? l.paths[path[0]] : last->target != target ? l.paths[path[hops - 1]]
                                                                                               : NULL;
        if (bad != NULL) {
            fprintf(stderr, "matremap convert: error: '%s' converts %s to %s, but the conversion asked is %s to %s\n",
                    bad, (bad == l.paths[path[0]] ? first : last)->source->name,
                    (bad == l.paths[path[0]] ? first : last)->target->name, source->name, target->name);
            loaded_free(&l);
            return CLI_EXIT_BAD_INPUT;
        }
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
    if (code == CLI_EXIT_OK && maps_given) {
        if (prefix == NULL) code = cli_usage_error(COMMAND, "maps given: name the outputs with -o PREFIX");
        for (int j = 0; code == CLI_EXIT_OK && j <= out_count; j++) {
            char name[256];
            if (j < out_count)
                snprintf(name, sizeof name, "%s.%s", target->params[j].name, format);
            else
                snprintf(name, sizeof name, "flags.png");
            if (!cli_output_name(names[j], sizeof names[j], prefix, name))
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
        loaded_free(&l);
        return code;
    }
    const mr_learned *chain[MR_LEARNED_MAX_HOPS];
    for (int h = 0; h < hops; h++) chain[h] = l.all[path[h]];
    for (int h = 0; h < hops && !direct; h++) // a transform that failed its check: said before the work
        if (chain[h]->check.done && !chain[h]->check.passed)
            fprintf(stderr, "matremap convert: warning: transform %s (%s -> %s by %s) failed its check against the "
                    "remaps when it was learned (docs/learn.md, \"The check\"); every texel it converts is flagged "
                    "(red)\n", l.paths[path[h]], chain[h]->source->name, chain[h]->target->name,
                    mr_learn_method_name(chain[h]->method));
    // Constants alone are one texel: remapped at their exact values, not at a quantised neighbour (which the
    // default step puts up to 12 % away for a dark colour), unless --tolerance says otherwise.
    if (direct && !maps_given && dopts.tolerance == 0.0) dopts.tolerance = MR_DIRECT_MIN_TOLERANCE;
    mr_transform_kind *kind = NULL;
    progress_state progress = {isatty(STDERR_FILENO) && !json, cli_now()};
    dopts.threads = threads;
    dopts.progress = draw_progress;
    dopts.progress_user = &progress;
    mr_status status = direct ? mr_direct_kind_create(source, target, &dopts, &kind)
                              : mr_learned_kind_create(chain, hops, &kind);
    if (status != MR_OK) {
        for (int k = 0; k < assignment_count; k++) free(owned[k]);
        loaded_free(&l);
        return cli_fail(COMMAND, status);
    }

    // The source material: maps and constants.
    const double started = cli_now();
    mr_material *m = NULL;
    code = cli_material_load(COMMAND, from, assignments, assignment_count, &m);
    mr_transform *t = NULL;
    mr_transform_options topts = {0};
    topts.threads = threads;
    if (code == CLI_EXIT_OK) {
        status = mr_transform_create(kind, &topts, &t);
        if (status != MR_OK) code = cli_fail(COMMAND, status);
    }
    mr_image *out[MR_TRANSFORM_MAX_SLOTS] = {NULL}; // RGB outputs carry the first map's alpha
    uint8_t *flags = NULL;
    const int any_map = code == CLI_EXIT_OK && m->map_count > 0;
    double convert_seconds = 0.0;
    if (code == CLI_EXIT_OK) {
        const double t0 = cli_now();
        status = mr_transform_convert_material(t, m, out, &flags);
        convert_seconds = cli_now() - t0;
        if (progress.draw && direct) fprintf(stderr, "\r\033[K");
        if (status != MR_OK) code = cli_fail(COMMAND, status);
    }
    // extrapolated or unconverged, clamped output, clamped input, any flag, by a transform that failed its check
    // (the flag map's red is the first or the last)
    static const unsigned reasons[5] = {MR_WF_EXTRAPOLATED | MR_WF_UNCONVERGED, MR_WF_CLAMPED_OUTPUT,
                                        MR_WF_CLAMPED_INPUT | MR_WF_NONFINITE_INPUT, 0xFFu, MR_WF_UNCHECKED};
    size_t n = 0, counts[5] = {0};
    int width = 0, height = 0;
    if (code == CLI_EXIT_OK) {
        width = out[0]->width;
        height = out[0]->height;
        n = (size_t)width * (size_t)height;
        mr_flags_count(flags, n, reasons, 5, counts);
    }
    // Write: every output, then the flag map, all or none (mr_img_write_set).
    if (code == CLI_EXIT_OK && any_map) {
        mr_image *picture = NULL;
        mr_img_set_item items[MR_TRANSFORM_MAX_SLOTS + 1];
        char label[4096 + 8];
        snprintf(label, sizeof label, "-o %s", prefix);
        // The rule maps are read by, so a PNG output reads back as written.
        for (int j = 0; j < out_count; j++)
            items[j] = (mr_img_set_item){names[j], label, out[j],
                                         {mr_brdf_param_map_encoding(&target->params[j], MR_MAP_AS_PARAMETER), 0, 0}};
        status = mr_flag_picture(flags, width, height, &mr_learned_flag_code, &picture);
        items[out_count] = (mr_img_set_item){names[out_count], label, picture, {MR_IMG_DATA, 0, 0}};
        mr_img_set_options set_options = {threads};
        if (status == MR_OK) status = mr_img_write_set(items, out_count + 1, &set_options, NULL);
        code = status == MR_OK ? CLI_EXIT_OK : cli_fail(COMMAND, status);
        mr_image_free(picture);
    }
    const double seconds = cli_now() - started;
    const mr_direct_summary *ds = direct && code == CLI_EXIT_OK ? mr_direct_kind_summary(kind) : NULL;
    if (ds != NULL && !json)
        fprintf(stderr,
                "matremap convert: --direct: %zu distinct values (tolerance %.4g): %zu from the cache, %zu full "
                "remaps, %zu warm-started (%zu fell back to full), %ld renders; outcomes: %zu converged, %zu "
                "under-resolved, %zu at-bound, %zu unreachable, %zu local-minimum\n",
                ds->unique, dopts.tolerance > 0.0 ? dopts.tolerance : MR_DIRECT_DEFAULT_TOLERANCE, ds->cache_hits,
                ds->full, ds->warm, ds->fallbacks, ds->renders, ds->outcomes[MR_FIT_CONVERGED],
                ds->outcomes[MR_FIT_UNDER_RESOLVED], ds->outcomes[MR_FIT_AT_BOUND], ds->outcomes[MR_FIT_UNREACHABLE],
                ds->outcomes[MR_FIT_LOCAL_MINIMUM]);
    if (code == CLI_EXIT_OK) {
        if (json) {
            printf("{\"source\": \"%s\", \"target\": \"%s\", \"method\": \"%s\", ", source->name, target->name,
                   direct ? "direct" : "learned");
            if (ds != NULL)
                printf("\"direct\": {\"unique\": %zu, \"cache_hits\": %zu, \"full\": %zu, \"warm\": %zu, "
                       "\"fallbacks\": %zu, \"renders\": %ld, \"converged\": %zu}, ",
                       ds->unique, ds->cache_hits, ds->full, ds->warm, ds->fallbacks, ds->renders,
                       ds->outcomes[MR_FIT_CONVERGED]);
            printf("\"chain\": [");
            for (int h = 0; h < hops; h++) {
                printf("%s", h ? ", " : "");
                cli_json_string(stdout, l.paths[path[h]]);
            }
            printf("], \"width\": %d, \"height\": %d, \"texels\": %zu, \"seconds\": {\"convert\": %.6f, \"total\": "
                   "%.6f}, \"flags\": {\"extrapolated_or_unconverged\": %zu, \"clamped_output\": %zu, "
                   "\"clamped_input\": %zu, \"failed_check\": %zu, "
                   "\"any\": %zu}, \"outputs\": [",
                   width, height, n, convert_seconds, seconds, counts[0], counts[1], counts[2], counts[4], counts[3]);
            for (int j = 0; any_map && j <= out_count; j++) {
                printf("%s", j ? ", " : "");
                cli_json_string(stdout, names[j]);
            }
            printf("], \"values\": {");
            for (int j = 0; !any_map && j < out_count; j++)
                if (target->params[j].channels == 3)
                    printf("%s\"%s\": [%.9g, %.9g, %.9g]", j ? ", " : "", target->params[j].name,
                           out[j]->pixels[0], out[j]->pixels[1], out[j]->pixels[2]);
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
            if (counts[3]) {
                const char *hop_paths[MR_LEARNED_MAX_HOPS];
                double converted[MR_BRDF_MAX_VALUES];
                for (int h = 0; h < hops; h++) hop_paths[h] = l.paths[path[h]];
                for (int j = 0; j < out_count; j++)
                    for (int c = 0; c < target->params[j].channels; c++)
                        converted[mr_brdf_param_offset(target, j) + c] = out[j]->pixels[c];
                explain_texel(chain, hop_paths, direct ? 0 : hops, source, m->values, target, converted, flags[0]);
            }
        } else {
            if (direct)
                printf("matremap convert: %s -> %s by direct remaps, %dx%d = %zu texels in %.2f s (convert %.3f s): "
                       "%zu not converged, %zu clamped outputs, %zu clamped or non-finite inputs\n",
                       source->name, target->name, width, height, n, seconds, convert_seconds, counts[0], counts[1],
                       counts[2]);
            else
                printf("matremap convert: %s -> %s through %d transform%s, %dx%d = %zu texels in %.2f s (convert %.3f "
                       "s): %zu extrapolated (outside the training domain), %zu by a transform that failed its check, "
                       "%zu clamped outputs, %zu clamped or non-finite inputs\n",
                       source->name, target->name, hops, hops == 1 ? "" : "s", width, height, n, seconds,
                       convert_seconds, counts[0], counts[4], counts[1], counts[2]);
            fprintf(stderr, "matremap convert: wrote");
            for (int j = 0; j <= out_count; j++) fprintf(stderr, " %s", names[j]);
            fprintf(stderr, "\n");
        }
    }
    for (int j = 0; j < MR_TRANSFORM_MAX_SLOTS; j++) mr_image_free(out[j]);
    free(flags);
    mr_transform_free(t);
    mr_material_free(m);
    if (direct)
        mr_direct_kind_free(kind);
    else
        mr_learned_kind_free(kind);
    for (int k = 0; k < assignment_count; k++) free(owned[k]);
    loaded_free(&l);
    return code;
}
