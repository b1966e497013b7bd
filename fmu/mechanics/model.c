/* mechanics: the Stewart platform's multi-body dynamics as an FMU (Meng et al. 2010, Section 2).
 *
 * The dynamics live in platform.c (plain C, tested on its own); this file connects them to the
 * variable table: it builds the Platform from the parameters (parameters.c, the one mapping, which
 * tools reach through the platform_core library), reads the inputs, integrates, keeps
 * the energy accounts, and watches the stroke, the joint angles and the Jacobian.
 *
 *   M_s(x) u_dot = sum_i [n_i; r_i x n_i] (K_FT T_i + F_i) + (gravity, velocity terms, friction,
 *                  external wrench)                                                    (Eq 23)
 *   d/dt (E_kin + E_pot) = power.drive - power.transmission_loss - power.friction_loss + power.load
 */
#include "fmu_common.h"
#include "parameters.h"

#include <string.h>

/* The energy accounts follow the platform states (explicit in the Rosenbrock-W solver: nothing
 * depends on them). */
enum { E_DRIVE = PLATFORM_STATES, E_TRANSMISSION, E_FRICTION, E_LOAD };

#define LEG_VRS(field) \
    {VR_leg1_##field, VR_leg2_##field, VR_leg3_##field, VR_leg4_##field, VR_leg5_##field, VR_leg6_##field}
static const int VR_PLANT_INERTIA[] = LEG_VRS(plant_inertia), VR_PLANT_STATIC_FORCE[] = LEG_VRS(plant_static_force);
static const int VR_TORQUE_SPEED_SLOPE[] = LEG_VRS(torque_speed_slope), VR_SPEED_SEEN[] = LEG_VRS(speed_seen),
                 VR_FORCE_VELOCITY_SLOPE[] = LEG_VRS(force_velocity_slope), VR_VELOCITY_SEEN[] = LEG_VRS(velocity_seen);
static const int VR_TORQUE[] = LEG_VRS(torque), VR_FORCE[] = LEG_VRS(force), VR_LENGTH[] = LEG_VRS(length),
                 VR_VELOCITY[] = LEG_VRS(velocity), VR_ANGLE[] = LEG_VRS(angle), VR_SPEED[] = LEG_VRS(speed),
                 VR_LENGTH_REF[] = LEG_VRS(length_ref), VR_ANGLE_REF[] = LEG_VRS(angle_ref),
                 VR_VELOCITY_REF[] = LEG_VRS(velocity_ref), VR_SPEED_REF[] = LEG_VRS(speed_ref),
                 VR_TORQUE_APPLIED[] = LEG_VRS(torque_applied), VR_FORCE_APPLIED[] = LEG_VRS(force_applied);
static const int VR_POSE_REF[] = {VR_pose_ref_x, VR_pose_ref_y, VR_pose_ref_z,
                                  VR_pose_ref_roll, VR_pose_ref_pitch, VR_pose_ref_yaw};
static const int VR_WRENCH[] = {VR_load_force_x, VR_load_force_y, VR_load_force_z,
                                VR_load_torque_x, VR_load_torque_y, VR_load_torque_z};
static const int VR_BODY_WRENCH[] = {VR_load_body_force_x, VR_load_body_force_y, VR_load_body_force_z,
                                     VR_load_body_torque_x, VR_load_body_torque_y, VR_load_body_torque_z};

static const double PI = 3.14159265358979323846;

static void initial_state(const ModelVariables *v, double *x) {
    const double pose[6] = {v->initial_pose_x, v->initial_pose_y, v->initial_pose_z,
                            v->initial_pose_roll, v->initial_pose_pitch, v->initial_pose_yaw};
    const double zero[6] = {0, 0, 0, 0, 0, 0};
    platform_state_from_pose(pose, zero, x);
    x[7] = v->initial_twist_vx; x[8] = v->initial_twist_vy; x[9] = v->initial_twist_vz;
    x[10] = v->initial_twist_wx; x[11] = v->initial_twist_wy; x[12] = v->initial_twist_wz;
}

/* The inputs at t for state x; the external wrench in the base frame: load.* plus the follower
 * load load.body.* turned by the platform's orientation R (force and torque alike: Eq 23's F_e and
 * M_e are base-frame vectors at the platform origin). */
static void inputs_at(const FmuInstance *fmu, double t, const double *x, double torque[6], double force[6],
                      PlatformDriveSlopes *slopes, double wrench[6]) {
    double body[6], R[9];
    for (int i = 0; i < 6; i++) {
        torque[i] = fmu_input_at(fmu, VR_TORQUE[i], t);
        force[i] = fmu_input_at(fmu, VR_FORCE[i], t);
        slopes->torque_speed_slope[i] = fmu_input_at(fmu, VR_TORQUE_SPEED_SLOPE[i], t);
        slopes->speed_seen[i] = fmu_input_at(fmu, VR_SPEED_SEEN[i], t);
        slopes->force_velocity_slope[i] = fmu_input_at(fmu, VR_FORCE_VELOCITY_SLOPE[i], t);
        slopes->velocity_seen[i] = fmu_input_at(fmu, VR_VELOCITY_SEEN[i], t);
        wrench[i] = fmu_input_at(fmu, VR_WRENCH[i], t);
        body[i] = fmu_input_at(fmu, VR_BODY_WRENCH[i], t);
    }
    platform_rotation_from_quaternion(x + 3, R);
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 3; c++) {
            wrench[r] += R[3 * r + c] * body[c];
            wrench[3 + r] += R[3 * r + c] * body[3 + c];
        }
}

