/*
 * labels.c — image-based labels for the learned spec -> metal converter (labels.h has the contract and the
 * basis derivation; docs/training.md the choices).
 */
#include "labels.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "brdf/brdf.h"
#include "metrics/metrics.h"
#include "mr_internal.h"
#include "render/render.h"

/* glTF metal-rough's dielectric (ior 1.5): F0 = 0.04, so 1 - max F = 0.96 (1 - w). */
#define DIELECTRIC_F0 0.04
#define LOG_FLOOR 0.01
#define METALLIC_GRID 11
#define GOLDEN_STEPS 10
#define GAUSS_NEWTON_STEPS 3

static const char *const objective_names[MR_WF_OBJECTIVE_COUNT] = {"luma", /* DEFAULT */
                                                                     "linear", "display", "log", "exposed", "luma"};

const char *mr_wf_objective_name(mr_wf_objective objective) {
    return (unsigned)objective < MR_WF_OBJECTIVE_COUNT ? objective_names[objective] : NULL;
}

mr_status mr_wf_objective_from_name(const char *name, mr_wf_objective *out) {
    for (int i = MR_WF_OBJECTIVE_LINEAR; name != NULL && i < MR_WF_OBJECTIVE_COUNT; i++)
        if (strcmp(name, objective_names[i]) == 0) {
            *out = (mr_wf_objective)i;
            return MR_OK;
        }
    return mr_fail(MR_ERR_INVALID_ARG, "objective '%s': unknown (valid: linear, display, log, exposed, luma)",
                   name ? name : "(null)");
}

mr_wf_label_options mr_wf_label_options_default(void) {
    mr_wf_label_options o;
    memset(&o, 0, sizeof o);
    o.objective = MR_WF_OBJECTIVE_LUMA;
    o.size = 32;
    o.glossiness_count = 4;
    o.glossiness[0] = 0.3;
    o.glossiness[1] = 0.6;
    o.glossiness[2] = 0.8;
    o.glossiness[3] = 0.95;
    o.env_samples = 256;
    o.reflection_samples = 40;
    o.chroma_weight = 0.1;
    o.regularisation = 1e-4;
    return o;
}

/* One view: the basis images (size² x 3 each) and the interior pixels the objective runs over. */
typedef struct label_view {
    float *p, *q0, *q1;
    double exposure; /* brings a white Lambertian sphere's mean interior radiance to 1 */
    double pp[3], pq[3], qq[3]; /* per channel, over interior pixels: sums of e^2 P P, e^2 P Q0, e^2 Q0 Q0 */
} label_view;

struct mr_wf_label_scene {
    mr_wf_label_options opts;
    int size, view_count;
    label_view *views;
    float *coverage;   /* size² */
    int *interior;     /* pixel indices with coverage 1 */
    int interior_count;
};

int mr_wf_label_view_count(const mr_wf_label_scene *scene) { return scene ? scene->view_count : 0; }
int mr_wf_label_size(const mr_wf_label_scene *scene) { return scene ? scene->size : 0; }
const float *mr_wf_label_coverage(const mr_wf_label_scene *scene) { return scene ? scene->coverage : NULL; }

void mr_wf_label_scene_free(mr_wf_label_scene *scene) {
    if (scene == NULL) return;
    for (int v = 0; v < scene->view_count; v++) {
        free(scene->views[v].p);
        free(scene->views[v].q0);
        free(scene->views[v].q1);
    }
    free(scene->views);
    free(scene->coverage);
    free(scene->interior);
    free(scene);
}

/* ---- the built-in environments ----------------------------------------------------------------------------- */

/* Direction of equirectangular texel (x, y) of a w x h map (render.h's convention). */
static void env_direction(int x, int y, int w, int h, double d[3]) {
    double theta = MR_PI * (y + 0.5) / h, phi = 2.0 * MR_PI * ((x + 0.5) / w - 0.5);
    d[0] = sin(theta) * sin(phi);
    d[1] = cos(theta);
    d[2] = -sin(theta) * cos(phi);
}

/* A soft round light: radiance `value` within `radius_deg` of the direction (azimuth, elevation in degrees,
 * azimuth 0 = +z, towards the camera), falling off smoothly over the outer fifth. */
static double soft_light(const double d[3], double azimuth, double elevation, double radius_deg, double value) {
    double a = azimuth * MR_PI / 180.0, e = elevation * MR_PI / 180.0;
    double c[3] = {cos(e) * sin(a), sin(e), cos(e) * cos(a)};
    double angle = acos(mr_clampd(d[0] * c[0] + d[1] * c[1] + d[2] * c[2], -1.0, 1.0)) * 180.0 / MR_PI;
    double t = (radius_deg - angle) / (0.2 * radius_deg);
    return value * mr_clampd(t, 0.0, 1.0);
}

