/* pmsm_drive: one leg's PMSM vector-control drive (Meng et al. 2010, Section 3, Figs 3-4).
 *
 * The drive computes the electromagnetic torque only; the rotor's inertia and viscous friction
 * belong to the platform mechanics (Eq 23), which returns the shaft angle and speed.
 *
 *   motor (Eqs 24-26)  u_d = R i_d + L_d di_d/dt - w_r L_q i_q
 *                      u_q = R i_q + L_q di_q/dt + w_r L_d i_d + w_r psi_r
 *                      T   = P (psi_r i_q + (L_d - L_q) i_d i_q),   w_r = P w_m,  psi_r = K_m / P
 *   control (Fig 4)    APR: w*  = clamp(Kp_p e_theta + int Ki_p e_theta + speed_ff, w_max)
 *                      ASR: i_q* = clamp(Kp_w e_w + int Ki_w e_w + torque_ff / K_m, I_max)
 *                      ACR: u    = clamp(Kp_c e_i + int Ki_c e_i, V_max / K_v), d and q, i_d* given
 *                      PI integrators with back-calculation anti-windup (tracking gain Ki / Kp).
 *   inverter           1 ideal u_dq = K_v u;  2 averaged tau_v du_dq/dt = K_v u - u_dq  (Fig 4);
 *                      3 switching: hysteresis comparators on the three phase currents drive a
 *                        two-level inverter fed by V_dc (Fig 3); the motor is integrated in dq0,
 *                        which is the abc model: with the star point isolated (Fig 3) the
 *                        zero-sequence current is zero; tied to the DC-link midpoint it obeys
 *                        L_0 di_0/dt = u_0 - R i_0 and carries no torque.
 * The dq quantities use the power-invariant transform, in which Eqs 24-26 hold as printed
 * (no factor 3/2) and u_d i_d + u_q i_q is the electrical power.
 */
#include "fmu_common.h"

#include <string.h>

/* The states: first the current loops' (stiff: the Rosenbrock-W solver takes them implicitly),
 * then the outer loops' integrators and the energy accounts (slow: explicit). */
enum { I_D, I_Q, I_0, V_D, V_Q, INT_CURRENT_D, INT_CURRENT_Q, N_STIFF,
       INT_POSITION = N_STIFF, INT_SPEED, E_ELECTRICAL, E_COPPER, E_MECHANICAL };

enum { INVERTER_IDEAL = 1, INVERTER_AVERAGED = 2, INVERTER_SWITCHING = 3 };
enum { MODE_POSITION = 1, MODE_SPEED = 2, MODE_TORQUE = 3 };

static const double SQRT_2_3 = 0.816496580927726032732428; /* sqrt(2/3) */
static const double SQRT_3_2 = 0.866025403784438646763723; /* sqrt(3)/2 */

static double clamp(double value, double limit) {
    return value > limit ? limit : (value < -limit ? -limit : value);
}

/* Every algebraic quantity of the drive at one instant. */
typedef struct {
    double angle, speed, electrical_angle, electrical_speed;
    double angle_error, speed_ref_raw, speed_ref, speed_error;
    double current_ref_q_raw, current_ref_q, current_ref_d;
    double command_d_raw, command_d, command_q_raw, command_q; /* current-controller outputs */
    double voltage_d, voltage_q, voltage_0;                     /* applied to the motor */
    double phase_current[3], phase_current_ref[3];
    double torque;
} Signals;

static const double SQRT_1_3 = 0.577350269189625764509149; /* 1/sqrt(3) */

/* Power-invariant inverse Park + Clarke: dq0 at electrical angle theta -> phases a, b, c. */
static void dq0_to_abc(double d, double q, double zero, double cos_t, double sin_t, double abc[3]) {
    double alpha = d * cos_t - q * sin_t, beta = d * sin_t + q * cos_t;
    abc[0] = SQRT_2_3 * alpha + SQRT_1_3 * zero;
    abc[1] = SQRT_2_3 * (-0.5 * alpha + SQRT_3_2 * beta) + SQRT_1_3 * zero;
    abc[2] = SQRT_2_3 * (-0.5 * alpha - SQRT_3_2 * beta) + SQRT_1_3 * zero;
}

/* Computes the drive's signals at t; the phase quantities only when `with_phases` (outputs,
 * switching inverter), since the dq model does not need them. */
