/* A model-based velocity observer for a serial robot of n <= RB_MAX_JOINTS
 * joints, and the online identification of its base parameters from the
 * observed state.  Plain C, no allocation, no FMI types.
 *
 * Observer: per joint the sampling-consistent implicit super-twisting
 * observer (implicit_twisting.h), with the paper's nominal model
 * f(x1, x2_hat, u) the forward dynamics of the rigid-body model
 *     a = M(y)^-1 (u - C(y, x2_hat) x2_hat - G(y) - friction(x2_hat))
 * at the measured positions y, the corrected velocity estimates and the
 * torques u (Davila, Fridman and Poznyak 2006, eq. (12) with F the nominal
 * model).  The joints are coupled through M^-1, so each sample runs in two
 * phases: every joint's corrector, then one forward dynamics at the corrected
 * state, which every joint takes as the nominal acceleration of the interval
 * that starts at the sample.  The injection then bounds only the model's
 * error (the gains' f+), not the whole acceleration.
 *
 * Identification (RobotRegression): the implicit corrector completes the
 * interval ending at the sample, so after sample k it knows the acceleration
 * at sample k-1, q''_{k-1} = (nominal acceleration around k-1) + injection.
 * The regression takes sample k-1's regressor Y(q, q', q'') (positions,
 * velocity estimates, accelerations) and torque residual z = u - Y pi_nominal,
 * and passes Y and z (not q, q', q'', u) through one first-order filter (time
 * constant tau: the filtered injection's) into the regressor identifier
 * (regressor_identifier.h).  Filtering both sides of the linear equation
 * z = Y Delta keeps it exact, whereas Y of filtered signals is not the filtered
 * Y: near every velocity reversal the Coulomb column sign(filtered q') differs
 * from the filtered sign(q'), which made the friction 4-12 % off.
 * Joint i's equation enters the filter with weight 0 (its row of Y and its z
 * both 0) where |q_i'| < min_speed, where q_i' changes sign, and within
 * reversal_margin seconds after such a sample: there the Coulomb friction is
 * not f_c sign(q') (stiction, the Stribeck effect, a simulator's smoothing),
 * and the observer is still catching up with the reversal.  Weighting before
 * the filter keeps every filtered equation exact.  The rule starts as after
 * such a sample; min_speed and reversal_margin both 0 use every equation.
 *
 * With RO_REGRESSION_WINDOW (the default), the regression takes instead the
 * positions' derivatives and the torques of a zero-phase window a fixed lag behind
 * the newest sample (fixed_lag.h, as a model file's FMU does; its cut-off chosen
 * from the measurement noise when identification starts): the observer's causal
 * velocities lag and carry its noise, which biased the friction (52 % low at
 * 1e-4 rad of noise on the bench's double pendulum).  Slow or reversing is then
 * judged on the window's velocity FL_REVERSAL_PERIODS of the cut-off ahead of
 * the centre, so that an equation is left out on both sides of the event, where
 * sign() of the smoothed velocity is not the smoothed sign() (and reversal_margin
 * seconds longer after it).  The observer's outputs stay causal; only the
 * parameters lag, by half the window and that lead.
 */
#ifndef ROBOT_OBSERVER_H
#define ROBOT_OBSERVER_H

#include "tuning.h"

#include "fixed_lag.h"
#include "implicit_twisting.h"
#include "regressor_identifier.h"
#include "rigid_body.h"

#define RO_MAX_JOINTS RB_MAX_JOINTS
_Static_assert(2 * RO_MAX_JOINTS <= FL_MAX_SIGNALS, "the window holds the joints and torques");

typedef enum {
    RO_REGRESSION_OBSERVER = 0, /* at the observer's causal estimates (the paper's) */
    RO_REGRESSION_WINDOW = 1    /* at a zero-phase window's derivatives, a fixed lag behind */
} RoRegression;

/* One joint's implicit observer between samples (implicit_twisting.h's
 * leapfrog): corrected position, mid-interval velocity, the nominal
 * acceleration of the interval that starts at the sample and its mean with
 * the previous one, the injection and its filter, the convergence detector,
 * the velocity estimate at the sample. */
typedef struct {
    double z1, mid, a_current, a_mean, v, z_filtered, rate, previous_sign, x2_now;
} RobotDof;

