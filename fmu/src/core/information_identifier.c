#include "information_identifier.h"

#include <math.h>
#include <string.h>

#include "cholesky.h"

#include "small_loops.h"

/* Size of the sums: m, or 2m with the drift model. */
static int dimension(const InformationIdentifier *id) { return id->drift ? 2 * id->m : id->m; }

void ii_init(InformationIdentifier *id, IdentifierKind kind, int rows, int m, double h,
               double rho, double R, int drift, const StoTuning *tuning)
{
    memset(id, 0, sizeof *id);
    const StoTuning t = tuning ? *tuning : tuning_default();
    id->tuning = t.identifier;
    id->rows = rows;
    id->m = m;
    id->drift = drift && kind == IDENTIFIER_MFF && 2 * m <= ID_MAX_REGRESSORS;
    id->h = h;
    id->rho = rho;
    id->lambda = kind == IDENTIFIER_MFF ? pow(R, h) : 1.0;
    id->one_minus_lambda_rho = (1.0 - id->lambda) * rho;
    id->batch_gain = -expm1(-h / t.identifier.batch_window);
    id->power_gain = -expm1(-h * INFO_STD_INTERVAL / t.identifier.power_window);
    id->forgetting_rate = kind == IDENTIFIER_MFF ? -log(R) : 0.0;
    leave_out_init(&id->leave_out, &t.leave_out, id->lambda, rho,
                   kind == IDENTIFIER_MFF ? R : 1.0, m / h); /* q leaves h out */
    /* LSM takes its scores' block increments every 32 samples */
    const double interval = id->forgetting_rate > 0.0
                                ? t.identifier.anchor_forgetting / (h * id->forgetting_rate)
                                : INFO_ANCHOR_MAX_INTERVAL;
    id->anchor_interval = interval >= INFO_ANCHOR_MAX_INTERVAL ? INFO_ANCHOR_MAX_INTERVAL
                          : interval >= 1.0                    ? (int)interval
                                                               : 1;
    ii_reset(id);
}

void ii_reset(InformationIdentifier *id)
{
    memset(id->P, 0, sizeof id->P);
    memset(id->theta, 0, sizeof id->theta);
    memset(id->delta, 0, sizeof id->delta);
    memset(id->anchor, 0, sizeof id->anchor);
    id->anchor_age = 0;
    memset(id->score_mean, 0, sizeof id->score_mean);
    memset(id->score_power, 0, sizeof id->score_power);
    memset(id->std_error, 0, sizeof id->std_error);
    id->std_age = 0;
    memset(id->factor, 0, sizeof id->factor);
    memset(id->theta_factored, 0, sizeof id->theta_factored);
    id->solve_pending = 0;
    id->residual_samples = 0.0;
    memset(id->reference, 0, sizeof id->reference);
    memset(id->reference_factor, 0, sizeof id->reference_factor);
    id->used_mean = 1.0;
    id->leave_out.gap_time = 0.0;
    const int n = dimension(id);
    for (int k = 0; k < id->m; ++k) {
        id->reference[k][k] = id->rho;
        id->reference_factor[k][k] = sqrt(id->rho);
    }
    for (int k = 0; k < n; ++k) {
        id->P[k][k] = id->rho;
        id->eigvec[k] = k < id->m ? 1.0 / sqrt((double)id->m) : 0.0;
    }
    if (id->lambda == 1.0)
        bs_init(&id->blocks, id->rows, id->m, id->tuning.lsm_score_window, &id->P[0][0],
                &id->theta[0][0]);
    id->active_time = 0.0;
    id->gamma_trace = id->m / id->rho;
    id->excitation = 0.0;
}

/* Re-centres the drift sums on the next step's time: with A = [[I,0],[-hI,I]],
 * P <- A P A^T and Theta <- Theta A^T (upper triangle of P kept). */
KERNEL recentre(InformationIdentifier *id, const int m)
{
    const double h = id->h;
    UNROLL for (int j = 0; j < m; ++j) {
        UNROLL for (int k = j; k < m; ++k) { /* P22 first: it reads the old P12, P21 */
            const double p11 = id->P[j][k];
            const double p12 = id->P[j][m + k], p21 = id->P[k][m + j];
            id->P[m + j][m + k] += h * h * p11 - h * p12 - h * p21;
        }
    }
    UNROLL for (int j = 0; j < m; ++j)
        UNROLL for (int k = 0; k < m; ++k) /* P12 block (rows j < m, columns m + k) */
            id->P[j][m + k] -= h * (k >= j ? id->P[j][k] : id->P[k][j]);
    for (int i = 0; i < id->rows; ++i)
        UNROLL for (int k = 0; k < m; ++k) id->theta[i][m + k] -= h * id->theta[i][k];
}

