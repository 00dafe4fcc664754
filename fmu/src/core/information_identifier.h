/* LSM and MFF in information form with stabilized forgetting: the default
 * identifier (identifier_form = 2).  Same regression as the paper's
 * (z = Delta phi, section 5), integrated without the paper's weaknesses:
 *
 * - Information form: accumulate P = Gamma^-1 and Theta = Delta P, eqs. (26)-(27)
 *   and (35), instead of integrating Gamma by explicit Euler (19)/(36), which
 *   diverges when h |Gamma| |phi|^2 > 2.  Each step is an exact quadrature:
 *       P     <- lambda P     + (1 - lambda) rho I           + h phi phi^T
 *       Theta <- lambda Theta + (1 - lambda) rho Delta_hat   + h z phi^T
 *   with lambda = R^h (MFF) or 1 (LSM).  Stable for any h.
 * - Stabilized forgetting: MFF forgets toward rho I (and toward the current
 *   estimate), not toward 0.  Without excitation P tends to rho I, so
 *   Gamma = P^-1 <= I/rho always (the bound), and the estimate stays where it
 *   is instead of winding up.  (The paper's (36) forgets the rho I term: Gamma
 *   grows like R^-t.)  P stays symmetric positive definite by construction.
 * - Delta_hat = Theta P^-1 is solved by Cholesky only when asked (at
 *   communication points), so the internal step costs O(m^2) multiply-adds.
 * - A reset restarts from the nominal parameters (Delta_hat = 0, P = rho I).
 * - Standard errors by the sandwich formula from the scores' low-frequency power
 *   (LSM: at the current estimate, block_scores.h).
 * - Drift model (MFF, optional): forgetting makes the estimate lag a moving
 *   parameter by about the memory 1/|ln R| (0.43 s at R = 0.1).  With
 *   drift on, each parameter is modelled locally as Delta(s) = Delta0 +
 *   Delta1 (s - t): the regressor is augmented with phi (s - t), which is 0
 *   for the newest sample, and the sums are re-centred at every step
 *   (phi (s - t - h) = phi (s - t) - h phi, a congruence with
 *   A = [[I, 0], [-h I, I]]).  Delta0 is then the estimate at the current
 *   time, free of the lag for a linear drift.  Without data the slope Delta1
 *   is forgotten toward 0 (not toward itself), so the estimate does not keep
 *   extrapolating its last trend.  Needs 2 m <= 8 regressors.
 * - Uninformative samples are left out (MFF), the rule of leave_out.h, a sample's
 *   information being q = h phi^T Pref^-1 phi with Pref's full m x m form (the
 *   Cholesky factor of the last anchor refresh); in a rest the drift model's clock
 *   stands still as well. */
#ifndef INFORMATION_IDENTIFIER_H
#define INFORMATION_IDENTIFIER_H

#include "tuning.h"

#include "block_scores.h"
#include "identifier.h"
#include "leave_out.h"

typedef struct {
    int rows, m;          /* m: the identified regressors; the sums have 2m with drift */
    int drift;            /* drift model on (MFF only) */
    double h, rho;
    IdentifierTuning tuning; /* the windows of its statistics (tuning.h) */
    double lambda;        /* R^h per step (MFF), 1 (LSM) */
    double one_minus_lambda_rho;
    double forgetting_rate;  /* |ln R| per second (MFF) */
    double active_time;   /* time integrated since the (re)start [s] */
    double P[ID_MAX_REGRESSORS][ID_MAX_REGRESSORS];     /* information matrix, upper triangle kept */
    double theta[ID_MAX_ROWS][ID_MAX_REGRESSORS];       /* Theta = Delta P */
    double delta[ID_MAX_ROWS][ID_MAX_REGRESSORS];       /* last solved Delta_hat (first m: Delta0) */
    /* MFF forgets toward this estimate, solved afresh every anchor_interval
     * samples by the identifier itself, so that the sums never depend on
     * when (at which communication points) Delta_hat is asked for.  The
     * interval forgets at most 1 % (1 - lambda^interval), and is 1..32 samples. */
    double anchor[ID_MAX_ROWS][ID_MAX_REGRESSORS];
    int anchor_interval, anchor_age;
    /* MFF: the long-run information inflow Pref (m x m, upper triangle) and
     * its Cholesky factor from the last anchor refresh */
    double reference[ID_MAX_REGRESSORS][ID_MAX_REGRESSORS];
    double reference_factor[ID_MAX_REGRESSORS][ID_MAX_REGRESSORS];
    LeaveOut leave_out;    /* its constants and gap clock */
    double used_mean;      /* fraction of the samples used, over the memory */
    double gamma_trace;   /* trace(P^-1), from the last solve */
    /* Standard errors of Delta_hat (sandwich form, correlated residuals
     * included), from the scores' low-frequency spectral density.  LSM: the
     * scores at the current estimate, from the sums' block increments
     * (block_scores.h).  MFF, whose estimate moves: the scores
     * phi (z - anchor phi) through a batch-mean filter (track_residual). */
    double batch_gain, power_gain, residual_samples;
    int std_age;          /* samples since the last update of the standard errors */
    BlockScores blocks;   /* LSM */
    double score_mean[ID_MAX_ROWS][ID_MAX_REGRESSORS];                     /* MFF */
    double score_power[ID_MAX_ROWS][ID_MAX_REGRESSORS][ID_MAX_REGRESSORS]; /* MFF, upper triangle */
    double std_error[ID_MAX_ROWS][ID_MAX_REGRESSORS]; /* from the last solve */
    double excitation;    /* smallest eigenvalue of the information per unit time */
    double eigvec[ID_MAX_REGRESSORS]; /* inverse-iteration vector for that eigenvalue */
    /* ii_factor's Cholesky factor of P (lower triangle) and Theta at that
     * moment, from which ii_finish solves Delta_hat and gamma_trace later:
     * the sums move on with the next internal steps */
    double factor[ID_MAX_REGRESSORS][ID_MAX_REGRESSORS];
    double theta_factored[ID_MAX_ROWS][ID_MAX_REGRESSORS];
    int solve_pending;    /* ii_finish has work to do */
} InformationIdentifier;

/* tuning: its identifier and leave_out groups are taken (NULL: tuning.h's). */
void ii_init(InformationIdentifier *id, IdentifierKind kind, int rows, int m, double h,
               double rho, double R, int drift, const StoTuning *tuning);

/* Back to the nominal parameters and P = rho I. */
void ii_reset(InformationIdentifier *id);

/* One internal step with the (filtered) injection z and regressor phi. */
void ii_step(InformationIdentifier *id, const double z[], const double phi[]);

/* ii_step over `count` samples in turn. */
void ii_run(InformationIdentifier *id, const IdSample samples[], int count);

/* Solves Delta_hat = Theta P^-1 and refreshes gamma_trace and excitation.
 * Returns 0, or -1 if P is not positive definite (cannot happen with rho > 0
 * and finite data; the previous estimate is then kept).  The same as
 * ii_factor then ii_finish. */
int ii_solve(InformationIdentifier *id);

/* The part of ii_solve that must run when asked: factors P, keeps the factor
 * and Theta for ii_finish, and takes the excitation's inverse-iteration step
 * (a state: one step per call).  Returns 0, or -1 as ii_solve (nothing kept). */
int ii_factor(InformationIdentifier *id);

/* The rest of ii_solve at the last successful ii_factor: Delta_hat and
 * gamma_trace, as ii_solve would have left them then (nothing if done). */
void ii_finish(InformationIdentifier *id);

#endif
