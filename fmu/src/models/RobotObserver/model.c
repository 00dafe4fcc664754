/* RobotObserver: the model-based velocity observer and the online
 * identification of a serial robot (up to 7 revolute or prismatic joints)
 * with its rigid-body model built in (core/robot_observer.h).
 *
 * The robot's kinematic and inertial data are parameters, in the flat form
 * of rigid_body.h's rb_load (what `python -m harness robot-fmu-parameters
 * ROBOT.urdf` writes from a URDF, with the base columns of the regressor and
 * the nominal base parameters).  Inputs: joint positions q and torques u,
 * held over each communication step.  Each internal step: the observer's
 * corrector, the forward dynamics at the corrected state, and (identifier on)
 * the regressor, one identifier step and a slice of the solve with standard
 * errors (statistics_job.h: a snapshot at a communication point at least
 * statistics_interval seconds after the last, its O(p^3) work spread over the
 * following internal steps).  At communication
 * points: the estimates (the fresher of the identifier's running solution and
 * the last completed solve) and the last completed solve's statistics.
 * Value references are stable and documented in docs/robots.md. */
#include <math.h>
#include <stddef.h>
#include <string.h>

#include "../../core/gains.h"
#include "../../core/regressor_identifier.h"
#include "../../core/rigid_body.h"
#include "../../core/robot_observer.h"
#include "../../core/robot_pipeline.h"
#include "../../core/statistics_job.h"
#include "../../instance/model_interface.h"
#include "../fixed_lag_outputs.h"
#include "../input_cadence_outputs.h"
#include "../state_fields.h"

#define MAX_N RB_MAX_JOINTS
#define MAX_P RB_MAX_PARAMETERS

typedef struct {
    /* parameters */
    double h;
    int n, identifier, base_count, regression_kind;
    double tau, convergence_window, rho, R, t_id, statistics_interval, coulomb_velocity, p;
    double min_speed, reversal_margin;
    double gravity[3];
    int joint_type[MAX_N];
    double axis[MAX_N][3], xyz[MAX_N][3], rpy[MAX_N][3];
    double link[MAX_N][RB_LINK_PARAMETERS], friction[MAX_N][RB_JOINT_FRICTION];
    double f_plus[MAX_N], alpha1[MAX_N], alpha2[MAX_N], torque_scale[MAX_N];
    int base_columns[MAX_P];
    double base_nominal[MAX_P];
    int max_internal_steps;
    double max_work, input_period;
    /* calculated parameters */
    double alpha1_used[MAX_N], alpha2_used[MAX_N];
    double work_per_step;
    /* inputs */
    double q[MAX_N], u[MAX_N];
    int identifier_reset;
    /* outputs */
    double q_hat[MAX_N], qd_hat[MAX_N], qd_sample[MAX_N], base_estimate[MAX_P], base_std[MAX_P],
        base_excitation[MAX_P];
    double gamma_trace, excitation, input_hold, identifier_cutoff;
    int identifier_active, converged, coarse_inputs;
    /* state */
    RigidBodyModel model;
    RobotObserver obs;
    RobotRegression regression;
    RegressorIdentifier id;
    StatisticsJob statistics;
    int reset_seen;
    double failures_seen;   /* obs.model_failures at the last communication point */
    double statistics_seen; /* statistics.completed at the last communication point */
    InputCadence cadence;   /* of the positions and torques */
    int coarse_logged;      /* the staircase warning stands */
} RobotData;
_Static_assert(2 * MAX_N <= IC_MAX_VALUES, "the cadence watches every position and torque");

#define OFF(field) offsetof(RobotData, field)

/* The default robot: two revolute joints about x (a double pendulum standing
 * upright at q = 0), 1 kg links with the centre of mass 5 cm up the link,
 * joint 2 10 cm above joint 1.  Joints 3..7 (unused at n = 2) repeat them. */
#define LINK_START 1.0, 0.0, 0.0, 0.05, 0.0035, 0.0, 0.0035, 0.0, 0.0, 0.0005
static const double LINK_STARTS[MAX_N * RB_LINK_PARAMETERS] = {
    LINK_START, LINK_START, LINK_START, LINK_START, LINK_START, LINK_START, LINK_START};
static const double AXIS_STARTS[MAX_N * 3] = {1, 0, 0, 1, 0, 0, 1, 0, 0, 1, 0, 0,
                                               1, 0, 0, 1, 0, 0, 1, 0, 0};
static const double XYZ_STARTS[MAX_N * 3] = {0, 0, 0, 0, 0, 0.1, 0, 0, 0.1, 0, 0, 0.1,
                                              0, 0, 0.1, 0, 0, 0.1, 0, 0, 0.1};
