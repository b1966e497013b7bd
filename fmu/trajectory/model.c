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
 * and each wrench component is the sum of its two pulses (value for start <= t <= end; edges within
 * 1e-9 relative count as reached, for communication points' round-off). The FMU has
 * no state: outputs are evaluated at the communication point, and fmi2GetRealOutputDerivatives gives
 * their exact first and second time derivatives (zero across steps and pulses), so that a master
 * extrapolating its inputs over a macro step never rings on a step.
 */
#define _POSIX_C_SOURCE 200809L /* stat: a table must be a regular file */
#include "fmu_common.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

static const double PI = 3.14159265358979323846;

#define N_DOF 6
static const char *const DOF_NAMES[N_DOF] = {"x", "y", "z", "roll", "pitch", "yaw"};

/* The value references of one coordinate's signal. */
typedef struct {
    int output, offset, sine[3][3] /* amplitude, frequency, phase */, step[2][2] /* time, height */,
        ramp[2][3] /* start, end, slope */;
} DofSignal;

#define SINE_REFS(dof, k) {VR_##dof##_sine##k##_amplitude, VR_##dof##_sine##k##_frequency, VR_##dof##_sine##k##_phase}
#define STEP_REFS(dof, k) {VR_##dof##_step##k##_time, VR_##dof##_step##k##_height}
#define RAMP_REFS(dof, k) {VR_##dof##_ramp##k##_start, VR_##dof##_ramp##k##_end, VR_##dof##_ramp##k##_slope}
#define DOF_REFS(dof)                                                                              \
    {VR_pose_ref_##dof, VR_##dof##_offset, {SINE_REFS(dof, 1), SINE_REFS(dof, 2), SINE_REFS(dof, 3)}, \
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

/* ---- the table (model data: read once from table.file, outside the FMU state) ---- */

typedef struct {
    char path[FMU_TEXT_MAX];  /* the file it was read from */
    int rows, columns;        /* columns besides time */
    int column_of[N_DOF];     /* column of each coordinate, or -1 */
    double *time;             /* rows */
    double *values, *slopes;  /* rows x columns, row-major; slopes for the cubic Hermite */
} Table;

static void free_table(FmuInstance *fmu, void *data) {
    Table *table = (Table *)data;
    fmu_free(fmu, table->time);
    fmu_free(fmu, table->values);
    fmu_free(fmu, table->slopes);
    fmu_free(fmu, table);
}

static char *trim(char *s) {
    while (*s == ' ' || *s == '\t') s++;
    char *end = s + strlen(s);
    while (end > s && (end[-1] == ' ' || end[-1] == '\t' || end[-1] == '\r' || end[-1] == '\n')) *--end = '\0';
    return s;
}

/* The next comma-separated field of *cursor (NULL at the end); re-entrant, unlike strtok. */
static char *next_field(char **cursor) {
    if (!*cursor) return NULL;
    char *field = *cursor, *comma = strchr(field, ',');
    if (comma) { *comma = '\0'; *cursor = comma + 1; }
    else *cursor = NULL;
    return field;
}

static int is_blank_or_comment(const char *line) {
    while (*line == ' ' || *line == '\t') line++;
    return *line == '\0' || *line == '\n' || *line == '\r' || *line == '#';
}

#define TABLE_LINE_MAX 4096
#define TABLE_MAX_BYTES (64L * 1024 * 1024) /* a table larger than this is refused, not read */
#define TABLE_MAX_LINES 1000000L

/* Reads table.file; logs what is wrong (with the line) and returns NULL on error. */
static Table *read_table(FmuInstance *fmu, const char *given_path) {
    const char *path = strncmp(given_path, "file://", 7) == 0 ? given_path + 7 : given_path;
    struct stat info;
    if (stat(path, &info) != 0) {
        fmu_reject(fmu, VR_table_file, "cannot be opened for reading");
        return NULL;
    }
    if (!S_ISREG(info.st_mode)) {
        fmu_reject(fmu, VR_table_file, "is not a regular file (a device, pipe or folder cannot be a table)");
        return NULL;
    }
    if (info.st_size > TABLE_MAX_BYTES) {
        fmu_reject(fmu, VR_table_file, "is larger than 64 MiB");
        return NULL;
    }
    FILE *file = fopen(path, "r");
    if (!file) {
        fmu_reject(fmu, VR_table_file, "cannot be opened for reading");
        return NULL;
    }
    char line[TABLE_LINE_MAX];
    long data_lines = 0, lines = 0;
    int header_seen = 0;
    while (fgets(line, sizeof line, file)) {
        if (++lines > TABLE_MAX_LINES) {
            fclose(file);
            fmu_reject(fmu, VR_table_file, "has more than 1000000 lines");
            return NULL;
        }
        if (is_blank_or_comment(line)) continue;
        if (header_seen) data_lines++;
        header_seen = 1;
    }
    Table *table = (Table *)fmu_calloc(fmu, 1, sizeof(Table));
    if (!table) { fclose(file); return NULL; }
    strcpy(table->path, given_path);
    for (int d = 0; d < N_DOF; d++) table->column_of[d] = -1;
    rewind(file);
    int number = 0, ok = 1, row = 0;
    while (ok && fgets(line, sizeof line, file)) {
        number++;
        if (is_blank_or_comment(line)) continue;
        if (!strchr(line, '\n') && !feof(file)) {
            fmu_log(fmu, fmi2Error, "logStatusError", "table.file %s:%d: line longer than %d bytes", path, number,
                    TABLE_LINE_MAX - 1);
            ok = 0;
            break;
        }
        if (!table->time) { /* the header */
            char *cursor = line, *field = next_field(&cursor);
            if (!field || strcmp(trim(field), "time") != 0) {
                fmu_log(fmu, fmi2Error, "logStatusError", "table.file %s:%d: the first column must be 'time'", path, number);
                ok = 0;
                break;
            }
            while (ok && (field = next_field(&cursor)) != NULL) {
                const char *name = trim(field);
                int d = 0;
                while (d < N_DOF && strcmp(name, DOF_NAMES[d]) != 0) d++;
                if (d == N_DOF || table->column_of[d] >= 0) {
                    fmu_log(fmu, fmi2Error, "logStatusError", "table.file %s:%d: column '%s' is %s (use x, y, z, "
                            "roll, pitch, yaw, each once)", path, number, name, d == N_DOF ? "unknown" : "repeated");
                    ok = 0;
                }
                else table->column_of[d] = table->columns++;
            }
            if (!ok) break;
            if (data_lines == 0) {
                fmu_log(fmu, fmi2Error, "logStatusError", "table.file %s: no rows after the header", path);
                ok = 0;
                break;
            }
            table->time = (double *)fmu_calloc(fmu, (size_t)data_lines, sizeof(double));
            table->values = (double *)fmu_calloc(fmu, (size_t)data_lines * (size_t)(table->columns + 1), sizeof(double));
            table->slopes = (double *)fmu_calloc(fmu, (size_t)data_lines * (size_t)(table->columns + 1), sizeof(double));
            if (!table->time || !table->values || !table->slopes) ok = 0;
            continue;
        }
        char *cursor = line, *end;
        for (int c = -1; c < table->columns && ok; c++) {
            double value = strtod(cursor, &end);
            while (*end == ' ' || *end == '\t') end++;
            const int separator_ok = (c + 1 < table->columns) ? (*end == ',') : (*end == '\0' || *end == '\n' || *end == '\r');
            if (end == cursor || !isfinite(value) || !separator_ok) {
                fmu_log(fmu, fmi2Error, "logStatusError", "table.file %s:%d: expected %d finite numbers separated "
                        "by commas", path, number, table->columns + 1);
                ok = 0;
                break;
            }
            if (c < 0) table->time[row] = value;
            else table->values[row * table->columns + c] = value;
            cursor = end + 1;
        }
        if (ok && row > 0 && !(table->time[row] > table->time[row - 1])) {
            fmu_log(fmu, fmi2Error, "logStatusError", "table.file %s:%d: time %g does not increase", path, number,
                    table->time[row]);
            ok = 0;
        }
        row++;
    }
    fclose(file);
    if (!ok || !table->time) {
        if (ok) fmu_log(fmu, fmi2Error, "logStatusError", "table.file %s: no header line", path);
        free_table(fmu, table);
        return NULL;
    }
    table->rows = row;
    /* Cubic Hermite slopes: the weighted three-point difference inside, one-sided at the ends. */
    for (int c = 0; c < table->columns; c++) {
        const double *y = table->values + c;
        const int n = table->rows, stride = table->columns;
        for (int i = 0; i < n; i++) {
            double slope = 0.0;
            if (n > 1) {
                if (i == 0) slope = (y[stride] - y[0]) / (table->time[1] - table->time[0]);
                else if (i == n - 1) slope = (y[i * stride] - y[(i - 1) * stride]) / (table->time[i] - table->time[i - 1]);
                else {
                    const double h0 = table->time[i] - table->time[i - 1], h1 = table->time[i + 1] - table->time[i];
                    const double d0 = (y[i * stride] - y[(i - 1) * stride]) / h0;
                    const double d1 = (y[(i + 1) * stride] - y[i * stride]) / h1;
                    slope = (h1 * d0 + h0 * d1) / (h0 + h1);
                }
            }
            table->slopes[i * stride + c] = slope;
        }
    }
    return table;
}

/* Value and first two derivatives of column c at t. */
static void table_at(const Table *table, int c, int interpolation, double t, double out[3]) {
    const int n = table->rows, stride = table->columns;
    out[1] = out[2] = 0.0;
    if (t < table->time[0] || n == 1) { out[0] = table->values[c]; return; } /* from time[0] on: its first interval */
    if (t >= table->time[n - 1]) { out[0] = table->values[(n - 1) * stride + c]; return; }
    int lo = 0, hi = n - 1; /* time[lo] <= t < time[hi] */
    while (hi - lo > 1) {
        const int mid = (lo + hi) / 2;
        if (table->time[mid] <= t) lo = mid;
        else hi = mid;
    }
    const double h = table->time[hi] - table->time[lo], s = (t - table->time[lo]) / h;
    const double y0 = table->values[lo * stride + c], y1 = table->values[hi * stride + c];
    if (interpolation == 1) {
        out[0] = y0 + s * (y1 - y0);
        out[1] = (y1 - y0) / h;
        return;
    }
    const double m0 = h * table->slopes[lo * stride + c], m1 = h * table->slopes[hi * stride + c];
    const double s2 = s * s, s3 = s2 * s;
    out[0] = (2 * s3 - 3 * s2 + 1) * y0 + (s3 - 2 * s2 + s) * m0 + (3 * s2 - 2 * s3) * y1 + (s3 - s2) * m1;
    out[1] = ((6 * s2 - 6 * s) * y0 + (3 * s2 - 4 * s + 1) * m0 + (6 * s - 6 * s2) * y1 + (3 * s2 - 2 * s) * m1) / h;
    out[2] = ((12 * s - 6) * y0 + (6 * s - 4) * m0 + (6 - 12 * s) * y1 + (6 * s - 2) * m1) / (h * h);
}

/* ---- the signals ---- */

/* Communication points accumulate round-off (1000 steps of 1 ms end near, not at, 1 s): an edge
 * within this of t counts as reached, so a step or pulse edge on a communication point is hit. */
static double edge_tolerance(double t) { return 1e-9 * (fabs(t) > 1.0 ? fabs(t) : 1.0); }

/* Value and first two time derivatives of coordinate d at t. */
static void pose_at(FmuInstance *fmu, int d, double t, double out[3]) {
    const DofSignal *q = &DOFS[d];
    out[0] = *fmu_real(fmu, q->offset);
    out[1] = out[2] = 0.0;
    for (int k = 0; k < 3; k++) {
        const double amplitude = *fmu_real(fmu, q->sine[k][0]), w = 2.0 * PI * *fmu_real(fmu, q->sine[k][1]);
        const double angle = w * t + *fmu_real(fmu, q->sine[k][2]);
        out[0] += amplitude * sin(angle);
        out[1] += amplitude * w * cos(angle);
        out[2] -= amplitude * w * w * sin(angle);
    }
    for (int k = 0; k < 2; k++)
        if (t >= *fmu_real(fmu, q->step[k][0]) - edge_tolerance(t)) out[0] += *fmu_real(fmu, q->step[k][1]);
    for (int k = 0; k < 2; k++) {
        const double start = *fmu_real(fmu, q->ramp[k][0]), end = *fmu_real(fmu, q->ramp[k][1]);
        const double slope = *fmu_real(fmu, q->ramp[k][2]);
        if (t > start) out[0] += slope * ((t < end ? t : end) - start);
        if (t > start && t < end) out[1] += slope;
    }
    const Table *table = (const Table *)fmu->model_data;
    if (table && table->column_of[d] >= 0) {
        double column[3];
        table_at(table, table->column_of[d], fmu->s.v.table_interpolation, t, column);
        for (int i = 0; i < 3; i++) out[i] += column[i];
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
    const Table *loaded = (const Table *)fmu->model_data;
    if (!path[0]) {
        fmu_set_model_data(fmu, NULL, NULL);
    } else if (!loaded || strcmp(loaded->path, path) != 0) {
        Table *table = read_table(fmu, path);
        if (!table) errors++;
        fmu_set_model_data(fmu, table, table ? free_table : NULL);
    }
    return errors ? fmi2Error : fmi2OK;
}

void model_initialize(FmuInstance *fmu) { (void)fmu; }

fmi2Status model_do_step(FmuInstance *fmu, double h) {
    (void)fmu; (void)h; /* the outputs are functions of time; the layer advances it */
    return fmi2OK;
}

void model_compute_outputs(FmuInstance *fmu) {
    const double t = fmu->s.time;
    for (int d = 0; d < N_DOF; d++) {
        double q[3];
        pose_at(fmu, d, t, q);
        *fmu_real(fmu, DOFS[d].output) = q[0];
        fmu->s.internal.derivatives[d][0] = q[1];
        fmu->s.internal.derivatives[d][1] = q[2];
    }
    for (int c = 0; c < 6; c++) {
        *fmu_real(fmu, WRENCH[c].output) = wrench_at(fmu, c, t, 1);
        *fmu_real(fmu, WRENCH[c].body_output) = wrench_at(fmu, c, t, 2);
    }
    const Table *table = (const Table *)fmu->model_data;
    fmu->s.v.table_rows = table ? table->rows : 0;
}

double model_output_derivative(FmuInstance *fmu, int vr, int order) {
    /* the layer has refreshed the outputs (model_compute_outputs) at the current time */
    for (int d = 0; d < N_DOF; d++)
        if (DOFS[d].output == vr) return fmu->s.internal.derivatives[d][order - 1];
    return 0.0; /* the wrench is piecewise constant */
}
