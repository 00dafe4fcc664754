/* SuperTwistingObserver: the observer FMU's variables and step.
 *
 * Wires the plain-C algorithms (core/) to the FMI layer: the nominal model
 * (built-in joint or external F and phi inputs), the super-twisting observer
 * with its equivalent output injection, and the LSM/MFF identifier.
 * Value references are stable and documented in docs/observer.md. */
#include <math.h>
#include <stddef.h>
#include <string.h>

#include "../core/gains.h"
#include "../core/identifier.h"
#include "../core/implicit_twisting.h"
#include "../core/information_identifier.h"
#include "../core/joint_model.h"
#include "../core/model_feedback.h"
#include "../core/noise_adaptive.h"
#include "../core/small_loops.h"
#include "../core/super_twisting.h"
#include "../instance/model_interface.h"

#define MAX_N STO_MAX_DOF
#define MAX_L ID_MAX_REGRESSORS

enum { NOMINAL_JOINT = 1, NOMINAL_EXTERNAL = 2 };
enum { FORM_PAPER = 1, FORM_INFORMATION = 2 };
enum { START_AT_T_ID = 0, START_WHEN_CONVERGED = 1 };

typedef struct {
    /* parameters */
    double h;
    int n, nominal_model, scheme, identifier, l;
    double alpha1[MAX_N], alpha2[MAX_N], f_plus[MAX_N], p[MAX_N];
    double tau;
    double b, c_nominal[JOINT_BASIS_SIZE];
    double theta_nominal[MAX_N][MAX_L];
    double t_id, rho, R;
    int identify[MAX_L];
    int start_from_measurement;
    double x1_hat_start[MAX_N], x2_hat_start[MAX_N];
    int identifier_form, identifier_start, filter_regressor, mff_drift, identify_b;
    double convergence_window;
    double tau_identifier;
    int model_feedback;
    int max_internal_steps;
    double max_work;
    /* calculated parameters */
    double alpha1_used[MAX_N], alpha2_used[MAX_N];
    double work_per_step;
    /* inputs */
    double y[MAX_N], u, F[MAX_N], phi[MAX_L];
    int identifier_reset;
    /* outputs not read straight from the algorithm state */
    double theta_hat[MAX_N][MAX_L];
    double gamma_trace, excitation, b_hat, b_std;
    double theta_std[MAX_N][MAX_L];
    int identifier_active, converged;
    /* derived at initialization */
    int m;                  /* number of identified regressors */
    int selected[MAX_L];    /* their indices in the full regressor */
    /* algorithm state */
    SuperTwistingObserver obs;
    AdaptiveBank bank;          /* scheme 3: the linear observers beside obs */
    double shadow[MAX_L][3];    /* scheme 3: the selected regressors through the followed
                                 * member's filter G (adaptive_shadow_step) */
    Identifier id;              /* identifier_form = 1 (the paper's explicit Euler) */
    InformationIdentifier info; /* identifier_form = 2 */
    double identifier_gain;     /* per step, of the filter on both sides of z = Delta phi */
    double phi_filtered[MAX_L]; /* selected regressors through the z_eq filter */
    double z_identifier[MAX_N]; /* z_eq through the same filter, started with phi_filtered */
    double phi_previous[MAX_L]; /* selected regressors of the previous sample (implicit scheme) */
    double velocity_before[2];  /* the joint's velocity two samples and one sample back */
    double input_before;        /* the joint's input two samples back */
    int reset_seen;             /* identifier_reset value at the last step */
    /* the selected regressors held over a communication step (hold_inputs) */
    double phi_now[MAX_L + 1];  /* selected regressors at this sample; [MAX_L] is a scratch slot */
    int slot_velocity, slot_velocity_sign; /* joint: where x2, sign(x2) go in phi_now (MAX_L:
                                            * not selected) */
    int slot_input;             /* joint: where u goes in phi_now (MAX_L: not identified) */
    /* model_feedback: the joint model the observer predicts with, b_model = b + D_b,
     * c_model = c_nominal - D (D in the identifier's Delta units, model_delta), and the
     * identifier's injection shifted back to the nominal model, D phi through the
     * followed member's filter G (model_shadow) and the identifier's filter (model_z) */
    double b_model, c_model[JOINT_BASIS_SIZE];
    double model_delta[MAX_L];
    double model_shadow[3];
    double model_z;
} ObserverData;

#define OFF(field) offsetof(ObserverData, field)

/* The paper's pendulum (section 6): J = M L^2, c = [MgL/(2J), Vs/J, Ps/J, 0, 0]. */
#define PAPER_J (1.1 * 0.9 * 0.9)
static const double C_NOMINAL_START[JOINT_BASIS_SIZE] = {
    1.1 * 9.815 * 0.9 / (2.0 * PAPER_J), 0.18 / PAPER_J, 0.45 / PAPER_J, 0.0, 0.0};
static const double IDENTIFY_START[MAX_L] = {1, 1, 1, 0, 0, 0, 0, 0};
static const double P_START[MAX_N] = {0.5, 0.5, 0.5, 0.5};
static const double F_PLUS_START[MAX_N] = {10.0, 10.0, 10.0, 10.0};

