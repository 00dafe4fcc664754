#include "noise_adaptive.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "adaptive_rules.h"
#include "implicit_twisting.h"

typedef double Matrix3[3][3];

static void multiply(Matrix3 a, Matrix3 b, Matrix3 out)
{
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            out[i][j] = a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j];
}

static void transpose(Matrix3 a, Matrix3 out)
{
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) out[i][j] = a[j][i];
}

/* Inverse by cofactors; returns 0 if singular. */
static int invert(Matrix3 a, Matrix3 out)
{
    const double c00 = a[1][1] * a[2][2] - a[1][2] * a[2][1];
    const double c01 = a[1][2] * a[2][0] - a[1][0] * a[2][2];
    const double c02 = a[1][0] * a[2][1] - a[1][1] * a[2][0];
    const double det = a[0][0] * c00 + a[0][1] * c01 + a[0][2] * c02;
    if (!(fabs(det) > 0.0) || !isfinite(det)) return 0;
    out[0][0] = c00 / det;
    out[1][0] = c01 / det;
    out[2][0] = c02 / det;
    out[0][1] = (a[0][2] * a[2][1] - a[0][1] * a[2][2]) / det;
    out[1][1] = (a[0][0] * a[2][2] - a[0][2] * a[2][0]) / det;
    out[2][1] = (a[0][1] * a[2][0] - a[0][0] * a[2][1]) / det;
    out[0][2] = (a[0][1] * a[1][2] - a[0][2] * a[1][1]) / det;
    out[1][2] = (a[0][2] * a[1][0] - a[0][0] * a[1][2]) / det;
    out[2][2] = (a[0][0] * a[1][1] - a[0][1] * a[1][0]) / det;
    return 1;
}

/* Steady-state Kalman gain of x1^- = x1 + h m + h^2 xi, m^- = m + h xi,
 * xi^- = xi + w (variance q), y = x1 + noise (variance 1).  The a-priori
 * covariance X solves the Riccati equation X = A^T X (I + G X)^-1 A + Q with
 * A = F^T, G = H^T H; the structure-preserving doubling algorithm (Chu, Fan
 * and Lin 2005) converges quadratically, in about log2(1/(omega h)) + 10
 * steps, where the plain recursion needs some 30/(omega h): a bank at
 * h = 1e-6 initializes in microseconds instead of seconds. */
static AdaptiveGains steady_state_gains(double h, double omega)
{
    Matrix3 A = {{1.0, 0.0, 0.0}, {h, 1.0, 0.0}, {h * h, h, 1.0}}; /* F^T */
    Matrix3 G = {{1.0, 0.0, 0.0}, {0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}};
    Matrix3 X = {{0.0, 0.0, 0.0}, {0.0, 0.0, 0.0}, {0.0, 0.0, pow(omega, 6.0) * h * h}};
    for (int iteration = 0; iteration < 200; ++iteration) {
        Matrix3 GX, W, Winv, WinvA, AT, AWinvA, WinvG, GAT, AWinvGAT, XWinvA, ATXWinvA;
        multiply(G, X, GX);
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) W[i][j] = (i == j) + GX[i][j];
        if (!invert(W, Winv)) break;
        transpose(A, AT);
        multiply(Winv, A, WinvA);
        multiply(A, WinvA, AWinvA);                /* A_(k+1) = A W^-1 A */
        multiply(Winv, G, WinvG);
        multiply(WinvG, AT, GAT);
        multiply(A, GAT, AWinvGAT);                /* G_(k+1) = G + A W^-1 G A^T */
        multiply(X, WinvA, XWinvA);
        multiply(AT, XWinvA, ATXWinvA);            /* X_(k+1) = X + A^T X W^-1 A */
        double change = 0.0, size = 0.0;
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) {
                change = fmax(change, fabs(ATXWinvA[i][j]));
                size = fmax(size, fabs(X[i][j]));
                X[i][j] += ATXWinvA[i][j];
                G[i][j] += AWinvGAT[i][j];
                A[i][j] = AWinvA[i][j];
            }
        if (change <= 1e-15 * size) break;
    }
    const double S = X[0][0] + 1.0;
    AdaptiveGains g = {.omega = omega, .k1 = X[0][0] / S, .k2 = X[1][0] / S, .k3 = X[2][0] / S,
                       .innovation_variance = S};
    /* the a-posteriori velocity variance: X11 - X10^2 / S */
    g.velocity_std = sqrt(fmax(0.0, X[1][1] - X[1][0] * X[1][0] / S));
    return g;
}

