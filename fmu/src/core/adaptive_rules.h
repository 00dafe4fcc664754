/* The noise-adaptive bank's selection rules (noise_adaptive.h describes the bank),
 * one function per rule over the bank's statistics, so that each is read and
 * tested alone (tests/fmu/core/test_noise_adaptive.c, case adaptive_rules).  Header-only;
 * noise_adaptive.c applies them after every step. */
#ifndef ADAPTIVE_RULES_H
#define ADAPTIVE_RULES_H

#include <math.h>

#include "noise_adaptive.h"

/* The selection after a step: whose velocity is published and whose injection is
 * the published perturbation (member indices, or ADAPTIVE_SUPER_TWISTING). */
typedef struct {
    int selected, source;
} AdaptiveSelection;

/* A member by its index: the members, then the zoom members. */
static inline const AdaptiveMember *ar_member_at(const AdaptiveBank *bank, int i, int index)
{
    return index < bank->count ? &bank->member[i][index] : &bank->zoom[i][index - bank->count];
}

static inline const AdaptiveGains *ar_gains_at(const AdaptiveBank *bank, int i, int index)
{
    return index < bank->count ? &bank->gains[index]
                               : &bank->fine[bank->zoom_index[i][index - bank->count]];
}

/* Bits low..high of a mask of `count` members (none if the range is empty). */
static inline unsigned ar_member_range(int low, int high, int count)
{
    low = low < 0 ? 0 : low;
    high = high > count - 1 ? count - 1 : high;
    return low > high ? 0u : (~0u >> (31 - (high - low))) << low;
}

/* Reach: the members that run on DOF i, as bits (bit j: member j).  Every member
 * runs until the velocities have been compared for ADAPTIVE_SETTLED windows and
 * there is a centre; then the members from ADAPTIVE_REACH_SLOWER below to
 * ADAPTIVE_REACH_FASTER above the centre and the published perturbation's member,
 * and the one the identifier follows.  The others pause (their state is stale)
 * and, when they run again, continue from the nearest running member
 * (noise_adaptive.c, wake): the rankings then climb the grid. */
static inline unsigned ar_running_mask(const AdaptiveBank *bank, int i)
{
    const int count = bank->count, c = bank->center[i], s = bank->perturbation[i];
    const int slower = bank->tuning.reach_slower, faster = bank->tuning.reach_faster;
    if (c < 0 || bank->sta[i].velocity_samples * bank->velocity_gain < bank->tuning.settled)
        return ar_member_range(0, count - 1, count);
    unsigned mask = ar_member_range(c - slower, c + faster, count);
    if (s != ADAPTIVE_SUPER_TWISTING) mask |= ar_member_range(s - slower, s + faster, count);
    if (bank->follow != ADAPTIVE_SUPER_TWISTING)
        mask |= ar_member_range(bank->follow, bank->follow, count);
    return mask;
}

/* The running member of the smallest one-step innovation mean square (count > 0). */
static inline int ar_quietest_member(const AdaptiveBank *bank, int i)
{
    const AdaptiveMember *members = bank->member[i];
    const unsigned running = ar_running_mask(bank, i);
    int best = -1;
    for (int j = 0; j < bank->count; ++j)
        if ((running >> j & 1u) &&
            (best < 0 || members[j].stats.mean_square < members[best].stats.mean_square))
            best = j;
    return best;
}

/* Ranking: the observer of the smallest mean square of a ranking among the
 * super-twisting observer and the running members, or the current one unless the
 * best is smaller by ADAPTIVE_HYSTERESIS (a paused current one always gives way).
 * *best gets the best member. */
static inline int ar_choose(const AdaptiveBank *bank, int i, int current, int rank, int *best)
{
    const AdaptiveMember *members = bank->member[i];
    const unsigned running = ar_running_mask(bank, i);
    *best = -1;
    for (int j = 0; j < bank->count; ++j)
        if ((running >> j & 1u) &&
            (*best < 0 || members[j].stats.ranking[rank] < members[*best].stats.ranking[rank]))
            *best = j;
    if (*best < 0) return current; /* no member runs (none fits the step) */
    const double sta = bank->sta[i].ranking[rank], member = members[*best].stats.ranking[rank];
    const double now = current == ADAPTIVE_SUPER_TWISTING ? sta
                       : (running >> current & 1u) ? members[current].stats.ranking[rank]
                                                   : INFINITY;
    const int candidate = member < sta ? *best : ADAPTIVE_SUPER_TWISTING;
    return (member < sta ? member : sta) < bank->tuning.hysteresis * now ? candidate : current;
}

/* Saturation: the super-twisting injection saturates in at least
 * ADAPTIVE_SATURATION_LIMIT of the steps (the perturbation outruns alpha1). */
static inline int ar_saturating(const AdaptiveBank *bank, int i)
{
    return bank->sta_saturation[i] >= bank->tuning.saturation_limit;
}

