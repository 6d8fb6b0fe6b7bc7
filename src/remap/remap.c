/*
 * remap.c — uniform image-based remapping (contract and strategies in remap.h).
 *
 * The fit works in normalised coordinates u in [0,1] per fitted scalar (log-spaced where the descriptor flags
 * MR_PARAM_LOG_SCALE), as nlopt's documentation recommends for derivative-free local methods; the gradient local
 * stage (levenberg.h) steps in the same coordinates, with the chain rule through to_value. Two objective
 * forms share the context below:
 *   - direct: render the target with every fitted value and sum squared differences (the paper's strategies);
 *   - projected (AUTO): render the basis images of the affine parameters for the current nonlinear values,
 *     solve the bounded linear least-squares problem for the affine parameters exactly, and return its
 *     residual (Golub and Pereyra's variable projection, SIAM J. Numer. Anal. 10(2), 1973).
 * Sums run over the pixels the object covers, in a fixed order, in double precision.
 */
#include "remap.h"

#include <math.h>
#include <nlopt.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "../metrics/metrics.h"
#include "../mr_internal.h"
#include "../render/render.h"
#include "levenberg.h"

#define MAX_SLOTS MR_BRDF_MAX_VALUES
#define DEFAULT_MAX_EVALUATIONS 400
#define DEFAULT_XTOL 1e-6
#define DEFAULT_GRID_1D 16
#define DEFAULT_GRID_2D 8
#define DEFAULT_GRID_3D 6
#define DEFAULT_STARTS 8
#define DEFAULT_SEED 1
#define MAX_REFINED_STARTS 3
/* Outcome thresholds (remap.h):
 *   - a residual RMS above 25 % of the source's RMS radiance is "unreachable" (a lobe that merely has another
 *     shape, Ward against GGX's tails, typically stays near 10 %);
 *   - a parameter on its range's edge is "at-bound" only while the residual exceeds 1 %: a bound the fit
 *     reaches exactly is the source's value;
 *   - AUTO refines against real renders when its affine prediction misses the render by more than 1 % of the
 *     source's RMS radiance (PREDICTION_TOLERANCE); a render that departs from affine behaviour in the linear
 *     parameters by more than 0.5 % (affine_departure) means the model rescaled the solution (Mitsuba's
 *     trimming, which engages with a 1 % step: 0.99 / max(rho_d + rho_s));
 *   - two minima within 1 % of each other's error but 0.1 apart (normalised) are ambiguous;
 *   - a local fit whose error the global search lowers by more than 10 % stopped in a local minimum, unless its
 *     residual is below 0.1 % of the source's RMS radiance already. */
#define UNREACHABLE_RELATIVE_RMSE 0.25
#define AT_BOUND_RELATIVE_RMSE 0.01
#define RELATIVE_RMS_FLOOR 1e-4
#define PREDICTION_TOLERANCE 0.01
#define AMBIGUITY_ERROR 0.01
#define AMBIGUITY_DISTANCE 0.1
#define LOCAL_MINIMUM_GAIN 0.10
#define LOCAL_MINIMUM_FLOOR 1e-3
#define AFFINE_DEPARTURE_TOLERANCE 0.005
/* Resolution (remap.h, UNDER_RESOLVED): a shape parameter is only bounded when values whose lobes are a factor
 * RESOLUTION_RANGE apart in width render within RESOLUTION_TOLERANCE of the source's RMS radiance of each other;
 * lobes under LOBE_ENERGY_FLOOR of the fitted render's energy have no shape to resolve. The range is walked in
 * factors of 2, at most RESOLUTION_STEPS each way. */
#define RESOLUTION_TOLERANCE 0.005
#define RESOLUTION_RANGE 4.0
#define RESOLUTION_STEPS 12
#define LOBE_ENERGY_FLOOR 1e-3
/* mr_remap's closer look (remap.h, UNDER_RESOLVED): the highlight ZOOM times closer; a fit whose render there
 * misses the source's by more than ZOOM_RELATIVE_RMSE and ZOOM_GAIN times its own relative RMSE (at least 1 %)
 * matched a lobe the fit scene's pixels do not resolve. */
#define ZOOM 8.0
#define ZOOM_RELATIVE_RMSE 0.05
#define ZOOM_GAIN 3.0

static const char *const strategy_names[MR_REMAP_STRATEGY_COUNT] = {"auto", "single", "two", "three", "joint"};
static const char *const local_method_names[MR_LOCAL_METHOD_COUNT] = {"auto", "gradient", "bobyqa"};
static const char *const outcome_names[MR_FIT_OUTCOME_COUNT] = {"converged", "at-bound", "unreachable",
                                                                "local-minimum", "under-resolved"};

const char *mr_remap_strategy_name(mr_remap_strategy strategy) {
    return (unsigned)strategy < MR_REMAP_STRATEGY_COUNT ? strategy_names[strategy] : NULL;
}

mr_status mr_remap_strategy_from_name(const char *name, mr_remap_strategy *out) {
    for (int i = 0; i < MR_REMAP_STRATEGY_COUNT; i++)
        if (name != NULL && strcmp(name, strategy_names[i]) == 0) {
            *out = (mr_remap_strategy)i;
            return MR_OK;
        }
    return mr_fail(MR_ERR_INVALID_ARG, "unknown strategy '%s' (valid: auto, single, two, three, joint)",
                   name ? name : "(null)");
}

const char *mr_fit_outcome_name(mr_fit_outcome outcome) {
    return (unsigned)outcome < MR_FIT_OUTCOME_COUNT ? outcome_names[outcome] : NULL;
}

const char *mr_local_method_name(mr_local_method method) {
    return (unsigned)method < MR_LOCAL_METHOD_COUNT ? local_method_names[method] : NULL;
}

mr_status mr_local_method_from_name(const char *name, mr_local_method *out) {
    for (int i = 0; name != NULL && i < MR_LOCAL_METHOD_COUNT; i++)
        if (strcmp(name, local_method_names[i]) == 0) {
            *out = (mr_local_method)i;
            return MR_OK;
        }
    return mr_fail(MR_ERR_INVALID_ARG, "unknown local method '%s' (valid: auto, gradient, bobyqa)",
                   name ? name : "(null)");
}

mr_status mr_fit_outcome_from_name(const char *name, mr_fit_outcome *out) {
    for (int o = 0; name != NULL && o < MR_FIT_OUTCOME_COUNT; o++)
        if (strcmp(name, outcome_names[o]) == 0) {
            *out = (mr_fit_outcome)o;
            return MR_OK;
        }
    return mr_fail(MR_ERR_INVALID_ARG,
                   "unknown fit outcome '%s' (valid: converged, at-bound, unreachable, local-minimum, under-resolved)",
                   name ? name : "(null)");
}

mr_remap_options mr_remap_options_default(void) {
    mr_remap_options o;
    memset(&o, 0, sizeof o);
    o.strategy = MR_REMAP_AUTO;
    o.max_evaluations = DEFAULT_MAX_EVALUATIONS;
    o.xtol = DEFAULT_XTOL;
    o.grid_points = 0;
    o.starts = DEFAULT_STARTS;
    o.seed = DEFAULT_SEED;
    o.target_values = NULL;
    return o;
}

/* ---- the fit context ------------------------------------------------------------------------------------ */

/* One fitted scalar: a packed slot with its bounds and scale. */
typedef struct fitted_slot {
    int slot;
    int param;
    double lo, hi;
    int log_scale;
} fitted_slot;

typedef struct fit_context {
    const mr_render_plan *plan;
    const mr_brdf_model *model;
    mr_remap_options opts;
    double base[MAX_SLOTS];  /* current full value vector; fixed parameters and switches never change */
    int value_count;

    fitted_slot nonlinear[MAX_SLOTS]; /* NONLINEAR parameters, fitted */
    int nonlinear_count;
    int linear_params[MAX_SLOTS];     /* LINEAR/AFFINE parameter indices, fitted */
    int linear_param_count;
    fitted_slot linear[MAX_SLOTS];    /* their slots */
    int linear_count;

    /* direct objective: which slots vary (pointers into nonlinear/linear) and against which image */
    const fitted_slot *vary[2 * MAX_SLOTS];
    int vary_count;
    const mr_image *goal;
    mr_component component;
    /* projection: the component the basis renders show and ctx->goal holds (FULL, or one lobe while AUTO
     * fits that lobe's shape, lobe_staged_fit) */
    mr_component projection_component;

    const int *pixels; /* covered pixels, ascending */
    int pixel_count;
    mr_image *scratch;               /* a render */
    mr_image *basis[MAX_SLOTS + 1];  /* projection: R0 and one render per linear parameter */
    /* The projection's fast path: at most one linear parameter per lobe, each in the diffuse or the specular
     * lobe only, so one render split into components yields both basis images (split_lobes); if moreover the
     * model renders black with every linear parameter at 0 (homogeneous), R0 needs no render at all. */
    int split_lobes;
    int homogeneous;
    mr_image *lobe_images[4];        /* diffuse and specular at all-zero (0, 1) and all-one (2, 3) values */
    long renders;
    mr_status failure;               /* set when a render fails inside an nlopt callback */
    nlopt_opt running;
    int warm;                        /* AUTO/JOINT from opts.initial_values: one local refinement, no grid */
    int gradient;                    /* local fits by Levenberg-Marquardt with derivatives (mr_local_method) */
    /* What ctx->scratch holds (render_values records it): a render of scratch_component at scratch_values, when
     * scratch_valid; the verdict renders the same values again only when it does not (built-in renders only: an
     * external renderer's noise would make two renders of one material differ) */
    int scratch_valid;
    mr_component scratch_component;
    double scratch_values[MAX_SLOTS];
    mr_image *derivatives[2 * MAX_SLOTS]; /* gradient fits: d render / d fitted slot, one image per slot */
    /* The last projection's columns and Gram matrix (project), for the gradient fit's Gauss-Newton matrix */
    int column_count;
    int column_image[MAX_SLOTS], column_channel[MAX_SLOTS];
    double gram[MAX_SLOTS * MAX_SLOTS];
    int external;                    /* opts.target_renderer is an external renderer: every render goes to it */
} fit_context;

static double to_value(const fitted_slot *s, double u) {
    u = mr_clampd(u, 0.0, 1.0);
    if (s->log_scale) return exp(log(s->lo) + u * (log(s->hi) - log(s->lo)));
    return s->lo + u * (s->hi - s->lo);
}

static double to_unit(const fitted_slot *s, double v) {
    if (!(s->hi > s->lo)) return 0.0;
    v = mr_clampd(v, s->lo, s->hi);
    if (s->log_scale) return (log(v) - log(s->lo)) / (log(s->hi) - log(s->lo));
    return (v - s->lo) / (s->hi - s->lo);
}

static fitted_slot make_slot(const mr_brdf_model *m, int param, int slot) {
    const mr_brdf_param *p = &m->params[param];
    fitted_slot s;
    s.slot = slot;
    s.param = param;
    s.lo = p->min_value;
    s.hi = p->max_value;
    s.log_scale = (p->flags & MR_PARAM_LOG_SCALE) && p->min_value > 0.0;
    return s;
}

/* Sum of squared differences between `image` and `goal` over the covered pixels. */
static double sse_against(const fit_context *ctx, const mr_image *image, const mr_image *goal) {
    double sum = 0.0;
    for (int i = 0; i < ctx->pixel_count; i++) {
        const float *a = image->pixels + (size_t)ctx->pixels[i] * 3, *b = goal->pixels + (size_t)ctx->pixels[i] * 3;
        for (int c = 0; c < 3; c++) {
            double d = (double)a[c] - (double)b[c];
            sum += d * d;
        }
    }
    return sum;
}

/* Energy (sum of squares over the covered pixels) of a render. */
static double image_energy(const fit_context *ctx, const mr_image *image) {
    double sum = 0.0;
    for (int i = 0; i < ctx->pixel_count; i++)
        for (int c = 0; c < 3; c++) {
            double v = image->pixels[(size_t)ctx->pixels[i] * 3 + c];
            sum += v * v;
        }
    return sum;
}

/* The target's components by the fit's renderer: the built-in one in process; an external one without component
 * renders leaves them to the built-in model (remap.h, target_renderer). */
static mr_status render_components(const fit_context *ctx, const double *values, mr_image *diffuse,
                                   mr_image *specular) {
    if (ctx->external && mr_renderer_has_components(ctx->opts.target_renderer))
        return mr_renderer_render(ctx->opts.target_renderer, ctx->plan, ctx->model, values, NULL, diffuse, specular);
    return mr_render_components_into_threads(ctx->plan, ctx->opts.threads, ctx->model, values, diffuse, specular);
}