static void rhs(void *ctx, double t, const double *x, double *dxdt) {
    const FmuInstance *fmu = (const FmuInstance *)ctx;
    double torque[6], force[6], wrench[6];
    PlatformDriveSlopes slopes;
    PlatformDiagnostics d;
    inputs_at(fmu, t, x, torque, force, &slopes, wrench);
    if (platform_derivatives(&fmu->s.internal.platform, x, torque, force, &slopes, wrench, dxdt, &d) != 0) {
        for (int k = 0; k < MODEL_N_STATES; k++) dxdt[k] = NAN; /* the solver reports it */
        return;
    }
    dxdt[E_DRIVE] = d.drive_power;
    dxdt[E_TRANSMISSION] = d.transmission_loss;
    dxdt[E_FRICTION] = d.friction_loss;
    dxdt[E_LOAD] = d.load_power;
}

/* Stroke, joint limits and singularity of the platform `in` at state x and time t. Returns
 * fmi2Error for what must stop the run; logs warnings once per excursion otherwise. */
static fmi2Status check_limits(const FmuInstance *fmu, ModelInternal *in, const double *x, double t) {
    const ModelVariables *v = &fmu->s.v;
    LegGeometry legs[PLATFORM_LEGS];
    platform_legs(&in->platform, x, legs);
    /* each leg's largest tilt from its neutral direction, at the lower joint (base frame) or at the
     * upper joint (platform frame): past the limit where its cosine is below the limit's */
    double R[9], q[4], norm = sqrt(x[3] * x[3] + x[4] * x[4] + x[5] * x[5] + x[6] * x[6]);
    for (int k = 0; k < 4; k++) q[k] = x[3 + k] / norm;
    platform_rotation_from_quaternion(q, R);
    const double cos_limit = v->limit_joint_angle < PI ? cos(v->limit_joint_angle) : -2.0; /* pi: never */
    const fmi2Status severity = v->limit_hard_stop ? fmi2Error : fmi2Warning;
    const char *category = v->limit_hard_stop ? "logStatusError" : "logStatusWarning";
    fmi2Status status = fmi2OK;
    for (int i = 0; i < PLATFORM_LEGS; i++) {
        const double L = legs[i].length;
        if (!(legs[i].axis[2] > 0.0) || !(L > 1e-6)) {
            fmu_log(fmu, fmi2Error, "logStatusError",
                    "t = %.6f s: leg %d reached its lower joint or passed below it (length %.6g m, axis z %.3g): "
                    "the joints cross", t, i + 1, L, legs[i].axis[2]);
            return fmi2Error;
        }
        const int outside = L < v->limit_leg_length_min || L > v->limit_leg_length_max;
        if (outside && (!in->out_of_stroke[i] || v->limit_hard_stop)) {
            fmu_log(fmu, severity, category, "t = %.6f s: leg %d length %.6f m is outside the stroke [%.4g, %.4g] m",
                    t, i + 1, L, v->limit_leg_length_min, v->limit_leg_length_max);
            if (v->limit_hard_stop) status = fmi2Error;
        } else if (!outside && in->out_of_stroke[i]) {
            fmu_log(fmu, fmi2OK, "logEvents", "t = %.6f s: leg %d is back inside the stroke", t, i + 1);
        }
        in->out_of_stroke[i] = outside;
        double cos_lower, cos_upper;
        platform_joint_cosines(R, legs[i].axis, in->neutral_axis[i], &cos_lower, &cos_upper);
        const int past = fmin(cos_lower, cos_upper) < cos_limit;
        if (past && (!in->past_joint_limit[i] || v->limit_hard_stop)) {
            fmu_log(fmu, severity, category, "t = %.6f s: leg %d joint angle %.2f deg exceeds the limit %.2f deg", t,
                    i + 1, acos(fmin(cos_lower, cos_upper)) * 180.0 / PI, v->limit_joint_angle * 180.0 / PI);
            if (v->limit_hard_stop) status = fmi2Error;
        }
        in->past_joint_limit[i] = past;
    }
    const double conditioning = platform_jacobian_conditioning(legs);
    if (conditioning < 1e-6) {
        fmu_log(fmu, fmi2Error, "logStatusError",
                "t = %.6f s: the leg Jacobian is near-singular (normalised |det J| = %.3g < 1e-6)", t, conditioning);
        return fmi2Error;
    }
    return status;
}

