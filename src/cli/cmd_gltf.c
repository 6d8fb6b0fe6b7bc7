/*
 * cmd_gltf.c — `matremap gltf spec2metal|metal2spec IN -o OUT [options]`: converts the materials of a glTF asset
 * between KHR_materials_pbrSpecularGlossiness and core pbrMetallicRoughness through the workflow converters
 * (src/workflow/workflow.h, the network of nn/ for --method mlp), texel by texel, and saves the asset with its new
 * textures beside it (gltf/mr_gltf.h). Everything else in the asset is left as it was.
 *
 * Per material (spec2metal): the spec-gloss factors multiply their textures in linear values (colour textures
 * sRGB-decoded, glossiness linear, glTF's rule), the product is converted with glossiness -> roughness = 1 -
 * glossiness and the spec-gloss diffuse read as glTF renders it (--convention), and the result becomes
 * factors alone (no textures) or a base-colour texture (RGBA when the diffuse has alpha) plus a packed
 * metallic-roughness texture (G roughness, B metallic) with factors 1. Both textures keep the UV set,
 * KHR_texture_transform and sampler of the source textures; the two source textures must share their UV mapping
 * (they do in practice: one texel of each describes one surface point) and are brought to one size (bilinear).
 * A spec-gloss material that carries core metal-rough values of its own (the authors' fallback) is kept, not
 * converted, unless --overwrite-metal-rough; the output says so per material. The off-manifold tolerance of each
 * input value follows its texture's encoding (half a code, times the factor; workflow.h, "Tolerances") unless
 * --eps. metal2spec is the inverse: the spec-gloss extension is added beside the core material, which stays as
 * the fallback glTF asks for.
 */
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "cli.h"
#include "gltf/mr_gltf.h"

#define PATH_SIZE 4096

static void print_help(void) {
    printf("Usage: matremap gltf spec2metal IN.gltf|IN.glb -o OUT.gltf|OUT.glb [options]\n"
           "       matremap gltf metal2spec IN.gltf|IN.glb -o OUT.gltf|OUT.glb [options]\n"
           "\n"
           "spec2metal converts every KHR_materials_pbrSpecularGlossiness material of a glTF asset to core\n"
           "metallic-roughness: factors times textures, texel by texel, with the converters of 'matremap\n"
           "spec2metal' (docs/workflow.md). New textures (PNG, or EXR with --format exr) are written beside OUT;\n"
           "extensionsUsed/Required are updated; meshes, nodes, animations and other extensions are kept.\n"
           "A material that already carries core metal-rough values of its own beside spec-gloss (a\n"
           "baseColorTexture or metallicRoughnessTexture, or factors other than 1: the artist's own fallback, as\n"
           "in the Avocado) is kept as it is and not converted, and the output says so; its spec-gloss extension\n"
           "goes like the converted ones' (--keep-specgloss keeps it). --overwrite-metal-rough converts it anyway.\n"
           "metal2spec adds the spec-gloss extension to every metal-rough material (Eq. 2), keeping the core\n"
           "material as the fallback.\n"
           "After converting, every texture, image and sampler that nothing in the asset refers to any more is\n"
           "removed (spec2metal's old diffuse and specular-glossiness textures, but also any the input left\n"
           "unused), and its image file is not written beside OUT; references are renumbered. What an unknown\n"
           "extension might refer to is kept (gltf/mr_gltf.h, mr_gltf_prune_unused).\n"
           "\n"
           "Options:\n"
           "  -o, --output OUT      the converted asset (.gltf with its files beside it, or .glb); never an input\n"
           "  --method M            spec2metal: mlp (default), weighted, mean, khronos, or extension: the lossless\n"
           "                        route of KHR_materials_specular + KHR_materials_ior (ior 1000, textures reused,\n"
           "                        metallic 0; for engines that support both); metal2spec: eq2 (default), khronos\n"
           "  --weights FILE        the network for mlp (default: the shipped one, as 'matremap spec2metal')\n"
           "  --convention C        gltf (default) or paper: how the spec-gloss diffuse is read (docs/workflow.md)\n"
           "  --overwrite-metal-rough  spec2metal: also convert materials that carry metal-rough values of their\n"
           "                        own beside spec-gloss, overwriting them (default: keep them, and say so)\n"
           "  --eps E               spec2metal, weighted/mean/khronos: the off-manifold tolerance, for every value\n"
           "                        (default: per texel, half a code value of the texture it comes from, times its\n"
           "                        factor, at least 1e-6: a clean 8-bit export flags nothing; docs/workflow.md)\n"
           "  --threads N           OpenMP threads of the conversion (default 0: automatic, a team for textures of\n"
           "                        16384 texels or more)\n"
           "  --keep-specgloss      spec2metal: keep the spec-gloss extension in the output beside the new core\n"
           "                        material (default: remove it, so engines without it read the core material)\n"
           "  --format F            png (default) or exr for the new textures (EXR is not a core glTF image\n"
           "                        type: the validator reports it and many viewers cannot read it)\n"
           "  --keep-unused         keep unreferenced textures, images and samplers (default: remove them)\n"
           "  --json                a JSON summary on stdout\n"
           "  --help                this text\n"
           "\n"
           "Prints one line per material (converted: texture size, flagged texels by flag, time; kept or left as it\n"
           "is: why), a total and what was removed; --json gives the same, with the lists of converted and kept\n"
           "materials.\n"
           "\n"
           "Example:\n"
           "  matremap gltf spec2metal FloppyDisk/scene.gltf -o out/floppy.gltf --method weighted\n");
}

typedef struct options {
    const char *direction, *input, *output, *method, *weights, *format;
    mr_wf_diffuse convention;
    double eps;    /* --eps, when eps_given */
    int eps_given; /* else each input's tolerance follows its texture's encoding */
    int threads;   /* --threads: mr_wf_options.threads (0 automatic) */
    int overwrite, keep_specgloss, keep_unused, json;
} options;

/* ---- textures ----------------------------------------------------------------------------------------------- */

