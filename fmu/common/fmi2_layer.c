/* The FMI 2.0 Co-Simulation API every model shares: the entry points, the call-sequence checks of
 * the FMI 2.0 state machine, the checks of what is set, and the step (its inputs extrapolated, its
 * failure rolled back). Compiled once per model, against that model's variables.h; the model
 * itself implements the hooks of fmu_common.h; the services it calls are in runtime.c and FMU
 * state in fmu_state.c.
 */
#include "fmu_common.h"
#include "runtime.h"

#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifndef MODEL_GUID
#error "MODEL_GUID must be defined by the build (a hash of the model's variables.h)"
#endif

/* ------------------------------------------------------------------------------------------ */
/* Variables: start values and the checks of a get or set                                     */

static void set_start_values(FmuInstance *fmu) {
    for (int vr = 1; vr < VR_COUNT; vr++) {
        const FmuVariable *var = &fmu_variables[vr];
        if (var->type == FMU_REAL) *(double *)fmu_value_address(fmu, vr) = var->start;
        else if (var->type == FMU_STRING) ((FmuText *)fmu_value_address(fmu, vr))->text[0] = '\0';
        else *(int *)fmu_value_address(fmu, vr) = (int)var->start;
    }
}

static const char *type_name(FmuType t) {
    return t == FMU_REAL ? "Real" : t == FMU_INTEGER ? "Integer" : t == FMU_BOOLEAN ? "Boolean" : "String";
}

static int check_reference(FmuInstance *fmu, const char *call, fmi2ValueReference vr, FmuType type) {
    if (vr < 1 || vr >= VR_COUNT) {
        LOG_ERROR(fmu, "%s: unknown value reference %u", call, (unsigned)vr);
        return 0;
    }
    if (fmu_variables[vr].type != type) {
        LOG_ERROR(fmu, "%s: variable '%s' (value reference %u) is of type %s, not %s", call,
                  fmu_variables[vr].name, (unsigned)vr, type_name(fmu_variables[vr].type), type_name(type));
        return 0;
    }
    return 1;
}

/* May `vr` be set now, and is `value` acceptable? Logs the reason when not. */
static int check_settable(FmuInstance *fmu, const char *call, int vr, double value) {
    const FmuVariable *var = &fmu_variables[vr];
    if (var->causality == FMU_OUTPUT || var->causality == FMU_LOCAL) {
        LOG_ERROR(fmu, "%s: '%s' is an output; it cannot be set", call, var->name);
        return 0;
    }
    if (fmu->s.phase & (PHASE_STEP_COMPLETE)) {
        if (var->causality == FMU_PARAMETER && var->variability != FMU_TUNABLE) {
            LOG_ERROR(fmu, "%s: '%s' is a fixed parameter; it can only be set before initialization ends",
                      call, var->name);
            return 0;
        }
        if (fmu->model_exchange && fmu->s.continuous_time_mode &&
            !(var->causality == FMU_INPUT && var->variability == FMU_CONTINUOUS)) {
            LOG_ERROR(fmu, "%s: '%s' is not a continuous input; it can be set in Event Mode, not in Continuous-Time "
                      "Mode (fmi2EnterEventMode first)", call, var->name);
            return 0;
        }
    } else if (!(fmu->s.phase & (PHASE_INSTANTIATED | PHASE_INITIALIZATION))) {
        LOG_ERROR(fmu, "%s: illegal call sequence: '%s' cannot be set in state '%s'", call, var->name,
                  fmu_phase_name(fmu->s.phase));
        return 0;
    }
    if (!isfinite(value)) {
        LOG_ERROR(fmu, "%s: '%s' = %g rejected: not a finite number", call, var->name, value);
        return 0;
    }
    if (var->min == FMU_POSITIVE && !(value >= var->min)) {
        LOG_ERROR(fmu, "%s: '%s' = %g %s: must be > 0 (rejected: outside (0, %g])", call, var->name, value, var->unit,
                  var->max);
        return 0;
    }
    if (value < var->min || value > var->max) {
        LOG_ERROR(fmu, "%s: '%s' = %g rejected: outside [%g, %g] %s", call, var->name, value, var->min,
                  var->max, var->unit);
        return 0;
    }
    return 1;
}

/* Does a set call of these (checked) references change a parameter? Only then is the model validated
 * afterwards, and only then are the variables kept aside to be put back. */
static int sets_parameter(const fmi2ValueReference vr[], size_t nvr) {
    for (size_t i = 0; i < nvr; i++)
        if (fmu_variables[vr[i]].causality != FMU_INPUT) return 1;
    return 0;
}

/* Called after values were set: outputs must be recomputed; a tunable parameter changed after
 * initialization must leave the model valid, or it is put back (inputs are checked one by one
 * when set, so setting only inputs costs no model validation). */