static const ModelVariable VARIABLES[] = {
    {.name = "h", .vr = 1, .type = TYPE_REAL, PARAM(.offset = OFF(h), .start = 1e-4, .min = 0.0,
     .max = 1.0, .min_exclusive = true, .unit = "s",
     .description = "Fixed internal step of the observer and identifier")},
    {.name = "n", .vr = 2, .type = TYPE_INTEGER, PARAM(.offset = OFF(n), .start = 1, .min = 1,
     .max = MAX_N, .description = "Degrees of freedom observed (active rows of the vectors)")},
    {.name = "nominal_model", .vr = 3, .type = TYPE_INTEGER, PARAM(.offset = OFF(nominal_model),
     .start = NOMINAL_JOINT, .min = 1, .max = 2,
     .description = "1: built-in joint x'' = b u - sum c_k psi_k (n = 1); 2: external, "
                    "nominal acceleration F and regressor phi come as inputs")},
    {.name = "scheme", .vr = 4, .type = TYPE_INTEGER, PARAM(.offset = OFF(scheme),
     .start = STO_SCHEME_ADAPTIVE, .min = 1, .max = 3,
     .description = "Discretization: 1 explicit Euler as in the paper; 2 sampling-consistent "
                    "implicit (no chattering, no filter needed); 3 the implicit observer beside "
                    "linear observers for noisy measurements, the best predictor published")},
    {.name = "identifier", .vr = 5, .type = TYPE_INTEGER, PARAM(.offset = OFF(identifier),
     .start = IDENTIFIER_OFF, .min = 0, .max = 2,
     .description = "Parameter identifier: 0 off, 1 least squares (18)-(19), 2 matrix "
                    "forgetting factor (36)-(37)")},
    {.name = "l", .vr = 6, .type = TYPE_INTEGER, PARAM(.offset = OFF(l), .start = 3, .min = 1,
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
    {.name = "tau", .vr = 26, .type = TYPE_REAL, PARAM(.offset = OFF(tau), .start = 0.002,
     .min = 0.0, .max = NAN, .unit = "s",
     .description = "Time constant of the equivalent output injection filter; 0: no filter")},
    {.name = "b", .vr = 27, .type = TYPE_REAL, PARAM(.offset = OFF(b), .start = 1.0 / PAPER_J,
     UNBOUNDED, .description = "Built-in joint: input gain b (1/J) [1/(kg.m2)]")},
    {.name = "c_nominal", .vr = 28, .rows = JOINT_BASIS_SIZE, .type = TYPE_REAL,
     PARAM(.offset = OFF(c_nominal), .starts = C_NOMINAL_START, UNBOUNDED,
     .description = "Built-in joint: nominal coefficients of [sin x1, x2, sign(x2), x1, 1]")},
    {.name = "theta_nominal", .vr = 40, .rows = MAX_N, .cols = MAX_L, .type = TYPE_REAL,
     PARAM(.offset = OFF(theta_nominal), .start = 0.0, UNBOUNDED,
     .description = "External model: nominal parameters thetabar of (12), acceleration "
                    "F + thetabar phi")},
    {.name = "t_id", .vr = 80, .type = TYPE_REAL, PARAM(.offset = OFF(t_id), .start = 0.0,
     UNBOUNDED, .unit = "s", .description = "Earliest time at which the identifier starts")},
    {.name = "rho", .vr = 81, .type = TYPE_REAL, PARAM(.offset = OFF(rho), .start = 1e-3,
     .min = 0.0, .max = NAN, .min_exclusive = true,
     .description = "Regularization: Gamma(0) = I/rho")},
    {.name = "R", .vr = 82, .type = TYPE_REAL, PARAM(.offset = OFF(R), .start = 0.1, .min = 0.0,
     .max = 1.0, .min_exclusive = true, .max_exclusive = true,
     .description = "MFF forgetting factor per second (R I, weight R^(t - s))")},
    {.name = "identify", .vr = 83, .rows = MAX_L, .type = TYPE_BOOLEAN,
     PARAM(.offset = OFF(identify), .starts = IDENTIFY_START, UNBOUNDED,
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
     PARAM(.offset = OFF(identifier_form), .start = FORM_INFORMATION, .min = 1, .max = 2,
     .description = "1: explicit Euler on Gamma as in the paper; 2: information form with "
                    "stabilized forgetting (Gamma <= I/rho, stable for any h)")},
    {.name = "identifier_start", .vr = 111, .type = TYPE_INTEGER,
     PARAM(.offset = OFF(identifier_start), .start = START_WHEN_CONVERGED, .min = 0, .max = 1,
     .description = "0: start at t_id; 1: start once the observer has converged and t >= t_id")},
    {.name = "filter_regressor", .vr = 112, .type = TYPE_BOOLEAN,
     PARAM(.offset = OFF(filter_regressor), .start = 1, UNBOUNDED,
     .description = "Pass the regressor through the same filter as z_eq (removes the O(tau) "
                    "bias of filtering one side only)")},
    {.name = "mff_drift", .vr = 114, .type = TYPE_BOOLEAN,
     PARAM(.offset = OFF(mff_drift), .start = 1, UNBOUNDED,
     .description = "MFF in information form: model each parameter as locally linear in "
                    "time, which removes the lag of forgetting (needs 2 m <= 8)")},
    {.name = "identify_b", .vr = 115, .type = TYPE_BOOLEAN,
     PARAM(.offset = OFF(identify_b), .start = 1, UNBOUNDED,
     .description = "Built-in joint: identify the input gain b (u is a regressor); the "
                    "estimate is the output b_hat")},
    {.name = "convergence_window", .vr = 113, .type = TYPE_REAL,
     PARAM(.offset = OFF(convergence_window), .start = 0.05, .min = 0.0, .max = NAN,
     .min_exclusive = true, .unit = "s",
     .description = "Time constant of the convergence test (rate of sign switching of e)")},
    {.name = "model_feedback", .vr = 117, .type = TYPE_BOOLEAN,
     PARAM(.offset = OFF(model_feedback), .start = 1, UNBOUNDED,
     .description = "Built-in joint, LSM in information form: once identified (from "
                    "1 s of data on, entering over 1 s), the observer predicts with the identified b "
                    "and c, each correction weighted by its significance; z_eq is then the "
                    "perturbation beyond that model. false: always the nominal b, c_nominal")},
    {.name = "tau_identifier", .vr = 116, .type = TYPE_REAL,
     PARAM(.offset = OFF(tau_identifier), .start = 0.1, .min = 0.0, .max = NAN, .unit = "s",
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
     INPUT(.offset = OFF(y), .unit = "rad", .description = "Measured position x1")},
    {.name = "u", .vr = 204, .type = TYPE_REAL,
     INPUT(.offset = OFF(u), .start = 1.0, .unit = "N.m",
     .description = "Built-in joint: actuator torque (start 1 N.m: with y held at 0 the "
                    "default experiment shows the injection cancelling b u)")},
    {.name = "F", .vr = 208, .rows = MAX_N, .type = TYPE_REAL,
     INPUT(.offset = OFF(F), .unit = "rad/s2",
     .description = "External model: nominal acceleration F(t, y, x2_hat, u)")},
    {.name = "phi", .vr = 212, .rows = MAX_L, .type = TYPE_REAL,
     INPUT(.offset = OFF(phi), .description = "External model: regressor phi(t, y, x2_hat, u)")},
    {.name = "identifier_reset", .vr = 220, .type = TYPE_BOOLEAN,
     .causality = CAUSALITY_INPUT, .variability = VARIABILITY_DISCRETE, UNBOUNDED,
     .offset = OFF(identifier_reset),
     .description = "A rising edge restarts identification from the nominal parameters"},
    {.name = "x1_hat", .vr = 300, .rows = MAX_N, .type = TYPE_REAL,
     OUTPUT(.offset = OFF(obs.x1_hat), .unit = "rad", .description = "Position estimate")},
    {.name = "x2_hat", .vr = 304, .rows = MAX_N, .type = TYPE_REAL,
     OUTPUT(.offset = OFF(obs.x2_hat), .unit = "rad/s", .description = "Velocity estimate")},
    {.name = "z_eq", .vr = 308, .rows = MAX_N, .type = TYPE_REAL,
     OUTPUT(.offset = OFF(obs.z_eq), .unit = "rad/s2",
     .description = "Equivalent output injection alpha1 sign(e), eq. (7), unfiltered")},
    {.name = "z_eq_filtered", .vr = 312, .rows = MAX_N, .type = TYPE_REAL,
     OUTPUT(.offset = OFF(obs.z_filtered), .unit = "rad/s2",
     .description = "Filtered injection: the identified perturbation, eq. (10)")},
    {.name = "theta_hat", .vr = 320, .rows = MAX_N, .cols = MAX_L, .type = TYPE_REAL,
     OUTPUT(.offset = OFF(theta_hat),
     .description = "Parameter estimates: built-in joint: theta_hat[1,k] estimates c_k; "
                    "external: theta in xi = theta phi")},
    {.name = "gamma_trace", .vr = 360, .type = TYPE_REAL,
     OUTPUT(.offset = OFF(gamma_trace), .description = "Trace of the identifier's Gamma")},
    {.name = "identifier_active", .vr = 361, .type = TYPE_BOOLEAN,
     .causality = CAUSALITY_OUTPUT, .variability = VARIABILITY_DISCRETE, UNBOUNDED,
     .offset = OFF(identifier_active), .description = "The identifier is integrating"},
    {.name = "converged", .vr = 362, .type = TYPE_BOOLEAN,
     .causality = CAUSALITY_OUTPUT, .variability = VARIABILITY_DISCRETE, UNBOUNDED,
     .offset = OFF(converged),
     .description = "The observer is in its sliding mode by the switching-rate test"},
    {.name = "excitation", .vr = 363, .type = TYPE_REAL,
     OUTPUT(.offset = OFF(excitation),
     .description = "Smallest eigenvalue of the identifier's information per unit time "
                    "(identifier_form 2); near 0: theta_hat is not being learned")},
    {.name = "b_hat", .vr = 364, .type = TYPE_REAL,
     OUTPUT(.offset = OFF(b_hat),
     .description = "Built-in joint: estimate of the input gain b [1/(kg.m2)] (b while not "
                    "identified)")},
    {.name = "theta_std", .vr = 380, .rows = MAX_N, .cols = MAX_L, .type = TYPE_REAL,
     OUTPUT(.offset = OFF(theta_std),
     .description = "Standard error of theta_hat (identifier_form 2; 0 where not identified): "
                    "from the information matrix and the residuals' low-frequency power")},
    {.name = "b_std", .vr = 412, .type = TYPE_REAL,
     OUTPUT(.offset = OFF(b_std), .description = "Standard error of b_hat (identifier_form 2)")},
    {.name = "noise_std", .vr = 370, .rows = MAX_N, .type = TYPE_REAL,
     OUTPUT(.offset = OFF(bank.noise_std), .unit = "rad",
     .description = "Scheme 3: estimated standard deviation of the measurement noise "
                    "(quantization included) from the published observer's innovations")},
    {.name = "observer_bandwidth", .vr = 374, .rows = MAX_N, .type = TYPE_REAL,
     OUTPUT(.offset = OFF(bank.bandwidth), .unit = "rad/s",
     .description = "Scheme 3: bandwidth of the published observer (1/h: the super-twisting "
                    "observer)")},
    MAX_INTERNAL_STEPS_VARIABLE(OFF(max_internal_steps)),
    WORK_VARIABLES(OFF(max_work), OFF(work_per_step)),
};

/* theta_hat from the identified corrections.  Built-in joint: the injection
 * is z = xi = -(c - cbar) psi, so Delta = cbar - c and c_hat = cbar - Delta_hat
 * (the paper's 6.2 Delta = [-a1 + a1bar, ...]).  External: theta_hat = thetabar + Delta_hat. */
static const double (*identified_delta(const ObserverData *d))[MAX_L]
{
    return d->identifier_form == FORM_PAPER ? (const double (*)[MAX_L])d->id.delta
                                            : (const double (*)[MAX_L])d->info.delta;
}

static void publish_estimates(ObserverData *d)
{
    if (d->identifier != IDENTIFIER_OFF && d->identifier_form == FORM_INFORMATION)
        info_solve(&d->info); /* keeps the previous estimate if it cannot solve */
    const double (*delta)[MAX_L] = identified_delta(d);
    const int with_std = d->identifier != IDENTIFIER_OFF && d->identifier_form == FORM_INFORMATION;
    memset(d->theta_std, 0, sizeof d->theta_std);
    d->b_std = 0.0;
    if (d->nominal_model == NOMINAL_JOINT) {
        for (int k = 0; k < JOINT_BASIS_SIZE; ++k) d->theta_hat[0][k] = d->c_nominal[k];
        d->b_hat = d->b;
        for (int j = 0; j < d->m; ++j) {
            const int k = d->selected[j];
            const double std = with_std ? d->info.std_error[0][j] : 0.0;
            /* u enters as + (b - bbar) u: Delta = b - bbar there */
            if (k == JOINT_INPUT) {
                d->b_hat = d->b + delta[0][j];
                d->b_std = std;
            } else {
                d->theta_hat[0][k] = d->c_nominal[k] - delta[0][j];
                d->theta_std[0][k] = std;
            }
        }
    } else {
        for (int i = 0; i < d->n; ++i) {
            for (int k = 0; k < d->l; ++k) d->theta_hat[i][k] = d->theta_nominal[i][k];
            for (int j = 0; j < d->m; ++j) {
                d->theta_hat[i][d->selected[j]] += delta[i][j];
                if (with_std) d->theta_std[i][d->selected[j]] = d->info.std_error[i][j];
            }
        }
    }
    if (d->identifier_form == FORM_PAPER) {
        d->gamma_trace = identifier_gamma_trace(&d->id);
        d->excitation = 0.0;
    } else {
        d->gamma_trace = d->info.gamma_trace;
        d->excitation = d->info.excitation;
    }
    d->converged = sto_converged(&d->obs);
}

static ModelStatus complete_gains(ObserverData *d, const ModelLogger *log)
{
    ModelStatus status = MODEL_OK;
    for (int i = 0; i < d->n; ++i) {
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

/* model_feedback applies: the built-in joint's LSM in information form with the
 * regression filtered on both sides, under an implicit scheme. */
static int feedback_on(const ObserverData *d)
{
    return d->model_feedback && d->nominal_model == NOMINAL_JOINT &&
           d->identifier == IDENTIFIER_LSM && d->identifier_form == FORM_INFORMATION &&
           d->filter_regressor && d->scheme != STO_SCHEME_PAPER;
}

/* The significant part of each identified correction (model_feedback.h), kept
 * physical: friction not negative, b within a factor 2 of the nominal. */
static void take_identified_model(ObserverData *d)
{
    for (int j = 0; j < d->m; ++j) {
        const int k = d->selected[j];
        const double delta = d->info.delta[0][j];
        double D = delta * feedback_weight(delta, d->info.std_error[0][j], d->info.active_time);
        if (k == JOINT_INPUT) { /* Delta = b - bbar */
            D = fmin(fmax(D, fmin(-0.5 * d->b, d->b)), fmax(-0.5 * d->b, d->b));
            d->b_model = d->b + D;
        } else { /* Delta = cbar - c */
            if (k == JOINT_VELOCITY || k == JOINT_VELOCITY_SIGN) D = fmin(D, d->c_nominal[k]);
            d->c_model[k] = d->c_nominal[k] - D;
        }
        d->model_delta[j] = D;
    }
}

/* The model the observer predicts with: the nominal one until the LSM has
 * FEEDBACK_START s of data, then the identified one (entering over FEEDBACK_RAMP). */
static void update_model(ObserverData *d)
{
    const double coulomb_before = d->c_model[JOINT_VELOCITY_SIGN];
    d->b_model = d->b;
    memcpy(d->c_model, d->c_nominal, sizeof d->c_model);
    memset(d->model_delta, 0, sizeof d->model_delta);
    if (feedback_on(d) && d->identifier_active) take_identified_model(d);
    /* The implicit corrector learns the Coulomb level the model misses
     * (implicit_twisting.h): keep the total level, model plus learned, where it
     * was instead of relearning it over the next reversals. */
    const double coulomb = d->c_model[JOINT_VELOCITY_SIGN];
    if (coulomb != coulomb_before)
        d->obs.coulomb_learned[0] =
            fmax(d->obs.coulomb_learned[0] + coulomb_before - coulomb, -coulomb);
}

/* Work units (about ns, model_interface.h) of one internal step: upper bounds
 * of the time measured per configuration (docs/observer.md, Limits): the
 * observer per DOF (scheme 3: the bank of linear observers beside it), the
 * identifier's sums over its d (2m with MFF's drift model) regressors and rows,
 * and under scheme 3 the regressors' pass through the followed member's filter. */
static double step_work(const ObserverData *d)
{
    const double n = d->n, m = d->m;
    double work = d->scheme == STO_SCHEME_PAPER      ? 10.0 * n
                  : d->scheme == STO_SCHEME_IMPLICIT ? 15.0 * n
                                                     : 600.0 + 50.0 * n;
    if (d->identifier != IDENTIFIER_OFF) {
        const double dim = d->info.drift && d->identifier_form == FORM_INFORMATION ? 2.0 * m : m;
        work += 100.0 + 8.0 * dim * (n + dim) + (d->scheme == STO_SCHEME_ADAPTIVE ? 50.0 * m : 0.0);
    }
    return work;
}

static ModelStatus initialize(void *data, double start_time, const ModelLogger *log)
{
    (void)start_time;
    ObserverData *d = data;
    if (d->nominal_model == NOMINAL_JOINT && d->n != 1) {
        log->log(log->context, MODEL_ERROR,
                 "n = %d: the built-in joint model (nominal_model = 1) has one degree of freedom; "
                 "use nominal_model = 2 for n > 1", d->n);
        return MODEL_ERROR;
    }
    const int regressors = d->nominal_model == NOMINAL_JOINT ? JOINT_BASIS_SIZE : d->l;
    d->m = 0;
    d->b_hat = d->b;
    d->slot_velocity = d->slot_velocity_sign = MAX_L;
    for (int k = 0; k < regressors; ++k) {
        if (!d->identify[k]) continue;
        if (d->nominal_model == NOMINAL_JOINT && k == JOINT_VELOCITY) d->slot_velocity = d->m;
        if (d->nominal_model == NOMINAL_JOINT && k == JOINT_VELOCITY_SIGN)
            d->slot_velocity_sign = d->m;
        d->selected[d->m++] = k;
    }
    d->slot_input = MAX_L;
    if (d->nominal_model == NOMINAL_JOINT && d->identify_b) {
        d->slot_input = d->m;
        d->selected[d->m++] = JOINT_INPUT;
    }
    if (d->identifier != IDENTIFIER_OFF && d->m == 0) {
        log->log(log->context, MODEL_ERROR,
                 "identifier = %d but no regressor is selected (identify[1..%d] are all false)",
                 d->identifier, regressors);
        return MODEL_ERROR;
    }
    ModelStatus status = complete_gains(d, log);
    if (status == MODEL_ERROR) return status;

    double x1_hat0[MAX_N];
    for (int i = 0; i < MAX_N; ++i)
        x1_hat0[i] = d->start_from_measurement ? d->y[i] : d->x1_hat_start[i];
    sto_init(&d->obs, d->n, d->h, d->alpha1_used, d->alpha2_used, d->tau, x1_hat0, d->x2_hat_start);
    sto_configure(&d->obs, (StoScheme)d->scheme, d->convergence_window);
    adaptive_init(&d->bank, d->h);
    memset(d->shadow, 0, sizeof d->shadow);
    identifier_init(&d->id, (IdentifierKind)d->identifier, d->n, d->m, d->h, d->rho, d->R);
    if (d->identifier == IDENTIFIER_MFF && d->identifier_form == FORM_INFORMATION && d->mff_drift &&
        2 * d->m > ID_MAX_REGRESSORS) {
        log->log(log->context, MODEL_ERROR,
                 "mff_drift needs 2 m <= %d identified regressors, %d are selected (the "
                 "built-in joint's u counts when identify_b is true); select fewer or set "
                 "mff_drift = false", ID_MAX_REGRESSORS, d->m);
        return MODEL_ERROR;
    }
    info_init(&d->info, (IdentifierKind)d->identifier, d->n, d->m, d->h, d->rho, d->R,
              d->mff_drift);
    /* Constant parameters need no tracking: measured on bench/real_measurements.py's
     * open-loop rows (docs/improvements.md), a 0.1 s filter instead of tau's 2 ms took
     * explicit-Euler plant data from 28 % to 12 % and a 12-bit encoder at 10 kHz from
     * 26 % to 1.7 %. */
    const int lsm = d->identifier == IDENTIFIER_LSM && d->identifier_form == FORM_INFORMATION;
    d->identifier_gain = !lsm                    ? d->obs.filter_gain
                         : d->tau_identifier > 0 ? -expm1(-d->h / d->tau_identifier)
                                                 : 1.0;
    memset(d->phi_filtered, 0, sizeof d->phi_filtered);
    memset(d->phi_previous, 0, sizeof d->phi_previous);
    memset(d->velocity_before, 0, sizeof d->velocity_before);
    d->input_before = d->u;
    memset(d->phi_now, 0, sizeof d->phi_now);
    memset(d->z_identifier, 0, sizeof d->z_identifier);
    d->identifier_active = 0;
    memcpy(d->c_model, d->c_nominal, sizeof d->c_model);
    update_model(d);
    memset(d->model_shadow, 0, sizeof d->model_shadow);
    d->model_z = 0.0;
    d->work_per_step = step_work(d);
    d->reset_seen = d->identifier_reset;
    publish_estimates(d);
    return status;
}

static double internal_step(const void *data) { return ((const ObserverData *)data)->h; }

static double max_work(const void *data) { return ((const ObserverData *)data)->max_work; }

static double work_per_step(const void *data)
{
    return ((const ObserverData *)data)->work_per_step;
}

static uint64_t max_internal_steps(const void *data)
{
    return (uint64_t)((const ObserverData *)data)->max_internal_steps;
}

/* Restarts identification from the nominal parameters (and the observer's model). */
static void restart_identifier(ObserverData *d)
{
    identifier_init(&d->id, (IdentifierKind)d->identifier, d->n, d->m, d->h, d->rho, d->R);
    info_reset(&d->info);
    d->identifier_active = 0;
    update_model(d);
}

/* What depends only on the inputs held over the communication step: the
 * nominal acceleration (the joint: affine in the velocity, its position part
 * with the sin evaluated here) and the selected regressors (the joint: all
 * but the velocity ones, which come from the observer's trace). */
static void nominal_model(const ObserverData *d, StoAcceleration acceleration[MAX_N],
                          double regressor[MAX_L])
{
    memset(regressor, 0, MAX_L * sizeof *regressor);
    if (d->nominal_model == NOMINAL_JOINT) {
        joint_position_basis(d->y[0], regressor);
        regressor[JOINT_INPUT] = d->u;
        acceleration[0] = joint_acceleration(d->b_model, d->c_model, d->u, regressor);
    } else {
        for (int i = 0; i < d->n; ++i) {
            double a = d->F[i];
            for (int k = 0; k < d->l; ++k) a += d->theta_nominal[i][k] * d->phi[k];
            acceleration[i] = (StoAcceleration){.held = a, .point = 0.0, .viscous = 0.0,
                                                .coulomb = 0.0};
        }
        memcpy(regressor, d->phi, MAX_L * sizeof *regressor);
    }
}

static void hold_inputs(ObserverData *d, StoAcceleration acceleration[MAX_N])
{
    double regressor[MAX_L];
    nominal_model(d, acceleration, regressor);
    if (d->identifier != IDENTIFIER_OFF)
        for (int j = 0; j < d->m; ++j) d->phi_now[j] = regressor[d->selected[j]];
}

/* The regressor of step k of a trace: the joint's velocity entries.  The
 * implicit schemes take the previous sample's regressor, to match the
 * injection, a second difference over the two intervals around that sample:
 * - its Coulomb entry becomes the mean sign around it (implicit_mean_sign)
 *   once the velocity after it is known, where the sign is hard (a smoothed
 *   expected sign of a linear member is left as it is);
 * - its input entry becomes the mean of the inputs held over the two
 *   intervals, as the nominal acceleration takes them: the input held after
 *   the sample alone leads the injection by half a sample, which leaked
 *   (b - bbar) h/2 u' into the other estimates (1 kHz, noise-free, J -10 %
 *   and +10 %: the viscous estimate 2.9 % and 0.02 % off, now 1.4 % and 1.2 %). */
static void take_velocity(ObserverData *d, const StoTrace *trace, int k)
{
    const double v = trace->velocity[0][k];
    d->phi_now[d->slot_velocity] = v;
    d->phi_now[d->slot_velocity_sign] = trace->velocity_sign[0][k];
    if (d->scheme == STO_SCHEME_PAPER) return;
    const int slot = d->slot_velocity_sign;
    if (slot < MAX_L && fabs(d->phi_previous[slot]) == 1.0)
        d->phi_previous[slot] = implicit_mean_sign(d->velocity_before[0], d->velocity_before[1], v);
    d->velocity_before[0] = d->velocity_before[1];
    d->velocity_before[1] = v;
    if (d->slot_input < MAX_L) {
        const double input = d->phi_previous[d->slot_input];
        d->phi_previous[d->slot_input] = 0.5 * (d->input_before + input);
        d->input_before = input;
    }
}

/* Whether the identifier starts at this sample (time t); restarts its filters if so. */
static int start_identifier(ObserverData *d, double t)
{
    d->identifier_active = t >= d->t_id &&
                           (d->identifier_start == START_AT_T_ID ||
                            (sto_converged(&d->obs) &&
                             (d->scheme != STO_SCHEME_ADAPTIVE || adaptive_settled(&d->bank, d->n))));
    if (d->identifier_active) {
        /* Both filters start from zero together: z = Delta phi then holds for
         * the filtered pair exactly, with no trace of the observer's transient. */
        memset(d->phi_filtered, 0, sizeof d->phi_filtered);
        memset(d->z_identifier, 0, sizeof d->z_identifier);
        memset(d->shadow, 0, sizeof d->shadow);
        memset(d->model_shadow, 0, sizeof d->model_shadow);
        d->model_z = 0.0;
        if (d->scheme == STO_SCHEME_ADAPTIVE) adaptive_follow_published(&d->bank);
    }
    return d->identifier_active;
}

/* The identifier over the `count` steps just observed (m constant: small_loops.h). */
KERNEL identify_run(ObserverData *d, const StoTrace *trace, int count, const int m)
{
    /* The implicit scheme's injection belongs to the previous sample (its
     * corrector runs one sample behind), so its regressor is taken one sample
     * back as well. */
    const double *sample = d->scheme == STO_SCHEME_PAPER ? d->phi_now : d->phi_previous;
    const double g = d->identifier_gain;
    /* Scheme 3 following a linear member: its injection is the perturbation
     * through the member's filter G, so the regressor passes G as well. */
    const int adaptive = d->scheme == STO_SCHEME_ADAPTIVE;
    const AdaptiveGains *G = adaptive && d->bank.follow != ADAPTIVE_SUPER_TWISTING
                                 ? &d->bank.gains[d->bank.follow]
                                 : NULL;
    const double(*z_source)[STO_RUN_MAX] = adaptive ? trace->z_identify : trace->z_eq;
    IdSample samples[STO_RUN_MAX];
    for (int i = 0; i < d->n; ++i) { /* z side: DOF by DOF, each over the run */
        double z = d->z_identifier[i];
        if (d->filter_regressor) { /* the same filter on both sides of z = Delta phi */
            for (int k = 0; k < count; ++k) samples[k].z[i] = z += g * (z_source[i][k] - z);
        } else {
            for (int k = 0; k < count; ++k) samples[k].z[i] = trace->z_filtered[i][k];
        }
        d->z_identifier[i] = z;
    }
    const int feedback = feedback_on(d);
    for (int k = 0; k < count; ++k) { /* regressor side */
        double *phi = samples[k].phi;
        take_velocity(d, trace, k);
        if (feedback) { /* the injection against the nominal model: + D phi, filtered alike */
            double shift = 0.0;
            UNROLL for (int j = 0; j < m; ++j) shift += d->model_delta[j] * sample[j];
            if (G) shift = adaptive_shadow_step(G, d->h, d->model_shadow, shift);
            d->model_z += g * (shift - d->model_z);
            samples[k].z[0] += d->model_z;
        }
        if (G) {
            UNROLL for (int j = 0; j < m; ++j) {
                const double through_g = adaptive_shadow_step(G, d->h, d->shadow[j], sample[j]);
                phi[j] = d->filter_regressor
                             ? (d->phi_filtered[j] += g * (through_g - d->phi_filtered[j]))
                             : through_g;
                d->phi_previous[j] = d->phi_now[j];
            }
        } else if (d->filter_regressor) {
            UNROLL for (int j = 0; j < m; ++j) {
                phi[j] = d->phi_filtered[j] += g * (sample[j] - d->phi_filtered[j]);
                d->phi_previous[j] = d->phi_now[j];
            }
        } else {
            UNROLL for (int j = 0; j < m; ++j) {
                phi[j] = sample[j];
                d->phi_previous[j] = d->phi_now[j];
            }
        }
    }
    if (d->identifier_form == FORM_PAPER) identifier_run(&d->id, samples, count);
    else info_run(&d->info, samples, count);
}

static void advance(void *data, double start_time, uint64_t k, uint64_t k_end)
{
    ObserverData *d = data;
    StoAcceleration acceleration[MAX_N];
    hold_inputs(d, acceleration);
    const int identifying = d->identifier != IDENTIFIER_OFF;
    if (identifying && d->identifier_reset != d->reset_seen) {
        d->reset_seen = d->identifier_reset;
        if (d->identifier_reset) restart_identifier(d);
    }
    StoTrace trace;
    while (k < k_end) {
        /* Runs of up to STO_RUN_MAX steps; single steps while the identifier
         * waits to start, as its start condition is checked after each. */
        const uint64_t left = k_end - k;
        const int count = identifying && !d->identifier_active ? 1
                          : left < STO_RUN_MAX             ? (int)left
                                                           : STO_RUN_MAX;
        if (d->scheme == STO_SCHEME_ADAPTIVE)
            adaptive_run(&d->obs, &d->bank, d->y, acceleration, count, &trace);
        else
            sto_run(&d->obs, d->y, acceleration, count, &trace);
        if (identifying) {
            if (d->identifier_active || start_identifier(d, start_time + (double)k * d->h)) {
                WITH_CONSTANT_M(d->m, identify_run, d, &trace, count);
            } else { /* the delay line still moves */
                take_velocity(d, &trace, 0);
                memcpy(d->phi_previous, d->phi_now, sizeof d->phi_previous);
            }
        }
        k += count;
    }
}

/* Why DOF i's estimate is not finite: a nominal acceleration that overflows
 * (the inputs or nominal parameters), a measurement out of range, else the
 * discretization (h, gains). */
static void explain_divergence(const ObserverData *d, double t, int i, const ModelLogger *log)
{
    StoAcceleration acceleration[MAX_N];
    double regressor[MAX_L];
    nominal_model(d, acceleration, regressor);
    const StoAcceleration a = acceleration[i];
    if (!(fabs(a.held + a.point) < 1e300) || !isfinite(a.viscous) || !isfinite(a.coulomb)) {
        if (d->nominal_model == NOMINAL_JOINT)
            log->log(log->context, MODEL_ERROR,
                     "observer: the nominal acceleration b u - c psi(y) = %g at t = %g is out of "
                     "floating-point range (b = %g, u = %g, y[1] = %g): the input or the nominal "
                     "parameters are too large", a.held + a.point, t, d->b, d->u, d->y[0]);
        else
            log->log(log->context, MODEL_ERROR,
                     "observer: the nominal acceleration F[%d] + theta_nominal phi = %g at t = %g "
                     "is out of floating-point range (F[%d] = %g): the inputs F, phi or "
                     "theta_nominal are too large", i + 1, a.held, t, i + 1, d->F[i]);
    } else if (!(fabs(d->y[i]) < 1e300)) {
        log->log(log->context, MODEL_ERROR,
                 "observer: the measurement y[%d] = %g at t = %g is too large to observe",
                 i + 1, d->y[i], t);
    } else {
        log->log(log->context, MODEL_ERROR,
                 "observer diverged at t = %g: x1_hat[%d] = %g, x2_hat[%d] = %g (reduce h or "
                 "the gains)", t, i + 1, d->obs.x1_hat[i], i + 1, d->obs.x2_hat[i]);
    }
}

static ModelStatus communication_point(void *data, double t, const ModelLogger *log)
{
    ObserverData *d = data;
    if (d->scheme == STO_SCHEME_ADAPTIVE) adaptive_outputs(&d->obs, &d->bank);
    else sto_update_outputs(&d->obs);
    publish_estimates(d);
    update_model(d);
    for (int i = 0; i < d->n; ++i) {
        if (!isfinite(d->obs.x1_hat[i]) || !isfinite(d->obs.x2_hat[i])) {
            explain_divergence(d, t, i, log);
            return MODEL_ERROR;
        }
    }
    if (!isfinite(d->gamma_trace)) {
        log->log(log->context, MODEL_ERROR,
                 "identifier diverged at t = %g: trace(Gamma) = %g (explicit Euler needs "
                 "h |Gamma| |phi|^2 < 2; increase rho or reduce h)", t, d->gamma_trace);
        return MODEL_ERROR;
    }
    return MODEL_OK;
}

/* A deserialized state, field by field (model_interface.h): what initialize
 * derives from the parameters must be what it derives from the state's own;
 * the counters the steps move must lie in their ranges; every double not
 * listed must be finite. */
#define D(field) DERIVED_FIELD(ObserverData, field)
#define I(field, lo, hi) STATE_FIELD(ObserverData, field, FIELD_INT, lo, hi)
#define U(field) STATE_FIELD(ObserverData, field, FIELD_UNSIGNED, 0, 4294967295.0)
static const StateField STATE_FIELDS[] = {
    D(m), D(selected), D(slot_velocity), D(slot_velocity_sign), D(slot_input),
    D(identifier_gain), I(reset_seen, 0, 1),
    D(obs.n), D(obs.h), D(obs.h_squared), D(obs.inverse_h_squared), D(obs.alpha1),
    D(obs.alpha2), D(obs.filter_gain), D(obs.rate_gain), D(obs.scheme), I(obs.primed, 0, 1),
    I(obs.reversal_age, -1, IMPLICIT_REVERSAL_SAMPLES - 1),
    I(obs.smooth_samples, 0, IMPLICIT_SMOOTH_SAMPLES),
    D(bank.count), D(bank.gain), D(bank.stride), D(bank.span), D(bank.velocity_gain),
    D(bank.start_limit), D(bank.gains), D(bank.fine),
    I(bank.zoom_index, -1, (ADAPTIVE_MAX_MEMBERS - 1) * ADAPTIVE_FINE),
    I(bank.center, -1, ADAPTIVE_MAX_MEMBERS - 1), I(bank.started, 0, 1), U(bank.waited),
    U(bank.age),
    I(bank.selected, ADAPTIVE_SUPER_TWISTING, ADAPTIVE_MAX_MEMBERS + ADAPTIVE_ZOOM - 1),
    I(bank.published, ADAPTIVE_SUPER_TWISTING, ADAPTIVE_MAX_MEMBERS + ADAPTIVE_ZOOM - 1),
    I(bank.perturbation, ADAPTIVE_SUPER_TWISTING, ADAPTIVE_MAX_MEMBERS - 1),
    I(bank.follow, ADAPTIVE_SUPER_TWISTING, ADAPTIVE_MAX_MEMBERS - 1),
    D(id.kind), D(id.rows), D(id.m), D(id.h), D(id.h_log_r),
    D(info.rows), D(info.m), D(info.drift), D(info.h), D(info.rho), D(info.lambda),
    D(info.one_minus_lambda_rho), D(info.forgetting_rate), D(info.anchor_interval),
    I(info.anchor_age, 0, INFO_ANCHOR_MAX_INTERVAL),
    STATE_FIELD(ObserverData, info.reference_factor, FIELD_ANY, 0, 0), D(info.reference_lambda),
    D(info.reference_pull), D(info.rest_lambda), D(info.rest_pull), D(info.skip_threshold),
    D(info.batch_gain), D(info.power_gain), I(info.std_age, 0, INFO_STD_INTERVAL),
    D(info.blocks.rows), D(info.blocks.m), D(info.blocks.pairs), D(info.blocks.first),
    D(info.blocks.second), D(info.blocks.stage_gain_per_second),
    /* the doubles, named by their struct */
    REAL_FIELDS(ObserverData, obs), REAL_FIELDS(ObserverData, bank), REAL_FIELDS(ObserverData, id),
    REAL_FIELDS(ObserverData, info.blocks), REAL_FIELDS(ObserverData, info),
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
    if (!adaptive_valid(&d->bank, d->n)) {
        log->log(log->context, MODEL_ERROR, "deserialized FMU state: an index of bank (center, "
                 "zoom_index, selected, published, perturbation or follow) is not one of its %d "
                 "members; state refused", d->bank.count);
        return MODEL_ERROR;
    }
    if (d->info.anchor_age > d->info.anchor_interval) {
        log->log(log->context, MODEL_ERROR, "deserialized FMU state: info.anchor_age = %d exceeds "
                 "info.anchor_interval = %d; state refused", d->info.anchor_age,
                 d->info.anchor_interval);
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
    .state_fields = STATE_FIELDS,
    .n_state_fields = sizeof STATE_FIELDS / sizeof STATE_FIELDS[0],
    .check_restored = check_restored,
};