/* Decode the image of texture `ref` (colour: RGB sRGB-decoded, alpha linear; data: all linear). Returns an exit
 * code (messages printed). */
int cli_gltf_read_texture(const mr_gltf *asset, const mr_gltf_texture_ref *ref, mr_img_encoding encoding,
                          const char *scratch, mr_image **out) {
    return cli_gltf_read_texture_stored(asset, ref, encoding, scratch, out, NULL);
}

int cli_gltf_read_texture_stored(const mr_gltf *asset, const mr_gltf_texture_ref *ref, mr_img_encoding encoding,
                                 const char *scratch, mr_image **out, mr_img_stored *stored) {
    (void)scratch;
    mr_img_read_options ro = {0};
    ro.encoding = encoding;
    mr_status status = mr_gltf_texture_read(asset, ref->index, &ro, out, stored);
    return status == MR_OK ? CLI_EXIT_OK : cli_fail("gltf", status);
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
    int xa = x0 < 0 ? 0 : x0, xb = x0 + 1 >= im->width ? im->width - 1 : x0 + 1;
    int ya = y0 < 0 ? 0 : y0, yb = y0 + 1 >= im->height ? im->height - 1 : y0 + 1;
    if (xa >= im->width) xa = im->width - 1;
    if (ya >= im->height) ya = im->height - 1;
    double top = mr_image_at(im, xa, ya)[channel] * (1 - fx) + mr_image_at(im, xb, ya)[channel] * fx;
    double bottom = mr_image_at(im, xa, yb)[channel] * (1 - fx) + mr_image_at(im, xb, yb)[channel] * fx;
    return (float)(top * (1 - fy) + bottom * fy);
}

/* Two texture references map texels to the surface the same way. */
static int same_mapping(const mr_gltf_texture_ref *a, const mr_gltf_texture_ref *b) {
    return a->tex_coord == b->tex_coord && a->has_transform == b->has_transform &&
           (!a->has_transform || (a->offset[0] == b->offset[0] && a->offset[1] == b->offset[1] &&
                                  a->rotation == b->rotation && a->scale[0] == b->scale[0] &&
                                  a->scale[1] == b->scale[1] && a->transform_tex_coord == b->transform_tex_coord));
}

/* Write the `count` (1 or 2) new textures of material `material` (named OUTBASE_mK_NAME.EXT) to the scratch
 * folder, encoded in parallel, then add them to the asset under those relative URIs as textures with the sampler
 * of texture `like` (none if it has none). Returns a status; texture[] receives the indices. */
static mr_status add_textures(mr_gltf *asset, int count, mr_image *const images[2],
                              const mr_img_encoding encodings[2], const char *const names[2], const options *o,
                              const char *scratch, const char *outbase, int material, int like, int texture[2]) {
    char files[2][PATH_SIZE], uris[2][PATH_SIZE / 2];
    for (int t = 0; t < count; t++) {
        int length = snprintf(uris[t], sizeof uris[t], "%s_m%d_%s.%s", outbase, material, names[t], o->format);
        int total = length < 0 || (size_t)length >= sizeof uris[t]
                        ? -1 : snprintf(files[t], sizeof files[t], "%s/%s", scratch, uris[t]);
        if (total < 0 || (size_t)total >= sizeof files[t]) {
            fprintf(stderr, "matremap gltf: error: -o '%s': the output's name is too long\n", o->output);
            return MR_ERR_INVALID_ARG;
        }
    }
    mr_status statuses[2];
    char messages[2][1024]; // mr_last_error() is per thread
#pragma omp parallel for schedule(static, 1)
    for (int t = 0; t < count; t++) {
        mr_img_write_options wo = {0};
        wo.encoding = encodings[t];
        statuses[t] = mr_img_write(files[t], images[t], &wo);
        snprintf(messages[t], sizeof messages[t], "%s", statuses[t] == MR_OK ? "" : mr_last_error());
    }
    mr_gltf_sampler sampler, *sampler_ptr = NULL;
    mr_gltf_texture source;
    if (like >= 0 && mr_gltf_get_texture(asset, like, &source) == MR_OK && source.sampler >= 0) {
        sampler = source.params;
        sampler_ptr = &sampler;
    }
    mr_status status = MR_OK;
    for (int t = 0; t < count; t++) {
        int image = -1;
        if (status == MR_OK && statuses[t] != MR_OK) {
            fprintf(stderr, "matremap gltf: error: %s\n", messages[t]);
            status = statuses[t];
        }
        if (status == MR_OK) status = mr_gltf_add_image_file(asset, files[t], uris[t], &image);
        if (status == MR_OK) status = mr_gltf_add_texture(asset, image, sampler_ptr, &texture[t]);
        remove(files[t]);
    }
    return status;
}

/* ---- one material ------------------------------------------------------------------------------------------- */

/* What happened to a material, for the summary. */
typedef enum outcome_kind {
    OUTCOME_SKIPPED = 0, /* nothing to convert (no spec-gloss extension, or metal2spec: it has one already) */
    OUTCOME_CONVERTED,
    OUTCOME_KEPT         /* spec2metal: its own metal-rough values kept (--overwrite-metal-rough converts) */
} outcome_kind;

typedef struct outcome {
    outcome_kind kind;
    char reason[256];  /* why kept or skipped; "" when converted */
    int width, height; /* texture size, 0 when factors only */
    size_t flagged;    /* texels with any workflow flag */
    size_t off_manifold, nonfinite, clamped, failed; /* texels with each flag */
    double seconds;
} outcome;

/* Count the n texels' flags into r. */
static void count_flags(outcome *r, const uint8_t *flags, size_t n) {
    for (size_t i = 0; i < n; i++) {
        r->flagged += flags[i] != 0;
        r->off_manifold += (flags[i] & MR_WF_OFF_MANIFOLD) != 0;
        r->nonfinite += (flags[i] & MR_WF_NONFINITE_INPUT) != 0;
        r->clamped += (flags[i] & MR_WF_CLAMPED_INPUT) != 0;
        r->failed += (flags[i] & MR_WF_METHOD_FAILED) != 0;
    }
}

