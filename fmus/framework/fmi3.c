/* The FMI 3.0 co-simulation API on top of the framework; FMI 3 types stay in this file. */
#include <stdbool.h>
#include <string.h>

#include "fmi3Functions.h"
#include "instance.h"
#include "state.h"
#include "variables.h"

static fmi3Status to_fmi3(Status status)
{
    switch (status) {
    case STATUS_OK: return fmi3OK;
    case STATUS_WARNING: return fmi3Warning;
    case STATUS_DISCARD: return fmi3Discard;
    case STATUS_ERROR: return fmi3Error;
    case STATUS_FATAL: return fmi3Fatal;
    }
    return fmi3Fatal;
}

static void deliver(const LogTarget *target, const char *instance_name, Status status, const char *category,
                    const char *message)
{
    fmi3LogMessageCallback callback = (fmi3LogMessageCallback)target->callback;

    (void)instance_name; /* the importer knows its instance by instanceEnvironment */
    callback(target->environment, to_fmi3(status), category, message);
}

static LogTarget target_of(fmi3InstanceEnvironment environment, fmi3LogMessageCallback callback)
{
    LogTarget target = {NULL, NULL, NULL};

    if (callback != NULL) {
        target.deliver = deliver;
        target.callback = (void (*)(void))callback;
        target.environment = environment;
    }
    return target;
}

/* The one exit of every call on an instance: an error puts the instance into
   the error state, as FMI 3 requires. */
static fmi3Status finish(Instance *inst, Status status)
{
    if (status >= STATUS_ERROR) {
        inst->phase = PHASE_ERROR;
    }
    return to_fmi3(status);
}

static fmi3Status unsupported(fmi3Instance instance, const char *fn, const char *why)
{
    if (instance == NULL) {
        return fmi3Error;
    }
    return finish(instance, log_error(instance, "%s: not supported by this FMU (%s)", fn, why));
}

/* FMI 3 passes the length of the value array separately because of arrays;
   every variable here is a scalar, so it must equal the number of references. */
static Status begin(Instance *inst, const char *fn, bool set, size_t nvr, const void *vrs, const void *values,
                    size_t n_values)
{
    if (n_values != nvr) {
        return log_error(inst, "%s: %zu values for %zu value references (all variables are scalars)", fn, n_values,
                         nvr);
    }
    return variables_begin(inst, fn, set, nvr, vrs, values);
}

/* ------------------------------------------------------------ common functions */

const char *fmi3GetVersion(void)
{
    return fmi3Version;
}

fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean loggingOn, size_t nCategories,
                               const fmi3String categories[])
{
    if (instance == NULL) {
        return fmi3Error;
    }
    return finish(instance, log_configure(instance, __func__, loggingOn, nCategories, categories));
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
    LogTarget target = target_of(instanceEnvironment, logMessage);
    const char *name = instanceName != NULL ? instanceName : "";

    /* No resources, no early return, no intermediate updates: the
       description declares none, so these arguments change nothing. */
    (void)resourcePath;
    (void)visible;
    (void)earlyReturnAllowed;
    (void)requiredIntermediateVariables;
    (void)nRequiredIntermediateVariables;
    (void)intermediateUpdate;
    if (instanceName == NULL) {
        log_error_to(&target, name, "fmi3InstantiateCoSimulation: the instance name is NULL");
        return NULL;
    }
    if (instantiationToken == NULL || strcmp(instantiationToken, MODEL_TOKEN) != 0) {
        log_error_to(&target, name,
                     "fmi3InstantiateCoSimulation: instantiation token %s does not match %s of this binary "
                     "(modelDescription.xml of another build?)",
                     instantiationToken != NULL ? instantiationToken : "(null)", MODEL_TOKEN);
        return NULL;
    }
    if (eventModeUsed) {
        log_error_to(&target, name,
                     "fmi3InstantiateCoSimulation: eventModeUsed is true but the FMU declares hasEventMode=\"false\"");
        return NULL;
    }
    return instance_new(name, target, loggingOn);
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName, fmi3String instantiationToken,
                                          fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn,
                                          fmi3InstanceEnvironment instanceEnvironment,
                                          fmi3LogMessageCallback logMessage)
{
    LogTarget target = target_of(instanceEnvironment, logMessage);

    (void)instantiationToken;
    (void)resourcePath;
    (void)visible;
    (void)loggingOn;
    log_error_to(&target, instanceName != NULL ? instanceName : "",
                 "fmi3InstantiateModelExchange: %s supports co-simulation only", MODEL_IDENTIFIER);
    return NULL;
}

