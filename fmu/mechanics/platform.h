/* Stewart platform dynamics core (Meng et al. 2010, Section 2): plain C, no FMI, so that tests and
 * tools can reach it directly.
 *
 * Generalized speeds u = [t_dot; w] (platform origin velocity and angular velocity, base frame).
 * State x = [t (3), quaternion q = (w, x, y, z) (4), t_dot (3), w (3)]: the unit quaternion has no
 * singular orientation, so the platform can be integrated anywhere in (and beyond) its workspace;
 * roll, pitch, yaw (R = Rz(yaw) Ry(pitch) Rx(roll)) are computed from it for output only.
 *
 * Each leg (UPS: universal joint at the base, prismatic, spherical at the platform) is a system
 * whose configuration is its upper joint p_a. Its kinetic energy at the upper joint velocity v_a is
 *     T_leg = 1/2 v_a' (mu_axial n n' + mu_perp(L) P) v_a,   P = I - n n',
 *     mu_axial = m_a + i_R i_theta^2                                 (rod slides, rotor spins),
 *     mu_perp  = m_a (1 - r_ac/L)^2 + m_b (r_bc/L)^2 + m_s (r_sc/L)^2 + (i_a + i_b + i_s)/L^2,
 * which is Eqs 7, 11, 14, 15 and 19 collected; Lagrange's equations in p_a give the leg's force at
 * the upper joint, and Kane's partial velocities J_a (Eq 3) carry it to the platform (Eqs 20-23).
 *
 * Legs that turn about their own axis with the platform (Halder et al.'s 6-SBU: spherical joint at
 * the base, universal at the top) add, per leg, with spin s = n.w, swing w_sw = n x v_a / L and the
 * leg's angular velocity w_b = s n + w_sw:
 *     T_spin = 1/2 I_s s^2                         (leg_spin_inertia I_s about the leg axis),
 *     D      = 1/2 C_S |w_b|^2 + 1/2 C_U |w_b - w|^2  (viscous friction of the lower and upper joints),
 * entered through Kane's partial angular velocities d w_b / d u = E_w' n n' + (1/L) [n]x J_a.
 * Both are zero for Meng's and Sumnu's platforms.
 */
#ifndef PLATFORM_H
#define PLATFORM_H

#define PLATFORM_LEGS 6
#define PLATFORM_STATES 13

typedef struct {
    /* geometry */
    double upper_joint[PLATFORM_LEGS][3]; /* a_i^p, platform frame [m] */
    double lower_joint[PLATFORM_LEGS][3]; /* b_i, base frame [m] */
    double neutral_pose[6];               /* pose at which every motor angle is zero */
    double neutral_length[PLATFORM_LEGS]; /* leg lengths at the neutral pose [m] */
    /* platform */
    double platform_mass, platform_inertia[3]; /* m_p, diagonal of I_p^p about the CoM (origin) */
    /* actuator parts */
    double moving_mass, moving_inertia, moving_com;       /* m_a, i_a, r_ac from the upper joint */
    double rotating_mass, rotating_inertia, rotating_com; /* m_b, i_b, r_bc from the lower joint */
    /* motor system carried by the rotating part */
    double motor_mass, motor_inertia, motor_com;          /* m_s, i_s, r_sc from the lower joint */
    double rotor_inertia;                                 /* i_R: rotor and screw spin [kg m^2] */
    double screw_ratio;                                   /* i_theta: motor angle per leg length [rad/m] */
    double force_torque;                                  /* K_FT: leg force per motor torque [N/(N m)] */
    double viscous_friction;                              /* B_m on the motor shaft [N m s/rad] */
    double leg_spin_inertia;                              /* I_s: leg about its axis, turning with the platform [kg m^2] */
    double joint_friction_lower, joint_friction_upper;    /* C_S, C_U: viscous joint friction [N m s/rad] */
    double gravity[3];
    /* effect switches */
    int actuator_inertia_on, motor_inertia_on, friction_on;
} Platform;