static int render_values(fit_context *ctx, const double *values, mr_component component, mr_image *into) {
    mr_status status;
    if (into == ctx->scratch) ctx->scratch_valid = 0;
    if (ctx->external)
        status = mr_renderer_render(ctx->opts.target_renderer, ctx->plan, ctx->model, values,
                                    component == MR_COMPONENT_FULL ? into : NULL,
                                    component == MR_COMPONENT_DIFFUSE ? into : NULL,
                                    component == MR_COMPONENT_SPECULAR ? into : NULL);
    else
        status = mr_render_into_threads(ctx->plan, ctx->opts.threads, ctx->model, values, component, into);
    ctx->renders++;
    if (status != MR_OK) {
        ctx->failure = status;
        if (ctx->running) nlopt_force_stop(ctx->running);
        return 0;
    }
    if (into == ctx->scratch && !ctx->external) {
        ctx->scratch_valid = 1;
        ctx->scratch_component = component;
        memcpy(ctx->scratch_values, values, (size_t)ctx->value_count * sizeof *values);
    }
    return 1;
}

/* The full render of `values` into ctx->scratch, unless it holds that render already (render_values' record). */
static int render_full_into_scratch(fit_context *ctx, const double *values) {
    if (ctx->scratch_valid && ctx->scratch_component == MR_COMPONENT_FULL &&
        memcmp(ctx->scratch_values, values, (size_t)ctx->value_count * sizeof *values) == 0)
        return 1;
    return render_values(ctx, values, MR_COMPONENT_FULL, ctx->scratch);
}

/* ---- variable projection -------------------------------------------------------------------------------- */

/* Minimise 0.5 b'Gb - h'b over lo <= b <= hi (G symmetric positive semi-definite, k <= 3*MAX_SLOTS) by cyclic
 * coordinate descent with exact clamped steps; this converges to the global minimum of a convex box-constrained
 * quadratic. Columns with no energy (G_jj = 0: the parameter does not show in this scene) keep b_j as given. */
static void box_least_squares(int k, const double *G, const double *h, const double *lo, const double *hi,
                              double *b) {
    for (int sweep = 0; sweep < 1000; sweep++) {
        double largest_step = 0.0;
        for (int j = 0; j < k; j++) {
            double gjj = G[j * k + j];
            if (!(gjj > 0.0)) continue;
            double r = h[j];
            for (int i = 0; i < k; i++)
                if (i != j) r -= G[j * k + i] * b[i];
            double next = mr_clampd(r / gjj, lo[j], hi[j]);
            double step = fabs(next - b[j]) / (1.0 + fabs(b[j]));
            if (step > largest_step) largest_step = step;
            b[j] = next;
        }
        if (largest_step < 1e-13) break;
    }
}

/* For the nonlinear values already in ctx->base: render the basis, solve for the linear slots (written into
 * ctx->base) and return the squared residual against ctx->goal, or NAN if a render failed. */
/* The basis renders with one component render per value vector (the split_lobes fast path): the render at
 * all-zero linear values, R0, and for each parameter p the render with p at 1, R_p. A parameter confined to one
 * lobe changes only that component, so R_p is its lobe's component plus the other lobe's all-zero one
 * (split_value builds both per pixel from ctx->lobe_images; no basis image is written).
 * The shared render sets every linear parameter to SPLIT_PROBE, not 1, and scales the difference back: with
 * all of them at 1 at once, Ward's diffuse + specular = 2 would trigger Mitsuba's energy trimming and halve
 * the basis, while 2 x 0.25 stays in the affine region. */
#define SPLIT_PROBE 0.25
static int split_basis(fit_context *ctx, const double *zero, const double *one) {
    if (!ctx->homogeneous) {
        if (render_components(ctx, zero, ctx->lobe_images[0], ctx->lobe_images[1]) != MR_OK)
            return render_values(ctx, zero, MR_COMPONENT_FULL, ctx->basis[0]); // records the failure
        ctx->renders++;
    }
    if (render_components(ctx, one, ctx->lobe_images[2], ctx->lobe_images[3]) != MR_OK)
        return render_values(ctx, one, MR_COMPONENT_FULL, ctx->basis[0]);
    ctx->renders++;
    return 1;
}

/* What the projection's pixel loops read (projection_sums, linearise_sums), copied out of the context so that the
 * compiler keeps it in registers: the goal, R0 and the R_p of the basis renders or the four lobe images of
 * split_basis, and the derivative images. */
typedef struct basis_view {
    const float *goal;
    const float *basis[MAX_SLOTS + 1];      /* R0, R_1 .. R_P (not split_lobes) */
    const float *lobe[4];                   /* ctx->lobe_images (split_lobes); [0], [1] NULL when homogeneous */
    const float *derivative[2 * MAX_SLOTS]; /* ctx->derivatives made so far */
    int keep_diffuse, keep_specular;        /* the projection component's lobes (split_lobes) */
    int split;                              /* ctx->split_lobes */
    unsigned char diffuse_param[MAX_SLOTS];
} basis_view;

static void basis_view_init(const fit_context *ctx, basis_view *v) {
    memset(v, 0, sizeof *v);
    v->goal = ctx->goal->pixels;
    v->split = ctx->split_lobes;
    v->keep_diffuse = ctx->projection_component != MR_COMPONENT_SPECULAR;
    v->keep_specular = ctx->projection_component != MR_COMPONENT_DIFFUSE;
    for (int p = 0; p < ctx->linear_param_count; p++)
        v->diffuse_param[p] = ctx->model->params[ctx->linear_params[p]].lobe == MR_LOBE_DIFFUSE;
    if (ctx->split_lobes)
        for (int i = 0; i < 4; i++) v->lobe[i] = i < 2 && ctx->homogeneous ? NULL : ctx->lobe_images[i]->pixels;
    else
        for (int p = 0; p <= ctx->linear_param_count; p++) v->basis[p] = ctx->basis[p]->pixels;
    for (int a = 0; a < 2 * MAX_SLOTS; a++)
        if (ctx->derivatives[a] != NULL) v->derivative[a] = ctx->derivatives[a]->pixels;
}

/* R0 and the R_p (into r[p], p < P) at value index `at` (pixel * 3 + channel). From split_basis's lobe images: a
 * parameter confined to one lobe changes only that lobe, so R_p is its lobe at 1 plus the other lobe at 0. */
static MR_ALWAYS_INLINE float basis_values(const basis_view *v, const int P, size_t at, float *r) {
    if (!v->split) {
        for (int p = 0; p < P; p++) r[p] = v->basis[p + 1][at];
        return v->basis[0][at];
    }
    float d0 = v->lobe[0] != NULL ? v->lobe[0][at] : 0.0f;
    float s0 = v->lobe[1] != NULL ? v->lobe[1][at] : 0.0f;
    float d1 = d0 + (v->lobe[2][at] - d0) / (float)SPLIT_PROBE;
    float s1 = s0 + (v->lobe[3][at] - s0) / (float)SPLIT_PROBE;
    if (!v->keep_diffuse) d0 = d1 = 0.0f;
    if (!v->keep_specular) s0 = s1 = 0.0f;
    for (int p = 0; p < P; p++) r[p] = v->diffuse_param[p] ? d1 + s0 : d0 + s1;
    return d0 + s0;
}

/* One lane of the projection's sums (projection_sums): every quantity summed over the pixels i with i % SUM_LANES
 * equal to the lane. */
#define SUM_LANES 4
typedef struct projection_lane {
    double total, h[MAX_SLOTS], g[MAX_SLOTS][MAX_SLOTS];
} projection_lane;

static MR_ALWAYS_INLINE void projection_add(const basis_view *v, const int P, size_t at, projection_lane *lane) {
    float r[MAX_SLOTS];
    const float r0 = basis_values(v, P, at, r);
    const double base = r0, residual = (double)v->goal[at] - base;
    lane->total += residual * residual;
    for (int p = 0; p < P; p++) {
        const double d = (double)r[p] - base;
        lane->h[p] += d * residual;
        for (int q = 0; q <= p; q++) lane->g[p][q] += d * ((double)r[q] - base);
    }
}

/* The projection's sums over the covered pixels, per image channel c and basis render p, q < P (P the linear
 * parameter count): H[c][p] = sum d_p (goal - R0), S[c][p][q] = sum d_p d_q (q <= p) with d_p = R_p - R0, and
 * *constant = sum (goal - R0)^2 over all channels. */
static MR_ALWAYS_INLINE void projection_sums(const fit_context *ctx, const int P, double *constant,
                                             double H[3][MAX_SLOTS], double S[3][MAX_SLOTS][MAX_SLOTS]) {
    basis_view v;
    basis_view_init(ctx, &v);
    const int *pixels = ctx->pixels, n = ctx->pixel_count, whole = n - n % SUM_LANES;
    double sum[3];
    // Channel by channel, the sums in registers (per pixel and channel, indexed by the channel, they went through
    // memory: a fifth of a remap), each in SUM_LANES partial sums added up in a fixed order at the end (one running
    // sum per quantity made every pixel wait for the previous pixel's additions); the same on every run.
    for (int c = 0; c < 3; c++) {
        projection_lane l0 = {0}, l1 = {0}, l2 = {0}, l3 = {0};
        for (int i = 0; i < whole; i += SUM_LANES) {
            projection_add(&v, P, (size_t)pixels[i] * 3 + (size_t)c, &l0);
            projection_add(&v, P, (size_t)pixels[i + 1] * 3 + (size_t)c, &l1);
            projection_add(&v, P, (size_t)pixels[i + 2] * 3 + (size_t)c, &l2);
            projection_add(&v, P, (size_t)pixels[i + 3] * 3 + (size_t)c, &l3);
        }
        for (int i = whole; i < n; i++) projection_add(&v, P, (size_t)pixels[i] * 3 + (size_t)c, &l0);
        sum[c] = (l0.total + l1.total) + (l2.total + l3.total);
        for (int p = 0; p < P; p++) {
            H[c][p] = (l0.h[p] + l1.h[p]) + (l2.h[p] + l3.h[p]);
            for (int q = 0; q <= p; q++) S[c][p][q] = (l0.g[p][q] + l1.g[p][q]) + (l2.g[p][q] + l3.g[p][q]);
        }
    }
    *constant = sum[0] + sum[1] + sum[2];
}

static double project(fit_context *ctx) {
    double values[MAX_SLOTS];
    memcpy(values, ctx->base, sizeof values);
    for (int j = 0; j < ctx->linear_count; j++) values[ctx->linear[j].slot] = 0.0;
    if (ctx->split_lobes) {
        double one[MAX_SLOTS];
        memcpy(one, values, sizeof one);
        for (int j = 0; j < ctx->linear_count; j++) one[ctx->linear[j].slot] = SPLIT_PROBE;
        if (!split_basis(ctx, values, one)) return NAN;
    } else {
        if (!render_values(ctx, values, ctx->projection_component, ctx->basis[0])) return NAN;
        for (int p = 0; p < ctx->linear_param_count; p++) {
            int param = ctx->linear_params[p];
            int offset = mr_brdf_param_offset(ctx->model, param);
            double one[MAX_SLOTS];
            memcpy(one, values, sizeof one);
            for (int c = 0; c < ctx->model->params[param].channels; c++) one[offset + c] = 1.0;
            if (!render_values(ctx, one, ctx->projection_component, ctx->basis[p + 1])) return NAN;
        }
    }

    // Columns: one per linear slot. An RGB parameter's channel c drives image channel c only (the roles
    // test_brdf checks), so its column is its basis image restricted to that channel.
    const int k = ctx->linear_count;
    double *G = ctx->gram, h[MAX_SLOTS] = {0}, lo[MAX_SLOTS], hi[MAX_SLOTS], b[MAX_SLOTS];
    int *column_image = ctx->column_image, *column_channel = ctx->column_channel;
    memset(G, 0, sizeof ctx->gram);
    ctx->column_count = k;
    for (int j = 0, p = 0; p < ctx->linear_param_count; p++) {
        int channels = ctx->model->params[ctx->linear_params[p]].channels;
        for (int c = 0; c < channels; c++, j++) {
            column_image[j] = p + 1;
            column_channel[j] = channels == 3 ? c : -1;
        }
    }
    // Sums per image channel and basis image first (P images, at most MAX_SLOTS), then the columns' products
    // from them: a column is nonzero in its own channel only (or in all three), so this does per pixel what the
    // column-by-column products did with mostly zero factors (it was 14 % of a remap).
    const int P = ctx->linear_param_count;
    double constant = 0.0, S[3][MAX_SLOTS][MAX_SLOTS] = {{{0}}}, H[3][MAX_SLOTS] = {{0}};
    switch (P) { // constant counts let the compiler keep the sums in registers (the common models have 1 or 2)
    case 1: projection_sums(ctx, 1, &constant, H, S); break;
    case 2: projection_sums(ctx, 2, &constant, H, S); break;
    default: projection_sums(ctx, P, &constant, H, S); break;
    }
    for (int a = 0; a < k; a++) {
        const int pa = column_image[a] - 1;
        for (int c = 0; c < 3; c++) {
            if (column_channel[a] >= 0 && column_channel[a] != c) continue;
            h[a] += H[c][pa];
            for (int bb = 0; bb <= a; bb++) {
                const int pb = column_image[bb] - 1;
                if (column_channel[bb] >= 0 && column_channel[bb] != c) continue;
                G[a * k + bb] += pa >= pb ? S[c][pa][pb] : S[c][pb][pa];
            }
        }
    }
    for (int a = 0; a < k; a++)
        for (int bb = a + 1; bb < k; bb++) G[a * k + bb] = G[bb * k + a];
    for (int j = 0; j < k; j++) {
        lo[j] = ctx->linear[j].lo;
        hi[j] = ctx->linear[j].hi;
        b[j] = mr_clampd(ctx->base[ctx->linear[j].slot], lo[j], hi[j]);
    }
    box_least_squares(k, G, h, lo, hi, b);
    double sse = constant;
    for (int a = 0; a < k; a++) {
        sse -= 2.0 * h[a] * b[a];
        for (int bb = 0; bb < k; bb++) sse += b[a] * G[a * k + bb] * b[bb];
    }
    for (int j = 0; j < k; j++) ctx->base[ctx->linear[j].slot] = b[j];
    return sse > 0.0 ? sse : 0.0;
}

