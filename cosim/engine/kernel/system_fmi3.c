/* The system FMU's FMI 3.0 API, Co-Simulation or (where exported so) Model Exchange: each call
 * checked against the FMU's phase and passed
 * to the system's life cycle (system_fmu.c), over the same nested FMI 2.0 FMUs as its FMI 2.0 API.
 * Float64, Int32, Boolean and String scalars; the independent variable `time` at the value
 * reference after the system's variables. No event mode, intermediate update or early return (a
 * step always completes), no FMU state, no Scheduled Execution: each of those calls is refused with
 * the reason logged (its modelDescription.xml says so). Offered as Model Exchange (system_me.c) where
 * the export made it so. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "fmi3Functions.h"
#include "system.h"

typedef struct { /* the instance an importer holds: the system and the importer's logger */
    System *system;
    fmi3LogMessageCallback log;
    fmi3InstanceEnvironment environment;
} Instance;

static void log_fmi3(void *environment, const char *instance, int status, const char *category, const char *message) {
    const Instance *holder = environment;
    (void)instance;
    if (holder->log) holder->log(holder->environment, (fmi3Status)status, category, message);
}

#define SYSTEM(c, call, ok) System *s = (c) ? ((Instance *)(c))->system : NULL; \
    if (!system_allowed(s, call, s && (ok))) return fmi3Error
/* 1 if every pointer the call needs was given; else 0, the refusal's reason kept for SYSTEM. */
static int given(fmi3Instance c, int all_given) {
    if (c && !all_given) ((Instance *)c)->system->refusal = "a pointer it needs is NULL";
    return all_given;
}
#define UNSUPPORTED(c, call) (fmi3Status)system_unsupported((c) ? ((Instance *)(c))->system : NULL, call)

const char *fmi3GetVersion(void) { return fmi3Version; }

fmi3Instance fmi3InstantiateCoSimulation(fmi3String instanceName, fmi3String instantiationToken,
                                         fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn,
                                         fmi3Boolean eventModeUsed, fmi3Boolean earlyReturnAllowed,
                                         const fmi3ValueReference requiredIntermediateVariables[],
                                         size_t nRequiredIntermediateVariables,
                                         fmi3InstanceEnvironment instanceEnvironment,
                                         fmi3LogMessageCallback logMessage,
                                         fmi3IntermediateUpdateCallback intermediateUpdate) {
    (void)visible, (void)earlyReturnAllowed, (void)requiredIntermediateVariables, (void)nRequiredIntermediateVariables;
    (void)intermediateUpdate;
    Instance *instance = calloc(1, sizeof *instance);
    if (!instance) return NULL;
    instance->log = logMessage, instance->environment = instanceEnvironment;
    if (eventModeUsed) {
        log_fmi3(instance, instanceName, fmi3Error, "logStatusError",
                 "fmi3InstantiateCoSimulation: this FMU has no event mode (hasEventMode = false)");
        free(instance);
        return NULL;
    }
    instance->system = system_new("fmi3", instanceName, instantiationToken, resourcePath, loggingOn, 0, log_fmi3,
                                  instance);
    if (!instance->system) {
        free(instance);
        return NULL;
    }
    return instance;
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName, fmi3String instantiationToken,
                                          fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn,
                                          fmi3InstanceEnvironment instanceEnvironment,
                                          fmi3LogMessageCallback logMessage) {
    (void)visible;
    Instance *instance = calloc(1, sizeof *instance);
    if (!instance) return NULL;
    instance->log = logMessage, instance->environment = instanceEnvironment;
    instance->system = system_new("fmi3", instanceName, instantiationToken, resourcePath, loggingOn, 1, log_fmi3,
                                  instance);
    if (!instance->system) {
        free(instance);
        return NULL;
    }
    return instance;
}

void fmi3FreeInstance(fmi3Instance instance) {
    if (!instance) return;
    system_free(((Instance *)instance)->system);
    free(instance);
}

fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean loggingOn, size_t nCategories,
                               const fmi3String categories[]) {
    (void)nCategories, (void)categories;
    SYSTEM(instance, "fmi3SetDebugLogging", 1);
    s->logging = loggingOn;
    return fmi3OK;
}

fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean toleranceDefined, fmi3Float64 tolerance,
                                       fmi3Float64 startTime, fmi3Boolean stopTimeDefined, fmi3Float64 stopTime) {
    SYSTEM(instance, "fmi3EnterInitializationMode", s->phase == PHASE_INSTANTIATED);
    const int setup = system_setup(s, toleranceDefined, tolerance, startTime, stopTimeDefined, stopTime);
    return (fmi3Status)(setup > 1 ? setup : system_enter(s));
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance instance) {
    SYSTEM(instance, "fmi3ExitInitializationMode", s->phase == PHASE_INITIALIZATION);
    return (fmi3Status)system_exit(s);
}

fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 currentCommunicationPoint, fmi3Float64 communicationStepSize,
                      fmi3Boolean noSetFMUStatePriorToCurrentPoint, fmi3Boolean *eventHandlingNeeded,
                      fmi3Boolean *terminateSimulation, fmi3Boolean *earlyReturn, fmi3Float64 *lastSuccessfulTime) {
    (void)noSetFMUStatePriorToCurrentPoint;
    SYSTEM(instance, "fmi3DoStep", given(instance, eventHandlingNeeded && terminateSimulation && earlyReturn &&
                                               lastSuccessfulTime) && s->phase == PHASE_STEPPING && system_interface_is(s, 0));
    const int status = system_do_step(s, currentCommunicationPoint, communicationStepSize);
    *eventHandlingNeeded = *terminateSimulation = *earlyReturn = fmi3False;
    *lastSuccessfulTime = system_time(s);
    return (fmi3Status)status;
}

fmi3Status fmi3Terminate(fmi3Instance instance) {
    SYSTEM(instance, "fmi3Terminate", s->phase == PHASE_STEPPING || s->phase == PHASE_FAILED);
    return (fmi3Status)system_terminate(s);
}

fmi3Status fmi3Reset(fmi3Instance instance) {
    SYSTEM(instance, "fmi3Reset", 1);
    return (fmi3Status)system_reset(s);
}

/* Scalars: one value per reference, each passed on to the instance whose it is (the worst status,
 * stopping at an error); a Boolean through FMI 2.0's int. */
#define VALUES(call, ok)                                                                           \
    SYSTEM(instance, call, (ok) && system_values_allowed(s, strncmp(call, "fmi3Set", 7) == 0) &&     \
           (nValueReferences == 0 || (valueReferences && values)));                                \
    if (nValues != nValueReferences) {                                                             \
        say(s, fmi2Error, "logStatusError", "%s: %zu values for %zu references (scalars only)", call, nValues, \
            nValueReferences);                                                                     \
        return fmi3Error;                                                                          \
    }                                                                                              \
    fmi3Status worst = fmi3OK

#define EACH(status_expression)                                                                    \
    for (size_t i = 0; i < nValueReferences && worst <= fmi3Warning; i++) {                        \
        const fmi3Status status = (fmi3Status)(status_expression);                                 \
        if (status > worst) worst = status;                                                        \
    }                                                                                              \
    return worst

