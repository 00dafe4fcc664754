/* The constants of MFF's rule that leaves uninformative samples out, shared by the
 * single-joint identifier (information_identifier.h, where the rule is described)
 * and the robots' regressor identifier (regressor_identifier.h). */
#ifndef LEAVE_OUT_H
#define LEAVE_OUT_H

#define INFO_REFERENCE_MEMORY 10.0 /* Pref's memory, in MFF memories 1/|ln R| */
#define INFO_REST_MEMORY 100.0  /* Pref's memory over the samples left out */
#define INFO_SKIP_SHARE 0.04    /* below this share of the long-run inflow a sample is left
                                 * out: |v| < 0.2 RMS(v) for a velocity regressor */
#define INFO_GAP_MEMORY 0.25    /* gaps longer than this many memories freeze the sums */

#endif
