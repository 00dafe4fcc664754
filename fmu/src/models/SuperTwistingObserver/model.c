/* SuperTwistingObserver: the observer FMU's variables and hooks over the
 * observer/identifier pipeline (core/observer_pipeline.h), with the checks and
 * messages the FMI layer gives a user.
 * Value references are stable and documented in docs/observer.md. */
#include <math.h>
#include <stddef.h>
#include <string.h>

#include "../../core/gains.h"
#include "../../core/observer_pipeline.h"
#include "../../instance/model_interface.h"
#include "../input_cadence_outputs.h"
#include "../state_fields.h"

#define MAX_N OP_MAX_N
#define MAX_L OP_MAX_L

typedef struct {
    ObserverPipeline pipe;  /* its configuration holds most parameters */
    /* parameters of the gains and the start */
    double alpha1[MAX_N], alpha2[MAX_N], f_plus[MAX_N], p[MAX_N];
    int start_from_measurement;
    double x1_hat_start[MAX_N], x2_hat_start[MAX_N];
    int max_internal_steps;
    double max_work, input_period;
    /* calculated parameters */
    double alpha1_used[MAX_N], alpha2_used[MAX_N];
    double work_per_step;
    /* inputs */
    ObserverInputs in;
    int identifier_reset;
    /* outputs not read straight from the algorithm state */
    ObserverEstimates out;
    double input_hold;
    int coarse_inputs;
    int reset_seen; /* identifier_reset value at the last step */
    InputCadence cadence; /* of every input (the unused ones do not change) */
    int coarse_logged;    /* the staircase warning stands */
    double communicated;  /* time of the last communication point */
} ObserverData;

/* The inputs as the cadence watches them: the struct's doubles. */
#define INPUT_VALUES (sizeof(ObserverInputs) / sizeof(double))
_Static_assert(sizeof(ObserverInputs) % sizeof(double) == 0 && INPUT_VALUES <= IC_MAX_VALUES,
               "the cadence watches the inputs' doubles");

#define OFF(field) offsetof(ObserverData, field)

/* The paper's pendulum (section 6): J = M L^2, c = [MgL/(2J), Vs/J, Ps/J, 0, 0]. */
#define PAPER_J (1.1 * 0.9 * 0.9)
static const double C_NOMINAL_START[JOINT_BASIS_SIZE] = {
    1.1 * 9.815 * 0.9 / (2.0 * PAPER_J), 0.18 / PAPER_J, 0.45 / PAPER_J, 0.0, 0.0};
static const double IDENTIFY_START[MAX_L] = {1, 1, 1, 0, 0, 0, 0, 0};
static const double P_START[MAX_N] = {0.5, 0.5, 0.5, 0.5};
static const double F_PLUS_START[MAX_N] = {10.0, 10.0, 10.0, 10.0};

