/* libFuzzer target: random sequences of FMI 2 calls with random arguments,
 * decoded from the fuzz input, on one instance of the model it is linked with
 * (tools/abuse/fuzz.sh builds one per FMU).
 *
 * Each input: instantiate (with callbacks chosen by the first byte), then
 * operations until the input is used up; each operation is one byte (the
 * call) followed by the bytes of its arguments (value references: an index
 * into the model's variables of the right type, or any 32-bit number; doubles:
 * one of INTERESTING[] or 8 raw bytes).  Invariants checked:
 *   - no crash, no sanitizer report, no call runs away (doSteps of more than
 *     FUZZ_MAX_STEPS internal steps are skipped: legal but slow);
 *   - every status is one of OK, Warning, Discard, Error;
 *   - after fmi2Reset a normal setup / init / doStep sequence returns OK;
 *   - fmi2FreeInstance frees every block the instance allocated. */
#include "fuzz_common.h"

#define SLOTS 4

typedef struct {
    fmi2Component c, other;     /* the instance, and a second one for foreign states */
    fmi2FMUstate state[SLOTS];
    fmi2FMUstate foreign;
    uint8_t *bytes;             /* the last serialized state */
    size_t n_bytes;
    double time;                /* where the instance believes it is (for doStep) */
} World;

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc, (void)argv;
    index_variables();
    return 0;
}

static fmi2ValueReference take_vr(Input *in, VariableType type)
{
    const uint8_t b = take_byte(in);
    if (b < 224 && n_vrs_of_type[type]) return vrs_of_type[type][b % n_vrs_of_type[type]];
    if (b < 240) {  /* a valid reference of another type */
        const size_t t = (type + 1 + b % 2) % 3;
        if (n_vrs_of_type[t]) return vrs_of_type[t][b % n_vrs_of_type[t]];
    }
    return take_u32(in);
}

static void check_status(fmi2Status s, const char *call)
{
    if (s != fmi2OK && s != fmi2Warning && s != fmi2Discard && s != fmi2Error)
        fuzz_fail("%s returned status %d", call, (int)s);
}

static void get_set(World *w, Input *in, int set, VariableType type)
{
    fmi2ValueReference vr[8];
    double reals[8];
    int ints[8];
    const uint8_t shape = take_byte(in);
    size_t n = shape % 9; /* 0..8 */
    for (size_t i = 0; i < n; ++i) {
        vr[i] = take_vr(in, type);
        if (type == TYPE_REAL) reals[i] = take_double(in);
        else ints[i] = (shape & 0x40) ? (int)take_u32(in) : (int)(int8_t)take_byte(in);
    }
    const fmi2ValueReference *vrp = (shape & 0x10) ? NULL : vr;   /* NULL arrays */
    void *values = (shape & 0x20) ? NULL : type == TYPE_REAL ? (void *)reals : (void *)ints;
    fmi2Status s;
    if (type == TYPE_REAL)
        s = set ? fmi2SetReal(w->c, vrp, n, values) : fmi2GetReal(w->c, vrp, n, values);
    else if (type == TYPE_INTEGER)
        s = set ? fmi2SetInteger(w->c, vrp, n, values) : fmi2GetInteger(w->c, vrp, n, values);
    else
        s = set ? fmi2SetBoolean(w->c, vrp, n, values) : fmi2GetBoolean(w->c, vrp, n, values);
    check_status(s, set ? "fmi2Set*" : "fmi2Get*");
}

static fmi2FMUstate *slot(World *w, Input *in)
{
    return &w->state[take_byte(in) % SLOTS];
}

/* A state pointer to hand to the FMU: ours, NULL, the other instance's, or garbage. */
static fmi2FMUstate some_state(World *w, Input *in)
{
    static uint8_t garbage[4096];
    const uint8_t b = take_byte(in);
    switch (b % 8) {
    case 5: return NULL;
    case 6: return w->foreign;
    case 7: return garbage + (b >> 3);
    default: return w->state[b % SLOTS];
    }
}