/* Planar buffers of n texels for one conversion. */
typedef struct buffers {
    float *in_rgb, *in_rgb2, *in_scalar, *alpha; /* inputs: colour, second colour (specular), roughness */
    float *out_rgb, *out_rgb2, *out_scalar, *out_scalar2;
    uint8_t *flags;
} buffers;

static int buffers_alloc(buffers *b, size_t n) {
    memset(b, 0, sizeof *b);
    b->in_rgb = malloc(3 * n * sizeof(float));
    b->in_rgb2 = malloc(3 * n * sizeof(float));
    b->in_scalar = malloc(n * sizeof(float));
    b->alpha = malloc(n * sizeof(float));
    b->out_rgb = malloc(3 * n * sizeof(float));
    b->out_rgb2 = malloc(3 * n * sizeof(float));
    b->out_scalar = malloc(n * sizeof(float));
    b->out_scalar2 = malloc(n * sizeof(float));
    b->flags = malloc(n);
    return b->in_rgb && b->in_rgb2 && b->in_scalar && b->alpha && b->out_rgb && b->out_rgb2 && b->out_scalar &&
           b->out_scalar2 && b->flags;
}

static void buffers_free(buffers *b) {
    free(b->in_rgb);
    free(b->in_rgb2);
    free(b->in_scalar);
    free(b->alpha);
    free(b->out_rgb);
    free(b->out_rgb2);
    free(b->out_scalar);
    free(b->out_scalar2);
    free(b->flags);
}

/* A 3- or 4-channel image of n = width x height texels from RGB values and an optional fourth channel. */
static mr_status compose(int width, int height, const float *rgb, const float *fourth, mr_image **out) {
    mr_status status = mr_image_create(width, height, fourth ? 4 : 3, out);
    if (status != MR_OK) return status;
    size_t n = (size_t)width * (size_t)height;
    int channels = fourth ? 4 : 3;
    for (size_t i = 0; i < n; i++) {
        for (int c = 0; c < 3; c++) (*out)->pixels[i * (size_t)channels + (size_t)c] = rgb[3 * i + (size_t)c];
        if (fourth) (*out)->pixels[i * 4 + 3] = fourth[i];
    }
    return MR_OK;
}

/* The two new textures of a per-texel conversion: images from rgb[t] (with fourth[t] as alpha when not NULL),
 * written and added like `mapping`'s texture (mapping is the first of the source textures that exists), and
 * refs[t] set to `mapping` (texCoord, transform) with the new texture's index. */
static mr_status add_converted_textures(mr_gltf *asset, int material, const options *o, const char *scratch,
                                        const char *outbase, int width, int height, const float *const rgb[2],
                                        const float *const fourth[2], const mr_img_encoding encodings[2],
                                        const char *const names[2], const mr_gltf_texture_ref *mapping,
                                        mr_gltf_texture_ref *const refs[2]) {
    mr_image *images[2] = {NULL, NULL};
    int indices[2] = {-1, -1};
    mr_status status = compose(width, height, rgb[0], fourth[0], &images[0]);
    if (status == MR_OK) status = compose(width, height, rgb[1], fourth[1], &images[1]);
    if (status == MR_OK)
        status = add_textures(asset, 2, images, encodings, names, o, scratch, outbase, material, mapping->index,
                              indices);
    for (int t = 0; t < 2; t++) {
        *refs[t] = *mapping;
        refs[t]->index = indices[t];
        mr_image_free(images[t]);
    }
    return status;
}

/* Read the two source textures of a material (either may be absent: index -1) and settle the grid they are
 * converted on: the larger texture's size, 1 x 1 without textures. Returns an exit code. */
static int read_pair(const mr_gltf *asset, int k, const char *name, const mr_gltf_texture_ref *a,
                     mr_img_encoding a_encoding, const mr_gltf_texture_ref *b, mr_img_encoding b_encoding,
                     const char *scratch, mr_image **a_image, mr_image **b_image, mr_img_stored stored[2],
                     int *width, int *height) {
    if (a->index >= 0 && b->index >= 0 && !same_mapping(a, b)) {
        fprintf(stderr, "matremap gltf: error: material %d '%s': its two textures map onto the surface differently "
                "(UV set or KHR_texture_transform), so their texels cannot be converted pairwise\n", k, name);
        return CLI_EXIT_BAD_INPUT;
    }
    int code = CLI_EXIT_OK;
    if (a->index >= 0) code = cli_gltf_read_texture_stored(asset, a, a_encoding, scratch, a_image, &stored[0]);
    if (code == CLI_EXIT_OK && b->index >= 0)
        code = cli_gltf_read_texture_stored(asset, b, b_encoding, scratch, b_image, &stored[1]);
    if (code != CLI_EXIT_OK) return code;
    *width = *height = 1;
    const mr_image *images[2] = {*a_image, *b_image};
    for (int i = 0; i < 2; i++)
        if (images[i] != NULL) {
            if (images[i]->width > *width) *width = images[i]->width;
            if (images[i]->height > *height) *height = images[i]->height;
        }
    return CLI_EXIT_OK;
}

/* read_pair, then the buffers for the grid's texels; on failure nothing is left allocated. stored[t] says how
 * each texture's file stored its samples (stored[t].bits 0 for an absent texture). Returns an exit code. */
