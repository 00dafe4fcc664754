/* Batch entry points over fmu/src/core for the harness (ctypes): the model is an
 * opaque buffer of rn_model_size() bytes that rn_load fills, and every function
 * runs over `count` samples stored row by row (sample k's joint i at k n + i). */
#include <stddef.h>
#include <string.h>

#include "rigid_body.h"

size_t rn_model_size(void) { return sizeof(RigidBodyModel); }

int rn_max_joints(void) { return RB_MAX_JOINTS; }

int rn_load(RigidBodyModel *model, int n, const int type[], const double axis[], const double xyz[],
            const double rpy[], const double link[], const double friction[],
            const double gravity[3], double coulomb_velocity)
{
    return rb_load(model, n, type, axis, xyz, rpy, link, friction, gravity, coulomb_velocity);
}

/* tau = M qdd + C qd + G + friction (with_friction) for each sample. */
void rn_inverse_dynamics(const RigidBodyModel *model, long count, const double q[],
                         const double qd[], const double qdd[], int with_gravity,
                         int with_friction, double tau[])
{
    const int n = model->n;
    for (long k = 0; k < count; ++k) {
        rb_inverse_dynamics(model, q + k * n, qd + k * n, qdd + k * n, with_gravity, tau + k * n);
        if (with_friction) {
            double f[RB_MAX_JOINTS];
            rb_friction(model, qd + k * n, f);
            for (int i = 0; i < n; ++i) tau[k * n + i] += f[i];
        }
    }
}

void rn_gravity(const RigidBodyModel *model, long count, const double q[], double g[])
{
    for (long k = 0; k < count; ++k) rb_gravity(model, q + k * model->n, g + k * model->n);
}

void rn_coriolis(const RigidBodyModel *model, long count, const double q[], const double qd[],
                 double c[])
{
    const int n = model->n;
    for (long k = 0; k < count; ++k) rb_coriolis(model, q + k * n, qd + k * n, c + k * n);
}

/* M of each sample, n x n row-major. */
void rn_mass_matrix(const RigidBodyModel *model, long count, const double q[], double M[])
{
    const int n = model->n;
    for (long k = 0; k < count; ++k) {
        double full[RB_MAX_JOINTS][RB_MAX_JOINTS];
        rb_mass_matrix(model, q + k * n, full);
        for (int i = 0; i < n; ++i) memcpy(M + (k * n + i) * n, full[i], (size_t)n * sizeof(double));
    }
}

/* Returns the number of samples whose M was not positive definite. */
long rn_forward_dynamics(const RigidBodyModel *model, long count, const double q[],
                         const double qd[], const double tau[], double qdd[])
{
    const int n = model->n;
    long failures = 0;
    for (long k = 0; k < count; ++k)
        failures += rb_forward_dynamics(model, q + k * n, qd + k * n, tau + k * n, qdd + k * n) != 0;
    return failures;
}

/* Y of each sample, n x 12n row-major. */
void rn_regressor(const RigidBodyModel *model, long count, const double q[], const double qd[],
                  const double qdd[], double Y[])
{
    const int n = model->n, p = rb_parameter_count(model);
    for (long k = 0; k < count; ++k) {
        double full[RB_MAX_JOINTS][RB_MAX_PARAMETERS];
        rb_regressor(model, q + k * n, qd + k * n, qdd + k * n, full);
        for (int i = 0; i < n; ++i) memcpy(Y + (k * n + i) * p, full[i], (size_t)p * sizeof(double));
    }
}
