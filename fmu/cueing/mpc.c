/* cueing, algorithm 2: model-predictive cueing (after Dagdelen et al. 2009 and Bruschetta et al.
 * 2017): every mpc.period, the platform's accelerations over a horizon that make what the occupant
 * perceives closest to what the vehicle's occupant perceives, within the platform's envelope.
 *
 * The platform's motion per DOF d (x, y, z, roll, pitch, yaw from neutral): q_d'' = a_d, a_d held
 * over each of the horizon's N intervals (the decisions: 6 N accelerations). What it is felt as,
 * linearised about neutral (small angles, as the classical washout's tilt): the specific force
 *     s_x = a_x - g pitch,  s_y = a_y + g roll,  s_z = a_z,
 * and the angular rate (roll', pitch', yaw'). The vehicle's r (its specific force less g along z,
 * its angular rate) is read ahead of now as far as mpc.preview (a recording, vehicle.file), beyond
 * predicted from there (cueing_vehicle_ahead: held, along its trend, returning to rest; the trend's
 * rate taken once per solve, smoothed over solves by mpc.trend_smoothing: update_trend). The
 * error e = s - r goes through the vestibular models (perception.py gives the same constants):
 *     otoliths (Young and Meiry 1968):     K (1 + tau_a s) / ((1 + tau_L s)(1 + tau_S s)),
 *     semicircular canals (Telban and Cardullo 2005, after Zacharias 1978):
 *         tau_a s / (1 + tau_a s) * tau_1 s (1 + tau_L s) / ((1 + tau_1 s)(1 + tau_2 s)),
 * each as x' = A x + B e, y = C x + D e (controllable canonical form). Over an interval of h the
 * error is a polynomial in time (a_d constant: s_x is quadratic through the pitch), so the step is
 * exact with the phi-functions of the shared solvers (ode.h):
 *     x(h) = phi_0 x + h phi_1 B e_0 + h^2 phi_2 B e_1 + h^3 phi_3 B e_2,  e(t) = e_0 + e_1 t + e_2 t^2/2.
 * The prediction is linear in the decisions z: X_k = X_k^free + S_k z, with S_k (the response to
 * each decision alone) built once by the same step. The cost, each term weighted by its interval:
 *     sum_k h_k (|y_k|^2_Wy + |q_k|^2_Wq + |q'_k|^2_Wv + |a_k|^2_Wa),
 * a QP in z: H = sum S' W S (constant), f from the free response. Solved in u = R z (H = R' R, its
 * Cholesky factor, once): the cost 1/2 |u|^2 + (R^-T f)' u, every constraint's row a S R^-1, whose
 * S R^-1 is formed once, so that a solve forms the constraints as cheaply as in z and the solver
 * has no product with R^-1 to form (the acceleration bounds become the rows of R^-1). Constraints at
 * every interval's end, linearised about the pose now (re-linearised every solve; the leg Jacobian
 * J = dL/dq by central differences of the mechanics' inverse kinematics, platform.c):
 *     legs within the stroke less the margin:  L(q_0) + J (q_k - q_0) in [L_min + m, L_max - m],
 *     leg speeds:                              |J q'_k| <= limit.leg_velocity,
 *     each joint's tilt from the leg's neutral direction n_0 within limit.joint_angle: the leg's
 *     direction across n_0 (2 components, in the base frame at the lower joint, in the platform's
 *     at the upper; sin of the tilt is its length) linearised alike, within an octagon inscribed in
 *     the circle of sin(limit.joint_angle),
 *     the platform's roll and pitch rate (the vector; pitch in roll's measure when
 *     tilt.pitch_rate_limit gives it an ellipse) within tilt.rate_limit plus the vehicle's own
 *     roll and pitch rate there: the tilt that stands for sustained force turns below what the
 *     canals notice, a rotational cue as fast as the vehicle's own (an octagon inscribed in that
 *     circle: 4 pairs of facets),
 * and |a_k| within mpc.acceleration_limit / mpc.angular_acceleration_limit. The general
 * constraints are soft (a solve always has an answer; mpc.softened counts the solves whose answer
 * broke a limit by more than 1e-3 of its units). Solved by DAQP (Arnstrom, Bemporad and Axehill 2022, a dual
 * active-set solver for small dense QPs), warm-started from the previous solve's working set (kept
 * outside the FMU state: a restored state solves the same QP, to the solver's tolerance).
 */
#include "mpc.h"

#include "api.h"
#include "platform.h"
#include "utils.h" /* daqp_update_ldp */

#include <math.h>
#include <stddef.h> /* offsetof */
#include <string.h>

