/* Test-only model: a step counter whose doStep fails or crashes on request. */
#include <signal.h>

#include "model.h"

static Status step(Instance *inst, double t, double h)
{
    (void)h;
    if (inst->var.fail) {
        return log_error(inst, "faulty: asked to fail at t = %g s after %d steps", t, (int)inst->var.steps);
    }
    if (inst->var.steps + 1 == inst->var.crash_at) {
        raise(SIGSEGV);   /* what a buggy FMU does to the process that loaded it */
    }
    inst->var.steps += 1;
    return STATUS_OK;
}

const ModelHooks MODEL_HOOKS = {.initialize = NULL, .step = step};
