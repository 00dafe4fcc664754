/* Unit tests of the super-twisting observer (fmu/src/core/super_twisting.h)
 * on trajectories with a known solution, under both of its schemes
 * (observer_scheme.h: the paper's explicit Euler and the implicit step), and
 * of its filtered injection against the perturbation: run as
 * `test_super_twisting CASE` (check.h).
 *
 * The bounds were chosen around the measured figures (quoted next to each) so
 * that a wrong algorithm fails: a term dropped or scaled in (12) or (9) moves some
 * figure well past its bound (checked by mutating the core sources one term at a
 * time). */
#include <math.h>
#include <string.h>

#include "check.h"

#include "gains.h"
#include "observer_scheme.h"
#include "super_twisting.h"

static const char *scheme_name(int scheme) { return scheme == 1 ? "paper" : "implicit"; }

/* ---- observer on trajectories with a known solution ------------------------------- */

/* A trajectory x1(t) of x'' = known(t) + unknown(t).  The observer is given the known
 * part as its nominal acceleration; the unknown part xi is what z_eq must recover. */
typedef struct {
    double (*x1)(double t);
    double (*x2)(double t);
    double (*known)(double t);
    double (*unknown)(double t);
} Trajectory;

#define N_TOLERANCES 4
static const double TOLERANCES[N_TOLERANCES] = {1e-2, 3e-3, 1e-3, 1e-6};

typedef struct {
    double t_conv[N_TOLERANCES]; /* last time |x2 - x2_hat| >= TOLERANCES[j] (0: never) */
    double max_e2;               /* max |x2 - x2_hat| after t_after */
    double rms_xi;               /* RMS(z_filtered - xi) after t_after */
    double rms_lagged;           /* RMS(z_filtered - the same filter applied to xi) */
    double max_lagged;           /* max |z_filtered - filtered xi| after t_after */
} Observation;

/* Runs the observer from x1_hat = x2_hat = 0 for t_end seconds at h = 1e-4. */
static Observation observe(const Trajectory *tr, int scheme, double alpha1, double alpha2,
                           double tau, double t_after, double t_end)
{
    const double h = 1e-4;
    SuperTwistingObserver o;
    const double a1[1] = {alpha1}, a2[1] = {alpha2}, zero[1] = {0.0};
    st_init(&o, 1, h, a1, a2, tau, zero, zero);
    st_configure(&o, (StoScheme)scheme, 0.05);
    Observation r;
    memset(&r, 0, sizeof r);
    double reference = 0.0, sum_xi = 0.0, sum_lagged = 0.0;
    long n = 0;
    const long steps = (long)(t_end / h + 0.5);
    for (long k = 0; k < steps; ++k) {
        const double t = k * h, t1 = t + h;
        const double y[1] = {tr->x1(t)};
        const StoAcceleration nominal[1] = {{.held = tr->known(t), .viscous = 0.0, .coulomb = 0.0}};
        os_run(&o, y, nominal, 1, NULL);
        os_update_outputs(&o);
        /* the filter (9), discretized exactly as the observer does, applied to xi itself:
         * what z_filtered can at best be, lag included */
        reference += o.filter_gain * (tr->unknown(t) - reference);
        const double e2 = fabs(tr->x2(t1) - o.x2_hat[0]);
        for (int j = 0; j < N_TOLERANCES; ++j)
            if (e2 >= TOLERANCES[j]) r.t_conv[j] = t1;
        if (t1 >= t_after) {
            const double d_xi = o.z_filtered[0] - tr->unknown(t1);
            const double d_lagged = o.z_filtered[0] - reference;
            r.max_e2 = fmax(r.max_e2, e2);
            r.max_lagged = fmax(r.max_lagged, fabs(d_lagged));
            sum_xi += d_xi * d_xi;
            sum_lagged += d_lagged * d_lagged;
            ++n;
        }
    }
    r.rms_xi = sqrt(sum_xi / (double)n);
    r.rms_lagged = sqrt(sum_lagged / (double)n);
    return r;
}

/* x1 = sin t with the exact acceleration: xi = 0. */
static double sin_t(double t) { return sin(t); }
static double cos_t(double t) { return cos(t); }
static double minus_sin_t(double t) { return -sin(t); }
static double nothing(double t) { (void)t; return 0.0; }

