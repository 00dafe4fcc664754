#include "regressor_identifier.h"

#include <math.h>
#include <string.h>

#include "cholesky.h"
#include "information_statistics.h"

static void anchor_snapshot(RegressorIdentifier *id);

/* The settings shared by both layouts; the columns and runs are set by the caller. */
static int init_settings(RegressorIdentifier *id, IdentifierKind kind, int rows, int p,
                         const double torque_scale[], double h, double rho, double R,
                         const LeaveOutTuning *leave_out)
{
    if (!(h > 0.0) || !isfinite(h) || !(rho > 0.0) || !isfinite(rho)) return -1;
    if (kind == IDENTIFIER_MFF && !(R > 0.0 && R < 1.0)) return -1;
    if (kind != IDENTIFIER_LSM && kind != IDENTIFIER_MFF) return -1;
    for (int i = 0; i < rows; ++i) {
        const double s = torque_scale ? torque_scale[i] : 1.0;
        if (!(s > 0.0) || !isfinite(s)) return -1;
        id->weight[i] = 1.0 / (s * s);
    }
    id->rows = rows;
    id->p = p;
    id->h = h;
    id->rho = rho;
    id->lambda = kind == IDENTIFIER_MFF ? pow(R, h) : 1.0;
    id->one_minus_lambda_rho = (1.0 - id->lambda) * rho;
    /* an int: a tiny h (below RRI_BATCH_TIME / RRI_MAX_BATCH_SAMPLES) gets shorter batches */
    id->batch_samples = (int)fmin(ceil(RRI_BATCH_TIME / h), RRI_MAX_BATCH_SAMPLES);
    id->batch_lambda = pow(id->lambda, 2.0 * id->batch_samples); /* variances forget twice as fast */
    const LeaveOutTuning t = leave_out ? *leave_out : tuning_default().leave_out;
    leave_out_init(&id->leave_out, &t, id->lambda, rho, kind == IDENTIFIER_MFF ? R : 1.0, p);
    ri_reset(id);
    return 0;
}

int ri_init(RegressorIdentifier *id, IdentifierKind kind, int rows, int p, const int columns[],
             const double torque_scale[], double h, double rho, double R,
             const LeaveOutTuning *leave_out)
{
    memset(id, 0, sizeof *id);
    if (rows < 1 || rows > RRI_MAX_ROWS || p < 1 || p > RRI_PARAMETERS_OF(rows)) return -1;
    for (int k = 0; k < p; ++k) {
        if (columns[k] < 0 || columns[k] >= RRI_PARAMETERS_OF(rows)) return -1;
        for (int j = 0; j < k; ++j)
            if (columns[j] == columns[k]) return -1;
        id->columns[k] = columns[k];
    }
    /* link l's columns reach joints 0..l, joint i's friction only joint i */
    const int link_columns = RB_LINK_PARAMETERS * rows;
    for (int i = 0; i < rows; ++i) {
        id->runs[i] = 0;
        for (int k = 0; k < p; ++k) {
            const int c = columns[k];
            const int reaches = c < link_columns ? i <= c / RB_LINK_PARAMETERS
                                                 : (c - link_columns) / RB_JOINT_FRICTION == i;
            if (!reaches) continue;
            if (id->runs[i] > 0 && id->run_end[i][id->runs[i] - 1] == k) {
                id->run_end[i][id->runs[i] - 1] = k + 1;
            } else {
                id->run_start[i][id->runs[i]] = k;
                id->run_end[i][id->runs[i]++] = k + 1;
            }
        }
    }
    return init_settings(id, kind, rows, p, torque_scale, h, rho, R, leave_out);
}