static void refresh_anchor(InformationIdentifier *id);
static void update_standard_errors(InformationIdentifier *id);

/* LSM: plain accumulation. */
KERNEL lsm_accumulate(InformationIdentifier *id, const double z[], const double phi[], const int m,
                      const int rows)
{
    const double h = id->h;
    UNROLL for (int j = 0; j < m; ++j) {
        const double hj = h * phi[j];
        UNROLL for (int k = j; k < m; ++k) id->P[j][k] += hj * phi[k];
    }
    for (int i = 0; i < rows; ++i) {
        const double hz = h * z[i];
        UNROLL for (int k = 0; k < m; ++k) id->theta[i][k] += hz * phi[k];
    }
}

/* MFF over sums of size n (m, or 2m with the drift model): forget toward
 * rho I and toward the current estimate (its drift part toward 0, so that a
 * learned slope fades without data); the newest sample has s - t = 0, so it
 * only enters the first m rows/columns. */
KERNEL mff_accumulate_n(InformationIdentifier *id, const double z[], const double phi[],
                        const int m, const int n, const int rows)
{
    const double h = id->h, lambda = id->lambda, pull = id->one_minus_lambda_rho;
    UNROLL for (int j = 0; j < n; ++j) {
        const double hj = j < m ? h * phi[j] : 0.0;
        UNROLL for (int k = j; k < n; ++k)
            id->P[j][k] = lambda * id->P[j][k] + (k < m ? hj * phi[k] : 0.0);
        id->P[j][j] += pull;
    }
    for (int i = 0; i < rows; ++i) {
        const double hz = h * z[i];
        UNROLL for (int k = 0; k < n; ++k)
            id->theta[i][k] = lambda * id->theta[i][k] +
                              (k < m ? pull * id->anchor[i][k] + hz * phi[k] : 0.0);
    }
}

/* Adds the sample to the long-run inflow Pref and tells whether it is used,
 * by the rule of leave_out.h with q = phi^T Pref^-1 phi (with the factor of the
 * last anchor refresh; the threshold holds h). */
INLINED int leave_out_rule(InformationIdentifier *id, const double phi[], const int m)
{
    double y[ID_MAX_REGRESSORS], q = 0.0;
    UNROLL for (int i = 0; i < m; ++i) { /* y = L^-1 phi */
        double s = phi[i];
        UNROLL for (int k = 0; k < i; ++k) s -= id->reference_factor[i][k] * y[k];
        y[i] = s / id->reference_factor[i][i];
        q += y[i] * y[i];
    }
    double lambda, pull;
    const double h = id->h;
    const int use = leave_out_decide(&id->leave_out, q, h, &lambda, &pull);
    UNROLL for (int j = 0; j < m; ++j) {
        const double hj = h * phi[j];
        UNROLL for (int k = j; k < m; ++k) id->reference[j][k] = lambda * id->reference[j][k] + hj * phi[k];
        id->reference[j][j] += pull;
    }
    id->used_mean += (1.0 - id->lambda) * ((double)(use > 0) - id->used_mean);
    return use;
}

KERNEL mff_accumulate(InformationIdentifier *id, const double z[], const double phi[], const int m,
                      const int rows)
{
    const int drift = id->drift && 2 * m <= ID_MAX_REGRESSORS; /* (the second test removes
                                                                 * the impossible large-m copies) */
    const int use = leave_out_rule(id, phi, m);
    if (use < 0) return; /* a rest: the sums frozen */
    if (use == 0) { /* a short gap (a velocity zero) forgets and extrapolates as before,
                     * without the sample's data */
        static const double none[ID_MAX_ROWS + ID_MAX_REGRESSORS] = {0};
        z = none;
        phi = none;
    }
    if (drift) {
        recentre(id, m);
        mff_accumulate_n(id, z, phi, m, 2 * m, rows);
    } else {
        mff_accumulate_n(id, z, phi, m, m, rows);
    }
}

void ii_step(InformationIdentifier *id, const double z[], const double phi[])
{
    const IdSample sample = identifier_sample(id->rows, id->m, z, phi);
    ii_run(id, &sample, 1);
}

