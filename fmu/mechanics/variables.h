/* mechanics: the variable table (the one source of truth for model.c, modelDescription.xml and the
 * documentation). Defaults equal ../shared/params/meng2010.toml. */
#ifndef MECHANICS_VARIABLES_H
#define MECHANICS_VARIABLES_H

#include "platform.h"

#define MODEL_IDENTIFIER mechanics
#define MODEL_VERSION "0.1.0"
#define MODEL_DESCRIPTION                                                                          \
    "Stewart platform multi-body dynamics (Meng et al. 2010, Section 2, Kane's method): moving "   \
    "platform, the two parts of each actuator and the motor systems carried by the legs"
#define MODEL_STOP_TIME 1.0
#define MODEL_COMMUNICATION_STEP 1e-3

/* pose and twist (13, see platform.h) and the energy accounts: drive, transmission loss,
 * friction loss, load (4) */
#define MODEL_N_STATES 17
/* Model Exchange too (fmi2_me.c): the importer's solver integrates these states. */
#define MODEL_MODEL_EXCHANGE 1
/* The energies and powers (an evaluation of the dynamics of their own) computed when read. */
#define MODEL_LAZY_OUTPUTS 1

typedef struct {
    Platform platform;                 /* geometry and mass properties, set at initialization */
    int out_of_stroke[PLATFORM_LEGS];  /* reported, so a warning is logged once per excursion */
    int past_joint_limit[PLATFORM_LEGS];
    double neutral_axis[PLATFORM_LEGS][3]; /* leg axes at the neutral pose, for joint angles */
    /* the inputs as the outputs were computed with them (a step's extrapolated inputs at its end),
     * which the energies and powers, computed when read, take too */
    double output_torque[PLATFORM_LEGS], output_force[PLATFORM_LEGS], output_wrench[6];
    PlatformDriveSlopes output_slopes;
} ModelInternal;

