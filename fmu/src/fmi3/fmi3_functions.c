/* The FMI 3.0 Co-Simulation API over the instance core (../instance/).
 *
 * This file owns what is FMI 3: its state machine (Instantiated,
 * InitializationMode, StepMode, Terminated; no event mode, no clocks, no
 * intermediate update), array variables with one value reference each,
 * fmi3DoStep's outputs, the logger callback, and the refusal of everything
 * this FMU does not provide (Model Exchange, Scheduled Execution, other
 * variable types, derivatives, configuration mode).  Everything else is the
 * core's, shared with the FMI 2 API. */
#include <string.h>

#include "fmi3Functions.h"
#include "../instance/instance.h"

/* The core stores Int32 values as int. */
typedef char int32_is_int[sizeof(fmi3Int32) == sizeof(int) ? 1 : -1];

typedef enum {
    ST_INSTANTIATED = 1u << 0,
    ST_INIT_MODE = 1u << 1,
    ST_STEP_MODE = 1u << 2,
    ST_TERMINATED = 1u << 3,
    ST_ERROR = 1u << 4
} InstanceState;

#define ALIVE (ST_INSTANTIATED | ST_INIT_MODE | ST_STEP_MODE | ST_TERMINATED | ST_ERROR)
#define MASK_EnterInitializationMode ST_INSTANTIATED
#define MASK_ExitInitializationMode ST_INIT_MODE
#define MASK_Terminate ST_STEP_MODE
#define MASK_Get (ST_INIT_MODE | ST_STEP_MODE | ST_TERMINATED | ST_ERROR)
#define MASK_Set (ST_INSTANTIATED | ST_INIT_MODE | ST_STEP_MODE)
#define MASK_DoStep ST_STEP_MODE

static const char *state_name(uint32_t state)
{
    switch (state) {
    case ST_INSTANTIATED: return "Instantiated";
    case ST_INIT_MODE: return "InitializationMode";
    case ST_STEP_MODE: return "StepMode";
    case ST_TERMINATED: return "Terminated";
    default: return "Error";
    }
}

/* The FMI 3 message is plain text (no printf format, no #vr# references):
 * passed on as it is. */
static void fmi3_sink(AnyFunction logger, void *environment, const char *instance_name,
                      Status status, const char *category, const char *message)
{
    (void)instance_name; /* the FMI 3 logger has no such argument */
    ((fmi3LogMessageCallback)logger)(environment, (fmi3Status)status, category, message);
}

static const InstanceApi FMI3_API = {
    .sink = fmi3_sink,
    .state_name = state_name,
    .instantiated_state = ST_INSTANTIATED,
    .error_state = ST_ERROR,
    .restorable_states = ALIVE,
    .unstarted_states = ST_INSTANTIATED | ST_INIT_MODE,
    .stepping_states = ST_STEP_MODE,
    .parameter_states = ST_INSTANTIATED | ST_INIT_MODE,
    .array_references = true,
    .c_bool = true,
    .time_at_vr0 = true,
    .state_magic = {'S', 'T', 'O', 'S', 'T', 'A', 'T', '3'},
};

/* Opens every function that takes an instance: NULL check and state mask. */
#define ENTER(function, mask)                                                              \
    Instance *inst = (Instance *)instance;                                                 \
    if (!inst) return fmi3Error;                                                           \
    if (!(inst->clock.state & (mask)))                                                     \
        return (fmi3Status)instance_fail(inst, "%s: illegal call sequence (not allowed in " \
                                         "state %s)", function, state_name(inst->clock.state))

/* A capability this FMU does not declare: refused with the reason. */
#define UNSUPPORTED(function, why)                                                     \
    ENTER(function, ALIVE);                                                            \
    return (fmi3Status)instance_fail(inst, "%s is not supported (%s)", function, why)

/* ---- common functions --------------------------------------------------- */

const char *fmi3GetVersion(void) { return fmi3Version; }

fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean loggingOn, size_t nCategories,
                               const fmi3String categories[])
{
    ENTER("fmi3SetDebugLogging", ALIVE);
    return (fmi3Status)instance_set_debug_logging(inst, "fmi3SetDebugLogging", loggingOn,
                                                  nCategories, categories);
}

fmi3Instance fmi3InstantiateCoSimulation(
    fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath,
    fmi3Boolean visible, fmi3Boolean loggingOn, fmi3Boolean eventModeUsed,
    fmi3Boolean earlyReturnAllowed, const fmi3ValueReference requiredIntermediateVariables[],
    size_t nRequiredIntermediateVariables, fmi3InstanceEnvironment instanceEnvironment,
    fmi3LogMessageCallback logMessage, fmi3IntermediateUpdateCallback intermediateUpdate)
{
    (void)visible, (void)intermediateUpdate;
    (void)earlyReturnAllowed; /* it never returns early */
    (void)requiredIntermediateVariables;
    const char *function = "fmi3InstantiateCoSimulation";
    AnyFunction logger = (AnyFunction)logMessage;
    if (eventModeUsed) {
        instance_log_to(&FMI3_API, logger, instanceEnvironment, instanceName, STATUS_ERROR,
                        "%s: eventModeUsed = true, but %s has no event mode (hasEventMode = "
                        "false)", function, MODEL_DESCRIPTOR.model_identifier);
        return NULL;
    }
    if (nRequiredIntermediateVariables > 0) {
        instance_log_to(&FMI3_API, logger, instanceEnvironment, instanceName, STATUS_ERROR,
                        "%s: %zu intermediate variables required, but %s provides no "
                        "intermediate update", function, nRequiredIntermediateVariables,
                        MODEL_DESCRIPTOR.model_identifier);
        return NULL;
    }
    if (!instance_arguments_valid(&FMI3_API, logger, instanceEnvironment, function,
                                  instanceName, instantiationToken))
        return NULL;
    return instance_new(&FMI3_API, function, instanceName, logger, instanceEnvironment,
                        loggingOn, resourcePath);
}

static void refuse_interface(fmi3InstanceEnvironment environment, fmi3LogMessageCallback log,
                             const char *name, const char *interface)
{
    instance_log_to(&FMI3_API, (AnyFunction)log, environment, name, STATUS_ERROR,
                    "fmi3Instantiate%s: %s supports Co-Simulation only", interface,
                    MODEL_DESCRIPTOR.model_identifier);
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName, fmi3String instantiationToken,
                                          fmi3String resourcePath, fmi3Boolean visible,
                                          fmi3Boolean loggingOn,
                                          fmi3InstanceEnvironment instanceEnvironment,
                                          fmi3LogMessageCallback logMessage)
{
    (void)instantiationToken, (void)resourcePath, (void)visible, (void)loggingOn;
    refuse_interface(instanceEnvironment, logMessage, instanceName, "ModelExchange");
    return NULL;
}

fmi3Instance fmi3InstantiateScheduledExecution(
    fmi3String instanceName, fmi3String instantiationToken, fmi3String resourcePath,
    fmi3Boolean visible, fmi3Boolean loggingOn, fmi3InstanceEnvironment instanceEnvironment,
    fmi3LogMessageCallback logMessage, fmi3ClockUpdateCallback clockUpdate,
    fmi3LockPreemptionCallback lockPreemption, fmi3UnlockPreemptionCallback unlockPreemption)
{
    (void)instantiationToken, (void)resourcePath, (void)visible, (void)loggingOn;
    (void)clockUpdate, (void)lockPreemption, (void)unlockPreemption;
    refuse_interface(instanceEnvironment, logMessage, instanceName, "ScheduledExecution");
    return NULL;
}

void fmi3FreeInstance(fmi3Instance instance) { instance_free((Instance *)instance); }

fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean toleranceDefined,
                                       fmi3Float64 tolerance, fmi3Float64 startTime,
                                       fmi3Boolean stopTimeDefined, fmi3Float64 stopTime)
{
    (void)toleranceDefined, (void)tolerance; /* fixed-step: the tolerance does not apply */
    ENTER("fmi3EnterInitializationMode", MASK_EnterInitializationMode);
    const Status status = instance_setup_experiment(inst, "fmi3EnterInitializationMode",
                                                    startTime, stopTimeDefined, stopTime);
    if (status == STATUS_OK) inst->clock.state = ST_INIT_MODE;
    return (fmi3Status)status;
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance instance)
{
    ENTER("fmi3ExitInitializationMode", MASK_ExitInitializationMode);
    const Status status = instance_initialize(inst, "fmi3ExitInitializationMode");
    if (status < STATUS_ERROR) inst->clock.state = ST_STEP_MODE; /* no event mode */
    return (fmi3Status)status;
}

fmi3Status fmi3EnterEventMode(fmi3Instance instance)
{
    UNSUPPORTED("fmi3EnterEventMode", "hasEventMode = false");
}

fmi3Status fmi3Terminate(fmi3Instance instance)
{
    ENTER("fmi3Terminate", MASK_Terminate);
    inst->clock.state = ST_TERMINATED;
    return fmi3OK;
}

fmi3Status fmi3Reset(fmi3Instance instance)
{
    ENTER("fmi3Reset", ALIVE);
    instance_reset(inst);
    return fmi3OK;
}

/* ---- get / set: Float64, Int32 and Boolean variables --------------------- */

