/* The instance core's FMU states: snapshots, their serialization
 * (state_format.h) and the checks that a restored state is one this FMU could have
 * written itself. */
#if defined(__MINGW32__) && !defined(__USE_MINGW_ANSI_STDIO)
#define __USE_MINGW_ANSI_STDIO 1 /* C99 printf (%zu) on Windows too */
#endif
#include "instance_internal.h"
#include "state_format.h"

#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- FMU states ------------------------------------------------------------ */

static size_t snapshot_size(void) { return sizeof(Snapshot) + MD.data_size; }

static int owns_snapshot(const Instance *inst, const void *s)
{
    for (size_t i = 0; i < inst->n_snapshots; ++i)
        if ((const void *)inst->snapshots[i] == s) return 1;
    return 0;
}

static Snapshot *new_snapshot(Instance *inst)
{
    if (inst->n_snapshots == inst->snapshot_capacity) {
        size_t capacity = inst->snapshot_capacity ? 2 * inst->snapshot_capacity : 4;
        Snapshot **grown = realloc(inst->snapshots, capacity * sizeof *grown);
        if (!grown) return NULL;
        inst->snapshots = grown;
        inst->snapshot_capacity = capacity;
    }
    Snapshot *s = calloc(1, snapshot_size());
    if (s) inst->snapshots[inst->n_snapshots++] = s;
    return s;
}

static int model_data_valid(Instance *inst, const char *function, const unsigned char *data,
                            const unsigned char *initialized);

Status instance_get_state(Instance *inst, const char *function, void **state)
{
    if (!state) return instance_fail(inst, "%s: FMUstate is NULL", function);
    if (instance_refresh_outputs(inst) != STATUS_OK) return STATUS_ERROR; /* a state holds its outputs */
    /* never hand out a state that deserialization would refuse: a computation that
     * overflowed (from a restored state of extreme values) leaves no state to take */
    if ((inst->clock.state & inst->api->stepping_states) &&
        !model_data_valid(inst, function, inst->data, NULL))
        return instance_fail(inst, "%s: the instance's computation overflowed; no state taken",
                             function);
    Snapshot *s = *state;
    if (s && !owns_snapshot(inst, s))
        return instance_fail(inst, "%s: *FMUstate is neither NULL nor a state of this "
                             "instance (uninitialized pointer?)", function);
    if (!s && !(s = new_snapshot(inst))) return instance_fail(inst, "%s: out of memory", function);
    s->clock = inst->clock;
    memcpy(s->data, inst->data, MD.data_size);
    *state = s;
    return STATUS_OK;
}

Status instance_set_state(Instance *inst, const char *function, const void *state)
{
    const Snapshot *s = state;
    if (!s || !owns_snapshot(inst, s))
        return instance_fail(inst, "%s: FMUstate is NULL or not a state of this instance",
                             function);
    inst->clock = s->clock;
    memcpy(inst->data, s->data, MD.data_size);
    return STATUS_OK;
}

Status instance_free_state(Instance *inst, const char *function, void **state)
{
    if (!state || !*state) return STATUS_OK; /* freeing nothing is harmless */
    for (size_t i = 0; i < inst->n_snapshots; ++i) {
        if ((void *)inst->snapshots[i] == *state) {
            free(inst->snapshots[i]);
            inst->snapshots[i] = inst->snapshots[--inst->n_snapshots];
            *state = NULL;
            return STATUS_OK;
        }
    }
    return instance_fail(inst, "%s: not a state of this instance", function);
}

static size_t serialized_size(void) { return sizeof(StateHeader) + snapshot_size(); }

Status instance_serialized_size(Instance *inst, const char *function, const void *state,
                                size_t *size)
{
    if (!state || !owns_snapshot(inst, state) || !size)
        return instance_fail(inst, "%s: FMUstate or size is NULL or foreign", function);
    *size = serialized_size();
    return STATUS_OK;
}