static fmi2Status after_set(FmuInstance *fmu, const ModelVariables *before, int any_input, int any_parameter) {
    if (any_input) fmu->s.input_time = fmu->s.time;
    fmu->outputs_stale = 1;
    if (any_parameter && (fmu->s.phase & PHASE_STEP_COMPLETE) && model_validate(fmu) != fmi2OK) {
        fmu->s.v = *before;
        return fmi2Error;
    }
    return fmi2OK;
}

/* Every Real output finite? Logs the first that is not, naming the call. */
static int outputs_finite(FmuInstance *fmu, const char *call) {
    for (int k = 0; k < fmu->n_real_outputs; k++) {
        const int vr = fmu->real_outputs[k];
        if (!isfinite(*(double *)fmu_value_address(fmu, vr))) {
            LOG_ERROR(fmu, "%s: output '%s' is not finite at t = %.9g s (the inputs or parameters are beyond what the "
                      "model can compute)", call, fmu_variables[vr].name, fmu->s.time);
            return 0;
        }
    }
    return 1;
}

/* The outputs computed for the state and inputs now; the lazy ones (MODEL_LAZY_OUTPUTS) wait for
 * their first read. */
static void outputs_computed(FmuInstance *fmu) {
    model_compute_outputs(fmu);
    fmu->outputs_stale = 0;
    fmu->lazy_outputs_stale = 1;
}

/* Outputs recomputed if inputs or parameters changed; 0 (logged) when one is not finite. */
static int refresh_outputs(FmuInstance *fmu, const char *call) {
    if (!fmu->outputs_stale) return 1;
    if (fmu->s.phase & PHASE_INITIALIZATION) model_initialize(fmu);
    if (fmu->s.phase & (PHASE_INITIALIZATION | AFTER_INITIALIZATION)) outputs_computed(fmu);
    fmu->outputs_stale = 0;
    return outputs_finite(fmu, call);
}

/* The lazy outputs computed where one of `vr` is among them and they are stale. */
static void refresh_lazy_outputs(FmuInstance *fmu, const fmi2ValueReference vr[], size_t nvr) {
#if MODEL_LAZY_OUTPUTS
    if (!fmu->lazy_outputs_stale || !(fmu->s.phase & (PHASE_INITIALIZATION | AFTER_INITIALIZATION))) return;
    for (size_t i = 0; i < nvr; i++)
        if (vr[i] < VR_COUNT && model_output_is_lazy((int)vr[i])) {
            model_compute_lazy_outputs(fmu);
            fmu->lazy_outputs_stale = 0;
            return;
        }
#else
    (void)fmu, (void)vr, (void)nvr;
#endif
}

/* ------------------------------------------------------------------------------------------ */
/* Instance life cycle                                                                         */

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[]) {
    FmuInstance *fmu = (FmuInstance *)c;
    if (!fmu_allowed(fmu, "fmi2SetDebugLogging", ANY_LIVE_PHASE)) return fmi2Error;
    fmu->logging_on = loggingOn;
    if (nCategories == 0) {
        fmu->log_events = fmu->log_warnings = fmu->log_all = loggingOn;
        fmu->log_errors = 1;
        return fmi2OK;
    }
    for (size_t i = 0; i < nCategories; i++) {
        const char *cat = categories ? categories[i] : NULL;
        if (!cat) { LOG_ERROR(fmu, "fmi2SetDebugLogging: category %zu is NULL", i); return fmi2Error; }
        if (strcmp(cat, "logEvents") == 0) fmu->log_events = loggingOn;
        else if (strcmp(cat, "logStatusWarning") == 0) fmu->log_warnings = loggingOn;
        else if (strcmp(cat, "logStatusError") == 0) fmu->log_errors = 1; /* errors are always reported */
        else if (strcmp(cat, "logAll") == 0) fmu->log_all = loggingOn;
        else {
            LOG_ERROR(fmu, "fmi2SetDebugLogging: unknown log category '%s'", cat);
            return fmi2Error;
        }
    }
    return fmi2OK;
}

/* ------------------------------------------------------------------------------------------ */
/* Start values an FMU carries (cosim export: a scene's values inside its FMUs)                */

static const char CARRIED_FILE[] = "start_values.txt";
enum { CARRIED_MAX = 1 << 20 }; /* [bytes] a larger start_values.txt is refused */

/* The text of resources/start_values.txt (NULL where there is none); 0 after logging a file that
 * cannot be read whole. */
static int read_carried(FmuInstance *fmu) {
    char path[4096];
    if (!fmu->resources || strlen(fmu->resources) + sizeof CARRIED_FILE > sizeof path) return 1;
    strcpy(path, fmu->resources);
    strcat(path, CARRIED_FILE);
    FILE *file = fopen(path, "rb");
    if (!file) return 1; /* an FMU that carries none */
    const long size = fseek(file, 0, SEEK_END) == 0 ? ftell(file) : -1;
    char *text = size >= 0 && size <= CARRIED_MAX && fseek(file, 0, SEEK_SET) == 0
                     ? (char *)fmu->callbacks.allocateMemory((size_t)size + 1, 1)
                     : NULL;
    const size_t n = text ? fread(text, 1, (size_t)size, file) : 0;
    fclose(file);
    if (!text || n != (size_t)size) {
        LOG_ERROR(fmu, "fmi2Instantiate: %s: %s", path, size > CARRIED_MAX ? "larger than 1 MiB" : "cannot be read");
        if (text) fmu->callbacks.freeMemory(text);
        return 0;
    }
    text[n] = '\0';
    fmu->carried = text;
    return 1;
}

