/* Six instances of one model stepped on six threads at once, then the same six one after
 * another: every output of every step must be bit for bit the same (built with -DCOSIM_FUZZ=ON;
 * with -DCOSIM_SANITIZE=ON under ThreadSanitizer, which reports any data race between them).
 *
 *   threads_<model> [--steps N]     exit 0 when identical and race-free
 */
#define _POSIX_C_SOURCE 200809L
#include "fmu_common.h"
#include "model_guid.h"

#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum { THREADS = 6 };

typedef struct {
    int k, steps;
    double *outputs; /* steps x (number of Real outputs) */
    int failed;
} Job;

static void quiet(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status, fmi2String category,
                  fmi2String message, ...) {
    (void)env; (void)name; (void)status; (void)category; (void)message;
}

static int n_outputs(void) {
    int n = 0;
    for (int vr = 1; vr < VR_COUNT; vr++) n += fmu_variables[vr].causality == FMU_OUTPUT && fmu_variables[vr].type == FMU_REAL;
    return n;
}

/* One instance: each Real input driven by a slow sine whose amplitude depends on k. */
static void *run(void *argument) {
    Job *job = (Job *)argument;
    const fmi2CallbackFunctions callbacks = {quiet, calloc, free, NULL, NULL};
    char name[32];
    snprintf(name, sizeof name, "thread%d", job->k);
    fmi2Component c = fmi2Instantiate(name, fmi2CoSimulation, MODEL_GUID, "", &callbacks, fmi2False, fmi2False);
    if (!c || fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) != fmi2OK ||
        fmi2EnterInitializationMode(c) != fmi2OK || fmi2ExitInitializationMode(c) != fmi2OK) {
        job->failed = 1;
        if (c) fmi2FreeInstance(c);
        return NULL;
    }
    const int m = n_outputs();
    for (int step = 0; step < job->steps; step++) {
        for (int vr = 1; vr < VR_COUNT; vr++) {
            if (fmu_variables[vr].causality != FMU_INPUT || fmu_variables[vr].type != FMU_REAL) continue;
            const fmi2ValueReference ref = (fmi2ValueReference)vr;
            const double value = fmu_variables[vr].start + 0.001 * (job->k + 1) * sin(0.01 * step + vr);
            fmi2SetReal(c, &ref, 1, &value);
        }
        if (fmi2DoStep(c, 1e-3 * step, 1e-3, fmi2False) > fmi2Warning) { job->failed = 1; break; }
        int j = 0;
        for (int vr = 1; vr < VR_COUNT; vr++) {
            if (fmu_variables[vr].causality != FMU_OUTPUT || fmu_variables[vr].type != FMU_REAL) continue;
            const fmi2ValueReference ref = (fmi2ValueReference)vr;
            fmi2GetReal(c, &ref, 1, &job->outputs[(size_t)step * (size_t)m + (size_t)j++]);
        }
    }
    fmi2FreeInstance(c);
    return NULL;
}

int main(int argc, char **argv) {
    int steps = 300;
    if (argc == 3 && !strcmp(argv[1], "--steps")) steps = atoi(argv[2]);
    const size_t m = (size_t)n_outputs(), size = (size_t)steps * m;
    Job parallel[THREADS], sequential[THREADS];
    pthread_t threads[THREADS];
    for (int k = 0; k < THREADS; k++) {
        parallel[k] = (Job){k, steps, (double *)calloc(size, sizeof(double)), 0};
        sequential[k] = (Job){k, steps, (double *)calloc(size, sizeof(double)), 0};
        if (!parallel[k].outputs || !sequential[k].outputs) return 2;
    }
    for (int k = 0; k < THREADS; k++) pthread_create(&threads[k], NULL, run, &parallel[k]);
    for (int k = 0; k < THREADS; k++) pthread_join(threads[k], NULL);
    for (int k = 0; k < THREADS; k++) run(&sequential[k]);
    int differ = 0;
    for (int k = 0; k < THREADS; k++) {
        if (parallel[k].failed || sequential[k].failed) { fprintf(stderr, "instance %d failed\n", k); differ = 1; }
        else if (memcmp(parallel[k].outputs, sequential[k].outputs, size * sizeof(double)) != 0) {
            fprintf(stderr, "instance %d: threaded outputs differ from the sequential run\n", k);
            differ = 1;
        }
        free(parallel[k].outputs);
        free(sequential[k].outputs);
    }
    printf("%s: %d instances x %d steps on %d threads: %s\n", MODEL_IDENTIFIER_STRING, THREADS, steps, THREADS,
           differ ? "DIFFER" : "bit for bit the sequential runs");
    return differ;
}