static const double GRAVITY_START[3] = {0.0, 0.0, -9.81};
/* Friction of joints 1 and 2 (viscous, Coulomb): always base parameters. */
static const double COLUMN_STARTS[MAX_P] = {20, 21, 22, 23};

static const ModelVariable VARIABLES[] = {
    {.name = "h", .vr = 1, .type = TYPE_REAL, PARAM(.offset = OFF(h), .start = RO_STEP, .min = 0.0,
     .max = 1.0, .min_exclusive = true, .unit = "s",
     .description = "Fixed internal step (the sampling period of q and u)")},
    {.name = "n", .vr = 2, .type = TYPE_INTEGER, PARAM(.offset = OFF(n), .start = 2, .min = 1,
     .max = MAX_N, .description = "Number of joints (active rows of the joint arrays)")},
    {.name = "identifier", .vr = 3, .type = TYPE_INTEGER, PARAM(.offset = OFF(identifier),
     .start = IDENTIFIER_LSM, .min = 0, .max = 2,
     .description = "Base-parameter identifier: 0 off, 1 least squares, 2 matrix forgetting "
                    "factor")},
    {.name = "base_count", .vr = 4, .type = TYPE_INTEGER, PARAM(.offset = OFF(base_count),
     .start = 4, .min = 1, .max = MAX_P,
     .description = "Number of identified base parameters (entries of base_columns)")},
    {.name = "tau", .vr = 5, .type = TYPE_REAL, PARAM(.offset = OFF(tau), .start = RO_TAU,
     .min = 0.0, .max = NAN, .unit = "s",
     .description = "Time constant of the filter of the injection and of the regression "
                    "(the regressor Y(q, q', q'') and the torque residual); 0: none")},
    {.name = "convergence_window", .vr = 6, .type = TYPE_REAL,
     PARAM(.offset = OFF(convergence_window), .start = RO_CONVERGENCE_WINDOW, .min = 0.0,
     .max = NAN, .min_exclusive = true, .unit = "s",
     .description = "Time constant of the convergence test (rate of sign switching of e)")},
    {.name = "rho", .vr = 7, .type = TYPE_REAL, PARAM(.offset = OFF(rho), .start = RO_RHO,
     .min = 0.0, .max = NAN, .min_exclusive = true,
     .description = "Regularization of the identifier: Gamma <= I/rho")},
    {.name = "R", .vr = 8, .type = TYPE_REAL, PARAM(.offset = OFF(R), .start = RO_R, .min = 0.0,
     .max = 1.0, .min_exclusive = true, .max_exclusive = true,
     .description = "MFF forgetting factor per second")},
    {.name = "t_id", .vr = 9, .type = TYPE_REAL, PARAM(.offset = OFF(t_id), .start = 0.2,
     UNBOUNDED, .unit = "s",
     .description = "Time at which the identifier starts (after the observer's transient)")},
    {.name = "statistics_interval", .vr = 11, .type = TYPE_REAL,
     PARAM(.offset = OFF(statistics_interval), .start = RO_STATISTICS_INTERVAL, .min = 0.0,
     .max = NAN, .unit = "s",
     .description = "Least time between the snapshots of solves with standard errors, whose "
                    "p^3 operations are spread over the internal steps after each (published "
                    "when complete); the estimates in between: the identifier's running "
                    "solution; 0: a solve as soon as the last completes")},
    {.name = "coulomb_velocity", .vr = 12, .type = TYPE_REAL,
     PARAM(.offset = OFF(coulomb_velocity), .start = 0.0, .min = 0.0, .max = NAN,
     .unit = "rad/s",
     .description = "Coulomb friction f_c sat(q'/v) below this velocity v; 0: f_c sign(q')")},
    {.name = "p", .vr = 13, .type = TYPE_REAL, PARAM(.offset = OFF(p), .start = RO_GAIN_EXPONENT,
     .min = 0.0, .max = 1.0, .min_exclusive = true, .max_exclusive = true,
     .description = "Constant p of condition (6) for the gains computed from f_plus")},
    {.name = "gravity", .vr = 14, .rows = 3, .type = TYPE_REAL,
     PARAM(.offset = OFF(gravity), .starts = GRAVITY_START, UNBOUNDED, .unit = "m/s2",
     .description = "Gravity in the base frame")},
    {.name = "regression", .vr = 19, .type = TYPE_INTEGER,
     PARAM(.offset = OFF(regression_kind), .start = RO_REGRESSION_WINDOW, .min = 0, .max = 1,
     .description = "What the identifier regresses on: 1 the positions and torques smoothed "
                    "by a zero-phase window a fixed lag behind the newest sample, its cut-off "
                    "chosen from the measurement noise (identifier_cutoff); 0 the observer's "
                    "causal estimates (the paper's scheme)")},
    {.name = "min_speed", .vr = 17, .type = TYPE_REAL, PARAM(.offset = OFF(min_speed),
     .start = RO_MIN_SPEED, .min = 0.0, .max = NAN, .unit = "rad/s",
     .description = "The identifier leaves out joint i's equation where |q_i'| is below this "
                    "speed (rad/s, or m/s for a prismatic joint) or q_i' reverses, and for "
                    "reversal_margin after (with regression = 1 also for 1.5 periods of "
                    "identifier_cutoff on both sides): there Coulomb friction is not "
                    "f_c sign(q')")},
    {.name = "reversal_margin", .vr = 18, .type = TYPE_REAL,
     PARAM(.offset = OFF(reversal_margin), .start = RO_REVERSAL_MARGIN, .min = 0.0, .max = NAN,
     .unit = "s",
     .description = "Time after a slow or reversing sample of a joint during which its "
                    "equation is still left out (min_speed and reversal_margin both 0: every "
                    "equation is used)")},
    {.name = "joint_type", .vr = 20, .rows = MAX_N, .type = TYPE_INTEGER,
     PARAM(.offset = OFF(joint_type), .start = RB_REVOLUTE, .min = 0, .max = 1,
     .description = "0 revolute, 1 prismatic")},
    {.name = "axis", .vr = 30, .rows = MAX_N, .cols = 3, .type = TYPE_REAL,
     PARAM(.offset = OFF(axis), .starts = AXIS_STARTS, UNBOUNDED,
     .description = "Joint axis in the joint's frame (URDF <axis xyz>; normalized)")},
    {.name = "xyz", .vr = 51, .rows = MAX_N, .cols = 3, .type = TYPE_REAL,
     PARAM(.offset = OFF(xyz), .starts = XYZ_STARTS, UNBOUNDED, .unit = "m",
     .description = "Joint placement in the previous joint's frame (URDF <origin xyz>)")},
    {.name = "rpy", .vr = 72, .rows = MAX_N, .cols = 3, .type = TYPE_REAL,
     PARAM(.offset = OFF(rpy), .start = 0.0, UNBOUNDED, .unit = "rad",
     .description = "Joint placement rotation (URDF <origin rpy>)")},
    {.name = "link", .vr = 130, .rows = MAX_N, .cols = RB_LINK_PARAMETERS, .type = TYPE_REAL,
     PARAM(.offset = OFF(link), .starts = LINK_STARTS, UNBOUNDED,
     .description = "Standard parameters of each link in its joint frame: m, m c_x, m c_y, "
                    "m c_z, I_xx, I_xy, I_yy, I_xz, I_yz, I_zz (inertia about the frame origin)")},
    {.name = "friction", .vr = 200, .rows = MAX_N, .cols = RB_JOINT_FRICTION, .type = TYPE_REAL,
     PARAM(.offset = OFF(friction), .start = 0.0, .min = 0.0, .max = NAN,
     .description = "Nominal joint friction: viscous [N.m.s/rad], Coulomb [N.m]")},
    {.name = "f_plus", .vr = 220, .rows = MAX_N, .type = TYPE_REAL,
     PARAM(.offset = OFF(f_plus), .start = RO_F_PLUS, .min = 0.0, .max = NAN, .unit = "rad/s2",
     .description = "Bound f+ on the model's acceleration error (gains by Theorem 3.1)")},
    {.name = "alpha1", .vr = 230, .rows = MAX_N, .type = TYPE_REAL,
     PARAM(.offset = OFF(alpha1), .start = 0.0, .min = 0.0, .max = NAN, .unit = "rad/s2",
     .description = "Gain of alpha1 sign(e); 0: computed from f_plus by Theorem 3.1")},
    {.name = "alpha2", .vr = 240, .rows = MAX_N, .type = TYPE_REAL,
     PARAM(.offset = OFF(alpha2), .start = 0.0, .min = 0.0, .max = NAN,
     .description = "Gain of alpha2 |e|^(1/2) sign(e); 0: computed by Theorem 3.1")},
    {.name = "torque_scale", .vr = 250, .rows = MAX_N, .type = TYPE_REAL,
     PARAM(.offset = OFF(torque_scale), .start = 1.0, .min = 0.0, .max = NAN,
     .min_exclusive = true, .unit = "N.m",
     .description = "Per-joint torque scale s_i: the identifier weighs joint i by 1/s_i^2")},
    {.name = "base_columns", .vr = 300, .rows = MAX_P, .type = TYPE_INTEGER,
     PARAM(.offset = OFF(base_columns), .starts = COLUMN_STARTS, .min = 0, .max = MAX_P - 1,
     .description = "Columns of the regressor (0-based, link parameters then friction) of "
                    "the identified base parameters")},
    {.name = "base_nominal", .vr = 400, .rows = MAX_P, .type = TYPE_REAL,
     PARAM(.offset = OFF(base_nominal), .start = 0.0, UNBOUNDED,
     .description = "The base parameters of the nominal model (the estimates start here)")},
    MAX_INTERNAL_STEPS_VARIABLE(OFF(max_internal_steps)),
    WORK_VARIABLES(OFF(max_work), OFF(work_per_step)),
    {.name = "alpha1_used", .vr = 500, .rows = MAX_N, .type = TYPE_REAL,
     CALC(.offset = OFF(alpha1_used), .unit = "rad/s2",
     .description = "alpha1 in use (given, or from Theorem 3.1)")},
    {.name = "alpha2_used", .vr = 510, .rows = MAX_N, .type = TYPE_REAL,
     CALC(.offset = OFF(alpha2_used), .description = "alpha2 in use (given, or from Theorem 3.1)")},
    {.name = "q", .vr = 600, .rows = MAX_N, .type = TYPE_REAL,
     INPUT(.offset = OFF(q), .unit = "rad", .description = "Measured joint positions")},
    {.name = "u", .vr = 610, .rows = MAX_N, .type = TYPE_REAL,
     INPUT(.offset = OFF(u), .unit = "N.m", .description = "Joint torques (forces)")},
    {.name = "identifier_reset", .vr = 620, .type = TYPE_BOOLEAN,
     .causality = CAUSALITY_INPUT, .variability = VARIABILITY_DISCRETE, UNBOUNDED,
     .offset = OFF(identifier_reset),
     .description = "A rising edge restarts identification from the nominal parameters"},
    {.name = "q_hat", .vr = 700, .rows = MAX_N, .type = TYPE_REAL,
     OUTPUT(.offset = OFF(q_hat), .unit = "rad",
     .description = "Position estimate at the end of the communication step")},
    {.name = "qd_hat", .vr = 710, .rows = MAX_N, .type = TYPE_REAL,
     OUTPUT(.offset = OFF(qd_hat), .unit = "rad/s",
     .description = "Velocity estimate at the end of the communication step")},
    {.name = "qd_sample", .vr = 720, .rows = MAX_N, .type = TYPE_REAL,
     OUTPUT(.offset = OFF(qd_sample), .unit = "rad/s",
     .description = "Velocity estimate at the last sample (h before the end of the "
                    "communication step): more accurate than qd_hat, which predicts over h")},
    {.name = "base_estimate", .vr = 800, .rows = MAX_P, .type = TYPE_REAL,
     OUTPUT(.offset = OFF(base_estimate),
     .description = "Identified base parameters (base_nominal plus the identified change)")},
    {.name = "base_std", .vr = 900, .rows = MAX_P, .type = TYPE_REAL,
     OUTPUT(.offset = OFF(base_std),
     .description = "Standard errors of base_estimate (sandwich formula, at the snapshot of "
                    "the last completed solve with statistics)")},
    {.name = "base_excitation", .vr = 1100, .rows = MAX_P, .type = TYPE_REAL,
     OUTPUT(.offset = OFF(base_excitation),
     .description = "Share of each base parameter's regressor column that the others do not "
                    "explain, sqrt(1 - R^2) of the identifier's information: 0 (not excited, "
                    "or a combination of the others) to 1 (orthogonal); below 0.001 the log "
                    "does not determine it. At the last completed solve with statistics")},
    {.name = "gamma_trace", .vr = 1000, .type = TYPE_REAL,
     OUTPUT(.offset = OFF(gamma_trace), .description = "Trace of the identifier's Gamma")},
    {.name = "excitation", .vr = 1001, .type = TYPE_REAL,
     OUTPUT(.offset = OFF(excitation),
     .description = "Smallest eigenvalue of the identifier's information per unit time; near "
                    "0: some base parameter is not being learned")},
    {.name = "identifier_active", .vr = 1002, .type = TYPE_BOOLEAN,
     .causality = CAUSALITY_OUTPUT, .variability = VARIABILITY_DISCRETE, UNBOUNDED,
     .offset = OFF(identifier_active), .description = "The identifier is integrating"},
    {.name = "converged", .vr = 1003, .type = TYPE_BOOLEAN,
     .causality = CAUSALITY_OUTPUT, .variability = VARIABILITY_DISCRETE, UNBOUNDED,
     .offset = OFF(converged),
     .description = "Every joint's observer is in its sliding mode by the switching-rate test"},
    INPUT_CADENCE_VARIABLES(1004, OFF(input_hold), OFF(coarse_inputs), OFF(input_period)),
    IDENTIFIER_CUTOFF_VARIABLE(1010, OFF(identifier_cutoff)),
};

