/* The runtime services every model calls (fmu_common.h): logging, its variables' storage, its
 * inputs at any time within a step (with the derivatives the master gave or the FMU's own
 * extrapolation), memory and model data, rejecting a parameter, and the integration of its
 * states; and the call-sequence check the FMI layers share (runtime.h).
 */
#include "fmu_common.h"
#include "location.h"
#include "runtime.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

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

const char *fmu_phase_name(int phase) {
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
int fmu_allowed(FmuInstance *fmu, const char *call, int phases) {
    if (!fmu) return 0;
    if (fmu->s.phase & phases) return 1;
    LOG_ERROR(fmu, "%s: illegal call sequence: not allowed in state '%s'", call, fmu_phase_name(fmu->s.phase));
    return 0;
}

/* ------------------------------------------------------------------------------------------ */
/* Variables                                                                                   */

void *fmu_value_address(FmuInstance *fmu, int vr) {
    return (char *)&fmu->s.v + fmu_variables[vr].offset;
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
void fmu_extrapolate_inputs(FmuInstance *fmu, double t0) {
    FmuSnapshot *s = &fmu->s;
    if (!s->v.fmi_extrapolate_inputs) return;
    const int history = s->input_previous_valid && t0 > s->input_previous_time;
    const double span = t0 - s->input_previous_time;
    for (int k = 0; k < fmu->n_real_inputs; k++) {
        const int vr = fmu->real_inputs[k];
        const double value = *(const double *)fmu_value_address(fmu, vr);
        if (s->input_derivative_given[vr] == 0 && !held_input(vr)) {
            const int rate = rate_input_of(vr);
            const double slope = rate ? *(const double *)fmu_value_address(fmu, rate)
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

double *fmu_real(FmuInstance *fmu, int vr) { return (double *)fmu_value_address(fmu, vr); }
int *fmu_integer(FmuInstance *fmu, int vr) { return (int *)fmu_value_address(fmu, vr); }

int fmu_input_has_derivative(const FmuInstance *fmu, int vr) { return fmu->s.input_derivative_given[vr]; }

#if MODEL_SHARED_SOLVER
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

/* ---- the FMU's resources folder ---- */

const char *fmu_resource_path(const FmuInstance *fmu, const char *path, char *out, size_t size) {
    static const char prefix[] = "@resources/";
    if (strncmp(path, prefix, sizeof prefix - 1) != 0) return path;
    if (!fmu->resources || strlen(fmu->resources) + strlen(path) >= size) return NULL;
    strcpy(out, fmu->resources);
    strcat(out, path + sizeof prefix - 1);
    return out;
}

char *fmu_resources_folder(FmuInstance *fmu, const char *location) {
    return location_folder(location, fmu->callbacks.allocateMemory);
}