fmi3Instance fmi3InstantiateScheduledExecution(fmi3String instanceName, fmi3String instantiationToken,
                                               fmi3String resourcePath, fmi3Boolean visible,
                                               fmi3Boolean loggingOn, fmi3InstanceEnvironment instanceEnvironment,
                                               fmi3LogMessageCallback logMessage,
                                               fmi3ClockUpdateCallback clockUpdate,
                                               fmi3LockPreemptionCallback lockPreemption,
                                               fmi3UnlockPreemptionCallback unlockPreemption)
{
    LogTarget target = target_of(instanceEnvironment, logMessage);

    (void)instantiationToken;
    (void)resourcePath;
    (void)visible;
    (void)loggingOn;
    (void)clockUpdate;
    (void)lockPreemption;
    (void)unlockPreemption;
    log_error_to(&target, instanceName != NULL ? instanceName : "",
                 "fmi3InstantiateScheduledExecution: %s supports co-simulation only", MODEL_IDENTIFIER);
    return NULL;
}

void fmi3FreeInstance(fmi3Instance instance)
{
    instance_free(instance);
}

fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean toleranceDefined, fmi3Float64 tolerance,
                                       fmi3Float64 startTime, fmi3Boolean stopTimeDefined, fmi3Float64 stopTime)
{
    /* The models are discrete logic: no tolerance to honour, nothing that ends at a stop time. */
    (void)toleranceDefined;
    (void)tolerance;
    (void)stopTimeDefined;
    (void)stopTime;
    if (instance == NULL) {
        return fmi3Error;
    }
    return finish(instance, instance_enter_initialization(instance, __func__, startTime));
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance instance)
{
    if (instance == NULL) {
        return fmi3Error;
    }
    return finish(instance, instance_exit_initialization(instance, __func__));
}

fmi3Status fmi3EnterEventMode(fmi3Instance instance)
{
    return unsupported(instance, __func__, "hasEventMode=\"false\"");
}

fmi3Status fmi3Terminate(fmi3Instance instance)
{
    if (instance == NULL) {
        return fmi3Error;
    }
    return finish(instance, instance_terminate(instance, __func__));
}

fmi3Status fmi3Reset(fmi3Instance instance)
{
    if (instance == NULL) {
        return fmi3Error;
    }
    return finish(instance, instance_reset(instance));
}

/* ------------------------------------------------------------ getting and setting values */

/* Every typed getter and setter has one shape: check the call, then move each value through
   the variable table (which checks reference, type, phase and range and logs what is wrong). */
#define FMI3_GETTER(function, fmi_type, get)                                                                  \
    fmi3Status function(fmi3Instance instance, const fmi3ValueReference valueReferences[],                    \
                        size_t nValueReferences, fmi_type values[], size_t nValues)                           \
    {                                                                                                         \
        Status status;                                                                                        \
        size_t i;                                                                                             \
                                                                                                              \
        if (instance == NULL) {                                                                               \
            return fmi3Error;                                                                                 \
        }                                                                                                     \
        status = begin(instance, __func__, false, nValueReferences, valueReferences, values, nValues);        \
        for (i = 0; status <= STATUS_WARNING && i < nValueReferences; i++) {                                  \
            if (get(instance, __func__, valueReferences[i], &values[i]) != STATUS_OK) {                       \
                status = STATUS_ERROR;                                                                        \
            }                                                                                                 \
        }                                                                                                     \
        return finish(instance, status);                                                                      \
    }

