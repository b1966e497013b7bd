"""Real time: a run paced to the wall clock, streamed out live and driven from outside
(docs/guide/realtime.md). `session`: what a run is asked for, its sockets and the C side's state
over the run, what it measured; `datagrams`: the layouts on the wire, a receiver and a sender. The
stepping itself, the pacing, the stream and the live input's checks are in C
(cosim/engine/kernel/realtime.c); the platform's part (its stream, its envelope, the live view)
is cosim.platform.realtime."""

from .datagrams import (LAYOUT, LIVE_VERSION, MAC_SIZE, MAX_VALUES, REFERENCE, SAMPLE, VERSION, Sample, Sender,
                        address, decode, is_loopback, layout_datagram, read_key, receive, reference_datagram)
from .session import GUARD_KINDS, LIVE_KINDS, LiveInput, Pacing, RealTime, Session, _RealTime, batch_size

__all__ = ["LAYOUT", "LIVE_VERSION", "MAC_SIZE", "MAX_VALUES", "REFERENCE", "SAMPLE", "VERSION", "Sample", "Sender",
           "address", "decode", "is_loopback", "layout_datagram", "read_key", "receive", "reference_datagram",
           "GUARD_KINDS", "LIVE_KINDS", "LiveInput", "Pacing", "RealTime", "Session", "_RealTime", "batch_size"]
