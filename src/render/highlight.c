/*
 * highlight.c — sub-pixel quadrature around a point light's highlight (contract and rationale in highlight.h).
 */
#include "highlight.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "../mr_internal.h"

/* Each ring sector is cut into SPLIT x SPLIT parts (in ln r and in angle) only to share it out between the
 * pixels it straddles; a pixel gets one sample per sector, at the centroid of the parts it holds. */
#define SPLIT 8
/* Points per side of a grid cell that a disc cuts, to place the cell's sample in the part outside the disc. */
#define CELL_PROBES 32

/* The radii bounding the rings: HIGHLIGHT_INNER * ratio^k while rings are thinner than HIGHLIGHT_SPACING, then
 * HIGHLIGHT_SPACING apart, the last one clipped to the disc's radius. Returns the number of rings (radii has one
 * more entry). */
static int ring_radii(double radius, double radii[64]) {
    int rings = 0;
    radii[0] = HIGHLIGHT_INNER;
    while (radii[rings] < radius && rings < 62) {
        const double next = MR_MIN(radii[rings] * HIGHLIGHT_RING_RATIO, radii[rings] + HIGHLIGHT_SPACING);
        radii[rings + 1] = MR_MIN(next, radius);
        rings++;
    }
    return rings;
}

/* Sectors of a ring whose outer radius is r: HIGHLIGHT_ANGLES, or more where their arcs would be longer than
 * HIGHLIGHT_SPACING. */
static int ring_angles(double r) { return MR_MAX(HIGHLIGHT_ANGLES, (int)ceil(2.0 * MR_PI * r / HIGHLIGHT_SPACING)); }

int mr_highlight_max_samples(int count) {
    return HIGHLIGHT_GRID * HIGHLIGHT_GRID + count * (62 * ring_angles(HIGHLIGHT_RADIUS) + 2);
}

int mr_highlight_touches(const highlight_disc *discs, int count, int x, int y) {
    for (int d = 0; d < count; d++) {
        double nx = mr_clampd(discs[d].cx, x, x + 1.0) - discs[d].cx;
        double ny = mr_clampd(discs[d].cy, y, y + 1.0) - discs[d].cy;
        if (nx * nx + ny * ny < discs[d].radius * discs[d].radius) return 1;
    }
    return 0;
}

/* The integral of sqrt(r^2 - x^2) from 0 to x, |x| <= r. */
static double half_chord_integral(double x, double r) {
    x = mr_clampd(x, -r, r);
    return 0.5 * (x * sqrt(MR_MAX(0.0, r * r - x * x)) + r * r * asin(x / r));
}

double mr_highlight_disc_rect_area(double cx, double cy, double r, double x0, double y0, double x1, double y1) {
    if (!(r > 0.0)) return 0.0;
    x0 = MR_MAX(x0 - cx, -r);
    x1 = MR_MIN(x1 - cx, r);
    y0 -= cy;
    y1 -= cy;
    if (!(x1 > x0) || !(y1 > y0)) return 0.0;
    // Between consecutive breakpoints (where the circle crosses y0 or y1) the chord's clipped ends follow one
    // branch each, the circle or a line, so each piece integrates in closed form.
    double cuts[6] = {x0, x1, 0, 0, 0, 0};
    int n = 2;
    const double ys[2] = {y0, y1};
    for (int k = 0; k < 2; k++)
        if (fabs(ys[k]) < r) {
            double xb = sqrt(r * r - ys[k] * ys[k]);
            if (xb > x0 && xb < x1) cuts[n++] = xb;
            if (-xb > x0 && -xb < x1) cuts[n++] = -xb;
        }
    for (int i = 1; i < n; i++) // insertion sort: at most six values
        for (int j = i; j > 0 && cuts[j - 1] > cuts[j]; j--) {
            double t = cuts[j];
            cuts[j] = cuts[j - 1];
            cuts[j - 1] = t;
        }
    double area = 0.0;
    for (int i = 0; i + 1 < n; i++) {
        double a = cuts[i], b = cuts[i + 1];
        if (!(b > a)) continue;
        double mid = 0.5 * (a + b), s = sqrt(MR_MAX(0.0, r * r - mid * mid));
        double top_mid = MR_MIN(y1, s), bottom_mid = MR_MAX(y0, -s);
        if (!(top_mid > bottom_mid)) continue;
        double chord = half_chord_integral(b, r) - half_chord_integral(a, r);
        double top = y1 < s ? y1 * (b - a) : chord;
        double bottom = y0 > -s ? y0 * (b - a) : -chord;
        area += top - bottom;
    }
    return MR_MAX(area, 0.0);
}

