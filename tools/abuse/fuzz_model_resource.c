/* libFuzzer target of ModelObserver (tools/abuse/fuzz.sh): its resources/model.txt
 * (the term program, core/term_program.h) and the state of an instance that read it.
 *
 * Each input: the bytes up to the first NUL are the resource file, written into a
 * private resources folder; the FMU is instantiated over it (the real path: the
 * instance core reads the file and the model parses it).  When that succeeds, the
 * rest of the input drives it: inputs and positions (any double), doSteps, a state
 * taken, serialized, maybe damaged or forged, deserialized and set.  Invariants:
 *   - no crash, no sanitizer report, every status OK, Warning, Discard or Error;
 *   - a refused file logs why; an accepted one initializes with its defaults;
 *   - after a doStep that returned OK every Real output is finite (a non-finite
 *     state is an error of that doStep, never published);
 *   - fmi2FreeInstance frees every block the instance allocated. */
#define _POSIX_C_SOURCE 200809L /* mkdtemp */
#include <stdlib.h>
#include <unistd.h>

#include "fuzz_common.h"

static char resource_dir[256];
static char resource_uri[300];
static char resource_file[300];

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc, (void)argv;
    index_variables();
    const char *tmp = getenv("TMPDIR");
    snprintf(resource_dir, sizeof resource_dir, "%s/fuzz_model_resource_XXXXXX",
             tmp && tmp[0] ? tmp : "/tmp");
    if (!mkdtemp(resource_dir)) fuzz_fail("cannot make a resources folder");
    snprintf(resource_uri, sizeof resource_uri, "file://%s", resource_dir);
    snprintf(resource_file, sizeof resource_file, "%s/%s", resource_dir, MD.resource_file);
    return 0;
}

static void check_status(fmi2Status s, const char *call)
{
    if (s != fmi2OK && s != fmi2Warning && s != fmi2Discard && s != fmi2Error)
        fuzz_fail("%s returned status %d", call, (int)s);
}

/* Every Real output of an instance whose last doStep returned OK is finite. */
static void outputs_finite(fmi2Component c)
{
    for (size_t v = 0; v < MD.n_variables; ++v) {
        const ModelVariable *var = &MD.variables[v];
        if (var->type != TYPE_REAL || var->causality != CAUSALITY_OUTPUT) continue;
        for (size_t e = 0; e < model_variable_count(var); ++e) {
            const fmi2ValueReference vr = var->vr + (uint32_t)e;
            double value = 0.0;
            if (fmi2GetReal(c, &vr, 1, &value) == fmi2OK && !isfinite(value))
                fuzz_fail("doStep returned OK but %s (element %zu) = %g", var->name, e, value);
        }
    }
}

/* Inputs (positions and known inputs) of any value, then doSteps and states. */
static void drive(fmi2Component c, Input *in)
{
    fmi2Status s;
    double t = 0.0, h = (double[]){1e-3, 1e-4, 1e-2, 2.5e-5}[take_byte(in) & 3];
    check_status(fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0), "setup");
    check_status(fmi2SetReal(c, &vr_h, 1, &h), "set h");
    if ((s = fmi2EnterInitializationMode(c)) != fmi2OK) return;
    if ((s = fmi2ExitInitializationMode(c)) != fmi2OK) {
        check_status(s, "exitInitializationMode");
        return;
    }
    fmi2FMUstate state = NULL;
    for (int ops = 0; in->n && ops < 64; ++ops) {
        const uint8_t op = take_byte(in);
        switch (op % 6) {
        case 0: case 1: { /* an input or position of any value */
            const ModelVariable *var = &MD.variables[take_byte(in) % MD.n_variables];
            if (var->causality != CAUSALITY_INPUT || var->type != TYPE_REAL) break;
            const fmi2ValueReference vr = var->vr + (uint32_t)(take_byte(in) %
                                                               model_variable_count(var));
            const double value = take_double(in);
            check_status(fmi2SetReal(c, &vr, 1, &value), "set an input");
            break;
        }
        case 2: case 3: { /* a doStep of 1 to 64 internal steps */
            const double H = h * (1 + take_byte(in) % 64);
            s = fmi2DoStep(c, t, H, fmi2True);
            check_status(s, "doStep");
            if (s == fmi2OK) {
                t += H;
                outputs_finite(c);
            } else if (s == fmi2Error) {
                return; /* the instance is in its Error state */
            }
            break;
        }
        case 4: check_status(fmi2GetFMUstate(c, &state), "getFMUstate"); break;
        case 5: { /* the state serialized, maybe damaged or forged, and set again */
            if (!state) break;
            size_t size = 0;
            if (fmi2SerializedFMUstateSize(c, state, &size) != fmi2OK || size == 0) break;
            uint8_t *bytes = malloc(size);
            if (!bytes) break;
            if (fmi2SerializeFMUstate(c, state, (fmi2Byte *)bytes, size) != fmi2OK)
                fuzz_fail("serialize failed after its size was given");
            const uint8_t how = take_byte(in);
            if (how & 1) bytes[take_u32(in) % size] ^= (uint8_t)(1u << (how >> 1 & 7));
#ifndef FUZZ_NO_FORGED
            if (how & 0x20) {
                const size_t at = take_u32(in) % size;
                for (int i = 0; i < 8 && at + i < size; ++i) bytes[at + i] = take_byte(in);
                forge_checksum(bytes, size);
            }
#endif
            fmi2FMUstate restored = NULL;
            s = fmi2DeSerializeFMUstate(c, (const fmi2Byte *)bytes, size, &restored);
            check_status(s, "deSerializeFMUstate");
            free(bytes);
            if (s == fmi2OK) {
                check_status(fmi2SetFMUstate(c, restored), "setFMUstate");
                fmi2FreeFMUstate(c, &restored);
                double last = t;
                fmi2GetRealStatus(c, fmi2LastSuccessfulTime, &last);
                t = last;
            }
            break;
        }
        }
    }
    if (state) fmi2FreeFMUstate(c, &state);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const uint8_t *end = memchr(data, 0, size);
    const size_t text = end ? (size_t)(end - data) : size;
    FILE *file = fopen(resource_file, "wb");
    if (!file) fuzz_fail("cannot write %s", resource_file);
    if (fwrite(data, 1, text, file) != text) fuzz_fail("cannot write %s", resource_file);
    fclose(file);
    Input in = {data + text + (end ? 1 : 0), size - text - (end ? 1 : 0)};
    live_blocks = 0;
    messages_logged = 0;
    fmi2Component c = fmi2Instantiate("fuzz", fmi2CoSimulation, MD.guid, resource_uri,
                                      &FUZZ_CALLBACKS, fmi2False, fmi2False);
    if (!c) {
        if (messages_logged == 0) fuzz_fail("a resource file was refused without a message");
    } else {
        drive(c, &in);
        fmi2FreeInstance(c);
    }
    if (live_blocks != 0) fuzz_fail("%ld blocks not freed by fmi2FreeInstance", live_blocks);
    return 0;
}