/* Mass >= 0 and, with mass, a positive definite inertia about the centre of
 * mass; logs and returns MODEL_ERROR otherwise. */
static ModelStatus check_link(const RobotData *d, int i, const ModelLogger *log)
{
    const double *l = d->link[i], m = l[RB_MASS];
    if (!(m >= 0.0)) {
        log->log(log->context, MODEL_ERROR, "link[%d]: negative mass %g", i + 1, m);
        return MODEL_ERROR;
    }
    if (m == 0.0) return MODEL_OK; /* a massless link: M's definiteness is checked at q */
    const double c[3] = {l[1] / m, l[2] / m, l[3] / m};
    const double cc = c[0] * c[0] + c[1] * c[1] + c[2] * c[2];
    /* inertia about the centre of mass: I_o - m (|c|^2 1 - c c^T) */
    const double xx = l[4] - m * (cc - c[0] * c[0]), yy = l[6] - m * (cc - c[1] * c[1]);
    const double zz = l[9] - m * (cc - c[2] * c[2]);
    const double xy = l[5] + m * c[0] * c[1], xz = l[7] + m * c[0] * c[2];
    const double yz = l[8] + m * c[1] * c[2];
    const double minor2 = xx * yy - xy * xy;
    const double det = xx * (yy * zz - yz * yz) - xy * (xy * zz - yz * xz) + xz * (xy * yz - yy * xz);
    if (!(xx > 0.0 && minor2 > 0.0 && det > 0.0)) {
        log->log(log->context, MODEL_ERROR,
                 "link[%d]: the inertia about the centre of mass (xx %g, yy %g, zz %g, xy %g, "
                 "xz %g, yz %g) is not positive definite: no rigid body has it", i + 1, xx, yy,
                 zz, xy, xz, yz);
        return MODEL_ERROR;
    }
    return MODEL_OK;
}

