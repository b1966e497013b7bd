/* cueing: the variable table (the one source of truth for model.c, modelDescription.xml and the
 * documentation). The classical washout of Reid and Nahon (1985) and Nahon and Reid (1990): a
 * vehicle's specific force and angular rate at the occupant's head in, the platform's pose
 * reference out. Defaults: Meng's platform (its neutral height), moderate washout gains. */
#ifndef CUEING_VARIABLES_H
#define CUEING_VARIABLES_H

#define MODEL_IDENTIFIER cueing
#define MODEL_VERSION "0.1.0"
#define MODEL_DESCRIPTION                                                                          \
    "Motion cueing by the classical washout (Reid and Nahon 1985): the vehicle's specific force "  \
    "and angular rate at the head, scaled and limited, high-passed into platform translation and " \
    "rotation, and the low-passed specific force turned into rate-limited tilt; the pose "         \
    "reference with its exact first and second time derivatives"
#define MODEL_STOP_TIME 10.0
#define MODEL_COMMUNICATION_STEP 1e-3
#define MODEL_MAX_OUTPUT_DERIVATIVE_ORDER 2

/* The continuous state, fmu->s.x, by algorithm (Co-Simulation steps it itself, exactly: no shared
 * solver; Model Exchange gives its derivatives):
 *   classical: [0, 19) the filters' states, each channel's in a row: per translational axis x, y, z
 *     (3: the break filter's state, position, velocity), per rotational axis roll, pitch, yaw (2),
 *     per tilt axis pitch from x, roll from y (2: the low-passed specific force and its rate);
 *     [19, 21) the tilt's roll and pitch;
 *   MPC (mpc.c): [0, 6) the pose from neutral [m, rad], [6, 12) its rate, [12, 27) the perceived
 *     error's filter states (otoliths x, y, z: 2 each; canals roll, pitch, yaw: 3 each). */
#define MODEL_N_STATES 27
#define MODEL_SHARED_SOLVER 0
#define CUEING_TILT_STATE 19
/* Model Exchange too (fmi2_me.c), the MPC's solves its time events. */
#define MODEL_MODEL_EXCHANGE 1
#define MODEL_TIME_EVENTS 1
#define MODEL_STATE_NOMINALS 1 /* the MPC's perception states are far from 1 (model_state_nominals) */

/* Meng 2010's neutral height (../shared/params/meng2010.toml), the default neutral.z. */
#define CUEING_NEUTRAL_HEIGHT 1.689527733348906

/* The model-predictive cueing's discrete state (algorithm 2, mpc.c); its motion is fmu->s.x. */
typedef struct {
    double a[6];             /* the pose's acceleration until the next solve */
    double since;            /* [s] since the last solve (Co-Simulation) */
    double solved_at;        /* [s] the time of the last solve (Model Exchange: the next is a period on) */
    double trend_rate[6];    /* the vehicle's rate its prediction continues (mpc.prediction_trend), smoothed */
    int trend_known;         /* trend_rate holds a solve's rate (the first solve takes its rate as it is) */
    int iterations, softened;
} MpcState;

/* The guard on the cueing's own output (guard = true, guard.c): the reference it hands on. */
typedef struct {
    double motion[3][6]; /* the pose reference's value, rate and acceleration (over the next step) */
    int active;          /* 0: not started, 2: the guard's own motion handed on, 3: the cueing's passed on */
    int pending;         /* a step has ended and the guard has not yet taken its motion */
    double step;         /* [s] the step that ended */
    double taken_at;     /* [s] when the guard last took the cueing's motion (Model Exchange: the next is guard.period on) */
} GuardState;

typedef struct {
    double tilt[2][4];   /* roll and pitch of the tilt coordination: angle and its first three derivatives */
    double pose[6][4];   /* the pose's value and first three derivatives at the communication point */
    MpcState mpc;
    GuardState guard;
} ModelInternal;

