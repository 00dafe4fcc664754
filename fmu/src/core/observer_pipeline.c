#include "observer_pipeline.h"

#include <math.h>
#include <string.h>

#include "implicit_twisting.h"
#include "model_feedback.h"
#include "small_loops.h"

#define MAX_N OP_MAX_N
#define MAX_L OP_MAX_L

/* theta_hat from the identified corrections.  Built-in joint: the injection
 * is z = xi = -(c - cbar) psi, so Delta = cbar - c and c_hat = cbar - Delta_hat
 * (the paper's 6.2 Delta = [-a1 + a1bar, ...]).  External: theta_hat = thetabar + Delta_hat. */
static const double (*identified_delta(const ObserverPipeline *p))[MAX_L]
{
    return p->identifier_form == OP_FORM_PAPER ? (const double (*)[MAX_L])p->id.delta
                                               : (const double (*)[MAX_L])p->info.delta;
}

/* The information form's identifier is in use. */
static int information(const ObserverPipeline *p)
{
    return p->identifier != IDENTIFIER_OFF && p->identifier_form == OP_FORM_INFORMATION;
}

/* The estimates from the identifier's last solve (ii_finish done). */
static void publish(const ObserverPipeline *p, ObserverEstimates *out)
{
    const int info_form = information(p);
    const double (*delta)[MAX_L] = identified_delta(p);
    memset(out->theta_std, 0, sizeof out->theta_std);
    out->b_std = 0.0;
    if (p->nominal_model == OP_NOMINAL_JOINT) {
        for (int k = 0; k < JOINT_BASIS_SIZE; ++k) out->theta_hat[0][k] = p->c_nominal[k];
        out->b_hat = p->b;
        for (int j = 0; j < p->m; ++j) {
            const int k = p->selected[j];
            const double std = info_form ? p->info.std_error[0][j] : 0.0;
            /* u enters as + (b - bbar) u: Delta = b - bbar there */
            if (k == JOINT_INPUT) {
                out->b_hat = p->b + delta[0][j];
                out->b_std = std;
            } else {
                out->theta_hat[0][k] = p->c_nominal[k] - delta[0][j];
                out->theta_std[0][k] = std;
            }
        }
    } else {
        for (int i = 0; i < p->n; ++i) {
            for (int k = 0; k < p->l; ++k) out->theta_hat[i][k] = p->theta_nominal[i][k];
            for (int j = 0; j < p->m; ++j) {
                out->theta_hat[i][p->selected[j]] += delta[i][j];
                if (info_form) out->theta_std[i][p->selected[j]] = p->info.std_error[i][j];
            }
        }
    }
    if (p->identifier_form == OP_FORM_PAPER) {
        out->gamma_trace = identifier_gamma_trace(&p->id);
        out->excitation = 0.0;
    } else {
        out->gamma_trace = p->info.gamma_trace;
        out->excitation = p->info.excitation;
    }
    out->identifier_active = p->identifier_active;
    out->converged = st_converged(&p->obs);
}

/* Model feedback applies: the built-in joint's LSM in information form with the
 * regression filtered on both sides, under an implicit scheme. */
static int feedback_on(const ObserverPipeline *p)
{
    return p->model_feedback && p->nominal_model == OP_NOMINAL_JOINT &&
           p->identifier == IDENTIFIER_LSM && p->identifier_form == OP_FORM_INFORMATION &&
           p->filter_regressor && p->scheme != STO_SCHEME_PAPER;
}

/* The significant part of each identified correction (model_feedback.h), kept
 * physical: friction not negative, b within a factor 2 of the nominal. */