static fmi2Status set_values(fmi2Component c, const char *call, FmuType type, const fmi2ValueReference vr[],
                             size_t nvr, const void *values);

/* The carried values set as fmi2Set* sets them: one "name=value" a line (Real and Integer as C reads
 * numbers, Boolean true or false, String the rest of the line). 0 after logging the first that is
 * refused (an unknown name, a value the variable does not take). */
static int apply_carried(FmuInstance *fmu) {
    static const char call[] = "the FMU's start_values.txt";
    for (const char *line = fmu->carried; line && *line;) {
        const char *end = strchr(line, '\n'), *next = end ? end + 1 : line + strlen(line);
        size_t length = (size_t)((end ? end : next) - line);
        if (length && line[length - 1] == '\r') length--;
        char text[FMU_TEXT_MAX + 256];
        if (length >= sizeof text) { LOG_ERROR(fmu, "%s: a line longer than %d bytes", call, (int)sizeof text - 1); return 0; }
        memcpy(text, line, length);
        text[length] = '\0';
        line = next;
        char *value = strchr(text, '=');
        if (!text[0] || text[0] == '#') continue;
        if (!value) { LOG_ERROR(fmu, "%s: '%s' is not name=value", call, text); return 0; }
        *value++ = '\0';
        fmi2ValueReference vr = 0;
        for (int k = 1; k < VR_COUNT && !vr; k++)
            if (strcmp(fmu_variables[k].name, text) == 0) vr = (fmi2ValueReference)k;
        if (!vr) { LOG_ERROR(fmu, "%s: no variable '%s'", call, text); return 0; }
        const FmuType type = fmu_variables[vr].type;
        char *rest = value;
        fmi2Status status;
        if (type == FMU_REAL) {
            const double number = strtod(value, &rest);
            status = *rest || rest == value ? fmi2Error : set_values(fmu, call, type, &vr, 1, &number);
        } else if (type == FMU_STRING) {
            const fmi2String string = value;
            status = set_values(fmu, call, type, &vr, 1, &string);
        } else {
            const long number = type == FMU_BOOLEAN ? (strcmp(value, "true") == 0 ? 1 : strcmp(value, "false") == 0 ? 0 : -1)
                                                    : strtol(value, &rest, 10);
            const fmi2Integer whole = (fmi2Integer)number;
            status = (type == FMU_BOOLEAN ? number < 0 : *rest || rest == value || number != whole) ? fmi2Error
                     : set_values(fmu, call, type, &vr, 1, &whole);
        }
        if (status != fmi2OK) { LOG_ERROR(fmu, "%s: %s = '%s' not taken", call, text, value); return 0; }
    }
    return 1;
}

/* The instance as instantiated: the table's start values, then those it carries. 0 after logging a
 * carried value refused (only ever at instantiation: a reset takes what was taken then). */
