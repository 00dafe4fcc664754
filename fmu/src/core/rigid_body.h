/* Rigid-body dynamics of a serial chain of revolute and prismatic joints
 * (fixed base, up to RB_MAX_JOINTS joints):
 *     M(q) q'' + C(q, q') q' + G(q) + friction(q') = tau
 * by recursive algorithms (RNEA for inverse dynamics, CRBA for M) and the
 * inverse-dynamics regressor Y(q, q', q'') with tau = Y pi, linear in the
 * standard parameters pi.  Plain C, no allocation, no FMI types.
 *
 * Conventions (those of URDF and Pinocchio):
 * - Joint i moves frame i relative to frame i-1 (frame -1 is the base):
 *   frame i = placement_i * motion_i(q_i), with the placement at q = 0 given
 *   as a translation and a rotation (URDF origin xyz, rpy), and the motion a
 *   rotation by q_i about axis_i (revolute) or a translation by q_i along
 *   axis_i (prismatic); axis_i is a unit vector in frame i.
 * - Link i (the body that joint i moves, with every link fixed to it) has
 *   the 10 standard inertial parameters in frame i:
 *       m, m c_x, m c_y, m c_z, I_xx, I_xy, I_yy, I_xz, I_yz, I_zz
 *   with c the centre of mass and I the inertia about the frame origin
 *   (not about the centre of mass): the parameters tau is linear in.
 * - Joint friction: viscous f_v q' + Coulomb f_c sign(q') per joint.
 * - The parameter vector pi of the regressor is the links' 10 n standard
 *   parameters in turn, then (f_v, f_c) for each joint: 12 n in all.
 * Velocities and forces are spatial, as pairs of 3-vectors (linear part at
 * the frame origin, angular part) expressed in the link's frame. */
#ifndef RIGID_BODY_H
#define RIGID_BODY_H

/* Joints of a chain at most: 7 in the FMUs, whose variable tables it sizes; the
 * native library of the offline path is compiled with more (cmake/native.cmake). */
#ifndef RB_MAX_JOINTS
#define RB_MAX_JOINTS 7
#endif
#define RB_LINK_PARAMETERS 10
#define RB_JOINT_FRICTION 2
#define RB_PARAMETERS_PER_JOINT (RB_LINK_PARAMETERS + RB_JOINT_FRICTION)
#define RB_MAX_PARAMETERS (RB_PARAMETERS_PER_JOINT * RB_MAX_JOINTS)

typedef enum { RB_REVOLUTE = 0, RB_PRISMATIC = 1 } RbJointType;

enum { RB_MASS = 0, RB_FIRST_MOMENT = 1, RB_INERTIA = 4 }; /* offsets in a link's parameters */
enum { RB_VISCOUS = 0, RB_COULOMB = 1 };                   /* offsets in a joint's friction */

typedef struct {
    int n;                                      /* joints, 1..RB_MAX_JOINTS */
    int type[RB_MAX_JOINTS];                    /* RbJointType */
    double axis[RB_MAX_JOINTS][3];              /* unit vector in frame i */
    double rotation[RB_MAX_JOINTS][3][3];       /* placement: frame i in frame i-1 at q = 0 */
    double translation[RB_MAX_JOINTS][3];
    double link[RB_MAX_JOINTS][RB_LINK_PARAMETERS]; /* standard parameters in frame i */
    double friction[RB_MAX_JOINTS][RB_JOINT_FRICTION]; /* viscous, Coulomb */
    double gravity[3];                          /* in the base frame, e.g. (0, 0, -9.81) */
    /* Coulomb friction uses sign(q'), or the saturation sat(q'/v_s) if this
     * velocity v_s is > 0 (a smooth model; the regressor follows it). */
    double coulomb_velocity;
} RigidBodyModel;

typedef enum {
    RB_OK = 0,
    RB_BAD_JOINT_COUNT = -1,  /* n outside 1..RB_MAX_JOINTS */
    RB_BAD_JOINT_TYPE = -2,   /* neither revolute nor prismatic */
    RB_BAD_AXIS = -3,         /* a zero or non-finite axis */
    RB_NOT_FINITE = -4        /* a placement, parameter or gravity entry is NaN or infinite */
} RbStatus;

