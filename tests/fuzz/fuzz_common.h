/* What the fuzz harnesses share (fuzz_fmi.c: FMI 2.0, fuzz_fmi3.c: FMI 3.0): random numbers,
 * hostile values, the oracle's bookkeeping, the alarm and the command line. Random call sequences
 * against one model, linked in with the shared layer (build with -DCOSIM_FUZZ=ON; with
 * -DCOSIM_SANITIZE=ON under AddressSanitizer and UndefinedBehaviorSanitizer).
 *
 *   fuzz_<model> | fuzz3_<model> [--seed S] [--sequences N] [--calls M] [--replay K] [--verbose]
 *
 * Each sequence instantiates the model and makes up to M calls chosen at random, with hostile
 * arguments: value references in and out of range, NaN, infinities, huge and tiny numbers, NULL
 * arrays, step sizes of every sign and size, FMU states of its own, altered serialized bytes.
 * Every result is judged by an oracle built from the standard's Co-Simulation and Model Exchange
 * state machines (the set of states the instance may be in after each call): a call the standard does not allow that returns
 * OK, a Real output read as NaN or infinite with fmi2OK, or a call that takes longer than
 * HANG_SECONDS (an alarm re-armed after every call) is a violation, reported with the seed and the
 * sequence index, which replay it
 * alone (--replay K, with --verbose printing every call). Crashes and memory errors are the
 * sanitizers' to report. Exit status: 0 without violations, 1 otherwise.
 */
#ifndef FUZZ_COMMON_H
#define FUZZ_COMMON_H
#define _POSIX_C_SOURCE 200809L /* alarm, signal */

/* A hang is a call that has not returned after this long. The layers bound one fmi2DoStep's work
 * (200000 internal steps, fmu/common/ode.c), and a hostile step size may ask for nearly all of it:
 * about 8 s for the mechanics under the sanitizers on this machine's cores. A per-sequence budget
 * (200 calls of bounded work) could not tell that from a hang; a per-call one with room does.
 * A system FMU bounds a communication step at 200000 of the system's steps
 * (cosim/engine/kernel/system_fmu.c), each a step of every FMU in it: far more work per call, the
 * most with every log category on, where the drives log each switching of their inverters (tens of
 * thousands of lines per simulated second). Measured on Meng's system: a step of 160 s (160174 of its
 * 1 ms steps) with debug logging on took 52 s of CPU here; the most it allows, about 65 s. */
#ifdef FUZZ_SYSTEM
#define HANG_SECONDS 240
#else
#define HANG_SECONDS 30
#endif
#ifndef FUZZ_SYSTEM /* a model's harness: its variable table (a system's reads its FMU's description) */
#include "fmu_common.h"
#include "model_guid.h"
#endif

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

#ifndef FUZZ_SYSTEM
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
#endif

/* ---- the oracle: FMI 2.0 Co-Simulation and Model Exchange states (a set: after an error the
 * instance may be anywhere); after initialization Co-Simulation is in Step Complete (or Failed),
 * Model Exchange in Event Mode or Continuous-Time Mode ---- */
enum { S_INSTANTIATED = 1, S_INIT = 2, S_STEP_COMPLETE = 4, S_STEP_FAILED = 8, S_TERMINATED = 16, S_ERROR = 32,
       S_EVENT = 64, S_CONTINUOUS = 128 };
#define S_ANY (S_INSTANTIATED | S_INIT | S_STEP_COMPLETE | S_STEP_FAILED | S_TERMINATED | S_ERROR | S_EVENT | S_CONTINUOUS)
#define S_GET (S_INIT | S_STEP_COMPLETE | S_STEP_FAILED | S_TERMINATED | S_ERROR | S_EVENT | S_CONTINUOUS)
#define S_SET (S_INSTANTIATED | S_INIT | S_STEP_COMPLETE | S_EVENT | S_CONTINUOUS)
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

/* judge a call (status 0 OK, 1 warning, 3 error, as FMI 2.0 and 3.0 both number them): allowed_in = the
 * states in which the standard allows it */
