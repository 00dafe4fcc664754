/* The super-twisting observer under the scheme it is configured with
 * (st_configure): the paper's explicit Euler (super_twisting.c) or the
 * sampling-consistent implicit step (implicit_twisting.c).  Above both, so
 * that neither scheme depends on the other. */
#ifndef OBSERVER_SCHEME_H
#define OBSERVER_SCHEME_H

#include "super_twisting.h"

/* Runs `count` (1..STO_RUN_MAX; other counts do nothing) steps of the selected
 * scheme with the measurement y held; trace (may be NULL) receives every step.
 * With y and the acceleration held the DOFs are independent over the run, so
 * each DOF runs all its steps in turn with its state in registers.  Before
 * x1_hat and x2_hat are read, call os_update_outputs. */
void os_run(SuperTwistingObserver *o, const double y[], const StoAcceleration a[], int count,
             StoTrace *trace);

/* x1_hat, x2_hat for the end of the last step (the implicit scheme computes
 * its prediction only when asked). */
void os_update_outputs(SuperTwistingObserver *o);

#endif
