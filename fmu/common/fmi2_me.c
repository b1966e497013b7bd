/* The FMI 2.0 Model Exchange API (after the Reference-FMUs, which build one model for both
 * interfaces): the importer's solver integrates the model's continuous states, fmu->s.x, through
 * its derivatives (the model's model_derivatives, the right-hand side its Co-Simulation integrates
 * itself). The same instance life cycle, variables, FMU states and checks as fmi2_layer.c's;
 * after initialization an instance is in Event Mode or Continuous-Time Mode, both the layer's
 * PHASE_STEP_COMPLETE, told apart by fmu->s.continuous_time_mode: the calls Model Exchange adds are
 * allowed in the modes of the standard's state machine (FMI 2.0, section 3.2.3).
 * The shipped models have no state events as Model Exchange (a part with them, such as the PMSM
 * drive's switching inverter, is refused at initialization with its reason): zero event
 * indicators; a model with time events (MODEL_TIME_EVENTS: the trajectory's load pulses, the
 * MPC cueing's solves) updates its discrete state and gives the next in fmi2NewDiscreteStates.
 */
#include "runtime.h"

#include <math.h>
#include <string.h>

#if MODEL_MODEL_EXCHANGE

#define ME_PHASES (PHASE_STEP_COMPLETE)
enum { EVENT_MODE = 1, CONTINUOUS_TIME_MODE = 2, EITHER_MODE = 3 };

/* A Model Exchange call on this instance, now: in one of `phases`, and where that is after
 * initialization, in one of `modes`? Logs why not. */
static int me_allowed_in(FmuInstance *fmu, const char *call, int phases, int modes) {
    if (!fmu_allowed(fmu, call, phases)) return 0;
    if (!fmu->model_exchange) {
        LOG_ERROR(fmu, "%s: this instance is Co-Simulation (fmi2Instantiate with fmi2ModelExchange for Model "
                  "Exchange)", call);
        return 0;
    }
    const int mode = fmu->s.continuous_time_mode ? CONTINUOUS_TIME_MODE : EVENT_MODE;
    if (fmu->s.phase == PHASE_STEP_COMPLETE && !(modes & mode)) {
        LOG_ERROR(fmu, "%s: not allowed in %s (FMI 2.0's Model Exchange state machine)", call,
                  mode == EVENT_MODE ? "Event Mode (fmi2EnterContinuousTimeMode first)"
                                     : "Continuous-Time Mode (fmi2EnterEventMode first)");
        return 0;
    }
    return 1;
}

static int me_allowed(FmuInstance *fmu, const char *call, int phases) {
    return me_allowed_in(fmu, call, phases, EITHER_MODE);
}

static int array_fits(FmuInstance *fmu, const char *call, const void *array, size_t n, size_t expected) {
    if (n != expected) {
        LOG_ERROR(fmu, "%s: %zu values, and the model has %zu", call, n, expected);
        return 0;
    }
    if (n > 0 && !array) {
        LOG_ERROR(fmu, "%s: NULL array", call);
        return 0;
    }
    return 1;
}

fmi2Status fmi2SetTime(fmi2Component c, fmi2Real time) {
    FmuInstance *fmu = (FmuInstance *)c;
    if (!me_allowed(fmu, "fmi2SetTime", ME_PHASES)) return fmi2Error;
    if (!isfinite(time)) {
        LOG_ERROR(fmu, "fmi2SetTime: time %g is not finite", time);
        return fmi2Error;
    }
    fmu->s.time = time;
    fmu->s.input_time = time;
    fmu->outputs_stale = 1;
    return fmi2OK;
}

