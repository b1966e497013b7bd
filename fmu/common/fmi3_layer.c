/* The FMI 3.0 Co-Simulation layer: the same model, through the FMI 2.0 layer (fmi2_layer.c) it is
 * compiled with. Each fmi3 entry point maps onto its fmi2 twin: the instance is the FMI 2.0
 * layer's, its call-sequence checks, validation, logging and FMU state are that layer's; what
 * FMI 3.0 adds or names differently is translated here (types, instantiation, the initialization
 * mode's experiment, fmi3DoStep's flags).
 *
 * What the FMUs use of FMI 3.0 and what they leave out, and why:
 * - Co-Simulation only, without event mode (hasEventMode = false): the models have no events or
 *   clocks a master would need to handle; Model Exchange and Scheduled Execution return NULL.
 * - No intermediate update and no early return: fmi3DoStep always completes its step (the FMI 2.0
 *   models' step is one exact or fixed-step integration).
 * - Scalar variables only (no arrays, no structural parameters, no configuration mode): the
 *   variable tables are scalars; Float64, Int32, Boolean and String, as Real, Integer, Boolean and
 *   String in FMI 2.0 with the same names, value references, units and starts.
 * - Output derivatives (fmi3GetOutputDerivatives) as in FMI 2.0. FMI 3.0 has no input
 *   derivatives: each Real input's first and second derivative over the next step are inputs of
 *   their own, fmi.rate.<input> and fmi.curvature.<input> (FMU_INPUT_DERIVATIVE_VR), set as
 *   fmi2SetRealInputDerivatives sets them; an instance given none holds its inputs over a step
 *   (or extrapolates them itself: fmi.extrapolate_inputs).
 * - FMU state get, set and serialization (the FMI 2.0 layer's checksummed state).
 * The binary exports the fmi2 entry points too (the layer it is built on); tools load the fmi3 ones.
 */
#include "fmu_common.h"

#include "fmi3Functions.h"

#include <ctype.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* The FMI 3.0 importer's logger, held for the FMI 2.0 layer's callbacks. */
typedef struct {
    fmi3LogMessageCallback log;
    fmi3InstanceEnvironment environment;
} Logger;

/* The FMI 2.0 calls FMI 3.0 names otherwise; any other fmi2X is fmi3X. */
static const char *const RENAMED[][2] = {
    {"fmi2GetReal", "fmi3GetFloat64"}, {"fmi2SetReal", "fmi3SetFloat64"}, {"fmi2GetInteger", "fmi3GetInt32"},
    {"fmi2SetInteger", "fmi3SetInt32"}, {"fmi2GetFMUstate", "fmi3GetFMUState"}, {"fmi2SetFMUstate", "fmi3SetFMUState"},
    {"fmi2FreeFMUstate", "fmi3FreeFMUState"}, {"fmi2SerializedFMUstateSize", "fmi3SerializedFMUStateSize"},
    {"fmi2SerializeFMUstate", "fmi3SerializeFMUState"}, {"fmi2DeSerializeFMUstate", "fmi3DeserializeFMUState"},
    {"fmi2SetupExperiment", "fmi3EnterInitializationMode"}, {"fmi2NewDiscreteStates", "fmi3UpdateDiscreteStates"},
    {"fmi2GetRealOutputDerivatives", "fmi3GetOutputDerivatives"},
    {"fmi2SetRealInputDerivatives", "fmi3SetFloat64 (fmi.rate.*, fmi.curvature.*)"},
    {"fmi2GetDerivatives", "fmi3GetContinuousStateDerivatives"}};

/* The message as an FMI 3.0 importer reads it: each fmi2 call named as the FMI 3.0 call that reached
 * it, and the FMI 2.0 layer's '%' escape (for importers that treat the message as a format) undone. */
static void as_fmi3(const char *message, char *out, size_t size) {
    size_t j = 0;
    for (size_t i = 0; message[i] && j + 1 < size;) {
        if (message[i] == '%' && message[i + 1] == '%') i++;
        size_t n = 0; /* the length of an fmi2 call's name here, 0 if none */
        if (strncmp(message + i, "fmi2", 4) == 0)
            for (n = 4; isalnum((unsigned char)message[i + n]); n++) continue;
        if (n == 0) {
            out[j++] = message[i++];
            continue;
        }
        const char *name = NULL;
        for (size_t k = 0; k < sizeof RENAMED / sizeof RENAMED[0] && !name; k++)
            if (strlen(RENAMED[k][0]) == n && strncmp(message + i, RENAMED[k][0], n) == 0) name = RENAMED[k][1];
        char plain[96];
        if (!name) { /* fmi2X: fmi3X */
            snprintf(plain, sizeof plain, "fmi3%.*s", (int)(n - 4 < 80 ? n - 4 : 80), message + i + 4);
            name = plain;
        }
        for (const char *c = name; *c && j + 1 < size; c++) out[j++] = *c;
        i += n;
    }
    out[j] = '\0';
}

