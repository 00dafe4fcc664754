/* Unit tests of MFF's rule that leaves uninformative samples out
 * (fmu/src/core/leave_out.h): run as `test_leave_out CASE` (check.h). */
#include <math.h>

#include "check.h"

#include "leave_out.h"

static LeaveOut rule_of(double h, double R, double p)
{
    const LeaveOutTuning tuning = tuning_default().leave_out;
    LeaveOut rule;
    leave_out_init(&rule, &tuning, pow(R, h), 1e-6, R, p);
    return rule;
}

static int uses_samples_of_their_share(void)
{
    const double h = 1e-3, R = 0.5;
    LeaveOut rule = rule_of(h, R, 3.0);
    double lambda = 0.0, pull = 0.0;
    int failed = 0;
    const int used = leave_out_decide(&rule, 1.01 * rule.skip_threshold, h, &lambda, &pull);
    failed += check(used == 1 && lambda == rule.reference_lambda && pull == rule.reference_pull,
                    "a sample just above the threshold %g is used with Pref's memory (%d)",
                    rule.skip_threshold, used);
    const int left = leave_out_decide(&rule, 0.99 * rule.skip_threshold, h, &lambda, &pull);
    failed += check(left == 0 && lambda == rule.rest_lambda &&
                        rule.rest_lambda > rule.reference_lambda,
                    "one just below is left out, Pref forgetting slower (%d, lambda %.12f > %.12f)",
                    left, lambda, rule.reference_lambda);
    const LeaveOut twice = rule_of(h, R, 6.0);
    failed += check(fabs(twice.skip_threshold - 2.0 * rule.skip_threshold) <=
                        1e-15 * rule.skip_threshold,
                    "twice the parameters, twice the threshold (%g, %g)", rule.skip_threshold,
                    twice.skip_threshold);
    return failed;
}

static int freezes_after_a_gap_of_its_memories(void)
{
    const double h = 1e-3, R = 0.5;
    LeaveOut rule = rule_of(h, R, 3.0);
    const double limit = tuning_default().leave_out.gap_memory / -log(R);
    double lambda, pull;
    int failed = 0, first_rest = -1;
    for (int k = 1; k <= 1000 && first_rest < 0; ++k)
        if (leave_out_decide(&rule, 0.0, h, &lambda, &pull) < 0) first_rest = k;
    failed += check(first_rest >= 0 && fabs(first_rest * h - limit) <= 1.0001 * h,
                    "a gap freezes the sums after gap_memory memories (%d samples, %g s; %g s)",
                    first_rest, first_rest * h, limit);
    const int used = leave_out_decide(&rule, 2.0 * rule.skip_threshold, h, &lambda, &pull);
    failed += check(used == 1 && rule.gap_time == 0.0,
                    "an informative sample ends the gap (%d, gap %g s)", used, rule.gap_time);
    return failed;
}

int main(int argc, char **argv)
{
    static const TestCase cases[] = {
        {"uses_samples_of_their_share", uses_samples_of_their_share},
        {"freezes_after_a_gap_of_its_memories", freezes_after_a_gap_of_its_memories},
    };
    return run_cases("test_leave_out", cases, sizeof cases / sizeof cases[0], argc, argv);
}
