/* The motion envelope of a live reference (envelope.h).
 *
 * The reference moves with a constant acceleration over each step. A motion is safe when the
 * state it ends in can still stop inside the envelope: braking, every channel decelerates at the
 * same fraction of its speed (a straight line in pose space along its rate, stopping at a step's
 * end, within each channel's largest acceleration), and the braking that lasts one step more than
 * that is checked at BRAKING_SAMPLES points along its path. Braking from a safe state is safe
 * again (its path is the rest of the one checked), so a reference that starts safe stays so: the
 * guard takes the asked acceleration if it is safe, else the largest blend of it with braking
 * that is (bisection), and braking itself when none is.
 *
 * A reference outside the envelope (a takeover from a reference that was outside, parameters
 * changed under it) is not held there: recovery gives it a pose inside to go back to, on the way
 * to the neutral pose, and the kernel moves it there within its rate and acceleration limits. */
#include "envelope.h"

#include <math.h>

#if defined(_WIN32)
#define ENVELOPE_EXPORT __declspec(dllexport)
#else
#define ENVELOPE_EXPORT __attribute__((visibility("default")))
#endif

enum { BRAKING_SAMPLES_MAX = 8, BISECTIONS = 6, EDGE_BISECTIONS = 40 };
static const double SAMPLE_SPACING = 1e-3; /* [m] of a joint's travel between two checked points of a braking path */

/* The limits a pose moving at `rate` breaks; each leg's speed into `leg_velocity`. */
static int pose_violations(const PlatformEnvelope *e, const double pose[6], const double rate[6],
                           double leg_velocity[PLATFORM_LEGS]) {
    double x[PLATFORM_STATES], R[9];
    LegGeometry legs[PLATFORM_LEGS];
    platform_state_from_pose(pose, rate, x);
    platform_legs(&e->platform, x, legs); /* Eq 2-3: lengths, directions, extension rates */
    platform_rotation_from_euler(pose[3], pose[4], pose[5], R);
    const double cos_max = cos(e->joint_angle_max);
    int broken = 0;
    for (int i = 0; i < PLATFORM_LEGS; i++) {
        double lower, upper;
        platform_joint_cosines(R, legs[i].axis, e->neutral_axis[i], &lower, &upper);
        if (!(legs[i].length >= e->length_min && legs[i].length <= e->length_max)) broken |= ENVELOPE_STROKE;
        if (!(lower >= cos_max && upper >= cos_max)) broken |= ENVELOPE_JOINT;
        if (!(fabs(legs[i].velocity) <= e->leg_velocity_max)) broken |= ENVELOPE_LEG_VELOCITY;
        leg_velocity[i] = legs[i].velocity;
    }
    return broken;
}

/* The legs' neutral directions, once per envelope (the joints' tilts are measured from them). */
static const PlatformEnvelope *prepared(void *envelope) {
    PlatformEnvelope *e = (PlatformEnvelope *)envelope;
    if (!e->prepared) {
        const double at_rest[6] = {0, 0, 0, 0, 0, 0};
        double x[PLATFORM_STATES];
        LegGeometry neutral[PLATFORM_LEGS];
        platform_state_from_pose(e->platform.neutral_pose, at_rest, x);
        platform_legs(&e->platform, x, neutral);
        for (int i = 0; i < PLATFORM_LEGS; i++)
            for (int k = 0; k < 3; k++) e->neutral_axis[i][k] = neutral[i].axis[k];
        e->prepared = 1;
    }
    return e;
}

/* Steps of h the braking from `rate` takes, each channel at most its largest deceleration. */
static double braking_steps(const PlatformEnvelope *e, const double rate[6], double h) {
    double time = 0.0;
    for (int i = 0; i < 6; i++) time = fmax(time, fabs(rate[i]) / e->acceleration_max[i]);
    return ceil(time / h - 1e-9);
}

