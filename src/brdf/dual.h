/*
 * dual.h — forward-mode dual numbers for the eval_grad of the layered models (openpbr.c, blender_principled.c,
 * standard_surface.c); internal, not installed.
 *
 * Why dual numbers there: those models chain a dozen layers (albedo scaling by tabulated albedos, darkening, F82
 * tint, EON's multiple scattering, Turquin's and Cycles' energy factors), each a function of several parameters.
 * Written by hand the chain rule would be hundreds of lines that repeat the model with every term doubled; with a
 * dual number, eval_grad is the model's prepare + eval transcribed once, operation for operation, and each
 * operation carries d(value)/d(values[j]) for every packed slot j at once. This is analytic differentiation (the
 * exact derivative of the computed function, to rounding), not finite differences. The models' own eval stays in
 * plain doubles: the transcriptions are checked against central differences of eval at random points and one-sided
 * ones at the defaults (tests/test_brdf.c, gradient_matches_central_differences and
 * gradient_at_defaults_matches_one_sided_differences), which a transcription that strayed from eval fails.
 *
 * One derivative slot per packed value: MR_DUAL_N >= the largest value count of a model using it (static asserts in
 * each model). The small operations are static inline; the loops over the slots are out of line in dual.c.
 *
 * Prepared derivatives (brdf.h, grad_ops; each model's op/bp/ss_grad_ops): each model's transcription is split in
 * a value-only half (its prepare) and a direction-dependent half (its eval). A derivative render (render.c) runs the
 * first once, on the tape of a mr_dual_grad_state, with columns for the slots the fit asks for only (the others are
 * constants, and operations on constants make no row), and the second per sample on a scratch tape. Measured
 * (tests/bench_brdf_grad.c, one thread, 5 slots of openpbr's 19): 0.23-0.38 us per sample against 2.2-2.9 us for
 * eval_grad, 0.2 us to prepare; a 64^2 derivative render 4-5 times a plain render instead of 35-60 times.
 *
 * Non-differentiable points: min, max and clamps pass the derivative of the branch they select (at a tie of min or
 * max, the derivative from the left, slot by slot; a clamp keeps its argument's derivative when it is exactly at the
 * bound), i.e. a one-sided derivative, from the inside of the range where the value sits at a bound. sqrt and log
 * at 0 give derivative 0 (the callers only reach them where the other side is clamped away). Pure functions:
 * thread-safe.
 */
#ifndef MR_BRDF_DUAL_H
#define MR_BRDF_DUAL_H

#include "brdf_internal.h"

/* Derivative slots: the largest value count among the models that use this (standard-surface's 20). */
#define MR_DUAL_N 20

/* The derivative rows live on a tape (a bump allocator over a caller's buffer); a dual is its value and a pointer to
 * its row, 16 bytes, which the x86-64 and AArch64 calling conventions pass and return in registers. Holding the 20
 * derivatives in the dual itself (168 bytes) was measured at 10-14 us per openpbr eval_grad: every operation copied
 * three of them, and inlined, 250 operations made 86 KB of code. A constant has no row (d == NULL), so operations
 * with constants skip its slots.
 *
 * Columns: a tape's rows are `width` doubles wide, one column per differentiated slot. eval_grad differentiates every
 * packed slot (width MR_DUAL_N, column j = slot j); a prepared derivative state (brdf.h, mr_brdf_grad_ops) only the
 * slots a caller asks for (width k, column c = slots[c]), the other slots being constants (mr_dual_vars): each column
 * is computed by the same operations in the same order either way, so the k columns equal eval_grad's (to the sign
 * of a zero). Rows of two tapes combine when their widths agree: a prepared state keeps the value-only part (the
 * model's prepare) on a tape of its own, read-only afterwards, and each evaluation puts the direction-dependent part
 * on a scratch tape on its stack. */
#define MR_DUAL_ROWS 384 /* rows of MR_DUAL_N per scratch buffer (61 KB of the caller's stack); the layered models'
                            eval_grad takes 170-215, dual.c */
#define MR_DUAL_SCRATCH (MR_DUAL_ROWS * MR_DUAL_N) /* doubles of a scratch buffer */

typedef struct mr_dual {
    double v;         /* value */
    const double *d;  /* d v / d values[slot of column c], c < the tape's width; NULL: all 0 (a constant) */
} mr_dual;

typedef struct mr_dual_tape {
    int used;      /* doubles taken */
    int width;     /* columns per row, a multiple of 4 up to MR_DUAL_N */
    int capacity;  /* doubles in buf */
    double *buf;
} mr_dual_tape;

/* A tape of `width` columns over buf[capacity] (the caller's storage, which must outlive the rows). */
static inline void mr_dual_tape_init(mr_dual_tape *t, double *buf, int capacity, int width) {
    t->used = 0;
    t->width = (width + 3) & ~3; /* whole groups of 4 (dual.c's loops); the columns beyond `width` are never read */
    t->capacity = capacity;
    t->buf = buf;
}