mr_status mr_wf_label_builtin_env(int index, mr_image **out) {
    if (out == NULL || index < 0 || index > 1)
        return mr_fail(MR_ERR_INVALID_ARG, "built-in label environment %d: expected 0 (studio) or 1 (sky)", index);
    const int w = 512, h = 256;
    mr_image *map = NULL;
    mr_status status = mr_image_create(w, h, 1, &map);
    if (status != MR_OK) return status;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            double d[3], v;
            env_direction(x, y, w, h, d);
            if (index == 0) {
                /* studio: dim walls, a darker floor, a key, a fill and a small rim box */
                v = d[1] >= 0.0 ? 0.08 : 0.03;
                v += soft_light(d, 40.0, 30.0, 14.0, 30.0);
                v += soft_light(d, -110.0, 10.0, 22.0, 5.0);
                v += soft_light(d, 170.0, 45.0, 6.0, 60.0);
            } else {
                /* sky: brighter towards the horizon, a sun, a dark ground */
                v = d[1] >= 0.0 ? 0.6 + 0.6 * (1.0 - d[1]) : 0.12;
                v += soft_light(d, -60.0, 35.0, 2.5, 4000.0);
            }
            map->pixels[(size_t)y * w + x] = (float)v;
        }
    *out = map;
    return MR_OK;
}

/* ---- creating the basis ------------------------------------------------------------------------------------- */

static double map_mean_luminance(const mr_image *map) {
    double sum = 0.0;
    size_t n = (size_t)map->width * (size_t)map->height;
    for (size_t i = 0; i < n; i++) {
        const float *p = map->pixels + i * (size_t)map->channels;
        sum += map->channels >= 3 ? 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2] : p[0];
    }
    return sum / (double)n;
}

/* The options in force: *given with its zero fields read as their defaults and MR_WF_LABEL_OFF as 0 (labels.h), so
 * that a zeroed struct is mr_wf_label_options_default(). */
static mr_wf_label_options options_in_force(const mr_wf_label_options *given) {
    const mr_wf_label_options d = mr_wf_label_options_default();
    mr_wf_label_options o = *given;
    if (o.objective == MR_WF_OBJECTIVE_DEFAULT) o.objective = d.objective;
    if (o.size == 0) o.size = d.size;
    if (o.glossiness_count == 0) {
        o.glossiness_count = d.glossiness_count;
        memcpy(o.glossiness, d.glossiness, sizeof o.glossiness);
    }
    if (o.env_samples == 0) o.env_samples = d.env_samples;
    o.reflection_samples = o.reflection_samples == 0                 ? d.reflection_samples
                           : o.reflection_samples == MR_WF_LABEL_OFF ? 0
                                                                      : o.reflection_samples;
    o.chroma_weight = o.chroma_weight == 0.0                 ? d.chroma_weight
                      : o.chroma_weight == MR_WF_LABEL_OFF ? 0.0
                                                            : o.chroma_weight;
    o.regularisation = o.regularisation == 0.0                 ? d.regularisation
                       : o.regularisation == MR_WF_LABEL_OFF ? 0.0
                                                              : o.regularisation;
    return o;
}

static mr_status check_options(const mr_wf_label_options *o) {
    const char *what = "label options";
    if ((int)o->objective <= MR_WF_OBJECTIVE_DEFAULT || (int)o->objective >= MR_WF_OBJECTIVE_COUNT)
        return mr_fail(MR_ERR_INVALID_ARG, "%s: objective %d unknown", what, (int)o->objective);
    if (o->size < 16 || o->size > 1024)
        return mr_fail(MR_ERR_INVALID_ARG, "%s: size %d outside 16 .. 1024", what, o->size);
    if (o->glossiness_count < 1 || o->glossiness_count > MR_WF_LABEL_MAX_GLOSS)
        return mr_fail(MR_ERR_INVALID_ARG, "%s: glossiness_count %d outside 1 .. %d", what, o->glossiness_count,
                       MR_WF_LABEL_MAX_GLOSS);
    for (int g = 0; g < o->glossiness_count; g++)
        if (!(o->glossiness[g] >= 0.0 && o->glossiness[g] <= 1.0))
            return mr_fail(MR_ERR_INVALID_ARG, "%s: glossiness[%d] = %g outside [0, 1]", what, g, o->glossiness[g]);
    if (o->env_count < 0 || o->env_count > MR_WF_LABEL_MAX_ENVS)
        return mr_fail(MR_ERR_INVALID_ARG, "%s: env_count %d outside 0 .. %d", what, o->env_count,
                       MR_WF_LABEL_MAX_ENVS);
    for (int e = 0; e < o->env_count; e++)
        if (o->envs[e] == NULL) return mr_fail(MR_ERR_INVALID_ARG, "%s: envs[%d] is NULL", what, e);
    if (o->env_samples < 1 || o->env_samples > MR_ENV_MAX_SAMPLES)
        return mr_fail(MR_ERR_INVALID_ARG, "%s: env_samples %d outside 1 .. %d", what, o->env_samples,
                       MR_ENV_MAX_SAMPLES);
    if (o->reflection_samples < 0 || o->reflection_samples > MR_ENV_MAX_REFLECTION_SAMPLES)
        return mr_fail(MR_ERR_INVALID_ARG, "%s: reflection_samples %d outside 0 .. %d", what,
                       o->reflection_samples, MR_ENV_MAX_REFLECTION_SAMPLES);
    if (!(o->chroma_weight >= 0.0) || !isfinite(o->chroma_weight))
        return mr_fail(MR_ERR_INVALID_ARG, "%s: chroma_weight %g must be finite and >= 0", what, o->chroma_weight);
    if (!(o->regularisation >= 0.0) || !isfinite(o->regularisation))
        return mr_fail(MR_ERR_INVALID_ARG, "%s: regularisation %g must be finite and >= 0", what, o->regularisation);
    if (o->threads < 0 || o->threads > 1024)
        return mr_fail(MR_ERR_INVALID_ARG, "%s: threads %d outside 0 (automatic) .. 1024", what, o->threads);
    return MR_OK;
}

