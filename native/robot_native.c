/* Batch entry points over fmu/src/core for the harness (ctypes): the model is an
 * opaque buffer of rn_model_size() bytes that rn_load fills, and every function
 * runs over `count` samples stored row by row (sample k's joint i at k n + i). */
#include <math.h>
#include <stddef.h>
#include <string.h>

#include "gains.h"
#include "noise_adaptive.h"
#include "regressor_identifier.h"
#include "robot_observer.h"
#include "robot_pipeline.h"
#include "rigid_body.h"
#include "statistics_job.h"
#include "super_twisting.h"

size_t rn_model_size(void) { return sizeof(RigidBodyModel); }

int rn_max_joints(void) { return RB_MAX_JOINTS; }

/* The parameter vector's layout (rigid_body.h), so that the harness keeps no copy of
 * it: a link's parameter count, a joint's friction count, and the offsets of the mass
 * in a link's parameters and of the viscous and Coulomb levels in a joint's friction. */
void rn_layout(int out[6])
{
    out[0] = RB_LINK_PARAMETERS;
    out[1] = RB_JOINT_FRICTION;
    out[2] = RB_MASS;
    out[3] = RB_VISCOUS;
    out[4] = RB_COULOMB;
    out[5] = RB_FIRST_MOMENT;
}

int rn_load(RigidBodyModel *model, int n, const int type[], const double axis[], const double xyz[],
            const double rpy[], const double link[], const double friction[],
            const double gravity[3], double coulomb_velocity)
{
    return rb_load(model, n, type, axis, xyz, rpy, link, friction, gravity, coulomb_velocity);
}

/* tau = M qdd + C qd + G + friction (with_friction) for each sample. */
void rn_inverse_dynamics(const RigidBodyModel *model, long count, const double q[],
                         const double qd[], const double qdd[], int with_gravity,
                         int with_friction, double tau[])
{
    const int n = model->n;
    for (long k = 0; k < count; ++k) {
        rb_inverse_dynamics(model, q + k * n, qd + k * n, qdd + k * n, with_gravity, tau + k * n);
        if (with_friction) {
            double f[RB_MAX_JOINTS];
            rb_friction(model, qd + k * n, f);
            for (int i = 0; i < n; ++i) tau[k * n + i] += f[i];
        }
    }
}

void rn_gravity(const RigidBodyModel *model, long count, const double q[], double g[])
{
    for (long k = 0; k < count; ++k) rb_gravity(model, q + k * model->n, g + k * model->n);
}

void rn_coriolis(const RigidBodyModel *model, long count, const double q[], const double qd[],
                 double c[])
{
    const int n = model->n;
    for (long k = 0; k < count; ++k) rb_coriolis(model, q + k * n, qd + k * n, c + k * n);
}

/* M of each sample, n x n row-major. */
void rn_mass_matrix(const RigidBodyModel *model, long count, const double q[], double M[])
{
    const int n = model->n;
    for (long k = 0; k < count; ++k) {
        double full[RB_MAX_JOINTS][RB_MAX_JOINTS];
        rb_mass_matrix(model, q + k * n, full);
        for (int i = 0; i < n; ++i) memcpy(M + (k * n + i) * n, full[i], (size_t)n * sizeof(double));
    }
}

/* Returns the number of samples whose M was not positive definite. */
long rn_forward_dynamics(const RigidBodyModel *model, long count, const double q[],
                         const double qd[], const double tau[], double qdd[])
{
    const int n = model->n;
    long failures = 0;
    for (long k = 0; k < count; ++k)
        failures += rb_forward_dynamics(model, q + k * n, qd + k * n, tau + k * n, qdd + k * n) != 0;
    return failures;
}

/* Y of each sample, n x 12n row-major. */
void rn_regressor(const RigidBodyModel *model, long count, const double q[], const double qd[],
                  const double qdd[], double Y[])
{
    const int n = model->n, p = rb_parameter_count(model);
    for (long k = 0; k < count; ++k) {
        RbRegressor full;
        rb_regressor(model, q + k * n, qd + k * n, qdd + k * n, &full);
        for (int i = 0; i < n; ++i)
            memcpy(Y + (k * n + i) * p, full.row[i], (size_t)p * sizeof(double));
    }
}

/* The online identifier (regressor_identifier.c) over recorded samples: the torque
 * residual of the model is z = tau - (M qdd + C qd + G + friction), the regressor
 * the model's.  Outputs the estimate Delta (p), its standard errors (p) and
 * stats = (trace of Gamma, excitation).  Returns 0, or -1 for bad settings.
 * The identifier's state lives in a buffer of rn_identifier_size() bytes; it is
 * reset before sample reset_at (-1: never). */
