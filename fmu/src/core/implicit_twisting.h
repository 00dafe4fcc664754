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

#include "tuning.h"

#include <math.h>

#include "super_twisting.h"

/* The Coulomb level is learned from the injection's jump at velocity
 * reversals: a nominal model whose Coulomb coefficient is off by dc leaves
 * -dc sign(v) in the perturbation, which the injection held over a sample
 * carries across a reversal, an error of up to 2 dc h on the velocity in the
 * samples after it (exact 1 kHz data, c3 off by 0.4, with the sign change
 * of it_coulomb_mean_acceleration: up to 9e-4 rad/s, the RMS error 5.7e-5 where
 * it is 1.5e-5 away from reversals; with the learning 1.7e-5).  The injection's
 * change from the sample before a reversal to IMPLICIT_REVERSAL_SAMPLES after
 * it (the second differences that do not span it) is -2 (dc - learned)
 * sign(v) plus the smooth perturbation's change; the learned level moves by
 * the learning gain (IMPLICIT_LEARNING_GAIN) of the difference, and only between injections in
 * the sliding set (exact data: on noisy data the injection saturates).  The
 * injection is published relative to the nominal level, so the identifier
 * and z_eq see the same perturbation as without learning. */

/* The published prediction (it_outputs) takes the injection's trend
 * where it is smooth: a perturbation that changes (a nominal b 10 % off with
 * a multi-sine input) is otherwise held one to 1.75 samples behind where the
 * prediction uses it (exact 1 kHz data, J +10 %: velocity RMS 3.2e-5, the
 * Kalman filter 2.6e-5; now 1.3e-5).  The trend is the change over two
 * samples (over one it follows the input's sample-to-sample ripple: at
 * 10 kHz 5.6e-7 where the held injection gives 3.0e-7), taken only after
 * IMPLICIT_SMOOTH_SAMPLES in the sliding set without a velocity reversal
 * (2.8e-7; 3.5e-7 without that condition), so that noise (a saturating
 * injection) and the Coulomb jumps are never extrapolated. */

/* The mean of sign(v) over one interval next to a sample, weighted as the
 * triangle below weighs it (1 at the sample, 0 at the neighbour), with v
 * linear from v_sample to v_neighbour. */
static inline double it_half_mean_sign(double v_sample, double v_neighbour)
{
    if (v_sample * v_neighbour >= 0.0) return st_sign(v_sample != 0.0 ? v_sample : v_neighbour);
    const double outer = fabs(v_neighbour) / (fabs(v_sample) + fabs(v_neighbour));
    return st_sign(v_sample) * (1.0 - 2.0 * outer * outer); /* the neighbour's sign weighs outer^2 */
}

/* The Coulomb regressor that matches the injection at a sample: the
 * injection is a second difference of the measurements around the sample
 * before, the acceleration weighted by the triangle (h - |t|) / h^2 over the
 * two intervals around it, so the Coulomb term it holds is that mean of
 * sign(v), not the sign at the sample.  v_before, v, v_after: the velocity
 * at the samples (taken linear between them).  With sign(v) instead, each
 * velocity reversal put up to one sample of the wrong sign into the
 * regression. */
static inline double it_mean_sign(double v_before, double v, double v_after)
{
    return 0.5 * (it_half_mean_sign(v, v_before) + it_half_mean_sign(v, v_after));
}

/* The implicit injection for the innovation w = y_k - (prediction without
 * injection), reach = h^2 alpha1 and b = h alpha2: sets the injection *v and
 * returns e = y_k - x1_k (0 in the sliding set), and counts the step in the
 * convergence detector (rate, previous_sign). */
static inline double it_inject(double w, double reach, double b, double alpha1,
                                     double inverse_h2, double *v, double *rate,
                                     double *previous_sign, double rate_gain)
{
    if (fabs(w) <= reach) { /* sliding: the injection keeps x1_hat on y */
        *v = w * inverse_h2;
        st_track_switching(rate, previous_sign, rate_gain, 0.0);
        return 0.0;
    }
    const double sign_w = w > 0.0 ? 1.0 : -1.0, r = fabs(w) - reach;
    const double q = 2.0 * r / (b + sqrt(b * b + 4.0 * r)); /* stable root form */
    const double e = sign_w * q * q;
    *v = alpha1 * sign_w;
    st_track_switching(rate, previous_sign, rate_gain, e != 0.0 ? sign_w : 0.0);
    return e;
}

