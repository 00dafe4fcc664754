/* LSM and MFF in information form over a regressor matrix: the identification
 * of robots, where one parameter vector is shared by all joints.
 *     z = Y Delta,   z (n) the torque residual tau - Y beta_nominal,
 *                    Y (n x p) the base regressor, Delta = beta - beta_nominal.
 * Per-joint friction then costs 2 parameters per joint, and link inertial
 * parameters (reduced to base parameters) and a payload enter the regression.
 *
 * Same guarantees as information_identifier.h, in this form:
 * - information form, an exact quadrature at each step, stable for any h:
 *       P <- lambda P + (1 - lambda) rho I          + h Y^T W Y
 *       b <- lambda b + (1 - lambda) rho Delta_anchor + h Y^T W z
 *   with lambda = R^h (MFF) or 1 (LSM), W = diag(1/s_i^2) the joints' torque
 *   scales (so that joints with large torques do not drown the others);
 * - stabilized forgetting toward rho I: Gamma = P^-1 <= I / rho always;
 * - Delta_hat = P^-1 b by Cholesky only when asked (ri_solve), so the
 *   internal step costs at most n p (p + 3) / 2 multiply-adds, plus the
 *   running solution (the anchor): the solve of a snapshot of P and b taken every
 *   RRI_ANCHOR_INTERVAL samples, spread in equal shares of work over the
 *   samples up to the next snapshot (about (p^3 / 6 + p^2) / RRI_ANCHOR_INTERVAL
 *   multiply-adds per sample: no sample carries the whole factorization);
 * - reset back to the nominal parameters (Delta = 0, P = rho I);
 * - standard errors by the sandwich formula P^-1 S P^-1, S the (forgotten) sum
 *   of the outer products of the scores h Y^T W (z - Y Delta_anchor) summed over
 *   batches of RRI_BATCH_TIME seconds, so that residuals correlated over less
 *   than a batch (filtered signals) are accounted for.  The scores are at the
 *   anchor of their time, and an anchor still far from the estimate (the first
 *   batches, from nominal parameters that may be 0) adds its own error times
 *   Y^T W Y, power that is not in the final estimate's error and that least
 *   squares would keep for ever (the oscillator's standard errors were 36 to 160
 *   times the spread over seeds): so when the anchor has moved, since the kept
 *   batches began, by d with d^T P d / memory (the residual power that move
 *   makes) above RRI_SCORE_RESTART of the batch's residual power, the sum
 *   restarts; S is the kept batches' sum scaled to the count of all
 *   (ri_score_scale);
 * - trust outputs: trace(Gamma) and the excitation (smallest eigenvalue of the
 *   information per unit time);
 * - uninformative samples left out (MFF), the rule of leave_out.h, a sample's
 *   information being q = h sum_i w_i sum_k y_ik^2 / Pref_kk, the trace
 *   tr(D^-1 Y^T W Y) with D the diagonal of the long-run inflow Pref; a rest is the
 *   joint equations weighted 0 below min_speed, the filter decayed.
 *   The diagonal, not Pref^-1: one multiply-add per
 *   regressor entry read instead of n p^2 / 2 (a forward substitution per row, 11 k
 *   for the Panda arm, about the whole rank-n update again); what the rule must tell
 *   apart is rows of the excitation's size from rows that have collapsed (weight 0,
 *   a decayed filter, velocity columns at a crawl), which the column-scaled norm sees
 *   as the full form does.  Its blind spot, a small row along a direction that Pref
 *   holds little of (a difference of nearly collinear columns), is left out where the
 *   full form would take it: information lost at low excitation, never a wind-up.
 * The columns of Y taken are the base columns (an index list that the harness
 * computes offline from the URDF, harness/robot/base_parameters.py). */
#ifndef REGRESSOR_IDENTIFIER_H
#define REGRESSOR_IDENTIFIER_H

#include "identifier.h"
#include "leave_out.h"
#include "tuning.h"

#include "rigid_body.h"

#define RRI_MAX_ROWS RB_MAX_JOINTS
#define RRI_MAX_PARAMETERS RB_MAX_PARAMETERS
#define RRI_PARAMETERS_OF(rows) (RB_PARAMETERS_PER_JOINT * (rows)) /* full regressor's columns */
#define RRI_MAX_BATCH_SAMPLES 1e9 /* samples in a batch at most (an int) */

