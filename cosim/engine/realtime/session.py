"""A run in real time: paced to the wall clock, streamed out live and driven from outside.

The stepping stays in C (cosim/engine/kernel/realtime.c): each macro step starts at its deadline
on the monotonic clock, one datagram goes out every N steps, and the live input's datagrams
(cosim.engine.realtime.datagrams) are taken between steps. This module holds what a run is asked
for (`RealTime`, `LiveInput`), the sockets and the C side's state over the run (`Session`), and
what it measured (`Pacing`). It knows nothing of the platform: the application says which columns
stream, which outputs the live input replaces, what lies within its envelope and how the
reference is held there (C functions of the values), and what the guard's limits are called.
"""

from __future__ import annotations

import ctypes
import math
import time
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Sequence

import numpy as np

if TYPE_CHECKING:
    import socket

from ..errors import UsageError
from .datagrams import MAC_SIZE, MAX_VALUES, REFERENCE, SAMPLE, address, is_loopback, layout_datagram

LIVE_KINDS = ("accepted", "outside", "late", "future", "repeated", "out_of_order", "malformed", "old_version",
              "non_finite", "beyond_limits", "foreign", "unauthenticated", "watchdog")
GUARD_KINDS = 8  # the guard's limits, as bits (kernel.h)
MAX_LIVE = 64    # the outputs a live input replaces, at most (realtime.c's scratch: motion_guard.h's MOTION_GUARD_CHANNELS)


@dataclass(frozen=True)
class LiveInput:
    """Which outputs of which instance the live input replaces (a source that gives its outputs'
    exact derivatives: the reference then reaches its inputs with its rate and acceleration), the
    limits the reference moves within, its neutral values (where the watchdog takes it), how old
    a packet may be [s simulated] and how long the input may be silent [s wall]; `admissible`: a
    C function int(void *context, const double *values) and its context (None: any finite value),
    `refusal`: what a refused value is called in the report ('outside the workspace');
    `rate_outputs`: per output, the instance's output that carries its rate ("" where none), set
    to the live rate (the inputs that take a rate where the master gives no derivatives);
    `guard`: a C function int(void *context, double h, const double *value, const double *rate,
    double *acceleration) that holds the reference within the envelope, and its context;
    `guard_kinds`: what its bits 0, 1, .. are called in the report ('the stroke'); `recover`: a C
    function int(void *context, const double *value, double *goal) that, for values outside the
    envelope, gives the values to go back to (the guard's context; None: a reference outside is only
    braked); `guarded`: with no live target (no packet yet, or no --listen at all), the instance's own
    outputs pass through the guard too: taken as they are while the guard would take their motion,
    otherwise followed by a reference held within the envelope until it has caught up with them;
    `key`: the shared key every datagram must be tagged with (None: none)."""
    instance: str
    outputs: Sequence[str]
    rate_max: Sequence[float]
    acceleration_max: Sequence[float]
    neutral: Sequence[float]
    late_after: float = 0.1
    watchdog: float = 0.5
    admissible: object = None  # a ctypes function pointer
    admissible_context: object = None  # what it points at, kept alive with it
    refusal: str = "not admissible"
    rate_outputs: Sequence[str] = ()
    guard: object = None  # a ctypes function pointer
    guard_context: object = None
    guard_kinds: Sequence[str] = ()
    recover: object = None  # a ctypes function pointer
    guarded: bool = False
    key: bytes | None = None