#define FMI3_SETTER(function, fmi_type, set)                                                                  \
    fmi3Status function(fmi3Instance instance, const fmi3ValueReference valueReferences[],                    \
                        size_t nValueReferences, const fmi_type values[], size_t nValues)                     \
    {                                                                                                         \
        Status status;                                                                                        \
        size_t i;                                                                                             \
                                                                                                              \
        if (instance == NULL) {                                                                               \
            return fmi3Error;                                                                                 \
        }                                                                                                     \
        status = begin(instance, __func__, true, nValueReferences, valueReferences, values, nValues);         \
        for (i = 0; status == STATUS_OK && i < nValueReferences; i++) {                                       \
            status = set(instance, __func__, valueReferences[i], values[i]);                                  \
        }                                                                                                     \
        return finish(instance, status);                                                                      \
    }

FMI3_GETTER(fmi3GetFloat64, fmi3Float64, variable_get_real)
FMI3_GETTER(fmi3GetInt32, fmi3Int32, variable_get_int)
FMI3_GETTER(fmi3GetBoolean, fmi3Boolean, variable_get_bool)
FMI3_GETTER(fmi3GetString, fmi3String, variable_get_string)
FMI3_SETTER(fmi3SetFloat64, fmi3Float64, variable_set_real)
FMI3_SETTER(fmi3SetInt32, fmi3Int32, variable_set_int)
FMI3_SETTER(fmi3SetBoolean, fmi3Boolean, variable_set_bool)
FMI3_SETTER(fmi3SetString, fmi3String, variable_set_string)

/* The models have no variables of the remaining types: every reference is
   reported with the type it really has. */
static fmi3Status reject_type(fmi3Instance instance, const char *fn, bool set, const fmi3ValueReference vrs[],
                              size_t nvr, const void *values, size_t n_values, const char *type_name)
{
    Status status;

    if (instance == NULL) {
        return fmi3Error;
    }
    status = begin(instance, fn, set, nvr, vrs, values, n_values);
    if (status <= STATUS_WARNING && nvr > 0) {
        status = variable_reject_type(instance, fn, vrs[0], type_name);
    }
    return finish(instance, status);
}

#define REJECT_TYPE(Type, CType)                                                                                 \
    fmi3Status fmi3Get##Type(fmi3Instance instance, const fmi3ValueReference valueReferences[],                  \
                             size_t nValueReferences, CType values[], size_t nValues)                            \
    {                                                                                                            \
        return reject_type(instance, __func__, false, valueReferences, nValueReferences, values, nValues, #Type); \
    }                                                                                                            \
    fmi3Status fmi3Set##Type(fmi3Instance instance, const fmi3ValueReference valueReferences[],                  \
                             size_t nValueReferences, const CType values[], size_t nValues)                      \
    {                                                                                                            \
        return reject_type(instance, __func__, true, valueReferences, nValueReferences, values, nValues, #Type);  \
    }

REJECT_TYPE(Float32, fmi3Float32)
REJECT_TYPE(Int8, fmi3Int8)
REJECT_TYPE(UInt8, fmi3UInt8)
REJECT_TYPE(Int16, fmi3Int16)
REJECT_TYPE(UInt16, fmi3UInt16)
REJECT_TYPE(UInt32, fmi3UInt32)
REJECT_TYPE(Int64, fmi3Int64)
REJECT_TYPE(UInt64, fmi3UInt64)

fmi3Status fmi3GetBinary(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                         size_t nValueReferences, size_t valueSizes[], fmi3Binary values[], size_t nValues)
{
    (void)valueSizes;
    return reject_type(instance, __func__, false, valueReferences, nValueReferences, values, nValues, "Binary");
}

fmi3Status fmi3SetBinary(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                         size_t nValueReferences, const size_t valueSizes[], const fmi3Binary values[],
                         size_t nValues)
{
    (void)valueSizes;
    return reject_type(instance, __func__, true, valueReferences, nValueReferences, values, nValues, "Binary");
}

fmi3Status fmi3GetClock(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                        fmi3Clock values[])
{
    return reject_type(instance, __func__, false, valueReferences, nValueReferences, values, nValueReferences,
                       "Clock");
}

fmi3Status fmi3SetClock(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                        const fmi3Clock values[])
{
    return reject_type(instance, __func__, true, valueReferences, nValueReferences, values, nValueReferences,
                       "Clock");
}

/* ------------------------------------------------------------ optional capabilities, all declared false */

fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance instance, fmi3ValueReference valueReference,
                                               size_t *nDependencies)
{
    (void)valueReference;
    (void)nDependencies;
    return unsupported(instance, __func__, "providesPerElementDependencies=\"false\"");
}

