/* Does stepping the six drives of a Gauss-Seidel sweep on two threads pay at a 1 ms macro step?
 *
 * Six instances of a drive FMU, each on its own rigid load (as benchmarks/drive_bench.c), stepped
 * for SECONDS at STEP: once one after another, once three per thread on two threads that meet at a
 * barrier after every macro step (as the step kernel would have to: the mechanics needs all six
 * efforts before it steps). The barrier spins (a futex sleep costs more than a drive's step).
 * Prints: wall seconds sequential, wall seconds on two threads, and whether the six final efforts
 * are bit for bit the same.
 *
 * usage: drive_threads LIB GUID STEP SECONDS INERTIA AMPLITUDE FREQUENCY VR_REF VR_POS VR_VEL VR_OUT
 */
#define _POSIX_C_SOURCE 200809L
#include <dlfcn.h>
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "fmi2Functions.h"

#define DRIVES 6
static const double PI = 3.14159265358979323846;

static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status, fmi2String category,
                   fmi2String message, ...) {
    (void)env; (void)category;
    if (status >= fmi2Error) fprintf(stderr, "%s: %s\n", name, message);
}

static fmi2InstantiateTYPE *instantiate;
static fmi2SetupExperimentTYPE *setup;
static fmi2EnterInitializationModeTYPE *enter;
static fmi2ExitInitializationModeTYPE *leave;
static fmi2SetRealTYPE *set_real;
static fmi2GetRealTYPE *get_real;
static fmi2DoStepTYPE *do_step;
static fmi2FreeInstanceTYPE *free_instance;

typedef struct {
    fmi2Component c;
    double position, velocity, effort, phase;
} Drive;

static double step, inertia, amplitude, frequency;
static fmi2ValueReference inputs[3], output;
static long n_steps;

/* One drive, one macro step: inputs from its load, step, effort integrates the load (trapezoid). */
static int advance(Drive *d, long k) {
    const double t = k * step;
    fmi2Real values[3] = {amplitude * sin(2 * PI * frequency * t + d->phase), d->position, d->velocity};
    if (set_real(d->c, inputs, 3, values) != fmi2OK || do_step(d->c, t, step, fmi2True) != fmi2OK) return -1;
    double before = d->effort;
    if (get_real(d->c, &output, 1, &d->effort) != fmi2OK) return -1;
    double new_velocity = d->velocity + step * 0.5 * (before + d->effort) / inertia;
    d->position += 0.5 * step * (d->velocity + new_velocity);
    d->velocity = new_velocity;
    return 0;
}

static int make(Drive *drives, const char *guid, fmi2CallbackFunctions *callbacks) {
    for (int i = 0; i < DRIVES; i++) {
        memset(&drives[i], 0, sizeof drives[i]);
        drives[i].phase = i * PI / 3;
        drives[i].c = instantiate("drive", fmi2CoSimulation, guid, "", callbacks, fmi2False, fmi2False);
        if (!drives[i].c || setup(drives[i].c, fmi2False, 0.0, 0.0, fmi2False, 0.0) != fmi2OK ||
            enter(drives[i].c) != fmi2OK || leave(drives[i].c) != fmi2OK)
            return -1;
    }
    return 0;
}

/* a sense-reversing spin barrier for two threads */
static atomic_int arrived, sense;

static void barrier(int *local_sense) {
    *local_sense = !*local_sense;
    if (atomic_fetch_add(&arrived, 1) == 1) {
        atomic_store(&arrived, 0);
        atomic_store(&sense, *local_sense);
    } else {
        while (atomic_load(&sense) != *local_sense) {
        }
    }
}

typedef struct {
    Drive *drives;
    int first, status;
} Work;

static void *run_half(void *arg) {
    Work *w = arg;
    int local_sense = 0;
    for (long k = 0; k < n_steps; k++) {
        for (int i = w->first; i < w->first + DRIVES / 2; i++)
            if (advance(&w->drives[i], k) != 0) w->status = -1;
        barrier(&local_sense); /* all six efforts are there: the mechanics would step now */
    }
    return NULL;
}

static double now(void) {
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return t.tv_sec + 1e-9 * t.tv_nsec;
}

int main(int argc, char **argv) {
    if (argc != 12) { fprintf(stderr, "usage: see drive_threads.c\n"); return 2; }
    void *lib = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    if (!lib) { fprintf(stderr, "%s\n", dlerror()); return 2; }
    *(void **)&instantiate = dlsym(lib, "fmi2Instantiate");
    *(void **)&setup = dlsym(lib, "fmi2SetupExperiment");
    *(void **)&enter = dlsym(lib, "fmi2EnterInitializationMode");
    *(void **)&leave = dlsym(lib, "fmi2ExitInitializationMode");
    *(void **)&set_real = dlsym(lib, "fmi2SetReal");
    *(void **)&get_real = dlsym(lib, "fmi2GetReal");
    *(void **)&do_step = dlsym(lib, "fmi2DoStep");
    *(void **)&free_instance = dlsym(lib, "fmi2FreeInstance");
    if (!instantiate || !setup || !enter || !leave || !set_real || !get_real || !do_step || !free_instance) return 2;
    step = atof(argv[3]);
    n_steps = lround(atof(argv[4]) / step);
    inertia = atof(argv[5]), amplitude = atof(argv[6]), frequency = atof(argv[7]);
    for (int i = 0; i < 3; i++) inputs[i] = (fmi2ValueReference)atoi(argv[8 + i]);
    output = (fmi2ValueReference)atoi(argv[11]);
    fmi2CallbackFunctions callbacks = {logger, calloc, free, NULL, NULL};

    Drive sequential[DRIVES], threaded[DRIVES];
    if (make(sequential, argv[2], &callbacks) != 0 || make(threaded, argv[2], &callbacks) != 0) return 1;
    double start = now();
    for (long k = 0; k < n_steps; k++)
        for (int i = 0; i < DRIVES; i++)
            if (advance(&sequential[i], k) != 0) return 1;
    double wall_sequential = now() - start;

    Work halves[2] = {{threaded, 0, 0}, {threaded, DRIVES / 2, 0}};
    pthread_t other;
    start = now();
    if (pthread_create(&other, NULL, run_half, &halves[1]) != 0) return 1;
    run_half(&halves[0]);
    pthread_join(other, NULL);
    double wall_threaded = now() - start;
    if (halves[0].status || halves[1].status) return 1;

    int identical = 1;
    for (int i = 0; i < DRIVES; i++)
        identical &= memcmp(&sequential[i].effort, &threaded[i].effort, sizeof(double)) == 0 &&
                     memcmp(&sequential[i].position, &threaded[i].position, sizeof(double)) == 0;
    printf("%.9g %.9g %d\n", wall_sequential, wall_threaded, identical);
    for (int i = 0; i < DRIVES; i++) { free_instance(sequential[i].c); free_instance(threaded[i].c); }
    return 0;
}