@dataclass(frozen=True)
class RealTime:
    """A run paced at `factor` (simulated seconds per wall second; None: as fast as it goes),
    streamed to `stream` (udp://HOST:PORT[?every=N]: a datagram every N macro steps) with the
    recorded columns `stream_names` (default all), and driven through `listen` by `live` (with no
    `listen`, a `live` that is `guarded` holds the instance's own outputs within its envelope)."""
    factor: float | None = 1.0
    stream: str | None = None
    stream_names: Sequence[str] | None = None
    listen: str | None = None
    live: LiveInput | None = None

    def __post_init__(self):
        if self.factor is not None and not (isinstance(self.factor, (int, float)) and math.isfinite(self.factor)
                                            and self.factor > 0):
            raise UsageError(f"--real-time {self.factor}: expected a real-time factor > 0 (1: the wall clock's pace)")
        if self.stream is not None:
            _, _, query = address(self.stream, "--stream")
            unknown = sorted(set(query) - {"every"})
            if unknown:
                raise UsageError(f"--stream {self.stream}: unknown option '{unknown[0]}' (known: every)")
            if "every" in query and not (query["every"].isdigit() and int(query["every"]) >= 1):
                raise UsageError(f"--stream {self.stream}: every={query['every']} is not a whole number >= 1")
        if self.listen is not None:
            host = address(self.listen, "--listen")[0]
            if self.live is None:
                raise UsageError("--listen: this system names no outputs for a live input to replace")
            if not is_loopback(host) and not self.live.key:
                raise UsageError(f"--listen {self.listen}: {host} is not this machine's loopback (127.0.0.0/8, ::1), "
                                 "so datagrams from other machines could drive the run: give a shared key "
                                 "(--listen-key FILE) that every datagram is tagged with")

    @property
    def every(self) -> int:
        return int(address(self.stream, "--stream")[2].get("every", 1)) if self.stream else 1


class _RealTime(ctypes.Structure):
    _P, _D, _I = ctypes.c_void_p, ctypes.POINTER(ctypes.c_double), ctypes.POINTER(ctypes.c_int)
    _fields_ = [("factor", ctypes.c_double), ("origin", ctypes.c_double), ("t0", ctypes.c_double),
                ("waited", ctypes.c_double),
                ("stream_fd", ctypes.c_int), ("stream_every", ctypes.c_int), ("stream_countdown", ctypes.c_int),
                ("n_stream", ctypes.c_int), ("stream_columns", _I), ("stream_sequence", ctypes.c_ulonglong),
                ("packet", _P), ("stream_failed", ctypes.c_int), ("listen_fd", ctypes.c_int),
                ("live_instance", ctypes.c_int), ("n_live", ctypes.c_int), ("live_index", _I),
                ("live_column", _I), ("live_rate_index", _I), ("live_rate_column", _I), ("rate_max", _D), ("acceleration_max", _D), ("neutral", _D),
                ("late_after", ctypes.c_double), ("watchdog", ctypes.c_double), ("admissible", _P),
                ("admissible_context", _P), ("guard", _P), ("recover", _P), ("guard_context", _P),
                ("guard_source", ctypes.c_int), ("live_target", ctypes.c_int), ("key", _P),
                ("key_size", ctypes.c_int), ("live", _D), ("target_time", ctypes.c_double),
                ("last_good", ctypes.c_double), ("live_active", ctypes.c_int), ("watchdog_engaged", ctypes.c_int),
                ("owned", ctypes.c_int), ("owner_size", ctypes.c_uint), ("owner_address", ctypes.c_ubyte * 128),
                ("owner_session", ctypes.c_ulonglong), ("live_sequence", ctypes.c_ulonglong),
                ("counts", ctypes.c_longlong * len(LIVE_KINDS)), ("guard_counts", ctypes.c_longlong * GUARD_KINDS),
                ("watchdog_time", ctypes.c_double), ("received", _P), ("receive_size", ctypes.c_int)]


