/* One FMU instance and its life cycle, independent of the FMI version. */
#include <math.h>
#include <stdlib.h>

#include "instance.h"
#include "model.h"
#include "owned_string.h"
#include "variables.h"

/* Communication points are doubles computed by the importer, e.g. as
   start + n * h, so the point it steps from may differ from our t + h in
   the last bits. One nanosecond (relative beyond 1 s) is the clock resolution
   models work with (fixed_time.h). */
#define TIME_TOLERANCE 1e-9

static const char *phase_name(Phase phase)
{
    switch (phase) {
    case PHASE_INSTANTIATED: return "the instantiated state";
    case PHASE_INITIALIZATION: return "initialization mode";
    case PHASE_STEP: return "step mode";
    case PHASE_TERMINATED: return "the terminated state";
    case PHASE_ERROR: return "the error state (after a failed call only get, terminate, reset, free and setting an FMU state work)";
    }
    return "an unknown state";
}

Instance *instance_new(const char *name, LogTarget target, bool logging_on)
{
    Instance *inst = calloc(1, sizeof *inst);

    if (inst == NULL) {
        log_error_to(&target, name, "out of memory allocating the instance");
        return NULL;
    }
    inst->log_target = target;
    log_set_defaults(inst, logging_on);
    inst->name = owned_string_copy(name);
    if (inst->name == NULL) {
        log_error_to(&target, name, "out of memory copying the instance name");
        free(inst);
        return NULL;
    }
    inst->phase = PHASE_INSTANTIATED;
    if (variables_reset(inst) != STATUS_OK) {
        instance_free(inst);
        return NULL;
    }
    return inst;
}

void instance_free(Instance *inst)
{
    if (inst == NULL) {
        return;
    }
    variables_free(inst);
    free(inst->name);
    free(inst);
}

bool instance_allows(Instance *inst, const char *fn, unsigned allowed)
{
    if ((inst->phase & allowed) != 0) {
        return true;
    }
    log_error(inst, "%s: not allowed in %s", fn, phase_name(inst->phase));
    return false;
}

Status instance_reset(Instance *inst)
{
    inst->phase = PHASE_INSTANTIATED;
    inst->start_time = 0.0;
    inst->time = 0.0;
    return variables_reset(inst);
}

Status instance_enter_initialization(Instance *inst, const char *fn, double start_time)
{
    if (!instance_allows(inst, fn, PHASE_INSTANTIATED)) {
        return STATUS_ERROR;
    }
    if (!isfinite(start_time)) {
        return log_error(inst, "%s: start time %g is not finite", fn, start_time);
    }
    inst->start_time = start_time;
    inst->time = start_time;
    inst->phase = PHASE_INITIALIZATION;
    return STATUS_OK;
}

Status instance_update_initial_unknowns(Instance *inst, const char *fn)
{
    if (!instance_allows(inst, fn, PHASE_INITIALIZATION)) {
        return STATUS_ERROR;
    }
    return MODEL_HOOKS.initialize != NULL ? MODEL_HOOKS.initialize(inst) : STATUS_OK;
}

Status instance_exit_initialization(Instance *inst, const char *fn)
{
    Status status = instance_update_initial_unknowns(inst, fn);

    if (status <= STATUS_WARNING) {
        inst->phase = PHASE_STEP;
    }
    return status;
}

Status instance_do_step(Instance *inst, const char *fn, double t, double h)
{
    Status status;

    if (!instance_allows(inst, fn, PHASE_STEP)) {
        return STATUS_ERROR;
    }
    if (!isfinite(t) || !isfinite(h) || h < 0.0) {
        return log_error(inst, "%s: step from t = %g by h = %g: both must be finite and h >= 0", fn, t, h);
    }
    if (fabs(t - inst->time) > TIME_TOLERANCE * fmax(1.0, fabs(t))) {
        return log_error(inst, "%s: step from t = %.17g but the instance is at t = %.17g", fn, t, inst->time);
    }
    status = MODEL_HOOKS.step(inst, t, h);
    if (status <= STATUS_WARNING) {
        inst->time = t + h;
    }
    return status;
}

Status instance_terminate(Instance *inst, const char *fn)
{
    if (!instance_allows(inst, fn, PHASE_STEP | PHASE_ERROR)) {
        return STATUS_ERROR;
    }
    inst->phase = PHASE_TERMINATED;
    return STATUS_OK;
}
