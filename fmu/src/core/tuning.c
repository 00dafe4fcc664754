#include "tuning.h"

#include <math.h>
#include <stddef.h>

StoTuning tuning_default(void)
{
    const StoTuning tuning = {
        .bank = {.lowest_bandwidth = ADAPTIVE_LOWEST_BANDWIDTH,
                 .highest_bandwidth = ADAPTIVE_HIGHEST_BANDWIDTH,
                 .ratio = ADAPTIVE_RATIO,
                 .window = ADAPTIVE_WINDOW,
                 .secant_time = ADAPTIVE_SECANT_TIME,
                 .start_time = ADAPTIVE_START_TIME,
                 .hysteresis = ADAPTIVE_HYSTERESIS,
                 .exact_ratio = ADAPTIVE_EXACT_RATIO,
                 .saturation_limit = ADAPTIVE_SATURATION_LIMIT,
                 .averaging = ADAPTIVE_AVERAGING,
                 .settled = ADAPTIVE_SETTLED,
                 .min_samples = ADAPTIVE_MIN_SAMPLES,
                 .reach_slower = ADAPTIVE_REACH_SLOWER,
                 .reach_faster = ADAPTIVE_REACH_FASTER},
        .implicit = {.learning_gain = IMPLICIT_LEARNING_GAIN},
        .identifier = {.anchor_forgetting = INFO_ANCHOR_FORGETTING,
                       .batch_window = INFO_BATCH_WINDOW,
                       .lsm_score_window = INFO_LSM_SCORE_WINDOW,
                       .power_window = INFO_POWER_WINDOW,
                       .score_delay = INFO_SCORE_DELAY},
        .leave_out = {.reference_memory = INFO_REFERENCE_MEMORY,
                      .rest_memory = INFO_REST_MEMORY,
                      .skip_share = INFO_SKIP_SHARE,
                      .gap_memory = INFO_GAP_MEMORY},
        .feedback = {.start = FEEDBACK_START, .ramp = FEEDBACK_RAMP, .sigmas = FEEDBACK_SIGMAS}};
    return tuning;
}

const char *tuning_adaptive_problem(const AdaptiveTuning *t)
{
    if (!(t->lowest_bandwidth > 0.0 && isfinite(t->lowest_bandwidth)))
        return "lowest_bandwidth must be positive and finite";
    if (!(t->highest_bandwidth > 0.0 && isfinite(t->highest_bandwidth)))
        return "highest_bandwidth must be positive and finite";
    if (!(t->ratio > 1.0 && isfinite(t->ratio))) return "ratio must exceed 1";
    if (!(t->window > 0.0 && isfinite(t->window))) return "window must be positive and finite";
    if (!(t->secant_time > 0.0 && isfinite(t->secant_time)))
        return "secant_time must be positive and finite";
    if (!(t->start_time > 0.0 && isfinite(t->start_time)))
        return "start_time must be positive and finite";
    if (!(t->hysteresis > 0.0 && t->hysteresis <= 1.0)) return "hysteresis must be in (0, 1]";
    if (!(t->exact_ratio >= 0.0 && isfinite(t->exact_ratio))) return "exact_ratio must be >= 0";
    if (!(t->saturation_limit >= 0.0 && t->saturation_limit <= 1.0))
        return "saturation_limit must be in [0, 1]";
    if (!(t->averaging > 0.0 && isfinite(t->averaging))) return "averaging must be positive";
    if (!(t->settled >= 0.0 && isfinite(t->settled))) return "settled must be >= 0";
    if (!(t->min_samples >= 0.0 && t->min_samples <= 1e9)) return "min_samples must be in [0, 1e9]";
    if (t->reach_slower < 1) return "reach_slower must be >= 1 (the candidate takes the member "
                                    "below the centre)";
    if (t->reach_faster < 0) return "reach_faster must be >= 0";
    return NULL;
}

static int positive(double x) { return x > 0.0 && isfinite(x); }
static int non_negative(double x) { return x >= 0.0 && isfinite(x); }

const char *tuning_problem(const StoTuning *t)
{
    const char *bank = tuning_adaptive_problem(&t->bank);
    if (bank) return bank;
    if (!(t->implicit.learning_gain > 0.0 && t->implicit.learning_gain <= 1.0))
        return "implicit.learning_gain must be in (0, 1]";
    if (!positive(t->identifier.anchor_forgetting))
        return "identifier.anchor_forgetting must be positive";
    if (!positive(t->identifier.batch_window)) return "identifier.batch_window must be positive";
    if (!positive(t->identifier.lsm_score_window))
        return "identifier.lsm_score_window must be positive";
    if (!positive(t->identifier.power_window)) return "identifier.power_window must be positive";
    if (!non_negative(t->identifier.score_delay)) return "identifier.score_delay must be >= 0";
    if (!positive(t->leave_out.reference_memory))
        return "leave_out.reference_memory must be positive";
    if (!positive(t->leave_out.rest_memory)) return "leave_out.rest_memory must be positive";
    if (!non_negative(t->leave_out.skip_share)) return "leave_out.skip_share must be >= 0";
    if (!non_negative(t->leave_out.gap_memory)) return "leave_out.gap_memory must be >= 0";
    if (!non_negative(t->feedback.start)) return "feedback.start must be >= 0";
    if (!positive(t->feedback.ramp)) return "feedback.ramp must be positive";
    if (!non_negative(t->feedback.sigmas)) return "feedback.sigmas must be >= 0";
    return NULL;
}
