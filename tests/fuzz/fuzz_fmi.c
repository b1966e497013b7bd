/* Random FMI 2.0 call sequences against one model (tests/fuzz/fuzz_common.h says how they are
 * judged and run): every FMI 2.0 Co-Simulation function with hostile arguments: value references in
 * and out of range, NaN, infinities, huge and tiny numbers, NULL arrays, step sizes of every sign
 * and size, FMU states of its own, altered serialized bytes. A model with Model Exchange
 * (MODEL_MODEL_EXCHANGE) is instantiated as that in half the sequences, which then make Model
 * Exchange's calls (times, states of every size, event and continuous-time modes) in place of
 * steps; each interface's own calls on the other's instance are never allowed.
 *
 * Built with FUZZ_SYSTEM (fuzz_system), the same sequences run against a whole system as ONE FMI 2.0
 * FMU (`cosim export SCENE --fmu FILE`, with --me its Model Exchange): its layer
 * (cosim/engine/kernel/system_fmi2.c over system_fmu.c, system_me.c, system_read.c, kernel.c)
 * linked in, the nested FMUs loaded from its resources/ as any importer's instance loads them,
 * what it offers read from its modelDescription.xml (fuzz_common.h, fuzz_system.h): its value
 * references, causality, variability, interface, states, whether it can get and set its state.
 *
 *   fuzz_system --fmu-dir DIR [--seed S] [--sequences N] [--calls M] [--replay K] [--verbose]
 *
 * DIR: the exported FMU unpacked (scripts/fuzz.sh exports and unpacks the ones CI fuzzes). */
#include "fuzz_common.h"

#ifdef FUZZ_SYSTEM
#include "fmi2Functions.h"
#endif

static int model_exchange; /* this sequence's instance is Model Exchange */

/* The states in which a call of one interface is allowed on this sequence's instance: none for
 * the other interface's. */
static int for_cs(int states) { return model_exchange ? 0 : states; }
static int for_me(int states) { return model_exchange ? states : 0; }

/* One of Model Exchange's calls (on a Co-Simulation instance: each is refused), by the FMI 2.0
 * Model Exchange state machine; x: states to set, altered at random. *time: the instance's time as
 * the calls so far set it, NAN where the oracle cannot know it (a state set back, a reset). */
static void model_exchange_call(fmi2Component c, double *time) {
#if !defined(FUZZ_SYSTEM) && !MODEL_MODEL_EXCHANGE /* a Co-Simulation-only model's binary has none of them */
    (void)c, (void)time;
#else
    enum { N = STATES_CAPACITY };
    double x[N], dx[N];
    const size_t n = pick(10) ? (size_t)MODEL_N_STATES : (size_t)pick(N + 2); /* the wrong size now and then */
    fmi2Status status;
    switch (pick(10)) {
    case 0: {
        const double t = (isnan(*time) ? 0.0 : *time) + (pick(8) ? 1e-3 * uniform() : hostile_real());
        status = fmi2SetTime(c, t);
        judge("fmi2SetTime", status, for_me(S_EVENT | S_CONTINUOUS));
        if (status == fmi2OK) *time = t; /* a refused time is not the instance's */
        after(status, 0);
        break;
    }
    case 1: {
        for (int k = 0; k < N; k++) x[k] = 0.0;
        fmi2GetContinuousStates(c, x, MODEL_N_STATES);
        for (int k = 0; k < N; k++) x[k] = pick(4) ? x[k] * (1.0 + 1e-3 * (uniform() - 0.5)) : hostile_real();
        status = fmi2SetContinuousStates(c, n <= (size_t)N ? x : NULL, n);
        judge("fmi2SetContinuousStates", status, for_me(S_CONTINUOUS));
        after(status, 0);
        break;
    }
    case 2:
        status = fmi2GetContinuousStates(c, pick(20) ? x : NULL, n <= (size_t)N ? n : (size_t)N);
        judge("fmi2GetContinuousStates", status, for_me(S_EVENT | S_CONTINUOUS | S_TERMINATED | S_ERROR | S_INIT));
        break;
    case 3:
        status = fmi2GetDerivatives(c, pick(20) ? dx : NULL, n <= (size_t)N ? n : (size_t)N);
        judge("fmi2GetDerivatives", status, for_me(S_EVENT | S_CONTINUOUS | S_TERMINATED | S_ERROR));
        if (status == fmi2OK)
            for (size_t k = 0; k < n && k < (size_t)N; k++)
                if (!isfinite(dx[k])) violation("fmi2GetDerivatives", "a derivative returned with fmi2OK is not finite");
        break;
    case 4:
        status = pick(2) ? fmi2GetEventIndicators(c, dx, (size_t)pick(2))
                         : fmi2GetNominalsOfContinuousStates(c, dx, n <= (size_t)N ? n : (size_t)N);
        judge("fmi2GetEventIndicators/NominalsOfContinuousStates", status,
              for_me(S_INSTANTIATED | S_INIT | S_EVENT | S_CONTINUOUS | S_TERMINATED | S_ERROR));
        break;
    case 5:
        status = fmi2EnterEventMode(c);
        judge("fmi2EnterEventMode", status, for_me(S_EVENT | S_CONTINUOUS));
        after(status, S_EVENT);
        break;
    case 6: case 7: {
        fmi2EventInfo info;
        status = fmi2NewDiscreteStates(c, pick(20) ? &info : NULL);
        judge("fmi2NewDiscreteStates", status, for_me(S_EVENT));
        if (status == fmi2OK && info.nextEventTimeDefined && !isnan(*time) && !(info.nextEventTime > *time))
            violation("fmi2NewDiscreteStates", "the next time event is not after the time now");
        after(status, 0);
        break;
    }
    case 8:
        status = fmi2EnterContinuousTimeMode(c);
        judge("fmi2EnterContinuousTimeMode", status, for_me(S_EVENT));
        after(status, S_CONTINUOUS);
        break;
    default: {
        fmi2Boolean enter, terminate;
        status = fmi2CompletedIntegratorStep(c, fmi2True, pick(20) ? &enter : NULL, &terminate);
        judge("fmi2CompletedIntegratorStep", status, for_me(S_CONTINUOUS));
        after(status, 0);
    }
    }
#endif
}

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status, fmi2String category,
                   fmi2String message, ...) {
    (void)env; (void)name; (void)status; (void)category;
    if (verbose) fprintf(stderr, "    log: %s\n", message);
}

