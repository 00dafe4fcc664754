/* Unit tests of the regressor identifier's solve with statistics spread over
 * internal steps (fmu/src/core/statistics_job.h): run as
 * `test_statistics_job CASE` (check.h). */
#include <math.h>
#include <string.h>

#include "check.h"
#include "random_data.h"

#include "regressor_identifier.h"
#include "statistics_job.h"

/* ---- the solve with statistics spread over internal steps ------------------------- */

/* A 7-joint identifier over every column (p = 84) on random data with one weakly
 * excited direction; a job every 700 samples with a budget of 2000 multiply-adds
 * per step.  Each completed job must give ri_solve + ri_statistics of a copy of
 * the identifier taken at its snapshot: Delta_hat, the standard errors and
 * trace(Gamma) to 1e-12 (the same arithmetic: measured 0), the excitation to 1e-12
 * of the smallest eigenvalue per remembered time (different starts of the inverse
 * iteration, each to its convergence). */
static int statistics_job_equals_full_solve(void)
{
    static RegressorIdentifier id, snapshot;
    static StatisticsJob job;
    int failures = 0;
    for (int kind = IDENTIFIER_LSM; kind <= IDENTIFIER_MFF; ++kind) {
        const int rows = 7, p = RRI_PARAMETERS_OF(7);
        int columns[RRI_MAX_PARAMETERS];
        for (int k = 0; k < p; ++k) columns[k] = k;
        const double h = 1e-3;
        if (ri_init(&id, (IdentifierKind)kind, rows, p, columns, NULL, h, 1e-6, 0.5, NULL) != 0) return 1;
        sj_init(&job, p, 700.0, 2000.0);
        unsigned long state = 12345;
        int jobs = 0, sliced = 0;
        double worst = 0.0, worst_excitation = 0.0, most_iterations = 0.0;
        double least_iterations = STATS_EIGEN_ITERATIONS;
        for (int step = 0; step < 6000; ++step) {
            RbRegressor Y;
            double z[RRI_MAX_ROWS];
            memset(&Y, 0, sizeof Y);
            for (int i = 0; i < rows; ++i) {
                for (int c = 0; c < p; ++c) Y.row[i][c] = uniform_random(&state);
                Y.row[i][1] = Y.row[i][0] + 1e-3 * Y.row[i][1]; /* the weak direction */
                z[i] = 0.1 * uniform_random(&state);
            }
            ri_step(&id, z, &Y);
            const int done = sj_step(&job);
            sj_schedule(&job, &id); /* a communication point after every step */
            if (job.since == 0.0) snapshot = id; /* sj_schedule took its snapshot here */
            if (!done) continue;
            ++jobs;
            sliced += job.age > 1.0;
            if (ri_solve(&snapshot) != 0) return 1;
            ri_statistics(&snapshot);
            for (int k = 0; k < p; ++k) {
                worst = fmax(worst, relative(job.delta[k], snapshot.delta[k]));
                worst = fmax(worst, relative(job.std_error[k], snapshot.std_error[k]));
            }
            worst = fmax(worst, relative(job.gamma_trace, snapshot.gamma_trace));
            /* the excitation is (eigenvalue - rho) / memory: relative to eigenvalue / memory */
            const double scale = snapshot.excitation + snapshot.rho / (snapshot.active_time > 0.0
                                                                        ? snapshot.active_time
                                                                        : 1.0);
            worst_excitation = fmax(worst_excitation,
                                    fabs(job.excitation - snapshot.excitation) / scale);
            most_iterations = fmax(most_iterations, job.iterations);
            if (jobs > 1) least_iterations = fmin(least_iterations, job.iterations);
        }
        const char *name = kind == IDENTIFIER_LSM ? "LSM" : "MFF";
        failures += check(jobs == 9 && sliced == jobs, "%s: %d jobs completed, %d over several "
                          "steps (expected 9, each sliced)", name, jobs, sliced);
        failures += check(worst <= 1e-12, "%s: Delta_hat, standard errors, trace(Gamma) of the "
                          "sliced jobs against the full solve at their snapshots: worst relative "
                          "difference %.3g (bound 1e-12)", name, worst);
        failures += check(worst_excitation <= 1e-12, "%s: excitation: worst difference %.3g of "
                          "the eigenvalue per remembered time (bound 1e-12)", name,
                          worst_excitation);
        failures += check(least_iterations < most_iterations, "%s: inverse iterations per job "
                          "from the warm start %g (the first job %g at most)", name,
                          least_iterations, most_iterations);
    }
    return failures;
}

