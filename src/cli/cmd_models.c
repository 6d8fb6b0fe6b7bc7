/* cmd_models.c — `matremap models [NAME] [--json]`: the registered BRDF models and their parameters. */
#include <string.h>

#include "cli.h"

#define MAX_INT(a, b) ((a) > (b) ? (a) : (b))

/* The default as text: one number, or r,g,b when the channels differ. */
static const char *default_text(const mr_brdf_param *p, char *buf, size_t size) {
    if (p->channels == 3 && p->default_rgb)
        snprintf(buf, size, "%.3g,%.3g,%.3g", p->default_rgb[0], p->default_rgb[1], p->default_rgb[2]);
    else
        snprintf(buf, size, "%.4g", p->default_value);
    return buf;
}

/* How an 8/16-bit map of the parameter is read: "sRGB" or "linear" (the one rule, io/image_io.h). */
static const char *map_encoding(const mr_brdf_param *p) {
    return mr_img_encoding_name(mr_brdf_param_map_encoding(p, MR_MAP_AS_PARAMETER));
}

/* "name name[rgb] ..." for the model list. */
static void print_help(void) {
    printf("Usage: matremap models [NAME] [--json]\n"
           "\n"
           "Lists every registered BRDF model with its parameters. With NAME, describes that model in detail:\n"
           "each parameter's channels, default, range, role, lobe, map encoding and meaning. Parameters are given\n"
           "to other commands as name=value, or name=r,g,b for RGB ones (a single value sets all three channels),\n"
           "or as texture maps (name=@FILE).\n"
           "\n"
           "ENCODING is how every command reads an 8/16-bit map of the parameter: sRGB for colours (reflectances\n"
           "and albedos given as RGB colours: diffuse, specular, f0, base colour), linear for everything else\n"
           "(roughness, alpha, metallic, ior, scalars, switches), whatever the parameter's range. Float files (EXR,\n"
           "HDR, float TIFF) are always linear. FILE:linear or FILE:srgb overrides the rule for one map.\n"
           "\n"
           "Options:\n"
           "  --json    machine-readable output on stdout\n"
           "  --help    this text\n");
}

static void print_json_model(const mr_brdf_model *m) {
    printf("{\"name\": ");
    cli_json_string(stdout, m->name);
    printf(", \"summary\": ");
    cli_json_string(stdout, m->summary);
    printf(", \"source\": ");
    cli_json_string(stdout, m->source);
    printf(", \"energy_conserving\": %s, \"analytic_gradient\": %s, \"parameters\": [",
           (m->flags & MR_BRDF_NOT_ENERGY_CONSERVING) ? "false" : "true", m->eval_grad ? "true" : "false");
    for (int i = 0; i < m->param_count; i++) {
        const mr_brdf_param *p = &m->params[i];
        printf("%s{\"name\": ", i ? ", " : "");
        cli_json_string(stdout, p->name);
        printf(", \"channels\": %d, \"default\": ", p->channels);
        if (p->channels == 3)
            printf("[%.17g, %.17g, %.17g]", mr_brdf_param_default(p, 0), mr_brdf_param_default(p, 1),
                   mr_brdf_param_default(p, 2));
        else
            printf("%.17g", p->default_value);
        printf(", \"min\": %.17g, \"max\": %.17g, \"role\": \"%s\", \"lobe\": \"%s\", \"log_scale\": %s, "
               "\"map_encoding\": \"%s\", ",
               p->min_value, p->max_value, mr_param_role_name(p->role), mr_param_lobe_name(p->lobe),
               (p->flags & MR_PARAM_LOG_SCALE) ? "true" : "false", map_encoding(p));
        printf("\"fit\": \"%s\", \"meaning\": ", // fitted, or held by default (mr_brdf_hold_reason)
               mr_brdf_hold_reason(m, 0, i) == MR_HOLD_FITTED ? "fitted"
               : mr_brdf_hold_reason(m, 0, i) == MR_HOLD_SWITCH ? "switch" : "held");
        cli_json_string(stdout, p->meaning);
        printf("}");
    }
    printf("]}");
}

