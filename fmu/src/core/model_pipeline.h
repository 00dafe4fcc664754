/* The observer and identifier of a mechanical system declared in a model file,
 * composed once over its term program (term_program.h):
 *     sum_k theta_k Y_ik(q, q', q'', u) = r_i(q, q', q'', u),   i = 1..n.
 *
 * Observer: the super-twisting observer of every coordinate (implicit scheme,
 * or beside the bank of noise-adaptive linear observers: noise_adaptive.h),
 * with the paper's nominal model F (Davila, Fridman and Poznyak 2006, (12))
 * the model file's equations solved for the accelerations at the nominal
 * parameters, the measured positions, the velocity estimates and the inputs.
 * Where the nominal inertia is singular, F = 0 (the injection then carries the
 * whole acceleration).
 *
 * Identification (regression = MP_REGRESSION_WINDOW, the default): the
 * equations at the positions, velocities and accelerations of a zero-phase
 * window a fixed lag behind the newest sample (fixed_lag.h; its cut-off chosen
 * from the measurement noise when identification starts), the inputs
 * through the same window, every entry through one first-order low-pass
 * filter G (time constant tau_identifier) into the regressor identifier.
 * The observer's states stay causal; only the parameters lag.
 * An equation with sign(q') (Coulomb friction) holds between the smoothed signals
 * only where q' moves and away from its reversals: its other rows are left out, as
 * identify's friction rows are (the window's centre then lags FL_REVERSAL_PERIODS
 * more, to see the reversals ahead of it).
 * With regression = MP_REGRESSION_OBSERVER: the equations at the observer's
 * causal velocity estimates, every entry through G into the regressor identifier (regressor_identifier.h: LSM or MFF in information form,
 * standard errors by the sandwich over batches), with the statistics' solve
 * spread over the internal steps (statistics_job.h).  The equations are affine
 * in the accelerations, Y = Y0(q, q', u) + A(q, q') q'' (the same for r), and
 * G q'' = d/dt (G q'): the acceleration's part of each filtered entry is A
 * times the derivative of the filtered velocity, so that no acceleration
 * estimate is differentiated or filtered twice; where A is constant (a mass)
 * this is the filtered entry exactly.  The unknowns are identified in SI units
 * (theta_SI = scale theta): the regularization rho does not depend on the
 * units a file is written in.
 * Plain C, no allocation, no FMI types. */
#ifndef MODEL_PIPELINE_H
#define MODEL_PIPELINE_H

#include "fixed_lag.h"
#include "noise_adaptive.h"
#include "regressor_identifier.h"
#include "statistics_job.h"
#include "super_twisting.h"
#include "term_program.h"

#define MP_MAX_COORDINATES TP_MAX_COORDINATES
/* The observer runs over groups of at most STO_MAX_DOF coordinates (each
 * coordinate's observer is its own: a group only shares the loop) */
#define MP_GROUP_SIZE STO_MAX_DOF
#define MP_GROUPS ((MP_MAX_COORDINATES + MP_GROUP_SIZE - 1) / MP_GROUP_SIZE)

typedef enum {
    MP_REGRESSION_OBSERVER = 0, /* at the observer's causal velocities (the paper's) */
    MP_REGRESSION_WINDOW = 1    /* at a zero-phase window's derivatives, a fixed lag behind */
} MpRegression;

