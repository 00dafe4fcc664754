/* Pendulum: the paper's plant (section 6) as a bench FMU.
 *
 *   x1' = x2
 *   x2' = u/J - (M g L/(2J)) sin x1 - (Vs/J) x2 - (Ps/J) sign(x2) - d(t) x2 + v(t)
 *
 * J = M L^2; d(t) = d_mean + d_amplitude sin(t/d_period) (section 6.3) or 0;
 * v(t): none, v_amplitude sin(v_frequency t), or v_amplitude sign(sin(2 pi t/v_period)).
 * Classical RK4 at the internal step h with u held over the communication step
 * (v and d are evaluated at the stage times).  The true coefficients and the
 * true perturbation terms are outputs so that a harness can score an observer
 * against them.
 *
 * The state (x1, x2) lives on the layer's grid start + k h.  A communication
 * step that is not a multiple of h ends between two grid points; the outputs
 * then come from one extra RK4 step of the remaining fraction of h, taken from
 * the grid state into the outputs only (the state stays on the grid), so the
 * outputs always describe the pendulum at the end of the communication step. */
#include <float.h>
#include <math.h>
#include <stddef.h>

#include "../../instance/model_interface.h"

#define TWO_PI 6.283185307179586

enum { DAMPING_NONE = 0, DAMPING_TIME_VARYING = 1 };
enum { DISTURBANCE_NONE = 0, DISTURBANCE_SINE = 1, DISTURBANCE_SQUARE = 2 };

typedef struct {
    /* parameters */
    double h, M, g, L, Vs, Ps, theta_start, omega_start;
    int damping;
    double d_mean, d_amplitude, d_period;
    int disturbance;
    double v_amplitude, v_frequency, v_period;
    int max_internal_steps;
    double max_work;
    /* calculated parameters */
    double a_gravity, a_viscous, a_coulomb, b_input, work_per_step;
    /* input */
    double u;
    /* outputs */
    double theta, omega, acceleration, v, d;
    /* state: on the grid, at time t_state */
    double x1, x2, t_state;
} PendulumData;

#define OFF(field) offsetof(PendulumData, field)

