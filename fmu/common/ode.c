/* Internal ODE solvers: fixed-step RK4, adaptive Dormand-Prince 5(4) and the L-stable
 * Rosenbrock-W method ROS34PW2 (fixed or adaptive step), with state events. See ode.h for the
 * contract. */
#include "ode.h"

#include <float.h>
#include <math.h>
#include <string.h>

/* Dormand & Prince (1980), the RK5(4)7M pair. */
static const double C2 = 1.0 / 5, C3 = 3.0 / 10, C4 = 4.0 / 5, C5 = 8.0 / 9;
static const double A21 = 1.0 / 5;
static const double A31 = 3.0 / 40, A32 = 9.0 / 40;
static const double A41 = 44.0 / 45, A42 = -56.0 / 15, A43 = 32.0 / 9;
static const double A51 = 19372.0 / 6561, A52 = -25360.0 / 2187, A53 = 64448.0 / 6561,
                    A54 = -212.0 / 729;
static const double A61 = 9017.0 / 3168, A62 = -355.0 / 33, A63 = 46732.0 / 5247,
                    A64 = 49.0 / 176, A65 = -5103.0 / 18656;
static const double B1 = 35.0 / 384, B3 = 500.0 / 1113, B4 = 125.0 / 192, B5 = -2187.0 / 6784,
                    B6 = 11.0 / 84;
/* Error weights: 5th-order minus embedded 4th-order solution. */
static const double E1 = 71.0 / 57600, E3 = -71.0 / 16695, E4 = 71.0 / 1920,
                    E5 = -17253.0 / 339200, E6 = 22.0 / 525, E7 = -1.0 / 40;

/* Rang & Angermann (2005), ROS34PW2: a 4-stage Rosenbrock-W method of order 3 with an embedded
 * solution of order 2, L-stable and stiffly accurate (b_i = alpha_4i + gamma_4i); as a W-method it
 * keeps order 3 with an approximate (here: lagged) Jacobian (tests/models/test_ode.py). Stage i of
 * a step h from (t, y), with gamma_i = sum_j<=i gamma_ij and alpha_i = sum_j<i alpha_ij:
 *   (I - h gamma J) k_i = h f(t + alpha_i h, y + sum_j<i alpha_ij k_j) + h J sum_j<i gamma_ij k_j
 *                         + gamma_i h^2 f_t,
 *   y_new = y + sum_i b_i k_i,   error estimate sum_i (b_i - b_hat_i) k_i. */
#define RW_STAGES 4
static const double RW_GAMMA = 0.435866521508459;
static const double RW_ALPHA[RW_STAGES][RW_STAGES - 1] = {
    {0.0, 0.0, 0.0},
    {0.87173304301691801, 0.0, 0.0},
    {0.84457060015369423, -0.11299064236484185, 0.0},
    {0.0, 0.0, 1.0}};
static const double RW_GAMMA_BELOW[RW_STAGES][RW_STAGES - 1] = {
    {0.0, 0.0, 0.0},
    {-0.87173304301691801, 0.0, 0.0},
    {-0.90338057013044082, 0.054180672388095326, 0.0},
    {0.24212380706095346, -1.2232505839045147, 0.54526025533510214}};
static const double RW_B[RW_STAGES] = {0.24212380706095346, -1.2232505839045147, 1.5452602553351020,
                                       0.435866521508459};
static const double RW_B_HAT[RW_STAGES] = {0.37810903145819369, -0.096042292212423178, 0.5,
                                           0.21793326075422950};

/* The linearisation a Rosenbrock-W step uses: J ~ df/dx in the columns of the leading, stiff states
 * (the model's, or by forward differences; the other columns zero, so the other states are
 * treated explicitly) and f_t ~ df/dt (forward difference), taken at (t, x) once per call of
 * ode_integrate and again after every event (a W-method keeps its order with any such matrix, and
 * with a lagged one); the LU factors of I - h gamma J's stiff block for the last h. */
typedef struct {
    double jacobian[ODE_MAX_STATES][ODE_MAX_STATES], f_t[ODE_MAX_STATES];
    double t, x[ODE_MAX_STATES], f[ODE_MAX_STATES]; /* where it was taken, and f there */
    double lu[ODE_MAX_STATES][ODE_MAX_STATES], lu_h, inverse_pivot[ODE_MAX_STATES]; /* 1 / U_kk */
    int pivot[ODE_MAX_STATES], taken, factored;
    double rhs_calls; /* evaluations since the solver last counted them */
} Linearization;

