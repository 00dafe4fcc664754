/* Model-independent instance core (see instance.h).  Every FMU of the
 * project links this file unchanged with one model file that defines
 * MODEL_DESCRIPTOR and with one API file (FMI 2 or FMI 3). */
#if defined(__MINGW32__) && !defined(__USE_MINGW_ANSI_STDIO)
#define __USE_MINGW_ANSI_STDIO 1 /* C99 printf (%zu) on Windows too */
#endif
#include "instance.h"
#include "state_format.h"

#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define MD MODEL_DESCRIPTOR

/* ---- logging ------------------------------------------------------------ */

static const char *const LOG_CATEGORIES[] = {"logStatusWarning", "logStatusError", "logAll"};
#define N_LOG_CATEGORIES (sizeof LOG_CATEGORIES / sizeof LOG_CATEGORIES[0])
#define LOG_TEXT_SIZE 1024

static void vlog_to(const InstanceApi *api, AnyFunction logger, void *environment,
                    const char *name, bool logging_on, Status status, const char *format,
                    va_list args)
{
    if (!logger) return;
    /* Warnings and errors are always reported; OK-level messages only with debug logging. */
    if (status == STATUS_OK && !logging_on) return;
    char text[LOG_TEXT_SIZE];
    vsnprintf(text, sizeof text, format, args);
    const char *category = status >= STATUS_ERROR ? "logStatusError"
                           : status == STATUS_WARNING ? "logStatusWarning" : "logAll";
    api->sink(logger, environment, name ? name : "", status, category, text);
}

void instance_log_to(const InstanceApi *api, AnyFunction logger, void *environment,
                     const char *name, Status status, const char *format, ...)
{
    va_list args;
    va_start(args, format);
    vlog_to(api, logger, environment, name, true, status, format, args);
    va_end(args);
}

static void vlog_instance(const Instance *inst, Status status, const char *format, va_list args)
{
    vlog_to(inst->api, inst->logger, inst->environment, inst->name, inst->logging_on, status,
            format, args);
}

void instance_log(const Instance *inst, Status status, const char *format, ...)
{
    va_list args;
    va_start(args, format);
    vlog_instance(inst, status, format, args);
    va_end(args);
}

static void model_log(void *context, ModelStatus status, const char *format, ...)
{
    va_list args;
    va_start(args, format);
    vlog_instance(context, (Status)status, format, args);
    va_end(args);
}

static ModelLogger model_logger(Instance *inst)
{
    ModelLogger logger = {model_log, inst};
    return logger;
}

/* An error leaves the instance in the API's error state. */
Status instance_escalate(Instance *inst, Status status)
{
    if (status >= STATUS_ERROR) inst->clock.state = inst->api->error_state;
    return status;
}

Status instance_fail(Instance *inst, const char *format, ...)
{
    va_list args;
    va_start(args, format);
    vlog_instance(inst, STATUS_ERROR, format, args);
    va_end(args);
    return instance_escalate(inst, STATUS_ERROR);
}

Status instance_set_debug_logging(Instance *inst, const char *function, bool on,
                                  size_t n_categories, const char *const categories[])
{
    if (n_categories > 0 && !categories)
        return instance_fail(inst, "%s: categories is NULL but nCategories = %zu", function,
                             n_categories);
    for (size_t i = 0; i < n_categories; ++i) {
        int known = 0;
        for (size_t k = 0; categories[i] && k < N_LOG_CATEGORIES; ++k)
            known |= strcmp(categories[i], LOG_CATEGORIES[k]) == 0;
        if (!known)
            return instance_fail(inst, "%s: unknown log category \"%s\"", function,
                                 categories[i] ? categories[i] : "(NULL)");
    }
    inst->logging_on = on;
    return STATUS_OK;
}

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
static int is_checked_output(const ModelVariable *var, int with_calculated)
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
        if (!is_checked_output(var, 0)) continue;
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
static void start_data(const Instance *inst, void *data)
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
        ModelLogger logger = model_logger(inst);
        ok = MD.parse_resource(inst->resource, text, length, &logger) != MODEL_ERROR;
    }
    free(path);
    free(text);
    return ok;
}

/* A restored block must hold this instance's resource region. */
static int resource_valid(const Instance *inst, const char *function, const unsigned char *data)
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
    start_data(inst, inst->data);
}

/* ---- variables ------------------------------------------------------------ */

static const char *type_name(VariableType type)
{
    return type == TYPE_REAL ? "Real" : type == TYPE_INTEGER ? "Integer" : "Boolean";
}

