#include "identifier.h"

#include <math.h>
#include <string.h>

#include "small_loops.h"

_Static_assert(ID_MAX_REGRESSORS == 8, "small_loops.h dispatches m = 1..8");

void identifier_init(Identifier *id, IdentifierKind kind, int rows, int m, double h, double rho,
                     double R)
{
    memset(id, 0, sizeof *id);
    id->kind = kind;
    id->rows = rows;
    id->m = m;
    id->h = h;
    id->h_log_r = kind == IDENTIFIER_MFF ? h * log(R) : 0.0;
    for (int k = 0; k < m; ++k) id->gamma[k][k] = 1.0 / rho;
}

KERNEL euler_step(Identifier *id, const double z[], const double phi[], const int m,
                  const int rows)
{
    const double h = id->h;
    double g[ID_MAX_REGRESSORS]; /* Gamma * phi (= (phi^T Gamma)^T, Gamma symmetric) */
    UNROLL for (int j = 0; j < m; ++j) {
        double sum = 0.0;
        UNROLL for (int k = 0; k < m; ++k) sum += id->gamma[j][k] * phi[k];
        g[j] = sum;
    }
    /* (18)/(37): Delta' = (z - Delta phi) phi^T Gamma */
    for (int i = 0; i < rows; ++i) {
        double prediction = 0.0;
        UNROLL for (int k = 0; k < m; ++k) prediction += id->delta[i][k] * phi[k];
        const double step = h * (z[i] - prediction);
        UNROLL for (int k = 0; k < m; ++k) id->delta[i][k] += step * g[k];
    }
    /* (19)/(36): Gamma' = -Gamma phi phi^T Gamma - ln(R) Gamma; the upper
     * triangle is updated and mirrored so Gamma stays exactly symmetric. */
    const double decay = 1.0 - id->h_log_r;
    UNROLL for (int j = 0; j < m; ++j) {
        UNROLL for (int k = j; k < m; ++k) {
            const double value = decay * id->gamma[j][k] - h * g[j] * g[k];
            id->gamma[j][k] = value;
            id->gamma[k][j] = value;
        }
    }
}

void identifier_step(Identifier *id, const double z[], const double phi[])
{
    const IdSample sample = identifier_sample(id->rows, id->m, z, phi);
    identifier_run(id, &sample, 1);
}

KERNEL euler_run(Identifier *id, const IdSample samples[], int count, const int rows,
                 const int m)
{
    for (int k = 0; k < count; ++k) euler_step(id, samples[k].z, samples[k].phi, m, rows);
}

void identifier_run(Identifier *id, const IdSample samples[], int count)
{
    WITH_CONSTANT_SIZES(id->rows, id->m, euler_run, id, samples, count);
}

double identifier_gamma_trace(const Identifier *id)
{
    double trace = 0.0;
    for (int k = 0; k < id->m; ++k) trace += id->gamma[k][k];
    return trace;
}