Status instance_serialize(Instance *inst, const char *function, const void *state,
                          unsigned char *bytes, size_t size)
{
    if (!state || !owns_snapshot(inst, state) || !bytes)
        return instance_fail(inst, "%s: FMUstate or buffer is NULL or foreign", function);
    if (size != serialized_size())
        return instance_fail(inst, "%s: buffer size %zu, expected %zu", function, size,
                             serialized_size());
    StateHeader header;
    memset(&header, 0, sizeof header);
    memcpy(header.magic, inst->api->state_magic, sizeof header.magic);
    header.version = STATE_VERSION;
    header.size = size;
    header.guid_hash = state_fnv1a(MD.guid, strlen(MD.guid), STATE_FNV_OFFSET);
    header.checksum = state_fnv1a(state, snapshot_size(), STATE_FNV_OFFSET);
    memcpy(bytes, &header, sizeof header);
    memcpy(bytes + sizeof header, state, snapshot_size());
    return STATUS_OK;
}

/* ---- restored model data ----------------------------------------------------
 * A serialized state is native bytes behind an unkeyed checksum: anyone can
 * patch a field and recompute it.  So the data block is accepted only if it
 * is one that this FMU could have written itself, field by field. */

static void silent_log(void *context, ModelStatus status, const char *format, ...)
{
    (void)context, (void)status, (void)format;
}

/* Before initialization only the setters have written: the block must be the
 * start values with the variables' values (built the same way, byte for byte). */
static int unstarted_data_valid(const Instance *inst, const char *function,
                                const unsigned char *data)
{
    unsigned char *fresh = malloc(MD.data_size);
    if (!fresh) {
        instance_log(inst, STATUS_ERROR, "%s: out of memory", function);
        return 0;
    }
    instance_start_data(inst, fresh);
    for (size_t v = 0; v < MD.n_variables; ++v) {
        const ModelVariable *var = &MD.variables[v];
        const size_t element = var->type == TYPE_REAL ? sizeof(double) : sizeof(int);
        memcpy(fresh + var->offset, data + var->offset, model_variable_count(var) * element);
    }
    size_t at = 0;
    while (at < MD.data_size && fresh[at] == data[at]) ++at;
    free(fresh);
    if (at == MD.data_size) return 1;
    instance_log(inst, STATUS_ERROR, "%s: the state is one before initialization, but its "
                 "internal data (byte %zu of %zu) is not the start state; state refused",
                 function, at, MD.data_size);
    return 0;
}

static void mark(unsigned char *covered, size_t offset, size_t size)
{
    memset(covered + offset, 1, size);
}

/* Every 8-byte word of [offset, offset + size) that nothing covers is a finite
 * double (a word that holds part of a listed int is its padding).  Logs the first
 * offender by the field's name and byte. */
static int reals_valid(const Instance *inst, const char *function, const unsigned char *data,
                       unsigned char *covered, const char *name, size_t offset, size_t size)
{
    for (size_t at = offset + (8 - offset % 8) % 8; at + 8 <= offset + size; at += 8) {
        int free_word = 1;
        for (size_t b = 0; b < 8; ++b) free_word &= !covered[at + b];
        if (!free_word) continue;
        double value;
        memcpy(&value, data + at, sizeof value);
        if (!isfinite(value)) {
            instance_log(inst, STATUS_ERROR, "%s: %s (its byte %zu) = %g in the state is not "
                         "finite; state refused", function, name, at - offset, value);
            return 0;
        }
        mark(covered, at, 8);
    }
    return 1;
}

/* One field of the model's table (initialized NULL: derived fields are not compared). */
static int field_valid(const Instance *inst, const char *function, const StateField *f,
                       const unsigned char *data, const unsigned char *initialized,
                       unsigned char *covered)
{
    const size_t width = f->check == FIELD_REAL ? sizeof(double) : sizeof(int);
    if (f->offset > MD.data_size || f->size > MD.data_size - f->offset ||
        (f->check <= FIELD_REAL && f->size % width != 0)) {
        instance_log(inst, STATUS_ERROR, "%s: the model's field table is wrong at %s", function,
                     f->name);
        return 0;
    }
    if (f->check == FIELD_REALS)
        return reals_valid(inst, function, data, covered, f->name, f->offset, f->size);
    mark(covered, f->offset, f->size);
    if (f->check == FIELD_ANY) return 1;
    if (f->check == FIELD_DERIVED) {
        if (!initialized) return 1;
        if (memcmp(data + f->offset, initialized + f->offset, f->size) == 0) return 1;
        instance_log(inst, STATUS_ERROR, "%s: %s in the state is not what initialization derives "
                     "from the state's own parameters; state refused", function, f->name);
        return 0;
    }
    const double lo = isnan(f->min) ? -DBL_MAX : f->min, hi = isnan(f->max) ? DBL_MAX : f->max;
    for (size_t e = 0; e < f->size / width; ++e) {
        double value;
        const unsigned char *at = data + f->offset + e * width;
        if (f->check == FIELD_REAL) {
            memcpy(&value, at, sizeof value);
        } else if (f->check == FIELD_INT) {
            int i;
            memcpy(&i, at, sizeof i);
            value = i;
        } else {
            unsigned u;
            memcpy(&u, at, sizeof u);
            value = u;
        }
        if (!(value >= lo && value <= hi)) {
            char index[32] = "";
            if (f->size > width) snprintf(index, sizeof index, " (element %zu)", e);
            instance_log(inst, STATUS_ERROR, "%s: %s%s = %.17g in the state is out of its range "
                         "[%.17g, %.17g]; state refused", function, f->name, index, value, lo, hi);
            return 0;
        }
    }
    return 1;
}

