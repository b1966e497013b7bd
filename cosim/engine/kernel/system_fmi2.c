/* The system FMU's FMI 2.0 API, Co-Simulation or (where exported so) Model Exchange: each call
 * checked against the FMU's phase and passed to the system's life cycle (system_fmu.c, system_me.c). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"
#include "system.h"

static void log_fmi2(void *environment, const char *instance, int status, const char *category, const char *message) {
    const fmi2CallbackFunctions *callbacks = environment;
    if (callbacks->logger) callbacks->logger(callbacks->componentEnvironment, instance, (fmi2Status)status, category, message);
}

typedef struct { /* the instance an importer holds: the system and the importer's callbacks */
    System *system;
    fmi2CallbackFunctions callbacks;
} Instance;

#define SYSTEM(c, call, ok) System *s = (c) ? ((Instance *)(c))->system : NULL; \
    if (!system_allowed(s, call, s && (ok))) return fmi2Error

#define CO_SIMULATION(s) system_interface_is(s, 0)
#define MODEL_EXCHANGE(s) system_interface_is(s, 1)
#define mode_is system_mode_is

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation, const fmi2CallbackFunctions *functions,
                              fmi2Boolean visible, fmi2Boolean loggingOn) {
    (void)visible;
    if (!functions) return NULL;
    Instance *instance = calloc(1, sizeof *instance);
    if (!instance) return NULL;
    instance->callbacks = *functions;
    if (fmuType != fmi2CoSimulation && fmuType != fmi2ModelExchange) {
        log_fmi2(&instance->callbacks, instanceName, fmi2Error, "logStatusError",
                 "fmi2Instantiate: fmuType is neither fmi2ModelExchange nor fmi2CoSimulation");
        free(instance);
        return NULL;
    }
    instance->system = system_new("fmi2", instanceName, fmuGUID, fmuResourceLocation, loggingOn == fmi2True,
                                  fmuType == fmi2ModelExchange, log_fmi2, &instance->callbacks);
    if (!instance->system) {
        free(instance);
        return NULL;
    }
    return instance;
}

void fmi2FreeInstance(fmi2Component c) {
    if (!c) return;
    system_free(((Instance *)c)->system);
    free(c);
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    SYSTEM(c, "fmi2SetupExperiment", s->phase == PHASE_INSTANTIATED);
    return (fmi2Status)system_setup(s, toleranceDefined, tolerance, startTime, stopTimeDefined, stopTime);
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
    SYSTEM(c, "fmi2EnterInitializationMode", s->phase == PHASE_INSTANTIATED);
    return (fmi2Status)system_enter(s);
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    SYSTEM(c, "fmi2ExitInitializationMode", s->phase == PHASE_INITIALIZATION);
    return (fmi2Status)system_exit(s);
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint, fmi2Real communicationStepSize,
                      fmi2Boolean noSetFMUStatePriorToCurrentPoint) {
    (void)noSetFMUStatePriorToCurrentPoint;
    SYSTEM(c, "fmi2DoStep", s->phase == PHASE_STEPPING && CO_SIMULATION(s));
    return (fmi2Status)system_do_step(s, currentCommunicationPoint, communicationStepSize);
}

fmi2Status fmi2Terminate(fmi2Component c) {
    SYSTEM(c, "fmi2Terminate", s->phase == PHASE_STEPPING || s->phase == PHASE_FAILED);
    return (fmi2Status)system_terminate(s);
}

fmi2Status fmi2Reset(fmi2Component c) {
    SYSTEM(c, "fmi2Reset", 1);
    return (fmi2Status)system_reset(s);
}

