/* Super-twisting second-order sliding-mode observer, Davila, Fridman and
 * Poznyak (2006), eqs. (3) and (12), with the equivalent output injection (7)
 * and its first-order filter (9).  Plain C, no FMI types. */
#ifndef SUPER_TWISTING_H
#define SUPER_TWISTING_H

#define STO_MAX_DOF 4

typedef enum {
    STO_SCHEME_PAPER = 1,   /* explicit Euler on (12), exactly as the paper implies */
    STO_SCHEME_IMPLICIT = 2 /* sampling-consistent implicit step, implicit_twisting.c */
} StoScheme;

typedef struct {
    int n;                       /* degrees of freedom, 1..STO_MAX_DOF */
    double h;                    /* internal step [s] */
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
    double a_previous[STO_MAX_DOF], a_current[STO_MAX_DOF]; /* nominal accelerations of the last two intervals */
    double x2_now[STO_MAX_DOF];  /* velocity estimate at the current sample */
} SuperTwistingObserver;

/* Rate of switching above which the observer counts as converged. */
#define STO_CONVERGED_RATE 0.25

/* Sets gains, filter and initial estimates; z_eq and its filter start at 0. */
void sto_init(SuperTwistingObserver *o, int n, double h, const double alpha1[],
              const double alpha2[], double tau, const double x1_hat0[], const double x2_hat0[]);

/* Selects the scheme and the convergence window [s] (after sto_init). */
void sto_configure(SuperTwistingObserver *o, StoScheme scheme, double convergence_window);

/* One step of either scheme, in two halves so that the caller can evaluate
 * the nominal acceleration with the freshest velocity estimate:
 *   x2 = sto_begin_step(o, y);            velocity estimate at the sample time
 *   a = F(t, y, x2, u) + thetabar*phi(y, x2, u);
 *   sto_end_step(o, y, a);                 estimates for the end of the step */
const double *sto_begin_step(SuperTwistingObserver *o, const double y[]);
void sto_end_step(SuperTwistingObserver *o, const double y[], const double nominal_acceleration[]);

/* All DOFs converged by the switching-rate test. */
int sto_converged(const SuperTwistingObserver *o);

/* One explicit Euler step of (12) (it also feeds the convergence test) with measurement y and the nominal
 * acceleration F(t, y, x2_hat, u) + thetabar*phi evaluated by the caller at the
 * current estimates. */
void sto_step(SuperTwistingObserver *o, const double y[], const double nominal_acceleration[]);

/* sign with sign(0) = 0, as the observer requires. */
static inline double sto_sign(double x) { return (x > 0.0) - (x < 0.0); }

/* Convergence detector update for DOF i with s = sign(e): a step counts as
 * switching if e = 0 or sign(e) flipped. */
static inline void sto_track_switching(SuperTwistingObserver *o, int i, double s)
{
    const double switched = (s == 0.0 || s != o->previous_sign[i]) ? 1.0 : 0.0;
    o->switching_rate[i] += o->rate_gain * (switched - o->switching_rate[i]);
    o->previous_sign[i] = s;
}

#endif
