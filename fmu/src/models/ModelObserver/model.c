/* ModelObserver: the observer and identifier FMU of any mechanical system
 * declared in a model file (core/model_pipeline.h), whose equations reach it
 * as data: resources/model.txt, the term program (core/term_program.h) that
 * `sto-harness fmu --model` writes beside a modelDescription.xml naming the
 * model's coordinates, inputs and parameters.  One binary serves every model
 * file; the variables are generic scalars (position_1, theta_3, ...) that the
 * generated modelDescription renames, and those a model does not use stay 0.
 * Value references are stable (docs/fmu.md). */
#include <math.h>
#include <stddef.h>
#include <string.h>

#include "../../core/gains.h"
#include "../../core/model_damping.h"
#include "../../core/model_pipeline.h"
#include "../../core/term_program.h"
#include "../../instance/model_interface.h"
#include "../fixed_lag_outputs.h"
#include "../input_cadence_outputs.h"
#include "../state_fields.h"

#define MAX_N MP_MAX_COORDINATES
#define MAX_U TP_MAX_INPUTS
#define MAX_P TP_MAX_PARAMETERS
#define GAINS_P 0.5 /* p of condition (6) for the gains of Theorem 3.1 */
#define F_PLUS_SI 10.0 /* default bound of the acceleration error [SI units per s^2] */

typedef struct {
    TermProgram program; /* the resource region: the model file, as read at instantiation */
    ModelPipeline pipe;  /* its configuration holds most parameters */
    double f_plus[MAX_N];
    int max_internal_steps;
    double max_work;
    double work_per_step;
    double input_period;
    double alpha1[MAX_N], alpha2[MAX_N]; /* from f_plus by Theorem 3.1 */
    /* inputs */
    double y[MAX_N], u[MAX_U];
    int identifier_reset;
    int reset_seen;
    InputCadence cadence; /* of the positions and inputs */
    int coarse_logged;    /* the staircase warning stands */
    /* outputs */
    double position[MAX_N], velocity[MAX_N], theta[MAX_P], theta_std[MAX_P];
    double excitation, input_hold, identifier_cutoff;
    int converged, identifier_active, coarse_inputs;
    int parameters_held;  /* held at an end of their declared range */
    int held_logged;      /* the count the last message said */
    int held_seen;        /* the count at the last communication point ... */
    double held_since;    /* [s] ... since this time */
    int held[MAX_P];      /* per parameter -1, 0, 1 (box_projection.h) */
    double theta_excitation[MAX_P]; /* per parameter (statistics_job.h) */
    int parameters_not_excited; /* column excitation below MP_NOT_EXCITED */
    int weak_logged, weak_seen; /* as held_logged, held_seen, held_since */
    double weak_since;
    int negative_damping; /* the published model creates energy (model_damping.h) */
    int damping_logged;   /* the warning stands */
    int energy_seen;      /* it did at the last communication point ... */
    double energy_since;  /* [s] ... since this time */
} ModelData;
_Static_assert(MAX_N + MAX_U <= IC_MAX_VALUES, "the cadence watches every position and input");

#define OFF(field) offsetof(ModelData, field)

/* One generic scalar per element: the generated modelDescription renames them. */
#define ELEMENT(kind, base, vr0, field, unit_, text, i) \
    {.name = base "_" #i, .vr = (vr0) + (i) - 1, .type = TYPE_REAL,                              \
     kind(.offset = OFF(field) + ((i) - 1) * sizeof(double), .unit = unit_, .description = text)}
#define SEVEN(kind, base, vr0, field, unit, text)                                                \
    ELEMENT(kind, base, vr0, field[0], unit, text, 1), ELEMENT(kind, base, vr0, field[0], unit, text, 2), \
    ELEMENT(kind, base, vr0, field[0], unit, text, 3), ELEMENT(kind, base, vr0, field[0], unit, text, 4), \
    ELEMENT(kind, base, vr0, field[0], unit, text, 5), ELEMENT(kind, base, vr0, field[0], unit, text, 6), \
    ELEMENT(kind, base, vr0, field[0], unit, text, 7)
