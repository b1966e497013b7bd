/* cueing: the classical washout (Reid and Nahon 1985; Nahon and Reid 1990) as an FMU, so that a
 * scene can take a vehicle's motion instead of a platform pose.
 *
 * Inputs, vehicle frame at the occupant's head (x forward, y left, z up): specific force f and
 * angular rate w. Per channel, scaled and clipped, then filtered (state space x' = A x + B u):
 *
 *   translation, a = x, y, z:  u = clip(k_a (f_a - g [a = z]))
 *     position p_a = s / ((s^2 + 2 zeta w_n s + w_n^2)(s + w_b)) u: the acceleration high-passed
 *     (second order, times s / (s + w_b) for the third order) and integrated twice:
 *       z' = -w_b z + u,  y = u - w_b z,  p' = v,  v' = y - 2 zeta w_n v - w_n^2 p
 *   rotation, r = roll, pitch, yaw:  u = clip(k_r w_r)
 *     angle b_r = s / (s^2 + 2 zeta w_n s + w_n^2) u: the rate high-passed and integrated:
 *       q' = b,  b' = u - 2 zeta w_n b - w_n^2 q
 *   tilt coordination:  u = k_tilt f_x (pitch), k_tilt f_y (roll)
 *     l = w_n^2 / (s^2 + 2 zeta w_n s + w_n^2) u, the sustained part of the specific force, stood
 *     for by gravity: pitch_t = -asin(l_x / g), roll_t = asin(l_y / g) (R = Rz Ry Rx: a pitch theta
 *     is felt as f_x = -g sin theta, a roll phi as f_y = g sin phi), at most tilt.limit; the tilt
 *     follows its target with the tilt vector (roll, pitch) turning at no more than tilt.rate_limit
 *     (with tilt.pitch_rate_limit: within the ellipse of the two, pitch counted in roll's measure).
 *
 * The pose reference is the neutral pose plus p and b, with the tilt added to roll and pitch; its
 * rate and acceleration (fmi2GetRealOutputDerivatives) are the filters' own, exact. The filters are
 * discretised exactly at the communication step h for the input the master gives over the step
 * (its value and rate: first-order hold): x(t + h) = e^{hA} x + h phi_1(hA) B u_0 + h^2 phi_2(hA)
 * B u_1, the phi-functions of the shared solvers (ode.h) kept per step size as model data. The tilt's
 * rate limit acts once a step. Angular rates are taken as the rates of roll, pitch and yaw (small
 * angles), and the translational channel's specific force in the vehicle frame as in the platform's.
 * The motion is the inputs', or a recorded one's from vehicle.file (linear between its rows).
 *
 * algorithm = 2 takes the model-predictive cueing of mpc.c instead of these filters.
 *
 * As Model Exchange (the end of this file) the same states (fmu->s.x, laid out in variables.h) go
 * to the importer's solver with their derivatives x' = A x + B u; the tilt's rate limit acts
 * continuously (tilt_rate), and the MPC's solves are time events.
 */
#include "fmu_common.h"
#include "guard.h"
#include "mpc.h"
#include "table.h"

#include <math.h>
#include <string.h>

enum { N_TRANSLATION = 3, N_ROTATION = 3, N_TILT = 2, N_CHANNELS = 8, MAX_ORDER = 3 };

/* A channel's filter: order n (its states at `first` in the model's state), x' = A x + B u. */
typedef struct {
    int n, first;
    double a[MAX_ORDER * MAX_ORDER], b[MAX_ORDER];
} Filter;

static const int FIRST[N_CHANNELS] = {0, 3, 6, 9, 11, 13, 15, 17}; /* translation x, y, z; rotation; tilt x, y */

static const int FORCE[3] = {VR_specific_force_x, VR_specific_force_y, VR_specific_force_z};
static const int RATE[3] = {VR_angular_rate_x, VR_angular_rate_y, VR_angular_rate_z};
static const int VEHICLE[6] = {VR_vehicle_specific_force_x, VR_vehicle_specific_force_y, VR_vehicle_specific_force_z,
                               VR_vehicle_angular_rate_x, VR_vehicle_angular_rate_y, VR_vehicle_angular_rate_z};
static const int POSE[6] = {VR_pose_ref_x, VR_pose_ref_y, VR_pose_ref_z, VR_pose_ref_roll, VR_pose_ref_pitch,
                            VR_pose_ref_yaw};
