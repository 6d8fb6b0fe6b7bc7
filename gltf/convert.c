/*
 * convert.c — a glTF asset's materials converted between the PBR workflows through a transform (contract in
 * mr_gltf_convert.h). Per material: read the source textures, then, band of rows by band of rows, factors x texels
 * into the transform's input planes, the transform, and its outputs packed into the target's 8-bit textures; the
 * textures encoded in memory (PNG) and added to the asset.
 */
#define _DEFAULT_SOURCE /* mkstemps */
#include "gltf/mr_gltf_convert.h"

#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "io/png_texture.h"
#include "mr_internal.h"

/* Texels per band: the band's planes (about 20 floats a texel) stay within a few MB. */
#define BAND_TEXELS 131072

/* Where an input plane comes from: channels [first, first + count) of source texture `texture` (0 or 1), times
 * factors; a missing texture reads 1 (and a missing alpha channel 1). */
typedef struct input_source {
    int texture, first, count;
} input_source;

/* One workflow side as glTF stores it. */
typedef struct workflow_side {
    const char *model;               /* the transform's model name */
    const char *texture_names[2];    /* new images' names */
    mr_img_encoding encodings[2];    /* how the two textures are read and written */
    input_source inputs[3];          /* the model's three slots, in the transform's order */
    const char *slots[2][4];         /* per texture, per channel: the slot written there; "" = 0, "alpha" */
} workflow_side;

static const workflow_side specgloss_side = {
    "gltf-specgloss",
    {"diffuse", "specularGlossiness"},
    {MR_IMG_COLOR, MR_IMG_COLOR},
    {{0, 0, 3}, {1, 0, 3}, {1, 3, 1}},
    {{"diffuse", "diffuse", "diffuse", "alpha"}, {"specular", "specular", "specular", "glossiness"}},
};

static const workflow_side metalrough_side = {
    "gltf",
    {"basecolor", "metallicRoughness"},
    {MR_IMG_COLOR, MR_IMG_DATA},
    {{0, 0, 3}, {1, 2, 1}, {1, 1, 1}},
    {{"base_color", "base_color", "base_color", "alpha"}, {"", "roughness", "metallic", NULL}},
};

/* A material's sources: the two textures and the factors of the three inputs and alpha. */
typedef struct sources {
    mr_gltf_texture_ref refs[2];
    double factors[3][3]; /* per input, per channel */
    double alpha_factor;
    int images[2];        /* image indices, -1 = none (with the samplers and mapping: what decides that two
                             materials share a conversion) */
    int samplers[2];      /* sampler indices, -1 = none */
    mr_gltf_sampler sampler_params[2];
} sources;

static void sources_of(const mr_gltf_material *m, int to_metal, sources *s) {
    memset(s, 0, sizeof *s);
    if (to_metal) {
        s->refs[0] = m->diffuse_texture;
        s->refs[1] = m->specular_glossiness_texture;
        for (int c = 0; c < 3; c++) {
            s->factors[0][c] = m->diffuse_factor[c];
            s->factors[1][c] = m->specular_factor[c];
        }
        s->factors[2][0] = m->glossiness_factor;
        s->alpha_factor = m->diffuse_factor[3];
    } else {
        s->refs[0] = m->base_color_texture;
        s->refs[1] = m->metallic_roughness_texture;
        for (int c = 0; c < 3; c++) s->factors[0][c] = m->base_color_factor[c];
        s->factors[1][0] = m->metallic_factor;
        s->factors[2][0] = m->roughness_factor;
        s->alpha_factor = m->base_color_factor[3];
    }
}

/* The textures a conversion made, for materials with the same sources. */
typedef struct made {
    sources key;
    int textures[2]; /* -1 = none made */
    int has_alpha;
    double values[3 * MR_TRANSFORM_MAX_SLOTS]; /* the outputs where they are one value: factors-only conversions
                                                  (the one texel), and the slots of a uniform texture */
    double alpha;                              /* the alpha of a uniform first texture */
    mr_gltf_material_report report;
    int extension_done;                        /* the specular extension solved: its texture (-1 none), factor */
    int extension_texture;
    double extension_factor[3];
    mr_gltf_material_report extension;         /* its counts (the extension fields) */
} made;

/* Two texture references map texels to the surface the same way. */
static int same_mapping(const mr_gltf_texture_ref *a, const mr_gltf_texture_ref *b) {
    return a->tex_coord == b->tex_coord && a->has_transform == b->has_transform &&
           (!a->has_transform || (a->offset[0] == b->offset[0] && a->offset[1] == b->offset[1] &&
                                  a->rotation == b->rotation && a->scale[0] == b->scale[0] &&
                                  a->scale[1] == b->scale[1] && a->transform_tex_coord == b->transform_tex_coord));
}

static int same_sources(const sources *a, const sources *b) {
    if (a->images[0] != b->images[0] || a->images[1] != b->images[1] || a->alpha_factor != b->alpha_factor)
        return 0;
    for (int t = 0; t < 2; t++)
        if ((a->samplers[t] < 0) != (b->samplers[t] < 0) ||
            memcmp(&a->sampler_params[t], &b->sampler_params[t], sizeof a->sampler_params[t]) != 0)
            return 0;
    for (int i = 0; i < 3; i++)
        for (int c = 0; c < 3; c++)
            if (a->factors[i][c] != b->factors[i][c]) return 0;
    return same_mapping(&a->refs[0], &b->refs[0]) && same_mapping(&a->refs[1], &b->refs[1]);
}

/* Channel c of `im` at texel (x, y) of a width x height grid, bilinear when the sizes differ (texel centres
 * aligned, clamped at the edges); a grey image answers every colour channel, a missing alpha is 1. */
static float sample(const mr_image *im, int c, int x, int y, int width, int height) {
    if (c == 3 && im->channels != 4) return 1.0f;
    int channel = im->channels < 3 ? 0 : c;
    if (im->width == width && im->height == height) return mr_image_at(im, x, y)[channel];
    double u = (x + 0.5) * im->width / width - 0.5, v = (y + 0.5) * im->height / height - 0.5;
    int x0 = (int)floor(u), y0 = (int)floor(v);
    double fx = u - x0, fy = v - y0;
    int xa = x0 < 0 ? 0 : x0 >= im->width ? im->width - 1 : x0, xb = x0 + 1 >= im->width ? im->width - 1 : x0 + 1;
    int ya = y0 < 0 ? 0 : y0 >= im->height ? im->height - 1 : y0, yb = y0 + 1 >= im->height ? im->height - 1 : y0 + 1;
    double top = mr_image_at(im, xa, ya)[channel] * (1 - fx) + mr_image_at(im, xb, ya)[channel] * fx;
    double bottom = mr_image_at(im, xa, yb)[channel] * (1 - fx) + mr_image_at(im, xb, yb)[channel] * fx;
    return (float)(top * (1 - fy) + bottom * fy);
}

/* ---- one conversion ----------------------------------------------------------------------------------------- */

typedef struct conversion {
    mr_gltf *asset;
    const mr_gltf_convert_options *opts;
    const mr_transform_kind *kind;
    const workflow_side *from, *to;
    int material;
    const char *name;
} conversion;

/* Where output slot `name` of the kind goes, or -1. */
static int output_of(const mr_transform_kind *kind, const char *name) {
    return name && name[0] && strcmp(name, "alpha") != 0 ? mr_transform_output_index(kind, name) : -1;
}

/* Does texture t of the target side hold a computed output (not a constant, not a copy of an input)? */
static int texture_needed(const mr_transform_kind *kind, const workflow_side *to, int t) {
    for (int c = 0; c < 4; c++) {
        int j = output_of(kind, to->slots[t][c]);
        if (j >= 0 && !(kind->outputs[j].flags & MR_SLOT_CONSTANT) && kind->outputs[j].copy_of < 0) return 1;
    }
    return 0;
}

/* Where channel c of target texture t comes from: the source's alpha, channel `offset` of output slot `output`
 * (`stride` channels), or one value (0 for an unused channel; a constant slot's texel, 1, or 0 for 0, since its
 * factor holds the constant: the texture alone still reads right); `colour`: written sRGB-encoded. `value_index`
 * is its place among the output channels then alpha (what uniformity is tracked over). */
typedef struct channel_source {
    int alpha, output, constant, colour, value_index;
    size_t stride, offset;
    float value;
} channel_source;

static channel_source channel_source_of(const mr_transform_kind *kind, const workflow_side *to, int t, int c) {
    channel_source src = {0, -1, 0, to->encodings[t] == MR_IMG_COLOR && c < 3, 0, 1, 0, 0.0f};
    const char *slot = to->slots[t][c];
    for (int k = 0; k < kind->output_count; k++) src.value_index += kind->outputs[k].channels; // alpha's place
    if (slot != NULL && strcmp(slot, "alpha") == 0) {
        src.alpha = 1;
        return src;
    }
    const int j = output_of(kind, slot);
    if (j < 0) return src;
    src.output = j;
    src.stride = (size_t)kind->outputs[j].channels;
    src.offset = src.stride == 3 ? (size_t)c : 0;
    src.value_index = (int)src.offset;
    for (int k = 0; k < j; k++) src.value_index += kind->outputs[k].channels;
    if (kind->outputs[j].flags & MR_SLOT_CONSTANT) {
        src.constant = 1;
        src.value = kind->outputs[j].value == 0.0 ? 0.0f : 1.0f;
    }
    return src;
}

