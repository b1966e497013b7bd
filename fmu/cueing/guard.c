/* cueing: the guard on its own output (guard = true). The pose reference is held within the
 * platform's envelope (fmu/mechanics/envelope.c: every leg within its stroke less the margin,
 * every joint within its tilt, the legs' speeds and accelerations within their limits, braking in
 * time) exactly as `cosim run`'s master holds a cueing's output (the step kernel's guard on a
 * source, cosim/engine/kernel/realtime.c), by the same stepping (fmu/common/motion_guard.c): after
 * each step the cueing's own motion (value, rate, acceleration) is passed on as it is while the
 * guard would take it; where it would not, a reference takes over from the motion last handed on,
 * follows the cueing's within the limits and the envelope (its acceleration constant over each
 * step: the outputs' derivatives its exact motion), and hands it back once it has caught up. One
 * outside the envelope is brought back in. So a tool that runs this FMU (or the one-FMU export of a
 * cueing scene) gets the platform `cosim run` gets, bit for bit.
 *
 * Model Exchange steps the guard alike at time events guard.period apart (a scene's step): the
 * reference it holds is its motion carried from its last step (its acceleration constant). */
#include "guard.h"

#include <math.h>
#include <string.h>

#include "envelope.h"
#include "motion_guard.h"
#include "mpc.h"

enum { DOF = 6, HELD_KINDS = 5 };

/* The outputs counting the steps held, per bit of what held the reference (envelope.h's ENVELOPE_*). */
static const int HELD[HELD_KINDS] = {VR_guard_held_stroke, VR_guard_held_joint, VR_guard_held_leg_velocity,
                                     VR_guard_held_leg_acceleration, VR_guard_held_return};

struct CueingGuard {
    PlatformEnvelope envelope;
    double rate_max[DOF];
};

CueingGuard *cueing_guard_create(FmuInstance *fmu) {
    const ModelVariables *v = &fmu->s.v;
    CueingGuard *g = (CueingGuard *)fmu_calloc(fmu, 1, sizeof(CueingGuard));
    if (!g) {
        fmu_log(fmu, fmi2Error, "logStatusError", "cueing: out of memory");
        return NULL;
    }
    PlatformEnvelope *e = &g->envelope;
    if (!cueing_platform(fmu, &e->platform)) {
        fmu_free(fmu, g);
        return NULL;
    }
    e->length_min = v->limit_leg_length_min + v->limit_stroke_margin;
    e->length_max = v->limit_leg_length_max - v->limit_stroke_margin;
    e->joint_angle_max = v->limit_joint_angle;
    e->leg_velocity_max = v->limit_leg_velocity;
    e->leg_acceleration_max = v->limit_leg_acceleration;
    for (int d = 0; d < DOF; d++) {
        e->acceleration_max[d] = d < 3 ? v->guard_acceleration_max : v->guard_angular_acceleration_max;
        g->rate_max[d] = d < 3 ? v->guard_velocity_max : v->guard_angular_velocity_max;
    }
    for (int i = 0; i < PLATFORM_LEGS; i++) { /* the farthest upper joint from the platform's origin */
        const double *a = e->platform.upper_joint[i];
        const double arm = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
        if (arm > e->arm) e->arm = arm;
    }
    if (!(e->length_min < e->length_max) || !platform_envelope_contains(e, e->platform.neutral_pose)) {
        fmu_log(fmu, fmi2Error, "logStatusError", "guard: the neutral pose is outside the envelope (limit.leg_length_"
                "min/max less limit.stroke_margin, limit.joint_angle): there is nowhere to hold the reference");
        fmu_free(fmu, g);
        return NULL;
    }
    return g;
}

void cueing_guard_free(FmuInstance *fmu, CueingGuard *guard) { fmu_free(fmu, guard); }

int cueing_guard_state_valid(FmuInstance *fmu) {
    const GuardState *s = &fmu->s.internal.guard;
    int finite = isfinite(s->step) && s->step >= 0.0 && isfinite(s->taken_at);
    for (int k = 0; k < 3 * DOF; k++) finite = finite && isfinite((&s->motion[0][0])[k]);
    if (finite && (s->active == 0 || s->active == 2 || s->active == 3) && (s->pending == 0 || s->pending == 1))
        return 1;
    fmu_log(fmu, fmi2Error, "logStatusError", "guard: the state's guarded reference is not one the guard can be in");
    return 0;
}

void cueing_guard_initialize(FmuInstance *fmu) {
    memset(&fmu->s.internal.guard, 0, sizeof fmu->s.internal.guard);
    fmu->s.internal.guard.taken_at = fmu->s.time;
    for (int k = 0; k < HELD_KINDS; k++) *fmu_real(fmu, HELD[k]) = 0.0;
}

/* The guard's motion over the next step from the cueing's own at the step's end: carried over the
 * step, then the cueing's own passed on or followed (motion_guard_follow, as the master's guard on
 * a source steps it in cosim/engine/kernel/realtime.c). */
static void take_step(FmuInstance *fmu, CueingGuard *guard, const double own[3 * DOF]) {
    GuardState *s = &fmu->s.internal.guard;
    const MotionGuard g = {DOF, guard->rate_max, guard->envelope.acceleration_max, platform_envelope_guard,
                           platform_envelope_recovery, &guard->envelope};
    if (s->active >= 2) motion_guard_carry(DOF, &s->motion[0][0], s->step);
    const int held = motion_guard_follow(&g, &s->motion[0][0], &s->active, own, s->step);
    for (int k = 0; k < HELD_KINDS; k++)
        if (held > 0 && (held & (1 << k))) *fmu_real(fmu, HELD[k]) += 1.0;
}

void cueing_guard_hand_on(FmuInstance *fmu, CueingGuard *guard, double reference[3][6]) {
    GuardState *s = &fmu->s.internal.guard;
    if (!guard) return;
    if (s->pending) {
        take_step(fmu, guard, &reference[0][0]);
        s->pending = 0;
        s->taken_at = fmu->s.time;
    }
    if (s->active != 2) return;
    memcpy(reference, s->motion, sizeof s->motion);
    const double since = fmu->s.time - s->taken_at; /* Model Exchange, between the guard's steps */
    if (since > 0.0) motion_guard_carry(DOF, &reference[0][0], since);
}

int cueing_guard_time_event(FmuInstance *fmu, CueingGuard *guard) {
    GuardState *s = &fmu->s.internal.guard;
    if (!guard || fmu->s.time < s->taken_at + (1.0 - 1e-9) * fmu->s.v.guard_period) return 0;
    s->pending = 1;
    s->step = fmu->s.time - s->taken_at;
    return 1;
}

double cueing_guard_next_step(const FmuInstance *fmu, const CueingGuard *guard) {
    return guard ? fmu->s.internal.guard.taken_at + fmu->s.v.guard_period : INFINITY;
}

int cueing_guard_derivative(const FmuInstance *fmu, int d, int rate, int order, double *value) {
    const GuardState *s = &fmu->s.internal.guard;
    if (s->active != 2) return 0;
    const int k = rate + order; /* the motion's row: 1 rate, 2 acceleration, beyond 0 (constant over the step) */
    *value = k <= 2 ? s->motion[k][d] : 0.0;
    return 1;
}