/* An angle bounding ring sectors, with its cosine and sine: taken once for the two sectors it bounds. */
typedef struct sector_angle {
    double phi, cos_phi, sin_phi;
} sector_angle;

static sector_angle angle_at(double phi) { return (sector_angle){phi, cos(phi), sin(phi)}; }

/* The bounding box {x0, y0, x1, y1} of the ring sector [ra, rb] x [phi0, phi1] of the disc: its four corners and
 * the outer arc's extremes where it crosses an axis. */
static void sector_box(const highlight_disc *disc, double ra, double rb, const sector_angle *phi0,
                       const sector_angle *phi1, double box[4]) {
    box[0] = box[1] = INFINITY;
    box[2] = box[3] = -INFINITY;
    const sector_angle *phis[2] = {phi0, phi1};
    const double rs[2] = {ra, rb};
    for (int a = 0; a < 2; a++)
        for (int b = 0; b < 2; b++) {
            const double px = disc->cx + rs[b] * phis[a]->cos_phi, py = disc->cy + rs[b] * phis[a]->sin_phi;
            box[0] = MR_MIN(box[0], px);
            box[1] = MR_MIN(box[1], py);
            box[2] = MR_MAX(box[2], px);
            box[3] = MR_MAX(box[3], py);
        }
    for (int q = 0; q <= 4; q++) { // axis directions 0, pi/2, pi, 3pi/2, 2pi inside the arc
        const double axis = 0.5 * MR_PI * q;
        if (axis <= phi0->phi || axis >= phi1->phi) continue;
        const double px = disc->cx + rb * cos(axis), py = disc->cy + rb * sin(axis);
        box[0] = MR_MIN(box[0], px);
        box[1] = MR_MIN(box[1], py);
        box[2] = MR_MAX(box[2], px);
        box[3] = MR_MAX(box[3], py);
    }
}

/* A ring sector [ra, rb] x [step j, step (j + 1)] wholly inside one pixel: one sample at its centroid. */
static highlight_sample whole_sector_sample(const highlight_disc *disc, double ra, double rb, double step, int j) {
    const double half = 0.5 * step, phi = step * (j + 0.5);
    const double rc = 2.0 / 3.0 * (rb * rb * rb - ra * ra * ra) / (rb * rb - ra * ra) * sin(half) / half;
    return (highlight_sample){disc->cx + rc * cos(phi), disc->cy + rc * sin(phi), 0.5 * (rb * rb - ra * ra) * step};
}

/* One of the SPLIT x SPLIT parts a sector that straddles pixels is cut into: its centroid and area. */
typedef struct sector_part {
    double x, y, area;
} sector_part;

/* The parts of ring k's sector j (ring radii[k] .. radii[k + 1], `ratio` = the SPLIT-th root of their ratio), in
 * the order their shares are summed: by ln r, then by angle. */
static void sector_parts(const highlight_disc *disc, const double *radii, int k, double ratio, double step, int j,
                         sector_part parts[SPLIT * SPLIT]) {
    // The parts' angles are the same at every radius: their sines and cosines are taken once.
    double cos_phi[SPLIT], sin_phi[SPLIT];
    for (int b = 0; b < SPLIT; b++) {
        const double phi = step * (j + (b + 0.5) / SPLIT);
        cos_phi[b] = cos(phi);
        sin_phi[b] = sin(phi);
    }
    const double half = 0.5 * step / SPLIT, sin_half = sin(half);
    double ra = radii[k];
    for (int a = 0; a < SPLIT; a++, ra *= ratio) {
        const double rb = a == SPLIT - 1 ? radii[k + 1] : ra * ratio;
        const double part = 0.5 * (rb * rb - ra * ra) * (step / SPLIT);
        // the part's centroid: the sectors' samples sit at the centroid of what they cover, so a shading that
        // varies linearly across the pixel is integrated exactly
        const double rc = 2.0 / 3.0 * (rb * rb * rb - ra * ra * ra) / (rb * rb - ra * ra) * sin_half / half;
        for (int b = 0; b < SPLIT; b++)
            parts[a * SPLIT + b] = (sector_part){disc->cx + rc * cos_phi[b], disc->cy + rc * sin_phi[b], part};
    }
}

