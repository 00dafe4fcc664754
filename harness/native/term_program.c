/* The native library's entry point of the term program (core/term_program.h):
 * a model file's regressor, compiled to its text form by harness/model/program.py,
 * evaluated over a whole log by the same C the FMU runs (harness/model/native.py). */
#include <stdlib.h>

#include "term_program.h"

/* q, qd, qdd: samples x n (row-major), u: samples x m; Y: samples x n x p, r:
 * samples x n.  Returns 0, -1 for a text tp_parse refuses (its message in
 * error), -2 out of memory. */
int sto_term_program_evaluate(const char *text, size_t length, long samples,
                                     const double *q, const double *qd, const double *qdd,
                                     const double *u, double *Y, double *r, char *error,
                                     size_t error_size)
{
    TermProgram *program = malloc(sizeof *program);
    if (!program) return -2;
    if (tp_parse(program, text, length, error, error_size)) {
        free(program);
        return -1;
    }
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
