/* A stand-in for another tool's FMI 3.0 co-simulation FMU: a variable of every kind the hub maps
   (Enumeration, Float32, UInt16, Int64, Int8, Binary, arrays, a structural parameter), checked as
   an exporter's FMU would check them. The functions it does not implement are generated stubs
   (tests/foreign_fmus.py). Value references: see typed3.xml. */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi3Functions.h"

#define BLOB_MAX 16

typedef struct {
    fmi3LogMessageCallback log;
    fmi3InstanceEnvironment env;
    double time;
    int initializing;
    fmi3Int64 mode;              /* 1 Enumeration, items 1..3 */
    fmi3Float32 gain32, x32, y32; /* 2, 3, 4 */
    fmi3UInt16 count16, limit16;  /* 5, 6 */
    fmi3Int64 big64, big64_out;   /* 7, 8 */
    fmi3Byte blob[BLOB_MAX];      /* 10 */
    size_t blob_size;
    fmi3Byte blob_out[BLOB_MAX];  /* 11 */
    size_t blob_out_size;
    double u[3], A[4], v[2];      /* 13, 14, 15 */
    fmi3UInt64 twice64;           /* 16: 2 * big64 in unsigned 64-bit arithmetic: wraps for a negative big64 */
} Model;

static fmi3Status fail(Model *m, const char *format, ...)
{
    char text[256];
    va_list args;

    va_start(args, format);
    vsnprintf(text, sizeof text, format, args);
    va_end(args);
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

    if (instantiationToken == NULL || strcmp(instantiationToken, "{typed3}") != 0 || eventModeUsed) {
        return NULL;
    }
    m = calloc(1, sizeof *m);
    if (m == NULL) {
        return NULL;
    }
    m->log = logMessage;
    m->env = instanceEnvironment;
    m->mode = 1;
    m->gain32 = 1.5f;
    m->count16 = 7;
    m->limit16 = 1000;
    m->blob[0] = 1;
    m->blob[1] = 2;
    m->blob_size = 2;
    m->blob_out_size = 0;
    m->u[0] = 1.0; m->u[1] = 2.0; m->u[2] = 3.0;
    m->A[0] = 1.0; m->A[3] = 1.0;
    return m;
}

void fmi3FreeInstance(fmi3Instance instance) { free(instance); }

fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean toleranceDefined, fmi3Float64 tolerance,
                                       fmi3Float64 startTime, fmi3Boolean stopTimeDefined, fmi3Float64 stopTime)
{
    ((Model *)instance)->time = startTime;
    ((Model *)instance)->initializing = 1;
    return fmi3OK;
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance instance)
{
    ((Model *)instance)->initializing = 0;
    return fmi3OK;
}

fmi3Status fmi3Terminate(fmi3Instance instance) { return fmi3OK; }

fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 currentCommunicationPoint, fmi3Float64 communicationStepSize,
                      fmi3Boolean noSetFMUStatePriorToCurrentPoint, fmi3Boolean *eventHandlingNeeded,
                      fmi3Boolean *terminateSimulation, fmi3Boolean *earlyReturn, fmi3Float64 *lastSuccessfulTime)
{
    Model *m = instance;
    size_t i;

    m->y32 = m->gain32 * m->x32;
    m->big64_out = m->big64 + (fmi3Int64)m->count16 * m->mode;
    m->twice64 = 2u * (fmi3UInt64)m->big64;
    for (i = 0; i < m->blob_size; i++) {
        m->blob_out[i] = m->blob[m->blob_size - 1 - i];
    }
    m->blob_out_size = m->blob_size;
    for (i = 0; i < 2; i++) {
        m->v[i] = m->A[2 * i] * m->u[0] + m->A[2 * i + 1] * m->u[1] + m->u[2];
    }
    m->time = currentCommunicationPoint + communicationStepSize;
    *eventHandlingNeeded = fmi3False;
    *terminateSimulation = fmi3False;
    *earlyReturn = fmi3False;
    *lastSuccessfulTime = m->time;
    return fmi3OK;
}

/* Each getter and setter walks its references, taking as many values as each variable has. */
#define NEED(count)                                                                                  \
    if (k + (count) > nValues) {                                                                     \
        return fail(m, "%s: %zu values are too few", __func__, nValues);                             \
    }

fmi3Status fmi3GetFloat32(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3Float32 values[],
                          size_t nValues)
{
    Model *m = instance;
    size_t i, k = 0;

    for (i = 0; i < nvr; i++) {
        NEED(1)
        switch (vr[i]) {
        case 2: values[k++] = m->gain32; break;
        case 3: values[k++] = m->x32; break;
        case 4: values[k++] = m->y32; break;
        default: return fail(m, "%s: no Float32 variable has value reference %u", __func__, vr[i]);
        }
    }
    return fmi3OK;
}

fmi3Status fmi3SetFloat32(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                          const fmi3Float32 values[], size_t nValues)
{
    Model *m = instance;
    size_t i, k = 0;

    for (i = 0; i < nvr; i++) {
        NEED(1)
        switch (vr[i]) {
        case 2:
            if (values[k] < 0 || values[k] > 10) {
                return fail(m, "gain32 = %g is outside [0, 10]", values[k]);
            }
            m->gain32 = values[k++];
            break;
        case 3: m->x32 = values[k++]; break;
        default: return fail(m, "%s: value reference %u cannot be set", __func__, vr[i]);
        }
    }
    return fmi3OK;
}