static double projected_objective(unsigned n, const double *u, double *grad, void *data) {
    (void)grad;
    fit_context *ctx = data;
    for (unsigned i = 0; i < n; i++) ctx->base[ctx->nonlinear[i].slot] = to_value(&ctx->nonlinear[i], u[i]);
    double sse = project(ctx);
    return isnan(sse) ? HUGE_VAL : sse;
}

static double direct_objective(unsigned n, const double *u, double *grad, void *data) {
    (void)grad;
    fit_context *ctx = data;
    double values[MAX_SLOTS];
    memcpy(values, ctx->base, sizeof values);
    for (unsigned i = 0; i < n; i++) values[ctx->vary[i]->slot] = to_value(ctx->vary[i], u[i]);
    if (!render_values(ctx, values, ctx->component, ctx->scratch)) return HUGE_VAL;
    return sse_against(ctx, ctx->scratch, ctx->goal);
}

/* ---- gradient-based local fits (mr_local_method, levenberg.h) --------------------------------------------- */

/* The relative rounding of a sum of squares of float image differences, below which a gradient fit's steps cannot
 * be judged (levenberg.h, noise): a float carries 24 bits (6e-8). */
#define FLOAT_IMAGE_NOISE 1e-7

/* d value / d u of a fitted slot at u (to_value's derivative). */
static double value_per_unit(const fitted_slot *s, double u) {
    if (s->log_scale) return to_value(s, u) * (log(s->hi) - log(s->lo));
    return s->hi - s->lo;
}

/* Render the derivative images of `count` slots at ctx->base (the component `component`); 0 on a failure. */
static int render_derivatives(fit_context *ctx, const fitted_slot *const *slots, int count, mr_component component) {
    int packed[2 * MAX_SLOTS];
    mr_status status = MR_OK;
    const mr_scene *scene = mr_render_plan_scene(ctx->plan);
    for (int i = 0; i < count; i++) {
        packed[i] = slots[i]->slot;
        if (ctx->derivatives[i] == NULL && status == MR_OK) // made on first use: a fit that never steps needs none
            status = mr_image_create(scene->width, scene->height, 3, &ctx->derivatives[i]);
    }
    if (status != MR_OK) {
        ctx->failure = status;
        return 0;
    }
    status = mr_render_derivatives_into(ctx->plan, ctx->opts.threads, ctx->model, ctx->base, component, packed, count,
                                        ctx->derivatives);
    ctx->renders++;
    if (status != MR_OK) ctx->failure = status;
    return status == MR_OK;
}

/* The projected objective as levenberg.h wants it: NAN after a failed render. */
static double projected_value(void *data, const double *u) {
    fit_context *ctx = data;
    double sse = projected_objective((unsigned)ctx->nonlinear_count, u, NULL, ctx);
    return ctx->failure != MR_OK ? NAN : sse;
}

/* projected_linearise's sums over the covered pixels, per image channel c, basis render p < P and derivative image
 * a < n (constant counts let the compiler keep them in registers, as projection_sums): g[a] = -2 sum r D_a,
 * DtD[a][b] = sum D_a D_b (b <= a), T[c][a][p] = sum over channel c of d_p D_a, with d_p = R_p - R0 and the residual
 * r = goal - R0 - sum_p w[c][p] d_p (w[c][p]: the solved value of parameter p's column in channel c). */
static MR_ALWAYS_INLINE void linearise_sums(const fit_context *ctx, const int P, const int n,
                                            double w[3][MAX_SLOTS], double *g, double DtD[][MAX_SLOTS],
                                            double T[3][MAX_SLOTS][MAX_SLOTS]) {
    basis_view v;
    basis_view_init(ctx, &v);
    for (int c = 0; c < 3; c++) { // channel by channel, as projection_sums: the sums stay in registers
        double gc[MAX_SLOTS] = {0}, Dc[MAX_SLOTS][MAX_SLOTS] = {{0}}, Tc[MAX_SLOTS][MAX_SLOTS] = {{0}};
        for (int i = 0; i < ctx->pixel_count; i++) {
            const size_t at = (size_t)ctx->pixels[i] * 3 + (size_t)c;
            float r[MAX_SLOTS];
            const float r0 = basis_values(&v, P, at, r);
            double column[MAX_SLOTS], residual = (double)v.goal[at] - (double)r0;
            for (int p = 0; p < P; p++) {
                column[p] = (double)r[p] - (double)r0;
                residual -= w[c][p] * column[p];
            }
            double d[MAX_SLOTS];
            for (int a = 0; a < n; a++) {
                d[a] = v.derivative[a][at];
                gc[a] -= 2.0 * residual * d[a];
                for (int bb = 0; bb <= a; bb++) Dc[a][bb] += d[a] * d[bb];
                for (int p = 0; p < P; p++) Tc[a][p] += column[p] * d[a];
            }
        }
        for (int a = 0; a < n; a++) {
            g[a] += gc[a];
            for (int bb = 0; bb <= a; bb++) DtD[a][bb] += Dc[a][bb];
            for (int p = 0; p < P; p++) T[c][a][p] = Tc[a][p];
        }
    }
}

/* The gradient and Gauss-Newton matrix of the projected objective at the point project() last solved (ctx->base
 * holds its nonlinear values and their linear solution b). With R(theta, b) the render the projection predicts:
 *   - gradient: dF/dtheta = -2 sum r . dR/dtheta at fixed b, exact at the solution b(theta) (its own derivative
 *     drops out: b minimises F, within its bounds; Golub and Pereyra 1973);
 *   - Gauss-Newton matrix: J^T J with J = -(I - P) dR/dtheta, P the projection onto the solved columns that are
 *     not on a bound (Kaufman 1975), i.e. D^T D - T G^-1 T^T with T = D^T A, G = A^T A (the projection's Gram).
 * One derivative render (every nonlinear slot at once) and one pass over the covered pixels. */
static int projected_linearise(void *data, const double *u, double *gradient, double *gauss_newton) {
    fit_context *ctx = data;
    const int n = ctx->nonlinear_count, P = ctx->linear_param_count, k = ctx->column_count;
    const fitted_slot *slots[MAX_SLOTS];
    for (int a = 0; a < n; a++) slots[a] = &ctx->nonlinear[a];
    if (!render_derivatives(ctx, slots, n, ctx->projection_component)) return 0;
    // A column is parameter p's basis render in one channel (an RGB parameter) or in all three (a scalar one).
    double b[MAX_SLOTS], w[3][MAX_SLOTS] = {{0}};
    for (int j = 0; j < k; j++) {
        b[j] = ctx->base[ctx->linear[j].slot];
        for (int c = 0; c < 3; c++)
            if (ctx->column_channel[j] < 0 || ctx->column_channel[j] == c) w[c][ctx->column_image[j] - 1] = b[j];
    }
    double g[MAX_SLOTS] = {0}, DtD[MAX_SLOTS][MAX_SLOTS] = {{0}}, Tc[3][MAX_SLOTS][MAX_SLOTS] = {{{0}}};
    if (P == 1 && n == 1) linearise_sums(ctx, 1, 1, w, g, DtD, Tc);
    else if (P == 2 && n == 1) linearise_sums(ctx, 2, 1, w, g, DtD, Tc);
    else if (P == 2 && n == 2) linearise_sums(ctx, 2, 2, w, g, DtD, Tc);
    else linearise_sums(ctx, P, n, w, g, DtD, Tc);
    double T[MAX_SLOTS][MAX_SLOTS] = {{0}}; // T[a][j] = sum over column j's channels of Tc
    for (int j = 0; j < k; j++)
        for (int c = 0; c < 3; c++)
            if (ctx->column_channel[j] < 0 || ctx->column_channel[j] == c)
                for (int a = 0; a < n; a++) T[a][j] += Tc[c][a][ctx->column_image[j] - 1];
    // The columns the projection moves freely: inside their bounds and seen by the images.
    int free_columns[MAX_SLOTS], f = 0;
    for (int j = 0; j < k; j++)
        if (ctx->gram[j * k + j] > 0.0 && b[j] > ctx->linear[j].lo && b[j] < ctx->linear[j].hi) free_columns[f++] = j;
    double G[MAX_SLOTS * MAX_SLOTS], X[MAX_SLOTS * MAX_SLOTS];
    for (int x = 0; x < f; x++) {
        for (int y = 0; y < f; y++) G[x * f + y] = ctx->gram[free_columns[x] * k + free_columns[y]];
        for (int a = 0; a < n; a++) X[x * n + a] = T[a][free_columns[x]];
    }
    const int projected = f > 0 && mr_lm_spd_solve(f, G, n, X); // X = G^-1 T^T
    for (int a = 0; a < n; a++) {
        const double sa = value_per_unit(&ctx->nonlinear[a], u[a]);
        gradient[a] = g[a] * sa;
        for (int bb = 0; bb <= a; bb++) {
            double m = DtD[a][bb];
            for (int x = 0; projected && x < f; x++) m -= T[a][free_columns[x]] * X[x * n + bb];
            const double scaled = m * sa * value_per_unit(&ctx->nonlinear[bb], u[bb]);
            gauss_newton[a * n + bb] = gauss_newton[bb * n + a] = scaled;
        }
    }
    return 1;
}

/* The direct objective as levenberg.h wants it: NAN after a failed render. Leaves the render in ctx->scratch. */
static double direct_value(void *data, const double *u) {
    fit_context *ctx = data;
    double sse = direct_objective((unsigned)ctx->vary_count, u, NULL, ctx);
    return ctx->failure != MR_OK ? NAN : sse;
}

/* The gradient and Gauss-Newton matrix of the direct objective at the point direct_value last rendered: J = -dR/du
 * for every varied slot, one derivative render (at those values) and one pass over the covered pixels. */
static int direct_linearise(void *data, const double *u, double *gradient, double *gauss_newton) {
    fit_context *ctx = data;
    const int n = ctx->vary_count;
    double saved[MAX_SLOTS];
    memcpy(saved, ctx->base, sizeof saved);
    for (int a = 0; a < n; a++) ctx->base[ctx->vary[a]->slot] = to_value(ctx->vary[a], u[a]);
    const int rendered = render_derivatives(ctx, ctx->vary, n, ctx->component);
    memcpy(ctx->base, saved, sizeof saved);
    if (!rendered) return 0;
    double g[2 * MAX_SLOTS] = {0}, M[2 * MAX_SLOTS][2 * MAX_SLOTS] = {{0}};
    for (int i = 0; i < ctx->pixel_count; i++) {
        const size_t at = (size_t)ctx->pixels[i] * 3;
        for (int c = 0; c < 3; c++) {
            const double residual = (double)ctx->goal->pixels[at + c] - (double)ctx->scratch->pixels[at + c];
            double d[2 * MAX_SLOTS];
            for (int a = 0; a < n; a++) {
                d[a] = ctx->derivatives[a]->pixels[at + c];
                g[a] -= 2.0 * residual * d[a];
                for (int bb = 0; bb <= a; bb++) M[a][bb] += d[a] * d[bb];
            }
        }
    }
    for (int a = 0; a < n; a++) {
        const double sa = value_per_unit(ctx->vary[a], u[a]);
        gradient[a] = g[a] * sa;
        for (int bb = 0; bb <= a; bb++)
            gauss_newton[a * n + bb] = gauss_newton[bb * n + a] = M[a][bb] * sa * value_per_unit(ctx->vary[bb], u[bb]);
    }
    return 1;
}

/* Levenberg-Marquardt from u (in/out) on the projected (projected = 1) or direct objective; the minimum, or NAN
 * after a failed render. *at_point: 1 when the last evaluation was at the returned u (ctx->base holds its linear
 * solution, for the projected objective). */
static double gradient_fit(fit_context *ctx, int projected, double *u, int *at_point) {
    const int n = projected ? ctx->nonlinear_count : ctx->vary_count;
    // F sums float images in double: its last ~7 digits are the images' rounding (FLOAT_IMAGE_NOISE).
    mr_lm_problem problem = {n, ctx, projected ? projected_value : direct_value,
                             projected ? projected_linearise : direct_linearise, FLOAT_IMAGE_NOISE};
    mr_lm_result result = mr_lm_minimise(&problem, ctx->opts.xtol, ctx->opts.max_evaluations, u);
    *at_point = result.at_last_value;
    if (ctx->failure != MR_OK) return NAN;
    return result.minimum;
}

