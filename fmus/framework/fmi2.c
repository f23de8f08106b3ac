/* The FMI 2.0 co-simulation API on top of the framework; FMI 2 types stay in this file. */
#include <stdbool.h>
#include <string.h>

#include "fmi2Functions.h"
#include "instance.h"
#include "state.h"
#include "variables.h"

/* Every message the framework writes fits twice over, escaped. */
#define ESCAPED_SIZE 1024

static fmi2Status to_fmi2(Status status)
{
    switch (status) {
    case STATUS_OK: return fmi2OK;
    case STATUS_WARNING: return fmi2Warning;
    case STATUS_DISCARD: return fmi2Discard;
    case STATUS_ERROR: return fmi2Error;
    case STATUS_FATAL: return fmi2Fatal;
    }
    return fmi2Fatal;
}

/* The FMI 2 logger takes its message as a printf format in which "#...#"
   refers to a variable: '%' and '#' in our text must arrive as "%%" and "##". */
static void deliver(const LogTarget *target, const char *instance_name, Status status, const char *category,
                    const char *message)
{
    fmi2CallbackLogger logger = (fmi2CallbackLogger)target->callback;
    char escaped[ESCAPED_SIZE];
    size_t out = 0;

    for (; *message != '\0' && out + 3 <= sizeof escaped; message++) {
        if (*message == '%' || *message == '#') {
            escaped[out++] = *message;
        }
        escaped[out++] = *message;
    }
    escaped[out] = '\0';
    logger(target->environment, instance_name, to_fmi2(status), category, escaped);
}

/* The one exit of every call on an instance: an error puts the instance into
   the error state, as FMI 2 requires. */
static fmi2Status finish(Instance *inst, Status status)
{
    if (status >= STATUS_ERROR) {
        inst->phase = PHASE_ERROR;
    }
    return to_fmi2(status);
}

static fmi2Status unsupported(fmi2Component c, const char *fn, const char *why)
{
    if (c == NULL) {
        return fmi2Error;
    }
    return finish(c, log_error(c, "%s: not supported by this FMU (%s)", fn, why));
}

/* ------------------------------------------------------------ common functions */

const char *fmi2GetTypesPlatform(void)
{
    return fmi2TypesPlatform;
}

const char *fmi2GetVersion(void)
{
    return fmi2Version;
}

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[])
{
    if (c == NULL) {
        return fmi2Error;
    }
    return finish(c, log_configure(c, __func__, loggingOn != fmi2False, nCategories, categories));
}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation, const fmi2CallbackFunctions *functions,
                              fmi2Boolean visible, fmi2Boolean loggingOn)
{
    LogTarget target = {NULL, NULL, NULL};
    const char *name = instanceName != NULL ? instanceName : "";

    (void)fmuResourceLocation; /* the models have no resources */
    (void)visible;
    if (functions != NULL && functions->logger != NULL) {
        target.deliver = deliver;
        target.callback = (void (*)(void))functions->logger;
        target.environment = functions->componentEnvironment;
    }
    if (instanceName == NULL) {
        log_error_to(&target, name, "fmi2Instantiate: the instance name is NULL");
        return NULL;
    }
    if (fmuType != fmi2CoSimulation) {
        log_error_to(&target, name, "fmi2Instantiate: %s supports co-simulation only, not model exchange",
                     MODEL_IDENTIFIER);
        return NULL;
    }
    if (fmuGUID == NULL || strcmp(fmuGUID, MODEL_TOKEN) != 0) {
        log_error_to(&target, name,
                     "fmi2Instantiate: GUID %s does not match %s of this binary "
                     "(modelDescription.xml of another build?)",
                     fmuGUID != NULL ? fmuGUID : "(null)", MODEL_TOKEN);
        return NULL;
    }
    return instance_new(name, target, loggingOn != fmi2False);
}

void fmi2FreeInstance(fmi2Component c)
{
    instance_free(c);
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime)
{
    Instance *inst = c;

    /* The models are discrete logic: no tolerance to honour, nothing that ends at a stop time. */
    (void)toleranceDefined;
    (void)tolerance;
    (void)stopTimeDefined;
    (void)stopTime;
    if (inst == NULL) {
        return fmi2Error;
    }
    if (!instance_allows(inst, __func__, PHASE_INSTANTIATED)) {
        return finish(inst, STATUS_ERROR);
    }
    inst->start_time = startTime;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c)
{
    Instance *inst = c;

    if (inst == NULL) {
        return fmi2Error;
    }
    return finish(inst, instance_enter_initialization(inst, __func__, inst->start_time));
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c)
{
    if (c == NULL) {
        return fmi2Error;
    }
    return finish(c, instance_exit_initialization(c, __func__));
}

