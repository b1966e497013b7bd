/* Test FMU (not shipped): mass m1 on spring k1 and damper d1 to the wall, driven by the coupling
 * force F: m1 x1'' = -k1 x1 - d1 x1' + F. Half of the two-mass oscillator the coupling tests use. */
#ifndef OSCILLATOR_MASS_VARIABLES_H
#define OSCILLATOR_MASS_VARIABLES_H
#define MODEL_IDENTIFIER oscillator_mass
#define MODEL_VERSION "0.1.0"
#define MODEL_DESCRIPTION "Two-mass oscillator, first half: mass on a spring to the wall, coupling force in"
#define MODEL_STOP_TIME 10.0
#define MODEL_COMMUNICATION_STEP 1e-2
#define MODEL_N_STATES 2
typedef struct { int unused; } ModelInternal;
#define MODEL_VARIABLES(X) \
X(Real, force, "force", input, continuous, "N", 0.0, -FMU_INF, FMU_INF, "Coupling force on the mass") \
X(Real, force_position_slope, "force_position_slope", input, continuous, "N/m", 0.0, -FMU_INF, FMU_INF, \
  "Interface Jacobian d force / d x1 from the coupling FMU: the mass feels force + slope (x1 - position_seen)") \
X(Real, position_seen, "position_seen", input, continuous, "m", 0.0, -FMU_INF, FMU_INF, "x1 as the coupling FMU was given it") \
X(Real, force_velocity_slope, "force_velocity_slope", input, continuous, "N.s/m", 0.0, -FMU_INF, FMU_INF, \
  "Interface Jacobian d force / d v1: the mass feels force + slope (v1 - velocity_seen) too") \
X(Real, velocity_seen, "velocity_seen", input, continuous, "m/s", 0.0, -FMU_INF, FMU_INF, "v1 as the coupling FMU was given it") \
X(Real, position, "position", output, continuous, "m", 0.0, -FMU_INF, FMU_INF, "Position x1") \
X(Real, velocity, "velocity", output, continuous, "m/s", 0.0, -FMU_INF, FMU_INF, "Velocity v1") \
X(Real, mass, "mass", parameter, fixed, "kg", 1.0, 0.0, FMU_INF, "m1") \
X(Real, stiffness, "stiffness", parameter, fixed, "N/m", 10.0, 0.0, FMU_INF, "k1") \
X(Real, damping, "damping", parameter, fixed, "N.s/m", 0.1, 0.0, FMU_INF, "d1") \
X(Real, initial_position, "initial.position", parameter, fixed, "m", 1.0, -FMU_INF, FMU_INF, "x1(0)") \
FMU_SOLVER_VARIABLES(X, 2, 1e-2, 1e-12, 1e-14) \
FMU_LAYER_VARIABLES(X)
/* Direct feed-through: none (the mass's position and velocity are its state). */
#define MODEL_FEEDTHROUGH(D)

#endif
