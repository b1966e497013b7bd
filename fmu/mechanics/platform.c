/* Stewart platform dynamics core; see platform.h for the formulation. */
#include "platform.h"

#include <math.h>
#include <string.h>

static const double PI = 3.14159265358979323846;

/* ---- small vector helpers ---------------------------------------------------------------- */

static double dot(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

static void cross(const double a[3], const double b[3], double out[3]) {
    double c[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
    memcpy(out, c, sizeof c);
}

static void mat_vec(const double R[9], const double v[3], double out[3]) {
    for (int i = 0; i < 3; i++) out[i] = R[3 * i] * v[0] + R[3 * i + 1] * v[1] + R[3 * i + 2] * v[2];
}

/* Cholesky factorisation of the symmetric positive definite A (n x n, row major) in place, then
 * solves A y = b into y. Returns -1 if A is not positive definite. */
static int cholesky_solve(int n, double *A, const double *b, double *y) {
    for (int j = 0; j < n; j++) {
        double d = A[j * n + j];
        for (int k = 0; k < j; k++) d -= A[j * n + k] * A[j * n + k];
        if (!(d > 0.0)) return -1;
        A[j * n + j] = sqrt(d);
        for (int i = j + 1; i < n; i++) {
            double s = A[i * n + j];
            for (int k = 0; k < j; k++) s -= A[i * n + k] * A[j * n + k];
            A[i * n + j] = s / A[j * n + j];
        }
    }
    for (int i = 0; i < n; i++) { /* L z = b */
        double s = b[i];
        for (int k = 0; k < i; k++) s -= A[i * n + k] * y[k];
        y[i] = s / A[i * n + i];
    }
    for (int i = n - 1; i >= 0; i--) { /* L' y = z */
        double s = y[i];
        for (int k = i + 1; k < n; k++) s -= A[k * n + i] * y[k];
        y[i] = s / A[i * n + i];
    }
    return 0;
}

/* Solves A y = b (n x n, row major, A overwritten) by LU with partial pivoting; -1 if singular. */
static int lu_solve(int n, double *A, const double *b, double *y) {
    double rhs[6];
    memcpy(rhs, b, sizeof(double) * (size_t)n);
    double scale = 0.0;
    for (int i = 0; i < n * n; i++) scale = fmax(scale, fabs(A[i]));
    for (int k = 0; k < n; k++) {
        int pivot = k;
        for (int i = k + 1; i < n; i++)
            if (fabs(A[i * n + k]) > fabs(A[pivot * n + k])) pivot = i;
        if (!(fabs(A[pivot * n + k]) > 1e-12 * scale)) return -1;
        if (pivot != k) {
            for (int j = 0; j < n; j++) { double t = A[k * n + j]; A[k * n + j] = A[pivot * n + j]; A[pivot * n + j] = t; }
            double t = rhs[k]; rhs[k] = rhs[pivot]; rhs[pivot] = t;
        }
        for (int i = k + 1; i < n; i++) {
            double f = A[i * n + k] / A[k * n + k];
            for (int j = k; j < n; j++) A[i * n + j] -= f * A[k * n + j];
            rhs[i] -= f * rhs[k];
        }
    }
    for (int i = n - 1; i >= 0; i--) {
        double s = rhs[i];
        for (int j = i + 1; j < n; j++) s -= A[i * n + j] * y[j];
        y[i] = s / A[i * n + i];
    }
    return 0;
}

/* ---- orientation ------------------------------------------------------------------------- */

void platform_rotation_from_euler(double roll, double pitch, double yaw, double R[9]) {
    double cr = cos(roll), sr = sin(roll), cp = cos(pitch), sp = sin(pitch), cy = cos(yaw), sy = sin(yaw);
    double M[9] = {cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr,
                   sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr,
                   -sp,     cp * sr,                cp * cr};
    memcpy(R, M, sizeof M);
}

void platform_rotation_from_quaternion(const double q[4], double R[9]) {
    double w = q[0], x = q[1], y = q[2], z = q[3];
    double M[9] = {1 - 2 * (y * y + z * z), 2 * (x * y - w * z),     2 * (x * z + w * y),
                   2 * (x * y + w * z),     1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
                   2 * (x * z - w * y),     2 * (y * z + w * x),     1 - 2 * (x * x + y * y)};
    memcpy(R, M, sizeof M);
}

void platform_quaternion_from_euler(double roll, double pitch, double yaw, double q[4]) {
    double cr = cos(roll / 2), sr = sin(roll / 2), cp = cos(pitch / 2), sp = sin(pitch / 2);
    double cy = cos(yaw / 2), sy = sin(yaw / 2);
    q[0] = cy * cp * cr + sy * sp * sr;
    q[1] = cy * cp * sr - sy * sp * cr;
    q[2] = cy * sp * cr + sy * cp * sr;
    q[3] = sy * cp * cr - cy * sp * sr;
}

void platform_euler_from_rotation(const double R[9], double euler[3]) {
    euler[0] = atan2(R[7], R[8]);
    euler[1] = -asin(fmax(-1.0, fmin(1.0, R[6])));
    euler[2] = atan2(R[3], R[0]);
}

/* w = E(roll, pitch, yaw) [roll_dot, pitch_dot, yaw_dot] for R = Rz Ry Rx; E_dot likewise. */
static void euler_rate_matrix(const double angle[3], const double rate[3], double E[9], double E_dot[9]) {
    double cp = cos(angle[1]), sp = sin(angle[1]), cy = cos(angle[2]), sy = sin(angle[2]);
    double pd = rate[1], yd = rate[2];
    double M[9] = {cy * cp, -sy, 0, sy * cp, cy, 0, -sp, 0, 1};
    double D[9] = {-sy * yd * cp - cy * sp * pd, -cy * yd, 0,
                   cy * yd * cp - sy * sp * pd,  -sy * yd, 0,
                   -cp * pd,                     0,        0};
    memcpy(E, M, sizeof M);
    memcpy(E_dot, D, sizeof D);
}

/* ---- geometry ---------------------------------------------------------------------------- */

int platform_layout_from_radii(Platform *p, double upper_radius, double lower_radius, double upper_spacing,
                               double lower_spacing, double middle_length, const double lower_centres_deg[3],
                               const double upper_centres_deg[3]) {
    if (!(upper_radius > 0 && lower_radius > 0 && upper_spacing >= 0 && lower_spacing >= 0 &&
          upper_spacing < 2 * upper_radius && lower_spacing < 2 * lower_radius))
        return -1;
    const double alpha_a = asin(upper_spacing / (2 * upper_radius));
    const double alpha_b = asin(lower_spacing / (2 * lower_radius));
    for (int k = 0; k < 3; k++) {
        const double lower_centre = lower_centres_deg[k] * PI / 180.0;
        const double lower_angle[2] = {lower_centre - alpha_b, lower_centre + alpha_b};
        const double upper_angle[2] = {upper_centres_deg[(k + 2) % 3] * PI / 180.0 + alpha_a,
                                       upper_centres_deg[k] * PI / 180.0 - alpha_a};
        for (int j = 0; j < 2; j++) {
            double *b = p->lower_joint[2 * k + j], *a = p->upper_joint[2 * k + j];
            b[0] = lower_radius * cos(lower_angle[j]); b[1] = lower_radius * sin(lower_angle[j]); b[2] = 0.0;
            a[0] = upper_radius * cos(upper_angle[j]); a[1] = upper_radius * sin(upper_angle[j]); a[2] = 0.0;
        }
    }
    /* neutral height from leg 1; the layout is symmetric, so every leg has the same length */
    double dx = p->upper_joint[0][0] - p->lower_joint[0][0], dy = p->upper_joint[0][1] - p->lower_joint[0][1];
    double horizontal2 = dx * dx + dy * dy;
    if (!(middle_length * middle_length > horizontal2)) return -1;
    memset(p->neutral_pose, 0, sizeof p->neutral_pose);
    p->neutral_pose[2] = sqrt(middle_length * middle_length - horizontal2);
    platform_leg_lengths(p, p->neutral_pose, p->neutral_length);
    return 0;
}

int platform_layout_from_joints(Platform *p, const double upper[PLATFORM_LEGS][3],
                                const double lower[PLATFORM_LEGS][3], const double neutral_pose[6]) {
    memcpy(p->upper_joint, upper, sizeof p->upper_joint);
    memcpy(p->lower_joint, lower, sizeof p->lower_joint);
    memcpy(p->neutral_pose, neutral_pose, sizeof p->neutral_pose);
    platform_leg_lengths(p, p->neutral_pose, p->neutral_length);
    for (int i = 0; i < PLATFORM_LEGS; i++)
        if (!(p->neutral_length[i] > 0.0)) return -1;
    return 0;
}

void platform_leg_lengths(const Platform *p, const double pose[6], double length[PLATFORM_LEGS]) {
    double R[9];
    platform_rotation_from_euler(pose[3], pose[4], pose[5], R);
    for (int i = 0; i < PLATFORM_LEGS; i++) {
        double r[3], l[3];
        mat_vec(R, p->upper_joint[i], r);
        for (int k = 0; k < 3; k++) l[k] = pose[k] + r[k] - p->lower_joint[i][k]; /* Eq 2 */
        length[i] = sqrt(dot(l, l));
    }
}

void platform_legs(const Platform *p, const double *x, LegGeometry legs[PLATFORM_LEGS]) {
    double q[4], R[9], norm = sqrt(x[3] * x[3] + x[4] * x[4] + x[5] * x[5] + x[6] * x[6]);
    for (int k = 0; k < 4; k++) q[k] = x[3 + k] / norm;
    platform_rotation_from_quaternion(q, R);
    const double *t = x, *v = x + 7, *w = x + 10;
    for (int i = 0; i < PLATFORM_LEGS; i++) {
        LegGeometry *g = &legs[i];
        double l[3], v_a[3], w_x_r[3];
        mat_vec(R, p->upper_joint[i], g->arm);
        for (int k = 0; k < 3; k++) l[k] = t[k] + g->arm[k] - p->lower_joint[i][k];
        g->length = sqrt(dot(l, l));
        for (int k = 0; k < 3; k++) g->axis[k] = l[k] / g->length;
        cross(w, g->arm, w_x_r);
        for (int k = 0; k < 3; k++) v_a[k] = v[k] + w_x_r[k]; /* Eq 3 */
        g->velocity = dot(g->axis, v_a);
    }
}

void platform_leg_jacobian(const LegGeometry legs[PLATFORM_LEGS], double J[36]) {
    for (int i = 0; i < PLATFORM_LEGS; i++) {
        double r_x_n[3];
        cross(legs[i].arm, legs[i].axis, r_x_n);
        for (int k = 0; k < 3; k++) {
            J[6 * i + k] = legs[i].axis[k];
            J[6 * i + 3 + k] = r_x_n[k];
        }
    }
}

double platform_jacobian_conditioning(const LegGeometry legs[PLATFORM_LEGS]) {
    double J[36];
    platform_leg_jacobian(legs, J);
    double scale = 1.0;
    for (int i = 0; i < 6; i++) {
        double norm = 0.0;
        for (int j = 0; j < 6; j++) norm += J[6 * i + j] * J[6 * i + j];
        norm = sqrt(norm);
        for (int j = 0; j < 6; j++) J[6 * i + j] /= norm;
    }
    /* determinant by Gaussian elimination with partial pivoting */
    for (int k = 0; k < 6; k++) {
        int pivot = k;
        for (int i = k + 1; i < 6; i++)
            if (fabs(J[6 * i + k]) > fabs(J[6 * pivot + k])) pivot = i;
        if (J[6 * pivot + k] == 0.0) return 0.0;
        if (pivot != k)
            for (int j = 0; j < 6; j++) { double t = J[6 * k + j]; J[6 * k + j] = J[6 * pivot + j]; J[6 * pivot + j] = t; }
        scale *= J[6 * k + k];
        for (int i = k + 1; i < 6; i++) {
            double f = J[6 * i + k] / J[6 * k + k];
            for (int j = k; j < 6; j++) J[6 * i + j] -= f * J[6 * k + j];
        }
    }
    return fabs(scale);
}

/* ---- dynamics ---------------------------------------------------------------------------- */

/* What the legs' inertia and friction are made of, with the platform's switches applied (see
 * platform.h): the moving, rotating and motor masses, their centres, the transverse inertia about
 * the lower joint, the rotor's spin reflected through the screw, the leg's spin inertia and the
 * joints' friction. */
typedef struct {
    double m_a, m_b, m_s, i_ab, spin, r_ac, r_bc, r_sc, I_s, C_S, C_U;
} LegConstants;

static LegConstants leg_constants(const Platform *p) {
    const int act = p->actuator_inertia_on, mot = p->motor_inertia_on;
    LegConstants c;
    c.m_a = act ? p->moving_mass : 0.0;
    c.m_b = act ? p->rotating_mass : 0.0;
    c.m_s = mot ? p->motor_mass : 0.0;
    c.i_ab = (act ? p->moving_inertia + p->rotating_inertia : 0.0) + (mot ? p->motor_inertia : 0.0);
    c.spin = mot ? p->rotor_inertia * p->screw_ratio * p->screw_ratio : 0.0;
    c.r_ac = p->moving_com;
    c.r_bc = p->rotating_com;
    c.r_sc = p->motor_com;
    c.I_s = act ? p->leg_spin_inertia : 0.0;
    c.C_S = p->friction_on ? p->joint_friction_lower : 0.0;
    c.C_U = p->friction_on ? p->joint_friction_upper : 0.0;
    return c;
}

/* The energies and loss power assemble sums over the bodies. */
typedef struct {
    double kinetic, potential, friction_loss;
} Energies;

/* Leg spin with the platform and joint friction (see platform.h). For y a torque-like vector at
 * the leg, (d w_b / du)' y = E_w' n (n.y) + (1/L) J_a' (y x n): a torque on the platform plus a
 * force (y x n) / L at the upper joint. n: the leg's axis, L its length, r its arm, v_a the upper
 * joint's velocity and P_v its part across the leg. */
static void add_leg_spin(const LegConstants *c, const double n[3], double L, const double r[3], const double w[3],
                         const double v_a[3], const double P_v[3], double M[36], double rhs0[6], Energies *e) {
    const double I_s = c->I_s, C_S = c->C_S, C_U = c->C_U;
    const double s = dot(n, w);
    double n_dot[3], n_x_v[3], w_b[3], rho[3];
    for (int k = 0; k < 3; k++) n_dot[k] = P_v[k] / L;
    cross(n, v_a, n_x_v);
    for (int k = 0; k < 3; k++) {
        w_b[k] = s * n[k] + n_x_v[k] / L;
        rho[k] = w_b[k] - w[k]; /* rate across the upper joint; rho . n = 0 */
    }
    /* dH/dt of the spin, I_s (s_dot n + s n_dot): its s_dot part, with s_dot = n_dot.w + n.w_dot,
     * goes to M and the rest here; C_S w_b on the leg; C_U rho on the leg and -C_U rho on the
     * platform. */
    double n_x_ndot[3], friction_y[3], y_x_n[3], f_joint[3], r_x_f_joint[3];
    cross(n, n_dot, n_x_ndot);
    for (int k = 0; k < 3; k++) friction_y[k] = C_S * w_b[k] + C_U * rho[k];
    cross(friction_y, n, y_x_n);
    const double n_dot_w = dot(n_dot, w);
    for (int k = 0; k < 3; k++) f_joint[k] = I_s * s / L * n_x_ndot[k] - y_x_n[k] / L;
    cross(r, f_joint, r_x_f_joint);
    for (int k = 0; k < 3; k++) {
        rhs0[k] += f_joint[k];
        rhs0[3 + k] += r_x_f_joint[k] - I_s * n_dot_w * n[k] - C_S * s * n[k] + C_U * rho[k];
    }
    for (int a = 0; a < 3; a++)
        for (int b = 0; b < 3; b++) M[6 * (3 + a) + 3 + b] += I_s * n[a] * n[b];
    e->kinetic += 0.5 * I_s * s * s;
    e->friction_loss += C_S * dot(w_b, w_b) + C_U * dot(rho, rho);
}

/* M += J_a' S J_a for a leg of inertia S at arm r, with J_a = [I, -[r]x]:
 * [[S, -S [r]x], [[r]x S, -[r]x S [r]x]]. */
static void add_leg_mass(const double S[9], const double r[3], double M[36]) {
    double S_rx[9];
    for (int a = 0; a < 3; a++) { /* row a of S [r]x is (row a of S) x r */
        const double *row = S + 3 * a;
        S_rx[3 * a + 0] = row[1] * r[2] - row[2] * r[1];
        S_rx[3 * a + 1] = row[2] * r[0] - row[0] * r[2];
        S_rx[3 * a + 2] = row[0] * r[1] - row[1] * r[0];
    }
    for (int a = 0; a < 3; a++)
        for (int b = 0; b < 3; b++) {
            /* ([r]x S [r]x)_ab = sum_c [r]x_ac (S [r]x)_cb, with [r]x = [[0,-r2,r1],[r2,0,-r0],[-r1,r0,0]] */
            const double rx_S_rx = (a == 0)   ? -r[2] * S_rx[3 + b] + r[1] * S_rx[6 + b]
                                   : (a == 1) ? r[2] * S_rx[b] - r[0] * S_rx[6 + b]
                                              : -r[1] * S_rx[b] + r[0] * S_rx[3 + b];
            M[6 * a + b] += S[3 * a + b];
            M[6 * a + 3 + b] -= S_rx[3 * a + b];
            M[6 * (3 + b) + a] -= S_rx[3 * a + b]; /* symmetric block: ([r]x S)' = -S [r]x */
            M[6 * (3 + a) + 3 + b] -= rx_S_rx;
        }
}

/* Leg i of the platform at position t, rotation R, velocity v and angular velocity w: its
 * geometry (leg), its inertia added to M and its forces other than the actuator's to rhs0, its
 * energies and losses to e. */
static void add_leg(const Platform *p, const LegConstants *c, int i, const double R[9], const double *t,
                    const double *v, const double *w, double M[36], double rhs0[6], LegGeometry *leg, Energies *e) {
    const double *g = p->gravity;
    double l[3], v_a[3], w_x_r[3], bias[3], n[3], r[3];
    mat_vec(R, p->upper_joint[i], r);
    memcpy(leg->arm, r, sizeof r);
    for (int k = 0; k < 3; k++) l[k] = t[k] + r[k] - p->lower_joint[i][k];
    const double L = sqrt(dot(l, l));
    for (int k = 0; k < 3; k++) n[k] = l[k] / L;
    memcpy(leg->axis, n, sizeof n);
    leg->length = L;
    cross(w, r, w_x_r);
    for (int k = 0; k < 3; k++) v_a[k] = v[k] + w_x_r[k]; /* Eq 3 */
    cross(w, w_x_r, bias);                               /* Eq 8: w x (w x r) */
    const double L_dot = dot(n, v_a);
    leg->velocity = L_dot;

    /* Leg inertia at the upper joint: mu_axial n n' + mu_perp P, and d mu_perp / dL. */
    const double m_a = c->m_a, m_b = c->m_b, m_s = c->m_s, r_ac = c->r_ac, r_bc = c->r_bc, r_sc = c->r_sc;
    const double ua = 1.0 - r_ac / L, ub = r_bc / L, us = r_sc / L;
    const double mu_axial = m_a + c->spin;
    const double mu_perp = m_a * ua * ua + m_b * ub * ub + m_s * us * us + c->i_ab / (L * L);
    const double mu_perp_dL = (2.0 * m_a * ua * r_ac - 2.0 * m_b * ub * r_bc - 2.0 * m_s * us * r_sc) / (L * L) -
                              2.0 * c->i_ab / (L * L * L);
    double P_v[3], P_g[3], P_bias[3];
    for (int k = 0; k < 3; k++) {
        P_v[k] = v_a[k] - n[k] * L_dot;
        P_g[k] = g[k] - n[k] * dot(n, g);
        P_bias[k] = bias[k] - n[k] * dot(n, bias);
    }
    const double vPv = dot(v_a, P_v);

    /* Leg force at the upper joint from everything but the actuator (acting on the platform):
     * -(M_leg bias + velocity terms + gravity gradient + friction), Lagrange in p_a. */
    const double c_axial = ((mu_axial - mu_perp) / L - 0.5 * mu_perp_dL) * vPv;
    const double friction = p->friction_on ? p->viscous_friction * p->screw_ratio * p->screw_ratio * L_dot : 0.0;
    double f[3];
    for (int k = 0; k < 3; k++) {
        double inertial = mu_axial * n[k] * dot(n, bias) + mu_perp * P_bias[k];
        double velocity_terms = c_axial * n[k] + mu_perp_dL * L_dot * P_v[k];
        double gravity = m_a * (n[k] * dot(n, g) + ua * P_g[k]) + (m_b * ub + m_s * us) * P_g[k];
        f[k] = -inertial - velocity_terms + gravity - friction * n[k];
    }
    double r_x_f[3];
    cross(r, f, r_x_f);
    for (int k = 0; k < 3; k++) {
        rhs0[k] += f[k];
        rhs0[3 + k] += r_x_f[k];
    }
    double S[9];
    for (int a = 0; a < 3; a++)
        for (int b = 0; b < 3; b++) S[3 * a + b] = mu_axial * n[a] * n[b] + mu_perp * ((a == b) - n[a] * n[b]);
    add_leg_mass(S, r, M);
    if (c->I_s != 0.0 || c->C_S != 0.0 || c->C_U != 0.0) add_leg_spin(c, n, L, r, w, v_a, P_v, M, rhs0, e);

    e->kinetic += 0.5 * (mu_axial * L_dot * L_dot + mu_perp * vPv);
    /* centres of mass: p_a - r_ac n (moving), b + r_bc n (rotating), b + r_sc n (motor) */
    e->potential -= m_a * (dot(g, t) + dot(g, r) - r_ac * dot(g, n)) +
                    (m_b + m_s) * dot(g, p->lower_joint[i]) + (m_b * r_bc + m_s * r_sc) * dot(g, n);
    if (p->friction_on) {
        double speed = p->screw_ratio * L_dot;
        e->friction_loss += p->viscous_friction * speed * speed;
    }
}

/* Assembles the mass matrix M (Eq 23) and the generalized force of everything but the actuators
 * (gravity, velocity terms, friction, external wrench): M u_dot = rhs0 + sum_i [n_i; r_i x n_i] F_i.
 * Fills the energies and the loss powers of diag (if not NULL). */
static void assemble(const Platform *p, const double *x, const double wrench[6], double M[36], double rhs0[6],
                     LegGeometry legs[PLATFORM_LEGS], PlatformDiagnostics *diag) {
    double q[4], R[9], norm = sqrt(x[3] * x[3] + x[4] * x[4] + x[5] * x[5] + x[6] * x[6]);
    for (int k = 0; k < 4; k++) q[k] = x[3 + k] / norm;
    platform_rotation_from_quaternion(q, R);
    const double *t = x, *v = x + 7, *w = x + 10, *g = p->gravity;

    /* Platform (Eq 9): I_p = R I_p^p R' */
    double Ip[9];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            double s = 0.0;
            for (int k = 0; k < 3; k++) s += R[3 * i + k] * p->platform_inertia[k] * R[3 * j + k];
            Ip[3 * i + j] = s;
        }
    memset(M, 0, sizeof(double) * 36);
    for (int k = 0; k < 3; k++) M[7 * k] = p->platform_mass;
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) M[6 * (3 + i) + 3 + j] = Ip[3 * i + j];
    double Ip_w[3], gyro[3];
    mat_vec(Ip, w, Ip_w);
    cross(w, Ip_w, gyro);
    for (int k = 0; k < 3; k++) {
        rhs0[k] = p->platform_mass * g[k] + wrench[k];
        rhs0[3 + k] = -gyro[k] + wrench[3 + k];
    }
    Energies e = {0.5 * p->platform_mass * dot(v, v) + 0.5 * dot(w, Ip_w), -p->platform_mass * dot(g, t), 0.0};
    const LegConstants c = leg_constants(p);
    for (int i = 0; i < PLATFORM_LEGS; i++) add_leg(p, &c, i, R, t, v, w, M, rhs0, &legs[i], &e);
    if (diag) {
        memcpy(diag->mass_matrix, M, sizeof(double) * 36);
        diag->kinetic = e.kinetic;
        diag->potential = e.potential;
        diag->friction_loss = e.friction_loss;
        diag->load_power = dot(wrench, v) + dot(wrench + 3, w);
    }
}

