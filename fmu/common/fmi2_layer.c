/* Generic FMI 2.0 Co-Simulation layer: the entry points, the call-sequence checks of the FMI 2.0
 * state machine, logging, validation of what is set, FMU state get/set/serialize and input
 * extrapolation. It is compiled once per model, against that model's variables.h; the model
 * itself only implements the four hooks of fmu_common.h.
 */
#include "fmu_common.h"

#include <limits.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#ifndef MODEL_GUID
#error "MODEL_GUID must be defined by the build (a hash of the model's variables.h)"
#endif

/* ------------------------------------------------------------------------------------------ */
/* Logging                                                                                     */

void fmu_log(const FmuInstance *fmu, fmi2Status status, const char *category, const char *format, ...) {
    if (!fmu) return;
    /* a warning makes the call that raised it return fmi2Warning, logged or not (the instance
     * itself is never const: models only get read access to it) */
    if (status == fmi2Warning) ((FmuInstance *)fmu)->warned = 1;
    if (!fmu->callbacks.logger) return;
    /* errors and the warnings a call returns always carry their reason, logging on or off (FMI 3.0
     * requires it of a warning, FMI 2.0 permits it): a tool that stops at a warning can say why;
     * a warning returned as fmi2OK (fmi.warnings_as_ok) is logged only where warnings are asked for */
    int enabled = fmu->log_all || (status >= fmi2Error && fmu->log_errors) ||
                  (status == fmi2Warning && (fmu->log_warnings || !fmu->s.v.fmi_warnings_as_ok)) ||
                  (strcmp(category, "logEvents") == 0 && fmu->log_events);
    if (!enabled) return;
    char message[1024], escaped[2048];
    va_list args;
    va_start(args, format);
    vsnprintf(message, sizeof message, format, args);
    va_end(args);
    /* The importer may treat the message as a format string: escape '%'. */
    size_t j = 0;
    for (size_t i = 0; message[i] && j + 2 < sizeof escaped; i++) {
        if (message[i] == '%') escaped[j++] = '%';
        escaped[j++] = message[i];
    }
    escaped[j] = '\0';
    fmu->callbacks.logger(fmu->callbacks.componentEnvironment, fmu->instance_name, status, category,
                          escaped);
}

#define LOG_ERROR(fmu, ...) fmu_log((fmu), fmi2Error, "logStatusError", __VA_ARGS__)

static const char *phase_name(int phase) {
    switch (phase) {
    case PHASE_INSTANTIATED: return "instantiated";
    case PHASE_INITIALIZATION: return "initialization mode";
    case PHASE_STEP_COMPLETE: return "step complete";
    case PHASE_STEP_FAILED: return "step failed";
    case PHASE_TERMINATED: return "terminated";
    case PHASE_ERROR: return "error";
    }
    return "unknown";
}

/* The call-sequence check: `allowed` is the set of phases in which `call` may be made. */
static int allowed(FmuInstance *fmu, const char *call, int phases) {
    if (!fmu) return 0;
    if (fmu->s.phase & phases) return 1;
    LOG_ERROR(fmu, "%s: illegal call sequence: not allowed in state '%s'", call, phase_name(fmu->s.phase));
    return 0;
}

#define ANY_LIVE_PHASE                                                                            \
    (PHASE_INSTANTIATED | PHASE_INITIALIZATION | PHASE_STEP_COMPLETE | PHASE_STEP_FAILED |         \
     PHASE_TERMINATED | PHASE_ERROR)
#define AFTER_INITIALIZATION (PHASE_STEP_COMPLETE | PHASE_STEP_FAILED | PHASE_TERMINATED | PHASE_ERROR)

/* ------------------------------------------------------------------------------------------ */
/* Variables                                                                                   */

static void *value_address(FmuInstance *fmu, int vr) {
    return (char *)&fmu->s.v + fmu_variables[vr].offset;
}

static void set_start_values(FmuInstance *fmu) {
    for (int vr = 1; vr < VR_COUNT; vr++) {
        const FmuVariable *var = &fmu_variables[vr];
        if (var->type == FMU_REAL) *(double *)value_address(fmu, vr) = var->start;
        else if (var->type == FMU_STRING) ((FmuText *)value_address(fmu, vr))->text[0] = '\0';
        else *(int *)value_address(fmu, vr) = (int)var->start;
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
    } else if (!(fmu->s.phase & (PHASE_INSTANTIATED | PHASE_INITIALIZATION))) {
        LOG_ERROR(fmu, "%s: illegal call sequence: '%s' cannot be set in state '%s'", call, var->name,
                  phase_name(fmu->s.phase));
        return 0;
    }
    if (!isfinite(value)) {
        LOG_ERROR(fmu, "%s: '%s' = %g rejected: not a finite number", call, var->name, value);
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
        if (!isfinite(*(double *)value_address(fmu, vr))) {
            LOG_ERROR(fmu, "%s: output '%s' is not finite at t = %.9g s (the inputs or parameters are beyond what the "
                      "model can compute)", call, fmu_variables[vr].name, fmu->s.time);
            return 0;
        }
    }
    return 1;
}