/* The structured name of one element, e.g. theta_hat[1,3]. */
static void element_name(const ModelVariable *var, size_t element, char *out, size_t size)
{
    if (!var->rows) snprintf(out, size, "%s", var->name);
    else if (!var->cols) snprintf(out, size, "%s[%zu]", var->name, element + 1);
    else snprintf(out, size, "%s[%zu,%zu]", var->name, element / var->cols + 1,
                  element % var->cols + 1);
}

/* Is the value finite and inside the variable's declared range? */
static int in_range(const ModelVariable *var, double value)
{
    if (!isfinite(value)) return 0;
    if (!isnan(var->min) && (var->min_exclusive ? value <= var->min : value < var->min)) return 0;
    if (!isnan(var->max) && (var->max_exclusive ? value >= var->max : value > var->max)) return 0;
    return 1;
}

/* The value of one element of a data block, as a double. */
static double element_value(const void *data, const ModelVariable *var, size_t element)
{
    const char *base = (const char *)data + var->offset;
    return var->type == TYPE_REAL ? ((const double *)base)[element]
                                  : (double)((const int *)base)[element];
}

/* An OK status never comes with a non-finite output: checks every Real output
 * (and, at initialization, calculated parameter); logs the first offender.
 * The usual case costs one multiply-add per output: x * 0 is NaN for inf and NaN. */
static int outputs_finite(const Instance *inst, const char *function, int with_calculated)
{
    if (!with_calculated && inst->n_output_spans != (size_t)-1) {
        double poison = 0.0;
        for (size_t s = 0; s < inst->n_output_spans; ++s) {
            const double *values =
                (const double *)((const char *)inst->data + inst->output_span_offset[s]);
            const uint32_t count = inst->output_span_count[s];
            uint32_t e = 0;
            double other = 0.0; /* two sums: half the dependent additions */
            for (; e + 2 <= count; e += 2) {
                poison += values[e] * 0.0;
                other += values[e + 1] * 0.0;
            }
            if (e < count) poison += values[e] * 0.0;
            poison += other;
        }
        if (poison == 0.0) return 1;
    }
    for (size_t v = 0; v < MD.n_variables; ++v) {
        const ModelVariable *var = &MD.variables[v];
        if (!is_checked_output(var, with_calculated)) continue;
        const double *values = (const double *)((const char *)inst->data + var->offset);
        for (size_t e = 0; e < model_variable_count(var); ++e) {
            if (!isfinite(values[e])) {
                char name[64];
                element_name(var, e, name, sizeof name);
                instance_log(inst, STATUS_ERROR, "%s: %s = %g is not finite (the parameters or "
                             "inputs drive the model out of range)", function, name, values[e]);
                return 0;
            }
        }
    }
    return 1;
}

/* A restored data block must satisfy what the setters enforce: every parameter
 * and input inside its range.  (The state checksum detects accidents, not a
 * forged buffer.)  Logs the first offender. */
static int data_valid(const Instance *inst, const char *function, const void *data)
{
    for (size_t v = 0; v < MD.n_variables; ++v) {
        const ModelVariable *var = &MD.variables[v];
        if (var->causality != CAUSALITY_PARAMETER && var->causality != CAUSALITY_INPUT) continue;
        for (size_t e = 0; e < model_variable_count(var); ++e) {
            const double value = element_value(data, var, e);
            if (var->type == TYPE_BOOLEAN ? value != 0.0 && value != 1.0 : !in_range(var, value)) {
                char name[64];
                element_name(var, e, name, sizeof name);
                instance_log(inst, STATUS_ERROR, "%s: %s = %g in the state is not finite or out "
                             "of range", function, name, value);
                return 0;
            }
        }
    }
    return 1;
}

/* One value reference resolved: the variable, its first element addressed by
 * the reference and how many elements the reference stands for. */
typedef struct {
    const ModelVariable *var;
    size_t element, count;
} Target;

