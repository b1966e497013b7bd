/* A whole system as one Co-Simulation FMU (FMI 2.0 or 3.0): the FMUs of the system nested in its
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
 * that no connection feeds, its parameters, the recorded outputs); a call on it is passed on.
 *
 * This file is the system's life cycle, whatever the FMI version; system_fmi2.c and system_fmi3.c
 * offer it as FMI 2.0 and as FMI 3.0 (the nested FMUs are FMI 2.0 either way). */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "location.h"
#include "system.h"

enum { OK = 0, WARNING = 1, ERROR = 3 };

/* ---- logging ---- */

void say(System *s, fmi2Status status, const char *category, const char *format, ...) {
    if (!s->log || (status == fmi2OK && !s->logging)) return;
    char text[2048], escaped[4200];
    va_list args;
    va_start(args, format);
    vsnprintf(text, sizeof text, format, args);
    va_end(args);
    size_t k = 0; /* an FMI 2.0 importer's logger formats the message again: a '%' in it is doubled */
    for (const char *c = text; *c && k + 2 < sizeof escaped; c++) {
        if (*c == '%' && s->api[3] == '2') escaped[k++] = '%';
        escaped[k++] = *c;
    }
    escaped[k] = '\0';
    s->log(s->environment, s->instance_name, (int)status, category, escaped);
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
    s->logging++; /* what the instance chose to log is passed on, whatever its status */
    say(s, status, category ? category : "", "%s: %s", inner->name, text);
    s->logging--;
}

/* ---- instantiation ---- */

/* Sets an instance's values, each by the call of its kind; 0 (the instance logged why) on refusal. */
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
        inner->callbacks.allocateMemory = calloc;
        inner->callbacks.freeMemory = free;
        inner->callbacks.componentEnvironment = inner;
        inner->component = n->instantiate(inner->name, s->model_exchange ? fmi2ModelExchange : fmi2CoSimulation, n->guid,
                                          n->resources_uri, &inner->callbacks, fmi2False,
                                          s->logging ? fmi2True : fmi2False);
        if (!inner->component) {
            say(s, fmi2Error, "logStatusError", "%s: its FMU did not instantiate", inner->name);
            return 0;
        }
        s->kernel_instances[k].component = inner->component;
        if (!set_values(s, inner)) return 0;
    }
    return 1;
}