static int prepare(const mr_gltf *asset, int k, const char *name, const mr_gltf_texture_ref *a,
                   mr_img_encoding a_encoding, const mr_gltf_texture_ref *b, mr_img_encoding b_encoding,
                   const char *scratch, mr_image **a_image, mr_image **b_image, mr_img_stored stored[2], int *width,
                   int *height, buffers *bufs) {
    memset(stored, 0, 2 * sizeof *stored);
    int code = read_pair(asset, k, name, a, a_encoding, b, b_encoding, scratch, a_image, b_image, stored, width,
                         height);
    if (code == CLI_EXIT_OK && !buffers_alloc(bufs, (size_t)*width * (size_t)*height)) {
        buffers_free(bufs);
        fprintf(stderr, "matremap gltf: error: out of memory for %dx%d texels\n", *width, *height);
        code = CLI_EXIT_INTERNAL;
    }
    if (code != CLI_EXIT_OK) {
        mr_image_free(*a_image);
        mr_image_free(*b_image);
        *a_image = *b_image = NULL;
    }
    return code;
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

/* --method extension: the lossless route of KHR_materials_specular + KHR_materials_ior (what gltf-transform's
 * `metalrough` does). Nothing is converted per texel: the diffuse becomes the base colour (metallic 0), the
 * specular colour becomes the specular extension's colour (factor and texture reused), ior 1000 makes the
 * dielectric's F0 that colour (((1000 - 1)/(1000 + 1))^2 = 0.996), and glossiness becomes a roughness texture
 * (G = 1 - glossiness, the only new texture) or factor. Engines without the two extensions see a plain
 * dielectric with the diffuse as its colour. */
static int extension_material(mr_gltf *asset, int k, const options *o, mr_gltf_material *m, const char *scratch,
                              const char *outbase, outcome *r) {
    double started = cli_now();
    const mr_gltf_texture_ref diffuse = m->diffuse_texture, sg = m->specular_glossiness_texture;
    mr_status status = MR_OK;
    m->base_color_texture = diffuse;
    for (int c = 0; c < 4; c++) m->base_color_factor[c] = m->diffuse_factor[c];
    m->metallic_factor = 0.0;
    m->has_specular = 1;
    m->specular_strength = 1.0;
    for (int c = 0; c < 3; c++) m->specular_color_factor[c] = m->specular_factor[c];
    m->specular_color_texture = sg;
    mr_gltf_texture_ref_none(&m->specular_texture);
    m->has_ior = 1;
    m->ior = 1000.0;
    if (sg.index < 0) { // glossiness is a factor: roughness is one too
        m->roughness_factor = 1.0 - m->glossiness_factor;
        mr_gltf_texture_ref_none(&m->metallic_roughness_texture);
    } else {
        mr_image *sg_image = NULL, *rough = NULL;
        int code = cli_gltf_read_texture(asset, &sg, MR_IMG_COLOR, scratch, &sg_image);
        if (code != CLI_EXIT_OK) return code;
        status = mr_image_create(sg_image->width, sg_image->height, 3, &rough);
        size_t n = (size_t)sg_image->width * (size_t)sg_image->height;
        for (size_t i = 0; status == MR_OK && i < n; i++) {
            float gloss = sg_image->channels == 4 ? sg_image->pixels[4 * i + 3] : 1.0f;
            double roughness = 1.0 - gloss * m->glossiness_factor;
            rough->pixels[3 * i] = 0.0f;
            // A non-finite glossiness is glossiness 0 (docs/workflow.md), as in the per-texel conversions.
            if (!isfinite(roughness)) {
                roughness = 1.0;
                r->nonfinite++;
                r->flagged++;
            }
            rough->pixels[3 * i + 1] = (float)roughness;
            rough->pixels[3 * i + 2] = 0.0f;
        }
        int index[2] = {-1, -1};
        if (status == MR_OK) {
            mr_image *const images[2] = {rough, NULL};
            static const mr_img_encoding encodings[2] = {MR_IMG_DATA, MR_IMG_DATA};
            static const char *const names[2] = {"roughness", NULL};
            status = add_textures(asset, 1, images, encodings, names, o, scratch, outbase, k, sg.index, index);
        }
        m->metallic_roughness_texture = sg;
        m->metallic_roughness_texture.index = index[0];
        m->roughness_factor = 1.0;
        r->width = sg_image->width;
        r->height = sg_image->height;
        mr_image_free(sg_image);
        mr_image_free(rough);
    }
    m->has_spec_gloss = o->keep_specgloss;
    if (status == MR_OK) status = mr_gltf_set_material(asset, k, m);
    r->kind = OUTCOME_CONVERTED;
    r->seconds = cli_now() - started;
    return status == MR_OK ? CLI_EXIT_OK : cli_fail("gltf", status);
}

static int spec2metal_material(mr_gltf *asset, int k, const options *o, const mr_mlp *net, const mr_wf_options *wf,
                               const char *scratch, const char *outbase, outcome *r) {
    mr_gltf_material m;
    mr_status status = mr_gltf_get_material(asset, k, &m);
    if (status != MR_OK) return cli_fail("gltf", status);
    if (!m.has_spec_gloss) {
        snprintf(r->reason, sizeof r->reason, "no spec-gloss extension");
        return CLI_EXIT_OK;
    }
    char own[128];
    if (!o->overwrite && core_values(&m, own, sizeof own) > 0) {
        // The artist's own metal-rough version of the material (glTF's recommended fallback beside spec-gloss):
        // kept, not overwritten by a conversion. The extension goes like every converted material's (this is a
        // metal-rough asset now), unless --keep-specgloss; the message says so.
        m.has_spec_gloss = o->keep_specgloss;
        status = mr_gltf_set_material(asset, k, &m);
        r->kind = OUTCOME_KEPT;
        snprintf(r->reason, sizeof r->reason, "it has metal-rough values of its own: %s", own);
        return status == MR_OK ? CLI_EXIT_OK : cli_fail("gltf", status);
    }
    if (strcmp(o->method, "extension") == 0) return extension_material(asset, k, o, &m, scratch, outbase, r);
    double started = cli_now();
    const mr_gltf_texture_ref *dref = &m.diffuse_texture, *sref = &m.specular_glossiness_texture;
    mr_image *dimg = NULL, *simg = NULL;
    int width = 1, height = 1;
    buffers b;
    mr_img_stored stored[2];
    int code = prepare(asset, k, m.name, dref, MR_IMG_COLOR, sref, MR_IMG_COLOR, scratch, &dimg, &simg, stored,
                       &width, &height, &b);
    if (code != CLI_EXIT_OK) return code;
    size_t n = (size_t)width * (size_t)height;
    // Factors times textures, in linear values (glTF multiplies them so).
    int has_alpha = 0;
#pragma omp parallel for schedule(static) reduction(| : has_alpha)
    for (int y = 0; y < height; y++)
        for (int x = 0; x < width; x++) {
            size_t i = (size_t)y * (size_t)width + (size_t)x;
            for (int c = 0; c < 3; c++) {
                b.in_rgb[3 * i + c] = (float)((dimg ? sample(dimg, c, x, y, width, height) : 1.0f) *
                                              m.diffuse_factor[c]);
                b.in_rgb2[3 * i + c] = (float)((simg ? sample(simg, c, x, y, width, height) : 1.0f) *
                                               m.specular_factor[c]);
            }
            b.alpha[i] = (float)((dimg ? sample(dimg, 3, x, y, width, height) : 1.0f) * m.diffuse_factor[3]);
            has_alpha |= b.alpha[i] != 1.0f;
            b.in_scalar[i] = (float)(1.0 - (simg ? sample(simg, 3, x, y, width, height) : 1.0f) *
                                               m.glossiness_factor);
        }
    mr_wf_spec_maps in = {b.in_rgb, b.in_rgb2, b.in_scalar};
    mr_wf_metal_maps out = {b.out_rgb, b.out_scalar, b.out_scalar2};
    mr_wf_options wfm = *wf;
    if (!o->eps_given) { // each value is known to half a code of its texture, times the factor (docs/workflow.md)
        wfm.diffuse_quantisation = cli_quantisation(dimg ? &stored[0] : NULL, m.diffuse_factor);
        wfm.specular_quantisation = cli_quantisation(simg ? &stored[1] : NULL, m.specular_factor);
    }
    status = net ? mr_wf_spec_to_metal_mlp_batch(net, &in, n, &wfm, &out, b.flags)
                 : mr_wf_spec_to_metal_batch(&in, n, &wfm, &out, b.flags);
    if (status == MR_OK) count_flags(r, b.flags, n);
    if (status == MR_OK && dimg == NULL && simg == NULL) { // factors only
        for (int c = 0; c < 3; c++) m.base_color_factor[c] = b.out_rgb[c];
        m.base_color_factor[3] = b.alpha[0];
        m.metallic_factor = b.out_scalar[0];
        m.roughness_factor = b.out_scalar2[0];
        mr_gltf_texture_ref_none(&m.base_color_texture);
        mr_gltf_texture_ref_none(&m.metallic_roughness_texture);
    } else if (status == MR_OK) {
        // R of the packed texture is unused by glTF (occlusion often lives there in ORM textures): 0.
        for (size_t i = 0; i < n; i++) {
            b.out_rgb2[3 * i] = 0.0f;
            b.out_rgb2[3 * i + 1] = b.out_scalar2[i];
            b.out_rgb2[3 * i + 2] = b.out_scalar[i];
        }
        const mr_gltf_texture_ref mapping = dref->index >= 0 ? *dref : *sref;
        const float *const rgb[2] = {b.out_rgb, b.out_rgb2}, *const fourth[2] = {has_alpha ? b.alpha : NULL, NULL};
        static const mr_img_encoding encodings[2] = {MR_IMG_COLOR, MR_IMG_DATA};
        static const char *const names[2] = {"basecolor", "metallicRoughness"};
        mr_gltf_texture_ref *const refs[2] = {&m.base_color_texture, &m.metallic_roughness_texture};
        status = add_converted_textures(asset, k, o, scratch, outbase, width, height, rgb, fourth, encodings, names,
                                        &mapping, refs);
        for (int c = 0; c < 4; c++) m.base_color_factor[c] = 1.0;
        m.metallic_factor = m.roughness_factor = 1.0;
        r->width = width;
        r->height = height;
    }
    m.has_spec_gloss = o->keep_specgloss;
    if (status == MR_OK) status = mr_gltf_set_material(asset, k, &m);
    r->kind = OUTCOME_CONVERTED;
    r->seconds = cli_now() - started;
    mr_image_free(dimg);
    mr_image_free(simg);
    buffers_free(&b);
    return status == MR_OK ? CLI_EXIT_OK : cli_fail("gltf", status);
}

static int metal2spec_material(mr_gltf *asset, int k, const options *o, const mr_wf_options *wf,
                               const char *scratch, const char *outbase, outcome *r) {
    mr_gltf_material m;
    mr_status status = mr_gltf_get_material(asset, k, &m);
    if (status != MR_OK) return cli_fail("gltf", status);
    if (m.has_spec_gloss) {
        snprintf(r->reason, sizeof r->reason, "it carries spec-gloss already");
        return CLI_EXIT_OK;
    }
    double started = cli_now();
    const mr_gltf_texture_ref *bref = &m.base_color_texture, *mref = &m.metallic_roughness_texture;
    mr_image *bimg = NULL, *mimg = NULL;
    int width = 1, height = 1;
    buffers b;
    mr_img_stored stored[2];
    int code = prepare(asset, k, m.name, bref, MR_IMG_COLOR, mref, MR_IMG_DATA, scratch, &bimg, &mimg, stored,
                       &width, &height, &b);
    if (code != CLI_EXIT_OK) return code;
    size_t n = (size_t)width * (size_t)height;
    int has_alpha = 0;
#pragma omp parallel for schedule(static) reduction(| : has_alpha)
    for (int y = 0; y < height; y++)
        for (int x = 0; x < width; x++) {
            size_t i = (size_t)y * (size_t)width + (size_t)x;
            for (int c = 0; c < 3; c++)
                b.in_rgb[3 * i + c] = (float)((bimg ? sample(bimg, c, x, y, width, height) : 1.0f) *
                                              m.base_color_factor[c]);
            // The base colour's alpha travels to the diffuse.
            b.alpha[i] = (float)((bimg ? sample(bimg, 3, x, y, width, height) : 1.0f) * m.base_color_factor[3]);
            has_alpha |= b.alpha[i] != 1.0f;
            b.in_scalar[i] = (float)((mimg ? sample(mimg, 2, x, y, width, height) : 1.0f) * m.metallic_factor);
            b.out_scalar2[i] = (float)((mimg ? sample(mimg, 1, x, y, width, height) : 1.0f) * m.roughness_factor);
        }
    mr_wf_metal_maps in = {b.in_rgb, b.in_scalar, b.out_scalar2};
    mr_wf_spec_maps out = {b.out_rgb, b.out_rgb2, b.out_scalar};
    status = mr_wf_metal_to_spec_batch(&in, n, wf, &out, b.flags);
    if (status == MR_OK) count_flags(r, b.flags, n);
    for (size_t i = 0; status == MR_OK && i < n; i++) b.out_scalar[i] = 1.0f - b.out_scalar[i]; // glossiness
    if (status == MR_OK && bimg == NULL && mimg == NULL) {
        for (int c = 0; c < 3; c++) {
            m.diffuse_factor[c] = b.out_rgb[c];
            m.specular_factor[c] = b.out_rgb2[c];
        }
        m.diffuse_factor[3] = b.alpha[0];
        m.glossiness_factor = b.out_scalar[0];
        mr_gltf_texture_ref_none(&m.diffuse_texture);
        mr_gltf_texture_ref_none(&m.specular_glossiness_texture);
    } else if (status == MR_OK) {
        const mr_gltf_texture_ref mapping = bref->index >= 0 ? *bref : *mref;
        // RGB specular sRGB-encoded, A glossiness linear: what the image writer does for a colour image with alpha.
        const float *const rgb[2] = {b.out_rgb, b.out_rgb2};
        const float *const fourth[2] = {has_alpha ? b.alpha : NULL, b.out_scalar};
        static const mr_img_encoding encodings[2] = {MR_IMG_COLOR, MR_IMG_COLOR};
        static const char *const names[2] = {"diffuse", "specularGlossiness"};
        mr_gltf_texture_ref *const refs[2] = {&m.diffuse_texture, &m.specular_glossiness_texture};
        status = add_converted_textures(asset, k, o, scratch, outbase, width, height, rgb, fourth, encodings, names,
                                        &mapping, refs);
        for (int c = 0; c < 4; c++) m.diffuse_factor[c] = 1.0;
        for (int c = 0; c < 3; c++) m.specular_factor[c] = 1.0;
        m.glossiness_factor = 1.0;
        r->width = width;
        r->height = height;
    }
    m.has_spec_gloss = 1; // the core material stays as the fallback
    if (status == MR_OK) status = mr_gltf_set_material(asset, k, &m);
    r->kind = OUTCOME_CONVERTED;
    r->seconds = cli_now() - started;
    mr_image_free(bimg);
    mr_image_free(mimg);
    buffers_free(&b);
    return status == MR_OK ? CLI_EXIT_OK : cli_fail("gltf", status);
}

/* ---- the command -------------------------------------------------------------------------------------------- */

static int parse(int argc, char **argv, options *o) {
    for (int i = 1; i < argc; i++) {
        const char *value = NULL;
        int taken;
        if ((taken = cli_take_option("gltf", argc, argv, &i, "--output", &value)) ||
            (taken = cli_take_option("gltf", argc, argv, &i, "-o", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            o->output = value;
        } else if ((taken = cli_take_option("gltf", argc, argv, &i, "--method", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            o->method = value;
        } else if ((taken = cli_take_option("gltf", argc, argv, &i, "--weights", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            o->weights = value;
        } else if ((taken = cli_take_option("gltf", argc, argv, &i, "--format", &value))) {
            if (taken < 0) return CLI_EXIT_USAGE;
            if (strcmp(value, "png") != 0 && strcmp(value, "exr") != 0)
                return cli_usage_error("gltf", "--format '%s': expected png or exr", value);
            o->format = value;
        } else if ((taken = cli_take_option("gltf", argc, argv, &i, "--convention", &value))) {
            if (taken < 0 || !cli_parse_convention("gltf", value, &o->convention)) return CLI_EXIT_USAGE;
        } else if ((taken = cli_take_option("gltf", argc, argv, &i, "--fallback", &value))) {
            return cli_usage_error("gltf", "--fallback is gone: a material's own metal-rough values are kept by "
                                   "default; --overwrite-metal-rough converts them instead");
        } else if ((taken = cli_take_option("gltf", argc, argv, &i, "--eps", &value))) {
            if (taken < 0 || !cli_parse_double("gltf", "--eps", value, 0.0, 0.5, &o->eps)) return CLI_EXIT_USAGE;
            o->eps_given = 1;
        } else if ((taken = cli_take_option("gltf", argc, argv, &i, "--threads", &value))) {
            if (taken < 0 || !cli_parse_int("gltf", "--threads", value, 0, 1024, &o->threads)) return CLI_EXIT_USAGE;
        } else if (strcmp(argv[i], "--overwrite-metal-rough") == 0) {
            o->overwrite = 1;
        } else if (strcmp(argv[i], "--keep-specgloss") == 0) {
            o->keep_specgloss = 1;
        } else if (strcmp(argv[i], "--keep-unused") == 0) {
            o->keep_unused = 1;
        } else if (strcmp(argv[i], "--json") == 0) {
            o->json = 1;
        } else if (argv[i][0] == '-') {
            return cli_usage_error("gltf", "unknown option '%s'", argv[i]);
        } else if (o->direction == NULL) {
            o->direction = argv[i];
        } else if (o->input == NULL) {
            o->input = argv[i];
        } else {
            return cli_usage_error("gltf", "unexpected argument '%s' (one input asset)", argv[i]);
        }
    }
    if (o->direction == NULL) return cli_usage_error("gltf", "missing spec2metal or metal2spec");
    int to_metal = strcmp(o->direction, "spec2metal") == 0;
    if (!to_metal && strcmp(o->direction, "metal2spec") != 0)
        return cli_usage_error("gltf", "'%s': expected spec2metal or metal2spec", o->direction);
    if (o->input == NULL) return cli_usage_error("gltf", "missing the input asset (.gltf or .glb)");
    if (o->output == NULL) return cli_usage_error("gltf", "missing -o OUT (.gltf or .glb)");
    if (o->method == NULL) o->method = to_metal ? "mlp" : "eq2";
    if (o->format == NULL) o->format = "png";
    if (!to_metal && (o->weights || o->overwrite || o->keep_specgloss || o->eps_given))
        return cli_usage_error("gltf", "--weights, --eps, --overwrite-metal-rough and --keep-specgloss go with "
                               "spec2metal");
    if (o->eps_given && (strcmp(o->method, "mlp") == 0 || strcmp(o->method, "extension") == 0))
        return cli_usage_error("gltf", "--eps applies to the analytic methods (weighted, mean, khronos); --method %s "
                               "computes no off-manifold flag", o->method);
    return CLI_EXIT_OK;
}

/* The output's file name without folder and extension: the stem of the new textures' names. */
static void output_stem(const char *output, char *stem, size_t size) {
    const char *slash = strrchr(output, '/');
    snprintf(stem, size, "%s", slash ? slash + 1 : output);
    char *dot = strrchr(stem, '.');
    if (dot != NULL && dot != stem) *dot = '\0';
}

/* The folder of the output, where the new textures are staged before the asset copies them beside it. */
static void output_folder(const char *output, char *folder, size_t size) {
    const char *slash = strrchr(output, '/');
    if (slash == NULL)
        snprintf(folder, size, ".");
    else
        snprintf(folder, size, "%.*s", (int)(slash - output), output);
}

int cmd_gltf(int argc, char **argv) {
    for (int i = 1; i < argc; i++)
        if (cli_is_help(argv[i])) {
            print_help();
            return CLI_EXIT_OK;
        }
    options o;
    memset(&o, 0, sizeof o);
    o.convention = MR_WF_DIFFUSE_SPECGLOSS;
    int code = parse(argc, argv, &o);
    if (code != CLI_EXIT_OK) return code;
    int to_metal = strcmp(o.direction, "spec2metal") == 0;

    mr_wf_options wf = mr_wf_options_default();
    wf.spec_diffuse = o.convention;
    wf.threads = o.threads;
    if (o.eps_given) wf.eps = o.eps;
    int use_mlp = to_metal && strcmp(o.method, "mlp") == 0;
    if (to_metal && strcmp(o.method, "extension") == 0) {
        // no converter: the material is rewritten with extensions (extension_material)
    } else if (to_metal && !use_mlp) {
        if (mr_wf_method_from_name(o.method, &wf.method) != MR_OK || wf.method == MR_WF_CUSTOM)
            return cli_usage_error("gltf", "--method '%s': expected mlp, weighted, mean, khronos or extension",
                                   o.method);
    } else if (!to_metal) {
        if (strcmp(o.method, "khronos") == 0)
            wf.method = MR_WF_KHRONOS;
        else if (strcmp(o.method, "eq2") != 0)
            return cli_usage_error("gltf", "--method '%s': expected eq2 or khronos", o.method);
    }

    mr_mlp *net = NULL;
    char net_path[PATH_SIZE] = "";
    if (use_mlp) code = cli_load_network("gltf", o.weights, &net, net_path, sizeof net_path);
    mr_gltf *asset = NULL;
    if (code == CLI_EXIT_OK) {
        mr_status status = mr_gltf_load(o.input, &asset);
        if (status != MR_OK) code = cli_fail("gltf", status);
    }
    // New textures are staged in a scratch folder beside the output; the asset copies them when it is saved.
    char folder[PATH_SIZE], scratch[PATH_SIZE], stem[PATH_SIZE];
    output_folder(o.output, folder, sizeof folder);
    output_stem(o.output, stem, sizeof stem);
    scratch[0] = '\0';
    if (code == CLI_EXIT_OK) {
        int length = snprintf(scratch, sizeof scratch, "%s/.matremap-gltf-XXXXXX", folder);
        if (length < 0 || (size_t)length >= sizeof scratch || mkdtemp(scratch) == NULL) {
            fprintf(stderr, "matremap gltf: error: cannot write in '%s': %s\n", folder, strerror(errno));
            scratch[0] = '\0';
            code = CLI_EXIT_BAD_INPUT;
        }
    }
    double started = cli_now();
    mr_gltf_counts counts = {0};
    if (asset) mr_gltf_get_counts(asset, &counts);
    outcome *outcomes = calloc((size_t)(counts.materials > 0 ? counts.materials : 1), sizeof *outcomes);
    if (outcomes == NULL && code == CLI_EXIT_OK) code = CLI_EXIT_INTERNAL;
    int converted = 0, kept = 0;
    for (int k = 0; k < counts.materials && code == CLI_EXIT_OK; k++) {
        code = to_metal ? spec2metal_material(asset, k, &o, net, &wf, scratch, stem, &outcomes[k])
                        : metal2spec_material(asset, k, &o, &wf, scratch, stem, &outcomes[k]);
        converted += code == CLI_EXIT_OK && outcomes[k].kind == OUTCOME_CONVERTED;
        kept += code == CLI_EXIT_OK && outcomes[k].kind == OUTCOME_KEPT;
    }
    // The off-manifold tolerance, where one is computed (analytic spec2metal methods).
    const char *tolerance = !to_metal || use_mlp || strcmp(o.method, "extension") == 0 ? NULL
                            : o.eps_given ? "eps" : "encoding";
    mr_gltf_prune_stats pruned = {0};
    if (code == CLI_EXIT_OK && !o.keep_unused) {
        // Converted materials no longer point at their old textures (spec2metal's diffuse and
        // specular-glossiness ones, the replaced core ones); left in, they are dead files beside the output and
        // the validator's UNUSED_OBJECT infos.
        mr_status status = mr_gltf_prune_unused(asset, &pruned);
        if (status != MR_OK) code = cli_fail("gltf", status);
    }
    if (code == CLI_EXIT_OK) {
        // Spec-gloss kept beside a new core material (--keep-specgloss, or metal2spec's fallback): engines without
        // the extension read the core material, so it must not be required (FloppyDisk requires it).
        mr_status status = MR_OK;
        if (o.keep_specgloss || !to_metal)
            status = mr_gltf_set_extension_required(asset, "KHR_materials_pbrSpecularGlossiness", 0);
        mr_gltf_sync_extensions(asset);
        if (status == MR_OK) status = mr_gltf_save(asset, o.output);
        if (status != MR_OK) code = cli_fail("gltf", status);
    }
    double seconds = cli_now() - started;
    if (code == CLI_EXIT_OK && !o.json) {
        for (int k = 0; k < counts.materials; k++) {
            const outcome *r = &outcomes[k];
            mr_gltf_material m;
            mr_gltf_get_material(asset, k, &m);
            printf("material %d '%s': ", k, m.name);
            if (r->kind == OUTCOME_KEPT) {
                printf("kept, not converted: %s; its spec-gloss extension %s; --overwrite-metal-rough converts it "
                       "instead\n", r->reason, o.keep_specgloss ? "kept (--keep-specgloss)" : "removed");
                continue;
            }
            if (r->kind == OUTCOME_SKIPPED) {
                printf("left as it is: %s\n", r->reason);
                continue;
            }
            printf("converted, ");
            if (r->width > 0)
                printf("%dx%d textures", r->width, r->height);
            else
                printf("factors only");
            printf(", %zu texel%s flagged", r->flagged, r->flagged == 1 ? "" : "s");
            if (r->flagged > 0) {
                printf(" (");
                if (tolerance) printf("%zu off-manifold, ", r->off_manifold);
                printf("%zu non-finite input, %zu clamped input", r->nonfinite, r->clamped);
                if (r->failed) printf(", %zu method failed", r->failed);
                printf(")");
            }
            printf(", %.3f s\n", r->seconds);
        }
        printf("gltf %s: %d of %d materials converted", o.direction, converted, counts.materials);
        if (kept > 0) printf(", %d kept with metal-rough values of %s own", kept, kept == 1 ? "its" : "their");
        printf(" with %s%s%s", o.method, use_mlp ? " " : "", use_mlp ? net_path : "");
        if (tolerance && o.eps_given)
            printf(" (off-manifold tolerance %g)", o.eps);
        else if (tolerance)
            printf(" (off-manifold tolerance: half a code value of each texture, times its factor)");
        printf(" in %.2f s; wrote %s\n", seconds, o.output);
        if (o.keep_unused) {
            printf("unreferenced textures, images and samplers kept (--keep-unused)\n");
        } else {
            printf("pruned %d texture%s, %d image%s and %d sampler%s that nothing refers to", pruned.textures,
                   pruned.textures == 1 ? "" : "s", pruned.images, pruned.images == 1 ? "" : "s", pruned.samplers,
                   pruned.samplers == 1 ? "" : "s");
            if (pruned.uncertain > 0)
                printf(" (%d kept that only extensions or extras this tool cannot read may refer to)",
                       pruned.uncertain);
            printf("\n");
        }
    } else if (code == CLI_EXIT_OK) {
        static const char *const kinds[] = {"skipped", "converted", "kept"};
        printf("{\"command\": \"gltf %s\", \"input\": ", o.direction);
        cli_json_string(stdout, o.input);
        printf(", \"output\": ");
        cli_json_string(stdout, o.output);
        printf(", \"method\": \"%s\", \"seconds\": %.6f, \"tolerance\": ", o.method, seconds);
        if (tolerance)
            printf("\"%s\", \"eps\": %.17g", tolerance, o.eps_given ? o.eps : MR_WF_DEFAULT_EPS);
        else
            printf("null, \"eps\": null");
        for (int kind = OUTCOME_CONVERTED; kind <= OUTCOME_KEPT; kind++) {
            printf(", \"%s\": [", kinds[kind]);
            for (int k = 0, first = 1; k < counts.materials; k++)
                if (outcomes[k].kind == (outcome_kind)kind) {
                    printf("%s%d", first ? "" : ", ", k);
                    first = 0;
                }
            printf("]");
        }
        printf(", \"materials\": [");
        for (int k = 0; k < counts.materials; k++) {
            const outcome *r = &outcomes[k];
            mr_gltf_material m;
            mr_gltf_get_material(asset, k, &m);
            printf("%s{\"index\": %d, \"name\": ", k ? ", " : "", k);
            cli_json_string(stdout, m.name);
            printf(", \"outcome\": \"%s\", \"reason\": ", kinds[r->kind]);
            if (r->kind == OUTCOME_CONVERTED)
                printf("null");
            else
                cli_json_string(stdout, r->reason);
            printf(", \"width\": %d, \"height\": %d, \"flagged\": %zu, \"flags\": {\"off_manifold\": ", r->width,
                   r->height, r->flagged);
            if (tolerance && r->kind == OUTCOME_CONVERTED)
                printf("%zu", r->off_manifold);
            else
                printf("null");
            printf(", \"nonfinite_input\": %zu, \"clamped_input\": %zu, \"method_failed\": %zu}, \"seconds\": %.6f}",
                   r->nonfinite, r->clamped, r->failed, r->seconds);
        }
        printf("], \"keep_unused\": %s, \"pruned\": {\"textures\": %d, \"images\": %d, \"samplers\": %d, "
               "\"uncertain\": %d}}\n", o.keep_unused ? "true" : "false", pruned.textures, pruned.images,
               pruned.samplers, pruned.uncertain);
    }
    if (scratch[0] != '\0') rmdir(scratch);
    free(outcomes);
    mr_gltf_free(asset);
    mr_mlp_free(net);
    return code;
}