/* The three basis images of one plan at glossiness g (labels.h): P from the diffuse component at d = 1, s = 0;
 * Q1 from the specular component there; Q0 from the specular component at s = 1, minus Q1. */
static mr_status render_basis(const mr_render_plan *plan, double g, size_t pixels, label_view *view) {
    const mr_brdf_model *sg = mr_brdf_find("gltf-specgloss");
    if (sg == NULL) return mr_fail(MR_ERR_UNSUPPORTED, "label basis: the gltf-specgloss model is missing");
    int size = mr_render_plan_scene(plan)->width;
    mr_image *diffuse = NULL, *spec0 = NULL, *spec1 = NULL;
    mr_status status = mr_image_create(size, size, 3, &diffuse);
    if (status == MR_OK) status = mr_image_create(size, size, 3, &spec0);
    if (status == MR_OK) status = mr_image_create(size, size, 3, &spec1);
    double dull[7] = {1, 1, 1, 0, 0, 0, g}, mirror[7] = {0, 0, 0, 1, 1, 1, g};
    if (status == MR_OK) status = mr_render_components_into(plan, sg, dull, diffuse, spec0);
    if (status == MR_OK) status = mr_render_components_into(plan, sg, mirror, NULL, spec1);
    if (status == MR_OK) {
        view->p = malloc(3 * pixels * sizeof *view->p);
        view->q0 = malloc(3 * pixels * sizeof *view->q0);
        view->q1 = malloc(3 * pixels * sizeof *view->q1);
        if (view->p == NULL || view->q0 == NULL || view->q1 == NULL)
            status = mr_fail(MR_ERR_NOMEM, "label basis: out of memory for %zu pixels", pixels);
    }
    for (size_t i = 0; status == MR_OK && i < 3 * pixels; i++) {
        view->p[i] = diffuse->pixels[i];
        view->q1[i] = spec0->pixels[i];
        view->q0[i] = spec1->pixels[i] - spec0->pixels[i];
    }
    mr_image_free(diffuse);
    mr_image_free(spec0);
    mr_image_free(spec1);
    return status;
}

mr_status mr_wf_label_scene_create(const mr_wf_label_options *opts, mr_wf_label_scene **out) {
    if (opts == NULL || out == NULL) return mr_fail(MR_ERR_INVALID_ARG, "label scene: NULL options or output");
    const mr_wf_label_options in_force = options_in_force(opts);
    opts = &in_force;
    mr_status status = check_options(opts);
    if (status != MR_OK) return status;
    mr_wf_label_scene *scene = calloc(1, sizeof *scene);
    if (scene == NULL) return mr_fail(MR_ERR_NOMEM, "label scene: out of memory");
    scene->opts = *opts;
    memset(scene->opts.envs, 0, sizeof scene->opts.envs); /* borrowed for this call only */
    scene->size = opts->size;
    int env_count = opts->env_count ? opts->env_count : 2;
    size_t pixels = (size_t)opts->size * (size_t)opts->size;
    scene->views = calloc((size_t)(env_count * opts->glossiness_count), sizeof *scene->views);
    scene->coverage = malloc(pixels * sizeof *scene->coverage);
    scene->interior = malloc(pixels * sizeof *scene->interior);
    if (scene->views == NULL || scene->coverage == NULL || scene->interior == NULL) {
        mr_wf_label_scene_free(scene);
        return mr_fail(MR_ERR_NOMEM, "label scene: out of memory");
    }
    for (int e = 0; status == MR_OK && e < env_count; e++) {
        mr_image *builtin = NULL;
        const mr_image *map = opts->env_count ? opts->envs[e] : NULL;
        if (map == NULL) {
            status = mr_wf_label_builtin_env(e, &builtin);
            map = builtin;
        }
        mr_render_plan *plan = NULL;
        if (status == MR_OK) {
            double mean = map_mean_luminance(map);
            mr_fit_scene_options fit = {opts->size, MR_FIT_LIGHT_45, 0.0};
            mr_scene s = mr_scene_fit(&fit);
            s.lights[0] = mr_light_environment(map, mean > 0.0 ? 0.5 / mean : 1.0, 0.0, opts->env_samples);
            s.lights[0].reflection_samples = opts->reflection_samples;
            s.threads = opts->threads;
            status = mr_render_plan_create(&s, &plan);
        }
        if (status == MR_OK && e == 0) {
            memcpy(scene->coverage, mr_render_plan_coverage(plan), pixels * sizeof *scene->coverage);
            for (size_t i = 0; i < pixels; i++)
                if (scene->coverage[i] >= 1.0f) scene->interior[scene->interior_count++] = (int)i;
        }
        for (int g = 0; status == MR_OK && g < opts->glossiness_count; g++) {
            label_view *view = &scene->views[scene->view_count++];
            status = render_basis(plan, opts->glossiness[g], pixels, view);
            /* exposure: a white Lambertian sphere renders about P (1 - w is near 1 for most pairs) */
            double sum = 0.0;
            for (int k = 0; status == MR_OK && k < scene->interior_count; k++)
                for (int c = 0; c < 3; c++) sum += view->p[3 * (size_t)scene->interior[k] + c];
            view->exposure = sum > 0.0 ? 3.0 * scene->interior_count / sum : 1.0;
            double e2 = view->exposure * view->exposure;
            for (int k = 0; status == MR_OK && k < scene->interior_count; k++)
                for (int c = 0; c < 3; c++) {
                    size_t i = 3 * (size_t)scene->interior[k] + (size_t)c;
                    view->pp[c] += e2 * view->p[i] * view->p[i];
                    view->pq[c] += e2 * view->p[i] * view->q0[i];
                    view->qq[c] += e2 * view->q0[i] * view->q0[i];
                }
        }
        mr_render_plan_free(plan);
        mr_image_free(builtin);
    }
    if (status == MR_OK && scene->interior_count == 0)
        status = mr_fail(MR_ERR_INVALID_ARG, "label scene: the sphere covers no whole pixel at size %d", opts->size);
    if (status != MR_OK) {
        mr_wf_label_scene_free(scene);
        return status;
    }
    *out = scene;
    return MR_OK;
}