void platform_applied_efforts(const Platform *p, const LegGeometry legs[PLATFORM_LEGS],
                              const double torque_in[PLATFORM_LEGS], const double force_in[PLATFORM_LEGS],
                              const PlatformDriveSlopes *slopes, double torque[PLATFORM_LEGS],
                              double force[PLATFORM_LEGS]) {
    for (int i = 0; i < PLATFORM_LEGS; i++) {
        torque[i] = torque_in[i];
        force[i] = force_in[i];
        if (slopes) { /* the drives' interface Jacobians (see platform.h) */
            torque[i] += slopes->torque_speed_slope[i] * (p->screw_ratio * legs[i].velocity - slopes->speed_seen[i]);
            force[i] += slopes->force_velocity_slope[i] * (legs[i].velocity - slopes->velocity_seen[i]);
        }
    }
}

int platform_derivatives(const Platform *p, const double *x, const double torque_in[PLATFORM_LEGS],
                         const double force_in[PLATFORM_LEGS], const PlatformDriveSlopes *slopes,
                         const double wrench[6], double *dxdt, PlatformDiagnostics *diag) {
    double M[36], rhs[6], accel[6];
    LegGeometry legs[PLATFORM_LEGS];
    PlatformDiagnostics local;
    if (!diag) diag = &local;
    assemble(p, x, wrench, M, rhs, legs, diag);
    double drive_power = 0.0, transmission_loss = 0.0, torque[PLATFORM_LEGS], force[PLATFORM_LEGS];
    platform_applied_efforts(p, legs, torque_in, force_in, slopes, torque, force);
    for (int i = 0; i < PLATFORM_LEGS; i++) {
        /* Eq 22: the screw turns motor torque into leg force K_FT T = eta i_theta T */
        const double F = p->force_torque * torque[i] + force[i];
        double r_x_n[3];
        cross(legs[i].arm, legs[i].axis, r_x_n);
        for (int k = 0; k < 3; k++) {
            rhs[k] += F * legs[i].axis[k];
            rhs[3 + k] += F * r_x_n[k];
        }
        const double motor_speed = p->screw_ratio * legs[i].velocity;
        drive_power += torque[i] * motor_speed + force[i] * legs[i].velocity;
        transmission_loss += (p->screw_ratio - p->force_torque) * torque[i] * legs[i].velocity;
    }
    diag->drive_power = drive_power;
    diag->transmission_loss = transmission_loss;
    diag->singular = cholesky_solve(6, M, rhs, accel) != 0;
    if (diag->singular) return -1;

    const double *q = x + 3, *w = x + 10;
    memcpy(dxdt, x + 7, sizeof(double) * 3); /* t_dot = v */
    dxdt[3] = 0.5 * (-w[0] * q[1] - w[1] * q[2] - w[2] * q[3]); /* q_dot = 1/2 (0, w) (x) q */
    dxdt[4] = 0.5 * (w[0] * q[0] + w[1] * q[3] - w[2] * q[2]);
    dxdt[5] = 0.5 * (w[1] * q[0] + w[2] * q[1] - w[0] * q[3]);
    dxdt[6] = 0.5 * (w[2] * q[0] + w[0] * q[2] - w[1] * q[1]);
    memcpy(dxdt + 7, accel, sizeof accel);
    return 0;
}

