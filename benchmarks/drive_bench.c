#define _POSIX_C_SOURCE 200809L
/* Native test bench for one drive FMU: loads the FMU's binary, turns a rigid inertia with it at a
 * fixed communication step, and prints the process CPU time spent per simulated second, so that
 * the figure is the FMU's own cost and not an interpreter's.
 *
 * usage: drive_bench LIB GUID STEP SECONDS INERTIA AMPLITUDE FREQUENCY
 *                    VR_REF VR_POSITION VR_VELOCITY VR_OUT [r<vr>=<value> | i<vr>=<value> | b<vr>=<0|1>]...
 * The reference input is AMPLITUDE sin(2 pi FREQUENCY t); VR_OUT is the torque (or force) output.
 * Prints: cpu_seconds_per_simulated_second final_tracking_error
 */
#include <dlfcn.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "fmi2Functions.h"

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status, fmi2String category,
                   fmi2String message, ...) {
    (void)env; (void)category;
    if (status >= fmi2Warning) fprintf(stderr, "%s: %s\n", name, message);
}

/* POSIX's way to take a function pointer from dlsym without an object-to-function cast. */
#define LOAD(name)                                                            \
    name##TYPE *name;                                                         \
    *(void **)(&name) = dlsym(lib, #name);                                    \
    if (!name) { fprintf(stderr, "missing %s\n", #name); return 2; }

static const double PI = 3.14159265358979323846;

int main(int argc, char **argv) {
    if (argc < 12) { fprintf(stderr, "usage: see drive_bench.c\n"); return 2; }
    void *lib = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    if (!lib) { fprintf(stderr, "%s\n", dlerror()); return 2; }
    LOAD(fmi2Instantiate) LOAD(fmi2SetupExperiment) LOAD(fmi2EnterInitializationMode)
    LOAD(fmi2ExitInitializationMode) LOAD(fmi2SetReal) LOAD(fmi2SetInteger) LOAD(fmi2SetBoolean) LOAD(fmi2GetReal)
    LOAD(fmi2DoStep) LOAD(fmi2FreeInstance)
    const double step = atof(argv[3]), seconds = atof(argv[4]), inertia = atof(argv[5]);
    const double amplitude = atof(argv[6]), frequency = atof(argv[7]);
    fmi2ValueReference inputs[3] = {(fmi2ValueReference)atoi(argv[8]), (fmi2ValueReference)atoi(argv[9]),
                                    (fmi2ValueReference)atoi(argv[10])};
    fmi2ValueReference output = (fmi2ValueReference)atoi(argv[11]);
    fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};
    fmi2Component c = fmi2Instantiate("bench", fmi2CoSimulation, argv[2], "", &callbacks, fmi2False, fmi2False);
    if (!c) return 1;
    if (fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) != fmi2OK) return 1;
    for (int i = 12; i < argc; i++) {
        fmi2ValueReference vr = (fmi2ValueReference)atoi(argv[i] + 1);
        const char *value = strchr(argv[i], '=');
        if (!value) return 2;
        if (argv[i][0] == 'i' || argv[i][0] == 'b') {
            fmi2Integer v = atoi(value + 1); /* fmi2Boolean is an int as well */
            if ((argv[i][0] == 'i' ? fmi2SetInteger(c, &vr, 1, &v) : fmi2SetBoolean(c, &vr, 1, &v)) != fmi2OK)
                return 1;
        } else {
            fmi2Real v = atof(value + 1);
            if (fmi2SetReal(c, &vr, 1, &v) != fmi2OK) return 1;
        }
    }
    if (fmi2EnterInitializationMode(c) != fmi2OK || fmi2ExitInitializationMode(c) != fmi2OK) return 1;

    double position = 0.0, velocity = 0.0, effort = 0.0, t = 0.0;
    const long n = lround(seconds / step);
    struct timespec start, end;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &start);
    for (long k = 0; k < n; k++) {
        t = k * step;
        fmi2Real values[3] = {amplitude * sin(2 * PI * frequency * t), position, velocity};
        if (fmi2SetReal(c, inputs, 3, values) != fmi2OK) return 1;
        if (fmi2DoStep(c, t, step, fmi2True) != fmi2OK) return 1;
        double before = effort;
        if (fmi2GetReal(c, &output, 1, &effort) != fmi2OK) return 1;
        double new_velocity = velocity + step * 0.5 * (before + effort) / inertia;
        position += 0.5 * step * (velocity + new_velocity);
        velocity = new_velocity;
    }
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &end);
    double cpu = (end.tv_sec - start.tv_sec) + 1e-9 * (end.tv_nsec - start.tv_nsec);
    printf("%.9g %.9g\n", cpu / seconds, fabs(position - amplitude * sin(2 * PI * frequency * n * step)));
    fmi2FreeInstance(c);
    return 0;
}
