"""The Meng scene (scenes/meng_eq35.toml) at a 1 ms macro step: our master against libcosim
(libcosimpy, the Open Simulation Platform's engine) stepping the same seven FMUs with the same
connections (trajectory FMU included) at the same step, in one run.

Reports the real-time factor of each, their ratio, our master's overhead share (wall time outside
FMI calls), and how far the two runs' poses differ (libcosim's fixed-step algorithm holds inputs
constant over a step, like our order-0 Jacobi; ours runs the scene's Gauss-Seidel of order 1).

    python benchmarks/master.py [--duration 10]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import publish  # noqa: E402
from cosim.engine.artifacts import ROOT  # noqa: E402
from cosim.platform.libcosim import run_in_libcosim  # noqa: E402
from cosim.platform.runner import run_scene  # noqa: E402
from cosim.platform.scene import load_scene  # noqa: E402
from cosim.platform.system import POSE  # noqa: E402


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--duration", type=float, default=10.0)
    args = parser.parse_args()
    scene = load_scene(ROOT / "scenes" / "meng_eq35.toml")
    scene.duration = args.duration
    result, report = run_scene(scene)
    _, threaded = run_scene(load_scene(ROOT / "scenes" / "meng_eq35.toml",
                                       {"scene.duration": args.duration, "coupling.threads": 2}))
    ours = np.array([result[f"pose.{a}"][-1] for a in POSE])
    peer = run_in_libcosim(scene)
    wall_libcosim, theirs = peer.wall, peer.pose
    lines = [f"Meng scene, {args.duration:g} s at {scene.step * 1e3:g} ms, 8 FMUs (trajectory, mechanics, six drives):",
             "", "| engine | wall | real-time factor | master share of wall |", "|---|---|---|---|",
             f"| ours (Gauss-Seidel order 1, the step kernel) | {report.wall:.2f} s | {report.real_time_factor:.0f} | "
             f"{100 * report.master_share:.0f} % |",
             f"| ours, the drives on two threads (`[coupling] threads = 2`) | {threaded.wall:.2f} s | "
             f"{threaded.real_time_factor:.0f} | {100 * threaded.master_share:.0f} % |",
             f"| libcosim (fixed step) | {wall_libcosim:.2f} s | {args.duration / wall_libcosim:.0f} | |", "",
             f"Ratio in this run: libcosim's wall / ours {wall_libcosim / report.wall:.1f}, ours taking "
             f"{report.macro_steps} macro steps (the scene's finer start included), libcosim "
             f"{round(args.duration / scene.step)}; final pose difference (ours - libcosim, different algorithms) "
             f"{np.abs(ours - theirs).max():.1e}."]
    print("\n".join(lines))
    if args.duration == 10.0:
        publish("master", "python benchmarks/master.py", lines)


if __name__ == "__main__":
    main()
