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
 * that is not in the final estimate.  Measured on data set A of
 * bench/realdata (40 s at 1 kHz, noise 1e-4 rad, 96 seeds,
 * bench/standard_errors.py): the gravity term's reported error was 4.3x the
 * spread of its estimates, 0.98x now.  The current estimate changes at every
 * update, so the window's means are kept for the scores at any Delta: the means
 * of s = phi z and of Phi = phi phi^T, whose second moments give
 * Why two filter stages: the window is two first-order low-pass stages, each
 * of time constant T_b / 2 (T_b = INFO_LSM_SCORE_WINDOW) (same E[mean mean^T] = S_w / (2 T_b) for white
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

/* entries of a symmetric m x m matrix's upper triangle */
#define BS_PACKED (ID_MAX_REGRESSORS * (ID_MAX_REGRESSORS + 1) / 2)

typedef struct {
    int rows, m;
    int pairs;                    /* m (m + 1) / 2: the entries (first[q], second[q]) of Phi */
    int first[BS_PACKED], second[BS_PACKED];
    double stage_gain_per_second; /* 1 / (T_b / 2) */
    double samples;               /* power updates so far (growing window first) */
    double elapsed;               /* time since bs_init [s] */
    double last_P[ID_MAX_REGRESSORS][ID_MAX_REGRESSORS]; /* the sums at the last block's end */
    double last_theta[ID_MAX_ROWS][ID_MAX_REGRESSORS];
    /* the two stages' means of s (per row) and of Phi (packed) */
    double score_mean[2][ID_MAX_ROWS][ID_MAX_REGRESSORS];
    double info_mean[2][BS_PACKED];  /* Phi's entries, pair by pair */
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
 * for the first 1/gain updates, then with `gain` (an exponential window); gain 0:
 * 1/count always (the mean over all updates).  The window starts empty: its means
 * are divided by the share of their steady-state variance that white scores
 * would have reached, and count once it is half (three quarters of T_b). */
void bs_update_power(BlockScores *bs, double gain);

/* E[mean mean^T] of the scores of `row` at the estimate delta (m x m, full). */
void bs_score_power(const BlockScores *bs, int row, const double delta[],
                    double power[ID_MAX_REGRESSORS][ID_MAX_REGRESSORS]);

#endif
