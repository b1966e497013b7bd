/* The engine's step kernel: the one implementation of the coupling algorithms and step controllers.
 *
 * Coupling (cosim/engine/coupling.py resolves the wiring; cosim/engine/kernel.py hands it over):
 *   - Jacobi: every instance steps from t with inputs extrapolated from its sources' last k + 1
 *     output samples (extrapolation order k = 0, 1, 2), global error O(h^(k+1));
 *   - Gauss-Seidel: instances step in sequence; an input whose source has already stepped is
 *     interpolated through that source's new sample at t + h. A stage of consecutive instances
 *     that feed none of each other (the platform's six drives) may step on two threads
 *     (threads = 2): each member reads only what was there before the stage and writes only its
 *     own slots, so the results are bit for bit the sequential ones.
 *   A source that gives its outputs' time derivatives (fmi2GetRealOutputDerivatives) feeds its
 *   Taylor polynomial at t instead, with every derivative it gives whatever the order above 0
 *   (and already during the start's consistency sweeps). Input derivatives go to the FMU through
 *   fmi2SetRealInputDerivatives; an FMU that cannot interpolate gets each input held at its
 *   polynomial's value at the step's midpoint and no derivatives (one that extrapolates its held
 *   inputs itself, fmi.extrapolate_inputs, the value at t).
 *   Start: the outputs are made consistent with the connected inputs (fixed-point sweeps), and the
 *   first macro step, which has no history, is iterated to a fixed point with inputs interpolated
 *   between t and the latest guess at t + h (FMU states restored between sweeps).
 *   Every macro step measures the energy residual of each power bond (ECCO, Sadjina et al. 2017),
 *   counting the correction of a bond whose effort comes with its slope (an interface Jacobian).
 * Step control:
 *   - fixed: n macro steps of h;
 *   - step doubling: each H once whole and once as two halves from the saved FMU states; the
 *     scaled difference is the error; a step too large is rolled back (fmi2SetFMUstate);
 *   - energy: the bonds' energy residual against rtol |E| + atol sets the next step (PI law).
 *
 * tests/oracle.py is a plain Python transcription of this file that the tests hold it to, bit for
 * bit; it is never used to run anything.
 */
#define _POSIX_C_SOURCE 199309L /* clock_gettime, nanosleep */
#include <math.h>
#include <pthread.h>
#include <sched.h>
#include <stdatomic.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "kernel.h"

enum { FMI2_ERROR = 3 };
enum { CALL_SET_REAL = 1, CALL_SET_INPUT_DERIVATIVES, CALL_DO_STEP, CALL_GET_REAL, CALL_GET_OUTPUT_DERIVATIVES,
       CALL_GET_STATE, CALL_SET_STATE, CALL_FREE_STATE };

static double now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static _Thread_local int on_helper; /* set on the helper thread: its calls' time is the main thread's wait */

/* The time inside the FMUs is taken around each run of consecutive calls (one member's inputs,
 * step and outputs; one row's reads), not around every call: a clock read costs about as much
 * as a short FMI call, and the few arithmetic operations between the calls of a run (its inputs'
 * polynomials) are counted with them. */
static double clock_start(void) { return on_helper ? 0.0 : now(); }
/* Charges the time since `started` to instance k; returns the time read (0 on the helper). A run of
 * members that follow each other (a Gauss-Seidel sweep) starts each at the previous one's stop, one
 * clock read a member: what the loop does between them is counted with the next. */
static double clock_stop(Kernel *s, int k, double started) {
    if (on_helper) return 0.0;
    const double stopped = now();
    s->fmi_seconds[k] += stopped - started;
    return stopped;
}

#define FMI_CALL(s, k, code, expression)                                                          \
    do {                                                                                           \
        const int status_ = (expression);                                                          \
        if (status_ >= FMI2_ERROR) {                                                               \
            (s)->failed_instance = (k);                                                            \
            (s)->failed_call = (code);                                                             \
            return 0;                                                                              \
        }                                                                                          \
    } while (0)

/* Value, rate and curvature at t of the polynomial through the n samples (times[i], y[i]), by
 * Newton's divided differences, truncated to `order`. */
static void polynomial_at(int n, const double *times, const double *y, double t, int order, double out[3]) {
    out[1] = out[2] = 0.0;
    if (n == 1 || order == 0) { out[0] = y[n - 1]; return; }
    if (n == 2 || order == 1) {
        const double slope = (y[n - 1] - y[n - 2]) / (times[n - 1] - times[n - 2]);
        out[0] = y[n - 1] + slope * (t - times[n - 1]);
        out[1] = slope;
        return;
    }
    const double d1_0 = (y[1] - y[0]) / (times[1] - times[0]), d1_1 = (y[2] - y[1]) / (times[2] - times[1]);
    const double d2 = (d1_1 - d1_0) / (times[2] - times[0]);
    out[0] = y[0] + d1_0 * (t - times[0]) + d2 * (t - times[0]) * (t - times[1]);
    out[1] = d1_0 + d2 * ((t - times[0]) + (t - times[1]));
    out[2] = 2.0 * d2;
}