static const ModelVariable VARIABLES[] = {
    {.name = "h", .vr = 1, .type = TYPE_REAL, PARAM(.offset = OFF(pipe.h), .start = 1e-4, .min = 0.0,
     .max = 1.0, .min_exclusive = true, .unit = "s",
     .description = "Fixed internal step of the observer and identifier")},
    {.name = "n", .vr = 2, .type = TYPE_INTEGER, PARAM(.offset = OFF(pipe.n), .start = 1, .min = 1,
     .max = MAX_N, .description = "Degrees of freedom observed (active rows of the vectors)")},
    {.name = "nominal_model", .vr = 3, .type = TYPE_INTEGER, PARAM(.offset = OFF(pipe.nominal_model),
     .start = OP_NOMINAL_JOINT, .min = 1, .max = 2,
     .description = "1: built-in joint x'' = b u - sum c_k psi_k (n = 1); 2: external, "
                    "nominal acceleration F and regressor phi come as inputs")},
    {.name = "scheme", .vr = 4, .type = TYPE_INTEGER, PARAM(.offset = OFF(pipe.scheme),
     .start = STO_SCHEME_ADAPTIVE, .min = 1, .max = 3,
     .description = "Discretization: 1 explicit Euler as in the paper; 2 sampling-consistent "
                    "implicit (no chattering, no filter needed); 3 the implicit observer beside "
                    "linear observers for noisy measurements, the best predictor published")},
    {.name = "identifier", .vr = 5, .type = TYPE_INTEGER, PARAM(.offset = OFF(pipe.identifier),
     .start = IDENTIFIER_OFF, .min = 0, .max = 2,
     .description = "Parameter identifier: 0 off, 1 least squares (18)-(19), 2 matrix "
                    "forgetting factor (36)-(37)")},
    {.name = "l", .vr = 6, .type = TYPE_INTEGER, PARAM(.offset = OFF(pipe.l), .start = 3, .min = 1,
     .max = MAX_L, .description = "Number of regressors phi of the external model")},
    {.name = "alpha1", .vr = 10, .rows = MAX_N, .type = TYPE_REAL, PARAM(.offset = OFF(alpha1),
     .start = 0.0, .min = 0.0, .max = NAN, .unit = "rad/s2",
     .description = "Gain of alpha1 sign(e); 0: computed from f_plus by Theorem 3.1")},
    {.name = "alpha2", .vr = 14, .rows = MAX_N, .type = TYPE_REAL, PARAM(.offset = OFF(alpha2),
     .start = 0.0, .min = 0.0, .max = NAN,
     .description = "Gain of alpha2 |e|^(1/2) sign(e) [rad^(1/2)/s]; 0: computed by Theorem 3.1")},
    {.name = "f_plus", .vr = 18, .rows = MAX_N, .type = TYPE_REAL, PARAM(.offset = OFF(f_plus),
     .starts = F_PLUS_START, .min = 0.0, .max = NAN, .unit = "rad/s2",
     .description = "Bound f+ of condition (5) on the unknown acceleration")},
    {.name = "p", .vr = 22, .rows = MAX_N, .type = TYPE_REAL, PARAM(.offset = OFF(p),
     .starts = P_START, .min = 0.0, .max = 1.0, .min_exclusive = true, .max_exclusive = true,
     .description = "Constant p of condition (6), 0 < p < 1")},
    {.name = "tau", .vr = 26, .type = TYPE_REAL, PARAM(.offset = OFF(pipe.tau), .start = 0.002,
     .min = 0.0, .max = NAN, .unit = "s",
     .description = "Time constant of the equivalent output injection filter; 0: no filter")},
    {.name = "b", .vr = 27, .type = TYPE_REAL, PARAM(.offset = OFF(pipe.b), .start = 1.0 / PAPER_J,
     UNBOUNDED, .description = "Built-in joint: input gain b (1/J) [1/(kg.m2)]")},
    {.name = "c_nominal", .vr = 28, .rows = JOINT_BASIS_SIZE, .type = TYPE_REAL,
     PARAM(.offset = OFF(pipe.c_nominal), .starts = C_NOMINAL_START, UNBOUNDED,
     .description = "Built-in joint: nominal coefficients of [sin x1, x2, sign(x2), x1, 1]")},
    {.name = "theta_nominal", .vr = 40, .rows = MAX_N, .cols = MAX_L, .type = TYPE_REAL,
     PARAM(.offset = OFF(pipe.theta_nominal), .start = 0.0, UNBOUNDED,
     .description = "External model: nominal parameters thetabar of (12), acceleration "
                    "F + thetabar phi")},
    {.name = "t_id", .vr = 80, .type = TYPE_REAL, PARAM(.offset = OFF(pipe.t_id), .start = 0.0,
     UNBOUNDED, .unit = "s", .description = "Earliest time at which the identifier starts")},
    {.name = "rho", .vr = 81, .type = TYPE_REAL, PARAM(.offset = OFF(pipe.rho), .start = 1e-3,
     .min = 0.0, .max = NAN, .min_exclusive = true,
     .description = "Regularization: Gamma(0) = I/rho")},
    {.name = "R", .vr = 82, .type = TYPE_REAL, PARAM(.offset = OFF(pipe.R), .start = 0.1, .min = 0.0,
     .max = 1.0, .min_exclusive = true, .max_exclusive = true,
     .description = "MFF forgetting factor per second (R I, weight R^(t - s))")},
    {.name = "identify", .vr = 83, .rows = MAX_L, .type = TYPE_BOOLEAN,
     PARAM(.offset = OFF(pipe.identify), .starts = IDENTIFY_START, UNBOUNDED,
     .description = "Which regressors are identified; the others keep their nominal value")},
    {.name = "start_from_measurement", .vr = 91, .type = TYPE_BOOLEAN,
     PARAM(.offset = OFF(start_from_measurement), .start = 1, UNBOUNDED,
     .description = "Initial x1_hat = y at initialization (else x1_hat_start)")},
    {.name = "x1_hat_start", .vr = 92, .rows = MAX_N, .type = TYPE_REAL,
     PARAM(.offset = OFF(x1_hat_start), .start = 0.0, UNBOUNDED, .unit = "rad",
     .description = "Initial position estimate (if start_from_measurement is false)")},
    {.name = "x2_hat_start", .vr = 96, .rows = MAX_N, .type = TYPE_REAL,
     PARAM(.offset = OFF(x2_hat_start), .start = 0.0, UNBOUNDED, .unit = "rad/s",
     .description = "Initial velocity estimate")},
    {.name = "identifier_form", .vr = 110, .type = TYPE_INTEGER,
     PARAM(.offset = OFF(pipe.identifier_form), .start = OP_FORM_INFORMATION, .min = 1, .max = 2,
     .description = "1: explicit Euler on Gamma as in the paper; 2: information form with "
                    "stabilized forgetting (Gamma <= I/rho, stable for any h)")},
    {.name = "identifier_start", .vr = 111, .type = TYPE_INTEGER,
     PARAM(.offset = OFF(pipe.identifier_start), .start = OP_START_WHEN_CONVERGED, .min = 0, .max = 1,
     .description = "0: start at t_id; 1: start once the observer has converged and t >= t_id")},
    {.name = "filter_regressor", .vr = 112, .type = TYPE_BOOLEAN,
     PARAM(.offset = OFF(pipe.filter_regressor), .start = 1, UNBOUNDED,
     .description = "Pass the regressor through the same filter as z_eq (removes the O(tau) "
                    "bias of filtering one side only)")},
    {.name = "mff_drift", .vr = 114, .type = TYPE_BOOLEAN,
     PARAM(.offset = OFF(pipe.mff_drift), .start = 1, UNBOUNDED,
     .description = "MFF in information form: model each parameter as locally linear in "
                    "time, which removes the lag of forgetting (needs 2 m <= 8)")},
    {.name = "identify_b", .vr = 115, .type = TYPE_BOOLEAN,
     PARAM(.offset = OFF(pipe.identify_b), .start = 1, UNBOUNDED,
     .description = "Built-in joint: identify the input gain b (u is a regressor); the "
                    "estimate is the output b_hat")},
    {.name = "convergence_window", .vr = 113, .type = TYPE_REAL,
     PARAM(.offset = OFF(pipe.convergence_window), .start = 0.05, .min = 0.0, .max = NAN,
     .min_exclusive = true, .unit = "s",
     .description = "Time constant of the convergence test (rate of sign switching of e)")},
    {.name = "model_feedback", .vr = 117, .type = TYPE_BOOLEAN,
     PARAM(.offset = OFF(pipe.model_feedback), .start = 1, UNBOUNDED,
     .description = "Built-in joint, LSM in information form: once identified (from "
                    "1 s of data on, entering over 1 s), the observer predicts with the identified b "
                    "and c, each correction weighted by its significance; z_eq is then the "
                    "perturbation beyond that model. false: always the nominal b, c_nominal")},
    {.name = "tau_identifier", .vr = 116, .type = TYPE_REAL,
     PARAM(.offset = OFF(pipe.tau_identifier), .start = 0.1, .min = 0.0, .max = NAN, .unit = "s",
     .description = "LSM in information form: time constant of the filter on both sides of "
                    "the regression (z and the regressor), which keeps velocity noise and a "
                    "plant's discretization mismatch out of constant parameters; MFF and the "
                    "paper's form use tau (a tracking estimate pays the filter's lag); 0: no filter")},
    {.name = "alpha1_used", .vr = 100, .rows = MAX_N, .type = TYPE_REAL,
     CALC(.offset = OFF(alpha1_used), .unit = "rad/s2",
     .description = "alpha1 in use (given, or from Theorem 3.1)")},
    {.name = "alpha2_used", .vr = 104, .rows = MAX_N, .type = TYPE_REAL,
     CALC(.offset = OFF(alpha2_used), .description = "alpha2 in use (given, or from Theorem 3.1)")},
    {.name = "y", .vr = 200, .rows = MAX_N, .type = TYPE_REAL,
     INPUT(.offset = OFF(in.y), .unit = "rad", .description = "Measured position x1")},
    {.name = "u", .vr = 204, .type = TYPE_REAL,
     INPUT(.offset = OFF(in.u), .start = 1.0, .unit = "N.m",
     .description = "Built-in joint: actuator torque (start 1 N.m: with y held at 0 the "
                    "default experiment shows the injection cancelling b u)")},
    {.name = "F", .vr = 208, .rows = MAX_N, .type = TYPE_REAL,
     INPUT(.offset = OFF(in.F), .unit = "rad/s2",
     .description = "External model: nominal acceleration F(t, y, x2_hat, u)")},
    {.name = "phi", .vr = 212, .rows = MAX_L, .type = TYPE_REAL,
     INPUT(.offset = OFF(in.phi), .description = "External model: regressor phi(t, y, x2_hat, u)")},
    {.name = "identifier_reset", .vr = 220, .type = TYPE_BOOLEAN,
     .causality = CAUSALITY_INPUT, .variability = VARIABILITY_DISCRETE, UNBOUNDED,
     .offset = OFF(identifier_reset),
     .description = "A rising edge restarts identification from the nominal parameters"},
    {.name = "x1_hat", .vr = 300, .rows = MAX_N, .type = TYPE_REAL,
     OUTPUT(.offset = OFF(pipe.obs.x1_hat), .unit = "rad", .description = "Position estimate")},
    {.name = "x2_hat", .vr = 304, .rows = MAX_N, .type = TYPE_REAL,
     OUTPUT(.offset = OFF(pipe.obs.x2_hat), .unit = "rad/s", .description = "Velocity estimate")},
    {.name = "z_eq", .vr = 308, .rows = MAX_N, .type = TYPE_REAL,
     OUTPUT(.offset = OFF(pipe.obs.z_eq), .unit = "rad/s2",
     .description = "Equivalent output injection alpha1 sign(e), eq. (7), unfiltered")},
    {.name = "z_eq_filtered", .vr = 312, .rows = MAX_N, .type = TYPE_REAL,
     OUTPUT(.offset = OFF(pipe.obs.z_filtered), .unit = "rad/s2",
     .description = "Filtered injection: the identified perturbation, eq. (10)")},
    {.name = "theta_hat", .vr = 320, .rows = MAX_N, .cols = MAX_L, .type = TYPE_REAL,
     OUTPUT(.on_read = true, .offset = OFF(out.theta_hat),
     .description = "Parameter estimates: built-in joint: theta_hat[1,k] estimates c_k; "
                    "external: theta in xi = theta phi")},
    {.name = "gamma_trace", .vr = 360, .type = TYPE_REAL,
     OUTPUT(.on_read = true, .offset = OFF(out.gamma_trace),
     .description = "Trace of the identifier's Gamma")},
    {.name = "identifier_active", .vr = 361, .type = TYPE_BOOLEAN,
     .causality = CAUSALITY_OUTPUT, .variability = VARIABILITY_DISCRETE, UNBOUNDED,
     .offset = OFF(out.identifier_active), .description = "The identifier is integrating"},
    {.name = "converged", .vr = 362, .type = TYPE_BOOLEAN,
     .causality = CAUSALITY_OUTPUT, .variability = VARIABILITY_DISCRETE, UNBOUNDED,
     .offset = OFF(out.converged),
     .description = "The observer is in its sliding mode by the switching-rate test"},
    {.name = "excitation", .vr = 363, .type = TYPE_REAL,
     OUTPUT(.on_read = true, .offset = OFF(out.excitation),
     .description = "Smallest eigenvalue of the identifier's information per unit time "
                    "(identifier_form 2); near 0: theta_hat is not being learned")},
    {.name = "b_hat", .vr = 364, .type = TYPE_REAL,
     OUTPUT(.on_read = true, .offset = OFF(out.b_hat),
     .description = "Built-in joint: estimate of the input gain b [1/(kg.m2)] (b while not "
                    "identified)")},
    {.name = "theta_std", .vr = 380, .rows = MAX_N, .cols = MAX_L, .type = TYPE_REAL,
     OUTPUT(.on_read = true, .offset = OFF(out.theta_std),
     .description = "Standard error of theta_hat (identifier_form 2; 0 where not identified): "
                    "from the information matrix and the residuals' low-frequency power")},
    {.name = "b_std", .vr = 412, .type = TYPE_REAL,
     OUTPUT(.on_read = true, .offset = OFF(out.b_std),
     .description = "Standard error of b_hat (identifier_form 2)")},
    {.name = "noise_std", .vr = 370, .rows = MAX_N, .type = TYPE_REAL,
     OUTPUT(.offset = OFF(pipe.bank.noise_std), .unit = "rad",
     .description = "Scheme 3: estimated standard deviation of the measurement noise "
                    "(quantization included) from the published observer's innovations")},
    {.name = "observer_bandwidth", .vr = 374, .rows = MAX_N, .type = TYPE_REAL,
     OUTPUT(.offset = OFF(pipe.bank.bandwidth), .unit = "rad/s",
     .description = "Scheme 3: bandwidth of the published observer (1/h: the super-twisting "
                    "observer)")},
    MAX_INTERNAL_STEPS_VARIABLE(OFF(max_internal_steps)),
    WORK_VARIABLES(OFF(max_work), OFF(work_per_step)),
    INPUT_CADENCE_VARIABLES(420, OFF(input_hold), OFF(coarse_inputs), OFF(input_period)),
};