int na_init(AdaptiveBank *bank, double h, const AdaptiveTuning *tuning)
{
    memset(bank, 0, sizeof *bank);
    const int valid = !tuning || !tuning_adaptive_problem(tuning);
    bank->tuning = valid && tuning ? *tuning : tuning_default().bank;
    const AdaptiveTuning *t = &bank->tuning;
    bank->gain = h < t->window ? h / t->window : 1.0;
    const double stride = ceil(t->secant_time / (ADAPTIVE_SLOTS * h));
    bank->stride = stride > ADAPTIVE_MAX_STRIDE ? ADAPTIVE_MAX_STRIDE : stride < 1.0 ? 1 : (int)stride;
    bank->span = bank->stride * ADAPTIVE_SLOTS * h;
    bank->velocity_gain = fmin(1.0, bank->gain * bank->stride);
    const double start = ceil(t->start_time / h);
    bank->start_limit = start > 4e9 ? 4000000000u : start < 1.0 ? 1u : (unsigned)start;
    for (double omega = t->lowest_bandwidth;
         omega * h <= t->highest_bandwidth && bank->count < ADAPTIVE_MAX_MEMBERS; omega *= t->ratio)
    {
        bank->gains[bank->count] = steady_state_gains(h, omega);
        bank->gains[bank->count++].publish_gain = -expm1(-2.0 * h * omega / t->averaging);
    }
    for (int f = 0; bank->count > 0 && f <= (bank->count - 1) * ADAPTIVE_FINE; ++f)
        bank->fine[f] = f % ADAPTIVE_FINE == 0
                            ? bank->gains[f / ADAPTIVE_FINE]
                            : steady_state_gains(h, t->lowest_bandwidth *
                                                        pow(t->ratio, (double)f / ADAPTIVE_FINE));
    for (int i = 0; i < STO_MAX_DOF; ++i) {
        bank->selected[i] = bank->published[i] = bank->perturbation[i] = ADAPTIVE_SUPER_TWISTING;
        bank->center[i] = -1;
        for (int s = 0; s < ADAPTIVE_ZOOM; ++s) bank->zoom_index[i][s] = -1;
    }
    bank->follow = ADAPTIVE_SUPER_TWISTING;
    return valid;
}

/* The super-twisting corrector's innovation variance per unit R on white
 * noise: r = n_k - 3 n_(k-1) + 3 n_(k-2) - n_(k-3) in sliding. */
#define STA_INNOVATION_VARIANCE 20.0

/* A member starts from the super-twisting observer's state at step k of the
 * trace, so that it has no transient of its own. */
static void start_member(AdaptiveMember *m, const StoTrace *trace, int i, int k, StoAcceleration a)
{
    memset(m, 0, sizeof *m);
    m->z1 = trace->position[i][k];
    m->mid = trace->mid_velocity[i][k];
    m->xi = 0.0; /* the saturated injection would be a transient of +-alpha1 */
    m->x2_now = trace->velocity[i][k];
    m->a_free = a.held - a.viscous * m->x2_now;
    m->a_mean = st_acceleration(a, m->x2_now, trace->velocity_sign[i][k]);
    m->averaged = m->published = trace->z_filtered[i][k]; /* the published perturbation */
}

/* One sample of a linear member: corrects the interval that ends at y and
 * records the acceleration of the interval that starts.  Returns r. */
static inline double member_step(AdaptiveMember *m, const AdaptiveGains *g, double y,
                                 StoAcceleration a, double h, double h2)
{
    const double r = y - m->z1 - h * m->mid - h2 * (m->a_mean + m->xi);
    m->mid += h * (m->a_mean + m->xi) + g->k2 * r;
    m->xi += g->k3 * r;
    m->z1 = y - (1.0 - g->k1) * r;
    m->x2_now = it_advance(m->mid, m->xi, a, h, &m->a_free, &m->a_mean);
    return r;
}

