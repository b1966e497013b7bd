/* A CSV table a model reads from a file named by one of its String parameters (the trajectory's
 * table.file, the cueing's vehicle.file): a first line `time` and some of the model's column names,
 * comma separated; then rows of finite numbers, time increasing; blank lines and lines starting
 * with # skipped. Read once into model data (outside the FMU state); every fault is logged with the
 * parameter, the file and the line. */
#ifndef FMU_TABLE_READER_H
#define FMU_TABLE_READER_H

#include "fmu_common.h"

#define FMU_TABLE_MAX_COLUMNS 16

typedef struct {
    char path[FMU_TEXT_MAX];            /* the parameter's value it was read from */
    int rows, columns;                  /* columns besides time */
    int column_of[FMU_TABLE_MAX_COLUMNS]; /* per name the model gave: its column, or -1 */
    double *time;                       /* rows */
    double *values, *slopes;            /* rows x columns, row-major; slopes for the cubic Hermite */
} FmuTable;

/* Reads the file parameter `vr` names (its value `given_path`, "file://" allowed), whose columns
 * may be any of `names` (n_names of them), each once. Returns NULL after logging why. */
FmuTable *fmu_table_read(FmuInstance *fmu, int vr, const char *given_path, const char *const *names, int n_names);
void fmu_table_free(FmuInstance *fmu, FmuTable *table);

/* Value and first three time derivatives at t of column c (interpolation 1: linear, 2: cubic Hermite
 * with the slopes above); the end values held before the first and after the last row. */
void fmu_table_at(const FmuTable *table, int c, int interpolation, double t, double out[4]);

/* The time of the first row after t (INFINITY: none): where a linear interpolation has a corner, a
 * time event for a Model Exchange solver. */
double fmu_table_next_row(const FmuTable *table, double t);

#endif