void system_free(System *s) {
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

System *system_new(const char *api, const char *instance, const char *token, const char *location, int logging,
                   int model_exchange, void (*log)(void *, const char *, int, const char *, const char *),
                   void *environment) {
    System *s = calloc(1, sizeof *s);
    if (!s) return NULL;
    s->api = api, s->log = log, s->environment = environment, s->logging = logging;
    s->model_exchange = model_exchange;
    s->instance_name = copy(instance ? instance : "");
    s->resources = location_folder(location, calloc);
    if (!s->instance_name || !s->resources) {
        say(s, fmi2Error, "logStatusError", "%sInstantiate: the resource location '%s' is no folder here", api,
            location ? location : "");
        system_free(s);
        return NULL;
    }
    char path[4096];
    snprintf(path, sizeof path, "%ssystem.txt", s->resources);
    char *description = read_file(path);
    const int found = description != NULL;
    long line = 0;
    const int read = found ? read_system(s, description, token, &line) : READ_FAILED;
    free(description);
    if (read != READ_OK || !build_kernel(s)) {
        if (found && read == READ_FAILED)
            say(s, fmi2Error, "logStatusError", "%sInstantiate: %s:%ld: not what a system description holds there",
                api, path, line);
        else
            say(s, fmi2Error, "logStatusError", "%sInstantiate: %s %s", api, path,
                !found ? "cannot be read" : read == READ_FOREIGN ? "belongs to another FMU (its guid)"
                : read == READ_NESTED ? "names a nested FMU that cannot be loaded" : "cannot be set up");
        system_free(s);
        return NULL;
    }
    if (model_exchange && !s->offers_model_exchange) {
        say(s, fmi2Error, "logStatusError", "%sInstantiate: this FMU is Co-Simulation only (its modelDescription.xml)",
            api);
        system_free(s);
        return NULL;
    }
    if (!model_exchange && !s->offers_co_simulation) {
        say(s, fmi2Error, "logStatusError", "%sInstantiate: this FMU is Model Exchange only (its modelDescription.xml)",
            api);
        system_free(s);
        return NULL;
    }
    if (!instantiate_inners(s)) {
        system_free(s);
        return NULL;
    }
    s->phase = PHASE_INSTANTIATED;
    return s;
}

/* ---- the life cycle ---- */

int system_allowed(System *s, const char *call, int ok) {
    static const char *phases[] = {"instantiated, not initialized", "in initialization mode", "stepping",
                                   "terminated", "failed", "in error (a call failed before it ran: reset or free it)"};
    if (!s) return 0;
    if (!ok && s->refusal)
        say(s, fmi2Error, "logStatusError", "%s is not allowed: %s", call, s->refusal);
    else if (!ok)
        say(s, fmi2Error, "logStatusError", "%s is not allowed now: the FMU is %s", call, phases[s->phase]);
    s->refusal = NULL;
    return ok;
}

/* Calls `function` of every nested instance; ERROR (the failing instance named) on refusal. */
#define EVERY_INNER(s, call)                                                                       \
    do {                                                                                           \
        for (int k_ = 0; k_ < (s)->n_instances; k_++) {                                            \
            Inner *inner_ = &(s)->inners[k_];                                                      \
            if ((s)->fmus[inner_->fmu].call(inner_->component) > fmi2Warning) {                    \
                say(s, fmi2Error, "logStatusError", "%s: %s failed", inner_->name, #call);         \
                system_failed(s);                                                                  \
                return ERROR;                                                                      \
            }                                                                                      \
        }                                                                                          \
    } while (0)

int system_values_allowed(const System *s, int setting) {
    return setting ? s->phase == PHASE_INSTANTIATED || s->phase == PHASE_INITIALIZATION || s->phase == PHASE_STEPPING
                   : s->phase != PHASE_INSTANTIATED;
}

int system_interface_is(System *s, int model_exchange) {
    if (s->model_exchange != model_exchange)
        s->refusal = s->model_exchange ? "this instance is Model Exchange, the call Co-Simulation's"
                                       : "this instance is Co-Simulation, the call Model Exchange's";
    return s->model_exchange == model_exchange;
}

int system_mode_is(System *s, int continuous_time) {
    const int ok = s->phase != PHASE_STEPPING || s->continuous_time_mode == continuous_time;
    if (!ok)
        s->refusal = s->continuous_time_mode ? "the instance is in Continuous-Time Mode (EnterEventMode first)"
                                             : "the instance is in Event Mode (EnterContinuousTimeMode first)";
    return ok;
}

int system_setup(System *s, int tolerance_defined, double tolerance, double start, int stop_defined, double stop) {
    s->start = start;
    s->me_time = start;
    for (int k = 0; k < s->n_instances; k++) {
        Inner *inner = &s->inners[k];
        if (s->fmus[inner->fmu].setup_experiment(inner->component, tolerance_defined ? fmi2True : fmi2False, tolerance,
                                                 start, stop_defined ? fmi2True : fmi2False, stop) > fmi2Warning) {
            say(s, fmi2Error, "logStatusError", "%s: fmi2SetupExperiment failed", inner->name);
            return ERROR;
        }
    }
    return OK;
}

int system_enter(System *s) {
    EVERY_INNER(s, enter_initialization);
    s->phase = PHASE_INITIALIZATION;
    s->stale = 1;
    return OK;
}

static const char *call_name(int call) {
    static const char *names[] = {"?", "fmi2SetReal", "fmi2SetRealInputDerivatives", "fmi2DoStep", "fmi2GetReal",
                                  "fmi2GetRealOutputDerivatives", "fmi2GetFMUstate", "fmi2SetFMUstate",
                                  "fmi2FreeFMUstate"};
    return call >= 1 && call <= 8 ? names[call] : names[0];
}

static int kernel_failed(System *s) {
    const int k = s->kernel.failed_instance;
    say(s, fmi2Error, "logStatusError", "%s: %s failed at t = %.9g s", k >= 0 ? s->inners[k].name : "?",
        call_name(s->kernel.failed_call), k >= 0 ? s->kernel.instance_time[k] : NAN);
    system_failed(s);
    return ERROR;
}

void system_failed(System *s) {
    s->phase = s->phase == PHASE_STEPPING || s->phase == PHASE_FAILED ? PHASE_FAILED : PHASE_ERROR;
}

int system_exit(System *s) {
    if (s->model_exchange) { /* the connections carried into the initial values; then Event Mode */
        if (system_me_carry(s) != OK) return ERROR;
        EVERY_INNER(s, exit_initialization);
        s->continuous_time_mode = 0;
        s->stale = 1;
        s->phase = PHASE_STEPPING;
        return OK;
    }
    EVERY_INNER(s, exit_initialization);
    for (int k = 0; k < s->n_instances; k++) s->kernel.instance_time[k] = s->start;
    s->run = 0;
    s->run_left = s->n_runs > 0 ? s->run_count[0] : 0;
    s->grid_step = 0.0;
    if (!kernel_initialize(&s->kernel, s->start, s->sweeps, s->zero_start)) return kernel_failed(s);
    s->phase = PHASE_STEPPING;
    return OK;
}

double system_time(const System *s) { return s->model_exchange ? s->me_time : s->kernel.instance_time[s->clock]; }

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

/* At most this many of the system's steps in one communication step, as the models bound theirs
 * (ODE_MAX_STEPS, fmu/common/ode.h): a step asking for more is refused before it starts, not left
 * to run for as long as it would take. */
enum { MAX_STEPS_PER_COMMUNICATION_STEP = 200000 };

/* How many of the system's steps a communication step of h takes at most: every step left in the
 * plan's runs, and the regular step's over all of h (and the two partial steps at its ends). */
static double steps_at_most(const System *s, double h) {
    double steps = 2.0 + ceil(h / s->regular_step);
    if (s->run < s->n_runs) steps += s->run_left;
    for (int run = s->run + 1; run < s->n_runs; run++) steps += s->run_count[run];
    return steps;
}

int system_do_step(System *s, double t, double h_communication) {
    const double t_end = t + h_communication;
    double now = system_time(s);
    const double slack = 1e-9 * fmax(h_communication, fabs(now));
    if (!(h_communication > 0.0) || !isfinite(t_end) || fabs(t - now) > slack + 1e-12) {
        say(s, fmi2Error, "logStatusError",
            "%sDoStep: a step of %.9g s from t = %.9g s, where the system is at t = %.9g s (steps go forward from "
            "where the last one ended)", s->api, h_communication, t, now);
        return ERROR;
    }
    if (steps_at_most(s, h_communication) > MAX_STEPS_PER_COMMUNICATION_STEP) {
        say(s, fmi2Error, "logStatusError",
            "%sDoStep: a step of %.9g s would take more than %d of the system's steps (%.9g s each): give it in "
            "shorter communication steps", s->api, h_communication, MAX_STEPS_PER_COMMUNICATION_STEP, s->regular_step);
        return ERROR;
    }
    double residual, bond_energy[2 * 64];
    double *bonds = s->kernel.n_bonds <= 64 ? bond_energy : calloc(2 * (size_t)s->kernel.n_bonds, sizeof(double));
    if (!bonds) return ERROR;
    int status = OK;
    while (status == OK) {
        now = system_time(s);
        if (s->grid_step == 0.0) {
            s->grid_step = plan_step(s);
            s->grid_start = now;
            s->grid_end = now + s->grid_step;
        }
        const double tolerance = 1e-6 * s->grid_step;
        if (now >= t_end - tolerance) break;
        double h;
        const int whole = s->grid_end <= t_end + tolerance;
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

int system_terminate(System *s) {
    EVERY_INNER(s, terminate);
    s->phase = PHASE_TERMINATED;
    return OK;
}

int system_reset(System *s) {
    kernel_release(&s->kernel);
    EVERY_INNER(s, reset);
    for (int k = 0; k < s->n_instances; k++)
        if (!set_values(s, &s->inners[k])) {
            system_failed(s);
            return ERROR;
        }
    s->phase = PHASE_INSTANTIATED;
    s->continuous_time_mode = 0;
    return OK;
}

/* ---- values: passed on to the instance whose they are ---- */

static const Variable *variable(System *s, unsigned vr, char kind, const char *call) {
    if (vr >= (unsigned)s->n_variables || s->variables[vr].kind != kind) {
        say(s, fmi2Error, "logStatusError", "%s: no variable of this type has value reference %u", call, vr);
        return NULL;
    }
    return &s->variables[vr];
}

int system_get(System *s, const char *call, char kind, unsigned vr, void *value) {
    const Variable *v = variable(s, vr, kind, call);
    if (!v) return ERROR;
    if (s->model_exchange && (s->phase == PHASE_INITIALIZATION || s->phase == PHASE_STEPPING) &&
        system_me_carry(s) != OK) /* an output of the present time, states and inputs */
        return ERROR;
    const Inner *inner = &s->inners[v->instance];
    const Nested *n = &s->fmus[inner->fmu];
    return kind == 'r' ? n->get_real(inner->component, &v->vr, 1, value)
         : kind == 'i' ? n->get_integer(inner->component, &v->vr, 1, value)
         : kind == 'b' ? n->get_boolean(inner->component, &v->vr, 1, value)
                       : n->get_string(inner->component, &v->vr, 1, value);
}

int system_set(System *s, const char *call, char kind, unsigned vr, const void *value) {
    const Variable *v = variable(s, vr, kind, call);
    if (!v) return ERROR;
    if (!v->settable) { /* the nested variable may be an input (a connection's target): the system's, not the importer's */
        say(s, fmi2Error, "logStatusError", "%s: value reference %u is an output of this FMU (see its "
            "modelDescription.xml): it cannot be set", call, vr);
        return ERROR;
    }
    s->stale = 1;
    const Inner *inner = &s->inners[v->instance];
    const Nested *n = &s->fmus[inner->fmu];
    return kind == 'r' ? n->set_real(inner->component, &v->vr, 1, value)
         : kind == 'i' ? n->set_integer(inner->component, &v->vr, 1, value)
         : kind == 'b' ? n->set_boolean(inner->component, &v->vr, 1, value)
                       : n->set_string(inner->component, &v->vr, 1, value);
}

int system_unsupported(System *s, const char *call) {
    if (s) say(s, fmi2Error, "logStatusError", "%s: not supported by this FMU (see its modelDescription.xml)", call);
    return ERROR;
}