/* Outputs recomputed if inputs or parameters changed; 0 (logged) when one is not finite. */
static int refresh_outputs(FmuInstance *fmu, const char *call) {
    if (!fmu->outputs_stale) return 1;
    if (fmu->s.phase & PHASE_INITIALIZATION) model_initialize(fmu);
    if (fmu->s.phase & (PHASE_INITIALIZATION | AFTER_INITIALIZATION)) model_compute_outputs(fmu);
    fmu->outputs_stale = 0;
    return outputs_finite(fmu, call);
}

double fmu_input_at(const FmuInstance *fmu, int vr, double t) {
    double value = *(const double *)((const char *)&fmu->s.v + fmu_variables[vr].offset);
    const double dt = t - fmu->s.input_time;
    if (fmu->s.input_derivative_given[vr] >= 1) value += fmu->s.input_derivative[vr][0] * dt;
    if (fmu->s.input_derivative_given[vr] >= 2) value += 0.5 * fmu->s.input_derivative[vr][1] * dt * dt;
    return value;
}

/* The inputs that carry another input's exact rate (a model's MODEL_INPUT_RATES(R): R(input, its
 * rate input)), and those the model keeps piecewise constant (MODEL_HELD_INPUTS), which its own
 * extrapolation leaves held. */
#ifndef MODEL_INPUT_RATES
#define MODEL_INPUT_RATES(R)
#endif
#ifndef MODEL_HELD_INPUTS
#define MODEL_HELD_INPUTS
#endif
#define RATE_PAIR(input, rate) {input, rate},
static const int INPUT_RATES[][2] = {MODEL_INPUT_RATES(RATE_PAIR){0, 0}};
static const int HELD_INPUTS[] = {MODEL_HELD_INPUTS 0};

static int rate_input_of(int vr) {
    for (size_t k = 0; INPUT_RATES[k][0]; k++)
        if (INPUT_RATES[k][0] == vr) return INPUT_RATES[k][1];
    return 0;
}

static int held_input(int vr) {
    for (size_t k = 0; HELD_INPUTS[k]; k++)
        if (HELD_INPUTS[k] == vr) return 1;
    return 0;
}

double fmu_input_rate_at(const FmuInstance *fmu, int vr, double t) {
    if (fmu->s.input_derivative_given[vr] == 0) {
        const int rate = rate_input_of(vr);
        return rate ? fmu_input_at(fmu, rate, t) : 0.0;
    }
    double rate = fmu->s.input_derivative[vr][0];
    if (fmu->s.input_derivative_given[vr] >= 2) rate += fmu->s.input_derivative[vr][1] * (t - fmu->s.input_time);
    return rate;
}

/* At a step's start from t0, with fmi.extrapolate_inputs: every Real input the master gave no
 * derivative for gets one from the FMU itself, as if the master had sent it: the value of its rate
 * input where it has one (exact), else the slope from its value at the last step's start to its
 * value now (none on the first step); inputs the model holds are left alone. A master that holds
 * its inputs then couples at second order, as one that extrapolates them at order 1. */
static void extrapolate_inputs(FmuInstance *fmu, double t0) {
    FmuSnapshot *s = &fmu->s;
    if (!s->v.fmi_extrapolate_inputs) return;
    const int history = s->input_previous_valid && t0 > s->input_previous_time;
    const double span = t0 - s->input_previous_time;
    for (int vr = 1; vr < VR_COUNT; vr++) {
        if (fmu_variables[vr].causality != FMU_INPUT || fmu_variables[vr].type != FMU_REAL) continue;
        const double value = *(const double *)value_address(fmu, vr);
        if (s->input_derivative_given[vr] == 0 && !held_input(vr)) {
            const int rate = rate_input_of(vr);
            const double slope = rate ? *(const double *)value_address(fmu, rate)
                                      : history ? (value - s->input_previous[vr]) / span : 0.0;
            s->input_derivative[vr][0] = isfinite(slope) ? slope : 0.0; /* (huge values a tiny step apart) */
            s->input_derivative[vr][1] = 0.0;
            s->input_derivative_given[vr] = 1;
        }
        s->input_previous[vr] = value;
    }
    s->input_previous_time = t0;
    s->input_previous_valid = 1;
    s->input_time = t0; /* the values held since they were set are the values at t0 */
}