static const int POSE_RATE[6] = {VR_pose_ref_rate_x, VR_pose_ref_rate_y, VR_pose_ref_rate_z, VR_pose_ref_rate_roll,
                                 VR_pose_ref_rate_pitch, VR_pose_ref_rate_yaw};
static const int NEUTRAL[6] = {VR_neutral_x, VR_neutral_y, VR_neutral_z, VR_neutral_roll, VR_neutral_pitch,
                               VR_neutral_yaw};
/* per translational axis: gain, limit, frequency, damping, break; per rotational: gain, limit, frequency, damping */
static const int TRANSLATION[3][5] = {
    {VR_translation_x_gain, VR_translation_x_limit, VR_translation_x_frequency, VR_translation_x_damping, VR_translation_x_break},
    {VR_translation_y_gain, VR_translation_y_limit, VR_translation_y_frequency, VR_translation_y_damping, VR_translation_y_break},
    {VR_translation_z_gain, VR_translation_z_limit, VR_translation_z_frequency, VR_translation_z_damping, VR_translation_z_break}};
static const int ROTATION[3][4] = {
    {VR_rotation_roll_gain, VR_rotation_roll_limit, VR_rotation_roll_frequency, VR_rotation_roll_damping},
    {VR_rotation_pitch_gain, VR_rotation_pitch_limit, VR_rotation_pitch_frequency, VR_rotation_pitch_damping},
    {VR_rotation_yaw_gain, VR_rotation_yaw_limit, VR_rotation_yaw_frequency, VR_rotation_yaw_damping}};

/* ---- the vehicle's motion: the inputs, or vehicle.file's columns where it has them ---- */

static const char *const MOTION_NAMES[6] = {"specific_force.x", "specific_force.y", "specific_force.z",
                                            "angular_rate.x", "angular_rate.y", "angular_rate.z"};

/* What any vehicle's recorded motion stays within: 100 g of specific force, 100 rad/s of angular rate
 * (a value beyond is a broken file, not a vehicle: its cue would overflow the filters). */
static const double MOTION_BOUND[6] = {1000.0, 1000.0, 1000.0, 100.0, 100.0, 100.0};
static const char *const MOTION_UNITS[6] = {"m/s2", "m/s2", "m/s2", "rad/s", "rad/s", "rad/s"};

/* 1 if every value of the vehicle's table is within MOTION_BOUND; logs the first that is not. */
static int motion_within_bounds(FmuInstance *fmu, const FmuTable *table) {
    for (int k = 0; k < 6; k++) {
        const int c = table->column_of[k];
        if (c < 0) continue;
        for (int r = 0; r < table->rows; r++) {
            const double value = table->values[r * table->columns + c];
            if (fabs(value) <= MOTION_BOUND[k]) continue;
            fmu_log(fmu, fmi2Error, "logStatusError", "vehicle.file %s: %s = %g %s at t = %g s is beyond any vehicle's "
                    "motion (at most %g %s)", table->path, MOTION_NAMES[k], value, MOTION_UNITS[k], table->time[r],
                    MOTION_BOUND[k], MOTION_UNITS[k]);
            return 0;
        }
    }
    return 1;
}

/* The model data: the phi-functions per step size (derived), the vehicle table (read once), the
 * MPC's data (algorithm 2) and the guard's envelope (guard = true). */
typedef struct PhiCache PhiCache;
typedef struct {
    PhiCache *cache;
    FmuTable *vehicle;
    MpcData *mpc;
    CueingGuard *guard;
} ModelData;

/* Motion k (0-2 specific force, 3-5 angular rate) at t, and its rate into *rate. */
static double motion(FmuInstance *fmu, int k, double t, double *rate) {
    const ModelData *data = (const ModelData *)fmu->model_data;
    const int vr = k < 3 ? FORCE[k] : RATE[k - 3];
    if (data && data->vehicle && data->vehicle->column_of[k] >= 0) {
        double out[4];
        fmu_table_at(data->vehicle, data->vehicle->column_of[k], 1, t, out);
        if (rate) *rate = out[1];
        return out[0];
    }
    if (rate) *rate = fmu_input_rate_at(fmu, vr, t);
    return fmu_input_at(fmu, vr, t);
}

double cueing_vehicle(FmuInstance *fmu, int k, double t, double *rate) { return motion(fmu, k, t, rate); }

/* How far ahead of t_now the MPC reads motion k: a recording's up to mpc.preview on, a live input's now. */
static double seen_until(const FmuInstance *fmu, int k, double t_now) {
    const ModelData *data = (const ModelData *)fmu->model_data;
    const int recorded = data && data->vehicle && data->vehicle->column_of[k] >= 0;
    return recorded ? t_now + fmu->s.v.mpc_preview : t_now;
}