fmi3Status fmi3GetVariableDependencies(fmi3Instance instance, fmi3ValueReference dependent,
                                       size_t elementIndicesOfDependent[], fmi3ValueReference independents[],
                                       size_t elementIndicesOfIndependents[], fmi3DependencyKind dependencyKinds[],
                                       size_t nDependencies)
{
    (void)dependent;
    (void)elementIndicesOfDependent;
    (void)independents;
    (void)elementIndicesOfIndependents;
    (void)dependencyKinds;
    (void)nDependencies;
    return unsupported(instance, __func__, "providesPerElementDependencies=\"false\"");
}

fmi3Status fmi3GetFMUState(fmi3Instance instance, fmi3FMUState *FMUState)
{
    if (instance == NULL) {
        return fmi3Error;
    }
    return finish(instance, state_get(instance, __func__, FMUState));
}

fmi3Status fmi3SetFMUState(fmi3Instance instance, fmi3FMUState FMUState)
{
    if (instance == NULL) {
        return fmi3Error;
    }
    return finish(instance, state_set(instance, __func__, FMUState));
}

fmi3Status fmi3FreeFMUState(fmi3Instance instance, fmi3FMUState *FMUState)
{
    if (instance == NULL) {
        return fmi3Error;
    }
    return finish(instance, state_free(instance, __func__, FMUState));
}

fmi3Status fmi3SerializedFMUStateSize(fmi3Instance instance, fmi3FMUState FMUState, size_t *size)
{
    if (instance == NULL) {
        return fmi3Error;
    }
    return finish(instance, state_serialized_size(instance, __func__, FMUState, size));
}

fmi3Status fmi3SerializeFMUState(fmi3Instance instance, fmi3FMUState FMUState, fmi3Byte serializedState[],
                                 size_t size)
{
    if (instance == NULL) {
        return fmi3Error;
    }
    return finish(instance, state_serialize(instance, __func__, FMUState, serializedState, size));
}

fmi3Status fmi3DeserializeFMUState(fmi3Instance instance, const fmi3Byte serializedState[], size_t size,
                                   fmi3FMUState *FMUState)
{
    if (instance == NULL) {
        return fmi3Error;
    }
    return finish(instance, state_deserialize(instance, __func__, serializedState, size, FMUState));
}

fmi3Status fmi3GetDirectionalDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[], size_t nUnknowns,
                                        const fmi3ValueReference knowns[], size_t nKnowns, const fmi3Float64 seed[],
                                        size_t nSeed, fmi3Float64 sensitivity[], size_t nSensitivity)
{
    (void)unknowns;
    (void)nUnknowns;
    (void)knowns;
    (void)nKnowns;
    (void)seed;
    (void)nSeed;
    (void)sensitivity;
    (void)nSensitivity;
    return unsupported(instance, __func__, "providesDirectionalDerivatives=\"false\"");
}

fmi3Status fmi3GetAdjointDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[], size_t nUnknowns,
                                    const fmi3ValueReference knowns[], size_t nKnowns, const fmi3Float64 seed[],
                                    size_t nSeed, fmi3Float64 sensitivity[], size_t nSensitivity)
{
    (void)unknowns;
    (void)nUnknowns;
    (void)knowns;
    (void)nKnowns;
    (void)seed;
    (void)nSeed;
    (void)sensitivity;
    (void)nSensitivity;
    return unsupported(instance, __func__, "providesAdjointDerivatives=\"false\"");
}

