/* The one table of an FMU's variables, expanded into everything that must agree with it.
 *
 * Each model folder has a `variables.h` that defines MODEL_VARIABLES(X), one X(...) row per
 * variable:
 *
 *   X(type, field, "name", causality, variability, "unit", start, min, max, "description")
 *
 *   type         Real | Integer | Boolean | String (a String has no start, min or max: write 0; it
 *                starts empty and holds at most FMU_TEXT_MAX - 1 bytes)
 *   field        C name of the variable in ModelVariables (the FMI name with '.' -> '_')
 *   causality    parameter | input | output | local
 *   variability  fixed | tunable | discrete | continuous
 *   min, max     inclusive bounds; -FMU_INF / FMU_INF for none, FMU_POSITIVE for "> 0". The FMI layer rejects a parameter
 *                or input outside them with fmi2Error, naming the variable.
 *
 * From this one table follow: the ModelVariables struct the C model reads and writes, the value
 * references (VR_<field>, counted from 1 in table order), the metadata array the FMI layer uses
 * for get/set and validation, and modelDescription.xml and documentation/index.html (written at
 * build time by model_description.c from the same table). They cannot drift apart.
 */
#ifndef FMU_TABLE_H
#define FMU_TABLE_H

#include <float.h>
#include <math.h>
#include <stddef.h>

#define FMU_INF HUGE_VAL
/* The min of a value that must be > 0 (a gain, a time constant, a mass): the smallest positive
 * normal double, so that the table's inclusive bound states it and the FMI layer refuses 0 with
 * "must be > 0". */
#define FMU_POSITIVE DBL_MIN

/* FMI 3.0 has no input derivatives: the FMI 3.0 binaries take each Real input's first and second
 * time derivatives over the next step as inputs of their own, fmi.rate.<input> and
 * fmi.curvature.<input>, at these value references (docs/interfaces.md); what
 * fmi2SetRealInputDerivatives is to the FMI 2.0 binaries. */
#define FMU_INPUT_DERIVATIVE_SPAN 0x100000u
#define FMU_INPUT_DERIVATIVE_VR(vr, order) ((unsigned)(order) * FMU_INPUT_DERIVATIVE_SPAN + (unsigned)(vr))

/* Rows every model puts in its table: the internal solver's settings. */
#define FMU_SOLVER_VARIABLES(X, method, step, rtol, atol)                                          \
    X(Integer, solver_method, "solver.method", parameter, fixed, "", method, 1, 5,                 \
      "Internal ODE solver: 1 = classic Runge-Kutta 4 with fixed step solver.step, "               \
      "2 = Dormand-Prince 5(4) with error control (solver.rtol, solver.atol), steps <= solver.step, " \
      "3 = Rosenbrock-W ROS34PW2 (order 3, L-stable: no stability limit for stiff models) with "    \
      "fixed step solver.step, 4 = ROS34PW2 with error control, steps <= solver.step, "            \
      "5 = Heun (order 2, two evaluations a step: the order of inputs a master interpolates "      \
      "linearly) with fixed step solver.step")                                                     \
    X(Real, solver_step, "solver.step", parameter, fixed, "s", step, 1e-7, 1.0,                    \
      "RK4, Heun and ROS34PW2: the integration step; with error control: the largest step")       \
    X(Real, solver_rtol, "solver.rtol", parameter, fixed, "1", rtol, 1e-14, 0.1,                   \
      "Relative error tolerance per step (methods 2 and 4)")                                      \
    X(Real, solver_atol, "solver.atol", parameter, fixed, "1", atol, 1e-16, 1.0,                   \
      "Absolute error tolerance per step, in each state's own unit (methods 2 and 4)")            \
    X(Integer, solver_steps, "solver.steps", output, discrete, "", 0, -FMU_INF, FMU_INF,           \
      "Internal solver steps accepted since the start (cost indicator)")                           \
    X(Integer, solver_rejected, "solver.rejected", output, discrete, "", 0, -FMU_INF, FMU_INF,     \
      "Internal solver steps rejected by the error control since the start")

/* Rows every model puts in its table: the FMI layer's own settings. */
#define FMU_LAYER_VARIABLES(X)                                                                     \
    X(Boolean, fmi_warnings_as_ok, "fmi.warnings_as_ok", parameter, fixed, "", 0, 0, 1,            \
      "false (FMI 2.0): a call that raised a warning returns fmi2Warning; true: the warning stays " \
      "in the log, the call returns fmi2OK (for importers that stop on any status but fmi2OK, "    \
      "such as OMSimulator)")                                                                  \
    X(Boolean, fmi_extrapolate_inputs, "fmi.extrapolate_inputs", parameter, fixed, "", 0, 0, 1,    \
      "false: an input the master gives no derivative for (fmi2SetRealInputDerivatives) is held "  \
      "over the step; true: the FMU extrapolates it linearly over the step from its values at the " \
      "last two communication points, or with the rate input that carries its exact rate, so "   \
      "that a master which holds its inputs couples at second order under Jacobi (inputs the "   \
      "model keeps piecewise constant, such as loads, stay held)")

#define FMU_TEXT_MAX 1024
typedef struct { char text[FMU_TEXT_MAX]; } FmuText; /* a String variable's value, inside the snapshot */