/* x1 = 0.5 sin 2t with F = 0: everything, -2 sin 2t (|xi| <= 2), is unknown. */
static double x1_fast(double t) { return 0.5 * sin(2.0 * t); }
static double x2_fast(double t) { return cos(2.0 * t); }
static double a_fast(double t) { return -2.0 * sin(2.0 * t); }

/* x1 = sin t again, with an unknown xi = 0.5 sin 2t (or a square wave of amplitude
 * 0.5, the paper's "discontinuous perturbation") and the known part -sin t - xi. */
static double xi_sine(double t) { return 0.5 * sin(2.0 * t); }
static double known_sine(double t) { return -sin(t) - xi_sine(t); }
static double xi_square(double t) { return 0.5 * st_sign(sin(2.0 * t)); }
static double known_square(double t) { return -sin(t) - xi_square(t); }

/* Finite time, not asymptotic: once |e2| is at 1e-2, reaching the scheme's accuracy
 * floor (TOLERANCES[floor_index]: a few 1e-3 for the paper's explicit Euler, whose
 * chattering is O(h alpha1), 1e-6 for the implicit scheme) costs almost nothing more;
 * an exponential observer would pay ln(10)/lambda per decade. */
static int check_convergence(int scheme, const Observation *r, double t_bound, double max_e2,
                             int floor_index)
{
    int failures = 0;
    failures += check(r->t_conv[0] > 0.0 && r->t_conv[0] < t_bound,
                      "%s: |x2 - x2_hat| < 1e-2 from t = %.4f s on (bound %.2f s)",
                      scheme_name(scheme), r->t_conv[0], t_bound);
    const double extra = r->t_conv[floor_index] - r->t_conv[0];
    failures += check(extra < 0.01,
                      "%s: from 1e-2 down to %g in %.2g s more (finite time: bound 0.01 s)",
                      scheme_name(scheme), TOLERANCES[floor_index], extra);
    failures += check(r->max_e2 < max_e2, "%s: max |x2 - x2_hat| after 1 s = %.3g (bound %.1g)",
                      scheme_name(scheme), r->max_e2, max_e2);
    return failures;
}

static int observer_exact_model(void)
{
    const Trajectory tr = {sin_t, cos_t, minus_sin_t, nothing};
    int failures = 0;
    for (int scheme = 1; scheme <= 2; ++scheme) {
        /* x2(0) = 1, x2_hat(0) = 0.  Measured: 1e-2 at 0.495 s, 1e-3 at 0.4995 s (paper)
         * and 1e-6 at 0.5002 s (implicit); then max|e2| 2.5e-4 (paper: the O(h) chattering
         * of explicit Euler) and 8.4e-10 (implicit). */
        const Observation r = observe(&tr, scheme, 2.0, 5.0, 0.0, 1.0, 5.0);
        failures += check_convergence(scheme, &r, 0.6, scheme == 1 ? 5e-4 : 1e-8,
                                      scheme == 1 ? 2 : 3);
    }
    return failures;
}

static int observer_unknown_perturbation(void)
{
    const Trajectory tr = {x1_fast, x2_fast, nothing, a_fast};
    int failures = 0;
    for (int scheme = 1; scheme <= 2; ++scheme) {
        /* F = 0, |xi| <= 2 < alpha1 = 5.  Measured: 1e-2 at 0.185 s, 3e-3 (paper) 1.2 ms
         * later, 1e-6 (implicit) 2.1 ms later; max|e2| 1.9e-3
         * (paper), 7.3e-8 (implicit); RMS(zbar - xi) 0.061 (paper, tau = 20 ms: mostly the
         * filter lag, 2 * 2 * 0.02 / sqrt 2 = 0.057) and 5.6e-4 (implicit, no filter). */
        const double tau = scheme == 1 ? 0.02 : 0.0;
        const Observation r = observe(&tr, scheme, 5.0, 8.0, tau, 1.0, 6.0);
        failures += check_convergence(scheme, &r, 0.3, scheme == 1 ? 3e-3 : 1e-6,
                                      scheme == 1 ? 1 : 3);
        failures += check(r.rms_xi < (scheme == 1 ? 0.07 : 1e-3),
                          "%s: RMS(z_eq filtered - xi) after 1 s = %.3g (bound %g)",
                          scheme_name(scheme), r.rms_xi, scheme == 1 ? 0.07 : 1e-3);
    }
    return failures;
}

