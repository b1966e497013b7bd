/* Random FMI 3.0 call sequences against one model through fmu/common/fmi3_layer.c (tests/fuzz/
 * fuzz_common.h says how they are judged and run): instantiation with hostile options, the
 * initialization mode's experiment, get and set of the four types the tables have (scalars, and
 * value counts that do not match), of the types they have none of, fmi3DoStep's out-pointers, output
 * derivatives, FMU state with altered serialized bytes, and the event, clock and Model Exchange
 * functions a Co-Simulation FMU without event mode refuses. The oracle is FMI 3.0's Co-Simulation
 * state machine without event mode: instantiated, initialization mode, step mode, terminated. */
#include "fuzz_common.h"

#include "fmi3Functions.h"

static void log_message(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category, fmi3String message) {
    (void)env, (void)status, (void)category;
    if (verbose) fprintf(stderr, "    log: %s\n", message);
}

#define S_STEP S_STEP_COMPLETE

static void run_sequence(int max_calls) {
    fmi3Instance c = fmi3InstantiateCoSimulation("fuzz", MODEL_GUID, "", fmi3False, pick(2) != 0, fmi3False,
                                                 pick(2) != 0, NULL, 0, NULL, log_message, NULL);
    if (!c) { violation("fmi3InstantiateCoSimulation", "returned NULL for a valid token"); return; }
    if (pick(10) == 0) { /* what a Co-Simulation FMU without event mode must refuse */
        calls++;
        if (fmi3InstantiateCoSimulation("fuzz", MODEL_GUID, "", fmi3False, fmi3False, fmi3True, fmi3False, NULL, 0,
                                        NULL, log_message, NULL))
            violation("fmi3InstantiateCoSimulation", "accepted eventModeUsed without event mode");
        if (fmi3InstantiateCoSimulation("fuzz", "{not the token}", "", fmi3False, fmi3False, fmi3False, fmi3False,
                                        NULL, 0, NULL, log_message, NULL))
            violation("fmi3InstantiateCoSimulation", "accepted a wrong instantiation token");
        fmi3Instance me = fmi3InstantiateModelExchange("fuzz", MODEL_GUID, "", fmi3False, fmi3False, NULL, log_message);
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
    double time = 0.0;
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
            status = fmi3EnterInitializationMode(c, pick(2), pick(2) ? 1e-6 : hostile_real(),
                                                 pick(4) ? 0.0 : hostile_real(), pick(3) == 0,
                                                 pick(2) ? 10.0 : hostile_real());
            judge("fmi3EnterInitializationMode", status, S_INSTANTIATED);
            after(status, S_INIT);
            break;
        case 2: case 3:
            status = fmi3ExitInitializationMode(c);
            judge("fmi3ExitInitializationMode", status, S_INIT);
            after(status, S_STEP);
            time = 0.0;
            break;
        case 4: case 5: case 6: {
            const double h = pick(4) ? 1e-3 * (1 + pick(5)) : hostile_real();
            const double t = pick(8) ? time : hostile_real();
            fmi3Boolean event = fmi3True, terminate = fmi3True, early = fmi3True;
            fmi3Float64 last = NAN;
            const int null_pointer = pick(20) == 0;
            status = fmi3DoStep(c, t, h, fmi3False, &event, &terminate, null_pointer ? NULL : &early, &last);
            judge("fmi3DoStep", status, S_STEP);
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
            judge("fmi3SetFloat64", status, nvalues == nvr ? S_SET : 0);
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
        case 10:
            for (size_t i = 0; i < nvr; i++) {
                ints[i] = pick(3) ? pick(4) : (fmi3Int32)(next_random() & 0x7fffffff) - 0x3fffffff;
                booleans[i] = pick(2) != 0;
            }
            status = pick(2) ? fmi3SetInt32(c, vrs, nvr, ints, nvalues) : fmi3SetBoolean(c, vrs, nvr, booleans, nvalues);
            judge("fmi3SetInt32/Boolean", status, nvalues == nvr ? S_SET : 0);
            after(status, 0);
            break;
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
                judge("fmi3SetString", status, nvalues == nvr ? S_SET : 0);
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
            judge("fmi3GetOutputDerivatives", status, nvalues == nvr ? S_GET : 0);
            after(status, 0);
            break;
        }
        case 15: {
            const int slot = pick(3);
            switch (pick(3)) {
            case 0: status = fmi3GetFMUState(c, &states[slot]); judge("fmi3GetFMUState", status, S_ANY); break;
            case 1:
                if (!states[slot]) break;
                status = fmi3SetFMUState(c, states[slot]);
                judge("fmi3SetFMUState", status, S_ANY);
                if (status == fmi3OK) possible = S_ANY; /* the state's own phase: unknown to the oracle */
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
        case 18: { /* event mode, clocks, Model Exchange: never */
            fmi3Float64 x[2];
            size_t count;
            switch (pick(5)) {
            case 0: status = fmi3EnterEventMode(c); break;
            case 1: status = fmi3EnterStepMode(c); break;
            case 2: status = fmi3GetContinuousStates(c, x, 2); break;
            case 3: status = fmi3GetNumberOfEventIndicators(c, &count); break;
            default: status = fmi3EnterConfigurationMode(c);
            }
            judge("an event, clock or Model Exchange function", status, 0);
            break;
        }
        default: {
            const int which = pick(4);
            if (which == 0) {
                status = fmi3Terminate(c);
                judge("fmi3Terminate", status, S_STEP | S_STEP_FAILED);
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
