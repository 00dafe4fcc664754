/* The output of an FMU whose identifier regresses through the fixed-lag window
 * (core/fixed_lag.h): shared by the models that identify from a log. */
#ifndef FIXED_LAG_OUTPUTS_H
#define FIXED_LAG_OUTPUTS_H

#include "../instance/model_interface.h"

/* identifier_cutoff (Real, Hz) at vr_, its value at offset `at` of the model data. */
#define IDENTIFIER_CUTOFF_VARIABLE(vr_, at)                                                       \
    {.name = "identifier_cutoff", .vr = (vr_), .type = TYPE_REAL,                                \
     OUTPUT(.offset = (at), .unit = "Hz",                                                        \
            .description = "Cut-off of the fixed-lag window the identifier regresses through "    \
                           "(regression = 1), chosen when identification starts: the widest "     \
                           "band in which the measurement noise is at most 1 % of the "           \
                           "accelerations' mean square; the estimates lag by 6 periods of it "    \
                           "(7.5 where equations are left out near reversals). 0 before")}

#endif