void platform_state_from_pose(const double pose[6], const double pose_rate[6], double *x) {
    double E[9], E_dot[9];
    memcpy(x, pose, sizeof(double) * 3);
    platform_quaternion_from_euler(pose[3], pose[4], pose[5], x + 3);
    memcpy(x + 7, pose_rate, sizeof(double) * 3);
    euler_rate_matrix(pose + 3, pose_rate + 3, E, E_dot);
    mat_vec(E, pose_rate + 3, x + 10);
}

int platform_inverse_dynamics(const Platform *p, const double pose[6], const double pose_rate[6],
                              const double pose_acceleration[6], const double wrench[6],
                              double torque[PLATFORM_LEGS]) {
    double x[PLATFORM_STATES], M[36], rhs0[6], u_dot[6], E[9], E_dot[9], Q[6], J[36], JT[36], F[6];
    LegGeometry legs[PLATFORM_LEGS];
    platform_state_from_pose(pose, pose_rate, x);
    euler_rate_matrix(pose + 3, pose_rate + 3, E, E_dot);
    memcpy(u_dot, pose_acceleration, sizeof(double) * 3);
    double a[3], b[3];
    mat_vec(E, pose_acceleration + 3, a);
    mat_vec(E_dot, pose_rate + 3, b);
    for (int k = 0; k < 3; k++) u_dot[3 + k] = a[k] + b[k];
    assemble(p, x, wrench, M, rhs0, legs, NULL);
    for (int i = 0; i < 6; i++) {
        Q[i] = -rhs0[i];
        for (int j = 0; j < 6; j++) Q[i] += M[6 * i + j] * u_dot[j];
    }
    /* sum_i [n_i; r_i x n_i] F_i = J' F = Q */
    platform_leg_jacobian(legs, J);
    for (int i = 0; i < 6; i++)
        for (int j = 0; j < 6; j++) JT[6 * i + j] = J[6 * j + i];
    if (lu_solve(6, JT, Q, F) != 0) return -1;
    for (int i = 0; i < PLATFORM_LEGS; i++) torque[i] = F[i] / p->force_torque;
    return 0;
}