/* Sends instance k's input rates (top >= 1) and curvatures (top >= 2) as they stand in the arrays. */
static int send_derivatives(Kernel *s, int k, int top) {
    const KernelInstance *in = &s->instances[k];
    if (top >= 1)
        FMI_CALL(s, k, CALL_SET_INPUT_DERIVATIVES,
                 in->set_input_derivatives(in->component, in->input_vrs, (size_t)in->n_inputs, s->order_one,
                                           s->input_rates + in->input_offset));
    if (top >= 2)
        FMI_CALL(s, k, CALL_SET_INPUT_DERIVATIVES,
                 in->set_input_derivatives(in->component, in->input_vrs, (size_t)in->n_inputs, s->order_two,
                                           s->input_curvatures + in->input_offset));
    return 1;
}

/* Instance k's inputs over [t, t_new] at extrapolation order `order`: from the polynomial through
 * its sources' samples (with the new sample at t_new where a source has stepped), evaluated at t. */
static int set_inputs(Kernel *s, int k, double t, double t_new, int order) {
    const KernelInstance *in = &s->instances[k];
    const int latest = s->n_samples - 1;
    int sent = order; /* the highest derivative order sent: a source's exact derivatives all go */
    for (int i = 0; i < in->n_inputs; i++) {
        const int source = in->feed_source[i];
        const int at = s->instances[source].output_offset + in->feed_index[i];
        double p[3];
        if (s->instances[source].rate_order > 0) { /* Taylor polynomial at t with the exact derivatives */
            const int given = order == 0 ? 0 : s->instances[source].rate_order; /* all it has */
            if (given > sent) sent = given;
            p[0] = s->samples[latest * s->n_sample_values + at];
            p[1] = given >= 1 ? s->exact_rates[at] : 0.0;
            p[2] = given >= 2 ? s->exact_rates[s->n_sample_values + at] : 0.0;
        } else {
            double times[4], y[4];
            int n = 0;
            for (int j = 0; j < s->n_samples; j++) {
                times[n] = s->sample_time[j];
                y[n++] = s->samples[j * s->n_sample_values + at];
            }
            if (s->stepped[source]) { times[n] = t_new; y[n++] = s->new_values[at]; }
            const int count = order + 1 < n ? order + 1 : n;
            polynomial_at(count, times + (n - count), y + (n - count), t, order, p);
        }
        if (order >= 1 && !in->interpolating) { /* held at the polynomial's midpoint value */
            const double half = in->extrapolating ? 0.0 : 0.5 * (t_new - t); /* (at t: it extrapolates itself) */
            p[0] = p[0] + p[1] * half + 0.5 * p[2] * half * half;
            p[1] = p[2] = 0.0;
        }
        s->input_values[in->input_offset + i] = p[0];
        s->input_rates[in->input_offset + i] = p[1];
        s->input_curvatures[in->input_offset + i] = p[2];
    }
    FMI_CALL(s, k, CALL_SET_REAL, in->set_real(in->component, in->input_vrs, (size_t)in->n_inputs,
                                               s->input_values + in->input_offset));
    return !in->interpolating || send_derivatives(s, k, sent);
}

static int do_step(Kernel *s, int k, double h) {
    const KernelInstance *in = &s->instances[k];
    FMI_CALL(s, k, CALL_DO_STEP, in->do_step(in->component, s->instance_time[k], h, 0));
    s->instance_time[k] += h;
    return 1;
}

static int read_outputs(Kernel *s, int k) {
    const KernelInstance *in = &s->instances[k];
    if (in->n_outputs == 0) return 1;
    FMI_CALL(s, k, CALL_GET_REAL, in->get_real(in->component, in->output_vrs, (size_t)in->n_outputs,
                                               s->new_values + in->output_offset));
    s->stepped[k] = 1;
    return 1;
}

static int read_all_outputs(Kernel *s) {
    for (int k = 0; k < s->n_instances; k++) {
        const double started = clock_start();
        const int ok = read_outputs(s, k);
        clock_stop(s, k, started);
        if (!ok) return 0;
    }
    return 1;
}

/* The exact output derivatives of the sources that give them, at their current time. */
static int read_rates(Kernel *s) {
    for (int k = 0; k < s->n_instances; k++) {
        const KernelInstance *in = &s->instances[k];
        if (in->rate_order == 0) continue;
        const double started = clock_start();
        for (int order = 1; order <= in->rate_order; order++)
            FMI_CALL(s, k, CALL_GET_OUTPUT_DERIVATIVES,
                     in->get_output_derivatives(in->component, in->output_vrs, (size_t)in->n_outputs,
                                                order == 1 ? s->order_one : s->order_two,
                                                s->exact_rates + (order - 1) * s->n_sample_values + in->output_offset));
        clock_stop(s, k, started);
    }
    return 1;
}

/* The history's new sample: new_values at t_new, and the exact rates there. */
static int push_sample(Kernel *s, double t_new) {
    if (s->n_samples == s->keep) {
        memmove(s->sample_time, s->sample_time + 1, (size_t)(s->keep - 1) * sizeof(double));
        memmove(s->samples, s->samples + s->n_sample_values,
                (size_t)(s->keep - 1) * (size_t)s->n_sample_values * sizeof(double));
        s->n_samples--;
    }
    s->sample_time[s->n_samples] = t_new;
    memcpy(s->samples + s->n_samples * s->n_sample_values, s->new_values, (size_t)s->n_sample_values * sizeof(double));
    s->n_samples++;
    return read_rates(s);
}