/* The value channel source `src` gives texel i, from the outputs `out` and the alpha plane. */
static inline float channel_value(const channel_source *src, float *const *out, const float *alpha, size_t i) {
    if (src->alpha) return alpha[i];
    if (src->output < 0 || src->constant) return src->value;
    return out[src->output][src->stride * i + src->offset];
}

static inline uint8_t linear8(float v) { return (uint8_t)floor(mr_clampd(v, 0.0, 1.0) * 255.0 + 0.5); }

/* The 8-bit code a target texture stores for v: sRGB for a colour texture's RGB, linear otherwise. */
static inline uint8_t code_of(float v, int colour) { return colour ? mr_srgb8_encode(v) : linear8(v); }

/* Which target textures hold computed outputs (need) and their channel counts (RGB, or RGBA where the 4th channel
 * is used: alpha only when some texel has it). */
static void plan_textures(const mr_transform_kind *kind, const workflow_side *to, int has_alpha, int need[2],
                          int channels[2]) {
    for (int t = 0; t < 2; t++) {
        need[t] = texture_needed(kind, to, t);
        channels[t] = to->slots[t][3] == NULL || (strcmp(to->slots[t][3], "alpha") == 0 && !has_alpha) ? 3 : 4;
    }
}

static void count_flags(mr_gltf_material_report *r, const uint8_t *flags, size_t n) {
    static const unsigned reasons[5] = {0xFFu, MR_WF_OFF_MANIFOLD, MR_WF_NONFINITE_INPUT, MR_WF_CLAMPED_INPUT,
                                        MR_WF_METHOD_FAILED};
    size_t counts[5];
    mr_flags_count(flags, n, reasons, 5, counts); // transform.h: the one way flags are counted
    r->flagged += counts[0];
    r->off_manifold += counts[1];
    r->nonfinite += counts[2];
    r->clamped += counts[3];
    r->failed += counts[4];
}

/* A new texture, encoded: PNG bytes in memory, or an EXR in a temporary file. */
typedef struct encoded_texture {
    char uri[512];
    unsigned char *bytes;
    size_t size;
    char path[1024]; /* "" for PNG */
} encoded_texture;

/* Threads for a material's two textures handled side by side (read, decoded, encoded): two when there are two and
 * the caller's thread count allows it (the transform's threads option; 0 = OpenMP's default, which
 * OMP_NUM_THREADS sets), else one: a pair must never open a thread the caller did not grant. */
static int pair_team(const conversion *cv, int both) {
    if (!both) return 1;
    return MR_MIN(2, mr_auto_threads(mr_transform_options_of(cv->opts->transform)->threads, 1, 1));
}

/* New images are named PREFIX_mK_NAME.EXT (K the material, NAME the target texture's). */
static void texture_uri(const conversion *cv, int t, const char *extension, encoded_texture *e) {
    const char *prefix = cv->opts->image_prefix ? cv->opts->image_prefix : "converted";
    snprintf(e->uri, sizeof e->uri, "%s_m%d_%s.%s", prefix, cv->material, cv->to->texture_names[t], extension);
}

/* Encode texture t (PNG from 8-bit texels, or EXR from floats); touches nothing shared, so textures encode in
 * parallel. */
static mr_status encode_texture(const conversion *cv, int t, int width, int height, int channels,
                                const uint8_t *bytes8, const float *floats, encoded_texture *e) {
    texture_uri(cv, t, floats ? "exr" : "png", e);
    if (floats == NULL) {
        const mr_io_png_settings settings = MR_IO_PNG_DEFAULT;
        return mr_io_png_encode(e->uri, width, height, channels, 8, bytes8, cv->to->encodings[t] == MR_IMG_COLOR,
                                &settings, &e->bytes, &e->size);
    }
    // EXR through a private temporary file (the writer is OpenEXR Core's, to a path), its name made by mkstemps.
    mr_image im = {width, height, channels, (float *)floats};
    const char *dir = getenv("TMPDIR");
    snprintf(e->path, sizeof e->path, "%s/matremap-texture-XXXXXX.exr", dir && dir[0] ? dir : "/tmp");
    const int fd = mkstemps(e->path, 4);
    if (fd < 0) {
        mr_status status = mr_fail(MR_ERR_IO, "glTF '%s': material %d: cannot create a temporary file for '%s'",
                                   mr_gltf_path(cv->asset), cv->material, e->uri);
        e->path[0] = '\0';
        return status;
    }
    close(fd);
    mr_img_write_options wo = {0};
    wo.encoding = cv->to->encodings[t];
    return mr_img_write(e->path, &im, &wo);
}

/* Add an encoded texture to the asset (its bytes are copied), with the sampler of texture `like` (-1: none). */
static mr_status add_texture(const conversion *cv, encoded_texture *e, int like, int *texture) {
    int image = -1;
    mr_status status = e->path[0] ? mr_gltf_add_image_file(cv->asset, e->path, e->uri, &image)
                                  : mr_gltf_add_image_bytes(cv->asset, e->bytes, e->size, e->uri, &image);
    mr_gltf_sampler sampler, *sampler_ptr = NULL;
    mr_gltf_texture source;
    if (like >= 0 && mr_gltf_get_texture(cv->asset, like, &source) == MR_OK && source.sampler >= 0) {
        sampler = source.params;
        sampler_ptr = &sampler;
    }
    if (status == MR_OK) status = mr_gltf_add_texture(cv->asset, image, sampler_ptr, texture);
    if (status != MR_OK)
        mr_fail_context(status, "glTF '%s': material %d '%s': new texture '%s'", mr_gltf_path(cv->asset), cv->material,
                        cv->name, e->uri);
    return status;
}

static void encoded_texture_release(encoded_texture *e) {
    free(e->bytes);
    e->bytes = NULL;
    if (e->path[0]) remove(e->path);
    e->path[0] = '\0';
}

/* What every band of one conversion shares. */
typedef struct band_context {
    const conversion *cv;
    const sources *src;
    mr_image *const *images;   /* decoded textures (NULL: none, or read as codes) */
    const mr_io_codes *codes;  /* [2] 8-bit textures read undecoded (codes NULL: none) */
    const float *luts[2];      /* a code's value as the reader decodes it: [0] data and alpha, [1] sRGB colour */
    const mr_img_stored *stored;
    int width, height, band_rows;
    const int *need, *channels;
    void *const *texels;
    int exr;
    int values;       /* output channels, then alpha: what uniformity is tracked for */
    float *firsts;    /* [band][values]: the band's first texel */
    uint8_t *uniform; /* [band][values]: 1 when every texel of the band has its first texel's value */
} band_context;

/* One thread's planes for a band: alpha, then the transform's inputs and outputs. */
typedef struct band_work {
    float *planes;
    uint8_t *flags;
    mr_transform_batch batch;
} band_work;

static mr_status band_work_alloc(const mr_transform_kind *kind, size_t band, band_work *w) {
    memset(w, 0, sizeof *w);
    size_t floats = 1;
    for (int i = 0; i < kind->input_count; i++) floats += (size_t)kind->inputs[i].channels;
    for (int j = 0; j < kind->output_count; j++) floats += (size_t)kind->outputs[j].channels;
    w->planes = malloc(band * floats * sizeof *w->planes);
    w->flags = malloc(band);
    if (w->planes == NULL || w->flags == NULL) return MR_ERR_NOMEM;
    float *p = w->planes + band;
    for (int i = 0; i < kind->input_count; i++) {
        w->batch.in[i] = p;
        p += band * (size_t)kind->inputs[i].channels;
    }
    for (int j = 0; j < kind->output_count; j++) {
        w->batch.out[j] = p;
        p += band * (size_t)kind->outputs[j].channels;
    }
    w->batch.flags = w->flags;
    w->batch.threads = 1;
    return MR_OK;
}

static void band_work_free(band_work *w) {
    free(w->planes);
    free(w->flags);
}

