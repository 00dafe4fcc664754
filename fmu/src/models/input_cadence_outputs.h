/* The outputs, state fields and warning of an FMU that watches its inputs'
 * cadence (core/input_cadence.h): shared by the models that read a log. */
#ifndef INPUT_CADENCE_OUTPUTS_H
#define INPUT_CADENCE_OUTPUTS_H

#include "../core/input_cadence.h"
#include "../core/tuning.h"
#include "../instance/model_interface.h"

/* input_hold (Real, s) at vr0, coarse_inputs (Boolean) at vr0 + 1 and the
 * parameter input_period (Real, s) at vr0 + 2. */
#define INPUT_CADENCE_VARIABLES(vr0, hold_offset, coarse_offset, period_offset)                  \
    {.name = "input_period", .vr = (vr0) + 2, .type = TYPE_REAL,                                  \
     PARAM(.offset = (period_offset), .start = 0.0, .min = 0.0, .max = NAN, .unit = "s",          \
           .description = "The period at which the inputs are expected to change (0: every "     \
                          "internal step h): set it to the log's sample period when h is "       \
                          "chosen finer; a longer hold is reported (coarse_inputs)")},            \
    {.name = "input_hold", .vr = (vr0), .type = TYPE_REAL,                                        \
     OUTPUT(.offset = (hold_offset), .unit = "s",                                                 \
            .description = "Shortest time the measured inputs held a value over the last "       \
                           "2 s in which they changed (h: a new sample every internal step; "    \
                           "0: not yet seen)")},                                                           \
    {.name = "coarse_inputs", .vr = (vr0) + 1, .type = TYPE_BOOLEAN,                              \
     .causality = CAUSALITY_OUTPUT, .variability = VARIABILITY_DISCRETE, UNBOUNDED,              \
     .offset = (coarse_offset),                                                                   \
     .description = "The inputs arrive as a staircase coarser than the internal step (a "        \
                    "communication step longer than h, or an encoder coarser than the "          \
                    "motion): velocities and estimates are biased"}

/* The InputCadence at `c` of a model data block T. */
#define IC_STATE_FIELDS(T, c)                                                                    \
    DERIVED_FIELD(T, c.count), DERIVED_FIELD(T, c.window), DERIVED_FIELD(T, c.expected),         \
    STATE_FIELD(T, c.last, FIELD_ANY, 0, 0),                                                     \
    STATE_FIELD(T, c.since_change, FIELD_INT, 0, 1000000000),                                    \
    STATE_FIELD(T, c.window_age, FIELD_INT, 0, 1000000000),                                      \
    STATE_FIELD(T, c.window_changes, FIELD_INT, 0, 2),                                           \
    STATE_FIELD(T, c.window_shortest, FIELD_INT, 0, 1000000000),                                 \
    STATE_FIELD(T, c.shortest, FIELD_INT, 0, 1000000000)

/* At a communication point: a warning when the inputs become a staircase
 * (*logged remembers it, so that it is said once per episode). */
static inline void log_cadence(int *logged, int coarse, double hold, double h, double t,
                               const ModelLogger *log)
{
    if (coarse && !*logged)
        log->log(log->context, MODEL_WARNING,
                 "t = %g: the measured inputs held each value %g s at least over %g s, %.0f "
                 "internal steps of h = %g s: the observer and identifier see a "
                 "staircase and their estimates are biased. Give a new sample every internal "
                 "step (communication step h; fmpy: --output-interval %g), or set h to the "
                 "log's sample period", t, hold, CADENCE_WINDOW, hold / h, h, h);
    *logged = coarse;
}

/* check_restored's part: the invariant the field table cannot state. */
static inline ModelStatus check_cadence(const InputCadence *c, const ModelLogger *log)
{
    if (ic_valid(c)) return MODEL_OK;
    log->log(log->context, MODEL_ERROR, "deserialized FMU state: cadence.window_age = %d is "
             "not below cadence.window = %d; state refused", c->window_age, c->window);
    return MODEL_ERROR;
}

#endif