/* The model data's checks: the variables of the table (calculated parameters as
 * `initialized` derives them, outputs finite), the model's field table, every other
 * word a finite double.  initialized NULL: nothing is compared with an initialization
 * (a state about to be taken, which deserialization would otherwise refuse). */
static int model_data_valid(Instance *inst, const char *function, const unsigned char *data,
                            const unsigned char *initialized)
{
    unsigned char *covered = calloc(MD.data_size, 1);
    int ok = covered != NULL;
    if (!ok) instance_log(inst, STATUS_ERROR, "%s: out of memory", function);
    for (size_t v = 0; ok && v < MD.n_variables; ++v) {
        const ModelVariable *var = &MD.variables[v];
        const size_t count = model_variable_count(var);
        const size_t bytes = count * (var->type == TYPE_REAL ? sizeof(double) : sizeof(int));
        mark(covered, var->offset, bytes);
        for (size_t e = 0; ok && e < count; ++e) {
            const double value = instance_element_value(data, var, e);
            const double derived = initialized ? instance_element_value(initialized, var, e) : value;
            char name[64];
            instance_element_name(var, e, name, sizeof name);
            if (var->causality == CAUSALITY_CALCULATED_PARAMETER &&
                memcmp(&value, &derived, sizeof value) != 0) {
                instance_log(inst, STATUS_ERROR, "%s: %s = %g in the state is not what "
                             "initialization derives from the state's own parameters (%g); "
                             "state refused", function, name, value, derived);
                ok = 0;
            } else if (var->causality == CAUSALITY_OUTPUT &&
                       (var->type == TYPE_BOOLEAN ? value != 0.0 && value != 1.0
                                                  : !isfinite(value))) {
                instance_log(inst, STATUS_ERROR, "%s: the output %s = %g in the state is not "
                             "%s; state refused", function, name, value,
                             var->type == TYPE_BOOLEAN ? "a Boolean" : "finite");
                ok = 0;
            }
        }
    }
    if (ok && inst->resource) mark(covered, MD.resource_offset, MD.resource_size);
    for (size_t f = 0; ok && f < MD.n_state_fields; ++f)
        ok = field_valid(inst, function, &MD.state_fields[f], data, initialized, covered);
    if (ok) ok = reals_valid(inst, function, data, covered, "the model data", 0, MD.data_size);
    free(covered);
    return ok;
}

/* A state that can step again: the variables of the table (calculated
 * parameters as initialization derives them, outputs finite), the model's
 * field table, every other word a finite double, then the model's own
 * invariants.  The state's parameters go through initialize on a copy. */
static int stepping_data_valid(Instance *inst, const char *function, const Clock *clock,
                               const unsigned char *data)
{
    unsigned char *initialized = malloc(MD.data_size);
    int ok = initialized != NULL;
    if (!ok) instance_log(inst, STATUS_ERROR, "%s: out of memory", function);
    ModelLogger silent = {silent_log, NULL};
    if (ok) {
        memcpy(initialized, data, MD.data_size);
        ok = MD.initialize(initialized, clock->start_time, &silent) != MODEL_ERROR;
        if (!ok)
            instance_log(inst, STATUS_ERROR, "%s: the state's parameters do not initialize; "
                         "state refused", function);
    }
    if (ok) ok = model_data_valid(inst, function, data, initialized);
    ModelLogger logger = instance_model_logger(inst);
    if (ok && MD.check_restored) ok = MD.check_restored(data, initialized, &logger) != MODEL_ERROR;
    free(initialized);
    return ok;
}