/* The limits broken by moving from (pose, rate) with `acceleration` over h, or by braking after. */
static int motion_violations(const PlatformEnvelope *e, double h, const double pose[6], const double rate[6], const double leg_velocity[PLATFORM_LEGS],
                             const double acceleration[6]) {
    double end[6], end_rate[6], end_leg_velocity[PLATFORM_LEGS], scratch[PLATFORM_LEGS];
    for (int i = 0; i < 6; i++) {
        end[i] = pose[i] + rate[i] * h + 0.5 * acceleration[i] * h * h;
        end_rate[i] = rate[i] + acceleration[i] * h;
    }
    int broken = pose_violations(e, end, end_rate, end_leg_velocity);
    for (int i = 0; i < PLATFORM_LEGS; i++)
        if (!(fabs(end_leg_velocity[i] - leg_velocity[i]) <= e->leg_acceleration_max * h))
            broken |= ENVELOPE_LEG_ACCELERATION;
    /* braking one step longer than it takes: the path from end to end + rate T / 2, its speed
     * falling as sqrt(1 - d) of the way d, checked every millimetre an upper joint travels (its
     * end always; a slow reference's short path at one point) */
    const double reach = 0.5 * (braking_steps(e, end_rate, h) + 1.0) * h;
    const double travel = reach * (sqrt(end_rate[0] * end_rate[0] + end_rate[1] * end_rate[1] + end_rate[2] * end_rate[2]) +
                                   e->arm * sqrt(end_rate[3] * end_rate[3] + end_rate[4] * end_rate[4] +
                                                 end_rate[5] * end_rate[5]));
    const int samples = travel < BRAKING_SAMPLES_MAX * SAMPLE_SPACING ? 1 + (int)(travel / SAMPLE_SPACING)
                                                                      : BRAKING_SAMPLES_MAX;
    for (int k = 1; k <= samples; k++) {
        const double d = (double)k / samples, slower = sqrt(fmax(0.0, 1.0 - d));
        double at[6], at_rate[6];
        for (int i = 0; i < 6; i++) {
            at[i] = end[i] + end_rate[i] * reach * d;
            at_rate[i] = end_rate[i] * slower;
        }
        broken |= pose_violations(e, at, at_rate, scratch) & (ENVELOPE_STROKE | ENVELOPE_JOINT);
    }
    return broken;
}

ENVELOPE_EXPORT int platform_envelope_contains(void *envelope, const double *pose) {
    const PlatformEnvelope *e = prepared(envelope);
    const double at_rest[6] = {0, 0, 0, 0, 0, 0};
    double leg_velocity[PLATFORM_LEGS];
    return (pose_violations(e, pose, at_rest, leg_velocity) & (ENVELOPE_STROKE | ENVELOPE_JOINT)) == 0;
}

ENVELOPE_EXPORT int platform_envelope_guard(void *envelope, double h, const double *pose, const double *rate,
                                            double *acceleration) {
    const PlatformEnvelope *e = prepared(envelope);
    double leg_velocity[PLATFORM_LEGS];
    pose_violations(e, pose, rate, leg_velocity);
    const int asked = motion_violations(e, h, pose, rate, leg_velocity, acceleration);
    if (!asked) return 0;
    /* braking: to rest at the end of a whole number of steps, the same deceleration each step */
    const double steps = braking_steps(e, rate, h);
    double wanted[6], braking[6], blend[6];
    for (int i = 0; i < 6; i++) {
        wanted[i] = acceleration[i];
        braking[i] = steps > 0.0 ? -rate[i] / (steps * h) : 0.0;
    }
    double safe = 0.0, unsafe = 1.0;
    for (int k = 0; k < BISECTIONS; k++) {
        const double s = 0.5 * (safe + unsafe);
        for (int i = 0; i < 6; i++) blend[i] = braking[i] + s * (wanted[i] - braking[i]);
        if (motion_violations(e, h, pose, rate, leg_velocity, blend)) unsafe = s;
        else safe = s;
    }
    for (int i = 0; i < 6; i++) acceleration[i] = braking[i] + safe * (wanted[i] - braking[i]);
    return asked;
}

ENVELOPE_EXPORT int platform_envelope_recovery(void *envelope, const double *pose, double *goal) {
    const PlatformEnvelope *e = prepared(envelope);
    if (platform_envelope_contains(envelope, pose)) return 0;
    const double *neutral = e->platform.neutral_pose;
    double outside = 0.0, inside = 1.0, at[6];
    if (platform_envelope_contains(envelope, neutral)) {
        for (int k = 0; k < EDGE_BISECTIONS; k++) { /* the edge between pose (outside) and neutral (inside) */
            const double s = 0.5 * (outside + inside);
            for (int i = 0; i < 6; i++) at[i] = pose[i] + s * (neutral[i] - pose[i]);
            if (platform_envelope_contains(envelope, at)) inside = s;
            else outside = s;
        }
        inside += 0.1 * (1.0 - inside);
    }
    for (int i = 0; i < 6; i++) goal[i] = pose[i] + inside * (neutral[i] - pose[i]);
    return ENVELOPE_RETURN;
}
