/* The results table as CSV, written from C: every value with 17 significant digits (a double's
 * round trip), one header line of names. Python's own formatting costs about 0.6 us a number (0.3 s
 * for the 10 s Meng scene's 370 000 values) and printf's %.17g about 0.45 us (its exact decimal
 * conversion); format_g17 below writes the same characters in about a quarter of that for the
 * values results hold (the Meng scene's CSV 0.08 -> 0.023 s, its writing included), and the rows are
 * formatted in two halves on two threads (the bytes are the same as one thread's) and written in
 * order. */
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

enum { LONGEST = 32 }; /* "-1.2345678901234567e-308," and a newline fit */

/* 10^0 .. 10^22, each exact in a double. */
static const double EXACT_POWER_OF_TEN[23] = {1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11,
                                              1e12, 1e13, 1e14, 1e15, 1e16, 1e17, 1e18, 1e19, 1e20, 1e21, 1e22};

/* The upper 26 bits of a (Veltkamp's split; the volatile keeps a compiler from fusing K a - a). */
static double upper_half(double a) {
    volatile double scaled = 134217729.0 * a;
    return scaled - (scaled - a);
}

/* a b = *product + *error exactly (Dekker's product: each partial product of the halves is exact). */
static void exact_product(double a, double b, double *product, double *error) {
    const double a_high = upper_half(a), a_low = a - a_high, b_high = upper_half(b), b_low = b - b_high;
    *product = a * b;
    *error = ((a_high * b_high - *product) + a_high * b_low + a_low * b_high) + a_low * b_low;
}

/* printf's "%.17g" of `value`, character for character, or 0 when it is left to printf (zero aside,
 * magnitudes outside [1e-28, 1e17), and a value within 1e-6 of a rounding tie). The value is
 * multiplied by 10^(16-k), k its decimal exponent, in double-double arithmetic (10^n for n <= 44 is
 * the exact sum of two doubles: 10^22 10^(n-22), Dekker's product; the result's error is below
 * 1e-14 of a unit in the 17th digit) and rounded to the 17-digit integer whose digits printf writes;
 * %g's layout follows: fixed for exponents -4 .. 16, else d.ddd e+XX, trailing zeros dropped. */
static int format_g17(double value, char *out) {
    char *at = out;
    if (signbit(value)) *at++ = '-';
    const double magnitude = fabs(value);
    if (magnitude == 0.0) {
        *at++ = '0';
        return (int)(at - out);
    }
    if (!(magnitude >= 1e-28 && magnitude < 1e17)) return 0;
    int k = (int)floor(log10(magnitude));  /* the decimal exponent, corrected below if off by one */
    long long digits17 = 0;
    for (int tries = 0;; tries++) {
        const int n = 16 - k;
        if (n < 0 || n > 44 || tries == 3) return 0;
        double power = EXACT_POWER_OF_TEN[n < 22 ? n : 22], power_error = 0.0, scaled, scaled_error;
        if (n > 22) exact_product(EXACT_POWER_OF_TEN[22], EXACT_POWER_OF_TEN[n - 22], &power, &power_error);
        exact_product(magnitude, power, &scaled, &scaled_error);
        scaled_error += magnitude * power_error;          /* magnitude 10^n = scaled + scaled_error */
        const double whole = floor(scaled), fraction = (scaled - whole) + scaled_error;
        const double below = floor(fraction), above = fraction - below;  /* the part past the unit */
        if (fabs(above - 0.5) < 1e-6) return 0;             /* a tie or near one: printf decides */
        const long long truncated = (long long)whole + (long long)below;
        digits17 = truncated + (above > 0.5);
        if (truncated < 10000000000000000LL) k--;          /* fewer than 17 digits: k was high */
        else if (digits17 >= 100000000000000000LL) k++;    /* 18: k was low, or the rounding carried */
        else break;
    }
    char digit[17];
    for (int i = 16; i >= 0; i--, digits17 /= 10) digit[i] = (char)('0' + digits17 % 10);
    int last = 16;  /* the last digit written: trailing zeros are not */
    while (last > 0 && digit[last] == '0') last--;
    if (k >= -4 && k < 17) {  /* fixed */
        if (k >= 0) {
            for (int i = 0; i <= k; i++) *at++ = digit[i];
            if (last > k) *at++ = '.';
            for (int i = k + 1; i <= last; i++) *at++ = digit[i];
        } else {
            *at++ = '0';
            *at++ = '.';
            for (int i = 0; i < -k - 1; i++) *at++ = '0';
            for (int i = 0; i <= last; i++) *at++ = digit[i];
        }
    } else {  /* scientific, at least two exponent digits */
        *at++ = digit[0];
        if (last > 0) *at++ = '.';
        for (int i = 1; i <= last; i++) *at++ = digit[i];
        *at++ = 'e';
        *at++ = k < 0 ? '-' : '+';
        const int exponent = k < 0 ? -k : k;
        if (exponent >= 100) *at++ = (char)('0' + exponent / 100);
        *at++ = (char)('0' + exponent / 10 % 10);
        *at++ = (char)('0' + exponent % 10);
    }
    return (int)(at - out);
}

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
            const int fast = format_g17(value, at);
            if (fast > 0) {
                at += fast;
                *at++ = sep;
            } else {
                at += isnan(value) ? snprintf(at, LONGEST, "nan%c", sep) : snprintf(at, LONGEST, "%.17g%c", value, sep);
            }
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
