/* Real time for the step kernel (kernel.h's RealTime): pacing to the wall clock, the live output
 * stream and the live input, all done where the stepping is, with no interpreter in the loop.
 *
 * Pacing: the step that starts at simulated time t is due at origin + (t - t0) / factor on the
 * monotonic clock; the kernel sleeps until then (an absolute deadline, so no drift builds up), and
 * a step that ends past the next deadline is an overrun: the next one starts at once, and the run
 * stays in step with the clock rather than slowing down.
 *
 * Stream: every stream_every steps one datagram, little-endian: "CSIM", version (u16), the number
 * of values (u16), a sequence number (u64), the simulated time and the wall clock (Unix time) [s]
 * (f64), then the row's streamed columns (f64).
 *
 * Live input: datagrams "CREF", version (u16), count (u16: n, 2 n or 3 n for values, their rates,
 * their accelerations), sequence (u64), the simulated time they are for (f64; NaN: now), then the
 * values. Each is taken or counted by kind and refused (malformed, non-finite, late, repeated, out
 * of order, outside what `admissible` allows). The reference (the outputs it replaces) moves
 * towards the target within each channel's rate and acceleration limits; after `watchdog` seconds
 * without a good packet the target becomes the neutral values.
 */
#define _POSIX_C_SOURCE 200809L /* clock_nanosleep */
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/types.h>
#include <time.h>
#ifdef __linux__
#include <sys/prctl.h>
#endif

#include "kernel.h"

enum { STREAM_HEADER = 32, LIVE_HEADER = 24, VERSION = 1 };
enum { VALUE, RATE, ACCELERATION, TARGET, TARGET_RATE, TARGET_ACCELERATION }; /* rows of r->live */

static double clock_seconds(clockid_t id) {
    struct timespec ts;
    clock_gettime(id, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

double realtime_wait(RealTime *r, double t) {
    if (r->factor <= 0.0) return 0.0;
#ifdef __linux__
    static _Thread_local int slack_set;
    if (!slack_set) { prctl(PR_SET_TIMERSLACK, 1000UL, 0, 0, 0); slack_set = 1; } /* wake within 1 us, not 50 */
#endif
    const double deadline = r->origin + (t - r->t0) / r->factor;
    double current = clock_seconds(CLOCK_MONOTONIC);
    if (current < deadline) {
        const double whole = floor(deadline);
        const struct timespec until = {(time_t)whole, (long)((deadline - whole) * 1e9)};
        while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &until, NULL) == EINTR) {
        }
        const double woke = clock_seconds(CLOCK_MONOTONIC);
        r->waited += woke - current;
        current = woke;
    }
    return current - deadline;
}

static void stream_row(RealTime *r, const double *row) {
    unsigned char *p = r->packet;
    const uint16_t version = VERSION, count = (uint16_t)r->n_stream;
    const uint64_t sequence = r->stream_sequence++;
    const double wall = clock_seconds(CLOCK_REALTIME);
    memcpy(p, "CSIM", 4);
    memcpy(p + 4, &version, 2);
    memcpy(p + 6, &count, 2);
    memcpy(p + 8, &sequence, 8);
    memcpy(p + 16, &row[0], 8);
    memcpy(p + 24, &wall, 8);
    for (int i = 0; i < r->n_stream; i++) memcpy(p + STREAM_HEADER + 8 * i, &row[r->stream_columns[i]], 8);
    if (send(r->stream_fd, p, (size_t)(STREAM_HEADER + 8 * r->n_stream), MSG_DONTWAIT) < 0) r->stream_failed++;
}

/* One datagram of the live input, classified; a good one becomes the target. */
static void take_packet(Kernel *s, RealTime *r, ssize_t size, double t_now) {
    const unsigned char *p = r->received;
    const int n = r->n_live;
    uint16_t version, count;
    uint64_t sequence;
    double time, values[3 * 64];
    if (size < LIVE_HEADER || memcmp(p, "CREF", 4) != 0) { r->counts[LIVE_MALFORMED]++; return; }
    memcpy(&version, p + 4, 2);
    memcpy(&count, p + 6, 2);
    memcpy(&sequence, p + 8, 8);
    memcpy(&time, p + 16, 8);
    if (version != VERSION || (count != n && count != 2 * n && count != 3 * n) || count > 3 * 64 ||
        size != LIVE_HEADER + 8 * (ssize_t)count) {
        r->counts[LIVE_MALFORMED]++;
        return;
    }
    memcpy(values, p + LIVE_HEADER, 8 * (size_t)count);
    int finite = !isinf(time);
    for (int i = 0; i < count; i++) finite = finite && isfinite(values[i]);
    if (!finite) { r->counts[LIVE_NON_FINITE]++; return; }
    const int fresh = !r->live_active || r->watchdog_engaged; /* a sender after a silence may start again at 0 */
    if (!fresh && sequence == r->live_sequence) { r->counts[LIVE_REPEATED]++; return; }
    if (!fresh && sequence < r->live_sequence) { r->counts[LIVE_OUT_OF_ORDER]++; return; }
    if (!isnan(time) && time < t_now - r->late_after) { r->counts[LIVE_LATE]++; return; }
    if (r->admissible && !r->admissible(r->admissible_context, values)) { r->counts[LIVE_OUTSIDE]++; return; }
    r->counts[LIVE_ACCEPTED]++;
    r->live_sequence = sequence;
    r->last_good = clock_seconds(CLOCK_MONOTONIC);
    r->watchdog_engaged = 0;
    if (!r->live_active) { /* the reference starts where the replaced outputs are */
        const KernelInstance *in = &s->instances[r->live_instance];
        const double *latest = s->samples + (size_t)(s->n_samples - 1) * (size_t)s->n_sample_values;
        for (int i = 0; i < n; i++) {
            const int at = in->output_offset + r->live_index[i];
            r->live[VALUE * n + i] = latest[at];
            r->live[RATE * n + i] = in->rate_order >= 1 ? s->exact_rates[at] : 0.0;
            r->live[ACCELERATION * n + i] = in->rate_order >= 2 ? s->exact_rates[s->n_sample_values + at] : 0.0;
        }
        r->live_active = 1;
    }
    r->target_time = isnan(time) ? t_now : time;
    for (int i = 0; i < n; i++) {
        r->live[TARGET * n + i] = values[i];
        r->live[TARGET_RATE * n + i] = count >= 2 * n ? values[n + i] : 0.0;
        r->live[TARGET_ACCELERATION * n + i] = count >= 3 * n ? values[2 * n + i] : 0.0;
    }
}

