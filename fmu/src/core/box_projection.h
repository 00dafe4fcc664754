/* An estimate brought inside the ranges a model declares for its unknowns:
 *     x = argmin (x - x_hat)^T P (x - x_hat)   subject to lower <= x <= upper,
 * P the identifier's information (symmetric positive definite).  For least
 * squares with normal matrix P this is the least squares inside the box, the
 * answer identify computes offline (harness/model/fit.py, scipy's bounded
 * least squares); the estimate's correlations move the free unknowns when one
 * is held at a bound, which clipping each unknown alone would not.
 * Primal active set: the unknown furthest outside its range (in standard
 * deviations of P's diagonal) is held at that end, the others solved with it
 * fixed, until all lie inside; then a held unknown whose multiplier says the
 * objective falls by moving it inside is released.  At most BP_MAX_ROUNDS
 * rounds (cycling needs a degenerate P); if they run out, the unknowns are
 * clipped to their ranges and the call says so.
 * Plain C, no allocation (a p x p factor on the stack), no I/O. */
#ifndef BOX_PROJECTION_H
#define BOX_PROJECTION_H

#define BP_MAX_UNKNOWNS 32

typedef enum {
    BP_INSIDE = 0,   /* x_hat was inside: x = x_hat */
    BP_PROJECTED = 1, /* some unknowns held at an end (held[k] = -1 lower, 1 upper) */
    BP_CLIPPED = 2,  /* the rounds ran out or P could not be factored: clipped */
} BpResult;

/* p <= BP_MAX_UNKNOWNS unknowns; P row-major with `stride`, upper triangle
 * read (P[j][i], i >= j); lower[k] < upper[k] (either may be infinite);
 * x: x_hat in, the projection out; held: per unknown -1, 0 or 1. */
BpResult bp_project(int p, const double *P, int stride, const double lower[],
                    const double upper[], double x[], int held[]);

#endif