enum {
    N = 12,              /* intervals in the horizon */
    DOF = 6,
    Z = N * DOF,         /* decisions */
    XI = 15,             /* perception states */
    JOINTS = 2 * PLATFORM_LEGS, /* a leg's lower and upper joint */
    ROWS = 16 + 4 * JOINTS, /* constraint rows per interval: 6 stroke, 6 leg speed, 4 tilt-rate facets, 4 per joint */
    M = N * ROWS,        /* general constraints */
    STEP_SLOT = N        /* the phi-functions' slot of the communication step */
};

/* ---- the vestibular models (their published constants, as cosim/platform/perception.py) ---- */

static const double OTOLITH_K = 0.4, OTOLITH_TAU_A = 13.2, OTOLITH_TAU_L = 5.33, OTOLITH_TAU_S = 0.66;
static const double CANAL_TAU_A = 80.0, CANAL_TAU_1 = 5.73, CANAL_TAU_2 = 0.005, CANAL_TAU_L = 0.06;
static const double PI = 3.14159265358979323846;
static const int XI_FIRST[DOF] = {0, 2, 4, 6, 9, 12}; /* otoliths x, y, z; canals roll, pitch, yaw */

typedef struct {
    int n;
    double a[9], c[3], d; /* x' = A x + e_n e, y = C x + D e */
} Organ;

/* Controllable canonical form of (b_2 s^2 + b_1 s + b_0 + D (s^3 ...)) over a monic denominator. */
static Organ otolith(void) {
    const double tl = OTOLITH_TAU_L, ts = OTOLITH_TAU_S, ka = OTOLITH_K;
    Organ o = {2, {0.0, 1.0, -1.0 / (tl * ts), -(tl + ts) / (tl * ts)}, {ka / (tl * ts), ka * OTOLITH_TAU_A / (tl * ts)}, 0.0};
    return o;
}

static Organ canal(void) {
    const double ta = CANAL_TAU_A, t1 = CANAL_TAU_1, t2 = CANAL_TAU_2, tl = CANAL_TAU_L, c3 = ta * t1 * t2;
    const double d0 = 1.0 / c3, d1 = (ta + t1 + t2) / c3, d2 = (ta * t1 + ta * t2 + t1 * t2) / c3;
    const double n3 = tl / t2, n2 = 1.0 / t2; /* numerator tau_a tau_1 (tau_L s^3 + s^2) / c3 */
    Organ o = {3, {0.0, 1.0, 0.0, 0.0, 0.0, 1.0, -d0, -d1, -d2}, {-n3 * d0, -n3 * d1, n2 - n3 * d2}, n3};
    return o;
}

/* ---- the data: prediction, QP, solver ---- */

/* The motion the MPC commands and its perception: the model's continuous state, fmu->s.x, as it
 * lies there (variables.h). */
typedef struct {
    double q[DOF], v[DOF], xi[XI];
} Motion;
typedef char motion_is_the_state[sizeof(Motion) == MODEL_N_STATES * sizeof(double) ? 1 : -1];

struct MpcData {
    Platform platform;
    double lateral[PLATFORM_LEGS][2][3];          /* per leg, two unit vectors across its neutral axis */
    Organ organ[2];                               /* otolith, canal */
    double h[N], start[N + 1];                    /* the intervals and where each starts */
    double step;                                  /* the communication step the slot STEP_SLOT is for */
    double phi[N + 1][2][4 * 9];                  /* phi_0..3 per interval and organ */
    double weight_y[DOF], weight_q[DOF], weight_v[DOF], weight_a[DOF];
    double sq[N][DOF][Z], sv[N][DOF][Z], sy[N][DOF][Z]; /* the prediction's response to each decision */
    double H[Z * Z], f[Z], A[(Z + M) * Z], upper[Z + M], lower[Z + M];
    double rinv[Z * Z];                           /* R^-1 (upper triangular): z = R^-1 u */
    int sense[Z + M];
    DAQPProblem qp;
    DAQPSettings settings;
    DAQPWorkspace work;
    int ready; /* the workspace set up (at the first solve) */
};

/* The interval's step of the motion x under accelerations a, with the vehicle's r0 + r1 t; the
 * perceived error at its end into y. */
