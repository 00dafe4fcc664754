/* The built-in nominal model of a single-DOF joint:
 *     x'' = b u - sum_k c_k psi_k(x1, x2)
 * with the basis psi = [sin x1, x2, sign(x2), x1, 1] (gravity, viscous,
 * Coulomb, spring, constant).  The paper's pendulum is b = 1/J and
 * c = [MgL/(2J), Vs/J, Ps/J, 0, 0].
 *
 * The measured position x1 and the input u are held over a communication
 * step while the velocity estimate x2 changes at every internal step, so the
 * model is split along that line: the position part (with its sin) is
 * evaluated once per communication step, the velocity part every step
 * (st_acceleration). */
#ifndef JOINT_MODEL_H
#define JOINT_MODEL_H

#include <math.h>

#include "super_twisting.h"

#define JOINT_BASIS_SIZE 5
enum { JOINT_SIN = 0, JOINT_VELOCITY = 1, JOINT_VELOCITY_SIGN = 2, JOINT_POSITION = 3,
       JOINT_CONSTANT = 4 };
/* The input u as a regressor (identify_b), after the basis: x'' = b u - c psi
 * enters the injection as + (b - bbar) u. */
#define JOINT_INPUT JOINT_BASIS_SIZE

/* The basis entries that depend on x1 only (the velocity entries are set to 0). */
static inline void jm_position_basis(double x1, double psi[JOINT_BASIS_SIZE])
{
    psi[JOINT_SIN] = sin(x1);
    psi[JOINT_VELOCITY] = 0.0;
    psi[JOINT_VELOCITY_SIGN] = 0.0;
    psi[JOINT_POSITION] = x1;
    psi[JOINT_CONSTANT] = 1.0;
}

/* The acceleration as the observer takes it over a communication step:
 * affine in x2 (viscous and Coulomb terms), the input held over each
 * interval, the position terms a value at the sample (StoAcceleration). */
static inline StoAcceleration jm_acceleration(double b, const double c[JOINT_BASIS_SIZE], double u,
                                                 const double psi[JOINT_BASIS_SIZE])
{
    const StoAcceleration a = {
        .held = b * u,
        .point = -c[JOINT_SIN] * psi[JOINT_SIN] - c[JOINT_POSITION] * psi[JOINT_POSITION] -
                 c[JOINT_CONSTANT] * psi[JOINT_CONSTANT],
        .viscous = c[JOINT_VELOCITY],
        .coulomb = c[JOINT_VELOCITY_SIGN]};
    return a;
}

#endif
