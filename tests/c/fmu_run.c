/* Runs one co-simulation binary through an experiment and prints its Real outputs after every
 * step, so that the binaries of one FMU built by two compilers for two systems (Linux by gcc,
 * Windows by MinGW-w64 and run under Wine) can be compared (tests/models/test_win64.py). Built
 * twice from this file: for FMI 2.0, and with -DFMU_RUN_FMI3 for FMI 3.0 (the same experiment
 * through the fmi3 entry points).
 *
 * usage: fmu_run LIB TOKEN STEP STEPS[r] VRS [r<vr>=<value> | i<vr>=<value> | b<vr>=<0|1> | s<vr>=<text>]...
 *   TOKEN: the GUID (FMI 2.0) or instantiation token (FMI 3.0); VRS: the value references printed,
 *   comma separated; the values are set before initialization (parameters and inputs alike) and the
 *   inputs held. Prints one line per communication point: the time and each value, %.17g, comma
 *   separated. With STEPS followed by r, the state at the half is kept (get, serialize) and, after the
 *   last step, deserialized, set back and the second half run again, printed after a line "replay". A
 *   step before initialization must be refused first. Exit 1 when a call fails, 2 on bad usage.
 *   The environment's FMU_RUN_RESOURCES, if set, is the resource location given at instantiation
 *   (FMI 2.0: a file URI; FMI 3.0: a path), otherwise none ("").
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#ifdef FMU_RUN_FMI3
#include "fmi3Functions.h"
#else
#include "fmi2Functions.h"
#endif

#ifdef _WIN32
#include <windows.h>
typedef HMODULE Library;
static Library open_library(const char *path) { return LoadLibraryA(path); }
static void *symbol(Library lib, const char *name) { return (void *)(size_t)GetProcAddress(lib, name); }
#else
#include <dlfcn.h>
typedef void *Library;
static Library open_library(const char *path) { return dlopen(path, RTLD_NOW | RTLD_LOCAL); }
static void *symbol(Library lib, const char *name) { return dlsym(lib, name); }
#endif

enum { MOST = 512 };
#define RUN_OK 0 /* the statuses, numbered alike in FMI 2.0 and 3.0 */
#define RUN_WARNING 1
#define RUN_ERROR 3

static Library lib;

