/* What a model's model.c implements and may call; include only this file. */
#ifndef MODEL_H
#define MODEL_H

#include "fixed_time.h"
#include "instance.h"
#include "log.h"
#include "model_description.h"
#include "status.h"
#include "variables.h"

/* The hooks of one model. The framework has already applied the start values,
   zeroed inst->state, and checked every value the importer set against its
   type, causality, min and max. A NULL hook means there is nothing to do. */
typedef struct {
    /* Compute the outputs declared without a start value (initial="calculated")
       from parameters and inputs. Called during initialization whenever the
       importer reads them and once at its end, so it must not have side effects
       beyond those outputs. */
    Status (*initialize)(Instance *inst);

    /* Advance from communication point t to t + h (h >= 0): the inputs hold
       their values at t, the outputs must hold their values at t + h. */
    Status (*step)(Instance *inst, double t, double h);
} ModelHooks;

/* Defined by each model.c. */
extern const ModelHooks MODEL_HOOKS;

#endif