static void operate(World *w, Input *in)
{
    const uint8_t op = take_byte(in);
    fmi2Status s = fmi2OK;
    switch (op % 26) {
    case 0: {
        const int tol_defined = take_byte(in) & 1, stop_defined = take_byte(in) & 1;
        const double tol = take_double(in), start = take_double(in), stop = take_double(in);
        s = fmi2SetupExperiment(w->c, tol_defined, tol, start, stop_defined, stop);
        if (s == fmi2OK) w->time = start;
        break;
    }
    case 1: s = fmi2EnterInitializationMode(w->c); break;
    case 2: s = fmi2ExitInitializationMode(w->c); break;
    case 3: case 4: case 5: {
        const uint8_t how = take_byte(in);
        const double H = how & 1 ? take_double(in) : (double[]){1e-4, 1e-3, 2.5e-5, 0.01}[how >> 1 & 3];
        double t = w->time;
        fmi2GetRealStatus(w->c, fmi2LastSuccessfulTime, &t);
        if (how & 0x80) t = take_double(in);
        if (!step_is_affordable(w->c, H)) break;
        s = fmi2DoStep(w->c, t, H, how & 0x40 ? fmi2True : fmi2False);
        if (s == fmi2OK) w->time = t + H;
        break;
    }
    case 6: case 7: get_set(w, in, 1, TYPE_REAL); return;
    case 8: get_set(w, in, 0, TYPE_REAL); return;
    case 9: get_set(w, in, 1, TYPE_INTEGER); return;
    case 10: get_set(w, in, 0, TYPE_INTEGER); return;
    case 11: get_set(w, in, 1, TYPE_BOOLEAN); return;
    case 12: get_set(w, in, 0, TYPE_BOOLEAN); return;
    case 13: s = fmi2GetFMUstate(w->c, slot(w, in)); break;
    case 14: s = fmi2SetFMUstate(w->c, some_state(w, in)); break;
    case 15: s = fmi2FreeFMUstate(w->c, slot(w, in)); break;
    case 16: {
        fmi2FMUstate st = some_state(w, in);
        size_t size = 0;
        s = fmi2SerializedFMUstateSize(w->c, st, &size);
        if (s == fmi2OK) {
            free(w->bytes);
            w->bytes = malloc(size);
            w->n_bytes = size;
            if (w->bytes) s = fmi2SerializeFMUstate(w->c, st, (fmi2Byte *)w->bytes, size);
            if (w->bytes && s != fmi2OK) fuzz_fail("serialize failed after its size was given");
        }
        break;
    }
    case 17: {  /* deserialize the last serialized state, maybe damaged, maybe forged */
        if (!w->bytes) break;
        const uint8_t how = take_byte(in);
        size_t n = w->n_bytes;
        uint8_t *copy = malloc(n + 1);
        if (!copy) break;
        memcpy(copy, w->bytes, n);
        if (how & 1) copy[take_u32(in) % n] ^= (uint8_t)(1u << (how >> 1 & 7));
        if (how & 0x10) n = take_u32(in) % (n + 1); /* truncated (or exact) */
#ifndef FUZZ_NO_FORGED
        if (how & 0x20) {
            const size_t at = take_u32(in) % w->n_bytes;
            for (int i = 0; i < 8 && at + i < w->n_bytes; ++i) copy[at + i] = take_byte(in);
            forge_checksum(copy, w->n_bytes);
        }
#endif
        s = fmi2DeSerializeFMUstate(w->c, (const fmi2Byte *)copy, n, slot(w, in));
        free(copy);
        break;
    }
    case 18: s = fmi2Reset(w->c); if (s == fmi2OK) w->time = 0.0; break;
    case 19: s = fmi2Terminate(w->c); break;
    case 20: {
        static const char *const categories[] = {"logAll", "logStatusError", "logX", NULL};
        const uint8_t b = take_byte(in);
        const char *chosen[2] = {categories[b & 3], categories[b >> 2 & 3]};
        s = fmi2SetDebugLogging(w->c, b >> 4 & 1, b >> 5 & 3 ? (size_t)(b >> 5 & 1) + 1 : 0,
                                b & 0x80 ? NULL : chosen);
        break;
    }
    case 21: {
        fmi2Status st;
        double r;
        fmi2Integer i;
        fmi2Boolean bo;
        fmi2String str;
        const fmi2StatusKind kind = (fmi2StatusKind)(take_byte(in) % 5);
        check_status(fmi2GetStatus(w->c, kind, &st), "fmi2GetStatus");
        check_status(fmi2GetRealStatus(w->c, kind, &r), "fmi2GetRealStatus");
        check_status(fmi2GetIntegerStatus(w->c, kind, &i), "fmi2GetIntegerStatus");
        check_status(fmi2GetBooleanStatus(w->c, kind, &bo), "fmi2GetBooleanStatus");
        s = fmi2GetStringStatus(w->c, kind, &str);
        break;
    }
    case 22: s = fmi2CancelStep(w->c); break;
    case 23: {
        const fmi2ValueReference vr = take_vr(in, TYPE_REAL);
        const fmi2Integer order = 1;
        double v = take_double(in);
        s = take_byte(in) & 1 ? fmi2SetRealInputDerivatives(w->c, &vr, 1, &order, &v)
                              : fmi2GetRealOutputDerivatives(w->c, &vr, 1, &order, &v);
        break;
    }
    case 24: {  /* strings: there are none */
        const fmi2ValueReference vr = take_vr(in, TYPE_REAL);
        fmi2String value = "x";
        s = take_byte(in) & 1 ? fmi2SetString(w->c, &vr, 1, &value) : fmi2GetString(w->c, &vr, 1, &value);
        break;
    }
    case 25: {  /* a new instance with odd callbacks (the states go with the old one) */
        const uint8_t b = take_byte(in);
        fmi2CallbackFunctions cb = FUZZ_CALLBACKS;
        if (b & 1) cb.logger = NULL;
        if (b & 2) cb.allocateMemory = NULL;
        if (b & 4) cb.freeMemory = NULL;
        if (b & 8) { /* refused: no instance */
            const char *guid = b & 16 ? "{wrong}" : NULL;
            if (fmi2Instantiate(b & 32 ? "" : "x", fmi2CoSimulation, guid, NULL, &cb, 0, 0))
                fuzz_fail("fmi2Instantiate accepted a bad GUID or name");
            if (fmi2Instantiate("x", fmi2CoSimulation, MD.guid, NULL, NULL, 0, 0))
                fuzz_fail("fmi2Instantiate accepted NULL callbacks");
            break;
        }
        fmi2FreeInstance(w->c);
        memset(w->state, 0, sizeof w->state);
        w->c = fuzz_instantiate(&cb);
        if (!w->c) fuzz_fail("fmi2Instantiate failed");
        w->time = 0.0;
        break;
    }
    }
    check_status(s, "a call");
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    Input in = {data, size};
    World w;
    memset(&w, 0, sizeof w);
    live_blocks = 0;
    w.c = fuzz_instantiate(&FUZZ_CALLBACKS);
    w.other = fuzz_instantiate(&FUZZ_CALLBACKS);
    if (!w.c || !w.other) fuzz_fail("fmi2Instantiate failed");
    assert_normal_life(w.other, "start");
    if (fmi2GetFMUstate(w.other, &w.foreign) != fmi2OK) fuzz_fail("no state");
    for (int ops = 0; in.n && ops < 400; ++ops) operate(&w, &in);
    assert_normal_life(w.c, "the calls");
    /* the states handed out are still usable after the reset */
    for (int i = 0; i < SLOTS; ++i) {
        if (!w.state[i]) continue;
        const fmi2Status s = fmi2SetFMUstate(w.c, w.state[i]);
        if (s != fmi2OK) fuzz_fail("a state of this instance was refused after reset: %s", last_message);
    }
    fmi2FreeInstance(w.c);
    fmi2FreeInstance(w.other);
    free(w.bytes);
    if (live_blocks != 0) fuzz_fail("%ld blocks not freed by fmi2FreeInstance", live_blocks);
    return 0;
}
