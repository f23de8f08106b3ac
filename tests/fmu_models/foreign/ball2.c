/* A stand-in for another tool's FMI 2.0 model-exchange-only FMU: a ball dropped from h0 that bounces
   with restitution e. Its height is the event indicator (a state event at each impact); a bounce
   slower than v_min leaves the ball lying still, so the impacts do not pile up (no Zeno chatter).
   It can get, set and serialize its FMU state. Functions it does not implement are generated stubs
   (tests/foreign_fmus.py). */
#include <float.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"

/* FMI's states of an instance: a call in a state the standard does not allow it in is an error, so
   a test sees an importer that calls out of order. */
enum { INSTANTIATED, INITIALIZING, EVENT_MODE, CONTINUOUS, TERMINATED };
#define IN(m, allowed) if (!(allowed)) { return fmi2Error; }

typedef struct {
    int mode;
    fmi2Real time;
    fmi2Real h;        /* vr 1, output, state */
    fmi2Real v;        /* vr 3, output, state */
    fmi2Real g;        /* vr 5, parameter */
    fmi2Real e;        /* vr 6, parameter */
    fmi2Real h0;       /* vr 7, parameter: the height it is dropped from */
    fmi2Integer bounces; /* vr 8, output */
    fmi2Boolean lying;
} Model;

static const fmi2Real V_MIN = 0.1;

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation, const fmi2CallbackFunctions *functions,
                              fmi2Boolean visible, fmi2Boolean loggingOn)
{
    Model *m;

    if (fmuType != fmi2ModelExchange || fmuGUID == NULL || strcmp(fmuGUID, "{ball2}") != 0) {
        return NULL;
    }
    m = calloc(1, sizeof *m);
    if (m == NULL) {
        return NULL;
    }
    m->g = 9.81;
    m->e = 0.7;
    m->h0 = 1.0;
    return m;
}

void fmi2FreeInstance(fmi2Component c) { free(c); }

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime)
{
    ((Model *)c)->time = startTime;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c)
{
    Model *m = c;

    IN(m, m->mode == INSTANTIATED);
    m->mode = INITIALIZING;
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c)
{
    Model *m = c;

    IN(m, m->mode == INITIALIZING);
    m->mode = EVENT_MODE;
    m->h = m->h0;
    m->v = 0.0;
    return fmi2OK;
}

fmi2Status fmi2Terminate(fmi2Component c)
{
    Model *m = c;

    IN(m, m->mode == EVENT_MODE || m->mode == CONTINUOUS);
    m->mode = TERMINATED;
    return fmi2OK;
}

fmi2Status fmi2EnterEventMode(fmi2Component c)
{
    Model *m = c;

    IN(m, m->mode == CONTINUOUS);
    m->mode = EVENT_MODE;
    return fmi2OK;
}

fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c)
{
    Model *m = c;

    IN(m, m->mode == EVENT_MODE);
    m->mode = CONTINUOUS;
    return fmi2OK;
}

fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo *info)
{
    Model *m = c;

    IN(m, m->mode == EVENT_MODE);
    memset(info, 0, sizeof *info);
    if (!m->lying && m->h <= 0 && m->v < 0) {
        m->bounces++;
        m->h = DBL_MIN;   /* just above the floor: the indicator leaves zero at once */
        m->v = -m->e * m->v;
        if (m->v < V_MIN) {
            m->lying = fmi2True;
            m->h = 0.0;
            m->v = 0.0;
        }
        info->valuesOfContinuousStatesChanged = fmi2True;
    }
    return fmi2OK;
}

fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi2Boolean *enterEventMode, fmi2Boolean *terminateSimulation)
{
    IN((Model *)c, ((Model *)c)->mode == CONTINUOUS);
    *enterEventMode = fmi2False;
    *terminateSimulation = fmi2False;
    return fmi2OK;
}

