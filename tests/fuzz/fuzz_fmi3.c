/* Random FMI 3.0 call sequences against one model through fmu/common/fmi3_layer.c (tests/fuzz/
 * fuzz_common.h says how they are judged and run): instantiation with hostile options, the
 * initialization mode's experiment, get and set of the four types the tables have (scalars, and
 * value counts that do not match), of the types they have none of, fmi3DoStep's out-pointers, output
 * derivatives, FMU state with altered serialized bytes, and the event, clock and Model Exchange
 * functions a Co-Simulation FMU without event mode refuses. The oracle is FMI 3.0's Co-Simulation
 * state machine without event mode: instantiated, initialization mode, step mode, terminated. A
 * model with Model Exchange (MODEL_MODEL_EXCHANGE) is instantiated as that in half the sequences,
 * which then make Model Exchange's calls (times, states of every size, Event and Continuous-Time
 * Mode, discrete-state updates) in place of steps, by FMI 3.0's Model Exchange state machine; each
 * interface's own calls on the other's instance are never allowed.
 *
 * Built with FUZZ_SYSTEM (fuzz3_system), the same sequences run against a whole system as ONE FMI
 * 3.0 FMU (`cosim export SCENE --fmu FILE --fmi 3`, with --me its Model Exchange): its layer
 * (cosim/engine/kernel/system_fmi3.c over system_fmu.c) linked in, the nested FMUs loaded from its
 * resources/, what it offers read from its modelDescription.xml (fuzz_common.h, fuzz_system.h):
 *
 *   fuzz3_system --fmu-dir DIR [--seed S] [--sequences N] [--calls M] [--replay K] [--verbose] */
#include "fuzz_common.h"

#include "fmi3Functions.h"

static void log_message(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category, fmi3String message) {
    (void)env, (void)status, (void)category;
    if (verbose) fprintf(stderr, "    log: %s\n", message);
}

#define S_STEP S_STEP_COMPLETE

static int model_exchange; /* this sequence's instance is Model Exchange */
static int for_cs(int states) { return model_exchange ? 0 : states; }
static int for_me(int states) { return model_exchange ? states : 0; }

/* One of Model Exchange's calls (on a Co-Simulation instance: each is refused), by FMI 3.0's Model
 * Exchange state machine; *time: the instance's time as the calls so far set it (NAN: unknown). */