static ModelStatus complete_gains(ObserverData *d, const ModelLogger *log)
{
    ModelStatus status = MODEL_OK;
    for (int i = 0; i < d->pipe.n; ++i) {
        double a1 = d->alpha1[i], a2 = d->alpha2[i];
        const double f = d->f_plus[i], p = d->p[i];
        if (gains_complete(f, p, &a1, &a2) != 0) {
            const double given1 = d->alpha1[i];
            if (!(f > 0.0))
                log->log(log->context, MODEL_ERROR,
                         "alpha1[%d] = %g, alpha2[%d] = %g: a gain left at 0 needs f_plus[%d] > 0 "
                         "(and alpha1 > f_plus) to be computed by Theorem 3.1", i + 1, a1, i + 1,
                         a2, i + 1);
            else if (!isfinite(a1))
                log->log(log->context, MODEL_ERROR,
                         "f_plus[%d] = %g is too large: alpha1[%d] = %g f_plus[%d] of Theorem 3.1 "
                         "overflows; give a smaller f_plus[%d] or set alpha1[%d] and alpha2[%d]",
                         i + 1, f, i + 1, GAINS_ALPHA1_FACTOR, i + 1, i + 1, i + 1, i + 1);
            else if (!(a1 > f))
                log->log(log->context, MODEL_ERROR,
                         "alpha2[%d] = 0 is computed by Theorem 3.1 only when alpha1[%d] exceeds "
                         "f_plus[%d]: alpha1[%d] = %g, f_plus[%d] = %g; raise alpha1[%d] or set "
                         "alpha2[%d]", i + 1, i + 1, i + 1, i + 1, given1, i + 1, f, i + 1, i + 1);
            else
                log->log(log->context, MODEL_ERROR,
                         "f_plus[%d] = %g, alpha1[%d] = %g: the alpha2 bound of (6) overflows; "
                         "give smaller f_plus[%d] and alpha1[%d] or set alpha2[%d]", i + 1, f,
                         i + 1, a1, i + 1, i + 1, i + 1);
            return MODEL_ERROR;
        }
        if (f > 0.0 && !(a1 > f)) {
            log->log(log->context, MODEL_WARNING,
                     "alpha1[%d] = %g violates (6): it must exceed f_plus[%d] = %g (short by %g)",
                     i + 1, a1, i + 1, f, f - a1);
            status = MODEL_WARNING;
        } else if (f > 0.0) {
            const double bound = gains_alpha2_bound(a1, f, p);
            if (!(a2 > bound)) {
                log->log(log->context, MODEL_WARNING,
                         "alpha2[%d] = %g violates (6): the bound for alpha1 = %g, f_plus = %g, "
                         "p = %g is %g (short by %g, %.1f percent)", i + 1, a2, a1, f, p, bound,
                         bound - a2, 100.0 * (bound - a2) / bound);
                status = MODEL_WARNING;
            }
        }
        d->alpha1_used[i] = a1;
        d->alpha2_used[i] = a2;
    }
    return status;
}

