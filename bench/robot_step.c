/* Cost of one internal step of the robot identifier: the regressor, the nominal
 * torques (Y pi), the weighted regressor and residual through the regression's
 * first-order filter (as robot_observer.c's ro_regression_step) and the LSM (or
 * MFF, R = 0.1) step over the base columns (bench/robot_step_cost.py).
 * Usage: robot_step MODEL.txt STEPS [lsm|mff]; MODEL.txt: n, then per joint a line
 * "type ax ay az x y z roll pitch yaw m mx my mz Ixx Ixy Iyy Ixz Iyz Izz fv fc",
 * then p and the p base columns.  Prints nanoseconds per step. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "regressor_identifier.h"
#include "rigid_body.h"

int main(int argc, char **argv)
{
    if (argc != 3 && argc != 4) return 2;
    const int mff = argc == 4 && strcmp(argv[3], "mff") == 0;
    if (argc == 4 && !mff && strcmp(argv[3], "lsm") != 0) return 2;
    FILE *f = fopen(argv[1], "r");
    if (!f) return 2;
    int n = 0, p = 0, type[RB_MAX_JOINTS], columns[RB_MAX_PARAMETERS];
    double axis[3 * RB_MAX_JOINTS], xyz[3 * RB_MAX_JOINTS], rpy[3 * RB_MAX_JOINTS];
    double link[10 * RB_MAX_JOINTS], friction[2 * RB_MAX_JOINTS];
    const double gravity[3] = {0.0, 0.0, -9.81};
    if (fscanf(f, "%d", &n) != 1 || n < 1 || n > RB_MAX_JOINTS) return 2;
    for (int i = 0; i < n; ++i) {
        int ok = fscanf(f, "%d", &type[i]);
        for (int k = 0; k < 3; ++k) ok += fscanf(f, "%lf", &axis[3 * i + k]);
        for (int k = 0; k < 3; ++k) ok += fscanf(f, "%lf", &xyz[3 * i + k]);
        for (int k = 0; k < 3; ++k) ok += fscanf(f, "%lf", &rpy[3 * i + k]);
        for (int k = 0; k < 10; ++k) ok += fscanf(f, "%lf", &link[10 * i + k]);
        for (int k = 0; k < 2; ++k) ok += fscanf(f, "%lf", &friction[2 * i + k]);
        if (ok != 22) return 2;
    }
    if (fscanf(f, "%d", &p) != 1 || p < 1 || p > RB_MAX_PARAMETERS) return 2;
    for (int k = 0; k < p; ++k)
        if (fscanf(f, "%d", &columns[k]) != 1) return 2;
    fclose(f);
    static RigidBodyModel model;
    static RegressorIdentifier id;
    if (rb_load(&model, n, type, axis, xyz, rpy, link, friction, gravity, 0.0) != RB_OK) return 2;
    if (rri_init(&id, mff ? RRI_MFF : RRI_LSM, n, p, columns, NULL, 1e-4, 1e-6, 0.1) != 0)
        return 2;
    double pi[RB_MAX_PARAMETERS];
    rb_get_parameters(&model, pi);
    const long steps = atol(argv[2]);
    double q[RB_MAX_JOINTS], qd[RB_MAX_JOINTS], qdd[RB_MAX_JOINTS], tau[RB_MAX_JOINTS];
    double z[RB_MAX_JOINTS] = {0}, weight[RB_MAX_JOINTS];
    static RbRegressor Y, filtered; /* filtered: zero-initialized */
    const double gain = 0.18; /* 1 - exp(-h/tau) at h = 1 ms, tau = 5 ms */
    struct timespec start, stop;
    clock_gettime(CLOCK_MONOTONIC, &start);
    for (long s = 0; s < steps; ++s) {
        for (int i = 0; i < n; ++i) {
            const double t = 1e-4 * (double)s;
            q[i] = 0.5 * (i + 1) * t;
            qd[i] = 0.3 + 0.1 * i;
            qdd[i] = 0.2 * i - 0.1 * t;
        }
        rb_regressor(&model, q, qd, qdd, &Y);
        rb_regressor_torque(&model, &Y, pi, tau);
        for (int i = 0; i < n; ++i) {
            weight[i] = (s + i) % 16 ? 1.0 : 0.0; /* some equations left out */
            z[i] += gain * (weight[i] * 0.01 * tau[i] - z[i]);
        }
        rri_filter_regressor(&id, &Y, weight, gain, &filtered);
        rri_step(&id, z, &filtered);
    }
    clock_gettime(CLOCK_MONOTONIC, &stop);
    const double ns = (stop.tv_sec - start.tv_sec) * 1e9 + (stop.tv_nsec - start.tv_nsec);
    printf("%.1f\n", ns / (double)steps);
    return rri_solve(&id) == 0 ? 0 : 1;
}
