"""What resolving feed-through at each communication point changes (Algorithm.feedthrough, issue
29), for every coupling scheme, in one run: on the two-mass oscillator (error at t = 1 s against
the exact solution, at 10 ms) and on the Meng scene's first second (largest pose difference and
largest torque difference, relative to the torques' peak, against the scene at 62.5 us with
Gauss-Seidel of order 1; at 0.25 ms, where every scheme is stable on it, with the finer start). An
accuracy table, not a timing: published like the other benchmarks.

    .venv/bin/python benchmarks/feedthrough.py
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))
sys.path.insert(0, str(HERE.parent))
sys.path.insert(0, str(HERE.parent / "tests"))
sys.path.insert(0, str(HERE.parent / "tests" / "engine"))
from common import publish  # noqa: E402
from cosim.engine import Algorithm, FixedStep  # noqa: E402
from cosim.engine.execution import Execution  # noqa: E402
from cosim.engine.artifacts import ROOT  # noqa: E402
from cosim.platform.ports import POSE, per_leg  # noqa: E402
from cosim.engine.outcome import RunStopped  # noqa: E402
from cosim.platform.run.runner import run_scene  # noqa: E402
from cosim.platform.scene import load_scene  # noqa: E402
from test_coupling import exact_position_1, oscillator  # noqa: E402

SCHEMES = [("jacobi", 0), ("jacobi", 1), ("jacobi", 2), ("gauss-seidel", 0), ("gauss-seidel", 1), ("gauss-seidel", 2)]


def oscillator_error(kind: str, order: int, feedthrough: bool) -> float:
    sequence = ("coupling", "mass") if kind == "gauss-seidel" else None
    with Execution(oscillator(1.0), Algorithm(kind, order, sequence, feedthrough=feedthrough), FixedStep(1e-2),
                   [("mass", "position")]) as execution:
        result = execution.run(1.0)
    return abs(float(result["mass.position"][-1]) - exact_position_1(1.0))


def meng(overrides: dict) -> np.ndarray | None:
    """The scene's first second (None if the coupling diverged)."""
    scene = load_scene(ROOT / "scenes" / "meng_eq35.toml", {"scene.duration": 1.0, **overrides})
    try:
        return run_scene(scene)[0]
    except RunStopped:
        return None


def meng_errors(result: np.ndarray | None, reference: np.ndarray) -> tuple[float, float]:
    if result is None:
        return float("nan"), float("nan")
    t = result["time"]
    pose = max(float(np.max(np.abs(result[f"pose.{a}"] - np.interp(t, reference["time"], reference[f"pose.{a}"]))))
               for a in POSE)
    peak = max(float(np.max(np.abs(reference[c]))) for c in per_leg("torque"))
    torque = max(float(np.max(np.abs(result[c] - np.interp(t, reference["time"], reference[c])))) for c in per_leg("torque"))
    return pose, torque / peak


def main() -> None:
    lines = ["Two-mass oscillator at 10 ms, error of x1 at t = 1 s against the exact solution:", "",
             "| scheme | plain | feed-through resolved |", "|---|---|---|"]
    for kind, order in SCHEMES:
        plain, resolved = oscillator_error(kind, order, False), oscillator_error(kind, order, True)
        lines.append(f"| {kind} {order} | {plain:.2e} | {resolved:.2e} |")
    reference = meng({"scene.step": 6.25e-5, "coupling.startup_time": 0.0, "coupling.edge_time": 0.0})
    lines += ["", "Meng scene, first second at 0.25 ms with the finer start: largest pose difference [m, rad] and "
              "largest torque difference [% of the peak] against the scene at 62.5 us (Gauss-Seidel, order 1; nan: "
              "diverged):", "",
              "| scheme | pose, plain | pose, resolved | torque, plain | torque, resolved |", "|---|---|---|---|---|"]
    for kind, order in SCHEMES:
        base = {"coupling.algorithm": kind, "coupling.order": order, "scene.step": 2.5e-4,
                "coupling.startup_step": 3.125e-5}
        plain = meng_errors(meng(base), reference)
        resolved = meng_errors(meng({**base, "coupling.feedthrough": True}), reference)
        lines.append(f"| {kind} {order} | {plain[0]:.2e} | {resolved[0]:.2e} | {100 * plain[1]:.2f} | "
                     f"{100 * resolved[1]:.2f} |")
    print("\n".join(lines))
    publish("feedthrough", "python benchmarks/feedthrough.py", lines)


if __name__ == "__main__":
    main()