/* At the start, with extrapolation (order >= 1): the exact derivatives at t that sources give with
 * their outputs go to the inputs they feed (an output computed from an input's rate, such as the
 * mechanics' leg velocity_ref from pose_ref's, is then right from the first sample); 0 for the
 * other inputs. */
static int set_exact_derivatives(Kernel *s, int k) {
    const KernelInstance *in = &s->instances[k];
    if (s->order == 0 || !in->interpolating) return 1;
    int top = 0;
    for (int i = 0; i < in->n_inputs; i++) {
        const KernelInstance *source = &s->instances[in->feed_source[i]];
        const int at = source->output_offset + in->feed_index[i];
        s->input_rates[in->input_offset + i] = source->rate_order >= 1 ? s->exact_rates[at] : 0.0;
        s->input_curvatures[in->input_offset + i] = source->rate_order >= 2 ? s->exact_rates[s->n_sample_values + at] : 0.0;
        if (source->rate_order > top) top = source->rate_order;
    }
    return send_derivatives(s, k, top);
}

/* Makes the outputs at t consistent with the connected inputs (outputs that feed through from
 * inputs depend on them): up to `sweeps` rounds of setting every input from its source and reading
 * the outputs again, until they stop changing; then starts the history with that sample. With
 * zero_start the history starts from outputs of 0 instead, so every input is 0 over the first step
 * (the convention of tools that start their connections at 0, such as fmpy.ssp). */
int kernel_initialize(Kernel *s, double t, int sweeps, int zero_start) {
    s->failed_instance = s->failed_call = -1;
    s->n_samples = 0;
    if (!read_all_outputs(s) || !read_rates(s)) return 0;
    for (int sweep = 0; sweep < sweeps; sweep++) {
        for (int k = 0; k < s->n_instances; k++) {
            const KernelInstance *in = &s->instances[k];
            if (in->n_inputs == 0) continue;
            for (int i = 0; i < in->n_inputs; i++)
                s->input_values[in->input_offset + i] =
                    s->new_values[s->instances[in->feed_source[i]].output_offset + in->feed_index[i]];
            const double started = clock_start();
            FMI_CALL(s, k, CALL_SET_REAL, in->set_real(in->component, in->input_vrs, (size_t)in->n_inputs,
                                                       s->input_values + in->input_offset));
            if (!set_exact_derivatives(s, k)) return 0;
            clock_stop(s, k, started);
        }
        memcpy(s->guess, s->new_values, (size_t)s->n_sample_values * sizeof(double)); /* the old outputs */
        if (!read_all_outputs(s)) return 0;
        int settled = 1;
        for (int i = 0; i < s->n_sample_values; i++)
            if (s->guess[i] != s->new_values[i]) settled = 0;
        if (settled) break;
    }
    if (zero_start) memset(s->new_values, 0, (size_t)s->n_sample_values * sizeof(double));
    return push_sample(s, t);
}

/* _energy_residual: the largest |energy residual| of the bonds over the step just taken; per bond,
 * the residual and the energy transferred into bond_energy (2 per bond) if it is not NULL. Each
 * side's power is taken as it saw it: the outputs at t and t + h against the inputs as set over
 * the step, integrated by the trapezoidal rule. A bond with a slope (an interface Jacobian): the
 * flow's side felt effort + slope (its flow - the flow the effort's side was given). */
static double energy_residual(const Kernel *s, double h, double *bond_energy) {
    const double *before = s->samples + (s->n_samples - 2) * s->n_sample_values;
    const double *after = s->samples + (s->n_samples - 1) * s->n_sample_values;
    double largest = 0.0;
    for (int b = 0; b < s->n_bonds; b++) {
        const KernelBond *bond = &s->bonds[b];
        const int effort_out = s->instances[bond->effort_out.instance].output_offset + bond->effort_out.index;
        const int effort_in = s->instances[bond->effort_in.instance].input_offset + bond->effort_in.index;
        const int flow_out = s->instances[bond->flow_out.instance].output_offset + bond->flow_out.index;
        const int flow_in = s->instances[bond->flow_in.instance].input_offset + bond->flow_in.index;
#define SEEN(i, dt) (s->input_values[i] + s->input_rates[i] * (dt) + 0.5 * s->input_curvatures[i] * (dt) * (dt))
        const double given = 0.5 * h * (before[effort_out] * SEEN(flow_in, 0.0) + after[effort_out] * SEEN(flow_in, h));
        double felt_before = SEEN(effort_in, 0.0), felt_after = SEEN(effort_in, h);
        if (bond->slope_in.instance >= 0) {
            const int slope_in = s->instances[bond->slope_in.instance].input_offset + bond->slope_in.index;
            felt_before += SEEN(slope_in, 0.0) * (before[flow_out] - SEEN(flow_in, 0.0));
            felt_after += SEEN(slope_in, h) * (after[flow_out] - SEEN(flow_in, h));
        }
        const double taken = 0.5 * h * (felt_before * before[flow_out] + felt_after * after[flow_out]);
#undef SEEN
        const double residual = fabs(given - taken);
        if (residual > largest || isnan(residual)) largest = residual;
        if (bond_energy) {
            bond_energy[2 * b] = given - taken;
            bond_energy[2 * b + 1] = 0.5 * (fabs(given) + fabs(taken));
        }
    }
    return largest;
}

