/* trajectory: the signals of a scene as an FMU, so that a scene is FMUs and connections only and
 * runs unchanged in any FMI tool.
 *
 * Each pose coordinate q (x, y, z, roll, pitch, yaw) is
 *
 *   q(t) = offset + sum_k A_k sin(2 pi f_k t + phase_k)         3 sines
 *                 + sum_k height_k [t >= time_k]                2 steps
 *                 + sum_k slope_k (min(t, end_k) - start_k)^+   2 ramps
 *                 + table(t)                                    its column of table.file, if any
 *
 * with its rate q' as the output pose_ref_rate.* (for masters that give no input derivatives, wired
 * to the mechanics' pose_ref_rate.*), and each wrench component is the sum of its two pulses (value for start <= t <= end; edges within
 * 1e-9 relative count as reached, for communication points' round-off). The FMU has
 * no state: outputs are evaluated at the communication point, and fmi2GetRealOutputDerivatives gives
 * their exact first and second time derivatives (zero across steps and pulses; the rate's are the
 * pose's second and third), so that a master
 * extrapolating its inputs over a macro step never rings on a step.
 */
#include "fmu_common.h"
#include "table.h"

#include <math.h>
#include <string.h>

static const double PI = 3.14159265358979323846;

#define N_DOF 6
static const char *const DOF_NAMES[N_DOF] = {"x", "y", "z", "roll", "pitch", "yaw"};

/* The value references of one coordinate's signal. */
typedef struct {
    int output, rate_output, offset, sine[3][3] /* amplitude, frequency, phase */, step[2][2] /* time, height */,
        ramp[2][3] /* start, end, slope */;
} DofSignal;

#define SINE_REFS(dof, k) {VR_##dof##_sine##k##_amplitude, VR_##dof##_sine##k##_frequency, VR_##dof##_sine##k##_phase}
#define STEP_REFS(dof, k) {VR_##dof##_step##k##_time, VR_##dof##_step##k##_height}
#define RAMP_REFS(dof, k) {VR_##dof##_ramp##k##_start, VR_##dof##_ramp##k##_end, VR_##dof##_ramp##k##_slope}
#define DOF_REFS(dof)                                                                              \
    {VR_pose_ref_##dof, VR_pose_ref_rate_##dof, VR_##dof##_offset, {SINE_REFS(dof, 1), SINE_REFS(dof, 2), SINE_REFS(dof, 3)}, \
     {STEP_REFS(dof, 1), STEP_REFS(dof, 2)}, {RAMP_REFS(dof, 1), RAMP_REFS(dof, 2)}}
static const DofSignal DOFS[N_DOF] = {DOF_REFS(x), DOF_REFS(y), DOF_REFS(z), DOF_REFS(roll), DOF_REFS(pitch), DOF_REFS(yaw)};

/* One wrench component: its base- and platform-frame outputs and its two pulses (value, start,
 * end, frame). */
