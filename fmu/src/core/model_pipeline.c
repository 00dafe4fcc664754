#include "model_pipeline.h"

#include "small_solve.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "box_projection.h"
#include "observer_scheme.h"

#define MAX_N MP_MAX_COORDINATES

static int refuse(char *error, size_t size, const char *format, ...)
{
    if (error && size) {
        va_list args;
        va_start(args, format);
        vsnprintf(error, size, format, args);
        va_end(args);
    }
    return -1;
}

int mp_init(ModelPipeline *p, const TermProgram *program, const double alpha1[],
            const double alpha2[], const double y[], char *error, size_t error_size)
{
    const int n = program->n;
    if (n > MAX_N)
        return refuse(error, error_size, "the model has %d coordinates: this FMU observes at "
                      "most %d", n, MAX_N);
    if (p->scheme != STO_SCHEME_IMPLICIT && p->scheme != STO_SCHEME_ADAPTIVE)
        return refuse(error, error_size, "scheme = %d: 2 (implicit) or 3 (noise-adaptive)",
                      p->scheme);
    if (p->identifier != 0 && p->identifier != IDENTIFIER_LSM && p->identifier != IDENTIFIER_MFF)
        return refuse(error, error_size, "identifier = %d: 0 (off), 1 (LSM) or 2 (MFF)",
                      p->identifier);
    if (p->regression != MP_REGRESSION_OBSERVER && p->regression != MP_REGRESSION_WINDOW)
        return refuse(error, error_size, "regression = %d: 0 (the observer's velocities) or 1 "
                      "(a fixed-lag window)", p->regression);
    if (fl_init(&p->window, n, program->m, program->inputs_held, p->h))
        return refuse(error, error_size, "the fixed-lag window refused h = %g", p->h);
    /* the nonlinear entries of the positions and inputs (no derivatives) pass the window
     * as functions of the samples, as the equations' own terms do; one of positions and
     * held inputs is neither a sample's function nor a staircase's: at the smoothed
     * sample, as the entries with derivatives */
    p->terms_unwindowed = 0;
    memset(p->window_term, -1, sizeof p->window_term);
    for (int i = 0; i < n; ++i)
        for (int k = 0; k <= program->p; ++k) {
            const int kind = tp_entry_kind(program, i, k);
            const int positions = (kind & TP_READS_POSITIONS) != 0;
            const int held = program->inputs_held && (kind & TP_READS_INPUTS);
            if (!(kind & TP_NONLINEAR) || (kind & TP_READS_DERIVATIVES) || (positions && held))
                continue;
            const int term = fl_add_term(&p->window, held, i * (TP_MAX_PARAMETERS + 1) + k);
            if (term < 0) ++p->terms_unwindowed;
            else p->window_term[i][k] = term;
        }
    int coulomb = 0;
    for (int i = 0; i < n; ++i) coulomb |= p->sign_velocities[i] = tp_sign_velocities(program, i);
    if (coulomb) fl_lead(&p->window); /* to see reversals ahead of the centre */
    memset(p->lead_velocity, 0, sizeof p->lead_velocity);
    memset(p->since_reversal, 0, sizeof p->since_reversal);
    memset(p->speed_square, 0, sizeof p->speed_square);
    p->speed_samples = 0.0;
    if (!(p->tau_identifier >= 0.0) || !isfinite(p->tau_identifier) ||
        !(p->statistics_interval >= 0.0) || !isfinite(p->statistics_interval))
        return refuse(error, error_size, "tau_identifier = %g and statistics_interval = %g must "
                      "be finite and >= 0", p->tau_identifier, p->statistics_interval);
    const double zero[MAX_N] = {0};
    memset(p->obs, 0, sizeof p->obs);
    memset(p->bank, 0, sizeof p->bank);
    for (int g = 0; g < mp_groups(n); ++g) {
        const int first = g * MP_GROUP_SIZE;
        st_init(&p->obs[g], mp_group_size(n, g), p->h, alpha1 + first, alpha2 + first,
                 MP_INJECTION_TAU, y + first, zero);
        st_configure(&p->obs[g], (StoScheme)p->scheme, MP_CONVERGENCE_WINDOW);
        if (p->scheme == STO_SCHEME_ADAPTIVE) na_init(&p->bank[g], p->h, NULL);
    }
    p->gain = p->tau_identifier > 0.0 ? -expm1(-p->h / p->tau_identifier) : 1.0;
    p->warm_up = (int)fmin(ceil(MP_WARM_UP * p->tau_identifier / p->h), 1e9);
    p->warm_samples = 0;
    memset(p->velocity, 0, sizeof p->velocity);
    memset(p->nominal_acceleration, 0, sizeof p->nominal_acceleration);
    p->singular_steps = 0.0;
    p->identifying = p->started = 0;
    memset(p->Y0, 0, sizeof p->Y0);
    memset(p->velocity_filtered, 0, sizeof p->velocity_filtered);
    memset(&p->Y, 0, sizeof p->Y);
    memset(p->z, 0, sizeof p->z);
    memset(&p->id, 0, sizeof p->id);
    p->nonfinite = MP_FINITE;
    p->nonfinite_equation = p->nonfinite_entry = 0;
    p->nonfinite_time = 0.0;
    if (p->identifier &&
        ri_init_dense(&p->id, (IdentifierKind)p->identifier, n, program->p, NULL, p->h, p->rho, p->R,
                       NULL))
        return refuse(error, error_size, "the identifier refused its settings (h = %g, rho = %g, "
                      "R = %g): rho > 0, and 0 < R < 1 for MFF", p->h, p->rho, p->R);
    sj_init(&p->statistics, p->identifier ? program->p : 1,
            sj_interval_steps(p->statistics_interval, p->h), SJ_BUDGET);
    return 0;
}