static inline mr_dual mr_dual_const(double v) {
    mr_dual r = {v, NULL};
    return r;
}

/* A constant 0: a prepared state's slot left out of its columns at 0 (a coat weight or metalness a fit holds at 0).
 * The layered models skip the terms it switches off, as their eval does: those terms are then exact 0s and 1s whose
 * derivatives are 0 in every column, so skipping them changes no derivative beyond the sign of a zero (the full-width
 * eval_grad, where every slot is a variable, never skips). */
static inline int mr_dual_is_const_zero(mr_dual a) { return a.d == NULL && a.v == 0.0; }

/* The independent variable of column `column` (its row is a constant unit vector, not on the tape). */
mr_dual mr_dual_var(double v, int column);

/* x[j] for the packed values v[0..count): with slots == NULL every slot its own column j (eval_grad's width
 * MR_DUAL_N); otherwise slots[c] (distinct, < count) in column c for c < k and every other slot a constant. */
void mr_dual_vars(const double *v, int count, const int *slots, int k, mr_dual *x);

/* The rows' arithmetic, out of line (dual.c): a new row slope x, da x + db y, or (da x + db y) + dc z. */
const double *mr_dual_row1(mr_dual_tape *t, double slope, const double *x);
const double *mr_dual_row2(mr_dual_tape *t, double da, const double *x, double db, const double *y);
const double *mr_dual_row3(mr_dual_tape *t, double da, const double *x, double db, const double *y, double dc,
                           const double *z);

/* f(a) given f(a.v) = value and f'(a.v) = slope: the chain rule, the one primitive the others use; and f(a, b),
 * f(a, b, c) given their partial derivatives. Inline only to the point of skipping constants' rows without a call
 * (a prepared state's columns leave most of a model's terms constant); each row's loop is one call into dual.c. An
 * argument that is a constant contributes nothing, exactly as a row of zeros would to the sign of a zero. */
static inline mr_dual mr_dual_chain(mr_dual_tape *t, double value, double slope, mr_dual a) {
    mr_dual r = {value, a.d ? mr_dual_row1(t, slope, a.d) : NULL};
    return r;
}
static inline mr_dual mr_dual_chain2(mr_dual_tape *t, double value, double da, mr_dual a, double db, mr_dual b) {
    if (!b.d) return mr_dual_chain(t, value, da, a);
    if (!a.d) return mr_dual_chain(t, value, db, b);
    mr_dual r = {value, mr_dual_row2(t, da, a.d, db, b.d)};
    return r;
}
static inline mr_dual mr_dual_chain3(mr_dual_tape *t, double value, double da, mr_dual a, double db, mr_dual b,
                                     double dc, mr_dual c) {
    if (!c.d) return mr_dual_chain2(t, value, da, a, db, b);
    if (!a.d) return mr_dual_chain2(t, value, db, b, dc, c);
    if (!b.d) return mr_dual_chain2(t, value, da, a, dc, c);
    mr_dual r = {value, mr_dual_row3(t, da, a.d, db, b.d, dc, c.d)};
    return r;
}
/* At a tie of two duals, each slot takes the derivative from the left (the value's decreasing side): for max the
 * smaller of the two slopes, for min the larger. A grey colour's channels tie in a max over channels
 * (blender-principled's estimate), at its default 1, the top of its range, where only that side exists. */
mr_dual mr_dual_max(mr_dual_tape *t, mr_dual a, mr_dual b);
mr_dual mr_dual_min(mr_dual_tape *t, mr_dual a, mr_dual b);