#define GETTER(Type, variable_type, c_type)                                                    \
    fmi3Status fmi3Get##Type(fmi3Instance instance, const fmi3ValueReference valueReferences[], \
                             size_t nValueReferences, c_type values[], size_t nValues)         \
    {                                                                                          \
        ENTER("fmi3Get" #Type, MASK_Get);                                                      \
        return (fmi3Status)instance_get(inst, "fmi3Get" #Type, variable_type, valueReferences, \
                                        nValueReferences, values, nValues);                   \
    }
#define SETTER(Type, variable_type, c_type)                                                    \
    fmi3Status fmi3Set##Type(fmi3Instance instance, const fmi3ValueReference valueReferences[], \
                             size_t nValueReferences, const c_type values[], size_t nValues)   \
    {                                                                                          \
        ENTER("fmi3Set" #Type, MASK_Set);                                                      \
        return (fmi3Status)instance_set(inst, "fmi3Set" #Type, variable_type, valueReferences, \
                                        nValueReferences, values, nValues);                   \
    }
GETTER(Float64, TYPE_REAL, fmi3Float64)
GETTER(Int32, TYPE_INTEGER, fmi3Int32)
GETTER(Boolean, TYPE_BOOLEAN, fmi3Boolean)
SETTER(Float64, TYPE_REAL, fmi3Float64)
SETTER(Int32, TYPE_INTEGER, fmi3Int32)
SETTER(Boolean, TYPE_BOOLEAN, fmi3Boolean)

/* Types this FMU has no variables of: any value reference is unknown. */
#define NO_VARIABLES(Verb, Type, mask, values_type)                                             \
    fmi3Status fmi3##Verb##Type(fmi3Instance instance,                                          \
                                const fmi3ValueReference valueReferences[],                     \
                                size_t nValueReferences, values_type values[], size_t nValues)  \
    {                                                                                           \
        (void)nValues;                                                                          \
        ENTER("fmi3" #Verb #Type, mask);                                                        \
        return (fmi3Status)instance_no_variables_of(inst, "fmi3" #Verb #Type, #Type,            \
                                                    valueReferences, nValueReferences, values); \
    }
NO_VARIABLES(Get, Float32, MASK_Get, fmi3Float32)
NO_VARIABLES(Get, Int8, MASK_Get, fmi3Int8)
NO_VARIABLES(Get, UInt8, MASK_Get, fmi3UInt8)
NO_VARIABLES(Get, Int16, MASK_Get, fmi3Int16)
NO_VARIABLES(Get, UInt16, MASK_Get, fmi3UInt16)
NO_VARIABLES(Get, UInt32, MASK_Get, fmi3UInt32)
NO_VARIABLES(Get, Int64, MASK_Get, fmi3Int64)
NO_VARIABLES(Get, UInt64, MASK_Get, fmi3UInt64)
NO_VARIABLES(Get, String, MASK_Get, fmi3String)
NO_VARIABLES(Set, Float32, MASK_Set, const fmi3Float32)
NO_VARIABLES(Set, Int8, MASK_Set, const fmi3Int8)
NO_VARIABLES(Set, UInt8, MASK_Set, const fmi3UInt8)
NO_VARIABLES(Set, Int16, MASK_Set, const fmi3Int16)
NO_VARIABLES(Set, UInt16, MASK_Set, const fmi3UInt16)
NO_VARIABLES(Set, UInt32, MASK_Set, const fmi3UInt32)
NO_VARIABLES(Set, Int64, MASK_Set, const fmi3Int64)
NO_VARIABLES(Set, UInt64, MASK_Set, const fmi3UInt64)
NO_VARIABLES(Set, String, MASK_Set, const fmi3String)

fmi3Status fmi3GetBinary(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                         size_t nValueReferences, size_t valueSizes[], fmi3Binary values[],
                         size_t nValues)
{
    (void)valueSizes, (void)nValues;
    ENTER("fmi3GetBinary", MASK_Get);
    return (fmi3Status)instance_no_variables_of(inst, "fmi3GetBinary", "Binary", valueReferences,
                                                nValueReferences, values);
}

fmi3Status fmi3SetBinary(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                         size_t nValueReferences, const size_t valueSizes[],
                         const fmi3Binary values[], size_t nValues)
{
    (void)valueSizes, (void)nValues;
    ENTER("fmi3SetBinary", MASK_Set);
    return (fmi3Status)instance_no_variables_of(inst, "fmi3SetBinary", "Binary", valueReferences,
                                                nValueReferences, values);
}

fmi3Status fmi3GetClock(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                        size_t nValueReferences, fmi3Clock values[])
{
    ENTER("fmi3GetClock", ALIVE);
    return (fmi3Status)instance_no_variables_of(inst, "fmi3GetClock", "Clock", valueReferences,
                                                nValueReferences, values);
}

fmi3Status fmi3SetClock(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                        size_t nValueReferences, const fmi3Clock values[])
{
    ENTER("fmi3SetClock", ALIVE);
    return (fmi3Status)instance_no_variables_of(inst, "fmi3SetClock", "Clock", valueReferences,
                                                nValueReferences, values);
}

/* ---- FMU state ---------------------------------------------------------- */

fmi3Status fmi3GetFMUState(fmi3Instance instance, fmi3FMUState *FMUState)
{
    ENTER("fmi3GetFMUState", ALIVE);
    return (fmi3Status)instance_get_state(inst, "fmi3GetFMUState", FMUState);
}

fmi3Status fmi3SetFMUState(fmi3Instance instance, fmi3FMUState FMUState)
{
    ENTER("fmi3SetFMUState", ALIVE);
    return (fmi3Status)instance_set_state(inst, "fmi3SetFMUState", FMUState);
}

fmi3Status fmi3FreeFMUState(fmi3Instance instance, fmi3FMUState *FMUState)
{
    ENTER("fmi3FreeFMUState", ALIVE);
    return (fmi3Status)instance_free_state(inst, "fmi3FreeFMUState", FMUState);
}

fmi3Status fmi3SerializedFMUStateSize(fmi3Instance instance, fmi3FMUState FMUState, size_t *size)
{
    ENTER("fmi3SerializedFMUStateSize", ALIVE);
    return (fmi3Status)instance_serialized_size(inst, "fmi3SerializedFMUStateSize", FMUState,
                                                size);
}

fmi3Status fmi3SerializeFMUState(fmi3Instance instance, fmi3FMUState FMUState,
                                 fmi3Byte serializedState[], size_t size)
{
    ENTER("fmi3SerializeFMUState", ALIVE);
    return (fmi3Status)instance_serialize(inst, "fmi3SerializeFMUState", FMUState,
                                          serializedState, size);
}

fmi3Status fmi3DeserializeFMUState(fmi3Instance instance, const fmi3Byte serializedState[],
                                   size_t size, fmi3FMUState *FMUState)
{
    ENTER("fmi3DeserializeFMUState", ALIVE);
    return (fmi3Status)instance_deserialize(inst, "fmi3DeserializeFMUState", serializedState,
                                            size, FMUState);
}

/* ---- stepping ----------------------------------------------------------- */

fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 currentCommunicationPoint,
                      fmi3Float64 communicationStepSize,
                      fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                      fmi3Boolean *eventHandlingNeeded, fmi3Boolean *terminateSimulation,
                      fmi3Boolean *earlyReturn, fmi3Float64 *lastSuccessfulTime)
{
    (void)noSetFMUStatePriorToCurrentPoint;
    ENTER("fmi3DoStep", MASK_DoStep);
    if (!eventHandlingNeeded || !terminateSimulation || !earlyReturn || !lastSuccessfulTime)
        return (fmi3Status)instance_fail(inst, "fmi3DoStep: eventHandlingNeeded, "
                                         "terminateSimulation, earlyReturn or lastSuccessfulTime "
                                         "is NULL");
    const Status status = instance_do_step(inst, "fmi3DoStep", currentCommunicationPoint,
                                           communicationStepSize);
    /* No events, never a request to stop, never an early return; the time
     * reached is the end of the last successful step (this one if it succeeded). */
    *eventHandlingNeeded = fmi3False;
    *terminateSimulation = fmi3False;
    *earlyReturn = fmi3False;
    *lastSuccessfulTime = inst->clock.comm_time;
    return (fmi3Status)status;
}