fmi2Status model_do_step(FmuInstance *fmu, double h) {
    const OdeProblem problem = {MODEL_N_STATES, rhs, 0, NULL, NULL, PLATFORM_STATES, NULL};
    if (fmu_integrate(fmu, &problem, fmu, h, 0.0) != fmi2OK) return fmi2Error;
    double *q = fmu->s.x + 3, norm = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    for (int k = 0; k < 4; k++) q[k] /= norm; /* keep the quaternion on the unit sphere */
    return check_limits(fmu, &fmu->s.internal, fmu->s.x, fmu->s.time + h);
}

/* ---- Model Exchange (fmi2_me.c): the same right-hand side, the same checks after each step ---- */

const char *model_exchange_refusal(const FmuInstance *fmu) {
    (void)fmu;
    return NULL;
}

int model_derivatives(FmuInstance *fmu, double *dxdt) {
    rhs(fmu, fmu->s.time, fmu->s.x, dxdt);
    return isnan(dxdt[0]) ? -1 : 0;
}

fmi2Status model_completed_integrator_step(FmuInstance *fmu) {
    return check_limits(fmu, &fmu->s.internal, fmu->s.x, fmu->s.time);
}

/* The platform of the parameters with its neutral leg axes; -1 if the layout is impossible. */
static int build_internal(const ModelVariables *v, ModelInternal *in) {
    memset(in, 0, sizeof *in);
    if (mechanics_platform(v, &in->platform) != 0) return -1;
    LegGeometry legs[PLATFORM_LEGS];
    double x0[PLATFORM_STATES];
    const double zero[6] = {0, 0, 0, 0, 0, 0};
    platform_state_from_pose(in->platform.neutral_pose, zero, x0);
    platform_legs(&in->platform, x0, legs);
    for (int i = 0; i < PLATFORM_LEGS; i++) memcpy(in->neutral_axis[i], legs[i].axis, sizeof legs[i].axis);
    return 0;
}