static int stiff_states(const OdeProblem *p) { return p->n_stiff > 0 ? p->n_stiff : p->n_states; }

static void linearize(const OdeSolver *s, const OdeProblem *p, void *ctx, double t, const double *x,
                      Linearization *lin) {
    const int n = p->n_states, m = stiff_states(p);
    double y[ODE_MAX_STATES], f_perturbed[ODE_MAX_STATES];
    lin->t = t;
    memcpy(lin->x, x, sizeof(double) * (size_t)n);
    p->rhs(ctx, t, x, lin->f);
    if (p->jacobian) {
        for (int i = 0; i < n; i++)
            for (int j = 0; j < m; j++) lin->jacobian[i][j] = 0.0;
        p->jacobian(ctx, t, x, lin->jacobian);
    } else {
        const double scale_floor = s->atol / s->rtol; /* below it a state counts as absolutely small */
        memcpy(y, x, sizeof(double) * (size_t)n);
        for (int j = 0; j < m; j++) {
            const double delta = sqrt(DBL_EPSILON) * fmax(fabs(x[j]), scale_floor);
            y[j] = x[j] + delta;
            p->rhs(ctx, t, y, f_perturbed);
            const double actual = y[j] - x[j]; /* the increment as represented */
            for (int i = 0; i < n; i++) lin->jacobian[i][j] = (f_perturbed[i] - lin->f[i]) / actual;
            y[j] = x[j];
        }
        lin->rhs_calls += m;
    }
    const double dt = sqrt(DBL_EPSILON) * fmax(fabs(t), s->step);
    p->rhs(ctx, t + dt, x, f_perturbed);
    const double actual_dt = (t + dt) - t;
    for (int i = 0; i < n; i++) lin->f_t[i] = (f_perturbed[i] - lin->f[i]) / actual_dt;
    lin->taken = 1;
    lin->factored = 0;
    lin->rhs_calls += 2;
}

/* LU factors (partial pivoting) of the stiff block of I - h gamma J, in place; 0 if singular. */
static int factor(int m, Linearization *lin, double h) {
    for (int i = 0; i < m; i++)
        for (int j = 0; j < m; j++) lin->lu[i][j] = (i == j ? 1.0 : 0.0) - h * RW_GAMMA * lin->jacobian[i][j];
    for (int k = 0; k < m; k++) {
        int best = k;
        for (int i = k + 1; i < m; i++)
            if (fabs(lin->lu[i][k]) > fabs(lin->lu[best][k])) best = i;
        lin->pivot[k] = best;
        if (!(fabs(lin->lu[best][k]) > 0.0)) return 0;
        if (best != k) /* the columns from k on: the multipliers stay where they were made (LINPACK) */
            for (int j = k; j < m; j++) {
                double swap = lin->lu[k][j];
                lin->lu[k][j] = lin->lu[best][j];
                lin->lu[best][j] = swap;
            }
        lin->inverse_pivot[k] = 1.0 / lin->lu[k][k]; /* the solves multiply */
        for (int i = k + 1; i < m; i++) {
            double multiplier = (lin->lu[i][k] *= lin->inverse_pivot[k]);
            if (multiplier != 0.0)
                for (int j = k + 1; j < m; j++) lin->lu[i][j] -= multiplier * lin->lu[k][j];
        }
    }
    lin->lu_h = h;
    lin->factored = 1;
    return 1;
}

/* Solves (I - h gamma J) z = b in place. J's columns beyond the stiff block are zero, so the matrix
 * is block lower triangular, [I - h gamma A, 0; -h gamma B, I]: the stiff block by its factors, then
 * the other rows by substitution, z_rest = b_rest + h gamma B z_stiff. */
static void solve(int n, int m, const Linearization *lin, double *b) {
    for (int k = 0; k < m; k++) {
        int r = lin->pivot[k];
        if (r != k) { double swap = b[k]; b[k] = b[r]; b[r] = swap; }
        for (int i = k + 1; i < m; i++) b[i] -= lin->lu[i][k] * b[k];
    }
    for (int i = m - 1; i >= 0; i--) {
        double sum = b[i];
        for (int j = i + 1; j < m; j++) sum -= lin->lu[i][j] * b[j];
        b[i] = sum * lin->inverse_pivot[i];
    }
    for (int i = m; i < n; i++) {
        double sum = 0.0;
        for (int j = 0; j < m; j++) sum += lin->jacobian[i][j] * b[j];
        b[i] += lin->lu_h * RW_GAMMA * sum;
    }
}