/* Fills the model from flat arrays, as FMU parameters hold them (joint i's
 * entries at 3 i, 10 i, 2 i): type[n], axis[3n] (normalized here),
 * xyz[3n] and rpy[3n] of the placements (URDF origin: R = Rz(yaw) Ry(pitch)
 * Rx(roll)), link[10n] standard parameters, friction[2n], gravity[3].
 * Returns RB_OK, or the first problem found (the model is then unusable). */
RbStatus rb_load(RigidBodyModel *model, int n, const int type[], const double axis[],
                 const double xyz[], const double rpy[], const double link[],
                 const double friction[], const double gravity[3], double coulomb_velocity);

/* A short English text for a status (for the FMU's log). */
const char *rb_status_text(RbStatus status);

/* Number of parameters of the regressor: 12 n. */
static inline int rb_parameter_count(const RigidBodyModel *model)
{
    return RB_PARAMETERS_PER_JOINT * model->n;
}

/* pi <- the model's parameters; the model's parameters <- pi. */
void rb_get_parameters(const RigidBodyModel *model, double pi[]);
void rb_set_parameters(RigidBodyModel *model, const double pi[]);

/* RNEA: tau = M q'' + C q' (+ G if with_gravity), without friction.
 * qd or qdd may be NULL for zero. */
void rb_inverse_dynamics(const RigidBodyModel *model, const double q[], const double qd[],
                         const double qdd[], int with_gravity, double tau[]);

/* G(q) and C(q, q') q' (both by RNEA). */
void rb_gravity(const RigidBodyModel *model, const double q[], double g[]);
void rb_coriolis(const RigidBodyModel *model, const double q[], const double qd[], double c[]);

/* CRBA: the joint-space inertia matrix, full (both triangles). */
void rb_mass_matrix(const RigidBodyModel *model, const double q[],
                    double M[RB_MAX_JOINTS][RB_MAX_JOINTS]);

/* The friction torques f_v q' + f_c sign(q'). */
void rb_friction(const RigidBodyModel *model, const double qd[], double tau[]);

/* The regressor row entry of Coulomb friction: sign(v), or sat(v / v_s). */
double rb_coulomb_shape(const RigidBodyModel *model, double v);

/* q'' = M^-1 (tau - C q' - G - friction).  Returns 0, or -1 if M is not
 * positive definite (non-physical parameters; qdd is then zero). */
int rb_forward_dynamics(const RigidBodyModel *model, const double q[], const double qd[],
                        const double tau[], double qdd[]);

/* M = L L^T in place (L in the lower triangle).  Returns 0, or -1 if M is not
 * positive definite. */
int rb_cholesky(double M[RB_MAX_JOINTS][RB_MAX_JOINTS], int n);

/* x <- M^-1 x from the factor of rb_cholesky. */
void rb_cholesky_solve(double L[RB_MAX_JOINTS][RB_MAX_JOINTS], int n, double x[]);

/* A regressor matrix: row i is joint i, columns 0..12n-1 are used. */
typedef struct {
    double row[RB_MAX_JOINTS][RB_MAX_PARAMETERS];
} RbRegressor;

/* The regressor: tau = Y pi with gravity and friction, pi as above. */
void rb_regressor(const RigidBodyModel *model, const double q[], const double qd[],
                  const double qdd[], RbRegressor *Y);

/* tau = Y pi (pi: 12 n parameters in the regressor's order) over the entries of Y
 * that can be nonzero (joint j's row: the links j..n-1 and joint j's friction):
 * the torques of the parameters pi with gravity and friction, at the cost of
 * n (5 n + 7) multiply-adds once Y is known (instead of another RNEA). */
void rb_regressor_torque(const RigidBodyModel *model, const RbRegressor *Y, const double pi[],
                         double tau[]);

#endif
