/* The system FMU's parts: system_fmu.c, the system's life cycle whatever the FMI version it is
 * offered in (system_fmi2.c and system_fmi3.c: the FMI 2.0 and FMI 3.0 layers over it);
 * system_read.c, its description read, its nested FMI 2.0 FMUs loaded and the step kernel set up
 * over them. Statuses are FMI's (0 OK, 1 warning, 2 discard, 3 error, 4 fatal: the same in both). */
#ifndef COSIM_SYSTEM_H
#define COSIM_SYSTEM_H

#include "fmi2FunctionTypes.h"
#include "kernel.h"

/* FAILED: a call failed while it ran (it may still terminate); ERROR: one failed before it ran (FMI's
 * error state: its values may be read, then it is reset or freed) */
enum { PHASE_INSTANTIATED, PHASE_INITIALIZATION, PHASE_STEPPING, PHASE_TERMINATED, PHASE_FAILED, PHASE_ERROR };

typedef struct { /* a nested FMU's binary and its functions */
    void *library;
    char *resources_uri; /* its resources/ as a file URI */
    char *guid;
    fmi2InstantiateTYPE *instantiate;
    fmi2FreeInstanceTYPE *free_instance;
    fmi2SetupExperimentTYPE *setup_experiment;
    fmi2EnterInitializationModeTYPE *enter_initialization;
    fmi2ExitInitializationModeTYPE *exit_initialization;
    fmi2TerminateTYPE *terminate;
    fmi2ResetTYPE *reset;
    fmi2SetRealTYPE *set_real;
    fmi2SetIntegerTYPE *set_integer;
    fmi2SetBooleanTYPE *set_boolean;
    fmi2SetStringTYPE *set_string;
    fmi2GetRealTYPE *get_real;
    fmi2GetIntegerTYPE *get_integer;
    fmi2GetBooleanTYPE *get_boolean;
    fmi2GetStringTYPE *get_string;
    void *set_input_derivatives, *get_output_derivatives, *do_step, *get_state, *set_state, *free_state;
    /* Model Exchange (bound where the system is offered as Model Exchange) */
    fmi2SetTimeTYPE *set_time;
    fmi2SetContinuousStatesTYPE *set_states;
    fmi2GetContinuousStatesTYPE *get_states;
    fmi2GetNominalsOfContinuousStatesTYPE *get_nominals;
    fmi2GetDerivativesTYPE *get_derivatives;
    fmi2EnterEventModeTYPE *enter_event_mode;
    fmi2NewDiscreteStatesTYPE *new_discrete_states;
    fmi2EnterContinuousTimeModeTYPE *enter_continuous_time_mode;
    fmi2CompletedIntegratorStepTYPE *completed_integrator_step;
} Nested;

typedef struct { /* a value a component is given at instantiation */
    char kind;   /* r, i, b, s */
    unsigned vr;
    double real;
    int integer;
    char *text;
} Value;

typedef struct System System;

typedef struct { /* one nested instance */
    System *system;
    char *name;
    int fmu;
    fmi2Component component;
    fmi2CallbackFunctions callbacks;
    int n_values;
    Value *values;
    int n_states, first_state; /* its continuous states in the system's (Model Exchange) */
} Inner;

typedef struct { /* a variable of the outer FMU: one of an instance's */
    int instance;
    char kind;
    unsigned vr;
    int settable; /* an input or a parameter (its instance says when); not an output or a local */
} Variable;

struct System {
    void (*log)(void *environment, const char *instance, int status, const char *category, const char *message);
    void *environment;                 /* the importer's, passed back to log */
    const char *api;                   /* "fmi2" or "fmi3": how the calls are named in messages */
    char *instance_name, *resources;
    int logging, phase;
    int offers_co_simulation, offers_model_exchange; /* the interfaces its modelDescription.xml declares */
    int model_exchange;                /* this instance is Model Exchange */
    int continuous_time_mode;          /* Model Exchange after initialization: 1 Continuous-Time Mode, 0 Event Mode */
    int stale;                         /* Model Exchange: time, states or values changed since the connections were carried */
    int n_states;                      /* every instance's continuous states, one after another */
    double me_time;                    /* Model Exchange: the time last set */
    const char *refusal;               /* why the call being checked is refused (NULL: its phase) */
    /* the description */
    double start, regular_step;
    int n_runs, run, run_left; /* the step plan: runs of equal steps, the current one and its steps left */
    double *run_step;
    int *run_count;
    double grid_step, grid_start, grid_end; /* the plan's step under way (0: none) */
    int clock, sweeps, zero_start;
    int n_fmus, n_instances, n_variables;
    Nested *fmus;
    Inner *inners;
    Variable *variables;
    /* the kernel and its arrays */
    Kernel kernel;
    KernelInstance *kernel_instances;
    KernelBond *bonds;
    KernelFeed *feeds;
    int *ints[8];                      /* sequence, stage_end, feed_indices, stepped, order_one, order_two, sources, indices */
    unsigned *vrs[2];                  /* outputs and inputs of every instance, one after another */
    double *doubles;                   /* every double array of the kernel, one allocation */
    void **states;
    unsigned *feed_vrs;
    double row[1];
};