typedef struct {
    /* configuration */
    double h, tau_identifier, rho, R, t_id, statistics_interval;
    int scheme;                 /* STO_SCHEME_IMPLICIT or STO_SCHEME_ADAPTIVE */
    int identifier;             /* 0 off, IDENTIFIER_LSM, IDENTIFIER_MFF */
    int nominal_model;          /* 1: F from the nominal parameters; 0: F = 0 */
    int regression;             /* MpRegression */
    /* derived at initialization */
    double gain;                /* 1 - exp(-h / tau_identifier) */
    int warm_up;                /* samples of the filters before the rows enter */
    /* state */
    SuperTwistingObserver obs[MP_GROUPS]; /* coordinates g MP_GROUP_SIZE onwards */
    AdaptiveBank bank[MP_GROUPS];
    double velocity[MP_MAX_COORDINATES];     /* the published velocity at the last sample */
    double nominal_acceleration[MP_MAX_COORDINATES]; /* F of the interval that starts there */
    double singular_steps;      /* samples at which the nominal inertia was singular */
    int identifying, started;   /* the identifier runs; its filters hold a sample */
    int warm_samples;           /* samples since it started, up to warm_up */
    double Y0[MP_MAX_COORDINATES][TP_MAX_PARAMETERS + 1]; /* G of the acceleration-free */
    double velocity_filtered[MP_MAX_COORDINATES];          /* entries; G of the velocity
                                                            * (window: G of every entry) */
    FixedLag window;            /* the positions and inputs, for MP_REGRESSION_WINDOW */
    int terms_unwindowed;       /* entries of the samples alone left at the smoothed sample:
                                 * beyond FL_MAX_TERMS (mp_init; the model warns) */
    int window_term[MP_MAX_COORDINATES][TP_MAX_PARAMETERS + 1]; /* each entry's
                                 * window term, or -1 (mp_init) */
    /* Coulomb friction through the window: equation i reads coordinate j's velocity
     * inside sign() (bit j of sign_velocities[i], mp_init); its rows are left out
     * where j is slow or reverses within FL_REVERSAL_PERIODS of the cut-off of the
     * window's centre: there the friction is stiction, or sign() of the smoothed
     * velocity is not the smoothing of sign() that the smoothed equation holds with */
    int sign_velocities[MP_MAX_COORDINATES];
    double lead_velocity[MP_MAX_COORDINATES]; /* the window's velocity ahead of the centre */
    int since_reversal[MP_MAX_COORDINATES];   /* its samples since it changed sign, capped */
    double speed_square[MP_MAX_COORDINATES];  /* sums of the centre's squared velocities */
    double speed_samples;                     /* and their count, since the regression began */
    RbRegressor Y;              /* the filtered equations (SI parameters) ... */
    double z[MP_MAX_COORDINATES]; /* ... and their residual at the nominal parameters */
    RegressorIdentifier id;
    StatisticsJob statistics;
    /* The first internal step at which a velocity, an entry of the equations or the
     * identifier's sums turned non-finite (an input beyond the range of the model's
     * functions, sqrt of a negative number, products past 1e308): flagged on the
     * internal step, which must not log, and reported at the communication point
     * (mp_nonfinite) instead of publishing estimates that no longer follow the log. */
    int nonfinite;              /* MP_FINITE, or one of MpNonfinite */
    int nonfinite_equation;     /* 0-based equation, and its entry (-1: the known side) */
    int nonfinite_entry;
    double nonfinite_time;      /* [s] the internal step's time */
} ModelPipeline;

typedef enum {
    MP_FINITE = 0,
    MP_NONFINITE_VELOCITY = 1,   /* a velocity estimate (nonfinite_equation: coordinate) */
    MP_NONFINITE_ENTRY = 2,      /* an entry of the equations at the estimates */
    MP_NONFINITE_IDENTIFIER = 3  /* the identifier's information or its right-hand side */
} MpNonfinite;

/* Checks the configuration against the program (sizes, ranges) and starts the
 * observer at the positions y with gains alpha1, alpha2 (per coordinate).
 * Returns 0, or -1 with a message in error[error_size]. */
int mp_init(ModelPipeline *p, const TermProgram *program, const double alpha1[],
            const double alpha2[], const double y[], char *error, size_t error_size);

/* Internal steps k .. k_end - 1 (time start_time + k h) with the positions y
 * and inputs u held. */
void mp_run(ModelPipeline *p, const TermProgram *program, const double y[], const double u[],
            double start_time, unsigned long long k, unsigned long long k_end);

/* A communication point: the observer's outputs (the statistics follow the
 * internal steps, mp_run). */
void mp_communicate(ModelPipeline *p);

/* The parameters in the file's units and their standard errors (0 until the
 * first statistics job completes; the nominal values until identification
 * starts).  Where the program declares ranges, the estimate is the identifier's
 * least squares inside them (box_projection.h); held[k] (-1 lower end, 1 upper,
 * 0 free; may be NULL) says which are held at an end, with standard error 0.
 * Returns the projection's BpResult (BP_INSIDE without ranges). */
int mp_estimates(const ModelPipeline *p, const TermProgram *program, double theta[],
                 double std_error[], int held[]);

/* What turned non-finite first (MP_FINITE: nothing), said in message[size]
 * (at a communication point: formats, so never on the internal step). */
int mp_nonfinite(const ModelPipeline *p, char *message, size_t size);
/* Restarts identification from the nominal parameters. */
void mp_restart_identifier(ModelPipeline *p);

/* The observer groups an n-coordinate model uses, and group g's coordinates. */
int mp_groups(int n);
int mp_group_size(int n, int g);

/* Coordinate i's position and velocity estimates (after mp_communicate). */
double mp_position(const ModelPipeline *p, int i);
double mp_velocity(const ModelPipeline *p, int i);

/* Every group's super-twisting observer slides (the switching-rate test). */
int mp_converged(const ModelPipeline *p, int n);

#endif
