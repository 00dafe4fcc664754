/* Cost of one sample of the robot pipeline (core/robot_pipeline.c: the
 * model-based observer, the regression of its estimates, the LSM or MFF step
 * over the base columns and the statistics' share), the same function the
 * RobotObserver FMU and the batch runs call (bench/perf/robot_step_cost.py).
 * Usage: robot_step MODEL.txt STEPS [lsm|mff]; MODEL.txt: n, then per joint a line
 * "type ax ay az x y z roll pitch yaw m mx my mz Ixx Ixy Iyy Ixz Iyz Izz fv fc",
 * then p and the p base columns.  The trajectory is a sine per joint at 10 kHz,
 * its torques from the model's inverse dynamics (computed before the clock
 * starts), the settings the FMU's defaults (rp_default_settings) at h = 0.1 ms.
 * Prints nanoseconds per sample. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "robot_pipeline.h"

static int read_model(const char *path, RigidBodyModel *model, int *p, int columns[])
{
    FILE *f = fopen(path, "r");
    if (!f) return -1;
    int n = 0, type[RB_MAX_JOINTS], ok = fscanf(f, "%d", &n) == 1 && n >= 1 && n <= RB_MAX_JOINTS;
    double axis[3 * RB_MAX_JOINTS], xyz[3 * RB_MAX_JOINTS], rpy[3 * RB_MAX_JOINTS];
    double link[10 * RB_MAX_JOINTS], friction[2 * RB_MAX_JOINTS];
    const double gravity[3] = {0.0, 0.0, -9.81};
    for (int i = 0; ok && i < n; ++i) {
        int read = fscanf(f, "%d", &type[i]);
        for (int k = 0; k < 3; ++k) read += fscanf(f, "%lf", &axis[3 * i + k]);
        for (int k = 0; k < 3; ++k) read += fscanf(f, "%lf", &xyz[3 * i + k]);
        for (int k = 0; k < 3; ++k) read += fscanf(f, "%lf", &rpy[3 * i + k]);
        for (int k = 0; k < 10; ++k) read += fscanf(f, "%lf", &link[10 * i + k]);
        for (int k = 0; k < 2; ++k) read += fscanf(f, "%lf", &friction[2 * i + k]);
        ok = read == 22;
    }
    ok = ok && fscanf(f, "%d", p) == 1 && *p >= 1 && *p <= RB_MAX_PARAMETERS;
    for (int k = 0; ok && k < *p; ++k) ok = fscanf(f, "%d", &columns[k]) == 1;
    fclose(f);
    return ok && rb_load(model, n, type, axis, xyz, rpy, link, friction, gravity, 0.0) == RB_OK
               ? 0
               : -1;
}

int main(int argc, char **argv)
{
    if (argc != 3 && argc != 4) return 2;
    const int mff = argc == 4 && strcmp(argv[3], "mff") == 0;
    if (argc == 4 && !mff && strcmp(argv[3], "lsm") != 0) return 2;
    static RigidBodyModel model;
    static RobotObserver observer;
    static RobotRegression regression;
    static RegressorIdentifier identifier;
    static StatisticsJob statistics;
    RobotSettings settings = rp_default_settings(RB_MAX_JOINTS);
    if (read_model(argv[1], &model, &settings.p, settings.columns) != 0) return 2;
    const int n = model.n;
    const long steps = atol(argv[2]);
    if (steps < 1) return 2;
    const double h = 1e-4;
    double *y = malloc((size_t)steps * (size_t)n * sizeof *y);
    double *u = malloc((size_t)steps * (size_t)n * sizeof *u);
    if (!y || !u) return 2;
    for (long k = 0; k < steps; ++k) {
        double q[RB_MAX_JOINTS], qd[RB_MAX_JOINTS], qdd[RB_MAX_JOINTS];
        for (int i = 0; i < n; ++i) {
            const double w = 2.0 * 3.141592653589793 * (0.3 + 0.1 * i), t = (double)k * h;
            q[i] = 0.5 * sin(w * t);
            qd[i] = 0.5 * w * cos(w * t);
            qdd[i] = -0.5 * w * w * sin(w * t);
        }
        memcpy(y + k * n, q, (size_t)n * sizeof *q);
        double friction[RB_MAX_JOINTS];
        rb_inverse_dynamics(&model, q, qd, qdd, 1, u + k * n);
        rb_friction(&model, qd, friction);
        for (int i = 0; i < n; ++i) u[k * n + i] += friction[i];
    }
    settings.n = n;
    settings.h = h;
    settings.identifier = mff ? IDENTIFIER_MFF : IDENTIFIER_LSM;
    const RobotPipeline pipeline = {&observer, &regression, &identifier, &statistics};
    if (rp_init(&pipeline, &model, &settings, y, NULL) != RP_OK) return 2;
    struct timespec start, stop;
    clock_gettime(CLOCK_MONOTONIC, &start);
    rp_run(&pipeline, &model, y, u, n, steps, 0);
    clock_gettime(CLOCK_MONOTONIC, &stop);
    const double ns =
        (double)(stop.tv_sec - start.tv_sec) * 1e9 + (double)(stop.tv_nsec - start.tv_nsec);
    printf("%.1f\n", ns / (double)steps);
    free(y);
    free(u);
    return ri_solve(&identifier) == 0 && observer.model_failures == 0.0 ? 0 : 1;
}