static ModelStatus load_model(RobotData *d, const ModelLogger *log)
{
    const int n = d->n;
    for (int i = 0; i < n; ++i) {
        const double *a = d->axis[i];
        if (!(a[0] * a[0] + a[1] * a[1] + a[2] * a[2] > 0.0)) {
            log->log(log->context, MODEL_ERROR, "axis[%d] = (%g, %g, %g) is zero: joint %d has "
                     "no direction", i + 1, a[0], a[1], a[2], i + 1);
            return MODEL_ERROR;
        }
        if (check_link(d, i, log) != MODEL_OK) return MODEL_ERROR;
    }
    const RbStatus status = rb_load(&d->model, n, d->joint_type, &d->axis[0][0], &d->xyz[0][0],
                                    &d->rpy[0][0], &d->link[0][0], &d->friction[0][0],
                                    d->gravity, d->coulomb_velocity);
    if (status != RB_OK) {
        log->log(log->context, MODEL_ERROR, "the robot's parameters are refused: %s",
                 rb_status_text(status));
        return MODEL_ERROR;
    }
    double qd[MAX_N] = {0}, qdd[MAX_N];
    if (rb_forward_dynamics(&d->model, d->q, qd, d->u, qdd) != 0) {
        log->log(log->context, MODEL_ERROR,
                 "the joint-space inertia matrix M(q) of the robot's parameters is not positive "
                 "definite at the start positions q (a joint moves no mass; check link and the "
                 "joint axes of the %d joints)", n);
        return MODEL_ERROR;
    }
    return MODEL_OK;
}