/* ---- one sequence ---- */
static void run_sequence(int max_calls) {
    const fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};
    model_exchange = MODEL_MODEL_EXCHANGE && (!OFFERS_CO_SIMULATION || pick(2));
    if (pick(20) == 0) { /* an interface it does not offer, or another GUID: no instance */
        const int other = !model_exchange ? MODEL_MODEL_EXCHANGE == 0 : !OFFERS_CO_SIMULATION;
        fmi2Component wrong = other && pick(2)
            ? fmi2Instantiate("fuzz", model_exchange ? fmi2CoSimulation : fmi2ModelExchange, MODEL_GUID, RESOURCES,
                              &callbacks, fmi2False, fmi2False)
            : fmi2Instantiate("fuzz", model_exchange ? fmi2ModelExchange : fmi2CoSimulation, "{not its guid}",
                              RESOURCES, &callbacks, fmi2False, fmi2False);
        calls++;
        if (wrong) violation("fmi2Instantiate", "an instance of an interface it does not offer, or of another GUID");
        fmi2FreeInstance(wrong);
    }
    fmi2Component c = fmi2Instantiate("fuzz", model_exchange ? fmi2ModelExchange : fmi2CoSimulation, MODEL_GUID,
                                      RESOURCES, &callbacks, fmi2False, pick(2) ? fmi2True : fmi2False);
    if (!c) { violation("fmi2Instantiate", "returned NULL for a valid GUID"); return; }
    possible = S_INSTANTIATED;
    fmi2FMUstate states[3] = {NULL, NULL, NULL};
    double state_time[3] = {NAN, NAN, NAN}, bytes_time = NAN; /* the times they were taken at */
    double state_start[3] = {NAN, NAN, NAN}, bytes_start = NAN; /* the start times they carry */
    fmi2Byte *bytes = NULL;
    size_t n_bytes = 0;
    double time = 0.0, start = 0.0; /* the instance's time (NAN: unknown to the oracle), its start */
    for (int k = 0; k < max_calls; k++) {
        fmi2ValueReference vrs[4];
        double reals[4];
        int ints[4];
        fmi2Status status;
        const int n = pick(4) + (pick(8) == 0 ? -1 : 0) + 1;
        const size_t nvr = n < 0 ? 0 : (size_t)n;
        for (size_t i = 0; i < nvr; i++) vrs[i] = random_vr();
        switch (pick(22)) {
        case 0: {
            const int tolerance_defined = pick(2);
            const double start_time = pick(4) ? 0.0 : hostile_real();
            status = fmi2SetupExperiment(c, tolerance_defined, pick(2) ? 1e-6 : hostile_real(), start_time,
                                         pick(3) == 0, pick(2) ? 10.0 : hostile_real());
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
            if (model_exchange || pick(8) == 0) { /* Model Exchange's calls (on Co-Simulation: refused) */
                model_exchange_call(c, &time);
                break;
            }
            const double h = pick(4) ? 1e-3 * (1 + pick(5)) : hostile_real();
            const double t = pick(8) ? time : hostile_real();
            status = fmi2DoStep(c, t, h, fmi2False);
            judge("fmi2DoStep", status, for_cs(S_STEP_COMPLETE));
            if (status <= fmi2Warning) time += h;
            after(status, 0);
            break;
        }
        case 7: case 8: {
            for (size_t i = 0; i < nvr; i++) reals[i] = (vrs[i] >= 1 && vrs[i] < VR_COUNT) ? value_for((int)vrs[i]) : hostile_real();
            status = fmi2SetReal(c, pick(20) ? vrs : NULL, nvr, pick(20) ? reals : NULL);
            judge("fmi2SetReal", status, settable_states(vrs, nvr, 'r'));
            after(status, 0);
            break;
        }
        case 9: {
            fmi2Real out[4];
            status = fmi2GetReal(c, vrs, nvr, pick(20) ? out : NULL);
            judge("fmi2GetReal", status, S_GET);
            if (status == fmi2OK)
                for (size_t i = 0; i < nvr; i++)
                    if (!isfinite(out[i])) violation("fmi2GetReal", "a Real returned with fmi2OK is not finite");
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
            fmi2String text[4] = {"", "/dev/zero", "no such file", NULL};
            fmi2String out[4];
            if (pick(2)) { status = fmi2SetString(c, vrs, nvr, text); judge("fmi2SetString", status, settable_states(vrs, nvr, 's')); }
            else { status = fmi2GetString(c, vrs, nvr, out); judge("fmi2GetString", status, S_GET); }
            after(status, 0);
            break;
        }
        case 13: {
            fmi2Integer order[4];
            for (size_t i = 0; i < nvr; i++) { order[i] = 1 + pick(3) - (pick(10) == 0); reals[i] = hostile_real(); }
            status = fmi2SetRealInputDerivatives(c, pick(20) ? vrs : NULL, nvr, pick(20) ? order : NULL, reals);
            judge("fmi2SetRealInputDerivatives", status, for_cs(settable_states(vrs, nvr, 'r')));
            after(status, 0);
            break;
        }
        case 14: {
            fmi2Integer order[4];
            fmi2Real out[4];
            for (size_t i = 0; i < nvr; i++) order[i] = pick(4);
            status = fmi2GetRealOutputDerivatives(c, vrs, nvr, order, out);
            judge("fmi2GetRealOutputDerivatives", status, for_cs(S_GET));
            after(status, 0);
            break;
        }
        case 15: {
            const int slot = pick(3);
            status = fmi2GetFMUstate(c, &states[slot]);
            judge("fmi2GetFMUstate", status, FMU_STATE_CALLS);
            if (status == fmi2OK) state_time[slot] = time, state_start[slot] = start;
            break;
        }
        case 16: {
            const int slot = pick(3);
            if (!states[slot]) break;
            status = fmi2SetFMUstate(c, states[slot]);
            judge("fmi2SetFMUstate", status, FMU_STATE_CALLS);
            /* its phase: unknown; its time and the start time of its experiment (fmi2SetupExperiment's,
               which a later fmi2ExitInitializationMode starts from) are the state's */
            if (status == fmi2OK) possible = S_ANY, time = state_time[slot], start = state_start[slot];
            break;
        }
        case 17: {
            const int slot = pick(3);
            status = fmi2FreeFMUstate(c, &states[slot]);
            judge("fmi2FreeFMUstate", status, S_ANY);
            break;
        }
        case 18: {
            const int slot = pick(3);
            if (!states[slot]) break;
            size_t size = 0;
            status = fmi2SerializedFMUstateSize(c, states[slot], &size);
            judge("fmi2SerializedFMUstateSize", status, S_ANY);
            if (status != fmi2OK || size == 0 || size > (1u << 24)) break;
            free(bytes);
            bytes = (fmi2Byte *)malloc(size);
            n_bytes = size;
            if (!bytes) break;
            status = fmi2SerializeFMUstate(c, states[slot], bytes, size);
            judge("fmi2SerializeFMUstate", status, S_ANY);
            bytes_time = state_time[slot], bytes_start = state_start[slot];
            break;
        }
        case 19: {
            if (!bytes) break;
            if (pick(2)) { /* altered payload: its time, if taken, is unknown */
                bytes[next_random() % n_bytes] ^= (fmi2Byte)(1 + pick(255));
                bytes_time = bytes_start = NAN;
            }
            const int slot = pick(3);
            status = fmi2DeSerializeFMUstate(c, bytes, pick(10) ? n_bytes : n_bytes - 1, &states[slot]);
            judge("fmi2DeSerializeFMUstate", status, S_ANY);
            state_time[slot] = status == fmi2OK ? bytes_time : NAN;
            state_start[slot] = status == fmi2OK ? bytes_start : NAN;
            break;
        }
        case 20: {
            fmi2Real r;
            fmi2Boolean b;
            status = pick(2) ? fmi2GetRealStatus(c, fmi2LastSuccessfulTime, pick(10) ? &r : NULL)
                             : fmi2GetBooleanStatus(c, fmi2Terminated, pick(10) ? &b : NULL);
            judge("fmi2GetReal/BooleanStatus", status, for_cs(S_STATUS));
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
            }
            else {
                fmi2String categories[2] = {"logAll", pick(2) ? "logStatusWarning" : "no such category"};
                status = fmi2SetDebugLogging(c, pick(2), (size_t)pick(3), pick(8) ? categories : NULL);
                judge("fmi2SetDebugLogging", status, S_ANY);
            }
        }
        }
    }
    for (int slot = 0; slot < 3; slot++) fmi2FreeFMUstate(c, &states[slot]);
    free(bytes);
    fmi2FreeInstance(c);
}