static void advance(const MpcData *m, int slot, double h, double g, Motion *x, const double a[DOF],
                    const double r0[DOF], const double r1[DOF], double y[DOF]) {
    double e[DOF][3]; /* the error e_0 + e_1 t + e_2 t^2 / 2 per channel */
    e[0][0] = a[0] - g * x->q[4] - r0[0], e[0][1] = -g * x->v[4] - r1[0], e[0][2] = -g * a[4];
    e[1][0] = a[1] + g * x->q[3] - r0[1], e[1][1] = g * x->v[3] - r1[1], e[1][2] = g * a[3];
    e[2][0] = a[2] - r0[2], e[2][1] = -r1[2], e[2][2] = 0.0;
    for (int c = 3; c < DOF; c++) e[c][0] = x->v[c] - r0[c], e[c][1] = a[c] - r1[c], e[c][2] = 0.0;
    for (int c = 0; c < DOF; c++) {
        const Organ *o = &m->organ[c < 3 ? 0 : 1];
        const double *phi = m->phi[slot][c < 3 ? 0 : 1];
        const int n = o->n, nn = n * n, last = n - 1;
        double *xi = x->xi + XI_FIRST[c], next[3];
        for (int i = 0; i < n; i++) {
            next[i] = h * phi[nn + i * n + last] * e[c][0] + h * h * phi[2 * nn + i * n + last] * e[c][1] +
                      h * h * h * phi[3 * nn + i * n + last] * e[c][2];
            for (int j = 0; j < n; j++) next[i] += phi[i * n + j] * xi[j];
        }
        y[c] = o->d * (e[c][0] + e[c][1] * h + 0.5 * e[c][2] * h * h);
        for (int i = 0; i < n; i++) xi[i] = next[i], y[c] += o->c[i] * next[i];
    }
    for (int d = 0; d < DOF; d++) {
        x->q[d] += h * x->v[d] + 0.5 * h * h * a[d];
        x->v[d] += h * a[d];
    }
}

static void phi_slot(MpcData *m, int slot, double h) {
    for (int k = 0; k < 2; k++) ode_phi_functions(m->organ[k].n, m->organ[k].a, h, 3, m->phi[slot][k]);
}

/* S_k: the prediction's response to each decision alone (everything else zero). */
static void responses(MpcData *m, double g) {
    static const double zero[DOF] = {0};
    for (int j = 0; j < Z; j++) {
        Motion x;
        memset(&x, 0, sizeof x);
        for (int k = 0; k < N; k++) {
            double a[DOF] = {0}, y[DOF];
            if (k == j / DOF) a[j % DOF] = 1.0;
            advance(m, k, m->h[k], g, &x, a, zero, zero, y);
            for (int d = 0; d < DOF; d++) m->sq[k][d][j] = x.q[d], m->sv[k][d][j] = x.v[d], m->sy[k][d][j] = y[d];
        }
    }
}

/* H = sum_k h_k (Sy' Wy Sy + Sq' Wq Sq + Sv' Wv Sv) + the accelerations' own weights. */
static void hessian(MpcData *m) {
    memset(m->H, 0, sizeof m->H);
    for (int k = 0; k < N; k++)
        for (int d = 0; d < DOF; d++) {
            const double wy = m->h[k] * m->weight_y[d], wq = m->h[k] * m->weight_q[d], wv = m->h[k] * m->weight_v[d];
            for (int i = 0; i < Z; i++)
                for (int j = 0; j < Z; j++)
                    m->H[i * Z + j] += wy * m->sy[k][d][i] * m->sy[k][d][j] + wq * m->sq[k][d][i] * m->sq[k][d][j] +
                                       wv * m->sv[k][d][i] * m->sv[k][d][j];
        }
    for (int j = 0; j < Z; j++) m->H[j * Z + j] += m->h[j / DOF] * m->weight_a[j % DOF];
}

/* H = R' R (R upper triangular, Cholesky; a small multiple of the identity added where the weights
 * leave H only semi-definite), R^-1 into rinv; then each response S becomes S R^-1, the acceleration
 * bounds' rows R^-1's and H the identity: the QP in u = R z. 0, or -1 if H has no such factor (a
 * weight so large that H is not finite, or all of them 0). R is formed in those rows of A, which
 * become R^-1's once it is no longer needed. */