size_t rn_identifier_size(void) { return sizeof(RegressorIdentifier); }

int rn_identify(const RigidBodyModel *model, RegressorIdentifier *identifier, int kind, int p, const int columns[],
                const double torque_scale[], double h, double rho, double R, long count,
                const double q[], const double qd[], const double qdd[], const double tau[],
                long reset_at, double delta[], double std_error[], double stats[2])
{
    RegressorIdentifier *id = identifier;
    const int n = model->n;
    if (ri_init(id, (IdentifierKind)kind, n, p, columns, torque_scale, h, rho, R, NULL) != 0)
        return -1;
    double pi[RB_MAX_PARAMETERS];
    rb_get_parameters(model, pi);
    for (long k = 0; k < count; ++k) {
        if (k == reset_at) ri_reset(id);
        RbRegressor Y;
        double nominal[RB_MAX_JOINTS], z[RB_MAX_JOINTS];
        rb_regressor(model, q + k * n, qd + k * n, qdd + k * n, &Y);
        rb_regressor_torque(model, &Y, pi, nominal);
        for (int i = 0; i < n; ++i) z[i] = tau[k * n + i] - nominal[i];
        ri_step(id, z, &Y);
    }
    if (ri_solve(id) != 0) return -1;
    ri_statistics(id);
    memcpy(delta, id->delta, (size_t)p * sizeof(double));
    memcpy(std_error, id->std_error, (size_t)p * sizeof(double));
    stats[0] = id->gamma_trace;
    stats[1] = id->excitation;
    return 0;
}

/* Velocities of each joint by the observer FMU's default estimator without a
 * model (F = 0): the implicit super-twisting observer beside the bank of
 * noise-adaptive linear observers (noise_adaptive.c, scheme 3), one joint at a
 * time, one step per sample, gains from Theorem 3.1 for the acceleration bound
 * f_plus[i] (p = 0.5), tau the injection's filter.  Outputs per sample, count x n
 * row by row: velocity (the published estimate at the sample, after its
 * measurement: causal), acceleration (the published perturbation, here the
 * acceleration), noise (the estimated measurement noise std) and bandwidth
 * (of the published observer, 1/h for the super-twisting one).  The bank is
 * allocated by the caller (rn_adaptive_size() bytes).  nominal (count x n, or
 * NULL: model-free) is a known acceleration held over the interval that starts
 * at each sample.  position (count x n, or NULL: not wanted) receives the published
 * observer's corrected position at each sample.  Returns 0, or -1 for a bound that
 * gives no gains. */
size_t rn_adaptive_size(void) { return sizeof(AdaptiveBank); }

int rn_observe_adaptive(AdaptiveBank *bank, int n, long count, double h, const double y[],
                        const double nominal[], const double f_plus[], double tau,
                        double velocity[], double acceleration[], double noise[],
                        double bandwidth[], double position[])
{
    for (int i = 0; i < n; ++i) {
        double alpha1 = 0.0, alpha2 = 0.0, zero = 0.0, y0 = y[i];
        if (gains_complete(f_plus[i], 0.5, &alpha1, &alpha2) != 0) return -1;
        SuperTwistingObserver o;
        st_init(&o, 1, h, &alpha1, &alpha2, tau, &y0, &zero);
        st_configure(&o, STO_SCHEME_ADAPTIVE, 0.05); /* the FMU's convergence window */
        na_init(bank, h, NULL);
        StoTrace trace;
        for (long k = 0; k < count; ++k) {
            const StoAcceleration a = {.held = nominal ? nominal[k * n + i] : 0.0};
            na_run(&o, bank, y + k * n + i, &a, 1, &trace);
            velocity[k * n + i] = bank->velocity[0];
            if (position) position[k * n + i] = bank->position[0];
            acceleration[k * n + i] = trace.z_filtered[0][0];
            na_outputs(&o, bank);
            noise[k * n + i] = bank->noise_std[0];
            bandwidth[k * n + i] = bank->bandwidth[0];
        }
    }
    return 0;
}

/* The model-based observer and online identification (robot_observer.c) over a
 * log, as the RobotObserver FMU runs them: state in a buffer of
 * rn_robot_run_size() bytes. */
typedef struct {
    RobotObserver observer;
    RobotRegression regression;
    RegressorIdentifier identifier;
    StatisticsJob statistics;
} RobotRun;

size_t rn_robot_run_size(void) { return sizeof(RobotRun); }

