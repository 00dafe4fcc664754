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
