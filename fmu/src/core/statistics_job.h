/* The regressor identifier's solve with statistics (ri_solve and
 * ri_statistics: the estimate, the standard errors by the sandwich
 * P^-1 S P^-1, trace(Gamma) and the excitation) spread over internal steps, so
 * that no step of a hard real-time loop carries its O(p^3) work at once.
 *
 * A job starts from a snapshot of P (upper triangle), b and S (the scores'
 * outer products) taken at the end of an internal step (sj_schedule), at least
 * `interval` internal steps after the last and when no job runs, so that the
 * results follow the internal steps alone, never the importer's communication
 * step; each later
 * internal step (sj_step) does units of work (a column of the Cholesky
 * factor, a solve, a sandwich row, an inverse iteration) up to `budget`
 * multiply-adds; the results are published when the job completes.  Every unit
 * is the arithmetic of ri_solve and ri_statistics, in their order: the
 * results are those of the full solve at the snapshot.  The inverse iteration
 * for the smallest eigenvalue of P starts from the previous job's eigenvector
 * (warm start) and stops when its estimate changes by less than
 * STATS_EIGEN_TOLERANCE (relative; at most STATS_EIGEN_ITERATIONS iterations), as
 * ri_statistics' does from its own start: the excitations agree to that
 * tolerance, the other results exactly.  Each parameter's column excitation
 * comes with its column of Gamma: the Schur complement 1 / Gamma_kk is what of
 * P_kk the other columns do not explain.
 * Plain C, no allocation; the offline path (native/robot_native.c) runs the same
 * schedule as the RobotObserver FMU. */
#ifndef STATISTICS_JOB_H
#define STATISTICS_JOB_H

#include "tuning.h"

#include <math.h>

#include "information_statistics.h"
#include "regressor_identifier.h"

typedef enum {
    SJ_IDLE = 0,   /* no job: the results are the last completed job's */
    SJ_FACTOR,     /* column `index` of the Cholesky factor of the snapshot of P */
    SJ_ESTIMATE,   /* Delta_hat = P^-1 b */
    SJ_GAMMA,      /* column `index` of Gamma = P^-1, and its part of trace(Gamma) */
    SJ_SANDWICH,   /* its variance g^T S g */
    SJ_EIGEN       /* inverse iteration `index` */
} SjStage;

typedef struct {
    int p;
    double interval;            /* internal steps between snapshots, at least */
    double budget;              /* multiply-adds per internal step */
    double since;               /* internal steps since the last snapshot */
    /* the running job */
    int stage, index;
    double rho, lambda, h, active_time; /* the snapshot's identifier */
    double factor[RRI_MAX_PARAMETERS][RRI_MAX_PARAMETERS]; /* P's upper triangle, then L */
    double score_power[RRI_MAX_PARAMETERS][RRI_MAX_PARAMETERS]; /* S, upper triangle */
    double work_delta[RRI_MAX_PARAMETERS];  /* b, then Delta_hat */
    double column[RRI_MAX_PARAMETERS];      /* the Gamma column in work */
    double work_std[RRI_MAX_PARAMETERS], work_trace;
    double diagonal[RRI_MAX_PARAMETERS];     /* the snapshot's diagonal of P */
    double work_column_excitation[RRI_MAX_PARAMETERS];
    double eigenvector[RRI_MAX_PARAMETERS], norm; /* kept between jobs: the warm start */
    /* the last completed job */
    double completed;           /* jobs completed */
    double age;                 /* internal steps since its snapshot */
    double delta[RRI_MAX_PARAMETERS], std_error[RRI_MAX_PARAMETERS];
    double gamma_trace, excitation;
    /* per parameter, the share of its regressor column that the others do not
     * explain, sqrt(1 - R_k^2) of the information without the ridge rho I:
     * 0 (never excited, or a combination of the others) .. 1 (orthogonal) */
    double column_excitation[RRI_MAX_PARAMETERS];
    double iterations;          /* inverse iterations it took */
} StatisticsJob;

/* p the identifier's parameters; interval >= 0 internal steps between
 * snapshots (0: a job as soon as the last completes); budget > 0.  The first
 * snapshot is taken at the first sj_schedule. */
void sj_init(StatisticsJob *job, int p, double interval, double budget);

/* Internal steps of h in an interval of `seconds` >= 0 (rounded up, a few ulp of
 * slack; at most 1e15: as good as never). */
double sj_interval_steps(double seconds, double h);

/* The fresher estimate Delta_hat: the identifier's running solution (its anchor),
 * or the last completed job's if its snapshot is more recent. */
const double *sj_freshest_estimate(const StatisticsJob *job, const RegressorIdentifier *id);

/* The identifier was reset: the running job is dropped, the next sj_schedule
 * takes a snapshot; the last results stay (until a job completes), its estimate
 * no longer counts as fresher than the identifier's running solution. */
void sj_reset(StatisticsJob *job);

/* An internal step (after ri_step): a slice of the running job.  Returns 1 if
 * the job completed in this step. */
int sj_step(StatisticsJob *job);

/* After an internal step's sj_step: a snapshot (sj_start) if one is due and no
 * job runs: one every `interval` internal steps at most. */
void sj_schedule(StatisticsJob *job, const RegressorIdentifier *id);

/* The snapshot (what sj_schedule takes): copies P, b, S and the settings. */
void sj_start(StatisticsJob *job, const RegressorIdentifier *id);

/* Units of the running job up to `budget` multiply-adds (one unit at least).
 * Returns 1 if the job completed (its results published), 0 otherwise; a P that
 * is not positive definite drops the job (0). */
int sj_advance(StatisticsJob *job, double budget);

#endif
