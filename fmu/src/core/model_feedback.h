/* The identified joint model fed back into the observer (model_feedback).
 *
 * Why: the super-twisting observer and the linear members of the noise-adaptive
 * bank track whatever the nominal model misses as a perturbation.  A nominal
 * model 10 % off in inertia with its friction guessed at half leaves a
 * perturbation of about 10 % of b u, as fast as the torque: only a fast, noisy
 * member follows it.  Measured with the true model given as nominal instead
 * (bench/real_measurements.py --held-out's light fast joint, 1 kHz, 18-bit
 * encoder): velocity RMS 5.2e-4 rad/s against 0.030 from the 10 % off model.
 * Once the LSM has identified the model, the observer predicts with it and
 * tracks only what is left.
 *
 * Each identified correction Delta_j is taken with the weight
 *     w = Delta_j^2 / (Delta_j^2 + (sigmas sigma_j)^2),   (FEEDBACK_SIGMAS by default)
 * sigma_j its standard error: a correction well above its noise enters whole,
 * one within it hardly at all, so a parameter the data do not determine
 * leaves the nominal value in place. */
#ifndef MODEL_FEEDBACK_H
#define MODEL_FEEDBACK_H

#include "tuning.h"

/* The share of an identified correction the observer's model takes, after
 * `time` s of identification (from t->start, over t->ramp). */
static inline double mf_weight(const FeedbackTuning *t, double delta, double sigma,
                                     double time)
{
    const double d2 = delta * delta;
    const double s2 = t->sigmas * t->sigmas * sigma * sigma;
    const double ramp = (time - t->start) / t->ramp;
    if (!(ramp > 0.0) || !(d2 > 0.0)) return 0.0;
    return (ramp < 1.0 ? ramp : 1.0) * d2 / (d2 + s2);
}

#endif