/* f_<name>: the binary's <name>, found by load_<name> (the header declares <name> itself) */
#define LOAD(name)                                                         \
    static name##TYPE *f_##name;                                           \
    static int load_##name(void) {                                         \
        *(void **)(&f_##name) = symbol(lib, #name);                        \
        if (!f_##name) fprintf(stderr, "missing %s\n", #name);             \
        return f_##name != NULL;                                           \
    }

#ifdef FMU_RUN_FMI3
LOAD(fmi3InstantiateCoSimulation) LOAD(fmi3EnterInitializationMode) LOAD(fmi3ExitInitializationMode)
LOAD(fmi3SetFloat64) LOAD(fmi3SetInt32) LOAD(fmi3SetBoolean) LOAD(fmi3SetString) LOAD(fmi3GetFloat64)
LOAD(fmi3DoStep) LOAD(fmi3FreeInstance) LOAD(fmi3GetFMUState) LOAD(fmi3SetFMUState) LOAD(fmi3FreeFMUState)
LOAD(fmi3SerializedFMUStateSize) LOAD(fmi3SerializeFMUState) LOAD(fmi3DeserializeFMUState)

static fmi3Instance c;

static void log_message(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category, fmi3String message) {
    (void)env, (void)category;
    if (status >= fmi3Warning) fprintf(stderr, "%s\n", message);
}

static int set(char kind, unsigned vr, const char *text) {
    if (kind == 'i') { const fmi3Int32 v = atoi(text); return f_fmi3SetInt32(c, &vr, 1, &v, 1); }
    if (kind == 'b') { const fmi3Boolean v = atoi(text) != 0; return f_fmi3SetBoolean(c, &vr, 1, &v, 1); }
    if (kind == 's') return f_fmi3SetString(c, &vr, 1, &text, 1);
    const fmi3Float64 v = strtod(text, NULL);
    return f_fmi3SetFloat64(c, &vr, 1, &v, 1);
}
static int get_reals(const unsigned *vr, size_t n, double *out) { return f_fmi3GetFloat64(c, vr, n, out, n); }
static int initialize(void) {
    const int status = f_fmi3EnterInitializationMode(c, fmi3False, 0.0, 0.0, fmi3False, 0.0);
    return status != RUN_OK ? status : (int)f_fmi3ExitInitializationMode(c);
}
static int step(double t, double h) {
    fmi3Boolean event, terminate, early;
    fmi3Float64 last;
    return f_fmi3DoStep(c, t, h, fmi3True, &event, &terminate, &early, &last);
}
static int keep(char **bytes, size_t *size) {
    fmi3FMUState state = NULL;
    if (f_fmi3GetFMUState(c, &state) != RUN_OK || f_fmi3SerializedFMUStateSize(c, state, size) != RUN_OK)
        return RUN_ERROR;
    *bytes = (char *)malloc(*size);
    if (!*bytes || f_fmi3SerializeFMUState(c, state, (fmi3Byte *)*bytes, *size) != RUN_OK) return RUN_ERROR;
    return f_fmi3FreeFMUState(c, &state);
}
static int restore(const char *bytes, size_t size) {
    fmi3FMUState state = NULL;
    if (f_fmi3DeserializeFMUState(c, (const fmi3Byte *)bytes, size, &state) != RUN_OK ||
        f_fmi3SetFMUState(c, state) != RUN_OK)
        return RUN_ERROR;
    return f_fmi3FreeFMUState(c, &state);
}
static void release(void) { f_fmi3FreeInstance(c); }

static int open_instance(const char *token) {
    if (!(load_fmi3InstantiateCoSimulation() && load_fmi3EnterInitializationMode() &&
          load_fmi3ExitInitializationMode() && load_fmi3SetFloat64() && load_fmi3SetInt32() && load_fmi3SetBoolean() &&
          load_fmi3SetString() && load_fmi3GetFloat64() && load_fmi3DoStep() && load_fmi3FreeInstance() &&
          load_fmi3GetFMUState() && load_fmi3SetFMUState() && load_fmi3FreeFMUState() &&
          load_fmi3SerializedFMUStateSize() && load_fmi3SerializeFMUState() && load_fmi3DeserializeFMUState()))
        return 0;
    const char *resources = getenv("FMU_RUN_RESOURCES");
    c = f_fmi3InstantiateCoSimulation("run", token, resources ? resources : "", fmi3False, fmi3False, fmi3False, fmi3False, NULL, 0, NULL,
                                    log_message, NULL);
    return c != NULL;
}
#else
LOAD(fmi2Instantiate) LOAD(fmi2SetupExperiment) LOAD(fmi2EnterInitializationMode) LOAD(fmi2ExitInitializationMode)
LOAD(fmi2SetReal) LOAD(fmi2SetInteger) LOAD(fmi2SetBoolean) LOAD(fmi2SetString) LOAD(fmi2GetReal) LOAD(fmi2DoStep)
LOAD(fmi2FreeInstance) LOAD(fmi2GetFMUstate) LOAD(fmi2SetFMUstate) LOAD(fmi2FreeFMUstate)
LOAD(fmi2SerializedFMUstateSize) LOAD(fmi2SerializeFMUstate) LOAD(fmi2DeSerializeFMUstate)

static fmi2Component c;

static void log_message(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status, fmi2String category,
                        fmi2String message, ...) {
    (void)env, (void)category;
    if (status >= fmi2Warning) fprintf(stderr, "%s: %s\n", name, message);
}

static int set(char kind, unsigned vr, const char *text) {
    if (kind == 'i') { const fmi2Integer v = atoi(text); return f_fmi2SetInteger(c, &vr, 1, &v); }
    if (kind == 'b') { const fmi2Boolean v = atoi(text); return f_fmi2SetBoolean(c, &vr, 1, &v); }
    if (kind == 's') return f_fmi2SetString(c, &vr, 1, &text);
    const fmi2Real v = strtod(text, NULL);
    return f_fmi2SetReal(c, &vr, 1, &v);
}
static int get_reals(const unsigned *vr, size_t n, double *out) { return f_fmi2GetReal(c, vr, n, out); }
static int initialize(void) {
    const int status = f_fmi2EnterInitializationMode(c);
    return status != RUN_OK ? status : (int)f_fmi2ExitInitializationMode(c);
}
static int step(double t, double h) { return f_fmi2DoStep(c, t, h, fmi2True); }
static int keep(char **bytes, size_t *size) {
    fmi2FMUstate state = NULL;
    if (f_fmi2GetFMUstate(c, &state) != RUN_OK || f_fmi2SerializedFMUstateSize(c, state, size) != RUN_OK)
        return RUN_ERROR;
    *bytes = (char *)malloc(*size);
    if (!*bytes || f_fmi2SerializeFMUstate(c, state, (fmi2Byte *)*bytes, *size) != RUN_OK) return RUN_ERROR;
    return f_fmi2FreeFMUstate(c, &state);
}
static int restore(const char *bytes, size_t size) {
    fmi2FMUstate state = NULL;
    if (f_fmi2DeSerializeFMUstate(c, (const fmi2Byte *)bytes, size, &state) != RUN_OK ||
        f_fmi2SetFMUstate(c, state) != RUN_OK)
        return RUN_ERROR;
    return f_fmi2FreeFMUstate(c, &state);
}
static void release(void) { f_fmi2FreeInstance(c); }

static fmi2CallbackFunctions callbacks = {log_message, calloc, free, NULL, NULL};

static int open_instance(const char *token) {
    if (!(load_fmi2Instantiate() && load_fmi2SetupExperiment() && load_fmi2EnterInitializationMode() &&
          load_fmi2ExitInitializationMode() && load_fmi2SetReal() && load_fmi2SetInteger() && load_fmi2SetBoolean() &&
          load_fmi2SetString() && load_fmi2GetReal() && load_fmi2DoStep() && load_fmi2FreeInstance() &&
          load_fmi2GetFMUstate() && load_fmi2SetFMUstate() && load_fmi2FreeFMUstate() &&
          load_fmi2SerializedFMUstateSize() && load_fmi2SerializeFMUstate() && load_fmi2DeSerializeFMUstate()))
        return 0;
    const char *resources = getenv("FMU_RUN_RESOURCES");
    c = f_fmi2Instantiate("run", fmi2CoSimulation, token, resources ? resources : "", &callbacks, fmi2False,
                          fmi2False);
    return c != NULL && f_fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) == fmi2OK;
}
#endif