typedef struct {
    double axis[3];    /* n = l / |l| */
    double length;     /* L */
    double arm[3];     /* r = R a_i^p, from the platform origin to the upper joint */
    double velocity;   /* L_dot */
} LegGeometry;

/* Meng's layout (Table 1): three pairs of joints on each circle, pair spacing as chords; lower pairs
 * centred at lower_centres_deg, upper at upper_centres_deg; the neutral height makes every leg
 * middle_length long. Returns 0, or -1 if the numbers admit no such layout. */
int platform_layout_from_radii(Platform *p, double upper_radius, double lower_radius, double upper_spacing,
                               double lower_spacing, double middle_length, const double lower_centres_deg[3],
                               const double upper_centres_deg[3]);

/* Explicit joint coordinates (e.g. the Sumnu thesis): a_i^p in the platform frame, b_i in the base
 * frame, and the neutral pose at which every motor angle is zero. Returns -1 if a leg would have
 * zero length there. */
int platform_layout_from_joints(Platform *p, const double upper[PLATFORM_LEGS][3],
                                const double lower[PLATFORM_LEGS][3], const double neutral_pose[6]);

/* Rotation matrix (row major) of R = Rz(yaw) Ry(pitch) Rx(roll), and of a unit quaternion. */
void platform_rotation_from_euler(double roll, double pitch, double yaw, double R[9]);
void platform_rotation_from_quaternion(const double q[4], double R[9]);
void platform_quaternion_from_euler(double roll, double pitch, double yaw, double q[4]);
void platform_euler_from_rotation(const double R[9], double euler[3]);

/* Leg lengths of a pose [x, y, z, roll, pitch, yaw] (inverse kinematics, Eq 2). */
void platform_leg_lengths(const Platform *p, const double pose[6], double length[PLATFORM_LEGS]);
/* Legs at state x (pose from t and q, velocities from t_dot and w). */
void platform_legs(const Platform *p, const double *x, LegGeometry legs[PLATFORM_LEGS]);
/* Leg Jacobian J (6x6, row major): L_dot_i = J_i u, row i = [n_i', (r_i x n_i)']. */
void platform_leg_jacobian(const LegGeometry legs[PLATFORM_LEGS], double J[36]);

/* Each leg's plant at the pose of state x (its velocities ignored): inertia[i] = M_ii of the
 * joint-space mass matrix J^-T M J^-1 (the leg's inertia along its axis with the other legs held)
 * and static_force[i], the axial force that holds the pose without external loads. 0, or -1 at a
 * singular pose. */
int platform_leg_plants(const Platform *p, const double *x, double inertia[PLATFORM_LEGS],
                        double static_force[PLATFORM_LEGS]);

/* |det J| over the product of its rows' norms: 1 for orthogonal leg lines, 0 at a singularity. */
double platform_jacobian_conditioning(const LegGeometry legs[PLATFORM_LEGS]);

typedef struct {
    double mass_matrix[36];     /* M_s (Eq 23) */
    double kinetic, potential;  /* energies [J] */
    double drive_power;         /* sum of T_i w_m,i + F_i L_dot_i delivered by the drives [W] */
    double transmission_loss;   /* (1 - eta) sum T_i w_m,i [W] */
    double friction_loss;       /* sum B_m w_m,i^2 + joint friction C_S |w_b|^2 + C_U |w_b - w|^2 [W] */
    double load_power;          /* external wrench times twist [W] */
    int singular;               /* the mass matrix did not factorise */
} PlatformDiagnostics;

/* The drives' interface Jacobians over a co-simulation step (Sicklinger et al. 2014): each drive
 * computed its torque (force) for the motor speed (extension rate) it was given, speed_seen; the
 * leg feels torque + torque_speed_slope (w_m - speed_seen) at its actual speed w_m, and likewise
 * force + force_velocity_slope (L_dot - velocity_seen). The correction vanishes where the drive saw
 * the actual speed; where it did not, the drive's damping acts on the actual speed, inside the
 * mechanics' integration, instead of on an extrapolated one. */
