/*
 * learned.h — transforms learned from sweeps (paper sections 5-7): a regression from a source BRDF model's
 * parameters to a target model's, trained on uniform remaps (sweep_table.h), written to and read from versioned
 * text files (.mrt) that round-trip exactly, applied per texel to whole texture sets, and composed into chains.
 *
 * Main calls:
 *   mr_sweep_table rows;  mr_sweep_table_load(files, 2, NULL, &rows);
 *   mr_learn_options o = {0};  o.method = MR_LEARN_PARAMETRIC;           // zero = defaults
 *   mr_learned *t;  mr_learn(&rows, &o, &t);
 *   mr_learned_write(t, "ward-ggx.mrt");                                    // atomic, exact
 *   mr_learned_read("ward-ggx.mrt", &t2);                                   // errors name file and line
 *   mr_learned_apply(t, source_values, target_values, &flags);             // one texel, packed vectors
 *   mr_learned_free(t);
 * Converting a material (convert's job): mr_learned_set_add_file / mr_learned_set_add_folder, mr_learned_find_chain
 * or mr_learned_check_ends, mr_learned_convert_material, mr_learned_explain_texel (below).
 *
 * What a transform does with one texel (source packed values v -> target packed values w):
 *   1. w = base: the target values every transform writes where it learned nothing (the sweeps' fixed target
 *      values: switches, fixed extension factors, parameters held constant in every row).
 *   2. carries: w[target parameter] = factor * v[source parameter], per channel: a lobe the sweeps did not vary
 *      (a diffuse albedo held at 0 while the specular was swept) is carried by the ratio of the two models'
 *      Lambertian lobes (both parameters linear in f_r and direction-independent; factor = f_src(1) / f_tgt(1)), or,
 *      when the rows vary it and the method is parametric, by a per-channel slope fitted on the rows. When the rows
 *      hold the source parameter but the fits still vary the target one (a diffuse standing in for a lobe's tail),
 *      the carried parameter is also an output, learned on what the carry leaves, and added to it.
 *   3. the regression: features (source parameters the sweeps varied) -> outputs (target parameters that varied
 *      by more than 1e-5 of their range: the solver's residue on a lobe the source lacks, 1e-12 .. 1e-7, is not):
 *      - a SCALAR feature is a one-channel parameter; a GREY feature an RGB parameter every row held grey (r = g = b,
 *        as a grid axis sweeps it): it enters the regression as one number, and the regression is evaluated once
 *        per channel, channel c of every GREY feature in, channel c of every GREY output out (the paper's per-channel
 *        use of its sweeps); SCALAR and CHANNEL outputs come from one evaluation at the mean of each GREY feature's
 *        channels. A CHANNEL feature is one channel of an RGB parameter the rows varied per channel.
 *      - PARAMETRIC (section 7): exactly two features, the source roughness (SCALAR) and specular (GREY or SCALAR),
 *        and two outputs, the target roughness and specular: roughness' = polynomial(roughness) (degree <= 4, through
 *        the origin by default, as the authors' fit), specular'_c = k(roughness) specular_c with
 *        k(a) = c0 + c1 e^(-c2 a) + c3 e^(-c4 a^2) [+ c5 / a] (parametric.h says how it is fitted well-conditioned):
 *        one slope for the three channels, so chromaticity is kept, and linear extrapolation beyond the rows. A third
 *        output, a carried diffuse the fits add to, is diffuse'_c = carry + k_d(roughness) specular_c (same form).
 *      - SVR: one epsilon-SVR with an RBF kernel per output (svr.h), inputs and outputs normalised.
 *      - MLP: one hidden ReLU layer (nn/mlp.h), every output at once.
 *   4. outputs are clamped into the target parameters' ranges; a clamp sets MR_WF_CLAMPED_OUTPUT; a feature
 *      outside its training domain [min, max] (every channel of a GREY feature) sets MR_WF_EXTRAPOLATED (the paper's
 *      Fig. 19 failure is extrapolation); a non-finite input is read as the parameter's minimum and sets
 *      MR_WF_NONFINITE_INPUT, one outside its range is clamped and sets MR_WF_CLAMPED_INPUT.
 * A chain (mr_learned_chain_apply) runs transforms one after the other, each hop's target the next one's source,
 * flags or'ed.
 *
 * Validation. mr_learn splits the rows by a seeded shuffle (validation_fraction held out, default 0.2), fits on the
 * rest, measures each output's RMSE on the held-out rows (raw units; a GREY output over its three channel
 * evaluations), then (parametric, svr) refits on every row for the transform it returns; the MLP keeps the network
 * early stopping chose on the held-out rows. The figures are stored in the file.
 *
 * The file (mr_learned_write / mr_learned_read), version 1. Text, '\n' line ends, one key per line followed by
 * values separated by single spaces; numbers C99 hexadecimal floats ("%a": exact), counts decimal. Lines starting
 * with '#' are comments the writer adds for people (coefficients in decimal) and the reader skips. Keys in order:
 *   matremap-transform 1
 *   source MODEL                         target MODEL                 method parametric|svr|mlp
 *   features N   then N lines: feature PARAM scalar|grey|channel C MIN MAX
 *   outputs N    then N lines: output PARAM scalar|grey|channel C
 *   base V1 ... Vk                       (k = the target's packed value count)
 *   carries N    then N lines: carry TARGET_PARAM SOURCE_PARAM learned|lobes F_R [F_G F_B]
 *   validation FRACTION SEED TRAIN_ROWS VALIDATION_ROWS
 *   rmse R1 ... RN                       (one per output, raw units)
 *   check ROWS PASSED DSSIM_MEAN DSSIM_P90 MEDIAN1 P90_1 ... MEDIANN P90_N   (version 2; mr_learned_check;
 *                                        ROWS 0: not checked, PASSED 0 or 1, a NaN dSSIM written as "nan")
 *   provenance N then N lines: | TEXT    (the sweeps' files, row counts and header lines)
 *   the method's block: parametric: "roughness DEGREE ORIGIN C0 .. C4", "slope INVERSE C0 .. C5" and, with a
 *     third output, "diffuse_slope INVERSE C0 .. C5";
 *     svr: "svr N_IN N_OUT", "in_mean", "in_std", "out_mean", "out_std" lines, then per output
 *     "model SV_COUNT GAMMA C EPSILON RHO VALIDATION_RMSE GRID_RMSE" and SV_COUNT lines "sv COEF X1 .. XN_IN";
 *     mlp: "mlp LINES" then LINES lines holding a matremap-mlp weight file (nn/mlp.h)
 *   checksum XXXXXXXX                    (FNV-1a 32 of every byte before this line, hex)
 *   end
 * The reader checks everything: magic and version, registered models, parameter names and channel counts against
 * the models, domains (min <= max, finite), counts against limits, every number finite, the method block's sizes,
 * the checksum (a file edited or damaged after it was written is refused: "checksum mismatch"), and nothing after
 * "end"; any fault is MR_ERR_FORMAT naming the file, the line and what was expected. Writing then reading gives a
 * transform whose every number has the same bits, and writing that again gives the same bytes.
 *
 * Threads: a transform is immutable once made; apply may run on several threads at once. Ownership: one owner,
 * one free (mr_learned_free, NULL-safe). Nothing is printed.
 */