typedef struct {
    int n;
    double h, h_squared, inverse_h_squared;
    double filter_gain;            /* 1 - exp(-h/tau) of the injection filter */
    double rate_gain;              /* convergence detector: h / window */
    double alpha1[RO_MAX_JOINTS], alpha2[RO_MAX_JOINTS];
    RobotDof dof[RO_MAX_JOINTS];
    int primed;                    /* a sample has been taken */
    double x1_hat[RO_MAX_JOINTS];  /* outputs: the prediction for the end of the last */
    double x2_hat[RO_MAX_JOINTS];  /* interval (ro_outputs), or the initial estimates */
    double previous_acceleration[RO_MAX_JOINTS]; /* q'' at the sample before the last */
    double steps;                  /* samples taken */
    double model_failures;         /* samples at which M(y) was not positive definite */
} RobotObserver;

/* Gains per joint (alpha1 > f+ of the model error, alpha2 by Theorem 3.1),
 * tau the injection filter's time constant (0: none), the convergence
 * window [s] of the switching-rate test, initial estimates. */
void ro_init(RobotObserver *o, int n, double h, const double alpha1[], const double alpha2[],
             double tau, double convergence_window, const double x1_hat0[],
             const double x2_hat0[]);

/* One sample: positions y and torques u (held over the interval that starts
 * here).  Returns 0, or -1 if M(y) is not positive definite (the nominal
 * acceleration is then taken as 0 for this interval and the failure counted). */
int ro_step(RobotObserver *o, const RigidBodyModel *model, const double y[], const double u[]);

/* x1_hat, x2_hat: the prediction for the end of the last interval. */
void ro_outputs(RobotObserver *o);

/* Velocity estimate at the last sample (after its corrector). */
static inline double ro_velocity(const RobotObserver *o, int i) { return o->dof[i].x2_now; }

/* Every joint in its sliding mode by the switching-rate test. */
int ro_converged(const RobotObserver *o);

typedef struct {
    int kind;                      /* RoRegression */
    double gain;                   /* 1 - exp(-h/tau) of the regression filter */
    double min_speed;              /* joint equations below it weigh 0 ... */
    int margin_samples;            /* ... and this many samples after (reversal_margin / h) */
    int reversals;                 /* a sign change of q_i' weighs 0 (the rule is on) */
    int have_previous, have_older, started;
    double previous_y[RO_MAX_JOINTS], previous_u[RO_MAX_JOINTS],
        previous_velocity[RO_MAX_JOINTS], older_velocity[RO_MAX_JOINTS];
    int settled[RO_MAX_JOINTS];    /* samples since joint i was slow or reversed */
    double weight[RO_MAX_JOINTS];  /* the last row's weight of joint i's equation, 0 or 1 */
    int entered;                   /* a row entered the identifier at the last sample */
    FixedLag window;               /* RO_REGRESSION_WINDOW: the positions and torques */
    double lead_velocity[RO_MAX_JOINTS]; /* the window's, ahead of its centre */
    RbRegressor Y;                 /* the weighted regressor through the filter (the */
    double z[RO_MAX_JOINTS];       /* identifier's entries only), the torque residual */
    double pi_nominal[RB_MAX_PARAMETERS];
} RobotRegression;

/* The regression (kind: RoRegression), its filter (tau > 0; 0: no filter), the
 * nominal parameters (the model's) and the rule of the joint equations left out:
 * min_speed >= 0 [rad/s or m/s], reversal_margin >= 0 [s] (both 0: every equation
 * is used).  Returns 0, or -1 for an unknown kind, a negative or non-finite
 * min_speed or reversal_margin, or a step h the window refuses. */
int ro_regression_init(RobotRegression *r, const RigidBodyModel *model, int kind, double h,
                       double tau, double min_speed, double reversal_margin);

/* The filters start again at the next sample (with its values: no transient). */
void ro_regression_restart(RobotRegression *r);

/* After ro_step(o, model, y, u): one identifier step (ri_step) with the
 * regression of the previous sample (none on the first sample, nor with id
 * NULL: the identifier is not running, the sample is only remembered). */
void ro_regression_step(RobotRegression *r, const RigidBodyModel *model, const RobotObserver *o,
                        const double y[], const double u[], RegressorIdentifier *id);

/* The weight (0 or 1) with which joint i's equation of the sample ro_regression_lag
 * samples before the last entered the regression (after ro_regression_step; when
 * r->entered). */
static inline double ro_regression_weight(const RobotRegression *r, int i)
{
    return r->weight[i];
}

/* Samples from the newest to the one whose equations the last row holds: 1 at the
 * observer's estimates, the window's centre's lag (once chosen) through it. */
int ro_regression_lag(const RobotRegression *r);

#endif