static void judge(const char *call, int status, int allowed_in) {
    calls++;
    alarm(HANG_SECONDS); /* the next call's time starts now */
    if (verbose) fprintf(stderr, "  %s -> %d (states %#x)\n", call, status, possible);
    if (status == 0 && !(possible & allowed_in)) violation(call, "accepted in a state where the standard forbids it");
}

/* after a call that failed, the instance may have moved to the error state */
static void after(int status, int success_state) {
    if (status <= 1) { if (success_state) possible = success_state; }
    else possible |= S_ERROR;
}

#ifndef FUZZ_SYSTEM
/* Where setting these references (as `type`: 'r', 'i', 'b', 's'; a model's harness does not judge it)
 * may succeed: Model Exchange's Continuous-Time Mode takes continuous inputs only (its other
 * variables in Event Mode). */
static int settable_states(const unsigned *vrs, size_t nvr, int type) {
    (void)type;
    for (size_t i = 0; vrs && i < nvr; i++)
        if (vrs[i] >= 1 && vrs[i] < VR_COUNT &&
            !(fmu_variables[vrs[i]].causality == FMU_INPUT && fmu_variables[vrs[i]].variability == FMU_CONTINUOUS))
            return S_SET & ~S_CONTINUOUS;
    return S_SET;
}

/* a model's harness takes no options of its own; its name is its model's */
static int fuzz_option(const char *flag, const char *value) { (void)flag, (void)value; return 0; }
static const char *fuzz_name(void) { return MODEL_IDENTIFIER_STRING; }
#define STATES_CAPACITY (MODEL_N_STATES > 0 ? MODEL_N_STATES : 1) /* a state array's length */
#define OFFERS_CO_SIMULATION 1
#define FMU_STATE_CALLS S_ANY /* where its FMU state calls may succeed */
#define RESOURCES ""
#else
/* A system FMU's harness (fuzz_fmi.c and fuzz_fmi3.c built with FUZZ_SYSTEM: fuzz_system and
 * fuzz3_system): what a model's harness has from its variable table, read from the FMU's
 * description (fuzz_system.h, --fmu-dir DIR). */
#include "fuzz_system.h"
#define MODEL_GUID guid
#define MODEL_N_STATES n_states
#define STATES_CAPACITY (MAX_STATES + 2)
#define MODEL_MODEL_EXCHANGE offers_model_exchange
#define OFFERS_CO_SIMULATION (!offers_model_exchange) /* exported as one interface or the other */
#define FMU_STATE_CALLS (has_fmu_state ? S_ANY : 0)
#define VR_COUNT ((unsigned)n_variables)
#define RESOURCES resources
#endif

static void on_alarm(int signum) {
    (void)signum;
    char text[160];
    int n = snprintf(text, sizeof text, "VIOLATION seed %llu sequence %ld call %ld: hang (longer than %d s)\n", seed,
                     sequence_index, calls + 1, HANG_SECONDS);
    if (n > 0) { ssize_t ignored = write(2, text, (size_t)n); (void)ignored; }
    _exit(1);
}

static void run_sequence(int max_calls);

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
        else if (i + 1 < argc && fuzz_option(argv[i], argv[i + 1])) i++;
        else { fprintf(stderr, "usage: %s [--seed S] [--sequences N] [--calls M] [--replay K] [--verbose]\n", argv[0]); return 2; }
    }
    signal(SIGALRM, on_alarm);
    seed = first_seed;
    for (sequence_index = (replay >= 0 ? replay : 0); sequence_index < (replay >= 0 ? replay + 1 : sequences);
         sequence_index++) {
        rng_state = (first_seed * 0x9E3779B97F4A7C15ULL) ^ (unsigned long long)(sequence_index + 1) * 0xBF58476D1CE4E5B9ULL;
        if (!rng_state) rng_state = 1;
        alarm(HANG_SECONDS);
        run_sequence(max_calls);
        alarm(0);
    }
    printf("%s: seed %llu, %ld sequences, %ld calls, %ld violations\n", fuzz_name(), first_seed,
           replay >= 0 ? 1 : sequences, calls, violations);
    return violations ? 1 : 0;
}

#endif
