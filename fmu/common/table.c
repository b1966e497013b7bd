/* The CSV table reader the models share (table.h). */
#define _POSIX_C_SOURCE 200809L /* stat: a table must be a regular file */
#include "table.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

void fmu_table_free(FmuInstance *fmu, FmuTable *table) {
    if (!table) return;
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

FmuTable *fmu_table_read(FmuInstance *fmu, int vr, const char *given_path, const char *const *names, int n_names) {
    const char *path = strncmp(given_path, "file://", 7) == 0 ? given_path + 7 : given_path;
    struct stat info;
    if (stat(path, &info) != 0) {
        fmu_reject(fmu, vr, "cannot be opened for reading");
        return NULL;
    }
    if (!S_ISREG(info.st_mode)) {
        fmu_reject(fmu, vr, "is not a regular file (a device, pipe or folder cannot be a table)");
        return NULL;
    }
    if (info.st_size > TABLE_MAX_BYTES) {
        fmu_reject(fmu, vr, "is larger than 64 MiB");
        return NULL;
    }
    FILE *file = fopen(path, "r");
    if (!file) {
        fmu_reject(fmu, vr, "cannot be opened for reading");
        return NULL;
    }
    char line[TABLE_LINE_MAX];
    long data_lines = 0, lines = 0;
    int header_seen = 0;
    while (fgets(line, sizeof line, file)) {
        if (++lines > TABLE_MAX_LINES) {
            fclose(file);
            fmu_reject(fmu, vr, "has more than 1000000 lines");
            return NULL;
        }
        if (is_blank_or_comment(line)) continue;
        if (header_seen) data_lines++;
        header_seen = 1;
    }
    FmuTable *table = (FmuTable *)fmu_calloc(fmu, 1, sizeof(FmuTable));
    if (!table) { fclose(file); return NULL; }
    strcpy(table->path, given_path);
    for (int d = 0; d < FMU_TABLE_MAX_COLUMNS; d++) table->column_of[d] = -1;
    const char *what = fmu_variables[vr].name;
    char known[512] = ""; /* the names it may hold, for the message on one it may not */
    for (int d = 0; d < n_names && d < FMU_TABLE_MAX_COLUMNS; d++) {
        if (d) strncat(known, ", ", sizeof known - strlen(known) - 1);
        strncat(known, names[d], sizeof known - strlen(known) - 1);
    }
    rewind(file);
    int number = 0, ok = 1, row = 0;
    while (ok && fgets(line, sizeof line, file)) {
        number++;
        if (is_blank_or_comment(line)) continue;
        if (!strchr(line, '\n') && !feof(file)) {
            fmu_log(fmu, fmi2Error, "logStatusError", "%s %s:%d: line longer than %d bytes", what, path, number,
                    TABLE_LINE_MAX - 1);
            ok = 0;
            break;
        }
        if (!table->time) { /* the header */
            char *cursor = line, *field = next_field(&cursor);
            if (!field || strcmp(trim(field), "time") != 0) {
                fmu_log(fmu, fmi2Error, "logStatusError", "%s %s:%d: the first column must be 'time'", what, path, number);
                ok = 0;
                break;
            }
            while (ok && (field = next_field(&cursor)) != NULL) {
                const char *name = trim(field);
                int d = 0;
                while (d < n_names && strcmp(name, names[d]) != 0) d++;
                if (d == n_names || table->column_of[d] >= 0) {
                    fmu_log(fmu, fmi2Error, "logStatusError", "%s %s:%d: column '%s' is %s (use %s, each once)", what,
                            path, number, name, d == n_names ? "unknown" : "repeated", known);
                    ok = 0;
                }
                else table->column_of[d] = table->columns++;
            }
            if (!ok) break;
            if (data_lines == 0) {
                fmu_log(fmu, fmi2Error, "logStatusError", "%s %s: no rows after the header", what, path);
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
                fmu_log(fmu, fmi2Error, "logStatusError", "%s %s:%d: expected %d finite numbers separated "
                        "by commas", what, path, number, table->columns + 1);
                ok = 0;
                break;
            }
            if (c < 0) table->time[row] = value;
            else table->values[row * table->columns + c] = value;
            cursor = end + 1;
        }
        if (ok && row > 0 && !(table->time[row] > table->time[row - 1])) {
            fmu_log(fmu, fmi2Error, "logStatusError", "%s %s:%d: time %g does not increase", what, path, number,
                    table->time[row]);
            ok = 0;
        }
        row++;
    }
    fclose(file);
    if (!ok || !table->time) {
        if (ok) fmu_log(fmu, fmi2Error, "logStatusError", "%s %s: no header line", what, path);
        fmu_table_free(fmu, table);
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

/* Value and first three derivatives of column c at t. */
void fmu_table_at(const FmuTable *table, int c, int interpolation, double t, double out[4]) {
    const int n = table->rows, stride = table->columns;
    out[1] = out[2] = out[3] = 0.0;
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
    out[3] = (12 * y0 + 6 * m0 - 12 * y1 + 6 * m1) / (h * h * h);
}