/* Rows [y0, y0 + band_rows) of the grid: inputs, transform, packed outputs. */
static mr_status convert_band(const band_context *ctx, int y0, band_work *w, mr_gltf_material_report *counts) {
    const conversion *cv = ctx->cv;
    const mr_transform_kind *kind = cv->kind;
    const workflow_side *from = cv->from, *to = cv->to;
    const int width = ctx->width, height = ctx->height;
    const int rows = height - y0 < ctx->band_rows ? height - y0 : ctx->band_rows;
    mr_transform_batch b = w->batch;
    b.n = (size_t)rows * (size_t)width;
    for (int i = 0; i < kind->input_count && !cv->opts->exact_inputs; i++) {
        int tex = from->inputs[i].texture;
        const int present = ctx->images[tex] != NULL || ctx->codes[tex].codes != NULL;
        b.stored[i] = mr_wf_quantisation_of(present ? &ctx->stored[tex] : NULL, ctx->src->factors[i]);
    }
    // 1. Inputs: factors x texels, in linear values (glTF multiplies them so); the alpha plane first.
    for (int i = -1; i < kind->input_count; i++) {
        const input_source alpha_source = {0, 3, 1};
        const input_source *in = i < 0 ? &alpha_source : &from->inputs[i];
        const double *factors = i < 0 ? &ctx->src->alpha_factor : ctx->src->factors[i];
        const mr_image *im = ctx->images[in->texture];
        const mr_io_codes *codes = &ctx->codes[in->texture];
        float *dst = i < 0 ? w->planes : (float *)b.in[i];
        if (codes->codes != NULL) { // 8-bit samples through the reader's decode, by table (the same floats)
            const size_t ch = (size_t)codes->channels;
            const uint8_t *px = codes->codes + (size_t)y0 * (size_t)width * ch;
            int at[3];
            const float *lut[3];
            for (int c = 0; c < in->count; c++) {
                const int channel = in->first + c, has_alpha = ch == 2 || ch == 4;
                at[c] = channel == 3 ? (has_alpha ? (int)ch - 1 : -1) : ch < 3 ? 0 : channel;
                lut[c] = ctx->luts[channel < 3 && ctx->cv->from->encodings[in->texture] == MR_IMG_COLOR];
            }
            for (size_t k = 0; k < b.n; k++, px += ch)
                for (int c = 0; c < in->count; c++)
                    *dst++ = (float)((at[c] < 0 ? 1.0f : lut[c][px[at[c]]]) * factors[c]);
            continue;
        }
        if (im != NULL && im->width == width && im->height == height) { // the common case, without per-value tests
            const size_t ch = (size_t)im->channels;
            const float *px = im->pixels + (size_t)y0 * (size_t)width * ch;
            int at[3]; // per channel, the pixel's value read (-1: a missing alpha, 1)
            for (int c = 0; c < in->count; c++) {
                const int channel = in->first + c;
                at[c] = channel == 3 ? (ch == 4 ? 3 : -1) : ch < 3 ? 0 : channel;
            }
            for (size_t k = 0; k < b.n; k++, px += ch)
                for (int c = 0; c < in->count; c++)
                    *dst++ = (float)((at[c] < 0 ? 1.0f : px[at[c]]) * factors[c]);
            continue;
        }
        for (int y = 0; y < rows; y++)
            for (int x = 0; x < width; x++)
                for (int c = 0; c < in->count; c++) {
                    float v = im == NULL ? 1.0f : sample(im, in->first + c, x, y0 + y, width, height);
                    *dst++ = (float)(v * factors[c]);
                }
    }
    // 2. The transform.
    mr_status status = mr_transform_apply(cv->opts->transform, &b);
    if (status != MR_OK) return status;
    count_flags(counts, b.flags, b.n);
    // Uniformity (a texture whose texels are all one value becomes factors): per output channel and alpha.
    float *first = ctx->firsts + (size_t)(y0 / ctx->band_rows) * (size_t)ctx->values;
    uint8_t *uniform = ctx->uniform + (size_t)(y0 / ctx->band_rows) * (size_t)ctx->values;
    for (int j = 0, v = 0; j <= kind->output_count; j++) {
        const int ch = j < kind->output_count ? kind->outputs[j].channels : 1;
        const float *plane = j < kind->output_count ? b.out[j] : w->planes;
        for (int c = 0; c < ch; c++, v++) {
            first[v] = plane[c];
            uniform[v] = 1;
            for (size_t i = 1; i < b.n && uniform[v]; i++)
                uniform[v] = memcmp(&plane[(size_t)ch * i + (size_t)c], &first[v], sizeof first[v]) == 0;
        }
    }
    // 3. Its outputs packed as glTF packs them.
    for (int t = 0; t < 2; t++) {
        if (!ctx->need[t]) continue;
        const size_t ch = (size_t)ctx->channels[t], first = (size_t)y0 * (size_t)width * ch;
        for (size_t c = 0; c < ch; c++) {
            // The source as a plane and stride (or one value), resolved once: this loop runs per texel.
            const channel_source src = channel_source_of(kind, to, t, (int)c);
            const float *plane = src.alpha ? w->planes
                                 : src.output >= 0 && !src.constant ? b.out[src.output] + src.offset : NULL;
            const size_t stride = src.alpha ? 1 : src.stride;
            if (ctx->exr) {
                float *out = (float *)ctx->texels[t] + first + c;
                for (size_t i = 0; i < b.n; i++) out[ch * i] = plane ? plane[stride * i] : src.value;
            } else {
                uint8_t *out = (uint8_t *)ctx->texels[t] + first + c;
                for (size_t i = 0; i < b.n; i++)
                    out[ch * i] = code_of(plane ? plane[stride * i] : src.value, src.colour);
            }
        }
    }
    return MR_OK;
}

/* Which values are one value everywhere: uniform[v] over the output channels, then alpha (last). A target texture
 * whose every channel is uniform (or constant, or 0) is not needed: its slots become factors (mk->values). */
static void drop_uniform_textures(const mr_transform_kind *kind, const workflow_side *to, const int channels[2],
                                  const uint8_t *uniform, int need[2]) {
    for (int t = 0; t < 2; t++) {
        int all_uniform = need[t];
        for (int c = 0; c < channels[t] && all_uniform; c++) {
            const channel_source src = channel_source_of(kind, to, t, c);
            if (src.alpha || (src.output >= 0 && !src.constant)) all_uniform = uniform[src.value_index];
        }
        if (all_uniform) need[t] = 0; // its mk->textures[t] stays -1: set_outputs writes mk->values
    }
}

/* Band by band: factors x texels into the input planes, the transform, its outputs into the target's textures
 * (8-bit, or floats for EXR). images[t] NULL = no texture t. */