static int reset_to_start(FmuInstance *fmu) {
    fmu_set_model_data(fmu, NULL, NULL);
    memset(&fmu->s, 0, sizeof fmu->s);
    fmu->s.phase = PHASE_INSTANTIATED;
    set_start_values(fmu);
    fmu->outputs_stale = 1;
    return apply_carried(fmu);
}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation, const fmi2CallbackFunctions *functions,
                              fmi2Boolean visible, fmi2Boolean loggingOn) {
    (void)visible;
    if (!functions || !functions->allocateMemory || !functions->freeMemory) return NULL;
    FmuInstance probe;
    memset(&probe, 0, sizeof probe);
    probe.callbacks = *functions;
    probe.instance_name = (char *)(instanceName ? instanceName : "?");
    probe.log_errors = 1;
    if (!instanceName || !instanceName[0]) {
        LOG_ERROR(&probe, "fmi2Instantiate: missing instance name");
        return NULL;
    }
    if (fmuType != fmi2CoSimulation && !(MODEL_MODEL_EXCHANGE && fmuType == fmi2ModelExchange)) {
        LOG_ERROR(&probe, "fmi2Instantiate: %s is %s", MODEL_IDENTIFIER_STRING,
                  MODEL_MODEL_EXCHANGE ? "Co-Simulation or Model Exchange; the type asked for is neither"
                                       : "a Co-Simulation FMU; Model Exchange is not supported");
        return NULL;
    }
    if (!fmuGUID || strcmp(fmuGUID, MODEL_GUID) != 0) {
        LOG_ERROR(&probe, "fmi2Instantiate: GUID '%s' does not match this binary's '%s'",
                  fmuGUID ? fmuGUID : "(null)", MODEL_GUID);
        return NULL;
    }
    FmuInstance *fmu = (FmuInstance *)functions->allocateMemory(1, sizeof(FmuInstance));
    if (!fmu) return NULL;
    memset(fmu, 0, sizeof *fmu);
    fmu->callbacks = *functions;
    fmu->instance_name = (char *)functions->allocateMemory(strlen(instanceName) + 1, 1);
    if (!fmu->instance_name) { functions->freeMemory(fmu); return NULL; }
    strcpy(fmu->instance_name, instanceName);
    fmu->logging_on = loggingOn;
    fmu->model_exchange = fmuType == fmi2ModelExchange;
    fmu->log_errors = 1; /* errors and returned warnings are always reported; the rest only with logging on */
    fmu->log_warnings = fmu->log_events = fmu->log_all = loggingOn;
    for (int vr = 1; vr < VR_COUNT; vr++) {
        if (fmu_variables[vr].type != FMU_REAL) continue;
        if (fmu_variables[vr].causality == FMU_OUTPUT) fmu->real_outputs[fmu->n_real_outputs++] = vr;
        if (fmu_variables[vr].causality == FMU_INPUT) fmu->real_inputs[fmu->n_real_inputs++] = vr;
    }
    fmu->resources = fmu_resources_folder(fmu, fmuResourceLocation);
    if (!read_carried(fmu) || !reset_to_start(fmu)) {
        fmi2FreeInstance(fmu);
        return NULL;
    }
    return fmu;
}

void fmi2FreeInstance(fmi2Component c) {
    FmuInstance *fmu = (FmuInstance *)c;
    if (!fmu) return;
    fmi2CallbackFreeMemory release = fmu->callbacks.freeMemory;
    fmu_set_model_data(fmu, NULL, NULL);
    if (fmu->resources) release(fmu->resources);
    if (fmu->carried) release(fmu->carried);
    release(fmu->instance_name);
    release(fmu);
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    FmuInstance *fmu = (FmuInstance *)c;
    if (!fmu_allowed(fmu, "fmi2SetupExperiment", PHASE_INSTANTIATED)) return fmi2Error;
    if (toleranceDefined && !(tolerance > 0.0 && isfinite(tolerance))) {
        LOG_ERROR(fmu, "fmi2SetupExperiment: tolerance %g must be a positive finite number", tolerance);
        return fmi2Error;
    }
    if (!isfinite(startTime) || (stopTimeDefined && !(stopTime >= startTime && isfinite(stopTime)))) {
        LOG_ERROR(fmu, "fmi2SetupExperiment: invalid times start = %g, stop = %g", startTime, stopTime);
        return fmi2Error;
    }
    fmu->s.time = fmu->s.input_time = startTime;
    fmu->s.stop_time_defined = stopTimeDefined ? 1 : 0;
    fmu->s.stop_time = stopTimeDefined ? stopTime : 0.0;
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
    FmuInstance *fmu = (FmuInstance *)c;
    if (!fmu_allowed(fmu, "fmi2EnterInitializationMode", PHASE_INSTANTIATED)) return fmi2Error;
    if (model_validate(fmu) != fmi2OK) return fmi2Error;
    fmu->s.phase = PHASE_INITIALIZATION;
    fmu->outputs_stale = 1;
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    FmuInstance *fmu = (FmuInstance *)c;
    if (!fmu_allowed(fmu, "fmi2ExitInitializationMode", PHASE_INITIALIZATION)) return fmi2Error;
    if (model_validate(fmu) != fmi2OK) return fmi2Error;
#if MODEL_MODEL_EXCHANGE
    const char *refusal = fmu->model_exchange ? model_exchange_refusal(fmu) : NULL;
    if (refusal) {
        LOG_ERROR(fmu, "fmi2ExitInitializationMode: as Model Exchange, %s", refusal);
        return fmi2Error;
    }
#endif
    model_initialize(fmu);
    fmu->s.input_previous_valid = 0; /* the FMU's own extrapolation starts with the first step */
    fmu->s.phase = PHASE_STEP_COMPLETE; /* Model Exchange: in Event Mode */
    fmu->s.continuous_time_mode = 0;
    outputs_computed(fmu);
    if (!outputs_finite(fmu, "fmi2ExitInitializationMode")) {
        fmu->s.phase = PHASE_ERROR;
        return fmi2Error;
    }
    return fmi2OK;
}

fmi2Status fmi2Terminate(fmi2Component c) {
    FmuInstance *fmu = (FmuInstance *)c;
    if (!fmu_allowed(fmu, "fmi2Terminate", PHASE_STEP_COMPLETE | PHASE_STEP_FAILED)) return fmi2Error;
    fmu->s.phase = PHASE_TERMINATED;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component c) {
    FmuInstance *fmu = (FmuInstance *)c;
    if (!fmu_allowed(fmu, "fmi2Reset", ANY_LIVE_PHASE)) return fmi2Error;
    (void)reset_to_start(fmu); /* the values it carries were taken at instantiation */
    return fmi2OK;
}

