/* Super-twisting second-order sliding-mode observer, Davila, Fridman and
 * Poznyak (2006), eqs. (3) and (12), with the equivalent output injection (7)
 * and its first-order filter (9).  Plain C, no FMI types. */
#ifndef SUPER_TWISTING_H
#define SUPER_TWISTING_H

#define STO_MAX_DOF 4

typedef enum {
    STO_SCHEME_PAPER = 1 /* explicit Euler on (12), exactly as the paper implies */
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
} SuperTwistingObserver;

/* Sets gains, filter and initial estimates; z_eq and its filter start at 0. */
void sto_init(SuperTwistingObserver *o, int n, double h, const double alpha1[],
              const double alpha2[], double tau, const double x1_hat0[], const double x2_hat0[]);

/* One explicit Euler step of (12) with measurement y and the nominal
 * acceleration F(t, y, x2_hat, u) + thetabar*phi evaluated by the caller at the
 * current estimates. */
void sto_step(SuperTwistingObserver *o, const double y[], const double nominal_acceleration[]);

/* sign with sign(0) = 0, as the observer requires. */
static inline double sto_sign(double x) { return (x > 0.0) - (x < 0.0); }

#endif
