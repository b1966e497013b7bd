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

enum { FMI2_ERROR = 3 };
enum { CALL_SET_REAL = 1, CALL_SET_INPUT_DERIVATIVES, CALL_DO_STEP, CALL_GET_REAL, CALL_GET_OUTPUT_DERIVATIVES };

typedef struct {
    void *component;
    SetRealFn set_real;
    GetRealFn get_real;
    SetDerivativesFn set_input_derivatives;
    GetDerivativesFn get_output_derivatives;
    DoStepFn do_step;
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

/* Takes n_steps macro steps of h from the time of instance `clock` (whose time the rows carry).
 * Returns the number of steps completed; fewer than n_steps when an FMI call failed (then
 * failed_instance and failed_call say which). rows: n_steps x (1 + n_columns); residuals: n_steps;
 * bond_energy: n_steps x n_bonds x (residual, transferred), or NULL. */
int cosim_loop_run(LoopSetup *s, int clock, double h, int n_steps, double *rows, double *residuals,
                   double *bond_energy) {
    s->failed_instance = s->failed_call = -1;
    for (int step = 0; step < n_steps; step++) {
        const double t = s->instance_time[clock], t_new = t + h;
        memset(s->stepped, 0, (size_t)s->n_instances * sizeof(int));
        if (s->gauss_seidel) {
            for (int j = 0; j < s->n_instances; j++) {
                const int k = s->sequence[j];
                if (s->instances[k].n_inputs > 0 && !set_inputs(s, k, t, t_new)) return step;
                if (!do_step(s, k, h) || !read_outputs(s, k)) return step;
            }
        } else {
            for (int j = 0; j < s->n_instances; j++) {
                const int k = s->sequence[j];
                if (s->instances[k].n_inputs > 0 && !set_inputs(s, k, t, t_new)) return step;
            }
            for (int j = 0; j < s->n_instances; j++)
                if (!do_step(s, s->sequence[j], h)) return step;
            for (int j = 0; j < s->n_instances; j++)
                if (!read_outputs(s, s->sequence[j])) return step;
        }
        if (!push_sample(s, t_new)) return step;
        residuals[step] = s->n_bonds > 0
                              ? energy_residual(s, h, bond_energy ? bond_energy + (size_t)step * 2 * (size_t)s->n_bonds : NULL)
                              : 0.0;
        if (!record(s, rows + (size_t)step * (size_t)(1 + s->n_columns), s->instance_time[clock])) return step;
    }
    return n_steps;
}
