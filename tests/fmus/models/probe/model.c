/* Test-only model: every variable type and every set rule of the framework. */
#include <stdio.h>

#include "model.h"

static Status greet(Instance *inst)
{
    char text[64];

    /* Truncation is fine for a test model; snprintf never overruns. */
    snprintf(text, sizeof text, "hello %s", inst->var.label);
    return variable_store_string(inst, VR_GREETING, text);
}

static Status step(Instance *inst, double t, double h)
{
    (void)t;
    (void)h;
    inst->var.y = inst->var.gain * inst->var.x;
    if (inst->var.enable && inst->var.count < inst->var.limit) {
        inst->var.count++;
    }
    return greet(inst);
}

const ModelHooks MODEL_HOOKS = {.initialize = greet, .step = step};
