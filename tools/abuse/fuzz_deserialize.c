/* libFuzzer target: fmi2DeSerializeFMUstate of arbitrary bytes, then, if the
 * state is accepted, fmi2SetFMUstate, reads, a doStep from the restored time,
 * a serialization round trip, and a normal life after fmi2Reset.
 *
 * The first input byte selects how the rest becomes a serialized state:
 *   0  the bytes as they are (any size)
 *   1  a valid state of this instance, patched at fuzzed offsets in its
 *      payload, with the checksum recomputed: a forged state (FNV-1a is no
 *      MAC; anyone can do this).  Compiled out with -DFUZZ_NO_FORGED.
 *   2  a valid state whose first bytes (the header) are replaced
 *   3  the bytes, padded or cut to the size of a valid state
 *   4  a valid state of this instance after some steps, forged field by field:
 *      each patch picks a field of the model data (the model's own table of
 *      its counts, indices and derived fields, or a variable, or the clock), an
 *      element and a value likely to break an index or a loop bound (0, -1,
 *      the array sizes and one past them, INT_MAX, NaN, ...), then the
 *      checksum is recomputed: the forged states that once crashed the
 *      importer.  Compiled out with -DFUZZ_NO_FORGED.
 * Built by tools/abuse/fuzz.sh with the FMI 2 API file, the instance core and one model. */
#include "fuzz_common.h"

#define STATE_CLOCK_SIZE sizeof(Clock) /* the model data follows it */
#define N_MODES 5

/* Values that break an index, a count or a loop bound of this project's arrays. */
static const int INT_INTERESTING[] = {0, 1, -1, 2, 3, 4, 5, 7, 8, 9, 16, 17, 31, 32, 33, 36, 37,
                                      84, 85, 86, 255, 256, 1000, 100000, -100000, 1 << 20,
                                      2147483647, -2147483647 - 1};
#define N_INT_INTERESTING (sizeof INT_INTERESTING / sizeof INT_INTERESTING[0])

static uint8_t *template_state;
static size_t template_size;
/* mode 4's template: after 300 steps, the identifier on where the model has one */
static uint8_t *stepped_state;

static uint8_t *stepped_template(void)
{
    fmi2Component c = fuzz_instantiate(&FUZZ_CALLBACKS);
    if (!c) fuzz_fail("fmi2Instantiate failed");
    if (fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) != fmi2OK)
        fuzz_fail("setup: %s", last_message);
    for (size_t v = 0; v < MD.n_variables; ++v)
        if (strcmp(MD.variables[v].name, "identifier") == 0) {
            const fmi2ValueReference vr = MD.variables[v].vr;
            const fmi2Integer lsm = 1;
            fmi2SetInteger(c, &vr, 1, &lsm);
        }
    if (fmi2EnterInitializationMode(c) != fmi2OK || fmi2ExitInitializationMode(c) != fmi2OK)
        fuzz_fail("initialization: %s", last_message);
    for (int k = 0; k < 300; ++k)
        if (fmi2DoStep(c, k * 1e-3, 1e-3, fmi2True) != fmi2OK) fuzz_fail("step: %s", last_message);
    fmi2FMUstate s = NULL;
    size_t size = 0;
    uint8_t *bytes = NULL;
    if (fmi2GetFMUstate(c, &s) != fmi2OK || fmi2SerializedFMUstateSize(c, s, &size) != fmi2OK ||
        size != template_size || !(bytes = malloc(size)) ||
        fmi2SerializeFMUstate(c, s, (fmi2Byte *)bytes, size) != fmi2OK)
        fuzz_fail("cannot serialize the stepped state");
    fmi2FreeInstance(c);
    return bytes;
}

int LLVMFuzzerInitialize(int *argc, char ***argv)
{
    (void)argc, (void)argv;
    index_variables();
    fmi2Component c = fuzz_instantiate(&FUZZ_CALLBACKS);
    if (!c) fuzz_fail("fmi2Instantiate failed");
    assert_normal_life(c, "start");
    fmi2FMUstate s = NULL;
    if (fmi2GetFMUstate(c, &s) != fmi2OK || fmi2SerializedFMUstateSize(c, s, &template_size) != fmi2OK)
        fuzz_fail("no FMU state");
    template_state = malloc(template_size);
    if (!template_state || fmi2SerializeFMUstate(c, s, (fmi2Byte *)template_state, template_size) != fmi2OK)
        fuzz_fail("cannot serialize");
    fmi2FreeInstance(c);
    stepped_state = stepped_template();
    return 0;
}

/* Mode 4: one patch of a field of the model data in `state` (the serialized
 * template), chosen and valued by the input. */