#ifndef MR_LEARN_LEARNED_H
#define MR_LEARN_LEARNED_H

#include <stddef.h>

#include "../brdf/brdf.h"
#include "../mr_status.h"
#include "../remap/direct.h"
#include "../render/render.h"
#include "../transform/transform.h"
#include "parametric.h"
#include "sweep_table.h"

#ifdef __cplusplus
extern "C" {
#endif

#define MR_LEARNED_FILE_MAGIC "matremap-transform"
#define MR_LEARNED_FILE_VERSION 2 /* 2 adds the check line; version 1 files are read as unchecked */
#define MR_LEARNED_MAX_SLOTS MR_BRDF_MAX_VALUES /* features, outputs */
#define MR_LEARNED_MAX_PROVENANCE 4096          /* provenance lines kept */
#define MR_LEARNED_MAX_HOPS 8                    /* transforms in one chain */

/* Flags a texel may get from a learned transform, beyond workflow.h's mr_wf_flag bits (which share the byte). */
enum {
    MR_WF_EXTRAPOLATED = 1u << 4,   /* a feature lay outside the transform's training domain */
    MR_WF_CLAMPED_OUTPUT = 1u << 5, /* an output left the target parameter's range and was clamped */
    MR_WF_UNCHECKED = 1u << 7       /* the transform failed its check against the remaps (mr_learned_check) */
};

/* The colour code of a model-to-model conversion's flag picture (convert's PREFIX_flags.png; transform.h, "flags"):
 * one channel per kind of reason, each 1 where the texel has one: red extrapolated (MR_WF_EXTRAPOLATED), not
 * converged (--direct's MR_WF_UNCONVERGED, remap/direct.h) or converted by a transform that failed its check
 * (MR_WF_UNCHECKED); green clamped output; blue clamped or non-finite input. */
extern const mr_flag_code mr_learned_flag_code;

typedef enum mr_learn_method {
    MR_LEARN_PARAMETRIC = 0,
    MR_LEARN_SVR,
    MR_LEARN_MLP,
    MR_LEARN_METHOD_COUNT
} mr_learn_method;

/* "parametric", "svr", "mlp"; NULL outside the enum. */
const char *mr_learn_method_name(mr_learn_method method);
/* MR_ERR_INVALID_ARG naming the valid names for an unknown one. */
mr_status mr_learn_method_from_name(const char *name, mr_learn_method *out);

typedef enum mr_learned_slot_kind {
    MR_LEARNED_SCALAR = 0, /* a one-channel parameter */
    MR_LEARNED_GREY,       /* an RGB parameter as one number, evaluated per channel */
    MR_LEARNED_CHANNEL     /* one channel of an RGB parameter */
} mr_learned_slot_kind;

typedef struct mr_learned_slot {
    int param;                 /* the parameter's index in its model */
    mr_learned_slot_kind kind;
    int channel;               /* CHANNEL: 0, 1 or 2; else 0 */
    double min, max;           /* features: the training domain; outputs: 0 */
} mr_learned_slot;

/* A slot's name, as learn's summary and its JSON keys give it: the parameter's name in `model` (the transform's
 * source for a feature, its target for an output), with "_r", "_g" or "_b" for one channel of an RGB parameter
 * (MR_LEARNED_CHANNEL: f0_g); into buf (size bytes, truncated if need be). Returns buf. */
const char *mr_learned_slot_name(const mr_brdf_model *model, const mr_learned_slot *slot, char *buf, size_t size);

typedef struct mr_learned_carry {
    int target_param, source_param; /* the same channel count */
    int learned;                    /* 1: the factors were fitted on rows; 0: the ratio of the models' lobes */
    double factor[3];               /* per channel (one for scalars) */
} mr_learned_carry;

struct mr_svr;
struct mr_mlp;

/* The check of a transform against the remaps themselves (the answers of `convert --direct`, without its
 * quantisation) on the held-out rows, in the units a user reads (docs/learn.md, "The check"):
 *   - per output, the relative error |learned - remap| / max(|remap|, MR_LEARNED_CHECK_FLOOR min(1, range)) per
 *     row and channel (the floor: near black, a small absolute error is no error a user sees)
 *     (a roughness output skips the rows whose roughness the fit scene only bounds: outcome under-resolved), its
 *     median and 90th percentile;
 *   - dSSIM: the remap's own SSIM to the source's render (the row's ssim) less the learned answer's, both in the
 *     rows' fit scene, over at most MR_LEARNED_CHECK_MAX_RENDERS held-out rows: its mean and 90th percentile.
 * A transform passes when every output's 90th percentile is at most MR_LEARNED_MAX_RELATIVE_ERROR and the dSSIM's
 * at most MR_LEARNED_MAX_DSSIM: then 9 texels in 10 of a texture set inside its domain come within those bounds of
 * what --direct gives. `learn` warns about a transform that fails; `convert` warns too and flags every texel it
 * converts with it (MR_WF_UNCHECKED). */
#define MR_LEARNED_MAX_RELATIVE_ERROR 0.10
#define MR_LEARNED_CHECK_FLOOR 0.05
#define MR_LEARNED_MAX_DSSIM 0.02
#define MR_LEARNED_CHECK_MAX_RENDERS 256

typedef struct mr_learned_check {
    int done;                                    /* 0: not checked (a version 1 file); the rest is then 0 */
    int passed;                                  /* 1: within both bounds */
    long rows;                                   /* held-out rows checked */
    double relative_median[MR_LEARNED_MAX_SLOTS]; /* per output */
    double relative_p90[MR_LEARNED_MAX_SLOTS];
    double dssim_mean, dssim_p90;                /* NaN when the rows' fit scene could not be rendered */
} mr_learned_check;

typedef struct mr_learned {
    const mr_brdf_model *source, *target;
    mr_learn_method method;
    int feature_count, output_count, carry_count;
    mr_learned_slot features[MR_LEARNED_MAX_SLOTS];
    mr_learned_slot outputs[MR_LEARNED_MAX_SLOTS];
    mr_learned_carry carries[MR_LEARNED_MAX_SLOTS];
    double base[MR_BRDF_MAX_VALUES];               /* target packed values */
    double validation_fraction;
    unsigned long long seed;
    long train_rows, validation_rows;
    double rmse[MR_LEARNED_MAX_SLOTS];             /* per output, on the held-out rows, raw units */
    mr_learned_check check;                        /* against the remaps on the held-out rows */
    char *provenance;                              /* '\n'-terminated lines */
    /* PARAMETRIC */
    int roughness_degree, roughness_origin;
    double roughness[MR_POLY_MAX_DEGREE + 1];
    mr_specular_slope slope;
    mr_specular_slope diffuse_slope;               /* a third output (a carried diffuse the fits add to): k_d */
    /* SVR, MLP (owned) */
    struct mr_svr *svr;
    struct mr_mlp *mlp;
} mr_learned;

/* Options of mr_learn; zero = the defaults given. */
typedef struct mr_learn_options {
    mr_learn_method method;        /* PARAMETRIC */
    double validation_fraction;    /* 0 = 0.2; in (0, 0.5] */
    unsigned long long seed;       /* 0 = 1 */
    int roughness_degree;          /* PARAMETRIC: 0 = 4; 1 .. 4 */
    int roughness_intercept;       /* PARAMETRIC: 1 fits a constant term too; default 0 (through the origin) */
    int slope_inverse;             /* PARAMETRIC: 0 = automatic (the c5 / alpha term kept when it lowers the
                                      held-out error), 1 = always, -1 = never */
    int threads;                   /* SVR's search, MLP's training: 0 = automatic (mr_svr_train_options.threads,
                                      mr_mlp_train_options.threads: all cores) */
    int mlp_hidden;                /* MLP: 0 = 64 */
    int mlp_max_epochs;            /* MLP: 0 = 2000 */
    double svr_C, svr_gamma, svr_epsilon; /* SVR: > 0 fixes that hyper-parameter for every output (normalised
                                      units, svr.h) and leaves it out of the search; 0 = searched */
    void (*progress)(const char *stage, double fraction, void *user); /* optional, from the calling thread */
    void *progress_user;
} mr_learn_options;

/* Learn a transform from the rows of t. MR_ERR_INVALID_ARG naming what is wrong: too few rows, nothing varied, a
 * pair whose data does not have the parametric shape (a source specular parameter that is not linear in f_r, such
 * as an IOR: the paper changes variable with its Eq. 1 first; more varied parameters than roughness and specular),
 * options out of range. *out is set only on success. */
mr_status mr_learn(const mr_sweep_table *t, const mr_learn_options *opts, mr_learned **out);

/* One texel: source packed values in (mr_brdf_value_count(t->source)), target packed values out; *flags (may be
 * NULL) gets the MR_WF_* bits. Reentrant; it allocates scratch, and should that fail, writes the target's defaults
 * and sets MR_WF_METHOD_FAILED. */
void mr_learned_apply(const mr_learned *t, const double *source_values, double *target_values, unsigned *flags);

/* n texels at once (rows of packed values; flags may be NULL): the same values as n calls of mr_learned_apply, faster
 * (the regression runs on many rows per call). Runs on the calling thread. MR_ERR_NOMEM, MR_ERR_INVALID_ARG. */
mr_status mr_learned_apply_batch(const mr_learned *t, size_t n, const double *source_values, double *target_values,
                                 unsigned *flags);

/* Hops t[0], t[1], ... (t[i]->target == t[i+1]->source); flags or'ed over the hops. MR_ERR_INVALID_ARG when the
 * models do not connect. */
mr_status mr_learned_chain_apply(const mr_learned *const *t, int hops, const double *source_values,
                                 double *target_values, unsigned *flags);
/* The chain on n texels at once (as mr_learned_apply_batch). */
mr_status mr_learned_chain_apply_batch(const mr_learned *const *t, int hops, size_t n, const double *source_values,
                                       double *target_values, unsigned *flags);

/* The held-out RMSE summed over outputs in units of each target parameter's range (for choosing among chains). */
double mr_learned_error(const mr_learned *t);

/* The chain from `source` to `target` through `via[0..via_count)` (models to pass, in order; may be 0) among
 * `all[0..n)`: fewest hops, then the least summed mr_learned_error (ties: the lower indices). path[] receives the
 * indices into all[] of the hops, *hops their count (<= MR_LEARNED_MAX_HOPS). MR_ERR_INVALID_ARG naming the pair
 * and listing the transforms' pairs when no chain exists. */
mr_status mr_learned_find_chain(const mr_learned *const *all, int n, const mr_brdf_model *source,
                                const mr_brdf_model *target, const mr_brdf_model *const *via, int via_count,
                                int *path, int *hops);

/* A transform kind (transform.h) applying the chain hops[0..count) per texel: its inputs are every parameter of the
 * first hop's source (optional: a missing map is the model's default), its outputs every parameter of the last hop's
 * target, flags MR_TRANSFORM_PER_TEXEL (repeated texels converted once). Use it with mr_transform_create and
 * mr_transform_convert_maps. The kind borrows the hops (they must outlive it and every transform made from it) and
 * is freed by mr_learned_kind_free. MR_ERR_INVALID_ARG for hops that do not connect or a model with more than
 * MR_TRANSFORM_MAX_SLOTS parameters. */
mr_status mr_learned_kind_create(const mr_learned *const *hops, int count, mr_transform_kind **out);
void mr_learned_kind_free(mr_transform_kind *kind);

/* ---- converting a material: `matremap convert` as library calls (learned_convert.c) ---------------------------
 *   mr_learned_set set = {0};
 *   mr_learned_set_add_folder(&set, "transforms", NULL);                  // every *.mrt, sorted by name
 *   int path[MR_LEARNED_MAX_HOPS], hops;
 *   mr_learned_find_chain((const mr_learned *const *)set.all, set.count, ward, ggx, NULL, 0, path, &hops);
 *   const mr_learned *chain[MR_LEARNED_MAX_HOPS];  for (h ...) chain[h] = set.all[path[h]];
 *   const char *a[] = {"alpha=@rough.exr", "specular=@spec.png"};
 *   const char *outputs[] = {"out/ggx_alpha.exr", ..., "out/ggx_flags.png"};  // one per target parameter + flags
 *   mr_learned_conversion_spec spec = {.source = ward, .target = ggx, .chain = chain, .hops = hops,
 *                                      .assignments = a, .assignment_count = 2, .outputs = outputs};
 *   mr_learned_conversion r;  mr_learned_convert_material(&spec, &r);   ... r.extrapolated ...
 *   mr_learned_conversion_free(&r);  mr_learned_set_free(&set);
 */

/* Transforms read from files, with the names they were read by (messages, summaries). Zeroed = empty; one owner,
 * freed by mr_learned_set_free (the set's transforms with it). */
#define MR_LEARNED_SET_MAX 256
typedef struct mr_learned_set {
    int count;
    mr_learned *all[MR_LEARNED_SET_MAX];
    char *paths[MR_LEARNED_SET_MAX]; /* as read: the path given, or FOLDER/NAME */
} mr_learned_set;

/* Read the transform at `path` (mr_learned_read) and add it to the set. Errors: mr_learned_read's;
 * MR_ERR_INVALID_ARG "more than 256 transforms"; MR_ERR_NOMEM. The set is unchanged on failure. */
mr_status mr_learned_set_add_file(mr_learned_set *set, const char *path);

/* Add every file of the folder `dir` whose name ends in ".mrt", in the order of their names (strcmp), so that the
 * chain chosen among equals (mr_learned_find_chain) does not depend on the folder's order; at most
 * MR_LEARNED_SET_MAX names are taken, in the order the folder lists them. `label` names the folder in messages (NULL:
 * "folder 'DIR'"). Errors: MR_ERR_IO "LABEL: <the system's reason>" when the folder cannot be opened, "LABEL: no
 * *.mrt files there"; the first file that cannot be read (mr_learned_read's error; the files before it stay added). */
mr_status mr_learned_set_add_folder(mr_learned_set *set, const char *dir, const char *label);

/* Frees every transform and name of the set and empties it (NULL-safe). */
void mr_learned_set_free(mr_learned_set *set);

/* A chain given hop by hop (names[h] names chain[h] in messages) must start at `source` and end at `target`: MR_OK,
 * or MR_ERR_INVALID_ARG "'NAME' converts A to B, but the conversion asked is C to D" naming the first hop when it
 * starts elsewhere, else the last. (Whether the hops connect is mr_learned_kind_create's check.) */
mr_status mr_learned_check_ends(const mr_learned *const *chain, const char *const *names, int hops,
                                const mr_brdf_model *source, const mr_brdf_model *target);

/* Called once per hop that raised a flag: hop (0-based; with no hops, 0: the direct remap) and its note. */
typedef void (*mr_learned_note_fn)(int hop, const char *note, void *user);

/* Why one converted texel was flagged: the chain chain[0..hops) is run again hop by hop on the texel
 * (mr_learned_apply: each hop's values and own flags; `flags`, the texel's flags from the conversion, count for the
 * first hop), and each hop that raised a flag gets one note: "the transform failed its check against the remaps
 * when it was learned", "extrapolated, outside its training domain: alpha 0.9 (trained on [0.01, 0.5])" (each
 * source parameter outside the domain, with its value and the domain), "clamped into its range: roughness 1 (range
 * [0, 1])" (each target parameter left on a bound of its range), "an input was clamped or not finite", joined by
 * "; ". With hops 0 (the direct remap, target_values the converted texel), one note for the conversion: "the fit did
 * not converge" and the clamped parameters. Values are packed (source_values mr_brdf_value_count(source) doubles,
 * target_values the target's); note_fn may be NULL. Nothing is printed. */
void mr_learned_explain_texel(const mr_learned *const *chain, int hops, const mr_brdf_model *source,
                              const double *source_values, const mr_brdf_model *target, const double *target_values,
                              unsigned flags, mr_learned_note_fn note_fn, void *user);

/* A material converted from one model to another: through a learned chain (hops >= 1) or, with hops 0, the direct
 * remap (mr_direct_kind_create: no regression, every distinct texel remapped). */
typedef struct mr_learned_conversion_spec {
    const mr_brdf_model *source, *target;
    const mr_learned *const *chain;      /* [hops], chain[0]->source == source ... (mr_learned_kind_create) */
    int hops;                            /* 0: the direct remap */
    const mr_direct_options *direct;     /* hops 0: its options (NULL = defaults; copied, its threads replaced by
                                            `threads`; with no map among the assignments and tolerance 0, the values
                                            are remapped exactly: MR_DIRECT_MIN_TOLERANCE) */
    const char *const *assignments;      /* the source material as mr_material_from_assignments takes it */
    int assignment_count;
    struct mr_material *material;        /* or, instead of assignments (count 0), a material of `source` made by
                                            the caller (a glTF material's, mr_gltf_material_brdf): TAKEN, the
                                            result owns it from the call on (freed with it, or on failure) */
    const char *const *outputs;          /* NULL: nothing written; else target->param_count + 1 file names: one per
                                            target parameter, then the flag picture. Written only when the material
                                            has maps */
    const char *output_label;            /* names the outputs in messages ("-o PREFIX"); may be NULL */
    int threads;                         /* 0 = automatic; the result does not depend on it */
} mr_learned_conversion_spec;

typedef struct mr_learned_conversion {
    mr_material *material;                        /* the source material read (its values: the constants) */
    mr_image *converted[MR_TRANSFORM_MAX_SLOTS];  /* one per target parameter; RGB ones carry the first map's alpha */
    uint8_t *flags;                               /* width x height MR_WF_* bytes */
    int width, height;                            /* 1 x 1 for constants alone */
    size_t texels;
    size_t extrapolated;    /* texels extrapolated (outside a transform's domain) or not converged (direct) */
    size_t clamped_output;  /* an output clamped into its range */
    size_t clamped_input;   /* an input clamped or not finite */
    size_t failed_check;    /* converted by a transform that failed its check (MR_WF_UNCHECKED) */
    size_t flagged;         /* any flag */
    int written;            /* the outputs and the flag picture were written */
    int converting;         /* the conversion ran (also set on failure: it may have reported progress) */
    double convert_seconds; /* the conversion itself */
    double seconds;         /* reading the material, converting, writing */
    int has_direct;         /* the direct remap's summary: */
    mr_direct_summary direct;
    double direct_tolerance;                      /* the quantisation step it used */
    mr_material_text_report material_report;     /* which assignment failed, and whether its text was at fault */
} mr_learned_conversion;

/* The job of `matremap convert`: the kind made (the chain's, or the direct remap's), the material read from its
 * assignments (mr_material_from_assignments), converted texel by texel (mr_transform_convert_material: repeated
 * texels once, the first map's alpha carried), the flags counted, and, when outputs are named and the material has
 * maps, every target parameter written by the rule maps are read by (mr_brdf_param_map_encoding: PNG outputs read
 * back as written) with the flag picture (mr_flag_picture, mr_learned_flag_code), all or none (mr_img_write_set).
 * *out is zeroed first; on failure it holds only material_report and converting (nothing to free). Errors: those of
 * the kind, of the material (out->material_report.usage says whether its text was at fault), of the conversion and
 * of the writes. */
mr_status mr_learned_convert_material(const mr_learned_conversion_spec *spec, mr_learned_conversion *out);

/* Frees what a conversion holds and zeroes it (NULL-safe). */
void mr_learned_conversion_free(mr_learned_conversion *conversion);

mr_status mr_learned_write(const mr_learned *t, const char *path);
/* The file's text into *text (malloc'ed, NUL-terminated; the caller frees it), exactly what write writes. */
mr_status mr_learned_format(const mr_learned *t, char **text, size_t *length);
mr_status mr_learned_read(const char *path, mr_learned **out);
/* Parse `size` bytes of file text; `name` labels errors. */
mr_status mr_learned_parse(const char *text, size_t size, const char *name, mr_learned **out);

void mr_learned_free(mr_learned *t);

#ifdef __cplusplus
}
#endif

#endif /* MR_LEARN_LEARNED_H */
