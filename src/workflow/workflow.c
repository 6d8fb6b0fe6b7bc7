/*
 * workflow.c — metallic <-> specular workflow conversions: Eq. 2, the generalised Eq. 3 with the MEAN and
 * WEIGHTED single-metallic choices, the dispatch to the Khronos converter (khronos.c) and to a CUSTOM callback,
 * input sanitising and flags, and the OpenMP batch over planar maps. The contract is in workflow.h; the
 * derivations are in docs/workflow.md.
 *
 * Every texel goes through one pure function of its own inputs (metal_to_spec_texel, spec_to_metal_texel) in
 * double precision; the per-texel API and the batch both call it, so they agree bit for bit and the batch does not
 * depend on the thread count.
 */
#include "workflow.h"

#include <limits.h>
#include <math.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "../io/image_io.h"
#include "../mr_internal.h"
#include "nn/mlp.h"
#include "workflow_internal.h"

static const char *const method_names[MR_WF_METHOD_COUNT] = {
    [MR_WF_WEIGHTED] = "weighted", [MR_WF_MEAN] = "mean", [MR_WF_KHRONOS] = "khronos", [MR_WF_CUSTOM] = "custom"};
// The names of the CLI's --convention: one naming for library and tool (workflow.h).
static const char *const diffuse_names[MR_WF_DIFFUSE_COUNT] = {"paper", "gltf"};

const char *mr_wf_diffuse_name(mr_wf_diffuse diffuse) {
    return (unsigned)diffuse < MR_WF_DIFFUSE_COUNT ? diffuse_names[diffuse] : NULL;
}

mr_status mr_wf_diffuse_from_name(const char *name, mr_wf_diffuse *out) {
    if (out == NULL) return mr_fail(MR_ERR_INVALID_ARG, "diffuse convention: NULL output");
    for (int i = 0; i < MR_WF_DIFFUSE_COUNT; i++)
        if (name != NULL && strcmp(name, diffuse_names[i]) == 0) {
            *out = (mr_wf_diffuse)i;
            return MR_OK;
        }
    return mr_fail(MR_ERR_INVALID_ARG, "'%s' is not a diffuse convention: expected gltf (the spec-gloss diffuse is "
                   "dimmed by 1 - max specular, as glTF renders it) or paper (the diffuse is the Lambert lobe)",
                   name ? name : "(null)");
}

const char *mr_wf_method_name(mr_wf_method method) {
    return (unsigned)method < MR_WF_METHOD_COUNT ? method_names[method] : NULL;
}

mr_status mr_wf_method_from_name(const char *name, mr_wf_method *out) {
    if (out == NULL) return mr_fail(MR_ERR_INVALID_ARG, "workflow method: NULL output");
    for (int i = 0; i < MR_WF_METHOD_COUNT; i++)
        if (name != NULL && strcmp(name, method_names[i]) == 0) {
            *out = (mr_wf_method)i;
            return MR_OK;
        }
    return mr_fail(MR_ERR_INVALID_ARG, "workflow method '%s': unknown (valid: weighted, mean, khronos, custom)",
                   name ? name : "(null)");
}

mr_wf_options mr_wf_options_default(void) {
    mr_wf_options o;
    memset(&o, 0, sizeof o);
    o.dielectric_f0 = MR_WF_F0_GLTF;
    o.method = MR_WF_WEIGHTED;
    o.eps = MR_WF_DEFAULT_EPS;
    o.custom = NULL;
    o.custom_data = NULL;
    o.spec_diffuse = MR_WF_DIFFUSE_PLAIN;
    for (int c = 0; c < 3; c++) o.diffuse_quantisation.scale[c] = o.specular_quantisation.scale[c] = 1.0;
    return o;
}

/* The options in force: *opts (NULL: the defaults) with its zero fields read as their defaults, so a zeroed struct
 * is mr_wf_options_default() (workflow.h). */
static mr_wf_options options_in_force(const mr_wf_options *opts) {
    if (opts == NULL) return mr_wf_options_default();
    mr_wf_options o = *opts;
    if (o.dielectric_f0 == 0.0) o.dielectric_f0 = MR_WF_F0_GLTF;
    if (o.eps == 0.0) o.eps = MR_WF_DEFAULT_EPS;
    return o;
}

/* The batches' threads for n texels (workflow.h, mr_wf_options.threads). */
static int batch_threads(const mr_wf_options *o, size_t n) {
    return mr_auto_threads(o->threads, n > (size_t)LONG_MAX ? LONG_MAX : (long)n, MR_WF_PARALLEL_TEXELS);
}

/* MR_OK or MR_ERR_INVALID_ARG for one of the two quantisations. */
static mr_status check_quantisation(const char *name, const mr_wf_quantisation *q) {
    if (q->bits != 0 && q->bits != 8 && q->bits != 16)
        return mr_fail(MR_ERR_INVALID_ARG, "workflow options: %s.bits %d: expected 0 (exact), 8 or 16", name, q->bits);
    for (int c = 0; q->bits != 0 && c < 3; c++)
        if (!(q->scale[c] >= 0.0 && isfinite(q->scale[c])))
            return mr_fail(MR_ERR_INVALID_ARG, "workflow options: %s.scale[%d] %g: expected a finite factor >= 0",
                           name, c, q->scale[c]);
    return MR_OK;
}

mr_status mr_wf_options_check(const mr_wf_options *given) {
    if (given == NULL) return MR_OK;
    const mr_wf_options in_force = options_in_force(given), *opts = &in_force;
    if (opts->threads < 0 || opts->threads > 1024)
        return mr_fail(MR_ERR_INVALID_ARG, "workflow options: threads %d: expected 0 (automatic) to 1024",
                       opts->threads);
    if (!(opts->dielectric_f0 > 0.0 && opts->dielectric_f0 < 1.0)) // also rejects NaN
        return mr_fail(MR_ERR_INVALID_ARG, "workflow options: dielectric_f0 %g: expected a value in (0, 1) (0: the "
                       "default)", opts->dielectric_f0);
    if (!(opts->eps > 0.0 && opts->eps < 1.0))
        return mr_fail(MR_ERR_INVALID_ARG, "workflow options: eps %g: expected a value in (0, 1) (0: the default)",
                       opts->eps);
    if ((unsigned)opts->method >= MR_WF_METHOD_COUNT)
        return mr_fail(MR_ERR_INVALID_ARG, "workflow options: method %d: unknown (valid: 0 to %d)",
                       (int)opts->method, MR_WF_METHOD_COUNT - 1);
    if ((unsigned)opts->spec_diffuse >= MR_WF_DIFFUSE_COUNT)
        return mr_fail(MR_ERR_INVALID_ARG, "workflow options: spec_diffuse %d: unknown (valid: 0 plain, 1 specgloss)",
                       (int)opts->spec_diffuse);
    mr_status status = check_quantisation("diffuse_quantisation", &opts->diffuse_quantisation);
    if (status == MR_OK) status = check_quantisation("specular_quantisation", &opts->specular_quantisation);
    if (status != MR_OK) return status;
    if (opts->method == MR_WF_CUSTOM && opts->custom == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "workflow options: method custom: no callback in opts->custom");
    if (opts->method == MR_WF_KHRONOS && opts->dielectric_f0 != MR_WF_KHRONOS_F0)
        return mr_fail(MR_ERR_INVALID_ARG,
                       "workflow options: method khronos: dielectric_f0 %g: the Khronos converter fixes it at 0.04",
                       opts->dielectric_f0);
    return MR_OK;
}

/* ---- per texel ------------------------------------------------------------------------------------------------ */

/* A value read into [0, 1]: non-finite -> 0, outside -> clamped; flags say which happened. */
static double sanitise(double x, unsigned *flags) {
    if (!isfinite(x)) {
        *flags |= MR_WF_NONFINITE_INPUT;
        return 0.0;
    }
    if (x < 0.0 || x > 1.0) {
        *flags |= MR_WF_CLAMPED_INPUT;
        return x < 0.0 ? 0.0 : 1.0;
    }
    return x;
}

/* A roughness read into [0, 1]: like sanitise, but non-finite -> 1 (fully rough: a broken texel must not become a
 * mirror; glossiness 0 gives the same). */
static double sanitise_roughness(double x, unsigned *flags) {
    if (!isfinite(x)) {
        *flags |= MR_WF_NONFINITE_INPUT;
        return 1.0;
    }
    return sanitise(x, flags);
}