static void log_through(fmi2ComponentEnvironment environment, fmi2String instance_name, fmi2Status status,
                        fmi2String category, fmi2String message, ...) {
    (void)instance_name;
    const Logger *logger = (const Logger *)environment;
    if (!logger || !logger->log) return;
    char plain[2048];
    as_fmi3(message, plain, sizeof plain);
    logger->log(logger->environment, (fmi3Status)status, category, plain);
}

static FmuInstance *fmu_of(fmi3Instance instance) { return (FmuInstance *)instance; }

static fmi3Status refuse(fmi3Instance instance, const char *what) {
    if (instance) fmu_log(fmu_of(instance), fmi2Error, "logStatusError", "%s", what);
    return fmi3Error;
}

/* Scalars only: a get or set call passes one value per reference. */
static int scalars(fmi3Instance instance, const char *call, size_t n_references, size_t n_values) {
    if (n_references == n_values) return 1;
    if (instance)
        fmu_log(fmu_of(instance), fmi2Error, "logStatusError", "%s: %zu values for %zu value references: every "
                "variable is a scalar", call, n_values, n_references);
    return 0;
}

/* ---- instances ---- */

const char *fmi3GetVersion(void) { return fmi3Version; }

fmi3Status fmi3SetDebugLogging(fmi3Instance instance, fmi3Boolean loggingOn, size_t nCategories,
                               const fmi3String categories[]) {
    return (fmi3Status)fmi2SetDebugLogging(instance, loggingOn, nCategories, categories);
}

fmi3Instance fmi3InstantiateCoSimulation(fmi3String instanceName, fmi3String instantiationToken,
                                         fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn,
                                         fmi3Boolean eventModeUsed, fmi3Boolean earlyReturnAllowed,
                                         const fmi3ValueReference requiredIntermediateVariables[],
                                         size_t nRequiredIntermediateVariables,
                                         fmi3InstanceEnvironment instanceEnvironment, fmi3LogMessageCallback logMessage,
                                         fmi3IntermediateUpdateCallback intermediateUpdate) {
    (void)earlyReturnAllowed, (void)requiredIntermediateVariables, (void)intermediateUpdate;
    Logger *logger = (Logger *)calloc(1, sizeof(Logger));
    if (!logger) return NULL;
    logger->log = logMessage, logger->environment = instanceEnvironment;
    if (eventModeUsed || nRequiredIntermediateVariables > 0) {
        if (logMessage)
            logMessage(instanceEnvironment, fmi3Error, "logStatusError", eventModeUsed ?
                       "fmi3InstantiateCoSimulation: this FMU has no event mode (hasEventMode = false)" :
                       "fmi3InstantiateCoSimulation: this FMU provides no intermediate update");
        free(logger);
        return NULL;
    }
    const fmi2CallbackFunctions callbacks = {log_through, calloc, free, NULL, logger};
    fmi2Component c = fmi2Instantiate(instanceName, fmi2CoSimulation, instantiationToken, resourcePath, &callbacks,
                                      visible, loggingOn);
    if (!c) free(logger);
    return c;
}

fmi3Instance fmi3InstantiateModelExchange(fmi3String instanceName, fmi3String instantiationToken,
                                          fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn,
                                          fmi3InstanceEnvironment instanceEnvironment,
                                          fmi3LogMessageCallback logMessage) {
    if (!MODEL_MODEL_EXCHANGE) {
        if (logMessage)
            logMessage(instanceEnvironment, fmi3Error, "logStatusError",
                       "fmi3InstantiateModelExchange: this FMU is for Co-Simulation only");
        return NULL;
    }
    Logger *logger = (Logger *)calloc(1, sizeof(Logger));
    if (!logger) return NULL;
    logger->log = logMessage, logger->environment = instanceEnvironment;
    const fmi2CallbackFunctions callbacks = {log_through, calloc, free, NULL, logger};
    fmi2Component c = fmi2Instantiate(instanceName, fmi2ModelExchange, instantiationToken, resourcePath, &callbacks,
                                      visible, loggingOn);
    if (!c) free(logger);
    return c;
}

fmi3Instance fmi3InstantiateScheduledExecution(fmi3String instanceName, fmi3String instantiationToken,
                                               fmi3String resourcePath, fmi3Boolean visible, fmi3Boolean loggingOn,
                                               fmi3InstanceEnvironment instanceEnvironment,
                                               fmi3LogMessageCallback logMessage, fmi3ClockUpdateCallback clockUpdate,
                                               fmi3LockPreemptionCallback lockPreemption,
                                               fmi3UnlockPreemptionCallback unlockPreemption) {
    (void)instanceName, (void)instantiationToken, (void)resourcePath, (void)visible, (void)loggingOn;
    (void)clockUpdate, (void)lockPreemption, (void)unlockPreemption;
    if (logMessage)
        logMessage(instanceEnvironment, fmi3Error, "logStatusError",
                   "fmi3InstantiateScheduledExecution: this FMU is for Co-Simulation only");
    return NULL;
}