static mr_status convert_texels(const conversion *cv, const sources *src, mr_image *const images[2],
                                const mr_io_codes codes[2], const mr_img_stored stored[2], int width, int height,
                                made *mk) {
    const mr_transform_kind *kind = cv->kind;
    const workflow_side *to = cv->to;
    const int exr = cv->opts->image_format != NULL && strcmp(cv->opts->image_format, "exr") == 0;
    const size_t n = (size_t)width * (size_t)height;
    // Alpha travels from the source's first texture to the target's (written only when some texel has it; bilinear
    // resampling of alphas that are all 1 gives 1).
    const mr_image *first = images[0];
    float luts[2][256];
    for (unsigned q = 0; q < 256; q++) {
        luts[0][q] = mr_io_decode_code(q, 8, 0);
        luts[1][q] = mr_io_decode_code(q, 8, 1);
    }
    mk->has_alpha = (float)src->alpha_factor != 1.0f;
    for (size_t i = 0; first && first->channels == 4 && !mk->has_alpha && i < mr_image_value_count(first) / 4; i++)
        mk->has_alpha = (float)(first->pixels[4 * i + 3] * src->alpha_factor) != 1.0f;
    const int coded_alpha = codes[0].codes != NULL && (codes[0].channels == 2 || codes[0].channels == 4);
    for (size_t i = 0; coded_alpha && !mk->has_alpha && i < (size_t)width * (size_t)height; i++) {
        const uint8_t alpha = codes[0].codes[i * (size_t)codes[0].channels + (size_t)codes[0].channels - 1];
        mk->has_alpha = (float)(luts[0][alpha] * src->alpha_factor) != 1.0f;
    }
    int need[2], channels[2];
    void *texels[2] = {NULL, NULL};
    mr_status status = MR_OK;
    plan_textures(kind, to, mk->has_alpha, need, channels);
    for (int t = 0; t < 2; t++)
        if (need[t] && (texels[t] = malloc(n * (size_t)channels[t] * (exr ? sizeof(float) : 1))) == NULL)
            status = MR_ERR_NOMEM;
    // Bands of rows, side by side: each thread its own planes; the transform runs on one thread per band.
    const int band_rows = width >= BAND_TEXELS ? 1 : BAND_TEXELS / width;
    const int bands = (height + band_rows - 1) / band_rows;
    const int requested = mr_transform_options_of(cv->opts->transform)->threads;
    const int threads = mr_auto_threads(requested, (long)MR_MIN(n, 1u << 30), MR_WF_PARALLEL_TEXELS);
    const int team = MR_MIN(threads, bands);
    char message[1024] = "";
    band_context ctx = {cv,    src,        images,   codes,    {luts[0], luts[1]}, stored, width, height,
                        band_rows, need, channels, texels, exr,    1,     NULL,   NULL};
    for (int j = 0; j < kind->output_count; j++) ctx.values += kind->outputs[j].channels;
    ctx.firsts = malloc((size_t)bands * (size_t)ctx.values * sizeof *ctx.firsts);
    ctx.uniform = malloc((size_t)bands * (size_t)ctx.values);
    if (ctx.firsts == NULL || ctx.uniform == NULL) status = MR_ERR_NOMEM;
    if (status == MR_OK) mr_srgb8_init();
#pragma omp parallel num_threads(team) if (team > 1)
    {
        band_work w;
        memset(&w, 0, sizeof w); // freed below even when an earlier failure kept it from being allocated
        mr_status mine = status == MR_OK ? band_work_alloc(cv->kind, (size_t)band_rows * (size_t)width, &w)
                                         : MR_ERR_NOMEM;
        mr_gltf_material_report counts;
        memset(&counts, 0, sizeof counts);
#pragma omp for schedule(dynamic, 1)
        for (int k = 0; k < bands; k++)
            if (mine == MR_OK) mine = convert_band(&ctx, k * band_rows, &w, &counts);
        band_work_free(&w);
#pragma omp critical(mr_gltf_convert_band)
        {
            mk->report.flagged += counts.flagged;
            mk->report.off_manifold += counts.off_manifold;
            mk->report.nonfinite += counts.nonfinite;
            mk->report.clamped += counts.clamped;
            mk->report.failed += counts.failed;
            if (mine != MR_OK && status == MR_OK) {
                status = mine;
                snprintf(message, sizeof message, "%s", mine == MR_ERR_NOMEM ? "out of memory" : mr_last_error());
            }
        }
    }
    if (status == MR_ERR_NOMEM)
        status = mr_fail(status, "glTF '%s': material %d '%s': out of memory for %dx%d texels", mr_gltf_path(cv->asset),
                         cv->material, cv->name, width, height);
    else if (status != MR_OK)
        status = mr_fail(status, "%s", message);
    // Textures whose every channel is one value everywhere become factors (a constant roughness beside a diffuse
    // texture, say): no image, and exactly the converted value.
    for (int v = 0; status == MR_OK && v < ctx.values; v++) {
        int one = 1;
        for (int k = 0; k < bands && one; k++)
            one = ctx.uniform[(size_t)k * (size_t)ctx.values + (size_t)v] &&
                  memcmp(&ctx.firsts[(size_t)k * (size_t)ctx.values + (size_t)v], &ctx.firsts[v], sizeof(float)) == 0;
        ctx.uniform[v] = (uint8_t)one;
        if (v < ctx.values - 1)
            mk->values[v] = ctx.firsts[v];
        else
            mk->alpha = ctx.firsts[v];
    }
    if (status == MR_OK) drop_uniform_textures(kind, to, channels, ctx.uniform, need);
    free(ctx.firsts);
    free(ctx.uniform);
    // 4. The textures, encoded side by side (each its own thread's last error).
    mr_status statuses[2] = {MR_OK, MR_OK};
    char messages[2][1024] = {"", ""};
    encoded_texture encoded[2];
    memset(encoded, 0, sizeof encoded);
    if (status == MR_OK) {
        const int pair = pair_team(cv, need[0] && need[1]);
#pragma omp parallel for schedule(static, 1) num_threads(pair) if (pair > 1)
        for (int t = 0; t < 2; t++) {
            if (!need[t]) continue;
            statuses[t] = encode_texture(cv, t, width, height, channels[t], exr ? NULL : texels[t],
                                         exr ? texels[t] : NULL, &encoded[t]);
            if (statuses[t] != MR_OK) snprintf(messages[t], sizeof messages[t], "%s", mr_last_error());
        }
        for (int t = 0; t < 2 && status == MR_OK; t++)
            if (statuses[t] != MR_OK) status = mr_fail(statuses[t], "%s", messages[t]);
        for (int t = 0; t < 2 && status == MR_OK; t++)
            if (need[t]) // the sampler of the source texture in the same place, else of the other one
                status = add_texture(cv, &encoded[t], src->refs[src->refs[t].index >= 0 ? t : 1 - t].index,
                                     &mk->textures[t]);
    }
    for (int t = 0; t < 2; t++) {
        encoded_texture_release(&encoded[t]);
        free(texels[t]);
    }
    return status;
}

/* A paletted PNG source converts by converting its palette (png_texture.h, "Paletted PNG"): when it is the material's
 * only texture (the other inputs factors), every texel of one index gets one answer, so each target texture is the
 * same index stream under a converted palette; no texel is decoded, filtered or deflated, and the answers are those
 * of the texel-by-texel path (the same decoded values through the same transform, the same 8-bit codes). Returns
 * 0 when the material does not qualify (then nothing is changed), else 1 with *status set. */
static int convert_palette(const conversion *cv, const sources *src, made *mk, mr_status *status) {
    const int t = src->refs[0].index >= 0 ? 0 : 1;
    mr_gltf_image im;
    const int exr = cv->opts->image_format != NULL && strcmp(cv->opts->image_format, "exr") == 0;
    if (exr || src->refs[1 - t].index >= 0 || src->images[t] < 0 ||
        mr_gltf_get_image(cv->asset, src->images[t], &im) != MR_OK || !mr_io_png_is_paletted(im.bytes, im.size))
        return 0;
    const mr_transform_kind *kind = cv->kind;
    const workflow_side *from = cv->from, *to = cv->to;
    char label[600];
    snprintf(label, sizeof label, "glTF '%s': image %d", mr_gltf_path(cv->asset), src->images[t]);
    mr_io_png_palette p;
    if ((*status = mr_io_png_palette_read(im.bytes, im.size, label, &p)) != MR_OK) return 1;
    // The entries as the reader decodes texels (colour channels sRGB-decoded for a colour texture, alpha linear).
    enum { MAX_VALUES = 3 * MR_TRANSFORM_MAX_SLOTS };
    static const mr_wf_quantisation exact = {0, 0, {1.0, 1.0, 1.0}};
    float inputs[MR_TRANSFORM_MAX_SLOTS][3 * 256], outputs[MR_TRANSFORM_MAX_SLOTS][3 * 256], alpha[256];
    uint8_t flags[256];
    mr_transform_batch b = {0};
    b.n = (size_t)p.entries;
    b.flags = flags;
    b.threads = 1;
    const int colour = from->encodings[t] == MR_IMG_COLOR;
    for (int e = 0; e < p.entries; e++)
        alpha[e] = (float)((t == 0 ? mr_io_decode_code(p.alpha[e], 8, 0) : 1.0f) * src->alpha_factor);
    for (int i = 0; i < kind->input_count; i++) {
        const input_source *in = &from->inputs[i];
        for (int e = 0; e < p.entries; e++)
            for (int c = 0; c < in->count; c++) {
                const int channel = in->first + c;
                float v = in->texture != t ? 1.0f
                          : channel < 3    ? mr_io_decode_code(p.rgb[e][channel], 8, colour)
                                           : mr_io_decode_code(p.alpha[e], 8, 0);
                inputs[i][in->count * e + c] = (float)(v * src->factors[i][c]);
            }
        b.in[i] = inputs[i];
        const mr_img_stored stored = {8, from->encodings[t]};
        b.stored[i] = in->texture == t && !cv->opts->exact_inputs ? mr_wf_quantisation_of(&stored, src->factors[i])
                                                                   : exact;
    }
    for (int j = 0; j < kind->output_count; j++) b.out[j] = outputs[j];
    if ((*status = mr_transform_apply(cv->opts->transform, &b)) != MR_OK) {
        mr_io_png_palette_free(&p);
        return 1;
    }
    // Flags and uniformity over the entries the texels use.
    uint8_t uniform[MAX_VALUES + 1];
    int first_used = -1;
    memset(uniform, 1, sizeof uniform);
    mk->has_alpha = 0;
    for (int e = 0; e < p.entries; e++) {
        if (p.counts[e] == 0) continue;
        if (first_used < 0) first_used = e;
        for (size_t k = 0; k < p.counts[e]; k++) count_flags(&mk->report, &flags[e], 1);
        mk->has_alpha |= alpha[e] != 1.0f;
        for (int j = 0, v = 0; j <= kind->output_count; j++) {
            const int ch = j < kind->output_count ? kind->outputs[j].channels : 1;
            const float *plane = j < kind->output_count ? outputs[j] : alpha;
            for (int c = 0; c < ch; c++, v++)
                uniform[v] &= memcmp(&plane[ch * e + c], &plane[ch * first_used + c], sizeof(float)) == 0;
        }
    }
    for (int j = 0, v = 0; j < kind->output_count; j++)
        for (int c = 0; c < kind->outputs[j].channels; c++, v++)
            mk->values[v] = outputs[j][kind->outputs[j].channels * first_used + c];
    mk->alpha = alpha[first_used];
    int need[2], channels[2];
    plan_textures(kind, to, mk->has_alpha, need, channels);
    drop_uniform_textures(kind, to, channels, uniform, need);
    // The target textures: the index stream under the converted palette.
    mr_srgb8_init();
    for (int tt = 0; tt < 2 && *status == MR_OK; tt++) {
        if (!need[tt]) continue;
        unsigned char rgb[256][3], trns[256];
        for (int e = 0; e < p.entries; e++) {
            trns[e] = 255;
            for (int c = 0; c < channels[tt]; c++) {
                const channel_source src = channel_source_of(kind, to, tt, c);
                const unsigned char code = code_of(channel_value(&src, b.out, alpha, (size_t)e), src.colour);
                if (c < 3) rgb[e][c] = code;
                else trns[e] = code;
            }
        }
        encoded_texture e;
        memset(&e, 0, sizeof e);
        texture_uri(cv, tt, "png", &e);
        *status = mr_io_png_palette_write(&p, (const unsigned char(*)[3])rgb, channels[tt] == 4 ? trns : NULL,
                                          to->encodings[tt] == MR_IMG_COLOR, &e.bytes, &e.size);
        if (*status == MR_OK) *status = add_texture(cv, &e, src->refs[t].index, &mk->textures[tt]);
        encoded_texture_release(&e);
    }
    mk->report.width = p.width;
    mk->report.height = p.height;
    mr_io_png_palette_free(&p);
    return 1;
}