static void evaluate(const FmuInstance *fmu, double t, const double *x, Signals *s, int with_phases) {
    const ModelVariables *v = &fmu->s.v;
    const double pole_pairs = v->motor_pole_pairs, psi_r = v->motor_torque_constant / pole_pairs;
    const double dt = t - fmu->s.input_time;

    /* Inputs at t: the shaft angle advances with the speed inside a step unless the master gave
     * the angle's own derivative. */
    s->speed = fmu_input_at(fmu, VR_speed, t);
    s->angle = fmu_input_has_derivative(fmu, VR_angle)
                   ? fmu_input_at(fmu, VR_angle, t)
                   : v->angle + 0.5 * (v->speed + s->speed) * dt;
    s->electrical_angle = pole_pairs * s->angle;
    s->electrical_speed = pole_pairs * s->speed;
    const double torque_ff = fmu_input_at(fmu, VR_torque_ff, t);
    const double speed_ff = fmu_input_at(fmu, VR_speed_ff, t);

    /* Position loop (APR) and speed loop (ASR). */
    s->angle_error = fmu_input_at(fmu, VR_angle_ref, t) - s->angle;
    s->current_ref_d = v->control_current_d_ref;
    const double current_q_limit = sqrt(v->limit_current * v->limit_current - s->current_ref_d * s->current_ref_d);
    if (v->control_mode == MODE_TORQUE) {
        s->speed_ref_raw = s->speed_ref = s->speed_error = 0.0;
        s->current_ref_q_raw = torque_ff / v->motor_torque_constant;
    } else {
        s->speed_ref_raw = speed_ff;
        if (v->control_mode == MODE_POSITION)
            s->speed_ref_raw += v->control_position_kp * s->angle_error + x[INT_POSITION];
        s->speed_ref = clamp(s->speed_ref_raw, v->limit_speed);
        s->speed_error = s->speed_ref - s->speed;
        s->current_ref_q_raw = v->control_speed_kp * s->speed_error + x[INT_SPEED] + torque_ff / v->motor_torque_constant;
    }
    s->current_ref_q = clamp(s->current_ref_q_raw, current_q_limit);

    /* Current loops (ACR) and the inverter. */
    const int switching = v->inverter_model == INVERTER_SWITCHING;
    const double cos_t = (with_phases || switching) ? cos(s->electrical_angle) : 1.0;
    const double sin_t = (with_phases || switching) ? sin(s->electrical_angle) : 0.0;
    if (switching) {
        /* Phase-to-star-point voltages: each leg puts its phase at +-V_dc/2 about the DC-link
         * midpoint; an isolated star point floats to the mean of the three. */
        const int *sw = fmu->s.internal.switch_state;
        double phase_voltage[3], mean = 0.0;
        for (int k = 0; k < 3; k++) {
            phase_voltage[k] = v->inverter_dc_link_voltage * (sw[k] - 0.5);
            mean += phase_voltage[k] / 3.0;
        }
        if (!v->inverter_neutral_connected)
            for (int k = 0; k < 3; k++) phase_voltage[k] -= mean;
        double alpha = SQRT_2_3 * (phase_voltage[0] - 0.5 * phase_voltage[1] - 0.5 * phase_voltage[2]);
        double beta = SQRT_2_3 * SQRT_3_2 * (phase_voltage[1] - phase_voltage[2]);
        s->voltage_d = alpha * cos_t + beta * sin_t;
        s->voltage_q = -alpha * sin_t + beta * cos_t;
        s->voltage_0 = SQRT_1_3 * (phase_voltage[0] + phase_voltage[1] + phase_voltage[2]);
        s->command_d_raw = s->command_d = s->command_q_raw = s->command_q = 0.0;
    } else {
        const double command_limit = v->limit_voltage / v->inverter_gain;
        s->voltage_0 = 0.0;
        s->command_d_raw = v->control_current_kp * (s->current_ref_d - x[I_D]) + x[INT_CURRENT_D];
        s->command_q_raw = v->control_current_kp * (s->current_ref_q - x[I_Q]) + x[INT_CURRENT_Q];
        s->command_d = clamp(s->command_d_raw, command_limit);
        s->command_q = clamp(s->command_q_raw, command_limit);
        if (v->inverter_model == INVERTER_IDEAL) {
            s->voltage_d = v->inverter_gain * s->command_d;
            s->voltage_q = v->inverter_gain * s->command_q;
        } else {
            s->voltage_d = x[V_D];
            s->voltage_q = x[V_Q];
        }
    }
    if (with_phases) {
        dq0_to_abc(x[I_D], x[I_Q], x[I_0], cos_t, sin_t, s->phase_current);
        dq0_to_abc(s->current_ref_d, s->current_ref_q, 0.0, cos_t, sin_t, s->phase_current_ref);
    }

    /* Eq 26 */
    s->torque = pole_pairs * (psi_r * x[I_Q] + (v->motor_inductance_d - v->motor_inductance_q) * x[I_D] * x[I_Q]);
}