/* One ROS34PW2 step; returns the scaled error norm (HUGE_VAL, and x_new NaN, if I - h gamma J is
 * singular). */
static double rosenbrock_step(const OdeSolver *s, const OdeProblem *p, void *ctx, Linearization *lin,
                              double t, const double *x, double h, double *x_new) {
    const int n = p->n_states, m = stiff_states(p);
    double k[RW_STAGES][ODE_MAX_STATES], y[ODE_MAX_STATES], f[ODE_MAX_STATES], coupled[ODE_MAX_STATES];
    if (!(lin->factored && lin->lu_h == h) && !factor(m, lin, h)) {
        for (int i = 0; i < n; i++) x_new[i] = NAN; /* singular: no step */
        return HUGE_VAL;
    }
    const int at_linearization = lin->t == t && memcmp(lin->x, x, sizeof(double) * (size_t)n) == 0;
    for (int stage = 0; stage < RW_STAGES; stage++) {
        double alpha = 0.0, gamma = RW_GAMMA;
        for (int i = 0; i < n; i++) { y[i] = x[i]; coupled[i] = 0.0; }
        for (int j = 0; j < stage; j++) {
            alpha += RW_ALPHA[stage][j];
            gamma += RW_GAMMA_BELOW[stage][j];
            for (int i = 0; i < n; i++) {
                y[i] += RW_ALPHA[stage][j] * k[j][i];
                coupled[i] += RW_GAMMA_BELOW[stage][j] * k[j][i];
            }
        }
        if (stage == 0 && at_linearization) {
            memcpy(f, lin->f, sizeof(double) * (size_t)n);
        } else {
            p->rhs(ctx, t + alpha * h, y, f);
            lin->rhs_calls += 1;
        }
        for (int i = 0; i < n; i++) {
            double j_coupled = 0.0;
            if (stage > 0)
                for (int j = 0; j < m; j++) j_coupled += lin->jacobian[i][j] * coupled[j];
            k[stage][i] = h * (f[i] + j_coupled) + gamma * h * h * lin->f_t[i];
        }
        solve(n, m, lin, k[stage]);
    }
    double sum = 0.0;
    for (int i = 0; i < n; i++) {
        double step = 0.0, err = 0.0;
        for (int stage = 0; stage < RW_STAGES; stage++) {
            step += RW_B[stage] * k[stage][i];
            err += (RW_B[stage] - RW_B_HAT[stage]) * k[stage][i];
        }
        x_new[i] = x[i] + step;
        double scale = s->atol + s->rtol * fmax(fabs(x[i]), fabs(x_new[i]));
        sum += (err / scale) * (err / scale);
    }
    double norm = sqrt(sum / n);
    return isfinite(norm) ? norm : HUGE_VAL;
}

const char *ode_result_text(OdeResult r) {
    switch (r) {
    case ODE_OK: return "ok";
    case ODE_NONFINITE: return "a state or derivative became NaN or infinite";
    case ODE_STEP_TOO_SMALL: return "the adaptive step fell below the round-off floor";
    case ODE_BAD_SETTINGS: return "invalid solver settings";
    case ODE_EVENT_LOOP: return "an event handler did not clear its event";
    case ODE_TOO_MUCH_WORK: return "more than 200000 internal steps in one communication step (a shorter "
                                   "communication step or a longer solver.step is needed)";
    }
    return "unknown";
}

static int all_finite(int n, const double *x) {
    for (int i = 0; i < n; i++)
        if (!isfinite(x[i])) return 0;
    return 1;
}

/* One step of length h from (t, x) into x_new. Returns the scaled error norm for the adaptive
 * methods (0 for the fixed-step explicit ones, RK4 and Heun). */
