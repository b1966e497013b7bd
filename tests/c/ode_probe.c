/* Test-only probe of fmu/common/ode.c on problems with known solutions (built by tests/test_ode.py). */
#include <math.h>

#include "ode.h"

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
    OdeProblem problem = {2, oscillator, 0, 0, 0};
    double x[2] = {1.0, 0.0}, t = 0.0;
    for (int i = 0; i < pieces; i++) {
        double t_next = t_end * (i + 1) / pieces;
        if (ode_integrate(&solver, &problem, 0, x, t, t_next, 0) != ODE_OK) return -1.0;
        t = t_next;
    }
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
    OdeProblem problem = {2, oscillator_ctx, 1, threshold, record};
    EventLog log = {{0, 0, 0, 0}, 0, 1.0};
    double x[2] = {1.0, 0.0};
    if (ode_integrate(&solver, &problem, &log, x, 0.0, t_end, 0) != ODE_OK) return -1;
    for (int i = 0; i < 4; i++) times[i] = log.event_time[i];
    return log.count;
}