/* Eq. 2 for one channel. */
static void eq2(double albedo, double metallic, double f0, double *diffuse, double *specular) {
    *diffuse = albedo * (1.0 - metallic);
    *specular = f0 * (1.0 - metallic) + metallic * albedo;
}

/* Eq. 3 for one channel, generalised to any F0d (workflow.h; derivation in docs/workflow.md): the (A, m), m in
 * [0, 1], with A^2 - (s + d) A + F0d d = 0. Usually one root has m >= 0 (lo = hi, ambiguous 0). Where the larger
 * root is within eps (the specular's tolerance) of F0d or below, both roots reproduce the channel (ambiguous 1):
 * lo is the less metallic reading, hi the more metallic one; an ambiguous channel whose specular is within eps of
 * F0d has the dielectric it may be (A = d, m = 0) as its lo. */
typedef struct eq3_readings {
    double a_lo, m_lo, a_hi, m_hi;
    int ambiguous;
} eq3_readings;

static eq3_readings eq3(double d, double s, double f0, double eps) {
    double sum = s + d;
    double discriminant = sum * sum - 4.0 * f0 * d;
    if (discriminant < 0.0) discriminant = 0.0; // no exact solution: the nearest, double, root
    double big = 0.5 * (sum + sqrt(discriminant));
    eq3_readings r = {big, big > 0.0 ? mr_clampd(1.0 - d / big, 0.0, 1.0) : 0.0, 0.0, 0.0, 0};
    if (big > f0 + eps) { // the only root with m >= 0 (the other one, F0d d / big < d, has m < 0)
    } else if (fabs(s - f0) <= eps) { // a dielectric (A = d, m = 0: s = F0d) within the tolerance. Near the double
        // root the less metallic root is ill-conditioned (dm/ds is infinite): an 8-bit dielectric specular
        // 0.0395 beside a diffuse of 0.035 would read as m = 0.06 there.
        r.a_lo = d;
        r.m_lo = 0.0;
        r.ambiguous = 1;
    } else if (f0 > 0.0) { // two exact solutions; the smaller root is the less metallic one
        r.a_lo = big > 0.0 ? f0 * d / big : 0.0;
        r.m_lo = mr_clampd(1.0 - big / f0, 0.0, 1.0);
        r.ambiguous = 1;
    } else { // F0d = 0 and a black channel: any metallic reproduces it; the least metallic is 0
        r.a_lo = d;
        r.m_lo = 0.0;
    }
    r.a_hi = r.ambiguous ? big : r.a_lo;
    r.m_hi = r.ambiguous ? (big > 0.0 ? mr_clampd(1.0 - d / big, 0.0, 1.0) : 1.0) : r.m_lo;
    return r;
}

/* The albedo of one channel that best reproduces (d, s) through Eq. 2 with metallic m (least squares), clamped.
 * The normal equation of min_A (A (1 - m) - d)^2 + (F0d (1 - m) + m A - s)^2; its denominator is >= 1/2. */
static double best_albedo(double d, double s, double f0, double m) {
    double k = 1.0 - m;
    return mr_clampd((k * d + m * (s - f0 * k)) / (k * k + m * m), 0.0, 1.0);
}

/* 1 - max_c s_c: the factor KHR_materials_pbrSpecularGlossiness puts on its diffuse lobe. */
static double specgloss_diffuse_factor(const double s[3]) { return 1.0 - fmax(fmax(s[0], s[1]), s[2]); }

/* Does the specular side's diffuse carry spec-gloss's factor here? (KHRONOS applies its own.) */
static int reads_specgloss(const mr_wf_options *o) {
    return o->spec_diffuse == MR_WF_DIFFUSE_SPECGLOSS && o->method != MR_WF_KHRONOS;
}

/* The diffuse lobe of a sanitised spec-gloss texel, in place: d (1 - max_c s_c), in [0, 1]. */
static void specgloss_dim(double d[3], const double s[3]) {
    double k = specgloss_diffuse_factor(s);
    for (int c = 0; c < 3; c++) d[c] *= k;
}

/* The spec-gloss diffuse whose lobe is the plain diffuse d, in place: d / (1 - max_c s_c). A lobe that needs a
 * diffuse above 1 (or any lobe at all when max_c s_c = 1) is clamped to 1 and returns MR_WF_OFF_MANIFOLD. */
static unsigned specgloss_undim(double d[3], const double s[3]) {
    double k = specgloss_diffuse_factor(s);
    unsigned flags = 0;
    for (int c = 0; c < 3; c++) {
        if (d[c] <= 0.0) continue;
        if (d[c] > k) { // d / k > 1, written without dividing by a k that may be 0
            if (d[c] - k > 1e-12) flags |= MR_WF_OFF_MANIFOLD; // beyond rounding
            d[c] = 1.0;
        } else {
            d[c] /= k;
        }
    }
    return flags;
}

static unsigned metal_to_spec_texel(const mr_wf_options *o, const double albedo_in[3], double metallic_in,
                                    double diffuse[3], double specular[3]) {
    unsigned flags = 0;
    double albedo[3];
    for (int c = 0; c < 3; c++) albedo[c] = sanitise(albedo_in[c], &flags);
    double m = sanitise(metallic_in, &flags);
    if (o->method == MR_WF_KHRONOS) {
        mr_wf_khronos_metal_to_spec(albedo, m, diffuse, specular);
    } else {
        for (int c = 0; c < 3; c++) eq2(albedo[c], m, o->dielectric_f0, &diffuse[c], &specular[c]);
        if (reads_specgloss(o)) flags |= specgloss_undim(diffuse, specular);
    }
    // Both are within [0, 1] in exact arithmetic; rounding is not (Khronos's diffuse for an albedo channel of 1 is
    // 0.96 (1 - m) / (1 - (0.04 + 0.96 m)), which comes out up to ~1e-12 above 1).
    for (int c = 0; c < 3; c++) {
        diffuse[c] = mr_clampd(diffuse[c], 0.0, 1.0);
        specular[c] = mr_clampd(specular[c], 0.0, 1.0);
    }
    return flags;
}

/* How far the Eq. 2 fit with metallic m misses (d, s) beyond the tolerance tol[c] of channel c (both values of a
 * channel may miss by it: workflow.h, "Tolerances"): the largest miss - tol, <= 0 when everything is within. The
 * least-squares albedos go to albedo[]. */
static double excess_miss(const double d[3], const double s[3], const double tol[3], double f0, double m,
                          double albedo[3]) {
    double worst = -INFINITY;
    for (int c = 0; c < 3; c++) {
        double back_d, back_s;
        albedo[c] = best_albedo(d[c], s[c], f0, m);
        eq2(albedo[c], m, f0, &back_d, &back_s);
        worst = fmax(worst, fmax(fabs(back_d - d[c]), fabs(back_s - s[c])) - tol[c]);
    }
    return worst;
}

/* Eq. 3 per channel, the MEAN or WEIGHTED single metallic, and the least-squares albedos for it. ts: the specular
 * values' tolerances (the ambiguity test's), tol: each channel's (the fit's). An ambiguous channel has two readings;
 * of the up to 8 combinations the least metallic whose fit is within tol is taken, else the one that misses least
 * (every channel ambiguous and grey: the less metallic twin, as before; a dark coloured metal: its own readings,
 * which agree; a channel darker than F0d in a brighter metal: the reading the other channels agree with). */