static ModelStatus check_columns(const RobotData *d, const ModelLogger *log)
{
    const int columns = RB_PARAMETERS_PER_JOINT * d->n;
    if (d->base_count > columns) {
        log->log(log->context, MODEL_ERROR, "base_count = %d exceeds the %d columns of a %d-joint "
                 "regressor", d->base_count, columns, d->n);
        return MODEL_ERROR;
    }
    for (int k = 0; k < d->base_count; ++k) {
        if (d->base_columns[k] >= columns) {
            log->log(log->context, MODEL_ERROR, "base_columns[%d] = %d: a %d-joint regressor has "
                     "columns 0..%d", k + 1, d->base_columns[k], d->n, columns - 1);
            return MODEL_ERROR;
        }
        for (int j = 0; j < k; ++j)
            if (d->base_columns[j] == d->base_columns[k]) {
                log->log(log->context, MODEL_ERROR, "base_columns[%d] and base_columns[%d] are "
                         "both %d", j + 1, k + 1, d->base_columns[k]);
                return MODEL_ERROR;
            }
    }
    return MODEL_OK;
}

/* The pipeline's settings from the parameters. */
static RobotSettings settings_of(const RobotData *d)
{
    RobotSettings s = rp_default_settings(d->n);
    s.identifier = d->identifier;
    s.regression = d->regression_kind;
    s.p = d->base_count;
    memcpy(s.columns, d->base_columns, sizeof d->base_columns);
    s.h = d->h;
    s.tau = d->tau;
    s.convergence_window = d->convergence_window;
    s.gain_exponent = d->p;
    s.rho = d->rho;
    s.R = d->R;
    s.min_speed = d->min_speed;
    s.reversal_margin = d->reversal_margin;
    s.statistics_interval = d->statistics_interval;
    memcpy(s.f_plus, d->f_plus, sizeof d->f_plus);
    memcpy(s.alpha1, d->alpha1, sizeof d->alpha1);
    memcpy(s.alpha2, d->alpha2, sizeof d->alpha2);
    memcpy(s.torque_scale, d->torque_scale, sizeof d->torque_scale);
    return s;
}

