/* A sampling-consistent, implicit discretization of the super-twisting
 * observer (scheme 2).  Compared with explicit Euler (scheme 1, the paper):
 *
 * - The discontinuous injection is solved implicitly (set-valued sign, as in
 *   the implicit discretizations of Acary, Brogliato, Polyakov and others):
 *   inside the sliding set the injection takes the one value that keeps
 *   x1_hat on the measurement, so it does not chatter and needs no filter.
 * - Kinematics are leapfrog (velocity at mid-interval), which removes the
 *   period-2 oscillation that the exact zero-order-hold form has in sliding.
 * - The known acceleration enters as the average over the two intervals
 *   around a sample, which is what a mid-interval velocity difference sees:
 *   plain implicit Euler charges the injection with half of every jump of the
 *   known acceleration (a switching controller jumps every step).
 *
 * Per DOF, with sample y_k and injection v = alpha1 s, s in Sgn(e):
 *     m_{k-1/2} = m_{k-3/2} + h ((a_{k-2} + a_{k-1})/2 + v)
 *     x1_k      = x1_{k-1} + h m_{k-1/2} + h alpha2 |e_k|^(1/2) sign(e_k),  e_k = y_k - x1_k
 * which gives  e + h alpha2 |e|^(1/2) sign(e) + h^2 alpha1 s = w  with the
 * innovation w = y_k - x1_{k-1} - h m_{k-3/2} - h^2 (a_{k-2} + a_{k-1})/2, solved
 * in closed form: |w| <= h^2 alpha1 gives e = 0, v = w/h^2 (sliding); otherwise
 * s = sign(w) and sqrt|e| is the positive root of q^2 + h alpha2 q - (|w| - h^2 alpha1).
 *
 * In an FMI step from t_k to t_k + h the FMU knows y_k, not y_{k+1}: the
 * corrector completes the interval that ends at t_k (one sample behind) and
 * the outputs are the prediction for t_k + h with the injection held. */
#ifndef IMPLICIT_TWISTING_H
#define IMPLICIT_TWISTING_H

#include "super_twisting.h"

/* Runs `count` steps (sto_run): at each sample the corrector completes the
 * interval that ends there (the first sample only takes the initial
 * estimates), then the nominal acceleration of the interval that starts is
 * evaluated at the corrected velocity and recorded. */
void implicit_run(SuperTwistingObserver *o, const double y[], const StoAcceleration a[], int count,
                  StoTrace *trace);

/* The leapfrog prediction for the end of the next interval from the
 * corrected position z1 and mid-interval velocity mid, with the injection v
 * held (shared with the linear members of noise_adaptive.c). */
static inline void implicit_predict(double z1, double mid, double a_mean, double a_current,
                                    double v, double h, double *x1, double *x2)
{
    const double mid_next = mid + h * (a_mean + v);
    *x1 = z1 + h * mid_next;
    *x2 = mid_next + 0.5 * h * (a_current + v);
}

/* x1_hat, x2_hat: the prediction for the end of the last interval with the
 * injection held (only the outputs need it, so it is not made every step). */
void implicit_outputs(SuperTwistingObserver *o);

#endif
