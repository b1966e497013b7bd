/* A whole system as one Model Exchange FMU: the nested FMUs instantiated as Model Exchange, their
 * continuous states end to end as the system's, and the connections carried inside the right-hand
 * side, so that the importer's solver integrates the coupled system as one ODE with no coupling
 * delay (the answer cosim.engine.monolithic gives, with no Python in the loop).
 *
 * Whenever time, states, a value or a discrete state changed, the next evaluation (derivatives, an
 * output, an event update) first carries every connection's output to its input: instance after
 * instance in the coupling's Gauss-Seidel order (the order the co-simulation steps them in, sources
 * before their targets), sweep after sweep until no instance's inputs change. A system without
 * algebraic loops settles in one sweep and one more that finds nothing to set; a loop of
 * feed-through is iterated to its fixed point (at most SWEEPS sweeps, as the monolithic run).
 *
 * Events: the nested instances' time events (the trajectory's load pulses, the MPC cueing's
 * solves) are the system's: fmi2NewDiscreteStates updates each instance, carries the connections
 * and gives the earliest next event of any. The shipped models have no state events as Model
 * Exchange: no event indicators. */
#include <math.h>
#include <string.h>

#include "system.h"

enum { OK = 0, ERROR = 3, SWEEPS = 10 };

#define NESTED(s, inner) (&(s)->fmus[(inner)->fmu])

static int refused(System *s, const Inner *inner, const char *call) {
    say(s, fmi2Error, "logStatusError", "%s: %s failed at t = %.9g s", inner->name, call, s->me_time);
    system_failed(s);
    return ERROR;
}

int system_me_carry(System *s) {
    if (!s->stale) return OK;
    Kernel *k = &s->kernel;
    double *outputs = k->samples, *given = k->input_values, *wanted = k->input_rates;
    for (int sweep = 0; sweep < SWEEPS + s->n_instances; sweep++) {
        int evaluated = 0;
        for (int j = 0; j < s->n_instances; j++) {
            const int i = k->sequence[j];
            const KernelInstance *in = &s->kernel_instances[i];
            const Inner *inner = &s->inners[i];
            double *want = wanted + in->input_offset, *had = given + in->input_offset;
            for (int p = 0; p < in->n_inputs; p++)
                want[p] = outputs[s->kernel_instances[in->feed_source[p]].output_offset + in->feed_index[p]];
            if (sweep > 0 && memcmp(want, had, (size_t)in->n_inputs * sizeof(double)) == 0)
                continue; /* its inputs as they were: its outputs too */
            evaluated++;
            if (in->n_inputs > 0 && NESTED(s, inner)->set_real(inner->component, in->input_vrs, (size_t)in->n_inputs,
                                                                want) > fmi2Warning)
                return refused(s, inner, "fmi2SetReal (its connected inputs)");
            memcpy(had, want, (size_t)in->n_inputs * sizeof(double));
            if (in->n_outputs > 0 && NESTED(s, inner)->get_real(inner->component, in->output_vrs, (size_t)in->n_outputs,
                                                                 outputs + in->output_offset) > fmi2Warning)
                return refused(s, inner, "fmi2GetReal (its connected outputs)");
        }
        if (evaluated == 0) break;
    }
    s->stale = 0;
    return OK;
}

int system_me_set_time(System *s, double time) {
    for (int i = 0; i < s->n_instances; i++) {
        const Inner *inner = &s->inners[i];
        if (NESTED(s, inner)->set_time(inner->component, time) > fmi2Warning) return refused(s, inner, "fmi2SetTime");
    }
    s->me_time = time;
    s->stale = 1;
    return OK;
}

static int sizes_match(System *s, const char *call, const void *x, size_t n) {
    if (n != (size_t)s->n_states || (n > 0 && !x)) {
        say(s, fmi2Error, "logStatusError", "%s: %zu values%s, and the system has %d continuous states", call, n,
            n > 0 && !x ? " in a NULL array" : "", s->n_states);
        return 0;
    }
    return 1;
}

