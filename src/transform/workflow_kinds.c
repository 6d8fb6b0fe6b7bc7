/*
 * workflow_kinds.c — the metallic <-> specular workflow transforms (transform.h): the analytic converters of
 * workflow.h (paper section 8, Eq. 2 and Eq. 3 with the mean and the albedo-weighted metallic; Khronos's
 * converter), the learned network (nn/mlp.h through mr_wf_spec_to_metal_mlp_batch), and the lossless route of
 * KHR_materials_specular + KHR_materials_ior, each for the model pair it reads and writes:
 *   glTF:  gltf-specgloss (diffuse, specular, glossiness) <-> gltf (base_color, metallic, roughness); the diffuse
 *          read as KHR_materials_pbrSpecularGlossiness dims it (MR_WF_DIFFUSE_SPECGLOSS), roughness = 1 - glossiness;
 *   paper: ggx (diffuse, f0, alpha) <-> ggx-metallic (albedo, metallic, alpha), Eq. 2 as printed
 *          (MR_WF_DIFFUSE_PLAIN), alpha passed through.
 * One family sharing this file's code; each member's configuration is its descriptor's `config`.
 */
#include <math.h>
#include <string.h>

#include "mr_internal.h"
#include "transform/transform.h"

typedef struct workflow_config {
    int to_metal;          /* 1: specular -> metallic; 0: metallic -> specular */
    mr_wf_method method;   /* the analytic method (ignored by network kinds) */
    mr_wf_diffuse diffuse; /* how the specular side's diffuse is read */
    int network;           /* 1: nn/'s network (mr_transform_options.network) */
    int glossiness;        /* 1: the specular side stores glossiness = 1 - roughness (glTF); 0: alpha as is */
} workflow_config;

/* ---- slots -------------------------------------------------------------------------------------------------- */

#define COLOUR(name) {name, 3, 0.0, 1.0, 0.0, 0, 0.0, -1}
#define SCALAR(name) {name, 1, 0.0, 1.0, 0.0, 0, 0.0, -1}
/* A non-finite roughness is read as 1 (fully rough), a glossiness as 0: a broken texel never becomes a mirror. */
#define ROUGHNESS_IN(name) {name, 1, 0.0, 1.0, 1.0, MR_SLOT_OPTIONAL, 0.0, -1}
#define GLOSSINESS_IN {"glossiness", 1, 0.0, 1.0, 0.0, MR_SLOT_OPTIONAL, 0.0, -1}

static const mr_transform_slot gltf_spec_in[] = {COLOUR("diffuse"), COLOUR("specular"), GLOSSINESS_IN};
static const mr_transform_slot gltf_metal_out[] = {COLOUR("base_color"), SCALAR("metallic"), SCALAR("roughness")};
static const mr_transform_slot gltf_metal_in[] = {COLOUR("base_color"), SCALAR("metallic"),
                                                  ROUGHNESS_IN("roughness")};
static const mr_transform_slot gltf_spec_out[] = {COLOUR("diffuse"), COLOUR("specular"), SCALAR("glossiness")};
static const mr_transform_slot paper_spec_in[] = {COLOUR("diffuse"), COLOUR("f0"), ROUGHNESS_IN("alpha")};
static const mr_transform_slot paper_metal_out[] = {COLOUR("albedo"), SCALAR("metallic"),
                                                    {"alpha", 1, 0.0, 1.0, 0.0, 0, 0.0, 2}};
static const mr_transform_slot paper_metal_in[] = {COLOUR("albedo"), SCALAR("metallic"), ROUGHNESS_IN("alpha")};
static const mr_transform_slot paper_spec_out[] = {COLOUR("diffuse"), COLOUR("f0"),
                                                   {"alpha", 1, 0.0, 1.0, 0.0, 0, 0.0, 2}};
static const mr_transform_slot extension_out[] = {
    {"base_color", 3, 0.0, 1.0, 0.0, 0, 0.0, 0},
    {"metallic", 1, 0.0, 1.0, 0.0, MR_SLOT_CONSTANT, 0.0, -1},
    SCALAR("roughness"),
    {"specular", 1, 0.0, 1.0, 0.0, MR_SLOT_CONSTANT, 1.0, -1},
    {"specular_color", 3, 0.0, 1.0, 0.0, 0, 0.0, 1},
    // ior 1000 makes the dielectric's F0 the specular colour: ((1000 - 1) / (1000 + 1))^2 = 0.996.
    {"ior", 1, 1.0, 1000.0, 0.0, MR_SLOT_CONSTANT, 1000.0, -1},
};

/* ---- the converters ----------------------------------------------------------------------------------------- */

static mr_wf_options workflow_options(const mr_transform *t, const mr_transform_batch *b) {
    const workflow_config *config = mr_transform_kind_of(t)->config;
    const mr_transform_options *o = mr_transform_options_of(t);
    mr_wf_options w = mr_wf_options_default();
    w.method = config->method;
    w.spec_diffuse = o->plain_diffuse ? MR_WF_DIFFUSE_PLAIN : config->diffuse;
    w.dielectric_f0 = o->dielectric_f0;
    w.eps = o->eps;
    w.threads = b->threads > 0 ? b->threads : o->threads;
    return w;
}