/* The sample of a straddling sector in pixel (x, y): the centroid of its parts there. Returns 0 if none is. */
static int parts_sample(const sector_part parts[SPLIT * SPLIT], int x, int y, highlight_sample *out) {
    double weight = 0.0, sx = 0.0, sy = 0.0;
    for (int i = 0; i < SPLIT * SPLIT; i++) {
        const sector_part *q = &parts[i];
        if ((int)floor(q->x) != x || (int)floor(q->y) != y) continue;
        weight += q->area;
        sx += q->area * q->x;
        sy += q->area * q->y;
    }
    if (!(weight > 0.0)) return 0;
    *out = (highlight_sample){sx / weight, sy / weight, weight};
    return 1;
}

/* Does the box {x0, y0, x1, y1} miss pixel (x, y), or lie wholly in it? */
static int box_misses(const double box[4], int x, int y) {
    return box[2] <= x || box[0] >= x + 1.0 || box[3] <= y || box[1] >= y + 1.0;
}
static int box_within(const double box[4], int x, int y) {
    return box[0] >= x && box[2] <= x + 1.0 && box[1] >= y && box[3] <= y + 1.0;
}

/* Scale the disc's samples of pixel (x, y), out[first .. n - 1], to the disc's exact area there; a sliver of the
 * disc no sector's centre falls in gets one sample where the pixel comes nearest. Returns the new count. */
static int share_exact_area(const highlight_disc *disc, int x, int y, double exact, highlight_sample *out, int first,
                            int n) {
    double sum = 0.0;
    for (int i = first; i < n; i++) sum += out[i].weight;
    if (sum > 0.0) {
        for (int i = first; i < n; i++) out[i].weight *= exact / sum;
    } else {
        double px = mr_clampd(disc->cx, x, x + 1.0), py = mr_clampd(disc->cy, y, y + 1.0);
        out[n++] = (highlight_sample){px, py, exact};
    }
    return n;
}

/* The disc's sectors' samples in pixel (x, y), appended to out; their weights scaled to the disc's exact area
 * in the pixel. Returns the new count. This is the definition; mr_highlight_quadrature_build gives the same
 * samples for all pixels at once. */
static int disc_samples(const highlight_disc *disc, int x, int y, highlight_sample *out, int n) {
    const double exact = mr_highlight_disc_rect_area(disc->cx, disc->cy, disc->radius, x, y, x + 1.0, y + 1.0);
    if (!(exact > 0.0)) return n;
    const int first = n;
    double radii[64];
    const int rings = ring_radii(disc->radius, radii);
    // The innermost disc, r < HIGHLIGHT_INNER: one sample at the centre, in the pixel that holds it.
    if ((int)floor(disc->cx) == x && (int)floor(disc->cy) == y)
        out[n++] = (highlight_sample){disc->cx, disc->cy, MR_PI * radii[0] * radii[0]};
    for (int k = 0; k < rings; k++) {
        const double ratio = pow(radii[k + 1] / radii[k], 1.0 / SPLIT);
        const int angles = ring_angles(radii[k + 1]);
        const double step = 2.0 * MR_PI / angles;
        sector_angle from = angle_at(step * 0), to;
        for (int j = 0; j < angles; j++, from = to) {
            to = angle_at(step * (j + 1));
            // Most sectors lie in one pixel: their bounding box decides without cutting them up.
            double box[4];
            sector_box(disc, radii[k], radii[k + 1], &from, &to, box);
            if (box_misses(box, x, y)) continue; // elsewhere
            if (box_within(box, x, y)) {
                out[n++] = whole_sector_sample(disc, radii[k], radii[k + 1], step, j);
                continue;
            }
            sector_part parts[SPLIT * SPLIT];
            sector_parts(disc, radii, k, ratio, step, j, parts);
            n += parts_sample(parts, x, y, &out[n]);
        }
    }
    return share_exact_area(disc, x, y, exact, out, first, n);
}

/* A sample as build_disc_pixels makes it, with its pixel (an index into the disc's window). */
typedef struct placed_sample {
    highlight_sample sample;
    int pixel;
} placed_sample;

/* Make room for `needed` samples in *list (capacity *capacity); 0 on allocation failure. */
static int reserve_placed(placed_sample **list, int *capacity, int needed) {
    if (needed <= *capacity) return 1;
    const int grown_capacity = MR_MAX(2 * *capacity, MR_MAX(needed, 256));
    placed_sample *grown = realloc(*list, (size_t)grown_capacity * sizeof *grown);
    if (grown == NULL) return 0;
    *list = grown;
    *capacity = grown_capacity;
    return 1;
}

