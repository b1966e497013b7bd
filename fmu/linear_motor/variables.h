/* linear_motor: the variable table (the one source of truth for model.c, modelDescription.xml and
 * the documentation). Defaults equal ../shared/params/sumnu2015.toml, [linear_motor]. */
#ifndef LINEAR_MOTOR_VARIABLES_H
#define LINEAR_MOTOR_VARIABLES_H

#define MODEL_IDENTIFIER linear_motor
#define MODEL_VERSION "0.1.0"
#define MODEL_DESCRIPTION                                                                          \
    "One leg's linear-motor drive (Sumnu 2015, Section 4.3 and 5.3): force constant, back-EMF, RL " \
    "winding, Stribeck friction and force ripple, PID position control of the leg length"
#define MODEL_STOP_TIME 1.0
#define MODEL_COMMUNICATION_STEP 1e-3

/* current, position-loop integral, current-loop integral, energy accounts (electrical, copper,
 * electromagnetic work, friction and damping, ripple) */
#define MODEL_N_STATES 8
/* Model Exchange too (fmi2_me.c): the importer's solver integrates these states. */
#define MODEL_MODEL_EXCHANGE 1

typedef struct {
    int over_continuous_force; /* reported, so a warning is logged once per excursion */
} ModelInternal;

/* clang-format off */
#define MODEL_VARIABLES(X) \
X(Real, position_ref, "position_ref", input, continuous, "m", 0.0, -FMU_INF, FMU_INF, \
  "Leg length reference (inverse kinematics of the pose reference)") \
X(Real, position, "position", input, continuous, "m", 0.0, -FMU_INF, FMU_INF, "Leg length (from the mechanics)") \
X(Real, velocity, "velocity", input, continuous, "m/s", 0.0, -FMU_INF, FMU_INF, \
  "Leg extension rate (from the mechanics); also advances the position inside a step") \
X(Real, force_ff, "force_ff", input, continuous, "N", 0.0, -FMU_INF, FMU_INF, \
  "Force feedforward added to the position controller's output; in force mode the force command") \
X(Real, voltage_ref, "voltage_ref", input, continuous, "V", 0.0, -FMU_INF, FMU_INF, \
  "Winding voltage in voltage mode (control.mode = 3), for open-loop studies such as Eq 5.6") \
X(Real, velocity_ref, "velocity_ref", input, continuous, "m/s", 0.0, -FMU_INF, FMU_INF, \
  "Leg extension rate reference for the PID's derivative term, with control.velocity_ref_input (the " \
  "mechanics' leg[i].velocity_ref: where the rate of position_ref is only the slope of the master's extrapolation)") \
\
X(Real, force, "force", output, continuous, "N", 0.0, -FMU_INF, FMU_INF, \
  "Net axial force on the leg: K_f i - B_l v - friction(v) - ripple(x) (Eqs 4.28-4.31)") \
X(Real, force_electromagnetic, "force.electromagnetic", output, continuous, "N", 0.0, -FMU_INF, FMU_INF, \
  "Electromagnetic force K_f i (Eq 4.28)") \
X(Real, force_friction, "force.friction", output, continuous, "N", 0.0, -FMU_INF, FMU_INF, \
  "Friction force of Eq 4.30 (Stribeck, smoothed at zero speed), opposing the motion") \
X(Real, force_ripple, "force.ripple", output, continuous, "N", 0.0, -FMU_INF, FMU_INF, \
  "Force ripple A sin(w x + phi) of Eq 4.31, opposing") \
X(Real, force_ref, "force_ref", output, continuous, "N", 0.0, -FMU_INF, FMU_INF, \
  "Force command after the force limit (position controller plus force_ff)") \
X(Real, force_velocity_slope, "force_velocity_slope", output, continuous, "N.s/m", 0.0, -FMU_INF, FMU_INF, \
  "Interface Jacobian: d force / d velocity over a step of a few current-loop time constants, the limits as " \
  "they stand: -K_d - K_f K_e / (Kp_c + R) - B_l - f_v (the PID's derivative term while no limit holds it, " \
  "the back-EMF through the current loop, the damping and viscous friction; -K_d - B_l - f_v for the ideal " \
  "force source; the smoothed Coulomb and Stribeck friction are left out, their slope at rest is the " \
  "smoothing's); wired to the mechanics' leg[i].force_velocity_slope it makes the coupling implicit in it") \
X(Real, current, "current", output, continuous, "A", 0.0, -FMU_INF, FMU_INF, "Winding current i") \
X(Real, voltage, "voltage", output, continuous, "V", 0.0, -FMU_INF, FMU_INF, "Winding voltage V applied") \
X(Real, power_electrical, "power.electrical", output, continuous, "W", 0.0, -FMU_INF, FMU_INF, \
  "Electrical power (K_f/K_e) V i: the three-phase power of the single-phase equivalent model") \