int fmu_reject(const FmuInstance *fmu, int vr, const char *rule) {
    const FmuVariable *var = &fmu_variables[vr];
    const char *address = (const char *)&fmu->s.v + var->offset;
    if (var->type == FMU_STRING) {
        fmu_log(fmu, fmi2Error, "logStatusError", "parameter '%s' = \"%s\": %s", var->name,
                ((const FmuText *)address)->text, rule);
        return 1;
    }
    double value = var->type == FMU_REAL ? *(const double *)address : *(const int *)address;
    fmu_log(fmu, fmi2Error, "logStatusError", "parameter '%s' = %g %s: %s", var->name, value, var->unit, rule);
    return 1;
}

void *fmu_calloc(const FmuInstance *fmu, size_t count, size_t size) {
    return fmu->callbacks.allocateMemory(count, size);
}

void fmu_free(const FmuInstance *fmu, void *memory) {
    if (memory) fmu->callbacks.freeMemory(memory);
}

void fmu_set_model_data(FmuInstance *fmu, void *data, void (*release)(FmuInstance *fmu, void *data)) {
    if (fmu->model_data && fmu->free_model_data) fmu->free_model_data(fmu, fmu->model_data);
    fmu->model_data = data;
    fmu->free_model_data = release;
}

double *fmu_real(FmuInstance *fmu, int vr) { return (double *)value_address(fmu, vr); }
int *fmu_integer(FmuInstance *fmu, int vr) { return (int *)value_address(fmu, vr); }

int fmu_input_has_derivative(const FmuInstance *fmu, int vr) { return fmu->s.input_derivative_given[vr]; }

#if MODEL_N_STATES > 0
fmi2Status fmu_integrate(FmuInstance *fmu, const OdeProblem *problem, void *ctx, double h, double max_step) {
    OdeSolver *solver = &fmu->s.solver;
    solver->method = fmu->s.v.solver_method;
    solver->step = (max_step > 0.0 && max_step < fmu->s.v.solver_step) ? max_step : fmu->s.v.solver_step;
    solver->rtol = fmu->s.v.solver_rtol;
    solver->atol = fmu->s.v.solver_atol;
    double t_failed;
    OdeResult r = ode_integrate(solver, problem, ctx, fmu->s.x, fmu->s.time, fmu->s.time + h, &t_failed);
    if (r == ODE_OK) return fmi2OK;
    LOG_ERROR(fmu, "fmi2DoStep: internal solver failed at t = %.9g s (step from %.9g s): %s", t_failed,
              fmu->s.time, ode_result_text(r));
    return fmi2Error;
}

static void release_exponential(FmuInstance *fmu, void *data) { fmu_free(fmu, data); }

fmi2Status fmu_integrate_exponential(FmuInstance *fmu, const OdeProblem *problem, OdeRhsLinear rhs_linear,
                                     const double *linear_part, double h) {
    if (!fmu->model_data) { /* derived data: outside the FMU state, rebuilt for a new step or gain */
        void *cache = fmu_calloc(fmu, 1, sizeof(OdeExponentialCache));
        if (!cache) {
            LOG_ERROR(fmu, "fmi2DoStep: solver.exponential: out of memory");
            return fmi2Error;
        }
        fmu_set_model_data(fmu, cache, release_exponential);
    }
    double t_failed;
    const OdeResult r = ode_exponential_integrate((OdeExponentialCache *)fmu->model_data, &fmu->s.solver, problem,
                                                  rhs_linear, linear_part, fmu, fmu->s.x, fmu->s.time, h,
                                                  fmu->s.v.solver_step, &t_failed);
    if (r == ODE_OK) return fmi2OK;
    LOG_ERROR(fmu, "fmi2DoStep: internal solver failed at t = %.9g s (step from %.9g s): %s", t_failed,
              fmu->s.time, ode_result_text(r));
    return fmi2Error;
}
#endif

