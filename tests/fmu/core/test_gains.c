/* Unit tests of the observer gains from Theorem 3.1
 * (fmu/src/core/gains.h): run as `test_gains CASE` (check.h).
 *
 * The bounds were chosen around the measured figures (quoted next to each) so
 * that a wrong algorithm fails: a term dropped or scaled in (6) moves some
 * figure well past its bound (checked by mutating the core sources one term at a
 * time). */
#include <math.h>

#include "check.h"

#include "gains.h"

/* ---- Theorem 3.1, condition (6) ----------------------------------------------------- */

static int theorem_gains(void)
{
    int failures = 0;
    /* Hand computation of sqrt(2 / (alpha1 - f+)) (alpha1 + f+) (1 + p) / (1 - p):
     *   alpha1 = 20, f+ = 10, p = 0.5:  sqrt(2/10) * 30 * 1.5/0.5 = 0.4472135955 * 90
     *                                   = 40.2492235950
     *   alpha1 = 3,  f+ = 1,  p = 0.2:  sqrt(2/2) * 4 * 1.2/0.8 = 6
     *   alpha1 = 7,  f+ = 5,  p = 0.5:  sqrt(2/2) * 12 * 3 = 36, times 1.1 = 39.6
     *   alpha1 = 2,  f+ = 1,  p = 0.5:  sqrt(2/1) * 3 * 3 = 12.7279220614, times 1.1 = 14.0007 */
    const double bound = gains_alpha2_bound(20.0, 10.0, 0.5);
    failures += check(fabs(bound - 40.2492235949962) < 1e-9,
                      "bound(alpha1 = 20, f+ = 10, p = 0.5) = %.10f, by hand 40.2492235950", bound);
    const double six = gains_alpha2_bound(3.0, 1.0, 0.2);
    failures += check(fabs(six - 6.0) < 1e-12, "bound(3, 1, 0.2) = %.12g, by hand 6", six);
    failures += check(isinf(gains_alpha2_bound(1.0, 1.0, 0.5)) &&
                      isinf(gains_alpha2_bound(0.5, 1.0, 0.5)),
                      "alpha1 <= f+ admits no alpha2: the bound is +inf");

    double a1 = 0.0, a2 = 0.0;
    int rc = gains_complete(10.0, 0.5, &a1, &a2);
    failures += check(rc == 0 && a1 == 20.0 && fabs(a2 - 1.1 * 40.2492235949962) < 1e-9,
                      "both from f+ = 10, p = 0.5: alpha1 = %g (2 f+), alpha2 = %.9g (1.1 * "
                      "40.2492236 = 44.2741460)", a1, a2);
    a1 = 7.0, a2 = 0.0;
    rc = gains_complete(5.0, 0.5, &a1, &a2);
    failures += check(rc == 0 && a1 == 7.0 && fabs(a2 - 39.6) < 1e-9,
                      "alpha1 = 7 given, f+ = 5: alpha2 = %.12g (by hand 39.6)", a2);
    a1 = 2.0, a2 = 3.0;
    rc = gains_complete(0.0, 0.5, &a1, &a2);
    failures += check(rc == 0 && a1 == 2.0 && a2 == 3.0,
                      "given gains are kept even with f+ = 0: %g, %g", a1, a2);
    /* the error returns */
    a1 = 0.0, a2 = 3.0;
    rc = gains_complete(0.0, 0.5, &a1, &a2);
    failures += check(rc == -1, "alpha1 = 0 with f+ = 0: returns %d (expected -1)", rc);
    a1 = 4.0, a2 = 0.0;
    rc = gains_complete(0.0, 0.5, &a1, &a2);
    failures += check(rc == -1, "alpha2 = 0 with f+ = 0: returns %d (expected -1)", rc);
    a1 = 0.0, a2 = 0.0;
    rc = gains_complete(0.0, 0.5, &a1, &a2);
    failures += check(rc == -1, "both 0 with f+ = 0: returns %d (expected -1)", rc);
    a1 = 3.0, a2 = 0.0;
    rc = gains_complete(5.0, 0.5, &a1, &a2);
    failures += check(rc == -1, "alpha2 = 0 with a given alpha1 = 3 <= f+ = 5: returns %d "
                      "(expected -1: (6) has no bound)", rc);
    return failures;
}

int main(int argc, char **argv)
{
    static const TestCase cases[] = {
        {"theorem_gains", theorem_gains},
    };
    return run_cases("test_gains", cases, sizeof cases / sizeof cases[0], argc, argv);
}
