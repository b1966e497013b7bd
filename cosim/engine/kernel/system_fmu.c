/* A whole system as one FMI 2.0 Co-Simulation FMU: the FMUs of the system nested in its
 * resources/, coupled inside each communication step by the engine's step kernel (kernel.c), the
 * one implementation of the coupling that `cosim run` uses.
 *
 * cosim/engine/system_fmu.py writes the FMU: this library as its binary, the nested FMUs unzipped
 * under resources/fmus/, and resources/system.txt, the system as the engine resolved it (each
 * instance's coupled outputs and inputs with their sources, the bonds, the feed-through plan, the
 * algorithm, the scene's step plan with its finer start and edges, the components' values and the
 * outer variables' places among the instances; read by system_read.c, its layout in
 * docs/guide/engine.md).
 *
 * A communication step from t to t + H takes the plan's steps that end within it whole, and the
 * step that H ends inside up to t + H (the rest of it in the next communication step): where H is
 * a multiple of the plan's steps the FMU steps exactly as `cosim run` does, bit for bit; any H
 * steps at least as finely. A variable of the outer FMU is one of a nested instance's (its inputs
 * that no connection feeds, its parameters, the recorded outputs); a call on it is passed on. */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "location.h"
#include "system.h"

/* ---- logging ---- */

void say(System *s, fmi2Status status, const char *category, const char *format, ...) {
    if (!s->outer.logger) return;
    if (status == fmi2OK && !s->logging) return;
    char text[2048], escaped[4200];
    va_list args;
    va_start(args, format);
    vsnprintf(text, sizeof text, format, args);
    va_end(args);
    size_t k = 0; /* the importer's logger formats the message again: a '%' in it is doubled */
    for (const char *c = text; *c && k + 2 < sizeof escaped; c++) {
        if (*c == '%') escaped[k++] = '%';
        escaped[k++] = *c;
    }
    escaped[k] = '\0';
    s->outer.logger(s->outer.componentEnvironment, s->instance_name, status, category, escaped);
}

/* What a nested instance logs reaches the importer as the outer instance's, named by the instance. */
static void inner_logger(fmi2ComponentEnvironment environment, fmi2String name, fmi2Status status,
                         fmi2String category, fmi2String message, ...) {
    Inner *inner = environment;
    char text[2048];
    va_list args;
    va_start(args, message);
    vsnprintf(text, sizeof text, message ? message : "", args);
    va_end(args);
    (void)name;
    System *s = inner->system;
    if (!s->outer.logger) return;
    s->logging++; /* what the instance chose to log is passed on, whatever its status */
    say(s, status, category ? category : "", "%s: %s", inner->name, text);
    s->logging--;
}

/* ---- life cycle ---- */

static int set_values(System *s, Inner *inner) {
    const Nested *n = &s->fmus[inner->fmu];
    for (int v = 0; v < inner->n_values; v++) {
        const Value *value = &inner->values[v];
        const fmi2Boolean flag = value->integer ? fmi2True : fmi2False;
        const fmi2String string = value->text;
        const fmi2Status status =
            value->kind == 'r' ? n->set_real(inner->component, &value->vr, 1, &value->real)
            : value->kind == 'i' ? n->set_integer(inner->component, &value->vr, 1, &value->integer)
            : value->kind == 'b' ? n->set_boolean(inner->component, &value->vr, 1, &flag)
                                 : n->set_string(inner->component, &value->vr, 1, &string);
        if (status > fmi2Warning) {
            say(s, fmi2Error, "logStatusError", "%s: its value of reference %u was refused", inner->name, value->vr);
            return 0;
        }
    }
    return 1;
}

static int instantiate_inners(System *s) {
    for (int k = 0; k < s->n_instances; k++) {
        Inner *inner = &s->inners[k];
        const Nested *n = &s->fmus[inner->fmu];
        inner->callbacks.logger = inner_logger;
        inner->callbacks.allocateMemory = s->outer.allocateMemory;
        inner->callbacks.freeMemory = s->outer.freeMemory;
        inner->callbacks.componentEnvironment = inner;
        inner->component = n->instantiate(inner->name, fmi2CoSimulation, n->guid, n->resources_uri, &inner->callbacks,
                                          fmi2False, s->logging ? fmi2True : fmi2False);
        if (!inner->component) {
            say(s, fmi2Error, "logStatusError", "%s: its FMU did not instantiate", inner->name);
            return 0;
        }
        s->kernel_instances[k].component = inner->component;
        if (!set_values(s, inner)) return 0;
    }
    return 1;
}

