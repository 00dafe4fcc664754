#include "robot_pipeline.h"

#include <stddef.h>

void rp_run(const RobotPipeline *p, const RigidBodyModel *model, const double y[],
            const double u[], long stride, long count, long join)
{
    for (long j = 0; j < count; ++j) {
        const double *yj = y + j * stride, *uj = u + j * stride;
        ro_step(p->observer, model, yj, uj);
        if (!p->regression) continue;
        const int identifying = join == RP_ALREADY || (join >= 0 && j >= join);
        if (j == join) ro_regression_restart(p->regression);
        ro_regression_step(p->regression, model, p->observer, yj, uj,
                           identifying ? p->identifier : NULL);
        if (identifying) { /* the statistics on the internal steps' own schedule */
            sj_step(p->statistics);
            sj_schedule(p->statistics, p->identifier);
        }
    }
}

void rp_communicate(const RobotPipeline *p)
{
    ro_outputs(p->observer);
}