/* Every entry (k <= p) of every equation at the sample with q'' = 0 (e0) and
 * each acceleration's coefficient A[j] = entries(q'' = e_j) - e0. */
typedef struct {
    double e0[MAX_N][TP_MAX_PARAMETERS + 1];
    double A[MAX_N][MAX_N][TP_MAX_PARAMETERS + 1]; /* [j][i][k] */
} AffineEntries;

static void affine_entries(const TermProgram *program, TpSample *s, AffineEntries *out)
{
    const int n = program->n, p = program->p;
    memset(s->qdd, 0, sizeof s->qdd);
    for (int i = 0; i < n; ++i)
        for (int k = 0; k <= p; ++k) out->e0[i][k] = tp_entry(program, s, i, k);
    for (int j = 0; j < n; ++j) {
        s->qdd[j] = 1.0;
        for (int i = 0; i < n; ++i)
            for (int k = 0; k <= p; ++k)
                out->A[j][i][k] = tp_entry(program, s, i, k) - out->e0[i][k];
        s->qdd[j] = 0.0;
    }
}

/* The equations at the nominal parameters, M a = b, solved for the accelerations
 * by Gaussian elimination with partial pivoting.  Returns 0, or -1 (a = 0) for a
 * singular or non-finite M. */
static int nominal_acceleration(const TermProgram *program, const AffineEntries *e, double a[])
{
    const int n = program->n, p = program->p;
    double M[MAX_N][MAX_N], b[MAX_N], largest = 0.0;
    for (int i = 0; i < n; ++i) {
        double residual = -e->e0[i][p];
        for (int k = 0; k < p; ++k) residual += program->nominal[k] * e->e0[i][k];
        b[i] = -residual;
        for (int j = 0; j < n; ++j) {
            double m = -e->A[j][i][p];
            for (int k = 0; k < p; ++k) m += program->nominal[k] * e->A[j][i][k];
            M[i][j] = m;
            largest = fmax(largest, fabs(m));
        }
    }
    memset(a, 0, (size_t)n * sizeof a[0]);
    if (!(largest > 0.0) || !isfinite(largest)) return -1;
    double x[MAX_N];
    if (small_solve(n, M, b, x, MP_SINGULAR_PIVOT * largest)) return -1;
    memcpy(a, x, (size_t)n * sizeof a[0]);
    return 0;
}

/* Records the first non-finite value (model_pipeline.h); later ones keep it. */
static void flag_nonfinite(ModelPipeline *p, MpNonfinite what, int equation, int entry, double t)
{
    if (p->nonfinite != MP_FINITE) return;
    p->nonfinite = what;
    p->nonfinite_equation = equation;
    p->nonfinite_entry = entry;
    p->nonfinite_time = isfinite(t) ? t : 0.0;
}

/* The identifier's sums are finite: the diagonals of its information and of its
 * scores' power, and its right-hand side (both matrices are positive semidefinite,
 * so a finite diagonal bounds every entry; the scores carry the residuals, which
 * overflow first where the inputs are huge and the regressors are not). */
static int identifier_finite(const RegressorIdentifier *id)
{
    double sum = 0.0;
    for (int k = 0; k < id->p; ++k) sum += id->P[k][k] + fabs(id->b[k]) + id->score_power[k][k];
    return isfinite(sum);
}

/* One row of every equation (entry[i][k], k = p the known side; filtered) into the
 * identifier in SI parameters, once the warm-up is over; a non-finite row is
 * flagged and kept out of it. */