#define THIRTY_TWO(kind, base, vr0, field, text)                                                 \
    ELEMENTS_32(ELEMENT, kind, base, vr0, field[0], NULL, text)
/* The 32 elements with literal indices (their names are made by stringizing). */
#define ELEMENTS_32(E, ...)                                                                      \
    E(__VA_ARGS__, 1), E(__VA_ARGS__, 2), E(__VA_ARGS__, 3), E(__VA_ARGS__, 4),                  \
    E(__VA_ARGS__, 5), E(__VA_ARGS__, 6), E(__VA_ARGS__, 7), E(__VA_ARGS__, 8),                  \
    E(__VA_ARGS__, 9), E(__VA_ARGS__, 10), E(__VA_ARGS__, 11), E(__VA_ARGS__, 12),               \
    E(__VA_ARGS__, 13), E(__VA_ARGS__, 14), E(__VA_ARGS__, 15), E(__VA_ARGS__, 16),              \
    E(__VA_ARGS__, 17), E(__VA_ARGS__, 18), E(__VA_ARGS__, 19), E(__VA_ARGS__, 20),              \
    E(__VA_ARGS__, 21), E(__VA_ARGS__, 22), E(__VA_ARGS__, 23), E(__VA_ARGS__, 24),              \
    E(__VA_ARGS__, 25), E(__VA_ARGS__, 26), E(__VA_ARGS__, 27), E(__VA_ARGS__, 28),              \
    E(__VA_ARGS__, 29), E(__VA_ARGS__, 30), E(__VA_ARGS__, 31), E(__VA_ARGS__, 32)
#define F_PLUS(i)                                                                                \
    {.name = "f_plus_" #i, .vr = 17 + (i), .type = TYPE_REAL,                                     \
     PARAM(.offset = OFF(f_plus) + ((i) - 1) * sizeof(double), .start = F_PLUS_SI, .min = 0.0,    \
           .max = NAN, .min_exclusive = true,                                                     \
           .description = "Bound of the nominal model's acceleration error of coordinate " #i    \
                          " (its unit per s^2; default 10 m/s^2 or rad/s^2 in that unit): the " \
                          "super-twisting gains by Theorem 3.1")}