int ri_init_dense(RegressorIdentifier *id, IdentifierKind kind, int rows, int p,
                   const double torque_scale[], double h, double rho, double R,
                   const LeaveOutTuning *leave_out)
{
    memset(id, 0, sizeof *id);
    if (rows < 1 || rows > RRI_MAX_ROWS || p < 1 || p > RRI_MAX_PARAMETERS) return -1;
    for (int k = 0; k < p; ++k) id->columns[k] = k;
    for (int i = 0; i < rows; ++i) { /* every row may reach every column: one run */
        id->runs[i] = 1;
        id->run_start[i][0] = 0;
        id->run_end[i][0] = p;
    }
    return init_settings(id, kind, rows, p, torque_scale, h, rho, R, leave_out);
}

void ri_reset(RegressorIdentifier *id)
{
    memset(id->P, 0, sizeof id->P);
    memset(id->b, 0, sizeof id->b);
    memset(id->delta, 0, sizeof id->delta);
    memset(id->anchor, 0, sizeof id->anchor);
    memset(id->score, 0, sizeof id->score);
    memset(id->score_power, 0, sizeof id->score_power);
    memset(id->std_error, 0, sizeof id->std_error);
    id->batch_residual = id->batches = id->batches_kept = 0.0;
    memset(id->anchor_kept, 0, sizeof id->anchor_kept);
    for (int k = 0; k < id->p; ++k) {
        id->P[k][k] = id->reference[k] = id->rho;
        id->reference_inverse[k] = 1.0 / id->rho;
    }
    id->leave_out.gap_time = 0.0;
    id->batch_age = 0;
    anchor_snapshot(id);
    id->active_time = 0.0;
    id->gamma_trace = id->p / id->rho;
    id->excitation = 0.0;
}

/* Cholesky P = L L^T into id->factor (lower triangle); 0 or -1. */
static int factorize(RegressorIdentifier *id)
{
    return cholesky_factor(&id->P[0][0], &id->factor[0][0], id->p, RRI_MAX_PARAMETERS);
}

/* x <- P^-1 x with the factor. */
static void solve(const RegressorIdentifier *id, double x[])
{
    cholesky_solve(&id->factor[0][0], id->p, RRI_MAX_PARAMETERS, x);
}

/* The anchor's next solve starts from the state after this sample. */
static void anchor_snapshot(RegressorIdentifier *id)
{
    const int p = id->p;
    for (int j = 0; j < p; ++j)
        memcpy(&id->anchor_factor[j][j], &id->P[j][j], (size_t)(p - j) * sizeof(double));
    memcpy(id->anchor_solution, id->b, (size_t)p * sizeof(double));
    id->anchor_age = 0;
    id->anchor_unit = id->anchor_failed = 0;
    id->anchor_work = 0.0;
}

/* Multiply-adds of the anchor solve's unit u, and of the whole solve. */
static double anchor_unit_cost(int p, int u)
{
    return u < p ? (u + 1.0) * (double)(p - u) : 0.5 * p * p;
}

static double anchor_total_cost(int p)
{
    return p * (p + 1.0) * (p + 2.0) / 6.0 + (double)p * p;
}

/* After anchor_age samples of the interval, the units whose work fits in that
 * share of the whole; at the end of the interval the rest, the solution becomes
 * the anchor (kept if P was not positive definite) and the next snapshot is taken. */
static void anchor_slice(RegressorIdentifier *id)
{
    const int p = id->p;
    double *L = &id->anchor_factor[0][0];
    const int last = id->anchor_age >= RRI_ANCHOR_INTERVAL;
    const double share = id->anchor_age * anchor_total_cost(p) / RRI_ANCHOR_INTERVAL;
    while (id->anchor_unit < p + 2) {
        const int u = id->anchor_unit;
        const double cost = anchor_unit_cost(p, u);
        if (!last && id->anchor_work + cost > share) break;
        if (u < p) {
            if (cholesky_factor_column(L, L, p, RRI_MAX_PARAMETERS, u) != 0) {
                id->anchor_failed = 1;
                id->anchor_unit = p + 2;
                break;
            }
        } else if (u == p) {
            cholesky_forward(L, p, RRI_MAX_PARAMETERS, id->anchor_solution);
        } else {
            cholesky_backward(L, p, RRI_MAX_PARAMETERS, id->anchor_solution);
        }
        id->anchor_work += cost;
        ++id->anchor_unit;
    }
    if (!last) return;
    if (!id->anchor_failed) memcpy(id->anchor, id->anchor_solution, (size_t)p * sizeof(double));
    /* MFF's leave-out rule reads Pref's diagonal as refreshed with the anchor */
    for (int k = 0; k < p; ++k) id->reference_inverse[k] = 1.0 / id->reference[k];
    anchor_snapshot(id);
}