/* ------------------------------------------------------------------------------------------ */
/* Get and set                                                                                 */

/* FMI 2.0, Co-Simulation state machine: the fmi2Get functions in initialization mode, slave initialized,
 * terminated and error, not before initialization */
#define GET_PHASES (PHASE_INITIALIZATION | AFTER_INITIALIZATION)

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[]) {
    FmuInstance *fmu = (FmuInstance *)c;
    if (!fmu_allowed(fmu, "fmi2GetReal", GET_PHASES)) return fmi2Error;
    if (nvr > 0 && (!vr || !value)) { LOG_ERROR(fmu, "fmi2GetReal: NULL array"); return fmi2Error; }
    if (!refresh_outputs(fmu, "fmi2GetReal")) return fmi2Error;
    refresh_lazy_outputs(fmu, vr, nvr);
    int all_finite = 1;
    for (size_t i = 0; i < nvr; i++) {
#if MODEL_MODEL_EXCHANGE
        if (fmu->model_exchange && fmu_me_value(fmu, vr[i], &value[i])) { /* a state or its derivative (ME only) */
            all_finite = all_finite && isfinite(value[i]);
            continue;
        }
#endif
        if (!check_reference(fmu, "fmi2GetReal", vr[i], FMU_REAL)) return fmi2Error;
        value[i] = *(double *)fmu_value_address(fmu, (int)vr[i]);
        all_finite = all_finite && isfinite(value[i]);
    }
    if (!all_finite) { /* only an instance in the error state holds such values: read for diagnosis */
        fmu_log(fmu, fmi2Warning, "logStatusWarning", "fmi2GetReal: values of an instance in state '%s' that are not "
                "finite", fmu_phase_name(fmu->s.phase));
        return fmi2Warning;
    }
    return fmi2OK;
}

static fmi2Status get_ints(FmuInstance *fmu, const char *call, FmuType type,
                           const fmi2ValueReference vr[], size_t nvr, int value[]) {
    if (!fmu_allowed(fmu, call, GET_PHASES)) return fmi2Error;
    if (nvr > 0 && (!vr || !value)) { LOG_ERROR(fmu, "%s: NULL array", call); return fmi2Error; }
    if (!refresh_outputs(fmu, call)) return fmi2Error;
    for (size_t i = 0; i < nvr; i++) {
        if (!check_reference(fmu, call, vr[i], type)) return fmi2Error;
        value[i] = *(int *)fmu_value_address(fmu, (int)vr[i]);
    }
    return fmi2OK;
}

fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Integer value[]) {
    return get_ints((FmuInstance *)c, "fmi2GetInteger", FMU_INTEGER, vr, nvr, value);
}

fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Boolean value[]) {
    return get_ints((FmuInstance *)c, "fmi2GetBoolean", FMU_BOOLEAN, vr, nvr, value);
}

fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2String value[]) {
    FmuInstance *fmu = (FmuInstance *)c;
    if (!fmu_allowed(fmu, "fmi2GetString", GET_PHASES)) return fmi2Error;
    if (nvr > 0 && (!vr || !value)) { LOG_ERROR(fmu, "fmi2GetString: NULL array"); return fmi2Error; }
    for (size_t i = 0; i < nvr; i++) {
        if (!check_reference(fmu, "fmi2GetString", vr[i], FMU_STRING)) return fmi2Error;
        value[i] = ((FmuText *)fmu_value_address(fmu, (int)vr[i]))->text;
    }
    return fmi2OK;
}

#define SET_PHASES (PHASE_INSTANTIATED | PHASE_INITIALIZATION | PHASE_STEP_COMPLETE)

/* The i-th of a set call's values as a number (what the table's bounds are checked against; a
 * string's bound is the table's minimum, which every text meets), and stored in its variable. */
static double value_number(FmuType type, const void *values, size_t i) {
    switch (type) {
    case FMU_REAL: return ((const double *)values)[i];
    case FMU_BOOLEAN: return ((const int *)values)[i] != 0;
    case FMU_INTEGER: return ((const int *)values)[i];
    default: return 0.0;
    }
}

static void store_value(FmuInstance *fmu, FmuType type, int vr, const void *values, size_t i) {
    void *address = fmu_value_address(fmu, vr);
    if (type == FMU_REAL) *(double *)address = ((const double *)values)[i];
    else if (type == FMU_STRING) { /* the FMU keeps its own copy (FMI 2.0, 2.1.7) */
        const char *text = ((const fmi2String *)values)[i];
        strcpy(((FmuText *)address)->text, text ? text : "");
    } else *(int *)address = (int)value_number(type, values, i);
}