void fmi3FreeInstance(fmi3Instance instance) {
    if (!instance) return;
    Logger *logger = (Logger *)fmu_of(instance)->callbacks.componentEnvironment;
    fmi2FreeInstance(instance);
    free(logger);
}

fmi3Status fmi3EnterInitializationMode(fmi3Instance instance, fmi3Boolean toleranceDefined, fmi3Float64 tolerance,
                                       fmi3Float64 startTime, fmi3Boolean stopTimeDefined, fmi3Float64 stopTime) {
    const fmi2Status setup = fmi2SetupExperiment(instance, toleranceDefined, tolerance, startTime, stopTimeDefined,
                                                 stopTime);
    return setup > fmi2Warning ? (fmi3Status)setup : (fmi3Status)fmi2EnterInitializationMode(instance);
}

fmi3Status fmi3ExitInitializationMode(fmi3Instance instance) {
    return (fmi3Status)fmi2ExitInitializationMode(instance);
}

fmi3Status fmi3EnterEventMode(fmi3Instance instance) {
#if MODEL_MODEL_EXCHANGE
    if (instance && fmu_of(instance)->model_exchange) return (fmi3Status)fmi2EnterEventMode(instance);
#endif
    return refuse(instance, "fmi3EnterEventMode: this FMU has no event mode (hasEventMode = false)");
}

fmi3Status fmi3Terminate(fmi3Instance instance) { return (fmi3Status)fmi2Terminate(instance); }
fmi3Status fmi3Reset(fmi3Instance instance) { return (fmi3Status)fmi2Reset(instance); }

/* ---- get and set: Float64, Int32, Boolean and String are the FMI 2.0 layer's types ---- */

/* Is `vr` an input's derivative (fmi.rate.*, fmi.curvature.*)? Its input and order if so. */
static int input_derivative(fmi3ValueReference vr, fmi2ValueReference *input, fmi2Integer *order) {
    const unsigned of = vr % FMU_INPUT_DERIVATIVE_SPAN, k = vr / FMU_INPUT_DERIVATIVE_SPAN;
    if (k < 1 || k > 2 || of < 1 || of >= VR_COUNT || fmu_variables[of].causality != FMU_INPUT ||
        fmu_variables[of].type != FMU_REAL)
        return 0;
    *input = of, *order = (fmi2Integer)k;
    return 1;
}

static int any_input_derivative(const fmi3ValueReference references[], size_t n) {
    fmi2ValueReference input;
    fmi2Integer order;
    for (size_t i = 0; i < n && references; i++)
        if (input_derivative(references[i], &input, &order)) return 1;
    return 0;
}

/* A derivative's value as last set since the last step (0 where none was). */
static double derivative_value(fmi3Instance instance, fmi2ValueReference input, fmi2Integer order) {
    const FmuInstance *fmu = fmu_of(instance);
    return fmu->s.input_derivative_given[input] >= order ? fmu->s.input_derivative[input][order - 1] : 0.0;
}

/* Value reference 0 is the independent variable, time (FMI 3.0 lists it among the variables); the
 * inputs' derivatives read back as set. */
fmi3Status fmi3GetFloat64(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                          fmi3Float64 values[], size_t nValues) {
    if (!scalars(instance, "fmi3GetFloat64", nValueReferences, nValues)) return fmi3Error;
    int has_time = any_input_derivative(valueReferences, nValueReferences);
    for (size_t i = 0; i < nValueReferences && valueReferences; i++) has_time |= valueReferences[i] == 0;
    if (!has_time || !values) return (fmi3Status)fmi2GetReal(instance, valueReferences, nValueReferences, values);
    fmi2Status worst = fmi2OK;
    for (size_t i = 0; i < nValueReferences; i++) {
        fmi2ValueReference input;
        fmi2Integer order;
        const int derivative = input_derivative(valueReferences[i], &input, &order);
        const fmi2Status status = valueReferences[i] == 0 || derivative ? fmi2GetReal(instance, NULL, 0, NULL)
                                                          : fmi2GetReal(instance, &valueReferences[i], 1, &values[i]);
        if (status > fmi2Warning) return (fmi3Status)status;
        if (valueReferences[i] == 0) values[i] = fmu_of(instance)->s.time;
        if (derivative) values[i] = derivative_value(instance, input, order);
        worst = status > worst ? status : worst;
    }
    return (fmi3Status)worst;
}

/* Values, then the inputs' derivatives among them (as fmi2SetReal, then fmi2SetRealInputDerivatives:
 * each call checks all its references before it changes anything). */