/* Work units (about ns, model_interface.h) of one internal step: upper bounds
 * of the time measured per configuration (docs/observer.md, Limits): the
 * observer per DOF (scheme 3: the bank of linear observers beside it), the
 * identifier's sums over its d (2m with MFF's drift model) regressors and rows,
 * and under scheme 3 the regressors' pass through the followed member's filter. */
static double step_work(const ObserverPipeline *p)
{
    const double n = p->n, m = p->m;
    double work = p->scheme == STO_SCHEME_PAPER      ? 10.0 * n
                  : p->scheme == STO_SCHEME_IMPLICIT ? 15.0 * n
                                                     : 600.0 + 50.0 * n;
    if (p->identifier != IDENTIFIER_OFF) {
        const double dim = p->info.drift && p->identifier_form == OP_FORM_INFORMATION ? 2.0 * m : m;
        work += 100.0 + 8.0 * dim * (n + dim) + (p->scheme == STO_SCHEME_ADAPTIVE ? 50.0 * m : 0.0);
    }
    return work;
}

static ModelStatus initialize(void *data, double start_time, const ModelLogger *log)
{
    (void)start_time;
    ObserverData *d = data;
    ObserverPipeline *p = &d->pipe;
    if (p->nominal_model == OP_NOMINAL_JOINT && p->n != 1) {
        log->log(log->context, MODEL_ERROR,
                 "n = %d: the built-in joint model (nominal_model = 1) has one degree of freedom; "
                 "use nominal_model = 2 for n > 1", p->n);
        return MODEL_ERROR;
    }
    d->out.b_hat = p->b;
    if (op_select(p) == 0 && p->identifier != IDENTIFIER_OFF) {
        log->log(log->context, MODEL_ERROR,
                 "identifier = %d but no regressor is selected (identify[1..%d] are all false)",
                 p->identifier, p->nominal_model == OP_NOMINAL_JOINT ? JOINT_BASIS_SIZE : p->l);
        return MODEL_ERROR;
    }
    ModelStatus status = complete_gains(d, log);
    if (status == MODEL_ERROR) return status;

    double x1_hat0[MAX_N];
    for (int i = 0; i < MAX_N; ++i)
        x1_hat0[i] = d->start_from_measurement ? d->in.y[i] : d->x1_hat_start[i];
    if (op_init(p, d->alpha1_used, d->alpha2_used, x1_hat0, d->x2_hat_start, &d->in, &d->out,
                NULL)) {
        log->log(log->context, MODEL_ERROR,
                 "mff_drift needs 2 m <= %d identified regressors, %d are selected (the "
                 "built-in joint's u counts when identify_b is true); select fewer or set "
                 "mff_drift = false", ID_MAX_REGRESSORS, p->m);
        return MODEL_ERROR;
    }
    d->work_per_step = step_work(p);
    d->reset_seen = d->identifier_reset;
    ic_init(&d->cadence, (int)INPUT_VALUES, (const double *)&d->in, p->h, d->input_period);
    d->coarse_logged = 0;
    d->input_hold = 0.0;
    d->coarse_inputs = 0;
    return status;
}

