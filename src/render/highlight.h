/*
 * highlight.h — sub-pixel quadrature of the pixels around a point light's highlight (internal to the renderer;
 * render.h, mr_scene.highlight_samples, and docs/rendering.md "Narrow highlights" describe what it is for).
 *
 * A highlight is a disc in image space, centred where the light's mirror reflection is seen. Lobes of any width,
 * from far below a pixel to the disc's size, are integrated over the disc by rings whose radii grow
 * geometrically from HIGHLIGHT_INNER (a peaked function of width w, weighted by the ring's area r dr = r^2
 * d(ln r), is a bump of fixed shape in ln r whatever w is, so equal steps in ln r integrate every width alike),
 * then in steps of at most HIGHLIGHT_SPACING, and the rest of each pixel the disc touches by a regular grid of
 * cells. The samples of a pixel carry weights
 * that add up to the pixel's area (1) exactly: the disc's part of the pixel and each cell's part outside the
 * disc are computed in closed form.
 */
#ifndef MR_RENDER_HIGHLIGHT_H
#define MR_RENDER_HIGHLIGHT_H

#define HIGHLIGHT_RADIUS 1.5      /* pixels: the disc's radius. Measured: a disc of 1 pixel left more of GGX's
                                     convex tails to pixel centres, which underestimate them (-3 % of the light at
                                     alpha 0.02, frontal light, 64^2); 1.5 and 2 agree within 1 % */
#define HIGHLIGHT_INNER 1e-4      /* pixels: the innermost ring (the models' narrowest lobe, alpha 1e-4, seen on
                                     the fit sphere at 16^2 still spans 7e-4 px) */
#define HIGHLIGHT_RING_RATIO 1.5  /* outer over inner radius of a ring */
#define HIGHLIGHT_ANGLES 8        /* sectors per ring, at least */
#define HIGHLIGHT_SPACING 0.25    /* pixels: the longest ring thickness and sector arc (smooth shading's error
                                     grows with the square of a sample's extent) */
#define HIGHLIGHT_GRID 4          /* the pixel's cells per side outside the disc */
#define HIGHLIGHT_MAX_DISCS 8     /* one per point light (MR_SCENE_MAX_LIGHTS) */

typedef struct highlight_disc {
    double cx, cy; /* image position, pixels from the top-left corner */
    double radius;
} highlight_disc;

/* One sub-pixel sample: an image position and the share of its pixel it stands for. */
typedef struct highlight_sample {
    double x, y;
    double weight;
} highlight_sample;

/* Does the pixel (x, y) (the square [x, x + 1] x [y, y + 1]) meet any of the discs? */
int mr_highlight_touches(const highlight_disc *discs, int count, int x, int y);

/* The samples of pixel (x, y): the ring sectors of every disc that fall in it and the grid cells' parts outside
 * all discs, weights adding up to 1. Discs must not overlap each other. Returns the number written to `out`
 * (at most mr_highlight_max_samples()), or -1 if the pixel meets no disc. */
int mr_highlight_pixel_samples(const highlight_disc *discs, int count, int x, int y, highlight_sample *out);

/* An upper bound of mr_highlight_pixel_samples' count for `count` discs. */
int mr_highlight_max_samples(int count);

/* One disc's samples for every pixel of its window, the pixels its bounding square meets. */
typedef struct highlight_disc_pixels {
    int x0, y0, nx, ny;        /* the window: pixels x0 .. x0 + nx - 1, y0 .. y0 + ny - 1 */
    int *begin;                /* [nx ny + 1]: pixel (x0 + i, y0 + j)'s samples: samples[begin[j nx + i] .. next - 1] */
    highlight_sample *samples;
} highlight_disc_pixels;

/* The discs' samples of every pixel, made once for a render plan: mr_highlight_quadrature_pixel gives what
 * mr_highlight_pixel_samples gives, bit for bit, but each ring sector is placed (and cut up where it straddles
 * pixels) once instead of once for every pixel the disc meets (that was a third of a 64^2 plan's cost). Read-only
 * once built: the plan's rows share it. */
typedef struct highlight_quadrature {
    highlight_disc discs[HIGHLIGHT_MAX_DISCS];
    int count;
    highlight_disc_pixels pixels[HIGHLIGHT_MAX_DISCS];
} highlight_quadrature;

/* Make the quadrature of `count` (at most HIGHLIGHT_MAX_DISCS) discs that do not overlap each other. Returns 1,
 * or 0 on allocation failure (then *q holds nothing to free). */
int mr_highlight_quadrature_build(const highlight_disc *discs, int count, highlight_quadrature *q);

/* mr_highlight_pixel_samples of the quadrature's discs. */
int mr_highlight_quadrature_pixel(const highlight_quadrature *q, int x, int y, highlight_sample *out);

void mr_highlight_quadrature_free(highlight_quadrature *q);

/* The area of the disc (cx, cy, r) inside the rectangle [x0, x1] x [y0, y1], in closed form. */
double mr_highlight_disc_rect_area(double cx, double cy, double r, double x0, double y0, double x1, double y1);

#endif /* MR_RENDER_HIGHLIGHT_H */
