/* The least squares inside a box (box_projection.h). */
#include "box_projection.h"

#include <math.h>
#include <string.h>

#include "cholesky.h"

#define BP_MAX_ROUNDS (3 * BP_MAX_UNKNOWNS + 3)

/* P's (symmetric) entry i, j from its upper triangle. */
static double entry(const double *P, int stride, int i, int j)
{
    return i <= j ? P[i * stride + j] : P[j * stride + i];
}

/* The free unknowns solved with the held ones at their ends:
 *     P_FF (x_F - x_hat_F) = -P_FA (x_A - x_hat_A).
 * Returns -1 if P_FF cannot be factored. */
static int solve_free(int p, const double *P, int stride, const double x_hat[],
                      const double lower[], const double upper[], const int held[], double x[])
{
    int free_index[BP_MAX_UNKNOWNS], f = 0;
    double shift[BP_MAX_UNKNOWNS];
    for (int k = 0; k < p; ++k) {
        if (held[k]) x[k] = held[k] < 0 ? lower[k] : upper[k];
        else free_index[f++] = k;
        shift[k] = x[k] - x_hat[k];
    }
    if (f == 0) return 0;
    double A[BP_MAX_UNKNOWNS][BP_MAX_UNKNOWNS], rhs[BP_MAX_UNKNOWNS];
    for (int a = 0; a < f; ++a) {
        const int i = free_index[a];
        for (int b = a; b < f; ++b) A[a][b] = entry(P, stride, i, free_index[b]);
        rhs[a] = 0.0;
        for (int k = 0; k < p; ++k)
            if (held[k]) rhs[a] -= entry(P, stride, i, k) * shift[k];
    }
    if (cholesky_factor(&A[0][0], &A[0][0], f, BP_MAX_UNKNOWNS)) return -1;
    cholesky_solve(&A[0][0], f, BP_MAX_UNKNOWNS, rhs);
    for (int a = 0; a < f; ++a) x[free_index[a]] = x_hat[free_index[a]] + rhs[a];
    return 0;
}

static BpResult clipped(int p, const double lower[], const double upper[], double x[],
                        int held[])
{
    for (int k = 0; k < p; ++k) {
        held[k] = x[k] < lower[k] ? -1 : x[k] > upper[k] ? 1 : 0;
        x[k] = fmin(fmax(x[k], lower[k]), upper[k]);
    }
    return BP_CLIPPED;
}

BpResult bp_project(int p, const double *P, int stride, const double lower[],
                    const double upper[], double x[], int held[])
{
    memset(held, 0, (size_t)p * sizeof held[0]);
    int inside = 1;
    for (int k = 0; k < p; ++k) inside &= lower[k] <= x[k] && x[k] <= upper[k];
    if (inside) return BP_INSIDE;
    double x_hat[BP_MAX_UNKNOWNS];
    memcpy(x_hat, x, (size_t)p * sizeof x[0]);
    double tolerance = 0.0;
    for (int round = 0; round < BP_MAX_ROUNDS; ++round) {
        /* the free unknown furthest outside, in units of 1 / sqrt(P_kk) */
        int worst = -1;
        double furthest = 0.0;
        for (int k = 0; k < p; ++k) {
            if (held[k]) continue;
            const double out = fmax(lower[k] - x[k], x[k] - upper[k]) *
                               sqrt(entry(P, stride, k, k));
            if (out > furthest) furthest = out, worst = k;
        }
        if (round == 0) tolerance = 1e-9 * furthest;
        if (worst < 0) {
            /* all inside: release a held unknown whose gradient points inside */
            int release = -1;
            double strongest = tolerance; /* rounding must not release and hold again */
            for (int k = 0; k < p; ++k) {
                if (!held[k]) continue;
                double gradient = 0.0; /* of (x - x_hat)' P (x - x_hat) / 2 */
                for (int j = 0; j < p; ++j) gradient += entry(P, stride, k, j) * (x[j] - x_hat[j]);
                const double pull = held[k] * gradient / sqrt(entry(P, stride, k, k));
                if (pull > strongest) strongest = pull, release = k;
            }
            if (release < 0) return BP_PROJECTED;
            held[release] = 0;
        } else {
            held[worst] = x[worst] < lower[worst] ? -1 : 1;
        }
        memcpy(x, x_hat, (size_t)p * sizeof x[0]);
        if (solve_free(p, P, stride, x_hat, lower, upper, held, x)) {
            memcpy(x, x_hat, (size_t)p * sizeof x[0]);
            return clipped(p, lower, upper, x, held);
        }
    }
    return clipped(p, lower, upper, x, held);
}