fmi3Status fmi3EnterStepMode(fmi3Instance instance)
{
    /* Only reachable from event mode, which this FMU does not have. */
    ENTER("fmi3EnterStepMode", 0u);
    return fmi3Error;
}

fmi3Status fmi3GetOutputDerivatives(fmi3Instance instance,
                                    const fmi3ValueReference valueReferences[],
                                    size_t nValueReferences, const fmi3Int32 orders[],
                                    fmi3Float64 values[], size_t nValues)
{
    (void)valueReferences, (void)nValueReferences, (void)orders, (void)values, (void)nValues;
    UNSUPPORTED("fmi3GetOutputDerivatives", "maxOutputDerivativeOrder = 0");
}

/* ---- capabilities this FMU does not declare -------------------------------- */

fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance instance,
                                               fmi3ValueReference valueReference,
                                               size_t *nDependencies)
{
    (void)valueReference, (void)nDependencies;
    UNSUPPORTED("fmi3GetNumberOfVariableDependencies", "no per-element dependencies");
}

fmi3Status fmi3GetVariableDependencies(fmi3Instance instance, fmi3ValueReference dependent,
                                       size_t elementIndicesOfDependent[],
                                       fmi3ValueReference independents[],
                                       size_t elementIndicesOfIndependents[],
                                       fmi3DependencyKind dependencyKinds[], size_t nDependencies)
{
    (void)dependent, (void)elementIndicesOfDependent, (void)independents;
    (void)elementIndicesOfIndependents, (void)dependencyKinds, (void)nDependencies;
    UNSUPPORTED("fmi3GetVariableDependencies", "no per-element dependencies");
}

