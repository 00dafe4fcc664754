/* The native library's entry points of the term program (core/term_program.h):
 * a model file's regressor, compiled to its text form by harness/model/program.py,
 * evaluated over a whole log by the same C the FMU runs, and its equations
 * simulated (core/model_simulation.h; harness/model/simulation.py), and checked for
 * friction that gives energy (core/model_damping.h). */
#include <stdlib.h>

#include "model_damping.h"
#include "model_simulation.h"
#include "term_program.h"

/* The program of a text, allocated (free it), or NULL with *status -1 for a
 * text tp_parse refuses (its message in error), -2 out of memory. */
static TermProgram *parsed(const char *text, size_t length, char *error, size_t error_size,
                           int *status)
{
    TermProgram *program = malloc(sizeof *program);
    *status = program ? 0 : -2;
    if (program && tp_parse(program, text, length, error, error_size)) {
        free(program);
        program = NULL;
        *status = -1;
    }
    return program;
}

/* q, qd, qdd: samples x n (row-major), u: samples x m; Y: samples x n x p, r:
 * samples x n.  Returns 0, -1 for a text tp_parse refuses (its message in
 * error), -2 out of memory. */
int sto_term_program_evaluate(const char *text, size_t length, long samples,
                                     const double *q, const double *qd, const double *qdd,
                                     const double *u, double *Y, double *r, char *error,
                                     size_t error_size)
{
    int status;
    TermProgram *program = parsed(text, length, error, error_size, &status);
    if (!program) return status;
    const int n = program->n, m = program->m, p = program->p;
    TpSample sample = {{0.0}, {0.0}, {0.0}, {0.0}};
    for (long s = 0; s < samples; ++s) {
        for (int i = 0; i < n; ++i) {
            sample.q[i] = q[s * n + i];
            sample.qd[i] = qd[s * n + i];
            sample.qdd[i] = qdd[s * n + i];
        }
        for (int j = 0; j < m; ++j) sample.u[j] = u[s * m + j];
        for (int i = 0; i < n; ++i) {
            for (int k = 0; k < p; ++k) Y[(s * n + i) * p + k] = tp_entry(program, &sample, i, k);
            r[s * n + i] = tp_entry(program, &sample, i, p);
        }
    }
    free(program);
    return 0;
}

/* Runs of the program's equations (core/model_simulation.h): runs x samples
 * states from q0, qd0 (runs x n), parameters theta (runs x p), inputs u (runs x
 * (2 parts (samples - 1) + 1) x m).  Returns 0, -1 for a text tp_parse refuses
 * (its message in error), -2 out of memory. */
int sto_term_program_simulate(const char *text, size_t length, int runs, long samples,
                              int parts, double step, const double *theta, const double *q0,
                              const double *qd0, const double *u, const double *limit,
                              double *q, double *qd, long *diverged, char *error,
                              size_t error_size)
{
    int status;
    TermProgram *program = parsed(text, length, error, error_size, &status);
    if (!program) return status;
    const MsShape shape = {runs, samples, parts, step};
    ms_simulate(program, shape, theta, q0, qd0, u, limit, q, qd, diverged);
    free(program);
    return 0;
}

/* At each of `samples` states (q: samples x n, u: samples x m), whether the
 * equations with the parameters theta (p) create energy near rest
 * (md_creates_energy: 0, or 1 + the coordinate; -1 where an entry is not
 * finite) into which[samples].  Returns 0, -1 for a text tp_parse refuses (its
 * message in error), -2 out of memory. */
int sto_term_program_energy(const char *text, size_t length, long samples, const double *theta,
                            const double *q, const double *u, int *which, char *error,
                            size_t error_size)
{
    int status;
    TermProgram *program = parsed(text, length, error, error_size, &status);
    if (!program) return status;
    for (long s = 0; s < samples; ++s) {
        MdDamping damping;
        which[s] = md_damping(program, theta, q + s * program->n, u + s * program->m, &damping)
                       ? -1
                       : md_creates_energy(program->n, &damping);
    }
    free(program);
    return 0;
}
