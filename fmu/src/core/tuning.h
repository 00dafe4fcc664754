/* Every tuning constant of the core in one table: what each sets, in what
 * unit.  The reasoning behind the values is in docs/design/; the mechanisms
 * they tune are described in the header of the algorithm named in each group.
 * Array sizes and limits of the data structures are not tuning and stay with
 * their structures.  The same values are a struct at run time (StoTuning, below), of
 * which each part of the core takes its group when it starts. */
#ifndef TUNING_H
#define TUNING_H

/* ---- convergence test of every scheme (super_twisting.h) ---------------------------- */
#define STO_CONVERGED_RATE 0.25 /* switching rate of sign(e) above which a DOF slides */

/* ---- implicit scheme (implicit_twisting.h) ------------------------------------------ */
#define IMPLICIT_REVERSAL_SAMPLES 2 /* samples after a reversal over which the injection's
                                     * jump measures the Coulomb level missed */
#define IMPLICIT_LEARNING_GAIN 0.5  /* share of that jump the learned level takes */
#define IMPLICIT_SMOOTH_SAMPLES 4   /* samples in the sliding set without a reversal before
                                     * the prediction takes the injection's trend */

/* ---- noise-adaptive bank (noise_adaptive.h) ----------------------------------------- */
#define ADAPTIVE_LOWEST_BANDWIDTH 2.0 /* [rad/s] the slowest linear member */
#define ADAPTIVE_HIGHEST_BANDWIDTH 0.5 /* [1/h] the fastest member: omega h at most this */
#define ADAPTIVE_RATIO 1.8          /* between the bandwidths of neighbouring members */
#define ADAPTIVE_FINE 3             /* steps of the zoom members' grid per ADAPTIVE_RATIO */
#define ADAPTIVE_REACH_SLOWER 2     /* members below a chosen one that run (at least 1: the
                                     * velocity candidate takes the one below the centre) ... */
#define ADAPTIVE_REACH_FASTER 1     /* ... and above it */
#define ADAPTIVE_WINDOW 1.0         /* [s] of the mean square innovations */
#define ADAPTIVE_SECANT_TIME 0.04   /* [s] span of the secants that rank velocities ... */
#define ADAPTIVE_SLOTS 16           /* ... at least this many strides (the slots in flight) */
#define ADAPTIVE_PERTURBATION_SPANS 8 /* between the secants that measure the perturbation */
#define ADAPTIVE_START_TIME 0.3     /* [s] the members start then if the super-twisting
                                     * observer has not converged (quantized data) */
#define ADAPTIVE_MIN_SAMPLES 50     /* before the first selection */
#define ADAPTIVE_HYSTERESIS 0.9     /* a smaller mean square by this factor takes over */
#define ADAPTIVE_EXACT_RATIO 0.25   /* super-twisting one-step mean square below this times
                                     * the members' best: exact data, it stays published ... */
#define ADAPTIVE_SATURATION_LIMIT 0.1 /* ... while its injection saturates in fewer steps */
#define ADAPTIVE_AVERAGING 10.0     /* z_eq_filtered: a member's xi averaged over this / omega */
#define ADAPTIVE_SETTLED 0.6        /* windows of comparisons before the identifier follows
                                     * a member (earlier, it follows one chosen too early) */

/* ---- identifier in information form (information_identifier.h) --------------------- */
#define INFO_ANCHOR_MAX_INTERVAL 32 /* samples between the anchor's solves at most ... */
#define INFO_ANCHOR_FORGETTING 0.01 /* ... and at least every this share of MFF's memory */
#define INFO_BATCH_WINDOW 1.0       /* [s] MFF: batch-mean filter of the residuals */
#define INFO_LSM_SCORE_WINDOW 5.0   /* [s] LSM: window of the scores' mean (block_scores.h) */
#define INFO_POWER_WINDOW 30.0      /* [s] mean square of that mean (growing window first) */
#define INFO_SCORE_DELAY 2.0        /* [s] of identification before the scores count */
#define INFO_STD_INTERVAL 256       /* samples between updates of the standard errors */

/* ---- MFF's rule that leaves uninformative samples out (information_identifier.h) -- */
#define INFO_REFERENCE_MEMORY 10.0  /* Pref's memory, in MFF memories 1/|ln R| */
#define INFO_REST_MEMORY 100.0      /* Pref's memory over the samples left out */
#define INFO_SKIP_SHARE 0.04        /* below this share of the long-run inflow a sample is
                                     * left out: |v| < 0.2 RMS(v) for a velocity regressor */
#define INFO_GAP_MEMORY 0.25        /* gaps longer than this many memories freeze the sums */

