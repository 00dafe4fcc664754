/* Model-independent FMI 2.0 Co-Simulation layer.
 *
 * Every FMU of the project (observer, plant, controller) links this file
 * unchanged with one model file that defines MODEL_DESCRIPTOR.  This layer
 * owns the instance lifecycle, the FMI 2 state machine (an allowed-state mask
 * per function, status escalation to the Error state), get/set through the
 * model's variable table, the fixed-step clock and the FMU state.
 *
 * There is no global mutable state: everything lives in the instance. */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "model_interface.h"

/* ---- instance state machine (FMI 2.0 standard, section 4.2.4) ---------- */

typedef enum {
    ST_INSTANTIATED = 1u << 0,
    ST_INIT_MODE = 1u << 1,
    ST_STEP_COMPLETE = 1u << 2,
    ST_STEP_IN_PROGRESS = 1u << 3, /* never entered: doStep is synchronous */
    ST_STEP_FAILED = 1u << 4,
    ST_STEP_CANCELED = 1u << 5,
    ST_TERMINATED = 1u << 6,
    ST_ERROR = 1u << 7,
    ST_FATAL = 1u << 8
} InstanceState;

#define ALIVE (ST_INSTANTIATED | ST_INIT_MODE | ST_STEP_COMPLETE | ST_STEP_FAILED | \
               ST_STEP_CANCELED | ST_TERMINATED | ST_ERROR)
#define MASK_SetDebugLogging (ALIVE | ST_STEP_IN_PROGRESS)
#define MASK_SetupExperiment ST_INSTANTIATED
#define MASK_EnterInitializationMode ST_INSTANTIATED
#define MASK_ExitInitializationMode ST_INIT_MODE
#define MASK_Terminate (ST_STEP_COMPLETE | ST_STEP_FAILED)
#define MASK_Reset ALIVE
#define MASK_Get (ST_INIT_MODE | ST_STEP_COMPLETE | ST_STEP_FAILED | ST_STEP_CANCELED | \
                  ST_TERMINATED | ST_ERROR)
#define MASK_Set (ST_INSTANTIATED | ST_INIT_MODE | ST_STEP_COMPLETE)
#define MASK_FMUstate ALIVE
#define MASK_DirectionalDerivative MASK_Get
#define MASK_SetRealInputDerivatives (ST_INSTANTIATED | ST_INIT_MODE | ST_STEP_COMPLETE)
#define MASK_GetRealOutputDerivatives (ST_STEP_COMPLETE | ST_STEP_FAILED | ST_STEP_CANCELED | \
                                       ST_TERMINATED | ST_ERROR)
#define MASK_DoStep ST_STEP_COMPLETE
#define MASK_CancelStep ST_STEP_IN_PROGRESS
#define MASK_GetStatus (ST_STEP_COMPLETE | ST_STEP_IN_PROGRESS | ST_STEP_FAILED | \
                        ST_TERMINATED | ST_ERROR)

/* Everything besides the model data that an FMU state must capture. */
typedef struct {
    uint32_t state;
    uint32_t stop_time_defined;
    uint64_t steps;      /* internal steps taken since start_time: time = start + steps * h */
    double start_time;
    double stop_time;
    double comm_time;    /* the currentCommunicationPoint the next fmi2DoStep must carry */
} Clock;

/* An FMU state: a snapshot of the clock and the model data block. */
typedef struct {
    Clock clock;
    unsigned char data[]; /* MODEL_DESCRIPTOR.data_size bytes */
} Snapshot;

#define MAX_OUTPUT_SPANS 32

typedef struct {
    Clock clock;
    void *data;
    char *name;
    fmi2CallbackLogger logger;
    fmi2ComponentEnvironment environment;
    fmi2CallbackAllocateMemory allocate;
    fmi2CallbackFreeMemory release;
    fmi2Boolean logging_on;
    /* Real outputs as (byte offset, count) spans of the data block, for the
     * cheap finiteness check after every step (built once) */
    uint32_t output_span_offset[MAX_OUTPUT_SPANS], output_span_count[MAX_OUTPUT_SPANS];
    size_t n_output_spans;
    /* value reference -> index in MD.variables (-1: none), built once */
    int16_t *variable_of_vr;
    uint32_t vr_limit;
    /* Snapshots handed out by this instance: a pointer the importer passes
     * back is only dereferenced if it is one of these. */
    Snapshot **snapshots;
    size_t n_snapshots, snapshot_capacity;
} Instance;

#define MD MODEL_DESCRIPTOR

/* ---- memory: the importer's functions, or the C library's if it gave none -- */

static void *mem_alloc(fmi2CallbackAllocateMemory allocate, size_t size)
{
    return allocate ? allocate(1, size) : calloc(1, size);
}

static void mem_free(fmi2CallbackFreeMemory release, void *p)
{
    if (!p) return;
    if (release) release(p); else free(p);
}

/* ---- logging ------------------------------------------------------------ */

static const char *const LOG_CATEGORIES[] = {"logStatusWarning", "logStatusError", "logAll"};
#define N_LOG_CATEGORIES (sizeof LOG_CATEGORIES / sizeof LOG_CATEGORIES[0])

/* The FMI 2 logger reads its message as a printf format (FMI 2.0 section
 * 2.1.5: importers such as the FMI Library expand it with vsnprintf) in which
 * #<type><value reference># names a variable.  Every text the FMU logs is
 * therefore escaped as the standard says: '%' as "%%" and '#' as "##" -- the
 * GUID, instance name, category names, variable names, numbers: everything
 * the message is made of, whoever supplied it.  Truncates at `size`, never
 * in the middle of an escape. */
