/* The generic FMI 2.0 Co-Simulation layer every model shares (fmi2_layer.c), and the few hooks
 * a model implements in its model.c.
 *
 * Everything that defines where a simulation is lives in one plain struct, FmuSnapshot: variable
 * values, the internal ODE state, the solver's memory and the model's own discrete state. FMU
 * state get/set and serialization copy that struct, so a restored instance continues bit for bit.
 */
#ifndef FMU_COMMON_H
#define FMU_COMMON_H

#include "fmi2Functions.h"
#include "fmu_table.h"
#include "ode.h"

typedef enum {
    PHASE_INSTANTIATED = 1 << 0,
    PHASE_INITIALIZATION = 1 << 1,
    PHASE_STEP_COMPLETE = 1 << 2,
    PHASE_STEP_FAILED = 1 << 3,
    PHASE_TERMINATED = 1 << 4,
    PHASE_ERROR = 1 << 5
} FmuPhase;

typedef struct {
    int phase;                             /* FmuPhase */
    int continuous_time_mode;              /* Model Exchange after initialization: 1 Continuous-Time Mode, 0 Event
                                            * Mode (part of an FMU state: a state restores its mode) */
    double time;                           /* communication point reached */
    double input_time;                     /* time at which the inputs were last set */
    double stop_time;                      /* fmi2SetupExperiment's stop time, if defined */
    int stop_time_defined;
    ModelVariables v;                      /* every variable of the table */
    double input_derivative[VR_COUNT][2];  /* fmi2SetRealInputDerivatives, orders 1 and 2 */
    int input_derivative_given[VR_COUNT];  /* highest order given (0: none); cleared after each step */
    /* The FMU's own extrapolation (fmi.extrapolate_inputs): each input at the last step's start. */
    double input_previous[VR_COUNT];
    double input_previous_time;
    int input_previous_valid;              /* 0: no step yet since initialization */
    double x[MODEL_N_STATES > 0 ? MODEL_N_STATES : 1]; /* internal ODE state */
    OdeSolver solver;
    ModelInternal internal;                /* the model's own discrete state */
} FmuSnapshot;

typedef struct FmuInstance {
    FmuSnapshot s;
    char *instance_name;
    fmi2CallbackFunctions callbacks;
    int logging_on;
    int log_events, log_warnings, log_errors, log_all; /* categories */
    int warned;                            /* a warning was raised in the current fmi2DoStep */
    int outputs_stale;                     /* inputs or parameters changed since outputs were computed */
    /* Read-only data a model derives from its fixed parameters (e.g. a table read from a file):
     * kept outside the snapshot, so FMU states stay small; released with fmu_set_model_data. */
    void *model_data;
    void (*free_model_data)(struct FmuInstance *fmu, void *data);
    int model_exchange;                    /* instantiated as fmi2ModelExchange (fmi2_me.c) */
    int lazy_outputs_stale;                /* MODEL_LAZY_OUTPUTS: not computed since the outputs were */
    int n_real_outputs;                    /* the Real outputs, checked finite after every step */
    int real_outputs[VR_COUNT];
    int n_real_inputs;                     /* the Real inputs: a step extrapolates, keeps aside and */
    int real_inputs[VR_COUNT];             /* clears only their derivatives */
    char *resources;                       /* the FMU's resources folder, a native path ending in a separator
                                            * (NULL: not given, or not a local folder) */
    char *carried;                         /* its carried start values (resources/start_values.txt), or NULL */
} FmuInstance;

/* The file an FMU's resources hold, for a path given as "@resources/NAME" (a scene's file that
 * travels inside the FMU): resources + NAME written into `out` (size bytes); any other path as it
 * is. NULL if the FMU has no resources folder or the path does not fit. */
const char *fmu_resource_path(const FmuInstance *fmu, const char *path, char *out, size_t size);

/* ---- hooks implemented by each model (model.c) ---- */

/* Checks that need more than the table's bounds (strictly positive values, relations between
 * parameters). Logs each violation with fmu_log and returns fmi2Error if there is one. */
fmi2Status model_validate(FmuInstance *fmu);
/* Sets the internal state from the parameters at the end of initialization. */
void model_initialize(FmuInstance *fmu);
/* Advances from fmu->s.time by h; the layer updates time afterwards. */
fmi2Status model_do_step(FmuInstance *fmu, double h);
/* Computes every output from the state and the inputs at fmu->s.time. */
void model_compute_outputs(FmuInstance *fmu);

#if MODEL_MAX_OUTPUT_DERIVATIVE_ORDER > 0
/* The derivative of the given order (1..MODEL_MAX_OUTPUT_DERIVATIVE_ORDER) of output `vr` with
 * respect to time at fmu->s.time (fmi2GetRealOutputDerivatives). */