/* The workflow's own checks (Khronos's fixed F0, ranges) at creation, not at the first batch. */
static mr_status workflow_create(const mr_transform_kind *kind, const mr_transform_options *opts, void **state) {
    (void)state;
    const workflow_config *config = kind->config;
    mr_wf_options w = mr_wf_options_default();
    w.method = config->method;
    w.spec_diffuse = opts->plain_diffuse ? MR_WF_DIFFUSE_PLAIN : config->diffuse;
    w.dielectric_f0 = opts->dielectric_f0;
    w.eps = opts->eps;
    mr_status status = mr_wf_options_check(&w);
    return status == MR_OK ? MR_OK : mr_fail_context(status, "transform %s", kind->name);
}

/* 1 - x over n floats (glossiness <-> roughness); NaN and infinities stay non-finite. */
static void complement(const float *in, float *out, size_t n) {
    for (size_t i = 0; i < n; i++) out[i] = 1.0f - in[i];
}

static mr_status spec_to_metal_apply(const mr_transform *t, const mr_transform_batch *b) {
    const workflow_config *config = mr_transform_kind_of(t)->config;
    mr_wf_options w = workflow_options(t, b);
    // The roughness travels in the output plane: the converters pass it through in place.
    float *roughness = b->out[2];
    if (config->glossiness)
        complement(b->in[2], roughness, b->n);
    else if (roughness != b->in[2])
        memcpy(roughness, b->in[2], b->n * sizeof *roughness);
    const mr_wf_spec_input in = {b->in[0], b->in[1], roughness};
    const mr_wf_metal_maps out = {b->out[0], b->out[1], roughness};
    if (config->network)
        return mr_wf_spec_to_metal_mlp_batch(mr_transform_options_of(t)->network, &in, b->n, &w, &out, b->flags);
    w.diffuse_quantisation = b->stored[0];
    w.specular_quantisation = b->stored[1];
    return mr_wf_spec_to_metal_batch(&in, b->n, &w, &out, b->flags);
}

static mr_status metal_to_spec_apply(const mr_transform *t, const mr_transform_batch *b) {
    const workflow_config *config = mr_transform_kind_of(t)->config;
    const mr_wf_options w = workflow_options(t, b);
    float *roughness = b->out[2];
    if (roughness != b->in[2]) memcpy(roughness, b->in[2], b->n * sizeof *roughness);
    const mr_wf_metal_input in = {b->in[0], b->in[1], roughness};
    const mr_wf_spec_maps out = {b->out[0], b->out[1], roughness};
    mr_status status = mr_wf_metal_to_spec_batch(&in, b->n, &w, &out, b->flags);
    if (status == MR_OK && config->glossiness) complement(roughness, roughness, b->n);
    return status;
}

/* A value of [0, 1] as the converters read one: clamped, NaN and infinities -> `nonfinite`; flagged. */
static inline float sanitised(float v, float nonfinite, uint8_t *flags) {
    if (!isfinite(v)) {
        *flags |= MR_WF_NONFINITE_INPUT;
        return nonfinite;
    }
    if (v < 0.0f || v > 1.0f) {
        *flags |= MR_WF_CLAMPED_INPUT;
        return v < 0.0f ? 0.0f : 1.0f;
    }
    return v;
}

/* The extension route: nothing converted, values moved (and sanitised like every converter's inputs). */
static mr_status extension_apply(const mr_transform *t, const mr_transform_batch *b) {
    (void)t;
    for (size_t i = 0; i < b->n; i++) {
        uint8_t f = 0;
        for (int c = 0; c < 3; c++) {
            b->out[0][3 * i + c] = sanitised(b->in[0][3 * i + c], 0.0f, &f);
            b->out[4][3 * i + c] = sanitised(b->in[1][3 * i + c], 0.0f, &f);
        }
        b->out[1][i] = 0.0f;
        b->out[2][i] = 1.0f - sanitised(b->in[2][i], 0.0f, &f);
        b->out[3][i] = 1.0f;
        b->out[5][i] = 1000.0f;
        b->flags[i] = f;
    }
    return MR_OK;
}

/* ---- descriptors -------------------------------------------------------------------------------------------- */

#define COUNT(a) (int)(sizeof(a) / sizeof(a)[0])

#define KIND(var, kname, summary, src, dst, in, out, flags, apply, ...)                                              \
    static const workflow_config var##_config = {__VA_ARGS__};                                                     \
    const mr_transform_kind var = {kname, summary, src, dst, COUNT(in), in, COUNT(out), out, flags, &var##_config, \
                                   workflow_create, NULL, apply}

