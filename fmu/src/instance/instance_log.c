/* The instance core's messages: to the importer's logger through the API file's
 * sink, and the logger a model's hooks write through. */
#if defined(__MINGW32__) && !defined(__USE_MINGW_ANSI_STDIO)
#define __USE_MINGW_ANSI_STDIO 1 /* C99 printf (%zu) on Windows too */
#endif
#include "instance_internal.h"

#include <stdarg.h>
#include <stdio.h>
#include <string.h>

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

ModelLogger instance_model_logger(Instance *inst)
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
