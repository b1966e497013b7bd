/* pmsm_drive: the variable table (the one source of truth for model.c, modelDescription.xml and
 * the documentation). Defaults equal ../shared/params/meng2010.toml; see doc.html for the sources
 * of the values and the tuning rules behind the gains. */
#ifndef PMSM_DRIVE_VARIABLES_H
#define PMSM_DRIVE_VARIABLES_H

#define MODEL_IDENTIFIER pmsm_drive
#define MODEL_VERSION "0.1.0"
#define MODEL_DESCRIPTION                                                                          \
    "One leg's PMSM vector-control drive (Meng et al. 2010, Section 3): dq motor with back-EMF, "  \
    "ideal, averaged or hysteresis-switching inverter, cascaded position, speed and current loops"
#define MODEL_STOP_TIME 1.0
#define MODEL_COMMUNICATION_STEP 1e-3

/* Internal ODE state: stator currents, averaged-inverter voltages, controller integrators and
 * energy accounts (index names in model.c). */
#define MODEL_N_STATES 12
/* Model Exchange too (fmi2_me.c), but for the switching inverter (its hysteresis events). */
#define MODEL_MODEL_EXCHANGE 1

typedef struct {
    int switch_state[3]; /* switching inverter: upper switch of phase a, b, c closed */
    int switchings;      /* number of commutations so far */
} ModelInternal;

/* clang-format off */
#define MODEL_VARIABLES(X) \
X(Real, angle_ref, "angle_ref", input, continuous, "rad", 0.0, -FMU_INF, FMU_INF, \
  "Motor angle reference (from the leg length reference: screw ratio times the extension)") \
X(Real, angle, "angle", input, continuous, "rad", 0.0, -FMU_INF, FMU_INF, \
  "Motor shaft angle, zero at the neutral pose (from the mechanics)") \
X(Real, speed, "speed", input, continuous, "rad/s", 0.0, -FMU_INF, FMU_INF, \
  "Motor shaft speed (from the mechanics); also advances the angle inside a step") \
X(Real, torque_ff, "torque_ff", input, continuous, "N.m", 0.0, -FMU_INF, FMU_INF, \
  "Torque feedforward, added to the speed loop's current reference as torque_ff / K_m; " \
  "in torque mode the torque command") \
X(Real, speed_ff, "speed_ff", input, continuous, "rad/s", 0.0, -FMU_INF, FMU_INF, \
  "Speed feedforward added to the position loop's output; in speed mode the speed reference") \
\
X(Real, torque, "torque", output, continuous, "N.m", 0.0, -FMU_INF, FMU_INF, \
  "Electromagnetic torque T = P (psi_r i_q + (L_d - L_q) i_d i_q) (Eq 26)") \
X(Real, current_d, "current.d", output, continuous, "A", 0.0, -FMU_INF, FMU_INF, "Stator current, d axis") \
X(Real, current_q, "current.q", output, continuous, "A", 0.0, -FMU_INF, FMU_INF, "Stator current, q axis") \
X(Real, voltage_d, "voltage.d", output, continuous, "V", 0.0, -FMU_INF, FMU_INF, "Stator voltage applied, d axis") \
X(Real, voltage_q, "voltage.q", output, continuous, "V", 0.0, -FMU_INF, FMU_INF, "Stator voltage applied, q axis") \
X(Real, power_electrical, "power.electrical", output, continuous, "W", 0.0, -FMU_INF, FMU_INF, \
  "Electrical power into the stator, u_d i_d + u_q i_q + u_0 i_0") \
X(Real, power_mechanical, "power.mechanical", output, continuous, "W", 0.0, -FMU_INF, FMU_INF, \
  "Mechanical power delivered to the shaft, torque times speed") \
X(Real, power_copper_loss, "power.copper_loss", output, continuous, "W", 0.0, -FMU_INF, FMU_INF, \
  "Copper loss R_s (i_d^2 + i_q^2 + i_0^2)") \
X(Real, energy_magnetic, "energy.magnetic", output, continuous, "J", 0.0, -FMU_INF, FMU_INF, \
  "Magnetic energy stored in the winding inductances, (L_d i_d^2 + L_q i_q^2 + L_0 i_0^2) / 2") \
X(Real, energy_electrical, "energy.electrical", output, continuous, "J", 0.0, -FMU_INF, FMU_INF, \
  "Electrical energy delivered since the start (integral of power.electrical)") \
X(Real, energy_copper_loss, "energy.copper_loss", output, continuous, "J", 0.0, -FMU_INF, FMU_INF, \
  "Copper loss since the start") \
X(Real, energy_mechanical, "energy.mechanical", output, continuous, "J", 0.0, -FMU_INF, FMU_INF, \
  "Mechanical energy delivered since the start") \