static void free_system(System *s) {
    if (!s) return;
    kernel_release(&s->kernel);
    for (int k = 0; s->inners && k < s->n_instances; k++) {
        Inner *inner = &s->inners[k];
        if (inner->component) s->fmus[inner->fmu].free_instance(inner->component);
        for (int v = 0; inner->values && v < inner->n_values; v++) free(inner->values[v].text);
        free(inner->values);
        free(inner->name);
    }
    for (int f = 0; s->fmus && f < s->n_fmus; f++) {
        if (s->fmus[f].library) library_close(s->fmus[f].library);
        free(s->fmus[f].resources_uri);
        free(s->fmus[f].guid);
    }
    for (int i = 0; i < 8; i++) free(s->ints[i]);
    free(s->vrs[0]), free(s->vrs[1]);
    free(s->kernel.feed_values), free(s->kernel.feed_rates), free(s->feed_vrs);
    free(s->doubles), free(s->states), free(s->bonds), free(s->feeds), free(s->variables);
    free(s->inners), free(s->fmus), free(s->kernel_instances), free(s->run_step), free(s->run_count);
    free(s->resources), free(s->instance_name);
    free(s);
}

static char *copy(const char *text) {
    char *out = malloc(strlen(text) + 1);
    if (out) strcpy(out, text);
    return out;
}

fmi2Component fmi2Instantiate(fmi2String instanceName, fmi2Type fmuType, fmi2String fmuGUID,
                              fmi2String fmuResourceLocation, const fmi2CallbackFunctions *functions,
                              fmi2Boolean visible, fmi2Boolean loggingOn) {
    (void)visible;
    if (!functions || !functions->allocateMemory || !functions->freeMemory) return NULL;
    System *s = calloc(1, sizeof *s);
    if (!s) return NULL;
    s->outer = *functions;
    s->logging = loggingOn == fmi2True;
    s->instance_name = copy(instanceName ? instanceName : "");
    s->resources = location_folder(fmuResourceLocation, calloc);
    if (!s->instance_name || !s->resources) {
        say(s, fmi2Error, "logStatusError", "fmi2Instantiate: the resource location '%s' is no folder here",
            fmuResourceLocation ? fmuResourceLocation : "");
        free_system(s);
        return NULL;
    }
    if (fmuType != fmi2CoSimulation) {
        say(s, fmi2Error, "logStatusError", "fmi2Instantiate: this FMU is Co-Simulation only");
        free_system(s);
        return NULL;
    }
    char path[4096];
    snprintf(path, sizeof path, "%ssystem.txt", s->resources);
    char *description = read_file(path);
    const int found = description != NULL;
    long line = 0;
    const int read = found ? read_system(s, description, fmuGUID, &line) : READ_FAILED;
    free(description);
    if (read != READ_OK || !build_kernel(s)) {
        say(s, fmi2Error, "logStatusError", "fmi2Instantiate: %s%s %s", path, read == READ_FAILED && found ? "" : "",
            !found ? "cannot be read" : read == READ_FOREIGN ? "belongs to another FMU (its GUID)"
            : read == READ_NESTED ? "names a nested FMU that cannot be loaded" : "is malformed");
        if (found && read == READ_FAILED)
            say(s, fmi2Error, "logStatusError", "fmi2Instantiate: %s:%ld: not what a system description holds there",
                path, line);
        free_system(s);
        return NULL;
    }
    if (!instantiate_inners(s)) {
        free_system(s);
        return NULL;
    }
    s->phase = PHASE_INSTANTIATED;
    return s;
}

void fmi2FreeInstance(fmi2Component c) { free_system(c); }

static int allowed(System *s, const char *call, int ok) {
    static const char *phases[] = {"instantiated, not initialized", "in initialization mode", "stepping",
                                   "terminated", "failed"};
    if (!s) return 0;
    if (!ok) say(s, fmi2Error, "logStatusError", "%s is not allowed now: the FMU is %s", call, phases[s->phase]);
    return ok;
}

