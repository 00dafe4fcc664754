/* Unit tests of the noise-adaptive bank (fmu/src/core/noise_adaptive.h): its
 * selection rules (adaptive_rules.h) and its tuning: run as
 * `test_noise_adaptive CASE` (check.h). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "check.h"

#include "adaptive_rules.h"
#include "noise_adaptive.h"
#include "tuning.h"

/* ---- the noise-adaptive bank's selection rules (adaptive_rules.h) ------------------ */

/* Each rule on a crafted bank of three members for DOF 0: the statistics set by
 * hand, the choice checked against what the rule says. */
static int adaptive_rules(void)
{
    AdaptiveBank *bank = calloc(1, sizeof *bank);
    if (!bank) return 1;
    const int ST = ADAPTIVE_SUPER_TWISTING, P = ADAPTIVE_RANK_PERTURBATION,
              V = ADAPTIVE_RANK_VELOCITY;
    AdaptiveMember *m = bank->member[0];
    bank->tuning = tuning_default().bank;
    bank->count = 3;
    for (int s = 0; s < ADAPTIVE_ZOOM; ++s) bank->zoom_index[0][s] = -1;
    bank->center[0] = -1;
    m[0].stats.mean_square = 3.0, m[1].stats.mean_square = 1.0, m[2].stats.mean_square = 2.0;
    int failed = check(ar_quietest_member(bank, 0) == 1, "quietest member: 1 of {3, 1, 2}");

    /* ranking with hysteresis */
    int best = -1;
    bank->sta[0].ranking[P] = 1.0;
    m[0].stats.ranking[P] = 0.95, m[1].stats.ranking[P] = 2.0, m[2].stats.ranking[P] = 3.0;
    failed += check(ar_choose(bank, 0, ST, P, &best) == ST && best == 0,
                    "0.95 does not beat the super-twisting 1.0 by the hysteresis %g",
                    ADAPTIVE_HYSTERESIS);
    m[0].stats.ranking[P] = 0.8;
    failed += check(ar_choose(bank, 0, ST, P, &best) == 0, "0.8 beats 1.0: member 0");
    failed += check(ar_choose(bank, 0, 0, P, &best) == 0, "the current member stays");

    /* exact data and saturation */
    bank->sta[0].mean_square = 0.1; /* below 0.25 of the quietest member's 1.0 */
    failed += check(ar_exact_data(bank, 0), "exact data: the super-twisting observer kept");
    const AdaptiveSelection kept = ar_select(bank, 0, 1, 2);
    failed += check(kept.selected == ST && kept.source == ST, "exact data overrides the choice");
    bank->sta_saturation[0] = 0.2;
    failed += check(!ar_exact_data(bank, 0), "a saturating injection is not exact data");
    bank->sta[0].ranking[P] = 0.5; /* the super-twisting perturbation ranks best ... */
    failed += check(ar_perturbation_choice(bank, 0, ST) == 0,
                    "... but saturates: the best member's perturbation (0)");
    bank->sta_saturation[0] = 0.0;
    failed += check(ar_perturbation_choice(bank, 0, ST) == ST,
                    "not saturating: the super-twisting perturbation");
    bank->sta[0].mean_square = 10.0;

    /* the velocity: candidate among the centre, the member below and the zooms */
    bank->center[0] = 2;
    failed += check(ar_velocity_candidate(bank, 0) == 1,
                    "the member below the centre has the smaller innovation (1 < 2)");
    bank->zoom_index[0][0] = 4;
    bank->zoom[0][0].stats.mean_square = 0.5;
    failed += check(ar_velocity_candidate(bank, 0) == bank->count + 0,
                    "a zoom member with a smaller innovation (0.5) is the candidate");
    bank->sta[0].ranking[V] = 1.0;
    bank->zoom[0][0].stats.ranking[V] = 0.95;
    failed += check(ar_velocity_choice(bank, 0, ST, bank->count) == ST,
                    "the candidate's secant ranking 0.95 does not beat 1.0 by the hysteresis");
    bank->zoom[0][0].stats.ranking[V] = 0.5;
    failed += check(ar_velocity_choice(bank, 0, ST, bank->count) == bank->count,
                    "0.5 does: the zoom member publishes");
    failed += check(ar_velocity_choice(bank, 0, bank->count, bank->count) == bank->count,
                    "and stays until the super-twisting observer beats it by the hysteresis");

    /* the stand-in while the super-twisting injection saturates */
    failed += check(ar_stand_in(bank, 0, ST, 1) == ST, "members not started: no stand-in");
    bank->started[0] = 1;
    failed += check(ar_stand_in(bank, 0, ST, 1) == 1, "saturated: the quietest member");
    failed += check(ar_stand_in(bank, 0, ST, 0) == ST, "not saturated: the selection");
    failed += check(ar_stand_in(bank, 0, 2, 1) == 2, "a member selected: itself");

    /* the centre of the zoom members */
    bank->center[0] = -1;
    bank->sta[0].velocity_samples = 0.0;
    m[0].stats.ranking[V] = 3.0, m[1].stats.ranking[V] = 1.0, m[2].stats.ranking[V] = 2.0;
    failed += check(ar_new_centre(bank, 0) == -1, "no secant compared yet: no centre");
    bank->sta[0].velocity_samples = 1.0;
    failed += check(ar_new_centre(bank, 0) == 1, "the first centre: the best ranked, 1");
    bank->center[0] = 2;
    m[1].stats.ranking[V] = 1.9;
    failed += check(ar_new_centre(bank, 0) == -1,
                    "1.9 does not beat the centre's 2.0 by the hysteresis: kept");
    m[1].stats.ranking[V] = 1.0;
    failed += check(ar_new_centre(bank, 0) == 1, "1.0 does: the centre moves to 1");

    /* the reach: seven members, centre 3; member 0 ranks best but is paused (at
     * ADAPTIVE_REACH_SLOWER < 3) */
    bank->count = 7;
    bank->follow = ST;
    bank->center[0] = 3;
    bank->sta[0].mean_square = 10.0;
    bank->sta[0].ranking[P] = bank->sta[0].ranking[V] = 10.0;
    for (int j = 0; j < 7; ++j)
        m[j].stats.mean_square = m[j].stats.ranking[P] = m[j].stats.ranking[V] = 5.0 + j;
    m[0].stats.mean_square = m[0].stats.ranking[P] = m[0].stats.ranking[V] = 0.1;
    m[3].stats.mean_square = m[3].stats.ranking[P] = m[3].stats.ranking[V] = 1.0;
    bank->perturbation[0] = ST;
    bank->velocity_gain = 0.5 * ADAPTIVE_SETTLED;
    bank->sta[0].velocity_samples = 1.0; /* half the comparisons to settle: all run */
    int running = (int)ar_running_mask(bank, 0);
    failed += check(running == 0x7f, "not settled: every member runs (mask %#x)", running);
    bank->sta[0].velocity_samples = 2.0;
    running = (int)ar_running_mask(bank, 0);
    failed += check(running == (int)ar_member_range(3 - ADAPTIVE_REACH_SLOWER,
                                                          3 + ADAPTIVE_REACH_FASTER, 7),
                    "settled: the centre's reach (mask %#x)", running);
    failed += check(ar_member_range(2, 4, 7) == 0x1c && ar_member_range(-3, 0, 7) == 1 &&
                        ar_member_range(5, 9, 7) == 0x60 && ar_member_range(4, 3, 7) == 0,
                    "member ranges clipped to the bank");
    bank->perturbation[0] = 6;
    running = (int)ar_running_mask(bank, 0);
    failed += check((running >> 6 & 1) && (running >> (6 - ADAPTIVE_REACH_SLOWER) & 1),
                    "and the reach of the published perturbation's member");
    bank->perturbation[0] = ST;
    bank->follow = 0;
    failed += check(ar_running_mask(bank, 0) & 1u, "the member the identifier follows runs");
    bank->follow = ST;
    failed += check(ar_quietest_member(bank, 0) == 3, "the paused member 0 is not the quietest");
    failed += check(ar_new_centre(bank, 0) == -1, "nor the centre (3 ranks best of the rest)");
    failed += check(ar_choose(bank, 0, 0, P, &best) == 3,
                    "a paused current member gives way to the best running one");

    /* a tuning that runs every member: the reach covers the bank */
    bank->tuning.reach_slower = bank->tuning.reach_faster = ADAPTIVE_MAX_MEMBERS;
    running = (int)ar_running_mask(bank, 0);
    failed += check(running == 0x7f, "a reach of the whole bank runs every member (%#x)", running);
    bank->tuning = tuning_default().bank;

    bank->count = 0;
    const AdaptiveSelection none = ar_select(bank, 0, 1, 1);
    failed += check(none.selected == ST && none.source == ST, "no member fits: super-twisting");
    free(bank);
    return failed;
}