/* Back-calculation anti-windup: while the output is clamped the integrator tracks it. */
static double pi_integrator_rate(double ki, double kp, double error, double clamped, double raw) {
    return ki * error + (ki / kp) * (clamped - raw);
}

/* The model's derivatives at (t, x), and its signals there (which limits hold). */
static void derivatives(const FmuInstance *fmu, double t, const double *x, double *dxdt, Signals *signals) {
    const ModelVariables *v = &fmu->s.v;
    Signals s;
    evaluate(fmu, t, x, &s, 0);
    *signals = s;
    const double R = v->motor_resistance, L_d = v->motor_inductance_d, L_q = v->motor_inductance_q;
    const double psi_r = v->motor_torque_constant / v->motor_pole_pairs, w_r = s.electrical_speed;

    dxdt[I_D] = (s.voltage_d - R * x[I_D] + w_r * L_q * x[I_Q]) / L_d;          /* Eq 24 */
    dxdt[I_Q] = (s.voltage_q - R * x[I_Q] - w_r * L_d * x[I_D] - w_r * psi_r) / L_q; /* Eq 25 */
    dxdt[I_0] = (s.voltage_0 - R * x[I_0]) / v->motor_inductance_0;                /* zero sequence */

    if (v->inverter_model == INVERTER_AVERAGED) {
        dxdt[V_D] = (v->inverter_gain * s.command_d - x[V_D]) / v->inverter_time_constant;
        dxdt[V_Q] = (v->inverter_gain * s.command_q - x[V_Q]) / v->inverter_time_constant;
    } else {
        dxdt[V_D] = dxdt[V_Q] = 0.0;
    }
    /* Cascade anti-windup: the position integral also stops while the current limit holds the
     * inner loops back in the direction it would push. */
    const double current_excess = s.current_ref_q_raw - s.current_ref_q;
    const int inner_saturated = current_excess * s.angle_error > 0.0;
    dxdt[INT_POSITION] = (v->control_mode == MODE_POSITION && !inner_saturated)
                             ? pi_integrator_rate(v->control_position_ki, v->control_position_kp, s.angle_error,
                                                  s.speed_ref, s.speed_ref_raw)
                             : 0.0;
    dxdt[INT_SPEED] = v->control_mode != MODE_TORQUE
                          ? pi_integrator_rate(v->control_speed_ki, v->control_speed_kp, s.speed_error,
                                               s.current_ref_q, s.current_ref_q_raw)
                          : 0.0;
    if (v->inverter_model == INVERTER_SWITCHING) {
        dxdt[INT_CURRENT_D] = dxdt[INT_CURRENT_Q] = 0.0;
    } else {
        dxdt[INT_CURRENT_D] = pi_integrator_rate(v->control_current_ki, v->control_current_kp,
                                                 s.current_ref_d - x[I_D], s.command_d, s.command_d_raw);
        dxdt[INT_CURRENT_Q] = pi_integrator_rate(v->control_current_ki, v->control_current_kp,
                                                 s.current_ref_q - x[I_Q], s.command_q, s.command_q_raw);
    }
    dxdt[E_ELECTRICAL] = s.voltage_d * x[I_D] + s.voltage_q * x[I_Q] + s.voltage_0 * x[I_0];
    dxdt[E_COPPER] = R * (x[I_D] * x[I_D] + x[I_Q] * x[I_Q] + x[I_0] * x[I_0]);
    dxdt[E_MECHANICAL] = s.torque * s.speed;
}

static void rhs(void *ctx, double t, const double *x, double *dxdt) {
    Signals s;
    derivatives((const FmuInstance *)ctx, t, x, dxdt, &s);
}

/* The stiff block of df/dx for the Rosenbrock-W solver: the current loops, the inverter and the
 * winding (Eqs 24-25 with the ACR and the inverter lag), with the limits as they stand at (t, x).
 * The outer loops' integrators are outside the block (explicit): a W-method keeps its order with
 * any matrix, and they are slow. */