double model_output_derivative(FmuInstance *fmu, int vr, int order);
#endif

#if MODEL_LAZY_OUTPUTS
/* Outputs computed when read (fmu_table.h): is vr one of them; compute them all for the state and
 * inputs now (after model_compute_outputs). */
int model_output_is_lazy(int vr);
void model_compute_lazy_outputs(FmuInstance *fmu);
#endif

#if MODEL_MODEL_EXCHANGE
/* Model Exchange (fmi2_me.c). Why these parameters cannot run as Model Exchange (e.g. a part
 * with events the model does not give as event indicators), or NULL if they can. */
const char *model_exchange_refusal(const FmuInstance *fmu);
/* dx/dt at fmu->s.time and fmu->s.x, the inputs as set; 0, or -1 where the model cannot evaluate them. */
int model_derivatives(FmuInstance *fmu, double *dxdt);
/* After an integrator's step is accepted: the checks a Co-Simulation step makes at its end
 * (warnings logged; fmi2Error stops the run). */
fmi2Status model_completed_integrator_step(FmuInstance *fmu);
#if MODEL_STATE_NOMINALS
/* Each continuous state's nominal value (MODEL_N_STATES of them: 1 where the model knows none), for
 * the importer's solver: its absolute tolerance is the relative one times the nominal. */
void model_state_nominals(const FmuInstance *fmu, double *nominals);
#endif
#if MODEL_TIME_EVENTS
/* The next time after fmu->s.time at which the model changes discontinuously (INFINITY: none). */
double model_next_time_event(FmuInstance *fmu);
/* At an event (fmi2NewDiscreteStates), before the next is asked for: the model's discrete state
 * updated for fmu->s.time (a sampled controller's new output). Returns 1 where the model changes
 * discontinuously there (its right-hand side or outputs: the importer's solver restarts), 0 where
 * nothing does (an event of another model of the system, or a sample that changed nothing). */
int model_time_event(FmuInstance *fmu);
#endif
#endif

/* ---- services of the layer for models ---- */

/* Memory from the environment's allocator (zeroed), and its release. */
void *fmu_calloc(const FmuInstance *fmu, size_t count, size_t size);
void fmu_free(const FmuInstance *fmu, void *memory);
/* Replaces the model data (releasing the old with its free function) by `data`, released later
 * with `release` (at fmi2Reset and fmi2FreeInstance). */
void fmu_set_model_data(FmuInstance *fmu, void *data, void (*release)(FmuInstance *fmu, void *data));

void fmu_log(const FmuInstance *fmu, fmi2Status status, const char *category, const char *format, ...)
#if defined(__MINGW32__) /* the win64 build's C99 printf (__USE_MINGW_ANSI_STDIO, cmake/mingw-w64.cmake) */
    __attribute__((format(gnu_printf, 4, 5)))
#elif defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;

/* Logs that parameter `vr` breaks `rule` (naming it, its value and unit) and returns 1, so that
 * model_validate can count violations: errors += fmu_reject(fmu, VR_x, "must be below limit.y"). A
 * rule the table can state (a bound, "> 0": FMU_POSITIVE) lives in the table, not here. */
int fmu_reject(const FmuInstance *fmu, int vr, const char *rule);

/* Value of the real input `vr` at time t: the value set, extrapolated with the derivatives given
 * through fmi2SetRealInputDerivatives (orders 1 and 2, if any) from the time it was set. */
double fmu_input_at(const FmuInstance *fmu, int vr, double t);
/* Its rate of change at t from those derivatives; if none were given, the value of its rate input
 * (MODEL_INPUT_RATES) where the model has one, else 0. */
double fmu_input_rate_at(const FmuInstance *fmu, int vr, double t);
/* The Real variable `vr`, for models that address variables through arrays of references. */
double *fmu_real(FmuInstance *fmu, int vr);
int *fmu_integer(FmuInstance *fmu, int vr); /* an Integer variable by value reference */
int fmu_input_has_derivative(const FmuInstance *fmu, int vr);

/* Runs the internal solver (solver.* parameters) over [time, time + h] on the model's ODE, with
 * steps no longer than max_step if that is > 0, and logs a failure with the time it happened. */
fmi2Status fmu_integrate(FmuInstance *fmu, const OdeProblem *problem, void *ctx, double h, double max_step);
/* The same by the exponential integrator (ode_exponential_integrate: ETDRK4 with the stiff states'
 * constant linear part `linear_part`, in steps of at most solver.step), its functions kept as the
 * model data (for a model that keeps nothing else there). */
fmi2Status fmu_integrate_exponential(FmuInstance *fmu, const OdeProblem *problem, OdeRhsLinear rhs_linear,
                                     const double *linear_part, double h);

#endif