fmi3Status fmi3GetFloat64(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                          fmi3Float64 values[], size_t nValues) {
    VALUES("fmi3GetFloat64", 1);
    const unsigned time_vr = (unsigned)s->n_variables;
    EACH(valueReferences[i] == time_vr ? (values[i] = system_time(s), 0)
                                       : system_get(s, "fmi3GetFloat64", 'r', valueReferences[i], &values[i]));
}
fmi3Status fmi3SetFloat64(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                          const fmi3Float64 values[], size_t nValues) {
    VALUES("fmi3SetFloat64", 1);
    EACH(system_set(s, "fmi3SetFloat64", 'r', valueReferences[i], &values[i]));
}
fmi3Status fmi3GetInt32(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                        fmi3Int32 values[], size_t nValues) {
    VALUES("fmi3GetInt32", 1);
    EACH(system_get(s, "fmi3GetInt32", 'i', valueReferences[i], &values[i]));
}
fmi3Status fmi3SetInt32(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                        const fmi3Int32 values[], size_t nValues) {
    VALUES("fmi3SetInt32", 1);
    EACH(system_set(s, "fmi3SetInt32", 'i', valueReferences[i], &values[i]));
}
fmi3Status fmi3GetBoolean(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                          fmi3Boolean values[], size_t nValues) {
    VALUES("fmi3GetBoolean", 1);
    for (size_t i = 0; i < nValueReferences && worst <= fmi3Warning; i++) {
        int flag = 0;
        const fmi3Status status = (fmi3Status)system_get(s, "fmi3GetBoolean", 'b', valueReferences[i], &flag);
        values[i] = flag != 0;
        if (status > worst) worst = status;
    }
    return worst;
}
fmi3Status fmi3SetBoolean(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                          const fmi3Boolean values[], size_t nValues) {
    VALUES("fmi3SetBoolean", 1);
    int flag = 0;
    EACH((flag = values[i] ? 1 : 0, system_set(s, "fmi3SetBoolean", 'b', valueReferences[i], &flag)));
}
fmi3Status fmi3GetString(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                         fmi3String values[], size_t nValues) {
    VALUES("fmi3GetString", 1);
    EACH(system_get(s, "fmi3GetString", 's', valueReferences[i], &values[i]));
}
fmi3Status fmi3SetString(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                         const fmi3String values[], size_t nValues) {
    VALUES("fmi3SetString", 1);
    EACH(system_set(s, "fmi3SetString", 's', valueReferences[i], &values[i]));
}

/* ---- Model Exchange (system_me.c) ---- */

#define MODEL_EXCHANGE(s) system_interface_is(s, 1)

fmi3Status fmi3EnterEventMode(fmi3Instance instance) {
    SYSTEM(instance, "fmi3EnterEventMode", s->phase == PHASE_STEPPING && MODEL_EXCHANGE(s));
    return (fmi3Status)system_me_enter_event_mode(s);
}

fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean *discreteStatesNeedUpdate,
                                    fmi3Boolean *terminateSimulation, fmi3Boolean *nominalsOfContinuousStatesChanged,
                                    fmi3Boolean *valuesOfContinuousStatesChanged, fmi3Boolean *nextEventTimeDefined,
                                    fmi3Float64 *nextEventTime) {
    SYSTEM(instance, "fmi3UpdateDiscreteStates", s->phase == PHASE_STEPPING && MODEL_EXCHANGE(s) &&
                                                 system_mode_is(s, 0));
    int terminate, changed;
    double next;
    const fmi3Status status = (fmi3Status)system_me_new_discrete_states(s, &terminate, &changed, &next);
    if (discreteStatesNeedUpdate) *discreteStatesNeedUpdate = fmi3False; /* each instance was iterated through */
    if (terminateSimulation) *terminateSimulation = terminate ? fmi3True : fmi3False;
    if (nominalsOfContinuousStatesChanged) *nominalsOfContinuousStatesChanged = fmi3False;
    if (valuesOfContinuousStatesChanged) *valuesOfContinuousStatesChanged = changed ? fmi3True : fmi3False;
    if (nextEventTimeDefined) *nextEventTimeDefined = next < INFINITY ? fmi3True : fmi3False;
    if (nextEventTime) *nextEventTime = next < INFINITY ? next : 0.0;
    return status;
}

fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance instance) {
    SYSTEM(instance, "fmi3EnterContinuousTimeMode", s->phase == PHASE_STEPPING && MODEL_EXCHANGE(s) &&
                                                    system_mode_is(s, 0));
    return (fmi3Status)system_me_enter_continuous_time_mode(s);
}

fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi3Boolean *enterEventMode, fmi3Boolean *terminateSimulation) {
    (void)noSetFMUStatePriorToCurrentPoint;
    SYSTEM(instance, "fmi3CompletedIntegratorStep", s->phase == PHASE_STEPPING && MODEL_EXCHANGE(s) &&
                                                    system_mode_is(s, 1) && enterEventMode && terminateSimulation);
    int event, terminate;
    const fmi3Status status = (fmi3Status)system_me_completed_integrator_step(s, &event, &terminate);
    *enterEventMode = event ? fmi3True : fmi3False;
    *terminateSimulation = terminate ? fmi3True : fmi3False;
    return status;
}