static void stiff_jacobian(void *ctx, double t, const double *x, double J[][ODE_MAX_STATES]) {
    const FmuInstance *fmu = (const FmuInstance *)ctx;
    const ModelVariables *v = &fmu->s.v;
    Signals s;
    evaluate(fmu, t, x, &s, 0);
    const double R = v->motor_resistance, L_d = v->motor_inductance_d, L_q = v->motor_inductance_q;
    const double w_r = s.electrical_speed, kp = v->control_current_kp, ki = v->control_current_ki;
    J[I_D][I_D] = -R / L_d;
    J[I_D][I_Q] = w_r * L_q / L_d;
    J[I_Q][I_Q] = -R / L_q;
    J[I_Q][I_D] = -w_r * L_d / L_q;
    J[I_0][I_0] = -R / v->motor_inductance_0;
    /* The energy accounts' rows: P_el = u . i, P_cu = R |i|^2, P_mech = T(i) speed (Eq 26). */
    const double reluctance = v->motor_pole_pairs * (L_d - L_q);
    J[E_COPPER][I_D] = 2.0 * R * x[I_D];
    J[E_COPPER][I_Q] = 2.0 * R * x[I_Q];
    J[E_COPPER][I_0] = 2.0 * R * x[I_0];
    J[E_MECHANICAL][I_D] = reluctance * x[I_Q] * s.speed;
    J[E_MECHANICAL][I_Q] = (v->motor_torque_constant + reluctance * x[I_D]) * s.speed;
    J[E_ELECTRICAL][I_D] = s.voltage_d;
    J[E_ELECTRICAL][I_Q] = s.voltage_q;
    J[E_ELECTRICAL][I_0] = s.voltage_0;
    if (v->inverter_model == INVERTER_SWITCHING) return; /* the voltages are the switches' */

    /* The current controllers: command = kp (i* - i) + int, zero slope while clamped; then
     * int' = ki (i* - i) + (ki / kp) (command - raw): clamped, the integrator tracks the limit. */
    const int axis_current[2] = {I_D, I_Q}, axis_integral[2] = {INT_CURRENT_D, INT_CURRENT_Q};
    const int axis_voltage[2] = {V_D, V_Q};
    const int free[2] = {s.command_d == s.command_d_raw, s.command_q == s.command_q_raw};
    const double inductance[2] = {L_d, L_q};
    for (int axis = 0; axis < 2; axis++) {
        const int i = axis_current[axis], integral = axis_integral[axis], u = axis_voltage[axis];
        const double d_command_d_current = free[axis] ? -kp : 0.0, d_command_d_integral = free[axis] ? 1.0 : 0.0;
        J[integral][i] = free[axis] ? -ki : 0.0;
        J[integral][integral] = free[axis] ? 0.0 : -ki / kp;
        if (v->inverter_model == INVERTER_IDEAL) { /* u = K_v command */
            J[i][i] += v->inverter_gain * d_command_d_current / inductance[axis];
            J[i][integral] = v->inverter_gain * d_command_d_integral / inductance[axis];
            J[E_ELECTRICAL][i] += x[i] * v->inverter_gain * d_command_d_current;
            J[E_ELECTRICAL][integral] = x[i] * v->inverter_gain * d_command_d_integral;
        } else { /* tau_v u' = K_v command - u */
            J[E_ELECTRICAL][u] = x[i];
            J[i][u] = 1.0 / inductance[axis];
            J[u][u] = -1.0 / v->inverter_time_constant;
            J[u][i] = v->inverter_gain * d_command_d_current / v->inverter_time_constant;
            J[u][integral] = v->inverter_gain * d_command_d_integral / v->inverter_time_constant;
        }
    }
}

/* Hysteresis comparators: phase k with its upper switch open (current falling or free) switches
 * when the error i_k* - i_k reaches +band; with it closed, when the error reaches -band. */
static void hysteresis_events(void *ctx, double t, const double *x, double *g) {
    const FmuInstance *fmu = (const FmuInstance *)ctx;
    const double band = fmu->s.v.inverter_hysteresis_band;
    Signals s;
    evaluate(fmu, t, x, &s, 1);
    for (int k = 0; k < 3; k++) {
        double error = s.phase_current_ref[k] - s.phase_current[k];
        g[k] = fmu->s.internal.switch_state[k] ? (-band - error) : (error - band);
    }
}

