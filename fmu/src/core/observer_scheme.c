#include "observer_scheme.h"

#include "implicit_twisting.h"

void sto_run(SuperTwistingObserver *o, const double y[], const StoAcceleration a[], int count,
             StoTrace *trace)
{
    if (count < 1 || count > STO_RUN_MAX) return;
    StoTrace unused;
    if (!trace) trace = &unused;
    if (o->scheme != STO_SCHEME_PAPER) implicit_run(o, y, a, count, trace);
    else sto_run_paper(o, y, a, count, trace);
}

void sto_update_outputs(SuperTwistingObserver *o)
{
    if (o->scheme != STO_SCHEME_PAPER) implicit_outputs(o);
}