/* Each value passed on to the instance whose it is; the worst status, stopping at an error. */
#define PASS_ON(call, kind, how, type)                                                             \
    SYSTEM(c, call, system_values_allowed(s, strncmp(call, "fmi2Set", 7) == 0) && (nvr == 0 || (vr && value))); \
    fmi2Status worst = fmi2OK;                                                                     \
    for (size_t i = 0; i < nvr; i++) {                                                             \
        const fmi2Status status = (fmi2Status)how(s, call, kind, vr[i], (type)&value[i]);         \
        if (status > worst) worst = status;                                                        \
        if (status > fmi2Warning) break;                                                           \
    }                                                                                              \
    return worst

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[]) {
    PASS_ON("fmi2GetReal", 'r', system_get, void *);
}
fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Integer value[]) {
    PASS_ON("fmi2GetInteger", 'i', system_get, void *);
}
fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Boolean value[]) {
    PASS_ON("fmi2GetBoolean", 'b', system_get, void *);
}
fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2String value[]) {
    PASS_ON("fmi2GetString", 's', system_get, void *);
}
fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[]) {
    PASS_ON("fmi2SetReal", 'r', system_set, const void *);
}
fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Integer value[]) {
    PASS_ON("fmi2SetInteger", 'i', system_set, const void *);
}
fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Boolean value[]) {
    PASS_ON("fmi2SetBoolean", 'b', system_set, const void *);
}
fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2String value[]) {
    PASS_ON("fmi2SetString", 's', system_set, const void *);
}

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[]) {
    (void)nCategories, (void)categories;
    SYSTEM(c, "fmi2SetDebugLogging", 1);
    s->logging = loggingOn == fmi2True;
    return fmi2OK;
}

/* ---- what this FMU does not offer (its modelDescription.xml says so) ---- */

#define UNSUPPORTED(call) return (fmi2Status)system_unsupported(c ? ((Instance *)c)->system : NULL, call)

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *state) {
    (void)state;
    UNSUPPORTED("fmi2GetFMUstate");
}
fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate state) {
    (void)state;
    UNSUPPORTED("fmi2SetFMUstate");
}
fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *state) {
    (void)state;
    UNSUPPORTED("fmi2FreeFMUstate");
}
fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate state, size_t *size) {
    (void)state, (void)size;
    UNSUPPORTED("fmi2SerializedFMUstateSize");
}
fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate state, fmi2Byte bytes[], size_t size) {
    (void)state, (void)bytes, (void)size;
    UNSUPPORTED("fmi2SerializeFMUstate");
}
fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte bytes[], size_t size, fmi2FMUstate *state) {
    (void)bytes, (void)size, (void)state;
    UNSUPPORTED("fmi2DeSerializeFMUstate");
}
fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference unknowns[], size_t n_unknowns,
                                        const fmi2ValueReference knowns[], size_t n_knowns, const fmi2Real seed[],
                                        fmi2Real sensitivity[]) {
    (void)unknowns, (void)n_unknowns, (void)knowns, (void)n_knowns, (void)seed, (void)sensitivity;
    UNSUPPORTED("fmi2GetDirectionalDerivative");
}
fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[]) {
    (void)vr, (void)nvr, (void)order, (void)value;
    UNSUPPORTED("fmi2SetRealInputDerivatives");
}
fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                        const fmi2Integer order[], fmi2Real value[]) {
    (void)vr, (void)nvr, (void)order, (void)value;
    UNSUPPORTED("fmi2GetRealOutputDerivatives");
}
fmi2Status fmi2CancelStep(fmi2Component c) { UNSUPPORTED("fmi2CancelStep"); }
fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind kind, fmi2Status *value) {
    (void)kind, (void)value;
    UNSUPPORTED("fmi2GetStatus");
}
fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind kind, fmi2Real *value) {
    (void)kind, (void)value;
    UNSUPPORTED("fmi2GetRealStatus");
}
fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind kind, fmi2Integer *value) {
    (void)kind, (void)value;
    UNSUPPORTED("fmi2GetIntegerStatus");
}
fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind kind, fmi2Boolean *value) {
    (void)kind, (void)value;
    UNSUPPORTED("fmi2GetBooleanStatus");
}
fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind kind, fmi2String *value) {
    (void)kind, (void)value;
    UNSUPPORTED("fmi2GetStringStatus");
}

/* ---- Model Exchange (system_me.c) ---- */