int platform_leg_plants(const Platform *p, const double *x, double inertia[PLATFORM_LEGS],
                        double static_force[PLATFORM_LEGS]) {
    double at_rest[PLATFORM_STATES], M[36], rhs0[6], J[36], JT[36], Q[6];
    const double no_wrench[6] = {0, 0, 0, 0, 0, 0};
    LegGeometry legs[PLATFORM_LEGS];
    memcpy(at_rest, x, sizeof at_rest);
    memset(at_rest + 7, 0, sizeof(double) * 6);
    assemble(p, at_rest, no_wrench, M, rhs0, legs, NULL);
    platform_leg_jacobian(legs, J); /* leg rates = J u */
    for (int i = 0; i < 6; i++)
        for (int j = 0; j < 6; j++) JT[6 * i + j] = J[6 * j + i];
    for (int i = 0; i < PLATFORM_LEGS; i++) { /* u moving leg i alone at unit rate: J u = e_i */
        double e[6] = {0, 0, 0, 0, 0, 0}, u[6], A[36];
        e[i] = 1.0;
        memcpy(A, J, sizeof A); /* lu_solve overwrites its matrix */
        if (lu_solve(6, A, e, u) != 0) return -1;
        inertia[i] = 0.0; /* u' M u: twice the kinetic energy */
        for (int r = 0; r < 6; r++)
            for (int c = 0; c < 6; c++) inertia[i] += u[r] * M[6 * r + c] * u[c];
    }
    for (int k = 0; k < 6; k++) Q[k] = -rhs0[k]; /* at rest: J' F = -(gravity and bias terms) */
    return lu_solve(6, JT, Q, static_force) != 0 ? -1 : 0;
}