fmi3Status fmi3GetFloat64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3Float64 values[],
                          size_t nValues)
{
    Model *m = instance;
    size_t i, k = 0;

    for (i = 0; i < nvr; i++) {
        switch (vr[i]) {
        case 0: NEED(1) values[k++] = m->time; break;
        case 13: NEED(3) memcpy(values + k, m->u, sizeof m->u); k += 3; break;
        case 14: NEED(4) memcpy(values + k, m->A, sizeof m->A); k += 4; break;
        case 15: NEED(2) memcpy(values + k, m->v, sizeof m->v); k += 2; break;
        default: return fail(m, "%s: no Float64 variable has value reference %u", __func__, vr[i]);
        }
    }
    return fmi3OK;
}

fmi3Status fmi3SetFloat64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                          const fmi3Float64 values[], size_t nValues)
{
    Model *m = instance;
    size_t i, k = 0;

    for (i = 0; i < nvr; i++) {
        switch (vr[i]) {
        case 13: NEED(3) memcpy(m->u, values + k, sizeof m->u); k += 3; break;
        case 14: NEED(4) memcpy(m->A, values + k, sizeof m->A); k += 4; break;
        default: return fail(m, "%s: value reference %u cannot be set", __func__, vr[i]);
        }
    }
    return fmi3OK;
}

fmi3Status fmi3GetInt8(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3Int8 values[],
                       size_t nValues)
{
    Model *m = instance;
    size_t i, k = 0;

    for (i = 0; i < nvr; i++) {
        NEED(1)
        if (vr[i] != 9) {
            return fail(m, "%s: no Int8 variable has value reference %u", __func__, vr[i]);
        }
        values[k++] = (fmi3Int8)(-10 * m->mode);   /* level8: calculated from the mode, also while initializing */
    }
    return fmi3OK;
}

fmi3Status fmi3GetUInt16(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3UInt16 values[],
                         size_t nValues)
{
    Model *m = instance;
    size_t i, k = 0;

    for (i = 0; i < nvr; i++) {
        NEED(1)
        switch (vr[i]) {
        case 5: values[k++] = m->count16; break;
        case 6: values[k++] = m->limit16; break;
        default: return fail(m, "%s: no UInt16 variable has value reference %u", __func__, vr[i]);
        }
    }
    return fmi3OK;
}

fmi3Status fmi3SetUInt16(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                         const fmi3UInt16 values[], size_t nValues)
{
    Model *m = instance;
    size_t i, k = 0;

    for (i = 0; i < nvr; i++) {
        NEED(1)
        switch (vr[i]) {
        case 5: m->count16 = values[k++]; break;
        case 6:
            if (values[k] > 50000) {
                return fail(m, "limit16 = %u is above 50000", values[k]);
            }
            m->limit16 = values[k++];
            break;
        default: return fail(m, "%s: value reference %u cannot be set", __func__, vr[i]);
        }
    }
    return fmi3OK;
}

fmi3Status fmi3GetUInt64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3UInt64 values[],
                         size_t nValues)
{
    Model *m = instance;
    size_t i, k = 0;

    for (i = 0; i < nvr; i++) {
        NEED(1)
        switch (vr[i]) {
        case 12: values[k++] = 3; break;   /* n, the structural parameter: the size of u */
        case 16: values[k++] = m->twice64; break;
        default: return fail(m, "%s: no UInt64 variable has value reference %u", __func__, vr[i]);
        }
    }
    return fmi3OK;
}

fmi3Status fmi3GetInt64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, fmi3Int64 values[],
                        size_t nValues)
{
    Model *m = instance;
    size_t i, k = 0;

    for (i = 0; i < nvr; i++) {
        NEED(1)
        switch (vr[i]) {
        case 1: values[k++] = m->mode; break;
        case 7: values[k++] = m->big64; break;
        case 8: values[k++] = m->big64_out; break;
        default: return fail(m, "%s: no Int64 variable has value reference %u", __func__, vr[i]);
        }
    }
    return fmi3OK;
}

fmi3Status fmi3SetInt64(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr,
                        const fmi3Int64 values[], size_t nValues)
{
    Model *m = instance;
    size_t i, k = 0;

    for (i = 0; i < nvr; i++) {
        NEED(1)
        switch (vr[i]) {
        case 1:
            if (values[k] < 1 || values[k] > 3) {   /* what an exporter's FMU says of an illegal item */
                return fail(m, "%lld is not a legal value for mode", (long long)values[k]);
            }
            m->mode = values[k++];
            break;
        case 7: m->big64 = values[k++]; break;
        default: return fail(m, "%s: value reference %u cannot be set", __func__, vr[i]);
        }
    }
    return fmi3OK;
}

fmi3Status fmi3GetBinary(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, size_t valueSizes[],
                         fmi3Binary values[], size_t nValues)
{
    Model *m = instance;
    size_t i, k = 0;

    for (i = 0; i < nvr; i++) {
        NEED(1)
        switch (vr[i]) {
        case 10: valueSizes[k] = m->blob_size; values[k++] = m->blob; break;
        case 11: valueSizes[k] = m->blob_out_size; values[k++] = m->blob_out; break;
        default: return fail(m, "%s: no Binary variable has value reference %u", __func__, vr[i]);
        }
    }
    return fmi3OK;
}

fmi3Status fmi3SetBinary(fmi3Instance instance, const fmi3ValueReference vr[], size_t nvr, const size_t valueSizes[],
                         const fmi3Binary values[], size_t nValues)
{
    Model *m = instance;
    size_t i, k = 0;

    for (i = 0; i < nvr; i++) {
        NEED(1)
        if (vr[i] != 10) {
            return fail(m, "%s: value reference %u cannot be set", __func__, vr[i]);
        }
        if (valueSizes[k] > BLOB_MAX) {
            return fail(m, "blob: %zu bytes are more than its maxSize %d", valueSizes[k], BLOB_MAX);
        }
        memcpy(m->blob, values[k], valueSizes[k]);
        m->blob_size = valueSizes[k++];
    }
    return fmi3OK;
}
