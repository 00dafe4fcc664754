/* Standard errors of a least-squares estimate (LSM) by the sandwich formula,
 * with the scores taken at the current estimate rather than at a running one.
 *
 * The estimate solves P Delta = Theta with P = rho I + h sum phi phi^T and
 * Theta = h sum z phi^T.  Its error is P^-1 h sum phi e; for residuals e
 * correlated in time, cov = P^-1 (T S_w) P^-1, S_w the scores' w = phi e
 * spectral density at zero frequency and T the data's length.  S_w is read
 * from the mean score of a sliding window: E[mean mean^T] = S_w / (2 T_b).
 *
 * Why the current estimate: with the running estimate of each moment as the
 * reference (what the identifier had before), the scores carry that
 * estimate's own slowly shrinking error times phi phi^T, low-frequency power
 * that is not in the final estimate.  Measured on the 40 s pendulum of
 * tests/harness/test_real_measurements.py (noise 1e-3 rad, 32 seeds): the
 * gravity term's reported error was 2-3x the spread of its estimates, 1.4x
 * with the current estimate.  The current estimate changes at every update,
 * so the window's means are kept for the scores at any Delta: the means of
 * s = phi z and of Phi = phi phi^T, whose second moments give
 *     E[(s - Phi Delta)(s - Phi Delta)^T]
 *       = E[s s^T] - E[s (Phi Delta)^T] - E[(Phi Delta) s^T] + E[(Phi Delta)(Phi Delta)^T].
 *
 * Why two filter stages: the window is two first-order low-pass stages, each
 * of time constant T_b / 2 (same E[mean mean^T] = S_w / (2 T_b) for white
 * scores).  One stage passes the scores' high-frequency power with a 1/f^2
 * tail, and the scores of a regressor without noise (sin x1) times the
 * double-differentiated noise in z are blue: 300x their zero-frequency
 * density at 5-20 Hz, which one stage leaked into the standard errors.
 *
 * The means are taken over blocks of samples from the increments of the
 * cumulative sums P and Theta, which the identifier keeps anyway: nothing is
 * added to its per-sample step.  A block (at most 32 samples, 3.2 ms at
 * 10 kHz) is short against the window, and its mean nulls the frequencies
 * that would alias into the window's pass band. */
#ifndef BLOCK_SCORES_H
#define BLOCK_SCORES_H

#include "identifier.h"

/* entries of a symmetric m x m matrix in packed upper-triangle form */
#define BS_PACKED (ID_MAX_REGRESSORS * (ID_MAX_REGRESSORS + 1) / 2)

typedef struct {
    int rows, m;
    double stage_gain_per_second; /* 1 / (T_b / 2) */
    double samples;               /* power updates so far (growing window first) */
    double last_P[ID_MAX_REGRESSORS][ID_MAX_REGRESSORS]; /* the sums at the last block's end */
    double last_theta[ID_MAX_ROWS][ID_MAX_REGRESSORS];
    /* the two stages' means of s (per row) and of Phi (packed) */
    double score_mean[2][ID_MAX_ROWS][ID_MAX_REGRESSORS];
    double info_mean[2][BS_PACKED];
    /* running means of the second moments of the second stage's means */
    double score_power[ID_MAX_ROWS][ID_MAX_REGRESSORS][ID_MAX_REGRESSORS]; /* E[s s^T] */
    double cross_power[ID_MAX_ROWS][ID_MAX_REGRESSORS][BS_PACKED];        /* E[s Phi] */
    double info_power[BS_PACKED][BS_PACKED];                               /* E[Phi Phi] */
} BlockScores;

/* window: T_b [s]; P and theta: the identifier's sums now, row-major with rows of
 * ID_MAX_REGRESSORS (P's upper triangle is read). */
void bs_init(BlockScores *bs, int rows, int m, double window,
             const double *P, const double *theta);

/* One block of `duration` seconds has been added to P and theta (by h phi phi^T
 * and h z phi^T per sample): its mean scores enter the window. */
void bs_block(BlockScores *bs, double duration,
              const double *P, const double *theta);

/* The window's current means enter the second moments with weight 1/count
 * for the first 1/gain updates, then with `gain` (an exponential window). */
void bs_update_power(BlockScores *bs, double gain);

/* E[mean mean^T] of the scores of `row` at the estimate delta (m x m, full). */
void bs_score_power(const BlockScores *bs, int row, const double delta[],
                    double power[ID_MAX_REGRESSORS][ID_MAX_REGRESSORS]);

#endif
