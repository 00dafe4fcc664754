/* TwistingController: the twisting controller (44)/(46) of the paper as a bench FMU.
 *
 *   u = -k1 sign(theta - theta_d) - k2 sign(omega - omega_d)
 *   theta_d = A1 sin(w1 t + p1) + A2 sin(w2 t + p2),  omega_d its derivative
 *
 * A sampled feedback with sample period h.  At initialization, u, theta_d and
 * omega_d are computed for the start time from the inputs set during
 * initialization mode.  Each internal step from t to t + h computes them for
 * t + h from the current inputs (which the master has set to the plant's state
 * at the end of the communication step), so after fmi2DoStep(t, H) the outputs
 * are the control for t + H.  A communication step that is not a multiple of h
 * runs the samples on the grid start + k h only: the outputs are then those of
 * the last sample at or before t + H (a zero-order hold). */
#include <math.h>
#include <stddef.h>

#include "../../instance/model_interface.h"

typedef struct {
    double h, k1, k2, A1, w1, p1, A2, w2, p2; /* parameters */
    int max_internal_steps;
    double max_work, work_per_step;
    double theta, omega;                      /* inputs */
    double u, theta_d, omega_d;               /* outputs */
} ControllerData;

#define OFF(field) offsetof(ControllerData, field)

static const ModelVariable VARIABLES[] = {
    {.name = "h", .vr = 1, .type = TYPE_REAL, PARAM(.offset = OFF(h), .start = 1e-4, .min = 0.0,
     .max = 1.0, .min_exclusive = true, .unit = "s", .description = "Sample period")},
    {.name = "k1", .vr = 2, .type = TYPE_REAL, PARAM(.offset = OFF(k1), .start = 30.0, .min = 0.0,
     .max = NAN, .unit = "N.m", .description = "Gain on sign(theta - theta_d)")},
    {.name = "k2", .vr = 3, .type = TYPE_REAL, PARAM(.offset = OFF(k2), .start = 15.0, .min = 0.0,
     .max = NAN, .unit = "N.m", .description = "Gain on sign(omega - omega_d)")},
    {.name = "A1", .vr = 4, .type = TYPE_REAL, PARAM(.offset = OFF(A1), .start = 0.3, UNBOUNDED,
     .unit = "rad", .description = "Reference: first amplitude")},
    {.name = "w1", .vr = 5, .type = TYPE_REAL, PARAM(.offset = OFF(w1), .start = 3.0, UNBOUNDED,
     .unit = "rad/s", .description = "Reference: first frequency")},
    {.name = "p1", .vr = 6, .type = TYPE_REAL, PARAM(.offset = OFF(p1),
     .start = 0.78539816339744828, UNBOUNDED, .unit = "rad", .description = "Reference: first phase")},
    {.name = "A2", .vr = 7, .type = TYPE_REAL, PARAM(.offset = OFF(A2), .start = 0.3, UNBOUNDED,
     .unit = "rad", .description = "Reference: second amplitude")},
    {.name = "w2", .vr = 8, .type = TYPE_REAL, PARAM(.offset = OFF(w2), .start = 0.5, UNBOUNDED,
     .unit = "rad/s", .description = "Reference: second frequency")},
    {.name = "p2", .vr = 9, .type = TYPE_REAL, PARAM(.offset = OFF(p2),
     .start = 3.1415926535897931, UNBOUNDED, .unit = "rad", .description = "Reference: second phase")},
    {.name = "theta", .vr = 100, .type = TYPE_REAL, INPUT(.offset = OFF(theta), .unit = "rad",
     .description = "Measured angle")},
    {.name = "omega", .vr = 101, .type = TYPE_REAL, INPUT(.offset = OFF(omega), .unit = "rad/s",
     .description = "Measured angular velocity")},
    {.name = "u", .vr = 200, .type = TYPE_REAL, OUTPUT(.offset = OFF(u), .unit = "N.m",
     .description = "Control torque")},
    {.name = "theta_d", .vr = 201, .type = TYPE_REAL, OUTPUT(.offset = OFF(theta_d), .unit = "rad",
     .description = "Reference angle")},
    {.name = "omega_d", .vr = 202, .type = TYPE_REAL, OUTPUT(.offset = OFF(omega_d),
     .unit = "rad/s", .description = "Reference angular velocity (analytic derivative)")},
    MAX_INTERNAL_STEPS_VARIABLE(OFF(max_internal_steps)),
    WORK_VARIABLES(OFF(max_work), OFF(work_per_step)),
};

static double sign_of(double x) { return (x > 0.0) - (x < 0.0); }

static void control(ControllerData *c, double t)
{
    c->theta_d = c->A1 * sin(c->w1 * t + c->p1) + c->A2 * sin(c->w2 * t + c->p2);
    c->omega_d = c->A1 * c->w1 * cos(c->w1 * t + c->p1) + c->A2 * c->w2 * cos(c->w2 * t + c->p2);
    c->u = -c->k1 * sign_of(c->theta - c->theta_d) - c->k2 * sign_of(c->omega - c->omega_d);
}

static ModelStatus initialize(void *data, double start_time, const ModelLogger *log)
{
    (void)log;
    /* only the last internal step's sample is computed (advance): no work per step */
    ((ControllerData *)data)->work_per_step = 0.0;
    control(data, start_time);
    return MODEL_OK;
}

static double internal_step(const void *data) { return ((const ControllerData *)data)->h; }

static double max_work(const void *data) { return ((const ControllerData *)data)->max_work; }

static double work_per_step(const void *data)
{
    return ((const ControllerData *)data)->work_per_step;
}

/* The control law is a function of the time and the held inputs: only the
 * last internal step's sample is ever seen. */
static void advance(void *data, double start_time, uint64_t k_first, uint64_t k_end)
{
    ControllerData *c = data;
    if (k_end == k_first) return; /* no sample in this step: the output is held */
    control(c, start_time + (double)(k_end - 1) * c->h + c->h);
}

static uint64_t max_internal_steps(const void *data)
{
    return (uint64_t)((const ControllerData *)data)->max_internal_steps;
}

static ModelStatus communication_point(void *data, double t, const ModelLogger *log)
{
    (void)data, (void)t, (void)log;
    return MODEL_OK; /* outputs are bounded by k1 + k2 and the reference amplitudes */
}

const ModelDescriptor MODEL_DESCRIPTOR = {
    .model_name = "TwistingController",
    .model_identifier = "TwistingController",
    .guid = "{2a9d4e6f-1b3c-4d5e-8f70-a1b2c3d4e5f6}",
    .description = "Twisting controller (44)/(46) tracking theta_d = A1 sin(w1 t + p1) + "
                   "A2 sin(w2 t + p2) (Davila, Fridman, Poznyak 2006)",
    .variables = VARIABLES,
    .n_variables = sizeof VARIABLES / sizeof VARIABLES[0],
    .data_size = sizeof(ControllerData),
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