fmi2Status fmi2Terminate(fmi2Component c)
{
    if (c == NULL) {
        return fmi2Error;
    }
    return finish(c, instance_terminate(c, __func__));
}

fmi2Status fmi2Reset(fmi2Component c)
{
    if (c == NULL) {
        return fmi2Error;
    }
    return finish(c, instance_reset(c));
}

/* ------------------------------------------------------------ getting and setting values */

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[])
{
    Status status;
    size_t i;

    if (c == NULL) {
        return fmi2Error;
    }
    status = variables_begin(c, __func__, false, nvr, vr, value);
    for (i = 0; status <= STATUS_WARNING && i < nvr; i++) {
        if (variable_get_real(c, __func__, vr[i], &value[i]) != STATUS_OK) {
            status = STATUS_ERROR;
        }
    }
    return finish(c, status);
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Integer value[])
{
    Status status;
    size_t i;

    if (c == NULL) {
        return fmi2Error;
    }
    status = variables_begin(c, __func__, false, nvr, vr, value);
    for (i = 0; status <= STATUS_WARNING && i < nvr; i++) {
        int32_t v;

        if (variable_get_int(c, __func__, vr[i], &v) != STATUS_OK) {
            status = STATUS_ERROR;
        } else {
            value[i] = v;
        }
    }
    return finish(c, status);
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Boolean value[])
{
    Status status;
    size_t i;

    if (c == NULL) {
        return fmi2Error;
    }
    status = variables_begin(c, __func__, false, nvr, vr, value);
    for (i = 0; status <= STATUS_WARNING && i < nvr; i++) {
        bool v;

        if (variable_get_bool(c, __func__, vr[i], &v) != STATUS_OK) {
            status = STATUS_ERROR;
        } else {
            value[i] = v ? fmi2True : fmi2False;
        }
    }
    return finish(c, status);
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2String value[])
{
    Status status;
    size_t i;

    if (c == NULL) {
        return fmi2Error;
    }
    status = variables_begin(c, __func__, false, nvr, vr, value);
    for (i = 0; status <= STATUS_WARNING && i < nvr; i++) {
        if (variable_get_string(c, __func__, vr[i], &value[i]) != STATUS_OK) {
            status = STATUS_ERROR;
        }
    }
    return finish(c, status);
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[])
{
    Status status;
    size_t i;

    if (c == NULL) {
        return fmi2Error;
    }
    status = variables_begin(c, __func__, true, nvr, vr, value);
    for (i = 0; status == STATUS_OK && i < nvr; i++) {
        status = variable_set_real(c, __func__, vr[i], value[i]);
    }
    return finish(c, status);
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Integer value[])
{
    Status status;
    size_t i;

    if (c == NULL) {
        return fmi2Error;
    }
    status = variables_begin(c, __func__, true, nvr, vr, value);
    for (i = 0; status == STATUS_OK && i < nvr; i++) {
        status = variable_set_int(c, __func__, vr[i], value[i]);
    }
    return finish(c, status);
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Boolean value[])
{
    Status status;
    size_t i;

    if (c == NULL) {
        return fmi2Error;
    }
    status = variables_begin(c, __func__, true, nvr, vr, value);
    for (i = 0; status == STATUS_OK && i < nvr; i++) {
        status = variable_set_bool(c, __func__, vr[i], value[i] != fmi2False);
    }
    return finish(c, status);
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2String value[])
{
    Status status;
    size_t i;

    if (c == NULL) {
        return fmi2Error;
    }
    status = variables_begin(c, __func__, true, nvr, vr, value);
    for (i = 0; status == STATUS_OK && i < nvr; i++) {
        status = variable_set_string(c, __func__, vr[i], value[i]);
    }
    return finish(c, status);
}

/* ------------------------------------------------------------ FMU state (state.c) */

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *FMUstate)
{
    if (c == NULL) {
        return fmi2Error;
    }
    return finish(c, state_get(c, __func__, FMUstate));
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate FMUstate)
{
    if (c == NULL) {
        return fmi2Error;
    }
    return finish(c, state_set(c, __func__, FMUstate));
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *FMUstate)
{
    if (c == NULL) {
        return fmi2Error;
    }
    return finish(c, state_free(c, __func__, FMUstate));
}

fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate FMUstate, size_t *size)
{
    if (c == NULL) {
        return fmi2Error;
    }
    return finish(c, state_serialized_size(c, __func__, FMUstate, size));
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate FMUstate, fmi2Byte serializedState[], size_t size)
{
    if (c == NULL) {
        return fmi2Error;
    }
    return finish(c, state_serialize(c, __func__, FMUstate, (unsigned char *)serializedState, size));
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte serializedState[], size_t size,
                                   fmi2FMUstate *FMUstate)
{
    if (c == NULL) {
        return fmi2Error;
    }
    return finish(c, state_deserialize(c, __func__, (const unsigned char *)serializedState, size, FMUstate));
}

/* ------------------------------------------------------------ optional capabilities, all declared false */

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown_ref[], size_t nUnknown,
                                        const fmi2ValueReference vKnown_ref[], size_t nKnown,
                                        const fmi2Real dvKnown[], fmi2Real dvUnknown[])
{
    (void)vUnknown_ref;
    (void)nUnknown;
    (void)vKnown_ref;
    (void)nKnown;
    (void)dvKnown;
    (void)dvUnknown;
    return unsupported(c, __func__, "providesDirectionalDerivative=\"false\"");
}

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[])
{
    (void)vr;
    (void)nvr;
    (void)order;
    (void)value;
    return unsupported(c, __func__, "canInterpolateInputs=\"false\"");
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                        const fmi2Integer order[], fmi2Real value[])
{
    (void)vr;
    (void)nvr;
    (void)order;
    (void)value;
    return unsupported(c, __func__, "maxOutputDerivativeOrder=\"0\"");
}

fmi2Status fmi2CancelStep(fmi2Component c)
{
    return unsupported(c, __func__, "fmi2DoStep never returns fmi2Pending");
}

/* ------------------------------------------------------------ co-simulation */

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint, fmi2Real communicationStepSize,
                      fmi2Boolean noSetFMUStatePriorToCurrentPoint)
{
    (void)noSetFMUStatePriorToCurrentPoint; /* FMU states are independent copies: nothing to drop */
    if (c == NULL) {
        return fmi2Error;
    }
    return finish(c, instance_do_step(c, __func__, currentCommunicationPoint, communicationStepSize));
}

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value)
{
    (void)s;
    (void)value;
    return unsupported(c, __func__, "fmi2DoStep never returns fmi2Pending");
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value)
{
    Instance *inst = c;

    if (inst == NULL) {
        return fmi2Error;
    }
    if (s != fmi2LastSuccessfulTime || value == NULL) {
        return finish(inst, log_error(inst, "%s: only fmi2LastSuccessfulTime is a real status", __func__));
    }
    *value = inst->time;
    return fmi2OK;
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value)
{
    (void)s;
    (void)value;
    return unsupported(c, __func__, "FMI 2.0 defines no integer status");
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value)
{
    Instance *inst = c;

    if (inst == NULL) {
        return fmi2Error;
    }
    if (s != fmi2Terminated || value == NULL) {
        return finish(inst, log_error(inst, "%s: only fmi2Terminated is a boolean status", __func__));
    }
    *value = fmi2False; /* the models never ask to end the simulation */
    return fmi2OK;
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value)
{
    (void)s;
    (void)value;
    return unsupported(c, __func__, "fmi2DoStep never returns fmi2Pending");
}

/* ------------------------------------------------------------ model exchange
   Exported as errors, for importers that bind every symbol of fmi2Functions.h. */

fmi2Status fmi2EnterEventMode(fmi2Component c)
{
    return unsupported(c, __func__, "co-simulation only");
}

fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo *eventInfo)
{
    (void)eventInfo;
    return unsupported(c, __func__, "co-simulation only");
}

fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c)
{
    return unsupported(c, __func__, "co-simulation only");
}

fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi2Boolean *enterEventMode, fmi2Boolean *terminateSimulation)
{
    (void)noSetFMUStatePriorToCurrentPoint;
    (void)enterEventMode;
    (void)terminateSimulation;
    return unsupported(c, __func__, "co-simulation only");
}

fmi2Status fmi2SetTime(fmi2Component c, fmi2Real time)
{
    (void)time;
    return unsupported(c, __func__, "co-simulation only");
}

fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t nx)
{
    (void)x;
    (void)nx;
    return unsupported(c, __func__, "co-simulation only");
}

fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real derivatives[], size_t nx)
{
    (void)derivatives;
    (void)nx;
    return unsupported(c, __func__, "co-simulation only");
}

fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real eventIndicators[], size_t ni)
{
    (void)eventIndicators;
    (void)ni;
    return unsupported(c, __func__, "co-simulation only");
}

fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t nx)
{
    (void)x;
    (void)nx;
    return unsupported(c, __func__, "co-simulation only");
}

fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x_nominal[], size_t nx)
{
    (void)x_nominal;
    (void)nx;
    return unsupported(c, __func__, "co-simulation only");
}