/* Sets the pipeline up, saying which setting it refuses. */
static ModelStatus init_pipeline(RobotData *d, const ModelLogger *log)
{
    const RobotSettings settings = settings_of(d);
    const RobotPipeline pipeline = {&d->obs, &d->regression, &d->id, &d->statistics};
    int i = 0;
    switch (rp_init(&pipeline, &d->model, &settings, d->q, &i)) {
    case RP_OK:
        break;
    case RP_NO_GAINS:
        log->log(log->context, MODEL_ERROR,
                 "joint %d: no gains from f_plus[%d] = %g, alpha1[%d] = %g, alpha2[%d] = %g "
                 "(a gain left at 0 needs f_plus > 0, and alpha1 > f_plus, by Theorem 3.1)",
                 i + 1, i + 1, d->f_plus[i], i + 1, d->alpha1[i], i + 1, d->alpha2[i]);
        return MODEL_ERROR;
    case RP_BAD_REGRESSION:
        log->log(log->context, MODEL_ERROR, "min_speed = %g and reversal_margin = %g must be "
                 "finite and >= 0, and h = %g positive", d->min_speed, d->reversal_margin, d->h);
        return MODEL_ERROR;
    case RP_BAD_IDENTIFIER:
        log->log(log->context, MODEL_ERROR, "the identifier refused its settings (h = %g, rho = "
                 "%g, R = %g)", d->h, d->rho, d->R);
        return MODEL_ERROR;
    }
    memcpy(d->alpha1_used, d->obs.alpha1, (size_t)d->n * sizeof d->alpha1_used[0]);
    memcpy(d->alpha2_used, d->obs.alpha2, (size_t)d->n * sizeof d->alpha2_used[0]);
    return MODEL_OK;
}

static void publish_estimates(RobotData *d)
{
    const StatisticsJob *job = &d->statistics;
    /* the running solution (at most 32 samples old), or the last solve's if fresher */
    const double *delta = sj_freshest_estimate(job, &d->id);
    if (d->identifier && job->completed > d->statistics_seen) {
        d->statistics_seen = job->completed;
        for (int k = 0; k < d->base_count; ++k) {
            d->base_std[k] = job->std_error[k];
            d->base_excitation[k] = job->column_excitation[k];
        }
        d->gamma_trace = job->gamma_trace;
        d->excitation = job->excitation;
    }
    for (int k = 0; k < d->base_count; ++k)
        d->base_estimate[k] = d->base_nominal[k] + (d->identifier ? delta[k] : 0.0);
    for (int i = 0; i < d->n; ++i) {
        d->q_hat[i] = d->obs.x1_hat[i];
        d->qd_hat[i] = d->obs.x2_hat[i];
        d->qd_sample[i] = d->obs.primed ? ro_velocity(&d->obs, i) : d->obs.x2_hat[i];
    }
    d->converged = d->obs.steps > 0.0 && ro_converged(&d->obs);
    d->identifier_cutoff = d->identifier && d->regression_kind == RO_REGRESSION_WINDOW
                               ? fl_cutoff(&d->regression.window) : 0.0;
    d->input_hold = ic_shortest(&d->cadence) * d->h;
    d->coarse_inputs = ic_coarse(&d->cadence);
}

/* The positions then the torques: what the cadence watches. */
static int measured(const RobotData *d, double values[])
{
    memcpy(values, d->q, (size_t)d->n * sizeof values[0]);
    memcpy(values + d->n, d->u, (size_t)d->n * sizeof values[0]);
    return 2 * d->n;
}

