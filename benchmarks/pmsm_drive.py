"""CPU time per simulated second of one pmsm_drive instance, per inverter model, at the default
internal solver settings (RK4 at 0.1 ms; switching: steps <= 5 us), with Dormand-Prince 5(4), and
with the L-stable Rosenbrock-W method ROS34PW2 (one step per 1 ms communication step, and adaptive),
with RK4 at 0.2 ms (the shipped Meng scenes' step) and with the exponential integrator
(solver.exponential: ETDRK4 on the current loops' linear part, one step per communication step).

Duty: the position loop follows a 2 Hz, 10 rad sine of the angle reference (22 A peak) on the
motor-side inertia of one leg (J_eq = 0.0209 kg m^2), at the platform's 1 ms communication step.
The FMU is stepped from C (benchmarks/drive_bench.c), so the figure is the FMU's own cost; the same
duty stepped from Python through fmpy (cosim.bench) is measured in the same run, and the ratio is
the per-call cost a Python master adds.

    python benchmarks/pmsm_drive.py [--seconds 5]
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "examples"))
from common import publish, run_native  # noqa: E402

from drive_bench import RigidInertia, run_on_inertia  # noqa: E402
from cosim.engine.fmi import FmuInstance  # noqa: E402
from cosim.engine.artifacts import fmu_path  # noqa: E402
from cosim.engine.observers import TaskProgress  # noqa: E402

J_EQ, AMPLITUDE, FREQUENCY, STEP = 0.0209, 10.0, 2.0, 1e-3
PORTS = ("angle_ref", "angle", "speed", "torque")
CASES = [  # name, parameters, goal [s CPU per simulated s]
    ("ideal, RK4 0.1 ms (default)", {"inverter.model": 1}, 2e-3),
    ("averaged, RK4 0.1 ms (default)", {"inverter.model": 2}, 2e-3),
    ("averaged, Dormand-Prince 1e-6", {"inverter.model": 2, "solver.method": 2}, 2e-3),
    ("switching, RK4 <= 5 us (default)", {"inverter.model": 3}, 0.5),
    ("switching, Dormand-Prince 1e-6", {"inverter.model": 3, "solver.method": 2}, 0.5),
    ("averaged, ROS34PW2 1 ms (L-stable)", {"inverter.model": 2, "solver.method": 3, "solver.step": 1e-3}, 2e-3),
    ("averaged, ROS34PW2 1e-6", {"inverter.model": 2, "solver.method": 4, "solver.step": 1e-3}, 2e-3),
    ("averaged, RK4 0.2 ms (the Meng scenes')", {"inverter.model": 2, "solver.step": 2e-4}, 2e-3),
    ("averaged, exponential 1 ms (ETDRK4)", {"inverter.model": 2, "solver.exponential": True, "solver.step": 1e-3},
     2e-3),
]


def python_loop_cost(parameters: dict, seconds: float) -> float:
    drive = FmuInstance(fmu_path("pmsm_drive"), "python_loop")
    drive.initialize(parameters)
    start = time.process_time()
    run_on_inertia(drive, RigidInertia(J_EQ), seconds, STEP,
                   lambda t: {"angle_ref": AMPLITUDE * np.sin(2 * np.pi * FREQUENCY * t)})
    cost = (time.process_time() - start) / seconds
    drive.free()
    return cost


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seconds", type=float, default=5.0, help="simulated seconds per case")
    args = parser.parse_args()
    progress = TaskProgress("pmsm_drive benchmark", len(CASES) + 1)
    lines = ["| case | CPU per simulated second | real-time factor | goal | tracking error |", "|---|---|---|---|---|"]
    native = {}
    for name, parameters, goal in CASES:
        seconds = args.seconds if "switching" not in name else min(args.seconds, 1.0)
        cpu, error = run_native("pmsm_drive", PORTS, STEP, seconds, J_EQ, AMPLITUDE, FREQUENCY, parameters)
        native[name] = cpu
        lines.append(f"| {name} | {cpu * 1e3:.2f} ms | {1 / cpu:.0f} | <= {goal * 1e3:g} ms | {error:.1e} rad |")
        progress.advance(name)
    averaged = CASES[1]
    python_cost = python_loop_cost(averaged[1], min(args.seconds, 2.0))
    progress.advance("through fmpy")
    lines += ["", "Ratios in this run: switching / averaged (defaults) "
              f"{native[CASES[3][0]] / native[averaged[0]]:.1f}; Dormand-Prince / RK4 (averaged) "
              f"{native[CASES[2][0]] / native[averaged[0]]:.1f}; ROS34PW2 at 1 ms / RK4 at 0.1 ms (averaged) "
              f"{native[CASES[5][0]] / native[averaged[0]]:.2f}; exponential at 1 ms / RK4 at 0.2 ms "
              f"{native[CASES[8][0]] / native[CASES[7][0]]:.2f}; the same duty stepped through fmpy's Python API / "
              f"the native loop {python_cost / native[averaged[0]]:.1f} ({python_cost * 1e3:.1f} ms per simulated "
              "second through fmpy)."]
    print("\n".join(lines))
    if args.seconds == 5.0:  # the documented command
        publish("pmsm_drive", "python benchmarks/pmsm_drive.py", lines)


if __name__ == "__main__":
    main()
