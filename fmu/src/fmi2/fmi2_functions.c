/* The FMI 2.0 Co-Simulation API over the instance core (../instance/).
 *
 * This file owns what is FMI 2: the state machine (an allowed-state mask per
 * function, FMI 2.0 section 4.2.4), the importer's callbacks, the escaping
 * of logged text, and the status inquiries.  Everything else is the core's. */
#include <ctype.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "../instance/instance.h"

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

static void fmi2_sink(AnyFunction logger, void *environment, const char *instance_name,
                      Status status, const char *category, const char *message)
{
    char escaped[2048];
    escape_for_logger(message, escaped, sizeof escaped);
    ((fmi2CallbackLogger)logger)(environment, instance_name, (fmi2Status)status, category,
                                 escaped);
}

static const InstanceApi FMI2_API = {
    .sink = fmi2_sink,
    .state_name = state_name,
    .instantiated_state = ST_INSTANTIATED,
    .error_state = ST_ERROR,
    .restorable_states = ALIVE,
    .unstarted_states = ST_INSTANTIATED | ST_INIT_MODE,
    .stepping_states = ST_STEP_COMPLETE,
    .parameter_states = ST_INSTANTIATED | ST_INIT_MODE,
    .array_references = false,
    .c_bool = false,
    .time_at_vr0 = false,
    .state_magic = {'S', 'T', 'O', 'S', 'T', 'A', 'T', 'E'},
};

/* Opens every function that takes an instance: NULL check and state mask. */
#define ENTER(function, mask)                                                              \
    Instance *inst = (Instance *)c;                                                        \
    if (!inst) return fmi2Error;                                                           \
    if (!(inst->clock.state & (mask)))                                                     \
        return (fmi2Status)instance_fail(inst, "%s: illegal call sequence (not allowed in " \
                                         "state %s)", function, state_name(inst->clock.state))

/* ---- common functions --------------------------------------------------- */

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[])
{
    ENTER("fmi2SetDebugLogging", MASK_SetDebugLogging);
    return (fmi2Status)instance_set_debug_logging(inst, "fmi2SetDebugLogging", loggingOn != 0,
                                                  nCategories, categories);
}

/* The native path of a file: URI (RFC 8089 as FMI 2 importers write it:
 * file:///C:/x, file:/x, file://localhost/x; %XX decoded) into out[size];
 * NULL for NULL, another scheme, a remote host or a path too long. */
static const char *uri_path(const char *uri, char *out, size_t size)
{
    if (!uri) return NULL;
    const char *rest;
    if (strncmp(uri, "file://", 7) == 0) {
        rest = uri + 7;
        if (strncmp(rest, "localhost/", 10) == 0) rest += 9;
        if (rest[0] != '/') return NULL; /* a remote host */
    } else if (strncmp(uri, "file:/", 6) == 0) {
        rest = uri + 5;
    } else {
        return NULL;
    }
    /* a drive letter: /C:/x is C:/x */
    if (isalpha((unsigned char)rest[1]) && (rest[2] == ':' || rest[2] == '|')) ++rest;
    size_t at = 0;
    for (const char *c = rest; *c; ++c) {
        int value = (unsigned char)*c;
        if (*c == '%' && isxdigit((unsigned char)c[1]) && isxdigit((unsigned char)c[2])) {
            const char hex[3] = {c[1], c[2], '\0'};
            value = (int)strtol(hex, NULL, 16);
            c += 2;
        }
        if (value == 0 || at + 1 >= size) return NULL;
        out[at++] = (char)value;
    }
    out[at] = '\0';
    return out;
}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation,
                              const fmi2CallbackFunctions *functions, fmi2Boolean visible,
                              fmi2Boolean loggingOn)
{
    (void)visible;
    if (!functions) return NULL; /* nobody to tell */
    /* Memory comes from the C library (canNotUseMemoryManagementFunctions). */
    AnyFunction logger = (AnyFunction)functions->logger;
    void *env = functions->componentEnvironment;
    if (fmuType != fmi2CoSimulation) {
        instance_log_to(&FMI2_API, logger, env, instanceName, STATUS_ERROR,
                        "fmi2Instantiate: %s supports Co-Simulation only (fmuType = %d)",
                        MODEL_DESCRIPTOR.model_identifier, (int)fmuType);
        return NULL;
    }
    if (!instance_arguments_valid(&FMI2_API, logger, env, "fmi2Instantiate", instanceName,
                                  fmuGUID))
        return NULL;
    char path[4096];
    return instance_new(&FMI2_API, "fmi2Instantiate", instanceName, logger, env, loggingOn != 0,
                        uri_path(fmuResourceLocation, path, sizeof path));
}