fmi3Status fmi3SetFloat64(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                          const fmi3Float64 values[], size_t nValues) {
    if (!scalars(instance, "fmi3SetFloat64", nValueReferences, nValues)) return fmi3Error;
    if (!any_input_derivative(valueReferences, nValueReferences))
        return (fmi3Status)fmi2SetReal(instance, valueReferences, nValueReferences, values);
    enum { MOST = 4 * VR_COUNT };
    fmi2ValueReference plain[MOST], inputs[MOST];
    fmi2Real plain_values[MOST], derivatives[MOST];
    fmi2Integer orders[MOST];
    if (nValueReferences > MOST) return refuse(instance, "fmi3SetFloat64: more value references than the FMU has");
    if (!values) return refuse(instance, "fmi3SetFloat64: NULL array");
    size_t n_plain = 0, n_derivatives = 0;
    for (size_t i = 0; i < nValueReferences; i++) {
        if (input_derivative(valueReferences[i], &inputs[n_derivatives], &orders[n_derivatives])) {
            derivatives[n_derivatives++] = values[i];
        } else {
            plain[n_plain] = valueReferences[i];
            plain_values[n_plain++] = values[i];
        }
    }
    const fmi2Status set = fmi2SetReal(instance, plain, n_plain, plain_values);
    if (set > fmi2Warning) return (fmi3Status)set;
    const fmi2Status rates = fmi2SetRealInputDerivatives(instance, inputs, n_derivatives, orders, derivatives);
    return (fmi3Status)(rates > set ? rates : set);
}

fmi3Status fmi3GetInt32(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                        fmi3Int32 values[], size_t nValues) {
    if (!scalars(instance, "fmi3GetInt32", nValueReferences, nValues)) return fmi3Error;
    return (fmi3Status)fmi2GetInteger(instance, valueReferences, nValueReferences, (fmi2Integer *)values);
}

fmi3Status fmi3SetInt32(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                        const fmi3Int32 values[], size_t nValues) {
    if (!scalars(instance, "fmi3SetInt32", nValueReferences, nValues)) return fmi3Error;
    return (fmi3Status)fmi2SetInteger(instance, valueReferences, nValueReferences, (const fmi2Integer *)values);
}

/* fmi3Boolean is a C bool, fmi2Boolean an int: through a buffer of the FMI 2.0 type. */
enum { MOST_BOOLEANS = 64 };

fmi3Status fmi3GetBoolean(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                          fmi3Boolean values[], size_t nValues) {
    fmi2Boolean buffer[MOST_BOOLEANS];
    if (!scalars(instance, "fmi3GetBoolean", nValueReferences, nValues)) return fmi3Error;
    if (nValueReferences > MOST_BOOLEANS) return refuse(instance, "fmi3GetBoolean: more than 64 value references");
    if (nValueReferences > 0 && !values) return refuse(instance, "fmi3GetBoolean: NULL array");
    const fmi2Status status = fmi2GetBoolean(instance, valueReferences, nValueReferences, buffer);
    if (status <= fmi2Warning)
        for (size_t i = 0; i < nValueReferences; i++) values[i] = buffer[i] != fmi2False;
    return (fmi3Status)status;
}

fmi3Status fmi3SetBoolean(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                          const fmi3Boolean values[], size_t nValues) {
    fmi2Boolean buffer[MOST_BOOLEANS];
    if (!scalars(instance, "fmi3SetBoolean", nValueReferences, nValues)) return fmi3Error;
    if (nValueReferences > MOST_BOOLEANS) return refuse(instance, "fmi3SetBoolean: more than 64 value references");
    if (nValueReferences > 0 && !values) return refuse(instance, "fmi3SetBoolean: NULL array");
    for (size_t i = 0; i < nValueReferences; i++) buffer[i] = values[i] ? fmi2True : fmi2False;
    return (fmi3Status)fmi2SetBoolean(instance, valueReferences, nValueReferences, buffer);
}

fmi3Status fmi3GetString(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                         fmi3String values[], size_t nValues) {
    if (!scalars(instance, "fmi3GetString", nValueReferences, nValues)) return fmi3Error;
    return (fmi3Status)fmi2GetString(instance, valueReferences, nValueReferences, values);
}

fmi3Status fmi3SetString(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                         const fmi3String values[], size_t nValues) {
    if (!scalars(instance, "fmi3SetString", nValueReferences, nValues)) return fmi3Error;
    return (fmi3Status)fmi2SetString(instance, valueReferences, nValueReferences, values);
}

/* The types the tables have none of: no value reference is of them. */
#define NO_VARIABLES_OF(Type, call_name)                                                                         \
    static fmi3Status none_of_##Type(fmi3Instance instance, const fmi3ValueReference references[], size_t n) {  \
        if (n == 0) return fmi3OK;                                                                             \
        if (instance)                                                                                          \
            fmu_log(fmu_of(instance), fmi2Error, "logStatusError", "%s: this FMU has no " #Type " variables "  \
                    "(value reference %u is not one)", call_name, references ? (unsigned)references[0] : 0u); \
        return fmi3Error;                                                                                      \
    }