static void analytic_spec_to_metal(const mr_wf_options *o, const double d[3], const double s[3], const double ts[3],
                                   const double tol[3], double albedo[3], double *metallic) {
    eq3_readings r[3];
    unsigned ambiguous = 0;
    for (int c = 0; c < 3; c++) {
        r[c] = eq3(d[c], s[c], o->dielectric_f0, ts[c]);
        if (r[c].ambiguous) ambiguous |= 1u << c;
    }
    // Each combination's single m (cheap), then the fits (dearer) in order of increasing m: the first that fits
    // is the answer. Ties in m keep the order of `hi`, so the answer does not depend on the search.
    double cand_m[8];
    unsigned cand_hi[8], count = 0;
    for (unsigned hi = 0; hi < 8; hi++) {
        if (hi & ~ambiguous) continue; // only ambiguous channels have a second reading
        double a[3], mc[3];
        for (int c = 0; c < 3; c++) {
            a[c] = hi & (1u << c) ? r[c].a_hi : r[c].a_lo;
            mc[c] = hi & (1u << c) ? r[c].m_hi : r[c].m_lo;
        }
        double weight = a[0] + a[1] + a[2];
        double m = (mc[0] + mc[1] + mc[2]) / 3.0;
        if (o->method == MR_WF_WEIGHTED && weight > o->eps) m = (a[0] * mc[0] + a[1] * mc[1] + a[2] * mc[2]) / weight;
        m = mr_clampd(m, 0.0, 1.0); // rounding could leave the weighted mean an ulp outside
        unsigned k = count++;
        for (; k > 0 && cand_m[k - 1] > m; k--) { // insertion sort by m, stable
            cand_m[k] = cand_m[k - 1];
            cand_hi[k] = cand_hi[k - 1];
        }
        cand_m[k] = m;
        cand_hi[k] = hi;
    }
    if (count == 1) { // nothing is ambiguous: the one combination, no fit to compare
        for (int c = 0; c < 3; c++) albedo[c] = best_albedo(d[c], s[c], o->dielectric_f0, cand_m[0]);
        *metallic = cand_m[0];
        return;
    }
    double best_excess = INFINITY;
    unsigned best_hi = 8;
    for (unsigned k = 0; k < count; k++) {
        double fit[3];
        double excess = excess_miss(d, s, tol, o->dielectric_f0, cand_m[k], fit);
        if (excess < best_excess || (excess == best_excess && cand_hi[k] < best_hi)) {
            best_excess = excess;
            best_hi = cand_hi[k];
            *metallic = cand_m[k];
            memcpy(albedo, fit, sizeof fit);
        }
        if (excess <= 0.0) return; // the least metallic combination that fits
    }
}

/* A CUSTOM callback's answer, sanitised; METHOD_FAILED when it failed or needed sanitising. */
static unsigned custom_spec_to_metal(const mr_wf_options *o, const double d[3], const double s[3], double albedo[3],
                                     double *metallic) {
    double a[3] = {0.0, 0.0, 0.0}, m = 0.0;
    if (o->custom(o, d, s, a, &m) != 0) {
        albedo[0] = albedo[1] = albedo[2] = 0.0;
        *metallic = 0.0;
        return MR_WF_METHOD_FAILED;
    }
    unsigned flags = 0;
    for (int c = 0; c < 3; c++) albedo[c] = sanitise(a[c], &flags);
    *metallic = sanitise(m, &flags);
    return flags != 0 ? MR_WF_METHOD_FAILED : 0u;
}

/* ---- tolerances (workflow.h, "Tolerances") -------------------------------------------------------------------- */

/* An input's quantisation, ready to answer per value. For sRGB codes a batch tabulates, per code q, the decode of
 * q + 1/2 (upper[q], increasing: a value's code is the first q with value < upper[q]) and mr_img_half_step at q
 * (half[q]), and per bucket k of [0, 1] in equal parts the code of k / buckets (start[k]; a bucket spans at most
 * 7 codes, where they are densest, near 0), so a value costs a few comparisons instead of three pow() calls;
 * without tables (upper NULL: the per-texel API) mr_img_half_step is called. 16-bit tables take 1 MB, kept that
 * small because each value looks them up at random. */
typedef struct quantisation {
    const mr_wf_quantisation *q;
    int max_code;      /* 255 or 65535; 0 when bits is 0 */
    int buckets;       /* 4096 for 8 bits, 131072 for 16 */
    float *upper;      /* max_code values (decodes are floats), or NULL */
    double *half;      /* max_code + 1 values, or NULL */
    uint16_t *start;   /* buckets values, or NULL */
} quantisation;

static quantisation quantisation_plain(const mr_wf_quantisation *q) {
    int max_code = q->bits == 0 ? 0 : (1 << q->bits) - 1;
    quantisation t = {q, max_code, q->bits == 8 ? 4096 : 131072, NULL, NULL, NULL};
    return t;
}

/* The tables for sRGB codes (nothing to tabulate for linear ones or bits 0). MR_ERR_NOMEM (t left plain). */
static mr_status quantisation_tabulate(const mr_wf_quantisation *q, quantisation *t) {
    *t = quantisation_plain(q);
    if (t->max_code == 0 || !q->srgb) return MR_OK;
    float *upper = malloc((size_t)t->max_code * sizeof *upper);
    double *half = malloc(((size_t)t->max_code + 1) * sizeof *half);
    uint16_t *start = malloc((size_t)t->buckets * sizeof *start);
    if (upper == NULL || half == NULL || start == NULL) {
        free(upper);
        free(half);
        free(start);
        return mr_fail(MR_ERR_NOMEM, "spec -> metal batch: out of memory for a %d-bit sRGB tolerance table", q->bits);
    }
    for (int code = 0; code <= t->max_code; code++) {
        // The same decodes mr_img_half_step compares with, so the table answers exactly what it would.
        half[code] = mr_img_half_step(mr_srgb_to_linear((float)((double)code / t->max_code)), q->bits, MR_IMG_COLOR);
        if (code < t->max_code) upper[code] = mr_srgb_to_linear((float)((code + 0.5) / t->max_code));
    }
    for (int k = 0, code = 0; k < t->buckets; k++) {
        while (code < t->max_code && (double)k / t->buckets >= upper[code]) code++;
        start[k] = (uint16_t)code;
    }
    t->upper = upper;
    t->half = half;
    t->start = start;
    return MR_OK;
}

static void quantisation_free(quantisation *t) {
    free(t->upper);
    free(t->half);
    free(t->start);
    t->upper = NULL;
    t->half = NULL;
    t->start = NULL;
}

/* The tolerance of value v (sanitised) of channel c: max(eps, scale[c] x half a code at v / scale[c]). */
static inline double tolerance(const quantisation *t, int c, double v, double eps) {
    const mr_wf_quantisation *q = t->q;
    if (t->max_code == 0 || q->scale[c] <= 0.0) return eps;
    double step;
    if (!q->srgb) {
        step = 0.5 / t->max_code;
    } else if (t->upper == NULL) {
        step = mr_img_half_step(v / q->scale[c], q->bits, MR_IMG_COLOR);
    } else {
        double x = mr_clampd(q->scale[c] == 1.0 ? v : v / q->scale[c], 0.0, 1.0);
        int k = (int)(x * t->buckets);
        int code = t->start[k < t->buckets ? k : t->buckets - 1]; // the code of the bucket's start: <= x's
        while (code < t->max_code && x >= t->upper[code]) code++;
        step = t->half[code];
    }
    step *= q->scale[c];
    return step > eps ? step : eps;
}

/* ---- spec -> metal -------------------------------------------------------------------------------------------- */

/* One texel spec -> metal; qd and qs: how its diffuse and specular were stored. */
static unsigned spec_to_metal_texel(const mr_wf_options *o, const quantisation *qd, const quantisation *qs,
                                    const double diffuse_in[3], const double specular_in[3], double albedo[3],
                                    double *metallic) {
    unsigned flags = 0;
    double d[3], s[3], tol_d[3], ts[3]; // the values and their tolerances
    for (int c = 0; c < 3; c++) {
        d[c] = sanitise(diffuse_in[c], &flags);
        s[c] = sanitise(specular_in[c], &flags);
        tol_d[c] = tolerance(qd, c, d[c], o->eps);
        ts[c] = tolerance(qs, c, s[c], o->eps);
    }
    if (reads_specgloss(o)) { // from here on, d is the diffuse lobe Eq. 2 describes
        // Its tolerance, to first order: d (1 - s_k) moves by t_d (1 - s_k) + d t_s[k], k the channel of max s.
        int k = s[1] > s[0] ? 1 : 0;
        k = s[2] > s[k] ? 2 : k;
        double factor = specgloss_diffuse_factor(s);
        for (int c = 0; c < 3; c++) tol_d[c] = tol_d[c] * factor + d[c] * ts[k];
        specgloss_dim(d, s);
    }
    // Both values of channel c may miss by both tolerances: a fit spreads an error in either over both.
    double tol[3] = {tol_d[0] + ts[0], tol_d[1] + ts[1], tol_d[2] + ts[2]};
    double back_d[3], back_s[3]; // the result put through the method's forward conversion
    if (o->method == MR_WF_KHRONOS) {
        mr_wf_khronos_spec_to_metal(d, s, albedo, metallic);
        mr_wf_khronos_metal_to_spec(albedo, *metallic, back_d, back_s);
    } else {
        if (o->method == MR_WF_CUSTOM)
            flags |= custom_spec_to_metal(o, d, s, albedo, metallic);
        else
            analytic_spec_to_metal(o, d, s, ts, tol, albedo, metallic);
        for (int c = 0; c < 3; c++) eq2(albedo[c], *metallic, o->dielectric_f0, &back_d[c], &back_s[c]);
    }
    for (int c = 0; c < 3; c++)
        if (!(fabs(back_d[c] - d[c]) <= tol[c] && fabs(back_s[c] - s[c]) <= tol[c])) flags |= MR_WF_OFF_MANIFOLD;
    return flags;
}