fmi2Status fmi2SetTime(fmi2Component c, fmi2Real time) {
    SYSTEM(c, "fmi2SetTime", s->phase == PHASE_STEPPING && MODEL_EXCHANGE(s));
    return (fmi2Status)system_me_set_time(s, time);
}

fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t nx) {
    SYSTEM(c, "fmi2SetContinuousStates", s->phase == PHASE_STEPPING && MODEL_EXCHANGE(s) && mode_is(s, 1));
    return (fmi2Status)system_me_set_states(s, x, nx);
}

fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t nx) {
    SYSTEM(c, "fmi2GetContinuousStates", (s->phase == PHASE_STEPPING || s->phase == PHASE_INITIALIZATION ||
                                          s->phase == PHASE_TERMINATED) && MODEL_EXCHANGE(s));
    return (fmi2Status)system_me_get_states(s, x, nx);
}

fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x_nominal[], size_t nx) {
    SYSTEM(c, "fmi2GetNominalsOfContinuousStates", s->phase != PHASE_FAILED && MODEL_EXCHANGE(s));
    return (fmi2Status)system_me_get_nominals(s, x_nominal, nx);
}

fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real derivatives[], size_t nx) {
    SYSTEM(c, "fmi2GetDerivatives", (s->phase == PHASE_STEPPING || s->phase == PHASE_TERMINATED) && MODEL_EXCHANGE(s));
    return (fmi2Status)system_me_get_derivatives(s, derivatives, nx);
}

fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real eventIndicators[], size_t ni) {
    (void)eventIndicators;
    SYSTEM(c, "fmi2GetEventIndicators", (s->phase == PHASE_STEPPING || s->phase == PHASE_INITIALIZATION) &&
                                        MODEL_EXCHANGE(s));
    if (ni != 0) {
        say(s, fmi2Error, "logStatusError", "fmi2GetEventIndicators: %zu values, and the system has no event indicators",
            ni);
        return fmi2Error;
    }
    return fmi2OK;
}

fmi2Status fmi2EnterEventMode(fmi2Component c) {
    SYSTEM(c, "fmi2EnterEventMode", s->phase == PHASE_STEPPING && MODEL_EXCHANGE(s));
    return (fmi2Status)system_me_enter_event_mode(s);
}

fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo *info) {
    SYSTEM(c, "fmi2NewDiscreteStates", s->phase == PHASE_STEPPING && MODEL_EXCHANGE(s) && mode_is(s, 0) && info);
    int terminate, changed;
    double next;
    const fmi2Status status = (fmi2Status)system_me_new_discrete_states(s, &terminate, &changed, &next);
    info->newDiscreteStatesNeeded = fmi2False; /* each instance was iterated through */
    info->terminateSimulation = terminate ? fmi2True : fmi2False;
    info->nominalsOfContinuousStatesChanged = fmi2False;
    info->valuesOfContinuousStatesChanged = changed ? fmi2True : fmi2False;
    info->nextEventTimeDefined = next < INFINITY ? fmi2True : fmi2False;
    info->nextEventTime = next < INFINITY ? next : 0.0;
    return status;
}

fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c) {
    SYSTEM(c, "fmi2EnterContinuousTimeMode", s->phase == PHASE_STEPPING && MODEL_EXCHANGE(s) && mode_is(s, 0));
    return (fmi2Status)system_me_enter_continuous_time_mode(s);
}

fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi2Boolean *enterEventMode, fmi2Boolean *terminateSimulation) {
    (void)noSetFMUStatePriorToCurrentPoint;
    SYSTEM(c, "fmi2CompletedIntegratorStep", s->phase == PHASE_STEPPING && MODEL_EXCHANGE(s) && mode_is(s, 1) &&
                                             enterEventMode && terminateSimulation);
    int event, terminate;
    const fmi2Status status = (fmi2Status)system_me_completed_integrator_step(s, &event, &terminate);
    *enterEventMode = event ? fmi2True : fmi2False;
    *terminateSimulation = terminate ? fmi2True : fmi2False;
    return status;
}
