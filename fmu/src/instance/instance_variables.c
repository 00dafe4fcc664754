/* The instance core's variables: getters and setters by value reference, the
 * ranges they enforce and the finiteness of every output. */
#if defined(__MINGW32__) && !defined(__USE_MINGW_ANSI_STDIO)
#define __USE_MINGW_ANSI_STDIO 1 /* C99 printf (%zu) on Windows too */
#endif
#include "instance_internal.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

/* ---- variables ------------------------------------------------------------ */

static const char *type_name(VariableType type)
{
    return type == TYPE_REAL ? "Real" : type == TYPE_INTEGER ? "Integer" : "Boolean";
}

/* The structured name of one element, e.g. theta_hat[1,3]. */
void instance_element_name(const ModelVariable *var, size_t element, char *out, size_t size)
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
double instance_element_value(const void *data, const ModelVariable *var, size_t element)
{
    const char *base = (const char *)data + var->offset;
    return var->type == TYPE_REAL ? ((const double *)base)[element]
                                  : (double)((const int *)base)[element];
}

/* An OK status never comes with a non-finite output: checks every Real output
 * (and, at initialization, calculated parameter); logs the first offender.
 * The usual case costs one multiply-add per output: x * 0 is NaN for inf and NaN. */
int instance_outputs_finite(const Instance *inst, const char *function, int with_calculated)
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
        if (!instance_is_checked_output(var, with_calculated)) continue;
        const double *values = (const double *)((const char *)inst->data + var->offset);
        for (size_t e = 0; e < model_variable_count(var); ++e) {
            if (!isfinite(values[e])) {
                char name[64];
                instance_element_name(var, e, name, sizeof name);
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
int instance_data_valid(const Instance *inst, const char *function, const void *data)
{
    for (size_t v = 0; v < MD.n_variables; ++v) {
        const ModelVariable *var = &MD.variables[v];
        if (var->causality != CAUSALITY_PARAMETER && var->causality != CAUSALITY_INPUT) continue;
        for (size_t e = 0; e < model_variable_count(var); ++e) {
            const double value = instance_element_value(data, var, e);
            if (var->type == TYPE_BOOLEAN ? value != 0.0 && value != 1.0 : !in_range(var, value)) {
                char name[64];
                instance_element_name(var, e, name, sizeof name);
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
        instance_element_name(var, target->element, name, sizeof name);
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
Status instance_refresh_outputs(Instance *inst)
{
    if (!MD.refresh_outputs) return STATUS_OK;
    ModelLogger logger = instance_model_logger(inst);
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
            if (instance_refresh_outputs(inst) != STATUS_OK) return STATUS_ERROR;
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
    instance_element_name(var, element, name, sizeof name);
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