void cueing_vehicle_rate(FmuInstance *fmu, double t_now, double rate[6]) {
    const double period = fmu->s.v.mpc_period;
    for (int k = 0; k < 6; k++) {
        const double seen = seen_until(fmu, k, t_now);
        rate[k] = (motion(fmu, k, seen, NULL) - motion(fmu, k, seen - period, NULL)) / period;
    }
}

/* Beyond what it read (at seen), the MPC predicts the vehicle's motion from there: the last of it
 * held, or continued along its trend (mpc.prediction_trend: the rate there as the solve took it,
 * cueing_vehicle_rate smoothed by mpc.trend_smoothing, fading with that time constant: it adds at
 * most the rate times it), and returning to rest (mpc.prediction_decay). */
double cueing_vehicle_ahead(FmuInstance *fmu, int k, double t_now, double t) {
    const ModelVariables *v = &fmu->s.v;
    const double seen = fmin(t, seen_until(fmu, k, t_now));
    const double last = motion(fmu, k, seen, NULL);
    if (t <= seen) return last;
    const double ahead = t - seen, trend = v->mpc_prediction_trend, decay = v->mpc_prediction_decay;
    double predicted = last;
    if (trend > 0.0) predicted += fmu->s.internal.mpc.trend_rate[k] * trend * (1.0 - exp(-ahead / trend));
    if (!(decay > 0.0)) return predicted;
    const double rest = k == 2 ? v->gravity : 0.0; /* standing: gravity's specific force alone */
    return rest + (predicted - rest) * exp(-ahead / decay);
}

static MpcData *mpc_of(const FmuInstance *fmu) {
    const ModelData *data = (const ModelData *)fmu->model_data;
    return data && fmu->s.v.algorithm == 2 ? data->mpc : NULL;
}

static CueingGuard *guard_of(const FmuInstance *fmu) {
    const ModelData *data = (const ModelData *)fmu->model_data;
    return data && fmu->s.v.guard ? data->guard : NULL;
}

static double clip(double value, double limit) { return value > limit ? limit : value < -limit ? -limit : value; }

/* Channel c's filter from the parameters. */
static Filter filter(FmuInstance *fmu, int c) {
    Filter f = {0, FIRST[c], {0.0}, {0.0}};
    if (c < N_TRANSLATION) { /* states z, p, v */
        const int *k = TRANSLATION[c];
        const double w = *fmu_real(fmu, k[2]), zeta = *fmu_real(fmu, k[3]), wb = *fmu_real(fmu, k[4]);
        f.n = 3;
        f.a[0] = -wb;                                          /* z' = -w_b z + u */
        f.a[5] = 1.0;                                          /* p' = v */
        f.a[6] = -wb, f.a[7] = -w * w, f.a[8] = -2.0 * zeta * w; /* v' = u - w_b z - w^2 p - 2 zeta w v */
        f.b[0] = wb > 0.0 ? 1.0 : 0.0, f.b[2] = 1.0;
    } else if (c < N_TRANSLATION + N_ROTATION) { /* states q, b */
        const int *k = ROTATION[c - N_TRANSLATION];
        const double w = *fmu_real(fmu, k[2]), zeta = *fmu_real(fmu, k[3]);
        f.n = 2;
        f.a[1] = 1.0, f.a[2] = -w * w, f.a[3] = -2.0 * zeta * w;
        f.b[1] = 1.0;
    } else { /* states l, l' */
        const double w = fmu->s.v.tilt_frequency, zeta = fmu->s.v.tilt_damping;
        f.n = 2;
        f.a[1] = 1.0, f.a[2] = -w * w, f.a[3] = -2.0 * zeta * w;
        f.b[1] = w * w;
    }
    return f;
}

/* Channel c's input at t: scaled and clipped as the channel takes it. */
static double channel_input(FmuInstance *fmu, int c, double t) {
    const ModelVariables *v = &fmu->s.v;
    if (c < N_TRANSLATION) {
        const int *k = TRANSLATION[c];
        const double f = motion(fmu, c, t, NULL) - (c == 2 ? v->gravity : 0.0);
        return clip(*fmu_real(fmu, k[0]) * f, *fmu_real(fmu, k[1]));
    }
    if (c < N_TRANSLATION + N_ROTATION) {
        const int *k = ROTATION[c - N_TRANSLATION];
        return clip(*fmu_real(fmu, k[0]) * motion(fmu, 3 + c - N_TRANSLATION, t, NULL), *fmu_real(fmu, k[1]));
    }
    return v->tilt_gain * motion(fmu, c - N_TRANSLATION - N_ROTATION, t, NULL);
}