static void take_identified_model(ObserverPipeline *p)
{
    for (int j = 0; j < p->m; ++j) {
        const int k = p->selected[j];
        const double delta = p->info.delta[0][j];
        double D = delta * mf_weight(&p->feedback, delta, p->info.std_error[0][j],
                                           p->info.active_time);
        if (k == JOINT_INPUT) { /* Delta = b - bbar */
            D = fmin(fmax(D, fmin(-0.5 * p->b, p->b)), fmax(-0.5 * p->b, p->b));
            p->b_model = p->b + D;
        } else { /* Delta = cbar - c */
            if (k == JOINT_VELOCITY || k == JOINT_VELOCITY_SIGN) D = fmin(D, p->c_nominal[k]);
            p->c_model[k] = p->c_nominal[k] - D;
        }
        p->model_delta[j] = D;
    }
}

/* The model the observer predicts with: the nominal one until the LSM has
 * the feedback tuning's start (FEEDBACK_START) s of data, then the identified one
 * (entering over its ramp, FEEDBACK_RAMP). */
static void update_model(ObserverPipeline *p)
{
    const double coulomb_before = p->c_model[JOINT_VELOCITY_SIGN];
    p->b_model = p->b;
    memcpy(p->c_model, p->c_nominal, sizeof p->c_model);
    memset(p->model_delta, 0, sizeof p->model_delta);
    if (feedback_on(p) && p->identifier_active) take_identified_model(p);
    /* The implicit corrector learns the Coulomb level the model misses
     * (implicit_twisting.h): keep the total level, model plus learned, where it
     * was instead of relearning it over the next reversals. */
    const double coulomb = p->c_model[JOINT_VELOCITY_SIGN];
    if (coulomb != coulomb_before)
        p->obs.implicit.coulomb_learned[0] =
            fmax(p->obs.implicit.coulomb_learned[0] + coulomb_before - coulomb, -coulomb);
}

int op_select(ObserverPipeline *p)
{
    const int regressors = p->nominal_model == OP_NOMINAL_JOINT ? JOINT_BASIS_SIZE : p->l;
    p->m = 0;
    p->slot_velocity = p->slot_velocity_sign = MAX_L;
    for (int k = 0; k < regressors; ++k) {
        if (!p->identify[k]) continue;
        if (p->nominal_model == OP_NOMINAL_JOINT && k == JOINT_VELOCITY) p->slot_velocity = p->m;
        if (p->nominal_model == OP_NOMINAL_JOINT && k == JOINT_VELOCITY_SIGN)
            p->slot_velocity_sign = p->m;
        p->selected[p->m++] = k;
    }
    p->slot_input = MAX_L;
    if (p->nominal_model == OP_NOMINAL_JOINT && p->identify_b) {
        p->slot_input = p->m;
        p->selected[p->m++] = JOINT_INPUT;
    }
    return p->m;
}

int op_init(ObserverPipeline *p, const double alpha1[], const double alpha2[],
            const double x1_hat0[], const double x2_hat0[], const ObserverInputs *in,
            ObserverEstimates *out, const StoTuning *tuning)
{
    if (tuning && tuning_problem(tuning)) return -1;
    const StoTuning t = tuning ? *tuning : tuning_default();
    st_init(&p->obs, p->n, p->h, alpha1, alpha2, p->tau, x1_hat0, x2_hat0);
    st_configure(&p->obs, (StoScheme)p->scheme, p->convergence_window);
    p->obs.learning_gain = t.implicit.learning_gain;
    na_init(&p->bank, p->h, &t.bank);
    p->feedback = t.feedback;
    memset(p->shadow, 0, sizeof p->shadow);
    identifier_init(&p->id, (IdentifierKind)p->identifier, p->n, p->m, p->h, p->rho, p->R);
    if (p->identifier == IDENTIFIER_MFF && p->identifier_form == OP_FORM_INFORMATION &&
        p->mff_drift && 2 * p->m > ID_MAX_REGRESSORS)
        return -1;
    ii_init(&p->info, (IdentifierKind)p->identifier, p->n, p->m, p->h, p->rho, p->R,
              p->mff_drift, &t);
    /* Constant parameters need no tracking: the LSM filters the regression over
     * tau_identifier, long enough to keep velocity noise and the plant's
     * discretization mismatch out; MFF tracks and pays a filter's lag, so it
     * keeps the injection's own filter. */
    const int lsm = p->identifier == IDENTIFIER_LSM && p->identifier_form == OP_FORM_INFORMATION;
    p->identifier_gain = !lsm                    ? p->obs.filter_gain
                         : p->tau_identifier > 0 ? -expm1(-p->h / p->tau_identifier)
                                                 : 1.0;
    memset(p->phi_filtered, 0, sizeof p->phi_filtered);
    memset(p->phi_previous, 0, sizeof p->phi_previous);
    memset(p->velocity_before, 0, sizeof p->velocity_before);
    p->input_before = in->u;
    memset(p->phi_now, 0, sizeof p->phi_now);
    memset(p->z_identifier, 0, sizeof p->z_identifier);
    p->identifier_active = 0;
    memcpy(p->c_model, p->c_nominal, sizeof p->c_model);
    update_model(p);
    memset(p->model_shadow, 0, sizeof p->model_shadow);
    p->model_z = 0.0;
    out->b_hat = p->b;
    if (information(p)) ii_solve(&p->info);
    publish(p, out);
    p->publish_pending = 0;
    return 0;
}