fmi3Status fmi3GetDirectionalDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[],
                                        size_t nUnknowns, const fmi3ValueReference knowns[],
                                        size_t nKnowns, const fmi3Float64 seed[], size_t nSeed,
                                        fmi3Float64 sensitivity[], size_t nSensitivity)
{
    (void)unknowns, (void)nUnknowns, (void)knowns, (void)nKnowns, (void)seed, (void)nSeed;
    (void)sensitivity, (void)nSensitivity;
    UNSUPPORTED("fmi3GetDirectionalDerivative", "providesDirectionalDerivatives = false");
}

fmi3Status fmi3GetAdjointDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[],
                                    size_t nUnknowns, const fmi3ValueReference knowns[],
                                    size_t nKnowns, const fmi3Float64 seed[], size_t nSeed,
                                    fmi3Float64 sensitivity[], size_t nSensitivity)
{
    (void)unknowns, (void)nUnknowns, (void)knowns, (void)nKnowns, (void)seed, (void)nSeed;
    (void)sensitivity, (void)nSensitivity;
    UNSUPPORTED("fmi3GetAdjointDerivative", "providesAdjointDerivatives = false");
}

fmi3Status fmi3EnterConfigurationMode(fmi3Instance instance)
{
    UNSUPPORTED("fmi3EnterConfigurationMode", "no structural parameters");
}

fmi3Status fmi3ExitConfigurationMode(fmi3Instance instance)
{
    UNSUPPORTED("fmi3ExitConfigurationMode", "no structural parameters");
}

#define NO_CLOCKS "this FMU has no clocks"

fmi3Status fmi3GetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                  size_t nValueReferences, fmi3Float64 intervals[],
                                  fmi3IntervalQualifier qualifiers[])
{
    (void)valueReferences, (void)nValueReferences, (void)intervals, (void)qualifiers;
    UNSUPPORTED("fmi3GetIntervalDecimal", NO_CLOCKS);
}

fmi3Status fmi3GetIntervalFraction(fmi3Instance instance,
                                   const fmi3ValueReference valueReferences[],
                                   size_t nValueReferences, fmi3UInt64 counters[],
                                   fmi3UInt64 resolutions[], fmi3IntervalQualifier qualifiers[])
{
    (void)valueReferences, (void)nValueReferences, (void)counters, (void)resolutions;
    (void)qualifiers;
    UNSUPPORTED("fmi3GetIntervalFraction", NO_CLOCKS);
}

fmi3Status fmi3GetShiftDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                               size_t nValueReferences, fmi3Float64 shifts[])
{
    (void)valueReferences, (void)nValueReferences, (void)shifts;
    UNSUPPORTED("fmi3GetShiftDecimal", NO_CLOCKS);
}

fmi3Status fmi3GetShiftFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                size_t nValueReferences, fmi3UInt64 counters[],
                                fmi3UInt64 resolutions[])
{
    (void)valueReferences, (void)nValueReferences, (void)counters, (void)resolutions;
    UNSUPPORTED("fmi3GetShiftFraction", NO_CLOCKS);
}

fmi3Status fmi3SetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                  size_t nValueReferences, const fmi3Float64 intervals[])
{
    (void)valueReferences, (void)nValueReferences, (void)intervals;
    UNSUPPORTED("fmi3SetIntervalDecimal", NO_CLOCKS);
}

fmi3Status fmi3SetIntervalFraction(fmi3Instance instance,
                                   const fmi3ValueReference valueReferences[],
                                   size_t nValueReferences, const fmi3UInt64 counters[],
                                   const fmi3UInt64 resolutions[])
{
    (void)valueReferences, (void)nValueReferences, (void)counters, (void)resolutions;
    UNSUPPORTED("fmi3SetIntervalFraction", NO_CLOCKS);
}

fmi3Status fmi3SetShiftDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                               size_t nValueReferences, const fmi3Float64 shifts[])
{
    (void)valueReferences, (void)nValueReferences, (void)shifts;
    UNSUPPORTED("fmi3SetShiftDecimal", NO_CLOCKS);
}