/* An exponentially weighted mean square, growing windows first (no bias
 * toward the zero start). */
static inline void weigh(double *mean_square, double *samples, double value, double gain)
{
    const double g = *samples * gain < 1.0 ? 1.0 / ++*samples : gain;
    *mean_square += g * (value - *mean_square);
}

/* The zoom members surround member c on the fine grid: the ones already there
 * keep running, the others start from member c's state and statistics. */
static void zoom_to(AdaptiveBank *bank, int i, int c)
{
    int wanted[ADAPTIVE_ZOOM], kept[ADAPTIVE_ZOOM];
    AdaptiveMember moved[ADAPTIVE_ZOOM];
    int w = 0;
    const int last = (bank->count - 1) * ADAPTIVE_FINE;
    for (int d = -(ADAPTIVE_FINE - 1); d < 0; ++d) {
        const int f = c * ADAPTIVE_FINE + d;
        wanted[w++] = f >= 0 && f <= last ? f : -1;
    }
    for (int s = 0; s < ADAPTIVE_ZOOM; ++s) {
        kept[s] = 0;
        for (int t = 0; t < ADAPTIVE_ZOOM && wanted[s] >= 0; ++t)
            if (bank->zoom_index[i][t] == wanted[s]) {
                moved[s] = bank->zoom[i][t];
                kept[s] = 1;
            }
    }
    for (int s = 0; s < ADAPTIVE_ZOOM; ++s) {
        bank->zoom[i][s] = kept[s] ? moved[s] : bank->member[i][c];
        bank->zoom_index[i][s] = wanted[s];
    }
    bank->center[i] = c;
}

/* What the observers are compared with at a stride's start (see the header). */
typedef struct {
    double velocity;     /* at the middle of the last span (from the first full span) */
    double perturbation; /* mean over the span before (from the second full span) */
} AdaptiveMeasured;

/* At a stride's start (`tick` strides since the start): compares an
 * observer's velocity of ADAPTIVE_SLOTS / 2 strides ago and its published
 * perturbation of ADAPTIVE_PERTURBATION_DELAY strides ago with the measured
 * ones (once there are), and keeps both of now. */
static inline void track_strides(AdaptiveStatistics *st, const AdaptiveBank *bank,
                                 unsigned tick, AdaptiveMeasured measured, double velocity,
                                 double perturbation)
{
    enum { KEPT = ADAPTIVE_PERTURBATION_DELAY + 1 };
    if (tick >= ADAPTIVE_SLOTS) {
        const double e = measured.velocity - st->velocity[(tick + ADAPTIVE_SLOTS / 2) % ADAPTIVE_SLOTS];
        weigh(&st->ranking[ADAPTIVE_RANK_VELOCITY], &st->velocity_samples, e * e, bank->velocity_gain);
    }
    if (tick >= ADAPTIVE_RING) {
        const double e = measured.perturbation - st->perturbation[(tick + 1) % KEPT];
        weigh(&st->ranking[ADAPTIVE_RANK_PERTURBATION], &st->perturbation_samples, e * e,
              bank->velocity_gain);
    }
    st->velocity[tick % ADAPTIVE_SLOTS] = velocity;
    st->perturbation[tick % KEPT] = perturbation;
}

/* At a stride's start: closes the stride that ended and returns what the
 * observers are compared with.  The velocity is the secant over the last
 * ADAPTIVE_SLOTS strides minus the nominal model's (mean velocity - velocity
 * at the middle) over them: the velocity at the middle.  The perturbation is
 * the change of that velocity since the secant one span earlier minus the
 * nominal model's change between the two middles, over the span: the mean
 * perturbation between the middles, centred on the span's start.  0 before
 * the first full spans. */