fmi3Status fmi3EnterConfigurationMode(fmi3Instance instance)
{
    return unsupported(instance, __func__, "no structural parameters");
}

fmi3Status fmi3ExitConfigurationMode(fmi3Instance instance)
{
    return unsupported(instance, __func__, "no structural parameters");
}

fmi3Status fmi3GetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                  size_t nValueReferences, fmi3Float64 intervals[],
                                  fmi3IntervalQualifier qualifiers[])
{
    (void)valueReferences;
    (void)nValueReferences;
    (void)intervals;
    (void)qualifiers;
    return unsupported(instance, __func__, "no clocks");
}

fmi3Status fmi3GetIntervalFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                   size_t nValueReferences, fmi3UInt64 counters[], fmi3UInt64 resolutions[],
                                   fmi3IntervalQualifier qualifiers[])
{
    (void)valueReferences;
    (void)nValueReferences;
    (void)counters;
    (void)resolutions;
    (void)qualifiers;
    return unsupported(instance, __func__, "no clocks");
}

fmi3Status fmi3GetShiftDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                               size_t nValueReferences, fmi3Float64 shifts[])
{
    (void)valueReferences;
    (void)nValueReferences;
    (void)shifts;
    return unsupported(instance, __func__, "no clocks");
}

fmi3Status fmi3GetShiftFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                size_t nValueReferences, fmi3UInt64 counters[], fmi3UInt64 resolutions[])
{
    (void)valueReferences;
    (void)nValueReferences;
    (void)counters;
    (void)resolutions;
    return unsupported(instance, __func__, "no clocks");
}

fmi3Status fmi3SetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                  size_t nValueReferences, const fmi3Float64 intervals[])
{
    (void)valueReferences;
    (void)nValueReferences;
    (void)intervals;
    return unsupported(instance, __func__, "no clocks");
}

fmi3Status fmi3SetIntervalFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                   size_t nValueReferences, const fmi3UInt64 counters[],
                                   const fmi3UInt64 resolutions[])
{
    (void)valueReferences;
    (void)nValueReferences;
    (void)counters;
    (void)resolutions;
    return unsupported(instance, __func__, "no clocks");
}

fmi3Status fmi3SetShiftDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                               size_t nValueReferences, const fmi3Float64 shifts[])
{
    (void)valueReferences;
    (void)nValueReferences;
    (void)shifts;
    return unsupported(instance, __func__, "no clocks");
}

fmi3Status fmi3SetShiftFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                size_t nValueReferences, const fmi3UInt64 counters[], const fmi3UInt64 resolutions[])
{
    (void)valueReferences;
    (void)nValueReferences;
    (void)counters;
    (void)resolutions;
    return unsupported(instance, __func__, "no clocks");
}

fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance instance)
{
    return unsupported(instance, __func__, "hasEventMode=\"false\"");
}

fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean *discreteStatesNeedUpdate,
                                    fmi3Boolean *terminateSimulation, fmi3Boolean *nominalsOfContinuousStatesChanged,
                                    fmi3Boolean *valuesOfContinuousStatesChanged, fmi3Boolean *nextEventTimeDefined,
                                    fmi3Float64 *nextEventTime)
{
    (void)discreteStatesNeedUpdate;
    (void)terminateSimulation;
    (void)nominalsOfContinuousStatesChanged;
    (void)valuesOfContinuousStatesChanged;
    (void)nextEventTimeDefined;
    (void)nextEventTime;
    return unsupported(instance, __func__, "hasEventMode=\"false\"");
}

/* ------------------------------------------------------------ co-simulation */

fmi3Status fmi3EnterStepMode(fmi3Instance instance)
{
    return unsupported(instance, __func__, "hasEventMode=\"false\": initialization leads straight to step mode");
}

