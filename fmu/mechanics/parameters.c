/* The mechanics' parameters -> the dynamics core's Platform (see parameters.h). */
#include "parameters.h"

#include "envelope.h"

#include <string.h>

#if defined(_WIN32)
#define MECHANICS_EXPORT __declspec(dllexport)
#else
#define MECHANICS_EXPORT __attribute__((visibility("default")))
#endif

static const double PI = 3.14159265358979323846;

#define JOINT(kind, i) {v->geometry_##kind##_joint_##i##_x, v->geometry_##kind##_joint_##i##_y, v->geometry_##kind##_joint_##i##_z}
#define JOINT_ARRAY(kind) {JOINT(kind, 1), JOINT(kind, 2), JOINT(kind, 3), JOINT(kind, 4), JOINT(kind, 5), JOINT(kind, 6)}

int mechanics_platform(const ModelVariables *v, Platform *p) {
    memset(p, 0, sizeof *p);
    const double to_deg = 180.0 / PI;
    const double lower[3] = {v->geometry_lower_pair_centre_1 * to_deg, v->geometry_lower_pair_centre_2 * to_deg,
                             v->geometry_lower_pair_centre_3 * to_deg};
    const double upper[3] = {v->geometry_upper_pair_centre_1 * to_deg, v->geometry_upper_pair_centre_2 * to_deg,
                             v->geometry_upper_pair_centre_3 * to_deg};
    int status;
    if (v->geometry_layout == 2) {
        const double base[6][3] = JOINT_ARRAY(base), top[6][3] = JOINT_ARRAY(platform);
        const double neutral[6] = {v->geometry_neutral_x, v->geometry_neutral_y, v->geometry_neutral_z,
                                   v->geometry_neutral_roll, v->geometry_neutral_pitch, v->geometry_neutral_yaw};
        status = platform_layout_from_joints(p, top, base, neutral);
    } else {
        status = platform_layout_from_radii(p, v->geometry_upper_joint_radius, v->geometry_lower_joint_radius,
                                            v->geometry_upper_joint_spacing, v->geometry_lower_joint_spacing,
                                            v->geometry_middle_leg_length, lower, upper);
    }
    p->platform_mass = v->platform_mass;
    p->platform_inertia[0] = v->platform_inertia_xx;
    p->platform_inertia[1] = v->platform_inertia_yy;
    p->platform_inertia[2] = v->platform_inertia_zz;
    p->moving_mass = v->actuator_moving_mass;
    p->moving_inertia = v->actuator_moving_inertia;
    p->moving_com = v->actuator_moving_com;
    p->rotating_mass = v->actuator_rotating_mass;
    p->rotating_inertia = v->actuator_rotating_inertia;
    p->rotating_com = v->actuator_rotating_com;
    p->motor_mass = v->motor_system_mass;
    p->motor_inertia = v->motor_system_inertia;
    p->motor_com = v->motor_system_com;
    p->rotor_inertia = v->motor_system_rotor_inertia;
    p->screw_ratio = v->transmission_screw_ratio;
    p->force_torque = v->transmission_force_torque;
    p->viscous_friction = v->motor_viscous_friction;
    p->leg_spin_inertia = v->actuator_spin_inertia;
    p->joint_friction_lower = v->joint_friction_lower;
    p->joint_friction_upper = v->joint_friction_upper;
    p->gravity[0] = v->environment_gravity_x;
    p->gravity[1] = v->environment_gravity_y;
    p->gravity[2] = v->environment_gravity_z;
    p->actuator_inertia_on = v->effects_actuator_inertia;
    p->motor_inertia_on = v->effects_motor_inertia;
    p->friction_on = v->effects_friction;
    return status;
}

MECHANICS_EXPORT int mechanics_value_references(void) { return VR_COUNT; }

MECHANICS_EXPORT int mechanics_platform_from_values(const double *values, int count, Platform *p) {
    if (count != VR_COUNT) return -2;
    ModelVariables v;
    memset(&v, 0, sizeof v);
    for (int vr = 1; vr < VR_COUNT; vr++) {
        char *field = (char *)&v + fmu_variables[vr].offset;
        switch (fmu_variables[vr].type) {
        case FMU_REAL: *(double *)field = values[vr]; break;
        case FMU_INTEGER:
        case FMU_BOOLEAN: *(int *)field = (int)values[vr]; break;
        case FMU_STRING: break;
        }
    }
    return mechanics_platform(&v, p);
}

#define P(field) STRUCT_LAYOUT_FIELD(Platform, field)
#define L(field) STRUCT_LAYOUT_FIELD(LegGeometry, field)
#define D(field) STRUCT_LAYOUT_FIELD(PlatformDiagnostics, field)
static const StructLayout LAYOUT[] = {
    STRUCT_LAYOUT(Platform), P(upper_joint), P(lower_joint), P(neutral_pose), P(neutral_length), P(platform_mass),
    P(platform_inertia), P(moving_mass), P(moving_inertia), P(moving_com), P(rotating_mass), P(rotating_inertia),
    P(rotating_com), P(motor_mass), P(motor_inertia), P(motor_com), P(rotor_inertia), P(screw_ratio),
    P(force_torque), P(viscous_friction), P(leg_spin_inertia), P(joint_friction_lower), P(joint_friction_upper),
    P(gravity), P(actuator_inertia_on), P(motor_inertia_on), P(friction_on),
    STRUCT_LAYOUT(LegGeometry), L(axis), L(length), L(arm), L(velocity),
    STRUCT_LAYOUT(PlatformDiagnostics), D(mass_matrix), D(kinetic), D(potential), D(drive_power),
    D(transmission_loss), D(friction_loss), D(load_power), D(singular),
#define E(field) STRUCT_LAYOUT_FIELD(PlatformEnvelope, field)
    STRUCT_LAYOUT(PlatformEnvelope), E(platform), E(length_min), E(length_max), E(joint_angle_max),
    E(leg_velocity_max), E(leg_acceleration_max), E(acceleration_max), E(arm), E(neutral_axis), E(prepared),
    STRUCT_LAYOUT_END};

MECHANICS_EXPORT const StructLayout *platform_core_layout(void) { return LAYOUT; }