typedef struct {
    int rows, p;                 /* joints n; identified (base) parameters p */
    int columns[RRI_MAX_PARAMETERS]; /* columns of the full regressor taken */
    /* where row i of the base regressor can be nonzero (in the layout of
     * rb_regressor): columns run_start[i][r]..run_end[i][r]-1, r < runs[i] */
    int runs[RRI_MAX_ROWS];
    int run_start[RRI_MAX_ROWS][RRI_MAX_PARAMETERS], run_end[RRI_MAX_ROWS][RRI_MAX_PARAMETERS];
    double weight[RRI_MAX_ROWS]; /* 1 / s_i^2 */
    double h, rho, lambda, one_minus_lambda_rho;
    double active_time;          /* [s] since the (re)start */
    double P[RRI_MAX_PARAMETERS][RRI_MAX_PARAMETERS]; /* upper triangle kept */
    double b[RRI_MAX_PARAMETERS];
    double delta[RRI_MAX_PARAMETERS];       /* last solved Delta_hat */
    double anchor[RRI_MAX_PARAMETERS];      /* what MFF forgets toward; the scores' estimate */
    int anchor_age;              /* samples since the snapshot of the anchor's next solve */
    /* that solve, spread over the RRI_ANCHOR_INTERVAL samples after its snapshot:
     * P (upper triangle) then its Cholesky factor, b then the solution, the next
     * unit (column j < p, forward solve p, backward solve p + 1) and the work done */
    double anchor_factor[RRI_MAX_PARAMETERS][RRI_MAX_PARAMETERS];
    double anchor_solution[RRI_MAX_PARAMETERS];
    int anchor_unit, anchor_failed;
    double anchor_work;
    /* scores over the current batch, and the sum of their outer products over the
     * batches kept (see ri_score_scale) */
    double score[RRI_MAX_PARAMETERS];
    double score_power[RRI_MAX_PARAMETERS][RRI_MAX_PARAMETERS]; /* upper triangle */
    int batch_samples, batch_age;
    double batch_lambda;         /* lambda over one batch */
    double batch_residual;       /* h w e^2 over the current batch */
    double batches, batches_kept; /* (forgotten) counts of all batches and of those kept */
    double anchor_kept[RRI_MAX_PARAMETERS]; /* the anchor when the kept batches began */
    double std_error[RRI_MAX_PARAMETERS];   /* from the last solve */
    double gamma_trace, excitation;
    double factor[RRI_MAX_PARAMETERS][RRI_MAX_PARAMETERS]; /* Cholesky workspace */
    /* MFF's leave-out rule: the diagonal of the long-run inflow Pref, its inverse
     * from the last anchor refresh, and the rule's constants */
    double reference[RRI_MAX_PARAMETERS], reference_inverse[RRI_MAX_PARAMETERS];
    LeaveOut leave_out;
} RegressorIdentifier;

/* columns[p]: the base columns of the full regressor (0..12n-1, distinct);
 * torque_scale[rows]: per-joint torque scales s_i > 0 (NULL: 1); leave_out: MFF's rule
 * (NULL: tuning.h's).
 * Returns 0, or -1 for sizes, columns, h, rho or R out of range. */
int ri_init(RegressorIdentifier *id, IdentifierKind kind, int rows, int p, const int columns[],
             const double torque_scale[], double h, double rho, double R,
             const LeaveOutTuning *leave_out);

/* The same over a dense regressor of any model (a model file's, model_pipeline.h):
 * Y's columns 0..p-1 are the parameters and every row may reach every column. */
int ri_init_dense(RegressorIdentifier *id, IdentifierKind kind, int rows, int p,
                   const double torque_scale[], double h, double rho, double R,
                   const LeaveOutTuning *leave_out);

/* Back to the nominal parameters and P = rho I. */
void ri_reset(RegressorIdentifier *id);

/* What score_power is multiplied by for the sum over all batches: their count over
 * the count of those kept (1 before any). */
double ri_score_scale(const RegressorIdentifier *id);

/* One internal step: z the torque residual (rows), Y the full regressor in the
 * layout of rb_regressor, whose structural zeros are not read (joint i's row
 * for the links before i and for the other joints' friction): the step costs
 * the regressor's nonzero products only, about a third of n p (p + 3) / 2 for
 * a 7-joint arm. */
void ri_step(RegressorIdentifier *id, const double z[], const RbRegressor *Y);

/* The entries of Y that ri_step reads (row i's base columns), weighted and
 * through a first-order filter: filtered <- filtered + gain (weight_i Y - filtered)
 * (gain 1: filtered = weight_i Y).  The other entries of `filtered` are left as
 * they are (zero-initialize it).  Costs one multiply-add per entry read. */
void ri_filter_regressor(const RegressorIdentifier *id, const RbRegressor *Y,
                          const double weight[], double gain, RbRegressor *filtered);

/* Solves Delta_hat = P^-1 b (p^3/6 multiply-adds).  Returns 0, or -1 if P is
 * not positive definite (cannot happen with rho > 0 and finite data; the
 * estimate is then kept).  Between solves, the anchor is an estimate of P and b
 * RRI_ANCHOR_INTERVAL to 2 RRI_ANCHOR_INTERVAL - 1 samples old (ri_anchor_age),
 * which the step keeps at a bounded cost per step: what an FMU can output at
 * every communication point. */
int ri_solve(RegressorIdentifier *id);

/* Samples since the snapshot of P and b that the anchor solves (after the first
 * solve since the reset; before it the anchor is the reset's 0, exact). */
static inline int ri_anchor_age(const RegressorIdentifier *id)
{
    return id->anchor_age + RRI_ANCHOR_INTERVAL;
}

/* After ri_solve: the standard errors, trace(Gamma) and the excitation
 * (p^3 multiply-adds: at a slower rate than the estimate, or spread over
 * internal steps by statistics_job.h in the same arithmetic).  The inverse
 * iteration for the smallest eigenvalue starts from the uniform vector and
 * stops at convergence (information_statistics.h's STATS_EIGEN_TOLERANCE), after
 * STATS_EIGEN_ITERATIONS iterations at most. */
void ri_statistics(RegressorIdentifier *id);

#endif