/* ------------------------------------------------------------------------------------------ */
/* Instance life cycle                                                                         */

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[]) {
    FmuInstance *fmu = (FmuInstance *)c;
    if (!allowed(fmu, "fmi2SetDebugLogging", ANY_LIVE_PHASE)) return fmi2Error;
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

static void reset_to_start(FmuInstance *fmu) {
    fmu_set_model_data(fmu, NULL, NULL);
    memset(&fmu->s, 0, sizeof fmu->s);
    fmu->s.phase = PHASE_INSTANTIATED;
    set_start_values(fmu);
    fmu->outputs_stale = 1;
}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation, const fmi2CallbackFunctions *functions,
                              fmi2Boolean visible, fmi2Boolean loggingOn) {
    (void)fmuResourceLocation;
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
    if (fmuType != fmi2CoSimulation) {
        LOG_ERROR(&probe, "fmi2Instantiate: %s is a Co-Simulation FMU; Model Exchange is not supported",
                  MODEL_IDENTIFIER_STRING);
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
    fmu->log_errors = 1; /* errors and returned warnings are always reported; the rest only with logging on */
    fmu->log_warnings = fmu->log_events = fmu->log_all = loggingOn;
    for (int vr = 1; vr < VR_COUNT; vr++)
        if (fmu_variables[vr].causality == FMU_OUTPUT && fmu_variables[vr].type == FMU_REAL)
            fmu->real_outputs[fmu->n_real_outputs++] = vr;
    reset_to_start(fmu);
    return fmu;
}

void fmi2FreeInstance(fmi2Component c) {
    FmuInstance *fmu = (FmuInstance *)c;
    if (!fmu) return;
    fmi2CallbackFreeMemory release = fmu->callbacks.freeMemory;
    fmu_set_model_data(fmu, NULL, NULL);
    release(fmu->instance_name);
    release(fmu);
}

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    FmuInstance *fmu = (FmuInstance *)c;
    if (!allowed(fmu, "fmi2SetupExperiment", PHASE_INSTANTIATED)) return fmi2Error;
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
    if (!allowed(fmu, "fmi2EnterInitializationMode", PHASE_INSTANTIATED)) return fmi2Error;
    if (model_validate(fmu) != fmi2OK) return fmi2Error;
    fmu->s.phase = PHASE_INITIALIZATION;
    fmu->outputs_stale = 1;
    return fmi2OK;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    FmuInstance *fmu = (FmuInstance *)c;
    if (!allowed(fmu, "fmi2ExitInitializationMode", PHASE_INITIALIZATION)) return fmi2Error;
    if (model_validate(fmu) != fmi2OK) return fmi2Error;
    model_initialize(fmu);
    fmu->s.input_previous_valid = 0; /* the FMU's own extrapolation starts with the first step */
    fmu->s.phase = PHASE_STEP_COMPLETE;
    model_compute_outputs(fmu);
    fmu->outputs_stale = 0;
    if (!outputs_finite(fmu, "fmi2ExitInitializationMode")) {
        fmu->s.phase = PHASE_ERROR;
        return fmi2Error;
    }
    return fmi2OK;
}

fmi2Status fmi2Terminate(fmi2Component c) {
    FmuInstance *fmu = (FmuInstance *)c;
    if (!allowed(fmu, "fmi2Terminate", PHASE_STEP_COMPLETE | PHASE_STEP_FAILED)) return fmi2Error;
    fmu->s.phase = PHASE_TERMINATED;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component c) {
    FmuInstance *fmu = (FmuInstance *)c;
    if (!allowed(fmu, "fmi2Reset", ANY_LIVE_PHASE)) return fmi2Error;
    reset_to_start(fmu);
    return fmi2OK;
}

/* ------------------------------------------------------------------------------------------ */
/* Get and set                                                                                 */

/* FMI 2.0, Co-Simulation state machine: the fmi2Get functions in initialization mode, slave initialized,
 * terminated and error, not before initialization */
#define GET_PHASES (PHASE_INITIALIZATION | AFTER_INITIALIZATION)

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[]) {
    FmuInstance *fmu = (FmuInstance *)c;
    if (!allowed(fmu, "fmi2GetReal", GET_PHASES)) return fmi2Error;
    if (nvr > 0 && (!vr || !value)) { LOG_ERROR(fmu, "fmi2GetReal: NULL array"); return fmi2Error; }
    if (!refresh_outputs(fmu, "fmi2GetReal")) return fmi2Error;
    int all_finite = 1;
    for (size_t i = 0; i < nvr; i++) {
        if (!check_reference(fmu, "fmi2GetReal", vr[i], FMU_REAL)) return fmi2Error;
        value[i] = *(double *)value_address(fmu, (int)vr[i]);
        all_finite = all_finite && isfinite(value[i]);
    }
    if (!all_finite) { /* only an instance in the error state holds such values: read for diagnosis */
        fmu_log(fmu, fmi2Warning, "logStatusWarning", "fmi2GetReal: values of an instance in state '%s' that are not "
                "finite", phase_name(fmu->s.phase));
        return fmi2Warning;
    }
    return fmi2OK;
}