NO_VARIABLES_OF(Float32, "fmi3Get/SetFloat32")
NO_VARIABLES_OF(Int8, "fmi3Get/SetInt8")
NO_VARIABLES_OF(UInt8, "fmi3Get/SetUInt8")
NO_VARIABLES_OF(Int16, "fmi3Get/SetInt16")
NO_VARIABLES_OF(UInt16, "fmi3Get/SetUInt16")
NO_VARIABLES_OF(UInt32, "fmi3Get/SetUInt32")
NO_VARIABLES_OF(Int64, "fmi3Get/SetInt64")
NO_VARIABLES_OF(UInt64, "fmi3Get/SetUInt64")
NO_VARIABLES_OF(Binary, "fmi3Get/SetBinary")
NO_VARIABLES_OF(Clock, "fmi3Get/SetClock")

#define GET_SET_NONE(Type)                                                                                       \
    fmi3Status fmi3Get##Type(fmi3Instance instance, const fmi3ValueReference valueReferences[],                 \
                             size_t nValueReferences, fmi3##Type values[], size_t nValues) {                    \
        (void)values, (void)nValues;                                                                           \
        return none_of_##Type(instance, valueReferences, nValueReferences);                                    \
    }                                                                                                          \
    fmi3Status fmi3Set##Type(fmi3Instance instance, const fmi3ValueReference valueReferences[],                 \
                             size_t nValueReferences, const fmi3##Type values[], size_t nValues) {              \
        (void)values, (void)nValues;                                                                           \
        return none_of_##Type(instance, valueReferences, nValueReferences);                                    \
    }
GET_SET_NONE(Float32)
GET_SET_NONE(Int8)
GET_SET_NONE(UInt8)
GET_SET_NONE(Int16)
GET_SET_NONE(UInt16)
GET_SET_NONE(UInt32)
GET_SET_NONE(Int64)
GET_SET_NONE(UInt64)

fmi3Status fmi3GetBinary(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                         size_t valueSizes[], fmi3Binary values[], size_t nValues) {
    (void)valueSizes, (void)values, (void)nValues;
    return none_of_Binary(instance, valueReferences, nValueReferences);
}

fmi3Status fmi3SetBinary(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                         const size_t valueSizes[], const fmi3Binary values[], size_t nValues) {
    (void)valueSizes, (void)values, (void)nValues;
    return none_of_Binary(instance, valueReferences, nValueReferences);
}

fmi3Status fmi3GetClock(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                        fmi3Clock values[]) {
    (void)values;
    return none_of_Clock(instance, valueReferences, nValueReferences);
}

fmi3Status fmi3SetClock(fmi3Instance instance, const fmi3ValueReference valueReferences[], size_t nValueReferences,
                        const fmi3Clock values[]) {
    (void)values;
    return none_of_Clock(instance, valueReferences, nValueReferences);
}

/* ---- dependencies: in the modelDescription's ModelStructure ---- */

fmi3Status fmi3GetNumberOfVariableDependencies(fmi3Instance instance, fmi3ValueReference valueReference,
                                               size_t *nDependencies) {
    (void)valueReference, (void)nDependencies;
    return refuse(instance, "fmi3GetNumberOfVariableDependencies: not provided; the dependencies are in the "
                            "modelDescription's ModelStructure");
}

fmi3Status fmi3GetVariableDependencies(fmi3Instance instance, fmi3ValueReference dependent,
                                       size_t elementIndicesOfDependent[], fmi3ValueReference independents[],
                                       size_t elementIndicesOfIndependents[], fmi3DependencyKind dependencyKinds[],
                                       size_t nDependencies) {
    (void)dependent, (void)elementIndicesOfDependent, (void)independents, (void)elementIndicesOfIndependents;
    (void)dependencyKinds, (void)nDependencies;
    return refuse(instance, "fmi3GetVariableDependencies: not provided; the dependencies are in the "
                            "modelDescription's ModelStructure");
}

/* ---- FMU state: the FMI 2.0 layer's, tagged and checksummed ---- */

fmi3Status fmi3GetFMUState(fmi3Instance instance, fmi3FMUState *FMUState) {
    return (fmi3Status)fmi2GetFMUstate(instance, FMUState);
}

fmi3Status fmi3SetFMUState(fmi3Instance instance, fmi3FMUState FMUState) {
    return (fmi3Status)fmi2SetFMUstate(instance, FMUState);
}

fmi3Status fmi3FreeFMUState(fmi3Instance instance, fmi3FMUState *FMUState) {
    return (fmi3Status)fmi2FreeFMUstate(instance, FMUState);
}

fmi3Status fmi3SerializedFMUStateSize(fmi3Instance instance, fmi3FMUState FMUState, size_t *size) {
    return (fmi3Status)fmi2SerializedFMUstateSize(instance, FMUState, size);
}

