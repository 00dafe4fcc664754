/* Derivatives of measured positions at a fixed lag behind the newest sample,
 * zero-phase within a symmetric window, for the identifier's regression.
 *
 * Why: parameters are constant or slow, so their estimate may lag by a window,
 * while a causal derivative's own lag biases every regressor on a coarse or fast
 * log (a resonance near fs/9 is not tracked by any causal observer at that rate).
 * The window smooths the samples with a low-pass kernel K (a Blackman-windowed
 * sinc of cut-off f_c, half-length FL_CYCLES / f_c samples, sampled: k0) and
 * differentiates the smoothed signal with kernels of the same length whose
 * responses are i w and -w^2 times k0's over its band (fixed_lag_kernels.h,
 * exact on constants, ramps and parabolas), and the inputs pass the same k0, so
 * that a linear equation holds between the smoothed signals as it does between
 * the measured ones.  A nonlinear term of the samples (fl_add_term) passes as an
 * input does.  An input held over each sample
 * (a zero-order hold) is the staircase it draws: sample u_i acts from t_i to
 * t_i + h, so its weight is K at the middle of that interval.
 *
 * The cut-off is chosen from the measurement noise: candidates FL_CANDIDATES
 * from FL_HIGHEST_FRACTION of the sample rate, each half the one before.  From
 * the start, every candidate's acceleration mean square is accumulated, and the
 * noise's, measured as what a kernel of cut-off FL_PROBE_FRACTION leaves of the
 * positions (mechanical motion rarely reaches that band; the bank's estimate
 * would include its members' tracking error where the nominal model misses
 * the dynamics, a resonance).  fl_choose takes the widest band in which that
 * noise, white, is at most FL_NOISE_SHARE of the acceleration's mean square
 * (the errors-in-variables bias of an acceleration's coefficient is about that
 * share), else the narrowest.
 * The velocities may also be wanted ahead of the centre (fl_lead): a sign(q') in the
 * equations holds only away from q''s reversals, and whether one lies within
 * FL_REVERSAL_PERIODS of the cut-off on either side of the centre is known once the
 * window's velocity has passed that far beyond it.
 * Plain C, no allocation, no FMI types. */
#ifndef FIXED_LAG_H
#define FIXED_LAG_H

#include <math.h>

#include "tuning.h"

#ifndef FL_MAX_SIGNALS /* positions then inputs: a model's 7 and 7, a robot's joints and torques */
#define FL_MAX_SIGNALS 14 /* (the native library's offline robots have more: cmake/native.cmake) */
#endif
#define FL_MAX_TERMS 16   /* functions of the samples, smoothed after them (fl_add_term) */
#define FL_MAX_HALF 240 /* ceil(FL_CYCLES / FL_HIGHEST_FRACTION) 2^(FL_CANDIDATES - 1) */
#define FL_MAX_LEAD 60 /* ceil(FL_REVERSAL_PERIODS / FL_HIGHEST_FRACTION) 2^(FL_CANDIDATES - 1) */
/* a held input's window reaches one sample further, a lead FL_MAX_LEAD further still */
#define FL_RING (2 * FL_MAX_HALF + 2 + FL_MAX_LEAD)
#define FL_PROBE_HALF 15 /* ceil(FL_CYCLES / FL_PROBE_FRACTION) */