/* ---- the objective ------------------------------------------------------------------------------------------ */

/* The objective's per-value transform of exposed radiance y, and its derivative. */
static inline double transform(mr_wf_objective o, double y, double *dy) {
    if (y < 0.0) y = 0.0;
    switch (o) {
    case MR_WF_OBJECTIVE_LINEAR:
        *dy = 1.0;
        return y;
    case MR_WF_OBJECTIVE_DISPLAY:
    case MR_WF_OBJECTIVE_EXPOSED:
    case MR_WF_OBJECTIVE_LUMA: {
        double r = y / (1.0 + y), t = sqrt(r);
        *dy = t > 1e-12 ? 0.5 / t / ((1.0 + y) * (1.0 + y)) : 0.5 / sqrt(1e-12);
        return t;
    }
    default:
        *dy = 1.0 / (y + LOG_FLOOR);
        return log(y + LOG_FLOOR);
    }
}

/* One texel's fixed data: its spec-gloss source coefficients per channel (labels.h) and the analytic anchor. */
#define MAX_VIEWS (MR_WF_LABEL_MAX_ENVS * MR_WF_LABEL_MAX_GLOSS)

static const double REC709[3] = {0.2126, 0.7152, 0.0722};

typedef struct texel {
    double a[3], s[3]; /* source: a_c P + s_c Q0 + Q1 */
    double exposure[MAX_VIEWS]; /* e per view: the view's, or (EXPOSED) the source's mean luminance to 0.18 */
    double *source_t; /* LUMA: per view and interior pixel, T of the source's luminance and of its 3 channels */
    double anchor_albedo[3], anchor_metallic;
} texel;

/* Sum over views and interior pixels of channel c's squared residual for the metal-rough (A, m), normalised to
 * a mean; with gradient and Gauss-Newton curvature in A when asked. */
static double channel_loss(const mr_wf_label_scene *sc, const texel *t, int c, double A, double m, double *grad,
                           double *curv) {
    mr_wf_objective o = sc->opts.objective;
    double sum = 0.0, g = 0.0, h = 0.0;
    double kp = 0.96 * (1.0 - m) * A, kq = (1.0 - m) * DIELECTRIC_F0 + m * A;
    double dkp = 0.96 * (1.0 - m), dkq = m;
    for (int v = 0; v < sc->view_count; v++) {
        const label_view *view = &sc->views[v];
        double e = t->exposure[v];
        for (int k = 0; k < sc->interior_count; k++) {
            size_t i = 3 * (size_t)sc->interior[k] + (size_t)c;
            double P = view->p[i], Q0 = view->q0[i], Q1 = view->q1[i];
            double src = e * (t->a[c] * P + t->s[c] * Q0 + Q1), tgt = e * (kp * P + kq * Q0 + Q1);
            double ds, dt;
            double r = transform(o, tgt, &dt) - transform(o, src, &ds);
            sum += r * r;
            if (grad) {
                double j = dt * e * (dkp * P + dkq * Q0);
                g += r * j;
                h += j * j;
            }
        }
    }
    double n = (double)sc->view_count * sc->interior_count * 3.0;
    if (grad) *grad = 2.0 * g / n;
    if (curv) *curv = 2.0 * h / n;
    return sum / n;
}

/* Channel c's albedo for metallic m: minimises channel_loss + lambda (A - anchor)^2 over [0, 1]. LINEAR is a
 * quadratic in A (Gauss-Newton is exact: one step from anywhere); the others take projected Gauss-Newton steps
 * with step halving, starting from the LINEAR-like step. Returns the channel's regularised loss. */
