#include "robot_pipeline.h"

#include <stddef.h>
#include <string.h>

#include "gains.h"
#include "tuning.h"

RobotSettings rp_default_settings(int n)
{
    RobotSettings s;
    memset(&s, 0, sizeof s);
    s.n = n;
    s.regression = RO_REGRESSION_WINDOW;
    s.h = RO_STEP;
    s.tau = RO_TAU;
    s.convergence_window = RO_CONVERGENCE_WINDOW;
    s.gain_exponent = RO_GAIN_EXPONENT;
    s.rho = RO_RHO;
    s.R = RO_R;
    s.min_speed = RO_MIN_SPEED;
    s.reversal_margin = RO_REVERSAL_MARGIN;
    s.statistics_interval = RO_STATISTICS_INTERVAL;
    for (int i = 0; i < RB_MAX_JOINTS; ++i) {
        s.f_plus[i] = RO_F_PLUS;
        s.torque_scale[i] = 1.0;
    }
    return s;
}

RpProblem rp_init(const RobotPipeline *p, const RigidBodyModel *model, const RobotSettings *s,
                  const double y0[], int *joint)
{
    double alpha1[RB_MAX_JOINTS], alpha2[RB_MAX_JOINTS];
    const double zero[RB_MAX_JOINTS] = {0};
    for (int i = 0; i < s->n; ++i) {
        alpha1[i] = s->alpha1[i];
        alpha2[i] = s->alpha2[i];
        if (gains_complete(s->f_plus[i], s->gain_exponent, &alpha1[i], &alpha2[i]) != 0) {
            if (joint) *joint = i;
            return RP_NO_GAINS;
        }
    }
    ro_init(p->observer, s->n, s->h, alpha1, alpha2, s->tau, s->convergence_window, y0, zero);
    if (p->regression && ro_regression_init(p->regression, model, s->regression, s->h, s->tau,
                                            s->min_speed, s->reversal_margin) != 0)
        return RP_BAD_REGRESSION;
    memset(p->identifier, 0, sizeof *p->identifier);
    if (s->identifier && ri_init(p->identifier, (IdentifierKind)s->identifier, s->n, s->p,
                                  s->columns, s->torque_scale, s->h, s->rho, s->R, NULL) != 0)
        return RP_BAD_IDENTIFIER;
    sj_init(p->statistics, s->identifier ? s->p : 1, sj_interval_steps(s->statistics_interval, s->h),
            SJ_BUDGET);
    return RP_OK;
}

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
