/* Random FMI 2.0 call sequences against a whole system as ONE FMU (`cosim export SCENE --fmu FILE`,
 * its Co-Simulation, and with --me its Model Exchange): the system FMU's layer
 * (cosim/engine/kernel/system_fmi2.c, system_fmu.c, system_me.c, system_read.c, kernel.c) linked
 * in under the sanitizers, the nested FMUs the export carries loaded from its resources/ as any
 * importer's instance loads them. The calls, the hostile arguments and the oracle are those of
 * the models' harness (fuzz_common.h, fuzz_fmi.c); what a model's harness knows from its variable
 * table this one reads from the FMU's modelDescription.xml (value references, causality,
 * variability, the interface, the states, whether it can get and set its state).
 *
 *   fuzz_system --fmu-dir DIR [--seed S] [--sequences N] [--calls M] [--replay K] [--verbose]
 *
 * DIR: the exported FMU unpacked. scripts/fuzz.sh exports Meng's scene both ways and runs it on each. */
#define FUZZ_SYSTEM
#include "fuzz_common.h"
#include "fuzz_system.h"

#include "fmi2Functions.h"

static void logger(fmi2ComponentEnvironment env, fmi2String instance, fmi2Status status, fmi2String category,
                   fmi2String message, ...) {
    (void)env; (void)instance; (void)status; (void)category;
    if (verbose) fprintf(stderr, "    log: %s\n", message);
}

/* One of Model Exchange's calls, by its state machine (on a Co-Simulation instance: refused). */
static void model_exchange_call(fmi2Component c, int model_exchange, double *time) {
    const int me = model_exchange ? ~0 : 0;
    double x[MAX_STATES + 2], dx[MAX_STATES + 2];
    const size_t n = pick(10) ? (size_t)n_states : (size_t)pick(n_states + 2);
    fmi2Status status;
    switch (pick(9)) {
    case 0: {
        const double t = (isnan(*time) ? 0.0 : *time) + (pick(8) ? 1e-4 * uniform() : hostile_real());
        status = fmi2SetTime(c, t);
        judge("fmi2SetTime", status, me & (S_EVENT | S_CONTINUOUS));
        if (status == fmi2OK) *time = t;
        break;
    }
    case 1: {
        for (int k = 0; k < n_states; k++) x[k] = 0.0;
        fmi2GetContinuousStates(c, x, (size_t)n_states);
        for (int k = 0; k < n_states; k++) x[k] = pick(4) ? x[k] * (1.0 + 1e-3 * (uniform() - 0.5)) : hostile_real();
        status = fmi2SetContinuousStates(c, pick(20) ? x : NULL, n);
        judge("fmi2SetContinuousStates", status, me & S_CONTINUOUS);
        after(status, 0);
        break;
    }
    case 2:
        status = fmi2GetContinuousStates(c, pick(20) ? x : NULL, n);
        judge("fmi2GetContinuousStates", status, me & (S_EVENT | S_CONTINUOUS | S_TERMINATED | S_ERROR | S_INIT));
        break;
    case 3:
        status = fmi2GetDerivatives(c, pick(20) ? dx : NULL, n);
        judge("fmi2GetDerivatives", status, me & (S_EVENT | S_CONTINUOUS | S_TERMINATED | S_ERROR));
        for (size_t k = 0; status == fmi2OK && k < n; k++)
            if (!isfinite(dx[k])) { violation("fmi2GetDerivatives", "a derivative returned with fmi2OK is not finite"); break; }
        break;
    case 4:
        status = fmi2EnterEventMode(c);
        judge("fmi2EnterEventMode", status, me & (S_EVENT | S_CONTINUOUS));
        after(status, S_EVENT);
        break;
    case 5: case 6: {
        fmi2EventInfo info;
        status = fmi2NewDiscreteStates(c, pick(20) ? &info : NULL);
        judge("fmi2NewDiscreteStates", status, me & S_EVENT);
        if (status == fmi2OK && info.nextEventTimeDefined && !isnan(*time) && !(info.nextEventTime > *time))
            violation("fmi2NewDiscreteStates", "the next time event is not after the time now");
        after(status, 0);
        break;
    }
    case 7:
        status = fmi2EnterContinuousTimeMode(c);
        judge("fmi2EnterContinuousTimeMode", status, me & S_EVENT);
        after(status, S_CONTINUOUS);
        break;
    default: {
        fmi2Boolean enter, terminate;
        status = fmi2CompletedIntegratorStep(c, fmi2True, pick(20) ? &enter : NULL, &terminate);
        judge("fmi2CompletedIntegratorStep", status, me & S_CONTINUOUS);
        after(status, 0);
    }
    }
}

