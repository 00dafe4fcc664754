#include "block_scores.h"

#include <math.h>
#include <string.h>

/* Index of entry (a, b), a <= b, of a packed symmetric matrix (fixed layout). */
static int packed(int a, int b)
{
    if (a > b) {
        const int t = a;
        a = b;
        b = t;
    }
    return a * (2 * ID_MAX_REGRESSORS - a + 1) / 2 + (b - a);
}

void bs_init(BlockScores *bs, int rows, int m, double window,
             const double *P, const double *theta)
{
    memset(bs, 0, sizeof *bs);
    bs->rows = rows;
    bs->m = m;
    bs->stage_gain_per_second = 2.0 / window;
    memcpy(bs->last_P, P, sizeof bs->last_P);
    memcpy(bs->last_theta, theta, sizeof bs->last_theta);
}

void bs_block(BlockScores *bs, double duration,
              const double *P, const double *theta)
{
    const int m = bs->m;
    const double g = -expm1(-duration * bs->stage_gain_per_second), scale = 1.0 / duration;
    for (int a = 0; a < m; ++a)
        for (int b = a; b < m; ++b) {
            const int k = packed(a, b);
            const double mean = (P[a * ID_MAX_REGRESSORS + b] - bs->last_P[a][b]) * scale;
            bs->info_mean[0][k] += g * (mean - bs->info_mean[0][k]);
            bs->info_mean[1][k] += g * (bs->info_mean[0][k] - bs->info_mean[1][k]);
        }
    for (int i = 0; i < bs->rows; ++i)
        for (int a = 0; a < m; ++a) {
            const double mean = (theta[i * ID_MAX_REGRESSORS + a] - bs->last_theta[i][a]) * scale;
            bs->score_mean[0][i][a] += g * (mean - bs->score_mean[0][i][a]);
            bs->score_mean[1][i][a] += g * (bs->score_mean[0][i][a] - bs->score_mean[1][i][a]);
        }
    memcpy(bs->last_P, P, sizeof bs->last_P);
    memcpy(bs->last_theta, theta, sizeof bs->last_theta);
}

void bs_update_power(BlockScores *bs, double gain)
{
    const int m = bs->m;
    const double w = bs->samples * gain < 1.0 ? 1.0 / ++bs->samples : gain;
    const double *info = bs->info_mean[1];
    for (int x = 0; x < m; ++x)
        for (int y = x; y < m; ++y) {
            const int p = packed(x, y);
            for (int a = 0; a < m; ++a)
                for (int b = a; b < m; ++b) {
                    const int q = packed(a, b);
                    bs->info_power[p][q] += w * (info[p] * info[q] - bs->info_power[p][q]);
                }
        }
    for (int i = 0; i < bs->rows; ++i) {
        const double *s = bs->score_mean[1][i];
        for (int a = 0; a < m; ++a) {
            for (int b = 0; b < m; ++b)
                bs->score_power[i][a][b] += w * (s[a] * s[b] - bs->score_power[i][a][b]);
            for (int x = 0; x < m; ++x)
                for (int y = x; y < m; ++y) {
                    const int p = packed(x, y);
                    bs->cross_power[i][a][p] += w * (s[a] * info[p] - bs->cross_power[i][a][p]);
                }
        }
    }
}

void bs_score_power(const BlockScores *bs, int row, const double delta[],
                    double power[ID_MAX_REGRESSORS][ID_MAX_REGRESSORS])
{
    const int m = bs->m;
    /* E[s (Phi delta)_b] and E[(Phi delta)_a (Phi delta)_b] */
    double cross[ID_MAX_REGRESSORS][ID_MAX_REGRESSORS] = {{0}};
    for (int a = 0; a < m; ++a)
        for (int b = 0; b < m; ++b)
            for (int c = 0; c < m; ++c) cross[a][b] += bs->cross_power[row][a][packed(b, c)] * delta[c];
    for (int a = 0; a < m; ++a)
        for (int b = a; b < m; ++b) {
            double quadratic = 0.0;
            for (int c = 0; c < m; ++c) {
                double inner = 0.0;
                for (int d = 0; d < m; ++d) inner += bs->info_power[packed(a, c)][packed(b, d)] * delta[d];
                quadratic += delta[c] * inner;
            }
            power[a][b] = power[b][a] =
                bs->score_power[row][a][b] - cross[a][b] - cross[b][a] + quadratic;
        }
}
