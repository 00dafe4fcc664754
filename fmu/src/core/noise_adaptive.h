/* The noise-adaptive scheme (scheme 3, the default): the implicit
 * super-twisting observer of implicit_twisting.c runs beside a bank of
 * linear observers of the same sampled model, and each DOF publishes the one
 * that predicts its measurements best.  The reasoning and the measurements
 * behind it are in docs/design/observer.md.
 *
 * Why: on exact samples the implicit super-twisting corrector is deadbeat
 * (x1_hat lands on y, the injection is the exact second-difference residual),
 * which no linear filter beats.  On real measurements (noise, encoder
 * quantization, a plant integrated differently from the observer's model)
 * its injection saturates to +-alpha1, noise of variance alpha1^2; a linear
 * correction with Kalman gains for the noise level is the minimum-variance
 * answer there, and with the nominal model inside it beats model-free
 * differentiators, which must track the whole acceleration.
 *
 * Members: each uses the implicit scheme's leapfrog prediction with the
 * injection xi held, x1^- = x1 + h m + h^2 (a_mean + xi), and corrects with
 * the steady-state Kalman gain K of the model [x1, m, xi] (xi a random walk)
 * for one ratio of process to measurement noise, r = y - x1^-:
 *     m  <- m + h (a_mean + xi) + K2 r,   xi <- xi + K3 r,   x1 <- y - (1 - K1) r.
 * The super-twisting corrector in sliding is the member K = (1, 1/h, 1/h^2).
 * The ratios are set by a bandwidth omega (q = omega^6 h^2 per step against
 * R = 1), from ADAPTIVE_LOWEST_BANDWIDTH up to ADAPTIVE_HIGHEST_BANDWIDTH / h,
 * a factor ADAPTIVE_RATIO apart; ADAPTIVE_ZOOM zoom members run on a grid
 * ADAPTIVE_FINE times finer below the centre member.
 *
 * Reach: every member runs until the rankings have settled (ADAPTIVE_SETTLED
 * windows of comparisons); then only the members from ADAPTIVE_REACH_SLOWER below
 * to ADAPTIVE_REACH_FASTER above the centre and the published perturbation's
 * member, and the identifier's, run (ar_running_mask); the rankings move
 * the two choices along the grid, each newly running member starting from its
 * nearest running neighbour.  The members far from both choices only cost: with
 * them the step was twice as expensive for the same results (docs/design).
 *
 * Rankings (all exponentially weighted over ADAPTIVE_WINDOW):
 * - innovation: each observer's one-step innovation mean square, which for
 *   an unknown noise level picks the maximum-likelihood member;
 * - velocity: every stride (ADAPTIVE_SECANT_TIME / ADAPTIVE_SLOTS, at least one
 *   step) each observer's velocity against the secant of the measurements
 *   over the ADAPTIVE_SLOTS strides around it, corrected by the nominal
 *   model's curvature over the span (without it the secant misses the ripple
 *   a switching controller puts on the velocity);
 * - perturbation: each observer's published perturbation (a member's xi
 *   averaged over ADAPTIVE_AVERAGING / omega, the super-twisting injection
 *   through the tau filter) against the change between two corrected secants
 *   ADAPTIVE_PERTURBATION_SPANS spans apart minus the nominal model's change.
 *
 * The rules (adaptive_rules.h, one function each; the selection is made at each
 * stride's start, when the rankings change): the centre of the zoom members is the
 * running member of the best velocity ranking (ADAPTIVE_HYSTERESIS to move); the
 * velocity candidate is the smallest innovation among the centre, the member below
 * it and the zoom members, and the velocity ranking decides between it and the
 * super-twisting observer; the perturbation ranking picks the published
 * perturbation; exact data (the super-twisting innovation below
 * ADAPTIVE_EXACT_RATIO times every running member's while its injection saturates
 * in fewer than ADAPTIVE_SATURATION_LIMIT of the steps) keeps the super-twisting
 * observer; in each step where its injection saturates, the quietest member stands
 * in for its velocity.  The measurement noise estimate is the smallest ratio,
 * over the running members, of the innovation mean square to its steady-state
 * innovation variance per unit noise variance.
 *
 * The Coulomb regressor of a linear member is E[sign v | x2_hat] =
 * erf(x2_hat / (sqrt 2 sigma_v)), sigma_v its velocity error for the noise
 * estimate: sign(x2_hat) is wrong whenever |v| < sigma_v, which attenuates the
 * identified Coulomb coefficient (errors in variables).
 *
 * Identification with a linear member: xi is the perturbation through the
 * member's closed-loop filter G, so the regressor must pass the same G
 * (na_shadow_step) for xi = Delta (G phi) to hold; the identifier
 * follows one member, fixed when it starts: the one whose velocity is
 * published then, or the centre if that is a zoom member (the regressors take
 * the centre's velocity, see na_run). */
