/* Model-independent instance core (see instance.h): lifecycle, start values and
 * tables, the clock and stepping.  Every FMU of the project links the core's files
 * unchanged with one model file that defines MODEL_DESCRIPTOR and with one API file
 * (FMI 2 or FMI 3). */
#include "instance_internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- start values and tables --------------------------------------------- */

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

/* FMI 2 names every element (vr + e); FMI 3 names the array (vr) only. */
static void fill_vr_table(int16_t *table, uint32_t limit, bool array_references)
{
    for (uint32_t r = 0; r < limit; ++r) table[r] = -1;
    for (size_t v = 0; v < MD.n_variables; ++v) {
        const size_t elements = array_references ? 1 : model_variable_count(&MD.variables[v]);
        for (size_t e = 0; e < elements; ++e) table[MD.variables[v].vr + e] = (int16_t)v;
    }
}

/* with_calculated: at initialization, where every output is derived */
int instance_is_checked_output(const ModelVariable *var, int with_calculated)
{
    return var->type == TYPE_REAL &&
           ((var->causality == CAUSALITY_OUTPUT && (with_calculated || !var->on_read)) ||
            (with_calculated && var->causality == CAUSALITY_CALCULATED_PARAMETER));
}

static void build_output_spans(Instance *inst)
{
    inst->n_output_spans = 0;
    for (size_t v = 0; v < MD.n_variables; ++v) {
        const ModelVariable *var = &MD.variables[v];
        if (!instance_is_checked_output(var, 0)) continue;
        const size_t last = inst->n_output_spans - 1;
        if (inst->n_output_spans > 0 && /* adjacent to the last span: one loop for both */
            inst->output_span_offset[last] + inst->output_span_count[last] * sizeof(double) ==
                var->offset) {
            inst->output_span_count[last] += (uint32_t)model_variable_count(var);
            continue;
        }
        if (inst->n_output_spans == MAX_OUTPUT_SPANS) { /* too many: always use the full scan */
            inst->n_output_spans = (size_t)-1;
            return;
        }
        inst->output_span_offset[inst->n_output_spans] = (uint32_t)var->offset;
        inst->output_span_count[inst->n_output_spans++] = (uint32_t)model_variable_count(var);
    }
}

/* A data block at its start: the start values and the instance's resource region. */
void instance_start_data(const Instance *inst, void *data)
{
    apply_start_values(data);
    if (!inst->resource) return;
    memcpy((unsigned char *)data + MD.resource_offset, inst->resource, MD.resource_size);
    if (MD.resource_start_values) MD.resource_start_values(data);
}

/* Reads the model's resource file from resource_dir into inst->resource. */
static int load_resource(Instance *inst, const char *function, const char *resource_dir)
{
    if (!resource_dir || !resource_dir[0]) {
        instance_log(inst, STATUS_ERROR, "%s: no resource location given: %s reads its model "
                     "from resources/%s", function, MD.model_identifier, MD.resource_file);
        return 0;
    }
    const size_t dir_length = strlen(resource_dir), file_length = strlen(MD.resource_file);
    char *path = malloc(dir_length + file_length + 2);
    char *text = malloc(MD.resource_max_bytes + 1);
    inst->resource = calloc(1, MD.resource_size);
    if (!path || !text || !inst->resource) {
        free(path);
        free(text);
        instance_log(inst, STATUS_ERROR, "%s: out of memory", function);
        return 0;
    }
    memcpy(path, resource_dir, dir_length);
    const char last = dir_length ? resource_dir[dir_length - 1] : '/';
    size_t at = dir_length;
    if (last != '/' && last != '\\') path[at++] = '/';
    memcpy(path + at, MD.resource_file, file_length + 1);
    FILE *file = fopen(path, "rb");
    size_t length = 0;
    int ok = file != NULL;
    if (!file) {
        instance_log(inst, STATUS_ERROR, "%s: cannot open the model file %s", function, path);
    } else {
        length = fread(text, 1, MD.resource_max_bytes + 1, file);
        if (ferror(file)) {
            instance_log(inst, STATUS_ERROR, "%s: cannot read %s", function, path);
            ok = 0;
        } else if (length > MD.resource_max_bytes) {
            instance_log(inst, STATUS_ERROR, "%s: %s is longer than %zu bytes", function, path,
                         MD.resource_max_bytes);
            ok = 0;
        }
        fclose(file);
    }
    if (ok) {
        ModelLogger logger = instance_model_logger(inst);
        ok = MD.parse_resource(inst->resource, text, length, &logger) != MODEL_ERROR;
    }
    free(path);
    free(text);
    return ok;
}