void op_restart_identifier(ObserverPipeline *p)
{
    identifier_init(&p->id, (IdentifierKind)p->identifier, p->n, p->m, p->h, p->rho, p->R);
    ii_reset(&p->info);
    p->identifier_active = 0;
    update_model(p);
}

/* The nominal acceleration (the joint: affine in the velocity, its position
 * part with the sin evaluated here) and the regressors (the joint: all but the
 * velocity ones, which come from the observer's trace). */
void op_nominal_model(const ObserverPipeline *p, const ObserverInputs *in,
                      StoAcceleration acceleration[MAX_N], double regressor[MAX_L])
{
    memset(regressor, 0, MAX_L * sizeof *regressor);
    if (p->nominal_model == OP_NOMINAL_JOINT) {
        jm_position_basis(in->y[0], regressor);
        regressor[JOINT_INPUT] = in->u;
        acceleration[0] = jm_acceleration(p->b_model, p->c_model, in->u, regressor);
    } else {
        for (int i = 0; i < p->n; ++i) {
            double a = in->F[i];
            for (int k = 0; k < p->l; ++k) a += p->theta_nominal[i][k] * in->phi[k];
            acceleration[i] = (StoAcceleration){.held = a, .point = 0.0, .viscous = 0.0,
                                                .coulomb = 0.0};
        }
        memcpy(regressor, in->phi, MAX_L * sizeof *regressor);
    }
}

/* The regressor of step k of a trace: the joint's velocity entries.  The
 * implicit schemes take the previous sample's regressor, to match the
 * injection, a second difference over the two intervals around that sample:
 * - its Coulomb entry becomes the mean sign around it (it_mean_sign)
 *   once the velocity after it is known, where the sign is hard (a smoothed
 *   expected sign of a linear member is left as it is);
 * - its input entry becomes the mean of the inputs held over the two
 *   intervals, as the nominal acceleration takes them: the input held after
 *   the sample alone leads the injection by half a sample, which leaks
 *   (b - bbar) h/2 u' into the other estimates. */
static void take_velocity(ObserverPipeline *p, const StoTrace *trace, int k)
{
    const double v = trace->velocity[0][k];
    p->phi_now[p->slot_velocity] = v;
    p->phi_now[p->slot_velocity_sign] = trace->velocity_sign[0][k];
    if (p->scheme == STO_SCHEME_PAPER) return;
    const int slot = p->slot_velocity_sign;
    if (slot < MAX_L && fabs(p->phi_previous[slot]) == 1.0)
        p->phi_previous[slot] = it_mean_sign(p->velocity_before[0], p->velocity_before[1], v);
    p->velocity_before[0] = p->velocity_before[1];
    p->velocity_before[1] = v;
    if (p->slot_input < MAX_L) {
        const double input = p->phi_previous[p->slot_input];
        p->phi_previous[p->slot_input] = 0.5 * (p->input_before + input);
        p->input_before = input;
    }
}