fmi3Status fmi3SerializeFMUState(fmi3Instance instance, fmi3FMUState FMUState, fmi3Byte serializedState[],
                                 size_t size) {
    return (fmi3Status)fmi2SerializeFMUstate(instance, FMUState, (fmi2Byte *)serializedState, size);
}

fmi3Status fmi3DeserializeFMUState(fmi3Instance instance, const fmi3Byte serializedState[], size_t size,
                                   fmi3FMUState *FMUState) {
    return (fmi3Status)fmi2DeSerializeFMUstate(instance, (const fmi2Byte *)serializedState, size, FMUState);
}

/* ---- what these FMUs do not provide ---- */

fmi3Status fmi3GetDirectionalDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[], size_t nUnknowns,
                                        const fmi3ValueReference knowns[], size_t nKnowns, const fmi3Float64 seed[],
                                        size_t nSeed, fmi3Float64 sensitivity[], size_t nSensitivity) {
    (void)unknowns, (void)nUnknowns, (void)knowns, (void)nKnowns, (void)seed, (void)nSeed, (void)sensitivity;
    (void)nSensitivity;
    return refuse(instance, "fmi3GetDirectionalDerivative: not provided (providesDirectionalDerivatives = false)");
}

fmi3Status fmi3GetAdjointDerivative(fmi3Instance instance, const fmi3ValueReference unknowns[], size_t nUnknowns,
                                    const fmi3ValueReference knowns[], size_t nKnowns, const fmi3Float64 seed[],
                                    size_t nSeed, fmi3Float64 sensitivity[], size_t nSensitivity) {
    (void)unknowns, (void)nUnknowns, (void)knowns, (void)nKnowns, (void)seed, (void)nSeed, (void)sensitivity;
    (void)nSensitivity;
    return refuse(instance, "fmi3GetAdjointDerivative: not provided (providesAdjointDerivatives = false)");
}

fmi3Status fmi3EnterConfigurationMode(fmi3Instance instance) {
    return refuse(instance, "fmi3EnterConfigurationMode: this FMU has no structural parameters");
}

fmi3Status fmi3ExitConfigurationMode(fmi3Instance instance) {
    return refuse(instance, "fmi3ExitConfigurationMode: this FMU has no structural parameters");
}

#define NO_CLOCKS(call) "fmi3" #call ": this FMU has no clocks"

fmi3Status fmi3GetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                  size_t nValueReferences, fmi3Float64 intervals[], fmi3IntervalQualifier qualifiers[]) {
    (void)valueReferences, (void)nValueReferences, (void)intervals, (void)qualifiers;
    return refuse(instance, NO_CLOCKS(GetIntervalDecimal));
}

fmi3Status fmi3GetIntervalFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                   size_t nValueReferences, fmi3UInt64 counters[], fmi3UInt64 resolutions[],
                                   fmi3IntervalQualifier qualifiers[]) {
    (void)valueReferences, (void)nValueReferences, (void)counters, (void)resolutions, (void)qualifiers;
    return refuse(instance, NO_CLOCKS(GetIntervalFraction));
}

fmi3Status fmi3GetShiftDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                               size_t nValueReferences, fmi3Float64 shifts[]) {
    (void)valueReferences, (void)nValueReferences, (void)shifts;
    return refuse(instance, NO_CLOCKS(GetShiftDecimal));
}

fmi3Status fmi3GetShiftFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                size_t nValueReferences, fmi3UInt64 counters[], fmi3UInt64 resolutions[]) {
    (void)valueReferences, (void)nValueReferences, (void)counters, (void)resolutions;
    return refuse(instance, NO_CLOCKS(GetShiftFraction));
}

fmi3Status fmi3SetIntervalDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                  size_t nValueReferences, const fmi3Float64 intervals[]) {
    (void)valueReferences, (void)nValueReferences, (void)intervals;
    return refuse(instance, NO_CLOCKS(SetIntervalDecimal));
}

fmi3Status fmi3SetIntervalFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                   size_t nValueReferences, const fmi3UInt64 counters[],
                                   const fmi3UInt64 resolutions[]) {
    (void)valueReferences, (void)nValueReferences, (void)counters, (void)resolutions;
    return refuse(instance, NO_CLOCKS(SetIntervalFraction));
}

fmi3Status fmi3SetShiftDecimal(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                               size_t nValueReferences, const fmi3Float64 shifts[]) {
    (void)valueReferences, (void)nValueReferences, (void)shifts;
    return refuse(instance, NO_CLOCKS(SetShiftDecimal));
}

fmi3Status fmi3SetShiftFraction(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                size_t nValueReferences, const fmi3UInt64 counters[], const fmi3UInt64 resolutions[]) {
    (void)valueReferences, (void)nValueReferences, (void)counters, (void)resolutions;
    return refuse(instance, NO_CLOCKS(SetShiftFraction));
}

