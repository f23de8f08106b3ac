/* Logging through the importer's callback, filtered by the FMU's log categories. */
#ifndef LOG_H
#define LOG_H

#include <stdbool.h>
#include <stddef.h>

#include "model_description.h"
#include "status.h"

#if defined(__GNUC__)
#define PRINTF_LIKE(format_index, first_arg) __attribute__((format(printf, format_index, first_arg)))
#else
#define PRINTF_LIKE(format_index, first_arg)
#endif

struct Instance;

/* Where messages go. Each FMI binding fills it with its own deliver function
   and the importer's callback, so that this file knows no FMI types. */
typedef struct LogTarget {
    void (*deliver)(const struct LogTarget *target, const char *instance_name, Status status,
                    const char *category, const char *message);
    /* The importer's logger, type-erased; deliver converts it back, which
       C99 6.3.2.3p8 guarantees to give the original pointer. */
    void (*callback)(void);
    void *environment; /* the importer's componentEnvironment / instanceEnvironment */
} LogTarget;

/* An error before there is an instance to hold the log settings (instantiation). */
void log_error_to(const LogTarget *target, const char *instance_name, const char *format, ...) PRINTF_LIKE(3, 4);

/* Log under logStatusError and return STATUS_ERROR, for `return log_error(...)`. */
Status log_error(const struct Instance *inst, const char *format, ...) PRINTF_LIKE(2, 3);

/* Log a model event under logEvents. */
void log_event(const struct Instance *inst, const char *format, ...) PRINTF_LIKE(2, 3);

/* Status categories on, logEvents only if the importer asked for logging. */
void log_set_defaults(struct Instance *inst, bool logging_on);

/* fmiXSetDebugLogging: n == 0 switches every category, otherwise only the named ones. */
Status log_configure(struct Instance *inst, const char *fn, bool logging_on, size_t n,
                     const char *const categories[]);

#endif