/* Resolves vr for a get or set of the given type; logs and returns 0 if it cannot. */
static int locate(Instance *inst, const char *function, uint32_t vr, VariableType type,
                  Target *target)
{
    if (vr >= inst->vr_limit || inst->variable_of_vr[vr] < 0) {
        instance_log(inst, STATUS_ERROR, "%s: unknown value reference %u", function,
                     (unsigned)vr);
        return 0;
    }
    const ModelVariable *var = &MD.variables[inst->variable_of_vr[vr]];
    target->var = var;
    target->element = vr - var->vr;
    target->count = inst->api->array_references ? model_variable_count(var) : 1;
    if (var->type != type) {
        char name[64];
        element_name(var, target->element, name, sizeof name);
        if (inst->api->array_references) snprintf(name, sizeof name, "%s", var->name);
        instance_log(inst, STATUS_ERROR, "%s: %s (value reference %u) is a %s, not a %s",
                     function, name, (unsigned)vr, type_name(var->type), type_name(type));
        return 0;
    }
    return 1;
}

static Status check_arrays(Instance *inst, const char *function, const void *vr, size_t nvr,
                           const void *values)
{
    if (nvr > 0 && (!vr || !values))
        return instance_fail(inst, "%s: vr or value array is NULL with nvr = %zu", function, nvr);
    return STATUS_OK;
}

static bool is_time(const Instance *inst, VariableType type, uint32_t vr)
{
    return inst->api->time_at_vr0 && vr == 0 && type == TYPE_REAL;
}

/* Every reference resolvable, and (FMI 3) the values' length the elements' total. */
static Status check_targets(Instance *inst, const char *function, VariableType type,
                            const uint32_t vr[], size_t nvr, size_t n_values)
{
    size_t total = 0;
    for (size_t i = 0; i < nvr; ++i) {
        Target target;
        if (is_time(inst, type, vr[i])) { ++total; continue; }
        if (!locate(inst, function, vr[i], type, &target))
            return instance_escalate(inst, STATUS_ERROR);
        total += target.count;
    }
    if (total != n_values)
        return instance_fail(inst, "%s: nValues = %zu, but the %zu value references have %zu "
                             "values", function, n_values, nvr, total);
    return STATUS_OK;
}

/* The outputs the model derives when read (ModelDescriptor.refresh_outputs). */
static Status refresh_outputs(Instance *inst)
{
    if (!MD.refresh_outputs) return STATUS_OK;
    ModelLogger logger = model_logger(inst);
    if (MD.refresh_outputs(inst->data, &logger) == MODEL_ERROR)
        return instance_escalate(inst, STATUS_ERROR);
    return STATUS_OK;
}

Status instance_get(Instance *inst, const char *function, VariableType type,
                    const uint32_t vr[], size_t nvr, void *values, size_t n_values)
{
    if (check_arrays(inst, function, vr, nvr, values) != STATUS_OK ||
        check_targets(inst, function, type, vr, nvr, n_values) != STATUS_OK)
        return STATUS_ERROR;
    size_t k = 0;
    int refreshed = 0;
    for (size_t i = 0; i < nvr; ++i) {
        if (is_time(inst, type, vr[i])) {
            ((double *)values)[k++] = inst->clock.comm_time;
            continue;
        }
        Target t;
        locate(inst, function, vr[i], type, &t);
        if (t.var->on_read && !refreshed) { /* only a read of one of them derives them */
            if (refresh_outputs(inst) != STATUS_OK) return STATUS_ERROR;
            refreshed = 1;
        }
        const char *base = (const char *)inst->data + t.var->offset;
        for (size_t e = t.element; e < t.element + t.count; ++e, ++k) {
            if (type == TYPE_REAL) ((double *)values)[k] = ((const double *)base)[e];
            else if (type == TYPE_INTEGER) ((int *)values)[k] = ((const int *)base)[e];
            else if (inst->api->c_bool) ((bool *)values)[k] = ((const int *)base)[e] != 0;
            else ((int *)values)[k] = ((const int *)base)[e] != 0;
        }
    }
    return STATUS_OK;
}

/* Is this element settable now, and is the value valid?  Logs why not (the
 * element's name is only formatted then: this runs on every set). */