mr_status mr_wf_metal_to_spec(const mr_wf_metal *in, const mr_wf_options *opts, mr_wf_spec *out, unsigned *flags) {
    if (in == NULL || out == NULL) return mr_fail(MR_ERR_INVALID_ARG, "metal -> spec: NULL input or output texel");
    mr_status status = mr_wf_options_check(opts);
    if (status != MR_OK) return status;
    mr_wf_options o = options_in_force(opts);
    mr_wf_spec result;
    unsigned f = metal_to_spec_texel(&o, in->albedo, in->metallic, result.diffuse, result.specular);
    result.roughness = sanitise_roughness(in->roughness, &f);
    *out = result;
    if (flags) *flags = f;
    return MR_OK;
}

mr_status mr_wf_spec_to_metal(const mr_wf_spec *in, const mr_wf_options *opts, mr_wf_metal *out, unsigned *flags) {
    if (in == NULL || out == NULL) return mr_fail(MR_ERR_INVALID_ARG, "spec -> metal: NULL input or output texel");
    mr_status status = mr_wf_options_check(opts);
    if (status != MR_OK) return status;
    mr_wf_options o = options_in_force(opts);
    mr_wf_metal result;
    quantisation qd = quantisation_plain(&o.diffuse_quantisation), qs = quantisation_plain(&o.specular_quantisation);
    unsigned f = spec_to_metal_texel(&o, &qd, &qs, in->diffuse, in->specular, result.albedo, &result.metallic);
    result.roughness = sanitise_roughness(in->roughness, &f);
    *out = result;
    if (flags) *flags = f;
    return MR_OK;
}

/* ---- batches -------------------------------------------------------------------------------------------------- */

/* The checks both batches share: n, options, and the roughness pairing. */
static mr_status check_batch(const char *what, size_t n, const mr_wf_options *opts, const float *rough_in,
                             const float *rough_out) {
    if (n > SIZE_MAX / (3 * sizeof(float)))
        return mr_fail(MR_ERR_INVALID_ARG, "%s: %zu texels: more than an RGB map can address", what, n);
    mr_status status = mr_wf_options_check(opts);
    if (status != MR_OK) return status;
    if (n > 0 && (rough_in == NULL) != (rough_out == NULL))
        return mr_fail(MR_ERR_INVALID_ARG, "%s: roughness map given for the %s only (give both or neither)", what,
                       rough_in == NULL ? "output" : "input");
    return MR_OK;
}

mr_status mr_wf_metal_to_spec_batch(const mr_wf_metal_input *in, size_t n, const mr_wf_options *opts,
                                    const mr_wf_spec_maps *out, uint8_t *flags) {
    const char *what = "metal -> spec batch";
    if (in == NULL || out == NULL) return mr_fail(MR_ERR_INVALID_ARG, "%s: NULL input or output maps", what);
    if (n > 0 && (in->albedo == NULL || in->metallic == NULL))
        return mr_fail(MR_ERR_INVALID_ARG, "%s: NULL %s map", what, in->albedo == NULL ? "albedo" : "metallic");
    if (n > 0 && (out->diffuse == NULL || out->specular == NULL))
        return mr_fail(MR_ERR_INVALID_ARG, "%s: NULL %s map", what, out->diffuse == NULL ? "diffuse" : "specular");
    mr_status status = check_batch(what, n, opts, in->roughness, out->roughness);
    if (status != MR_OK) return status;
    mr_wf_options o = options_in_force(opts);
    const float *albedo = in->albedo, *metallic = in->metallic, *rough_in = in->roughness;
    float *diffuse = out->diffuse, *specular = out->specular, *rough_out = out->roughness;

    const int threads = batch_threads(&o, n);
#pragma omp parallel for schedule(static) num_threads(threads) if (threads > 1)
    for (size_t i = 0; i < n; i++) {
        double a[3] = {albedo[3 * i], albedo[3 * i + 1], albedo[3 * i + 2]};
        double m = metallic[i];
        double rough = rough_in ? rough_in[i] : 0.0;
        double d[3], s[3];
        unsigned f = metal_to_spec_texel(&o, a, m, d, s);
        rough = sanitise_roughness(rough, &f);
        for (int c = 0; c < 3; c++) {
            diffuse[3 * i + c] = (float)d[c];
            specular[3 * i + c] = (float)s[c];
        }
        if (rough_out) rough_out[i] = (float)rough;
        if (flags) flags[i] = (uint8_t)f;
    }
    return MR_OK;
}

mr_status mr_wf_spec_to_metal_batch(const mr_wf_spec_input *in, size_t n, const mr_wf_options *opts,
                                    const mr_wf_metal_maps *out, uint8_t *flags) {
    const char *what = "spec -> metal batch";
    if (in == NULL || out == NULL) return mr_fail(MR_ERR_INVALID_ARG, "%s: NULL input or output maps", what);
    if (n > 0 && (in->diffuse == NULL || in->specular == NULL))
        return mr_fail(MR_ERR_INVALID_ARG, "%s: NULL %s map", what, in->diffuse == NULL ? "diffuse" : "specular");
    if (n > 0 && (out->albedo == NULL || out->metallic == NULL))
        return mr_fail(MR_ERR_INVALID_ARG, "%s: NULL %s map", what, out->albedo == NULL ? "albedo" : "metallic");
    mr_status status = check_batch(what, n, opts, in->roughness, out->roughness);
    if (status != MR_OK) return status;
    mr_wf_options o = options_in_force(opts);
    quantisation qd, qs = quantisation_plain(&o.specular_quantisation);
    status = quantisation_tabulate(&o.diffuse_quantisation, &qd);
    if (status == MR_OK) status = quantisation_tabulate(&o.specular_quantisation, &qs);
    if (status != MR_OK) {
        quantisation_free(&qd);
        return status;
    }
    const float *diffuse = in->diffuse, *specular = in->specular, *rough_in = in->roughness;
    float *albedo = out->albedo, *metallic = out->metallic, *rough_out = out->roughness;

    const int threads = batch_threads(&o, n);
#pragma omp parallel for schedule(static) num_threads(threads) if (threads > 1)
    for (size_t i = 0; i < n; i++) {
        double d[3] = {diffuse[3 * i], diffuse[3 * i + 1], diffuse[3 * i + 2]};
        double s[3] = {specular[3 * i], specular[3 * i + 1], specular[3 * i + 2]};
        double rough = rough_in ? rough_in[i] : 0.0;
        double a[3], m;
        unsigned f = spec_to_metal_texel(&o, &qd, &qs, d, s, a, &m);
        rough = sanitise_roughness(rough, &f);
        for (int c = 0; c < 3; c++) albedo[3 * i + c] = (float)a[c];
        metallic[i] = (float)m;
        if (rough_out) rough_out[i] = (float)rough;
        if (flags) flags[i] = (uint8_t)f;
    }
    quantisation_free(&qd);
    quantisation_free(&qs);
    return MR_OK;
}

/* ---- the learned method (nn/mlp.h) ---------------------------------------------------------------------------- */

#define MLP_CHUNK 32768 /* texels a thread converts at a time (its scratch: ~6 MB) */
#define MLP_DEDUPE_PROBE 4096 /* texels of a chunk looked up before deciding whether looking up pays */

