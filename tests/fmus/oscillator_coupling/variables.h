/* Test FMU (not shipped): mass m2 on spring k2 to the wall, tied to mass 1 by the coupling spring kc
 * and damper dc; outputs the coupling force on mass 1:
 *   F = kc (x2 - x1) + dc (v2 - v1),   m2 x2'' = -k2 x2 - F. */
#ifndef OSCILLATOR_COUPLING_VARIABLES_H
#define OSCILLATOR_COUPLING_VARIABLES_H
#define MODEL_IDENTIFIER oscillator_coupling
#define MODEL_VERSION "0.1.0"
#define MODEL_DESCRIPTION "Two-mass oscillator, second half: mass, spring and the coupling spring-damper"
#define MODEL_STOP_TIME 10.0
#define MODEL_COMMUNICATION_STEP 1e-2
#define MODEL_N_STATES 2
typedef struct { int unused; } ModelInternal;
#define MODEL_VARIABLES(X) \
X(Real, position_1, "position_1", input, continuous, "m", 0.0, -FMU_INF, FMU_INF, "Position of mass 1") \
X(Real, velocity_1, "velocity_1", input, continuous, "m/s", 0.0, -FMU_INF, FMU_INF, "Velocity of mass 1") \
X(Real, force, "force", output, continuous, "N", 0.0, -FMU_INF, FMU_INF, "Coupling force on mass 1") \
X(Real, force_position_slope, "force_position_slope", output, continuous, "N/m", 0.0, -FMU_INF, FMU_INF, \
  "Interface Jacobian d force / d position_1 = -kc") \
X(Real, force_velocity_slope, "force_velocity_slope", output, continuous, "N.s/m", 0.0, -FMU_INF, FMU_INF, \
  "Interface Jacobian d force / d velocity_1 = -dc") \
X(Real, position, "position", output, continuous, "m", 0.0, -FMU_INF, FMU_INF, "Position x2") \
X(Real, mass, "mass", parameter, fixed, "kg", 1.0, 0.0, FMU_INF, "m2") \
X(Real, stiffness, "stiffness", parameter, fixed, "N/m", 10.0, 0.0, FMU_INF, "k2") \
X(Real, coupling_stiffness, "coupling_stiffness", parameter, fixed, "N/m", 100.0, 0.0, FMU_INF, "kc") \
X(Real, coupling_damping, "coupling_damping", parameter, fixed, "N.s/m", 1.0, 0.0, FMU_INF, "dc") \
FMU_SOLVER_VARIABLES(X, 2, 1e-2, 1e-12, 1e-14) \
FMU_LAYER_VARIABLES(X)
/* Direct feed-through (the ModelStructure's output dependencies): the spring-damper force
 * follows the first mass's position and velocity at once. */
#define MODEL_FEEDTHROUGH(D) D(force, VR_position_1, VR_velocity_1)

#endif