/* Its rate at t (0 where the clip holds it). */
static double channel_input_rate(FmuInstance *fmu, int c, double t) {
    const double u = channel_input(fmu, c, t);
    double rate;
    if (c < N_TRANSLATION) {
        const int *k = TRANSLATION[c];
        motion(fmu, c, t, &rate);
        return fabs(u) < *fmu_real(fmu, k[1]) ? *fmu_real(fmu, k[0]) * rate : 0.0;
    }
    if (c < N_TRANSLATION + N_ROTATION) {
        const int *k = ROTATION[c - N_TRANSLATION];
        motion(fmu, 3 + c - N_TRANSLATION, t, &rate);
        return fabs(u) < *fmu_real(fmu, k[1]) ? *fmu_real(fmu, k[0]) * rate : 0.0;
    }
    motion(fmu, c - N_TRANSLATION - N_ROTATION, t, &rate);
    return fmu->s.v.tilt_gain * rate;
}

/* ---- the phi-functions per step size (derived data, outside the FMU state) ---- */

enum { KEPT = 4 };
struct PhiCache {
    double h[KEPT];
    double phi[KEPT][N_CHANNELS][3 * MAX_ORDER * MAX_ORDER]; /* phi_0, phi_1, phi_2 of each channel */
    int next;
};

static void free_data(FmuInstance *fmu, void *data) {
    ModelData *d = (ModelData *)data;
    fmu_free(fmu, d->cache);
    fmu_table_free(fmu, d->vehicle);
    mpc_free(fmu, d->mpc);
    cueing_guard_free(fmu, d->guard);
    fmu_free(fmu, d);
}

static const double *phi_of(FmuInstance *fmu, double h, int c) {
    PhiCache *cache = ((ModelData *)fmu->model_data)->cache;
    for (int e = 0; e < KEPT; e++)
        if (cache->h[e] == h) return cache->phi[e][c];
    const int e = cache->next;
    cache->next = (e + 1) % KEPT;
    cache->h[e] = h;
    for (int k = 0; k < N_CHANNELS; k++) {
        const Filter f = filter(fmu, k);
        double phi[3 * MAX_ORDER * MAX_ORDER];
        ode_phi_functions(f.n, f.a, h, 2, phi);
        memcpy(cache->phi[e][k], phi, sizeof phi);
    }
    return cache->phi[e][c];
}

/* ---- the tilt: its target from the low-passed force, and the rate limit ---- */

/* Target angle and its first three derivatives of tilt axis j (0: pitch from x, 1: roll from y). */
static void tilt_target(FmuInstance *fmu, int j, double t, double out[4]) {
    const ModelVariables *v = &fmu->s.v;
    const double *x = fmu->s.x + FIRST[N_TRANSLATION + N_ROTATION + j];
    const double w = v->tilt_frequency, zeta = v->tilt_damping, g = v->gravity;
    const double u = channel_input(fmu, N_TRANSLATION + N_ROTATION + j, t);
    const double top = sin(v->tilt_limit), sign = j == 0 ? -1.0 : 1.0;
    const double s = x[0] / g, ds = x[1] / g, dds = (w * w * (u - x[0]) - 2.0 * zeta * w * x[1]) / g;
    if (fabs(s) >= top) {
        out[0] = sign * copysign(v->tilt_limit, s), out[1] = out[2] = out[3] = 0.0;
        return;
    }
    const double du = channel_input_rate(fmu, N_TRANSLATION + N_ROTATION + j, t);
    const double ddds = (w * w * (du - x[1]) - 2.0 * zeta * w * dds * g) / g; /* l''' = w^2 (u' - l') - 2 zeta w l'' */
    const double c2 = 1.0 - s * s, c = sqrt(c2);
    out[0] = sign * asin(s);
    out[1] = sign * ds / c;
    out[2] = sign * (dds * c2 + s * ds * ds) / (c2 * c);
    /* d/dt of s'/c + s s'^2/c^3, with (1/c)' = s s'/c^3 and (1/c^3)' = 3 s s'/c^5 */
    out[3] = sign * (ddds / c + (3.0 * s * ds * dds + ds * ds * ds) / (c2 * c) + 3.0 * s * s * ds * ds * ds / (c2 * c2 * c));
}

