/* A stand-in for another tool's FMI 3.0 co-simulation FMU: an Int32 `counter` that goes up by
   `increment` at every whole `period` of time, the raw counts of an analogue input card. The
   functions it does not implement are generated stubs (tests/foreign_fmus.py). Value references:
   see stair.xml. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "fmi3Functions.h"

typedef struct {
    fmi3LogMessageCallback log;
    fmi3InstanceEnvironment env;
    double time;
    fmi3Int32 counter;    /* 1 */
    double period;        /* 2 */
    fmi3Int32 increment;  /* 3 */
    long long steps;      /* whole periods counted so far */
} Model;

static fmi3Status fail(Model *m, const char *text)
{
    if (m->log != NULL) {
        m->log(m->env, fmi3Error, "logStatusError", text);
    }
    return fmi3Error;
}

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

    if (instantiationToken == NULL || strcmp(instantiationToken, "{stair}") != 0 || eventModeUsed) {
        return NULL;
    }
    m = calloc(1, sizeof *m);
    if (m == NULL) {
        return NULL;
    }
    m->log = logMessage;
    m->env = instanceEnvironment;
    m->period = 1.0;
    m->increment = 1;
    return m;
}

void fmi3FreeInstance(fmi3Instance instance) { free(instance); }

fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean toleranceDefined, fmi3Float64 tolerance,
                                       fmi3Float64 startTime, fmi3Boolean stopTimeDefined, fmi3Float64 stopTime)
{
    ((Model *)instance)->time = startTime;
    return fmi3OK;
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance instance) { return fmi3OK; }
fmi3Status fmi3Terminate(fmi3Instance instance) { return fmi3OK; }

fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 currentCommunicationPoint, fmi3Float64 communicationStepSize,
                      fmi3Boolean noSetFMUStatePriorToCurrentPoint, fmi3Boolean *eventHandlingNeeded,
                      fmi3Boolean *terminateSimulation, fmi3Boolean *earlyReturn, fmi3Float64 *lastSuccessfulTime)
{
    Model *m = instance;
    double end = currentCommunicationPoint + communicationStepSize;

    /* A step's end that a sum of tick times leaves a hair short of a period's end still counts it,
       as a time event at that instant would. */
    while (end >= (double)(m->steps + 1) * m->period - 1e-9 * m->period) {
        m->steps++;
        m->counter += m->increment;
    }
    m->time = end;
    *eventHandlingNeeded = fmi3False;
    *terminateSimulation = fmi3False;
    *earlyReturn = fmi3False;
    *lastSuccessfulTime = end;
    return fmi3OK;
}

fmi3Status fmi3GetFloat64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3Float64 values[],
                          size_t nValues)
{
    Model *m = instance;
    size_t i;

    if (nValues < nvr) {
        return fail(m, "fmi3GetFloat64: too few values");
    }
    for (i = 0; i < nvr; i++) {
        switch (vr[i]) {
        case 0: values[i] = m->time; break;
        case 2: values[i] = m->period; break;
        default: return fail(m, "fmi3GetFloat64: no such Float64 variable");
        }
    }
    return fmi3OK;
}

fmi3Status fmi3SetFloat64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                          const fmi3Float64 values[], size_t nValues)
{
    Model *m = instance;
    size_t i;

    if (nValues < nvr) {
        return fail(m, "fmi3SetFloat64: too few values");
    }
    for (i = 0; i < nvr; i++) {
        if (vr[i] != 2) {
            return fail(m, "fmi3SetFloat64: only period can be set");
        }
        if (!(values[i] >= 1e-6) || !isfinite(values[i])) {
            return fail(m, "period must be a finite number of at least 1e-6 s");
        }
        m->period = values[i];
    }
    return fmi3OK;
}

fmi3Status fmi3GetInt32(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3Int32 values[],
                        size_t nValues)
{
    Model *m = instance;
    size_t i;

    if (nValues < nvr) {
        return fail(m, "fmi3GetInt32: too few values");
    }
    for (i = 0; i < nvr; i++) {
        switch (vr[i]) {
        case 1: values[i] = m->counter; break;
        case 3: values[i] = m->increment; break;
        default: return fail(m, "fmi3GetInt32: no such Int32 variable");
        }
    }
    return fmi3OK;
}

fmi3Status fmi3SetInt32(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, const fmi3Int32 values[],
                        size_t nValues)
{
    Model *m = instance;
    size_t i;

    if (nValues < nvr) {
        return fail(m, "fmi3SetInt32: too few values");
    }
    for (i = 0; i < nvr; i++) {
        if (vr[i] != 3) {
            return fail(m, "fmi3SetInt32: only increment can be set");
        }
        m->increment = values[i];
    }
    return fmi3OK;
}