/* MFF's leave-out rule (leave_out.h) with q = h sum_i w_i sum_k y_ik^2 / Pref_kk:
 * adds the sample's inflow to the diagonal of Pref and tells whether the sample is
 * used (1), left out within a short gap (0) or left out in a rest (-1). */
static int leave_out_rule(RegressorIdentifier *id, const RbRegressor *Y)
{
    double inflow[RRI_MAX_PARAMETERS] = {0};
    for (int i = 0; i < id->rows; ++i) {
        const double *row = Y->row[i], c = id->h * id->weight[i];
        for (int r = 0; r < id->runs[i]; ++r)
            for (int k = id->run_start[i][r]; k < id->run_end[i][r]; ++k) {
                const double y = row[id->columns[k]];
                inflow[k] += c * y * y;
            }
    }
    double q = 0.0;
    for (int k = 0; k < id->p; ++k) q += inflow[k] * id->reference_inverse[k];
    double lambda, pull;
    const int use = leave_out_decide(&id->leave_out, q, id->h, &lambda, &pull);
    for (int k = 0; k < id->p; ++k) id->reference[k] = lambda * id->reference[k] + pull + inflow[k];
    return use;
}

/* The residual power per unit time that the move d of the anchor makes:
 * d^T P d over the time P remembers. */
static double move_power(const RegressorIdentifier *id, const double d[])
{
    double quadratic = 0.0;
    for (int j = 0; j < id->p; ++j) {
        quadratic += id->P[j][j] * d[j] * d[j];
        for (int k = j + 1; k < id->p; ++k) quadratic += 2.0 * id->P[j][k] * d[j] * d[k];
    }
    const double memory = stats_memory(id->lambda, id->h, id->active_time);
    return memory > 0.0 ? quadratic / memory : 0.0;
}

/* The batch's scores enter the sum of outer products, which restarts first when the
 * anchor has moved so far since the kept batches began that their scores are more
 * the anchor's error than the residuals'. */
static void close_batch(RegressorIdentifier *id)
{
    const int p = id->p;
    const double lambda = id->batch_lambda;
    double d[RRI_MAX_PARAMETERS];
    for (int k = 0; k < p; ++k) d[k] = id->anchor[k] - id->anchor_kept[k];
    const double residual_power = id->batch_residual / (id->batch_samples * id->h);
    if (id->batches_kept > 0.0 && move_power(id, d) > RRI_SCORE_RESTART * residual_power) {
        memset(id->score_power, 0, sizeof id->score_power);
        id->batches_kept = 0.0;
        memcpy(id->anchor_kept, id->anchor, (size_t)p * sizeof id->anchor[0]);
    }
    for (int j = 0; j < p; ++j)
        for (int k = j; k < p; ++k)
            id->score_power[j][k] = lambda * id->score_power[j][k] + id->score[j] * id->score[k];
    id->batches = lambda * id->batches + 1.0;
    id->batches_kept = lambda * id->batches_kept + 1.0;
    memset(id->score, 0, sizeof id->score);
    id->batch_residual = 0.0;
    id->batch_age = 0;
}

double ri_score_scale(const RegressorIdentifier *id)
{
    return id->batches_kept > 0.0 ? id->batches / id->batches_kept : 1.0;
}