static double solve_channel(const mr_wf_label_scene *sc, const texel *t, int c, double m, double *albedo) {
    double lambda = sc->opts.regularisation, anchor = t->anchor_albedo[c];
    /* The LINEAR optimum from the views' moments: the residual is (kp - a) P + (kq - s) Q0 with kp = 0.96 (1 - m) A
     * and kq = (1 - m) F0 + m A, a quadratic in A whose sums are pp, pq, qq. It is the answer for LINEAR and the
     * starting point of the Gauss-Newton steps of the others. */
    double uu = 0.0, ur = 0.0, n = (double)sc->view_count * sc->interior_count * 3.0;
    double dkp = 0.96 * (1.0 - m), dkq = m, rq = (1.0 - m) * DIELECTRIC_F0 - t->s[c], rp = -t->a[c];
    for (int v = 0; v < sc->view_count; v++) {
        const label_view *view = &sc->views[v];
        uu += dkp * dkp * view->pp[c] + 2.0 * dkp * dkq * view->pq[c] + dkq * dkq * view->qq[c];
        ur += dkp * rp * view->pp[c] + (dkp * rq + dkq * rp) * view->pq[c] + dkq * rq * view->qq[c];
    }
    double A = (uu + lambda * n) > 0.0 ? mr_clampd((lambda * n * anchor - ur) / (uu + lambda * n), 0.0, 1.0) : anchor;
    if (sc->opts.objective == MR_WF_OBJECTIVE_LINEAR) {
        double dp = dkp * A + rp, dq = dkq * A + rq, sum = 0.0;
        for (int v = 0; v < sc->view_count; v++)
            sum += dp * dp * sc->views[v].pp[c] + 2.0 * dp * dq * sc->views[v].pq[c] + dq * dq * sc->views[v].qq[c];
        *albedo = A;
        return sum / n + lambda * (A - anchor) * (A - anchor);
    }
    double grad, curv;
    double f = channel_loss(sc, t, c, A, m, &grad, &curv) + lambda * (A - anchor) * (A - anchor);
    for (int it = 0; it < GAUSS_NEWTON_STEPS; it++) {
        double gr = grad + 2.0 * lambda * (A - anchor), cv = curv + 2.0 * lambda;
        if (!(cv > 0.0)) break;
        double step = -gr / cv;
        int accepted = 0;
        for (int halve = 0; halve < 4 && !accepted; halve++, step *= 0.5) {
            double next = mr_clampd(A + step, 0.0, 1.0);
            if (next == A) break;
            double ng, nc;
            double nf = channel_loss(sc, t, c, next, m, &ng, &nc) + lambda * (next - anchor) * (next - anchor);
            if (nf <= f) {
                A = next;
                f = nf;
                grad = ng;
                curv = nc;
                accepted = 1;
            }
        }
        if (!accepted) break;
    }
    *albedo = A;
    return f;
}

/* LUMA's loss at (A, m), normalised to a mean over views and pixels; with its gradient and Gauss-Newton matrix
 * (3 x 3, row-major) in A when asked. The channels are coupled through the luminance. */
static double luma_loss(const mr_wf_label_scene *sc, const texel *t, const double A[3], double m, double g[3],
                        double H[9]) {
    double kp[3], kq[3], dkp = 0.96 * (1.0 - m), dkq = m, sum = 0.0;
    for (int c = 0; c < 3; c++) {
        kp[c] = 0.96 * (1.0 - m) * A[c];
        kq[c] = (1.0 - m) * DIELECTRIC_F0 + m * A[c];
    }
    if (g) memset(g, 0, 3 * sizeof *g);
    if (H) memset(H, 0, 9 * sizeof *H);
    const double kc = sc->opts.chroma_weight / 3.0;
    for (int v = 0; v < sc->view_count; v++) {
        const label_view *view = &sc->views[v];
        double e = t->exposure[v];
        for (int k = 0; k < sc->interior_count; k++) {
            const size_t i = 3 * (size_t)sc->interior[k];
            const double *ts = t->source_t + 4 * ((size_t)v * sc->interior_count + k);
            double tgt[3], u[3], yt = 0.0;
            for (int c = 0; c < 3; c++) {
                double P = view->p[i + c], Q0 = view->q0[i + c], Q1 = view->q1[i + c];
                tgt[c] = e * (kp[c] * P + kq[c] * Q0 + Q1);
                u[c] = e * (dkp * P + dkq * Q0);
                yt += REC709[c] * tgt[c];
            }
            double dtt;
            double r = transform(MR_WF_OBJECTIVE_LUMA, yt, &dtt) - ts[0];
            sum += r * r;
            double j[3];
            for (int c = 0; c < 3; c++) j[c] = dtt * REC709[c] * u[c];
            for (int c = 0; c < 3; c++) {
                double dc;
                double rc = transform(MR_WF_OBJECTIVE_LUMA, tgt[c], &dc) - ts[1 + c];
                sum += kc * rc * rc;
                if (g) {
                    double jc = dc * u[c];
                    g[c] += r * j[c] + kc * rc * jc;
                    H[4 * c] += kc * jc * jc;
                    for (int d = 0; d < 3; d++) H[3 * c + d] += j[c] * j[d];
                }
            }
        }
    }
    double n = (double)sc->view_count * sc->interior_count;
    for (int c = 0; g && c < 3; c++) g[c] *= 2.0 / n;
    for (int q = 0; H && q < 9; q++) H[q] *= 2.0 / n;
    return sum / n;
}