fmi3Status fmi3SetTime(fmi3Instance instance, fmi3Float64 time) {
    SYSTEM(instance, "fmi3SetTime", s->phase == PHASE_STEPPING && MODEL_EXCHANGE(s));
    return (fmi3Status)system_me_set_time(s, time);
}

fmi3Status fmi3SetContinuousStates(fmi3Instance instance, const fmi3Float64 continuousStates[],
                                   size_t nContinuousStates) {
    SYSTEM(instance, "fmi3SetContinuousStates", s->phase == PHASE_STEPPING && MODEL_EXCHANGE(s) &&
                                                system_mode_is(s, 1));
    return (fmi3Status)system_me_set_states(s, continuousStates, nContinuousStates);
}

fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance instance, fmi3Float64 derivatives[],
                                             size_t nContinuousStates) {
    SYSTEM(instance, "fmi3GetContinuousStateDerivatives", (s->phase == PHASE_STEPPING ||
                                                           s->phase == PHASE_TERMINATED) && MODEL_EXCHANGE(s));
    return (fmi3Status)system_me_get_derivatives(s, derivatives, nContinuousStates);
}

fmi3Status fmi3GetEventIndicators(fmi3Instance instance, fmi3Float64 eventIndicators[], size_t nEventIndicators) {
    (void)eventIndicators;
    SYSTEM(instance, "fmi3GetEventIndicators", (s->phase == PHASE_STEPPING || s->phase == PHASE_INITIALIZATION) &&
                                               MODEL_EXCHANGE(s));
    if (nEventIndicators != 0) {
        say(s, fmi2Error, "logStatusError", "fmi3GetEventIndicators: %zu values, and the system has no event "
            "indicators", nEventIndicators);
        return fmi3Error;
    }
    return fmi3OK;
}

fmi3Status fmi3GetContinuousStates(fmi3Instance instance, fmi3Float64 continuousStates[], size_t nContinuousStates) {
    SYSTEM(instance, "fmi3GetContinuousStates", (s->phase == PHASE_STEPPING || s->phase == PHASE_INITIALIZATION ||
                                                 s->phase == PHASE_TERMINATED) && MODEL_EXCHANGE(s));
    return (fmi3Status)system_me_get_states(s, continuousStates, nContinuousStates);
}

fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance instance, fmi3Float64 nominals[],
                                             size_t nContinuousStates) {
    SYSTEM(instance, "fmi3GetNominalsOfContinuousStates", s->phase != PHASE_FAILED && MODEL_EXCHANGE(s));
    return (fmi3Status)system_me_get_nominals(s, nominals, nContinuousStates);
}

fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t *nEventIndicators) {
    SYSTEM(instance, "fmi3GetNumberOfEventIndicators", given(instance, nEventIndicators != NULL));
    *nEventIndicators = 0;
    return fmi3OK;
}

fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t *nContinuousStates) {
    SYSTEM(instance, "fmi3GetNumberOfContinuousStates", given(instance, nContinuousStates != NULL));
    *nContinuousStates = (size_t)(s->model_exchange ? s->n_states : 0);
    return fmi3OK;
}

/* ---- what this FMU does not offer ---- */