#ifndef NOISE_ADAPTIVE_H
#define NOISE_ADAPTIVE_H

#include "tuning.h"

#include "super_twisting.h"

#define ADAPTIVE_MAX_MEMBERS 16
#define ADAPTIVE_PERTURBATION_LAG (ADAPTIVE_SLOTS * ADAPTIVE_PERTURBATION_SPANS) /* strides */
#define ADAPTIVE_RING (ADAPTIVE_SLOTS + ADAPTIVE_PERTURBATION_LAG) /* strides of secants kept */
/* strides from a published perturbation to the measurement it is compared with */
#define ADAPTIVE_PERTURBATION_DELAY (ADAPTIVE_SLOTS / 2 + ADAPTIVE_PERTURBATION_LAG / 2)
#define ADAPTIVE_MAX_STRIDE 100000000
#define ADAPTIVE_SUPER_TWISTING (-1) /* member index of the super-twisting observer */
#define ADAPTIVE_ZOOM (ADAPTIVE_FINE - 1) /* zoom members below the centre */
#define ADAPTIVE_MAX_FINE ((ADAPTIVE_MAX_MEMBERS - 1) * ADAPTIVE_FINE + 1)

/* Gains of one linear member. */
typedef struct {
    double omega;     /* bandwidth [rad/s] */
    double k1, k2, k3;
    double innovation_variance; /* steady-state innovation variance per unit R */
    double velocity_std;        /* steady-state velocity error per unit noise std */
    double publish_gain;        /* of the filter that averages xi for z_eq_filtered */
} AdaptiveGains;

/* What the observers are ranked by (indices of AdaptiveStatistics.ranking). */
enum { ADAPTIVE_RANK_PERTURBATION, ADAPTIVE_RANK_VELOCITY, ADAPTIVE_RANKINGS };

/* Exponentially weighted statistics of an observer's predictions. */
typedef struct {
    double mean_square;       /* of the innovations r (one sample ahead) */
    double ranking[ADAPTIVE_RANKINGS]; /* mean squares: the published perturbations
                                        * against the measured one; the velocities
                                        * against the corrected secants */
    double samples, perturbation_samples, velocity_samples; /* counted up to 1 / gain:
                                                             * growing windows first */
    double perturbation[ADAPTIVE_PERTURBATION_DELAY + 1]; /* the published perturbations
                                                           * and ... */
    double velocity[ADAPTIVE_SLOTS];     /* ... velocities at the last strides */
} AdaptiveStatistics;

/* The measured secant velocity over the last ADAPTIVE_SLOTS strides of one
 * DOF, corrected by the nominal model's own curvature over them (see the header). */
typedef struct {
    double y[ADAPTIVE_SLOTS];           /* the measurement at each stride's start */
    double dv[ADAPTIVE_RING], dw[ADAPTIVE_SLOTS]; /* integrals of the nominal acceleration
                                                   * over each stride: once, twice */
    double v, w;                        /* the same over the running stride */
    double middle[ADAPTIVE_RING];       /* the corrected secants (velocities at the middles) */
    double nominal; /* the sum of dv between the middles of the secants compared for the
                     * perturbation (slid by a stride each stride, summed afresh every
                     * ADAPTIVE_RING strides) */
} AdaptiveSecant;

/* One member's state for one DOF. */
typedef struct {
    double z1, mid, xi, a_free, a_mean, x2_now; /* as in implicit_twisting.c */
    double averaged, published; /* xi after the first and the second averaging stage */
    AdaptiveStatistics stats;
} AdaptiveMember;

