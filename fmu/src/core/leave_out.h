/* MFF's rule that leaves uninformative samples out, shared by the information-form
 * identifier (information_identifier.h) and the robot's regressor identifier
 * (regressor_identifier.h), which differ only in how they measure a sample.
 *
 * A sample whose information q (its inflow measured against the long-run inflow
 * Pref, the information with the longer memory reference_memory / |ln R|) is below
 * skip_share of its share p (1 - lambda_ref) of Pref does not add to the sums.  A
 * gap of such samples up to gap_memory memories long (a velocity zero) forgets as
 * before; a longer one (a rest) freezes the sums.  Without that, a motion that stops
 * or decays to a crawl, where quantization, static friction and discretization
 * dominate the data, is fitted with a Gamma that has grown to its bound 1/rho:
 * measured on the 6.3 pendulum after 50 s of excitation (bench/no_excitation.py), the
 * estimate moved 160-600 % in the 3 s ring-down with a 12-bit encoder, and up to
 * 850 % over 60 s at rest on explicit-Euler plant data, whose velocity keeps
 * alternating.  Over left-out samples Pref forgets with the 10x longer memory
 * rest_memory / |ln R|, so that an isolated pulse after a long rest (an encoder step
 * of a creeping plant) stays small against it, while a lasting smaller excitation is
 * taken up again.  At steady excitation only the samples around velocity zeros are
 * left out, which carry little information on any parameter whose regressor
 * vanishes with the velocity.  Plain C, no FMI types. */
#ifndef LEAVE_OUT_H
#define LEAVE_OUT_H

#include <math.h>

#include "tuning.h"

typedef struct {
    double reference_lambda, reference_pull; /* lambda^(1/reference_memory), its rho pull */
    double rest_lambda, rest_pull;           /* the same over left-out samples (rest_memory) */
    double skip_threshold; /* skip_share p (1 - reference_lambda), in q's units */
    double gap_limit;      /* gap_memory / |ln R| [s] */
    double gap_time;       /* since the last sample used [s] */
} LeaveOut;

/* The rule for a forgetting factor lambda = R^h per step, with Pref's pull toward
 * rho I; q_scale is p for a q that includes the step h, p / h for one that does not. */
static inline void leave_out_init(LeaveOut *rule, const LeaveOutTuning *tuning, double lambda,
                                  double rho, double R, double q_scale)
{
    rule->reference_lambda = pow(lambda, 1.0 / tuning->reference_memory);
    rule->reference_pull = (1.0 - rule->reference_lambda) * rho;
    rule->rest_lambda = pow(lambda, 1.0 / tuning->rest_memory);
    rule->rest_pull = (1.0 - rule->rest_lambda) * rho;
    rule->skip_threshold = tuning->skip_share * q_scale * (1.0 - rule->reference_lambda);
    rule->gap_limit = R > 0.0 && R < 1.0 ? tuning->gap_memory / -log(R) : 0.0; /* (MFF only) */
    rule->gap_time = 0.0;
}

/* Which forgetting Pref takes for the sample of information q, and whether the
 * sample is used (1), left out within a short gap, which forgets (0), or left out
 * in a rest, which freezes the sums (-1). */
static inline int leave_out_decide(LeaveOut *rule, double q, double h, double *lambda,
                                   double *pull)
{
    const int used = q >= rule->skip_threshold;
    *lambda = used ? rule->reference_lambda : rule->rest_lambda;
    *pull = used ? rule->reference_pull : rule->rest_pull;
    if (used) {
        rule->gap_time = 0.0;
        return 1;
    }
    rule->gap_time += h;
    return rule->gap_time >= rule->gap_limit ? -1 : 0;
}

#endif
