/* The built-in nominal model of a single-DOF joint:
 *     x'' = b u - sum_k c_k psi_k(x1, x2)
 * with the basis psi = [sin x1, x2, sign(x2), x1, 1] (gravity, viscous,
 * Coulomb, spring, constant).  The paper's pendulum is b = 1/J and
 * c = [MgL/(2J), Vs/J, Ps/J, 0, 0]. */
#ifndef JOINT_MODEL_H
#define JOINT_MODEL_H

#include <math.h>

#include "super_twisting.h"

#define JOINT_BASIS_SIZE 5

static inline void joint_basis(double x1, double x2, double psi[JOINT_BASIS_SIZE])
{
    psi[0] = sin(x1);
    psi[1] = x2;
    psi[2] = sto_sign(x2);
    psi[3] = x1;
    psi[4] = 1.0;
}

static inline double joint_acceleration(double b, const double c[JOINT_BASIS_SIZE], double u,
                                        const double psi[JOINT_BASIS_SIZE])
{
    double a = b * u;
    for (int k = 0; k < JOINT_BASIS_SIZE; ++k) a -= c[k] * psi[k];
    return a;
}

#endif
