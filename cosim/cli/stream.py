"""`cosim stream-layout SCENE`: what `cosim run SCENE --stream` sends, byte by byte (the datagram
layouts of cosim.engine.realtime and the scene's values, with their units)."""

from __future__ import annotations

import argparse
from pathlib import Path


def add(commands) -> argparse.ArgumentParser:
    layout = commands.add_parser("stream-layout", help="the datagram layout of a scene's live stream (--stream) and "
                                 "of the live input (--listen)")
    layout.add_argument("scene", type=Path)
    return layout


def main(args: argparse.Namespace) -> int:
    from ..engine.realtime import LIVE_VERSION, MAC_SIZE, REFERENCE, SAMPLE
    from ..platform.ports import POSE
    from ..platform.realtime import stream_fields
    from ..platform.scene import load_scene
    scene = load_scene(args.scene)
    fields = stream_fields(scene)
    print(f"{scene.name}: `cosim run {args.scene} --stream udp://HOST:PORT[?every=N]` sends one datagram every N "
          "macro steps, little-endian:")
    print("  offset  type     field")
    for offset, kind, what in ((0, "char[4]", '"CSIM"'), (4, "uint16", "version (1)"),
                               (6, "uint16", f"number of values ({len(fields)})"), (8, "uint64", "sequence number"),
                               (16, "float64", "simulated time [s]"), (24, "float64", "wall clock, Unix time [s]")):
        print(f"  {offset:6d}  {kind:7s}  {what}")
    for k, (name, unit, description) in enumerate(fields):
        print(f"  {SAMPLE.size + 8 * k:6d}  float64  {name} [{unit or '1'}]: {description}")
    print('and before the first sample, then once a second, the names: "CSLY", version (uint16), their number '
          "(uint16), then the names, UTF-8, one per line.")
    print(f"`--listen udp://HOST:PORT` takes: \"CREF\", version (uint16, {LIVE_VERSION}), count (uint16: 6, 12 or 18), "
          "session (uint64, the sender's own: the first sender owns the input until it is silent past the watchdog), "
          f"sequence (uint64), the simulated time they are for (float64, NaN: on arrival), then at offset "
          f"{REFERENCE.size} the pose {', '.join(POSE)} [m, rad], then optionally its rates and its accelerations "
          f"(float64 each); with --listen-key, then the HMAC-SHA256 of all that ({MAC_SIZE} bytes).")
    return 0
