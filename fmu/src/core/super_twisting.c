#include "super_twisting.h"

#include <math.h>
#include <string.h>

#include "implicit_twisting.h"

void sto_init(SuperTwistingObserver *o, int n, double h, const double alpha1[],
              const double alpha2[], double tau, const double x1_hat0[], const double x2_hat0[])
{
    memset(o, 0, sizeof *o);
    o->scheme = STO_SCHEME_PAPER;
    o->rate_gain = 1.0;
    o->n = n;
    o->h = h;
    /* Exact discretization of tau*z' = -z + z_eq over one step: stable for any
     * tau >= 0, and equal to explicit Euler (h/tau) up to O((h/tau)^2). */
    o->filter_gain = tau > 0.0 ? -expm1(-h / tau) : 1.0;
    for (int i = 0; i < STO_MAX_DOF; ++i) {
        int active = i < n;
        o->alpha1[i] = active ? alpha1[i] : 0.0;
        o->alpha2[i] = active ? alpha2[i] : 0.0;
        o->x1_hat[i] = active ? x1_hat0[i] : 0.0;
        o->x2_hat[i] = active ? x2_hat0[i] : 0.0;
        o->z_eq[i] = 0.0;
        o->z_filtered[i] = 0.0;
    }
}

void sto_configure(SuperTwistingObserver *o, StoScheme scheme, double convergence_window)
{
    o->scheme = scheme;
    o->rate_gain = convergence_window > o->h ? o->h / convergence_window : 1.0;
}

int sto_converged(const SuperTwistingObserver *o)
{
    for (int i = 0; i < o->n; ++i)
        if (!(o->switching_rate[i] >= STO_CONVERGED_RATE)) return 0;
    return 1;
}

const double *sto_begin_step(SuperTwistingObserver *o, const double y[])
{
    if (o->scheme == STO_SCHEME_IMPLICIT) {
        implicit_correct(o, y);
        return o->x2_now;
    }
    return o->x2_hat;
}

void sto_end_step(SuperTwistingObserver *o, const double y[], const double nominal_acceleration[])
{
    if (o->scheme == STO_SCHEME_IMPLICIT) {
        implicit_predict(o, nominal_acceleration);
        return;
    }
    sto_step(o, y, nominal_acceleration);
}

void sto_step(SuperTwistingObserver *o, const double y[], const double nominal_acceleration[])
{
    const double h = o->h, g = o->filter_gain;
    for (int i = 0; i < o->n; ++i) {
        const double e = y[i] - o->x1_hat[i];
        const double s = sto_sign(e);
        const double z = o->alpha1[i] * s;
        sto_track_switching(o, i, s);
        o->x1_hat[i] += h * (o->x2_hat[i] + o->alpha2[i] * sqrt(fabs(e)) * s);
        o->x2_hat[i] += h * (nominal_acceleration[i] + z);
        o->z_eq[i] = z;
        o->z_filtered[i] += g * (z - o->z_filtered[i]);
    }
}