/* ---- the material ------------------------------------------------------------------------------------------- */

/* Where an output slot lives in mr_gltf_material: its factor (channels doubles) and texture reference. */
typedef struct material_field {
    const char *slot;
    size_t factor, ref; /* offsetof into mr_gltf_material; ref SIZE_MAX = none */
    int texture;        /* the target side's texture (0 or 1) holding it, -1 = an extension's own texture */
} material_field;

#define FIELD(slot, factor, ref, t) {slot, offsetof(mr_gltf_material, factor), offsetof(mr_gltf_material, ref), t}
static const material_field metalrough_fields[] = {
    FIELD("base_color", base_color_factor, base_color_texture, 0),
    FIELD("metallic", metallic_factor, metallic_roughness_texture, 1),
    FIELD("roughness", roughness_factor, metallic_roughness_texture, 1),
    FIELD("specular", specular_strength, specular_texture, -1),
    FIELD("specular_color", specular_color_factor, specular_color_texture, -1),
    {"ior", offsetof(mr_gltf_material, ior), SIZE_MAX, -1},
};
static const material_field specgloss_fields[] = {
    FIELD("diffuse", diffuse_factor, diffuse_texture, 0),
    FIELD("specular", specular_factor, specular_glossiness_texture, 1),
    FIELD("glossiness", glossiness_factor, specular_glossiness_texture, 1),
};

static const material_field *field_of(const workflow_side *side, const char *slot) {
    const material_field *fields = side == &metalrough_side ? metalrough_fields : specgloss_fields;
    size_t count = side == &metalrough_side ? sizeof metalrough_fields / sizeof *fields
                                            : sizeof specgloss_fields / sizeof *fields;
    for (size_t k = 0; k < count; k++)
        if (strcmp(fields[k].slot, slot) == 0) return &fields[k];
    return NULL;
}

/* Write a conversion's result into material m: per output, a copied source texture and factor, a constant factor, a
 * made texture (factor 1), or (factors only) the value. */
static void set_outputs(const conversion *cv, const sources *src, const made *mk, int textured, mr_gltf_material *m) {
    const mr_transform_kind *kind = cv->kind;
    const mr_gltf_texture_ref mapping = src->refs[src->refs[0].index >= 0 ? 0 : 1];
    size_t value = 0;
    for (int j = 0; j < kind->output_count; value += (size_t)kind->outputs[j].channels, j++) {
        const mr_transform_slot *slot = &kind->outputs[j];
        const material_field *f = field_of(cv->to, slot->name);
        if (f == NULL) continue; // a target parameter glTF does not store
        double *factor = (double *)((char *)m + f->factor);
        mr_gltf_texture_ref *ref = f->ref == SIZE_MAX ? NULL : (mr_gltf_texture_ref *)((char *)m + f->ref);
        const int made_texture = f->texture >= 0 && mk->textures[f->texture] >= 0;
        for (int c = 0; c < slot->channels; c++) {
            if (slot->flags & MR_SLOT_CONSTANT)
                factor[c] = slot->value; // a made texture holds 1 there (0 for 0: channel_source_of)
            else if (slot->copy_of >= 0)
                factor[c] = src->factors[slot->copy_of][c];
            else
                factor[c] = made_texture ? 1.0 : mk->values[value + (size_t)c];
        }
        if (ref == NULL) continue;
        if (made_texture) {
            *ref = mapping;
            ref->index = mk->textures[f->texture];
        } else if (slot->copy_of >= 0) {
            *ref = src->refs[cv->from->inputs[slot->copy_of].texture];
        } else {
            mr_gltf_texture_ref_none(ref);
        }
        // KHR_materials_specular is metal-rough's: the spec-gloss side's "specular" is the extension's own factor.
        if (cv->to == &metalrough_side &&
            (strcmp(slot->name, "specular") == 0 || strcmp(slot->name, "specular_color") == 0))
            m->has_specular = 1;
    }
    if (mr_transform_output_index(kind, "ior") >= 0 && cv->to == &metalrough_side) m->has_ior = 1;
    if (cv->to == &metalrough_side && mr_transform_output_index(kind, "specular_color") >= 0 &&
        mr_transform_output_index(kind, "specular") < 0)
        m->specular_strength = 1.0;
    // Alpha: in the made first texture (factor 1), or the source's alpha factor where the colour was copied.
    double *colour = (double *)((char *)m + field_of(cv->to, cv->to->slots[0][0])->factor);
    const int copied = cv->kind->outputs[0].copy_of >= 0;
    colour[3] = mk->textures[0] >= 0 ? 1.0 : textured && !copied ? mk->alpha : src->alpha_factor;
}

/* The core metal-rough values a material carries of its own (textures, or factors other than glTF's defaults
 * 1,1,1,1 / 1 / 1), named in `list` ("baseColorTexture, metallicFactor"); returns how many. */
static int core_values(const mr_gltf_material *m, char *list, size_t size) {
    const char *names[5];
    int count = 0;
    if (m->base_color_texture.index >= 0) names[count++] = "baseColorTexture";
    if (m->metallic_roughness_texture.index >= 0) names[count++] = "metallicRoughnessTexture";
    if (m->base_color_factor[0] != 1.0 || m->base_color_factor[1] != 1.0 || m->base_color_factor[2] != 1.0 ||
        m->base_color_factor[3] != 1.0)
        names[count++] = "baseColorFactor";
    if (m->metallic_factor != 1.0) names[count++] = "metallicFactor";
    if (m->roughness_factor != 1.0) names[count++] = "roughnessFactor";
    list[0] = '\0';
    for (int k = 0; k < count; k++)
        snprintf(list + strlen(list), size - strlen(list), "%s%s", k ? ", " : "", names[k]);
    return count;
}

/* Read the material's source textures (side by side) and settle the grid: the larger texture's size. */
static mr_status read_sources(const conversion *cv, const sources *src, mr_image *images[2], mr_img_stored stored[2],
                              int *width, int *height) {
    if (src->refs[0].index >= 0 && src->refs[1].index >= 0 && !same_mapping(&src->refs[0], &src->refs[1]))
        return mr_fail(MR_ERR_FORMAT, "glTF '%s': material %d '%s': its two textures map onto the surface differently "
                       "(UV set or KHR_texture_transform), so their texels cannot be converted pairwise",
                       mr_gltf_path(cv->asset), cv->material, cv->name);
    mr_status statuses[2] = {MR_OK, MR_OK};
    char messages[2][1024] = {"", ""};
    const int both = src->refs[0].index >= 0 && src->refs[1].index >= 0;
    const int pair = pair_team(cv, both);
#pragma omp parallel for schedule(static, 1) num_threads(pair) if (pair > 1)
    for (int t = 0; t < 2; t++) {
        if (src->refs[t].index < 0) continue;
        mr_img_read_options ro = {0};
        ro.encoding = cv->from->encodings[t];
        statuses[t] = mr_gltf_texture_read(cv->asset, src->refs[t].index, &ro, &images[t], &stored[t]);
        if (statuses[t] != MR_OK) snprintf(messages[t], sizeof messages[t], "%s", mr_last_error());
    }
    for (int t = 0; t < 2; t++)
        if (statuses[t] != MR_OK)
            return mr_fail(statuses[t], "material %d '%s': %s", cv->material, cv->name, messages[t]);
    *width = *height = 1;
    for (int t = 0; t < 2; t++)
        if (images[t] != NULL) {
            *width = MR_MAX(*width, images[t]->width);
            *height = MR_MAX(*height, images[t]->height);
        }
    return MR_OK;
}

/* The material's textures as 8-bit codes, undecoded (a quarter of the floats' memory; mr_io_png_deflate_read_codes),
 * side by side: when every texture is a non-palette 8-bit PNG and all have one size. Returns 0 (nothing kept) when
 * they are not, else 1 with *status (a decoding failure names the asset, the image and the material). */
