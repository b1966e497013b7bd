/* FMI 3.0 co-simulation instances under the step kernel: the kernel calls every instance through
 * the FMI 2.0-shaped function pointers of KernelInstance (kernel.h); for an FMI 3.0 instance those
 * are these adapters, its `component` a Fmi3Component holding the instance and its FMU's own fmi3
 * functions (cosim/engine/kernel.py fills it in from the loaded binary). FMI 3.0 has no input
 * derivatives: an FMU that takes them as inputs of its own (ours: fmi.rate.<input> and
 * fmi.curvature.<input>, at order x derivative_span + the input's value reference) gets them there;
 * the kernel never calls set_input_derivatives on an instance that does not interpolate, and such
 * an instance holds its inputs over a step. */
#include <stdbool.h>
#include <stddef.h>

#include "struct_layout.h"

typedef struct {
    void *instance;
    int (*set_float64)(void *, const unsigned *, size_t, const double *, size_t);
    int (*get_float64)(void *, const unsigned *, size_t, double *, size_t);
    int (*get_output_derivatives)(void *, const unsigned *, size_t, const int *, double *, size_t);
    int (*do_step)(void *, double, double, bool, bool *, bool *, bool *, double *);
    int (*get_state)(void *, void **);
    int (*set_state)(void *, void *);
    int (*free_state)(void *, void **);
    unsigned derivative_span; /* 0: the FMU takes no input derivatives */
} Fmi3Component;

int fmi3_set_real(void *c, const unsigned *vr, size_t n, const double *values) {
    const Fmi3Component *f = (const Fmi3Component *)c;
    return f->set_float64(f->instance, vr, n, values, n);
}

int fmi3_get_real(void *c, const unsigned *vr, size_t n, double *values) {
    const Fmi3Component *f = (const Fmi3Component *)c;
    return f->get_float64(f->instance, vr, n, values, n);
}

/* The derivatives onto the FMU's own derivative inputs, in chunks of the buffer's size. */
int fmi3_set_input_derivatives(void *c, const unsigned *vr, size_t n, const int *order, const double *values) {
    const Fmi3Component *f = (const Fmi3Component *)c;
    if (n == 0) return 0;
    if (f->derivative_span == 0) return 3; /* fmi3Error: this FMU takes no input derivatives */
    enum { CHUNK = 256 };
    unsigned derivative_vr[CHUNK];
    int worst = 0;
    for (size_t done = 0; done < n; done += CHUNK) {
        const size_t count = n - done < CHUNK ? n - done : CHUNK;
        for (size_t i = 0; i < count; i++) derivative_vr[i] = (unsigned)order[done + i] * f->derivative_span + vr[done + i];
        const int status = f->set_float64(f->instance, derivative_vr, count, values + done, count);
        if (status > 1) return status;
        if (status > worst) worst = status;
    }
    return worst;
}

int fmi3_get_output_derivatives(void *c, const unsigned *vr, size_t n, const int *order, double *values) {
    const Fmi3Component *f = (const Fmi3Component *)c;
    return f->get_output_derivatives(f->instance, vr, n, order, values, n);
}

/* An event, a request to terminate or an early return (none of which the kernel handles) is an error. */
int fmi3_do_step(void *c, double t, double h, int no_set_prior) {
    const Fmi3Component *f = (const Fmi3Component *)c;
    bool event = false, terminate = false, early = false;
    double last = t;
    const int status = f->do_step(f->instance, t, h, no_set_prior != 0, &event, &terminate, &early, &last);
    return status <= 1 && (event || terminate || early) ? 3 : status;
}

int fmi3_get_state(void *c, void **state) {
    const Fmi3Component *f = (const Fmi3Component *)c;
    return f->get_state(f->instance, state);
}

int fmi3_set_state(void *c, void *state) {
    const Fmi3Component *f = (const Fmi3Component *)c;
    return f->set_state(f->instance, state);
}

int fmi3_free_state(void *c, void **state) {
    const Fmi3Component *f = (const Fmi3Component *)c;
    return f->free_state(f->instance, state);
}

static const StructLayout LAYOUT[] = {
    STRUCT_LAYOUT(Fmi3Component), STRUCT_LAYOUT_FIELD(Fmi3Component, instance),
    STRUCT_LAYOUT_FIELD(Fmi3Component, set_float64), STRUCT_LAYOUT_FIELD(Fmi3Component, get_float64),
    STRUCT_LAYOUT_FIELD(Fmi3Component, get_output_derivatives), STRUCT_LAYOUT_FIELD(Fmi3Component, do_step),
    STRUCT_LAYOUT_FIELD(Fmi3Component, get_state), STRUCT_LAYOUT_FIELD(Fmi3Component, set_state),
    STRUCT_LAYOUT_FIELD(Fmi3Component, free_state), STRUCT_LAYOUT_FIELD(Fmi3Component, derivative_span),
    STRUCT_LAYOUT_END};

const StructLayout *fmi3_layout(void) { return LAYOUT; }
