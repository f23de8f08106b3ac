/* Test-only model: a step counter whose doStep fails on request. */
#include "model.h"

static Status step(Instance *inst, double t, double h)
{
    (void)h;
    if (inst->var.fail) {
        return log_error(inst, "faulty: asked to fail at t = %g s after %d steps", t, (int)inst->var.steps);
    }
    inst->var.steps += 1;
    return STATUS_OK;
}

const ModelHooks MODEL_HOOKS = {.initialize = NULL, .step = step};