static void model_exchange_call(fmi3Instance c, double *time) {
    enum { N = STATES_CAPACITY };
    double x[N], dx[N];
    const size_t n = pick(10) ? (size_t)MODEL_N_STATES : (size_t)pick(N + 2); /* the wrong size now and then */
    const size_t fits = n <= (size_t)N ? n : (size_t)N;
    fmi3Status status;
    switch (pick(12)) {
    case 0: {
        const double t = (isnan(*time) ? 0.0 : *time) + (pick(8) ? 1e-3 * uniform() : hostile_real());
        status = fmi3SetTime(c, t);
        judge("fmi3SetTime", status, for_me(S_EVENT | S_CONTINUOUS));
        if (status == fmi3OK) *time = t;
        after(status, 0);
        break;
    }
    case 1:
        for (int k = 0; k < N; k++) x[k] = 0.0;
        fmi3GetContinuousStates(c, x, MODEL_N_STATES);
        for (int k = 0; k < N; k++) x[k] = pick(4) ? x[k] * (1.0 + 1e-3 * (uniform() - 0.5)) : hostile_real();
        status = fmi3SetContinuousStates(c, n <= (size_t)N ? x : NULL, n);
        judge("fmi3SetContinuousStates", status, for_me(S_CONTINUOUS));
        after(status, 0);
        break;
    case 2:
        status = fmi3GetContinuousStates(c, pick(20) ? x : NULL, fits);
        judge("fmi3GetContinuousStates", status, for_me(S_EVENT | S_CONTINUOUS | S_TERMINATED | S_ERROR | S_INIT));
        break;
    case 3:
        status = fmi3GetContinuousStateDerivatives(c, pick(20) ? dx : NULL, fits);
        judge("fmi3GetContinuousStateDerivatives", status, for_me(S_EVENT | S_CONTINUOUS | S_TERMINATED | S_ERROR));
        if (status == fmi3OK)
            for (size_t k = 0; k < fits; k++)
                if (!isfinite(dx[k]))
                    violation("fmi3GetContinuousStateDerivatives", "a derivative returned with fmi3OK is not finite");
        break;
    case 4:
        status = pick(2) ? fmi3GetEventIndicators(c, dx, (size_t)pick(2))
                         : fmi3GetNominalsOfContinuousStates(c, dx, fits);
        judge("fmi3GetEventIndicators/NominalsOfContinuousStates", status,
              for_me(S_INSTANTIATED | S_INIT | S_EVENT | S_CONTINUOUS | S_TERMINATED | S_ERROR));
        break;
    case 5: {
        size_t count = 12345;
        const int states = pick(2);
        status = states ? fmi3GetNumberOfContinuousStates(c, pick(20) ? &count : NULL)
                        : fmi3GetNumberOfEventIndicators(c, pick(20) ? &count : NULL);
        /* in any state (the Reference FMUs' mask), of either interface: a Co-Simulation instance may
         * answer (none) or refuse */
        judge("fmi3GetNumberOfContinuousStates/EventIndicators", status, S_ANY);
        if (status == fmi3OK && count != (states && model_exchange ? (size_t)MODEL_N_STATES : 0))
            violation("fmi3GetNumberOfContinuousStates/EventIndicators", "a count that is not the model's");
        break;
    }
    case 6:
        status = fmi3EnterEventMode(c);
        judge("fmi3EnterEventMode", status, for_me(S_EVENT | S_CONTINUOUS));
        after(status, S_EVENT);
        break;
    case 7: case 8: {
        fmi3Boolean update, terminate, nominals, values, defined;
        fmi3Float64 next = NAN;
        status = fmi3UpdateDiscreteStates(c, &update, &terminate, &nominals, &values, &defined, &next);
        judge("fmi3UpdateDiscreteStates", status, for_me(S_EVENT));
        if (status == fmi3OK && defined && !isnan(*time) && !(next > *time)) {
            char what[160];
            snprintf(what, sizeof what, "the next time event %.17g is not after the time now %.17g", next, *time);
            violation("fmi3UpdateDiscreteStates", what);
        }
        after(status, 0);
        break;
    }
    case 9:
        status = fmi3EnterContinuousTimeMode(c);
        judge("fmi3EnterContinuousTimeMode", status, for_me(S_EVENT));
        after(status, S_CONTINUOUS);
        break;
    default: {
        fmi3Boolean enter, terminate;
        status = fmi3CompletedIntegratorStep(c, fmi3True, pick(20) ? &enter : NULL, &terminate);
        judge("fmi3CompletedIntegratorStep", status, for_me(S_CONTINUOUS));
        after(status, 0);
    }
    }
}

