#include "observer_scheme.h"

#include "implicit_twisting.h"

void os_run(SuperTwistingObserver *o, const double y[], const StoAcceleration a[], int count,
             StoTrace *trace)
{
    if (count < 1 || count > STO_RUN_MAX) return;
    StoTrace unused;
    if (!trace) trace = &unused;
    if (o->scheme != STO_SCHEME_PAPER) it_run(o, y, a, count, trace);
    else st_run_paper(o, y, a, count, trace);
}

void os_update_outputs(SuperTwistingObserver *o)
{
    if (o->scheme != STO_SCHEME_PAPER) it_outputs(o);
}
