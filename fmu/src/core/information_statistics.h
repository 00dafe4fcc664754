/* The arithmetic of an identifier's statistics from its information matrix P
 * (row-major with a row stride): sandwich variances of the standard errors and
 * the inverse iteration for P's smallest eigenvalue, the excitation.  Shared by
 * the regressor identifier's full solve (ri_statistics) and the statistics job
 * that spreads the same solve over internal steps, so both give the same
 * numbers.  Header-only, plain C. */
#ifndef INFORMATION_STATISTICS_H
#define INFORMATION_STATISTICS_H

#include "tuning.h"

#include <math.h>

#include "cholesky.h"

/* The sandwich variance g^T S g, S from its upper triangle. */
static inline double stats_sandwich(const double *S, int p, int stride, const double g[])
{
    double variance = 0.0;
    for (int j = 0; j < p; ++j) {
        const double *S_j = S + j * stride;
        double row = S_j[j] * g[j];
        for (int i = j + 1; i < p; ++i) row += 2.0 * S_j[i] * g[i];
        variance += g[j] * row;
    }
    return variance;
}

/* One inverse iteration with the Cholesky factor L of P: v <- P^-1 v, then v
 * normalized; returns the norm of P^-1 v (-> 1 / the smallest eigenvalue). */
static inline double stats_inverse_iteration(const double *L, int p, int stride, double v[])
{
    cholesky_solve(L, p, stride, v);
    double norm = 0.0;
    for (int k = 0; k < p; ++k) norm += v[k] * v[k];
    norm = sqrt(norm);
    for (int k = 0; k < p; ++k) v[k] /= norm;
    return norm;
}

/* The iteration has converged: the norm changed by at most STATS_EIGEN_TOLERANCE. */
static inline int stats_eigen_converged(double norm, double previous)
{
    return previous > 0.0 && !(fabs(norm - previous) > STATS_EIGEN_TOLERANCE * norm);
}

/* [s] The time the information remembers: active_time for least squares, less
 * with forgetting (lambda per sample of h). */
static inline double stats_memory(double lambda, double h, double active_time)
{
    const double rate = lambda < 1.0 ? -log(lambda) / h : 0.0;
    return rate > 0.0 ? -expm1(-rate * active_time) / rate : active_time;
}

/* The excitation from the inverse iteration's norm: the smallest eigenvalue of
 * the information beyond rho, per unit of remembered time (0 if none). */
static inline double stats_excitation(double norm, double rho, double lambda, double h,
                                      double active_time)
{
    const double memory = stats_memory(lambda, h, active_time);
    const double excitation = memory > 0.0 ? (1.0 / norm - rho) / memory : 0.0;
    return excitation > 0.0 ? excitation : 0.0;
}

/* A parameter's column excitation from the diagonal entries P_kk and Gamma_kk
 * = (P^-1)_kk of an information P = A + rho I: 1 / Gamma_kk - rho is what of
 * the column's energy A_kk the other columns leave unexplained (with the ridge),
 * so the result is sqrt(1 - R_k^2), the figure identify reports.  0 for a
 * column whose energy is lost in the ridge's rounding. */
static inline double stats_column_excitation(double P_kk, double Gamma_kk, double rho)
{
    const double energy = P_kk - rho;
    if (!(energy > 1e-9 * P_kk) || !(Gamma_kk > 0.0)) return 0.0;
    const double share = (1.0 / Gamma_kk - rho) / energy;
    return share > 0.0 ? sqrt(share < 1.0 ? share : 1.0) : 0.0;
}

#endif