static double one_step(const OdeSolver *s, const OdeProblem *p, void *ctx, Linearization *lin, double t,
                       const double *x, double h, double *x_new) {
    const int n = p->n_states;
    double k1[ODE_MAX_STATES], k2[ODE_MAX_STATES], k3[ODE_MAX_STATES], k4[ODE_MAX_STATES],
        k5[ODE_MAX_STATES], k6[ODE_MAX_STATES], k7[ODE_MAX_STATES], y[ODE_MAX_STATES];
    int i;

    if (s->method == ODE_ROSENBROCK || s->method == ODE_ROSENBROCK_ADAPTIVE)
        return rosenbrock_step(s, p, ctx, lin, t, x, h, x_new);

    if (s->method == ODE_HEUN) {
        p->rhs(ctx, t, x, k1);
        for (i = 0; i < n; i++) y[i] = x[i] + h * k1[i];
        p->rhs(ctx, t + h, y, k2);
        for (i = 0; i < n; i++) x_new[i] = x[i] + 0.5 * h * (k1[i] + k2[i]);
        return 0.0;
    }
    if (s->method == ODE_RK4) {
        p->rhs(ctx, t, x, k1);
        for (i = 0; i < n; i++) y[i] = x[i] + 0.5 * h * k1[i];
        p->rhs(ctx, t + 0.5 * h, y, k2);
        for (i = 0; i < n; i++) y[i] = x[i] + 0.5 * h * k2[i];
        p->rhs(ctx, t + 0.5 * h, y, k3);
        for (i = 0; i < n; i++) y[i] = x[i] + h * k3[i];
        p->rhs(ctx, t + h, y, k4);
        for (i = 0; i < n; i++) x_new[i] = x[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
        return 0.0;
    }

    p->rhs(ctx, t, x, k1);
    for (i = 0; i < n; i++) y[i] = x[i] + h * A21 * k1[i];
    p->rhs(ctx, t + C2 * h, y, k2);
    for (i = 0; i < n; i++) y[i] = x[i] + h * (A31 * k1[i] + A32 * k2[i]);
    p->rhs(ctx, t + C3 * h, y, k3);
    for (i = 0; i < n; i++) y[i] = x[i] + h * (A41 * k1[i] + A42 * k2[i] + A43 * k3[i]);
    p->rhs(ctx, t + C4 * h, y, k4);
    for (i = 0; i < n; i++)
        y[i] = x[i] + h * (A51 * k1[i] + A52 * k2[i] + A53 * k3[i] + A54 * k4[i]);
    p->rhs(ctx, t + C5 * h, y, k5);
    for (i = 0; i < n; i++)
        y[i] = x[i] + h * (A61 * k1[i] + A62 * k2[i] + A63 * k3[i] + A64 * k4[i] + A65 * k5[i]);
    p->rhs(ctx, t + h, y, k6);
    for (i = 0; i < n; i++)
        x_new[i] = x[i] + h * (B1 * k1[i] + B3 * k3[i] + B4 * k4[i] + B5 * k5[i] + B6 * k6[i]);
    p->rhs(ctx, t + h, x_new, k7);

    double sum = 0.0;
    for (i = 0; i < n; i++) {
        double err = h * (E1 * k1[i] + E3 * k3[i] + E4 * k4[i] + E5 * k5[i] + E6 * k6[i] + E7 * k7[i]);
        double scale = s->atol + s->rtol * fmax(fabs(x[i]), fabs(x_new[i]));
        sum += (err / scale) * (err / scale);
    }
    double norm = sqrt(sum / n);
    return isfinite(norm) ? norm : HUGE_VAL;
}

/* Index of the first event component that went from negative to non-negative, the one with the
 * earliest linear estimate of its crossing; -1 if none. */
static int first_crossing(int m, const double *g_a, const double *g_b) {
    int best = -1;
    double best_fraction = 2.0;
    for (int k = 0; k < m; k++) {
        if (g_a[k] < 0.0 && g_b[k] >= 0.0) {
            double fraction = g_a[k] / (g_a[k] - g_b[k]);
            if (fraction < best_fraction) { best_fraction = fraction; best = k; }
        }
    }
    return best;
}

/* The step [t, t+h] crossed event k. Finds the shortest step length b such that some event
 * component is >= 0 at the end of a step of length b, to within a small fraction of h, by the
 * Illinois method; writes the state there to x_event. Returns the crossing component. */
static int locate_event(OdeSolver *s, const OdeProblem *p, void *ctx, Linearization *lin, double t, const double *x,
                        const double *g_start, double h, double *x_event, double *h_event,
                        int k, const double *g_end) {
    const int n = p->n_states, m = p->n_events;
    double x_trial[ODE_MAX_STATES], g_trial[ODE_MAX_EVENTS];
    double a = 0.0, b = h, ga = g_start[k], gb = g_end[k];
    const double tolerance = 1e-7 * h;
    int side = 0;

    one_step(s, p, ctx, lin, t, x, h, x_event); /* b starts at the full step */
    for (int iteration = 0; iteration < 60 && b - a > tolerance; iteration++) {
        double c = (a * gb - b * ga) / (gb - ga);
        if (!(c > a && c < b)) c = 0.5 * (a + b);
        one_step(s, p, ctx, lin, t, x, c, x_trial);
        p->events(ctx, t + c, x_trial, g_trial);
        int other = first_crossing(m, g_start, g_trial);
        if (other >= 0) { /* some component has crossed by c: the event is in [a, c] */
            if (other != k) { k = other; ga = g_start[k]; side = 0; }
            b = c; gb = g_trial[k];
            memcpy(x_event, x_trial, sizeof(double) * (size_t)n);
            if (side == +1) ga *= 0.5;
            side = +1;
        } else {
            a = c; ga = g_trial[k];
            if (side == -1) gb *= 0.5;
            side = -1;
        }
    }
    *h_event = b;
    return k;
}

/* Lets on_event handle the event that was just located (`located`, or -1 for none) and then every
 * event function that is positive at (t, x). A function left exactly at zero by its handler counts
 * as cleared (it has to go negative and come back to fire again). */
static OdeResult handle_events_now(OdeSolver *s, const OdeProblem *p, void *ctx, double t,
                                   const double *x, double *g, int located) {
    if (located >= 0) {
        p->on_event(ctx, t, x, located);
        s->events += 1;
    }
    for (int round = 0; round < 2 * ODE_MAX_EVENTS + 2; round++) {
        p->events(ctx, t, x, g);
        int pending = -1;
        for (int k = 0; k < p->n_events && pending < 0; k++)
            if (g[k] > 0.0) pending = k;
        if (pending < 0) return ODE_OK;
        p->on_event(ctx, t, x, pending);
        s->events += 1;
    }
    return ODE_EVENT_LOOP;
}

/* Are the solver's settings and the problem's sizes ones ode_integrate can take? */
static int settings_valid(const OdeSolver *s, const OdeProblem *p) {
    const int n = p->n_states, m = p->n_events;
    return n >= 1 && n <= ODE_MAX_STATES && m >= 0 && m <= ODE_MAX_EVENTS && s->step > 0.0 && p->n_stiff >= 0 &&
           p->n_stiff <= n && s->method >= ODE_RK4 && s->method <= ODE_HEUN &&
           (s->method == ODE_RK4 || s->method == ODE_HEUN || (s->rtol > 0.0 && s->atol > 0.0));
}

/* The next step with `remaining` to go: fixed-step methods split it into equal steps of at most
 * s->step; adaptive ones take their planned step (a first one of 1 % of the span), cut to the end.
 * reaches_end: the step ends the span. */
static double next_step(const OdeSolver *s, int adaptive, double remaining, int *reaches_end) {
    if (!adaptive) {
        double steps = ceil(remaining / s->step - 1e-9);
        *reaches_end = steps <= 1.0;
        return remaining / (steps < 1.0 ? 1.0 : steps);
    }
    double planned = s->h_next > 0.0 ? fmin(s->h_next, s->step) : fmin(s->step, 1e-2 * remaining + 1e-9);
    *reaches_end = planned >= remaining;
    return *reaches_end ? remaining : planned;
}

OdeResult ode_integrate(OdeSolver *s, const OdeProblem *p, void *ctx, double *x, double t0,
                        double t1, double *t_reached) {
    const int n = p->n_states, m = p->n_events;
    double x_new[ODE_MAX_STATES], x_event[ODE_MAX_STATES];
    double g_start[ODE_MAX_EVENTS], g_end[ODE_MAX_EVENTS];
    double t = t0;
    OdeResult result = ODE_OK;

    if (t_reached) *t_reached = t0;
    if (!settings_valid(s, p)) return ODE_BAD_SETTINGS;
    const int rosenbrock = s->method == ODE_ROSENBROCK || s->method == ODE_ROSENBROCK_ADAPTIVE;
    const int adaptive = s->method == ODE_DOPRI5 || s->method == ODE_ROSENBROCK_ADAPTIVE;
    /* The error estimates are of order 5 (Dormand-Prince) and 3 (ROS34PW2) in h. */
    const double error_exponent = rosenbrock ? -1.0 / 3.0 : -0.2;
    Linearization lin; /* ROS34PW2 only */
    lin.taken = lin.factored = 0;
    lin.rhs_calls = 0.0;
    if (m > 0 && (result = handle_events_now(s, p, ctx, t, x, g_start, -1)) != ODE_OK) return result;

    const double t_eps = 1e-13 * fmax(1.0, fabs(t1));
    if (!isfinite(t0) || !isfinite(t1) || (t1 - t0) / s->step > ODE_MAX_STEPS) return ODE_TOO_MUCH_WORK;
    long work = 0;
    while (t1 - t > t_eps) {
        if (++work > ODE_MAX_STEPS) { result = ODE_TOO_MUCH_WORK; break; }
        int reaches_end;
        const double h = next_step(s, adaptive, t1 - t, &reaches_end);

        if (rosenbrock && !lin.taken) linearize(s, p, ctx, t, x, &lin);
        double error = one_step(s, p, ctx, &lin, t, x, h, x_new);
        s->rhs_calls += s->method == ODE_RK4 ? 4 : s->method == ODE_HEUN ? 2 : rosenbrock ? lin.rhs_calls : 7;
        lin.rhs_calls = 0;
        if (adaptive) {
            if (error > 1.0 || !all_finite(n, x_new)) {
                s->rejected += 1;
                s->h_next = h * (isfinite(error) ? fmax(0.2, 0.9 * pow(error, error_exponent)) : 0.2);
                if (s->h_next < 1e-14 * fmax(1.0, fabs(t))) { result = ODE_STEP_TOO_SMALL; break; }
                /* A rejection may mean the lagged Jacobian no longer fits: retake it here. */
                if (rosenbrock && (lin.t != t || memcmp(lin.x, x, sizeof(double) * (size_t)n) != 0))
                    lin.taken = 0;
                continue;
            }
            double factor = error > 0.0 ? fmin(5.0, fmax(0.2, 0.9 * pow(error, error_exponent))) : 5.0;
            double proposal = fmin(s->step, h * factor);
            /* A step cut short to meet t1 says little about the next one; keep the plan. */
            s->h_next = (reaches_end && s->h_next > proposal) ? s->h_next : proposal;
        } else if (!all_finite(n, x_new)) {
            result = ODE_NONFINITE;
            break;
        }

        if (m > 0) {
            p->events(ctx, t + h, x_new, g_end);
            int k = first_crossing(m, g_start, g_end);
            if (k >= 0) {
                double h_event;
                k = locate_event(s, p, ctx, &lin, t, x, g_start, h, x_event, &h_event, k, g_end);
                t = (h_event >= h) ? t + h : t + h_event;
                memcpy(x, x_event, sizeof(double) * (size_t)n);
                s->steps += 1;
                if ((result = handle_events_now(s, p, ctx, t, x, g_start, k)) != ODE_OK) break;
                lin.taken = 0; /* the event changed the model */
                continue;
            }
            memcpy(g_start, g_end, sizeof(double) * (size_t)m);
        }
        memcpy(x, x_new, sizeof(double) * (size_t)n);
        t = reaches_end ? t1 : t + h;
        s->steps += 1;
    }
    if (result == ODE_OK) t = t1;
    if (t_reached) *t_reached = t;
    return result;
}

/* ---- phi-functions of a small matrix (exponential integrators) ---- */

/* out = a b for n x n row-major matrices (out may not alias a or b). */
static void mat_mul(int n, const double *a, const double *b, double *out) {
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++) {
            double sum = 0.0;
            for (int k = 0; k < n; k++) sum += a[i * n + k] * b[k * n + j];
            out[i * n + j] = sum;
        }
}

