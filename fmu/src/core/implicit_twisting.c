#include "implicit_twisting.h"

#include <math.h>

/* One DOF's state over a run, in locals. */
typedef struct {
    double z1, mid, a_free, a_mean, v, z_filtered, rate, previous_sign, x2_now;
    double x2_previous;        /* the velocity one sample before x2_now */
    double learned;            /* the Coulomb level learned from the injection (see the header) */
    double reversal_injection; /* the injection before the reversal being measured */
    int reversal_age;          /* samples since that reversal; -1: none */
    double v1, v2;             /* the injections one and two samples before */
    int smooth;                /* samples in the sliding set without a reversal */
} DofState;

/* The corrector at sample y: completes the interval that ends there, and
 * the nominal acceleration of the interval that starts, at the corrected
 * velocity (implicit_advance).  Returns the innovation against the
 * prediction with the injection held, which the noise-adaptive scheme
 * compares across its observers. */
static inline double correct(DofState *s, double y, StoAcceleration a, double h, double h2,
                             double inverse_h2, double reach, double b, double alpha1,
                             double rate_gain)
{
    const double v_before = s->v;
    const double w = implicit_correct(y, s->a_mean, h, h2, reach, b, alpha1, inverse_h2, rate_gain,
                                      &s->z1, &s->mid, &s->v, &s->rate, &s->previous_sign);
    const double innovation = w - h2 * v_before;
    s->x2_previous = s->x2_now;
    a.coulomb += s->learned;
    s->x2_now = implicit_advance(s->mid, s->v, a, h, &s->a_free, &s->a_mean);
    return innovation;
}

/* Learns the Coulomb level from the injection's jump over a velocity
 * reversal (see the header), after the corrector; v_before is the injection
 * before it, coulomb the nominal level. */
static inline void learn_coulomb(DofState *s, double v_before, double coulomb, double alpha1)
{
    const double sign_now = sto_sign(s->x2_now), sign_before = sto_sign(s->x2_previous);
    if (sign_now != sign_before) {
        /* only a reversal between two sliding injections is measured */
        s->reversal_age = sign_now * sign_before < 0.0 && fabs(v_before) < alpha1 ? 0 : -1;
        s->reversal_injection = v_before;
    } else if (s->reversal_age >= 0 && ++s->reversal_age == IMPLICIT_REVERSAL_SAMPLES) {
        s->reversal_age = -1;
        if (!(fabs(s->v) < alpha1)) return;
        /* v = -(c - cbar - learned) sign(v) + smooth: the jump is twice the level's error */
        const double error = -(s->v - s->reversal_injection) * 0.5 * sign_now;
        const double learned = fmax(s->learned + IMPLICIT_LEARNING_GAIN * error, -coulomb);
        /* the nominal takes (learned - s->learned) sign(v) from the injection */
        s->v += (learned - s->learned) * sign_now;
        s->a_mean -= (learned - s->learned) * sign_now;
        s->learned = learned;
    }
}

/* What a sample leaves in the trace: the injection relative to the nominal
 * Coulomb level, over the two intervals around the previous sample that the
 * corrector's second difference spans (implicit_mean_sign). */
static inline void record(DofState *s, double x2_before, double g, double alpha1,
                          StoTrace *trace, int i, int k)
{
    const double published =
        s->learned == 0.0
            ? s->v
            : s->v - s->learned * implicit_mean_sign(x2_before, s->x2_previous, s->x2_now);
    s->z_filtered += g * (published - s->z_filtered);
    trace->velocity[i][k] = s->x2_now;
    trace->velocity_sign[i][k] = sto_sign(s->x2_now);
    trace->z_eq[i][k] = published;
    trace->z_filtered[i][k] = s->z_filtered;
    trace->saturated[i][k] = fabs(s->v) >= alpha1;
}