static void escape_for_logger(const char *text, char *out, size_t size)
{
    size_t n = 0;
    for (; *text; ++text) {
        const size_t width = (*text == '%' || *text == '#') ? 2u : 1u;
        if (n + width >= size) break;
        out[n++] = *text;
        if (width == 2u) out[n++] = *text;
    }
    out[n] = '\0';
}

#define LOG_TEXT_SIZE 1024

static void vlog_to(fmi2CallbackLogger logger, fmi2ComponentEnvironment env, const char *name,
                    fmi2Boolean logging_on, fmi2Status status, const char *format, va_list args)
{
    if (!logger) return;
    /* Warnings and errors are always reported; OK-level messages only with debug logging. */
    if (status == fmi2OK && !logging_on) return;
    char text[LOG_TEXT_SIZE], message[2 * LOG_TEXT_SIZE];
    vsnprintf(text, sizeof text, format, args);
    escape_for_logger(text, message, sizeof message);
    const char *category = status >= fmi2Error ? "logStatusError"
                           : status == fmi2Warning ? "logStatusWarning" : "logAll";
    logger(env, name ? name : "", status, category, message);
}

/* A message before there is an instance (fmi2Instantiate refusing). */
static void log_to(fmi2CallbackLogger logger, fmi2ComponentEnvironment env, const char *name,
                   fmi2Status status, const char *format, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 5, 6)))
#endif
    ;
static void log_to(fmi2CallbackLogger logger, fmi2ComponentEnvironment env, const char *name,
                   fmi2Status status, const char *format, ...)
{
    va_list args;
    va_start(args, format);
    vlog_to(logger, env, name, fmi2True, status, format, args);
    va_end(args);
}

