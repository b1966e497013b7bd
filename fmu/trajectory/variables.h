/* trajectory: the variable table (the one source of truth for model.c, modelDescription.xml and
 * the documentation). Defaults: the Meng 2010 platform held at its neutral pose, no load. */
#ifndef TRAJECTORY_VARIABLES_H
#define TRAJECTORY_VARIABLES_H

#define MODEL_IDENTIFIER trajectory
#define MODEL_VERSION "0.1.0"
#define MODEL_DESCRIPTION                                                                          \
    "Signal source of a scene: the reference pose of the platform per degree of freedom (offset, " \
    "sines, steps, ramps and a CSV table) and the external wrench on it (rectangular pulses), "    \
    "with their exact time derivatives for the master's input extrapolation"
#define MODEL_STOP_TIME 10.0
#define MODEL_COMMUNICATION_STEP 1e-3
#define MODEL_N_STATES 0
/* Model Exchange too (fmi2_me.c): no states; the load pulses' edges are its time events. */
#define MODEL_MODEL_EXCHANGE 1
#define MODEL_TIME_EVENTS 1
#define MODEL_MAX_OUTPUT_DERIVATIVE_ORDER 2

/* Neutral height of the Meng 2010 platform (../shared/params/meng2010.toml), the default z offset. */
#define TRAJECTORY_NEUTRAL_HEIGHT 1.689527733348906

typedef struct {
    /* The signals are functions of time alone (the table lives in the model data); this holds each
     * pose coordinate's first three time derivatives at the outputs' time, computed with its value,
     * for fmi2GetRealOutputDerivatives (of pose_ref and of its rate pose_ref_rate). */
    double derivatives[6][3];
} ModelInternal;

