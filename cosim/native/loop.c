/* The master's inner loop in C: fixed macro steps of cosim.coupling's Jacobi or Gauss-Seidel with
 * input extrapolation of order 0..2, energy residuals of the power bonds and recording of selected
 * outputs, calling the FMUs' fmi2 functions directly.
 *
 * It performs, operation for operation, what cosim/coupling.py does in Python (the tests compare
 * the two bit for bit), so the Python code stays the reference and the readable description; this
 * file only takes the interpreter off the hot path. Python sets everything up (instances, history,
 * connections) and hands it over in a LoopSetup; see cosim/native.py.
 */
#define _POSIX_C_SOURCE 199309L /* clock_gettime */
#include <math.h>
#include <stddef.h>
#include <string.h>
#include <time.h>

typedef int (*SetRealFn)(void *, const unsigned *, size_t, const double *);
typedef int (*GetRealFn)(void *, const unsigned *, size_t, double *);
typedef int (*SetDerivativesFn)(void *, const unsigned *, size_t, const int *, const double *);
typedef int (*GetDerivativesFn)(void *, const unsigned *, size_t, const int *, double *);
typedef int (*DoStepFn)(void *, double, double, int);
typedef int (*GetStateFn)(void *, void **);
typedef int (*SetStateFn)(void *, void *);
typedef int (*FreeStateFn)(void *, void **);

enum { FMI2_ERROR = 3 };
enum { CALL_SET_REAL = 1, CALL_SET_INPUT_DERIVATIVES, CALL_DO_STEP, CALL_GET_REAL, CALL_GET_OUTPUT_DERIVATIVES,
       CALL_GET_STATE, CALL_SET_STATE, CALL_FREE_STATE };

typedef struct {
    void *component;
    SetRealFn set_real;
    GetRealFn get_real;
    SetDerivativesFn set_input_derivatives;
    GetDerivativesFn get_output_derivatives;
    DoStepFn do_step;
    GetStateFn get_state;
    SetStateFn set_state;
    FreeStateFn free_state;
    int n_outputs, output_offset;     /* its coupled outputs, at output_offset in a sample */
    const unsigned *output_vrs;
    int n_inputs, input_offset;       /* its coupled inputs, at input_offset in the input arrays */
    const unsigned *input_vrs;
    const int *feed_source;           /* per input: the source instance */
    const int *feed_index;            /* per input: the index in the source's outputs */
    int rate_order;                   /* output derivatives it provides (0: none; at most 2) */
    int n_record, record_offset;      /* outputs recorded each step, at record_offset in the scratch */
    const unsigned *record_vrs;
} LoopInstance;

typedef struct {
    int n_instances;
    LoopInstance *instances;
    const int *sequence;              /* stepping order (n_instances entries) */
    int gauss_seidel, order;
    /* history: n_samples (<= keep) samples, oldest first; each holds every instance's outputs */
    int keep, n_samples;
    double *sample_time;              /* [3] */
    double *samples;                  /* [3][n_sample_values] */
    int n_sample_values;
    double *exact_rates;              /* [2][n_sample_values]: output derivatives at the latest sample */
    double *new_values;               /* [n_sample_values] scratch: outputs at t + h */
    int *stepped;                     /* [n_instances] scratch */
    double *input_values, *input_rates, *input_curvatures; /* as set over the current step */
    int n_bonds;
    const int *bonds;                 /* per bond 8 ints: effort (source, index), (target, index); flow (same) */
    int n_columns;
    const int *column_of;             /* per recorded column: index in the record scratch */
    double *record_scratch;
    double *instance_time;            /* [n_instances] each instance's time, advanced as FmuInstance.time */
    double *fmi_seconds;              /* [n_instances] accumulated time inside its FMI calls */
    const int *order_one, *order_two; /* arrays of 1s and 2s, long enough for any call */
    int failed_instance, failed_call; /* set when a call fails */
} LoopSetup;

