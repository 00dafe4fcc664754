/* Whether a model file's equations, at given parameter values, create energy.
 * The power a passive machine's friction takes is never negative, so near rest
 * (q'' = 0, e = Y(q, q', q'', u) theta - r in the equations' force units):
 * - the damping D_ij = d e_i / d q'_j must have a positive semidefinite
 *   symmetric part (a negative viscous friction breaks it), and
 * - the Coulomb level c_j, the half-jump of e_j across q'_j = 0, must not be
 *   negative (a friction force that pushes along the motion).
 * A model that breaks either has a free response that grows: an unstable model
 * that no machine has.  An unstable equilibrium (an inverted pendulum: a
 * negative stiffness) is physics and is not what this checks.
 * D is a secant between the velocities v and 2 v on each side of rest,
 * averaged (a term in sign(q') cancels in it, a viscous term is exact, terms
 * quadratic in q' such as Coriolis or drag add 3 v times their coefficient,
 * negligible at v = 1e-6 SI units); c_j is (e_j(v) - e_j(-v)) / 2 - D_jj v.
 * Plain C, no allocation, no I/O. */
#ifndef MODEL_DAMPING_H
#define MODEL_DAMPING_H

#include "term_program.h"

typedef struct {
    double D[TP_MAX_COORDINATES][TP_MAX_COORDINATES]; /* per unit of the velocities */
    double coulomb[TP_MAX_COORDINATES];
    double size;  /* the largest |e_i| met: the yardstick of rounding */
} MdDamping;

/* At the positions q and inputs u (the program's units) for the parameters
 * theta (the file's units).  Returns 0, or -1 if an entry is not finite. */
int md_damping(const TermProgram *program, const double theta[], const double q[],
               const double u[], MdDamping *out);

/* 0 if the equations take energy (within rounding: 1e-9 of D's largest
 * diagonal entry, of the largest |e|); else 1 + the coordinate whose damping
 * (the smallest diagonal entry when sym(D) fails) or Coulomb level is negative. */
int md_creates_energy(int n, const MdDamping *damping);

#endif