static int record(Kernel *s, double *row, double t) {
    const double started = clock_start(); /* the row's reads, counted as the first instance's */
    for (int k = 0; k < s->n_instances; k++) {
        const KernelInstance *in = &s->instances[k];
        if (in->n_record > 0)
            FMI_CALL(s, k, CALL_GET_REAL, in->get_real(in->component, in->record_vrs, (size_t)in->n_record,
                                                       s->record_scratch + in->record_offset));
    }
    clock_stop(s, 0, started);
    row[0] = t;
    for (int c = 0; c < s->n_columns; c++) row[1 + c] = s->record_scratch[s->column_of[c]];
    return 1;
}

/* Records the row at the current time of instance `clock` (the first row of a run). */
int kernel_record(Kernel *s, int clock, double *row) {
    s->failed_instance = s->failed_call = -1;
    return record(s, row, s->instance_time[clock]);
}

static int save_states(Kernel *s, void **states) {
    for (int k = 0; k < s->n_instances; k++) {
        const KernelInstance *in = &s->instances[k];
        states[k] = NULL;
        const double started = clock_start();
        FMI_CALL(s, k, CALL_GET_STATE, in->get_state(in->component, &states[k]));
        clock_stop(s, k, started);
    }
    return 1;
}

static int restore_states(Kernel *s, void **states, const double *saved_instance_time) {
    for (int k = 0; k < s->n_instances; k++) {
        const KernelInstance *in = &s->instances[k];
        const double started = clock_start();
        FMI_CALL(s, k, CALL_SET_STATE, in->set_state(in->component, states[k]));
        clock_stop(s, k, started);
    }
    memcpy(s->instance_time, saved_instance_time, (size_t)s->n_instances * sizeof(double));
    return 1;
}

static void free_states(Kernel *s, void **states) {
    for (int k = 0; k < s->n_instances; k++) {
        const KernelInstance *in = &s->instances[k];
        if (states[k]) in->free_state(in->component, &states[k]);
        states[k] = NULL;
    }
}

/* The first macro step, which has no history: iterated with inputs interpolated linearly between
 * the outputs at t and the latest guess of the outputs at t + h until the guess changes by less
 * than 1e-13 (relative) or 50 sweeps were made; the instances stay at t + h. */
static int start_up(Kernel *s, double t, double h) {
    enum { SWEEPS = 50 };
    const double tolerance = 1e-13;
    double *guess = s->guess, *saved_instance_time = s->saved_time;
    memcpy(saved_instance_time, s->instance_time, (size_t)s->n_instances * sizeof(double));
    if (!save_states(s, s->startup_states)) { free_states(s, s->startup_states); return 0; }
    /* the guess at t + h starts as the outputs at t */
    memcpy(s->new_values, s->samples + (s->n_samples - 1) * s->n_sample_values,
           (size_t)s->n_sample_values * sizeof(double));
    for (int k = 0; k < s->n_instances; k++) s->stepped[k] = s->instances[k].n_outputs > 0;
    for (int sweep = 0; sweep < SWEEPS; sweep++) {
        memcpy(guess, s->new_values, (size_t)s->n_sample_values * sizeof(double));
        for (int k = 0; k < s->n_instances; k++) {
            const double started = clock_start();
            const int ok = (s->instances[k].n_inputs == 0 || set_inputs(s, k, t, t + h, 1)) && do_step(s, k, h);
            clock_stop(s, k, started);
            if (!ok) { free_states(s, s->startup_states); return 0; }
        }
        /* the new outputs: read into new_values only after every instance stepped (set_inputs
         * reads the guess from new_values) */
        if (!read_all_outputs(s)) { free_states(s, s->startup_states); return 0; }
        double change = 0.0;
        for (int i = 0; i < s->n_sample_values; i++) {
            const double c = fabs(s->new_values[i] - guess[i]) / (1.0 + fabs(s->new_values[i]));
            if (c > change || isnan(c)) change = c;
        }
        if (change < tolerance || sweep == SWEEPS - 1) break;
        if (!restore_states(s, s->startup_states, saved_instance_time)) { free_states(s, s->startup_states); return 0; }
    }
    free_states(s, s->startup_states);
    return push_sample(s, t + h);
}

/* ---- a stage on two threads ---- */

/* One Gauss-Seidel member: its inputs, its step, its outputs; timed from *lap (the previous
 * member's stop), which it moves to its own stop (NULL: timed on its own). */
static int step_member(Kernel *s, int k, double t, double t_new, double h, double *lap) {
    const double started = lap ? *lap : clock_start();
    const int ok = (s->instances[k].n_inputs == 0 || set_inputs(s, k, t, t_new, s->order)) && do_step(s, k, h) &&
                   read_outputs(s, k);
    const double stopped = clock_stop(s, k, started);
    if (lap) *lap = stopped;
    return ok;
}

typedef struct {
    pthread_t thread;
    atomic_int generation; /* the main thread bumps it to hand out work; -1: quit */
    atomic_int finished;   /* the generation the helper has finished */
    Kernel *s;
    int first, last, status;
    double t, t_new, h;
} Helper;

