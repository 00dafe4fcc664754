/* libFuzzer target: random sequences of FMI 3 Co-Simulation calls with random
 * arguments, decoded from the fuzz input, on one instance of the model it is
 * linked with (CMake's fuzz preset builds one per FMU with the FMI 3 API file).
 * The input decoding and the model's variables come from fuzz_common.h.
 * Invariants checked:
 *   - no crash, no sanitizer report, no call runs away (doSteps of more than
 *     FUZZ_MAX_STEPS internal steps are skipped: legal but slow);
 *   - every status is one of OK, Warning, Discard, Error;
 *   - after fmi3Reset a normal initialization and three doSteps return OK;
 *   - a state this instance handed out is still accepted after the reset. */
#include "fmi3Functions.h"
#include "fuzz_common.h"

#define SLOTS 4

typedef struct {
    fmi3Instance c;
    fmi3FMUState state[SLOTS];
    uint8_t *bytes; /* the last serialized state */
    size_t n_bytes;
    double time;
} World;

static void log_message(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category,
                        fmi3String message)
{
    (void)env, (void)status, (void)category;
    snprintf(last_message, sizeof last_message, "%s", message ? message : "(null)");
    ++messages_logged;
}

static fmi3Instance instantiate(int logging)
{
    return fmi3InstantiateCoSimulation("fuzz", MD.guid, FUZZ_RESOURCE_PATH, fmi3False,
                                       logging ? fmi3True : fmi3False,
                                       fmi3False, fmi3False, NULL, 0, NULL,
                                       logging ? log_message : NULL, NULL);
}

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc, (void)argv, (void)FUZZ_CALLBACKS; /* the FMI 2 callbacks are not used here */
    index_variables();
    return 0;
}

static void check_status(fmi3Status s, const char *call)
{
    if (s != fmi3OK && s != fmi3Warning && s != fmi3Discard && s != fmi3Error)
        fuzz_fail("%s returned status %d", call, (int)s);
}

static fmi3ValueReference take_vr(Input *in, VariableType type)
{
    const uint8_t b = take_byte(in);
    if (b < 224 && n_vrs_of_type[type]) return vrs_of_type[type][b % n_vrs_of_type[type]];
    return take_u32(in);
}

static int step_affordable(fmi3Instance c, double H)
{
    double h = 0.0;
    if (!(H > 0.0) || !isfinite(H)) return 1; /* rejected at once */
    if (fmi3GetFloat64(c, &vr_h, 1, &h, 1) != fmi3OK) return 1;
    return !(h > 0.0) || H / h <= FUZZ_MAX_STEPS || H / h >= 9007199254740992.0;
}

static void get_set(World *w, Input *in, int set, VariableType type)
{
    fmi3ValueReference vr[8];
    double reals[16];
    int32_t ints[16];
    bool bools[16];
    const uint8_t shape = take_byte(in);
    const size_t n = shape % 9, n_values = (shape & 0x80) ? take_byte(in) % 17 : n;
    for (size_t i = 0; i < n; ++i) vr[i] = take_vr(in, type);
    for (size_t i = 0; i < 16; ++i) {
        reals[i] = take_double(in);
        ints[i] = (int32_t)take_u32(in);
        bools[i] = take_byte(in) & 1;
    }
    const fmi3ValueReference *vrp = (shape & 0x10) ? NULL : vr;
    fmi3Status s;
    if (type == TYPE_REAL)
        s = set ? fmi3SetFloat64(w->c, vrp, n, (shape & 0x20) ? NULL : reals, n_values)
                : fmi3GetFloat64(w->c, vrp, n, (shape & 0x20) ? NULL : reals, n_values);
    else if (type == TYPE_INTEGER)
        s = set ? fmi3SetInt32(w->c, vrp, n, (shape & 0x20) ? NULL : ints, n_values)
                : fmi3GetInt32(w->c, vrp, n, (shape & 0x20) ? NULL : ints, n_values);
    else
        s = set ? fmi3SetBoolean(w->c, vrp, n, (shape & 0x20) ? NULL : bools, n_values)
                : fmi3GetBoolean(w->c, vrp, n, (shape & 0x20) ? NULL : bools, n_values);
    check_status(s, set ? "fmi3Set*" : "fmi3Get*");
}

static void serialize(World *w, fmi3FMUState state)
{
    size_t size = 0;
    if (fmi3SerializedFMUStateSize(w->c, state, &size) != fmi3OK) return;
    free(w->bytes);
    w->bytes = malloc(size ? size : 1);
    w->n_bytes = size;
    if (w->bytes && fmi3SerializeFMUState(w->c, state, w->bytes, size) != fmi3OK)
        fuzz_fail("serialize failed after its size was given");
}