static int read_codes(const conversion *cv, const sources *src, mr_io_codes codes[2], mr_img_stored stored[2],
                      int *width, int *height, mr_status *status) {
    mr_gltf_image im[2];
    for (int t = 0; t < 2; t++) {
        if (src->refs[t].index < 0) continue;
        if (src->images[t] < 0 || mr_gltf_get_image(cv->asset, src->images[t], &im[t]) != MR_OK ||
            im[t].bytes == NULL || im[t].size < 8 || memcmp(im[t].bytes, "\x89PNG", 4) != 0 ||
            mr_io_png_is_paletted(im[t].bytes, im[t].size))
            return 0;
    }
    mr_status statuses[2] = {MR_OK, MR_OK};
    int handled[2] = {1, 1};
    char messages[2][1024] = {"", ""};
    const int both = src->refs[0].index >= 0 && src->refs[1].index >= 0;
    const int pair = pair_team(cv, both);
#pragma omp parallel for schedule(static, 1) num_threads(pair) if (pair > 1)
    for (int t = 0; t < 2; t++) {
        if (src->refs[t].index < 0) continue;
        char label[600];
        snprintf(label, sizeof label, "glTF '%s': image %d", mr_gltf_path(cv->asset), src->images[t]);
        FILE *f = fmemopen((void *)im[t].bytes, im[t].size, "rb");
        statuses[t] = f ? mr_io_png_deflate_read_codes(f, label, MR_IO_MAX_DIMENSION_DEFAULT, &codes[t], &handled[t])
                        : mr_fail(MR_ERR_NOMEM, "%s: cannot open the bytes as a stream", label);
        if (f != NULL) fclose(f);
        if (statuses[t] != MR_OK) snprintf(messages[t], sizeof messages[t], "%s", mr_last_error());
    }
    const int same_size = !both || (codes[0].width == codes[1].width && codes[0].height == codes[1].height);
    if (statuses[0] == MR_OK && statuses[1] == MR_OK && (!handled[0] || !handled[1] || !same_size)) {
        free(codes[0].codes);
        free(codes[1].codes);
        memset(codes, 0, 2 * sizeof *codes);
        return 0; // decoded to floats instead (resampled when the sizes differ)
    }
    *status = MR_OK;
    for (int t = 0; t < 2 && *status == MR_OK; t++)
        if (statuses[t] != MR_OK)
            *status = mr_fail(statuses[t], "material %d '%s': %s", cv->material, cv->name, messages[t]);
    const int t = src->refs[0].index >= 0 ? 0 : 1;
    *width = codes[t].width;
    *height = codes[t].height;
    for (int k = 0; k < 2; k++) stored[k] = (mr_img_stored){8, cv->from->encodings[k]};
    return 1;
}

/* ---- both readings: KHR_materials_specular over the core values (mr_gltf_convert.h) ------------------------- */

unsigned mr_gltf_specular_color_solve(const float base[3], float metallic, const float target[3], double ior,
                                      float color[3]) {
    const double f0_ior = ((ior - 1.0) / (ior + 1.0)) * ((ior - 1.0) / (ior + 1.0));
    const double m = mr_clampd(isfinite(metallic) ? metallic : 0.0, 0.0, 1.0);
    unsigned flags = 0;
    for (int c = 0; c < 3; c++) {
        const double b = mr_clampd(isfinite(base[c]) ? base[c] : 0.0, 0.0, 1.0);
        const double t = mr_clampd(isfinite(target[c]) ? target[c] : 0.0, 0.0, 1.0);
        if (m >= 1.0) { // no dielectric part: F0 is the base colour whatever the extension says; the colour a
                        // dielectric texel would take, so that a texture filtered across metal edges stays smooth
            color[c] = (float)mr_clampd(t / f0_ior, 0.0, 1.0 / f0_ior);
            if (fabs(b - t) > MR_GLTF_HYBRID_TOLERANCE) flags |= MR_GLTF_F0_METAL;
            continue;
        }
        const double wanted = (t - m * b) / ((1.0 - m) * f0_ior), top = 1.0 / f0_ior;
        const double sc = mr_clampd(wanted, 0.0, top);
        color[c] = (float)sc;
        const double f0 = (1.0 - m) * MR_MIN(f0_ior * (double)color[c], 1.0) + m * b;
        if (fabs(f0 - t) > MR_GLTF_HYBRID_TOLERANCE) flags |= wanted < 0.0 ? MR_GLTF_F0_BELOW : MR_GLTF_F0_ABOVE;
    }
    return flags;
}

/* One texture of the solve: decoded linear values (NULL: none) and the factor that multiplies them. */
typedef struct solve_input {
    const mr_gltf_texture_ref *ref;
    mr_img_encoding encoding;
    const double *factors; /* 3 */
    int first;             /* the first channel read (metallic: B, 2) */
    mr_image *image;
} solve_input;

/* Add KHR_materials_specular values to material m (its core values final: converted or kept), solved per texel from
 * the spec-gloss material `sg` it came from. `mk`: the conversion shared by materials with the same sources (its
 * result reused), or NULL. Fills r's extension fields; a material whose textures map differently gets a note. */