/* A restored block must hold this instance's resource region. */
int instance_resource_valid(const Instance *inst, const char *function, const unsigned char *data)
{
    if (!inst->resource ||
        memcmp(data + MD.resource_offset, inst->resource, MD.resource_size) == 0)
        return 1;
    instance_log(inst, STATUS_ERROR, "%s: the state was written with another model file than "
                 "this instance's resources/%s; state refused", function, MD.resource_file);
    return 0;
}

static void reset_clock(Instance *inst)
{
    memset(&inst->clock, 0, sizeof inst->clock);
    inst->clock.state = inst->api->instantiated_state;
}

/* ---- lifecycle ------------------------------------------------------------ */

bool instance_arguments_valid(const InstanceApi *api, AnyFunction logger, void *environment,
                              const char *function, const char *name, const char *token)
{
    if (!name || !name[0]) {
        instance_log_to(api, logger, environment, name, STATUS_ERROR,
                        "%s: instanceName is NULL or empty", function);
        return false;
    }
    if (!token || strcmp(token, MD.guid) != 0) {
        instance_log_to(api, logger, environment, name, STATUS_ERROR,
                        "%s: GUID mismatch: got %s, this binary is %s", function,
                        token ? token : "(NULL)", MD.guid);
        return false;
    }
    return true;
}

Instance *instance_new(const InstanceApi *api, const char *function, const char *name,
                       AnyFunction logger, void *environment, bool logging_on,
                       const char *resource_dir)
{
    Instance *inst = calloc(1, sizeof *inst);
    if (inst) {
        inst->api = api;
        inst->logger = logger;
        inst->environment = environment;
        inst->logging_on = logging_on;
        inst->name = malloc(strlen(name) + 1);
        inst->data = calloc(1, MD.data_size);
        inst->vr_limit = count_value_references();
        inst->variable_of_vr = calloc(inst->vr_limit, sizeof *inst->variable_of_vr);
    }
    if (!inst || !inst->name || !inst->data || !inst->variable_of_vr) {
        instance_log_to(api, logger, environment, name, STATUS_ERROR, "%s: out of memory",
                        function);
        instance_free(inst);
        return NULL;
    }
    strcpy(inst->name, name);
    if (MD.resource_file && !load_resource(inst, function, resource_dir)) {
        instance_free(inst);
        return NULL;
    }
    fill_vr_table(inst->variable_of_vr, inst->vr_limit, api->array_references);
    build_output_spans(inst);
    instance_reset(inst);
    return inst;
}

void instance_free(Instance *inst)
{
    if (!inst) return;
    for (size_t i = 0; i < inst->n_snapshots; ++i) free(inst->snapshots[i]);
    free(inst->snapshots);
    free(inst->variable_of_vr);
    free(inst->resource);
    free(inst->data);
    free(inst->name);
    free(inst);
}

void instance_reset(Instance *inst)
{
    reset_clock(inst);
    instance_start_data(inst, inst->data);
}

/* ---- experiment and stepping ---------------------------------------------- */

Status instance_setup_experiment(Instance *inst, const char *function, double start_time,
                                 bool stop_time_defined, double stop_time)
{
    if (!isfinite(start_time))
        return instance_fail(inst, "%s: startTime = %g is not finite", function, start_time);
    if (stop_time_defined && !(isfinite(stop_time) && stop_time >= start_time))
        return instance_fail(inst, "%s: stopTime = %g must be finite and >= startTime = %g",
                             function, stop_time, start_time);
    inst->clock.start_time = start_time;
    inst->clock.comm_time = start_time;
    inst->clock.stop_time_defined = stop_time_defined ? 1u : 0u;
    inst->clock.stop_time = stop_time_defined ? stop_time : 0.0;
    return STATUS_OK;
}

