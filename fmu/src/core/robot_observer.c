#include "robot_observer.h"

#include <math.h>
#include <string.h>

void ro_init(RobotObserver *o, int n, double h, const double alpha1[], const double alpha2[],
             double tau, double convergence_window, const double x1_hat0[],
             const double x2_hat0[])
{
    memset(o, 0, sizeof *o);
    o->n = n;
    o->h = h;
    o->h_squared = h * h;
    o->inverse_h_squared = 1.0 / o->h_squared;
    o->filter_gain = tau > 0.0 ? -expm1(-h / tau) : 1.0;
    o->rate_gain = convergence_window > h ? h / convergence_window : 1.0;
    for (int i = 0; i < n; ++i) {
        o->alpha1[i] = alpha1[i];
        o->alpha2[i] = alpha2[i];
        o->x1_hat[i] = x1_hat0[i];
        o->x2_hat[i] = x2_hat0[i];
    }
}

/* The velocity v at the end of an interval from the velocity r it would reach
 * without the joint's own friction: v = r - c f(v), c = h (M^-1)_ii > 0,
 * f(v) = f_v v + f_c sat(v / v_s) (sign(v) if v_s = 0), solved exactly (f is
 * monotone; negative coefficients count as 0).  Returns f(v). */
static double implicit_friction(double r, double c, double viscous, double coulomb, double v_s)
{
    const double cv = c * (viscous > 0.0 ? viscous : 0.0), cc = c * (coulomb > 0.0 ? coulomb : 0.0);
    double v;
    if (v_s > 0.0 && fabs(r) <= v_s * (1.0 + cv + cc / v_s)) v = r / (1.0 + cv + cc / v_s);
    else if (v_s <= 0.0 && fabs(r) <= cc) v = 0.0; /* sticks */
    else v = (r - (r > 0.0 ? cc : -cc)) / (1.0 + cv);
    return (r - v) / c;
}

/* The nominal acceleration of the interval that starts at the sample:
 * M(y)^-1 (u - C x2 - G - friction) at the corrected velocities x2, with each
 * joint's friction taken implicitly (at the velocity the interval ends with):
 * Coulomb friction on a light link is far too stiff for an explicit step
 * (f_c / (v_s m) h >> 1), and would make the estimate ring at every velocity
 * reversal.  0 and -1 if M is not positive definite. */
static int nominal_acceleration(RobotObserver *o, const RigidBodyModel *model, const double y[],
                                const double u[], double a[])
{
    const int n = o->n;
    double x2[RO_MAX_JOINTS] = {0}, bias[RO_MAX_JOINTS], friction[RO_MAX_JOINTS];
    double M[RB_MAX_JOINTS][RB_MAX_JOINTS];
    for (int i = 0; i < n; ++i) x2[i] = o->dof[i].x2_now;
    rb_mass_matrix(model, y, M);
    rb_inverse_dynamics(model, y, x2, NULL, 1, bias);
    rb_friction(model, x2, friction);
    if (rb_cholesky(M, n) != 0) {
        memset(a, 0, (size_t)n * sizeof a[0]);
        o->model_failures += 1.0;
        return -1;
    }
    for (int i = 0; i < n; ++i) a[i] = u[i] - bias[i] - friction[i];
    rb_cholesky_solve(M, n, a);
    for (int i = 0; i < n; ++i) { /* joint i's friction, implicitly: column i of M^-1 */
        double column[RO_MAX_JOINTS] = {0};
        column[i] = 1.0;
        rb_cholesky_solve(M, n, column);
        const double c = o->h * column[i], r = x2[i] + o->h * (a[i] + column[i] * friction[i]);
        const double change = friction[i] - implicit_friction(r, c, model->friction[i][RB_VISCOUS],
                                                             model->friction[i][RB_COULOMB],
                                                             model->coulomb_velocity);
        for (int j = 0; j < n; ++j) a[j] += column[j] * change;
    }
    return 0;
}