static const ModelVariable VARIABLES[] = {
    {.name = "h", .vr = 1, .type = TYPE_REAL, PARAM(.offset = OFF(h), .start = 1e-5, .min = 0.0,
     .max = 1.0, .min_exclusive = true, .unit = "s", .description = "Internal RK4 step")},
    {.name = "M", .vr = 2, .type = TYPE_REAL, PARAM(.offset = OFF(M), .start = 1.1, .min = 0.0,
     .max = NAN, .min_exclusive = true, .unit = "kg", .description = "Pendulum mass")},
    {.name = "g", .vr = 3, .type = TYPE_REAL, PARAM(.offset = OFF(g), .start = 9.815, UNBOUNDED,
     .unit = "m/s2", .description = "Gravity")},
    {.name = "L", .vr = 4, .type = TYPE_REAL, PARAM(.offset = OFF(L), .start = 0.9, .min = 0.0,
     .max = NAN, .min_exclusive = true, .unit = "m", .description = "Arm length (J = M L^2)")},
    {.name = "Vs", .vr = 5, .type = TYPE_REAL, PARAM(.offset = OFF(Vs), .start = 0.18, .min = 0.0,
     .max = NAN, .unit = "N.m.s", .description = "Viscous friction coefficient")},
    {.name = "Ps", .vr = 6, .type = TYPE_REAL, PARAM(.offset = OFF(Ps), .start = 0.45, .min = 0.0,
     .max = NAN, .unit = "N.m", .description = "Coulomb friction coefficient")},
    {.name = "theta_start", .vr = 7, .type = TYPE_REAL, PARAM(.offset = OFF(theta_start),
     .start = 0.1, UNBOUNDED, .unit = "rad", .description = "Initial angle")},
    {.name = "omega_start", .vr = 8, .type = TYPE_REAL, PARAM(.offset = OFF(omega_start),
     .start = 0.5, UNBOUNDED, .unit = "rad/s", .description = "Initial angular velocity")},
    {.name = "damping", .vr = 9, .type = TYPE_INTEGER, PARAM(.offset = OFF(damping), .start = 0,
     .min = 0, .max = 1,
     .description = "0: d = 0; 1: d(t) = d_mean + d_amplitude sin(t / d_period) (paper 6.3)")},
    {.name = "d_mean", .vr = 10, .type = TYPE_REAL, PARAM(.offset = OFF(d_mean), .start = 0.5,
     UNBOUNDED, .unit = "1/s", .description = "Mean of the time-varying damping")},
    {.name = "d_amplitude", .vr = 11, .type = TYPE_REAL, PARAM(.offset = OFF(d_amplitude),
     .start = 0.6, UNBOUNDED, .unit = "1/s",
     .description = "Amplitude of the time-varying damping")},
    {.name = "d_period", .vr = 12, .type = TYPE_REAL, PARAM(.offset = OFF(d_period), .start = 7.0,
     .min = 0.0, .max = NAN, .min_exclusive = true, .unit = "s",
     .description = "Time scale of the damping: sin(t / d_period)")},
    {.name = "disturbance", .vr = 13, .type = TYPE_INTEGER, PARAM(.offset = OFF(disturbance),
     .start = 0, .min = 0, .max = 2,
     .description = "0: none; 1: v_amplitude sin(v_frequency t); 2: v_amplitude "
                    "sign(sin(2 pi t / v_period))")},
    {.name = "v_amplitude", .vr = 14, .type = TYPE_REAL, PARAM(.offset = OFF(v_amplitude),
     .start = 0.5, UNBOUNDED, .unit = "rad/s2", .description = "Disturbance amplitude")},
    {.name = "v_frequency", .vr = 15, .type = TYPE_REAL, PARAM(.offset = OFF(v_frequency),
     .start = 2.0, UNBOUNDED, .unit = "rad/s", .description = "Sine disturbance frequency")},
    {.name = "v_period", .vr = 16, .type = TYPE_REAL, PARAM(.offset = OFF(v_period),
     .start = 6.283185307179586, .min = 0.0, .max = NAN, .min_exclusive = true, .unit = "s",
     .description = "Square-wave disturbance period")},
    {.name = "a_gravity", .vr = 50, .type = TYPE_REAL, CALC(.offset = OFF(a_gravity),
     .unit = "rad/s2", .description = "True M g L / (2 J)")},
    {.name = "a_viscous", .vr = 51, .type = TYPE_REAL, CALC(.offset = OFF(a_viscous),
     .unit = "1/s", .description = "True Vs / J")},
    {.name = "a_coulomb", .vr = 52, .type = TYPE_REAL, CALC(.offset = OFF(a_coulomb),
     .unit = "rad/s2", .description = "True Ps / J")},
    {.name = "b_input", .vr = 53, .type = TYPE_REAL, CALC(.offset = OFF(b_input),
     .description = "True 1 / J [1/(kg.m2)]")},
    {.name = "u", .vr = 100, .type = TYPE_REAL, .causality = CAUSALITY_INPUT,
     .variability = VARIABILITY_CONTINUOUS, UNBOUNDED, .offset = OFF(u), .unit = "N.m",
     .description = "Applied torque, held over each communication step"},
    {.name = "theta", .vr = 200, .type = TYPE_REAL, OUTPUT(.offset = OFF(theta), .unit = "rad",
     .description = "Angle x1")},
    {.name = "omega", .vr = 201, .type = TYPE_REAL, OUTPUT(.offset = OFF(omega), .unit = "rad/s",
     .description = "Angular velocity x2")},
    {.name = "acceleration", .vr = 202, .type = TYPE_REAL, OUTPUT(.offset = OFF(acceleration),
     .unit = "rad/s2", .description = "x2' at the current state and input")},
    {.name = "v", .vr = 203, .type = TYPE_REAL, OUTPUT(.offset = OFF(v), .unit = "rad/s2",
     .description = "Disturbance v(t) now")},
    {.name = "d", .vr = 204, .type = TYPE_REAL, OUTPUT(.offset = OFF(d), .unit = "1/s",
     .description = "Damping coefficient d(t) now")},
    MAX_INTERNAL_STEPS_VARIABLE(OFF(max_internal_steps)),
    WORK_VARIABLES(OFF(max_work), OFF(work_per_step)),
};