/* The one body of fmi2SetReal, -Integer, -Boolean and -String: every reference checked (its type,
 * whether it may be set now, its value within the table's bounds, a string's length) before any is
 * stored, so that a rejected call changes nothing; then stored, and the model told (after_set). */
static fmi2Status set_values(fmi2Component c, const char *call, FmuType type, const fmi2ValueReference vr[],
                             size_t nvr, const void *values) {
    FmuInstance *fmu = (FmuInstance *)c;
    if (!fmu_allowed(fmu, call, SET_PHASES)) return fmi2Error;
    if (nvr > 0 && (!vr || !values)) { LOG_ERROR(fmu, "%s: NULL array", call); return fmi2Error; }
    for (size_t i = 0; i < nvr; i++) {
        if (!check_reference(fmu, call, vr[i], type)) return fmi2Error; /* before vr indexes the table */
        const double number = type == FMU_STRING ? fmu_variables[vr[i]].min : value_number(type, values, i);
        if (!check_settable(fmu, call, (int)vr[i], number)) return fmi2Error;
        const char *text = type == FMU_STRING ? ((const fmi2String *)values)[i] : NULL;
        if (text && strlen(text) >= FMU_TEXT_MAX) {
            LOG_ERROR(fmu, "%s: '%s' rejected: longer than %d bytes", call, fmu_variables[vr[i]].name,
                      FMU_TEXT_MAX - 1);
            return fmi2Error;
        }
    }
    const int any_parameter = sets_parameter(vr, nvr);
    ModelVariables before;
    if (any_parameter) before = fmu->s.v;
    int any_input = 0;
    for (size_t i = 0; i < nvr; i++) {
        store_value(fmu, type, (int)vr[i], values, i);
        if (fmu_variables[vr[i]].causality == FMU_INPUT) any_input = 1;
    }
    return after_set(fmu, &before, any_input, any_parameter);
}

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[]) {
    return set_values(c, "fmi2SetReal", FMU_REAL, vr, nvr, value);
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Integer value[]) {
    return set_values(c, "fmi2SetInteger", FMU_INTEGER, vr, nvr, value);
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Boolean value[]) {
    return set_values(c, "fmi2SetBoolean", FMU_BOOLEAN, vr, nvr, value);
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2String value[]) {
    return set_values(c, "fmi2SetString", FMU_STRING, vr, nvr, value);
}

/* ------------------------------------------------------------------------------------------ */
/* Co-simulation                                                                               */

/* A Co-Simulation call on this instance, now? Logs why not (a Model Exchange instance has none). */
static int cs_allowed(FmuInstance *fmu, const char *call, int phases) {
    if (!fmu_allowed(fmu, call, phases)) return 0;
    if (fmu->model_exchange) {
        LOG_ERROR(fmu, "%s: a Co-Simulation call, and this instance is Model Exchange", call);
        return 0;
    }
    return 1;
}

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[]) {
    FmuInstance *fmu = (FmuInstance *)c;
    if (!cs_allowed(fmu, "fmi2SetRealInputDerivatives", SET_PHASES)) return fmi2Error;
    if (nvr > 0 && (!vr || !order || !value)) {
        LOG_ERROR(fmu, "fmi2SetRealInputDerivatives: NULL array");
        return fmi2Error;
    }
    for (size_t i = 0; i < nvr; i++) {
        if (!check_reference(fmu, "fmi2SetRealInputDerivatives", vr[i], FMU_REAL)) return fmi2Error;
        if (fmu_variables[vr[i]].causality != FMU_INPUT) {
            LOG_ERROR(fmu, "fmi2SetRealInputDerivatives: '%s' is not an input", fmu_variables[vr[i]].name);
            return fmi2Error;
        }
        if (order[i] != 1 && order[i] != 2) {
            LOG_ERROR(fmu, "fmi2SetRealInputDerivatives: '%s': derivative order %d not supported (1 and 2 are)",
                      fmu_variables[vr[i]].name, (int)order[i]);
            return fmi2Error;
        }
        if (!isfinite(value[i])) {
            LOG_ERROR(fmu, "fmi2SetRealInputDerivatives: derivative of '%s' = %g rejected: not finite",
                      fmu_variables[vr[i]].name, value[i]);
            return fmi2Error;
        }
    }
    for (size_t i = 0; i < nvr; i++) {
        double *derivative = fmu->s.input_derivative[vr[i]];
        if (fmu->s.input_derivative_given[vr[i]] == 0) derivative[0] = derivative[1] = 0.0; /* fresh since the step */
        derivative[order[i] - 1] = value[i];
        if (order[i] > fmu->s.input_derivative_given[vr[i]]) fmu->s.input_derivative_given[vr[i]] = order[i];
    }
    fmu->s.input_time = fmu->s.time;
    fmu->outputs_stale = 1;
    return fmi2OK;
}

fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                        const fmi2Integer order[], fmi2Real value[]) {
    FmuInstance *fmu = (FmuInstance *)c;
    if (!cs_allowed(fmu, "fmi2GetRealOutputDerivatives", PHASE_STEP_COMPLETE | PHASE_STEP_FAILED)) return fmi2Error;
#if MODEL_MAX_OUTPUT_DERIVATIVE_ORDER > 0
    if (nvr > 0 && (!vr || !order || !value)) {
        LOG_ERROR(fmu, "fmi2GetRealOutputDerivatives: NULL array");
        return fmi2Error;
    }
    if (!refresh_outputs(fmu, "fmi2GetRealOutputDerivatives")) return fmi2Error;
    for (size_t i = 0; i < nvr; i++) {
        if (!check_reference(fmu, "fmi2GetRealOutputDerivatives", vr[i], FMU_REAL)) return fmi2Error;
        if (fmu_variables[vr[i]].causality != FMU_OUTPUT) {
            LOG_ERROR(fmu, "fmi2GetRealOutputDerivatives: '%s' is not an output", fmu_variables[vr[i]].name);
            return fmi2Error;
        }
        if (order[i] < 1 || order[i] > MODEL_MAX_OUTPUT_DERIVATIVE_ORDER) {
            LOG_ERROR(fmu, "fmi2GetRealOutputDerivatives: order %d of '%s' not in 1..%d", (int)order[i],
                      fmu_variables[vr[i]].name, MODEL_MAX_OUTPUT_DERIVATIVE_ORDER);
            return fmi2Error;
        }
        value[i] = model_output_derivative(fmu, (int)vr[i], order[i]);
    }
    return fmi2OK;
#else
    (void)vr; (void)order; (void)value;
    if (nvr == 0) return fmi2OK;
    LOG_ERROR(fmu, "fmi2GetRealOutputDerivatives: not provided (maxOutputDerivativeOrder=0)");
    return fmi2Error;
#endif
}

/* The part of the snapshot a step writes: its time, the variables, the ODE state, the solver's and
 * the model's memory, and of the inputs (only Real inputs have derivatives) the derivatives and
 * previous values its extrapolation writes, one entry per Real input (fmu->real_inputs). */
typedef struct {
    double time, input_time;
    ModelVariables v;
    double x[MODEL_N_STATES > 0 ? MODEL_N_STATES : 1];
    OdeSolver solver;
    ModelInternal internal;
    double input_derivative[VR_COUNT][2], input_previous[VR_COUNT], input_previous_time;
    int input_derivative_given[VR_COUNT], input_previous_valid;
} StepBackup;

static void backup_step(const FmuInstance *fmu, StepBackup *b) {
    b->time = fmu->s.time;
    b->input_time = fmu->s.input_time;
    for (int k = 0; k < fmu->n_real_inputs; k++) {
        const int vr = fmu->real_inputs[k];
        b->input_derivative[k][0] = fmu->s.input_derivative[vr][0];
        b->input_derivative[k][1] = fmu->s.input_derivative[vr][1];
        b->input_derivative_given[k] = fmu->s.input_derivative_given[vr];
        b->input_previous[k] = fmu->s.input_previous[vr];
    }
    b->input_previous_time = fmu->s.input_previous_time;
    b->input_previous_valid = fmu->s.input_previous_valid;
    b->v = fmu->s.v;
    memcpy(b->x, fmu->s.x, sizeof b->x);
    b->solver = fmu->s.solver;
    b->internal = fmu->s.internal;
}