static void forge_field(uint8_t *state, size_t n, Input *in)
{
    const size_t data = STATE_HEADER_SIZE + STATE_CLOCK_SIZE;
    const uint8_t kind = take_byte(in);
    const uint32_t pick = take_byte(in) << 8 | take_byte(in);
    size_t offset, size;
    int real;
    if (kind % 4 == 0 && MD.n_state_fields > 0) { /* the model's table of non-double fields */
        const StateField *f = &MD.state_fields[pick % MD.n_state_fields];
        offset = f->offset;
        size = f->size;
        real = f->check == FIELD_REAL || f->check == FIELD_REALS || f->check == FIELD_ANY ||
               (f->check == FIELD_DERIVED && (kind & 4));
    } else if (kind % 4 == 1) { /* the clock: state, stop flag, steps, times */
        real = kind & 4;
        const size_t width = real ? 8 : 4;
        const size_t at = STATE_HEADER_SIZE + (pick % (STATE_CLOCK_SIZE / width)) * width;
        if (real) {
            const double v = take_double(in);
            memcpy(state + at, &v, sizeof v);
        } else {
            const int v = INT_INTERESTING[take_byte(in) % N_INT_INTERESTING];
            memcpy(state + at, &v, sizeof v);
        }
        return;
    } else { /* a variable: parameters, inputs, outputs */
        const ModelVariable *var = &MD.variables[pick % MD.n_variables];
        real = var->type == TYPE_REAL;
        offset = var->offset;
        size = model_variable_count(var) * (real ? sizeof(double) : sizeof(int));
    }
    const size_t width = real ? sizeof(double) : sizeof(int);
    if (size < width) return;
    const size_t element = (size_t)take_byte(in) % (size / width);
    const size_t at = data + offset + element * width;
    if (at + width > n) return;
    if (real) {
        const double v = take_double(in);
        memcpy(state + at, &v, sizeof v);
    } else {
        int v;
        const uint8_t how = take_byte(in);
        memcpy(&v, state + at, sizeof v);
        /* the value there plus or minus a little, or an interesting one */
        v = how < 64 ? (int)((unsigned)v + (unsigned)(how % 5) - 2u)
                     : INT_INTERESTING[how % N_INT_INTERESTING];
        memcpy(state + at, &v, sizeof v);
    }
}

static void use_restored(fmi2Component c, fmi2FMUstate s, double H)
{
    if (fmi2SetFMUstate(c, s) != fmi2OK) fuzz_fail("an accepted state cannot be set: %s", last_message);
    read_everything(c);
    double t = 0.0;
    if (fmi2GetRealStatus(c, fmi2LastSuccessfulTime, &t) == fmi2OK && step_is_affordable(c, H)) {
        fmi2DoStep(c, t, H, fmi2False);
        read_everything(c);
    }
    size_t size = 0;
    fmi2FMUstate again = NULL;
    if (fmi2GetFMUstate(c, &again) == fmi2OK && fmi2SerializedFMUstateSize(c, again, &size) == fmi2OK) {
        uint8_t *bytes = malloc(size);
        if (!bytes) return;
        if (fmi2SerializeFMUstate(c, again, (fmi2Byte *)bytes, size) != fmi2OK ||
            fmi2DeSerializeFMUstate(c, (const fmi2Byte *)bytes, size, &again) != fmi2OK)
            fuzz_fail("a state taken from a restored state does not round-trip: %s", last_message);
        free(bytes);
    }
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (size < 1) return 0;
    Input in = {data + 1, size - 1};
    const int mode = data[0] % N_MODES;
    uint8_t *state;
    size_t n;
    if (mode == 0) {
        n = in.n;
        state = malloc(n ? n : 1);
        if (!state) return 0;
        if (n) memcpy(state, in.p, n);
    } else {
        n = template_size;
        state = malloc(n);
        if (!state) return 0;
        memcpy(state, mode == 4 ? stepped_state : template_state, n);
        if (mode == 1) {
#ifdef FUZZ_NO_FORGED
            free(state);
            return 0;
#else
            /* patches: u16 offset into the payload, u8 length, bytes */
            while (in.n >= 3) {
                const size_t at = STATE_HEADER_SIZE + ((size_t)take_byte(&in) << 8 | take_byte(&in)) %
                                                          (n - STATE_HEADER_SIZE);
                size_t len = take_byte(&in) % 16 + 1;
                for (size_t i = 0; i < len && at + i < n && in.n; ++i) state[at + i] = take_byte(&in);
            }
            forge_checksum(state, n);
#endif
        } else if (mode == 4) {
#ifdef FUZZ_NO_FORGED
            free(state);
            return 0;
#else
            while (in.n >= 4) forge_field(state, n, &in);
            forge_checksum(state, n);
#endif
        } else if (mode == 2) {
            memcpy(state, in.p, in.n < STATE_HEADER_SIZE ? in.n : STATE_HEADER_SIZE);
        } else {
            memset(state, 0, n);
            memcpy(state, in.p, in.n < n ? in.n : n);
        }
    }

    fmi2Component c = fuzz_instantiate(&FUZZ_CALLBACKS);
    if (!c) fuzz_fail("fmi2Instantiate failed");
    fmi2FMUstate s = NULL;
    const fmi2Status status = fmi2DeSerializeFMUstate(c, (const fmi2Byte *)state, n, &s);
    if (status == fmi2OK) {
        if (!s) fuzz_fail("fmi2DeSerializeFMUstate: OK without a state");
        use_restored(c, s, mode == 1 || mode == 4 ? 1e-3 : 1e-4);
    } else if (status != fmi2Error) {
        fuzz_fail("fmi2DeSerializeFMUstate returned %d", status);
    } else if (s) {
        fuzz_fail("a rejected state was handed out");
    }
    assert_normal_life(c, "deserialization");
    fmi2FreeInstance(c);
    if (live_blocks != 0) fuzz_fail("%ld blocks not freed by fmi2FreeInstance", live_blocks);
    free(state);
    return 0;
}