@dataclass
class Pacing:
    """What a real-time run measured: per macro step how late it started past its deadline and
    how far past the next deadline it ended [s] (> 0: an overrun), the stream's datagrams sent
    and refused by the socket, the live input's packets by kind (LIVE_KINDS), the steps at which
    the guard held the reference back, per limit (`held`), and where the watchdog last engaged
    [s simulated]."""
    factor: float | None
    lateness: np.ndarray
    finish: np.ndarray
    waited: float = 0.0  # [s] of wall time slept until deadlines
    streamed: int = 0
    stream_failed: int = 0
    live: dict[str, int] = field(default_factory=dict)
    watchdog_time: float | None = None
    refusal: str = "not admissible"
    held: dict[str, int] = field(default_factory=dict)
    dropped: int = 0  # datagrams the operating system dropped before the run could read them

    @property
    def overruns(self) -> int:
        return int(np.count_nonzero(self.finish > 0.0))

    def percentiles(self) -> tuple[float, float, float]:
        """Lateness p50, p99 and largest [s]."""
        if not len(self.lateness):
            return (math.nan,) * 3
        return (float(np.percentile(self.lateness, 50)), float(np.percentile(self.lateness, 99)),
                float(self.lateness.max()))

    def histogram(self, bins: int = 20) -> tuple[np.ndarray, np.ndarray]:
        """Counts of the steps' lateness and the bins' edges [s]."""
        top = max(float(self.lateness.max(initial=0.0)), 1e-6)
        return np.histogram(self.lateness, bins=bins, range=(0.0, top))

    def lines(self) -> list[str]:
        out = []
        if self.factor is not None and len(self.lateness):
            p50, p99, top = self.percentiles()
            out.append(f"paced at {self.factor:g} x the wall clock: lateness of a step's start p50 {1e3 * p50:.3f} ms, "
                       f"p99 {1e3 * p99:.3f} ms, largest {1e3 * top:.3f} ms; {self.overruns} of {len(self.finish)} "
                       "steps overran their deadline")
        if self.streamed or self.stream_failed:
            out.append(f"streamed {self.streamed} samples" + (f" ({self.stream_failed} not taken by the socket: no "
                                                               "receiver)" if self.stream_failed else ""))
        if self.live:
            refused = {k: v for k, v in self.live.items() if k not in ("accepted", "outside", "watchdog") and v}
            names = {"out_of_order": "out of order", "non_finite": "non-finite", "old_version": "of the old version 1",
                     "beyond_limits": "with rates or accelerations beyond the limits",
                     "future": "for a time beyond the next step", "foreign": "from another sender"}
            taken = self.live.get("accepted", 0) + self.live.get("outside", 0)
            out.append(f"live input: {taken} references taken" + (
                f" ({self.live['outside']} {self.refusal}: held at it)" if self.live.get("outside") else "") + (
                "; refused: " + ", ".join(f"{v} {names.get(k, k)}" for k, v in refused.items()) if refused else "") + (
                f"; {self.dropped} dropped unread by the operating system (its receive buffer full)"
                if self.dropped else "") +
                (f"; the watchdog engaged {self.live['watchdog']} times, last at t = {self.watchdog_time:.3f} s "
                 "(no input: back to neutral)" if self.live.get("watchdog") else ""))
        held = {k: v for k, v in self.held.items() if v}
        if held:  # (cosim.platform.run.envelope.held_line says a cueing FMU's guard's in these words)
            out.append("the envelope held the reference back at " + ", ".join(f"{v} steps by {k}" for k, v in held.items()))
        return out

    def row(self) -> dict[str, float]:
        p50, p99, top = self.percentiles()
        return {"lateness_p50": p50, "lateness_p99": p99, "lateness_max": top, "overruns": self.overruns}