static int change_to_unit_hessian(MpcData *m) {
    double *R = m->A, largest = 0.0;
    for (int j = 0; j < Z * Z; j++) largest = fmax(largest, fabs(m->H[j]));
    if (!(largest > 0.0) || !isfinite(largest)) return -1;
    for (double shift = 0.0;; shift = shift == 0.0 ? 1e-12 * largest : 10.0 * shift) {
        if (shift > 1e-3 * largest) return -1; /* no factor with a shift that leaves the cost as weighted */
        int positive = 1;
        memset(R, 0, Z * Z * sizeof *R);
        for (int j = 0; j < Z && positive; j++) {
            double pivot = m->H[j * Z + j] + shift;
            for (int k = 0; k < j; k++) pivot -= R[k * Z + j] * R[k * Z + j];
            if (!(pivot > 1e-14 * largest)) { positive = 0; break; }
            R[j * Z + j] = sqrt(pivot);
            for (int i = j + 1; i < Z; i++) {
                double sum = m->H[j * Z + i];
                for (int k = 0; k < j; k++) sum -= R[k * Z + j] * R[k * Z + i];
                R[j * Z + i] = sum / R[j * Z + j];
            }
        }
        if (positive) break;
    }
    memset(m->rinv, 0, sizeof m->rinv);
    for (int c = 0; c < Z; c++) { /* R X = e_c by back substitution */
        m->rinv[c * Z + c] = 1.0 / R[c * Z + c];
        for (int i = c - 1; i >= 0; i--) {
            double sum = 0.0;
            for (int k = i + 1; k <= c; k++) sum += R[i * Z + k] * m->rinv[k * Z + c];
            m->rinv[i * Z + c] = -sum / R[i * Z + i];
        }
    }
    double (*const responses[3])[DOF][Z] = {m->sq, m->sv, m->sy};
    for (int s = 0; s < 3; s++)
        for (int k = 0; k < N; k++)
            for (int d = 0; d < DOF; d++) {
                double *row = responses[s][k][d], out[Z];
                for (int j = 0; j < Z; j++) {
                    out[j] = 0.0;
                    for (int i = 0; i <= j; i++) out[j] += row[i] * m->rinv[i * Z + j];
                }
                memcpy(row, out, sizeof out);
            }
    memcpy(m->A, m->rinv, sizeof m->rinv);
    memset(m->H, 0, sizeof m->H);
    for (int j = 0; j < Z; j++) m->H[j * Z + j] = 1.0;
    return 0;
}

static double gravity_of(const FmuInstance *fmu) { return fmu->s.v.gravity; }

/* Per leg, two unit vectors across its axis at the neutral pose: a joint's tilt from there is
 * asin of the length of the leg's direction's part along them (the lower joint's in the base
 * frame, the upper's in the platform's). */
static void lateral_directions(MpcData *m) {
    const double at_rest[6] = {0, 0, 0, 0, 0, 0};
    double x[PLATFORM_STATES];
    LegGeometry legs[PLATFORM_LEGS];
    platform_state_from_pose(m->platform.neutral_pose, at_rest, x);
    platform_legs(&m->platform, x, legs);
    for (int i = 0; i < PLATFORM_LEGS; i++) {
        const double *n = legs[i].axis;
        const int k = fabs(n[0]) < 0.6 ? 0 : 1; /* the axis least along n */
        double e[3] = {0, 0, 0}, *e1 = m->lateral[i][0], *e2 = m->lateral[i][1];
        e[k] = 1.0;
        const double along = e[0] * n[0] + e[1] * n[1] + e[2] * n[2];
        double norm = 0.0;
        for (int j = 0; j < 3; j++) e1[j] = e[j] - along * n[j], norm += e1[j] * e1[j];
        for (int j = 0; j < 3; j++) e1[j] /= sqrt(norm);
        e2[0] = n[1] * e1[2] - n[2] * e1[1], e2[1] = n[2] * e1[0] - n[0] * e1[2], e2[2] = n[0] * e1[1] - n[1] * e1[0];
    }
}

int cueing_platform(FmuInstance *fmu, Platform *platform) {
    const ModelVariables *v = &fmu->s.v;
    double upper[PLATFORM_LEGS][3], lower[PLATFORM_LEGS][3], neutral[6];
    for (int i = 0; i < PLATFORM_LEGS; i++) /* the table's order per leg: base x, y, z, platform x, y, z */
        for (int k = 0; k < 3; k++) {
            lower[i][k] = *fmu_real(fmu, VR_geometry_base_joint_1_x + 6 * i + k);
            upper[i][k] = *fmu_real(fmu, VR_geometry_base_joint_1_x + 6 * i + 3 + k);
        }
    neutral[0] = v->neutral_x, neutral[1] = v->neutral_y, neutral[2] = v->neutral_z;
    neutral[3] = v->neutral_roll, neutral[4] = v->neutral_pitch, neutral[5] = v->neutral_yaw;
    if (platform_layout_from_joints(platform, (const double(*)[3])upper, (const double(*)[3])lower, neutral) != 0) {
        fmu_log(fmu, fmi2Error, "logStatusError", "geometry.*: a leg has no length at the neutral pose");
        return 0;
    }
    return 1;
}

