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

/* The file a table parameter names, opened if it is a regular file of at most TABLE_MAX_BYTES;
 * NULL after logging why not. */
static FILE *open_table(FmuInstance *fmu, int vr, const char *path) {
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
    if (!file) fmu_reject(fmu, vr, "cannot be opened for reading");
    return file;
}

/* The rows after the header (blank and comment lines not counted), or -1 after logging a file of
 * more than TABLE_MAX_LINES lines. */
static long count_rows(FmuInstance *fmu, int vr, FILE *file) {
    char line[TABLE_LINE_MAX];
    long data_lines = 0, lines = 0;
    int header_seen = 0;
    while (fgets(line, sizeof line, file)) {
        if (++lines > TABLE_MAX_LINES) {
            fmu_reject(fmu, vr, "has more than 1000000 lines");
            return -1;
        }
        if (is_blank_or_comment(line)) continue;
        if (header_seen) data_lines++;
        header_seen = 1;
    }
    return data_lines;
}

/* One table being read: where from (for the messages) and the column names it may hold. */
typedef struct {
    FmuInstance *fmu;
    const char *what, *path;        /* the parameter's name, the file */
    const char *const *names;
    int n_names;
    char known[512];                /* the names, listed for the message on one it may not hold */
    int number;                     /* the line being read */
} Reading;

#define TABLE_ERROR(r, format, ...)                                                                               \
    fmu_log((r)->fmu, fmi2Error, "logStatusError", "%s %s:%d: " format, (r)->what, (r)->path, (r)->number,     \
            __VA_ARGS__)

/* The header line: 'time', then each of the names at most once; the arrays for `rows` rows. */
static int read_header(Reading *r, FmuTable *table, char *line, long rows) {
    if (!strchr(line, ',') && strchr(line, ';')) { /* a spreadsheet set to a decimal comma saves these */
        TABLE_ERROR(r, "%s", "the columns are separated by ';': separate them by ',' (and write numbers with '.')");
        return 0;
    }
    char *cursor = line, *field = next_field(&cursor);
    if (!field || strcmp(trim(field), "time") != 0) {
        TABLE_ERROR(r, "%s", "the first column must be 'time'");
        return 0;
    }
    while ((field = next_field(&cursor)) != NULL) {
        const char *name = trim(field);
        int d = 0;
        while (d < r->n_names && strcmp(name, r->names[d]) != 0) d++;
        if (d == r->n_names || table->column_of[d] >= 0) {
            TABLE_ERROR(r, "column '%s' is %s (use %s, each once)", name, d == r->n_names ? "unknown" : "repeated",
                        r->known);
            return 0;
        }
        table->column_of[d] = table->columns++;
    }
    if (rows == 0) {
        fmu_log(r->fmu, fmi2Error, "logStatusError", "%s %s: no rows after the header", r->what, r->path);
        return 0;
    }
    table->time = (double *)fmu_calloc(r->fmu, (size_t)rows, sizeof(double));
    table->values = (double *)fmu_calloc(r->fmu, (size_t)rows * (size_t)(table->columns + 1), sizeof(double));
    table->slopes = (double *)fmu_calloc(r->fmu, (size_t)rows * (size_t)(table->columns + 1), sizeof(double));
    return table->time && table->values && table->slopes;
}

/* Row `row`: the time and every column, finite numbers separated by commas, time increasing. */
static int read_row(Reading *r, FmuTable *table, const char *line, int row) {
    const char *cursor = line;
    char *end;
    for (int c = -1; c < table->columns; c++) {
        double value = strtod(cursor, &end);
        while (*end == ' ' || *end == '\t') end++;
        const int separator_ok = (c + 1 < table->columns) ? (*end == ',') : (*end == '\0' || *end == '\n' || *end == '\r');
        if (end == cursor || !isfinite(value) || !separator_ok) {
            TABLE_ERROR(r, "expected %d finite numbers separated by commas", table->columns + 1);
            return 0;
        }
        if (c < 0) table->time[row] = value;
        else table->values[row * table->columns + c] = value;
        cursor = end + 1;
    }
    if (row > 0 && !(table->time[row] > table->time[row - 1])) {
        TABLE_ERROR(r, "time %g does not increase", table->time[row]);
        return 0;
    }
    return 1;
}

/* Cubic Hermite slopes: the weighted three-point difference inside, one-sided at the ends. */
static void hermite_slopes(FmuTable *table) {
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
}

FmuTable *fmu_table_read(FmuInstance *fmu, int vr, const char *given_path, const char *const *names, int n_names) {
    char resolved[2 * FMU_TEXT_MAX];
    const char *path = strncmp(given_path, "file://", 7) == 0 ? given_path + 7 : given_path;
    path = fmu_resource_path(fmu, path, resolved, sizeof resolved);
    if (!path) {
        fmu_reject(fmu, vr, "names a file in the FMU's resources, and the FMU was given no resources folder");
        return NULL;
    }
    FILE *file = open_table(fmu, vr, path);
    if (!file) return NULL;
    const long rows = count_rows(fmu, vr, file);
    FmuTable *table = rows < 0 ? NULL : (FmuTable *)fmu_calloc(fmu, 1, sizeof(FmuTable));
    if (!table) { fclose(file); return NULL; }
    strcpy(table->path, given_path);
    for (int d = 0; d < FMU_TABLE_MAX_COLUMNS; d++) table->column_of[d] = -1;
    Reading r = {fmu, fmu_variables[vr].name, path, names, n_names, "", 0};
    for (int d = 0; d < n_names && d < FMU_TABLE_MAX_COLUMNS; d++) {
        if (d) strncat(r.known, ", ", sizeof r.known - strlen(r.known) - 1);
        strncat(r.known, names[d], sizeof r.known - strlen(r.known) - 1);
    }
    rewind(file);
    char line[TABLE_LINE_MAX];
    int ok = 1, row = 0;
    while (ok && fgets(line, sizeof line, file)) {
        r.number++;
        if (r.number == 1 && strncmp(line, "\xEF\xBB\xBF", 3) == 0) /* UTF-8's byte order mark (Excel's CSV) */
            memmove(line, line + 3, strlen(line + 3) + 1);
        if (is_blank_or_comment(line)) continue;
        if (!strchr(line, '\n') && !feof(file)) {
            TABLE_ERROR(&r, "line longer than %d bytes", TABLE_LINE_MAX - 1);
            ok = 0;
        } else if (!table->time) {
            ok = read_header(&r, table, line, rows);
        } else {
            ok = read_row(&r, table, line, row++);
        }
    }
    fclose(file);
    if (!ok || !table->time) {
        if (ok) fmu_log(fmu, fmi2Error, "logStatusError", "%s %s: no header line", r.what, path);
        fmu_table_free(fmu, table);
        return NULL;
    }
    table->rows = row;
    hermite_slopes(table);
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


/* The first row's time after t (INFINITY: none). */
double fmu_table_next_row(const FmuTable *table, double t) {
    const int n = table->rows;
    if (n == 0 || t >= table->time[n - 1]) return INFINITY;
    if (t < table->time[0]) return table->time[0];
    int lo = 0, hi = n - 1; /* time[lo] <= t < time[hi] */
    while (hi - lo > 1) {
        const int mid = (lo + hi) / 2;
        if (table->time[mid] <= t) lo = mid;
        else hi = mid;
    }
    return table->time[hi];
}
