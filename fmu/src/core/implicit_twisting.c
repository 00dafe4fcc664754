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
 * velocity (it_advance).  Returns the innovation against the
 * prediction with the injection held, which the noise-adaptive scheme
 * compares across its observers. */
static inline double correct(DofState *s, double y, StoAcceleration a, double h, double h2,
                             double inverse_h2, double reach, double b, double alpha1,
                             double rate_gain)
{
    const double v_before = s->v;
    const double w = it_correct(y, s->a_mean, h, h2, reach, b, alpha1, inverse_h2, rate_gain,
                                      &s->z1, &s->mid, &s->v, &s->rate, &s->previous_sign);
    const double innovation = w - h2 * v_before;
    s->x2_previous = s->x2_now;
    a.coulomb += s->learned;
    s->x2_now = it_advance(s->mid, s->v, a, h, &s->a_free, &s->a_mean);
    return innovation;
}

/* Learns the Coulomb level from the injection's jump over a velocity
 * reversal (see the header), after the corrector; v_before is the injection
 * before it, coulomb the nominal level. */
static inline void learn_coulomb(DofState *s, double v_before, double coulomb, double alpha1,
                                 double gain)
{
    const double sign_now = st_sign(s->x2_now), sign_before = st_sign(s->x2_previous);
    if (sign_now != sign_before) {
        /* only a reversal between two sliding injections is measured */
        s->reversal_age = sign_now * sign_before < 0.0 && fabs(v_before) < alpha1 ? 0 : -1;
        s->reversal_injection = v_before;
    } else if (s->reversal_age >= 0 && ++s->reversal_age == IMPLICIT_REVERSAL_SAMPLES) {
        s->reversal_age = -1;
        if (!(fabs(s->v) < alpha1)) return;
        /* v = -(c - cbar - learned) sign(v) + smooth: the jump is twice the level's error */
        const double error = -(s->v - s->reversal_injection) * 0.5 * sign_now;
        const double learned = fmax(s->learned + gain * error, -coulomb);
        /* the nominal takes (learned - s->learned) sign(v) from the injection */
        s->v += (learned - s->learned) * sign_now;
        s->a_mean -= (learned - s->learned) * sign_now;
        s->learned = learned;
    }
}

/* What a sample leaves in the trace: the injection relative to the nominal
 * Coulomb level, over the two intervals around the previous sample that the
 * corrector's second difference spans (it_mean_sign). */
static inline void record(DofState *s, double x2_before, double g, double alpha1,
                          StoTrace *trace, int i, int k)
{
    const double published =
        s->learned == 0.0
            ? s->v
            : s->v - s->learned * it_mean_sign(x2_before, s->x2_previous, s->x2_now);
    s->z_filtered += g * (published - s->z_filtered);
    trace->velocity[i][k] = s->x2_now;
    trace->velocity_sign[i][k] = st_sign(s->x2_now);
    trace->z_eq[i][k] = published;
    trace->z_filtered[i][k] = s->z_filtered;
    trace->saturated[i][k] = fabs(s->v) >= alpha1;
}

void it_run(SuperTwistingObserver *o, const double y[], const StoAcceleration a[], int count,
                  StoTrace *trace)
{
    ImplicitState *is = &o->implicit;
    const double h = o->h, h2 = o->h_squared, inverse_h2 = o->inverse_h_squared;
    const double g = o->filter_gain, rate_gain = o->rate_gain;
    for (int i = 0; i < o->n; ++i) {
        const double reach = h2 * o->alpha1[i], b = h * o->alpha2[i], alpha1 = o->alpha1[i];
        const StoAcceleration ai = a[i];
        /* a nominal model with a Coulomb term has its level learned */
        const int learning = ai.coulomb > 0.0;
        DofState s = {is->z1[i], is->mid_velocity[i], is->a_free[i], is->a_mean[i], is->injection[i],
                      is->filtered[i], o->switching_rate[i], o->previous_sign[i], is->x2_now[i],
                      is->x2_previous[i], learning ? is->coulomb_learned[i] : 0.0,
                      is->reversal_injection[i], is->reversal_age[i],
                      is->injection_before[i][0], is->injection_before[i][1], is->smooth_samples[i]};
        int k = 0;
        if (!is->primed) { /* the initial estimates; the leapfrog starts half a step back */
            s.z1 = o->x1_hat[i];
            s.x2_now = s.x2_previous = o->x2_hat[i];
            const double a0 = st_acceleration(ai, s.x2_now, st_sign(s.x2_now));
            s.mid = s.x2_now - 0.5 * h * a0;
            s.a_free = ai.held - ai.viscous * s.x2_now;
            s.a_mean = 0.5 * (a0 + it_coulomb_mean_acceleration(s.x2_now, s.a_free + ai.point + s.v,
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
            if (learning) learn_coulomb(&s, v_before, ai.coulomb, alpha1, o->learning_gain);
            s.v2 = s.v1;
            s.v1 = v_before;
            const int steady = fabs(s.v) < alpha1 && st_sign(s.x2_now) == st_sign(s.x2_previous);
            s.smooth = steady ? (s.smooth < IMPLICIT_SMOOTH_SAMPLES ? s.smooth + 1 : s.smooth) : 0;
            trace->position[i][k] = s.z1;
            trace->mid_velocity[i][k] = s.mid;
            trace->switching_rate[i][k] = s.rate;
            record(&s, x2_before, g, alpha1, trace, i, k);
        }
        is->z1[i] = s.z1;
        is->mid_velocity[i] = s.mid;
        is->a_free[i] = s.a_free;
        is->coulomb[i] = ai.coulomb;
        is->point[i] = ai.point;
        is->a_mean[i] = s.a_mean;
        is->injection[i] = s.v;
        o->z_eq[i] = is->published[i] = trace->z_eq[i][count - 1];
        o->z_filtered[i] = is->filtered[i] = s.z_filtered;
        o->switching_rate[i] = s.rate;
        o->previous_sign[i] = s.previous_sign;
        is->x2_now[i] = s.x2_now;
        is->x2_previous[i] = s.x2_previous;
        is->coulomb_learned[i] = s.learned;
        is->reversal_injection[i] = s.reversal_injection;
        is->reversal_age[i] = s.reversal_age;
        is->injection_before[i][0] = s.v1;
        is->injection_before[i][1] = s.v2;
        is->smooth_samples[i] = s.smooth;
    }
    is->primed = 1;
}

void it_outputs(SuperTwistingObserver *o)
{
    ImplicitState *is = &o->implicit;
    if (!is->primed) return; /* still the initial estimates */
    const double h = o->h;
    for (int i = 0; i < o->n; ++i) {
        const double v = is->injection[i];
        const double dv = is->smooth_samples[i] >= IMPLICIT_SMOOTH_SAMPLES
                              ? 0.5 * (v - is->injection_before[i][1])
                              : 0.0;
        it_predict(is->z1[i], is->mid_velocity[i], is->a_mean[i], is->a_free[i] + is->point[i],
                         is->coulomb[i] + is->coulomb_learned[i], v, dv, h, &o->x1_hat[i],
                         &o->x2_hat[i]);
    }
}
