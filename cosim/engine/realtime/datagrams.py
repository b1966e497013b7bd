"""The real-time datagrams (docs/guide/realtime.md, docs/interfaces.md), little-endian, for the
run's own sockets, users and tests: the stream's samples and layouts a run sends, the live input's
references it takes, with a receiver and a sender.

- stream, one a sample: "CSIM", version (u16, 1), n (u16), sequence (u64), simulated time (f64),
  wall clock as Unix time (f64), then n values (f64);
- stream layout, before the first sample and then every second: "CSLY", version (u16, 1), n (u16),
  then the n column names, UTF-8, one per line;
- live input: "CREF", version (u16, 2), count (u16: n values, then optionally n rates and n
  accelerations), session (u64: the sender's, chosen at random once), sequence (u64), the simulated
  time they are for (f64, NaN: now), the values; with a key, then the HMAC-SHA256 of all that
  (32 bytes). Version 1 (no session) is refused, counted as old.
"""

from __future__ import annotations

import math
import os
import struct
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Iterator, Sequence

import numpy as np

from ..errors import UsageError

VERSION = 1           # the stream's
LIVE_VERSION = 2      # the live input's (1 had no session: refused)
SAMPLE = struct.Struct("<4sHHQdd")     # magic, version, n, sequence, time, wall
LAYOUT = struct.Struct("<4sHH")        # magic, version, n; then the names
REFERENCE = struct.Struct("<4sHHQQd")  # magic, version, count, session, sequence, time
MAC_SIZE = 32                          # HMAC-SHA256
MAX_VALUES = (65507 - SAMPLE.size) // 8  # what one UDP datagram holds
DEFAULT_HOST = "127.0.0.1"
KEY_MIN = 16                           # bytes of a shared key, at least
KEY_MAX = 256


def address(text: str, option: str) -> tuple[str, int, dict[str, str]]:
    """udp://HOST:PORT[?key=value] (HOST may be left out: 127.0.0.1) as (host, port, query);
    a UsageError naming `option` for anything else."""
    from urllib.parse import parse_qs, urlsplit  # here: a run that streams nothing loads no networking
    parts = urlsplit(text if "://" in text else f"udp://{text}")
    try:
        port = parts.port
    except ValueError:
        port = None
    if parts.scheme != "udp" or port is None or parts.path not in ("", "/"):
        raise UsageError(f"{option} {text}: expected udp://HOST:PORT (HOST defaults to {DEFAULT_HOST})")
    query = {k: v[-1] for k, v in parse_qs(parts.query, keep_blank_values=True).items()}
    return parts.hostname or DEFAULT_HOST, port, query


def is_loopback(host: str) -> bool:
    """True if every address `host` names is this machine's loopback (127.0.0.0/8, ::1)."""
    import ipaddress
    import socket
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        pass
    try:
        found = socket.getaddrinfo(host, None, type=socket.SOCK_DGRAM)
    except OSError:
        return False
    return bool(found) and all(ipaddress.ip_address(info[4][0].split("%")[0]).is_loopback for info in found)


def read_key(path: str | os.PathLike, option: str = "--listen-key") -> bytes:
    """The shared key in a file: its bytes, surrounding white space stripped, 16 to 256 of them."""
    try:
        key = Path(path).read_bytes().strip()
    except OSError as error:
        raise UsageError(f"{option} {path}: {error.strerror or error}") from None
    if not KEY_MIN <= len(key) <= KEY_MAX:
        raise UsageError(f"{option} {path}: a key of {len(key)} bytes; it takes {KEY_MIN} to {KEY_MAX} (e.g. "
                         "`openssl rand -hex 32 > FILE`)")
    return key


def layout_datagram(names: Sequence[str]) -> bytes:
    return LAYOUT.pack(b"CSLY", VERSION, len(names)) + "\n".join(names).encode()


@dataclass(frozen=True)
class Sample:
    """One streamed sample: its sequence number, simulated time, wall clock (Unix time) when it
    was sent, and its values by name (`sample["pose.z"]`)."""
    sequence: int
    time: float
    wall: float
    names: tuple[str, ...]
    values: np.ndarray

    def __getitem__(self, name: str) -> float:
        try:
            return float(self.values[self.names.index(name)])
        except ValueError:
            raise KeyError(f"'{name}' is not streamed (streamed: {', '.join(self.names)})") from None

    def as_dict(self) -> dict[str, float]:
        return dict(zip(self.names, self.values.tolist()))