typedef struct {
    double torque_speed_slope[PLATFORM_LEGS], speed_seen[PLATFORM_LEGS];      /* [N m s/rad], [rad/s] */
    double force_velocity_slope[PLATFORM_LEGS], velocity_seen[PLATFORM_LEGS]; /* [N s/m], [m/s] */
} PlatformDriveSlopes;

/* The efforts the legs feel at their current velocities: each drive's torque (force) plus its
 * slope times (the leg's motor speed (extension rate) - the one the drive was given); the inputs
 * themselves where slopes is NULL. */
void platform_applied_efforts(const Platform *p, const LegGeometry legs[PLATFORM_LEGS],
                              const double torque_in[PLATFORM_LEGS], const double force_in[PLATFORM_LEGS],
                              const PlatformDriveSlopes *slopes, double torque[PLATFORM_LEGS],
                              double force[PLATFORM_LEGS]);

/* dx/dt for motor torques (screw legs), direct axial forces (with the drives' slopes, or NULL) and
 * the external wrench [F (3), M (3)] at the platform origin, base frame. Returns 0, or -1 if the
 * mass matrix is not positive definite (diag may be NULL). */
int platform_derivatives(const Platform *p, const double *x, const double torque[PLATFORM_LEGS],
                         const double force[PLATFORM_LEGS], const PlatformDriveSlopes *slopes,
                         const double wrench[6], double *dxdt, PlatformDiagnostics *diag);

/* Motor torques that make the platform follow pose(t) with the given first and second time
 * derivatives (of x, y, z, roll, pitch, yaw), under the external wrench. Returns 0, or -1 at a
 * singular leg Jacobian. */
int platform_inverse_dynamics(const Platform *p, const double pose[6], const double pose_rate[6],
                              const double pose_acceleration[6], const double wrench[6],
                              double torque[PLATFORM_LEGS]);

/* State x from a pose and its rate (Euler angle rates). */
void platform_state_from_pose(const double pose[6], const double pose_rate[6], double *x);

/* A leg's tilt from its neutral direction n0 (base frame, at the neutral pose, whose orientation
 * is the identity) at the lower joint, acos(n.n0), and at the upper joint in the platform frame,
 * acos((R'n).n0), with R the platform's orientation [rad] (Halder et al., Eq 9: the angles
 * between the leg and its bottom and top stubs, which are collinear with it at the neutral). */
void platform_joint_angles(const double R[9], const double axis[3], const double n0[3], double *lower,
                           double *upper);
/* Their cosines, n.n0 and (R'n).n0 (clamped to [-1, 1]): what a limit check compares. */
void platform_joint_cosines(const double R[9], const double axis[3], const double n0[3], double *lower,
                            double *upper);

/* For design studies, at each of n poses (x, y, z, roll, pitch, yaw; row major): each leg's length,
 * its joint angles (platform_joint_angles) and the leg Jacobian (36 entries, row major). Any
 * output may be NULL. */
void platform_pose_kinematics(const Platform *p, int n, const double *poses, double *length,
                              double *lower_angle, double *upper_angle, double *jacobian);

/* At each of n poses with their rates (row major, 6 each): each leg's extension rate [m/s]
 * (Eq 3's velocity of the upper joint along the leg). */
void platform_leg_velocities_many(const Platform *p, int n, const double *pose, const double *pose_rate,
                                  double *velocity);

/* platform_inverse_dynamics at each of n poses with their rates and accelerations (row major, 6
 * each) under one external wrench; the torques of a singular pose are NaN. Returns the number of
 * singular poses. */
int platform_inverse_dynamics_many(const Platform *p, int n, const double *pose, const double *pose_rate,
                                   const double *pose_acceleration, const double wrench[6], double *torque);

#endif
