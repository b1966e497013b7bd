/* linear_motor: one leg's linear-motor drive (Sumnu 2015, Section 4.3; control as in Section 5.3).
 *
 *   F_em = K_f i                                                            (Eq 4.28)
 *   V    = K_e v + R i + L di/dt                                            (Eq 4.30)
 *   f_f  = (f_c + (f_s - f_c) exp(-|v / v_s|^delta)) sgn(v) + f_v v         (Eq 4.30, friction)
 *   f_r  = A sin(w x + phi)                                                 (Eq 4.31)
 *   F    = F_em - B_l v - f_f - f_r        the net axial force on the leg; the forcer's mass m of
 *                                          Eq 4.29 moves with the leg and is part of the mechanics.
 * Control: PID on the leg length gives a force command (limited), plus force_ff; the current
 * command F/K_f (limited) is held by a PI current loop whose voltage is limited by the DC bus.
 * sgn(v) is smoothed as tanh(v / v_smooth). Power uses the factor K_f / K_e (the three-phase power
 * of this single-phase equivalent model), which makes electromagnetic and mechanical power agree.
 */
#include "fmu_common.h"

#include <string.h>

/* The states: first the current loop's (stiff: the Rosenbrock-W solver takes them implicitly),
 * then the position integrator and the energy accounts (slow: explicit). */
enum { CURRENT, INT_CURRENT, N_STIFF, INT_POSITION = N_STIFF, E_ELECTRICAL, E_COPPER, E_ELECTROMAGNETIC, E_LOSS,
       E_RIPPLE };
enum { MODE_POSITION = 1, MODE_FORCE = 2, MODE_VOLTAGE = 3 };

static const double PI = 3.14159265358979323846;

static double clamp(double value, double limit) {
    return value > limit ? limit : (value < -limit ? -limit : value);
}

typedef struct {
    double position, velocity, position_error, force_raw, force_command, current_ref, current;
    double voltage_raw, voltage, force_em, friction, damping, ripple, force;
} Signals;

static void evaluate(const FmuInstance *fmu, double t, const double *x, Signals *s) {
    const ModelVariables *v = &fmu->s.v;
    const double dt = t - fmu->s.input_time;
    s->velocity = fmu_input_at(fmu, VR_velocity, t);
    s->position = fmu_input_has_derivative(fmu, VR_position) ? fmu_input_at(fmu, VR_position, t)
                                                              : v->position + 0.5 * (v->velocity + s->velocity) * dt;
    const double force_ff = fmu_input_at(fmu, VR_force_ff, t);

    /* Position PID (Section 5.3), derivative on the velocity error. */
    s->position_error = fmu_input_at(fmu, VR_position_ref, t) - s->position;
    const double velocity_ref = v->control_velocity_ref_input ? fmu_input_at(fmu, VR_velocity_ref, t)
                                                              : fmu_input_rate_at(fmu, VR_position_ref, t);
    s->force_raw = force_ff;
    if (v->control_mode == MODE_POSITION)
        s->force_raw += v->control_position_kp * s->position_error + x[INT_POSITION] +
                        v->control_position_kd * (velocity_ref - s->velocity);
    s->force_command = clamp(s->force_raw, v->limit_force);
    s->current_ref = clamp(s->force_command / v->motor_force_constant, v->limit_current);

    /* Winding and current loop. */
    if (!v->effects_electrical) {
        s->current = s->current_ref; /* ideal force source */
        s->voltage_raw = s->voltage = v->motor_resistance * s->current + v->motor_back_emf_constant * s->velocity;
    } else {
        s->current = x[CURRENT];
        if (v->control_mode == MODE_VOLTAGE) {
            s->voltage_raw = fmu_input_at(fmu, VR_voltage_ref, t);
        } else {
            s->voltage_raw = v->control_current_kp * (s->current_ref - s->current) + x[INT_CURRENT];
        }
        s->voltage = clamp(s->voltage_raw, v->limit_voltage);
    }

    /* Forces on the leg (Eqs 4.28-4.31). */
    s->force_em = v->motor_force_constant * s->current;
    s->damping = v->motor_damping * s->velocity;
    s->friction = 0.0;
    if (v->effects_friction) {
        const double ratio = s->velocity / v->friction_stribeck_velocity; /* delta = 2 (Gaussian) is the usual case */
        const double stribeck = exp(-(v->friction_stribeck_exponent == 2.0 ? ratio * ratio
                                                                           : pow(fabs(ratio), v->friction_stribeck_exponent)));
        s->friction = (v->friction_coulomb + (v->friction_static - v->friction_coulomb) * stribeck) *
                          tanh(s->velocity / v->friction_smoothing_velocity) +
                      v->friction_viscous * s->velocity;
    }
    s->ripple = v->effects_ripple
                    ? v->ripple_amplitude * sin(2.0 * PI * s->position / v->ripple_period + v->ripple_phase)
                    : 0.0;
    s->force = s->force_em - s->damping - s->friction - s->ripple;
}