static int accept_value(Instance *inst, const char *function, const ModelVariable *var,
                        size_t element, double value)
{
    enum { FINE, READ_ONLY, FIXED, NOT_FINITE, OUT_OF_RANGE } problem = FINE;
    if (var->causality == CAUSALITY_OUTPUT || var->causality == CAUSALITY_CALCULATED_PARAMETER)
        problem = READ_ONLY;
    else if (var->causality == CAUSALITY_PARAMETER &&
             !(inst->clock.state & inst->api->parameter_states))
        problem = FIXED;
    else if (!isfinite(value))
        problem = NOT_FINITE;
    else if (!in_range(var, value))
        problem = OUT_OF_RANGE;
    if (problem == FINE) return 1;

    char name[64];
    element_name(var, element, name, sizeof name);
    switch (problem) {
    case READ_ONLY:
        instance_log(inst, STATUS_ERROR, "%s: %s is %s and cannot be set", function, name,
                     var->causality == CAUSALITY_OUTPUT ? "an output" : "a calculated parameter");
        break;
    case FIXED:
        instance_log(inst, STATUS_ERROR,
                     "%s: %s is a fixed parameter and cannot be set after initialization "
                     "(state %s)", function, name, inst->api->state_name(inst->clock.state));
        break;
    case NOT_FINITE:
        instance_log(inst, STATUS_ERROR, "%s: %s = %g is not finite; value rejected", function,
                     name, value);
        break;
    default:
        /* Integer bounds in full (2147483647, not 2.14748e+09) */
        instance_log(inst, STATUS_ERROR,
                     var->type == TYPE_REAL ? "%s: %s = %.17g is out of range %s%g, %g%s; value "
                                              "rejected"
                                            : "%s: %s = %.17g is out of range %s%.0f, %.0f%s; "
                                              "value rejected",
                     function, name, value, var->min_exclusive ? "(" : "[", var->min, var->max,
                     var->max_exclusive ? ")" : "]");
    }
    return 0;
}

static double value_at(const Instance *inst, VariableType type, const void *values, size_t k)
{
    if (type == TYPE_REAL) return ((const double *)values)[k];
    if (type == TYPE_INTEGER) return (double)((const int *)values)[k];
    if (inst->api->c_bool) return ((const bool *)values)[k] ? 1.0 : 0.0;
    return ((const int *)values)[k] ? 1.0 : 0.0;
}

Status instance_set(Instance *inst, const char *function, VariableType type,
                    const uint32_t vr[], size_t nvr, const void *values, size_t n_values)
{
    if (check_arrays(inst, function, vr, nvr, values) != STATUS_OK ||
        check_targets(inst, function, type, vr, nvr, n_values) != STATUS_OK)
        return STATUS_ERROR;
    for (int write = 0; write <= 1; ++write) {
        size_t k = 0;
        for (size_t i = 0; i < nvr; ++i) {
            if (is_time(inst, type, vr[i]))
                return instance_fail(inst, "%s: time (value reference 0) is the independent "
                                     "variable and cannot be set", function);
            Target t;
            locate(inst, function, vr[i], type, &t);
            char *base = (char *)inst->data + t.var->offset;
            for (size_t e = t.element; e < t.element + t.count; ++e, ++k) {
                const double value = value_at(inst, type, values, k);
                if (!write) {
                    if (!accept_value(inst, function, t.var, e, value))
                        return instance_escalate(inst, STATUS_ERROR);
                } else if (type == TYPE_REAL) {
                    ((double *)base)[e] = value;
                } else {
                    ((int *)base)[e] = (int)value;
                }
            }
        }
    }
    return STATUS_OK;
}

Status instance_no_variables_of(Instance *inst, const char *function, const char *type,
                                const uint32_t vr[], size_t nvr, const void *values)
{
    if (check_arrays(inst, function, vr, nvr, values) != STATUS_OK) return STATUS_ERROR;
    if (nvr > 0)
        return instance_fail(inst, "%s: unknown value reference %u (this FMU has no %s "
                             "variables)", function, (unsigned)vr[0], type);
    return STATUS_OK;
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
    ModelLogger logger = model_logger(inst);
    ModelStatus status = MD.initialize(inst->data, inst->clock.start_time, &logger);
    if (status == MODEL_ERROR || !outputs_finite(inst, function, 1))
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
    ModelLogger logger = model_logger(inst);
    if (MD.communication_point(inst->data, t_end, &logger) == MODEL_ERROR ||
        !outputs_finite(inst, function, 0))
        return instance_escalate(inst, STATUS_ERROR); /* the clock stays at the last
                                                       * successful step's end */
    clock->steps = k_end;
    clock->comm_time = t_end;
    return STATUS_OK;
}

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
    if (refresh_outputs(inst) != STATUS_OK) return STATUS_ERROR; /* a state holds its outputs */
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
    start_data(inst, fresh);
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
            const double value = element_value(data, var, e);
            const double derived = initialized ? element_value(initialized, var, e) : value;
            char name[64];
            element_name(var, e, name, sizeof name);
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
    ModelLogger logger = model_logger(inst);
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
    if (!data_valid(inst, function, data) || !resource_valid(inst, function, data))
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
