/* Shared by the libFuzzer targets fuzz_deserialize.c and fuzz_calls.c: they are
 * linked statically with the FMI 2 API file, the instance core and one model (tools/abuse/fuzz.sh), so
 * MODEL_DESCRIPTOR tells them the model's variables.
 *
 * A failed invariant prints why and abort()s, which libFuzzer reports as a
 * crash with the input that caused it. */
#ifndef FUZZ_COMMON_H
#define FUZZ_COMMON_H

#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "model_interface.h"
#include "state_format.h"

#define MD MODEL_DESCRIPTOR

static inline void fuzz_fail(const char *format, ...)
{
    va_list args;
    va_start(args, format);
    fprintf(stderr, "\nFUZZ INVARIANT BROKEN (%s): ", MD.model_identifier);
    vfprintf(stderr, format, args);
    fprintf(stderr, "\n");
    va_end(args);
    abort();
}

/* ---- the logger: every message is formatted (as an importer would) ----------- */

static char last_message[1200];
static long messages_logged;

static inline void fuzz_logger(fmi2ComponentEnvironment env, fmi2String instance, fmi2Status status,
                        fmi2String category, fmi2String message, ...)
{
    (void)env, (void)status;
    /* the FMI logger's message is a printf format; the layer promises none of its
     * own '%' survive, so formatting it with no arguments must be safe */
    va_list args;
    va_start(args, message);
    vsnprintf(last_message, sizeof last_message, message, args);
    va_end(args);
    if (!instance || !category) fuzz_fail("logger called with a NULL instance name or category");
    ++messages_logged;
    if (getenv("FUZZ_VERBOSE")) fprintf(stderr, "[%s] %s\n", instance, last_message);
}

static inline void *counting_calloc(size_t n, size_t size);
static inline void counting_free(void *p);
static long live_blocks;

static inline void *counting_calloc(size_t n, size_t size)
{
    void *p = calloc(n, size);
    if (p) ++live_blocks;
    return p;
}

static inline void counting_free(void *p)
{
    if (p) --live_blocks;
    free(p);
}

static const fmi2CallbackFunctions FUZZ_CALLBACKS = {fuzz_logger, counting_calloc, counting_free,
                                                     NULL, NULL};

/* The resources of a model that reads them (cmake/fuzz.cmake defines where). */
#ifndef FUZZ_RESOURCE_URI
#define FUZZ_RESOURCE_URI NULL
#endif
#ifndef FUZZ_RESOURCE_PATH
#define FUZZ_RESOURCE_PATH NULL
#endif

static inline fmi2Component fuzz_instantiate(const fmi2CallbackFunctions *callbacks)
{
    return fmi2Instantiate("fuzz", fmi2CoSimulation, MD.guid, FUZZ_RESOURCE_URI, callbacks,
                           fmi2False, fmi2False);
}

/* ---- the model's variables ------------------------------------------------------ */

static fmi2ValueReference vrs_of_type[3][512];
static size_t n_vrs_of_type[3];
static fmi2ValueReference vr_h; /* the internal step parameter "h" */

static inline void index_variables(void)
{
    for (size_t v = 0; v < MD.n_variables; ++v) {
        const ModelVariable *var = &MD.variables[v];
        for (size_t e = 0; e < model_variable_count(var); ++e)
            if (n_vrs_of_type[var->type] < 512)
                vrs_of_type[var->type][n_vrs_of_type[var->type]++] = var->vr + (uint32_t)e;
        if (strcmp(var->name, "h") == 0) vr_h = var->vr;
    }
}

/* A normal life after fmi2Reset must succeed, whatever came before. */
static inline void assert_normal_life(fmi2Component c, const char *after)
{
    fmi2Status s;
    if ((s = fmi2Reset(c)) != fmi2OK) fuzz_fail("fmi2Reset after %s: %d (%s)", after, s, last_message);
    if ((s = fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0)) != fmi2OK ||
        (s = fmi2EnterInitializationMode(c)) != fmi2OK ||
        (s = fmi2ExitInitializationMode(c)) != fmi2OK)
        fuzz_fail("initialization after reset after %s: %d (%s)", after, s, last_message);
    for (int k = 0; k < 3; ++k)
        if ((s = fmi2DoStep(c, k * 1e-3, 1e-3, fmi2True)) != fmi2OK)
            fuzz_fail("doStep after reset after %s: %d (%s)", after, s, last_message);
}

/* Reads every variable; an OK read must give finite Reals unless the FMU is in
 * the Error state (where getters show what went wrong). */
static inline void read_everything(fmi2Component c)
{
    static double reals[512];
    static int ints[512];
    fmi2GetReal(c, vrs_of_type[TYPE_REAL], n_vrs_of_type[TYPE_REAL], reals);
    fmi2GetInteger(c, vrs_of_type[TYPE_INTEGER], n_vrs_of_type[TYPE_INTEGER], ints);
    fmi2GetBoolean(c, vrs_of_type[TYPE_BOOLEAN], n_vrs_of_type[TYPE_BOOLEAN], ints);
}

/* The number of internal steps a doStep of H would run, or a huge number if
 * unknown: doSteps of more than FUZZ_MAX_STEPS are legal but merely slow, and
 * are skipped so that each input runs in milliseconds. */
#define FUZZ_MAX_STEPS 2e5
static inline int step_is_affordable(fmi2Component c, double H)
{
    double h = 0.0;
    if (!(H > 0.0) || !isfinite(H)) return 1; /* rejected at once */
    if (fmi2GetReal(c, &vr_h, 1, &h) != fmi2OK) return 1; /* not initialized: rejected */
    return !(h > 0.0) || H / h <= FUZZ_MAX_STEPS || H / h >= 9007199254740992.0;
}

/* ---- serialized states (state_format.h) --------------------------------------- */

#define STATE_HEADER_SIZE sizeof(StateHeader)

/* A checksum that matches the (changed) payload: what anyone can compute. */
static inline void forge_checksum(uint8_t *state, size_t size)
{
    if (size < STATE_HEADER_SIZE) return;
    const uint64_t sum = state_checksum(state, size);
    memcpy(state + offsetof(StateHeader, checksum), &sum, sizeof sum);
}

/* ---- decoding the fuzz input ------------------------------------------------------ */

typedef struct {
    const uint8_t *p;
    size_t n;
} Input;

static inline uint8_t take_byte(Input *in)
{
    if (!in->n) return 0;
    --in->n;
    return *in->p++;
}

static inline uint32_t take_u32(Input *in)
{
    uint32_t v = 0;
    for (int i = 0; i < 4; ++i) v = v << 8 | take_byte(in);
    return v;
}

static const double INTERESTING[] = {0.0, -0.0, 1e-4, 1e-3, 1e-5, 2.5e-5, 0.5, 1.0, -1.0, 2.0,
                                     10.0, 1e-300, 5e-324, 1e300, -1e300, 1.7976931348623157e308,
                                     NAN, INFINITY, -INFINITY, 3.0, 0.1, 1e-12, 4.0, 8.0};
#define N_INTERESTING (sizeof INTERESTING / sizeof INTERESTING[0])

static inline double take_double(Input *in)
{
    const uint8_t selector = take_byte(in);
    if (selector < 2 * N_INTERESTING) return INTERESTING[selector % N_INTERESTING];
    double v;
    uint64_t bits = (uint64_t)take_u32(in) << 32 | take_u32(in);
    memcpy(&v, &bits, sizeof v);
    return v;
}

#endif
