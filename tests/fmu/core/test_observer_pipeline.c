/* Unit tests of the observer/identifier pipeline
 * (fmu/src/core/observer_pipeline.h): run as `test_observer_pipeline CASE`
 * (check.h). */
#include <math.h>
#include <stdint.h>
#include <stdlib.h>

#include "check.h"

#include "gains.h"
#include "observer_pipeline.h"

/* ---- the observer/identifier pipeline (observer_pipeline.h) ------------------------ */

/* The paper's joint x'' = b u - c1 sin x - c2 x' under a held multi-sine torque,
 * integrated by RK4 (ten sub-steps a sample); the pipeline starts from c guessed
 * 30 % off and must identify c1 and c2 (default scheme, LSM, model feedback). */
static double joint_acceleration_true(double x, double v, double u)
{
    return u - 9.0 * sin(x) - 0.4 * v;
}

static int pipeline_identifies_a_joint(void)
{
    const double h = 1e-3, t_end = 30.0;
    ObserverPipeline *p = calloc(1, sizeof *p);
    ObserverEstimates out;
    ObserverInputs in = {.y = {0.0}, .u = 0.0};
    p->h = h;
    p->n = 1;
    p->nominal_model = OP_NOMINAL_JOINT;
    p->scheme = STO_SCHEME_ADAPTIVE;
    p->identifier = IDENTIFIER_LSM;
    p->tau = 0.002;
    p->b = 1.0;
    p->c_nominal[0] = 0.7 * 9.0;
    p->c_nominal[1] = 1.3 * 0.4;
    p->rho = 1e-3;
    p->R = 0.1;
    p->identify[0] = p->identify[1] = 1;
    p->identifier_form = OP_FORM_INFORMATION;
    p->identifier_start = OP_START_WHEN_CONVERGED;
    p->filter_regressor = 1;
    p->convergence_window = 0.05;
    p->tau_identifier = 0.1;
    p->model_feedback = 1;
    const int m = op_select(p);
    int failed = check(m == 2, "two regressors selected (m = %d)", m);
    double a1[1] = {0.0}, a2[1] = {0.0}, zero[1] = {0.0};
    gains_complete(20.0, 0.5, &a1[0], &a2[0]);
    failed += check(op_init(p, a1, a2, zero, zero, &in, &out, NULL) == 0, "the pipeline starts");
    double x = 0.0, v = 0.0, max_error = 0.0, sum = 0.0;
    long counted = 0;
    const long samples = (long)(t_end / h + 0.5);
    for (long k = 0; k < samples; ++k) {
        const double t = k * h;
        in.y[0] = x;
        in.u = 3.0 * sin(2.1 * t) + 2.0 * sin(5.3 * t + 1.0) + 1.5 * sin(0.7 * t);
        op_run(p, &in, 0.0, (uint64_t)k, (uint64_t)k + 1, 0);
        op_communicate(p, &out);
        const double x2_hat = p->obs.x2_hat[0]; /* the prediction for the next sample */
        const double dt = h / 10.0;
        for (int s = 0; s < 10; ++s) { /* RK4 with the torque held over the sample */
            const double k1x = v, k1v = joint_acceleration_true(x, v, in.u);
            const double k2x = v + 0.5 * dt * k1v,
                         k2v = joint_acceleration_true(x + 0.5 * dt * k1x, k2x, in.u);
            const double k3x = v + 0.5 * dt * k2v,
                         k3v = joint_acceleration_true(x + 0.5 * dt * k2x, k3x, in.u);
            const double k4x = v + dt * k3v, k4v = joint_acceleration_true(x + dt * k3x, k4x, in.u);
            x += dt / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x);
            v += dt / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
        }
        if (t > 5.0) {
            const double e = fabs(x2_hat - v);
            max_error = fmax(max_error, e);
            sum += e * e;
            ++counted;
        }
    }
    op_publish(p, &out); /* the estimates are derived when read */
    const double c1 = out.theta_hat[0][0], c2 = out.theta_hat[0][1];
    failed += check(out.identifier_active && out.converged, "identifying and converged at %g s",
                    t_end);
    failed += check(fabs(c1 / 9.0 - 1.0) < 1e-3, "c1 = %.6f (true 9, nominal 6.3): error %.2e < 1e-3",
                    c1, fabs(c1 / 9.0 - 1.0));
    failed += check(fabs(c2 / 0.4 - 1.0) < 1e-3, "c2 = %.6f (true 0.4, nominal 0.52): error %.2e < 1e-3",
                    c2, fabs(c2 / 0.4 - 1.0));
    failed += check(out.theta_std[0][0] > 0.0 && out.theta_std[0][0] < 0.05,
                    "standard error of c1 %.2e in (0, 0.05)", out.theta_std[0][0]);
    failed += check(sqrt(sum / counted) < 3e-5, "velocity RMS after 5 s %.2e < 3e-5 (max %.2e)",
                    sqrt(sum / counted), max_error);
    /* a restart forgets the estimate: one sample later it is back near the nominal */
    op_run(p, &in, 0.0, (uint64_t)samples, (uint64_t)samples + 1, 1);
    op_communicate(p, &out);
    op_publish(p, &out);
    failed += check(fabs(out.theta_hat[0][0] - p->c_nominal[0]) < 1e-2,
                    "one sample after a restart c1 = %.6f, within 1e-2 of the nominal %.6f",
                    out.theta_hat[0][0], p->c_nominal[0]);
    free(p);
    return failed;
}

int main(int argc, char **argv)
{
    static const TestCase cases[] = {
        {"pipeline_identifies_a_joint", pipeline_identifies_a_joint},
    };
    return run_cases("test_observer_pipeline", cases, sizeof cases / sizeof cases[0], argc, argv);
}