/* phi_0..phi_count of Z = hA by scaling and squaring on the n x n matrices themselves (Skaflestad
 * and Wright 2009): Z / 2^s with a 1-norm at most 1/2, where phi_k(Z) = sum_j Z^j / (j + k)! to
 * round-off (17 terms bound the remainder by 2^-17 / 17!), then s times
 * phi_k(2Z) = 2^-k (phi_0(Z) phi_k(Z) + sum_{j=1..k} phi_j(Z) / (k - j)!). */
void ode_phi_functions(int n, const double *a, double h, int count, double *phi) {
    enum { MAX = ODE_PHI_MAX * ODE_PHI_MAX, TERMS = 17 };
    const int nn = n * n;
    double norm = 0.0, z[MAX], power[MAX], next[MAX], old[4 * MAX];
    for (int j = 0; j < n; j++) {
        double column = 0.0;
        for (int i = 0; i < n; i++) column += fabs(h * a[i * n + j]);
        norm = fmax(norm, column);
    }
    if (!(norm <= 0x1p500)) { /* no exponential (NaN, or past what 500 squarings hold): NaN, which the
                                 caller's steps refuse */
        for (int i = 0; i < (count + 1) * nn; i++) phi[i] = NAN;
        return;
    }
    const int s = norm > 0.5 ? (int)ceil(log2(norm / 0.5)) : 0;
    const double scale = ldexp(h, -s);
    double factorial[TERMS + 4]; /* 1 / m! */
    factorial[0] = 1.0;
    for (int m = 1; m < TERMS + 4; m++) factorial[m] = factorial[m - 1] / m;
    for (int i = 0; i < nn; i++) {
        z[i] = a[i] * scale;
        power[i] = (i % (n + 1) == 0) ? 1.0 : 0.0; /* the identity */
        for (int k = 0; k <= count; k++) phi[k * nn + i] = power[i] * factorial[k];
    }
    for (int j = 1; j <= TERMS; j++) {
        mat_mul(n, power, z, next);
        memcpy(power, next, sizeof(double) * (size_t)nn);
        for (int k = 0; k <= count; k++)
            for (int i = 0; i < nn; i++) phi[k * nn + i] += power[i] * factorial[j + k];
    }
    for (int r = 0; r < s; r++) {
        memcpy(old, phi, sizeof(double) * (size_t)((count + 1) * nn));
        for (int k = 0; k <= count; k++) {
            double *out = phi + k * nn;
            mat_mul(n, old, old + k * nn, out);
            for (int j = 1; j <= k; j++)
                for (int i = 0; i < nn; i++) out[i] += old[j * nn + i] * factorial[k - j];
            const double half = ldexp(1.0, -k);
            for (int i = 0; i < nn; i++) out[i] *= half;
        }
    }
}