static mr_status add_extension(const conversion *cv, const mr_gltf_material *sg, mr_gltf_material *m, made *mk,
                               mr_gltf_material_report *r) {
    const double ior = cv->opts->extension_ior > 0.0 ? cv->opts->extension_ior : 1.5;
    const mr_transform_options *to = mr_transform_options_of(cv->opts->transform);
    // The texture mapping of the new one: the first of the sources' (all must agree, checked below).
    const mr_gltf_texture_ref *refs[4] = {&sg->diffuse_texture, &sg->specular_glossiness_texture,
                                          &m->base_color_texture, &m->metallic_roughness_texture};
    const mr_gltf_texture_ref *mapping = NULL;
    int like = -1;
    for (int k = 0; k < 4; k++)
        if (refs[k]->index >= 0) {
            if (mapping == NULL) {
                mapping = refs[k];
                like = refs[k]->index;
            } else if (!same_mapping(mapping, refs[k])) {
                snprintf(r->extension_note, sizeof r->extension_note,
                         "no KHR_materials_specular: its spec-gloss and core textures map onto the surface "
                         "differently");
                return MR_OK;
            }
        }
    if (mk != NULL && mk->extension_done) {
        r->extension = mk->extension.extension;
        r->texels = mk->extension.texels;
        r->f0_unmet = mk->extension.f0_unmet;
        r->diffuse_off = mk->extension.diffuse_off;
        r->f0_max_error = mk->extension.f0_max_error;
        r->diffuse_mean_error = mk->extension.diffuse_mean_error;
        r->diffuse_max_error = mk->extension.diffuse_max_error;
    } else {
        const double metallic_factor[3] = {m->metallic_factor, m->metallic_factor, m->metallic_factor};
        solve_input in[4] = {
            {&sg->diffuse_texture, MR_IMG_COLOR, sg->diffuse_factor, 0, NULL},
            {&sg->specular_glossiness_texture, MR_IMG_COLOR, sg->specular_factor, 0, NULL},
            {&m->base_color_texture, MR_IMG_COLOR, m->base_color_factor, 0, NULL},
            {&m->metallic_roughness_texture, MR_IMG_DATA, metallic_factor, 2, NULL},
        };
        mr_status status = MR_OK;
        int width = 1, height = 1;
        for (int k = 0; k < 4 && status == MR_OK; k++) {
            if (in[k].ref->index < 0) continue;
            mr_img_read_options ro = {0};
            ro.encoding = in[k].encoding;
            mr_img_stored stored;
            status = mr_gltf_texture_read(cv->asset, in[k].ref->index, &ro, &in[k].image, &stored);
            if (status == MR_OK) {
                width = MR_MAX(width, in[k].image->width);
                height = MR_MAX(height, in[k].image->height);
            } else {
                mr_fail_context(status, "material %d '%s': KHR_materials_specular", cv->material, cv->name);
            }
        }
        const size_t n = (size_t)width * (size_t)height;
        float *colour = status == MR_OK ? malloc(n * 3 * sizeof *colour) : NULL;
        if (status == MR_OK && colour == NULL)
            status = mr_fail(MR_ERR_NOMEM, "glTF '%s': material %d '%s': out of memory for %dx%d texels",
                             mr_gltf_path(cv->asset), cv->material, cv->name, width, height);
        size_t unmet = 0, off = 0;
        double f0_max = 0.0, diffuse_sum = 0.0, diffuse_max = 0.0;
        float top[3] = {0.0f, 0.0f, 0.0f};
        // Per row sums, added in row order afterwards: the mean does not depend on the thread count.
        double *row_sums = status == MR_OK ? calloc((size_t)height, sizeof *row_sums) : NULL;
        if (status == MR_OK && row_sums == NULL)
            status = mr_fail(MR_ERR_NOMEM, "glTF '%s': material %d '%s': out of memory", mr_gltf_path(cv->asset),
                             cv->material, cv->name);
        const int threads = mr_auto_threads(to->threads, (long)MR_MIN(n, 1u << 30), MR_WF_PARALLEL_TEXELS);
        if (status == MR_OK) {
#pragma omp parallel for num_threads(threads) if (threads > 1) schedule(static) \
    reduction(+ : unmet, off) reduction(max : f0_max, diffuse_max)
            for (int y = 0; y < height; y++)
                for (int x = 0; x < width; x++) {
                    float v[4][3];
                    for (int k = 0; k < 4; k++)
                        for (int c = 0; c < 3; c++) {
                            const int channel = in[k].first ? in[k].first : c;
                            const float t = in[k].image ? sample(in[k].image, channel, x, y, width, height) : 1.0f;
                            v[k][c] = (float)mr_clampd(t * in[k].factors[c], 0.0, 1.0);
                        }
                    float *sc = colour + 3 * ((size_t)y * (size_t)width + (size_t)x);
                    const float metallic = v[3][0];
                    const unsigned flags = mr_gltf_specular_color_solve(v[2], metallic, v[1], ior, sc);
                    unmet += flags != 0;
                    const double f0_ior = ((ior - 1.0) / (ior + 1.0)) * ((ior - 1.0) / (ior + 1.0));
                    const double dim = to->plain_diffuse ? 1.0 : 1.0 - MR_MAX(v[1][0], MR_MAX(v[1][1], v[1][2]));
                    double worst = 0.0;
                    for (int c = 0; c < 3; c++) {
                        const double f0 = (1.0 - metallic) * MR_MIN(f0_ior * sc[c], 1.0) + metallic * v[2][c];
                        f0_max = MR_MAX(f0_max, fabs(f0 - v[1][c]));
                        const double e = fabs(v[2][c] * (1.0 - metallic) - v[0][c] * dim);
                        row_sums[y] += e;
                        worst = MR_MAX(worst, e);
                    }
                    diffuse_max = MR_MAX(diffuse_max, worst);
                    off += worst > MR_GLTF_HYBRID_TOLERANCE;
                }
            for (size_t i = 0; i < n; i++)
                for (int c = 0; c < 3; c++) top[c] = MR_MAX(top[c], colour[3 * i + c]);
            for (int y = 0; y < height; y++) diffuse_sum += row_sums[y];
        }
        free(row_sums);
        for (int k = 0; k < 4; k++) mr_image_free(in[k].image);
        int uniform = 1;
        for (size_t i = 1; status == MR_OK && i < n && uniform; i++)
            uniform = memcmp(&colour[3 * i], colour, 3 * sizeof *colour) == 0;
        int texture = -1;
        double factor[3] = {1.0, 1.0, 1.0};
        if (status == MR_OK) {
            for (int c = 0; c < 3; c++) factor[c] = uniform ? colour[c] : top[c];
            if (!uniform) { // the colour over its largest value per channel, sRGB-encoded as the extension stores it
                uint8_t *codes = malloc(n * 3);
                encoded_texture e;
                memset(&e, 0, sizeof e);
                const char *prefix = cv->opts->image_prefix ? cv->opts->image_prefix : "converted";
                snprintf(e.uri, sizeof e.uri, "%s_m%d_specularColor.png", prefix, cv->material);
                if (codes == NULL) {
                    status = mr_fail(MR_ERR_NOMEM, "glTF '%s': material %d '%s': out of memory",
                                     mr_gltf_path(cv->asset), cv->material, cv->name);
                } else {
                    mr_srgb8_init();
                    for (size_t i = 0; i < n; i++)
                        for (int c = 0; c < 3; c++)
                            codes[3 * i + c] = mr_srgb8_encode(top[c] > 0.0f ? colour[3 * i + c] / top[c] : 0.0f);
                    const mr_io_png_settings settings = MR_IO_PNG_DEFAULT;
                    status = mr_io_png_encode(e.uri, width, height, 3, 8, codes, 1, &settings, &e.bytes, &e.size);
                    if (status == MR_OK) status = add_texture(cv, &e, like, &texture);
                }
                encoded_texture_release(&e);
                free(codes);
            }
        }
        free(colour);
        if (status != MR_OK) return status;
        r->extension = 1;
        r->texels = n;
        r->f0_unmet = unmet;
        r->diffuse_off = off;
        r->f0_max_error = f0_max;
        r->diffuse_mean_error = diffuse_sum / (3.0 * (double)n);
        r->diffuse_max_error = diffuse_max;
        if (mk != NULL) {
            mk->extension_done = 1;
            mk->extension_texture = texture;
            memcpy(mk->extension_factor, factor, sizeof factor);
            mk->extension = *r;
        }
        if (texture >= 0) {
            m->specular_color_texture = *mapping;
            m->specular_color_texture.index = texture;
        } else {
            mr_gltf_texture_ref_none(&m->specular_color_texture);
        }
        memcpy(m->specular_color_factor, factor, sizeof factor);
    }
    if (mk != NULL && mk->extension_done && r->extension) {
        if (mk->extension_texture >= 0) {
            m->specular_color_texture = *mapping;
            m->specular_color_texture.index = mk->extension_texture;
        } else {
            mr_gltf_texture_ref_none(&m->specular_color_texture);
        }
        memcpy(m->specular_color_factor, mk->extension_factor, sizeof mk->extension_factor);
    }
    m->has_specular = 1;
    m->specular_strength = 1.0;
    mr_gltf_texture_ref_none(&m->specular_texture);
    m->has_ior = ior != 1.5;
    m->ior = ior;
    return MR_OK;
}

/* Does a spec-gloss material converted to (or kept as) metal-rough get specular values over its core ones? Not with
 * core_only, not on the extension route (it has its own), not with EXR textures, not beside a kept spec-gloss
 * extension (the two must not share a material: KHR_materials_specular, "Exclusions"); r says why. */
static int wants_extension(const conversion *cv, mr_gltf_material_report *r) {
    if (cv->opts->core_only || mr_transform_output_index(cv->kind, "specular_color") >= 0) return 0;
    if (cv->opts->image_format != NULL && strcmp(cv->opts->image_format, "exr") == 0) {
        snprintf(r->extension_note, sizeof r->extension_note,
                 "no KHR_materials_specular with EXR textures (the solve reads the core textures as engines decode "
                 "8-bit ones)");
        return 0;
    }
    if (cv->opts->keep_source) {
        snprintf(r->extension_note, sizeof r->extension_note,
                 "no KHR_materials_specular beside the kept spec-gloss extension (they must not share a material)");
        return 0;
    }
    return 1;
}

/* Convert material cv->material (unless an earlier one with the same sources did: `cache`). */
static mr_status convert_material(conversion *cv, made *cache, int *cached, mr_gltf_material_report *r) {
    mr_gltf_material m;
    mr_status status = mr_gltf_get_material(cv->asset, cv->material, &m);
    if (status != MR_OK) return status;
    cv->name = m.name;
    const int to_metal = cv->to == &metalrough_side;
    if (to_metal && !m.has_spec_gloss) {
        snprintf(r->reason, sizeof r->reason, "no spec-gloss extension");
        return MR_OK;
    }
    if (!to_metal && m.has_spec_gloss) {
        snprintf(r->reason, sizeof r->reason, "it carries spec-gloss already");
        return MR_OK;
    }
    char own[128];
    if (to_metal && !cv->opts->overwrite && core_values(&m, own, sizeof own) > 0) {
        // The artist's own metal-rough version of the material (glTF's recommended fallback beside spec-gloss): kept,
        // not overwritten by a conversion. The extension goes like every converted material's unless keep_source.
        const mr_gltf_material sg = m;
        m.has_spec_gloss = cv->opts->keep_source;
        r->outcome = MR_GLTF_KEPT;
        snprintf(r->reason, sizeof r->reason, "it has metal-rough values of its own: %s", own);
        if (wants_extension(cv, r)) status = add_extension(cv, &sg, &m, NULL, r);
        return status == MR_OK ? mr_gltf_set_material(cv->asset, cv->material, &m) : status;
    }
    const double started = mr_now_seconds();
    sources src;
    sources_of(&m, to_metal, &src);
    for (int t = 0; t < 2; t++) {
        mr_gltf_texture texture;
        int known = src.refs[t].index >= 0 && mr_gltf_get_texture(cv->asset, src.refs[t].index, &texture) == MR_OK;
        src.images[t] = known ? texture.image : -1;
        src.samplers[t] = known ? texture.sampler : -1;
        if (known) src.sampler_params[t] = texture.params;
    }
    made *mk = NULL;
    for (int k = 0; k < *cached && mk == NULL; k++)
        if (same_sources(&cache[k].key, &src)) mk = &cache[k];
    int textured = src.refs[0].index >= 0 || src.refs[1].index >= 0;
    if (mk != NULL) {
        *r = mk->report;
        r->outcome = MR_GLTF_SHARED;
    } else {
        mk = &cache[(*cached)++];
        memset(mk, 0, sizeof *mk);
        mk->key = src;
        mk->textures[0] = mk->textures[1] = -1;
        mr_image *images[2] = {NULL, NULL};
        mr_img_stored stored[2];
        memset(stored, 0, sizeof stored);
        int width = 1, height = 1;
        mr_io_codes codes[2];
        memset(codes, 0, sizeof codes);
        const int by_palette = textured && convert_palette(cv, &src, mk, &status);
        const int by_codes = textured && !by_palette && read_codes(cv, &src, codes, stored, &width, &height, &status);
        if (by_palette || (by_codes && status != MR_OK)) {
            // done: a paletted texture converted through its palette (or a failure reading the codes)
        } else if (by_codes || ((status = read_sources(cv, &src, images, stored, &width, &height)) == MR_OK &&
                                textured)) {
            status = convert_texels(cv, &src, images, codes, stored, width, height, mk);
            mk->report.width = width;
            mk->report.height = height;
        } else if (status == MR_OK) { // factors only: one texel
            double in[3 * MR_TRANSFORM_MAX_SLOTS];
            size_t k = 0;
            for (int i = 0; i < cv->kind->input_count; i++)
                for (int c = 0; c < cv->kind->inputs[i].channels; c++) in[k++] = src.factors[i][c];
            unsigned flags = 0;
            status = mr_transform_apply_values(cv->opts->transform, in, mk->values, &flags);
            uint8_t f = (uint8_t)flags;
            count_flags(&mk->report, &f, 1);
        }
        mr_image_free(images[0]);
        mr_image_free(images[1]);
        free(codes[0].codes);
        free(codes[1].codes);
        if (status != MR_OK) {
            (*cached)--;
            return status;
        }
        mk->report.outcome = MR_GLTF_CONVERTED;
        mk->report.seconds = mr_now_seconds() - started;
        *r = mk->report;
    }
    const mr_gltf_material sg = m;
    set_outputs(cv, &src, mk, textured, &m);
    if (to_metal && wants_extension(cv, r) && (status = add_extension(cv, &sg, &m, mk, r)) != MR_OK) return status;
    // A KHR_materials_specular at its defaults (factor 1, colour 1, no textures) means what the core material means
    // alone: written out, it is an empty object (beside spec-gloss, the validator's MULTIPLE_EXTENSIONS); dropped.
    if (m.has_specular && m.specular_strength == 1.0 && m.specular_color_factor[0] == 1.0 &&
        m.specular_color_factor[1] == 1.0 && m.specular_color_factor[2] == 1.0 && m.specular_texture.index < 0 &&
        m.specular_color_texture.index < 0)
        m.has_specular = 0;
    if (to_metal) m.has_spec_gloss = cv->opts->keep_source;
    else m.has_spec_gloss = 1; // the core material stays as the fallback
    status = mr_gltf_set_material(cv->asset, cv->material, &m);
    r->seconds = mr_now_seconds() - started;
    return status;
}