static void *helper_main(void *arg) {
    Helper *helper = arg;
    on_helper = 1;
    int seen = 0;
    for (;;) {
        int generation;
        long spins = 0;
        while ((generation = atomic_load(&helper->generation)) == seen) {
            if (++spins > 200000) { /* idle (between the kernel's calls): nap instead of spinning */
                const struct timespec nap = {0, 20000};
                nanosleep(&nap, NULL);
            } else if (spins > 2000) {
                sched_yield(); /* let whatever shares this core run */
            }
        }
        if (generation < 0) return NULL;
        seen = generation;
        int ok = 1;
        for (int j = helper->first; j < helper->last && ok; j++)
            ok = step_member(helper->s, helper->s->sequence[j], helper->t, helper->t_new, helper->h, NULL);
        helper->status = ok;
        atomic_store(&helper->finished, generation);
    }
}

/* Sequence positions [j0, j1) (a stage) on two threads: the first half here, the rest on the
 * helper; the main thread's wait counts as the helper's first member's FMI time. Timed from *lap,
 * as step_member. */
static int parallel_stage(Kernel *s, int j0, int j1, double t, double t_new, double h, double *lap) {
    Helper *helper = s->helper;
    if (!helper) {
        helper = calloc(1, sizeof *helper);
        if (helper) {
            helper->s = s;
            atomic_init(&helper->generation, 0);
            atomic_init(&helper->finished, 0);
            if (pthread_create(&helper->thread, NULL, helper_main, helper) != 0) { free(helper); helper = NULL; }
        }
        if (!helper) { /* no second thread to be had: this stage, and the next, one after another */
            s->threads = 1;
            for (int j = j0; j < j1; j++)
                if (!step_member(s, s->sequence[j], t, t_new, h, lap)) return 0;
            return 1;
        }
        s->helper = helper;
    }
    helper->first = j0 + (j1 - j0 + 1) / 2;
    helper->last = j1;
    helper->t = t, helper->t_new = t_new, helper->h = h;
    const int generation = atomic_load(&helper->generation) + 1;
    atomic_store(&helper->generation, generation);
    int ok = 1;
    for (int j = j0; j < helper->first && ok; j++) ok = step_member(s, s->sequence[j], t, t_new, h, lap);
    for (long spins = 0; atomic_load(&helper->finished) != generation;)
        if (++spins > 2000) sched_yield(); /* the helper may be waiting for this core */
    *lap = clock_stop(s, s->sequence[helper->first], *lap);
    return ok && helper->status;
}

/* Ends the helper thread, if there is one. */
void kernel_release(Kernel *s) {
    Helper *helper = s->helper;
    if (!helper) return;
    atomic_store(&helper->generation, -1);
    pthread_join(helper->thread, NULL);
    free(helper);
    s->helper = NULL;
}

/* Feed-through at the newest sample (time t_new): per step of the plan, the inputs its outputs
 * depend on set to their sources' newest values (and exact derivatives, under extrapolation, from
 * the sources that give them), then those outputs read again into the sample. An output that
 * depends on an input thus carries the input's value at the same communication point, as tools
 * that order outputs along the connections (OMSimulator) have it. */
static int resolve_feedthrough(Kernel *s) {
    const size_t n = (size_t)s->n_sample_values;
    double *sample = s->samples + (size_t)(s->n_samples - 1) * n;
    for (int f = 0; f < s->n_feeds; f++) {
        const KernelFeed *feed = &s->feeds[f];
        const int k = feed->instance;
        const KernelInstance *in = &s->instances[k];
        const int *index = s->feed_indices + feed->first;
        const double started = clock_start();
        int top = 0;
        for (int j = 0; j < feed->n_inputs; j++) {
            const int i = index[j];
            const KernelInstance *source = &s->instances[in->feed_source[i]];
            const int at = source->output_offset + in->feed_index[i];
            s->feed_vrs[j] = in->input_vrs[i];
            s->feed_values[j] = sample[at];
            const int given = s->order > 0 && in->interpolating ? source->rate_order : 0;
            s->feed_rates[j] = given >= 1 ? s->exact_rates[at] : 0.0;
            s->feed_rates[feed->n_inputs + j] = given >= 2 ? s->exact_rates[n + (size_t)at] : 0.0;
            if (given > top) top = given;
        }
        FMI_CALL(s, k, CALL_SET_REAL, in->set_real(in->component, s->feed_vrs, (size_t)feed->n_inputs, s->feed_values));
        if (top >= 1)
            FMI_CALL(s, k, CALL_SET_INPUT_DERIVATIVES,
                     in->set_input_derivatives(in->component, s->feed_vrs, (size_t)feed->n_inputs, s->order_one,
                                               s->feed_rates));
        if (top >= 2)
            FMI_CALL(s, k, CALL_SET_INPUT_DERIVATIVES,
                     in->set_input_derivatives(in->component, s->feed_vrs, (size_t)feed->n_inputs, s->order_two,
                                               s->feed_rates + feed->n_inputs));
        for (int j = 0; j < feed->n_outputs; j++) s->feed_vrs[j] = in->output_vrs[index[feed->n_inputs + j]];
        FMI_CALL(s, k, CALL_GET_REAL, in->get_real(in->component, s->feed_vrs, (size_t)feed->n_outputs, s->feed_values));
        for (int j = 0; j < feed->n_outputs; j++)
            sample[in->output_offset + index[feed->n_inputs + j]] = s->feed_values[j];
        clock_stop(s, k, started);
    }
    return 1;
}

