/* Internal ODE solvers shared by every FMU.
 *
 * Plain C with no FMI dependency, so the solvers can be tested and reused on their own.
 *
 * Two methods:
 *   ODE_RK4    classic fixed-step Runge-Kutta of order 4; the interval is cut into equal steps
 *              no longer than `step`.
 *   ODE_DOPRI5 Dormand-Prince 5(4) embedded pair with local error control
 *              (err_i / (atol + rtol * max(|x_i|, |x_new_i|)), RMS norm <= 1), steps capped at `step`.
 *
 * State events: a problem may give event functions g(t, x). An event occurs when a component
 * goes from g < 0 to g >= 0 inside a step; the solver locates it by the Illinois variant of
 * regula falsi on the step length (every trial is a full step of the method from the start of
 * the step, so the located state is as accurate as any step), stops there, and calls on_event,
 * which must change the model so that this g is no longer positive (a hysteresis switch makes it
 * negative; a g left at exactly zero counts as cleared and fires again only after going negative).
 *
 * All solver memory that matters for the next step lives in OdeSolver, a plain struct: copying it
 * (as fmi2GetFMUstate does) and restoring it later continues the integration bit for bit.
 */
#ifndef ODE_H
#define ODE_H

#define ODE_MAX_STATES 32
#define ODE_MAX_EVENTS 8

typedef enum { ODE_RK4 = 1, ODE_DOPRI5 = 2 } OdeMethod;

typedef enum {
    ODE_OK = 0,
    ODE_NONFINITE,       /* a derivative or state became NaN or infinite */
    ODE_STEP_TOO_SMALL,  /* the adaptive step fell below the round-off floor */
    ODE_BAD_SETTINGS,    /* non-positive step or tolerance, too many states */
    ODE_EVENT_LOOP,      /* an event handler did not clear its event */
    ODE_TOO_MUCH_WORK    /* more than ODE_MAX_STEPS internal steps (taken, rejected or at events) */
} OdeResult;

/* The most internal steps one call of ode_integrate may take: the work of one communication step
 * is bounded whatever the step sizes and the problem (under 1 s of CPU for the costliest model,
 * the mechanics; at the default internal steps a communication step of up to 20 s for the PMSM
 * drive, 200 s for the mechanics, 1 s for the switching inverter's 5 us limit). */
#define ODE_MAX_STEPS 200000

typedef void (*OdeRhs)(void *ctx, double t, const double *x, double *dxdt);
typedef void (*OdeEvents)(void *ctx, double t, const double *x, double *g);
typedef void (*OdeOnEvent)(void *ctx, double t, const double *x, int which);

typedef struct {
    int n_states;
    OdeRhs rhs;
    int n_events;         /* 0: no events */
    OdeEvents events;
    OdeOnEvent on_event;
} OdeProblem;

typedef struct {
    int method;           /* OdeMethod */
    double step;          /* RK4: the step; DOPRI5: the largest step */
    double rtol, atol;    /* DOPRI5 only */
    double h_next;        /* DOPRI5: step proposed by the controller for the next step (0: choose) */
    double steps, rejected, events, rhs_calls; /* counters (double: they survive a state copy as data) */
} OdeSolver;

/* Integrates x from t0 to t1 in place. On failure x holds the last good state and *t_reached
 * (if not NULL) the time it belongs to. */
OdeResult ode_integrate(OdeSolver *solver, const OdeProblem *problem, void *ctx,
                        double *x, double t0, double t1, double *t_reached);

const char *ode_result_text(OdeResult r);

#endif