/* The bank's tuning: tuning.h's table by default, another one honoured, a bad one
 * named and refused (the defaults taken). */
static int adaptive_tuning(void)
{
    AdaptiveBank *bank = calloc(1, sizeof *bank);
    if (!bank) return 1;
    const AdaptiveTuning defaults = tuning_default().bank;
    int failed = check(tuning_adaptive_problem(&defaults) == NULL, "the defaults have no problem");
    int ok = na_init(bank, 1e-3, NULL);
    failed += check(ok && bank->count == 10, "1 kHz: ten members 2 rad/s to 0.5/h, 1.8 apart (%d)",
                    bank->count);
    failed += check(bank->tuning.hysteresis == ADAPTIVE_HYSTERESIS, "with tuning.h's values");
    na_init(bank, 1e-4, NULL);
    failed += check(bank->count == 14, "10 kHz: 14 members (%d)", bank->count);

    AdaptiveTuning coarse = defaults;
    coarse.ratio = ADAPTIVE_RATIO * ADAPTIVE_RATIO;
    ok = na_init(bank, 1e-4, &coarse);
    failed += check(ok && bank->count == 7 && bank->tuning.ratio == coarse.ratio,
                    "a ratio of 1.8^2 is honoured: 7 members (%d)", bank->count);
    failed += check(fabs(bank->gains[1].omega - 2.0 * coarse.ratio) < 1e-12,
                    "the second member at 2 * 3.24 rad/s (%g)", bank->gains[1].omega);

    AdaptiveTuning bad = defaults;
    bad.reach_slower = 0;
    const char *problem = tuning_adaptive_problem(&bad);
    failed += check(problem && strstr(problem, "reach_slower"), "reach_slower 0: %s",
                    problem ? problem : "(none)");
    ok = na_init(bank, 1e-4, &bad);
    failed += check(!ok && bank->tuning.reach_slower == ADAPTIVE_REACH_SLOWER,
                    "refused: the defaults taken");
    bad = defaults;
    bad.ratio = 1.0;
    problem = tuning_adaptive_problem(&bad);
    failed += check(problem && strstr(problem, "ratio"), "ratio 1: %s", problem ? problem : "(none)");
    bad = defaults;
    bad.hysteresis = NAN;
    problem = tuning_adaptive_problem(&bad);
    failed += check(problem && strstr(problem, "hysteresis"), "hysteresis NaN: %s",
                    problem ? problem : "(none)");
    free(bank);
    return failed;
}

int main(int argc, char **argv)
{
    static const TestCase cases[] = {
        {"adaptive_rules", adaptive_rules},
        {"adaptive_tuning", adaptive_tuning},
    };
    return run_cases("test_noise_adaptive", cases, sizeof cases / sizeof cases[0], argc, argv);
}