def decode(datagram: bytes, names: Sequence[str] | None = None) -> Sample | list[str] | None:
    """A sample (named by `names`, else value[k]), a layout (its names), or None for anything else."""
    if datagram[:4] == b"CSLY" and len(datagram) >= LAYOUT.size:
        _, version, n = LAYOUT.unpack_from(datagram)
        listed = datagram[LAYOUT.size:].decode("utf-8", "replace").split("\n") if n else []
        return listed if version == VERSION and len(listed) == n else None
    if datagram[:4] != b"CSIM" or len(datagram) < SAMPLE.size:
        return None
    _, version, n, sequence, simulated, wall = SAMPLE.unpack_from(datagram)
    if version != VERSION or len(datagram) != SAMPLE.size + 8 * n:
        return None
    values = np.frombuffer(datagram, dtype="<f8", count=n, offset=SAMPLE.size).copy()
    named = tuple(names) if names is not None and len(names) == n else tuple(f"value[{k}]" for k in range(n))
    return Sample(sequence, simulated, wall, named, values)


def receive(where: str, timeout: float | None = 10.0, names: Sequence[str] | None = None,
            ready=None, until=None) -> Iterator[Sample]:
    """The samples a run streams to `where` (udp://HOST:PORT, HOST default 127.0.0.1), decoded and
    named by the layout the stream sends (or by `names`); ends when nothing arrives for `timeout`
    seconds (None: never) or, if `until` (a threading.Event) is given, only once it is set.
    `ready`, if given, is called once the socket is bound (a test starts the run then). Samples
    that arrive before the first layout are held until it comes."""
    import socket
    host, port, _ = address(where, "receive")
    sock = socket.socket(socket.AF_INET6 if ":" in host else socket.AF_INET, socket.SOCK_DGRAM)
    try:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 1 << 22)
        sock.bind((host, port))
        sock.settimeout(0.2 if until is not None else timeout)
        if ready is not None:
            ready()
        layout, held = list(names) if names is not None else None, []
        while until is None or not until.is_set():
            try:
                datagram = sock.recv(65535)
            except (socket.timeout, TimeoutError):
                if until is not None:
                    continue
                break
            decoded = decode(datagram, layout)
            if isinstance(decoded, list):
                if layout is None or decoded != layout:  # a new run may stream other columns
                    layout = decoded
                    yield from (decode(d, layout) for d in held)
                    held = []
            elif decoded is not None:
                if layout is None:
                    held.append(datagram)
                else:
                    yield decoded
        yield from (decode(d, layout) for d in held)
    finally:
        sock.close()


def reference_datagram(values: Sequence[float], sequence: int, time: float | None = None,
                       rates: Sequence[float] | None = None, accelerations: Sequence[float] | None = None,
                       session: int = 0, key: bytes | None = None) -> bytes:
    """One live-input datagram: the values (and their rates, and then accelerations, if given) for
    simulated time `time` (None: apply on arrival), from `session`, tagged with `key` if given."""
    parts = [list(values)]
    if rates is not None:
        parts.append(list(rates))
    if accelerations is not None:
        if rates is None:
            parts.append([0.0] * len(parts[0]))
        parts.append(list(accelerations))
    if any(len(p) != len(parts[0]) for p in parts):
        raise UsageError("send: values, rates and accelerations must be as many each")
    flat = [float(v) for p in parts for v in p]
    datagram = REFERENCE.pack(b"CREF", LIVE_VERSION, len(flat), session, sequence,
                              math.nan if time is None else float(time)) + struct.pack(f"<{len(flat)}d", *flat)
    if not key:
        return datagram
    import hashlib
    import hmac
    return datagram + hmac.new(key, datagram, hashlib.sha256).digest()


class Sender:
    """Sends live-input datagrams to `where` (udp://HOST:PORT), numbering them, as one session (a
    random id unless given), tagged with `key` (the run's --listen-key) if given."""

    def __init__(self, where: str, key: bytes | None = None, session: int | None = None):
        import socket
        host, port, _ = address(where, "send")
        self.socket = socket.socket(socket.AF_INET6 if ":" in host else socket.AF_INET, socket.SOCK_DGRAM)
        self.target, self.sequence, self.key = (host, port), 0, key
        self.session = int.from_bytes(os.urandom(8), "little") if session is None else session

    def send(self, values: Sequence[float], time: float | None = None, rates: Sequence[float] | None = None,
             accelerations: Sequence[float] | None = None) -> int:
        """Sends one; returns its sequence number."""
        sequence = self.sequence
        self.socket.sendto(reference_datagram(values, sequence, time, rates, accelerations, self.session, self.key),
                           self.target)
        self.sequence += 1
        return sequence

    def close(self) -> None:
        self.socket.close()

    def __enter__(self) -> "Sender":
        return self

    def __exit__(self, *exc) -> None:
        self.close()


if sys.byteorder != "little":  # the kernel writes and reads the datagrams in the host's order
    raise ImportError("cosim.engine.realtime: the datagrams are little-endian and this host is not")