/* Solve the 3 x 3 system M x = b by Cramer's rule; 0 if M is singular. */
static int solve3(const double M[9], const double b[3], double x[3]) {
    double det = M[0] * (M[4] * M[8] - M[5] * M[7]) - M[1] * (M[3] * M[8] - M[5] * M[6]) +
                 M[2] * (M[3] * M[7] - M[4] * M[6]);
    if (!(fabs(det) > 1e-300)) return 0;
    for (int c = 0; c < 3; c++) {
        double N[9];
        memcpy(N, M, sizeof N);
        for (int r = 0; r < 3; r++) N[3 * r + c] = b[r];
        x[c] = (N[0] * (N[4] * N[8] - N[5] * N[7]) - N[1] * (N[3] * N[8] - N[5] * N[6]) +
                N[2] * (N[3] * N[7] - N[4] * N[6])) / det;
    }
    return 1;
}

/* LUMA's albedo for metallic m: projected Gauss-Newton in all three channels from the per-channel LINEAR
 * starting point, with step halving. Returns the regularised loss. */
static double luma_solve(const mr_wf_label_scene *sc, const texel *t, double m, double A[3]) {
    double lambda = sc->opts.regularisation;
    const double *anchor = t->anchor_albedo;
    for (int c = 0; c < 3; c++) A[c] = anchor[c];
    double g[3], H[9];
    double reg = 0.0;
    for (int c = 0; c < 3; c++) reg += (A[c] - anchor[c]) * (A[c] - anchor[c]);
    double f = luma_loss(sc, t, A, m, g, H) + lambda * reg;
    for (int it = 0; it < GAUSS_NEWTON_STEPS + 1; it++) {
        double M[9], b[3], step[3];
        memcpy(M, H, sizeof M);
        for (int c = 0; c < 3; c++) {
            M[4 * c] += 2.0 * lambda + 1e-12;
            b[c] = -(g[c] + 2.0 * lambda * (A[c] - anchor[c]));
        }
        if (!solve3(M, b, step)) break;
        int accepted = 0;
        for (int halve = 0; halve < 4 && !accepted; halve++) {
            double next[3], ng[3], nH[9], nreg = 0.0;
            for (int c = 0; c < 3; c++) {
                next[c] = mr_clampd(A[c] + step[c], 0.0, 1.0);
                nreg += (next[c] - anchor[c]) * (next[c] - anchor[c]);
            }
            double nf = luma_loss(sc, t, next, m, ng, nH) + lambda * nreg;
            if (nf <= f) {
                memcpy(A, next, sizeof next);
                memcpy(g, ng, sizeof ng);
                memcpy(H, nH, sizeof nH);
                f = nf;
                accepted = 1;
            }
            for (int c = 0; c < 3; c++) step[c] *= 0.5;
        }
        if (!accepted) break;
    }
    return f;
}

/* The regularised objective at metallic m with the best albedo for it. */
static double metallic_loss(const mr_wf_label_scene *sc, const texel *t, double m, double albedo[3]) {
    double lambda = sc->opts.regularisation, f = lambda * (m - t->anchor_metallic) * (m - t->anchor_metallic);
    if (sc->opts.objective == MR_WF_OBJECTIVE_LUMA) return f + luma_solve(sc, t, m, albedo);
    for (int c = 0; c < 3; c++) f += solve_channel(sc, t, c, m, &albedo[c]) / 3.0;
    return f;
}

static double plain_loss(const mr_wf_label_scene *sc, const texel *t, const double albedo[3], double m) {
    if (sc->opts.objective == MR_WF_OBJECTIVE_LUMA) return luma_loss(sc, t, albedo, m, NULL, NULL);
    double f = 0.0;
    for (int c = 0; c < 3; c++) f += channel_loss(sc, t, c, albedo[c], m, NULL, NULL) / 3.0;
    return f;
}

static double sanitised(double x) { return isfinite(x) ? mr_clampd(x, 0.0, 1.0) : 0.0; }

/* The texel's source coefficients and its analytic anchor (WEIGHTED, glTF reading of the diffuse). */
static mr_status texel_coefficients(const mr_wf_spec *in, texel *t) {
    mr_wf_spec s = *in;
    double smax = 0.0;
    for (int c = 0; c < 3; c++) {
        s.diffuse[c] = sanitised(s.diffuse[c]);
        s.specular[c] = sanitised(s.specular[c]);
        smax = fmax(smax, s.specular[c]);
    }
    s.roughness = 0.0;
    for (int c = 0; c < 3; c++) {
        t->a[c] = s.diffuse[c] * (1.0 - smax) * (1.0 - s.specular[c]);
        t->s[c] = s.specular[c];
    }
    mr_wf_options o = mr_wf_options_default();
    o.method = MR_WF_WEIGHTED;
    o.spec_diffuse = MR_WF_DIFFUSE_SPECGLOSS;
    mr_wf_metal w;
    mr_status status = mr_wf_spec_to_metal(&s, &o, &w, NULL);
    if (status != MR_OK) return status;
    for (int c = 0; c < 3; c++) t->anchor_albedo[c] = w.albedo[c];
    t->anchor_metallic = w.metallic;
    t->source_t = NULL;
    return MR_OK;
}

/* texel_coefficients, then the per-view exposures and (LUMA) the source's transformed pixels; the caller frees
 * t->source_t. */