void implicit_run(SuperTwistingObserver *o, const double y[], const StoAcceleration a[], int count,
                  StoTrace *trace)
{
    const double h = o->h, h2 = o->h_squared, inverse_h2 = o->inverse_h_squared;
    const double g = o->filter_gain, rate_gain = o->rate_gain;
    for (int i = 0; i < o->n; ++i) {
        const double reach = h2 * o->alpha1[i], b = h * o->alpha2[i], alpha1 = o->alpha1[i];
        const StoAcceleration ai = a[i];
        /* a nominal model with a Coulomb term has its level learned */
        const int learning = ai.coulomb > 0.0;
        DofState s = {o->z1[i], o->mid_velocity[i], o->a_free[i], o->a_mean[i], o->injection[i],
                      o->z_filtered[i], o->switching_rate[i], o->previous_sign[i], o->x2_now[i],
                      o->x2_previous[i], learning ? o->coulomb_learned[i] : 0.0,
                      o->reversal_injection[i], o->reversal_age[i],
                      o->injection_before[i][0], o->injection_before[i][1], o->smooth_samples[i]};
        int k = 0;
        if (!o->primed) { /* the initial estimates; the leapfrog starts half a step back */
            s.z1 = o->x1_hat[i];
            s.x2_now = s.x2_previous = o->x2_hat[i];
            const double a0 = sto_acceleration(ai, s.x2_now, sto_sign(s.x2_now));
            s.mid = s.x2_now - 0.5 * h * a0;
            s.a_free = ai.held - ai.viscous * s.x2_now;
            s.a_mean = 0.5 * (a0 + coulomb_mean_acceleration(s.x2_now, s.a_free + ai.point + s.v,
                                                             ai.coulomb, 0.5 * h) - s.v);
            trace->innovation[i][k] = 0.0;
            trace->position[i][k] = s.z1;
            trace->mid_velocity[i][k] = s.mid;
            trace->switching_rate[i][k] = s.rate;
            record(&s, s.x2_now, g, alpha1, trace, i, k++);
        }
        for (; k < count; ++k) {
            const double v_before = s.v, x2_before = s.x2_previous;
            trace->innovation[i][k] = correct(&s, y[i], ai, h, h2, inverse_h2, reach, b, alpha1,
                                              rate_gain);
            if (learning) learn_coulomb(&s, v_before, ai.coulomb, alpha1);
            s.v2 = s.v1;
            s.v1 = v_before;
            const int steady = fabs(s.v) < alpha1 && sto_sign(s.x2_now) == sto_sign(s.x2_previous);
            s.smooth = steady ? (s.smooth < IMPLICIT_SMOOTH_SAMPLES ? s.smooth + 1 : s.smooth) : 0;
            trace->position[i][k] = s.z1;
            trace->mid_velocity[i][k] = s.mid;
            trace->switching_rate[i][k] = s.rate;
            record(&s, x2_before, g, alpha1, trace, i, k);
        }
        o->z1[i] = s.z1;
        o->mid_velocity[i] = s.mid;
        o->a_free[i] = s.a_free;
        o->coulomb[i] = ai.coulomb;
        o->point[i] = ai.point;
        o->a_mean[i] = s.a_mean;
        o->injection[i] = s.v;
        o->z_eq[i] = trace->z_eq[i][count - 1];
        o->z_filtered[i] = s.z_filtered;
        o->switching_rate[i] = s.rate;
        o->previous_sign[i] = s.previous_sign;
        o->x2_now[i] = s.x2_now;
        o->x2_previous[i] = s.x2_previous;
        o->coulomb_learned[i] = s.learned;
        o->reversal_injection[i] = s.reversal_injection;
        o->reversal_age[i] = s.reversal_age;
        o->injection_before[i][0] = s.v1;
        o->injection_before[i][1] = s.v2;
        o->smooth_samples[i] = s.smooth;
    }
    o->primed = 1;
}

void implicit_outputs(SuperTwistingObserver *o)
{
    if (!o->primed) return; /* still the initial estimates */
    const double h = o->h;
    for (int i = 0; i < o->n; ++i) {
        const double v = o->injection[i];
        const double dv = o->smooth_samples[i] >= IMPLICIT_SMOOTH_SAMPLES
                              ? 0.5 * (v - o->injection_before[i][1])
                              : 0.0;
        implicit_predict(o->z1[i], o->mid_velocity[i], o->a_mean[i], o->a_free[i] + o->point[i],
                         o->coulomb[i] + o->coulomb_learned[i], v, dv, h, &o->x1_hat[i],
                         &o->x2_hat[i]);
    }
}
