#include "statistics_job.h"

#include <math.h>
#include <string.h>

#include "cholesky.h"

static void uniform(double v[], int p)
{
    for (int k = 0; k < p; ++k) v[k] = 1.0 / sqrt((double)p);
}

void sj_init(StatisticsJob *job, int p, double interval, double budget)
{
    memset(job, 0, sizeof *job);
    job->p = p;
    job->interval = interval;
    job->budget = budget;
    uniform(job->eigenvector, p);
    sj_reset(job);
}

double sj_interval_steps(double seconds, double h)
{
    return fmin(ceil(seconds / h - 1e-6), 1e15);
}

const double *sj_freshest_estimate(const StatisticsJob *job, const RegressorIdentifier *id)
{
    return job->completed > 0.0 && job->age < ri_anchor_age(id) ? job->delta : id->anchor;
}

void sj_reset(StatisticsJob *job)
{
    job->stage = SJ_IDLE;
    job->age = HUGE_VAL; /* its estimate is of the identifier before the reset */
    job->since = job->interval; /* a snapshot at the next step */
}

void sj_start(StatisticsJob *job, const RegressorIdentifier *id)
{
    const int p = job->p;
    const double scale = ri_score_scale(id); /* the kept batches' sum, to all batches' */
    for (int j = 0; j < p; ++j) { /* the upper triangles, row by row */
        memcpy(&job->factor[j][j], &id->P[j][j], (size_t)(p - j) * sizeof(double));
        for (int k = j; k < p; ++k) job->score_power[j][k] = scale * id->score_power[j][k];
        job->diagonal[j] = id->P[j][j];
    }
    memcpy(job->work_delta, id->b, (size_t)p * sizeof(double));
    job->rho = id->rho;
    job->lambda = id->lambda;
    job->h = id->h;
    job->active_time = id->active_time;
    job->work_trace = 0.0;
    job->norm = 0.0;
    job->stage = SJ_FACTOR;
    job->index = 0;
    job->since = 0.0;
}

/* Multiply-adds of the running job's next unit (what the budget counts). */
static double unit_cost(const StatisticsJob *job)
{
    const double p = job->p;
    switch (job->stage) {
    case SJ_FACTOR: return (job->index + 1.0) * (p - job->index);
    case SJ_SANDWICH: return 0.5 * p * (p + 1.0);
    case SJ_EIGEN: return p * (p + 2.0);
    default: return p * p; /* a solve */
    }
}

static void complete(StatisticsJob *job, int iterations)
{
    const int p = job->p;
    memcpy(job->delta, job->work_delta, (size_t)p * sizeof(double));
    memcpy(job->std_error, job->work_std, (size_t)p * sizeof(double));
    memcpy(job->column_excitation, job->work_column_excitation, (size_t)p * sizeof(double));
    job->gamma_trace = job->work_trace;
    job->excitation = stats_excitation(job->norm, job->rho, job->lambda, job->h, job->active_time);
    job->iterations = iterations;
    job->age = job->since;
    job->completed += 1.0;
    job->stage = SJ_IDLE;
}

/* One unit of the running job; 1 if the job completed, -1 if it was dropped. */
static int unit(StatisticsJob *job)
{
    const int p = job->p;
    double *L = &job->factor[0][0];
    switch (job->stage) {
    case SJ_FACTOR:
        if (cholesky_factor_column(L, L, p, RRI_MAX_PARAMETERS, job->index) != 0) {
            job->stage = SJ_IDLE;
            return -1;
        }
        if (++job->index == p) job->stage = SJ_ESTIMATE;
        return 0;
    case SJ_ESTIMATE:
        cholesky_solve(L, p, RRI_MAX_PARAMETERS, job->work_delta);
        job->stage = SJ_GAMMA;
        job->index = 0;
        return 0;
    case SJ_GAMMA:
        memset(job->column, 0, sizeof job->column);
        job->column[job->index] = 1.0;
        cholesky_solve(L, p, RRI_MAX_PARAMETERS, job->column);
        job->work_trace += job->column[job->index];
        job->work_column_excitation[job->index] =
            stats_column_excitation(job->diagonal[job->index], job->column[job->index], job->rho);
        job->stage = SJ_SANDWICH;
        return 0;
    case SJ_SANDWICH: {
        const double variance = stats_sandwich(&job->score_power[0][0], p, RRI_MAX_PARAMETERS, job->column);
        job->work_std[job->index] = sqrt(variance > 0.0 ? variance : 0.0);
        job->stage = ++job->index == p ? SJ_EIGEN : SJ_GAMMA;
        if (job->stage == SJ_EIGEN) job->index = 0;
        return 0;
    }
    case SJ_EIGEN: {
        const double previous = job->norm;
        job->norm = stats_inverse_iteration(L, p, RRI_MAX_PARAMETERS, job->eigenvector);
        if (++job->index >= STATS_EIGEN_ITERATIONS || stats_eigen_converged(job->norm, previous)) {
            if (!isfinite(job->norm)) uniform(job->eigenvector, p); /* no warm start from it */
            complete(job, job->index);
            return 1;
        }
        return 0;
    }
    default:
        return 0;
    }
}

int sj_advance(StatisticsJob *job, double budget)
{
    double spent = 0.0;
    while (job->stage != SJ_IDLE) {
        const double cost = unit_cost(job);
        if (spent > 0.0 && spent + cost > budget) break;
        spent += cost;
        const int status = unit(job);
        if (status != 0) return status > 0;
    }
    return 0;
}

int sj_step(StatisticsJob *job)
{
    job->since += 1.0;
    job->age += 1.0;
    return sj_advance(job, job->budget);
}

void sj_schedule(StatisticsJob *job, const RegressorIdentifier *id)
{
    if (job->stage == SJ_IDLE && job->since >= job->interval) sj_start(job, id);
}
