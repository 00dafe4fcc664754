/* The contract between the model-independent instance core (instance.c,
 * under the FMI 2 and FMI 3 API files) and one model (observer, plant,
 * controller).  No FMI types appear here:
 * a model is a plain-C variable table plus a few hooks over a plain struct
 * ("model data") that holds every parameter, input, output and state.
 *
 * The model data block must contain no pointers: the layer copies it
 * byte-for-byte to save, restore and serialize the FMU state. */
#ifndef MODEL_INTERFACE_H
#define MODEL_INTERFACE_H

#include <math.h> /* NAN in the variable tables */
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

/* Same numbering as fmi2Status and fmi3Status so the API files can pass it through. */
typedef enum { MODEL_OK = 0, MODEL_WARNING = 1, MODEL_ERROR = 3 } ModelStatus;

typedef enum { TYPE_REAL, TYPE_INTEGER, TYPE_BOOLEAN } VariableType;

typedef enum {
    CAUSALITY_PARAMETER,            /* set by the user before initialization */
    CAUSALITY_CALCULATED_PARAMETER, /* derived from parameters at initialization */
    CAUSALITY_INPUT,
    CAUSALITY_OUTPUT
} VariableCausality;

typedef enum {
    VARIABILITY_FIXED,
    VARIABILITY_DISCRETE,
    VARIABILITY_CONTINUOUS
} VariableVariability;

/* One scalar, vector (rows) or matrix (rows x cols, row-major) variable.
 * Element (i, j) has value reference vr + i * cols + j and is exposed with
 * the FMI 2 structured name name[i+1] or name[i+1,j+1]. */
typedef struct {
    const char *name;
    uint32_t vr;
    uint16_t rows;  /* 0 for a scalar */
    uint16_t cols;  /* 0 for a scalar or vector */
    VariableType type;
    VariableCausality causality;
    VariableVariability variability;
    size_t offset;  /* offsetof(model data, first element): double for reals, int otherwise */
    double start;   /* start (or initial) value of every element ... */
    const double *starts; /* ... unless this per-element array is given */
    double min, max;      /* valid range (NAN: unbounded); reals and integers */
    bool min_exclusive;   /* min itself is invalid (e.g. a step size > 0) */
    bool max_exclusive;
    bool on_read;  /* an output derived when read (refresh_outputs, which checks it):
                    * not checked after each doStep */
    const char *unit;        /* NULL: dimensionless */
    const char *description;
} ModelVariable;

/* Shorthands for the designated initializers of a model's variable table:
 *   {.name = "h", .vr = 1, .type = TYPE_REAL, PARAM(.offset = ..., .start = 1e-4, ...)} */
#define UNBOUNDED .min = NAN, .max = NAN
#define PARAM(...) .causality = CAUSALITY_PARAMETER, .variability = VARIABILITY_FIXED, __VA_ARGS__
#define CALC(...) .causality = CAUSALITY_CALCULATED_PARAMETER, \
                  .variability = VARIABILITY_FIXED, UNBOUNDED, __VA_ARGS__
#define INPUT(...) .causality = CAUSALITY_INPUT, .variability = VARIABILITY_CONTINUOUS, \
                   UNBOUNDED, __VA_ARGS__
#define OUTPUT(...) .causality = CAUSALITY_OUTPUT, .variability = VARIABILITY_CONTINUOUS, \
                    UNBOUNDED, __VA_ARGS__

/* printf-style format checking.  MinGW's "printf" means Microsoft's runtime
 * (no %zu); the instance core formats with MinGW's C99 printf instead. */
#if defined(__MINGW32__)
#define PRINTF_LIKE(format_index, first_arg) \
    __attribute__((format(gnu_printf, format_index, first_arg)))
#elif defined(__GNUC__)
#define PRINTF_LIKE(format_index, first_arg) __attribute__((format(printf, format_index, first_arg)))
#else
#define PRINTF_LIKE(format_index, first_arg)
#endif

/* Messages go through this; the model never sees the FMI logger. */
typedef struct {
    void (*log)(void *context, ModelStatus status, const char *format, ...) PRINTF_LIKE(3, 4);
    void *context;
} ModelLogger;

