/* A reference motion held within an envelope: per channel its value, rate and acceleration
 * ([3][n], the acceleration constant over each step), moved towards a goal within each channel's
 * rate and acceleration limits, held within the envelope by `guard`, brought back in by `recover`
 * where it is outside. The step kernel's live input and cueing guard (cosim/engine/kernel/realtime.c)
 * step it; the envelope is the application's (fmu/mechanics/envelope.h: the platform's). */
#ifndef MOTION_GUARD_H
#define MOTION_GUARD_H

enum { GUARD_KINDS = 8, MOTION_GUARD_CHANNELS = 64 };

/* May replace the acceleration (per channel, constant over the next h) that the reference at
 * value with rate is about to take; returns the bits (< 1 << GUARD_KINDS) of the limits it held
 * back, 0 if it took it as asked. */
typedef int (*GuardFn)(void *context, double h, const double *value, const double *rate, double *acceleration);
/* 0 if the values are within the envelope; otherwise the bits (< 1 << GUARD_KINDS) counted for a
 * step spent going back, and in `goal` the values the reference goes back to (inside). */
typedef int (*RecoverFn)(void *context, const double *value, double *goal);

typedef struct {
    int n;                                     /* channels, at most MOTION_GUARD_CHANNELS */
    const double *rate_max, *acceleration_max; /* per channel */
    GuardFn guard;                             /* NULL: the rate and acceleration limits alone */
    RecoverFn recover;                         /* NULL: a reference outside is only braked */
    void *context;                             /* the guard's and the recovery's */
} MotionGuard;

/* The motion ([3][n]) carried over h by its acceleration: values and rates at the step's end. */
void motion_guard_carry(int n, double *motion, double h);

/* The motion's acceleration over the next h ([3][n] in place): towards the goal ([3][n]: where it
 * is, its rate and acceleration now), or where the motion is outside the envelope towards the way
 * back in that `recover` gives, then held within the envelope by `guard` (not on the way back in).
 * Returns the bits of what held it back (recover's or guard's; 0: as asked). */
int motion_guard_advance(const MotionGuard *g, double *motion, const double *goal, double h);

/* 1 if a source's own motion ([3][n]) may be passed on as it is: inside the envelope, and the guard
 * would take its acceleration over the next h. */
int motion_guard_takes(const MotionGuard *g, double h, const double *own);

/* A source's own motion ([3][n] at the end of a step of h) guarded: passed on as it is while the
 * guard would take it (once a reference the guard held has caught up with it); where it would not,
 * a reference takes over from the motion last handed on (`motion`, [3][n], carried over the step by
 * the caller) and follows the source's within the limits and the envelope. `active`: 0 before the
 * first step, then 3 while the source's own is passed on, 2 while the reference is. Returns -1 when
 * the source's own is passed on (copied into `motion`), else the bits of what held the reference
 * back (motion_guard_advance). */
int motion_guard_follow(const MotionGuard *g, double *motion, int *active, const double *own, double h);

/* 1 if the motion has caught up with a source's own ([3][n]): the same values within 0.1 um (urad)
 * and rates within 10 um/s, so that handing the source's back moves nothing a drive feels. */
int motion_guard_caught_up(int n, const double *motion, const double *own);

#endif
