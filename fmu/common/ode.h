/* Internal ODE solvers shared by every FMU.
 *
 * Plain C with no FMI dependency, so the solvers can be tested and reused on their own.
 *
 * The methods:
 *   ODE_RK4    classic fixed-step Runge-Kutta of order 4; the interval is cut into equal steps
 *              no longer than `step`.
 *   ODE_DOPRI5 Dormand-Prince 5(4) embedded pair with local error control
 *              (err_i / (atol + rtol * max(|x_i|, |x_new_i|)), RMS norm <= 1), steps capped at `step`.
 *
 *   ODE_ROSENBROCK  ROS34PW2 (Rang & Angermann 2005), a linearly implicit Rosenbrock-W method of
 *              order 3 with fixed steps (as RK4); L-stable and stiffly accurate, so a stiff part
 *              (a current loop far faster than the step) is damped as the exact solution damps it,
 *              with no stability limit on the step. The method's matrix approximates df/dx in the
 *              columns of the leading n_stiff states (the others' columns zero: states such as slow
 *              integrators and energy accounts are explicit), the model's own
 *              (OdeProblem.jacobian) or by forward differences (n_stiff evaluations of the
 *              right-hand side), taken once per call and after each event (a W-method keeps its
 *              order 3 with any such matrix, and with a lagged one). Then f and df/dt (2
 *              evaluations), and 4 per step (3 on the step that starts where the matrix was
 *              taken).
 *   ODE_ROSENBROCK_ADAPTIVE  the same with error control by its embedded order-2 solution (the
 *              Jacobian also retaken after a rejection), steps capped at `step`.
 *   ODE_HEUN   Heun's method (the explicit trapezoidal rule), order 2, two evaluations per step,
 *              fixed steps as RK4. For a model inside a co-simulation whose inputs are themselves of
 *              order 2 (a master interpolating or extrapolating them linearly: the coupling's error
 *              is O(h^2) whatever the FMU's solver), it matches that order at half RK4's work.
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

typedef enum { ODE_RK4 = 1, ODE_DOPRI5 = 2, ODE_ROSENBROCK = 3, ODE_ROSENBROCK_ADAPTIVE = 4, ODE_HEUN = 5 } OdeMethod;

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
/* Optional: the model's own approximation of df/dx at (t, x) in the stiff states' columns, written
 * into the entries it knows of jacobian[0 .. n-1][0 .. n_stiff-1], which the solver has zeroed. */
typedef void (*OdeJacobian)(void *ctx, double t, const double *x, double jacobian[][ODE_MAX_STATES]);

typedef struct {
    int n_states;
    OdeRhs rhs;
    int n_events;         /* 0: no events */
    OdeEvents events;
    OdeOnEvent on_event;
    int n_stiff;          /* Rosenbrock-W: the leading n_stiff states are implicit (0: all); the
                             rest (slow integrators, energy accounts) are explicit */
    OdeJacobian jacobian; /* NULL: the Rosenbrock-W method takes df/dx by forward differences */
} OdeProblem;

typedef struct {
    int method;           /* OdeMethod */
    double step;          /* RK4, ROSENBROCK: the step; the adaptive methods: the largest step */
    double rtol, atol;    /* the adaptive methods only */
    double h_next;        /* adaptive: step proposed by the controller for the next step (0: choose) */
    double steps, rejected, events, rhs_calls; /* counters (double: they survive a state copy as data) */
} OdeSolver;

/* Integrates x from t0 to t1 in place. On failure x holds the last good state and *t_reached
 * (if not NULL) the time it belongs to. */
OdeResult ode_integrate(OdeSolver *solver, const OdeProblem *problem, void *ctx,
                        double *x, double t0, double t1, double *t_reached);

const char *ode_result_text(OdeResult r);

/* For exponential integrators: phi_0(hA) = e^{hA}, phi_1(hA), ..., phi_count(hA) of an n x n
 * row-major matrix A (n <= ODE_PHI_MAX, count <= 3), phi_k(z) = (e^z - sum_{j<k} z^j / j!) / z^k,
 * written one after another (count + 1 n x n matrices) into phi. By scaling and squaring on the
 * n x n matrices (their Taylor series at hA / 2^s, then a doubling formula for each); costs a few
 * dozen products of n x n matrices (about 20 us for the PMSM drive's 7 x 7 at 1 ms), so a caller
 * keeps them for its step. */
#define ODE_PHI_MAX 8
void ode_phi_functions(int n, const double *a, double h, int count, double *phi);

/* ---- the exponential integrator ETDRK4 (Cox and Matthews 2002) ----
 * For x' = A x + N(t, x) with A constant on the leading n_stiff states (zero elsewhere): the linear
 * part exactly through e^{hA} and its phi-functions, N explicitly; where A = 0 it is classic RK4.
 * A model gives A and, with each evaluation of its derivatives, whether A is its linear part there
 * (no limit engaged); a step where it is not is taken by RK4 at the fastest diagonal's time scale
 * (h |a_ii| <= 1), and so are steps no longer than that. */

/* The derivatives at (t, x) into dxdt; returns whether A is the linear part there. */
typedef int (*OdeRhsLinear)(void *ctx, double t, const double *x, double *dxdt);

/* The matrices of a step, each stored by column (row i, column j at [j * n + i]: the products run
 * down the columns, several rows at once) but for `a`, which is as the model gives it. */
typedef struct {
    double h;                                   /* the step they are for (0: none yet) */
    double a[ODE_PHI_MAX * ODE_PHI_MAX];        /* the linear part they are of, row major */
    double a_by_column[ODE_PHI_MAX * ODE_PHI_MAX];
    double e[ODE_PHI_MAX * ODE_PHI_MAX], e2[ODE_PHI_MAX * ODE_PHI_MAX], q[ODE_PHI_MAX * ODE_PHI_MAX];
    double f1[ODE_PHI_MAX * ODE_PHI_MAX], f2[ODE_PHI_MAX * ODE_PHI_MAX], f3[ODE_PHI_MAX * ODE_PHI_MAX];
} OdeExponential;

/* The functions of the last few steps (a run's macro step, a finer start's, a last short one), kept
 * by the caller outside anything it copies often (they are derived data). */
enum { ODE_EXPONENTIAL_KEPT = 4 };
typedef struct {
    OdeExponential entry[ODE_EXPONENTIAL_KEPT];
    int next; /* the entry to replace next */
} OdeExponentialCache;

/* Integrates x from t0 over `span` in place, in equal steps of at most `step`, with the n_stiff x
 * n_stiff linear part a (row major); the RK4 steps go through `problem` and count in `solver` (its
 * method and step are set here), as do the exponential ones. The steps are span / count, so that a
 * run's equal communication steps meet the functions kept for them. On failure as ode_integrate. */
OdeResult ode_exponential_integrate(OdeExponentialCache *cache, OdeSolver *solver, const OdeProblem *problem,
                                    OdeRhsLinear rhs_linear, const double *a, void *ctx, double *x, double t0,
                                    double span, double step, double *t_reached);

#endif