/* ---- the exponential integrator ---- */

static const OdeExponential *exponential_for(OdeExponentialCache *cache, int m, const double *a, double h) {
    for (int k = 0; k < ODE_EXPONENTIAL_KEPT; k++)
        if (cache->entry[k].h == h && memcmp(a, cache->entry[k].a, sizeof(double) * (size_t)(m * m)) == 0)
            return &cache->entry[k];
    OdeExponential *e = &cache->entry[cache->next];
    cache->next = (cache->next + 1) % ODE_EXPONENTIAL_KEPT;
    const int mm = m * m;
    double phi[4 * ODE_PHI_MAX * ODE_PHI_MAX], half[2 * ODE_PHI_MAX * ODE_PHI_MAX];
    ode_phi_functions(m, a, h, 3, phi);
    ode_phi_functions(m, a, 0.5 * h, 1, half);
    for (int k = 0; k < mm; k++) {
        const int c = (k % m) * m + k / m; /* row k / m, column k % m, stored by column */
        const double p1 = phi[mm + k], p2 = phi[2 * mm + k], p3 = phi[3 * mm + k];
        e->e[c] = phi[k];
        e->f1[c] = h * (p1 - 3.0 * p2 + 4.0 * p3);
        e->f2[c] = h * (p2 - 2.0 * p3);
        e->f3[c] = h * (-p2 + 4.0 * p3);
        e->e2[c] = half[k];
        e->q[c] = 0.5 * h * half[mm + k];
        e->a_by_column[c] = a[k];
    }
    memcpy(e->a, a, sizeof(double) * (size_t)mm);
    e->h = h;
    return e;
}