static void feed_identifier(ModelPipeline *p, const TermProgram *program,
                            double entry[][TP_MAX_PARAMETERS + 1], double t)
{
    const int np = program->p;
    for (int i = 0; i < program->n; ++i) {
        double z = entry[i][np];
        for (int k = 0; k < np; ++k) {
            if (!isfinite(entry[i][k])) flag_nonfinite(p, MP_NONFINITE_ENTRY, i, k, t);
            z -= entry[i][k] * program->nominal[k];
            p->Y.row[i][k] = entry[i][k] / program->scale[k];
        }
        p->z[i] = z;
        if (!isfinite(z)) flag_nonfinite(p, MP_NONFINITE_ENTRY, i, -1, t);
    }
    p->started = 1;
    if (p->nonfinite != MP_FINITE) return; /* the identifier keeps its last finite sums */
    if (p->warm_samples < p->warm_up) {
        ++p->warm_samples;
        return;
    }
    ri_step(&p->id, p->z, &p->Y);
    if (!identifier_finite(&p->id)) flag_nonfinite(p, MP_NONFINITE_IDENTIFIER, 0, 0, t);
    sj_step(&p->statistics);
    sj_schedule(&p->statistics, &p->id); /* on the internal steps, whatever the importer's */
}

/* One sample of the regression at the velocity estimates through G
 * (model_pipeline.h).  G q'' starts at 0 where the other entries start at their
 * values: the rows enter once that transient has decayed (warm_up). */
static void regression_step(ModelPipeline *p, const TermProgram *program, const AffineEntries *e,
                            double t)
{
    const int n = program->n, np = program->p;
    const double g = p->started ? p->gain : 1.0; /* the first sample: no transient */
    double acceleration[MAX_N];
    for (int j = 0; j < n; ++j) {
        const double before = p->velocity_filtered[j];
        p->velocity_filtered[j] += g * (p->velocity[j] - before);
        acceleration[j] = p->started ? (p->velocity_filtered[j] - before) / p->h : 0.0;
    }
    double entry[MAX_N][TP_MAX_PARAMETERS + 1];
    for (int i = 0; i < n; ++i)
        for (int k = 0; k <= np; ++k) {
            /* the acceleration below is G q'' between the last two samples: the other
             * entries are taken there too, as the mean of their filtered values */
            const double before = p->started ? p->Y0[i][k] : e->e0[i][k];
            p->Y0[i][k] += g * (e->e0[i][k] - p->Y0[i][k]);
            double v = 0.5 * (before + p->Y0[i][k]);
            for (int j = 0; j < n; ++j) v += e->A[j][i][k] * acceleration[j];
            entry[i][k] = v;
        }
    feed_identifier(p, program, entry, t);
}

/* The equations (bits 1 << i) whose Coulomb terms hold at the window's centre (the
 * rule of identify's friction rows): every coordinate in their sign() moves there,
 * faster than MP_SLOW_FRACTION of its RMS velocity since the regression began (at
 * rest the friction is stiction, not f_c sign(q')), and has not reversed within the
 * lead on either side of it (judged ahead of the centre, at the lead). */
static int coulomb_holds(ModelPipeline *p, int n, const double centre_velocity[])
{
    const int lead = fl_lead_samples(&p->window);
    int coulomb = 0, moving = 0, equations = 0;
    for (int i = 0; i < n; ++i) coulomb |= p->sign_velocities[i];
    if (!p->started) p->speed_samples = 0.0;
    p->speed_samples += 1.0;
    for (int j = 0; j < n; ++j) {
        if (!(coulomb >> j & 1)) continue;
        const double v = fl_lead_velocity(&p->window, j), c = centre_velocity[j];
        if (!p->started) p->speed_square[j] = 0.0;
        p->speed_square[j] += c * c;
        const double slow = MP_SLOW_FRACTION * MP_SLOW_FRACTION * p->speed_square[j] /
                            p->speed_samples;
        if (fl_settled(&p->since_reversal[j], &p->lead_velocity[j], v, !p->started, 2 * lead) &&
            c * c >= slow)
            moving |= 1 << j;
    }
    for (int i = 0; i < n; ++i)
        if (!(p->sign_velocities[i] & ~moving)) equations |= 1 << i;
    return equations;
}

/* One sample of the window's regression: every entry of the equations at the
 * window's smoothed sample, a fixed lag behind (model_pipeline.h), through G into
 * Y0 (an equation whose Coulomb terms do not hold there left out, as zeros).  G
 * starts at the first row, which satisfies the equations as every later one does: no
 * warm-up. */