static void log_instance(const Instance *inst, fmi2Status status, const char *format, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
static void log_instance(const Instance *inst, fmi2Status status, const char *format, ...)
{
    va_list args;
    va_start(args, format);
    vlog_to(inst->logger, inst->environment, inst->name, inst->logging_on, status, format, args);
    va_end(args);
}

static void model_log(void *context, ModelStatus status, const char *format, ...)
{
    const Instance *inst = context;
    va_list args;
    va_start(args, format);
    vlog_to(inst->logger, inst->environment, inst->name, inst->logging_on, (fmi2Status)status,
            format, args);
    va_end(args);
}

static ModelLogger model_logger(Instance *inst)
{
    ModelLogger logger = {model_log, inst};
    return logger;
}

static const char *state_name(uint32_t state)
{
    switch (state) {
    case ST_INSTANTIATED: return "Instantiated";
    case ST_INIT_MODE: return "InitializationMode";
    case ST_STEP_COMPLETE: return "StepComplete";
    case ST_STEP_IN_PROGRESS: return "StepInProgress";
    case ST_STEP_FAILED: return "StepFailed";
    case ST_STEP_CANCELED: return "StepCanceled";
    case ST_TERMINATED: return "Terminated";
    case ST_ERROR: return "Error";
    default: return "Fatal";
    }
}

/* An fmi2Error leaves the instance in the Error state (only fmi2Reset,
 * fmi2SetFMUstate, getters and fmi2FreeInstance remain allowed). */
static fmi2Status escalate(Instance *inst, fmi2Status status)
{
    if (status == fmi2Error) inst->clock.state = ST_ERROR;
    else if (status == fmi2Fatal) inst->clock.state = ST_FATAL;
    return status;
}

static fmi2Status fail(Instance *inst, const char *format, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;
static fmi2Status fail(Instance *inst, const char *format, ...)
{
    va_list args;
    va_start(args, format);
    vlog_to(inst->logger, inst->environment, inst->name, inst->logging_on, fmi2Error, format, args);
    va_end(args);
    return escalate(inst, fmi2Error);
}

/* Opens every function that takes an instance: NULL check and state mask. */
#define ENTER(function, mask)                                                              \
    Instance *inst = (Instance *)c;                                                        \
    if (!inst) return fmi2Error;                                                           \
    if (!(inst->clock.state & (mask)))                                                     \
        return fail(inst, "%s: illegal call sequence (not allowed in state %s)", function, \
                    state_name(inst->clock.state))

/* ---- start values ------------------------------------------------------- */

static void apply_start_values(void *data)
{
    memset(data, 0, MD.data_size);
    for (size_t v = 0; v < MD.n_variables; ++v) {
        const ModelVariable *var = &MD.variables[v];
        size_t count = model_variable_count(var);
        for (size_t e = 0; e < count; ++e) {
            double start = var->starts ? var->starts[e] : var->start;
            if (var->type == TYPE_REAL)
                ((double *)((char *)data + var->offset))[e] = start;
            else
                ((int *)((char *)data + var->offset))[e] = (int)start;
        }
    }
}

/* Value references are small and dense: one table lookup per get/set. */
static uint32_t count_value_references(void)
{
    uint32_t limit = 0;
    for (size_t v = 0; v < MD.n_variables; ++v) {
        const uint32_t end = MD.variables[v].vr + (uint32_t)model_variable_count(&MD.variables[v]);
        if (end > limit) limit = end;
    }
    return limit;
}

static void fill_vr_table(int16_t *table, uint32_t limit)
{
    for (uint32_t r = 0; r < limit; ++r) table[r] = -1;
    for (size_t v = 0; v < MD.n_variables; ++v)
        for (size_t e = 0; e < model_variable_count(&MD.variables[v]); ++e)
            table[MD.variables[v].vr + e] = (int16_t)v;
}

static void reset_clock(Clock *clock)
{
    memset(clock, 0, sizeof *clock);
    clock->state = ST_INSTANTIATED;
}

/* ---- sanity of a whole data block ----------------------------------------- */

static void element_name(const ModelVariable *var, size_t element, char *out, size_t size);
static int in_range(const ModelVariable *var, double value);
static double element_value(const void *data, const ModelVariable *var, size_t element);

static int is_checked_output(const ModelVariable *var, int with_calculated)
{
    return var->type == TYPE_REAL &&
           (var->causality == CAUSALITY_OUTPUT ||
            (with_calculated && var->causality == CAUSALITY_CALCULATED_PARAMETER));
}

static void build_output_spans(Instance *inst)
{
    inst->n_output_spans = 0;
    for (size_t v = 0; v < MD.n_variables; ++v) {
        const ModelVariable *var = &MD.variables[v];
        if (!is_checked_output(var, 0)) continue;
        if (inst->n_output_spans == MAX_OUTPUT_SPANS) { /* too many: always use the full scan */
            inst->n_output_spans = (size_t)-1;
            return;
        }
        inst->output_span_offset[inst->n_output_spans] = (uint32_t)var->offset;
        inst->output_span_count[inst->n_output_spans++] = (uint32_t)model_variable_count(var);
    }
}

/* An OK status never comes with a non-finite output: checks every Real output
 * (and, at initialization, calculated parameter); logs the first offender.
 * The usual case costs one multiply-add per output: x * 0 is NaN for inf and NaN. */
static int outputs_finite(const Instance *inst, const char *function, int with_calculated)
{
    if (!with_calculated && inst->n_output_spans != (size_t)-1) {
        double poison = 0.0;
        for (size_t s = 0; s < inst->n_output_spans; ++s) {
            const double *values =
                (const double *)((const char *)inst->data + inst->output_span_offset[s]);
            for (uint32_t e = 0; e < inst->output_span_count[s]; ++e) poison += values[e] * 0.0;
        }
        if (poison == 0.0) return 1;
    }
    for (size_t v = 0; v < MD.n_variables; ++v) {
        const ModelVariable *var = &MD.variables[v];
        if (!is_checked_output(var, with_calculated)) continue;
        const double *values = (const double *)((const char *)inst->data + var->offset);
        for (size_t e = 0; e < model_variable_count(var); ++e) {
            if (!isfinite(values[e])) {
                char name[64];
                element_name(var, e, name, sizeof name);
                log_instance(inst, fmi2Error, "%s: %s = %g is not finite (the parameters or "
                             "inputs drive the model out of range)", function, name, values[e]);
                return 0;
            }
        }
    }
    return 1;
}

/* A restored data block must satisfy what fmi2Set* enforces: every parameter
 * and input inside its range.  (The state checksum detects accidents, not a
 * forged buffer.)  Logs the first offender. */
static int data_valid(const Instance *inst, const char *function, const void *data)
{
    for (size_t v = 0; v < MD.n_variables; ++v) {
        const ModelVariable *var = &MD.variables[v];
        if (var->causality != CAUSALITY_PARAMETER && var->causality != CAUSALITY_INPUT) continue;
        for (size_t e = 0; e < model_variable_count(var); ++e) {
            const double value = element_value(data, var, e);
            if (!in_range(var, value)) {
                char name[64];
                element_name(var, e, name, sizeof name);
                log_instance(inst, fmi2Error, "%s: %s = %g in the state is not finite or out of "
                             "range", function, name, value);
                return 0;
            }
        }
    }
    return 1;
}

/* ---- common functions --------------------------------------------------- */

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[])
{
    ENTER("fmi2SetDebugLogging", MASK_SetDebugLogging);
    if (nCategories > 0 && !categories)
        return fail(inst, "fmi2SetDebugLogging: categories is NULL but nCategories = %zu",
                    nCategories);
    for (size_t i = 0; i < nCategories; ++i) {
        int known = 0;
        for (size_t k = 0; categories[i] && k < N_LOG_CATEGORIES; ++k)
            known |= strcmp(categories[i], LOG_CATEGORIES[k]) == 0;
        if (!known)
            return fail(inst, "fmi2SetDebugLogging: unknown log category \"%s\"",
                        categories[i] ? categories[i] : "(NULL)");
    }
    inst->logging_on = loggingOn ? fmi2True : fmi2False;
    return fmi2OK;
}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation,
                              const fmi2CallbackFunctions *functions, fmi2Boolean visible,
                              fmi2Boolean loggingOn)
{
    (void)fmuResourceLocation; /* no resources needed; NULL is accepted */
    (void)visible;
    if (!functions) return NULL; /* nobody to tell */
    fmi2CallbackLogger logger = functions->logger;
    fmi2ComponentEnvironment env = functions->componentEnvironment;
    /* allocateMemory and freeMemory must come as a pair. */
    fmi2CallbackAllocateMemory allocate = functions->allocateMemory;
    fmi2CallbackFreeMemory release = functions->freeMemory;
    if (!allocate || !release) allocate = NULL, release = NULL;

#define REFUSE(...)                                                                \
    do {                                                                           \
        log_to(logger, env, instanceName, fmi2Error, __VA_ARGS__);                 \
        return NULL;                                                               \
    } while (0)

    if (!instanceName || !instanceName[0])
        REFUSE("fmi2Instantiate: instanceName is NULL or empty");
    if (fmuType != fmi2CoSimulation)
        REFUSE("fmi2Instantiate: %s supports Co-Simulation only (fmuType = %d)",
               MD.model_identifier, (int)fmuType);
    if (!fmuGUID || strcmp(fmuGUID, MD.guid) != 0)
        REFUSE("fmi2Instantiate: GUID mismatch: got %s, this binary is %s",
               fmuGUID ? fmuGUID : "(NULL)", MD.guid);

    Instance *inst = mem_alloc(allocate, sizeof *inst);
    if (!inst) REFUSE("fmi2Instantiate: out of memory");
    memset(inst, 0, sizeof *inst);
    inst->allocate = allocate;
    inst->release = release;
    inst->logger = logger;
    inst->environment = env;
    inst->logging_on = loggingOn ? fmi2True : fmi2False;
    inst->name = mem_alloc(allocate, strlen(instanceName) + 1);
    inst->data = mem_alloc(allocate, MD.data_size);
    inst->vr_limit = count_value_references();
    inst->variable_of_vr = mem_alloc(allocate, inst->vr_limit * sizeof *inst->variable_of_vr);
    if (!inst->name || !inst->data || !inst->variable_of_vr) {
        mem_free(release, inst->name);
        mem_free(release, inst->data);
        mem_free(release, inst->variable_of_vr);
        mem_free(release, inst);
        REFUSE("fmi2Instantiate: out of memory");
    }
#undef REFUSE
    strcpy(inst->name, instanceName);
    fill_vr_table(inst->variable_of_vr, inst->vr_limit);
    build_output_spans(inst);
    reset_clock(&inst->clock);
    apply_start_values(inst->data);
    return inst;
}