/* disc_samples for every pixel of the disc's window at once: each sector is placed (and, if it straddles pixels,
 * cut up) once instead of once per pixel. A pixel's samples are made in sector order, the order disc_samples
 * appends them in, by the same operations, so they are the same values. Returns 0 on allocation failure. */
static int build_disc_pixels(const highlight_disc *disc, highlight_disc_pixels *dp) {
    const int pixels = dp->nx * dp->ny;
    double *exact = malloc((size_t)MR_MAX(pixels, 1) * sizeof *exact);
    placed_sample *made = NULL;
    int made_count = 0, made_capacity = 0, ok = exact != NULL;
    for (int p = 0; p < pixels && ok; p++) {
        const int x = dp->x0 + p % dp->nx, y = dp->y0 + p / dp->nx;
        exact[p] = mr_highlight_disc_rect_area(disc->cx, disc->cy, disc->radius, x, y, x + 1.0, y + 1.0);
    }
    double radii[64];
    const int rings = ring_radii(disc->radius, radii);
    const int centre = ((int)floor(disc->cy) - dp->y0) * dp->nx + (int)floor(disc->cx) - dp->x0;
    const int centre_inside = (int)floor(disc->cx) >= dp->x0 && (int)floor(disc->cx) < dp->x0 + dp->nx &&
                              (int)floor(disc->cy) >= dp->y0 && (int)floor(disc->cy) < dp->y0 + dp->ny;
    if (ok && centre_inside && exact[centre] > 0.0) {
        ok = reserve_placed(&made, &made_capacity, 1);
        if (ok) made[made_count++] = (placed_sample){{disc->cx, disc->cy, MR_PI * radii[0] * radii[0]}, centre};
    }
    for (int k = 0; k < rings && ok; k++) {
        const double ratio = pow(radii[k + 1] / radii[k], 1.0 / SPLIT);
        const int angles = ring_angles(radii[k + 1]);
        const double step = 2.0 * MR_PI / angles;
        sector_angle from = angle_at(step * 0), to;
        for (int j = 0; j < angles && ok; j++, from = to) {
            to = angle_at(step * (j + 1));
            double box[4];
            sector_box(disc, radii[k], radii[k + 1], &from, &to, box);
            int cut = 0; // the parts are made when the first pixel needs them
            sector_part parts[SPLIT * SPLIT];
            for (int p = 0; p < pixels; p++) {
                const int x = dp->x0 + p % dp->nx, y = dp->y0 + p / dp->nx;
                if (!(exact[p] > 0.0) || box_misses(box, x, y)) continue;
                if (!(ok = reserve_placed(&made, &made_capacity, made_count + 1))) break;
                if (box_within(box, x, y)) {
                    made[made_count].sample = whole_sector_sample(disc, radii[k], radii[k + 1], step, j);
                } else {
                    if (!cut) sector_parts(disc, radii, k, ratio, step, j, parts);
                    cut = 1;
                    if (!parts_sample(parts, x, y, &made[made_count].sample)) continue;
                }
                made[made_count++].pixel = p;
            }
        }
    }
    if (ok) { // grouped by pixel, order kept; each pixel with room for a sliver's one sample
        dp->begin = malloc((size_t)(pixels + 1) * sizeof *dp->begin);
        dp->samples = malloc((size_t)(made_count + pixels + 1) * sizeof *dp->samples);
        ok = dp->begin != NULL && dp->samples != NULL;
    }
    if (ok) {
        int next = 0;
        for (int p = 0; p < pixels; p++) {
            const int first = next;
            dp->begin[p] = first;
            if (!(exact[p] > 0.0)) continue;
            for (int i = 0; i < made_count; i++)
                if (made[i].pixel == p) dp->samples[next++] = made[i].sample;
            next = share_exact_area(disc, dp->x0 + p % dp->nx, dp->y0 + p / dp->nx, exact[p], dp->samples, first,
                                    next);
        }
        dp->begin[pixels] = next;
    }
    free(exact);
    free(made);
    return ok;
}