fmi2Status fmi2SetContinuousStates(fmi2Component c, const fmi2Real x[], size_t nx) {
    FmuInstance *fmu = (FmuInstance *)c;
    if (!me_allowed_in(fmu, "fmi2SetContinuousStates", ME_PHASES, CONTINUOUS_TIME_MODE)) return fmi2Error;
    if (!array_fits(fmu, "fmi2SetContinuousStates", x, nx, MODEL_N_STATES)) return fmi2Error;
    for (size_t k = 0; k < nx; k++)
        if (!isfinite(x[k])) {
            LOG_ERROR(fmu, "fmi2SetContinuousStates: state %zu is not finite (%g)", k + 1, x[k]);
            return fmi2Error;
        }
    for (size_t k = 0; k < nx; k++) fmu->s.x[k] = x[k];
    fmu->outputs_stale = 1;
    return fmi2OK;
}

fmi2Status fmi2GetContinuousStates(fmi2Component c, fmi2Real x[], size_t nx) {
    FmuInstance *fmu = (FmuInstance *)c;
    if (!me_allowed(fmu, "fmi2GetContinuousStates", AFTER_INITIALIZATION)) return fmi2Error;
    if (!array_fits(fmu, "fmi2GetContinuousStates", x, nx, MODEL_N_STATES)) return fmi2Error;
    for (size_t k = 0; k < nx; k++) x[k] = fmu->s.x[k];
    return fmi2OK;
}

fmi2Status fmi2GetNominalsOfContinuousStates(fmi2Component c, fmi2Real x_nominal[], size_t nx) {
    FmuInstance *fmu = (FmuInstance *)c;
    if (!me_allowed(fmu, "fmi2GetNominalsOfContinuousStates", PHASE_INSTANTIATED | ME_PHASES | PHASE_TERMINATED | PHASE_ERROR))
        return fmi2Error;
    if (!array_fits(fmu, "fmi2GetNominalsOfContinuousStates", x_nominal, nx, MODEL_N_STATES)) return fmi2Error;
#if MODEL_STATE_NOMINALS
    model_state_nominals(fmu, x_nominal); /* nx is MODEL_N_STATES (array_fits) */
#else
    for (size_t k = 0; k < nx; k++) x_nominal[k] = 1.0;
#endif
    return fmi2OK;
}

fmi2Status fmi2GetDerivatives(fmi2Component c, fmi2Real derivatives[], size_t nx) {
    FmuInstance *fmu = (FmuInstance *)c;
    if (!me_allowed(fmu, "fmi2GetDerivatives", ME_PHASES | PHASE_TERMINATED)) return fmi2Error;
    if (!array_fits(fmu, "fmi2GetDerivatives", derivatives, nx, MODEL_N_STATES)) return fmi2Error;
    if (nx == 0) return fmi2OK;
    double dxdt[MODEL_N_STATES > 0 ? MODEL_N_STATES : 1];
    if (model_derivatives(fmu, dxdt) != 0) {
        LOG_ERROR(fmu, "fmi2GetDerivatives: the model cannot evaluate its derivatives at t = %.9g s for these states",
                  fmu->s.time);
        return fmi2Error;
    }
    for (size_t k = 0; k < nx; k++) {
        if (!isfinite(dxdt[k])) {
            LOG_ERROR(fmu, "fmi2GetDerivatives: derivative %zu is not finite at t = %.9g s", k + 1, fmu->s.time);
            return fmi2Error;
        }
        derivatives[k] = dxdt[k];
    }
    return fmi2OK;
}

fmi2Status fmi2GetEventIndicators(fmi2Component c, fmi2Real eventIndicators[], size_t ni) {
    FmuInstance *fmu = (FmuInstance *)c;
    if (!me_allowed(fmu, "fmi2GetEventIndicators", PHASE_INITIALIZATION | AFTER_INITIALIZATION)) return fmi2Error;
    return array_fits(fmu, "fmi2GetEventIndicators", eventIndicators, ni, 0) ? fmi2OK : fmi2Error;
}

fmi2Status fmi2EnterEventMode(fmi2Component c) {
    FmuInstance *fmu = (FmuInstance *)c;
    if (!me_allowed(fmu, "fmi2EnterEventMode", ME_PHASES)) return fmi2Error;
    fmu->s.continuous_time_mode = 0;
    return fmi2OK;
}