MpcData *mpc_create(FmuInstance *fmu) {
    const ModelVariables *v = &fmu->s.v;
    if (v->mpc_horizon < N * v->mpc_period) {
        fmu_log(fmu, fmi2Error, "logStatusError", "mpc.horizon = %g s is shorter than its %d intervals of at least "
                "mpc.period = %g s", v->mpc_horizon, N, v->mpc_period);
        return NULL;
    }
    MpcData *m = (MpcData *)fmu_calloc(fmu, 1, sizeof(MpcData));
    if (!m) {
        fmu_log(fmu, fmi2Error, "logStatusError", "cueing: out of memory");
        return NULL;
    }
    if (!cueing_platform(fmu, &m->platform)) {
        fmu_free(fmu, m);
        return NULL;
    }
    m->platform.gravity[2] = -gravity_of(fmu);
    lateral_directions(m);
    double length[PLATFORM_LEGS];
    platform_leg_lengths(&m->platform, m->platform.neutral_pose, length);
    for (int i = 0; i < PLATFORM_LEGS; i++)
        if (length[i] < v->limit_leg_length_min + v->limit_stroke_margin ||
            length[i] > v->limit_leg_length_max - v->limit_stroke_margin) {
            fmu_log(fmu, fmi2Error, "logStatusError", "the neutral pose puts leg %d at %g m, outside the stroke %g-%g m "
                    "less limit.stroke_margin = %g m: the MPC has nowhere to return to", i + 1, length[i],
                    v->limit_leg_length_min, v->limit_leg_length_max, v->limit_stroke_margin);
            fmu_free(fmu, m);
            return NULL;
        }
    m->organ[0] = otolith(), m->organ[1] = canal();
    const double growth = 2.0 * (v->mpc_horizon - N * v->mpc_period) / (N * (N - 1.0)); /* h_k = period + k growth */
    for (int k = 0; k < N; k++) {
        m->h[k] = v->mpc_period + k * growth;
        m->start[k + 1] = m->start[k] + m->h[k];
        phi_slot(m, k, m->h[k]);
    }
    for (int d = 0; d < DOF; d++) {
        const int turn = d >= 3;
        m->weight_y[d] = turn ? v->mpc_weight_angular_rate : v->mpc_weight_specific_force;
        m->weight_q[d] = turn ? v->mpc_weight_angle : v->mpc_weight_position;
        m->weight_v[d] = turn ? v->mpc_weight_angular_velocity : v->mpc_weight_velocity;
        m->weight_a[d] = turn ? v->mpc_weight_angular_acceleration : v->mpc_weight_acceleration;
    }
    responses(m, gravity_of(fmu));
    hessian(m);
    if (change_to_unit_hessian(m) != 0) {
        fmu_log(fmu, fmi2Error, "logStatusError", "mpc.weight.*: the MPC's cost has no positive definite Hessian "
                "(a weight so large that it is not finite, or every weight 0)");
        fmu_free(fmu, m);
        return NULL;
    }
    for (int j = 0; j < Z; j++) {
        const double limit = j % DOF >= 3 ? v->mpc_angular_acceleration_limit : v->mpc_acceleration_limit;
        m->upper[j] = limit, m->lower[j] = -limit, m->sense[j] = 0;
    }
    for (int r = Z; r < Z + M; r++) m->sense[r] = DAQP_SOFT;
    m->qp.n = Z, m->qp.m = Z + M, m->qp.ms = 0; /* the acceleration bounds: rows of R^-1, hard */
    m->qp.H = m->H, m->qp.f = m->f, m->qp.A = m->A, m->qp.bupper = m->upper, m->qp.blower = m->lower;
    m->qp.sense = m->sense;
    daqp_default_settings(&m->settings);
    m->work.settings = &m->settings;
    return m;
}

void mpc_free(FmuInstance *fmu, MpcData *m) {
    if (!m) return;
    if (m->ready) {
        m->work.settings = NULL; /* ours */
        free_daqp_workspace(&m->work);
        free_daqp_ldp(&m->work);
    }
    fmu_free(fmu, m);
}

/* ---- a solve ---- */

/* The vehicle's r (specific force less g along z, angular rate) at t as predicted at t_now. */
static void vehicle_error_reference(FmuInstance *fmu, double t_now, double t, double r[DOF]) {
    for (int k = 0; k < DOF; k++) r[k] = cueing_vehicle_ahead(fmu, k, t_now, t);
    r[2] -= gravity_of(fmu);
}

/* The platform's envelope at pose q (from neutral): each leg's length, and per joint the leg's
 * direction across its neutral axis (2 components: lower joints, then upper, leg by leg). */
enum { ENVELOPE_VALUES = PLATFORM_LEGS + 2 * JOINTS };
static void envelope_values(const MpcData *m, const double q[DOF], double out[ENVELOPE_VALUES]) {
    const double at_rest[6] = {0, 0, 0, 0, 0, 0};
    double pose[6], x[PLATFORM_STATES], R[9];
    LegGeometry legs[PLATFORM_LEGS];
    for (int d = 0; d < DOF; d++) pose[d] = m->platform.neutral_pose[d] + q[d];
    platform_state_from_pose(pose, at_rest, x);
    platform_legs(&m->platform, x, legs);
    platform_rotation_from_euler(pose[3], pose[4], pose[5], R);
    for (int i = 0; i < PLATFORM_LEGS; i++) {
        const double *n = legs[i].axis;
        double local[3]; /* R' n: the leg's direction in the platform's frame */
        for (int k = 0; k < 3; k++) local[k] = R[k] * n[0] + R[3 + k] * n[1] + R[6 + k] * n[2];
        out[i] = legs[i].length;
        for (int c = 0; c < 2; c++) {
            const double *e = m->lateral[i][c];
            out[PLATFORM_LEGS + 2 * i + c] = n[0] * e[0] + n[1] * e[1] + n[2] * e[2];
            out[PLATFORM_LEGS + 2 * (PLATFORM_LEGS + i) + c] = local[0] * e[0] + local[1] * e[1] + local[2] * e[2];
        }
    }
}