static mr_status texel_init(const mr_wf_label_scene *sc, const mr_wf_spec *in, texel *t) {
    mr_status status = texel_coefficients(in, t);
    if (status != MR_OK) return status;
    for (int v = 0; v < sc->view_count; v++) {
        const label_view *view = &sc->views[v];
        t->exposure[v] = view->exposure;
        if (sc->opts.objective != MR_WF_OBJECTIVE_EXPOSED && sc->opts.objective != MR_WF_OBJECTIVE_LUMA) continue;
        double sum = 0.0;
        for (int k = 0; k < sc->interior_count; k++)
            for (int c = 0; c < 3; c++) {
                size_t i = 3 * (size_t)sc->interior[k] + (size_t)c;
                sum += REC709[c] * (t->a[c] * view->p[i] + t->s[c] * view->q0[i] + view->q1[i]);
            }
        if (sum > 0.0) t->exposure[v] = 0.18 * sc->interior_count / sum;
    }
    if (sc->opts.objective != MR_WF_OBJECTIVE_LUMA) return MR_OK;
    t->source_t = malloc(4 * (size_t)sc->view_count * (size_t)sc->interior_count * sizeof *t->source_t);
    if (t->source_t == NULL) return mr_fail(MR_ERR_NOMEM, "label fit: out of memory");
    for (int v = 0; v < sc->view_count; v++) {
        const label_view *view = &sc->views[v];
        for (int k = 0; k < sc->interior_count; k++) {
            const size_t i = 3 * (size_t)sc->interior[k];
            double *ts = t->source_t + 4 * ((size_t)v * sc->interior_count + k), y = 0.0, d;
            for (int c = 0; c < 3; c++) {
                double x = t->exposure[v] * (t->a[c] * view->p[i + c] + t->s[c] * view->q0[i + c] + view->q1[i + c]);
                ts[1 + c] = transform(MR_WF_OBJECTIVE_LUMA, x, &d);
                y += REC709[c] * x;
            }
            ts[0] = transform(MR_WF_OBJECTIVE_LUMA, y, &d);
        }
    }
    return MR_OK;
}

mr_status mr_wf_label_fit(const mr_wf_label_scene *scene, const mr_wf_spec *in, mr_wf_metal *out,
                          mr_wf_label_result *result) {
    if (scene == NULL || in == NULL || out == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "label fit: NULL scene, texel or output");
    texel t;
    mr_status status = texel_init(scene, in, &t);
    if (status != MR_OK) return status;
    /* the analytic answer, as a candidate */
    double best_albedo[3], albedo[3];
    double best_m = t.anchor_metallic;
    double best = metallic_loss(scene, &t, best_m, best_albedo);
    int best_index = -1;
    double grid_loss[METALLIC_GRID];
    for (int i = 0; i < METALLIC_GRID; i++) {
        double m = (double)i / (METALLIC_GRID - 1);
        grid_loss[i] = metallic_loss(scene, &t, m, albedo);
        if (grid_loss[i] < best) {
            best = grid_loss[i];
            best_m = m;
            best_index = i;
            memcpy(best_albedo, albedo, sizeof albedo);
        }
    }
    if (best_index >= 0) {
        /* golden-section refinement in the grid cells on either side of the best grid point */
        double lo = (double)(best_index > 0 ? best_index - 1 : 0) / (METALLIC_GRID - 1);
        double hi = (double)(best_index < METALLIC_GRID - 1 ? best_index + 1 : METALLIC_GRID - 1) /
                    (METALLIC_GRID - 1);
        const double phi = 0.6180339887498949;
        double x1 = hi - phi * (hi - lo), x2 = lo + phi * (hi - lo);
        double a1[3], a2[3];
        double f1 = metallic_loss(scene, &t, x1, a1), f2 = metallic_loss(scene, &t, x2, a2);
        for (int it = 0; it < GOLDEN_STEPS; it++) {
            if (f1 < f2) {
                hi = x2;
                x2 = x1;
                f2 = f1;
                memcpy(a2, a1, sizeof a1);
                x1 = hi - phi * (hi - lo);
                f1 = metallic_loss(scene, &t, x1, a1);
            } else {
                lo = x1;
                x1 = x2;
                f1 = f2;
                memcpy(a1, a2, sizeof a2);
                x2 = lo + phi * (hi - lo);
                f2 = metallic_loss(scene, &t, x2, a2);
            }
        }
        if (f1 < best) {
            best = f1;
            best_m = x1;
            memcpy(best_albedo, a1, sizeof a1);
        }
        if (f2 < best) {
            best = f2;
            best_m = x2;
            memcpy(best_albedo, a2, sizeof a2);
        }
    }
    for (int c = 0; c < 3; c++) out->albedo[c] = best_albedo[c];
    out->metallic = best_m;
    out->roughness = 0.0;
    if (result) {
        result->loss = plain_loss(scene, &t, best_albedo, best_m);
        result->analytic_loss = plain_loss(scene, &t, t.anchor_albedo, t.anchor_metallic);
        result->kept_analytic = best_index < 0;
    }
    free(t.source_t);
    return MR_OK;
}

