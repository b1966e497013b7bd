/* One evaluation of the mechanics' equations of motion (platform_derivatives in
 * libplatform_core.so), n times on a platform and state written by benchmarks/mechanics.py: prints
 * the wall nanoseconds per evaluation. Under valgrind's callgrind the same binary gives each
 * instruction's count (benchmarks/mechanics.py classifies them).
 *
 * usage: derivatives_bench LIBPLATFORM_CORE PLATFORM_BYTES STATE_BYTES N
 */
#define _POSIX_C_SOURCE 200809L
#include <dlfcn.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

typedef int (*Derivatives)(const void *platform, const double *x, const double *torque, const double *force,
                           const void *slopes, const double *wrench, double *dxdt, void *diagnostics);

static void *read_file(const char *path, long *size) {
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    fseek(f, 0, SEEK_END);
    *size = ftell(f);
    fseek(f, 0, SEEK_SET);
    void *data = malloc((size_t)*size);
    if (data && fread(data, 1, (size_t)*size, f) != (size_t)*size) data = NULL;
    fclose(f);
    return data;
}

int main(int argc, char **argv) {
    if (argc < 5) { fprintf(stderr, "usage: see derivatives_bench.c\n"); return 2; }
    void *lib = dlopen(argv[1], RTLD_NOW | RTLD_LOCAL);
    if (!lib) { fprintf(stderr, "%s\n", dlerror()); return 2; }
    Derivatives derivatives;
    *(void **)(&derivatives) = dlsym(lib, "platform_derivatives");
    long platform_size, state_size;
    void *platform = read_file(argv[2], &platform_size);
    double *x = read_file(argv[3], &state_size);
    if (!derivatives || !platform || !x || state_size != 13 * (long)sizeof(double)) return 2;
    const long n = atol(argv[4]);
    double torque[6] = {8.0, 8.0, 8.0, 8.0, 8.0, 8.0}, force[6] = {0}, wrench[6] = {0}, dxdt[13], sink = 0.0;
    struct timespec start, end;
    clock_gettime(CLOCK_MONOTONIC, &start);
    for (long k = 0; k < n; k++) {
        x[7] += 1e-12; /* a new state each time: nothing to cache */
        if (derivatives(platform, x, torque, force, NULL, wrench, dxdt, NULL) != 0) return 1;
        sink += dxdt[7];
    }
    clock_gettime(CLOCK_MONOTONIC, &end);
    double seconds = (end.tv_sec - start.tv_sec) + 1e-9 * (end.tv_nsec - start.tv_nsec);
    printf("%.6g %.17g\n", n ? 1e9 * seconds / n : 0.0, sink);
    return 0;
}