/* Logs through the importer's logger: errors and warnings always, the rest where logging is on. */
void say(System *s, fmi2Status status, const char *category, const char *format, ...);

enum { READ_OK, READ_FAILED, READ_FOREIGN, READ_NESTED };

/* The system from resources/system.txt's text (changed in place): READ_OK, READ_FOREIGN where it is
 * another FMU's (guid), READ_NESTED where a nested FMU's binary cannot be loaded (logged),
 * READ_FAILED where it is malformed, *line then where. */
int read_system(System *s, char *description, const char *guid, long *line);

/* The whole file at path (NUL-terminated, freed by the caller), NULL where it cannot be read. */
char *read_file(const char *path);

/* The step kernel's struct over arrays of the system's own, the instances' functions bound. */
int build_kernel(System *s);

/* Lets a nested FMU's binary go. */
void library_close(void *library);

/* ---- the life cycle (system_fmu.c), called by the FMI layers ---- */

/* The system of the FMU whose resources `location` names (FMI 2.0's URI or FMI 3.0's path), its
 * description's guid `token` (NULL: not checked), its nested instances instantiated with their
 * values, as Model Exchange where model_exchange; NULL (the reason logged) where it cannot be. */
System *system_new(const char *api, const char *instance, const char *token, const char *location, int logging,
                   int model_exchange, void (*log)(void *, const char *, int, const char *, const char *), void *environment);
void system_free(System *s);
/* 1 if `call` may be made now (ok), else 0 with the reason logged. */
int system_allowed(System *s, const char *call, int ok);
/* 1 if the instance is Model Exchange (model_exchange 1) or Co-Simulation (0) as the call needs; 1
 * if a Model Exchange instance after initialization is in Continuous-Time Mode (continuous_time 1)
 * or Event Mode (0) as the call needs (FMI's state machine); else 0, the reason kept for
 * system_allowed's refusal. */
int system_interface_is(System *s, int model_exchange);
int system_mode_is(System *s, int continuous_time);
/* 1 if values may be got (setting 0: from initialization on, a failed or terminated instance too)
 * or set (setting 1: instantiated, initializing or running) in the instance's phase, as FMI's
 * state machines have it (the nested instance then says which variable when). */
int system_values_allowed(const System *s, int setting);
/* A nested call failed: the system FAILED if it was running, else in ERROR. */
void system_failed(System *s);
int system_setup(System *s, int tolerance_defined, double tolerance, double start, int stop_defined, double stop);
int system_enter(System *s);
int system_exit(System *s);
int system_do_step(System *s, double t, double h);
int system_terminate(System *s);
int system_reset(System *s);
double system_time(const System *s);
/* A variable's value got or set through its instance: kind r (double), i (int), b (int, FMI 2.0's
 * Boolean), s (const char *); `call` names the importer's call in a refusal. */
int system_get(System *s, const char *call, char kind, unsigned vr, void *value);
int system_set(System *s, const char *call, char kind, unsigned vr, const void *value);
/* ---- Model Exchange (system_me.c): the instances' states end to end, the connections carried at
 * each evaluation ---- */

/* Every connection's output to its input, sweep after sweep in the coupling's order until no input
 * changes, where time, states or values changed since the last time (s->stale). */
int system_me_carry(System *s);
int system_me_set_time(System *s, double time);
int system_me_set_states(System *s, const double x[], size_t n);
int system_me_get_states(System *s, double x[], size_t n);
int system_me_get_nominals(System *s, double nominals[], size_t n);
int system_me_get_derivatives(System *s, double derivatives[], size_t n);
int system_me_enter_event_mode(System *s);
/* Every instance's discrete states updated (its own iteration through), the connections carried;
 * *next the earliest next time event of any (inf: none). */
int system_me_new_discrete_states(System *s, int *terminate, int *states_changed, double *next);
int system_me_enter_continuous_time_mode(System *s);
int system_me_completed_integrator_step(System *s, int *enter_event_mode, int *terminate);

/* Where the importer's call is not offered: fmi2Error/fmi3Error with the reason logged. */
int system_unsupported(System *s, const char *call);

#endif
