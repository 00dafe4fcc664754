/* Unit tests of the inputs' cadence (fmu/src/core/input_cadence.h): run as
 * `test_input_cadence CASE` (check.h). */
#include <string.h>

#include "check.h"

#include "input_cadence.h"
#include "tuning.h"

#define H 1e-3                     /* 2000 internal steps per window */
#define SECONDS 5
#define STEPS (SECONDS * 1000)

/* A sampled signal that changes every `hold` internal steps: value k / hold. */
static void run(InputCadence *c, int hold, int chunk)
{
    const double start[2] = {0.0, 0.0};
    ic_init(c, 2, start, H, 0.0);
    for (int k = 0; k < STEPS; k += chunk) {
        const double values[2] = {(double)(k / hold), 0.5};
        ic_advance(c, values, (unsigned long long)chunk);
    }
}

static int every_sample_is_not_a_staircase(void)
{
    InputCadence c;
    run(&c, 1, 1);
    return check(ic_shortest(&c) == 1 && !ic_coarse(&c),
                 "inputs new at every step: shortest hold %d step(s), coarse %d (expected 1, 0)",
                 ic_shortest(&c), ic_coarse(&c));
}

static int a_coarse_communication_step_is_a_staircase(void)
{
    InputCadence c;
    run(&c, 40, 40); /* fmpy's default: every 40th sample of a 1 kHz log */
    int failed = check(ic_shortest(&c) == 40 && ic_coarse(&c),
                       "inputs held 40 steps: shortest %d, coarse %d (expected 40, 1)",
                       ic_shortest(&c), ic_coarse(&c));
    run(&c, 1000, 1000); /* a 1 s step: half the window, the longest seen */
    failed += check(ic_shortest(&c) == 1000 && ic_coarse(&c),
                    "inputs held 1000 steps: shortest %d, coarse %d (expected 1000, 1)",
                    ic_shortest(&c), ic_coarse(&c));
    run(&c, 2, 1); /* every other sample: the least staircase */
    failed += check(ic_shortest(&c) == 2 && ic_coarse(&c),
                    "inputs held 2 steps: shortest %d, coarse %d (expected 2, 1)",
                    ic_shortest(&c), ic_coarse(&c));
    return failed;
}

/* The same inputs through communication steps of 1, 10 and 7 internal steps:
 * the same cadence state, byte for byte. */
static int the_communication_step_does_not_matter(void)
{
    int failed = 0;
    for (int hold = 1; hold <= 50; hold += 7) {
        InputCadence one, ten;
        run(&one, hold * 10, 1);
        run(&ten, hold * 10, 10);
        failed += check(memcmp(&one, &ten, sizeof one) == 0 && ic_shortest(&one) == hold * 10,
                        "hold %d: steps of 1 and of 10 give shortest %d and %d, states %s",
                        hold * 10, ic_shortest(&one), ic_shortest(&ten),
                        memcmp(&one, &ten, sizeof one) == 0 ? "equal" : "different");
    }
    /* a step that does not divide the hold: changes seen late, by up to 6 steps */
    InputCadence seven;
    run(&seven, 40, 7);
    failed += check(ic_shortest(&seven) >= 35 && ic_shortest(&seven) <= 42,
                    "hold 40 seen through steps of 7: shortest %d (35 .. 42)",
                    ic_shortest(&seven));
    return failed;
}

static int inputs_at_rest_are_not_a_staircase(void)
{
    InputCadence c;
    const double still[1] = {1.0};
    ic_init(&c, 1, still, H, 0.0);
    ic_advance(&c, still, 5000);
    int failed = check(ic_shortest(&c) == 0 && !ic_coarse(&c),
                       "inputs at rest: shortest %d, coarse %d (expected 0, 0)", ic_shortest(&c),
                       ic_coarse(&c));
    /* motion after rest, starting at the end of a window: the long hold at rest is
     * not a staircase; the motion's holds of one step are what counts */
    double value = 1.0;
    ic_advance(&c, &value, (unsigned long long)(c.window - 1 - c.window_age));
    int ever_coarse = 0;
    for (int k = 0; k < 4000; ++k) {
        value += 1.0;
        ic_advance(&c, &value, 1);
        ever_coarse |= ic_coarse(&c);
    }
    failed += check(ic_shortest(&c) == 1 && !ever_coarse,
                    "rest, then motion at every step: shortest %d, ever coarse %d (expected 1, 0)",
                    ic_shortest(&c), ever_coarse);
    return failed;
}

/* An internal step finer than the log's period on purpose (input_period): a hold of
 * that period is expected, a longer one is a staircase. */
static int a_stated_period_is_expected(void)
{
    InputCadence c;
    const double start[1] = {0.0};
    int failed = 0;
    for (int hold = 1; hold <= 8; hold *= 2) {
        ic_init(&c, 1, start, H, 4 * H);
        for (int k = 0; k < STEPS; k += hold) {
            const double value = (double)(k / hold);
            ic_advance(&c, &value, (unsigned long long)hold);
        }
        failed += check(ic_shortest(&c) == hold && ic_coarse(&c) == (hold > 4),
                        "period 4 h, inputs held %d steps: coarse %d (expected %d)", hold,
                        ic_coarse(&c), hold > 4);
    }
    return failed;
}

int main(int argc, char **argv)
{
    static const TestCase cases[] = {
        {"every_sample_is_not_a_staircase", every_sample_is_not_a_staircase},
        {"a_coarse_communication_step_is_a_staircase", a_coarse_communication_step_is_a_staircase},
        {"the_communication_step_does_not_matter", the_communication_step_does_not_matter},
        {"inputs_at_rest_are_not_a_staircase", inputs_at_rest_are_not_a_staircase},
        {"a_stated_period_is_expected", a_stated_period_is_expected},
    };
    return run_cases("test_input_cadence", cases, sizeof cases / sizeof cases[0], argc, argv);
}
