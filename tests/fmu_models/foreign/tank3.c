/* A stand-in for another tool's FMI 3.0 model-exchange-only FMU: a tank's level fed by an inflow and
   drained through an outlet (time constant tau) until the outlet closes at t_close (a time event);
   `full` turns true when the level rises above `threshold` (a state event); `latest` is the latest
   time the importer set, so a test sees whether the equations were evaluated past a point. Functions it does not
   implement are generated stubs (tests/foreign_fmus.py). */
#include <stdlib.h>
#include <string.h>

#include "fmi3Functions.h"

/* FMI's states of an instance: a call in a state the standard does not allow it in is an error, so
   a test sees an importer that calls out of order. */
enum { INSTANTIATED, INITIALIZING, EVENT_MODE, CONTINUOUS, TERMINATED };
#define IN(m, allowed) if (!(allowed)) { return fmi3Error; }

typedef struct {
    int mode;
    fmi3Float64 time;
    fmi3Float64 inflow;    /* vr 1, input, m/s of level */
    fmi3Float64 level;     /* vr 2, output, state, m */
    fmi3Float64 tau;       /* vr 4, parameter, s */
    fmi3Float64 threshold; /* vr 5, parameter, m */
    fmi3Float64 t_close;   /* vr 6, parameter, s */
    fmi3Boolean full;      /* vr 7, output */
    fmi3Float64 latest;    /* vr 8, output: the latest time the importer set, so a test sees how far it integrated */
    fmi3Boolean closed;
} Model;

fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName, fmi3String instantiationToken,
                                          fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn,
                                          fmi3InstanceEnvironment instanceEnvironment,
                                          fmi3LogMessageCallback logMessage)
{
    Model *m;

    if (instantiationToken == NULL || strcmp(instantiationToken, "{tank3}") != 0) {
        return NULL;
    }
    m = calloc(1, sizeof *m);
    if (m == NULL) {
        return NULL;
    }
    m->tau = 2.0;
    m->threshold = 0.15;
    m->t_close = 3.0;
    return m;
}

void fmi3FreeInstance(fmi3Instance instance) { free(instance); }

fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean toleranceDefined, fmi3Float64 tolerance,
                                       fmi3Float64 startTime, fmi3Boolean stopTimeDefined, fmi3Float64 stopTime)
{
    Model *m = instance;

    IN(m, m->mode == INSTANTIATED);
    m->mode = INITIALIZING;
    m->time = startTime;
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
    return move(instance, INITIALIZING, INITIALIZING, EVENT_MODE);
}

fmi3Status fmi3Terminate(fmi3Instance instance) { return move(instance, EVENT_MODE, CONTINUOUS, TERMINATED); }
fmi3Status fmi3EnterEventMode(fmi3Instance instance) { return move(instance, CONTINUOUS, CONTINUOUS, EVENT_MODE); }

fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance instance)
{
    return move(instance, EVENT_MODE, EVENT_MODE, CONTINUOUS);
}

fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean *discreteStatesNeedUpdate,
                                    fmi3Boolean *terminateSimulation, fmi3Boolean *nominalsOfContinuousStatesChanged,
                                    fmi3Boolean *valuesOfContinuousStatesChanged, fmi3Boolean *nextEventTimeDefined,
                                    fmi3Float64 *nextEventTime)
{
    Model *m = instance;

    IN(m, m->mode == EVENT_MODE);
    m->full = m->level > m->threshold;
    m->closed = m->time >= m->t_close;
    *discreteStatesNeedUpdate = fmi3False;
    *terminateSimulation = fmi3False;
    *nominalsOfContinuousStatesChanged = fmi3False;
    *valuesOfContinuousStatesChanged = fmi3False;
    *nextEventTimeDefined = !m->closed;
    *nextEventTime = m->t_close;
    return fmi3OK;
}

fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi3Boolean *enterEventMode, fmi3Boolean *terminateSimulation)
{
    IN((Model *)instance, ((Model *)instance)->mode == CONTINUOUS);
    *enterEventMode = fmi3False;
    *terminateSimulation = fmi3False;
    return fmi3OK;
}

fmi3Status fmi3SetTime(fmi3Instance instance, fmi3Float64 time)
{
    Model *m = instance;

    IN(m, m->mode == CONTINUOUS);
    m->time = time;
    if (time > m->latest) {
        m->latest = time;
    }
    return fmi3OK;
}

fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t *n)
{
    *n = 1;
    return fmi3OK;
}

fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t *n)
{
    *n = 1;
    return fmi3OK;
}

fmi3Status fmi3SetContinuousStates(fmi3Instance instance, const fmi3Float64 x[], size_t nx)
{
    IN((Model *)instance, ((Model *)instance)->mode == CONTINUOUS);
    if (nx != 1) {
        return fmi3Error;
    }
    ((Model *)instance)->level = x[0];
    return fmi3OK;
}

fmi3Status fmi3GetContinuousStates(fmi3Instance instance, fmi3Float64 x[], size_t nx)
{
    if (nx != 1) {
        return fmi3Error;
    }
    x[0] = ((Model *)instance)->level;
    return fmi3OK;
}

static fmi3Float64 derivative(const Model *m)
{
    return m->inflow - (m->closed ? 0.0 : m->level / m->tau);
}

fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance instance, fmi3Float64 dx[], size_t nx)
{
    if (nx != 1) {
        return fmi3Error;
    }
    dx[0] = derivative(instance);
    return fmi3OK;
}

fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance instance, fmi3Float64 nominals[], size_t nx)
{
    if (nx != 1) {
        return fmi3Error;
    }
    nominals[0] = 1.0;
    return fmi3OK;
}

fmi3Status fmi3GetEventIndicators(fmi3Instance instance, fmi3Float64 z[], size_t nz)
{
    Model *m = instance;

    if (nz != 1) {
        return fmi3Error;
    }
    z[0] = m->level - m->threshold;
    return fmi3OK;
}

fmi3Status fmi3GetFloat64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3Float64 values[],
                          size_t nValues)
{
    Model *m = instance;
    size_t i;

    if (nValues != nvr) {
        return fmi3Error;
    }
    for (i = 0; i < nvr; i++) {
        switch (vr[i]) {
        case 0: values[i] = m->time; break;
        case 1: values[i] = m->inflow; break;
        case 2: values[i] = m->level; break;
        case 3: values[i] = derivative(m); break;
        case 4: values[i] = m->tau; break;
        case 5: values[i] = m->threshold; break;
        case 6: values[i] = m->t_close; break;
        case 8: values[i] = m->latest; break;
        default: return fmi3Error;
        }
    }
    return fmi3OK;
}

fmi3Status fmi3SetFloat64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                          const fmi3Float64 values[], size_t nValues)
{
    Model *m = instance;
    size_t i;

    if (nValues != nvr) {
        return fmi3Error;
    }
    for (i = 0; i < nvr; i++) {
        int tuning = m->mode == INSTANTIATED || m->mode == INITIALIZING;

        switch (vr[i]) {
        case 1: IN(m, m->mode != TERMINATED); m->inflow = values[i]; break;
        case 4: IN(m, tuning); m->tau = values[i]; break;
        case 5: IN(m, tuning); m->threshold = values[i]; break;
        case 6: IN(m, tuning); m->t_close = values[i]; break;
        default: return fmi3Error;
        }
    }
    return fmi3OK;
}

fmi3Status fmi3GetBoolean(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3Boolean values[],
                          size_t nValues)
{
    size_t i;

    for (i = 0; i < nvr; i++) {
        if (vr[i] != 7) {
            return fmi3Error;
        }
        values[i] = ((Model *)instance)->full;
    }
    return fmi3OK;
}