/* The anchor with W's options given (the batch builds them once; mr_wf_options_default is not free). */
static void residual_anchor(const mr_wf_options *o, const double lobe[3], const double specular[3],
                            mr_wf_residual_anchor *out) {
    // float inputs: every value's tolerance is eps, so both values of a channel together may miss by 2 eps
    const double ts[3] = {o->eps, o->eps, o->eps}, tol[3] = {2.0 * o->eps, 2.0 * o->eps, 2.0 * o->eps};
    analytic_spec_to_metal(o, lobe, specular, ts, tol, out->albedo, &out->metallic);
    double r = 0.0, dm = 0.0, sm = 0.0, dc = 0.0, sc = 0.0;
    for (int c = 0; c < 3; c++) {
        double back_d, back_s;
        eq2(out->albedo[c], out->metallic, o->dielectric_f0, &back_d, &back_s);
        r = MR_MAX(r, MR_MAX(fabs(back_d - lobe[c]), fabs(back_s - specular[c])));
        dm += lobe[c] / 3.0;
        sm += specular[c] / 3.0;
    }
    for (int c = 0; c < 3; c++) {
        dc = MR_MAX(dc, fabs(lobe[c] - dm));
        sc = MR_MAX(sc, fabs(specular[c] - sm));
    }
    out->gate = r < MR_WF_RESIDUAL_GATE ? r / MR_WF_RESIDUAL_GATE : 1.0;
    out->chroma = dc + sc < MR_WF_RESIDUAL_CHROMA ? (dc + sc) / MR_WF_RESIDUAL_CHROMA : 1.0;
}

static mr_wf_options residual_anchor_options(void) {
    mr_wf_options o = mr_wf_options_default();
    o.method = MR_WF_WEIGHTED;
    return o;
}

void mr_wf_residual_anchor_of(const double lobe[3], const double specular[3], mr_wf_residual_anchor *out) {
    mr_wf_options o = residual_anchor_options();
    residual_anchor(&o, lobe, specular, out);
}

void mr_wf_residual_targets(const float *x, float *y, size_t n) {
    mr_wf_options o = residual_anchor_options();
    for (size_t r = 0; r < n; r++) {
        double lobe[3], spec[3];
        for (int k = 0; k < 3; k++) {
            lobe[k] = mr_clampd(x[6 * r + k], 0.0, 1.0);
            spec[k] = mr_clampd(x[6 * r + 3 + k], 0.0, 1.0);
        }
        mr_wf_residual_anchor a;
        residual_anchor(&o, lobe, spec, &a);
        for (int k = 0; k < 3; k++) y[4 * r + k] -= (float)a.albedo[k];
        y[4 * r + 3] -= (float)a.metallic;
    }
}


/* Row r's anchor one at a time (planes as for mr_wf_residual_anchors). */
static void anchors_scalar_row(const mr_wf_options *o, const double *planes, size_t stride, size_t r,
                               mr_wf_residual_anchor *out) {
    double lobe[3], spec[3];
    for (int c = 0; c < 3; c++) {
        lobe[c] = planes[(size_t)c * stride + r];
        spec[c] = planes[(size_t)(3 + c) * stride + r];
    }
    residual_anchor(o, lobe, spec, &out[r]);
}

/* ---- the anchors of many rows ----------------------------------------------------------------------------------- */

/* The network batch's anchors eight rows at a time with AVX-512, four with AVX2 (x86-64 Linux with GCC, chosen at
 * run time; elsewhere, or with MR_WF_SCALAR_ANCHORS set to a non-empty value, one row at a time). A row none of whose
 * channels is ambiguous
 * (Eq. 3's larger root above F0d + eps in all three: every random or real texel but the darkest) takes the
 * one-combination path of analytic_spec_to_metal, which the vectors compute with the same double operations in the
 * same order (no fused multiply-add: ISO C mode; sqrt and division correctly rounded; each comparison written as
 * its masked blend, so NaN and signed zeros go as in the scalar code), hence the same bits; a lane with an
 * ambiguous channel is redone by residual_anchor. tests/test_workflow.c checks the two paths bit for bit. */
#if defined(__GNUC__) && !defined(__clang__) && __GNUC__ >= 12 && defined(__x86_64__) && defined(__linux__)
#define MR_WF_ANCHORS_V4 1
#include <immintrin.h>

/* x >= lo ? (x <= hi ? x : hi) : lo, as mr_clampd. */
__attribute__((target("avx512f"))) static inline __m512d clamp8(__m512d x, __m512d lo, __m512d hi) {
    __m512d upper = _mm512_mask_blend_pd(_mm512_cmp_pd_mask(x, hi, _CMP_LE_OQ), hi, x);
    return _mm512_mask_blend_pd(_mm512_cmp_pd_mask(x, lo, _CMP_GE_OQ), lo, upper);
}

__attribute__((target("avx512f"))) static inline __m512d abs8(__m512d x) {
    return _mm512_castsi512_pd(_mm512_and_si512(_mm512_castpd_si512(x), _mm512_set1_epi64(INT64_MAX)));
}

/* Rows [0, count): lobe and specular channel c of row r at planes[c * stride + r] and planes[(3 + c) * stride + r]. */
__attribute__((target("avx512f"))) static void anchors_v4(const mr_wf_options *o, const double *planes, size_t stride,
                                                           size_t count, mr_wf_residual_anchor *out) {
    const __m512d zero = _mm512_setzero_pd(), one = _mm512_set1_pd(1.0), half = _mm512_set1_pd(0.5);
    const __m512d three = _mm512_set1_pd(3.0), f0 = _mm512_set1_pd(o->dielectric_f0);
    const __m512d four_f0 = _mm512_set1_pd(4.0 * o->dielectric_f0); // eq3's 4.0 * f0 * d is (4.0 * f0) * d
    const __m512d unambiguous = _mm512_set1_pd(o->dielectric_f0 + o->eps), eps = _mm512_set1_pd(o->eps);
    const __m512d gate_scale = _mm512_set1_pd(MR_WF_RESIDUAL_GATE);
    const __m512d chroma_scale = _mm512_set1_pd(MR_WF_RESIDUAL_CHROMA);
    size_t r = 0;
    for (; r + 8 <= count; r += 8) {
        __m512d d[3], s[3], a[3], m[3];
        __mmask8 plain = 0xff;
        for (int c = 0; c < 3; c++) { // eq3, one root
            d[c] = _mm512_loadu_pd(planes + (size_t)c * stride + r);
            s[c] = _mm512_loadu_pd(planes + (size_t)(3 + c) * stride + r);
            __m512d sum = _mm512_add_pd(s[c], d[c]);
            __m512d disc = _mm512_sub_pd(_mm512_mul_pd(sum, sum), _mm512_mul_pd(four_f0, d[c]));
            disc = _mm512_mask_blend_pd(_mm512_cmp_pd_mask(disc, zero, _CMP_LT_OQ), disc, zero);
            __m512d big = _mm512_mul_pd(half, _mm512_add_pd(sum, _mm512_sqrt_pd(disc)));
            __m512d metal = clamp8(_mm512_sub_pd(one, _mm512_div_pd(d[c], big)), zero, one);
            m[c] = _mm512_mask_blend_pd(_mm512_cmp_pd_mask(big, zero, _CMP_GT_OQ), zero, metal);
            a[c] = big;
            plain &= _mm512_cmp_pd_mask(big, unambiguous, _CMP_GT_OQ);
        }
        if (plain == 0) {
            for (int l = 0; l < 8; l++) anchors_scalar_row(o, planes, stride, r + (size_t)l, out);
            continue;
        }
        __m512d weight = _mm512_add_pd(_mm512_add_pd(a[0], a[1]), a[2]);
        __m512d mm = _mm512_div_pd(_mm512_add_pd(_mm512_add_pd(m[0], m[1]), m[2]), three);
        if (o->method == MR_WF_WEIGHTED) {
            __m512d dot = _mm512_add_pd(_mm512_add_pd(_mm512_mul_pd(a[0], m[0]), _mm512_mul_pd(a[1], m[1])),
                                        _mm512_mul_pd(a[2], m[2]));
            mm = _mm512_mask_blend_pd(_mm512_cmp_pd_mask(weight, eps, _CMP_GT_OQ), mm, _mm512_div_pd(dot, weight));
        }
        mm = clamp8(mm, zero, one);
        __m512d k = _mm512_sub_pd(one, mm);
        __m512d den = _mm512_add_pd(_mm512_mul_pd(k, k), _mm512_mul_pd(mm, mm));
        __m512d f0k = _mm512_mul_pd(f0, k), rr = zero, dm = zero, sm = zero;
        __m512d albedo[3];
        for (int c = 0; c < 3; c++) { // best_albedo, then residual_anchor's Eq. 2 round trip and means
            __m512d num = _mm512_add_pd(_mm512_mul_pd(k, d[c]), _mm512_mul_pd(mm, _mm512_sub_pd(s[c], f0k)));
            albedo[c] = clamp8(_mm512_div_pd(num, den), zero, one);
            __m512d back_d = _mm512_mul_pd(albedo[c], k);
            __m512d back_s = _mm512_add_pd(_mm512_mul_pd(f0, k), _mm512_mul_pd(mm, albedo[c]));
            __m512d miss = _mm512_max_pd(abs8(_mm512_sub_pd(back_d, d[c])), abs8(_mm512_sub_pd(back_s, s[c])));
            rr = _mm512_max_pd(rr, miss); // MR_MAX(a, b) = a > b ? a : b, what vmaxpd computes
            dm = _mm512_add_pd(dm, _mm512_div_pd(d[c], three));
            sm = _mm512_add_pd(sm, _mm512_div_pd(s[c], three));
        }
        __m512d dc = zero, sc = zero;
        for (int c = 0; c < 3; c++) {
            dc = _mm512_max_pd(dc, abs8(_mm512_sub_pd(d[c], dm)));
            sc = _mm512_max_pd(sc, abs8(_mm512_sub_pd(s[c], sm)));
        }
        __m512d spread = _mm512_add_pd(dc, sc);
        __m512d gate = _mm512_mask_blend_pd(_mm512_cmp_pd_mask(rr, gate_scale, _CMP_LT_OQ), one,
                                            _mm512_div_pd(rr, gate_scale));
        __m512d chroma = _mm512_mask_blend_pd(_mm512_cmp_pd_mask(spread, chroma_scale, _CMP_LT_OQ), one,
                                              _mm512_div_pd(spread, chroma_scale));
        double lanes[6][8];
        for (int c = 0; c < 3; c++) _mm512_storeu_pd(lanes[c], albedo[c]);
        _mm512_storeu_pd(lanes[3], mm);
        _mm512_storeu_pd(lanes[4], gate);
        _mm512_storeu_pd(lanes[5], chroma);
        for (int l = 0; l < 8; l++) {
            if (!(plain & (1u << l))) {
                anchors_scalar_row(o, planes, stride, r + (size_t)l, out);
                continue;
            }
            mr_wf_residual_anchor *x = &out[r + (size_t)l];
            for (int c = 0; c < 3; c++) x->albedo[c] = lanes[c][l];
            x->metallic = lanes[3][l];
            x->gate = lanes[4][l];
            x->chroma = lanes[5][l];
        }
    }
    for (; r < count; r++) anchors_scalar_row(o, planes, stride, r, out);
}