/* The envelope's values at q and their Jacobian (ENVELOPE_VALUES x 6) by central differences. */
static void envelope_linearised(const MpcData *m, const double q[DOF], double value[ENVELOPE_VALUES],
                                double jacobian[ENVELOPE_VALUES * DOF]) {
    double at[DOF], plus[ENVELOPE_VALUES], minus[ENVELOPE_VALUES];
    memcpy(at, q, sizeof at);
    envelope_values(m, at, value);
    for (int d = 0; d < DOF; d++) {
        const double delta = 1e-6;
        at[d] = q[d] + delta;
        envelope_values(m, at, plus);
        at[d] = q[d] - delta;
        envelope_values(m, at, minus);
        at[d] = q[d];
        for (int i = 0; i < ENVELOPE_VALUES; i++) jacobian[i * DOF + d] = (plus[i] - minus[i]) / (2.0 * delta);
    }
}

/* Row r of the general constraints: coefficients row . S (S one of sq/sv at interval k), bounds
 * [low, high] less row . free. */
static void constrain(MpcData *m, int r, const double row[DOF], double (*s)[Z], const double *free_part,
                      double low, double high) {
    double *a = m->A + (size_t)(Z + r) * Z, shift = 0.0;
    for (int j = 0; j < Z; j++) {
        a[j] = 0.0;
        for (int d = 0; d < DOF; d++) a[j] += row[d] * s[d][j];
    }
    for (int d = 0; d < DOF; d++) shift += row[d] * free_part[d];
    m->upper[Z + r] = high - shift, m->lower[Z + r] = low - shift;
}

/* The QP's linear term and constraints at time t for the motion now (in u: the responses are S R^-1). */
static void form_qp(FmuInstance *fmu, MpcData *m, double t, const Motion *at) {
    const ModelVariables *v = &fmu->s.v;
    const double g = gravity_of(fmu), zero[DOF] = {0};
    const Motion now = *at;
    Motion x = now;
    double envelope[ENVELOPE_VALUES], J[ENVELOPE_VALUES * DOF];
    envelope_linearised(m, now.q, envelope, J);
    const double *length = envelope;
    const double sideways = sin(fmin(v->limit_joint_angle, PI / 2.0)) * cos(PI / 8.0); /* the joints' octagons */
    const double low = v->limit_leg_length_min + v->limit_stroke_margin;
    const double high = v->limit_leg_length_max - v->limit_stroke_margin;
    const double facet = v->tilt_rate_limit * cos(PI / 8.0); /* the octagon inscribed in the circle */
    const double measure = cueing_pitch_rate_scale(fmu); /* pitch in roll's measure: the circle of its ellipse */
    memset(m->f, 0, sizeof m->f);
    for (int k = 0; k < N; k++) {
        double r[DOF], y[DOF];
        vehicle_error_reference(fmu, t, t + 0.5 * (m->start[k] + m->start[k + 1]), r);
        advance(m, k, m->h[k], g, &x, zero, r, zero, y); /* the free response */
        for (int d = 0; d < DOF; d++) {
            const double wy = m->h[k] * m->weight_y[d] * y[d], wq = m->h[k] * m->weight_q[d] * x.q[d];
            const double wv = m->h[k] * m->weight_v[d] * x.v[d];
            for (int j = 0; j < Z; j++) m->f[j] += wy * m->sy[k][d][j] + wq * m->sq[k][d][j] + wv * m->sv[k][d][j];
        }
        double moved[DOF];
        for (int d = 0; d < DOF; d++) moved[d] = x.q[d] - now.q[d];
        for (int i = 0; i < PLATFORM_LEGS; i++) {
            const double *row = J + i * DOF;
            constrain(m, k * ROWS + i, row, m->sq[k], moved, low - length[i], high - length[i]);
            constrain(m, k * ROWS + 6 + i, row, m->sv[k], x.v, -v->limit_leg_velocity, v->limit_leg_velocity);
        }
        for (int i = 0; i < 2 * JOINTS; i += 2) { /* a joint's two components within its octagon */
            const double *g1 = J + (PLATFORM_LEGS + i) * DOF, *g2 = g1 + DOF;
            for (int j = 0; j < 4; j++) {
                const double c = cos(j * PI / 4.0), s = sin(j * PI / 4.0);
                const double now = c * envelope[PLATFORM_LEGS + i] + s * envelope[PLATFORM_LEGS + i + 1];
                double row[DOF];
                for (int d = 0; d < DOF; d++) row[d] = c * g1[d] + s * g2[d];
                constrain(m, k * ROWS + 16 + 2 * i + j, row, m->sq[k], moved, -sideways - now, sideways - now);
            }
        }
        /* the roll and pitch rate: the threshold, and as fast as the vehicle's own turns */
        const double radius = facet + sqrt(r[3] * r[3] + measure * r[4] * measure * r[4]) * cos(PI / 8.0);
        for (int j = 0; j < 4; j++) {
            double row[DOF] = {0};
            row[3] = cos(j * PI / 4.0), row[4] = sin(j * PI / 4.0) * measure;
            constrain(m, k * ROWS + 12 + j, row, m->sv[k], x.v, -radius, radius);
        }
    }
}