static int filtered_injection_recovers_perturbation(void)
{
    int failures = 0;
    /* Gains by Theorem 3.1 from f+ = 1 > |xi| = 0.5, p = 0.5: alpha1 = 2,
     * alpha2 = 1.1 sqrt(2/1) 3 * 3 = 14.0. */
    double alpha1 = 0.0, alpha2 = 0.0;
    const int rc = gains_complete(1.0, 0.5, &alpha1, &alpha2);
    failures += check(rc == 0 && alpha1 == 2.0 &&
                      fabs(alpha2 - 1.1 * sqrt(2.0) * 9.0) < 1e-12,
                      "gains from f+ = 1, p = 0.5: alpha1 = %g, alpha2 = %.6g", alpha1, alpha2);

    /* xi = 0.5 sin 2t, tau = 0.02, h = 1e-4.  The first-order filter lags it: the
     * error zbar - xi of a perfect injection is 0.5 * 2 tau / sqrt(1 + (2 tau)^2) in
     * amplitude, RMS 0.01413.  What the observer adds to the lag is measured against
     * the same filter applied to xi.  Measured: implicit RMS(zbar - xi) 0.01422,
     * RMS(zbar - filtered xi) 1.05e-4 (one sample of delay); paper 0.0297 and 0.0213
     * (its injection chatters between +-alpha1, and the filter passes some of it). */
    const Trajectory sine = {sin_t, cos_t, known_sine, xi_sine};
    const double lag_rms = 0.5 * 0.04 / sqrt(1.0 + 0.04 * 0.04) / sqrt(2.0);
    for (int scheme = 1; scheme <= 2; ++scheme) {
        const Observation r = observe(&sine, scheme, alpha1, alpha2, 0.02, 2.0, 10.0);
        failures += check(r.t_conv[0] > 0.0 && r.t_conv[0] < 0.7,
                          "%s, xi = 0.5 sin 2t: |x2 - x2_hat| < 1e-2 from t = %.4f s (bound 0.7)",
                          scheme_name(scheme), r.t_conv[0]);
        if (scheme == 1) {
            failures += check(r.rms_xi < 0.04,
                              "paper: RMS(zbar - xi) after 2 s = %.4f (bound 0.04; the lag "
                              "alone is %.4f)", r.rms_xi, lag_rms);
            failures += check(r.rms_lagged < 0.03,
                              "paper: RMS(zbar - filtered xi) = %.4f (bound 0.03)",
                              r.rms_lagged);
        } else {
            failures += check(fabs(r.rms_xi - lag_rms) < 0.05 * lag_rms,
                              "implicit: RMS(zbar - xi) after 2 s = %.5f, the filter lag "
                              "%.5f within 5 percent", r.rms_xi, lag_rms);
            failures += check(r.rms_lagged < 2e-4 && r.max_lagged < 5e-4,
                              "implicit: RMS(zbar - filtered xi) = %.3g, max %.3g "
                              "(bounds 2e-4, 5e-4)", r.rms_lagged, r.max_lagged);
        }
    }

    /* The paper's discontinuous perturbation, with its tau = 2 ms: a square wave of
     * amplitude 0.5.  Measured RMS(zbar - filtered xi): paper 0.084, implicit 1.9e-3
     * (max 0.071 right after a jump: one sample of delay, times 1 - exp(-h/tau)). */
    const Trajectory square = {sin_t, cos_t, known_square, xi_square};
    for (int scheme = 1; scheme <= 2; ++scheme) {
        const Observation r = observe(&square, scheme, alpha1, alpha2, 0.002, 2.0, 10.0);
        const double bound = scheme == 1 ? 0.11 : 3e-3;
        failures += check(r.rms_lagged < bound,
                          "%s, square-wave xi, tau = 2 ms: RMS(zbar - filtered xi) = %.3g "
                          "(bound %g), RMS(zbar - xi) = %.3g", scheme_name(scheme),
                          r.rms_lagged, bound, r.rms_xi);
    }
    return failures;
}

int main(int argc, char **argv)
{
    static const TestCase cases[] = {
        {"observer_exact_model", observer_exact_model},
        {"observer_unknown_perturbation", observer_unknown_perturbation},
        {"filtered_injection_recovers_perturbation", filtered_injection_recovers_perturbation},
    };
    return run_cases("test_super_twisting", cases, sizeof cases / sizeof cases[0], argc, argv);
}