static double sign_of(double x) { return (x > 0.0) - (x < 0.0); }

static double damping_at(const PendulumData *p, double t)
{
    return p->damping == DAMPING_TIME_VARYING ? p->d_mean + p->d_amplitude * sin(t / p->d_period)
                                               : 0.0;
}

static double disturbance_at(const PendulumData *p, double t)
{
    switch (p->disturbance) {
    case DISTURBANCE_SINE: return p->v_amplitude * sin(p->v_frequency * t);
    case DISTURBANCE_SQUARE: return p->v_amplitude * sign_of(sin(TWO_PI * t / p->v_period));
    default: return 0.0;
    }
}

/* x2' with the damping d and disturbance v of the stage time. */
static double acceleration_at(const PendulumData *p, double x1, double x2, double d, double v)
{
    return p->b_input * p->u - p->a_gravity * sin(x1) - p->a_viscous * x2 -
           p->a_coulomb * sign_of(x2) - d * x2 + v;
}

/* One classical RK4 step of length dt from (x1, x2) at time t, u held. */
static void rk4(const PendulumData *p, double t, double dt, double x1, double x2, double *x1_out,
                double *x2_out)
{
    const double d0 = damping_at(p, t), v0 = disturbance_at(p, t);
    const double dm = damping_at(p, t + 0.5 * dt), vm = disturbance_at(p, t + 0.5 * dt);
    const double d1 = damping_at(p, t + dt), v1 = disturbance_at(p, t + dt);
    const double k1x = x2, k1v = acceleration_at(p, x1, x2, d0, v0);
    const double k2x = x2 + 0.5 * dt * k1v;
    const double k2v = acceleration_at(p, x1 + 0.5 * dt * k1x, k2x, dm, vm);
    const double k3x = x2 + 0.5 * dt * k2v;
    const double k3v = acceleration_at(p, x1 + 0.5 * dt * k2x, k3x, dm, vm);
    const double k4x = x2 + dt * k3v;
    const double k4v = acceleration_at(p, x1 + dt * k3x, k4x, d1, v1);
    *x1_out = x1 + dt / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x);
    *x2_out = x2 + dt / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
}

/* The outputs at time t >= t_state (t - t_state < h). */
static void update_outputs(PendulumData *p, double t)
{
    const double dt = t - p->t_state;
    if (dt > 1e-6 * p->h) { /* the layer counts a grid point within 1e-6 h as reached */
        rk4(p, p->t_state, dt, p->x1, p->x2, &p->theta, &p->omega);
    } else {
        p->theta = p->x1;
        p->omega = p->x2;
    }
    p->v = disturbance_at(p, t);
    p->d = damping_at(p, t);
    p->acceleration = acceleration_at(p, p->theta, p->omega, p->d, p->v);
}

static ModelStatus initialize(void *data, double start_time, const ModelLogger *log)
{
    (void)log;
    PendulumData *p = data;
    const double J = p->M * p->L * p->L;
    p->a_gravity = p->M * p->g * p->L / (2.0 * J);
    p->a_viscous = p->Vs / J;
    p->a_coulomb = p->Ps / J;
    p->b_input = 1.0 / J;
    p->work_per_step = 150.0; /* one RK4 step: measured up to 100 ns (docs/observer.md, Limits) */
    p->x1 = p->theta_start;
    p->x2 = p->omega_start;
    p->t_state = start_time;
    update_outputs(p, start_time);
    return MODEL_OK;
}

static double internal_step(const void *data) { return ((const PendulumData *)data)->h; }

static double max_work(const void *data) { return ((const PendulumData *)data)->max_work; }

static double work_per_step(const void *data)
{
    return ((const PendulumData *)data)->work_per_step;
}

static uint64_t max_internal_steps(const void *data)
{
    return (uint64_t)((const PendulumData *)data)->max_internal_steps;
}

static void advance(void *data, double start_time, uint64_t k, uint64_t k_end)
{
    PendulumData *p = data;
    for (; k < k_end; ++k) {
        const double t = start_time + (double)k * p->h;
        rk4(p, t, p->h, p->x1, p->x2, &p->x1, &p->x2);
        p->t_state = t + p->h;
    }
}

