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
 * - Uninformative samples are left out (MFF): a sample whose information
 *   q = h phi^T Pref^-1 phi is below INFO_SKIP_SHARE of its share
 *   m (1 - lambda_ref) of the long-run inflow Pref (the information with the
 *   longer memory INFO_REFERENCE_MEMORY / |ln R|) does not add to the sums.
 *   A gap of such samples up to INFO_GAP_MEMORY memories long (a velocity
 *   zero) forgets and extrapolates the drift as before; a longer one (a
 *   rest) freezes the sums, and the drift model's clock stands still.
 *   Without that, a motion that stops or decays to a crawl, where
 *   quantization, static friction and discretization dominate the data, is
 *   fitted with a Gamma that has grown to its bound 1/rho: measured on the
 *   6.3 pendulum after 50 s of excitation (bench/no_excitation.py), the
 *   estimate moved 160-600 % in the 3 s ring-down with a 12-bit encoder,
 *   and up to 850 % over 60 s at rest on explicit-Euler plant data, whose
 *   velocity keeps alternating.  Over left-out samples Pref forgets with the
 *   10x longer memory INFO_REST_MEMORY / |ln R|, so that an isolated pulse
 *   after a long rest (an encoder step of a creeping plant) stays small
 *   against it, while a lasting smaller excitation is taken up again.  At
 *   steady excitation only the samples around velocity zeros are left out,
 *   which carry little information on any parameter whose regressor
 *   vanishes with the velocity. */
#ifndef INFORMATION_IDENTIFIER_H
#define INFORMATION_IDENTIFIER_H

#include "tuning.h"

#include "block_scores.h"
#include "identifier.h"

typedef struct {
    int rows, m;          /* m: the identified regressors; the sums have 2m with drift */
    int drift;            /* drift model on (MFF only) */
    double h, rho;
    IdentifierTuning tuning; /* the windows of its statistics (tuning.h) */
    double gap_memory;    /* MFF's leave-out rule: memories of a gap that freeze the sums */
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
    double reference_lambda, reference_pull; /* lambda^(1/INFO_REFERENCE_MEMORY), its rho pull */
    double rest_lambda, rest_pull; /* the same over left-out samples: lambda^(1/INFO_REST_MEMORY) */
    double skip_threshold; /* INFO_SKIP_SHARE m (1 - reference_lambda) / h */
    double used_mean;      /* fraction of the samples used, over the memory */
    double gap_time;       /* time since the last sample used [s] */
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
    /* info_factor's Cholesky factor of P (lower triangle) and Theta at that
     * moment, from which info_finish solves Delta_hat and gamma_trace later:
     * the sums move on with the next internal steps */
    double factor[ID_MAX_REGRESSORS][ID_MAX_REGRESSORS];
    double theta_factored[ID_MAX_ROWS][ID_MAX_REGRESSORS];
    int solve_pending;    /* info_finish has work to do */
} InformationIdentifier;

/* tuning: its identifier and leave_out groups are taken (NULL: tuning.h's). */
void info_init(InformationIdentifier *id, IdentifierKind kind, int rows, int m, double h,
               double rho, double R, int drift, const StoTuning *tuning);

/* Back to the nominal parameters and P = rho I. */
void info_reset(InformationIdentifier *id);

/* One internal step with the (filtered) injection z and regressor phi. */
void info_step(InformationIdentifier *id, const double z[], const double phi[]);

/* info_step over `count` samples in turn. */
void info_run(InformationIdentifier *id, const IdSample samples[], int count);

/* Solves Delta_hat = Theta P^-1 and refreshes gamma_trace and excitation.
 * Returns 0, or -1 if P is not positive definite (cannot happen with rho > 0
 * and finite data; the previous estimate is then kept).  The same as
 * info_factor then info_finish. */
int info_solve(InformationIdentifier *id);

/* The part of info_solve that must run when asked: factors P, keeps the factor
 * and Theta for info_finish, and takes the excitation's inverse-iteration step
 * (a state: one step per call).  Returns 0, or -1 as info_solve (nothing kept). */
int info_factor(InformationIdentifier *id);

/* The rest of info_solve at the last successful info_factor: Delta_hat and
 * gamma_trace, as info_solve would have left them then (nothing if done). */
void info_finish(InformationIdentifier *id);

#endif
