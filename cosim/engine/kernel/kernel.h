/* The step kernel's interface (kernel.c): the structs a caller fills in, and the entry points.
 * cosim/engine/kernel.py holds ctypes copies of these structs; kernel_layout() publishes their
 * layout (fmu/common/struct_layout.h) so that the copies are checked against the build at load. */
#ifndef COSIM_KERNEL_H
#define COSIM_KERNEL_H

#include <stddef.h>

#include "struct_layout.h"
#include "motion_guard.h"

typedef int (*SetRealFn)(void *, const unsigned *, size_t, const double *);
typedef int (*GetRealFn)(void *, const unsigned *, size_t, double *);
typedef int (*SetDerivativesFn)(void *, const unsigned *, size_t, const int *, const double *);
typedef int (*GetDerivativesFn)(void *, const unsigned *, size_t, const int *, double *);
typedef int (*DoStepFn)(void *, double, double, int);
typedef int (*GetStateFn)(void *, void **);
typedef int (*SetStateFn)(void *, void *);
typedef int (*FreeStateFn)(void *, void **);

/* Where a bond's value is: an instance and the index among its coupled outputs (or inputs). */
typedef struct {
    int instance, index;
} KernelPort;

/* A power bond (effort times flow is a power): the effort's output and the input it feeds, the
 * flow's likewise, and the input that takes the effort's slope (an interface Jacobian), instance
 * -1 if none. */
typedef struct {
    KernelPort effort_out, effort_in, flow_out, flow_in, slope_in;
} KernelBond;

/* A step of the feed-through resolution at each communication point: instance, and at
 * feed_indices[first ...] the n_inputs indices of the inputs to set, then the n_outputs indices
 * of its coupled outputs to read again. */
typedef struct {
    int instance, first, n_inputs, n_outputs;
} KernelFeed;

typedef struct {
    void *component;
    SetRealFn set_real;
    GetRealFn get_real;
    SetDerivativesFn set_input_derivatives;
    GetDerivativesFn get_output_derivatives;
    DoStepFn do_step;
    GetStateFn get_state;
    SetStateFn set_state;
    FreeStateFn free_state;
    int n_outputs, output_offset;     /* its coupled outputs, at output_offset in a sample */
    const unsigned *output_vrs;
    int n_inputs, input_offset;       /* its coupled inputs, at input_offset in the input arrays */
    const unsigned *input_vrs;
    const int *feed_source;           /* per input: the source instance */
    const int *feed_index;            /* per input: the index in the source's outputs */
    int rate_order;                   /* output derivatives it provides (0: none; at most 2) */
    int interpolating;                /* takes input derivatives (canInterpolateInputs) */
    int extrapolating;                /* not interpolating, but extrapolates held inputs itself over a
                                       * step from its values at the communication points
                                       * (fmi.extrapolate_inputs): gets them at t, not the midpoint */
    int n_record, record_offset;      /* outputs recorded each step, at record_offset in the scratch */
    const unsigned *record_vrs;
} KernelInstance;

typedef struct {
    int n_instances;
    KernelInstance *instances;
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
    int n_inputs_total;
    double *input_values, *input_rates, *input_curvatures; /* as set over the current step */
    int n_bonds;
    const KernelBond *bonds;
    int n_columns;
    const int *column_of;             /* per recorded column: index in the record scratch */
    double *record_scratch;
    double *instance_time;            /* [n_instances] each instance's time */
    double *fmi_seconds;              /* [n_instances] accumulated time inside its FMI calls */
    const int *order_one, *order_two; /* arrays of 1s and 2s, long enough for any call */
    void **states;                    /* [n_instances] saved FMU states of the step controller */
    void **startup_states;            /* [n_instances] saved FMU states of the start-up iteration */
    double *guess, *saved_time;       /* scratch: [n_sample_values], [n_instances] (start-up) */
    int failed_instance, failed_call; /* set when a call fails */
    int threads;                      /* 2: a stage of independent instances steps on two threads */
    const int *stage_end;             /* per sequence position j: the stage j belongs to ends before it */
    void *helper;                     /* the second thread (Helper), made when first needed */
    /* feed-through resolution (none if n_feeds is 0): after each macro step, in dependency order,
     * the inputs that feed-through outputs depend on are set to their sources' values at t + h
     * (with the exact derivatives of the sources that give them) and those outputs read again */
    int n_feeds;
    const KernelFeed *feeds;
    const int *feed_indices;
    unsigned *feed_vrs;               /* scratch, as long as the longest step's inputs or outputs */
    double *feed_values, *feed_rates; /* scratch: values; rates then curvatures (2 x as long) */
} Kernel;

typedef struct {
    double h, h_min, h_max, rtol;
    const double *atol;     /* step doubling: per sample value, +inf where the error is not measured */
    double atol_energy;     /* energy control [J] */
    double k_i, k_p, previous; /* energy control: PI gains and the previous scaled residual */
    double safety, change_min, change_max; /* energy control: H_next / H = clamp(safety x PI law) */
    double t;               /* the controller's time, advanced by each accepted H */
    int rejected;           /* added to */
    int accepted_count;     /* accepted steps so far (over batches) */
    int *force_reject; int n_force_reject; /* test hook: reject the first try of these accepted-step indices */
    /* scratch, sized by Python: */
    double *saved_time, *saved_samples, *saved_rates, *saved_inputs, *saved_instance_time, *full;
} Controller;