/* Why the state or outputs are not finite: the first cause found, in the order
 * in which one feeds the next (a non-finite term of the model, then the
 * input, then RK4's stability limit, else the size of the state itself). */
static void explain_divergence(const PendulumData *p, double t, const char *name,
                               const ModelLogger *log)
{
    const double d_bound = fabs(p->d_mean) + fabs(p->d_amplitude);
    if (p->damping == DAMPING_TIME_VARYING && !isfinite(p->d)) {
        log->log(log->context, MODEL_ERROR,
                 "pendulum: the damping d(t) = d_mean + d_amplitude sin(t / d_period) is %g at "
                 "t = %g: t / d_period = %g (d_mean = %g, d_amplitude = %g, d_period = %g); "
                 "d_period is too small or the amplitudes too large for floating point",
                 p->d, t, t / p->d_period, p->d_mean, p->d_amplitude, p->d_period);
    } else if (!(fabs(p->v) < DBL_MAX / 16.0)) { /* RK4 sums 6 such terms */
        log->log(log->context, MODEL_ERROR,
                 "pendulum: the disturbance v(t) is %g at t = %g (disturbance = %d, "
                 "v_amplitude = %g, v_frequency = %g, v_period = %g): its parameters are out "
                 "of floating-point range for RK4",
                 p->v, t, p->disturbance, p->v_amplitude, p->v_frequency, p->v_period);
    } else if (!(fabs(p->b_input * p->u) < DBL_MAX / 16.0)) { /* RK4 sums 6 such terms */
        log->log(log->context, MODEL_ERROR,
                 "pendulum: the input torque u = %g gives u / J = %g at t = %g, too large for "
                 "RK4 in floating point: the input is out of range", p->u, p->b_input * p->u, t);
    } else if (p->h * (p->a_viscous + (p->damping == DAMPING_TIME_VARYING ? d_bound : 0.0)) >
               2.78) {
        const double rate = p->a_viscous + (p->damping == DAMPING_TIME_VARYING ? d_bound : 0.0);
        log->log(log->context, MODEL_ERROR,
                 "pendulum diverged at t = %g: %s is not finite (theta = %g, omega = %g, "
                 "acceleration = %g); RK4 needs h (a_viscous + |d|) below about 2.78, "
                 "here h = %g, a_viscous = %g, |d| <= %g: reduce h below %g or the damping",
                 t, name, p->theta, p->omega, p->acceleration, p->h, p->a_viscous, d_bound,
                 2.78 / rate);
    } else {
        log->log(log->context, MODEL_ERROR,
                 "pendulum diverged at t = %g: %s is not finite (theta = %g, omega = %g, "
                 "acceleration = %g, u = %g): the inputs or parameters drive the state out of "
                 "the floating-point range", t, name, p->theta, p->omega, p->acceleration, p->u);
    }
}

static ModelStatus communication_point(void *data, double t, const ModelLogger *log)
{
    PendulumData *p = data;
    update_outputs(p, t);
    const char *name = !isfinite(p->theta)          ? "theta"
                       : !isfinite(p->omega)        ? "omega"
                       : !isfinite(p->acceleration) ? "acceleration"
                       : !isfinite(p->d)            ? "d"
                       : !isfinite(p->v)            ? "v"
                                                    : NULL;
    if (name) {
        explain_divergence(p, t, name, log);
        return MODEL_ERROR;
    }
    return MODEL_OK;
}

const ModelDescriptor MODEL_DESCRIPTOR = {
    .model_name = "Pendulum",
    .model_identifier = "Pendulum",
    .guid = "{8f6b2c1d-3e4a-4b5c-9d6e-7f8091a2b3c4}",
    .description = "Pendulum with viscous and Coulomb friction, time-varying damping and a "
                   "disturbance (Davila, Fridman, Poznyak 2006, section 6)",
    .variables = VARIABLES,
    .n_variables = sizeof VARIABLES / sizeof VARIABLES[0],
    .data_size = sizeof(PendulumData),
    .default_stop_time = 10.0,
    .default_tolerance = 1e-6,
    .initialize = initialize,
    .internal_step = internal_step,
    .max_internal_steps = max_internal_steps,
    .max_work = max_work,
    .work_per_step = work_per_step,
    .advance = advance,
    .communication_point = communication_point,
};
