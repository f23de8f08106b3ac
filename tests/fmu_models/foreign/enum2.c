/* A stand-in for another tool's FMI 2.0 co-simulation FMU with an Enumeration input whose legal values
   are 1..3 (start 1): 0, what a master that writes zeros to unfed inputs sends, is refused as an
   exporter's FMU refuses it. Functions it does not implement are generated stubs (tests/foreign_fmus.py). */
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"

typedef struct {
    fmi2CallbackFunctions callbacks;
    fmi2String name;
    fmi2Integer mode;      /* vr 1, Enumeration Mode: 1 slow, 2 fast, 3 stop */
    fmi2Integer level;     /* vr 2, output: 10 * mode after each step */
    fmi2Integer threshold; /* vr 3, parameter, 0..100 */
    fmi2Boolean above;     /* vr 4, output: level > threshold */
} Model;

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation, const fmi2CallbackFunctions *functions,
                              fmi2Boolean visible, fmi2Boolean loggingOn)
{
    Model *m;

    if (fmuType != fmi2CoSimulation || fmuGUID == NULL || strcmp(fmuGUID, "{enum2}") != 0) {
        return NULL;
    }
    m = calloc(1, sizeof *m);
    if (m == NULL) {
        return NULL;
    }
    m->callbacks = *functions;
    m->name = instanceName;
    m->mode = 1;
    m->threshold = 5;
    return m;
}

void fmi2FreeInstance(fmi2Component c) { free(c); }

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime)
{
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) { return fmi2OK; }
fmi2Status fmi2ExitInitializationMode(fmi2Component c) { return fmi2OK; }
fmi2Status fmi2Terminate(fmi2Component c) { return fmi2OK; }

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint, fmi2Real communicationStepSize,
                      fmi2Boolean noSetFMUStatePriorToCurrentCommunicationPoint)
{
    Model *m = c;

    m->level = 10 * m->mode;
    m->above = m->level > m->threshold;
    return fmi2OK;
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Integer value[])
{
    Model *m = c;
    size_t i;

    for (i = 0; i < nvr; i++) {
        switch (vr[i]) {
        case 1: value[i] = m->mode; break;
        case 2: value[i] = m->level; break;
        case 3: value[i] = m->threshold; break;
        default: return fmi2Error;
        }
    }
    return fmi2OK;
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Integer value[])
{
    Model *m = c;
    size_t i;

    for (i = 0; i < nvr; i++) {
        if (vr[i] == 1 && (value[i] < 1 || value[i] > 3)) {
            m->callbacks.logger(m->callbacks.componentEnvironment, m->name, fmi2Error, "logStatusError",
                                "%d is not a legal value for mode", (int)value[i]);
            return fmi2Error;
        }
        if (vr[i] == 1) {
            m->mode = value[i];
        } else if (vr[i] == 3) {
            m->threshold = value[i];
        } else {
            return fmi2Error;
        }
    }
    return fmi2OK;
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Boolean value[])
{
    Model *m = c;
    size_t i;

    for (i = 0; i < nvr; i++) {
        if (vr[i] != 4) {
            return fmi2Error;
        }
        value[i] = m->above;
    }
    return fmi2OK;
}