/* Pitch's rate in roll's measure: the factor that turns the ellipse of tilt.rate_limit (roll) and
 * tilt.pitch_rate_limit into the circle of tilt.rate_limit (1 exactly when pitch has no limit of
 * its own: the tilt vector's circle, bit for bit). */
double cueing_pitch_rate_scale(const FmuInstance *fmu) {
    const ModelVariables *v = &fmu->s.v;
    return v->tilt_pitch_rate_limit > 0.0 ? v->tilt_rate_limit / v->tilt_pitch_rate_limit : 1.0;
}

/* The tilt at t after the target has moved: towards it at no more than the rate limit over h (h
 * = 0: on it, at the start). The limit is on the tilt vector's rate (roll and pitch together: the
 * rate the semicircular canals feel), not per axis: a diagonal tilt turns no faster than one
 * about a single axis. Pitch counts in roll's measure (its rate scaled), so that with a pitch limit
 * of its own the vector stays within their ellipse. */
static void tilt_follow(FmuInstance *fmu, double t, double h) {
    const double limit = fmu->s.v.tilt_rate_limit;
    const double measure[N_TILT] = {cueing_pitch_rate_scale(fmu), 1.0}; /* j: 0 pitch, 1 roll */
    double target[N_TILT][4], gap[N_TILT], *tilt[N_TILT], *angle[N_TILT];
    for (int j = 0; j < N_TILT; j++) {
        tilt_target(fmu, j, t, target[j]);
        tilt[j] = fmu->s.internal.tilt[1 - j]; /* internal.tilt[0] roll, [1] pitch */
        angle[j] = fmu->s.x + CUEING_TILT_STATE + 1 - j;
        gap[j] = target[j][0] - *angle[j];
    }
    const double along[N_TILT] = {measure[0] * gap[0], measure[1] * gap[1]};
    const double distance = sqrt(along[0] * along[0] + along[1] * along[1]); /* (not hypot: glibc 2.35 versions it anew) */
    if (h == 0.0 || distance <= limit * h) { /* on its target, turning at most at the limit */
        const double rate[N_TILT] = {measure[0] * target[0][1], measure[1] * target[1][1]};
        const double speed = sqrt(rate[0] * rate[0] + rate[1] * rate[1]);
        const int within = speed < limit;
        for (int j = 0; j < N_TILT; j++) {
            *angle[j] = target[j][0];
            tilt[j][1] = within ? target[j][1] : target[j][1] * (limit / speed);
            tilt[j][2] = within ? target[j][2] : 0.0;
            tilt[j][3] = within ? target[j][3] : 0.0;
        }
    } else { /* towards it along the gap, at the limit */
        for (int j = 0; j < N_TILT; j++) {
            *angle[j] += limit * h * gap[j] / distance;
            tilt[j][1] = limit * gap[j] / distance;
            tilt[j][2] = tilt[j][3] = 0.0;
        }
    }
}

/* Model Exchange's tilt (its angles states of the importer's solver): the rate limit in continuous
 * time. Co-Simulation's tilt snaps onto its target once within a step's reach; this one closes
 * the gap within TILT_CATCH_UP: its rate is the target's plus gap / TILT_CATCH_UP, the tilt
 * vector's rate (pitch in roll's measure) at most tilt.rate_limit. The rates (roll, pitch) into rate where given, and into
 * internal.tilt[.][1] (the higher derivatives 0). */
static const double TILT_CATCH_UP = 1e-4;

static void tilt_rate(FmuInstance *fmu, double *rate) {
    const double limit = fmu->s.v.tilt_rate_limit;
    const double measure[N_TILT] = {1.0, cueing_pitch_rate_scale(fmu)}; /* k: 0 roll, 1 pitch (in roll's measure) */
    double *tilt[N_TILT] = {fmu->s.internal.tilt[0], fmu->s.internal.tilt[1]}, speed = 0.0;
    for (int j = 0; j < N_TILT; j++) { /* target j: 0 pitch from x, 1 roll from y */
        double target[4];
        tilt_target(fmu, j, fmu->s.time, target);
        const int k = 1 - j;
        tilt[k][1] = target[1] + (target[0] - fmu->s.x[CUEING_TILT_STATE + k]) / TILT_CATCH_UP;
        tilt[k][2] = tilt[k][3] = 0.0;
        speed += measure[k] * tilt[k][1] * measure[k] * tilt[k][1];
    }
    speed = sqrt(speed);
    for (int k = 0; k < N_TILT; k++) {
        if (speed > limit) tilt[k][1] *= limit / speed;
        if (rate) rate[k] = tilt[k][1];
    }
}