X(Real, power_mechanical, "power.mechanical", output, continuous, "W", 0.0, -FMU_INF, FMU_INF, \
  "Mechanical power delivered to the leg, force times velocity") \
X(Real, energy_electrical, "energy.electrical", output, continuous, "J", 0.0, -FMU_INF, FMU_INF, "Electrical energy since the start") \
X(Real, energy_copper_loss, "energy.copper_loss", output, continuous, "J", 0.0, -FMU_INF, FMU_INF, "Copper loss (K_f/K_e) R i^2 since the start") \
X(Real, energy_magnetic, "energy.magnetic", output, continuous, "J", 0.0, -FMU_INF, FMU_INF, "Magnetic energy (K_f/K_e) L i^2 / 2") \
X(Real, energy_electromagnetic, "energy.electromagnetic", output, continuous, "J", 0.0, -FMU_INF, FMU_INF, "Work of the electromagnetic force K_f i v since the start") \
X(Real, energy_mechanical_loss, "energy.mechanical_loss", output, continuous, "J", 0.0, -FMU_INF, FMU_INF, "Work against damping and friction since the start") \
X(Real, energy_ripple, "energy.ripple", output, continuous, "J", 0.0, -FMU_INF, FMU_INF, "Work against the force ripple since the start") \
\
X(Real, motor_force_constant, "motor.force_constant", parameter, fixed, "N/A", 44.0, FMU_POSITIVE, FMU_INF, "K_f (Table 4.2)") \
X(Real, motor_back_emf_constant, "motor.back_emf_constant", parameter, fixed, "V.s/m", 26.0, FMU_POSITIVE, FMU_INF, "K_e (Table 4.2)") \
X(Real, motor_resistance, "motor.resistance", parameter, fixed, "Ohm", 3.1, FMU_POSITIVE, FMU_INF, "R (Table 4.2)") \
X(Real, motor_inductance, "motor.inductance", parameter, fixed, "H", 0.010, FMU_POSITIVE, FMU_INF, \
  "L (assumed: not in the thesis; L/R = 3.2 ms, usual for an iron-core forcer of this size)") \
X(Real, motor_damping, "motor.damping", parameter, fixed, "N.s/m", 0.01, 0.0, FMU_INF, "B_l (Table 4.2)") \
X(Real, motor_forcer_mass, "motor.forcer_mass", parameter, fixed, "kg", 1.8, 0.0, FMU_INF, \
  "M_f (Table 4.2); informative here: the forcer moves with the leg and belongs to the mechanics' moving part") \
X(Real, motor_stator_mass_per_length, "motor.stator_mass_per_length", parameter, fixed, "kg/m", 4.2, 0.0, FMU_INF, \
  "M_s (Table 4.2); informative here: the stator belongs to the mechanics' rotating part") \
X(Real, motor_continuous_force, "motor.continuous_force", parameter, fixed, "N", 203.0, 0.0, FMU_INF, \
  "F_net (Table 4.2): thermal rating; a force command above it is reported once per excursion") \
X(Real, friction_coulomb, "friction.coulomb", parameter, fixed, "N", 8.0, 0.0, FMU_INF, "f_c of Eq 4.30 (assumed)") \
X(Real, friction_static, "friction.static", parameter, fixed, "N", 12.0, 0.0, FMU_INF, "f_s of Eq 4.30 (assumed)") \
X(Real, friction_stribeck_velocity, "friction.stribeck_velocity", parameter, fixed, "m/s", 0.01, FMU_POSITIVE, FMU_INF, "x_s of Eq 4.30 (assumed)") \
X(Real, friction_stribeck_exponent, "friction.stribeck_exponent", parameter, fixed, "1", 2.0, 0.0, FMU_INF, "delta of Eq 4.30 (assumed)") \
X(Real, friction_viscous, "friction.viscous", parameter, fixed, "N.s/m", 0.01, 0.0, FMU_INF, "f_v of Eq 4.30 (assumed, = B_l)") \
X(Real, friction_smoothing_velocity, "friction.smoothing_velocity", parameter, fixed, "m/s", 1e-3, FMU_POSITIVE, FMU_INF, \
  "sgn(v) is replaced by tanh(v / this), so the force is smooth through zero speed and the solver does not chatter") \
X(Real, ripple_amplitude, "ripple.amplitude", parameter, fixed, "N", 2.0, 0.0, FMU_INF, "A of Eq 4.31 (assumed: 1 % of F_net)") \
X(Real, ripple_period, "ripple.period", parameter, fixed, "m", 0.030, FMU_POSITIVE, FMU_INF, "Ripple period 2 pi / w of Eq 4.31 (assumed: one magnet pole pitch)") \
X(Real, ripple_phase, "ripple.phase", parameter, fixed, "rad", 0.0, -FMU_INF, FMU_INF, "phi of Eq 4.31") \
X(Boolean, effects_electrical, "effects.electrical", parameter, fixed, "", 1, 0, 1, \
  "Electrical dynamics (RL winding, back-EMF, current loop); off: an ideal force source delivering the limited force command") \
