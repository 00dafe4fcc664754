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
 * Built by tools/abuse/fuzz.sh with the FMI 2 API file, the instance core and one model. */
#include "fuzz_common.h"

static uint8_t *template_state;
static size_t template_size;

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
    /* this harness's idea of the layout must be the layer's */
    uint64_t stored;
    memcpy(&stored, template_state + STATE_CHECKSUM_OFFSET, sizeof stored);
    if (stored != fnv1a(template_state + STATE_HEADER_SIZE, template_size - STATE_HEADER_SIZE))
        fuzz_fail("the serialized layout changed: update STATE_HEADER_SIZE in fuzz_common.h");
    fmi2FreeInstance(c);
    return 0;
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
    const int mode = data[0] & 3;
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
        memcpy(state, template_state, n);
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
        use_restored(c, s, mode == 1 ? 1e-3 : 1e-4);
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