static void free_snapshots(Instance *inst)
{
    for (size_t i = 0; i < inst->n_snapshots; ++i) mem_free(inst->release, inst->snapshots[i]);
    mem_free(inst->release, inst->snapshots);
    inst->snapshots = NULL;
    inst->n_snapshots = inst->snapshot_capacity = 0;
}

void fmi2FreeInstance(fmi2Component c)
{
    Instance *inst = (Instance *)c;
    if (!inst) return;
    if (!(inst->clock.state & ALIVE)) {
        log_instance(inst, fmi2Error, "fmi2FreeInstance: illegal call sequence (state %s)",
                     state_name(inst->clock.state));
    }
    free_snapshots(inst);
    mem_free(inst->release, inst->variable_of_vr);
    mem_free(inst->release, inst->data);
    mem_free(inst->release, inst->name);
    mem_free(inst->release, inst);
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined,
                               fmi2Real stopTime)
{
    ENTER("fmi2SetupExperiment", MASK_SetupExperiment);
    (void)toleranceDefined; /* fixed-step: the tolerance does not apply */
    (void)tolerance;
    if (!isfinite(startTime))
        return fail(inst, "fmi2SetupExperiment: startTime = %g is not finite", startTime);
    if (stopTimeDefined && !(isfinite(stopTime) && stopTime >= startTime))
        return fail(inst, "fmi2SetupExperiment: stopTime = %g must be finite and >= startTime = %g",
                    stopTime, startTime);
    inst->clock.start_time = startTime;
    inst->clock.comm_time = startTime;
    inst->clock.stop_time_defined = stopTimeDefined ? 1u : 0u;
    inst->clock.stop_time = stopTimeDefined ? stopTime : 0.0;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c)
{
    ENTER("fmi2EnterInitializationMode", MASK_EnterInitializationMode);
    inst->clock.state = ST_INIT_MODE;
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c)
{
    ENTER("fmi2ExitInitializationMode", MASK_ExitInitializationMode);
    ModelLogger logger = model_logger(inst);
    ModelStatus status = MD.initialize(inst->data, inst->clock.start_time, &logger);
    if (status == MODEL_ERROR || !outputs_finite(inst, "fmi2ExitInitializationMode", 1))
        return escalate(inst, fmi2Error);
    inst->clock.steps = 0;
    inst->clock.comm_time = inst->clock.start_time;
    inst->clock.state = ST_STEP_COMPLETE;
    return (fmi2Status)status;
}

fmi2Status fmi2Terminate(fmi2Component c)
{
    ENTER("fmi2Terminate", MASK_Terminate);
    inst->clock.state = ST_TERMINATED;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component c)
{
    ENTER("fmi2Reset", MASK_Reset);
    /* Exactly the freshly instantiated state; FMU states already handed out stay valid. */
    reset_clock(&inst->clock);
    apply_start_values(inst->data);
    return fmi2OK;
}

/* ---- get / set ---------------------------------------------------------- */

static const ModelVariable *find_variable(const Instance *inst, fmi2ValueReference vr,
                                          size_t *element)
{
    if (vr >= inst->vr_limit || inst->variable_of_vr[vr] < 0) return NULL;
    const ModelVariable *var = &MD.variables[inst->variable_of_vr[vr]];
    *element = vr - var->vr;
    return var;
}

static const char *type_name(VariableType type)
{
    return type == TYPE_REAL ? "Real" : type == TYPE_INTEGER ? "Integer" : "Boolean";
}

/* The structured FMI name of one element, e.g. theta_hat[1,3]. */
static void element_name(const ModelVariable *var, size_t element, char *out, size_t size)
{
    if (!var->rows) snprintf(out, size, "%s", var->name);
    else if (!var->cols) snprintf(out, size, "%s[%zu]", var->name, element + 1);
    else snprintf(out, size, "%s[%zu,%zu]", var->name, element / var->cols + 1,
                  element % var->cols + 1);
}

