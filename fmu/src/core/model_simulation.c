/* Runs of a model file's equations (model_simulation.h). */
#include "model_simulation.h"

#include <math.h>

#include "small_solve.h"

/* Which accelerations each entry (i, k) reads, bit j for q''_j: an entry that
 * reads none has the same value at every q'' (the entries are affine in q''), so
 * the mass matrix needs only the others evaluated again. */
typedef struct {
    unsigned reads[TP_MAX_COORDINATES][TP_MAX_PARAMETERS + 1];
} Reads;

static void find_reads(const TermProgram *program, Reads *out)
{
    for (int i = 0; i < program->n; ++i)
        for (int k = 0; k <= program->p; ++k) {
            unsigned bits = 0u;
            const int end = program->start[i][k] + program->length[i][k];
            for (int t = program->start[i][k]; t < end; ++t)
                if (program->op[t] == TP_ACCELERATION) bits |= 1u << program->arg[t];
            out->reads[i][k] = bits;
        }
}

static int accelerations(const TermProgram *program, const Reads *reads, const double theta[],
                         const double q[], const double qd[], const double u[], double qdd[])
{
    const int n = program->n, p = program->p;
    TpSample sample = {{0.0}, {0.0}, {0.0}, {0.0}};
    for (int i = 0; i < n; ++i) {
        sample.q[i] = q[i];
        sample.qd[i] = qd[i];
    }
    for (int j = 0; j < program->m; ++j) sample.u[j] = u[j];
    double Y[TP_MAX_COORDINATES][TP_MAX_PARAMETERS], r[TP_MAX_COORDINATES];
    double M[TP_MAX_COORDINATES][TP_MAX_COORDINATES], b[TP_MAX_COORDINATES];
    tp_evaluate(program, &sample, Y, r);  /* at q'' = 0: b = -(Y theta - r) */
    for (int i = 0; i < n; ++i) {
        double sum = -r[i];
        for (int k = 0; k < p; ++k) sum += Y[i][k] * theta[k];
        b[i] = -sum;
    }
    for (int j = 0; j < n; ++j) {  /* column j of M: the change of Y theta - r as q''_j 0 -> 1 */
        const unsigned bit = 1u << j;
        sample.qdd[j] = 1.0;
        for (int i = 0; i < n; ++i) {
            double change = 0.0;
            for (int k = 0; k < p; ++k)
                if (reads->reads[i][k] & bit)
                    change += (tp_entry(program, &sample, i, k) - Y[i][k]) * theta[k];
            if (reads->reads[i][p] & bit) change -= tp_entry(program, &sample, i, p) - r[i];
            M[i][j] = change;
        }
        sample.qdd[j] = 0.0;
    }
    const int status = small_solve(n, M, b, qdd, 0.0);
    if (status)
        for (int i = 0; i < n; ++i) qdd[i] = NAN;
    return status;
}

int ms_accelerations(const TermProgram *program, const double theta[], const double q[],
                     const double qd[], const double u[], double qdd[])
{
    Reads reads;
    find_reads(program, &reads);
    return accelerations(program, &reads, theta, q, qd, u, qdd);
}

/* One run (model_simulation.h, ms_simulate); u: this run's inputs. */
static long run(const TermProgram *program, const Reads *reads, MsShape shape,
                const double theta[],
                const double q0[], const double qd0[], const double *u, const double limit[],
                double *q_out, double *qd_out)
{
    const int n = program->n, m = program->m;
    const double h = shape.step / shape.parts, half = 0.5 * h, sixth = h / 6.0;
    double q[TP_MAX_COORDINATES], qd[TP_MAX_COORDINATES];
    double a1[TP_MAX_COORDINATES], a2[TP_MAX_COORDINATES], a3[TP_MAX_COORDINATES],
        a4[TP_MAX_COORDINATES];
    double qs[TP_MAX_COORDINATES], vs2[TP_MAX_COORDINATES], vs3[TP_MAX_COORDINATES],
        vs4[TP_MAX_COORDINATES];
    for (int i = 0; i < n; ++i) {
        q[i] = q_out[i] = q0[i];
        qd[i] = qd_out[i] = qd0[i];
    }
    long diverged = -1;
    for (long s = 1; s < shape.samples; ++s) {
        for (int j = 0; j < shape.parts && diverged < 0; ++j) {
            const long i0 = 2 * ((s - 1) * shape.parts + j);
            const double *u0 = u + i0 * m, *um = u0 + m, *u1 = um + m;
            accelerations(program, reads, theta, q, qd, u0, a1);
            for (int i = 0; i < n; ++i) {
                qs[i] = q[i] + half * qd[i];
                vs2[i] = qd[i] + half * a1[i];
            }
            accelerations(program, reads, theta, qs, vs2, um, a2);
            for (int i = 0; i < n; ++i) {
                qs[i] = q[i] + half * vs2[i];
                vs3[i] = qd[i] + half * a2[i];
            }
            accelerations(program, reads, theta, qs, vs3, um, a3);
            for (int i = 0; i < n; ++i) {
                qs[i] = q[i] + h * vs3[i];
                vs4[i] = qd[i] + h * a3[i];
            }
            accelerations(program, reads, theta, qs, vs4, u1, a4);
            for (int i = 0; i < n; ++i) {
                q[i] += sixth * (qd[i] + 2.0 * (vs2[i] + vs3[i]) + vs4[i]);
                qd[i] += sixth * (a1[i] + 2.0 * (a2[i] + a3[i]) + a4[i]);
            }
        }
        double *q_now = q_out + s * n, *qd_now = qd_out + s * n;
        if (diverged < 0)
            for (int i = 0; i < n; ++i)
                if (!(isfinite(q[i]) && isfinite(qd[i]) && fabs(q[i] - q0[i]) <= limit[i]))
                    diverged = s;
        for (int i = 0; i < n; ++i) {  /* held at the last good state once diverged */
            q_now[i] = diverged < 0 ? q[i] : q_now[i - n];
            qd_now[i] = diverged < 0 ? qd[i] : qd_now[i - n];
        }
    }
    return diverged;
}

void ms_simulate(const TermProgram *program, MsShape shape, const double *theta,
                 const double *q0, const double *qd0, const double *u, const double limit[],
                 double *q, double *qd, long *diverged)
{
    const int n = program->n;
    const long inputs = (2L * shape.parts * (shape.samples - 1) + 1) * program->m;
    Reads reads;
    find_reads(program, &reads);
    for (int r = 0; r < shape.runs; ++r)
        diverged[r] = run(program, &reads, shape, theta + (long)r * program->p, q0 + (long)r * n,
                          qd0 + (long)r * n, u + r * inputs, limit, q + r * shape.samples * n,
                          qd + r * shape.samples * n);
}
