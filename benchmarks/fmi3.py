"""Every shipped scene at its defaults on our FMI 3.0 FMUs against the FMI 2.0 ones, in one run: the
stepping's wall time of each (the best of three, taken in rounds that alternate the two so that a
busy spell of the machine hits both alike), their ratio, and whether the FMI 3.0 run is the FMI 2.0
run bit for bit. FMI 3.0 has no input derivatives; our FMI 3.0 FMUs take each input's rate and
curvature as inputs of their own (fmi.rate.*, fmi.curvature.*), so a scene couples at its own step
on either (before they had those, an FMI 3.0 run took an eighth of the scene's step: 8 times the
macro steps).

    python benchmarks/fmi3.py [--duration 2]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import publish  # noqa: E402
from cosim.engine.artifacts import ROOT  # noqa: E402
from cosim.platform.run.runner import run_scene  # noqa: E402
from cosim.platform.scene import load_scene  # noqa: E402

ROUNDS = 3


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--duration", type=float, default=2.0, help="simulated seconds per scene")
    args = parser.parse_args()
    lines = ["| scene | FMI 2.0 stepping wall [s] | FMI 3.0 [s] | FMI 3.0 / FMI 2.0 | macro steps (both) | "
             "bit for bit |", "|---|---|---|---|---|---|"]
    ratios = []
    for path in sorted((ROOT / "scenes").glob("*.toml")):
        scene = load_scene(path, {"scene.duration": args.duration})
        walls: dict[int, list[float]] = {2: [], 3: []}
        results, steps = {}, {}
        for _ in range(ROUNDS):
            for fmi in (2, 3):
                result, report = run_scene(scene.changed({"scene.fmi": fmi}))
                walls[fmi].append(report.wall)
                results[fmi], steps[fmi] = result, report.macro_steps
        same = results[2].dtype.names == results[3].dtype.names and all(
            np.array_equal(results[2][n], results[3][n]) for n in results[2].dtype.names)
        ratio = min(walls[3]) / min(walls[2])
        ratios.append(ratio)
        lines.append(f"| {path.stem} | {min(walls[2]):.3f} | {min(walls[3]):.3f} | {ratio:.2f} | "
                     f"{steps[2]}{'' if steps[2] == steps[3] else f' / {steps[3]}'} | {'yes' if same else 'no'} |")
    lines += ["", f"{args.duration:g} s of each scene; FMI 3.0 over FMI 2.0 at most {max(ratios):.2f} (the goal: "
              "1.5); the FMI 3.0 layer's only extra work per step is the translation of each call onto the FMI 2.0 "
              "layer beneath it and the derivatives' value references."]
    publish("fmi3", "python benchmarks/fmi3.py", lines)


if __name__ == "__main__":
    main()
