"""Talking to a run in real time (docs/guide/realtime.md): `receive` the samples a run streams
(`cosim run SCENE --real-time --stream udp://127.0.0.1:9870`), `send` it poses to follow
(`--listen udp://127.0.0.1:9871`).

    for sample in cosim.realtime.receive("udp://127.0.0.1:9870"):
        print(sample.sequence, sample.time, sample["pose.z"])

    cosim.realtime.send("udp://127.0.0.1:9871", [0, 0, 1.74, 0, 0.05, 0])

The layouts are those of cosim.engine.realtime (and `cosim stream-layout SCENE`).
"""

from __future__ import annotations

import atexit
from typing import Sequence

from .engine.realtime import Sample, Sender, decode, read_key, receive, reference_datagram

__all__ = ["receive", "send", "Sample", "Sender", "decode", "read_key", "reference_datagram"]

_senders: dict[str, Sender] = {}


def send(address: str, pose: Sequence[float], time: float | None = None, rates: Sequence[float] | None = None,
         accelerations: Sequence[float] | None = None, key: bytes | None = None) -> int:
    """Sends one pose (x, y, z [m], roll, pitch, yaw [rad], absolute as a scene's reference is) to
    a run listening at `address`, for simulated time `time` (None: on arrival), with its rates and
    accelerations if given, tagged with `key` (the run's --listen-key) if given; numbered after the
    last one this process sent there, as one session. Returns its sequence number."""
    sender = _senders.get(address)
    if sender is None:
        sender = _senders[address] = Sender(address, key)
    sender.key = key
    return sender.send(pose, time, rates, accelerations)


@atexit.register
def _close() -> None:
    for sender in _senders.values():
        sender.close()