Status instance_initialize(Instance *inst, const char *function)
{
    ModelLogger logger = instance_model_logger(inst);
    ModelStatus status = MD.initialize(inst->data, inst->clock.start_time, &logger);
    if (status == MODEL_ERROR || !instance_outputs_finite(inst, function, 1))
        return instance_escalate(inst, STATUS_ERROR);
    inst->clock.steps = 0;
    inst->clock.comm_time = inst->clock.start_time;
    return (Status)status;
}

#define GRID_SLACK 1e-3

Status instance_do_step(Instance *inst, const char *function, double t, double H)
{
    const double h = MD.internal_step(inst->data);
    Clock *clock = &inst->clock;
    if (!(H > 0.0) || !isfinite(H))
        return instance_fail(inst, "%s: communicationStepSize = %g must be > 0 and finite",
                             function, H);
    /* Importers accumulate t += H, so allow a few ulp of disagreement. */
    const double tolerance = 1e-6 * h + 1e-12 * fabs(clock->comm_time);
    if (!isfinite(t) || fabs(t - clock->comm_time) > tolerance)
        return instance_fail(inst, "%s: currentCommunicationPoint = %.17g is not the "
                             "instance's time %.17g", function, t, clock->comm_time);
    const double t_end = t + H;
    if (clock->stop_time_defined && t_end > clock->stop_time + tolerance)
        return instance_fail(inst, "%s: step to %.17g goes past stopTime = %.17g", function,
                             t_end, clock->stop_time);
    /* Internal grid points start_time + k*h with k an integer (no drift).  A step
     * that is not a multiple of h runs every internal step ending at or before
     * t_end; the outputs then belong to the last grid point, less than h before t_end.
     * A grid point less than GRID_SLACK h after t_end counts as reached: a master
     * that accumulates t += H drifts off the grid by rounding, far more at large t. */
    const double k_end_real = floor((t_end - clock->start_time) / h + GRID_SLACK);
    /* The work of one call is bounded: refused before any of it is done. */
    const uint64_t limit = MD.max_internal_steps(inst->data);
    if (!(k_end_real < 9007199254740992.0))
        return instance_fail(inst, "%s: step to %.17g needs more than 2^53 internal steps of "
                             "h = %g, more than the limit max_internal_steps = %llu allows; take "
                             "shorter communication steps", function, t_end, h,
                             (unsigned long long)limit);
    const uint64_t k_end = k_end_real > (double)clock->steps ? (uint64_t)k_end_real : clock->steps;
    if (k_end - clock->steps > limit)
        return instance_fail(inst, "%s: the step from %.17g to %.17g needs %llu internal steps "
                             "of h = %g, more than the limit max_internal_steps = %llu; take "
                             "shorter communication steps or raise the parameter "
                             "max_internal_steps (value reference %u) before initialization",
                             function, t, t_end, (unsigned long long)(k_end - clock->steps), h,
                             (unsigned long long)limit, (unsigned)MAX_INTERNAL_STEPS_VR);
    /* The same refusal by the work it would take: the step count alone lets an
     * expensive configuration (a 7-joint robot with its identifier) run for minutes. */
    const uint64_t steps = k_end - clock->steps;
    const double cost = MD.work_per_step(inst->data), budget = MD.max_work(inst->data);
    if ((double)steps * cost > budget) {
        const double most = floor(budget / cost);
        return instance_fail(inst, "%s: the step from %.17g to %.17g needs %llu internal steps "
                             "of h = %g at work_per_step = %g work units each, %.4g units, more "
                             "than the work budget max_work = %.4g; take communication steps "
                             "of at most %.0f internal steps (%g s) or raise the parameter "
                             "max_work (value reference %u) before initialization", function, t,
                             t_end, (unsigned long long)steps, h, cost, (double)steps * cost,
                             budget, most, most * h, (unsigned)MAX_WORK_VR);
    }
    /* Called even when the step reaches no grid point (H < h): the model sees
     * every communication step's inputs (a rising edge of a discrete input
     * held for one short step is never lost). */
    MD.advance(inst->data, clock->start_time, clock->steps, k_end);
    ModelLogger logger = instance_model_logger(inst);
    if (MD.communication_point(inst->data, t_end, &logger) == MODEL_ERROR ||
        !instance_outputs_finite(inst, function, 0))
        return instance_escalate(inst, STATUS_ERROR); /* the clock stays at the last
                                                       * successful step's end */
    clock->steps = k_end;
    clock->comm_time = t_end;
    return STATUS_OK;
}