static double internal_step(const void *data) { return ((const ObserverData *)data)->pipe.h; }

static double max_work(const void *data) { return ((const ObserverData *)data)->max_work; }

static double work_per_step(const void *data)
{
    return ((const ObserverData *)data)->work_per_step;
}

static uint64_t max_internal_steps(const void *data)
{
    return (uint64_t)((const ObserverData *)data)->max_internal_steps;
}

static void advance(void *data, double start_time, uint64_t k, uint64_t k_end)
{
    ObserverData *d = data;
    const int edge = d->identifier_reset != d->reset_seen;
    if (d->pipe.identifier != IDENTIFIER_OFF && edge) d->reset_seen = d->identifier_reset;
    ic_advance(&d->cadence, (const double *)&d->in, k_end - k);
    op_run(&d->pipe, &d->in, start_time, k, k_end,
           d->pipe.identifier != IDENTIFIER_OFF && edge && d->identifier_reset);
}

/* Why DOF i's estimate is not finite: a nominal acceleration that overflows
 * (the inputs or nominal parameters), a measurement out of range, else the
 * discretization (h, gains). */
static void explain_divergence(const ObserverData *d, double t, int i, const ModelLogger *log)
{
    const ObserverPipeline *p = &d->pipe;
    StoAcceleration acceleration[MAX_N];
    double regressor[MAX_L];
    op_nominal_model(p, &d->in, acceleration, regressor);
    const StoAcceleration a = acceleration[i];
    if (!(fabs(a.held + a.point) < 1e300) || !isfinite(a.viscous) || !isfinite(a.coulomb)) {
        if (p->nominal_model == OP_NOMINAL_JOINT)
            log->log(log->context, MODEL_ERROR,
                     "observer: the nominal acceleration b u - c psi(y) = %g at t = %g is out of "
                     "floating-point range (b = %g, u = %g, y[1] = %g): the input or the nominal "
                     "parameters are too large", a.held + a.point, t, p->b, d->in.u, d->in.y[0]);
        else
            log->log(log->context, MODEL_ERROR,
                     "observer: the nominal acceleration F[%d] + theta_nominal phi = %g at t = %g "
                     "is out of floating-point range (F[%d] = %g): the inputs F, phi or "
                     "theta_nominal are too large", i + 1, a.held, t, i + 1, d->in.F[i]);
    } else if (!(fabs(d->in.y[i]) < 1e300)) {
        log->log(log->context, MODEL_ERROR,
                 "observer: the measurement y[%d] = %g at t = %g is too large to observe",
                 i + 1, d->in.y[i], t);
    } else {
        log->log(log->context, MODEL_ERROR,
                 "observer diverged at t = %g: x1_hat[%d] = %g, x2_hat[%d] = %g (reduce h or "
                 "the gains)", t, i + 1, p->obs.x1_hat[i], i + 1, p->obs.x2_hat[i]);
    }
}