static fmi2Status get_ints(FmuInstance *fmu, const char *call, FmuType type,
                           const fmi2ValueReference vr[], size_t nvr, int value[]) {
    if (!allowed(fmu, call, GET_PHASES)) return fmi2Error;
    if (nvr > 0 && (!vr || !value)) { LOG_ERROR(fmu, "%s: NULL array", call); return fmi2Error; }
    if (!refresh_outputs(fmu, call)) return fmi2Error;
    for (size_t i = 0; i < nvr; i++) {
        if (!check_reference(fmu, call, vr[i], type)) return fmi2Error;
        value[i] = *(int *)value_address(fmu, (int)vr[i]);
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
    if (!allowed(fmu, "fmi2GetString", GET_PHASES)) return fmi2Error;
    if (nvr > 0 && (!vr || !value)) { LOG_ERROR(fmu, "fmi2GetString: NULL array"); return fmi2Error; }
    for (size_t i = 0; i < nvr; i++) {
        if (!check_reference(fmu, "fmi2GetString", vr[i], FMU_STRING)) return fmi2Error;
        value[i] = ((FmuText *)value_address(fmu, (int)vr[i]))->text;
    }
    return fmi2OK;
}

#define SET_PHASES (PHASE_INSTANTIATED | PHASE_INITIALIZATION | PHASE_STEP_COMPLETE)

fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[]) {
    FmuInstance *fmu = (FmuInstance *)c;
    if (!allowed(fmu, "fmi2SetReal", SET_PHASES)) return fmi2Error;
    if (nvr > 0 && (!vr || !value)) { LOG_ERROR(fmu, "fmi2SetReal: NULL array"); return fmi2Error; }
    /* Check all first, so that a rejected call changes nothing. */
    for (size_t i = 0; i < nvr; i++)
        if (!check_reference(fmu, "fmi2SetReal", vr[i], FMU_REAL) ||
            !check_settable(fmu, "fmi2SetReal", (int)vr[i], value[i]))
            return fmi2Error;
    const int any_parameter = sets_parameter(vr, nvr);
    ModelVariables before;
    if (any_parameter) before = fmu->s.v;
    int any_input = 0;
    for (size_t i = 0; i < nvr; i++) {
        *(double *)value_address(fmu, (int)vr[i]) = value[i];
        if (fmu_variables[vr[i]].causality == FMU_INPUT) any_input = 1;
    }
    return after_set(fmu, &before, any_input, any_parameter);
}

static fmi2Status set_ints(FmuInstance *fmu, const char *call, FmuType type,
                           const fmi2ValueReference vr[], size_t nvr, const int value[]) {
    if (!allowed(fmu, call, SET_PHASES)) return fmi2Error;
    if (nvr > 0 && (!vr || !value)) { LOG_ERROR(fmu, "%s: NULL array", call); return fmi2Error; }
    for (size_t i = 0; i < nvr; i++)
        if (!check_reference(fmu, call, vr[i], type) ||
            !check_settable(fmu, call, (int)vr[i], type == FMU_BOOLEAN ? (value[i] != 0) : value[i]))
            return fmi2Error;
    const int any_parameter = sets_parameter(vr, nvr);
    ModelVariables before;
    if (any_parameter) before = fmu->s.v;
    int any_input = 0;
    for (size_t i = 0; i < nvr; i++) {
        *(int *)value_address(fmu, (int)vr[i]) = type == FMU_BOOLEAN ? (value[i] != 0) : value[i];
        if (fmu_variables[vr[i]].causality == FMU_INPUT) any_input = 1;
    }
    return after_set(fmu, &before, any_input, any_parameter);
}

fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Integer value[]) {
    return set_ints((FmuInstance *)c, "fmi2SetInteger", FMU_INTEGER, vr, nvr, value);
}

fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Boolean value[]) {
    return set_ints((FmuInstance *)c, "fmi2SetBoolean", FMU_BOOLEAN, vr, nvr, value);
}

fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2String value[]) {
    FmuInstance *fmu = (FmuInstance *)c;
    if (!allowed(fmu, "fmi2SetString", SET_PHASES)) return fmi2Error;
    if (nvr > 0 && (!vr || !value)) { LOG_ERROR(fmu, "fmi2SetString: NULL array"); return fmi2Error; }
    for (size_t i = 0; i < nvr; i++) {
        if (!check_reference(fmu, "fmi2SetString", vr[i], FMU_STRING) ||
            !check_settable(fmu, "fmi2SetString", (int)vr[i], fmu_variables[vr[i]].min))
            return fmi2Error;
        if (value[i] && strlen(value[i]) >= FMU_TEXT_MAX) {
            LOG_ERROR(fmu, "fmi2SetString: '%s' rejected: longer than %d bytes", fmu_variables[vr[i]].name,
                      FMU_TEXT_MAX - 1);
            return fmi2Error;
        }
    }
    const int any_parameter = sets_parameter(vr, nvr);
    ModelVariables before;
    if (any_parameter) before = fmu->s.v;
    int any_input = 0;
    for (size_t i = 0; i < nvr; i++) {
        FmuText *text = (FmuText *)value_address(fmu, (int)vr[i]);
        strcpy(text->text, value[i] ? value[i] : ""); /* the FMU keeps its own copy (FMI 2.0, 2.1.7) */
        if (fmu_variables[vr[i]].causality == FMU_INPUT) any_input = 1;
    }
    return after_set(fmu, &before, any_input, any_parameter);
}

/* ------------------------------------------------------------------------------------------ */
/* FMU state                                                                                   */