X(Real, current_a, "current.a", output, continuous, "A", 0.0, -FMU_INF, FMU_INF, \
  "Phase current a (power-invariant Park/Clarke transform of i_d, i_q)") \
X(Real, current_b, "current.b", output, continuous, "A", 0.0, -FMU_INF, FMU_INF, "Phase current b") \
X(Real, current_c, "current.c", output, continuous, "A", 0.0, -FMU_INF, FMU_INF, "Phase current c") \
X(Real, current_error_max, "current_error.max", output, continuous, "A", 0.0, -FMU_INF, FMU_INF, \
  "Largest phase-current error |i_k* - i_k| over the three phases (the hysteresis band bounds it)") \
X(Real, speed_ref, "speed_ref", output, continuous, "rad/s", 0.0, -FMU_INF, FMU_INF, \
  "Speed reference after the speed limit (position loop output plus speed_ff)") \
X(Real, current_ref_q, "current_ref.q", output, continuous, "A", 0.0, -FMU_INF, FMU_INF, \
  "q-current reference after the current limit") \
X(Real, torque_speed_slope, "torque_speed_slope", output, continuous, "N.m.s/rad", 0.0, -FMU_INF, FMU_INF, \
  "Interface Jacobian: d torque / d speed over a step of a few current-loop time constants, the limits as " \
  "they stand: -(K_m + P (L_d - L_q) i_d) (Kp_w + K_m / (K_v Kp_c + R)) (the speed loop's gain, while the " \
  "current limit leaves it free, and the back-EMF's through the current loop); wired to the mechanics' " \
  "leg[i].torque_speed_slope it makes the coupling implicit in that damping") \
X(Integer, inverter_switchings, "inverter.switchings", output, discrete, "", 0, -FMU_INF, FMU_INF, \
  "Number of commutations of the switching inverter since the start") \
\
X(Integer, motor_pole_pairs, "motor.pole_pairs", parameter, fixed, "", 4, 1, 64, \
  "Number of pole pairs P (Table 2)") \
X(Real, motor_torque_constant, "motor.torque_constant", parameter, fixed, "N.m/A", 1.5, FMU_POSITIVE, FMU_INF, \
  "Torque constant K_m = P psi_r (Table 2); psi_r = K_m / P") \
X(Real, motor_inductance_d, "motor.inductance_d", parameter, fixed, "H", 6.9e-3, FMU_POSITIVE, FMU_INF, \
  "Stator inductance L_d (assumed = L_q: surface magnets; the paper gives only L_q)") \
X(Real, motor_inductance_q, "motor.inductance_q", parameter, fixed, "H", 6.9e-3, FMU_POSITIVE, FMU_INF, \
  "Stator inductance L_q (Table 2, printed 6.9 M.h, read as 6.9 mH)") \
X(Real, motor_resistance, "motor.resistance", parameter, fixed, "Ohm", 0.7, FMU_POSITIVE, FMU_INF, \
  "Stator resistance R_s (Table 2)") \
\
X(Integer, inverter_model, "inverter.model", parameter, fixed, "", 2, 1, 3, \
  "Inverter model: 1 = ideal (voltage = K_v times command), 2 = averaged K_v / (tau_v s + 1) (Fig 4), " \
  "3 = switching two-level inverter with hysteresis-band phase-current control (Fig 3)") \
X(Real, inverter_gain, "inverter.gain", parameter, fixed, "1", 50.7, FMU_POSITIVE, FMU_INF, \
  "Inverter magnification K_v: volts per unit of current-controller output (Table 2, printed V/A)") \
X(Real, inverter_time_constant, "inverter.time_constant", parameter, fixed, "s", 1.0e-4, FMU_POSITIVE, FMU_INF, \
  "Averaged inverter delay tau_v (assumed: one period of a 10 kHz PWM carrier)") \
X(Real, inverter_dc_link_voltage, "inverter.dc_link_voltage", parameter, fixed, "V", 860.0, FMU_POSITIVE, FMU_INF, \
  "DC-link voltage of the switching inverter (assumed; see meng2010.toml)") \
X(Real, inverter_hysteresis_band, "inverter.hysteresis_band", parameter, fixed, "A", 0.5, 0.01, FMU_INF, \
  "Half width of the hysteresis band of each phase-current comparator (assumed)") \
X(Boolean, inverter_neutral_connected, "inverter.neutral_connected", parameter, fixed, "", 0, 0, 1, \
  "Switching inverter: false = star point isolated (Fig 3; the three comparators interact and a phase " \
  "error can reach twice the band), true = star point tied to the DC-link midpoint (phases independent, " \
  "errors inside the band; zero-sequence current flows through motor.inductance_0)") \