/* Local bounded minimisation with BOBYQA from u (in/out), first steps steps[i] (normalised units); returns the
 * minimum or NAN on an nlopt failure. */
static double local_fit(fit_context *ctx, unsigned n, nlopt_func objective, double *u, const double *steps) {
    nlopt_opt opt = nlopt_create(NLOPT_LN_BOBYQA, n);
    if (opt == NULL) {
        ctx->failure = mr_fail(MR_ERR_NOMEM, "out of memory for the local optimiser");
        return NAN;
    }
    double lower[2 * MAX_SLOTS], upper[2 * MAX_SLOTS];
    for (unsigned i = 0; i < n; i++) {
        lower[i] = 0.0;
        upper[i] = 1.0;
        u[i] = mr_clampd(u[i], 0.0, 1.0);
    }
    nlopt_set_lower_bounds(opt, lower);
    nlopt_set_upper_bounds(opt, upper);
    nlopt_set_min_objective(opt, objective, ctx);
    nlopt_set_xtol_rel(opt, ctx->opts.xtol);
    nlopt_set_xtol_abs1(opt, ctx->opts.xtol);
    nlopt_set_maxeval(opt, ctx->opts.max_evaluations);
    nlopt_set_initial_step(opt, steps);
    double minimum = HUGE_VAL;
    ctx->running = opt;
    nlopt_result result = nlopt_optimize(opt, u, &minimum);
    ctx->running = NULL;
    nlopt_destroy(opt);
    if (ctx->failure != MR_OK) return NAN;
    // Running out of evaluations or rounding-limited steps still leave the best point found, which is what a
    // bounded-work fit reports; only a failure to run at all is an error.
    if (result < 0 && result != NLOPT_ROUNDOFF_LIMITED && result != NLOPT_FORCED_STOP) {
        mr_fail(MR_ERR_EXTERNAL, "remap: nlopt BOBYQA failed: %s", nlopt_result_to_string(result));
        ctx->failure = MR_ERR_EXTERNAL;
        return NAN;
    }
    return minimum;
}

/* ---- AUTO: global search over the nonlinear parameters, projected ---------------------------------------- */

typedef struct candidate {
    double u[MAX_SLOTS];
    double sse;
    double values[MAX_SLOTS];
} candidate;

static int compare_candidates(const void *a, const void *b) {
    double x = ((const candidate *)a)->sse, y = ((const candidate *)b)->sse;
    return (x > y) - (x < y);
}

/* Evaluate a grid of `points` values per nonlinear dimension (d <= 3, points^d projections), keep its local
 * minima (no lower neighbour among the 3^d - 1 around), best first, in starts[]; returns the count. */
static int grid_minima(fit_context *ctx, int points, candidate *starts, int max_starts) {
    const int d = ctx->nonlinear_count;
    int total = 1;
    for (int i = 0; i < d; i++) total *= points;
    double *sse = malloc((size_t)total * sizeof *sse);
    candidate *all = malloc((size_t)total * sizeof *all);
    if (sse == NULL || all == NULL) {
        free(sse);
        free(all);
        ctx->failure = mr_fail(MR_ERR_NOMEM, "out of memory for a grid of %d points", total);
        return 0;
    }
    for (int g = 0; g < total && ctx->failure == MR_OK; g++) {
        double u[3];
        for (int i = 0, rest = g; i < d; i++, rest /= points) u[i] = (double)(rest % points) / (points - 1);
        sse[g] = projected_objective((unsigned)d, u, NULL, ctx);
    }
    int found = 0, neighbourhood = 1;
    for (int i = 0; i < d; i++) neighbourhood *= 3;
    for (int g = 0; g < total && ctx->failure == MR_OK; g++) {
        int at[3], is_minimum = 1;
        for (int i = 0, rest = g; i < d; i++, rest /= points) at[i] = rest % points;
        for (int n = 0; n < neighbourhood && is_minimum; n++) {
            int neighbour = 0, stride = 1, inside = 1, moved = 0;
            for (int i = 0, rest = n; i < d; i++, rest /= 3, stride *= points) {
                int coordinate = at[i] + rest % 3 - 1;
                moved |= rest % 3 != 1;
                if (coordinate < 0 || coordinate >= points) inside = 0;
                neighbour += coordinate * stride;
            }
            if (moved && inside && sse[neighbour] < sse[g]) is_minimum = 0;
        }
        if (!is_minimum) continue;
        for (int i = 0; i < d; i++) all[found].u[i] = (double)at[i] / (points - 1);
        all[found].sse = sse[g];
        found++;
    }
    qsort(all, (size_t)found, sizeof *all, compare_candidates);
    int kept = MR_MIN(found, max_starts);
    memcpy(starts, all, (size_t)kept * sizeof *all);
    free(all);
    free(sse);
    return kept;
}

/* Fill best (and report whether a distinct, nearly equal minimum exists) with the AUTO search. */
static void auto_fit(fit_context *ctx, candidate *best, int *ambiguous) {
    const int d = ctx->nonlinear_count;
    candidate starts[64];
    int start_count = 0;
    double step = 0.05;
    *ambiguous = 0;
    if (d == 0) {
        best->sse = project(ctx);
        memcpy(best->values, ctx->base, sizeof best->values);
        return;
    }
    if (ctx->warm) { // a warm start (remap.h, initial_values): the start's basin only
        for (int i = 0; i < d; i++) starts[0].u[i] = to_unit(&ctx->nonlinear[i], ctx->base[ctx->nonlinear[i].slot]);
        starts[0].sse = HUGE_VAL;
        start_count = 1;
        step = MR_REMAP_WARM_STEP;
    } else if (d <= 3) {
        static const int default_points[4] = {0, DEFAULT_GRID_1D, DEFAULT_GRID_2D, DEFAULT_GRID_3D};
        int points = ctx->opts.grid_points > 1 ? ctx->opts.grid_points : default_points[d];
        start_count = grid_minima(ctx, points, starts, MAX_REFINED_STARTS);
        step = 1.0 / (points - 1);
    } else {
        uint64_t state = ctx->opts.seed; // the multi-start points, seeded (remap.h: deterministic)
        // A gradient fit sees less of the range than BOBYQA's first steps do, and costs a fraction of one: it starts
        // from twice as many points (remap.h, starts).
        int wanted = MR_MIN(MR_MAX(ctx->opts.starts, 1) * (ctx->gradient ? 2 : 1), 64);
        for (int s = 0; s < wanted; s++) {
            for (int i = 0; i < d; i++)
                starts[s].u[i] = s == 0 ? to_unit(&ctx->nonlinear[i], ctx->base[ctx->nonlinear[i].slot])
                                        : mr_rng_unit(&state);
            starts[s].sse = HUGE_VAL;
        }
        start_count = wanted;
        step = 0.1;
    }
    double saved_base[MAX_SLOTS];
    memcpy(saved_base, ctx->base, sizeof saved_base);
    candidate refined[64];
    int refined_count = 0;
    for (int s = 0; s < start_count && ctx->failure == MR_OK; s++) {
        memcpy(ctx->base, saved_base, sizeof saved_base);
        candidate *r = &refined[refined_count];
        memcpy(r->u, starts[s].u, sizeof r->u);
        double steps[MAX_SLOTS];
        for (int i = 0; i < d; i++) steps[i] = step;
        int at_point = 0;
        r->sse = ctx->gradient ? gradient_fit(ctx, 1, r->u, &at_point)
                               : local_fit(ctx, (unsigned)d, projected_objective, r->u, steps);
        if (isnan(r->sse)) break;
        // Re-project at the returned point so base holds exactly its linear solution.
        if (!at_point) r->sse = projected_objective((unsigned)d, r->u, NULL, ctx);
        memcpy(r->values, ctx->base, sizeof r->values);
        refined_count++;
    }
    if (refined_count == 0) {
        best->sse = NAN;
        return;
    }
    qsort(refined, (size_t)refined_count, sizeof *refined, compare_candidates);
    *best = refined[0];
    for (int s = 1; s < refined_count; s++) {
        double distance = 0.0;
        for (int i = 0; i < d; i++) distance = fmax(distance, fabs(refined[s].u[i] - best->u[i]));
        if (distance > AMBIGUITY_DISTANCE && refined[s].sse <= best->sse * (1.0 + AMBIGUITY_ERROR) + 1e-12)
            *ambiguous = 1;
    }
    memcpy(ctx->base, best->values, sizeof ctx->base);
}

/* AUTO lobe by lobe (remap.h): each lobe's shape — its nonlinear parameters — comes from the global search
 * against the source's render of that lobe alone, with the other lobe's linear parameters at 0 (so that a
 * coupling such as Ward's trimming cannot enter); then every linear parameter is solved jointly against the
 * full render with the shapes held. Returns 0 without doing anything unless the source has component images
 * and every fitted nonlinear parameter belongs to exactly one lobe. */
static int lobe_staged_fit(fit_context *ctx, const mr_remap_source *source, double source_energy, candidate *best,
                           int *ambiguous) {
    if (source->diffuse == NULL || source->specular == NULL || ctx->nonlinear_count == 0) return 0;
    if (ctx->external && !mr_renderer_has_components(ctx->opts.target_renderer)) return 0;
    for (int i = 0; i < ctx->nonlinear_count; i++) {
        mr_param_lobe lobe = ctx->model->params[ctx->nonlinear[i].param].lobe;
        if (lobe != MR_LOBE_DIFFUSE && lobe != MR_LOBE_SPECULAR) return 0;
    }
    fitted_slot nonlinear[MAX_SLOTS], linear[MAX_SLOTS];
    int linear_params[MAX_SLOTS];
    const int nonlinear_count = ctx->nonlinear_count, linear_count = ctx->linear_count;
    const int linear_param_count = ctx->linear_param_count;
    memcpy(nonlinear, ctx->nonlinear, sizeof nonlinear);
    memcpy(linear, ctx->linear, sizeof linear);
    memcpy(linear_params, ctx->linear_params, sizeof linear_params);
    *ambiguous = 0;
    static const mr_param_lobe lobes[2] = {MR_LOBE_SPECULAR, MR_LOBE_DIFFUSE};
    for (int l = 0; l < 2 && ctx->failure == MR_OK; l++) {
        const mr_param_lobe lobe = lobes[l];
        ctx->nonlinear_count = 0;
        for (int i = 0; i < nonlinear_count; i++)
            if (ctx->model->params[nonlinear[i].param].lobe == lobe)
                ctx->nonlinear[ctx->nonlinear_count++] = nonlinear[i];
        if (ctx->nonlinear_count == 0) continue;
        ctx->linear_param_count = 0;
        ctx->linear_count = 0;
        for (int j = 0; j < linear_count; j++) {
            if (ctx->model->params[linear[j].param].lobe & lobe)
                ctx->linear[ctx->linear_count++] = linear[j];
            else
                ctx->base[linear[j].slot] = 0.0;
        }
        for (int p = 0; p < linear_param_count; p++)
            if (ctx->model->params[linear_params[p]].lobe & lobe)
                ctx->linear_params[ctx->linear_param_count++] = linear_params[p];
        ctx->goal = lobe == MR_LOBE_SPECULAR ? source->specular : source->diffuse;
        ctx->projection_component = lobe == MR_LOBE_SPECULAR ? MR_COMPONENT_SPECULAR : MR_COMPONENT_DIFFUSE;
        candidate stage;
        int stage_ambiguous = 0;
        auto_fit(ctx, &stage, &stage_ambiguous); // leaves the lobe's best shape in ctx->base
        // A lobe too faint to see (a dielectric's highlight at IOR 1.01) has an undetermined shape that does
        // not matter to the image: its ambiguity is not a local minimum. It counts from 0.1 % of the energy.
        if (stage_ambiguous && image_energy(ctx, ctx->goal) >= 1e-3 * source_energy) *ambiguous = 1;
    }
    ctx->nonlinear_count = nonlinear_count;
    ctx->linear_count = linear_count;
    ctx->linear_param_count = linear_param_count;
    memcpy(ctx->nonlinear, nonlinear, sizeof nonlinear);
    memcpy(ctx->linear, linear, sizeof linear);
    memcpy(ctx->linear_params, linear_params, sizeof linear_params);
    ctx->goal = source->full;
    ctx->projection_component = MR_COMPONENT_FULL;
    best->sse = ctx->failure == MR_OK ? project(ctx) : NAN;
    memcpy(best->values, ctx->base, sizeof best->values);
    for (int i = 0; i < nonlinear_count; i++) best->u[i] = to_unit(&nonlinear[i], ctx->base[nonlinear[i].slot]);
    return 1;
}