/* MFF: the score w = phi r of a sample (r = z - anchor phi, the residual)
 * through the batch-mean filter (window INFO_BATCH_WINDOW).  Every
 * INFO_STD_INTERVAL samples the mean's outer product enters its running mean
 * (growing window first, then INFO_POWER_WINDOW) and the standard errors are
 * solved (update_standard_errors): for scores correlated over less than the
 * batch window, E[mean mean^T] = S_w / (2 T_b), S_w the scores' spectral
 * density at zero frequency, whose integral over the data is the covariance
 * of int phi r dt = P (Delta_hat - Delta). */
KERNEL track_residual(InformationIdentifier *id, const double z[], const double phi[],
                      const int m, const int rows)
{
    const double gb = id->batch_gain;
    for (int i = 0; i < rows; ++i) {
        double r = z[i];
        UNROLL for (int k = 0; k < m; ++k) r -= id->anchor[i][k] * phi[k];
        double *mean = id->score_mean[i];
        UNROLL for (int k = 0; k < m; ++k) mean[k] += gb * (phi[k] * r - mean[k]);
    }
    if (++id->std_age >= INFO_STD_INTERVAL) update_standard_errors(id);
}

KERNEL lsm_run(InformationIdentifier *id, const IdSample samples[], int count, const int rows,
               const int m)
{
    for (int k = 0; k < count; ++k) {
        id->active_time += id->h;
        lsm_accumulate(id, samples[k].z, samples[k].phi, m, rows);
        if (++id->anchor_age >= id->anchor_interval) {
            id->anchor_age = 0;
            bs_block(&id->blocks, id->anchor_interval * id->h, &id->P[0][0], &id->theta[0][0]);
            if ((id->std_age += id->anchor_interval) >= INFO_STD_INTERVAL) update_standard_errors(id);
        }
    }
}

KERNEL mff_run(InformationIdentifier *id, const IdSample samples[], int count, const int rows,
               const int m)
{
    for (int k = 0; k < count; ++k) {
        id->active_time += id->h;
        mff_accumulate(id, samples[k].z, samples[k].phi, m, rows);
        track_residual(id, samples[k].z, samples[k].phi, m, rows);
        if (++id->anchor_age >= id->anchor_interval) refresh_anchor(id);
    }
}

void ii_run(InformationIdentifier *id, const IdSample samples[], int count)
{
    if (id->lambda == 1.0) WITH_CONSTANT_SIZES(id->rows, id->m, lsm_run, id, samples, count);
    else WITH_CONSTANT_SIZES(id->rows, id->m, mff_run, id, samples, count);
}

/* Cholesky P = L L^T from the upper triangle; returns -1 if not positive definite. */
static int cholesky(const InformationIdentifier *id, int m,
                    double L[ID_MAX_REGRESSORS][ID_MAX_REGRESSORS])
{
    return cholesky_factor(&id->P[0][0], &L[0][0], m, ID_MAX_REGRESSORS);
}

/* Solves L L^T x = b in place. */
static void solve(int m, double L[ID_MAX_REGRESSORS][ID_MAX_REGRESSORS], double x[])
{
    cholesky_solve(&L[0][0], m, ID_MAX_REGRESSORS, x);
}

/* Delta_hat = Theta P^-1 into estimate, with the Cholesky factor L of P. */
static void solve_estimate(const InformationIdentifier *id, int n,
                           double L[ID_MAX_REGRESSORS][ID_MAX_REGRESSORS],
                           double estimate[ID_MAX_ROWS][ID_MAX_REGRESSORS])
{
    for (int i = 0; i < id->rows; ++i) {
        double x[ID_MAX_REGRESSORS];
        memcpy(x, id->theta[i], sizeof x);
        solve(n, L, x);
        memcpy(estimate[i], x, sizeof x);
    }
}

static void refresh_anchor(InformationIdentifier *id)
{
    double L[ID_MAX_REGRESSORS][ID_MAX_REGRESSORS] = {{0.0}}; /* the upper triangle is copied */
    const int n = dimension(id);
    id->anchor_age = 0;
    if (cholesky(id, n, L) == 0) solve_estimate(id, n, L, id->anchor); /* else keep it */
    if (id->lambda < 1.0 && cholesky_factor(&id->reference[0][0], &L[0][0], id->m,
                                            ID_MAX_REGRESSORS) == 0)
        memcpy(id->reference_factor, L, sizeof L);
}

