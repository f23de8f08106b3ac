/* Belt drive: the speed follows its target (setpoint while running, 0 when
   stopped) with at most `ramp` of change per second. */
#include <math.h>

#include "model.h"

/* Repeated additions of ramp * h leave the speed a few ulps short of the
   setpoint; without this relative slack it would arrive one step late. */
#define ARRIVAL_SLACK 1e-9

static Status initialize(Instance *inst)
{
    inst->var.running = inst->var.speed != 0.0;
    return STATUS_OK;
}

static Status step(Instance *inst, double t, double h)
{
    ModelVariables *v = &inst->var;
    const double target = v->run ? v->speed_setpoint : 0.0;
    const double gap = target - v->speed;
    const double max_change = v->ramp * h;

    if (gap == 0.0) {
        return STATUS_OK;
    }
    if (v->ramp == 0.0 || fabs(gap) <= max_change * (1.0 + ARRIVAL_SLACK)) {
        v->speed = target;
        log_event(inst, "speed reached %g m/s at t = %g s", target, t + h);
    } else {
        v->speed += gap > 0.0 ? max_change : -max_change;
    }
    v->running = v->speed != 0.0;
    return STATUS_OK;
}

const ModelHooks MODEL_HOOKS = {.initialize = initialize, .step = step};