/* The samples of pixel (x, y)'s grid cells, their parts outside every disc. Returns their count. */
static int grid_samples(const highlight_disc *discs, int count, int x, int y, highlight_sample *out) {
    int n = 0;
    const double cell = 1.0 / HIGHLIGHT_GRID;
    for (int j = 0; j < HIGHLIGHT_GRID; j++)
        for (int i = 0; i < HIGHLIGHT_GRID; i++) {
            const double x0 = x + i * cell, y0 = y + j * cell;
            double inside = 0.0;
            for (int d = 0; d < count; d++)
                inside += mr_highlight_disc_rect_area(discs[d].cx, discs[d].cy, discs[d].radius, x0, y0, x0 + cell,
                                                   y0 + cell);
            const double outside = cell * cell - inside;
            if (!(outside > 1e-12)) continue;
            double sx = x0 + 0.5 * cell, sy = y0 + 0.5 * cell;
            if (inside > 0.0) { // the centroid of the probes outside every disc
                double px = 0.0, py = 0.0;
                int kept = 0;
                for (int b = 0; b < CELL_PROBES; b++)
                    for (int a = 0; a < CELL_PROBES; a++) {
                        const double qx = x0 + (a + 0.5) * cell / CELL_PROBES, qy = y0 + (b + 0.5) * cell / CELL_PROBES;
                        int in_disc = 0;
                        for (int d = 0; d < count && !in_disc; d++) {
                            double dx = qx - discs[d].cx, dy = qy - discs[d].cy;
                            in_disc = dx * dx + dy * dy < discs[d].radius * discs[d].radius;
                        }
                        if (in_disc) continue;
                        px += qx;
                        py += qy;
                        kept++;
                    }
                if (kept > 0) {
                    sx = px / kept;
                    sy = py / kept;
                } else { // a sliver no probe sees: the cell's corner farthest from the discs
                    double best = -1.0;
                    for (int c = 0; c < 4; c++) {
                        const double qx = x0 + (c & 1) * cell, qy = y0 + (c >> 1) * cell;
                        double nearest = INFINITY;
                        for (int d = 0; d < count; d++)
                            nearest = MR_MIN(nearest, hypot(qx - discs[d].cx, qy - discs[d].cy) - discs[d].radius);
                        if (nearest > best) {
                            best = nearest;
                            sx = qx;
                            sy = qy;
                        }
                    }
                }
            }
            out[n++] = (highlight_sample){sx, sy, outside};
        }
    return n;
}

int mr_highlight_pixel_samples(const highlight_disc *discs, int count, int x, int y, highlight_sample *out) {
    if (!mr_highlight_touches(discs, count, x, y)) return -1;
    int n = grid_samples(discs, count, x, y, out);
    for (int d = 0; d < count; d++) n = disc_samples(&discs[d], x, y, out, n);
    return n;
}

void mr_highlight_quadrature_free(highlight_quadrature *q) {
    for (int d = 0; d < q->count; d++) {
        free(q->pixels[d].begin);
        free(q->pixels[d].samples);
    }
    memset(q, 0, sizeof *q);
}

int mr_highlight_quadrature_build(const highlight_disc *discs, int count, highlight_quadrature *q) {
    memset(q, 0, sizeof *q);
    q->count = MR_MIN(MR_MAX(count, 0), HIGHLIGHT_MAX_DISCS);
    for (int d = 0; d < q->count; d++) {
        const highlight_disc *disc = &discs[d];
        highlight_disc_pixels *dp = &q->pixels[d];
        q->discs[d] = *disc;
        // The window: every pixel the disc's bounding square meets (a disc anywhere else meets no pixel).
        const double span = 2.0 * disc->radius + 2.0;
        if (isfinite(disc->cx) && isfinite(disc->cy) && disc->radius > 0.0 && span < 1e4 &&
            fabs(disc->cx) < 1e9 && fabs(disc->cy) < 1e9) {
            dp->x0 = (int)floor(disc->cx - disc->radius);
            dp->y0 = (int)floor(disc->cy - disc->radius);
            dp->nx = (int)floor(disc->cx + disc->radius) - dp->x0 + 1;
            dp->ny = (int)floor(disc->cy + disc->radius) - dp->y0 + 1;
        }
        if (!build_disc_pixels(disc, dp)) {
            mr_highlight_quadrature_free(q);
            return 0;
        }
    }
    return 1;
}

int mr_highlight_quadrature_pixel(const highlight_quadrature *q, int x, int y, highlight_sample *out) {
    if (!mr_highlight_touches(q->discs, q->count, x, y)) return -1;
    int n = grid_samples(q->discs, q->count, x, y, out);
    for (int d = 0; d < q->count; d++) {
        const highlight_disc_pixels *dp = &q->pixels[d];
        const int i = x - dp->x0, j = y - dp->y0;
        if (i < 0 || i >= dp->nx || j < 0 || j >= dp->ny) continue;
        const int p = j * dp->nx + i;
        for (int k = dp->begin[p]; k < dp->begin[p + 1]; k++) out[n++] = dp->samples[k];
    }
    return n;
}