class Session:
    """The C side's real-time state over one run, its sockets and what it measured. `columns`:
    the recorded column names (the row's columns 1 ..), `record`: the (instance, variable) each
    holds, `instances`: the kernel's instance names, `outputs`: per instance its coupled outputs'
    names."""

    def __init__(self, options: RealTime, columns: Sequence[str], record: Sequence[tuple[str, str]],
                 instances: Sequence[str], outputs: dict[str, Sequence[str]]):
        self.options = options
        self.state = r = _RealTime()
        self._keep: list = []
        self.lateness: list[np.ndarray] = []
        self.finish: list[np.ndarray] = []
        self.sockets: list[socket.socket] = []
        self.last_layout = -math.inf
        self.started = False
        self.watchdog_said = 0
        r.factor = options.factor or 0.0
        r.stream_fd = r.listen_fd = -1
        try:
            if options.stream:
                self._open_stream(options, list(columns))
            if options.live is not None and (options.listen or options.live.guarded):
                self._open_reference(options.live, [tuple(r) for r in record], list(instances), outputs)
            if options.listen:
                self._open_listen(options)
        except BaseException:
            self.close()
            raise

    def _array(self, values, kind=np.float64) -> np.ndarray:
        array = np.ascontiguousarray(values, dtype=kind)
        self._keep.append(array)
        return array

    def _open_stream(self, options: RealTime, columns: list[str]) -> None:
        names = list(options.stream_names) if options.stream_names is not None else columns
        missing = [n for n in names if n not in columns]
        if missing:
            raise UsageError(f"--stream: '{missing[0]}' is not recorded by this run (recorded: {', '.join(columns)})")
        if len(names) > MAX_VALUES:
            raise UsageError(f"--stream: {len(names)} values do not fit one datagram (at most {MAX_VALUES})")
        host, port, _ = address(options.stream, "--stream")
        sock = self._socket(host)
        try:
            sock.connect((host, port))
        except OSError as error:
            raise UsageError(f"--stream {options.stream}: {error.strerror or error}") from None
        self.stream_socket, self.stream_names = sock, names
        r = self.state
        r.stream_fd, r.stream_every, r.stream_countdown = sock.fileno(), options.every, options.every
        r.n_stream = len(names)
        r.stream_columns = self._array([1 + columns.index(n) for n in names], np.intc).ctypes.data_as(
            ctypes.POINTER(ctypes.c_int))
        r.packet = self._array(np.zeros(SAMPLE.size // 8 + len(names))).ctypes.data
        self.layout_datagram = layout_datagram(names)
        self.between_batches()  # the layout, before the first sample

    def _open_listen(self, options: RealTime) -> None:
        host, port, query = address(options.listen, "--listen")
        if query:
            raise UsageError(f"--listen {options.listen}: takes no options")
        sock = self._socket(host)
        try:
            sock.bind((host, port))
        except OSError as error:
            raise UsageError(f"--listen {options.listen}: {error.strerror or error}") from None
        sock.setblocking(False)
        self.listen_socket = sock
        r = self.state
        r.listen_fd = sock.fileno()
        live = options.live
        if live.key:
            key = ctypes.create_string_buffer(live.key, len(live.key))
            self._keep.append(key)
            r.key, r.key_size = ctypes.cast(key, ctypes.c_void_p).value, len(live.key)
        n = len(live.outputs)
        r.receive_size = REFERENCE.size + 8 * 3 * n + MAC_SIZE + 8
        r.received = self._array(np.zeros(r.receive_size // 8 + 1)).ctypes.data

    def _open_reference(self, live: LiveInput, record: list[tuple[str, str]], instances: list[str],
                        outputs: dict[str, Sequence[str]]) -> None:
        """The outputs the reference replaces, its limits, envelope and state."""
        r = self.state
        n = len(live.outputs)
        if n > MAX_LIVE:
            raise UsageError(f"a live input replaces at most {MAX_LIVE} outputs, not {n}")
        r.live_instance, r.n_live = instances.index(live.instance), n
        own = list(outputs[live.instance])
        ints = ctypes.POINTER(ctypes.c_int)
        r.live_index = self._array([own.index(o) for o in live.outputs], np.intc).ctypes.data_as(ints)
        replaced = [(live.instance, o) for o in live.outputs]
        r.live_column = self._array([1 + record.index(c) if c in record else -1 for c in replaced],
                                    np.intc).ctypes.data_as(ints)
        # (a rate output that feeds nothing has nothing to replace)
        rates = [(live.instance, o) if o in own else None for o in (live.rate_outputs or [""] * n)]
        r.live_rate_index = self._array([own.index(c[1]) if c else -1 for c in rates], np.intc).ctypes.data_as(ints)
        r.live_rate_column = self._array([1 + record.index(c) if c in record else -1 for c in rates],
                                         np.intc).ctypes.data_as(ints)
        doubles = ctypes.POINTER(ctypes.c_double)
        r.rate_max = self._array(live.rate_max).ctypes.data_as(doubles)
        r.acceleration_max = self._array(live.acceleration_max).ctypes.data_as(doubles)
        r.neutral = self._array(live.neutral).ctypes.data_as(doubles)
        r.late_after, r.watchdog = live.late_after, live.watchdog
        if live.admissible is not None:
            r.admissible = ctypes.cast(live.admissible, ctypes.c_void_p).value
            r.admissible_context = ctypes.cast(live.admissible_context, ctypes.c_void_p).value
            self._keep.append((live.admissible, live.admissible_context))
        if live.guard is not None:
            r.guard = ctypes.cast(live.guard, ctypes.c_void_p).value
            r.guard_context = ctypes.cast(live.guard_context, ctypes.c_void_p).value
            self._keep.append((live.guard, live.guard_context))
        if live.recover is not None:
            r.recover = ctypes.cast(live.recover, ctypes.c_void_p).value
            self._keep.append(live.recover)
        r.guard_source = int(live.guarded)
        r.live = self._array(np.zeros(6 * n)).ctypes.data_as(doubles)

    def _socket(self, host: str) -> socket.socket:
        import socket  # here: a run that streams and listens to nothing loads no networking
        family = socket.AF_INET6 if ":" in host else socket.AF_INET
        sock = socket.socket(family, socket.SOCK_DGRAM)
        self.sockets.append(sock)
        return sock

    @property
    def pointer(self):
        return ctypes.byref(self.state)

    def unpaced(self) -> "Session":
        """This session with its pacing off until `start` (the first step: streamed, not timed)."""
        self.state.factor = 0.0
        return self

    def start(self, t0: float) -> None:
        """The clock starts: simulated time t0 is due now (steps before it are not timed)."""
        self.state.factor = self.options.factor or 0.0
        self.state.origin, self.state.t0 = time.monotonic(), t0
        self.state.waited = 0.0
        self.lateness, self.finish = [], []
        self.started = True
        self.between_batches()

    def between_batches(self) -> None:
        """The stream's layout before the first sample, then once a second."""
        if self.state.stream_fd >= 0 and time.monotonic() - self.last_layout >= 1.0:
            try:
                self.stream_socket.send(self.layout_datagram)
            except OSError:
                self.state.stream_failed += 1
            self.last_layout = time.monotonic()

    def news(self) -> list:
        """What the master logs of the live input since the last call: the watchdog engaging."""
        from ..fmi import LogMessage
        engaged = int(self.state.counts[LIVE_KINDS.index("watchdog")])
        out = []
        if engaged > self.watchdog_said:
            t = float(self.state.watchdog_time)
            out.append(LogMessage("warning", "live input", f"t = {t:.6f} s: no good live input for "
                                  f"{self.options.live.watchdog:g} s: the reference goes back to the neutral pose", t))
            self.watchdog_said = engaged
        return out

    def add(self, lateness: np.ndarray, finish: np.ndarray) -> None:
        self.lateness.append(lateness)
        self.finish.append(finish)

    def pacing(self) -> Pacing:
        r = self.state
        live = dict(zip(LIVE_KINDS, list(r.counts))) if r.listen_fd >= 0 else {}
        kinds = self.options.live.guard_kinds if self.options.live else ()
        held = {kind: int(r.guard_counts[k]) for k, kind in enumerate(kinds)} if r.n_live else {}
        return Pacing(self.options.factor, np.concatenate(self.lateness) if self.lateness else np.zeros(0),
                      np.concatenate(self.finish) if self.finish else np.zeros(0), waited=float(r.waited),
                      streamed=int(r.stream_sequence), stream_failed=int(r.stream_failed), live=live,
                      watchdog_time=float(r.watchdog_time) if live.get("watchdog") else None,
                      refusal=self.options.live.refusal if self.options.live else "not admissible", held=held,
                      dropped=self._dropped())

    def _dropped(self) -> int:
        """Datagrams the operating system dropped at the listening socket, its receive buffer full:
        the socket's drop counter (Linux: /proc/net/udp and udp6, by the socket's inode; 0 where
        it cannot be read)."""
        if self.state.listen_fd < 0:
            return 0
        import os
        inode = str(os.fstat(self.state.listen_fd).st_ino)
        for table in ("/proc/net/udp", "/proc/net/udp6"):
            try:
                with open(table) as f:
                    for line in f.readlines()[1:]:
                        fields = line.split()
                        if len(fields) > 12 and fields[9] == inode:
                            return int(fields[12])
            except OSError:
                continue
        return 0

    def close(self) -> None:
        for sock in self.sockets:
            sock.close()
        self.sockets = []


def batch_size(options: RealTime, h: float) -> int:
    """Steps a kernel call takes under pacing: about a fifth of a second of wall time (at most 4000
    steps), so that the work between calls (recording, monitoring, a Ctrl-C) comes seldom and soon
    enough."""
    if options.factor is None:
        return 1000
    return int(min(4000, max(1, round(0.2 * options.factor / h))))
