/* cueing: the model-predictive cueing (algorithm 2, mpc.c), which model.c calls in the classical
 * washout's place. */
#ifndef CUEING_MPC_H
#define CUEING_MPC_H

#include "fmu_common.h"
#include "platform.h"

/* The vehicle's motion k (0-2 specific force, 3-5 angular rate) at t, its rate into *rate (model.c). */
double cueing_vehicle(FmuInstance *fmu, int k, double t, double *rate);
/* The vehicle's motion k (0-2 specific force, 3-5 angular rate) at t as the MPC predicts it at t_now:
 * the recorded motion (vehicle.file) up to mpc.preview ahead of now, the input now for a live drive;
 * beyond, the last of it held, continued along its trend (mpc.prediction_trend: the rate the last
 * solve took, fmu->s.internal.mpc.trend_rate) and returning to rest (mpc.prediction_decay). */
double cueing_vehicle_ahead(FmuInstance *fmu, int k, double t_now, double t);
/* The vehicle's rate per DOF where what the MPC reads at t_now ends (now, or mpc.preview on into a
 * recording): over the last mpc.period, from the past alone, as a live feed shows it. */
void cueing_vehicle_rate(FmuInstance *fmu, double t_now, double rate[6]);
/* Pitch's rate in roll's measure (model.c): tilt.rate_limit / tilt.pitch_rate_limit, 1 without the latter. */
double cueing_pitch_rate_scale(const FmuInstance *fmu);

/* The platform of the joints geometry.* at the neutral pose neutral.* (the mechanics' layout, as
 * the MPC's envelope and the guard's take it); 0 with a logged reason if a leg has no length. */
int cueing_platform(FmuInstance *fmu, Platform *platform);

typedef struct MpcData MpcData;

/* Builds the MPC's data for the parameters (the prediction, the QP's constant parts, the solver's
 * workspace); NULL with a logged reason if it cannot be had. */
MpcData *mpc_create(FmuInstance *fmu);
void mpc_free(FmuInstance *fmu, MpcData *data);

/* At the start: the platform at neutral, the perception settled, then the first solve. */
void mpc_initialize(FmuInstance *fmu, MpcData *data);
/* One communication step of h: the motion and the perception advanced, a solve where one is due. */
fmi2Status mpc_do_step(FmuInstance *fmu, MpcData *data, double h);
/* The perceived error (the platform's felt motion less the vehicle's through the otoliths and
 * canals: specific force x, y, z, angular rate roll, pitch, yaw) now. */
void mpc_perceived_error(FmuInstance *fmu, const MpcData *data, double y[6]);
/* Model Exchange: the state's derivatives under the accelerations held since the last solve; at an
 * event, a solve where one is due; the time the next is. */
void mpc_derivatives(FmuInstance *fmu, const MpcData *data, double *dxdt);
/* The nominal value of each state (MODEL_N_STATES): 1 for the platform's motion; for each organ's
 * state the size that moves the perceived error by 0.1 (m/s^2, rad/s), below the indifference
 * thresholds, so that an importer's solver (absolute tolerance: the relative one times the nominal)
 * holds the perceived errors, not only the motion, to its tolerance. */
void mpc_state_nominals(const MpcData *data, double *nominals);
/* A solve where a period has passed since the last (1: solved, a new plan), else 0. */
int mpc_time_event(FmuInstance *fmu, MpcData *data);
double mpc_next_solve(const FmuInstance *fmu);
/* The pose reference (value and first three derivatives per DOF, from neutral) into pose. */
void mpc_pose(const FmuInstance *fmu, double pose[6][4]);

#endif