/* The identifier's published estimates are finite. */
static ModelStatus check_estimates(const ObserverData *d, const ModelLogger *log)
{
    const ObserverEstimates *e = &d->out;
    const double t = d->communicated;
    if (!isfinite(e->gamma_trace)) {
        log->log(log->context, MODEL_ERROR,
                 "identifier diverged at t = %g: trace(Gamma) = %g (explicit Euler needs "
                 "h |Gamma| |phi|^2 < 2; increase rho or reduce h)", t, e->gamma_trace);
        return MODEL_ERROR;
    }
    /* x * 0 is NaN for inf and NaN (a sum of finite values could overflow) */
    double poison = e->excitation * 0.0 + e->b_hat * 0.0 + e->b_std * 0.0;
    for (int i = 0; i < d->pipe.n; ++i)
        for (int k = 0; k < MAX_L; ++k)
            poison += e->theta_hat[i][k] * 0.0 + e->theta_std[i][k] * 0.0;
    if (poison != 0.0) {
        log->log(log->context, MODEL_ERROR,
                 "identifier diverged at t = %g: an estimate of theta_hat, theta_std, b_hat, "
                 "b_std or excitation is not finite", t);
        return MODEL_ERROR;
    }
    return MODEL_OK;
}

static ModelStatus communication_point(void *data, double t, const ModelLogger *log)
{
    ObserverData *d = data;
    op_communicate(&d->pipe, &d->out);
    d->input_hold = ic_shortest(&d->cadence) * d->pipe.h;
    d->coarse_inputs = ic_coarse(&d->cadence);
    log_cadence(&d->coarse_logged, d->coarse_inputs, d->input_hold, d->pipe.h, t, log);
    for (int i = 0; i < d->pipe.n; ++i) {
        if (!isfinite(d->pipe.obs.x1_hat[i]) || !isfinite(d->pipe.obs.x2_hat[i])) {
            explain_divergence(d, t, i, log);
            return MODEL_ERROR;
        }
    }
    d->communicated = t;
    /* the paper form's estimates are published here: its explicit Euler can
     * diverge, and they cost little */
    if (d->pipe.identifier_form == OP_FORM_PAPER && op_publish(&d->pipe, &d->out))
        return check_estimates(d, log);
    return MODEL_OK;
}