/* ---- model feedback (model_feedback.h) ---------------------------------------------- */
#define FEEDBACK_START 1.0  /* [s] of identification before the model is fed back ... */
#define FEEDBACK_RAMP 1.0   /* [s] ... and over which it enters (a jump would put h times
                             * its change on the next velocity) */
#define FEEDBACK_SIGMAS 2.0 /* a correction of this many standard errors enters at 4/5 */

/* ---- robots: regression and identifier (robot_observer.h, regressor_identifier.h) --- */
#define RO_STEP 1e-3               /* [s] the robot observer's default internal step */
#define RO_TAU 0.01                /* [s] default of its injection's and regression's filter */
#define RO_CONVERGENCE_WINDOW 0.05 /* [s] default of its switching-rate test's window */
#define RO_F_PLUS 10.0             /* [rad/s2] default bound of the model's acceleration error */
#define RO_GAIN_EXPONENT 0.5       /* default p of Theorem 3.1 */
#define RO_RHO 1e-6                /* default regularization of its identifier */
#define RO_R 0.1                   /* [1/s] default forgetting factor of its identifier (MFF) */
#define RO_MIN_SPEED 0.05          /* [rad/s or m/s] default of the regression's min_speed */
#define RO_REVERSAL_MARGIN 0.02    /* [s] default of its reversal_margin */
#define RO_STATISTICS_INTERVAL 0.1 /* [s] default of the FMU's statistics_interval */
#define RRI_BATCH_TIME 0.5         /* [s] of scores summed into one batch */
#define RRI_SCORE_RESTART 0.1      /* the residual power of the anchor's move since the kept
                                    * batches began, over the batch's: above, the scores'
                                    * sum restarts (regressor_identifier.h) */
#define RRI_ANCHOR_INTERVAL 32     /* samples between snapshots of the anchor's solve */

/* ---- model files (model_pipeline.h) ------------------------------------------------ */
#define MP_INJECTION_TAU 0.002      /* [s] filter of the observer's injection (its output) */
#define MP_CONVERGENCE_WINDOW 0.05  /* [s] of the switching-rate test before identifying */
#define MP_SINGULAR_PIVOT 1e-12     /* a pivot below this share of the largest |M_ij|: the
                                     * nominal inertia is singular, F = 0 */
#define MP_WARM_UP 10.0             /* time constants of G before its rows enter (e^-10) */
#define MP_TAU_IDENTIFIER 0.02      /* [s] default of the regression's filter G */
#define MP_RHO 1e-12                /* default regularization, SI parameters */
#define MP_SLOW_FRACTION 0.05       /* an equation with sign(q') is left out where |q'| is
                                     * below this share of its RMS (identify's friction
                                     * rows use the same share) */

/* ---- the identifier's fixed-lag derivatives (fixed_lag.h) --------------------------- */
#define FL_HIGHEST_FRACTION 0.2     /* the widest candidate's cut-off [sample rate] ... */
#define FL_CANDIDATES 4             /* ... and each next one half the one before */
#define FL_CYCLES 6.0               /* half a window: this many periods of its cut-off */
#define FL_NOISE_SHARE 0.01         /* noise's share of an acceleration's mean square, at
                                     * most, in the band chosen */
#define FL_PROBE_FRACTION 0.4       /* [sample rate] the noise is what a kernel of this
                                     * cut-off leaves of the positions */
