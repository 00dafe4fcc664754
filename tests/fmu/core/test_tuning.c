/* Unit tests of the core's run-time tuning (fmu/src/core/tuning.h): run as
 * `test_tuning CASE` (check.h). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"

#include "information_identifier.h"
#include "model_feedback.h"
#include "tuning.h"

/* The other groups of the run-time tuning: the defaults pass, a bad value is named,
 * and each part honours its group. */
static int tuning_groups(void)
{
    const StoTuning defaults = tuning_default();
    int failed = check(tuning_problem(&defaults) == NULL, "the defaults have no problem");
    StoTuning t = defaults;
    t.implicit.learning_gain = 0.0;
    const char *problem = tuning_problem(&t);
    failed += check(problem && strstr(problem, "learning_gain"), "learning_gain 0: %s",
                    problem ? problem : "(none)");
    t = defaults;
    t.leave_out.rest_memory = -1.0;
    problem = tuning_problem(&t);
    failed += check(problem && strstr(problem, "rest_memory"), "rest_memory -1: %s",
                    problem ? problem : "(none)");
    t = defaults;
    t.feedback.ramp = 0.0;
    problem = tuning_problem(&t);
    failed += check(problem && strstr(problem, "feedback.ramp"), "feedback ramp 0: %s",
                    problem ? problem : "(none)");
    t = defaults;
    t.bank.hysteresis = 2.0;
    problem = tuning_problem(&t);
    failed += check(problem && strstr(problem, "hysteresis"), "the bank's part checked too: %s",
                    problem ? problem : "(none)");

    /* the identifier takes its windows and the leave-out rule */
    const double h = 1e-3;
    InformationIdentifier *id = calloc(2, sizeof *id);
    if (!id) return failed + 1;
    t = defaults;
    t.identifier.batch_window = 2.0 * defaults.identifier.batch_window;
    t.leave_out.skip_share = 2.0 * defaults.leave_out.skip_share;
    ii_init(&id[0], IDENTIFIER_MFF, 1, 2, h, 1e-3, 0.9, 0, NULL);
    ii_init(&id[1], IDENTIFIER_MFF, 1, 2, h, 1e-3, 0.9, 0, &t);
    failed += check(fabs(id[1].leave_out.skip_threshold - 2.0 * id[0].leave_out.skip_threshold) <=
                        1e-15 * id[0].leave_out.skip_threshold,
                    "twice the skip share, twice the threshold (%g, %g)", id[0].leave_out.skip_threshold,
                    id[1].leave_out.skip_threshold);
    failed += check(fabs(id[1].batch_gain + expm1(-h / t.identifier.batch_window)) < 1e-18 &&
                        id[1].batch_gain < id[0].batch_gain,
                    "the batch window honoured (gain %g, default %g)", id[1].batch_gain,
                    id[0].batch_gain);
    free(id);

    /* model feedback: nothing before its start, then the ramp */
    FeedbackTuning f = defaults.feedback;
    const double at = f.start + 0.5 * f.ramp;
    const double w = mf_weight(&f, 1.0, 0.0, at);
    failed += check(fabs(w - 0.5) < 1e-12, "half the ramp, an exact correction: weight %g", w);
    f.start = at + 1.0;
    failed += check(mf_weight(&f, 1.0, 0.0, at) == 0.0, "a later start: weight 0");
    return failed;
}

int main(int argc, char **argv)
{
    static const TestCase cases[] = {
        {"tuning_groups", tuning_groups},
    };
    return run_cases("test_tuning", cases, sizeof cases / sizeof cases[0], argc, argv);
}