int ro_step(RobotObserver *o, const RigidBodyModel *model, const double y[], const double u[])
{
    const int n = o->n;
    const double h = o->h;
    double a[RO_MAX_JOINTS];
    int status;
    if (!o->primed) { /* the initial estimates; the leapfrog starts half a step back */
        for (int i = 0; i < n; ++i) {
            o->dof[i].z1 = o->x1_hat[i];
            o->dof[i].x2_now = o->x2_hat[i];
        }
        status = nominal_acceleration(o, model, y, u, a);
        for (int i = 0; i < n; ++i) {
            o->dof[i].a_current = a[i];
            o->dof[i].mid = o->dof[i].x2_now - 0.5 * h * a[i];
        }
        o->primed = 1;
    } else {
        for (int i = 0; i < n; ++i) { /* each joint's corrector (implicit_twisting.h) */
            RobotDof *s = &o->dof[i];
            it_correct(y[i], s->a_mean, h, o->h_squared, o->h_squared * o->alpha1[i],
                             h * o->alpha2[i], o->alpha1[i], o->inverse_h_squared, o->rate_gain,
                             &s->z1, &s->mid, &s->v, &s->rate, &s->previous_sign);
            /* the velocity difference across the previous sample over h */
            o->previous_acceleration[i] = s->a_mean + s->v;
            s->x2_now = s->mid + 0.5 * h * (s->a_current + s->v);
        }
        status = nominal_acceleration(o, model, y, u, a);
    }
    for (int i = 0; i < n; ++i) { /* the interval that starts here */
        RobotDof *s = &o->dof[i];
        s->a_mean = 0.5 * (s->a_current + a[i]);
        s->a_current = a[i];
        s->z_filtered += o->filter_gain * (s->v - s->z_filtered);
    }
    o->steps += 1.0;
    return status;
}

void ro_outputs(RobotObserver *o)
{
    if (!o->primed) return; /* still the initial estimates */
    for (int i = 0; i < o->n; ++i) {
        const RobotDof *s = &o->dof[i];
        /* no Coulomb term in the prediction (a_current has the joint's friction), the
         * injection held */
        it_predict(s->z1, s->mid, s->a_mean, s->a_current, 0.0, s->v, 0.0, o->h,
                         &o->x1_hat[i], &o->x2_hat[i]);
    }
}

int ro_converged(const RobotObserver *o)
{
    for (int i = 0; i < o->n; ++i)
        if (!(o->dof[i].rate >= STO_CONVERGED_RATE)) return 0;
    return 1;
}

int ro_regression_init(RobotRegression *r, const RigidBodyModel *model, int kind, double h,
                       double tau, double min_speed, double reversal_margin)
{
    memset(r, 0, sizeof *r);
    if ((kind != RO_REGRESSION_OBSERVER && kind != RO_REGRESSION_WINDOW) ||
        !(min_speed >= 0.0) || !isfinite(min_speed) || !(reversal_margin >= 0.0) ||
        !isfinite(reversal_margin))
        return -1;
    r->kind = kind;
    r->gain = tau > 0.0 ? -expm1(-h / tau) : 1.0;
    r->min_speed = min_speed;
    /* an int: a margin of more than 1e9 samples is as good as forever */
    r->margin_samples = (int)fmin(round(reversal_margin / h), 1e9);
    r->reversals = min_speed > 0.0 || reversal_margin > 0.0;
    rb_get_parameters(model, r->pi_nominal);
    if (kind == RO_REGRESSION_WINDOW) {
        if (fl_init(&r->window, model->n, model->n, 0, h) != 0) return -1;
        if (r->reversals) fl_lead(&r->window); /* to see the events ahead of the centre */
    }
    return 0;
}

void ro_regression_restart(RobotRegression *r)
{
    r->started = 0;
    r->window.chosen = -1; /* chosen again when the identifier joins */
}

int ro_regression_lag(const RobotRegression *r)
{
    if (r->kind == RO_REGRESSION_OBSERVER) return 1;
    const FixedLag *w = &r->window;
    return w->chosen >= 0 ? w->half[w->chosen] + fl_lead_samples(w) : 0;
}