/* Work units (about ns, model_interface.h) of one internal step: upper bounds
 * of the time measured for 1-7 joints and 2n-12n parameters (docs/robots.md):
 * the corrector and the forward dynamics per joint, then the identifier's rank-n
 * update of its p-parameter sums (structural zeros skipped) and the statistics
 * job's fixed slice; through the window, its kernels over each joint's position
 * (three, and the velocity ahead) and torque at the longest window. */
static double step_work(const RobotData *d)
{
    const double n = d->n, p = d->base_count;
    const double window = d->regression_kind == RO_REGRESSION_WINDOW ? 5.0 * n * FL_MAX_HALF : 0.0;
    return 400.0 * n + (d->identifier ? 1000.0 + n * p * (p + 3.0) / 6.0 + window : 0.0);
}

static ModelStatus initialize(void *data, double start_time, const ModelLogger *log)
{
    (void)start_time;
    RobotData *d = data;
    if (load_model(d, log) != MODEL_OK) return MODEL_ERROR;
    if (d->identifier && check_columns(d, log) != MODEL_OK) return MODEL_ERROR;
    if (init_pipeline(d, log) != MODEL_OK) return MODEL_ERROR;
    memset(d->base_std, 0, sizeof d->base_std);
    memset(d->base_excitation, 0, sizeof d->base_excitation);
    memset(d->base_estimate, 0, sizeof d->base_estimate);
    d->gamma_trace = d->identifier ? d->id.gamma_trace : 0.0;
    d->excitation = 0.0;
    d->identifier_active = 0;
    d->reset_seen = d->identifier_reset;
    d->failures_seen = 0.0;
    d->statistics_seen = 0.0;
    double values[IC_MAX_VALUES];
    const int count = measured(d, values);
    ic_init(&d->cadence, count, values, d->h, d->input_period);
    d->coarse_logged = 0;
    d->work_per_step = step_work(d);
    publish_estimates(d);
    return MODEL_OK;
}

static double internal_step(const void *data) { return ((const RobotData *)data)->h; }

static double max_work(const void *data) { return ((const RobotData *)data)->max_work; }

static double work_per_step(const void *data)
{
    return ((const RobotData *)data)->work_per_step;
}

static uint64_t max_internal_steps(const void *data)
{
    return (uint64_t)((const RobotData *)data)->max_internal_steps;
}

static void advance(void *data, double start_time, uint64_t k, uint64_t k_end)
{
    RobotData *d = data;
    if (d->identifier && d->identifier_reset != d->reset_seen) {
        d->reset_seen = d->identifier_reset;
        if (d->identifier_reset) {
            ri_reset(&d->id);
            sj_reset(&d->statistics);
            d->identifier_active = 0;
        }
    }
    double values[IC_MAX_VALUES];
    measured(d, values);
    ic_advance(&d->cadence, values, k_end - k);
    /* the identifier joins at the first internal step at or after t_id */
    long join = d->identifier_active ? RP_ALREADY : RP_NEVER;
    for (uint64_t j = k; d->identifier && join == RP_NEVER && j < k_end; ++j)
        if (start_time + (double)j * d->h >= d->t_id) join = (long)(j - k);
    const RobotPipeline pipeline = {&d->obs, d->identifier ? &d->regression : NULL, &d->id,
                                     &d->statistics};
    rp_run(&pipeline, &d->model, d->q, d->u, 0, (long)(k_end - k), join);
    if (join >= 0) d->identifier_active = 1;
}

static ModelStatus communication_point(void *data, double t, const ModelLogger *log)
{
    RobotData *d = data;
    const RobotPipeline pipeline = {&d->obs, NULL, &d->id, &d->statistics};
    rp_communicate(&pipeline);
    publish_estimates(d);
    log_cadence(&d->coarse_logged, d->coarse_inputs, d->input_hold, d->h, t, log);
    if (d->obs.model_failures > d->failures_seen) {
        d->failures_seen = d->obs.model_failures;
        log->log(log->context, MODEL_ERROR,
                 "the inertia matrix M(q) is not positive definite at t = %g (q[1] = %g): the "
                 "robot's inertial parameters are not physical there", t, d->q[0]);
        return MODEL_ERROR;
    }
    for (int i = 0; i < d->n; ++i) {
        if (!isfinite(d->q_hat[i]) || !isfinite(d->qd_hat[i])) {
            log->log(log->context, MODEL_ERROR,
                     "observer diverged at t = %g: q_hat[%d] = %g, qd_hat[%d] = %g (q[%d] = %g, "
                     "u[%d] = %g): the model's acceleration error exceeds what the gains "
                     "(alpha1_used[%d] = %g) correct; raise f_plus[%d] or correct the model",
                     t, i + 1, d->q_hat[i], i + 1, d->qd_hat[i], i + 1, d->q[i], i + 1, d->u[i],
                     i + 1, d->alpha1_used[i], i + 1);
            return MODEL_ERROR;
        }
    }
    return MODEL_OK;
}