/* Resolves vr for a get or set of the given type; logs and returns NULL if it cannot. */
static void *locate(Instance *inst, const char *function, fmi2ValueReference vr,
                    VariableType type, const ModelVariable **out_var, size_t *out_element)
{
    size_t element = 0;
    const ModelVariable *var = find_variable(inst, vr, &element);
    if (!var) {
        log_instance(inst, fmi2Error, "%s: unknown value reference %u", function, (unsigned)vr);
        return NULL;
    }
    if (var->type != type) {
        char name[64];
        element_name(var, element, name, sizeof name);
        log_instance(inst, fmi2Error, "%s: %s (value reference %u) is a %s, not a %s", function,
                     name, (unsigned)vr, type_name(var->type), type_name(type));
        return NULL;
    }
    *out_var = var;
    *out_element = element;
    char *base = (char *)inst->data + var->offset;
    return type == TYPE_REAL ? (void *)((double *)base + element) : (void *)((int *)base + element);
}

static fmi2Status check_arrays(Instance *inst, const char *function, const void *vr, size_t nvr,
                               const void *values)
{
    if (nvr > 0 && (!vr || !values))
        return fail(inst, "%s: vr or value array is NULL with nvr = %zu", function, nvr);
    return fmi2OK;
}

static fmi2Status get_values(Instance *inst, const char *function, VariableType type,
                             const fmi2ValueReference vr[], size_t nvr, void *values)
{
    if (check_arrays(inst, function, vr, nvr, values) != fmi2OK) return fmi2Error;
    for (size_t i = 0; i < nvr; ++i) {
        const ModelVariable *var;
        size_t element;
        void *slot = locate(inst, function, vr[i], type, &var, &element);
        if (!slot) return escalate(inst, fmi2Error);
        if (type == TYPE_REAL) ((fmi2Real *)values)[i] = *(double *)slot;
        else if (type == TYPE_INTEGER) ((fmi2Integer *)values)[i] = *(int *)slot;
        else ((fmi2Boolean *)values)[i] = *(int *)slot ? fmi2True : fmi2False;
    }
    return fmi2OK;
}

/* Is the value finite and inside the variable's declared range? */
static int in_range(const ModelVariable *var, double value)
{
    if (!isfinite(value)) return 0;
    if (!isnan(var->min) && (var->min_exclusive ? value <= var->min : value < var->min)) return 0;
    if (!isnan(var->max) && (var->max_exclusive ? value >= var->max : value > var->max)) return 0;
    return 1;
}

/* The value of one element of a data block, as a double. */
static double element_value(const void *data, const ModelVariable *var, size_t element)
{
    const char *base = (const char *)data + var->offset;
    return var->type == TYPE_REAL ? ((const double *)base)[element]
                                  : (double)((const int *)base)[element];
}

/* Is this element settable now, and is the value valid?  Logs why not (the
 * element's name is only formatted then: this runs on every set). */
static int accept_value(Instance *inst, const char *function, const ModelVariable *var,
                        size_t element, double value)
{
    enum { FINE, READ_ONLY, FIXED, NOT_FINITE, OUT_OF_RANGE } problem = FINE;
    if (var->causality == CAUSALITY_OUTPUT || var->causality == CAUSALITY_CALCULATED_PARAMETER)
        problem = READ_ONLY;
    else if (var->causality == CAUSALITY_PARAMETER &&
             !(inst->clock.state & (ST_INSTANTIATED | ST_INIT_MODE)))
        problem = FIXED;
    else if (!isfinite(value))
        problem = NOT_FINITE;
    else if (!in_range(var, value))
        problem = OUT_OF_RANGE;
    if (problem == FINE) return 1;

    char name[64];
    element_name(var, element, name, sizeof name);
    switch (problem) {
    case READ_ONLY:
        log_instance(inst, fmi2Error, "%s: %s is %s and cannot be set", function, name,
                     var->causality == CAUSALITY_OUTPUT ? "an output" : "a calculated parameter");
        break;
    case FIXED:
        log_instance(inst, fmi2Error,
                     "%s: %s is a fixed parameter and cannot be set after initialization "
                     "(state %s)", function, name, state_name(inst->clock.state));
        break;
    case NOT_FINITE:
        log_instance(inst, fmi2Error, "%s: %s = %g is not finite; value rejected", function, name,
                     value);
        break;
    default:
        /* Integer bounds in full (2147483647, not 2.14748e+09) */
        log_instance(inst, fmi2Error,
                     var->type == TYPE_REAL ? "%s: %s = %.17g is out of range %s%g, %g%s; value "
                                              "rejected"
                                            : "%s: %s = %.17g is out of range %s%.0f, %.0f%s; "
                                              "value rejected",
                     function, name, value, var->min_exclusive ? "(" : "[", var->min, var->max,
                     var->max_exclusive ? ")" : "]");
    }
    return 0;
}