/* ---- hooks ---- */

fmi2Status model_validate(FmuInstance *fmu) { /* the bounds, "> 0" among them, are the table's */
    const ModelVariables *v = &fmu->s.v;
    ModelData *data = (ModelData *)fmu->model_data;
    if (!data) {
        data = (ModelData *)fmu_calloc(fmu, 1, sizeof(ModelData));
        if (data) data->cache = (PhiCache *)fmu_calloc(fmu, 1, sizeof(PhiCache));
        if (!data || !data->cache) {
            if (data) fmu_free(fmu, data);
            fmu_log(fmu, fmi2Error, "logStatusError", "cueing: out of memory");
            return fmi2Error;
        }
        fmu_set_model_data(fmu, data, free_data);
    }
    for (int e = 0; e < KEPT; e++) data->cache->h[e] = 0.0; /* the parameters may have changed */
    const double measure = cueing_pitch_rate_scale(fmu); /* the MPC's rows and the tilt's ellipse scale by it */
    if (!(measure >= 1e-3 && measure <= 1e3)) {
        fmu_log(fmu, fmi2Error, "logStatusError", "tilt.pitch_rate_limit = %g rad/s: more than a thousand times "
                "tilt.rate_limit (%g rad/s) or less than a thousandth of it (0: pitch takes tilt.rate_limit's)",
                v->tilt_pitch_rate_limit, v->tilt_rate_limit);
        return fmi2Error;
    }
    const char *path = v->vehicle_file.text;
    if (!path[0]) {
        fmu_table_free(fmu, data->vehicle);
        data->vehicle = NULL;
    } else if (!data->vehicle || strcmp(data->vehicle->path, path) != 0) {
        fmu_table_free(fmu, data->vehicle);
        data->vehicle = fmu_table_read(fmu, VR_vehicle_file, path, MOTION_NAMES, 6);
        if (!data->vehicle) return fmi2Error;
        if (!motion_within_bounds(fmu, data->vehicle)) {
            fmu_table_free(fmu, data->vehicle);
            data->vehicle = NULL;
            return fmi2Error;
        }
    }
    mpc_free(fmu, data->mpc); /* the parameters may have changed */
    data->mpc = NULL;
    if (v->algorithm == 2 && !(data->mpc = mpc_create(fmu))) return fmi2Error;
    cueing_guard_free(fmu, data->guard);
    data->guard = NULL;
    if (v->guard && !(data->guard = cueing_guard_create(fmu))) return fmi2Error;
    return cueing_guard_state_valid(fmu) ? fmi2OK : fmi2Error;
}

/* Each filter settled for the inputs at the start (a vehicle at rest, or in steady motion, starts
 * with its cue settled: no translational or rotational cue, the tilt on its target). */
void model_initialize(FmuInstance *fmu) {
    cueing_guard_initialize(fmu);
    if (mpc_of(fmu)) {
        mpc_initialize(fmu, mpc_of(fmu));
        return;
    }
    double *x = fmu->s.x;
    memset(x, 0, sizeof fmu->s.x);
    for (int c = 0; c < N_CHANNELS; c++) {
        const Filter f = filter(fmu, c);
        const double u = channel_input(fmu, c, fmu->s.time);
        double *s = x + f.first;
        if (c < N_TRANSLATION) { /* z = u / w_b (third order), p = (u - w_b z) / w^2 */
            s[0] = f.a[0] < 0.0 ? u / -f.a[0] : 0.0;
            s[1] = (u + f.a[6] * s[0]) / -f.a[7];
        } else if (c < N_TRANSLATION + N_ROTATION) { /* q = u / w^2, b = 0 */
            s[0] = u / -f.a[2];
        } else { /* l = u */
            s[0] = u;
        }
    }
    tilt_follow(fmu, fmu->s.time, 0.0);
}