fmi3Instance fmi3InstantiateScheduledExecution(fmi3String instanceName, fmi3String instantiationToken,
                                               fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn,
                                               fmi3InstanceEnvironment instanceEnvironment,
                                               fmi3LogMessageCallback logMessage, fmi3ClockUpdateCallback clockUpdate,
                                               fmi3LockPreemptionCallback lockPreemption,
                                               fmi3UnlockPreemptionCallback unlockPreemption) {
    (void)instanceName;
    (void)instantiationToken, (void)resourcePath, (void)visible, (void)loggingOn, (void)instanceEnvironment,
        (void)logMessage, (void)clockUpdate, (void)lockPreemption, (void)unlockPreemption;
    return NULL;
}
fmi3Status fmi3GetFloat32(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                          fmi3Float32 values[], size_t nValues) {
    (void)valueReferences, (void)nValueReferences, (void)values, (void)nValues;
    return UNSUPPORTED(instance, "fmi3GetFloat32");
}
fmi3Status fmi3GetInt8(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                       fmi3Int8 values[], size_t nValues) {
    (void)valueReferences, (void)nValueReferences, (void)values, (void)nValues;
    return UNSUPPORTED(instance, "fmi3GetInt8");
}
fmi3Status fmi3GetUInt8(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                        fmi3UInt8 values[], size_t nValues) {
    (void)valueReferences, (void)nValueReferences, (void)values, (void)nValues;
    return UNSUPPORTED(instance, "fmi3GetUInt8");
}
fmi3Status fmi3GetInt16(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                        fmi3Int16 values[], size_t nValues) {
    (void)valueReferences, (void)nValueReferences, (void)values, (void)nValues;
    return UNSUPPORTED(instance, "fmi3GetInt16");
}
fmi3Status fmi3GetUInt16(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                         fmi3UInt16 values[], size_t nValues) {
    (void)valueReferences, (void)nValueReferences, (void)values, (void)nValues;
    return UNSUPPORTED(instance, "fmi3GetUInt16");
}
fmi3Status fmi3GetUInt32(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                         fmi3UInt32 values[], size_t nValues) {
    (void)valueReferences, (void)nValueReferences, (void)values, (void)nValues;
    return UNSUPPORTED(instance, "fmi3GetUInt32");
}
fmi3Status fmi3GetInt64(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                        fmi3Int64 values[], size_t nValues) {
    (void)valueReferences, (void)nValueReferences, (void)values, (void)nValues;
    return UNSUPPORTED(instance, "fmi3GetInt64");
}
fmi3Status fmi3GetUInt64(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                         fmi3UInt64 values[], size_t nValues) {
    (void)valueReferences, (void)nValueReferences, (void)values, (void)nValues;
    return UNSUPPORTED(instance, "fmi3GetUInt64");
}
fmi3Status fmi3GetBinary(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                         size_t valueSizes[], fmi3Binary values[], size_t nValues) {
    (void)valueReferences, (void)nValueReferences, (void)valueSizes, (void)values, (void)nValues;
    return UNSUPPORTED(instance, "fmi3GetBinary");
}
fmi3Status fmi3GetClock(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                        fmi3Clock values[]) {
    (void)valueReferences, (void)nValueReferences, (void)values;
    return UNSUPPORTED(instance, "fmi3GetClock");
}
fmi3Status fmi3SetFloat32(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                          const fmi3Float32 values[], size_t nValues) {
    (void)valueReferences, (void)nValueReferences, (void)values, (void)nValues;
    return UNSUPPORTED(instance, "fmi3SetFloat32");
}
fmi3Status fmi3SetInt8(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                       const fmi3Int8 values[], size_t nValues) {
    (void)valueReferences, (void)nValueReferences, (void)values, (void)nValues;
    return UNSUPPORTED(instance, "fmi3SetInt8");
}
fmi3Status fmi3SetUInt8(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                        const fmi3UInt8 values[], size_t nValues) {
    (void)valueReferences, (void)nValueReferences, (void)values, (void)nValues;
    return UNSUPPORTED(instance, "fmi3SetUInt8");
}
fmi3Status fmi3SetInt16(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                        const fmi3Int16 values[], size_t nValues) {
    (void)valueReferences, (void)nValueReferences, (void)values, (void)nValues;
    return UNSUPPORTED(instance, "fmi3SetInt16");
}
fmi3Status fmi3SetUInt16(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                         const fmi3UInt16 values[], size_t nValues) {
    (void)valueReferences, (void)nValueReferences, (void)values, (void)nValues;
    return UNSUPPORTED(instance, "fmi3SetUInt16");
}
fmi3Status fmi3SetUInt32(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                         const fmi3UInt32 values[], size_t nValues) {
    (void)valueReferences, (void)nValueReferences, (void)values, (void)nValues;
    return UNSUPPORTED(instance, "fmi3SetUInt32");
}
fmi3Status fmi3SetInt64(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                        const fmi3Int64 values[], size_t nValues) {
    (void)valueReferences, (void)nValueReferences, (void)values, (void)nValues;
    return UNSUPPORTED(instance, "fmi3SetInt64");
}
fmi3Status fmi3SetUInt64(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                         const fmi3UInt64 values[], size_t nValues) {
    (void)valueReferences, (void)nValueReferences, (void)values, (void)nValues;
    return UNSUPPORTED(instance, "fmi3SetUInt64");
}
fmi3Status fmi3SetBinary(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                         const size_t valueSizes[], const fmi3Binary values[], size_t nValues) {
    (void)valueReferences, (void)nValueReferences, (void)valueSizes, (void)values, (void)nValues;
    return UNSUPPORTED(instance, "fmi3SetBinary");
}
fmi3Status fmi3SetClock(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                        const fmi3Clock values[]) {
    (void)valueReferences, (void)nValueReferences, (void)values;
    return UNSUPPORTED(instance, "fmi3SetClock");
}
fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance instance, fmi3ValueReference valueReference,
                                               size_t* nDependencies) {
    (void)valueReference, (void)nDependencies;
    return UNSUPPORTED(instance, "fmi3GetNumberOfVariableDependencies");
}
fmi3Status fmi3GetVariableDependencies(fmi3Instance instance, fmi3ValueReference dependent,
                                       size_t elementIndicesOfDependent[], fmi3ValueReference independents[],
                                       size_t elementIndicesOfIndependents[], fmi3DependencyKind dependencyKinds[],
                                       size_t nDependencies) {
    (void)dependent, (void)elementIndicesOfDependent, (void)independents, (void)elementIndicesOfIndependents,
        (void)dependencyKinds, (void)nDependencies;
    return UNSUPPORTED(instance, "fmi3GetVariableDependencies");
}
fmi3Status fmi3GetFMUState(fmi3Instance instance, fmi3FMUState* FMUState) {
    (void)FMUState;
    return UNSUPPORTED(instance, "fmi3GetFMUState");
}
fmi3Status fmi3SetFMUState(fmi3Instance instance, fmi3FMUState FMUState) {
    (void)FMUState;
    return UNSUPPORTED(instance, "fmi3SetFMUState");
}
fmi3Status fmi3FreeFMUState(fmi3Instance instance, fmi3FMUState* FMUState) {
    (void)FMUState;
    return UNSUPPORTED(instance, "fmi3FreeFMUState");
}
fmi3Status fmi3SerializedFMUStateSize(fmi3Instance instance, fmi3FMUState FMUState, size_t* size) {
    (void)FMUState, (void)size;
    return UNSUPPORTED(instance, "fmi3SerializedFMUStateSize");
}
fmi3Status fmi3SerializeFMUState(fmi3Instance instance, fmi3FMUState FMUState, fmi3Byte serializedState[],
                                 size_t size) {
    (void)FMUState, (void)serializedState, (void)size;
    return UNSUPPORTED(instance, "fmi3SerializeFMUState");
}
fmi3Status fmi3DeserializeFMUState(fmi3Instance instance, const fmi3Byte serializedState[], size_t size,
                                   fmi3FMUState* FMUState) {
    (void)serializedState, (void)size, (void)FMUState;
    return UNSUPPORTED(instance, "fmi3DeserializeFMUState");
}
fmi3Status fmi3GetDirectionalDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[], size_t nUnknowns,
                                        const fmi3ValueReference knowns[], size_t nKnowns, const fmi3Float64 seed[],
                                        size_t nSeed, fmi3Float64 sensitivity[], size_t nSensitivity) {
    (void)unknowns, (void)nUnknowns, (void)knowns, (void)nKnowns, (void)seed, (void)nSeed, (void)sensitivity,
        (void)nSensitivity;
    return UNSUPPORTED(instance, "fmi3GetDirectionalDerivative");
}
fmi3Status fmi3GetAdjointDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[], size_t nUnknowns,
                                    const fmi3ValueReference knowns[], size_t nKnowns, const fmi3Float64 seed[],
                                    size_t nSeed, fmi3Float64 sensitivity[], size_t nSensitivity) {
    (void)unknowns, (void)nUnknowns, (void)knowns, (void)nKnowns, (void)seed, (void)nSeed, (void)sensitivity,
        (void)nSensitivity;
    return UNSUPPORTED(instance, "fmi3GetAdjointDerivative");
}
fmi3Status fmi3EnterConfigurationMode(fmi3Instance instance) {
    return UNSUPPORTED(instance, "fmi3EnterConfigurationMode");
}
fmi3Status fmi3ExitConfigurationMode(fmi3Instance instance) {
    return UNSUPPORTED(instance, "fmi3ExitConfigurationMode");
}
fmi3Status fmi3GetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                  size_t nValueReferences, fmi3Float64 intervals[],
                                  fmi3IntervalQualifier qualifiers[]) {
    (void)valueReferences, (void)nValueReferences, (void)intervals, (void)qualifiers;
    return UNSUPPORTED(instance, "fmi3GetIntervalDecimal");
}
fmi3Status fmi3GetIntervalFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                   size_t nValueReferences, fmi3UInt64 counters[], fmi3UInt64 resolutions[],
                                   fmi3IntervalQualifier qualifiers[]) {
    (void)valueReferences, (void)nValueReferences, (void)counters, (void)resolutions, (void)qualifiers;
    return UNSUPPORTED(instance, "fmi3GetIntervalFraction");
}
fmi3Status fmi3GetShiftDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                               size_t nValueReferences, fmi3Float64 shifts[]) {
    (void)valueReferences, (void)nValueReferences, (void)shifts;
    return UNSUPPORTED(instance, "fmi3GetShiftDecimal");
}
fmi3Status fmi3GetShiftFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                size_t nValueReferences, fmi3UInt64 counters[], fmi3UInt64 resolutions[]) {
    (void)valueReferences, (void)nValueReferences, (void)counters, (void)resolutions;
    return UNSUPPORTED(instance, "fmi3GetShiftFraction");
}
fmi3Status fmi3SetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                  size_t nValueReferences, const fmi3Float64 intervals[]) {
    (void)valueReferences, (void)nValueReferences, (void)intervals;
    return UNSUPPORTED(instance, "fmi3SetIntervalDecimal");
}
fmi3Status fmi3SetIntervalFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                   size_t nValueReferences, const fmi3UInt64 counters[],
                                   const fmi3UInt64 resolutions[]) {
    (void)valueReferences, (void)nValueReferences, (void)counters, (void)resolutions;
    return UNSUPPORTED(instance, "fmi3SetIntervalFraction");
}
fmi3Status fmi3SetShiftDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                               size_t nValueReferences, const fmi3Float64 shifts[]) {
    (void)valueReferences, (void)nValueReferences, (void)shifts;
    return UNSUPPORTED(instance, "fmi3SetShiftDecimal");
}
fmi3Status fmi3SetShiftFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                size_t nValueReferences, const fmi3UInt64 counters[],
                                const fmi3UInt64 resolutions[]) {
    (void)valueReferences, (void)nValueReferences, (void)counters, (void)resolutions;
    return UNSUPPORTED(instance, "fmi3SetShiftFraction");
}
fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance instance) {
    return UNSUPPORTED(instance, "fmi3EvaluateDiscreteStates");
}
fmi3Status fmi3EnterStepMode(fmi3Instance instance) {
    return UNSUPPORTED(instance, "fmi3EnterStepMode");
}
fmi3Status fmi3GetOutputDerivatives(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                    size_t nValueReferences, const fmi3Int32 orders[], fmi3Float64 values[],
                                    size_t nValues) {
    (void)valueReferences, (void)nValueReferences, (void)orders, (void)values, (void)nValues;
    return UNSUPPORTED(instance, "fmi3GetOutputDerivatives");
}
fmi3Status fmi3ActivateModelPartition(fmi3Instance instance, fmi3ValueReference clockReference,
                                      fmi3Float64 activationTime) {
    (void)clockReference, (void)activationTime;
    return UNSUPPORTED(instance, "fmi3ActivateModelPartition");
}