/* sqrt(1 - R_k^2) of column k of the information A (three columns): its
 * regression on the other two, solved directly, with `ridge` added to the
 * others' diagonal (the identifier's rho I). */
static double unexplained_share(double A[3][3], int k, double ridge)
{
    const int a = (k + 1) % 3, b = (k + 2) % 3;
    const double Aaa = A[a][a] + ridge, Abb = A[b][b] + ridge;
    const double det = Aaa * Abb - A[a][b] * A[a][b];
    double explained;
    if (det > 0.0) {
        const double ca = (Abb * A[a][k] - A[a][b] * A[b][k]) / det;
        const double cb = (Aaa * A[b][k] - A[a][b] * A[a][k]) / det;
        explained = ca * A[a][k] + cb * A[b][k];
    } else { /* one of the others is never reached: the regression on the one left */
        const int c = Aaa > 0.0 ? a : b;
        explained = A[c][c] > 0.0 ? A[c][k] * A[c][k] / A[c][c] : 0.0;
    }
    return A[k][k] > 0.0 ? sqrt(fmax(1.0 - explained / A[k][k], 0.0)) : 0.0;
}

/* Each parameter's column excitation, what identify reports: a column nearly
 * equal to another (1e-2 of it apart) near 1e-2, a third column the rows never
 * reach 0, the first as its regression on the others says.  Exactly (1e-9) with
 * the ridge rho I on the other columns, and within 1 % of the ridge-free share
 * (measured 0.5 %: rho = 1e-6 is not small beside the near copies' unexplained
 * part).  Before any data every column's excitation is 0. */
static int column_excitation_is_the_unexplained_share(void)
{
    static RegressorIdentifier id;
    static StatisticsJob job;
    const int p = 3;
    if (ri_init_dense(&id, IDENTIFIER_LSM, 1, p, NULL, 1e-3, 1e-6, 0.5, NULL) != 0) return 1;
    sj_init(&job, p, 0.0, 1e9);
    sj_schedule(&job, &id);
    while (!sj_step(&job)) {}
    int failures = check(job.column_excitation[0] == 0.0 && job.column_excitation[2] == 0.0,
                         "no data: column excitations %g, %g, %g (expected 0)",
                         job.column_excitation[0], job.column_excitation[1],
                         job.column_excitation[2]);
    unsigned long state = 777;
    for (int step = 0; step < 3000; ++step) {
        RbRegressor Y;
        memset(&Y, 0, sizeof Y);
        Y.row[0][0] = uniform_random(&state);
        Y.row[0][1] = 0.5 * Y.row[0][0] + 1e-2 * uniform_random(&state);
        const double z = uniform_random(&state);
        ri_step(&id, &z, &Y);
    }
    sj_schedule(&job, &id);
    while (!sj_step(&job)) {}
    double A[3][3];
    for (int i = 0; i < p; ++i)
        for (int j = 0; j < p; ++j)
            A[i][j] = (i <= j ? id.P[i][j] : id.P[j][i]) - (i == j ? id.rho : 0.0);
    double exact = 0.0, ridge_free = 0.0;
    for (int k = 0; k < 2; ++k) {
        exact = fmax(exact, relative(job.column_excitation[k], unexplained_share(A, k, id.rho)));
        ridge_free = fmax(ridge_free, relative(job.column_excitation[k],
                                               unexplained_share(A, k, 0.0)));
    }
    failures += check(exact <= 1e-9 && ridge_free <= 1e-2 && job.column_excitation[2] == 0.0 &&
                      job.column_excitation[1] > 5e-3 && job.column_excitation[1] < 5e-2,
                      "column excitations %.6g, %.6g, %.6g: relative difference from the "
                      "regression on the other columns %.3g with the ridge (bound 1e-9), %.3g "
                      "without (bound 1e-2); the unreached column's 0, the near copy's in "
                      "(5e-3, 5e-2)", job.column_excitation[0], job.column_excitation[1],
                      job.column_excitation[2], exact, ridge_free);
    return failures;
}

int main(int argc, char **argv)
{
    static const TestCase cases[] = {
        {"statistics_job_equals_full_solve", statistics_job_equals_full_solve},
        {"column_excitation", column_excitation_is_the_unexplained_share},
    };
    return run_cases("test_statistics_job", cases, sizeof cases / sizeof cases[0], argc, argv);
}
