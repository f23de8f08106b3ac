/* Logging through the importer's callback, filtered by the FMU's log categories. */
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "instance.h"
#include "log.h"

/* Long enough for every message the framework writes; longer ones are cut, not overrun. */
#define MESSAGE_SIZE 512

static void deliver(const LogTarget *target, const char *instance_name, Status status, LogCategory category,
                    const char *format, va_list args)
{
    char message[MESSAGE_SIZE];

    if (target->deliver == NULL) {
        return;
    }
    vsnprintf(message, sizeof message, format, args);
    target->deliver(target, instance_name, status, LOG_CATEGORY_NAMES[category], message);
}

void log_error_to(const LogTarget *target, const char *instance_name, const char *format, ...)
{
    va_list args;

    va_start(args, format);
    deliver(target, instance_name, STATUS_ERROR, LOG_STATUS_ERROR, format, args);
    va_end(args);
}

Status log_error(const Instance *inst, const char *format, ...)
{
    va_list args;

    if (inst->log_enabled[LOG_STATUS_ERROR]) {
        va_start(args, format);
        deliver(&inst->log_target, inst->name, STATUS_ERROR, LOG_STATUS_ERROR, format, args);
        va_end(args);
    }
    return STATUS_ERROR;
}

void log_event(const Instance *inst, const char *format, ...)
{
    va_list args;

    if (!inst->log_enabled[LOG_EVENTS]) {
        return;
    }
    va_start(args, format);
    deliver(&inst->log_target, inst->name, STATUS_OK, LOG_EVENTS, format, args);
    va_end(args);
}

void log_set_defaults(Instance *inst, bool logging_on)
{
    size_t i;

    for (i = 0; i < LOG_CATEGORY_COUNT; i++) {
        inst->log_enabled[i] = logging_on;
    }
    /* An importer that did not ask for debug logging still needs to learn
       why a call failed. */
    inst->log_enabled[LOG_STATUS_WARNING] = true;
    inst->log_enabled[LOG_STATUS_DISCARD] = true;
    inst->log_enabled[LOG_STATUS_ERROR] = true;
    inst->log_enabled[LOG_STATUS_FATAL] = true;
}

Status log_configure(Instance *inst, const char *fn, bool logging_on, size_t n, const char *const categories[])
{
    bool requested[LOG_CATEGORY_COUNT] = {false};
    size_t i, c;

    if (n > 0 && categories == NULL) {
        return log_error(inst, "%s: %zu categories announced but the array is NULL", fn, n);
    }
    /* Check every name before changing anything, so a bad call changes nothing. */
    for (i = 0; i < n; i++) {
        for (c = 0; c < LOG_CATEGORY_COUNT; c++) {
            if (categories[i] != NULL && strcmp(categories[i], LOG_CATEGORY_NAMES[c]) == 0) {
                break;
            }
        }
        if (c == LOG_CATEGORY_COUNT) {
            return log_error(inst, "%s: unknown log category '%s' (see LogCategories in modelDescription.xml)",
                             fn, categories[i] != NULL ? categories[i] : "(null)");
        }
        requested[c] = true;
    }
    for (c = 0; c < LOG_CATEGORY_COUNT; c++) {
        if (n == 0 || requested[c]) {
            inst->log_enabled[c] = logging_on;
        }
    }
    return STATUS_OK;
}
