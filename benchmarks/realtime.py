"""The platform paced to the wall clock (cosim.engine.realtime): how late its steps start, how
often one overruns, and what it costs.

Meng's scene (scenes/meng_eq35.toml) paced at real time for 30 s, its stream at 1 kHz (every
macro step) to a receiver and a sender at 100 Hz giving its pose reference (a slow sway about the
neutral pose, as a motion-cueing host would), both in a second process, so that this process's CPU
time is the run's alone. Four runs: at 1 ms throughout (the scene's finer start and edge windows
off: a step every millisecond), as shipped (its first 75 ms and 5 ms after each load edge at
62.5 us: a deadline every 62.5 us there), and each with the drives on two threads. Reported per
run: lateness of a step's start p50 / p99 / largest, overruns, the packets taken, and the CPU
share (the run's process CPU time over its wall time, set-up included); then the first again beside
the test suite's packet fuzzer (tests/platform/packet_fuzz.py) sending hostile datagrams at about
1 kHz from a third process (the hostile case: what the live input's checks and the envelope's guard
cost), and with the process in the real-time scheduling class SCHED_FIFO where that is permitted.
The goals: p99 at most 0.2 ms, the largest 1 ms, no overrun.

    python benchmarks/realtime.py [--seconds 30] [--write]
"""

from __future__ import annotations

import argparse
import multiprocessing
import os
import socket
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import publish  # noqa: E402
import cosim  # noqa: E402
from cosim.platform.core import Core  # noqa: E402


def free_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as probe:
        probe.bind(("127.0.0.1", 0))
        return probe.getsockname()[1]


def client(stream: str, listen: str, neutral: list[float], seconds: float, out) -> None:
    """Receives the stream (counting samples and gaps) and sends a pose at 100 Hz meanwhile."""
    import threading
    from cosim.realtime import Sender, receive
    counted = {"samples": 0, "gaps": 0, "last": -1}

    def listen_loop():
        for sample in receive(stream, timeout=5.0):
            counted["gaps"] += sample.sequence != counted["last"] + 1
            counted["last"] = sample.sequence
            counted["samples"] += 1

    receiver = threading.Thread(target=listen_loop)
    receiver.start()
    with Sender(listen) as sender:
        start = time.monotonic()
        k = 0
        while time.monotonic() - start < seconds + 10:  # set-up first, then the run's seconds
            t = time.monotonic() - start
            pose = list(neutral)
            pose[1] += 0.05 * np.sin(2 * np.pi * 0.2 * t)
            pose[3] += 0.03 * np.sin(2 * np.pi * 0.3 * t)
            sender.send(pose)
            k += 1
            time.sleep(max(0.0, start + 0.01 * k - time.monotonic()))
            if not receiver.is_alive():
                break
    receiver.join()
    out.put(counted)


def hostile(port: int, neutral: list[float], seconds: float) -> None:
    """The packet fuzzer at about 1 kHz, once the good sender owns the input."""
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "tests" / "platform"))
    from packet_fuzz import fuzz
    time.sleep(2.0)
    fuzz(("127.0.0.1", port), np.array(neutral), lambda: 0.0, count=int(1000 * seconds), seconds=seconds, seed=1)


def paced(seconds: float, finer: bool, threads: int, fuzzed: bool = False) -> dict:
    stream, listen = f"udp://127.0.0.1:{free_port()}", f"udp://127.0.0.1:{free_port()}"
    queue = multiprocessing.Queue()
    other = multiprocessing.Process(target=client, args=(stream, listen, Core().neutral_pose.tolist(), seconds, queue))
    other.start()
    if fuzzed:
        multiprocessing.Process(target=hostile, args=(int(listen.rsplit(":", 1)[1]), Core().neutral_pose.tolist(),
                                                      seconds), daemon=True).start()
    time.sleep(1.0)  # the receiver is bound
    overrides = {"coupling.threads": threads} | ({} if finer else {"coupling.startup_time": 0.0,
                                                                     "coupling.edge_time": 0.0})
    cpu, wall = time.process_time(), time.perf_counter()
    run = cosim.simulate("meng_eq35", duration=seconds, overrides=overrides, real_time=1.0, stream=stream,
                         listen=listen)
    cpu, wall = time.process_time() - cpu, time.perf_counter() - wall
    counted = queue.get(timeout=60)
    other.join(30)
    pacing = run.report.pacing
    p50, p99, largest = pacing.percentiles()
    return {"p50": p50, "p99": p99, "max": largest, "overruns": pacing.overruns, "steps": len(pacing.lateness),
            "cpu": cpu / wall, "received": counted["samples"], "gaps": counted["gaps"], "streamed": pacing.streamed,
            "taken": pacing.live.get("accepted", 0),
            "refused": sum(v for k, v in pacing.live.items() if k not in ("accepted", "outside", "watchdog")),
            "worst": float(run["time"][1:][1:][np.argmax(pacing.lateness)])}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=30.0)
    args = parser.parse_args()
    rows = ["| meng_eq35 paced at 1 x for {:g} s | steps | lateness p50 / p99 / largest [ms] | overruns | "
            "worst at t [s] | samples received / sent (gaps) | references taken | CPU share |".format(args.seconds),
            "|---|---|---|---|---|---|---|---|"]
    for finer, label in ((False, "1 ms throughout"), (True, "as shipped: 62.5 us at the start and load edges")):
        for threads in (1, 2):
            r = paced(args.seconds, finer, threads)
            rows.append(f"| {label}, drives on {threads} thread{'s' if threads > 1 else ''} | {r['steps']} | "
                        f"{1e3 * r['p50']:.3f} / {1e3 * r['p99']:.3f} / {1e3 * r['max']:.3f} | {r['overruns']} | "
                        f"{r['worst']:.3f} | {r['received']} / {r['streamed']} ({r['gaps']}) | {r['taken']} | "
                        f"{100 * r['cpu']:.0f} % |")
            print(rows[-1], flush=True)
    r = paced(args.seconds, False, 1, fuzzed=True)
    rows.append(f"| 1 ms throughout, drives on 1 thread, beside the packet fuzzer at 1 kHz ({r['refused']} refused) | "
                f"{r['steps']} | {1e3 * r['p50']:.3f} / {1e3 * r['p99']:.3f} / {1e3 * r['max']:.3f} | {r['overruns']} | "
                f"{r['worst']:.3f} | {r['received']} / {r['streamed']} ({r['gaps']}) | {r['taken']} | "
                f"{100 * r['cpu']:.0f} % |")
    print(rows[-1], flush=True)
    try:  # the real-time scheduling class a rig would use (root, or CAP_SYS_NICE)
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(50))
    except (PermissionError, AttributeError, OSError):
        rows.append("| 1 ms throughout, SCHED_FIFO: not permitted here | | | | | | | |")
    else:
        r = paced(args.seconds, False, 1)
        os.sched_setscheduler(0, os.SCHED_OTHER, os.sched_param(0))
        rows.append(f"| 1 ms throughout, drives on 1 thread, SCHED_FIFO priority 50 | {r['steps']} | "
                    f"{1e3 * r['p50']:.3f} / {1e3 * r['p99']:.3f} / {1e3 * r['max']:.3f} | {r['overruns']} | "
                    f"{r['worst']:.3f} | {r['received']} / {r['streamed']} ({r['gaps']}) | {r['taken']} | "
                    f"{100 * r['cpu']:.0f} % |")
        print(rows[-1], flush=True)
    publish("realtime", "python benchmarks/realtime.py", rows)


if __name__ == "__main__":
    main()