void fmi2FreeInstance(fmi2Component c)
{
    Instance *inst = (Instance *)c;
    if (!inst) return;
    if (!(inst->clock.state & ALIVE))
        instance_log(inst, STATUS_ERROR, "fmi2FreeInstance: illegal call sequence (state %s)",
                     state_name(inst->clock.state));
    instance_free(inst);
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined,
                               fmi2Real stopTime)
{
    ENTER("fmi2SetupExperiment", MASK_SetupExperiment);
    (void)toleranceDefined; /* fixed-step: the tolerance does not apply */
    (void)tolerance;
    return (fmi2Status)instance_setup_experiment(inst, "fmi2SetupExperiment", startTime,
                                                 stopTimeDefined != 0, stopTime);
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
    const Status status = instance_initialize(inst, "fmi2ExitInitializationMode");
    if (status < STATUS_ERROR) inst->clock.state = ST_STEP_COMPLETE;
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
    instance_reset(inst);
    return fmi2OK;
}

/* ---- get / set ---------------------------------------------------------- */

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[])
{
    ENTER("fmi2GetReal", MASK_Get);
    return (fmi2Status)instance_get(inst, "fmi2GetReal", TYPE_REAL, vr, nvr, value, nvr);
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Integer value[])
{
    ENTER("fmi2GetInteger", MASK_Get);
    return (fmi2Status)instance_get(inst, "fmi2GetInteger", TYPE_INTEGER, vr, nvr, value, nvr);
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          fmi2Boolean value[])
{
    ENTER("fmi2GetBoolean", MASK_Get);
    return (fmi2Status)instance_get(inst, "fmi2GetBoolean", TYPE_BOOLEAN, vr, nvr, value, nvr);
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         fmi2String value[])
{
    ENTER("fmi2GetString", MASK_Get);
    return (fmi2Status)instance_no_variables_of(inst, "fmi2GetString", "String", vr, nvr, value);
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                       const fmi2Real value[])
{
    ENTER("fmi2SetReal", MASK_Set);
    return (fmi2Status)instance_set(inst, "fmi2SetReal", TYPE_REAL, vr, nvr, value, nvr);
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Integer value[])
{
    ENTER("fmi2SetInteger", MASK_Set);
    return (fmi2Status)instance_set(inst, "fmi2SetInteger", TYPE_INTEGER, vr, nvr, value, nvr);
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                          const fmi2Boolean value[])
{
    ENTER("fmi2SetBoolean", MASK_Set);
    return (fmi2Status)instance_set(inst, "fmi2SetBoolean", TYPE_BOOLEAN, vr, nvr, value, nvr);
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                         const fmi2String value[])
{
    ENTER("fmi2SetString", MASK_Set);
    return (fmi2Status)instance_no_variables_of(inst, "fmi2SetString", "String", vr, nvr, value);
}

