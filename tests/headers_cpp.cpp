// Every public header must compile as C++ too (the glTF and image-I/O shims include them); see also
// tests/test_headers.c. Built by `make check`; a compile error is the failure.
#include "matremap.h"
#include "mr_core.h"
#include "mr_image.h"
#include "mr_status.h"
#include "brdf/brdf.h"
#include "render/render.h"
#include "io/image_io.h"
#include "io/obj_load.h"
#include "metrics/metrics.h"
#include "remap/remap.h"
#include "remap/direct.h"
#include "remap/sweep.h"
#include "workflow/workflow.h"
#include "workflow/dataset.h"
#include "workflow/pairs.h"
#include "learn/learned_plots.h"
#include "report/report.h"
#include "nn/mlp.h"
#include "gltf/mr_gltf.h"
#include "gltf/mr_gltf_scene.h"
#include "doc/doc.h"

extern "C" int mr_headers_cpp_probe(void);
int mr_headers_cpp_probe(void) { return MR_STATUS_COUNT + MR_COMPONENT_COUNT; }
