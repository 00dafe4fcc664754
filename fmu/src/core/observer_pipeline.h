/* The observer and identifier of one mechanical system, composed once: the
 * nominal model (the built-in joint x'' = b u - c psi, or an external F and
 * regressor phi), the super-twisting observer (or the noise-adaptive bank
 * around it), the regression of its equivalent output injection on the
 * selected regressors (Davila, Fridman and Poznyak 2006, (18)-(19) and
 * (36)-(37)), the LSM/MFF identifier and the identified model fed back into
 * the observer.  The SuperTwistingObserver FMU runs it over its internal
 * steps; the pipeline owns its configuration (the FMU's parameters) and its
 * state, and knows nothing of FMI.  Plain C, no allocation. */
#ifndef OBSERVER_PIPELINE_H
#define OBSERVER_PIPELINE_H

#include <stdint.h>

#include "identifier.h"
#include "information_identifier.h"
#include "joint_model.h"
#include "noise_adaptive.h"
#include "observer_scheme.h"

#define OP_MAX_N STO_MAX_DOF
#define OP_MAX_L ID_MAX_REGRESSORS

enum { OP_NOMINAL_JOINT = 1, OP_NOMINAL_EXTERNAL = 2 };
enum { OP_FORM_PAPER = 1, OP_FORM_INFORMATION = 2 };
enum { OP_START_AT_T_ID = 0, OP_START_WHEN_CONVERGED = 1 };

/* The measurements and known inputs of a sample. */
typedef struct {
    double y[OP_MAX_N];    /* measured positions */
    double u;              /* built-in joint: the actuator torque */
    double F[OP_MAX_N];    /* external model: the nominal acceleration */
    double phi[OP_MAX_L];  /* external model: the regressor */
} ObserverInputs;

/* What the pipeline publishes at a communication point. */
typedef struct {
    double theta_hat[OP_MAX_N][OP_MAX_L];
    double theta_std[OP_MAX_N][OP_MAX_L];
    double gamma_trace, excitation, b_hat, b_std;
    int identifier_active, converged;
} ObserverEstimates;

typedef struct {
    /* configuration */
    double h;
    int n, nominal_model, scheme, identifier, l;
    double tau;
    double b, c_nominal[JOINT_BASIS_SIZE];
    double theta_nominal[OP_MAX_N][OP_MAX_L];
    double t_id, rho, R;
    int identify[OP_MAX_L];
    int identifier_form, identifier_start, filter_regressor, mff_drift, identify_b;
    double convergence_window;
    double tau_identifier;
    int model_feedback;
    /* derived at initialization */
    int m;                     /* number of identified regressors */
    FeedbackTuning feedback;   /* model feedback's tuning (tuning.h) */
    int selected[OP_MAX_L];    /* their indices in the full regressor */
    /* state */
    SuperTwistingObserver obs;
    AdaptiveBank bank;          /* scheme 3: the linear observers beside obs */
    double shadow[OP_MAX_L][3]; /* scheme 3: the selected regressors through the followed
                                 * member's filter G (na_shadow_step) */
    Identifier id;              /* identifier_form = 1 (the paper's explicit Euler) */
    InformationIdentifier info; /* identifier_form = 2 */
    int identifier_active;
    double identifier_gain;      /* per step, of the filter on both sides of z = Delta phi */
    double phi_filtered[OP_MAX_L]; /* selected regressors through the z_eq filter */
    double z_identifier[OP_MAX_N]; /* z_eq through the same filter, started with phi_filtered */
    double phi_previous[OP_MAX_L]; /* selected regressors of the previous sample (implicit) */
    double velocity_before[2];  /* the joint's velocity two samples and one sample back */
    double input_before;        /* the joint's input two samples back */
    /* the selected regressors held over a communication step */
    double phi_now[OP_MAX_L + 1]; /* selected regressors at this sample; [OP_MAX_L]: scratch */
    int slot_velocity, slot_velocity_sign; /* joint: where x2, sign(x2) go in phi_now
                                            * (OP_MAX_L: not selected) */
    int slot_input;             /* joint: where u goes in phi_now (OP_MAX_L: not identified) */
    /* model feedback: the joint model the observer predicts with, b_model = b + D_b,
     * c_model = c_nominal - D (D in the identifier's Delta units, model_delta), and the
     * identifier's injection shifted back to the nominal model, D phi through the
     * followed member's filter G (model_shadow) and the identifier's filter (model_z) */
    double b_model, c_model[JOINT_BASIS_SIZE];
    double model_delta[OP_MAX_L];
    double model_shadow[3];
    double model_z;
    int publish_pending; /* op_publish has estimates to derive */
} ObserverPipeline;

/* Selects the identified regressors from `identify` (and identify_b); returns m. */
int op_select(ObserverPipeline *p);

/* Starts the observer at x1_hat0, x2_hat0 with the gains in use and the
 * identifier from the nominal parameters (after op_select); `in` holds the
 * first sample's inputs; every part takes its group of `tuning` (NULL: tuning.h's
 * values).  Returns 0, or -1 when MFF with drift is asked for more than
 * ID_MAX_REGRESSORS / 2 regressors or the tuning has a problem. */
int op_init(ObserverPipeline *p, const double alpha1[], const double alpha2[],
            const double x1_hat0[], const double x2_hat0[], const ObserverInputs *in,
            ObserverEstimates *out, const StoTuning *tuning);

/* Restarts identification from the nominal parameters (and the observer's model). */
void op_restart_identifier(ObserverPipeline *p);

/* The nominal acceleration of each DOF and the full regressor for the inputs
 * held over a communication step. */
void op_nominal_model(const ObserverPipeline *p, const ObserverInputs *in,
                      StoAcceleration acceleration[OP_MAX_N], double regressor[OP_MAX_L]);

/* Internal steps k .. k_end - 1 (time start_time + k h) with the inputs held;
 * restart: identification restarts first (op_restart_identifier), the step's
 * nominal model taken before it. */
void op_run(ObserverPipeline *p, const ObserverInputs *in, double start_time, uint64_t k,
            uint64_t k_end, int restart);

/* A communication point: the observer's outputs, identifier_active, converged
 * and the model the observer predicts with brought up to date; the other
 * estimates are left to op_publish. */
void op_communicate(ObserverPipeline *p, ObserverEstimates *out);

/* The estimates of the last communication point into `out`, as op_communicate
 * would have published them there; only what a reader sees needs them.  Returns 1
 * if it derived them, 0 if they were up to date. */
int op_publish(ObserverPipeline *p, ObserverEstimates *out);

#endif
