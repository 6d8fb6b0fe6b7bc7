/*
 * gen-ggx-albedo.c — writes src/brdf/ggx_albedo_tables.h, the directional-albedo tables of single-scattering GGX
 * that src/brdf/layering.c interpolates for the layered models (openpbr.c, blender_principled.c,
 * standard_surface.c: albedo scaling f = f_top + (1 - E_top(mu)) f_below).
 *
 *   make tables                       (builds this file, runs it, replaces the header atomically)
 *   cc -O2 -std=c11 -Isrc scripts/gen-ggx-albedo.c -lm -o gen && ./gen > src/brdf/ggx_albedo_tables.h
 *   cc -O2 -std=c11 -Isrc -DGEN_CHECK scripts/gen-ggx-albedo.c -lm -o check && ./check
 *       (the committed header against a fresh computation of a sample of its entries; tests/ggx_albedo_table.sh)
 *
 * C rather than numpy: each entry is computed by the library's own lobe, mr_ggx_dv_correlated and
 * mr_fresnel_dielectric of brdf_internal.h, the very functions the models evaluate, so table and models cannot
 * disagree about the integrand; and it needs nothing but the C compiler the build already needs.
 *
 * Each entry is E(mu) = integral of D V F cos(theta_o) d omega_o over the upper hemisphere (F = the exact
 * dielectric Fresnel at wi.h for index eta, or F = 1 for the white table), by a midpoint rule on the half vector
 * (d omega_o = 4 (wi.h) d omega_h): rings logarithmic in tan(theta_h) from e^-16 to e^6 (one grid resolves alpha
 * 1e-4 .. 1), 1200 rings x 96 sectors on the half azimuth [0, pi] (the lobe is symmetric about the plane of
 * incidence).
 *
 * Grid (node j of n, t = j/(n - 1)); every axis is quadratic in t, so nodes crowd where E bends:
 *   mu  = t^2               41 nodes  (grazing incidence; node 0 taken at mu = 1e-4)
 *   r   = 0.01 + 0.99 t^2   33 nodes  (smooth lobes; alpha = r^2)
 *   eta = 1 + 2 t^2         25 nodes  (ior near 1, where F has a sharp knee near grazing, cos ~ sqrt(eta^2 - 1))
 * The white table (F = 1) has 65 roughness nodes on the same axis (41 x 65 floats, 10 KB): Turquin's factor
 * 1 + F0 (1 - E_1)/E_1 (openpbr) and Multiscatter GGX (blender-principled) divide by E_1, so its error shows
 * undamped in a white metal's furnace (25 nodes: 0.0023 at roughness 0.6, normal incidence; 65: ~0.0003).
 * layering.c interpolates linearly in t on each axis. This is the grid of the former standard-surface table
 * (quadratic axes, mu node 0 at 1e-4: half the error of the former uniform-in-r table beyond 88 degrees) with 33
 * instead of 17 roughness nodes: roughness is the axis that dominates the error at mid roughness up to 88 degrees
 * (17 nodes: 0.0026 up to 80 degrees at random points, against the uniform 32-node table's 0.0016; 25 nodes left
 * 0.0012 at a coat of roughness 0.2, ior 1.6, 80 degrees, where 33 leave 1e-4). Written with 6 significant
 * digits into float arrays (rounding <= 5e-7, well under the interpolation error; 345 KB of source, 146 KB of
 * data). On stderr and in the header: the largest difference between that interpolation and direct quadrature at
 * cell centres.
 */
#include <stdio.h>
#include <string.h>

#include "brdf/brdf_internal.h"

#define N_MU 41
#define N_R 33
#define N_R1 65 /* the white table's roughness nodes */
#define N_ETA 25
#define MU_NODE0 1e-4
#define RINGS 1200
#define SECTORS 96

static double node_mu(int i) {
    double t = (double)i / (N_MU - 1);
    return i ? t * t : MU_NODE0;
}
static double node_r(int j, int n) {
    double t = (double)j / (n - 1);
    return 0.01 + 0.99 * t * t;
}
static double node_eta(int k) {
    double t = (double)k / (N_ETA - 1);
    return 1.0 + 2.0 * t * t;
}