/* A deserialized state, field by field (model_interface.h): the robot model and
 * every size, index list and constant that initialize derives from the
 * parameters must be what it derives from the state's own; the counters the
 * steps move must lie in their ranges; every double not listed must be finite. */
#define D(field) DERIVED_FIELD(RobotData, field)
#define I(field, lo, hi) STATE_FIELD(RobotData, field, FIELD_INT, lo, hi)
#define R(field, lo, hi) STATE_FIELD(RobotData, field, FIELD_REAL, lo, hi)
static const StateField STATE_FIELDS[] = {
    D(model), I(reset_seen, 0, 1), R(failures_seen, 0.0, NAN), R(statistics_seen, 0.0, NAN),
    IC_STATE_FIELDS(RobotData, cadence), I(coarse_logged, 0, 1),
    D(obs.n), D(obs.h), D(obs.h_squared), D(obs.inverse_h_squared), D(obs.filter_gain),
    D(obs.rate_gain), D(obs.alpha1), D(obs.alpha2), I(obs.primed, 0, 1),
    R(obs.steps, 0.0, NAN), R(obs.model_failures, 0.0, NAN),
    D(regression.gain), D(regression.min_speed), D(regression.margin_samples),
    D(regression.reversals), D(regression.pi_nominal), I(regression.have_previous, 0, 1),
    I(regression.have_older, 0, 1), I(regression.started, 0, 1),
    I(regression.settled, 0, 2147483647), R(regression.weight, 0.0, 1.0),
    D(regression.kind), I(regression.entered, 0, 1), FL_STATE_FIELDS(RobotData, regression.window),
    RRI_STATE_FIELDS(RobotData, id), SJ_STATE_FIELDS(RobotData, statistics),
    /* the doubles, named by their struct */
    REAL_FIELDS(RobotData, obs), REAL_FIELDS(RobotData, regression), REAL_FIELDS(RobotData, id),
    REAL_FIELDS(RobotData, statistics),
};
#undef D
#undef I
#undef R

/* What the field table cannot state: positions below a count held in another field. */
static ModelStatus check_restored(const void *data, const void *initialized,
                                  const ModelLogger *log)
{
    const RobotData *d = data;
    (void)initialized;
    if (check_cadence(&d->cadence, log) != MODEL_OK) return MODEL_ERROR;
    const StatisticsJob *job = &d->statistics;
    const int index_limit = job->stage == SJ_EIGEN ? STATS_EIGEN_ITERATIONS : job->p;
    if (d->id.anchor_unit > d->id.p + 2 ||
        (d->identifier && d->id.batch_age >= d->id.batch_samples)) {
        log->log(log->context, MODEL_ERROR, "deserialized FMU state: id.anchor_unit = %d or "
                 "id.batch_age = %d is out of range for p = %d, batch_samples = %d; state refused",
                 d->id.anchor_unit, d->id.batch_age, d->id.p, d->id.batch_samples);
        return MODEL_ERROR;
    }
    if (job->stage != SJ_IDLE && job->stage != SJ_ESTIMATE && job->index >= index_limit) {
        log->log(log->context, MODEL_ERROR, "deserialized FMU state: statistics.index = %d is "
                 "out of range for its stage %d (below %d); state refused", job->index,
                 job->stage, index_limit);
        return MODEL_ERROR;
    }
    return MODEL_OK;
}

const ModelDescriptor MODEL_DESCRIPTOR = {
    .model_name = "RobotObserver",
    .model_identifier = "RobotObserver",
    .guid = "{3c9e5a71-0b4d-4f6e-8a2c-7d1e9f4b6a53}",
    .description = "Model-based super-twisting velocity observer and base-parameter identifier "
                   "for serial robots of up to 7 joints, with the rigid-body model built in",
    .variables = VARIABLES,
    .n_variables = sizeof VARIABLES / sizeof VARIABLES[0],
    .data_size = sizeof(RobotData),
    .default_stop_time = 1.0,
    .default_tolerance = 1e-6,
    .initialize = initialize,
    .internal_step = internal_step,
    .max_internal_steps = max_internal_steps,
    .max_work = max_work,
    .work_per_step = work_per_step,
    .advance = advance,
    .communication_point = communication_point,
    .state_fields = STATE_FIELDS,
    .n_state_fields = sizeof STATE_FIELDS / sizeof STATE_FIELDS[0],
    .check_restored = check_restored,
};
