/* Unit tests of the implicit super-twisting step
 * (fmu/src/core/implicit_twisting.h) across velocity reversals: the Coulomb
 * level it learns and the mean sign around a reversal: run as
 * `test_implicit_twisting CASE` (check.h). */
#include <math.h>

#include "check.h"

#include "implicit_twisting.h"
#include "observer_scheme.h"
#include "super_twisting.h"

/* ---- velocity reversals with a Coulomb term (implicit scheme) ---------------------- */

/* x1 = sin t (exact samples) with the nominal -sin t - c sign(v), c = 0.3: the data
 * have no Coulomb friction, the perturbation is +c sign(v).  The injection held over a
 * sample carries -c sign(v) of the old sign across each reversal; the Coulomb level
 * learned from the injection's jumps takes it out (implicit_twisting.h).  Measured
 * (h = 1e-4, t in [30, 40] s, after 9 reversals): learned -0.29996 (exact: -c), the
 * largest velocity error within 3 samples of a reversal 6.4e-8 and elsewhere 9.7e-10;
 * without learning (IMPLICIT_LEARNING_GAIN 0) 6.6e-5 near reversals.  z_eq is published
 * relative to the nominal: |z_eq - c sign v| 5.1e-5 away from reversals (the held
 * -sin t_k leaves h/2 cos t in the injection); the raw injection would be off by c. */
#define PI 3.14159265358979323846 /* M_PI is not C11 */
static int coulomb_level_learned(void)
{
    const double h = 1e-4, c = 0.3;
    SuperTwistingObserver o;
    const double a1[1] = {2.0}, a2[1] = {5.0}, x0[1] = {0.0}, v0[1] = {1.0};
    st_init(&o, 1, h, a1, a2, 0.0, x0, v0);
    st_configure(&o, STO_SCHEME_IMPLICIT, 0.05);
    double near = 0.0, away = 0.0, z_error = 0.0;
    const long steps = (long)(40.0 / h + 0.5);
    for (long k = 0; k < steps; ++k) {
        const double t = k * h, t1 = t + h;
        const double y[1] = {sin(t)};
        const StoAcceleration nominal[1] = {{.held = -sin(t), .viscous = 0.0, .coulomb = c}};
        os_run(&o, y, nominal, 1, NULL);
        os_update_outputs(&o);
        if (t1 < 30.0) continue;
        /* distance to the nearest reversal, t = pi/2 + j pi, in samples */
        const double from_reversal = fabs(remainder(t1 - 0.5 * PI, PI)) / h;
        const double e2 = fabs(cos(t1) - o.x2_hat[0]);
        if (from_reversal <= 3.0) near = fmax(near, e2);
        else {
            away = fmax(away, e2);
            z_error = fmax(z_error, fabs(o.z_eq[0] - c * st_sign(cos(t))));
        }
    }
    int failures = 0;
    failures += check(fabs(o.implicit.coulomb_learned[0] + c) < 1e-3,
                      "learned Coulomb level %.6f (expected %g)", o.implicit.coulomb_learned[0], -c);
    failures += check(near < 1e-7, "max |e2| within 3 samples of a reversal %.3g (bound 1e-7)",
                      near);
    failures += check(away < 1e-8, "max |e2| elsewhere %.3g (bound 1e-8)", away);
    failures += check(z_error < 1e-4, "max |z_eq - c sign v| away from reversals %.3g "
                      "(bound 1e-4)", z_error);
    return failures;
}

/* it_mean_sign: the triangle-weighted mean of sign(v) around a sample. */
static int mean_sign_of_a_reversal(void)
{
    int failures = 0;
    const struct { double before, v, after, expected; } cases[] = {
        {1.0, 2.0, 3.0, 1.0},     /* no reversal */
        {-1.0, 0.0, 1.0, 0.0},    /* at the sample: half each side */
        {1.0, 1.0, -1.0, 0.75},   /* halfway to the next sample: 1/4 of that side's weight */
        {-1.0, -3.0, 1.0, -0.9375}, /* 3/4 of the way: 1/16 of that side's weight flips */
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        const double m = it_mean_sign(cases[i].before, cases[i].v, cases[i].after);
        failures += check(fabs(m - cases[i].expected) < 1e-15, "mean sign (%g, %g, %g) = %.17g "
                          "(expected %g)", cases[i].before, cases[i].v, cases[i].after, m,
                          cases[i].expected);
    }
    return failures;
}

int main(int argc, char **argv)
{
    static const TestCase cases[] = {
        {"coulomb_level_learned", coulomb_level_learned},
        {"mean_sign_of_a_reversal", mean_sign_of_a_reversal},
    };
    return run_cases("test_implicit_twisting", cases, sizeof cases / sizeof cases[0], argc, argv);
}