/* The settings' size and tuning.h's defaults for n joints (robot_pipeline.h), so
 * that the harness's ctypes Structure is checked against them and keeps no defaults. */
size_t rn_settings_size(void) { return sizeof(RobotSettings); }

void rn_default_settings(int n, RobotSettings *settings) { *settings = rp_default_settings(n); }

/* y, u: count x n, the pipeline set up by `settings` (robot_pipeline.h; gains left at
 * 0 computed from f_plus by Theorem 3.1, as the FMU does).  Outputs per sample:
 * velocity (the estimate at the sample) and prediction (for the end of the interval
 * that starts there, an FMU's output at the next communication point).  With an
 * identifier the identifier runs from sample `start` on (its regression by
 * settings->regression: at the observer's estimates, or a fixed-lag window behind) and
 * delta, std_error,
 * stats = (trace of Gamma, excitation) are solved at the end, and `published`
 * (3 p + 2) holds what the FMU publishes after the last sample under the same
 * schedule (statistics_job.h: a snapshot every statistics_interval seconds, its work
 * spread over the following samples): the estimate Delta (the fresher of the running
 * solution and the last completed solve), the standard errors, trace of Gamma, the
 * excitation and each parameter's column excitation of the last completed solve
 * (before any: 0, p / rho, 0 and 0).  weight
 * (count x n): the weight of each sample's joint equations in the regression (NaN for
 * the samples no row was taken at: before the identifier, the last, the window's
 * last lag), acceleration (count x n): the observer's q'' at each sample (the last
 * sample's: NaN, not known yet).
 * Returns the number of samples at which M was not positive definite, -1 for bad
 * identifier settings, -2 for gains that cannot be computed, -3 if the identifier's
 * information is not positive definite at the end (the observer diverged), -4 for a
 * negative or non-finite min_speed or reversal_margin. */
long rn_robot_observe(const RigidBodyModel *model, RobotRun *run, const RobotSettings *settings,
                      long count, long start, const double y[], const double u[],
                      double velocity[], double prediction[], double weight[],
                      double acceleration[], double delta[], double std_error[],
                      double stats[2], double published[])
{
    const int n = model->n, kind = settings->identifier, p = settings->p;
    if (n != settings->n) return -1;
    const RobotPipeline pipeline = {&run->observer, &run->regression, &run->identifier,
                                    &run->statistics};
    switch (rp_init(&pipeline, model, settings, y, NULL)) {
    case RP_OK:
        break;
    case RP_NO_GAINS:
        return -2;
    case RP_BAD_REGRESSION:
        return -4;
    case RP_BAD_IDENTIFIER:
        return -1;
    }
    for (long k = 0; k < count * n; ++k) weight[k] = acceleration[k] = NAN;
    for (long k = 0; k < count; ++k) {
        const int identifying = kind && k >= start;
        rp_run(&pipeline, model, y + k * n, u + k * n, 0, 1,
               !kind ? RP_NEVER : k == start ? 0 : identifying ? RP_ALREADY : RP_NEVER);
        /* the FMU's communication point after the sample (doStep(t_k, h)) */
        rp_communicate(&pipeline);
        for (int i = 0; i < n; ++i) {
            velocity[k * n + i] = ro_velocity(&run->observer, i);
            prediction[k * n + i] = run->observer.x2_hat[i];
            const long row = k - ro_regression_lag(&run->regression);
            if (run->regression.entered && row >= 0)
                weight[row * n + i] = ro_regression_weight(&run->regression, i);
            if (k > 0) acceleration[(k - 1) * n + i] = run->observer.previous_acceleration[i];
        }
    }
    if (kind) {
        const StatisticsJob *job = &run->statistics;
        const int solved = job->completed > 0.0;
        memcpy(published, sj_freshest_estimate(job, &run->identifier), (size_t)p * sizeof(double));
        for (int k = 0; k < p; ++k) published[p + k] = solved ? job->std_error[k] : 0.0;
        published[2 * p] = solved ? job->gamma_trace : p / settings->rho;
        published[2 * p + 1] = solved ? job->excitation : 0.0;
        for (int k = 0; k < p; ++k)
            published[2 * p + 2 + k] = solved ? job->column_excitation[k] : 0.0;
        if (ri_solve(&run->identifier) != 0) return -3;
        ri_statistics(&run->identifier);
        memcpy(delta, run->identifier.delta, (size_t)p * sizeof(double));
        memcpy(std_error, run->identifier.std_error, (size_t)p * sizeof(double));
        stats[0] = run->identifier.gamma_trace;
        stats[1] = run->identifier.excitation;
    }
    return (long)run->observer.model_failures;
}