static void update_standard_errors(InformationIdentifier *id)
{
    const int n = dimension(id), m = id->m;
    id->std_age = 0;
    const int lsm = id->lambda == 1.0;
    /* MFF: the first INFO_SCORE_DELAY seconds hold the estimate's own transient
     * (LSM's scores are at the current estimate: block_scores.h) */
    if (!lsm && id->active_time < id->tuning.score_delay) return;
    if (lsm) {
        /* over all the data, as the estimate weighs it (a growing mean) */
        bs_update_power(&id->blocks, 0.0);
        if (id->blocks.samples == 0.0) return; /* no window filled yet: none (0) */
    } else {
        /* MFF: in proportion to the samples used, so that a rest (no data, no
         * forgetting) leaves the standard errors where the excitation left them */
        const double gp = id->residual_samples * id->power_gain < 1.0
                              ? 1.0 / ++id->residual_samples
                              : id->power_gain * id->used_mean;
        for (int i = 0; i < id->rows; ++i)
            for (int a = 0; a < m; ++a)
                for (int b = a; b < m; ++b)
                    id->score_power[i][a][b] +=
                        gp * (id->score_mean[i][a] * id->score_mean[i][b] - id->score_power[i][a][b]);
    }
    double L[ID_MAX_REGRESSORS][ID_MAX_REGRESSORS], gamma[ID_MAX_REGRESSORS][ID_MAX_REGRESSORS];
    if (cholesky(id, n, L) != 0) return; /* keep the last ones */
    double estimate[ID_MAX_ROWS][ID_MAX_REGRESSORS];
    if (lsm) solve_estimate(id, n, L, estimate);
    for (int j = 0; j < m; ++j) {
        double e[ID_MAX_REGRESSORS] = {0};
        e[j] = 1.0;
        solve(n, L, e); /* column j of P^-1 */
        memcpy(gamma[j], e, sizeof e);
    }
    /* Sandwich: cov(Delta_i) = Gamma (T 2 T_b E[mean mean^T]) Gamma, T the data's
     * length: the active time for LSM, the memory of the squared weights
     * 1/(2 |ln R|) for MFF. */
    const double memory = id->lambda < 1.0 ? 0.5 / id->forgetting_rate : id->active_time;
    const double scale = memory < id->active_time ? memory : id->active_time;
    const double window = lsm ? id->tuning.lsm_score_window : id->tuning.batch_window;
    for (int i = 0; i < id->rows; ++i) {
        double power[ID_MAX_REGRESSORS][ID_MAX_REGRESSORS];
        if (lsm) {
            bs_score_power(&id->blocks, i, estimate[i], power);
        } else {
            for (int a = 0; a < m; ++a)
                for (int b = a; b < m; ++b) power[a][b] = power[b][a] = id->score_power[i][a][b];
        }
        for (int k = 0; k < m; ++k) {
            double variance = 0.0;
            for (int a = 0; a < m; ++a)
                for (int b = 0; b < m; ++b) variance += gamma[k][a] * power[a][b] * gamma[k][b];
            id->std_error[i][k] = sqrt(fmax(0.0, 2.0 * window * scale * variance));
        }
    }
}

/* ii_factor and ii_finish for constant sizes (small_loops.h): n = m, or 2m
 * with the drift model (drift, 2m <= ID_MAX_REGRESSORS); the arithmetic of
 * cholesky.h's factor and solves, in its order. */
#define SUMS(m, drift) ((drift) && 2 * (m) <= ID_MAX_REGRESSORS ? 2 * (m) : (m))

/* x <- P^-1 x over the leading `size` rows of the factor L. */
KERNEL factor_solve(double L[ID_MAX_REGRESSORS][ID_MAX_REGRESSORS], double x[],
                    const int size)
{
    UNROLL for (int i = 0; i < size; ++i) {
        UNROLL for (int k = 0; k < i; ++k) x[i] -= L[i][k] * x[k];
        x[i] /= L[i][i];
    }
    UNROLL for (int i = size - 1; i >= 0; --i) {
        UNROLL for (int k = i + 1; k < size; ++k) x[i] -= L[k][i] * x[k];
        x[i] /= L[i][i];
    }
}