static void restore_step(FmuInstance *fmu, const StepBackup *b) {
    fmu->s.time = b->time;
    fmu->s.input_time = b->input_time;
    for (int k = 0; k < fmu->n_real_inputs; k++) {
        const int vr = fmu->real_inputs[k];
        fmu->s.input_derivative[vr][0] = b->input_derivative[k][0];
        fmu->s.input_derivative[vr][1] = b->input_derivative[k][1];
        fmu->s.input_derivative_given[vr] = b->input_derivative_given[k];
        fmu->s.input_previous[vr] = b->input_previous[k];
    }
    fmu->s.input_previous_time = b->input_previous_time;
    fmu->s.input_previous_valid = b->input_previous_valid;
    fmu->s.v = b->v;
    memcpy(fmu->s.x, b->x, sizeof b->x);
    fmu->s.solver = b->solver;
    fmu->s.internal = b->internal;
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint, fmi2Real communicationStepSize,
                      fmi2Boolean noSetFMUStatePriorToCurrentPoint) {
    FmuInstance *fmu = (FmuInstance *)c;
    (void)noSetFMUStatePriorToCurrentPoint;
    if (!fmu_allowed(fmu, "fmi2DoStep", PHASE_STEP_COMPLETE)) return fmi2Error;
    if (fmu->model_exchange) {
        LOG_ERROR(fmu, "fmi2DoStep: this instance is Model Exchange (the importer's solver steps it)");
        return fmi2Error;
    }
    fmu->warned = 0;
    double t0 = fmu->s.time, h = communicationStepSize;
    if (!(h > 0.0) || !isfinite(h)) {
        LOG_ERROR(fmu, "fmi2DoStep: communication step size %g must be positive and finite", h);
        return fmi2Error;
    }
    if (fmu->s.stop_time_defined && t0 + h > fmu->s.stop_time + 1e-9 * fmax(1.0, fabs(fmu->s.stop_time))) {
        LOG_ERROR(fmu, "fmi2DoStep: a step to %.12g s passes the stop time %.12g s of fmi2SetupExperiment", t0 + h,
                  fmu->s.stop_time);
        return fmi2Error;
    }
    if (!(fabs(currentCommunicationPoint - t0) <= 1e-9 * fmax(1.0, fabs(t0)))) {
        LOG_ERROR(fmu, "fmi2DoStep: current communication point %.12g s differs from the FMU's time %.12g s",
                  currentCommunicationPoint, t0);
        return fmi2Error;
    }
    /* A failed step leaves the instance exactly as it was before it, for inspection or retry: what
     * a step changes is kept aside (the inputs and their derivatives it only reads). */
    StepBackup before;
    backup_step(fmu, &before);
    fmu_extrapolate_inputs(fmu, t0);
    if (model_do_step(fmu, h) != fmi2OK) {
        restore_step(fmu, &before);
        fmu->s.phase = PHASE_ERROR;
        return fmi2Error;
    }
    fmu->s.time = t0 + h;
#if MODEL_SHARED_SOLVER
    fmu->s.v.solver_steps = fmu->s.solver.steps < INT_MAX ? (int)fmu->s.solver.steps : INT_MAX;
    fmu->s.v.solver_rejected = fmu->s.solver.rejected < INT_MAX ? (int)fmu->s.solver.rejected : INT_MAX;
#endif
    outputs_computed(fmu);
    for (int k = 0; k < fmu->n_real_outputs; k++) {
        const int vr = fmu->real_outputs[k];
        if (!isfinite(*(double *)fmu_value_address(fmu, vr))) {
            LOG_ERROR(fmu, "fmi2DoStep: output '%s' is not finite at t = %.9g s", fmu_variables[vr].name,
                      fmu->s.time);
            restore_step(fmu, &before);
            fmu->s.phase = PHASE_ERROR;
            return fmi2Error;
        }
    }
    for (int k = 0; k < fmu->n_real_inputs; k++) fmu->s.input_derivative_given[fmu->real_inputs[k]] = 0; /* spent */
    return fmu->warned && !fmu->s.v.fmi_warnings_as_ok ? fmi2Warning : fmi2OK;
}

fmi2Status fmi2CancelStep(fmi2Component c) {
    LOG_ERROR((FmuInstance *)c, "fmi2CancelStep: illegal call sequence: fmi2DoStep never runs asynchronously");
    return fmi2Error;
}

/* FMI 2.0: the status functions in step complete, step failed and terminated (not in error) */
#define STATUS_PHASES (PHASE_STEP_COMPLETE | PHASE_STEP_FAILED | PHASE_TERMINATED)

fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind s, fmi2Status *value) {
    (void)s; (void)value;
    LOG_ERROR((FmuInstance *)c, "fmi2GetStatus: no asynchronous step is pending");
    return fmi2Error;
}

fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind s, fmi2Real *value) {
    FmuInstance *fmu = (FmuInstance *)c;
    if (!cs_allowed(fmu, "fmi2GetRealStatus", STATUS_PHASES)) return fmi2Error;
    if (!value) { LOG_ERROR(fmu, "fmi2GetRealStatus: NULL value"); return fmi2Error; }
    if (s == fmi2LastSuccessfulTime) { *value = fmu->s.time; return fmi2OK; }
    LOG_ERROR(fmu, "fmi2GetRealStatus: status kind %d not provided", (int)s);
    return fmi2Error;
}

fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind s, fmi2Integer *value) {
    (void)s; (void)value;
    LOG_ERROR((FmuInstance *)c, "fmi2GetIntegerStatus: no integer status is provided");
    return fmi2Error;
}

fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind s, fmi2Boolean *value) {
    FmuInstance *fmu = (FmuInstance *)c;
    if (!cs_allowed(fmu, "fmi2GetBooleanStatus", STATUS_PHASES)) return fmi2Error;
    if (!value) { LOG_ERROR(fmu, "fmi2GetBooleanStatus: NULL value"); return fmi2Error; }
    if (s == fmi2Terminated) { *value = fmi2False; return fmi2OK; }
    LOG_ERROR(fmu, "fmi2GetBooleanStatus: status kind %d not provided", (int)s);
    return fmi2Error;
}

fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind s, fmi2String *value) {
    (void)s; (void)value;
    LOG_ERROR((FmuInstance *)c, "fmi2GetStringStatus: no string status is provided");
    return fmi2Error;
}