mr_status mr_wf_label_loss(const mr_wf_label_scene *scene, const mr_wf_spec *in, const mr_wf_metal *metal,
                           double *loss) {
    if (scene == NULL || in == NULL || metal == NULL || loss == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "label loss: NULL argument");
    texel t;
    mr_status status = texel_init(scene, in, &t);
    if (status != MR_OK) return status;
    double albedo[3];
    for (int c = 0; c < 3; c++) albedo[c] = sanitised(metal->albedo[c]);
    *loss = plain_loss(scene, &t, albedo, sanitised(metal->metallic));
    free(t.source_t);
    return MR_OK;
}

mr_status mr_wf_label_render(const mr_wf_label_scene *scene, int view, const mr_wf_spec *spec,
                             const mr_wf_metal *metal, mr_image *image) {
    if (scene == NULL || image == NULL || (spec == NULL) == (metal == NULL))
        return mr_fail(MR_ERR_INVALID_ARG, "label render: NULL scene or image, or not exactly one material");
    if (view < 0 || view >= scene->view_count)
        return mr_fail(MR_ERR_INVALID_ARG, "label render: view %d outside 0 .. %d", view, scene->view_count - 1);
    if (image->width != scene->size || image->height != scene->size || image->channels != 3)
        return mr_fail(MR_ERR_INVALID_ARG, "label render: the image must be %d x %d RGB", scene->size, scene->size);
    double kp[3], kq[3];
    if (spec) {
        texel t;
        mr_status status = texel_coefficients(spec, &t);
        if (status != MR_OK) return status;
        for (int c = 0; c < 3; c++) {
            kp[c] = t.a[c];
            kq[c] = t.s[c];
        }
    } else {
        double m = sanitised(metal->metallic);
        for (int c = 0; c < 3; c++) {
            double A = sanitised(metal->albedo[c]);
            kp[c] = 0.96 * (1.0 - m) * A;
            kq[c] = (1.0 - m) * DIELECTRIC_F0 + m * A;
        }
    }
    const label_view *v = &scene->views[view];
    size_t n = (size_t)scene->size * (size_t)scene->size;
    for (size_t i = 0; i < n; i++)
        for (int c = 0; c < 3; c++) {
            size_t j = 3 * i + (size_t)c;
            image->pixels[j] = (float)(kp[c] * v->p[j] + kq[c] * v->q0[j] + v->q1[j]);
        }
    return MR_OK;
}

/* ---- object SSIM --------------------------------------------------------------------------------------------- */

/* The side of the largest centred square of whole pixels inside the sphere (0 if none of 11 pixels fits). */
static int inner_side(const mr_wf_label_scene *scene) {
    int size = scene->size;
    for (int side = size; side >= 11; side--) {
        int x0 = (size - side) / 2, ok = 1;
        for (int y = 0; y < side && ok; y++)
            for (int x = 0; x < side && ok; x++)
                if (scene->coverage[(size_t)(y + x0) * size + (x + x0)] < 1.0f) ok = 0;
        if (ok) return side;
    }
    return 0;
}

static void crop_centre(const mr_image *img, mr_image *out) {
    int x0 = (img->width - out->width) / 2;
    for (int y = 0; y < out->height; y++)
        memcpy(out->pixels + 3 * (size_t)y * out->width, img->pixels + 3 * ((size_t)(y + x0) * img->width + x0),
               3 * (size_t)out->width * sizeof *out->pixels);
}

mr_status mr_wf_label_ssim(const mr_wf_label_scene *scene, const mr_wf_spec *spec, const mr_wf_metal *metal,
                           double *ssim) {
    if (scene == NULL || spec == NULL || metal == NULL || ssim == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "label ssim: NULL argument");
    int side = inner_side(scene), size = scene->size;
    if (side < 11) return mr_fail(MR_ERR_INVALID_ARG, "label ssim: a %d-pixel sphere holds no 11 x 11 square", size);
    mr_image *src = NULL, *dst = NULL, *a = NULL, *b = NULL;
    mr_status status = mr_image_create(size, size, 3, &src);
    if (status == MR_OK) status = mr_image_create(size, size, 3, &dst);
    if (status == MR_OK) status = mr_image_create(side, side, 3, &a);
    if (status == MR_OK) status = mr_image_create(side, side, 3, &b);
    double sum = 0.0;
    for (int v = 0; status == MR_OK && v < scene->view_count; v++) {
        status = mr_wf_label_render(scene, v, spec, NULL, src);
        if (status == MR_OK) status = mr_wf_label_render(scene, v, NULL, metal, dst);
        if (status != MR_OK) break;
        crop_centre(src, a);
        crop_centre(dst, b);
        double lum = 0.0;
        for (size_t i = 0; i < (size_t)side * side; i++)
            for (int c = 0; c < 3; c++) lum += REC709[c] * a->pixels[3 * i + c];
        mr_ssim_options o = {lum > 0.0 ? 0.18 * side * side / lum : 1.0, 0, NULL, 0};
        double s = 0.0;
        status = mr_ssim(a, b, &o, &s, NULL);
        sum += s;
    }
    mr_image_free(src);
    mr_image_free(dst);
    mr_image_free(a);
    mr_image_free(b);
    if (status == MR_OK) *ssim = sum / scene->view_count;
    return status;
}
