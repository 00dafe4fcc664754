/* The state-field groups (model_interface.h, StateField) of the core's parts,
 * shared by the models that hold them: STO_STATE_FIELDS(ModelData, pipe.obs)
 * lists the fields of a SuperTwistingObserver at pipe.obs that are not
 * doubles (or are derived), with their checks.  Each model adds REAL_FIELDS of
 * the same struct for its doubles, and its own fields. */
#ifndef STATE_FIELDS_H
#define STATE_FIELDS_H

#include "../core/fixed_lag.h"
#include "../core/implicit_twisting.h"
#include "../core/noise_adaptive.h"
#include "../core/regressor_identifier.h"
#include "../core/statistics_job.h"
#include "../instance/model_interface.h"

/* A SuperTwistingObserver (super_twisting.h). */
#define STO_STATE_FIELDS(T, o)                                                                   \
    DERIVED_FIELD(T, o.n), DERIVED_FIELD(T, o.h), DERIVED_FIELD(T, o.h_squared),                 \
    DERIVED_FIELD(T, o.inverse_h_squared), DERIVED_FIELD(T, o.alpha1),                           \
    DERIVED_FIELD(T, o.alpha2), DERIVED_FIELD(T, o.filter_gain), DERIVED_FIELD(T, o.rate_gain),  \
    DERIVED_FIELD(T, o.scheme), DERIVED_FIELD(T, o.learning_gain),                                \
    STATE_FIELD(T, o.implicit.primed, FIELD_INT, 0, 1),                       \
    STATE_FIELD(T, o.implicit.reversal_age, FIELD_INT, -1, IMPLICIT_REVERSAL_SAMPLES - 1),                \
    STATE_FIELD(T, o.implicit.smooth_samples, FIELD_INT, 0, IMPLICIT_SMOOTH_SAMPLES)

/* An AdaptiveBank (noise_adaptive.h); its indices below its member count are
 * na_valid's to check. */
#define BANK_STATE_FIELDS(T, b)                                                                  \
    DERIVED_FIELD(T, b.tuning), DERIVED_FIELD(T, b.count), DERIVED_FIELD(T, b.gain),            \
    DERIVED_FIELD(T, b.stride),                                                                  \
    DERIVED_FIELD(T, b.span), DERIVED_FIELD(T, b.velocity_gain), DERIVED_FIELD(T, b.start_limit), \
    DERIVED_FIELD(T, b.gains), DERIVED_FIELD(T, b.fine),                                         \
    STATE_FIELD(T, b.zoom_index, FIELD_INT, -1, (ADAPTIVE_MAX_MEMBERS - 1) * ADAPTIVE_FINE),     \
    STATE_FIELD(T, b.center, FIELD_INT, -1, ADAPTIVE_MAX_MEMBERS - 1),                           \
    STATE_FIELD(T, b.started, FIELD_INT, 0, 1),                                                  \
    STATE_FIELD(T, b.waited, FIELD_UNSIGNED, 0, 4294967295.0),                                   \
    STATE_FIELD(T, b.age, FIELD_UNSIGNED, 0, 4294967295.0),                                      \
    STATE_FIELD(T, b.selected, FIELD_INT, ADAPTIVE_SUPER_TWISTING,                               \
                ADAPTIVE_MAX_MEMBERS + ADAPTIVE_ZOOM - 1),                                       \
    STATE_FIELD(T, b.published, FIELD_INT, ADAPTIVE_SUPER_TWISTING,                              \
                ADAPTIVE_MAX_MEMBERS + ADAPTIVE_ZOOM - 1),                                       \
    STATE_FIELD(T, b.perturbation, FIELD_INT, ADAPTIVE_SUPER_TWISTING, ADAPTIVE_MAX_MEMBERS - 1), \
    STATE_FIELD(T, b.follow, FIELD_INT, ADAPTIVE_SUPER_TWISTING, ADAPTIVE_MAX_MEMBERS - 1)