static AdaptiveMeasured measure_strides(AdaptiveSecant *sc, const AdaptiveBank *bank,
                                        unsigned tick, double y, double h)
{
    const unsigned slot = tick % ADAPTIVE_SLOTS; /* also the oldest, tick - ADAPTIVE_SLOTS */
    AdaptiveMeasured measured = {0.0, 0.0};
    if (tick > 0) {
        sc->dv[(tick - 1) % ADAPTIVE_RING] = sc->v;
        sc->dw[(tick - 1) % ADAPTIVE_SLOTS] = sc->w;
    }
    if (tick >= ADAPTIVE_SLOTS) {
        double v = 0.0, w = 0.0, v_middle = 0.0; /* from the span's start */
        for (unsigned t = tick - ADAPTIVE_SLOTS; t < tick; ++t) {
            w += v * bank->stride * h + sc->dw[t % ADAPTIVE_SLOTS];
            v += sc->dv[t % ADAPTIVE_RING];
            if (t == tick - ADAPTIVE_SLOTS / 2 - 1) v_middle = v;
        }
        measured.velocity = (y - sc->y[slot]) / bank->span - (w / bank->span - v_middle);
        if (tick >= ADAPTIVE_RING) {
            /* the nominal velocity change between the two middles: the strides
             * [first, end), one on from the last stride's */
            const unsigned end = tick - ADAPTIVE_SLOTS / 2, first = end - ADAPTIVE_PERTURBATION_LAG;
            if (tick % ADAPTIVE_RING == 0 || tick == ADAPTIVE_RING) {
                sc->nominal = 0.0; /* afresh, so that rounding does not accumulate */
                for (unsigned t = first; t < end; ++t) sc->nominal += sc->dv[t % ADAPTIVE_RING];
            } else {
                sc->nominal += sc->dv[(end - 1) % ADAPTIVE_RING] - sc->dv[(first - 1) % ADAPTIVE_RING];
            }
            const double earlier = sc->middle[(tick - ADAPTIVE_PERTURBATION_LAG) % ADAPTIVE_RING];
            measured.perturbation = (measured.velocity - earlier - sc->nominal) /
                                    (ADAPTIVE_PERTURBATION_SPANS * bank->span);
        }
        sc->middle[tick % ADAPTIVE_RING] = measured.velocity;
    }
    sc->y[slot] = y;
    sc->v = sc->w = 0.0;
    return measured;
}

/* Integrates the nominal acceleration over one step into the running stride. */
static inline void integrate_nominal(AdaptiveSecant *sc, double acceleration, double h, double h2)
{
    sc->w += sc->v * h + 0.5 * acceleration * h2;
    sc->v += acceleration * h;
}

/* E[sign(v) | v_hat] for a velocity error of standard deviation sigma:
 * the Coulomb regressor without the errors-in-variables attenuation that
 * sign(v_hat) has wherever |v| is within the velocity error (regression
 * calibration). */
static inline double expected_sign(double v_hat, double sigma)
{
    return sigma > 0.0 ? erf(v_hat / (1.4142135623730951 * sigma)) : st_sign(v_hat);
}

/* The index of the lowest set bit of a nonzero mask. */
static inline int lowest_bit(unsigned mask)
{
#if defined(__GNUC__) || defined(__clang__)
    return __builtin_ctz(mask);
#else
    int j = 0;
    while (!(mask >> j & 1u)) ++j;
    return j;
#endif
}

/* One step of DOF i's members and zoom members: each predicts, corrects and
 * weighs its innovation; the members average their xi for the published
 * perturbation; at a stride's start (measured given) each is compared with
 * the measured secants. */
static void step_members(AdaptiveBank *bank, int i, unsigned running, double y, StoAcceleration a,
                         double h, double h2, double g, const AdaptiveMeasured *measured,
                         unsigned tick)
{
    const double gain = bank->gain;
    for (; running; running &= running - 1u) { /* the running members (bits), lowest first */
        const int j = lowest_bit(running);
        AdaptiveMember *m = &bank->member[i][j];
        const AdaptiveGains *gj = &bank->gains[j];
        const double r = member_step(m, gj, y, a, h, h2);
        weigh(&m->stats.mean_square, &m->stats.samples, r * r, gain);
        /* xi averaged over `averaging` of the member's time constants
         * 1/omega, in two first-order stages of half that (less noise for the
         * same delay), at least over tau */
        const double averaging = gj->publish_gain < g ? gj->publish_gain : g;
        m->averaged += averaging * (m->xi - m->averaged);
        m->published += averaging * (m->averaged - m->published);
        if (measured) track_strides(&m->stats, bank, tick, *measured, m->x2_now, m->published);
    }
    for (int s = 0; s < ADAPTIVE_ZOOM; ++s) {
        if (bank->zoom_index[i][s] < 0) continue;
        AdaptiveMember *m = &bank->zoom[i][s];
        const double r = member_step(m, &bank->fine[bank->zoom_index[i][s]], y, a, h, h2);
        weigh(&m->stats.mean_square, &m->stats.samples, r * r, gain);
        if (measured) track_strides(&m->stats, bank, tick, *measured, m->x2_now, m->published);
    }
}