/* out = sum_k M_k v_k on the m stiff states, sum_k s_k v_k on the others (where A = 0 the matrices
 * are the scalars s_k). */
static void combine(int n, int m, int terms, const double *const *matrix, const double *scalar,
                    const double *const *vector, double *out) {
    for (int i = 0; i < n; i++) out[i] = 0.0;
    for (int k = 0; k < terms; k++) {
        const double *restrict mk = matrix[k], *restrict vk = vector[k];
        double sum[ODE_PHI_MAX];
        for (int i = 0; i < m; i++) sum[i] = 0.0;
        for (int j = 0; j < m; j++) /* down column j: each row's sum in a dot product's order */
            for (int i = 0; i < m; i++) sum[i] += mk[j * m + i] * vk[j];
        for (int i = 0; i < m; i++) out[i] += sum[i];
        for (int i = m; i < n; i++) out[i] += scalar[k] * vk[i];
    }
}

/* N = f - A x at (t, x), A stored by column; 0 where A is not the linear part there. */
static int nonlinear(OdeRhsLinear rhs_linear, void *ctx, int m, const double *a_by_column, double t,
                     const double *x, double *n) {
    const int holds = rhs_linear(ctx, t, x, n);
    for (int j = 0; j < m; j++)
        for (int i = 0; i < m; i++) n[i] -= a_by_column[j * m + i] * x[j];
    return holds;
}