/* All-or-nothing: every value is checked before any is written. */
static fmi2Status set_values(Instance *inst, const char *function, VariableType type,
                             const fmi2ValueReference vr[], size_t nvr, const void *values)
{
    if (check_arrays(inst, function, vr, nvr, values) != fmi2OK) return fmi2Error;
    for (int write = 0; write <= 1; ++write) {
        for (size_t i = 0; i < nvr; ++i) {
            const ModelVariable *var;
            size_t element;
            void *slot = locate(inst, function, vr[i], type, &var, &element);
            if (!slot) return escalate(inst, fmi2Error);
            double value = type == TYPE_REAL ? ((const fmi2Real *)values)[i]
                           : type == TYPE_INTEGER ? (double)((const fmi2Integer *)values)[i]
                           : (((const fmi2Boolean *)values)[i] ? 1.0 : 0.0);
            if (!write) {
                if (!accept_value(inst, function, var, element, value))
                    return escalate(inst, fmi2Error);
            } else if (type == TYPE_REAL) {
                *(double *)slot = value;
            } else {
                *(int *)slot = (int)value;
            }
        }
    }
    return fmi2OK;
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[])
{
    ENTER("fmi2GetReal", MASK_Get);
    return get_values(inst, "fmi2GetReal", TYPE_REAL, vr, nvr, value);
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Integer value[])
{
    ENTER("fmi2GetInteger", MASK_Get);
    return get_values(inst, "fmi2GetInteger", TYPE_INTEGER, vr, nvr, value);
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Boolean value[])
{
    ENTER("fmi2GetBoolean", MASK_Get);
    return get_values(inst, "fmi2GetBoolean", TYPE_BOOLEAN, vr, nvr, value);
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         fmi2String value[])
{
    ENTER("fmi2GetString", MASK_Get);
    if (check_arrays(inst, "fmi2GetString", vr, nvr, value) != fmi2OK) return fmi2Error;
    if (nvr > 0)
        return fail(inst, "fmi2GetString: unknown value reference %u (this FMU has no String "
                    "variables)", (unsigned)vr[0]);
    return fmi2OK;
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       const fmi2Real value[])
{
    ENTER("fmi2SetReal", MASK_Set);
    return set_values(inst, "fmi2SetReal", TYPE_REAL, vr, nvr, value);
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Integer value[])
{
    ENTER("fmi2SetInteger", MASK_Set);
    return set_values(inst, "fmi2SetInteger", TYPE_INTEGER, vr, nvr, value);
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Boolean value[])
{
    ENTER("fmi2SetBoolean", MASK_Set);
    return set_values(inst, "fmi2SetBoolean", TYPE_BOOLEAN, vr, nvr, value);
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         const fmi2String value[])
{
    ENTER("fmi2SetString", MASK_Set);
    if (check_arrays(inst, "fmi2SetString", vr, nvr, value) != fmi2OK) return fmi2Error;
    if (nvr > 0)
        return fail(inst, "fmi2SetString: unknown value reference %u (this FMU has no String "
                    "variables)", (unsigned)vr[0]);
    return fmi2OK;
}

/* ---- FMU state ---------------------------------------------------------- */

static size_t snapshot_size(void) { return sizeof(Snapshot) + MD.data_size; }

static int owns_snapshot(const Instance *inst, const Snapshot *s)
{
    for (size_t i = 0; i < inst->n_snapshots; ++i)
        if (inst->snapshots[i] == s) return 1;
    return 0;
}

static Snapshot *new_snapshot(Instance *inst)
{
    if (inst->n_snapshots == inst->snapshot_capacity) {
        size_t capacity = inst->snapshot_capacity ? 2 * inst->snapshot_capacity : 4;
        Snapshot **grown = mem_alloc(inst->allocate, capacity * sizeof *grown);
        if (!grown) return NULL;
        if (inst->n_snapshots) memcpy(grown, inst->snapshots, inst->n_snapshots * sizeof *grown);
        mem_free(inst->release, inst->snapshots);
        inst->snapshots = grown;
        inst->snapshot_capacity = capacity;
    }
    Snapshot *s = mem_alloc(inst->allocate, snapshot_size());
    if (s) inst->snapshots[inst->n_snapshots++] = s;
    return s;
}

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *FMUstate)
{
    ENTER("fmi2GetFMUstate", MASK_FMUstate);
    if (!FMUstate) return fail(inst, "fmi2GetFMUstate: FMUstate is NULL");
    Snapshot *s = *FMUstate;
    if (s && !owns_snapshot(inst, s))
        return fail(inst, "fmi2GetFMUstate: *FMUstate is neither NULL nor a state of this "
                    "instance (uninitialized pointer?)");
    if (!s && !(s = new_snapshot(inst))) return fail(inst, "fmi2GetFMUstate: out of memory");
    s->clock = inst->clock;
    memcpy(s->data, inst->data, MD.data_size);
    *FMUstate = s;
    return fmi2OK;
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate)
{
    ENTER("fmi2SetFMUstate", MASK_FMUstate);
    const Snapshot *s = FMUstate;
    if (!s || !owns_snapshot(inst, s))
        return fail(inst, "fmi2SetFMUstate: FMUstate is NULL or not a state of this instance");
    inst->clock = s->clock;
    memcpy(inst->data, s->data, MD.data_size);
    return fmi2OK;
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *FMUstate)
{
    ENTER("fmi2FreeFMUstate", MASK_FMUstate);
    if (!FMUstate || !*FMUstate) return fmi2OK; /* freeing nothing is harmless */
    Snapshot *s = *FMUstate;
    for (size_t i = 0; i < inst->n_snapshots; ++i) {
        if (inst->snapshots[i] == s) {
            inst->snapshots[i] = inst->snapshots[--inst->n_snapshots];
            mem_free(inst->release, s);
            *FMUstate = NULL;
            return fmi2OK;
        }
    }
    return fail(inst, "fmi2FreeFMUstate: not a state of this instance");
}

/* Serialized layout (native byte order; valid for the same binary):
 *   magic[8] "STOSTATE" | u32 version | u32 reserved | u64 total size |
 *   u64 hash of the GUID | u64 checksum of everything after it | Clock | model data */
#define STATE_MAGIC "STOSTATE"
#define STATE_VERSION 1u
typedef struct {
    char magic[8];
    uint32_t version;
    uint32_t reserved;
    uint64_t size;
    uint64_t guid_hash;
    uint64_t checksum;
} StateHeader;

static uint64_t fnv1a(const void *bytes, size_t n, uint64_t hash)
{
    const unsigned char *p = bytes;
    for (size_t i = 0; i < n; ++i) hash = (hash ^ p[i]) * 1099511628211ull;
    return hash;
}
#define FNV_OFFSET 14695981039346656037ull