mr_status mr_gltf_convert(mr_gltf *asset, const mr_gltf_convert_options *opts, mr_gltf_material_report *reports) {
    if (asset == NULL || opts == NULL || opts->transform == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "glTF conversion: NULL asset, options or transform");
    const mr_transform_kind *kind = mr_transform_kind_of(opts->transform);
    conversion cv = {asset, opts, kind, NULL, NULL, 0, ""};
    if (strcmp(kind->source, specgloss_side.model) == 0 && strcmp(kind->target, metalrough_side.model) == 0) {
        cv.from = &specgloss_side;
        cv.to = &metalrough_side;
    } else if (strcmp(kind->source, metalrough_side.model) == 0 && strcmp(kind->target, specgloss_side.model) == 0) {
        cv.from = &metalrough_side;
        cv.to = &specgloss_side;
    } else {
        return mr_fail(MR_ERR_INVALID_ARG, "glTF '%s': transform %s converts %s to %s; a glTF asset converts between "
                       "gltf-specgloss and gltf", mr_gltf_path(asset), kind->name, kind->source, kind->target);
    }
    if (opts->image_format != NULL && strcmp(opts->image_format, "png") != 0 && strcmp(opts->image_format, "exr"))
        return mr_fail(MR_ERR_INVALID_ARG, "glTF conversion: image format '%s': expected png or exr",
                       opts->image_format);
    if (opts->extension_ior != 0.0 && !(opts->extension_ior > 1.0 && opts->extension_ior <= 1e4))
        return mr_fail(MR_ERR_INVALID_ARG, "glTF conversion: extension ior %g: expected a value in (1, 10000]",
                       opts->extension_ior);
    mr_gltf_counts counts;
    mr_gltf_get_counts(asset, &counts);
    made *cache = calloc((size_t)MR_MAX(counts.materials, 1), sizeof *cache);
    if (cache == NULL) return mr_fail(MR_ERR_NOMEM, "glTF '%s': out of memory", mr_gltf_path(asset));
    int cached = 0;
    mr_status status = MR_OK;
    for (int k = 0; k < counts.materials && status == MR_OK; k++) {
        mr_gltf_material_report r;
        memset(&r, 0, sizeof r);
        cv.material = k;
        status = convert_material(&cv, cache, &cached, &r);
        mr_gltf_material m;
        if (mr_gltf_get_material(asset, k, &m) == MR_OK) snprintf(r.name, sizeof r.name, "%s", m.name);
        if (reports != NULL) reports[k] = r;
        if (opts->progress != NULL) opts->progress(opts->progress_user, k, counts.materials);
    }
    free(cache);
    return status;
}

mr_status mr_gltf_convert_file(const char *input, const char *output, const mr_gltf_convert_options *opts,
                               mr_gltf_convert_result *result) {
    if (result != NULL) memset(result, 0, sizeof *result);
    if (input == NULL || output == NULL || opts == NULL || opts->transform == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "glTF conversion: NULL input, output, options or transform");
    // New images are named after the output (out/avocado.gltf: avocado_m0_basecolor.png) unless told otherwise.
    mr_gltf_convert_options o = *opts;
    char stem[512];
    if (o.image_prefix == NULL) {
        const char *slash = strrchr(output, '/');
        snprintf(stem, sizeof stem, "%s", slash ? slash + 1 : output);
        char *dot = strrchr(stem, '.');
        if (dot != NULL && dot != stem) *dot = '\0';
        o.image_prefix = stem;
    }
    opts = &o;
    mr_gltf *asset = NULL;
    mr_status status = mr_gltf_load(input, &asset);
    if (status != MR_OK) return status;
    mr_gltf_counts counts;
    mr_gltf_get_counts(asset, &counts);
    mr_gltf_material_report *reports = calloc((size_t)MR_MAX(counts.materials, 1), sizeof *reports);
    if (reports == NULL) status = mr_fail(MR_ERR_NOMEM, "glTF '%s': out of memory", input);
    if (status == MR_OK) status = mr_gltf_convert(asset, opts, reports);
    mr_gltf_prune_stats pruned = {0, 0, 0, 0};
    // Converted materials no longer point at their old textures; left in, they are dead files beside the output.
    if (status == MR_OK && !opts->keep_unused) status = mr_gltf_prune_unused(asset, &pruned);
    // Spec-gloss kept beside a new core material: engines without the extension read the core material, so it must
    // not be required (FloppyDisk requires it).
    const int to_specgloss = strcmp(mr_transform_kind_of(opts->transform)->target, specgloss_side.model) == 0;
    if (status == MR_OK && (opts->keep_source || to_specgloss))
        status = mr_gltf_set_extension_required(asset, "KHR_materials_pbrSpecularGlossiness", 0);
    if (status == MR_OK) {
        mr_gltf_sync_extensions(asset);
        // Side files named after the output, so that two outputs in one folder never share one (every Sketchfab
        // export's buffer is scene.bin), and no file another asset uses replaced unless asked.
        mr_gltf_save_options so = {1, opts->replace_files, opts->replace_hint};
        status = mr_gltf_save_with(asset, output, &so);
    }
    mr_gltf_free(asset);
    if (status != MR_OK || result == NULL) {
        free(reports);
        return status;
    }
    result->material_count = counts.materials;
    result->materials = reports;
    result->pruned = pruned;
    return MR_OK;
}

void mr_gltf_convert_result_free(mr_gltf_convert_result *result) {
    if (result == NULL) return;
    free(result->materials);
    memset(result, 0, sizeof *result);
}

void mr_gltf_convert_totals_of(const mr_gltf_convert_result *result, mr_gltf_convert_totals *out) {
    memset(out, 0, sizeof *out);
    for (int k = 0; result != NULL && k < result->material_count; k++) {
        const mr_gltf_material_report *r = &result->materials[k];
        out->converted += r->outcome == MR_GLTF_CONVERTED || r->outcome == MR_GLTF_SHARED;
        out->kept += r->outcome == MR_GLTF_KEPT;
        out->extensions += r->extension;
        if (r->extension && r->outcome != MR_GLTF_SHARED) { // each solve once, as the textures
            const double seen = (double)out->total.texels;
            out->total.diffuse_mean_error = (out->total.diffuse_mean_error * seen +
                                             r->diffuse_mean_error * (double)r->texels) / (seen + (double)r->texels);
            out->total.texels += r->texels;
            out->total.f0_unmet += r->f0_unmet;
            out->total.diffuse_off += r->diffuse_off;
            out->total.f0_max_error = MR_MAX(out->total.f0_max_error, r->f0_max_error);
            out->total.diffuse_max_error = MR_MAX(out->total.diffuse_max_error, r->diffuse_max_error);
        }
        if (r->outcome != MR_GLTF_CONVERTED) continue; // each conversion once: its textures are written once
        out->texels += r->width > 0 ? (size_t)r->width * (size_t)r->height : 1;
        out->total.flagged += r->flagged;
        out->total.off_manifold += r->off_manifold;
        out->total.nonfinite += r->nonfinite;
        out->total.clamped += r->clamped;
        out->total.failed += r->failed;
    }
}