fmi3Status fmi3GetOutputDerivatives(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                    size_t nValueReferences, const fmi3Int32 orders[], fmi3Float64 values[],
                                    size_t nValues)
{
    (void)valueReferences;
    (void)nValueReferences;
    (void)orders;
    (void)values;
    (void)nValues;
    return unsupported(instance, __func__, "maxOutputDerivativeOrder=\"0\"");
}

fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 currentCommunicationPoint,
                      fmi3Float64 communicationStepSize, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                      fmi3Boolean *eventHandlingNeeded, fmi3Boolean *terminateSimulation, fmi3Boolean *earlyReturn,
                      fmi3Float64 *lastSuccessfulTime)
{
    Instance *inst = instance;
    Status status;

    (void)noSetFMUStatePriorToCurrentPoint; /* FMU states are independent copies: nothing to drop */
    if (inst == NULL) {
        return fmi3Error;
    }
    if (eventHandlingNeeded == NULL || terminateSimulation == NULL || earlyReturn == NULL
        || lastSuccessfulTime == NULL) {
        return finish(inst, log_error(inst, "%s: an output argument is NULL", __func__));
    }
    status = instance_do_step(inst, __func__, currentCommunicationPoint, communicationStepSize);
    *eventHandlingNeeded = false;
    *terminateSimulation = false;
    *earlyReturn = false;
    *lastSuccessfulTime = inst->time;
    return finish(inst, status);
}

/* ------------------------------------------------------------ model exchange and scheduled execution: exported
   because FMI 3 requires every function of fmi3Functions.h */

fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance instance)
{
    return unsupported(instance, __func__, "co-simulation only");
}

fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi3Boolean *enterEventMode, fmi3Boolean *terminateSimulation)
{
    (void)noSetFMUStatePriorToCurrentPoint;
    (void)enterEventMode;
    (void)terminateSimulation;
    return unsupported(instance, __func__, "co-simulation only");
}

fmi3Status fmi3SetTime(fmi3Instance instance, fmi3Float64 time)
{
    (void)time;
    return unsupported(instance, __func__, "co-simulation only");
}

fmi3Status fmi3SetContinuousStates(fmi3Instance instance, const fmi3Float64 continuousStates[],
                                   size_t nContinuousStates)
{
    (void)continuousStates;
    (void)nContinuousStates;
    return unsupported(instance, __func__, "co-simulation only");
}

fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance instance, fmi3Float64 derivatives[],
                                             size_t nContinuousStates)
{
    (void)derivatives;
    (void)nContinuousStates;
    return unsupported(instance, __func__, "co-simulation only");
}

fmi3Status fmi3GetEventIndicators(fmi3Instance instance, fmi3Float64 eventIndicators[], size_t nEventIndicators)
{
    (void)eventIndicators;
    (void)nEventIndicators;
    return unsupported(instance, __func__, "co-simulation only");
}

fmi3Status fmi3GetContinuousStates(fmi3Instance instance, fmi3Float64 continuousStates[], size_t nContinuousStates)
{
    (void)continuousStates;
    (void)nContinuousStates;
    return unsupported(instance, __func__, "co-simulation only");
}

fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance instance, fmi3Float64 nominals[], size_t nContinuousStates)
{
    (void)nominals;
    (void)nContinuousStates;
    return unsupported(instance, __func__, "co-simulation only");
}

fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t *nEventIndicators)
{
    (void)nEventIndicators;
    return unsupported(instance, __func__, "co-simulation only");
}

fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t *nContinuousStates)
{
    (void)nContinuousStates;
    return unsupported(instance, __func__, "co-simulation only");
}

fmi3Status fmi3ActivateModelPartition(fmi3Instance instance, fmi3ValueReference clockReference,
                                      fmi3Float64 activationTime)
{
    (void)clockReference;
    (void)activationTime;
    return unsupported(instance, __func__, "co-simulation only");
}