/* The members of DOF i that run now but did not (bits of `was_running`) continue
 * from the nearest member that did: state and statistics, as the zoom members start. */
static void wake(AdaptiveBank *bank, int i, unsigned was_running)
{
    const unsigned woken = ar_running_mask(bank, i) & ~was_running;
    for (int j = 0; j < bank->count; ++j) {
        if (!(woken >> j & 1u)) continue;
        int nearest = -1;
        for (int k = 0; k < bank->count; ++k)
            if ((was_running >> k & 1u) && (nearest < 0 || abs(k - j) < abs(nearest - j)))
                nearest = k;
        if (nearest >= 0) bank->member[i][j] = bank->member[i][nearest];
    }
}

/* The zoom members and the running members move to the new centre; a selected
 * zoom member stays selected where its bandwidth still is on the fine grid, else
 * the centre is.  Returns the selection after the move. */
static int recentre(AdaptiveBank *bank, int i, int centre, int selected)
{
    const int fine = selected >= bank->count ? bank->zoom_index[i][selected - bank->count] : -1;
    const unsigned was_running = ar_running_mask(bank, i);
    zoom_to(bank, i, centre);
    wake(bank, i, was_running);
    if (selected < bank->count) return selected;
    selected = centre;
    for (int z = 0; z < ADAPTIVE_ZOOM; ++z)
        if (fine >= 0 && bank->zoom_index[i][z] == fine) selected = bank->count + z;
    return selected;
}

/* What a DOF's run carries from sample to sample: the selected member, the
 * perturbation's source, the published observer and the running members (bits). */
typedef struct {
    int selected, source, published;
    unsigned running;
} AdaptiveChoice;

/* One sample of DOF i once its members run: the super-twisting observer's and the
 * members' statistics, the secants at a stride's start, and there the ranking and
 * the selection (adaptive_rules.h). */
static inline void step_started(SuperTwistingObserver *o, AdaptiveBank *bank, int i, int k,
                                double y, StoAcceleration a, const StoTrace *trace,
                                AdaptiveChoice *c)
{
    const double h = o->h, h2 = o->h_squared, gain = bank->gain;
    const unsigned age = bank->age[i]++;
    const double x2 = trace->velocity[i][k];
    bank->sta_saturation[i] += gain * (trace->saturated[i][k] - bank->sta_saturation[i]);
    const double a_sta = st_acceleration(a, x2, trace->velocity_sign[i][k]);
    weigh(&bank->sta[i].mean_square, &bank->sta[i].samples,
          trace->innovation[i][k] * trace->innovation[i][k], gain);
    const int stride_start = age % (unsigned)bank->stride == 0;
    const unsigned tick = age / (unsigned)bank->stride;
    AdaptiveMeasured measured = {0.0, 0.0};
    if (stride_start) {
        measured = measure_strides(&bank->secant[i], bank, tick, y, h);
        track_strides(&bank->sta[i], bank, tick, measured, x2, trace->z_filtered[i][k]);
    }
    integrate_nominal(&bank->secant[i], a_sta, h, h2);
    step_members(bank, i, c->running, y, a, h, h2, o->filter_gain,
                 stride_start ? &measured : NULL, tick);
    if (!stride_start || age < bank->tuning.min_samples) return;
    const int centre = ar_new_centre(bank, i);
    if (centre >= 0) c->selected = recentre(bank, i, centre, c->selected);
    const AdaptiveSelection choice = ar_select(bank, i, c->selected, c->source);
    c->selected = choice.selected;
    if (choice.source != c->source) { /* its reach runs from now on */
        const unsigned was_running = ar_running_mask(bank, i);
        c->source = bank->perturbation[i] = choice.source;
        wake(bank, i, was_running);
    }
    c->running = ar_running_mask(bank, i);
}