/* The rate the prediction continues (mpc.prediction_trend) at a solve at t: the vehicle's rate where
 * the MPC's reading ends, through a first-order low-pass of time constant mpc.trend_smoothing
 * sampled every solve (the first solve takes the rate as it is). */
static void update_trend(FmuInstance *fmu, double t) {
    const ModelVariables *v = &fmu->s.v;
    MpcState *state = &fmu->s.internal.mpc;
    if (!(v->mpc_prediction_trend > 0.0)) return;
    double rate[DOF];
    cueing_vehicle_rate(fmu, t, rate);
    const int smooth = state->trend_known && v->mpc_trend_smoothing > 0.0;
    const double keep = smooth ? exp(-v->mpc_period / v->mpc_trend_smoothing) : 0.0;
    for (int d = 0; d < DOF; d++)
        state->trend_rate[d] = smooth ? keep * state->trend_rate[d] + (1.0 - keep) * rate[d] : rate[d];
    state->trend_known = 1;
}

/* The QP at time t for the motion now (state mpc), solved: the first interval's accelerations. */
static void solve(FmuInstance *fmu, MpcData *m, double t) {
    const ModelVariables *v = &fmu->s.v;
    MpcState *state = &fmu->s.internal.mpc;
    Motion now;
    memcpy(&now, fmu->s.x, sizeof now);
    update_trend(fmu, t);
    form_qp(fmu, m, t, &now);
    DAQPResult result;
    double solution[Z], multipliers[Z + M]; /* u */
    result.x = solution, result.lam = multipliers;
    int status;
    if (!m->ready) {
        status = setup_daqp(&m->qp, &m->work, NULL);
        m->ready = status >= 0;
    } else {
        status = daqp_update_ldp(DAQP_UPDATE_M | DAQP_UPDATE_v | DAQP_UPDATE_d, &m->work, &m->qp);
    }
    if (status >= 0) {
        daqp_solve(&result, &m->work);
        daqp_extract_result(&result, &m->work);
        status = result.exitflag;
    }
    state->since = 0.0;
    state->solved_at = t;
    if (status < 0) { /* no answer: brake to rest at the largest acceleration */
        fmu_log(fmu, fmi2Warning, "logStatusWarning", "MPC at t = %g s: the QP solver gave no answer (DAQP exit %d); "
                "braking", t, status);
        for (int d = 0; d < DOF; d++) {
            const double limit = d >= 3 ? v->mpc_angular_acceleration_limit : v->mpc_acceleration_limit;
            state->a[d] = fmax(-limit, fmin(limit, -now.v[d] / m->h[0]));
        }
        state->iterations = 0;
        return;
    }
    for (int d = 0; d < DOF; d++) { /* z = R^-1 u: the first interval's */
        state->a[d] = 0.0;
        for (int j = d; j < Z; j++) state->a[d] += m->rinv[d * Z + j] * solution[j];
    }
    state->iterations = result.iter;
    if (result.soft_slack > 1e-3) state->softened++;
}

/* ---- the hooks model.c calls ---- */

void mpc_initialize(FmuInstance *fmu, MpcData *m) {
    MpcState *state = &fmu->s.internal.mpc;
    memset(state, 0, sizeof *state);
    Motion x; /* at neutral, at rest */
    memset(&x, 0, sizeof x);
    double r[DOF];
    vehicle_error_reference(fmu, fmu->s.time, fmu->s.time, r);
    for (int c = 0; c < DOF; c++) { /* settled for the error now: x = -A^-1 B e = (e / a_0, 0, ...) */
        const Organ *o = &m->organ[c < 3 ? 0 : 1];
        x.xi[XI_FIRST[c]] = -r[c] / -o->a[(o->n - 1) * o->n];
    }
    memcpy(fmu->s.x, &x, sizeof x);
    solve(fmu, m, fmu->s.time);
}