#define ANALYTIC (MR_TRANSFORM_PER_TEXEL | MR_TRANSFORM_TOLERANCES | MR_TRANSFORM_USES_F0)
#define CLOSED_FORM (MR_TRANSFORM_PER_TEXEL | MR_TRANSFORM_USES_F0)
#define GLTF_CONVENTION MR_TRANSFORM_CONVENTION /* glTF-pair kinds that read the diffuse (Khronos has its own) */

KIND(mr_transform_spec2metal_weighted, "weighted",
     "Eq. 3 per channel, the albedo-weighted mean metallic (paper section 8, strategy 2)", "gltf-specgloss", "gltf",
     gltf_spec_in, gltf_metal_out, ANALYTIC | GLTF_CONVENTION, spec_to_metal_apply, 1, MR_WF_WEIGHTED,
     MR_WF_DIFFUSE_SPECGLOSS, 0, 1);
KIND(mr_transform_spec2metal_mlp, "mlp", "the learned network (data/spec2metal.mlp, docs/training.md)",
     "gltf-specgloss", "gltf", gltf_spec_in, gltf_metal_out, MR_TRANSFORM_NEEDS_NETWORK | GLTF_CONVENTION,
     spec_to_metal_apply, 1, MR_WF_WEIGHTED, MR_WF_DIFFUSE_SPECGLOSS, 1, 1);
KIND(mr_transform_spec2metal_mean, "mean", "Eq. 3 per channel, the mean metallic (paper section 8, strategy 1)",
     "gltf-specgloss", "gltf", gltf_spec_in, gltf_metal_out, ANALYTIC | GLTF_CONVENTION, spec_to_metal_apply, 1,
     MR_WF_MEAN, MR_WF_DIFFUSE_SPECGLOSS, 0, 1);
KIND(mr_transform_spec2metal_khronos, "khronos",
     "the glTF project's converter (three.pbrUtilities.js): perceived brightness, F0 0.04", "gltf-specgloss", "gltf",
     gltf_spec_in, gltf_metal_out, ANALYTIC, spec_to_metal_apply, 1, MR_WF_KHRONOS, MR_WF_DIFFUSE_SPECGLOSS, 0, 1);
KIND(mr_transform_spec2metal_extension, "extension",
     "lossless: diffuse as base colour (metallic 0), specular as KHR_materials_specular's colour, ior 1000",
     "gltf-specgloss", "gltf", gltf_spec_in, extension_out, MR_TRANSFORM_PER_TEXEL, extension_apply, 1,
     MR_WF_WEIGHTED, MR_WF_DIFFUSE_SPECGLOSS, 0, 1);
KIND(mr_transform_metal2spec_eq2, "eq2", "paper Eq. 2, exact", "gltf", "gltf-specgloss", gltf_metal_in,
     gltf_spec_out, CLOSED_FORM | GLTF_CONVENTION, metal_to_spec_apply, 0, MR_WF_WEIGHTED, MR_WF_DIFFUSE_SPECGLOSS,
     0, 1);
KIND(mr_transform_metal2spec_khronos, "khronos", "the glTF project's converter (three.pbrUtilities.js), F0 0.04",
     "gltf", "gltf-specgloss", gltf_metal_in, gltf_spec_out, CLOSED_FORM, metal_to_spec_apply, 0, MR_WF_KHRONOS,
     MR_WF_DIFFUSE_SPECGLOSS, 0, 1);
KIND(mr_transform_paper_spec2metal_weighted, "weighted",
     "Eq. 3 per channel, the albedo-weighted mean metallic (paper section 8, strategy 2)", "ggx", "ggx-metallic",
     paper_spec_in, paper_metal_out, ANALYTIC, spec_to_metal_apply, 1, MR_WF_WEIGHTED, MR_WF_DIFFUSE_PLAIN, 0, 0);
KIND(mr_transform_paper_spec2metal_mlp, "mlp", "the learned network (data/spec2metal.mlp, docs/training.md)", "ggx",
     "ggx-metallic", paper_spec_in, paper_metal_out, MR_TRANSFORM_NEEDS_NETWORK, spec_to_metal_apply, 1,
     MR_WF_WEIGHTED, MR_WF_DIFFUSE_PLAIN, 1, 0);
KIND(mr_transform_paper_spec2metal_mean, "mean", "Eq. 3 per channel, the mean metallic (paper section 8, strategy 1)",
     "ggx", "ggx-metallic", paper_spec_in, paper_metal_out, ANALYTIC, spec_to_metal_apply, 1, MR_WF_MEAN,
     MR_WF_DIFFUSE_PLAIN, 0, 0);
KIND(mr_transform_paper_metal2spec_eq2, "eq2", "paper Eq. 2 as printed, exact", "ggx-metallic", "ggx",
     paper_metal_in, paper_spec_out, CLOSED_FORM, metal_to_spec_apply, 0, MR_WF_WEIGHTED, MR_WF_DIFFUSE_PLAIN, 0, 0);
