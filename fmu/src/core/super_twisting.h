/* Super-twisting second-order sliding-mode observer, Davila, Fridman and
 * Poznyak (2006), eqs. (3) and (12), with the equivalent output injection (7)
 * and its first-order filter (9).  Plain C, no FMI types. */
#ifndef SUPER_TWISTING_H
#define SUPER_TWISTING_H

#include "tuning.h"

#define STO_MAX_DOF 4

typedef enum {
    STO_SCHEME_PAPER = 1,   /* explicit Euler on (12), exactly as the paper implies */
    STO_SCHEME_IMPLICIT = 2, /* sampling-consistent implicit step, implicit_twisting.c */
    STO_SCHEME_ADAPTIVE = 3  /* implicit step beside linear observers, noise_adaptive.c */
} StoScheme;

typedef struct {
    int n;                       /* degrees of freedom, 1..STO_MAX_DOF */
    double h;                    /* internal step [s] */
    double h_squared, inverse_h_squared; /* h^2 and 1/h^2, for the implicit corrector */
    double alpha1[STO_MAX_DOF];  /* gain of the discontinuous term */
    double alpha2[STO_MAX_DOF];  /* gain of the square-root term */
    double filter_gain;          /* 1 - exp(-h/tau); 1 means no filter (tau = 0) */
    double x1_hat[STO_MAX_DOF];  /* position estimate */
    double x2_hat[STO_MAX_DOF];  /* velocity estimate */
    double z_eq[STO_MAX_DOF];    /* equivalent output injection alpha1 sign(e), eq. (7) */
    double z_filtered[STO_MAX_DOF]; /* its low-pass filtered value: the identified perturbation (10) */
    /* Convergence detector (both schemes): an exponentially weighted rate of
     * steps that are in the sliding set (e = 0) or switch sign(e).  During the
     * reaching phase e keeps its sign; in the (discrete) sliding mode it
     * switches nearly every step, with or without measurement noise. */
    double switching_rate[STO_MAX_DOF];
    double previous_sign[STO_MAX_DOF];
    double rate_gain;            /* h / convergence window */
    /* Implicit scheme only (see implicit_twisting.h). */
    int scheme;
    int primed;                  /* a corrected sample exists */
    double z1[STO_MAX_DOF];      /* corrected position at the last sample */
    double mid_velocity[STO_MAX_DOF]; /* velocity at the middle of the last interval */
    double a_free[STO_MAX_DOF];  /* nominal acceleration of the interval that starts at the
                                  * sample, without its Coulomb and position terms
                                  * (implicit_advance) */
    double coulomb[STO_MAX_DOF]; /* the nominal Coulomb level of the last run ... */
    double point[STO_MAX_DOF];   /* ... and its position part (StoAcceleration) */
    double injection[STO_MAX_DOF]; /* the corrector's injection (z_eq: relative to the nominal) */
    double x2_previous[STO_MAX_DOF]; /* velocity estimate at the sample before */
    double coulomb_learned[STO_MAX_DOF]; /* added to the nominal Coulomb level (implicit_twisting.h) */
    double reversal_injection[STO_MAX_DOF]; /* the injection before the reversal measured ... */
    int reversal_age[STO_MAX_DOF];           /* ... this many samples ago; -1: none */
    double injection_before[STO_MAX_DOF][2]; /* the injections one and two samples before */
    int smooth_samples[STO_MAX_DOF];          /* in the sliding set without a reversal, up to
                                               * IMPLICIT_SMOOTH_SAMPLES */
    double a_mean[STO_MAX_DOF];  /* nominal mean acceleration over the leapfrog interval */
    double x2_now[STO_MAX_DOF];  /* velocity estimate at the current sample */
} SuperTwistingObserver;

/* Rate of switching above which the observer counts as converged. */

/* Sets gains, filter and initial estimates; z_eq and its filter start at 0. */
void sto_init(SuperTwistingObserver *o, int n, double h, const double alpha1[],
              const double alpha2[], double tau, const double x1_hat0[], const double x2_hat0[]);

/* Selects the scheme and the convergence window [s] (after sto_init). */
void sto_configure(SuperTwistingObserver *o, StoScheme scheme, double convergence_window);

/* The nominal acceleration of one DOF over a run of steps, affine in its
 * velocity estimate v:  held + point - viscous v - coulomb sign(v).  held is
 * the part held over each interval (the input), point the part that is a
 * function of the measured position, a value at the sample: over the two
 * half intervals around a sample its mean is the value there, where the
 * mean of the held parts of the two intervals lagged half a sample behind
 * (1 kHz, noise-free: the gravity term's lag, c1 h/2 cos(x) v, took the
 * viscous estimate 0.5-1.3 % off).  The built-in joint uses all four; an
 * external model's acceleration F + thetabar phi is held over the run
 * (point = viscous = coulomb = 0). */
typedef struct {
    double held, point, viscous, coulomb;
} StoAcceleration;

/* Longest run of steps sto_run takes at once. */
#define STO_RUN_MAX 32

/* What each step of a run leaves for the identifier, per DOF and step. */
typedef struct {
    double velocity[STO_MAX_DOF][STO_RUN_MAX];      /* x2 estimate at the sample (the regressor's) */
    double velocity_sign[STO_MAX_DOF][STO_RUN_MAX]; /* its sign */
    double z_eq[STO_MAX_DOF][STO_RUN_MAX];          /* injection */
    double z_filtered[STO_MAX_DOF][STO_RUN_MAX];    /* filtered injection */
    /* Implicit and adaptive schemes: the super-twisting corrector's innovation
     * (measurement minus prediction with the injection held). */
    double innovation[STO_MAX_DOF][STO_RUN_MAX];
    double position[STO_MAX_DOF][STO_RUN_MAX];       /* corrected position at the sample */
    double mid_velocity[STO_MAX_DOF][STO_RUN_MAX];   /* velocity of the interval just ended */
    double switching_rate[STO_MAX_DOF][STO_RUN_MAX]; /* the convergence detector's rate */
    double saturated[STO_MAX_DOF][STO_RUN_MAX];      /* 1: the injection is +-alpha1 */
    /* Adaptive scheme: the injection of the observer the identifier follows. */
    double z_identify[STO_MAX_DOF][STO_RUN_MAX];
} StoTrace;

/* Runs `count` (1..STO_RUN_MAX) steps of the paper's explicit Euler on (12)
 * with the measurement y held, each DOF over the run; trace receives every
 * step.  The scheme switch (sto_run) is observer_scheme.h's. */
void sto_run_paper(SuperTwistingObserver *o, const double y[], const StoAcceleration a[],
                   int count, StoTrace *trace);

/* All DOFs converged by the switching-rate test. */
int sto_converged(const SuperTwistingObserver *o);

/* sign with sign(0) = 0, as the observer requires. */
static inline double sto_sign(double x) { return x > 0.0 ? 1.0 : x < 0.0 ? -1.0 : 0.0; }

/* Nominal acceleration at the velocity v, whose sign is sign_v. */
static inline double sto_acceleration(StoAcceleration a, double v, double sign_v)
{
    return a.held + a.point - a.viscous * v - a.coulomb * sign_v;
}

/* Convergence detector update with s = sign(e): a step counts as switching if
 * e = 0 or sign(e) flipped.  (On a DOF's rate and previous sign, which the
 * runs keep in locals.) */
static inline void sto_track_switching(double *rate, double *previous_sign, double gain, double s)
{
    const double switched = (s == 0.0 || s != *previous_sign) ? 1.0 : 0.0;
    *rate += gain * (switched - *rate);
    *previous_sign = s;
}

#endif
