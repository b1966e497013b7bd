"""CPU time per simulated second of one linear_motor instance, with and without the electrical
dynamics, stepped from C at a 1 ms communication step (benchmarks/drive_bench.c).

Duty: PID position control of a 5 kg leg following a 2 Hz, 1 cm sine. Ratios from the same run.

    python benchmarks/linear_motor.py [--seconds 5]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import publish, run_native  # noqa: E402
from cosim.engine.observers import TaskProgress  # noqa: E402

PORTS = ("position_ref", "position", "velocity", "force")
CASES = [
    ("everything on (electrical, friction, ripple)", {"effects.friction": 1, "effects.ripple": 1}),
    ("electrical dynamics, default (no friction, ripple)", {}),
    ("ideal force source (electrical off)", {"effects.electrical": 0}),
    ("everything on, ROS34PW2 0.5 ms (L-stable; RK4 diverges at 0.5 ms)",
     {"effects.friction": 1, "effects.ripple": 1, "solver.method": 3, "solver.step": 5e-4}),
]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seconds", type=float, default=5.0)
    args = parser.parse_args()
    progress = TaskProgress("linear_motor benchmark", len(CASES))
    lines = ["| case | CPU per simulated second | real-time factor | goal | tracking error |", "|---|---|---|---|---|"]
    cost = {}
    for name, settings in CASES:
        cpu, error = run_native("linear_motor", PORTS, 1e-3, args.seconds, 5.0, 0.01, 2.0, settings)
        cost[name] = cpu
        lines.append(f"| {name} | {cpu * 1e3:.2f} ms | {1 / cpu:.0f} | <= 1 ms | {error:.1e} m |")
        progress.advance(name)
    lines += ["", f"Ratios in this run: everything on / ideal force source {cost[CASES[0][0]] / cost[CASES[2][0]]:.1f}; "
              f"ROS34PW2 at 0.5 ms / RK4 at 0.25 ms (everything on) {cost[CASES[3][0]] / cost[CASES[0][0]]:.2f}."]
    print("\n".join(lines))
    if args.seconds == 5.0:  # the documented command
        publish("linear_motor", "python benchmarks/linear_motor.py", lines)


if __name__ == "__main__":
    main()