/* The derivatives at (t, x), and the signals there (which limits hold). */
static void derivatives(const FmuInstance *fmu, double t, const double *x, double *dxdt, Signals *signals) {
    const ModelVariables *v = &fmu->s.v;
    Signals s;
    evaluate(fmu, t, x, &s);
    *signals = s;
    const double power_scale = v->motor_force_constant / v->motor_back_emf_constant;
    memset(dxdt, 0, sizeof(double) * MODEL_N_STATES);
    if (v->effects_electrical) {
        dxdt[CURRENT] = (s.voltage - v->motor_back_emf_constant * s.velocity - v->motor_resistance * s.current) /
                        v->motor_inductance; /* Eq 4.30 */
        if (v->control_mode != MODE_VOLTAGE)
            dxdt[INT_CURRENT] = v->control_current_ki * (s.current_ref - s.current) +
                                (v->control_current_ki / v->control_current_kp) * (s.voltage - s.voltage_raw);
        dxdt[E_ELECTRICAL] = power_scale * s.voltage * s.current;
        dxdt[E_COPPER] = power_scale * v->motor_resistance * s.current * s.current;
    } else {
        dxdt[E_ELECTRICAL] = s.force_em * s.velocity;
    }
    if (v->control_mode == MODE_POSITION) {
        /* back-calculation on the force limit; frozen while the current limit holds it back */
        const int inner_saturated = (s.force_command / v->motor_force_constant - s.current_ref) * s.position_error > 0.0;
        dxdt[INT_POSITION] = inner_saturated ? 0.0
                                             : v->control_position_ki * s.position_error +
                                                   (v->control_position_ki / v->control_position_kp) *
                                                       (s.force_command - s.force_raw);
    }
    dxdt[E_ELECTROMAGNETIC] = s.force_em * s.velocity;
    dxdt[E_LOSS] = (s.damping + s.friction) * s.velocity;
    dxdt[E_RIPPLE] = s.ripple * s.velocity;
}

static void rhs(void *ctx, double t, const double *x, double *dxdt) {
    Signals s;
    derivatives((const FmuInstance *)ctx, t, x, dxdt, &s);
}

/* ---- solver.exponential (fmu/common/ode.c: ETDRK4) ----
 * While the voltage limit does not hold, the current loop and the winding (Eq 4.30 with the PI) are
 * linear with constant coefficients: i' = (kp (i* - i) + int - R i - K_e v) / L, int' = ki (i* - i).
 * A is their part in i and int; the current reference, the back-EMF and the rest are explicit. */
static void linear_part(const ModelVariables *v, double A[N_STIFF * N_STIFF]) {
    memset(A, 0, sizeof(double) * N_STIFF * N_STIFF);
    if (!v->effects_electrical) return; /* no winding: nothing stiff */
    const double L = v->motor_inductance;
    if (v->control_mode == MODE_VOLTAGE) {
        A[CURRENT * N_STIFF + CURRENT] = -v->motor_resistance / L;
        return;
    }
    A[CURRENT * N_STIFF + CURRENT] = -(v->control_current_kp + v->motor_resistance) / L;
    A[CURRENT * N_STIFF + INT_CURRENT] = 1.0 / L;
    A[INT_CURRENT * N_STIFF + CURRENT] = -v->control_current_ki;
}

static int rhs_linear(void *ctx, double t, const double *x, double *dxdt) {
    Signals s;
    derivatives((const FmuInstance *)ctx, t, x, dxdt, &s);
    return s.voltage == s.voltage_raw;
}

/* Warns once per excursion of the force command past the continuous force, at t. */
static void check_continuous_force(FmuInstance *fmu, double t) {
    Signals s;
    evaluate(fmu, t, fmu->s.x, &s);
    const int over = fabs(s.force_command) > fmu->s.v.motor_continuous_force;
    if (over && !fmu->s.internal.over_continuous_force)
        fmu_log(fmu, fmi2Warning, "logStatusWarning",
                "t = %.6f s: force command %.1f N exceeds the continuous force %.0f N (Table 4.2)",
                t, s.force_command, fmu->s.v.motor_continuous_force);
    fmu->s.internal.over_continuous_force = over;
}