static inline mr_dual mr_dual_add(mr_dual_tape *t, mr_dual a, mr_dual b) {
    return mr_dual_chain2(t, a.v + b.v, 1.0, a, 1.0, b);
}
static inline mr_dual mr_dual_sub(mr_dual_tape *t, mr_dual a, mr_dual b) {
    return mr_dual_chain2(t, a.v - b.v, 1.0, a, -1.0, b);
}
static inline mr_dual mr_dual_mul(mr_dual_tape *t, mr_dual a, mr_dual b) {
    return mr_dual_chain2(t, a.v * b.v, b.v, a, a.v, b);
}
static inline mr_dual mr_dual_div(mr_dual_tape *t, mr_dual a, mr_dual b) {
    double q = a.v / b.v;
    return mr_dual_chain2(t, q, 1.0 / b.v, a, -q / b.v, b);
}
/* a + k, k - a, k a for a constant k */
static inline mr_dual mr_dual_addc(mr_dual_tape *t, mr_dual a, double k) { return mr_dual_chain(t, a.v + k, 1.0, a); }
static inline mr_dual mr_dual_rsubc(mr_dual_tape *t, double k, mr_dual a) { return mr_dual_chain(t, k - a.v, -1.0, a); }
static inline mr_dual mr_dual_scale(mr_dual_tape *t, mr_dual a, double k) { return mr_dual_chain(t, k * a.v, k, a); }
static inline mr_dual mr_dual_sq(mr_dual_tape *t, mr_dual a) { return mr_dual_chain(t, a.v * a.v, 2.0 * a.v, a); }
static inline mr_dual mr_dual_recip(mr_dual_tape *t, mr_dual a) {
    return mr_dual_chain(t, 1.0 / a.v, -1.0 / (a.v * a.v), a);
}
static inline mr_dual mr_dual_sqrt(mr_dual_tape *t, mr_dual a) {
    double s = sqrt(a.v);
    return mr_dual_chain(t, s, s > 0.0 ? 0.5 / s : 0.0, a);
}
static inline mr_dual mr_dual_exp(mr_dual_tape *t, mr_dual a) {
    double e = exp(a.v);
    return mr_dual_chain(t, e, e, a);
}
static inline mr_dual mr_dual_log(mr_dual_tape *t, mr_dual a) {
    return mr_dual_chain(t, log(a.v), a.v > 0.0 ? 1.0 / a.v : 0.0, a);
}
/* a^k for a constant k, a > 0 */
static inline mr_dual mr_dual_powc(mr_dual_tape *t, mr_dual a, double k) {
    double p = pow(a.v, k);
    return mr_dual_chain(t, p, a.v > 0.0 ? k * p / a.v : 0.0, a);
}
/* a + (b - a) t, written as the models write it (the same rounding as their lerp helpers) */
static inline mr_dual mr_dual_lerp(mr_dual_tape *t, mr_dual a, mr_dual b, mr_dual u) {
    return mr_dual_chain3(t, a.v + (b.v - a.v) * u.v, 1.0 - u.v, a, u.v, b, b.v - a.v, u);
}

/* MR_MIN, MR_MAX and mr_clampd against constants, with the selected branch's derivative (see the top of the file) */
static inline mr_dual mr_dual_minc(mr_dual a, double k) { return a.v < k ? a : mr_dual_const(k); }
static inline mr_dual mr_dual_maxc(mr_dual a, double k) { return a.v > k ? a : mr_dual_const(k); }
/* at the bounds themselves the argument's derivative is kept: the one-sided derivative from inside */
static inline mr_dual mr_dual_clampc(mr_dual a, double lo, double hi) {
    return a.v >= lo ? (a.v <= hi ? a : mr_dual_const(hi)) : mr_dual_const(lo);
}

/* ---- the shared lobes and tables, lifted (brdf_internal.h, layering.c) ---- */

/* mr_fresnel_dielectric(cos_i, eta) with eta a dual number (cos_i a geometric constant) */
static inline mr_dual mr_dual_fresnel_dielectric(mr_dual_tape *t, double cos_i, mr_dual eta) {
    double dF;
    double F = mr_fresnel_dielectric(cos_i, eta.v, &dF);
    return mr_dual_chain(t, F, dF, eta);
}

/* mr_ggx_dv_correlated at a dual alpha */
static inline mr_dual mr_dual_ggx_dv(mr_dual_tape *t, mr_dual alpha, const mr_brdf_geom *g) {
    double dDV;
    double DV = mr_ggx_dv_correlated(alpha.v, g, &dDV);
    return mr_dual_chain(t, DV, dDV, alpha);
}

/* the albedo tables of layering.c at dual (r, eps); mu is a geometric constant */
static inline mr_dual mr_dual_albedo_dielectric(mr_dual_tape *t, double mu, mr_dual r, mr_dual eps) {
    double dr, deps;
    double E = mr_ggx_albedo_dielectric_grad(mu, r.v, eps.v, &dr, &deps);
    return mr_dual_chain2(t, E, dr, r, deps, eps);
}
static inline mr_dual mr_dual_albedo_one(mr_dual_tape *t, double mu, mr_dual r) {
    double dr;
    double E = mr_ggx_albedo_one_grad(mu, r.v, &dr);
    return mr_dual_chain(t, E, dr, r);
}
static inline mr_dual mr_dual_albedo_one_avg(mr_dual_tape *t, mr_dual r) {
    double dr;
    double E = mr_ggx_albedo_one_avg_grad(r.v, &dr);
    return mr_dual_chain(t, E, dr, r);
}
static inline mr_dual mr_dual_fresnel_dielectric_avg(mr_dual_tape *t, mr_dual eta) {
    double d;
    double F = mr_fresnel_dielectric_avg_grad(eta.v, &d);
    return mr_dual_chain(t, F, d, eta);
}