/* The corrector at sample y (the super-twisting observer's and the robot
 * observer's): the innovation w against the leapfrog prediction without
 * injection from the corrected position z1, the mid-interval velocity mid and
 * the nominal mean acceleration a_mean; sets the injection (it_inject),
 * completes the interval (mid) and corrects the position (z1).  Returns w. */
static inline double it_correct(double y, double a_mean, double h, double h2, double reach,
                                      double b, double alpha1, double inverse_h2,
                                      double rate_gain, double *z1, double *mid, double *v,
                                      double *rate, double *previous_sign)
{
    const double w = y - *z1 - h * *mid - h2 * a_mean;
    const double e =
        it_inject(w, reach, b, alpha1, inverse_h2, v, rate, previous_sign, rate_gain);
    *mid += h * (a_mean + *v);
    *z1 = y - e;
    return w;
}

/* Runs `count` steps (os_run): at each sample the corrector completes the
 * interval that ends there (the first sample only takes the initial
 * estimates), then the nominal acceleration of the interval that starts is
 * evaluated at the corrected velocity and recorded. */
void it_run(SuperTwistingObserver *o, const double y[], const StoAcceleration a[], int count,
                  StoTrace *trace);

/* The mean acceleration over dt from the velocity v0 when every term but the
 * Coulomb one sums to `other` (injection included): if the velocity reaches 0
 * within dt, the Coulomb term changes sign there, or holds the velocity at 0
 * (sticking) when the rest is within the Coulomb level.  The Coulomb term of
 * the sign at the start over the whole dt put an error of up to 2 coulomb dt
 * on the velocity after every reversal, and the injection took up the same
 * error over the next samples: on exact 1 kHz data spikes of up to 1e-3 rad/s
 * in the 2-3 samples after each reversal, the velocity's RMS error 6.2e-5
 * where it is 1.5e-5 away from the reversals (bench/reversal_errors.py). */
static inline double it_coulomb_mean_acceleration(double v0, double other, double coulomb, double dt)
{
    const double s = st_sign(v0), a = other - coulomb * s;
    if (!(coulomb > 0.0)) return a;
    if (s == 0.0) /* at rest: moves once the rest beats the Coulomb level */
        return fabs(other) <= coulomb ? 0.0 : other - coulomb * st_sign(other);
    if ((v0 + a * dt) * s >= 0.0) return a; /* no reversal within dt */
    const double after = other + coulomb * s; /* the other sign's */
    const double v_end = after * s < 0.0 ? after * (dt + v0 / a) : 0.0;
    return (v_end - v0) / dt;
}

/* The leapfrog prediction for the end of the next interval from the
 * corrected position z1 and mid-interval velocity mid (shared with the
 * linear members of noise_adaptive.c).  a_rest: the nominal acceleration of
 * the interval without its Coulomb term.  The injection v holds the
 * perturbation at the sample before; with its change per sample dv the
 * perturbation is taken at the samples it is used for: one sample on over
 * the next interval, 1.75 samples on over its second half (dv = 0: held). */
static inline void it_predict(double z1, double mid, double a_mean, double a_rest,
                                    double coulomb, double v, double dv, double h, double *x1,
                                    double *x2)
{
    const double mid_next = mid + h * (a_mean + v + dv);
    *x1 = z1 + h * mid_next;
    *x2 = mid_next + 0.5 * h * it_coulomb_mean_acceleration(mid_next, a_rest + v + 1.75 * dv,
                                                         coulomb, 0.5 * h);
}

/* After the corrector of an interval: the velocity at its end from the
 * mid-interval velocity, and the mean of the nominal accelerations of its
 * second half and of the first half of the interval that starts (the
 * leapfrog's next velocity increment).  *a_free gets the new interval's
 * acceleration without its Coulomb and position terms (the position term is
 * the sample's over both halves); v is the injection. */
static inline double it_advance(double mid, double v, StoAcceleration a, double h,
                                      double *a_free, double *a_mean)
{
    const double half = 0.5 * h;
    const double rest = a.point + v;
    const double second = it_coulomb_mean_acceleration(mid, *a_free + rest, a.coulomb, half);
    const double x2 = mid + half * second;
    *a_free = a.held - a.viscous * x2;
    const double first = it_coulomb_mean_acceleration(x2, *a_free + rest, a.coulomb, half);
    *a_mean = 0.5 * (second + first) - v;
    return x2;
}

/* x1_hat, x2_hat: the prediction for the end of the last interval with the
 * injection held (only the outputs need it, so it is not made every step). */
void it_outputs(SuperTwistingObserver *o);

#endif