/* Whether the identifier starts at this sample (time t); restarts its filters if so. */
static int start_identifier(ObserverPipeline *p, double t)
{
    p->identifier_active = t >= p->t_id &&
                           (p->identifier_start == OP_START_AT_T_ID ||
                            (st_converged(&p->obs) &&
                             (p->scheme != STO_SCHEME_ADAPTIVE || na_settled(&p->bank, p->n))));
    if (p->identifier_active) {
        /* Both filters start from zero together: z = Delta phi then holds for
         * the filtered pair exactly, with no trace of the observer's transient. */
        memset(p->phi_filtered, 0, sizeof p->phi_filtered);
        memset(p->z_identifier, 0, sizeof p->z_identifier);
        memset(p->shadow, 0, sizeof p->shadow);
        memset(p->model_shadow, 0, sizeof p->model_shadow);
        p->model_z = 0.0;
        if (p->scheme == STO_SCHEME_ADAPTIVE) na_follow_published(&p->bank);
    }
    return p->identifier_active;
}

/* The identifier over the `count` steps just observed (m constant: small_loops.h). */
KERNEL identify_run(ObserverPipeline *p, const StoTrace *trace, int count, const int m)
{
    /* The implicit scheme's injection belongs to the previous sample (its
     * corrector runs one sample behind), so its regressor is taken one sample
     * back as well. */
    const double *sample = p->scheme == STO_SCHEME_PAPER ? p->phi_now : p->phi_previous;
    const double g = p->identifier_gain;
    /* Scheme 3 following a linear member: its injection is the perturbation
     * through the member's filter G, so the regressor passes G as well. */
    const int adaptive = p->scheme == STO_SCHEME_ADAPTIVE;
    const AdaptiveGains *G = adaptive && p->bank.follow != ADAPTIVE_SUPER_TWISTING
                                 ? &p->bank.gains[p->bank.follow]
                                 : NULL;
    const double(*z_source)[STO_RUN_MAX] = adaptive ? trace->z_identify : trace->z_eq;
    IdSample samples[STO_RUN_MAX];
    for (int i = 0; i < p->n; ++i) { /* z side: DOF by DOF, each over the run */
        double z = p->z_identifier[i];
        if (p->filter_regressor) { /* the same filter on both sides of z = Delta phi */
            for (int k = 0; k < count; ++k) samples[k].z[i] = z += g * (z_source[i][k] - z);
        } else {
            for (int k = 0; k < count; ++k) samples[k].z[i] = trace->z_filtered[i][k];
        }
        p->z_identifier[i] = z;
    }
    const int feedback = feedback_on(p);
    for (int k = 0; k < count; ++k) { /* regressor side */
        double *phi = samples[k].phi;
        take_velocity(p, trace, k);
        if (feedback) { /* the injection against the nominal model: + D phi, filtered alike */
            double shift = 0.0;
            UNROLL for (int j = 0; j < m; ++j) shift += p->model_delta[j] * sample[j];
            if (G) shift = na_shadow_step(G, p->h, p->model_shadow, shift);
            p->model_z += g * (shift - p->model_z);
            samples[k].z[0] += p->model_z;
        }
        if (G) {
            UNROLL for (int j = 0; j < m; ++j) {
                const double through_g = na_shadow_step(G, p->h, p->shadow[j], sample[j]);
                phi[j] = p->filter_regressor
                             ? (p->phi_filtered[j] += g * (through_g - p->phi_filtered[j]))
                             : through_g;
                p->phi_previous[j] = p->phi_now[j];
            }
        } else if (p->filter_regressor) {
            UNROLL for (int j = 0; j < m; ++j) {
                phi[j] = p->phi_filtered[j] += g * (sample[j] - p->phi_filtered[j]);
                p->phi_previous[j] = p->phi_now[j];
            }
        } else {
            UNROLL for (int j = 0; j < m; ++j) {
                phi[j] = sample[j];
                p->phi_previous[j] = p->phi_now[j];
            }
        }
    }
    if (p->identifier_form == OP_FORM_PAPER) identifier_run(&p->id, samples, count);
    else ii_run(&p->info, samples, count);
}