X(Real, motor_inductance_0, "motor.inductance_0", parameter, fixed, "H", 1.4e-3, FMU_POSITIVE, FMU_INF, \
  "Zero-sequence inductance, used only with inverter.neutral_connected (assumed: 0.2 L_q, the order " \
  "of the leakage inductance of a surface-magnet machine)") \
X(Real, inverter_max_step, "inverter.max_step", parameter, fixed, "s", 5e-6, 1e-7, 1e-3, \
  "Largest internal step with the switching inverter; must be shorter than a current ramp across the band") \
\
X(Integer, control_mode, "control.mode", parameter, fixed, "", 1, 1, 3, \
  "Outermost loop closed: 1 = position (APR-ASR-ACR), 2 = speed (reference speed_ff), " \
  "3 = torque (current loop only, reference torque_ff)") \
X(Real, control_position_kp, "control.position_kp", parameter, tunable, "1/s", 60.0, FMU_POSITIVE, FMU_INF, \
  "Position loop (APR) proportional gain: rad/s of speed reference per rad of angle error") \
X(Real, control_position_ki, "control.position_ki", parameter, tunable, "1/s2", 300.0, 0.0, FMU_INF, \
  "Position loop (APR) integral gain") \
X(Real, control_speed_kp, "control.speed_kp", parameter, tunable, "A.s/rad", 6.97, FMU_POSITIVE, FMU_INF, \
  "Speed loop (ASR) proportional gain (symmetric-optimum style design, see documentation)") \
X(Real, control_speed_ki, "control.speed_ki", parameter, tunable, "A/rad", 580.5, 0.0, FMU_INF, \
  "Speed loop (ASR) integral gain") \
X(Real, control_current_kp, "control.current_kp", parameter, tunable, "1/A", 0.6805, FMU_POSITIVE, FMU_INF, \
  "Current loops (ACR, d and q) proportional gain (modulus optimum, see documentation)") \
X(Real, control_current_ki, "control.current_ki", parameter, tunable, "1/(A.s)", 69.03, 0.0, FMU_INF, \
  "Current loops (ACR, d and q) integral gain") \
X(Real, control_current_d_ref, "control.current_d_ref", parameter, tunable, "A", 0.0, -FMU_INF, FMU_INF, \
  "d-axis current reference (0: field-oriented control with i_d* = 0)") \
X(Real, limit_speed, "limit.speed", parameter, tunable, "rad/s", 600.0, FMU_POSITIVE, FMU_INF, \
  "Speed reference limit omega_max (Table 4)") \
X(Real, limit_current, "limit.current", parameter, tunable, "A", 42.0, FMU_POSITIVE, FMU_INF, \
  "Current reference limit I_max (Table 4): |i_q*| <= sqrt(I_max^2 - i_d*^2)") \
X(Real, limit_voltage, "limit.voltage", parameter, tunable, "V", 1200.0, FMU_POSITIVE, FMU_INF, \
  "Current-controller output limit per axis, in volts after K_v (ideal and averaged inverters); " \
  "the switching inverter is bounded by its DC link instead") \
X(Real, initial_current_q, "initial.current_q", parameter, fixed, "A", 0.0, -FMU_INF, FMU_INF, \
  "q current held at the start, with the integrators preset to hold it (e.g. against gravity)") \
X(Boolean, solver_exponential, "solver.exponential", parameter, fixed, "", 0, 0, 1, \
  "1: the current loops, the inverter and the winding, linear with constant coefficients between " \
  "the limits, taken exactly (exponential integrator ETDRK4, Cox and Matthews 2002) and the rest " \
  "explicitly, at steps of solver.step; RK4 at the inverter's time scale for a step in which a voltage " \
  "limit holds. The averaged and ideal inverters (the switching one keeps solver.method)") \
FMU_SOLVER_VARIABLES(X, 1, 1e-4, 1e-6, 1e-6) \
FMU_LAYER_VARIABLES(X)
/* clang-format on */

/* Direct feed-through (the ModelStructure's output dependencies): D(output, the value references of
 * the inputs it depends on at the same communication point), one row per such output; every other
 * output depends on no input (on the state alone). The union over the control modes and the
 * inverter models.
 * tests/models/test_dependencies.py perturbs each input and holds this table to what moves. */
#define LOOP_INPUTS VR_angle_ref, VR_angle, VR_speed, VR_torque_ff, VR_speed_ff
#define MODEL_FEEDTHROUGH(D) \
D(voltage_d, VR_angle) \
D(voltage_q, LOOP_INPUTS) \
D(power_electrical, LOOP_INPUTS) \
D(power_mechanical, VR_speed) \
D(current_a, VR_angle) \
D(current_b, VR_angle) \
D(current_c, VR_angle) \
D(current_error_max, LOOP_INPUTS) \
D(speed_ref, VR_angle_ref, VR_angle, VR_speed_ff) \
D(current_ref_q, LOOP_INPUTS)

#endif
