/* The results table as CSV, written from C: every value with 17 significant digits (a double's
 * round trip), one header line of names. Python's own formatting costs about 0.6 us a number (0.3 s
 * for the 10 s Meng scene's 370 000 values); printf's %.17g about a tenth of that, which is still
 * most of writing a run's results, so the rows are formatted in two halves on two threads (the
 * bytes are the same as one thread's) and written in order. */
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum { LONGEST = 32 }; /* "-1.2345678901234567e-308," and a newline fit */

typedef struct {
    const double *data;
    long first, last; /* rows [first, last) */
    int cols;
    char *text;       /* the formatted rows */
    size_t length;
} Part;

static void *format_rows(void *arg) {
    Part *part = (Part *)arg;
    part->text = malloc((size_t)(part->last - part->first) * (size_t)part->cols * LONGEST + 1);
    if (!part->text) return NULL;
    char *at = part->text;
    for (long r = part->first; r < part->last; r++) {
        for (int c = 0; c < part->cols; c++) {
            const double value = part->data[r * part->cols + c];
            const char sep = c + 1 < part->cols ? ',' : '\n';
            at += isnan(value) ? snprintf(at, LONGEST, "nan%c", sep) : snprintf(at, LONGEST, "%.17g%c", value, sep);
        }
    }
    part->length = (size_t)(at - part->text);
    return NULL;
}

/* Writes `rows` x `cols` doubles (row major) under `header` (one line, no newline) to `path`;
 * 0, or -1 if the file cannot be written. */
int table_write_csv(const char *path, const char *header, const double *data, int rows, int cols) {
    Part parts[2] = {{data, 0, rows / 2, cols, NULL, 0}, {data, rows / 2, rows, cols, NULL, 0}};
    pthread_t second;
    const int threaded = rows >= 1000 && pthread_create(&second, NULL, format_rows, &parts[1]) == 0;
    format_rows(&parts[0]);
    if (threaded)
        pthread_join(second, NULL);
    else
        format_rows(&parts[1]);
    FILE *f = fopen(path, "w");
    int ok = f && parts[0].text && parts[1].text && fprintf(f, "%s\n", header) >= 0;
    for (int k = 0; ok && k < 2; k++) ok = fwrite(parts[k].text, 1, parts[k].length, f) == parts[k].length;
    free(parts[0].text);
    free(parts[1].text);
    if (!f) return -1;
    return fclose(f) == 0 && ok ? 0 : -1;
}