static size_t serialized_size(void) { return sizeof(StateHeader) + snapshot_size(); }

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate, size_t *size)
{
    ENTER("fmi2SerializedFMUstateSize", MASK_FMUstate);
    if (!FMUstate || !owns_snapshot(inst, FMUstate) || !size)
        return fail(inst, "fmi2SerializedFMUstateSize: FMUstate or size is NULL or foreign");
    *size = serialized_size();
    return fmi2OK;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate, fmi2Byte serializedState[],
                                 size_t size)
{
    ENTER("fmi2SerializeFMUstate", MASK_FMUstate);
    if (!FMUstate || !owns_snapshot(inst, FMUstate) || !serializedState)
        return fail(inst, "fmi2SerializeFMUstate: FMUstate or buffer is NULL or foreign");
    if (size != serialized_size())
        return fail(inst, "fmi2SerializeFMUstate: buffer size %zu, expected %zu", size,
                    serialized_size());
    StateHeader header;
    memset(&header, 0, sizeof header);
    memcpy(header.magic, STATE_MAGIC, sizeof header.magic);
    header.version = STATE_VERSION;
    header.size = size;
    header.guid_hash = fnv1a(MD.guid, strlen(MD.guid), FNV_OFFSET);
    header.checksum = fnv1a(FMUstate, snapshot_size(), FNV_OFFSET);
    memcpy(serializedState, &header, sizeof header);
    memcpy(serializedState + sizeof header, FMUstate, snapshot_size());
    return fmi2OK;
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[], size_t size,
                                   fmi2FMUstate *FMUstate)
{
    ENTER("fmi2DeSerializeFMUstate", MASK_FMUstate);
    if (!serializedState || !FMUstate)
        return fail(inst, "fmi2DeSerializeFMUstate: buffer or FMUstate is NULL");
    if (size != serialized_size())
        return fail(inst, "fmi2DeSerializeFMUstate: wrong size %zu, a %s state has %zu bytes",
                    size, MD.model_identifier, serialized_size());
    StateHeader header;
    memcpy(&header, serializedState, sizeof header);
    if (memcmp(header.magic, STATE_MAGIC, sizeof header.magic) != 0)
        return fail(inst, "fmi2DeSerializeFMUstate: not a serialized FMU state (bad magic)");
    if (header.version != STATE_VERSION)
        return fail(inst, "fmi2DeSerializeFMUstate: format version %u, expected %u",
                    (unsigned)header.version, STATE_VERSION);
    if (header.size != size || header.guid_hash != fnv1a(MD.guid, strlen(MD.guid), FNV_OFFSET))
        return fail(inst, "fmi2DeSerializeFMUstate: state of another FMU or build");
    const fmi2Byte *payload = serializedState + sizeof header;
    if (header.checksum != fnv1a(payload, snapshot_size(), FNV_OFFSET))
        return fail(inst, "fmi2DeSerializeFMUstate: checksum mismatch (corrupted state)");
    Clock clock;
    memcpy(&clock, payload, sizeof clock);
    if (!(clock.state & ALIVE) || (clock.state & (clock.state - 1)))
        return fail(inst, "fmi2DeSerializeFMUstate: invalid instance state in buffer");
    const fmi2Byte *data = payload + offsetof(Snapshot, data);
    if (!data_valid(inst, "fmi2DeSerializeFMUstate", data)) return escalate(inst, fmi2Error);
    ModelLogger logger = model_logger(inst);
    if (MD.check_restored && MD.check_restored(data, &logger) == MODEL_ERROR)
        return escalate(inst, fmi2Error);
    /* The clock must be where its step count says: comm_time = start + steps h
     * (within a step); otherwise the next doStep could run ~2^53 steps. */
    const double h = MD.internal_step(data);
    const double grid_time = clock.start_time + (double)clock.steps * h;
    if (!isfinite(clock.start_time) || !isfinite(clock.comm_time) ||
        !isfinite(clock.stop_time) || !(fabs(clock.comm_time - grid_time) <= 2.0 * h))
        return fail(inst, "fmi2DeSerializeFMUstate: inconsistent clock in the state (time %g, "
                    "%llu steps of %g from %g)", clock.comm_time, (unsigned long long)clock.steps,
                    h, clock.start_time);
    Snapshot *s = *FMUstate;
    if (s && !owns_snapshot(inst, s))
        return fail(inst, "fmi2DeSerializeFMUstate: *FMUstate is not a state of this instance");
    if (!s && !(s = new_snapshot(inst)))
        return fail(inst, "fmi2DeSerializeFMUstate: out of memory");
    memcpy(s, payload, snapshot_size());
    *FMUstate = s;
    return fmi2OK;
}

/* ---- unsupported capabilities ------------------------------------------- */

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown_ref[],
                                        size_t nUnknown, const fmi2ValueReference vKnown_ref[],
                                        size_t nKnown, const fmi2Real dvKnown[],
                                        fmi2Real dvUnknown[])
{
    (void)vUnknown_ref, (void)nUnknown, (void)vKnown_ref, (void)nKnown, (void)dvKnown,
        (void)dvUnknown;
    ENTER("fmi2GetDirectionalDerivative", MASK_DirectionalDerivative);
    return fail(inst, "fmi2GetDirectionalDerivative is not supported "
                "(providesDirectionalDerivative = false)");
}

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[])
{
    (void)vr, (void)nvr, (void)order, (void)value;
    ENTER("fmi2SetRealInputDerivatives", MASK_SetRealInputDerivatives);
    return fail(inst, "fmi2SetRealInputDerivatives is not supported (canInterpolateInputs = false)");
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                        const fmi2Integer order[], fmi2Real value[])
{
    (void)vr, (void)nvr, (void)order, (void)value;
    ENTER("fmi2GetRealOutputDerivatives", MASK_GetRealOutputDerivatives);
    return fail(inst, "fmi2GetRealOutputDerivatives is not supported "
                "(maxOutputDerivativeOrder = 0)");
}

