"""CPU time per simulated second of one pmsm_drive instance, per inverter model, at the default
internal solver settings (RK4 at 0.1 ms; switching: steps <= 5 us) and with Dormand-Prince 5(4).

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
from common import run_native  # noqa: E402

from drive_bench import RigidInertia, run_on_inertia  # noqa: E402
from cosim.engine.fmi import FmuInstance  # noqa: E402
from cosim.engine.artifacts import fmu_path  # noqa: E402

J_EQ, AMPLITUDE, FREQUENCY, STEP = 0.0209, 10.0, 2.0, 1e-3
PORTS = ("angle_ref", "angle", "speed", "torque")
CASES = [  # name, parameters, goal [s CPU per simulated s]
    ("ideal, RK4 0.1 ms (default)", {"inverter.model": 1}, 2e-3),
    ("averaged, RK4 0.1 ms (default)", {"inverter.model": 2}, 2e-3),
    ("averaged, Dormand-Prince 1e-6", {"inverter.model": 2, "solver.method": 2}, 2e-3),
    ("switching, RK4 <= 5 us (default)", {"inverter.model": 3}, 0.5),
    ("switching, Dormand-Prince 1e-6", {"inverter.model": 3, "solver.method": 2}, 0.5),
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
    print(f"{'case':<34} {'CPU ms/sim s':>12} {'real-time x':>11} {'goal ms':>8} {'cost/goal':>9} {'tracking err':>12}")
    native = {}
    for name, parameters, goal in CASES:
        seconds = args.seconds if "switching" not in name else min(args.seconds, 1.0)
        cpu, error = run_native("pmsm_drive", PORTS, STEP, seconds, J_EQ, AMPLITUDE, FREQUENCY, parameters)
        native[name] = cpu
        print(f"{name:<34} {cpu*1e3:>12.3f} {1/cpu:>11.0f} {goal*1e3:>8.1f} {cpu/goal:>9.2f} {error:>10.2e} rad")
    averaged = CASES[1]
    python_cost = python_loop_cost(averaged[1], min(args.seconds, 2.0))
    print("\nratios measured in this run:")
    print(f"  switching / averaged (defaults):          {native[CASES[3][0]] / native[averaged[0]]:8.1f}")
    print(f"  Dormand-Prince / RK4 (averaged):          {native[CASES[2][0]] / native[averaged[0]]:8.1f}")
    print(f"  fmpy Python loop / native loop (averaged): {python_cost / native[averaged[0]]:8.1f}"
          f"   ({python_cost*1e3:.1f} ms per simulated s through fmpy)")


if __name__ == "__main__":
    main()
