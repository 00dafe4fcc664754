#include "rigid_body.h"

#include <math.h>
#include <string.h>

#include "cholesky.h"

/* ---- 3-vector helpers ---------------------------------------------------------- */

static void cross(const double a[3], const double b[3], double out[3])
{
    const double x = a[1] * b[2] - a[2] * b[1];
    const double y = a[2] * b[0] - a[0] * b[2];
    const double z = a[0] * b[1] - a[1] * b[0];
    out[0] = x, out[1] = y, out[2] = z;
}

static double dot(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* out = R x */
static void rotate(const double R[3][3], const double x[3], double out[3])
{
    double r[3];
    for (int i = 0; i < 3; ++i) r[i] = R[i][0] * x[0] + R[i][1] * x[1] + R[i][2] * x[2];
    memcpy(out, r, sizeof r);
}

/* out = R^T x */
static void rotate_back(const double R[3][3], const double x[3], double out[3])
{
    double r[3];
    for (int i = 0; i < 3; ++i) r[i] = R[0][i] * x[0] + R[1][i] * x[1] + R[2][i] * x[2];
    memcpy(out, r, sizeof r);
}

/* The symmetric inertia (xx, xy, yy, xz, yz, zz) times x. */
static void inertia_times(const double I[6], const double x[3], double out[3])
{
    out[0] = I[0] * x[0] + I[1] * x[1] + I[3] * x[2];
    out[1] = I[1] * x[0] + I[2] * x[1] + I[4] * x[2];
    out[2] = I[3] * x[0] + I[4] * x[1] + I[5] * x[2];
}

static int finite_all(const double *x, int count)
{
    for (int k = 0; k < count; ++k)
        if (!isfinite(x[k])) return 0;
    return 1;
}

/* ---- model ---------------------------------------------------------------------- */

RbStatus rb_load(RigidBodyModel *model, int n, const int type[], const double axis[],
                 const double xyz[], const double rpy[], const double link[],
                 const double friction[], const double gravity[3], double coulomb_velocity)
{
    memset(model, 0, sizeof *model);
    if (n < 1 || n > RB_MAX_JOINTS) return RB_BAD_JOINT_COUNT;
    if (!finite_all(xyz, 3 * n) || !finite_all(rpy, 3 * n) ||
        !finite_all(link, RB_LINK_PARAMETERS * n) || !finite_all(friction, RB_JOINT_FRICTION * n) ||
        !finite_all(gravity, 3) || !isfinite(coulomb_velocity))
        return RB_NOT_FINITE;
    model->n = n;
    for (int i = 0; i < n; ++i) {
        if (type[i] != RB_REVOLUTE && type[i] != RB_PRISMATIC) return RB_BAD_JOINT_TYPE;
        model->type[i] = type[i];
        const double *a = axis + 3 * i;
        const double norm = sqrt(dot(a, a));
        if (!(norm > 0.0) || !isfinite(norm)) return RB_BAD_AXIS;
        for (int k = 0; k < 3; ++k) model->axis[i][k] = a[k] / norm;
        /* URDF: R = Rz(yaw) Ry(pitch) Rx(roll) */
        const double cr = cos(rpy[3 * i]), sr = sin(rpy[3 * i]);
        const double cp = cos(rpy[3 * i + 1]), sp = sin(rpy[3 * i + 1]);
        const double cy = cos(rpy[3 * i + 2]), sy = sin(rpy[3 * i + 2]);
        const double R[3][3] = {{cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr},
                                {sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr},
                                {-sp, cp * sr, cp * cr}};
        memcpy(model->rotation[i], R, sizeof R);
        memcpy(model->translation[i], xyz + 3 * i, 3 * sizeof(double));
        memcpy(model->link[i], link + RB_LINK_PARAMETERS * i, RB_LINK_PARAMETERS * sizeof(double));
        memcpy(model->friction[i], friction + RB_JOINT_FRICTION * i,
               RB_JOINT_FRICTION * sizeof(double));
    }
    memcpy(model->gravity, gravity, 3 * sizeof(double));
    model->coulomb_velocity = coulomb_velocity > 0.0 ? coulomb_velocity : 0.0;
    return RB_OK;
}

const char *rb_status_text(RbStatus status)
{
    switch (status) {
    case RB_OK: return "ok";
    case RB_BAD_JOINT_COUNT: return "the number of joints is not between 1 and 7";
    case RB_BAD_JOINT_TYPE: return "a joint type is neither revolute (0) nor prismatic (1)";
    case RB_BAD_AXIS: return "a joint axis is zero or not finite";
    case RB_NOT_FINITE: return "a placement, inertial, friction or gravity value is not finite";
    }
    return "unknown status";
}

void rb_get_parameters(const RigidBodyModel *model, double pi[])
{
    const int n = model->n;
    for (int i = 0; i < n; ++i) {
        memcpy(pi + RB_LINK_PARAMETERS * i, model->link[i], sizeof model->link[i]);
        memcpy(pi + RB_LINK_PARAMETERS * n + RB_JOINT_FRICTION * i, model->friction[i],
               sizeof model->friction[i]);
    }
}

void rb_set_parameters(RigidBodyModel *model, const double pi[])
{
    const int n = model->n;
    for (int i = 0; i < n; ++i) {
        memcpy(model->link[i], pi + RB_LINK_PARAMETERS * i, sizeof model->link[i]);
        memcpy(model->friction[i], pi + RB_LINK_PARAMETERS * n + RB_JOINT_FRICTION * i,
               sizeof model->friction[i]);
    }
}

/* ---- kinematics ------------------------------------------------------------------ */

/* Joint i's transform at q_i: frame i in frame i-1. */
typedef struct {
    double R[3][3];
    double p[3];
} Transform;

static void joint_transform(const RigidBodyModel *model, int i, double q, Transform *X)
{
    const double *a = model->axis[i];
    const double(*R0)[3] = model->rotation[i];
    memcpy(X->p, model->translation[i], sizeof X->p);
    if (model->type[i] == RB_PRISMATIC) {
        memcpy(X->R, R0, sizeof X->R);
        double d[3];
        rotate(R0, a, d);
        for (int k = 0; k < 3; ++k) X->p[k] += q * d[k];
        return;
    }
    /* Rodrigues: Rot(a, q) = cos q I + sin q [a]x + (1 - cos q) a a^T */
    const double c = cos(q), s = sin(q), v = 1.0 - c;
    const double rot[3][3] = {
        {c + v * a[0] * a[0], v * a[0] * a[1] - s * a[2], v * a[0] * a[2] + s * a[1]},
        {v * a[1] * a[0] + s * a[2], c + v * a[1] * a[1], v * a[1] * a[2] - s * a[0]},
        {v * a[2] * a[0] - s * a[1], v * a[2] * a[1] + s * a[0], c + v * a[2] * a[2]}};
    for (int r = 0; r < 3; ++r)
        for (int k = 0; k < 3; ++k)
            X->R[r][k] = R0[r][0] * rot[0][k] + R0[r][1] * rot[1][k] + R0[r][2] * rot[2][k];
}

/* Motion subspace of joint i: linear and angular parts. */
static void joint_subspace(const RigidBodyModel *model, int i, double s_lin[3], double s_ang[3])
{
    const int prismatic = model->type[i] == RB_PRISMATIC;
    for (int k = 0; k < 3; ++k) {
        s_lin[k] = prismatic ? model->axis[i][k] : 0.0;
        s_ang[k] = prismatic ? 0.0 : model->axis[i][k];
    }
}

/* A force (lin, ang) in frame i expressed in frame i-1 (in place). */
static void force_to_parent(const Transform *X, double lin[3], double ang[3])
{
    double moment[3];
    rotate(X->R, lin, lin);
    rotate(X->R, ang, ang);
    cross(X->p, lin, moment);
    for (int k = 0; k < 3; ++k) ang[k] += moment[k];
}

/* Velocities and spatial accelerations of every link (RNEA's forward pass). */
typedef struct {
    Transform X[RB_MAX_JOINTS];
    double w[RB_MAX_JOINTS][3], v[RB_MAX_JOINTS][3];         /* angular, linear at origin */
    double alpha[RB_MAX_JOINTS][3], a[RB_MAX_JOINTS][3];     /* spatial acceleration */
} LinkMotion;

static void forward_pass(const RigidBodyModel *model, const double q[], const double qd[],
                         const double qdd[], int with_gravity, LinkMotion *s)
{
    double w[3] = {0}, v[3] = {0}, alpha[3] = {0}, a[3] = {0};
    /* gravity as a base acceleration of -g */
    if (with_gravity)
        for (int k = 0; k < 3; ++k) a[k] = -model->gravity[k];
    for (int i = 0; i < model->n; ++i) {
        joint_transform(model, i, q[i], &s->X[i]);
        const Transform *X = &s->X[i];
        double s_lin[3], s_ang[3], t[3];
        joint_subspace(model, i, s_lin, s_ang);
        const double dq = qd ? qd[i] : 0.0, ddq = qdd ? qdd[i] : 0.0;
        /* a_i = X a_{i-1} + S q'' + v_i x (S q'); the parent's alpha, w first */
        cross(alpha, X->p, t);
        for (int k = 0; k < 3; ++k) t[k] += a[k];   /* a + alpha x p */
        rotate_back(X->R, t, a);
        rotate_back(X->R, alpha, alpha);
        cross(w, X->p, t);
        for (int k = 0; k < 3; ++k) t[k] += v[k];   /* v + w x p */
        rotate_back(X->R, t, v);
        rotate_back(X->R, w, w);
        for (int k = 0; k < 3; ++k) {
            w[k] += s_ang[k] * dq;
            v[k] += s_lin[k] * dq;
        }
        double c1[3], c2[3], c3[3];
        const double sa[3] = {s_ang[0] * dq, s_ang[1] * dq, s_ang[2] * dq};
        const double sl[3] = {s_lin[0] * dq, s_lin[1] * dq, s_lin[2] * dq};
        cross(w, sa, c1);
        cross(w, sl, c2);
        cross(v, sa, c3);
        for (int k = 0; k < 3; ++k) {
            alpha[k] += s_ang[k] * ddq + c1[k];
            a[k] += s_lin[k] * ddq + c2[k] + c3[k];
        }
        memcpy(s->w[i], w, sizeof w);
        memcpy(s->v[i], v, sizeof v);
        memcpy(s->alpha[i], alpha, sizeof alpha);
        memcpy(s->a[i], a, sizeof a);
    }
}

/* ---- inverse dynamics --------------------------------------------------------------- */

void rb_inverse_dynamics(const RigidBodyModel *model, const double q[], const double qd[],
                         const double qdd[], int with_gravity, double tau[])
{
    LinkMotion s;
    forward_pass(model, q, qd, qdd, with_gravity, &s);
    double f[3] = {0}, n[3] = {0};  /* force of link i+1 on link i, in frame i+1 */
    for (int i = model->n - 1; i >= 0; --i) {
        const double *p = model->link[i];
        const double m = p[RB_MASS], *h = p + RB_FIRST_MOMENT, *I = p + RB_INERTIA;
        const double *w = s.w[i], *v = s.v[i], *alpha = s.alpha[i];
        if (i < model->n - 1) force_to_parent(&s.X[i + 1], f, n);
        /* f = m a' + alpha x h + w x (w x h),  n = I alpha + w x I w + h x a',
         * with a' = a + w x v the classical acceleration of the origin */
        double ac[3], t[3], u[3];
        cross(w, v, t);
        for (int k = 0; k < 3; ++k) ac[k] = s.a[i][k] + t[k];
        cross(alpha, h, t);
        cross(w, h, u);
        cross(w, u, u);
        for (int k = 0; k < 3; ++k) f[k] += m * ac[k] + t[k] + u[k];
        inertia_times(I, alpha, t);
        for (int k = 0; k < 3; ++k) n[k] += t[k];
        inertia_times(I, w, t);
        cross(w, t, u);
        cross(h, ac, t);
        for (int k = 0; k < 3; ++k) n[k] += u[k] + t[k];
        double s_lin[3], s_ang[3];
        joint_subspace(model, i, s_lin, s_ang);
        tau[i] = dot(s_lin, f) + dot(s_ang, n);
    }
}

void rb_gravity(const RigidBodyModel *model, const double q[], double g[])
{
    rb_inverse_dynamics(model, q, NULL, NULL, 1, g);
}

void rb_coriolis(const RigidBodyModel *model, const double q[], const double qd[], double c[])
{
    rb_inverse_dynamics(model, q, qd, NULL, 0, c);
}

/* ---- joint-space inertia (CRBA) ---------------------------------------------------- */

/* [a]x [b]x + [b]x [a]x, symmetric, stored as (xx, xy, yy, xz, yz, zz). */
static void symmetric_cross_product(const double a[3], const double b[3], double out[6])
{
    const double ab = dot(a, b);
    out[0] = 2.0 * (a[0] * b[0] - ab);
    out[1] = a[1] * b[0] + a[0] * b[1];
    out[2] = 2.0 * (a[1] * b[1] - ab);
    out[3] = a[2] * b[0] + a[0] * b[2];
    out[4] = a[2] * b[1] + a[1] * b[2];
    out[5] = 2.0 * (a[2] * b[2] - ab);
}

/* A rigid-body inertia (m, h, I about the origin) of frame i expressed in
 * frame i-1: h' = R h + m p, I' = R I R^T - m [p]x^2 - [p]x[Rh]x - [Rh]x[p]x. */
static void inertia_to_parent(const Transform *X, const double in[10], double out[10])
{
    const double m = in[RB_MASS];
    const double *I = in + RB_INERTIA;
    const double full[3][3] = {{I[0], I[1], I[3]}, {I[1], I[2], I[4]}, {I[3], I[4], I[5]}};
    double RI[3][3], rotated[3][3];
    for (int r = 0; r < 3; ++r)
        for (int k = 0; k < 3; ++k)
            RI[r][k] = X->R[r][0] * full[0][k] + X->R[r][1] * full[1][k] + X->R[r][2] * full[2][k];
    for (int r = 0; r < 3; ++r)
        for (int k = 0; k < 3; ++k)
            rotated[r][k] = RI[r][0] * X->R[k][0] + RI[r][1] * X->R[k][1] + RI[r][2] * X->R[k][2];
    double h[3], pp[6], ph[6];
    rotate(X->R, in + RB_FIRST_MOMENT, h);
    symmetric_cross_product(X->p, X->p, pp);  /* 2 [p]x^2 */
    symmetric_cross_product(X->p, h, ph);
    out[RB_MASS] = m;
    for (int k = 0; k < 3; ++k) out[RB_FIRST_MOMENT + k] = h[k] + m * X->p[k];
    const double upper[6] = {rotated[0][0], rotated[0][1], rotated[1][1],
                             rotated[0][2], rotated[1][2], rotated[2][2]};
    for (int k = 0; k < 6; ++k) out[RB_INERTIA + k] = upper[k] - 0.5 * m * pp[k] - ph[k];
}

void rb_mass_matrix(const RigidBodyModel *model, const double q[],
                    double M[RB_MAX_JOINTS][RB_MAX_JOINTS])
{
    const int n = model->n;
    Transform X[RB_MAX_JOINTS];
    for (int i = 0; i < n; ++i) joint_transform(model, i, q[i], &X[i]);
    double composite[RB_LINK_PARAMETERS];
    memcpy(composite, model->link[n - 1], sizeof composite);
    for (int i = n - 1; i >= 0; --i) {
        const double m = composite[RB_MASS], *h = composite + RB_FIRST_MOMENT;
        const double *I = composite + RB_INERTIA;
        double s_lin[3], s_ang[3], f[3], nm[3], t[3];
        joint_subspace(model, i, s_lin, s_ang);
        /* F = I^c S: the momentum (m v + w x h, I w + h x v) of the unit motion S */
        cross(s_ang, h, t);
        for (int k = 0; k < 3; ++k) f[k] = m * s_lin[k] + t[k];
        inertia_times(I, s_ang, nm);
        cross(h, s_lin, t);
        for (int k = 0; k < 3; ++k) nm[k] += t[k];
        M[i][i] = dot(s_lin, f) + dot(s_ang, nm);
        for (int j = i - 1; j >= 0; --j) {
            force_to_parent(&X[j + 1], f, nm);
            double j_lin[3], j_ang[3];
            joint_subspace(model, j, j_lin, j_ang);
            M[i][j] = M[j][i] = dot(j_lin, f) + dot(j_ang, nm);
        }
        if (i > 0) {
            double parent[RB_LINK_PARAMETERS];
            inertia_to_parent(&X[i], composite, parent);
            for (int k = 0; k < RB_LINK_PARAMETERS; ++k)
                composite[k] = parent[k] + model->link[i - 1][k];
        }
    }
}

/* ---- friction and forward dynamics ---------------------------------------------------- */

double rb_coulomb_shape(const RigidBodyModel *model, double v)
{
    if (model->coulomb_velocity > 0.0) {
        const double r = v / model->coulomb_velocity;
        return r > 1.0 ? 1.0 : r < -1.0 ? -1.0 : r;
    }
    return v > 0.0 ? 1.0 : v < 0.0 ? -1.0 : 0.0;
}

void rb_friction(const RigidBodyModel *model, const double qd[], double tau[])
{
    for (int i = 0; i < model->n; ++i)
        tau[i] = model->friction[i][RB_VISCOUS] * qd[i] +
                 model->friction[i][RB_COULOMB] * rb_coulomb_shape(model, qd[i]);
}

int rb_forward_dynamics(const RigidBodyModel *model, const double q[], const double qd[],
                        const double tau[], double qdd[])
{
    const int n = model->n;
    double M[RB_MAX_JOINTS][RB_MAX_JOINTS], bias[RB_MAX_JOINTS], fr[RB_MAX_JOINTS];
    rb_mass_matrix(model, q, M);
    rb_inverse_dynamics(model, q, qd, NULL, 1, bias);
    rb_friction(model, qd, fr);
    for (int i = 0; i < n; ++i) qdd[i] = tau[i] - bias[i] - fr[i];
    if (rb_cholesky(M, n) != 0) {
        memset(qdd, 0, (size_t)n * sizeof qdd[0]);
        return -1;
    }
    rb_cholesky_solve(M, n, qdd);
    return 0;
}

int rb_cholesky(double M[RB_MAX_JOINTS][RB_MAX_JOINTS], int n)
{
    return cholesky_factor(&M[0][0], &M[0][0], n, RB_MAX_JOINTS); /* M is symmetric */
}

void rb_cholesky_solve(double L[RB_MAX_JOINTS][RB_MAX_JOINTS], int n, double x[])
{
    cholesky_solve(&L[0][0], n, RB_MAX_JOINTS, x);
}

/* ---- regressor ------------------------------------------------------------------------ */

/* The 10 columns (force lin, ang per parameter) of link i's spatial force
 * f = I a + v x* I v in the standard parameters. */
static void link_force_columns(const LinkMotion *s, int i, double lin[10][3], double ang[10][3])
{
    const double *w = s->w[i], *v = s->v[i], *alpha = s->alpha[i];
    double ac[3], t[3];
    cross(w, v, t);
    for (int k = 0; k < 3; ++k) ac[k] = s->a[i][k] + t[k];
    memset(lin, 0, 10 * sizeof lin[0]);
    memset(ang, 0, 10 * sizeof ang[0]);
    memcpy(lin[RB_MASS], ac, sizeof ac);
    for (int k = 0; k < 3; ++k) {
        const double e[3] = {k == 0, k == 1, k == 2};
        double u[3];
        cross(alpha, e, lin[RB_FIRST_MOMENT + k]);
        cross(w, e, u);
        cross(w, u, u);
        for (int r = 0; r < 3; ++r) lin[RB_FIRST_MOMENT + k][r] += u[r];
        cross(e, ac, ang[RB_FIRST_MOMENT + k]);
    }
    /* inertia entry (r, c) (xx, xy, yy, xz, yz, zz): with U its unit symmetric
     * matrix, U alpha + w x U w = alpha_c e_r + alpha_r e_c + w_c (w x e_r) + w_r (w x e_c)
     * (once if r = c) */
    static const int entry[6][2] = {{0, 0}, {0, 1}, {1, 1}, {0, 2}, {1, 2}, {2, 2}};
    const double w_cross_e[3][3] = {{0.0, w[2], -w[1]}, {-w[2], 0.0, w[0]}, {w[1], -w[0], 0.0}};
    for (int k = 0; k < 6; ++k) {
        const int r = entry[k][0], c = entry[k][1];
        double *out = ang[RB_INERTIA + k];
        for (int d = 0; d < 3; ++d) out[d] = w[c] * w_cross_e[r][d];
        out[r] += alpha[c];
        if (r != c) {
            for (int d = 0; d < 3; ++d) out[d] += w[r] * w_cross_e[c][d];
            out[c] += alpha[r];
        }
    }
}

/* A motion (lin, ang) in frame i-1 expressed in frame i (in place): the dual of
 * force_to_parent, so that dot(S, force_to_parent(f)) = dot(motion_to_child(S), f). */
static void motion_to_child(const Transform *X, double lin[3], double ang[3])
{
    double t[3];
    cross(ang, X->p, t);
    for (int k = 0; k < 3; ++k) t[k] += lin[k];
    rotate_back(X->R, t, lin);
    rotate_back(X->R, ang, ang);
}

void rb_regressor(const RigidBodyModel *model, const double q[], const double qd[],
                  const double qdd[], RbRegressor *regressor)
{
    double(*Y)[RB_MAX_PARAMETERS] = regressor->row;
    const int n = model->n;
    LinkMotion s;
    forward_pass(model, q, qd, qdd, 1, &s);
    for (int j = 0; j < n; ++j)
        for (int c = 0; c < RB_PARAMETERS_PER_JOINT * n; ++c) Y[j][c] = 0.0;
    /* joint j's motion subspace expressed in frame i (for every j <= i) */
    double s_lin[RB_MAX_JOINTS][3], s_ang[RB_MAX_JOINTS][3];
    for (int i = 0; i < n; ++i) {
        for (int j = 0; j < i; ++j) motion_to_child(&s.X[i], s_lin[j], s_ang[j]);
        joint_subspace(model, i, s_lin[i], s_ang[i]);
        double lin[10][3], ang[10][3];
        link_force_columns(&s, i, lin, ang);
        /* link i's force reaches every joint j <= i: Y = S_j . f in frame i,
         * where the mass has no moment, the inertia no force */
        for (int j = i; j >= 0; --j) {
            double *y = Y[j] + RB_LINK_PARAMETERS * i;
            y[RB_MASS] = dot(s_lin[j], lin[RB_MASS]);
            for (int c = RB_FIRST_MOMENT; c < RB_INERTIA; ++c)
                y[c] = dot(s_lin[j], lin[c]) + dot(s_ang[j], ang[c]);
            for (int c = RB_INERTIA; c < RB_LINK_PARAMETERS; ++c) y[c] = dot(s_ang[j], ang[c]);
        }
        Y[i][RB_LINK_PARAMETERS * n + RB_JOINT_FRICTION * i + RB_VISCOUS] = qd ? qd[i] : 0.0;
        Y[i][RB_LINK_PARAMETERS * n + RB_JOINT_FRICTION * i + RB_COULOMB] =
            rb_coulomb_shape(model, qd ? qd[i] : 0.0);
    }
}

void rb_regressor_torque(const RigidBodyModel *model, const RbRegressor *Y, const double pi[],
                         double tau[])
{
    const int n = model->n;
    for (int j = 0; j < n; ++j) {
        const double *y = Y->row[j];
        double sum = 0.0;
        for (int c = RB_LINK_PARAMETERS * j; c < RB_LINK_PARAMETERS * n; ++c) sum += y[c] * pi[c];
        const int own = RB_LINK_PARAMETERS * n + RB_JOINT_FRICTION * j; /* joint j's friction */
        for (int c = own; c < own + RB_JOINT_FRICTION; ++c) sum += y[c] * pi[c];
        tau[j] = sum;
    }
}