void ri_step(RegressorIdentifier *id, const double z[], const RbRegressor *Y)
{
    const int p = id->p;
    int use = 1;
    id->active_time += id->h;
    if (id->lambda < 1.0) {
        use = leave_out_rule(id, Y);
        if (use < 0) { /* a rest: nothing forgotten, nothing added, the batch stands still */
            ++id->anchor_age; /* (the anchor's solve goes on, of the same sums) */
            anchor_slice(id);
            return;
        }
        const double lambda = id->lambda, pull = id->one_minus_lambda_rho;
        for (int j = 0; j < p; ++j) {
            for (int k = j; k < p; ++k) id->P[j][k] *= lambda;
            id->P[j][j] += pull;
            id->b[j] = lambda * id->b[j] + pull * id->anchor[j];
        }
    }
    /* row i adds h w_i y_i^T (y_i, z_i, residual_i) over the columns where y_i
     * can be nonzero (its runs): the upper triangle of P row by row */
    for (int i = 0; i < id->rows && use; ++i) {
        const int runs = id->runs[i];
        const int *start = id->run_start[i], *end = id->run_end[i];
        const double *row = Y->row[i], c = id->h * id->weight[i];
        double y[RRI_MAX_PARAMETERS], residual = z[i];
        for (int r = 0; r < runs; ++r)
            for (int k = start[r]; k < end[r]; ++k) {
                y[k] = row[id->columns[k]];
                residual -= y[k] * id->anchor[k];
            }
        id->batch_residual += c * residual * residual;
        for (int r = 0; r < runs; ++r)
            for (int j = start[r]; j < end[r]; ++j) {
                const double a = c * y[j];
                double *P = id->P[j];
                id->b[j] += a * z[i];
                id->score[j] += a * residual;
                for (int k = j; k < end[r]; ++k) P[k] += a * y[k];
                for (int s = r + 1; s < runs; ++s)
                    for (int k = start[s]; k < end[s]; ++k) P[k] += a * y[k];
            }
    }
    if (++id->batch_age >= id->batch_samples) close_batch(id);
    ++id->anchor_age;
    anchor_slice(id);
}

void ri_filter_regressor(const RegressorIdentifier *id, const RbRegressor *Y,
                          const double weight[], double gain, RbRegressor *filtered)
{
    for (int i = 0; i < id->rows; ++i) {
        const double w = weight[i], *row = Y->row[i];
        double *out = filtered->row[i];
        for (int r = 0; r < id->runs[i]; ++r)
            for (int k = id->run_start[i][r]; k < id->run_end[i][r]; ++k) {
                const int c = id->columns[k];
                out[c] += gain * (w * row[c] - out[c]);
            }
    }
}

int ri_solve(RegressorIdentifier *id)
{
    if (factorize(id) != 0) return -1;
    memcpy(id->delta, id->b, sizeof id->b);
    solve(id, id->delta);
    return 0;
}

void ri_statistics(RegressorIdentifier *id)
{
    const int p = id->p;
    /* Gamma's columns g_k give trace(Gamma) and the sandwich g_k^T S g_k */
    double trace = 0.0;
    for (int k = 0; k < p; ++k) {
        double g[RRI_MAX_PARAMETERS] = {0};
        g[k] = 1.0;
        solve(id, g);
        trace += g[k];
        const double variance = ri_score_scale(id) *
                                stats_sandwich(&id->score_power[0][0], p, RRI_MAX_PARAMETERS, g);
        id->std_error[k] = sqrt(variance > 0.0 ? variance : 0.0);
    }
    id->gamma_trace = trace;
    /* smallest eigenvalue of P by inverse iteration, per unit of remembered time */
    double v[RRI_MAX_PARAMETERS], norm = 0.0;
    for (int k = 0; k < p; ++k) v[k] = 1.0 / sqrt((double)p);
    for (int iteration = 0; iteration < STATS_EIGEN_ITERATIONS; ++iteration) {
        const double previous = norm;
        norm = stats_inverse_iteration(&id->factor[0][0], p, RRI_MAX_PARAMETERS, v);
        if (stats_eigen_converged(norm, previous)) break;
    }
    id->excitation = stats_excitation(norm, id->rho, id->lambda, id->h, id->active_time);
}
