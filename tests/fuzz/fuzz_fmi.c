/* Random FMI 2.0 call sequences against one model, linked in with the shared layer (build with
 * -DCOSIM_FUZZ=ON; with -DCOSIM_SANITIZE=ON under AddressSanitizer and UndefinedBehaviorSanitizer).
 *
 *   fuzz_<model> [--seed S] [--sequences N] [--calls M] [--replay K] [--verbose]
 *
 * Each sequence instantiates the model and makes up to M calls chosen at random, with hostile
 * arguments: value references in and out of range, NaN, infinities, huge and tiny numbers, NULL
 * arrays, step sizes of every sign and size, FMU states of its own, altered serialized bytes.
 * Every result is judged by an oracle built from FMI 2.0's Co-Simulation state machine (the set of
 * states the instance may be in after each call): a call the standard does not allow that returns
 * fmi2OK, a Real output read as NaN or infinite with fmi2OK, or a sequence that takes longer than
 * 10 s (an alarm) is a violation, reported with the seed and the sequence index, which replay it
 * alone (--replay K, with --verbose printing every call). Crashes and memory errors are the
 * sanitizers' to report. Exit status: 0 without violations, 1 otherwise.
 */
#define _POSIX_C_SOURCE 200809L /* alarm, signal */
#include "fmu_common.h"
#include "model_guid.h"

#include <float.h>
#include <math.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

/* ---- random numbers: xorshift64*, reproducible from the seed ---- */
static unsigned long long rng_state;
static unsigned long long next_random(void) {
    rng_state ^= rng_state >> 12; rng_state ^= rng_state << 25; rng_state ^= rng_state >> 27;
    return rng_state * 2685821657736338717ULL;
}
static int pick(int n) { return (int)(next_random() % (unsigned long long)n); }
static double uniform(void) { return (double)(next_random() >> 11) / 9007199254740992.0; }

static double hostile_real(void) {
    static const double special[] = {0.0, -0.0, 1.0, -1.0, 1e-300, -1e-300, 1e308, -1e308, DBL_MAX, -DBL_MAX,
                                     DBL_MIN, 1e-9, 1e9, 0.5, 2.0, 1e-3};
    switch (pick(4)) {
    case 0: return special[pick((int)(sizeof special / sizeof special[0]))];
    case 1: return pick(3) == 0 ? NAN : (pick(2) ? INFINITY : -INFINITY);
    case 2: return (uniform() - 0.5) * pow(10.0, pick(12) - 4);
    default: return uniform();
    }
}

/* a value for variable vr: mostly within its bounds (to get deep into the model), sometimes hostile */
static double value_for(int vr) {
    const FmuVariable *var = &fmu_variables[vr];
    if (pick(3) == 0) return hostile_real();
    const double lo = isfinite(var->min) ? var->min : -10.0, hi = isfinite(var->max) ? var->max : 10.0;
    return lo + (hi - lo) * uniform();
}

static unsigned random_vr(void) {
    return pick(10) == 0 ? (unsigned)(pick(3) == 0 ? 0 : VR_COUNT + pick(100)) : (unsigned)(1 + pick(VR_COUNT - 1));
}

/* ---- the oracle: FMI 2.0 Co-Simulation states (a set: after an error the instance may be anywhere) ---- */
enum { S_INSTANTIATED = 1, S_INIT = 2, S_STEP_COMPLETE = 4, S_STEP_FAILED = 8, S_TERMINATED = 16, S_ERROR = 32 };
#define S_ANY (S_INSTANTIATED | S_INIT | S_STEP_COMPLETE | S_STEP_FAILED | S_TERMINATED | S_ERROR)
#define S_GET (S_INIT | S_STEP_COMPLETE | S_STEP_FAILED | S_TERMINATED | S_ERROR)
#define S_SET (S_INSTANTIATED | S_INIT | S_STEP_COMPLETE)
#define S_STATUS (S_STEP_COMPLETE | S_STEP_FAILED | S_TERMINATED)

static int possible;              /* the states the instance may be in */
static long violations, calls;
static unsigned long long seed;
static long sequence_index;
static int verbose;