#define INPUT_ELEMENT(i)                                                                         \
    {.name = "input_" #i, .vr = 209 + (i), .type = TYPE_REAL,                                     \
     INPUT(.offset = OFF(u) + ((i) - 1) * sizeof(double), .description = "Known input " #i)}

static const ModelVariable VARIABLES[] = {
    {.name = "h", .vr = 1, .type = TYPE_REAL, PARAM(.offset = OFF(pipe.h), .start = 1e-3,
     .min = 0.0, .max = 1.0, .min_exclusive = true, .unit = "s",
     .description = "Fixed internal step of the observer and identifier (the log's sample "
                    "period: one internal step per sample)")},
    {.name = "nominal_model", .vr = 3, .type = TYPE_BOOLEAN,
     PARAM(.offset = OFF(pipe.nominal_model), .start = 1, UNBOUNDED,
     .description = "The observer predicts with the model's equations at the nominal "
                    "parameters (false: no model, the injection carries the acceleration)")},
    {.name = "scheme", .vr = 4, .type = TYPE_INTEGER, PARAM(.offset = OFF(pipe.scheme),
     .start = STO_SCHEME_ADAPTIVE, .min = 2, .max = 3,
     .description = "2: the implicit super-twisting observer; 3: beside it, linear observers "
                    "that adapt to the measurement noise (the velocity of the one that fits)")},
    {.name = "identifier", .vr = 5, .type = TYPE_INTEGER, PARAM(.offset = OFF(pipe.identifier),
     .start = IDENTIFIER_LSM, .min = 0, .max = 2,
     .description = "Parameter identifier: 0 off, 1 least squares (constant parameters), "
                    "2 matrix forgetting factor (time-varying)")},
    {.name = "statistics_interval", .vr = 11, .type = TYPE_REAL,
     PARAM(.offset = OFF(pipe.statistics_interval), .start = 0.1, .min = 0.0, .max = NAN,
     .unit = "s", .description = "Time between the solves of the standard errors (their "
                                 "p^3 work spread over the internal steps after each)")},
    F_PLUS(1), F_PLUS(2), F_PLUS(3), F_PLUS(4), F_PLUS(5), F_PLUS(6), F_PLUS(7),
    {.name = "t_id", .vr = 80, .type = TYPE_REAL, PARAM(.offset = OFF(pipe.t_id), .start = 0.0,
     UNBOUNDED, .unit = "s",
     .description = "Earliest time at which identification starts (once the observer has "
                    "converged)")},
    {.name = "rho", .vr = 81, .type = TYPE_REAL, PARAM(.offset = OFF(pipe.rho), .start = MP_RHO,
     .min = 0.0, .max = NAN, .min_exclusive = true,
     .description = "Regularization of the parameters in SI units: the information starts "
                    "at rho I")},
    {.name = "R", .vr = 82, .type = TYPE_REAL, PARAM(.offset = OFF(pipe.R), .start = 0.1,
     .min = 0.0, .max = 1.0, .min_exclusive = true, .max_exclusive = true,
     .description = "MFF forgetting factor per second (weight R^(t - s))")},
    {.name = "tau_identifier", .vr = 116, .type = TYPE_REAL,
     PARAM(.offset = OFF(pipe.tau_identifier), .start = MP_TAU_IDENTIFIER, .min = 0.0,
     .max = NAN, .unit = "s",
     .description = "Time constant of the filter on every entry of the equations before the "
                    "identifier (0: none)")},
    {.name = "regression", .vr = 117, .type = TYPE_INTEGER,
     PARAM(.offset = OFF(pipe.regression), .start = MP_REGRESSION_WINDOW, .min = 0, .max = 1,
     .description = "What the identifier regresses on: 1 the positions smoothed by a "
                    "zero-phase window a fixed lag behind the newest sample, its cut-off "
                    "chosen from the measurement noise (identifier_cutoff); 0 the observer's "
                    "causal velocity estimates (the paper's scheme)")},
    MAX_INTERNAL_STEPS_VARIABLE(OFF(max_internal_steps)),
    WORK_VARIABLES(OFF(max_work), OFF(work_per_step)),
    SEVEN(INPUT, "position", 200, y, NULL, "Measured coordinate"),
    INPUT_ELEMENT(1), INPUT_ELEMENT(2), INPUT_ELEMENT(3), INPUT_ELEMENT(4), INPUT_ELEMENT(5),
    INPUT_ELEMENT(6), INPUT_ELEMENT(7),
    {.name = "identifier_reset", .vr = 220, .type = TYPE_BOOLEAN,
     .causality = CAUSALITY_INPUT, .variability = VARIABILITY_DISCRETE, UNBOUNDED,
     .offset = OFF(identifier_reset),
     .description = "A rising edge restarts identification from the nominal parameters"},
    SEVEN(OUTPUT, "position_estimate", 300, position, NULL, "Position estimate"),
    SEVEN(OUTPUT, "velocity", 310, velocity, NULL, "Velocity estimate"),
    THIRTY_TWO(OUTPUT, "theta", 400, theta, "Parameter estimate (the model file's unit)"),
    THIRTY_TWO(OUTPUT, "theta_std", 440, theta_std, "Standard error of the parameter estimate"),
    THIRTY_TWO(OUTPUT, "theta_excitation", 480, theta_excitation,
               "Share of the parameter's regressor column that the others do not explain, "
               "sqrt(1 - R^2) of the identifier's information: 0 (not excited, or a "
               "combination of the others) to 1 (orthogonal); below 0.001 its estimate is "
               "not determined by the log. 0 until the first solve"),
    {.name = "identifier_active", .vr = 361, .type = TYPE_BOOLEAN,
     .causality = CAUSALITY_OUTPUT, .variability = VARIABILITY_DISCRETE, UNBOUNDED,
     .offset = OFF(identifier_active), .description = "The identifier is integrating"},
    {.name = "converged", .vr = 362, .type = TYPE_BOOLEAN,
     .causality = CAUSALITY_OUTPUT, .variability = VARIABILITY_DISCRETE, UNBOUNDED,
     .offset = OFF(converged),
     .description = "The observer is in its sliding mode by the switching-rate test"},
    {.name = "excitation", .vr = 363, .type = TYPE_REAL,
     OUTPUT(.offset = OFF(excitation),
     .description = "Smallest eigenvalue of the identifier's information per unit time (SI "
                    "parameters); near 0: some parameter is not being learned")},
    INPUT_CADENCE_VARIABLES(364, OFF(input_hold), OFF(coarse_inputs), OFF(input_period)),
    {.name = "parameters_held", .vr = 367, .type = TYPE_INTEGER,
     .causality = CAUSALITY_OUTPUT, .variability = VARIABILITY_DISCRETE, UNBOUNDED,
     .offset = OFF(parameters_held),
     .description = "Parameters the estimate holds at an end of the range the model file "
                    "declares (positive = true, range = [a, b]): the identifier's least "
                    "squares lie outside it; their theta_std is 0. 0 without ranges"},
    {.name = "parameters_not_excited", .vr = 370, .type = TYPE_INTEGER,
     .causality = CAUSALITY_OUTPUT, .variability = VARIABILITY_DISCRETE, UNBOUNDED,
     .offset = OFF(parameters_not_excited),
     .description = "Parameters whose theta_excitation is below 0.001 while the identifier "
                    "runs: the log so far does not tell them from the others (their estimates "
                    "and theta_std mean little). 0 before the first solve"},
    IDENTIFIER_CUTOFF_VARIABLE(369, OFF(identifier_cutoff)),
    {.name = "negative_damping", .vr = 368, .type = TYPE_BOOLEAN,
     .causality = CAUSALITY_OUTPUT, .variability = VARIABILITY_DISCRETE, UNBOUNDED,
     .offset = OFF(negative_damping),
     .description = "The estimated model creates energy: near rest at the position "
                    "estimate its damping (d equations / d velocities) has a negative "
                    "eigenvalue or a Coulomb level is negative, so its free response grows "
                    "(an unstable model). Declare the friction parameters positive = true in "
                    "the model file"},
};

static ModelStatus parse_resource(void *region, const char *text, size_t length,
                                  const ModelLogger *log)
{
    char error[256];
    if (tp_parse(region, text, length, error, sizeof error) == 0) return MODEL_OK;
    log->log(log->context, MODEL_ERROR, "resources/model.txt: %s", error);
    return MODEL_ERROR;
}

/* The identifier the model file asks for (--identifier mff of `fmu --model`), and each
 * coordinate's gain bound in its own unit: F_PLUS_SI in SI (so that a file in mm
 * observes as one in m). */
static void resource_start_values(void *data)
{
    ModelData *d = data;
    d->pipe.identifier = d->program.identifier;
    for (int i = 0; i < d->program.n; ++i) d->f_plus[i] = F_PLUS_SI / d->program.coordinate_scale[i];
}

/* 0 if the published model takes energy at the position estimate, else 1 + the
 * coordinate whose friction creates it (model_damping.h). */
static int creates_energy(const ModelData *d, MdDamping *damping)
{
    return md_damping(&d->program, d->theta, d->position, d->u, damping) == 0
               ? md_creates_energy(d->program.n, damping)
               : 0;
}

static void publish(ModelData *d)
{
    const int n = d->program.n;
    mp_estimates(&d->pipe, &d->program, d->theta, d->theta_std, d->held);
    d->parameters_held = 0;
    for (int k = 0; k < d->program.p; ++k) d->parameters_held += d->held[k] != 0;
    const StatisticsJob *job = &d->pipe.statistics;
    const int solved = d->pipe.identifying && job->completed > 0.0;
    d->parameters_not_excited = 0;
    for (int k = 0; k < d->program.p; ++k) {
        d->theta_excitation[k] = solved ? job->column_excitation[k] : 0.0;
        d->parameters_not_excited += solved && d->theta_excitation[k] < MP_NOT_EXCITED;
    }
    for (int i = 0; i < n; ++i) {
        d->position[i] = mp_position(&d->pipe, i);
        d->velocity[i] = mp_velocity(&d->pipe, i); /* for the end of the step, as x1_hat */
    }
    d->excitation = d->pipe.identifying ? d->pipe.statistics.excitation : 0.0;
    d->identifier_active = d->pipe.identifying;
    d->identifier_cutoff = d->pipe.regression == MP_REGRESSION_WINDOW && d->pipe.identifying
                               ? fl_cutoff(&d->pipe.window)
                               : 0.0;
    d->converged = mp_converged(&d->pipe, n);
    d->input_hold = ic_shortest(&d->cadence) * d->pipe.h;
    d->coarse_inputs = ic_coarse(&d->cadence);
    MdDamping damping;
    d->negative_damping = creates_energy(d, &damping) != 0;
}

/* The positions then the inputs: what the cadence watches. */
static int measured(const ModelData *d, double values[])
{
    memcpy(values, d->y, (size_t)d->program.n * sizeof values[0]);
    memcpy(values + d->program.n, d->u, (size_t)d->program.m * sizeof values[0]);
    return d->program.n + d->program.m;
}

/* Work units (about ns, model_interface.h) of one internal step: the observer
 * per coordinate (the bank of linear observers beside it), two evaluations of
 * the program at n + 1 accelerations, the identifier's rank-n update and the
 * statistics job's slice, and the fixed-lag window's sums. */
static double step_work(const ModelData *d)
{
    const double n = d->program.n, p = d->program.p;
    const double tokens = d->program.n_tokens;
    return (d->pipe.scheme == STO_SCHEME_ADAPTIVE ? 600.0 + 50.0 * n : 15.0 * n) +
           2.0 * (n + 1.0) * 5.0 * tokens +
           (d->pipe.identifier ? 1000.0 + n * p * (p + 3.0) / 2.0 : 0.0) +
           (d->pipe.identifier && d->pipe.regression == MP_REGRESSION_WINDOW
                ? 1500.0 * (n + d->program.m) + 5.0 * n * tokens /* its kernels, the program */
                : 0.0);
}

static ModelStatus initialize(void *data, double start_time, const ModelLogger *log)
{
    (void)start_time;
    ModelData *d = data;
    const int n = d->program.n;
    for (int i = 0; i < n; ++i) {
        double a1 = 0.0, a2 = 0.0;
        if (gains_complete(d->f_plus[i], GAINS_P, &a1, &a2) != 0) {
            log->log(log->context, MODEL_ERROR, "f_plus_%d = %g gives no gains by Theorem 3.1 "
                     "(too large)", i + 1, d->f_plus[i]);
            return MODEL_ERROR;
        }
        d->alpha1[i] = a1;
        d->alpha2[i] = a2;
    }
    char error[256];
    if (mp_init(&d->pipe, &d->program, d->alpha1, d->alpha2, d->y, error, sizeof error)) {
        log->log(log->context, MODEL_ERROR, "%s", error);
        return MODEL_ERROR;
    }
    if (d->pipe.terms_unwindowed && d->pipe.identifier && d->pipe.regression == MP_REGRESSION_WINDOW)
        log->log(log->context, MODEL_WARNING, "%d nonlinear entries of the positions and inputs "
                 "alone are evaluated at the smoothed sample, which misses their part beyond the "
                 "window's band: the window passes at most %d as functions of the samples",
                 d->pipe.terms_unwindowed, FL_MAX_TERMS);
    if (d->program.inputs_held && d->pipe.identifier && d->pipe.regression != MP_REGRESSION_WINDOW)
        log->log(log->context, MODEL_WARNING, "the model file declares its inputs held over each "
                 "sample; regression = %d takes them as samples (only the fixed-lag window, "
                 "regression = 1, takes the hold)", d->pipe.regression);
    d->reset_seen = d->identifier_reset;
    double values[IC_MAX_VALUES];
    const int count = measured(d, values);
    ic_init(&d->cadence, count, values, d->pipe.h, d->input_period);
    d->coarse_logged = 0;
    d->held_logged = d->held_seen = 0;
    d->held_since = 0.0;
    d->weak_logged = d->weak_seen = 0;
    d->weak_since = 0.0;
    d->damping_logged = d->energy_seen = 0;
    d->energy_since = 0.0;
    d->work_per_step = step_work(d);
    publish(d);
    return MODEL_OK;
}

static double internal_step(const void *data) { return ((const ModelData *)data)->pipe.h; }

static double max_work(const void *data) { return ((const ModelData *)data)->max_work; }

static double work_per_step(const void *data) { return ((const ModelData *)data)->work_per_step; }

static uint64_t max_internal_steps(const void *data)
{
    return (uint64_t)((const ModelData *)data)->max_internal_steps;
}

static void advance(void *data, double start_time, uint64_t k, uint64_t k_end)
{
    ModelData *d = data;
    if (d->identifier_reset != d->reset_seen) {
        d->reset_seen = d->identifier_reset;
        if (d->identifier_reset) mp_restart_identifier(&d->pipe);
    }
    double values[IC_MAX_VALUES];
    measured(d, values);
    ic_advance(&d->cadence, values, k_end - k);
    mp_run(&d->pipe, &d->program, d->y, d->u, start_time, k, k_end);
}

/* How long `value` has stood unchanged at communication point t [s]: the time
 * since it last changed (seen: the value at the last point, since: that time). */
static double standing(int value, double t, int *seen, double *since)
{
    if (value != *seen) *since = t;
    *seen = value;
    return t - *since;
}

/* Whether a count of parameters has grown beyond the last one logged and stood
 * MP_WARNING_DELAY (then it becomes the one logged); a count that falls is
 * remembered, so that growing again is said again. */
static int grown(int count, double t, int *logged, int *seen, double *since)
{
    const double stood = standing(count, t, seen, since);
    if (count < *logged) *logged = count;
    if (count > *logged && stood >= MP_WARNING_DELAY) {
        *logged = count;
        return 1;
    }
    return 0;
}

/* A warning each time more parameters have been held at their ranges' ends for
 * MP_WARNING_DELAY, naming the first: the log pushes the estimate outside what the
 * file declares (the transient's first estimates often are, briefly). */
static void log_held(ModelData *d, double t, const ModelLogger *log)
{
    if (grown(d->parameters_held, t, &d->held_logged, &d->held_seen, &d->held_since)) {
        int k = 0;
        while (!d->held[k]) ++k;
        log->log(log->context, MODEL_WARNING,
                 "t = %g: %d parameter(s) held at an end of the range the model file declares "
                 "since t = %g, %s at its %s end %g: the identifier's least squares lie "
                 "outside the range (a model term missing, or a parameter the log does not "
                 "excite yet)", t, d->parameters_held, d->held_since, d->program.names[k],
                 d->held[k] < 0 ? "lower" : "upper", d->theta[k]);
    }
}

/* A warning each time more parameters have not been excited for MP_WARNING_DELAY,
 * naming the least excited: its estimate is the log's noise or the nominal value. */
static void log_not_excited(ModelData *d, double t, const ModelLogger *log)
{
    if (grown(d->parameters_not_excited, t, &d->weak_logged, &d->weak_seen, &d->weak_since)) {
        int k = 0;
        for (int j = 1; j < d->program.p; ++j)
            if (d->theta_excitation[j] < d->theta_excitation[k]) k = j;
        log->log(log->context, MODEL_WARNING,
                 "t = %g: %d parameter(s) not excited since t = %g, the least %s (excitation "
                 "%.2g, below %g): its regressor column is zero so far or a combination of the "
                 "others, so the log does not determine its estimate %g or its theta_std. "
                 "Excite the motion that this term describes", t, d->parameters_not_excited,
                 d->weak_since, d->program.names[k], d->theta_excitation[k], MP_NOT_EXCITED,
                 d->theta[k]);
    }
}

/* A warning when the published model has created energy for MP_WARNING_DELAY
 * (once per episode; the transient's first estimates often do, briefly). */
static void log_damping(ModelData *d, double t, const ModelLogger *log)
{
    const double stood = standing(d->negative_damping, t, &d->energy_seen, &d->energy_since);
    if (!d->negative_damping) {
        d->damping_logged = 0;
        return;
    }
    MdDamping damping;
    const int which = !d->damping_logged && stood >= MP_WARNING_DELAY
                          ? creates_energy(d, &damping)
                          : 0;
    if (which) {
        const int i = which - 1;
        log->log(log->context, MODEL_WARNING,
                 "t = %g: the estimated model has created energy since t = %g: at rest, "
                 "coordinate %d's friction is negative (damping d equation_%d / d velocity_%d "
                 "= %g, Coulomb level %g), so its free response grows and a simulation of it "
                 "diverges. Declare the friction parameters positive = true in the model "
                 "file, or excite the motion more", t, d->energy_since, which, which, which,
                 damping.D[i][i], damping.coulomb[i]);
        d->damping_logged = 1;
    }
}

static ModelStatus communication_point(void *data, double t, const ModelLogger *log)
{
    ModelData *d = data;
    char message[512];
    if (mp_nonfinite(&d->pipe, message, sizeof message) != MP_FINITE) {
        log->log(log->context, MODEL_ERROR, "%s (reported at t = %g)", message, t);
        return MODEL_ERROR;
    }
    mp_communicate(&d->pipe);
    publish(d);
    log_cadence(&d->coarse_logged, d->coarse_inputs, d->input_hold, d->pipe.h, t, log);
    log_held(d, t, log);
    log_not_excited(d, t, log);
    log_damping(d, t, log);
    for (int i = 0; i < d->program.n; ++i) {
        if (!isfinite(d->position[i]) || !isfinite(d->velocity[i])) {
            log->log(log->context, MODEL_ERROR,
                     "observer diverged at t = %g: position_estimate_%d = %g, velocity_%d = %g "
                     "(position_%d = %g): raise f_plus_%d, or check the model's nominal values "
                     "and the step h", t, i + 1, d->position[i], i + 1, d->velocity[i], i + 1,
                     d->y[i], i + 1);
            return MODEL_ERROR;
        }
    }
    for (int k = 0; k < d->program.p; ++k) {
        if (!isfinite(d->theta[k]) || !isfinite(d->theta_std[k])) {
            log->log(log->context, MODEL_ERROR, "identifier diverged at t = %g: %s = %g "
                     "(a non-finite entry of the equations: an input or measurement out of "
                     "range of the model's functions?)", t, d->program.names[k], d->theta[k]);
            return MODEL_ERROR;
        }
    }
    return MODEL_OK;
}

/* A deserialized state, field by field (model_interface.h). */
#define D(field) DERIVED_FIELD(ModelData, field)
#define I(field, lo, hi) STATE_FIELD(ModelData, field, FIELD_INT, lo, hi)
#define R(field, lo, hi) STATE_FIELD(ModelData, field, FIELD_REAL, lo, hi)
static const StateField STATE_FIELDS[] = {
    D(alpha1), D(alpha2), I(reset_seen, 0, 1), IC_STATE_FIELDS(ModelData, cadence),
    I(coarse_logged, 0, 1), I(held_logged, 0, MAX_P), I(held_seen, 0, MAX_P),
    I(held, -1, 1), I(weak_logged, 0, MAX_P), I(weak_seen, 0, MAX_P),
    I(damping_logged, 0, 1), I(energy_seen, 0, 1), D(pipe.gain), D(pipe.warm_up),
    D(pipe.terms_unwindowed), D(pipe.window_term), D(pipe.sign_velocities),
    I(pipe.since_reversal, 0, 2 * FL_MAX_LEAD + 1), R(pipe.speed_samples, 0.0, NAN),
    R(pipe.speed_square, 0.0, NAN),
    I(pipe.identifying, 0, 1), I(pipe.started, 0, 1), I(pipe.warm_samples, 0, 1000000000),
    R(pipe.singular_steps, 0.0, NAN), I(pipe.nonfinite, MP_FINITE, MP_NONFINITE_IDENTIFIER),
    I(pipe.nonfinite_equation, 0, MAX_N - 1), I(pipe.nonfinite_entry, -1, MAX_P - 1),
    FL_STATE_FIELDS(ModelData, pipe.window),
    STO_STATE_FIELDS(ModelData, pipe.obs[0]),
    STO_STATE_FIELDS(ModelData, pipe.obs[1]), BANK_STATE_FIELDS(ModelData, pipe.bank[0]),
    BANK_STATE_FIELDS(ModelData, pipe.bank[1]), RRI_STATE_FIELDS(ModelData, pipe.id),
    SJ_STATE_FIELDS(ModelData, pipe.statistics),
    /* the doubles, named by their struct */
    REAL_FIELDS(ModelData, pipe.obs), REAL_FIELDS(ModelData, pipe.bank),
    REAL_FIELDS(ModelData, pipe.id), REAL_FIELDS(ModelData, pipe.statistics),
    REAL_FIELDS(ModelData, pipe.window),
};
#undef D
#undef I
#undef R
_Static_assert(MP_GROUPS == 2, "STATE_FIELDS lists each observer group");

/* What the field table cannot state: indices below counts held in other fields. */
static ModelStatus check_restored(const void *data, const void *initialized,
                                  const ModelLogger *log)
{
    const ModelData *d = data;
    (void)initialized;
    for (int g = 0; g < mp_groups(d->program.n); ++g)
        if (d->pipe.scheme == STO_SCHEME_ADAPTIVE &&
            !na_valid(&d->pipe.bank[g], mp_group_size(d->program.n, g))) {
            log->log(log->context, MODEL_ERROR, "deserialized FMU state: an index of "
                     "pipe.bank[%d] is not one of its %d members; state refused", g,
                     d->pipe.bank[g].count);
            return MODEL_ERROR;
        }
    if (check_cadence(&d->cadence, log) != MODEL_OK) return MODEL_ERROR;
    if (d->pipe.warm_samples > d->pipe.warm_up) {
        log->log(log->context, MODEL_ERROR, "deserialized FMU state: pipe.warm_samples = %d "
                 "exceeds pipe.warm_up = %d; state refused", d->pipe.warm_samples,
                 d->pipe.warm_up);
        return MODEL_ERROR;
    }
    const RegressorIdentifier *id = &d->pipe.id;
    const StatisticsJob *job = &d->pipe.statistics;
    const int index_limit = job->stage == SJ_EIGEN ? STATS_EIGEN_ITERATIONS : job->p;
    if (d->pipe.identifier && (id->anchor_unit > id->p + 2 || id->batch_age >= id->batch_samples)) {
        log->log(log->context, MODEL_ERROR, "deserialized FMU state: pipe.id.anchor_unit = %d or "
                 "pipe.id.batch_age = %d is out of range; state refused", id->anchor_unit,
                 id->batch_age);
        return MODEL_ERROR;
    }
    if (job->stage != SJ_IDLE && job->stage != SJ_ESTIMATE && job->index >= index_limit) {
        log->log(log->context, MODEL_ERROR, "deserialized FMU state: pipe.statistics.index = %d "
                 "is out of range for its stage %d; state refused", job->index, job->stage);
        return MODEL_ERROR;
    }
    return MODEL_OK;
}

const ModelDescriptor MODEL_DESCRIPTOR = {
    .model_name = "ModelObserver",
    .model_identifier = "ModelObserver",
    .guid = "{8f3b2d6e-4a1c-4e7b-9d05-6c2a7e1f3b94}",
    .description = "Super-twisting observer and LSM/MFF identifier of a mechanical system "
                   "declared in a model file (resources/model.txt)",
    .variables = VARIABLES,
    .n_variables = sizeof VARIABLES / sizeof VARIABLES[0],
    .data_size = sizeof(ModelData),
    .default_stop_time = 10.0,
    .default_tolerance = 1e-6,
    .initialize = initialize,
    .internal_step = internal_step,
    .max_internal_steps = max_internal_steps,
    .max_work = max_work,
    .work_per_step = work_per_step,
    .advance = advance,
    .communication_point = communication_point,
    .state_fields = STATE_FIELDS,
    .n_state_fields = sizeof STATE_FIELDS / sizeof STATE_FIELDS[0],
    .check_restored = check_restored,
    .resource_file = "model.txt",
    .resource_offset = offsetof(ModelData, program),
    .resource_size = sizeof(TermProgram),
    .resource_max_bytes = TP_MAX_TEXT,
    .parse_resource = parse_resource,
    .resource_start_values = resource_start_values,
};
