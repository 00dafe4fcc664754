/* What the instance core's files share beyond instance.h: instance.c (lifecycle,
 * start values, clock and stepping), instance_log.c (messages), instance_variables.c
 * (getters, setters and their checks) and instance_states.c (FMU states and their
 * serialization).  Not part of the core's interface to the API files. */
#ifndef INSTANCE_INTERNAL_H
#define INSTANCE_INTERNAL_H

#include "instance.h"

#define MD MODEL_DESCRIPTOR

/* ---- instance_log.c ---- */
/* The logger a model's hooks write through. */
ModelLogger instance_model_logger(Instance *inst);

/* ---- instance.c ---- */
/* A data block at its start: the start values and the instance's resource region. */
void instance_start_data(const Instance *inst, void *data);
/* A restored block must hold this instance's resource region. */
int instance_resource_valid(const Instance *inst, const char *function, const unsigned char *data);

/* ---- instance_variables.c ---- */
/* with_calculated: at initialization, where every output is derived */
int instance_is_checked_output(const ModelVariable *var, int with_calculated);
/* An OK status never comes with a non-finite output (logs the first offender). */
int instance_outputs_finite(const Instance *inst, const char *function, int with_calculated);
/* The outputs the model derives when read (ModelDescriptor.refresh_outputs). */
Status instance_refresh_outputs(Instance *inst);
/* The structured name of one element, e.g. theta_hat[1,3]. */
void instance_element_name(const ModelVariable *var, size_t element, char *out, size_t size);
/* The value of one element of a data block, as a double. */
double instance_element_value(const void *data, const ModelVariable *var, size_t element);
/* Every parameter and input of a restored block inside its range (logs the first
 * offender). */
int instance_data_valid(const Instance *inst, const char *function, const void *data);

#endif