static void deserialize(World *w, Input *in)
{
    if (!w->bytes || !w->n_bytes) return;
    const uint8_t how = take_byte(in);
    size_t n = w->n_bytes;
    uint8_t *copy = malloc(n);
    if (!copy) return;
    memcpy(copy, w->bytes, n);
    if (how & 1) copy[take_u32(in) % n] ^= (uint8_t)(1u << (how >> 1 & 7));
    if (how & 0x10) n = take_u32(in) % (n + 1);
#ifndef FUZZ_NO_FORGED
    if (how & 0x20) { /* a field patched, the checksum recomputed */
        const size_t at = take_u32(in) % w->n_bytes;
        for (int i = 0; i < 8 && at + i < w->n_bytes; ++i) copy[at + i] = take_byte(in);
        forge_checksum(copy, w->n_bytes);
    }
#endif
    fmi3FMUState *slot = &w->state[take_byte(in) % SLOTS];
    check_status(fmi3DeserializeFMUState(w->c, copy, n, slot), "fmi3DeserializeFMUState");
    free(copy);
}

static void operate(World *w, Input *in)
{
    const uint8_t op = take_byte(in);
    fmi3Status s = fmi3OK;
    switch (op % 18) {
    case 0: {
        const int tol_defined = take_byte(in) & 1, stop_defined = take_byte(in) & 1;
        const double tol = take_double(in), start = take_double(in), stop = take_double(in);
        s = fmi3EnterInitializationMode(w->c, tol_defined, tol, start, stop_defined, stop);
        if (s == fmi3OK) w->time = start;
        break;
    }
    case 1: s = fmi3ExitInitializationMode(w->c); break;
    case 2: case 3: case 4: {
        const uint8_t how = take_byte(in);
        const double H = how & 1 ? take_double(in) : (double[]){1e-4, 1e-3, 2.5e-5, 0.01}[how >> 1 & 3];
        const double t = how & 0x80 ? take_double(in) : w->time;
        if (!step_affordable(w->c, H)) break;
        fmi3Boolean event = fmi3False, terminate = fmi3False, early = fmi3False;
        double last = 0.0;
        s = fmi3DoStep(w->c, t, H, how & 0x40 ? fmi3True : fmi3False, &event, &terminate, &early,
                       &last);
        if (s == fmi3OK) w->time = t + H;
        break;
    }
    case 5: case 6: get_set(w, in, 1, TYPE_REAL); return;
    case 7: get_set(w, in, 0, TYPE_REAL); return;
    case 8: get_set(w, in, take_byte(in) & 1, TYPE_INTEGER); return;
    case 9: get_set(w, in, take_byte(in) & 1, TYPE_BOOLEAN); return;
    case 10: s = fmi3GetFMUState(w->c, &w->state[take_byte(in) % SLOTS]); break;
    case 11: {
        const uint8_t b = take_byte(in);
        s = fmi3SetFMUState(w->c, b & 0x80 ? NULL : w->state[b % SLOTS]);
        break;
    }
    case 12: s = fmi3FreeFMUState(w->c, &w->state[take_byte(in) % SLOTS]); break;
    case 13: serialize(w, w->state[take_byte(in) % SLOTS]); return;
    case 14: deserialize(w, in); return;
    case 15: s = fmi3Reset(w->c); if (s == fmi3OK) w->time = 0.0; break;
    case 16: s = fmi3Terminate(w->c); break;
    case 17: {
        static const char *const categories[] = {"logAll", "logStatusError", "logX"};
        const uint8_t b = take_byte(in);
        const char *chosen[1] = {categories[b % 3]};
        s = fmi3SetDebugLogging(w->c, b & 0x10 ? fmi3True : fmi3False, b >> 5 & 1,
                                b & 0x40 ? NULL : chosen);
        break;
    }
    }
    check_status(s, "a call");
}

/* A normal life after fmi3Reset must succeed, whatever came before. */
static void assert_normal_life3(fmi3Instance c)
{
    fmi3Status s;
    if ((s = fmi3Reset(c)) != fmi3OK) fuzz_fail("fmi3Reset: %d (%s)", s, last_message);
    if ((s = fmi3EnterInitializationMode(c, fmi3False, 0.0, 0.0, fmi3False, 0.0)) != fmi3OK ||
        (s = fmi3ExitInitializationMode(c)) != fmi3OK)
        fuzz_fail("initialization after reset: %d (%s)", s, last_message);
    for (int k = 0; k < 3; ++k) {
        fmi3Boolean event, terminate, early;
        double last;
        if ((s = fmi3DoStep(c, k * 1e-3, 1e-3, fmi3True, &event, &terminate, &early, &last)) !=
            fmi3OK)
            fuzz_fail("doStep after reset: %d (%s)", s, last_message);
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    Input in = {data, size};
    World w;
    memset(&w, 0, sizeof w);
    w.c = instantiate(size > 0 && (data[0] & 1));
    if (!w.c) fuzz_fail("fmi3InstantiateCoSimulation failed");
    for (int ops = 0; in.n && ops < 400; ++ops) operate(&w, &in);
    assert_normal_life3(w.c);
    for (int i = 0; i < SLOTS; ++i) {
        if (!w.state[i]) continue;
        if (fmi3SetFMUState(w.c, w.state[i]) != fmi3OK)
            fuzz_fail("a state of this instance was refused after reset: %s", last_message);
    }
    for (int i = 0; i < SLOTS; ++i) fmi3FreeFMUState(w.c, &w.state[i]);
    fmi3FreeInstance(w.c);
    free(w.bytes);
    return 0;
}