static void commutate(void *ctx, double t, const double *x, int phase) {
    FmuInstance *fmu = (FmuInstance *)ctx;
    (void)x;
    fmu->s.internal.switch_state[phase] = !fmu->s.internal.switch_state[phase];
    fmu->s.internal.switchings += 1;
    if (fmu->log_all)
        fmu_log(fmu, fmi2OK, "logEvents", "t = %.9g s: phase %c upper switch %s", t, 'a' + phase,
                fmu->s.internal.switch_state[phase] ? "on" : "off");
}

/* ---- solver.exponential: the linear part taken exactly ----
 * Between the limits the current loops (ACR), the inverter's lag and the winding (Eqs 24-25) are
 * linear with constant coefficients, x_s' = A x_s + ..., but for the speed's cross-coupling w_r L i,
 * the back-EMF w_r psi_r and the current reference the outer loops set: those, the outer loops and
 * the energy accounts are N(t, x) = f(t, x) - A x. ETDRK4 (Cox and Matthews 2002) takes e^{hA} and
 * its phi-functions exactly and N explicitly, so the step is bounded by the outer loops (500 rad/s)
 * and the cross-coupling (P w_m, about 400 rad/s), not by the inverter (10^4 1/s). */

/* A: the stiff block's constant part with neither current controller clamped (the entries of
 * stiff_jacobian without the speed's terms). */
static void linear_part(const ModelVariables *v, double *A) {
    memset(A, 0, sizeof(double) * N_STIFF * N_STIFF);
#define AT(i, j) A[(i) * N_STIFF + (j)]
    const int current[2] = {I_D, I_Q}, integral[2] = {INT_CURRENT_D, INT_CURRENT_Q}, voltage[2] = {V_D, V_Q};
    const double inductance[2] = {v->motor_inductance_d, v->motor_inductance_q};
    const double R = v->motor_resistance, kp = v->control_current_kp, ki = v->control_current_ki;
    const double K_v = v->inverter_gain, tau = v->inverter_time_constant;
    for (int axis = 0; axis < 2; axis++) {
        const int i = current[axis], c = integral[axis], u = voltage[axis];
        const double L = inductance[axis];
        AT(i, i) = -R / L;
        AT(c, i) = -ki;                          /* int' = ki (i* - i) */
        if (v->inverter_model == INVERTER_IDEAL) { /* u = K_v (kp (i* - i) + int) */
            AT(i, i) -= K_v * kp / L;
            AT(i, c) = K_v / L;
        } else { /* tau u' = K_v (kp (i* - i) + int) - u */
            AT(i, u) = 1.0 / L;
            AT(u, u) = -1.0 / tau;
            AT(u, i) = -K_v * kp / tau;
            AT(u, c) = K_v / tau;
        }
    }
    AT(I_0, I_0) = -R / v->motor_inductance_0;
#undef AT
}

/* The derivatives, and whether A is the linear part here: neither current controller clamped. */
static int rhs_linear(void *ctx, double t, const double *x, double *dxdt) {
    Signals s;
    derivatives((const FmuInstance *)ctx, t, x, dxdt, &s);
    return s.command_d == s.command_d_raw && s.command_q == s.command_q_raw;
}

fmi2Status model_do_step(FmuInstance *fmu, double h) {
    const int switching = fmu->s.v.inverter_model == INVERTER_SWITCHING;
    const OdeProblem problem = {MODEL_N_STATES, rhs, switching ? 3 : 0, hysteresis_events, commutate, N_STIFF,
                                stiff_jacobian};
    if (fmu->s.v.solver_exponential && !switching) {
        double A[N_STIFF * N_STIFF];
        linear_part(&fmu->s.v, A);
        return fmu_integrate_exponential(fmu, &problem, rhs_linear, A, h);
    }
    return fmu_integrate(fmu, &problem, fmu, h, switching ? fmu->s.v.inverter_max_step : 0.0);
}

/* ---- Model Exchange (fmi2_me.c): the same right-hand side ---- */

const char *model_exchange_refusal(const FmuInstance *fmu) {
    return fmu->s.v.inverter_model == INVERTER_SWITCHING
               ? "inverter.model = 3 (switching) has the hysteresis comparators' events, which this FMU does not give "
                 "as event indicators: take 1 (ideal) or 2 (averaged), or Co-Simulation"
               : NULL;
}

int model_derivatives(FmuInstance *fmu, double *dxdt) {
    rhs(fmu, fmu->s.time, fmu->s.x, dxdt);
    return 0;
}

fmi2Status model_completed_integrator_step(FmuInstance *fmu) {
    (void)fmu;
    return fmi2OK;
}