typedef struct {
    AdaptiveTuning tuning;
    int count;                         /* linear members */
    double gain;                       /* h / window */
    int stride;                        /* steps between the velocity comparisons */
    double span;                       /* [s] of a secant: ADAPTIVE_SLOTS strides */
    double velocity_gain;              /* the window's gain per comparison */
    unsigned start_limit;              /* start_time in steps */
    AdaptiveGains gains[ADAPTIVE_MAX_MEMBERS];
    AdaptiveGains fine[ADAPTIVE_MAX_FINE]; /* bandwidths ADAPTIVE_RATIO^(1/ADAPTIVE_FINE) apart:
                                            * fine[j ADAPTIVE_FINE] = gains[j] */
    AdaptiveMember member[STO_MAX_DOF][ADAPTIVE_MAX_MEMBERS];
    AdaptiveMember zoom[STO_MAX_DOF][ADAPTIVE_ZOOM]; /* member index count + s */
    int zoom_index[STO_MAX_DOF][ADAPTIVE_ZOOM];      /* their fine index (-1: idle) */
    int center[STO_MAX_DOF];             /* the member they surround (-1: none yet) */
    AdaptiveStatistics sta[STO_MAX_DOF]; /* the super-twisting observer's */
    double sta_saturation[STO_MAX_DOF];  /* its rate of saturated steps (window as sta) */
    AdaptiveSecant secant[STO_MAX_DOF];
    int started[STO_MAX_DOF];            /* the members run (the observer has converged) */
    unsigned waited[STO_MAX_DOF];        /* steps before they started */
    unsigned age[STO_MAX_DOF];           /* steps since they started */
    int selected[STO_MAX_DOF];           /* whose velocity is chosen (ar_select): a
                                          * member index or ADAPTIVE_SUPER_TWISTING */
    int published[STO_MAX_DOF];          /* whose velocity is published at the last sample:
                                          * `selected`, or while the super-twisting injection
                                          * saturates, the member of the smallest one-step
                                          * mean square (ar_stand_in) */
    int perturbation[STO_MAX_DOF];       /* whose injection is published (ar_select) */
    int follow;                          /* the member the identifier follows */
    double z_filtered[STO_MAX_DOF];      /* the published perturbation */
    double noise_std[STO_MAX_DOF];       /* estimated measurement noise [rad] */
    double bandwidth[STO_MAX_DOF];       /* omega of the published member (1/h: super-twisting) */
    double velocity[STO_MAX_DOF];        /* the published velocity at the last sample */
    double position[STO_MAX_DOF];        /* and the published observer's corrected position */
} AdaptiveBank;

/* Gains of the members for step h (steady-state Riccati, at initialization), with
 * the tuning (NULL: the defaults).  Returns 0, with the defaults taken, if the
 * tuning has a problem. */
int na_init(AdaptiveBank *bank, double h, const AdaptiveTuning *tuning);

/* The scheme's run: the super-twisting observer and the members over `count`
 * steps with y held; the trace gets the selected member's values. */
void na_run(SuperTwistingObserver *o, AdaptiveBank *bank, const double y[],
                  const StoAcceleration a[], int count, StoTrace *trace);

/* x1_hat, x2_hat, z_eq, z_filtered, noise_std and bandwidth of the selected members. */
void na_outputs(SuperTwistingObserver *o, AdaptiveBank *bank);

/* Whether every DOF's innovations and velocities have been compared for ADAPTIVE_SETTLED
 * windows: the selection is then worth following (the identifier waits for
 * it when it starts by itself). */
int na_settled(const AdaptiveBank *bank, int n);

/* Fixes the member the identifier follows to the one whose velocity is
 * published now on DOF 1
 * (one member for all DOFs: the rows of the regression share one regressor). */
void na_follow_published(AdaptiveBank *bank);

/* One step of G for a regressor entry: state s[3] = position error, velocity
 * error, estimate; returns the estimate (G phi).  s starts at 0. */
static inline double na_shadow_step(const AdaptiveGains *g, double h, double s[3],
                                          double phi)
{
    s[1] += h * (phi - s[2]);
    const double r = s[0] + h * s[1];
    s[1] -= g->k2 * r;
    s[2] += g->k3 * r;
    s[0] = (1.0 - g->k1) * r;
    return s[2];
}

/* Whether a deserialized bank's counts and indices fit its arrays. */
int na_valid(const AdaptiveBank *bank, int n);

#endif
