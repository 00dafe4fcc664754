#include "implicit_twisting.h"

#include <math.h>

/* One DOF's state over a run, in locals. */
typedef struct {
    double z1, mid, a_current, a_mean, v, z_filtered, rate, previous_sign, x2_now;
} DofState;

/* The corrector at sample y: completes the interval that ends there.
 * Returns the innovation against the prediction with the injection held,
 * which the noise-adaptive scheme compares across its observers. */
static inline double correct(DofState *s, double y, double h, double h2, double inverse_h2,
                             double reach, double b, double alpha1, double rate_gain)
{
    const double w = y - s->z1 - h * s->mid - h2 * s->a_mean, innovation = w - h2 * s->v;
    double e;
    if (fabs(w) <= reach) { /* sliding: the injection keeps x1_hat on y */
        e = 0.0;
        s->v = w * inverse_h2;
        sto_track_switching(&s->rate, &s->previous_sign, rate_gain, 0.0);
    } else {
        const double sign_w = w > 0.0 ? 1.0 : -1.0, r = fabs(w) - reach;
        const double q = 2.0 * r / (b + sqrt(b * b + 4.0 * r)); /* stable root form */
        e = sign_w * q * q;
        s->v = alpha1 * sign_w;
        sto_track_switching(&s->rate, &s->previous_sign, rate_gain, e != 0.0 ? sign_w : 0.0);
    }
    s->mid += h * (s->a_mean + s->v);
    s->z1 = y - e;
    s->x2_now = s->mid + 0.5 * h * (s->a_current + s->v);
    return innovation;
}

/* The acceleration of the interval that starts at this sample, at the corrected velocity. */
static inline double record(DofState *s, StoAcceleration a, double g, StoTrace *trace, int i, int k)
{
    const double sign_v = sto_sign(s->x2_now), acceleration = sto_acceleration(a, s->x2_now, sign_v);
    s->a_mean = 0.5 * (s->a_current + acceleration);
    s->a_current = acceleration;
    s->z_filtered += g * (s->v - s->z_filtered);
    trace->velocity[i][k] = s->x2_now;
    trace->velocity_sign[i][k] = sign_v;
    trace->z_eq[i][k] = s->v;
    trace->z_filtered[i][k] = s->z_filtered;
    return acceleration;
}

void implicit_run(SuperTwistingObserver *o, const double y[], const StoAcceleration a[], int count,
                  StoTrace *trace)
{
    const double h = o->h, h2 = o->h_squared, inverse_h2 = o->inverse_h_squared;
    const double g = o->filter_gain, rate_gain = o->rate_gain;
    for (int i = 0; i < o->n; ++i) {
        const double reach = h2 * o->alpha1[i], b = h * o->alpha2[i], alpha1 = o->alpha1[i];
        const StoAcceleration ai = a[i];
        DofState s = {o->z1[i], o->mid_velocity[i], o->a_current[i], o->a_mean[i], o->z_eq[i],
                      o->z_filtered[i], o->switching_rate[i], o->previous_sign[i], o->x2_now[i]};
        int k = 0;
        if (!o->primed) { /* the initial estimates; the leapfrog starts half a step back */
            s.z1 = o->x1_hat[i];
            s.x2_now = o->x2_hat[i];
            s.a_current = sto_acceleration(ai, s.x2_now, sto_sign(s.x2_now));
            s.mid = s.x2_now - 0.5 * h * s.a_current;
            trace->innovation[i][k] = 0.0;
            trace->position[i][k] = s.z1;
            trace->mid_velocity[i][k] = s.mid;
            trace->switching_rate[i][k] = s.rate;
            record(&s, ai, g, trace, i, k++);
        }
        for (; k < count; ++k) {
            trace->innovation[i][k] = correct(&s, y[i], h, h2, inverse_h2, reach, b, alpha1,
                                              rate_gain);
            trace->position[i][k] = s.z1;
            trace->mid_velocity[i][k] = s.mid;
            trace->switching_rate[i][k] = s.rate;
            record(&s, ai, g, trace, i, k);
        }
        o->z1[i] = s.z1;
        o->mid_velocity[i] = s.mid;
        o->a_current[i] = s.a_current;
        o->a_mean[i] = s.a_mean;
        o->z_eq[i] = s.v;
        o->z_filtered[i] = s.z_filtered;
        o->switching_rate[i] = s.rate;
        o->previous_sign[i] = s.previous_sign;
        o->x2_now[i] = s.x2_now;
    }
    o->primed = 1;
}

void implicit_outputs(SuperTwistingObserver *o)
{
    if (!o->primed) return; /* still the initial estimates */
    const double h = o->h;
    for (int i = 0; i < o->n; ++i) {
        implicit_predict(o->z1[i], o->mid_velocity[i], o->a_mean[i], o->a_current[i], o->z_eq[i],
                         h, &o->x1_hat[i], &o->x2_hat[i]);
    }
}
