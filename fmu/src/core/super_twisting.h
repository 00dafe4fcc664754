/* Super-twisting second-order sliding-mode observer, Davila, Fridman and
 * Poznyak (2006), eqs. (3) and (12), with the equivalent output injection (7)
 * and its first-order filter (9).  Plain C, no FMI types. */
#ifndef SUPER_TWISTING_H
#define SUPER_TWISTING_H

#include "tuning.h"

#include "implicit_state.h"
#include "observer_types.h"

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
    double learning_gain;        /* the implicit scheme's (tuning.h; st_init sets the
                                  * default, a caller may set another after it) */
    int scheme;                  /* StoScheme */
    ImplicitState implicit; /* the implicit scheme's (schemes 2 and 3) */
} SuperTwistingObserver;

/* Sets gains, filter and initial estimates; z_eq and its filter start at 0. */
void st_init(SuperTwistingObserver *o, int n, double h, const double alpha1[],
              const double alpha2[], double tau, const double x1_hat0[], const double x2_hat0[]);

/* Selects the scheme and the convergence window [s] (after st_init). */
void st_configure(SuperTwistingObserver *o, StoScheme scheme, double convergence_window);

/* Runs `count` (1..STO_RUN_MAX) steps of the paper's explicit Euler on (12)
 * with the measurement y held, each DOF over the run; trace receives every
 * step.  The scheme switch (os_run) is observer_scheme.h's. */
void st_run_paper(SuperTwistingObserver *o, const double y[], const StoAcceleration a[],
                   int count, StoTrace *trace);

/* All DOFs converged by the switching-rate test. */
int st_converged(const SuperTwistingObserver *o);

/* sign with sign(0) = 0, as the observer requires. */
static inline double st_sign(double x) { return x > 0.0 ? 1.0 : x < 0.0 ? -1.0 : 0.0; }

/* Nominal acceleration at the velocity v, whose sign is sign_v. */
static inline double st_acceleration(StoAcceleration a, double v, double sign_v)
{
    return a.held + a.point - a.viscous * v - a.coulomb * sign_v;
}

/* Convergence detector update with s = sign(e): a step counts as switching if
 * e = 0 or sign(e) flipped.  (On a DOF's rate and previous sign, which the
 * runs keep in locals.) */
static inline void st_track_switching(double *rate, double *previous_sign, double gain, double s)
{
    const double switched = (s == 0.0 || s != *previous_sign) ? 1.0 : 0.0;
    *rate += gain * (switched - *rate);
    *previous_sign = s;
}

#endif