/* How far the target's render `rendered` at `values` departs from affine behaviour along the segment from all
 * linear parameters at 0 to their fitted values: |R(b) - 2 R(b/2) + R(0)|, which is 0 (up to float rounding)
 * wherever the image is affine in b and is not as soon as the model rescales the values somewhere on the
 * segment (Ward's trimming: engaged at b but not at b/2, or by another factor). Uses basis[0] and basis[1] as
 * scratch; 0 when there are no linear parameters; NAN if a render failed. */
static double affine_departure(fit_context *ctx, const double *values, const mr_image *rendered) {
    if (ctx->linear_param_count == 0) return 0.0;
    double half[MAX_SLOTS], zero[MAX_SLOTS];
    memcpy(half, values, sizeof half);
    memcpy(zero, values, sizeof zero);
    for (int j = 0; j < ctx->linear_count; j++) {
        half[ctx->linear[j].slot] = 0.5 * values[ctx->linear[j].slot];
        zero[ctx->linear[j].slot] = 0.0;
    }
    if (!render_values(ctx, half, MR_COMPONENT_FULL, ctx->basis[0]) ||
        !render_values(ctx, zero, MR_COMPONENT_FULL, ctx->basis[1]))
        return NAN;
    double sum = 0.0;
    for (int i = 0; i < ctx->pixel_count; i++)
        for (int c = 0; c < 3; c++) {
            size_t at = (size_t)ctx->pixels[i] * 3 + c;
            double d = (double)rendered->pixels[at] - 2.0 * ctx->basis[0]->pixels[at] + ctx->basis[1]->pixels[at];
            sum += d * d;
        }
    return sqrt(sum);
}

/* Whether the affine optimum at the fit's nonlinear values is one the model rescales: the projection's solution,
 * rendered, misses its prediction (remap.h, UNREACHABLE). For the local strategies, whose own fits never see a
 * prediction (AUTO and JOINT check it while fitting). Uses the basis images; leaves ctx->base as it was; 0 when
 * a render fails (ctx->failure says so). */
static int affine_optimum_rescaled(fit_context *ctx, const mr_image *full, double energy_scale) {
    if (ctx->linear_count == 0) return 0;
    double saved[MAX_SLOTS];
    memcpy(saved, ctx->base, sizeof saved);
    ctx->goal = full;
    ctx->projection_component = MR_COMPONENT_FULL;
    double predicted = project(ctx);
    int rescaled = 0;
    if (!isnan(predicted) && render_values(ctx, ctx->base, MR_COMPONENT_FULL, ctx->basis[0])) {
        double actual = sse_against(ctx, ctx->basis[0], full);
        rescaled = fabs(sqrt(actual) - sqrt(predicted)) > PREDICTION_TOLERANCE * sqrt(energy_scale);
    }
    memcpy(ctx->base, saved, sizeof saved);
    return rescaled;
}

/* ---- the paper's strategies: direct local fits ---------------------------------------------------------- */

/* Fit the slots whose parameter lobe matches `lobes` (any of the bits; 0 = every slot) against `goal`, rendering
 * `component`, from the current base values. */
static double direct_stage(fit_context *ctx, unsigned lobes, int exact_lobe, const mr_image *goal,
                           mr_component component) {
    ctx->vary_count = 0;
    const fitted_slot *pools[2] = {ctx->nonlinear, ctx->linear};
    int counts[2] = {ctx->nonlinear_count, ctx->linear_count};
    for (int pool = 0; pool < 2; pool++)
        for (int i = 0; i < counts[pool]; i++) {
            unsigned lobe = (unsigned)ctx->model->params[pools[pool][i].param].lobe;
            int match = lobes == 0 || (exact_lobe ? lobe == lobes : (lobe & lobes) != 0);
            if (match) ctx->vary[ctx->vary_count++] = &pools[pool][i];
        }
    if (ctx->vary_count == 0) return 0.0;
    ctx->goal = goal;
    ctx->component = component;
    double u[2 * MAX_SLOTS], steps[2 * MAX_SLOTS];
    for (int i = 0; i < ctx->vary_count; i++) {
        const fitted_slot *v = ctx->vary[i];
        u[i] = to_unit(v, ctx->base[v->slot]);
        // First steps of 0.1 of the range, but at most 0.1 in the value's own units: a reflectance allowed up to
        // 10 (Ward's rho_s) would otherwise first jump by 1.0, straight onto the plateau of Ward's energy
        // trimming, where the objective is flat in the reflectances' common scale and BOBYQA stalls.
        steps[i] = v->log_scale ? 0.1 : 0.1 * fmin(1.0, 1.0 / (v->hi - v->lo));
    }
    int at_point;
    double minimum = ctx->gradient ? gradient_fit(ctx, 0, u, &at_point)
                                   : local_fit(ctx, (unsigned)ctx->vary_count, direct_objective, u, steps);
    if (isnan(minimum)) return NAN;
    for (int i = 0; i < ctx->vary_count; i++) ctx->base[ctx->vary[i]->slot] = to_value(ctx->vary[i], u[i]);
    return minimum;
}

/* ---- which parameters the projection may solve for ----------------------------------------------------- */

static void random_direction(uint64_t *state, double d[3]) {
    // Cosine-distributed above 0.05 of the horizon: the region a fit scene actually samples.
    double u = mr_rng_unit(state), v = mr_rng_unit(state);
    double z = sqrt(0.0025 + (1.0 - 0.0025) * u), r = sqrt(fmax(0.0, 1.0 - z * z)), phi = 2.0 * MR_PI * v;
    d[0] = r * cos(phi);
    d[1] = r * sin(phi);
    d[2] = z;
}

static void eval_full(const mr_brdf_model *m, const double *values, const double wi[3], const double wo[3],
                      double f[3]) {
    mr_brdf_eval_full(m, values, wi, wo, f);
}

static int close_enough(double a, double b, double scale) { return fabs(a - b) <= 1e-9 * scale + 1e-300; }

/* True if f_r is jointly affine in the parameters with is_linear[i] set, each RGB parameter's channel c
 * driving output channel c only, for seeded random directions (half of them near the mirror configuration, so
 * that narrow specular lobes are sampled where they are not zero) and random values of every other free
 * parameter (fixed ones and switches at `base`). The candidate parameter spans its whole range; the already
 * linear ones are drawn from the lowest 5 % of theirs, where no clamp or energy trimming engages: what is
 * checked is the formula, not its safety nets. */
/* Bit i set: parameter i is not fitted: a switch, a parameter the descriptor holds (MR_PARAM_FIT_FIXED) unless the
 * caller frees it (mr_remap_options.freed), or one the caller holds (mr_remap_options.held): brdf.h's one rule,
 * which the commands print. The functions below take this mask where they say `held`. */
static unsigned fixed_mask(const mr_brdf_model *m, unsigned held, unsigned freed) {
    unsigned mask = 0;
    for (int i = 0; i < m->param_count && i < 32; i++) {
        const mr_hold_reason why = mr_brdf_hold_reason(m, held, i);
        if (why != MR_HOLD_FITTED && !(why == MR_HOLD_MODEL && ((freed >> i) & 1u))) mask |= 1u << i;
    }
    return mask;
}

static int held_fixed(const mr_brdf_model *m, unsigned fixed, int i) {
    (void)m;
    return i < 32 && ((fixed >> i) & 1u);
}

static int jointly_affine(const mr_brdf_model *m, unsigned held, const double *base, const unsigned char *is_linear,
                          int candidate) {
    uint64_t state = 0x5eedULL;
    int count = mr_brdf_value_count(m);
    for (int trial = 0; trial < 48; trial++) {
        double u[MAX_SLOTS], w[MAX_SLOTS], mid[MAX_SLOTS], wi[3], wo[3], fu[3], fw[3], fm[3];
        memcpy(u, base, sizeof u);
        for (int i = 0; i < m->param_count; i++) {
            const mr_brdf_param *p = &m->params[i];
            if (held_fixed(m, held, i)) continue;
            int offset = mr_brdf_param_offset(m, i);
            double span = (is_linear[i] && i != candidate) ? 0.05 : 1.0;
            for (int c = 0; c < p->channels; c++)
                u[offset + c] = p->min_value + span * mr_rng_unit(&state) * (p->max_value - p->min_value);
        }
        memcpy(w, u, sizeof w);
        for (int i = 0; i < m->param_count; i++) {
            if (!is_linear[i]) continue;
            const mr_brdf_param *p = &m->params[i];
            int offset = mr_brdf_param_offset(m, i);
            double span = i == candidate ? 1.0 : 0.05;
            for (int c = 0; c < p->channels; c++)
                w[offset + c] = p->min_value + span * mr_rng_unit(&state) * (p->max_value - p->min_value);
        }
        for (int j = 0; j < count; j++) mid[j] = 0.5 * (u[j] + w[j]);
        random_direction(&state, wi);
        random_direction(&state, wo);
        if (trial % 2 == 0) {
            // Near the mirror direction of wi: tilt the mirror by up to ~0.05 rad.
            wo[0] = -wi[0] + 0.05 * (mr_rng_unit(&state) - 0.5);
            wo[1] = -wi[1] + 0.05 * (mr_rng_unit(&state) - 0.5);
            wo[2] = wi[2];
            double len = sqrt(wo[0] * wo[0] + wo[1] * wo[1] + wo[2] * wo[2]);
            for (int k = 0; k < 3; k++) wo[k] /= len;
        }
        eval_full(m, u, wi, wo, fu);
        eval_full(m, w, wi, wo, fw);
        eval_full(m, mid, wi, wo, fm);
        for (int c = 0; c < 3; c++) {
            double scale = fabs(fu[c]) + fabs(fw[c]);
            if (!close_enough(fm[c], 0.5 * (fu[c] + fw[c]), scale)) return 0;
        }
        // Channel independence: moving channel k of an RGB linear parameter leaves the other outputs alone.
        for (int i = 0; i < m->param_count; i++) {
            if (!is_linear[i] || m->params[i].channels != 3) continue;
            int offset = mr_brdf_param_offset(m, i);
            for (int k = 0; k < 3; k++) {
                double moved[MAX_SLOTS], fk[3];
                memcpy(moved, u, sizeof moved);
                moved[offset + k] = w[offset + k];
                eval_full(m, moved, wi, wo, fk);
                for (int c = 0; c < 3; c++)
                    if (c != k && !close_enough(fk[c], fu[c], fabs(fu[c]))) return 0;
            }
        }
    }
    return 1;
}

/* True if the linear parameters can share one component render (the projection's fast path): at most one per
 * lobe, each confined to the diffuse or the specular lobe. */
static int lobes_split(const mr_brdf_model *m, const int *linear_params, int count) {
    int diffuse = 0, specular = 0;
    for (int p = 0; p < count; p++) {
        mr_param_lobe lobe = m->params[linear_params[p]].lobe;
        if (lobe == MR_LOBE_DIFFUSE)
            diffuse++;
        else if (lobe == MR_LOBE_SPECULAR)
            specular++;
        else
            return 0;
    }
    return count > 0 && diffuse <= 1 && specular <= 1;
}

/* True if f_r is exactly 0 with every linear parameter at 0, for seeded random directions and values of the
 * others (Ward: no diffuse, no specular, no light; GGX with Schlick F0 = 0 still reflects at grazing angles). */
static int black_without_linear(const mr_brdf_model *m, unsigned held, const double *base,
                                const unsigned char *is_linear) {
    uint64_t state = 0xb1ac0ULL;
    for (int trial = 0; trial < 32; trial++) {
        double v[MAX_SLOTS], wi[3], wo[3], f[3];
        memcpy(v, base, sizeof v);
        for (int i = 0; i < m->param_count; i++) {
            const mr_brdf_param *p = &m->params[i];
            if (held_fixed(m, held, i)) continue;
            int offset = mr_brdf_param_offset(m, i);
            for (int c = 0; c < p->channels; c++)
                v[offset + c] = is_linear[i] ? 0.0
                                             : p->min_value + mr_rng_unit(&state) * (p->max_value - p->min_value);
        }
        random_direction(&state, wi);
        random_direction(&state, wo);
        if (trial % 2 == 0) { // near the mirror configuration, where specular lobes live
            wo[0] = -wi[0];
            wo[1] = -wi[1];
            wo[2] = wi[2];
        }
        eval_full(m, v, wi, wo, f);
        if (f[0] != 0.0 || f[1] != 0.0 || f[2] != 0.0) return 0;
    }
    return 1;
}

/* The parameters the projection solves for: those the descriptor declares LINEAR or AFFINE, plus any
 * NONLINEAR parameter that is in fact affine (jointly with the rest) once the fixed parameters hold their
 * values. Cycles' base colour is the example: its specular tint divides by the colour's luminance, but with
 * the tint held at 0 the colour enters affinely, and solving for it exactly removes three dimensions from the
 * nonlinear search. RGB parameters are tried first (they remove the most), then the others in table order. */