/* The estimates of the last communication point, derived when first read
 * (model_interface.h): the information form's solve costs more than an
 * internal step, and a closed loop at H = h reads none of them. */
static ModelStatus refresh_outputs(void *data, const ModelLogger *log)
{
    ObserverData *d = data;
    if (!op_publish(&d->pipe, &d->out)) return MODEL_OK;
    return check_estimates(d, log);
}

/* A deserialized state, field by field (model_interface.h): what initialize
 * derives from the parameters must be what it derives from the state's own;
 * the counters the steps move must lie in their ranges; every double not
 * listed must be finite. */
#define D(field) DERIVED_FIELD(ObserverData, field)
#define I(field, lo, hi) STATE_FIELD(ObserverData, field, FIELD_INT, lo, hi)
#define U(field) STATE_FIELD(ObserverData, field, FIELD_UNSIGNED, 0, 4294967295.0)
static const StateField STATE_FIELDS[] = {
    D(pipe.m), D(pipe.selected), D(pipe.slot_velocity), D(pipe.slot_velocity_sign),
    D(pipe.slot_input), D(pipe.identifier_gain), D(pipe.feedback), I(pipe.identifier_active, 0, 1),
    I(reset_seen, 0, 1), IC_STATE_FIELDS(ObserverData, cadence), I(coarse_logged, 0, 1),
    I(pipe.publish_pending, 0, 1), I(pipe.info.solve_pending, 0, 1),
    STO_STATE_FIELDS(ObserverData, pipe.obs),
    BANK_STATE_FIELDS(ObserverData, pipe.bank), D(pipe.id.kind),
    D(pipe.id.rows), D(pipe.id.m), D(pipe.id.h), D(pipe.id.h_log_r), D(pipe.info.rows),
    D(pipe.info.m), D(pipe.info.drift), D(pipe.info.h), D(pipe.info.rho), D(pipe.info.tuning),
    D(pipe.info.lambda),
    D(pipe.info.one_minus_lambda_rho), D(pipe.info.forgetting_rate), D(pipe.info.anchor_interval),
    I(pipe.info.anchor_age, 0, INFO_ANCHOR_MAX_INTERVAL),
    LEAVE_OUT_STATE_FIELDS(ObserverData, pipe.info.leave_out), D(pipe.info.batch_gain),
    D(pipe.info.power_gain), I(pipe.info.std_age, 0, INFO_STD_INTERVAL), D(pipe.info.blocks.rows),
    D(pipe.info.blocks.m), D(pipe.info.blocks.pairs), D(pipe.info.blocks.first),
    D(pipe.info.blocks.second), D(pipe.info.blocks.stage_gain_per_second),
    /* the doubles, named by their struct */
    REAL_FIELDS(ObserverData, pipe.obs), REAL_FIELDS(ObserverData, pipe.bank),
    REAL_FIELDS(ObserverData, pipe.id), REAL_FIELDS(ObserverData, pipe.info.blocks),
    REAL_FIELDS(ObserverData, pipe.info),
};
#undef D
#undef I
#undef U