/* ---- FMU state ---------------------------------------------------------- */

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *FMUstate)
{
    ENTER("fmi2GetFMUstate", MASK_FMUstate);
    return (fmi2Status)instance_get_state(inst, "fmi2GetFMUstate", FMUstate);
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate)
{
    ENTER("fmi2SetFMUstate", MASK_FMUstate);
    return (fmi2Status)instance_set_state(inst, "fmi2SetFMUstate", FMUstate);
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *FMUstate)
{
    ENTER("fmi2FreeFMUstate", MASK_FMUstate);
    return (fmi2Status)instance_free_state(inst, "fmi2FreeFMUstate", FMUstate);
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate, size_t *size)
{
    ENTER("fmi2SerializedFMUstateSize", MASK_FMUstate);
    return (fmi2Status)instance_serialized_size(inst, "fmi2SerializedFMUstateSize", FMUstate,
                                                size);
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate, fmi2Byte serializedState[],
                                 size_t size)
{
    ENTER("fmi2SerializeFMUstate", MASK_FMUstate);
    return (fmi2Status)instance_serialize(inst, "fmi2SerializeFMUstate", FMUstate,
                                          (unsigned char *)serializedState, size);
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[], size_t size,
                                   fmi2FMUstate *FMUstate)
{
    ENTER("fmi2DeSerializeFMUstate", MASK_FMUstate);
    return (fmi2Status)instance_deserialize(inst, "fmi2DeSerializeFMUstate",
                                            (const unsigned char *)serializedState, size,
                                            FMUstate);
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
    return (fmi2Status)instance_fail(inst, "fmi2GetDirectionalDerivative is not supported "
                                     "(providesDirectionalDerivative = false)");
}

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[])
{
    (void)vr, (void)nvr, (void)order, (void)value;
    ENTER("fmi2SetRealInputDerivatives", MASK_SetRealInputDerivatives);
    return (fmi2Status)instance_fail(inst, "fmi2SetRealInputDerivatives is not supported "
                                     "(canInterpolateInputs = false)");
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                        const fmi2Integer order[], fmi2Real value[])
{
    (void)vr, (void)nvr, (void)order, (void)value;
    ENTER("fmi2GetRealOutputDerivatives", MASK_GetRealOutputDerivatives);
    return (fmi2Status)instance_fail(inst, "fmi2GetRealOutputDerivatives is not supported "
                                     "(maxOutputDerivativeOrder = 0)");
}

fmi2Status fmi2CancelStep(fmi2Component c)
{
    ENTER("fmi2CancelStep", MASK_CancelStep);
    return (fmi2Status)instance_fail(inst, "fmi2CancelStep is not supported "
                                     "(canRunAsynchronuously = false)");
}

/* ---- stepping ----------------------------------------------------------- */

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint,
                      fmi2Real communicationStepSize, fmi2Boolean noSetFMUStatePriorToCurrentPoint)
{
    (void)noSetFMUStatePriorToCurrentPoint;
    ENTER("fmi2DoStep", MASK_DoStep);
    return (fmi2Status)instance_do_step(inst, "fmi2DoStep", currentCommunicationPoint,
                                        communicationStepSize);
}

/* ---- status inquiry ----------------------------------------------------- */

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value)
{
    ENTER("fmi2GetStatus", MASK_GetStatus);
    if (!value) return (fmi2Status)instance_fail(inst, "fmi2GetStatus: value is NULL");
    if (s != fmi2DoStepStatus) return fmi2Discard;
    *value = fmi2OK; /* doStep is synchronous: it never stays pending */
    return fmi2OK;
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value)
{
    ENTER("fmi2GetRealStatus", MASK_GetStatus);
    if (!value) return (fmi2Status)instance_fail(inst, "fmi2GetRealStatus: value is NULL");
    if (s != fmi2LastSuccessfulTime) return fmi2Discard;
    *value = inst->clock.comm_time; /* a failed step leaves it at the end of the last good one */
    return fmi2OK;
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value)
{
    (void)s;
    ENTER("fmi2GetIntegerStatus", MASK_GetStatus);
    if (!value) return (fmi2Status)instance_fail(inst, "fmi2GetIntegerStatus: value is NULL");
    return fmi2Discard; /* no Integer status is defined for this FMU */
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value)
{
    ENTER("fmi2GetBooleanStatus", MASK_GetStatus);
    if (!value) return (fmi2Status)instance_fail(inst, "fmi2GetBooleanStatus: value is NULL");
    if (s != fmi2Terminated) return fmi2Discard;
    *value = fmi2False; /* the FMU never asks to end the simulation */
    return fmi2OK;
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value)
{
    (void)s;
    ENTER("fmi2GetStringStatus", MASK_GetStatus);
    if (!value) return (fmi2Status)instance_fail(inst, "fmi2GetStringStatus: value is NULL");
    return fmi2Discard;
}