fmi3Status fmi3EvaluateDiscreteStates(fmi3Instance instance) {
    return refuse(instance, "fmi3EvaluateDiscreteStates: this FMU has no event mode");
}

#if MODEL_MODEL_EXCHANGE
/* ---- Model Exchange: the FMI 2.0 layer's (fmi2_me.c), FMI 3.0's names ---- */

fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean *discreteStatesNeedUpdate,
                                    fmi3Boolean *terminateSimulation, fmi3Boolean *nominalsOfContinuousStatesChanged,
                                    fmi3Boolean *valuesOfContinuousStatesChanged, fmi3Boolean *nextEventTimeDefined,
                                    fmi3Float64 *nextEventTime) {
    fmi2EventInfo info;
    const fmi2Status status = fmi2NewDiscreteStates(instance, &info);
    if (status > fmi2Warning) return (fmi3Status)status;
    if (discreteStatesNeedUpdate) *discreteStatesNeedUpdate = info.newDiscreteStatesNeeded;
    if (terminateSimulation) *terminateSimulation = info.terminateSimulation;
    if (nominalsOfContinuousStatesChanged) *nominalsOfContinuousStatesChanged = info.nominalsOfContinuousStatesChanged;
    if (valuesOfContinuousStatesChanged) *valuesOfContinuousStatesChanged = info.valuesOfContinuousStatesChanged;
    if (nextEventTimeDefined) *nextEventTimeDefined = info.nextEventTimeDefined;
    if (nextEventTime) *nextEventTime = info.nextEventTime;
    return (fmi3Status)status;
}

fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance instance) {
    return (fmi3Status)fmi2EnterContinuousTimeMode(instance);
}

fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi3Boolean *enterEventMode, fmi3Boolean *terminateSimulation) {
    fmi2Boolean enter = fmi2False, terminate = fmi2False;
    const fmi2Status status = fmi2CompletedIntegratorStep(instance, noSetFMUStatePriorToCurrentPoint, &enter, &terminate);
    if (enterEventMode) *enterEventMode = enter;
    if (terminateSimulation) *terminateSimulation = terminate;
    return (fmi3Status)status;
}

fmi3Status fmi3SetTime(fmi3Instance instance, fmi3Float64 time) { return (fmi3Status)fmi2SetTime(instance, time); }

fmi3Status fmi3SetContinuousStates(fmi3Instance instance, const fmi3Float64 continuousStates[],
                                   size_t nContinuousStates) {
    return (fmi3Status)fmi2SetContinuousStates(instance, continuousStates, nContinuousStates);
}

fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance instance, fmi3Float64 derivatives[],
                                             size_t nContinuousStates) {
    return (fmi3Status)fmi2GetDerivatives(instance, derivatives, nContinuousStates);
}

fmi3Status fmi3GetEventIndicators(fmi3Instance instance, fmi3Float64 eventIndicators[], size_t nEventIndicators) {
    return (fmi3Status)fmi2GetEventIndicators(instance, eventIndicators, nEventIndicators);
}

fmi3Status fmi3GetContinuousStates(fmi3Instance instance, fmi3Float64 continuousStates[], size_t nContinuousStates) {
    return (fmi3Status)fmi2GetContinuousStates(instance, continuousStates, nContinuousStates);
}

fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance instance, fmi3Float64 nominals[], size_t nContinuousStates) {
    return (fmi3Status)fmi2GetNominalsOfContinuousStates(instance, nominals, nContinuousStates);
}

fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t *nEventIndicators) {
    if (!instance || !nEventIndicators || !fmu_of(instance)->model_exchange)
        return refuse(instance, "fmi3GetNumberOfEventIndicators: for a Model Exchange instance, with its count's address");
    *nEventIndicators = 0;
    return fmi3OK;
}

fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t *nContinuousStates) {
    if (!instance || !nContinuousStates || !fmu_of(instance)->model_exchange)
        return refuse(instance, "fmi3GetNumberOfContinuousStates: for a Model Exchange instance, with its count's address");
    *nContinuousStates = MODEL_N_STATES;
    return fmi3OK;
}

#else
fmi3Status fmi3UpdateDiscreteStates(fmi3Instance instance, fmi3Boolean *discreteStatesNeedUpdate,
                                    fmi3Boolean *terminateSimulation, fmi3Boolean *nominalsOfContinuousStatesChanged,
                                    fmi3Boolean *valuesOfContinuousStatesChanged, fmi3Boolean *nextEventTimeDefined,
                                    fmi3Float64 *nextEventTime) {
    (void)discreteStatesNeedUpdate, (void)terminateSimulation, (void)nominalsOfContinuousStatesChanged;
    (void)valuesOfContinuousStatesChanged, (void)nextEventTimeDefined, (void)nextEventTime;
    return refuse(instance, "fmi3UpdateDiscreteStates: this FMU has no event mode");
}