static void run_sequence(int max_calls) {
    if (!n_variables) {
        fprintf(stderr, "usage: fuzz_system --fmu-dir DIR (an exported system FMU unpacked) [--seed S] ...\n");
        exit(2);
    }
    const fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};
    const int model_exchange = offers_model_exchange;
    const int cs = model_exchange ? 0 : ~0, state_calls = has_fmu_state ? S_ANY : 0;
    if (pick(20) == 0) { /* the interface it does not offer, or another GUID: no instance */
        fmi2Component wrong = pick(2) ? fmi2Instantiate("fuzz", model_exchange ? fmi2CoSimulation : fmi2ModelExchange,
                                                        guid, resources, &callbacks, fmi2False, fmi2False)
                                      : fmi2Instantiate("fuzz", model_exchange ? fmi2ModelExchange : fmi2CoSimulation,
                                                        "{not its guid}", resources, &callbacks, fmi2False, fmi2False);
        if (wrong) violation("fmi2Instantiate", "an instance of an interface it does not offer, or of another GUID");
        fmi2FreeInstance(wrong);
    }
    fmi2Component c = fmi2Instantiate("fuzz", model_exchange ? fmi2ModelExchange : fmi2CoSimulation, guid, resources,
                                      &callbacks, fmi2False, pick(2) ? fmi2True : fmi2False);
    if (!c) { violation("fmi2Instantiate", "returned NULL for its own GUID and resources"); return; }
    possible = S_INSTANTIATED;
    fmi2FMUstate state = NULL;
    double time = 0.0, start = 0.0;
    for (int k = 0; k < max_calls; k++) {
        fmi2ValueReference vrs[4];
        double reals[4];
        int ints[4];
        fmi2Status status;
        const int n = pick(4) + (pick(8) == 0 ? -1 : 0) + 1;
        const size_t nvr = n < 0 ? 0 : (size_t)n;
        for (size_t i = 0; i < nvr; i++) vrs[i] = random_vr();
        switch (pick(18)) {
        case 0: {
            const double start_time = pick(4) ? 0.0 : hostile_real();
            status = fmi2SetupExperiment(c, pick(2), pick(2) ? 1e-6 : hostile_real(), start_time, pick(3) == 0,
                                         pick(2) ? 10.0 : hostile_real());
            judge("fmi2SetupExperiment", status, S_INSTANTIATED);
            if (status == fmi2OK) start = start_time;
            after(status, 0);
            break;
        }
        case 1: status = fmi2EnterInitializationMode(c); judge("fmi2EnterInitializationMode", status, S_INSTANTIATED);
            after(status, S_INIT); break;
        case 2: case 3: status = fmi2ExitInitializationMode(c); judge("fmi2ExitInitializationMode", status, S_INIT);
            after(status, model_exchange ? S_EVENT : S_STEP_COMPLETE);
            if (status == fmi2OK) time = start;
            break;
        case 4: case 5: case 6: {
            if (model_exchange || pick(8) == 0) { model_exchange_call(c, model_exchange, &time); break; }
            const double h = pick(4) ? 1e-3 * (1 + pick(5)) : hostile_real();
            const double t = pick(8) ? time : hostile_real();
            status = fmi2DoStep(c, t, h, fmi2False);
            judge("fmi2DoStep", status, cs & S_STEP_COMPLETE);
            if (status <= fmi2Warning) time += h;
            after(status, 0);
            break;
        }
        case 7: case 8: {
            for (size_t i = 0; i < nvr; i++) reals[i] = vrs[i] < (unsigned)n_variables ? value_for((int)vrs[i]) : hostile_real();
            status = fmi2SetReal(c, pick(20) ? vrs : NULL, nvr, pick(20) ? reals : NULL);
            if (verbose) for (size_t i = 0; i < nvr; i++) fprintf(stderr, "    vr %u = %g\n", vrs[i], reals[i]);
            judge("fmi2SetReal", status, settable_states(vrs, nvr, 'r'));
            after(status, 0);
            break;
        }
        case 9: {
            fmi2Real out[4];
            status = fmi2GetReal(c, vrs, nvr, pick(20) ? out : NULL);
            judge("fmi2GetReal", status, S_GET);
            for (size_t i = 0; status == fmi2OK && i < nvr; i++)
                if (!isfinite(out[i])) { violation("fmi2GetReal", "a Real returned with fmi2OK is not finite"); break; }
            after(status, 0);
            break;
        }
        case 10: {
            for (size_t i = 0; i < nvr; i++) ints[i] = pick(3) ? pick(4) : (int)(next_random() & 0x7fffffff) - 0x3fffffff;
            const int boolean = pick(2);
            status = boolean ? fmi2SetBoolean(c, vrs, nvr, ints) : fmi2SetInteger(c, vrs, nvr, ints);
            judge("fmi2SetInteger/Boolean", status, settable_states(vrs, nvr, boolean ? 'b' : 'i'));
            after(status, 0);
            break;
        }
        case 11: {
            fmi2Integer out[4];
            status = pick(2) ? fmi2GetInteger(c, vrs, nvr, out) : fmi2GetBoolean(c, vrs, nvr, out);
            judge("fmi2GetInteger/Boolean", status, S_GET);
            after(status, 0);
            break;
        }
        case 12: {
            fmi2String text[4] = {"", "/dev/zero", "no such file", NULL}, out[4];
            if (pick(2)) { status = fmi2SetString(c, vrs, nvr, text); judge("fmi2SetString", status, settable_states(vrs, nvr, 's')); }
            else { status = fmi2GetString(c, vrs, nvr, out); judge("fmi2GetString", status, S_GET); }
            after(status, 0);
            break;
        }
        case 13: {
            fmi2Integer order[4];
            for (size_t i = 0; i < nvr; i++) { order[i] = 1 + pick(3) - (pick(10) == 0); reals[i] = hostile_real(); }
            status = fmi2SetRealInputDerivatives(c, pick(20) ? vrs : NULL, nvr, pick(20) ? order : NULL, reals);
            judge("fmi2SetRealInputDerivatives", status, cs & settable_states(vrs, nvr, 'r'));
            after(status, 0);
            break;
        }
        case 14: {
            fmi2Integer order[4];
            fmi2Real out[4];
            for (size_t i = 0; i < nvr; i++) order[i] = pick(4);
            status = fmi2GetRealOutputDerivatives(c, vrs, nvr, order, out);
            judge("fmi2GetRealOutputDerivatives", status, cs & S_GET);
            after(status, 0);
            break;
        }
        case 15: { /* its state: refused where the description says it cannot */
            const int which = pick(3);
            if (which == 0) { status = fmi2GetFMUstate(c, &state); judge("fmi2GetFMUstate", status, state_calls); }
            else if (which == 1) { status = fmi2SetFMUstate(c, state); judge("fmi2SetFMUstate", status, state ? state_calls : 0);
                if (status == fmi2OK) possible = S_ANY, time = NAN; }
            else { status = fmi2FreeFMUstate(c, &state); judge("fmi2FreeFMUstate", status, S_ANY); }
            break;
        }
        case 16: {
            fmi2Real r;
            status = fmi2GetRealStatus(c, fmi2LastSuccessfulTime, pick(10) ? &r : NULL);
            judge("fmi2GetRealStatus", status, cs & S_STATUS);
            break;
        }
        default: {
            const int which = pick(4);
            if (which == 0) { status = fmi2Terminate(c); judge("fmi2Terminate", status, S_STEP_COMPLETE | S_STEP_FAILED | S_EVENT | S_CONTINUOUS);
                after(status, S_TERMINATED); }
            else if (which == 1) {
                status = fmi2Reset(c);
                judge("fmi2Reset", status, S_ANY);
                after(status, S_INSTANTIATED);
                if (status == fmi2OK) time = NAN, start = 0.0;
            } else {
                fmi2String categories[2] = {"logAll", pick(2) ? "logStatusWarning" : "no such category"};
                status = fmi2SetDebugLogging(c, pick(2), (size_t)pick(3), pick(8) ? categories : NULL);
                judge("fmi2SetDebugLogging", status, S_ANY);
            }
        }
        }
    }
    fmi2FreeFMUstate(c, &state);
    fmi2FreeInstance(c);
}
