#include "super_twisting.h"

#include <math.h>
#include <string.h>

void st_init(SuperTwistingObserver *o, int n, double h, const double alpha1[],
              const double alpha2[], double tau, const double x1_hat0[], const double x2_hat0[])
{
    memset(o, 0, sizeof *o);
    o->learning_gain = IMPLICIT_LEARNING_GAIN;
    o->scheme = STO_SCHEME_PAPER;
    o->rate_gain = 1.0;
    o->n = n;
    o->h = h;
    o->h_squared = h * h;
    o->inverse_h_squared = 1.0 / o->h_squared;
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
        o->implicit.reversal_age[i] = -1;
        o->z_filtered[i] = 0.0;
    }
}

void st_configure(SuperTwistingObserver *o, StoScheme scheme, double convergence_window)
{
    o->scheme = scheme;
    o->rate_gain = convergence_window > o->h ? o->h / convergence_window : 1.0;
}

int st_converged(const SuperTwistingObserver *o)
{
    for (int i = 0; i < o->n; ++i)
        if (!(o->switching_rate[i] >= STO_CONVERGED_RATE)) return 0;
    return 1;
}

void st_run_paper(SuperTwistingObserver *o, const double y[], const StoAcceleration a[],
                   int count, StoTrace *trace)
{
    const double h = o->h, g = o->filter_gain, rate_gain = o->rate_gain;
    for (int i = 0; i < o->n; ++i) {
        const double yi = y[i], alpha1 = o->alpha1[i], alpha2 = o->alpha2[i];
        const StoAcceleration ai = a[i];
        double x1 = o->x1_hat[i], x2 = o->x2_hat[i], z = o->z_eq[i], zf = o->z_filtered[i];
        double rate = o->switching_rate[i], previous_sign = o->previous_sign[i];
        for (int k = 0; k < count; ++k) {
            const double sign_v = st_sign(x2), acceleration = st_acceleration(ai, x2, sign_v);
            const double e = yi - x1, s = st_sign(e);
            z = alpha1 * s;
            st_track_switching(&rate, &previous_sign, rate_gain, s);
            trace->velocity[i][k] = x2;
            trace->velocity_sign[i][k] = sign_v;
            x1 += h * (x2 + alpha2 * sqrt(fabs(e)) * s);
            x2 += h * (acceleration + z);
            zf += g * (z - zf);
            trace->z_eq[i][k] = z;
            trace->z_filtered[i][k] = zf;
        }
        o->x1_hat[i] = x1;
        o->x2_hat[i] = x2;
        o->z_eq[i] = z;
        o->z_filtered[i] = zf;
        o->switching_rate[i] = rate;
        o->previous_sign[i] = previous_sign;
    }
}