#define FL_REVERSAL_PERIODS 1.5     /* periods of the cut-off: an equation with a joint's
                                     * Coulomb friction is left out this near (before and
                                     * after) a reversal of the window's velocity
                                     * (identify's friction rows use the same margin) */
#define OP_MODEL_STEPS 32           /* internal steps between the updates of the observer's
                                     * identified model (information form: the factor,
                                     * the excitation's iteration, the fed-back estimate),
                                     * on the instance's clock: a long communication step
                                     * equals its single steps, at a 32nd of the cost */
#define MP_WARNING_DELAY 1.0        /* [s] the published model creates energy, holds
                                     * parameters at their ranges or leaves some not
                                     * excited this long before the warning: not every
                                     * transient estimate */
#define MP_NOT_EXCITED 1e-3         /* a parameter's column excitation below this is not
                                     * excited: the threshold identify refuses below */

/* ---- the inputs' cadence (input_cadence.h) ----------------------------------------- */
#define CADENCE_WINDOW 2.0          /* [s] over which the shortest hold of the inputs counts
                                     * (holds up to half of it are seen) */
#define CADENCE_COARSE_STEPS 2      /* inputs held this many internal steps at least over a
                                     * whole window: a staircase coarser than the step */

/* ---- statistics of an identifier (information_statistics.h, statistics_job.h) ------ */
#define STATS_EIGEN_ITERATIONS 30   /* inverse iterations at most */
#define STATS_EIGEN_TOLERANCE 1e-13 /* stop at this relative change of the eigenvalue */
#define SJ_BUDGET 4096.0            /* multiply-adds of the statistics job per internal step */

/* ---- the same values at run time ------------------------------------------------------
 * Each part of the core takes its group of this table when it is initialized
 * (tuning_default: the values above), so that a caller may run it with others:
 * a study of one rule, a test.  The limits that size arrays or bound a restored
 * state's counters (IMPLICIT_REVERSAL_SAMPLES, IMPLICIT_SMOOTH_SAMPLES,
 * INFO_ANCHOR_MAX_INTERVAL, INFO_STD_INTERVAL, RRI_ANCHOR_INTERVAL) stay compile-time. */

/* The noise-adaptive bank's (noise_adaptive.h; ADAPTIVE_FINE, ADAPTIVE_SLOTS and
 * ADAPTIVE_PERTURBATION_SPANS size its arrays: they are not tuning). */
typedef struct {
    double lowest_bandwidth;  /* [rad/s] ADAPTIVE_LOWEST_BANDWIDTH */
    double highest_bandwidth; /* [1/h] ADAPTIVE_HIGHEST_BANDWIDTH */
    double ratio;             /* ADAPTIVE_RATIO, > 1 */
    double window;            /* [s] ADAPTIVE_WINDOW */
    double secant_time;       /* [s] ADAPTIVE_SECANT_TIME */
    double start_time;        /* [s] ADAPTIVE_START_TIME */
    double hysteresis;        /* ADAPTIVE_HYSTERESIS, in (0, 1] */
    double exact_ratio;       /* ADAPTIVE_EXACT_RATIO */
    double saturation_limit;  /* ADAPTIVE_SATURATION_LIMIT */
    double averaging;         /* ADAPTIVE_AVERAGING */
    double settled;           /* ADAPTIVE_SETTLED */
    double min_samples;       /* ADAPTIVE_MIN_SAMPLES (a count) */
    int reach_slower;         /* ADAPTIVE_REACH_SLOWER, >= 1 */
    int reach_faster;         /* ADAPTIVE_REACH_FASTER, >= 0 */
} AdaptiveTuning;

/* The implicit scheme's (implicit_twisting.h). */
typedef struct {
    double learning_gain; /* IMPLICIT_LEARNING_GAIN, in (0, 1] */
} ImplicitTuning;

/* The information-form identifier's (information_identifier.h). */
typedef struct {
    double anchor_forgetting; /* INFO_ANCHOR_FORGETTING, > 0 */
    double batch_window;      /* [s] INFO_BATCH_WINDOW */
    double lsm_score_window;  /* [s] INFO_LSM_SCORE_WINDOW */
    double power_window;      /* [s] INFO_POWER_WINDOW */
    double score_delay;       /* [s] INFO_SCORE_DELAY, >= 0 */
} IdentifierTuning;

/* MFF's rule that leaves uninformative samples out (both identifiers). */
typedef struct {
    double reference_memory; /* INFO_REFERENCE_MEMORY, > 0 */
    double rest_memory;      /* INFO_REST_MEMORY, > 0 */
    double skip_share;       /* INFO_SKIP_SHARE, >= 0 */
    double gap_memory;       /* INFO_GAP_MEMORY, >= 0 */
} LeaveOutTuning;

/* Model feedback's (model_feedback.h). */
typedef struct {
    double start;  /* [s] FEEDBACK_START, >= 0 */
    double ramp;   /* [s] FEEDBACK_RAMP, > 0 */
    double sigmas; /* FEEDBACK_SIGMAS, >= 0 */
} FeedbackTuning;

/* A restored FMU state's tuning is compared byte for byte with a fresh one's: no padding. */
_Static_assert(sizeof(AdaptiveTuning) == 12 * sizeof(double) + 2 * sizeof(int),
               "AdaptiveTuning has padding");

typedef struct {
    AdaptiveTuning bank;
    ImplicitTuning implicit;
    IdentifierTuning identifier;
    LeaveOutTuning leave_out;
    FeedbackTuning feedback;
} StoTuning;

/* The table's values. */
StoTuning tuning_default(void);

/* What is wrong with a tuning, or its bank's part (NULL: nothing). */
const char *tuning_problem(const StoTuning *tuning);
const char *tuning_adaptive_problem(const AdaptiveTuning *tuning);

#endif
