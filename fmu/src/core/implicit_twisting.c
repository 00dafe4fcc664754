#include "implicit_twisting.h"

#include <math.h>

void implicit_correct(SuperTwistingObserver *o, const double y[])
{
    const double h = o->h, h2 = h * h, inverse_h2 = 1.0 / h2;
    for (int i = 0; i < o->n; ++i) {
        if (!o->primed) {
            o->z1[i] = o->x1_hat[i];
            o->x2_now[i] = o->x2_hat[i];
            continue;
        }
        const double a_mean = 0.5 * (o->a_previous[i] + o->a_current[i]);
        const double w = y[i] - o->z1[i] - h * o->mid_velocity[i] - h2 * a_mean;
        const double reach = h2 * o->alpha1[i];
        double e, v;
        if (fabs(w) <= reach) { /* sliding: the injection keeps x1_hat on y */
            e = 0.0;
            v = w * inverse_h2;
        } else {
            const double s = sto_sign(w), r = fabs(w) - reach, b = h * o->alpha2[i];
            const double q = 2.0 * r / (b + sqrt(b * b + 4.0 * r)); /* stable root form */
            e = s * q * q;
            v = o->alpha1[i] * s;
        }
        sto_track_switching(o, i, sto_sign(e));
        o->mid_velocity[i] += h * (a_mean + v);
        o->z1[i] = y[i] - e;
        o->z_eq[i] = v;
        o->x2_now[i] = o->mid_velocity[i] + 0.5 * h * (o->a_current[i] + v);
    }
}

void implicit_predict(SuperTwistingObserver *o, const double nominal_acceleration[])
{
    const double h = o->h, g = o->filter_gain;
    for (int i = 0; i < o->n; ++i) {
        const double a = nominal_acceleration[i], v = o->z_eq[i];
        if (!o->primed) { /* start the leapfrog half a step back, at the initial velocity */
            o->a_current[i] = a;
            o->mid_velocity[i] = o->x2_now[i] - 0.5 * h * a;
        }
        o->a_previous[i] = o->a_current[i];
        o->a_current[i] = a;
        const double mid_next = o->mid_velocity[i] + h * (0.5 * (o->a_previous[i] + a) + v);
        o->x1_hat[i] = o->z1[i] + h * mid_next;
        o->x2_hat[i] = mid_next + 0.5 * h * (a + v);
        o->z_filtered[i] += g * (v - o->z_filtered[i]);
    }
    o->primed = 1;
}