void model_initialize(FmuInstance *fmu) {
    build_internal(&fmu->s.v, &fmu->s.internal);
    memset(fmu->s.x, 0, sizeof fmu->s.x);
    initial_state(&fmu->s.v, fmu->s.x);
    memset(&fmu->s.solver, 0, sizeof fmu->s.solver);
    /* the legs' plants at the start pose, for whoever designs the drives (they do not change) */
    double inertia[PLATFORM_LEGS], static_force[PLATFORM_LEGS];
    if (platform_leg_plants(&fmu->s.internal.platform, fmu->s.x, inertia, static_force) != 0)
        for (int i = 0; i < PLATFORM_LEGS; i++) inertia[i] = static_force[i] = NAN;
    for (int i = 0; i < PLATFORM_LEGS; i++) {
        *fmu_real(fmu, VR_PLANT_INERTIA[i]) = inertia[i];
        *fmu_real(fmu, VR_PLANT_STATIC_FORCE[i]) = static_force[i];
    }
}

void model_compute_outputs(FmuInstance *fmu) {
    ModelVariables *v = &fmu->s.v;
    const Platform *p = &fmu->s.internal.platform;
    const double *x = fmu->s.x, t = fmu->s.time;
    LegGeometry legs[PLATFORM_LEGS];
    double torque[6], force[6], wrench[6], pose_ref[6], length_ref[6], R[9], euler[3];
    double pose_ref_rate[6], x_ref[PLATFORM_STATES];
    LegGeometry legs_ref[PLATFORM_LEGS];
    platform_legs(p, x, legs);
    for (int i = 0; i < 6; i++) {
        pose_ref[i] = fmu_input_at(fmu, VR_POSE_REF[i], t);
        pose_ref_rate[i] = fmu_input_rate_at(fmu, VR_POSE_REF[i], t);
    }
    platform_leg_lengths(p, pose_ref, length_ref);
    platform_state_from_pose(pose_ref, pose_ref_rate, x_ref); /* the reference pose moving at its rate */
    platform_legs(p, x_ref, legs_ref);
    for (int i = 0; i < PLATFORM_LEGS; i++) {
        *fmu_real(fmu, VR_LENGTH[i]) = legs[i].length;
        *fmu_real(fmu, VR_VELOCITY[i]) = legs[i].velocity;
        *fmu_real(fmu, VR_ANGLE[i]) = p->screw_ratio * (legs[i].length - p->neutral_length[i]);
        *fmu_real(fmu, VR_SPEED[i]) = p->screw_ratio * legs[i].velocity; /* Eq 4 */
        *fmu_real(fmu, VR_LENGTH_REF[i]) = length_ref[i];
        *fmu_real(fmu, VR_ANGLE_REF[i]) = p->screw_ratio * (length_ref[i] - p->neutral_length[i]);
        *fmu_real(fmu, VR_VELOCITY_REF[i]) = legs_ref[i].velocity;
        *fmu_real(fmu, VR_SPEED_REF[i]) = p->screw_ratio * legs_ref[i].velocity;
    }
    platform_rotation_from_quaternion(x + 3, R);
    platform_euler_from_rotation(R, euler);
    v->pose_x = x[0]; v->pose_y = x[1]; v->pose_z = x[2];
    v->pose_roll = euler[0]; v->pose_pitch = euler[1]; v->pose_yaw = euler[2];
    v->twist_vx = x[7]; v->twist_vy = x[8]; v->twist_vz = x[9];
    v->twist_wx = x[10]; v->twist_wy = x[11]; v->twist_wz = x[12];
    PlatformDriveSlopes slopes;
    inputs_at(fmu, t, x, torque, force, &slopes, wrench);
    ModelInternal *in = &fmu->s.internal;
    memcpy(in->output_torque, torque, sizeof torque), memcpy(in->output_force, force, sizeof force);
    memcpy(in->output_wrench, wrench, sizeof wrench), in->output_slopes = slopes;
    double torque_applied[PLATFORM_LEGS], force_applied[PLATFORM_LEGS];
    platform_applied_efforts(p, legs, torque, force, &slopes, torque_applied, force_applied);
    for (int i = 0; i < PLATFORM_LEGS; i++) {
        *fmu_real(fmu, VR_TORQUE_APPLIED[i]) = torque_applied[i];
        *fmu_real(fmu, VR_FORCE_APPLIED[i]) = force_applied[i];
    }
    v->energy_drive = x[E_DRIVE];
    v->energy_transmission_loss = x[E_TRANSMISSION];
    v->energy_friction_loss = x[E_FRICTION];
    v->energy_load = x[E_LOAD];
}