/* The identified model: the information form's factor (and the excitation's
 * iteration; the solve keeps the previous estimate if it cannot factor), the
 * estimate where the observer's model takes it, and the model. */
static void model_update(ObserverPipeline *p)
{
    if (information(p)) {
        ii_factor(&p->info);
        if (feedback_on(p) && p->identifier_active) ii_finish(&p->info);
    }
    update_model(p);
}

void op_run(ObserverPipeline *p, const ObserverInputs *in, double start_time, uint64_t k,
            uint64_t k_end, int restart)
{
    /* the model of the step as it was before a restart */
    StoAcceleration acceleration[MAX_N];
    double regressor[MAX_L];
    op_nominal_model(p, in, acceleration, regressor);
    const int identifying = p->identifier != IDENTIFIER_OFF;
    if (identifying)
        for (int j = 0; j < p->m; ++j) p->phi_now[j] = regressor[p->selected[j]];
    if (identifying && restart) {
        op_restart_identifier(p);
        if (information(p)) model_update(p); /* no estimate of the old information */
    }
    StoTrace trace;
    /* In the information form the identified model is updated on the internal
     * steps' clock, after every OP_MODEL_STEPS-th step of the instance, never at
     * the importer's communication points: the runs end there. */
    const int clocked = information(p);
    while (k < k_end) {
        /* Runs of up to STO_RUN_MAX steps; single steps while the identifier
         * waits to start, as its start condition is checked after each. */
        const uint64_t left = k_end - k;
        const uint64_t to_update = OP_MODEL_STEPS - k % OP_MODEL_STEPS;
        const uint64_t most = clocked && to_update < STO_RUN_MAX ? to_update : STO_RUN_MAX;
        const int count = identifying && !p->identifier_active ? 1
                          : left < most                       ? (int)left
                                                              : (int)most;
        if (p->scheme == STO_SCHEME_ADAPTIVE)
            na_run(&p->obs, &p->bank, in->y, acceleration, count, &trace);
        else
            os_run(&p->obs, in->y, acceleration, count, &trace);
        if (identifying) {
            if (p->identifier_active || start_identifier(p, start_time + (double)k * p->h)) {
                WITH_CONSTANT_M(p->m, identify_run, p, &trace, count);
            } else { /* the delay line still moves */
                take_velocity(p, &trace, 0);
                memcpy(p->phi_previous, p->phi_now, sizeof p->phi_previous);
            }
        }
        k += count;
        if (clocked && k % OP_MODEL_STEPS == 0) {
            model_update(p);
            op_nominal_model(p, in, acceleration, regressor); /* the model it took */
        }
    }
}

void op_communicate(ObserverPipeline *p, ObserverEstimates *out)
{
    if (p->scheme == STO_SCHEME_ADAPTIVE) na_outputs(&p->obs, &p->bank);
    else os_update_outputs(&p->obs);
    if (!information(p)) update_model(p); /* the paper's form: the nominal model */
    out->identifier_active = p->identifier_active;
    out->converged = st_converged(&p->obs);
    p->publish_pending = 1;
}

int op_publish(ObserverPipeline *p, ObserverEstimates *out)
{
    if (!p->publish_pending) return 0;
    p->publish_pending = 0;
    if (information(p)) ii_finish(&p->info);
    publish(p, out);
    return 1;
}