static void window_step(ModelPipeline *p, const TermProgram *program, double t)
{
    TpSample s;
    memset(&s, 0, sizeof s);
    double terms[FL_MAX_TERMS];
    fl_at_lag(&p->window, s.q, s.qd, s.qdd, s.u, terms);
    const double g = p->started ? p->gain : 1.0;
    const int holding = coulomb_holds(p, program->n, s.qd);
    for (int i = 0; i < program->n; ++i) {
        const double weight = holding >> i & 1 ? 1.0 : 0.0;
        for (int k = 0; k <= program->p; ++k) {
            const int term = p->window_term[i][k];
            const double v = term >= 0 ? terms[term] : tp_entry(program, &s, i, k);
            p->Y0[i][k] += g * (weight * v - p->Y0[i][k]);
        }
    }
    feed_identifier(p, program, p->Y0, t);
}

/* Every group's bank of linear observers has settled (noise_adaptive.h). */
static int settled(const ModelPipeline *p, int n)
{
    for (int g = 0; g < mp_groups(n); ++g)
        if (!na_settled(&p->bank[g], mp_group_size(n, g))) return 0;
    return 1;
}

void mp_run(ModelPipeline *p, const TermProgram *program, const double y[], const double u[],
            double start_time, unsigned long long k, unsigned long long k_end)
{
    const int n = program->n;
    TpSample s;
    memset(&s, 0, sizeof s);
    memcpy(s.q, y, (size_t)n * sizeof s.q[0]);
    memcpy(s.u, u, (size_t)program->m * sizeof s.u[0]);
    AffineEntries e;
    StoTrace trace;
    int current = 0; /* e holds the entries at (y, p->velocity, u): the regression's of the
                      * last step, which the next step's nominal model takes again */
    for (; k < k_end; ++k) {
        StoAcceleration a[MAX_N];
        memset(a, 0, sizeof a);
        if (p->nominal_model) { /* the interval that starts here, at the last velocities */
            if (!current) {
                memcpy(s.qd, p->velocity, (size_t)n * sizeof s.qd[0]);
                affine_entries(program, &s, &e);
            }
            if (nominal_acceleration(program, &e, p->nominal_acceleration))
                p->singular_steps += 1.0;
            for (int i = 0; i < n; ++i) a[i].held = p->nominal_acceleration[i];
        }
        for (int g = 0; g < mp_groups(n); ++g) {
            const int first = g * MP_GROUP_SIZE, size = mp_group_size(n, g);
            if (p->scheme == STO_SCHEME_ADAPTIVE) {
                na_run(&p->obs[g], &p->bank[g], y + first, a + first, 1, &trace);
                memcpy(p->velocity + first, p->bank[g].velocity,
                       (size_t)size * sizeof p->velocity[0]);
            } else {
                os_run(&p->obs[g], y + first, a + first, 1, &trace);
                for (int i = 0; i < size; ++i) p->velocity[first + i] = trace.velocity[i][0];
            }
        }
        current = 0;
        const double t = start_time + (double)k * p->h;
        const int window = p->identifier && p->regression == MP_REGRESSION_WINDOW;
        if (window) {
            double terms[FL_MAX_TERMS]; /* the terms at this sample (s: y and u) */
            for (int m = 0; m < p->window.terms; ++m) {
                const int tag = p->window.term_tag[m];
                terms[m] = tp_entry(program, &s, tag / (TP_MAX_PARAMETERS + 1),
                                    tag % (TP_MAX_PARAMETERS + 1));
            }
            fl_push(&p->window, y, u, terms);
        }
        for (int i = 0; i < n; ++i)
            if (!isfinite(p->velocity[i])) flag_nonfinite(p, MP_NONFINITE_VELOCITY, i, 0, t);
        if (!p->identifier) continue;
        /* the observer slides, or the bank's members have settled (they track where the
         * super-twisting observer's gains are too small to slide) */
        const int ready = mp_converged(p, n) || (p->scheme == STO_SCHEME_ADAPTIVE && settled(p, n));
        if (!p->identifying && t >= p->t_id && ready) {
            p->identifying = 1;
            p->started = p->warm_samples = 0;
            if (window) {
                fl_choose(&p->window);
                p->warm_samples = p->warm_up; /* window_step needs none */
            }
        }
        if (!p->identifying) continue;
        if (window) {
            if (fl_ready(&p->window)) window_step(p, program, t);
            continue;
        }
        memcpy(s.qd, p->velocity, (size_t)n * sizeof s.qd[0]);
        affine_entries(program, &s, &e);
        current = 1;
        regression_step(p, program, &e, t);
    }
}

