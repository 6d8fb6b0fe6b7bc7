/*
 * dual.c — the primitives of dual.h's forward-mode dual numbers: the chain rule onto a tape row. Out of line on
 * purpose: each is a short loop over a tape's columns (MR_DUAL_N or fewer), called from a few hundred places per
 * eval_grad; inlined, the layered models' eval_grad grew to 86 KB of code and ran slower than with these calls. Pure
 * functions of their arguments and the caller's tape: thread-safe.
 */
#include "dual.h"

/* Unit rows of the independent variables: row j is e_j. Constant data. */
static const double unit_rows[MR_DUAL_N][MR_DUAL_N] = {
    {1}, {0, 1}, {0, 0, 1}, {0, 0, 0, 1}, {0, 0, 0, 0, 1}, {0, 0, 0, 0, 0, 1}, {0, 0, 0, 0, 0, 0, 1},
    {0, 0, 0, 0, 0, 0, 0, 1}, {0, 0, 0, 0, 0, 0, 0, 0, 1}, {0, 0, 0, 0, 0, 0, 0, 0, 0, 1},
    {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1}, {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1},
    {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1}, {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1},
    {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1}, {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1},
    {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1}, {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1},
    {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1},
    {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1},
};
_Static_assert(MR_DUAL_N == 20, "unit_rows spells out 20 rows");

/* The rows' loops over a tape's columns in groups of 4 (its width is a multiple of 4: mr_dual_tape_init), with
 * restrict parameters so that GCC vectorises them at -O2 (restrict locals did not suffice). Whole groups, not a
 * loop to the width with a remainder: at the 4-8 columns of a prepared state the remainder's bookkeeping cost as much
 * as the arithmetic. */
_Static_assert(MR_DUAL_N % 4 == 0, "tape widths are rounded up to whole groups of 4 within MR_DUAL_N");
static void row_scale(double *restrict r, int n, double a, const double *restrict x) {
    for (int j = 0; j < n; j += 4)
        for (int i = 0; i < 4; i++) r[j + i] = a * x[j + i];
}
static void row_axpby(double *restrict r, int n, double a, const double *restrict x, double b,
                      const double *restrict y) {
    for (int j = 0; j < n; j += 4)
        for (int i = 0; i < 4; i++) r[j + i] = a * x[j + i] + b * y[j + i];
}
static void row_add_scaled(double *restrict r, int n, double a, const double *restrict x) {
    for (int j = 0; j < n; j += 4)
        for (int i = 0; i < 4; i++) r[j + i] += a * x[j + i];
}

mr_dual mr_dual_var(double v, int column) {
    mr_dual r = {v, unit_rows[column]};
    return r;
}

void mr_dual_vars(const double *v, int count, const int *slots, int k, mr_dual *x) {
    for (int j = 0; j < count; j++) x[j] = slots ? mr_dual_const(v[j]) : mr_dual_var(v[j], j);
    if (slots)
        for (int c = 0; c < k; c++) x[slots[c]] = mr_dual_var(v[slots[c]], c);
}

void mr_dual_grad_state_begin(const mr_brdf_model *model, const double *values, const int *slots, int count,
                              mr_dual_grad_state *st, double *v, mr_dual *x) {
    mr_brdf_clamp_values(model, values, v);
    st->count = count;
    for (int c = 0; c < count; c++) st->slots[c] = slots[c];
    mr_dual_tape_init(&st->tape, st->rows, MR_DUAL_PREP_ROWS * MR_DUAL_N, count);
    mr_dual_vars(v, mr_brdf_value_count(model), slots, count, x);
}

void mr_dual_eval_grad(const mr_brdf_grad_ops *ops, const mr_brdf_model *model, const double *values,
                       const double wi[3], const double wo[3], double *d_diffuse, double *d_specular) {
    const int count = mr_brdf_value_count(model);
    int slots[MR_DUAL_N];
    for (int j = 0; j < count; j++) slots[j] = j;
    mr_dual_grad_state state;
    ops->prepare(model, values, slots, count, &state);
    ops->eval(&state, wi, wo, d_diffuse, d_specular);
}

/* The next free row. The number of rows an evaluation takes is fixed by its code (no loop depends on data), far below
 * a tape's capacity; should a change of a model ever exceed it, the last row is reused: memory stays safe and the
 * derivative tests (tests/test_brdf.c) fail on the wrong derivatives instead. */
static double *tape_row(mr_dual_tape *t) {
    if (t->used + t->width <= t->capacity) {
        double *row = t->buf + t->used;
        t->used += t->width;
        return row;
    }
    return t->buf + (t->capacity - t->width);
}

const double *mr_dual_row1(mr_dual_tape *t, double slope, const double *x) {
    double *row = tape_row(t);
    row_scale(row, t->width, slope, x);
    return row;
}

const double *mr_dual_row2(mr_dual_tape *t, double da, const double *x, double db, const double *y) {
    double *row = tape_row(t);
    row_axpby(row, t->width, da, x, db, y);
    return row;
}

const double *mr_dual_row3(mr_dual_tape *t, double da, const double *x, double db, const double *y, double dc,
                           const double *z) {
    double *row = tape_row(t);
    row_axpby(row, t->width, da, x, db, y);
    row_add_scaled(row, t->width, dc, z);
    return row;
}

/* the left derivatives at a tie: slot by slot, the smaller slope for max, the larger for min */
static mr_dual tie(mr_dual_tape *t, mr_dual a, mr_dual b, int take_max) {
    double *row = tape_row(t);
    for (int j = 0; j < t->width; j++) {
        double x = a.d ? a.d[j] : 0.0, y = b.d ? b.d[j] : 0.0;
        row[j] = take_max ? MR_MAX(x, y) : MR_MIN(x, y);
    }
    mr_dual r = {a.v, row};
    return r;
}

mr_dual mr_dual_max(mr_dual_tape *t, mr_dual a, mr_dual b) {
    if (a.v != b.v) return a.v > b.v ? a : b;
    return tie(t, a, b, 0);
}

mr_dual mr_dual_min(mr_dual_tape *t, mr_dual a, mr_dual b) {
    if (a.v != b.v) return a.v < b.v ? a : b;
    return tie(t, a, b, 1);
}
