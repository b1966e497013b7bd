/* Test-only probe of fmu/common/ode.c on problems with known solutions (built by tests/test_ode.py). */
#include <math.h>

#include "ode.h"

/* Integrates x from 0 to t_end in `pieces` equal calls, as FMI communication steps would. */
static OdeResult integrate_in_pieces(OdeSolver *solver, const OdeProblem *problem, void *ctx, double *x,
                                     double t_end, int pieces) {
    double t = 0.0;
    for (int i = 0; i < pieces; i++) {
        double t_next = t_end * (i + 1) / pieces;
        OdeResult r = ode_integrate(solver, problem, ctx, x, t, t_next, 0);
        if (r != ODE_OK) return r;
        t = t_next;
    }
    return ODE_OK;
}

/* Harmonic oscillator x'' = -x, x(0) = 1, x'(0) = 0. */
static void oscillator(void *ctx, double t, const double *x, double *dxdt) {
    (void)ctx; (void)t;
    dxdt[0] = x[1];
    dxdt[1] = -x[0];
}

/* Integrates the oscillator to t_end in `pieces` calls (as FMI communication steps would) and
 * returns the largest error against (cos t, -sin t); counts steps and rejections. */
double probe_oscillator(int method, double step, double rtol, double t_end, int pieces, double *steps,
                        double *rejected) {
    OdeSolver solver = {method, step, rtol, rtol, 0.0, 0, 0, 0, 0};
    OdeProblem problem = {2, oscillator, 0, 0, 0, 0, 0};
    double x[2] = {1.0, 0.0};
    if (integrate_in_pieces(&solver, &problem, 0, x, t_end, pieces) != ODE_OK) return -1.0;
    *steps = solver.steps;
    *rejected = solver.rejected;
    return fmax(fabs(x[0] - cos(t_end)), fabs(x[1] + sin(t_end)));
}

/* Event: g = 0.5 - x(t) on the oscillator, rising through zero at t = pi/3 (and again at 5 pi/3,
 * where x rises back through 0.5 is a falling g: not an event). The handler records the time and
 * flips the sign convention so that g is negative again. */
typedef struct { double event_time[4]; int count; double sign; } EventLog;

static void threshold(void *ctx, double t, const double *x, double *g) {
    (void)t;
    EventLog *log = (EventLog *)ctx;
    g[0] = log->sign * (0.5 - x[0]);
}

static void record(void *ctx, double t, const double *x, int which) {
    (void)x; (void)which;
    EventLog *log = (EventLog *)ctx;
    if (log->count < 4) log->event_time[log->count] = t;
    log->count++;
    log->sign = -log->sign;
}

static void oscillator_ctx(void *ctx, double t, const double *x, double *dxdt) { oscillator(ctx, t, x, dxdt); }

/* Returns the number of events on [0, t_end]; their times go to times[0..3]. */
int probe_events(int method, double step, double rtol, double t_end, double *times) {
    OdeSolver solver = {method, step, rtol, rtol, 0.0, 0, 0, 0, 0};
    OdeProblem problem = {2, oscillator_ctx, 1, threshold, record, 0, 0};
    EventLog log = {{0, 0, 0, 0}, 0, 1.0};
    double x[2] = {1.0, 0.0};
    if (ode_integrate(&solver, &problem, &log, x, 0.0, t_end, 0) != ODE_OK) return -1;
    for (int i = 0; i < 4; i++) times[i] = log.event_time[i];
    return log.count;
}

/* Prothero-Robinson: x' = lambda (x - sin t) + cos t, x(0) = 0, exact x = sin t for any lambda;
 * with lambda = -1e6 a step of 0.1 is 1e5 times an explicit method's stability limit. A second,
 * non-stiff state y' = x is a quadrature (its integral, 1 - cos t). */
static void prothero_robinson(void *ctx, double t, const double *x, double *dxdt) {
    const double lambda = *(const double *)ctx;
    dxdt[0] = lambda * (x[0] - sin(t)) + cos(t);
    dxdt[1] = x[0];
}

/* Integrates it to t_end in `pieces` calls; returns the largest error of either state against the
 * exact solution (or -1 if the solver failed, -2 if the result is not finite). */
double probe_stiff(int method, double step, double rtol, double lambda, double t_end, int pieces, double *steps,
                   double *rhs_calls) {
    OdeSolver solver = {method, step, rtol, rtol, 0.0, 0, 0, 0, 0};
    OdeProblem problem = {2, prothero_robinson, 0, 0, 0, 1, 0};
    double x[2] = {0.0, 0.0};
    OdeResult r = integrate_in_pieces(&solver, &problem, &lambda, x, t_end, pieces);
    if (r == ODE_NONFINITE) return -2.0;
    if (r != ODE_OK) return -1.0;
    *steps = solver.steps;
    *rhs_calls = solver.rhs_calls;
    if (!isfinite(x[0]) || !isfinite(x[1])) return -2.0;
    return fmax(fabs(x[0] - sin(t_end)), fabs(x[1] - (1.0 - cos(t_end))));
}

/* x' = A x for a dense n x n matrix A (row-major, n <= 8): `pieces` calls of length t_end / pieces
 * from x (in place); returns the solver's result code. */
typedef struct { int n; const double *a; } LinearSystem;

static void linear_system(void *ctx, double t, const double *x, double *dxdt) {
    const LinearSystem *system = (const LinearSystem *)ctx;
    (void)t;
    for (int i = 0; i < system->n; i++) {
        dxdt[i] = 0.0;
        for (int j = 0; j < system->n; j++) dxdt[i] += system->a[i * system->n + j] * x[j];
    }
}

int probe_linear(int method, double step, int n, const double *a, double *x, double t_end, int pieces) {
    OdeSolver solver = {method, step, 1e-6, 1e-6, 0.0, 0, 0, 0, 0};
    OdeProblem problem = {n, linear_system, 0, 0, 0, 0, 0};
    LinearSystem system = {n, a};
    return (int)integrate_in_pieces(&solver, &problem, &system, x, t_end, pieces);
}

/* The logistic equation x' = x (1 - x), x(0) = 0.1: exact x = 1 / (1 + 9 e^-t); its Jacobian
 * 1 - 2x goes from 0.8 to -0.8 over [0, 5]. Integrated in one call, so a Rosenbrock-W step uses the
 * Jacobian of t = 0 throughout. Returns the error at t_end (-1 if the solver failed). */
static void logistic(void *ctx, double t, const double *x, double *dxdt) {
    (void)ctx; (void)t;
    dxdt[0] = x[0] * (1.0 - x[0]);
}

double probe_logistic(int method, double step, double t_end) {
    OdeSolver solver = {method, step, 1e-6, 1e-6, 0.0, 0, 0, 0, 0};
    OdeProblem problem = {1, logistic, 0, 0, 0, 0, 0};
    double x[1] = {0.1};
    if (ode_integrate(&solver, &problem, 0, x, 0.0, t_end, 0) != ODE_OK) return -1.0;
    return fabs(x[0] - 1.0 / (1.0 + 9.0 * exp(-t_end)));
}