/* The same with AVX2, four rows at a time: each masked blend of anchors_v4 is a blendv on a comparison's mask. */
__attribute__((target("avx2"))) static inline __m256d clamp4(__m256d x, __m256d lo, __m256d hi) {
    __m256d upper = _mm256_blendv_pd(hi, x, _mm256_cmp_pd(x, hi, _CMP_LE_OQ));
    return _mm256_blendv_pd(lo, upper, _mm256_cmp_pd(x, lo, _CMP_GE_OQ));
}

__attribute__((target("avx2"))) static inline __m256d abs4(__m256d x) {
    return _mm256_and_pd(x, _mm256_castsi256_pd(_mm256_set1_epi64x(INT64_MAX)));
}

__attribute__((target("avx2"))) static void anchors_v3(const mr_wf_options *o, const double *planes, size_t stride,
                                                       size_t count, mr_wf_residual_anchor *out) {
    const __m256d zero = _mm256_setzero_pd(), one = _mm256_set1_pd(1.0), half = _mm256_set1_pd(0.5);
    const __m256d three = _mm256_set1_pd(3.0), f0 = _mm256_set1_pd(o->dielectric_f0);
    const __m256d four_f0 = _mm256_set1_pd(4.0 * o->dielectric_f0);
    const __m256d unambiguous = _mm256_set1_pd(o->dielectric_f0 + o->eps), eps = _mm256_set1_pd(o->eps);
    const __m256d gate_scale = _mm256_set1_pd(MR_WF_RESIDUAL_GATE);
    const __m256d chroma_scale = _mm256_set1_pd(MR_WF_RESIDUAL_CHROMA);
    size_t r = 0;
    for (; r + 4 <= count; r += 4) {
        __m256d d[3], s[3], a[3], m[3];
        int plain = 0xf;
        for (int c = 0; c < 3; c++) {
            d[c] = _mm256_loadu_pd(planes + (size_t)c * stride + r);
            s[c] = _mm256_loadu_pd(planes + (size_t)(3 + c) * stride + r);
            __m256d sum = _mm256_add_pd(s[c], d[c]);
            __m256d disc = _mm256_sub_pd(_mm256_mul_pd(sum, sum), _mm256_mul_pd(four_f0, d[c]));
            disc = _mm256_blendv_pd(disc, zero, _mm256_cmp_pd(disc, zero, _CMP_LT_OQ));
            __m256d big = _mm256_mul_pd(half, _mm256_add_pd(sum, _mm256_sqrt_pd(disc)));
            __m256d metal = clamp4(_mm256_sub_pd(one, _mm256_div_pd(d[c], big)), zero, one);
            m[c] = _mm256_blendv_pd(zero, metal, _mm256_cmp_pd(big, zero, _CMP_GT_OQ));
            a[c] = big;
            plain &= _mm256_movemask_pd(_mm256_cmp_pd(big, unambiguous, _CMP_GT_OQ));
        }
        if (plain == 0) {
            for (int l = 0; l < 4; l++) anchors_scalar_row(o, planes, stride, r + (size_t)l, out);
            continue;
        }
        __m256d weight = _mm256_add_pd(_mm256_add_pd(a[0], a[1]), a[2]);
        __m256d mm = _mm256_div_pd(_mm256_add_pd(_mm256_add_pd(m[0], m[1]), m[2]), three);
        if (o->method == MR_WF_WEIGHTED) {
            __m256d dot = _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(a[0], m[0]), _mm256_mul_pd(a[1], m[1])),
                                        _mm256_mul_pd(a[2], m[2]));
            mm = _mm256_blendv_pd(mm, _mm256_div_pd(dot, weight), _mm256_cmp_pd(weight, eps, _CMP_GT_OQ));
        }
        mm = clamp4(mm, zero, one);
        __m256d k = _mm256_sub_pd(one, mm);
        __m256d den = _mm256_add_pd(_mm256_mul_pd(k, k), _mm256_mul_pd(mm, mm));
        __m256d f0k = _mm256_mul_pd(f0, k), rr = zero, dm = zero, sm = zero;
        __m256d albedo[3];
        for (int c = 0; c < 3; c++) {
            __m256d num = _mm256_add_pd(_mm256_mul_pd(k, d[c]), _mm256_mul_pd(mm, _mm256_sub_pd(s[c], f0k)));
            albedo[c] = clamp4(_mm256_div_pd(num, den), zero, one);
            __m256d back_d = _mm256_mul_pd(albedo[c], k);
            __m256d back_s = _mm256_add_pd(_mm256_mul_pd(f0, k), _mm256_mul_pd(mm, albedo[c]));
            __m256d miss = _mm256_max_pd(abs4(_mm256_sub_pd(back_d, d[c])), abs4(_mm256_sub_pd(back_s, s[c])));
            rr = _mm256_max_pd(rr, miss);
            dm = _mm256_add_pd(dm, _mm256_div_pd(d[c], three));
            sm = _mm256_add_pd(sm, _mm256_div_pd(s[c], three));
        }
        __m256d dc = zero, sc = zero;
        for (int c = 0; c < 3; c++) {
            dc = _mm256_max_pd(dc, abs4(_mm256_sub_pd(d[c], dm)));
            sc = _mm256_max_pd(sc, abs4(_mm256_sub_pd(s[c], sm)));
        }
        __m256d spread = _mm256_add_pd(dc, sc);
        __m256d gate = _mm256_blendv_pd(one, _mm256_div_pd(rr, gate_scale), _mm256_cmp_pd(rr, gate_scale, _CMP_LT_OQ));
        __m256d chroma = _mm256_blendv_pd(one, _mm256_div_pd(spread, chroma_scale),
                                          _mm256_cmp_pd(spread, chroma_scale, _CMP_LT_OQ));
        double lanes[6][4];
        for (int c = 0; c < 3; c++) _mm256_storeu_pd(lanes[c], albedo[c]);
        _mm256_storeu_pd(lanes[3], mm);
        _mm256_storeu_pd(lanes[4], gate);
        _mm256_storeu_pd(lanes[5], chroma);
        for (int l = 0; l < 4; l++) {
            if (!(plain & (1 << l))) {
                anchors_scalar_row(o, planes, stride, r + (size_t)l, out);
                continue;
            }
            mr_wf_residual_anchor *x = &out[r + (size_t)l];
            for (int c = 0; c < 3; c++) x->albedo[c] = lanes[c][l];
            x->metallic = lanes[3][l];
            x->gate = lanes[4][l];
            x->chroma = lanes[5][l];
        }
    }
    for (; r < count; r++) anchors_scalar_row(o, planes, stride, r, out);
}
#else
#define MR_WF_ANCHORS_V4 0
#endif