/* The reference at t_new and its motion over the next step: first carried over the step just
 * taken with the acceleration chosen for it (not on the step the input starts: it starts where
 * the replaced outputs are), then the next step's acceleration chosen towards the target
 * (extrapolated by its rate and acceleration from the time it was given for) as fast as the
 * limits allow, braking in time. Constant over a step, that acceleration makes the value, rate and
 * acceleration handed to the inputs the reference's exact motion over the step. */
static void advance_reference(RealTime *r, double t_new, double h) {
    const int n = r->n_live, carry = r->live_active == 2;
    double since = t_new - r->target_time;
    if (fabs(since) > r->watchdog) since = copysign(r->watchdog, since); /* never extrapolated further */
    for (int i = 0; i < n; i++) {
        double *value = &r->live[VALUE * n + i], *rate = &r->live[RATE * n + i], *acceleration = &r->live[ACCELERATION * n + i];
        if (carry) {
            *value += *rate * h + 0.5 * *acceleration * h * h;
            *rate += *acceleration * h;
        }
        const double a_max = r->acceleration_max[i], v_max = r->rate_max[i];
        const double goal = r->live[TARGET * n + i] + r->live[TARGET_RATE * n + i] * since +
                            0.5 * r->live[TARGET_ACCELERATION * n + i] * since * since;
        const double goal_rate = r->live[TARGET_RATE * n + i] + r->live[TARGET_ACCELERATION * n + i] * since;
        const double error = goal - *value;
        /* the rate wanted: the braking curve sqrt(2 a |e|) far from the goal, 0.25 |e| / h near it (the
         * error then decays by real factors 0.70 and 0.18 a step: no ringing) */
        double wanted = goal_rate + copysign(fmin(sqrt(2.0 * a_max * fabs(error)), 0.25 * fabs(error) / h), error);
        wanted = fmax(-v_max, fmin(v_max, wanted));
        *acceleration = fmax(-a_max, fmin(a_max, (wanted - *rate) / h));
    }
    r->live_active = 2;
}

static void live_step(Kernel *s, RealTime *r, double t_new, double h, double *row) {
    for (;;) {
        const ssize_t size = recv(r->listen_fd, r->received, (size_t)r->receive_size, MSG_DONTWAIT);
        if (size < 0) break; /* nothing more waiting (or the socket failed: the input is then silent) */
        take_packet(s, r, size, t_new - h);
    }
    if (!r->live_active) return;
    if (!r->watchdog_engaged && clock_seconds(CLOCK_MONOTONIC) - r->last_good > r->watchdog) {
        const int n = r->n_live;
        for (int i = 0; i < n; i++) {
            r->live[TARGET * n + i] = r->neutral[i];
            r->live[TARGET_RATE * n + i] = r->live[TARGET_ACCELERATION * n + i] = 0.0;
        }
        r->target_time = t_new;
        r->watchdog_engaged = 1;
        r->watchdog_time = t_new;
        r->counts[LIVE_WATCHDOG]++;
    }
    advance_reference(r, t_new, h);
    const KernelInstance *in = &s->instances[r->live_instance];
    double *latest = s->samples + (size_t)(s->n_samples - 1) * (size_t)s->n_sample_values;
    for (int i = 0; i < r->n_live; i++) { /* the history's newest sample, as if the instance had given it */
        const int at = in->output_offset + r->live_index[i];
        latest[at] = r->live[VALUE * r->n_live + i];
        if (in->rate_order >= 1) s->exact_rates[at] = r->live[RATE * r->n_live + i];
        if (in->rate_order >= 2) s->exact_rates[s->n_sample_values + at] = r->live[ACCELERATION * r->n_live + i];
        if (r->live_column[i] >= 0) row[r->live_column[i]] = latest[at];
        if (r->live_rate_index[i] < 0) continue;
        /* the output that carries the reference's rate (a master that gives no derivatives hands it
         * to the inputs that take the rate): the live rate, its rate the live acceleration, constant
         * over the step */
        const int rate_at = in->output_offset + r->live_rate_index[i];
        latest[rate_at] = r->live[RATE * r->n_live + i];
        if (in->rate_order >= 1) s->exact_rates[rate_at] = r->live[ACCELERATION * r->n_live + i];
        if (in->rate_order >= 2) s->exact_rates[s->n_sample_values + rate_at] = 0.0;
        if (r->live_rate_column[i] >= 0) row[r->live_rate_column[i]] = latest[rate_at];
    }
}

double realtime_after_step(Kernel *s, RealTime *r, double t_new, double h, double *row) {
    if (r->listen_fd >= 0) live_step(s, r, t_new, h, row);
    if (r->stream_fd >= 0 && --r->stream_countdown <= 0) {
        stream_row(r, row);
        r->stream_countdown = r->stream_every;
    }
    if (r->factor <= 0.0) return 0.0;
    return clock_seconds(CLOCK_MONOTONIC) - (r->origin + (t_new - r->t0) / r->factor);
}
