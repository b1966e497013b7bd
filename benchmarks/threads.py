"""Would stepping the six drives of a Gauss-Seidel sweep on two threads pay at a 1 ms step?
(issue 12: measure first, keep only if it wins.)

benchmarks/drive_threads.c steps six pmsm_drive instances, each on its own rigid load (the leg's
motor-side inertia, a 2 Hz, 10 rad sine of the angle, phases 60 deg apart), for 5 s at 1 ms: one
after another, then three per thread on two threads meeting at a spinning barrier after every
macro step (where the mechanics would step). Reports both walls, their ratio and whether the
results are bit for bit the same, in one run, three times.

    python benchmarks/threads.py
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import fmu_library, native_bench, publish  # noqa: E402
from cosim.engine.observers import TaskProgress  # noqa: E402

PORTS = ("angle_ref", "angle", "speed", "torque")


def main() -> None:
    lib, variables, guid = fmu_library("pmsm_drive")
    exe = native_bench("drive_threads")
    progress = TaskProgress("threads benchmark", 3)
    lines = ["| run | six drives one after another | three per thread on two threads | speed-up | bit for bit |",
             "|---|---|---|---|---|"]
    ratios = []
    for run in range(1, 4):
        out = subprocess.run([str(exe), str(lib), guid, "1e-3", "5", "0.0209", "10", "2",
                              *[str(variables[p].valueReference) for p in PORTS]],
                             check=True, capture_output=True, text=True).stdout.split()
        sequential, threaded, identical = float(out[0]), float(out[1]), out[2] == "1"
        ratios.append(sequential / threaded)
        lines.append(f"| {run} | {sequential * 1e3:.1f} ms | {threaded * 1e3:.1f} ms | {ratios[-1]:.2f}x | "
                     f"{'yes' if identical else 'NO'} |")
        progress.advance(f"run {run}")
    lines += ["", f"The six drives' part of a sweep runs {min(ratios):.2f}-{max(ratios):.2f}x faster on two threads "
              "(5 s at 1 ms, wall time). The step kernel does this with `[coupling] threads = 2` (opt-in; "
              "benchmarks/master.py measures the whole scene): the mechanics steps alone between the stages, and "
              "it pays only while the second core is free; with the other core busy the spinning threads make "
              "the run 2-3x slower, so sweeps step every point on one thread."]
    print("\n".join(lines))
    publish("threads", "python benchmarks/threads.py", lines)


if __name__ == "__main__":
    main()
