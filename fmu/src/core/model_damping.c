/* The damping of a model file's equations near rest (model_damping.h). */
#include "model_damping.h"

#include <float.h>
#include <math.h>
#include <string.h>

#include "cholesky.h"

#define MD_VELOCITY_STEP 1e-6 /* SI units per second */

/* e = Y theta - r at the sample (q'' = 0); the largest |e_i| into *size. */
static void residuals(const TermProgram *program, const double theta[], const TpSample *s,
                      double e[], double *size)
{
    double Y[TP_MAX_COORDINATES][TP_MAX_PARAMETERS], r[TP_MAX_COORDINATES];
    tp_evaluate(program, s, Y, r);
    for (int i = 0; i < program->n; ++i) {
        e[i] = -r[i];
        for (int k = 0; k < program->p; ++k) e[i] += Y[i][k] * theta[k];
        *size = fmax(*size, fabs(e[i]));
    }
}

int md_damping(const TermProgram *program, const double theta[], const double q[],
               const double u[], MdDamping *out)
{
    const int n = program->n;
    TpSample s = {{0.0}, {0.0}, {0.0}, {0.0}};
    for (int i = 0; i < n; ++i) s.q[i] = q[i];
    for (int j = 0; j < program->m; ++j) s.u[j] = u[j];
    memset(out, 0, sizeof *out);
    for (int j = 0; j < n; ++j) {
        const double v = MD_VELOCITY_STEP / program->coordinate_scale[j];
        double e[2][2][TP_MAX_COORDINATES]; /* [side -, +][v, 2 v] */
        for (int side = 0; side < 2; ++side)
            for (int far = 0; far < 2; ++far) {
                s.qd[j] = (side ? 1.0 : -1.0) * (far ? 2.0 : 1.0) * v;
                residuals(program, theta, &s, e[side][far], &out->size);
            }
        s.qd[j] = 0.0;
        for (int i = 0; i < n; ++i)
            out->D[i][j] = 0.5 * ((e[1][1][i] - e[1][0][i]) + (e[0][0][i] - e[0][1][i])) / v;
        out->coulomb[j] = 0.5 * (e[1][0][j] - e[0][0][j]) - out->D[j][j] * v;
    }
    int finite = isfinite(out->size);
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) finite &= isfinite(out->D[i][j]);
    return finite ? 0 : -1;
}

int md_creates_energy(int n, const MdDamping *damping)
{
    double largest = 0.0;
    int smallest = 0;
    for (int i = 0; i < n; ++i) {
        largest = fmax(largest, fabs(damping->D[i][i]));
        if (damping->D[i][i] < damping->D[smallest][smallest]) smallest = i;
    }
    for (int j = 0; j < n; ++j)
        if (damping->coulomb[j] < -(1e-9 * damping->size + DBL_MIN)) return 1 + j;
    const double tolerance = 1e-9 * largest + DBL_MIN;
    double S[TP_MAX_COORDINATES][TP_MAX_COORDINATES];
    for (int i = 0; i < n; ++i)
        for (int j = i; j < n; ++j)
            S[i][j] = 0.5 * (damping->D[i][j] + damping->D[j][i]) + (i == j ? tolerance : 0.0);
    return cholesky_factor(&S[0][0], &S[0][0], n, TP_MAX_COORDINATES) ? 1 + smallest : 0;
}
