"""A live-input packet fuzzer, written from docs/guide/realtime.md: random and mutated datagrams of
all three kinds (samples, layouts, references), every field and sizes from 0 to 65507 bytes, in
bursts, from a socket of its own that also owns the input (its valid references come first), so
that every check the run makes is reached. Bounded in count and time; returns what it sent."""

from __future__ import annotations

import math
import os
import socket
import struct
import time

import numpy as np

HEADER = struct.Struct("<4sHHQQd")  # CREF, version, count, session, sequence, time (the guide's table)
SAMPLE = struct.Struct("<4sHHQdd")   # CSIM, version, n, sequence, time, wall
SPECIAL = (0.0, -0.0, 1e-300, -1e300, 1e300, 1.79e308, -1.79e308, math.inf, -math.inf, math.nan, 5e-324)


def reference(session: int, sequence: int, t: float, values: np.ndarray) -> bytes:
    return HEADER.pack(b"CREF", 2, len(values), session, sequence, t) + np.asarray(values, "<f8").tobytes()


def fuzz(target: tuple[str, int], neutral: np.ndarray, now, count: int = 1500, seconds: float = 1.5,
         seed: int = 0, rate_max: float = 0.25) -> int:
    """Sends `count` datagrams to `target` over about `seconds` (bursts of up to 20, then a pause);
    `now()`: the run's simulated time as the sender last saw it. Returns the number sent."""
    rng = np.random.default_rng(seed)
    session = int.from_bytes(os.urandom(8), "little")
    sequence, sent = 1, 0
    start = time.monotonic()
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as sock:
        sock.sendto(reference(session, 0, math.nan, neutral), target)  # the input is this sender's
        sent += 1
        while sent < count and time.monotonic() - start < 2 * seconds:
            for _ in range(int(rng.integers(1, 21))):
                sock.sendto(_datagram(rng, session, sequence, neutral, now(), rate_max), target)
                sequence += int(rng.integers(-2, 4))
                sequence = max(sequence, 0)
                sent += 1
            time.sleep(seconds / count * 10)
    return sent


def _datagram(rng: np.random.Generator, session: int, sequence: int, neutral: np.ndarray, now: float,
              rate_max: float) -> bytes:
    kind = rng.random()
    pose = neutral + rng.uniform(-1, 1, 6) * [0.6, 0.6, 0.6, 0.8, 0.8, 1.5]  # well beyond the workspace
    count = int(rng.choice([6, 12, 18]))
    values = np.concatenate([pose, rng.uniform(-1.5, 1.5, count - 6) * rate_max])[:count]
    t = now + float(rng.choice([math.nan, 0.0, -0.05, -0.2, 0.0005, 0.002, 1000.0, 1e300]))
    if kind < 0.45:  # a well-formed reference: anywhere, any time, rates within and beyond the limits
        return reference(session, sequence, t, values)
    if kind < 0.75:  # one of its fields, or a value, replaced by a special number or random bytes
        datagram = bytearray(reference(session, sequence, t, values))
        if rng.random() < 0.5:
            at = int(rng.integers(0, (len(datagram) - 24) // 8)) * 8 + 24
            datagram[at:at + 8] = struct.pack("<d", float(rng.choice(SPECIAL)))
        else:
            for at in rng.integers(0, len(datagram), size=int(rng.integers(1, 4))):
                datagram[at] = int(rng.integers(0, 256))
        return bytes(datagram[:int(rng.integers(0, len(datagram) + 1))] if rng.random() < 0.2 else datagram)
    if kind < 0.85:  # a sample or a layout, sent to the wrong port
        if rng.random() < 0.5:
            n = int(rng.integers(0, 50))
            return SAMPLE.pack(b"CSIM", 1, n, sequence, now, time.time()) + bytes(8 * n)
        return struct.pack("<4sHH", b"CSLY", 1, 2) + b"pose.x\npose.y"
    size = int(rng.choice([0, 1, 23, 24, 31, 32, 33, 79, 80, 81, 200, 1500, 9000, 65507]))
    return rng.bytes(size)