fmi2Status fmi2CancelStep(fmi2Component c)
{
    ENTER("fmi2CancelStep", MASK_CancelStep);
    return fail(inst, "fmi2CancelStep is not supported (canRunAsynchronuously = false)");
}

/* ---- stepping ----------------------------------------------------------- */

#define GRID_SLACK 1e-3

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint,
                      fmi2Real communicationStepSize, fmi2Boolean noSetFMUStatePriorToCurrentPoint)
{
    (void)noSetFMUStatePriorToCurrentPoint;
    ENTER("fmi2DoStep", MASK_DoStep);
    const double t = currentCommunicationPoint, H = communicationStepSize;
    const double h = MD.internal_step(inst->data);
    Clock *clock = &inst->clock;
    if (!(H > 0.0) || !isfinite(H))
        return fail(inst, "fmi2DoStep: communicationStepSize = %g must be > 0 and finite", H);
    /* Importers accumulate t += H, so allow a few ulp of disagreement. */
    const double tolerance = 1e-6 * h + 1e-12 * fabs(clock->comm_time);
    if (!isfinite(t) || fabs(t - clock->comm_time) > tolerance)
        return fail(inst, "fmi2DoStep: currentCommunicationPoint = %.17g is not the instance's "
                    "time %.17g", t, clock->comm_time);
    const double t_end = t + H;
    if (clock->stop_time_defined && t_end > clock->stop_time + tolerance)
        return fail(inst, "fmi2DoStep: step to %.17g goes past stopTime = %.17g", t_end,
                    clock->stop_time);
    /* Internal grid points start_time + k*h with k an integer (no drift).  A step
     * that is not a multiple of h runs every internal step ending at or before
     * t_end; the outputs then belong to the last grid point, less than h before t_end.
     * A grid point less than GRID_SLACK h after t_end counts as reached: a master
     * that accumulates t += H drifts off the grid by rounding, far more at large t. */
    const double k_end_real = floor((t_end - clock->start_time) / h + GRID_SLACK);
    /* The work of one call is bounded: refused before any of it is done. */
    const uint64_t limit = MD.max_internal_steps(inst->data);
    if (!(k_end_real < 9007199254740992.0))
        return fail(inst, "fmi2DoStep: step to %.17g needs more than 2^53 internal steps of "
                    "h = %g, more than the limit max_internal_steps = %llu allows; take shorter "
                    "communication steps", t_end, h, (unsigned long long)limit);
    const uint64_t k_end = k_end_real > (double)clock->steps ? (uint64_t)k_end_real : clock->steps;
    if (k_end - clock->steps > limit)
        return fail(inst, "fmi2DoStep: the step from %.17g to %.17g needs %llu internal steps of "
                    "h = %g, more than the limit max_internal_steps = %llu; take shorter "
                    "communication steps or raise the parameter max_internal_steps (value "
                    "reference %u) before initialization", t, t_end,
                    (unsigned long long)(k_end - clock->steps), h, (unsigned long long)limit,
                    (unsigned)MAX_INTERNAL_STEPS_VR);
    /* Called even when the step reaches no grid point (H < h): the model sees
     * every communication step's inputs (a rising edge of a discrete input
     * held for one short step is never lost). */
    MD.advance(inst->data, clock->start_time, clock->steps, k_end);
    ModelLogger logger = model_logger(inst);
    if (MD.communication_point(inst->data, t_end, &logger) == MODEL_ERROR ||
        !outputs_finite(inst, "fmi2DoStep", 0))
        return escalate(inst, fmi2Error); /* the clock stays at the last successful step's end
                                           * (fmi2LastSuccessfulTime) */
    clock->steps = k_end;
    clock->comm_time = t_end;
    return fmi2OK;
}

/* ---- status inquiry ----------------------------------------------------- */

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value)
{
    ENTER("fmi2GetStatus", MASK_GetStatus);
    if (!value) return fail(inst, "fmi2GetStatus: value is NULL");
    if (s != fmi2DoStepStatus) return fmi2Discard;
    *value = fmi2OK; /* doStep is synchronous: it never stays pending */
    return fmi2OK;
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value)
{
    ENTER("fmi2GetRealStatus", MASK_GetStatus);
    if (!value) return fail(inst, "fmi2GetRealStatus: value is NULL");
    if (s != fmi2LastSuccessfulTime) return fmi2Discard;
    *value = inst->clock.comm_time; /* a failed step leaves it at the end of the last good one */
    return fmi2OK;
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value)
{
    (void)s;
    ENTER("fmi2GetIntegerStatus", MASK_GetStatus);
    if (!value) return fail(inst, "fmi2GetIntegerStatus: value is NULL");
    return fmi2Discard; /* no Integer status is defined for this FMU */
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value)
{
    ENTER("fmi2GetBooleanStatus", MASK_GetStatus);
    if (!value) return fail(inst, "fmi2GetBooleanStatus: value is NULL");
    if (s != fmi2Terminated) return fmi2Discard;
    *value = fmi2False; /* the FMU never asks to end the simulation */
    return fmi2OK;
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value)
{
    (void)s;
    ENTER("fmi2GetStringStatus", MASK_GetStatus);
    if (!value) return fail(inst, "fmi2GetStringStatus: value is NULL");
    return fmi2Discard;
}