/* A state as the importer holds it: a tag that names this build and the snapshot's size and
 * checksum, whether the outputs were current, then the snapshot. The checksum covers every byte
 * that is read back from the tag's end on (the outputs_stale flag and the snapshot). A state pointer is checked by its
 * tag before anything is copied (a pointer from another FMU, or memory that is no state, is
 * refused without reading past the tag: every state is larger than it), and a restored snapshot is
 * validated as if its values had been set one by one. */
typedef struct {
    char magic[8];
    unsigned long long guid_hash, size, checksum;
    int outputs_stale;
} StateTag;

typedef struct {
    StateTag tag;
    FmuSnapshot s;
} StoredState;

static const char STATE_MAGIC[8] = "STEWST1";

#define FNV_OFFSET 1469598103934665603ULL

static unsigned long long fnv1a_from(unsigned long long hash, const void *data, size_t n) {
    const unsigned char *bytes = (const unsigned char *)data;
    for (size_t i = 0; i < n; i++) hash = (hash ^ bytes[i]) * 1099511628211ULL;
    return hash;
}

static unsigned long long fnv1a(const void *data, size_t n) { return fnv1a_from(FNV_OFFSET, data, n); }

/* The snapshot, then the outputs_stale flag. */
static unsigned long long state_checksum(const StoredState *stored) {
    return fnv1a_from(fnv1a(&stored->s, sizeof(FmuSnapshot)), &stored->tag.outputs_stale,
                      sizeof stored->tag.outputs_stale);
}

static void tag_state(StoredState *stored, int outputs_stale) {
    memcpy(stored->tag.magic, STATE_MAGIC, sizeof stored->tag.magic);
    stored->tag.guid_hash = fnv1a(MODEL_GUID, strlen(MODEL_GUID));
    stored->tag.size = sizeof(FmuSnapshot);
    stored->tag.outputs_stale = outputs_stale;
    stored->tag.checksum = state_checksum(stored);
}

/* Is this a state of this build, unaltered? Logs why not. */
static int state_is_ours(FmuInstance *fmu, const char *call, const StoredState *stored, int check_sum) {
    if (memcmp(stored->tag.magic, STATE_MAGIC, sizeof STATE_MAGIC) != 0 ||
        stored->tag.guid_hash != fnv1a(MODEL_GUID, strlen(MODEL_GUID)) || stored->tag.size != sizeof(FmuSnapshot)) {
        LOG_ERROR(fmu, "%s: not a state of this build of %s (%s)", call, MODEL_IDENTIFIER_STRING, MODEL_GUID);
        return 0;
    }
    if (check_sum && (stored->tag.checksum != state_checksum(stored) ||
                      (stored->tag.outputs_stale != 0 && stored->tag.outputs_stale != 1))) {
        LOG_ERROR(fmu, "%s: the state's bytes were altered (checksum mismatch)", call);
        return 0;
    }
    return 1;
}

/* The snapshot now in fmu->s as trustworthy as set values: a valid phase and time, every
 * parameter and input finite and within its bounds, finite internal states and solver memory,
 * and the model's own rules (which also rebuild model data such as a table from the snapshot). */
