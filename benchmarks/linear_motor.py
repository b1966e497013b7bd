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
from common import run_native  # noqa: E402

PORTS = ("position_ref", "position", "velocity", "force")
CASES = [
    ("everything on (electrical, friction, ripple)", {"effects.friction": 1, "effects.ripple": 1}),
    ("electrical dynamics, default (no friction, ripple)", {}),
    ("ideal force source (electrical off)", {"effects.electrical": 0}),
]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seconds", type=float, default=5.0)
    args = parser.parse_args()
    print(f"{'case':<52} {'CPU ms/sim s':>12} {'real-time x':>11} {'vs goal 1 ms':>12} {'tracking err':>13}")
    cost = {}
    for name, settings in CASES:
        cpu, error = run_native("linear_motor", PORTS, 1e-3, args.seconds, 5.0, 0.01, 2.0, settings)
        cost[name] = cpu
        print(f"{name:<52} {cpu * 1e3:>12.3f} {1 / cpu:>11.0f} {cpu / 1e-3:>12.2f} {error:>11.2e} m")
    print(f"\nratio everything on / ideal force source: {cost[CASES[0][0]] / cost[CASES[2][0]]:.1f}")


if __name__ == "__main__":
    main()