/* Calls `function` of every nested instance; fmi2Error (the failing instance named) on refusal. */
#define EVERY_INNER(s, call)                                                                       \
    do {                                                                                           \
        for (int k_ = 0; k_ < (s)->n_instances; k_++) {                                            \
            Inner *inner_ = &(s)->inners[k_];                                                      \
            if ((s)->fmus[inner_->fmu].call(inner_->component) > fmi2Warning) {                    \
                say(s, fmi2Error, "logStatusError", "%s: %s failed", inner_->name, #call);         \
                (s)->phase = PHASE_FAILED;                                                         \
                return fmi2Error;                                                                  \
            }                                                                                      \
        }                                                                                          \
    } while (0)

fmi2Status fmi2SetupExperiment(fmi2Component c, fmi2Boolean toleranceDefined, fmi2Real tolerance,
                               fmi2Real startTime, fmi2Boolean stopTimeDefined, fmi2Real stopTime) {
    System *s = c;
    if (!allowed(s, "fmi2SetupExperiment", s && s->phase == PHASE_INSTANTIATED)) return fmi2Error;
    s->start = startTime;
    for (int k = 0; k < s->n_instances; k++) {
        Inner *inner = &s->inners[k];
        if (s->fmus[inner->fmu].setup_experiment(inner->component, toleranceDefined, tolerance, startTime,
                                                 stopTimeDefined, stopTime) > fmi2Warning) {
            say(s, fmi2Error, "logStatusError", "%s: fmi2SetupExperiment failed", inner->name);
            return fmi2Error;
        }
    }
    return fmi2OK;
}

fmi2Status fmi2EnterInitializationMode(fmi2Component c) {
    System *s = c;
    if (!allowed(s, "fmi2EnterInitializationMode", s && s->phase == PHASE_INSTANTIATED)) return fmi2Error;
    EVERY_INNER(s, enter_initialization);
    s->phase = PHASE_INITIALIZATION;
    return fmi2OK;
}

static const char *call_name(int call) {
    static const char *names[] = {"?", "fmi2SetReal", "fmi2SetRealInputDerivatives", "fmi2DoStep", "fmi2GetReal",
                                  "fmi2GetRealOutputDerivatives", "fmi2GetFMUstate", "fmi2SetFMUstate",
                                  "fmi2FreeFMUstate"};
    return call >= 1 && call <= 8 ? names[call] : names[0];
}

static fmi2Status kernel_failed(System *s) {
    const int k = s->kernel.failed_instance;
    say(s, fmi2Error, "logStatusError", "%s: %s failed at t = %.9g s", k >= 0 ? s->inners[k].name : "?",
        call_name(s->kernel.failed_call), k >= 0 ? s->kernel.instance_time[k] : NAN);
    s->phase = PHASE_FAILED;
    return fmi2Error;
}

fmi2Status fmi2ExitInitializationMode(fmi2Component c) {
    System *s = c;
    if (!allowed(s, "fmi2ExitInitializationMode", s && s->phase == PHASE_INITIALIZATION)) return fmi2Error;
    EVERY_INNER(s, exit_initialization);
    for (int k = 0; k < s->n_instances; k++) s->kernel.instance_time[k] = s->start;
    s->run = 0;
    s->run_left = s->n_runs > 0 ? s->run_count[0] : 0;
    s->grid_step = 0.0;
    if (!kernel_initialize(&s->kernel, s->start, s->sweeps, s->zero_start)) return kernel_failed(s);
    s->phase = PHASE_STEPPING;
    return fmi2OK;
}

/* The plan's next step: its runs in turn, then the regular step. */
static double plan_step(System *s) {
    while (s->run < s->n_runs && s->run_left == 0)
        if (++s->run < s->n_runs) s->run_left = s->run_count[s->run];
    if (s->run < s->n_runs) {
        s->run_left--;
        return s->run_step[s->run];
    }
    return s->regular_step;
}

fmi2Status fmi2DoStep(fmi2Component c, fmi2Real currentCommunicationPoint, fmi2Real communicationStepSize,
                      fmi2Boolean noSetFMUStatePriorToCurrentPoint) {
    System *s = c;
    (void)noSetFMUStatePriorToCurrentPoint;
    if (!allowed(s, "fmi2DoStep", s && s->phase == PHASE_STEPPING)) return fmi2Error;
    const double t_end = currentCommunicationPoint + communicationStepSize;
    double now = s->kernel.instance_time[s->clock];
    const double slack = 1e-9 * fmax(communicationStepSize, fabs(now));
    if (!(communicationStepSize > 0.0) || !isfinite(t_end) || fabs(currentCommunicationPoint - now) > slack + 1e-12) {
        say(s, fmi2Error, "logStatusError",
            "fmi2DoStep: a step of %.9g s from t = %.9g s, where the system is at t = %.9g s (steps go forward from "
            "where the last one ended)", communicationStepSize, currentCommunicationPoint, now);
        return fmi2Error;
    }
    double residual, bond_energy[2 * 64];
    double *bonds = s->kernel.n_bonds <= 64 ? bond_energy : calloc(2 * (size_t)s->kernel.n_bonds, sizeof(double));
    if (!bonds) return fmi2Error;
    fmi2Status status = fmi2OK;
    while (status == fmi2OK) {
        now = s->kernel.instance_time[s->clock];
        if (s->grid_step == 0.0) {
            s->grid_step = plan_step(s);
            s->grid_start = now;
            s->grid_end = now + s->grid_step;
        }
        const double tolerance = 1e-6 * s->grid_step;
        if (now >= t_end - tolerance) break;
        double h;
        int whole = s->grid_end <= t_end + tolerance;
        if (whole) /* the plan's step, or what is left of it, ends within this communication step */
            h = now == s->grid_start ? s->grid_step : s->grid_end - now;
        else
            h = t_end - now;
        if (kernel_run_fixed(&s->kernel, NULL, s->clock, h, 1, s->row, &residual, bonds, NULL, NULL) != 1)
            status = kernel_failed(s);
        if (whole) s->grid_step = 0.0;
    }
    if (bonds != bond_energy) free(bonds);
    return status;
}

fmi2Status fmi2Terminate(fmi2Component c) {
    System *s = c;
    if (!allowed(s, "fmi2Terminate", s && (s->phase == PHASE_STEPPING || s->phase == PHASE_FAILED))) return fmi2Error;
    EVERY_INNER(s, terminate);
    s->phase = PHASE_TERMINATED;
    return fmi2OK;
}

fmi2Status fmi2Reset(fmi2Component c) {
    System *s = c;
    if (!allowed(s, "fmi2Reset", s != NULL)) return fmi2Error;
    kernel_release(&s->kernel);
    EVERY_INNER(s, reset);
    for (int k = 0; k < s->n_instances; k++)
        if (!set_values(s, &s->inners[k])) {
            s->phase = PHASE_FAILED;
            return fmi2Error;
        }
    s->phase = PHASE_INSTANTIATED;
    return fmi2OK;
}

/* ---- values: passed on to the instance whose they are ---- */

static const Variable *variable(System *s, fmi2ValueReference vr, char kind, const char *call) {
    if (vr >= (fmi2ValueReference)s->n_variables || s->variables[vr].kind != kind) {
        say(s, fmi2Error, "logStatusError", "%s: no variable of this type has value reference %u", call, vr);
        return NULL;
    }
    return &s->variables[vr];
}

#define PASS_ON(kind, call, field, type)                                                           \
    System *s = c;                                                                                 \
    if (!allowed(s, call, s && s->phase != PHASE_TERMINATED) || (nvr > 0 && (!vr || !value)))       \
        return fmi2Error;                                                                          \
    fmi2Status worst = fmi2OK;                                                                     \
    for (size_t i = 0; i < nvr; i++) {                                                             \
        const Variable *v = variable(s, vr[i], kind, call);                                        \
        if (!v) return fmi2Error;                                                                  \
        const Inner *inner = &s->inners[v->instance];                                              \
        const fmi2Status status = s->fmus[inner->fmu].field(inner->component, &v->vr, 1, (type)&value[i]); \
        if (status > worst) worst = status;                                                        \
        if (status > fmi2Warning) return status;                                                   \
    }                                                                                              \
    return worst;

fmi2Status fmi2GetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Real value[]) {
    PASS_ON('r', "fmi2GetReal", get_real, fmi2Real *)
}
fmi2Status fmi2GetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Integer value[]) {
    PASS_ON('i', "fmi2GetInteger", get_integer, fmi2Integer *)
}
fmi2Status fmi2GetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2Boolean value[]) {
    PASS_ON('b', "fmi2GetBoolean", get_boolean, fmi2Boolean *)
}
fmi2Status fmi2GetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, fmi2String value[]) {
    PASS_ON('s', "fmi2GetString", get_string, fmi2String *)
}
fmi2Status fmi2SetReal(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Real value[]) {
    PASS_ON('r', "fmi2SetReal", set_real, const fmi2Real *)
}
fmi2Status fmi2SetInteger(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Integer value[]) {
    PASS_ON('i', "fmi2SetInteger", set_integer, const fmi2Integer *)
}
fmi2Status fmi2SetBoolean(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2Boolean value[]) {
    PASS_ON('b', "fmi2SetBoolean", set_boolean, const fmi2Boolean *)
}
fmi2Status fmi2SetString(fmi2Component c, const fmi2ValueReference vr[], size_t nvr, const fmi2String value[]) {
    PASS_ON('s', "fmi2SetString", set_string, const fmi2String *)
}