/* A FixedLag (fixed_lag.h); its doubles other than the coefficients are REAL_FIELDS. */
#define FL_STATE_FIELDS(T, f)                                                                    \
    DERIVED_FIELD(T, f.coordinates), DERIVED_FIELD(T, f.signals), DERIVED_FIELD(T, f.h),         \
    DERIVED_FIELD(T, f.inputs_held), DERIVED_FIELD(T, f.held), DERIVED_FIELD(T, f.terms),       \
    DERIVED_FIELD(T, f.term_held), DERIVED_FIELD(T, f.term_tag),                                 \
    DERIVED_FIELD(T, f.half), DERIVED_FIELD(T, f.leads), DERIVED_FIELD(T, f.lead),               \
    DERIVED_FIELD(T, f.k0), DERIVED_FIELD(T, f.k1), DERIVED_FIELD(T, f.k2),                      \
    DERIVED_FIELD(T, f.noise_gain), DERIVED_FIELD(T, f.probe),                                   \
    DERIVED_FIELD(T, f.probe_gain), STATE_FIELD(T, f.noise_square, FIELD_REAL, 0.0, NAN),         \
    STATE_FIELD(T, f.noise_squares, FIELD_REAL, 0.0, NAN),                                       \
    STATE_FIELD(T, f.newest, FIELD_INT, 0, FL_RING - 1),                                         \
    STATE_FIELD(T, f.filled, FIELD_INT, 0, FL_RING),                                             \
    STATE_FIELD(T, f.square, FIELD_REAL, 0.0, NAN), STATE_FIELD(T, f.squares, FIELD_REAL, 0.0, NAN), \
    STATE_FIELD(T, f.chosen, FIELD_INT, -1, FL_CANDIDATES - 1)

/* A LeaveOut rule (leave_out.h): its constants; the gap clock is a real. */
#define LEAVE_OUT_STATE_FIELDS(T, rule)                                                          \
    DERIVED_FIELD(T, rule.reference_lambda), DERIVED_FIELD(T, rule.reference_pull),              \
    DERIVED_FIELD(T, rule.rest_lambda), DERIVED_FIELD(T, rule.rest_pull),                        \
    DERIVED_FIELD(T, rule.skip_threshold), DERIVED_FIELD(T, rule.gap_limit)

/* A RegressorIdentifier (regressor_identifier.h); anchor_unit and batch_age
 * below p + 2 and batch_samples are the model's check_restored's. */
#define RRI_STATE_FIELDS(T, id)                                                                  \
    DERIVED_FIELD(T, id.rows), DERIVED_FIELD(T, id.p), DERIVED_FIELD(T, id.columns),             \
    DERIVED_FIELD(T, id.runs), DERIVED_FIELD(T, id.run_start), DERIVED_FIELD(T, id.run_end),     \
    DERIVED_FIELD(T, id.weight), DERIVED_FIELD(T, id.h), DERIVED_FIELD(T, id.rho),               \
    DERIVED_FIELD(T, id.lambda), DERIVED_FIELD(T, id.one_minus_lambda_rho),                      \
    STATE_FIELD(T, id.anchor_age, FIELD_INT, 0, RRI_ANCHOR_INTERVAL),                            \
    STATE_FIELD(T, id.anchor_unit, FIELD_INT, 0, RRI_MAX_PARAMETERS + 2),                        \
    STATE_FIELD(T, id.anchor_failed, FIELD_INT, 0, 1), DERIVED_FIELD(T, id.batch_samples),       \
    STATE_FIELD(T, id.batch_age, FIELD_INT, 0, RRI_MAX_BATCH_SAMPLES),                           \
    DERIVED_FIELD(T, id.batch_lambda), LEAVE_OUT_STATE_FIELDS(T, id.leave_out)

/* A StatisticsJob (statistics_job.h); its index below the stage's limit is the
 * model's check_restored's (statistics_job_valid). */
#define SJ_STATE_FIELDS(T, job)                                                                  \
    DERIVED_FIELD(T, job.p), DERIVED_FIELD(T, job.interval), DERIVED_FIELD(T, job.budget),       \
    STATE_FIELD(T, job.since, FIELD_REAL, 0.0, NAN),                                             \
    STATE_FIELD(T, job.stage, FIELD_INT, SJ_IDLE, SJ_EIGEN),                                     \
    STATE_FIELD(T, job.index, FIELD_INT, 0,                                                      \
                RRI_MAX_PARAMETERS > STATS_EIGEN_ITERATIONS ? RRI_MAX_PARAMETERS                 \
                                                            : STATS_EIGEN_ITERATIONS),           \
    STATE_FIELD(T, job.completed, FIELD_REAL, 0.0, NAN),                                         \
    STATE_FIELD(T, job.age, FIELD_REAL, 0.0, INFINITY)

#endif