static double now(void) {
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

#define FMI_CALL(setup, k, code, expression)                                                      \
    do {                                                                                           \
        const double started_ = now();                                                             \
        const int status_ = (expression);                                                          \
        (setup)->fmi_seconds[k] += now() - started_;                                               \
        if (status_ >= FMI2_ERROR) {                                                               \
            (setup)->failed_instance = (k);                                                        \
            (setup)->failed_call = (code);                                                         \
            return 0;                                                                              \
        }                                                                                          \
    } while (0)

/* polynomial_at of cosim/coupling.py: value, rate and curvature at t of the polynomial through the
 * n samples (times[i], y[i]), truncated to `order`. */
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

/* _set_inputs: instance k's inputs over [t, t + h] from its sources. */
static int set_inputs(LoopSetup *s, int k, double t, double t_new) {
    const LoopInstance *in = &s->instances[k];
    const int order = s->order, latest = s->n_samples - 1;
    for (int i = 0; i < in->n_inputs; i++) {
        const int source = in->feed_source[i];
        const int at = s->instances[source].output_offset + in->feed_index[i];
        double p[3];
        if (s->instances[source].rate_order > 0) {
            const int given = order < s->instances[source].rate_order ? order : s->instances[source].rate_order;
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
        s->input_values[in->input_offset + i] = p[0];
        s->input_rates[in->input_offset + i] = p[1];
        s->input_curvatures[in->input_offset + i] = p[2];
    }
    FMI_CALL(s, k, CALL_SET_REAL, in->set_real(in->component, in->input_vrs, (size_t)in->n_inputs,
                                               s->input_values + in->input_offset));
    if (order >= 1)
        FMI_CALL(s, k, CALL_SET_INPUT_DERIVATIVES,
                 in->set_input_derivatives(in->component, in->input_vrs, (size_t)in->n_inputs, s->order_one,
                                           s->input_rates + in->input_offset));
    if (order >= 2)
        FMI_CALL(s, k, CALL_SET_INPUT_DERIVATIVES,
                 in->set_input_derivatives(in->component, in->input_vrs, (size_t)in->n_inputs, s->order_two,
                                           s->input_curvatures + in->input_offset));
    return 1;
}

static int do_step(LoopSetup *s, int k, double h) {
    const LoopInstance *in = &s->instances[k];
    FMI_CALL(s, k, CALL_DO_STEP, in->do_step(in->component, s->instance_time[k], h, 0));
    s->instance_time[k] += h;
    return 1;
}

static int read_outputs(LoopSetup *s, int k) {
    const LoopInstance *in = &s->instances[k];
    if (in->n_outputs == 0) return 1;
    FMI_CALL(s, k, CALL_GET_REAL, in->get_real(in->component, in->output_vrs, (size_t)in->n_outputs,
                                               s->new_values + in->output_offset));
    s->stepped[k] = 1;
    return 1;
}

/* History.push: the new sample, and the exact output derivatives of the sources that give them. */
static int push_sample(LoopSetup *s, double t_new) {
    if (s->n_samples == s->keep) {
        memmove(s->sample_time, s->sample_time + 1, (size_t)(s->keep - 1) * sizeof(double));
        memmove(s->samples, s->samples + s->n_sample_values,
                (size_t)(s->keep - 1) * (size_t)s->n_sample_values * sizeof(double));
        s->n_samples--;
    }
    s->sample_time[s->n_samples] = t_new;
    memcpy(s->samples + s->n_samples * s->n_sample_values, s->new_values, (size_t)s->n_sample_values * sizeof(double));
    s->n_samples++;
    for (int k = 0; k < s->n_instances; k++) {
        const LoopInstance *in = &s->instances[k];
        for (int order = 1; order <= in->rate_order; order++)
            FMI_CALL(s, k, CALL_GET_OUTPUT_DERIVATIVES,
                     in->get_output_derivatives(in->component, in->output_vrs, (size_t)in->n_outputs,
                                                order == 1 ? s->order_one : s->order_two,
                                                s->exact_rates + (order - 1) * s->n_sample_values + in->output_offset));
    }
    return 1;
}

/* _energy_residual: the largest |energy residual| of the bonds over the step just taken; per bond,
 * the residual and the energy transferred into bond_energy (2 per bond) if it is not NULL. */
static double energy_residual(const LoopSetup *s, double h, double *bond_energy) {
    const double *before = s->samples + (s->n_samples - 2) * s->n_sample_values;
    const double *after = s->samples + (s->n_samples - 1) * s->n_sample_values;
    double largest = 0.0;
    for (int b = 0; b < s->n_bonds; b++) {
        const int *bond = s->bonds + 8 * b;
        const int effort_out = s->instances[bond[0]].output_offset + bond[1];
        const int effort_in = s->instances[bond[2]].input_offset + bond[3];
        const int flow_out = s->instances[bond[4]].output_offset + bond[5];
        const int flow_in = s->instances[bond[6]].input_offset + bond[7];
#define SEEN(i, dt) (s->input_values[i] + s->input_rates[i] * (dt) + 0.5 * s->input_curvatures[i] * (dt) * (dt))
        const double given = 0.5 * h * (before[effort_out] * SEEN(flow_in, 0.0) + after[effort_out] * SEEN(flow_in, h));
        const double taken = 0.5 * h * (SEEN(effort_in, 0.0) * before[flow_out] + SEEN(effort_in, h) * after[flow_out]);
#undef SEEN
        const double residual = fabs(given - taken);
        if (residual > largest) largest = residual;
        if (bond_energy) {
            bond_energy[2 * b] = given - taken;
            bond_energy[2 * b + 1] = 0.5 * (fabs(given) + fabs(taken));
        }
    }
    return largest;
}

static int record(LoopSetup *s, double *row, double t) {
    for (int k = 0; k < s->n_instances; k++) {
        const LoopInstance *in = &s->instances[k];
        if (in->n_record > 0)
            FMI_CALL(s, k, CALL_GET_REAL, in->get_real(in->component, in->record_vrs, (size_t)in->n_record,
                                                       s->record_scratch + in->record_offset));
    }
    row[0] = t;
    for (int c = 0; c < s->n_columns; c++) row[1 + c] = s->record_scratch[s->column_of[c]];
    return 1;
}

/* One macro step of the algorithm from t (the master's time, as in cosim/coupling.py) to t + h:
 * the sweep, the new history sample, and the bonds' energy residual (largest into *residual, per
 * bond into bond_energy if not NULL). Returns 0 when an FMI call failed. */
static int macro_step(LoopSetup *s, double t, double h, double *residual, double *bond_energy) {
    const double t_new = t + h;
    memset(s->stepped, 0, (size_t)s->n_instances * sizeof(int));
    if (s->gauss_seidel) {
        for (int j = 0; j < s->n_instances; j++) {
            const int k = s->sequence[j];
            if (s->instances[k].n_inputs > 0 && !set_inputs(s, k, t, t_new)) return 0;
            if (!do_step(s, k, h) || !read_outputs(s, k)) return 0;
        }
    } else {
        for (int j = 0; j < s->n_instances; j++) {
            const int k = s->sequence[j];
            if (s->instances[k].n_inputs > 0 && !set_inputs(s, k, t, t_new)) return 0;
        }
        for (int j = 0; j < s->n_instances; j++)
            if (!do_step(s, s->sequence[j], h)) return 0;
        for (int j = 0; j < s->n_instances; j++)
            if (!read_outputs(s, s->sequence[j])) return 0;
    }
    if (!push_sample(s, t_new)) return 0;
    *residual = s->n_bonds > 0 ? energy_residual(s, h, bond_energy) : 0.0;
    return 1;
}

/* Takes n_steps macro steps of h from the time of instance `clock` (whose time the rows carry).
 * Returns the number of steps completed; fewer than n_steps when an FMI call failed (then
 * failed_instance and failed_call say which). rows: n_steps x (1 + n_columns); residuals: n_steps;
 * bond_energy: n_steps x n_bonds x (residual, transferred), or NULL. */
int cosim_loop_run(LoopSetup *s, int clock, double h, int n_steps, double *rows, double *residuals,
                   double *bond_energy) {
    s->failed_instance = s->failed_call = -1;
    for (int step = 0; step < n_steps; step++) {
        double *bonds = bond_energy ? bond_energy + (size_t)step * 2 * (size_t)s->n_bonds : NULL;
        if (!macro_step(s, s->instance_time[clock], h, &residuals[step], bonds)) return step;
        if (!record(s, rows + (size_t)step * (size_t)(1 + s->n_columns), s->instance_time[clock])) return step;
    }
    return n_steps;
}

/* ---- step doubling (cosim.coupling.AdaptiveStep, operation for operation) ---- */

typedef struct {
    double h, h_min, h_max, rtol;
    const double *atol;     /* per sample value; +inf where the error is not measured */
    double t;               /* the controller's time, advanced by each accepted H */
    int rejected;           /* added to */
    /* scratch, sized by Python: */
    void **states;          /* n_instances saved FMU states */
    double *saved_time, *saved_samples, *saved_rates, *saved_inputs, *saved_instance_time, *full;
} AdaptiveSetup;

static void save_memory(LoopSetup *s, AdaptiveSetup *a, int *n_samples) {
    const size_t n = (size_t)s->n_sample_values;
    memcpy(a->saved_time, s->sample_time, 3 * sizeof(double));
    memcpy(a->saved_samples, s->samples, 3 * n * sizeof(double));
    memcpy(a->saved_rates, s->exact_rates, 2 * n * sizeof(double));
    *n_samples = s->n_samples;
}

static void restore_memory(LoopSetup *s, AdaptiveSetup *a, int n_samples) {
    const size_t n = (size_t)s->n_sample_values;
    memcpy(s->sample_time, a->saved_time, 3 * sizeof(double));
    memcpy(s->samples, a->saved_samples, 3 * n * sizeof(double));
    memcpy(s->exact_rates, a->saved_rates, 2 * n * sizeof(double));
    s->n_samples = n_samples;
}

static int save_states(LoopSetup *s, AdaptiveSetup *a, int n_inputs_total) {
    for (int k = 0; k < s->n_instances; k++) {
        const LoopInstance *in = &s->instances[k];
        a->states[k] = NULL;
        FMI_CALL(s, k, CALL_GET_STATE, in->get_state(in->component, &a->states[k]));
    }
    memcpy(a->saved_instance_time, s->instance_time, (size_t)s->n_instances * sizeof(double));
    memcpy(a->saved_inputs, s->input_values, (size_t)n_inputs_total * sizeof(double));
    memcpy(a->saved_inputs + n_inputs_total, s->input_rates, (size_t)n_inputs_total * sizeof(double));
    memcpy(a->saved_inputs + 2 * n_inputs_total, s->input_curvatures, (size_t)n_inputs_total * sizeof(double));
    return 1;
}

static int restore_states(LoopSetup *s, AdaptiveSetup *a, int n_inputs_total) {
    for (int k = 0; k < s->n_instances; k++) {
        const LoopInstance *in = &s->instances[k];
        FMI_CALL(s, k, CALL_SET_STATE, in->set_state(in->component, a->states[k]));
    }
    memcpy(s->instance_time, a->saved_instance_time, (size_t)s->n_instances * sizeof(double));
    memcpy(s->input_values, a->saved_inputs, (size_t)n_inputs_total * sizeof(double));
    memcpy(s->input_rates, a->saved_inputs + n_inputs_total, (size_t)n_inputs_total * sizeof(double));
    memcpy(s->input_curvatures, a->saved_inputs + 2 * n_inputs_total, (size_t)n_inputs_total * sizeof(double));
    return 1;
}

static void free_states(LoopSetup *s, AdaptiveSetup *a) {
    for (int k = 0; k < s->n_instances; k++) {
        const LoopInstance *in = &s->instances[k];
        if (a->states[k]) in->free_state(in->component, &a->states[k]);
        a->states[k] = NULL;
    }
}

/* Step doubling from a->t towards t_end: each macro step H once whole and once as two halves from
 * the saved states; accepted when the scaled difference of the outputs is <= 1 (or H <= h_min),
 * then a row is recorded (time of instance `clock`), H into accepted_h and the halves' energy
 * residuals into residuals (2 per row). Stops at t_end or after max_rows rows. Returns the rows
 * written, or -1 - rows when an FMI call failed (failed_instance and failed_call say which). */
int cosim_loop_adaptive(LoopSetup *s, AdaptiveSetup *a, int clock, double t_end, int max_rows, int n_inputs_total,
                        double *rows, double *accepted_h, double *residuals) {
    s->failed_instance = s->failed_call = -1;
    const size_t n = (size_t)s->n_sample_values;
    int written = 0;
    while (written < max_rows && t_end - a->t > 1e-12 * (fabs(t_end) > 1.0 ? fabs(t_end) : 1.0)) {
        const double t = a->t, h = a->h < t_end - t ? a->h : t_end - t;
        int n_samples, ok = 1;
        double r_full, r_half_1, r_half_2;
        save_memory(s, a, &n_samples);
        if (!save_states(s, a, n_inputs_total)) { free_states(s, a); return -1 - written; }
        ok = macro_step(s, t, h, &r_full, NULL);
        if (ok) {
            memcpy(a->full, s->samples + (size_t)(s->n_samples - 1) * n, n * sizeof(double));
            restore_memory(s, a, n_samples);
            ok = restore_states(s, a, n_inputs_total) && macro_step(s, t, h / 2, &r_half_1, NULL) &&
                 macro_step(s, t + h / 2, h / 2, &r_half_2, NULL);
        }
        if (!ok) { free_states(s, a); return -1 - written; }
        const double *half = s->samples + (size_t)(s->n_samples - 1) * n;
        double error = 0.0;
        int first = 1;
        for (size_t i = 0; i < n; i++) {
            if (isinf(a->atol[i])) continue;
            const double scaled = fabs(half[i] - a->full[i]) / (a->atol[i] + a->rtol * fabs(half[i]));
            if (first || scaled > error) error = scaled;
            first = 0;
        }
        if (error <= 1.0 || h <= a->h_min) {
            a->t = t + h;
            accepted_h[written] = h;
            residuals[2 * written] = r_half_1;
            residuals[2 * written + 1] = r_half_2;
            if (!record(s, rows + (size_t)written * (size_t)(1 + s->n_columns), s->instance_time[clock])) {
                free_states(s, a);
                return -1 - written;
            }
            written++;
        } else {
            restore_memory(s, a, n_samples);
            if (!restore_states(s, a, n_inputs_total)) { free_states(s, a); return -1 - written; }
            a->rejected++;
        }
        const double factor = error == 0.0 ? 2.0 : fmin(2.0, fmax(0.2, 0.9 * pow(error, -1.0 / (s->order + 2))));
        const double next = h * factor;
        a->h = a->h_max < (a->h_min > next ? a->h_min : next) ? a->h_max : (a->h_min > next ? a->h_min : next);
        free_states(s, a);
    }
    return written;
}