int main(int argc, char **argv) {
    if (argc < 6) {
        fprintf(stderr, "usage: fmu_run LIB TOKEN STEP STEPS[r] VRS [r<vr>=<value>]...\n");
        return 2;
    }
    lib = open_library(argv[1]);
    if (!lib) {
        fprintf(stderr, "cannot load %s\n", argv[1]);
        return 2;
    }
    if (!open_instance(argv[2])) return 1;
    const double h = atof(argv[3]);
    char *mode;
    const long steps = strtol(argv[4], &mode, 10);
    const int replay = *mode == 'r';
    unsigned out[MOST];
    size_t n_out = 0;
    for (char *item = strtok(argv[5], ","); item && n_out < MOST; item = strtok(NULL, ","))
        out[n_out++] = (unsigned)strtoul(item, NULL, 10);
    for (int i = 6; i < argc; i++) {
        const char *value = strchr(argv[i], '=');
        if (!value) return 2;
        if (set(argv[i][0], (unsigned)strtoul(argv[i] + 1, NULL, 10), value + 1) != RUN_OK) return 1;
    }
    if (step(0.0, h) != RUN_ERROR) return 1; /* before initialization: refused */
    if (initialize() != RUN_OK) return 1;
    double values[MOST];
    char *bytes = NULL;
    size_t size = 0;
    const long half = steps / 2;
    for (int pass = 0; pass <= replay; pass++) {
        if (pass == 1) { /* the kept state, through its bytes, into a fresh state object */
            if (restore(bytes, size) != RUN_OK) return 1;
            printf("replay\n");
        }
        for (long k = pass ? half : 0; k <= steps; k++) {
            if (k > (pass ? half : 0) && step((k - 1) * h, h) > RUN_WARNING) return 1;
            if (get_reals(out, n_out, values) != RUN_OK) return 1;
            printf("%.17g", k * h);
            for (size_t j = 0; j < n_out; j++) printf(",%.17g", values[j]);
            printf("\n");
            if (replay && pass == 0 && k == half && keep(&bytes, &size) != RUN_OK) return 1;
        }
    }
    free(bytes);
    release();
    return 0;
}