/* The washout's filters over a step of h, exactly, and the tilt after them. */
static fmi2Status washout_step(FmuInstance *fmu, double h) {
    const double t = fmu->s.time;
    for (int c = 0; c < N_CHANNELS; c++) {
        const Filter f = filter(fmu, c);
        const double *phi = phi_of(fmu, h, c);
        const int n = f.n, nn = n * n;
        if (!isfinite(phi[0])) {
            fmu_log(fmu, fmi2Error, "logStatusError", "fmi2DoStep: a step of %g s is beyond what the filters' "
                    "frequencies allow to be taken exactly (e^(hA) overflows)", h);
            return fmi2Error;
        }
        const double u0 = channel_input(fmu, c, t), u1 = (channel_input(fmu, c, t + h) - u0) / h; /* the chord */
        double *x = fmu->s.x + f.first, next[MAX_ORDER];
        for (int i = 0; i < n; i++) {
            next[i] = 0.0;
            for (int j = 0; j < n; j++)
                next[i] += phi[i * n + j] * x[j] + (h * phi[nn + i * n + j] * u0 + h * h * phi[2 * nn + i * n + j] * u1) * f.b[j];
        }
        memcpy(x, next, (size_t)n * sizeof(double));
    }
    tilt_follow(fmu, t + h, h);
    return fmi2OK;
}

fmi2Status model_do_step(FmuInstance *fmu, double h) {
    const fmi2Status status = mpc_of(fmu) ? mpc_do_step(fmu, mpc_of(fmu), h) : washout_step(fmu, h);
    if (status == fmi2OK) { /* the guard takes the motion at the step's end (model_compute_outputs) */
        fmu->s.internal.guard.pending = 1;
        fmu->s.internal.guard.step = h;
    }
    return status;
}

/* d/dt of the filter's state x' = A x + B u for an input moving at du (first-order hold: u'' = 0). */
static void state_rate(const Filter *f, const double *x, double u, double out[MAX_ORDER]) {
    for (int i = 0; i < f->n; i++) {
        out[i] = f->b[i] * u;
        for (int j = 0; j < f->n; j++) out[i] += f->a[i * f->n + j] * x[j];
    }
}

/* The classical washout's pose (from neutral) with its first three derivatives. */
static void classical_pose(FmuInstance *fmu, double pose[6][4]) {
    const double t = fmu->s.time, *x = fmu->s.x;
    for (int c = 0; c < N_TRANSLATION + N_ROTATION; c++) { /* each channel's output, its second state, */
        const Filter f = filter(fmu, c);                     /* and that state's first three derivatives */
        const double *s = x + f.first, u = channel_input(fmu, c, t), du = channel_input_rate(fmu, c, t);
        double rate[MAX_ORDER], curvature[MAX_ORDER], jerk[MAX_ORDER];
        state_rate(&f, s, u, rate);
        state_rate(&f, rate, du, curvature);
        state_rate(&f, curvature, 0.0, jerk);
        pose[c][0] = s[1], pose[c][1] = rate[1], pose[c][2] = curvature[1], pose[c][3] = jerk[1];
    }
    for (int k = 0; k < N_TILT; k++) fmu->s.internal.tilt[k][0] = fmu->s.x[CUEING_TILT_STATE + k];
    for (int k = 0; k < 4; k++) { /* tilt onto roll (3) and pitch (4) */
        pose[3][k] += fmu->s.internal.tilt[0][k];
        pose[4][k] += fmu->s.internal.tilt[1][k];
    }
}

void model_compute_outputs(FmuInstance *fmu) {
    const double t = fmu->s.time;
    double (*pose)[4] = fmu->s.internal.pose;
    if (mpc_of(fmu)) { /* the MPC does not split its roll and pitch: the tilt is all of them */
        mpc_pose(fmu, pose);
        for (int k = 0; k < 4; k++) fmu->s.internal.tilt[0][k] = pose[3][k], fmu->s.internal.tilt[1][k] = pose[4][k];
        double perceived[6];
        mpc_perceived_error(fmu, mpc_of(fmu), perceived);
        for (int c = 0; c < 6; c++) *fmu_real(fmu, VR_mpc_perceived_error_specific_force_x + c) = perceived[c];
        fmu->s.v.mpc_iterations = fmu->s.internal.mpc.iterations;
        fmu->s.v.mpc_softened = fmu->s.internal.mpc.softened;
    } else {
        if (fmu->model_exchange) tilt_rate(fmu, NULL);
        classical_pose(fmu, pose);
    }
    double reference[3][6]; /* the pose reference's value, rate and acceleration: the cueing's, or the guard's */
    for (int d = 0; d < 6; d++)
        reference[0][d] = *fmu_real(fmu, NEUTRAL[d]) + pose[d][0], reference[1][d] = pose[d][1],
        reference[2][d] = pose[d][2];
    cueing_guard_hand_on(fmu, guard_of(fmu), reference);
    for (int d = 0; d < 6; d++) {
        *fmu_real(fmu, POSE[d]) = reference[0][d];
        *fmu_real(fmu, POSE_RATE[d]) = reference[1][d];
    }
    for (int k = 0; k < 6; k++) *fmu_real(fmu, VEHICLE[k]) = motion(fmu, k, t, NULL);
    fmu->s.v.tilt_roll = fmu->s.internal.tilt[0][0];
    fmu->s.v.tilt_pitch = fmu->s.internal.tilt[1][0];
    const ModelData *data = (const ModelData *)fmu->model_data;
    fmu->s.v.vehicle_rows = data && data->vehicle ? data->vehicle->rows : 0;
}

