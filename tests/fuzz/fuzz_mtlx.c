/*
 * fuzz_mtlx.c — the MaterialX reader (src/doc/mtlx_read.c: expat and our walk over its elements; export's .mtlx
 * input) and what export does with what it read without a remap: written again as MaterialX or USD text, the
 * maps rebased to another folder, and a copy conversion (the same model). The remap route is left out (a fit per
 * material is seconds, not a parser).
 */
#include <stdlib.h>

#include "doc/doc.h"
#include "fuzz.h"
#include "matremap.h"

int mr_fuzz_mtlx(const uint8_t *data, size_t size) {
    const char *path = fuzz_write_scratch("in.mtlx", data, size);
    if (path == NULL) return 0;
    mr_doc *doc = NULL;
    if (mr_doc_read_mtlx(path, &doc) != MR_OK) return 0;
    char *text = NULL;
    if (mr_doc_to_text(doc, MR_DOC_FORMAT_MTLX, &text) == MR_OK) free(text);
    text = NULL;
    if (mr_doc_to_text(doc, MR_DOC_FORMAT_USDA, &text) == MR_OK) free(text);
    (void)mr_doc_rebase(doc, path, "out/sub/out.mtlx");
    const mr_doc_material *m = mr_doc_material_get(doc, 0);
    mr_doc_gltf_options o = {0};
    o.target = m ? m->model : NULL;
    mr_doc_gltf_result *r = NULL;
    if (mr_doc_convert(doc, "fuzz", &o, &r) == MR_OK) mr_doc_gltf_result_free(r);
    mr_doc_free(doc);
    return 0;
}

MR_FUZZ_ENTRY(mr_fuzz_mtlx)
