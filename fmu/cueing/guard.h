/* cueing: the guard on its own output (guard = true, guard.c). */
#ifndef CUEING_GUARD_H
#define CUEING_GUARD_H

#include "fmu_common.h"

typedef struct CueingGuard CueingGuard;

/* The platform's envelope and the guard's limits from the parameters (limit.*, guard.*, the joints
 * geometry.* and the neutral pose); NULL with a logged reason if it cannot be had. */
CueingGuard *cueing_guard_create(FmuInstance *fmu);
void cueing_guard_free(FmuInstance *fmu, CueingGuard *guard);

/* 1 if the guard's state (a state set back, its bytes perhaps foreign) is one it can be in; 0 with
 * a logged reason otherwise. */
int cueing_guard_state_valid(FmuInstance *fmu);

/* At the start: nothing held, nothing counted. */
void cueing_guard_initialize(FmuInstance *fmu);

/* The pose reference handed on (outputs pose_ref.*, pose_ref_rate.* and their derivatives) in
 * `reference`, which comes in as the cueing's own (value, rate, acceleration per DOF): where a step
 * has just ended, the guard takes the cueing's motion there (once a step); while it holds the
 * reference, the reference's own replaces it (carried from the guard's last step to now, between
 * Model Exchange's steps of it). guard NULL: off, the cueing's own as it is. */
void cueing_guard_hand_on(FmuInstance *fmu, CueingGuard *guard, double reference[3][6]);

/* Model Exchange: where guard.period has passed since the guard last took the cueing's motion, a
 * step of it ends now (1: the outputs take it, model_compute_outputs); 0 otherwise or guard NULL. */
int cueing_guard_time_event(FmuInstance *fmu, CueingGuard *guard);

/* Model Exchange: when the guard's next step ends (INFINITY for guard NULL). */
double cueing_guard_next_step(const FmuInstance *fmu, const CueingGuard *guard);

/* The derivative of that order (1, 2) of output d's value (rate = 0) or rate (rate = 1) while the
 * guard holds the reference, into *value; 0 where the cueing's own is handed on. */
int cueing_guard_derivative(const FmuInstance *fmu, int d, int rate, int order, double *value);

#endif