double model_output_derivative(FmuInstance *fmu, int vr, int order) {
    for (int d = 0; d < 6; d++) {
        double guarded;
        if (POSE[d] == vr)
            return cueing_guard_derivative(fmu, d, 0, order, &guarded) ? guarded : fmu->s.internal.pose[d][order];
        if (POSE_RATE[d] == vr)
            return cueing_guard_derivative(fmu, d, 1, order, &guarded) ? guarded : fmu->s.internal.pose[d][order + 1];
    }
    if (vr == VR_tilt_roll) return fmu->s.internal.tilt[0][order];
    if (vr == VR_tilt_pitch) return fmu->s.internal.tilt[1][order];
    return 0.0;
}

/* ---- Model Exchange (fmi2_me.c): the filters' own equations; the MPC's solves and the guard's steps time events ---- */

const char *model_exchange_refusal(const FmuInstance *fmu) {
    (void)fmu; /* every algorithm and the guard run as Model Exchange */
    return NULL;
}

int model_derivatives(FmuInstance *fmu, double *dxdt) {
    memset(dxdt, 0, MODEL_N_STATES * sizeof *dxdt);
    if (mpc_of(fmu)) {
        mpc_derivatives(fmu, mpc_of(fmu), dxdt);
        return 0;
    }
    for (int c = 0; c < N_CHANNELS; c++) { /* x' = A x + B u */
        const Filter f = filter(fmu, c);
        double rate[MAX_ORDER];
        state_rate(&f, fmu->s.x + f.first, channel_input(fmu, c, fmu->s.time), rate);
        memcpy(dxdt + f.first, rate, (size_t)f.n * sizeof *rate);
    }
    tilt_rate(fmu, dxdt + CUEING_TILT_STATE);
    return 0;
}

void model_state_nominals(const FmuInstance *fmu, double *nominals) {
    for (int k = 0; k < MODEL_N_STATES; k++) nominals[k] = 1.0; /* the washout's filters and tilt */
    if (mpc_of(fmu)) mpc_state_nominals(mpc_of(fmu), nominals);
}

fmi2Status model_completed_integrator_step(FmuInstance *fmu) {
    (void)fmu;
    return fmi2OK;
}

/* A new plan of the MPC, a corner of the vehicle table's interpolation, or a step of the guard that
 * does not pass the cueing's motion on as before (it holds it, or hands it back). */
int model_time_event(FmuInstance *fmu) {
    const ModelData *data = (const ModelData *)fmu->model_data;
    const double t = fmu->s.time, near = 1e-12 * fmax(1.0, fabs(t));
    int changed = mpc_of(fmu) ? mpc_time_event(fmu, mpc_of(fmu)) : 0;
    if (data && data->vehicle && fabs(fmu_table_next_row(data->vehicle, t - near) - t) <= near) changed = 1;
    const int passed_on = fmu->s.internal.guard.active == 3;
    if (cueing_guard_time_event(fmu, guard_of(fmu))) { /* the guard takes the motion now */
        model_compute_outputs(fmu);
        if (!(passed_on && fmu->s.internal.guard.active == 3)) changed = 1;
    }
    return changed;
}

/* The MPC's next solve, a period after the last, the guard's next step, or the vehicle table's next
 * row (a corner of its linear interpolation, which a Model Exchange solver would otherwise step
 * over), whichever comes first; at a time too large for the period to show in it (a start near the largest double), the
 * next time there is: an event time is always after now. */
double model_next_time_event(FmuInstance *fmu) {
    const ModelData *data = (const ModelData *)fmu->model_data;
    double next = fmin(mpc_of(fmu) ? mpc_next_solve(fmu) : INFINITY, cueing_guard_next_step(fmu, guard_of(fmu)));
    if (data && data->vehicle) next = fmin(next, fmu_table_next_row(data->vehicle, fmu->s.time));
    return isfinite(next) ? fmax(next, nextafter(fmu->s.time, INFINITY)) : INFINITY;
}
