/*
 * doc_write — one uniform material written as a document by the library's writer (src/doc/doc.h), for the
 * materials of make evaluation-clients that `matremap export` cannot make from a glTF asset (a coat, a metal's
 * specular_color: glTF's model has neither; docs/evaluation-clients.md).
 *
 *   doc_write OUT.mtlx|OUT.usda MODEL NAME [name=value ...]
 *
 * MODEL is openpbr, standard-surface, gltf (MaterialX) or usd-preview (USD). Every parameter of the model is written
 * as a constant, as `matremap export` writes a remapped material: its value from the arguments (name=v or
 * name=r,g,b), else the model's default. Exit codes: 0 written, 1 usage, 2 bad input.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "src/brdf/brdf.h"
#include "src/doc/doc.h"

static int parse_values(const char *text, int channels, double *out) {
    char *end = NULL;
    for (int c = 0; c < channels; c++) {
        out[c] = strtod(text, &end);
        if (end == text) return 0;
        if (c + 1 < channels) {
            if (*end == '\0') { /* one value for every channel */
                for (int k = c + 1; k < channels; k++) out[k] = out[c];
                return 1;
            }
            if (*end != ',') return 0;
            text = end + 1;
        }
    }
    return *end == '\0';
}

int main(int argc, char **argv) {
    if (argc < 4) {
        fprintf(stderr, "usage: doc_write OUT.mtlx|OUT.usda MODEL NAME [name=value ...]\n");
        return 1;
    }
    const mr_brdf_model *model = mr_brdf_find(argv[2]);
    if (model == NULL) {
        fprintf(stderr, "doc_write: %s\n", mr_last_error());
        return 1;
    }
    double values[MR_BRDF_MAX_VALUES][3];
    for (int p = 0; p < model->param_count; p++) {
        const mr_brdf_param *param = &model->params[p];
        for (int c = 0; c < param->channels; c++)
            values[p][c] = param->default_rgb != NULL ? param->default_rgb[c] : param->default_value;
    }
    for (int a = 4; a < argc; a++) {
        const char *eq = strchr(argv[a], '=');
        int found = -1;
        for (int p = 0; eq != NULL && p < model->param_count; p++) {
            if (strlen(model->params[p].name) == (size_t)(eq - argv[a]) &&
                strncmp(model->params[p].name, argv[a], (size_t)(eq - argv[a])) == 0)
                found = p;
        }
        if (found < 0 || !parse_values(eq + 1, model->params[found].channels, values[found])) {
            fprintf(stderr, "doc_write: '%s': expected name=value with a parameter of %s\n", argv[a], model->name);
            return 1;
        }
    }
    mr_doc *doc = mr_doc_create();
    mr_doc_material *m = NULL;
    mr_status status = doc == NULL ? MR_ERR_NOMEM : mr_doc_add_material(doc, argv[3], model, &m);
    for (int p = 0; status == MR_OK && p < model->param_count; p++)
        status = mr_doc_set_constant(m, model->params[p].name, values[p]);
    if (status == MR_OK) status = mr_doc_write(doc, argv[1]);
    mr_doc_free(doc);
    if (status != MR_OK) {
        fprintf(stderr, "doc_write: %s\n", mr_last_error());
        return 2;
    }
    return 0;
}