/* ---- design studies ------------------------------------------------------------------------ */

void platform_joint_cosines(const double R[9], const double axis[3], const double n0[3], double *lower,
                            double *upper) {
    double along = 0.0, across = 0.0;
    for (int k = 0; k < 3; k++) {
        along += axis[k] * n0[k];
        across += (R[k] * axis[0] + R[3 + k] * axis[1] + R[6 + k] * axis[2]) * n0[k]; /* (R'n).n0 */
    }
    *lower = fmax(-1.0, fmin(1.0, along));
    *upper = fmax(-1.0, fmin(1.0, across));
}

void platform_joint_angles(const double R[9], const double axis[3], const double n0[3], double *lower,
                           double *upper) {
    platform_joint_cosines(R, axis, n0, lower, upper);
    *lower = acos(*lower);
    *upper = acos(*upper);
}

void platform_pose_kinematics(const Platform *p, int n, const double *poses, double *length,
                              double *lower_angle, double *upper_angle, double *jacobian) {
    const double at_rest[6] = {0, 0, 0, 0, 0, 0};
    double x[PLATFORM_STATES], R[9];
    LegGeometry neutral[PLATFORM_LEGS], legs[PLATFORM_LEGS];
    platform_state_from_pose(p->neutral_pose, at_rest, x);
    platform_legs(p, x, neutral);
    for (int k = 0; k < n; k++) {
        const double *pose = poses + 6 * k;
        platform_state_from_pose(pose, at_rest, x);
        platform_legs(p, x, legs);
        platform_rotation_from_euler(pose[3], pose[4], pose[5], R);
        for (int i = 0; i < PLATFORM_LEGS; i++) {
            double lower, upper;
            platform_joint_angles(R, legs[i].axis, neutral[i].axis, &lower, &upper);
            if (length) length[6 * k + i] = legs[i].length;
            if (lower_angle) lower_angle[6 * k + i] = lower;
            if (upper_angle) upper_angle[6 * k + i] = upper;
        }
        if (jacobian) platform_leg_jacobian(legs, jacobian + 36 * k);
    }
}

void platform_leg_velocities_many(const Platform *p, int n, const double *pose, const double *pose_rate,
                                  double *velocity) {
    double x[PLATFORM_STATES];
    LegGeometry legs[PLATFORM_LEGS];
    for (int k = 0; k < n; k++) {
        platform_state_from_pose(pose + 6 * k, pose_rate + 6 * k, x);
        platform_legs(p, x, legs);
        for (int i = 0; i < PLATFORM_LEGS; i++) velocity[6 * k + i] = legs[i].velocity;
    }
}

int platform_inverse_dynamics_many(const Platform *p, int n, const double *pose, const double *pose_rate,
                                   const double *pose_acceleration, const double wrench[6], double *torque) {
    int singular = 0;
    for (int k = 0; k < n; k++) {
        if (platform_inverse_dynamics(p, pose + 6 * k, pose_rate + 6 * k, pose_acceleration + 6 * k, wrench,
                                      torque + 6 * k) != 0) {
            for (int i = 0; i < PLATFORM_LEGS; i++) torque[6 * k + i] = NAN;
            singular++;
        }
    }
    return singular;
}