/* One macro step from t (the master's time) to t + h: the start-up iteration if there is no
 * history yet, otherwise one sweep; the new history sample; the bonds' energy residual (largest
 * into *residual, per bond into bond_energy if not NULL). Returns 0 when an FMI call failed. */
static int macro_step(Kernel *s, double t, double h, double *residual, double *bond_energy) {
    const double t_new = t + h;
    if (s->n_samples == 1 && s->order > 0) {
        if (!start_up(s, t, h)) return 0;
    } else {
        memset(s->stepped, 0, (size_t)s->n_instances * sizeof(int));
        double lap = clock_start(); /* one clock read a member from here on */
        if (s->gauss_seidel) {
            for (int j = 0; j < s->n_instances;) {
                const int end = s->threads > 1 && s->stage_end ? s->stage_end[j] : j + 1;
                if (end - j > 1) {
                    if (!parallel_stage(s, j, end, t, t_new, h, &lap)) return 0;
                } else if (!step_member(s, s->sequence[j], t, t_new, h, &lap)) {
                    return 0;
                }
                j = end;
            }
        } else {
            for (int j = 0; j < s->n_instances; j++) {
                const int k = s->sequence[j];
                const int ok = s->instances[k].n_inputs == 0 || set_inputs(s, k, t, t_new, s->order);
                lap = clock_stop(s, k, lap);
                if (!ok) return 0;
            }
            for (int j = 0; j < s->n_instances; j++) {
                const int k = s->sequence[j];
                const int ok = do_step(s, k, h) && read_outputs(s, k);
                lap = clock_stop(s, k, lap);
                if (!ok) return 0;
            }
        }
        if (!push_sample(s, t_new)) return 0;
    }
    if (s->n_feeds > 0 && !resolve_feedthrough(s)) return 0;
    *residual = s->n_bonds > 0 && s->n_samples >= 2 ? energy_residual(s, h, bond_energy) : 0.0;
    return 1;
}

/* ---- fixed step ---- */

/* Takes n_steps macro steps of h from the time of instance `clock` (whose time the rows carry).
 * Returns the number of steps completed; fewer than n_steps when an FMI call failed (then
 * failed_instance and failed_call say which). rows: n_steps x (1 + n_columns); residuals: n_steps;
 * bond_energy: n_steps x n_bonds x (residual, transferred). With real_time (else NULL), each step
 * starts at its deadline and its lateness and finish (realtime.c) go to lateness and finish. */
int kernel_run_fixed(Kernel *s, RealTime *real_time, int clock, double h, int n_steps, double *rows,
                     double *residuals, double *bond_energy, double *lateness, double *finish) {
    s->failed_instance = s->failed_call = -1;
    for (int step = 0; step < n_steps; step++) {
        double *bonds = bond_energy + (size_t)step * 2 * (size_t)s->n_bonds;
        double *row = rows + (size_t)step * (size_t)(1 + s->n_columns);
#ifndef KERNEL_WITHOUT_REAL_TIME /* the system FMU (system_fmu.c): an importer's steps, no clock or sockets */
        if (real_time) lateness[step] = realtime_wait(real_time, s->instance_time[clock]);
#endif
        if (!macro_step(s, s->instance_time[clock], h, &residuals[step], bonds)) return step;
        if (!record(s, row, s->instance_time[clock])) return step;
#ifndef KERNEL_WITHOUT_REAL_TIME
        if (real_time) finish[step] = realtime_after_step(s, real_time, s->instance_time[clock], h, row);
#else
        (void)real_time, (void)lateness, (void)finish;
#endif
    }
    return n_steps;
}

/* ---- step control: step doubling and energy ---- */

static void save_memory(Kernel *s, Controller *a, int *n_samples) {
    const size_t n = (size_t)s->n_sample_values, m = (size_t)s->n_inputs_total;
    memcpy(a->saved_time, s->sample_time, 3 * sizeof(double));
    memcpy(a->saved_samples, s->samples, 3 * n * sizeof(double));
    memcpy(a->saved_rates, s->exact_rates, 2 * n * sizeof(double));
    memcpy(a->saved_inputs, s->input_values, m * sizeof(double));
    memcpy(a->saved_inputs + m, s->input_rates, m * sizeof(double));
    memcpy(a->saved_inputs + 2 * m, s->input_curvatures, m * sizeof(double));
    memcpy(a->saved_instance_time, s->instance_time, (size_t)s->n_instances * sizeof(double));
    *n_samples = s->n_samples;
}