static int snapshot_valid(FmuInstance *fmu, const char *call) {
    const FmuSnapshot *s = &fmu->s;
    const int phase = s->phase;
    if (phase != PHASE_INSTANTIATED && phase != PHASE_INITIALIZATION && phase != PHASE_STEP_COMPLETE &&
        phase != PHASE_STEP_FAILED && phase != PHASE_TERMINATED && phase != PHASE_ERROR) {
        LOG_ERROR(fmu, "%s: the state's phase %d is not one of FMI 2.0's", call, phase);
        return 0;
    }
    if (!isfinite(s->time) || !isfinite(s->input_time) || !isfinite(s->stop_time) ||
        !isfinite(s->input_previous_time) || (s->input_previous_valid != 0 && s->input_previous_valid != 1)) {
        LOG_ERROR(fmu, "%s: the state's time is not finite", call);
        return 0;
    }
    for (int vr = 1; vr < VR_COUNT; vr++) {
        const FmuVariable *var = &fmu_variables[vr];
        if (var->causality == FMU_OUTPUT || var->causality == FMU_LOCAL || var->type == FMU_STRING) continue;
        const double value = var->type == FMU_REAL ? *(double *)value_address(fmu, vr)
                                                   : (double)*(int *)value_address(fmu, vr);
        if (!isfinite(value) || value < var->min || value > var->max) {
            LOG_ERROR(fmu, "%s: the state's '%s' = %g is outside [%g, %g] %s", call, var->name, value, var->min,
                      var->max, var->unit);
            return 0;
        }
        if (s->input_derivative_given[vr] < 0 || s->input_derivative_given[vr] > 2 ||
            !isfinite(s->input_derivative[vr][0]) || !isfinite(s->input_derivative[vr][1]) ||
            !isfinite(s->input_previous[vr])) {
            LOG_ERROR(fmu, "%s: the state's input derivatives of '%s' are invalid", call, var->name);
            return 0;
        }
    }
    for (int vr = 1; vr < VR_COUNT; vr++)
        if (fmu_variables[vr].type == FMU_STRING &&
            memchr(((FmuText *)value_address(fmu, vr))->text, '\0', FMU_TEXT_MAX) == NULL) {
            LOG_ERROR(fmu, "%s: the state's '%s' is not a terminated string", call, fmu_variables[vr].name);
            return 0;
        }
#if MODEL_N_STATES > 0
    for (int k = 0; k < MODEL_N_STATES; k++)
        if (!isfinite(s->x[k])) {
            LOG_ERROR(fmu, "%s: the state's internal state %d is not finite", call, k);
            return 0;
        }
    const OdeSolver *solver = &s->solver;
    if (!(solver->h_next >= 0.0 && solver->h_next <= 1.0) || !(solver->steps >= 0.0) || !(solver->rejected >= 0.0)) {
        LOG_ERROR(fmu, "%s: the state's solver memory is invalid", call);
        return 0;
    }
#endif
    return model_validate(fmu) == fmi2OK;
}

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *state) {
    FmuInstance *fmu = (FmuInstance *)c;
    if (!allowed(fmu, "fmi2GetFMUstate", ANY_LIVE_PHASE)) return fmi2Error;
    if (!state) { LOG_ERROR(fmu, "fmi2GetFMUstate: NULL state pointer"); return fmi2Error; }
    if (*state && !state_is_ours(fmu, "fmi2GetFMUstate", (const StoredState *)*state, 0)) return fmi2Error;
    if (!*state) *state = fmu->callbacks.allocateMemory(1, sizeof(StoredState));
    if (!*state) { LOG_ERROR(fmu, "fmi2GetFMUstate: out of memory"); return fmi2Error; }
    StoredState *stored = (StoredState *)*state;
    memcpy(&stored->s, &fmu->s, sizeof(FmuSnapshot));
    tag_state(stored, fmu->outputs_stale);
    return fmi2OK;
}

fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate state) {
    FmuInstance *fmu = (FmuInstance *)c;
    if (!allowed(fmu, "fmi2SetFMUstate", ANY_LIVE_PHASE)) return fmi2Error;
    if (!state) { LOG_ERROR(fmu, "fmi2SetFMUstate: NULL state"); return fmi2Error; }
    const StoredState *stored = (const StoredState *)state;
    if (!state_is_ours(fmu, "fmi2SetFMUstate", stored, 1)) return fmi2Error;
    FmuSnapshot before = fmu->s;
    const int stale_before = fmu->outputs_stale;
    memcpy(&fmu->s, &stored->s, sizeof(FmuSnapshot));
    if (!snapshot_valid(fmu, "fmi2SetFMUstate")) {
        fmu->s = before;
        fmu->outputs_stale = stale_before;
        model_validate(fmu); /* model data back to the instance's own */
        return fmi2Error;
    }
    /* the outputs are the snapshot's own: exactly what they were when the state was taken */
    fmu->outputs_stale = stored->tag.outputs_stale;
    return fmi2OK;
}

fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *state) {
    FmuInstance *fmu = (FmuInstance *)c;
    if (!fmu) return fmi2Error;
    if (state && *state) {
        if (!state_is_ours(fmu, "fmi2FreeFMUstate", (const StoredState *)*state, 0)) return fmi2Error;
        memset(*state, 0, sizeof(StateTag)); /* a freed state is no state any more */
        fmu->callbacks.freeMemory(*state);
        *state = NULL;
    }
    return fmi2OK;
}

/* Serialized form: the stored state (tag and snapshot) as bytes. */
fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate state, size_t *size) {
    FmuInstance *fmu = (FmuInstance *)c;
    if (!allowed(fmu, "fmi2SerializedFMUstateSize", ANY_LIVE_PHASE)) return fmi2Error;
    if (!size) { LOG_ERROR(fmu, "fmi2SerializedFMUstateSize: NULL size"); return fmi2Error; }
    if (state && !state_is_ours(fmu, "fmi2SerializedFMUstateSize", (const StoredState *)state, 0)) return fmi2Error;
    *size = sizeof(StoredState);
    return fmi2OK;
}

fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate state, fmi2Byte bytes[], size_t size) {
    FmuInstance *fmu = (FmuInstance *)c;
    if (!allowed(fmu, "fmi2SerializeFMUstate", ANY_LIVE_PHASE)) return fmi2Error;
    if (!state || !bytes || size < sizeof(StoredState)) {
        LOG_ERROR(fmu, "fmi2SerializeFMUstate: NULL state or buffer, or buffer of %zu bytes < %zu", size,
                  sizeof(StoredState));
        return fmi2Error;
    }
    if (!state_is_ours(fmu, "fmi2SerializeFMUstate", (const StoredState *)state, 1)) return fmi2Error;
    memcpy(bytes, state, sizeof(StoredState));
    return fmi2OK;
}

fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte bytes[], size_t size, fmi2FMUstate *state) {
    FmuInstance *fmu = (FmuInstance *)c;
    if (!allowed(fmu, "fmi2DeSerializeFMUstate", ANY_LIVE_PHASE)) return fmi2Error;
    if (!bytes || !state || size != sizeof(StoredState)) {
        LOG_ERROR(fmu, "fmi2DeSerializeFMUstate: expected %zu bytes, got %zu", sizeof(StoredState), size);
        return fmi2Error;
    }
    StoredState *copy = (StoredState *)fmu->callbacks.allocateMemory(1, sizeof(StoredState));
    if (!copy) { LOG_ERROR(fmu, "fmi2DeSerializeFMUstate: out of memory"); return fmi2Error; }
    memcpy(copy, bytes, sizeof(StoredState));
    if (!state_is_ours(fmu, "fmi2DeSerializeFMUstate", copy, 1)) {
        fmu->callbacks.freeMemory(copy);
        return fmi2Error;
    }
    if (*state) {
        if (!state_is_ours(fmu, "fmi2DeSerializeFMUstate", (const StoredState *)*state, 0)) {
            fmu->callbacks.freeMemory(copy);
            return fmi2Error;
        }
        memcpy(*state, copy, sizeof(StoredState));
        fmu->callbacks.freeMemory(copy);
    } else {
        *state = copy;
    }
    return fmi2OK;
}

fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference vUnknown_ref[],
                                        size_t nUnknown, const fmi2ValueReference vKnown_ref[], size_t nKnown,
                                        const fmi2Real dvKnown[], fmi2Real dvUnknown[]) {
    (void)vUnknown_ref; (void)nUnknown; (void)vKnown_ref; (void)nKnown; (void)dvKnown; (void)dvUnknown;
    LOG_ERROR((FmuInstance *)c, "fmi2GetDirectionalDerivative: not provided (providesDirectionalDerivative=false)");
    return fmi2Error;
}

/* ------------------------------------------------------------------------------------------ */
/* Co-simulation                                                                               */

fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[]) {
    FmuInstance *fmu = (FmuInstance *)c;
    if (!allowed(fmu, "fmi2SetRealInputDerivatives", SET_PHASES)) return fmi2Error;
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
    if (!allowed(fmu, "fmi2GetRealOutputDerivatives", PHASE_STEP_COMPLETE | PHASE_STEP_FAILED)) return fmi2Error;
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
 * the model's memory. */
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
    memcpy(b->input_derivative, fmu->s.input_derivative, sizeof b->input_derivative);
    memcpy(b->input_derivative_given, fmu->s.input_derivative_given, sizeof b->input_derivative_given);
    memcpy(b->input_previous, fmu->s.input_previous, sizeof b->input_previous);
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
    memcpy(fmu->s.input_derivative, b->input_derivative, sizeof b->input_derivative);
    memcpy(fmu->s.input_derivative_given, b->input_derivative_given, sizeof b->input_derivative_given);
    memcpy(fmu->s.input_previous, b->input_previous, sizeof b->input_previous);
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
    if (!allowed(fmu, "fmi2DoStep", PHASE_STEP_COMPLETE)) return fmi2Error;
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
    extrapolate_inputs(fmu, t0);
    if (model_do_step(fmu, h) != fmi2OK) {
        restore_step(fmu, &before);
        fmu->s.phase = PHASE_ERROR;
        return fmi2Error;
    }
    fmu->s.time = t0 + h;
#if MODEL_N_STATES > 0
    fmu->s.v.solver_steps = fmu->s.solver.steps < INT_MAX ? (int)fmu->s.solver.steps : INT_MAX;
    fmu->s.v.solver_rejected = fmu->s.solver.rejected < INT_MAX ? (int)fmu->s.solver.rejected : INT_MAX;
#endif
    model_compute_outputs(fmu);
    fmu->outputs_stale = 0;
    for (int k = 0; k < fmu->n_real_outputs; k++) {
        const int vr = fmu->real_outputs[k];
        if (!isfinite(*(double *)value_address(fmu, vr))) {
            LOG_ERROR(fmu, "fmi2DoStep: output '%s' is not finite at t = %.9g s", fmu_variables[vr].name,
                      fmu->s.time);
            restore_step(fmu, &before);
            fmu->s.phase = PHASE_ERROR;
            return fmi2Error;
        }
    }
    memset(fmu->s.input_derivative_given, 0, sizeof fmu->s.input_derivative_given); /* spent by the step */
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
    if (!allowed(fmu, "fmi2GetRealStatus", STATUS_PHASES)) return fmi2Error;
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
    if (!allowed(fmu, "fmi2GetBooleanStatus", STATUS_PHASES)) return fmi2Error;
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