static void run_sequence(int max_calls) {
    model_exchange = MODEL_MODEL_EXCHANGE && (!OFFERS_CO_SIMULATION || pick(2));
    fmi3Instance c = model_exchange
        ? fmi3InstantiateModelExchange("fuzz", MODEL_GUID, RESOURCES, fmi3False, pick(2) != 0, NULL, log_message)
        : fmi3InstantiateCoSimulation("fuzz", MODEL_GUID, RESOURCES, fmi3False, pick(2) != 0, fmi3False, pick(2) != 0, NULL,
                                      0, NULL, log_message, NULL);
    if (!c) { violation("fmi3Instantiate", "returned NULL for a valid token"); return; }
    if (pick(10) == 0) { /* what a Co-Simulation FMU without event mode must refuse */
        calls++;
        if (fmi3InstantiateCoSimulation("fuzz", MODEL_GUID, RESOURCES, fmi3False, fmi3False, fmi3True, fmi3False, NULL, 0,
                                        NULL, log_message, NULL))
            violation("fmi3InstantiateCoSimulation", "accepted eventModeUsed without event mode");
        if (fmi3InstantiateCoSimulation("fuzz", "{not the token}", RESOURCES, fmi3False, fmi3False, fmi3False, fmi3False,
                                        NULL, 0, NULL, log_message, NULL))
            violation("fmi3InstantiateCoSimulation", "accepted a wrong instantiation token");
        fmi3Instance me = fmi3InstantiateModelExchange("fuzz", MODEL_GUID, RESOURCES, fmi3False, fmi3False, NULL, log_message);
        if (me && !MODEL_MODEL_EXCHANGE)
            violation("fmi3InstantiateModelExchange", "a Co-Simulation FMU gave a Model Exchange instance");
        if (!me && MODEL_MODEL_EXCHANGE)
            violation("fmi3InstantiateModelExchange", "a Model Exchange FMU refused a valid token");
        fmi3FreeInstance(me);
    }
    possible = S_INSTANTIATED;
    fmi3FMUState states[3] = {NULL, NULL, NULL};
    fmi3Byte *bytes = NULL;
    size_t n_bytes = 0;
    double time = 0.0, start = 0.0; /* the instance's time (NAN: unknown to the oracle), its start */
    for (int k = 0; k < max_calls; k++) {
        fmi3ValueReference vrs[4];
        double reals[4];
        fmi3Int32 ints[4];
        fmi3Boolean booleans[4];
        fmi3Status status;
        const int n = pick(4) + (pick(8) == 0 ? -1 : 0) + 1;
        const size_t nvr = n < 0 ? 0 : (size_t)n;
        const size_t nvalues = pick(12) ? nvr : nvr + 1; /* sometimes a count that does not match */
        for (size_t i = 0; i < nvr; i++) vrs[i] = random_vr();
        switch (pick(20)) {
        case 0: case 1:
        {
            const double tolerance = pick(2) ? 1e-6 : hostile_real(), start_time = pick(4) ? 0.0 : hostile_real();
            status = fmi3EnterInitializationMode(c, pick(2), tolerance, start_time, pick(3) == 0,
                                                 pick(2) ? 10.0 : hostile_real());
            judge("fmi3EnterInitializationMode", status, S_INSTANTIATED);
            if (status == fmi3OK) start = start_time;
            after(status, S_INIT);
            break;
        }
        case 2: case 3:
            status = fmi3ExitInitializationMode(c);
            judge("fmi3ExitInitializationMode", status, S_INIT);
            after(status, model_exchange ? S_EVENT : S_STEP);
            if (status == fmi3OK) time = start; /* a refused call leaves the instance's time as it was */
            break;
        case 4: case 5: case 6: {
            if (model_exchange || pick(8) == 0) { /* Model Exchange's calls (on Co-Simulation: refused) */
                model_exchange_call(c, &time);
                break;
            }
            const double h = pick(4) ? 1e-3 * (1 + pick(5)) : hostile_real();
            const double t = pick(8) ? time : hostile_real();
            fmi3Boolean event = fmi3True, terminate = fmi3True, early = fmi3True;
            fmi3Float64 last = NAN;
            const int null_pointer = pick(20) == 0;
            status = fmi3DoStep(c, t, h, fmi3False, &event, &terminate, null_pointer ? NULL : &early, &last);
            judge("fmi3DoStep", status, for_cs(S_STEP));
            if (status <= fmi3Warning) {
                if (null_pointer) violation("fmi3DoStep", "accepted a NULL out-pointer");
                if (event || terminate || early || !isfinite(last))
                    violation("fmi3DoStep", "a completed step reported an event, termination, early return or no time");
                time += h;
            }
            after(status, 0);
            break;
        }
        case 7: case 8:
            for (size_t i = 0; i < nvr; i++) reals[i] = (vrs[i] >= 1 && vrs[i] < VR_COUNT) ? value_for((int)vrs[i]) : hostile_real();
            status = fmi3SetFloat64(c, pick(20) ? vrs : NULL, nvr, pick(20) ? reals : NULL, nvalues);
            judge("fmi3SetFloat64", status, nvalues == nvr ? settable_states(vrs, nvr, 'r') : 0);
            after(status, 0);
            break;
        case 9: {
            fmi3Float64 out[5];
            status = fmi3GetFloat64(c, vrs, nvr, pick(20) ? out : NULL, nvalues);
            judge("fmi3GetFloat64", status, nvalues == nvr ? S_GET : 0);
            if (status == fmi3OK)
                for (size_t i = 0; i < nvr; i++)
                    if (!isfinite(out[i])) violation("fmi3GetFloat64", "a Float64 returned with fmi3OK is not finite");
            after(status, 0);
            break;
        }
        case 10: {
            for (size_t i = 0; i < nvr; i++) {
                ints[i] = pick(3) ? pick(4) : (fmi3Int32)(next_random() & 0x7fffffff) - 0x3fffffff;
                booleans[i] = pick(2) != 0;
            }
            const int boolean = pick(2);
            status = boolean ? fmi3SetBoolean(c, vrs, nvr, booleans, nvalues) : fmi3SetInt32(c, vrs, nvr, ints, nvalues);
            judge("fmi3SetInt32/Boolean", status, nvalues == nvr ? settable_states(vrs, nvr, boolean ? 'b' : 'i') : 0);
            after(status, 0);
            break;
        }
        case 11:
            status = pick(2) ? fmi3GetInt32(c, vrs, nvr, ints, nvalues) : fmi3GetBoolean(c, vrs, nvr, booleans, nvalues);
            judge("fmi3GetInt32/Boolean", status, nvalues == nvr ? S_GET : 0);
            after(status, 0);
            break;
        case 12: {
            fmi3String text[5] = {"", "/dev/zero", "no such file", NULL, ""};
            fmi3String out[5];
            if (pick(2)) {
                status = fmi3SetString(c, vrs, nvr, text, nvalues);
                judge("fmi3SetString", status, nvalues == nvr ? settable_states(vrs, nvr, 's') : 0);
            } else {
                status = fmi3GetString(c, vrs, nvr, out, nvalues);
                judge("fmi3GetString", status, nvalues == nvr ? S_GET : 0);
            }
            after(status, 0);
            break;
        }
        case 13: { /* the types the tables have none of: only an empty call may succeed */
            fmi3Float32 f32[5] = {0};
            fmi3UInt64 u64[5] = {0};
            status = pick(2) ? fmi3GetFloat32(c, vrs, nvr, f32, nvalues) : fmi3SetUInt64(c, vrs, nvr, u64, nvalues);
            judge("fmi3Get/Set of a type without variables", status, nvr == 0 ? S_ANY : 0);
            after(status, 0);
            break;
        }
        case 14: {
            fmi3Int32 order[5];
            fmi3Float64 out[5];
            for (size_t i = 0; i < nvr; i++) order[i] = pick(4);
            status = fmi3GetOutputDerivatives(c, vrs, nvr, order, out, nvalues);
            judge("fmi3GetOutputDerivatives", status, nvalues == nvr ? for_cs(S_GET) : 0);
            after(status, 0);
            break;
        }
        case 15: {
            const int slot = pick(3);
            switch (pick(3)) {
            case 0: status = fmi3GetFMUState(c, &states[slot]); judge("fmi3GetFMUState", status, FMU_STATE_CALLS); break;
            case 1:
                if (!states[slot]) break;
                status = fmi3SetFMUState(c, states[slot]);
                judge("fmi3SetFMUState", status, FMU_STATE_CALLS);
                if (status == fmi3OK) possible = S_ANY, time = NAN; /* the state's own phase and time: unknown */
                break;
            default: status = fmi3FreeFMUState(c, &states[slot]); judge("fmi3FreeFMUState", status, S_ANY);
            }
            break;
        }
        case 16: {
            const int slot = pick(3);
            if (!states[slot]) break;
            size_t size = 0;
            status = fmi3SerializedFMUStateSize(c, states[slot], &size);
            judge("fmi3SerializedFMUStateSize", status, S_ANY);
            if (status != fmi3OK || size == 0 || size > (1u << 24)) break;
            free(bytes);
            bytes = (fmi3Byte *)malloc(size);
            n_bytes = size;
            if (!bytes) break;
            status = fmi3SerializeFMUState(c, states[slot], bytes, size);
            judge("fmi3SerializeFMUState", status, S_ANY);
            break;
        }
        case 17: {
            if (!bytes) break;
            if (pick(2)) bytes[next_random() % n_bytes] ^= (fmi3Byte)(1 + pick(255)); /* altered payload */
            status = fmi3DeserializeFMUState(c, bytes, pick(10) ? n_bytes : n_bytes - 1, &states[pick(3)]);
            judge("fmi3DeserializeFMUState", status, S_ANY);
            break;
        }
        case 18: { /* Co-Simulation's event mode, clocks, configuration: never */
            switch (pick(3)) {
            case 0: status = fmi3EnterStepMode(c); break;
            case 1: status = fmi3EnterConfigurationMode(c); break;
            default: status = model_exchange ? fmi3EnterStepMode(c) : fmi3EnterEventMode(c);
            }
            judge("an event, clock or configuration function", status, 0);
            break;
        }
        default: {
            const int which = pick(4);
            if (which == 0) {
                status = fmi3Terminate(c);
                judge("fmi3Terminate", status, S_STEP | S_STEP_FAILED | S_EVENT | S_CONTINUOUS);
                after(status, S_TERMINATED);
            } else if (which == 1) {
                status = fmi3Reset(c);
                judge("fmi3Reset", status, S_ANY);
                after(status, S_INSTANTIATED);
            } else {
                fmi3String categories[2] = {"logAll", pick(2) ? "logStatusWarning" : "no such category"};
                status = fmi3SetDebugLogging(c, pick(2) != 0, (size_t)pick(3), pick(8) ? categories : NULL);
                judge("fmi3SetDebugLogging", status, S_ANY);
            }
        }
        }
    }
    for (int slot = 0; slot < 3; slot++) fmi3FreeFMUState(c, &states[slot]);
    free(bytes);
    fmi3FreeInstance(c);
}
