/* Test-only model: a step counter whose doStep fails, crashes, hangs or outputs NaN on request. */
#include <math.h>
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
    if (inst->var.steps + 1 == inst->var.hang_at) {
        for (volatile int spin = 0;; spin++) {   /* what a deadlocked FMU does: never return */
        }
    }
    inst->var.steps += 1;
    inst->var.level = (inst->var.nan_at >= 0 && inst->var.steps >= inst->var.nan_at) ? NAN : 0.1 * inst->var.steps;
    return STATUS_OK;
}

const ModelHooks MODEL_HOOKS = {.initialize = NULL, .step = step};