X(Boolean, effects_friction, "effects.friction", parameter, fixed, "", 0, 0, 1, \
  "Friction of Eq 4.30 (off by default, as in the thesis' simulations; near zero speed it is stiff, see the documentation)") \
X(Boolean, effects_ripple, "effects.ripple", parameter, fixed, "", 0, 0, 1, "Force ripple of Eq 4.31 (off by default, as in the thesis' simulations)") \
X(Integer, control_mode, "control.mode", parameter, fixed, "", 1, 1, 3, \
  "1 = position (PID on leg length -> force -> PI current loop), 2 = force (force_ff -> current loop), " \
  "3 = voltage (voltage_ref applied to the winding, open loop)") \
X(Real, control_position_kp, "control.position_kp", parameter, tunable, "N/m", 19739.0, FMU_POSITIVE, FMU_INF, \
  "Position PID: m w^2 for a design mass m = 5 kg and w = 2 pi 10 Hz (critically damped)") \
X(Real, control_position_ki, "control.position_ki", parameter, tunable, "N/(m.s)", 124025.0, 0.0, FMU_INF, \
  "Position PID integral gain: Kp w / 10 (integral zero a decade below w)") \
X(Real, control_position_kd, "control.position_kd", parameter, tunable, "N.s/m", 628.3, 0.0, FMU_INF, \
  "Position PID derivative gain 2 m w, acting on the velocity error (reference velocity from the derivative of position_ref when given)") \
X(Boolean, control_velocity_ref_input, "control.velocity_ref_input", parameter, fixed, "", 0, 0, 1, \
  "The derivative term's reference velocity: the input velocity_ref (true) or the rate of position_ref (false)") \
X(Real, control_current_kp, "control.current_kp", parameter, tunable, "V/A", 62.83, FMU_POSITIVE, FMU_INF, \
  "Current PI: L w_c with w_c = 2 pi 1 kHz (zero cancels L/R)") \
X(Real, control_current_ki, "control.current_ki", parameter, tunable, "V/(A.s)", 19478.0, 0.0, FMU_INF, \
  "Current PI integral gain R w_c") \
X(Real, limit_force, "limit.force", parameter, tunable, "N", 610.0, FMU_POSITIVE, FMU_INF, \
  "Force command limit: peak force (assumed about 3 x F_net, usual for iron-core forcers)") \
X(Real, limit_current, "limit.current", parameter, tunable, "A", 13.9, FMU_POSITIVE, FMU_INF, "Current limit: peak force / K_f (assumed)") \
X(Real, limit_voltage, "limit.voltage", parameter, tunable, "V", 325.0, FMU_POSITIVE, FMU_INF, "Voltage limit: DC bus of a 230 V AC drive (assumed)") \
X(Boolean, solver_exponential, "solver.exponential", parameter, fixed, "", 0, 0, 1, \
  "1: the current loop and the winding, linear with constant coefficients while the voltage limit " \
  "does not hold, taken exactly (exponential integrator ETDRK4, Cox and Matthews 2002) and the rest " \
  "explicitly, at steps of solver.step; RK4 at the current loop's time scale for a step in which " \
  "the voltage limit holds") \
FMU_SOLVER_VARIABLES(X, 1, 2.5e-4, 1e-6, 1e-8) \
FMU_LAYER_VARIABLES(X)
/* clang-format on */

/* Direct feed-through (the ModelStructure's output dependencies): D(output, the value references of
 * the inputs it depends on at the same communication point), one row per such output; every other
 * output depends on no input (on the state alone). The union over the control modes and the
 * effects (without the winding, the force follows the controller at once).
 * tests/models/test_dependencies.py perturbs each input and holds this table to what moves. */
#define LOOP_INPUTS VR_position_ref, VR_position, VR_velocity, VR_force_ff, VR_velocity_ref
#define MODEL_FEEDTHROUGH(D) \
D(force, LOOP_INPUTS) \
D(force_electromagnetic, LOOP_INPUTS) \
D(force_friction, VR_velocity) \
D(force_ripple, VR_position) \
D(force_ref, LOOP_INPUTS) \
D(current, LOOP_INPUTS) \
D(voltage, LOOP_INPUTS, VR_voltage_ref) \
D(power_electrical, LOOP_INPUTS, VR_voltage_ref) \
D(power_mechanical, LOOP_INPUTS)

#endif