/* How this process computes anchors: 2 eight at a time (AVX-512F), 1 four at a time (AVX2), 0 one at a time (no
 * vectors, or MR_WF_SCALAR_ANCHORS set). Once: the CPU and the environment do not change. */
static _Atomic int anchors_vector_choice; // the level + 1; 0 unknown

static int anchors_vector(void) {
    int choice = atomic_load(&anchors_vector_choice);
    if (choice == 0) {
        const char *scalar = getenv("MR_WF_SCALAR_ANCHORS");
        choice = 1;
#if MR_WF_ANCHORS_V4
        __builtin_cpu_init();
        if (scalar == NULL || scalar[0] == '\0')
            choice = __builtin_cpu_supports("avx512f") ? 3 : __builtin_cpu_supports("avx2") ? 2 : 1;
#else
        (void)scalar;
#endif
        atomic_store(&anchors_vector_choice, choice);
    }
    return choice - 1;
}

/* The anchors of rows [0, count) (planes as for anchors_v4) at vector level `level` (anchors_vector's). */
static void anchors_of_rows(const mr_wf_options *o, const double *planes, size_t stride, size_t count, int level,
                            mr_wf_residual_anchor *out) {
#if MR_WF_ANCHORS_V4
    if (level >= 2) {
        anchors_v4(o, planes, stride, count, out);
        return;
    }
    if (level == 1) {
        anchors_v3(o, planes, stride, count, out);
        return;
    }
#else
    (void)level;
#endif
    for (size_t r = 0; r < count; r++) anchors_scalar_row(o, planes, stride, r, out);
}

int mr_wf_residual_anchors(const double *planes, size_t stride, size_t count, int level,
                           mr_wf_residual_anchor *out) {
    mr_wf_options o = residual_anchor_options();
    int best = anchors_vector();
    level = level < 0 ? 0 : level > best ? best : level;
    anchors_of_rows(&o, planes, stride, count, level, out);
    return level;
}

/* The network batch works on the distinct texels of a block: real textures repeat their values (a 2048^2 8-bit
 * spec-gloss set holds ~5 % distinct (diffuse, specular) pairs: Avocado 4.7 %, FloppyDisk 5.5 %), and a texel's
 * answer is a pure function of its inputs, so each distinct pair is sanitised, anchored and run through the
 * network once and its answer copied to every texel that holds it: the same bits as converting every texel.
 * A batch is cut into chunks of MLP_CHUNK texels, each deduplicated on its own by the bit patterns of the six
 * input floats (a value repeated across chunks is computed once per chunk) and converted whole by one thread, in
 * its own scratch: */
typedef struct mlp_block {
    float *x, *y;                   /* distinct rows: network inputs (block x 6), outputs (block x 4) */
    mr_wf_residual_anchor *anchors; /* per distinct row (residual form) */
    double *planes;                 /* the anchors' inputs (residual form): 6 planes of `block` doubles, lobe RGB
                                       and specular RGB of each distinct row */
    size_t block;                   /* texels per chunk */
    int vector_anchors;             /* the anchors' vector level (anchors_vector) */
    long *slot;                     /* per distinct row: its row among those the network sees, or -1 */
    float *answer;                  /* per distinct row: albedo RGB, metallic, final */
    uint8_t *row_flags;             /* per distinct row */
    uint32_t *first;                /* per distinct row: its first texel, chunk-relative */
    uint32_t *row_of;               /* per texel: its distinct row */
    uint32_t *table;                /* table_size hash slots: row + 1, 0 empty */
    size_t table_size;              /* a power of two >= twice the chunk's texels */
    size_t distinct;                /* distinct rows of the chunk */
} mlp_block;

static void mlp_block_free(mlp_block *b) {
    free(b->x);
    free(b->y);
    free(b->anchors);
    free(b->planes);
    free(b->slot);
    free(b->answer);
    free(b->row_flags);
    free(b->first);
    free(b->row_of);
    free(b->table);
    memset(b, 0, sizeof *b); // freed twice (a failed mlp_block_alloc, then the batch's own free) is harmless
}

static mr_status mlp_block_alloc(size_t block, int residual, mlp_block *b) {
    memset(b, 0, sizeof *b);
    b->block = block;
    b->vector_anchors = residual ? anchors_vector() : 0;
    for (b->table_size = 16; b->table_size < 2 * block; b->table_size *= 2) {
    }
    b->x = malloc(block * 6 * sizeof *b->x);
    b->y = malloc(block * 4 * sizeof *b->y);
    b->anchors = malloc(block * sizeof *b->anchors);
    b->planes = residual ? malloc(block * 6 * sizeof *b->planes) : NULL;
    b->slot = malloc(block * sizeof *b->slot);
    b->answer = malloc(block * 4 * sizeof *b->answer);
    b->row_flags = malloc(block);
    b->first = malloc(block * sizeof *b->first);
    b->row_of = malloc(block * sizeof *b->row_of);
    b->table = malloc(b->table_size * sizeof *b->table);
    if (!b->x || !b->y || !b->anchors || (residual && !b->planes) || !b->slot || !b->answer || !b->row_flags ||
        !b->first || !b->row_of || !b->table) {
        mlp_block_free(b);
        return MR_ERR_NOMEM;
    }
    return MR_OK;
}

/* The six input floats of texel i, as bits (two texels with equal bits get equal answers). */
static inline void texel_key(const mr_wf_spec_input *in, size_t i, uint32_t k[6]) {
    memcpy(k, in->diffuse + 3 * i, 3 * sizeof *k);
    memcpy(k + 3, in->specular + 3 * i, 3 * sizeof *k);
}

/* A new distinct row for texel i: sanitised (and dimmed) into x, and when anchor_options is not NULL its double
 * values into the planes its anchor is computed from (mlp_dedupe), as the per-texel path does. */
static void mlp_new_row(const mr_wf_spec_input *in, const mr_wf_options *o, const mr_wf_options *anchor_options,
                        size_t i, mlp_block *b, size_t row) {
    unsigned f = 0;
    double d[3], s[3];
    for (int c = 0; c < 3; c++) {
        d[c] = sanitise(in->diffuse[3 * i + c], &f);
        s[c] = sanitise(in->specular[3 * i + c], &f);
    }
    if (reads_specgloss(o)) specgloss_dim(d, s); // the network learned Eq. 2's plain diffuse lobe
    for (int c = 0; c < 3; c++) {
        b->x[6 * row + c] = (float)d[c];
        b->x[6 * row + 3 + c] = (float)s[c];
    }
    b->row_flags[row] = (uint8_t)f;
    for (int c = 0; anchor_options && c < 3; c++) {
        b->planes[(size_t)c * b->block + row] = d[c];
        b->planes[(size_t)(3 + c) * b->block + row] = s[c];
    }
}

/* Deduplicates the chunk of `count` texels starting at texel `start`: its distinct values become rows 0, 1, ...,
 * every texel's row goes to row_of, and (residual form) the rows' anchors are computed. A chunk whose first
 * MLP_DEDUPE_PROBE texels are mostly distinct (noise, float data) stops looking values up: hashing would only cost. */
static void mlp_dedupe(const mr_wf_spec_input *in, const mr_wf_options *o, const mr_wf_options *anchor_options,
                       size_t start, size_t count, mlp_block *b) {
    uint32_t *table = b->table;
    memset(table, 0, b->table_size * sizeof *table);
    size_t mask = b->table_size - 1, rows = 0;
    int hashing = 1;
    for (size_t r = 0; r < count; r++) {
        if (r == MLP_DEDUPE_PROBE && 4 * rows > 3 * MLP_DEDUPE_PROBE) hashing = 0;
        uint32_t key[6], other[6];
        size_t h = 0;
        if (hashing) {
            texel_key(in, start + r, key);
            for (h = mr_hash_words(key, 6) & mask; table[h] != 0; h = (h + 1) & mask) {
                texel_key(in, start + b->first[table[h] - 1], other);
                if (memcmp(key, other, sizeof key) == 0) break;
            }
            if (table[h] != 0) { // seen before in this chunk
                b->row_of[r] = table[h] - 1;
                continue;
            }
        }
        size_t row = rows++;
        if (hashing) table[h] = (uint32_t)(row + 1);
        b->first[row] = (uint32_t)r;
        b->row_of[r] = (uint32_t)row;
        mlp_new_row(in, o, anchor_options, start + r, b, row);
    }
    b->distinct = rows;
    if (anchor_options) anchors_of_rows(anchor_options, b->planes, b->block, rows, b->vector_anchors, b->anchors);
}