/* Sample k-1's weight of joint i's equation: 0 while the joint is slow or
 * reverses, and for margin_samples samples after. */
static void update_weights(RobotRegression *r, int n)
{
    for (int i = 0; i < n; ++i) {
        const double v = r->previous_velocity[i];
        const int reversed = r->reversals && r->have_older &&
                             signbit(v) != signbit(r->older_velocity[i]);
        if (fabs(v) < r->min_speed || reversed) r->settled[i] = 0;
        else if (r->settled[i] <= r->margin_samples) ++r->settled[i];
        r->weight[i] = r->settled[i] > r->margin_samples ? 1.0 : 0.0;
    }
}

/* The window centre's weight of joint i's equation: 0 from the lead before to the lead
 * and margin_samples after a sample at which the window's velocity was slow or
 * reversed (judged at the lead, which sees that far ahead of the centre). */
static void window_weights(RobotRegression *r, int n)
{
    const int lead = fl_lead_samples(&r->window), span = 2 * lead + r->margin_samples;
    for (int i = 0; i < n; ++i) {
        if (!r->reversals) {
            r->weight[i] = 1.0;
            continue;
        }
        const double v = fl_lead_velocity(&r->window, i);
        r->weight[i] = fl_settled(&r->settled[i], &r->lead_velocity[i], v,
                                  !r->started || fabs(v) < r->min_speed, span) ? 1.0 : 0.0;
    }
}

/* One row of the joint equations at (q, q', q'', u), weighted, through the filter
 * (Y and z alike) into the identifier. */
static void enter_row(RobotRegression *r, const RigidBodyModel *model, int n, const double q[],
                      const double qd[], const double qdd[], const double u[],
                      RegressorIdentifier *id)
{
    RbRegressor Y;
    double nominal[RO_MAX_JOINTS];
    const double gain = r->started ? r->gain : 1.0; /* the first: no transient */
    rb_regressor(model, q, qd, qdd, &Y);
    rb_regressor_torque(model, &Y, r->pi_nominal, nominal);
    for (int i = 0; i < n; ++i) r->z[i] += gain * (r->weight[i] * (u[i] - nominal[i]) - r->z[i]);
    ri_filter_regressor(id, &Y, r->weight, gain, &r->Y);
    r->started = r->entered = 1;
    ri_step(id, r->z, &r->Y);
}

/* The window's regression: the sample into the window; while identifying, the row
 * at its centre once the window is full (its cut-off chosen as the identifier joins). */
static void window_step(RobotRegression *r, const RigidBodyModel *model, int n, const double y[],
                        const double u[], RegressorIdentifier *id)
{
    fl_push(&r->window, y, u, NULL);
    if (!id) return;
    if (r->window.chosen < 0) fl_choose(&r->window);
    if (!fl_ready(&r->window)) return;
    double q[RO_MAX_JOINTS], qd[RO_MAX_JOINTS], qdd[RO_MAX_JOINTS], torque[RO_MAX_JOINTS];
    fl_at_lag(&r->window, q, qd, qdd, torque, NULL);
    window_weights(r, n);
    enter_row(r, model, n, q, qd, qdd, torque, id);
}

void ro_regression_step(RobotRegression *r, const RigidBodyModel *model, const RobotObserver *o,
                        const double y[], const double u[], RegressorIdentifier *id)
{
    const int n = o->n;
    r->entered = 0;
    if (r->kind == RO_REGRESSION_WINDOW) {
        window_step(r, model, n, y, u, id);
        return;
    }
    if (r->have_previous) {
        update_weights(r, n);
        /* sample k-1's equation */
        if (id) enter_row(r, model, n, r->previous_y, r->previous_velocity,
                          o->previous_acceleration, r->previous_u, id);
    }
    for (int i = 0; i < n; ++i) {
        r->older_velocity[i] = r->previous_velocity[i];
        r->previous_y[i] = y[i];
        r->previous_u[i] = u[i];
        r->previous_velocity[i] = o->dof[i].x2_now;
    }
    r->have_older = r->have_previous;
    r->have_previous = 1;
}
