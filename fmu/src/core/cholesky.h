/* Cholesky factorization and solve of a small symmetric positive definite
 * matrix stored row-major with a row stride (the identifiers' P, the robot's
 * mass matrix M: each a fixed-size 2-D array of its own size). */
#ifndef CHOLESKY_H
#define CHOLESKY_H

#include <math.h>

/* P = L L^T from P's upper triangle (P[j][i], i >= j) into L's lower triangle,
 * column j by column j (cholesky_factor_column: column j of L from columns
 * 0..j-1, so that the factorization can be spread over calls, in the same
 * arithmetic).  L may be P itself: an entry of the upper triangle is read before
 * the same column's lower entries are written.  Returns 0, or -1 if P is not
 * positive definite (or overflows). */
static inline int cholesky_factor_column(const double *P, double *L, int n, int stride, int j)
{
    double d = P[j * stride + j];
    for (int k = 0; k < j; ++k) d -= L[j * stride + k] * L[j * stride + k];
    if (!(d > 0.0) || !isfinite(d)) return -1;
    L[j * stride + j] = sqrt(d);
    for (int i = j + 1; i < n; ++i) {
        double s = P[j * stride + i]; /* P[i][j] of the symmetric matrix */
        for (int k = 0; k < j; ++k) s -= L[i * stride + k] * L[j * stride + k];
        L[i * stride + j] = s / L[j * stride + j];
    }
    return 0;
}

/* cholesky_factor_column for j = 0..n-1. */
static inline int cholesky_factor(const double *P, double *L, int n, int stride)
{
    for (int j = 0; j < n; ++j)
        if (cholesky_factor_column(P, L, n, stride, j) != 0) return -1;
    return 0;
}

/* x <- L^-1 x and x <- L^-T x with the factor L of cholesky_factor. */
static inline void cholesky_forward(const double *L, int n, int stride, double x[])
{
    for (int i = 0; i < n; ++i) {
        for (int k = 0; k < i; ++k) x[i] -= L[i * stride + k] * x[k];
        x[i] /= L[i * stride + i];
    }
}

static inline void cholesky_backward(const double *L, int n, int stride, double x[])
{
    for (int i = n - 1; i >= 0; --i) {
        for (int k = i + 1; k < n; ++k) x[i] -= L[k * stride + i] * x[k];
        x[i] /= L[i * stride + i];
    }
}

/* x <- P^-1 x with the factor L of cholesky_factor. */
static inline void cholesky_solve(const double *L, int n, int stride, double x[])
{
    cholesky_forward(L, n, stride, x);
    cholesky_backward(L, n, stride, x);
}

#endif