static void print_model_detail(const mr_brdf_model *m) {
    printf("%s — %s\n", m->name, m->summary);
    printf("source: %s\n", m->source);
    if (m->flags & MR_BRDF_NOT_ENERGY_CONSERVING)
        printf("note: may reflect more energy than it receives (not bounded by the white-furnace test)\n");
    if (m->flags & MR_BRDF_NON_RECIPROCAL)
        printf("note: not reciprocal (layers are albedo-scaled at the view direction, the first of eval's two)\n");
    printf("analytic parameter derivatives: %s\n", m->eval_grad ? "yes" : "no");
    // The default holds (brdf.h, mr_brdf_hold_reason): what a remap into this model fits and what it holds.
    double defaults[MR_BRDF_MAX_VALUES];
    mr_brdf_default_values(m, defaults);
    char held[1024];
    if (mr_brdf_format_holds(m, defaults, 0, NULL, held, sizeof held) > 0) {
        printf("fits hold: %s; --hold NAME=VALUE holds others or another value\nfits solve:", held);
        for (int i = 0; i < m->param_count; i++)
            if (mr_brdf_hold_reason(m, 0, i) == MR_HOLD_FITTED) printf(" %s", m->params[i].name);
        printf("\n");
    }
    printf("\n");
    int width = 15; // the names' column: as wide as the longest name (use_specular_workflow)
    for (int i = 0; i < m->param_count; i++)
        if ((int)strlen(m->params[i].name) > width) width = (int)strlen(m->params[i].name);
    printf("  %-*s %-3s %-17s %7s %7s  %-9s %-8s %-8s %s\n", width, "PARAMETER", "CH", "DEFAULT", "MIN", "MAX",
           "ROLE", "LOBE", "ENCODING", "MEANING");
    for (int i = 0; i < m->param_count; i++) {
        const mr_brdf_param *p = &m->params[i];
        char def[64];
        printf("  %-*s %-3d %-17s %7.4g %7.4g  %-9s %-8s %-8s %s\n", width, p->name, p->channels,
               default_text(p, def, sizeof def), p->min_value, p->max_value, mr_param_role_name(p->role),
               mr_param_lobe_name(p->lobe), map_encoding(p), p->meaning);
    }
    printf("\nENCODING: how an 8/16-bit map of the parameter is read (float files are always linear; FILE:linear or\n"
           "FILE:srgb overrides it).\n");
}

int cmd_models(int argc, char **argv) {
    int json = 0;
    const char *name = NULL;
    for (int i = 1; i < argc; i++) {
        if (cli_is_help(argv[i])) {
            print_help();
            return CLI_EXIT_OK;
        } else if (strcmp(argv[i], "--json") == 0) {
            json = 1;
        } else if (argv[i][0] == '-') {
            return cli_usage_error("models", "unknown option '%s'", argv[i]);
        } else if (name == NULL) {
            name = argv[i];
        } else {
            return cli_usage_error("models", "unexpected argument '%s'", argv[i]);
        }
    }
    if (name != NULL) {
        const mr_brdf_model *m = mr_brdf_find(name);
        if (m == NULL) return cli_fail("models", MR_ERR_INVALID_ARG);
        if (json) {
            print_json_model(m);
            printf("\n");
        } else {
            print_model_detail(m);
        }
        return CLI_EXIT_OK;
    }
    const mr_brdf_model *const *models = mr_brdf_models();
    if (json) {
        printf("[");
        for (int i = 0; models[i] != NULL; i++) {
            printf("%s\n  ", i ? "," : "");
            print_json_model(models[i]);
        }
        printf("\n]\n");
        return CLI_EXIT_OK;
    }
    // One line per model (its name, then its summary, in one column), its parameters on the lines below it,
    // wrapped: today's layered models have twenty parameters, too many for a column.
    int name_width = 5;
    for (int i = 0; models[i] != NULL; i++) name_width = MAX_INT(name_width, (int)strlen(models[i]->name));
    printf("%-*s  %s\n", name_width, "MODEL", "SUMMARY (PARAMETERS below)");
    for (int i = 0; models[i] != NULL; i++) {
        const mr_brdf_model *m = models[i];
        printf("%-*s  %s%s\n", name_width, m->name, m->summary,
               (m->flags & MR_BRDF_NOT_ENERGY_CONSERVING) ? " [albedo can exceed 1]" : "");
        int column = 0;
        for (int k = 0; k < m->param_count; k++) {
            char word[96];
            snprintf(word, sizeof word, "%s%s", m->params[k].name, m->params[k].channels == 3 ? "[rgb]" : "");
            if (column > 0 && column + 1 + (int)strlen(word) > 116) {
                printf("\n");
                column = 0;
            }
            column += printf("%*s%s", column == 0 ? name_width + 2 : 1, "", word);
        }
        printf("\n");
    }
    printf("\n'matremap models NAME' shows a model's parameters with ranges and meanings.\n");
    return CLI_EXIT_OK;
}
