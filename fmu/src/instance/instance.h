/* The model-independent instance core shared by the FMI 2 and FMI 3 API
 * files (fmi2/fmi2_functions.c, fmi3/fmi3_functions.c): the variable table
 * (get/set with validation), the fixed-step clock, the FMU state snapshots
 * and their serialization, and message formatting.  No FMI types appear
 * here: the API files own the state machines and the importer's callbacks,
 * and describe themselves to the core with an InstanceApi.
 *
 * There is no global mutable state: everything lives in the instance. */
#ifndef INSTANCE_H
#define INSTANCE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "model_interface.h"

/* Same numbering as fmi2Status and fmi3Status. */
typedef enum {
    STATUS_OK = 0,
    STATUS_WARNING = 1,
    STATUS_DISCARD = 2,
    STATUS_ERROR = 3,
    STATUS_FATAL = 4
} Status;

/* Any function pointer: the importer's logger, cast back by the API's sink. */
typedef void (*AnyFunction)(void);

/* Hands one formatted message to the importer's logger. */
typedef void (*LogSink)(AnyFunction logger, void *environment, const char *instance_name,
                        Status status, const char *category, const char *message);

/* What the core needs to know about the API file above it. */
typedef struct {
    LogSink sink;
    const char *(*state_name)(uint32_t state);
    uint32_t instantiated_state;     /* the state after instantiation and reset */
    uint32_t error_state;            /* where an error leaves the instance */
    uint32_t restorable_states;      /* states a deserialized FMU state may carry */
    uint32_t unstarted_states;       /* before initialization: the model data is the start
                                      * values plus what the setters wrote */
    uint32_t stepping_states;        /* from which doStep runs the model: a restored model
                                      * state must be whole (every field checked) */
    uint32_t parameter_states;       /* states in which fixed parameters may be set */
    bool array_references;           /* FMI 3: one value reference per array */
    bool c_bool;                     /* booleans are C bool (FMI 3), not int (FMI 2) */
    bool time_at_vr0;                /* value reference 0 is the independent variable time */
    char state_magic[8];             /* first bytes of a serialized FMU state */
} InstanceApi;

/* Everything besides the model data that an FMU state must capture. */
typedef struct {
    uint32_t state;
    uint32_t stop_time_defined;
    uint64_t steps;      /* internal steps taken since start_time: time = start + steps * h */
    double start_time;
    double stop_time;
    double comm_time;    /* the currentCommunicationPoint the next doStep must carry */
} Clock;

typedef struct Snapshot Snapshot;

#define MAX_OUTPUT_SPANS 32

typedef struct {
    Clock clock;
    void *data;
    char *name;
    const InstanceApi *api;
    AnyFunction logger;
    void *environment;
    bool logging_on;
    /* Real outputs as (byte offset, count) spans of the data block, for the
     * cheap finiteness check after every step (built once) */
    uint32_t output_span_offset[MAX_OUTPUT_SPANS], output_span_count[MAX_OUTPUT_SPANS];
    size_t n_output_spans;
    /* value reference -> index in the variable table (-1: none), built once */
    int16_t *variable_of_vr;
    uint32_t vr_limit;
    /* The model's resource region as read at instantiation (NULL: none) */
    unsigned char *resource;
    /* Snapshots handed out by this instance: a pointer the importer passes
     * back is only dereferenced if it is one of these. */
    Snapshot **snapshots;
    size_t n_snapshots, snapshot_capacity;
} Instance;

/* ---- lifecycle ---- */
/* Checks the instance name and the token, logging why they are refused. */
bool instance_arguments_valid(const InstanceApi *api, AnyFunction logger, void *environment,
                              const char *function, const char *name, const char *token);
/* NULL (after logging) if out of memory, or if the model reads a resource file
 * (ModelDescriptor.resource_file) that resource_dir (a native path, NULL: none
 * given) does not hold or that the model refuses.  Memory comes from the C library. */
Instance *instance_new(const InstanceApi *api, const char *function, const char *name,
                       AnyFunction logger, void *environment, bool logging_on,
                       const char *resource_dir);
void instance_free(Instance *inst);
/* Back to the freshly instantiated state (FMU states handed out stay valid). */
void instance_reset(Instance *inst);

/* ---- messages ---- */
void instance_log(const Instance *inst, Status status, const char *format, ...) PRINTF_LIKE(3, 4);
/* Logs an error and moves the instance to the API's error state. */
Status instance_fail(Instance *inst, const char *format, ...) PRINTF_LIKE(2, 3);
Status instance_escalate(Instance *inst, Status status);
/* Before there is an instance. */
void instance_log_to(const InstanceApi *api, AnyFunction logger, void *environment,
                     const char *name, Status status, const char *format, ...) PRINTF_LIKE(6, 7);
/* Checks the categories of a SetDebugLogging call and switches logging. */
Status instance_set_debug_logging(Instance *inst, const char *function, bool on,
                                  size_t n_categories, const char *const categories[]);

/* ---- experiment and clock ---- */
Status instance_setup_experiment(Instance *inst, const char *function, double start_time,
                                 bool stop_time_defined, double stop_time);
/* The model's initialize and the first output check; steps := 0. */
Status instance_initialize(Instance *inst, const char *function);
/* One communication step from t to t + H; an error leaves the clock at the
 * end of the last successful step. */
Status instance_do_step(Instance *inst, const char *function, double t, double H);

/* ---- variables ---- */
/* values: double, int, or bool/int per api->c_bool for booleans.  n_values is
 * the length of values (with array_references it may exceed nvr). */
Status instance_get(Instance *inst, const char *function, VariableType type,
                    const uint32_t vr[], size_t nvr, void *values, size_t n_values);
/* All-or-nothing: every value is checked before any is written. */
Status instance_set(Instance *inst, const char *function, VariableType type,
                    const uint32_t vr[], size_t nvr, const void *values, size_t n_values);
/* Refuses any value reference of a type this FMU has no variables of. */
Status instance_no_variables_of(Instance *inst, const char *function, const char *type,
                                const uint32_t vr[], size_t nvr, const void *values);

/* ---- FMU states ---- */
Status instance_get_state(Instance *inst, const char *function, void **state);
Status instance_set_state(Instance *inst, const char *function, const void *state);
Status instance_free_state(Instance *inst, const char *function, void **state);
Status instance_serialized_size(Instance *inst, const char *function, const void *state,
                                size_t *size);
Status instance_serialize(Instance *inst, const char *function, const void *state,
                          unsigned char *bytes, size_t size);
Status instance_deserialize(Instance *inst, const char *function, const unsigned char *bytes,
                            size_t size, void **state);

#endif