fmi2Status model_do_step(FmuInstance *fmu, double h) {
    const OdeProblem problem = {MODEL_N_STATES, rhs, 0, NULL, NULL, N_STIFF, NULL};
    double A[N_STIFF * N_STIFF];
    linear_part(&fmu->s.v, A);
    if ((fmu->s.v.solver_exponential ? fmu_integrate_exponential(fmu, &problem, rhs_linear, A, h)
                                     : fmu_integrate(fmu, &problem, fmu, h, 0.0)) != fmi2OK)
        return fmi2Error;
    check_continuous_force(fmu, fmu->s.time + h);
    return fmi2OK;
}

/* ---- Model Exchange (fmi2_me.c): the same right-hand side, the same check after each step ---- */

const char *model_exchange_refusal(const FmuInstance *fmu) {
    (void)fmu;
    return NULL;
}

int model_derivatives(FmuInstance *fmu, double *dxdt) {
    rhs(fmu, fmu->s.time, fmu->s.x, dxdt);
    return 0;
}

fmi2Status model_completed_integrator_step(FmuInstance *fmu) {
    check_continuous_force(fmu, fmu->s.time);
    return fmi2OK;
}

void model_initialize(FmuInstance *fmu) {
    memset(fmu->s.x, 0, sizeof fmu->s.x);
    memset(&fmu->s.internal, 0, sizeof fmu->s.internal);
    memset(&fmu->s.solver, 0, sizeof fmu->s.solver);
}

void model_compute_outputs(FmuInstance *fmu) {
    ModelVariables *v = &fmu->s.v;
    const double *x = fmu->s.x;
    Signals s;
    evaluate(fmu, fmu->s.time, x, &s);
    const double power_scale = v->motor_force_constant / v->motor_back_emf_constant;
    v->force = s.force;
    v->force_electromagnetic = s.force_em;
    v->force_friction = s.friction + s.damping;
    v->force_ripple = s.ripple;
    v->force_ref = s.force_command;
    /* The interface Jacobian d force / d velocity over a step of a few current-loop time constants:
     * the PID's derivative term moves the current reference by -K_d / K_f per m/s while neither the
     * force nor the current limit holds it, and the current follows its reference; with the
     * winding, the back-EMF K_e v (Eq 4.30) pushes the current by -K_e / (Kp_c + R) per m/s at once,
     * which the current PI's integrator takes back only later; a clamped voltage (or voltage mode)
     * opens the loop, and the winding's L/R then answers more slowly than a step (left out). Then
     * the damping and viscous friction; the smoothed Coulomb and Stribeck friction are left out
     * (their slope at rest is the smoothing's, far stiffer than the mechanics' step could take). */
    const int pid_free = v->control_mode == MODE_POSITION && s.force_command == s.force_raw &&
                         fabs(s.force_command / v->motor_force_constant) <= v->limit_current;
    const double d_current_ref = pid_free ? -v->control_position_kd / v->motor_force_constant : 0.0;
    double d_current = d_current_ref;
    if (v->effects_electrical)
        d_current = (v->control_mode == MODE_VOLTAGE || s.voltage != s.voltage_raw)
                        ? 0.0
                        : d_current_ref - v->motor_back_emf_constant / (v->control_current_kp + v->motor_resistance);
    v->force_velocity_slope = v->motor_force_constant * d_current - v->motor_damping -
                              (v->effects_friction ? v->friction_viscous : 0.0);
    v->current = s.current;
    v->voltage = s.voltage;
    v->power_electrical = v->effects_electrical ? power_scale * s.voltage * s.current : s.force_em * s.velocity;
    v->power_mechanical = s.force * s.velocity;
    v->energy_electrical = x[E_ELECTRICAL];
    v->energy_copper_loss = x[E_COPPER];
    v->energy_magnetic = v->effects_electrical ? 0.5 * power_scale * v->motor_inductance * s.current * s.current : 0.0;
    v->energy_electromagnetic = x[E_ELECTROMAGNETIC];
    v->energy_mechanical_loss = x[E_LOSS];
    v->energy_ripple = x[E_RIPPLE];
}

fmi2Status model_validate(FmuInstance *fmu) {
    const ModelVariables *v = &fmu->s.v;
    int errors = 0;
    if (v->friction_static < v->friction_coulomb)
        errors += fmu_reject(fmu, VR_friction_static, "must not be below friction.coulomb (Stribeck: f_s >= f_c)");
    return errors ? fmi2Error : fmi2OK;
}