static void choose_linear_parameters(const mr_brdf_model *m, unsigned held, const double *base,
                                     unsigned char *is_linear) {
    memset(is_linear, 0, MAX_SLOTS);
    for (int i = 0; i < m->param_count; i++) {
        const mr_brdf_param *p = &m->params[i];
        is_linear[i] = !held_fixed(m, held, i) && (p->role == MR_PARAM_LINEAR || p->role == MR_PARAM_AFFINE);
    }
    for (int pass = 0; pass < 2; pass++)
        for (int i = 0; i < m->param_count; i++) {
            const mr_brdf_param *p = &m->params[i];
            if (is_linear[i] || p->role != MR_PARAM_NONLINEAR || held_fixed(m, held, i)) continue;
            if ((pass == 0) != (p->channels == 3)) continue;
            is_linear[i] = 1;
            if (!jointly_affine(m, held, base, is_linear, i)) is_linear[i] = 0;
        }
}

/* ---- driver --------------------------------------------------------------------------------------------- */

static mr_status check_source_image(const mr_render_plan *plan, const mr_image *image, const char *what) {
    const mr_scene *scene = mr_render_plan_scene(plan);
    if (image->width != scene->width || image->height != scene->height || image->channels != 3)
        return mr_fail(MR_ERR_INVALID_ARG, "remap: the source %s image is %dx%dx%d, the fit scene is %dx%dx3", what,
                       image->width, image->height, image->channels, scene->width, scene->height);
    char label[96];
    snprintf(label, sizeof label, "remap: the source %s image", what);
    return mr_image_check_radiance(image, label);
}

static void free_context(fit_context *ctx) {
    mr_image_free(ctx->scratch);
    for (int i = 0; i <= MAX_SLOTS; i++) mr_image_free(ctx->basis[i]);
    for (int i = 0; i < 4; i++) mr_image_free(ctx->lobe_images[i]);
    for (int i = 0; i < 2 * MAX_SLOTS; i++) mr_image_free(ctx->derivatives[i]);
    free((void *)ctx->pixels);
}

