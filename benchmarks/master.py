"""The Meng scene (scenes/meng_eq35.toml) at a 1 ms macro step: our master against libcosim
(libcosimpy, the Open Simulation Platform's engine) stepping the same seven FMUs with the same
connections (trajectory FMU included) at the same step, in one run.

Reports the real-time factor of each, their ratio, our master's overhead share (wall time outside
FMI calls), ours also with the drives on two threads and on the L-stable ROS34PW2 solver at the
macro step, and how far the two runs' poses differ (libcosim's fixed-step algorithm holds inputs
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
    l_stable = {"scene.duration": args.duration, 'drive.parameters."solver.method"': 3,
                'drive.parameters."solver.step"': scene.step, "coupling.startup_step": scene.step / 16}
    _, rosenbrock = run_scene(load_scene(ROOT / "scenes" / "meng_eq35.toml", l_stable))
    ours = np.array([result[f"pose.{a}"][-1] for a in POSE])
    peer = run_in_libcosim(scene)
    wall_libcosim, theirs = peer.wall, peer.pose
    lines = [f"Meng scene, {args.duration:g} s at {scene.step * 1e3:g} ms, 8 FMUs (trajectory, mechanics, six drives):",
             "", "| engine | wall | real-time factor | master share of wall |", "|---|---|---|---|",
             f"| ours (Gauss-Seidel order 1, the step kernel) | {report.wall:.2f} s | {report.real_time_factor:.0f} | "
             f"{100 * report.master_share:.0f} % |",
             f"| ours, the drives on two threads (`[coupling] threads = 2`) | {threaded.wall:.2f} s | "
             f"{threaded.real_time_factor:.0f} | {100 * threaded.master_share:.0f} % |",
             f"| ours, the drives on ROS34PW2 at the macro step, the start at a sixteenth (see below) | "
             f"{rosenbrock.wall:.2f} s | {rosenbrock.real_time_factor:.0f} | {100 * rosenbrock.master_share:.0f} % |",
             f"| libcosim (fixed step) | {wall_libcosim:.2f} s | {args.duration / wall_libcosim:.0f} | |", "",
             f"Ratio in this run: libcosim's wall / ours {wall_libcosim / report.wall:.1f}, ours taking "
             f"{report.macro_steps} macro steps (the scene's finer start included), libcosim "
             f"{round(args.duration / scene.step)}; final pose difference (ours - libcosim, different algorithms) "
             f"{np.abs(ours - theirs).max():.1e}; the L-stable drives / the shipped RK4 drives "
             f"{rosenbrock.wall / report.wall:.2f} in wall time ({rosenbrock.macro_steps} macro steps). With the "
             "drives' L-stable solver at one step per macro step the start needs a sixteenth of the step to keep the "
             "torques within 1 % of their peak (tests/platform/test_step_control.py); the scene does not ship it as its "
             "default yet because a scene's drive parameters would follow a swapped drive (the linear motor needs "
             "0.5 ms steps on it)."]
    print("\n".join(lines))
    if args.duration == 10.0:
        publish("master", "python benchmarks/master.py", lines)


if __name__ == "__main__":
    main()
