/* The types every scheme of the observer shares (super_twisting.h, implicit_twisting.h,
 * noise_adaptive.h): the size limits, the scheme switch, the nominal acceleration of a
 * run and what a run leaves for the identifier. */
#ifndef OBSERVER_TYPES_H
#define OBSERVER_TYPES_H

#define STO_MAX_DOF 4

typedef enum {
    STO_SCHEME_PAPER = 1,   /* explicit Euler on (12), exactly as the paper implies */
    STO_SCHEME_IMPLICIT = 2, /* sampling-consistent implicit step, implicit_twisting.c */
    STO_SCHEME_ADAPTIVE = 3  /* implicit step beside linear observers, noise_adaptive.c */
} StoScheme;

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

/* Longest run of steps os_run takes at once. */
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

#endif
