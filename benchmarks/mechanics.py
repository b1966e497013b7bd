"""CPU time per simulated second of the mechanics FMU, full and reduced models, at its default
solver (RK4, 1 ms) and at Dormand-Prince rtol 1e-8, stepped from C at a 1 ms communication step
(benchmarks/fmu_step_bench.c), so the figure is the FMU's own cost.

Duty: weightless, zero inputs, the platform started from a shifted, tilted pose with a twist, so it
drifts and turns through the workspace (by about 0.1 m and 0.1 rad in 5 s) while every term of the
dynamics is evaluated; with gravity and no controller it would fall out of the workspace. In the
same run, the same dynamics (the C core through ctypes) integrated by scipy's solve_ivp (DOP853,
rtol 1e-8) stands for a monolithic numpy/scipy solve; the ratio is printed.

    python benchmarks/mechanics.py [--seconds 5]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent))
from common import publish, run_stepping  # noqa: E402
from cosim.engine.observers import TaskProgress  # noqa: E402
from cosim.platform.platform_core import Core  # noqa: E402
from cosim.platform.ports import POSE  # noqa: E402

TWIST = ["vx", "vy", "vz", "wx", "wy", "wz"]
CASES = [
    ("full model, RK4 1 ms (default)", {}),
    ("full model, Dormand-Prince 1e-8", {"solver.method": 2}),
    ("without motor systems", {"effects.motor_inertia": 0}),
    ("without actuators and motor systems", {"effects.motor_inertia": 0, "effects.actuator_inertia": 0}),
    ("without friction", {"effects.friction": 0}),
]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seconds", type=float, default=5.0)
    args = parser.parse_args()
    core = Core()
    pose = core.neutral_pose + np.array([0.05, -0.03, 0.1, 0.04, -0.03, 0.08])
    twist = np.array([0.02, -0.01, 0.015, 0.01, 0.02, -0.015])
    duty = {f"initial.pose.{a}": pose[k] for k, a in enumerate(POSE)}
    duty["environment.gravity_z"] = 0.0
    duty.update({f"initial.twist.{n}": twist[k] for k, n in enumerate(TWIST)})

    progress = TaskProgress("mechanics benchmark", len(CASES) + 1)
    lines = ["| case | CPU per simulated second | real-time factor | goal |", "|---|---|---|---|"]
    results = {}
    for name, settings in CASES:
        values = {**duty, **settings}
        cpu = run_stepping("mechanics", 1e-3, args.seconds, values)
        results[name] = cpu
        lines.append(f"| {name} | {cpu * 1e3:.2f} ms | {1 / cpu:.0f} | <= 5 ms |")
        progress.advance(name)

    core.p.gravity[2] = 0.0
    x0 = core.state(pose)
    x0[7:] = twist
    start = time.process_time()
    seconds = min(args.seconds, 1.0)
    solve_ivp(lambda t, x: core.derivatives(x)[0], (0, seconds), x0, method="DOP853", rtol=1e-8, atol=1e-10)
    scipy_cost = (time.process_time() - start) / seconds
    progress.advance("scipy")
    lines += ["", f"Ratios in this run: the FMU at Dormand-Prince 1e-8 (1000 communication steps per second) / "
              f"scipy's solve_ivp (DOP853, rtol 1e-8, free steps) on the same C dynamics core "
              f"{results[CASES[1][0]] / scipy_cost:.2f} (scipy: {scipy_cost * 1e3:.1f} ms per simulated second); "
              f"full model / without actuators and motor systems {results[CASES[0][0]] / results[CASES[3][0]]:.2f}."]
    print("\n".join(lines))
    if args.seconds == 5.0:  # the documented command
        publish("mechanics", "python benchmarks/mechanics.py", lines)


if __name__ == "__main__":
    main()