/* The signal of one pose coordinate: offset + 3 sines + 2 steps + 2 ramps (+ its table column). */
#define SINE_VARIABLES(X, dof, k, unit) \
X(Real, dof##_sine##k##_amplitude, #dof ".sine[" #k "].amplitude", parameter, fixed, unit, 0.0, -FMU_INF, FMU_INF, \
  "Amplitude of sine " #k " of " #dof ": A sin(2 pi f t + phase)") \
X(Real, dof##_sine##k##_frequency, #dof ".sine[" #k "].frequency", parameter, fixed, "Hz", 0.0, 0.0, FMU_INF, \
  "Frequency of sine " #k " of " #dof) \
X(Real, dof##_sine##k##_phase, #dof ".sine[" #k "].phase", parameter, fixed, "rad", 0.0, -FMU_INF, FMU_INF, \
  "Phase of sine " #k " of " #dof)

#define STEP_VARIABLES(X, dof, k, unit) \
X(Real, dof##_step##k##_time, #dof ".step[" #k "].time", parameter, fixed, "s", 0.0, -FMU_INF, FMU_INF, \
  "Time of step " #k " of " #dof) \
X(Real, dof##_step##k##_height, #dof ".step[" #k "].height", parameter, fixed, unit, 0.0, -FMU_INF, FMU_INF, \
  "Height of step " #k " of " #dof " (added from its time on)")

#define RAMP_VARIABLES(X, dof, k, rate_unit) \
X(Real, dof##_ramp##k##_start, #dof ".ramp[" #k "].start", parameter, fixed, "s", 0.0, -FMU_INF, FMU_INF, \
  "Start of ramp " #k " of " #dof) \
X(Real, dof##_ramp##k##_end, #dof ".ramp[" #k "].end", parameter, fixed, "s", 0.0, -FMU_INF, FMU_INF, \
  "End of ramp " #k " of " #dof " (the value is held after it)") \
X(Real, dof##_ramp##k##_slope, #dof ".ramp[" #k "].slope", parameter, fixed, rate_unit, 0.0, -FMU_INF, FMU_INF, \
  "Slope of ramp " #k " of " #dof)

#define DOF_VARIABLES(X, dof, unit, rate_unit, offset, what) \
X(Real, pose_ref_##dof, "pose_ref." #dof, output, continuous, unit, 0.0, -FMU_INF, FMU_INF, \
  "Reference pose of the platform, " what) \
X(Real, pose_ref_rate_##dof, "pose_ref_rate." #dof, output, continuous, rate_unit, 0.0, -FMU_INF, FMU_INF, \
  "Rate of pose_ref." #dof ", exact (for masters that give no input derivatives: wired to the mechanics' " \
  "pose_ref_rate." #dof ")") \
X(Real, dof##_offset, #dof ".offset", parameter, fixed, unit, offset, -FMU_INF, FMU_INF, "Constant part of " #dof) \
SINE_VARIABLES(X, dof, 1, unit) SINE_VARIABLES(X, dof, 2, unit) SINE_VARIABLES(X, dof, 3, unit) \
STEP_VARIABLES(X, dof, 1, unit) STEP_VARIABLES(X, dof, 2, unit) \
RAMP_VARIABLES(X, dof, 1, rate_unit) RAMP_VARIABLES(X, dof, 2, rate_unit)

/* One component of the external wrench: two rectangular pulses (value for start <= t <= end). */
#define PULSE_VARIABLES(X, kind, axis, k, unit) \
X(Real, load_##kind##_##axis##_pulse##k##_value, "load." #kind "." #axis ".pulse[" #k "].value", parameter, fixed, \
  unit, 0.0, -FMU_INF, FMU_INF, "Height of pulse " #k " of load." #kind "." #axis) \
X(Real, load_##kind##_##axis##_pulse##k##_start, "load." #kind "." #axis ".pulse[" #k "].start", parameter, fixed, \
  "s", 0.0, -FMU_INF, FMU_INF, "Start of pulse " #k " of load." #kind "." #axis) \
X(Real, load_##kind##_##axis##_pulse##k##_end, "load." #kind "." #axis ".pulse[" #k "].end", parameter, fixed, \
  "s", 0.0, -FMU_INF, FMU_INF, "End of pulse " #k " of load." #kind "." #axis " (inclusive)") \
X(Integer, load_##kind##_##axis##_pulse##k##_frame, "load." #kind "." #axis ".pulse[" #k "].frame", parameter, \
  fixed, "", 1, 1, 2, "Frame of pulse " #k ": 1 = base (output load." #kind "." #axis "), 2 = platform, a " \
  "follower load that turns with it (output load.body." #kind "." #axis ")")

#define WRENCH_VARIABLES(X, kind, axis, unit, what) \
X(Real, load_##kind##_##axis, "load." #kind "." #axis, output, continuous, unit, 0.0, -FMU_INF, FMU_INF, \
  "External " what " on the platform, base frame (the sum of its base-frame pulses)") \
X(Real, load_body_##kind##_##axis, "load.body." #kind "." #axis, output, continuous, unit, 0.0, -FMU_INF, FMU_INF, \
  "External " what " on the platform, platform frame (the sum of its platform-frame pulses)") \
PULSE_VARIABLES(X, kind, axis, 1, unit) PULSE_VARIABLES(X, kind, axis, 2, unit)

/* clang-format off */
#define MODEL_VARIABLES(X) \
DOF_VARIABLES(X, x, "m", "m/s", 0.0, "x (surge)") \
DOF_VARIABLES(X, y, "m", "m/s", 0.0, "y (sway)") \
DOF_VARIABLES(X, z, "m", "m/s", TRAJECTORY_NEUTRAL_HEIGHT, "z (heave)") \
DOF_VARIABLES(X, roll, "rad", "rad/s", 0.0, "roll") \
DOF_VARIABLES(X, pitch, "rad", "rad/s", 0.0, "pitch") \
DOF_VARIABLES(X, yaw, "rad", "rad/s", 0.0, "yaw") \
X(String, table_file, "table.file", parameter, fixed, "", 0, 0, 0, \
  "CSV file added to the pose (empty: none). First line: 'time' and any of x, y, z, roll, pitch, " \
  "yaw, comma separated; then rows of numbers in s, m and rad with time increasing; lines starting " \
  "with # are skipped. Before its first and after its last row the end values are held.") \
X(Integer, table_interpolation, "table.interpolation", parameter, fixed, "", 2, 1, 2, \
  "Between the table's rows: 1 = linear, 2 = cubic Hermite with finite-difference slopes " \
  "(continuous rate, for the drives' reference feedforward)") \
X(Integer, table_rows, "table.rows", output, discrete, "", 0, -FMU_INF, FMU_INF, "Rows read from table.file") \
WRENCH_VARIABLES(X, force, x, "N", "force, x") \
WRENCH_VARIABLES(X, force, y, "N", "force, y") \
WRENCH_VARIABLES(X, force, z, "N", "force, z") \
WRENCH_VARIABLES(X, torque, x, "N.m", "torque, x") \
WRENCH_VARIABLES(X, torque, y, "N.m", "torque, y") \
WRENCH_VARIABLES(X, torque, z, "N.m", "torque, z") \
FMU_LAYER_VARIABLES(X)
/* clang-format on */

/* Direct feed-through: none (the trajectory has no inputs; its outputs are functions of time). */
#define MODEL_FEEDTHROUGH(D)

#endif