fmi2Status fmi2NewDiscreteStates(fmi2Component c, fmi2EventInfo *info) {
    FmuInstance *fmu = (FmuInstance *)c;
    if (!me_allowed_in(fmu, "fmi2NewDiscreteStates", ME_PHASES, EVENT_MODE)) return fmi2Error;
    if (!info) {
        LOG_ERROR(fmu, "fmi2NewDiscreteStates: NULL event info");
        return fmi2Error;
    }
    memset(info, 0, sizeof *info); /* no new discrete states, nothing changed */
#if MODEL_TIME_EVENTS
    const int changed = model_time_event(fmu);
    const double next = model_next_time_event(fmu);
    if (isfinite(next)) info->nextEventTimeDefined = fmi2True, info->nextEventTime = next;
    /* A time event that changes the right-hand side (a pulse's edge, a table's corner, the MPC's new
     * plan, the guard's new motion): the importer's solver is told to take the states afresh and
     * restart there, as the standard has it after a change of states (Reference-FMUs' fmusim, for
     * one, lets CVODE step on past an event otherwise, on a solution of the right-hand side before
     * it). One that changes nothing (the guard passing the cueing's motion on as before, another
     * model's event) lets the solver step on: no restart for it. */
    info->valuesOfContinuousStatesChanged = changed ? fmi2True : fmi2False;
#endif
    fmu->outputs_stale = 1; /* what the event changed (a pulse's edge, a new solve) shows in the outputs */
    return fmi2OK;
}

fmi2Status fmi2EnterContinuousTimeMode(fmi2Component c) {
    FmuInstance *fmu = (FmuInstance *)c;
    if (!me_allowed_in(fmu, "fmi2EnterContinuousTimeMode", ME_PHASES, EVENT_MODE)) return fmi2Error;
    fmu->s.continuous_time_mode = 1;
    return fmi2OK;
}

fmi2Status fmi2CompletedIntegratorStep(fmi2Component c, fmi2Boolean noSetFMUStatePriorToCurrentPoint,
                                       fmi2Boolean *enterEventMode, fmi2Boolean *terminateSimulation) {
    FmuInstance *fmu = (FmuInstance *)c;
    (void)noSetFMUStatePriorToCurrentPoint;
    if (!me_allowed_in(fmu, "fmi2CompletedIntegratorStep", ME_PHASES, CONTINUOUS_TIME_MODE)) return fmi2Error;
    if (!enterEventMode || !terminateSimulation) {
        LOG_ERROR(fmu, "fmi2CompletedIntegratorStep: NULL argument");
        return fmi2Error;
    }
    *enterEventMode = fmi2False;
    *terminateSimulation = fmi2False;
    fmu->warned = 0;
    const fmi2Status status = model_completed_integrator_step(fmu);
    if (status == fmi2Error) {
        *terminateSimulation = fmi2True;
        fmu->s.phase = PHASE_ERROR;
    }
    /* a warning logged (a leg past its stroke) is returned as fmi2DoStep returns it */
    return status == fmi2OK && fmu->warned && !fmu->s.v.fmi_warnings_as_ok ? fmi2Warning : status;
}

int fmu_me_value(FmuInstance *fmu, unsigned vr, double *value) {
    if (vr < (unsigned)FMU_STATE_VR(0) || vr >= (unsigned)FMU_DERIVATIVE_VR(MODEL_N_STATES)) return 0;
    if (vr < (unsigned)FMU_DERIVATIVE_VR(0)) {
        *value = fmu->s.x[vr - FMU_STATE_VR(0)];
        return 1;
    }
    double dxdt[MODEL_N_STATES > 0 ? MODEL_N_STATES : 1];
    *value = model_derivatives(fmu, dxdt) == 0 ? dxdt[vr - FMU_DERIVATIVE_VR(0)] : NAN;
    return 1;
}

#endif