void model_initialize(FmuInstance *fmu) {
    const ModelVariables *v = &fmu->s.v;
    const double i_q0 = v->initial_current_q, u_q0 = v->motor_resistance * i_q0; /* at rest */
    memset(fmu->s.x, 0, sizeof fmu->s.x);
    memset(&fmu->s.internal, 0, sizeof fmu->s.internal);
    memset(&fmu->s.solver, 0, sizeof fmu->s.solver);
    fmu->s.x[I_Q] = i_q0;
    fmu->s.x[V_Q] = u_q0;
    fmu->s.x[INT_SPEED] = i_q0;
    fmu->s.x[INT_CURRENT_Q] = u_q0 / v->inverter_gain;
}

void model_compute_outputs(FmuInstance *fmu) {
    ModelVariables *v = &fmu->s.v;
    const double *x = fmu->s.x;
    Signals s;
    evaluate(fmu, fmu->s.time, x, &s, 1);
    v->torque = s.torque;
    v->current_d = x[I_D];
    v->current_q = x[I_Q];
    v->voltage_d = s.voltage_d;
    v->voltage_q = s.voltage_q;
    v->power_electrical = s.voltage_d * x[I_D] + s.voltage_q * x[I_Q] + s.voltage_0 * x[I_0];
    v->power_mechanical = s.torque * s.speed;
    v->power_copper_loss = v->motor_resistance * (x[I_D] * x[I_D] + x[I_Q] * x[I_Q] + x[I_0] * x[I_0]);
    v->energy_magnetic = 0.5 * (v->motor_inductance_d * x[I_D] * x[I_D] + v->motor_inductance_q * x[I_Q] * x[I_Q] +
                                v->motor_inductance_0 * x[I_0] * x[I_0]);
    v->energy_electrical = x[E_ELECTRICAL];
    v->energy_copper_loss = x[E_COPPER];
    v->energy_mechanical = x[E_MECHANICAL];
    v->current_a = s.phase_current[0];
    v->current_b = s.phase_current[1];
    v->current_c = s.phase_current[2];
    v->current_error_max = 0.0;
    for (int k = 0; k < 3; k++)
        v->current_error_max = fmax(v->current_error_max, fabs(s.phase_current_ref[k] - s.phase_current[k]));
    v->speed_ref = s.speed_ref;
    v->current_ref_q = s.current_ref_q;
    /* The interface Jacobian d torque / d speed over a step of a few current-loop time constants:
     * the speed loop moves i_q* by -Kp_w per rad/s while neither limit holds it, and the current
     * follows its reference (the ACR's zero cancels the winding's pole); the back-EMF K_m w (Eq 25)
     * pushes the current by -K_m / (K_v Kp_c + R) per rad/s at once, which the ACR's integrator
     * takes back only over L/R (10 ms). The torque moves by dT/di_q = P (psi_r + (L_d - L_q) i_d)
     * (Eq 26) per ampere. The hysteresis inverter holds the current at its reference; a clamped
     * voltage opens the loop, and the winding's L/R then answers more slowly than a step (left out). */
    const int speed_loop_free = v->control_mode != MODE_TORQUE && s.current_ref_q == s.current_ref_q_raw;
    const double d_current_ref = speed_loop_free ? -v->control_speed_kp : 0.0;
    double d_current;
    if (v->inverter_model == INVERTER_SWITCHING) {
        d_current = d_current_ref;
    } else if (s.command_q != s.command_q_raw) {
        d_current = 0.0;
    } else {
        d_current = d_current_ref - v->motor_torque_constant /
                                        (v->inverter_gain * v->control_current_kp + v->motor_resistance);
    }
    v->torque_speed_slope = (v->motor_torque_constant + v->motor_pole_pairs *
                             (v->motor_inductance_d - v->motor_inductance_q) * x[I_D]) * d_current;
    v->inverter_switchings = fmu->s.internal.switchings;
}

fmi2Status model_validate(FmuInstance *fmu) {
    const ModelVariables *v = &fmu->s.v;
    int errors = 0;
    if (!(fabs(v->control_current_d_ref) < v->limit_current))
        errors += fmu_reject(fmu, VR_control_current_d_ref, "|i_d*| must be below limit.current");
    if (!(fabs(v->initial_current_q) <= v->limit_current))
        errors += fmu_reject(fmu, VR_initial_current_q, "must not exceed limit.current");
    return errors ? fmi2Error : fmi2OK;
}
