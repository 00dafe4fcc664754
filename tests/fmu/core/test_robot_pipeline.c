/* Unit tests of the robot pipeline's set-up (fmu/src/core/robot_pipeline.h): run as
 * `test_robot_pipeline CASE` (check.h). */
#include <math.h>

#include "check.h"

#include "robot_pipeline.h"

static RobotObserver observer;
static RobotRegression regression;
static RegressorIdentifier identifier;
static StatisticsJob statistics;
static const RobotPipeline PIPELINE = {&observer, &regression, &identifier, &statistics};

/* One revolute joint about z, a 1 kg point 0.5 m out, gravity along -y. */
static int load_pendulum(RigidBodyModel *model)
{
    const int type[1] = {RB_REVOLUTE};
    const double axis[3] = {0, 0, 1}, xyz[3] = {0}, rpy[3] = {0};
    const double link[10] = {1.0, 0.5, 0, 0, 0.25, 0, 0.25, 0, 0, 0.25};
    const double friction[2] = {0.1, 0.2}, gravity[3] = {0, -9.81, 0};
    return rb_load(model, 1, type, axis, xyz, rpy, link, friction, gravity, 0.0) == RB_OK ? 0 : 1;
}

static int completes_the_gains_from_the_defaults(void)
{
    static RigidBodyModel model;
    int failed = load_pendulum(&model);
    RobotSettings s = rp_default_settings(1);
    s.identifier = IDENTIFIER_LSM;
    s.p = 2;
    s.columns[0] = 10; /* the joint's viscous and Coulomb friction */
    s.columns[1] = 11;
    const double y0[1] = {0.3};
    const RpProblem problem = rp_init(&PIPELINE, &model, &s, y0, NULL);
    failed += check(problem == RP_OK && observer.alpha1[0] > s.f_plus[0] &&
                        observer.alpha2[0] > 0.0 && observer.x1_hat[0] == 0.3,
                    "the defaults set up (%d): alpha1 %g > f_plus %g, alpha2 %g, at y0", problem,
                    observer.alpha1[0], s.f_plus[0], observer.alpha2[0]);
    failed += check(identifier.p == 2 && identifier.h == s.h && identifier.rho == s.rho,
                    "the identifier has the settings' columns, step and rho (p %d, h %g, rho %g)",
                    identifier.p, identifier.h, identifier.rho);
    return failed;
}

static int names_what_it_refuses(void)
{
    static RigidBodyModel model;
    int failed = load_pendulum(&model), joint = -1;
    const double y0[1] = {0.0};
    RobotSettings s = rp_default_settings(1);
    s.f_plus[0] = 0.0; /* and the gains left at 0: nothing to compute them from */
    RpProblem problem = rp_init(&PIPELINE, &model, &s, y0, &joint);
    failed += check(problem == RP_NO_GAINS && joint == 0, "no gains, joint %d (%d)", joint,
                    problem);
    s = rp_default_settings(1);
    s.min_speed = -1.0;
    problem = rp_init(&PIPELINE, &model, &s, y0, NULL);
    failed += check(problem == RP_BAD_REGRESSION, "a negative min_speed (%d)", problem);
    s = rp_default_settings(1);
    s.identifier = IDENTIFIER_MFF;
    s.p = 1;
    s.R = 1.0;
    problem = rp_init(&PIPELINE, &model, &s, y0, NULL);
    failed += check(problem == RP_BAD_IDENTIFIER, "MFF with R = 1 (%d)", problem);
    return failed;
}

int main(int argc, char **argv)
{
    static const TestCase cases[] = {
        {"completes_the_gains_from_the_defaults", completes_the_gains_from_the_defaults},
        {"names_what_it_refuses", names_what_it_refuses},
    };
    return run_cases("test_robot_pipeline", cases, sizeof cases / sizeof cases[0], argc, argv);
}