/* What the field table cannot state: the bank's indices below its member count. */
static ModelStatus check_restored(const void *data, const void *initialized,
                                  const ModelLogger *log)
{
    const ObserverData *d = data;
    (void)initialized;
    if (check_cadence(&d->cadence, log) != MODEL_OK) return MODEL_ERROR;
    if (!na_valid(&d->pipe.bank, d->pipe.n)) {
        log->log(log->context, MODEL_ERROR, "deserialized FMU state: an index of bank (center, "
                 "zoom_index, selected, published, perturbation or follow) is not one of its %d "
                 "members; state refused", d->pipe.bank.count);
        return MODEL_ERROR;
    }
    if (d->pipe.info.anchor_age > d->pipe.info.anchor_interval) {
        log->log(log->context, MODEL_ERROR, "deserialized FMU state: info.anchor_age = %d exceeds "
                 "info.anchor_interval = %d; state refused", d->pipe.info.anchor_age,
                 d->pipe.info.anchor_interval);
        return MODEL_ERROR;
    }
    return MODEL_OK;
}

const ModelDescriptor MODEL_DESCRIPTOR = {
    .model_name = "SuperTwistingObserver",
    .model_identifier = "SuperTwistingObserver",
    .guid = "{5d0c3f0e-7b7a-4c52-9d5e-2f1a6b8e9c01}",
    .description = "Second-order sliding-mode (super-twisting) observer and LSM/MFF identifier "
                   "for mechanical systems (Davila, Fridman, Poznyak 2006)",
    .variables = VARIABLES,
    .n_variables = sizeof VARIABLES / sizeof VARIABLES[0],
    .data_size = sizeof(ObserverData),
    .default_stop_time = 10.0,
    .default_tolerance = 1e-6,
    .initialize = initialize,
    .internal_step = internal_step,
    .max_internal_steps = max_internal_steps,
    .max_work = max_work,
    .work_per_step = work_per_step,
    .advance = advance,
    .communication_point = communication_point,
    .refresh_outputs = refresh_outputs,
    .state_fields = STATE_FIELDS,
    .n_state_fields = sizeof STATE_FIELDS / sizeof STATE_FIELDS[0],
    .check_restored = check_restored,
};