/* Exact data: unless it saturates, the deadbeat super-twisting corrector that
 * predicts the next sample far better than any linear member is kept. */
static inline int ar_exact_data(const AdaptiveBank *bank, int i)
{
    if (ar_saturating(bank, i)) return 0;
    const double smallest = bank->member[i][ar_quietest_member(bank, i)].stats.mean_square;
    return bank->sta[i].mean_square < bank->tuning.exact_ratio * smallest;
}

/* Velocity candidate: the member of the smallest one-step innovation mean square
 * among the centre, the member below it and the zoom members (the
 * maximum-likelihood bandwidth for an unknown noise level). */
static inline int ar_velocity_candidate(const AdaptiveBank *bank, int i)
{
    const AdaptiveMember *members = bank->member[i];
    int member = bank->center[i];
    if (member > 0 && members[member - 1].stats.mean_square < members[member].stats.mean_square)
        member = member - 1;
    for (int s = 0; s < ADAPTIVE_ZOOM; ++s)
        if (bank->zoom_index[i][s] >= 0 &&
            bank->zoom[i][s].stats.mean_square <
                ar_member_at(bank, i, member)->stats.mean_square)
            member = bank->count + s;
    return member;
}

/* Velocity: the candidate against the super-twisting observer by the secant
 * ranking, with hysteresis either way. */
static inline int ar_velocity_choice(const AdaptiveBank *bank, int i, int selected,
                                           int candidate)
{
    const double c = ar_member_at(bank, i, candidate)->stats.ranking[ADAPTIVE_RANK_VELOCITY];
    const double st = bank->sta[i].ranking[ADAPTIVE_RANK_VELOCITY];
    if (selected == ADAPTIVE_SUPER_TWISTING)
        return c < bank->tuning.hysteresis * st ? candidate : selected;
    return st < bank->tuning.hysteresis * c ? ADAPTIVE_SUPER_TWISTING : candidate;
}

/* Perturbation: the perturbation ranking; a super-twisting observer whose
 * injection saturates often gives way to the best member's perturbation. */
static inline int ar_perturbation_choice(const AdaptiveBank *bank, int i, int source)
{
    int best;
    const int chosen = ar_choose(bank, i, source, ADAPTIVE_RANK_PERTURBATION, &best);
    return chosen == ADAPTIVE_SUPER_TWISTING && ar_saturating(bank, i) ? best : chosen;
}

/* The rules together, after a step of DOF i. */
static inline AdaptiveSelection ar_select(const AdaptiveBank *bank, int i, int selected,
                                                int source)
{
    const AdaptiveSelection super_twisting = {ADAPTIVE_SUPER_TWISTING, ADAPTIVE_SUPER_TWISTING};
    if (bank->count == 0) return super_twisting; /* h > 0.25 s: no member fits */
    if (ar_exact_data(bank, i)) return super_twisting;
    AdaptiveSelection choice = {selected, source};
    if (bank->sta[i].velocity_samples > 0.0 && bank->center[i] >= 0)
        choice.selected =
            ar_velocity_choice(bank, i, selected, ar_velocity_candidate(bank, i));
    if (bank->sta[i].perturbation_samples > 0.0)
        choice.source = ar_perturbation_choice(bank, i, source);
    return choice;
}

/* Stand-in: whose velocity is published at a sample is the selected observer's,
 * but for the super-twisting observer while its injection saturates: then the
 * perturbation outruns alpha1 and its velocity error grows by the excess times
 * h every step; a linear member has no bound to outrun, so the member of the
 * smallest one-step mean square stands in. */
static inline int ar_stand_in(const AdaptiveBank *bank, int i, int selected, int saturated)
{
    if (selected != ADAPTIVE_SUPER_TWISTING || !saturated || !bank->started[i] || bank->count == 0)
        return selected;
    return ar_quietest_member(bank, i);
}

/* Centre: the running member whose velocity matches the corrected secants best becomes
 * the centre of the zoom members when it beats the current centre by
 * ADAPTIVE_HYSTERESIS (or there is none yet); returns it, or -1 to keep the centre. */
static inline int ar_new_centre(const AdaptiveBank *bank, int i)
{
    const AdaptiveMember *members = bank->member[i];
    const unsigned running = ar_running_mask(bank, i);
    const int c = bank->center[i] < 0 ? 0 : bank->center[i];
    int best = c;
    for (int j = 0; j < bank->count; ++j)
        if ((running >> j & 1u) && members[j].stats.ranking[ADAPTIVE_RANK_VELOCITY] <
                                       members[best].stats.ranking[ADAPTIVE_RANK_VELOCITY])
            best = j;
    const int due = bank->sta[i].velocity_samples > 0.0 &&
                    (bank->center[i] < 0 || members[best].stats.ranking[ADAPTIVE_RANK_VELOCITY] <
                                                bank->tuning.hysteresis *
                                                    members[c].stats.ranking[ADAPTIVE_RANK_VELOCITY]);
    return due ? best : -1;
}

#endif