/* One translational axis a (x, y, z) of the vehicle's specific force into platform position. */
#define TRANSLATION_VARIABLES(X, a, omega, limit) \
X(Real, translation_##a##_gain, "translation." #a ".gain", parameter, fixed, "1", 0.5, 0.0, FMU_INF, \
  "Scale of the specific force along " #a " (after gravity is taken off z)") \
X(Real, translation_##a##_limit, "translation." #a ".limit", parameter, fixed, "m/s2", limit, 0.0, FMU_INF, \
  "Largest scaled specific force along " #a " passed on (larger ones are clipped)") \
X(Real, translation_##a##_frequency, "translation." #a ".frequency", parameter, fixed, "rad/s", omega, FMU_POSITIVE, FMU_INF, \
  "omega_n of the second-order high-pass s^2 / (s^2 + 2 zeta omega_n s + omega_n^2) along " #a) \
X(Real, translation_##a##_damping, "translation." #a ".damping", parameter, fixed, "1", 1.0, FMU_POSITIVE, FMU_INF, \
  "zeta of that high-pass along " #a) \
X(Real, translation_##a##_break, "translation." #a ".break", parameter, fixed, "rad/s", 0.3, 0.0, FMU_INF, \
  "omega_b of the third order's first-order high-pass s / (s + omega_b) along " #a " (0: second order)")

/* One rotational axis (roll, pitch, yaw) of the vehicle's angular rate into platform angle. */
#define ROTATION_VARIABLES(X, r, axis) \
X(Real, rotation_##r##_gain, "rotation." #r ".gain", parameter, fixed, "1", 0.5, 0.0, FMU_INF, \
  "Scale of the angular rate about " #axis) \
X(Real, rotation_##r##_limit, "rotation." #r ".limit", parameter, fixed, "rad/s", 0.5, 0.0, FMU_INF, \
  "Largest scaled angular rate about " #axis " passed on (larger ones are clipped)") \
X(Real, rotation_##r##_frequency, "rotation." #r ".frequency", parameter, fixed, "rad/s", 1.0, FMU_POSITIVE, FMU_INF, \
  "omega_n of the second-order high-pass of the rate about " #axis ", integrated into the angle") \
X(Real, rotation_##r##_damping, "rotation." #r ".damping", parameter, fixed, "1", 1.0, FMU_POSITIVE, FMU_INF, \
  "zeta of that high-pass about " #axis)

#define POSE_VARIABLES(X, dof, unit, offset, what) \
X(Real, pose_ref_##dof, "pose_ref." #dof, output, continuous, unit, offset, -FMU_INF, FMU_INF, \
  "Reference pose of the platform, " what " (neutral plus the washed-out motion)") \
X(Real, pose_ref_rate_##dof, "pose_ref_rate." #dof, output, continuous, unit "/s", 0.0, -FMU_INF, FMU_INF, \
  "Rate of pose_ref." #dof ", exact (for masters that give no input derivatives: wired to the mechanics' " \
  "pose_ref_rate." #dof ")") \
X(Real, neutral_##dof, "neutral." #dof, parameter, fixed, unit, offset, -FMU_INF, FMU_INF, \
  "The platform's neutral pose, " what ": where the washout returns it")

/* The vehicle's motion the cueing took (its input, or vehicle.file's column): what a run records to
 * judge the platform's motion against (cosim.platform.cueing). */
#define VEHICLE_VARIABLES(X, quantity, a, unit, start, what) \
X(Real, vehicle_##quantity##_##a, "vehicle." #quantity "." #a, output, continuous, unit, start, -FMU_INF, FMU_INF, \
  "The vehicle's " what " at the head that the cueing took (its input, or vehicle.file's column)")

/* clang-format off */
#define MODEL_VARIABLES(X) \
X(Real, specific_force_x, "specific_force.x", input, continuous, "m/s2", 0.0, -FMU_INF, FMU_INF, \
  "Vehicle's specific force at the head, x forward (vehicle frame: x forward, y left, z up)") \
X(Real, specific_force_y, "specific_force.y", input, continuous, "m/s2", 0.0, -FMU_INF, FMU_INF, \
  "Vehicle's specific force at the head, y left") \
X(Real, specific_force_z, "specific_force.z", input, continuous, "m/s2", 9.81, -FMU_INF, FMU_INF, \
  "Vehicle's specific force at the head, z up (+g at rest)") \
X(Real, angular_rate_x, "angular_rate.x", input, continuous, "rad/s", 0.0, -FMU_INF, FMU_INF, \
  "Vehicle's angular rate about x (roll)") \
X(Real, angular_rate_y, "angular_rate.y", input, continuous, "rad/s", 0.0, -FMU_INF, FMU_INF, \
  "Vehicle's angular rate about y (pitch)") \
X(Real, angular_rate_z, "angular_rate.z", input, continuous, "rad/s", 0.0, -FMU_INF, FMU_INF, \
  "Vehicle's angular rate about z (yaw)") \
POSE_VARIABLES(X, x, "m", 0.0, "x (surge)") \
POSE_VARIABLES(X, y, "m", 0.0, "y (sway)") \
POSE_VARIABLES(X, z, "m", CUEING_NEUTRAL_HEIGHT, "z (heave)") \
POSE_VARIABLES(X, roll, "rad", 0.0, "roll") \
POSE_VARIABLES(X, pitch, "rad", 0.0, "pitch") \
POSE_VARIABLES(X, yaw, "rad", 0.0, "yaw") \
VEHICLE_VARIABLES(X, specific_force, x, "m/s2", 0.0, "specific force along x") \
VEHICLE_VARIABLES(X, specific_force, y, "m/s2", 0.0, "specific force along y") \
VEHICLE_VARIABLES(X, specific_force, z, "m/s2", 9.81, "specific force along z") \
VEHICLE_VARIABLES(X, angular_rate, x, "rad/s", 0.0, "angular rate about x") \
VEHICLE_VARIABLES(X, angular_rate, y, "rad/s", 0.0, "angular rate about y") \
VEHICLE_VARIABLES(X, angular_rate, z, "rad/s", 0.0, "angular rate about z") \
X(Real, tilt_roll, "tilt.roll", output, continuous, "rad", 0.0, -FMU_INF, FMU_INF, \
  "The roll of the tilt coordination (part of pose_ref.roll): gravity standing for sustained sway") \
X(Real, tilt_pitch, "tilt.pitch", output, continuous, "rad", 0.0, -FMU_INF, FMU_INF, \
  "The pitch of the tilt coordination (part of pose_ref.pitch): gravity standing for sustained surge") \
TRANSLATION_VARIABLES(X, x, 2.0, 5.0) \
TRANSLATION_VARIABLES(X, y, 2.0, 5.0) \
TRANSLATION_VARIABLES(X, z, 4.0, 5.0) \
ROTATION_VARIABLES(X, roll, x) \
ROTATION_VARIABLES(X, pitch, y) \
ROTATION_VARIABLES(X, yaw, z) \
X(Real, tilt_gain, "tilt.gain", parameter, fixed, "1", 0.5, 0.0, FMU_INF, \
  "Scale of the specific force along x and y that tilt coordination renders (0: no tilt)") \
X(Real, tilt_frequency, "tilt.frequency", parameter, fixed, "rad/s", 2.0, FMU_POSITIVE, FMU_INF, \
  "omega_n of the second-order low-pass omega_n^2 / (s^2 + 2 zeta omega_n s + omega_n^2) of that force") \
X(Real, tilt_damping, "tilt.damping", parameter, fixed, "1", 1.0, FMU_POSITIVE, FMU_INF, "zeta of that low-pass") \
X(Real, tilt_rate_limit, "tilt.rate_limit", parameter, fixed, "rad/s", 0.04363323129985824, FMU_POSITIVE, FMU_INF, \
  "Largest tilt rate (default 2.5 deg/s: a margin below the 3 deg/s at which the semicircular canals notice a roll, " \
  "for the platform, whose drives lag the reference, turns up to about 12 % faster than commanded); the tilt " \
  "vector's, roll and pitch together, unless tilt.pitch_rate_limit gives pitch its own") \
X(Real, tilt_pitch_rate_limit, "tilt.pitch_rate_limit", parameter, fixed, "rad/s", 0.0, 0.0, FMU_INF, \
  "Largest tilt rate in pitch (0: tilt.rate_limit's, a circle). Else the tilt's rate within the ellipse " \
  "(roll'/tilt.rate_limit)^2 + (pitch'/tilt.pitch_rate_limit)^2 <= 1: the canals notice a pitch at 3.6 deg/s, " \
  "a roll at 3 deg/s, so pitch may take 3 deg/s at the same margin as roll's 2.5") \
X(Real, tilt_limit, "tilt.limit", parameter, fixed, "rad", 0.349065850398866, 0.0, 1.5707963267948966, \
  "Largest tilt angle (default 20 deg)") \
X(String, vehicle_file, "vehicle.file", parameter, fixed, "", 0, 0, 0, \
  "CSV file of the vehicle's motion (empty: the inputs). First line: 'time' and any of specific_force.x, " \
  "specific_force.y, specific_force.z, angular_rate.x, angular_rate.y, angular_rate.z, comma separated; then rows " \
  "of numbers in s, m/s2 and rad/s with time increasing, linear between them; lines starting with # are skipped. A " \
  "column given there replaces its input; before the first and after the last row the end values are held.") \
X(Integer, vehicle_rows, "vehicle.rows", output, discrete, "", 0, -FMU_INF, FMU_INF, "Rows read from vehicle.file") \
X(Real, gravity, "gravity", parameter, fixed, "m/s2", 9.81, FMU_POSITIVE, FMU_INF, \
  "Gravity: taken off the vertical specific force, and what tilt turns into specific force; the platform's, one " \
  "for every FMU (the master sets it from the mechanics' environment.gravity_x/y/z; default as the mechanics')") \
MPC_VARIABLES(X) \
GUARD_VARIABLES(X) \
FMU_LAYER_VARIABLES(X)
/* clang-format on */

/* The platform's joints (the mechanics' own parameters of these names, its computed layout): what
 * the MPC keeps in its envelope. Defaults: Meng's platform (the mechanics' geometry.layout 1). */
#define JOINT_VARIABLES(X, i, bx, by, ax, ay) \
X(Real, geometry_base_joint_##i##_x, "geometry.base_joint[" #i "].x", parameter, fixed, "m", bx, -FMU_INF, FMU_INF, "Lower joint b_" #i ", base frame, x (the MPC's envelope)") \
X(Real, geometry_base_joint_##i##_y, "geometry.base_joint[" #i "].y", parameter, fixed, "m", by, -FMU_INF, FMU_INF, "Lower joint b_" #i ", y") \
X(Real, geometry_base_joint_##i##_z, "geometry.base_joint[" #i "].z", parameter, fixed, "m", 0.0, -FMU_INF, FMU_INF, "Lower joint b_" #i ", z") \
X(Real, geometry_platform_joint_##i##_x, "geometry.platform_joint[" #i "].x", parameter, fixed, "m", ax, -FMU_INF, FMU_INF, "Upper joint a_" #i ", platform frame, x (the MPC's envelope)") \
X(Real, geometry_platform_joint_##i##_y, "geometry.platform_joint[" #i "].y", parameter, fixed, "m", ay, -FMU_INF, FMU_INF, "Upper joint a_" #i ", y") \
X(Real, geometry_platform_joint_##i##_z, "geometry.platform_joint[" #i "].z", parameter, fixed, "m", 0.0, -FMU_INF, FMU_INF, "Upper joint a_" #i ", z")

#define MPC_WEIGHT(X, name, unit, value, what) \
X(Real, mpc_weight_##name, "mpc.weight." #name, parameter, fixed, unit, value, 0.0, FMU_INF, what)

#define MPC_PERCEIVED(X, quantity, a, unit) \
X(Real, mpc_perceived_error_##quantity##_##a, "mpc.perceived_error." #quantity "." #a, output, continuous, unit, 0.0, \
  -FMU_INF, FMU_INF, "MPC: the " #quantity " along " #a " the occupant perceives less what the vehicle's would (the " \
  "vestibular models of its prediction, on its linearised platform motion)")

/* clang-format off */
#define MPC_VARIABLES(X) \
X(Integer, algorithm, "algorithm", parameter, fixed, "", 1, 1, 2, \
  "1: the classical washout; 2: model-predictive cueing (MPC: the perceived error least over mpc.horizon, the " \
  "platform's legs within limit.* at its joints geometry.*)") \
X(Real, mpc_period, "mpc.period", parameter, fixed, "s", 0.02, FMU_POSITIVE, FMU_INF, \
  "MPC: time between two solves (each a QP over the horizon; the acceleration it gives is held until the next)") \
X(Real, mpc_horizon, "mpc.horizon", parameter, fixed, "s", 3.0, FMU_POSITIVE, FMU_INF, \
  "MPC: how far it looks ahead (12 intervals, the first mpc.period long, growing evenly)") \
X(Real, mpc_preview, "mpc.preview", parameter, fixed, "s", 0.0, 0.0, FMU_INF, \
  "MPC: how far ahead of now it reads a recorded drive (vehicle.file): foresight, which a live drive does not give " \
  "(0: none, as live); the motion beyond it is predicted from the last it read (mpc.prediction_decay)") \
X(Real, mpc_prediction_decay, "mpc.prediction_decay", parameter, fixed, "s", 0.0, 0.0, FMU_INF, \
  "MPC: the vehicle's motion beyond what it reads, predicted from the last it read: held (0), or returning to rest " \
  "(no acceleration, no rotation) with this time constant") \
X(Real, mpc_prediction_trend, "mpc.prediction_trend", parameter, fixed, "s", 0.0, 0.0, FMU_INF, \
  "MPC: the vehicle's motion beyond what it reads continued along its trend there (its rate over the last " \
  "mpc.period, from the past alone as a live feed shows it), the trend fading with this time constant (0: none)") \
X(Real, mpc_trend_smoothing, "mpc.trend_smoothing", parameter, fixed, "s", 0.0, 0.0, FMU_INF, \
  "MPC: time constant of a first-order low-pass, updated at each solve, on the rate the trend continues (0: the " \
  "rate as it comes; a noisy feed's rate needs it, or the trend predicts the noise on)") \
MPC_WEIGHT(X, specific_force, "s4/m2", 1.0, "MPC: weight of the perceived specific force's error (per axis)") \
MPC_WEIGHT(X, angular_rate, "s2/rad2", 30.0, "MPC: weight of the perceived angular rate's error (per axis)") \
MPC_WEIGHT(X, position, "1/m2", 1.0, "MPC: weight of the platform's translation from neutral (the washout)") \
MPC_WEIGHT(X, angle, "1/rad2", 1.0, "MPC: weight of its rotation from neutral") \
MPC_WEIGHT(X, velocity, "s2/m2", 1.0, "MPC: weight of its velocity") \
MPC_WEIGHT(X, angular_velocity, "s2/rad2", 1.0, "MPC: weight of its angular velocity") \
MPC_WEIGHT(X, acceleration, "s4/m2", 0.1, "MPC: weight of its acceleration") \
MPC_WEIGHT(X, angular_acceleration, "s4/rad2", 0.01, "MPC: weight of its angular acceleration") \
X(Real, mpc_acceleration_limit, "mpc.acceleration_limit", parameter, fixed, "m/s2", 6.0, FMU_POSITIVE, FMU_INF, \
  "MPC: largest acceleration along x, y, z it commands") \
X(Real, mpc_angular_acceleration_limit, "mpc.angular_acceleration_limit", parameter, fixed, "rad/s2", 3.0, FMU_POSITIVE, \
  FMU_INF, "MPC: largest angular acceleration it commands") \
MPC_PERCEIVED(X, specific_force, x, "m/s2") MPC_PERCEIVED(X, specific_force, y, "m/s2") \
MPC_PERCEIVED(X, specific_force, z, "m/s2") MPC_PERCEIVED(X, angular_rate, x, "rad/s") \
MPC_PERCEIVED(X, angular_rate, y, "rad/s") MPC_PERCEIVED(X, angular_rate, z, "rad/s") \
X(Integer, mpc_iterations, "mpc.iterations", output, discrete, "", 0, -FMU_INF, FMU_INF, \
  "MPC: the active-set iterations of the latest solve (DAQP)") \
X(Integer, mpc_softened, "mpc.softened", output, discrete, "", 0, -FMU_INF, FMU_INF, \
  "MPC: solves so far whose answer broke a limit (the stroke less the margin, a leg's speed, a joint's tilt, the tilt " \
  "rate) by more than 1e-3 of its units: its constraints are soft, so that a solve always has an answer") \
JOINT_VARIABLES(X, 1, 1.0897247358851685, -0.15, 0.4834652370381326, -0.637386354243376) \
JOINT_VARIABLES(X, 2, 1.0897247358851685, 0.15, 0.48346523703813243, 0.6373863542433761) \
JOINT_VARIABLES(X, 3, -0.4149585573749186, 1.0187293044088437, 0.3102601562812446, 0.7373863542433761) \
JOINT_VARIABLES(X, 4, -0.6747661785102501, 0.8687293044088438, -0.7937253933193772, 0.10000000000000014) \
JOINT_VARIABLES(X, 5, -0.6747661785102494, -0.8687293044088441, -0.7937253933193773, -0.09999999999999995) \
JOINT_VARIABLES(X, 6, -0.41495855737491816, -1.018729304408844, 0.3102601562812448, -0.7373863542433761) \
X(Real, limit_leg_length_min, "limit.leg_length_min", parameter, fixed, "m", 1.535, 0.0, FMU_INF, "Shortest leg of the stroke (the mechanics')") \
X(Real, limit_leg_length_max, "limit.leg_length_max", parameter, fixed, "m", 2.2, 0.0, FMU_INF, "Longest leg of the stroke (the mechanics')") \
X(Real, limit_stroke_margin, "limit.stroke_margin", parameter, fixed, "m", 0.01, 0.0, FMU_INF, \
  "The stroke the MPC may use is limit.leg_length_min/max less this at each end (the mechanics')") \
X(Real, limit_leg_velocity, "limit.leg_velocity", parameter, fixed, "m/s", 1.0, FMU_POSITIVE, FMU_INF, "A leg's largest extension rate (the mechanics')") \
X(Real, limit_joint_angle, "limit.joint_angle", parameter, fixed, "rad", 0.3490658503988659, 0.0, 3.2, \
  "Largest tilt of a leg from its neutral direction at either joint (the mechanics')")
/* clang-format on */

#define GUARD_HELD(X, kind, what) \
X(Real, guard_held_##kind, "guard.held." #kind, output, discrete, "1", 0.0, 0.0, FMU_INF, "guard: steps " what)

/* clang-format off */
#define GUARD_VARIABLES(X) \
X(Boolean, guard, "guard", parameter, fixed, "", 0, 0, 1, \
  "Hold the pose reference within the platform's envelope: every leg within limit.leg_length_min/max " \
  "less limit.stroke_margin, every joint within limit.joint_angle, the legs' speeds and accelerations within " \
  "limit.leg_velocity and limit.leg_acceleration, braking in time within guard.*_max; the motion passed on as it is " \
  "while it keeps there (as cosim run's master guards it: on for a tool that runs this FMU without it)") \
X(Real, guard_period, "guard.period", parameter, fixed, "s", 1e-3, FMU_POSITIVE, FMU_INF, \
  "guard: Model Exchange's guard steps, a time event each this far apart, as a co-simulation's steps of it (a " \
  "scene's step; Co-Simulation: its communication steps)") \
X(Real, guard_velocity_max, "guard.velocity_max", parameter, fixed, "m/s", 0.25, FMU_POSITIVE, FMU_INF, \
  "guard: the reference's largest speed along x, y, z where the guard holds it (a scene's [live] velocity_max)") \
X(Real, guard_angular_velocity_max, "guard.angular_velocity_max", parameter, fixed, "rad/s", 0.5, FMU_POSITIVE, FMU_INF, \
  "guard: its largest roll, pitch and yaw rate there") \
X(Real, guard_acceleration_max, "guard.acceleration_max", parameter, fixed, "m/s2", 2.0, FMU_POSITIVE, FMU_INF, \
  "guard: its largest acceleration along x, y, z there (its braking)") \
X(Real, guard_angular_acceleration_max, "guard.angular_acceleration_max", parameter, fixed, "rad/s2", 4.0, FMU_POSITIVE, \
  FMU_INF, "guard: its largest angular acceleration there") \
X(Real, limit_leg_acceleration, "limit.leg_acceleration", parameter, fixed, "m/s2", 10.0, 0.0, FMU_INF, \
  "guard: a leg's largest acceleration (the mechanics')") \
GUARD_HELD(X, stroke, "on which a leg's stroke held the reference back") \
GUARD_HELD(X, joint, "on which a joint's tilt held it back") \
GUARD_HELD(X, leg_velocity, "on which a leg's speed held it back") \
GUARD_HELD(X, leg_acceleration, "on which a leg's acceleration held it back") \
GUARD_HELD(X, return, "spent bringing it back into the envelope from outside")
/* clang-format on */

/* Direct feed-through: the vehicle's motion taken, from its input; the rotations' rates, whose
 * high-pass passes the angular rate straight into the angle's rate (the pose follows the filters'
 * states; the inputs reach its derivatives, not its value). */
#define MODEL_FEEDTHROUGH(D) \
D(vehicle_specific_force_x, VR_specific_force_x) D(vehicle_specific_force_y, VR_specific_force_y) \
D(vehicle_specific_force_z, VR_specific_force_z) D(vehicle_angular_rate_x, VR_angular_rate_x) \
D(vehicle_angular_rate_y, VR_angular_rate_y) D(vehicle_angular_rate_z, VR_angular_rate_z) \
D(pose_ref_rate_roll, VR_angular_rate_x) D(pose_ref_rate_pitch, VR_angular_rate_y) D(pose_ref_rate_yaw, VR_angular_rate_z)

#endif