#include "model_guid.h" /* MODEL_GUID, written by the build */
#include "variables.h"

/* Highest order of fmi2GetRealOutputDerivatives a model provides (it then implements
 * model_output_derivative); 0 for none. */
#ifndef MODEL_MAX_OUTPUT_DERIVATIVE_ORDER
#define MODEL_MAX_OUTPUT_DERIVATIVE_ORDER 0
#endif

/* Model Exchange (fmi2_me.c): a model that can give its states' derivatives as it stands sets
 * MODEL_MODEL_EXCHANGE 1 and implements the hooks of fmu_common.h; its continuous states and their
 * derivatives are variables of their own after the table's (ode.x[k] and der(ode.x[k])). */
#ifndef MODEL_MODEL_EXCHANGE
#define MODEL_MODEL_EXCHANGE 0
#endif
#ifndef MODEL_TIME_EVENTS
#define MODEL_TIME_EVENTS 0
#endif
#ifndef MODEL_STATE_NOMINALS /* 1: the model gives its states' nominal values (model_state_nominals), else all 1 */
#define MODEL_STATE_NOMINALS 0
#endif
/* A model with continuous states integrates them in Co-Simulation by the shared solvers (ode.h,
 * FMU_SOLVER_VARIABLES in its table) unless it sets MODEL_SHARED_SOLVER 0 (it steps them itself:
 * the cueing's filters, discretised exactly). */
/* Outputs computed when read (MODEL_LAZY_OUTPUTS 1): costly outputs that a master seldom reads
 * (the mechanics' energies and powers) are computed at their first read after a step, not at
 * every step (the model's model_output_is_lazy and model_compute_lazy_outputs, fmu_common.h). */
#ifndef MODEL_LAZY_OUTPUTS
#define MODEL_LAZY_OUTPUTS 0
#endif
#ifndef MODEL_SHARED_SOLVER
#define MODEL_SHARED_SOLVER (MODEL_N_STATES > 0)
#endif
#define FMU_STATE_VR(k) (VR_COUNT + (k))
#define FMU_DERIVATIVE_VR(k) (VR_COUNT + MODEL_N_STATES + (k))

typedef enum { FMU_REAL, FMU_INTEGER, FMU_BOOLEAN, FMU_STRING } FmuType;
typedef enum { FMU_PARAMETER, FMU_INPUT, FMU_OUTPUT, FMU_LOCAL } FmuCausality;
typedef enum { FMU_FIXED, FMU_TUNABLE, FMU_DISCRETE, FMU_CONTINUOUS } FmuVariability;

#define FMU_TYPE_Real FMU_REAL
#define FMU_TYPE_Integer FMU_INTEGER
#define FMU_TYPE_Boolean FMU_BOOLEAN
#define FMU_TYPE_String FMU_STRING
#define FMU_CTYPE_Real double
#define FMU_CTYPE_Integer int
#define FMU_CTYPE_Boolean int
#define FMU_CTYPE_String FmuText
#define FMU_CAUSALITY_parameter FMU_PARAMETER
#define FMU_CAUSALITY_input FMU_INPUT
#define FMU_CAUSALITY_output FMU_OUTPUT
#define FMU_CAUSALITY_local FMU_LOCAL
#define FMU_VARIABILITY_fixed FMU_FIXED
#define FMU_VARIABILITY_tunable FMU_TUNABLE
#define FMU_VARIABILITY_discrete FMU_DISCRETE
#define FMU_VARIABILITY_continuous FMU_CONTINUOUS

typedef struct {
#define FMU_X_FIELD(type, field, name, causality, variability, unit, start, min, max, doc) \
    FMU_CTYPE_##type field;
    MODEL_VARIABLES(FMU_X_FIELD)
#undef FMU_X_FIELD
} ModelVariables;

enum {
    VR_NONE = 0,
#define FMU_X_VR(type, field, name, causality, variability, unit, start, min, max, doc) VR_##field,
    MODEL_VARIABLES(FMU_X_VR)
#undef FMU_X_VR
    VR_COUNT
};

typedef struct {
    FmuType type;
    const char *name;
    FmuCausality causality;
    FmuVariability variability;
    const char *unit;
    double start, min, max;
    const char *description;
    size_t offset; /* of the value in ModelVariables */
} FmuVariable;

/* Indexed by value reference; entry 0 is unused. */
static const FmuVariable fmu_variables[VR_COUNT] = {
    {FMU_REAL, NULL, FMU_LOCAL, FMU_FIXED, NULL, 0, 0, 0, NULL, 0},
#define FMU_X_META(type, field, name, causality, variability, unit, start, min, max, doc) \
    {FMU_TYPE_##type, name, FMU_CAUSALITY_##causality, FMU_VARIABILITY_##variability, unit, \
     (double)(start), (double)(min), (double)(max), doc, offsetof(ModelVariables, field)},
    MODEL_VARIABLES(FMU_X_META)
#undef FMU_X_META
};

#define FMU_STRINGIFY2(x) #x
#define FMU_STRINGIFY(x) FMU_STRINGIFY2(x)
#define MODEL_IDENTIFIER_STRING FMU_STRINGIFY(MODEL_IDENTIFIER)

#endif
