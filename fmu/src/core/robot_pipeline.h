/* The robot observer's pipeline, composed once for every consumer: the
 * model-based observer, the regression of the joint equations it feeds, the
 * identifier and the spread solve of its statistics.  The RobotObserver FMU
 * runs it over its internal steps, the harness over a whole log (the batch
 * entry points of the package's native library), the bench drivers over
 * synthetic samples: the same functions, so they cannot drift apart.
 *
 * The parts stay in their owner's state (the FMU's model data, a batch run's
 * buffer); the pipeline only points at them.  Plain C, no allocation. */
#ifndef ROBOT_PIPELINE_H
#define ROBOT_PIPELINE_H

#include "regressor_identifier.h"
#include "rigid_body.h"
#include "robot_observer.h"
#include "statistics_job.h"

typedef struct {
    RobotObserver *observer;
    RobotRegression *regression;    /* NULL: the observer alone, nothing identified */
    RegressorIdentifier *identifier;
    StatisticsJob *statistics;
} RobotPipeline;

/* How a pipeline is set up: the RobotObserver FMU fills it from its parameters,
 * the harness through a ctypes Structure of the same fields (harness/robot/native.py),
 * the bench drivers from rp_default_settings. */
typedef struct {
    int n;          /* joints */
    int identifier; /* 0 off, IDENTIFIER_LSM, IDENTIFIER_MFF */
    int regression; /* RoRegression: the observer's estimates or the fixed-lag window */
    int p;          /* base parameters identified: columns' length */
    int columns[RRI_MAX_PARAMETERS]; /* their columns of the full regressor */
    double h;                  /* internal step [s] */
    double tau;                /* the injection's and the regression's filter [s] */
    double convergence_window; /* [s] of the switching-rate test */
    double gain_exponent;      /* p of Theorem 3.1 for gains left at 0 */
    double rho, R;             /* the identifier's regularization, MFF's forgetting */
    double min_speed, reversal_margin; /* the joint equations left out (robot_observer.h) */
    double statistics_interval;        /* [s] between solves with standard errors */
    double f_plus[RB_MAX_JOINTS];      /* bounds of the model's acceleration error */
    double alpha1[RB_MAX_JOINTS], alpha2[RB_MAX_JOINTS]; /* gains, 0: from f_plus */
    double torque_scale[RB_MAX_JOINTS]; /* joint equations weighed 1 / scale^2 */
} RobotSettings;

/* tuning.h's defaults for n joints, nothing identified. */
RobotSettings rp_default_settings(int n);

/* What rp_init finds wrong with its settings. */
typedef enum { RP_OK = 0, RP_NO_GAINS, RP_BAD_REGRESSION, RP_BAD_IDENTIFIER } RpProblem;

/* Sets the parts up from the settings, the observer at rest at positions y0 (gains
 * left at 0 completed by Theorem 3.1: the observer holds those used).  Returns RP_OK,
 * or the problem (*joint: the joint without gains). */
RpProblem rp_init(const RobotPipeline *p, const RigidBodyModel *model, const RobotSettings *s,
                  const double y0[], int *joint);

/* When the identifier takes part in a run of samples: from sample `join` on
 * (its regression restarts there), never with RP_NEVER; RP_ALREADY: it already
 * took part before the run. */
enum { RP_NEVER = -1, RP_ALREADY = -2 };

/* Runs `count` samples (the observer's step, the regression and, while
 * identifying, the identifier's step and a share of the statistics' solve).
 * Sample j has the positions y + j * stride and torques u + j * stride
 * (stride 0: inputs held, as an FMU's between communication points). */
void rp_run(const RobotPipeline *p, const RigidBodyModel *model, const double y[],
            const double u[], long stride, long count, long join);

/* A communication point after a sample: the observer's outputs (the statistics
 * follow the internal steps, rp_run). */
void rp_communicate(const RobotPipeline *p);

#endif