static void violation(const char *call, const char *what) {
    violations++;
    fprintf(stderr, "VIOLATION seed %llu sequence %ld call %ld: %s: %s\n", seed, sequence_index, calls, call, what);
}

/* judge a call: allowed_in = the states in which the standard allows it */
static void judge(const char *call, fmi2Status status, int allowed_in) {
    calls++;
    if (verbose) fprintf(stderr, "  %s -> %d (states %#x)\n", call, (int)status, possible);
    if (status == fmi2OK && !(possible & allowed_in)) violation(call, "accepted in a state where FMI 2.0 forbids it");
}

/* after a call that failed, the instance may have moved to the error state */
static void after(fmi2Status status, int success_state) {
    if (status <= fmi2Warning) { if (success_state) possible = success_state; }
    else possible |= S_ERROR;
}

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status, fmi2String category,
                   fmi2String message, ...) {
    (void)env; (void)name; (void)status; (void)category;
    if (verbose) fprintf(stderr, "    log: %s\n", message);
}

static void on_alarm(int signum) {
    (void)signum;
    char text[160];
    int n = snprintf(text, sizeof text, "VIOLATION seed %llu sequence %ld call %ld: hang (longer than 10 s)\n", seed,
                     sequence_index, calls);
    if (n > 0) { ssize_t ignored = write(2, text, (size_t)n); (void)ignored; }
    _exit(1);
}

