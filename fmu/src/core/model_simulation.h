/* A model file's equations simulated: runs driven by their inputs.
 *
 * The equations of a term program (term_program.h) are affine in the
 * accelerations, so for parameter values theta they read
 *     M(q, theta) q'' = -(Y(q, q', 0, u) theta - r(q, q', 0, u)),
 * column j of M being the change of Y theta - r when q''_j goes from 0 to 1.
 * ms_simulate integrates runs of them with classical Runge-Kutta, `parts`
 * sub-steps per sampling step, the inputs given at every half sub-step.  The
 * values are in the model file's units, as the term program takes them.
 * Plain C, no allocation, no I/O. */
#ifndef MODEL_SIMULATION_H
#define MODEL_SIMULATION_H

#include "term_program.h"

/* q'' at one state (n values each; u: m values; theta: p values).  Returns 0,
 * or -1 when M is singular or a value is not finite (qdd then NaN). */
int ms_accelerations(const TermProgram *program, const double theta[], const double q[],
                     const double qd[], const double u[], double qdd[]);

/* The shapes of a batch of runs. */
typedef struct {
    int runs;
    long samples;  /* per run, the first being the initial state */
    int parts;     /* Runge-Kutta sub-steps per sampling step */
    double step;   /* sampling step [s] */
} MsShape;

/* Runs from q0, qd0 (runs x n), each with its own parameters theta (runs x p)
 * and inputs u (runs x (2 parts (samples - 1) + 1) x m).  Writes q, qd (runs x
 * samples x n).  A run whose position leaves its start by more than limit[i]
 * (or turns non-finite) is held at its last good state from there on, and
 * diverged[run] is that sample's index (-1 for a run that never diverges). */
void ms_simulate(const TermProgram *program, MsShape shape, const double *theta,
                 const double *q0, const double *qd0, const double *u, const double limit[],
                 double *q, double *qd, long *diverged);

#endif