/* eta <= 0: F = 1; eta = 1: no reflection (0). */
static double albedo(double mu, double r, double eta) {
    if (eta == 1.0) return 0.0;
    double alpha = r * r;
    double wi[3] = {sqrt(1.0 - mu * mu), 0.0, mu};
    double lo = -16.0, hi = 6.0, ds = (hi - lo) / RINGS, dphi = MR_PI / SECTORS, sum = 0.0;
    for (int i = 0; i < RINGS; i++) {
        double t = exp(lo + (i + 0.5) * ds);
        double cos_h = 1.0 / sqrt(1.0 + t * t), sin_h = t * cos_h, jac = t * t * cos_h * cos_h * cos_h;
        for (int j = 0; j < SECTORS; j++) {
            double phi = (j + 0.5) * dphi;
            double h[3] = {sin_h * cos(phi), sin_h * sin(phi), cos_h};
            double dot = wi[0] * h[0] + wi[2] * h[2];
            if (dot <= 0.0) continue;
            double wo[3] = {2.0 * dot * h[0] - wi[0], 2.0 * dot * h[1], 2.0 * dot * h[2] - wi[2]};
            if (wo[2] <= 0.0) continue;
            mr_brdf_geom g;
            if (!mr_brdf_geom_init(wi, wo, &g)) continue;
            double F = eta > 0.0 ? mr_fresnel_dielectric(g.dot_h, eta, NULL) : 1.0;
            sum += F * mr_ggx_dv_correlated(alpha, &g, NULL) * wo[2] * 4.0 * dot * jac;
        }
    }
    return 2.0 * sum * ds * dphi;
}

#ifndef GEN_CHECK
static float tab_d[N_ETA][N_R][N_MU], tab_1[N_R1][N_MU];

static double lerp(double a, double b, double t) { return a + (b - a) * t; }

/* Node index and fraction of t in [0, 1] on n nodes (as layering.c). */
static int cell(double t, int n, double *frac) {
    double x = t * (n - 1);
    int i = (int)x;
    if (i > n - 2) i = n - 2;
    *frac = x - i;
    return i;
}

static double interp(double mu, double r, double eta) {
    double a, b, c;
    int it = cell(sqrt(mu), N_MU, &a), ir = cell(sqrt((r - 0.01) / 0.99), N_R, &b);
    int ie = cell(sqrt((eta - 1.0) / 2.0), N_ETA, &c);
    double v[2];
    for (int e = 0; e < 2; e++)
        v[e] = lerp(lerp(tab_d[ie + e][ir][it], tab_d[ie + e][ir][it + 1], a),
                    lerp(tab_d[ie + e][ir + 1][it], tab_d[ie + e][ir + 1][it + 1], a), b);
    return lerp(v[0], v[1], c);
}

static double interp_one(double mu, double r) {
    double a, b;
    int it = cell(sqrt(mu), N_MU, &a), ir = cell(sqrt((r - 0.01) / 0.99), N_R1, &b);
    return lerp(lerp(tab_1[ir][it], tab_1[ir][it + 1], a), lerp(tab_1[ir + 1][it], tab_1[ir + 1][it + 1], a), b);
}

static void print_row(const float *row, int n, const char *indent) {
    printf("%s{", indent);
    for (int i = 0; i < n; i++) printf("%s%.6g", i ? (i % 9 ? "," : ",\n ") : "", row[i]);
    printf("},\n");
}

