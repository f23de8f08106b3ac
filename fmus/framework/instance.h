/* One FMU instance and its life cycle, independent of the FMI version. */
#ifndef INSTANCE_H
#define INSTANCE_H

#include <stdbool.h>

#include "log.h"
#include "model_description.h"
#include "status.h"

/* Bit flags, so that a call can name every phase it is allowed in. */
typedef enum {
    PHASE_INSTANTIATED = 1,
    PHASE_INITIALIZATION = 2,
    PHASE_STEP = 4,
    PHASE_TERMINATED = 8,
    PHASE_ERROR = 16 /* a call returned error; only get, terminate, reset, free and set FMU state remain */
} Phase;

/* Everything one instance owns; nothing lives in globals, so instances in one
   process are independent. */
typedef struct Instance {
    char *name;
    LogTarget log_target;
    bool log_enabled[LOG_CATEGORY_COUNT];
    Phase phase;
    double start_time;
    double time; /* the communication point the instance has reached */
    ModelVariables var;
    ModelState state;
} Instance;

/* NULL if out of memory or the start values cannot be applied (reported through target). */
Instance *instance_new(const char *name, LogTarget target, bool logging_on);
void instance_free(Instance *inst);

/* Log an error naming fn unless inst is in one of the allowed phases. */
bool instance_allows(Instance *inst, const char *fn, unsigned allowed);

/* fmi2Reset / fmi3Reset: back to the state right after instantiation. */
Status instance_reset(Instance *inst);

Status instance_enter_initialization(Instance *inst, const char *fn, double start_time);

/* Compute the initial unknowns (outputs with initial="calculated") from the
   current parameters and inputs; importers may get them during initialization. */
Status instance_update_initial_unknowns(Instance *inst, const char *fn);

Status instance_exit_initialization(Instance *inst, const char *fn);
Status instance_do_step(Instance *inst, const char *fn, double t, double h);
Status instance_terminate(Instance *inst, const char *fn);

#endif