/* ---- the rest of the API ---- */

const char *fmi2GetTypesPlatform(void) { return fmi2TypesPlatform; }
const char *fmi2GetVersion(void) { return fmi2Version; }

fmi2Status fmi2SetDebugLogging(fmi2Component c, fmi2Boolean loggingOn, size_t nCategories,
                               const fmi2String categories[]) {
    System *s = c;
    (void)nCategories, (void)categories;
    if (!s) return fmi2Error;
    s->logging = loggingOn == fmi2True;
    return fmi2OK;
}

static fmi2Status unsupported(fmi2Component c, const char *call) {
    System *s = c;
    if (s) say(s, fmi2Error, "logStatusError", "%s: not supported by this FMU (see its modelDescription.xml)", call);
    return fmi2Error;
}

fmi2Status fmi2GetFMUstate(fmi2Component c, fmi2FMUstate *state) {
    (void)state;
    return unsupported(c, "fmi2GetFMUstate");
}
fmi2Status fmi2SetFMUstate(fmi2Component c, fmi2FMUstate state) {
    (void)state;
    return unsupported(c, "fmi2SetFMUstate");
}
fmi2Status fmi2FreeFMUstate(fmi2Component c, fmi2FMUstate *state) {
    (void)state;
    return unsupported(c, "fmi2FreeFMUstate");
}
fmi2Status fmi2SerializedFMUstateSize(fmi2Component c, fmi2FMUstate state, size_t *size) {
    (void)state, (void)size;
    return unsupported(c, "fmi2SerializedFMUstateSize");
}
fmi2Status fmi2SerializeFMUstate(fmi2Component c, fmi2FMUstate state, fmi2Byte bytes[], size_t size) {
    (void)state, (void)bytes, (void)size;
    return unsupported(c, "fmi2SerializeFMUstate");
}
fmi2Status fmi2DeSerializeFMUstate(fmi2Component c, const fmi2Byte bytes[], size_t size, fmi2FMUstate *state) {
    (void)bytes, (void)size, (void)state;
    return unsupported(c, "fmi2DeSerializeFMUstate");
}
fmi2Status fmi2GetDirectionalDerivative(fmi2Component c, const fmi2ValueReference unknowns[], size_t n_unknowns,
                                        const fmi2ValueReference knowns[], size_t n_knowns, const fmi2Real seed[],
                                        fmi2Real sensitivity[]) {
    (void)unknowns, (void)n_unknowns, (void)knowns, (void)n_knowns, (void)seed, (void)sensitivity;
    return unsupported(c, "fmi2GetDirectionalDerivative");
}
fmi2Status fmi2SetRealInputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                       const fmi2Integer order[], const fmi2Real value[]) {
    (void)vr, (void)nvr, (void)order, (void)value;
    return unsupported(c, "fmi2SetRealInputDerivatives");
}
fmi2Status fmi2GetRealOutputDerivatives(fmi2Component c, const fmi2ValueReference vr[], size_t nvr,
                                        const fmi2Integer order[], fmi2Real value[]) {
    (void)vr, (void)nvr, (void)order, (void)value;
    return unsupported(c, "fmi2GetRealOutputDerivatives");
}
fmi2Status fmi2CancelStep(fmi2Component c) { return unsupported(c, "fmi2CancelStep"); }
fmi2Status fmi2GetStatus(fmi2Component c, const fmi2StatusKind kind, fmi2Status *value) {
    (void)kind, (void)value;
    return unsupported(c, "fmi2GetStatus");
}
fmi2Status fmi2GetRealStatus(fmi2Component c, const fmi2StatusKind kind, fmi2Real *value) {
    (void)kind, (void)value;
    return unsupported(c, "fmi2GetRealStatus");
}
fmi2Status fmi2GetIntegerStatus(fmi2Component c, const fmi2StatusKind kind, fmi2Integer *value) {
    (void)kind, (void)value;
    return unsupported(c, "fmi2GetIntegerStatus");
}
fmi2Status fmi2GetBooleanStatus(fmi2Component c, const fmi2StatusKind kind, fmi2Boolean *value) {
    (void)kind, (void)value;
    return unsupported(c, "fmi2GetBooleanStatus");
}
fmi2Status fmi2GetStringStatus(fmi2Component c, const fmi2StatusKind kind, fmi2String *value) {
    (void)kind, (void)value;
    return unsupported(c, "fmi2GetStringStatus");
}
