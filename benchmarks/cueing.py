"""The shipped car drive's motion cueing tuned (cosim.platform.design.cueing, `cosim tune`): how
long, and how much closer to the vehicle it feels.

The scene examples/vehicle/car_drive.toml (a car's braking, lane change and curve on Meng's platform
with the PMSM drives) tuned over the default ranges (eight parameters: the x and y translation,
the tilt and the yaw rotation, gain and frequency each) by differential evolution on two Dask
workers, its own cueing and the tuned one screened and co-simulated. Reported: the search's
screenings and wall, per channel the perceived rms error, correlation and cues by kind (spurious, sign error, missing) of both
cueings as co-simulated, and their limits' margins; the perception figures of both runs are written
to docs/figures/ for the user guide (docs/guide/cueing.md).

    python benchmarks/cueing.py
"""

from __future__ import annotations

import math
import shutil
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from common import publish  # noqa: E402
from cosim.engine.artifacts import ROOT  # noqa: E402
from cosim.platform.design.cueing import tune  # noqa: E402
from cosim.platform.run.runner import run_scene  # noqa: E402
from cosim.platform.scene import load_scene  # noqa: E402

EXAMPLE = ROOT / "examples" / "vehicle" / "car_drive.toml"
FIGURES = ROOT / "docs" / "figures"


def main() -> None:
    scene = load_scene(EXAMPLE)
    iterations, population, seed = scene.cueing_search
    tuning = tune(scene, workers=2, seed=seed, iterations=iterations, population=population)
    tuned = scene.changed({"cueing.parameters": {**scene.cueing_parameters, **tuning.best}})
    with tempfile.TemporaryDirectory() as folder:
        for name, which in (("car_drive", scene), ("car_drive_tuned", tuned)):
            run_scene(which, Path(folder), plots=True)
            shutil.copy(Path(folder) / "car_drive_perception.png", FIGURES / f"{name}_perception.png")
    own, best = tuning.confirmed["scene"], tuning.confirmed["tuned"]

    def cells(q) -> str:
        correlation = "-" if math.isnan(q.correlation) else f"{q.correlation:.2f}"
        return f"{q.rms_error:.3g} | {correlation} | {q.spurious_time:.2f} / {q.sign_error_time:.2f} / {q.missing_time:.2f}"
    lines = [f"Search: {len(tuning.ranges)} parameters, differential evolution ({iterations} generations of "
             f"{population} per parameter), {tuning.evaluations} screenings on 2 Dask workers in {tuning.seconds:.0f} s "
             f"wall; then both cueings co-simulated (20 s each).", "",
             "| perceived, co-simulated | scene's cueing: rms error | correlation | spurious / sign error / missing "
             "cues [s] | tuned: rms error | correlation | spurious / sign error / missing cues [s] |",
             "|---|---|---|---|---|---|---|"]
    for a, b in zip(own.channels, best.channels):
        lines.append(f"| {a.channel} [{a.unit}] | {cells(a)} | {cells(b)} |")
    lines.append(f"| perceived error (rms past the threshold, in thresholds, summed) | {own.perceived_error:.3f} | | | "
                 f"{best.perceived_error:.3f} | | |")
    lines += ["", "| margin, co-simulated | scene's cueing | tuned |", "|---|---|---|"]
    lines += [f"| {k} | {own.margins[k]:.1%} | {best.margins[k]:.1%} |" for k in own.margins]
    lines += ["", "Screened (the platform on its reference): perceived error "
              f"{tuning.screened['scene'].perceived_error:.3f} (scene's), {tuning.screened['tuned'].perceived_error:.3f} "
              "(tuned). Tuned: " + ", ".join(f"`{k}` = {v:.4g}" for k, v in tuning.best.items()) + ".",
              "", "Verdict: " + tuning.lines()[-1].split(": ", 1)[1] + "."]
    publish("cueing", "python benchmarks/cueing.py", lines)


if __name__ == "__main__":
    main()
