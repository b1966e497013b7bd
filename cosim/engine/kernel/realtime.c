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
 * Live input: datagrams "CREF", version (u16, 2), count (u16: n, 2 n or 3 n for values, their
 * rates, their accelerations), session (u64), sequence (u64), the simulated time they are for
 * (f64; NaN: now), the values, and with a key the HMAC-SHA256 of all that (32 bytes). Each is
 * taken or counted by kind and refused: malformed, of the old version, unauthenticated, foreign
 * (another sender's while one owns the input), non-finite, late, for a time beyond the next step,
 * with rates or accelerations beyond the limits, repeated, out of order. A target outside what
 * `admissible` allows is taken and counted as outside: the guard stops the reference at the
 * envelope. The reference (the outputs it replaces) moves towards the target within each
 * channel's rate and acceleration limits, and `guard` holds it within the application's
 * envelope; after `watchdog` seconds without a good packet the target becomes the neutral
 * values and the input has no owner.
 *
 * The guard on the instance's own outputs (guard_source, with or without a live input): until a
 * packet gives a target, the outputs' own motion is passed on untouched while the guard would take
 * it; where it would not, a reference takes over from the motion last handed on and follows the
 * outputs within the limits and the envelope, and hands them back once it has caught up. A
 * reference outside the envelope goes back in towards what `recover` gives, never held outside.
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

enum { STREAM_HEADER = 32, LIVE_HEADER = 32, VERSION = 1, LIVE_VERSION = 2, LIVE_OLD_VERSION_1 = 1 };
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

/* 1 if every value's extrapolation by its rate and acceleration over +-horizon is finite and
 * every rate and acceleration within its channel's limits (0: beyond), -1 if any is not finite. */
static int numbers_within(const RealTime *r, const double *values, int count, double horizon) {
    const int n = r->n_live;
    for (int i = 0; i < n; i++) {
        const double rate = count >= 2 * n ? values[n + i] : 0.0, acceleration = count >= 3 * n ? values[2 * n + i] : 0.0;
        if (!(fabs(rate) <= r->rate_max[i]) || !(fabs(acceleration) <= r->acceleration_max[i]))
            return 0;
        const double reach = fabs(values[i]) + fabs(rate) * horizon + 0.5 * fabs(acceleration) * horizon * horizon;
        if (!isfinite(reach)) return -1;
    }
    return 1;
}

static int constant_time_equal(const unsigned char *a, const unsigned char *b, size_t size) {
    unsigned char differ = 0;
    for (size_t i = 0; i < size; i++) differ |= (unsigned char)(a[i] ^ b[i]);
    return differ == 0;
}

/* The replaced outputs' own motion in the newest sample, [3][n]: values, rates, accelerations (the
 * rates from the outputs that carry them where the coupling gives no derivatives). */
static void own_motion(const Kernel *s, const RealTime *r, double *motion) {
    const KernelInstance *in = &s->instances[r->live_instance];
    const double *latest = s->samples + (size_t)(s->n_samples - 1) * (size_t)s->n_sample_values;
    const int n = r->n_live;
    for (int i = 0; i < n; i++) {
        const int at = in->output_offset + r->live_index[i];
        const int rate_at = r->live_rate_index[i] >= 0 ? in->output_offset + r->live_rate_index[i] : -1;
        motion[i] = latest[at];
        motion[n + i] = in->rate_order >= 1 ? s->exact_rates[at] : rate_at >= 0 ? latest[rate_at] : 0.0;
        motion[2 * n + i] = in->rate_order >= 2   ? s->exact_rates[s->n_sample_values + at]
                            : in->rate_order >= 1 && rate_at >= 0 ? s->exact_rates[rate_at]
                                                                  : 0.0;
    }
}

/* The reference takes over the replaced outputs where they are, with their motion. */
static void start_reference(const Kernel *s, RealTime *r) {
    own_motion(s, r, r->live); /* rows VALUE, RATE, ACCELERATION */
    r->live_active = 1;
}

/* One datagram of the live input from `from`, classified; a good one becomes the target. t_now:
 * where the reference is applied from (the step just taken ended there). */
static void take_packet(Kernel *s, RealTime *r, ssize_t size, const void *from, unsigned from_size, double t_now,
                        double h) {
    const unsigned char *p = r->received;
    const int n = r->n_live;
    uint16_t version, count;
    uint64_t session, sequence;
    double time, values[3 * MOTION_GUARD_CHANNELS];
    if (size < 8 || memcmp(p, "CREF", 4) != 0) { r->counts[LIVE_MALFORMED]++; return; }
    memcpy(&version, p + 4, 2);
    memcpy(&count, p + 6, 2);
    if (version == LIVE_OLD_VERSION_1) { r->counts[LIVE_OLD_VERSION]++; return; }
    const ssize_t mac = r->key_size > 0 ? LIVE_MAC : 0;
    if (version != LIVE_VERSION || (count != n && count != 2 * n && count != 3 * n) || count > 3 * MOTION_GUARD_CHANNELS ||
        size != LIVE_HEADER + 8 * (ssize_t)count + mac) {
        r->counts[size == LIVE_HEADER + 8 * (ssize_t)count && mac && version == LIVE_VERSION ? LIVE_UNAUTHENTICATED
                                                                                             : LIVE_MALFORMED]++;
        return;
    }
    if (mac) {
        unsigned char tag[LIVE_MAC];
        hmac_sha256(r->key, (size_t)r->key_size, p, (size_t)(size - mac), tag);
        if (!constant_time_equal(tag, p + size - mac, LIVE_MAC)) { r->counts[LIVE_UNAUTHENTICATED]++; return; }
    }
    memcpy(&session, p + 8, 8);
    memcpy(&sequence, p + 16, 8);
    memcpy(&time, p + 24, 8);
    const int owner = r->owned && from_size == r->owner_size && memcmp(from, r->owner_address, from_size) == 0 &&
                      session == r->owner_session;
    if (r->owned && !owner) { r->counts[LIVE_FOREIGN]++; return; }
    memcpy(values, p + LIVE_HEADER, 8 * (size_t)count);
    int finite = !isinf(time);
    for (int i = 0; i < count; i++) finite = finite && isfinite(values[i]);
    if (!finite) { r->counts[LIVE_NON_FINITE]++; return; }
    if (!isnan(time) && time > t_now + h * (1.0 + 1e-9)) { r->counts[LIVE_FUTURE]++; return; }
    if (!isnan(time) && time < t_now - h - r->late_after) { r->counts[LIVE_LATE]++; return; }
    const int numbers = numbers_within(r, values, count, r->late_after + r->watchdog + h);
    if (numbers < 0) { r->counts[LIVE_NON_FINITE]++; return; }
    if (numbers == 0) { r->counts[LIVE_BEYOND_LIMITS]++; return; }
    if (owner && sequence == r->live_sequence) { r->counts[LIVE_REPEATED]++; return; }
    if (owner && sequence < r->live_sequence) { r->counts[LIVE_OUT_OF_ORDER]++; return; }
    const int within = !r->admissible || r->admissible(r->admissible_context, values);
    r->counts[within ? LIVE_ACCEPTED : LIVE_OUTSIDE]++;
    if (!owner) { /* the first sender, or the first after a silence, owns the input */
        r->owned = 1;
        r->owner_size = from_size;
        memcpy(r->owner_address, from, from_size);
        r->owner_session = session;
    }
    r->live_sequence = sequence;
    r->last_good = clock_seconds(CLOCK_MONOTONIC);
    r->watchdog_engaged = 0;
    if (r->live_active != 2) start_reference(s, r); /* it starts where the replaced outputs are */
    r->live_target = 1;
    r->target_time = isnan(time) ? t_now : time;
    for (int i = 0; i < n; i++) {
        r->live[TARGET * n + i] = values[i];
        r->live[TARGET_RATE * n + i] = count >= 2 * n ? values[n + i] : 0.0;
        r->live[TARGET_ACCELERATION * n + i] = count >= 3 * n ? values[2 * n + i] : 0.0;
    }
}

/* The guard's view of the reference (motion_guard.h): its channels' limits and the envelope. */
static MotionGuard guard_of(const RealTime *r) {
    const MotionGuard g = {r->n_live, r->rate_max, r->acceleration_max, r->guard, r->recover, r->guard_context};
    return g;
}

/* A step on which the envelope held the reference back, counted by what held it (bits). */
static void count_held(RealTime *r, int held) {
    for (int k = 0; k < GUARD_KINDS; k++)
        if (held & (1 << k)) r->guard_counts[k]++;
}

/* The reference carried over the step just taken with the motion handed on for it, chosen or
 * passed on (not on the step it starts: it starts where the replaced outputs are). */
static void carry_reference(RealTime *r, double h) {
    if (r->live_active >= 2) motion_guard_carry(r->n_live, r->live, h);
}

/* The reference's motion over the next step: its acceleration chosen towards the target
 * (extrapolated by its rate and acceleration from the time it was given for, never further than
 * the watchdog's silence), held within the envelope (motion_guard_advance). Constant over a step,
 * that acceleration makes the value, rate and acceleration handed to the inputs the reference's
 * exact motion over the step. */
static void advance_reference(RealTime *r, double t_new, double h) {
    const int n = r->n_live;
    double since = t_new - r->target_time, goal[3 * MOTION_GUARD_CHANNELS];
    if (fabs(since) > r->watchdog) since = copysign(r->watchdog, since); /* never extrapolated further */
    for (int i = 0; i < n; i++) {
        const double target = r->live[TARGET * n + i], target_rate = r->live[TARGET_RATE * n + i],
                     target_acceleration = r->live[TARGET_ACCELERATION * n + i];
        goal[i] = target + target_rate * since + 0.5 * target_acceleration * since * since;
        goal[n + i] = target_rate + target_acceleration * since;
        goal[2 * n + i] = target_acceleration;
    }
    const MotionGuard g = guard_of(r);
    count_held(r, motion_guard_advance(&g, r->live, goal, h)); /* rows VALUE, RATE, ACCELERATION */
    r->live_active = 2;
}

/* The datagrams waiting, each classified. */
static void receive_packets(Kernel *s, RealTime *r, double t_new, double h) {
    for (;;) {
        struct sockaddr_storage from;
        socklen_t from_size = sizeof from;
        memset(&from, 0, sizeof from);
        const ssize_t size = recvfrom(r->listen_fd, r->received, (size_t)r->receive_size, MSG_DONTWAIT,
                                      (struct sockaddr *)&from, &from_size);
        if (size < 0) break; /* nothing more waiting (or the socket failed: the input is then silent) */
        take_packet(s, r, size, &from, from_size <= sizeof from ? (unsigned)from_size : (unsigned)sizeof from, t_new, h);
    }
}

static void live_step(Kernel *s, RealTime *r, double t_new, double h, double *row) {
    const int n = r->n_live;
    if (r->listen_fd >= 0) receive_packets(s, r, t_new, h);
    if (r->live_target && !r->watchdog_engaged && clock_seconds(CLOCK_MONOTONIC) - r->last_good > r->watchdog) {
        for (int i = 0; i < n; i++) {
            r->live[TARGET * n + i] = r->neutral[i];
            r->live[TARGET_RATE * n + i] = r->live[TARGET_ACCELERATION * n + i] = 0.0;
        }
        r->target_time = t_new;
        r->watchdog_engaged = 1;
        r->owned = 0; /* the silent owner lets go: the next good sender takes the input */
        r->watchdog_time = t_new;
        r->counts[LIVE_WATCHDOG]++;
    }
    carry_reference(r, h);
    if (!r->live_target) { /* no live target: the outputs' own motion, guarded where asked */
        double own[3 * MOTION_GUARD_CHANNELS];
        if (!r->guard_source) return;
        own_motion(s, r, own);
        /* passed on as it is while the guard would take it, kept as the reference's motion: what the
         * inputs were handed over the step, from which a reference the guard must hold starts, with
         * no jump (motion_guard_follow: the cueing FMU's own guard steps the same way) */
        const MotionGuard g = guard_of(r);
        const int held = motion_guard_follow(&g, r->live, &r->live_active, own, h);
        if (held < 0) return;
        count_held(r, held);
    } else {
        if (!r->live_active) return;
        advance_reference(r, t_new, h);
    }
    const KernelInstance *in = &s->instances[r->live_instance];
    double *latest = s->samples + (size_t)(s->n_samples - 1) * (size_t)s->n_sample_values;
    for (int i = 0; i < n; i++) { /* the history's newest sample, as if the instance had given it */
        const int at = in->output_offset + r->live_index[i];
        latest[at] = r->live[VALUE * n + i];
        if (in->rate_order >= 1) s->exact_rates[at] = r->live[RATE * n + i];
        if (in->rate_order >= 2) s->exact_rates[s->n_sample_values + at] = r->live[ACCELERATION * n + i];
        if (r->live_column[i] >= 0) row[r->live_column[i]] = latest[at];
        if (r->live_rate_index[i] < 0) continue;
        /* the output that carries the reference's rate (a master that gives no derivatives hands it
         * to the inputs that take the rate): the live rate, its rate the live acceleration, constant
         * over the step */
        const int rate_at = in->output_offset + r->live_rate_index[i];
        latest[rate_at] = r->live[RATE * n + i];
        if (in->rate_order >= 1) s->exact_rates[rate_at] = r->live[ACCELERATION * n + i];
        if (in->rate_order >= 2) s->exact_rates[s->n_sample_values + rate_at] = 0.0;
        if (r->live_rate_column[i] >= 0) row[r->live_rate_column[i]] = latest[rate_at];
    }
}

double realtime_after_step(Kernel *s, RealTime *r, double t_new, double h, double *row) {
    if (r->listen_fd >= 0 || r->guard_source) live_step(s, r, t_new, h, row);
    if (r->stream_fd >= 0 && --r->stream_countdown <= 0) {
        stream_row(r, row);
        r->stream_countdown = r->stream_every;
    }
    if (r->factor <= 0.0) return 0.0;
    return clock_seconds(CLOCK_MONOTONIC) - (r->origin + (t_new - r->t0) / r->factor);
}