/* What sample k of DOF i publishes: the velocity and position of the published
 * observer, and in the trace the regressors' velocity (the centre member's) and the
 * perturbation of its source. */
static inline void publish_sample(AdaptiveBank *bank, int i, int k, StoTrace *trace,
                                  AdaptiveChoice *c)
{
    const AdaptiveMember *members = bank->member[i];
    const int follow = bank->follow;
    trace->z_identify[i][k] =
        follow == ADAPTIVE_SUPER_TWISTING ? trace->z_eq[i][k] : members[follow].xi;
    c->published = ar_stand_in(bank, i, c->selected, trace->saturated[i][k]);
    bank->velocity[i] = c->published == ADAPTIVE_SUPER_TWISTING
                            ? trace->velocity[i][k]
                            : ar_member_at(bank, i, c->published)->x2_now;
    bank->position[i] = c->published == ADAPTIVE_SUPER_TWISTING
                            ? trace->position[i][k]
                            : ar_member_at(bank, i, c->published)->z1;
    if (c->selected != ADAPTIVE_SUPER_TWISTING) {
        /* the published velocity: the selected member's; the regressors' (the
         * trace): the centre's, the member the identifier follows (with the
         * selected one's, a zoom member or the centre's neighbour, velocity and xi
         * came from different members and b's standard error was 1.55 times its
         * spread over noise seeds) */
        const int v = bank->center[i] >= 0 ? bank->center[i] : c->selected;
        const AdaptiveMember *m = ar_member_at(bank, i, v);
        const AdaptiveGains *gs = ar_gains_at(bank, i, v);
        trace->velocity[i][k] = m->x2_now;
        trace->velocity_sign[i][k] = expected_sign(
            m->x2_now, gs->velocity_std * sqrt(m->stats.mean_square / gs->innovation_variance));
    }
    if (c->source != ADAPTIVE_SUPER_TWISTING) {
        trace->z_eq[i][k] = members[c->source].xi;
        trace->z_filtered[i][k] = members[c->source].published;
    }
}

void na_run(SuperTwistingObserver *o, AdaptiveBank *bank, const double y[],
                  const StoAcceleration a[], int count, StoTrace *trace)
{
    it_run(o, y, a, count, trace);
    for (int i = 0; i < o->n; ++i) {
        /* which members run changes only with the rules (and the follow, between runs) */
        AdaptiveChoice c = {bank->selected[i], bank->perturbation[i], bank->published[i],
                            ar_running_mask(bank, i)};
        for (int k = 0; k < count; ++k) {
            if (bank->started[i]) {
                step_started(o, bank, i, k, y[i], a[i], trace, &c);
            } else if (trace->switching_rate[i][k] >= STO_CONVERGED_RATE ||
                       ++bank->waited[i] >= bank->start_limit) {
                /* The members start once the super-twisting observer has
                 * converged: its finite-time, bounded reaching phase beats a
                 * linear transient.  On quantized data it may not converge
                 * for seconds (12-bit, 10 kHz: 1.3 s, velocity error 0.2): the
                 * members start after the tuning's start_time then. */
                for (int j = 0; j < bank->count; ++j)
                    start_member(&bank->member[i][j], trace, i, k, a[i]);
                memset(&bank->sta[i], 0, sizeof bank->sta[i]);
                bank->started[i] = 1;
            }
            publish_sample(bank, i, k, trace, &c);
        }
        bank->selected[i] = c.selected;
        bank->published[i] = c.published;
        bank->perturbation[i] = c.source;
        if (count > 0) bank->z_filtered[i] = trace->z_filtered[i][count - 1];
    }
}

