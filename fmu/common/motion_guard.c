/* A reference motion held within an envelope (motion_guard.h). */
#include "motion_guard.h"

#include <math.h>
#include <string.h>

/* The acceleration, constant over the next h, that takes a value moving at `rate` towards a goal
 * moving at goal_rate with goal_acceleration, as fast as the limits allow, and lands on it: the
 * rate it asks for at the step's end is the largest from which braking at a_max stops on the goal
 * (the braking curve of whole steps: the step's own travel counted, so braking starts in time and
 * never overshoots), near the goal a quarter of the error a step (the error then decays by real
 * factors 0.70 and 0.18 a step: no ringing). */
static double towards(double value, double rate, double goal, double goal_rate, double goal_acceleration,
                      double v_max, double a_max, double h) {
    const double error = goal - value, distance = fabs(error), direction = error < 0.0 ? -1.0 : 1.0;
    const double closing = direction * (rate - goal_rate);      /* [/s] towards the goal, relative to it */
    /* w, the closing rate at the step's end: (closing + w) h / 2 + w^2 / (2 a_max) = distance */
    const double room = 0.25 * h * h + 2.0 * (distance - 0.5 * closing * h) / a_max;
    const double braking = room >= 0.0 ? a_max * (sqrt(room) - 0.5 * h) : -INFINITY;
    double wanted = goal_rate + goal_acceleration * h + direction * fmin(braking, 0.25 * distance / h);
    wanted = fmax(-v_max, fmin(v_max, wanted));
    return fmax(-a_max, fmin(a_max, (wanted - rate) / h));
}

void motion_guard_carry(int n, double *motion, double h) {
    for (int i = 0; i < n; i++) {
        double *value = &motion[i], *rate = &motion[n + i];
        const double acceleration = motion[2 * n + i];
        *value += *rate * h + 0.5 * acceleration * h * h;
        *rate += acceleration * h;
    }
}

int motion_guard_advance(const MotionGuard *g, double *motion, const double *goal, double h) {
    const int n = g->n;
    double back[MOTION_GUARD_CHANNELS];
    const int returning = g->recover ? g->recover(g->context, motion, back) : 0;
    for (int i = 0; i < n; i++)
        motion[2 * n + i] = towards(motion[i], motion[n + i], returning ? back[i] : goal[i],
                                    returning ? 0.0 : goal[n + i], returning ? 0.0 : goal[2 * n + i], g->rate_max[i],
                                    g->acceleration_max[i], h);
    /* the envelope: it may hold the motion back, towards braking (not on the way back in) */
    if (returning) return returning;
    return g->guard ? g->guard(g->context, h, motion, motion + n, motion + 2 * n) : 0;
}

int motion_guard_takes(const MotionGuard *g, double h, const double *own) {
    const int n = g->n;
    double scratch[MOTION_GUARD_CHANNELS];
    if (g->recover && g->recover(g->context, own, scratch)) return 0;
    for (int i = 0; i < n; i++) scratch[i] = own[2 * n + i];
    return !g->guard || !g->guard(g->context, h, own, own + n, scratch);
}

int motion_guard_caught_up(int n, const double *motion, const double *own) {
    for (int i = 0; i < n; i++)
        if (!(fabs(motion[i] - own[i]) <= 1e-7 && fabs(motion[n + i] - own[n + i]) <= 1e-5)) return 0;
    return 1;
}

int motion_guard_follow(const MotionGuard *g, double *motion, int *active, const double *own, double h) {
    const int n = g->n;
    if ((*active != 2 || motion_guard_caught_up(n, motion, own)) && motion_guard_takes(g, h, own)) {
        memcpy(motion, own, 3 * (size_t)n * sizeof(double));
        *active = 3;
        return -1;
    }
    if (!*active) memcpy(motion, own, 3 * (size_t)n * sizeof(double)); /* it starts where the source is */
    *active = 2;
    return motion_guard_advance(g, motion, own, h); /* towards the source's motion now */
}