#define NOT_ME(call) "fmi3" #call ": a Model Exchange function; this FMU is for Co-Simulation only"

fmi3Status fmi3EnterContinuousTimeMode(fmi3Instance instance) {
    return refuse(instance, NOT_ME(EnterContinuousTimeMode));
}

fmi3Status fmi3CompletedIntegratorStep(fmi3Instance instance, fmi3Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi3Boolean *enterEventMode, fmi3Boolean *terminateSimulation) {
    (void)noSetFMUStatePriorToCurrentPoint, (void)enterEventMode, (void)terminateSimulation;
    return refuse(instance, NOT_ME(CompletedIntegratorStep));
}

fmi3Status fmi3SetTime(fmi3Instance instance, fmi3Float64 time) {
    (void)time;
    return refuse(instance, NOT_ME(SetTime));
}

fmi3Status fmi3SetContinuousStates(fmi3Instance instance, const fmi3Float64 continuousStates[],
                                   size_t nContinuousStates) {
    (void)continuousStates, (void)nContinuousStates;
    return refuse(instance, NOT_ME(SetContinuousStates));
}

fmi3Status fmi3GetContinuousStateDerivatives(fmi3Instance instance, fmi3Float64 derivatives[],
                                             size_t nContinuousStates) {
    (void)derivatives, (void)nContinuousStates;
    return refuse(instance, NOT_ME(GetContinuousStateDerivatives));
}

fmi3Status fmi3GetEventIndicators(fmi3Instance instance, fmi3Float64 eventIndicators[], size_t nEventIndicators) {
    (void)eventIndicators, (void)nEventIndicators;
    return refuse(instance, NOT_ME(GetEventIndicators));
}

fmi3Status fmi3GetContinuousStates(fmi3Instance instance, fmi3Float64 continuousStates[], size_t nContinuousStates) {
    (void)continuousStates, (void)nContinuousStates;
    return refuse(instance, NOT_ME(GetContinuousStates));
}

fmi3Status fmi3GetNominalsOfContinuousStates(fmi3Instance instance, fmi3Float64 nominals[], size_t nContinuousStates) {
    (void)nominals, (void)nContinuousStates;
    return refuse(instance, NOT_ME(GetNominalsOfContinuousStates));
}

fmi3Status fmi3GetNumberOfEventIndicators(fmi3Instance instance, size_t *nEventIndicators) {
    (void)nEventIndicators;
    return refuse(instance, NOT_ME(GetNumberOfEventIndicators));
}

fmi3Status fmi3GetNumberOfContinuousStates(fmi3Instance instance, size_t *nContinuousStates) {
    (void)nContinuousStates;
    return refuse(instance, NOT_ME(GetNumberOfContinuousStates));
}
#endif

fmi3Status fmi3ActivateModelPartition(fmi3Instance instance, fmi3ValueReference clockReference,
                                      fmi3Float64 activationTime) {
    (void)clockReference, (void)activationTime;
    return refuse(instance, "fmi3ActivateModelPartition: a Scheduled Execution function; this FMU is for "
                            "Co-Simulation only");
}

/* ---- co-simulation ---- */

fmi3Status fmi3EnterStepMode(fmi3Instance instance) {
    return refuse(instance, "fmi3EnterStepMode: this FMU has no event mode: it is in step mode from "
                            "fmi3ExitInitializationMode on");
}

fmi3Status fmi3GetOutputDerivatives(fmi3Instance instance, const fmi3ValueReference valueReferences[],
                                    size_t nValueReferences, const fmi3Int32 orders[], fmi3Float64 values[],
                                    size_t nValues) {
    if (!scalars(instance, "fmi3GetOutputDerivatives", nValueReferences, nValues)) return fmi3Error;
    return (fmi3Status)fmi2GetRealOutputDerivatives(instance, valueReferences, nValueReferences,
                                                    (const fmi2Integer *)orders, values);
}

fmi3Status fmi3DoStep(fmi3Instance instance, fmi3Float64 currentCommunicationPoint, fmi3Float64 communicationStepSize,
                      fmi3Boolean noSetFMUStatePriorToCurrentPoint, fmi3Boolean *eventHandlingNeeded,
                      fmi3Boolean *terminateSimulation, fmi3Boolean *earlyReturn, fmi3Float64 *lastSuccessfulTime) {
    if (instance && (!eventHandlingNeeded || !terminateSimulation || !earlyReturn || !lastSuccessfulTime))
        return refuse(instance, "fmi3DoStep: NULL out-pointer");
    const fmi2Status status = fmi2DoStep(instance, currentCommunicationPoint, communicationStepSize,
                                         noSetFMUStatePriorToCurrentPoint);
    if (instance) {
        *eventHandlingNeeded = *terminateSimulation = *earlyReturn = fmi3False;
        *lastSuccessfulTime = fmu_of(instance)->s.time;
    }
    return (fmi3Status)status;
}