/* One ETDRK4 step; 0 (x untouched) where the linear part did not hold at a stage. */
static int exponential_step(const OdeExponential *e, int n, int m, OdeRhsLinear rhs_linear, void *ctx, double t,
                            double h, double *x) {
    double nx[ODE_MAX_STATES], a[ODE_MAX_STATES], na[ODE_MAX_STATES], b[ODE_MAX_STATES], nb[ODE_MAX_STATES];
    double c[ODE_MAX_STATES], nc[ODE_MAX_STATES], mix[ODE_MAX_STATES], next[ODE_MAX_STATES];
    const double half[2] = {1.0, 0.5 * h};
    if (!nonlinear(rhs_linear, ctx, m, e->a_by_column, t, x, nx)) return 0;
    combine(n, m, 2, (const double *[]){e->e2, e->q}, half, (const double *[]){x, nx}, a);
    if (!nonlinear(rhs_linear, ctx, m, e->a_by_column, t + 0.5 * h, a, na)) return 0;
    combine(n, m, 2, (const double *[]){e->e2, e->q}, half, (const double *[]){x, na}, b);
    if (!nonlinear(rhs_linear, ctx, m, e->a_by_column, t + 0.5 * h, b, nb)) return 0;
    for (int i = 0; i < n; i++) mix[i] = 2.0 * nb[i] - nx[i];
    combine(n, m, 2, (const double *[]){e->e2, e->q}, half, (const double *[]){a, mix}, c);
    if (!nonlinear(rhs_linear, ctx, m, e->a_by_column, t + h, c, nc)) return 0;
    for (int i = 0; i < n; i++) mix[i] = 2.0 * (na[i] + nb[i]);
    /* e^{hA} x + f1 N_x + 2 f2 (N_a + N_b) + f3 N_c; where A = 0: x + h/6 (N_x + 2 N_a + 2 N_b + N_c) */
    combine(n, m, 4, (const double *[]){e->e, e->f1, e->f2, e->f3}, (const double[]){1.0, h / 6.0, h / 6.0, h / 6.0},
            (const double *[]){x, nx, mix, nc}, next);
    if (!all_finite(n, next)) return 0;
    memcpy(x, next, sizeof(double) * (size_t)n);
    return 1;
}

OdeResult ode_exponential_integrate(OdeExponentialCache *cache, OdeSolver *solver, const OdeProblem *problem,
                                    OdeRhsLinear rhs_linear, const double *a, void *ctx, double *x, double t0,
                                    double span, double step, double *t_reached) {
    const int n = problem->n_states, m = problem->n_stiff;
    const double t1 = t0 + span;
    if (n > ODE_MAX_STATES || m < 1 || m > ODE_PHI_MAX || !(step > 0.0) || !(span > 0.0)) {
        if (t_reached) *t_reached = t0;
        return (span == 0.0) ? ODE_OK : ODE_BAD_SETTINGS;
    }
    const double wanted = ceil(span / step - 1e-9);
    if (wanted > ODE_MAX_STEPS) { /* bounded work, as ode_integrate's */
        if (t_reached) *t_reached = t0;
        return ODE_TOO_MUCH_WORK;
    }
    const int count = (int)wanted;
    const double h = span / count, steps_before = solver->steps;
    const OdeExponential *e = exponential_for(cache, m, a, h);
    double fastest = 0.0;
    for (int i = 0; i < m; i++) fastest = fmax(fastest, fabs(a[i * m + i]));
    solver->method = ODE_RK4;
    solver->step = fastest > 0.0 ? fmin(h, 1.0 / fastest) : h;
    const int explicit_enough = h <= solver->step; /* where RK4 is stable its step is cheaper */
    for (int k = 0; k < count; k++) {
        const double t = t0 + k * h, t_next = (k + 1 == count) ? t1 : t + h;
        if (!explicit_enough && exponential_step(e, n, m, rhs_linear, ctx, t, t_next - t, x)) {
            solver->steps += 1;
            solver->rhs_calls += 4;
            continue;
        }
        const OdeResult r = ode_integrate(solver, problem, ctx, x, t, t_next, t_reached);
        if (r != ODE_OK) return r;
        if (solver->steps - steps_before > ODE_MAX_STEPS) { /* the RK4 steps of many clamped steps */
            if (t_reached) *t_reached = t_next;
            return ODE_TOO_MUCH_WORK;
        }
    }
    if (t_reached) *t_reached = t1;
    return ODE_OK;
}
