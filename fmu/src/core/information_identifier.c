#include "information_identifier.h"

#include <math.h>
#include <string.h>

void info_init(InformationIdentifier *id, IdentifierKind kind, int rows, int m, double h,
               double rho, double R)
{
    memset(id, 0, sizeof *id);
    id->rows = rows;
    id->m = m;
    id->h = h;
    id->rho = rho;
    id->lambda = kind == IDENTIFIER_MFF ? pow(R, h) : 1.0;
    id->one_minus_lambda_rho = (1.0 - id->lambda) * rho;
    info_reset(id);
}

void info_reset(InformationIdentifier *id)
{
    memset(id->P, 0, sizeof id->P);
    memset(id->theta, 0, sizeof id->theta);
    memset(id->delta, 0, sizeof id->delta);
    for (int k = 0; k < id->m; ++k) {
        id->P[k][k] = id->rho;
        id->eigvec[k] = 1.0 / sqrt((double)id->m);
    }
    id->active_time = 0.0;
    id->gamma_trace = id->m / id->rho;
    id->excitation = 0.0;
}

void info_step(InformationIdentifier *id, const double z[], const double phi[])
{
    const int m = id->m;
    const double h = id->h, lambda = id->lambda, pull = id->one_minus_lambda_rho;
    if (lambda == 1.0) { /* LSM: plain accumulation */
        for (int j = 0; j < m; ++j) {
            const double hj = h * phi[j];
            for (int k = j; k < m; ++k) id->P[j][k] += hj * phi[k];
        }
        for (int i = 0; i < id->rows; ++i) {
            const double hz = h * z[i];
            for (int k = 0; k < m; ++k) id->theta[i][k] += hz * phi[k];
        }
    } else { /* MFF: forget toward rho I and toward the current estimate */
        for (int j = 0; j < m; ++j) {
            const double hj = h * phi[j];
            for (int k = j; k < m; ++k) id->P[j][k] = lambda * id->P[j][k] + hj * phi[k];
            id->P[j][j] += pull;
        }
        for (int i = 0; i < id->rows; ++i) {
            const double hz = h * z[i];
            for (int k = 0; k < m; ++k)
                id->theta[i][k] = lambda * id->theta[i][k] + pull * id->delta[i][k] + hz * phi[k];
        }
    }
    id->active_time += h;
}

/* Cholesky P = L L^T from the upper triangle; returns -1 if not positive definite. */
static int cholesky(const InformationIdentifier *id, double L[ID_MAX_REGRESSORS][ID_MAX_REGRESSORS])
{
    const int m = id->m;
    for (int j = 0; j < m; ++j) {
        double d = id->P[j][j];
        for (int k = 0; k < j; ++k) d -= L[j][k] * L[j][k];
        if (!(d > 0.0)) return -1;
        L[j][j] = sqrt(d);
        for (int i = j + 1; i < m; ++i) {
            double s = id->P[j][i]; /* P[i][j] of the symmetric matrix */
            for (int k = 0; k < j; ++k) s -= L[i][k] * L[j][k];
            L[i][j] = s / L[j][j];
        }
    }
    return 0;
}

/* Solves L L^T x = b in place. */
static void cholesky_solve(int m, double L[ID_MAX_REGRESSORS][ID_MAX_REGRESSORS], double x[])
{
    for (int i = 0; i < m; ++i) {
        for (int k = 0; k < i; ++k) x[i] -= L[i][k] * x[k];
        x[i] /= L[i][i];
    }
    for (int i = m - 1; i >= 0; --i) {
        for (int k = i + 1; k < m; ++k) x[i] -= L[k][i] * x[k];
        x[i] /= L[i][i];
    }
}

int info_solve(InformationIdentifier *id)
{
    const int m = id->m;
    double L[ID_MAX_REGRESSORS][ID_MAX_REGRESSORS];
    if (m == 0) return 0;
    if (cholesky(id, L) != 0) return -1;
    for (int i = 0; i < id->rows; ++i) {
        double x[ID_MAX_REGRESSORS];
        memcpy(x, id->theta[i], sizeof x);
        cholesky_solve(m, L, x);
        memcpy(id->delta[i], x, sizeof x);
    }
    /* trace(P^-1) = sum of squared entries of L^-1 */
    double trace = 0.0;
    for (int j = 0; j < m; ++j) {
        double col[ID_MAX_REGRESSORS] = {0};
        col[j] = 1.0;
        for (int i = j; i < m; ++i) { /* forward substitution for column j of L^-1 */
            double s = col[i];
            for (int k = j; k < i; ++k) s -= L[i][k] * col[k];
            col[i] = s / L[i][i];
            trace += col[i] * col[i];
        }
    }
    id->gamma_trace = trace;
    /* One inverse-iteration step toward the eigenvector of the smallest
     * eigenvalue of P; the Rayleigh quotient estimates that eigenvalue. */
    double v[ID_MAX_REGRESSORS];
    memcpy(v, id->eigvec, sizeof v);
    cholesky_solve(m, L, v);
    double norm = 0.0;
    for (int k = 0; k < m; ++k) norm += v[k] * v[k];
    norm = sqrt(norm);
    if (norm > 0.0 && isfinite(norm)) {
        for (int k = 0; k < m; ++k) id->eigvec[k] = v[k] / norm;
    }
    double rayleigh = 0.0;
    for (int j = 0; j < m; ++j) {
        double pv = 0.0;
        for (int k = 0; k < m; ++k) pv += (k >= j ? id->P[j][k] : id->P[k][j]) * id->eigvec[k];
        rayleigh += id->eigvec[j] * pv;
    }
    /* Information gathered per unit time: LSM averages over the active time,
     * MFF's window has length 1/|ln R| (lambda = R^h). */
    const double excess = rayleigh - id->rho;
    if (id->lambda < 1.0) id->excitation = excess * (-log(id->lambda) / id->h);
    else id->excitation = id->active_time > 0.0 ? excess / id->active_time : 0.0;
    if (id->excitation < 0.0) id->excitation = 0.0;
    return 0;
}
