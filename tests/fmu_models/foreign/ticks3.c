/* A stand-in for another tool's FMI 3.0 co-simulation FMU with event mode (hasEventMode): a tick every
   `period` seconds is a time event that only event mode counts. Given early return, doStep stops at a
   tick and says so; a master that handles no events sees `ticks` stay 0. `since` is the time since
   the last tick counted. Functions it does not implement are generated stubs (tests/foreign_fmus.py). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "fmi3Functions.h"

/* FMI's states of an instance: a call in a state the standard does not allow it in is an error, so
   a test sees an importer that calls out of order. */
enum { INSTANTIATED, INITIALIZING, EVENT_MODE, STEP_MODE, TERMINATED };
#define IN(m, allowed) if (!(allowed)) { return fmi3Error; }

typedef struct {
    int mode;
    fmi3Float64 time;
    fmi3Float64 period;   /* vr 1, parameter */
    fmi3Int32 ticks;      /* vr 2, output: ticks counted in event mode */
    fmi3Float64 since;    /* vr 3, output: time since the last tick counted */
    fmi3Float64 last;     /* when the last tick was counted */
    fmi3Boolean eventMode, earlyReturn;
} Model;

fmi3Instance fmi3InstantiateCoSimulation(fmi3String instanceName, fmi3String instantiationToken,
                                         fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn,
                                         fmi3Boolean eventModeUsed, fmi3Boolean earlyReturnAllowed,
                                         const fmi3ValueReference requiredIntermediateVariables[],
                                         size_t nRequiredIntermediateVariables,
                                         fmi3InstanceEnvironment instanceEnvironment,
                                         fmi3LogMessageCallback logMessage,
                                         fmi3IntermediateUpdateCallback intermediateUpdate)
{
    Model *m;

    if (instantiationToken == NULL || strcmp(instantiationToken, "{ticks3}") != 0) {
        return NULL;
    }
    m = calloc(1, sizeof *m);
    if (m == NULL) {
        return NULL;
    }
    m->period = 0.25;
    m->eventMode = eventModeUsed;
    m->earlyReturn = earlyReturnAllowed;
    return m;
}

void fmi3FreeInstance(fmi3Instance instance) { free(instance); }

fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean toleranceDefined, fmi3Float64 tolerance,
                                       fmi3Float64 startTime, fmi3Boolean stopTimeDefined, fmi3Float64 stopTime)
{
    Model *m = instance;

    IN(m, m->mode == INSTANTIATED);
    m->mode = INITIALIZING;
    m->time = m->last = startTime;
    return fmi3OK;
}

static fmi3Status move(Model *m, int from, int from_too, int to)
{
    IN(m, m->mode == from || m->mode == from_too);
    m->mode = to;
    return fmi3OK;
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance instance)
{
    Model *m = instance;

    return move(m, INITIALIZING, INITIALIZING, m->eventMode ? EVENT_MODE : STEP_MODE);
}

fmi3Status fmi3EnterEventMode(fmi3Instance instance)
{
    Model *m = instance;

    IN(m, m->eventMode);
    return move(m, STEP_MODE, STEP_MODE, EVENT_MODE);
}

fmi3Status fmi3EnterStepMode(fmi3Instance instance) { return move(instance, EVENT_MODE, EVENT_MODE, STEP_MODE); }
fmi3Status fmi3Terminate(fmi3Instance instance) { return move(instance, STEP_MODE, EVENT_MODE, TERMINATED); }

/* The next tick after `time` (a tick at `time` itself is due now). */
static fmi3Float64 next_tick(const Model *m)
{
    return (m->ticks + 1) * m->period;
}

fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean *discreteStatesNeedUpdate,
                                    fmi3Boolean *terminateSimulation, fmi3Boolean *nominalsOfContinuousStatesChanged,
                                    fmi3Boolean *valuesOfContinuousStatesChanged, fmi3Boolean *nextEventTimeDefined,
                                    fmi3Float64 *nextEventTime)
{
    Model *m = instance;

    IN(m, m->mode == EVENT_MODE);
    if (m->time >= next_tick(m) - 1e-12) {
        m->ticks++;
        m->last = m->time;
    }
    m->since = m->time - m->last;
    *discreteStatesNeedUpdate = fmi3False;
    *terminateSimulation = fmi3False;
    *nominalsOfContinuousStatesChanged = fmi3False;
    *valuesOfContinuousStatesChanged = fmi3False;
    *nextEventTimeDefined = fmi3True;
    *nextEventTime = next_tick(m);
    return fmi3OK;
}

fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 currentCommunicationPoint, fmi3Float64 communicationStepSize,
                      fmi3Boolean noSetFMUStatePriorToCurrentPoint, fmi3Boolean *eventHandlingNeeded,
                      fmi3Boolean *terminateSimulation, fmi3Boolean *earlyReturn, fmi3Float64 *lastSuccessfulTime)
{
    Model *m = instance;
    fmi3Float64 end = currentCommunicationPoint + communicationStepSize;
    fmi3Float64 tick = next_tick(m);

    IN(m, m->mode == STEP_MODE);
    *terminateSimulation = fmi3False;
    *earlyReturn = fmi3False;
    *eventHandlingNeeded = fmi3False;
    if (m->eventMode && tick <= end + 1e-12) {
        *eventHandlingNeeded = fmi3True;
        if (m->earlyReturn && tick < end - 1e-12) {
            end = tick;
            *earlyReturn = fmi3True;
        }
    }
    m->time = end;
    m->since = m->time - m->last;
    *lastSuccessfulTime = end;
    return fmi3OK;
}

fmi3Status fmi3GetFloat64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3Float64 values[],
                          size_t nValues)
{
    Model *m = instance;
    size_t i;

    for (i = 0; i < nvr; i++) {
        switch (vr[i]) {
        case 0: values[i] = m->time; break;
        case 1: values[i] = m->period; break;
        case 3: values[i] = m->since; break;
        default: return fmi3Error;
        }
    }
    return fmi3OK;
}

fmi3Status fmi3SetFloat64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                          const fmi3Float64 values[], size_t nValues)
{
    size_t i;

    IN((Model *)instance, ((Model *)instance)->mode == INSTANTIATED || ((Model *)instance)->mode == INITIALIZING);
    for (i = 0; i < nvr; i++) {
        if (vr[i] != 1) {
            return fmi3Error;
        }
        ((Model *)instance)->period = values[i];
    }
    return fmi3OK;
}

fmi3Status fmi3GetInt32(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3Int32 values[],
                        size_t nValues)
{
    size_t i;

    for (i = 0; i < nvr; i++) {
        if (vr[i] != 2) {
            return fmi3Error;
        }
        values[i] = ((Model *)instance)->ticks;
    }
    return fmi3OK;
}