fmi2Status fmi2SetTime(fmi2Component c, fmi2Real time)
{
    IN((Model *)c, ((Model *)c)->mode == EVENT_MODE || ((Model *)c)->mode == CONTINUOUS);
    ((Model *)c)->time = time;
    return fmi2OK;
}

fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t nx)
{
    Model *m = c;

    IN(m, m->mode == CONTINUOUS);
    if (nx != 2) {
        return fmi2Error;
    }
    m->h = x[0];
    m->v = x[1];
    return fmi2OK;
}

fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t nx)
{
    Model *m = c;

    if (nx != 2) {
        return fmi2Error;
    }
    x[0] = m->h;
    x[1] = m->v;
    return fmi2OK;
}

fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real dx[], size_t nx)
{
    Model *m = c;

    if (nx != 2) {
        return fmi2Error;
    }
    dx[0] = m->lying ? 0.0 : m->v;
    dx[1] = m->lying ? 0.0 : -m->g;
    return fmi2OK;
}

fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x_nominal[], size_t nx)
{
    size_t i;

    for (i = 0; i < nx; i++) {
        x_nominal[i] = 1.0;
    }
    return fmi2OK;
}

fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real z[], size_t nz)
{
    Model *m = c;

    if (nz != 1) {
        return fmi2Error;
    }
    z[0] = m->lying ? 1.0 : m->h;
    return fmi2OK;
}

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[])
{
    Model *m = c;
    size_t i;

    for (i = 0; i < nvr; i++) {
        switch (vr[i]) {
        case 1: value[i] = m->h; break;
        case 2: value[i] = m->lying ? 0.0 : m->v; break;
        case 3: value[i] = m->v; break;
        case 4: value[i] = m->lying ? 0.0 : -m->g; break;
        case 5: value[i] = m->g; break;
        case 6: value[i] = m->e; break;
        case 7: value[i] = m->h0; break;
        default: return fmi2Error;
        }
    }
    return fmi2OK;
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[])
{
    Model *m = c;
    size_t i;

    IN(m, m->mode == INSTANTIATED || m->mode == INITIALIZING);
    for (i = 0; i < nvr; i++) {
        switch (vr[i]) {
        case 5: m->g = value[i]; break;
        case 6: m->e = value[i]; break;
        case 7: m->h0 = value[i]; break;
        default: return fmi2Error;
        }
    }
    return fmi2OK;
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Integer value[])
{
    Model *m = c;
    size_t i;

    for (i = 0; i < nvr; i++) {
        if (vr[i] != 8) {
            return fmi2Error;
        }
        value[i] = m->bounces;
    }
    return fmi2OK;
}

/* FMU state: the Model struct holds no pointer, so a copy of it is the whole state and its bytes
   the serialized form (a checkpoint test of model exchange needs one FMU that can). */
fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *state)
{
    Model *copy = *state != NULL ? *state : malloc(sizeof *copy);

    if (copy == NULL) {
        return fmi2Error;
    }
    *copy = *(Model *)c;
    *state = copy;
    return fmi2OK;
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate state)
{
    if (state == NULL) {
        return fmi2Error;
    }
    *(Model *)c = *(Model *)state;
    return fmi2OK;
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *state)
{
    free(*state);
    *state = NULL;
    return fmi2OK;
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate state, size_t *size)
{
    *size = sizeof(Model);
    return fmi2OK;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate state, fmi2Byte bytes[], size_t size)
{
    if (size != sizeof(Model)) {
        return fmi2Error;
    }
    memcpy(bytes, state, sizeof(Model));
    return fmi2OK;
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte bytes[], size_t size, fmi2FMUstate *state)
{
    if (size != sizeof(Model)) {
        return fmi2Error;
    }
    if (*state == NULL) {
        *state = malloc(sizeof(Model));
    }
    if (*state == NULL) {
        return fmi2Error;
    }
    memcpy(*state, bytes, sizeof(Model));
    return fmi2OK;
}