/* Schlick's curve F0 + (1 - F0)(1 - mu)^5 at a dual F0 (affine in it) */
static inline mr_dual mr_dual_schlick(mr_dual_tape *t, double mu, mr_dual f0) {
    double w = mr_schlick_weight(mu);
    return mr_dual_chain(t, mr_schlick(mu, f0.v), 1.0 - w, f0);
}

/* mr_f82_coeff(f0, tint) and mr_f82_tint(mu, f0, b) at dual arguments (both affine in each argument; the tint's
 * clamp into [0, 1] is one-sided at its ends) */
static inline mr_dual mr_dual_f82_coeff(mr_dual_tape *t, mr_dual f0, mr_dual tint) {
    double m = 1.0 - MR_F82_MU_BAR, m2 = m * m, m6 = m2 * m2 * m2, k = 1.0 / (MR_F82_MU_BAR * m6);
    double s = mr_schlick(MR_F82_MU_BAR, f0.v), ds = 1.0 - mr_schlick_weight(MR_F82_MU_BAR);
    return mr_dual_chain2(t, mr_f82_coeff(f0.v, tint.v), (1.0 - tint.v) * ds * k, f0, -s * k, tint);
}
static inline mr_dual mr_dual_f82_tint(mr_dual_tape *t, double mu, mr_dual f0, mr_dual b) {
    double m = 1.0 - mu, m2 = m * m, p = mu * m2 * m2 * m2;
    double raw = mr_schlick(mu, f0.v) - b.v * p;
    double F = mr_f82_tint(mu, f0.v, b.v);
    if (!(raw >= 0.0 && raw <= 1.0)) return mr_dual_const(F);
    return mr_dual_chain2(t, F, 1.0 - mr_schlick_weight(mu), f0, -p, b);
}

/* Writes the derivatives of a model's diffuse[3] and specular[3] duals into the arrays of eval_grad ([slot*3 + c], for
 * the model's `count` slots, on a full-width tape) or of a prepared state's eval ([column*3 + c], `count` columns). */
static inline void mr_dual_store_grad(const mr_dual diffuse[3], const mr_dual specular[3], int count,
                                      double *d_diffuse, double *d_specular) {
    for (int j = 0; j < count; j++)
        for (int c = 0; c < 3; c++) {
            d_diffuse[j * 3 + c] = diffuse[c].d ? diffuse[c].d[j] : 0.0;
            d_specular[j * 3 + c] = specular[c].d ? specular[c].d[j] : 0.0;
        }
}

/* The prepared derivative state of a layered model (brdf.h, mr_brdf_grad_ops): the model's own struct of prepared
 * duals `prep` (bytes, aligned for double, at most MR_DUAL_PREP_BYTES), the columns' slots, and the tape the duals'
 * rows live on. It points into itself: used where it was prepared, never copied. */
#define MR_DUAL_PREP_BYTES 2048
#define MR_DUAL_PREP_ROWS 160 /* rows of MR_DUAL_N for the value-only part; the layered models take 60-110 */
typedef struct mr_dual_grad_state {
    union {
        double align;
        unsigned char bytes[MR_DUAL_PREP_BYTES];
    } prep;
    int count;                /* columns (slots asked for) */
    int slots[MR_DUAL_N];
    mr_dual_tape tape;        /* over rows[], width count */
    double rows[MR_DUAL_PREP_ROWS * MR_DUAL_N];
} mr_dual_grad_state;

/* Common start of a layered model's grad_ops.prepare: clamps the values into v[], fills the columns and the tape of
 * `st` and x[] (mr_dual_vars). 0 when slots are not distinct slots of the model (then the state is not usable; the
 * caller, mr_brdf_grad_prepare in registry.c, checks that before). */
void mr_dual_grad_state_begin(const mr_brdf_model *model, const double *values, const int *slots, int count,
                              mr_dual_grad_state *st, double *v, mr_dual *x);

/* A layered model's eval_grad: its grad_ops prepared for every slot in order and evaluated at (wi, wo), the state on
 * the stack (the derivatives of the slots asked for do not depend on which others are asked: test_brdf checks every
 * subset against this). */
void mr_dual_eval_grad(const mr_brdf_grad_ops *ops, const mr_brdf_model *model, const double *values,
                       const double wi[3], const double wo[3], double *d_diffuse, double *d_specular);

/* Common start of a layered model's grad_ops.eval: zeroes the state's count*3 outputs and fills g; 0 below the
 * horizon (the derivatives are then 0, as eval_grad's). */
static inline int mr_dual_grad_eval_begin(const mr_dual_grad_state *st, const double wi[3], const double wo[3],
                                          double *d_diffuse, double *d_specular, mr_brdf_geom *g) {
    for (int j = 0; j < st->count * 3; j++) d_diffuse[j] = d_specular[j] = 0.0;
    return mr_brdf_geom_init(wi, wo, g);
}

#endif /* MR_BRDF_DUAL_H */