void mp_communicate(ModelPipeline *p)
{
    for (int g = 0; g < MP_GROUPS && p->obs[g].n > 0; ++g) {
        if (p->scheme == STO_SCHEME_ADAPTIVE) na_outputs(&p->obs[g], &p->bank[g]);
        else os_update_outputs(&p->obs[g]);
    }
}

int mp_groups(int n) { return (n + MP_GROUP_SIZE - 1) / MP_GROUP_SIZE; }

int mp_group_size(int n, int g)
{
    const int rest = n - g * MP_GROUP_SIZE;
    return rest < MP_GROUP_SIZE ? rest : MP_GROUP_SIZE;
}

double mp_position(const ModelPipeline *p, int i)
{
    return p->obs[i / MP_GROUP_SIZE].x1_hat[i % MP_GROUP_SIZE];
}

double mp_velocity(const ModelPipeline *p, int i)
{
    return p->obs[i / MP_GROUP_SIZE].x2_hat[i % MP_GROUP_SIZE];
}

int mp_converged(const ModelPipeline *p, int n)
{
    for (int g = 0; g < mp_groups(n); ++g)
        if (!st_converged(&p->obs[g])) return 0;
    return 1;
}

_Static_assert(TP_MAX_PARAMETERS <= BP_MAX_UNKNOWNS, "every parameter may have a range");

int mp_estimates(const ModelPipeline *p, const TermProgram *program, double theta[],
                 double std_error[], int held[])
{
    const double *delta = p->identifying ? sj_freshest_estimate(&p->statistics, &p->id) : NULL;
    const int published = p->identifying && p->statistics.completed > 0.0;
    double x[TP_MAX_PARAMETERS], lower[TP_MAX_PARAMETERS], upper[TP_MAX_PARAMETERS];
    int ends[TP_MAX_PARAMETERS] = {0};
    BpResult result = BP_INSIDE;
    for (int k = 0; k < program->p; ++k) {
        x[k] = delta ? delta[k] : 0.0; /* SI, as the identifier's information */
        lower[k] = (program->lower[k] - program->nominal[k]) * program->scale[k];
        upper[k] = (program->upper[k] - program->nominal[k]) * program->scale[k];
    }
    if (delta && program->bounded)
        result = bp_project(program->p, &p->id.P[0][0], RRI_MAX_PARAMETERS, lower, upper, x,
                            ends);
    for (int k = 0; k < program->p; ++k) {
        theta[k] = ends[k] < 0 ? program->lower[k] : ends[k] > 0 ? program->upper[k]
                                                                : program->nominal[k] +
                                                                      x[k] / program->scale[k];
        std_error[k] = published && !ends[k] ? p->statistics.std_error[k] / program->scale[k]
                                             : 0.0;
        if (held) held[k] = ends[k];
    }
    return (int)result;
}

#define OUT_OF_RANGE                                                                          \
    "an input or measurement out of the range of the model's functions (sqrt or log of a "    \
    "negative number, a value near 1e308?); the estimates stop there"

int mp_nonfinite(const ModelPipeline *p, char *message, size_t size)
{
    const double t = p->nonfinite_time;
    const int i = p->nonfinite_equation + 1, k = p->nonfinite_entry + 1;
    switch (p->nonfinite) {
    case MP_NONFINITE_VELOCITY:
        snprintf(message, size, "the velocity estimate of coordinate %d turned non-finite at "
                 "t = %g: an input or measurement beyond the range of the model's functions, "
                 "or the model's nominal values or the step h do not fit the log", i, t);
        break;
    case MP_NONFINITE_ENTRY:
        if (p->nonfinite_entry < 0)
            snprintf(message, size, "the known side of equation %d turned non-finite at t = %g: "
                     "%s", i, t, OUT_OF_RANGE);
        else
            snprintf(message, size, "the term of unknown %d (in the model file's order) in "
                     "equation %d turned non-finite at t = %g: %s", k, i, t, OUT_OF_RANGE);
        break;
    case MP_NONFINITE_IDENTIFIER:
        snprintf(message, size, "the identifier's sums overflowed at t = %g: the equations' "
                 "entries are too large for double precision (inputs or measurements near "
                 "1e154 or beyond: check their units and scaling)", t);
        break;
    default:
        if (size) message[0] = '\0';
        return MP_FINITE;
    }
    return p->nonfinite;
}

void mp_restart_identifier(ModelPipeline *p)
{
    if (!p->identifier) return;
    ri_reset(&p->id);
    sj_reset(&p->statistics);
    p->identifying = p->started = p->warm_samples = 0;
    p->window.chosen = -1; /* chosen again when identification starts */
}