static void restore_memory(Kernel *s, Controller *a, int n_samples) {
    const size_t n = (size_t)s->n_sample_values, m = (size_t)s->n_inputs_total;
    memcpy(s->sample_time, a->saved_time, 3 * sizeof(double));
    memcpy(s->samples, a->saved_samples, 3 * n * sizeof(double));
    memcpy(s->exact_rates, a->saved_rates, 2 * n * sizeof(double));
    memcpy(s->input_values, a->saved_inputs, m * sizeof(double));
    memcpy(s->input_rates, a->saved_inputs + m, m * sizeof(double));
    memcpy(s->input_curvatures, a->saved_inputs + 2 * m, m * sizeof(double));
    s->n_samples = n_samples;
}

static int forced(const Controller *a) {
    for (int i = 0; i < a->n_force_reject; i++)
        if (a->force_reject[i] == a->accepted_count) return 1;
    return 0;
}

/* Step doubling from a->t towards t_end: each macro step H once whole and once as two halves from
 * the saved states; accepted when err = max |y_half - y_full| / (atol + rtol |y_half|) <= 1 (or
 * H <= h_min), then a row is recorded (time of instance `clock`), H into accepted_h and the
 * halves' energy residuals into residuals and bond_energy (2 per row). Otherwise every FMU is
 * rolled back. H_next = H min(2, max(0.2, 0.9 err^(-1/(k+2)))) within [h_min, h_max]. Stops at
 * t_end or after max_rows rows. Returns the rows written, or -1 - rows when an FMI call failed. */
int kernel_run_doubling(Kernel *s, Controller *a, int clock, double t_end, int max_rows, double *rows,
                        double *accepted_h, double *residuals, double *bond_energy) {
    s->failed_instance = s->failed_call = -1;
    const size_t n = (size_t)s->n_sample_values, nb = 2 * (size_t)s->n_bonds;
    int written = 0;
    while (written < max_rows && t_end - a->t > 1e-12 * (fabs(t_end) > 1.0 ? fabs(t_end) : 1.0)) {
        const double t = a->t, h = a->h < t_end - t ? a->h : t_end - t;
        int n_samples, ok;
        double r_full, r_half_1, r_half_2;
        double *bonds_1 = bond_energy + 2 * (size_t)written * nb, *bonds_2 = bonds_1 + nb;
        save_memory(s, a, &n_samples);
        if (!save_states(s, s->states)) { free_states(s, s->states); return -1 - written; }
        ok = macro_step(s, t, h, &r_full, NULL);
        if (ok) {
            memcpy(a->full, s->samples + (size_t)(s->n_samples - 1) * n, n * sizeof(double));
            restore_memory(s, a, n_samples);
            ok = restore_states(s, s->states, a->saved_instance_time) && macro_step(s, t, h / 2, &r_half_1, bonds_1) &&
                 macro_step(s, t + h / 2, h / 2, &r_half_2, bonds_2);
        }
        if (!ok) { free_states(s, s->states); return -1 - written; }
        const double *half = s->samples + (size_t)(s->n_samples - 1) * n;
        double error = 0.0;
        int first = 1;
        for (size_t i = 0; i < n; i++) {
            if (isinf(a->atol[i])) continue;
            const double scaled = fabs(half[i] - a->full[i]) / (a->atol[i] + a->rtol * fabs(half[i]));
            if (first || scaled > error || isnan(scaled)) error = scaled;
            first = 0;
        }
        const int force = forced(a);
        double factor = error == 0.0 ? 2.0 : fmin(2.0, fmax(0.2, 0.9 * pow(error, -1.0 / (s->order + 2))));
        if ((error <= 1.0 || h <= a->h_min) && !force) {
            a->t = t + h;
            accepted_h[written] = h;
            residuals[2 * written] = r_half_1;
            residuals[2 * written + 1] = r_half_2;
            if (!record(s, rows + (size_t)written * (size_t)(1 + s->n_columns), s->instance_time[clock])) {
                free_states(s, s->states);
                return -1 - written;
            }
            written++;
            a->accepted_count++;
        } else {
            restore_memory(s, a, n_samples);
            if (!restore_states(s, s->states, a->saved_instance_time)) { free_states(s, s->states); return -1 - written; }
            a->rejected++;
            if (force) { /* the forced retry takes the same step again */
                factor = 1.0;
                for (int i = 0; i < a->n_force_reject; i++)
                    if (a->force_reject[i] == a->accepted_count) a->force_reject[i] = -1;
            }
        }
        const double next = h * factor;
        a->h = fmin(a->h_max, fmax(a->h_min, next));
        free_states(s, s->states);
    }
    return written;
}

/* Energy control (ECCO) from a->t towards t_end: after each step of H, eps = max over the bonds of
 * |dE| / (atol + rtol |E|) (at least 1e-10), and H_next = H safety (1/eps)^k_I (eps_prev/eps)^k_P,
 * limited to [change_min H, change_max H] and [h_min, h_max] (cosim/engine/settings.py:
 * EnergyControl). No rollback. Returns rows written as kernel_run_doubling (one residual and one
 * bond_energy block per row). */