void na_outputs(SuperTwistingObserver *o, AdaptiveBank *bank)
{
    it_outputs(o);
    const double h = o->h;
    for (int i = 0; i < o->n; ++i) {
        const int selected = bank->selected[i], published = bank->published[i];
        double mean_square = bank->sta[i].mean_square, variance = STA_INNOVATION_VARIANCE;
        bank->bandwidth[i] = 1.0 / h;
        if (published != ADAPTIVE_SUPER_TWISTING && o->implicit.primed) {
            const AdaptiveMember *m = ar_member_at(bank, i, published);
            it_predict(m->z1, m->mid, m->a_mean, m->a_free + o->implicit.point[i],
                             o->implicit.coulomb[i], m->xi, 0.0, h, &o->x1_hat[i], &o->x2_hat[i]);
            bank->bandwidth[i] = ar_gains_at(bank, i, published)->omega;
        }
        if (selected != ADAPTIVE_SUPER_TWISTING && o->implicit.primed) {
            mean_square = ar_member_at(bank, i, selected)->stats.mean_square;
            variance = ar_gains_at(bank, i, selected)->innovation_variance;
        }
        o->z_eq[i] = bank->perturbation[i] != ADAPTIVE_SUPER_TWISTING && o->implicit.primed
                         ? bank->member[i][bank->perturbation[i]].xi
                         : o->implicit.published[i];
        o->z_filtered[i] = bank->z_filtered[i];
        /* A member faster than the data need sees mostly the noise in its
         * innovations, one slower sees its lag too: the smallest ratio of
         * mean square to steady-state innovation variance (per unit R) over
         * the members estimates R (measured 3.5 % low on white noise). */
        double ratio = mean_square / variance;
        if (o->implicit.primed && bank->started[i])
            for (unsigned running = ar_running_mask(bank, i); running;
                 running &= running - 1u) {
                const int j = lowest_bit(running);
                ratio = fmin(ratio, bank->member[i][j].stats.mean_square /
                                        bank->gains[j].innovation_variance);
            }
        bank->noise_std[i] = sqrt(ratio);
    }
}

int na_settled(const AdaptiveBank *bank, int n)
{
    for (int i = 0; i < n; ++i)
        if (!bank->started[i] || bank->sta[i].samples * bank->gain < bank->tuning.settled ||
            bank->sta[i].velocity_samples * bank->velocity_gain < bank->tuning.settled)
            return 0;
    return 1;
}

void na_follow_published(AdaptiveBank *bank)
{
    unsigned was_running[STO_MAX_DOF];
    for (int i = 0; i < STO_MAX_DOF; ++i) was_running[i] = ar_running_mask(bank, i);
    /* a zoom member moves with its centre: the identifier follows the centre */
    bank->follow = bank->selected[0] >= bank->count ? bank->center[0] : bank->selected[0];
    for (int i = 0; i < STO_MAX_DOF; ++i)
        if (bank->started[i]) wake(bank, i, was_running[i]);
}

int na_valid(const AdaptiveBank *bank, int n)
{
    if (bank->count < 0 || bank->count > ADAPTIVE_MAX_MEMBERS) return 0;
    if (bank->stride < 1 || bank->stride > ADAPTIVE_MAX_STRIDE || !(bank->span > 0.0))
        return 0;
    if (bank->follow < ADAPTIVE_SUPER_TWISTING || bank->follow >= bank->count) return 0;
    for (int i = 0; i < n && i < STO_MAX_DOF; ++i) {
        if (bank->center[i] < -1 || bank->center[i] >= bank->count) return 0;
        for (int s = 0; s < ADAPTIVE_ZOOM; ++s)
            if (bank->zoom_index[i][s] < -1 ||
                bank->zoom_index[i][s] > (bank->count - 1) * ADAPTIVE_FINE)
                return 0;
        if (bank->selected[i] >= bank->count &&
            (bank->center[i] < 0 || bank->selected[i] >= bank->count + ADAPTIVE_ZOOM ||
             bank->zoom_index[i][bank->selected[i] - bank->count] < 0))
            return 0;
    }
    for (int i = 0; i < n && i < STO_MAX_DOF; ++i)
        if (bank->selected[i] < ADAPTIVE_SUPER_TWISTING ||
            bank->selected[i] >= bank->count + ADAPTIVE_ZOOM ||
            (bank->published[i] != bank->selected[i] &&
             (bank->published[i] < 0 || bank->published[i] >= bank->count)) ||
            bank->perturbation[i] < ADAPTIVE_SUPER_TWISTING ||
            bank->perturbation[i] >= bank->count)
            return 0;
    return 1;
}
