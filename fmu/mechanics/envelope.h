/* The motion envelope a live reference is held in (the step kernel's guard, docs/guide/realtime.md,
 * and the cueing FMU's own, fmu/cueing/guard.c): every leg within its stroke less a margin that
 * covers the drives' tracking error, every joint within its largest tilt, every leg's speed and
 * acceleration within their limits. Part of the platform_core library (the master's) and of the
 * cueing FMU, not of the mechanics FMU. */
#ifndef PLATFORM_ENVELOPE_H
#define PLATFORM_ENVELOPE_H

#include "platform.h"

typedef struct {
    Platform platform;
    double length_min, length_max;       /* [m] the stroke less the margin at both ends */
    double joint_angle_max;              /* [rad] at either joint, from the leg's neutral direction */
    double leg_velocity_max;             /* [m/s] */
    double leg_acceleration_max;         /* [m/s^2] */
    double acceleration_max[6];          /* the reference's own largest acceleration per channel: its braking */
    double arm;                          /* [m] the farthest upper joint from the platform's origin */
    /* derived on first use (prepared 0 until then): each leg's direction at the neutral pose */
    double neutral_axis[PLATFORM_LEGS][3];
    int prepared;
} PlatformEnvelope;

/* What a guard reports it held back (bits), and so what the kernel counts per step; RETURN: the
 * reference was outside and is on its way back in (platform_envelope_recovery). */
enum { ENVELOPE_STROKE = 1, ENVELOPE_JOINT = 2, ENVELOPE_LEG_VELOCITY = 4, ENVELOPE_LEG_ACCELERATION = 8,
       ENVELOPE_RETURN = 16 };

/* 1 if the pose (x, y, z [m], roll, pitch, yaw [rad]) puts every leg within the stroke less the
 * margin and every joint within its tilt, 0 otherwise: the step kernel's AdmissibleFn. */
int platform_envelope_contains(void *envelope, const double *pose);

/* The step kernel's GuardFn: the reference at pose with its rate is to move with `acceleration`
 * (per channel, constant) over the next h; replaces it by the one nearest to it on the way to the
 * braking acceleration whose motion, and the braking from where it ends, stay within the envelope.
 * Returns the bits of the limits the asked acceleration would have broken (0: taken as asked). */
int platform_envelope_guard(void *envelope, double h, const double *pose, const double *rate, double *acceleration);

/* The step kernel's RecoverFn: 0 if the pose is inside the envelope (stroke and joints); otherwise
 * ENVELOPE_RETURN, with `goal` the pose the reference returns to: on the straight line from the
 * pose to the platform's neutral pose, past the envelope's edge by a tenth of what is left of the
 * way (the neutral pose itself where that line finds no inside). */
int platform_envelope_recovery(void *envelope, const double *pose, double *goal);

#endif