/* A run paced to the wall clock, streamed out and driven from outside (realtime.c): every macro
 * step starts at its deadline, origin + (t - t0) / factor on the monotonic clock; after each step
 * the live input's datagrams are taken (the reference they give replaces outputs of one instance
 * in the history, moving towards it within rate and acceleration limits and, through `guard`,
 * within the application's envelope) and every stream_every steps the row's streamed columns go
 * out as one datagram. Layouts: docs/guide/realtime.md. */
enum { LIVE_ACCEPTED, LIVE_OUTSIDE, LIVE_LATE, LIVE_FUTURE, LIVE_REPEATED, LIVE_OUT_OF_ORDER, LIVE_MALFORMED,
       LIVE_OLD_VERSION, LIVE_NON_FINITE, LIVE_BEYOND_LIMITS, LIVE_FOREIGN, LIVE_UNAUTHENTICATED, LIVE_WATCHDOG,
       LIVE_COUNTS };
enum { LIVE_KEY_MAX = 256, LIVE_MAC = 32 };

typedef int (*AdmissibleFn)(void *context, const double *values); /* 1: the values are within the envelope */
/* GuardFn, RecoverFn, GUARD_KINDS: motion_guard.h (the reference's stepping within the envelope) */

typedef struct {
    /* pacing (factor <= 0: as fast as it goes) */
    double factor;                    /* simulated seconds per wall second */
    double origin, t0;                /* the monotonic clock [s] at which simulated time t0 is due */
    double waited;                    /* [s] slept until deadlines, added to */
    /* stream (stream_fd < 0: none): a connected datagram socket */
    int stream_fd, stream_every, stream_countdown, n_stream;
    const int *stream_columns;        /* row columns streamed (0 is the time) */
    unsigned long long stream_sequence;
    unsigned char *packet;            /* scratch: header and n_stream values */
    int stream_failed;                /* datagrams the socket did not take */
    /* live input (listen_fd < 0: none): a bound non-blocking datagram socket */
    int listen_fd, live_instance, n_live;
    const int *live_index;            /* per channel: index among the instance's coupled outputs */
    const int *live_column;           /* per channel: its row column, or -1 */
    const int *live_rate_index;       /* per channel: index of the output that carries its rate, or -1 */
    const int *live_rate_column;      /* per channel: that output's row column, or -1 */
    const double *rate_max, *acceleration_max, *neutral; /* per channel */
    double late_after, watchdog;      /* [s] simulated age of a late packet; [s] wall silence for the watchdog */
    AdmissibleFn admissible;          /* NULL: every finite value is within */
    void *admissible_context;
    GuardFn guard;                    /* NULL: the rate and acceleration limits alone */
    RecoverFn recover;                /* NULL: a reference outside is only braked (the guard's context) */
    void *guard_context;
    int guard_source;                 /* 1: with no live target the instance's own outputs are the target, taken
                                       * as they are while the guard would take their motion, else guarded */
    int live_target;                  /* 1 once a packet or the watchdog gave the target */
    const unsigned char *key;         /* HMAC-SHA256 key of every datagram (key_size 0: none) */
    int key_size;
    double *live;                     /* [6][n_live]: reference value, rate, acceleration; target, its rate, acceleration */
    double target_time, last_good;    /* simulated time the target was given for; wall time of the last good packet */
    int live_active, watchdog_engaged; /* live_active: 0 not yet, 1 starts now, 2 guarded, 3 passed on as it is */
    int owned;                        /* a sender owns the input: owner_address and owner_session */
    unsigned owner_size;
    unsigned char owner_address[128]; /* a struct sockaddr_storage's bytes */
    unsigned long long owner_session;
    unsigned long long live_sequence; /* of the last accepted packet */
    long long counts[LIVE_COUNTS];
    long long guard_counts[GUARD_KINDS]; /* steps the guard held back the reference, per limit */
    double watchdog_time;             /* simulated time the watchdog last engaged */
    unsigned char *received;          /* scratch: one datagram (receive_size bytes) */
    int receive_size;
} RealTime;

/* hmac.c: the HMAC-SHA256 tag of message under key. */
void hmac_sha256(const unsigned char *key, size_t key_size, const unsigned char *message, size_t size,
                 unsigned char tag[32]);

/* realtime.c: waits for step's deadline (returns how late it started [s]); after the step at t_new,
 * takes the live input into the history and the row and streams the row (returns how far past
 * the next deadline the step ended [s]: > 0 an overrun). */
double realtime_wait(RealTime *r, double t);
double realtime_after_step(Kernel *s, RealTime *r, double t_new, double h, double *row);

/* The layout of KernelPort, KernelBond, KernelInstance, Kernel, Controller and RealTime. */
const StructLayout *kernel_layout(void);

int kernel_initialize(Kernel *s, double t, int sweeps, int zero_start);
int kernel_record(Kernel *s, int clock, double *row);
void kernel_release(Kernel *s);
int kernel_run_fixed(Kernel *s, RealTime *real_time, int clock, double h, int n_steps, double *rows,
                     double *residuals, double *bond_energy, double *lateness, double *finish);
int kernel_run_doubling(Kernel *s, Controller *a, int clock, double t_end, int max_rows, double *rows,
                        double *accepted_h, double *residuals, double *bond_energy);
int kernel_run_energy(Kernel *s, Controller *a, int clock, double t_end, int max_rows, double *rows,
                      double *accepted_h, double *residuals, double *bond_energy);

#endif