Status instance_deserialize(Instance *inst, const char *function, const unsigned char *bytes,
                            size_t size, void **state)
{
    if (!bytes || !state) return instance_fail(inst, "%s: buffer or FMUstate is NULL", function);
    if (size != serialized_size())
        return instance_fail(inst, "%s: wrong size %zu, a %s state has %zu bytes", function,
                             size, MD.model_identifier, serialized_size());
    StateHeader header;
    memcpy(&header, bytes, sizeof header);
    if (memcmp(header.magic, inst->api->state_magic, sizeof header.magic) != 0)
        return instance_fail(inst, "%s: not a serialized FMU state (bad magic)", function);
    if (header.version != STATE_VERSION)
        return instance_fail(inst, "%s: format version %u, expected %u", function,
                             (unsigned)header.version, STATE_VERSION);
    if (header.size != size ||
        header.guid_hash != state_fnv1a(MD.guid, strlen(MD.guid), STATE_FNV_OFFSET))
        return instance_fail(inst, "%s: state of another FMU or build", function);
    const unsigned char *payload = bytes + sizeof header;
    if (header.checksum != state_checksum(bytes, size))
        return instance_fail(inst, "%s: checksum mismatch (corrupted state)", function);
    if (header.reserved != 0)
        return instance_fail(inst, "%s: reserved header field %u is not 0", function,
                             (unsigned)header.reserved);
    Clock clock;
    memcpy(&clock, payload, sizeof clock);
    if (!(clock.state & inst->api->restorable_states) || (clock.state & (clock.state - 1)))
        return instance_fail(inst, "%s: invalid instance state in buffer", function);
    if (clock.stop_time_defined > 1u ||
        (clock.stop_time_defined && !(clock.stop_time >= clock.start_time)))
        return instance_fail(inst, "%s: inconsistent stop time in the state (defined = %u, "
                             "stopTime = %g, startTime = %g)", function,
                             (unsigned)clock.stop_time_defined, clock.stop_time, clock.start_time);
    const unsigned char *data = payload + offsetof(Snapshot, data);
    if (!instance_data_valid(inst, function, data) || !instance_resource_valid(inst, function, data))
        return instance_escalate(inst, STATUS_ERROR);
    if ((clock.state & inst->api->unstarted_states) &&
        (clock.steps != 0 || clock.comm_time != clock.start_time))
        return instance_fail(inst, "%s: a state before initialization with %llu steps taken "
                             "(time %g, start %g); state refused", function,
                             (unsigned long long)clock.steps, clock.comm_time, clock.start_time);
    if ((clock.state & inst->api->unstarted_states) && !unstarted_data_valid(inst, function, data))
        return instance_escalate(inst, STATUS_ERROR);
    if ((clock.state & inst->api->stepping_states) &&
        !stepping_data_valid(inst, function, &clock, data))
        return instance_escalate(inst, STATUS_ERROR);
    /* The clock must be where its step count says: comm_time = start + steps h
     * (within a step); otherwise the next doStep could run ~2^53 steps. */
    const double h = MD.internal_step(data);
    const double grid_time = clock.start_time + (double)clock.steps * h;
    if (!isfinite(clock.start_time) || !isfinite(clock.comm_time) ||
        !isfinite(clock.stop_time) || !(fabs(clock.comm_time - grid_time) <= 2.0 * h))
        return instance_fail(inst, "%s: inconsistent clock in the state (time %g, %llu steps of "
                             "%g from %g)", function, clock.comm_time,
                             (unsigned long long)clock.steps, h, clock.start_time);
    Snapshot *s = *state;
    if (s && !owns_snapshot(inst, s))
        return instance_fail(inst, "%s: *FMUstate is not a state of this instance", function);
    if (!s && !(s = new_snapshot(inst))) return instance_fail(inst, "%s: out of memory", function);
    memcpy(s, payload, snapshot_size());
    *state = s;
    return STATUS_OK;
}
