/* The state of the implicit scheme (implicit_twisting.h) per DOF: its own, held by the
 * observer that runs it (SuperTwistingObserver.implicit); the paper's scheme has none
 * of it. */
#ifndef IMPLICIT_STATE_H
#define IMPLICIT_STATE_H

#include "observer_types.h"

typedef struct {
    int primed;                  /* a corrected sample exists */
    double z1[STO_MAX_DOF];      /* corrected position at the last sample */
    double mid_velocity[STO_MAX_DOF]; /* velocity at the middle of the last interval */
    double a_free[STO_MAX_DOF];  /* nominal acceleration of the interval that starts at the
                                  * sample, without its Coulomb and position terms
                                  * (it_advance) */
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
    double published[STO_MAX_DOF]; /* the injection as published (z_eq) at the last sample ... */
    double filtered[STO_MAX_DOF];  /* ... and through the tau filter (z_filtered): the
                                    * observer's outputs unless the noise-adaptive bank
                                    * publishes a member's */
} ImplicitState;

#endif