/* One leg's ports; i is the leg number 1..6. */
#define LEG_VARIABLES(X, i) \
X(Real, leg##i##_torque, "leg[" #i "].torque", input, continuous, "N.m", 0.0, -FMU_INF, FMU_INF, \
  "Motor electromagnetic torque on the screw of leg " #i " (PMSM drive)") \
X(Real, leg##i##_force, "leg[" #i "].force", input, continuous, "N", 0.0, -FMU_INF, FMU_INF, \
  "Axial force of a direct drive on leg " #i " (linear motor); added to the screw's force") \
X(Real, leg##i##_torque_speed_slope, "leg[" #i "].torque_speed_slope", input, continuous, "N.m.s/rad", 0.0, -FMU_INF, FMU_INF, \
  "Interface Jacobian of the drive on leg " #i ": d torque / d speed (the drive's output torque_speed_slope); " \
  "the screw feels torque + slope (speed - speed_seen), so the coupling is implicit in the drive's damping") \
X(Real, leg##i##_speed_seen, "leg[" #i "].speed_seen", input, continuous, "rad/s", 0.0, -FMU_INF, FMU_INF, \
  "The motor speed the drive on leg " #i " was given over the step (wired from this FMU's own leg[" #i "].speed)") \
X(Real, leg##i##_force_velocity_slope, "leg[" #i "].force_velocity_slope", input, continuous, "N.s/m", 0.0, -FMU_INF, FMU_INF, \
  "Interface Jacobian of the direct drive on leg " #i ": d force / d velocity (the linear motor's output " \
  "force_velocity_slope); the leg feels force + slope (velocity - velocity_seen)") \
X(Real, leg##i##_velocity_seen, "leg[" #i "].velocity_seen", input, continuous, "m/s", 0.0, -FMU_INF, FMU_INF, \
  "The extension rate the direct drive on leg " #i " was given over the step (wired from leg[" #i "].velocity)") \
X(Real, leg##i##_length, "leg[" #i "].length", output, continuous, "m", 0.0, -FMU_INF, FMU_INF, \
  "Length of leg " #i ", lower to upper joint (Eq 2)") \
X(Real, leg##i##_velocity, "leg[" #i "].velocity", output, continuous, "m/s", 0.0, -FMU_INF, FMU_INF, \
  "Extension rate of leg " #i) \
X(Real, leg##i##_angle, "leg[" #i "].angle", output, continuous, "rad", 0.0, -FMU_INF, FMU_INF, \
  "Motor angle of leg " #i ": screw ratio times (length - neutral length)") \
X(Real, leg##i##_speed, "leg[" #i "].speed", output, continuous, "rad/s", 0.0, -FMU_INF, FMU_INF, \
  "Motor speed of leg " #i ": screw ratio times the extension rate (Eq 4)") \
X(Real, leg##i##_length_ref, "leg[" #i "].length_ref", output, continuous, "m", 0.0, -FMU_INF, FMU_INF, \
  "Length of leg " #i " at pose_ref (inverse kinematics)") \
X(Real, leg##i##_angle_ref, "leg[" #i "].angle_ref", output, continuous, "rad", 0.0, -FMU_INF, FMU_INF, \
  "Motor angle of leg " #i " at pose_ref") \
X(Real, leg##i##_velocity_ref, "leg[" #i "].velocity_ref", output, continuous, "m/s", 0.0, -FMU_INF, FMU_INF, \
  "Extension rate of leg " #i " at pose_ref moving at the rate of pose_ref (its inputs' derivatives): the rate " \
  "of leg[" #i "].length_ref") \
X(Real, leg##i##_speed_ref, "leg[" #i "].speed_ref", output, continuous, "rad/s", 0.0, -FMU_INF, FMU_INF, \
  "Motor speed of leg " #i " at pose_ref: screw ratio times velocity_ref") \
X(Real, leg##i##_torque_applied, "leg[" #i "].torque_applied", output, continuous, "N.m", 0.0, -FMU_INF, FMU_INF, \
  "Motor torque the screw of leg " #i " feels: torque + torque_speed_slope (speed - speed_seen), the drive's " \
  "torque corrected by its interface Jacobian (the torque input itself without one)") \
X(Real, leg##i##_force_applied, "leg[" #i "].force_applied", output, continuous, "N", 0.0, -FMU_INF, FMU_INF, \
  "Direct-drive force leg " #i " feels: force + force_velocity_slope (velocity - velocity_seen)")

/* What a drive designer needs of leg i, at the start pose (computed once, at initialization): the
 * leg's inertia with the other legs held, M_ii of the joint-space mass matrix J^-T M J^-1, and the
 * axial force that holds the start pose against gravity. The stroke is limit.leg_length_min/max. */
#define LEG_PLANT_VARIABLES(X, i) \
X(Real, leg##i##_plant_inertia, "leg[" #i "].plant.inertia", output, discrete, "kg", 0.0, -FMU_INF, FMU_INF, \
  "Inertia of leg " #i " along its axis with the other legs held, at the start pose (motor systems included when on)") \
X(Real, leg##i##_plant_static_force, "leg[" #i "].plant.static_force", output, discrete, "N", 0.0, -FMU_INF, FMU_INF, \
  "Axial force of leg " #i " that holds the start pose (positive: pushing; K_FT times the motor torque for a screw)")

#define POSE_VARIABLES(X, prefix, field_prefix, causality, variability, what) \
X(Real, field_prefix##x, prefix ".x", causality, variability, "m", 0.0, -FMU_INF, FMU_INF, what ", x (surge)") \
X(Real, field_prefix##y, prefix ".y", causality, variability, "m", 0.0, -FMU_INF, FMU_INF, what ", y (sway)") \
X(Real, field_prefix##z, prefix ".z", causality, variability, "m", NEUTRAL_HEIGHT, -FMU_INF, FMU_INF, what ", z (heave)") \
X(Real, field_prefix##roll, prefix ".roll", causality, variability, "rad", 0.0, -FMU_INF, FMU_INF, what ", roll") \
X(Real, field_prefix##pitch, prefix ".pitch", causality, variability, "rad", 0.0, -FMU_INF, FMU_INF, what ", pitch") \
X(Real, field_prefix##yaw, prefix ".yaw", causality, variability, "rad", 0.0, -FMU_INF, FMU_INF, what ", yaw")

/* The pose reference's rate as a connection (the trajectory's pose_ref_rate.*), for masters that
 * give no input derivatives: the legs' reference rates (leg[i].velocity_ref, speed_ref) follow it
 * where pose_ref has no derivative from the master, and fmi.extrapolate_inputs extrapolates
 * pose_ref with it. Unconnected (0) and without input derivatives: the references stand still. */
#define POSE_RATE_VARIABLES(X) \
X(Real, pose_ref_rate_x, "pose_ref_rate.x", input, continuous, "m/s", 0.0, -FMU_INF, FMU_INF, "Rate of pose_ref.x (where the master gives pose_ref no derivative)") \
X(Real, pose_ref_rate_y, "pose_ref_rate.y", input, continuous, "m/s", 0.0, -FMU_INF, FMU_INF, "Rate of pose_ref.y") \
X(Real, pose_ref_rate_z, "pose_ref_rate.z", input, continuous, "m/s", 0.0, -FMU_INF, FMU_INF, "Rate of pose_ref.z") \
X(Real, pose_ref_rate_roll, "pose_ref_rate.roll", input, continuous, "rad/s", 0.0, -FMU_INF, FMU_INF, "Rate of pose_ref.roll") \
X(Real, pose_ref_rate_pitch, "pose_ref_rate.pitch", input, continuous, "rad/s", 0.0, -FMU_INF, FMU_INF, "Rate of pose_ref.pitch") \
X(Real, pose_ref_rate_yaw, "pose_ref_rate.yaw", input, continuous, "rad/s", 0.0, -FMU_INF, FMU_INF, "Rate of pose_ref.yaw")

/* Explicit joint coordinates of leg i, used with geometry.layout = 2. */
#define JOINT_VARIABLES(X, i) \
X(Real, geometry_base_joint_##i##_x, "geometry.base_joint[" #i "].x", parameter, fixed, "m", 0.0, -FMU_INF, FMU_INF, "Lower joint b_" #i ", base frame, x (layout 2)") \
X(Real, geometry_base_joint_##i##_y, "geometry.base_joint[" #i "].y", parameter, fixed, "m", 0.0, -FMU_INF, FMU_INF, "Lower joint b_" #i ", y (layout 2)") \
X(Real, geometry_base_joint_##i##_z, "geometry.base_joint[" #i "].z", parameter, fixed, "m", 0.0, -FMU_INF, FMU_INF, "Lower joint b_" #i ", z (layout 2)") \
X(Real, geometry_platform_joint_##i##_x, "geometry.platform_joint[" #i "].x", parameter, fixed, "m", 0.0, -FMU_INF, FMU_INF, "Upper joint a_" #i ", platform frame, x (layout 2)") \
X(Real, geometry_platform_joint_##i##_y, "geometry.platform_joint[" #i "].y", parameter, fixed, "m", 0.0, -FMU_INF, FMU_INF, "Upper joint a_" #i ", y (layout 2)") \
X(Real, geometry_platform_joint_##i##_z, "geometry.platform_joint[" #i "].z", parameter, fixed, "m", 0.0, -FMU_INF, FMU_INF, "Upper joint a_" #i ", z (layout 2)")

/* Neutral height of the default layout (params/meng2010.toml: z0 = 1.68953 m, every leg l_0 long). */
#define NEUTRAL_HEIGHT 1.689527733348906

/* clang-format off */
#define MODEL_VARIABLES(X) \
LEG_VARIABLES(X, 1) LEG_VARIABLES(X, 2) LEG_VARIABLES(X, 3) \
LEG_VARIABLES(X, 4) LEG_VARIABLES(X, 5) LEG_VARIABLES(X, 6) \
POSE_VARIABLES(X, "pose_ref", pose_ref_, input, continuous, "Desired pose (base frame), used only for the inverse kinematics outputs") \
X(Real, load_force_x, "load.force.x", input, continuous, "N", 0.0, -FMU_INF, FMU_INF, "External force on the platform at its origin, base frame, x") \
X(Real, load_force_y, "load.force.y", input, continuous, "N", 0.0, -FMU_INF, FMU_INF, "External force, y") \
X(Real, load_force_z, "load.force.z", input, continuous, "N", 0.0, -FMU_INF, FMU_INF, "External force, z") \
X(Real, load_torque_x, "load.torque.x", input, continuous, "N.m", 0.0, -FMU_INF, FMU_INF, "External torque about the platform origin, base frame, x") \
X(Real, load_torque_y, "load.torque.y", input, continuous, "N.m", 0.0, -FMU_INF, FMU_INF, "External torque, y") \
X(Real, load_torque_z, "load.torque.z", input, continuous, "N.m", 0.0, -FMU_INF, FMU_INF, "External torque, z") \
X(Real, load_body_force_x, "load.body.force.x", input, continuous, "N", 0.0, -FMU_INF, FMU_INF, "External force on the platform at its origin, platform frame (a follower load that turns with the platform; added to load.force), x") \
X(Real, load_body_force_y, "load.body.force.y", input, continuous, "N", 0.0, -FMU_INF, FMU_INF, "External force, platform frame, y") \
X(Real, load_body_force_z, "load.body.force.z", input, continuous, "N", 0.0, -FMU_INF, FMU_INF, "External force, platform frame, z") \
X(Real, load_body_torque_x, "load.body.torque.x", input, continuous, "N.m", 0.0, -FMU_INF, FMU_INF, "External torque about the platform origin, platform frame, x") \
X(Real, load_body_torque_y, "load.body.torque.y", input, continuous, "N.m", 0.0, -FMU_INF, FMU_INF, "External torque, platform frame, y") \
X(Real, load_body_torque_z, "load.body.torque.z", input, continuous, "N.m", 0.0, -FMU_INF, FMU_INF, "External torque, platform frame, z") \
\
POSE_VARIABLES(X, "pose", pose_, output, continuous, "Platform pose (base frame; R = Rz(yaw) Ry(pitch) Rx(roll))") \
X(Real, twist_vx, "twist.vx", output, continuous, "m/s", 0.0, -FMU_INF, FMU_INF, "Platform origin velocity, base frame, x") \
X(Real, twist_vy, "twist.vy", output, continuous, "m/s", 0.0, -FMU_INF, FMU_INF, "Platform origin velocity, y") \
X(Real, twist_vz, "twist.vz", output, continuous, "m/s", 0.0, -FMU_INF, FMU_INF, "Platform origin velocity, z") \
X(Real, twist_wx, "twist.wx", output, continuous, "rad/s", 0.0, -FMU_INF, FMU_INF, "Platform angular velocity, base frame, x") \
X(Real, twist_wy, "twist.wy", output, continuous, "rad/s", 0.0, -FMU_INF, FMU_INF, "Platform angular velocity, y") \
X(Real, twist_wz, "twist.wz", output, continuous, "rad/s", 0.0, -FMU_INF, FMU_INF, "Platform angular velocity, z") \
X(Real, energy_kinetic, "energy.kinetic", output, continuous, "J", 0.0, -FMU_INF, FMU_INF, "Kinetic energy of platform, actuators and motor systems") \
X(Real, energy_potential, "energy.potential", output, continuous, "J", 0.0, -FMU_INF, FMU_INF, "Potential energy in gravity (zero at the base plane)") \
X(Real, power_drive, "power.drive", output, continuous, "W", 0.0, -FMU_INF, FMU_INF, "Power all drive inputs deliver: sum of torque x motor speed + force x extension rate") \
X(Real, power_transmission_loss, "power.transmission_loss", output, continuous, "W", 0.0, -FMU_INF, FMU_INF, "Screw and belt loss (1 - eta) torque x motor speed, eta = K_FT / i_theta") \
X(Real, power_friction_loss, "power.friction_loss", output, continuous, "W", 0.0, -FMU_INF, FMU_INF, "Viscous friction loss of the motors, B_m speed^2") \
X(Real, power_load, "power.load", output, continuous, "W", 0.0, -FMU_INF, FMU_INF, "Power of the external wrench on the platform") \
X(Real, energy_drive, "energy.drive", output, continuous, "J", 0.0, -FMU_INF, FMU_INF, "Integral of power.drive since the start") \
X(Real, energy_transmission_loss, "energy.transmission_loss", output, continuous, "J", 0.0, -FMU_INF, FMU_INF, "Integral of power.transmission_loss") \
X(Real, energy_friction_loss, "energy.friction_loss", output, continuous, "J", 0.0, -FMU_INF, FMU_INF, "Integral of power.friction_loss") \
X(Real, energy_load, "energy.load", output, continuous, "J", 0.0, -FMU_INF, FMU_INF, "Integral of power.load") \
\
POSE_VARIABLES(X, "initial.pose", initial_pose_, parameter, fixed, "Start pose (default: the neutral pose of the default layout)") \
X(Real, initial_twist_vx, "initial.twist.vx", parameter, fixed, "m/s", 0.0, -FMU_INF, FMU_INF, "Start velocity, x") \
X(Real, initial_twist_vy, "initial.twist.vy", parameter, fixed, "m/s", 0.0, -FMU_INF, FMU_INF, "Start velocity, y") \
X(Real, initial_twist_vz, "initial.twist.vz", parameter, fixed, "m/s", 0.0, -FMU_INF, FMU_INF, "Start velocity, z") \
X(Real, initial_twist_wx, "initial.twist.wx", parameter, fixed, "rad/s", 0.0, -FMU_INF, FMU_INF, "Start angular velocity, x") \
X(Real, initial_twist_wy, "initial.twist.wy", parameter, fixed, "rad/s", 0.0, -FMU_INF, FMU_INF, "Start angular velocity, y") \
X(Real, initial_twist_wz, "initial.twist.wz", parameter, fixed, "rad/s", 0.0, -FMU_INF, FMU_INF, "Start angular velocity, z") \
X(Integer, geometry_layout, "geometry.layout", parameter, fixed, "", 1, 1, 2, "Joint layout: 1 = from radii, spacings and l_0 (Meng, Table 1); 2 = explicit joint coordinates geometry.base_joint[i], geometry.platform_joint[i] with the neutral pose geometry.neutral (Sumnu)") \
JOINT_VARIABLES(X, 1) JOINT_VARIABLES(X, 2) JOINT_VARIABLES(X, 3) \
JOINT_VARIABLES(X, 4) JOINT_VARIABLES(X, 5) JOINT_VARIABLES(X, 6) \
POSE_VARIABLES(X, "geometry.neutral", geometry_neutral_, parameter, fixed, "Layout 2: the pose at which every motor angle is zero") \
X(Real, geometry_upper_joint_radius, "geometry.upper_joint_radius", parameter, fixed, "m", 0.8, FMU_POSITIVE, FMU_INF, "r_a (Table 1)") \
X(Real, geometry_lower_joint_radius, "geometry.lower_joint_radius", parameter, fixed, "m", 1.1, FMU_POSITIVE, FMU_INF, "r_b (Table 1)") \
X(Real, geometry_upper_joint_spacing, "geometry.upper_joint_spacing", parameter, fixed, "m", 0.2, 0.0, FMU_INF, "d_a, chord between the two joints of an upper pair (Table 1)") \
X(Real, geometry_lower_joint_spacing, "geometry.lower_joint_spacing", parameter, fixed, "m", 0.3, 0.0, FMU_INF, "d_b, chord between the two joints of a lower pair (Table 1)") \
X(Real, geometry_middle_leg_length, "geometry.middle_leg_length", parameter, fixed, "m", 1.86, FMU_POSITIVE, FMU_INF, "l_0, leg length at the neutral pose (Table 1); defines the neutral height") \
X(Real, geometry_lower_pair_centre_1, "geometry.lower_pair_centre_1", parameter, fixed, "rad", 0.0, -FMU_INF, FMU_INF, "Angle of the first lower joint pair's centre (legs 1, 2)") \
X(Real, geometry_lower_pair_centre_2, "geometry.lower_pair_centre_2", parameter, fixed, "rad", 2.0943951023931957, -FMU_INF, FMU_INF, "Second lower pair (legs 3, 4): 120 deg") \
X(Real, geometry_lower_pair_centre_3, "geometry.lower_pair_centre_3", parameter, fixed, "rad", 4.1887902047863914, -FMU_INF, FMU_INF, "Third lower pair (legs 5, 6): 240 deg") \
X(Real, geometry_upper_pair_centre_1, "geometry.upper_pair_centre_1", parameter, fixed, "rad", 1.0471975511965979, -FMU_INF, FMU_INF, "First upper pair (legs 2, 3): 60 deg") \
X(Real, geometry_upper_pair_centre_2, "geometry.upper_pair_centre_2", parameter, fixed, "rad", 3.1415926535897931, -FMU_INF, FMU_INF, "Second upper pair (legs 4, 5): 180 deg") \
X(Real, geometry_upper_pair_centre_3, "geometry.upper_pair_centre_3", parameter, fixed, "rad", 5.2359877559829888, -FMU_INF, FMU_INF, "Third upper pair (legs 6, 1): 300 deg") \
X(Real, platform_mass, "platform.mass", parameter, fixed, "kg", 950.0, FMU_POSITIVE, FMU_INF, "m_p (Table 3)") \
X(Real, platform_inertia_xx, "platform.inertia_xx", parameter, fixed, "kg.m2", 216.0, FMU_POSITIVE, FMU_INF, "I_p^p about the centre of mass (the origin), xx (assumed: disc r = 0.95 m, h = 0.15 m)") \
X(Real, platform_inertia_yy, "platform.inertia_yy", parameter, fixed, "kg.m2", 216.0, FMU_POSITIVE, FMU_INF, "I_p^p, yy (assumed)") \
X(Real, platform_inertia_zz, "platform.inertia_zz", parameter, fixed, "kg.m2", 429.0, FMU_POSITIVE, FMU_INF, "I_p^p, zz (assumed)") \
X(Real, actuator_moving_mass, "actuator.moving_mass", parameter, fixed, "kg", 30.0, 0.0, FMU_INF, "m_a, piston rod and nut (Table 3)") \
X(Real, actuator_moving_inertia, "actuator.moving_inertia", parameter, fixed, "kg.m2", 2.5, 0.0, FMU_INF, "i_a, transverse, about its centre of mass (assumed: slender 1.0 m rod)") \
X(Real, actuator_moving_com, "actuator.moving_com", parameter, fixed, "m", 0.5, 0.0, FMU_INF, "r_ac, centre of mass from the upper joint (assumed)") \
X(Real, actuator_rotating_mass, "actuator.rotating_mass", parameter, fixed, "kg", 50.0, 0.0, FMU_INF, "m_b, cylinder housing (Table 3)") \
X(Real, actuator_rotating_inertia, "actuator.rotating_inertia", parameter, fixed, "kg.m2", 7.04, 0.0, FMU_INF, "i_b, transverse, about its centre of mass (assumed: slender 1.3 m tube)") \
X(Real, actuator_rotating_com, "actuator.rotating_com", parameter, fixed, "m", 0.6, 0.0, FMU_INF, "r_bc, centre of mass from the lower joint (assumed)") \
X(Real, motor_system_mass, "motor_system.mass", parameter, fixed, "kg", 27.6, 0.0, FMU_INF, "m_s, rotor, screw and motor carried by the leg (Table 3)") \
X(Real, motor_system_inertia, "motor_system.inertia", parameter, fixed, "kg.m2", 1.5, 0.0, FMU_INF, "i_s, transverse inertia of the motor system about its centre of mass (assumed)") \
X(Real, motor_system_com, "motor_system.com", parameter, fixed, "m", 0.6, 0.0, FMU_INF, "r_sc, its centre of mass from the lower joint (assumed, as Eq 18 uses J_bc)") \
X(Real, motor_system_rotor_inertia, "motor_system.rotor_inertia", parameter, fixed, "kg.m2", 6.66e-3, 0.0, FMU_INF, "i_R, rotor and screw spin inertia (Table 3)") \
X(Real, transmission_screw_ratio, "transmission.screw_ratio", parameter, fixed, "rad/m", 277.777777777778, FMU_POSITIVE, FMU_INF, "i_theta, motor angle per metre of leg (assumed: eta = K_FT / i_theta = 0.9)") \
X(Real, transmission_force_torque, "transmission.force_torque", parameter, fixed, "1/m", 250.0, FMU_POSITIVE, FMU_INF, "K_FT, leg force per motor torque (Table 3)") \
X(Real, motor_viscous_friction, "motor.viscous_friction", parameter, fixed, "N.m.s/rad", 0.00792, 0.0, FMU_INF, "B_m on the motor shaft (Table 2)") \
X(Real, actuator_spin_inertia, "actuator.spin_inertia", parameter, fixed, "kg.m2", 0.0, 0.0, FMU_INF, "I_s, the leg about its own axis, for legs that turn with the platform (spherical joint at the base, universal at the top: Halder et al.'s 6-SBU, I^ml); 0 for Meng's UPS legs") \
X(Real, joint_friction_lower, "joint.friction_lower", parameter, fixed, "N.m.s/rad", 0.0, 0.0, FMU_INF, "C_S, viscous friction of the lower (spherical) joint on the leg's angular velocity (Halder et al.)") \
X(Real, joint_friction_upper, "joint.friction_upper", parameter, fixed, "N.m.s/rad", 0.0, 0.0, FMU_INF, "C_U, viscous friction of the upper (universal) joint on the rate across it (Halder et al.)") \
X(Real, environment_gravity_x, "environment.gravity_x", parameter, fixed, "m/s2", 0.0, -FMU_INF, FMU_INF, "Gravity, base frame, x") \
X(Real, environment_gravity_y, "environment.gravity_y", parameter, fixed, "m/s2", 0.0, -FMU_INF, FMU_INF, "Gravity, y") \
X(Real, environment_gravity_z, "environment.gravity_z", parameter, fixed, "m/s2", -9.81, -FMU_INF, FMU_INF, "Gravity, z") \
X(Boolean, effects_actuator_inertia, "effects.actuator_inertia", parameter, fixed, "", 1, 0, 1, "Include the actuators' moving and rotating parts (m_a, i_a, m_b, i_b) and the legs' spin I_s") \
X(Boolean, effects_motor_inertia, "effects.motor_inertia", parameter, fixed, "", 1, 0, 1, "Include the motor systems: rotor and screw spin i_R, motor carried by the leg (m_s, i_s)") \
X(Boolean, effects_friction, "effects.friction", parameter, fixed, "", 1, 0, 1, "Include the motors' viscous friction B_m and the joints' friction C_S, C_U") \
X(Real, limit_leg_length_min, "limit.leg_length_min", parameter, fixed, "m", 1.535, 0.0, FMU_INF, "Shortest leg of the stroke (Table 4)") \
X(Real, limit_leg_length_max, "limit.leg_length_max", parameter, fixed, "m", 2.2, 0.0, FMU_INF, "Longest leg of the stroke (Table 4)") \
X(Real, limit_joint_angle, "limit.joint_angle", parameter, fixed, "rad", 0.3490658503988659, 0.0, 3.2, "Largest tilt of a leg from its neutral direction at either joint (20 deg, Halder et al.)") \
X(Real, limit_stroke_margin, "limit.stroke_margin", parameter, fixed, "m", 0.016, 0.0, FMU_INF, "Motion envelope: the stroke a guarded reference may use is limit.leg_length_min/max less this at each end (covers the platform's tracking error; measured for Meng's platform and PMSM drives, docs/guide/realtime.md)") \
X(Real, limit_joint_margin, "limit.joint_margin", parameter, fixed, "rad", 0.017453292519943295, 0.0, 3.2, "Motion envelope: the tilt a guarded reference may take at a joint is limit.joint_angle less this (covers the platform's tracking error; 1 deg, measured for Meng's platform and PMSM drives, docs/guide/realtime.md)") \
X(Real, limit_leg_velocity, "limit.leg_velocity", parameter, fixed, "m/s", 1.0, 0.0, FMU_INF, "Motion envelope: a live reference's largest leg extension rate") \
X(Real, limit_leg_acceleration, "limit.leg_acceleration", parameter, fixed, "m/s2", 10.0, 0.0, FMU_INF, "Motion envelope: a live reference's largest leg acceleration") \
X(Boolean, limit_hard_stop, "limit.hard_stop", parameter, fixed, "", 0, 0, 1, "false: leaving the stroke or a joint limit is a logged warning; true: an error that stops the run") \
FMU_SOLVER_VARIABLES(X, 1, 1e-3, 1e-8, 1e-10) \
LEG_PLANT_VARIABLES(X, 1) LEG_PLANT_VARIABLES(X, 2) LEG_PLANT_VARIABLES(X, 3) \
LEG_PLANT_VARIABLES(X, 4) LEG_PLANT_VARIABLES(X, 5) LEG_PLANT_VARIABLES(X, 6) \
POSE_RATE_VARIABLES(X) \
FMU_LAYER_VARIABLES(X)
/* clang-format on */

/* Direct feed-through (the ModelStructure's output dependencies): D(output, the value references of
 * the inputs it depends on at the same communication point), one row per such output; every other
 * output depends on no input (on the state alone). The legs' references follow pose_ref (and
 * its derivatives); the applied efforts and the powers follow the efforts; the load's power the load.
 * tests/models/test_dependencies.py perturbs each input and holds this table to what moves. */
#define POSE_REF_INPUTS VR_pose_ref_x, VR_pose_ref_y, VR_pose_ref_z, VR_pose_ref_roll, VR_pose_ref_pitch, VR_pose_ref_yaw
#define POSE_RATE_INPUTS VR_pose_ref_rate_x, VR_pose_ref_rate_y, VR_pose_ref_rate_z, VR_pose_ref_rate_roll, \
    VR_pose_ref_rate_pitch, VR_pose_ref_rate_yaw
#define LEG_EFFORT_INPUTS(i) VR_leg##i##_torque, VR_leg##i##_force, VR_leg##i##_torque_speed_slope, VR_leg##i##_speed_seen, \
    VR_leg##i##_force_velocity_slope, VR_leg##i##_velocity_seen
#define LEG_TORQUE_INPUTS(i) VR_leg##i##_torque, VR_leg##i##_torque_speed_slope, VR_leg##i##_speed_seen
#define ALL_LEGS(inputs) inputs(1), inputs(2), inputs(3), inputs(4), inputs(5), inputs(6)
#define LEG_REFERENCES(D, i) D(leg##i##_length_ref, POSE_REF_INPUTS) D(leg##i##_angle_ref, POSE_REF_INPUTS) \
    D(leg##i##_velocity_ref, POSE_REF_INPUTS, POSE_RATE_INPUTS) D(leg##i##_speed_ref, POSE_REF_INPUTS, POSE_RATE_INPUTS) \
    D(leg##i##_torque_applied, VR_leg##i##_torque, VR_leg##i##_torque_speed_slope, VR_leg##i##_speed_seen) \
    D(leg##i##_force_applied, VR_leg##i##_force, VR_leg##i##_force_velocity_slope, VR_leg##i##_velocity_seen)
#define MODEL_FEEDTHROUGH(D) \
LEG_REFERENCES(D, 1) LEG_REFERENCES(D, 2) LEG_REFERENCES(D, 3) \
LEG_REFERENCES(D, 4) LEG_REFERENCES(D, 5) LEG_REFERENCES(D, 6) \
D(power_drive, ALL_LEGS(LEG_EFFORT_INPUTS)) \
D(power_transmission_loss, ALL_LEGS(LEG_TORQUE_INPUTS)) \
D(power_load, VR_load_force_x, VR_load_force_y, VR_load_force_z, VR_load_torque_x, VR_load_torque_y, VR_load_torque_z, \
  VR_load_body_force_x, VR_load_body_force_y, VR_load_body_force_z, VR_load_body_torque_x, VR_load_body_torque_y, \
  VR_load_body_torque_z)

/* The inputs that carry another's exact rate, and those the mechanics holds over a step
 * (fmi.extrapolate_inputs leaves the loads piecewise constant, as the trajectory makes them). */
#define MODEL_INPUT_RATES(R) R(VR_pose_ref_x, VR_pose_ref_rate_x) R(VR_pose_ref_y, VR_pose_ref_rate_y) \
    R(VR_pose_ref_z, VR_pose_ref_rate_z) R(VR_pose_ref_roll, VR_pose_ref_rate_roll) \
    R(VR_pose_ref_pitch, VR_pose_ref_rate_pitch) R(VR_pose_ref_yaw, VR_pose_ref_rate_yaw)
#define MODEL_HELD_INPUTS VR_load_force_x, VR_load_force_y, VR_load_force_z, VR_load_torque_x, VR_load_torque_y, \
    VR_load_torque_z, VR_load_body_force_x, VR_load_body_force_y, VR_load_body_force_z, VR_load_body_torque_x, \
    VR_load_body_torque_y, VR_load_body_torque_z,

#endif