/* How one field (or array) of the model data block that is not a variable
 * of the table is checked in a restored state (ModelDescriptor.state_fields). */
typedef enum {
    FIELD_DERIVED,  /* set by initialize from the parameters alone: equal to a fresh initialize's */
    FIELD_INT,      /* int elements in [min, max] */
    FIELD_UNSIGNED, /* unsigned elements in [min, max] */
    FIELD_REAL,     /* doubles in [min, max] (a NAN bound: any finite value on that side;
                     * an infinite bound admits that infinity) */
    FIELD_REALS,    /* every 8-byte word in the field that no earlier entry covers is a
                     * finite double (a struct of doubles and listed ints) */
    FIELD_ANY       /* doubles that may hold NaN in a state the model wrote (a factor's
                     * unused entries): only ever multiplied, never an index or a count */
} FieldCheck;

typedef struct StateField {
    const char *name;
    size_t offset, size;
    FieldCheck check;
    double min, max;
} StateField;

/* STATE_FIELD(ModelData, obs.primed, FIELD_INT, 0, 1) */
#define STATE_FIELD(type, field, kind, lo, hi) \
    {#field, offsetof(type, field), sizeof(((type *)0)->field), kind, lo, hi}
#define DERIVED_FIELD(type, field) STATE_FIELD(type, field, FIELD_DERIVED, 0, 0)
#define REAL_FIELDS(type, field) STATE_FIELD(type, field, FIELD_REALS, 0, 0)

typedef struct {
    const char *model_name;
    const char *model_identifier;
    const char *guid;
    const char *description;
    const ModelVariable *variables;
    size_t n_variables;
    size_t data_size;
    double default_stop_time;
    double default_tolerance;

    /* Cross-parameter checks and derived quantities, when initialization mode is left.
     * May log warnings; returns MODEL_ERROR (after logging why) to refuse. */
    ModelStatus (*initialize)(void *data, double start_time, const ModelLogger *log);
    /* The fixed internal step h of this instance (valid after initialize). */
    double (*internal_step)(const void *data);
    /* The most internal steps one doStep may take (the model's parameter
     * max_internal_steps, MAX_INTERNAL_STEPS_VARIABLE) ... */
    uint64_t (*max_internal_steps)(const void *data);
    /* ... and the work budget of one doStep (the parameter max_work) and the
     * model's estimate of the work of one internal step (the calculated parameter
     * work_per_step, from the configuration; valid after initialize), both in work
     * units (WORK_VARIABLES).  The layer refuses a communication step over either
     * limit before doing any work, so that no call runs for minutes and cannot
     * be cancelled. */
    double (*max_work)(const void *data);
    double (*work_per_step)(const void *data);
    /* The internal steps k = k_first .. k_end - 1 of one communication step,
     * step k going from start_time + k h to start_time + (k + 1) h with the
     * inputs held.  One call per communication step, so that the model can
     * work out once what depends only on the held inputs.  Runs millions of
     * steps: no allocation, no logging, no I/O. */
    void (*advance)(void *data, double start_time, uint64_t k_first, uint64_t k_end);
    /* Once per communication step, after the internal steps: derive the
     * outputs that are not read straight from the state, and check them (a
     * diverged state).  May log; MODEL_ERROR if the outputs cannot be trusted. */
    ModelStatus (*communication_point)(void *data, double t, const ModelLogger *log);
    /* Optional (NULL: every output is derived by communication_point): derives
     * the outputs marked on_read, which communication_point leaves to be
     * derived when read, as they were at that communication point, and checks
     * them (MODEL_ERROR after logging if one is not finite).  The layer calls
     * it before a get that reads one of them and before the state is copied,
     * so a value read after a doStep is the value at that communication point;
     * an output that costs more than the step and that a closed loop never
     * reads is not derived at every point.  It writes nothing else, and what
     * the steps and the next points use must not wait for it. */
    ModelStatus (*refresh_outputs)(void *data, const ModelLogger *log);
    /* A deserialized state that can step again is checked field by field
     * before it is accepted (the checksum only detects accidents: anyone can
     * recompute it).  The layer checks the variables of the table, re-runs
     * initialize on a copy of the state and checks each entry of state_fields
     * against it; every 8-byte word of the data block that no variable or
     * entry covers must be a finite double.  So every field that is not a
     * double must be listed, with its range or as derived. */
    const struct StateField *state_fields;
    size_t n_state_fields;
    /* Optional (NULL: nothing more): the invariants between fields that the
     * table cannot state (indices below a count held in another field).
     * `initialized` is the state's own parameters and inputs through
     * initialize.  May log; MODEL_ERROR refuses the state. */
    ModelStatus (*check_restored)(const void *data, const void *initialized,
                                  const ModelLogger *log);
    /* Optional (resource_file NULL: none): a file of the FMU's resources folder
     * that the model reads at instantiation (the model file of ModelObserver).
     * parse_resource reads its text (at most resource_max_bytes) into the
     * resource region [resource_offset, resource_offset + resource_size) of a
     * data block; MODEL_ERROR (after logging why) refuses the instantiation.
     * The region is pointer-free and holds no variable; the layer keeps it
     * through resets, and a restored state must hold this instance's region
     * byte for byte (a state of another model file is refused). */
    const char *resource_file;
    size_t resource_offset, resource_size, resource_max_bytes;
    ModelStatus (*parse_resource)(void *region, const char *text, size_t length,
                                  const ModelLogger *log);
    /* Optional: the start values the resource sets (after the table's), so that
     * an FMU whose modelDescription is written with its resource states them. */
    void (*resource_start_values)(void *data);
} ModelDescriptor;

/* Every model has the parameter max_internal_steps, at the same value
 * reference, with the same default and description. */
#define MAX_INTERNAL_STEPS_VR 120
#define MAX_INTERNAL_STEPS_DEFAULT 10000000
#define MAX_INTERNAL_STEPS_VARIABLE(field_offset)                                                 \
    {.name = "max_internal_steps", .vr = MAX_INTERNAL_STEPS_VR, .type = TYPE_INTEGER,             \
     PARAM(.offset = (field_offset), .start = MAX_INTERNAL_STEPS_DEFAULT, .min = 1,               \
           .max = 2147483647,                                                                     \
           .description = "Most internal steps one doStep may take; a longer communication "    \
                          "step is refused with an error before any work (the work budget "      \
                          "max_work bounds it too). Raise it for longer steps (docs/observer.md, " \
                          "Limits)")}

/* Every model has the parameter max_work and the calculated parameter
 * work_per_step, at the same value references.  A work unit is about a
 * nanosecond of one core of a 2020s x86-64 machine: each model's
 * work_per_step is an upper bound of its measured time per internal step in
 * its configuration (docs/observer.md, Limits), so the default budget of 10^9
 * units bounds one doStep to about a second. */
#define MAX_WORK_VR 121
#define WORK_PER_STEP_VR 122
#define MAX_WORK_DEFAULT 1e9
#define WORK_VARIABLES(max_work_offset, work_per_step_offset)                                     \
    {.name = "max_work", .vr = MAX_WORK_VR, .type = TYPE_REAL,                                     \
     PARAM(.offset = (max_work_offset), .start = MAX_WORK_DEFAULT, .min = 0.0, .max = NAN,        \
           .min_exclusive = true,                                                                 \
           .description = "Work budget of one doStep in work units (about a nanosecond of "      \
                          "one core each): a communication step whose internal steps times "      \
                          "work_per_step exceed it is refused with an error before any work "     \
                          "(10^9: about 1 s). Raise it for longer steps (docs/observer.md, "      \
                          "Limits)")},                                                            \
    {.name = "work_per_step", .vr = WORK_PER_STEP_VR, .type = TYPE_REAL,                           \
     CALC(.offset = (work_per_step_offset),                                                       \
          .description = "Work units of one internal step in this configuration (the "           \
                         "model's estimate; the budget max_work allows max_work / "               \
                         "work_per_step internal steps per doStep)")}

/* Each model file defines exactly one of these (read-only, not state). */
extern const ModelDescriptor MODEL_DESCRIPTOR;

/* Expanded element count of a variable (1 for a scalar). */
static inline size_t model_variable_count(const ModelVariable *v)
{
    return (size_t)(v->rows ? v->rows : 1) * (size_t)(v->cols ? v->cols : 1);
}

#endif