fmi2Status mpc_do_step(FmuInstance *fmu, MpcData *m, double h) {
    MpcState *state = &fmu->s.internal.mpc;
    const double t = fmu->s.time;
    if (m->step != h) {
        phi_slot(m, STEP_SLOT, h);
        m->step = h;
    }
    double r0[DOF], r1[DOF], y[DOF];
    for (int k = 0; k < DOF; k++) r0[k] = cueing_vehicle(fmu, k, t, &r1[k]);
    r0[2] -= gravity_of(fmu);
    Motion x;
    memcpy(&x, fmu->s.x, sizeof x);
    advance(m, STEP_SLOT, h, gravity_of(fmu), &x, state->a, r0, r1, y);
    memcpy(fmu->s.x, &x, sizeof x);
    state->since += h;
    if (state->since >= fmu->s.v.mpc_period * (1.0 - 1e-9)) solve(fmu, m, t + h);
    return fmi2OK;
}

/* The error each organ takes now (the platform's felt motion less the vehicle's), as advance's e_0. */
static void error_now(FmuInstance *fmu, const Motion *x, const double a[DOF], double e[DOF]) {
    const double g = gravity_of(fmu);
    double r[DOF];
    for (int k = 0; k < DOF; k++) r[k] = cueing_vehicle(fmu, k, fmu->s.time, NULL);
    r[2] -= g;
    e[0] = a[0] - g * x->q[4] - r[0];
    e[1] = a[1] + g * x->q[3] - r[1];
    e[2] = a[2] - r[2];
    for (int c = 3; c < DOF; c++) e[c] = x->v[c] - r[c];
}

void mpc_perceived_error(FmuInstance *fmu, const MpcData *m, double y[DOF]) {
    Motion x;
    double e[DOF];
    memcpy(&x, fmu->s.x, sizeof x);
    error_now(fmu, &x, fmu->s.internal.mpc.a, e);
    for (int c = 0; c < DOF; c++) { /* y = C xi + D e */
        const Organ *o = &m->organ[c < 3 ? 0 : 1];
        y[c] = o->d * e[c];
        for (int i = 0; i < o->n; i++) y[c] += o->c[i] * x.xi[XI_FIRST[c] + i];
    }
}

void mpc_derivatives(FmuInstance *fmu, const MpcData *m, double *dxdt) {
    const double *a = fmu->s.internal.mpc.a;
    Motion x, rate;
    double e[DOF];
    memcpy(&x, fmu->s.x, sizeof x);
    error_now(fmu, &x, a, e);
    for (int d = 0; d < DOF; d++) rate.q[d] = x.v[d], rate.v[d] = a[d];
    for (int c = 0; c < DOF; c++) { /* xi' = A xi + e_n e */
        const Organ *o = &m->organ[c < 3 ? 0 : 1];
        const double *xi = x.xi + XI_FIRST[c];
        for (int i = 0; i < o->n; i++) {
            double *out = rate.xi + XI_FIRST[c] + i;
            *out = i == o->n - 1 ? e[c] : 0.0;
            for (int j = 0; j < o->n; j++) *out += o->a[i * o->n + j] * xi[j];
        }
    }
    memcpy(dxdt, &rate, sizeof rate);
}

void mpc_state_nominals(const MpcData *m, double *nominals) {
    const double perceived_scale = 0.1; /* [m/s^2], [rad/s] */
    const size_t first = offsetof(Motion, xi) / sizeof(double);
    for (size_t k = 0; k < first; k++) nominals[k] = 1.0;
    for (int c = 0; c < DOF; c++) { /* y = C xi + D e: the canals' C reaches 2e3 (their 5 ms mode) */
        const Organ *o = &m->organ[c < 3 ? 0 : 1];
        for (int i = 0; i < o->n; i++)
            nominals[first + XI_FIRST[c] + i] = o->c[i] != 0.0 ? perceived_scale / fabs(o->c[i]) : 1.0;
    }
}

int mpc_time_event(FmuInstance *fmu, MpcData *m) {
    if (fmu->s.time < mpc_next_solve(fmu) - 1e-9 * fmu->s.v.mpc_period) return 0;
    solve(fmu, m, fmu->s.time);
    return 1;
}

double mpc_next_solve(const FmuInstance *fmu) { return fmu->s.internal.mpc.solved_at + fmu->s.v.mpc_period; }

void mpc_pose(const FmuInstance *fmu, double pose[6][4]) {
    const MpcState *state = &fmu->s.internal.mpc;
    Motion x;
    memcpy(&x, fmu->s.x, sizeof x);
    for (int d = 0; d < DOF; d++) pose[d][0] = x.q[d], pose[d][1] = x.v[d], pose[d][2] = state->a[d], pose[d][3] = 0.0;
}
