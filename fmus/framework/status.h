/* Outcome of a framework call; the FMI bindings map it onto fmi2Status / fmi3Status. */
#ifndef STATUS_H
#define STATUS_H

/* Ordered by severity so that the worse of two outcomes is the larger one. */
typedef enum {
    STATUS_OK,
    STATUS_WARNING,
    STATUS_DISCARD,
    STATUS_ERROR,
    STATUS_FATAL
} Status;

#endif