/* Texels [start, start + count) of the batch, on the calling thread: their distinct values (all of the chunk's
 * inputs are read before any of its outputs is written: in-place conversion stays correct), the network on those
 * whose gate is open (residual form; the others' answer is the anchor, whatever the network says), each distinct
 * value's answer, and every texel's. MR_OK or the network's error. */
static mr_status mlp_convert_chunk(const mr_mlp *net, mr_mlp_kernel kernel, const mr_wf_spec_input *in,
                                   const mr_wf_options *o, const mr_wf_options *anchor_options, size_t start,
                                   size_t count, const mr_wf_metal_maps *out, uint8_t *flags, mlp_block *b) {
    const int residual = anchor_options != NULL;
    mlp_dedupe(in, o, anchor_options, start, count, b);
    const size_t rows = b->distinct;
    size_t seen = rows;
    if (residual) {
        seen = 0;
        for (size_t r = 0; r < rows; r++) {
            b->slot[r] = b->anchors[r].gate > 0.0 ? (long)seen : -1;
            if (b->anchors[r].gate > 0.0 && seen++ != r) memcpy(b->x + 6 * (seen - 1), b->x + 6 * r, 6 * sizeof *b->x);
        }
    }
    mr_status status = seen > 0 ? mr_mlp_predict_kernel(net, b->x, seen, b->y, 1, kernel) : MR_OK;
    if (status != MR_OK) return status;
    for (size_t r = 0; r < rows; r++) {
        unsigned f = b->row_flags[r];
        double v4[4] = {0.0, 0.0, 0.0, 0.0};
        if (!residual || b->slot[r] >= 0) {
            size_t row = residual ? (size_t)b->slot[r] : r;
            for (int k = 0; k < 4; k++) v4[k] = b->y[4 * row + k];
        }
        if (residual) { // the correction to W, gated and made neutral (workflow.h)
            const mr_wf_residual_anchor *a = &b->anchors[r];
            double mean = (v4[0] + v4[1] + v4[2]) / 3.0;
            for (int c = 0; c < 3; c++) v4[c] = a->albedo[c] + a->gate * (mean + a->chroma * (v4[c] - mean));
            v4[3] = a->metallic + a->gate * v4[3];
        }
        for (int k = 0; k < 4; k++) {
            // Outputs slightly outside [0, 1] are the regressor's normal overshoot, clamped; only non-finite ones
            // mean it failed (answer 0). Written as selects the compiler turns into min/max rather than branches:
            // which way a random texel's output falls is a coin toss the branch predictor loses.
            double v = v4[k], clamped = v < 0.0 ? 0.0 : v;
            clamped = clamped > 1.0 ? 1.0 : clamped;
            int finite = isfinite(v) != 0;
            f |= finite ? 0u : (unsigned)MR_WF_METHOD_FAILED;
            b->answer[4 * r + k] = finite ? (float)clamped : 0.0f;
        }
        b->row_flags[r] = (uint8_t)f;
    }
    for (size_t r = 0; r < count; r++) { // every texel gets its row's answer (and its own roughness)
        size_t i = start + r, row = b->row_of[r];
        unsigned f = b->row_flags[row];
        // roughness read before any write: metallic may be the very array roughness came in
        float roughness = out->roughness ? (float)sanitise_roughness(in->roughness[i], &f) : 0.0f;
        for (int c = 0; c < 3; c++) out->albedo[3 * i + c] = b->answer[4 * row + c];
        out->metallic[i] = b->answer[4 * row + 3];
        if (out->roughness) out->roughness[i] = roughness;
        if (flags) flags[i] = (uint8_t)f;
    }
    return MR_OK;
}

mr_status mr_wf_spec_to_metal_mlp_batch(const mr_mlp *net, const mr_wf_spec_input *in, size_t n,
                                        const mr_wf_options *opts, const mr_wf_metal_maps *out, uint8_t *flags) {
    const char *what = "spec -> metal batch (mlp)";
    if (net == NULL || in == NULL || out == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "%s: NULL network, input or output maps", what);
    if (net->n_in != 6 || net->n_out != 4)
        return mr_fail(MR_ERR_INVALID_ARG, "%s: the network maps %d inputs to %d outputs; expected 6 (diffuse RGB, "
                       "specular RGB) to 4 (albedo RGB, metallic)", what, net->n_in, net->n_out);
    if (n > 0 && (in->diffuse == NULL || in->specular == NULL))
        return mr_fail(MR_ERR_INVALID_ARG, "%s: NULL %s map", what, in->diffuse == NULL ? "diffuse" : "specular");
    if (n > 0 && (out->albedo == NULL || out->metallic == NULL))
        return mr_fail(MR_ERR_INVALID_ARG, "%s: NULL %s map", what, out->albedo == NULL ? "albedo" : "metallic");
    mr_wf_options o = options_in_force(opts);
    o.method = MR_WF_MEAN; // the analytic method is not used; only the shared checks apply
    mr_status status = check_batch(what, n, &o, in->roughness, out->roughness);
    if (status != MR_OK) return status;
    int residual = strcmp(net->kind, MR_WF_MLP_RESIDUAL_KIND) == 0;
    if (!residual && net->kind[0] != '\0')
        return mr_fail(MR_ERR_INVALID_ARG, "%s: the network's kind '%s' is not a spec -> metal form this build knows "
                       "(plain or " MR_WF_MLP_RESIDUAL_KIND ")", what, net->kind);
    if (n == 0) return MR_OK;
    // The kernel, resolved here so that a bad MR_MLP_KERNEL fails on the calling thread with its message.
    mr_mlp_kernel kernel = MR_MLP_KERNEL_AUTO;
    status = mr_mlp_kernel_auto(&kernel);
    if (status != MR_OK) return status;
    const mr_wf_options anchor_options = residual_anchor_options();
    const size_t chunk = n < MLP_CHUNK ? n : MLP_CHUNK, chunks = (n + chunk - 1) / chunk;
    int threads = batch_threads(&o, n);
    if ((size_t)threads > chunks) threads = (int)chunks;
    // One team for the whole batch, no barrier inside it: each thread converts whole chunks on its own (a thread
    // that the system deschedules holds up no other). A failing chunk (out of memory) stops the others at their
    // next chunk; its status and message (thread-local: mr_last_error) are carried to the calling thread.
    mr_status failed = MR_OK;
    char message[256] = "";
#pragma omp parallel num_threads(threads) if (threads > 1)
    {
        mlp_block b;
        mr_status mine = mlp_block_alloc(chunk, residual, &b);
        if (mine != MR_OK) mr_fail(MR_ERR_NOMEM, "%s: out of memory for %zu texels", what, chunk);
#pragma omp for schedule(dynamic, 1)
        for (size_t c = 0; c < chunks; c++) {
            mr_status stop;
#pragma omp atomic read
            stop = failed;
            if (mine != MR_OK || stop != MR_OK) continue;
            size_t start = c * chunk, count = n - start < chunk ? n - start : chunk;
            mine = mlp_convert_chunk(net, kernel, in, &o, residual ? &anchor_options : NULL, start, count, out,
                                     flags, &b);
        }
        if (mine != MR_OK) {
#pragma omp critical(mr_wf_mlp_batch_error)
            if (failed == MR_OK) {
                snprintf(message, sizeof message, "%s", mr_last_error());
#pragma omp atomic write
                failed = mine;
            }
        }
        mlp_block_free(&b);
    }
    return failed == MR_OK ? MR_OK : mr_fail(failed, "%s", message);
}

mr_wf_quantisation mr_wf_quantisation_of(const mr_img_stored *stored, const double *scale) {
    mr_wf_quantisation q = {0, 0, {1.0, 1.0, 1.0}};
    if (stored == NULL || stored->bits == 0) return q;
    q.bits = stored->bits;
    q.srgb = stored->encoding == MR_IMG_COLOR;
    for (int c = 0; scale != NULL && c < 3; c++) q.scale[c] = scale[c];
    return q;
}