static double now_seconds(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Decide the outcome of a finished fit (remap.h) and write its detail line. */
static void classify(fit_context *ctx, double departure, int rescaled_optimum, int ambiguous, double projected_gain,
                     mr_remap_result *out) {
    out->outcome = MR_FIT_CONVERGED;
    snprintf(out->detail, sizeof out->detail, "converged: relative RMSE %.3g", out->relative_rmse);
    // The image is affine in the linear parameters unless the model clamps or rescales them: where it does at
    // the solution, the values are not the ones the render shows (any strategy).
    if (departure > AFFINE_DEPARTURE_TOLERANCE) {
        out->outcome = MR_FIT_UNREACHABLE;
        snprintf(out->detail, sizeof out->detail,
                 "unreachable: the target rescales these values (e.g. energy trimming when diffuse + specular > 1); "
                 "its render departs from them by %.1f %% of the source's RMS radiance", 100.0 * departure);
        return;
    }
    // AUTO's best affine solution lies where the model rescales: the refinement against real renders then
    // settles on the edge of the region the model leaves alone (Ward: diffuse + specular = 1), a value pinned by
    // the target's limit, not the source's.
    if (rescaled_optimum) {
        out->outcome = MR_FIT_UNREACHABLE;
        snprintf(out->detail, sizeof out->detail,
                 "unreachable: the best fit needs values the target rescales (e.g. energy trimming when diffuse + "
                 "specular > 1); the closest render leaves %.1f %% of the source's RMS radiance",
                 100.0 * out->relative_rmse);
        return;
    }
    // A residual below 0.1 % of the source's radiance is a match, whatever a global search finds beyond it.
    if (ambiguous || (projected_gain > LOCAL_MINIMUM_GAIN && out->relative_rmse > LOCAL_MINIMUM_FLOOR)) {
        out->outcome = MR_FIT_LOCAL_MINIMUM;
        if (ambiguous)
            snprintf(out->detail, sizeof out->detail,
                     "local-minimum: distinct parameter sets fit within %.0f %% of each other's error",
                     100.0 * AMBIGUITY_ERROR);
        else
            snprintf(out->detail, sizeof out->detail,
                     "local-minimum: the global search (strategy joint) finds a fit with %.0f %% less squared error",
                     100.0 * projected_gain);
        return;
    }
    // Only a residual that no better fit removes says the target cannot reach the source.
    if (out->relative_rmse > UNREACHABLE_RELATIVE_RMSE) {
        out->outcome = MR_FIT_UNREACHABLE;
        snprintf(out->detail, sizeof out->detail,
                 "unreachable: the best fit leaves a residual of %.1f %% of the source's RMS radiance",
                 100.0 * out->relative_rmse);
        return;
    }
    const fitted_slot *pools[2] = {ctx->nonlinear, ctx->linear};
    int counts[2] = {ctx->nonlinear_count, ctx->linear_count};
    for (int pool = 0; pool < 2; pool++)
        for (int i = 0; i < counts[pool]; i++) {
            const fitted_slot *s = &pools[pool][i];
            double u = to_unit(s, out->values[s->slot]);
            // A reflectance at 0 is an absent lobe, not a limit; an upper bound, or any bound of a nonlinear
            // parameter, means the source asks for a value outside the target's range.
            int at_upper = u > 1.0 - 1e-6, at_lower = u < 1e-6 && pool == 0;
            // A bound the fit reaches exactly (a dielectric's metallic = 0) is a value, not a limit: only an
            // imperfect fit says the source wants something beyond the range.
            if ((at_upper || at_lower) && out->relative_rmse > AT_BOUND_RELATIVE_RMSE) {
                out->outcome = MR_FIT_AT_BOUND;
                snprintf(out->detail, sizeof out->detail, "at-bound: %s = %g is the %s of its range",
                         ctx->model->params[s->param].name, out->values[s->slot], at_upper ? "maximum" : "minimum");
                return;
            }
        }
}

/* ---- resolution: what the scene can and cannot tell apart ------------------------------------------------ */

/* How a shape parameter's value maps to its lobe's width, width ~ value^k: alphas and Blender's rms are widths;
 * glTF and Cycles roughness are sqrt(alpha); a Phong exponent n gives a width ~ 1 / sqrt(n). */
static double lobe_width_power(const char *name) {
    if (strcmp(name, "roughness") == 0) return 2.0;
    if (strcmp(name, "exponent") == 0) return -0.5;
    return 1.0;
}

/* The range [lo, hi] of fitted slot s's values, walked from `values` in factors of 2 within its bounds, over
 * which the full render stays within tol_sse (squared error) of `fitted`; beyond[0] and beyond[1], the first
 * values below and above it whose render differs (the range's own ends where nothing did). 0 if a render
 * failed. */
static int shape_range(fit_context *ctx, const double *values, const fitted_slot *s, const mr_image *fitted,
                       mr_image *scratch, double tol_sse, double *lo, double *hi, double beyond[2]) {
    double trial[MAX_SLOTS];
    const double v = values[s->slot];
    *lo = *hi = v;
    for (int direction = -1; direction <= 1; direction += 2) {
        double *end = direction < 0 ? lo : hi;
        beyond[direction > 0] = *end;
        for (int step = 1; step <= RESOLUTION_STEPS; step++) {
            double candidate = mr_clampd(v * pow(2.0, direction * step), s->lo, s->hi);
            if (candidate == *end) break; // the parameter's bound
            memcpy(trial, values, sizeof trial);
            trial[s->slot] = candidate;
            if (!render_values(ctx, trial, MR_COMPONENT_FULL, scratch)) return 0;
            beyond[direction > 0] = candidate;
            if (sse_against(ctx, scratch, fitted) > tol_sse) break;
            *end = candidate;
        }
    }
    return 1;
}

/* Refine a CONVERGED or ambiguous LOCAL_MINIMUM verdict (remap.h): a black source or a shapeless lobe is
 * CONVERGED, a shape only bounded is UNDER_RESOLVED. `fitted` is the render at out->values. Returns 0 if a
 * render failed (ctx->failure says why). */
static int check_resolution(fit_context *ctx, double source_rms, const mr_image *fitted, int ambiguous,
                            mr_remap_result *out) {
    // A black source fitted by a render as black to the eye (its RMS under the same floor): nothing to bound,
    // nothing at a limit (GGX cannot be black: Schlick's term leaves a faint highlight, at any alpha).
    if (source_rms < RELATIVE_RMS_FLOOR && out->relative_rmse <= 1.0) {
        out->outcome = MR_FIT_CONVERGED;
        snprintf(out->detail, sizeof out->detail,
                 "converged: the source is black (RMS radiance %.2g) and so is the fit (RMS %.2g)", source_rms,
                 out->relative_rmse * RELATIVE_RMS_FLOOR);
        return 1;
    }
    const int local_minimum_by_ambiguity = out->outcome == MR_FIT_LOCAL_MINIMUM && ambiguous;
    if (out->outcome != MR_FIT_CONVERGED && !local_minimum_by_ambiguity) return 1;
    // Which lobes show: the fitted render's components.
    mr_image *diffuse = NULL, *specular = NULL, *scratch = NULL;
    const mr_scene *scene = mr_render_plan_scene(ctx->plan);
    mr_status status = mr_image_create(scene->width, scene->height, 3, &diffuse);
    if (status == MR_OK) status = mr_image_create(scene->width, scene->height, 3, &specular);
    if (status == MR_OK) status = mr_image_create(scene->width, scene->height, 3, &scratch);
    if (status == MR_OK)
        status = render_components(ctx, out->values, diffuse, specular);
    ctx->renders++;
    if (status != MR_OK) {
        ctx->failure = status;
        mr_image_free(diffuse);
        mr_image_free(specular);
        mr_image_free(scratch);
        return 0;
    }
    const double e_diffuse = image_energy(ctx, diffuse), e_specular = image_energy(ctx, specular);
    const double e_total = fmax(e_diffuse + e_specular, 1e-300);
    const double tol_sse = 3.0 * ctx->pixel_count * pow(RESOLUTION_TOLERANCE * source_rms, 2.0);
    int shown = 0, unresolved = 0, ok = 1;
    double worst_ratio = 0.0;
    for (int i = 0; i < ctx->nonlinear_count && ok; i++) {
        const fitted_slot *s = &ctx->nonlinear[i];
        const mr_brdf_param *p = &ctx->model->params[s->param];
        double lobe_energy = p->lobe == MR_LOBE_DIFFUSE    ? e_diffuse
                             : p->lobe == MR_LOBE_SPECULAR ? e_specular
                                                           : e_total;
        if (lobe_energy < LOBE_ENERGY_FLOOR * e_total) continue; // a lobe that does not show has no shape
        shown++;
        if (!s->log_scale) continue; // only roughness-like parameters narrow below a pixel
        double lo, hi, beyond[2];
        if (!(ok = shape_range(ctx, out->values, s, fitted, scratch, tol_sse, &lo, &hi, beyond))) break;
        // The range as lobe widths (a factor 2 in glTF roughness is a factor 4 in alpha).
        const double k = lobe_width_power(p->name), widths = pow(hi / lo, fabs(k));
        if (!(widths >= RESOLUTION_RANGE) || widths <= worst_ratio) continue;
        worst_ratio = widths;
        unresolved = 1;
        // The fit scene that shows the value found as wide as the first lobe outside the range, wider than its
        // widest, shows now (pixels scale with the lobe's width).
        const double v = out->values[s->slot];
        const double resolved = k > 0.0 ? beyond[1] : beyond[0], grow = pow(resolved / v, k);
        char size[48];
        if (scene->width * grow <= MR_RENDER_MAX_SIZE)
            snprintf(size, sizeof size, "about %.0f^2", ceil(scene->width * grow));
        else
            snprintf(size, sizeof size, "more than %d^2", MR_RENDER_MAX_SIZE);
        out->outcome = MR_FIT_UNDER_RESOLVED;
        snprintf(out->detail, sizeof out->detail,
                 "under-resolved: %s anywhere in [%.3g, %.3g] renders the same at %d^2 (a lobe narrower than the "
                 "pixels); %s would resolve %s = %.3g",
                 p->name, lo, hi, scene->width, size, p->name, v);
    }
    mr_image_free(diffuse);
    mr_image_free(specular);
    mr_image_free(scratch);
    if (!ok) return 0;
    if (local_minimum_by_ambiguity && !unresolved && shown == 0) { // the ambiguity lies in shapes nothing shows
        out->outcome = MR_FIT_CONVERGED;
        snprintf(out->detail, sizeof out->detail,
                 "converged: relative RMSE %.3g (the lobes whose shape differs between equal fits carry under "
                 "%.1f %% of the energy)", out->relative_rmse, 100.0 * LOBE_ENERGY_FLOOR);
    }
    return 1;
}

mr_status mr_remap_images(const mr_render_plan *plan, const mr_remap_source *source, const mr_brdf_model *target,
                          const mr_remap_options *opts_in, mr_remap_result *out) {
    if (plan == NULL || source == NULL || source->full == NULL || target == NULL || out == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "remap: NULL plan, source image, target model or result");
    double start_time = now_seconds();
    mr_remap_options opts = opts_in ? *opts_in : mr_remap_options_default();
    if (opts.max_evaluations <= 0) opts.max_evaluations = DEFAULT_MAX_EVALUATIONS;
    if (!(opts.xtol > 0.0)) opts.xtol = DEFAULT_XTOL;
    if (opts.starts <= 0) opts.starts = DEFAULT_STARTS;
    if (opts.seed == 0) opts.seed = DEFAULT_SEED; // so that a zeroed struct is the defaults, as everywhere
    if ((unsigned)opts.strategy >= MR_REMAP_STRATEGY_COUNT)
        return mr_fail(MR_ERR_INVALID_ARG, "remap: unknown strategy %d", (int)opts.strategy);
    if ((unsigned)opts.local_method >= MR_LOCAL_METHOD_COUNT)
        return mr_fail(MR_ERR_INVALID_ARG, "remap: unknown local method %d", (int)opts.local_method);
    if (opts.threads < 0 || opts.threads > 1024)
        return mr_fail(MR_ERR_INVALID_ARG, "remap: threads %d: expected 0 (the plan's rule) to 1024", opts.threads);
    if (opts.ties.tied != 0)
        return mr_fail(MR_ERR_INVALID_ARG, "remap: ties need the source's values (mr_remap), not only its images");
    for (int i = 0; i < 32; i++)
        if (((opts.freed >> i) & 1u) && (i >= target->param_count || !(target->params[i].flags & MR_PARAM_FIT_FIXED)))
            return mr_fail(MR_ERR_INVALID_ARG, "remap: %s%s is not one of the parameters '%s' holds by default, so "
                           "there is nothing to free", i < target->param_count ? "parameter " : "bit ",
                           i < target->param_count ? target->params[i].name : "beyond the model's", target->name);
    const int external = !mr_renderer_is_builtin(opts.target_renderer);
    if (external && !mr_renderer_supports(opts.target_renderer, target))
        return mr_fail(MR_ERR_UNSUPPORTED, "remap: renderer '%s' does not render model '%s' by values",
                       mr_renderer_name(opts.target_renderer), target->name);
    if (external && !mr_renderer_has_components(opts.target_renderer) &&
        (opts.strategy == MR_REMAP_TWO || opts.strategy == MR_REMAP_THREE))
        return mr_fail(MR_ERR_UNSUPPORTED, "remap: the %s strategy fits the target's diffuse and specular renders, "
                       "which renderer '%s' does not separate (use auto, joint or single)",
                       mr_remap_strategy_name(opts.strategy), mr_renderer_name(opts.target_renderer));
    mr_status status = check_source_image(plan, source->full, "full");
    if (status != MR_OK) return status;
    // An external target renderer: the built-in model fits first, in process, and its answer starts the fit
    // through the renderer, which then only corrects where the two differ (remap.h, target_renderer): a few dozen
    // external renders instead of a global search's hundreds.
    double surrogate_values[MAX_SLOTS];
    if (external && opts.initial_values == NULL &&
        (opts.strategy == MR_REMAP_AUTO || opts.strategy == MR_REMAP_JOINT)) {
        mr_remap_options inner = opts;
        inner.target_renderer = NULL;
        mr_remap_result surrogate;
        status = mr_remap_images(plan, source, target, &inner, &surrogate);
        if (status != MR_OK) return mr_fail_context(status, "remap: the built-in model's fit that starts the fit "
                                                    "through renderer '%s'", mr_renderer_name(opts.target_renderer));
        memcpy(surrogate_values, surrogate.values, sizeof surrogate_values);
        opts.initial_values = surrogate_values;
    }
    if (opts.strategy == MR_REMAP_TWO || opts.strategy == MR_REMAP_THREE) {
        if (source->diffuse == NULL || source->specular == NULL)
            return mr_fail(MR_ERR_INVALID_ARG, "remap: the %s strategy needs the source's diffuse-only and "
                           "specular-only renders", mr_remap_strategy_name(opts.strategy));
        if ((status = check_source_image(plan, source->diffuse, "diffuse")) != MR_OK) return status;
        if ((status = check_source_image(plan, source->specular, "specular")) != MR_OK) return status;
    }

    fit_context ctx;
    memset(&ctx, 0, sizeof ctx);
    ctx.plan = plan;
    ctx.model = target;
    ctx.opts = opts;
    ctx.external = external;
    ctx.value_count = mr_brdf_value_count(target);
    ctx.goal = source->full;
    ctx.failure = MR_OK;
    if (opts.target_values)
        memcpy(ctx.base, opts.target_values, (size_t)ctx.value_count * sizeof(double));
    else
        mr_brdf_default_values(target, ctx.base);
    unsigned char is_linear[MAX_SLOTS];
    const unsigned fixed = fixed_mask(target, opts.held, opts.freed);
    choose_linear_parameters(target, fixed, ctx.base, is_linear);
    for (int i = 0; i < target->param_count; i++) {
        const mr_brdf_param *p = &target->params[i];
        if (held_fixed(target, fixed, i)) continue;
        int offset = mr_brdf_param_offset(target, i);
        if (!is_linear[i]) {
            for (int c = 0; c < p->channels; c++)
                ctx.nonlinear[ctx.nonlinear_count++] = make_slot(target, i, offset + c);
        } else {
            ctx.linear_params[ctx.linear_param_count++] = i;
            for (int c = 0; c < p->channels; c++)
                ctx.linear[ctx.linear_count++] = make_slot(target, i, offset + c);
        }
    }

    const mr_scene *scene = mr_render_plan_scene(plan);
    const float *coverage = mr_render_plan_coverage(plan);
    int *pixels = malloc((size_t)scene->width * (size_t)scene->height * sizeof *pixels);
    if (pixels == NULL) return mr_fail(MR_ERR_NOMEM, "remap: out of memory");
    for (int p = 0; p < scene->width * scene->height; p++)
        if (coverage[p] > 0.0f) pixels[ctx.pixel_count++] = p;
    ctx.pixels = pixels;
    status = mr_image_create(scene->width, scene->height, 3, &ctx.scratch);
    for (int i = 0; status == MR_OK && i <= ctx.linear_param_count; i++)
        status = mr_image_create(scene->width, scene->height, 3, &ctx.basis[i]);
    // A warm start: the fitted parameters start from opts.initial_values (remap.h).
    for (int i = 0; opts.initial_values != NULL && i < target->param_count; i++) {
        if (held_fixed(target, fixed, i)) continue;
        const int offset = mr_brdf_param_offset(target, i);
        for (int c = 0; c < target->params[i].channels; c++)
            ctx.base[offset + c] = mr_clampd(opts.initial_values[offset + c], target->params[i].min_value,
                                             target->params[i].max_value);
    }
    ctx.warm = opts.initial_values != NULL && (opts.strategy == MR_REMAP_AUTO || opts.strategy == MR_REMAP_JOINT);
    // The local stage (mr_local_method): by derivatives wherever the target's renders have them.
    // The paper's local strategies keep the paper's derivative-free search unless asked (their traps are what they
    // reproduce: docs/paper-reproduction.md).
    const int paper_strategy = opts.strategy != MR_REMAP_AUTO && opts.strategy != MR_REMAP_JOINT;
    ctx.gradient = opts.local_method != MR_LOCAL_BOBYQA && !(paper_strategy && opts.local_method == MR_LOCAL_AUTO) &&
                   !external && target->eval_grad != NULL && mr_render_plan_point_lit_only(plan) &&
                   mr_render_plan_material_count(plan) == 1;
    if (status == MR_OK && opts.local_method == MR_LOCAL_GRADIENT && !ctx.gradient)
        status = mr_fail(MR_ERR_UNSUPPORTED, "remap: the gradient local method needs %s",
                         target->eval_grad == NULL ? "a target model with analytic derivatives"
                         : external ? "the built-in renderer (an external one gives no derivatives)"
                                    : "a plan lit by point lights only, with one material");
    ctx.split_lobes = lobes_split(target, ctx.linear_params, ctx.linear_param_count) &&
                      (!external || mr_renderer_has_components(opts.target_renderer));
    ctx.homogeneous = ctx.split_lobes && black_without_linear(target, fixed, ctx.base, is_linear);
    for (int i = 0; status == MR_OK && ctx.split_lobes && i < 4; i++)
        status = mr_image_create(scene->width, scene->height, 3, &ctx.lobe_images[i]);
    if (status != MR_OK) {
        free_context(&ctx);
        return status;
    }

    const double source_energy = image_energy(&ctx, source->full);

    // The source energy that relative figures divide by, floored like relative_rmse so a black source gives
    // finite ratios.
    const double energy_scale = fmax(source_energy, 3.0 * ctx.pixel_count * RELATIVE_RMS_FLOOR * RELATIVE_RMS_FLOOR);
    double projected_gain = 0.0;
    int ambiguous = 0, rescaled_optimum = 0;
    if (opts.strategy == MR_REMAP_AUTO || opts.strategy == MR_REMAP_JOINT) {
        candidate best;
        if (!(opts.strategy == MR_REMAP_AUTO && lobe_staged_fit(&ctx, source, source_energy, &best, &ambiguous)))
            auto_fit(&ctx, &best, &ambiguous);
        // Where the model rescales the solved values (Ward's energy trimming when diffuse + specular > 1), the
        // affine prediction no longer describes the render: refine every parameter against real renders from
        // the projected solution, and keep whichever renders closer. The outcome still reports the gap.
        if (ctx.failure == MR_OK && !isnan(best.sse) &&
            render_values(&ctx, ctx.base, MR_COMPONENT_FULL, ctx.scratch)) {
            double projected_actual = sse_against(&ctx, ctx.scratch, source->full);
            if (fabs(sqrt(projected_actual) - sqrt(best.sse)) > PREDICTION_TOLERANCE * sqrt(energy_scale)) {
                rescaled_optimum = 1;
                double kept[MAX_SLOTS];
                memcpy(kept, ctx.base, sizeof kept);
                double refined = direct_stage(&ctx, 0, 0, source->full, MR_COMPONENT_FULL);
                if (ctx.failure == MR_OK && !(refined < projected_actual)) memcpy(ctx.base, kept, sizeof kept);
            }
        }
    } else {
        if (opts.strategy == MR_REMAP_TWO || opts.strategy == MR_REMAP_THREE) {
            direct_stage(&ctx, MR_LOBE_DIFFUSE, 1, source->diffuse, MR_COMPONENT_DIFFUSE);
            if (ctx.failure == MR_OK) direct_stage(&ctx, MR_LOBE_SPECULAR, 1, source->specular, MR_COMPONENT_SPECULAR);
            if (ctx.failure == MR_OK) direct_stage(&ctx, MR_LOBE_BOTH, 1, source->full, MR_COMPONENT_FULL);
        }
        if (ctx.failure == MR_OK && (opts.strategy == MR_REMAP_SINGLE || opts.strategy == MR_REMAP_THREE))
            direct_stage(&ctx, 0, 0, source->full, MR_COMPONENT_FULL);
    }
    if (ctx.failure != MR_OK) {
        status = ctx.failure;
        free_context(&ctx);
        return status == MR_ERR_EXTERNAL ? status : mr_fail_context(status, "remap to '%s'", target->name);
    }

    // The verdict render: the target exactly as a renderer would show it.
    mr_remap_result result;
    memset(&result, 0, sizeof result);
    memcpy(result.values, ctx.base, sizeof result.values);
    if (!render_full_into_scratch(&ctx, result.values)) { // AUTO's check above may have rendered it
        status = ctx.failure;
        free_context(&ctx);
        return status;
    }
    double actual = sse_against(&ctx, ctx.scratch, source->full);
    long fit_renders = ctx.renders;
    // An external renderer is only nearly affine in the linear parameters (three.js's multiple-scattering boost of a
    // metal's F0): its images were fitted directly where the projection's prediction missed (above), so neither
    // the departure nor the rescaled optimum says the target cannot reach the source; the residual does.
    // A model that never rescales its linear parameters (brdf.h, `rescales` NULL: all but Mitsuba's trimming Ward
    // and Phong) renders affinely in them by its descriptor's contract (test_brdf checks the roles), so its
    // departure is 0 without the two renders that would show float rounding.
    double departure = external || target->rescales == NULL ? 0.0 : affine_departure(&ctx, result.values, ctx.scratch);
    if (external) rescaled_optimum = 0;
    if (isnan(departure)) {
        status = ctx.failure;
        free_context(&ctx);
        return status;
    }
    int local = opts.strategy != MR_REMAP_AUTO && opts.strategy != MR_REMAP_JOINT;
    if (local && affine_optimum_rescaled(&ctx, source->full, energy_scale)) rescaled_optimum = 1;
    if (ctx.failure != MR_OK) {
        status = ctx.failure;
        free_context(&ctx);
        return status;
    }
    if (local && !opts.skip_global_check && actual > 0.0) {
        // A local fit stopped in a local minimum if the global search does clearly better (remap.h). Its renders
        // are counted apart, so `renders` stays the strategy's own cost.
        double saved[MAX_SLOTS];
        memcpy(saved, ctx.base, sizeof saved);
        if (opts.target_values)
            memcpy(ctx.base, opts.target_values, (size_t)ctx.value_count * sizeof(double));
        else
            mr_brdf_default_values(target, ctx.base);
        ctx.goal = source->full;
        candidate global;
        int ignored;
        ctx.warm = 0; // the global search itself, whatever the start
        auto_fit(&ctx, &global, &ignored);
        memcpy(ctx.base, saved, sizeof saved);
        if (ctx.failure != MR_OK) {
            status = ctx.failure;
            free_context(&ctx);
            return status;
        }
        // Compare real renders, not the projection's prediction: where the target rescales its values (Ward's
        // trimming), the prediction promises a fit no render delivers.
        if (!isnan(global.sse)) {
            if (!render_values(&ctx, global.values, MR_COMPONENT_FULL, ctx.basis[0])) {
                status = ctx.failure;
                free_context(&ctx);
                return status;
            }
            double global_actual = sse_against(&ctx, ctx.basis[0], source->full);
            projected_gain = (actual - global_actual) / actual;
        }
    }
    status = mr_rmse(ctx.scratch, source->full, &result.rmse);
    if (status == MR_OK) status = mr_ssim(ctx.scratch, source->full, NULL, &result.ssim, NULL);
    if (status != MR_OK) {
        free_context(&ctx);
        return status;
    }
    double source_rms = ctx.pixel_count > 0 ? sqrt(source_energy / (3.0 * ctx.pixel_count)) : 0.0;
    double fit_rms = ctx.pixel_count > 0 ? sqrt(actual / (3.0 * ctx.pixel_count)) : 0.0;
    // A black source has no radiance to be relative to: RMS radiance is floored at 1e-4 (display value ~0.001,
    // black to the eye), which keeps the ratio finite and a black fit's float-rounding residue negligible.
    result.relative_rmse = fit_rms / fmax(source_rms, RELATIVE_RMS_FLOOR);
    result.renders = fit_renders;
    result.local_method = ctx.gradient ? MR_LOCAL_GRADIENT : MR_LOCAL_BOBYQA;
    classify(&ctx, departure / sqrt(energy_scale), rescaled_optimum, ambiguous, projected_gain, &result);
    // The verdict render, for the resolution check (again only if a check above reused the scratch image).
    if (!render_full_into_scratch(&ctx, result.values) ||
        !check_resolution(&ctx, source_rms, ctx.scratch, ambiguous, &result)) {
        status = ctx.failure;
        free_context(&ctx);
        return status;
    }
    free_context(&ctx);
    result.seconds = now_seconds() - start_time;
    *out = result;
    return MR_OK;
}

/* Mean square of a - b (b NULL: of a) over the values of the pixels the plan's object covers; 0 if none. Unlike
 * image_energy, for a plan without a fit context (the closer look's). */
static double covered_mean_square(const mr_render_plan *plan, const mr_image *a, const mr_image *b) {
    const mr_scene *scene = mr_render_plan_scene(plan);
    const float *coverage = mr_render_plan_coverage(plan);
    double sum = 0.0;
    long values = 0;
    for (int p = 0; p < scene->width * scene->height; p++) {
        if (!(coverage[p] > 0.0f)) continue;
        for (int c = 0; c < 3; c++, values++) {
            const double d = (double)a->pixels[(size_t)p * 3 + c] - (b ? (double)b->pixels[(size_t)p * 3 + c] : 0.0);
            sum += d * d;
        }
    }
    return values > 0 ? sum / (double)values : 0.0;
}

/* Relative RMSE of `fit` against `source` over the pixels the plan's object covers, as mr_remap_result's: the
 * source's RMS radiance floored at RELATIVE_RMS_FLOOR (a black source gives a finite ratio). */
static double covered_relative_rmse(const mr_render_plan *plan, const mr_image *fit, const mr_image *source) {
    return sqrt(covered_mean_square(plan, fit, source)) /
           fmax(sqrt(covered_mean_square(plan, source, NULL)), RELATIVE_RMS_FLOOR);
}

/* The closer look of remap.h (UNDER_RESOLVED, model sources): a CONVERGED fit of a source that is not black
 * (`full`, its render in the fit scene) rendered with the source ZOOM times closer to the highlight; the built-in
 * renderer's check only (opts: both renderers built-in). */
static mr_status zoom_check(const mr_render_plan *plan, const mr_brdf_model *source_model, const double *source_values,
                            const mr_image *full, const mr_brdf_model *target, const mr_remap_options *opts,
                            mr_remap_result *out) {
    const int threads = opts->threads;
    if (out->outcome != MR_FIT_CONVERGED) return MR_OK;
    // The closer view compares a lobe with itself; two renderers differ there for their own reasons (three.js widens
    // a highlight by the screen-space change of the normal), so it is the built-in renderer's alone.
    if (!mr_renderer_is_builtin(opts->source_renderer) || !mr_renderer_is_builtin(opts->target_renderer)) return MR_OK;
    const mr_scene *scene = mr_render_plan_scene(plan);
    if (sqrt(covered_mean_square(plan, full, NULL)) < RELATIVE_RMS_FLOOR) return MR_OK; // black: nothing to look at
    const mr_render_plan *closer = NULL; // kept by `plan`: built by the first remap that asks
    mr_status status = mr_render_plan_zoomed(plan, ZOOM, &closer);
    if (status != MR_OK || closer == NULL) return status;
    const mr_scene *zoomed = mr_render_plan_scene(closer);
    mr_image *source = NULL, *fit = NULL;
    status = mr_image_create(zoomed->width, zoomed->height, 3, &source);
    if (status == MR_OK) status = mr_image_create(zoomed->width, zoomed->height, 3, &fit);
    if (status == MR_OK)
        status = mr_render_into_threads(closer, threads, source_model, source_values, MR_COMPONENT_FULL, source);
    if (status == MR_OK) status = mr_render_into_threads(closer, threads, target, out->values, MR_COMPONENT_FULL, fit);
    if (status == MR_OK) {
        const double closer_rmse = covered_relative_rmse(closer, fit, source);
        if (closer_rmse > ZOOM_RELATIVE_RMSE && closer_rmse > ZOOM_GAIN * fmax(out->relative_rmse, 0.01)) {
            out->outcome = MR_FIT_UNDER_RESOLVED;
            snprintf(out->detail, sizeof out->detail,
                     "under-resolved: the fit matches at %d^2 (relative RMSE %.3g) but %.0f times closer to the "
                     "highlight it misses by %.0f %%: a lobe narrower than the pixels; about %.0f^2 would resolve it",
                     scene->width, out->relative_rmse, ZOOM, 100.0 * closer_rmse, ZOOM * scene->width);
        }
    }
    mr_image_free(source);
    mr_image_free(fit);
    return status;
}

mr_status mr_remap(const mr_render_plan *plan, const mr_brdf_model *source_model, const double *source_values,
                   const mr_brdf_model *target, const mr_remap_options *opts, mr_remap_result *out) {
    if (plan == NULL || source_model == NULL || source_values == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "remap: NULL plan, source model or source values");
    double start = now_seconds();
    const mr_scene *scene = mr_render_plan_scene(plan);
    mr_image *full = NULL, *diffuse = NULL, *specular = NULL;
    mr_status status = mr_image_create(scene->width, scene->height, 3, &full);
    if (status == MR_OK) status = mr_image_create(scene->width, scene->height, 3, &diffuse);
    if (status == MR_OK) status = mr_image_create(scene->width, scene->height, 3, &specular);
    const int threads = opts ? opts->threads : 0;
    mr_renderer *source_renderer = opts ? opts->source_renderer : NULL;
    const int components = mr_renderer_has_components(source_renderer);
    if (status == MR_OK && mr_renderer_is_builtin(source_renderer)) {
        status = mr_render_components_into_threads(plan, threads, source_model, source_values, diffuse, specular);
        if (status == MR_OK)
            status = mr_render_into_threads(plan, threads, source_model, source_values, MR_COMPONENT_FULL, full);
    } else if (status == MR_OK) {
        status = mr_renderer_render(source_renderer, plan, source_model, source_values, full,
                                    components ? diffuse : NULL, components ? specular : NULL);
    }
    // Ties: the tied target parameters held at the source's values (brdf.h), for this remap only.
    mr_remap_options tied = opts ? *opts : mr_remap_options_default();
    double tied_values[MR_BRDF_MAX_VALUES];
    if (tied.ties.tied != 0) {
        if (tied.target_values)
            memcpy(tied_values, tied.target_values, (size_t)mr_brdf_value_count(target) * sizeof(double));
        else
            mr_brdf_default_values(target, tied_values);
        mr_brdf_apply_ties(source_model, source_values, target, &tied.ties, tied_values, &tied.held);
        tied.target_values = tied_values;
        memset(&tied.ties, 0, sizeof tied.ties);
    }
    if (status == MR_OK) {
        mr_remap_source source = {full, components ? diffuse : NULL, components ? specular : NULL};
        status = mr_remap_images(plan, &source, target, &tied, out);
        if (status == MR_OK) status = zoom_check(plan, source_model, source_values, full, target, &tied, out);
        if (status == MR_OK) out->seconds = now_seconds() - start;
    }
    mr_image_free(full);
    mr_image_free(diffuse);
    mr_image_free(specular);
    return status;
}

mr_status mr_remap_external(const mr_render_plan *plan, mr_renderer *renderer, const mr_external_material *material,
                            const mr_brdf_model *target, const mr_remap_options *opts, mr_remap_result *out,
                            mr_image *full) {
    if (plan == NULL || renderer == NULL || material == NULL || target == NULL || out == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "remap: NULL plan, renderer, material, target or result");
    const mr_scene *scene = mr_render_plan_scene(plan);
    const int components = mr_renderer_has_components(renderer);
    mr_image *images[3] = {NULL, NULL, NULL};
    mr_status status = MR_OK;
    for (int k = 0; k < 3 && status == MR_OK; k++)
        if (k == 0 || components) status = mr_image_create(scene->width, scene->height, 3, &images[k]);
    if (status == MR_OK)
        status = mr_renderer_render_external(renderer, plan, material, images[0], images[1], images[2]);
    if (status == MR_OK) {
        mr_remap_source source = {images[0], images[1], images[2]};
        status = mr_remap_images(plan, &source, target, opts, out);
    }
    if (status == MR_OK && full != NULL) {
        if (full->width != scene->width || full->height != scene->height || full->channels != 3)
            status = mr_fail(MR_ERR_INVALID_ARG, "remap: the full render's image is %dx%dx%d, the scene %dx%dx3",
                             full->width, full->height, full->channels, scene->width, scene->height);
        else
            memcpy(full->pixels, images[0]->pixels, (size_t)scene->width * (size_t)scene->height * 3 * sizeof(float));
    }
    for (int k = 0; k < 3; k++) mr_image_free(images[k]);
    return status;
}

mr_status mr_irradiance_scale(const mr_render_plan *plan, const mr_image *reference, double albedo,
                              double *scale) {
    if (plan == NULL || reference == NULL || scale == NULL)
        return mr_fail(MR_ERR_INVALID_ARG, "irradiance matching: NULL plan, reference or output");
    if (!(albedo > 0.0 && albedo <= 1.0))
        return mr_fail(MR_ERR_INVALID_ARG, "irradiance matching: reference albedo %g: expected (0, 1]", albedo);
    mr_status status = check_source_image(plan, reference, "irradiance reference");
    if (status != MR_OK) return status;
    const mr_brdf_model *lambert = mr_brdf_find("lambert");
    if (lambert == NULL) return MR_ERR_UNSUPPORTED;
    double values[3] = {albedo, albedo, albedo};
    mr_image *ours = NULL;
    status = mr_render(plan, lambert, values, MR_COMPONENT_FULL, &ours);
    if (status != MR_OK) return status;
    const mr_scene *scene = mr_render_plan_scene(plan);
    const float *coverage = mr_render_plan_coverage(plan);
    size_t pixel_count = (size_t)scene->width * (size_t)scene->height;
    double peak = 0.0;
    for (size_t i = 0; i < pixel_count * 3; i++) peak = fmax(peak, ours->pixels[i]);
    double sum_ours = 0.0, sum_reference = 0.0;
    for (size_t p = 0; p < pixel_count; p++) {
        if (coverage[p] < 1.0f) continue;
        for (int c = 0; c < 3; c++) {
            double v = ours->pixels[p * 3 + c];
            if (v <= 0.01 * peak) continue;
            sum_ours += v;
            sum_reference += reference->pixels[p * 3 + c];
        }
    }
    mr_image_free(ours);
    if (!(sum_ours > 0.0))
        return mr_fail(MR_ERR_INVALID_ARG, "irradiance matching: the fit scene has no lit pixels at %dx%d",
                       scene->width, scene->height);
    if (!(sum_reference > 1e-6 * sum_ours))
        return mr_fail(MR_ERR_INVALID_ARG, "irradiance matching: the reference is black where the fit scene's sphere "
                       "is lit (is it a render of the same scene, with the light at the same position?)");
    *scale = sum_ours / sum_reference;
    return MR_OK;
}