int main(void) {
    for (int i = 0; i < N_MU; i++) {
        for (int j = 0; j < N_R1; j++) tab_1[j][i] = (float)albedo(node_mu(i), node_r(j, N_R1), -1.0);
        for (int j = 0; j < N_R; j++)
            for (int k = 0; k < N_ETA; k++) tab_d[k][j][i] = (float)albedo(node_mu(i), node_r(j, N_R), node_eta(k));
    }
    /* Cell centres: every mu cell, every other r and eta cell. Bands: [0] up to 80 degrees, [1] up to 88, [2] all;
     * row 0 over eta 1-3, row 1 over eta >= 1.05 (where the models' indices live). */
    double worst[2][3] = {{0}}, mu80 = cos(80.0 * MR_PI / 180.0), mu88 = cos(88.0 * MR_PI / 180.0);
    for (int k = 0; k + 1 < N_ETA; k += 2)
        for (int j = 0; j + 1 < N_R; j += 2)
            for (int i = 0; i + 1 < N_MU; i++) {
                double t = (i + 0.5) / (N_MU - 1), s = (j + 0.5) / (N_R - 1), u = (k + 0.5) / (N_ETA - 1);
                double mu = t * t, r = 0.01 + 0.99 * s * s, eta = 1.0 + 2.0 * u * u;
                double err = fabs(interp(mu, r, eta) - albedo(mu, r, eta));
                for (int row = 0; row < 2; row++) {
                    if (row == 1 && eta < 1.05) continue;
                    worst[row][2] = fmax(worst[row][2], err);
                    if (mu >= mu88) worst[row][1] = fmax(worst[row][1], err);
                    if (mu >= mu80) worst[row][0] = fmax(worst[row][0], err);
                }
            }
    double worst_1[3] = {0}; /* the white table, every cell */
    for (int j = 0; j + 1 < N_R1; j++)
        for (int i = 0; i + 1 < N_MU; i++) {
            double t = (i + 0.5) / (N_MU - 1), s = (j + 0.5) / (N_R1 - 1), mu = t * t, r = 0.01 + 0.99 * s * s;
            double err = fabs(interp_one(mu, r) - albedo(mu, r, -1.0));
            worst_1[2] = fmax(worst_1[2], err);
            if (mu >= mu88) worst_1[1] = fmax(worst_1[1], err);
            if (mu >= mu80) worst_1[0] = fmax(worst_1[0], err);
        }
    char summary[600];
    snprintf(summary, sizeof summary,
             " * Largest trilinear interpolation error at cell centres (every mu cell, every other r and eta cell):\n"
             " *   ior 1.05-3: %.2g up to 80 degrees, %.2g up to 88, %.2g beyond;\n"
             " *   ior 1-3:    %.2g up to 80 degrees, %.2g up to 88, %.2g beyond (ior near 1: Fresnel's knee);\n"
             " *   F = 1 (every cell): %.2g up to 80 degrees, %.2g up to 88, %.2g beyond.\n",
             worst[1][0], worst[1][1], worst[1][2], worst[0][0], worst[0][1], worst[0][2], worst_1[0], worst_1[1],
             worst_1[2]);
    fputs(summary, stderr);
    printf("/* ggx_albedo_tables.h — GENERATED by scripts/gen-ggx-albedo.c (make tables; see there); do not edit.\n"
           " * Directional albedo of single-scattering GGX (height-correlated Smith), with the exact dielectric\n"
           " * Fresnel (mr_ggx_alb_dielectric[eta][r][mu]) and with F = 1 (mr_ggx_alb_one[r][mu]); nodes quadratic\n"
           " * in t = j/(n - 1): mu = t^2 (node 0 at %g), r = 0.01 + 0.99 t^2, eta = 1 + 2 t^2.\n%s */\n",
           MU_NODE0, summary);
    printf("#define MR_GGX_ALB_N_MU %d\n#define MR_GGX_ALB_N_R %d\n#define MR_GGX_ALB_N_ETA %d\n"
           "#define MR_GGX_ALB_ONE_N_R %d\n\n", N_MU, N_R, N_ETA, N_R1);
    printf("static const float mr_ggx_alb_dielectric[%d][%d][%d] = {\n", N_ETA, N_R, N_MU);
    for (int k = 0; k < N_ETA; k++) {
        printf("{\n");
        for (int j = 0; j < N_R; j++) print_row(tab_d[k][j], N_MU, "");
        printf("},\n");
    }
    printf("};\n\nstatic const float mr_ggx_alb_one[%d][%d] = {\n", N_R1, N_MU);
    for (int j = 0; j < N_R1; j++) print_row(tab_1[j], N_MU, "");
    printf("};\n");
    return 0;
}
#else
#include "brdf/ggx_albedo_tables.h"

_Static_assert(MR_GGX_ALB_N_MU == N_MU && MR_GGX_ALB_N_R == N_R && MR_GGX_ALB_N_ETA == N_ETA &&
                   MR_GGX_ALB_ONE_N_R == N_R1,
               "the committed table's grid is not the generator's: run make tables");

/* A sample of entries (every 29th of the dielectric table, every 7th of the white one: primes, so the sample
 * walks through all mu, r and eta nodes) against a fresh quadrature. The only expected difference is the 6-digit
 * rounding (<= 5e-7) and the compiler's (2e-6 allows both). Prints one line per failure and a summary; exit status 1 if
 * any entry differs. */
int main(void) {
    int checked = 0, bad = 0;
    double worst = 0.0;
    for (int n = 0; n < N_ETA * N_R * N_MU + N_R1 * N_MU; n += n < N_ETA * N_R * N_MU ? 29 : 7) {
        int white = n >= N_ETA * N_R * N_MU, m = white ? n - N_ETA * N_R * N_MU : n;
        int i = m % N_MU, j = (m / N_MU) % (white ? N_R1 : N_R), k = white ? 0 : m / (N_MU * N_R);
        double stored = white ? mr_ggx_alb_one[j][i] : mr_ggx_alb_dielectric[k][j][i];
        double fresh = albedo(node_mu(i), node_r(j, white ? N_R1 : N_R), white ? -1.0 : node_eta(k));
        double err = fabs(stored - fresh);
        worst = fmax(worst, err);
        checked++;
        if (err > 2e-6 && bad++ < 5)
            printf("FAIL  %s entry (eta node %d, r node %d, mu node %d): stored %.9g, computed %.9g\n",
                   white ? "mr_ggx_alb_one" : "mr_ggx_alb_dielectric", white ? -1 : k, j, i, stored, fresh);
    }
    printf("%s %d of %d sampled entries of src/brdf/ggx_albedo_tables.h match a fresh quadrature (largest "
           "difference %.2g)\n", bad ? "FAIL " : "ok   ", checked - bad, checked, worst);
    return bad ? 1 : 0;
}
#endif
