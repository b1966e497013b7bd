/* Native stepping of one co-simulation FMU with constant inputs: prints the process CPU time per
 * simulated second, so the figure is the FMU's own cost.
 *
 * usage: fmu_step_bench LIB GUID STEP SECONDS [r<vr>=<value> | i<vr>=<value> | b<vr>=<0|1>]...
 * The values are set before initialization (parameters and inputs alike).
 */
#define _POSIX_C_SOURCE 200809L
#include <dlfcn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "fmi2Functions.h"

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status, fmi2String category,
                   fmi2String message, ...) {
    (void)env; (void)category;
    if (status >= fmi2Error) fprintf(stderr, "%s: %s\n", name, message);
}

#define LOAD(name)                                                            \
    name##TYPE *name;                                                         \
    *(void **)(&name) = dlsym(lib, #name);                                    \
    if (!name) { fprintf(stderr, "missing %s\n", #name); return 2; }

int main(int argc, char **argv) {
    if (argc < 5) { fprintf(stderr, "usage: see fmu_step_bench.c\n"); return 2; }
    void *lib = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    if (!lib) { fprintf(stderr, "%s\n", dlerror()); return 2; }
    LOAD(fmi2Instantiate) LOAD(fmi2SetupExperiment) LOAD(fmi2EnterInitializationMode)
    LOAD(fmi2ExitInitializationMode) LOAD(fmi2SetReal) LOAD(fmi2SetInteger) LOAD(fmi2SetBoolean)
    LOAD(fmi2DoStep) LOAD(fmi2FreeInstance)
    const double step = atof(argv[3]), seconds = atof(argv[4]);
    fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};
    fmi2Component c = fmi2Instantiate("bench", fmi2CoSimulation, argv[2], "", &callbacks, fmi2False, fmi2False);
    if (!c || fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) != fmi2OK) return 1;
    for (int i = 5; i < argc; i++) {
        fmi2ValueReference vr = (fmi2ValueReference)atoi(argv[i] + 1);
        const char *value = strchr(argv[i], '=');
        if (!value) return 2;
        fmi2Status s;
        if (argv[i][0] == 'i') { fmi2Integer v = atoi(value + 1); s = fmi2SetInteger(c, &vr, 1, &v); }
        else if (argv[i][0] == 'b') { fmi2Boolean v = atoi(value + 1); s = fmi2SetBoolean(c, &vr, 1, &v); }
        else { fmi2Real v = atof(value + 1); s = fmi2SetReal(c, &vr, 1, &v); }
        if (s != fmi2OK) return 1;
    }
    if (fmi2EnterInitializationMode(c) != fmi2OK || fmi2ExitInitializationMode(c) != fmi2OK) return 1;
    const long n = (long)(seconds / step + 0.5);
    struct timespec start, end;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &start);
    for (long k = 0; k < n; k++)
        if (fmi2DoStep(c, k * step, step, fmi2True) != fmi2OK) return 1;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &end);
    double cpu = (end.tv_sec - start.tv_sec) + 1e-9 * (end.tv_nsec - start.tv_nsec);
    printf("%.9g\n", cpu / seconds);
    fmi2FreeInstance(c);
    return 0;
}