/* The energies and powers now: an evaluation of the dynamics of their own, so computed when read
 * (MODEL_LAZY_OUTPUTS): a master that reads the pose and the legs every step does not pay for them.
 * The inputs are those the other outputs were computed with (a step's input derivatives are spent
 * by the time of the read). */
int model_output_is_lazy(int vr) {
    return vr == VR_energy_kinetic || vr == VR_energy_potential || vr == VR_power_drive ||
           vr == VR_power_transmission_loss || vr == VR_power_friction_loss || vr == VR_power_load;
}

void model_compute_lazy_outputs(FmuInstance *fmu) {
    ModelVariables *v = &fmu->s.v;
    const ModelInternal *in = &fmu->s.internal;
    double dxdt[MODEL_N_STATES];
    PlatformDiagnostics d;
    if (platform_derivatives(&in->platform, fmu->s.x, in->output_torque, in->output_force, &in->output_slopes,
                             in->output_wrench, dxdt, &d) != 0)
        d.drive_power = NAN;
    v->energy_kinetic = d.kinetic;
    v->energy_potential = d.potential;
    v->power_drive = d.drive_power;
    v->power_transmission_loss = d.transmission_loss;
    v->power_friction_loss = d.friction_loss;
    v->power_load = d.load_power;
}

fmi2Status model_validate(FmuInstance *fmu) {
    const ModelVariables *v = &fmu->s.v;
    int errors = 0;
    if (v->transmission_force_torque > v->transmission_screw_ratio)
        errors += fmu_reject(fmu, VR_transmission_force_torque,
                         "exceeds transmission.screw_ratio: the transfer efficiency K_FT / i_theta would pass 1");
    if (!(v->limit_leg_length_min < v->limit_leg_length_max))
        errors += fmu_reject(fmu, VR_limit_leg_length_min, "must be below limit.leg_length_max");

    ModelInternal in;
    if (build_internal(v, &in) != 0) {
        if (v->geometry_layout == 2)
            fmu_log(fmu, fmi2Error, "logStatusError",
                    "geometry: no layout: with the explicit joints a leg has zero length at geometry.neutral");
        else
            fmu_log(fmu, fmi2Error, "logStatusError",
                    "geometry: no layout with r_a = %g m, r_b = %g m, d_a = %g m, d_b = %g m, l_0 = %g m (a spacing "
                    "reaches the circle's diameter, or l_0 is shorter than the legs' horizontal reach)",
                    v->geometry_upper_joint_radius, v->geometry_lower_joint_radius, v->geometry_upper_joint_spacing,
                    v->geometry_lower_joint_spacing, v->geometry_middle_leg_length);
        return fmi2Error;
    }
    const Platform *p = &in.platform;
    for (int i = 0; i < PLATFORM_LEGS; i++)
        for (int j = i + 1; j < PLATFORM_LEGS; j++) {
            double du = 0.0, dl = 0.0;
            for (int k = 0; k < 3; k++) {
                du += pow(p->upper_joint[i][k] - p->upper_joint[j][k], 2);
                dl += pow(p->lower_joint[i][k] - p->lower_joint[j][k], 2);
            }
            if (du < 1e-12 || dl < 1e-12) {
                fmu_log(fmu, fmi2Error, "logStatusError", "geometry: the %s joints of legs %d and %d coincide",
                        du < 1e-12 ? "upper" : "lower", i + 1, j + 1);
                errors++;
            }
        }
    if (errors) return fmi2Error;

    /* The start pose must be reachable: every leg longer than zero, above its lower joint, and the
     * legs not singular; out-of-stroke is judged as at any other time. */
    double x[MODEL_N_STATES];
    memset(x, 0, sizeof x);
    initial_state(v, x);
    fmi2Status status = check_limits(fmu, &in, x, fmu->s.time);
    if (status == fmi2Error) fmu_log(fmu, fmi2Error, "logStatusError", "initial.pose: the start pose is not admissible");
    return status == fmi2Error ? fmi2Error : fmi2OK;
}