fmi3Status fmi3SetShiftFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                size_t nValueReferences, const fmi3UInt64 counters[],
                                const fmi3UInt64 resolutions[])
{
    (void)valueReferences, (void)nValueReferences, (void)counters, (void)resolutions;
    UNSUPPORTED("fmi3SetShiftFraction", NO_CLOCKS);
}

fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance instance)
{
    UNSUPPORTED("fmi3EvaluateDiscreteStates", NO_CLOCKS);
}

fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean *discreteStatesNeedUpdate,
                                    fmi3Boolean *terminateSimulation,
                                    fmi3Boolean *nominalsOfContinuousStatesChanged,
                                    fmi3Boolean *valuesOfContinuousStatesChanged,
                                    fmi3Boolean *nextEventTimeDefined, fmi3Float64 *nextEventTime)
{
    (void)discreteStatesNeedUpdate, (void)terminateSimulation;
    (void)nominalsOfContinuousStatesChanged, (void)valuesOfContinuousStatesChanged;
    (void)nextEventTimeDefined, (void)nextEventTime;
    UNSUPPORTED("fmi3UpdateDiscreteStates", "hasEventMode = false");
}

fmi3Status fmi3ActivateModelPartition(fmi3Instance instance, fmi3ValueReference clockReference,
                                      fmi3Float64 activationTime)
{
    (void)clockReference, (void)activationTime;
    UNSUPPORTED("fmi3ActivateModelPartition", "not a Scheduled Execution FMU");
}

/* Model Exchange functions: an instance of this FMU is never a Model Exchange one. */
#define NOT_ME "not a Model Exchange FMU"

fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance instance)
{
    UNSUPPORTED("fmi3EnterContinuousTimeMode", NOT_ME);
}

fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance,
                                       fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi3Boolean *enterEventMode,
                                       fmi3Boolean *terminateSimulation)
{
    (void)noSetFMUStatePriorToCurrentPoint, (void)enterEventMode, (void)terminateSimulation;
    UNSUPPORTED("fmi3CompletedIntegratorStep", NOT_ME);
}

fmi3Status fmi3SetTime(fmi3Instance instance, fmi3Float64 time)
{
    (void)time;
    UNSUPPORTED("fmi3SetTime", NOT_ME);
}

fmi3Status fmi3SetContinuousStates(fmi3Instance instance, const fmi3Float64 continuousStates[],
                                   size_t nContinuousStates)
{
    (void)continuousStates, (void)nContinuousStates;
    UNSUPPORTED("fmi3SetContinuousStates", NOT_ME);
}

fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance instance, fmi3Float64 derivatives[],
                                             size_t nContinuousStates)
{
    (void)derivatives, (void)nContinuousStates;
    UNSUPPORTED("fmi3GetContinuousStateDerivatives", NOT_ME);
}

fmi3Status fmi3GetEventIndicators(fmi3Instance instance, fmi3Float64 eventIndicators[],
                                  size_t nEventIndicators)
{
    (void)eventIndicators, (void)nEventIndicators;
    UNSUPPORTED("fmi3GetEventIndicators", NOT_ME);
}

fmi3Status fmi3GetContinuousStates(fmi3Instance instance, fmi3Float64 continuousStates[],
                                   size_t nContinuousStates)
{
    (void)continuousStates, (void)nContinuousStates;
    UNSUPPORTED("fmi3GetContinuousStates", NOT_ME);
}

fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance instance, fmi3Float64 nominals[],
                                             size_t nContinuousStates)
{
    (void)nominals, (void)nContinuousStates;
    UNSUPPORTED("fmi3GetNominalsOfContinuousStates", NOT_ME);
}

fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t *nEventIndicators)
{
    (void)nEventIndicators;
    UNSUPPORTED("fmi3GetNumberOfEventIndicators", NOT_ME);
}

fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t *nContinuousStates)
{
    (void)nContinuousStates;
    UNSUPPORTED("fmi3GetNumberOfContinuousStates", NOT_ME);
}
