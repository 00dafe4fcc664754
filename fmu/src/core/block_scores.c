#include "block_scores.h"

#include <math.h>
#include <string.h>

void bs_init(BlockScores *bs, int rows, int m, double window,
             const double *P, const double *theta)
{
    memset(bs, 0, sizeof *bs);
    bs->rows = rows;
    bs->m = m;
    bs->stage_gain_per_second = 2.0 / window;
    for (int a = 0; a < m; ++a)
        for (int b = a; b < m; ++b) {
            bs->first[bs->pairs] = a;
            bs->second[bs->pairs++] = b;
        }
    memcpy(bs->last_P, P, sizeof bs->last_P);
    memcpy(bs->last_theta, theta, sizeof bs->last_theta);
}

void bs_block(BlockScores *bs, double duration,
              const double *P, const double *theta)
{
    const int m = bs->m;
    const double g = -expm1(-duration * bs->stage_gain_per_second), scale = 1.0 / duration;
    bs->elapsed += duration;
    for (int k = 0; k < bs->pairs; ++k) {
        const int a = bs->first[k], b = bs->second[k];
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
    /* the share of the steady-state variance that two stages of time constant
     * tau reach from rest for white input: 1 - e^-2x (1 + 2x + 2x^2), x = t / tau */
    const double x = bs->elapsed * bs->stage_gain_per_second;
    const double filled = 1.0 - exp(-2.0 * x) * (1.0 + 2.0 * x + 2.0 * x * x);
    if (filled < 0.5) return;
    const double w = bs->samples * gain < 1.0 ? 1.0 / ++bs->samples : gain, c = 1.0 / filled;
    const double *info = bs->info_mean[1];
    const int pairs = bs->pairs;
    for (int p = 0; p < pairs; ++p)
        for (int q = 0; q < pairs; ++q)
            bs->info_power[p][q] += w * (c * info[p] * info[q] - bs->info_power[p][q]);
    for (int i = 0; i < bs->rows; ++i) {
        const double *s = bs->score_mean[1][i];
        for (int a = 0; a < m; ++a) {
            for (int b = 0; b < m; ++b)
                bs->score_power[i][a][b] += w * (c * s[a] * s[b] - bs->score_power[i][a][b]);
            for (int p = 0; p < pairs; ++p)
                bs->cross_power[i][a][p] += w * (c * s[a] * info[p] - bs->cross_power[i][a][p]);
        }
    }
}

/* out[a][j] += sum over the pairs q = (x, y) of in[a][q] times delta at the pair's
 * other index, where j is one of its indices: (Phi delta)_j = sum_q Phi_q delta_other. */
static void contract(const BlockScores *bs, int rows, const double in[][BS_PACKED],
                     const double delta[], double out[][ID_MAX_REGRESSORS])
{
    for (int a = 0; a < rows; ++a)
        for (int q = 0; q < bs->pairs; ++q) {
            const int x = bs->first[q], y = bs->second[q];
            out[a][x] += in[a][q] * delta[y];
            if (x != y) out[a][y] += in[a][q] * delta[x];
        }
}

void bs_score_power(const BlockScores *bs, int row, const double delta[],
                    double power[ID_MAX_REGRESSORS][ID_MAX_REGRESSORS])
{
    const int m = bs->m;
    /* E[s_a (Phi delta)_b]; E[(Phi delta)_a Phi_q], then E[(Phi delta)_a (Phi delta)_b] */
    double cross[ID_MAX_REGRESSORS][ID_MAX_REGRESSORS] = {{0}};
    double half[ID_MAX_REGRESSORS][BS_PACKED] = {{0}}, quadratic[ID_MAX_REGRESSORS][ID_MAX_REGRESSORS] = {{0}};
    contract(bs, m, bs->cross_power[row], delta, cross);
    for (int p = 0; p < bs->pairs; ++p) {
        const int x = bs->first[p], y = bs->second[p];
        for (int q = 0; q < bs->pairs; ++q) {
            half[x][q] += bs->info_power[p][q] * delta[y];
            if (x != y) half[y][q] += bs->info_power[p][q] * delta[x];
        }
    }
    contract(bs, m, (const double(*)[BS_PACKED])half, delta, quadratic);
    for (int a = 0; a < m; ++a)
        for (int b = a; b < m; ++b)
            power[a][b] = power[b][a] =
                bs->score_power[row][a][b] - cross[a][b] - cross[b][a] + quadratic[a][b];
}