typedef struct { int output, body_output, pulse[2][4]; } WrenchSignal;
#define PULSE_REFS(kind, axis, k)                                                                  \
    {VR_load_##kind##_##axis##_pulse##k##_value, VR_load_##kind##_##axis##_pulse##k##_start,      \
     VR_load_##kind##_##axis##_pulse##k##_end, VR_load_##kind##_##axis##_pulse##k##_frame}
#define WRENCH_REFS(kind, axis) \
    {VR_load_##kind##_##axis, VR_load_body_##kind##_##axis, {PULSE_REFS(kind, axis, 1), PULSE_REFS(kind, axis, 2)}}
static const WrenchSignal WRENCH[6] = {WRENCH_REFS(force, x),  WRENCH_REFS(force, y),  WRENCH_REFS(force, z),
                                       WRENCH_REFS(torque, x), WRENCH_REFS(torque, y), WRENCH_REFS(torque, z)};

static void free_table(FmuInstance *fmu, void *data) { fmu_table_free(fmu, (FmuTable *)data); }

/* ---- the signals ---- */

/* Communication points accumulate round-off (1000 steps of 1 ms end near, not at, 1 s): an edge
 * within this of t counts as reached, so a step or pulse edge on a communication point is hit. */
static double edge_tolerance(double t) { return 1e-9 * (fabs(t) > 1.0 ? fabs(t) : 1.0); }

/* Value and first three time derivatives of coordinate d at t. */
static void pose_at(FmuInstance *fmu, int d, double t, double out[4]) {
    const DofSignal *q = &DOFS[d];
    out[0] = *fmu_real(fmu, q->offset);
    out[1] = out[2] = out[3] = 0.0;
    for (int k = 0; k < 3; k++) {
        const double amplitude = *fmu_real(fmu, q->sine[k][0]), w = 2.0 * PI * *fmu_real(fmu, q->sine[k][1]);
        const double angle = w * t + *fmu_real(fmu, q->sine[k][2]);
        out[0] += amplitude * sin(angle);
        out[1] += amplitude * w * cos(angle);
        out[2] -= amplitude * w * w * sin(angle);
        out[3] -= amplitude * w * w * w * cos(angle);
    }
    for (int k = 0; k < 2; k++)
        if (t >= *fmu_real(fmu, q->step[k][0]) - edge_tolerance(t)) out[0] += *fmu_real(fmu, q->step[k][1]);
    for (int k = 0; k < 2; k++) {
        const double start = *fmu_real(fmu, q->ramp[k][0]), end = *fmu_real(fmu, q->ramp[k][1]);
        const double slope = *fmu_real(fmu, q->ramp[k][2]);
        if (t > start) out[0] += slope * ((t < end ? t : end) - start);
        if (t > start && t < end) out[1] += slope;
    }
    const FmuTable *table = (const FmuTable *)fmu->model_data;
    if (table && table->column_of[d] >= 0) {
        double column[4];
        fmu_table_at(table, table->column_of[d], fmu->s.v.table_interpolation, t, column);
        for (int i = 0; i < 4; i++) out[i] += column[i];
    }
}

/* The sum at t of a wrench component's pulses given in `frame` (1 base, 2 platform). */
static double wrench_at(FmuInstance *fmu, int component, double t, int frame) {
    double value = 0.0;
    for (int k = 0; k < 2; k++) {
        const int *pulse = WRENCH[component].pulse[k];
        if (*fmu_integer(fmu, pulse[3]) != frame) continue;
        if (t >= *fmu_real(fmu, pulse[1]) - edge_tolerance(t) && t <= *fmu_real(fmu, pulse[2]) + edge_tolerance(t))
            value += *fmu_real(fmu, pulse[0]);
    }
    return value;
}

/* ---- hooks ---- */

fmi2Status model_validate(FmuInstance *fmu) {
    int errors = 0;
    for (int d = 0; d < N_DOF; d++)
        for (int k = 0; k < 2; k++)
            if (*fmu_real(fmu, DOFS[d].ramp[k][1]) < *fmu_real(fmu, DOFS[d].ramp[k][0]))
                errors += fmu_reject(fmu, DOFS[d].ramp[k][1], "must not be before the ramp's start");
    for (int c = 0; c < 6; c++)
        for (int k = 0; k < 2; k++)
            if (*fmu_real(fmu, WRENCH[c].pulse[k][2]) < *fmu_real(fmu, WRENCH[c].pulse[k][1]))
                errors += fmu_reject(fmu, WRENCH[c].pulse[k][2], "must not be before the pulse's start");
    const char *path = fmu->s.v.table_file.text;
    const FmuTable *loaded = (const FmuTable *)fmu->model_data;
    if (!path[0]) {
        fmu_set_model_data(fmu, NULL, NULL);
    } else if (!loaded || strcmp(loaded->path, path) != 0) {
        FmuTable *table = fmu_table_read(fmu, VR_table_file, path, DOF_NAMES, N_DOF);
        if (!table) errors++;
        fmu_set_model_data(fmu, table, table ? free_table : NULL);
    }
    return errors ? fmi2Error : fmi2OK;
}

void model_initialize(FmuInstance *fmu) { (void)fmu; }

/* ---- Model Exchange (fmi2_me.c): no states; each load pulse's start and end a time event ---- */

const char *model_exchange_refusal(const FmuInstance *fmu) {
    (void)fmu;
    return NULL;
}

int model_derivatives(FmuInstance *fmu, double *dxdt) {
    (void)fmu, (void)dxdt;
    return 0;
}

fmi2Status model_completed_integrator_step(FmuInstance *fmu) {
    (void)fmu;
    return fmi2OK;
}

/* The pulses are functions of time alone: an event changes the wrench where it is one's edge. */
int model_time_event(FmuInstance *fmu) {
    const double t = fmu->s.time;
    for (int c = 0; c < 6; c++)
        for (int k = 0; k < 2; k++) {
            const int *pulse = WRENCH[c].pulse[k];
            if (*fmu_real(fmu, pulse[0]) == 0.0) continue;
            for (int edge = 1; edge <= 2; edge++)
                if (fabs(*fmu_real(fmu, pulse[edge]) - t) <= edge_tolerance(t)) return 1;
        }
    return 0;
}

double model_next_time_event(FmuInstance *fmu) {
    const double t = fmu->s.time;
    double next = INFINITY;
    for (int c = 0; c < 6; c++)
        for (int k = 0; k < 2; k++) {
            const int *pulse = WRENCH[c].pulse[k];
            if (*fmu_real(fmu, pulse[0]) == 0.0) continue;
            for (int edge = 1; edge <= 2; edge++) {
                const double at = *fmu_real(fmu, pulse[edge]);
                if (at > t + edge_tolerance(t) && at < next) next = at;
            }
        }
    return next;
}

fmi2Status model_do_step(FmuInstance *fmu, double h) {
    (void)fmu; (void)h; /* the outputs are functions of time; the layer advances it */
    return fmi2OK;
}

void model_compute_outputs(FmuInstance *fmu) {
    const double t = fmu->s.time;
    for (int d = 0; d < N_DOF; d++) {
        double q[4];
        pose_at(fmu, d, t, q);
        *fmu_real(fmu, DOFS[d].output) = q[0];
        *fmu_real(fmu, DOFS[d].rate_output) = q[1];
        for (int k = 0; k < 3; k++) fmu->s.internal.derivatives[d][k] = q[k + 1];
    }
    for (int c = 0; c < 6; c++) {
        *fmu_real(fmu, WRENCH[c].output) = wrench_at(fmu, c, t, 1);
        *fmu_real(fmu, WRENCH[c].body_output) = wrench_at(fmu, c, t, 2);
    }
    const FmuTable *table = (const FmuTable *)fmu->model_data;
    fmu->s.v.table_rows = table ? table->rows : 0;
}

double model_output_derivative(FmuInstance *fmu, int vr, int order) {
    /* the layer has refreshed the outputs (model_compute_outputs) at the current time */
    for (int d = 0; d < N_DOF; d++) {
        if (DOFS[d].output == vr) return fmu->s.internal.derivatives[d][order - 1];
        if (DOFS[d].rate_output == vr) return fmu->s.internal.derivatives[d][order];
    }
    return 0.0; /* the wrench is piecewise constant */
}
