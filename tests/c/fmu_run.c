/* Runs one FMI 2.0 co-simulation binary through an experiment and prints its Real outputs after
 * every step, so that the binaries of one FMU built by two compilers for two systems (linux64 by
 * gcc, win64 by MinGW-w64 and run under Wine) can be compared (tests/models/test_win64.py).
 *
 * usage: fmu_run LIB GUID STEP STEPS[r] VRS [r<vr>=<value> | i<vr>=<value> | b<vr>=<0|1> | s<vr>=<text>]...
 *   VRS: the value references printed, comma separated; the values are set before initialization
 *   (parameters and inputs alike) and the inputs held. Prints one line per communication point:
 *   the time and each value, %.17g, comma separated. With STEPS followed by r, the state at the
 *   half is kept (fmi2GetFMUstate, serialized and deserialized) and, after the last step, set back
 *   and the second half run again, printed after a line "replay". A step before initialization
 *   must be refused first. Exit 1 when a call fails, 2 on bad usage.
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "fmi2Functions.h"

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

static void log_message(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status, fmi2String category,
                        fmi2String message, ...) {
    (void)env, (void)category;
    if (status >= fmi2Warning) fprintf(stderr, "%s: %s\n", name, message);
}

#define LOAD(name)                                                     \
    name##TYPE *name;                                                  \
    *(void **)(&name) = symbol(lib, #name);                            \
    if (!name) {                                                       \
        fprintf(stderr, "missing %s\n", #name);                        \
        return 2;                                                      \
    }

int main(int argc, char **argv) {
    if (argc < 6) {
        fprintf(stderr, "usage: fmu_run LIB GUID STEP STEPS VRS [r<vr>=<value>]...\n");
        return 2;
    }
    Library lib = open_library(argv[1]);
    if (!lib) {
        fprintf(stderr, "cannot load %s\n", argv[1]);
        return 2;
    }
    LOAD(fmi2Instantiate) LOAD(fmi2SetupExperiment) LOAD(fmi2EnterInitializationMode)
    LOAD(fmi2ExitInitializationMode) LOAD(fmi2SetReal) LOAD(fmi2SetInteger) LOAD(fmi2SetBoolean)
    LOAD(fmi2SetString) LOAD(fmi2GetReal) LOAD(fmi2DoStep) LOAD(fmi2FreeInstance) LOAD(fmi2GetFMUstate)
    LOAD(fmi2SetFMUstate) LOAD(fmi2FreeFMUstate) LOAD(fmi2SerializedFMUstateSize) LOAD(fmi2SerializeFMUstate)
    LOAD(fmi2DeSerializeFMUstate)
    const double step = atof(argv[3]);
    char *mode;
    const long steps = strtol(argv[4], &mode, 10);
    const int replay = *mode == 'r';
    fmi2ValueReference out[MOST];
    size_t n_out = 0;
    for (char *item = strtok(argv[5], ","); item && n_out < MOST; item = strtok(NULL, ","))
        out[n_out++] = (fmi2ValueReference)strtoul(item, NULL, 10);
    fmi2CallbackFunctions callbacks = {log_message, calloc, free, NULL, NULL};
    fmi2Component c = fmi2Instantiate("run", fmi2CoSimulation, argv[2], "", &callbacks, fmi2False, fmi2False);
    if (!c || fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) != fmi2OK) return 1;
    for (int i = 6; i < argc; i++) {
        const fmi2ValueReference vr = (fmi2ValueReference)strtoul(argv[i] + 1, NULL, 10);
        const char *value = strchr(argv[i], '=');
        fmi2Status s;
        if (!value) return 2;
        value++;
        if (argv[i][0] == 'i') {
            const fmi2Integer v = atoi(value);
            s = fmi2SetInteger(c, &vr, 1, &v);
        } else if (argv[i][0] == 'b') {
            const fmi2Boolean v = atoi(value);
            s = fmi2SetBoolean(c, &vr, 1, &v);
        } else if (argv[i][0] == 's') {
            s = fmi2SetString(c, &vr, 1, &value);
        } else {
            const fmi2Real v = strtod(value, NULL);
            s = fmi2SetReal(c, &vr, 1, &v);
        }
        if (s != fmi2OK) return 1;
    }
    if (fmi2DoStep(c, 0.0, step, fmi2True) != fmi2Error) return 1; /* before initialization: refused */
    if (fmi2EnterInitializationMode(c) != fmi2OK || fmi2ExitInitializationMode(c) != fmi2OK) return 1;
    fmi2Real values[MOST];
    fmi2FMUstate kept = NULL;
    char *bytes = NULL;
    size_t size = 0;
    const long half = steps / 2;
    for (int pass = 0; pass <= replay; pass++) {
        if (pass == 1) { /* the kept state, through its bytes, into a fresh state object */
            fmi2FMUstate restored = NULL;
            if (fmi2DeSerializeFMUstate(c, (const fmi2Byte *)bytes, size, &restored) != fmi2OK ||
                fmi2SetFMUstate(c, restored) != fmi2OK || fmi2FreeFMUstate(c, &restored) != fmi2OK)
                return 1;
            printf("replay\n");
        }
        for (long k = pass ? half : 0; k <= steps; k++) {
            if (k > (pass ? half : 0) && fmi2DoStep(c, (k - 1) * step, step, fmi2True) > fmi2Warning) return 1;
            if (fmi2GetReal(c, out, n_out, values) != fmi2OK) return 1;
            printf("%.17g", k * step);
            for (size_t j = 0; j < n_out; j++) printf(",%.17g", values[j]);
            printf("\n");
            if (replay && pass == 0 && k == half) {
                if (fmi2GetFMUstate(c, &kept) != fmi2OK || fmi2SerializedFMUstateSize(c, kept, &size) != fmi2OK)
                    return 1;
                bytes = (char *)malloc(size);
                if (!bytes || fmi2SerializeFMUstate(c, kept, (fmi2Byte *)bytes, size) != fmi2OK ||
                    fmi2FreeFMUstate(c, &kept) != fmi2OK)
                    return 1;
            }
        }
    }
    free(bytes);
    fmi2FreeInstance(c);
    return 0;
}