/* ---- one sequence ---- */
static void run_sequence(int max_calls) {
    const fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};
    fmi2Component c = fmi2Instantiate("fuzz", fmi2CoSimulation, MODEL_GUID, "", &callbacks, fmi2False,
                                      pick(2) ? fmi2True : fmi2False);
    if (!c) { violation("fmi2Instantiate", "returned NULL for a valid GUID"); return; }
    possible = S_INSTANTIATED;
    fmi2FMUstate states[3] = {NULL, NULL, NULL};
    fmi2Byte *bytes = NULL;
    size_t n_bytes = 0;
    double time = 0.0;
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
            status = fmi2SetupExperiment(c, tolerance_defined, pick(2) ? 1e-6 : hostile_real(), pick(4) ? 0.0 : hostile_real(),
                                         pick(3) == 0, pick(2) ? 10.0 : hostile_real());
            judge("fmi2SetupExperiment", status, S_INSTANTIATED);
            after(status, 0);
            break;
        }
        case 1: status = fmi2EnterInitializationMode(c); judge("fmi2EnterInitializationMode", status, S_INSTANTIATED);
            after(status, S_INIT); break;
        case 2: case 3: status = fmi2ExitInitializationMode(c); judge("fmi2ExitInitializationMode", status, S_INIT);
            after(status, S_STEP_COMPLETE); time = 0.0; break;
        case 4: case 5: case 6: {
            const double h = pick(4) ? 1e-3 * (1 + pick(5)) : hostile_real();
            const double t = pick(8) ? time : hostile_real();
            status = fmi2DoStep(c, t, h, fmi2False);
            judge("fmi2DoStep", status, S_STEP_COMPLETE);
            if (status <= fmi2Warning) time += h;
            after(status, 0);
            break;
        }
        case 7: case 8: {
            for (size_t i = 0; i < nvr; i++) reals[i] = (vrs[i] >= 1 && vrs[i] < VR_COUNT) ? value_for((int)vrs[i]) : hostile_real();
            status = fmi2SetReal(c, pick(20) ? vrs : NULL, nvr, pick(20) ? reals : NULL);
            judge("fmi2SetReal", status, S_SET);
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
            status = pick(2) ? fmi2SetInteger(c, vrs, nvr, ints) : fmi2SetBoolean(c, vrs, nvr, ints);
            judge("fmi2SetInteger/Boolean", status, S_SET);
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
            if (pick(2)) { status = fmi2SetString(c, vrs, nvr, text); judge("fmi2SetString", status, S_SET); }
            else { status = fmi2GetString(c, vrs, nvr, out); judge("fmi2GetString", status, S_GET); }
            after(status, 0);
            break;
        }
        case 13: {
            fmi2Integer order[4];
            for (size_t i = 0; i < nvr; i++) { order[i] = 1 + pick(3) - (pick(10) == 0); reals[i] = hostile_real(); }
            status = fmi2SetRealInputDerivatives(c, pick(20) ? vrs : NULL, nvr, pick(20) ? order : NULL, reals);
            judge("fmi2SetRealInputDerivatives", status, S_SET);
            after(status, 0);
            break;
        }
        case 14: {
            fmi2Integer order[4];
            fmi2Real out[4];
            for (size_t i = 0; i < nvr; i++) order[i] = pick(4);
            status = fmi2GetRealOutputDerivatives(c, vrs, nvr, order, out);
            judge("fmi2GetRealOutputDerivatives", status, S_GET);
            after(status, 0);
            break;
        }
        case 15: {
            const int slot = pick(3);
            status = fmi2GetFMUstate(c, &states[slot]);
            judge("fmi2GetFMUstate", status, S_ANY);
            break;
        }
        case 16: {
            const int slot = pick(3);
            if (!states[slot]) break;
            status = fmi2SetFMUstate(c, states[slot]);
            judge("fmi2SetFMUstate", status, S_ANY);
            if (status == fmi2OK) possible = S_ANY; /* the state's own phase: unknown to the oracle */
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
            break;
        }
        case 19: {
            if (!bytes) break;
            if (pick(2)) bytes[next_random() % n_bytes] ^= (fmi2Byte)(1 + pick(255)); /* altered payload */
            const int slot = pick(3);
            status = fmi2DeSerializeFMUstate(c, bytes, pick(10) ? n_bytes : n_bytes - 1, &states[slot]);
            judge("fmi2DeSerializeFMUstate", status, S_ANY);
            break;
        }
        case 20: {
            fmi2Real r;
            fmi2Boolean b;
            status = pick(2) ? fmi2GetRealStatus(c, fmi2LastSuccessfulTime, pick(10) ? &r : NULL)
                             : fmi2GetBooleanStatus(c, fmi2Terminated, pick(10) ? &b : NULL);
            judge("fmi2GetReal/BooleanStatus", status, S_STATUS);
            break;
        }
        default: {
            const int which = pick(4);
            if (which == 0) { status = fmi2Terminate(c); judge("fmi2Terminate", status, S_STEP_COMPLETE | S_STEP_FAILED);
                after(status, S_TERMINATED); }
            else if (which == 1) { status = fmi2Reset(c); judge("fmi2Reset", status, S_ANY); after(status, S_INSTANTIATED); }
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

int main(int argc, char **argv) {
    unsigned long long first_seed = 1;
    long sequences = 1000, replay = -1;
    int max_calls = 200;
    for (int i = 1; i < argc; i++) {
        if (!strcmp(argv[i], "--seed") && i + 1 < argc) first_seed = strtoull(argv[++i], NULL, 10);
        else if (!strcmp(argv[i], "--sequences") && i + 1 < argc) sequences = strtol(argv[++i], NULL, 10);
        else if (!strcmp(argv[i], "--calls") && i + 1 < argc) max_calls = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--replay") && i + 1 < argc) replay = strtol(argv[++i], NULL, 10);
        else if (!strcmp(argv[i], "--verbose")) verbose = 1;
        else { fprintf(stderr, "usage: %s [--seed S] [--sequences N] [--calls M] [--replay K] [--verbose]\n", argv[0]); return 2; }
    }
    signal(SIGALRM, on_alarm);
    seed = first_seed;
    for (sequence_index = (replay >= 0 ? replay : 0); sequence_index < (replay >= 0 ? replay + 1 : sequences);
         sequence_index++) {
        rng_state = (first_seed * 0x9E3779B97F4A7C15ULL) ^ (unsigned long long)(sequence_index + 1) * 0xBF58476D1CE4E5B9ULL;
        if (!rng_state) rng_state = 1;
        alarm(10);
        run_sequence(max_calls);
        alarm(0);
    }
    printf("%s: seed %llu, %ld sequences, %ld calls, %ld violations\n", MODEL_IDENTIFIER_STRING, first_seed,
           replay >= 0 ? 1 : sequences, calls, violations);
    return violations ? 1 : 0;
}