/* One of the nested instances' vector calls over each one's part of the system's vector. */
#define EACH_PART(s, call, name, vector, n)                                                        \
    do {                                                                                           \
        if (!sizes_match(s, name, vector, n)) return ERROR;                                        \
        for (int i_ = 0; i_ < (s)->n_instances; i_++) {                                            \
            const Inner *inner_ = &(s)->inners[i_];                                                \
            if (inner_->n_states > 0 &&                                                            \
                NESTED(s, inner_)->call(inner_->component, (vector) + inner_->first_state,         \
                                        (size_t)inner_->n_states) > fmi2Warning)                   \
                return refused(s, inner_, name);                                                   \
        }                                                                                          \
    } while (0)

int system_me_set_states(System *s, const double x[], size_t n) {
    EACH_PART(s, set_states, "fmi2SetContinuousStates", x, n);
    s->stale = 1;
    return OK;
}

int system_me_get_states(System *s, double x[], size_t n) {
    EACH_PART(s, get_states, "fmi2GetContinuousStates", x, n);
    return OK;
}

int system_me_get_nominals(System *s, double nominals[], size_t n) {
    EACH_PART(s, get_nominals, "fmi2GetNominalsOfContinuousStates", nominals, n);
    return OK;
}

int system_me_get_derivatives(System *s, double derivatives[], size_t n) {
    if (system_me_carry(s) != OK) return ERROR;
    EACH_PART(s, get_derivatives, "fmi2GetDerivatives", derivatives, n);
    return OK;
}

int system_me_enter_event_mode(System *s) {
    for (int i = 0; i < s->n_instances; i++) {
        const Inner *inner = &s->inners[i];
        if (NESTED(s, inner)->enter_event_mode(inner->component) > fmi2Warning)
            return refused(s, inner, "fmi2EnterEventMode");
    }
    s->continuous_time_mode = 0;
    return OK;
}

int system_me_new_discrete_states(System *s, int *terminate, int *states_changed, double *next) {
    *terminate = 0, *states_changed = 0, *next = INFINITY;
    if (system_me_carry(s) != OK) return ERROR;
    for (int i = 0; i < s->n_instances; i++) {
        const Inner *inner = &s->inners[i];
        fmi2EventInfo info = {fmi2True, fmi2False, fmi2False, fmi2False, fmi2False, 0.0};
        for (int round = 0; info.newDiscreteStatesNeeded; round++) {
            if (round == 100) {
                say(s, fmi2Error, "logStatusError", "%s: still new discrete states after %d rounds of "
                    "fmi2NewDiscreteStates at t = %.9g s", inner->name, round, s->me_time);
                system_failed(s);
                return ERROR;
            }
            if (NESTED(s, inner)->new_discrete_states(inner->component, &info) > fmi2Warning)
                return refused(s, inner, "fmi2NewDiscreteStates");
            *states_changed |= info.valuesOfContinuousStatesChanged == fmi2True;
            if (info.terminateSimulation == fmi2True) {
                say(s, fmi2OK, "logAll", "%s: asks to terminate at t = %.9g s", inner->name, s->me_time);
                *terminate = 1;
            }
        }
        if (info.nextEventTimeDefined == fmi2True && info.nextEventTime < *next) *next = info.nextEventTime;
    }
    s->stale = 1; /* what the event changed reaches the inputs it feeds */
    return system_me_carry(s);
}

int system_me_enter_continuous_time_mode(System *s) {
    for (int i = 0; i < s->n_instances; i++) {
        const Inner *inner = &s->inners[i];
        if (NESTED(s, inner)->enter_continuous_time_mode(inner->component) > fmi2Warning)
            return refused(s, inner, "fmi2EnterContinuousTimeMode");
    }
    s->continuous_time_mode = 1;
    return OK;
}

int system_me_completed_integrator_step(System *s, int *enter_event_mode, int *terminate) {
    *enter_event_mode = 0, *terminate = 0;
    if (system_me_carry(s) != OK) return ERROR;
    for (int i = 0; i < s->n_instances; i++) {
        const Inner *inner = &s->inners[i];
        fmi2Boolean event = fmi2False, stop = fmi2False;
        /* a warning (a leg past its stroke) is logged by the instance and the step goes on, as in the
         * Co-Simulation system FMU's steps: a tool that stops at the first fmi2Warning runs on */
        if (NESTED(s, inner)->completed_integrator_step(inner->component, fmi2True, &event, &stop) > fmi2Warning)
            return refused(s, inner, "fmi2CompletedIntegratorStep");
        *enter_event_mode |= event == fmi2True;
        *terminate |= stop == fmi2True;
    }
    return OK;
}