typedef struct {
    int coordinates, signals; /* positions, then inputs up to signals */
    int inputs_held;          /* the inputs act until the next sample */
    int terms;                /* functions of the samples, after the signals in the ring */
    int term_held[FL_MAX_TERMS]; /* a function of held inputs only: a staircase too */
    int term_tag[FL_MAX_TERMS];  /* the caller's name for each */
    double h;
    int half[FL_CANDIDATES];  /* samples on each side of the centre */
    int leads;                /* fl_lead: the centre lies lead[] samples further back */
    int lead[FL_CANDIDATES];  /* FL_REVERSAL_PERIODS of each candidate's cut-off */
    /* coefficient of the sample j steps after the centre, j = 0 .. half (k1 is odd:
     * -k1[j] before the centre; k0 and k2 even), in units of h^-derivative */
    double k0[FL_CANDIDATES][FL_MAX_HALF + 1], k1[FL_CANDIDATES][FL_MAX_HALF + 1],
        k2[FL_CANDIDATES][FL_MAX_HALF + 1];
    double held[FL_CANDIDATES][FL_MAX_HALF + 1]; /* a held input's kernel: the samples m
                                                  * after and m + 1 before the centre */
    double noise_gain[FL_CANDIDATES]; /* acceleration variance per unit noise variance */
    double probe[FL_PROBE_HALF + 1];  /* the noise probe's kernel (k0's form) ... */
    double probe_gain;                /* ... its residual's variance per unit noise variance */
    /* each signal's last FL_RING samples, written twice (at j and j + FL_RING) so that
     * every window is contiguous: the newest at ring[s][newest + FL_RING] */
    double ring[FL_MAX_SIGNALS + FL_MAX_TERMS][2 * FL_RING];
    int newest, filled;       /* ring index of the newest sample; samples held */
    double square[FL_CANDIDATES][FL_MAX_SIGNALS]; /* sums of each candidate's squared */
    double squares[FL_CANDIDATES];                /* accelerations, and their count */
    double noise_square[FL_MAX_SIGNALS];          /* sums of the probe's squared residuals */
    double noise_squares;                         /* and their count */
    int chosen;               /* the candidate in use; -1 before fl_choose */
} FixedLag;

/* The coefficients of the candidates at step h [s], the inputs held over each
 * sample or not. Returns 0, or -1 for more signals than FL_MAX_SIGNALS or a step
 * that is not positive and finite. */
int fl_init(FixedLag *f, int coordinates, int inputs, int inputs_held, double h);

/* Adds a term: a function of one sample's positions and inputs (no derivatives), whose
 * values fl_push takes beside the samples and fl_at_lag smooths by K as an input is
 * (by the held input's kernel where held is set: a function of held inputs only), so
 * that a nonlinear term of the equations passes the window as the equations' own
 * samples do, where the same function of the smoothed samples would not.  Before
 * the first fl_push.  Returns the term's index, or -1 when FL_MAX_TERMS are taken. */
int fl_add_term(FixedLag *f, int held, int tag);

/* Moves the centre lead[] samples further back, so that fl_lead_velocity sees that far
 * beyond it.  Before the first fl_push. */
void fl_lead(FixedLag *f);

/* Takes a sample (the positions y, the inputs u, the terms' values at them; terms
 * may be NULL without terms) and, until the choice, accumulates the mean square of
 * every candidate's acceleration whose window is full and the noise probe's. */
void fl_push(FixedLag *f, const double y[], const double u[], const double terms[]);

/* Chooses the cut-off from the statistics so far. Returns the candidate. */
int fl_choose(FixedLag *f);

/* Coordinate i's measurement noise standard deviation, as the probe measures it. */
double fl_noise_std(const FixedLag *f, int i);

/* The chosen candidate's window is full: fl_at_lag has a sample. */
int fl_ready(const FixedLag *f);

/* The smoothed positions, velocities, accelerations, inputs and terms (NULL without
 * terms) at the chosen candidate's centre, half[chosen] samples behind the newest
 * (and lead[chosen] more after fl_lead). */
void fl_at_lag(const FixedLag *f, double q[], double qd[], double qdd[], double u[],
               double terms[]);

/* Coordinate i's smoothed velocity half[chosen] samples behind the newest: after
 * fl_lead, lead[chosen] samples after the centre (before it, the centre's). */
double fl_lead_velocity(const FixedLag *f, int i);

/* The centre's lead in samples (0 without fl_lead or before fl_choose). */
int fl_lead_samples(const FixedLag *f);

/* The rule of the rows left out near an event, on a velocity v taken at the lead: a
 * reversal of v since *previous (which takes v), or `event` (the caller's: a start, a
 * slow sample) restarts *since, which counts up to span + 1.  Returns 1 when no event
 * lies within span samples, that is (span = 2 lead) within the lead on either side of
 * the centre. */
static inline int fl_settled(int *since, double *previous, double v, int event, int span)
{
    const int reversed = signbit(v) != signbit(*previous);
    *previous = v;
    if (event || reversed) *since = 0;
    else if (*since <= span) ++*since;
    return *since > span;
}

/* The chosen candidate's cut-off [Hz] (0 before fl_choose). */
double fl_cutoff(const FixedLag *f);

#endif