int kernel_run_energy(Kernel *s, Controller *a, int clock, double t_end, int max_rows, double *rows,
                      double *accepted_h, double *residuals, double *bond_energy) {
    s->failed_instance = s->failed_call = -1;
    const size_t nb = 2 * (size_t)s->n_bonds;
    int written = 0;
    while (written < max_rows && t_end - a->t > 1e-12 * (fabs(t_end) > 1.0 ? fabs(t_end) : 1.0)) {
        const double h = a->h < t_end - a->t ? a->h : t_end - a->t;
        double *bonds = bond_energy + (size_t)written * nb;
        if (!macro_step(s, a->t, h, &residuals[written], bonds)) return -1 - written;
        a->t += h;
        accepted_h[written] = h;
        if (!record(s, rows + (size_t)written * (size_t)(1 + s->n_columns), s->instance_time[clock]))
            return -1 - written;
        written++;
        a->accepted_count++;
        double eps = 0.0;
        for (int b = 0; b < s->n_bonds; b++) {
            const double e = fabs(bonds[2 * b]) / (a->atol_energy + a->rtol * bonds[2 * b + 1]);
            if (b == 0 || e > eps || isnan(e)) eps = e;
        }
        eps = fmax(eps, 1e-10);
        const double factor = a->safety * pow(1.0 / eps, a->k_i) * pow(a->previous / eps, a->k_p);
        a->previous = eps;
        a->h = fmin(a->h_max, fmax(a->h_min, h * fmin(a->change_max, fmax(a->change_min, factor))));
    }
    return written;
}

/* ---- the structs' layout, for the ctypes copies (kernel.h) ---- */

static const StructLayout LAYOUT[] = {
    STRUCT_LAYOUT(KernelPort), STRUCT_LAYOUT_FIELD(KernelPort, instance), STRUCT_LAYOUT_FIELD(KernelPort, index),
    STRUCT_LAYOUT(KernelBond), STRUCT_LAYOUT_FIELD(KernelBond, effort_out), STRUCT_LAYOUT_FIELD(KernelBond, effort_in),
    STRUCT_LAYOUT_FIELD(KernelBond, flow_out), STRUCT_LAYOUT_FIELD(KernelBond, flow_in),
    STRUCT_LAYOUT_FIELD(KernelBond, slope_in),
#define I(field) STRUCT_LAYOUT_FIELD(KernelInstance, field)
    STRUCT_LAYOUT(KernelInstance), I(component), I(set_real), I(get_real), I(set_input_derivatives),
    I(get_output_derivatives), I(do_step), I(get_state), I(set_state), I(free_state), I(n_outputs), I(output_offset),
    I(output_vrs), I(n_inputs), I(input_offset), I(input_vrs), I(feed_source), I(feed_index), I(rate_order),
    I(interpolating), I(extrapolating), I(n_record), I(record_offset), I(record_vrs),
#undef I
#define K(field) STRUCT_LAYOUT_FIELD(Kernel, field)
    STRUCT_LAYOUT(Kernel), K(n_instances), K(instances), K(sequence), K(gauss_seidel), K(order), K(keep),
    K(n_samples), K(sample_time), K(samples), K(n_sample_values), K(exact_rates), K(new_values), K(stepped),
    K(n_inputs_total), K(input_values), K(input_rates), K(input_curvatures), K(n_bonds), K(bonds), K(n_columns),
    K(column_of), K(record_scratch), K(instance_time), K(fmi_seconds), K(order_one), K(order_two), K(states),
    K(startup_states), K(guess), K(saved_time), K(failed_instance), K(failed_call), K(threads), K(stage_end),
    K(helper), K(n_feeds), K(feeds), K(feed_indices), K(feed_vrs), K(feed_values), K(feed_rates),
#undef K
    STRUCT_LAYOUT(KernelFeed), STRUCT_LAYOUT_FIELD(KernelFeed, instance), STRUCT_LAYOUT_FIELD(KernelFeed, first),
    STRUCT_LAYOUT_FIELD(KernelFeed, n_inputs), STRUCT_LAYOUT_FIELD(KernelFeed, n_outputs),
#define C(field) STRUCT_LAYOUT_FIELD(Controller, field)
    STRUCT_LAYOUT(Controller), C(h), C(h_min), C(h_max), C(rtol), C(atol), C(atol_energy), C(k_i), C(k_p),
    C(previous), C(safety), C(change_min), C(change_max), C(t), C(rejected), C(accepted_count), C(force_reject), C(n_force_reject), C(saved_time),
    C(saved_samples), C(saved_rates), C(saved_inputs), C(saved_instance_time), C(full),
#undef C
#define R(field) STRUCT_LAYOUT_FIELD(RealTime, field)
    STRUCT_LAYOUT(RealTime), R(factor), R(origin), R(t0), R(waited), R(stream_fd), R(stream_every), R(stream_countdown),
    R(n_stream), R(stream_columns), R(stream_sequence), R(packet), R(stream_failed), R(listen_fd), R(live_instance),
    R(n_live), R(live_index), R(live_column), R(live_rate_index), R(live_rate_column), R(rate_max), R(acceleration_max), R(neutral), R(late_after),
    R(watchdog), R(admissible), R(admissible_context), R(guard), R(recover), R(guard_context), R(guard_source), R(live_target), R(key), R(key_size), R(live),
    R(target_time), R(last_good), R(live_active), R(watchdog_engaged), R(owned), R(owner_size), R(owner_address),
    R(owner_session), R(live_sequence), R(counts), R(guard_counts), R(watchdog_time), R(received), R(receive_size),
#undef R
    STRUCT_LAYOUT_END};

const StructLayout *kernel_layout(void) { return LAYOUT; }