KERNEL factor_kernel(InformationIdentifier *id, int *status, const int rows, const int m,
                     const int drift)
{
    const int n = SUMS(m, drift);
    double L[ID_MAX_REGRESSORS][ID_MAX_REGRESSORS];
    *status = -1;
    UNROLL for (int j = 0; j < n; ++j) { /* P = L L^T, cholesky_factor_column */
        double d = id->P[j][j];
        UNROLL for (int k = 0; k < j; ++k) d -= L[j][k] * L[j][k];
        if (!(d > 0.0) || !isfinite(d)) return;
        L[j][j] = sqrt(d);
        UNROLL for (int i = j + 1; i < n; ++i) {
            double s = id->P[j][i];
            UNROLL for (int k = 0; k < j; ++k) s -= L[i][k] * L[j][k];
            L[i][j] = s / L[j][j];
        }
    }
    *status = 0;
    UNROLL for (int i = 0; i < n; ++i)
        UNROLL for (int k = 0; k <= i; ++k) id->factor[i][k] = L[i][k];
    for (int i = 0; i < rows; ++i)
        UNROLL for (int k = 0; k < n; ++k) id->theta_factored[i][k] = id->theta[i][k];
    id->solve_pending = 1;
    /* One inverse-iteration step toward the eigenvector of the smallest
     * eigenvalue of the current parameters' information P11 (the leading
     * block of L is its Cholesky factor); the Rayleigh quotient estimates it. */
    double v[ID_MAX_REGRESSORS];
    UNROLL for (int k = 0; k < m; ++k) v[k] = id->eigvec[k];
    factor_solve(L, v, m);
    double norm = 0.0;
    UNROLL for (int k = 0; k < m; ++k) norm += v[k] * v[k];
    norm = sqrt(norm);
    if (norm > 0.0 && isfinite(norm)) {
        UNROLL for (int k = 0; k < m; ++k) id->eigvec[k] = v[k] / norm;
    }
    double rayleigh = 0.0;
    UNROLL for (int j = 0; j < m; ++j) {
        double pv = 0.0;
        UNROLL for (int k = 0; k < m; ++k)
            pv += (k >= j ? id->P[j][k] : id->P[k][j]) * id->eigvec[k];
        rayleigh += id->eigvec[j] * pv;
    }
    /* Information gathered per unit time: LSM averages over the active time;
     * MFF holds what arrives over its window 1/|ln R| (lambda = R^h), of the
     * samples it uses. */
    const double excess = rayleigh - id->rho;
    if (id->lambda < 1.0) id->excitation = excess * id->forgetting_rate * id->used_mean;
    else id->excitation = id->active_time > 0.0 ? excess / id->active_time : 0.0;
    if (id->excitation < 0.0) id->excitation = 0.0;
}

KERNEL finish_kernel(InformationIdentifier *id, const int rows, const int m, const int drift)
{
    const int n = SUMS(m, drift);
    double(*L)[ID_MAX_REGRESSORS] = id->factor;
    for (int i = 0; i < rows; ++i) { /* Delta_hat = Theta P^-1 */
        double x[ID_MAX_REGRESSORS];
        UNROLL for (int k = 0; k < n; ++k) x[k] = id->theta_factored[i][k];
        factor_solve(L, x, n);
        UNROLL for (int k = 0; k < n; ++k) id->delta[i][k] = x[k];
    }
    /* Trace of the current parameters' block of Gamma = P^-1.  Without the
     * drift model that is the whole trace, ||L^-1||_F^2, by forward
     * substitution of the columns of L^-1; with it, the first m diagonal
     * entries of P^-1, one solve each. */
    double trace = 0.0;
    if (n == m) {
        UNROLL for (int j = 0; j < m; ++j) {
            double col[ID_MAX_REGRESSORS];
            UNROLL for (int i = j; i < m; ++i) {
                double s = i == j ? 1.0 : 0.0;
                UNROLL for (int k = j; k < i; ++k) s -= L[i][k] * col[k];
                col[i] = s / L[i][i];
                trace += col[i] * col[i];
            }
        }
    } else {
        for (int j = 0; j < m; ++j) {
            double e[ID_MAX_REGRESSORS] = {0};
            e[j] = 1.0;
            factor_solve(L, e, n); /* column j of P^-1 */
            trace += e[j];
        }
    }
    id->gamma_trace = trace;
}

KERNEL factor_sizes(InformationIdentifier *id, int *status, const int rows, const int m)
{
    if (id->drift) factor_kernel(id, status, rows, m, 1);
    else factor_kernel(id, status, rows, m, 0);
}

KERNEL finish_sizes(InformationIdentifier *id, const int rows, const int m)
{
    if (id->drift) finish_kernel(id, rows, m, 1);
    else finish_kernel(id, rows, m, 0);
}

int ii_factor(InformationIdentifier *id)
{
    int status = 0; /* m == 0: nothing to solve */
    WITH_CONSTANT_SIZES(id->rows, id->m, factor_sizes, id, &status);
    return status;
}

void ii_finish(InformationIdentifier *id)
{
    if (!id->solve_pending) return;
    id->solve_pending = 0;
    WITH_CONSTANT_SIZES(id->rows, id->m, finish_sizes, id);
}

int ii_solve(InformationIdentifier *id)
{
    if (ii_factor(id) != 0) return -1;
    ii_finish(id);
    return 0;
}
